#include "util/color/spectrum.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

tb_status tb_spectrum_check(int n, const double *lambda, const double *value)
{
    if (n < 2)
        return tb_error(TB_ERR_ARG, "spectrum: %d samples, need at least 2", n);
    if (!lambda)
        return tb_error(TB_ERR_ARG, "spectrum: no wavelengths given");
    for (int i = 0; i < n; i++) {
        if (!isfinite(lambda[i]) || !(lambda[i] > 0.0))
            return tb_error(TB_ERR_ARG, "spectrum: wavelength %d is %g nm (must be finite and > 0)",
                            i, lambda[i]);
        if (i > 0 && !(lambda[i] > lambda[i - 1]))
            return tb_error(TB_ERR_ARG,
                            "spectrum: wavelength %d (%g nm) is not greater than wavelength %d (%g nm)",
                            i, lambda[i], i - 1, lambda[i - 1]);
        if (value && !isfinite(value[i]))
            return tb_error(TB_ERR_ARG, "spectrum: value %d (at %g nm) is not finite (%g)", i,
                            lambda[i], value[i]);
    }
    return TB_OK;
}

/* Allocates one block holding n wavelengths then n values; the caller fills them. */
static tb_status tb__spectrum_alloc(tb_spectrum *out, int n, double **lambda, double **value)
{
    double *mem = malloc(2 * (size_t)n * sizeof *mem);
    if (!mem)
        return tb_error(TB_ERR_NOMEM, "spectrum: no memory for %d samples", n);
    *lambda = mem;
    *value = mem + n;
    out->n = n;
    out->lambda = mem;
    out->value = mem + n;
    out->storage = mem;
    return TB_OK;
}

tb_status tb_spectrum_init(tb_spectrum *out, int n, const double *lambda, const double *value)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "spectrum: no output given");
    memset(out, 0, sizeof *out);
    if (!value)
        return tb_error(TB_ERR_ARG, "spectrum: no values given");
    tb_status st = tb_spectrum_check(n, lambda, value);
    if (st)
        return st;
    double *l = NULL, *v = NULL;
    if ((st = tb__spectrum_alloc(out, n, &l, &v)))
        return st;
    memcpy(l, lambda, (size_t)n * sizeof *l);
    memcpy(v, value, (size_t)n * sizeof *v);
    return TB_OK;
}

tb_status tb_spectrum_init_constant(tb_spectrum *out, double lambda_min, double lambda_max,
                                    double value)
{
    const double l[2] = {lambda_min, lambda_max}, v[2] = {value, value};
    return tb_spectrum_init(out, 2, l, v);
}

void tb_spectrum_release(tb_spectrum *s)
{
    if (!s)
        return;
    free(s->storage);
    memset(s, 0, sizeof *s);
}

/* Index i of the segment [lambda[i], lambda[i+1]] holding x, for x inside the
 * range (the last segment for x at the upper end). */
static int tb__segment(const tb_spectrum *s, double x)
{
    int lo = 0, hi = s->n - 1; /* invariant: lambda[lo] <= x < lambda[hi] or hi = n-1 */
    while (hi - lo > 1) {
        int mid = lo + (hi - lo) / 2;
        if (s->lambda[mid] <= x)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* The linear piece of segment i at x; exact at both ends of the segment. */
static double tb__on_segment(const tb_spectrum *s, int i, double x)
{
    double t = (x - s->lambda[i]) / (s->lambda[i + 1] - s->lambda[i]);
    return (1.0 - t) * s->value[i] + t * s->value[i + 1];
}

double tb_spectrum_eval(const tb_spectrum *s, double lambda)
{
    if (isnan(lambda))
        return lambda;
    if (lambda < s->lambda[0] || lambda > s->lambda[s->n - 1])
        return 0.0;
    return tb__on_segment(s, tb__segment(s, lambda), lambda);
}

/* Integral of the product of k piecewise-linear factors (k <= 3) over the range
 * where all are defined: Simpson's rule on each interval between merged
 * breakpoints, exact because the integrand there is a polynomial of degree k. */
static double tb__product_integral(const tb_spectrum *const *f, int k, double lo, double hi)
{
    for (int j = 0; j < k; j++) {
        if (f[j]->lambda[0] > lo)
            lo = f[j]->lambda[0];
        if (f[j]->lambda[f[j]->n - 1] < hi)
            hi = f[j]->lambda[f[j]->n - 1];
    }
    if (!(lo < hi))
        return 0.0;
    int seg[3];
    for (int j = 0; j < k; j++)
        seg[j] = tb__segment(f[j], lo);
    double sum = 0.0, p = lo;
    while (p < hi) {
        double q = hi;
        for (int j = 0; j < k; j++)
            if (f[j]->lambda[seg[j] + 1] < q)
                q = f[j]->lambda[seg[j] + 1];
        double m = 0.5 * (p + q), fp = 1.0, fm = 1.0, fq = 1.0;
        for (int j = 0; j < k; j++) {
            fp *= tb__on_segment(f[j], seg[j], p);
            fm *= tb__on_segment(f[j], seg[j], m);
            fq *= tb__on_segment(f[j], seg[j], q);
        }
        sum += (q - p) / 6.0 * (fp + 4.0 * fm + fq);
        p = q;
        for (int j = 0; j < k; j++)
            while (seg[j] + 2 < f[j]->n && f[j]->lambda[seg[j] + 1] <= p)
                seg[j]++;
    }
    return sum;
}

double tb_spectrum_integral(const tb_spectrum *s, double lo, double hi)
{
    if (hi < lo)
        return -tb_spectrum_integral(s, hi, lo);
    const tb_spectrum *f[1] = {s};
    return tb__product_integral(f, 1, lo, hi);
}

double tb_spectrum_product_integral(const tb_spectrum *a, const tb_spectrum *b,
                                    const tb_spectrum *c)
{
    const tb_spectrum *f[3] = {a, b, c};
    return tb__product_integral(f, c ? 3 : 2, -INFINITY, INFINITY);
}

/* Integral over [a, b] of s times the linear ramp from ra (at a) to rb (at b). */
static double tb__ramp_integral(const tb_spectrum *s, double a, double b, double ra, double rb)
{
    const double l[2] = {a, b}, v[2] = {ra, rb};
    const tb_spectrum ramp = {2, l, v, NULL};
    const tb_spectrum *f[2] = {s, &ramp};
    return tb__product_integral(f, 2, a, b);
}

/* True if s is one linear function on [a, b]: no sample strictly inside, and
 * not straddling (or touching from outside) an end of s, where it jumps to 0. */
static int tb__linear_on(const tb_spectrum *s, double a, double b)
{
    double lo = s->lambda[0], hi = s->lambda[s->n - 1];
    if (b < lo || a > hi)
        return 1; /* wholly in the zero region */
    if (a < lo || b > hi)
        return 0;
    int i = tb__segment(s, a); /* lambda[i] <= a < lambda[i+1], or a at the upper end */
    return !(i + 1 < s->n && s->lambda[i + 1] < b);
}

tb_status tb_spectrum_resample_values(const tb_spectrum *s, int n, const double *lambda,
                                      double *out_values)
{
    if (!s || !out_values)
        return tb_error(TB_ERR_ARG, "spectrum resample: no spectrum or output given");
    tb_status st = tb_spectrum_check(n, lambda, NULL);
    if (st)
        return tb_error_context(st, "spectrum resample: target");
    for (int j = 0; j < n; j++) {
        int left = j > 0 && tb__linear_on(s, lambda[j - 1], lambda[j]);
        int right = j + 1 < n && tb__linear_on(s, lambda[j], lambda[j + 1]);
        if ((j == 0 || left) && (j + 1 == n || right)) {
            out_values[j] = tb_spectrum_eval(s, lambda[j]); /* refinement: exact */
            continue;
        }
        /* Each half of the hat adds its share of the integral: the trapezoid share
         * h/2 * s(l[j]) where s is linear on it (so that it pairs exactly with the
         * neighbour's share), else the hat-weighted integral. Either way the shares
         * of one interval add up to the integral of s over it, and are >= 0 if s is. */
        double num = 0.0, den = 0.0, here = tb_spectrum_eval(s, lambda[j]);
        if (j > 0) {
            double h = lambda[j] - lambda[j - 1];
            num += left ? 0.5 * h * here : tb__ramp_integral(s, lambda[j - 1], lambda[j], 0.0, 1.0);
            den += 0.5 * h;
        }
        if (j + 1 < n) {
            double h = lambda[j + 1] - lambda[j];
            num += right ? 0.5 * h * here : tb__ramp_integral(s, lambda[j], lambda[j + 1], 1.0, 0.0);
            den += 0.5 * h;
        }
        out_values[j] = num / den;
    }
    return TB_OK;
}

tb_status tb_spectrum_resample(const tb_spectrum *s, int n, const double *lambda,
                               tb_spectrum *out)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "spectrum resample: no output given");
    memset(out, 0, sizeof *out);
    if (!s)
        return tb_error(TB_ERR_ARG, "spectrum resample: no spectrum given");
    tb_status st = tb_spectrum_check(n, lambda, NULL);
    if (st)
        return tb_error_context(st, "spectrum resample: target");
    double *l = NULL, *v = NULL;
    if ((st = tb__spectrum_alloc(out, n, &l, &v)))
        return st;
    memcpy(l, lambda, (size_t)n * sizeof *l);
    if ((st = tb_spectrum_resample_values(s, n, lambda, v)))
        tb_spectrum_release(out);
    return st;
}

tb_status tb_spectrum_scale(const tb_spectrum *s, double k, tb_spectrum *out)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "spectrum scale: no output given");
    memset(out, 0, sizeof *out);
    if (!s)
        return tb_error(TB_ERR_ARG, "spectrum scale: no spectrum given");
    if (!isfinite(k))
        return tb_error(TB_ERR_ARG, "spectrum scale: factor %g is not finite", k);
    double *l = NULL, *v = NULL;
    tb_status st = tb__spectrum_alloc(out, s->n, &l, &v);
    if (st)
        return st;
    for (int i = 0; i < s->n; i++) {
        l[i] = s->lambda[i];
        v[i] = k * s->value[i];
    }
    return TB_OK;
}

tb_status tb_spectrum_multiply(const tb_spectrum *a, const tb_spectrum *b, tb_spectrum *out)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "spectrum multiply: no output given");
    memset(out, 0, sizeof *out);
    if (!a || !b)
        return tb_error(TB_ERR_ARG, "spectrum multiply: no spectrum given");
    double lo = fmax(a->lambda[0], b->lambda[0]);
    double hi = fmin(a->lambda[a->n - 1], b->lambda[b->n - 1]);
    if (!(lo < hi))
        return tb_spectrum_init_constant(out, a->lambda[0], a->lambda[a->n - 1], 0.0);
    double *l = NULL, *v = NULL;
    tb_status st = tb__spectrum_alloc(out, a->n + b->n, &l, &v);
    if (st)
        return st;
    /* Merge the two sample sets inside [lo, hi]. */
    int i = 0, j = 0, m = 0;
    while (i < a->n || j < b->n) {
        double x;
        if (j >= b->n || (i < a->n && a->lambda[i] < b->lambda[j]))
            x = a->lambda[i++];
        else if (i >= a->n || b->lambda[j] < a->lambda[i])
            x = b->lambda[j++];
        else {
            x = a->lambda[i++];
            j++;
        }
        if (x < lo || x > hi)
            continue;
        l[m] = x;
        v[m] = tb_spectrum_eval(a, x) * tb_spectrum_eval(b, x);
        m++;
    }
    out->n = m; /* >= 2: lo and hi are both samples */
    return TB_OK;
}
