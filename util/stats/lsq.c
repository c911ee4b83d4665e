/* Least squares through the normal equations of unit-norm columns with a
 * tiny ridge (util/stats/lsq.h); NNLS after Lawson & Hanson, "Solving
 * Least Squares Problems" (1974), ch. 23, on the same Gram matrix. Cost
 * models have a handful of columns and tens of rows, so the Gram matrix is
 * small and the conditioning is handled by the scaling and the ridge. */
#include "util/stats/lsq.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#define TB__LSQ_MAX_COLS 256

/* Solves (G + ridge I) restricted to the columns with in[j] for s (others 0),
 * by Cholesky; false if it is not positive definite (cannot happen with a
 * positive ridge and finite G, but checked). */
static bool tb__lsq_solve(const double *G, const double *g, int n, const bool *in, double ridge, double *s,
                          double *work)
{
    int idx[TB__LSQ_MAX_COLS], k = 0;
    for (int j = 0; j < n; j++) {
        s[j] = 0.0;
        if (in[j])
            idx[k++] = j;
    }
    double *L = work, *y = work + (size_t)k * (size_t)k;
    for (int a = 0; a < k; a++)
        for (int c = 0; c <= a; c++) {
            double v = G[idx[a] * n + idx[c]] + (a == c ? ridge : 0.0);
            for (int t = 0; t < c; t++)
                v -= L[a * k + t] * L[c * k + t];
            if (a == c) {
                if (!(v > 0.0))
                    return false;
                L[a * k + a] = sqrt(v);
            } else {
                L[a * k + c] = v / L[c * k + c];
            }
        }
    for (int a = 0; a < k; a++) { /* L y = g */
        double v = g[idx[a]];
        for (int t = 0; t < a; t++)
            v -= L[a * k + t] * y[t];
        y[a] = v / L[a * k + a];
    }
    for (int a = k - 1; a >= 0; a--) { /* L^T s = y */
        double v = y[a];
        for (int t = a + 1; t < k; t++)
            v -= L[t * k + a] * s[idx[t]];
        s[idx[a]] = v / L[a * k + a];
    }
    return true;
}

tb_status tb_lsq_fit(const double *A, const double *b, const double *w, int m, int n, unsigned flags, double *x,
                     tb_lsq_info *info)
{
    if (!A || !b || !x || m < 1 || n < 1 || n > TB__LSQ_MAX_COLS)
        return tb_error(TB_ERR_ARG, "least squares: need m >= 1 rows, 1 <= n <= %d columns and arrays (m %d, n %d)",
                        TB__LSQ_MAX_COLS, m, n);
    size_t nn = (size_t)n;
    double *G = calloc(nn * nn + 4 * nn + nn * nn + nn, sizeof *G);
    bool *use = calloc((size_t)m, sizeof *use);
    if (!G || !use) {
        free(G);
        free(use);
        return tb_error(TB_ERR_NOMEM, "least squares: out of memory");
    }
    double *g = G + nn * nn, *scale = g + nn, *z = scale + nn, *s = z + nn, *work = s + nn;
    int rows = 0;
    for (int i = 0; i < m; i++) {
        double wi = w ? w[i] : 1.0;
        bool ok = isfinite(wi) && wi > 0.0 && isfinite(b[i]);
        for (int j = 0; ok && j < n; j++)
            ok = isfinite(A[(size_t)i * nn + (size_t)j]);
        use[i] = ok;
        rows += ok;
    }
    if (!rows) {
        free(G);
        free(use);
        return tb_error(TB_ERR_ARG, "least squares: no row with finite values and a positive weight");
    }
    /* column norms of the weighted matrix (scaled to avoid overflow) */
    for (int j = 0; j < n; j++) {
        double mx = 0.0;
        for (int i = 0; i < m; i++)
            if (use[i])
                mx = fmax(mx, fabs((w ? w[i] : 1.0) * A[(size_t)i * nn + (size_t)j]));
        double ss = 0.0;
        if (mx > 0.0 && isfinite(mx))
            for (int i = 0; i < m; i++)
                if (use[i]) {
                    double v = (w ? w[i] : 1.0) * A[(size_t)i * nn + (size_t)j] / mx;
                    ss += v * v;
                }
        scale[j] = mx > 0.0 && isfinite(mx) ? mx * sqrt(ss) : 0.0;
    }
    double bmax = 0.0;
    for (int i = 0; i < m; i++)
        if (use[i])
            bmax = fmax(bmax, fabs((w ? w[i] : 1.0) * b[i]));
    double bscale = bmax > 0.0 && isfinite(bmax) ? bmax : 1.0;
    for (int i = 0; i < m; i++) {
        if (!use[i])
            continue;
        double wi = w ? w[i] : 1.0, bi = wi * b[i] / bscale;
        for (int j = 0; j < n; j++) {
            if (scale[j] == 0.0)
                continue;
            double aj = wi * A[(size_t)i * nn + (size_t)j] / scale[j];
            g[j] += aj * bi;
            for (int k = 0; k <= j; k++)
                if (scale[k] != 0.0)
                    G[j * n + k] += aj * wi * A[(size_t)i * nn + (size_t)k] / scale[k];
        }
    }
    double trace = 0.0;
    for (int j = 0; j < n; j++) {
        for (int k = 0; k < j; k++)
            G[k * n + j] = G[j * n + k];
        trace += G[j * n + j];
    }
    double ridge = 1e-12 * (trace > 0.0 ? trace : 1.0);
    bool in[TB__LSQ_MAX_COLS], ok = true;
    int iterations = 0;
    if (!(flags & TB_LSQ_NONNEG)) {
        for (int j = 0; j < n; j++)
            in[j] = scale[j] != 0.0;
        ok = tb__lsq_solve(G, g, n, in, ridge, z, work);
    } else {
        /* Lawson-Hanson: grow the passive set by the steepest descent direction */
        memset(in, 0, sizeof in);
        double gmax = 0.0;
        for (int j = 0; j < n; j++)
            gmax = fmax(gmax, fabs(g[j]));
        double tol = 1e-12 * (gmax > 0.0 ? gmax : 1.0);
        for (iterations = 0; ok && iterations < 3 * n + 10; iterations++) {
            int best = -1;
            double bestv = tol;
            for (int j = 0; j < n; j++) {
                if (in[j] || scale[j] == 0.0)
                    continue;
                double grad = g[j] - ridge * z[j];
                for (int k = 0; k < n; k++)
                    grad -= G[j * n + k] * z[k];
                if (grad > bestv)
                    bestv = grad, best = j;
            }
            if (best < 0)
                break;
            in[best] = true;
            for (int inner = 0; inner < 3 * n + 10; inner++) {
                if (!(ok = tb__lsq_solve(G, g, n, in, ridge, s, work)))
                    break;
                double alpha = 2.0;
                for (int j = 0; j < n; j++)
                    if (in[j] && s[j] <= 0.0) {
                        double a = z[j] / (z[j] - s[j]);
                        if (a < alpha)
                            alpha = a;
                    }
                if (alpha > 1.0) { /* all positive: accept */
                    memcpy(z, s, nn * sizeof *z);
                    break;
                }
                for (int j = 0; j < n; j++) {
                    z[j] += alpha * (s[j] - z[j]);
                    if (in[j] && z[j] <= 1e-15 * fabs(s[j]) + 1e-300)
                        in[j] = false, z[j] = 0.0;
                }
            }
        }
    }
    int active = 0;
    for (int j = 0; j < n; j++) {
        x[j] = ok && scale[j] != 0.0 && isfinite(z[j]) ? z[j] * bscale / scale[j] : 0.0;
        if (!isfinite(x[j]))
            x[j] = 0.0;
        active += x[j] != 0.0;
    }
    if (info) {
        double rss = 0.0;
        for (int i = 0; i < m; i++) {
            if (!use[i])
                continue;
            double r = -b[i];
            for (int j = 0; j < n; j++)
                r += A[(size_t)i * nn + (size_t)j] * x[j];
            r *= w ? w[i] : 1.0;
            rss += r * r;
        }
        info->rows = rows;
        info->active = active;
        info->rms = sqrt(rss / rows);
        info->iterations = iterations;
    }
    free(G);
    free(use);
    if (!ok)
        return tb_error(TB_ERR_ARG, "least squares: the normal equations are not positive definite");
    return TB_OK;
}
