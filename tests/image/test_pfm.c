/* PFM: files built byte by byte from the format description are read as
 * expected, writes produce exactly the expected bytes, round trips are bit
 * exact, and every malformed or truncated input is a clear error. */
#include "tb_test.h"

#include <stdint.h>
#include <string.h>
#include <unistd.h>

#include "util/image/image.h"

/* A growable byte string for building files. */
typedef struct bytes {
    unsigned char b[4096];
    size_t n;
} bytes;

static void put_str(bytes *d, const char *s)
{
    size_t k = strlen(s);
    memcpy(d->b + d->n, s, k);
    d->n += k;
}

static void put_u32(bytes *d, uint32_t u, int little)
{
    for (int i = 0; i < 4; i++)
        d->b[d->n++] = (unsigned char)(little ? u >> (8 * i) : u >> (8 * (3 - i)));
}

static uint32_t bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    return u;
}

/* Reads `n` bytes as a PFM from memory. */
static tb_status read_mem(const void *data, size_t n, tb_image **out)
{
    if (n == 0) { /* fmemopen() may refuse an empty buffer; use an empty file */
        FILE *f = tmpfile();
        tb_status st = tb_pfm_read(f, "mem.pfm", out);
        fclose(f);
        return st;
    }
    FILE *f = fmemopen((void *)data, n, "rb");
    assert_non_null(f);
    tb_status st = tb_pfm_read(f, "mem.pfm", out);
    fclose(f);
    return st;
}

/* The same through a pipe, which cannot seek (the reader's other path). */
static tb_status read_pipe(const void *data, size_t n, tb_image **out)
{
    int fd[2];
    assert_int_equal(pipe(fd), 0);
    assert_true(n < 60000); /* fits in the pipe buffer: no writer thread needed */
    assert_int_equal(write(fd[1], data, n), (ssize_t)n);
    close(fd[1]);
    FILE *f = fdopen(fd[0], "rb");
    assert_non_null(f);
    tb_status st = tb_pfm_read(f, "pipe.pfm", out);
    fclose(f);
    return st;
}

/* A 2 x 2 little-endian RGB file: the bottom row comes first in the file. */
static void test_read_little_endian_rgb(void **state)
{
    (void)state;
    bytes d = {0};
    put_str(&d, "PF\n2 2\n-1.0\n");
    /* bottom row (our y = 1) */
    const uint32_t bottom[6] = {0x3f800000u /* 1 */, 0x40000000u /* 2 */, 0x40400000u /* 3 */,
                                0xbf000000u /* -0.5 */, 0x00000001u /* 2^-149 */, 0x7f800000u /* inf */};
    const uint32_t top[6] = {0x00000000u, 0x80000000u /* -0 */, 0x3e800000u /* 0.25 */,
                             0x42c80000u /* 100 */, 0x7f7fffffu /* FLT_MAX */, 0xc1200000u /* -10 */};
    for (int i = 0; i < 6; i++)
        put_u32(&d, bottom[i], 1);
    for (int i = 0; i < 6; i++)
        put_u32(&d, top[i], 1);
    for (int via_pipe = 0; via_pipe < 2; via_pipe++) {
        tb_image *img = NULL;
        assert_int_equal(via_pipe ? read_pipe(d.b, d.n, &img) : read_mem(d.b, d.n, &img), TB_OK);
        assert_int_equal(img->width, 2);
        assert_int_equal(img->height, 2);
        assert_int_equal(img->channels, 3);
        assert_string_equal(img->names[0], "R");
        for (int i = 0; i < 6; i++) {
            assert_int_equal(bits(img->pixels[i]), top[i]);
            assert_int_equal(bits(img->pixels[6 + i]), bottom[i]);
        }
        assert_true(img->pixels[0 * 3 + 2] == 0.25f);
        assert_true(img->pixels[1 * 3 + 0] == 100.0f);
        assert_true(tb_image_at(img, 0, 1)[0] == 1.0f);
        tb_image_free(img);
    }
}

/* Grey, big-endian (positive scale, any magnitude), odd white space. */
static void test_read_big_endian_grey(void **state)
{
    (void)state;
    const char *headers[] = {"Pf\n3 1\n1.0\n", "Pf 3 1 +2.5e0 ", "Pf\t3\r\n1\n\n 1\n", "Pf\n0003 1\n.5E-3\n"};
    for (size_t h = 0; h < sizeof headers / sizeof *headers; h++) {
        bytes d = {0};
        put_str(&d, headers[h]);
        put_u32(&d, bits(1.5f), 0);
        put_u32(&d, bits(-3.0f), 0);
        put_u32(&d, bits(0.125f), 0);
        tb_image *img = NULL;
        if (read_mem(d.b, d.n, &img) != TB_OK)
            fail_msg("header %zu: %s", h, tb_last_error());
        assert_int_equal(img->channels, 1);
        assert_string_equal(img->names[0], "Y");
        assert_true(img->pixels[0] == 1.5f && img->pixels[1] == -3.0f && img->pixels[2] == 0.125f);
        tb_image_free(img);
    }
}

/* Our writer's bytes, exactly: header, little-endian floats, bottom row first. */
static void test_write_bytes(void **state)
{
    (void)state;
    tb_image *img = tb_image_create(1, 2, 3, NULL);
    const float v[6] = {1.0f, -2.0f, 0.5f, /* top */ 3.0f, 0.0f, -0.25f /* bottom */};
    memcpy(img->pixels, v, sizeof v);
    char buf[256] = {0};
    FILE *f = fmemopen(buf, sizeof buf, "wb");
    assert_int_equal(tb_pfm_write(f, "x.pfm", img, NULL), TB_OK);
    long n = ftell(f);
    fclose(f);
    bytes d = {0};
    put_str(&d, "PF\n1 2\n-1.0\n");
    for (int i = 3; i < 6; i++)
        put_u32(&d, bits(v[i]), 1);
    for (int i = 0; i < 3; i++)
        put_u32(&d, bits(v[i]), 1);
    assert_int_equal(n, (long)d.n);
    assert_memory_equal(buf, d.b, d.n);

    /* Exposure +2 stops multiplies by 4. */
    f = fmemopen(buf, sizeof buf, "wb");
    tb_image_write_options o = {.exposure = 2.0f};
    assert_int_equal(tb_pfm_write(f, "x.pfm", img, &o), TB_OK);
    fclose(f);
    tb_image *back = NULL;
    assert_int_equal(read_mem(buf, d.n, &back), TB_OK);
    for (int i = 0; i < 6; i++)
        assert_true(back->pixels[i] == 4.0f * v[i]);
    tb_image_free(back);
    tb_image_free(img);
}

static void test_write_rejects_channel_counts(void **state)
{
    (void)state;
    for (int c = 2; c <= 5; c += (c == 2 ? 2 : 1)) {
        tb_image *img = tb_image_create(2, 2, c, NULL);
        char buf[256];
        FILE *f = fmemopen(buf, sizeof buf, "wb");
        assert_int_equal(tb_pfm_write(f, "x.pfm", img, NULL), TB_ERR_UNSUPPORTED);
        assert_non_null(strstr(tb_last_error(), "1 (grey) or 3 (RGB)"));
        fclose(f);
        tb_image_free(img);
    }
}

/* Random sizes and random bit patterns (NaN payloads, denormals, infinities
 * included) come back bit for bit. */
static void test_round_trip_random_bits(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("pfm round trip", 1991), 0);
    for (int iter = 0; iter < 40; iter++) {
        int w = 1 + (int)tb_rng_below(&rng, 17), h = 1 + (int)tb_rng_below(&rng, 9);
        int c = tb_rng_below(&rng, 2) ? 3 : 1;
        tb_image *img = tb_image_create(w, h, c, NULL);
        size_t n = (size_t)w * h * c;
        for (size_t i = 0; i < n; i++) {
            uint32_t u = tb_rng_u32(&rng);
            memcpy(&img->pixels[i], &u, 4);
        }
        char *buf = NULL;
        size_t len = 0;
        FILE *f = open_memstream(&buf, &len);
        assert_int_equal(tb_pfm_write(f, "r.pfm", img, NULL), TB_OK);
        fclose(f);
        tb_image *back = NULL;
        assert_int_equal(read_mem(buf, len, &back), TB_OK);
        assert_int_equal(back->width, w);
        assert_int_equal(back->height, h);
        assert_int_equal(back->channels, c);
        assert_memory_equal(back->pixels, img->pixels, n * 4);
        free(buf);
        tb_image_free(back);
        tb_image_free(img);
    }
}

/* Two images back to back in one stream: each read stops at its own end. */
static void test_concatenated(void **state)
{
    (void)state;
    bytes d = {0};
    put_str(&d, "Pf\n1 1\n-1\n");
    put_u32(&d, bits(7.0f), 1);
    put_str(&d, "PF\n1 1\n1\n");
    put_u32(&d, bits(1.0f), 0);
    put_u32(&d, bits(2.0f), 0);
    put_u32(&d, bits(3.0f), 0);
    FILE *f = fmemopen(d.b, d.n, "rb");
    tb_image *a = NULL, *b = NULL;
    assert_int_equal(tb_pfm_read(f, "two", &a), TB_OK);
    assert_int_equal(tb_pfm_read(f, "two", &b), TB_OK);
    fclose(f);
    assert_true(a->pixels[0] == 7.0f);
    assert_true(b->pixels[0] == 1.0f && b->pixels[2] == 3.0f);
    tb_image_free(a);
    tb_image_free(b);
}

typedef struct bad_case {
    const char *text;   /* the whole file */
    tb_status status;
    const char *message; /* expected in tb_last_error() */
} bad_case;

static void test_malformed(void **state)
{
    (void)state;
    static const bad_case cases[] = {
        {"", TB_ERR_FORMAT, "empty file"},
        {"P6\n1 1\n255\n\x01\x02\x03", TB_ERR_FORMAT, "not a PFM"},
        {"PF4\n1 1\n-1\n", TB_ERR_UNSUPPORTED, "PF4"},
        {"PFx\n1 1\n-1\n", TB_ERR_FORMAT, "white space"},
        {"pf\n1 1\n-1\n", TB_ERR_FORMAT, "not a PFM"},
        {"PF\n0 1\n-1\n", TB_ERR_FORMAT, "at least 1"},
        {"PF\n1 0\n-1\n", TB_ERR_FORMAT, "at least 1"},
        {"PF\n-1 1\n-1\n", TB_ERR_FORMAT, "not a positive integer"},
        {"PF\n1x 1\n-1\n", TB_ERR_FORMAT, "not a positive integer"},
        {"PF\n# comment\n1 1\n-1\n", TB_ERR_FORMAT, "not a positive integer"},
        {"PF\n1 1\n0.0\n", TB_ERR_FORMAT, "scale is zero"},
        {"PF\n1 1\n-0\n", TB_ERR_FORMAT, "scale is zero"},
        {"PF\n1 1\nabc\n", TB_ERR_FORMAT, "not a number"},
        {"PF\n1 1\n1e\n", TB_ERR_FORMAT, "not a number"},
        {"PF\n1 1\n1,5\n", TB_ERR_FORMAT, "not a number"},
        {"PF\n1 1\nnan\n", TB_ERR_FORMAT, "not a number"},
        {"PF\n1 1\n-inf\n", TB_ERR_FORMAT, "not a number"},
        {"PF\n1 1\n.\n", TB_ERR_FORMAT, "not a number"},
        {"PF\n2147483648 1\n-1\n", TB_ERR_FORMAT, "too large"},
        {"PF\n99999999999999999999 1\n-1\n", TB_ERR_FORMAT, "too large"},
        {"PF\n2147483647 2147483647\n-1\n", TB_ERR_FORMAT, "too large"},
        {"Pf\n65536 65536\n-1\n\x01\x02\x03\x04", TB_ERR_FORMAT, "too large"},
        /* within the size limit but with 4 bytes of data: rejected before allocating */
        {"PF\n40000 10000\n-1\n\x01\x02\x03\x04", TB_ERR_FORMAT, "truncated"},
        {"PF\n1 1\n-1\n\x01\x02\x03\x04", TB_ERR_FORMAT, "truncated"},
        {"PF\n1 1\n-1", TB_ERR_FORMAT, "truncated"},
        {"PF\n1 1", TB_ERR_FORMAT, "truncated"},
        {"PF", TB_ERR_FORMAT, "truncated"},
        {"PF\n1 1\n-1.000000000000000000000000000000000000000000000000000000000000000000000000\n",
         TB_ERR_FORMAT, "too long"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        for (int via_pipe = 0; via_pipe < 2; via_pipe++) {
            tb_image *img = (tb_image *)&img; /* must be reset to NULL */
            size_t n = strlen(cases[i].text);
            tb_status st = via_pipe ? read_pipe(cases[i].text, n, &img) : read_mem(cases[i].text, n, &img);
            if (st != cases[i].status || !strstr(tb_last_error(), cases[i].message))
                fail_msg("case %zu (%s): status %d, message '%s'; expected %d, '%s'", i,
                         via_pipe ? "pipe" : "memory", st, tb_last_error(), cases[i].status,
                         cases[i].message);
            assert_null(img);
            assert_non_null(strstr(tb_last_error(), via_pipe ? "pipe.pfm" : "mem.pfm"));
        }
    }
}

/* Cut a valid file at every length: never accepted, always a format error.
 * Flip every header byte: always rejected. */
static void test_truncated_and_flipped(void **state)
{
    (void)state;
    bytes d = {0};
    put_str(&d, "PF\n3 2\n-1.0\n");
    size_t header = d.n;
    for (int i = 0; i < 18; i++)
        put_u32(&d, bits((float)i * 0.5f), 1);
    tb_image *img = NULL;
    assert_int_equal(read_mem(d.b, d.n, &img), TB_OK);
    tb_image_free(img);
    for (size_t len = 0; len < d.n; len++) {
        for (int via_pipe = 0; via_pipe < 2; via_pipe++) {
            img = NULL;
            tb_status st = via_pipe ? read_pipe(d.b, len, &img) : read_mem(d.b, len, &img);
            if (st != TB_ERR_FORMAT)
                fail_msg("cut at %zu: status %d (%s)", len, st, tb_last_error());
            assert_null(img);
        }
    }
    for (size_t i = 0; i < header; i++) {
        bytes e = d;
        e.b[i] ^= 0xff;
        img = NULL;
        tb_status st = read_mem(e.b, e.n, &img);
        if (st == TB_OK)
            fail_msg("flipped header byte %zu accepted", i);
        assert_null(img);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_read_little_endian_rgb),
        cmocka_unit_test(test_read_big_endian_grey),
        cmocka_unit_test(test_write_bytes),
        cmocka_unit_test(test_write_rejects_channel_counts),
        cmocka_unit_test(test_round_trip_random_bits),
        cmocka_unit_test(test_concatenated),
        cmocka_unit_test(test_malformed),
        cmocka_unit_test(test_truncated_and_flipped),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
