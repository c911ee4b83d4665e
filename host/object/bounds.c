/* Bounding volumes of every primitive (docs/primitives.md, "Bounds"): one
 * support function per kind, from which the object box, the exact world box
 * under an affine transform and a bounding sphere follow. */
#include "host/object/bounds.h"

#include <float.h>
#include <math.h>

#include "host/object/param.h"
#include "util/math/float.h"
#include "util/stats/stats.h"

TB_STAT_COUNTER(tb__bounds_sphere_calls, "Bounds/sphere");
TB_STAT_COUNTER(tb__bounds_cube_calls, "Bounds/cube");
TB_STAT_COUNTER(tb__bounds_cylinder_calls, "Bounds/cylinder");
TB_STAT_COUNTER(tb__bounds_cone_calls, "Bounds/cone");
TB_STAT_COUNTER(tb__bounds_pyramid_calls, "Bounds/pyramid");
TB_STAT_COUNTER(tb__bounds_prism_calls, "Bounds/prism");
TB_STAT_COUNTER(tb__bounds_torus_calls, "Bounds/torus");
TB_STAT_COUNTER(tb__bounds_polygons_calls, "Bounds/polygons");
TB_STAT_COUNTER(tb__bounds_conic_calls, "Bounds/conic");
TB_STAT_COUNTER(tb__bounds_square_arch_calls, "Bounds/square_arch");
TB_STAT_COUNTER(tb__bounds_round_arch_calls, "Bounds/round_arch");
TB_STAT_COUNTER(tb__bounds_csg_calls, "Bounds/csg");

static tb_dvec3 tb__v3(double x, double y, double z) { return (tb_dvec3){x, y, z}; }

/* Counts one world-box or sphere request for `kind`. */
static void tb__count(tb_prim_kind kind)
{
    static tb_stat *const per_kind[] = {
        &tb__bounds_sphere_calls, &tb__bounds_cube_calls,     &tb__bounds_cylinder_calls,
        &tb__bounds_cone_calls,   &tb__bounds_pyramid_calls,  &tb__bounds_prism_calls,
        &tb__bounds_torus_calls,  &tb__bounds_polygons_calls, &tb__bounds_conic_calls,
        &tb__bounds_square_arch_calls, &tb__bounds_round_arch_calls,
    };
    if ((unsigned)kind < sizeof per_kind / sizeof per_kind[0])
        TB_STAT_INC(*per_kind[kind]);
}

/* --------------------------------------------------------- support functions */

/* max of d . p over the circle of radius R at height z about the z axis. */
static double tb__disc_support(tb_dvec3 d, double R, double z) { return d.z * z + R * hypot(d.x, d.y); }

/* max of d . p over the vertices vs[0..n). */
static double tb__verts_support(tb_dvec3 d, const tb_dvec3 *vs, int n)
{
    double h = -INFINITY;
    for (int i = 0; i < n; i++)
        h = fmax(h, tb_dvec3_dot(d, vs[i]));
    return h;
}

/* r^2 of a conic at z (compensated, as param.c's points). */
static double tb__conic_q(const tb_geom_conic *c, double z) { return tb_param_conic_r2(c, z); }

/* a z + s r(z) at z: the support of the rim at height z (s = |d_xy|). */
static double tb__conic_f(const tb_geom_conic *c, double a, double s, double z)
{
    return a * z + s * tb_safe_sqrt(tb__conic_q(c, z));
}

/* max over z in [z0, z1] of a z + s r(z). r(z) = sqrt(q(z)) is either convex
 * (c2 > 0 with q > 0 at its vertex: the maximum is at an end) or concave
 * (every other case), so the ends plus the stationary points of the closed
 * form, s^2 q'^2 = 4 a^2 q, plus a golden-section search (which finds the
 * maximum of a concave function) cover it. Every candidate is a point of the
 * surface, so none can make the result too large. */
static double tb__conic_support(const tb_geom_conic *c, tb_dvec3 d)
{
    double a = d.z, s = hypot(d.x, d.y), z0 = c->z0, z1 = c->z1;
    double h = fmax(tb__conic_f(c, a, s, z0), tb__conic_f(c, a, s, z1));
    if (s == 0.0)
        return h;
    double k = s * s * c->c[2] - a * a;
    double A = 4.0 * c->c[2] * k, B = 4.0 * c->c[1] * k, C = s * s * c->c[1] * c->c[1] - 4.0 * a * a * c->c[0];
    double roots[2];
    int nr = 0;
    if (A != 0.0) {
        double disc = B * B - 4.0 * A * C;
        if (disc >= 0.0) {
            double q = -0.5 * (B + copysign(sqrt(disc), B));
            roots[nr++] = q / A;
            if (q != 0.0)
                roots[nr++] = C / q;
        }
    } else if (B != 0.0) {
        roots[nr++] = -C / B;
    }
    for (int i = 0; i < nr; i++)
        if (roots[i] > z0 && roots[i] < z1)
            h = fmax(h, tb__conic_f(c, a, s, roots[i]));
    /* Golden-section search for the concave case (harmless otherwise). */
    const double g = 0.6180339887498949;
    double lo = z0, hi = z1, x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
    double f1 = tb__conic_f(c, a, s, x1), f2 = tb__conic_f(c, a, s, x2);
    for (int it = 0; it < 80; it++) {
        if (f1 > f2)
            hi = x2, x2 = x1, f2 = f1, x1 = hi - g * (hi - lo), f1 = tb__conic_f(c, a, s, x1);
        else
            lo = x1, x1 = x2, f1 = f2, x2 = lo + g * (hi - lo), f2 = tb__conic_f(c, a, s, x2);
    }
    return fmax(h, fmax(f1, f2));
}

/* max over a regular n-gon's points of dx x + dy y: at the points next to
 * the direction's angle. */
static double tb__regular_support(const tb_geom_prism *g, double dx, double dy)
{
    int n = g->sides;
    double phi = atan2(dy, dx);
    if (phi < 0.0)
        phi += TB_2PI;
    int k = (int)floor(phi / TB_2PI * n);
    double h = -INFINITY;
    for (int j = k - 1; j <= k + 2; j++) {
        double x, y;
        tb_param_prism_point(g, j, &x, &y);
        h = fmax(h, dx * x + dy * y);
    }
    return h;
}

tb_status tb_bounds_support(tb_prim_kind kind, const tb_mid_geometry *g, tb_dvec3 d, double *h)
{
    tb_status st = tb_param_check(kind, g);
    if (st)
        return st;
    if (!h)
        return tb_error(TB_ERR_ARG, "bounds: NULL output");
    if (!tb_dvec3_isfinite(d))
        return tb_error(TB_ERR_ARG, "bounds: direction is not finite");
    switch (kind) {
    case TB_PRIM_SPHERE:
        *h = tb_dvec3_length(d);
        return TB_OK;
    case TB_PRIM_CUBE:
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH: /* the block [-1,1]^3 is the hull of both arches */
        *h = fabs(d.x) + fabs(d.y) + fabs(d.z);
        return TB_OK;
    case TB_PRIM_CYLINDER:
        *h = fmax(tb__disc_support(d, 1.0, -1.0), tb__disc_support(d, 1.0, 1.0));
        return TB_OK;
    case TB_PRIM_CONE:
        *h = fmax(tb__disc_support(d, 1.0, -1.0), tb__disc_support(d, g->cone.top_radius, 1.0));
        return TB_OK;
    case TB_PRIM_PYRAMID: {
        double t = g->pyramid.top;
        tb_dvec3 vs[8] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                          {-t, -t, 1},  {t, -t, 1},  {t, t, 1},  {-t, t, 1}};
        *h = tb__verts_support(d, vs, 8);
        return TB_OK;
    }
    case TB_PRIM_PRISM: {
        const tb_geom_prism *pr = &g->prism;
        double m;
        if (pr->sides > 0) {
            m = tb__regular_support(pr, d.x, d.y);
        } else {
            m = -INFINITY;
            for (int i = 0; i < pr->nprofile; i++)
                m = fmax(m, d.x * pr->profile[i].x + d.y * pr->profile[i].y);
        }
        *h = m + fabs(d.z);
        return TB_OK;
    }
    case TB_PRIM_TORUS:
        /* The solid torus is the centre circle plus a ball of radius minor. */
        *h = g->torus.major * hypot(d.x, d.y) + g->torus.minor * tb_dvec3_length(d);
        return TB_OK;
    case TB_PRIM_POLYGONS: {
        const tb_geom_polygons *p = &g->polygons;
        double m = -INFINITY;
        int nidx = p->nfaces > 0 ? p->face_start[p->nfaces] : 0;
        for (int i = 0; i < nidx; i++) {
            int k = p->indices[i];
            if (k < 0 || k >= p->nvertices)
                return tb_error(TB_ERR_ARG, "bounds: polygons: vertex index %d out of range", k);
            m = fmax(m, tb_dvec3_dot(d, tb_vec3_to_d(p->vertices[k])));
        }
        *h = m;
        return TB_OK;
    }
    case TB_PRIM_CONIC:
        *h = tb__conic_support(&g->conic, d);
        return TB_OK;
    default:
        return tb_error(TB_ERR_ARG, "bounds: %s is not a primitive", tb_prim_kind_name(kind));
    }
}

/* ------------------------------------------------------------------ boxes */

tb_aabb tb_bounds_round_out(tb_dvec3 lo, tb_dvec3 hi)
{
    if (!(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z))
        return tb_aabb_empty();
    return (tb_aabb){{tb_float_round_down(lo.x), tb_float_round_down(lo.y), tb_float_round_down(lo.z)},
                     {tb_float_round_up(hi.x), tb_float_round_up(hi.y), tb_float_round_up(hi.z)}};
}

/* True if the matrix is affine (last row 0 0 0 1). */
static bool tb__affine(const tb_transform *t)
{
    return t->m.m[3][0] == 0.0 && t->m.m[3][1] == 0.0 && t->m.m[3][2] == 0.0 && t->m.m[3][3] == 1.0;
}

/* The double world box: coordinate i ranges over t_i +- h(+-L_i). Under a
 * transform (tw != NULL) the few roundings of h and the sum are covered by a
 * relative pad of 2^-48 (16 double ulps), and the float rounding of object
 * points by another (see below); the object box (tw == NULL) takes h as
 * computed, so that exact extents (1 for the cube, R + r for the torus when
 * representable) stay exact floats (and rounding an object point to the
 * nearest float never leaves a float box that holds the exact point). */
static tb_status tb__world_box(tb_prim_kind kind, const tb_mid_geometry *g, const tb_transform *tw,
                               tb_dvec3 *lo, tb_dvec3 *hi)
{
    double l[3], h[3], fround = 0.0;
    if (tw) {
        /* Points of the object rounded to float in object space (tessellation
         * vertices, float hit points) may stand half a float ulp outside the
         * exact surface; the world box holds them too: pad each axis by that
         * rounding (2^-24 of the largest object coordinate) through the row. */
        tb_dvec3 olo, ohi;
        tb_status st = tb__world_box(kind, g, NULL, &olo, &ohi);
        if (st)
            return st;
        if (olo.x <= ohi.x)
            fround = 0x1p-24 * fmax(tb_dvec3_max_comp(tb_dvec3_abs(olo)), tb_dvec3_max_comp(tb_dvec3_abs(ohi)));
    }
    for (int i = 0; i < 3; i++) {
        tb_dvec3 row = tw ? tb__v3(tw->m.m[i][0], tw->m.m[i][1], tw->m.m[i][2])
                          : tb__v3(i == 0, i == 1, i == 2);
        double t = tw ? tw->m.m[i][3] : 0.0, hp, hm;
        tb_status st = tb_bounds_support(kind, g, row, &hp);
        if (st)
            return st;
        st = tb_bounds_support(kind, g, tb_dvec3_neg(row), &hm);
        if (st)
            return st;
        if (hp == -INFINITY) { /* no points */
            *lo = tb__v3(INFINITY, INFINITY, INFINITY), *hi = tb__v3(-INFINITY, -INFINITY, -INFINITY);
            return TB_OK;
        }
        double pad = tw ? 0x1p-48 * (fabs(t) + fabs(hp) + fabs(hm)) + fround * (fabs(row.x) + fabs(row.y) + fabs(row.z)) : 0.0;
        h[i] = t + hp + pad;
        l[i] = t - hm - pad;
    }
    *lo = tb__v3(l[0], l[1], l[2]);
    *hi = tb__v3(h[0], h[1], h[2]);
    return TB_OK;
}

tb_status tb_bounds_object(tb_prim_kind kind, const tb_mid_geometry *geom, tb_aabb *out)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "bounds: NULL output");
    tb_dvec3 lo, hi;
    tb_status st = tb__world_box(kind, geom, NULL, &lo, &hi);
    if (st)
        return st;
    *out = tb_bounds_round_out(lo, hi);
    return TB_OK;
}

tb_status tb_bounds_world(tb_prim_kind kind, const tb_mid_geometry *geom, const tb_transform *to_world,
                          tb_aabb *out)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "bounds: NULL output");
    tb__count(kind);
    if (to_world && !tb__affine(to_world)) {
        tb_aabb ob;
        tb_status st = tb_bounds_object(kind, geom, &ob);
        if (st)
            return st;
        *out = tb_transform_aabb(to_world, &ob);
        return TB_OK;
    }
    tb_dvec3 lo, hi;
    tb_status st = tb__world_box(kind, geom, to_world, &lo, &hi);
    if (st)
        return st;
    *out = tb_bounds_round_out(lo, hi);
    return TB_OK;
}

/* ------------------------------------------------------------------ spheres */

/* Largest singular value of the linear part: sqrt of the largest eigenvalue
 * of L^T L, by the trigonometric solution of the symmetric 3x3 eigenproblem
 * (Smith 1961), rounded up by a relative 1e-12. */
double tb_bounds_max_stretch(const tb_transform *t)
{
    if (!t)
        return 1.0;
    double a[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double s = 0.0;
            for (int k = 0; k < 3; k++)
                s += t->m.m[k][i] * t->m.m[k][j];
            a[i][j] = s;
        }
    double p1 = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    double q = (a[0][0] + a[1][1] + a[2][2]) / 3.0, lmax;
    if (p1 == 0.0) {
        lmax = fmax(a[0][0], fmax(a[1][1], a[2][2]));
    } else {
        double p2 = (a[0][0] - q) * (a[0][0] - q) + (a[1][1] - q) * (a[1][1] - q) + (a[2][2] - q) * (a[2][2] - q) + 2.0 * p1;
        double p = sqrt(p2 / 6.0), b[3][3];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                b[i][j] = (a[i][j] - (i == j ? q : 0.0)) / p;
        double detb = b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1]) - b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0]) +
                      b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0]);
        double phi = acos(tb_clamp(detb / 2.0, -1.0, 1.0)) / 3.0;
        lmax = q + 2.0 * p * cos(phi);
        /* The trace bound guards against rounding in the closed form. */
        lmax = fmin(fmax(lmax, q), 3.0 * q);
    }
    return sqrt(lmax) * (1.0 + 1e-12);
}

/* An object-space sphere (centre c on the z axis) holding the primitive:
 * returns its radius. */
static double tb__object_sphere(tb_prim_kind kind, const tb_mid_geometry *g, tb_dvec3 *c)
{
    *c = tb__v3(0, 0, 0);
    switch (kind) {
    case TB_PRIM_SPHERE:
        return 1.0;
    case TB_PRIM_CUBE:
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH:
        return sqrt(3.0);
    case TB_PRIM_CYLINDER:
    case TB_PRIM_CONE:
    case TB_PRIM_PYRAMID: {
        /* Two rims: radius 1 (square: half-diagonal sqrt 2) at z = -1 and r at
         * z = 1; the centre height equalising their distances, clamped. */
        double r0 = 1.0, r1 = kind == TB_PRIM_CYLINDER ? 1.0 : kind == TB_PRIM_CONE ? g->cone.top_radius : g->pyramid.top;
        if (kind == TB_PRIM_PYRAMID)
            r0 = sqrt(2.0), r1 *= sqrt(2.0);
        double zc = tb_clamp((r1 * r1 - r0 * r0) / 4.0, -1.0, 1.0);
        *c = tb__v3(0, 0, zc);
        return fmax(hypot(r0, zc + 1.0), hypot(r1, 1.0 - zc)) * (1.0 + 1e-15);
    }
    case TB_PRIM_PRISM: {
        const tb_geom_prism *pr = &g->prism;
        if (pr->sides > 0)
            return sqrt(2.0);
        double m = 0.0;
        for (int i = 0; i < pr->nprofile; i++)
            m = fmax(m, hypot(pr->profile[i].x, pr->profile[i].y));
        return hypot(m, 1.0) * (1.0 + 1e-15);
    }
    case TB_PRIM_TORUS:
        return g->torus.major + g->torus.minor;
    case TB_PRIM_CONIC: {
        /* Centre between the end rims as for the cone; the squared distance
         * q(z) + (z - zc)^2 is quadratic in z, so its maximum is at an end or
         * at its vertex. */
        const tb_geom_conic *k = &g->conic;
        double q0 = fmax(tb__conic_q(k, k->z0), 0.0), q1 = fmax(tb__conic_q(k, k->z1), 0.0);
        double zc = tb_clamp(0.5 * (k->z0 + k->z1) + (q1 - q0) / (2.0 * (k->z1 - k->z0)), k->z0, k->z1);
        double m = fmax(q0 + (k->z0 - zc) * (k->z0 - zc), q1 + (k->z1 - zc) * (k->z1 - zc));
        double A = k->c[2] + 1.0, B = k->c[1] - 2.0 * zc;
        if (A < 0.0) {
            double zv = -B / (2.0 * A);
            if (zv > k->z0 && zv < k->z1)
                m = fmax(m, tb__conic_q(k, zv) + (zv - zc) * (zv - zc));
        }
        *c = tb__v3(0, 0, zc);
        return sqrt(m) * (1.0 + 1e-14);
    }
    default:
        return INFINITY;
    }
}

/* The polyhedral kinds' vertices (at most 8) for the exact world sphere. */
static int tb__polyhedron_vertices(tb_prim_kind kind, const tb_mid_geometry *g, tb_dvec3 vs[8])
{
    if (kind == TB_PRIM_CUBE || kind == TB_PRIM_SQUARE_ARCH || kind == TB_PRIM_ROUND_ARCH ||
        kind == TB_PRIM_PYRAMID) {
        double t = kind == TB_PRIM_PYRAMID ? g->pyramid.top : 1.0;
        for (int i = 0; i < 8; i++) {
            double s = i < 4 ? 1.0 : t;
            vs[i] = tb__v3((i & 1) ? s : -s, (i & 2) ? s : -s, i < 4 ? -1.0 : 1.0);
        }
        return 8;
    }
    return 0;
}

tb_status tb_bounds_sphere(tb_prim_kind kind, const tb_mid_geometry *geom, const tb_transform *to_world,
                           tb_dvec3 *center, double *radius)
{
    if (!center || !radius)
        return tb_error(TB_ERR_ARG, "bounds: NULL output");
    tb_aabb box;
    tb_status st = tb_bounds_world(kind, geom, to_world, &box);
    if (st)
        return st;
    if (tb_aabb_is_empty(&box)) {
        *center = tb__v3(0, 0, 0), *radius = -INFINITY;
        return TB_OK;
    }
    tb_dvec3 lo = tb_vec3_to_d(box.lo), hi = tb_vec3_to_d(box.hi);
    tb_dvec3 c = tb_dvec3_scale(tb_dvec3_add(lo, hi), 0.5);
    double r = 0.5 * tb_dvec3_length(tb_dvec3_sub(hi, lo)) * (1.0 + 1e-15);
    tb_transform id = tb_transform_identity();
    const tb_transform *tw = to_world ? to_world : &id;
    if (kind == TB_PRIM_POLYGONS) {
        const tb_geom_polygons *p = &geom->polygons;
        double m = 0.0;
        int nidx = p->face_start[p->nfaces];
        for (int i = 0; i < nidx; i++)
            m = fmax(m, tb_dvec3_length(tb_dvec3_sub(tb_transform_dpoint(tw, tb_vec3_to_d(p->vertices[p->indices[i]])), c)));
        *center = c, *radius = fmin(r, m * (1.0 + 1e-14));
        return TB_OK;
    }
    tb_dvec3 vs[8];
    int nv = tb__polyhedron_vertices(kind, geom, vs);
    if (nv > 0 && tb__affine(tw)) {
        double m = 0.0;
        for (int i = 0; i < nv; i++)
            m = fmax(m, tb_dvec3_length(tb_dvec3_sub(tb_transform_dpoint(tw, vs[i]), c)));
        *center = c, *radius = fmin(r, m * (1.0 + 1e-14));
        return TB_OK;
    }
    if (tb__affine(tw)) {
        tb_dvec3 oc;
        double orad = tb__object_sphere(kind, geom, &oc) * tb_bounds_max_stretch(tw);
        if (orad < r) {
            *center = tb_transform_dpoint(tw, oc), *radius = orad;
            return TB_OK;
        }
    }
    *center = c, *radius = r;
    return TB_OK;
}

/* ----------------------------------------------------------- point sets, CSG */

tb_status tb_bounds_points(const tb_vec3 *pts, size_t n, const tb_transform *to_world, tb_aabb *out)
{
    if (!out || (n > 0 && !pts))
        return tb_error(TB_ERR_ARG, "bounds: NULL points or output");
    tb_dvec3 lo = {INFINITY, INFINITY, INFINITY}, hi = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < n; i++) {
        tb_dvec3 p = tb_vec3_to_d(pts[i]);
        if (to_world)
            p = tb_transform_dpoint(to_world, p);
        lo = tb_dvec3_min(lo, p), hi = tb_dvec3_max(hi, p);
    }
    *out = n > 0 && to_world ? tb_bounds_transformed(lo, hi) : tb_bounds_round_out(lo, hi);
    return TB_OK;
}

tb_aabb tb_bounds_transformed(tb_dvec3 lo, tb_dvec3 hi)
{
    /* Each transformed coordinate carries a few double roundings. */
    double pad = 0x1p-48 * fmax(tb_dvec3_max_comp(tb_dvec3_abs(lo)), tb_dvec3_max_comp(tb_dvec3_abs(hi)));
    lo = tb_dvec3_sub(lo, tb__v3(pad, pad, pad)), hi = tb_dvec3_add(hi, tb__v3(pad, pad, pad));
    return tb_bounds_round_out(lo, hi);
}

tb_status tb_bounds_points_sphere(const tb_vec3 *pts, size_t n, const tb_transform *to_world,
                                  tb_dvec3 *center, double *radius)
{
    if (!center || !radius)
        return tb_error(TB_ERR_ARG, "bounds: NULL output");
    tb_aabb box;
    tb_status st = tb_bounds_points(pts, n, to_world, &box);
    if (st)
        return st;
    if (n == 0) {
        *center = tb__v3(0, 0, 0), *radius = -INFINITY;
        return TB_OK;
    }
    tb_dvec3 c = tb_dvec3_scale(tb_dvec3_add(tb_vec3_to_d(box.lo), tb_vec3_to_d(box.hi)), 0.5);
    double m = 0.0;
    for (size_t i = 0; i < n; i++) {
        tb_dvec3 p = tb_vec3_to_d(pts[i]);
        if (to_world)
            p = tb_transform_dpoint(to_world, p);
        m = fmax(m, tb_dvec3_length(tb_dvec3_sub(p, c)));
    }
    *center = c, *radius = m * (1.0 + 1e-14);
    return TB_OK;
}

tb_aabb tb_bounds_csg(tb_prim_kind op, const tb_aabb *children, int n)
{
    TB_STAT_INC(tb__bounds_csg_calls);
    if (!children || n <= 0 || !tb_prim_is_csg(op))
        return tb_aabb_empty();
    if (op == TB_PRIM_DIFFERENCE)
        return children[0];
    tb_aabb b = children[0];
    for (int i = 1; i < n; i++)
        b = op == TB_PRIM_UNION ? tb_aabb_union(b, children[i]) : tb_aabb_intersection(b, children[i]);
    if (tb_aabb_is_empty(&b))
        return tb_aabb_empty();
    return b;
}
