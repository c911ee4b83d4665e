/* util/math/mat.h: products, transposes, determinants and inverses on
 * hand-worked matrices; the inverse identity M M^-1 = I on seeded random
 * matrices; singular and ill-conditioned matrices rejected with a message. */
#include "tb_test.h"

#include <float.h>
#include <math.h>
#include <string.h>

#include "util/base/error.h"
#include "util/math/mat.h"

static const double k_rows16[16] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16};

static void assert_mat4_eq(const tb_mat4 *a, const double want[16], double tol)
{
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            if (!(fabs(a->m[i][j] - want[i * 4 + j]) <= tol))
                fail_msg("m[%d][%d] = %.17g, want %.17g", i, j, a->m[i][j], want[i * 4 + j]);
}

static void test_mat3_hand(void **state)
{
    (void)state;
    /* A classic integer matrix with det 1 and an integer inverse. */
    tb_mat3 a = {{{1, 2, 3}, {0, 1, 4}, {5, 6, 0}}};
    assert_true(tb_mat3_det(&a) == 1.0);
    tb_mat3 inv;
    assert_int_equal(tb_mat3_inverse(&a, &inv), TB_OK);
    const double want[3][3] = {{-24, 18, 5}, {20, -15, -4}, {-5, 4, 1}};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            assert_true(inv.m[i][j] == want[i][j]);
    tb_mat3 p = tb_mat3_mul(&a, &inv), id = tb_mat3_identity();
    assert_memory_equal(&p, &id, sizeof p);
    tb_mat3 t = tb_mat3_transpose(&a);
    assert_true(t.m[0][2] == 5 && t.m[2][0] == 3 && t.m[1][2] == 6 && t.m[1][1] == 1);
    tb_dvec3 v = tb_mat3_mul_vec(&a, (tb_dvec3){1, -1, 2});
    assert_true(v.x == 5 && v.y == 7 && v.z == -1);
    /* In place (out aliases a). */
    assert_int_equal(tb_mat3_inverse(&a, &a), TB_OK);
    assert_true(a.m[0][0] == -24 && a.m[2][2] == 1);
}

static void test_mat4_hand(void **state)
{
    (void)state;
    tb_mat4 a = tb_mat4_from_rows(k_rows16);
    assert_true(a.m[1][2] == 7 && a.m[3][0] == 13);
    tb_mat4 at = tb_mat4_transpose(&a);
    assert_true(at.m[2][1] == 7 && at.m[0][3] == 13);
    /* A A^T: row dot products of 1..16, worked by hand. */
    tb_mat4 g = tb_mat4_mul(&a, &at);
    assert_true(g.m[0][0] == 30 && g.m[0][1] == 70 && g.m[1][0] == 70);
    assert_true(g.m[1][1] == 174 && g.m[3][3] == 846 && g.m[2][3] == 9 * 13 + 10 * 14 + 11 * 15 + 12 * 16);
    /* Rank 2: determinant exactly 0. */
    assert_true(tb_mat4_det(&a) == 0.0);
    /* Ones with -1 on the anti-diagonal: M M = 4 I, det -16 (eigenvalues 2, 2, 2, -2). */
    const double h[16] = {1, 1, 1, -1, 1, 1, -1, 1, 1, -1, 1, 1, -1, 1, 1, 1};
    tb_mat4 hm = tb_mat4_from_rows(h);
    assert_true(tb_mat4_det(&hm) == -16.0);
    tb_mat4 h2 = tb_mat4_mul(&hm, &hm);
    const double four[16] = {4, 0, 0, 0, 0, 4, 0, 0, 0, 0, 4, 0, 0, 0, 0, 4};
    assert_mat4_eq(&h2, four, 0.0);
    tb_mat4 hi;
    assert_int_equal(tb_mat4_inverse(&hm, &hi), TB_OK); /* general (projective) path */
    double quarter[16];
    for (int i = 0; i < 16; ++i)
        quarter[i] = h[i] / 4.0;
    assert_mat4_eq(&hi, quarter, 1e-16);
    /* Identity and its properties. */
    tb_mat4 id = tb_mat4_identity();
    assert_true(tb_mat4_det(&id) == 1.0);
    assert_true(tb_mat4_is_affine(&id));
    assert_false(tb_mat4_is_affine(&hm));
    tb_mat4 ai = tb_mat4_mul(&a, &id);
    assert_true(tb_mat4_equal(&ai, &a));
    /* a[i][j] - a[j][i] = 3 (i - j): largest at (3, 0), |13 - 4| = 9. */
    assert_true(tb_mat4_max_abs_diff(&a, &at) == 9.0);
}

static void test_mat4_affine_inverse_and_points(void **state)
{
    (void)state;
    /* Scale (2, 4, 8) then translate (1, 2, 3): inverse by hand. */
    const double m[16] = {2, 0, 0, 1, 0, 4, 0, 2, 0, 0, 8, 3, 0, 0, 0, 1};
    const double want[16] = {0.5, 0, 0, -0.5, 0, 0.25, 0, -0.5, 0, 0, 0.125, -0.375, 0, 0, 0, 1};
    tb_mat4 a = tb_mat4_from_rows(m), inv;
    assert_int_equal(tb_mat4_inverse(&a, &inv), TB_OK);
    assert_mat4_eq(&inv, want, 0.0);
    assert_true(tb_mat4_det(&a) == 64.0);
    tb_dvec3 p = tb_mat4_mul_point(&a, (tb_dvec3){1, 1, 1});
    assert_true(p.x == 3 && p.y == 6 && p.z == 11);
    tb_dvec3 v = tb_mat4_mul_vec(&a, (tb_dvec3){1, 1, 1});
    assert_true(v.x == 2 && v.y == 4 && v.z == 8);
    tb_mat3 l = tb_mat4_linear(&a);
    assert_true(l.m[0][0] == 2 && l.m[1][1] == 4 && l.m[2][2] == 8 && l.m[0][1] == 0);
    tb_mat4 back = tb_mat4_from_linear(&l, (tb_dvec3){1, 2, 3});
    assert_true(tb_mat4_equal(&back, &a));
    /* Projective: w = z, so (2, 4, 2) maps to (1, 2, 1). */
    const double proj[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0};
    tb_mat4 pm = tb_mat4_from_rows(proj);
    p = tb_mat4_mul_point(&pm, (tb_dvec3){2, 4, 2});
    assert_true(p.x == 1 && p.y == 2 && p.z == 1);
}

static void test_mat4f_layout(void **state)
{
    (void)state;
    tb_mat4 a = tb_mat4_from_rows(k_rows16);
    tb_mat4f f = tb_mat4_to_f(&a);
    /* Column-major: the first four floats are the first column. */
    assert_true(f.m[0] == 1 && f.m[1] == 5 && f.m[2] == 9 && f.m[3] == 13);
    assert_true(f.m[4] == 2 && f.m[12] == 4 && f.m[15] == 16);
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
            assert_true(tb_mat4f_at(&f, r, c) == (float)a.m[r][c]);
    tb_mat4 t = tb_mat4_identity();
    t.m[0][3] = 0.1; /* rounded to float once */
    f = tb_mat4_to_f(&t);
    assert_true(f.m[12] == 0.1f && tb_mat4f_at(&f, 0, 3) == 0.1f);
}

static void expect_numeric(const tb_mat4 *a, const char *what)
{
    tb_mat4 out = tb_mat4_identity();
    out.m[0][1] = 42.0; /* sentinel: must survive a failed inversion */
    tb_clear_error();
    tb_status st = tb_mat4_inverse(a, &out);
    if (st != TB_ERR_NUMERIC)
        fail_msg("%s: status %d (%s), want TB_ERR_NUMERIC", what, (int)st, tb_status_name(st));
    assert_true(out.m[0][1] == 42.0);
    const char *msg = tb_last_error();
    if (!strstr(msg, "singular"))
        fail_msg("%s: message '%s' does not say singular", what, msg);
    print_message("[ info     ] %s: %s\n", what, msg);
}

static void test_singular_and_ill_conditioned(void **state)
{
    (void)state;
    tb_mat4 z;
    memset(&z, 0, sizeof z);
    expect_numeric(&z, "zero matrix");
    tb_mat4 r2 = tb_mat4_from_rows(k_rows16);
    expect_numeric(&r2, "rank-2 matrix 1..16");
    /* Affine with a zero scale on y. */
    tb_mat4 s0 = tb_mat4_identity();
    s0.m[1][1] = 0.0;
    s0.m[0][3] = 5.0;
    expect_numeric(&s0, "scale (1, 0, 1)");
    /* Affine with a 1e-20 scale on x: invertible in exact arithmetic, but the
     * inverse would amplify by 1e20. */
    tb_mat4 s20 = tb_mat4_identity();
    s20.m[0][0] = 1e-20;
    expect_numeric(&s20, "scale (1e-20, 1, 1)");
    /* Rank-deficient affine: third row of the linear part = first + second. */
    const double rd[16] = {1, 2, 3, 0, 4, 5, 6, 0, 5, 7, 9, 0, 0, 0, 0, 1};
    tb_mat4 rdm = tb_mat4_from_rows(rd);
    expect_numeric(&rdm, "rank-deficient linear part");
    /* Nearly rank-deficient: perturbed by 1e-14 (rcond ~ 1e-15). */
    tb_mat4 near = rdm;
    near.m[2][2] += 1e-14;
    expect_numeric(&near, "near-singular linear part");
    /* General (projective) path: a nearly singular 4x4. */
    tb_mat4 hp = tb_mat4_from_rows(k_rows16);
    hp.m[3][3] += 1e-13;
    expect_numeric(&hp, "near-singular projective");
    /* 3x3 directly. */
    tb_mat3 m3 = {{{1, 2, 3}, {2, 4, 6}, {0, 0, 1}}}, o3;
    assert_int_equal(tb_mat3_inverse(&m3, &o3), TB_ERR_NUMERIC);
    /* Non-finite entries are an argument error. */
    tb_mat4 nan = tb_mat4_identity();
    nan.m[2][1] = NAN;
    tb_mat4 o;
    assert_int_equal(tb_mat4_inverse(&nan, &o), TB_ERR_ARG);
    nan.m[2][1] = INFINITY;
    assert_int_equal(tb_mat4_inverse(&nan, &o), TB_ERR_ARG);
    nan = tb_mat4_identity();
    nan.m[3][0] = NAN; /* non-affine row */
    assert_int_equal(tb_mat4_inverse(&nan, &o), TB_ERR_ARG);
}

/* The test is relative: uniformly tiny or huge matrices are as well
 * conditioned as the identity, and translations do not count. */
static void test_scale_free_verdict(void **state)
{
    (void)state;
    const double scales[] = {1e-20, 1e-150, 1e20, 1e150};
    for (size_t i = 0; i < sizeof scales / sizeof scales[0]; ++i) {
        double s = scales[i];
        tb_mat4 a = tb_mat4_identity(), inv;
        a.m[0][0] = a.m[1][1] = a.m[2][2] = s;
        a.m[0][3] = 1e6;
        assert_int_equal(tb_mat4_inverse(&a, &inv), TB_OK);
        tb_assert_near(inv.m[0][0], 1.0 / s, 1e-15 / s);
        tb_assert_near(inv.m[0][3], -1e6 / s, 1e-9 / s);
        /* The projective path on a uniformly scaled well-conditioned matrix. */
        const double h[16] = {1, 1, 1, -1, 1, 1, -1, 1, 1, -1, 1, 1, -1, 1, 1, 1};
        tb_mat4 hm = tb_mat4_from_rows(h);
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c)
                hm.m[r][c] *= s;
        assert_int_equal(tb_mat4_inverse(&hm, &inv), TB_OK);
        tb_assert_near(inv.m[0][3], -0.25 / s, 1e-15 / s);
    }
    /* A huge translation with unit scale stays invertible. */
    tb_mat4 t = tb_mat4_identity(), inv;
    t.m[0][3] = 1e300;
    assert_int_equal(tb_mat4_inverse(&t, &inv), TB_OK);
    assert_true(inv.m[0][3] == -1e300);
}

static double norm_inf4(const tb_mat4 *a)
{
    double best = 0.0;
    for (int i = 0; i < 4; ++i)
        best = fmax(best, fabs(a->m[i][0]) + fabs(a->m[i][1]) + fabs(a->m[i][2]) + fabs(a->m[i][3]));
    return best;
}

/* Backward-stable inversion: ||M X - I|| <= c n u ||M|| ||X||. We state
 * c n = 64 (n = 4, c = 16) and record the worst ratio seen. */
static void test_inverse_identity_random(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("inverse_identity_random", 2024), 3);
    const double u = 0x1p-53, c = 64.0;
    tb_mat4 id = tb_mat4_identity();
    double worst = 0.0;
    int accepted = 0, trials = 4000;
    for (int k = 0; k < trials; ++k) {
        tb_mat4 a;
        bool affine = k & 1;
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j)
                a.m[i][j] = 2.0 * tb_rng_double(&r) - 1.0;
        if (affine) {
            for (int i = 0; i < 3; ++i)
                a.m[i][3] *= 100.0; /* translations larger than the linear part */
            a.m[3][0] = a.m[3][1] = a.m[3][2] = 0.0;
            a.m[3][3] = 1.0;
        }
        tb_mat4 x;
        if (tb_mat4_inverse(&a, &x) != TB_OK)
            continue;
        ++accepted;
        double bound = c * u * norm_inf4(&a) * norm_inf4(&x);
        tb_mat4 p = tb_mat4_mul(&a, &x);
        double err = tb_mat4_max_abs_diff(&p, &id);
        /* The product itself is rounded: add its own error bound. */
        bound += 4 * u * norm_inf4(&a) * norm_inf4(&x);
        if (err / bound > worst)
            worst = err / bound;
        if (!(err <= bound))
            fail_msg("trial %d: |M X - I| = %.3g > bound %.3g", k, err, bound);
        tb_mat4 q = tb_mat4_mul(&x, &a);
        assert_true(tb_mat4_max_abs_diff(&q, &id) <= bound);
    }
    print_message("[ info     ] inverse: %d/%d accepted, worst |MX-I| / bound = %.3g\n", accepted,
                  trials, worst);
    /* Random [-1,1] matrices are rarely that ill-conditioned. */
    assert_true(accepted >= trials * 99 / 100);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mat3_hand),
        cmocka_unit_test(test_mat4_hand),
        cmocka_unit_test(test_mat4_affine_inverse_and_points),
        cmocka_unit_test(test_mat4f_layout),
        cmocka_unit_test(test_singular_and_ill_conditioned),
        cmocka_unit_test(test_scale_free_verdict),
        cmocka_unit_test(test_inverse_identity_random),
    };
    return cmocka_run_group_tests_name("util/math mat", tests, NULL, NULL);
}
