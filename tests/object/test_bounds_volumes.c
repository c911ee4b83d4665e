/* host/object/bounds: boxes and spheres hold every surface point (sampled via
 * tb_param_eval under random affine transforms), the boxes are tight (each
 * face is touched by the surface: by the transformed vertices for polyhedra,
 * by a numerical maximisation over (face, u, v) for curved kinds), hand
 * values, CSG rules and errors. */
#include "tb_test.h"

#include "host/object/bounds.h"
#include "host/object/param.h"
#include "test_param_shapes.h"

/* Random point on a present face, on the face proper. */
static bool sample(tb_rng *r, const ts_shape *s, tb_dvec3 *p)
{
    int nf = tb_param_face_count(s->kind, &s->g);
    for (int tries = 0; tries < 100; tries++) {
        int f = (int)tb_rng_below(r, (uint32_t)nf);
        if (!tb_param_face_present(s->kind, &s->g, f))
            continue;
        double u = tb_rng_double(r), v = tb_rng_double(r);
        if (tb_rng_below(r, 8) == 0)
            u = (double)tb_rng_below(r, 2); /* edges too */
        if (tb_rng_below(r, 8) == 0)
            v = (double)tb_rng_below(r, 2);
        assert_int_equal(tb_param_eval(s->kind, &s->g, f, u, v, p, NULL, NULL, NULL), TB_OK);
        if (ts_on_face_domain(s, f, *p, u, v))
            return true;
    }
    return false;
}

static bool in_box(const tb_aabb *b, tb_dvec3 p)
{
    return p.x >= b->lo.x && p.x <= b->hi.x && p.y >= b->lo.y && p.y <= b->hi.y && p.z >= b->lo.z &&
           p.z <= b->hi.z;
}

static void test_bounds_contain_surface(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("bounds_contain", 21), 1);
    for (int ki = 0; ki < TS_NKINDS; ki++) {
        tb_prim_kind k = ts_kinds[ki];
        for (int shape = 0; shape < 40; shape++) {
            ts_shape s;
            ts_random_shape(&r, k, &s);
            tb_transform tw = shape % 4 == 0 ? tb_transform_identity() : ts_random_transform(&r);
            tb_aabb box, obox;
            tb_dvec3 c;
            double rad;
            assert_int_equal(tb_bounds_world(k, &s.g, &tw, &box), TB_OK);
            assert_int_equal(tb_bounds_object(k, &s.g, &obox), TB_OK);
            assert_int_equal(tb_bounds_sphere(k, &s.g, &tw, &c, &rad), TB_OK);
            tb_dvec3 e = tb_dvec3_sub(tb_vec3_to_d(box.hi), tb_vec3_to_d(box.lo));
            /* never looser than the box's own circumsphere */
            assert_true(rad <= 0.5 * tb_dvec3_length(e) * (1 + 1e-9));
            for (int i = 0; i < 250; i++) {
                tb_dvec3 p;
                if (!sample(&r, &s, &p))
                    continue;
                if (k == TB_PRIM_POLYGONS) {
                    /* eval gives points on the polygon's (Newell) plane, which the
                     * float vertices leave by their rounding: move p back onto the
                     * box by that much before testing */
                    tb_dvec3 lo = tb_vec3_to_d(obox.lo), hi = tb_vec3_to_d(obox.hi);
                    double tol = 1e-6 * tb_dvec3_length(tb_dvec3_sub(hi, lo));
                    p = (tb_dvec3){tb_clamp(p.x, lo.x - tol, hi.x + tol) == p.x ? tb_clamp(p.x, lo.x, hi.x) : p.x,
                                   tb_clamp(p.y, lo.y - tol, hi.y + tol) == p.y ? tb_clamp(p.y, lo.y, hi.y) : p.y,
                                   tb_clamp(p.z, lo.z - tol, hi.z + tol) == p.z ? tb_clamp(p.z, lo.z, hi.z) : p.z};
                }
                if (!in_box(&obox, p))
                    fail_msg("%s: object point (%.17g %.17g %.17g) outside its object box", tb_prim_kind_name(k),
                             p.x, p.y, p.z);
                tb_dvec3 pw = tb_transform_dpoint(&tw, p);
                if (!in_box(&box, pw))
                    fail_msg("%s: world point (%.17g %.17g %.17g) outside [%.9g %.9g %.9g]-[%.9g %.9g %.9g]",
                             tb_prim_kind_name(k), pw.x, pw.y, pw.z, box.lo.x, box.lo.y, box.lo.z, box.hi.x,
                             box.hi.y, box.hi.z);
                double d = tb_dvec3_length(tb_dvec3_sub(pw, c));
                if (d > rad)
                    fail_msg("%s: point %.17g from the sphere centre, radius %.17g", tb_prim_kind_name(k), d, rad);
            }
        }
    }
}

/* --------------------------------------------------------------- tightness */

/* World coordinate `axis` (times sign) of the surface point (face, u, v), or
 * -inf if the point is off the face proper. */
static double coord(const ts_shape *s, const tb_transform *tw, int face, double u, double v, int axis, double sign)
{
    tb_dvec3 p;
    if (tb_param_eval(s->kind, &s->g, face, u, v, &p, NULL, NULL, NULL) != TB_OK || !ts_on_face_domain(s, face, p, u, v))
        return -INFINITY;
    return sign * tb_dvec3_get(tb_transform_dpoint(tw, p), axis);
}

/* u wraps around on surfaces of revolution (and v on the torus). */
static bool periodic_u(tb_prim_kind k)
{
    return k == TB_PRIM_SPHERE || k == TB_PRIM_CYLINDER || k == TB_PRIM_CONE || k == TB_PRIM_CONIC ||
           k == TB_PRIM_TORUS;
}

/* Pattern search for the largest coord from (u, v) = (bu, bv) on face f. */
static double refine(const ts_shape *s, const tb_transform *tw, int f, int axis, double sign, double bu, double bv,
                     double step)
{
    double bf = coord(s, tw, f, bu, bv, axis, sign);
    for (; step > 1e-13; step *= 0.5) {
        for (bool moved = true; moved;) {
            moved = false;
            const double du[8] = {1, -1, 0, 0, 1, 1, -1, -1}, dv[8] = {0, 0, 1, -1, 1, -1, 1, -1};
            for (int d = 0; d < 8; d++) {
                double u = bu + step * du[d], v = bv + step * dv[d];
                /* across the seam where u (v on the torus) wraps around */
                u = periodic_u(s->kind) ? u - floor(u) : tb_clamp(u, 0, 1);
                v = s->kind == TB_PRIM_TORUS ? v - floor(v) : tb_clamp(v, 0, 1);
                double c = coord(s, tw, f, u, v, axis, sign);
                if (c > bf)
                    bf = c, bu = u, bv = v, moved = true;
            }
        }
    }
    return bf;
}

/* The largest sign * world coordinate over the surface: a grid over every
 * face, then a pattern search from the best grid point and from the best
 * interior one (a pole, where u does not move the point, would stop the
 * search from the wrong u). */
static double surface_max(const ts_shape *s, const tb_transform *tw, int axis, double sign)
{
    enum { G = 16 };
    int nf = tb_param_face_count(s->kind, &s->g);
    double best = -INFINITY;
    for (int f = 0; f < nf; f++) {
        if (!tb_param_face_present(s->kind, &s->g, f))
            continue;
        double bu = 0, bv = 0, bf = -INFINITY, iu = 0.5, iv = 0.5, ibf = -INFINITY;
        for (int i = 0; i <= G; i++)
            for (int j = 0; j <= G; j++) {
                double c = coord(s, tw, f, (double)i / G, (double)j / G, axis, sign);
                if (c > bf)
                    bf = c, bu = (double)i / G, bv = (double)j / G;
                if (i > 0 && i < G && j > 0 && j < G && c > ibf)
                    ibf = c, iu = (double)i / G, iv = (double)j / G;
            }
        if (bf == -INFINITY)
            continue;
        best = fmax(best, refine(s, tw, f, axis, sign, bu, bv, 1.0 / G));
        if (ibf > -INFINITY)
            best = fmax(best, refine(s, tw, f, axis, sign, iu, iv, 1.0 / G));
    }
    return best;
}

/* The vertices of the polyhedral kinds, written from docs/mid.md. */
static int vertices_of(const ts_shape *s, tb_dvec3 *vs, int cap)
{
    int n = 0;
    switch (s->kind) {
    case TB_PRIM_CUBE:
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH:
    case TB_PRIM_PYRAMID: {
        double t = s->kind == TB_PRIM_PYRAMID ? s->g.pyramid.top : 1.0;
        for (int i = 0; i < 4; i++) {
            double x = (i & 1) ? 1 : -1, y = (i & 2) ? 1 : -1;
            vs[n++] = (tb_dvec3){x, y, -1};
            vs[n++] = (tb_dvec3){t * x, t * y, 1};
        }
        return n;
    }
    case TB_PRIM_PRISM: {
        static double xs[2000], ys[2000];
        int m = ts_prism_loop(&s->g.prism, xs, ys, 2000);
        for (int i = 0; i < m && n + 2 <= cap; i++) {
            vs[n++] = (tb_dvec3){xs[i], ys[i], -1};
            vs[n++] = (tb_dvec3){xs[i], ys[i], 1};
        }
        return n;
    }
    case TB_PRIM_POLYGONS:
        for (int i = 0; i < s->g.polygons.face_start[s->g.polygons.nfaces]; i++)
            vs[n++] = tb_vec3_to_d(s->g.polygons.vertices[s->g.polygons.indices[i]]);
        return n;
    default:
        return 0;
    }
}

static void test_bounds_tight(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("bounds_tight", 22), 2);
    static tb_dvec3 vs[4000];
    for (int ki = 0; ki < TS_NKINDS; ki++) {
        tb_prim_kind k = ts_kinds[ki];
        double worst = 0.0;
        for (int shape = 0; shape < 8; shape++) {
            ts_shape s;
            ts_random_shape(&r, k, &s);
            tb_transform tw = shape % 3 == 0 ? tb_transform_identity() : ts_random_transform(&r);
            tb_aabb box;
            assert_int_equal(tb_bounds_world(k, &s.g, &tw, &box), TB_OK);
            /* float rounding scales with the coordinates' magnitude, not the box's size */
            tb_vec3 ext = tb_aabb_extent(&box);
            double size = fmax(fmax(ext.x, fmax(ext.y, ext.z)),
                               fmax(tb_vec3_max_comp(tb_vec3_abs(box.lo)), tb_vec3_max_comp(tb_vec3_abs(box.hi))));
            int nv = vertices_of(&s, vs, 4000);
            for (int axis = 0; axis < 3; axis++)
                for (int sg = -1; sg <= 1; sg += 2) {
                    double m = -INFINITY;
                    if (nv > 0) {
                        for (int i = 0; i < nv; i++)
                            m = fmax(m, sg * tb_dvec3_get(tb_transform_dpoint(&tw, vs[i]), axis));
                    } else {
                        m = surface_max(&s, &tw, axis, sg);
                    }
                    double face = sg > 0 ? tb_vec3_get(box.hi, axis) : -tb_vec3_get(box.lo, axis);
                    double gap = face - m;
                    assert_true(gap >= 0.0); /* the box holds the extreme */
                    worst = fmax(worst, gap / size);
                }
        }
        print_message("[          ] %-12s largest gap between box face and surface: %.3g of the box size (or coordinates)\n",
                      tb_prim_kind_name(k), worst);
        assert_true(worst < 1e-6); /* float rounding of the faces is 6e-8 */
    }
}

/* ------------------------------------------------------------ by hand */

static void box_near(tb_aabb b, double x0, double y0, double z0, double x1, double y1, double z1)
{
    double tol = 1e-6;
    tb_assert_near(b.lo.x, x0, tol);
    tb_assert_near(b.lo.y, y0, tol);
    tb_assert_near(b.lo.z, z0, tol);
    tb_assert_near(b.hi.x, x1, tol);
    tb_assert_near(b.hi.y, y1, tol);
    tb_assert_near(b.hi.z, z1, tol);
}

static void test_bounds_hand_values(void **state)
{
    (void)state;
    tb_mid_geometry g;
    tb_aabb b;
    /* torus: [-R-r, R+r]^2 x [-r, r] */
    g = tb_mid_geometry_default(TB_PRIM_TORUS);
    g.torus.major = 2, g.torus.minor = 0.5;
    assert_int_equal(tb_bounds_object(TB_PRIM_TORUS, &g, &b), TB_OK);
    box_near(b, -2.5, -2.5, -0.5, 2.5, 2.5, 0.5);
    /* the torus lying on its side (rotate 90 about x): y <-> z */
    tb_transform rx;
    assert_int_equal(tb_transform_rotate_deg(90, (tb_dvec3){1, 0, 0}, &rx), TB_OK);
    assert_int_equal(tb_bounds_world(TB_PRIM_TORUS, &g, &rx, &b), TB_OK);
    box_near(b, -2.5, -0.5, -2.5, 2.5, 0.5, 2.5);
    /* sphere under scale (1, 2, 3) then a 45 degree turn about z: the ellipse
     * x^2 + y^2/4 turned by 45 degrees reaches sqrt((1 + 4) / 2) in x and y */
    tb_transform sc, rz, m;
    assert_int_equal(tb_transform_scale((tb_dvec3){1, 2, 3}, &sc), TB_OK);
    assert_int_equal(tb_transform_rotate_deg(45, (tb_dvec3){0, 0, 1}, &rz), TB_OK);
    m = tb_transform_compose(&rz, &sc);
    assert_int_equal(tb_bounds_world(TB_PRIM_SPHERE, NULL, &m, &b), TB_OK);
    double e = sqrt(2.5);
    box_near(b, -e, -e, -3, e, e, 3);
    /* bounding sphere of a sphere under a similarity: itself */
    tb_transform s2, t;
    assert_int_equal(tb_transform_scale((tb_dvec3){2, 2, 2}, &s2), TB_OK);
    t = tb_transform_translate((tb_dvec3){1, 2, 3});
    m = tb_transform_compose(&t, &s2);
    tb_dvec3 c;
    double rad;
    assert_int_equal(tb_bounds_sphere(TB_PRIM_SPHERE, NULL, &m, &c, &rad), TB_OK);
    tb_assert_near(c.x, 1, 1e-12); tb_assert_near(c.y, 2, 1e-12);
    tb_assert_near(c.z, 3, 1e-12); tb_assert_near(rad, 2, 1e-9);
    /* cone: pointed cone's bounding sphere passes through the apex and base rim: radius 5/4 */
    g = tb_mid_geometry_default(TB_PRIM_CONE);
    assert_int_equal(tb_bounds_sphere(TB_PRIM_CONE, &g, NULL, &c, &rad), TB_OK);
    tb_assert_near(rad, 1.25, 1e-9);
    /* frustum wider at the top */
    g.cone.top_radius = 1.5;
    assert_int_equal(tb_bounds_object(TB_PRIM_CONE, &g, &b), TB_OK);
    box_near(b, -1.5, -1.5, -1, 1.5, 1.5, 1);
    /* conic: r^2 = 1 - z^2 on [-0.5, 1] is widest at its vertex z = 0 */
    g = tb_mid_geometry_default(TB_PRIM_CONIC);
    g.conic.z0 = -0.5;
    assert_int_equal(tb_bounds_object(TB_PRIM_CONIC, &g, &b), TB_OK);
    box_near(b, -1, -1, -0.5, 1, 1, 1);
    /* ... and on [0.6, 1] widest at z = 0.6: r = 0.8 */
    g.conic.z0 = 0.6;
    assert_int_equal(tb_bounds_object(TB_PRIM_CONIC, &g, &b), TB_OK);
    box_near(b, -0.8, -0.8, 0.6, 0.8, 0.8, 1);
    /* one-sheet hyperboloid r^2 = 1 + z^2 on [-1, 2]: r(2) = sqrt 5 */
    g.conic.c[0] = 1, g.conic.c[1] = 0, g.conic.c[2] = 1, g.conic.z0 = -1, g.conic.z1 = 2;
    assert_int_equal(tb_bounds_object(TB_PRIM_CONIC, &g, &b), TB_OK);
    box_near(b, -sqrt(5.0), -sqrt(5.0), -1, sqrt(5.0), sqrt(5.0), 2);
    /* regular hexagon prism: x in [-1, 1], y in [-sqrt3/2, sqrt3/2] */
    g = tb_mid_geometry_default(TB_PRIM_PRISM);
    g.prism.sides = 6;
    assert_int_equal(tb_bounds_object(TB_PRIM_PRISM, &g, &b), TB_OK);
    box_near(b, -1, -sqrt(3.0) / 2, -1, 1, sqrt(3.0) / 2, 1);
    /* profile prism: the profile's bounds */
    tb_vec2 prof[4] = {{0, 0}, {3, 0}, {3, 0.5f}, {-1, 2}};
    g.prism.sides = 0, g.prism.nprofile = 4, g.prism.profile = prof;
    assert_int_equal(tb_bounds_object(TB_PRIM_PRISM, &g, &b), TB_OK);
    box_near(b, -1, 0, -1, 3, 2, 1);
    /* pyramid frustum, arches */
    g = tb_mid_geometry_default(TB_PRIM_PYRAMID);
    g.pyramid.top = 2;
    assert_int_equal(tb_bounds_object(TB_PRIM_PYRAMID, &g, &b), TB_OK);
    box_near(b, -2, -2, -1, 2, 2, 1);
    g = tb_mid_geometry_default(TB_PRIM_ROUND_ARCH);
    assert_int_equal(tb_bounds_object(TB_PRIM_ROUND_ARCH, &g, &b), TB_OK);
    box_near(b, -1, -1, -1, 1, 1, 1);
    /* polygons: only the vertices the faces use */
    tb_vec3 vs[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 5}, {100, 100, 100}};
    int fs[2] = {0, 3}, idx[3] = {0, 1, 2};
    g = tb_mid_geometry_default(TB_PRIM_POLYGONS);
    g.polygons.nvertices = 4, g.polygons.vertices = vs, g.polygons.nfaces = 1;
    g.polygons.face_start = fs, g.polygons.indices = idx;
    assert_int_equal(tb_bounds_object(TB_PRIM_POLYGONS, &g, &b), TB_OK);
    box_near(b, 0, 0, 0, 1, 1, 5);
    /* the boxes are exact floats here: no rounding slack on exact values */
    g = tb_mid_geometry_default(TB_PRIM_CUBE);
    assert_int_equal(tb_bounds_object(TB_PRIM_CUBE, &g, &b), TB_OK);
    assert_true(b.lo.x == -1.0f && b.hi.z == 1.0f);
    /* point sets */
    assert_int_equal(tb_bounds_points(vs, 3, NULL, &b), TB_OK);
    box_near(b, 0, 0, 0, 1, 1, 5);
    assert_int_equal(tb_bounds_points(vs, 0, NULL, &b), TB_OK);
    assert_true(tb_aabb_is_empty(&b));
    assert_int_equal(tb_bounds_points_sphere(vs, 3, &t, &c, &rad), TB_OK);
    tb_assert_near(c.x, 1.5, 1e-6); tb_assert_near(c.z, 5.5, 1e-6);
}

static void test_bounds_csg_and_errors(void **state)
{
    (void)state;
    tb_aabb kids[3] = {
        {{0, 0, 0}, {2, 2, 2}},
        {{1, 1, 1}, {3, 3, 3}},
        {{1.5f, -1, 0}, {4, 1.5f, 1}},
    };
    tb_aabb u = tb_bounds_csg(TB_PRIM_UNION, kids, 3);
    box_near(u, 0, -1, 0, 4, 3, 3);
    tb_aabb i = tb_bounds_csg(TB_PRIM_INTERSECTION, kids, 2);
    box_near(i, 1, 1, 1, 2, 2, 2);
    i = tb_bounds_csg(TB_PRIM_INTERSECTION, kids, 3); /* y: [1, 1.5], z: [1, 1] */
    box_near(i, 1.5, 1, 1, 2, 1.5, 1);
    tb_aabb far = {{10, 10, 10}, {11, 11, 11}};
    tb_aabb two[2] = {kids[0], far};
    i = tb_bounds_csg(TB_PRIM_INTERSECTION, two, 2);
    assert_true(tb_aabb_is_empty(&i));
    tb_aabb d = tb_bounds_csg(TB_PRIM_DIFFERENCE, kids, 3);
    box_near(d, 0, 0, 0, 2, 2, 2);
    tb_aabb none = tb_bounds_csg(TB_PRIM_UNION, kids, 0);
    assert_true(tb_aabb_is_empty(&none));
    none = tb_bounds_csg(TB_PRIM_SPHERE, kids, 3);
    assert_true(tb_aabb_is_empty(&none));
    /* errors */
    tb_aabb b;
    double h;
    assert_int_equal(tb_bounds_world(TB_PRIM_UNION, NULL, NULL, &b), TB_ERR_ARG);
    tb_mid_geometry g = tb_mid_geometry_default(TB_PRIM_TORUS);
    g.torus.minor = -1;
    assert_int_equal(tb_bounds_object(TB_PRIM_TORUS, &g, &b), TB_ERR_ARG);
    assert_int_equal(tb_bounds_support(TB_PRIM_SPHERE, NULL, (tb_dvec3){NAN, 0, 0}, &h), TB_ERR_ARG);
    assert_int_equal(tb_bounds_points(NULL, 3, NULL, &b), TB_ERR_ARG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bounds_contain_surface),
        cmocka_unit_test(test_bounds_tight),
        cmocka_unit_test(test_bounds_hand_values),
        cmocka_unit_test(test_bounds_csg_and_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
