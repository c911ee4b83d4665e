/* util/math/vec.h: every operation on hand-computed values, plus the
 * orthonormal basis of Duff et al. on random unit vectors. */
#include "tb_test.h"

#include "util/math/rng.h"

#include <math.h>

#include "util/math/float.h"
#include "util/math/vec.h"

#define assert_vec3_eq(v, X, Y, Z)                                                           \
    do {                                                                                     \
        tb_vec3 tb__v = (v);                                                                 \
        if (!(tb__v.x == (X) && tb__v.y == (Y) && tb__v.z == (Z)))                           \
            fail_msg("%s = (%.9g, %.9g, %.9g), want (%.9g, %.9g, %.9g)", #v, tb__v.x, tb__v.y, \
                     tb__v.z, (double)(X), (double)(Y), (double)(Z));                        \
    } while (0)

static void test_vec3_ops(void **state)
{
    (void)state;
    tb_vec3 a = tb_vec3_make(1, 2, 3), b = tb_vec3_make(4, 5, 6);
    assert_vec3_eq(tb_vec3_add(a, b), 5, 7, 9);
    assert_vec3_eq(tb_vec3_sub(a, b), -3, -3, -3);
    assert_vec3_eq(tb_vec3_mul(a, b), 4, 10, 18);
    assert_vec3_eq(tb_vec3_div(b, tb_vec3_make(2, 5, 4)), 2, 1, 1.5);
    assert_vec3_eq(tb_vec3_scale(a, -2), -2, -4, -6);
    assert_vec3_eq(tb_vec3_neg(a), -1, -2, -3);
    assert_vec3_eq(tb_vec3_splat(7), 7, 7, 7);
    assert_true(tb_vec3_dot(a, b) == 32.0f);
    assert_true(tb_vec3_absdot(tb_vec3_neg(a), b) == 32.0f);
    /* (2*6 - 3*5, 3*4 - 1*6, 1*5 - 2*4) */
    assert_vec3_eq(tb_vec3_cross(a, b), -3, 6, -3);
    /* Right-handed: x cross y = z, y cross z = x, z cross x = y. */
    tb_vec3 x = {1, 0, 0}, y = {0, 1, 0}, z = {0, 0, 1};
    assert_vec3_eq(tb_vec3_cross(x, y), 0, 0, 1);
    assert_vec3_eq(tb_vec3_cross(y, z), 1, 0, 0);
    assert_vec3_eq(tb_vec3_cross(z, x), 0, 1, 0);
    assert_true(tb_vec3_length(tb_vec3_make(3, 4, 0)) == 5.0f);
    assert_true(tb_vec3_length(tb_vec3_make(2, 3, 6)) == 7.0f);
    assert_true(tb_vec3_length2(a) == 14.0f);
    assert_true(tb_vec3_distance(a, b) == sqrtf(27.0f));
    tb_vec3 n = tb_vec3_normalize(tb_vec3_make(3, 0, -4));
    tb_assert_near(n.x, 0.6, 1e-7);
    tb_assert_near(n.z, -0.8, 1e-7);
    assert_true(n.y == 0.0f);
    assert_vec3_eq(tb_vec3_min(tb_vec3_make(1, 5, -2), tb_vec3_make(3, -1, -2)), 1, -1, -2);
    assert_vec3_eq(tb_vec3_max(tb_vec3_make(1, 5, -2), tb_vec3_make(3, -1, -2)), 3, 5, -2);
    /* fminf/fmaxf: a NaN component loses (keeps empty boxes and unions sane). */
    assert_vec3_eq(tb_vec3_min(tb_vec3_make(NAN, 1, 1), tb_vec3_make(2, 1, 1)), 2, 1, 1);
    assert_vec3_eq(tb_vec3_abs(tb_vec3_make(-1, 0, 2.5f)), 1, 0, 2.5f);
    assert_vec3_eq(tb_vec3_lerp(tb_vec3_make(0, 0, 0), tb_vec3_make(2, 4, 8), 0.25f), 0.5f, 1, 2);
    assert_vec3_eq(tb_vec3_lerp(a, b, 0.0f), 1, 2, 3);
    assert_vec3_eq(tb_vec3_lerp(a, b, 1.0f), 4, 5, 6);
    assert_true(tb_vec3_max_comp(tb_vec3_make(-1, 7, 3)) == 7.0f);
    assert_true(tb_vec3_min_comp(tb_vec3_make(-1, 7, 3)) == -1.0f);
    assert_int_equal(tb_vec3_max_dim(tb_vec3_make(1, 2, 3)), 2);
    assert_int_equal(tb_vec3_max_dim(tb_vec3_make(1, 3, 3)), 1); /* first on ties */
    assert_int_equal(tb_vec3_max_dim(tb_vec3_make(4, 3, 4)), 0);
    assert_int_equal(tb_vec3_max_dim(tb_vec3_make(-4, -3, -5)), 1);
    assert_true(tb_vec3_get(b, 0) == 4 && tb_vec3_get(b, 1) == 5 && tb_vec3_get(b, 2) == 6);
    assert_vec3_eq(tb_vec3_permute(a, 2, 0, 1), 3, 1, 2);
    assert_true(tb_vec3_equal(tb_vec3_make(0.0f, 1, 2), tb_vec3_make(-0.0f, 1, 2)));
    assert_false(tb_vec3_equal(tb_vec3_make(NAN, 1, 2), tb_vec3_make(NAN, 1, 2)));
}

/* A cross product whose float formula cancels: (1+2^-13)(1-2^-13) - 1*1 =
 * -2^-26, which the naive float formula returns as 0. */
static void test_vec3_cross_cancellation(void **state)
{
    (void)state;
    tb_vec3 a = {1.0f + 0x1p-13f, 1.0f, 0.0f}, b = {1.0f, 1.0f - 0x1p-13f, 0.0f};
    volatile float p = a.x * b.y, q = a.y * b.x;
    assert_true(p - q == 0.0f); /* what float arithmetic alone gives */
    assert_vec3_eq(tb_vec3_cross(a, b), 0, 0, -0x1p-26f);
}

static void test_vec2_vec4(void **state)
{
    (void)state;
    tb_vec2 a = tb_vec2_make(1, 2), b = tb_vec2_make(3, -4);
    tb_vec2 s = tb_vec2_add(a, b);
    assert_true(s.x == 4 && s.y == -2);
    s = tb_vec2_sub(a, b);
    assert_true(s.x == -2 && s.y == 6);
    s = tb_vec2_mul(a, b);
    assert_true(s.x == 3 && s.y == -8);
    s = tb_vec2_scale(a, 3);
    assert_true(s.x == 3 && s.y == 6);
    assert_true(tb_vec2_dot(a, b) == -5);
    assert_true(tb_vec2_length(b) == 5);
    s = tb_vec2_lerp(a, b, 0.5f);
    assert_true(s.x == 2 && s.y == -1);

    tb_vec4 c = tb_vec4_make(1, 2, 3, 4), d = tb_vec4_from3(tb_vec3_make(5, 6, 7), 8);
    tb_vec4 e = tb_vec4_add(c, d);
    assert_true(e.x == 6 && e.y == 8 && e.z == 10 && e.w == 12);
    e = tb_vec4_sub(d, c);
    assert_true(e.x == 4 && e.y == 4 && e.z == 4 && e.w == 4);
    e = tb_vec4_mul(c, d);
    assert_true(e.x == 5 && e.y == 12 && e.z == 21 && e.w == 32);
    e = tb_vec4_scale(c, 0.5f);
    assert_true(e.x == 0.5f && e.y == 1 && e.z == 1.5f && e.w == 2);
    assert_true(tb_vec4_dot(c, d) == 70);
    e = tb_vec4_lerp(c, d, 0.25f);
    assert_true(e.x == 2 && e.y == 3 && e.z == 4 && e.w == 5);
    assert_vec3_eq(tb_vec4_xyz(d), 5, 6, 7);
}

static void test_dvec3_and_conversions(void **state)
{
    (void)state;
    tb_dvec3 a = tb_dvec3_make(1, 2, 3), b = tb_dvec3_make(4, 5, 6);
    tb_dvec3 r = tb_dvec3_cross(a, b);
    assert_true(r.x == -3 && r.y == 6 && r.z == -3);
    assert_true(tb_dvec3_dot(a, b) == 32);
    r = tb_dvec3_add(a, b);
    assert_true(r.x == 5 && r.y == 7 && r.z == 9);
    r = tb_dvec3_sub(a, b);
    assert_true(r.x == -3 && r.y == -3 && r.z == -3);
    r = tb_dvec3_mul(a, b);
    assert_true(r.x == 4 && r.y == 10 && r.z == 18);
    r = tb_dvec3_scale(a, 0.5);
    assert_true(r.x == 0.5 && r.y == 1 && r.z == 1.5);
    r = tb_dvec3_neg(a);
    assert_true(r.x == -1 && r.y == -2 && r.z == -3);
    assert_true(tb_dvec3_length(tb_dvec3_make(2, 3, 6)) == 7.0);
    assert_true(tb_dvec3_length2(a) == 14.0);
    r = tb_dvec3_normalize(tb_dvec3_make(0, -5, 0));
    assert_true(r.x == 0 && r.y == -1 && r.z == 0);
    r = tb_dvec3_min(a, tb_dvec3_make(0, 9, 3));
    assert_true(r.x == 0 && r.y == 2 && r.z == 3);
    r = tb_dvec3_max(a, tb_dvec3_make(0, 9, 3));
    assert_true(r.x == 1 && r.y == 9 && r.z == 3);
    r = tb_dvec3_abs(tb_dvec3_make(-1, 2, -0.5));
    assert_true(r.x == 1 && r.y == 2 && r.z == 0.5);
    assert_true(tb_dvec3_max_comp(tb_dvec3_make(-1, 2, -0.5)) == 2);
    r = tb_dvec3_lerp(a, b, 0.5);
    assert_true(r.x == 2.5 && r.y == 3.5 && r.z == 4.5);
    assert_true(tb_dvec3_get(b, 2) == 6);
    assert_true(tb_dvec3_isfinite(a));
    assert_false(tb_dvec3_isfinite(tb_dvec3_make(0, INFINITY, 0)));
    /* Widening is exact; narrowing rounds each component to nearest once. */
    tb_dvec3 w = tb_vec3_to_d(tb_vec3_make(0.1f, -3, 1e-45f));
    assert_true(w.x == (double)0.1f && w.y == -3.0 && w.z == (double)1e-45f);
    tb_vec3 f = tb_dvec3_to_f(tb_dvec3_make(0.1, 1.0 + 0x1p-25, 1e300));
    assert_vec3_eq(f, 0.1f, 1.0f, INFINITY);
    f = tb_dvec3_to_f(tb_dvec3_make(1.0 + 0x1.8p-24, 0, 0)); /* above the halfway point */
    assert_true(f.x == 1.0f + 0x1p-23f);
}

static void test_basis_axes(void **state)
{
    (void)state;
    tb_vec3 b1, b2;
    tb_vec3_basis(tb_vec3_make(0, 0, 1), &b1, &b2);
    assert_vec3_eq(b1, 1, 0, 0);
    assert_vec3_eq(b2, 0, 1, 0);
    tb_vec3_basis(tb_vec3_make(0, 0, -1), &b1, &b2);
    assert_vec3_eq(b1, 1, 0, 0);
    assert_vec3_eq(b2, 0, -1, 0);
    /* n = +x: (b1, b2, n) right-handed means b1 x b2 = x. */
    tb_vec3_basis(tb_vec3_make(1, 0, 0), &b1, &b2);
    assert_vec3_eq(b1, 0, 0, -1);
    assert_vec3_eq(b2, 0, 1, 0);
}

static void test_basis_random(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("basis_random", 11), 2);
    double worst_f = 0.0, worst_d = 0.0;
    for (int i = 0; i < 20000; ++i) {
        /* Uniform on the sphere; every 4th one squeezed toward the poles,
         * where the construction divides by (1 + |z|)... and near z = 0. */
        double z = 2.0 * tb_rng_double(&r) - 1.0;
        if (i % 4 == 1)
            z = copysign(1.0 - 1e-7 * tb_rng_double(&r), z);
        if (i % 4 == 2)
            z = 1e-7 * (tb_rng_double(&r) - 0.5);
        double phi = TB_2PI * tb_rng_double(&r), s = sqrt(1.0 - z * z);
        tb_dvec3 n = {s * cos(phi), s * sin(phi), z};
        tb_dvec3 d1, d2;
        tb_dvec3_basis(n, &d1, &d2);
        tb_dvec3 c = tb_dvec3_cross(d1, d2);
        double e = fmax(fmax(fabs(tb_dvec3_dot(d1, d2)), fabs(tb_dvec3_dot(d1, n))),
                        fmax(fabs(tb_dvec3_dot(d2, n)), fabs(tb_dvec3_length(d1) - 1.0)));
        e = fmax(e, fmax(fabs(tb_dvec3_length(d2) - 1.0), tb_dvec3_length(tb_dvec3_sub(c, n))));
        worst_d = fmax(worst_d, e);

        tb_vec3 nf = tb_vec3_normalize(tb_dvec3_to_f(n)), f1, f2;
        tb_vec3_basis(nf, &f1, &f2);
        tb_dvec3 g1 = tb_vec3_to_d(f1), g2 = tb_vec3_to_d(f2), gn = tb_vec3_to_d(nf);
        tb_dvec3 gc = tb_dvec3_cross(g1, g2);
        double ef = fmax(fmax(fabs(tb_dvec3_dot(g1, g2)), fabs(tb_dvec3_dot(g1, gn))),
                         fmax(fabs(tb_dvec3_dot(g2, gn)), fabs(tb_dvec3_length(g1) - 1.0)));
        ef = fmax(ef, fmax(fabs(tb_dvec3_length(g2) - 1.0), tb_dvec3_length(tb_dvec3_sub(gc, gn))));
        worst_f = fmax(worst_f, ef);
    }
    print_message("[ info     ] basis: worst orthonormality error float %.3g, double %.3g\n",
                  worst_f, worst_d);
    /* A few roundings of unit-sized values: a handful of ulps. */
    assert_true(worst_d < 1e-15);
    assert_true(worst_f < 1e-6);
}

/* PCG32 against the reference implementation's published output
 * (pcg32-demo, pcg-c-basic: seed 42, sequence 54), and tb_rng_float as the
 * top 24 bits of the same numbers: the generator every renderer's samples
 * come from (inline in rng.h). Fails on any change of the sequence. */
static void test_rng_reference(void **state)
{
    (void)state;
    static const uint32_t want[6] = {0xa15c02b7u, 0x7b47f409u, 0xba1d3330u, 0x83d2f293u, 0xbfa4784bu, 0xcbed606eu};
    tb_rng r, q;
    tb_rng_seed(&r, 42u, 54u);
    tb_rng_seed(&q, 42u, 54u);
    for (int i = 0; i < 6; i++) {
        assert_int_equal(tb_rng_u32(&r), want[i]);
        float f = tb_rng_float(&q);
        assert_true(f == (float)(want[i] >> 8) * 0x1p-24f);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rng_reference),
        cmocka_unit_test(test_vec3_ops),
        cmocka_unit_test(test_vec3_cross_cancellation),
        cmocka_unit_test(test_vec2_vec4),
        cmocka_unit_test(test_dvec3_and_conversions),
        cmocka_unit_test(test_basis_axes),
        cmocka_unit_test(test_basis_random),
    };
    return cmocka_run_group_tests_name("util/math vec", tests, NULL, NULL);
}
