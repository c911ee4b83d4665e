/* host/object/param: documented values by hand, and property tests on random
 * primitives of every kind: (face, u, v) -> point -> (face, u, v), point ->
 * param -> point (also for points off the surface: the nearest point),
 * tangents against finite differences, normals against an independent
 * inside test, the world-space wrappers, and the error cases. */
#include "tb_test.h"

#include "host/object/param.h"
#include "test_param_shapes.h"
#include "util/math/float.h"

/* Random (face, u, v) on a present face of s with (u, v) in [m, 1 - m]^2 and
 * the point on the face proper; false if none found. */
static bool pick(tb_rng *r, const ts_shape *s, double m, int *face, double *u, double *v, tb_dvec3 *p)
{
    int nf = tb_param_face_count(s->kind, &s->g);
    for (int tries = 0; tries < 200; tries++) {
        int f = (int)tb_rng_below(r, (uint32_t)nf);
        if (!tb_param_face_present(s->kind, &s->g, f))
            continue;
        double uu = m + (1 - 2 * m) * tb_rng_double(r), vv = m + (1 - 2 * m) * tb_rng_double(r);
        tb_dvec3 q;
        assert_int_equal(tb_param_eval(s->kind, &s->g, f, uu, vv, &q, NULL, NULL, NULL), TB_OK);
        if (!ts_on_face_domain(s, f, q, uu, vv))
            continue;
        *face = f, *u = uu, *v = vv, *p = q;
        return true;
    }
    return false;
}

/* u wraps around on surfaces of revolution (and v on the torus). */
static bool periodic_u(tb_prim_kind k)
{
    return k == TB_PRIM_SPHERE || k == TB_PRIM_CYLINDER || k == TB_PRIM_CONE || k == TB_PRIM_CONIC ||
           k == TB_PRIM_TORUS;
}

static double pdist(double a, double b, bool periodic)
{
    double d = fabs(a - b);
    return periodic ? fmin(d, 1.0 - d) : d;
}

/* A conic cap whose radius is a rounding residue of r^2 = 0 (a pole the
 * generator placed at the end): too small for the 1e-7 inside/outside steps. */
static bool tiny_face(const ts_shape *s, int face)
{
    if (s->kind != TB_PRIM_CONIC || face == TB_FACE_CONIC_SIDE)
        return false;
    return ts_conic_q(&s->g.conic, face == TB_FACE_CONIC_BOTTOM ? s->g.conic.z0 : s->g.conic.z1) < 1e-6;
}

static double dist(tb_dvec3 a, tb_dvec3 b) { return tb_dvec3_length(tb_dvec3_sub(a, b)); }

/* ------------------------------------------------------------ by hand */

static void near3(tb_dvec3 a, double x, double y, double z)
{
    tb_assert_near(a.x, x, 1e-15);
    tb_assert_near(a.y, y, 1e-15);
    tb_assert_near(a.z, z, 1e-15);
}

static void test_documented_values(void **state)
{
    (void)state;
    tb_mid_geometry g;
    tb_dvec3 p, n, du, dv;
    int f;
    double u, v;
    /* sphere: u = 0 at +x, v = 0 at the south pole, 1/2 on the equator */
    g = tb_mid_geometry_default(TB_PRIM_SPHERE);
    assert_int_equal(tb_param_eval(TB_PRIM_SPHERE, &g, 0, 0.25, 0.5, &p, &n, &du, &dv), TB_OK);
    near3(p, 0, 1, 0);
    near3(n, 0, 1, 0);
    near3(du, -2 * TS_PI, 0, 0); /* counter-clockwise seen from +z */
    near3(dv, 0, 0, TS_PI);
    assert_int_equal(tb_param_eval(TB_PRIM_SPHERE, &g, 0, 0.7, 0.0, &p, &n, &du, NULL), TB_OK);
    near3(p, 0, 0, -1);
    near3(du, 0, 0, 0);
    assert_int_equal(tb_param_from_point(TB_PRIM_SPHERE, &g, (tb_dvec3){1, 0, 0}, -1, &f, &u, &v), TB_OK);
    assert_int_equal(f, TB_FACE_SPHERE);
    tb_assert_near(u, 0, 0); tb_assert_near(v, 0.5, 1e-16);
    assert_int_equal(tb_param_from_point(TB_PRIM_SPHERE, &g, (tb_dvec3){0, -2, 0}, -1, &f, &u, &v), TB_OK);
    tb_assert_near(u, 0.75, 1e-16); tb_assert_near(v, 0.5, 1e-16);
    assert_int_equal(tb_param_from_point(TB_PRIM_SPHERE, &g, (tb_dvec3){0, 0, 1}, -1, &f, &u, &v), TB_OK);
    tb_assert_near(u, 0, 0); tb_assert_near(v, 1, 0); /* pole: u = 0 */
    /* cube: +x face, u along +y, v along +z; -z face: u along +x, v along -y */
    g = tb_mid_geometry_default(TB_PRIM_CUBE);
    assert_int_equal(tb_param_eval(TB_PRIM_CUBE, &g, TB_FACE_CUBE_POS_X, 0.75, 0.25, &p, &n, &du, &dv), TB_OK);
    near3(p, 1, 0.5, -0.5), near3(n, 1, 0, 0), near3(du, 0, 2, 0), near3(dv, 0, 0, 2);
    assert_int_equal(tb_param_eval(TB_PRIM_CUBE, &g, TB_FACE_CUBE_NEG_Z, 0.75, 0.25, &p, &n, &du, &dv), TB_OK);
    near3(p, 0.5, 0.5, -1), near3(n, 0, 0, -1), near3(du, 2, 0, 0), near3(dv, 0, -2, 0);
    assert_int_equal(tb_param_eval(TB_PRIM_CUBE, &g, TB_FACE_CUBE_POS_Y, 0.75, 0.25, &p, &n, NULL, NULL), TB_OK);
    near3(p, -0.5, 1, -0.5), near3(n, 0, 1, 0);
    assert_int_equal(tb_param_from_point(TB_PRIM_CUBE, &g, (tb_dvec3){0.2, -0.4, 1.5}, -1, &f, &u, &v), TB_OK);
    assert_int_equal(f, TB_FACE_CUBE_POS_Z);
    tb_assert_near(u, 0.6, 1e-15); tb_assert_near(v, 0.3, 1e-15);
    /* cylinder: bottom cap v = rho, top cap v = 1 - rho */
    g = tb_mid_geometry_default(TB_PRIM_CYLINDER);
    assert_int_equal(tb_param_eval(TB_PRIM_CYLINDER, &g, TB_FACE_CYLINDER_TOP, 0.5, 0.75, &p, &n, NULL, NULL), TB_OK);
    near3(p, -0.25, 0, 1), near3(n, 0, 0, 1);
    assert_int_equal(tb_param_eval(TB_PRIM_CYLINDER, &g, TB_FACE_CYLINDER_BOTTOM, 0.5, 0.75, &p, &n, NULL, NULL), TB_OK);
    near3(p, -0.75, 0, -1), near3(n, 0, 0, -1);
    assert_int_equal(tb_param_from_point(TB_PRIM_CYLINDER, &g, (tb_dvec3){0, 0.5, -1}, -1, &f, &u, &v), TB_OK);
    assert_int_equal(f, TB_FACE_CYLINDER_BOTTOM);
    tb_assert_near(u, 0.25, 1e-16); tb_assert_near(v, 0.5, 1e-16);
    g.cylinder.caps = false;
    assert_int_equal(tb_param_from_point(TB_PRIM_CYLINDER, &g, (tb_dvec3){0, 0.5, -1}, -1, &f, &u, &v), TB_OK);
    assert_int_equal(f, TB_FACE_CYLINDER_SIDE); /* no caps: the rim is nearest */
    tb_assert_near(v, 0, 0);
    /* cone: apex at v = 1, normal (2 cos, 2 sin, 1) / sqrt 5 */
    g = tb_mid_geometry_default(TB_PRIM_CONE);
    assert_int_equal(tb_param_eval(TB_PRIM_CONE, &g, TB_FACE_CONE_SIDE, 0, 0.5, &p, &n, NULL, NULL), TB_OK);
    near3(p, 0.5, 0, 0), near3(n, 2 / sqrt(5.0), 0, 1 / sqrt(5.0));
    assert_false(tb_param_face_present(TB_PRIM_CONE, &g, TB_FACE_CONE_TOP));
    /* torus: v = 0 on the outer equator, 1/4 on top of the tube */
    g = tb_mid_geometry_default(TB_PRIM_TORUS);
    assert_int_equal(tb_param_eval(TB_PRIM_TORUS, &g, 0, 0.5, 0.25, &p, &n, NULL, NULL), TB_OK);
    near3(p, -1, 0, 0.25), near3(n, 0, 0, 1);
    assert_int_equal(tb_param_from_point(TB_PRIM_TORUS, &g, (tb_dvec3){0, 0.75, 0}, -1, &f, &u, &v), TB_OK);
    tb_assert_near(u, 0.25, 1e-16); tb_assert_near(v, 0.5, 1e-16);
    /* pyramid side +x: normal (2, 0, 1) / sqrt 5 */
    g = tb_mid_geometry_default(TB_PRIM_PYRAMID);
    assert_int_equal(tb_param_eval(TB_PRIM_PYRAMID, &g, TB_FACE_PYRAMID_POS_X, 1, 0.5, &p, &n, NULL, NULL), TB_OK);
    near3(p, 0.5, 0.5, 0), near3(n, 2 / sqrt(5.0), 0, 1 / sqrt(5.0));
    /* conic: the default is the unit sphere with v linear in z */
    g = tb_mid_geometry_default(TB_PRIM_CONIC);
    assert_int_equal(tb_param_eval(TB_PRIM_CONIC, &g, TB_FACE_CONIC_SIDE, 0.25, 0.75, &p, &n, NULL, NULL), TB_OK);
    near3(p, 0, sqrt(0.75), 0.5), near3(n, 0, sqrt(0.75), 0.5);
    assert_false(tb_param_face_present(TB_PRIM_CONIC, &g, TB_FACE_CONIC_TOP)); /* r = 0 there */
    /* prism: regular triangle, side 0 from (1, 0) to (cos 120, sin 120) */
    g = tb_mid_geometry_default(TB_PRIM_PRISM);
    assert_int_equal(tb_param_face_count(TB_PRIM_PRISM, &g), 5);
    assert_int_equal(tb_param_eval(TB_PRIM_PRISM, &g, TB_FACE_PRISM_SIDE0, 0.5, 1, &p, &n, NULL, NULL), TB_OK);
    tb_assert_near(p.x, 0.25, 1e-15); tb_assert_near(p.y, sqrt(3.0) / 4, 1e-15); tb_assert_near(p.z, 1, 0);
    tb_assert_near(n.x, 0.5, 1e-15); tb_assert_near(n.y, sqrt(3.0) / 2, 1e-15);
    /* round arch: vault top at u = 1/2, normal -z; square arch ceiling */
    g = tb_mid_geometry_default(TB_PRIM_ROUND_ARCH); /* w 1, h 1.5: zs = 0 */
    assert_int_equal(tb_param_eval(TB_PRIM_ROUND_ARCH, &g, TB_FACE_ARCH_CEILING, 0.5, 0.5, &p, &n, NULL, NULL), TB_OK);
    near3(p, 0, 0, 0.5), near3(n, 0, 0, -1);
    assert_int_equal(tb_param_from_point(TB_PRIM_ROUND_ARCH, &g, (tb_dvec3){-0.5, 0.2, 0}, -1, &f, &u, &v), TB_OK);
    assert_true(f == TB_FACE_ARCH_CEILING || f == TB_FACE_ARCH_INNER_LEFT);
    g = tb_mid_geometry_default(TB_PRIM_SQUARE_ARCH);
    assert_int_equal(tb_param_from_point(TB_PRIM_SQUARE_ARCH, &g, (tb_dvec3){0.1, 0.5, 0.4}, -1, &f, &u, &v), TB_OK);
    assert_int_equal(f, TB_FACE_ARCH_CEILING);
    tb_assert_near(u, 0.6, 1e-15); tb_assert_near(v, 0.25, 1e-15);
    /* a point in the opening, next to the front face, belongs to the wall */
    assert_int_equal(tb_param_from_point(TB_PRIM_SQUARE_ARCH, &g, (tb_dvec3){-0.45, -0.9, -0.5}, -1, &f, &u, &v), TB_OK);
    assert_int_equal(f, TB_FACE_ARCH_INNER_LEFT);
}

/* ------------------------------------------------------ property tests */

static void test_param_point_param(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("param_point_param", 11), 1);
    for (int ki = 0; ki < TS_NKINDS; ki++) {
        tb_prim_kind k = ts_kinds[ki];
        long checked = 0, other_face = 0;
        for (int shape = 0; shape < 40; shape++) {
            ts_shape s;
            ts_random_shape(&r, k, &s);
            assert_int_equal(tb_param_check(k, &s.g), TB_OK);
            for (int i = 0; i < 60; i++) {
                int face, f2;
                double u, v, u2, v2;
                tb_dvec3 p, q, du;
                if (!pick(&r, &s, 0.0005, &face, &u, &v, &p))
                    continue;
                assert_int_equal(tb_param_eval(k, &s.g, face, u, v, &p, NULL, &du, NULL), TB_OK);
                double scale = fmax(1.0, tb_dvec3_length(p));
                /* with the face known */
                assert_int_equal(tb_param_from_point(k, &s.g, p, face, &f2, &u2, &v2), TB_OK);
                assert_int_equal(f2, face);
                if (tb_dvec3_length(du) > 1e-6) /* u is undefined at poles and cap centres */
                    if (pdist(u, u2, periodic_u(k)) > 1e-9)
                        fail_msg("%s face %d: u %.17g -> %.17g", tb_prim_kind_name(k), face, u, u2);
                if (pdist(v, v2, k == TB_PRIM_TORUS) > 1e-9)
                    fail_msg("%s face %d: v %.17g -> %.17g (u %.17g)", tb_prim_kind_name(k), face, v, v2, u);
                /* without: the nearest face, which is this one except on an edge */
                assert_int_equal(tb_param_from_point(k, &s.g, p, -1, &f2, &u2, &v2), TB_OK);
                assert_int_equal(tb_param_eval(k, &s.g, f2, u2, v2, &q, NULL, NULL, NULL), TB_OK);
                if (dist(p, q) > 1e-9 * scale)
                    fail_msg("%s face %d (%.17g, %.17g) -> face %d (%.17g, %.17g): %.3g apart",
                             tb_prim_kind_name(k), face, u, v, f2, u2, v2, dist(p, q));
                other_face += f2 != face;
                checked++;
            }
        }
        print_message("[          ] %-12s %ld points, %ld found on a neighbouring face (edges)\n",
                      tb_prim_kind_name(k), checked, other_face);
        assert_true(checked > 1000);
        assert_true(other_face * 100 < checked);
    }
}

static void test_point_param_point_off_surface(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("point_param_point", 12), 2);
    for (int ki = 0; ki < TS_NKINDS; ki++) {
        tb_prim_kind k = ts_kinds[ki];
        double worst_same = 0.0;
        for (int shape = 0; shape < 30; shape++) {
            ts_shape s;
            ts_random_shape(&r, k, &s);
            for (int i = 0; i < 60; i++) {
                int face, f2;
                double u, v, u2, v2;
                tb_dvec3 p, n, q;
                if (!pick(&r, &s, 0.02, &face, &u, &v, &p))
                    continue;
                assert_int_equal(tb_param_eval(k, &s.g, face, u, v, &p, &n, NULL, NULL), TB_OK);
                double eps = (tb_rng_below(&r, 2) ? 1e-4 : -1e-4) * (tb_rng_below(&r, 4) ? 1.0 : 0.0);
                tb_dvec3 po = tb_dvec3_add(p, tb_dvec3_scale(n, eps));
                assert_int_equal(tb_param_from_point(k, &s.g, po, -1, &f2, &u2, &v2), TB_OK);
                assert_int_equal(tb_param_eval(k, &s.g, f2, u2, v2, &q, NULL, NULL, NULL), TB_OK);
                /* The point found is never farther than the surface point we came from. */
                double dq = dist(po, q), dp = dist(po, p);
                if (dq > dp * (1 + 1e-6) + 1e-12)
                    fail_msg("%s: off-surface point %.3g from face %d (%.6g, %.6g) got face %d at %.3g",
                             tb_prim_kind_name(k), dp, face, u, v, f2, dq);
                if (f2 == face)
                    worst_same = fmax(worst_same, dist(p, q));
            }
        }
        print_message("[          ] %-12s foot point error %.3g\n", tb_prim_kind_name(k), worst_same);
        assert_true(worst_same < 1e-6);
    }
}

static void test_tangents_and_normals(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("tangents_normals", 13), 3);
    for (int ki = 0; ki < TS_NKINDS; ki++) {
        tb_prim_kind k = ts_kinds[ki];
        for (int shape = 0; shape < 30; shape++) {
            ts_shape s;
            ts_random_shape(&r, k, &s);
            for (int i = 0; i < 40; i++) {
                int face;
                double u, v;
                tb_dvec3 p, n, du, dv, pa, pb;
                if (!pick(&r, &s, 0.01, &face, &u, &v, &p))
                    continue;
                assert_int_equal(tb_param_eval(k, &s.g, face, u, v, &p, &n, &du, &dv), TB_OK);
                tb_assert_near(tb_dvec3_length(n), 1.0, 1e-12);
                double ldu = tb_dvec3_length(du), ldv = tb_dvec3_length(dv);
                tb_assert_near(tb_dvec3_dot(n, du), 0.0, 1e-10 * fmax(ldu, 1));
                tb_assert_near(tb_dvec3_dot(n, dv), 0.0, 1e-10 * fmax(ldv, 1));
                tb_dvec3 c = tb_dvec3_cross(du, dv);
                if (tb_dvec3_length(c) > 1e-9) {
                    tb_dvec3 cn = tb_dvec3_normalize(c);
                    if (dist(cn, n) > 1e-9)
                        fail_msg("%s face %d: dp/du x dp/dv not along the outward normal", tb_prim_kind_name(k), face);
                }
                /* central differences */
                const double h = 1e-6;
                assert_int_equal(tb_param_eval(k, &s.g, face, u + h, v, &pa, NULL, NULL, NULL), TB_OK);
                assert_int_equal(tb_param_eval(k, &s.g, face, u - h, v, &pb, NULL, NULL, NULL), TB_OK);
                tb_dvec3 fd = tb_dvec3_scale(tb_dvec3_sub(pa, pb), 0.5 / h);
                if (dist(fd, du) > 1e-5 * fmax(1, ldu))
                    fail_msg("%s face %d: dp/du off by %.3g", tb_prim_kind_name(k), face, dist(fd, du));
                assert_int_equal(tb_param_eval(k, &s.g, face, u, v + h, &pa, NULL, NULL, NULL), TB_OK);
                assert_int_equal(tb_param_eval(k, &s.g, face, u, v - h, &pb, NULL, NULL, NULL), TB_OK);
                fd = tb_dvec3_scale(tb_dvec3_sub(pa, pb), 0.5 / h);
                if (dist(fd, dv) > 1e-5 * fmax(1, ldv))
                    fail_msg("%s face %d: dp/dv off by %.3g", tb_prim_kind_name(k), face, dist(fd, dv));
                /* outward: the solid is behind the normal, empty space in front */
                if (k != TB_PRIM_POLYGONS && !tiny_face(&s, face)) {
                    const double d = 1e-7;
                    if (!ts_inside(&s, tb_dvec3_sub(p, tb_dvec3_scale(n, d))) ||
                        ts_inside(&s, tb_dvec3_add(p, tb_dvec3_scale(n, d))))
                        fail_msg("%s face %d (%.6g, %.6g): normal not outward", tb_prim_kind_name(k), face, u, v);
                }
            }
        }
    }
}

static void test_world_wrappers(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("param_world", 14), 4);
    for (int ki = 0; ki < TS_NKINDS; ki++) {
        tb_prim_kind k = ts_kinds[ki];
        for (int shape = 0; shape < 20; shape++) {
            ts_shape s;
            ts_random_shape(&r, k, &s);
            tb_transform tw = ts_random_transform(&r);
            tb_transform inv = tb_transform_inverse(&tw);
            for (int i = 0; i < 30; i++) {
                int face, f2;
                double u, v, u2, v2;
                tb_dvec3 p, n, du, dv, pw, nw, duw, dvw;
                if (!pick(&r, &s, 0.01, &face, &u, &v, &p))
                    continue;
                assert_int_equal(tb_param_eval(k, &s.g, face, u, v, &p, &n, &du, &dv), TB_OK);
                assert_int_equal(tb_param_eval_world(k, &s.g, &tw, face, u, v, &pw, &nw, &duw, &dvw), TB_OK);
                tb_dvec3 m = tb_transform_dpoint(&tw, p);
                assert_true(dist(m, pw) <= 1e-12 * fmax(1, tb_dvec3_length(m)));
                tb_assert_near(tb_dvec3_length(nw), 1, 1e-12);
                tb_assert_near(tb_dvec3_dot(nw, duw), 0, 1e-9 * tb_dvec3_length(duw));
                tb_assert_near(tb_dvec3_dot(nw, dvw), 0, 1e-9 * tb_dvec3_length(dvw));
                if (k != TB_PRIM_POLYGONS && !tiny_face(&s, face)) {
                    const double d = 1e-7;
                    tb_dvec3 in = tb_transform_dpoint(&inv, tb_dvec3_sub(pw, tb_dvec3_scale(nw, d)));
                    tb_dvec3 out = tb_transform_dpoint(&inv, tb_dvec3_add(pw, tb_dvec3_scale(nw, d)));
                    if (!ts_inside(&s, in) || ts_inside(&s, out))
                        fail_msg("%s face %d (%.9g, %.9g): world normal not outward", tb_prim_kind_name(k), face, u, v);
                }
                assert_int_equal(tb_param_from_point_world(k, &s.g, &tw, pw, face, &f2, &u2, &v2), TB_OK);
                assert_int_equal(f2, face);
                /* The transform round trip moves p by ~1e-15 of its size: in (u, v)
                 * that is this much divided by the tangent's length. */
                double e = 1e-12 * fmax(1, tb_dvec3_length(p));
                double eu = 1e-9 + e / tb_dvec3_length(du), ev = 1e-9 + e / tb_dvec3_length(dv);
                if (tb_dvec3_length(du) > 1e-6 && pdist(u, u2, periodic_u(k)) > eu)
                    fail_msg("%s face %d: u %.17g -> %.17g", tb_prim_kind_name(k), face, u, u2);
                if (pdist(v, v2, k == TB_PRIM_TORUS) > ev)
                    fail_msg("%s face %d: v %.17g -> %.17g", tb_prim_kind_name(k), face, v, v2);
            }
        }
    }
}

static void test_errors(void **state)
{
    (void)state;
    tb_mid_geometry g = tb_mid_geometry_default(TB_PRIM_CYLINDER);
    int f;
    double u, v;
    tb_dvec3 p;
    assert_int_equal(tb_param_from_point(TB_PRIM_UNION, &g, (tb_dvec3){0, 0, 0}, -1, &f, &u, &v), TB_ERR_ARG);
    assert_int_equal(tb_param_eval(TB_PRIM_DIFFERENCE, &g, 0, 0, 0, &p, NULL, NULL, NULL), TB_ERR_ARG);
    assert_int_equal(tb_param_from_point(TB_PRIM_CYLINDER, &g, (tb_dvec3){NAN, 0, 0}, -1, &f, &u, &v), TB_ERR_ARG);
    assert_int_equal(tb_param_from_point(TB_PRIM_CYLINDER, &g, (tb_dvec3){INFINITY, 0, 0}, -1, &f, &u, &v), TB_ERR_ARG);
    assert_int_equal(tb_param_from_point(TB_PRIM_CYLINDER, &g, (tb_dvec3){1, 0, 0}, 3, &f, &u, &v), TB_ERR_ARG);
    assert_int_equal(tb_param_eval(TB_PRIM_CYLINDER, &g, 0, 1.5, 0, &p, NULL, NULL, NULL), TB_ERR_ARG);
    assert_int_equal(tb_param_eval(TB_PRIM_CYLINDER, &g, 0, 0.5, NAN, &p, NULL, NULL, NULL), TB_ERR_ARG);
    assert_int_equal(tb_param_eval(TB_PRIM_CYLINDER, &g, -1, 0.5, 0.5, &p, NULL, NULL, NULL), TB_ERR_ARG);
    g.cylinder.caps = false;
    assert_false(tb_param_face_present(TB_PRIM_CYLINDER, &g, TB_FACE_CYLINDER_TOP));
    assert_int_equal(tb_param_eval(TB_PRIM_CYLINDER, &g, TB_FACE_CYLINDER_TOP, 0.5, 0.5, &p, NULL, NULL, NULL), TB_ERR_ARG);
    assert_int_equal(tb_param_from_point(TB_PRIM_CYLINDER, &g, (tb_dvec3){0, 0, 1}, TB_FACE_CYLINDER_TOP, &f, &u, &v), TB_ERR_ARG);
    assert_true(strstr(tb_last_error(), "no face") != NULL);
    g = tb_mid_geometry_default(TB_PRIM_TORUS);
    g.torus.minor = 2.0;
    assert_int_equal(tb_param_check(TB_PRIM_TORUS, &g), TB_ERR_ARG);
    assert_int_equal(tb_param_face_count(TB_PRIM_TORUS, &g), 0);
    g = tb_mid_geometry_default(TB_PRIM_CONIC);
    g.conic.z1 = g.conic.z0;
    assert_int_equal(tb_param_eval(TB_PRIM_CONIC, &g, 0, 0.5, 0.5, &p, NULL, NULL, NULL), TB_ERR_ARG);
    g = tb_mid_geometry_default(TB_PRIM_ROUND_ARCH);
    g.arch.height = 0.4; /* below w/2 */
    assert_int_equal(tb_param_check(TB_PRIM_ROUND_ARCH, &g), TB_ERR_ARG);
    g = tb_mid_geometry_default(TB_PRIM_POLYGONS);
    g.polygons.mesh.text = "box.fed";
    assert_int_equal(tb_param_check(TB_PRIM_POLYGONS, &g), TB_ERR_UNSUPPORTED);
    /* a polygon with an out-of-range index */
    tb_vec3 vs[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    int fs[2] = {0, 3}, idx[3] = {0, 1, 7};
    g = tb_mid_geometry_default(TB_PRIM_POLYGONS);
    g.polygons.nvertices = 3, g.polygons.vertices = vs, g.polygons.nfaces = 1;
    g.polygons.face_start = fs, g.polygons.indices = idx;
    assert_int_equal(tb_param_eval(TB_PRIM_POLYGONS, &g, 0, 0.5, 0.5, &p, NULL, NULL, NULL), TB_ERR_ARG);
    idx[2] = 2;
    assert_int_equal(tb_param_eval(TB_PRIM_POLYGONS, &g, 0, 0.25, 0.25, &p, NULL, NULL, NULL), TB_OK);
    tb_assert_near(p.x, 0.25, 1e-7); tb_assert_near(p.y, 0.25, 1e-7); tb_assert_near(p.z, 0, 1e-7);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_documented_values),
        cmocka_unit_test(test_param_point_param),
        cmocka_unit_test(test_point_param_point_off_surface),
        cmocka_unit_test(test_tangents_and_normals),
        cmocka_unit_test(test_world_wrappers),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
