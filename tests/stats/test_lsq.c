/* util/stats/lsq: least squares and NNLS recover known coefficients from
 * synthetic data, including badly scaled, collinear and zero columns,
 * non-finite rows and the non-negativity constraint. */
#include "tb_test.h"

#include <math.h>

#include "util/stats/lsq.h"
#include "util/math/rng.h"

/* y = A x_true exactly over m rows of random features with scales spanning 1e-3 .. 1e9. */
static void test_lsq_exact_recovery(void **state)
{
    (void)state;
    enum { M = 40, N = 5 };
    const double truth[N] = {2e-9, 3.5e-7, 0.25, 4e-3, 1.5};
    const double col_scale[N] = {1e9, 1e6, 1.0, 1e2, 1e-3};
    double A[M * N], b[M], x[N];
    tb_rng rng;
    tb_rng_seed(&rng, 7, 0);
    for (int i = 0; i < M; i++) {
        b[i] = 0.0;
        for (int j = 0; j < N; j++) {
            A[i * N + j] = col_scale[j] * (0.1 + tb_rng_double(&rng));
            b[i] += A[i * N + j] * truth[j];
        }
    }
    tb_lsq_info info;
    assert_int_equal(tb_lsq_fit(A, b, NULL, M, N, 0, x, &info), TB_OK);
    for (int j = 0; j < N; j++)
        tb_assert_near(x[j] / truth[j], 1.0, 1e-6);
    assert_int_equal(info.rows, M);
    assert_true(info.rms < 1e-6);
    assert_int_equal(tb_lsq_fit(A, b, NULL, M, N, TB_LSQ_NONNEG, x, &info), TB_OK);
    for (int j = 0; j < N; j++)
        tb_assert_near(x[j] / truth[j], 1.0, 1e-6);
    /* relative weights (1/y, as the cost fits use) give the same exact answer */
    double w[M];
    for (int i = 0; i < M; i++)
        w[i] = 1.0 / b[i];
    assert_int_equal(tb_lsq_fit(A, b, w, M, N, TB_LSQ_NONNEG, x, NULL), TB_OK);
    for (int j = 0; j < N; j++)
        tb_assert_near(x[j] / truth[j], 1.0, 1e-6);
}

/* Noisy data: the estimate is near the truth (and the known noise level shows in rms). */
static void test_lsq_noisy(void **state)
{
    (void)state;
    enum { M = 400, N = 3 };
    const double truth[N] = {1.0, -2.0, 0.5};
    double A[M * N], b[M], x[N];
    tb_rng rng;
    tb_rng_seed(&rng, 11, 0);
    for (int i = 0; i < M; i++) {
        b[i] = 0.0;
        for (int j = 0; j < N; j++) {
            A[i * N + j] = 2.0 * tb_rng_double(&rng) - 1.0;
            b[i] += A[i * N + j] * truth[j];
        }
        b[i] += 0.01 * (2.0 * tb_rng_double(&rng) - 1.0); /* uniform noise, sd 0.01/sqrt(3) */
    }
    tb_lsq_info info;
    assert_int_equal(tb_lsq_fit(A, b, NULL, M, N, 0, x, &info), TB_OK);
    for (int j = 0; j < N; j++)
        tb_assert_near(x[j], truth[j], 3e-3);
    tb_assert_near(info.rms, 0.01 / sqrt(3.0), 1.5e-3);
}

/* NNLS: a negative unconstrained answer is clamped to 0 and the rest refit;
 * against the solution worked out by hand. */
static void test_lsq_nonneg(void **state)
{
    (void)state;
    /* b = 1*c0 - 1*c1 where c1 is orthogonal to c0: NNLS gives x0 = 1, x1 = 0 */
    const double A[] = {1, 0, 0, 1, 1, 0, 0, 1};
    const double b[] = {1, -1, 1, -1};
    double x[2];
    tb_lsq_info info;
    assert_int_equal(tb_lsq_fit(A, b, NULL, 4, 2, 0, x, NULL), TB_OK);
    tb_assert_near(x[0], 1.0, 1e-8);
    tb_assert_near(x[1], -1.0, 1e-8);
    assert_int_equal(tb_lsq_fit(A, b, NULL, 4, 2, TB_LSQ_NONNEG, x, &info), TB_OK);
    tb_assert_near(x[0], 1.0, 1e-8);
    assert_true(x[1] == 0.0);
    assert_int_equal(info.active, 1);
    tb_assert_near(info.rms, 1.0 / sqrt(2.0), 1e-8);
    /* correlated columns where the unconstrained answer goes negative:
     * rows (1, 1), (1, 2), b (3, 2.5): LS gives x = (3.5, -0.5); NNLS with
     * only column 0 gives x0 = (3 + 2.5) / 2 = 2.75, column 1 alone 8/5 = 1.6
     * with a larger residual, so (2.75, 0) */
    const double A2[] = {1, 1, 1, 2}, b2[] = {3, 2.5};
    assert_int_equal(tb_lsq_fit(A2, b2, NULL, 2, 2, 0, x, NULL), TB_OK);
    tb_assert_near(x[0], 3.5, 1e-6);
    tb_assert_near(x[1], -0.5, 1e-6);
    assert_int_equal(tb_lsq_fit(A2, b2, NULL, 2, 2, TB_LSQ_NONNEG, x, NULL), TB_OK);
    tb_assert_near(x[0], 2.75, 1e-8);
    assert_true(x[1] == 0.0);
}

/* Collinear, duplicated and zero columns: finite coefficients, the fit still exact. */
static void test_lsq_collinear(void **state)
{
    (void)state;
    enum { M = 20, N = 4 };
    double A[M * N], b[M], x[N];
    for (int i = 0; i < M; i++) {
        double t = 1.0 + i;
        A[i * N + 0] = t;
        A[i * N + 1] = 2.0 * t; /* exactly collinear with column 0 */
        A[i * N + 2] = 0.0;     /* never varies: no information */
        A[i * N + 3] = 1.0;
        b[i] = 5.0 * t + 3.0;
    }
    for (unsigned flags = 0; flags <= TB_LSQ_NONNEG; flags += TB_LSQ_NONNEG) {
        tb_lsq_info info;
        assert_int_equal(tb_lsq_fit(A, b, NULL, M, N, flags, x, &info), TB_OK);
        for (int j = 0; j < N; j++)
            assert_true(isfinite(x[j]));
        assert_true(x[2] == 0.0);
        tb_assert_near(x[0] + 2.0 * x[1], 5.0, 1e-6); /* the combination is determined */
        tb_assert_near(x[3], 3.0, 1e-5);
        assert_true(info.rms < 1e-5);
        if (flags)
            assert_true(x[0] >= 0.0 && x[1] >= 0.0);
    }
    /* more columns than rows: still finite, still fits */
    const double A3[] = {1, 2, 3, 4, 5, 6}, b3[] = {1, 2};
    assert_int_equal(tb_lsq_fit(A3, b3, NULL, 2, 3, 0, x, NULL), TB_OK);
    for (int j = 0; j < 3; j++)
        assert_true(isfinite(x[j]));
    tb_assert_near(x[0] + 2 * x[1] + 3 * x[2], 1.0, 1e-6);
    tb_assert_near(4 * x[0] + 5 * x[1] + 6 * x[2], 2.0, 1e-6);
}

/* Rows with NaN, infinities or zero weight are left out; bad arguments refused. */
static void test_lsq_bad_rows_and_args(void **state)
{
    (void)state;
    const double A[] = {1, NAN, 2, INFINITY, 4, 5};
    const double b[] = {2, 4, 4, 8, NAN, 10};
    const double w[] = {1, 1, 1, 1, 1, 0};
    double x[1];
    tb_lsq_info info;
    assert_int_equal(tb_lsq_fit(A, b, w, 6, 1, TB_LSQ_NONNEG, x, &info), TB_OK);
    assert_int_equal(info.rows, 2); /* rows 0 and 2 */
    tb_assert_near(x[0], 2.0, 1e-8);
    assert_int_equal(tb_lsq_fit(A, b, w, 0, 1, 0, x, NULL), TB_ERR_ARG);
    assert_int_equal(tb_lsq_fit(A, b, w, 6, 0, 0, x, NULL), TB_ERR_ARG);
    assert_int_equal(tb_lsq_fit(NULL, b, w, 6, 1, 0, x, NULL), TB_ERR_ARG);
    const double nanrow[] = {NAN}, one[] = {1};
    assert_int_equal(tb_lsq_fit(nanrow, one, NULL, 1, 1, 0, x, NULL), TB_ERR_ARG);
    /* all-zero data: x = 0, no NaN */
    const double zero[] = {0, 0, 0, 0};
    double x2[2];
    assert_int_equal(tb_lsq_fit(zero, zero, NULL, 2, 2, TB_LSQ_NONNEG, x2, NULL), TB_OK);
    assert_true(x2[0] == 0.0 && x2[1] == 0.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lsq_exact_recovery),
        cmocka_unit_test(test_lsq_noisy),
        cmocka_unit_test(test_lsq_nonneg),
        cmocka_unit_test(test_lsq_collinear),
        cmocka_unit_test(test_lsq_bad_rows_and_args),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
