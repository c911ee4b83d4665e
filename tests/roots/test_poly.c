/* util/roots cubics and quartics (and tb_poly_roots at every degree).
 *
 * Every polynomial is built from chosen roots in long double and rounded to
 * double once (roots_ref.h); expected values are the exact roots of the
 * rounded polynomial, found by long double Newton with compensated
 * evaluation. Stated bounds:
 *  - simple roots: <= SIMPLE_ULPS (1) ulp from the reference, including
 *    clustered (1, 1 + 1e-7) and widely spread (1e-8 .. 1e8) roots, whose
 *    conditioning would cost a plain-Horner Newton many ulps;
 *  - every root: backward error |p(x)| <= 4 n u sum |c_i||x|^(n-i);
 *  - multiple roots given by inexact coefficients, where ulps are
 *    meaningless: the k real roots found near an m-fold root satisfy k <= m,
 *    k = m mod 2, each within 4 (u p~(r) / |p^(m)(r)/m!|)^(1/m) of it (the
 *    perturbation bound for an m-fold root); with exact coefficients the
 *    m-fold root is returned exactly, m times. */
#include "tb_test.h"

#include <string.h>

#include "roots_ref.h"
#include "util/roots/roots.h"
#include "util/roots/roots_internal.h"

#define SIMPLE_ULPS 1.0

/* Worst errors measured over all tests, printed for docs/roots.md. */
static double g_worst_simple_ulps, g_worst_backward;

static void sort_ld(long double *v, int n)
{
    for (int i = 1; i < n; ++i)
        for (int j = i; j > 0 && v[j - 1] > v[j]; --j) {
            long double t = v[j];
            v[j] = v[j - 1];
            v[j - 1] = t;
        }
}

/* Solves the rounded polynomial coef (degree n) and checks it has exactly the
 * real roots near `guess` (simple roots): count, <= SIMPLE_ULPS each,
 * backward error. Returns the worst ulps. */
static double check_simple_coefs(const char *name, const double *c, int n, const long double *guess, int nreal)
{
    long double ref[4] = {0};
    for (int i = 0; i < nreal; ++i) {
        ref[i] = ref_refine(c, n, guess[i]);
        /* The case itself must be valid: rounding the coefficients must not
         * have turned a close pair complex (Newton then wanders off). */
        long double ab, p = ref_eval(c, n, ref[i], NULL, &ab);
        if (!(fabsl(p) <= 0x1p-60L * ab) || !(fabsl(ref[i] - guess[i]) <= 1e-3L * (1.0L + fabsl(guess[i]))))
            fail_msg("%s: invalid case: no real root of the rounded polynomial near %.17Lg", name, guess[i]);
    }
    sort_ld(ref, nreal);
    for (int i = 1; i < nreal; ++i)
        if (!(ref[i] > ref[i - 1]))
            fail_msg("%s: invalid case: roots %d and %d merged", name, i - 1, i);
    double r[4];
    int k = tb_poly_roots(c, n, r);
    if (k != nreal)
        fail_msg("%s: %d roots, expected %d (first %.17g)", name, k, nreal, k > 0 ? r[0] : 0.0);
    double worst = 0.0;
    for (int i = 0; i < k; ++i) {
        double e = ref_ulps(r[i], ref[i]);
        double be = ref_backward(c, n, r[i]);
        worst = fmax(worst, e);
        g_worst_backward = fmax(g_worst_backward, be);
        if (!(e <= SIMPLE_ULPS) || !(be <= 4.0 * n))
            fail_msg("%s: root %d = %.17g, reference %.21Lg: %.2f ulps, backward error %.2f u", name, i, r[i],
                     ref[i], e, be);
    }
    g_worst_simple_ulps = fmax(g_worst_simple_ulps, worst);
    return worst;
}

/* Builds lead * prod (x - real) * prod (complex pairs), then check_simple_coefs. */
static double check_simple(const char *name, long double lead, const long double *real, int nreal,
                           const long double *re, const long double *im, int ncplx)
{
    long double coef[5];
    int n = ref_expand(lead, real, nreal, re, im, ncplx, coef);
    double c[5];
    for (int i = 0; i <= n; ++i)
        c[i] = (double)coef[i];
    return check_simple_coefs(name, c, n, real, nreal);
}

#define LD(...) ((const long double[]){__VA_ARGS__})
#define NREAL(...) (int)(sizeof((const long double[]){__VA_ARGS__}) / sizeof(long double))

static void test_simple_roots(void **state)
{
    (void)state;
    double w = 0.0;
    /* cubics */
    w = fmax(w, check_simple("cubic 1,2,3", 1.0L, LD(1, 2, 3), 3, NULL, NULL, 0));
    w = fmax(w, check_simple("cubic -5,0.25,7 lead -3", -3.0L, LD(-5, 0.25L, 7), 3, NULL, NULL, 0));
    w = fmax(w, check_simple("cubic 1e-4,1,1e4", 1.0L, LD(1e-4L, 1, 1e4L), 3, NULL, NULL, 0));
    w = fmax(w, check_simple("cubic 1e-8,1,2", 2.5L, LD(1e-8L, 1, 2), 3, NULL, NULL, 0));
    w = fmax(w, check_simple("cubic -1e8,1e-8,3", 1.0L, LD(-1e8L, 1e-8L, 3), 3, NULL, NULL, 0));
    w = fmax(w, check_simple("cubic 1,1+1e-7,3 (clustered)", 1.0L, LD(1, 1 + 1e-7L, 3), 3, NULL, NULL, 0));
    w = fmax(w, check_simple("cubic -2,-2+1e-9,5 (clustered)", 0.5L, LD(-2, -2 + 1e-9L, 5), 3, NULL, NULL, 0));
    w = fmax(w, check_simple("cubic 2 and -1+-i", 1.0L, LD(2), 1, LD(-1), LD(1), 1));
    w = fmax(w, check_simple("cubic 1e-6 and 1e3+-1e3i", -4.0L, LD(1e-6L), 1, LD(1e3L), LD(1e3L), 1));
    /* quartics */
    w = fmax(w, check_simple("quartic -2,-1,1,2", 1.0L, LD(-2, -1, 1, 2), 4, NULL, NULL, 0));
    w = fmax(w, check_simple("quartic 1e-4,1e-2,1e2,1e4", 1.0L, LD(1e-4L, 1e-2L, 1e2L, 1e4L), 4, NULL, NULL, 0));
    w = fmax(w, check_simple("quartic -1e-8,1,3,1e8", 3.0L, LD(-1e-8L, 1, 3, 1e8L), 4, NULL, NULL, 0));
    /* Pairs 1e-7 apart are at the limit of what double coefficients resolve
     * (the dip between them, ~1e-15, is the size of the coefficient rounding),
     * so the tight quartic clusters use dyadic roots, whose coefficients are exact. */
    w = fmax(w, check_simple("quartic 1,1+2^-23,2,2+2^-22 (exact)", 1.0L,
                             LD(1, 1 + 0x1p-23L, 2, 2 + 0x1p-22L), 4, NULL, NULL, 0));
    w = fmax(w, check_simple("cubic 1,1+2^-30,-1 (exact)", 1.0L, LD(1, 1 + 0x1p-30L, -1), 3, NULL, NULL, 0));
    w = fmax(w, check_simple("quartic 1,1+1e-6,2,2+1e-6", 1.0L, LD(1, 1 + 1e-6L, 2, 2 + 1e-6L), 4, NULL, NULL, 0));
    w = fmax(w, check_simple("quartic -0.3,0.1,0.1+1e-6,40", -7.0L, LD(-0.3L, 0.1L, 0.1L + 1e-6L, 40), 4, NULL,
                             NULL, 0));
    w = fmax(w, check_simple("quartic 0.5,3 and 1+-2i", 1.0L, LD(0.5L, 3), 2, LD(1), LD(2), 1));
    w = fmax(w, check_simple("quartic -1e4,1e-4 and 0+-1i", 2.0L, LD(-1e4L, 1e-4L), 2, LD(0), LD(1), 1));
    w = fmax(w, check_simple("quartic (x^2+1)(x^2+4)", 1.0L, NULL, 0, LD(0, 0), LD(1, 2), 2));
    w = fmax(w, check_simple("quartic 1+-0.1i, -2+-3i", -1.0L, NULL, 0, LD(1, -2), LD(0.1L, 3), 2));
    w = fmax(w, check_simple("quartic 1+-1e-5i twice (near-real pairs)", 1.0L, NULL, 0, LD(1, 1.5L),
                             LD(1e-5L, 1e-5L), 2));
    print_message("[ measured ] constructed simple roots: worst %.2f ulps\n", w);
}

/* Exact coefficients with multiple roots: the roots come back exactly, with multiplicity. */
static void expect_exact(const char *name, const double *c, int n, const double *want, int nwant)
{
    double r[4] = {0};
    int k = tb_poly_roots(c, n, r);
    int ok = k == nwant;
    for (int i = 0; ok && i < k; ++i)
        ok = r[i] == want[i];
    if (!ok)
        fail_msg("%s: %d roots (%.17g %.17g %.17g %.17g), expected %d", name, k, r[0], r[1], r[2], r[3], nwant);
}

#define DV(...) ((const double[]){__VA_ARGS__})

static void test_exact_multiple_roots(void **state)
{
    (void)state;
    expect_exact("(x-1)^3", DV(1, -3, 3, -1), 3, DV(1, 1, 1), 3);
    expect_exact("-2 (x+2)^3", DV(-2, -12, -24, -16), 3, DV(-2, -2, -2), 3);
    expect_exact("(x-1)^2 (x+3)", DV(1, 1, -5, 3), 3, DV(-3, 1, 1), 3);
    expect_exact("(x-1)^4", DV(1, -4, 6, -4, 1), 4, DV(1, 1, 1, 1), 4);
    expect_exact("(x-2)^3 (x+1)", DV(1, -5, 6, 4, -8), 4, DV(-1, 2, 2, 2), 4);
    expect_exact("(x-1)^2 (x+2)(x-3)", DV(1, -3, -3, 11, -6), 4, DV(-2, 1, 1, 3), 4);
    expect_exact("(x-1)^2 (x+1)^2", DV(1, 0, -2, 0, 1), 4, DV(-1, -1, 1, 1), 4);
    expect_exact("(x-0.5)^2 (x^2+1)", DV(1, -1, 1.25, -1, 0.25), 4, DV(0.5, 0.5), 2);
    expect_exact("x^3", DV(1, 0, 0, 0), 3, DV(0, 0, 0), 3);
    expect_exact("x^4 - x^2", DV(1, 0, -1, 0, 0), 4, DV(-1, 0, 0, 1), 4);
    expect_exact("x^3 + 1 (double critical point, one root)", DV(1, 0, 0, 1), 3, DV(-1), 1);
    expect_exact("x^4 - 1", DV(1, 0, 0, 0, -1), 4, DV(-1, 1), 2);
    expect_exact("x^4 + 1", DV(1, 0, 0, 0, 1), 4, DV(0), 0);
    /* Exact integer coefficients, double/triple root at 1/3 (not a double):
     * p at the computed critical point is ~1e-32, zero to within its rounding,
     * so the tangency is reported (a sign test alone would call it a miss). */
    double r3[4];
    assert_int_equal(tb_poly_roots(DV(9, -6, 10, -6, 1), 4, r3), 2); /* (3x-1)^2 (x^2+1) */
    assert_true(ref_ulps(r3[0], 1.0L / 3) <= 1.0 && ref_ulps(r3[1], 1.0L / 3) <= 1.0);
    assert_int_equal(tb_poly_roots(DV(27, -27, 9, -1), 3, r3), 3); /* (3x-1)^3 */
    for (int i = 0; i < 3; ++i)
        assert_true(ref_ulps(r3[i], 1.0L / 3) <= 1.0);
    assert_int_equal(tb_poly_roots(DV(9, -15, -11, 11, -2), 4, r3), 4); /* (3x-1)^2 (x-2)(x+1) */
    assert_true(r3[0] == -1.0 && r3[3] == 2.0);
    assert_true(ref_ulps(r3[1], 1.0L / 3) <= 1.0 && ref_ulps(r3[2], 1.0L / 3) <= 1.0);
    /* (14x-9)^2 (x^2+x+1) and (20x-11)^2 (x^2+x+1): here p at the critical
     * point comes out as +4e-31 and +8e-31, inside the rounding band. */
    assert_int_equal(tb_poly_roots(DV(196, -56, 25, -171, 81), 4, r3), 2);
    assert_true(ref_ulps(r3[0], 9.0L / 14) <= 1.0 && ref_ulps(r3[1], 9.0L / 14) <= 1.0);
    assert_int_equal(tb_poly_roots(DV(400, -40, 81, -319, 121), 4, r3), 2);
    assert_true(ref_ulps(r3[0], 11.0L / 20) <= 1.0 && ref_ulps(r3[1], 11.0L / 20) <= 1.0);
    /* tb_cubic / tb_quartic are the same solver */
    double r[4];
    assert_int_equal(tb_cubic(1, -6, 11, -6, r), 3);
    assert_true(r[0] == 1 && r[1] == 2 && r[2] == 3);
    assert_int_equal(tb_quartic(1, -10, 35, -50, 24, r), 4);
    assert_true(r[0] == 1 && r[1] == 2 && r[2] == 3 && r[3] == 4);
}

/* m-fold roots of inexact coefficients: see the header comment. */
static void check_multiple(const char *name, long double lead, const long double *real, int nreal,
                           const long double *re, const long double *im, int ncplx)
{
    long double coef[5];
    int n = ref_expand(lead, real, nreal, re, im, ncplx, coef);
    double c[5];
    for (int i = 0; i <= n; ++i)
        c[i] = (double)coef[i];
    double r[4];
    int k = tb_poly_roots(c, n, r);
    int used = 0;
    for (int i = 0; i < nreal; ++i) {
        int m = 0, first = 1;
        for (int j = 0; j < nreal; ++j) {
            if (real[j] == real[i]) {
                ++m;
                first &= j >= i;
            }
        }
        if (!first)
            continue;
        /* |p^(m)(r)/m!| = |lead| prod_{other roots} |r - r_j| prod_pairs |(r-re)^2 + im^2| */
        long double cm = fabsl(lead);
        for (int j = 0; j < nreal; ++j)
            if (real[j] != real[i])
                cm *= fabsl(real[i] - real[j]);
        for (int j = 0; j < ncplx; ++j)
            cm *= (real[i] - re[j]) * (real[i] - re[j]) + im[j] * im[j];
        long double ab;
        ref_eval(c, n, real[i], NULL, &ab);
        long double tol = 4.0L * powl(0x1p-53L * ab / cm, 1.0L / m);
        int near = 0;
        for (int j = 0; j < k; ++j)
            near += fabsl(r[j] - real[i]) <= tol;
        if (near > m || (near & 1) != (m & 1))
            fail_msg("%s: %d roots within %.3Lg of the %d-fold root %.17Lg", name, near, tol, m, real[i]);
        used += near;
    }
    if (used != k)
        fail_msg("%s: %d roots found, only %d near the true ones", name, k, used);
    for (int j = 0; j < k; ++j) {
        double be = ref_backward(c, n, r[j]);
        g_worst_backward = fmax(g_worst_backward, be);
        if (!(be <= 4.0 * n))
            fail_msg("%s: root %.17g has backward error %.2f u", name, r[j], be);
    }
}

static void test_inexact_multiple_roots(void **state)
{
    (void)state;
    check_multiple("(x-0.1)^2 (x-3)(x+2)", 1.0L, LD(0.1L, 0.1L, 3, -2), 4, NULL, NULL, 0);
    check_multiple("(x-0.1)^3", 1.0L, LD(0.1L, 0.1L, 0.1L), 3, NULL, NULL, 0);
    check_multiple("(x+1/3)^3 * 7", 7.0L, LD(-1.0L / 3, -1.0L / 3, -1.0L / 3), 3, NULL, NULL, 0);
    check_multiple("(x-0.7)^4", 1.0L, LD(0.7L, 0.7L, 0.7L, 0.7L), 4, NULL, NULL, 0);
    check_multiple("(x-0.3)^3 (x-5)", -2.0L, LD(0.3L, 0.3L, 0.3L, 5), 4, NULL, NULL, 0);
    check_multiple("(x-1/3)^2 (x-1e3)^2", 1.0L, LD(1.0L / 3, 1.0L / 3, 1e3L, 1e3L), 4, NULL, NULL, 0);
    check_multiple("(x-0.1)^2 (x^2+1)", 1.0L, LD(0.1L, 0.1L), 2, LD(0), LD(1), 1);
    check_multiple("(x-1e-5)^2 (x-1e5)", 1.0L, LD(1e-5L, 1e-5L, 1e5L), 3, NULL, NULL, 0);
}

/* Leading coefficient eps -> 0: roots of eps x^3 + (x-1)(x-2) and of
 * eps x^4 + (x-1)(x-2)(x+3) (the huge root near -1/eps included) stay within
 * the simple-root bound on both sides of the negligibility test, down to
 * where the huge root overflows and is dropped. */
static void test_small_leading_coefficient(void **state)
{
    (void)state;
    double w = 0.0;
    for (int e = 4; e <= 300; e += 3) {
        for (int sgn = -1; sgn <= 1; sgn += 2) {
            double eps = sgn * pow(10.0, -e);
            char name[64];
            snprintf(name, sizeof name, "cubic eps=%g", eps);
            double c3[4] = {eps, 1, -3, 2};
            /* The huge root is near -(b/a) = -1/eps, corrected by +c/b = +3. */
            long double g3[3] = {1, 2, -1.0L / eps - 3};
            w = fmax(w, check_simple_coefs(name, c3, 3, g3, isfinite(1 / eps) ? 3 : 2));

            snprintf(name, sizeof name, "quartic eps=%g", eps);
            double c4[5] = {eps, 1, 0, -7, 6}; /* (x-1)(x-2)(x+3) = x^3 - 7x + 6 */
            long double g4[4] = {-3, 1, 2, -1.0L / eps};
            w = fmax(w, check_simple_coefs(name, c4, 4, g4, 4));
        }
    }
    /* A leading coefficient that underflows the scaled range leaves the quadratic. */
    double r[3];
    assert_int_equal(tb_cubic(0x1p-1074, 1, -3, 2, r), 2);
    assert_true(r[0] == 1 && r[1] == 2);
    print_message("[ measured ] small leading coefficient (1e-4 .. 1e-298): worst %.2f ulps\n", w);
}

static void test_degrees_and_nonfinite(void **state)
{
    (void)state;
    double r[4];
    assert_int_equal(tb_poly_roots(DV(5), 0, r), 0);
    assert_int_equal(tb_poly_roots(DV(0), 0, r), 0);
    assert_int_equal(tb_poly_roots(DV(2, -3), 1, r), 1);
    assert_true(r[0] == 1.5);
    assert_int_equal(tb_poly_roots(DV(0, 0, 0, 2, -3), 4, r), 1); /* leading zeros */
    assert_true(r[0] == 1.5);
    assert_int_equal(tb_poly_roots(DV(0, 0, 0, 0, 0), 4, r), 0);
    assert_int_equal(tb_poly_roots(DV(1, -1, 0, 0, 0, 0), 5, r), 0); /* degree too high */
    assert_int_equal(tb_poly_roots(DV(1, -1), -1, r), 0);
    assert_int_equal(tb_poly_roots(NULL, 2, r), 0);
    /* powers of two far from 1 scale exactly */
    assert_int_equal(tb_quartic(0x1p900, -10 * 0x1p900, 35 * 0x1p900, -50 * 0x1p900, 24 * 0x1p900, r), 4);
    assert_true(r[0] == 1 && r[1] == 2 && r[2] == 3 && r[3] == 4);
    assert_int_equal(tb_cubic(0x1p-1000, -6 * 0x1p-1000, 11 * 0x1p-1000, -6 * 0x1p-1000, r), 3);
    assert_true(r[0] == 1 && r[1] == 2 && r[2] == 3);
    /* roots far from 1 (x = 2^+-200 y is substituted, exactly) */
    const double s = 0x1p-200, t = 0x1p200;
    assert_int_equal(tb_quartic(1, -10 * s, 35 * s * s, -50 * s * s * s, 24 * s * s * s * s, r), 4);
    assert_true(r[0] == 1 * s && r[1] == 2 * s && r[2] == 3 * s && r[3] == 4 * s);
    assert_int_equal(tb_quartic(1, -10 * t, 35 * t * t, -50 * t * t * t, 24 * t * t * t * t, r), 4);
    assert_true(r[0] == 1 * t && r[1] == 2 * t && r[2] == 3 * t && r[3] == 4 * t);
    assert_int_equal(tb_cubic(0x1p-1000, -6 * 0x1p-500, 11 * 0x1p0, -6 * 0x1p500, r), 3);
    assert_true(r[0] == 0x1p500 && r[1] == 2 * 0x1p500 && r[2] == 3 * 0x1p500);

    const double bad[3] = {NAN, INFINITY, -INFINITY};
    for (int pos = 0; pos < 5; ++pos)
        for (int j = 0; j < 3; ++j) {
            double c[5] = {1, -10, 35, -50, 24};
            c[pos] = bad[j];
            assert_int_equal(tb_quartic(c[0], c[1], c[2], c[3], c[4], r), 0);
            if (pos < 4)
                assert_int_equal(tb_cubic(c[0], c[1], c[2], c[3], r), 0);
        }
}

/* Torus (R, r) about the z axis against the ray o + t d: the quartic in t,
 * computed in long double from the double ray and rounded once. */
static int torus_quartic(const double o[3], const double d[3], double R, double rt, double c[5])
{
    long double dd = (long double)d[0] * d[0] + (long double)d[1] * d[1] + (long double)d[2] * d[2];
    long double od = (long double)o[0] * d[0] + (long double)o[1] * d[1] + (long double)o[2] * d[2];
    long double oo = (long double)o[0] * o[0] + (long double)o[1] * o[1] + (long double)o[2] * o[2];
    long double R2 = (long double)R * R, g = oo + R2 - (long double)rt * rt;
    long double dxy = (long double)d[0] * d[0] + (long double)d[1] * d[1];
    long double oxy = (long double)o[0] * d[0] + (long double)o[1] * d[1];
    long double oxyo = (long double)o[0] * o[0] + (long double)o[1] * o[1];
    c[0] = (double)(dd * dd);
    c[1] = (double)(4.0L * dd * od);
    c[2] = (double)(4.0L * od * od + 2.0L * dd * g - 4.0L * R2 * dxy);
    c[3] = (double)(4.0L * od * g - 8.0L * R2 * oxy);
    c[4] = (double)(g * g - 4.0L * R2 * oxyo);
    return 4;
}

/* A ray along +x at height z0 and offset y0 from x = x0 meets the torus where
 * (sqrt(x^2 + y0^2) - R)^2 + z0^2 = r^2, i.e. x = +-sqrt((R +- h)^2 - y0^2),
 * h = sqrt(r^2 - z0^2): analytic roots t = x - x0. Returns their number. */
static int torus_axis_roots(long double x0, long double y0, long double z0, long double R, long double rt,
                            long double *t)
{
    int n = 0;
    long double h2 = rt * rt - z0 * z0;
    if (h2 < 0)
        return 0;
    long double h = sqrtl(h2);
    long double rad[2] = {(R - h) * (R - h) - y0 * y0, (R + h) * (R + h) - y0 * y0};
    for (int i = 0; i < 2; ++i)
        if (rad[i] > 0) {
            t[n++] = -sqrtl(rad[i]) - x0;
            t[n++] = sqrtl(rad[i]) - x0;
        }
    sort_ld(t, n);
    return n;
}

static void test_torus_rays(void **state)
{
    (void)state;
    const double R = 1.0, rt = 0.25;
    struct {
        const char *name;
        double x0, y0, z0;
    } cases[] = {
        {"through the centre", -3, 0, 0},
        {"off-centre", -3, 0.5, 0.1},
        {"grazing the top, 1e-6 below", -3, 0, 0.25 * (1 - 1e-6)},
        {"grazing the top, 1e-12 below", -3, 0, 0.25 * (1 - 1e-12)},
        {"grazing the top off-centre, 1e-10 below", -3, 0.3, 0.25 * (1 - 1e-10)},
        {"grazing the outer equator, 1e-9 inside", -3, 1.25 - 1e-9, 0},
        {"grazing the inner hole, 1e-9 outside", -3, 0.75 + 1e-9, 0},
        {"distant origin", -1000, 0.3, 0.1},
    };
    double worst = 0.0;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        double o[3] = {cases[i].x0, cases[i].y0, cases[i].z0}, d[3] = {1, 0, 0}, c[5];
        torus_quartic(o, d, R, rt, c);
        long double t[4];
        int n = torus_axis_roots(o[0], o[1], o[2], R, rt, t);
        worst = fmax(worst, check_simple_coefs(cases[i].name, c, 4, t, n));
    }
    print_message("[ measured ] torus rays with analytic roots: worst %.2f ulps from the rounded quartic's roots\n",
                  worst);

    /* Exactly tangent rays (dyadic data, exact coefficients): double roots, reported twice. */
    double c[5], r[4];
    torus_quartic(DV(-3, 0, 0.25), DV(1, 0, 0), R, rt, c); /* touches the top circle at x = +-1 */
    assert_int_equal(tb_poly_roots(c, 4, r), 4);
    assert_true(r[0] == 2 && r[1] == 2 && r[2] == 4 && r[3] == 4);
    torus_quartic(DV(-3, 1.25, 0), DV(1, 0, 0), R, rt, c); /* touches the outer equator */
    assert_int_equal(tb_poly_roots(c, 4, r), 2);
    assert_true(r[0] == 3 && r[1] == 3);
    torus_quartic(DV(-3, 0.75, 0), DV(1, 0, 0), R, rt, c); /* touches the inner equator */
    assert_int_equal(tb_poly_roots(c, 4, r), 4);
    assert_true(r[0] == 2 && r[1] == 3 && r[2] == 3 && r[3] == 4);
    torus_quartic(DV(-3, 1.25 + 1e-9, 0), DV(1, 0, 0), R, rt, c); /* misses by 1e-9 */
    assert_int_equal(tb_poly_roots(c, 4, r), 0);
    torus_quartic(DV(-3, 0, 0.25 + 1e-12), DV(1, 0, 0), R, rt, c); /* passes 1e-12 above */
    assert_int_equal(tb_poly_roots(c, 4, r), 0);
}

/* Random rays at a torus (roots unknown): every found root has a small
 * backward error, and on a fine long double sign scan of p(t), each scan cell
 * holds an odd number of found roots exactly when p changes sign across it
 * (so no root is missed and none invented, except in pairs closer than a cell). */
static void test_torus_random_rays(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("torus_random_rays", 0x70a5u), 3);
    const double R = 1.0, rt = 0.3;
    const int cells = 4096;
    int hist[5] = {0};
    for (int t = 0; t < 1000; ++t) {
        double o[3], d[3], c[5], r[4];
        double th = 6.283185307179586 * tb_rng_double(&rng), z = 2.0 * tb_rng_double(&rng) - 1.0;
        double s = sqrt(1.0 - z * z), dist = 2.0 + 3.0 * tb_rng_double(&rng);
        o[0] = dist * s * cos(th);
        o[1] = dist * s * sin(th);
        o[2] = dist * z;
        double target[3]; /* one per statement: the order inside an initializer list is unspecified */
        target[0] = 2.6 * tb_rng_double(&rng) - 1.3;
        target[1] = 2.6 * tb_rng_double(&rng) - 1.3;
        target[2] = 0.7 * tb_rng_double(&rng) - 0.35;
        double len = 0.0;
        for (int i = 0; i < 3; ++i) {
            d[i] = target[i] - o[i];
            len += d[i] * d[i];
        }
        len = sqrt(len);
        for (int i = 0; i < 3; ++i)
            d[i] /= len;
        torus_quartic(o, d, R, rt, c);
        int k = tb_poly_roots(c, 4, r);
        hist[k]++;
        for (int j = 0; j < k; ++j) {
            double be = ref_backward(c, 4, r[j]);
            g_worst_backward = fmax(g_worst_backward, be);
            if (!(be <= 16.0))
                fail_msg("ray %d: root %.17g backward error %.2f u", t, r[j], be);
        }
        /* Roots of the torus along a unit ray lie within |o| + R + r of 0. */
        double lo = -(dist + R + rt + 1.0), hi = dist + R + rt + 1.0;
        long double prev = ref_eval(c, 4, lo, NULL, NULL);
        int j = 0;
        for (int cell = 1; cell <= cells; ++cell) {
            double x1 = lo + (hi - lo) * cell / cells;
            long double cur = ref_eval(c, 4, x1, NULL, NULL);
            int inside = 0;
            while (j < k && r[j] <= x1) {
                ++inside;
                ++j;
            }
            int change = (prev < 0) != (cur < 0);
            if (prev != 0 && cur != 0 && (inside & 1) != change)
                fail_msg("ray %d: cell ending at %.17g has %d roots, sign change %d", t, x1, inside, change);
            prev = cur;
        }
        if (j != k)
            fail_msg("ray %d: root outside the scanned range", t);
    }
    print_message("[ measured ] random torus rays: %d with 0 roots, %d with 2, %d with 4 (odd: %d, %d)\n",
                  hist[0], hist[2], hist[4], hist[1], hist[3]);
    assert_true(hist[2] > 50 && hist[4] > 50);
}

/* Random root sets: 1 or 3 real roots (cubic), 0, 2 or 4 (quartic), the rest
 * complex pairs; magnitudes log-uniform over 1e-3 .. 1e3 with either sign,
 * real roots at least 1e-3 apart relative to their size, complex pairs with
 * imaginary part 0.05 .. 2 times their real part (or purely imaginary).
 * Exactly the real roots must be found, each within SIMPLE_ULPS. */
static void test_random_root_sets(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("random_root_sets", 0x2007u), 4);
    double worst[5] = {0};
    int sets = 0;
    for (int t = 0; t < 30000; ++t) {
        int n = 3 + (t & 1);
        int nreal = (n == 3) ? 1 + 2 * (int)tb_rng_below(&rng, 2) : 2 * (int)tb_rng_below(&rng, 3);
        int ncplx = (n - nreal) / 2;
        long double real[4], re[2], im[2];
        for (int i = 0; i < nreal; ++i) {
            for (;;) {
                long double v = powl(10.0L, 6.0L * tb_rng_double(&rng) - 3.0L);
                real[i] = (tb_rng_u32(&rng) & 1u) ? -v : v;
                int ok = 1;
                for (int j = 0; j < i; ++j)
                    ok &= fabsl(real[i] - real[j]) >= 1e-3L * fmaxl(fabsl(real[i]), fabsl(real[j]));
                if (ok)
                    break;
            }
        }
        for (int i = 0; i < ncplx; ++i) {
            long double v = powl(10.0L, 6.0L * tb_rng_double(&rng) - 3.0L);
            if (tb_rng_below(&rng, 8) == 0) {
                re[i] = 0.0L;
                im[i] = v;
            } else {
                re[i] = (tb_rng_u32(&rng) & 1u) ? -v : v;
                im[i] = v * (0.05L + 1.95L * tb_rng_double(&rng));
            }
        }
        long double lead = powl(10.0L, 4.0L * tb_rng_double(&rng) - 2.0L);
        if (tb_rng_u32(&rng) & 1u)
            lead = -lead;
        char name[48];
        snprintf(name, sizeof name, "random set %d (seeded)", t);
        worst[n] = fmax(worst[n], check_simple(name, lead, real, nreal, re, im, ncplx));
        ++sets;
    }
    print_message("[ measured ] %d random root sets: cubic worst %.2f ulps, quartic worst %.2f ulps\n", sets,
                  worst[3], worst[4]);
}

static void test_polish(void **state)
{
    (void)state;
    /* (x-1)(x-2)(x-3)(x-4) with exact coefficients. */
    const double c[5] = {1, -10, 35, -50, 24};
    assert_true(tb_poly_polish(c, 4, 3.0, -INFINITY, INFINITY) == 3.0); /* an exact root stays */
    assert_true(tb_poly_polish(c, 4, 2.9, -INFINITY, INFINITY) == 3.0);
    assert_true(tb_poly_polish(c, 4, 2.6, 2.5, 3.5) == 3.0);            /* bracketed */
    assert_true(tb_poly_polish(c, 4, 1.0 + 1e-9, 0.5, 1.5) == 1.0);
    /* bracket respected: start at 2.6 but keep to [2.5, 2.55] (no sign change there) */
    double x = tb_poly_polish(c, 4, 2.6, 2.5, 2.55);
    assert_true(x >= 2.5 && x <= 2.55);
    assert_true(isnan(tb_poly_polish(c, 4, NAN, 0, 1)));
    assert_true(tb_poly_polish(DV(1, NAN, 0), 2, 0.5, -INFINITY, INFINITY) == 0.5);

    /* Random inexact polynomials and random starts: never a larger residual,
     * and a start near a simple root ends within SIMPLE_ULPS of it. */
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("polish", 0x9011u), 5);
    double worst = 0.0;
    for (int t = 0; t < 5000; ++t) {
        long double real[4];
        for (int i = 0; i < 4; ++i)
            real[i] = (long double)(4.0 * tb_rng_double(&rng) - 2.0) + (long double)i * 0.001L;
        long double coef[5];
        ref_expand(1.0L, real, 4, NULL, NULL, 0, coef);
        double cd[5];
        for (int i = 0; i <= 4; ++i)
            cd[i] = (double)coef[i];
        double x0 = 6.0 * tb_rng_double(&rng) - 3.0;
        long double ab;
        long double p0 = fabsl(ref_eval(cd, 4, x0, NULL, &ab));
        double x1 = tb_poly_polish(cd, 4, x0, -INFINITY, INFINITY);
        long double p1 = fabsl(ref_eval(cd, 4, x1, NULL, NULL));
        if (!(p1 <= p0 * (1.0L + 0x1p-50L) + 0x1p-100L * ab)) /* my |p| has error ~u|p| */
            fail_msg("t=%d: polish from %.17g to %.17g raised |p| from %.3Lg to %.3Lg", t, x0, x1, p0, p1);
        /* start 1e-6 away from a root that is at least 1e-2 from the others */
        int i = (int)tb_rng_below(&rng, 4);
        int isolated = 1;
        for (int j = 0; j < 4; ++j)
            isolated &= j == i || fabsl(real[j] - real[i]) > 1e-2L;
        if (!isolated)
            continue;
        long double ref = ref_refine(cd, 4, real[i]);
        double y = tb_poly_polish(cd, 4, (double)real[i] + 1e-6, -INFINITY, INFINITY);
        double e = ref_ulps(y, ref);
        worst = fmax(worst, e);
        if (!(e <= SIMPLE_ULPS))
            fail_msg("t=%d: polished %.17g, root %.21Lg (%.2f ulps)", t, y, ref, e);
    }
    print_message("[ measured ] polish from 1e-6 away: worst %.2f ulps\n", worst);
}

/* The exponent helpers of the root bounds give libm's values on every class
 * of input (normal, subnormal, zero, Inf, NaN; 2^k at and past the normal
 * range), so the roots do not depend on which one computed them. */
static void test_exponent_helpers(void **state)
{
    (void)state;
    const double xs[] = {1.0, -1.0, 0.75, 3.0, 0x1p-1022, -0x1p-1022, 0x1.fffffffffffffp+1023, -0x1p+1023,
                         0x1p-1074, 0x1.8p-1060, -0x1p-1030, 0.0, -0.0, INFINITY, -INFINITY, NAN, 1e-300,
                         1e300, 0x1.fffffffffffffp-1, 0x1p-100, 0x1p100};
    for (size_t i = 0; i < sizeof xs / sizeof xs[0]; ++i)
        if (tb__ilogb(xs[i]) != ilogb(xs[i]))
            fail_msg("tb__ilogb(%a) = %d, ilogb %d", xs[i], tb__ilogb(xs[i]), ilogb(xs[i]));
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("exponent_helpers", 0xe4au), 1);
    for (int t = 0; t < 100000; ++t) {
        uint64_t u = (uint64_t)tb_rng_u32(&rng) << 32 | tb_rng_u32(&rng);
        double x;
        memcpy(&x, &u, sizeof x);
        if (!(x != x) && tb__ilogb(x) != ilogb(x))
            fail_msg("tb__ilogb(%a) = %d, ilogb %d", x, tb__ilogb(x), ilogb(x));
    }
    for (int k = -1100; k <= 1100; ++k) {
        double a = tb__pow2(k), b = ldexp(1.0, k);
        if (memcmp(&a, &b, sizeof a) != 0)
            fail_msg("tb__pow2(%d) = %a, ldexp %a", k, a, b);
    }
}

static void test_report_worst(void **state)
{
    (void)state;
    print_message("[ measured ] all simple roots: worst %.2f ulps; all roots: worst backward error %.2f u\n",
                  g_worst_simple_ulps, g_worst_backward);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_simple_roots),
        cmocka_unit_test(test_exact_multiple_roots),
        cmocka_unit_test(test_inexact_multiple_roots),
        cmocka_unit_test(test_small_leading_coefficient),
        cmocka_unit_test(test_degrees_and_nonfinite),
        cmocka_unit_test(test_torus_rays),
        cmocka_unit_test(test_torus_random_rays),
        cmocka_unit_test(test_random_root_sets),
        cmocka_unit_test(test_polish),
        cmocka_unit_test(test_exponent_helpers),
        cmocka_unit_test(test_report_worst),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
