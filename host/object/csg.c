/* CSG by interval lists (rules in csg.h, docs/primitives.md "CSG"). */
#include "host/object/csg.h"

#include <math.h>
#include <stdlib.h>

#include "host/object/intersect_internal.h"

/* One child's end, tagged for the sweep. */
typedef struct tb__ev {
    tb__xing x;
    int child; /* child index in the node */
    int seq;   /* position in the child's list (keeps sorting stable) */
} tb__ev;

static int tb__ev_cmp(const void *pa, const void *pb)
{
    const tb__ev *a = pa, *b = pb;
    if (a->x.t != b->x.t)
        return a->x.t < b->x.t ? -1 : 1;
    if (a->child != b->child)
        return a->child < b->child ? -1 : 1;
    return (a->seq > b->seq) - (a->seq < b->seq);
}

/* |o|max / |d|max of the world ray: the t scale of rounding in its solutions. */
static double tb__t_scale(const tb_ray *r)
{
    double o = fmax(fabs(r->o.x), fmax(fabs(r->o.y), fabs(r->o.z)));
    double d = fmax(fabs(r->d.x), fmax(fabs(r->d.y), fabs(r->d.z)));
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

void tb__csg_xings(const tb_object *node, const tb_ray *ray, tb__xbuf *out)
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
    for (int i = 0; i < k; i++) {
        tb__xbuf_init(&lists[i]);
        tb__csg_xings(&node->children[i], ray, &lists[i]);
        if (lists[i].oom)
            out->oom = true;
        total += (size_t)lists[i].n;
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
            ev[m++] = (tb__ev){lists[i].x[j], i, j};
    qsort(ev, m, sizeof *ev, tb__ev_cmp);

    double scale = tb__t_scale(ray);
    int nin = 0;
    bool in = false;
    for (size_t i = 0; i < m;) {
        double tend = ev[i].x.t + TB_CSG_COINCIDENT_REL * (scale + fabs(ev[i].x.t));
        size_t j = i;
        for (; j < m && ev[j].x.t <= tend; j++) {
            bool now = ev[j].x.dir > 0;
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
                int eff = ev[q].x.dir;
                if (node->kind == TB_PRIM_DIFFERENCE && ev[q].child > 0)
                    eff = -eff;
                if (eff == want && (!best || ev[q].child < best->child))
                    best = &ev[q];
            }
            if (best) { /* always found for these monotone operations; kept safe anyway */
                tb__xing x = best->x;
                x.dir = want;
                tb__xbuf_push(out, &x);
                in = after;
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
