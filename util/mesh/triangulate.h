/* Triangulation of polygons with holes: ear clipping with exact predicates,
 * holes joined by bridges (Eberly, "Triangulation by ear clipping") or spliced
 * where they touch the boundary, and a spatial grid so that 10^5-vertex
 * polygons take well under a second (docs/meshing.md, "Triangulation").
 *
 * Every input vertex is kept (collinear ones too) and every output triangle is
 * counter-clockwise. For a weakly simple input (rings that do not cross;
 * they may touch at vertices) the triangles tile the polygon exactly: their
 * areas add up to its area, none overlap, and all have positive area unless
 * the input itself has zero-width parts (coincident consecutive points,
 * zero-width spikes). Invalid input (crossing rings, holes outside the outer
 * ring) still gives the right number of triangles without failing, but they
 * may overlap; stats.forced counts the ears taken without a valid-ear test. */
#ifndef TB_UTIL_MESH_TRIANGULATE_H
#define TB_UTIL_MESH_TRIANGULATE_H

#include <stdint.h>

#include "util/base/error.h"
#include "util/container/array.h"
#include "util/math/vec.h"

/* One output triangle: three point indices, counter-clockwise. */
typedef struct tb_tri {
    uint32_t v[3];
} tb_tri;

/* What the triangulator had to do (all zero for a simple polygon). */
typedef struct tb_triangulate_stats {
    uint32_t bridges;    /* holes joined by a bridge (each adds 2 triangles) */
    uint32_t splices;    /* holes joined at a vertex they share with the boundary */
    uint32_t splits;     /* rings split at a pinch vertex (each removes 2 triangles) */
    uint32_t degenerate; /* zero-area ears clipped (degenerate input) */
    uint32_t forced;     /* ears clipped without a valid-ear test (invalid input) */
} tb_triangulate_stats;

/* Triangulates a polygon with holes in the plane. `xy` holds the points,
 * 2 doubles each; the rings are consecutive runs of points of the sizes
 * ring_size[0..nrings-1]: ring 0 is the outer boundary, the others holes.
 * Either orientation is accepted for every ring. Appends tb_tri elements to
 * `tris` (an array of tb_tri) holding point indices 0 .. N-1 (N the total
 * point count); there are N - 2 + 2 * bridges - 2 * splits of them (see
 * `stats`, which may be NULL). TB_ERR_ARG for a ring of fewer than 3 points
 * or a non-finite coordinate; TB_ERR_NOMEM. */
tb_status tb_triangulate_2d(const double *xy, const uint32_t *ring_size, uint32_t nrings,
                            tb_array *tris, tb_triangulate_stats *stats);

/* Triangulates a polygon with holes in 3D: the points pts[idx[k]] (idx NULL:
 * pts[k]) for k = 0 .. N-1 in rings as above, projected to the dominant plane
 * of the outer ring's Newell normal (docs/meshing.md). Output triangles turn
 * counter-clockwise seen from the side the normal points to, and hold idx[k]
 * (or k when idx is NULL). */
tb_status tb_triangulate_3d(const tb_vec3 *pts, const uint32_t *idx, const uint32_t *ring_size,
                            uint32_t nrings, tb_array *tris, tb_triangulate_stats *stats);

#endif
