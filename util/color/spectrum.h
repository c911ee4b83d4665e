/* Sampled spectra. A spectrum is a function of wavelength given by values at
 * strictly increasing wavelengths (nm, any spacing). Between samples it is
 * LINEAR; outside [first, last] sample it is ZERO (the Cornell Box convention:
 * data measured over 400-700 nm says nothing, and contributes nothing, outside
 * that range). Every integral below is exact for that piecewise-linear function;
 * see docs/color.md for the rules and the quadrature. */
#ifndef TB_UTIL_COLOR_SPECTRUM_H
#define TB_UTIL_COLOR_SPECTRUM_H

#include <stddef.h>

#include "util/base/error.h"

/* A sampled spectrum. Treat as read-only; built-in tables (CIE, D65) are shared. */
typedef struct tb_spectrum {
    int n;                /* number of samples, >= 2 */
    const double *lambda; /* n wavelengths in nm, finite, > 0, strictly increasing */
    const double *value;  /* n finite values at those wavelengths */
    void *storage;        /* memory freed by tb_spectrum_release(); NULL for built-in tables */
} tb_spectrum;

/* Checks a sample set: n >= 2, wavelengths finite, > 0 and strictly increasing,
 * values (if `value` is not NULL) finite. TB_ERR_ARG with a message naming the
 * first bad sample otherwise. */
tb_status tb_spectrum_check(int n, const double *lambda, const double *value);

/* Copies n samples into a new spectrum `*out` (validated as tb_spectrum_check).
 * On error `*out` is zeroed. Free with tb_spectrum_release(). */
tb_status tb_spectrum_init(tb_spectrum *out, int n, const double *lambda, const double *value);

/* A constant spectrum `value` over [lambda_min, lambda_max] (two samples). */
tb_status tb_spectrum_init_constant(tb_spectrum *out, double lambda_min, double lambda_max,
                                    double value);

/* Frees what tb_spectrum_init*() (or any function filling a tb_spectrum) allocated
 * and zeroes `*s`; harmless on a zeroed struct and on built-in tables' copies. */
void tb_spectrum_release(tb_spectrum *s);

/* Value at `lambda` nm: linear interpolation between samples, the sample value
 * at a sample (including both ends), 0 outside [lambda[0], lambda[n-1]]; NaN for NaN. */
double tb_spectrum_eval(const tb_spectrum *s, double lambda);

/* Exact integral over [lo, hi] nm of the piecewise-linear function (zero outside
 * its samples); negative if hi < lo. */
double tb_spectrum_integral(const tb_spectrum *s, double lo, double hi);

/* Exact integral of a(l) * b(l) * c(l) dl over all wavelengths, `c` may be NULL
 * (then of a*b). Each factor is piecewise linear, so on every interval between
 * the merged breakpoints the integrand is a polynomial of degree <= 3, which
 * Simpson's rule integrates exactly. */
double tb_spectrum_product_integral(const tb_spectrum *a, const tb_spectrum *b,
                                    const tb_spectrum *c);

/* Resamples `s` onto the n wavelengths `lambda` (checked as tb_spectrum_check),
 * writing n values, so that the integral over [lambda[0], lambda[n-1]] is kept
 * exactly, values stay >= 0 if s is, and refinement is exact. The new value j is
 * its share of the integral divided by its trapezoid weight (l[j+1]-l[j-1])/2,
 * the share adding, for each half [l[j-1], l[j]] and [l[j], l[j+1]]:
 *  - where s is linear on the half (no sample of s strictly inside, no jump at an
 *    end of s): the trapezoid share, half length times s(l[j]). If both halves
 *    are so, the value is s(l[j]): up-sampling keeps coincident samples exactly;
 *  - otherwise: the integral of s times the hat function of the new sample set
 *    on that half, i.e. down-sampling averages s over each new bin.
 * The first and last samples have one half each. See docs/color.md. */
tb_status tb_spectrum_resample_values(const tb_spectrum *s, int n, const double *lambda,
                                      double *out_values);

/* tb_spectrum_resample_values() into a new spectrum `*out` on those wavelengths. */
tb_status tb_spectrum_resample(const tb_spectrum *s, int n, const double *lambda,
                               tb_spectrum *out);

/* `*out` = k * s, on the samples of s. k must be finite. */
tb_status tb_spectrum_scale(const tb_spectrum *s, double k, tb_spectrum *out);

/* `*out` = a * b sampled at every sample of either inside the range where both are
 * defined (the product of two linear pieces is quadratic, so it is exact at the
 * samples and linear between them). Disjoint ranges give a zero spectrum over a's range. */
tb_status tb_spectrum_multiply(const tb_spectrum *a, const tb_spectrum *b, tb_spectrum *out);

#endif
