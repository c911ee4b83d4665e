/* Summary statistics over seeds, line fits and log-log interpolation (summary.h). */
#include "util/stats/summary.h"

#include <math.h>

/* t(0.975, df) for df = 1 .. 30. */
static const double tb__t975[30] = {
    12.7062, 4.3027, 3.1824, 2.7764, 2.5706, 2.4469, 2.3646, 2.3060, 2.2622, 2.2281,
    2.2010,  2.1788, 2.1604, 2.1448, 2.1314, 2.1199, 2.1098, 2.1009, 2.0930, 2.0860,
    2.0796,  2.0739, 2.0687, 2.0639, 2.0595, 2.0555, 2.0518, 2.0484, 2.0452, 2.0423,
};

double tb_student_t975(int df)
{
    if (df < 1)
        return NAN;
    if (df <= 30)
        return tb__t975[df - 1];
    /* Cornish-Fisher expansion about the normal quantile (Abramowitz & Stegun 26.7.5) */
    const double z = 1.959963984540054, z3 = z * z * z, z5 = z3 * z * z, z7 = z5 * z * z, v = df;
    return z + (z3 + z) / (4 * v) + (5 * z5 + 16 * z3 + 3 * z) / (96 * v * v) +
           (3 * z7 + 19 * z5 + 17 * z3 - 15 * z) / (384 * v * v * v);
}

tb_summary tb_summarize(const double *x, int n)
{
    tb_summary s = {0, NAN, NAN, NAN, NAN, NAN};
    double sum = 0;
    for (int i = 0; i < n; i++) {
        if (!isfinite(x[i]))
            continue;
        if (s.n == 0 || x[i] < s.min)
            s.min = x[i];
        if (s.n == 0 || x[i] > s.max)
            s.max = x[i];
        sum += x[i];
        s.n++;
    }
    if (s.n == 0)
        return s;
    s.mean = sum / s.n;
    if (s.n < 2)
        return s;
    double ss = 0;
    for (int i = 0; i < n; i++)
        if (isfinite(x[i]))
            ss += (x[i] - s.mean) * (x[i] - s.mean);
    s.sd = sqrt(ss / (s.n - 1));
    s.ci95 = tb_student_t975(s.n - 1) * s.sd / sqrt((double)s.n);
    return s;
}

/* The least-squares line over the finite points (logs: the positive ones, in log10). */
static tb_status tb__fit(const double *x, const double *y, int n, int logs, tb_line_fit *out)
{
    double sx = 0, sy = 0;
    int m = 0;
    for (int pass = 0; pass < 2; pass++) {
        double sxx = 0, sxy = 0, syy = 0;
        for (int i = 0; i < n; i++) {
            double a = x[i], b = y[i];
            if (!isfinite(a) || !isfinite(b) || (logs && (a <= 0 || b <= 0)))
                continue;
            if (logs)
                a = log10(a), b = log10(b);
            if (pass == 0) {
                sx += a, sy += b, m++;
                continue;
            }
            double dx = a - sx, dy = b - sy;
            sxx += dx * dx, sxy += dx * dy, syy += dy * dy;
        }
        if (pass == 0) {
            if (m < 2)
                return tb_error(TB_ERR_ARG, "a line fit needs two points, got %d", m);
            sx /= m, sy /= m; /* the means */
            continue;
        }
        if (!(sxx > 0))
            return tb_error(TB_ERR_ARG, "a line fit needs two different x values");
        out->n = m;
        out->slope = sxy / sxx;
        out->intercept = sy - out->slope * sx;
        double sse = syy - out->slope * sxy;
        if (sse < 0)
            sse = 0;
        out->r2 = syy > 0 ? 1 - sse / syy : NAN;
        out->slope_se = m > 2 ? sqrt(sse / (m - 2) / sxx) : NAN;
    }
    return TB_OK;
}

tb_status tb_fit_line(const double *x, const double *y, int n, tb_line_fit *out)
{
    return tb__fit(x, y, n, 0, out);
}

tb_status tb_fit_loglog(const double *x, const double *y, int n, tb_line_fit *out)
{
    return tb__fit(x, y, n, 1, out);
}

/* Positive and finite: a point a log-log polyline can use. */
static int tb__pos(double v)
{
    return isfinite(v) && v > 0;
}

/* Log-log linear interpolation of the value v at u between (u0, v0) and (u1, v1). */
static double tb__lerp_log(double u0, double v0, double u1, double v1, double u)
{
    double lu0 = log(u0), lu1 = log(u1);
    if (lu1 == lu0)
        return sqrt(v0 * v1); /* a vertical or degenerate segment: the geometric mean */
    double t = (log(u) - lu0) / (lu1 - lu0);
    return exp(log(v0) + t * (log(v1) - log(v0)));
}

double tb_loglog_x_at(const double *x, const double *y, int n, double y_target)
{
    if (!tb__pos(y_target))
        return NAN;
    for (int i = 0; i + 1 < n; i++) {
        if (!tb__pos(x[i]) || !tb__pos(y[i]) || !tb__pos(x[i + 1]) || !tb__pos(y[i + 1]))
            continue;
        double lo = fmin(y[i], y[i + 1]), hi = fmax(y[i], y[i + 1]);
        if (y_target < lo || y_target > hi)
            continue;
        return tb__lerp_log(y[i], x[i], y[i + 1], x[i + 1], y_target);
    }
    if (n == 1 && tb__pos(x[0]) && y[0] == y_target)
        return x[0];
    return NAN;
}

double tb_loglog_y_at(const double *x, const double *y, int n, double x_target)
{
    if (!tb__pos(x_target))
        return NAN;
    for (int i = 0; i + 1 < n; i++) {
        if (!tb__pos(x[i]) || !tb__pos(y[i]) || !tb__pos(x[i + 1]) || !tb__pos(y[i + 1]))
            continue;
        double lo = fmin(x[i], x[i + 1]), hi = fmax(x[i], x[i + 1]);
        if (x_target < lo || x_target > hi)
            continue;
        return tb__lerp_log(x[i], y[i], x[i + 1], y[i + 1], x_target);
    }
    if (n == 1 && tb__pos(y[0]) && x[0] == x_target)
        return y[0];
    return NAN;
}
