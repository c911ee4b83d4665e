/* One triangle of a polygons object as an acceleration reference of its own
 * (docs/rendering.md, "Acceleration references").
 *
 * The object level intersects a polygons object as a whole (its own BVH over
 * its triangles). To let the scene's BVH or grid split a big mesh like any
 * other geometry, each triangle is tested here on its own, with exactly the
 * object level's method and conventions (docs/primitives.md, "Watertight
 * triangles"): the world ray mapped to object space by the inverse transform
 * in double, Woop, Benthin and Wald's watertight test in double with exact
 * signs for zero edge functions and the same tie rule for rays through edges
 * and vertices, the range checked on the float t, the face ID of the polygon
 * the triangle came from, (u, v) from host/object/param.h, the normal
 * (v1 - v0) x (v2 - v0) transformed by the inverse transpose. So a hit is the
 * record tb_object_intersect gives for the same triangle, and rays never leak
 * between the triangles of a mesh. (The object level offers no call for one
 * triangle of a mesh yet; if it gets one, this file should use it.)
 *
 * (u, v) are computed once per query, for the winning triangle only: the
 * callback keeps the best triangle candidate of the current query in
 * thread-local storage, ordered by the structure's own tie rule (t, object,
 * face, reference index), so the candidate kept is the one the structure
 * returns whenever it returns a triangle. */
#include "host/render/scene_internal.h"

#include <math.h>
#include <stdlib.h>

#include "host/object/bounds.h"
#include "host/object/param.h"
#include "util/math/mat.h"
#include "util/math/transform.h"
#include "util/mesh/predicates.h"

/* The ray in object space, prepared for the watertight test. */
typedef struct tb__sray {
    double o[3], d[3];
    int kx, ky, kz;   /* permutation: kz the largest direction component */
    double sx, sy, sz; /* shear constants */
} tb__sray;

static void tb__sray_init(tb__sray *w, const tb_object *obj, const tb_ray *ray)
{
    tb_dvec3 o = tb_mat4_mul_point(&obj->to_world.inv, (tb_dvec3){ray->o.x, ray->o.y, ray->o.z});
    tb_dvec3 d = tb_mat4_mul_vec(&obj->to_world.inv, (tb_dvec3){ray->d.x, ray->d.y, ray->d.z});
    w->o[0] = o.x;
    w->o[1] = o.y;
    w->o[2] = o.z;
    w->d[0] = d.x;
    w->d[1] = d.y;
    w->d[2] = d.z;
    int kz = 0;
    if (fabs(w->d[1]) > fabs(w->d[kz]))
        kz = 1;
    if (fabs(w->d[2]) > fabs(w->d[kz]))
        kz = 2;
    int kx = (kz + 1) % 3, ky = (kx + 1) % 3;
    if (w->d[kz] < 0.0) { /* keep the winding direction */
        int t = kx;
        kx = ky;
        ky = t;
    }
    w->kx = kx;
    w->ky = ky;
    w->kz = kz;
    w->sx = w->d[kx] / w->d[kz];
    w->sy = w->d[ky] / w->d[kz];
    w->sz = 1.0 / w->d[kz];
}

/* Sign of the edge function E(P, Q) = Qx Py - Qy Px, exact when e is 0. */
static int tb__edge_sign(double e, double px, double py, double qx, double qy)
{
    if (e != 0.0)
        return e > 0.0 ? 1 : -1;
    return -tb_orient2d_sign(px, py, qx, qy, 0.0, 0.0);
}

/* Tie rule for an edge P -> Q through the ray: claimed if the ray shifted by
 * (eps, eps^2) would be inside, i.e. s (Q - P) has y > 0, or y == 0 and x < 0. */
static bool tb__claims(int s, double px, double py, double qx, double qy)
{
    double ex = s * (qx - px), ey = s * (qy - py);
    return ey > 0.0 || (ey == 0.0 && ex < 0.0);
}

/* The watertight test; on a hit writes the line parameter t. */
static bool tb__tri(const tb__sray *w, tb_vec3 v0, tb_vec3 v1, tb_vec3 v2, double *t)
{
    double A[3] = {v0.x - w->o[0], v0.y - w->o[1], v0.z - w->o[2]};
    double B[3] = {v1.x - w->o[0], v1.y - w->o[1], v1.z - w->o[2]};
    double C[3] = {v2.x - w->o[0], v2.y - w->o[1], v2.z - w->o[2]};
    int kx = w->kx, ky = w->ky, kz = w->kz;
    double ax = A[kx] - w->sx * A[kz], ay = A[ky] - w->sy * A[kz];
    double bx = B[kx] - w->sx * B[kz], by = B[ky] - w->sy * B[kz];
    double cx = C[kx] - w->sx * C[kz], cy = C[ky] - w->sy * C[kz];
    double U = cx * by - cy * bx;
    double V = ax * cy - ay * cx;
    double W = bx * ay - by * ax;
    if ((U < 0.0 || V < 0.0 || W < 0.0) && (U > 0.0 || V > 0.0 || W > 0.0))
        return false;
    if (U == 0.0 || V == 0.0 || W == 0.0) {
        int su = tb__edge_sign(U, bx, by, cx, cy);
        int sv = tb__edge_sign(V, cx, cy, ax, ay);
        int sw = tb__edge_sign(W, ax, ay, bx, by);
        if ((su < 0 || sv < 0 || sw < 0) && (su > 0 || sv > 0 || sw > 0))
            return false;
        int s = su + sv + sw > 0 ? 1 : (su + sv + sw < 0 ? -1 : 0);
        if (s == 0)
            return false; /* the triangle is edge-on to the ray */
        if ((su == 0 && !tb__claims(s, bx, by, cx, cy)) || (sv == 0 && !tb__claims(s, cx, cy, ax, ay)) ||
            (sw == 0 && !tb__claims(s, ax, ay, bx, by)))
            return false;
    }
    double det = U + V + W;
    if (det == 0.0)
        return false;
    double az = w->sz * A[kz], bz = w->sz * B[kz], cz = w->sz * C[kz];
    double T = U * az + V * bz + W * cz;
    *t = T / det;
    return isfinite(*t);
}

/* Tests triangle `tri`; t in the ray's range on the float t. */
static bool tb__hit_tri(const tb_object *o, uint32_t tri, const tb_ray *ray, tb__sray *w, double *t)
{
    const tb_object_mesh *m = o->mesh;
    if (!m || tri >= m->ntris)
        return false;
    tb__sray_init(w, o, ray);
    const uint32_t *tv = &m->tris[3 * (size_t)tri];
    if (!tb__tri(w, m->vertices[tv[0]], m->vertices[tv[1]], m->vertices[tv[2]], t))
        return false;
    return (float)*t >= ray->tmin && (float)*t <= ray->tmax;
}

/* The best triangle candidate of this thread's current query. */
typedef struct tb__tri_best {
    bool valid;
    const tb_object *obj;
    uint32_t tri, index, face;
    float tf;   /* the reported t */
    double t;   /* the line parameter in double, as the object level uses it for (u, v) */
} tb__tri_best;

static _Thread_local tb__tri_best tb__best;

void tb__scene_tri_begin(void) { tb__best.valid = false; }

/* True if candidate (t, object, face, index) precedes the kept one. */
static bool tb__better(float t, uint32_t object, uint32_t face, uint32_t index)
{
    const tb__tri_best *b = &tb__best;
    if (!b->valid || t != b->tf)
        return !b->valid || t < b->tf;
    if (object != b->obj->index)
        return object < b->obj->index;
    if (face != b->face)
        return face < b->face;
    return index < b->index;
}

void tb__scene_tri_finish(const tb_ray *ray, tb_hit *hit)
{
    const tb__tri_best *b = &tb__best;
    if (!b->valid || hit->t != b->tf || hit->object != b->obj->index || hit->face != b->face)
        return; /* the winner is not a triangle reference */
    const tb_object *o = b->obj;
    tb_dvec3 ro = tb_mat4_mul_point(&o->to_world.inv, (tb_dvec3){ray->o.x, ray->o.y, ray->o.z});
    tb_dvec3 rd = tb_mat4_mul_vec(&o->to_world.inv, (tb_dvec3){ray->d.x, ray->d.y, ray->d.z});
    tb_dvec3 p = {ro.x + b->t * rd.x, ro.y + b->t * rd.y, ro.z + b->t * rd.z};
    uint32_t face = o->mesh->tri_face[b->tri];
    int pf = (int)face;
    double u = 0.0, v = 0.0;
    if (tb_param_from_point(o->kind, &o->geom, p, (int)face, &pf, &u, &v) != TB_OK)
        u = v = 0.0;
    hit->u = (float)u;
    hit->v = (float)v;
}

bool tb__scene_tri_intersect(const tb_object *o, uint32_t tri, uint32_t index, const tb_ray *ray, tb_hit *hit)
{
    tb__sray w;
    double t;
    if (!tb__hit_tri(o, tri, ray, &w, &t))
        return false;
    const tb_object_mesh *m = o->mesh;
    const uint32_t *tv = &m->tris[3 * (size_t)tri];
    tb_vec3 v0 = m->vertices[tv[0]], v1 = m->vertices[tv[1]], v2 = m->vertices[tv[2]];
    tb_dvec3 e1 = {(double)v1.x - v0.x, (double)v1.y - v0.y, (double)v1.z - v0.z};
    tb_dvec3 e2 = {(double)v2.x - v0.x, (double)v2.y - v0.y, (double)v2.z - v0.z};
    tb_dvec3 n = tb_dvec3_cross(e1, e2);
    if (n.x == 0.0 && n.y == 0.0 && n.z == 0.0)
        n.z = 1.0;
    tb_dvec3 nw = tb_transform_dnormal(&o->to_world, n);
    double len = tb_dvec3_length(nw);
    tb_vec3 ng = {0.0f, 0.0f, 1.0f};
    if (len > 0.0 && isfinite(len)) {
        double s = (o->flip ? -1.0 : 1.0) / len;
        ng = (tb_vec3){(float)(nw.x * s), (float)(nw.y * s), (float)(nw.z * s)};
    }
    uint32_t face = o->face_base + m->tri_face[tri];
    hit->t = (float)t;
    hit->object = o->index;
    hit->face = face;
    hit->u = hit->v = 0.0f; /* tb__scene_tri_finish, for the winner */
    hit->ng = ng;
    if (tb__better(hit->t, o->index, face, index))
        tb__best = (tb__tri_best){true, o, tri, index, face, hit->t, t};
    return true;
}

bool tb__scene_tri_occluded(const tb_object *o, uint32_t tri, const tb_ray *ray)
{
    tb__sray w;
    double t;
    return tb__hit_tri(o, tri, ray, &w, &t);
}

tb_status tb__scene_tri_bounds(const tb_object *o, uint32_t tri, tb_aabb *out)
{
    const tb_object_mesh *m = o->mesh;
    if (!m || tri >= m->ntris)
        return tb_error(TB_ERR_ARG, "scene: triangle %u out of range", tri);
    const uint32_t *tv = &m->tris[3 * (size_t)tri];
    tb_vec3 v[3] = {m->vertices[tv[0]], m->vertices[tv[1]], m->vertices[tv[2]]};
    return tb_bounds_points(v, 3, &o->to_world, out);
}

tb_status tb__scene_object_bounds(const tb_object *o, tb_aabb *out)
{
    if (tb_prim_is_csg(o->kind)) {
        tb_aabb local[8];
        tb_aabb *cb = o->nchildren <= 8 ? local : malloc(sizeof *cb * (size_t)o->nchildren);
        if (!cb)
            return tb_error(TB_ERR_NOMEM, "scene: out of memory for CSG bounds");
        tb_status st = TB_OK;
        for (int i = 0; i < o->nchildren && !st; i++)
            st = tb__scene_object_bounds(&o->children[i], &cb[i]);
        if (!st)
            *out = tb_bounds_csg(o->kind, cb, o->nchildren);
        if (cb != local)
            free(cb);
        return st;
    }
    if (o->kind == TB_PRIM_POLYGONS && o->mesh)
        return tb_bounds_points(o->mesh->vertices, o->mesh->nvertices, &o->to_world, out);
    return tb_bounds_world(o->kind, &o->geom, &o->to_world, out);
}
