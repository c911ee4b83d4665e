/* Pixel sample patterns: strata splits, one jittered sample per stratum in
 * every round, (0,m,2)-nets from the Sobol' pattern, samples independent of
 * the order pixels are visited in, the adaptive criteria against values
 * worked out by hand, and command-line parsing. */
#include "tb_test.h"

#include "util/math/float.h"

#include <string.h>

#include "host/render/antialias.h"

static void test_strata(void **state)
{
    (void)state;
    for (int n = 1; n <= 200; n++) {
        int nx, ny;
        tb_aa_strata(n, &nx, &ny);
        assert_int_equal(nx * ny, n);
        assert_true(nx >= ny && ny >= 1);
        /* ny is the largest divisor of n not above sqrt(n) */
        for (int d = ny + 1; d * d <= n; d++)
            assert_true(n % d != 0);
    }
    int nx, ny;
    tb_aa_strata(16, &nx, &ny);
    assert_true(nx == 4 && ny == 4);
    tb_aa_strata(12, &nx, &ny);
    assert_true(nx == 4 && ny == 3);
    tb_aa_strata(7, &nx, &ny);
    assert_true(nx == 7 && ny == 1);
}

static void test_one_per_stratum(void **state)
{
    (void)state;
    const int spps[] = {1, 2, 4, 6, 9, 12, 16, 25, 64};
    float xy[2 * 64];
    int cells[64];
    for (size_t si = 0; si < sizeof spps / sizeof spps[0]; si++) {
        tb_aa_options o = tb_aa_defaults();
        o.spp = spps[si];
        o.seed = 1234;
        int nx, ny;
        tb_aa_strata(o.spp, &nx, &ny);
        for (int py = 0; py < 6; py++)
            for (int px = 0; px < 6; px++) {
                tb_pixel_sampler s;
                tb_pixel_sampler_init(&s, &o, px, py);
                for (int round = 0; round < 4; round++) {
                    assert_int_equal(tb_pixel_sampler_round(&s, xy), o.spp);
                    memset(cells, 0, sizeof cells);
                    for (int k = 0; k < o.spp; k++) {
                        float x = xy[2 * k], y = xy[2 * k + 1];
                        assert_true(x >= 0.0f && x < 1.0f && y >= 0.0f && y < 1.0f);
                        /* the stratum in exact arithmetic (float times a
                         * small integer is exact in double) */
                        int cx = (int)floor((double)x * nx), cy = (int)floor((double)y * ny);
                        cells[cy * nx + cx]++;
                    }
                    for (int c = 0; c < o.spp; c++)
                        assert_int_equal(cells[c], 1);
                }
                assert_int_equal(s.taken, 4 * o.spp);
            }
    }
}

/* Every elementary interval of area 2^-m (2^-a by 2^-(m-a)) holds exactly one
 * of the 2^m points. */
static void assert_net(const double *xy, int m)
{
    int n = 1 << m;
    int counts[1 << 10];
    for (int a = 0; a <= m; a++) {
        int nxa = 1 << a, nya = 1 << (m - a);
        memset(counts, 0, sizeof(int) * (size_t)n);
        for (int k = 0; k < n; k++) {
            int cx = (int)(xy[2 * k] * nxa), cy = (int)(xy[2 * k + 1] * nya);
            counts[cy * nxa + cx]++;
        }
        for (int c = 0; c < n; c++)
            if (counts[c] != 1)
                fail_msg("(0,%d,2)-net broken: interval %d of %dx%d holds %d points", m, c, nxa, nya,
                         counts[c]);
    }
}

/* The rounds of a stratified pixel fill each stratum evenly: after 2^m rounds
 * the points of a stratum, in the stratum's own coordinates, are a
 * (0,m,2)-net (independent jittered rounds would clump). */
static void test_stratified_rounds_fill(void **state)
{
    (void)state;
    const int spps[] = {4, 6, 9};
    float xy[2 * 9 * 32];
    double local[2 * 32];
    for (size_t si = 0; si < sizeof spps / sizeof spps[0]; si++) {
        tb_aa_options o = tb_aa_defaults();
        o.spp = spps[si];
        o.seed = 99;
        int nx, ny;
        tb_aa_strata(o.spp, &nx, &ny);
        for (int p = 0; p < 4; p++) {
            tb_pixel_sampler s;
            tb_pixel_sampler_init(&s, &o, p, 7);
            for (int r = 0; r < 32; r++)
                tb_pixel_sampler_round(&s, xy + 2 * r * o.spp);
            for (int m = 1; m <= 5; m++)
                for (int c = 0; c < o.spp; c++) {
                    for (int r = 0; r < (1 << m); r++) {
                        const float *q = xy + 2 * (r * o.spp + c);
                        local[2 * r] = (double)q[0] * nx - c % nx;
                        local[2 * r + 1] = (double)q[1] * ny - c / nx;
                    }
                    assert_net(local, m);
                }
        }
    }
}

static void test_sobol_nets(void **state)
{
    (void)state;
    float xy[2 * 1024];
    double d[2 * 1024];
    for (int m = 0; m <= 8; m++) {
        tb_aa_options o = tb_aa_defaults();
        o.pattern = TB_AA_SOBOL;
        o.spp = 1 << m;
        o.seed = 77;
        for (int p = 0; p < 5; p++) {
            tb_pixel_sampler s;
            tb_pixel_sampler_init(&s, &o, p, 3 * p);
            /* each round on its own, and two rounds together (m + 1) */
            tb_pixel_sampler_round(&s, xy);
            tb_pixel_sampler_round(&s, xy + 2 * o.spp);
            for (int k = 0; k < 4 * o.spp; k++)
                d[k] = xy[k];
            assert_net(d, m);
            assert_net(d + 2 * o.spp, m);
            assert_net(d, m + 1);
        }
    }
    /* the scramble differs between pixels: the first points differ */
    tb_aa_options o = tb_aa_defaults();
    o.pattern = TB_AA_SOBOL;
    o.spp = 4;
    tb_pixel_sampler a, b;
    tb_pixel_sampler_init(&a, &o, 0, 0);
    tb_pixel_sampler_init(&b, &o, 1, 0);
    float xa[8], xb[8];
    tb_pixel_sampler_round(&a, xa);
    tb_pixel_sampler_round(&b, xb);
    assert_true(memcmp(xa, xb, sizeof xa) != 0);
}

/* Samples of a pixel are the same whatever order the pixels are visited in. */
static void test_order_independence(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("aa order", 17), 0);
    enum { W = 9, H = 7, SPP = 6, ROUNDS = 3 };
    static float ref[W * H][ROUNDS * SPP * 2], got[W * H][ROUNDS * SPP * 2];
    static uint32_t ref_r[W * H][ROUNDS * SPP], got_r[W * H][ROUNDS * SPP];
    for (int pat = 0; pat < 2; pat++) {
        tb_aa_options o = tb_aa_defaults();
        o.spp = SPP;
        o.pattern = (tb_aa_pattern)pat;
        o.seed = 0xfeedull;
        o.pass = 2;
        for (int pass = 0; pass < 2; pass++) {
            int order[W * H];
            for (int i = 0; i < W * H; i++)
                order[i] = i;
            if (pass == 1)
                for (int i = W * H - 1; i > 0; i--) {
                    int j = (int)tb_rng_below(&rng, (uint32_t)i + 1);
                    int t = order[i];
                    order[i] = order[j];
                    order[j] = t;
                }
            for (int i = 0; i < W * H; i++) {
                int p = order[i], px = p % W, py = p / W;
                tb_pixel_sampler s;
                tb_pixel_sampler_init(&s, &o, px, py);
                float(*dst)[ROUNDS * SPP * 2] = pass ? got : ref;
                uint32_t(*dr)[ROUNDS * SPP] = pass ? got_r : ref_r;
                for (int r = 0; r < ROUNDS; r++)
                    tb_pixel_sampler_round(&s, dst[p] + 2 * r * SPP);
                /* the per-sample streams, asked for in reverse order */
                for (int k = ROUNDS * SPP - 1; k >= 0; k--) {
                    tb_rng sr;
                    tb_aa_sample_rng(&o, px, py, (uint32_t)k, &sr);
                    dr[p][k] = tb_rng_u32(&sr);
                }
            }
        }
        assert_memory_equal(ref, got, sizeof ref);
        assert_memory_equal(ref_r, got_r, sizeof ref_r);
        /* different pixels and different samples get different streams */
        assert_true(memcmp(ref[0], ref[1], sizeof ref[0]) != 0);
        assert_true(ref_r[0][0] != ref_r[0][1] && ref_r[0][0] != ref_r[1][0]);
    }
    /* seed and pass change the samples */
    tb_aa_options o = tb_aa_defaults();
    o.spp = 4;
    float a[8], b[8], c[8];
    tb_pixel_sampler s;
    tb_pixel_sampler_init(&s, &o, 3, 3);
    tb_pixel_sampler_round(&s, a);
    o.seed = 1;
    tb_pixel_sampler_init(&s, &o, 3, 3);
    tb_pixel_sampler_round(&s, b);
    o.seed = 0;
    o.pass = 1;
    tb_pixel_sampler_init(&s, &o, 3, 3);
    tb_pixel_sampler_round(&s, c);
    assert_true(memcmp(a, b, sizeof a) != 0 && memcmp(a, c, sizeof a) != 0);
}

static void test_criteria(void **state)
{
    (void)state;
    tb_aa_options o = tb_aa_defaults();
    o.adaptive = true;
    float lw1[1] = {1.0f};
    /* fewer than two samples: always refine */
    float one[1] = {0.5f};
    assert_true(tb_aa_needs_more(&o, 1, lw1, one, 1));
    /* flat: never */
    float flat[4] = {0.25f, 0.25f, 0.25f, 0.25f};
    assert_false(tb_aa_needs_more(&o, 1, lw1, flat, 4));
    /* {1, 1, 1, 1.1}: mean 1.025, sum of squares 3 * 0.025^2 + 0.075^2 = 0.0075,
     * s^2 = 0.0025, standard error sqrt(0.0025 / 4) = 0.025; the bar is
     * T (1.025 + 1/256) = 0.0309 at T = 0.03 and 0.0206 at T = 0.02 */
    float v[4] = {1.0f, 1.0f, 1.0f, 1.1f};
    o.threshold = 0.03;
    assert_false(tb_aa_needs_more(&o, 1, lw1, v, 4));
    o.threshold = 0.02;
    assert_true(tb_aa_needs_more(&o, 1, lw1, v, 4));
    /* default threshold */
    o.threshold = 0.0;
    tb_assert_near(tb_aa_threshold(&o), TB_AA_STDERR_DEFAULT, 0.0);
    /* luminance weights decide for RGB: a change in blue alone counts 0.0722 */
    float lw3[3];
    tb_aa_luminance_weights(3, lw3);
    tb_assert_near(lw3[0] + lw3[1] + lw3[2], 1.0, 1e-6);
    float blue[6] = {1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.1f};
    o.threshold = 0.02; /* Y = {1, 1.00722}: se = 0.0036 < 0.02 (1.0036 + 1/256) */
    assert_false(tb_aa_needs_more(&o, 3, lw3, blue, 2));
    float green[6] = {1.0f, 1.0f, 1.0f, 1.0f, 1.1f, 1.0f};
    /* Y = {1, 1.07152}: se = 0.03576 > 0.02 (1.03576 + 1/256) */
    assert_true(tb_aa_needs_more(&o, 3, lw3, green, 2));

    /* Mitchell's contrast: thresholds 0.4, 0.3, 0.6 for R, G, B at T = 0.4 */
    o.criterion = TB_AA_CONTRAST;
    o.threshold = 0.0;
    tb_assert_near(tb_aa_threshold(&o), 0.4, 0.0);
    float r1[6] = {0.2f, 0.5f, 0.5f, 0.4f, 0.5f, 0.5f}; /* R: 0.2/0.6 = 0.333 < 0.4 */
    assert_false(tb_aa_needs_more(&o, 3, lw3, r1, 2));
    float r2[6] = {0.2f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f}; /* R: 0.3/0.7 = 0.429 > 0.4 */
    assert_true(tb_aa_needs_more(&o, 3, lw3, r2, 2));
    float g1[6] = {0.5f, 0.2f, 0.5f, 0.5f, 0.4f, 0.5f}; /* G: 0.333 > 0.3 */
    assert_true(tb_aa_needs_more(&o, 3, lw3, g1, 2));
    float b1[6] = {0.5f, 0.5f, 0.2f, 0.5f, 0.5f, 0.6f}; /* B: 0.5 < 0.6 */
    assert_false(tb_aa_needs_more(&o, 3, lw3, b1, 2));
    float zeros[6] = {0};
    assert_false(tb_aa_needs_more(&o, 3, lw3, zeros, 2));
}

static void test_parse_args(void **state)
{
    (void)state;
    char *argv[] = {"render", "--spp", "16", "--adaptive", "0.05", "--max-spp", "256", "--adaptive",
                    "--aa-pattern", "sobol", "--aa-criterion", "contrast", "--filter", "gaussian:2",
                    "-o", "x.png"};
    int argc = (int)(sizeof argv / sizeof argv[0]);
    tb_aa_options o = tb_aa_defaults();
    tb_filter f;
    tb_filter_init(&f, TB_FILTER_BOX, 0, 0);
    int i = 1, consumed = 0;
    for (; i < argc; i++) {
        int r = tb_aa_parse_arg(argc, argv, &i, &o, &f);
        assert_true(r >= 0);
        if (r == 0)
            break;
        consumed++;
    }
    assert_int_equal(consumed, 7);
    assert_string_equal(argv[i], "-o");
    assert_int_equal(o.spp, 16);
    assert_true(o.adaptive && o.threshold == 0.05 && o.max_spp == 256);
    assert_true(o.pattern == TB_AA_SOBOL && o.criterion == TB_AA_CONTRAST);
    assert_true(f.kind == TB_FILTER_GAUSSIAN && f.radius == 2.0);
    assert_int_equal(tb_aa_max_spp(&o), 256);
    o.max_spp = 0;
    assert_int_equal(tb_aa_max_spp(&o), 256); /* 16 spp */
    o.adaptive = false;
    assert_int_equal(tb_aa_max_spp(&o), 16);

    char *bad[][2] = {{"--spp", "0"},        {"--spp", "x"},         {"--spp", NULL},
                      {"--max-spp", "-3"},   {"--adaptive", "-0.1"}, {"--aa-pattern", "halton"},
                      {"--aa-criterion", ""}, {"--filter", "lanczos"}};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        int j = 0;
        int n = bad[k][1] ? 2 : 1;
        assert_int_equal(tb_aa_parse_arg(n, bad[k], &j, &o, &f), -1);
        assert_true(strlen(tb_last_error()) > 0);
    }
    /* not ours, or refused when the target is NULL */
    char *other[] = {"--threads", "4"};
    int j = 0;
    assert_int_equal(tb_aa_parse_arg(2, other, &j, &o, &f), 0);
    char *filt[] = {"--filter", "box"};
    assert_int_equal(tb_aa_parse_arg(2, filt, &j, &o, NULL), 0);
    /* --adaptive followed by another option keeps the default threshold */
    tb_aa_options o2 = tb_aa_defaults();
    char *ad[] = {"--adaptive", "--spp", "4"};
    j = 0;
    assert_int_equal(tb_aa_parse_arg(3, ad, &j, &o2, NULL), 1);
    assert_int_equal(j, 0);
    assert_true(o2.adaptive && o2.threshold == 0.0);
    /* option checks */
    o2.spp = 0;
    assert_int_equal(tb_aa_check(&o2), TB_ERR_ARG);
    o2.spp = 4;
    o2.threshold = NAN;
    assert_int_equal(tb_aa_check(&o2), TB_ERR_ARG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_strata),
        cmocka_unit_test(test_one_per_stratum),
        cmocka_unit_test(test_stratified_rounds_fill),
        cmocka_unit_test(test_sobol_nets),
        cmocka_unit_test(test_order_independence),
        cmocka_unit_test(test_criteria),
        cmocka_unit_test(test_parse_args),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
