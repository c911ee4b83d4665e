/* util/math/transform.h: constructors on hand-worked cases (exact where the
 * arithmetic is exact), composition order, look-at convention, and seeded
 * property tests: M M^-1 = I, associativity, normals stay perpendicular to
 * tangents, rotations keep lengths, transformed boxes hold the corners. */
#include "tb_test.h"

#include <float.h>
#include <math.h>
#include <string.h>

#include "util/base/error.h"
#include "util/math/float.h"
#include "util/math/transform.h"

#define assert_vec3_eq(v, X, Y, Z)                                                           \
    do {                                                                                     \
        tb_vec3 tb__v = (v);                                                                 \
        if (!(tb__v.x == (X) && tb__v.y == (Y) && tb__v.z == (Z)))                           \
            fail_msg("%s = (%.9g, %.9g, %.9g), want (%.9g, %.9g, %.9g)", #v, tb__v.x, tb__v.y, \
                     tb__v.z, (double)(X), (double)(Y), (double)(Z));                        \
    } while (0)

static double dist3(tb_dvec3 a, tb_dvec3 b) { return tb_dvec3_length(tb_dvec3_sub(a, b)); }

static tb_transform must(tb_status st, tb_transform t)
{
    if (st)
        fail_msg("unexpected failure: %s", tb_last_error());
    return t;
}

static tb_transform rot_deg(double deg, double x, double y, double z)
{
    tb_transform t;
    return must(tb_transform_rotate_deg(deg, (tb_dvec3){x, y, z}, &t), t);
}

static tb_transform scale3(double x, double y, double z)
{
    tb_transform t;
    return must(tb_transform_scale((tb_dvec3){x, y, z}, &t), t);
}

static void test_translate_scale(void **state)
{
    (void)state;
    tb_transform t = tb_transform_translate((tb_dvec3){1, 2, 3});
    assert_vec3_eq(tb_transform_point(&t, (tb_vec3){1, 1, 1}), 2, 3, 4);
    assert_vec3_eq(tb_transform_vector(&t, (tb_vec3){1, 1, 1}), 1, 1, 1);
    assert_vec3_eq(tb_transform_normal(&t, (tb_vec3){0, 0, 1}), 0, 0, 1);
    tb_transform ti = tb_transform_inverse(&t);
    assert_vec3_eq(tb_transform_point(&ti, (tb_vec3){2, 3, 4}), 1, 1, 1);
    assert_false(tb_transform_swaps_handedness(&t));
    assert_false(tb_transform_is_identity(&t));
    tb_transform id = tb_transform_identity();
    assert_true(tb_transform_is_identity(&id));

    tb_transform s = scale3(2, -4, 0.5);
    assert_vec3_eq(tb_transform_point(&s, (tb_vec3){1, 1, 1}), 2, -4, 0.5f);
    assert_vec3_eq(tb_transform_vector(&s, (tb_vec3){1, 0, 2}), 2, 0, 1);
    /* Normals use the inverse transpose: (1/2, -1/4, 2). */
    assert_vec3_eq(tb_transform_normal(&s, (tb_vec3){1, 1, 1}), 0.5f, -0.25f, 2);
    assert_true(tb_transform_swaps_handedness(&s)); /* det = -4 */
    tb_transform s2 = scale3(-1, -1, 1);
    assert_false(tb_transform_swaps_handedness(&s2)); /* det = +1: a rotation by 180 */

    tb_transform out = tb_transform_identity();
    tb_clear_error();
    assert_int_equal(tb_transform_scale((tb_dvec3){1, 0, 1}, &out), TB_ERR_ARG);
    assert_true(strstr(tb_last_error(), "zero") != NULL);
    assert_int_equal(tb_transform_scale((tb_dvec3){1, 1, -0.0}, &out), TB_ERR_ARG);
    assert_int_equal(tb_transform_scale((tb_dvec3){NAN, 1, 1}, &out), TB_ERR_ARG);
    assert_int_equal(tb_transform_scale((tb_dvec3){1, INFINITY, 1}, &out), TB_ERR_ARG);
    assert_int_equal(tb_transform_scale((tb_dvec3){1e-20, 1, 1}, &out), TB_ERR_NUMERIC);
    assert_true(tb_transform_is_identity(&out)); /* untouched on failure */
    /* A uniform scale loses no relative precision, however small. */
    tb_transform tiny = scale3(1e-20, 1e-20, 1e-20);
    assert_true(tiny.inv.m[0][0] == 1e20);
    /* 1e-20 scale given as a general matrix: the same verdict. */
    tb_mat4 m = tb_mat4_identity();
    m.m[2][2] = 1e-20;
    assert_int_equal(tb_transform_from_matrix(&m, &out), TB_ERR_NUMERIC);
    m.m[2][2] = 0.0;
    assert_int_equal(tb_transform_from_matrix(&m, &out), TB_ERR_NUMERIC);
    assert_true(strstr(tb_last_error(), "singular") != NULL);
}

static void test_rotations_exact(void **state)
{
    (void)state;
    /* Right-hand rule, exact through the degree variant. */
    tb_transform rz = rot_deg(90, 0, 0, 1), rx = rot_deg(90, 1, 0, 0), ry = rot_deg(90, 0, 1, 0);
    assert_vec3_eq(tb_transform_point(&rz, (tb_vec3){1, 0, 0}), 0, 1, 0);
    assert_vec3_eq(tb_transform_point(&rx, (tb_vec3){0, 1, 0}), 0, 0, 1);
    assert_vec3_eq(tb_transform_point(&ry, (tb_vec3){0, 0, 1}), 1, 0, 0);
    assert_vec3_eq(tb_transform_point(&rz, (tb_vec3){2, 3, 5}), -3, 2, 5);
    tb_transform r180 = rot_deg(180, 0, 0, 7); /* axis length does not matter */
    assert_vec3_eq(tb_transform_point(&r180, (tb_vec3){1, 2, 3}), -1, -2, 3);
    tb_transform rm90 = rot_deg(-90, 0, 0, 1), r270 = rot_deg(270, 0, 0, 1);
    assert_vec3_eq(tb_transform_point(&rm90, (tb_vec3){1, 0, 0}), 0, -1, 0);
    assert_true(tb_mat4_equal(&rm90.m, &r270.m));
    tb_transform r450 = rot_deg(450, 0, 0, 1), r720 = rot_deg(-720, 1, 2, 3);
    assert_true(tb_mat4_equal(&r450.m, &rz.m));
    assert_true(tb_transform_is_identity(&r720));
    /* Rotating by 90 and its inverse are exact transposes. */
    tb_transform back = tb_transform_compose(&rz, &rm90);
    assert_true(tb_transform_is_identity(&back));

    /* The radian variants agree with the right-hand rule to rounding. */
    tb_transform zr = tb_transform_rotate_z(TB_PI_2);
    tb_dvec3 p = tb_transform_dpoint(&zr, (tb_dvec3){1, 0, 0});
    assert_true(dist3(p, (tb_dvec3){0, 1, 0}) < 1e-16);
    tb_transform xr = tb_transform_rotate_x(TB_PI_2);
    p = tb_transform_dpoint(&xr, (tb_dvec3){0, 1, 0});
    assert_true(dist3(p, (tb_dvec3){0, 0, 1}) < 1e-16);
    tb_transform yr = tb_transform_rotate_y(TB_PI_2);
    p = tb_transform_dpoint(&yr, (tb_dvec3){0, 0, 1});
    assert_true(dist3(p, (tb_dvec3){1, 0, 0}) < 1e-16);
    /* 120 degrees about (1,1,1) cycles the axes. */
    tb_transform cyc = rot_deg(120, 1, 1, 1);
    p = tb_transform_dpoint(&cyc, (tb_dvec3){1, 0, 0});
    assert_true(dist3(p, (tb_dvec3){0, 1, 0}) < 1e-15);
    p = tb_transform_dpoint(&cyc, (tb_dvec3){0, 0, 1});
    assert_true(dist3(p, (tb_dvec3){1, 0, 0}) < 1e-15);
    /* 30 degrees: sin = 1/2, cos = sqrt(3)/2. */
    tb_transform r30 = rot_deg(30, 0, 0, 1), r30r;
    assert_int_equal(tb_transform_rotate(TB_PI / 6, (tb_dvec3){0, 0, 1}, &r30r), TB_OK);
    tb_assert_near(r30.m.m[1][0], 0.5, 1e-16);
    tb_assert_near(r30.m.m[0][0], sqrt(3.0) / 2.0, 2.3e-16); /* 1 ulp */
    assert_true(tb_mat4_max_abs_diff(&r30.m, &r30r.m) < 1e-16);

    tb_transform out;
    assert_int_equal(tb_transform_rotate(1.0, (tb_dvec3){0, 0, 0}, &out), TB_ERR_ARG);
    assert_int_equal(tb_transform_rotate(NAN, (tb_dvec3){0, 0, 1}, &out), TB_ERR_ARG);
    assert_int_equal(tb_transform_rotate_deg(INFINITY, (tb_dvec3){0, 0, 1}, &out), TB_ERR_ARG);
    assert_int_equal(tb_transform_rotate(1.0, (tb_dvec3){0, NAN, 1}, &out), TB_ERR_ARG);
    /* Tiny and huge axes are normalised without under/overflow. */
    assert_int_equal(tb_transform_rotate_deg(90, (tb_dvec3){0, 0, 1e-300}, &out), TB_OK);
    assert_true(tb_mat4_equal(&out.m, &rz.m));
    assert_int_equal(tb_transform_rotate_deg(90, (tb_dvec3){0, 0, 1e300}, &out), TB_OK);
    assert_true(tb_mat4_equal(&out.m, &rz.m));
}

static void test_compose_order_and_matrix(void **state)
{
    (void)state;
    tb_transform t = tb_transform_translate((tb_dvec3){1, 0, 0}), s = scale3(2, 2, 2);
    /* compose(a, b) applies b first. */
    tb_transform ts = tb_transform_compose(&t, &s), st = tb_transform_compose(&s, &t);
    assert_vec3_eq(tb_transform_point(&ts, (tb_vec3){1, 1, 1}), 3, 2, 2);
    assert_vec3_eq(tb_transform_point(&st, (tb_vec3){1, 1, 1}), 4, 2, 2);
    tb_transform tsi = tb_transform_inverse(&ts);
    assert_vec3_eq(tb_transform_point(&tsi, (tb_vec3){3, 2, 2}), 1, 1, 1);

    /* A general matrix: shear x += 2y, translate z by 5. */
    const double rows[16] = {1, 2, 0, 0, 0, 1, 0, 0, 0, 0, 1, 5, 0, 0, 0, 1};
    tb_mat4 m = tb_mat4_from_rows(rows);
    tb_transform sh;
    assert_int_equal(tb_transform_from_matrix(&m, &sh), TB_OK);
    assert_vec3_eq(tb_transform_point(&sh, (tb_vec3){1, 1, 1}), 3, 1, 6);
    assert_vec3_eq(tb_transform_vector(&sh, (tb_vec3){1, 1, 1}), 3, 1, 1);
    /* The plane x = 0 (normal +x) goes to the plane x = 2y: normal (1, -2, 0);
     * the plane y = 0 is mapped onto itself. */
    assert_vec3_eq(tb_transform_normal(&sh, (tb_vec3){1, 0, 0}), 1, -2, 0);
    assert_vec3_eq(tb_transform_normal(&sh, (tb_vec3){0, 1, 0}), 0, 1, 0);
    assert_true(sh.inv.m[0][1] == -2 && sh.inv.m[2][3] == -5);
    /* The plane z = 0 (normal +z) is mapped into itself by the shear. */
    assert_vec3_eq(tb_transform_normal(&sh, (tb_vec3){0, 0, 1}), 0, 0, 1);
    /* Projective matrices are allowed; the point is divided by w. */
    const double proj[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0.5, 1};
    tb_transform pr;
    assert_int_equal(tb_transform_from_matrix(&(tb_mat4){0}, &pr), TB_ERR_NUMERIC);
    m = tb_mat4_from_rows(proj);
    assert_int_equal(tb_transform_from_matrix(&m, &pr), TB_OK);
    assert_vec3_eq(tb_transform_point(&pr, (tb_vec3){2, 4, 2}), 1, 2, 1);
    tb_transform pri = tb_transform_inverse(&pr);
    assert_vec3_eq(tb_transform_point(&pri, (tb_vec3){1, 2, 1}), 2, 4, 2);
}

static void test_look_at(void **state)
{
    (void)state;
    /* Camera at (0,0,5) looking at the origin with +y up: camera axes are the
     * world axes, so camera-to-world is a pure translation. */
    tb_transform c;
    assert_int_equal(tb_transform_look_at((tb_dvec3){0, 0, 5}, (tb_dvec3){0, 0, 0},
                                          (tb_dvec3){0, 1, 0}, &c),
                     TB_OK);
    tb_transform t5 = tb_transform_translate((tb_dvec3){0, 0, 5});
    assert_true(tb_mat4_max_abs_diff(&c.m, &t5.m) == 0.0);
    /* Camera at (1,2,3) looking toward +x with up +z: forward (+x) is -z_cam,
     * up (+z) is +y_cam, so +x_cam = y cross z = ... = -y world. */
    assert_int_equal(tb_transform_look_at((tb_dvec3){1, 2, 3}, (tb_dvec3){11, 2, 3},
                                          (tb_dvec3){0, 0, 2}, &c),
                     TB_OK);
    tb_transform v = tb_transform_inverse(&c);
    assert_true(dist3(tb_transform_dpoint(&v, (tb_dvec3){1, 2, 3}), (tb_dvec3){0, 0, 0}) == 0.0);
    assert_true(dist3(tb_transform_dpoint(&v, (tb_dvec3){11, 2, 3}), (tb_dvec3){0, 0, -10}) < 1e-14);
    assert_true(dist3(tb_transform_dvector(&c, (tb_dvec3){1, 0, 0}), (tb_dvec3){0, -1, 0}) < 1e-16);
    assert_true(dist3(tb_transform_dvector(&c, (tb_dvec3){0, 1, 0}), (tb_dvec3){0, 0, 1}) < 1e-16);

    tb_transform out = tb_transform_identity();
    tb_dvec3 e = {1, 2, 3};
    assert_int_equal(tb_transform_look_at(e, e, (tb_dvec3){0, 1, 0}, &out), TB_ERR_ARG);
    assert_int_equal(tb_transform_look_at(e, (tb_dvec3){1, 5, 3}, (tb_dvec3){0, -2, 0}, &out), TB_ERR_ARG);
    assert_true(strstr(tb_last_error(), "parallel") != NULL);
    assert_int_equal(tb_transform_look_at(e, (tb_dvec3){0, 0, 0}, (tb_dvec3){0, 0, 0}, &out), TB_ERR_ARG);
    assert_int_equal(tb_transform_look_at(e, (tb_dvec3){NAN, 0, 0}, (tb_dvec3){0, 1, 0}, &out), TB_ERR_ARG);
    assert_true(tb_transform_is_identity(&out));
}

static void test_look_at_random(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("look_at_random", 99), 4);
    double worst = 0.0;
    for (int k = 0; k < 5000; ++k) {
        tb_dvec3 eye = {200 * tb_rng_double(&r) - 100, 200 * tb_rng_double(&r) - 100,
                        200 * tb_rng_double(&r) - 100};
        tb_dvec3 dir = {2 * tb_rng_double(&r) - 1, 2 * tb_rng_double(&r) - 1, 2 * tb_rng_double(&r) - 1};
        tb_dvec3 up = {2 * tb_rng_double(&r) - 1, 2 * tb_rng_double(&r) - 1, 2 * tb_rng_double(&r) - 1};
        tb_dvec3 target = tb_dvec3_add(eye, tb_dvec3_scale(dir, 1 + 10 * tb_rng_double(&r)));
        tb_transform c;
        if (tb_transform_look_at(eye, target, up, &c) != TB_OK)
            fail_msg("look-at %d failed: %s", k, tb_last_error());
        tb_transform v = tb_transform_inverse(&c);
        double dist = tb_dvec3_length(tb_dvec3_sub(target, eye));
        /* Eye to the origin, target onto the -z axis at its distance. */
        double e1 = tb_dvec3_length(tb_transform_dpoint(&v, eye)) / 100.0;
        tb_dvec3 tc = tb_transform_dpoint(&v, target);
        double e2 = dist3(tc, (tb_dvec3){0, 0, -dist}) / 100.0;
        /* Up lands in the camera's y-z plane with positive y. */
        tb_dvec3 uc = tb_transform_dvector(&v, up);
        assert_true(uc.y > 0.0);
        double e3 = fabs(uc.x) / tb_dvec3_length(up);
        /* Rigid and right-handed: orthonormal, det +1. */
        tb_mat3 l = tb_mat4_linear(&c.m), lt = tb_mat3_transpose(&l), ll = tb_mat3_mul(&lt, &l);
        double e4 = fabs(tb_mat3_det(&l) - 1.0);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                e4 = fmax(e4, fabs(ll.m[i][j] - (i == j)));
        worst = fmax(worst, fmax(fmax(e1, e2), fmax(e3, e4)));
        assert_false(tb_transform_swaps_handedness(&c));
    }
    print_message("[ info     ] look-at: worst relative error %.3g\n", worst);
    assert_true(worst < 1e-13);
}

/* A random affine transform: rotation, non-uniform scale (maybe mirrored),
 * a shear, and a translation, each built by its own constructor. */
static tb_transform random_affine(tb_rng *r)
{
    tb_transform rot, sc, sh;
    tb_dvec3 axis = {2 * tb_rng_double(r) - 1, 2 * tb_rng_double(r) - 1, 2 * tb_rng_double(r) - 1};
    if (tb_transform_rotate(TB_2PI * tb_rng_double(r), axis, &rot))
        rot = tb_transform_identity();
    double s[3];
    for (int i = 0; i < 3; ++i) {
        s[i] = exp(3.0 * (tb_rng_double(r) - 0.5)); /* 0.22 .. 4.5 */
        if (tb_rng_u32(r) & 1)
            s[i] = -s[i];
    }
    sc = scale3(s[0], s[1], s[2]);
    tb_mat4 m = tb_mat4_identity();
    m.m[0][1] = tb_rng_double(r) - 0.5;
    m.m[1][2] = tb_rng_double(r) - 0.5;
    sh = must(tb_transform_from_matrix(&m, &sh), sh);
    tb_transform tr = tb_transform_translate(
        (tb_dvec3){200 * tb_rng_double(r) - 100, 200 * tb_rng_double(r) - 100, 200 * tb_rng_double(r) - 100});
    tb_transform a = tb_transform_compose(&sh, &sc);
    tb_transform b = tb_transform_compose(&rot, &a);
    return tb_transform_compose(&tr, &b);
}

static tb_dvec3 random_dvec(tb_rng *r, double scale)
{
    return (tb_dvec3){scale * (2 * tb_rng_double(r) - 1), scale * (2 * tb_rng_double(r) - 1),
                      scale * (2 * tb_rng_double(r) - 1)};
}

static void test_properties_random(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("transform_properties", 5), 5);
    tb_mat4 id = tb_mat4_identity();
    double w_inv = 0, w_assoc = 0, w_manual = 0, w_perp = 0, w_perpf = 0, w_len = 0;
    for (int k = 0; k < 3000; ++k) {
        tb_transform a = random_affine(&r), b = random_affine(&r), c = random_affine(&r);
        /* m inv = I: each factor is conditioned up to ~20^2, composed ~400. */
        tb_mat4 p = tb_mat4_mul(&a.m, &a.inv);
        w_inv = fmax(w_inv, tb_mat4_max_abs_diff(&p, &id));
        /* (a b) c = a (b c), relative to the entries' size. */
        tb_transform ab = tb_transform_compose(&a, &b), bc = tb_transform_compose(&b, &c);
        tb_transform l = tb_transform_compose(&ab, &c), rr = tb_transform_compose(&a, &bc);
        double big = 0;
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j)
                big = fmax(big, fabs(l.m.m[i][j]));
        w_assoc = fmax(w_assoc, tb_mat4_max_abs_diff(&l.m, &rr.m) / big);
        /* Point through the composition vs. through each factor in turn. */
        tb_dvec3 x = random_dvec(&r, 10);
        tb_dvec3 via = tb_transform_dpoint(&a, tb_transform_dpoint(&b, x));
        tb_dvec3 direct = tb_transform_dpoint(&ab, x);
        w_manual = fmax(w_manual, dist3(via, direct) / fmax(1.0, tb_dvec3_length(via)));
        /* Normal of the plane spanned by two tangents stays perpendicular. */
        tb_dvec3 t1 = random_dvec(&r, 1), t2 = random_dvec(&r, 1);
        tb_dvec3 n = tb_dvec3_cross(t1, t2);
        tb_dvec3 n2 = tb_transform_dnormal(&ab, n);
        tb_dvec3 u1 = tb_transform_dvector(&ab, t1), u2 = tb_transform_dvector(&ab, t2);
        double den = tb_dvec3_length(n2);
        w_perp = fmax(w_perp, fmax(fabs(tb_dvec3_dot(n2, u1)) / (den * tb_dvec3_length(u1)),
                                   fabs(tb_dvec3_dot(n2, u2)) / (den * tb_dvec3_length(u2))));
        /* Same through the float interface (one rounding per component). */
        tb_vec3 nf = tb_transform_normal(&ab, tb_dvec3_to_f(n));
        tb_vec3 uf = tb_transform_vector(&ab, tb_dvec3_to_f(t1));
        tb_dvec3 nfd = tb_vec3_to_d(nf), ufd = tb_vec3_to_d(uf);
        w_perpf = fmax(w_perpf, fabs(tb_dvec3_dot(nfd, ufd)) /
                                    (tb_dvec3_length(nfd) * tb_dvec3_length(ufd)));
        /* Rotations keep lengths (and never mirror). */
        tb_transform rot;
        assert_int_equal(tb_transform_rotate(TB_2PI * tb_rng_double(&r), random_dvec(&r, 1), &rot), TB_OK);
        tb_dvec3 v = random_dvec(&r, 100);
        w_len = fmax(w_len, fabs(tb_dvec3_length(tb_transform_dvector(&rot, v)) - tb_dvec3_length(v)) /
                                tb_dvec3_length(v));
        assert_false(tb_transform_swaps_handedness(&rot));
        /* Handedness of a composition is the product of the factors'. */
        assert_true(tb_transform_swaps_handedness(&ab) ==
                    (tb_transform_swaps_handedness(&a) != tb_transform_swaps_handedness(&b)));
    }
    print_message("[ info     ] |M M^-1 - I| %.3g, associativity %.3g, composed point %.3g, "
                  "normal.tangent %.3g (float %.3g), rotation length %.3g\n",
                  w_inv, w_assoc, w_manual, w_perp, w_perpf, w_len);
    assert_true(w_inv < 1e-11);
    assert_true(w_assoc < 1e-13);
    assert_true(w_manual < 1e-12);
    assert_true(w_perp < 1e-12);
    /* Float rounding of n and t (2^-24 each) tilts them by ~1e-7; the
     * transform's conditioning (up to ~400) amplifies that. */
    assert_true(w_perpf < 1e-4);
    assert_true(w_len < 1e-15);
}

static void test_ray_transform(void **state)
{
    (void)state;
    tb_transform tr = tb_transform_translate((tb_dvec3){1, 2, 3}), sc = scale3(2, 2, 2);
    tb_transform t = tb_transform_compose(&tr, &sc);
    tb_ray r = tb_ray_make((tb_vec3){0, 0, 0}, (tb_vec3){1, 0, 0}, 0.5f, 4.0f);
    tb_ray q = tb_transform_ray(&t, &r);
    assert_vec3_eq(q.o, 1, 2, 3);
    assert_vec3_eq(q.d, 2, 0, 0);
    assert_true(q.tmin == 0.5f && q.tmax == 4.0f);
    /* The point at parameter t maps to the point at the same t. */
    tb_rng g;
    tb_rng_seed(&g, tb_test_seed("ray_transform", 8), 6);
    double worst = 0;
    for (int k = 0; k < 2000; ++k) {
        tb_transform a = random_affine(&g);
        tb_ray ray = tb_ray_make(tb_dvec3_to_f(random_dvec(&g, 10)), tb_dvec3_to_f(random_dvec(&g, 1)),
                                 0.0f, INFINITY);
        tb_ray ar = tb_transform_ray(&a, &ray);
        float s = 5.0f * tb_rng_float(&g);
        tb_dvec3 want = tb_transform_dpoint(
            &a, tb_dvec3_add(tb_vec3_to_d(ray.o), tb_dvec3_scale(tb_vec3_to_d(ray.d), s)));
        tb_dvec3 got = tb_dvec3_add(tb_vec3_to_d(ar.o), tb_dvec3_scale(tb_vec3_to_d(ar.d), s));
        worst = fmax(worst, dist3(want, got) / fmax(1.0, tb_dvec3_length(want)));
    }
    print_message("[ info     ] ray transform: worst relative point error %.3g\n", worst);
    assert_true(worst < 1e-6);
}

/* Largest float <= v. */
static float float_down(double v)
{
    float f = (float)v;
    return (double)f > v ? tb_next_float_down(f) : f;
}

/* Smallest float >= v. */
static float float_up(double v)
{
    float f = (float)v;
    return (double)f < v ? tb_next_float_up(f) : f;
}

static void test_aabb_transform_exact(void **state)
{
    (void)state;
    tb_aabb b = {{0, 0, 0}, {1, 2, 3}};
    tb_transform id = tb_transform_identity();
    tb_aabb o = tb_transform_aabb(&id, &b);
    assert_memory_equal(&o, &b, sizeof o);
    /* 90 degrees about z: x' = -y in [-2, 0], y' = x in [0, 1]; exact. */
    tb_transform rz = rot_deg(90, 0, 0, 1);
    o = tb_transform_aabb(&rz, &b);
    assert_vec3_eq(o.lo, -2, 0, 0);
    assert_vec3_eq(o.hi, 0, 1, 3);
    /* 45 degrees about z of the unit cube: x' in [-s, s], y' in [0, 2s], s = sqrt(1/2). */
    tb_transform r45 = rot_deg(45, 0, 0, 1);
    tb_aabb u = {{0, 0, 0}, {1, 1, 1}};
    o = tb_transform_aabb(&r45, &u);
    double s = sqrt(0.5);
    assert_true(o.lo.x <= -s && o.lo.x >= tb_next_float_down(float_down(-s)));
    assert_true(o.hi.y >= 2 * s && o.hi.y <= tb_next_float_up(float_up(2 * s)));
    /* Translation by 0.1 (not a float): rounded outward, to the nearest floats
     * around 0.1 and 1.1 on the correct sides. */
    tb_transform t = tb_transform_translate((tb_dvec3){0.1, 0, 0});
    o = tb_transform_aabb(&t, &u);
    assert_true(o.lo.x == float_down(0.1) && o.lo.x < 0.1f);
    assert_true(o.hi.x == float_up(1.1));
    /* Empty stays empty; infinite boxes stay infinite without NaN. */
    tb_aabb e = tb_aabb_empty();
    o = tb_transform_aabb(&r45, &e);
    assert_true(tb_aabb_is_empty(&o));
    tb_aabb half = {{0, 0, 0}, {INFINITY, INFINITY, 1}};
    o = tb_transform_aabb(&rz, &half);
    assert_vec3_eq(o.lo, -INFINITY, 0, 0);
    assert_vec3_eq(o.hi, 0, INFINITY, 1);
    o = tb_transform_aabb(&r45, &half);
    assert_vec3_eq(o.lo, -INFINITY, 0, 0);
    assert_vec3_eq(o.hi, INFINITY, INFINITY, 1);
    /* Projective: a corner behind the eye (w <= 0) gives the whole space. */
    const double proj[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0};
    tb_transform pr = {tb_mat4_from_rows(proj), tb_mat4_identity()}; /* inv unused here */
    tb_aabb front = {{-1, -1, 1}, {1, 1, 2}};
    o = tb_transform_aabb(&pr, &front);
    /* x/z over the box: [-1, 1]; z/z = 1. */
    assert_true(o.lo.x <= -1 && o.lo.x >= -1.0000002f && o.hi.x >= 1 && o.hi.x <= 1.0000002f);
    assert_true(o.lo.z <= 1 && o.hi.z >= 1);
    tb_aabb across = {{-1, -1, -1}, {1, 1, 2}};
    o = tb_transform_aabb(&pr, &across);
    assert_vec3_eq(o.lo, -INFINITY, -INFINITY, -INFINITY);
}

static void test_aabb_transform_random(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("aabb_transform_random", 31), 7);
    int exact = 0, faces = 0;
    for (int k = 0; k < 3000; ++k) {
        tb_transform a = random_affine(&r);
        tb_dvec3 p = random_dvec(&r, 50), q = random_dvec(&r, 50);
        tb_aabb b = tb_aabb_from_points(tb_dvec3_to_f(p), tb_dvec3_to_f(q));
        tb_aabb o = tb_transform_aabb(&a, &b);
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (int i = 0; i < 8; ++i) {
            tb_dvec3 c = {(i & 1) ? b.hi.x : b.lo.x, (i & 2) ? b.hi.y : b.lo.y, (i & 4) ? b.hi.z : b.lo.z};
            tb_dvec3 w = tb_transform_dpoint(&a, c);
            for (int j = 0; j < 3; ++j) {
                double v = tb_dvec3_get(w, j);
                lo[j] = fmin(lo[j], v);
                hi[j] = fmax(hi[j], v);
            }
            /* Every transformed corner is inside (compared in double). */
            if (!(w.x >= o.lo.x && w.x <= o.hi.x && w.y >= o.lo.y && w.y <= o.hi.y &&
                  w.z >= o.lo.z && w.z <= o.hi.z))
                fail_msg("trial %d corner %d (%.17g %.17g %.17g) outside the box", k, i, w.x, w.y, w.z);
        }
        /* Interior points too. */
        for (int i = 0; i < 4; ++i) {
            tb_dvec3 c = {b.lo.x + (b.hi.x - b.lo.x) * tb_rng_double(&r),
                          b.lo.y + (b.hi.y - b.lo.y) * tb_rng_double(&r),
                          b.lo.z + (b.hi.z - b.lo.z) * tb_rng_double(&r)};
            tb_dvec3 w = tb_transform_dpoint(&a, c);
            assert_true(w.x >= o.lo.x && w.x <= o.hi.x && w.y >= o.lo.y && w.y <= o.hi.y &&
                        w.z >= o.lo.z && w.z <= o.hi.z);
        }
        /* Tight: each face is the float just outside the corner extreme, or one further. */
        float ol[3] = {o.lo.x, o.lo.y, o.lo.z}, oh[3] = {o.hi.x, o.hi.y, o.hi.z};
        for (int j = 0; j < 3; ++j) {
            float fl = float_down(lo[j]), fh = float_up(hi[j]);
            assert_true(ol[j] == fl || ol[j] == tb_next_float_down(fl));
            assert_true(oh[j] == fh || oh[j] == tb_next_float_up(fh));
            exact += (ol[j] == fl) + (oh[j] == fh);
            faces += 2;
        }
    }
    print_message("[ info     ] aabb transform: %d of %d faces at the nearest float outside\n", exact, faces);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_translate_scale),
        cmocka_unit_test(test_rotations_exact),
        cmocka_unit_test(test_compose_order_and_matrix),
        cmocka_unit_test(test_look_at),
        cmocka_unit_test(test_look_at_random),
        cmocka_unit_test(test_properties_random),
        cmocka_unit_test(test_ray_transform),
        cmocka_unit_test(test_aabb_transform_exact),
        cmocka_unit_test(test_aabb_transform_random),
    };
    return cmocka_run_group_tests_name("util/math transform", tests, NULL, NULL);
}
