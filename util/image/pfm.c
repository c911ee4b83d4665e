/* Portable Float Map: "PF" (RGB) or "Pf" (grey), width, height, and a scale
 * whose sign gives the byte order (negative: little-endian), then 32-bit IEEE
 * floats with the BOTTOM row first. We write little-endian with scale -1.0.
 * The four-channel "PF4" variant is rejected (see docs/images.md). */
#include "util/image/image.h"
#include "util/base/stream.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>

/* Longest header token we accept; real headers use a handful of characters. */
#define TB__PFM_TOKEN_MAX 64

static int tb__pfm_space(int c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

static tb_status tb__pfm_truncated(const char *name, const char *where)
{
    return tb_error(TB_ERR_FORMAT, "%s: PFM file truncated in the %s", name, where);
}

/* Reads one header token: skips white space, collects the non-space bytes and
 * consumes the single white-space byte that ends it. */
static tb_status tb__pfm_token(FILE *f, const char *name, const char *what, char *buf)
{
    int c;
    while ((c = getc(f)) != EOF && tb__pfm_space(c))
        ;
    size_t n = 0;
    while (c != EOF && !tb__pfm_space(c)) {
        if (n + 1 >= TB__PFM_TOKEN_MAX)
            return tb_error(TB_ERR_FORMAT, "%s: PFM header: %s is too long", name, what);
        buf[n++] = (char)c;
        c = getc(f);
    }
    buf[n] = '\0';
    if (c == EOF)
        return tb__pfm_truncated(name, "header");
    return TB_OK;
}

/* A positive decimal integer no larger than INT_MAX, digits only. */
static tb_status tb__pfm_dimension(const char *tok, const char *name, const char *what, int *out)
{
    long long v = 0;
    if (!tok[0])
        return tb_error(TB_ERR_FORMAT, "%s: PFM header: missing %s", name, what);
    for (const char *p = tok; *p; p++) {
        if (*p < '0' || *p > '9')
            return tb_error(TB_ERR_FORMAT, "%s: PFM header: %s '%s' is not a positive integer", name,
                            what, tok);
        v = v * 10 + (*p - '0');
        if (v > INT_MAX)
            return tb_error(TB_ERR_FORMAT, "%s: PFM header: %s %s is too large", name, what, tok);
    }
    if (v < 1)
        return tb_error(TB_ERR_FORMAT, "%s: PFM header: %s must be at least 1", name, what);
    *out = (int)v;
    return TB_OK;
}

/* The scale: [+-]digits[.digits][(e|E)[+-]digits], not zero. Checked by hand
 * rather than with strtod, whose decimal point follows the locale; only the
 * sign is used (the magnitude is ignored, as by most readers). */
static tb_status tb__pfm_scale(const char *tok, const char *name, int *little_endian)
{
    const char *p = tok;
    int negative = 0, digits = 0, nonzero = 0;
    if (*p == '+' || *p == '-')
        negative = *p++ == '-';
    for (; *p >= '0' && *p <= '9'; p++, digits++)
        nonzero |= *p != '0';
    if (*p == '.')
        for (p++; *p >= '0' && *p <= '9'; p++, digits++)
            nonzero |= *p != '0';
    if (digits && (*p == 'e' || *p == 'E')) {
        p++;
        if (*p == '+' || *p == '-')
            p++;
        if (!(*p >= '0' && *p <= '9'))
            digits = 0;
        while (*p >= '0' && *p <= '9')
            p++;
    }
    if (!digits || *p)
        return tb_error(TB_ERR_FORMAT, "%s: PFM header: scale '%s' is not a number", name, tok);
    if (!nonzero)
        return tb_error(TB_ERR_FORMAT, "%s: PFM header: scale is zero (its sign gives the byte order)",
                        name);
    *little_endian = negative;
    return TB_OK;
}

/* Decodes `n` floats from `src` in the file's byte order. */
static void tb__pfm_decode(float *dst, const unsigned char *src, size_t n, int little_endian)
{
    for (size_t i = 0; i < n; i++, src += 4) {
        uint32_t u = little_endian
            ? (uint32_t)src[0] | (uint32_t)src[1] << 8 | (uint32_t)src[2] << 16 | (uint32_t)src[3] << 24
            : (uint32_t)src[3] | (uint32_t)src[2] << 8 | (uint32_t)src[1] << 16 | (uint32_t)src[0] << 24;
        memcpy(&dst[i], &u, sizeof u);
    }
}

/* Reads `n` bytes from a stream of unknown length into a buffer that grows
 * only as data arrives, so a lying header on a short pipe costs nothing. */
static tb_status tb__pfm_slurp(FILE *f, const char *name, size_t n, unsigned char **out)
{
    size_t cap = n < ((size_t)1 << 20) ? n : ((size_t)1 << 20), got = 0;
    unsigned char *buf = malloc(cap);
    if (!buf)
        return tb_error(TB_ERR_NOMEM, "%s: out of memory", name);
    for (;;) {
        got += fread(buf + got, 1, cap - got, f);
        if (got == n)
            break;
        if (got < cap) {
            tb_status st = ferror(f) ? tb_error(TB_ERR_IO, "%s: read failed: %s", name, strerror(errno))
                                     : tb__pfm_truncated(name, "pixel data");
            free(buf);
            return st;
        }
        size_t ncap = cap > n / 2 ? n : cap * 2;
        unsigned char *nbuf = realloc(buf, ncap);
        if (!nbuf) {
            free(buf);
            return tb_error(TB_ERR_NOMEM, "%s: out of memory", name);
        }
        buf = nbuf;
        cap = ncap;
    }
    *out = buf;
    return TB_OK;
}

tb_status tb_pfm_read(FILE *f, const char *name, tb_image **out)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "tb_pfm_read: NULL output pointer");
    *out = NULL;
    if (!name)
        name = "(stream)";
    if (!f)
        return tb_error(TB_ERR_ARG, "%s: no stream to read", name);

    int m0 = getc(f), m1 = getc(f), m2 = getc(f);
    if (m0 == EOF || m1 == EOF || m2 == EOF)
        return m0 == EOF ? tb_error(TB_ERR_FORMAT, "%s: empty file, not a PFM image", name)
                         : tb__pfm_truncated(name, "header");
    if (m0 != 'P' || (m1 != 'F' && m1 != 'f'))
        return tb_error(TB_ERR_FORMAT, "%s: not a PFM file (it must start with \"PF\" or \"Pf\")", name);
    if (m1 == 'F' && m2 == '4')
        return tb_error(TB_ERR_UNSUPPORTED, "%s: four-channel \"PF4\" PFM files are not supported", name);
    if (!tb__pfm_space(m2))
        return tb_error(TB_ERR_FORMAT, "%s: not a PFM file (\"P%c\" must be followed by white space)",
                        name, m1);
    int channels = m1 == 'F' ? 3 : 1;

    char tok[TB__PFM_TOKEN_MAX];
    int width = 0, height = 0, little_endian = 0;
    tb_status st;
    if ((st = tb__pfm_token(f, name, "width", tok)) || (st = tb__pfm_dimension(tok, name, "width", &width)))
        return st;
    if ((st = tb__pfm_token(f, name, "height", tok)) ||
        (st = tb__pfm_dimension(tok, name, "height", &height)))
        return st;
    if ((st = tb__pfm_token(f, name, "scale", tok)) || (st = tb__pfm_scale(tok, name, &little_endian)))
        return st;

    size_t samples = (size_t)width * (size_t)height; /* each <= INT_MAX: fits in 64 bits */
    if (samples > TB_IMAGE_MAX_SAMPLES / (size_t)channels)
        return tb_error(TB_ERR_FORMAT, "%s: PFM header: %d x %d x %d is too large", name, width, height,
                        channels);
    samples *= (size_t)channels;
    size_t bytes = samples * 4;
    size_t row_floats = (size_t)width * (size_t)channels;

    long long remaining = tb_stream_remaining(f);
    if (remaining >= 0 && (unsigned long long)remaining < bytes)
        return tb_error(TB_ERR_FORMAT,
                        "%s: PFM file truncated: %d x %d x %d floats need %zu bytes, only %lld follow "
                        "the header", name, width, height, channels, bytes, remaining);

    unsigned char *data = NULL;
    if (remaining < 0 && (st = tb__pfm_slurp(f, name, bytes, &data)))
        return st;
    tb_image *img = tb_image_create(width, height, channels, NULL);
    unsigned char *row = data ? NULL : malloc(row_floats * 4);
    if (!img || (!data && !row)) {
        tb_image_free(img);
        free(data);
        return tb_error(TB_ERR_NOMEM, "%s: out of memory for a %d x %d PFM image", name, width, height);
    }
    for (int r = 0; r < height; r++) {
        /* File row r counts from the bottom; ours count from the top. */
        float *dst = tb_image_at(img, 0, height - 1 - r);
        const unsigned char *src;
        if (data) {
            src = data + (size_t)r * row_floats * 4;
        } else {
            if (fread(row, 4, row_floats, f) != row_floats) {
                st = ferror(f) ? tb_error(TB_ERR_IO, "%s: read failed: %s", name, strerror(errno))
                               : tb__pfm_truncated(name, "pixel data");
                free(row);
                tb_image_free(img);
                return st;
            }
            src = row;
        }
        tb__pfm_decode(dst, src, row_floats, little_endian);
    }
    free(row);
    free(data);
    *out = img;
    return TB_OK;
}

tb_status tb_pfm_write(FILE *f, const char *name, const tb_image *img, const tb_image_write_options *opts)
{
    if (!name)
        name = "(stream)";
    if (!f || !img || !img->pixels)
        return tb_error(TB_ERR_ARG, "%s: tb_pfm_write: NULL argument", name);
    if (img->channels != 1 && img->channels != 3)
        return tb_error(TB_ERR_UNSUPPORTED,
                        "%s: PFM stores 1 (grey) or 3 (RGB) channels; this image has %d", name,
                        img->channels);
    float exposure = opts ? opts->exposure : 0.0f;
    if (!isfinite(exposure))
        return tb_error(TB_ERR_ARG, "%s: exposure must be a finite number of stops", name);
    float scale = (float)exp2((double)exposure);

    size_t row_floats = (size_t)img->width * (size_t)img->channels;
    unsigned char *row = malloc(row_floats * 4);
    if (!row)
        return tb_error(TB_ERR_NOMEM, "%s: out of memory", name);
    int ok = fprintf(f, "%s\n%d %d\n-1.0\n", img->channels == 3 ? "PF" : "Pf", img->width, img->height) > 0;
    for (int r = img->height - 1; ok && r >= 0; r--) {
        const float *src = tb_image_at(img, 0, r);
        for (size_t i = 0; i < row_floats; i++) {
            float v = exposure != 0.0f ? src[i] * scale : src[i];
            uint32_t u;
            memcpy(&u, &v, sizeof u);
            row[4 * i + 0] = (unsigned char)(u & 0xff);
            row[4 * i + 1] = (unsigned char)(u >> 8 & 0xff);
            row[4 * i + 2] = (unsigned char)(u >> 16 & 0xff);
            row[4 * i + 3] = (unsigned char)(u >> 24);
        }
        ok = fwrite(row, 4, row_floats, f) == row_floats;
    }
    free(row);
    if (!ok)
        return tb_error(TB_ERR_IO, "%s: write failed: %s", name, errno ? strerror(errno) : "short write");
    return TB_OK;
}
