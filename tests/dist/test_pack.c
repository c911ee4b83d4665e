/* The bytes host/dist moves: a film tile packed and unpacked into another
 * film of the same description merges to the same film, bit for bit, as the
 * original tile (tiles travel between ranks this way); a film packed and
 * unpacked continues as the original (checkpoints); wrong or damaged bytes
 * are refused with a message; checkpoint files round-trip, are replaced
 * atomically, and refuse another job, another kind, a bad checksum and a
 * truncated file; host/dist's tile exchange in a job of one rank gives the
 * plain loop's film. */
#include "tb_test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "host/dist/checkpoint.h"
#include "host/dist/dist.h"
#include "host/dist/tiles.h"
#include "host/render/antialias.h"
#include "host/render/film.h"
#include "util/math/rng.h"

/* A film with a tent filter (an apron: tiles overlap their neighbours). */
static tb_film *make_film(int w, int h, int channels)
{
    static tb_filter f;
    assert_int_equal(tb_filter_init(&f, TB_FILTER_TENT, 1.5, 0.0), TB_OK);
    tb_film_desc d = {.width = w, .height = h, .channels = channels, .filter = &f, .tile_size = 8};
    tb_film *film = tb_film_create(&d);
    assert_non_null(film);
    return film;
}

/* Fills tile `index` of `film` with random samples from stream `seed`. */
static tb_film_tile *random_tile(const tb_film *film, int index, uint64_t seed)
{
    tb_film_tile *t = tb_film_tile_create(film, index);
    assert_non_null(t);
    tb_tile_rect r = tb_film_tile_pixels(t);
    tb_rng rng;
    tb_rng_seed(&rng, seed, (uint64_t)index);
    float v[4];
    for (int k = 0; k < 40; k++) {
        double x = r.x0 + tb_rng_double(&rng) * (r.x1 - r.x0);
        double y = r.y0 + tb_rng_double(&rng) * (r.y1 - r.y0);
        for (int c = 0; c < 4; c++)
            v[c] = (float)tb_rng_double(&rng);
        tb_film_tile_add(t, x, y, v, 0.5 + tb_rng_double(&rng));
    }
    tb_film_tile_record_samples(t, r.x0, r.y0, 3);
    return t;
}

/* Resolves both films and compares every float's bits and every count. */
static void assert_films_equal(const tb_film *a, const tb_film *b)
{
    tb_image *ia = tb_film_resolve(a, NULL), *ib = tb_film_resolve(b, NULL);
    assert_non_null(ia);
    assert_non_null(ib);
    size_t n = (size_t)ia->width * (size_t)ia->height * (size_t)ia->channels;
    assert_memory_equal(ia->pixels, ib->pixels, n * sizeof(float));
    for (int y = 0; y < ia->height; y++)
        for (int x = 0; x < ia->width; x++) {
            assert_int_equal(tb_film_sample_count(a, x, y), tb_film_sample_count(b, x, y));
            double wa = tb_film_weight_sum(a, x, y), wb = tb_film_weight_sum(b, x, y);
            assert_memory_equal(&wa, &wb, sizeof wa);
        }
    tb_image_free(ia);
    tb_image_free(ib);
}

static void test_tile_travels(void **state)
{
    (void)state;
    tb_film *here = make_film(30, 21, 4), *there = make_film(30, 21, 4);
    int n = tb_film_tile_count(here);
    for (int pass = 0; pass < 2; pass++) {
        if (pass) {
            assert_int_equal(tb_film_begin_pass(here), TB_OK);
            assert_int_equal(tb_film_begin_pass(there), TB_OK);
        }
        /* `here` merges the tiles themselves (in reverse submission order:
         * the film orders them); `there` merges packed copies */
        for (int i = n - 1; i >= 0; i--) {
            tb_film_tile *t = random_tile(here, i, 100 + (uint64_t)pass);
            size_t len = tb_film_tile_packed_size(t);
            unsigned char *buf = malloc(len);
            assert_non_null(buf);
            tb_film_tile_pack(t, buf);
            tb_film_tile *u = tb_film_tile_unpack(there, buf, len);
            assert_non_null(u);
            assert_int_equal(tb_film_tile_submit(here, t), TB_OK);
            assert_int_equal(tb_film_tile_submit(there, u), TB_OK);
            free(buf);
        }
        assert_true(tb_film_pass_complete(there));
        assert_films_equal(here, there);
    }
    tb_film_free(here);
    tb_film_free(there);
}

static void test_tile_refused(void **state)
{
    (void)state;
    tb_film *a = make_film(30, 21, 4), *other = make_film(30, 21, 3), *small = make_film(20, 21, 4);
    tb_film_tile *t = random_tile(a, 5, 1);
    size_t len = tb_film_tile_packed_size(t);
    unsigned char *buf = malloc(len);
    tb_film_tile_pack(t, buf);
    assert_null(tb_film_tile_unpack(other, buf, len)); /* channels */
    assert_non_null(strstr(tb_last_error(), "channels"));
    assert_null(tb_film_tile_unpack(a, buf, len - 1)); /* length */
    assert_null(tb_film_tile_unpack(a, buf, 10));      /* shorter than the header */
    /* tile 5 of a 30-wide film is another rectangle in a 20-wide one */
    assert_null(tb_film_tile_unpack(small, buf, len));
    free(buf);
    tb_film_tile_free(t);
    tb_film_free(a);
    tb_film_free(other);
    tb_film_free(small);
}

/* A film half rendered, packed, unpacked into a new film and finished,
 * equals the film rendered in one go. */
static void test_film_continues(void **state)
{
    (void)state;
    tb_film *whole = make_film(17, 12, 4), *first = make_film(17, 12, 4), *second = make_film(17, 12, 4);
    int n = tb_film_tile_count(whole);
    for (int pass = 0; pass < 3; pass++) {
        tb_film *f = pass < 2 ? first : second;
        if (pass > 0) {
            assert_int_equal(tb_film_begin_pass(whole), TB_OK);
            if (pass != 2)
                assert_int_equal(tb_film_begin_pass(f), TB_OK);
        }
        for (int i = 0; i < n; i++) {
            assert_int_equal(tb_film_tile_submit(whole, random_tile(whole, i, 7 + (uint64_t)pass)), TB_OK);
            assert_int_equal(tb_film_tile_submit(f, random_tile(f, i, 7 + (uint64_t)pass)), TB_OK);
        }
        if (pass == 1) {
            size_t len = tb_film_packed_size(first);
            unsigned char *buf = malloc(len);
            tb_film_pack(first, buf);
            assert_int_equal(tb_film_unpack(second, buf, len - 1), TB_ERR_FORMAT);
            assert_int_equal(tb_film_unpack(second, buf, len), TB_OK);
            tb_film *wrong = make_film(16, 12, 4);
            assert_int_equal(tb_film_unpack(wrong, buf, len), TB_ERR_FORMAT);
            assert_non_null(strstr(tb_last_error(), "17 x 12"));
            tb_film_free(wrong);
            free(buf);
        }
    }
    assert_films_equal(whole, second);
    tb_film_free(whole);
    tb_film_free(first);
    tb_film_free(second);
}

static void test_checkpoint_file(void **state)
{
    (void)state;
    char path[512];
    snprintf(path, sizeof path, "%s/dist_pack_%d.ckpt", tb_test_tmpdir(), (int)getpid());
    const char payload[] = "the state of a job";
    assert_int_equal(tb_ckpt_write(path, TB_CKPT_RENDER, 42, 3, payload, sizeof payload), TB_OK);
    void *back;
    size_t len;
    uint64_t units;
    assert_int_equal(tb_ckpt_read(path, TB_CKPT_RENDER, 42, &back, &len, &units), TB_OK);
    assert_int_equal(len, sizeof payload);
    assert_int_equal(units, 3);
    assert_memory_equal(back, payload, sizeof payload);
    free(back);
    /* another job, another kind */
    assert_int_equal(tb_ckpt_read(path, TB_CKPT_RENDER, 43, &back, &len, &units), TB_ERR_FORMAT);
    assert_non_null(strstr(tb_last_error(), "another job"));
    assert_int_equal(tb_ckpt_read(path, TB_CKPT_RADIOSITY, 42, &back, &len, &units), TB_ERR_FORMAT);
    assert_non_null(strstr(tb_last_error(), "not a radiosity one"));
    /* a flipped payload byte, then a cut file */
    FILE *fp = fopen(path, "r+b");
    assert_non_null(fp);
    fseek(fp, 48 + 4, SEEK_SET);
    fputc('X', fp);
    fclose(fp);
    assert_int_equal(tb_ckpt_read(path, TB_CKPT_RENDER, 42, &back, &len, &units), TB_ERR_FORMAT);
    assert_non_null(strstr(tb_last_error(), "checksum"));
    assert_int_equal(truncate(path, 48 + 5), 0);
    assert_int_equal(tb_ckpt_read(path, TB_CKPT_RENDER, 42, &back, &len, &units), TB_ERR_FORMAT);
    assert_non_null(strstr(tb_last_error(), "truncated"));
    /* a new checkpoint replaces the damaged one whole; a failed write
     * (a folder that does not exist) leaves nothing */
    assert_int_equal(tb_ckpt_write(path, TB_CKPT_RENDER, 42, 4, payload, sizeof payload), TB_OK);
    assert_int_equal(tb_ckpt_read(path, TB_CKPT_RENDER, 42, &back, &len, &units), TB_OK);
    assert_int_equal(units, 4);
    free(back);
    char bad[600];
    snprintf(bad, sizeof bad, "%s/no-such-dir/x.ckpt", tb_test_tmpdir());
    assert_int_not_equal(tb_ckpt_write(bad, TB_CKPT_RENDER, 42, 4, payload, sizeof payload), TB_OK);
    assert_int_equal(tb_ckpt_read("/nonexistent/x.ckpt", TB_CKPT_RENDER, 42, &back, &len, &units), TB_ERR_IO);
    remove(path);
}

/* A radiance that varies within pixels and with the sample's stream, so a
 * tile rendered twice or merged out of order would show. */
static void wavy(void *ctx, double x, double y, tb_rng *rng, float *out)
{
    (void)ctx;
    float r = tb_rng_float(rng);
    out[0] = (float)(0.5 + 0.5 * sin(0.37 * x) * cos(0.23 * y)) + 0.1f * r;
    out[1] = (float)(x / 64.0);
    out[2] = r;
    out[3] = (float)(y / 48.0);
}

/* The tile exchange of host/dist in a job of one rank (no MPI): tb_aa_render
 * through it (claims from its counter, every tile merged here) gives the
 * film of the plain OpenMP loop bit for bit, for 1 and 3 threads and two
 * passes; the job is one rank and a failure agreed on is the rank's own. */
static void test_exchange_one_rank(void **state)
{
    (void)state;
    assert_int_equal(tb_dist_size(), 1);
    assert_int_equal(tb_dist_rank(), 0);
    tb_clear_error();
    assert_int_equal(tb_dist_agree_status(TB_OK, NULL), TB_OK);
    int who = 7;
    tb_error(TB_ERR_IO, "disk on fire");
    assert_int_equal(tb_dist_agree_status(TB_ERR_IO, &who), TB_ERR_IO);
    assert_int_equal(who, 0);
    assert_string_equal(tb_last_error(), "disk on fire");
    for (int threads = 1; threads <= 3; threads += 2) {
        tb_film *plain = make_film(61, 45, 4), *viaex = make_film(61, 45, 4);
        tb_tile_exchange *ex = tb_dist_tiles_create(threads);
        assert_non_null(ex);
        assert_int_equal(ex->ranks, 1);
        tb_aa_options aa = tb_aa_defaults();
        aa.spp = 3;
        aa.seed = 11;
        for (int pass = 0; pass < 2; pass++) {
            aa.pass = (uint32_t)pass;
            tb_aa_stats a, b;
            tb_aa_render_desc d = {.sample = wavy, .threads = threads};
            assert_int_equal(tb_aa_render(plain, &aa, &d, &a), TB_OK);
            d.exchange = ex;
            d.pass_index = pass;
            assert_int_equal(tb_aa_render(viaex, &aa, &d, &b), TB_OK);
            assert_int_equal(a.samples, b.samples);
            assert_int_equal(b.tiles_skipped, 0);
            assert_true(tb_film_pass_complete(viaex));
        }
        assert_films_equal(plain, viaex);
        tb_dist_stats my = tb_dist_my_stats();
        assert_true(my.units >= (uint64_t)tb_film_tile_count(plain)); /* tiles rendered here, all passes */
        tb_dist_tiles_free(ex);
        tb_film_free(plain);
        tb_film_free(viaex);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tile_travels),
        cmocka_unit_test(test_tile_refused),
        cmocka_unit_test(test_film_continues),
        cmocka_unit_test(test_checkpoint_file),
        cmocka_unit_test(test_exchange_one_rank),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
