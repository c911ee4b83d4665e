/* CSG by interval lists (rules in csg.h, docs/primitives.md "CSG"). */
#include "host/object/csg.h"

#include <math.h>
#include <stdlib.h>

#include "host/object/intersect_internal.h"

/* One child's end, tagged for the sweep: its t and direction, and where
 * the whole crossing is (lists[child].x[seq]), which is copied only when
 * the node reports it (24 bytes to sort instead of 64). */
typedef struct tb__ev {
    double t;  /* the crossing's t */
    int child; /* child index in the node */
    int seq;   /* position in the child's list (keeps sorting stable) */
    int dir;   /* the crossing's dir */
} tb__ev;

static int tb__ev_cmp(const void *pa, const void *pb)
{
    const tb__ev *a = pa, *b = pb;
    if (a->t != b->t)
        return a->t < b->t ? -1 : 1;
    if (a->child != b->child)
        return a->child < b->child ? -1 : 1;
    return (a->seq > b->seq) - (a->seq < b->seq);
}

/* |o|max / |d|max of the world ray: the t scale of rounding in its solutions. */
static double tb__t_scale(const tb_ray *r)
{
    /* The max by comparison, as fmax would give for these (no NaN in a
     * valid ray; fabs has no -0), without its libm calls. */
    double ox = fabs(r->o.x), oy = fabs(r->o.y), oz = fabs(r->o.z);
    double dx = fabs(r->d.x), dy = fabs(r->d.y), dz = fabs(r->d.z);
    double o = oy > oz ? oy : oz, d = dy > dz ? dy : dz;
    o = ox > o ? ox : o;
    d = dx > d ? dx : d;
    return o / d;
}

/* Node membership from the count of children inside. */
static bool tb__member(tb_prim_kind k, int nin, int nchildren, bool first_in)
{
    switch (k) {
    case TB_PRIM_UNION: return nin > 0;
    case TB_PRIM_INTERSECTION: return nin == nchildren;
    default: return first_in && nin == 1; /* difference: in the first child and no other */
    }
}

/* Sorts ev[0..m) by tb__ev_cmp. The keys (t, child, seq) are distinct, so
 * every correct sort gives the same order; the events arrive as the
 * children's sorted lists one after another, nearly in order, where
 * insertion sort is far cheaper than qsort's calls through a pointer. */
static void tb__ev_sort(tb__ev *ev, size_t m)
{
    if (m > 32) {
        qsort(ev, m, sizeof *ev, tb__ev_cmp);
        return;
    }
    for (size_t i = 1; i < m; i++) {
        if (tb__ev_cmp(&ev[i - 1], &ev[i]) <= 0)
            continue;
        tb__ev e = ev[i];
        size_t j = i;
        while (j > 0 && tb__ev_cmp(&ev[j - 1], &e) > 0) {
            ev[j] = ev[j - 1];
            j--;
        }
        ev[j] = e;
    }
}

/* A child without crossings whose absence already decides the node: an
 * empty first operand of a difference, or any empty operand of an
 * intersection, makes the node empty whatever the other children are. */
static bool tb__empty_decides(tb_prim_kind k, int child)
{
    return k == TB_PRIM_INTERSECTION || (k == TB_PRIM_DIFFERENCE && child == 0);
}

/* True if some crossing of the list has t, rounded to float as the queries
 * see it, in [tmin, tmax]. */
static bool tb__any_in_range(const tb__xbuf *b, double tmin, double tmax)
{
    for (int i = 0; i < b->n; i++)
        if ((float)b->x[i].t >= tmin && (float)b->x[i].t <= tmax)
            return true;
    return false;
}

/* True if no crossing of a node that lies inside the child with list b (an
 * intersection's operand, a difference's first one) can have a float t in
 * [tmin, tmax]. Such a node's crossings lie in the child's span [first,
 * last] widened by the coincidence tolerance (a batch of ends that changes
 * the node's membership also has the child inside just before or after
 * it, and spans at most the tolerance); the margin here is 16 times it.
 * This is what skips the other operands for a shadow ray that leaves the
 * solid's surface: the solid lies behind its origin. */
static bool tb__span_misses(const tb__xbuf *b, const tb_ray *ray, double tmin, double tmax)
{
    if (b->n == 0)
        return false;
    double scale = tb__t_scale(ray);
    double lo = b->x[0].t, hi = b->x[b->n - 1].t;
    double lo_pad = lo - 16.0 * TB_CSG_COINCIDENT_REL * (scale + fabs(lo));
    double hi_pad = hi + 16.0 * TB_CSG_COINCIDENT_REL * (scale + fabs(hi));
    return (float)hi_pad < tmin || (float)lo_pad > tmax;
}

/* The node's crossings as tb__csg_xings; with `range` (tmin, tmax), only the
 * first crossing in it matters (tb__csg_xings_in): the sweep is skipped when
 * no child crossing is in range (the node's crossings are some of its
 * children's, copied with their t) and stops after the first one in range
 * (it emits crossings in order of t). */
static void tb__csg_node(const tb_object *node, const tb_ray *ray, tb__xbuf *out, const double *range)
{
    if (!tb_prim_is_csg(node->kind)) {
        tb__oray r = tb__object_ray(node, ray);
        tb__prim_xings(node, &r, out);
        return;
    }
    tb__count_kind(node->kind);
    int k = node->nchildren;
    tb__xbuf local[4], *lists = local;
    if (k > 4 && !(lists = malloc(sizeof *lists * (size_t)k))) {
        out->oom = true;
        return;
    }
    size_t total = 0;
    for (int i = 0; i < k; i++)
        tb__xbuf_init(&lists[i]);
    bool any_in_range = range == NULL;
    for (int i = 0; i < k; i++) {
        tb__csg_node(&node->children[i], ray, &lists[i], NULL);
        if (lists[i].oom)
            out->oom = true;
        total += (size_t)lists[i].n;
        if (lists[i].n == 0 && !lists[i].oom && tb__empty_decides(node->kind, i)) {
            total = 0; /* the node is empty: the sweep below would find nothing */
            break;
        }
        if (range && !lists[i].oom && tb__empty_decides(node->kind, i) &&
            tb__span_misses(&lists[i], ray, range[0], range[1])) {
            total = 0; /* no crossing of the node can be in range */
            break;
        }
        if (!any_in_range)
            any_in_range = tb__any_in_range(&lists[i], range[0], range[1]);
    }
    if (total == 0 || !any_in_range) {
        for (int i = 0; i < k; i++)
            tb__xbuf_free(&lists[i]);
        if (lists != local)
            free(lists);
        return;
    }
    tb__ev evlocal[32], *ev = evlocal;
    bool *state = NULL, statelocal[16];
    if (total > 32 && !(ev = malloc(sizeof *ev * total)))
        goto oom;
    state = k > 16 ? calloc((size_t)k, sizeof *state) : statelocal;
    if (!state)
        goto oom;
    for (int i = 0; i < k && k <= 16; i++)
        state[i] = false;
    size_t m = 0;
    for (int i = 0; i < k; i++)
        for (int j = 0; j < lists[i].n; j++)
            ev[m++] = (tb__ev){lists[i].x[j].t, i, j, lists[i].x[j].dir};
    tb__ev_sort(ev, m);

    double scale = tb__t_scale(ray);
    int nin = 0;
    bool in = false;
    for (size_t i = 0; i < m;) {
        double tend = ev[i].t + TB_CSG_COINCIDENT_REL * (scale + fabs(ev[i].t));
        size_t j = i;
        for (; j < m && ev[j].t <= tend; j++) {
            bool now = ev[j].dir > 0;
            int c = ev[j].child;
            if (now != state[c]) {
                nin += now ? 1 : -1;
                state[c] = now;
            }
        }
        bool after = tb__member(node->kind, nin, k, state[0]);
        if (after != in) {
            /* The lowest child whose own change agrees with the node's. */
            int want = after ? +1 : -1;
            const tb__ev *best = NULL;
            for (size_t q = i; q < j; q++) {
                int eff = ev[q].dir;
                if (node->kind == TB_PRIM_DIFFERENCE && ev[q].child > 0)
                    eff = -eff;
                if (eff == want && (!best || ev[q].child < best->child))
                    best = &ev[q];
            }
            if (best) { /* always found for these monotone operations; kept safe anyway */
                tb__xing x = lists[best->child].x[best->seq];
                x.dir = want;
                tb__xbuf_push(out, &x);
                in = after;
                if (range && (float)x.t >= range[0] && (float)x.t <= range[1])
                    break; /* occlusion: this crossing answers it */
            }
        }
        i = j;
    }
    /* A bounded solid ends outside; close a dangling interval (only after a
     * lost crossing, e.g. out of memory) so ends still pair up. */
    if (in && out->n > 0) {
        tb__xing x = out->x[out->n - 1];
        x.dir = -1;
        tb__xbuf_push(out, &x);
    }
    if (ev != evlocal)
        free(ev);
    if (state != statelocal)
        free(state);
    for (int i = 0; i < k; i++)
        tb__xbuf_free(&lists[i]);
    if (lists != local)
        free(lists);
    return;
oom:
    out->oom = true;
    if (ev != evlocal)
        free(ev);
    if (state && state != statelocal)
        free(state);
    for (int i = 0; i < k; i++)
        tb__xbuf_free(&lists[i]);
    if (lists != local)
        free(lists);
}

void tb__csg_xings(const tb_object *node, const tb_ray *ray, tb__xbuf *out)
{
    tb__csg_node(node, ray, out, NULL);
}

void tb__csg_xings_in(const tb_object *node, const tb_ray *ray, double tmin, double tmax, tb__xbuf *out)
{
    double range[2] = {tmin, tmax};
    tb__csg_node(node, ray, out, range);
}

int tb_object_intervals(const tb_object *obj, const tb_ray *ray, float *t_in, float *t_out, int max)
{
    if (!obj || !ray || !obj->closed || !tb_ray_is_valid(ray))
        return 0;
    tb__xbuf b;
    tb__xbuf_init(&b);
    tb__csg_xings(obj, ray, &b);
    int n = 0;
    if (!b.oom) {
        for (int i = 0; i + 1 < b.n; i += 2) {
            if (n < max) {
                t_in[n] = (float)b.x[i].t;
                t_out[n] = (float)b.x[i + 1].t;
            }
            n++;
        }
    }
    tb__xbuf_free(&b);
    return n;
}
