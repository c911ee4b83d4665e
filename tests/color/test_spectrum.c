/* util/color/spectrum: validation, evaluation, exact integrals, resampling. */
#include "tb_test.h"

#include <string.h>

#include "util/color/spectrum.h"

/* Asserts that `call` fails with TB_ERR_ARG and a message containing `needle`. */
#define assert_arg_error(call, needle)                                                  \
    do {                                                                                \
        tb_clear_error();                                                               \
        assert_int_equal((call), TB_ERR_ARG);                                           \
        if (!strstr(tb_last_error(), (needle)))                                         \
            fail_msg("message '%s' lacks '%s'", tb_last_error(), (needle));             \
    } while (0)

static void test_validation(void **state)
{
    (void)state;
    tb_spectrum s;
    const double v[3] = {1, 2, 3};
    const double equal[3] = {400, 500, 500}, down[3] = {400, 500, 450};
    assert_arg_error(tb_spectrum_init(&s, 3, equal, v), "not greater");
    assert_null(s.lambda);
    assert_arg_error(tb_spectrum_init(&s, 3, down, v), "wavelength 2 (450 nm)");
    const double l[3] = {400, 500, 600};
    const double vnan[3] = {1, NAN, 3}, vinf[3] = {1, 2, INFINITY}, vminf[3] = {-INFINITY, 2, 3};
    assert_arg_error(tb_spectrum_init(&s, 3, l, vnan), "value 1 (at 500 nm) is not finite");
    assert_arg_error(tb_spectrum_init(&s, 3, l, vinf), "value 2");
    assert_arg_error(tb_spectrum_init(&s, 3, l, vminf), "value 0");
    const double lnan[3] = {400, NAN, 600}, linf[3] = {400, 500, INFINITY}, lneg[3] = {-1, 500, 600};
    assert_arg_error(tb_spectrum_init(&s, 3, lnan, v), "wavelength 1");
    assert_arg_error(tb_spectrum_init(&s, 3, linf, v), "wavelength 2");
    assert_arg_error(tb_spectrum_init(&s, 3, lneg, v), "> 0");
    assert_arg_error(tb_spectrum_init(&s, 1, l, v), "at least 2");
    assert_arg_error(tb_spectrum_init(&s, 3, NULL, v), "no wavelengths");
    assert_arg_error(tb_spectrum_init(&s, 3, l, NULL), "no values");

    /* Resampling validates the target sample set the same way. */
    assert_int_equal(tb_spectrum_init(&s, 3, l, v), TB_OK);
    double out[3];
    assert_arg_error(tb_spectrum_resample_values(&s, 3, down, out), "target");
    tb_spectrum r;
    assert_arg_error(tb_spectrum_resample(&s, 3, equal, &r), "not greater");
    assert_arg_error(tb_spectrum_scale(&s, NAN, &r), "not finite");
    tb_spectrum_release(&s);
    tb_spectrum_release(&s); /* harmless twice */
}

static void test_eval_rules(void **state)
{
    (void)state;
    const double l[3] = {400, 500, 700}, v[3] = {2, 4, 1};
    tb_spectrum s;
    assert_int_equal(tb_spectrum_init(&s, 3, l, v), TB_OK);
    for (int i = 0; i < 3; i++)
        assert_true(tb_spectrum_eval(&s, l[i]) == v[i]);
    tb_assert_near(tb_spectrum_eval(&s, 450), 3.0, 1e-15);
    tb_assert_near(tb_spectrum_eval(&s, 600), 2.5, 1e-15);
    /* Zero outside the samples, however close. */
    assert_true(tb_spectrum_eval(&s, nextafter(400.0, 0.0)) == 0.0);
    assert_true(tb_spectrum_eval(&s, nextafter(700.0, 1000.0)) == 0.0);
    assert_true(tb_spectrum_eval(&s, 380) == 0.0);
    assert_true(isnan(tb_spectrum_eval(&s, NAN)));
    tb_spectrum_release(&s);
}

/* Exact integrals against closed forms of polynomials. */
static void test_integrals_exact(void **state)
{
    (void)state;
    /* f(l) = 2 l / 100 + 1 on [400, 700] (linear, 4 unevenly spaced samples). */
    const double l[4] = {400, 437.5, 610, 700};
    double v[4];
    for (int i = 0; i < 4; i++)
        v[i] = 2 * l[i] / 100 + 1;
    tb_spectrum f;
    assert_int_equal(tb_spectrum_init(&f, 4, l, v), TB_OK);
    /* F(l) = l^2/100 + l */
#define F1(x) ((x) * (x) / 100 + (x))
    tb_assert_near(tb_spectrum_integral(&f, 400, 700), F1(700.0) - F1(400.0), 1e-9);
    tb_assert_near(tb_spectrum_integral(&f, 450, 620), F1(620.0) - F1(450.0), 1e-9);
    tb_assert_near(tb_spectrum_integral(&f, 620, 450), F1(450.0) - F1(620.0), 1e-9);
    /* Outside the samples nothing is added. */
    tb_assert_near(tb_spectrum_integral(&f, 0, 1000), F1(700.0) - F1(400.0), 1e-9);
    assert_true(tb_spectrum_integral(&f, 100, 300) == 0.0);

    /* g(l) = 3 - l/400 on [300, 650]; h(l) = l/500 on [450, 800]. The product
     * integrals run over [450, 650] where all are defined. */
    const double gl[3] = {300, 520, 650}, hl[2] = {450, 800};
    double gv[3], hv[2];
    for (int i = 0; i < 3; i++)
        gv[i] = 3 - gl[i] / 400;
    for (int i = 0; i < 2; i++)
        hv[i] = hl[i] / 500;
    tb_spectrum g, h;
    assert_int_equal(tb_spectrum_init(&g, 3, gl, gv), TB_OK);
    assert_int_equal(tb_spectrum_init(&h, 2, hl, hv), TB_OK);
    /* int (3 - x/400) x / 500 dx = 3x^2/1000 - x^3/600000 */
#define F2(x) (3 * (x) * (x) / 1000 - (x) * (x) * (x) / 600000)
    tb_assert_near(tb_spectrum_product_integral(&g, &h, NULL), F2(650.0) - F2(450.0), 1e-9);
    /* times f: int (3 - x/400)(x/500)(2x/100 + 1) dx, expanded:
     * (3x/500 - x^2/200000)(x/50 + 1) = 3x^2/25000 + 3x/500 - x^3/10^7 - x^2/200000 */
#define F3(x) ((x) * (x) * (x) / 25000 + 3 * (x) * (x) / 1000 - (x) * (x) * (x) * (x) / 4e7 - \
               (x) * (x) * (x) / 600000)
    tb_assert_near(tb_spectrum_product_integral(&g, &h, &f), F3(650.0) - F3(450.0), 1e-7);
    tb_spectrum_release(&f);
    tb_spectrum_release(&g);
    tb_spectrum_release(&h);
}

/* A random spectrum at 1 nm, 380-780 nm, values in [0, 1). */
static void tb__random_fine(tb_rng *rng, double *l, double *v, int n)
{
    for (int i = 0; i < n; i++) {
        l[i] = 380 + i;
        v[i] = tb_rng_double(rng);
    }
}

static void test_downsample_keeps_integral(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("downsample", 11), 1);
    enum { N = 401, M = 41 };
    double l[N], v[N], tl[M], tv[M], pv[M];
    for (int i = 0; i < M; i++)
        tl[i] = 380 + 10 * i;
    for (int trial = 0; trial < 20; trial++) {
        tb__random_fine(&rng, l, v, N);
        tb_spectrum s, r;
        assert_int_equal(tb_spectrum_init(&s, N, l, v), TB_OK);
        assert_int_equal(tb_spectrum_resample_values(&s, M, tl, tv), TB_OK);
        assert_int_equal(tb_spectrum_init(&r, M, tl, tv), TB_OK);
        double want = tb_spectrum_integral(&s, 380, 780);
        tb_assert_near(tb_spectrum_integral(&r, 380, 780), want, 1e-10 * want);
        /* Averages stay within the data's range (no ringing). */
        for (int j = 0; j < M; j++)
            assert_true(tv[j] >= 0.0 && tv[j] < 1.0);
        /* Point sampling would not keep it: the test can tell them apart. */
        for (int j = 0; j < M; j++)
            pv[j] = tb_spectrum_eval(&s, tl[j]);
        tb_spectrum p;
        assert_int_equal(tb_spectrum_init(&p, M, tl, pv), TB_OK);
        assert_true(fabs(tb_spectrum_integral(&p, 380, 780) - want) > 1e-6 * want);
        tb_spectrum_release(&p);
        tb_spectrum_release(&s);
        tb_spectrum_release(&r);
    }

    /* Linear data averaged onto an evenly spaced coarser grid: the hat is
     * symmetric, so all but the two end samples (half hats) are exact. */
    for (int i = 0; i < N; i++)
        v[i] = 0.5 + 0.002 * l[i];
    tb_spectrum lin;
    assert_int_equal(tb_spectrum_init(&lin, N, l, v), TB_OK);
    for (int j = 0; j < M - 1; j++)
        tl[j] = 385.5 + 9.75 * j;
    assert_int_equal(tb_spectrum_resample_values(&lin, M - 1, tl, tv), TB_OK);
    for (int j = 1; j + 2 < M; j++)
        tb_assert_near(tv[j], 0.5 + 0.002 * tl[j], 1e-12);
    tb_assert_near(tv[0], 0.5 + 0.002 * (tl[0] + 9.75 / 3), 1e-12); /* the half hat's centroid */
    tb_spectrum_release(&lin);

    /* Unevenly spaced coarse targets inside the range keep the integral over theirs. */
    tb__random_fine(&rng, l, v, N);
    tb_spectrum s;
    assert_int_equal(tb_spectrum_init(&s, N, l, v), TB_OK);
    double ul[6] = {401.5, 430, 431.25, 512, 600.7, 777}, uv[6];
    assert_int_equal(tb_spectrum_resample_values(&s, 6, ul, uv), TB_OK);
    tb_spectrum u;
    assert_int_equal(tb_spectrum_init(&u, 6, ul, uv), TB_OK);
    tb_assert_near(tb_spectrum_integral(&u, 0, 1000), tb_spectrum_integral(&s, 401.5, 777), 1e-9);
    tb_spectrum_release(&u);
    tb_spectrum_release(&s);
}

static void test_upsample_exact(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("upsample", 12), 2);
    enum { N = 41, M = 81 };
    double l[N], v[N], tl[M], tv[M];
    for (int i = 0; i < N; i++) {
        l[i] = 380 + 10 * i;
        v[i] = tb_rng_double(&rng);
    }
    for (int j = 0; j < M; j++)
        tl[j] = 380 + 5 * j;
    tb_spectrum s;
    assert_int_equal(tb_spectrum_init(&s, N, l, v), TB_OK);
    assert_int_equal(tb_spectrum_resample_values(&s, M, tl, tv), TB_OK);
    for (int i = 0; i < N; i++) /* coincident samples keep their values exactly */
        assert_true(tv[2 * i] == v[i]);
    for (int i = 0; i + 1 < N; i++) /* new samples lie on the line between */
        tb_assert_near(tv[2 * i + 1], 0.5 * (v[i] + v[i + 1]), 1e-15);
    tb_spectrum r;
    assert_int_equal(tb_spectrum_init(&r, M, tl, tv), TB_OK);
    tb_assert_near(tb_spectrum_integral(&r, 0, 1000), tb_spectrum_integral(&s, 0, 1000), 1e-10);

    /* Resampling onto its own samples is the identity. */
    double same[N];
    assert_int_equal(tb_spectrum_resample_values(&s, N, l, same), TB_OK);
    for (int i = 0; i < N; i++)
        assert_true(same[i] == v[i]);
    tb_spectrum_release(&r);
    tb_spectrum_release(&s);
}

/* The Cornell convention: data over 400-700 nm, zero outside. Resampled onto a
 * wider grid the jump at the ends is averaged, so the integral survives. */
static void test_resample_across_the_ends(void **state)
{
    (void)state;
    const double l[4] = {400, 500, 600, 700}, v[4] = {0.343, 0.747, 0.740, 0.737};
    tb_spectrum s, r;
    assert_int_equal(tb_spectrum_init(&s, 4, l, v), TB_OK);
    double tl[41];
    for (int j = 0; j < 41; j++)
        tl[j] = 380 + 10 * j;
    assert_int_equal(tb_spectrum_resample(&s, 41, tl, &r), TB_OK);
    tb_assert_near(tb_spectrum_integral(&r, 0, 1000), tb_spectrum_integral(&s, 0, 1000), 1e-10);
    assert_true(r.value[0] == 0.0 && r.value[1] == 0.0); /* 380, 390: nothing there */
    assert_true(r.value[2] > 0.0 && r.value[2] < 0.343);  /* 400: half a bin of data */
    tb_assert_near(r.value[12], 0.747, 1e-15);            /* 500: inside, exact */
    tb_spectrum_release(&r);
    tb_spectrum_release(&s);
}

/* Random sample sets on both sides (uneven spacing, finer and coarser in
 * places, target reaching past the source): the integral over the target range
 * is kept and values stay >= 0. */
static void tb__random_grid(tb_rng *rng, double lo, double *l, int n)
{
    l[0] = lo;
    for (int i = 1; i < n; i++)
        l[i] = l[i - 1] + 0.1 + 20.0 * tb_rng_double(rng) * tb_rng_double(rng);
}

static void test_resample_mixed_grids(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("mixed grids", 13), 3);
    enum { N = 60, M = 45 };
    for (int trial = 0; trial < 200; trial++) {
        double l[N], v[N], tl[M];
        tb__random_grid(&rng, 380 + 20 * tb_rng_double(&rng), l, N);
        tb__random_grid(&rng, 360 + 40 * tb_rng_double(&rng), tl, M);
        for (int i = 0; i < N; i++)
            v[i] = tb_rng_double(&rng) < 0.2 ? 0.0 : tb_rng_double(&rng);
        tb_spectrum s, r;
        assert_int_equal(tb_spectrum_init(&s, N, l, v), TB_OK);
        assert_int_equal(tb_spectrum_resample(&s, M, tl, &r), TB_OK);
        for (int j = 0; j < M; j++)
            assert_true(r.value[j] >= 0.0);
        double want = tb_spectrum_integral(&s, tl[0], tl[M - 1]);
        tb_assert_near(tb_spectrum_integral(&r, 0, 2000), want, 1e-12 * (1.0 + want));
        tb_spectrum_release(&r);

        tb_spectrum_release(&s);
    }
}

static void test_multiply_and_scale(void **state)
{
    (void)state;
    const double al[3] = {400, 500, 700}, av[3] = {1, 3, 2};
    const double bl[3] = {450, 550, 800}, bv[3] = {2, 0, 4};
    tb_spectrum a, b, p, k;
    assert_int_equal(tb_spectrum_init(&a, 3, al, av), TB_OK);
    assert_int_equal(tb_spectrum_init(&b, 3, bl, bv), TB_OK);
    assert_int_equal(tb_spectrum_multiply(&a, &b, &p), TB_OK);
    /* Samples: union inside the common range [450, 700]. */
    const double want_l[4] = {450, 500, 550, 700};
    assert_int_equal(p.n, 4);
    for (int i = 0; i < 4; i++) {
        assert_true(p.lambda[i] == want_l[i]);
        tb_assert_near(p.value[i], tb_spectrum_eval(&a, want_l[i]) * tb_spectrum_eval(&b, want_l[i]),
                       1e-15);
    }
    assert_true(tb_spectrum_eval(&p, 440) == 0.0 && tb_spectrum_eval(&p, 720) == 0.0);
    assert_int_equal(tb_spectrum_scale(&a, -2.5, &k), TB_OK);
    for (int i = 0; i < 3; i++)
        assert_true(k.value[i] == -2.5 * av[i] && k.lambda[i] == al[i]);
    tb_spectrum_release(&k);
    tb_spectrum_release(&p);

    /* Disjoint ranges: the product is zero. */
    const double cl[2] = {710, 720}, cv[2] = {1, 1};
    tb_spectrum c;
    assert_int_equal(tb_spectrum_init(&c, 2, cl, cv), TB_OK);
    assert_int_equal(tb_spectrum_multiply(&a, &c, &p), TB_OK);
    assert_true(tb_spectrum_integral(&p, 0, 1000) == 0.0);
    tb_spectrum_release(&p);
    tb_spectrum_release(&c);
    tb_spectrum_release(&a);
    tb_spectrum_release(&b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_validation),
        cmocka_unit_test(test_eval_rules),
        cmocka_unit_test(test_integrals_exact),
        cmocka_unit_test(test_downsample_keeps_integral),
        cmocka_unit_test(test_upsample_exact),
        cmocka_unit_test(test_resample_across_the_ends),
        cmocka_unit_test(test_resample_mixed_grids),
        cmocka_unit_test(test_multiply_and_scale),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
