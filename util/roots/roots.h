/* Real roots of polynomials of degree <= 4 and a bivariate Newton solver.
 *
 * Used by the object level: quadratics for spheres, cylinders, cones and
 * conics, the quartic for the torus, and tb_newton2 for inverting parametric
 * patches. See docs/roots.md for the methods and their measured accuracy.
 *
 * Conventions shared by every root finder here:
 *  - real roots are written to r[] in ascending order and their number is
 *    returned; a root of multiplicity m that is resolved as such is written
 *    m times (a tangent ray gives two equal hits, so in/out parity holds);
 *  - any NaN or infinite coefficient gives 0 roots; no root is ever NaN or
 *    infinite (a root that overflows is dropped);
 *  - coefficient arrays run from the highest power down:
 *    coef[0] x^n + coef[1] x^(n-1) + ... + coef[n]. */
#ifndef TB_UTIL_ROOTS_ROOTS_H
#define TB_UTIL_ROOTS_ROOTS_H

#include <math.h>

#include "util/base/error.h"
#include "util/math/float.h"

/* Highest degree tb_poly_roots() accepts. */
#define TB_POLY_MAX_DEGREE 4

/* tb_quadratic's general path (quadratic.c): every coefficient case, with
 * the rescaling for extreme magnitudes. Private; call tb_quadratic. */
int tb__quadratic_general(double a, double b, double c, double r[2]);

/* The solve both paths end with (quadratic.c explains it): a, c != 0 and
 * every coefficient within 2^+-480, the roots scaled by 2^k (the general
 * path's substitution x = 2^k y; 0 in the common case). Private. */
static inline int tb__quadratic_solve(double a, double b, double c, int k, double r[2])
{
    double disc = tb_diff_of_products(b, b, 4.0 * a, c);
    if (disc < 0.0)
        return 0;
    double q = -0.5 * (b + copysign(sqrt(disc), b));
    double x0 = q / a, x1 = c / q; /* q != 0: c != 0 */
    if (x0 > x1) {
        double t = x0;
        x0 = x1;
        x1 = t;
    }
    if (k != 0) {
        x0 = ldexp(x0, k);
        x1 = ldexp(x1, k);
    }
    int n = 0;
    if (isfinite(x0))
        r[n++] = x0;
    if (isfinite(x1))
        r[n++] = x1;
    return n;
}

/* Real roots of a x^2 + b x + c = 0 (0, 1 or 2; a == 0 solves the linear equation).
 * Inline for the common case, every nonzero coefficient within 2^+-480 with
 * a, c != 0 (a ray against a quadric: about a million calls per frame), where
 * the general path would take no early exit and no rescaling: the same
 * operations, so the same roots bit for bit; anything else goes there. */
static inline int tb_quadratic(double a, double b, double c, double r[2])
{
    const double lo = 0x1p-480, hi = 0x1p480;
    double fa = fabs(a), fb = fabs(b), fc = fabs(c);
    /* NaN and infinities fail these comparisons, so they go the general way. */
    if (!(fa >= lo && fa <= hi && fc >= lo && fc <= hi && (b == 0.0 || (fb >= lo && fb <= hi))))
        return tb__quadratic_general(a, b, c, r);
    return tb__quadratic_solve(a, b, c, 0, r);
}

/* tb_quadratic() in float arithmetic (same method, fmaf() for the discriminant). */
int tb_quadraticf(float a, float b, float c, float r[2]);

/* Real roots of a x^3 + b x^2 + c x + d = 0 (a negligible or zero lowers the degree). */
int tb_cubic(double a, double b, double c, double d, double r[3]);

/* Real roots of a x^4 + b x^3 + c x^2 + d x + e = 0 (a negligible or zero lowers the degree). */
int tb_quartic(double a, double b, double c, double d, double e, double r[4]);

/* Real roots of the polynomial coef[0..degree]; degree outside [0, TB_POLY_MAX_DEGREE] gives 0. */
int tb_poly_roots(const double *coef, int degree, double *r);

/* Value of the polynomial coef[0..degree] at x by compensated Horner (as if
 * evaluated in twice the precision, then rounded); *deriv (if not NULL) gets p'(x). */
double tb_poly_eval(const double *coef, int degree, double x, double *deriv);

/* Refines an approximate root x of coef[0..degree] by Newton's method kept
 * inside [lo, hi] (pass -INFINITY, INFINITY for no bound; x is clamped into
 * it). When p(lo) and p(hi) differ in sign, steps leaving the bracket become
 * bisections and the result is within about 1 ulp of the bracketed root.
 * The returned value never has a larger |p| than x (clamped) had. */
double tb_poly_polish(const double *coef, int degree, double x, double lo, double hi);

/* Callback for tb_newton2: writes F(u, v) to f[0..1] and its Jacobian to
 * jac[0..3] row by row (jac[0] = dF0/du, jac[1] = dF0/dv, jac[2] = dF1/du,
 * jac[3] = dF1/dv). Returns 0, or nonzero when (u, v) is outside its domain. */
typedef int (*tb_newton2_fn)(void *user, double u, double v, double f[2], double jac[4]);

/* Settings of tb_newton2; zero fields take the defaults given beside them. */
typedef struct tb_newton2_opts {
    double ftol;  /* converged when max(|F0|, |F1|) <= ftol; default 0 (exact zeros only) */
    double xtol;  /* ... or when the full Newton step is <= xtol * (1 + |(u,v)|); default 1e-14 */
    int max_iter; /* Newton iterations allowed; default 50 */
} tb_newton2_opts;

/* What tb_newton2 found: the best point it reached, also on failure. */
typedef struct tb_newton2_result {
    double u, v;     /* last accepted iterate */
    double residual; /* max(|F0|, |F1|) at (u, v) */
    int iterations;  /* Newton steps taken */
} tb_newton2_result;

/* Solves F(u, v) = 0 by damped Newton (backtracking on |F|^2) from (u0, v0).
 * TB_ERR_NUMERIC on a singular Jacobian, a failed line search or no
 * convergence within max_iter; TB_ERR_ARG on NULL fn/out or a non-finite
 * start. `opts` may be NULL (all defaults). `out` is filled in every case. */
tb_status tb_newton2(tb_newton2_fn fn, void *user, double u0, double v0,
                     const tb_newton2_opts *opts, tb_newton2_result *out);

#endif
