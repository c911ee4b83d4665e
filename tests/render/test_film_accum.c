/* The film: a constant radiance resolves to that constant everywhere,
 * including borders and corners, for every filter and through tiles; a
 * box-filtered half-plane gives each pixel's exact area coverage within the
 * proven stratification bound; samples on a shared border reach both pixels;
 * tile merging is independent of the submission order, bit for bit; pass
 * bookkeeping and dropped samples. */
#include "tb_test.h"

#include "util/math/float.h"

#include <string.h>

#include "host/render/antialias.h"
#include "host/render/film.h"

/* Exact area of the unit pixel [px, px+1] x [py, py+1] where a x + b y < c,
 * by clipping the square against the half-plane (Sutherland-Hodgman) and the
 * shoelace formula, in double. */
static double coverage(double a, double b, double c, int px, int py)
{
    double in[4][2] = {{px, py}, {px + 1.0, py}, {px + 1.0, py + 1.0}, {px, py + 1.0}};
    double out[8][2];
    int n = 0;
    for (int i = 0; i < 4; i++) {
        const double *p = in[i], *q = in[(i + 1) % 4];
        double fp = a * p[0] + b * p[1] - c, fq = a * q[0] + b * q[1] - c;
        if (fp < 0.0) {
            out[n][0] = p[0];
            out[n][1] = p[1];
            n++;
        }
        if ((fp < 0.0) != (fq < 0.0)) {
            double t = fp / (fp - fq);
            out[n][0] = p[0] + t * (q[0] - p[0]);
            out[n][1] = p[1] + t * (q[1] - p[1]);
            n++;
        }
    }
    double area = 0.0;
    for (int i = 0; i < n; i++)
        area += out[i][0] * out[(i + 1) % n][1] - out[(i + 1) % n][0] * out[i][1];
    return fabs(area) * 0.5;
}

/* Fills a film with `spp` stratified samples per pixel of the constant `v`
 * (3 channels), through tiles submitted in tile order. */
static void fill_constant(tb_film *film, int spp, const float *v, uint64_t seed)
{
    tb_aa_options o = tb_aa_defaults();
    o.spp = spp;
    o.seed = seed;
    float xy[2 * 64];
    for (int t = 0; t < tb_film_tile_count(film); t++) {
        tb_film_tile *tile = tb_film_tile_create(film, t);
        assert_non_null(tile);
        tb_tile_rect r = tb_film_tile_pixels(tile);
        for (int y = r.y0; y < r.y1; y++)
            for (int x = r.x0; x < r.x1; x++) {
                tb_pixel_sampler s;
                tb_pixel_sampler_init(&s, &o, x, y);
                int n = tb_pixel_sampler_round(&s, xy);
                for (int k = 0; k < n; k++)
                    tb_film_tile_add(tile, x + (double)xy[2 * k], y + (double)xy[2 * k + 1], v, 1.0);
            }
        assert_int_equal(tb_film_tile_submit(film, tile), TB_OK);
    }
    assert_true(tb_film_pass_complete(film));
}

static void test_constant(void **state)
{
    (void)state;
    const float v[3] = {0.3f, 1.7f, 5.0f};
    for (int k = 0; k < TB_FILTER_KIND_COUNT; k++) {
        const double radii[] = {0.0, 1.3, 2.5};
        for (int ri = 0; ri < 3; ri++) {
            tb_filter f;
            tb_filter_init(&f, (tb_filter_kind)k, radii[ri], 0.0);
            tb_film *film = tb_film_create(&(tb_film_desc){.width = 37, .height = 23, .channels = 3,
                                                           .filter = &f, .tile_size = 8});
            assert_non_null(film);
            fill_constant(film, 4, v, 11 + (uint64_t)k);
            tb_image *img = tb_film_resolve(film, NULL);
            assert_non_null(img);
            for (int y = 0; y < 23; y++)
                for (int x = 0; x < 37; x++) {
                    assert_true(tb_film_weight_sum(film, x, y) > 0.0);
                    for (int c = 0; c < 3; c++)
                        tb_assert_near(tb_image_at(img, x, y)[c], v[c], 2e-6 * v[c]);
                }
            tb_image_free(img);
            tb_film_free(film);
        }
    }
}

/* Box filter (radius 1/2): the film value of a pixel is the fraction of its
 * samples inside the half-plane. With n x n jittered strata a straight edge
 * crosses at most 2n - 1 of the cells, and only those cells can be wrong, so
 * |estimate - coverage| <= (2n - 1) / n^2 for every pixel. */
static void test_box_edge_coverage(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("film edge", 3), 0);
    const int W = 24, H = 20;
    for (int trial = 0; trial < 6; trial++) {
        double ang = 2.0 * TB_PI * tb_rng_double(&rng);
        double a = cos(ang), b = sin(ang), c = a * (W * tb_rng_double(&rng)) + b * (H * tb_rng_double(&rng));
        int n = 2 + trial; /* 2x2 .. 7x7 strata */
        tb_film *film = tb_film_create(&(tb_film_desc){.width = W, .height = H, .channels = 1, .tile_size = 7});
        assert_non_null(film);
        tb_aa_options o = tb_aa_defaults();
        o.spp = n * n;
        o.seed = tb_rng_u32(&rng);
        float xy[2 * 49];
        for (int t = 0; t < tb_film_tile_count(film); t++) {
            tb_film_tile *tile = tb_film_tile_create(film, t);
            tb_tile_rect r = tb_film_tile_pixels(tile);
            for (int y = r.y0; y < r.y1; y++)
                for (int x = r.x0; x < r.x1; x++) {
                    tb_pixel_sampler s;
                    tb_pixel_sampler_init(&s, &o, x, y);
                    int m = tb_pixel_sampler_round(&s, xy);
                    for (int k = 0; k < m; k++) {
                        double sx = x + (double)xy[2 * k], sy = y + (double)xy[2 * k + 1];
                        float val = a * sx + b * sy < c ? 1.0f : 0.0f;
                        tb_film_tile_add(tile, sx, sy, &val, 1.0);
                    }
                }
            tb_film_tile_submit(film, tile);
        }
        tb_image *img = tb_film_resolve(film, NULL);
        double bound = (2.0 * n - 1.0) / (n * n), worst = 0.0, sse = 0.0;
        int edge_pixels = 0;
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                /* every sample lands in exactly its own pixel */
                tb_assert_near(tb_film_weight_sum(film, x, y), n * n, 0.0);
                double cov = coverage(a, b, c, x, y);
                double err = fabs(tb_image_at(img, x, y)[0] - cov);
                if (cov > 0.0 && cov < 1.0) {
                    edge_pixels++;
                    sse += err * err;
                }
                worst = fmax(worst, err);
                if (err > bound + 1e-6)
                    fail_msg("pixel (%d,%d): estimate %g, coverage %g, bound %g", x, y,
                             tb_image_at(img, x, y)[0], cov, bound);
            }
        /* the sampling error: each crossed cell is one Bernoulli trial of
         * weight 1/n^2, so the variance is at most (2n - 1) / (4 n^4) */
        double rms = sqrt(sse / (edge_pixels ? edge_pixels : 1)), sigma = sqrt(2.0 * n - 1.0) / (2.0 * n * n);
        print_message("[ edge     ] %dx%d strata: %d edge pixels, worst error %.4f (bound %.4f), RMS %.4f "
                      "(sigma bound %.4f)\n", n, n, edge_pixels, worst, bound, rms, sigma);
        assert_true(rms <= sigma);
        tb_image_free(img);
        tb_film_free(film);
    }
}

static void test_shared_border(void **state)
{
    (void)state;
    /* A sample exactly on the border between pixels 3 and 4 (x = 4) is used by
     * both under a tent of radius 1, with equal weight; under the half-open
     * box only by pixel 4. */
    tb_filter tent, box;
    tb_filter_init(&tent, TB_FILTER_TENT, 1.0, 0.0);
    tb_filter_init(&box, TB_FILTER_BOX, 0.5, 0.0);
    float one = 1.0f;
    tb_film *ft = tb_film_create(&(tb_film_desc){.width = 8, .height = 8, .channels = 1, .filter = &tent});
    tb_film_add(ft, 4.0, 2.5, &one, 1.0);
    tb_assert_near(tb_film_weight_sum(ft, 3, 2), 0.5 * 1.0, 1e-15);
    tb_assert_near(tb_film_weight_sum(ft, 4, 2), 0.5 * 1.0, 1e-15);
    tb_assert_near(tb_film_weight_sum(ft, 2, 2), 0.0, 0.0);
    tb_assert_near(tb_film_weight_sum(ft, 5, 2), 0.0, 0.0);
    tb_film *fb = tb_film_create(&(tb_film_desc){.width = 8, .height = 8, .channels = 1, .filter = &box});
    tb_film_add(fb, 4.0, 2.5, &one, 1.0);
    tb_assert_near(tb_film_weight_sum(fb, 3, 2), 0.0, 0.0);
    tb_assert_near(tb_film_weight_sum(fb, 4, 2), 1.0, 0.0);
    /* through a tile: a sample at x = 3.75 belongs to tile 0 (tiles 4 pixels
     * wide) and its apron carries it into pixel 4, which is tile 1's */
    tb_film *tf = tb_film_create(&(tb_film_desc){.width = 8, .height = 8, .channels = 1, .filter = &tent, .tile_size = 4});
    tb_film_tile *t0 = tb_film_tile_create(tf, 0);
    tb_film_tile_add(t0, 3.75, 2.5, &one, 1.0);
    tb_film_tile_submit(tf, t0);
    tb_assert_near(tb_film_weight_sum(tf, 3, 2), 0.75, 1e-15);
    tb_assert_near(tb_film_weight_sum(tf, 4, 2), 0.25, 1e-15);
    tb_film_free(ft);
    tb_film_free(fb);
    tb_film_free(tf);
}

/* Tiles submitted in a random order merge to the same bits as in tile order. */
static void test_merge_order(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("film merge order", 5), 0);
    tb_filter f;
    tb_filter_init(&f, TB_FILTER_MITCHELL, 2.0, 0.0);
    const tb_film_desc d = {.width = 45, .height = 30, .channels = 2, .filter = &f, .tile_size = 8};
    tb_film *films[2] = {tb_film_create(&d), tb_film_create(&d)};
    int nt = tb_film_tile_count(films[0]);
    assert_int_equal(nt, 6 * 4);
    tb_film_tile *tiles[2][24];
    for (int which = 0; which < 2; which++)
        for (int t = 0; t < nt; t++) {
            tiles[which][t] = tb_film_tile_create(films[which], t);
            tb_tile_rect r = tb_film_tile_pixels(tiles[which][t]);
            tb_rng s;
            tb_rng_seed(&s, 99, (uint64_t)t);
            for (int k = 0; k < 300; k++) {
                double x = r.x0 + (r.x1 - r.x0) * tb_rng_double(&s);
                double y = r.y0 + (r.y1 - r.y0) * tb_rng_double(&s);
                float v[2] = {tb_rng_float(&s) * 10.0f, (float)sin(x * y)};
                tb_film_tile_add(tiles[which][t], x, y, v, 0.5 + tb_rng_double(&s));
            }
        }
    for (int t = 0; t < nt; t++)
        tb_film_tile_submit(films[0], tiles[0][t]);
    int order[24];
    for (int t = 0; t < nt; t++)
        order[t] = t;
    for (int t = nt - 1; t > 0; t--) {
        int j = (int)tb_rng_below(&rng, (uint32_t)t + 1);
        int tmp = order[t];
        order[t] = order[j];
        order[j] = tmp;
    }
    for (int t = 0; t < nt; t++) {
        /* nothing past the first missing tile is merged yet */
        tb_film_tile_submit(films[1], tiles[1][order[t]]);
        assert_true(tb_film_pass_complete(films[1]) == (t == nt - 1));
    }
    tb_image *a = tb_film_resolve(films[0], NULL), *b = tb_film_resolve(films[1], NULL);
    assert_memory_equal(a->pixels, b->pixels, sizeof(float) * 45 * 30 * 2);
    tb_image_free(a);
    tb_image_free(b);
    tb_film_free(films[0]);
    tb_film_free(films[1]);
}

static void test_passes_and_errors(void **state)
{
    (void)state;
    tb_film *film = tb_film_create(&(tb_film_desc){.width = 10, .height = 10, .channels = 1, .tile_size = 4});
    assert_int_equal(tb_film_tile_count(film), 9);
    tb_tile_rect r = tb_film_tile_rect(film, 8);
    assert_true(r.x0 == 8 && r.y0 == 8 && r.x1 == 10 && r.y1 == 10);
    tb_film_tile *t = tb_film_tile_create(film, 1);
    assert_int_equal(tb_film_tile_submit(film, t), TB_OK);
    /* tile 1 waits for tile 0; a new pass now would lose it */
    assert_int_equal(tb_film_begin_pass(film), TB_ERR_ARG);
    t = tb_film_tile_create(film, 1);
    assert_int_equal(tb_film_tile_submit(film, t), TB_ERR_ARG);
    assert_non_null(strstr(tb_last_error(), "twice"));
    for (int i = 0; i < 9; i++)
        if (i != 1)
            assert_int_equal(tb_film_tile_skip(film, i), TB_OK);
    assert_true(tb_film_pass_complete(film));
    assert_int_equal(tb_film_begin_pass(film), TB_OK);
    assert_false(tb_film_pass_complete(film));
    /* non-finite samples are dropped and counted; the pixel stays empty */
    t = tb_film_tile_create(film, 0);
    float nan = NAN, one = 1.0f;
    tb_film_tile_add(t, 1.5, 1.5, &nan, 1.0);
    tb_film_tile_add(t, 2.5, 1.5, &one, INFINITY);
    tb_film_tile_add(t, 3.5, 3.5, &one, 1.0);
    tb_film_tile_add(t, 5.5, 3.5, &one, 1.0); /* outside the tile: ignored */
    tb_film_tile_record_samples(t, 3, 3, 1);
    tb_film_tile_submit(film, t);
    for (int i = 1; i < 9; i++)
        tb_film_tile_skip(film, i);
    assert_int_equal((int)tb_film_dropped(film), 2);
    tb_image *img = tb_film_resolve(film, NULL);
    assert_true(tb_image_at(img, 1, 1)[0] == 0.0f && tb_image_at(img, 3, 3)[0] == 1.0f &&
                tb_image_at(img, 5, 3)[0] == 0.0f);
    assert_int_equal(tb_film_sample_count(film, 3, 3), 1);
    tb_image_free(img);
    assert_null(tb_film_tile_create(film, 9));
    tb_film_free(film);
    /* bad descriptions */
    assert_null(tb_film_create(&(tb_film_desc){.width = 0, .height = 4, .channels = 1}));
    assert_null(tb_film_create(&(tb_film_desc){.width = 4, .height = 4, .channels = 0}));
    assert_null(tb_film_create(&(tb_film_desc){.width = 4, .height = 4, .channels = TB_FILM_MAX_CHANNELS + 1}));
    tb_filter junk = {.kind = TB_FILTER_BOX, .radius = 0.5, .norm = 0.0};
    assert_null(tb_film_create(&(tb_film_desc){.width = 4, .height = 4, .channels = 1, .filter = &junk}));
    assert_non_null(strstr(tb_last_error(), "tb_filter_init"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_constant),
        cmocka_unit_test(test_box_edge_coverage),
        cmocka_unit_test(test_shared_border),
        cmocka_unit_test(test_merge_order),
        cmocka_unit_test(test_passes_and_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
