/* host/object/polygonize: tessellations of random primitives of every kind
 * are closed and outward (closed solids), carry valid face IDs, have their
 * vertices on the analytic surface and their facet centroids within the
 * sagitta bound, respect the edge and angle limits, lie in the bounds, and
 * their area (and volume) converges to the analytic value computed here
 * from docs/mid.md's definitions (the conic's by long double quadrature). */
#include "tb_test.h"

#include "host/object/bounds.h"
#include "host/object/param.h"
#include "host/object/polygonize.h"
#include "test_param_shapes.h"
#include "util/mesh/fed.h"

/* ------------------------------------------------------- analytic values */

/* 2 pi r sqrt(1 + r'^2) = 2 pi sqrt(q + q'^2 / 4) over [z0, z1], composite
 * Gauss-Legendre (5 points, 2000 panels) in long double. */
static double conic_lateral(const tb_geom_conic *c)
{
    static const long double x[5] = {0.0L, -0.5384693101056830910L, 0.5384693101056830910L,
                                     -0.9061798459386639928L, 0.9061798459386639928L};
    static const long double w[5] = {0.5688888888888888889L, 0.4786286704993664680L, 0.4786286704993664680L,
                                     0.2369268850561890875L, 0.2369268850561890875L};
    const int panels = 2000;
    long double a = c->z0, h = ((long double)c->z1 - c->z0) / panels, sum = 0.0L;
    for (int p = 0; p < panels; p++) {
        long double mid = a + (p + 0.5L) * h;
        for (int k = 0; k < 5; k++) {
            long double z = mid + 0.5L * h * x[k];
            long double q = c->c[0] + c->c[1] * z + c->c[2] * z * z, dq = c->c[1] + 2.0L * c->c[2] * z;
            long double f = q + 0.25L * dq * dq;
            sum += w[k] * 0.5L * h * sqrtl(f > 0 ? f : 0);
        }
    }
    return (double)(2.0L * 3.14159265358979323846264L * sum);
}

static double conic_cap(const tb_geom_conic *c, double z)
{
    double q = ts_conic_q(c, z);
    return c->caps && q > 0 ? TS_PI * q : 0.0;
}

/* Polygon area by Newell's formula, in double. */
static double polygon_area(const ts_shape *s, int f)
{
    const tb_geom_polygons *g = &s->g.polygons;
    int b = g->face_start[f], n = g->face_start[f + 1] - b;
    double nx = 0, ny = 0, nz = 0;
    for (int i = 0; i < n; i++) {
        tb_vec3 a = g->vertices[g->indices[b + i]], c = g->vertices[g->indices[b + (i + 1) % n]];
        nx += ((double)a.y - c.y) * ((double)a.z + c.z);
        ny += ((double)a.z - c.z) * ((double)a.x + c.x);
        nz += ((double)a.x - c.x) * ((double)a.y + c.y);
    }
    return 0.5 * sqrt(nx * nx + ny * ny + nz * nz);
}

/* Area of the prism's polygon and its perimeter. */
static void prism_polygon(const tb_geom_prism *p, double *area, double *perim)
{
    static double xs[2000], ys[2000];
    int n = ts_prism_loop(p, xs, ys, 2000);
    double a = 0, l = 0;
    for (int i = 0; i < n; i++) {
        int j = (i + 1) % n;
        a += xs[i] * ys[j] - xs[j] * ys[i];
        l += hypot(xs[j] - xs[i], ys[j] - ys[i]);
    }
    *area = 0.5 * fabs(a), *perim = l;
}

/* Cross-section area of an arch's opening. */
static double arch_opening(const ts_shape *s)
{
    double w = s->g.arch.width, h = s->g.arch.height;
    if (s->kind == TB_PRIM_SQUARE_ARCH)
        return w * h;
    return w * (h - 0.5 * w) + 0.5 * TS_PI * 0.25 * w * w;
}

/* The analytic surface area of a shape. */
static double analytic_area(const ts_shape *s)
{
    const tb_mid_geometry *g = &s->g;
    switch (s->kind) {
    case TB_PRIM_SPHERE: return 4 * TS_PI;
    case TB_PRIM_CUBE: return 24;
    case TB_PRIM_CYLINDER: return 4 * TS_PI + (g->cylinder.caps ? 2 * TS_PI : 0);
    case TB_PRIM_CONE: {
        double r = g->cone.top_radius;
        return TS_PI * (1 + r) * sqrt(4 + (1 - r) * (1 - r)) + (g->cone.caps ? TS_PI * (1 + r * r) : 0);
    }
    case TB_PRIM_PYRAMID: {
        double t = g->pyramid.top;
        return 4 * (1 + t) * sqrt(4 + (1 - t) * (1 - t)) + (g->pyramid.caps ? 4 + 4 * t * t : 0);
    }
    case TB_PRIM_PRISM: {
        double a, l;
        prism_polygon(&g->prism, &a, &l);
        return 2 * l + (g->prism.caps ? 2 * a : 0);
    }
    case TB_PRIM_TORUS: return 4 * TS_PI * TS_PI * g->torus.major * g->torus.minor;
    case TB_PRIM_POLYGONS: {
        double a = 0;
        for (int f = 0; f < g->polygons.nfaces; f++)
            a += polygon_area(s, f);
        return a;
    }
    case TB_PRIM_CONIC:
        return conic_lateral(&g->conic) + conic_cap(&g->conic, g->conic.z0) + conic_cap(&g->conic, g->conic.z1);
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH: {
        double w = g->arch.width, h = g->arch.height, a = 0.5 * w;
        double walls = s->kind == TB_PRIM_SQUARE_ARCH ? 2 * 2 * h : 2 * 2 * (h - a);
        double top = s->kind == TB_PRIM_SQUARE_ARCH ? 2 * w : 2 * TS_PI * a;
        return 4 * 4 - 2 * arch_opening(s) + (4 - 2 * w) + walls + top + 4;
    }
    default: return NAN;
    }
}

/* The analytic volume of a closed shape (NAN if open). */
static double analytic_volume(const ts_shape *s)
{
    const tb_mid_geometry *g = &s->g;
    switch (s->kind) {
    case TB_PRIM_SPHERE: return 4 * TS_PI / 3;
    case TB_PRIM_CUBE: return 8;
    case TB_PRIM_CYLINDER: return g->cylinder.caps ? 2 * TS_PI : NAN;
    case TB_PRIM_CONE: {
        double r = g->cone.top_radius;
        return g->cone.caps ? 2 * TS_PI / 3 * (1 + r + r * r) : NAN;
    }
    case TB_PRIM_PYRAMID: {
        double t = g->pyramid.top;
        return g->pyramid.caps ? 2.0 / 3 * (4 + 4 * t + 4 * t * t) : NAN;
    }
    case TB_PRIM_PRISM: {
        double a, l;
        prism_polygon(&g->prism, &a, &l);
        return g->prism.caps ? 2 * a : NAN;
    }
    case TB_PRIM_TORUS: return 2 * TS_PI * TS_PI * g->torus.major * g->torus.minor * g->torus.minor;
    case TB_PRIM_CONIC: {
        const tb_geom_conic *c = &g->conic;
        bool closed = (c->caps || ts_conic_q(c, c->z0) <= 0) && (c->caps || ts_conic_q(c, c->z1) <= 0);
        if (!closed)
            return NAN;
        double z0 = c->z0, z1 = c->z1;
        return TS_PI * (c->c[0] * (z1 - z0) + c->c[1] * (z1 * z1 - z0 * z0) / 2 + c->c[2] * (z1 * z1 * z1 - z0 * z0 * z0) / 3);
    }
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH: return 8 - 2 * arch_opening(s);
    default: return NAN;
    }
}

/* ---------------------------------------------------------- mesh measures */

static tb_dvec3 pos(const tb_fed *m, uint32_t v) { return tb_vec3_to_d(m->positions[v]); }

static double mesh_area(const tb_fed *m)
{
    double a = 0;
    for (uint32_t f = 0; f < m->nfaces; f++)
        a += tb_fed_face_area(m, f);
    return a;
}

/* Signed volume by the divergence theorem (fans from each face's first corner). */
static double mesh_volume(const tb_fed *m)
{
    double v = 0;
    for (uint32_t f = 0; f < m->nfaces; f++) {
        uint32_t l = tb_fed_face_outer(m, f), n = tb_fed_loop_size(m, l);
        tb_dvec3 p0 = pos(m, tb_fed_loop_vertex(m, l, 0));
        for (uint32_t i = 1; i + 1 < n; i++) {
            tb_dvec3 p1 = pos(m, tb_fed_loop_vertex(m, l, i)), p2 = pos(m, tb_fed_loop_vertex(m, l, i + 1));
            v += tb_dvec3_dot(p0, tb_dvec3_cross(p1, p2)) / 6.0;
        }
    }
    return v;
}

static tb_dvec3 centroid(const tb_fed *m, uint32_t f)
{
    uint32_t l = tb_fed_face_outer(m, f), n = tb_fed_loop_size(m, l);
    tb_dvec3 c = {0, 0, 0};
    for (uint32_t i = 0; i < n; i++)
        c = tb_dvec3_add(c, pos(m, tb_fed_loop_vertex(m, l, i)));
    return tb_dvec3_scale(c, 1.0 / n);
}

/* True if the shape is a closed solid. */
static bool closed_shape(const ts_shape *s) { return s->kind != TB_PRIM_POLYGONS && !isnan(analytic_volume(s)); }

/* Distance from p to the surface, through the library's nearest point (an
 * upper bound of the true distance). */
static double surface_distance(const ts_shape *s, tb_dvec3 p)
{
    int f;
    double u, v;
    tb_dvec3 q;
    assert_int_equal(tb_param_from_point(s->kind, &s->g, p, -1, &f, &u, &v), TB_OK);
    assert_int_equal(tb_param_eval(s->kind, &s->g, f, u, v, &q, NULL, NULL, NULL), TB_OK);
    return tb_dvec3_length(tb_dvec3_sub(p, q));
}

/* Independent check that p is on the solid's boundary: among 600 points at
 * distance d around it (a Fibonacci sphere, which also finds the narrow
 * wedges at sharp rims), some are inside and some outside. */
static bool on_boundary(const ts_shape *s, tb_dvec3 p, double d)
{
    bool in = false, out = false;
    const int n = 600;
    for (int k = 0; k < n && !(in && out); k++) {
        double z = 1 - (2 * k + 1.0) / n, rr = sqrt(1 - z * z), ph = k * 2.399963229728653;
        tb_dvec3 q = {p.x + d * rr * cos(ph), p.y + d * rr * sin(ph), p.z + d * z};
        if (ts_inside(s, q))
            in = true;
        else
            out = true;
    }
    return in && out;
}

/* Bound on the distance of a facet point from the surface for angle step a
 * and edge e on a circle of radius rho (docs/primitives.md). */
static double sag(double rho, double a, double e)
{
    double s = INFINITY;
    if (a > 0)
        s = rho * (1 - cos(a / 2));
    if (e > 0 && e < 2 * rho)
        s = fmin(s, rho - sqrt(rho * rho - e * e / 4));
    if (e > 0 && e >= 2 * rho)
        s = fmin(s, rho);
    return s;
}

static double sagitta_bound(const ts_shape *s, double a, double e)
{
    const tb_mid_geometry *g = &s->g;
    switch (s->kind) {
    case TB_PRIM_SPHERE: return 2 * sag(1, a, e);
    case TB_PRIM_CYLINDER: return sag(1, a, e);
    case TB_PRIM_CONE: return sag(fmax(1, g->cone.top_radius), a, e);
    case TB_PRIM_TORUS: return sag(g->torus.major + g->torus.minor, a, e) + sag(g->torus.minor, a, e);
    case TB_PRIM_CONIC: {
        double q = fmax(ts_conic_q(&g->conic, g->conic.z0), ts_conic_q(&g->conic, g->conic.z1));
        if (g->conic.c[2] < 0) {
            double zv = -g->conic.c[1] / (2 * g->conic.c[2]);
            if (zv > g->conic.z0 && zv < g->conic.z1)
                q = fmax(q, ts_conic_q(&g->conic, zv));
        }
        /* around: circles up to the widest radius; along: chords of at most e turning at most a */
        return sag(sqrt(q), a, e) + 0.5 * e * tan(a / 2);
    }
    case TB_PRIM_ROUND_ARCH: return sag(0.5 * g->arch.width, a, e);
    default: return 0;
    }
}

/* ------------------------------------------------------------------ tests */

/* Random shape with its caps on half of the time (so most are closed). */
static void shape_for(tb_rng *r, tb_prim_kind k, ts_shape *s)
{
    ts_random_shape(r, k, s);
    bool caps = tb_rng_below(r, 2) != 0;
    if (k == TB_PRIM_CYLINDER)
        s->g.cylinder.caps |= caps;
    if (k == TB_PRIM_CONE)
        s->g.cone.caps |= caps;
    if (k == TB_PRIM_PYRAMID)
        s->g.pyramid.caps |= caps;
    if (k == TB_PRIM_PRISM) {
        s->g.prism.caps |= caps;
        if (s->g.prism.sides > 64)
            s->g.prism.sides = 64; /* keep the mesh small */
    }
    if (k == TB_PRIM_CONIC)
        s->g.conic.caps |= caps;
}

static void test_poly_structure(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("poly_structure", 31), 1);
    for (int ki = 0; ki < TS_NKINDS; ki++) {
        tb_prim_kind k = ts_kinds[ki];
        int nclosed = 0;
        for (int shape = 0; shape < 8; shape++) {
            ts_shape s;
            shape_for(&r, k, &s);
            for (int split = 0; split < 2; split++) {
                tb_poly_options o = {.max_angle = 0.3, .max_edge = 0.4, .split = split};
                tb_fed *m;
                if (tb_polygonize(k, &s.g, &o, &m) != TB_OK)
                    fail_msg("%s: %s", tb_prim_kind_name(k), tb_last_error());
                tb_fed_report rep;
                uint32_t warnings = tb_fed_check(m, &rep);
                if (warnings)
                    fail_msg("%s split %d: %u FED warnings, first: %s", tb_prim_kind_name(k), split, warnings,
                             rep.issues[0].message);
                double size = 10;
                tb_aabb ob;
                assert_int_equal(tb_bounds_object(k, &s.g, &ob), TB_OK);
                size = tb_dvec3_length(tb_dvec3_sub(tb_vec3_to_d(ob.hi), tb_vec3_to_d(ob.lo)));
                if (!split && closed_shape(&s)) {
                    nclosed++;
                    if (!tb_fed_is_closed(m))
                        fail_msg("%s: closed solid, open mesh (%u boundary edges)", tb_prim_kind_name(k),
                                 rep.boundary_edges);
                    int64_t chi = tb_fed_euler_characteristic(m);
                    assert_int_equal(chi, k == TB_PRIM_TORUS ? 0 : 2);
                    double vol = mesh_volume(m), ref = analytic_volume(&s);
                    if (!(vol > 0) || fabs(vol - ref) > 0.15 * ref)
                        fail_msg("%s: volume %.6g, analytic %.6g", tb_prim_kind_name(k), vol, ref);
                }
                /* faces: present IDs; corners on their face; vertices on the surface */
                for (uint32_t f = 0; f < m->nfaces; f++) {
                    int id = m->face_ids[f];
                    assert_true(tb_param_face_present(k, &s.g, id));
                    uint32_t l = tb_fed_face_outer(m, f);
                    for (uint32_t i = 0; i < tb_fed_loop_size(m, l); i++) {
                        tb_dvec3 p = pos(m, tb_fed_loop_vertex(m, l, i));
                        double d = tb_param_face_distance(k, &s.g, id, p);
                        if (d > 1e-6 * size)
                            fail_msg("%s: corner %.3g off its face %d", tb_prim_kind_name(k), d, id);
                    }
                }
                for (uint32_t v = 0; v < m->nverts; v++) {
                    tb_dvec3 p = pos(m, v), n = tb_vec3_to_d(m->normals[v]);
                    tb_assert_near(tb_dvec3_length(n), 1.0, 1e-6);
                    assert_true(surface_distance(&s, p) <= 1e-6 * size);
                    if (k != TB_PRIM_POLYGONS && !on_boundary(&s, p, 1e-5 * size))
                        fail_msg("%s: vertex (%g %g %g) not on the solid's boundary", tb_prim_kind_name(k), p.x, p.y, p.z);
                }
                if (split) {
                    /* every corner carries its face's exact (u, v) and normal */
                    for (uint32_t f = 0; f < m->nfaces; f++) {
                        uint32_t l = tb_fed_face_outer(m, f);
                        for (uint32_t i = 0; i < tb_fed_loop_size(m, l); i++) {
                            uint32_t vi = tb_fed_loop_vertex(m, l, i);
                            tb_dvec3 q, n;
                            if (k == TB_PRIM_POLYGONS)
                                continue; /* polygons keep their own vertex attributes */
                            assert_int_equal(tb_param_eval(k, &s.g, m->face_ids[f], m->uvs[vi].x, m->uvs[vi].y, &q, &n,
                                                           NULL, NULL), TB_OK);
                            /* the stored (u, v) are floats: allow the change of point and
                             * normal over their rounding (large next to a conic's pole) */
                            double uu = m->uvs[vi].x, vv = m->uvs[vi].y, h = 1e-6, sens = 0, psens = 0;
                            tb_dvec3 na, nb, pa, pb;
                            int fid = m->face_ids[f];
                            assert_int_equal(tb_param_eval(k, &s.g, fid, fmin(uu + h, 1), vv, &pa, NULL, NULL, NULL), TB_OK);
                            assert_int_equal(tb_param_eval(k, &s.g, fid, fmax(uu - h, 0), vv, &pb, NULL, NULL, NULL), TB_OK);
                            psens += tb_dvec3_length(tb_dvec3_sub(pa, pb)) / h;
                            assert_int_equal(tb_param_eval(k, &s.g, fid, uu, fmin(vv + h, 1), &pa, NULL, NULL, NULL), TB_OK);
                            assert_int_equal(tb_param_eval(k, &s.g, fid, uu, fmax(vv - h, 0), &pb, NULL, NULL, NULL), TB_OK);
                            psens += tb_dvec3_length(tb_dvec3_sub(pa, pb)) / h;
                            assert_true(tb_dvec3_length(tb_dvec3_sub(q, pos(m, vi))) <= 1e-6 * size + 1e-7 * psens);
                            assert_int_equal(tb_param_eval(k, &s.g, fid, fmin(uu + h, 1), vv, NULL, &na, NULL, NULL), TB_OK);
                            assert_int_equal(tb_param_eval(k, &s.g, fid, fmax(uu - h, 0), vv, NULL, &nb, NULL, NULL), TB_OK);
                            sens += tb_dvec3_length(tb_dvec3_sub(na, nb)) / h;
                            assert_int_equal(tb_param_eval(k, &s.g, fid, uu, fmin(vv + h, 1), NULL, &na, NULL, NULL), TB_OK);
                            assert_int_equal(tb_param_eval(k, &s.g, fid, uu, fmax(vv - h, 0), NULL, &nb, NULL, NULL), TB_OK);
                            sens += tb_dvec3_length(tb_dvec3_sub(na, nb)) / h;
                            if (tb_dvec3_length(tb_dvec3_sub(n, tb_vec3_to_d(m->normals[vi]))) > 1e-6 + 1e-7 * sens)
                                fail_msg("%s face %d (%.9g %.9g): normal (%g %g %g), param (%g %g %g)", tb_prim_kind_name(k),
                                         m->face_ids[f], m->uvs[vi].x, m->uvs[vi].y, m->normals[vi].x,
                                         m->normals[vi].y, m->normals[vi].z, n.x, n.y, n.z);
                        }
                    }
                }
                tb_fed_free(m);
            }
        }
        if (k != TB_PRIM_POLYGONS)
            assert_true(nclosed > 0);
    }
}

static void test_poly_limits_and_sagitta(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("poly_limits", 32), 2);
    for (int ki = 0; ki < TS_NKINDS; ki++) {
        tb_prim_kind k = ts_kinds[ki];
        double worst_edge = 0, worst_angle = 0, worst_sag = 0;
        for (int shape = 0; shape < 10; shape++) {
            ts_shape s;
            shape_for(&r, k, &s);
            double a = ts_uniform(&r, 0.1, 0.5), e = ts_uniform(&r, 0.15, 0.8);
            bool world = shape % 2 == 1;
            tb_transform tw = world ? ts_random_transform(&r) : tb_transform_identity();
            tb_poly_options o = {.max_angle = a, .max_edge = e, .to_world = world ? &tw : NULL};
            tb_fed *m;
            assert_int_equal(tb_polygonize(k, &s.g, &o, &m), TB_OK);
            tb_aabb ob;
            assert_int_equal(tb_bounds_object(k, &s.g, &ob), TB_OK);
            double size = tb_dvec3_length(tb_dvec3_sub(tb_vec3_to_d(ob.hi), tb_vec3_to_d(ob.lo)));
            /* edges: world length <= e (object length when no transform) */
            for (uint32_t i = 0; i < m->nedges; i++) {
                tb_dvec3 p0 = tb_transform_dpoint(&tw, pos(m, m->edges[i].v[0]));
                tb_dvec3 p1 = tb_transform_dpoint(&tw, pos(m, m->edges[i].v[1]));
                double l = tb_dvec3_length(tb_dvec3_sub(p1, p0));
                worst_edge = fmax(worst_edge, l / e);
                /* facets of one face meeting here: normals within the angle */
                if (tb_fed_edge_nuses(m, i) == 2) {
                    uint32_t f0 = tb_fed_edge_face(m, i, 0), f1 = tb_fed_edge_face(m, i, 1);
                    /* (facets within 1e-4 of the size have normals blurred by the float vertices) */
                    if (m->face_ids[f0] == m->face_ids[f1] && l > 1e-4 * size) {
                        tb_dvec3 n0 = tb_dvec3_normalize(tb_fed_face_normal(m, f0));
                        tb_dvec3 n1 = tb_dvec3_normalize(tb_fed_face_normal(m, f1));
                        double ang = atan2(tb_dvec3_length(tb_dvec3_cross(n0, n1)), tb_dvec3_dot(n0, n1));
                        worst_angle = fmax(worst_angle, ang / a);
                    }
                }
            }
            /* facet centroids within the sagitta bound of the surface */
            /* the edge limit applied in object space (world edges <= e) */
            double bound = sagitta_bound(&s, a, world ? e / tb_bounds_max_stretch(&tw) : e);
            for (uint32_t f = 0; f < m->nfaces; f++) {
                double d = surface_distance(&s, centroid(m, f));
                if (d > 1.1 * bound + 1e-6 * size)
                    fail_msg("%s: centroid of facet %u (face %d) %.3g from the surface, bound %.3g",
                             tb_prim_kind_name(k), f, m->face_ids[f], d, bound);
                worst_sag = fmax(worst_sag, bound > 0 ? d / bound : 0);
            }
            /* every vertex inside the world bounds */
            tb_aabb wb;
            assert_int_equal(tb_bounds_world(k, &s.g, &tw, &wb), TB_OK);
            for (uint32_t v = 0; v < m->nverts; v++) {
                tb_dvec3 p = tb_transform_dpoint(&tw, pos(m, v));
                /* float vertices of polygons sit a rounding off the Newell plane */
                double tol = k == TB_PRIM_POLYGONS ? 1e-6 * size : 0;
                assert_true(p.x >= wb.lo.x - tol && p.x <= wb.hi.x + tol && p.y >= wb.lo.y - tol &&
                            p.y <= wb.hi.y + tol && p.z >= wb.lo.z - tol && p.z <= wb.hi.z + tol);
            }
            tb_fed_free(m);
        }
        print_message("[          ] %-12s edge/limit %.4f, angle/limit %.4f, centroid distance/sagitta bound %.3f\n",
                      tb_prim_kind_name(k), worst_edge, worst_angle, worst_sag);
        assert_true(worst_edge <= 1 + 1e-6);
        assert_true(worst_angle <= 1 + 1e-6);
    }
}

/* Relative area error of the tessellation at resolution a: angle a and
 * edge 2a (about a radian of the unit-sized shapes: the edge limit keeps the
 * conic's nearly straight stretches, whose turning allows long chords, from
 * dominating). */
static double area_error(const ts_shape *s, double a, double *vol_err)
{
    tb_poly_options o = {.max_angle = a, .max_edge = 2 * a};
    tb_fed *m;
    assert_int_equal(tb_polygonize(s->kind, &s->g, &o, &m), TB_OK);
    double ref = analytic_area(s), err = fabs(mesh_area(m) - ref) / ref;
    double vref = analytic_volume(s);
    *vol_err = isnan(vref) ? 0.0 : fabs(mesh_volume(m) - vref) / vref;
    tb_fed_free(m);
    return err;
}

static void test_poly_area_converges(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("poly_area", 33), 3);
    const double angles[4] = {0.4, 0.28, 0.2, 0.1};
    for (int ki = 0; ki < TS_NKINDS; ki++) {
        tb_prim_kind k = ts_kinds[ki];
        for (int shape = 0; shape < 3; shape++) {
            ts_shape s;
            shape_for(&r, k, &s);
            if (shape == 0 && k != TB_PRIM_POLYGONS) { /* the defaults too: sphere 4 pi, torus 4 pi^2 R r, ... */
                s.g = tb_mid_geometry_default(k);
                if (k == TB_PRIM_PRISM)
                    s.g.prism.sides = 6;
            }
            double err[4], verr[4];
            for (int i = 0; i < 4; i++)
                err[i] = area_error(&s, angles[i], &verr[i]);
            bool flat = k == TB_PRIM_CUBE || k == TB_PRIM_PYRAMID || k == TB_PRIM_PRISM ||
                        k == TB_PRIM_POLYGONS || k == TB_PRIM_SQUARE_ARCH;
            if (shape == 0)
                print_message("[          ] %-12s area error %.2e %.2e %.2e %.2e, volume error %.2e %.2e %.2e %.2e\n",
                              tb_prim_kind_name(k), err[0], err[1], err[2], err[3], verr[0], verr[1], verr[2], verr[3]);
            if (flat) {
                for (int i = 0; i < 4; i++)
                    assert_true(err[i] < 1e-6 && verr[i] < 1e-6); /* exact up to float rounding */
                continue;
            }
            /* Each refinement lowers the error, as a^2 (second order): from
             * a = 0.4 to 0.1 by more than 10, down to
             * float noise (1e-6; the round arch's polygonal opening and vault
             * nearly cancel in its area). On the conic the profile's chords
             * and the rings err with opposite signs where r(z) is convex
             * (hyperboloids), so the net error need not fall at every step:
             * there only the last must be below the first and within a^2. */
            bool conic = k == TB_PRIM_CONIC;
            for (int i = 1; i < 4 && !conic; i++) {
                if (!(err[i] < err[i - 1] || err[i] < 1e-6))
                    fail_msg("%s: area error %.3g at angle %g after %.3g at %g", tb_prim_kind_name(k), err[i],
                             angles[i], err[i - 1], angles[i - 1]);
                if (!(verr[i] < verr[i - 1] || verr[i] < 1e-6))
                    fail_msg("%s: volume error %.3g at angle %g after %.3g", tb_prim_kind_name(k), verr[i], angles[i],
                             verr[i - 1]);
            }
            double gain = conic ? 1 : 10;
            if (!((err[3] < err[0] / gain || err[3] < 1e-6) && (verr[3] < verr[0] / gain || verr[3] < 1e-6) &&
                  err[3] < angles[3] * angles[3] && verr[3] < angles[3] * angles[3]))
                fail_msg("%s: area errors %.3g .. %.3g, volume errors %.3g .. %.3g", tb_prim_kind_name(k), err[0],
                         err[3], verr[0], verr[3]);
        }
    }
}

static void test_poly_hand_cases(void **state)
{
    (void)state;
    tb_fed *m;
    /* the double cone r^2 = z^2 on [-1, 1]: two cones meeting at their apex */
    tb_mid_geometry g = tb_mid_geometry_default(TB_PRIM_CONIC);
    g.conic.c[0] = 0, g.conic.c[1] = 0, g.conic.c[2] = 1;
    tb_poly_options o = {.max_angle = 0.05};
    assert_int_equal(tb_polygonize(TB_PRIM_CONIC, &g, &o, &m), TB_OK);
    assert_true(tb_fed_is_closed(m));
    double ref = 2 * TS_PI * sqrt(2.0) + 2 * TS_PI;
    tb_assert_near(mesh_area(m), ref, 2e-3 * ref);
    tb_fed_free(m);
    /* a cube with edge 0.5: 4 x 4 quads a side, 98 vertices */
    g = tb_mid_geometry_default(TB_PRIM_CUBE);
    o = (tb_poly_options){.max_edge = 0.5};
    assert_int_equal(tb_polygonize(TB_PRIM_CUBE, &g, &o, &m), TB_OK);
    assert_int_equal(m->nfaces, 96);
    assert_int_equal(m->nverts, 6 * 9 + 12 * 3 + 8);
    tb_fed_free(m);
    /* sphere at 45 degrees: 8 around, 4 pole to pole: 8 x 2 quads + 16 pole triangles */
    g = tb_mid_geometry_default(TB_PRIM_SPHERE);
    o = (tb_poly_options){.max_angle = TS_PI / 4};
    assert_int_equal(tb_polygonize(TB_PRIM_SPHERE, &g, &o, &m), TB_OK);
    assert_int_equal(m->nfaces, 32);
    assert_int_equal(m->nverts, 8 * 3 + 2);
    /* welded normals at a pole are the pole's; uv at the seam is u = 0 */
    for (uint32_t v = 0; v < m->nverts; v++)
        if (m->positions[v].z == 1.0f)
            tb_assert_near(m->normals[v].z, 1.0, 1e-7);
    tb_fed_free(m);
    /* a cylinder's rim vertex in the welded mesh: the normalised sum of side and cap normals */
    g = tb_mid_geometry_default(TB_PRIM_CYLINDER);
    o = (tb_poly_options){.max_angle = TS_PI / 2};
    assert_int_equal(tb_polygonize(TB_PRIM_CYLINDER, &g, &o, &m), TB_OK);
    for (uint32_t v = 0; v < m->nverts; v++)
        if (m->positions[v].x == 1.0f && m->positions[v].z == 1.0f) {
            tb_assert_near(m->normals[v].x, sqrt(0.5), 1e-7);
            tb_assert_near(m->normals[v].z, sqrt(0.5), 1e-7);
        }
    tb_fed_free(m);
    /* default options: the default angle */
    g = tb_mid_geometry_default(TB_PRIM_TORUS);
    assert_int_equal(tb_polygonize(TB_PRIM_TORUS, &g, NULL, &m), TB_OK);
    /* 2 pi / 15 degrees = 24 around; the tube needs one or two more for its
     * facets (not its chords) to meet within 15 degrees */
    assert_int_equal(m->nfaces % 24, 0);
    assert_true(m->nfaces >= 24 * 24 && m->nfaces <= 24 * 26);
    tb_fed_free(m);
    /* errors */
    assert_int_equal(tb_polygonize(TB_PRIM_UNION, &g, NULL, &m), TB_ERR_UNSUPPORTED);
    assert_null(m);
    o = (tb_poly_options){.max_edge = -1};
    assert_int_equal(tb_polygonize(TB_PRIM_TORUS, &g, &o, &m), TB_ERR_ARG);
    o = (tb_poly_options){.max_angle = NAN};
    assert_int_equal(tb_polygonize(TB_PRIM_TORUS, &g, &o, &m), TB_ERR_ARG);
    g = tb_mid_geometry_default(TB_PRIM_POLYGONS);
    g.polygons.mesh.text = "x.fed";
    assert_int_equal(tb_polygonize(TB_PRIM_POLYGONS, &g, NULL, &m), TB_ERR_UNSUPPORTED);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_poly_structure),
        cmocka_unit_test(test_poly_limits_and_sagitta),
        cmocka_unit_test(test_poly_area_converges),
        cmocka_unit_test(test_poly_hand_cases),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
