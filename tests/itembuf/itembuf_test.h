/* Helpers shared by the item buffer tests: a coverage counter fed by the span
 * callback, and an independent per-pixel reference for "is this pixel centre
 * inside this polygon" in exact integer arithmetic. */
#ifndef TB_TESTS_ITEMBUF_ITEMBUF_TEST_H
#define TB_TESTS_ITEMBUF_ITEMBUF_TEST_H

#include "tb_test.h"

#include <stdint.h>
#include <string.h>

#include "util/itembuf/scan.h"

/* pi (M_PI is not part of strict C17). */
#define TEST_PI 3.14159265358979323846

/* Per-pixel coverage counts, filled by cover_span(). */
typedef struct cover {
    int w, h;
    uint8_t *count;   /* w*h counters (saturating at 255) */
    long spans;       /* spans received */
    int last_y, last_x1; /* previous span, to check ordering */
} cover;

static inline void cover_init(cover *c, int w, int h)
{
    c->w = w;
    c->h = h;
    c->count = calloc((size_t)w * (size_t)h, 1);
    assert_non_null(c->count);
    c->spans = 0;
    c->last_y = -1;
    c->last_x1 = 0;
}

static inline void cover_reset_order(cover *c)
{
    c->last_y = -1;
    c->last_x1 = 0;
}

static inline void cover_free(cover *c)
{
    free(c->count);
    c->count = NULL;
}

/* The span callback: checks the documented span contract, then counts. */
static inline void cover_span(void *user, int y, int x0, int x1)
{
    cover *c = user;
    if (!(y >= 0 && y < c->h && x0 >= 0 && x0 < x1 && x1 <= c->w))
        fail_msg("bad span y=%d [%d, %d) in %dx%d", y, x0, x1, c->w, c->h);
    /* Top to bottom, left to right, no overlap within one polygon. */
    if (y < c->last_y || (y == c->last_y && x0 < c->last_x1))
        fail_msg("span y=%d [%d, %d) out of order after y=%d x1=%d", y, x0, x1, c->last_y,
                 c->last_x1);
    c->last_y = y;
    c->last_x1 = x1;
    c->spans++;
    for (int x = x0; x < x1; x++) {
        uint8_t *p = &c->count[(size_t)y * (size_t)c->w + (size_t)x];
        if (*p < 255)
            (*p)++;
    }
}

static inline long cover_total(const cover *c)
{
    long n = 0;
    for (size_t i = 0; i < (size_t)c->w * (size_t)c->h; i++)
        n += c->count[i];
    return n;
}

/* Scans one polygon into `c` (resetting only the ordering check). */
static inline tb_status cover_polygon(cover *c, const float (*xy)[2], int n)
{
    cover_reset_order(c);
    return tb_scan_polygon(c->w, c->h, xy, n, cover_span, c);
}

/* Reference inside test for the centre of pixel (i, j) against contours whose
 * vertices lie on the 1/256 grid (the test builds them so, which makes the
 * scan converter's snapping the identity). Casts a ray from the centre to +x
 * and counts the edges it crosses, with the sample moved by (+e, +e^2): an
 * edge counts if its y range [ymin, ymax) holds the sample row and it crosses
 * strictly to the right of the centre. Returns the winding number (its parity
 * is the even-odd answer); no division, everything exact in int64. */
static inline int ref_winding(const float (*xy)[2], const int *counts, int ncontours, int i, int j)
{
    const int64_t px = 256 * (int64_t)i + 128, py = 256 * (int64_t)j + 128;
    int w = 0;
    for (int c = 0, first = 0; c < ncontours; first += counts[c], c++) {
        if (counts[c] < 3)
            continue;
        for (int k = 0; k < counts[c]; k++) {
            const float *a = xy[first + k], *b = xy[first + (k + 1) % counts[c]];
            int64_t ax = (int64_t)(a[0] * 256.0), ay = (int64_t)(a[1] * 256.0);
            int64_t bx = (int64_t)(b[0] * 256.0), by = (int64_t)(b[1] * 256.0);
            if (ay == by)
                continue;
            int down = by > ay;
            int64_t tx = down ? ax : bx, ty = down ? ay : by, ux = down ? bx : ax, uy = down ? by : ay;
            if (py < ty || py >= uy)
                continue;
            /* crossing x > px  <=>  (tx - px)(uy - ty) + (py - ty)(ux - tx) > 0 */
            if ((tx - px) * (uy - ty) + (py - ty) * (ux - tx) > 0)
                w += down ? 1 : -1;
        }
    }
    return w;
}

/* Reference coverage of pixel (i, j) under `rule`. */
static inline int ref_inside(const float (*xy)[2], const int *counts, int ncontours,
                             tb_fill_rule rule, int i, int j)
{
    int w = ref_winding(xy, counts, ncontours, i, j);
    return rule == TB_FILL_NONZERO ? w != 0 : (w & 1);
}

/* A uniform value in [lo, hi) rounded to a multiple of 1/2^bits. */
static inline float grid_rand(tb_rng *r, double lo, double hi, int bits)
{
    double v = lo + (hi - lo) * tb_rng_double(r);
    return (float)(floor(v * (double)(1 << bits)) / (double)(1 << bits));
}

#endif
