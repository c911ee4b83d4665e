/* Ray intersection for every primitive kind and CSG tree (docs/primitives.md,
 * "Intersection"). One function per query, each switching over all kinds.
 *
 *     tb_hit hit;
 *     if (tb_object_intersect(obj, &ray, &hit)) ray.tmax = hit.t;   // closest so far
 *     ...
 *     tb_vec3 p, perr;                       // to shade and spawn from the hit:
 *     tb_object_hit_point(obj, &ray, &hit, &p, &perr);
 *     tb_vec3 o2 = tb_spawn_ray_origin(p, perr, hit.ng, wi);   // hit.h
 *
 * The world ray (float) is mapped to object space by the object's inverse
 * transform in double, without normalising the direction, so t means the same
 * in both spaces; the primitive is then solved in double. Rays with a NaN or
 * infinite component, a zero direction or tmin > tmax are rejected (no hit,
 * counted as "Intersect/invalid rays"); every test is counted per kind
 * ("Intersect/sphere", ...). Thread-safe: objects are only read. */
#ifndef TB_HOST_OBJECT_INTERSECT_H
#define TB_HOST_OBJECT_INTERSECT_H

#include <stdbool.h>

#include "host/object/hit.h"
#include "host/object/object.h"
#include "util/math/ray.h"

/* Closest hit of the ray with the object's surface with tmin <= t <= tmax;
 * fills *hit (t, object index, face ID, (u, v) from host/object/param.h, unit
 * geometric normal out of the solid) and returns true, or returns false and
 * leaves *hit unchanged. A ray starting inside a solid hits its surface on
 * the way out. */
bool tb_object_intersect(const tb_object *obj, const tb_ray *ray, tb_hit *hit);

/* tb_object_intersect with hit->u = hit->v = 0 instead of the parametric
 * coordinates (the rest of the record bit for bit the same): for callers
 * whose materials read no (u, v), which then skip their cost (atan2, acos,
 * square roots per hit). */
bool tb_object_intersect_no_uv(const tb_object *obj, const tb_ray *ray, tb_hit *hit);

/* True if the ray hits the object's surface anywhere with tmin <= t <= tmax
 * (any-hit: may stop at the first one found). */
bool tb_object_occluded(const tb_object *obj, const tb_ray *ray);

/* The world-space point of a hit found by tb_object_intersect(obj, ray, hit),
 * recomputed in double (the float t alone cannot give it: its rounding moves
 * the point by up to |t d| 2^-24 along the ray), rounded to float, with a
 * bound on its absolute error per component: the distance of the double
 * point from the surface, the transform's rounding and the final rounding
 * (docs/primitives.md, "Hit points and error bounds"). `ray` is the ray of
 * the query (a tmax shortened to the hit's t is fine). Returns false, with p
 * and perr untouched, if the ray does not give that hit again. */
bool tb_object_hit_point(const tb_object *obj, const tb_ray *ray, const tb_hit *hit, tb_vec3 *p, tb_vec3 *perr);

/* Triangle `tri` of a polygons object's mesh (obj->mesh->tris) on its own, with
 * exactly the watertight test and tie rules tb_object_intersect uses for the
 * whole mesh, so an acceleration structure may hold a big mesh's triangles as
 * separate references. True if the world ray's line crosses the triangle, with
 * the line parameter in *t (double); the ray's [tmin, tmax] is NOT checked. */
bool tb_object_triangle_crossing(const tb_object *obj, uint32_t tri, const tb_ray *ray, double *t);

/* Unit world-space geometric normal of triangle `tri`, as tb_object_intersect
 * reports it for a hit on that triangle (kept per triangle: a load; inline,
 * as it ends every closest-hit query on a mesh). */
static inline tb_vec3 tb_object_triangle_normal(const tb_object *obj, uint32_t tri)
{
    return obj->mesh->wnormal[tri];
}

/* (u, v) of a crossing of triangle `tri` of a polygons object's mesh from
 * the edge functions U V W the watertight test gave for it (tb_wt_triangle's
 * uvw): the mix of the face's (u, v) at the triangle's corners, which is
 * tb_param_from_point's (u, v) of the crossing up to rounding (clamped to
 * [0, 1]). The corners' (u, v) are the vertices' uvs (read per call), or
 * without uvs the face's frame projection (kept per triangle). False, with u
 * and v untouched, for a triangle of a face of more than 3 corners with uvs
 * (param splits those its own way): use the point. */
bool tb_object_triangle_uv(const tb_object *obj, uint32_t tri, const double uvw[3], double *u, double *v);

/* Tells the object level that triangle `tri` of the top-level polygons
 * object obj, crossed at line parameter t with direction dir (both as
 * tb_wt_triangle gave them, host/object/watertight.h), is the closest
 * crossing of `ray` with obj from ray->tmin on: what tb_object_intersect
 * would find. A following tb_object_hit_point for that hit then takes it
 * from this thread's memo instead of searching the mesh again. Only for a
 * crossing that is that answer (the scene's triangle references note the
 * winner of a query: render_scene_accel checks the two agree). */
void tb_object_note_triangle_hit(const tb_object *obj, const tb_ray *ray, uint32_t tri, double t, int dir);

/* The point at line parameter t of the world ray, in obj's object space and
 * in double, exactly as tb_object_intersect computes a hit point for (u, v). */
tb_dvec3 tb_object_ray_point(const tb_object *obj, const tb_ray *ray, double t);

#endif
