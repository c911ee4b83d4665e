/* Item buffer: an ID + depth buffer filled by software scan conversion of
 * polygons, for hemicube form factors and primary visibility.
 *
 * Pixel (i, j) covers [i, i+1] x [j, j+1] in pixel space and is sampled at its
 * centre; row 0 is at the top (y grows downwards). Coverage follows
 * util/itembuf/scan.h: vertices snapped to 1/256 pixel, exact edge arithmetic,
 * top-left rule, so polygons sharing edges cover every pixel exactly once.
 *
 * Depth: each vertex carries a depth that must vary LINEARLY IN SCREEN SPACE
 * (for a perspective projection pass z/w or 1/w, not the eye-space distance).
 * The depth of a pixel is the plane through three well-separated vertices
 * (unsnapped, in double) evaluated at its centre, then rounded to float.
 * Smaller depth wins; on equal (float) depth the LOWER item id wins, so the
 * result does not depend on drawing order. See docs/itembuf.md.
 */
#ifndef TB_UTIL_ITEMBUF_ITEMBUF_H
#define TB_UTIL_ITEMBUF_ITEMBUF_H

#include <stddef.h>
#include <stdint.h>
#include "util/base/error.h"
#include "util/itembuf/scan.h"

/* Id of pixels nothing was drawn into (and never a valid item id). */
#define TB_ITEMBUF_EMPTY UINT32_MAX

/* An item buffer. */
typedef struct tb_itembuf {
    int width, height;
    uint32_t *ids; /* width*height item ids, row 0 at the top; TB_ITEMBUF_EMPTY where empty */
    float *depth;  /* depth of the kept item per pixel; +INFINITY where empty */
} tb_itembuf;

/* A cleared width x height buffer (1 .. TB_SCAN_MAX_DIM each); NULL on failure. */
tb_itembuf *tb_itembuf_create(int width, int height);

/* Frees the buffer; NULL is allowed. */
void tb_itembuf_free(tb_itembuf *buf);

/* Sets every pixel to TB_ITEMBUF_EMPTY at depth +INFINITY. */
void tb_itembuf_clear(tb_itembuf *buf);

/* Draws a polygon of `n` vertices (pixel coordinates; convex or not; even-odd
 * rule if it crosses itself) with per-vertex `depth` (NULL: all 0) as item
 * `id`. Fewer than 3 vertices or collinear vertices draw nothing (TB_OK);
 * NaN/infinite input or id == TB_ITEMBUF_EMPTY draws nothing (TB_ERR_ARG). */
tb_status tb_itembuf_draw_polygon(tb_itembuf *buf, const float (*xy)[2], const float *depth, int n,
                                  uint32_t id);

/* Draws one item made of several contours (e.g. a polygon with holes):
 * contour k has counts[k] vertices, taken in order from `xy` and `depth`. */
tb_status tb_itembuf_draw_contours(tb_itembuf *buf, const float (*xy)[2], const float *depth,
                                   const int *counts, int ncontours, tb_fill_rule rule, uint32_t id);

/* Item id at pixel (x, y) (no bounds check). */
static inline uint32_t tb_itembuf_id(const tb_itembuf *buf, int x, int y)
{
    return buf->ids[(size_t)y * (size_t)buf->width + (size_t)x];
}

/* Depth at pixel (x, y) (no bounds check). */
static inline float tb_itembuf_depth(const tb_itembuf *buf, int x, int y)
{
    return buf->depth[(size_t)y * (size_t)buf->width + (size_t)x];
}

/* Adds, for each pixel holding an item id, the pixel's weight (weights:
 * width*height floats in pixel order; NULL counts pixels) to sum_per_id[id]
 * (accumulated in double). The sums are not zeroed first, so several buffers
 * (hemicube faces) can add into one array. TB_ERR_ARG, with nothing added, if
 * some pixel holds an id >= nids. */
tb_status tb_itembuf_accumulate(const tb_itembuf *buf, const float *weights, double *sum_per_id,
                                uint32_t nids);

#endif
