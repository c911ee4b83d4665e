/* Ear clipping for polygons with holes (docs/meshing.md, "Triangulation").
 *
 * Outline:
 *  1. Each ring becomes a circular doubly linked list of nodes; the outer ring
 *     is made counter-clockwise and the holes clockwise, so the polygon's
 *     inside is always on the left of an edge.
 *  2. Holes are joined to the outer ring one at a time: where a hole shares a
 *     point with the ring it is spliced in there (no new edge), otherwise a
 *     bridge is cut from its rightmost vertex to a visible ring vertex
 *     (Eberly's ray cast), checked exactly before it is used.
 *  3. Ears are clipped best-first (by triangle shape) from an indexed priority
 *     queue. An ear at b (neighbours a, c) is valid if a, b, c turn strictly
 *     counter-clockwise and no other node lies in the closed triangle, where
 *     a node at the same position as a, b or c counts only if its own wedge
 *     overlaps the triangle's corner there. Only reflex/flat nodes and nodes
 *     sharing a position with another node can spoil an ear, so only those
 *     ("candidates") are kept in a uniform grid for the containment search.
 *  4. A valid ear stays valid until its neighbours change. An invalid one is
 *     filed under the candidate that spoiled it and re-tested when that
 *     candidate is clipped or changes, so no full rescans are needed.
 *  5. If no valid ear exists (only for touching or degenerate input), the
 *     ring is split at a pinch point, or a zero-area ear is clipped, or, for
 *     invalid input, any convex ear is clipped ("forced").
 *
 * All orientation decisions use the exact tb_orient2d; floating-point
 * estimates are used only to rank choices (ear quality, the ray hit), and the
 * resulting bridge is verified exactly. */
#include "util/mesh/triangulate.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "util/container/pqueue.h"
#include "util/mesh/polygon.h"
#include "util/mesh/predicates.h"

#define TB__NONE UINT32_MAX

/* One vertex of a ring. */
typedef struct tb__node {
    double x, y;
    uint32_t id;         /* output index (copies made by bridges share it) */
    uint32_t prev, next; /* ring neighbours */
    uint32_t stamp;      /* bumped when the neighbours change; stale blocked entries are skipped */
    uint32_t group;      /* first node of the set of nodes at this position, or NONE if alone */
    uint32_t group_next; /* next node of that set, or NONE */
    uint32_t cell;       /* grid cell listing this candidate, or NONE */
    uint32_t cell_pos;   /* slot in that cell */
    uint32_t live_pos;   /* slot in the list of all candidates */
    uint32_t blocked;    /* head of the list of ears this node spoils (block pool index), or NONE */
    uint32_t ring;       /* ring number: 0 = outer (and everything joined to it) */
    bool alive;
} tb__node;

/* "Ear `node` (as of `stamp`) is spoiled by the node whose list this is on." */
typedef struct tb__block {
    uint32_t node, stamp, next;
} tb__block;

typedef struct tb__ctx {
    tb__node *n;
    uint32_t nnodes;   /* nodes in use (input points, then bridge copies) */
    uint32_t npoints;  /* input points */
    uint32_t alive;    /* nodes still in some ring */
    uint32_t cursor;   /* where fallback scans resume */
    /* candidate grid */
    double gx0, gy0, gsx, gsy; /* origin and cells per unit length */
    uint32_t gnx, gny;
    uint32_t *cell_start, *cell_count, *cell_items;
    uint32_t *live;  /* all candidates, for ears whose box covers more cells than there are candidates */
    uint32_t nlive;
    tb_array blocks; /* tb__block pool */
    tb_pqueue pq;    /* valid ears by shape quality */
    tb_array *out;
    tb_triangulate_stats st;
    tb_status err; /* first allocation failure inside a void helper */
} tb__ctx;

/* ------------------------------------------------------------ small helpers */

static inline double tb__orient(const tb__ctx *c, uint32_t a, uint32_t b, uint32_t p)
{
    const tb__node *n = c->n;
    return tb_orient2d(n[a].x, n[a].y, n[b].x, n[b].y, n[p].x, n[p].y);
}

static inline bool tb__same_pos(const tb__ctx *c, uint32_t a, uint32_t b)
{
    return c->n[a].x == c->n[b].x && c->n[a].y == c->n[b].y;
}

static inline int tb__sgn(double v) { return (v > 0) - (v < 0); }

/* True if o->a and o->b point the same way (collinear, same side of o, both
 * non-zero). Signs of coordinate differences are exact. */
static bool tb__same_dir(const tb__ctx *c, uint32_t o, uint32_t a, uint32_t b)
{
    const tb__node *n = c->n;
    int ax = tb__sgn(n[a].x - n[o].x), ay = tb__sgn(n[a].y - n[o].y);
    int bx = tb__sgn(n[b].x - n[o].x), by = tb__sgn(n[b].y - n[o].y);
    if ((ax == 0 && ay == 0) || (bx == 0 && by == 0))
        return false;
    return ax == bx && ay == by && tb__orient(c, o, a, b) == 0;
}

/* Is the direction o->d strictly inside the counter-clockwise arc from o->s
 * to o->e? Arcs of 0 or 360 degrees (s and e the same way) count as full,
 * and so do arcs with a zero-length side: the conservative answer, since this
 * is used to decide whether something is in the way. */
static bool tb__in_arc(const tb__ctx *c, uint32_t o, uint32_t s, uint32_t e, uint32_t d)
{
    if (tb__same_pos(c, o, s) || tb__same_pos(c, o, e))
        return true;
    double ose = tb__orient(c, o, s, e);
    double osd = tb__orient(c, o, s, d);
    double oed = tb__orient(c, o, e, d);
    if (ose > 0)
        return osd > 0 && oed < 0;
    if (ose < 0)
        return osd > 0 || oed < 0;
    if (tb__same_dir(c, o, s, e))
        return !tb__same_dir(c, o, s, d);
    return osd > 0; /* s and e opposite: a half plane */
}

/* Does the wedge of node p (counter-clockwise from p->next to p->prev: the
 * polygon's inside at p) overlap the open corner of a triangle at p's
 * position, spanning counter-clockwise from o->t1 to o->t2 (< 180 degrees)? */
static bool tb__wedge_overlap(const tb__ctx *c, uint32_t o, uint32_t t1, uint32_t t2, uint32_t p)
{
    uint32_t w1 = c->n[p].next, w2 = c->n[p].prev;
    if (tb__same_pos(c, p, w1) || tb__same_pos(c, p, w2))
        return true;
    /* Two open arcs meet iff one starts inside the other or both start together. */
    return tb__in_arc(c, o, t1, t2, w1) || tb__in_arc(c, o, w1, w2, t1) || tb__same_dir(c, o, t1, w1);
}

/* ---------------------------------------------------------------- the grid */

static inline uint32_t tb__cell_x(const tb__ctx *c, double x)
{
    double f = (x - c->gx0) * c->gsx;
    if (!(f > 0))
        return 0;
    return f >= (double)(c->gnx - 1) ? c->gnx - 1 : (uint32_t)f;
}

static inline uint32_t tb__cell_y(const tb__ctx *c, double y)
{
    double f = (y - c->gy0) * c->gsy;
    if (!(f > 0))
        return 0;
    return f >= (double)(c->gny - 1) ? c->gny - 1 : (uint32_t)f;
}

static void tb__grid_remove(tb__ctx *c, uint32_t i)
{
    tb__node *n = c->n;
    uint32_t cell = n[i].cell;
    if (cell == TB__NONE)
        return;
    uint32_t last = c->cell_start[cell] + --c->cell_count[cell];
    uint32_t moved = c->cell_items[last];
    c->cell_items[n[i].cell_pos] = moved;
    n[moved].cell_pos = n[i].cell_pos;
    n[i].cell = TB__NONE;
    uint32_t lmoved = c->live[--c->nlive];
    c->live[n[i].live_pos] = lmoved;
    n[lmoved].live_pos = n[i].live_pos;
}

/* Builds the grid of candidate nodes (reflex or flat, or sharing a position). */
static tb_status tb__grid_build(tb__ctx *c, uint32_t start)
{
    tb__node *n = c->n;
    double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
    uint32_t ncand = 0;
    uint32_t i = start;
    do {
        x0 = fmin(x0, n[i].x), x1 = fmax(x1, n[i].x);
        y0 = fmin(y0, n[i].y), y1 = fmax(y1, n[i].y);
        bool cand = n[i].group != TB__NONE || tb__orient(c, n[i].prev, i, n[i].next) <= 0;
        n[i].cell = cand ? 0 : TB__NONE; /* mark; the real cell comes below */
        ncand += cand;
        i = n[i].next;
    } while (i != start);
    /* About one candidate per cell, cells shaped like the bounding box. */
    double w = x1 - x0, h = y1 - y0;
    double target = ncand > 0 ? (double)ncand : 1.0;
    double nx = 1, ny = 1;
    if (w > 0 && h > 0) {
        nx = ceil(sqrt(target * w / h));
        ny = ceil(target / nx);
    } else if (w > 0) {
        nx = target;
    } else if (h > 0) {
        ny = target;
    }
    nx = fmin(fmax(nx, 1), 1 << 12);
    ny = fmin(fmax(ny, 1), 1 << 12);
    c->gnx = (uint32_t)nx, c->gny = (uint32_t)ny;
    c->gx0 = x0, c->gy0 = y0;
    c->gsx = w > 0 ? nx / w : 0;
    c->gsy = h > 0 ? ny / h : 0;
    size_t ncells = (size_t)c->gnx * c->gny;
    c->cell_start = calloc(ncells + 1, sizeof(uint32_t));
    c->cell_count = calloc(ncells, sizeof(uint32_t));
    c->cell_items = malloc(((size_t)ncand + 1) * sizeof(uint32_t));
    c->live = malloc(((size_t)ncand + 1) * sizeof(uint32_t));
    if (!c->cell_start || !c->cell_count || !c->cell_items || !c->live)
        return tb_error(TB_ERR_NOMEM, "triangulate: out of memory for the search grid");
    i = start;
    do {
        if (n[i].cell != TB__NONE) {
            n[i].cell = tb__cell_y(c, n[i].y) * c->gnx + tb__cell_x(c, n[i].x);
            c->cell_count[n[i].cell]++;
        }
        i = n[i].next;
    } while (i != start);
    uint32_t sum = 0;
    for (size_t k = 0; k < ncells; k++) {
        c->cell_start[k] = sum;
        sum += c->cell_count[k];
        c->cell_count[k] = 0;
    }
    c->cell_start[ncells] = sum;
    i = start;
    do {
        if (n[i].cell != TB__NONE) {
            uint32_t cell = n[i].cell;
            n[i].cell_pos = c->cell_start[cell] + c->cell_count[cell]++;
            c->cell_items[n[i].cell_pos] = i;
            n[i].live_pos = c->nlive;
            c->live[c->nlive++] = i;
        }
        i = n[i].next;
    } while (i != start);
    return TB_OK;
}

/* ---------------------------------------------------------------- ear tests */

enum { TB__EAR_OK, TB__EAR_NO, TB__EAR_BLOCKED };

/* Does candidate p spoil the ear (a, b, cc) with bounding box x0..x1, y0..y1? */
static inline bool tb__spoils(const tb__ctx *c, uint32_t a, uint32_t b, uint32_t cc, uint32_t p,
                              double x0, double x1, double y0, double y1)
{
    const tb__node *n = c->n;
    if (p == a || p == b || p == cc)
        return false;
    double px = n[p].x, py = n[p].y;
    if (px < x0 || px > x1 || py < y0 || py > y1)
        return false;
    if (tb__same_pos(c, p, a))
        return tb__wedge_overlap(c, a, b, cc, p);
    if (tb__same_pos(c, p, b))
        return tb__wedge_overlap(c, b, cc, a, p);
    if (tb__same_pos(c, p, cc))
        return tb__wedge_overlap(c, cc, a, b, p);
    return tb__orient(c, a, b, p) >= 0 && tb__orient(c, b, cc, p) >= 0 && tb__orient(c, cc, a, p) >= 0;
}

/* Is b an ear? On TB__EAR_BLOCKED, *blocker is a candidate that spoils it. */
static int tb__ear_test(const tb__ctx *c, uint32_t b, uint32_t *blocker)
{
    const tb__node *n = c->n;
    uint32_t a = n[b].prev, cc = n[b].next;
    if (a == cc)
        return TB__EAR_NO;
    if (!(tb__orient(c, a, b, cc) > 0))
        return TB__EAR_NO;
    double x0 = fmin(n[a].x, fmin(n[b].x, n[cc].x)), x1 = fmax(n[a].x, fmax(n[b].x, n[cc].x));
    double y0 = fmin(n[a].y, fmin(n[b].y, n[cc].y)), y1 = fmax(n[a].y, fmax(n[b].y, n[cc].y));
    uint32_t cx0 = tb__cell_x(c, x0), cx1 = tb__cell_x(c, x1);
    uint32_t cy0 = tb__cell_y(c, y0), cy1 = tb__cell_y(c, y1);
    if ((uint64_t)(cx1 - cx0 + 1) * (cy1 - cy0 + 1) > c->nlive) {
        /* Fewer candidates left than cells to visit: check them all. */
        for (uint32_t k = 0; k < c->nlive; k++) {
            uint32_t p = c->live[k];
            if (tb__spoils(c, a, b, cc, p, x0, x1, y0, y1)) {
                *blocker = p;
                return TB__EAR_BLOCKED;
            }
        }
        return TB__EAR_OK;
    }
    const uint32_t tv[3] = {a, b, cc};
    for (uint32_t gy = cy0; gy <= cy1; gy++) {
        /* Only the cells of this row that the triangle can reach: its x
         * extent within the row's y slab (thin diagonal ears cover a small
         * part of their bounding box). The slab is widened by a quarter row
         * and the x range by a cell, far more than the rounding of the cell
         * arithmetic, so no candidate of the row is missed. */
        uint32_t rx0 = cx0, rx1 = cx1;
        if (cy1 > cy0 && c->gsy > 0) {
            double ylo = fmax(y0, c->gy0 + (gy - 0.25) / c->gsy);
            double yhi = fmin(y1, c->gy0 + (gy + 1.25) / c->gsy);
            double sx0 = INFINITY, sx1 = -INFINITY;
            for (int k = 0; k < 3; k++) {
                const tb__node *p = &n[tv[k]], *q = &n[tv[(k + 1) % 3]];
                double py = p->y, qy = q->y;
                if (fmax(py, qy) < ylo || fmin(py, qy) > yhi)
                    continue;
                if (py == qy) {
                    sx0 = fmin(sx0, fmin(p->x, q->x));
                    sx1 = fmax(sx1, fmax(p->x, q->x));
                    continue;
                }
                double ta = (fmax(fmin(py, qy), ylo) - py) / (qy - py);
                double tb = (fmin(fmax(py, qy), yhi) - py) / (qy - py);
                double xa = p->x + ta * (q->x - p->x), xb = p->x + tb * (q->x - p->x);
                sx0 = fmin(sx0, fmin(xa, xb));
                sx1 = fmax(sx1, fmax(xa, xb));
            }
            if (sx0 <= sx1) {
                uint32_t lo = tb__cell_x(c, sx0), hi = tb__cell_x(c, sx1);
                rx0 = lo > cx0 ? lo - 1 : cx0;
                rx1 = hi < cx1 ? hi + 1 : cx1;
            }
        }
        for (uint32_t gx = rx0; gx <= rx1; gx++) {
            uint32_t cell = gy * c->gnx + gx;
            const uint32_t *items = c->cell_items + c->cell_start[cell];
            for (uint32_t k = 0, m = c->cell_count[cell]; k < m; k++) {
                uint32_t p = items[k];
                bool spoils = tb__spoils(c, a, b, cc, p, x0, x1, y0, y1);
                if (spoils) {
                    *blocker = p;
                    return TB__EAR_BLOCKED;
                }
            }
        }
    }
    return TB__EAR_OK;
}

/* Shape quality of triangle a b c: 2 * area / (sum of squared edges); the
 * equilateral triangle scores highest. Only ranks ears. */
static double tb__quality(const tb__ctx *c, uint32_t a, uint32_t b, uint32_t cc)
{
    const tb__node *n = c->n;
    double ab = (n[b].x - n[a].x) * (n[b].x - n[a].x) + (n[b].y - n[a].y) * (n[b].y - n[a].y);
    double bc = (n[cc].x - n[b].x) * (n[cc].x - n[b].x) + (n[cc].y - n[b].y) * (n[cc].y - n[b].y);
    double ca = (n[a].x - n[cc].x) * (n[a].x - n[cc].x) + (n[a].y - n[cc].y) * (n[a].y - n[cc].y);
    double s = ab + bc + ca;
    double q = s > 0 ? tb_orient2d_fast(n[a].x, n[a].y, n[b].x, n[b].y, n[cc].x, n[cc].y) / s : 0;
    return isfinite(q) ? q : 0;
}

/* Re-evaluates node i: into the queue if it is an ear, else off it (and
 * filed under its blocker). */
static void tb__test(tb__ctx *c, uint32_t i)
{
    tb__node *n = c->n;
    if (!n[i].alive)
        return;
    uint32_t blocker = TB__NONE;
    int r = tb__ear_test(c, i, &blocker);
    if (r == TB__EAR_OK) {
        tb_status st = tb_pqueue_set(&c->pq, i, tb__quality(c, n[i].prev, i, n[i].next));
        if (st && !c->err)
            c->err = st;
        return;
    }
    tb_pqueue_remove(&c->pq, i);
    if (r == TB__EAR_BLOCKED) {
        tb__block blk = {i, n[i].stamp, n[blocker].blocked};
        tb_status st = tb_array_push(&c->blocks, &blk);
        if (st) {
            if (!c->err)
                c->err = st;
            return;
        }
        n[blocker].blocked = (uint32_t)(c->blocks.len - 1);
    }
}

/* Re-tests every ear that node i was spoiling (i died or changed). */
static void tb__release(tb__ctx *c, uint32_t i)
{
    uint32_t k = c->n[i].blocked;
    c->n[i].blocked = TB__NONE; /* detach first: re-tests may file entries under i again */
    while (k != TB__NONE) {
        tb__block blk = TB_ARRAY_AT(&c->blocks, tb__block, k);
        if (c->n[blk.node].alive && c->n[blk.node].stamp == blk.stamp)
            tb__test(c, blk.node);
        k = blk.next;
    }
}

/* Node i got new neighbours: drop it from the candidates if it became
 * convex (it cannot turn reflex again) and re-test it. */
static void tb__touch(tb__ctx *c, uint32_t i)
{
    tb__node *n = c->n;
    n[i].stamp++;
    if (n[i].cell != TB__NONE && n[i].group == TB__NONE && tb__orient(c, n[i].prev, i, n[i].next) > 0)
        tb__grid_remove(c, i);
    tb__test(c, i);
}

static void tb__kill(tb__ctx *c, uint32_t i)
{
    c->n[i].alive = false;
    c->alive--;
    tb_pqueue_remove(&c->pq, i);
    tb__grid_remove(c, i);
}

enum { TB__CLIP_EAR, TB__CLIP_DEGENERATE, TB__CLIP_FORCED };

/* Cuts off the triangle (prev, b, next). */
static void tb__clip(tb__ctx *c, uint32_t b, int kind)
{
    tb__node *n = c->n;
    uint32_t a = n[b].prev, cc = n[b].next;
    tb_tri t = {{n[a].id, n[b].id, n[cc].id}};
    tb_status st = tb_array_push(c->out, &t);
    if (st && !c->err)
        c->err = st;
    if (kind == TB__CLIP_DEGENERATE)
        c->st.degenerate++;
    else if (kind == TB__CLIP_FORCED)
        c->st.forced++;
    tb__kill(c, b);
    n[a].next = cc;
    n[cc].prev = a;
    c->cursor = a;
    if (n[a].prev == cc) { /* two nodes left: the ring is done */
        tb__kill(c, a);
        tb__kill(c, cc);
        tb__release(c, b);
        tb__release(c, a);
        tb__release(c, cc);
        return;
    }
    tb__touch(c, a);
    tb__touch(c, cc);
    tb__release(c, b);
    tb__release(c, a);
    tb__release(c, cc);
}

/* ------------------------------------------------------------------ fallbacks */

/* Twice the signed area of the ring piece from node i up to (not including)
 * node j, closed back to i. Also counts its nodes. */
static double tb__piece_area(const tb__ctx *c, uint32_t i, uint32_t j, uint32_t *count)
{
    const tb__node *n = c->n;
    double ox = n[i].x, oy = n[i].y, sum = 0;
    uint32_t k = i, m = 0;
    do {
        uint32_t nx = n[k].next == j ? i : n[k].next;
        sum += (n[k].x - ox) * (n[nx].y - oy) - (n[nx].x - ox) * (n[k].y - oy);
        m++;
        k = n[k].next;
    } while (k != j && m <= c->nnodes);
    *count = m;
    return sum;
}

/* Splits a ring at two nodes with the same position whose two pieces both
 * have positive area (a hole touching twice, a pinched outline). */
static bool tb__try_split(tb__ctx *c)
{
    tb__node *n = c->n;
    /* Number the rings. */
    for (uint32_t i = 0; i < c->nnodes; i++)
        n[i].ring = TB__NONE;
    uint32_t rings = 0;
    for (uint32_t i = 0; i < c->nnodes; i++) {
        if (!n[i].alive || n[i].ring != TB__NONE)
            continue;
        uint32_t k = i;
        do {
            n[k].ring = rings;
            k = n[k].next;
        } while (k != i);
        rings++;
    }
    for (uint32_t g = 0; g < c->nnodes; g++) {
        if (n[g].group != g)
            continue; /* visit each group once, from its first node */
        for (uint32_t i = g; i != TB__NONE; i = n[i].group_next) {
            if (!n[i].alive)
                continue;
            for (uint32_t j = n[i].group_next; j != TB__NONE; j = n[j].group_next) {
                if (!n[j].alive || n[j].ring != n[i].ring)
                    continue;
                uint32_t ci, cj;
                double ai = tb__piece_area(c, i, j, &ci);
                double aj = tb__piece_area(c, j, i, &cj);
                if (ci < 3 || cj < 3 || !(ai > 0) || !(aj > 0))
                    continue;
                uint32_t pi = n[i].prev, pj = n[j].prev;
                n[pj].next = i;
                n[i].prev = pj;
                n[pi].next = j;
                n[j].prev = pi;
                c->st.splits++;
                uint32_t changed[4] = {i, j, pi, pj};
                for (int k = 0; k < 4; k++)
                    tb__touch(c, changed[k]);
                for (int k = 0; k < 4; k++)
                    tb__release(c, changed[k]);
                return true;
            }
        }
    }
    return false;
}

/* First alive node at or after the cursor (there is one: alive >= 3). */
static uint32_t tb__some_alive(tb__ctx *c)
{
    uint32_t i = c->cursor < c->nnodes ? c->cursor : 0;
    while (!c->n[i].alive)
        i = (i + 1) % c->nnodes;
    return i;
}

/* Clips a node whose neighbours are collinear with it (a zero-area ear):
 * it removes nothing from the polygon. */
static bool tb__clip_degenerate(tb__ctx *c)
{
    uint32_t start = tb__some_alive(c);
    /* Walk every ring: alive nodes not reachable from start are in other rings. */
    for (uint32_t s = 0, i = start; s < c->nnodes; s++, i = (i + 1) % c->nnodes) {
        if (!c->n[i].alive)
            continue;
        if (c->n[i].prev != c->n[i].next && tb__orient(c, c->n[i].prev, i, c->n[i].next) == 0) {
            tb__clip(c, i, TB__CLIP_DEGENERATE);
            return true;
        }
    }
    return false;
}

/* Invalid input: clips the first convex node (or any node). */
static void tb__clip_forced(tb__ctx *c)
{
    uint32_t start = tb__some_alive(c);
    for (uint32_t s = 0, i = start; s < c->nnodes; s++, i = (i + 1) % c->nnodes) {
        if (c->n[i].alive && tb__orient(c, c->n[i].prev, i, c->n[i].next) > 0) {
            tb__clip(c, i, TB__CLIP_FORCED);
            return;
        }
    }
    tb__clip(c, start, TB__CLIP_FORCED);
}

/* ------------------------------------------------------------ joining holes */

/* Does the closed segment p-q share a point with segment m-P other than m or
 * P themselves (a crossing, a vertex on it, or an overlap)? */
static bool tb__blocks_segment(const tb__ctx *c, uint32_t m, uint32_t P, uint32_t p, uint32_t q)
{
    const tb__node *n = c->n;
    bool pm = tb__same_pos(c, p, m) || tb__same_pos(c, p, P);
    bool qm = tb__same_pos(c, q, m) || tb__same_pos(c, q, P);
    if (pm && qm)
        return tb__same_pos(c, p, q) ? false : true; /* the same segment */
    if (pm || qm) {
        /* Shares an end point: blocks only if it runs along m-P. */
        uint32_t shared = pm ? p : q, other = pm ? q : p;
        uint32_t far = tb__same_pos(c, shared, m) ? P : m;
        return tb__same_dir(c, shared, far, other);
    }
    double o1 = tb__orient(c, m, P, p), o2 = tb__orient(c, m, P, q);
    double o3 = tb__orient(c, p, q, m), o4 = tb__orient(c, p, q, P);
    if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0)))
        return true;
#define TB__ON(a, b, t)                                                                    \
    (fmin(n[a].x, n[b].x) <= n[t].x && n[t].x <= fmax(n[a].x, n[b].x) &&                 \
     fmin(n[a].y, n[b].y) <= n[t].y && n[t].y <= fmax(n[a].y, n[b].y))
    if ((o1 == 0 && TB__ON(m, P, p)) || (o2 == 0 && TB__ON(m, P, q)) ||
        (o3 == 0 && TB__ON(p, q, m)) || (o4 == 0 && TB__ON(p, q, P)))
        return true;
#undef TB__ON
    return false;
}

/* Is m-P a usable bridge: inside both wedges and crossing no edge? */
static bool tb__bridge_ok(const tb__ctx *c, uint32_t m, uint32_t P)
{
    const tb__node *n = c->n;
    if (tb__same_pos(c, m, P) || tb__same_pos(c, P, n[P].next) || tb__same_pos(c, P, n[P].prev) ||
        tb__same_pos(c, m, n[m].next) || tb__same_pos(c, m, n[m].prev))
        return false;
    if (!tb__in_arc(c, P, n[P].next, n[P].prev, m) || !tb__in_arc(c, m, n[m].next, n[m].prev, P))
        return false;
    for (uint32_t e = 0; e < c->nnodes; e++)
        if (n[e].alive && tb__blocks_segment(c, m, P, e, n[e].next))
            return false;
    return true;
}

/* Of P and the outer-ring nodes at its position, one that makes m-P a valid
 * bridge, or NONE. */
static uint32_t tb__bridge_ok_any(const tb__ctx *c, uint32_t m, uint32_t P)
{
    const tb__node *n = c->n;
    if (n[P].group == TB__NONE)
        return tb__bridge_ok(c, m, P) ? P : TB__NONE;
    for (uint32_t k = n[P].group; k != TB__NONE; k = n[k].group_next)
        if (n[k].alive && n[k].ring == 0 && tb__bridge_ok(c, m, k))
            return k;
    return TB__NONE;
}

typedef struct tb__dist {
    double d;
    uint32_t i;
} tb__dist;

static int tb__dist_cmp(const void *a, const void *b)
{
    const tb__dist *x = a, *y = b;
    return x->d < y->d ? -1 : (x->d > y->d ? 1 : (x->i < y->i ? -1 : (x->i > y->i)));
}

/* Adds node `orig`'s copy `copy` to orig's position group. */
static void tb__group_add(tb__ctx *c, uint32_t orig, uint32_t copy)
{
    tb__node *n = c->n;
    if (n[orig].group == TB__NONE) {
        n[orig].group = orig;
        n[orig].group_next = TB__NONE;
    }
    uint32_t head = n[orig].group;
    n[copy].group = head;
    n[copy].group_next = n[head].group_next;
    n[head].group_next = copy;
}

/* Joins hole ring `hole` (whose rightmost node is m) to the outer ring
 * (which contains node `outer`) by a bridge. */
static tb_status tb__bridge(tb__ctx *c, uint32_t outer, uint32_t m)
{
    tb__node *n = c->n;
    double mx = n[m].x, my = n[m].y;
    /* Eberly: cast a ray from m toward +x; find the nearest ring point hit. */
    double best_x = INFINITY;
    uint32_t best_edge = TB__NONE, best_vertex = TB__NONE;
    uint32_t p = outer;
    do {
        uint32_t q = n[p].next;
        if (n[p].y == my && n[p].x > mx) {
            if (n[p].x < best_x || (n[p].x == best_x && best_vertex == TB__NONE)) {
                best_x = n[p].x;
                best_vertex = p;
                best_edge = TB__NONE;
            }
        } else if ((n[p].y < my && n[q].y > my) || (n[p].y > my && n[q].y < my)) {
            double s = tb__orient(c, p, q, m);
            bool right = n[p].y < n[q].y ? s > 0 : s < 0;
            if (right) {
                double x = n[p].x + (my - n[p].y) * (n[q].x - n[p].x) / (n[q].y - n[p].y);
                x = fmax(x, fmax(mx, fmin(n[p].x, n[q].x)));
                x = fmin(x, fmax(n[p].x, n[q].x));
                if (x < best_x) {
                    best_x = x;
                    best_edge = p;
                    best_vertex = TB__NONE;
                }
            }
        }
        p = q;
    } while (p != outer);

    uint32_t P = TB__NONE;
    if (best_vertex != TB__NONE) {
        P = best_vertex;
    } else if (best_edge != TB__NONE) {
        uint32_t e0 = best_edge, e1 = n[e0].next;
        uint32_t P0 = n[e1].x > n[e0].x ? e1 : e0;
        /* Reflex ring vertices inside triangle (m, I, P0) may hide P0; the
         * visible one makes the smallest angle with the ray. */
        double ix = best_x, iy = my;
        double s0 = tb_orient2d(mx, my, ix, iy, n[P0].x, n[P0].y);
        double best_t = INFINITY, best_d = INFINITY;
        uint32_t R = TB__NONE;
        if (s0 != 0) {
            uint32_t r = outer;
            do {
                if (r != P0 && n[r].x > mx && tb__orient(c, n[r].prev, r, n[r].next) <= 0) {
                    double rx = n[r].x, ry = n[r].y;
                    double a1 = tb_orient2d(mx, my, ix, iy, rx, ry);
                    double a2 = tb_orient2d(ix, iy, n[P0].x, n[P0].y, rx, ry);
                    double a3 = tb_orient2d(n[P0].x, n[P0].y, mx, my, rx, ry);
                    bool in = s0 > 0 ? (a1 >= 0 && a2 >= 0 && a3 >= 0) : (a1 <= 0 && a2 <= 0 && a3 <= 0);
                    if (in) {
                        double dx = rx - mx, t = fabs(ry - my) / dx;
                        if (t < best_t || (t == best_t && dx < best_d)) {
                            best_t = t;
                            best_d = dx;
                            R = r;
                        }
                    }
                }
                r = n[r].next;
            } while (r != outer);
        }
        P = R != TB__NONE ? R : P0;
    }
    if (P != TB__NONE)
        P = tb__bridge_ok_any(c, m, P);
    if (P == TB__NONE) {
        /* The estimate failed (near-degenerate input): try ring vertices by
         * distance from m, each checked exactly. */
        uint32_t cnt = 0;
        p = outer;
        do {
            cnt++;
            p = n[p].next;
        } while (p != outer);
        tb__dist *d = malloc((size_t)cnt * sizeof *d);
        if (!d)
            return tb_error(TB_ERR_NOMEM, "triangulate: out of memory");
        uint32_t k = 0;
        p = outer;
        do {
            double dx = n[p].x - mx, dy = n[p].y - my;
            d[k++] = (tb__dist){dx * dx + dy * dy, p};
            p = n[p].next;
        } while (p != outer);
        qsort(d, cnt, sizeof *d, tb__dist_cmp);
        for (k = 0; k < cnt && P == TB__NONE; k++)
            if (tb__bridge_ok(c, m, d[k].i))
                P = d[k].i;
        if (P == TB__NONE) {
            /* Nothing is visible: the input is invalid (hole outside or
             * crossing). Bridge to the nearest vertex anyway. */
            for (k = 0; k < cnt && P == TB__NONE; k++)
                if (!tb__same_pos(c, m, d[k].i))
                    P = d[k].i;
            if (P == TB__NONE)
                P = d[0].i;
            c->st.forced++;
        }
        free(d);
    }

    /* Cut: P -> m -> (hole) -> m' -> P' -> old P.next. */
    uint32_t m2 = c->nnodes++, P2 = c->nnodes++;
    uint32_t pn = n[P].next, mp = n[m].prev;
    n[m2] = n[m];
    n[P2] = n[P];
    n[m2].blocked = n[P2].blocked = TB__NONE;
    n[m2].ring = n[P2].ring = 0;
    tb__group_add(c, m, m2);
    tb__group_add(c, P, P2);
    n[P].next = m;
    n[m].prev = P;
    n[mp].next = m2;
    n[m2].prev = mp;
    n[m2].next = P2;
    n[P2].prev = m2;
    n[P2].next = pn;
    n[pn].prev = P2;
    c->alive += 2;
    c->st.bridges++;
    return TB_OK;
}

/* Can hole node h (clockwise ring) be spliced into outer-ring node r at the
 * same position: does the hole's corner at h lie inside r's wedge? */
static bool tb__splice_ok(const tb__ctx *c, uint32_t r, uint32_t h)
{
    const tb__node *n = c->n;
    uint32_t h1 = n[h].next, hk = n[h].prev;
    if (tb__same_pos(c, h, h1) || tb__same_pos(c, h, hk) || tb__same_pos(c, r, n[r].next) ||
        tb__same_pos(c, r, n[r].prev))
        return false;
    return tb__in_arc(c, r, n[r].next, n[r].prev, hk) && tb__in_arc(c, r, n[r].next, n[r].prev, h1) &&
           tb__in_arc(c, r, hk, n[r].prev, h1);
}

typedef struct tb__hole {
    double x, y;     /* rightmost point (largest y among ties) */
    uint32_t ring;   /* ring number */
    uint32_t m;      /* its node */
    bool may_touch;  /* some node shares its position with another node */
    bool done;
} tb__hole;

static int tb__hole_cmp(const void *a, const void *b)
{
    const tb__hole *x = a, *y = b;
    if (x->x != y->x)
        return x->x > y->x ? -1 : 1;
    if (x->y != y->y)
        return x->y > y->y ? -1 : 1;
    return x->ring < y->ring ? -1 : (x->ring > y->ring);
}

typedef struct tb__pos {
    double x, y;
    uint32_t i;
} tb__pos;

static int tb__pos_cmp(const void *a, const void *b)
{
    const tb__pos *p = a, *q = b;
    if (p->x != q->x)
        return p->x < q->x ? -1 : 1;
    if (p->y != q->y)
        return p->y < q->y ? -1 : 1;
    return p->i < q->i ? -1 : (p->i > q->i);
}

/* Groups the input points by position. */
static tb_status tb__make_groups(tb__ctx *c)
{
    tb__node *n = c->n;
    tb__pos *s = malloc((size_t)c->npoints * sizeof *s);
    if (!s)
        return tb_error(TB_ERR_NOMEM, "triangulate: out of memory");
    for (uint32_t i = 0; i < c->npoints; i++)
        s[i] = (tb__pos){n[i].x, n[i].y, i};
    qsort(s, c->npoints, sizeof *s, tb__pos_cmp);
    for (uint32_t k = 0; k < c->npoints;) {
        uint32_t e = k + 1;
        while (e < c->npoints && s[e].x == s[k].x && s[e].y == s[k].y)
            e++;
        if (e - k > 1) {
            for (uint32_t j = k; j < e; j++) {
                n[s[j].i].group = s[k].i;
                n[s[j].i].group_next = j + 1 < e ? s[j + 1].i : TB__NONE;
            }
        }
        k = e;
    }
    free(s);
    return TB_OK;
}

static tb_status tb__join_holes(tb__ctx *c, const uint32_t *ring_first, uint32_t nrings)
{
    tb__node *n = c->n;
    uint32_t nholes = nrings - 1;
    if (nholes == 0)
        return TB_OK;
    tb__hole *h = malloc((size_t)nholes * sizeof *h);
    if (!h)
        return tb_error(TB_ERR_NOMEM, "triangulate: out of memory");
    for (uint32_t r = 1; r < nrings; r++) {
        tb__hole *hr = &h[r - 1];
        hr->ring = r;
        hr->m = ring_first[r];
        hr->may_touch = false;
        hr->done = false;
        uint32_t i = ring_first[r];
        do {
            if (n[i].x > n[hr->m].x || (n[i].x == n[hr->m].x && n[i].y > n[hr->m].y))
                hr->m = i;
            hr->may_touch |= n[i].group != TB__NONE;
            i = n[i].next;
        } while (i != ring_first[r]);
        hr->x = n[hr->m].x;
        hr->y = n[hr->m].y;
    }
    qsort(h, nholes, sizeof *h, tb__hole_cmp);
    uint32_t outer = ring_first[0];
    tb_status st = TB_OK;
    for (uint32_t left = nholes; left > 0 && !st; left--) {
        /* A hole touching the ring at a vertex is spliced in there. */
        bool spliced = false;
        for (uint32_t k = 0; k < nholes && !spliced; k++) {
            if (h[k].done || !h[k].may_touch)
                continue;
            uint32_t first = ring_first[h[k].ring], i = first, r = TB__NONE;
            do {
                for (uint32_t g = n[i].group; g != TB__NONE && r == TB__NONE; g = n[g].group_next)
                    if (g != i && n[g].ring == 0 && tb__splice_ok(c, g, i))
                        r = g;
                if (r == TB__NONE)
                    i = n[i].next;
            } while (r == TB__NONE && i != first);
            if (r == TB__NONE)
                continue;
            /* r -> (hole from i's successor round to i) -> r's old successor */
            uint32_t j = i;
            do {
                n[j].ring = 0;
                j = n[j].next;
            } while (j != i);
            uint32_t rn = n[r].next, hn = n[i].next;
            n[r].next = hn;
            n[hn].prev = r;
            n[i].next = rn;
            n[rn].prev = i;
            spliced = true;
            c->st.splices++;
            h[k].done = true;
        }
        if (spliced)
            continue;
        for (uint32_t k = 0; k < nholes; k++) {
            if (h[k].done)
                continue;
            uint32_t m = h[k].m;
            st = tb__bridge(c, outer, m);
            h[k].done = true;
            /* The hole's nodes run from m to the copy of m made last. */
            for (uint32_t j = m; !st && j != c->nnodes - 2; j = n[j].next)
                n[j].ring = 0;
            break;
        }
    }
    free(h);
    return st;
}

/* ------------------------------------------------------------------- driver */

/* Twice the signed area of ring r (nodes first .. first+size-1 in input order). */
static double tb__ring_area(const tb__node *n, uint32_t first, uint32_t size)
{
    double ox = n[first].x, oy = n[first].y, sum = 0;
    for (uint32_t k = 0; k < size; k++) {
        const tb__node *p = &n[first + k], *q = &n[first + (k + 1) % size];
        sum += (p->x - ox) * (q->y - oy) - (q->x - ox) * (p->y - oy);
    }
    return sum;
}

/* The triangulation proper; ids[k] (or k) is the output index of point k. */
static tb_status tb__triangulate(const double *xy, const uint32_t *ids, const uint32_t *ring_size,
                                 uint32_t nrings, tb_array *tris, tb_triangulate_stats *stats)
{
    if (stats)
        *stats = (tb_triangulate_stats){0};
    if (nrings == 0)
        return tb_error(TB_ERR_ARG, "triangulate: no rings");
    if (!tris || tris->elem_size != sizeof(tb_tri))
        return tb_error(TB_ERR_ARG, "triangulate: output must be an array of tb_tri");
    uint64_t total = 0;
    for (uint32_t r = 0; r < nrings; r++) {
        if (ring_size[r] < 3)
            return tb_error(TB_ERR_ARG, "triangulate: ring %u has %u points (at least 3 needed)", r,
                            ring_size[r]);
        total += ring_size[r];
    }
    uint64_t cap = total + 2 * (uint64_t)(nrings - 1);
    if (cap >= TB_PQUEUE_MAX_KEY)
        return tb_error(TB_ERR_ARG, "triangulate: too many points (%llu)", (unsigned long long)total);
    for (uint64_t k = 0; k < 2 * total; k++)
        if (!isfinite(xy[k]))
            return tb_error(TB_ERR_ARG, "triangulate: point %llu is not finite",
                            (unsigned long long)(k / 2));

    tb__ctx c = {0};
    c.out = tris;
    c.npoints = c.nnodes = (uint32_t)total;
    c.alive = (uint32_t)total;
    tb_array_init(&c.blocks, sizeof(tb__block));
    tb_pqueue_init(&c.pq);
    size_t len0 = tris->len;
    tb_status st = TB_OK;
    uint32_t *ring_first = malloc((size_t)nrings * sizeof(uint32_t));
    c.n = malloc((size_t)cap * sizeof(tb__node));
    if (!ring_first || !c.n) {
        st = tb_error(TB_ERR_NOMEM, "triangulate: out of memory for %llu points", (unsigned long long)total);
        goto done;
    }
    st = tb_array_reserve(tris, tris->len + (size_t)cap);
    if (st)
        goto done;
    st = tb_pqueue_reserve(&c.pq, (size_t)cap);
    if (st)
        goto done;

    /* Rings as linked lists, outer counter-clockwise, holes clockwise. */
    uint32_t first = 0;
    for (uint32_t r = 0; r < nrings; r++) {
        uint32_t sz = ring_size[r];
        ring_first[r] = first;
        for (uint32_t k = 0; k < sz; k++) {
            uint32_t i = first + k;
            c.n[i] = (tb__node){.x = xy[2 * (size_t)i], .y = xy[2 * (size_t)i + 1],
                                .id = ids ? ids[i] : i,
                                .prev = first + (k + sz - 1) % sz, .next = first + (k + 1) % sz,
                                .group = TB__NONE, .group_next = TB__NONE, .cell = TB__NONE,
                                .blocked = TB__NONE, .ring = r, .alive = true};
        }
        double area = tb__ring_area(c.n, first, sz);
        if ((r == 0) ? area < 0 : area > 0) {
            for (uint32_t k = 0; k < sz; k++) {
                tb__node *p = &c.n[first + k];
                uint32_t t = p->prev;
                p->prev = p->next;
                p->next = t;
            }
        }
        first += sz;
    }
    st = tb__make_groups(&c);
    if (!st)
        st = tb__join_holes(&c, ring_first, nrings);
    if (!st)
        st = tb__grid_build(&c, ring_first[0]);
    if (st)
        goto done;

    for (uint32_t i = 0; i < c.nnodes && !c.err; i++)
        tb__test(&c, i);
    while (c.alive >= 3 && !c.err) {
        uint32_t b;
        if (tb_pqueue_pop(&c.pq, &b, NULL)) {
            tb__clip(&c, b, TB__CLIP_EAR);
            continue;
        }
        if (tb__try_split(&c) || tb__clip_degenerate(&c))
            continue;
        tb__clip_forced(&c);
    }
    st = c.err;

done:
    if (st)
        tris->len = len0;
    else if (stats)
        *stats = c.st;
    free(ring_first);
    free(c.n);
    free(c.cell_start);
    free(c.cell_count);
    free(c.cell_items);
    free(c.live);
    tb_array_free(&c.blocks);
    tb_pqueue_free(&c.pq);
    return st;
}

tb_status tb_triangulate_2d(const double *xy, const uint32_t *ring_size, uint32_t nrings,
                            tb_array *tris, tb_triangulate_stats *stats)
{
    return tb__triangulate(xy, NULL, ring_size, nrings, tris, stats);
}

tb_status tb_triangulate_3d(const tb_vec3 *pts, const uint32_t *idx, const uint32_t *ring_size,
                            uint32_t nrings, tb_array *tris, tb_triangulate_stats *stats)
{
    if (nrings == 0)
        return tb_error(TB_ERR_ARG, "triangulate: no rings");
    uint64_t total = 0;
    for (uint32_t r = 0; r < nrings; r++)
        total += ring_size[r];
    if (total >= TB_PQUEUE_MAX_KEY)
        return tb_error(TB_ERR_ARG, "triangulate: too many points (%llu)", (unsigned long long)total);
    tb_projection pr = tb_projection_for_normal(tb_polygon_newell(pts, idx, ring_size[0]));
    double *xy = malloc((size_t)total * 2 * sizeof(double));
    if (!xy)
        return tb_error(TB_ERR_NOMEM, "triangulate: out of memory for %llu points", (unsigned long long)total);
    for (uint64_t k = 0; k < total; k++) {
        tb_vec3 p = pts[idx ? idx[k] : k];
        xy[2 * k] = tb_vec3_axis(p, pr.u);
        xy[2 * k + 1] = tb_vec3_axis(p, pr.v);
    }
    tb_status st = tb__triangulate(xy, idx, ring_size, nrings, tris, stats);
    free(xy);
    return st;
}
