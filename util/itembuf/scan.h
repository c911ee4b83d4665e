/* Exact scan conversion of polygons (convex, non-convex, several contours)
 * into horizontal pixel spans; the item buffer draws with it.
 *
 * Conventions (see docs/itembuf.md):
 * - Pixel (i, j) covers [i, i+1] x [j, j+1] and is sampled at its centre
 *   (i + 0.5, j + 0.5); y grows downwards (row 0 at the top).
 * - Vertices are snapped to a grid of 1/256 pixel (round to nearest, ties to
 *   even); everything after that is exact 64-bit integer arithmetic.
 * - A pixel is covered when its centre is inside by the chosen fill rule.
 *   Centres exactly on an edge follow the top-left rule: covered when the
 *   interior lies to the right of the edge (a left edge) or, for a horizontal
 *   edge, below it (a top edge). Equivalently the sample is moved by an
 *   infinitesimal (+e, +e^2). Polygons that share an edge therefore never both
 *   cover, and never both miss, a centre on it: a mesh is drawn exactly once.
 * - Vertices farther than TB_SCAN_COORD_LIMIT pixels from the origin are first
 *   clipped to that box (in double; a shared edge is clipped identically by both
 *   of its polygons, so the exactness survives).
 */
#ifndef TB_UTIL_ITEMBUF_SCAN_H
#define TB_UTIL_ITEMBUF_SCAN_H

#include "util/base/error.h"

/* Bits of sub-pixel precision of snapped vertices. */
#define TB_SCAN_SUBPIXEL_BITS 8

/* Largest width or height accepted. */
#define TB_SCAN_MAX_DIM (1 << 20)

/* Vertices are clipped to [-L, L]^2 (pixels) with L = TB_SCAN_COORD_LIMIT, which
 * keeps every product of the edge arithmetic below 2^62. */
#define TB_SCAN_COORD_LIMIT 2097152.0

/* How overlapping contours (or a self-intersecting contour) combine. */
typedef enum tb_fill_rule {
    TB_FILL_EVEN_ODD = 0, /* inside if a ray from the point crosses the outline an odd number of times */
    TB_FILL_NONZERO = 1,  /* inside if the winding number of the outline around the point is not 0 */
} tb_fill_rule;

/* Receives the covered pixels x0 .. x1-1 of row y (0 <= x0 < x1 <= width).
 * Spans come row by row, top to bottom, left to right, and never overlap. */
typedef void (*tb_span_fn)(void *user, int y, int x0, int x1);

/* Scan-converts `ncontours` closed contours, contour k having counts[k]
 * vertices taken in order from `xy`, into a width x height pixel grid.
 * Contours with fewer than 3 vertices and zero-area polygons produce nothing
 * (TB_OK). TB_ERR_ARG for NaN or infinite coordinates, bad sizes or counts
 * (then nothing is emitted); TB_ERR_NOMEM if scratch memory fails. */
tb_status tb_scan_contours(int width, int height, const float (*xy)[2], const int *counts,
                           int ncontours, tb_fill_rule rule, tb_span_fn fn, void *user);

/* tb_scan_contours() of one contour of `n` vertices (the fill rule only matters
 * if it intersects itself; even-odd is used). */
tb_status tb_scan_polygon(int width, int height, const float (*xy)[2], int n, tb_span_fn fn,
                          void *user);

#endif
