/* Emitting CSG objects as custom area emitters (lights.h) over a lazily
 * built tessellation of bounded size (docs/lights.md, "CSG emitters").
 *
 * Loading a scene only makes the emitter (no tessellation): its selection
 * weight among the scene's emitters is a proxy area, pi/6 times the surface
 * area of the object's world box (a sphere's area for its cube). The
 * tessellation is built on the first sample, pdf or line query, by exactly
 * one thread (the others wait for it), with the same result whatever the
 * threads: the world-space CSG tessellation of scene_emit.c, tried at
 * successively coarser tolerances until it has at most
 * TB_CSG_EMIT_MAX_TRIS triangles (TB_CSG_EMIT_LEVELS levels; the coarsest
 * is kept whatever its size). Samples are uniform by area over its
 * triangles (density 1 / tessellated area), so an estimate is unbiased for
 * the tessellated surface whatever the proxy: the proxy only shifts how
 * often this emitter is chosen. */
#ifndef TB_HOST_RENDER_EMIT_CSG_H
#define TB_HOST_RENDER_EMIT_CSG_H

#include <stdbool.h>
#include <stddef.h>

#include "host/object/object.h"
#include "host/render/lights.h"
#include "util/base/error.h"

/* Largest number of triangles of a CSG emitter's tessellation (unless its
 * coarsest level has more). */
#define TB_CSG_EMIT_MAX_TRIS 8192

/* Tolerance levels tried, finest first. */
#define TB_CSG_EMIT_LEVELS 4

/* The lazily tessellated emitter of one CSG object (opaque). */
typedef struct tb_csg_emitter tb_csg_emitter;

/* Makes the emitter of CSG object `o` (which must outlive it) with
 * radiance L; nothing is tessellated yet. TB_ERR_ARG if o is not a CSG
 * node or its bounds are empty or not finite (no emitter is then needed:
 * nothing to sample); TB_ERR_NOMEM. */
tb_status tb_csg_emitter_make(const tb_object *o, tb_channels L, tb_csg_emitter **out);

/* Frees it and its tessellation (NULL is allowed). */
void tb_csg_emitter_free(tb_csg_emitter *ce);

/* The custom emitter (lights.h): area the proxy, callbacks with ctx = ce. */
tb_emitter tb_emitter_csg(tb_csg_emitter *ce);

/* True if e is a CSG emitter (ctx is then a tb_csg_emitter). */
bool tb_emitter_is_csg(const tb_emitter *e);

/* Builds the tessellation now if it is not built (thread-safe); false if
 * it could not be built (out of memory, or a tree with no surface): the
 * emitter then gives no samples. */
bool tb_csg_emitter_build(tb_csg_emitter *ce);

/* True once the tessellation is built (or its build failed). */
bool tb_csg_emitter_built(const tb_csg_emitter *ce);

/* The proxy area used to choose the emitter (scene units^2). */
double tb_csg_emitter_proxy_area(const tb_csg_emitter *ce);

/* Area of the tessellation (builds it); 0 if it has none. */
double tb_csg_emitter_area(tb_csg_emitter *ce);

/* Triangles of the tessellation (builds it). */
int tb_csg_emitter_triangles(tb_csg_emitter *ce);

/* Level of the tessellation (0 the finest; builds it). */
int tb_csg_emitter_level(tb_csg_emitter *ce);

/* Bytes it holds now (struct, and the tessellation once built). */
size_t tb_csg_emitter_bytes(const tb_csg_emitter *ce);

/* Bytes of an emitter not yet built (for predictions). */
size_t tb_csg_emitter_unbuilt_bytes(void);

#endif
