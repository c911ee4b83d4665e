/* Summary statistics for studies over random seeds (docs/study.md): the mean,
 * sample standard deviation and 95% confidence interval of the mean
 * (Student's t), least-squares lines on log-log data (convergence rates),
 * and piecewise log-log interpolation (equal-time and equal-error tables).
 *
 *     tb_summary s = tb_summarize(relmse, nseeds);   // s.mean +- s.ci95
 *     tb_line_fit f;
 *     if (tb_fit_loglog(spp, relmse, n, &f) == TB_OK) printf("slope %g\n", f.slope);
 *
 * Non-finite values are skipped everywhere (counted out of n). */
#ifndef TB_UTIL_STATS_SUMMARY_H
#define TB_UTIL_STATS_SUMMARY_H

#include "util/base/error.h"

/* The mean and spread of a sample. */
typedef struct tb_summary {
    int n;           /* finite values used */
    double mean;     /* arithmetic mean; NaN when n = 0 */
    double sd;       /* sample standard deviation (n - 1 in the denominator); NaN when n < 2 */
    double ci95;     /* half-width of the 95% confidence interval of the mean, t(0.975, n-1) sd / sqrt(n); NaN when n < 2 */
    double min, max; /* NaN when n = 0 */
} tb_summary;

/* A least-squares line y = slope x + intercept. */
typedef struct tb_line_fit {
    int n;            /* points used */
    double slope, intercept;
    double slope_se;  /* standard error of the slope; NaN when n < 3 */
    double r2;        /* coefficient of determination; NaN when y is constant */
} tb_line_fit;

/* The 0.975 quantile of Student's t distribution with df degrees of freedom
 * (df >= 1; a table to 30, then the Cornish-Fisher expansion); NaN for df < 1. */
double tb_student_t975(int df);

/* Mean, standard deviation, 95% CI half-width, min and max of the finite values of x[0 .. n). */
tb_summary tb_summarize(const double *x, int n);

/* Fits y = slope x + intercept over the points where both are finite.
 * TB_ERR_ARG when fewer than two such points or all x equal. */
tb_status tb_fit_line(const double *x, const double *y, int n, tb_line_fit *out);

/* Fits log10 y = slope log10 x + intercept over the points where both are
 * finite and positive (a power law y = 10^intercept x^slope). TB_ERR_ARG as
 * tb_fit_line. */
tb_status tb_fit_loglog(const double *x, const double *y, int n, tb_line_fit *out);

/* Along the polyline (x[i], y[i]), i = 0 .. n-1 in the given order, straight
 * in log-log: the x where y first reaches y_target (a segment whose ends
 * bracket it, inclusive). NaN when no segment does or a point used is not
 * positive and finite. */
double tb_loglog_x_at(const double *x, const double *y, int n, double y_target);

/* Along the same polyline: the y at the first segment whose x ends bracket
 * x_target, log-log linear. NaN when none does. */
double tb_loglog_y_at(const double *x, const double *y, int n, double x_target);

#endif
