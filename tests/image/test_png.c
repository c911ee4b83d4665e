/* PNG: round trips exact on integer codes (checked against a plain libpng
 * decode with no conversions), every colour type libpng can store read back
 * with the expected values, text chunks, and malformed files. */
#include "tb_test.h"

#include <png.h>
#include <string.h>

#include "util/image/image.h"

/* ------------------------------------------------------------ helpers */

/* Nonzero if `needle` occurs in `hay` (memmem is not POSIX). */
static int contains(const char *hay, size_t n, const char *needle, size_t m)
{
    for (size_t i = 0; i + m <= n; i++)
        if (memcmp(hay + i, needle, m) == 0)
            return 1;
    return 0;
}

/* Writes `img` to memory with our writer; the caller frees *buf. */
static tb_status write_mem(const tb_image *img, const tb_image_write_options *o, char **buf, size_t *len)
{
    *buf = NULL;
    *len = 0;
    FILE *f = open_memstream(buf, len);
    assert_non_null(f);
    tb_status st = tb_png_write(f, "mem.png", img, o);
    fclose(f);
    return st;
}

static tb_status read_mem(const void *data, size_t n, const tb_image_read_options *o, tb_image **out)
{
    FILE *f = n ? fmemopen((void *)data, n, "rb") : tmpfile();
    assert_non_null(f);
    tb_status st = tb_png_read(f, "mem.png", o, out);
    fclose(f);
    return st;
}

/* A PNG decoded by libpng with no transformations at all: the stored codes. */
typedef struct raw_png {
    png_uint_32 w, h;
    int depth, color, channels;
    unsigned char *data; /* rows, each w * channels * depth/8 bytes */
    size_t rowbytes;
} raw_png;

typedef struct mem_reader {
    const unsigned char *p;
    size_t n, off;
} mem_reader;

static void mem_read_fn(png_structp png, png_bytep out, png_size_t n)
{
    mem_reader *r = png_get_io_ptr(png);
    if (r->off + n > r->n)
        png_error(png, "test reader: out of data");
    memcpy(out, r->p + r->off, n);
    r->off += n;
}

static void raw_decode(const void *data, size_t n, raw_png *out)
{
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png_create_info_struct(png);
    mem_reader r = {data, n, 0};
    unsigned char *volatile buf = NULL;
    png_bytep *volatile rows = NULL;
    if (setjmp(png_jmpbuf(png)))
        fail_msg("reference libpng decode failed");
    png_set_read_fn(png, &r, mem_read_fn);
    png_read_info(png, info);
    out->w = png_get_image_width(png, info);
    out->h = png_get_image_height(png, info);
    out->depth = png_get_bit_depth(png, info);
    out->color = png_get_color_type(png, info);
    out->channels = png_get_channels(png, info);
    out->rowbytes = png_get_rowbytes(png, info);
    buf = malloc(out->rowbytes * out->h);
    rows = malloc(sizeof *rows * out->h);
    for (png_uint_32 y = 0; y < out->h; y++)
        rows[y] = buf + y * out->rowbytes;
    png_read_image(png, rows);
    png_read_end(png, NULL);
    png_destroy_read_struct(&png, &info, NULL);
    free(rows);
    out->data = buf;
}

/* Code of channel c of pixel (x, y) in a raw decode. */
static unsigned raw_code(const raw_png *r, int x, int y, int c)
{
    const unsigned char *p = r->data + (size_t)y * r->rowbytes;
    size_t i = (size_t)x * (size_t)r->channels + (size_t)c;
    return r->depth == 16 ? (unsigned)(p[2 * i] << 8 | p[2 * i + 1]) : p[i];
}

/* Writes a PNG with plain libpng (not our writer): the rows are given as
 * stored. Returns the bytes in *buf (caller frees). */
static void raw_encode(int w, int h, int depth, int color, int interlace, const png_color *palette,
                       int npalette, const png_byte *trans, int ntrans, const png_color_16 *trans_color,
                       const unsigned char *rows_data, size_t rowbytes, char **buf, size_t *len)
{
    FILE *f = open_memstream(buf, len);
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png_create_info_struct(png);
    if (setjmp(png_jmpbuf(png)))
        fail_msg("reference libpng encode failed");
    png_init_io(png, f);
    png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, depth, color, interlace,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    if (palette)
        png_set_PLTE(png, info, palette, npalette);
    if (trans || trans_color)
        png_set_tRNS(png, info, trans, ntrans, trans_color);
    png_write_info(png, info);
    png_bytep *rows = malloc(sizeof *rows * (size_t)h);
    for (int y = 0; y < h; y++)
        rows[y] = (png_bytep)rows_data + (size_t)y * rowbytes;
    png_write_image(png, rows);
    png_write_end(png, NULL);
    png_destroy_write_struct(&png, &info);
    free(rows);
    fclose(f);
}

/* ------------------------------------------------------------ round trips */

/* Random integer codes, 1-4 channels, 8 and 16 bits, both encodings: the
 * file holds exactly those codes, and reading gives back the same floats. */
static void test_round_trip_codes(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("png round trip", 2024), 0);
    for (int bits = 8; bits <= 16; bits += 8) {
        for (int enc = 0; enc < 2; enc++) {
            for (int ch = 1; ch <= 4; ch++) {
                int w = 1 + (int)tb_rng_below(&rng, 23), h = 1 + (int)tb_rng_below(&rng, 11);
                tb_image *img = tb_image_create(w, h, ch, NULL);
                unsigned *codes = malloc(sizeof *codes * (size_t)w * h * ch);
                int alpha = ch == 2 || ch == 4;
                for (int i = 0; i < w * h * ch; i++) {
                    unsigned max = bits == 8 ? 255u : 65535u;
                    codes[i] = i < ch ? (i % 2 ? max : 0) : tb_rng_below(&rng, max + 1); /* extremes too */
                    tb_image_encoding e = alpha && i % ch == ch - 1 ? TB_ENCODING_LINEAR : (tb_image_encoding)enc;
                    img->pixels[i] = bits == 8 ? tb_image_dequantize8((unsigned char)codes[i], e)
                                               : tb_image_dequantize16((unsigned short)codes[i], e);
                }
                tb_image_write_options o = {.png_bits = bits, .encoding = (tb_image_encoding)enc};
                char *buf;
                size_t len;
                assert_int_equal(write_mem(img, &o, &buf, &len), TB_OK);

                raw_png r;
                raw_decode(buf, len, &r);
                assert_int_equal(r.w, (png_uint_32)w);
                assert_int_equal(r.h, (png_uint_32)h);
                assert_int_equal(r.channels, ch);
                assert_int_equal(r.depth, bits);
                for (int y = 0; y < h; y++)
                    for (int x = 0; x < w; x++)
                        for (int c = 0; c < ch; c++)
                            if (raw_code(&r, x, y, c) != codes[(y * w + x) * ch + c])
                                fail_msg("%d-bit, %d channels, enc %d: pixel (%d,%d,%d) stored %u, "
                                         "expected %u", bits, ch, enc, x, y, c, raw_code(&r, x, y, c),
                                         codes[(y * w + x) * ch + c]);
                free(r.data);

                tb_image_read_options ro = {.encoding = (tb_image_encoding)enc};
                tb_image *back = NULL;
                assert_int_equal(read_mem(buf, len, &ro, &back), TB_OK);
                assert_int_equal(back->channels, ch);
                assert_memory_equal(back->pixels, img->pixels, sizeof(float) * (size_t)w * h * ch);
                if (alpha)
                    assert_string_equal(back->names[ch - 1], "A");
                tb_image_free(back);
                free(buf);
                free(codes);
                tb_image_free(img);
            }
        }
    }
}

/* Alpha is stored linearly even in sRGB files, and exposure leaves it alone. */
static void test_alpha_linear_and_exposure(void **state)
{
    (void)state;
    tb_image *img = tb_image_create(1, 1, 4, NULL);
    float v[4] = {0.25f, 0.5f, 0.125f, 0.5f};
    memcpy(img->pixels, v, sizeof v);
    char *buf;
    size_t len;
    tb_image_write_options o = {.encoding = TB_ENCODING_LINEAR, .exposure = 1.0f};
    assert_int_equal(write_mem(img, &o, &buf, &len), TB_OK);
    raw_png r;
    raw_decode(buf, len, &r);
    /* colour doubled: 0.5*255 = 127.5 -> 128, 1.0 -> 255, 0.25*255 = 63.75 -> 64; alpha 0.5 -> 128 */
    assert_int_equal(raw_code(&r, 0, 0, 0), 128);
    assert_int_equal(raw_code(&r, 0, 0, 1), 255);
    assert_int_equal(raw_code(&r, 0, 0, 2), 64);
    assert_int_equal(raw_code(&r, 0, 0, 3), 128);
    free(r.data);
    free(buf);

    tb_image_write_options s = {0}; /* sRGB */
    assert_int_equal(write_mem(img, &s, &buf, &len), TB_OK);
    raw_decode(buf, len, &r);
    assert_int_equal(raw_code(&r, 0, 0, 1), 188); /* sRGB(0.5) * 255 = 187.52 */
    assert_int_equal(raw_code(&r, 0, 0, 3), 128); /* alpha: linear */
    free(r.data);
    free(buf);
    tb_image_free(img);
}

/* ------------------------------------------------------------ colour types */

static void test_read_palette_with_transparency(void **state)
{
    (void)state;
    const png_color pal[3] = {{255, 0, 0}, {0, 128, 255}, {10, 20, 30}};
    const png_byte trans[2] = {0, 200}; /* entry 2 is opaque */
    /* 4 x 2 pixels, 2 bits per index: row bytes hold four indices, MSB first. */
    const unsigned char idx[2][4] = {{0, 1, 2, 1}, {2, 2, 0, 0}};
    unsigned char rows[2][1];
    for (int y = 0; y < 2; y++)
        rows[y][0] = (unsigned char)(idx[y][0] << 6 | idx[y][1] << 4 | idx[y][2] << 2 | idx[y][3]);
    char *buf;
    size_t len;
    raw_encode(4, 2, 2, PNG_COLOR_TYPE_PALETTE, PNG_INTERLACE_NONE, pal, 3, trans, 2, NULL, &rows[0][0], 1,
               &buf, &len);
    tb_image_read_options ro = {.encoding = TB_ENCODING_LINEAR};
    tb_image *img = NULL;
    assert_int_equal(read_mem(buf, len, &ro, &img), TB_OK);
    assert_int_equal(img->channels, 4);
    for (int y = 0; y < 2; y++)
        for (int x = 0; x < 4; x++) {
            const png_color *c = &pal[idx[y][x]];
            const float *p = tb_image_at(img, x, y);
            assert_true(p[0] == c->red / 255.0f);
            assert_true(p[1] == c->green / 255.0f);
            assert_true(p[2] == c->blue / 255.0f);
            assert_true(p[3] == (idx[y][x] < 2 ? trans[idx[y][x]] : 255) / 255.0f);
        }
    tb_image_free(img);
    free(buf);
}

static void test_read_grey_low_bits_and_trns(void **state)
{
    (void)state;
    /* 1-bit grey, 9 pixels wide: 0 -> 0, 1 -> 255 after expansion. */
    const unsigned char bits1[2][2] = {{0xa5, 0x80}, {0x0f, 0x00}}; /* 10100101 1 / 00001111 0 */
    char *buf;
    size_t len;
    raw_encode(9, 2, 1, PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE, NULL, 0, NULL, 0, NULL, &bits1[0][0], 2,
               &buf, &len);
    tb_image *img = NULL;
    assert_int_equal(read_mem(buf, len, NULL, &img), TB_OK);
    assert_int_equal(img->channels, 1);
    assert_string_equal(img->names[0], "Y");
    for (int y = 0; y < 2; y++)
        for (int x = 0; x < 9; x++) {
            int bit = bits1[y][x / 8] >> (7 - x % 8) & 1;
            assert_true(tb_image_at(img, x, y)[0] == (bit ? 1.0f : 0.0f));
        }
    tb_image_free(img);
    free(buf);

    /* 8-bit grey where code 7 is transparent: becomes grey + alpha. */
    const unsigned char g[3] = {7, 8, 255};
    png_color_16 tc = {.gray = 7};
    raw_encode(3, 1, 8, PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE, NULL, 0, NULL, 0, &tc, g, 3, &buf, &len);
    img = NULL;
    assert_int_equal(read_mem(buf, len, NULL, &img), TB_OK);
    assert_int_equal(img->channels, 2);
    assert_string_equal(img->names[1], "A");
    for (int x = 0; x < 3; x++) {
        assert_true(img->pixels[2 * x] == tb_image_dequantize8(g[x], TB_ENCODING_SRGB));
        assert_true(img->pixels[2 * x + 1] == (x == 0 ? 0.0f : 1.0f));
    }
    tb_image_free(img);
    free(buf);
}

static void test_read_interlaced_16bit(void **state)
{
    (void)state;
    enum { W = 13, H = 7 };
    unsigned char rows[H][W * 4 * 2];
    for (int y = 0; y < H; y++)
        for (int i = 0; i < W * 4; i++) {
            unsigned v = (unsigned)(y * 7919 + i * 613) & 0xffff;
            rows[y][2 * i] = (unsigned char)(v >> 8);
            rows[y][2 * i + 1] = (unsigned char)v;
        }
    char *buf;
    size_t len;
    raw_encode(W, H, 16, PNG_COLOR_TYPE_RGB_ALPHA, PNG_INTERLACE_ADAM7, NULL, 0, NULL, 0, NULL, &rows[0][0],
               sizeof rows[0], &buf, &len);
    tb_image_read_options ro = {.encoding = TB_ENCODING_LINEAR};
    tb_image *img = NULL;
    assert_int_equal(read_mem(buf, len, &ro, &img), TB_OK);
    assert_int_equal(img->channels, 4);
    for (int y = 0; y < H; y++)
        for (int i = 0; i < W * 4; i++) {
            unsigned v = (unsigned)(y * 7919 + i * 613) & 0xffff;
            assert_true(img->pixels[y * W * 4 + i] == (float)v / 65535.0f);
        }
    tb_image_free(img);
    free(buf);
}

/* ------------------------------------------------------------ text chunks */

static void test_text_round_trip(void **state)
{
    (void)state;
    tb_image *img = tb_image_create(2, 1, 3, NULL);
    assert_int_equal(tb_image_set_attr(img, "Software", "testbed 0.1"), TB_OK);
    assert_int_equal(tb_image_set_attr(img, "testbed:scene", "cornell box\nline two"), TB_OK);
    assert_int_equal(tb_image_set_attr(img, "Author", "J\xc3\xbcrgen \xe2\x9c\x93"), TB_OK); /* UTF-8 */
    assert_int_equal(tb_image_set_attr(img, "Empty", ""), TB_OK);
    char *buf;
    size_t len;
    assert_int_equal(write_mem(img, NULL, &buf, &len), TB_OK);
    assert_true(contains(buf, len, "tEXtSoftware\0testbed 0.1", 24));
    assert_true(contains(buf, len, "iTXtAuthor", 10)); /* non-ASCII: iTXt */
    tb_image *back = NULL;
    assert_int_equal(read_mem(buf, len, NULL, &back), TB_OK);
    assert_int_equal(back->nattrs, 4);
    for (int i = 0; i < img->nattrs; i++) {
        const char *v = tb_image_get_attr(back, img->attrs[i].key);
        assert_non_null(v);
        assert_string_equal(v, img->attrs[i].value);
    }
    tb_image_free(back);
    free(buf);

    const char *bad_keys[] = {" lead", "trail ", "dou  ble", "", "caf\xc3\xa9",
                              "0123456789012345678901234567890123456789012345678901234567890123456789012345678X"};
    for (size_t k = 0; k < sizeof bad_keys / sizeof *bad_keys; k++) {
        tb_image *b = tb_image_create(1, 1, 1, NULL);
        if (bad_keys[k][0]) {
            assert_int_equal(tb_image_set_attr(b, bad_keys[k], "v"), TB_OK);
        } else { /* set_attr refuses empty keys; plant one to test the writer */
            assert_int_equal(tb_image_set_attr(b, "x", "v"), TB_OK);
            b->attrs[0].key[0] = '\0';
        }
        assert_int_equal(write_mem(b, NULL, &buf, &len), TB_ERR_ARG);
        assert_non_null(strstr(tb_last_error(), "PNG text keyword"));
        free(buf);
        tb_image_free(b);
    }
    tb_image_free(img);
}

/* Latin-1 tEXt written by another program reads back as UTF-8. */
static void test_text_latin1(void **state)
{
    (void)state;
    FILE *f;
    char *buf;
    size_t len;
    f = open_memstream(&buf, &len);
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png_create_info_struct(png);
    if (setjmp(png_jmpbuf(png)))
        fail_msg("libpng failed");
    png_init_io(png, f);
    png_set_IHDR(png, info, 1, 1, 8, PNG_COLOR_TYPE_GRAY, 0, 0, 0);
    png_text t = {.compression = PNG_TEXT_COMPRESSION_zTXt, .key = "Comment", .text = "caf\xe9"};
    t.text_length = 4;
    png_set_text(png, info, &t, 1);
    png_write_info(png, info);
    png_byte row[1] = {0};
    png_write_row(png, row);
    png_write_end(png, NULL);
    png_destroy_write_struct(&png, &info);
    fclose(f);
    tb_image *img = NULL;
    assert_int_equal(read_mem(buf, len, NULL, &img), TB_OK);
    assert_string_equal(tb_image_get_attr(img, "Comment"), "caf\xc3\xa9");
    tb_image_free(img);
    free(buf);
}

/* ------------------------------------------------------------ errors */

static void test_write_errors(void **state)
{
    (void)state;
    char *buf;
    size_t len;
    tb_image *img = tb_image_create(2, 2, 5, NULL);
    assert_int_equal(write_mem(img, NULL, &buf, &len), TB_ERR_UNSUPPORTED);
    assert_non_null(strstr(tb_last_error(), "1 to 4 channels"));
    free(buf);
    tb_image_free(img);
    img = tb_image_create(2, 2, 3, NULL);
    tb_image_write_options o = {.png_bits = 12};
    assert_int_equal(write_mem(img, &o, &buf, &len), TB_ERR_ARG);
    assert_non_null(strstr(tb_last_error(), "8 or 16"));
    free(buf);
    o.png_bits = 8;
    o.exposure = NAN;
    assert_int_equal(write_mem(img, &o, &buf, &len), TB_ERR_ARG);
    free(buf);
    tb_image_free(img);
}

static uint32_t crc32_of(const unsigned char *p, size_t n)
{
    uint32_t c = 0xffffffffu;
    for (size_t i = 0; i < n; i++) {
        c ^= p[i];
        for (int k = 0; k < 8; k++)
            c = c & 1 ? 0xedb88320u ^ (c >> 1) : c >> 1;
    }
    return c ^ 0xffffffffu;
}

static void put_be32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)(v >> 24);
    p[1] = (unsigned char)(v >> 16);
    p[2] = (unsigned char)(v >> 8);
    p[3] = (unsigned char)v;
}

/* A valid file whose IHDR claims w x h (CRC fixed up, so libpng gets as far
 * as the size checks). */
static void resize_ihdr(unsigned char *png, uint32_t w, uint32_t h)
{
    /* signature (8), length (4), "IHDR" (4), data (13), CRC (4) */
    put_be32(png + 16, w);
    put_be32(png + 20, h);
    put_be32(png + 29, crc32_of(png + 12, 17));
}

static void test_malformed(void **state)
{
    (void)state;
    tb_image *img = tb_image_create(6, 5, 3, NULL);
    for (int i = 0; i < 6 * 5 * 3; i++)
        img->pixels[i] = (float)i / 90.0f;
    assert_int_equal(tb_image_set_attr(img, "k", "v"), TB_OK);
    char *buf;
    size_t len;
    assert_int_equal(write_mem(img, NULL, &buf, &len), TB_OK);
    tb_image_free(img);
    unsigned char *p = (unsigned char *)buf;
    assert_int_equal(crc32_of(p + 12, 17), (uint32_t)p[29] << 24 | (uint32_t)p[30] << 16 | (uint32_t)p[31] << 8 | p[32]);

    /* Every cut is an error: the reader insists on IEND. */
    for (size_t n = 0; n < len; n++) {
        img = NULL;
        tb_status st = read_mem(buf, n, NULL, &img);
        if (st != TB_ERR_FORMAT)
            fail_msg("cut at %zu of %zu: status %d (%s)", n, len, st, tb_last_error());
        assert_null(img);
        assert_non_null(strstr(tb_last_error(), "mem.png"));
    }
    /* Flipping a byte of the signature or IHDR is always caught; elsewhere the
     * CRC catches it in critical chunks, while a damaged ancillary chunk is
     * dropped. Either way: no crash, a clean status, no half image. */
    unsigned char *copy = malloc(len);
    for (size_t i = 0; i < len; i++) {
        memcpy(copy, buf, len);
        copy[i] ^= 0xff;
        img = NULL;
        tb_status st = read_mem(copy, len, NULL, &img);
        if (i < 33 && st == TB_OK)
            fail_msg("flipped header byte %zu accepted", i);
        assert_true(st == TB_OK || st == TB_ERR_FORMAT);
        assert_true((st == TB_OK) == (img != NULL));
        tb_image_free(img);
    }

    /* Absurd sizes: beyond libpng's limits, and within them but far beyond
     * what the file's bytes can hold. */
    const uint32_t sizes[][2] = {{0x7fffffffu, 0x7fffffffu}, {0x80000000u, 1}, {1000000, 1000000}, {0, 5}};
    for (size_t s = 0; s < sizeof sizes / sizeof *sizes; s++) {
        memcpy(copy, buf, len);
        resize_ihdr(copy, sizes[s][0], sizes[s][1]);
        img = NULL;
        tb_status st = read_mem(copy, len, NULL, &img);
        if (st != TB_ERR_FORMAT)
            fail_msg("IHDR %u x %u: status %d (%s)", sizes[s][0], sizes[s][1], st, tb_last_error());
        assert_null(img);
    }
    memcpy(copy, buf, len);
    resize_ihdr(copy, 1000000, 1000000);
    read_mem(copy, len, NULL, &img);
    assert_non_null(strstr(tb_last_error(), "far more than"));

    const char *not_png[] = {"", "\x89PNG", "GIF89a........", "\x89PNG\r\n\x1a\n"};
    for (size_t k = 0; k < 4; k++) {
        img = NULL;
        size_t n = k == 3 ? 8 : strlen(not_png[k]);
        assert_int_equal(read_mem(not_png[k], n, NULL, &img), TB_ERR_FORMAT);
        assert_null(img);
    }
    free(copy);
    free(buf);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_round_trip_codes),
        cmocka_unit_test(test_alpha_linear_and_exposure),
        cmocka_unit_test(test_read_palette_with_transparency),
        cmocka_unit_test(test_read_grey_low_bits_and_trns),
        cmocka_unit_test(test_read_interlaced_16bit),
        cmocka_unit_test(test_text_round_trip),
        cmocka_unit_test(test_text_latin1),
        cmocka_unit_test(test_write_errors),
        cmocka_unit_test(test_malformed),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
