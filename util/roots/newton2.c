/* Damped Newton's method for two equations in two unknowns.
 *
 * Each step solves J d = -F by Cramer's rule (determinant and numerators by
 * Kahan's difference of products, so nearly parallel rows keep their digits)
 * and backtracks along d until |F|^2 drops by Armijo's sufficient-decrease
 * rule (Dennis and Schnabel, "Numerical Methods for Unconstrained
 * Optimization and Nonlinear Equations", 6.3). Far from a root this keeps
 * the iteration from diverging; near one the full step is always accepted
 * and convergence is quadratic. */
#include "util/roots/roots.h"

#include <math.h>

#include "util/math/float.h"

/* Calls fn and checks that what it wrote is finite; 0 on success. */
static int tb__newton2_call(tb_newton2_fn fn, void *user, double u, double v, double f[2], double jac[4])
{
    if (fn(user, u, v, f, jac) != 0)
        return -1;
    for (int i = 0; i < 2; ++i)
        if (!isfinite(f[i]))
            return -1;
    for (int i = 0; i < 4; ++i)
        if (!isfinite(jac[i]))
            return -1;
    return 0;
}

static double tb__maxabs2(const double f[2]) { return fmax(fabs(f[0]), fabs(f[1])); }

/* |f|^2 computed relative to `scale` so that huge residuals do not overflow. */
static double tb__norm2_scaled(const double f[2], double scale)
{
    double a = f[0] / scale, b = f[1] / scale;
    return a * a + b * b;
}

tb_status tb_newton2(tb_newton2_fn fn, void *user, double u0, double v0,
                     const tb_newton2_opts *opts, tb_newton2_result *out)
{
    tb_newton2_result res = {u0, v0, INFINITY, 0};
    if (out)
        *out = res;
    if (!fn || !out)
        return tb_error(TB_ERR_ARG, "tb_newton2: NULL %s", fn ? "result" : "callback");
    if (!isfinite(u0) || !isfinite(v0))
        return tb_error(TB_ERR_ARG, "tb_newton2: start (%g, %g) is not finite", u0, v0);
    /* F's scale is the caller's, so by default only the step (relative to
     * (u, v)) decides; once it is below xtol, the step taken leaves an error
     * of order xtol^2 (quadratic convergence). */
    double ftol = opts && opts->ftol > 0.0 ? opts->ftol : 0.0;
    double xtol = opts && opts->xtol > 0.0 ? opts->xtol : 1e-14;
    int max_iter = opts && opts->max_iter > 0 ? opts->max_iter : 50;

    double f[2], jac[4];
    if (tb__newton2_call(fn, user, u0, v0, f, jac) != 0)
        return tb_error(TB_ERR_ARG, "tb_newton2: F or its Jacobian is undefined at the start (%g, %g)", u0, v0);
    double u = u0, v = v0;
    res.residual = tb__maxabs2(f);
    *out = res;

    for (int it = 0;; ++it) {
        if (res.residual <= ftol)
            return TB_OK;
        if (it >= max_iter)
            return tb_error(TB_ERR_NUMERIC, "tb_newton2: no convergence after %d iterations (|F| = %.3g at (%.17g, %.17g))",
                            max_iter, res.residual, u, v);

        /* det relative to |J00 J11| + |J01 J10| is invariant to scaling rows
         * and columns; below 2^-50 the step would carry no correct digits. */
        double det = tb_diff_of_products(jac[0], jac[3], jac[1], jac[2]);
        double scale = fabs(jac[0] * jac[3]) + fabs(jac[1] * jac[2]);
        if (!(fabs(det) > 0x1p-50 * scale))
            return tb_error(TB_ERR_NUMERIC, "tb_newton2: singular Jacobian at (%.17g, %.17g) (det = %.3g)", u, v, det);
        double du = -tb_diff_of_products(jac[3], f[0], jac[1], f[1]) / det;
        double dv = -tb_diff_of_products(jac[0], f[1], jac[2], f[0]) / det;
        if (!isfinite(du) || !isfinite(dv))
            return tb_error(TB_ERR_NUMERIC, "tb_newton2: Newton step overflows at (%.17g, %.17g)", u, v);
        int tiny_step = hypot(du, dv) <= xtol * (1.0 + hypot(u, v));

        /* Backtracking: |F(x + l d)|^2 <= (1 - 2 alpha l) |F(x)|^2, alpha = 1e-4. */
        double s0 = tb__norm2_scaled(f, res.residual); /* in (0, 2] */
        double lambda = 1.0, fn_[2], jn[4], un = u, vn = v;
        int accepted = 0;
        for (int k = 0; k < 40 && !accepted; ++k, lambda *= 0.5) {
            un = u + lambda * du;
            vn = v + lambda * dv;
            if (tb__newton2_call(fn, user, un, vn, fn_, jn) != 0)
                continue;
            if (tiny_step || tb__norm2_scaled(fn_, res.residual) <= (1.0 - 2e-4 * lambda) * s0)
                accepted = 1;
        }
        if (!accepted)
            return tb_error(TB_ERR_NUMERIC, "tb_newton2: no decrease of |F| along the Newton step at (%.17g, %.17g) (|F| = %.3g)",
                            u, v, res.residual);
        u = un;
        v = vn;
        f[0] = fn_[0];
        f[1] = fn_[1];
        for (int i = 0; i < 4; ++i)
            jac[i] = jn[i];
        res.u = u;
        res.v = v;
        res.residual = tb__maxabs2(f);
        res.iterations = it + 1;
        *out = res;
        if (tiny_step)
            return TB_OK; /* the full step is below xtol: at the root to that precision */
    }
}
