/* Accurate polynomial evaluation and Newton polishing of roots.
 *
 * Newton's method can place a root no closer than the error of the computed
 * p(x) allows. Plain Horner has error about u * sum |a_i||x|^i, which for a
 * root with condition number K leaves K ulps; compensated Horner (Graillat,
 * Langlois, Louvet, "Algorithms for accurate, validated and fast polynomial
 * evaluation", 2009) carries the rounding error of every step exactly (fma
 * for products, TwoSum for sums), so the value is as good as if computed in
 * twice the precision and polished roots land within about 1 ulp unless
 * K approaches 1/u. */
#include "util/roots/roots.h"

#include <math.h>

#include "util/roots/roots_internal.h"

/* The bodies of tb__poly_eval and tb__poly_eval_quick, inlined where the
 * degree is a constant (tb__poly_bracketed's cubic and quartic cases) so
 * that the loops unroll; the same operations in the same order. */
static inline __attribute__((always_inline)) tb__peval tb__eval_impl(const double *a, int n, double x)
{
    double s = a[0], comp = 0.0, ds = 0.0, dds = 0.0, abs = fabs(a[0]), ax = fabs(x);
    for (int i = 1; i <= n; ++i) {
        dds = dds * x + ds;
        ds = ds * x + s;
        double prod = s * x;
        double prod_err = fma(s, x, -prod); /* s*x - prod exactly */
        double sum = prod + a[i];
        double z = sum - prod; /* TwoSum (Knuth): sum_err exact */
        double sum_err = (prod - (sum - z)) + (a[i] - z);
        comp = comp * x + (prod_err + sum_err);
        s = sum;
        abs = abs * ax + fabs(a[i]);
    }
    return (tb__peval){s + comp, ds, 2.0 * dds, abs};
}

tb__peval tb__poly_eval(const double *a, int n, double x) { return tb__eval_impl(a, n, x); }

static inline __attribute__((always_inline)) tb__peval tb__eval_quick_impl(const double *a, int n, double x)
{
    double p = a[0], dp = 0.0, ddp = 0.0, abs = fabs(a[0]), ax = fabs(x);
    for (int i = 1; i <= n; ++i) {
        ddp = ddp * x + dp;
        dp = dp * x + p;
        p = p * x + a[i];
        abs = abs * ax + fabs(a[i]);
    }
    /* Plain Horner is off by at most gamma(2n) * abs (Higham, 5.1); outside
     * twice that its sign is certain and its value good enough to steer. */
    double g = 2.0 * n * TB__ROOTS_U;
    if (fabs(p) > 2.5 * g * abs)
        return (tb__peval){p, dp, 2.0 * ddp, abs};
    return tb__eval_impl(a, n, x);
}

tb__peval tb__poly_eval_quick(const double *a, int n, double x) { return tb__eval_quick_impl(a, n, x); }

double tb_poly_eval(const double *coef, int degree, double x, double *deriv)
{
    if (!coef || degree < 0) {
        if (deriv)
            *deriv = 0.0;
        return 0.0;
    }
    tb__peval e = tb__poly_eval(coef, degree, x);
    if (deriv)
        *deriv = e.dp;
    return e.p;
}

/* True when [lo, hi] lies on one side of 0 and spans more than 8 binades:
 * then Newton from inside may crawl (far from the roots it shrinks x only by
 * (n-1)/n per step), while geometric bisection halves the span in binades. */
static int tb__wide(double lo, double hi)
{
    return (lo > 0.0 && hi > 256.0 * lo) || (hi < 0.0 && lo < 256.0 * hi);
}

/* Bisection point of [lo, hi]: 0 when the bracket straddles it, the
 * geometric mean of a wide bracket, else the midpoint. */
static double tb__split(double lo, double hi)
{
    if (lo < 0.0 && hi > 0.0)
        return 0.0;
    if (tb__wide(lo, hi)) {
        double g = sqrt(fabs(lo)) * sqrt(fabs(hi));
        g = hi > 0.0 ? g : -g;
        if (g > lo && g < hi)
            return g;
    }
    return 0.5 * lo + 0.5 * hi;
}

/* Laguerre's step (cubically convergent, and for a polynomial with only
 * real roots convergent from anywhere, where Newton crawls by (n-1)/n per
 * step far from the roots); Newton's step when the square root would be of
 * a negative number (complex roots nearby). */
static inline double tb__laguerre_step(int n, tb__peval e)
{
    double inv = 1.0 / e.p, g = e.dp * inv, h = g * g - e.ddp * inv;
    double rad = (double)(n - 1) * ((double)n * h - g * g);
    if (!(rad >= 0.0) || !isfinite(g) || !isfinite(h))
        return e.p / e.dp;
    double sq = sqrt(rad), den = g + copysign(sq, g);
    return den != 0.0 ? (double)n / den : e.p / e.dp;
}

static inline __attribute__((always_inline)) double tb__bracketed_impl(const double *a, int n, double lo, double hi,
                                                                      int slo, double x)
{
    if (!(x > lo && x < hi))
        x = tb__split(lo, hi);
    /* The Laguerre/Newton step is taken only while it stays inside the
     * bracket and shrinks fast enough (Numerical Recipes' rtsafe rule);
     * otherwise bisect. Near a multiple root the steps shrink slowly and
     * bisection takes over. */
    double dx_old = hi - lo, dx = dx_old;
    double best = x, best_abs = INFINITY;
    for (int it = 0; it < 400; ++it) {
        tb__peval e = tb__eval_quick_impl(a, n, x);
        double ap = fabs(e.p);
        if (ap < best_abs) {
            best_abs = ap;
            best = x;
        }
        if (ap <= tb__poly_band(n, e.abs))
            return x; /* p(x) is 0 to within its rounding error */
        if ((e.p > 0.0) == (slo > 0))
            lo = x;
        else
            hi = x;
        double step = tb__laguerre_step(n, e);
        double xn = x - step;
        if (xn == x)
            return x; /* the step is below half an ulp */
        if (!(xn > lo && xn < hi) || !(fabs(2.0 * step) <= fabs(dx_old)) || tb__wide(lo, hi)) {
            xn = tb__split(lo, hi);
            if (!(xn > lo && xn < hi))
                return best; /* lo and hi are adjacent doubles */
        }
        dx_old = dx;
        dx = xn - x;
        x = xn;
    }
    return best;
}

double tb__poly_bracketed(const double *a, int n, double lo, double hi, int slo, double x)
{
    /* The torus's quartic and its derivative cubic: constant degrees. */
    if (n == 4)
        return tb__bracketed_impl(a, 4, lo, hi, slo, x);
    if (n == 3)
        return tb__bracketed_impl(a, 3, lo, hi, slo, x);
    return tb__bracketed_impl(a, n, lo, hi, slo, x);
}

double tb_poly_polish(const double *coef, int degree, double x, double lo, double hi)
{
    if (!coef || degree < 1 || degree > TB_POLY_MAX_DEGREE || isnan(x))
        return x;
    for (int i = 0; i <= degree; ++i)
        if (!isfinite(coef[i]))
            return x;
    if (isnan(lo))
        lo = -INFINITY;
    if (isnan(hi))
        hi = INFINITY;
    if (lo > hi)
        return x;
    x = fmin(fmax(x, lo), hi);
    tb__peval e = tb__poly_eval(coef, degree, x);
    if (!isfinite(e.p) || e.p == 0.0)
        return x;
    double ax = fabs(e.p);

    /* A sign-change bracket guarantees convergence: use the safe hybrid. */
    if (isfinite(lo) && isfinite(hi) && lo < hi) {
        double plo = tb__poly_eval_quick(coef, degree, lo).p;
        double phi = tb__poly_eval_quick(coef, degree, hi).p;
        if (isfinite(plo) && isfinite(phi) && ((plo < 0.0 && phi > 0.0) || (plo > 0.0 && phi < 0.0))) {
            double y = tb__poly_bracketed(coef, degree, lo, hi, plo > 0.0 ? 1 : -1, x);
            return fabs(tb__poly_eval(coef, degree, y).p) <= ax ? y : x;
        }
    }

    /* No bracket: accept a Newton step (halved up to 8 times) only when it
     * lowers |p|, so the result is never worse than the start. */
    for (int it = 0; it < 100; ++it) {
        if (e.dp == 0.0 || !isfinite(e.dp))
            break;
        double step = e.p / e.dp, lambda = 1.0;
        int accepted = 0;
        for (int k = 0; k < 8 && !accepted; ++k, lambda *= 0.5) {
            double xn = fmin(fmax(x - lambda * step, lo), hi);
            if (xn == x)
                break;
            tb__peval en = tb__poly_eval(coef, degree, xn);
            if (fabs(en.p) < ax) {
                x = xn;
                e = en;
                ax = fabs(en.p);
                accepted = 1;
            }
        }
        if (!accepted || ax == 0.0)
            break;
    }
    return x;
}
