/* Internals shared by accel.c, bvh.c and grid.c: the structure itself, the
 * tie rule and the traversal tolerance (docs/accel.md). Not installed. */
#ifndef TB_HOST_RENDER_ACCEL_INTERNAL_H
#define TB_HOST_RENDER_ACCEL_INTERNAL_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>

#include "host/object/watertight.h"
#include "host/render/accel.h"
#include "util/math/float.h"

/* Relative tolerance in t by which traversal widens [tmin, tmax] when it
 * decides which boxes (BVH nodes, grid voxels) it may skip: a reference is
 * tested whenever the ray meets its box at some t within a relative 2^-16 of
 * [tmin, best t so far]. So a callback whose reported t is off by less than
 * that from a point inside the reference's box is still found, by every kind
 * (docs/accel.md, "Robustness"). Hits themselves are filtered with the exact
 * [tmin, tmax]. */
#define TB__ACCEL_T_TOL 0x1p-16

/* Most BVH levels split by SAH; deeper nodes are split at the median, so the
 * depth stays below TB__BVH_SAH_MAX_DEPTH + 32 and a fixed stack suffices. */
#define TB__BVH_SAH_MAX_DEPTH 64
#define TB__BVH_STACK 128

/* Children per node of the wide BVH the CPU queries traverse. */
#define TB__BVHW 8

/* One node of the wide BVH the CPU queries traverse (bvh_wide.c,
 * docs/accel.md "Wide nodes"): the binary tree collapsed so that a node
 * holds up to eight children, whose boxes are stored by coordinate
 * (structure of arrays) for one AVX slab test, or two SSE ones. The binary
 * nodes stay as they are (host/gpu converts them for the Vulkan kernels).
 * 288 bytes, 32-byte aligned. */
typedef struct tb__bvhw_node {
    /* Rows lo x, hi x, lo y, hi y, lo z, hi z; column i is child i. An unused
     * slot holds lo = +inf, hi = -inf, which no valid ray meets. */
    _Alignas(32) float box[6][TB__BVHW];
    uint32_t child[TB__BVHW]; /* inner child: its wide node; leaf child: its first stored reference */
    /* Leaf child: its references (1..255) in the low 8 bits, plus
     * TB__BVHW_PACKED when they are all triangles packed in tb_accel.lanes;
     * 0: an inner child or an unused slot. */
    uint16_t count[TB__BVHW];
    uint8_t n;                /* children used, 1..8 (slots 0 .. n-1) */
    uint8_t used;             /* (1 << n) - 1: the node test's mask is cut to it, so an unused slot is never
                               * followed even if a ray met its empty box (it cannot: docs/accel.md) */
    /* Per ray octant (bit a set: the direction's sign bit is set along axis
     * a), the children in traversal order far to near, 3 bits each from bit
     * 0: the binary tree's near-child-first order below this node. Last:
     * only a step that meets two children or more reads it. */
    _Alignas(32) uint32_t order[8];
} tb__bvhw_node;

_Static_assert(sizeof(tb__bvhw_node) == 288, "tb__bvhw_node is 288 bytes");

/* Flag in tb__bvhw_node.count: a leaf of triangle references only, whose
 * corners are packed in tb_accel.lanes for the multi-triangle test. */
#define TB__BVHW_PACKED 0x100u
/* Per reference in tb_accel.lanes: 9 corner values and one tb__lane_ids,
 * in doubles (TB__LANE_ROWS) or, when every packed corner is a float, in
 * floats (TB__LANE_ROWS_F). */
#define TB__LANE_ROWS 11u
#define TB__LANE_ROWS_F 13u

/* A packed triangle's identity, after its leaf's corner rows. */
typedef struct tb__lane_ids {
    uint32_t object, face; /* tb_accel_tri.object, .face */
    uint32_t index;        /* tb_accel.index of the reference (the tie rule's last key) */
    uint32_t sub;          /* its tb_accel_prim.sub */
} tb__lane_ids;

_Static_assert(sizeof(tb__lane_ids) == 2 * sizeof(double) && sizeof(tb__lane_ids) == 4 * sizeof(float),
               "tb__lane_ids fills two double rows or four float rows");

/* The reference count in tb__bvhw_node.count. */
#define TB__BVHW_COUNT(c) ((c) & 0xffu)

/* 3 x the position of child c in a node's order word (tb__bvhw_node.order:
 * far to near, 3 bits per position), without a loop: the fields equal to c
 * become 0 under the xor, and the lowest zero field is c's (positions past
 * the node's children read 0, but come later). c must be one of the node's
 * children. Only compared, so the factor 3 stays. */
static inline unsigned tb__bvhw_pos(uint32_t ord, unsigned c)
{
    uint32_t x = ord ^ (c * 0x249249u);
    return (unsigned)__builtin_ctz(~(x | x >> 1 | x >> 2) & 0x249249u);
}

/* Wide levels are at most the binary depth, each pushing at most 7 children. */
#define TB__BVHW_STACK (7 * TB__BVH_STACK)

/* The uniform grid (grid.c). Voxel (x, y, z) is cell x + res[0] (y + res[1] z)
 * and covers lo + (x, y, z) * cell .. lo + (x + 1, y + 1, z + 1) * cell. */
typedef struct tb__grid {
    double lo[3];          /* grid corner (the references' box, padded) */
    double hi[3];          /* opposite corner */
    double cell[3];        /* voxel size per axis */
    double inv_cell[3];    /* 1 / cell */
    int res[3];            /* voxels per axis, >= 1 */
    uint32_t *cell_start;  /* ncells + 1 offsets into cell_refs */
    uint32_t *cell_refs;   /* per voxel, positions in tb_accel.prims, ascending */
    size_t nrefs;          /* entries of cell_refs */
} tb__grid;

struct tb_accel {
    tb_accel_kind kind;
    tb_accel_callbacks cb;
    size_t n;              /* references stored */
    tb_accel_prim *prims;  /* stored references: BVH leaf order, else input order (empty boxes dropped);
                              NULL once built when every one is a packed triangle (lane_pos), unless the
                              binary nodes are kept: the lanes hold what the queries read (tb__accel_ids) */
    uint32_t *index;       /* input index of each stored reference (the tie rule's last key); NULL with prims */
    tb_accel_tri *tris;    /* cb.tris's triangles in stored order (a leaf's triangles side by side), or NULL
                              when there is none: see tb__accel_tri_at */
    uint32_t *tri_of;      /* per stored reference, its record in tris (TB_ACCEL_TRI_NONE: not a triangle);
                              NULL when every reference is a triangle (record k is reference k) */
    tb_aabb bounds;        /* union of the stored boxes */
    tb_accel_stats stats;  /* filled at build */
    tb_bvh_node *nodes;    /* BVH: depth-first binary nodes (the layout tb_accel_bvh_nodes exposes) */
    size_t nnodes;
    tb__bvhw_node *wide;   /* BVH: the binary tree collapsed 8-wide, depth-first (what the CPU traverses) */
    size_t nwide;
    bool wide_avx;         /* traverse with the AVX node test (the CPU has AVX and the options allow it) */
    /* BVH: the corners of each leaf of triangles only, packed by coordinate
     * for the multi-triangle test (docs/accel.md "Packed leaves"): the leaf
     * whose references are stored at s .. s + n - 1 has TB__LANE_ROWS n
     * doubles from (double *)lanes + TB__LANE_ROWS s (or TB__LANE_ROWS_F n
     * floats from (float *)lanes + TB__LANE_ROWS_F s when lanes_f32): rows
     * 3 c + a (corner c, axis a) holding its n triangles' values side by
     * side, then n tb__lane_ids (what a hit needs, so a hit reads no other
     * array). NULL when no leaf is packed. */
    void *lanes;
    bool lanes_f32;        /* every packed corner is a float (exactly), stored as one: 52 bytes per reference */
    /* When every reference is a triangle in a packed leaf, the records are
     * freed (tris NULL: the lanes hold the same values) and this gives, per
     * stored reference, its place in its leaf (high byte) and the leaf's
     * size (low byte), from which tb__accel_tri_at reads it back; else NULL. */
    uint16_t *lane_pos;
    tb__grid grid;         /* grid */
};

/* t moved outward by the relative tolerance (never NaN; +-inf stay). */
static inline float tb__accel_widen_lo(float t)
{
    return t > 0.0f ? t * (float)(1.0 - TB__ACCEL_T_TOL) : t * (float)(1.0 + TB__ACCEL_T_TOL);
}
static inline float tb__accel_widen_hi(float t)
{
    return t > 0.0f ? t * (float)(1.0 + TB__ACCEL_T_TOL) : t * (float)(1.0 - TB__ACCEL_T_TOL);
}

/* The robust slab test of util/math (tb_aabb_slab: same per-axis values,
 * bit for bit, so the same conservative guarantee), written for a traversal
 * loop: the near/far plane choice is made once per ray (neg_* from the sign
 * bit of inv_d), the outward widening by 2 gamma(3) multiplies by a factor
 * picked with copysign instead of branching on the sign of t (branches that
 * mispredict when rays start among the boxes), and box `b` must not be empty
 * (BVH nodes never are). A NaN product (origin on a plane, direction 0)
 * leaves the interval unchanged, as there. True if [tmin, tmax] meets b;
 * *tnear is then where the (widened) ray enters b, clamped to tmin, so the
 * same test with any smaller tmax passes exactly when *tnear <= tmax. */
static inline __attribute__((always_inline)) bool tb__accel_slab_t(const tb_aabb *b, tb_vec3 o, tb_vec3 inv,
                                                                   const bool neg[3], float tmin, float tmax,
                                                                   float *tnear)
{
    const float k = 2.0f * tb_gamma(3);
    float nx = neg[0] ? b->hi.x : b->lo.x, fx = neg[0] ? b->lo.x : b->hi.x;
    float ny = neg[1] ? b->hi.y : b->lo.y, fy = neg[1] ? b->lo.y : b->hi.y;
    float nz = neg[2] ? b->hi.z : b->lo.z, fz = neg[2] ? b->lo.z : b->hi.z;
    float tnx = (nx - o.x) * inv.x, tfx = (fx - o.x) * inv.x;
    float tny = (ny - o.y) * inv.y, tfy = (fy - o.y) * inv.y;
    float tnz = (nz - o.z) * inv.z, tfz = (fz - o.z) * inv.z;
    /* t > 0: near * (1 - k), far * (1 + k); otherwise the other way round
     * (for +-0 both give +-0, as in util/math). */
    tnx *= 1.0f - copysignf(k, tnx);
    tny *= 1.0f - copysignf(k, tny);
    tnz *= 1.0f - copysignf(k, tnz);
    tfx *= 1.0f + copysignf(k, tfx);
    tfy *= 1.0f + copysignf(k, tfy);
    tfz *= 1.0f + copysignf(k, tfz);
    /* `x > t ? x : t` keeps t when x is NaN. */
    tmin = tnx > tmin ? tnx : tmin;
    tmin = tny > tmin ? tny : tmin;
    tmin = tnz > tmin ? tnz : tmin;
    tmax = tfx < tmax ? tfx : tmax;
    tmax = tfy < tmax ? tfy : tmax;
    tmax = tfz < tmax ? tfz : tmax;
    *tnear = tmin;
    return tmin <= tmax;
}

/* The same test without the entry distance. */
static inline __attribute__((always_inline)) bool tb__accel_slab(const tb_aabb *b, tb_vec3 o, tb_vec3 inv,
                                                                 const bool neg[3], float tmin, float tmax)
{
    float tnear;
    return tb__accel_slab_t(b, o, inv, neg, tmin, tmax, &tnear);
}

/* The tie rule: true if hit a (from stored reference with input index ia)
 * comes before hit b (input index ib): smaller t, then smaller object index,
 * then smaller face ID, then smaller input index. A total order on distinct
 * references, so the closest hit does not depend on the order in which a
 * structure meets them. */
static inline bool tb__accel_before(const tb_hit *a, uint32_t ia, const tb_hit *b, uint32_t ib)
{
    if (a->t != b->t)
        return a->t < b->t;
    if (a->object != b->object)
        return a->object < b->object;
    if (a->face != b->face)
        return a->face < b->face;
    return ia < ib;
}

/* The running closest hit of one query. */
typedef struct tb__accel_best {
    tb_ray ray;      /* the query ray with tmax = best t so far (what callbacks see) */
    tb_hit hit;      /* valid when found */
    uint32_t index;  /* input index of hit's reference */
    bool found;
    bool wready;     /* w is prepared (on the first triangle reference the query tests) */
    tb_wt_ray w;     /* the ray prepared for the watertight test */
    tb_accel_tri_hit tri; /* the hit's triangle details when it came from a triangle reference */
} tb__accel_best;

/* The triangle record of stored reference k, or NULL if it is not a triangle
 * (only triangles have one: an 80-byte record per whole object would double
 * the structure's size in a scene of objects and a few meshes). Where the
 * records were dropped for the packed corners (acc->lane_pos), the record is
 * read back from its leaf's lanes into *tmp: the same doubles (a float lane
 * holds a value that is exactly a float). */
static inline const tb_accel_tri *tb__accel_tri_at(const tb_accel *acc, size_t k, tb_accel_tri *tmp)
{
    if (acc->lane_pos) {
        size_t j = acc->lane_pos[k] >> 8, n = acc->lane_pos[k] & 0xffu, s = k - j;
        const tb__lane_ids *id;
        if (acc->lanes_f32) {
            const float *base = (const float *)acc->lanes + TB__LANE_ROWS_F * s;
            for (size_t r = 0; r < 9; r++)
                tmp->v[r] = (double)base[r * n + j];
            id = (const tb__lane_ids *)(base + 9 * n) + j;
        } else {
            const double *base = (const double *)acc->lanes + TB__LANE_ROWS * s;
            for (size_t r = 0; r < 9; r++)
                tmp->v[r] = base[r * n + j];
            id = (const tb__lane_ids *)(base + 9 * n) + j;
        }
        tmp->object = id->object;
        tmp->face = id->face;
        return tmp;
    }
    if (!acc->tris)
        return NULL;
    if (!acc->tri_of)
        return &acc->tris[k];
    uint32_t i = acc->tri_of[k];
    return i == TB_ACCEL_TRI_NONE ? NULL : &acc->tris[i];
}

/* The packed identity of stored reference k, a triangle of a structure with
 * lane_pos (every reference packed): its object, face, input index and sub. */
static inline const tb__lane_ids *tb__accel_lane_ids(const tb_accel *acc, size_t k)
{
    size_t j = acc->lane_pos[k] >> 8, n = acc->lane_pos[k] & 0xffu, s = k - j;
    const char *base = acc->lanes_f32 ? (const char *)((const float *)acc->lanes + TB__LANE_ROWS_F * s)
                                      : (const char *)((const double *)acc->lanes + TB__LANE_ROWS * s);
    return (const tb__lane_ids *)(base + 9 * n * (acc->lanes_f32 ? sizeof(float) : sizeof(double))) + j;
}

/* The input index and sub of stored reference k (from its lanes when the
 * reference array was dropped). */
static inline void tb__accel_ids(const tb_accel *acc, size_t k, uint32_t *index, uint32_t *sub)
{
    if (acc->index) {
        *index = acc->index[k];
        *sub = acc->prims[k].sub;
    } else {
        const tb__lane_ids *id = tb__accel_lane_ids(acc, k);
        *index = id->index;
        *sub = id->sub;
    }
}

/* The triangle test on stored reference k (acc->tris[k] is a triangle): the
 * crossing's float t in [tmin, tmax]. */
static inline __attribute__((always_inline)) bool tb__accel_tri_test(const tb_accel_tri *tr, const tb_ray *ray,
                                                                     tb_wt_ray *w, bool *wready, double *t,
                                                                     int *dir, double *uvw)
{
    if (!*wready) {
        tb_wt_ray_init(w, ray);
        *wready = true;
    }
    if (!tb_wt_triangle(w, &tr->v[0], &tr->v[3], &tr->v[6], t, dir, uvw))
        return false;
    return (float)*t >= ray->tmin && (float)*t <= ray->tmax;
}

/* Hit h of the reference with input index idx becomes the running best if
 * it comes first in the tie rule; true if it did. */
static inline bool tb__accel_offer(tb__accel_best *b, const tb_hit *h, uint32_t idx)
{
    if (b->found && !tb__accel_before(h, idx, &b->hit, b->index))
        return false;
    b->hit = *h;
    b->index = idx;
    b->found = true;
    b->ray.tmax = h->t;
    return true;
}

/* Offers the crossing (t in the ray's range, dir, edge functions uvw) of a
 * triangle reference (its object, face, input index and sub) to the running
 * best; true if it became the best. */
static inline bool tb__accel_tri_offer(tb__accel_best *b, uint32_t object, uint32_t face, uint32_t index,
                                       uint32_t sub, double t, int dir, const double uvw[3])
{
    tb_hit h = {(float)t, object, face, 0.0f, 0.0f, {0.0f, 0.0f, 0.0f}};
    if (!tb__accel_offer(b, &h, index))
        return false;
    b->tri = (tb_accel_tri_hit){index, sub, dir, t, {uvw[0], uvw[1], uvw[2]}};
    return true;
}

/* Tests stored reference k against the running best; true if it improved it. */
static inline bool tb__accel_test(const tb_accel *acc, size_t k, tb__accel_best *b)
{
    tb_accel_tri tmp;
    const tb_accel_tri *tr = tb__accel_tri_at(acc, k, &tmp);
    if (tr) {
        double t, uvw[3];
        int dir;
        if (!tb__accel_tri_test(tr, &b->ray, &b->w, &b->wready, &t, &dir, uvw))
            return false;
        uint32_t index, sub;
        tb__accel_ids(acc, k, &index, &sub);
        return tb__accel_tri_offer(b, tr->object, tr->face, index, sub, t, dir, uvw);
    }
    tb_hit h;
    if (!acc->cb.intersect(acc->cb.ctx, &acc->prims[k], acc->index[k], &b->ray, &h))
        return false;
    /* The callback's range check is not trusted: hits outside [tmin, tmax] (or NaN) never pass. */
    if (!(h.t >= b->ray.tmin && h.t <= b->ray.tmax) || !tb__accel_offer(b, &h, acc->index[k]))
        return false;
    b->tri.index = TB_ACCEL_TRI_NONE;
    return true;
}

/* One any-hit query: the ray, and its preparation for triangle references. */
typedef struct tb__accel_any {
    const tb_ray *ray;
    bool wready;     /* w is prepared */
    tb_wt_ray w;
} tb__accel_any;

/* An any-hit query for `ray`, its triangle preparation not yet made. The
 * prepared ray is zeroed rather than left unset: GCC cannot see that it is
 * only read after tb__accel_tri_test prepares it, and the cost is a few
 * stores where a designated initialiser would clear the struct with rep stos. */
static inline tb__accel_any tb__accel_any_start(const tb_ray *ray)
{
    tb__accel_any q;
    q.ray = ray;
    q.wready = false;
    q.w = (tb_wt_ray){{0.0, 0.0, 0.0}, 0, 0, 0, 0.0, 0.0, 0.0};
    return q;
}

/* True if stored reference k is hit within the ray's [tmin, tmax]. */
static inline bool tb__accel_test_any(const tb_accel *acc, size_t k, tb__accel_any *q)
{
    const tb_ray *ray = q->ray;
    tb_accel_tri tmp;
    const tb_accel_tri *tr = tb__accel_tri_at(acc, k, &tmp);
    if (tr) {
        double t;
        int dir;
        return tb__accel_tri_test(tr, ray, &q->w, &q->wready, &t, &dir, NULL);
    }
    if (acc->cb.occluded)
        return acc->cb.occluded(acc->cb.ctx, &acc->prims[k], acc->index[k], ray);
    tb_hit h;
    if (!acc->cb.intersect(acc->cb.ctx, &acc->prims[k], acc->index[k], ray, &h))
        return false;
    return h.t >= ray->tmin && h.t <= ray->tmax;
}

/* Per kind: build over acc->prims / acc->index (input order, acc->n > 0),
 * filling the kind's part of acc->stats; then closest hit and any hit for
 * valid rays. */
tb_status tb__bvh_build(tb_accel *acc, const tb_accel_options *opt);
/* Collapses acc->nodes into acc->wide (bvh_wide.c; called by tb__bvh_build). */
tb_status tb__bvhw_build(tb_accel *acc, const tb_accel_options *opt);
/* Packs the corners of the wide tree's all-triangle leaves into acc->lanes
 * and flags them (bvh_wide.c; called once acc->tris is in stored order). */
tb_status tb__bvhw_pack(tb_accel *acc);
/* The wide node test on its own, for tests: bit i of the result is set if
 * child i's box meets [tmin, tmax] under tb__accel_slab_t's arithmetic (the
 * same bits per child), and tnear[i] is then that test's entry distance.
 * avx: the AVX test (only where tb__bvhw_have_avx()), else the SSE2 one. */
unsigned tb__bvhw_slab_test(const tb__bvhw_node *nd, const tb_ray *ray, float tmin, float tmax,
                            float tnear[TB__BVHW], bool avx);
/* True if this build has the AVX traversal and the CPU runs it. */
bool tb__bvhw_have_avx(void);
/* The traversal loops (bvh_wide_traverse.inc) per instruction set; the AVX
 * ones are compiled in bvh_wide_avx.c when TB_BVH_AVX is defined. */
bool tb__bvhw_closest_sse(const tb_accel *acc, const tb_ray *ray, tb__accel_best *best, int64_t *visited,
                          int64_t *tested);
bool tb__bvhw_any_sse(const tb_accel *acc, tb__accel_any *q, uint32_t *who, int64_t *visited, int64_t *tested);
/* The same for rays with tmin < 0 (the node test's full widening; the above need tmin >= 0). */
bool tb__bvhw_closest_sse_full(const tb_accel *acc, const tb_ray *ray, tb__accel_best *best, int64_t *visited,
                               int64_t *tested);
bool tb__bvhw_any_sse_full(const tb_accel *acc, tb__accel_any *q, uint32_t *who, int64_t *visited,
                           int64_t *tested);
#if defined(TB_BVH_AVX)
bool tb__bvhw_closest_avx(const tb_accel *acc, const tb_ray *ray, tb__accel_best *best, int64_t *visited,
                          int64_t *tested);
bool tb__bvhw_any_avx(const tb_accel *acc, tb__accel_any *q, uint32_t *who, int64_t *visited, int64_t *tested);
bool tb__bvhw_closest_avx_full(const tb_accel *acc, const tb_ray *ray, tb__accel_best *best, int64_t *visited,
                               int64_t *tested);
bool tb__bvhw_any_avx_full(const tb_accel *acc, tb__accel_any *q, uint32_t *who, int64_t *visited,
                           int64_t *tested);
unsigned tb__bvhw_slab_test_avx(const tb__bvhw_node *nd, const tb_ray *ray, float tmin, float tmax,
                                float tnear[TB__BVHW]);
#endif
bool tb__bvh_intersect(const tb_accel *acc, const tb_ray *ray, tb__accel_best *best);
bool tb__bvh_occluded(const tb_accel *acc, const tb_ray *ray);
void tb__bvh_free(tb_accel *acc);

tb_status tb__grid_build(tb_accel *acc, const tb_accel_options *opt);
bool tb__grid_intersect(const tb_accel *acc, const tb_ray *ray, tb__accel_best *best);
bool tb__grid_occluded(const tb_accel *acc, const tb_ray *ray);
void tb__grid_free(tb_accel *acc);

#endif
