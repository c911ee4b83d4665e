/* Internals shared by scene.c, scene_mesh.c and scene_emit.c. Not installed. */
#ifndef TB_HOST_RENDER_SCENE_INTERNAL_H
#define TB_HOST_RENDER_SCENE_INTERNAL_H

#include <stdbool.h>
#include <stdint.h>

#include "host/object/hit.h"
#include "host/object/object.h"
#include "host/render/channels.h"
#include "host/render/lights.h"
#include "util/base/error.h"
#include "util/math/aabb.h"
#include "util/math/ray.h"

/* One triangle reference, with what its test reads in one place: the world
 * corners copied from the mesh (tb_object_mesh.wvertices), so a test touches
 * one record instead of the triangle's index triple, three vertices spread
 * over the mesh's vertex array and its face entry. */
typedef struct tb__scene_tri {
    double v[9];           /* world corners x y z, as the mesh's test sees them */
    const tb_object *o;    /* the top-level polygons object */
    uint32_t tri;          /* triangle within o->mesh */
    uint32_t face;         /* face ID within the object (o->face_base + the mesh's tri_face) */
} tb__scene_tri;

/* Fills r for triangle `tri` of polygons object `o`. */
void tb__scene_tri_make(const tb_object *o, uint32_t tri, tb__scene_tri *r);

/* Closest hit of triangle reference r (triangle r->tri of the top-level
 * polygons object r->o) with the world ray, t in [ray->tmin, ray->tmax] on the
 * float t: the record tb_object_intersect gives when that triangle is the
 * object's closest (face ID, unit world normal out of the front side),
 * except (u, v) and the normal, which are left 0: finding them
 * (host/object/param.h) costs as much as the test, and only the closest hit
 * needs them. The candidate is
 * remembered per thread (`index` is the reference's number, for the tie
 * rule) and tb__scene_tri_finish fills in the (u, v) and normal of the
 * winner. */
bool tb__scene_tri_intersect(const tb__scene_tri *r, uint32_t index, const tb_ray *ray, tb_hit *hit);

/* Forgets this thread's triangle candidates: call before a closest-hit query. */
void tb__scene_tri_begin(void);

/* If the closest hit `hit` of a query (tb_accel_intersect with the scene's
 * callbacks, `ray` as given to it) came from a triangle reference, computes
 * its (u, v) and normal as tb_object_intersect does. */
void tb__scene_tri_finish(const tb_ray *ray, tb_hit *hit);

/* True if triangle reference r is hit with t in [ray->tmin, ray->tmax]. */
bool tb__scene_tri_occluded(const tb__scene_tri *r, const tb_ray *ray);

/* World box of triangle `tri` of polygons object `o` (exact, rounded outward). */
tb_status tb__scene_tri_bounds(const tb_object *o, uint32_t tri, tb_aabb *out);

/* World box of an object: the primitive's exact box, a polygons object's
 * vertices, or the CSG combination of the children's boxes. */
tb_status tb__scene_object_bounds(const tb_object *o, tb_aabb *out);

/* World-space surface area of primitive `leaf` (not a CSG node): exact for
 * polygons and for primitives with only flat faces, otherwise from two
 * tessellations and Richardson extrapolation (docs/rendering.md). */
tb_status tb__scene_leaf_area(const tb_object *leaf, double *area);

/* The emitters of object `leaf` (a primitive or a CSG tree) with radiance L:
 * one triangle per triangle of a polygons object, one sphere for a sphere
 * under a similarity transform, otherwise the triangles of its world-space
 * tessellation (scene_emit.c). Writes them to out (when not NULL) and their
 * count to *n (none if the tessellation fails). TB_ERR_NOMEM only. */
tb_status tb__scene_leaf_emitters(const tb_object *leaf, tb_channels L, tb_emitter *out, int *n);

#endif
