/* Parametric coordinates of every primitive (docs/primitives.md, "Parametric
 * coordinates"). One file for the function, a switch over all kinds.
 *
 * Each face has two routines: eval (u, v) -> point, normal, tangents, and
 * project p -> (u, v) of a point of the face near p (exactly the nearest one
 * for points over the face's interior, which is all an intersection routine
 * ever passes). The nearest face of a point is the face minimising
 * |p - eval(project(p))|. */
#include "host/object/param.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include "util/container/array.h"
#include "util/math/float.h"
#include "util/mesh/triangulate.h"
#include "util/stats/stats.h"

/* Calls per kind and function: "Param/<kind> from point", "Param/<kind> eval". */
#define TB__PARAM_STATS(k, name)                                                                    \
    TB_STAT_COUNTER(tb__param_fp_##k, "Param/" name " from point");                                \
    TB_STAT_COUNTER(tb__param_ev_##k, "Param/" name " eval")
TB__PARAM_STATS(sphere, "sphere");
TB__PARAM_STATS(cube, "cube");
TB__PARAM_STATS(cylinder, "cylinder");
TB__PARAM_STATS(cone, "cone");
TB__PARAM_STATS(pyramid, "pyramid");
TB__PARAM_STATS(prism, "prism");
TB__PARAM_STATS(torus, "torus");
TB__PARAM_STATS(polygons, "polygons");
TB__PARAM_STATS(conic, "conic");
TB__PARAM_STATS(square_arch, "square_arch");
TB__PARAM_STATS(round_arch, "round_arch");

/* Counts one call of from_point (eval false) or eval (true) for `kind`. */
static void tb__param_count(tb_prim_kind kind, bool eval)
{
    static tb_stat *const fp[] = {&tb__param_fp_sphere, &tb__param_fp_cube, &tb__param_fp_cylinder,
                                  &tb__param_fp_cone, &tb__param_fp_pyramid, &tb__param_fp_prism,
                                  &tb__param_fp_torus, &tb__param_fp_polygons, &tb__param_fp_conic,
                                  &tb__param_fp_square_arch, &tb__param_fp_round_arch};
    static tb_stat *const ev[] = {&tb__param_ev_sphere, &tb__param_ev_cube, &tb__param_ev_cylinder,
                                  &tb__param_ev_cone, &tb__param_ev_pyramid, &tb__param_ev_prism,
                                  &tb__param_ev_torus, &tb__param_ev_polygons, &tb__param_ev_conic,
                                  &tb__param_ev_square_arch, &tb__param_ev_round_arch};
    if ((unsigned)kind < sizeof fp / sizeof fp[0])
        TB_STAT_INC(*(eval ? ev : fp)[kind]);
}

/* Everything eval gives. */
typedef struct tb__surf {
    tb_dvec3 p, n, dpdu, dpdv;
} tb__surf;

static tb_dvec3 tb__v(double x, double y, double z) { return (tb_dvec3){x, y, z}; }

static double tb__clamp01(double t) { return tb_clamp(t, 0.0, 1.0); }

/* u = phi / 2 pi in [0, 1) of the direction (x, y); 0 on the axis. */
static double tb__angle_u(double x, double y)
{
    if (x == 0.0 && y == 0.0)
        return 0.0;
    double phi = atan2(y, x);
    if (phi < 0.0)
        phi += TB_2PI;
    double u = phi * TB_INV_2PI;
    return u < 1.0 ? u : 0.0; /* phi + 2 pi may round up to 2 pi */
}

/* Closest point to (px, py) on the segment a-b; returns the squared distance. */
static double tb__seg_closest(double px, double py, double ax, double ay, double bx, double by,
                              double *cx, double *cy)
{
    double ex = bx - ax, ey = by - ay, l2 = ex * ex + ey * ey;
    double t = l2 > 0.0 ? tb__clamp01(((px - ax) * ex + (py - ay) * ey) / l2) : 0.0;
    *cx = ax + t * ex;
    *cy = ay + t * ey;
    double dx = px - *cx, dy = py - *cy;
    return dx * dx + dy * dy;
}

/* ------------------------------------------------------------- validation */

static bool tb__finite(double x) { return isfinite(x) != 0; }

/* The rounding error of s = a + b (Knuth's TwoSum). */
static double tb__two_sum_err(double a, double b, double s)
{
    double bb = s - a;
    return (a - (s - bb)) + (b - bb);
}

double tb_param_conic_r2(const tb_geom_conic *c, double z)
{
    /* Graillat, Langlois, Louvet, "Compensated Horner scheme" (2005). */
    double s = c->c[2], err = 0.0;
    for (int i = 1; i >= 0; i--) {
        double p = s * z, pe = fma(s, z, -p);
        double t = p + c->c[i], te = tb__two_sum_err(p, c->c[i], t);
        err = err * z + (pe + te);
        s = t;
    }
    double q = s + err;
    /* The reader's rule (docs/mid.md, 6.3): within 1e-12 of the size of the
     * terms r^2 is 0, so coefficients meant to touch the axis (a pole, an
     * apex) do, instead of leaving a waist of radius ~1e-6 from their rounding. */
    double terms = fabs(c->c[0]) + fabs(c->c[1] * z) + fabs(c->c[2] * z * z);
    return fabs(q) <= 1e-12 * terms ? 0.0 : q;
}

static double tb__conic_q(const tb_geom_conic *c, double z) { return tb_param_conic_r2(c, z); }

int tb_param_prism_npoints(const tb_geom_prism *g) { return g->sides > 0 ? g->sides : g->nprofile; }

tb_status tb_param_check(tb_prim_kind kind, const tb_mid_geometry *g)
{
    if (!g && kind != TB_PRIM_SPHERE && kind != TB_PRIM_CUBE)
        return tb_error(TB_ERR_ARG, "param: NULL geometry for %s", tb_prim_kind_name(kind));
    switch (kind) {
    case TB_PRIM_SPHERE:
    case TB_PRIM_CUBE:
    case TB_PRIM_CYLINDER:
        return TB_OK;
    case TB_PRIM_CONE:
        if (!(g->cone.top_radius >= 0.0) || !tb__finite(g->cone.top_radius))
            return tb_error(TB_ERR_ARG, "param: cone top_radius %g is not >= 0", g->cone.top_radius);
        return TB_OK;
    case TB_PRIM_PYRAMID:
        if (!(g->pyramid.top >= 0.0) || !tb__finite(g->pyramid.top))
            return tb_error(TB_ERR_ARG, "param: pyramid top %g is not >= 0", g->pyramid.top);
        return TB_OK;
    case TB_PRIM_PRISM:
        if (g->prism.sides > 0 ? g->prism.sides < 3 : (g->prism.nprofile < 3 || !g->prism.profile))
            return tb_error(TB_ERR_ARG, "param: prism needs >= 3 sides or profile points");
        return TB_OK;
    case TB_PRIM_TORUS:
        if (!(g->torus.minor > 0.0 && g->torus.minor < g->torus.major) || !tb__finite(g->torus.major))
            return tb_error(TB_ERR_ARG, "param: torus needs 0 < minor < major (got %g, %g)",
                            g->torus.minor, g->torus.major);
        return TB_OK;
    case TB_PRIM_POLYGONS:
        if (g->polygons.mesh.text)
            return tb_error(TB_ERR_UNSUPPORTED, "param: polygons from a FED mesh file: use the loaded mesh");
        if (g->polygons.nfaces < 0 || (g->polygons.nfaces > 0 && (!g->polygons.face_start ||
                                                                  !g->polygons.indices ||
                                                                  !g->polygons.vertices)))
            return tb_error(TB_ERR_ARG, "param: polygons without vertex or face arrays");
        return TB_OK;
    case TB_PRIM_CONIC: {
        const tb_geom_conic *c = &g->conic;
        if (!(c->z0 < c->z1) || !tb__finite(c->z0) || !tb__finite(c->z1) || !tb__finite(c->c[0]) ||
            !tb__finite(c->c[1]) || !tb__finite(c->c[2]))
            return tb_error(TB_ERR_ARG, "param: conic needs finite coefficients and z0 < z1");
        return TB_OK;
    }
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH: {
        double w = g->arch.width, h = g->arch.height;
        bool ok = w > 0.0 && w < 2.0 && h > 0.0 && h < 2.0 &&
                  (kind == TB_PRIM_SQUARE_ARCH || h >= 0.5 * w);
        if (!ok)
            return tb_error(TB_ERR_ARG, "param: %s width %g / height %g out of range",
                            tb_prim_kind_name(kind), w, h);
        return TB_OK;
    }
    default:
        return tb_error(TB_ERR_ARG, "param: %s has no parametric coordinates", tb_prim_kind_name(kind));
    }
}

int tb_param_face_count(tb_prim_kind kind, const tb_mid_geometry *geom)
{
    if (tb_param_check(kind, geom) != TB_OK)
        return 0;
    switch (kind) {
    case TB_PRIM_SPHERE: return 1;
    case TB_PRIM_CUBE: return 6;
    case TB_PRIM_CYLINDER: return 3;
    case TB_PRIM_CONE: return 3;
    case TB_PRIM_PYRAMID: return 6;
    case TB_PRIM_PRISM: return TB_FACE_PRISM_SIDE0 + tb_param_prism_npoints(&geom->prism);
    case TB_PRIM_TORUS: return 1;
    case TB_PRIM_POLYGONS: return geom->polygons.nfaces;
    case TB_PRIM_CONIC: return 3;
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH: return TB_FACE_ARCH_COUNT;
    default: return 0;
    }
}

bool tb_param_face_present(tb_prim_kind kind, const tb_mid_geometry *g, int face)
{
    if (face < 0 || face >= tb_param_face_count(kind, g))
        return false;
    switch (kind) {
    case TB_PRIM_CYLINDER:
        return face == TB_FACE_CYLINDER_SIDE || g->cylinder.caps;
    case TB_PRIM_CONE:
        if (face == TB_FACE_CONE_SIDE)
            return true;
        return g->cone.caps && (face == TB_FACE_CONE_BOTTOM || g->cone.top_radius > 0.0);
    case TB_PRIM_PYRAMID:
        if (face < TB_FACE_PYRAMID_BOTTOM)
            return true;
        return g->pyramid.caps && (face == TB_FACE_PYRAMID_BOTTOM || g->pyramid.top > 0.0);
    case TB_PRIM_PRISM:
        return face >= TB_FACE_PRISM_SIDE0 || g->prism.caps;
    case TB_PRIM_CONIC:
        if (face == TB_FACE_CONIC_SIDE)
            return true;
        return g->conic.caps &&
               tb__conic_q(&g->conic, face == TB_FACE_CONIC_BOTTOM ? g->conic.z0 : g->conic.z1) > 0.0;
    case TB_PRIM_ROUND_ARCH:
        /* The straight walls under the vault vanish when h = w/2. */
        if (face == TB_FACE_ARCH_INNER_LEFT || face == TB_FACE_ARCH_INNER_RIGHT)
            return g->arch.height > 0.5 * g->arch.width;
        return true;
    default:
        return true;
    }
}

/* ------------------------------------------------------------ shared faces */

/* A disc of radius R at height zc about the z axis, polar parameters:
 * bottom (normal -z): rho = R v; top (normal +z): rho = R (1 - v). */
static void tb__disc_eval(double R, double zc, bool top, double u, double v, tb__surf *s)
{
    double phi = TB_2PI * u, c = cos(phi), sn = sin(phi);
    double rho = top ? R * (1.0 - v) : R * v;
    double dr = top ? -R : R;
    s->p = tb__v(rho * c, rho * sn, zc);
    s->n = tb__v(0.0, 0.0, top ? 1.0 : -1.0);
    s->dpdu = tb__v(-TB_2PI * rho * sn, TB_2PI * rho * c, 0.0);
    s->dpdv = tb__v(dr * c, dr * sn, 0.0);
}

static void tb__disc_project(double R, bool top, tb_dvec3 p, double *u, double *v)
{
    double rho = hypot(p.x, p.y);
    *u = tb__angle_u(p.x, p.y);
    double t = R > 0.0 ? tb__clamp01(rho / R) : 0.0;
    *v = top ? 1.0 - t : t;
}

/* The side of a cube-like face: outward axis a (unit), lateral axis b, with
 * p = s a + s (2u - 1) b + (2v - 1) z. Faces 0..3 = -x, +x, -y, +y. */
static void tb__side_axes(int face, tb_dvec3 *a, tb_dvec3 *b)
{
    switch (face) {
    case 0: *a = tb__v(-1, 0, 0); *b = tb__v(0, -1, 0); break;
    case 1: *a = tb__v(1, 0, 0); *b = tb__v(0, 1, 0); break;
    case 2: *a = tb__v(0, -1, 0); *b = tb__v(1, 0, 0); break;
    default: *a = tb__v(0, 1, 0); *b = tb__v(-1, 0, 0); break;
    }
}

/* Side `face` (0..3) of a pyramid frustum with half-size 1 at z = -1 and t at
 * z = 1 (t = 1: the cube). */
static void tb__pyr_side_eval(int face, double t, double u, double v, tb__surf *s)
{
    tb_dvec3 a, b;
    tb__side_axes(face, &a, &b);
    double sc = 1.0 + (t - 1.0) * v, l = 2.0 * u - 1.0;
    s->p = tb_dvec3_add(tb_dvec3_add(tb_dvec3_scale(a, sc), tb_dvec3_scale(b, sc * l)), tb__v(0, 0, 2.0 * v - 1.0));
    s->dpdu = tb_dvec3_scale(b, 2.0 * sc);
    s->dpdv = tb_dvec3_add(tb_dvec3_add(tb_dvec3_scale(a, t - 1.0), tb_dvec3_scale(b, (t - 1.0) * l)), tb__v(0, 0, 2.0));
    double k = 1.0 / sqrt(4.0 + (1.0 - t) * (1.0 - t));
    s->n = tb_dvec3_add(tb_dvec3_scale(a, 2.0 * k), tb__v(0, 0, (1.0 - t) * k));
}

static void tb__pyr_side_project(int face, double t, tb_dvec3 p, double *u, double *v)
{
    tb_dvec3 a, b;
    tb__side_axes(face, &a, &b);
    if (t != 1.0) {
        /* Drop p onto the face's plane first (through s a - z at v = 0). */
        double k = 1.0 / sqrt(4.0 + (1.0 - t) * (1.0 - t));
        tb_dvec3 n = tb_dvec3_add(tb_dvec3_scale(a, 2.0 * k), tb__v(0, 0, (1.0 - t) * k));
        double d = tb_dvec3_dot(tb_dvec3_sub(p, tb__v(a.x, a.y, -1.0)), n);
        p = tb_dvec3_sub(p, tb_dvec3_scale(n, d));
    }
    *v = tb__clamp01(0.5 * (p.z + 1.0));
    double sc = 1.0 + (t - 1.0) * *v;
    *u = sc > 0.0 ? tb__clamp01(0.5 * (tb_dvec3_dot(p, b) / sc + 1.0)) : 0.0;
}

/* Horizontal rectangle [x0,x1] x [y0,y1] at height z, as the cube's -z (bottom)
 * or +z (top) face: bottom p = (x0 + u dx, y1 - v dy, z), top (x0 + u dx, y0 + v dy, z). */
static void tb__rect_z_eval(double x0, double x1, double y0, double y1, double z, bool top, double u,
                            double v, tb__surf *s)
{
    double dx = x1 - x0, dy = y1 - y0;
    s->p = tb__v(x0 + u * dx, top ? y0 + v * dy : y1 - v * dy, z);
    s->n = tb__v(0, 0, top ? 1.0 : -1.0);
    s->dpdu = tb__v(dx, 0, 0);
    s->dpdv = tb__v(0, top ? dy : -dy, 0);
}

/* (u, v) of the point (x, y) on such a rectangle's plane (not clamped). */
static void tb__rect_z_uv(double x0, double x1, double y0, double y1, bool top, double x, double y,
                          double *u, double *v)
{
    double dx = x1 - x0, dy = y1 - y0;
    *u = dx > 0.0 ? (x - x0) / dx : 0.0;
    *v = dy > 0.0 ? (top ? (y - y0) / dy : (y1 - y) / dy) : 0.0;
}

/* ------------------------------------------------------------------ sphere */

static void tb__sphere_eval(double u, double v, tb__surf *s)
{
    double phi = TB_2PI * u, th = TB_PI * v;
    double cp = cos(phi), sp = sin(phi), ct = cos(th), st = sin(th);
    s->p = tb__v(st * cp, st * sp, -ct);
    s->n = s->p;
    s->dpdu = tb__v(-TB_2PI * st * sp, TB_2PI * st * cp, 0.0);
    s->dpdv = tb__v(TB_PI * ct * cp, TB_PI * ct * sp, TB_PI * st);
    if (v == 0.0 || v == 1.0) /* poles: exact points, no u direction */
        s->p = s->n = tb__v(0.0, 0.0, v == 0.0 ? -1.0 : 1.0), s->dpdu = tb__v(0, 0, 0);
}

static void tb__sphere_project(tb_dvec3 p, double *u, double *v)
{
    *u = tb__angle_u(p.x, p.y);
    *v = tb__clamp01(atan2(hypot(p.x, p.y), -p.z) * TB_INV_PI);
}

/* ----------------------------------------------------- revolved profiles */

/* Side of a cylinder or cone frustum: radius 1 at z = -1 to r at z = 1. */
static void tb__cone_side_eval(double r, double u, double v, tb__surf *s)
{
    double phi = TB_2PI * u, c = cos(phi), sn = sin(phi);
    double rho = 1.0 + (r - 1.0) * v;
    if (v == 1.0)
        rho = r; /* exact apex / top rim */
    s->p = tb__v(rho * c, rho * sn, 2.0 * v - 1.0);
    s->dpdu = tb__v(-TB_2PI * rho * sn, TB_2PI * rho * c, 0.0);
    s->dpdv = tb__v((r - 1.0) * c, (r - 1.0) * sn, 2.0);
    double k = 1.0 / sqrt(4.0 + (1.0 - r) * (1.0 - r));
    s->n = tb__v(2.0 * k * c, 2.0 * k * sn, (1.0 - r) * k);
}

static void tb__cone_side_project(double r, tb_dvec3 p, double *u, double *v)
{
    double rho = hypot(p.x, p.y);
    *u = tb__angle_u(p.x, p.y);
    if (r == 1.0) {
        *v = tb__clamp01(0.5 * (p.z + 1.0));
        return;
    }
    /* Nearest point of the meridian segment (1, -1) - (r, 1) in the (rho, z) plane. */
    double ex = r - 1.0, ez = 2.0;
    *v = tb__clamp01(((rho - 1.0) * ex + (p.z + 1.0) * ez) / (ex * ex + ez * ez));
}

/* Conic side: z = z0 + (z1 - z0) v, rho = sqrt(q(z)). */
static void tb__conic_side_eval(const tb_geom_conic *c, double u, double v, tb__surf *s)
{
    double dz = c->z1 - c->z0, z = v == 1.0 ? c->z1 : c->z0 + dz * v;
    double q = tb__conic_q(c, z), rho = tb_safe_sqrt(q);
    double dq = c->c[1] + 2.0 * c->c[2] * z; /* dq/dz */
    double phi = TB_2PI * u, cp = cos(phi), sp = sin(phi);
    s->p = tb__v(rho * cp, rho * sp, z);
    s->dpdu = tb__v(-TB_2PI * rho * sp, TB_2PI * rho * cp, 0.0);
    if (rho > 0.0) {
        double dr = dq / (2.0 * rho); /* drho/dz */
        s->dpdv = tb__v(dz * dr * cp, dz * dr * sp, dz);
        /* Gradient of x^2 + y^2 - q(z), pointing away from the axis. */
        s->n = tb_dvec3_normalize(tb__v(2.0 * rho * cp, 2.0 * rho * sp, -dq));
    } else {
        /* Pole: drho/dz is unbounded (or two-sided at a double root). */
        s->dpdv = tb__v(0, 0, 0);
        double sgn = dq != 0.0 ? (dq > 0.0 ? -1.0 : 1.0) : (z >= 0.5 * (c->z0 + c->z1) ? 1.0 : -1.0);
        s->n = tb__v(0, 0, sgn);
    }
}

/* Squared distance in the meridian plane from (rho, z) to the profile at z'. */
static double tb__conic_d2(const tb_geom_conic *c, double rho, double z, double zz)
{
    double dr = rho - tb_safe_sqrt(tb__conic_q(c, zz)), d = z - zz;
    return dr * dr + d * d;
}

static void tb__conic_side_project(const tb_geom_conic *c, tb_dvec3 p, double *u, double *v)
{
    double rho = hypot(p.x, p.y), dz = c->z1 - c->z0;
    *u = tb__angle_u(p.x, p.y);
    double zc = tb_clamp(p.z, c->z0, c->z1);
    double scale = fmax(fmax(fabs(c->z0), fabs(c->z1)), 1.0);
    if (zc == p.z && fabs(rho - tb_safe_sqrt(tb__conic_q(c, zc))) <= 1e-12 * scale) {
        *v = tb__clamp01((zc - c->z0) / dz); /* on the surface: v is linear in z */
        return;
    }
    /* Off the surface: minimise the meridian distance over [z0, z1] by sampling
     * and golden-section refinement of the best bracket. */
    enum { N = 48 };
    int best = 0;
    double bd = INFINITY;
    for (int i = 0; i <= N; i++) {
        double zz = i == N ? c->z1 : c->z0 + dz * i / N;
        double d = tb__conic_d2(c, rho, p.z, zz);
        if (d < bd)
            bd = d, best = i;
    }
    double a = c->z0 + dz * (best > 0 ? best - 1 : 0) / N;
    double b = best < N ? c->z0 + dz * (best + 1) / N : c->z1;
    const double g = 0.6180339887498949;
    double x1 = b - g * (b - a), x2 = a + g * (b - a);
    double f1 = tb__conic_d2(c, rho, p.z, x1), f2 = tb__conic_d2(c, rho, p.z, x2);
    for (int it = 0; it < 60 && b - a > 1e-15 * scale; it++) {
        if (f1 < f2)
            b = x2, x2 = x1, f2 = f1, x1 = b - g * (b - a), f1 = tb__conic_d2(c, rho, p.z, x1);
        else
            a = x1, x1 = x2, f1 = f2, x2 = a + g * (b - a), f2 = tb__conic_d2(c, rho, p.z, x2);
    }
    double zb = 0.5 * (a + b);
    if (tb__conic_d2(c, rho, p.z, zb) > bd)
        zb = c->z0 + dz * best / N;
    *v = tb__clamp01((zb - c->z0) / dz);
}

/* ------------------------------------------------------------------- torus */

static void tb__torus_eval(const tb_geom_torus *t, double u, double v, tb__surf *s)
{
    double phi = TB_2PI * u, psi = TB_2PI * v;
    double cp = cos(phi), sp = sin(phi), cs = cos(psi), ss = sin(psi);
    double rho = t->major + t->minor * cs;
    s->p = tb__v(rho * cp, rho * sp, t->minor * ss);
    s->n = tb__v(cs * cp, cs * sp, ss);
    s->dpdu = tb__v(-TB_2PI * rho * sp, TB_2PI * rho * cp, 0.0);
    s->dpdv = tb__v(-TB_2PI * t->minor * ss * cp, -TB_2PI * t->minor * ss * sp, TB_2PI * t->minor * cs);
}

static void tb__torus_project(const tb_geom_torus *t, tb_dvec3 p, double *u, double *v)
{
    *u = tb__angle_u(p.x, p.y);
    *v = tb__angle_u(hypot(p.x, p.y) - t->major, p.z);
}

/* ------------------------------------------------------------------- prism */

void tb_param_prism_point(const tb_geom_prism *g, int k, double *x, double *y)
{
    int n = tb_param_prism_npoints(g);
    k %= n;
    if (k < 0)
        k += n;
    if (g->sides > 0) {
        double a = TB_2PI * k / n;
        *x = cos(a), *y = sin(a);
        if (k == 0)
            *x = 1.0, *y = 0.0;
    } else {
        *x = g->profile[k].x, *y = g->profile[k].y;
    }
}

bool tb_param_prism_ccw(const tb_geom_prism *g)
{
    if (g->sides > 0)
        return true;
    double a = 0.0;
    int n = g->nprofile;
    for (int i = 0; i < n; i++) {
        const tb_vec2 *p = &g->profile[i], *q = &g->profile[(i + 1) % n];
        a += (double)p->x * q->y - (double)q->x * p->y;
    }
    return a > 0.0;
}

/* The polygon's bounding rectangle. */
static void tb__prism_bbox(const tb_geom_prism *g, double *x0, double *x1, double *y0, double *y1)
{
    int n = tb_param_prism_npoints(g);
    if (g->sides > 0) {
        /* The extremes are at the points nearest the angles 0, pi/2, pi, 3pi/2. */
        int ks[8] = {0, 0, n / 4, (n + 3) / 4, n / 2, (n + 1) / 2, 3 * n / 4, (3 * n + 3) / 4};
        *x0 = *y0 = INFINITY, *x1 = *y1 = -INFINITY;
        for (int i = 0; i < 8; i++) {
            double x, y;
            tb_param_prism_point(g, ks[i], &x, &y);
            *x0 = fmin(*x0, x), *x1 = fmax(*x1, x), *y0 = fmin(*y0, y), *y1 = fmax(*y1, y);
        }
        return;
    }
    *x0 = *y0 = INFINITY, *x1 = *y1 = -INFINITY;
    for (int i = 0; i < n; i++) {
        double x = g->profile[i].x, y = g->profile[i].y;
        *x0 = fmin(*x0, x), *x1 = fmax(*x1, x), *y0 = fmin(*y0, y), *y1 = fmax(*y1, y);
    }
}

/* The edge of side k oriented counter-clockwise: from a to b. */
static void tb__prism_edge(const tb_geom_prism *g, bool ccw, int k, double *ax, double *ay, double *bx,
                           double *by)
{
    if (ccw) {
        tb_param_prism_point(g, k, ax, ay);
        tb_param_prism_point(g, k + 1, bx, by);
    } else {
        tb_param_prism_point(g, k + 1, ax, ay);
        tb_param_prism_point(g, k, bx, by);
    }
}

static void tb__prism_side_eval(const tb_geom_prism *g, bool ccw, int k, double u, double v, tb__surf *s)
{
    double ax, ay, bx, by;
    tb__prism_edge(g, ccw, k, &ax, &ay, &bx, &by);
    double ex = bx - ax, ey = by - ay, l = hypot(ex, ey);
    s->p = tb__v(u == 1.0 ? bx : ax + u * ex, u == 1.0 ? by : ay + u * ey, 2.0 * v - 1.0);
    s->dpdu = tb__v(ex, ey, 0.0);
    s->dpdv = tb__v(0.0, 0.0, 2.0);
    s->n = l > 0.0 ? tb__v(ey / l, -ex / l, 0.0) : tb__v(0, 0, 0);
}

static void tb__prism_side_project(const tb_geom_prism *g, bool ccw, int k, tb_dvec3 p, double *u, double *v)
{
    double ax, ay, bx, by;
    tb__prism_edge(g, ccw, k, &ax, &ay, &bx, &by);
    double ex = bx - ax, ey = by - ay, l2 = ex * ex + ey * ey;
    *u = l2 > 0.0 ? tb__clamp01(((p.x - ax) * ex + (p.y - ay) * ey) / l2) : 0.0;
    *v = tb__clamp01(0.5 * (p.z + 1.0));
}

/* Even-odd test of (x, y) against the polygon; for a regular polygon only the
 * edge of the point's sector is looked at. */
static bool tb__prism_inside(const tb_geom_prism *g, double x, double y)
{
    int n = tb_param_prism_npoints(g);
    if (g->sides > 0) {
        int k = (int)floor(tb__angle_u(x, y) * n);
        if (k >= n)
            k = n - 1;
        double ax, ay, bx, by;
        tb_param_prism_point(g, k, &ax, &ay);
        tb_param_prism_point(g, k + 1, &bx, &by);
        return (bx - ax) * (y - ay) - (by - ay) * (x - ax) >= 0.0;
    }
    bool in = false;
    for (int i = 0, j = n - 1; i < n; j = i++) {
        double xi = g->profile[i].x, yi = g->profile[i].y, xj = g->profile[j].x, yj = g->profile[j].y;
        if ((yi > y) != (yj > y) && x < xj + (y - yj) * (xi - xj) / (yi - yj))
            in = !in;
    }
    return in;
}

/* The point of the (filled) polygon nearest to (x, y). */
static void tb__prism_cap_closest(const tb_geom_prism *g, double *x, double *y)
{
    if (tb__prism_inside(g, *x, *y))
        return;
    int n = tb_param_prism_npoints(g), k0 = 0, k1 = n;
    if (g->sides > 0) {
        /* Outside a regular polygon the nearest edge is in or next to the sector. */
        int k = (int)floor(tb__angle_u(*x, *y) * n);
        k0 = k - 1, k1 = k + 2;
        if (n < 4)
            k0 = 0, k1 = n;
    }
    double bd = INFINITY, bx = *x, by = *y;
    for (int k = k0; k < k1; k++) {
        double ax, ay, cx, cy, qx, qy;
        tb_param_prism_point(g, k, &ax, &ay);
        tb_param_prism_point(g, k + 1, &cx, &cy);
        double d = tb__seg_closest(*x, *y, ax, ay, cx, cy, &qx, &qy);
        if (d < bd)
            bd = d, bx = qx, by = qy;
    }
    *x = bx, *y = by;
}

/* -------------------------------------------------------------------- arches */

/* Opening dimensions: half-width a, the height where the straight walls end
 * (square: -1 + h, the ceiling; round: zs, the vault's axis). */
static void tb__arch_dims(tb_prim_kind kind, const tb_geom_arch *g, double *a, double *zw)
{
    *a = 0.5 * g->width;
    *zw = kind == TB_PRIM_SQUARE_ARCH ? -1.0 + g->height : -1.0 + g->height - 0.5 * g->width;
}

/* True if (x, z) lies in the open interior of the opening's cross-section. */
static bool tb__arch_in_opening(tb_prim_kind kind, double a, double zw, double x, double z)
{
    if (!(fabs(x) < a))
        return false;
    if (z < zw)
        return true;
    if (kind == TB_PRIM_SQUARE_ARCH)
        return false;
    double dz = z - zw;
    return x * x + dz * dz < a * a;
}

/* The point of the front/back face region (square [-1,1]^2 in (x, z) minus the
 * opening) nearest to (x, z). */
static void tb__arch_face_closest(tb_prim_kind kind, double a, double zw, double *x, double *z)
{
    bool in_square = fabs(*x) <= 1.0 && fabs(*z) <= 1.0;
    if (in_square && !tb__arch_in_opening(kind, a, zw, *x, *z))
        return;
    /* The region's boundary: the square's edges (the bottom one minus the gap)
     * and the opening's walls and top. */
    double segs[][4] = {
        {-1, -1, -1, 1}, {1, -1, 1, 1}, {-1, 1, 1, 1}, {-1, -1, -a, -1}, {a, -1, 1, -1},
        {-a, -1, -a, zw}, {a, -1, a, zw}, {-a, zw, a, zw},
    };
    int nseg = kind == TB_PRIM_SQUARE_ARCH ? 8 : 7;
    double bd = INFINITY, bx = *x, bz = *z;
    for (int i = 0; i < nseg; i++) {
        double qx, qz;
        double d = tb__seg_closest(*x, *z, segs[i][0], segs[i][1], segs[i][2], segs[i][3], &qx, &qz);
        if (d < bd)
            bd = d, bx = qx, bz = qz;
    }
    if (kind == TB_PRIM_ROUND_ARCH) {
        double th = atan2(*z - zw, *x);
        if (th < 0.0)
            th = th > -TB_PI_2 ? 0.0 : TB_PI;
        double qx = a * cos(th), qz = zw + a * sin(th), dx = *x - qx, dz = *z - qz;
        if (dx * dx + dz * dz < bd)
            bx = qx, bz = qz;
    }
    *x = bx, *z = bz;
}

static void tb__arch_eval(tb_prim_kind kind, const tb_geom_arch *g, int face, double u, double v, tb__surf *s)
{
    double a, zw;
    tb__arch_dims(kind, g, &a, &zw);
    switch (face) {
    case TB_FACE_ARCH_NEG_X:
    case TB_FACE_ARCH_POS_X:
    case TB_FACE_ARCH_NEG_Y:
    case TB_FACE_ARCH_POS_Y:
        tb__pyr_side_eval(face, 1.0, u, v, s);
        return;
    case TB_FACE_ARCH_BOTTOM:
        tb__rect_z_eval(-1, 1, -1, 1, -1, false, u, v, s);
        return;
    case TB_FACE_ARCH_TOP:
        tb__rect_z_eval(-1, 1, -1, 1, 1, true, u, v, s);
        return;
    case TB_FACE_ARCH_INNER_LEFT:
    case TB_FACE_ARCH_INNER_RIGHT: {
        double H = zw + 1.0, sg = face == TB_FACE_ARCH_INNER_LEFT ? 1.0 : -1.0;
        s->p = tb__v(-sg * a, sg * (2.0 * u - 1.0), v == 1.0 ? zw : -1.0 + v * H);
        s->n = tb__v(sg, 0, 0);
        s->dpdu = tb__v(0, 2.0 * sg, 0);
        s->dpdv = tb__v(0, 0, H);
        return;
    }
    default:
        if (kind == TB_PRIM_SQUARE_ARCH) {
            s->p = tb__v(-a + 2.0 * a * u, 1.0 - 2.0 * v, zw);
            s->n = tb__v(0, 0, -1);
            s->dpdu = tb__v(2.0 * a, 0, 0);
            s->dpdv = tb__v(0, -2.0, 0);
        } else {
            double th = TB_PI * u, c = cos(th), sn = sin(th);
            if (u == 0.5)
                c = 0.0;
            s->p = tb__v(a * c, 2.0 * v - 1.0, zw + a * sn);
            s->n = tb__v(-c, 0, -sn);
            s->dpdu = tb__v(-TB_PI * a * sn, 0, TB_PI * a * c);
            s->dpdv = tb__v(0, 2.0, 0);
        }
        return;
    }
}

static void tb__arch_project(tb_prim_kind kind, const tb_geom_arch *g, int face, tb_dvec3 p, double *u, double *v)
{
    double a, zw;
    tb__arch_dims(kind, g, &a, &zw);
    switch (face) {
    case TB_FACE_ARCH_NEG_X:
    case TB_FACE_ARCH_POS_X:
    case TB_FACE_ARCH_TOP:
        if (face == TB_FACE_ARCH_TOP) {
            *u = tb__clamp01(0.5 * (p.x + 1.0)), *v = tb__clamp01(0.5 * (p.y + 1.0));
        } else {
            tb__pyr_side_project(face, 1.0, p, u, v);
        }
        return;
    case TB_FACE_ARCH_NEG_Y:
    case TB_FACE_ARCH_POS_Y: {
        double x = p.x, z = p.z;
        tb__arch_face_closest(kind, a, zw, &x, &z);
        double l = face == TB_FACE_ARCH_NEG_Y ? x : -x;
        *u = tb__clamp01(0.5 * (l + 1.0)), *v = tb__clamp01(0.5 * (z + 1.0));
        return;
    }
    case TB_FACE_ARCH_BOTTOM: {
        double x = tb_clamp(p.x, -1.0, 1.0), y = tb_clamp(p.y, -1.0, 1.0);
        if (fabs(x) < a)
            x = x < 0.0 ? -a : a; /* the opening reaches the ground */
        *u = tb__clamp01(0.5 * (x + 1.0)), *v = tb__clamp01(0.5 * (1.0 - y));
        return;
    }
    case TB_FACE_ARCH_INNER_LEFT:
    case TB_FACE_ARCH_INNER_RIGHT: {
        double H = zw + 1.0, sg = face == TB_FACE_ARCH_INNER_LEFT ? 1.0 : -1.0;
        *u = tb__clamp01(0.5 * (sg * p.y + 1.0));
        *v = H > 0.0 ? tb__clamp01((p.z + 1.0) / H) : 0.0;
        return;
    }
    default:
        if (kind == TB_PRIM_SQUARE_ARCH) {
            *u = tb__clamp01((p.x + a) / (2.0 * a)), *v = tb__clamp01(0.5 * (1.0 - p.y));
        } else {
            double th = atan2(p.z - zw, p.x);
            if (th < 0.0)
                th = th > -TB_PI_2 ? 0.0 : TB_PI;
            *u = tb__clamp01(th * TB_INV_PI), *v = tb__clamp01(0.5 * (p.y + 1.0));
        }
        return;
    }
}

/* ---------------------------------------------------------------- polygons */

typedef tb_poly_frame tb__poly_frame;

/* Corner i of a loop: v[idx[i]], or v[i] without idx. */
static tb_dvec3 tb__cv(const tb_vec3 *v, const int *idx, int i) { return tb_vec3_to_d(v[idx ? idx[i] : i]); }

static tb_dvec3 tb__pv(const tb_geom_polygons *g, int face, int i)
{
    return tb__cv(g->vertices, g->indices + g->face_start[face], i);
}

static int tb__poly_nv(const tb_geom_polygons *g, int face) { return g->face_start[face + 1] - g->face_start[face]; }

bool tb_poly_frame_make(const tb_vec3 *v, const int *idx, int nv, tb_poly_frame *f)
{
    f->ncst = 0;
    /* Newell normal, relative to the first vertex. */
    tb_dvec3 o = tb__cv(v, idx, 0), nn = {0, 0, 0};
    for (int i = 0; i < nv; i++) {
        tb_dvec3 a = tb_dvec3_sub(tb__cv(v, idx, i), o), b = tb_dvec3_sub(tb__cv(v, idx, (i + 1) % nv), o);
        nn.x += (a.y - b.y) * (a.z + b.z);
        nn.y += (a.z - b.z) * (a.x + b.x);
        nn.z += (a.x - b.x) * (a.y + b.y);
    }
    double ln = tb_dvec3_length(nn);
    if (!(ln > 0.0) || !isfinite(ln))
        return false;
    f->n = tb_dvec3_scale(nn, 1.0 / ln);
    f->o = o;
    tb_dvec3 e = {0, 0, 0};
    for (int i = 1; i < nv; i++) {
        e = tb_dvec3_sub(tb__cv(v, idx, i), o);
        /* Keep only the part in the plane, so the frame is orthonormal. */
        e = tb_dvec3_sub(e, tb_dvec3_scale(f->n, tb_dvec3_dot(e, f->n)));
        if (tb_dvec3_length(e) > 0.0)
            break;
    }
    f->e1 = tb_dvec3_normalize(e);
    f->e2 = tb_dvec3_cross(f->n, f->e1);
    double s0 = INFINITY, s1 = -INFINITY, t0 = INFINITY, t1 = -INFINITY;
    /* The corners' (s, t) are kept for small loops: every (u, v) of a point
     * needs them (inside test, nearest edge), and they are tb__poly_st's
     * values (the same operations), so using them changes no bit. */
    f->ncst = nv <= TB_POLY_FRAME_CORNERS ? nv : 0;
    for (int i = 0; i < nv; i++) {
        tb_dvec3 d = tb_dvec3_sub(tb__cv(v, idx, i), o);
        double s = tb_dvec3_dot(d, f->e1), t = tb_dvec3_dot(d, f->e2);
        /* Comparisons, not fmin/fmax (library calls here): the same for
         * finite values, and zeros keep the first seen. */
        s0 = s < s0 ? s : s0, s1 = s > s1 ? s : s1, t0 = t < t0 ? t : t0, t1 = t > t1 ? t : t1;
        if (i < f->ncst)
            f->cst[i][0] = s, f->cst[i][1] = t;
    }
    f->s0 = s0, f->ds = s1 - s0, f->t0 = t0, f->dt = t1 - t0;
    return true;
}

static tb_status tb__poly_frame_of(const tb_geom_polygons *g, int face, tb__poly_frame *f)
{
    int nv = tb__poly_nv(g, face);
    if (nv < 3)
        return tb_error(TB_ERR_ARG, "param: polygon %d has %d vertices", face, nv);
    for (int i = 0; i < nv; i++) {
        int idx = g->indices[g->face_start[face] + i];
        if (idx < 0 || idx >= g->nvertices)
            return tb_error(TB_ERR_ARG, "param: polygon %d: vertex index %d out of range", face, idx);
    }
    if (!tb_poly_frame_make(g->vertices, g->indices + g->face_start[face], nv, f))
        return tb_error(TB_ERR_ARG, "param: polygon %d has no area", face);
    return TB_OK;
}

/* Plane coordinates (s, t) of p in the frame. */
static void tb__poly_st(const tb__poly_frame *f, tb_dvec3 p, double *s, double *t)
{
    tb_dvec3 d = tb_dvec3_sub(p, f->o);
    *s = tb_dvec3_dot(d, f->e1), *t = tb_dvec3_dot(d, f->e2);
}

/* Plane coordinates of corner i of the loop the frame was made from. */
static inline void tb__corner_st(const tb__poly_frame *f, const tb_vec3 *v, const int *idx, int i, double *s,
                                 double *t)
{
    if (i < f->ncst)
        *s = f->cst[i][0], *t = f->cst[i][1];
    else
        tb__poly_st(f, tb__cv(v, idx, i), s, t);
}

/* The point of the loop (its projection on the frame's plane, filled by the
 * even-odd rule) nearest to (s, t). */
static void tb__poly_closest(const tb__poly_frame *f, const tb_vec3 *v, const int *idx, int nv, double *s, double *t)
{
    /* Inside first (most points are): the nearest edge point only when outside. */
    bool in = false;
    double ps, pt;
    tb__corner_st(f, v, idx, nv - 1, &ps, &pt);
    for (int i = 0; i < nv; i++) {
        double qs, qt;
        tb__corner_st(f, v, idx, i, &qs, &qt);
        if ((qt > *t) != (pt > *t) && *s < ps + (*t - pt) * (qs - ps) / (qt - pt))
            in = !in;
        ps = qs, pt = qt;
    }
    if (in)
        return;
    double bd = INFINITY, bs = *s, bt = *t;
    tb__corner_st(f, v, idx, nv - 1, &ps, &pt);
    for (int i = 0; i < nv; i++) {
        double qs, qt, cs, ct;
        tb__corner_st(f, v, idx, i, &qs, &qt);
        double d = tb__seg_closest(*s, *t, ps, pt, qs, qt, &cs, &ct);
        if (d < bd)
            bd = d, bs = cs, bt = ct;
        ps = qs, pt = qt;
    }
    *s = bs, *t = bt;
}

void tb_poly_frame_uv(const tb_poly_frame *f, const tb_vec3 *v, const int *idx, int nv, tb_dvec3 p, double *u,
                      double *w)
{
    double s, t;
    tb__poly_st(f, p, &s, &t);
    tb__poly_closest(f, v, idx, nv, &s, &t);
    *u = f->ds > 0.0 ? tb__clamp01((s - f->s0) / f->ds) : 0.0;
    *w = f->dt > 0.0 ? tb__clamp01((t - f->t0) / f->dt) : 0.0;
}

/* A polygon's triangles as corner numbers (0 .. nv-1) into its loop: the fan
 * from corner 0 when the loop is convex in its plane, else util/mesh's
 * ear-clipping triangulation of the loop's plane coordinates. */
bool tb_poly_frame_convex(const tb_poly_frame *f, const tb_vec3 *v, const int *idx, int nv)
{
    double ps, pt, qs, qt;
    tb__corner_st(f, v, idx, nv - 2, &ps, &pt);
    tb__corner_st(f, v, idx, nv - 1, &qs, &qt);
    for (int i = 0; i < nv; i++) {
        double rs, rt;
        tb__corner_st(f, v, idx, i, &rs, &rt);
        if ((qs - ps) * (rt - pt) - (qt - pt) * (rs - ps) < 0.0)
            return false;
        ps = qs, pt = qt, qs = rs, qt = rt;
    }
    return true;
}

/* Barycentric coordinates of (x, y) in the 2D triangle a b c; false if degenerate. */
static bool tb__bary2(double x, double y, const double a[2], const double b[2], const double c[2], double w[3]);
/* How far outside the triangle barycentric weights are (0 inside). */
static double tb__bary_out(const double w[3]);

/* (s, t) of p (nearest point of the loop when outside it) to (u, v) by the
 * uvs of the triangle holding it (or coming closest); tri(j, c) gives the
 * corner numbers (0 .. nv-1) of triangle j of n. False when every triangle
 * is degenerate in the plane. */
static bool tb__poly_tex_uv(const tb_poly_frame *f, const tb_vec3 *v, const int *idx, const tb_vec2 *uvs, int nv,
                            const uint32_t (*tc)[3], int n, tb_dvec3 p, double *u, double *w)
{
    double s, t;
    tb__poly_st(f, p, &s, &t);
    tb__poly_closest(f, v, idx, nv, &s, &t);
    int best = -1;
    double bw[3] = {0, 0, 0}, bo = INFINITY;
    int bc[3] = {0, 0, 0};
    for (int j = 0; j < n; j++) {
        int c[3];
        if (!tc)
            c[0] = 0, c[1] = j + 1, c[2] = j + 2;
        else
            c[0] = (int)tc[j][0], c[1] = (int)tc[j][1], c[2] = (int)tc[j][2];
        double P[3][2];
        for (int i = 0; i < 3; i++)
            tb__corner_st(f, v, idx, c[i], &P[i][0], &P[i][1]);
        double wt[3];
        if (!tb__bary2(s, t, P[0], P[1], P[2], wt))
            continue;
        double o = tb__bary_out(wt);
        if (o < bo)
            bo = o, best = j, bw[0] = wt[0], bw[1] = wt[1], bw[2] = wt[2], bc[0] = c[0], bc[1] = c[1], bc[2] = c[2];
        if (o == 0.0)
            break;
    }
    if (best < 0)
        return false;
    tb_vec2 a = uvs[idx ? idx[bc[0]] : bc[0]], b = uvs[idx ? idx[bc[1]] : bc[1]], c = uvs[idx ? idx[bc[2]] : bc[2]];
    *u = tb__clamp01(bw[0] * a.x + bw[1] * b.x + bw[2] * c.x);
    *w = tb__clamp01(bw[0] * a.y + bw[1] * b.y + bw[2] * c.y);
    return true;
}

void tb_poly_fan_uv(const tb_poly_frame *f, const tb_vec3 *v, const int *idx, const tb_vec2 *uvs, int nv, tb_dvec3 p,
                    double *u, double *w)
{
    if (!tb__poly_tex_uv(f, v, idx, uvs, nv, NULL, nv - 2, p, u, w))
        *u = *w = 0.0;
}

typedef struct tb__poly_tris {
    int n;           /* triangles */
    uint32_t (*c)[3]; /* corners, or NULL for the fan */
    tb_array tris;   /* storage of the triangulated case */
} tb__poly_tris;

static void tb__poly_tris_free(tb__poly_tris *t) { tb_array_free(&t->tris); }

static tb_status tb__poly_tris_of(const tb_geom_polygons *g, int face, const tb__poly_frame *f, tb__poly_tris *t)
{
    int nv = tb__poly_nv(g, face);
    tb_array_init(&t->tris, sizeof(tb_tri));
    t->n = nv - 2, t->c = NULL;
    if (nv == 3)
        return TB_OK;
    if (tb_poly_frame_convex(f, g->vertices, g->indices + g->face_start[face], nv))
        return TB_OK;
    double *xy = malloc(sizeof(double) * 2 * (size_t)nv);
    if (!xy)
        return tb_error(TB_ERR_NOMEM, "param: out of memory");
    for (int i = 0; i < nv; i++)
        tb__poly_st(f, tb__pv(g, face, i), &xy[2 * i], &xy[2 * i + 1]);
    uint32_t ring = (uint32_t)nv;
    tb_status st = tb_triangulate_2d(xy, &ring, 1, &t->tris, NULL);
    free(xy);
    if (st)
        return st;
    t->n = (int)t->tris.len;
    t->c = (uint32_t(*)[3])t->tris.data;
    return TB_OK;
}

/* Vertex indices of triangle j. */
static void tb__poly_tri(const tb_geom_polygons *g, int face, const tb__poly_tris *t, int j, int c[3])
{
    int b = g->face_start[face];
    if (!t->c) {
        c[0] = g->indices[b], c[1] = g->indices[b + j + 1], c[2] = g->indices[b + j + 2];
        return;
    }
    for (int i = 0; i < 3; i++)
        c[i] = g->indices[b + (int)t->c[j][i]];
}

/* Barycentric coordinates of (x, y) in the 2D triangle a b c; false if degenerate. */
static bool tb__bary2(double x, double y, const double a[2], const double b[2], const double c[2], double w[3])
{
    double d = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
    if (d == 0.0 || !isfinite(d))
        return false;
    w[1] = ((x - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (y - a[1])) / d;
    w[2] = ((b[0] - a[0]) * (y - a[1]) - (x - a[0]) * (b[1] - a[1])) / d;
    w[0] = 1.0 - w[1] - w[2];
    return true;
}

/* How far outside the triangle barycentric weights are (0 inside). */
static double tb__bary_out(const double w[3])
{
    return fmax(0.0, -fmin(w[0], fmin(w[1], w[2])));
}

static tb_status tb__poly_eval(const tb_geom_polygons *g, int face, double u, double v, tb__surf *s)
{
    tb__poly_frame f;
    tb_status st = tb__poly_frame_of(g, face, &f);
    if (st)
        return st;
    s->n = f.n;
    if (!g->uvs) {
        s->p = tb_dvec3_add(f.o, tb_dvec3_add(tb_dvec3_scale(f.e1, f.s0 + u * f.ds),
                                              tb_dvec3_scale(f.e2, f.t0 + v * f.dt)));
        s->dpdu = tb_dvec3_scale(f.e1, f.ds);
        s->dpdv = tb_dvec3_scale(f.e2, f.dt);
        return TB_OK;
    }
    /* Find the triangle whose uv image holds (u, v) (or comes closest). */
    tb__poly_tris tr;
    if ((st = tb__poly_tris_of(g, face, &f, &tr)))
        return st;
    int best = -1;
    double bw[3] = {0, 0, 0}, bo = INFINITY;
    for (int j = 0; j < tr.n; j++) {
        int c[3];
        tb__poly_tri(g, face, &tr, j, c);
        double A[2] = {g->uvs[c[0]].x, g->uvs[c[0]].y}, B[2] = {g->uvs[c[1]].x, g->uvs[c[1]].y},
               C[2] = {g->uvs[c[2]].x, g->uvs[c[2]].y}, w[3];
        if (!tb__bary2(u, v, A, B, C, w))
            continue;
        double o = tb__bary_out(w);
        if (o < bo)
            bo = o, best = j, bw[0] = w[0], bw[1] = w[1], bw[2] = w[2];
        if (o == 0.0)
            break;
    }
    int c[3];
    if (best >= 0)
        tb__poly_tri(g, face, &tr, best, c);
    tb__poly_tris_free(&tr);
    if (best < 0)
        return tb_error(TB_ERR_ARG, "param: polygon %d has degenerate uvs", face);
    tb_dvec3 P[3];
    double U[3], V[3];
    for (int i = 0; i < 3; i++)
        P[i] = tb_vec3_to_d(g->vertices[c[i]]), U[i] = g->uvs[c[i]].x, V[i] = g->uvs[c[i]].y;
    s->p = tb_dvec3_add(tb_dvec3_add(tb_dvec3_scale(P[0], bw[0]), tb_dvec3_scale(P[1], bw[1])),
                        tb_dvec3_scale(P[2], bw[2]));
    /* Tangents of the affine map (u, v) -> p on that triangle. */
    tb_dvec3 e1 = tb_dvec3_sub(P[1], P[0]), e2 = tb_dvec3_sub(P[2], P[0]);
    double du1 = U[1] - U[0], du2 = U[2] - U[0], dv1 = V[1] - V[0], dv2 = V[2] - V[0];
    double det = du1 * dv2 - du2 * dv1;
    s->dpdu = tb_dvec3_scale(tb_dvec3_sub(tb_dvec3_scale(e1, dv2), tb_dvec3_scale(e2, dv1)), 1.0 / det);
    s->dpdv = tb_dvec3_scale(tb_dvec3_sub(tb_dvec3_scale(e2, du1), tb_dvec3_scale(e1, du2)), 1.0 / det);
    /* Float vertices leave the triangle's plane a rounding away from the
     * polygon's: keep the tangents perpendicular to the normal returned. */
    s->dpdu = tb_dvec3_sub(s->dpdu, tb_dvec3_scale(f.n, tb_dvec3_dot(s->dpdu, f.n)));
    s->dpdv = tb_dvec3_sub(s->dpdv, tb_dvec3_scale(f.n, tb_dvec3_dot(s->dpdv, f.n)));
    return TB_OK;
}

static tb_status tb__poly_project(const tb_geom_polygons *g, int face, tb_dvec3 p, double *u, double *v)
{
    tb__poly_frame f;
    tb_status st = tb__poly_frame_of(g, face, &f);
    if (st)
        return st;
    const int *idx = g->indices + g->face_start[face];
    int nv = tb__poly_nv(g, face);
    if (!g->uvs) {
        tb_poly_frame_uv(&f, g->vertices, idx, nv, p, u, v);
        return TB_OK;
    }
    tb__poly_tris tr;
    if ((st = tb__poly_tris_of(g, face, &f, &tr)))
        return st;
    if (!tb__poly_tex_uv(&f, g->vertices, idx, g->uvs, nv, (const uint32_t(*)[3])tr.c, tr.n, p, u, v))
        *u = *v = 0.0;
    tb__poly_tris_free(&tr);
    return TB_OK;
}

/* ------------------------------------------------------------- dispatching */

/* eval without argument checks. */
static tb_status tb__eval(tb_prim_kind kind, const tb_mid_geometry *g, int face, double u, double v, tb__surf *s)
{
    switch (kind) {
    case TB_PRIM_SPHERE:
        tb__sphere_eval(u, v, s);
        return TB_OK;
    case TB_PRIM_CUBE:
        if (face < 4)
            tb__pyr_side_eval(face, 1.0, u, v, s);
        else
            tb__rect_z_eval(-1, 1, -1, 1, face == TB_FACE_CUBE_NEG_Z ? -1.0 : 1.0, face == TB_FACE_CUBE_POS_Z, u, v, s);
        return TB_OK;
    case TB_PRIM_CYLINDER:
        if (face == TB_FACE_CYLINDER_SIDE)
            tb__cone_side_eval(1.0, u, v, s);
        else
            tb__disc_eval(1.0, face == TB_FACE_CYLINDER_TOP ? 1.0 : -1.0, face == TB_FACE_CYLINDER_TOP, u, v, s);
        return TB_OK;
    case TB_PRIM_CONE:
        if (face == TB_FACE_CONE_SIDE)
            tb__cone_side_eval(g->cone.top_radius, u, v, s);
        else if (face == TB_FACE_CONE_BOTTOM)
            tb__disc_eval(1.0, -1.0, false, u, v, s);
        else
            tb__disc_eval(g->cone.top_radius, 1.0, true, u, v, s);
        return TB_OK;
    case TB_PRIM_PYRAMID: {
        double t = g->pyramid.top;
        if (face < 4)
            tb__pyr_side_eval(face, t, u, v, s);
        else if (face == TB_FACE_PYRAMID_BOTTOM)
            tb__rect_z_eval(-1, 1, -1, 1, -1, false, u, v, s);
        else
            tb__rect_z_eval(-t, t, -t, t, 1, true, u, v, s);
        return TB_OK;
    }
    case TB_PRIM_PRISM: {
        const tb_geom_prism *pr = &g->prism;
        if (face >= TB_FACE_PRISM_SIDE0) {
            tb__prism_side_eval(pr, tb_param_prism_ccw(pr), face - TB_FACE_PRISM_SIDE0, u, v, s);
        } else {
            double x0, x1, y0, y1;
            tb__prism_bbox(pr, &x0, &x1, &y0, &y1);
            bool top = face == TB_FACE_PRISM_TOP;
            tb__rect_z_eval(x0, x1, y0, y1, top ? 1.0 : -1.0, top, u, v, s);
        }
        return TB_OK;
    }
    case TB_PRIM_TORUS:
        tb__torus_eval(&g->torus, u, v, s);
        return TB_OK;
    case TB_PRIM_POLYGONS:
        return tb__poly_eval(&g->polygons, face, u, v, s);
    case TB_PRIM_CONIC: {
        const tb_geom_conic *c = &g->conic;
        if (face == TB_FACE_CONIC_SIDE)
            tb__conic_side_eval(c, u, v, s);
        else if (face == TB_FACE_CONIC_BOTTOM)
            tb__disc_eval(tb_safe_sqrt(tb__conic_q(c, c->z0)), c->z0, false, u, v, s);
        else
            tb__disc_eval(tb_safe_sqrt(tb__conic_q(c, c->z1)), c->z1, true, u, v, s);
        return TB_OK;
    }
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH:
        tb__arch_eval(kind, &g->arch, face, u, v, s);
        return TB_OK;
    default:
        return tb_error(TB_ERR_ARG, "param: %s has no parametric coordinates", tb_prim_kind_name(kind));
    }
}

/* project without argument checks. */
static tb_status tb__project(tb_prim_kind kind, const tb_mid_geometry *g, int face, tb_dvec3 p, double *u, double *v)
{
    switch (kind) {
    case TB_PRIM_SPHERE:
        tb__sphere_project(p, u, v);
        return TB_OK;
    case TB_PRIM_CUBE:
        if (face < 4) {
            tb__pyr_side_project(face, 1.0, p, u, v);
        } else {
            bool top = face == TB_FACE_CUBE_POS_Z;
            tb__rect_z_uv(-1, 1, -1, 1, top, p.x, p.y, u, v);
            *u = tb__clamp01(*u), *v = tb__clamp01(*v);
        }
        return TB_OK;
    case TB_PRIM_CYLINDER:
        if (face == TB_FACE_CYLINDER_SIDE)
            tb__cone_side_project(1.0, p, u, v);
        else
            tb__disc_project(1.0, face == TB_FACE_CYLINDER_TOP, p, u, v);
        return TB_OK;
    case TB_PRIM_CONE:
        if (face == TB_FACE_CONE_SIDE)
            tb__cone_side_project(g->cone.top_radius, p, u, v);
        else if (face == TB_FACE_CONE_BOTTOM)
            tb__disc_project(1.0, false, p, u, v);
        else
            tb__disc_project(g->cone.top_radius, true, p, u, v);
        return TB_OK;
    case TB_PRIM_PYRAMID: {
        double t = g->pyramid.top;
        if (face < 4) {
            tb__pyr_side_project(face, t, p, u, v);
        } else {
            bool top = face == TB_FACE_PYRAMID_TOP;
            double h = top ? t : 1.0;
            tb__rect_z_uv(-h, h, -h, h, top, p.x, p.y, u, v);
            *u = tb__clamp01(*u), *v = tb__clamp01(*v);
        }
        return TB_OK;
    }
    case TB_PRIM_PRISM: {
        const tb_geom_prism *pr = &g->prism;
        if (face >= TB_FACE_PRISM_SIDE0) {
            tb__prism_side_project(pr, tb_param_prism_ccw(pr), face - TB_FACE_PRISM_SIDE0, p, u, v);
        } else {
            double x0, x1, y0, y1, x = p.x, y = p.y;
            tb__prism_bbox(pr, &x0, &x1, &y0, &y1);
            tb__prism_cap_closest(pr, &x, &y);
            tb__rect_z_uv(x0, x1, y0, y1, face == TB_FACE_PRISM_TOP, x, y, u, v);
            *u = tb__clamp01(*u), *v = tb__clamp01(*v);
        }
        return TB_OK;
    }
    case TB_PRIM_TORUS:
        tb__torus_project(&g->torus, p, u, v);
        return TB_OK;
    case TB_PRIM_POLYGONS:
        return tb__poly_project(&g->polygons, face, p, u, v);
    case TB_PRIM_CONIC: {
        const tb_geom_conic *c = &g->conic;
        if (face == TB_FACE_CONIC_SIDE)
            tb__conic_side_project(c, p, u, v);
        else if (face == TB_FACE_CONIC_BOTTOM)
            tb__disc_project(tb_safe_sqrt(tb__conic_q(c, c->z0)), false, p, u, v);
        else
            tb__disc_project(tb_safe_sqrt(tb__conic_q(c, c->z1)), true, p, u, v);
        return TB_OK;
    }
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH:
        tb__arch_project(kind, &g->arch, face, p, u, v);
        return TB_OK;
    default:
        return tb_error(TB_ERR_ARG, "param: %s has no parametric coordinates", tb_prim_kind_name(kind));
    }
}

double tb_param_face_distance(tb_prim_kind kind, const tb_mid_geometry *geom, int face, tb_dvec3 p)
{
    if (!tb_param_face_present(kind, geom, face) || !tb_dvec3_isfinite(p))
        return INFINITY;
    double u, v;
    tb__surf s;
    if (tb__project(kind, geom, face, p, &u, &v) || tb__eval(kind, geom, face, u, v, &s))
        return INFINITY;
    return tb_dvec3_length(tb_dvec3_sub(p, s.p));
}

/* Faces worth measuring for the nearest-face search: all of them, except the
 * sides of a regular prism, where only the sector's side and its neighbours
 * can be nearest. */
static void tb__candidate_faces(tb_prim_kind kind, const tb_mid_geometry *g, tb_dvec3 p, int *lo, int *hi,
                                int *extra_lo, int *extra_hi)
{
    *lo = 0, *hi = tb_param_face_count(kind, g);
    *extra_lo = *extra_hi = 0;
    if (kind == TB_PRIM_PRISM && g->prism.sides > 8) {
        int n = g->prism.sides, k = (int)floor(tb__angle_u(p.x, p.y) * n);
        *lo = 0, *hi = TB_FACE_PRISM_SIDE0;
        *extra_lo = k - 1, *extra_hi = k + 2; /* side indices, taken mod n */
    }
}

tb_status tb_param_from_point(tb_prim_kind kind, const tb_mid_geometry *geom, tb_dvec3 p, int face_hint,
                              int *face, double *u, double *v)
{
    tb__param_count(kind, false);
    tb_status st = tb_param_check(kind, geom);
    if (st)
        return st;
    if (!face || !u || !v)
        return tb_error(TB_ERR_ARG, "param: NULL output");
    if (!tb_dvec3_isfinite(p))
        return tb_error(TB_ERR_ARG, "param: point (%g, %g, %g) is not finite", p.x, p.y, p.z);
    if (face_hint >= 0) {
        if (!tb_param_face_present(kind, geom, face_hint))
            return tb_error(TB_ERR_ARG, "param: %s has no face %d", tb_prim_kind_name(kind), face_hint);
        st = tb__project(kind, geom, face_hint, p, u, v);
        if (st)
            return st;
        *face = face_hint;
        return TB_OK;
    }
    int lo, hi, elo, ehi, best = -1;
    double bd = INFINITY;
    tb__candidate_faces(kind, geom, p, &lo, &hi, &elo, &ehi);
    for (int f = lo; f < hi; f++) {
        double d = tb_param_face_distance(kind, geom, f, p);
        if (d < bd)
            bd = d, best = f;
    }
    if (elo < ehi) {
        /* Regular prism sides, in ID order so ties still go to the lower ID. */
        int n = geom->prism.sides, ids[3], m = 0;
        for (int k = elo; k < ehi; k++)
            ids[m++] = TB_FACE_PRISM_SIDE0 + ((k % n) + n) % n;
        for (int i = 0; i < m; i++) {
            double d = tb_param_face_distance(kind, geom, ids[i], p);
            if (d < bd || (d == bd && ids[i] < best))
                bd = d, best = ids[i];
        }
    }
    if (best < 0)
        return tb_error(TB_ERR_ARG, "param: %s has no faces", tb_prim_kind_name(kind));
    *face = best;
    return tb__project(kind, geom, best, p, u, v);
}

tb_status tb_param_eval(tb_prim_kind kind, const tb_mid_geometry *geom, int face, double u, double v,
                        tb_dvec3 *p, tb_dvec3 *n, tb_dvec3 *dpdu, tb_dvec3 *dpdv)
{
    tb__param_count(kind, true);
    tb_status st = tb_param_check(kind, geom);
    if (st)
        return st;
    if (!(u >= 0.0 && u <= 1.0 && v >= 0.0 && v <= 1.0))
        return tb_error(TB_ERR_ARG, "param: (u, v) = (%g, %g) outside [0, 1]^2", u, v);
    if (!tb_param_face_present(kind, geom, face))
        return tb_error(TB_ERR_ARG, "param: %s has no face %d", tb_prim_kind_name(kind), face);
    tb__surf s;
    st = tb__eval(kind, geom, face, u, v, &s);
    if (st)
        return st;
    if (p)
        *p = s.p;
    if (n)
        *n = s.n;
    if (dpdu)
        *dpdu = s.dpdu;
    if (dpdv)
        *dpdv = s.dpdv;
    return TB_OK;
}

tb_status tb_param_from_point_world(tb_prim_kind kind, const tb_mid_geometry *geom, const tb_transform *to_world,
                                    tb_dvec3 p_world, int face_hint, int *face, double *u, double *v)
{
    if (!to_world)
        return tb_error(TB_ERR_ARG, "param: NULL transform");
    tb_transform inv = tb_transform_inverse(to_world);
    return tb_param_from_point(kind, geom, tb_transform_dpoint(&inv, p_world), face_hint, face, u, v);
}

tb_status tb_param_eval_world(tb_prim_kind kind, const tb_mid_geometry *geom, const tb_transform *to_world,
                              int face, double u, double v, tb_dvec3 *p, tb_dvec3 *n, tb_dvec3 *dpdu,
                              tb_dvec3 *dpdv)
{
    if (!to_world)
        return tb_error(TB_ERR_ARG, "param: NULL transform");
    tb_dvec3 op, on, du, dv;
    tb_status st = tb_param_eval(kind, geom, face, u, v, &op, &on, &du, &dv);
    if (st)
        return st;
    if (p)
        *p = tb_transform_dpoint(to_world, op);
    if (n) {
        tb_dvec3 w = tb_transform_dnormal(to_world, on);
        double l = tb_dvec3_length(w);
        *n = l > 0.0 ? tb_dvec3_scale(w, 1.0 / l) : w;
    }
    if (dpdu)
        *dpdu = tb_transform_dvector(to_world, du);
    if (dpdv)
        *dpdv = tb_transform_dvector(to_world, dv);
    return TB_OK;
}
