/* The whole antialiasing pipeline (patterns, adaptive rounds, per-sample
 * random streams, tiles, splatting, ordered merge) on analytic images:
 * bit-identical images and sample counts with 1, 2 and 4 OpenMP threads;
 * adaptive refinement spends its samples at edges and beats uniform sampling
 * at equal total samples against the exact pixel coverage; a cancelled render
 * still completes its pass. */
#include "tb_test.h"

#include "util/math/float.h"

#include <omp.h>
#include <string.h>

#include "host/render/antialias.h"

/* A synthetic scene: a disc edge, a smooth gradient and a noise term drawn
 * from the sample's own random stream (so the per-sample streams matter). */
static void scene(void *ctx, double x, double y, tb_rng *rng, float *out)
{
    (void)ctx;
    double dx = x - 30.0, dy = y - 20.0;
    double inside = dx * dx + dy * dy < 15.0 * 15.0 ? 1.0 : 0.0;
    double noise = 0.2 * tb_rng_double(rng);
    out[0] = (float)(inside + noise);
    out[1] = (float)(0.5 + 0.5 * sin(0.3 * x) * cos(0.2 * y));
    out[2] = (float)(inside * 0.25 + 0.01 * x);
}

static tb_image *render(int threads, const tb_aa_options *aa, const tb_filter *f, int tile,
                        uint32_t **counts, tb_aa_stats *stats)
{
    tb_film *film = tb_film_create(&(tb_film_desc){.width = 67, .height = 45, .channels = 3,
                                                   .filter = f, .tile_size = tile});
    assert_non_null(film);
    tb_aa_render_desc d = {.sample = scene, .threads = threads};
    assert_int_equal(tb_aa_render(film, aa, &d, stats), TB_OK);
    assert_true(tb_film_pass_complete(film));
    tb_image *img = tb_film_resolve(film, NULL);
    *counts = malloc(sizeof(uint32_t) * 67 * 45);
    for (int y = 0; y < 45; y++)
        for (int x = 0; x < 67; x++)
            (*counts)[y * 67 + x] = tb_film_sample_count(film, x, y);
    tb_film_free(film);
    return img;
}

static void test_thread_count_determinism(void **state)
{
    (void)state;
    struct {
        tb_filter_kind filter;
        tb_aa_pattern pattern;
        bool adaptive;
        tb_aa_criterion crit;
        int spp, tile;
    } cases[] = {
        {TB_FILTER_MITCHELL, TB_AA_STRATIFIED, true, TB_AA_STDERR, 4, 16},
        {TB_FILTER_GAUSSIAN, TB_AA_SOBOL, true, TB_AA_CONTRAST, 4, 8},
        {TB_FILTER_TENT, TB_AA_STRATIFIED, false, TB_AA_STDERR, 9, 5},
        {TB_FILTER_BOX, TB_AA_SOBOL, false, TB_AA_STDERR, 2, 32},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        tb_filter f;
        tb_filter_init(&f, cases[c].filter, 0.0, 0.0);
        tb_aa_options aa = tb_aa_defaults();
        aa.spp = cases[c].spp;
        aa.pattern = cases[c].pattern;
        aa.adaptive = cases[c].adaptive;
        aa.criterion = cases[c].crit;
        aa.max_spp = 8 * aa.spp;
        aa.seed = 2024;
        const int threads[] = {1, 2, 4};
        tb_image *img[3];
        uint32_t *cnt[3];
        tb_aa_stats st[3];
        for (int t = 0; t < 3; t++)
            img[t] = render(threads[t], &aa, &f, cases[c].tile, &cnt[t], &st[t]);
        for (int t = 1; t < 3; t++) {
            assert_memory_equal(img[0]->pixels, img[t]->pixels, sizeof(float) * 67 * 45 * 3);
            assert_memory_equal(cnt[0], cnt[t], sizeof(uint32_t) * 67 * 45);
            assert_true(st[0].samples == st[t].samples && st[0].pixels_refined == st[t].pixels_refined);
        }
        assert_int_equal((int)st[0].pixels, 67 * 45);
        if (aa.adaptive)
            assert_true(st[0].pixels_refined > 0 && st[0].max_spp_used == aa.max_spp);
        else
            assert_true(st[0].samples == (uint64_t)67 * 45 * aa.spp);
        print_message("[ determ.  ] %s/%s%s: 1, 2, 4 threads identical, %llu samples, %llu pixels refined\n",
                      tb_filter_kind_name(cases[c].filter), cases[c].pattern == TB_AA_SOBOL ? "sobol" : "stratified",
                      aa.adaptive ? "/adaptive" : "", (unsigned long long)st[0].samples,
                      (unsigned long long)st[0].pixels_refined);
        /* a different seed gives a different image (the test can fail) */
        aa.seed = 2025;
        uint32_t *cnt2;
        tb_image *other = render(2, &aa, &f, cases[c].tile, &cnt2, NULL);
        assert_true(memcmp(img[0]->pixels, other->pixels, sizeof(float) * 67 * 45 * 3) != 0);
        tb_image_free(other);
        free(cnt2);
        for (int t = 0; t < 3; t++) {
            tb_image_free(img[t]);
            free(cnt[t]);
        }
    }
}

/* ---------------------------------------------------------------- adaptive */

/* Half-plane a x + b y < c. */
typedef struct edge {
    double a, b, c;
} edge;

static void edge_scene(void *ctx, double x, double y, tb_rng *rng, float *out)
{
    (void)rng;
    const edge *e = ctx;
    out[0] = e->a * x + e->b * y < e->c ? 1.0f : 0.0f;
}

/* Exact area of pixel (px, py) inside the half-plane (clip + shoelace). */
static double coverage(const edge *e, int px, int py)
{
    double in[4][2] = {{px, py}, {px + 1.0, py}, {px + 1.0, py + 1.0}, {px, py + 1.0}};
    double out[8][2];
    int n = 0;
    for (int i = 0; i < 4; i++) {
        const double *p = in[i], *q = in[(i + 1) % 4];
        double fp = e->a * p[0] + e->b * p[1] - e->c, fq = e->a * q[0] + e->b * q[1] - e->c;
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

/* RMS error against the exact coverage over all pixels, and mean spp of
 * edge and flat pixels. */
static void measure(const edge *e, const tb_aa_options *aa, int W, int H, double *rms,
                    double *spp_edge, double *spp_flat, uint64_t *total)
{
    tb_film *film = tb_film_create(&(tb_film_desc){.width = W, .height = H, .channels = 1});
    tb_aa_render_desc d = {.sample = edge_scene, .ctx = (void *)e, .threads = 2};
    tb_aa_stats st;
    assert_int_equal(tb_aa_render(film, aa, &d, &st), TB_OK);
    tb_image *img = tb_film_resolve(film, NULL);
    double sse = 0.0, se = 0.0, sf = 0.0;
    int ne = 0, nf = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            double cov = coverage(e, x, y), err = tb_image_at(img, x, y)[0] - cov;
            sse += err * err;
            if (cov > 0.0 && cov < 1.0) {
                se += tb_film_sample_count(film, x, y);
                ne++;
            } else {
                sf += tb_film_sample_count(film, x, y);
                nf++;
            }
        }
    *rms = sqrt(sse / (W * H));
    *spp_edge = se / ne;
    *spp_flat = sf / nf;
    *total = st.samples + st.ring_samples;
    tb_image_free(img);
    tb_film_free(film);
}

static void test_adaptive_vs_uniform(void **state)
{
    (void)state;
    const int W = 64, H = 64;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("adaptive edge", 8), 0);
    double worst_ratio = INFINITY;
    for (int crit = 0; crit < 2; crit++) {
        for (int pat = 0; pat < 2; pat++) {
            for (int trial = 0; trial < 3; trial++) {
                double ang = 0.1 + 1.3 * tb_rng_double(&rng);
                edge e = {cos(ang), sin(ang), 0.0};
                e.c = e.a * 32.3 + e.b * 31.7;
                tb_aa_options ad = tb_aa_defaults();
                ad.spp = 8;
                ad.adaptive = true;
                ad.criterion = (tb_aa_criterion)crit;
                ad.pattern = (tb_aa_pattern)pat;
                ad.max_spp = 256;
                ad.seed = tb_rng_u32(&rng);
                double rms_a, edge_a, flat_a, rms_u, edge_u, flat_u;
                uint64_t tot_a, tot_u;
                measure(&e, &ad, W, H, &rms_a, &edge_a, &flat_a, &tot_a);
                /* uniform with at least as many samples in all (the
                 * adaptive total includes the neighbours' first rounds) */
                tb_aa_options un = ad;
                un.adaptive = false;
                un.spp = (int)((tot_a + (uint64_t)(W * H) - 1) / (uint64_t)(W * H));
                measure(&e, &un, W, H, &rms_u, &edge_u, &flat_u, &tot_u);
                assert_true(tot_u >= tot_a);
                print_message("[ adaptive ] %s/%s, edge at %.2f rad: adaptive %llu samples (edge %.1f spp, "
                              "flat %.1f) RMS %.5f; uniform %d spp RMS %.5f; %.1fx lower\n",
                              crit ? "contrast" : "stderr", pat ? "sobol" : "stratified", ang,
                              (unsigned long long)tot_a, edge_a, flat_a, rms_a, un.spp, rms_u, rms_u / rms_a);
                /* most flat pixels settle after their first round; those next
                 * to the edge take one more */
                assert_true(flat_a < 9.0);
                assert_true(edge_a > 8.0 * flat_a);
                assert_true(rms_a < 0.6 * rms_u);
                worst_ratio = fmin(worst_ratio, rms_u / rms_a);
            }
        }
    }
    print_message("[ adaptive ] worst error ratio uniform / adaptive: %.2f\n", worst_ratio);
}

/* ---------------------------------------------------------------- cancel */

typedef struct counted {
    atomic_int *cancel;
    atomic_int calls;
} counted;

static void cancelling_scene(void *ctx, double x, double y, tb_rng *rng, float *out)
{
    (void)x;
    (void)y;
    (void)rng;
    counted *c = ctx;
    if (atomic_fetch_add(&c->calls, 1) == 500)
        atomic_store(c->cancel, 1);
    out[0] = 1.0f;
}

static void test_cancel(void **state)
{
    (void)state;
    atomic_int cancel = 1;
    counted ctx = {&cancel, 0};
    tb_film *film = tb_film_create(&(tb_film_desc){.width = 64, .height = 64, .channels = 1, .tile_size = 8});
    tb_aa_options aa = tb_aa_defaults();
    tb_aa_render_desc d = {.sample = cancelling_scene, .ctx = &ctx, .threads = 2, .cancel = &cancel};
    tb_aa_stats st;
    /* cancelled before the start: nothing rendered, pass complete */
    assert_int_equal(tb_aa_render(film, &aa, &d, &st), TB_OK);
    assert_int_equal(st.tiles_skipped, 64);
    assert_int_equal((int)st.samples, 0);
    assert_true(tb_film_pass_complete(film));
    /* cancelled after 500 samples: the tiles in flight finish, the rest are
     * skipped, and the next pass can start */
    atomic_store(&cancel, 0);
    assert_int_equal(tb_aa_render(film, &aa, &d, &st), TB_OK);
    assert_true(st.tiles_skipped > 0 && st.tiles_skipped < 64);
    assert_true(st.samples >= 501 && st.samples == (uint64_t)(64 - st.tiles_skipped) * 64);
    assert_true(tb_film_pass_complete(film));
    tb_image *img = tb_film_resolve(film, NULL);
    int lit = 0;
    for (int i = 0; i < 64 * 64; i++)
        lit += img->pixels[i] == 1.0f;
    assert_int_equal(lit, (int)st.samples);
    tb_image_free(img);
    tb_film_free(film);
    /* bad arguments */
    assert_int_equal(tb_aa_render(NULL, &aa, &d, NULL), TB_ERR_ARG);
    aa.spp = 0;
    film = tb_film_create(&(tb_film_desc){.width = 4, .height = 4, .channels = 1});
    assert_int_equal(tb_aa_render(film, &aa, &d, NULL), TB_ERR_ARG);
    tb_film_free(film);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_thread_count_determinism),
        cmocka_unit_test(test_adaptive_vs_uniform),
        cmocka_unit_test(test_cancel),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
