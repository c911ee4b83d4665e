/* Test helper for the netpbm interoperability tests: converts between binary
 * PNM (P5/P6, maxval 255) and Utah RLE through the library's tb_rle_read /
 * tb_rle_write, with raw codes (TB_ENCODING_LINEAR) on both sides so that a
 * byte in one file is the same byte in the other.
 *
 *   rle_tool topnm   IN.rle OUT.pnm [ALPHA.pgm]  (PGM for a Y image, else PPM)
 *   rle_tool frompnm IN.pnm OUT.rle [ALPHA.pgm]  (alpha from a PGM of the same size)
 *   rle_tool attrs   IN.rle                      (prints the attributes, key=value)
 */
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util/image/image.h"

static int fail(const char *what)
{
    fprintf(stderr, "rle_tool: %s: %s\n", what, tb_last_error());
    return 1;
}

/* Next header token of a PNM file, skipping whitespace and # comments. */
static int pnm_token(FILE *f, int *out)
{
    int c = getc(f);
    for (;;) {
        while (c != EOF && isspace(c))
            c = getc(f);
        if (c != '#')
            break;
        while (c != EOF && c != '\n')
            c = getc(f);
    }
    if (c == EOF || !isdigit(c))
        return -1;
    int v = 0;
    while (c != EOF && isdigit(c)) {
        v = v * 10 + (c - '0');
        c = getc(f);
    }
    *out = v; /* the single whitespace after maxval is consumed here */
    return 0;
}

/* Reads a P5 or P6 file with maxval 255: channels 1 or 3, bytes in *px. */
static int pnm_read(const char *path, int *w, int *h, int *nch, unsigned char **px)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        perror(path);
        return -1;
    }
    int ok = 0, maxval = 0;
    char magic[2];
    if (fread(magic, 1, 2, f) == 2 && magic[0] == 'P' && (magic[1] == '5' || magic[1] == '6') &&
        pnm_token(f, w) == 0 && pnm_token(f, h) == 0 && pnm_token(f, &maxval) == 0 &&
        maxval == 255 && *w > 0 && *h > 0) {
        *nch = magic[1] == '5' ? 1 : 3;
        size_t n = (size_t)*w * (size_t)*h * (size_t)*nch;
        *px = malloc(n);
        ok = *px && fread(*px, 1, n, f) == n;
    }
    fclose(f);
    if (!ok)
        fprintf(stderr, "rle_tool: %s: not a P5/P6 file with maxval 255\n", path);
    return ok ? 0 : -1;
}

static int pnm_write(const char *path, int w, int h, int nch, const unsigned char *px)
{
    FILE *f = fopen(path, "wb");
    if (!f) {
        perror(path);
        return -1;
    }
    fprintf(f, "P%c\n%d %d\n255\n", nch == 1 ? '5' : '6', w, h);
    size_t n = (size_t)w * (size_t)h * (size_t)nch;
    int ok = fwrite(px, 1, n, f) == n;
    ok &= fclose(f) == 0;
    return ok ? 0 : -1;
}

static int to_pnm(int argc, char **argv)
{
    FILE *f = fopen(argv[2], "rb");
    if (!f) {
        perror(argv[2]);
        return 1;
    }
    tb_image_read_options ro = {.encoding = TB_ENCODING_LINEAR};
    tb_image *img = NULL;
    tb_status st = tb_rle_read(f, argv[2], &ro, &img);
    fclose(f);
    if (st)
        return fail("read");
    int a = tb_image_channel(img, "A");
    int ncol = img->channels - (a >= 0 ? 1 : 0);
    size_t npix = (size_t)img->width * (size_t)img->height;
    unsigned char *px = malloc(npix * (size_t)ncol), *al = malloc(npix);
    for (size_t i = 0; i < npix; i++) {
        const float *p = img->pixels + i * (size_t)img->channels;
        for (int c = 0, k = 0; c < img->channels; c++)
            if (c != a)
                px[i * (size_t)ncol + (size_t)k++] = tb_image_quantize8(p[c], TB_ENCODING_LINEAR);
        al[i] = a >= 0 ? tb_image_quantize8(p[a], TB_ENCODING_LINEAR) : 0;
    }
    int rc = 0;
    if (ncol != 1 && ncol != 3) {
        fprintf(stderr, "rle_tool: %d colour channels do not fit a PNM file\n", ncol);
        rc = 1;
    } else if (pnm_write(argv[3], img->width, img->height, ncol, px)) {
        rc = 1;
    } else if (argc > 4) {
        if (a < 0) {
            fprintf(stderr, "rle_tool: %s has no alpha channel\n", argv[2]);
            rc = 1;
        } else if (pnm_write(argv[4], img->width, img->height, 1, al)) {
            rc = 1;
        }
    }
    free(px);
    free(al);
    tb_image_free(img);
    return rc;
}

static int from_pnm(int argc, char **argv)
{
    int w, h, nch;
    unsigned char *px = NULL, *al = NULL;
    if (pnm_read(argv[2], &w, &h, &nch, &px))
        return 1;
    int aw = 0, ah = 0, anch = 0;
    if (argc > 4 && (pnm_read(argv[4], &aw, &ah, &anch, &al) || aw != w || ah != h || anch != 1)) {
        fprintf(stderr, "rle_tool: %s must be a PGM of %dx%d\n", argv[4], w, h);
        free(px);
        free(al);
        return 1;
    }
    int channels = nch + (al ? 1 : 0);
    tb_image *img = tb_image_create(w, h, channels, NULL);
    if (!img)
        return fail("create");
    size_t npix = (size_t)w * (size_t)h;
    for (size_t i = 0; i < npix; i++) {
        float *p = img->pixels + i * (size_t)channels;
        for (int c = 0; c < nch; c++)
            p[c] = tb_image_dequantize8(px[i * (size_t)nch + (size_t)c], TB_ENCODING_LINEAR);
        if (al)
            p[nch] = tb_image_dequantize8(al[i], TB_ENCODING_LINEAR);
    }
    free(px);
    free(al);
    tb_image_set_attr(img, "source", argv[2]);
    FILE *f = fopen(argv[3], "wb");
    if (!f) {
        perror(argv[3]);
        tb_image_free(img);
        return 1;
    }
    tb_image_write_options wo = {.encoding = TB_ENCODING_LINEAR};
    tb_status st = tb_rle_write(f, argv[3], img, &wo);
    tb_image_free(img);
    if (fclose(f) != 0 && !st)
        st = TB_ERR_IO;
    return st ? fail("write") : 0;
}

static int attrs(char **argv)
{
    FILE *f = fopen(argv[2], "rb");
    if (!f) {
        perror(argv[2]);
        return 1;
    }
    tb_image *img = NULL;
    tb_status st = tb_rle_read(f, argv[2], NULL, &img);
    fclose(f);
    if (st)
        return fail("read");
    for (int i = 0; i < img->nattrs; i++)
        printf("%s=%s\n", img->attrs[i].key, img->attrs[i].value);
    tb_image_free(img);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc >= 4 && argc <= 5 && strcmp(argv[1], "topnm") == 0)
        return to_pnm(argc, argv);
    if (argc >= 4 && argc <= 5 && strcmp(argv[1], "frompnm") == 0)
        return from_pnm(argc, argv);
    if (argc == 3 && strcmp(argv[1], "attrs") == 0)
        return attrs(argv);
    fprintf(stderr, "usage: rle_tool topnm IN.rle OUT.pnm [ALPHA.pgm]\n"
                    "       rle_tool frompnm IN.pnm OUT.rle [ALPHA.pgm]\n"
                    "       rle_tool attrs IN.rle\n");
    return 2;
}
