/* Analytic area emitters over the exact surface of one primitive (sphere,
 * ellipsoid, cube, cylinder, cone, pyramid, prism, torus, conic, arches)
 * under any affine transform, sampled through the primitive's
 * parametrisation (host/object/param.h) instead of a tessellation
 * (docs/lights.md, "Analytic surface emitters").
 *
 * Each present face gets a table of at most TB_SURF_CELLS x TB_SURF_CELLS
 * cells over its (u, v) square, weighted by the integral of the world-space
 * area element J = |dp/du x dp/dv| over the cell (Gauss-Legendre); a
 * direction in which J does not vary gets one cell (a planar face under an
 * affine map: one cell in all). A sample picks a face by u1, a row (v) by
 * u2, a column (u) by what is left of u1, and a point uniformly in the cell;
 * its density per unit world area is p(u, v) / J(u, v), p the table's
 * piecewise-constant density on the square: exact, positive wherever J is,
 * close to uniform by area. Faces whose square is larger than the face
 * (prism caps, arch faces with the opening) reject points off the face (no
 * sample); the density of the points kept is the same formula. */
#ifndef TB_HOST_RENDER_EMIT_SURFACE_H
#define TB_HOST_RENDER_EMIT_SURFACE_H

#include <stdbool.h>
#include <stddef.h>

#include "host/object/object.h"
#include "host/render/lights.h"
#include "util/base/error.h"

/* Largest table side per face (cells per direction). */
#define TB_SURF_CELLS 16

/* The emitter of one primitive's whole surface (opaque). */
typedef struct tb_surface_emitter tb_surface_emitter;

/* Builds the emitter of primitive `o` (not CSG, not polygons), which must
 * outlive it. For arches (tb_surface_emitter_partial) the caller should set
 * the exact area with tb_surface_emitter_set_area. TB_ERR_ARG for
 * a CSG or polygons object or a surface of zero area; TB_ERR_NOMEM. */
tb_status tb_surface_emitter_make(const tb_object *o, tb_surface_emitter **out);

/* Frees it (NULL is allowed). */
void tb_surface_emitter_free(tb_surface_emitter *se);

/* World-space area of the emitting surface (scene units^2): the
 * Gauss-Legendre integral of J over every present face (8 points per cell
 * in each direction J varies in; measured errors in docs/lights.md), or
 * what tb_surface_emitter_set_area set. */
double tb_surface_emitter_area(const tb_surface_emitter *se);

/* True if the table's area is an estimate: arches, whose faces with the
 * opening cover only part of their (u, v) square (a prism's caps, also
 * partial, are computed exactly: their polygon's vector area). */
bool tb_surface_emitter_partial(const tb_surface_emitter *se);

/* Replaces the area (an exact figure computed elsewhere). */
void tb_surface_emitter_set_area(tb_surface_emitter *se, double area);

/* Bytes it holds (struct and tables, with the allocator's overhead as
 * tb_scene_memory counts it: `per_alloc` per allocation). */
size_t tb_surface_emitter_bytes(const tb_surface_emitter *se, size_t per_alloc);

/* Cells in its tables (all faces). */
int tb_surface_emitter_cells(const tb_surface_emitter *se);

/* The custom emitter (lights.h) of radiance L over the surface: area,
 * sample, pdf and intersect callbacks with ctx = se; object and face
 * (the face base) from the object. */
tb_emitter tb_emitter_surface(tb_surface_emitter *se, tb_channels L);

/* The callbacks (tb_emitter_sample_fn, tb_emitter_pdf_fn,
 * tb_emitter_intersect_fn) on ctx = a tb_surface_emitter. */
bool tb_surface_emitter_sample(void *ctx, float u1, float u2, tb_vec3 *q, tb_vec3 *n, double *pdf_area);
double tb_surface_emitter_pdf(void *ctx, tb_vec3 q);
bool tb_surface_emitter_intersect(void *ctx, tb_vec3 o, tb_vec3 d, double tmin, double *t, tb_vec3 *q,
                                  tb_vec3 *n);

/* True if the sample callback is the surface emitter's (ctx is then one). */
bool tb_emitter_is_surface(const tb_emitter *e);

/* True if the surface bounds a convex solid or is part of such a boundary
 * (sphere, cube, cylinder, cone, pyramid, regular prism): a segment from
 * outside to a point of it facing the segment's start cannot cross it. */
bool tb_surface_emitter_convex(const tb_surface_emitter *se);

/* The object the emitter was made of. */
const tb_object *tb_surface_emitter_object(const tb_surface_emitter *se);

/* Density per unit world area at a point of face `face` with parameters
 * (u, v) (0 where the sampler never goes). */
double tb_surface_emitter_pdf_uv(const tb_surface_emitter *se, int face, double u, double v);

#endif
