/* OpenEXR: round trips (FLOAT bit exact, HALF within half precision), any
 * channel names, string attributes; our header checked by an independent
 * parser written from the file-layout document; a file built byte by byte
 * (uncompressed, HALF/FLOAT/UINT, offset data window) and a tiled file read
 * correctly; damaged files rejected cleanly. */
#include "tb_test.h"

#include <openexr.h>
#include <stdint.h>
#include <string.h>
#include <unistd.h>

#include "util/image/image.h"

/* ------------------------------------------------------------ helpers */

static tb_status write_mem(const tb_image *img, const tb_image_write_options *o, char **buf, size_t *len)
{
    *buf = NULL;
    *len = 0;
    FILE *f = open_memstream(buf, len);
    assert_non_null(f);
    tb_status st = tb_exr_write_stream(f, "mem.exr", img, o);
    fclose(f);
    return st;
}

static tb_status read_mem(const void *data, size_t n, tb_image **out)
{
    FILE *f = n ? fmemopen((void *)data, n, "rb") : tmpfile();
    assert_non_null(f);
    tb_status st = tb_exr_read_stream(f, "mem.exr", out);
    fclose(f);
    return st;
}

static uint32_t fbits(float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    return u;
}

/* Nearest half to `v` is within this of v (normal halves: relative 2^-11;
 * subnormal ones: absolute 2^-25). */
static double half_tolerance(double v) { return fabs(v) * 0x1p-11 + 0x1p-25; }

/* ------------------------------------------------------------ round trips */

static void test_float_round_trip_bits(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("exr float round trip", 7), 0);
    for (int ch = 1; ch <= 5; ch++) {
        int w = 1 + (int)tb_rng_below(&rng, 40), h = 1 + (int)tb_rng_below(&rng, 40);
        tb_image *img = tb_image_create(w, h, ch, NULL);
        for (int i = 0; i < w * h * ch; i++) {
            uint32_t u = tb_rng_u32(&rng); /* every bit pattern: NaN payloads, denormals, inf */
            memcpy(&img->pixels[i], &u, 4);
        }
        char *buf;
        size_t len;
        assert_int_equal(write_mem(img, NULL, &buf, &len), TB_OK);
        tb_image *back = NULL;
        assert_int_equal(read_mem(buf, len, &back), TB_OK);
        assert_int_equal(back->width, w);
        assert_int_equal(back->height, h);
        assert_int_equal(back->channels, ch);
        for (int c = 0; c < ch; c++)
            assert_string_equal(back->names[c], img->names[c]); /* R,G,B,A order restored */
        assert_memory_equal(back->pixels, img->pixels, sizeof(float) * (size_t)w * h * ch);
        tb_image_free(back);
        free(buf);
        tb_image_free(img);
    }
}

/* A ZIP chunk whose compressed size comes out EQUAL to its raw size: the
 * reader takes a chunk of raw size as stored uncompressed, so the writer must
 * store such a chunk raw (OpenEXR 3.1's encoder falls back to raw only when
 * compression makes it strictly larger; a hybrid render at 64 x 64 once came
 * back with 15 garbage pixels near 3e38). One 16-row chunk of random floats
 * (incompressible: a few bytes more than raw) with a run of k equal values
 * after it: each value more in the run saves about four compressed bytes, so
 * over k = 0 .. 24 the compressed size steps down through the raw size, and
 * every image must read back bit for bit. */
static void test_zip_chunk_as_long_as_raw(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("exr zip equal to raw", 3), 0);
    const int w = 8, h = 16; /* one ZIP chunk (16 scanlines), 512 bytes */
    float noise[8 * 16];
    for (int i = 0; i < w * h; i++) {
        uint32_t u = tb_rng_u32(&rng) & 0x3fffffffu; /* finite, any magnitude */
        memcpy(&noise[i], &u, 4);
    }
    size_t shortest = SIZE_MAX, longest = 0;
    for (int k = 0; k <= 24; k++) {
        tb_image *img = tb_image_create(w, h, 1, NULL);
        assert_non_null(img);
        for (int i = 0; i < w * h; i++)
            img->pixels[i] = i < k ? 1.0f : noise[i];
        char *buf;
        size_t len;
        assert_int_equal(write_mem(img, NULL, &buf, &len), TB_OK);
        shortest = len < shortest ? len : shortest;
        longest = len > longest ? len : longest;
        tb_image *back = NULL;
        assert_int_equal(read_mem(buf, len, &back), TB_OK);
        for (int i = 0; i < w * h; i++)
            if (fbits(back->pixels[i]) != fbits(img->pixels[i]))
                fail_msg("k = %d: pixel %d wrote %a, read %a (file %zu bytes)", k, i, (double)img->pixels[i],
                         (double)back->pixels[i], len);
        tb_image_free(back);
        free(buf);
        tb_image_free(img);
    }
    /* the sweep crossed from stored raw (k = 0) to compressed: the file shrank */
    assert_true(shortest + 32 < longest);
}

static void test_half_round_trip(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("exr half round trip", 11), 0);
    tb_image *img = tb_image_create(37, 19, 3, NULL);
    size_t n = 37 * 19 * 3;
    for (size_t i = 0; i < n; i++) {
        double mag = pow(2.0, -20.0 + 34.0 * tb_rng_double(&rng)); /* 1e-6 .. 1.6e4 */
        img->pixels[i] = (float)(tb_rng_below(&rng, 2) ? mag : -mag);
    }
    /* Values that halves hold exactly come back exactly. */
    const float exact[] = {0.0f, -0.0f, 1.0f, -2.0f, 0.5f, 65504.0f, 0x1p-24f, 0x1p-14f, 1.0f + 0x1p-10f,
                           INFINITY, -INFINITY, 1024.0f, 3.0f / 1024.0f};
    for (size_t i = 0; i < sizeof exact / sizeof *exact; i++)
        img->pixels[i] = exact[i];
    tb_image_write_options o = {.exr_half = 1};
    char *buf;
    size_t len;
    assert_int_equal(write_mem(img, &o, &buf, &len), TB_OK);
    tb_image *back = NULL;
    assert_int_equal(read_mem(buf, len, &back), TB_OK);
    for (size_t i = 0; i < sizeof exact / sizeof *exact; i++)
        assert_int_equal(fbits(back->pixels[i]), fbits(exact[i]));
    for (size_t i = sizeof exact / sizeof *exact; i < n; i++)
        tb_assert_near(back->pixels[i], img->pixels[i], half_tolerance(img->pixels[i]));
    /* Beyond the half range: infinity; NaN stays NaN. */
    tb_image_free(back);
    free(buf);
    img->pixels[0] = 1e6f;
    img->pixels[1] = NAN;
    assert_int_equal(write_mem(img, &o, &buf, &len), TB_OK);
    assert_int_equal(read_mem(buf, len, &back), TB_OK);
    assert_true(isinf(back->pixels[0]) && back->pixels[0] > 0);
    assert_true(isnan(back->pixels[1]));
    tb_image_free(back);
    free(buf);
    tb_image_free(img);
}

/* Any channel names, including layers; R,G,B,A come first on reading, the
 * others in the file's (alphabetical) order; exposure scales only colour. */
static void test_named_channels_and_exposure(void **state)
{
    (void)state;
    const char *names[] = {"Z", "diffuse.R", "A", "B", "G", "R", "N.x"};
    enum { NC = 7 };
    tb_image *img = tb_image_create(5, 4, NC, names);
    for (int i = 0; i < 5 * 4 * NC; i++)
        img->pixels[i] = (float)i * 0.25f - 3.0f;
    char *buf;
    size_t len;
    tb_image_write_options o = {.exposure = -1.0f};
    assert_int_equal(write_mem(img, &o, &buf, &len), TB_OK);
    tb_image *back = NULL;
    assert_int_equal(read_mem(buf, len, &back), TB_OK);
    const char *order[NC] = {"R", "G", "B", "A", "N.x", "Z", "diffuse.R"};
    for (int c = 0; c < NC; c++)
        assert_string_equal(back->names[c], order[c]);
    for (int c = 0; c < NC; c++) {
        int k = tb_image_channel(back, names[c]);
        int colour = strcmp(names[c], "R") == 0 || strcmp(names[c], "G") == 0 ||
                     strcmp(names[c], "B") == 0 || strcmp(names[c], "diffuse.R") == 0;
        for (int p = 0; p < 5 * 4; p++)
            assert_true(back->pixels[p * NC + k] == img->pixels[p * NC + c] * (colour ? 0.5f : 1.0f));
    }
    tb_image_free(back);
    free(buf);

    const char *dup[] = {"R", "R"};
    tb_image *d = tb_image_create(1, 1, 2, dup);
    assert_int_equal(write_mem(d, NULL, &buf, &len), TB_ERR_ARG);
    assert_non_null(strstr(tb_last_error(), "unique"));
    free(buf);
    tb_image_free(d);
    tb_image_free(img);
}

static void test_attributes(void **state)
{
    (void)state;
    tb_image *img = tb_image_create(3, 2, 4, NULL);
    assert_int_equal(tb_image_set_attr(img, "testbed:revision", "abc123-dirty"), TB_OK);
    assert_int_equal(tb_image_set_attr(img, "owner", "Cornell PCG \xc2\xa9 1991"), TB_OK);
    assert_int_equal(tb_image_set_attr(img, "comments", "line 1\nline 2"), TB_OK);
    assert_int_equal(tb_image_set_attr(img, "empty", ""), TB_OK);
    assert_int_equal(tb_image_set_attr(img, "a.name.longer.than.thirty.one.bytes", "long"), TB_OK);
    char *buf;
    size_t len;
    assert_int_equal(write_mem(img, NULL, &buf, &len), TB_OK);
    tb_image *back = NULL;
    assert_int_equal(read_mem(buf, len, &back), TB_OK);
    assert_int_equal(back->nattrs, img->nattrs);
    for (int i = 0; i < img->nattrs; i++) {
        const char *v = tb_image_get_attr(back, img->attrs[i].key);
        if (!v)
            fail_msg("attribute '%s' lost", img->attrs[i].key);
        assert_string_equal(v, img->attrs[i].value);
    }
    tb_image_free(back);
    free(buf);

    const char *reserved[] = {"channels", "dataWindow", "compression", "name", "type", "expTime"};
    for (size_t r = 0; r < sizeof reserved / sizeof *reserved; r++) {
        tb_image *b = tb_image_create(1, 1, 1, NULL);
        assert_int_equal(tb_image_set_attr(b, reserved[r], "x"), TB_OK);
        assert_int_equal(write_mem(b, NULL, &buf, &len), TB_ERR_ARG);
        assert_non_null(strstr(tb_last_error(), reserved[r]));
        free(buf);
        tb_image_free(b);
    }
    tb_image_free(img);
}

/* ------------------------------------------------------------ our header, parsed independently */

typedef struct cursor {
    const unsigned char *p;
    size_t n, off;
} cursor;

static const char *cstr(cursor *c)
{
    const char *s = (const char *)c->p + c->off;
    size_t k = strnlen(s, c->n - c->off);
    assert_true(c->off + k < c->n);
    c->off += k + 1;
    return s;
}

static int32_t le32(const unsigned char *p)
{
    return (int32_t)((uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24);
}

static void test_header_layout(void **state)
{
    (void)state;
    const char *names[] = {"R", "G", "B", "A", "depth"};
    tb_image *img = tb_image_create(7, 3, 5, names);
    assert_int_equal(tb_image_set_attr(img, "software", "testbed"), TB_OK);
    for (int half = 0; half < 2; half++) {
        tb_image_write_options o = {.exr_half = half};
        char *buf;
        size_t len;
        assert_int_equal(write_mem(img, &o, &buf, &len), TB_OK);
        const unsigned char *p = (const unsigned char *)buf;
        /* Magic 20000630, version 2, no flags (single-part scanline, short names). */
        assert_int_equal(le32(p), 20000630);
        assert_int_equal(le32(p + 4), 2);
        cursor c = {p, len, 8};
        int seen_channels = 0, seen_comp = 0, seen_dw = 0, seen_sw = 0;
        for (;;) {
            const char *name = cstr(&c);
            if (!name[0])
                break;
            const char *type = cstr(&c);
            int32_t size = le32(p + c.off);
            c.off += 4;
            const unsigned char *v = p + c.off;
            assert_true(size >= 0 && c.off + (size_t)size <= len);
            if (strcmp(name, "channels") == 0) {
                assert_string_equal(type, "chlist");
                /* sorted by name: A B G R depth */
                const char *expect[] = {"A", "B", "G", "R", "depth"};
                cursor e = {v, (size_t)size, 0};
                for (int k = 0; k < 5; k++) {
                    assert_string_equal(cstr(&e), expect[k]);
                    assert_int_equal(le32(v + e.off), half ? 1 : 2); /* HALF = 1, FLOAT = 2 */
                    assert_int_equal(le32(v + e.off + 8), 1);        /* x sampling */
                    assert_int_equal(le32(v + e.off + 12), 1);       /* y sampling */
                    e.off += 16;
                }
                assert_int_equal(v[e.off], 0);
                assert_int_equal(e.off + 1, size);
                seen_channels = 1;
            } else if (strcmp(name, "compression") == 0) {
                assert_string_equal(type, "compression");
                assert_int_equal(v[0], 3); /* ZIP_COMPRESSION */
                seen_comp = 1;
            } else if (strcmp(name, "dataWindow") == 0) {
                assert_string_equal(type, "box2i");
                assert_int_equal(le32(v), 0);
                assert_int_equal(le32(v + 4), 0);
                assert_int_equal(le32(v + 8), 6);
                assert_int_equal(le32(v + 12), 2);
                seen_dw = 1;
            } else if (strcmp(name, "software") == 0) {
                assert_string_equal(type, "string");
                assert_int_equal(size, 7);
                assert_memory_equal(v, "testbed", 7);
                seen_sw = 1;
            }
            c.off += (size_t)size;
        }
        assert_true(seen_channels && seen_comp && seen_dw && seen_sw);
        /* Offset table: ZIP holds 16 lines per chunk, so one chunk for 3 lines,
         * pointing just past the table. */
        int64_t off = (int64_t)le32(p + c.off) | (int64_t)le32(p + c.off + 4) << 32;
        assert_int_equal(off, (int64_t)c.off + 8);
        assert_int_equal(le32(p + off), 0); /* first chunk starts at y = 0 */
        free(buf);
    }
    tb_image_free(img);
}

/* ------------------------------------------------------------ a file built by hand */

typedef struct bytes {
    unsigned char b[2048];
    size_t n;
} bytes;

static void put(bytes *d, const void *p, size_t k)
{
    memcpy(d->b + d->n, p, k);
    d->n += k;
}
static void put_str0(bytes *d, const char *s) { put(d, s, strlen(s) + 1); }
static void put_i32(bytes *d, int32_t v)
{
    for (int i = 0; i < 4; i++)
        d->b[d->n++] = (unsigned char)((uint32_t)v >> (8 * i));
}
static void put_u16(bytes *d, uint16_t v)
{
    d->b[d->n++] = (unsigned char)v;
    d->b[d->n++] = (unsigned char)(v >> 8);
}
static void put_f32(bytes *d, float f) { put_i32(d, (int32_t)fbits(f)); }
static void attr_head(bytes *d, const char *name, const char *type, int32_t size)
{
    put_str0(d, name);
    put_str0(d, type);
    put_i32(d, size);
}

/* Uncompressed scanline file, data window x 10..13, y -3..-1, channels
 * B (HALF), G (FLOAT), R (UINT), Z (FLOAT); one line per chunk. */
static void build_hand_file(bytes *d)
{
    const int W = 4, H = 3;
    memset(d, 0, sizeof *d);
    put_i32(d, 20000630);
    put_i32(d, 2);
    const char *chn[] = {"B", "G", "R", "Z"};
    const int32_t chtype[] = {1, 2, 0, 2};
    attr_head(d, "channels", "chlist", 4 * (2 + 16) + 1);
    for (int c = 0; c < 4; c++) {
        put_str0(d, chn[c]);
        put_i32(d, chtype[c]);
        put_i32(d, 0); /* pLinear + reserved */
        put_i32(d, 1);
        put_i32(d, 1);
    }
    d->b[d->n++] = 0;
    attr_head(d, "compression", "compression", 1);
    d->b[d->n++] = 0; /* NO_COMPRESSION */
    attr_head(d, "dataWindow", "box2i", 16);
    put_i32(d, 10), put_i32(d, -3), put_i32(d, 13), put_i32(d, -1);
    attr_head(d, "displayWindow", "box2i", 16);
    put_i32(d, 0), put_i32(d, -5), put_i32(d, 20), put_i32(d, 5);
    attr_head(d, "lineOrder", "lineOrder", 1);
    d->b[d->n++] = 0;
    attr_head(d, "pixelAspectRatio", "float", 4);
    put_f32(d, 1.0f);
    attr_head(d, "screenWindowCenter", "v2f", 8);
    put_f32(d, 0.0f), put_f32(d, 0.0f);
    attr_head(d, "screenWindowWidth", "float", 4);
    put_f32(d, 1.0f);
    attr_head(d, "renderer", "string", 12);
    put(d, "testbed 1991", 12);
    attr_head(d, "gain", "float", 4); /* not a string: not copied */
    put_f32(d, 2.0f);
    d->b[d->n++] = 0; /* end of header */
    size_t table = d->n;
    d->n += 8 * (size_t)H;
    size_t line_bytes = (size_t)W * (2 + 4 + 4 + 4);
    static const uint16_t halves[4] = {0x3c00 /* 1 */, 0xc000 /* -2 */, 0x0001 /* 2^-24 */, 0x7bff /* 65504 */};
    for (int y = 0; y < H; y++) {
        uint64_t off = d->n;
        for (int i = 0; i < 8; i++)
            d->b[table + 8 * (size_t)y + (size_t)i] = (unsigned char)(off >> (8 * i));
        put_i32(d, -3 + y);
        put_i32(d, (int32_t)line_bytes);
        for (int x = 0; x < W; x++) /* B */
            put_u16(d, y == 0 ? halves[x] : (uint16_t)(0x3c00 + y * 16 + x));
        for (int x = 0; x < W; x++) /* G */
            put_f32(d, (float)(x - y) * 0.75f);
        for (int x = 0; x < W; x++) /* R */
            put_i32(d, 1000000 * y + x);
        for (int x = 0; x < W; x++) /* Z */
            put_f32(d, -(float)(y * W + x));
    }
}

static void test_read_hand_built(void **state)
{
    (void)state;
    bytes d;
    build_hand_file(&d);
    tb_image *img = NULL;
    if (read_mem(d.b, d.n, &img) != TB_OK)
        fail_msg("%s", tb_last_error());
    assert_int_equal(img->width, 4);
    assert_int_equal(img->height, 3);
    assert_int_equal(img->channels, 4);
    const char *order[] = {"R", "G", "B", "Z"};
    for (int c = 0; c < 4; c++)
        assert_string_equal(img->names[c], order[c]);
    const float half0[4] = {1.0f, -2.0f, 0x1p-24f, 65504.0f};
    for (int y = 0; y < 3; y++)
        for (int x = 0; x < 4; x++) {
            const float *p = tb_image_at(img, x, y);
            assert_true(p[0] == (float)(1000000 * y + x));
            assert_true(p[1] == (float)(x - y) * 0.75f);
            /* 0x3c00 + k (k < 1024) is 1 + k/1024 */
            float b = y == 0 ? half0[x] : 1.0f + (float)(y * 16 + x) / 1024.0f;
            assert_true(p[2] == b);
            assert_true(p[3] == -(float)(y * 4 + x));
        }
    assert_string_equal(tb_image_get_attr(img, "renderer"), "testbed 1991");
    assert_null(tb_image_get_attr(img, "gain"));
    assert_int_equal(img->nattrs, 1);
    tb_image_free(img);
}

/* ------------------------------------------------------------ a tiled file */

static void test_read_tiled(void **state)
{
    (void)state;
    enum { W = 10, H = 7, TW = 4, TH = 3 };
    char path[512];
    snprintf(path, sizeof path, "%s/image_tiled_%d.exr", tb_test_tmpdir(), (int)getpid());
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    exr_context_t ctxt;
    int part;
    assert_int_equal(exr_start_write(&ctxt, path, EXR_WRITE_FILE_DIRECTLY, &init), 0);
    assert_int_equal(exr_add_part(ctxt, NULL, EXR_STORAGE_TILED, &part), 0);
    assert_int_equal(exr_initialize_required_attr_simple(ctxt, part, W, H, EXR_COMPRESSION_ZIP), 0);
    assert_int_equal(exr_set_tile_descriptor(ctxt, part, TW, TH, EXR_TILE_ONE_LEVEL, EXR_TILE_ROUND_DOWN), 0);
    assert_int_equal(exr_add_channel(ctxt, part, "G", EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1), 0);
    assert_int_equal(exr_add_channel(ctxt, part, "Y", EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1), 0);
    assert_int_equal(exr_write_header(ctxt), 0);
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    int first = 1;
    float tile[2][TW * TH];
    for (int ty = 0; ty * TH < H; ty++)
        for (int tx = 0; tx * TW < W; tx++) {
            exr_chunk_info_t cinfo;
            assert_int_equal(exr_write_tile_chunk_info(ctxt, part, tx, ty, 0, 0, &cinfo), 0);
            assert_int_equal(first ? exr_encoding_initialize(ctxt, part, &cinfo, &enc)
                                   : exr_encoding_update(ctxt, part, &cinfo, &enc), 0);
            for (int c = 0; c < 2; c++) {
                exr_coding_channel_info_t *ch = &enc.channels[c]; /* G, then Y */
                for (int y = 0; y < ch->height; y++)
                    for (int x = 0; x < ch->width; x++)
                        tile[c][y * ch->width + x] = (float)(100 * (ty * TH + y) + tx * TW + x) + 0.5f * (float)c;
                ch->encode_from_ptr = (const uint8_t *)tile[c];
                ch->user_pixel_stride = 4;
                ch->user_line_stride = 4 * ch->width;
                ch->user_data_type = EXR_PIXEL_FLOAT;
                ch->user_bytes_per_element = 4;
            }
            if (first)
                assert_int_equal(exr_encoding_choose_default_routines(ctxt, part, &enc), 0);
            assert_int_equal(exr_encoding_run(ctxt, part, &enc), 0);
            first = 0;
        }
    exr_encoding_destroy(ctxt, &enc);
    assert_int_equal(exr_finish(&ctxt), 0);

    tb_image *img = NULL;
    if (tb_exr_read(path, &img) != TB_OK)
        fail_msg("%s", tb_last_error());
    assert_int_equal(img->width, W);
    assert_int_equal(img->height, H);
    assert_string_equal(img->names[0], "G"); /* R, G, B, Y, A order */
    assert_string_equal(img->names[1], "Y");
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            assert_true(tb_image_at(img, x, y)[0] == (float)(100 * y + x));
            assert_true(tb_image_at(img, x, y)[1] == (float)(100 * y + x) + 0.5f);
        }
    tb_image_free(img);
    unlink(path);
}

/* ------------------------------------------------------------ damaged files */

static size_t find(const unsigned char *p, size_t n, const char *s, size_t m)
{
    for (size_t i = 0; i + m <= n; i++)
        if (memcmp(p + i, s, m) == 0)
            return i;
    fail_msg("'%s' not found", s);
    return 0;
}

static void check_rejected_cuts(const unsigned char *p, size_t len, const char *what)
{
    for (size_t n = 0; n < len; n++) {
        tb_image *img = NULL;
        tb_status st = read_mem(p, n, &img);
        if (st == TB_OK)
            fail_msg("%s cut at %zu of %zu accepted", what, n, len);
        assert_null(img);
        assert_non_null(strstr(tb_last_error(), "mem.exr"));
    }
}

static void test_malformed(void **state)
{
    (void)state;
    tb_image *img = tb_image_create(9, 20, 3, NULL);
    for (int i = 0; i < 9 * 20 * 3; i++)
        img->pixels[i] = sinf((float)i);
    assert_int_equal(tb_image_set_attr(img, "note", "damaged on purpose"), TB_OK);
    char *buf;
    size_t len;
    assert_int_equal(write_mem(img, NULL, &buf, &len), TB_OK);
    tb_image_free(img);
    const unsigned char *p = (const unsigned char *)buf;
    check_rejected_cuts(p, len, "ZIP file");
    bytes hand;
    build_hand_file(&hand);
    check_rejected_cuts(hand.b, hand.n, "hand-built file");

    /* Flip every byte of the header: no crash, no leak, a clean status. Some
     * flips (inside an attribute's value) are harmless and may be accepted. */
    size_t header_end = find(p, len, "note", 4) + 30;
    unsigned char *copy = malloc(len);
    for (size_t i = 0; i < header_end && i < len; i++) {
        memcpy(copy, p, len);
        copy[i] ^= 0xff;
        img = NULL;
        tb_status st = read_mem(copy, len, &img);
        if (i < 8 && st == TB_OK)
            fail_msg("flipped magic/version byte %zu accepted", i);
        assert_true((st == TB_OK) == (img != NULL));
        tb_image_free(img);
    }

    /* Absurd data windows. */
    size_t dw = find(p, len, "dataWindow", 11) + 11 + 6 + 4; /* name, "box2i", size */
    const int32_t windows[][4] = {{0, 0, 2147483646, 2147483646}, {-2147483647 - 1, 0, 2147483647, 0},
                                  {0, 0, 65535, 65535}, {5, 5, 4, 4}, {0, 0, 9999, 9999}};
    for (size_t k = 0; k < 5; k++) {
        memcpy(copy, p, len);
        for (int j = 0; j < 4; j++)
            for (int b = 0; b < 4; b++)
                copy[dw + 4 * (size_t)j + (size_t)b] = (unsigned char)((uint32_t)windows[k][j] >> (8 * b));
        img = NULL;
        tb_status st = read_mem(copy, len, &img);
        if (st == TB_OK)
            fail_msg("data window %zu accepted", k);
        assert_null(img);
    }
    /* The last one fits the size limit, but not in a file this small. */
    assert_non_null(strstr(tb_last_error(), "far more than"));
    free(copy);

    img = NULL;
    assert_int_equal(read_mem("\x89PNG\r\n\x1a\n0000000000000000", 24, &img), TB_ERR_FORMAT);
    assert_int_equal(read_mem("", 0, &img), TB_ERR_FORMAT);
    assert_null(img);
    free(buf);
}

/* A pipe cannot seek: both directions say so instead of failing oddly. */
static void test_needs_seekable_stream(void **state)
{
    (void)state;
    int fd[2];
    assert_int_equal(pipe(fd), 0);
    FILE *w = fdopen(fd[1], "wb"), *r = fdopen(fd[0], "rb");
    tb_image *img = tb_image_create(1, 1, 1, NULL);
    assert_int_equal(tb_exr_write_stream(w, "pipe.exr", img, NULL), TB_ERR_ARG);
    assert_non_null(strstr(tb_last_error(), "seekable"));
    tb_image *back = NULL;
    assert_int_equal(tb_exr_read_stream(r, "pipe.exr", &back), TB_ERR_ARG);
    assert_null(back);
    fclose(w);
    fclose(r);
    tb_image_free(img);
    assert_int_equal(tb_exr_read("/nonexistent/dir/x.exr", &back), TB_ERR_NOT_FOUND);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_float_round_trip_bits),
        cmocka_unit_test(test_half_round_trip),
        cmocka_unit_test(test_zip_chunk_as_long_as_raw),
        cmocka_unit_test(test_named_channels_and_exposure),
        cmocka_unit_test(test_attributes),
        cmocka_unit_test(test_header_layout),
        cmocka_unit_test(test_read_hand_built),
        cmocka_unit_test(test_read_tiled),
        cmocka_unit_test(test_malformed),
        cmocka_unit_test(test_needs_seekable_stream),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
