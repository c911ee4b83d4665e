/* One triangle of a polygons object as an acceleration reference of its own
 * (docs/rendering.md, "Acceleration references").
 *
 * The object level intersects a polygons object as a whole (its own BVH over
 * its triangles). To let the scene's BVH or grid split a big mesh like any
 * other geometry, each triangle is a reference the structure tests itself
 * (tb_accel_tri, host/render/accel.h) with exactly the object level's method
 * and conventions (docs/primitives.md, "Watertight triangles"): Woop, Benthin
 * and Wald's watertight test in double on the mesh's world-space corners (the
 * inline code of host/object/watertight.h, on a copy of the corners kept in
 * the reference's record), exact signs for zero edge functions and the same
 * tie rule for rays through edges and vertices, the range checked on the
 * float t, the face ID of the polygon the triangle came from. The winner's
 * (u, v) (the mix of its corners' by the test's edge functions,
 * tb_object_triangle_uv) and normal (kept per triangle by the mesh) are
 * filled in here, once per query. So a hit is the record tb_object_intersect
 * gives for the same triangle, and rays never leak between the triangles of
 * a mesh. */
#include "host/render/scene_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "host/object/bounds.h"
#include "host/object/intersect.h"
#include "host/object/param.h"

void tb__scene_tri_make(const tb_object *o, uint32_t tri, tb_accel_tri *r)
{
    const tb_object_mesh *m = o->mesh;
    for (int k = 0; k < 3; k++)
        memcpy(&r->v[3 * k], &m->wvertices[3 * (size_t)m->tris[3 * (size_t)tri + k]], sizeof(double) * 3);
    r->object = o->index;
    r->face = o->face_base + m->tri_face[tri];
}

/* ------------------------------------------------------ (u, v) of a face
 *
 * A triangle's (u, v) is the mix of its corners' by the test's weights
 * (tb_object_triangle_uv), as the object level computes it. Only faces of
 * more than 3 corners with uvs take it from the hit point (param splits
 * those its own way), and tb_param_from_point recomputes the polygon's frame
 * on every call: the code below memoises the frame per thread and uses
 * param.h's tb_poly_frame_make / tb_poly_fan_uv, the functions
 * tb_param_from_point itself uses, so (u, v) are the object level's bit for
 * bit (tests/render/test_scene_accel.c compares every hit with
 * tb_object_intersect's byte for byte). Non-convex faces (ear-clipped by
 * param) or more than TB__UV_MAX_NV corners use tb_param_from_point. */
#define TB__UV_MAX_NV 8
#define TB__UV_SLOTS 256u

typedef struct tb__uv_frame {
    const tb_geom_polygons *g; /* key: geometry and face, valid while gen is the current object generation */
    unsigned long gen;         /* tb_object_generation() when filled (a later object may reuse g's address) */
    int face, nv;
    tb_vec3 corner[TB__UV_MAX_NV];
    tb_vec2 uv[TB__UV_MAX_NV]; /* the corners' uvs, when the geometry has them */
    tb_poly_frame frame;
    bool ok;                   /* the frame exists (else param's error path: u = v = 0) */
    bool fan;                  /* with uvs: the loop is convex (param splits it as the fan) */
} tb__uv_frame;

static _Thread_local tb__uv_frame tb__uv_cache[TB__UV_SLOTS];

/* The frame of face `face` of g, from this thread's memo when it holds that
 * face of that geometry and no object was torn down since (objects are
 * read-only while they live, so the corners cannot have changed). */
static const tb__uv_frame *tb__uv_frame_of(const tb_geom_polygons *g, int face)
{
    int b = g->face_start[face], nv = g->face_start[face + 1] - b;
    if (nv < 3 || nv > TB__UV_MAX_NV)
        return NULL;
    uintptr_t h = ((uintptr_t)g >> 4) * 0x9E3779B97F4A7C15u + (uintptr_t)face * 0xC2B2AE3D27D4EB4Fu;
    tb__uv_frame *f = &tb__uv_cache[(h >> 32) % TB__UV_SLOTS];
    unsigned long gen = tb_object_generation();
    if (f->g == g && f->face == face && f->gen == gen)
        return f;
    for (int i = 0; i < nv; i++) {
        int idx = g->indices[b + i];
        if (idx < 0 || idx >= g->nvertices) {
            f->g = NULL;
            return NULL;
        }
        f->corner[i] = g->vertices[idx];
        if (g->uvs)
            f->uv[i] = g->uvs[idx];
    }
    f->g = g, f->face = face, f->nv = nv, f->gen = gen;
    f->ok = tb_poly_frame_make(f->corner, NULL, nv, &f->frame);
    f->fan = f->ok && (nv == 3 || tb_poly_frame_convex(&f->frame, f->corner, NULL, nv));
    return f;
}

void tb__scene_tri_finish(const tb_scene *s, const tb_ray *ray, const tb_accel_tri_hit *th, tb_hit *hit, bool uv)
{
    /* hit->object is the reference's object (tb__scene_tri_make), th->sub its
     * triangle: no lookup of the reference (a cache miss per hit on big meshes). */
    const tb_object *o = s->objects[hit->object];
    uint32_t tri = th->sub;
    double u = 0.0, v = 0.0;
    if (uv && !tb_object_triangle_uv(o, tri, th->uvw, &u, &v)) {
        /* A face of more than 3 corners with uvs: from the point. */
        tb_dvec3 p = tb_object_ray_point(o, ray, th->t);
        uint32_t face = o->mesh->tri_face[tri];
        int pf = (int)face;
        const tb_geom_polygons *g = &o->geom.polygons;
        const tb__uv_frame *f = tb_dvec3_isfinite(p) ? tb__uv_frame_of(g, (int)face) : NULL;
        if (f && f->fan) /* (fan implies a frame; otherwise ear-clipped or no area: param's own path) */
            tb_poly_fan_uv(&f->frame, f->corner, NULL, f->uv, f->nv, p, &u, &v);
        else if (tb_param_from_point(o->kind, &o->geom, p, (int)face, &pf, &u, &v) != TB_OK)
            u = v = 0.0;
    }
    hit->u = (float)u;
    hit->v = (float)v;
    hit->ng = tb_object_triangle_normal(o, tri);
    /* The shading point comes next (tb_object_hit_point): give the object
     * level the crossing so it need not search the mesh for it again. */
    tb_object_note_triangle_hit(o, ray, tri, th->t, th->dir);
}

tb_status tb__scene_tri_bounds(const tb_object *o, uint32_t tri, tb_aabb *out)
{
    const tb_object_mesh *m = o->mesh;
    if (!m || tri >= m->ntris)
        return tb_error(TB_ERR_ARG, "scene: triangle %u out of range", tri);
    const uint32_t *tv = &m->tris[3 * (size_t)tri];
    if (!m->wvertices) {
        tb_vec3 v[3] = {m->vertices[tv[0]], m->vertices[tv[1]], m->vertices[tv[2]]};
        return tb_bounds_points(v, 3, &o->to_world, out);
    }
    /* The world corners are stored (tb_transform_dpoint of each vertex, as
     * tb_bounds_points computes them): the same box without the transform
     * (a third of a large mesh's reference making). */
    tb_dvec3 lo = {INFINITY, INFINITY, INFINITY}, hi = {-INFINITY, -INFINITY, -INFINITY};
    for (int k = 0; k < 3; k++) {
        const double *w = &m->wvertices[3 * (size_t)tv[k]];
        tb_dvec3 p = {w[0], w[1], w[2]};
        lo = tb_dvec3_min(lo, p), hi = tb_dvec3_max(hi, p);
    }
    *out = tb_bounds_transformed(lo, hi);
    return TB_OK;
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
