/* Linear least squares for cost models (docs/predict.md): min |W (A x - b)|
 * over x, optionally with x >= 0 (Lawson & Hanson's NNLS), robust to
 * collinear and badly scaled columns.
 *
 *     double x[3];
 *     if (tb_lsq_fit(A, b, NULL, m, 3, TB_LSQ_NONNEG, x, NULL)) die(tb_last_error());
 *
 * A is row-major, m rows by n columns. Columns are scaled to unit norm
 * before solving and a tiny ridge term (1e-12 of the scaled Gram matrix's
 * trace) keeps the normal equations positive definite, so exactly
 * collinear columns share their weight instead of producing NaN or
 * infinities; a column of zeros gets coefficient 0. */
#ifndef TB_UTIL_STATS_LSQ_H
#define TB_UTIL_STATS_LSQ_H

#include "util/base/error.h"

/* Flags of tb_lsq_fit. */
enum {
    TB_LSQ_NONNEG = 1u << 0, /* every coefficient >= 0 (NNLS) */
};

/* What a fit achieved. */
typedef struct tb_lsq_info {
    int rows;          /* rows used (finite A row, finite b, finite positive weight) */
    int active;        /* coefficients not held at zero */
    double rms;        /* root mean square of the weighted residuals */
    int iterations;    /* NNLS outer iterations (0 without TB_LSQ_NONNEG) */
} tb_lsq_info;

/* Fits x[0 .. n) to minimise sum_i w[i]^2 (A[i] . x - b[i])^2 (w NULL: all
 * 1). Rows with a non-finite entry or weight <= 0 are skipped. Fewer usable
 * rows than columns is allowed (the ridge term picks the smallest-norm
 * answer in scaled units). TB_ERR_ARG for m < 1, n < 1, n > 256, NULL
 * arrays or no usable row; TB_ERR_NOMEM. x is finite on success. */
tb_status tb_lsq_fit(const double *A, const double *b, const double *w, int m, int n, unsigned flags, double *x,
                     tb_lsq_info *info);

#endif
