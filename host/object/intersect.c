/* Ray intersection for every kind: the public queries, the switch over kinds,
 * the hit record and the recomputed hit point with its error bound
 * (docs/primitives.md, "Intersection" and "Robustness"). The per-family
 * solvers are in intersect_quadric.c, intersect_planar.c, intersect_mesh.c;
 * CSG in csg.c. */
#include "host/object/intersect.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "host/object/csg.h"
#include "host/object/intersect_internal.h"
#include "host/object/param.h"
#include "util/math/float.h"
#include "util/stats/stats.h"

/* ------------------------------------------------------------------ statistics */

TB_STAT_COUNTER(tb__n_sphere, "Intersect/sphere");
TB_STAT_COUNTER(tb__n_cube, "Intersect/cube");
TB_STAT_COUNTER(tb__n_cylinder, "Intersect/cylinder");
TB_STAT_COUNTER(tb__n_cone, "Intersect/cone");
TB_STAT_COUNTER(tb__n_pyramid, "Intersect/pyramid");
TB_STAT_COUNTER(tb__n_prism, "Intersect/prism");
TB_STAT_COUNTER(tb__n_torus, "Intersect/torus");
TB_STAT_COUNTER(tb__n_polygons, "Intersect/polygons");
TB_STAT_COUNTER(tb__n_conic, "Intersect/conic");
TB_STAT_COUNTER(tb__n_square_arch, "Intersect/square_arch");
TB_STAT_COUNTER(tb__n_round_arch, "Intersect/round_arch");
TB_STAT_COUNTER(tb__n_union, "Intersect/union");
TB_STAT_COUNTER(tb__n_intersection, "Intersect/intersection");
TB_STAT_COUNTER(tb__n_difference, "Intersect/difference");
TB_STAT_COUNTER(tb__n_invalid, "Intersect/invalid rays");

tb_stat *const tb__kind_counters[TB_PRIM_COUNT] = {
    &tb__n_sphere, &tb__n_cube, &tb__n_cylinder, &tb__n_cone, &tb__n_pyramid,
    &tb__n_prism, &tb__n_torus, &tb__n_polygons, &tb__n_conic, &tb__n_square_arch,
    &tb__n_round_arch, &tb__n_union, &tb__n_intersection, &tb__n_difference,
};

/* ------------------------------------------------------------------ crossings */

bool tb__xbuf_grow(tb__xbuf *b)
{
    if (b->oom)
        return false;
    int cap = b->cap * 2;
    tb__xing *x = b->x == b->local ? malloc(sizeof *x * (size_t)cap) : realloc(b->x, sizeof *x * (size_t)cap);
    if (!x || cap <= b->cap) {
        b->oom = true;
        return false;
    }
    if (b->x == b->local)
        memcpy(x, b->local, sizeof b->local);
    b->x = x;
    b->cap = cap;
    return true;
}

void tb__prim_xings(const tb_object *o, const tb__oray *r, tb__xbuf *out)
{
    tb__count_kind(o->kind);
    switch (o->kind) {
    case TB_PRIM_SPHERE: tb__xings_sphere(o, r, out); break;
    case TB_PRIM_CUBE: tb__xings_cube(o, r, out); break;
    case TB_PRIM_CYLINDER:
    case TB_PRIM_CONE:
    case TB_PRIM_CONIC: tb__xings_revolved(o, r, out); break;
    case TB_PRIM_PYRAMID: tb__xings_pyramid(o, r, out); break;
    case TB_PRIM_PRISM: tb__xings_prism(o, r, out); break;
    case TB_PRIM_TORUS: tb__xings_torus(o, r, out); break;
    case TB_PRIM_POLYGONS: tb__xings_mesh(o, r, out); break;
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH: tb__xings_arch(o, r, out); break;
    default: break; /* CSG nodes go through tb__csg_xings */
    }
}

bool tb__prim_any(const tb_object *o, const tb__oray *r, double tmin, double tmax)
{
    switch (o->kind) {
    case TB_PRIM_SPHERE: tb__count_kind(o->kind); return tb__any_sphere(o, r, tmin, tmax);
    case TB_PRIM_CYLINDER:
    case TB_PRIM_CONE:
    case TB_PRIM_CONIC: tb__count_kind(o->kind); return tb__any_revolved(o, r, tmin, tmax);
    case TB_PRIM_TORUS:
        if (tb__torus_clear(o, r, tmin, tmax)) {
            tb__count_kind(o->kind);
            return false;
        }
        break;
    default: break;
    }
    tb__xbuf b;
    tb__xbuf_init(&b);
    tb__prim_xings(o, r, &b);
    bool any = false;
    for (int i = 0; i < b.n && !any; i++) /* tb__closest's range test */
        any = (float)b.x[i].t >= tmin && (float)b.x[i].t <= tmax;
    tb__xbuf_free(&b);
    return any;
}

/* The closest crossing of obj with t in [tmin, tmax] (double). */
static bool tb__closest(const tb_object *obj, const tb_ray *ray, double tmin, double tmax, tb__xing *hit)
{
    if (obj->kind == TB_PRIM_POLYGONS) {
        tb__count_kind(obj->kind);
        return tb__mesh_closest(obj, ray, tmin, tmax, hit); /* world space: no object ray */
    }
    tb__xbuf b;
    tb__xbuf_init(&b);
    if (tb_prim_is_csg(obj->kind)) {
        tb__csg_xings_in(obj, ray, tmin, tmax, &b);
    } else {
        tb__oray r = tb__object_ray(obj, ray);
        tb__prim_xings(obj, &r, &b);
    }
    bool found = false;
    /* The range is checked on t rounded to float, the t the caller sees: a
     * hit reported at t is found again with tmin = t or tmax = t. */
    for (int i = 0; i < b.n; i++)
        if ((float)b.x[i].t >= tmin && (float)b.x[i].t <= tmax) {
            *hit = b.x[i];
            found = true;
            break;
        }
    tb__xbuf_free(&b);
    return found;
}

/* ------------------------------------------------------------------ queries */

static bool tb__ray_ok(const tb_ray *ray)
{
    if (tb_ray_is_valid(ray))
        return true;
    tb_stat_add(&tb__n_invalid, 1);
    return false;
}

/* World-space unit normal of crossing x (flipped for subtracted CSG leaves). */
static tb_vec3 tb__world_normal(const tb__xing *x)
{
    tb_dvec3 n = tb_transform_dnormal(&x->leaf->to_world, x->n);
    double l = tb_dvec3_length(n);
    if (!(l > 0.0) || !isfinite(l))
        return (tb_vec3){0.0f, 0.0f, 1.0f};
    double s = (x->leaf->flip ? -1.0 : 1.0) / l;
    return (tb_vec3){(float)(n.x * s), (float)(n.y * s), (float)(n.z * s)};
}

/* The crossing of this thread's last successful tb_object_intersect (or
 * the triangle tb_object_note_triangle_hit was given, without x.n), with
 * its object and ray (o, d, tmin), so that tb_object_hit_point on the
 * winner of a scene query need not sweep (CSG trees, meshes) again. */
typedef struct tb__last_xing {
    const tb_object *obj;
    unsigned long gen; /* tb__object_generation when stored: x.leaf points into obj's tree */
    tb_vec3 o, d;
    float tmin;
    tb__xing x;
} tb__last_xing;

static _Thread_local tb__last_xing tb__last;

/* tb_object_intersect, with (u, v) computed only when `uv` is set (else 0):
 * the rest of the record does not depend on them. */
static inline bool tb__object_intersect(const tb_object *obj, const tb_ray *ray, tb_hit *hit, bool uv)
{
    if (!obj || !ray || !tb__ray_ok(ray))
        return false;
    tb__xing x;
    if (!tb__closest(obj, ray, ray->tmin, ray->tmax, &x))
        return false;
    tb__last = (tb__last_xing){obj, tb__object_generation, ray->o, ray->d, ray->tmin, x};
    const tb_object *leaf = x.leaf;
    double u = 0.0, v = 0.0, uvw[3];
    /* A triangle's (u, v): the mix of its corners' by the test's weights
     * (docs/primitives.md, "Parametric coordinates"), else from the point. */
    if (uv && !(leaf->kind == TB_PRIM_POLYGONS && tb__mesh_tri_weights(leaf, x.tri, ray, uvw) &&
                tb_object_triangle_uv(leaf, x.tri, uvw, &u, &v))) {
        tb__oray r = tb__object_ray(leaf, ray);
        tb_dvec3 p = {r.o.x + x.t * r.d.x, r.o.y + x.t * r.d.y, r.o.z + x.t * r.d.z};
        int face = (int)x.face;
        if (tb_param_from_point(leaf->kind, &leaf->geom, p, face, &face, &u, &v) != TB_OK)
            u = v = 0.0;
    }
    hit->t = (float)x.t;
    hit->object = obj->index;
    hit->face = leaf->face_base + x.face;
    hit->u = (float)u;
    hit->v = (float)v;
    /* A triangle's normal is kept by its mesh (the same formula). */
    hit->ng = leaf->kind == TB_PRIM_POLYGONS ? tb_object_triangle_normal(leaf, x.tri) : tb__world_normal(&x);
    return true;
}

bool tb_object_intersect(const tb_object *obj, const tb_ray *ray, tb_hit *hit)
{
    return tb__object_intersect(obj, ray, hit, true);
}

bool tb_object_intersect_no_uv(const tb_object *obj, const tb_ray *ray, tb_hit *hit)
{
    return tb__object_intersect(obj, ray, hit, false);
}

void tb_object_note_triangle_hit(const tb_object *obj, const tb_ray *ray, uint32_t tri, double t, int dir)
{
    const tb_object_mesh *m = obj->mesh;
    if (obj->kind != TB_PRIM_POLYGONS || !m || tri >= m->ntris)
        return;
    /* The record tb__mesh_closest makes for that triangle, but for the
     * normal n, which tb_object_hit_point (the memo's only reader) does not
     * read: left 0 here, as it costs half of this call (every query's winner
     * comes through here, whether or not a hit point follows). */
    tb__last_xing *c = &tb__last;
    c->obj = obj;
    c->gen = tb__object_generation;
    c->o = ray->o;
    c->d = ray->d;
    c->tmin = ray->tmin;
    c->x.t = t;
    c->x.n = (tb_dvec3){0.0, 0.0, 0.0};
    c->x.leaf = obj;
    c->x.face = m->tri_face[tri];
    c->x.tri = tri;
    c->x.dir = dir * m->wsign;
}

tb_dvec3 tb_object_ray_point(const tb_object *obj, const tb_ray *ray, double t)
{
    tb__oray r = tb__object_ray(obj, ray);
    return (tb_dvec3){r.o.x + t * r.d.x, r.o.y + t * r.d.y, r.o.z + t * r.d.z};
}

bool tb_object_occluded(const tb_object *obj, const tb_ray *ray)
{
    if (!obj || !ray || !tb__ray_ok(ray))
        return false;
    if (obj->kind == TB_PRIM_POLYGONS) {
        tb__count_kind(obj->kind);
        return tb__mesh_any(obj, ray, ray->tmin, ray->tmax);
    }
    if (!tb_prim_is_csg(obj->kind)) { /* any-hit: no list, no normals */
        tb__oray r = tb__object_ray(obj, ray);
        return tb__prim_any(obj, &r, ray->tmin, ray->tmax);
    }
    tb__xing x;
    return tb__closest(obj, ray, ray->tmin, ray->tmax, &x);
}

/* ------------------------------------------------------------------ hit points */

/* |p - n| along a plane with unit axis normal: distance to z = c etc. */
static double tb__plane_dist(tb_dvec3 p, tb_dvec3 n, double c)
{
    return fabs(tb_dvec3_dot(n, p) - c) / tb_dvec3_length(n);
}

/* |Q| / |grad Q| for Q = x^2 + y^2 - (c0 + c1 z + c2 z^2). */
static double tb__revolved_dist(const double *c, tb_dvec3 p)
{
    double q = p.x * p.x + p.y * p.y - (c[0] + c[1] * p.z + c[2] * p.z * p.z);
    double gz = c[1] + 2.0 * c[2] * p.z;
    double g = sqrt(4.0 * (p.x * p.x + p.y * p.y) + gz * gz);
    return g > 0.0 ? fabs(q) / g : sqrt(fabs(q));
}

/* fmax(a, b) without the libm call: the same value (NaN loses) for these
 * arguments, which are never of opposite-signed zeros (absolute values). */
static inline double tb__max_abs(double a, double b) { return a > b || b != b ? a : b; }

double tb__face_residual(const tb_object *o, uint32_t face, uint32_t tri, tb_dvec3 p)
{
    static const tb_dvec3 axis[6] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
    double size = tb__max_abs(fabs(p.x), tb__max_abs(fabs(p.y), fabs(p.z)));
    double d = 0.0;
    switch (o->kind) {
    case TB_PRIM_SPHERE: d = fabs(tb_dvec3_length(p) - 1.0); break;
    case TB_PRIM_CUBE: d = face < 6 ? tb__plane_dist(p, axis[face], 1.0) : INFINITY; break;
    case TB_PRIM_CYLINDER:
    case TB_PRIM_CONE:
    case TB_PRIM_CONIC:
        if (face == TB_FACE_CYLINDER_SIDE)
            d = tb__revolved_dist(o->conic, p);
        else
            d = fabs(p.z - o->zrange[face == TB_FACE_CYLINDER_BOTTOM ? 0 : 1]);
        break;
    case TB_PRIM_PYRAMID: {
        double top = o->geom.pyramid.top, a0 = 0.5 * (1.0 + top), b0 = 0.5 * (top - 1.0);
        if (face < 4) {
            tb_dvec3 n = axis[face];
            n.z = -b0;
            d = tb__plane_dist(p, n, a0);
        } else {
            d = fabs(p.z - (face == TB_FACE_PYRAMID_BOTTOM ? -1.0 : 1.0));
        }
        break;
    }
    case TB_PRIM_PRISM:
        if (face < TB_FACE_PRISM_SIDE0) {
            d = fabs(p.z - (face == TB_FACE_PRISM_BOTTOM ? -1.0 : 1.0));
        } else {
            int k = (int)(face - TB_FACE_PRISM_SIDE0);
            double a[2], b[2];
            if (o->nprofile > 0) {
                int n = o->nprofile;
                a[0] = o->profile[2 * k];
                a[1] = o->profile[2 * k + 1];
                b[0] = o->profile[2 * ((k + 1) % n)];
                b[1] = o->profile[2 * ((k + 1) % n) + 1];
            } else {
                int n = o->geom.prism.sides;
                tb__prism_vertex(n, k, &a[0], &a[1]);
                tb__prism_vertex(n, (k + 1) % n, &b[0], &b[1]);
            }
            tb_dvec3 n = {b[1] - a[1], a[0] - b[0], 0.0};
            d = tb__plane_dist(p, n, n.x * a[0] + n.y * a[1]);
        }
        break;
    case TB_PRIM_TORUS: {
        double R = o->geom.torus.major, r = o->geom.torus.minor;
        d = fabs(hypot(hypot(p.x, p.y) - R, p.z) - r);
        size += R + r;
        break;
    }
    case TB_PRIM_POLYGONS: {
        const tb_object_mesh *m = o->mesh;
        if (!m || tri >= m->ntris)
            return INFINITY;
        const uint32_t *t = &m->tris[3 * tri];
        tb_vec3 v0 = m->vertices[t[0]], v1 = m->vertices[t[1]], v2 = m->vertices[t[2]];
        tb_dvec3 e1 = {(double)v1.x - v0.x, (double)v1.y - v0.y, (double)v1.z - v0.z};
        tb_dvec3 e2 = {(double)v2.x - v0.x, (double)v2.y - v0.y, (double)v2.z - v0.z};
        tb_dvec3 n = tb_dvec3_cross(e1, e2);
        double l = tb_dvec3_length(n);
        tb_dvec3 q = {p.x - v0.x, p.y - v0.y, p.z - v0.z};
        d = l > 0.0 ? fabs(tb_dvec3_dot(n, q)) / l : tb_dvec3_length(q);
        size += tb__max_abs(fabs(v0.x), tb__max_abs(fabs(v0.y), fabs(v0.z)));
        break;
    }
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH: {
        double hw = 0.5 * o->geom.arch.width, h = o->geom.arch.height;
        if (face < 6)
            d = tb__plane_dist(p, axis[face], 1.0);
        else if (face == TB_FACE_ARCH_INNER_LEFT || face == TB_FACE_ARCH_INNER_RIGHT)
            d = fabs(fabs(p.x) - hw);
        else if (o->kind == TB_PRIM_SQUARE_ARCH)
            d = fabs(p.z - (-1.0 + h));
        else
            d = fabs(hypot(p.x, p.z - (-1.0 + h - hw)) - hw);
        break;
    }
    default: return INFINITY;
    }
    /* The rounding of evaluating d itself (a few operations on numbers of size `size`). */
    return d + 32.0 * TB_DOUBLE_UNIT_ROUNDOFF * (1.0 + size);
}

bool tb_object_hit_point(const tb_object *obj, const tb_ray *ray, const tb_hit *hit, tb_vec3 *p, tb_vec3 *perr)
{
    if (!obj || !ray || !hit || !p || !perr || !tb_ray_is_valid(ray) || !isfinite(hit->t))
        return false;
    float tmax = ray->tmax;
    if (!(tmax > hit->t))
        tmax = tb_next_float_up(hit->t); /* the query's tmax may have been shortened to t */
    /* tb__closest returns the first crossing of a list sorted by t whose
     * float t is in [tmin, tmax]; the crossings before the memo's failed
     * that test with t below the memo's, so by tmin alone, and the memo's is
     * in this range too: with the same object and ray (o, d, tmin) it is
     * this query's answer whatever tmax the earlier query had. */
    tb__xing xs;
    const tb__xing *x = &xs; /* the memo's in place (a copy stalled the loads that follow) */
    const tb__last_xing *c = &tb__last;
    if (c->obj == obj && c->gen == tb__object_generation && (float)c->x.t == hit->t && (float)c->x.t <= tmax &&
        memcmp(&c->o, &ray->o, sizeof c->o) == 0 && memcmp(&c->d, &ray->d, sizeof c->d) == 0 &&
        memcmp(&c->tmin, &ray->tmin, sizeof c->tmin) == 0)
        x = &c->x;
    else if (!tb__closest(obj, ray, ray->tmin, tmax, &xs))
        return false;
    if ((float)x->t != hit->t || x->leaf->face_base + x->face != hit->face)
        return false;
    const tb_object *leaf = x->leaf;
    tb__oray r = tb__object_ray(leaf, ray);
    const double xt = x->t;
    tb_dvec3 po = {r.o.x + xt * r.d.x, r.o.y + xt * r.d.y, r.o.z + xt * r.d.z};
    double dist = tb__face_residual(leaf, x->face, x->tri, po);
    const tb_mat4 *m = &leaf->to_world.m;
    double pw[3], err[3];
    double pov[3] = {po.x, po.y, po.z};
    for (int i = 0; i < 3; i++) {
        double s = m->m[i][3], mag = fabs(m->m[i][3]);
        for (int j = 0; j < 3; j++) {
            s += m->m[i][j] * pov[j];
            mag += fabs(m->m[i][j] * pov[j]);
        }
        pw[i] = s;
        /* Object-space distance times the transform's largest stretch, the
         * double rounding of the transform (and of the inverse that mapped the
         * ray), then the rounding to float. */
        err[i] = leaf->scale * dist + 16.0 * TB_DOUBLE_UNIT_ROUNDOFF * mag;
    }
    float pf[3], ef[3];
    for (int i = 0; i < 3; i++) {
        pf[i] = (float)pw[i];
        double e = err[i] + fabs((double)pf[i] - pw[i]) + FLT_TRUE_MIN;
        ef[i] = tb_float_round_up(e);
    }
    *p = (tb_vec3){pf[0], pf[1], pf[2]};
    *perr = (tb_vec3){ef[0], ef[1], ef[2]};
    return true;
}
