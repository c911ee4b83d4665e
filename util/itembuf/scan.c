#include "util/itembuf/scan.h"

#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* Sub-pixel units per pixel, and the sample offset (pixel centre) in them. */
#define TB__ONE ((int64_t)1 << TB_SCAN_SUBPIXEL_BITS)
#define TB__HALF (TB__ONE / 2)
/* Polygons up to this many vertices need no heap scratch memory. */
#define TB__SMALL 64

typedef struct tb__dpt {
    double x, y;
} tb__dpt;

typedef struct tb__ipt {
    int64_t x, y; /* snapped, in 1/256 pixel */
} tb__ipt;

/* A non-horizontal edge, stored top (smaller y) to bottom. */
typedef struct tb__edge {
    int64_t xt, yt; /* top endpoint */
    int64_t dx, dy; /* bottom minus top; dy > 0 */
    int row0, row1; /* rows [row0, row1) whose sample y lies in [yt, yt + dy), clamped */
    int dir;        /* +1 if the contour runs downwards along the edge, -1 upwards */
} tb__edge;

/* Where an edge crosses a row: pixels x >= `x` lie right of it (or on it). */
typedef struct tb__cross {
    int x;
    int dir;
} tb__cross;

/* ceil(num / den) for den > 0 (C division truncates towards zero). */
static int64_t tb__ceil_div(int64_t num, int64_t den)
{
    int64_t q = num / den;
    return q + (num % den != 0 && num > 0);
}

static int64_t tb__snap(double v)
{
    return (int64_t)nearbyint(v * (double)TB__ONE);
}

/* ---------------------------------------------------------------- clipping */

/* Point where segment p-q meets coordinate `axis` == `bound`. Computed from the
 * endpoints in a fixed (lexicographic) order, so that the same edge walked in
 * either direction, by either of the two polygons sharing it, yields the same
 * bits. */
static tb__dpt tb__intersect(tb__dpt p, tb__dpt q, int axis, double bound)
{
    if (q.x < p.x || (q.x == p.x && q.y < p.y)) {
        tb__dpt t = p;
        p = q;
        q = t;
    }
    tb__dpt r;
    if (axis == 0) {
        double t = (bound - p.x) / (q.x - p.x);
        r.x = bound;
        r.y = p.y + t * (q.y - p.y);
    } else {
        double t = (bound - p.y) / (q.y - p.y);
        r.x = p.x + t * (q.x - p.x);
        r.y = bound;
    }
    return r;
}

/* Sutherland-Hodgman against the half-plane sign * coord[axis] <= L. `out`
 * holds room for 2 n points; returns the output count. Clipping a contour keeps
 * the winding number of every point inside the half-plane, so it is valid for
 * non-convex contours and both fill rules. */
static int tb__clip_half(const tb__dpt *in, int n, tb__dpt *out, int axis, double sign)
{
    const double L = TB_SCAN_COORD_LIMIT;
    int m = 0;
    for (int i = 0; i < n; i++) {
        tb__dpt a = in[i], b = in[i + 1 < n ? i + 1 : 0];
        double ca = axis == 0 ? a.x : a.y, cb = axis == 0 ? b.x : b.y;
        int ain = sign * ca <= L, bin = sign * cb <= L;
        if (ain)
            out[m++] = a;
        if (ain != bin)
            out[m++] = tb__intersect(a, b, axis, sign * L);
    }
    return m;
}

/* Clips one contour to the box [-L, L]^2; returns a malloc'ed array (count in
 * *nout) or NULL when out of memory. */
static tb__dpt *tb__clip_contour(const float (*xy)[2], int n, int *nout)
{
    tb__dpt *a = malloc((size_t)n * sizeof *a);
    if (!a)
        return NULL;
    for (int i = 0; i < n; i++)
        a[i] = (tb__dpt){xy[i][0], xy[i][1]};
    static const struct {
        int axis;
        double sign;
    } planes[4] = {{0, 1.0}, {0, -1.0}, {1, 1.0}, {1, -1.0}};
    for (int k = 0; k < 4 && n > 0; k++) {
        tb__dpt *b = malloc((size_t)n * 2 * sizeof *b);
        if (!b) {
            free(a);
            return NULL;
        }
        n = tb__clip_half(a, n, b, planes[k].axis, planes[k].sign);
        free(a);
        a = b;
    }
    *nout = n;
    return a;
}

/* ---------------------------------------------------------------- scanning */

static int tb__cmp_edge(const void *a, const void *b)
{
    const tb__edge *x = a, *y = b;
    return (x->row0 > y->row0) - (x->row0 < y->row0);
}

static int tb__cmp_cross(const void *a, const void *b)
{
    const tb__cross *x = a, *y = b;
    return (x->x > y->x) - (x->x < y->x);
}

/* Appends the edge a -> b if it is not horizontal and meets a row of the grid. */
static void tb__add_edge(tb__edge *edges, int *nedges, tb__ipt a, tb__ipt b, int height)
{
    if (a.y == b.y)
        return; /* horizontal: handled by its neighbours' half-open row ranges */
    tb__edge e;
    e.dir = b.y > a.y ? 1 : -1;
    tb__ipt t = e.dir > 0 ? a : b, u = e.dir > 0 ? b : a;
    e.xt = t.x;
    e.yt = t.y;
    e.dx = u.x - t.x;
    e.dy = u.y - t.y;
    /* Row j samples y = j + 1/2, i.e. 256 j + 128: rows with yt <= that < yb. */
    int64_t r0 = tb__ceil_div(t.y - TB__HALF, TB__ONE), r1 = tb__ceil_div(u.y - TB__HALF, TB__ONE);
    if (r0 < 0)
        r0 = 0;
    if (r1 > height)
        r1 = height;
    if (r0 >= r1)
        return;
    e.row0 = (int)r0;
    e.row1 = (int)r1;
    edges[(*nedges)++] = e;
}

/* Sorts a row's crossings by x: insertion sort for the usual few, qsort beyond. */
static void tb__sort_cross(tb__cross *c, int m)
{
    if (m > 32) {
        qsort(c, (size_t)m, sizeof *c, tb__cmp_cross);
        return;
    }
    for (int i = 1; i < m; i++) {
        tb__cross v = c[i];
        int k = i;
        for (; k > 0 && c[k - 1].x > v.x; k--)
            c[k] = c[k - 1];
        c[k] = v;
    }
}

/* Emits the spans of the edges (sorted by row0). */
static void tb__scan_edges(tb__edge *edges, int nedges, int *active, tb__cross *cross, int width,
                           tb_fill_rule rule, tb_span_fn fn, void *user)
{
    int row_end = 0;
    for (int k = 0; k < nedges; k++)
        if (edges[k].row1 > row_end)
            row_end = edges[k].row1;
    int next = 0, nactive = 0;
    for (int j = edges[0].row0; j < row_end; j++) {
        while (next < nedges && edges[next].row0 <= j)
            active[nactive++] = next++;
        int keep = 0;
        for (int k = 0; k < nactive; k++)
            if (edges[active[k]].row1 > j)
                active[keep++] = active[k];
        nactive = keep;
        if (nactive == 0)
            continue; /* a gap between parts of the polygon */

        const int64_t Y = (int64_t)j * TB__ONE + TB__HALF;
        for (int k = 0; k < nactive; k++) {
            const tb__edge *e = &edges[active[k]];
            /* First pixel whose centre 256 i + 128 is >= the crossing
             * xt + (Y - yt) dx / dy; magnitudes stay below 2^61. */
            int64_t ix = tb__ceil_div((e->xt - TB__HALF) * e->dy + (Y - e->yt) * e->dx,
                                      TB__ONE * e->dy);
            cross[k].x = ix < 0 ? 0 : ix > width ? width : (int)ix;
            cross[k].dir = e->dir;
        }
        tb__sort_cross(cross, nactive);
        int w = 0, start = 0;
        for (int k = 0; k < nactive; k++) {
            int was = rule == TB_FILL_NONZERO ? w != 0 : (w & 1);
            w += cross[k].dir;
            int now = rule == TB_FILL_NONZERO ? w != 0 : (w & 1);
            if (!was && now)
                start = cross[k].x;
            else if (was && !now && cross[k].x > start)
                fn(user, j, start, cross[k].x);
        }
    }
}

tb_status tb_scan_contours(int width, int height, const float (*xy)[2], const int *counts,
                           int ncontours, tb_fill_rule rule, tb_span_fn fn, void *user)
{
    if (width < 1 || height < 1 || width > TB_SCAN_MAX_DIM || height > TB_SCAN_MAX_DIM)
        return tb_error(TB_ERR_ARG, "scan: size %dx%d outside 1..%d", width, height, TB_SCAN_MAX_DIM);
    if (!fn || ncontours < 0 || (ncontours > 0 && !counts))
        return tb_error(TB_ERR_ARG, "scan: missing callback or contour counts");
    if (rule != TB_FILL_EVEN_ODD && rule != TB_FILL_NONZERO)
        return tb_error(TB_ERR_ARG, "scan: unknown fill rule %d", (int)rule);
    int total = 0;
    for (int c = 0; c < ncontours; c++) {
        if (counts[c] < 0 || counts[c] > INT_MAX / 16 - total)
            return tb_error(TB_ERR_ARG, "scan: bad vertex count %d in contour %d", counts[c], c);
        total += counts[c];
    }
    if (total > 0 && !xy)
        return tb_error(TB_ERR_ARG, "scan: NULL vertex array");
    int clip = 0;
    for (int i = 0; i < total; i++) {
        double x = xy[i][0], y = xy[i][1];
        if (!isfinite(x) || !isfinite(y))
            return tb_error(TB_ERR_ARG, "scan: vertex %d is not finite (%g, %g)", i, x, y);
        clip |= fabs(x) > TB_SCAN_COORD_LIMIT || fabs(y) > TB_SCAN_COORD_LIMIT;
    }

    /* Snapped vertices and the contour sizes after clipping. */
    tb__ipt small_pts[TB__SMALL];
    int small_counts[TB__SMALL];
    tb__ipt *pts = small_pts;
    int *cnt = small_counts;
    tb__dpt **clipped = NULL;
    int npts = total;
    tb_status st = TB_OK;
    if (clip) {
        clipped = calloc((size_t)ncontours, sizeof *clipped);
        cnt = malloc((size_t)ncontours * sizeof *cnt);
        if (!clipped || !cnt) {
            st = tb_error(TB_ERR_NOMEM, "scan: out of memory clipping %d contours", ncontours);
            goto done;
        }
        npts = 0;
        for (int c = 0, first = 0; c < ncontours; first += counts[c], c++) {
            cnt[c] = 0;
            if (counts[c] < 3)
                continue;
            clipped[c] = tb__clip_contour(xy + first, counts[c], &cnt[c]);
            if (!clipped[c]) {
                st = tb_error(TB_ERR_NOMEM, "scan: out of memory clipping %d vertices", counts[c]);
                goto done;
            }
            npts += cnt[c];
        }
    } else if (ncontours > TB__SMALL) {
        cnt = malloc((size_t)ncontours * sizeof *cnt);
        if (!cnt) {
            st = tb_error(TB_ERR_NOMEM, "scan: out of memory for %d contours", ncontours);
            goto done;
        }
    }
    if (!clip && ncontours > 0)
        memcpy(cnt, counts, (size_t)ncontours * sizeof *cnt);
    if (npts > TB__SMALL && !(pts = malloc((size_t)npts * sizeof *pts))) {
        st = tb_error(TB_ERR_NOMEM, "scan: out of memory for %d vertices", npts);
        goto done;
    }
    for (int c = 0, k = 0, first = 0; c < ncontours; first += counts[c], c++)
        for (int i = 0; i < cnt[c]; i++, k++)
            pts[k] = clip ? (tb__ipt){tb__snap(clipped[c][i].x), tb__snap(clipped[c][i].y)}
                          : (tb__ipt){tb__snap(xy[first + i][0]), tb__snap(xy[first + i][1])};

    /* Edges (at most one per vertex), the active list and a row's crossings. */
    tb__edge small_edges[TB__SMALL];
    int small_active[TB__SMALL];
    tb__cross small_cross[TB__SMALL];
    tb__edge *edges = small_edges;
    int *active = small_active;
    tb__cross *cross = small_cross;
    if (npts > TB__SMALL) {
        edges = malloc((size_t)npts * sizeof *edges);
        active = malloc((size_t)npts * sizeof *active);
        cross = malloc((size_t)npts * sizeof *cross);
        if (!edges || !active || !cross) {
            st = tb_error(TB_ERR_NOMEM, "scan: out of memory for %d edges", npts);
            goto free_edges;
        }
    }
    int nedges = 0;
    for (int c = 0, first = 0; c < ncontours; first += cnt[c], c++) {
        if (cnt[c] < 3)
            continue; /* a point or a segment has no interior */
        for (int i = 0; i < cnt[c]; i++)
            tb__add_edge(edges, &nedges, pts[first + i], pts[first + (i + 1 < cnt[c] ? i + 1 : 0)],
                         height);
    }
    if (nedges > 0) {
        qsort(edges, (size_t)nedges, sizeof *edges, tb__cmp_edge);
        tb__scan_edges(edges, nedges, active, cross, width, rule, fn, user);
    }
free_edges:
    if (edges != small_edges) {
        free(edges);
        free(active);
        free(cross);
    }
done:
    if (pts != small_pts)
        free(pts);
    if (cnt != small_counts)
        free(cnt);
    if (clipped) {
        for (int c = 0; c < ncontours; c++)
            free(clipped[c]);
        free(clipped);
    }
    return st;
}

tb_status tb_scan_polygon(int width, int height, const float (*xy)[2], int n, tb_span_fn fn,
                          void *user)
{
    if (n < 0)
        return tb_error(TB_ERR_ARG, "scan: negative vertex count %d", n);
    return tb_scan_contours(width, height, xy, &n, 1, TB_FILL_EVEN_ODD, fn, user);
}
