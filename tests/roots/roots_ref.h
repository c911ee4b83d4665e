/* Long double references for the root-finder tests, written independently of
 * util/roots: polynomials are built from chosen roots in long double and
 * rounded to double once; the exact roots of the rounded (double)
 * polynomial are then found by Newton in long double with compensated
 * evaluation, good to about 2^-64 relative even for roots with
 * condition number up to ~1e15, i.e. far below one double ulp. */
#ifndef TB_TESTS_ROOTS_ROOTS_REF_H
#define TB_TESTS_ROOTS_ROOTS_REF_H

#include <float.h>
#include <math.h>

/* Coefficients (highest power first) of
 * lead * prod_i (x - real[i]) * prod_j (x^2 - 2 re_j x + re_j^2 + im_j^2). Returns the degree. */
static inline int ref_expand(long double lead, const long double *real, int nreal,
                             const long double *re, const long double *im, int ncplx, long double *coef)
{
    int n = 0;
    coef[0] = lead;
    for (int i = 0; i < nreal; ++i) { /* multiply by (x - r) */
        coef[n + 1] = 0.0L;
        for (int k = n + 1; k >= 1; --k)
            coef[k] -= real[i] * coef[k - 1];
        ++n;
    }
    for (int j = 0; j < ncplx; ++j) { /* multiply by (x^2 + s x + t) */
        long double s = -2.0L * re[j], t = re[j] * re[j] + im[j] * im[j];
        coef[n + 1] = coef[n + 2] = 0.0L;
        for (int k = n + 2; k >= 2; --k)
            coef[k] += s * coef[k - 1] + t * coef[k - 2];
        coef[1] += s * coef[0];
        n += 2;
    }
    return n;
}

/* a*b = *p + *e exactly (Dekker's product with Veltkamp's split for the
 * 64-bit long double significand; glibc's fmal is exact but ~50x slower). */
static inline void ref_two_prod(long double a, long double b, long double *p, long double *e)
{
    const long double split = 4294967297.0L; /* 2^32 + 1 */
    long double ca = split * a, cb = split * b;
    long double ah = ca - (ca - a), al = a - ah;
    long double bh = cb - (cb - b), bl = b - bh;
    *p = a * b;
    *e = ((ah * bh - *p) + ah * bl + al * bh) + al * bl;
}

/* p(x) for double coefficients c[0..n], compensated Horner in long double;
 * *dp gets p'(x), *abs gets sum |c_i| |x|^(n-i). */
static inline long double ref_eval(const double *c, int n, long double x, long double *dp, long double *abs)
{
    long double s = c[0], comp = 0.0L, ds = 0.0L, ab = fabsl((long double)c[0]), ax = fabsl(x);
    for (int i = 1; i <= n; ++i) {
        ds = ds * x + s;
        long double prod, pe;
        ref_two_prod(s, x, &prod, &pe);
        long double sum = prod + c[i];
        long double z = sum - prod;
        long double se = (prod - (sum - z)) + ((long double)c[i] - z);
        comp = comp * x + (pe + se);
        s = sum;
        ab = ab * ax + fabsl((long double)c[i]);
    }
    if (dp)
        *dp = ds;
    if (abs)
        *abs = ab;
    return s + comp;
}

/* The root of the double polynomial c[0..n] that Newton reaches from x (in long double). */
static inline long double ref_refine(const double *c, int n, long double x)
{
    for (int it = 0; it < 300; ++it) {
        long double dp;
        long double p = ref_eval(c, n, x, &dp, NULL);
        if (p == 0.0L || dp == 0.0L)
            break;
        long double step = p / dp;
        x -= step;
        if (fabsl(step) <= 0x1p-62L * fabsl(x))
            break;
    }
    return x;
}

/* Roots of the double quadratic a x^2 + b x + c in long double, with the
 * discriminant from exact two-products (so its sign and value are right even
 * when b^2 and 4ac cancel). Returns the count (roots ascending). */
static inline int ref_quadratic(double a, double b, double c, long double r[2])
{
    long double bb, bbe, ac, ace;
    ref_two_prod(b, b, &bb, &bbe);
    ref_two_prod(a, c, &ac, &ace);
    long double disc = (bb - 4.0L * ac) + (bbe - 4.0L * ace);
    if (a == 0.0) {
        if (b == 0.0)
            return 0;
        r[0] = -(long double)c / b;
        return 1;
    }
    if (disc < 0.0L)
        return 0;
    long double sq = sqrtl(disc);
    long double q = -0.5L * (b + (b < 0.0 ? -sq : sq));
    if (q == 0.0L) {
        r[0] = r[1] = 0.0L;
        return 2;
    }
    long double x0 = q / a, x1 = c / q;
    r[0] = x0 < x1 ? x0 : x1;
    r[1] = x0 < x1 ? x1 : x0;
    return 2;
}

/* |x - ref| in units of the double ulp at ref (0 when both are 0). */
static inline double ref_ulps(double x, long double ref)
{
    double r = fabs((double)ref);
    if (r == 0.0)
        return x == 0.0 ? 0.0 : INFINITY;
    double ulp = nextafter(r, INFINITY) - r;
    return (double)(fabsl((long double)x - ref) / ulp);
}

/* |x - ref| in units of the float ulp at ref. */
static inline double ref_ulpsf(float x, long double ref)
{
    float r = fabsf((float)ref);
    if (r == 0.0f)
        return x == 0.0f ? 0.0 : INFINITY;
    float ulp = nextafterf(r, INFINITY) - r;
    return (double)(fabsl((long double)x - ref) / ulp);
}

/* Backward error of a computed root: |p(x)| / sum |c_i| |x|^(n-i), in units
 * of u = 2^-53. A root within k ulps has at most about 2 n k. */
static inline double ref_backward(const double *c, int n, double x)
{
    long double ab;
    long double p = ref_eval(c, n, x, NULL, &ab);
    if (ab == 0.0L)
        return 0.0;
    return (double)(fabsl(p) / ab / 0x1p-53L);
}

#endif
