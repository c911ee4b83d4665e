/* Form factors for the radiosity renderer (docs/radiosity.md, "Form factors"):
 * the exact point-to-polygon form factor (the reference), ray-cast form
 * factors (Wallace, Elmquist and Haines 1989) with visibility through an
 * acceleration structure over the occluding polygons, and the hemicube
 * (Cohen and Greenberg 1985) drawn into the item buffer (util/itembuf).
 *
 * Every element of a radiosity mesh is a planar convex triangle or quad
 * (tb_ff_polygon); the same array describes the receivers, the occluders
 * and what the hemicube draws.
 *
 *     tb_ff_occluders *occ;
 *     tb_ff_occluders_build(polys, n, &occ);
 *     tb_vec3 pts[16];
 *     tb_ff_sample_polygon(&polys[shooter], 16, seed, pts);
 *     double f = tb_ff_raycast(pts, 16, ns, area, p, np, tb_ff_occluders_visible, occ);
 */
#ifndef TB_HOST_RADIOSITY_FORMFACTOR_H
#define TB_HOST_RADIOSITY_FORMFACTOR_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "util/base/error.h"
#include "util/math/vec.h"

/* Most corners of an element. */
#define TB_FF_MAX_VERTS 4

/* "No polygon" (e.g. nothing to skip in tb_hemicube_formfactors). */
#define TB_FF_NONE UINT32_MAX

/* Visibility is tested on the segment a + t (b - a) for t in
 * [TB_FF_SEGMENT_EPS, 1 - TB_FF_SEGMENT_EPS]: the ends are on surfaces, so a
 * relative margin keeps them from hitting their own polygons. The CPU path
 * and the GPU kernel use this same rule. */
#define TB_FF_SEGMENT_EPS 1e-4f

/* A planar convex polygon (a radiosity element). */
typedef struct tb_ff_polygon {
    tb_vec3 v[TB_FF_MAX_VERTS]; /* corners, counter-clockwise seen from the front (the normal's side) */
    int n;                      /* 3 or 4 */
} tb_ff_polygon;

/* True if nothing blocks the segment from a to b (see TB_FF_SEGMENT_EPS). */
typedef bool (*tb_ff_visible_fn)(void *ctx, tb_vec3 a, tb_vec3 b);

/* Unit normal (Newell) and area of a polygon (computed in double); a
 * degenerate polygon (collinear corners, n not 3 or 4) gives a zero normal
 * and area 0. Either output may be NULL. */
void tb_ff_polygon_frame(const tb_ff_polygon *poly, tb_vec3 *normal, double *area);

/* Exact unoccluded form factor from a differential area at p with unit
 * normal n to the front of `poly` (the contour integral of Lambert/Nusselt,
 * in double); the part of the polygon behind p's tangent plane is clipped
 * away, and 0 is returned if p sees the polygon's back or lies in its plane
 * (also on its edge: move such points into their element first), or for a
 * degenerate polygon or a zero normal (never NaN). "In a plane" has a
 * tolerance for float inputs: corners within 1e-7 (|corner - p|max +
 * largest coordinate magnitude) of p's tangent plane count as on it, and p
 * must be further than that in front of the polygon's plane. */
double tb_ff_point_polygon(tb_vec3 p, tb_vec3 n, const tb_ff_polygon *poly);

/* nsamples stratified jittered points on `poly`, each standing for
 * area / nsamples: the unit square is cut into nsamples equal cells (rows of
 * near-square cells) and mapped onto the polygon by a measure-preserving map
 * (triangles: Heitz 2019; convex quads: the bilinear patch with its linear
 * Jacobian inverted), so every cell becomes an equal-area stratum holding one
 * uniform point. The same (poly, nsamples, seed) gives the same points.
 * TB_ERR_ARG for nsamples < 1 or a degenerate polygon (zero area,
 * non-finite corner, n not 3 or 4). */
tb_status tb_ff_sample_polygon(const tb_ff_polygon *poly, int nsamples, uint64_t seed, tb_vec3 *out);

/* The same strata as tb_ff_sample_polygon, each point the image of its
 * cell's centre instead of a random point (no seed): eq. 5's disk term
 * assumes the sample sits in the middle of its area, so on compact elements
 * these points give ray casting less bias (a third of it on unit squares),
 * at the price of one fixed pattern; on thin triangles the mapped centres
 * are off the strata's centroids and can be worse (docs/formfactors.md,
 * "Ray casting"). Same errors as tb_ff_sample_polygon. */
tb_status tb_ff_sample_polygon_centres(const tb_ff_polygon *poly, int nsamples, tb_vec3 *out);

/* Ray-cast form factor from a differential receiver at p (unit normal n) to
 * a shooter of `area` and unit normal ns given by npts sample points:
 * sum over visible k of cos_s cos_r (area / npts) / (pi r^2 + area / npts)
 * (Wallace et al. 1989, eq. 5), in double. Samples behind either surface are
 * skipped without a visibility test; the others call visible(ctx, p, pts[k]).
 * `visible` NULL means no occlusion. The disk term biases the result low by
 * about (area / npts) / (pi r^2) (docs/formfactors.md, "Accuracy"). */
double tb_ff_raycast(const tb_vec3 *pts, int npts, tb_vec3 ns, double area, tb_vec3 p, tb_vec3 n,
                     tb_ff_visible_fn visible, void *ctx);

/* Wallace's visible fraction at p: sum_k V_k w_k / sum_k w_k over the
 * samples, w_k tb_ff_raycast's per-sample term and V_k = visible(ctx, p,
 * pts[k]) (visible NULL: 1), in [0, 1]; -1 if no sample is in front of both
 * surfaces (nothing measured). Rays only for samples with w_k > 0. */
double tb_ff_raycast_visible_fraction(const tb_vec3 *pts, int npts, tb_vec3 ns, double area, tb_vec3 p, tb_vec3 n,
                                      tb_ff_visible_fn visible, void *ctx);

/* Ray-cast form factor with an exact unoccluded part: tb_ff_point_polygon(p,
 * n, shooter) times tb_ff_raycast_visible_fraction over the shooter's sample
 * points pts (from tb_ff_sample_polygon on the same shooter). Exact when the
 * shooter is fully visible or fully hidden (no disk-term bias: meets issue 7's
 * 0.5% at 16 samples); under partial occlusion the fraction is Wallace's, with
 * its sampling error. No rays when the exact part is 0 or visible is NULL; one
 * extra ray (to the middle of the part p sees) if no sample is in front of p.
 * Costs one contour integral more than tb_ff_raycast (docs/formfactors.md). */
double tb_ff_raycast_exact(const tb_ff_polygon *shooter, const tb_vec3 *pts, int npts, tb_vec3 p, tb_vec3 n,
                           tb_ff_visible_fn visible, void *ctx);

/* Occluders: an acceleration structure (host/render/accel.h) over polygons. */
typedef struct tb_ff_occluders tb_ff_occluders;

/* Builds the occluders of polys[0..n) (copied; quads as two triangles split
 * along v0-v2, tested with the object level's watertight triangle test).
 * n == 0 gives occluders that block nothing. TB_ERR_ARG for a polygon with
 * n not 3 or 4 or a non-finite corner; *out is NULL on failure. */
tb_status tb_ff_occluders_build(const tb_ff_polygon *polys, size_t n, tb_ff_occluders **out);

/* A tb_ff_visible_fn: `ctx` is a tb_ff_occluders. Thread-safe. */
bool tb_ff_occluders_visible(void *ctx, tb_vec3 a, tb_vec3 b);

/* Frees the occluders; NULL is allowed. */
void tb_ff_occluders_free(tb_ff_occluders *occ);

/* Most triangles a tb_ff_shaft lists. */
#define TB_FF_SHAFT_MAX 8

/* The occluder triangles that may block the segments between two boxes
 * (from tb_ff_occluders_shaft). */
typedef struct tb_ff_shaft {
    const tb_ff_occluders *occ;
    size_t n;                       /* triangles listed */
    double margin;                  /* rounding allowance of the rejection tests */
    uint32_t tris[TB_FF_SHAFT_MAX]; /* occluder triangle indices */
} tb_ff_shaft;

/* Lists in *sh every occluder triangle that a segment from a point of box a
 * to a point of box b (lo xyz, hi xyz; tb_ff_occluders_visible's a and b)
 * could cross: those whose bounds meet the two boxes' convex hull (shaft
 * culling, Haines and Wallace 1991, down the occluders' tree), whose plane
 * such a segment can cross within [TB_FF_SEGMENT_EPS, 1 - TB_FF_SEGMENT_EPS]
 * of its length, and that reach the part of the shaft where it can (margins
 * for rounding). apts[0..na) and bpts[0..nb), when not NULL, are the only
 * a and b ends (inside their boxes), which tightens the plane test. False if there are more than
 * TB_FF_SHAFT_MAX (test those segments with tb_ff_occluders_visible). */
bool tb_ff_occluders_shaft(const tb_ff_occluders *occ, const float a[6], const tb_vec3 *apts, size_t na,
                           const float b[6], const tb_vec3 *bpts, size_t nb, tb_ff_shaft *sh);

/* A tb_ff_visible_fn whose ctx is a tb_ff_shaft: for a segment with one end
 * in each of its boxes, tb_ff_occluders_visible's answer from the listed
 * triangles only (box and plane rejection, then the same triangle test).
 * A blocker found moves to the front of the list (a shadow cache), so one
 * shaft is used by one thread at a time. */
bool tb_ff_shaft_visible(void *ctx, tb_vec3 a, tb_vec3 b);


/* Ray-cast form factors from one shooter to many receivers: ff[i] is
 * tb_ff_raycast(pts, npts, ns, area, p[i], n[i], ...) with visibility
 * through the occluders behind `ctx`. The solver calls whichever backend it
 * was given: tb_ff_raycast_batch (CPU) or the Vulkan kernel's
 * (host/gpu/formfactor.h). */
typedef tb_status (*tb_ff_batch_fn)(void *ctx, const tb_vec3 *pts, int npts, tb_vec3 ns, double area,
                                    const tb_vec3 *p, const tb_vec3 *n, size_t count, double *ff);

/* The CPU tb_ff_batch_fn: `ctx` is a tb_ff_occluders (NULL: no occlusion);
 * OpenMP over receivers, results independent of the thread count. */
tb_status tb_ff_raycast_batch(void *ctx, const tb_vec3 *pts, int npts, tb_vec3 ns, double area, const tb_vec3 *p,
                              const tb_vec3 *n, size_t count, double *ff);

/* tb_ff_raycast_exact for many receivers: ff[i] at (p[i], n[i]), visibility
 * through the tb_ff_occluders `ctx` (NULL: no occlusion); OpenMP over
 * receivers, results independent of the thread count. */
tb_status tb_ff_raycast_exact_batch(void *ctx, const tb_ff_polygon *shooter, const tb_vec3 *pts, int npts,
                                    const tb_vec3 *p, const tb_vec3 *n, size_t count, double *ff);

/* A hemicube with its delta form factors and item buffers (opaque). */
typedef struct tb_hemicube tb_hemicube;

/* A hemicube of res x res pixels on the top face (res x res / 2 on each
 * side); res even, 2..4096. NULL (with tb_error) otherwise or out of memory. */
tb_hemicube *tb_hemicube_create(int res);

/* Frees it; NULL is allowed. */
void tb_hemicube_free(tb_hemicube *hc);

/* ff[i] = form factor from a differential area at `center` (unit normal
 * `normal`) to polygon i, nearest polygon winning each hemicube pixel;
 * polygon `skip` (TB_FF_NONE: none) is not drawn. Polygons seen from behind
 * hide what is behind them but get ff 0. TB_ERR_ARG for a non-finite centre,
 * a zero normal, or a polygon with n not 3 or 4 or a non-finite corner. One
 * hemicube is used by one thread at a time. */
tb_status tb_hemicube_formfactors(tb_hemicube *hc, tb_vec3 center, tb_vec3 normal, const tb_ff_polygon *polys,
                                  size_t n, uint32_t skip, double *ff);

#endif
