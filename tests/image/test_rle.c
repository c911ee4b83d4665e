/* Utah RLE reader and writer: hand-assembled files (bytes written from the
 * format description, not from our writer), round trips, and every kind of
 * malformed input. The netpbm interoperability tests are in rle_netpbm.sh. */
#include <string.h>

#include "tb_test.h"
#include "util/image/image.h"

/* ------------------------------------------------------------ byte builders */

typedef struct buf {
    unsigned char b[4096];
    size_t n;
} buf;

static void put(buf *o, const void *p, size_t n)
{
    assert_true(o->n + n <= sizeof o->b);
    memcpy(o->b + o->n, p, n);
    o->n += n;
}

static void put_bytes(buf *o, int n, ...)
{
    va_list ap;
    va_start(ap, n);
    for (int i = 0; i < n; i++) {
        unsigned char c = (unsigned char)va_arg(ap, int);
        put(o, &c, 1);
    }
    va_end(ap);
}

/* The 15-byte header (little-endian words); no background colour. */
static void put_header(buf *o, int w, int h, int flags, int ncolors, int ncmap, int cmaplen)
{
    put_bytes(o, 15, 0x52, 0xCC, 0, 0, 0, 0, w & 0xff, w >> 8, h & 0xff, h >> 8, flags, ncolors, 8,
              ncmap, cmaplen);
}

static tb_status read_mem(const buf *in, const tb_image_read_options *o, tb_image **img)
{
    /* tmpfile, not fmemopen: it also handles the empty file. */
    FILE *f = tmpfile();
    assert_non_null(f);
    if (in->n)
        assert_int_equal(fwrite(in->b, 1, in->n, f), in->n);
    rewind(f);
    tb_status st = tb_rle_read(f, "mem.rle", o, img);
    fclose(f);
    return st;
}

/* Writes `img` into memory; returns the bytes (free them). */
static unsigned char *write_mem(const tb_image *img, const tb_image_write_options *o, size_t *len,
                                tb_status *st)
{
    char *p = NULL;
    FILE *f = open_memstream(&p, len);
    assert_non_null(f);
    *st = tb_rle_write(f, "mem.rle", img, o);
    fclose(f);
    return (unsigned char *)p;
}

static tb_status read_bytes(const unsigned char *p, size_t n, const tb_image_read_options *o,
                            tb_image **img)
{
    FILE *f = fmemopen((void *)p, n, "rb");
    assert_non_null(f);
    tb_status st = tb_rle_read(f, "mem.rle", o, img);
    fclose(f);
    return st;
}

static const tb_image_read_options linear_in = {.encoding = TB_ENCODING_LINEAR};
static const tb_image_write_options linear_out = {.encoding = TB_ENCODING_LINEAR};

#define CODE(v) tb_image_quantize8((v), TB_ENCODING_LINEAR)

/* ------------------------------------------------------------ reading */

/* A 5x3 grey image with every opcode, short and long; y = 0 of the file is
 * the bottom row, so the first scanline lands in the image's last row. */
static void test_read_opcodes_and_orientation(void **state)
{
    (void)state;
    buf o = {0};
    put_header(&o, 5, 3, 0x02 | 0x08, 1, 0, 0); /* NO_BACKGROUND | COMMENT */
    put_bytes(&o, 1, 0);                         /* filler */
    static const char com[] = "HISTORY=made by hand\0flag\0=nameless\0"; /* 36 bytes */
    put_bytes(&o, 2, 36, 0);
    put(&o, com, 36);
    /* bottom scanline: 10 20 30 then a run of two 40s */
    put_bytes(&o, 2, 2, 0);
    put_bytes(&o, 2 + 4, 5, 2, 10, 20, 30, 0 /* pad */);
    put_bytes(&o, 4, 6, 1, 40, 0);
    put_bytes(&o, 2, 1, 1); /* SkipLines 1 */
    /* middle: skip 2, run of three 99s */
    put_bytes(&o, 2, 2, 0);
    put_bytes(&o, 2, 3, 2);
    put_bytes(&o, 4, 6, 2, 99, 0);
    put_bytes(&o, 4, 0x41, 0, 1, 0); /* long SkipLines 1 */
    /* top: long ByteData of 5 */
    put_bytes(&o, 2, 2, 0);
    put_bytes(&o, 4 + 6, 0x45, 0, 4, 0, 1, 2, 3, 4, 5, 0);
    put_bytes(&o, 2, 7, 0); /* EOF */

    tb_image *img = NULL;
    assert_int_equal(read_mem(&o, &linear_in, &img), TB_OK);
    assert_int_equal(img->width, 5);
    assert_int_equal(img->height, 3);
    assert_int_equal(img->channels, 1);
    assert_string_equal(img->names[0], "Y");
    static const int want[3][5] = {{1, 2, 3, 4, 5}, {0, 0, 99, 99, 99}, {10, 20, 30, 40, 40}};
    for (int y = 0; y < 3; y++)
        for (int x = 0; x < 5; x++)
            assert_int_equal(CODE(*tb_image_at(img, x, y)), want[y][x]);
    assert_string_equal(tb_image_get_attr(img, "HISTORY"), "made by hand");
    assert_string_equal(tb_image_get_attr(img, "flag"), "");
    assert_int_equal(img->nattrs, 2); /* "=nameless" names no key */
    tb_image_free(img);

    /* The default encoding decodes the same codes through sRGB. */
    assert_int_equal(read_mem(&o, NULL, &img), TB_OK);
    assert_true(*tb_image_at(img, 2, 1) == tb_image_dequantize8(99, TB_ENCODING_SRGB));
    tb_image_free(img);
}

/* Pixels no instruction writes take the background colour; G and B of a
 * pixel whose R was written keep it too. */
static void test_read_background(void **state)
{
    (void)state;
    buf o = {0};
    put_header(&o, 4, 2, 0x01, 3, 0, 0); /* CLEARFIRST, background follows */
    put_bytes(&o, 3, 7, 8, 9);           /* 3 colours: already odd, no pad */
    put_bytes(&o, 2, 2, 0);              /* SetColor R */
    put_bytes(&o, 2, 3, 1);              /* SkipPixels 1 */
    put_bytes(&o, 4, 5, 0, 200, 0);      /* ByteData 1 + pad */
    put_bytes(&o, 2, 7, 0);
    tb_image *img = NULL;
    assert_int_equal(read_mem(&o, &linear_in, &img), TB_OK);
    assert_string_equal(img->names[0], "R");
    assert_string_equal(img->names[2], "B");
    for (int y = 0; y < 2; y++)
        for (int x = 0; x < 4; x++) {
            const float *p = tb_image_at(img, x, y);
            int written = y == 1 && x == 1; /* bottom row in the file = last row here */
            assert_int_equal(CODE(p[0]), written ? 200 : 7);
            assert_int_equal(CODE(p[1]), 8);
            assert_int_equal(CODE(p[2]), 9);
        }
    tb_image_free(img);

    /* Background without CLEARFIRST: still the fill for unwritten pixels. One
     * colour channel: the background byte is already an odd length. */
    buf g = {0};
    put_header(&g, 2, 1, 0, 1, 0, 0);
    put_bytes(&g, 1, 33);
    put_bytes(&g, 2, 7, 0);
    assert_int_equal(read_mem(&g, &linear_in, &img), TB_OK);
    assert_int_equal(CODE(img->pixels[0]), 33);
    assert_int_equal(CODE(img->pixels[1]), 33);
    tb_image_free(img);

    /* Two colours: background padded to 3 bytes. */
    buf t = {0};
    put_header(&t, 1, 1, 0, 2, 0, 0);
    put_bytes(&t, 3, 5, 6, 0xEE);
    put_bytes(&t, 2, 7, 0);
    assert_int_equal(read_mem(&t, &linear_in, &img), TB_OK);
    assert_int_equal(img->channels, 2);
    assert_string_equal(img->names[1], "G");
    assert_int_equal(CODE(img->pixels[0]), 5);
    assert_int_equal(CODE(img->pixels[1]), 6);
    tb_image_free(img);
}

/* Alpha is channel 255 in the file and always decoded linearly. */
static void test_read_alpha(void **state)
{
    (void)state;
    buf o = {0};
    put_header(&o, 3, 1, 0x02 | 0x04, 1, 0, 0);
    put_bytes(&o, 1, 0);
    put_bytes(&o, 2, 2, 255);
    put_bytes(&o, 2 + 4, 5, 2, 0, 128, 255, 0);
    put_bytes(&o, 2, 2, 0);
    put_bytes(&o, 4, 6, 1, 64, 0); /* only two grey pixels written */
    put_bytes(&o, 2, 7, 0);
    tb_image *img = NULL;
    assert_int_equal(read_mem(&o, NULL, &img), TB_OK);
    assert_int_equal(img->channels, 2);
    assert_string_equal(img->names[0], "Y");
    assert_string_equal(img->names[1], "A");
    assert_true(tb_image_at(img, 1, 0)[1] == tb_image_dequantize8(128, TB_ENCODING_LINEAR));
    assert_true(tb_image_at(img, 2, 0)[1] == 1.0f);
    assert_true(tb_image_at(img, 0, 0)[0] == tb_image_dequantize8(64, TB_ENCODING_SRGB));
    assert_true(tb_image_at(img, 2, 0)[0] == 0.0f); /* no background: 0 */
    tb_image_free(img);
}

/* Colour maps: 16-bit entries, the high byte is the colour. */
static void test_read_colour_maps(void **state)
{
    (void)state;
    /* Pseudocolour: 1 channel, 3 maps of 4 entries. */
    buf o = {0};
    put_header(&o, 4, 1, 0x02, 1, 3, 2);
    put_bytes(&o, 1, 0);
    static const unsigned short map[3][4] = {
        {0x0000, 0x1234, 0xff00, 0x80ff}, {0x0100, 0x2200, 0x3300, 0x44aa}, {0xa000, 0xb000, 0xc0c0, 0xd000}};
    for (int c = 0; c < 3; c++)
        for (int i = 0; i < 4; i++)
            put_bytes(&o, 2, map[c][i] & 0xff, map[c][i] >> 8);
    put_bytes(&o, 2, 2, 0);
    put_bytes(&o, 2 + 4, 5, 3, 3, 2, 1, 0);
    put_bytes(&o, 2, 7, 0);
    tb_image *img = NULL;
    assert_int_equal(read_mem(&o, &linear_in, &img), TB_OK);
    assert_int_equal(img->channels, 3);
    assert_string_equal(img->names[0], "R");
    static const int idx[4] = {3, 2, 1, 0};
    for (int x = 0; x < 4; x++)
        for (int c = 0; c < 3; c++)
            assert_int_equal(CODE(tb_image_at(img, x, 0)[c]), map[c][idx[x]] >> 8);
    tb_image_free(img);

    /* A value beyond the 4-entry map is malformed. */
    o.b[o.n - 2 - 4 + 1] = 4; /* second pixel */
    assert_int_equal(read_mem(&o, &linear_in, &img), TB_ERR_FORMAT);
    assert_null(img);
    assert_non_null(strstr(tb_last_error(), "colour map"));

    /* Per-channel maps: 3 channels, 2 entries each, inverted. */
    buf t = {0};
    put_header(&t, 2, 1, 0x02, 3, 3, 1);
    put_bytes(&t, 1, 0);
    for (int c = 0; c < 3; c++)
        put_bytes(&t, 4, 0, 0xff, 0, 0x10 * (c + 1));
    for (int c = 0; c < 3; c++) {
        put_bytes(&t, 2, 2, c);
        put_bytes(&t, 4, 5, 1, 0, 1);
    }
    put_bytes(&t, 2, 7, 0);
    assert_int_equal(read_mem(&t, &linear_in, &img), TB_OK);
    for (int c = 0; c < 3; c++) {
        assert_int_equal(CODE(tb_image_at(img, 0, 0)[c]), 0xff);
        assert_int_equal(CODE(tb_image_at(img, 1, 0)[c]), 0x10 * (c + 1));
    }
    tb_image_free(img);
}

/* ------------------------------------------------------------ malformed input */

/* A valid file with a background, a map, comments and data, cut at every length. */
static void valid_file(buf *o)
{
    memset(o, 0, sizeof *o);
    put_header(o, 3, 2, 0x01 | 0x08, 1, 1, 2);
    put_bytes(o, 1, 2);
    put_bytes(o, 8, 0, 0, 0, 0x40, 0, 0x80, 0, 0xff);
    put_bytes(o, 2, 3, 0);
    put(o, "a=b", 4);
    put_bytes(o, 2, 2, 0);
    put_bytes(o, 4, 6, 2, 1, 0);
    put_bytes(o, 4, 0x41, 0, 1, 0);
    put_bytes(o, 2, 2, 0);
    put_bytes(o, 2 + 4, 5, 2, 3, 0, 1, 0);
    put_bytes(o, 2, 7, 0);
}

static void test_truncated_everywhere(void **state)
{
    (void)state;
    buf full;
    valid_file(&full);
    tb_image *img = NULL;
    assert_int_equal(read_mem(&full, NULL, &img), TB_OK);
    tb_image_free(img);
    for (size_t n = 0; n < full.n; n++) {
        buf cut = full;
        cut.n = n;
        img = NULL;
        tb_status st = read_mem(&cut, NULL, &img);
        if (st != TB_ERR_FORMAT)
            fail_msg("cut at %zu: status %d (%s)", n, st, tb_last_error());
        assert_null(img);
        if (!strstr(tb_last_error(), "byte"))
            fail_msg("cut at %zu: message without an offset: %s", n, tb_last_error());
    }
}

/* Replaces bytes [at, at+n) of a copy of `o`, reads it, expects `want`, and
 * that the message contains `needle`. */
static void expect_error(const buf *o, size_t at, const unsigned char *bytes, size_t n,
                         tb_status want, const char *needle)
{
    buf b = *o;
    if (n)
        memcpy(b.b + at, bytes, n);
    tb_image *img = NULL;
    tb_status st = read_mem(&b, NULL, &img);
    if (st != want || !strstr(tb_last_error(), needle))
        fail_msg("bytes at %zu: status %d, message \"%s\"; wanted %d with \"%s\"", at, st,
                 tb_last_error(), want, needle);
    assert_null(img);
}

static void test_malformed(void **state)
{
    (void)state;
    buf g;
    valid_file(&g);
    /* offsets in valid_file: header 0-14, bg 15, map 16-23, comments 24-29,
     * SetColor 30, RunData 32, long SkipLines 36, SetColor 40, ByteData 42, EOF 48 */
    expect_error(&g, 0, (const unsigned char *)"\x52\xcd", 2, TB_ERR_FORMAT, "not a Utah RLE");
    expect_error(&g, 30, (const unsigned char *)"\x09\x00", 2, TB_ERR_FORMAT,
                 "unknown opcode 0x09 at byte 30");
    expect_error(&g, 30, (const unsigned char *)"\x02\x01", 2, TB_ERR_FORMAT,
                 "SetColor at byte 30 selects channel 1 of 1");
    expect_error(&g, 30, (const unsigned char *)"\x02\xff", 2, TB_ERR_FORMAT, "alpha flag");
    expect_error(&g, 32, (const unsigned char *)"\x06\x03", 2, TB_ERR_FORMAT,
                 "RunData at byte 32 writes pixels 0..3 of a 3-pixel scanline");
    expect_error(&g, 36, (const unsigned char *)"\x41\x00\x02\x00", 4, TB_ERR_FORMAT,
                 "ByteData at byte 42 writes scanline 2, above the image's 2 lines");
    expect_error(&g, 34, (const unsigned char *)"\x04", 1, TB_ERR_FORMAT,
                 "beyond the colour map of 4 entries");
    expect_error(&g, 15, (const unsigned char *)"\x04", 1, TB_ERR_FORMAT, "background value 4");
    expect_error(&g, 48, (const unsigned char *)"\x87", 1, TB_ERR_FORMAT, "unknown opcode 0x87");
    /* EOF replaced by a SkipLines and nothing after it */
    expect_error(&g, 48, (const unsigned char *)"\x01\x01", 2, TB_ERR_FORMAT, "without an EOF");
    /* header fields */
    expect_error(&g, 12, (const unsigned char *)"\x10", 1, TB_ERR_UNSUPPORTED, "16 bits per pixel");
    expect_error(&g, 11, (const unsigned char *)"\x00", 1, TB_ERR_UNSUPPORTED, "0 colour channels");
    expect_error(&g, 11, (const unsigned char *)"\x04", 1, TB_ERR_UNSUPPORTED, "4 colour channels");
    expect_error(&g, 13, (const unsigned char *)"\x02", 1, TB_ERR_UNSUPPORTED, "colour-map channels");
    expect_error(&g, 14, (const unsigned char *)"\x09", 1, TB_ERR_UNSUPPORTED, "2^9 entries");
    expect_error(&g, 6, (const unsigned char *)"\x00\x00", 2, TB_ERR_FORMAT, "empty image");
    /* A hostile size is refused before anything is allocated. */
    expect_error(&g, 6, (const unsigned char *)"\xff\xff\xff\xff", 4, TB_ERR_UNSUPPORTED,
                 "65535x65535 image");
}

/* ------------------------------------------------------------ writing */

/* The exact bytes for tiny images, assembled from the format description. */
static void test_write_exact_bytes(void **state)
{
    (void)state;
    tb_image *img = tb_image_create(6, 2, 1, NULL);
    /* top row: 1 2 2 2 2 9 ; bottom row: six 5s */
    static const int top[6] = {1, 2, 2, 2, 2, 9};
    for (int x = 0; x < 6; x++) {
        tb_image_at(img, x, 0)[0] = tb_image_dequantize8((unsigned char)top[x], TB_ENCODING_LINEAR);
        tb_image_at(img, x, 1)[0] = tb_image_dequantize8(5, TB_ENCODING_LINEAR);
    }
    size_t n;
    tb_status st;
    unsigned char *p = write_mem(img, &linear_out, &n, &st);
    assert_int_equal(st, TB_OK);
    static const unsigned char want[] = {
        0x52, 0xCC, 0, 0, 0, 0, 6, 0, 2, 0, 0x02, 1, 8, 0, 0, 0, /* header, filler */
        2, 0, 6, 5, 5, 0,                                    /* bottom: SetColor 0, RunData 6 x 5 */
        1, 1, 2, 0,                                          /* SkipLines 1, SetColor 0 */
        5, 0, 1, 0,                                          /* ByteData 1 (+pad) */
        6, 3, 2, 0,                                          /* RunData 4 x 2 */
        5, 0, 9, 0,                                          /* ByteData 1 (+pad) */
        7, 0};                                               /* EOF */
    assert_int_equal(n, sizeof want);
    assert_memory_equal(p, want, sizeof want);
    free(p);

    /* Attributes become "key=value" comments; an empty value is a bare key. */
    tb_image_set_attr(img, "k", "v");
    tb_image_set_attr(img, "flag", "");
    p = write_mem(img, &linear_out, &n, &st);
    assert_int_equal(st, TB_OK);
    assert_int_equal(p[10], 0x02 | 0x08);
    static const unsigned char com[] = {9, 0, 'k', '=', 'v', 0, 'f', 'l', 'a', 'g', 0, 0 /* pad */};
    assert_memory_equal(p + 16, com, sizeof com);
    free(p);
    tb_image_free(img);
}

/* Writer refusals. */
static void test_write_errors(void **state)
{
    (void)state;
    size_t n;
    tb_status st;
    tb_image *img = tb_image_create(2, 2, 1, NULL);
    tb_image_set_attr(img, "a=b", "c");
    free(write_mem(img, NULL, &n, &st));
    assert_int_equal(st, TB_ERR_ARG);
    tb_image_free(img);

    const char *alpha_only[] = {"A"};
    img = tb_image_create(2, 2, 1, alpha_only);
    free(write_mem(img, NULL, &n, &st));
    assert_int_equal(st, TB_ERR_UNSUPPORTED);
    tb_image_free(img);

    const char *four[] = {"P", "Q", "S", "T"};
    img = tb_image_create(2, 2, 4, four);
    free(write_mem(img, NULL, &n, &st));
    assert_int_equal(st, TB_ERR_UNSUPPORTED);
    tb_image_free(img);

    img = tb_image_create(32768, 1, 1, NULL);
    free(write_mem(img, NULL, &n, &st));
    assert_int_equal(st, TB_ERR_UNSUPPORTED);
    tb_image_free(img);

    /* Long comments overflow the 16-bit length. */
    img = tb_image_create(1, 1, 1, NULL);
    char *big = malloc(70000);
    memset(big, 'x', 69999);
    big[69999] = '\0';
    tb_image_set_attr(img, "big", big);
    free(big);
    free(write_mem(img, NULL, &n, &st));
    assert_int_equal(st, TB_ERR_UNSUPPORTED);
    tb_image_free(img);
}

/* Writes then reads random images of every channel layout: the codes come
 * back exactly, channel names and attributes too. Rows mix runs and noise;
 * widths up to 700 exercise the long opcode forms. */
static void test_round_trip_property(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("rle_round_trip", 20240611), 0);
    static const char *layouts[4][4] = {{"Y"}, {"Y", "A"}, {"R", "G", "B"}, {"R", "G", "B", "A"}};
    static const int nch[4] = {1, 2, 3, 4};
    for (int iter = 0; iter < 60; iter++) {
        int l = iter % 4;
        int w = 1 + (int)(tb_rng_double(&rng) * (iter % 10 == 9 ? 700 : 70));
        int h = 1 + (int)(tb_rng_double(&rng) * 20);
        tb_image_encoding enc = (iter / 4) % 2 ? TB_ENCODING_LINEAR : TB_ENCODING_SRGB;
        tb_image *img = tb_image_create(w, h, nch[l], layouts[l]);
        assert_non_null(img);
        for (int y = 0; y < h; y++) {
            float run = (float)tb_rng_double(&rng);
            for (int x = 0; x < w; x++)
                for (int c = 0; c < nch[l]; c++) {
                    int noisy = ((x / 9) + y) % 3 == 0;
                    float v = noisy ? (float)tb_rng_double(&rng) * 1.2f - 0.1f : run;
                    tb_image_at(img, x, y)[c] = v;
                }
        }
        tb_image_set_attr(img, "software", "test_rle");
        tb_image_set_attr(img, "seed", "x=y=z"); /* '=' is fine in values */
        tb_image_write_options wo = {.encoding = enc};
        tb_image_read_options ro = {.encoding = enc};
        size_t n;
        tb_status st;
        unsigned char *p = write_mem(img, &wo, &n, &st);
        assert_int_equal(st, TB_OK);
        tb_image *back = NULL;
        st = read_bytes(p, n, &ro, &back);
        if (st)
            fail_msg("iteration %d (%dx%d): %s", iter, w, h, tb_last_error());
        assert_int_equal(back->width, w);
        assert_int_equal(back->height, h);
        assert_int_equal(back->channels, nch[l]);
        for (int c = 0; c < nch[l]; c++)
            assert_string_equal(back->names[c], layouts[l][c]);
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++)
                for (int c = 0; c < nch[l]; c++) {
                    tb_image_encoding e = strcmp(layouts[l][c], "A") == 0 ? TB_ENCODING_LINEAR : enc;
                    float want = tb_image_dequantize8(tb_image_quantize8(tb_image_at(img, x, y)[c], e), e);
                    if (tb_image_at(back, x, y)[c] != want)
                        fail_msg("iteration %d: pixel (%d,%d) channel %d: %g, want %g", iter, x, y,
                                 c, tb_image_at(back, x, y)[c], want);
                }
        assert_string_equal(tb_image_get_attr(back, "software"), "test_rle");
        assert_string_equal(tb_image_get_attr(back, "seed"), "x=y=z");
        tb_image_free(back);
        free(p);
        tb_image_free(img);
    }
}

/* Long runs compress; exposure scales colour but not alpha. */
static void test_write_runs_and_exposure(void **state)
{
    (void)state;
    tb_image *img = tb_image_create(700, 3, 4, NULL);
    for (size_t i = 0; i < 700 * 3; i++) {
        img->pixels[4 * i + 0] = 0.25f;
        img->pixels[4 * i + 1] = 0.125f;
        img->pixels[4 * i + 2] = 0.0f;
        img->pixels[4 * i + 3] = 0.5f;
    }
    size_t n;
    tb_status st;
    tb_image_write_options wo = {.encoding = TB_ENCODING_LINEAR, .exposure = 1.0f};
    unsigned char *p = write_mem(img, &wo, &n, &st);
    assert_int_equal(st, TB_OK);
    /* per row: 4 x (SetColor 2 + long RunData 6), plus SkipLines */
    assert_true(n < 16 + 3 * 4 * 8 + 2 * 2 + 2 + 1);
    tb_image *back = NULL;
    assert_int_equal(read_bytes(p, n, &linear_in, &back), TB_OK);
    const float *px = tb_image_at(back, 699, 2);
    assert_int_equal(CODE(px[0]), CODE(0.5f));
    assert_int_equal(CODE(px[1]), CODE(0.25f));
    assert_int_equal(CODE(px[2]), 0);
    assert_int_equal(CODE(px[3]), CODE(0.5f));
    tb_image_free(back);
    free(p);
    tb_image_free(img);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_read_opcodes_and_orientation),
        cmocka_unit_test(test_read_background),
        cmocka_unit_test(test_read_alpha),
        cmocka_unit_test(test_read_colour_maps),
        cmocka_unit_test(test_truncated_everywhere),
        cmocka_unit_test(test_malformed),
        cmocka_unit_test(test_write_exact_bytes),
        cmocka_unit_test(test_write_errors),
        cmocka_unit_test(test_round_trip_property),
        cmocka_unit_test(test_write_runs_and_exposure),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
