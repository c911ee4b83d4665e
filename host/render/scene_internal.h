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
#include "util/container/arena.h"
#include "util/container/array.h"
#include "util/container/hash_table.h"
#include "util/math/aabb.h"
#include "util/math/ray.h"

/* Fills r, the acceleration structure's record for triangle `tri` of
 * polygons object `o`: the world corners copied from the mesh
 * (tb_object_mesh.wvertices), so a test touches one record instead of the
 * triangle's index triple, three vertices spread over the mesh's vertex
 * array and its face entry; the object index and the face ID. */
void tb__scene_tri_make(const tb_object *o, uint32_t tri, tb_accel_tri *r);

/* Completes the closest hit `hit` of tb_scene_intersect on triangle
 * reference th->index (`ray` as given to the structure): its (u, v) (0 unless `uv`) and
 * normal, as tb_object_intersect gives them for that triangle; and notes the
 * crossing for tb_object_hit_point (tb_object_note_triangle_hit). */
void tb__scene_tri_finish(const tb_scene *s, const tb_ray *ray, const tb_accel_tri_hit *th, tb_hit *hit, bool uv);

/* World box of triangle `tri` of polygons object `o` (exact, rounded outward). */
tb_status tb__scene_tri_bounds(const tb_object *o, uint32_t tri, tb_aabb *out);

/* World box of an object: the primitive's exact box, a polygons object's
 * vertices, or the CSG combination of the children's boxes. */
tb_status tb__scene_object_bounds(const tb_object *o, tb_aabb *out);

/* The world-space area of primitive `leaf` when it needs no tessellation
 * (polygons, a sphere under a similarity): true and *area set; else false. */
bool tb__scene_leaf_area_exact(const tb_object *leaf, double *area);

/* World-space surface area of primitive `leaf` (not a CSG node): exact for
 * polygons and for primitives with only flat faces, otherwise from two
 * tessellations and Richardson extrapolation (docs/rendering.md). */
tb_status tb__scene_leaf_area(const tb_object *leaf, double *area);

/* The emitters of object `leaf` (a primitive or a CSG tree) with radiance L:
 * one triangle per triangle of a polygons object, one sphere for a sphere
 * under a similarity transform, one analytic surface emitter
 * (emit_surface.h) for every other primitive, one lazily tessellated
 * emitter (emit_csg.h) for a CSG tree, and with `tessellate` the triangles
 * of the world-space tessellation for a CSG tree and for every primitive
 * other than polygons and similarity spheres (scene_emit.c).
 * Appends them to out (a tb_array of tb_emitter, when not NULL; a surface
 * emitter's table is then owned by the emitter: tb__scene_free_emitter)
 * and writes their count to *n (none if the shape has no area or the
 * tessellation fails); adds the bytes of surface emitter tables and of
 * unbuilt CSG emitters to *bytes
 * (may be NULL). TB_ERR_NOMEM only. */
tb_status tb__scene_leaf_emitters(const tb_object *leaf, tb_channels L, bool tessellate, tb_array *out, int *n,
                                  size_t *bytes);

/* Emitters from the world-space tessellation of o (a primitive other than
 * polygons, or a CSG tree) at angular tolerance `angle` (radians), CSG
 * refinement edge `edge` (a fraction of o's world box diagonal) and at most
 * `segments` per parametric direction of a face: one triangle emitter each,
 * lifted off curved surfaces (scene_emit.c), appended to out (when not
 * NULL); *count gets their number (0 if the shape cannot be tessellated).
 * TB_ERR_NOMEM only. */
tb_status tb__scene_tess_emitters(const tb_object *o, tb_channels L, double angle, double edge, int segments,
                                  tb_array *out, int *count);

/* Frees what emitter e owns (a surface emitter's table); e stays as it is. */
void tb__scene_free_emitter(tb_emitter *e);

/* ------------------------------------------------------------------ memory (scene_memory.c) */

/* Bytes of object o (struct, parameters, children, mesh), as tb_scene_memory counts them. */
size_t tb__scene_object_bytes(const tb_object *o);

/* Bytes per acceleration reference while the structure is built (the
 * prediction and the load's running check use it). */
#define TB__SCENE_BUILD_PER_REF 400

/* Puts the hash of every node material of m (as the material table keys
 * them, unknown attributes aside) into `set` (scene.c). TB_ERR_NOMEM only. */
tb_status tb__scene_predict_materials(const tb_mid_object *m, tb_htab *set);

/* Writes the parts of u, largest first, as "objects 12.0 MiB (... each), ...". */
void tb__scene_memory_describe(const tb_scene_memory_use *u, char *buf, size_t len);

/* ------------------------------------------------------------------ unknown attributes (scene_attrs.c) */

/* A CSG-tree node's effective material attributes while its object is built. */
typedef struct tb__attrs_pending {
    const tb_mid_material *mat; /* &node->material of the MID node (what the build callback is given) */
    tb_mid_attrs attrs;         /* effective unknown material attributes (reader's or temporary memory) */
    tb_mid_attr *owned;         /* the merged array when it had to be made, else NULL */
} tb__attrs_pending;

/* The unknown MID attributes a scene keeps (docs/rendering.md, "Attributes
 * for renderers"). Allocated on the first unknown attribute, so a scene
 * without any pays one NULL pointer; an object without any pays nothing. */
typedef struct tb__scene_attrs {
    tb_arena arena;           /* deep copies of every kept name, value and array */
    tb_htab nodes;            /* object node address -> its tb__node_attrs in the arena (nodes with some only) */
    tb_htab named;            /* named material -> its effective attributes (tb_mid_attrs in the arena) */
    tb_mid_attrs *materials;  /* per entry of the final material table; NULL when none has any */
    tb_mid_attrs *lights;     /* per light, file order (nlights entries once any light has some) */
    int caplights;
    tb_mid_attrs camera;      /* the camera's */
    tb__attrs_pending *pending; /* the object being built: one entry per node whose material has some */
    int npending, cappending, cursor;
} tb__scene_attrs;

/* The scene's attribute store, created on first use (scene.c); NULL when out of memory. */
tb__scene_attrs *tb__attrs_store(tb_scene *s);

/* The store, or NULL if the scene has kept no attribute (scene.c). */
const tb__scene_attrs *tb__attrs_peek(const tb_scene *s);

/* Frees the store; NULL is allowed. */
void tb__attrs_free(tb__scene_attrs *a);

/* Deep copy of `src` into the store's arena (an empty run stays {NULL, 0}). TB_ERR_NOMEM only. */
tb_status tb__attrs_copy(tb__scene_attrs *a, tb_mid_attrs src, tb_mid_attrs *dst);

/* Records a named material definition's effective attributes: those of the
 * material it names (if any), then its own, its own replacing same-named ones. */
tb_status tb__attrs_named_material(tb_scene *s, const tb_mid_material *def);

/* Before building object `m`: works out, per node, the effective unknown
 * attributes of its material (the named base's or the CSG parent's, then
 * the block's own), as the reader resolves the known ones. */
tb_status tb__attrs_begin_object(tb_scene *s, const tb_mid_object *m);

/* In the build callback: the effective attributes of node material `m`
 * (valid until tb__attrs_end_object). */
tb_mid_attrs tb__attrs_of_material(tb_scene *s, const tb_mid_material *m);

/* After building: keeps the body and geometry attributes of every node of
 * `m` with some, keyed by the matching node of `o` (NULL: the build failed,
 * only the temporary memory is released). */
tb_status tb__attrs_end_object(tb_scene *s, const tb_mid_object *m, const tb_object *o);

/* Feeds the bytes that decide whether two attribute runs are equal (names,
 * types and values; not locations) to put(ctx, bytes, n). */
void tb__attrs_key(tb_mid_attrs a, void (*put)(void *ctx, const void *p, size_t n), void *ctx);

#endif
