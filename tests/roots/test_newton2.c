/* util/roots tb_newton2: systems with known solutions, damping where plain
 * Newton diverges, domain exits, and each failure report. */
#include "tb_test.h"

#include <string.h>

#include "util/roots/roots.h"

/* u^2 + v^2 = 4 and u = v: solution (sqrt 2, sqrt 2) from u, v > 0. */
static int circle_line(void *user, double u, double v, double f[2], double j[4])
{
    (void)user;
    f[0] = u * u + v * v - 4.0;
    f[1] = u - v;
    j[0] = 2.0 * u;
    j[1] = 2.0 * v;
    j[2] = 1.0;
    j[3] = -1.0;
    return 0;
}

static void test_circle_line(void **state)
{
    (void)state;
    tb_newton2_result res;
    assert_int_equal(tb_newton2(circle_line, NULL, 1.0, 0.5, NULL, &res), TB_OK);
    tb_assert_near(res.u, sqrt(2.0), 4e-16);
    tb_assert_near(res.v, sqrt(2.0), 4e-16);
    assert_true(res.residual <= 1e-12);
    assert_true(res.iterations >= 3 && res.iterations <= 7); /* quadratic convergence */
    print_message("[ measured ] circle/line from (1, 0.5): %d iterations\n", res.iterations);

    /* A start that already meets the tolerance takes no step. */
    assert_int_equal(tb_newton2(circle_line, NULL, 1.0, 1.0, &(tb_newton2_opts){.ftol = 3.0}, &res), TB_OK);
    assert_int_equal(res.iterations, 0);
}

/* atan(u) = 0, v = 0: from |u| > 1.39 plain Newton overshoots further each
 * step (u -> u - atan(u)(1 + u^2)); only the backtracking brings it in. */
static int atan_system(void *user, double u, double v, double f[2], double j[4])
{
    int *calls = user;
    ++*calls;
    f[0] = atan(u);
    f[1] = v;
    j[0] = 1.0 / (1.0 + u * u);
    j[1] = 0.0;
    j[2] = 0.0;
    j[3] = 1.0;
    return 0;
}

static void test_damping(void **state)
{
    (void)state;
    int calls = 0;
    tb_newton2_result res;
    assert_int_equal(tb_newton2(atan_system, &calls, 10.0, -3.0, NULL, &res), TB_OK);
    tb_assert_near(res.u, 0.0, 1e-12);
    tb_assert_near(res.v, 0.0, 1e-12);
    assert_true(calls > res.iterations + 1); /* some steps were shortened */
}

/* A bilinear patch P(u, v) in the plane; solving P(u, v) = target inverts it. */
typedef struct patch {
    double p[4][2]; /* corners P00, P10, P01, P11 */
    double target[2];
} patch;

static void patch_eval(const patch *pt, double u, double v, double out[2])
{
    for (int k = 0; k < 2; ++k)
        out[k] = (1 - u) * (1 - v) * pt->p[0][k] + u * (1 - v) * pt->p[1][k] + (1 - u) * v * pt->p[2][k] +
                 u * v * pt->p[3][k];
}

static int patch_system(void *user, double u, double v, double f[2], double j[4])
{
    const patch *pt = user;
    double q[2];
    patch_eval(pt, u, v, q);
    for (int k = 0; k < 2; ++k) {
        f[k] = q[k] - pt->target[k];
        j[2 * k] = (1 - v) * (pt->p[1][k] - pt->p[0][k]) + v * (pt->p[3][k] - pt->p[2][k]);
        j[2 * k + 1] = (1 - u) * (pt->p[2][k] - pt->p[0][k]) + u * (pt->p[3][k] - pt->p[1][k]);
    }
    return 0;
}

static void test_patch_inversion(void **state)
{
    (void)state;
    patch pt = {{{0, 0}, {4, 0.5}, {-0.5, 3}, {5, 4}}, {0, 0}};
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("patch_inversion", 0xb11e7u), 7);
    double worst = 0.0;
    int max_it = 0;
    for (int t = 0; t < 2000; ++t) {
        double u = tb_rng_double(&rng), v = tb_rng_double(&rng);
        patch_eval(&pt, u, v, pt.target);
        tb_newton2_result res;
        assert_int_equal(tb_newton2(patch_system, &pt, 0.5, 0.5, NULL, &res), TB_OK);
        worst = fmax(worst, fmax(fabs(res.u - u), fabs(res.v - v)));
        if (res.iterations > max_it)
            max_it = res.iterations;
    }
    print_message("[ measured ] bilinear patch inversion: worst |(u,v) error| %.3g, at most %d iterations\n", worst,
                  max_it);
    assert_true(worst <= 2e-15);
}

/* log(u) = 1, v = 2, defined for u > 0 only: from u = 10 the first full step
 * lands at u = -3, where the callback refuses, and is shortened. */
static int log_system(void *user, double u, double v, double f[2], double j[4])
{
    (void)user;
    if (!(u > 0.0))
        return -1;
    f[0] = log(u) - 1.0;
    f[1] = v - 2.0;
    j[0] = 1.0 / u;
    j[1] = 0.0;
    j[2] = 0.0;
    j[3] = 1.0;
    return 0;
}

static void test_domain_exit(void **state)
{
    (void)state;
    tb_newton2_result res;
    assert_int_equal(tb_newton2(log_system, NULL, 10.0, 0.0, NULL, &res), TB_OK);
    tb_assert_near(res.u, exp(1.0), 1e-15);
    tb_assert_near(res.v, 2.0, 1e-14);
    /* A start outside the domain is the caller's error. */
    assert_int_equal(tb_newton2(log_system, NULL, -1.0, 0.0, NULL, &res), TB_ERR_ARG);
    assert_non_null(strstr(tb_last_error(), "undefined at the start"));
}

/* Parallel lines u + v = 1, 2u + 2v = 3: singular Jacobian everywhere. */
static int parallel_lines(void *user, double u, double v, double f[2], double j[4])
{
    (void)user;
    f[0] = u + v - 1.0;
    f[1] = 2.0 * u + 2.0 * v - 3.0;
    j[0] = 1.0;
    j[1] = 1.0;
    j[2] = 2.0;
    j[3] = 2.0;
    return 0;
}

/* u^2 + 1 = 0: no real solution; |F| is least at u = 0, where J is singular. */
static int no_root(void *user, double u, double v, double f[2], double j[4])
{
    (void)user;
    f[0] = u * u + 1.0;
    f[1] = v;
    j[0] = 2.0 * u;
    j[1] = 0.0;
    j[2] = 0.0;
    j[3] = 1.0;
    return 0;
}

static void test_failures(void **state)
{
    (void)state;
    tb_newton2_result res;
    assert_int_equal(tb_newton2(parallel_lines, NULL, 0.0, 0.0, NULL, &res), TB_ERR_NUMERIC);
    assert_non_null(strstr(tb_last_error(), "singular Jacobian"));

    /* Not enough iterations: reported, with the best point so far. */
    tb_newton2_opts few = {.max_iter = 2};
    assert_int_equal(tb_newton2(circle_line, NULL, 30.0, 1.0, &few, &res), TB_ERR_NUMERIC);
    assert_non_null(strstr(tb_last_error(), "no convergence after 2 iterations"));
    assert_int_equal(res.iterations, 2);
    assert_true(res.residual > 1e-12 && isfinite(res.u) && isfinite(res.v));

    /* No solution: must fail (singular or stalled), never claim success. */
    for (double u0 = 0.3; u0 < 5.0; u0 += 0.7) {
        assert_int_equal(tb_newton2(no_root, NULL, u0, 1.0, NULL, &res), TB_ERR_NUMERIC);
        assert_true(res.residual >= 1.0);
    }

    /* Bad arguments. */
    assert_int_equal(tb_newton2(NULL, NULL, 0.0, 0.0, NULL, &res), TB_ERR_ARG);
    assert_int_equal(tb_newton2(circle_line, NULL, 0.0, 0.0, NULL, NULL), TB_ERR_ARG);
    assert_int_equal(tb_newton2(circle_line, NULL, NAN, 0.0, NULL, &res), TB_ERR_ARG);
    assert_int_equal(tb_newton2(circle_line, NULL, 1.0, INFINITY, NULL, &res), TB_ERR_ARG);
}

/* Tolerances from the options are honoured: a loose ftol stops early. */
static void test_options(void **state)
{
    (void)state;
    tb_newton2_result loose, tight;
    tb_newton2_opts o = {.ftol = 1e-2};
    assert_int_equal(tb_newton2(circle_line, NULL, 3.0, 0.5, &o, &loose), TB_OK);
    assert_int_equal(tb_newton2(circle_line, NULL, 3.0, 0.5, NULL, &tight), TB_OK);
    assert_true(loose.residual <= 1e-2);
    assert_true(loose.iterations < tight.iterations);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_circle_line),   cmocka_unit_test(test_damping),
        cmocka_unit_test(test_patch_inversion), cmocka_unit_test(test_domain_exit),
        cmocka_unit_test(test_failures),      cmocka_unit_test(test_options),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
