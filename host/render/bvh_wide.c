/* The wide BVH the CPU queries traverse (docs/accel.md, "Wide nodes" and
 * "Wide traversal"): bvh.c's binary SAH tree collapsed so that a node holds
 * up to eight children (chosen by dynamic programming to minimise the sum of
 * the wide nodes' areas, below), the children's boxes stored by
 * coordinate and tested by one AVX slab test (bvh_wide_avx.c, where the CPU
 * has AVX) or two SSE2 ones (here) with tb__accel_slab_t's arithmetic, so
 * every box is met or missed exactly as the binary traversal decided it.
 * Closest hit goes near child first by a per-octant order table (the binary
 * tree's split-axis order), any hit tries the occluder cache first. The
 * order never changes the answer (the tie rule). */
#include <stdlib.h>
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "host/render/accel_internal.h"
#include "util/stats/stats.h"

TB_STAT_COUNTER(tb__bvh_rays, "BVH/rays");
TB_STAT_COUNTER(tb__bvh_shadow_rays, "BVH/occlusion rays");
TB_STAT_COUNTER(tb__bvh_nodes_visited, "BVH/nodes visited");
TB_STAT_COUNTER(tb__bvh_prims_tested, "BVH/primitives tested");
TB_STAT_COUNTER(tb__bvh_occ_hits, "BVH/occluder cache hits");

bool tb__bvhw_have_avx(void)
{
#if defined(TB_BVH_AVX)
    return __builtin_cpu_supports("avx");
#else
    return false;
#endif
}

/* ------------------------------------------------------------ collapse */

/* The collapse chooses, for every wide node, which binary descendants
 * become its (up to eight) children by the SAH over the wide tree (after
 * Ylitie, Karras and Laine, "Efficient incoherent ray traversal on GPUs
 * through compressed wide BVHs", HPG 2017, section 4.1), by dynamic
 * programming from the leaves up: cost[i] of binary node n is the least
 * cost of its subtree given at most i + 1 child slots of a wide node. Every
 * binary leaf stays one leaf child (the same references, in the same
 * order), so the leaves' SAH terms are the same in every choice and the
 * cost reduces to the sum of the wide nodes' areas (the expected number of
 * node steps of a ray, up to a factor): no constants to tune. */
typedef struct tb__cdp {
    double cost[TB__BVHW];     /* [i]: with at most i + 1 slots (the sum of the wide nodes' areas below) */
    uint8_t left[TB__BVHW];    /* [i]: slots given to the first child (0: n itself is one child) */
    uint8_t right[TB__BVHW];   /* [i]: slots given to the second child */
    uint8_t dl, dr;            /* the best split of all eight slots below n (when n becomes a wide node) */
} tb__cdp;

typedef struct tb__collapse {
    const tb_bvh_node *bin;
    tb__bvhw_node *out;
    uint32_t next;
    tb__cdp *dp;               /* per binary node */
} tb__collapse;

/* The binary subtree that one wide node replaces, flattened: its inner
 * nodes (at most 7) with, per side, the next inner node or a slot of kids[]. */
typedef struct tb__bvhw_sub {
    uint8_t axis[TB__BVHW];  /* split axis of inner node j */
    int8_t side[TB__BVHW][2]; /* first and second child: >= 0 inner node, < 0 slot -1 - s */
} tb__bvhw_sub;

/* Adds binary node b to sub: the slot of kids[] it is, or a new inner node. */
static int8_t tb__bvhw_sub_add(const tb_bvh_node *bin, uint32_t b, const uint32_t *kids, int nk, tb__bvhw_sub *sub,
                               int *ninner)
{
    for (int i = 0; i < nk; i++)
        if (kids[i] == b)
            return (int8_t)(-1 - i);
    int j = (*ninner)++;
    sub->axis[j] = bin[b].axis;
    int8_t first = tb__bvhw_sub_add(bin, b + 1, kids, nk, sub, ninner);
    int8_t second = tb__bvhw_sub_add(bin, bin[b].offset, kids, nk, sub, ninner);
    sub->side[j][0] = first;
    sub->side[j][1] = second;
    return (int8_t)j;
}

/* Appends to seq the slots below entry e of sub in the binary traversal's
 * order for octant `oct`: an inner node visits its first child first unless
 * the ray goes toward -axis. */
static void tb__bvhw_sub_order(const tb__bvhw_sub *sub, int8_t e, unsigned oct, uint8_t *seq, int *len)
{
    if (e < 0) {
        seq[(*len)++] = (uint8_t)(-1 - e);
        return;
    }
    unsigned back = oct >> sub->axis[e] & 1u;
    tb__bvhw_sub_order(sub, sub->side[e][back], oct, seq, len);
    tb__bvhw_sub_order(sub, sub->side[e][!back], oct, seq, len);
}

/* Half surface area in double, the build's measure (only compared here). */
static double tb__bvhw_area(const tb_aabb *b)
{
    double ex = (double)b->hi.x - b->lo.x, ey = (double)b->hi.y - b->lo.y, ez = (double)b->hi.z - b->lo.z;
    return ex * ey + ey * ez + ez * ex;
}

/* Fills c->dp bottom-up (children come after their parent in the array). */
static void tb__bvhw_dp(tb__collapse *c, size_t nnodes)
{
    const tb_bvh_node *bin = c->bin;
    for (size_t k = nnodes; k-- > 0;) {
        tb__cdp *d = &c->dp[k];
        if (bin[k].count) {
            for (int i = 0; i < TB__BVHW; i++) {
                d->cost[i] = 0.0;
                d->left[i] = d->right[i] = 0;
            }
            d->dl = d->dr = 0;
            continue;
        }
        const tb__cdp *l = &c->dp[k + 1], *r = &c->dp[bin[k].offset];
        /* dist[j]: the two children spread over at most j + 1 slots (j >= 1). */
        double dist[TB__BVHW];
        uint8_t dl[TB__BVHW], dr[TB__BVHW];
        /* Selects, not branches: the comparisons are data-dependent and
         * were a third of the whole build's mispredicted branches. */
        for (int j = 1; j < TB__BVHW; j++) {
            double best = INFINITY;
            int bk = 0;
            for (int kl = 0; kl < j; kl++) { /* kl + 1 slots left, j - kl right */
                double v = l->cost[kl] + r->cost[j - 1 - kl];
                bool lt = v < best;
                best = lt ? v : best;
                bk = lt ? kl : bk;
            }
            dist[j] = best;
            dl[j] = (uint8_t)(bk + 1);
            dr[j] = (uint8_t)(j - bk);
        }
        d->dl = dl[TB__BVHW - 1];
        d->dr = dr[TB__BVHW - 1];
        /* One slot: n becomes a wide node of its own. */
        d->cost[0] = tb__bvhw_area(&bin[k].bounds) + dist[TB__BVHW - 1];
        d->left[0] = d->right[0] = 0;
        for (int i = 1; i < TB__BVHW; i++) {
            bool lt = dist[i] < d->cost[i - 1];
            d->cost[i] = lt ? dist[i] : d->cost[i - 1];
            d->left[i] = lt ? dl[i] : d->left[i - 1];
            d->right[i] = lt ? dr[i] : d->right[i - 1];
        }
    }
}

/* Appends to kids[] the children that binary node b becomes with `slots`
 * slots (tb__cdp), in the binary tree's left-to-right order. */
static void tb__bvhw_kids(const tb__collapse *c, uint32_t b, int slots, uint32_t *kids, int *nk)
{
    const tb__cdp *d = &c->dp[b];
    if (d->left[slots - 1] == 0) {
        kids[(*nk)++] = b;
        return;
    }
    tb__bvhw_kids(c, b + 1, d->left[slots - 1], kids, nk);
    tb__bvhw_kids(c, c->bin[b].offset, d->right[slots - 1], kids, nk);
}

/* Writes the wide node for binary node b (an inner node, or the root when
 * it is a leaf) and, depth-first, those of its inner children; returns its index. */
static uint32_t tb__bvhw_collapse(tb__collapse *c, uint32_t b)
{
    const tb_bvh_node *bin = c->bin;
    uint32_t kids[TB__BVHW];
    int nk = 0;
    if (bin[b].count) {
        kids[0] = b;
        nk = 1;
    } else {
        tb__bvhw_kids(c, b + 1, c->dp[b].dl, kids, &nk);
        tb__bvhw_kids(c, bin[b].offset, c->dp[b].dr, kids, &nk);
    }
    uint32_t me = c->next++;
    tb__bvhw_node *o = &c->out[me];
    memset(o, 0, sizeof *o);
    o->n = (uint8_t)nk;
    o->used = (uint8_t)((1u << nk) - 1u);
    for (int i = 0; i < TB__BVHW; i++) {
        tb_aabb bx = i < nk ? bin[kids[i]].bounds : (tb_aabb){{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
        o->box[0][i] = bx.lo.x;
        o->box[1][i] = bx.hi.x;
        o->box[2][i] = bx.lo.y;
        o->box[3][i] = bx.hi.y;
        o->box[4][i] = bx.lo.z;
        o->box[5][i] = bx.hi.z;
    }
    /* The subtree is walked once; each octant's order is read off it. */
    tb__bvhw_sub sub;
    int ninner = 0;
    int8_t top = tb__bvhw_sub_add(bin, b, kids, nk, &sub, &ninner);
    for (unsigned oct = 0; oct < 8; oct++) {
        uint8_t seq[TB__BVHW];
        int len = 0;
        tb__bvhw_sub_order(&sub, top, oct, seq, &len);
        uint32_t packed = 0;
        for (int j = 0; j < len; j++) /* far to near */
            packed |= (uint32_t)seq[len - 1 - j] << (3 * j);
        o->order[oct] = packed;
    }
    for (int i = 0; i < nk; i++) {
        const tb_bvh_node *k = &bin[kids[i]];
        if (k->count) {
            o->child[i] = k->offset;
            o->count[i] = (uint16_t)k->count; /* leaves hold at most 255 references */
        } else {
            uint32_t w = tb__bvhw_collapse(c, kids[i]);
            c->out[me].child[i] = w; /* `o` stays valid: the array does not move */
        }
    }
    return me;
}

tb_status tb__bvhw_build(tb_accel *acc, const tb_accel_options *opt)
{
    /* Every wide node but a leaf root consumes at least one binary inner node. */
    size_t bound = acc->nnodes / 2 + 1;
    tb__bvhw_node *tmp = malloc(bound * sizeof *tmp);
    if (!tmp)
        return tb_error(TB_ERR_NOMEM, "BVH: out of memory for the wide nodes");
    tb__collapse c = {acc->nodes, tmp, 0, malloc(acc->nnodes * sizeof(tb__cdp))};
    if (!c.dp) {
        free(tmp);
        return tb_error(TB_ERR_NOMEM, "BVH: out of memory for the wide collapse");
    }
    tb__bvhw_dp(&c, acc->nnodes);
    tb__bvhw_collapse(&c, 0);
    free(c.dp);
    /* Exact size, 64-byte aligned (a node's box rows are 32-byte aligned for AVX loads). */
    /* (C11 wants the size a multiple of the alignment: 288-byte nodes are not.) */
    size_t bytes = ((size_t)c.next * sizeof(tb__bvhw_node) + 63u) & ~(size_t)63u;
    tb__bvhw_node *wide = aligned_alloc(64, bytes);
    if (!wide) {
        free(tmp);
        return tb_error(TB_ERR_NOMEM, "BVH: out of memory for the wide nodes");
    }
    memcpy(wide, tmp, (size_t)c.next * sizeof *wide);
    free(tmp);
    acc->wide = wide;
    acc->nwide = c.next;
    acc->wide_avx = !opt->bvh_no_avx && tb__bvhw_have_avx();
    return TB_OK;
}

/* True if leaf child i of nd holds triangle references only. */
static bool tb__bvhw_all_tris(const tb_accel *acc, const tb__bvhw_node *nd, unsigned i)
{
    uint32_t s = nd->child[i], n = TB__BVHW_COUNT(nd->count[i]);
    bool all = n > 0;
    for (uint32_t j = 0; all && j < n; j++)
        all = tb__accel_tri_at(acc, s + j, NULL) != NULL;
    return all;
}

tb_status tb__bvhw_pack(tb_accel *acc)
{
#if defined(__SSE2__)
    if (!acc->tris || !acc->wide)
        return TB_OK;
    /* Floats when every corner to pack is one exactly (meshes read from
     * files, placed without a transform): converted back on load they are
     * the same doubles, at 52 bytes per reference instead of 88. */
    bool any = false, f32 = true;
    for (size_t w = 0; w < acc->nwide; w++) {
        const tb__bvhw_node *nd = &acc->wide[w];
        for (unsigned i = 0; i < nd->n; i++) {
            if (!tb__bvhw_all_tris(acc, nd, i))
                continue;
            any = true;
            uint32_t s = nd->child[i], n = TB__BVHW_COUNT(nd->count[i]);
            for (uint32_t j = 0; f32 && j < n; j++)
                for (unsigned r = 0; r < 9; r++) {
                    double v = tb__accel_tri_at(acc, s + j, NULL)->v[r];
                    f32 = f32 && (double)(float)v == v; /* (a zero keeps its sign through float) */
                }
        }
    }
    if (!any)
        return TB_OK;
    /* Slack of one vector after the last row: a leaf's last partial vector
     * is read whole (its extra lanes are ignored). */
    size_t per = f32 ? TB__LANE_ROWS_F * sizeof(float) : TB__LANE_ROWS * sizeof(double);
    size_t bytes = (acc->n * per + 2 * sizeof(double) + 63u) & ~(size_t)63u;
    void *lanes = aligned_alloc(64, bytes);
    if (!lanes)
        return tb_error(TB_ERR_NOMEM, "BVH: out of memory for the packed triangle corners");
    memset(lanes, 0, bytes); /* lanes of unpacked leaves and the slack: defined values, never used */
    for (size_t w = 0; w < acc->nwide; w++) {
        tb__bvhw_node *nd = &acc->wide[w];
        for (unsigned i = 0; i < nd->n; i++) {
            if (!tb__bvhw_all_tris(acc, nd, i))
                continue;
            uint32_t s = nd->child[i], n = TB__BVHW_COUNT(nd->count[i]);
            char *base = (char *)lanes + per * s;
            tb__lane_ids *ids = (tb__lane_ids *)(base + 9 * (size_t)n * (f32 ? sizeof(float) : sizeof(double)));
            for (uint32_t j = 0; j < n; j++) {
                const tb_accel_tri *tr = tb__accel_tri_at(acc, s + j, NULL);
                for (unsigned r = 0; r < 9; r++) { /* row 3 c + a is v[3 c + a] */
                    if (f32)
                        ((float *)base)[r * n + j] = (float)tr->v[r];
                    else
                        ((double *)base)[r * n + j] = tr->v[r];
                }
                ids[j] = (tb__lane_ids){tr->object, tr->face, acc->index[s + j], acc->prims[s + j].sub};
            }
            nd->count[i] |= TB__BVHW_PACKED;
        }
    }
    acc->lanes = lanes;
    acc->lanes_f32 = f32;
    acc->stats.memory_bytes += bytes;
    acc->stats.tri_bytes += bytes;
    /* Every reference a triangle (so every leaf packed): the lanes hold what
     * the records do, so the records (80 bytes each) give way to a 2-byte
     * position per reference for the few reads outside the packed test (an
     * edge exactly 0, the occlusion hint). */
    if (!acc->tri_of) {
        uint16_t *pos = malloc(acc->n * sizeof *pos);
        if (!pos)
            return TB_OK; /* the records stay: the same answers */
        for (size_t w = 0; w < acc->nwide; w++) {
            const tb__bvhw_node *nd = &acc->wide[w];
            for (unsigned i = 0; i < nd->n; i++) {
                uint32_t s = nd->child[i], n = TB__BVHW_COUNT(nd->count[i]);
                if (nd->count[i] & TB__BVHW_PACKED)
                    for (uint32_t j = 0; j < n; j++)
                        pos[s + j] = (uint16_t)(j << 8 | n);
            }
        }
        acc->lane_pos = pos;
        free(acc->tris);
        acc->tris = NULL;
        size_t freed = acc->n * sizeof(tb_accel_tri), added = acc->n * sizeof *pos;
        acc->stats.memory_bytes = acc->stats.memory_bytes - freed + added;
        acc->stats.tri_bytes = acc->stats.tri_bytes - freed + added;
        /* The lanes also hold each reference's input index and sub, and its
         * box is only read by the occlusion hint (which can test the
         * triangle instead): the reference array (36 bytes each) goes too,
         * unless the binary nodes are kept (tb_accel_bvh_refs reads it). */
        if (!acc->nodes) {
            free(acc->prims);
            free(acc->index);
            acc->prims = NULL;
            acc->index = NULL;
            acc->stats.memory_bytes -= acc->n * (sizeof(tb_accel_prim) + sizeof(uint32_t));
        }
    }
#else
    (void)acc;
#endif
    return TB_OK;
}

/* ------------------------------------------------------------ node test (SSE2) */

#if defined(__SSE2__)
/* v, with its value unknown to the optimiser (an empty asm that may change it). */
static inline __m128 tb__f4_opaque(__m128 v)
{
    __asm__("" : "+x"(v));
    return v;
}
#endif

/* A query ray prepared for the node test. */
typedef struct tb__wray {
#if defined(__SSE2__)
    __m128 o[3], inv[3];  /* broadcasts */
    /* The test's constants, made once per ray and hidden from the optimiser
     * (tb__f4_opaque): as known constants GCC rebuilt each of them (load +
     * shuffle) in every node step. */
    __m128 sign, k, one, minus_inf, plus_inf;
    __m128 kn, kf;        /* 1 - k and 1 + k: the widening factors of t >= 0 */
#endif
    tb_vec3 ov, invv;
    bool neg[3];
    size_t near[3], far[3];   /* per axis, the byte offset in a node of the near and far planes' row */
    unsigned oct;             /* the direction's octant: bit a set when inv_d along a has its sign bit set */
} tb__wray;

static inline void tb__wray_init(tb__wray *r, const tb_ray *ray)
{
    r->ov = ray->o;
    r->invv = (tb_vec3){1.0f / ray->d.x, 1.0f / ray->d.y, 1.0f / ray->d.z};
    r->neg[0] = signbit(r->invv.x) != 0;
    r->neg[1] = signbit(r->invv.y) != 0;
    r->neg[2] = signbit(r->invv.z) != 0;
    r->oct = 0;
    for (unsigned a = 0; a < 3; a++) {
        r->near[a] = (2 * a + r->neg[a]) * sizeof(((tb__bvhw_node *)0)->box[0]);
        r->far[a] = (2 * a + 1 - r->neg[a]) * sizeof(((tb__bvhw_node *)0)->box[0]);
        r->oct |= (unsigned)r->neg[a] << a;
    }
#if defined(__SSE2__)
    r->o[0] = _mm_set1_ps(ray->o.x);
    r->o[1] = _mm_set1_ps(ray->o.y);
    r->o[2] = _mm_set1_ps(ray->o.z);
    r->inv[0] = _mm_set1_ps(r->invv.x);
    r->inv[1] = _mm_set1_ps(r->invv.y);
    r->inv[2] = _mm_set1_ps(r->invv.z);
    r->sign = tb__f4_opaque(_mm_set1_ps(-0.0f));
    r->k = tb__f4_opaque(_mm_set1_ps(2.0f * tb_gamma(3)));
    r->one = tb__f4_opaque(_mm_set1_ps(1.0f));
    r->kn = tb__f4_opaque(_mm_set1_ps(1.0f - 2.0f * tb_gamma(3)));
    r->kf = tb__f4_opaque(_mm_set1_ps(1.0f + 2.0f * tb_gamma(3)));
    r->minus_inf = tb__f4_opaque(_mm_set1_ps(-INFINITY));
    r->plus_inf = tb__f4_opaque(_mm_set1_ps(INFINITY));
#endif
}

#if defined(__SSE2__)
typedef __m128 tb__wvec;

static inline tb__wvec tb__wvec_set1(float x) { return _mm_set1_ps(x); }

/* Four children's slab tests at once (columns of the rows at byte offset
 * `half` of the node), lane for lane the arithmetic of tb__accel_slab_t:
 * (plane - o) * inv, widened outward by the factor 1 -+ copysign(2 gamma(3), t),
 * then `x > t ? x : t` (MAXPS returns its second operand when either is
 * NaN, exactly that rule) and the mirror for the far planes. Returns the
 * mask of children met; tn their entry distances. */
static inline __attribute__((always_inline)) unsigned tb__wtest4(const char *b, const tb__wray *r, tb__wvec tmin,
                                                                 tb__wvec tmax, float *tn, bool full)
{
    /* The plane distances, unwidened. */
    __m128 nx = _mm_mul_ps(_mm_sub_ps(_mm_load_ps((const float *)(b + r->near[0])), r->o[0]), r->inv[0]);
    __m128 fx = _mm_mul_ps(_mm_sub_ps(_mm_load_ps((const float *)(b + r->far[0])), r->o[0]), r->inv[0]);
    __m128 ny = _mm_mul_ps(_mm_sub_ps(_mm_load_ps((const float *)(b + r->near[1])), r->o[1]), r->inv[1]);
    __m128 fy = _mm_mul_ps(_mm_sub_ps(_mm_load_ps((const float *)(b + r->far[1])), r->o[1]), r->inv[1]);
    __m128 nz = _mm_mul_ps(_mm_sub_ps(_mm_load_ps((const float *)(b + r->near[2])), r->o[2]), r->inv[2]);
    __m128 fz = _mm_mul_ps(_mm_sub_ps(_mm_load_ps((const float *)(b + r->far[2])), r->o[2]), r->inv[2]);
    /* The largest near and smallest far distance, then widened once: the
     * widening t -> fl(t (1 -+ copysign(k, t))) is non-decreasing (one
     * constant factor per sign, rounding is monotone) and keeps a zero's
     * sign, so widening the maximum gives the maximum of the widened values
     * that the scalar test takes, bit for bit (both keep the first of equal
     * operands, the range's bound last here and first there, which ties
     * also keep). MAXPS/MINPS return the second operand when the first is
     * NaN: a NaN distance (origin on a plane, zero direction) is skipped as
     * the scalar `x > t ? x : t` skips it; with all three NaN the -inf /
     * +inf start leaves the ray's own range. */
    const __m128 sign = r->sign, k = r->k, one = r->one;
    __m128 n = _mm_max_ps(nz, _mm_max_ps(ny, _mm_max_ps(nx, r->minus_inf)));
    __m128 f = _mm_min_ps(fz, _mm_min_ps(fy, _mm_min_ps(fx, r->plus_inf)));
    if (full) {
        n = _mm_mul_ps(n, _mm_sub_ps(one, _mm_or_ps(_mm_and_ps(n, sign), k)));
        f = _mm_mul_ps(f, _mm_add_ps(one, _mm_or_ps(_mm_and_ps(f, sign), k)));
    } else {
        /* tmin >= 0 (the usual query): a negative near distance loses to
         * tmin and a negative far one fails the test whichever factor
         * widened it, so the sign-free factors give the same mask and entry
         * distances (docs/accel.md, "Traversal"). */
        n = _mm_mul_ps(n, r->kn);
        f = _mm_mul_ps(f, r->kf);
    }
    tmin = _mm_max_ps(n, tmin);
    tmax = _mm_min_ps(f, tmax);
    _mm_storeu_ps(tn, tmin);
    return (unsigned)_mm_movemask_ps(_mm_cmple_ps(tmin, tmax));
}

/* The eight children: two four-lane tests. */
static inline __attribute__((always_inline)) unsigned tb__wtest(const tb__bvhw_node *nd, const tb__wray *r,
                                                                tb__wvec tmin, tb__wvec tmax, float tn[TB__BVHW],
                                                                bool full)
{
    const char *b = (const char *)nd;
    return tb__wtest4(b, r, tmin, tmax, tn, full) | tb__wtest4(b + 16, r, tmin, tmax, tn + 4, full) << 4;
}

#else
/* Without SSE2: the same test one child at a time. */
typedef float tb__wvec;

static inline tb__wvec tb__wvec_set1(float x) { return x; }

static inline unsigned tb__wtest(const tb__bvhw_node *nd, const tb__wray *r, tb__wvec tmin, tb__wvec tmax,
                                 float tn[TB__BVHW], bool full)
{
    (void)full; /* the scalar test's widening is the full one */
    unsigned m = 0;
    for (int i = 0; i < TB__BVHW; i++) {
        tb_aabb b = {{nd->box[0][i], nd->box[2][i], nd->box[4][i]}, {nd->box[1][i], nd->box[3][i], nd->box[5][i]}};
        if (tb__accel_slab_t(&b, r->ov, r->invv, r->neg, tmin, tmax, &tn[i]))
            m |= 1u << i;
        else
            tn[i] = tmin;
    }
    return m;
}
#endif

static unsigned tb__bvhw_slab_test_sse(const tb__bvhw_node *nd, const tb_ray *ray, float tmin, float tmax,
                                       float tnear[TB__BVHW])
{
    tb__wray r;
    tb__wray_init(&r, ray);
    return tb__wtest(nd, &r, tb__wvec_set1(tmin), tb__wvec_set1(tmax), tnear, !(tmin >= 0.0f));
}

unsigned tb__bvhw_slab_test(const tb__bvhw_node *nd, const tb_ray *ray, float tmin, float tmax,
                            float tnear[TB__BVHW], bool avx)
{
#if defined(TB_BVH_AVX)
    if (avx && tb__bvhw_have_avx())
        return tb__bvhw_slab_test_avx(nd, ray, tmin, tmax, tnear);
#else
    (void)avx;
#endif
    return tb__bvhw_slab_test_sse(nd, ray, tmin, tmax, tnear);
}

/* ------------------------------------------------------------ traversal */

#define TB__WFULL 0
#define TB__WNAME(name) name##_sse
#include "host/render/bvh_wide_traverse.inc"
#undef TB__WNAME
#undef TB__WFULL
#define TB__WFULL 1
#define TB__WNAME(name) name##_sse_full
#include "host/render/bvh_wide_traverse.inc"
#undef TB__WNAME
#undef TB__WFULL

bool tb__bvh_intersect(const tb_accel *acc, const tb_ray *ray, tb__accel_best *best)
{
    int64_t visited, tested;
    bool found;
    /* The short widening holds for tmin >= 0 (tb__wtest4). */
    bool full = !(ray->tmin >= 0.0f);
#if defined(TB_BVH_AVX)
    if (acc->wide_avx)
        found = full ? tb__bvhw_closest_avx_full(acc, ray, best, &visited, &tested)
                     : tb__bvhw_closest_avx(acc, ray, best, &visited, &tested);
    else
#endif
        found = full ? tb__bvhw_closest_sse_full(acc, ray, best, &visited, &tested)
                     : tb__bvhw_closest_sse(acc, ray, best, &visited, &tested);
    TB_STAT_INC(tb__bvh_rays);
    tb_stat_add(&tb__bvh_nodes_visited, visited);
    tb_stat_add(&tb__bvh_prims_tested, tested);
    return found;
}

/* ------------------------------------------------------------ any hit */

/* The occluder cache (POV-Ray's "shadow cache"): per thread, a small table
 * of the references that last blocked a shadow ray, indexed by the ray's
 * coarse direction, so that the next shadow ray toward the same light from a
 * nearby point tests that reference first and skips the traversal when it
 * still blocks. The answer cannot change: a ray is occluded if any
 * reference blocks it, whichever is tested first, so the cache holds only
 * hints (a stale entry, even one left by another structure at the same
 * address, costs one test, and an index out of range is ignored). */
#define TB__OCC_SLOTS 64u

typedef struct tb__occ_cache {
    const tb_accel *acc;          /* the structure the hints are for */
    uint32_t k[TB__OCC_SLOTS];    /* stored reference numbers; UINT32_MAX: none */
} tb__occ_cache;

static _Thread_local tb__occ_cache tb__occ;

/* Slot of the ray's direction: each component of d / |d|_1 in 8 steps. */
static unsigned tb__occ_slot(tb_vec3 d)
{
    float l = fabsf(d.x) + fabsf(d.y) + fabsf(d.z);
    float s = l > 0.0f ? 3.999f / l : 0.0f;
    unsigned qx = (unsigned)(int)(d.x * s + 4.0f), qy = (unsigned)(int)(d.y * s + 4.0f);
    unsigned qz = (unsigned)(int)(d.z * s + 4.0f);
    return ((qx * 73856093u) ^ (qy * 19349663u) ^ (qz * 83492791u)) % TB__OCC_SLOTS;
}

/* The traversal's conservative box test of one box against the whole ray. */
static bool tb__bvh_box_hit(const tb_aabb *b, const tb_ray *ray)
{
    tb_vec3 inv = {1.0f / ray->d.x, 1.0f / ray->d.y, 1.0f / ray->d.z};
    bool neg[3] = {signbit(inv.x) != 0, signbit(inv.y) != 0, signbit(inv.z) != 0};
    return tb__accel_slab(b, ray->o, inv, neg, tb__accel_widen_lo(ray->tmin), tb__accel_widen_hi(ray->tmax));
}

bool tb__bvh_occluded(const tb_accel *acc, const tb_ray *ray)
{
    tb__occ_cache *c = &tb__occ;
    if (c->acc != acc) {
        c->acc = acc;
        memset(c->k, 0xff, sizeof c->k);
    }
    unsigned slot = tb__occ_slot(ray->d);
    uint32_t k = c->k[slot];
    tb__accel_any q = tb__accel_any_start(ray);
    /* The hint's box first: a miss there costs a slab test, not a callback
     * (without the reference array, a packed triangle: its test). */
    if (k < acc->n && (!acc->prims || tb__bvh_box_hit(&acc->prims[k].bounds, ray))) {
        tb_stat_add(&tb__bvh_prims_tested, 1);
        if (tb__accel_test_any(acc, k, &q)) {
            TB_STAT_INC(tb__bvh_shadow_rays);
            TB_STAT_INC(tb__bvh_occ_hits);
            return true;
        }
    }
    uint32_t who = UINT32_MAX;
    int64_t visited, tested;
    bool hit;
    bool full = !(ray->tmin >= 0.0f);
#if defined(TB_BVH_AVX)
    if (acc->wide_avx)
        hit = full ? tb__bvhw_any_avx_full(acc, &q, &who, &visited, &tested)
                   : tb__bvhw_any_avx(acc, &q, &who, &visited, &tested);
    else
#endif
        hit = full ? tb__bvhw_any_sse_full(acc, &q, &who, &visited, &tested)
                   : tb__bvhw_any_sse(acc, &q, &who, &visited, &tested);
    TB_STAT_INC(tb__bvh_shadow_rays);
    tb_stat_add(&tb__bvh_nodes_visited, visited);
    tb_stat_add(&tb__bvh_prims_tested, tested);
    if (hit)
        c->k[slot] = who;
    return hit;
}
