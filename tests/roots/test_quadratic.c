/* util/roots quadratics: special cases, roots within 4 ulps of a long double
 * reference with an exact discriminant (also for nearly tangent rays), and
 * float against double.
 *
 * Bound: the stable form with Kahan's discriminant has relative error <= 4u
 * per root (D: 2u, sqrt, add, divide: one rounding each), which is <= 4 ulps;
 * this holds for every finite input without overflow, conditioning plays no
 * part, so the property tests also use near-tangent coefficients. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "tb_test.h"

#include "roots_ref.h"
#include "util/roots/roots.h"

#define QUAD_ULPS 4.0

static void expect_roots(double a, double b, double c, int n, double r0, double r1)
{
    double r[2] = {-7.0, -7.0};
    int k = tb_quadratic(a, b, c, r);
    if (k != n)
        fail_msg("quadratic(%g, %g, %g): %d roots, expected %d", a, b, c, k, n);
    if ((n > 0 && r[0] != r0) || (n > 1 && r[1] != r1))
        fail_msg("quadratic(%g, %g, %g): roots %.17g, %.17g, expected %.17g, %.17g", a, b, c, r[0], r[1], r0, r1);

    if ((double)(float)a != a || (double)(float)b != b || (double)(float)c != c)
        return; /* not representable in float: double only */
    float rf[2];
    int kf = tb_quadraticf((float)a, (float)b, (float)c, rf);
    assert_int_equal(kf, n);
    if (n > 0)
        assert_true(rf[0] == (float)r0);
    if (n > 1)
        assert_true(rf[1] == (float)r1);
}

static void test_quadratic_special_cases(void **state)
{
    (void)state;
    expect_roots(1, -3, 2, 2, 1, 2);      /* (x-1)(x-2), exact */
    expect_roots(-2, 6, -4, 2, 1, 2);     /* negative leading coefficient */
    expect_roots(0, 2, 4, 1, -2, 0);      /* a == 0: linear */
    expect_roots(0, 0, 4, 0, 0, 0);       /* 4 = 0 */
    expect_roots(0, 0, 0, 0, 0, 0);       /* 0 = 0: reported as no roots */
    expect_roots(1, 0, -4, 2, -2, 2);     /* b == 0 */
    expect_roots(1, 0, 4, 0, 0, 0);       /* b == 0, imaginary */
    expect_roots(1, -3, 0, 2, 0, 3);      /* c == 0 */
    expect_roots(2, 0, 0, 2, 0, 0);       /* b == c == 0: double root at 0 */
    expect_roots(1, -2, 1, 2, 1, 1);      /* double root */
    expect_roots(4, 4, 1, 2, -0.5, -0.5); /* double root */
    expect_roots(1, 1, 1, 0, 0, 0);       /* complex pair */
    /* Scaled far from 1: the power-of-two rescaling keeps b^2 and 4ac finite. */
    expect_roots(0x1p1000, -3 * 0x1p1000, 2 * 0x1p1000, 2, 1, 2);
    expect_roots(0x1p-1000, -3 * 0x1p-1000, 2 * 0x1p-1000, 2, 1, 2);
    expect_roots(0x1p1000, -0x1p1001, 0x1p1000, 2, 1, 1);

    /* Products that would underflow: x = 2^k y rebalances them (exact here). */
    expect_roots(1.0, -4.5 * 0x1p-500, 4.5 * 0x1p-1000, 2, 1.5 * 0x1p-500, 3 * 0x1p-500);
    expect_roots(0x1p-1000, -4.5 * 0x1p-500, 4.5, 2, 1.5 * 0x1p500, 3 * 0x1p500);
    expect_roots(0x1p-1074, 0x1p-1074, -2 * 0x1p-1074, 2, -2, 1);
    expect_roots(1.0, 0.0, -0x1p-1000, 2, -0x1p-500, 0x1p-500);
    expect_roots(0x1p-900, 0x1p200, 0.0, 1, 0, 0); /* the root -2^1100 overflows: dropped */
    /* A root that overflows is dropped, the other kept: 1e-300 x^2 + 1e10 x + 1. */
    double r[2];
    assert_int_equal(tb_quadratic(1e-300, 1e10, 1.0, r), 1);
    tb_assert_near(r[0], -1e-10, 1e-25);
}

static void test_quadratic_nonfinite(void **state)
{
    (void)state;
    const double bad[3] = {NAN, INFINITY, -INFINITY};
    for (int pos = 0; pos < 3; ++pos)
        for (int j = 0; j < 3; ++j) {
            double c[3] = {1.0, -3.0, 2.0};
            c[pos] = bad[j];
            double r[2] = {0, 0};
            float rf[2] = {0, 0};
            assert_int_equal(tb_quadratic(c[0], c[1], c[2], r), 0);
            assert_int_equal(tb_quadraticf((float)c[0], (float)c[1], (float)c[2], rf), 0);
        }
}

/* Roots of lead (x - r0)(x - r1) built in long double, rounded to double;
 * checked against the reference roots of the rounded coefficients. */
static double check_constructed(long double lead, long double r0, long double r1)
{
    long double rr[2] = {r0, r1}, coef[3];
    ref_expand(lead, rr, 2, NULL, NULL, 0, coef);
    double a = (double)coef[0], b = (double)coef[1], c = (double)coef[2];
    long double ref[2];
    int nref = ref_quadratic(a, b, c, ref);
    double r[2];
    int n = tb_quadratic(a, b, c, r);
    assert_int_equal(n, nref);
    double worst = 0.0;
    for (int i = 0; i < n; ++i)
        worst = fmax(worst, ref_ulps(r[i], ref[i]));
    if (worst > QUAD_ULPS)
        fail_msg("roots %.17Lg, %.17Lg: %.2f ulps", r0, r1, worst);
    return worst;
}

static void test_quadratic_constructed(void **state)
{
    (void)state;
    double worst = 0.0;
    worst = fmax(worst, check_constructed(1.0L, 1e-4L, 1e4L));        /* 1e8 apart */
    worst = fmax(worst, check_constructed(-3.0L, 1e-8L, 1.0L));        /* 1e8 apart */
    worst = fmax(worst, check_constructed(1.0L, -1e-8L, 1e8L));        /* 1e16 apart */
    worst = fmax(worst, check_constructed(0.1L, 1.0L, 1.0L + 1e-7L));  /* clustered */
    worst = fmax(worst, check_constructed(7.0L, 1.0L, 1.0L + 1e-12L)); /* very clustered */
    worst = fmax(worst, check_constructed(1.0L, -2.5L, 3.75L));        /* mixed signs */
    worst = fmax(worst, check_constructed(1e-12L, 3.0L, 5.0L));        /* tiny leading */
    print_message("[ measured ] quadratic constructed cases: worst %.2f ulps\n", worst);
}

/* A random double in +-[0.5, 1.5) * 2^[-20, 20). */
static double rand_coef(tb_rng *rng)
{
    double m = tb_rng_double(rng) + 0.5; /* separate statements: argument order is unspecified */
    double v = ldexp(m, (int)tb_rng_below(rng, 40) - 20);
    return (tb_rng_u32(rng) & 1u) ? -v : v;
}

/* Random double quadratics, half of them nearly tangent (c = b^2/4a
 * perturbed by a random relative amount down to 2^-60), so the discriminant
 * cancels to any degree; counts must match the exact-sign reference and
 * every root be within 4 ulps of it. */
static void test_quadratic_property_double(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("quadratic_property_double", 0x51ad7u), 1);
    double worst = 0.0;
    int counts[3] = {0, 0, 0};
    for (int t = 0; t < 20000; ++t) {
        double a = rand_coef(&rng), b = rand_coef(&rng), c;
        if (t & 1) {
            double m = tb_rng_double(&rng) - 0.5;
            double rel = ldexp(m, -(int)tb_rng_below(&rng, 60));
            c = b * b / (4.0 * a) * (1.0 + rel);
        } else {
            c = rand_coef(&rng);
        }
        long double ref[2];
        int nref = ref_quadratic(a, b, c, ref);
        double r[2];
        int n = tb_quadratic(a, b, c, r);
        if (n != nref)
            fail_msg("t=%d: %a x^2 + %a x + %a: %d roots, reference %d", t, a, b, c, n, nref);
        counts[n]++;
        for (int i = 0; i < n; ++i) {
            double e = ref_ulps(r[i], ref[i]);
            worst = fmax(worst, e);
            if (e > QUAD_ULPS)
                fail_msg("t=%d: %a x^2 + %a x + %a: root %d = %.17g, reference %.20Lg (%.2f ulps)", t, a, b, c,
                         i, r[i], ref[i], e);
        }
    }
    print_message("[ measured ] quadratic random double (%d none, %d two): worst %.2f ulps\n", counts[0],
                  counts[2], worst);
    assert_true(counts[0] > 2000 && counts[2] > 2000); /* both outcomes exercised */
}

/* Random float quadratics (exact in double too, so both solvers face the
 * same equation): generic, nearly tangent (b = 2 sqrt(ac) rounded and nudged
 * by up to 2 ulps) and exactly tangent (a = s^2, b = 2st, c = t^2 with short
 * s, t). Counts agree exactly (both discriminant signs are exact); float
 * roots are within 4 float ulps of the reference and of the double roots. */
static void test_quadratic_property_float(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("quadratic_property_float", 0xf10a7u), 2);
    double worst_f = 0.0, worst_fd = 0.0;
    int counts[3] = {0, 0, 0};
    for (int t = 0; t < 20000; ++t) {
        float a = (float)rand_coef(&rng), b, c = (float)rand_coef(&rng);
        switch (t % 3) {
        case 0:
            b = (float)rand_coef(&rng);
            break;
        case 1: {
            c = copysignf(c, a);
            b = (float)(2.0 * sqrt((double)a * c));
            for (int k = (int)tb_rng_below(&rng, 5) - 2; k != 0; k += k > 0 ? -1 : 1)
                b = nextafterf(b, k > 0 ? INFINITY : 0.0f);
            if (tb_rng_u32(&rng) & 1u)
                b = -b;
            break;
        }
        default: {
            float s = (float)(int)(tb_rng_below(&rng, 4000) + 1), u = (float)(int)(tb_rng_below(&rng, 4000) + 1);
            a = s * s;
            c = u * u;
            b = ((tb_rng_u32(&rng) & 1u) ? 2.0f : -2.0f) * s * u;
            break;
        }
        }
        long double ref[2];
        int nref = ref_quadratic(a, b, c, ref);
        double r[2];
        int n = tb_quadratic(a, b, c, r);
        float rf[2];
        int nf = tb_quadraticf(a, b, c, rf);
        if (n != nref || nf != nref)
            fail_msg("t=%d: %a x^2 + %a x + %a: float %d roots, double %d, reference %d", t, a, b, c, nf, n,
                     nref);
        counts[n]++;
        for (int i = 0; i < n; ++i) {
            double ef = ref_ulpsf(rf[i], ref[i]);
            double efd = ref_ulpsf(rf[i], r[i]);
            worst_f = fmax(worst_f, ef);
            worst_fd = fmax(worst_fd, efd);
            if (ef > QUAD_ULPS || efd > QUAD_ULPS + 0.01)
                fail_msg("t=%d: float root %d = %.9g, reference %.12Lg, double %.17g", t, i, rf[i], ref[i], r[i]);
        }
    }
    print_message("[ measured ] quadratic random float (%d none, %d two): worst %.2f float ulps from the "
                  "reference, %.2f from the double solver\n",
                  counts[0], counts[2], worst_f, worst_fd);
    assert_true(counts[0] > 2000 && counts[2] > 2000);
}

/* Coefficients anywhere in the exponent range (double: 2^+-1000, float:
 * 2^+-120): counts exact and roots within 4 ulps wherever the root itself is
 * a normal number. The long double reference has no range problems. */
static void test_quadratic_wide_range(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("quadratic_wide_range", 0x31de5u), 6);
    double worst = 0.0, worst_f = 0.0;
    for (int t = 0; t < 20000; ++t) {
        double c3[3];
        for (int i = 0; i < 3; ++i) {
            double m = tb_rng_double(&rng) + 0.5;
            double v = ldexp(m, (int)tb_rng_below(&rng, 2000) - 1000);
            c3[i] = (tb_rng_u32(&rng) & 1u) ? -v : v;
        }
        if (t % 4 == 1) /* nearly tangent */
            c3[2] = c3[1] * c3[1] / (4.0 * c3[0]) * (1.0 + ldexp(tb_rng_double(&rng) - 0.5, -40));
        if (!isfinite(c3[2]) || c3[2] == 0.0)
            continue;
        long double ref[2];
        int nref = ref_quadratic(c3[0], c3[1], c3[2], ref);
        double r[2];
        int n = tb_quadratic(c3[0], c3[1], c3[2], r);
        int normal = 1;
        for (int i = 0; i < nref; ++i)
            normal &= fabsl(ref[i]) >= 0x1p-1000L && fabsl(ref[i]) <= 0x1p1000L;
        if (!normal)
            continue;
        if (n != nref)
            fail_msg("t=%d: %a x^2 + %a x + %a: %d roots, reference %d", t, c3[0], c3[1], c3[2], n, nref);
        for (int i = 0; i < n; ++i) {
            double e = ref_ulps(r[i], ref[i]);
            worst = fmax(worst, e);
            if (e > QUAD_ULPS)
                fail_msg("t=%d: %a x^2 + %a x + %a: root %.17g, reference %.20Lg (%.2f ulps)", t, c3[0], c3[1],
                         c3[2], r[i], ref[i], e);
        }

        float cf[3];
        for (int i = 0; i < 3; ++i) {
            double m = tb_rng_double(&rng) + 0.5;
            cf[i] = (float)ldexp(m, (int)tb_rng_below(&rng, 240) - 120);
        }
        if (t & 1)
            cf[1] = -cf[1];
        nref = ref_quadratic(cf[0], cf[1], cf[2], ref);
        float rf[2];
        n = tb_quadraticf(cf[0], cf[1], cf[2], rf);
        normal = 1;
        for (int i = 0; i < nref; ++i)
            normal &= fabsl(ref[i]) >= 0x1p-120L && fabsl(ref[i]) <= 0x1p120L;
        if (!normal)
            continue;
        if (n != nref)
            fail_msg("t=%d: float %a x^2 + %a x + %a: %d roots, reference %d", t, cf[0], cf[1], cf[2], n, nref);
        for (int i = 0; i < n; ++i) {
            double e = ref_ulpsf(rf[i], ref[i]);
            worst_f = fmax(worst_f, e);
            if (e > QUAD_ULPS)
                fail_msg("t=%d: float %a x^2 + %a x + %a: root %.9g, reference %.12Lg (%.2f ulps)", t, cf[0],
                         cf[1], cf[2], rf[i], ref[i], e);
        }
    }
    print_message("[ measured ] quadratic wide exponent range: double worst %.2f ulps, float worst %.2f ulps\n",
                  worst, worst_f);
}

/* tb_quadratic's inline common case (roots.h) against its general path:
 * the same count and roots bit for bit, on random coefficients of every
 * sign and magnitude 2^-1000..2^1000 (the inline range tests meet both
 * sides of 2^+-480, and outside them b^2 and 4ac over- or underflow), with b = 0 and near-tangent cases mixed in. Fails
 * when the inline path takes a case it should leave, or computes it
 * differently. */
static void test_quadratic_inline_matches_general(void **state)
{
    (void)state;
    uint64_t x = 0x9e3779b97f4a7c15u;
    int inline_cases = 0;
    for (int i = 0; i < 200000; i++) {
        double co[3];
        for (int j = 0; j < 3; j++) {
            x ^= x << 13, x ^= x >> 7, x ^= x << 17;
            double m = 1.0 + (double)(x >> 12) * 0x1p-52;   /* [1, 2) */
            int e = (int)((x >> 3) % 2001) - 1000;           /* -1000..1000 */
            co[j] = ldexp((x & 1) ? -m : m, e);
        }
        if (i % 7 == 0)
            co[1] = 0.0;
        if (i % 11 == 0) /* near-tangent: b^2 close to 4ac */
            co[2] = co[1] * co[1] / (4.0 * co[0]) * (1.0 + 0x1p-50 * (double)(i % 5));
        double r1[2] = {-7.0, -7.0}, r2[2] = {-7.0, -7.0};
        int n1 = tb_quadratic(co[0], co[1], co[2], r1);
        int n2 = tb__quadratic_general(co[0], co[1], co[2], r2);
        if (n1 != n2 || memcmp(r1, r2, sizeof(double) * (size_t)n1) != 0)
            fail_msg("quadratic(%a, %a, %a): inline %d roots, general %d", co[0], co[1], co[2], n1, n2);
        double fa = fabs(co[0]), fc = fabs(co[2]);
        inline_cases += fa >= 0x1p-480 && fa <= 0x1p480 && fc >= 0x1p-480 && fc <= 0x1p480;
    }
    assert_true(inline_cases > 1000); /* both paths were exercised */
    assert_true(inline_cases < 190000);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_quadratic_special_cases),
        cmocka_unit_test(test_quadratic_nonfinite),
        cmocka_unit_test(test_quadratic_constructed),
        cmocka_unit_test(test_quadratic_property_double),
        cmocka_unit_test(test_quadratic_property_float),
        cmocka_unit_test(test_quadratic_wide_range),
        cmocka_unit_test(test_quadratic_inline_matches_general),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
