/* Internals shared by scene.c, scene_mesh.c and scene_emit.c. Not installed. */
#ifndef TB_HOST_RENDER_SCENE_INTERNAL_H
#define TB_HOST_RENDER_SCENE_INTERNAL_H

#include <stdbool.h>
#include <stdint.h>

#include "host/object/hit.h"
#include "host/object/object.h"
#include "host/render/accel.h"
#include "host/render/channels.h"
#include "host/render/lights.h"
#include "host/render/scene.h"
#include "util/base/error.h"
#include "util/math/aabb.h"
#include "util/math/ray.h"

/* Fills r, the acceleration structure's record for triangle `tri` of
 * polygons object `o`: the world corners copied from the mesh
 * (tb_object_mesh.wvertices), so a test touches one record instead of the
 * triangle's index triple, three vertices spread over the mesh's vertex
 * array and its face entry; the object index and the face ID. */
void tb__scene_tri_make(const tb_object *o, uint32_t tri, tb_accel_tri *r);

/* Completes the closest hit `hit` of tb_scene_intersect on triangle
 * reference th->index (`ray` as given to the structure): its (u, v) and
 * normal, as tb_object_intersect gives them for that triangle; and notes the
 * crossing for tb_object_hit_point (tb_object_note_triangle_hit). */
void tb__scene_tri_finish(const tb_scene *s, const tb_ray *ray, const tb_accel_tri_hit *th, tb_hit *hit);

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
