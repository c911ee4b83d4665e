/* util/stats/summary: mean, standard deviation and 95% confidence interval
 * against hand-computed values, Student's t against published quantiles,
 * line fits on exact and noisy power laws, log-log interpolation. */
#include "tb_test.h"

#include "util/stats/summary.h"

static void test_summary_known_values(void **state)
{
    (void)state;
    /* 2, 4, 4, 4, 5, 5, 7, 9: mean 5, sum of squares 32, sd sqrt(32/7) */
    const double x[] = {2, 4, 4, 4, 5, 5, 7, 9, NAN, INFINITY};
    tb_summary s = tb_summarize(x, 10);
    assert_int_equal(s.n, 8);
    tb_assert_near(s.mean, 5.0, 1e-15);
    tb_assert_near(s.sd, sqrt(32.0 / 7.0), 1e-14);
    tb_assert_near(s.ci95, 2.3646 * sqrt(32.0 / 7.0) / sqrt(8.0), 1e-12);
    tb_assert_near(s.min, 2, 0);
    tb_assert_near(s.max, 9, 0);
    tb_summary one = tb_summarize(x, 1);
    assert_int_equal(one.n, 1);
    tb_assert_near(one.mean, 2, 0);
    assert_true(isnan(one.sd) && isnan(one.ci95));
    tb_summary none = tb_summarize(x + 8, 2);
    assert_int_equal(none.n, 0);
    assert_true(isnan(none.mean) && isnan(none.min));
}

static void test_student_t(void **state)
{
    (void)state;
    tb_assert_near(tb_student_t975(1), 12.7062, 1e-4);
    tb_assert_near(tb_student_t975(4), 2.7764, 1e-4);
    tb_assert_near(tb_student_t975(30), 2.0423, 1e-4);
    /* published: t(0.975, 40) = 2.0211, 60: 2.0003, 120: 1.9799 */
    tb_assert_near(tb_student_t975(40), 2.0211, 2e-4);
    tb_assert_near(tb_student_t975(60), 2.0003, 2e-4);
    tb_assert_near(tb_student_t975(120), 1.9799, 2e-4);
    assert_true(tb_student_t975(1000000) > 1.95996 && tb_student_t975(1000000) < 1.9601);
    assert_true(isnan(tb_student_t975(0)));
    for (int df = 1; df < 200; df++) /* decreasing towards the normal quantile */
        assert_true(tb_student_t975(df + 1) < tb_student_t975(df));
}

static void test_fits(void **state)
{
    (void)state;
    /* y = 3 x^-1 exactly: slope -1, intercept log10 3, r2 1 */
    double x[6] = {1, 2, 4, 8, 16, -1}, y[6];
    for (int i = 0; i < 5; i++)
        y[i] = 3 / x[i];
    y[5] = 5; /* x <= 0: left out of the log-log fit */
    tb_line_fit f;
    assert_int_equal(tb_fit_loglog(x, y, 6, &f), TB_OK);
    assert_int_equal(f.n, 5);
    tb_assert_near(f.slope, -1, 1e-12);
    tb_assert_near(f.intercept, log10(3.0), 1e-12);
    tb_assert_near(f.r2, 1, 1e-12);
    tb_assert_near(f.slope_se, 0, 1e-6);
    /* y = 2x + 1 with residuals +-0.5 alternating around it at x = 0..3 */
    const double lx[] = {0, 1, 2, 3}, ly[] = {1.5, 2.5, 5.5, 6.5};
    assert_int_equal(tb_fit_line(lx, ly, 4, &f), TB_OK);
    /* by hand: mean x 1.5, mean y 4, sum dx dy = 9, sum dx^2 = 5: slope 1.8 */
    tb_assert_near(f.slope, 1.8, 1e-12);
    tb_assert_near(f.intercept, 4 - 1.8 * 1.5, 1e-12);
    assert_true(f.r2 > 0.9 && f.r2 < 1);
    /* too few points, or one x */
    assert_int_equal(tb_fit_line(lx, ly, 1, &f), TB_ERR_ARG);
    const double same[] = {2, 2, 2};
    assert_int_equal(tb_fit_line(same, ly, 3, &f), TB_ERR_ARG);
}

static void test_loglog_interpolation(void **state)
{
    (void)state;
    /* time 1, 2, 4 s; error 0.1, 0.05, 0.025: error = 0.1 / t */
    const double t[] = {1, 2, 4}, e[] = {0.1, 0.05, 0.025};
    tb_assert_near(tb_loglog_x_at(t, e, 3, 0.04), 2.5, 1e-12);
    tb_assert_near(tb_loglog_x_at(t, e, 3, 0.1), 1, 1e-12);
    assert_true(isnan(tb_loglog_x_at(t, e, 3, 0.01)));  /* never reached */
    assert_true(isnan(tb_loglog_x_at(t, e, 3, 0.2)));   /* above the first point */
    tb_assert_near(tb_loglog_y_at(t, e, 3, 3), 0.1 / 3, 1e-12);
    tb_assert_near(tb_loglog_y_at(t, e, 3, 4), 0.025, 1e-12);
    assert_true(isnan(tb_loglog_y_at(t, e, 3, 8)));
    assert_true(isnan(tb_loglog_y_at(t, e, 3, 0)));
    /* a curve that rises again: the first crossing counts */
    const double t2[] = {1, 2, 4, 8}, e2[] = {1, 0.25, 1, 0.0625};
    tb_assert_near(tb_loglog_x_at(t2, e2, 4, 0.5), sqrt(2.0), 1e-12);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_summary_known_values),
        cmocka_unit_test(test_student_t),
        cmocka_unit_test(test_fits),
        cmocka_unit_test(test_loglog_interpolation),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
