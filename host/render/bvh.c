/* Bounding volume hierarchy over primitive references (docs/accel.md, "BVH"):
 * binned SAH build (Wald 2007, "On fast construction of SAH-based bounding
 * volume hierarchies"), subtrees built as OpenMP tasks, flattened depth-first
 * into 32-byte nodes (the layout tb_accel_bvh_nodes exposes), then collapsed
 * into the 8-wide tree that the CPU queries traverse (bvh_wide.c). */
#include <float.h>
#include <omp.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "host/render/accel_internal.h"
#include "util/stats/stats.h"

TB_STAT_TIMER(tb__bvh_build_time, "BVH/build");
TB_STAT_MEMORY(tb__bvh_memory, "BVH/memory");

#define TB__BVH_MAX_BINS 256
#define TB__BVH_DEFAULT_BINS 32
#define TB__BVH_DEFAULT_MAX_LEAF 8
/* Nodes with at least this many references bin with twice the bins. */
#define TB__BVH_WIDE_BINS_MIN 4096
/* Subtrees with fewer references are built by the task that made them:
 * below this a task costs more than it saves. */
#define TB__BVH_TASK_MIN 4096

/* A node of the tree under construction (ids are handed out as tasks run, so
 * they depend on timing; the flattened layout does not). */
typedef struct tb__bnode {
    tb_aabb bounds;
    uint32_t begin, count; /* the node's references: refs[begin .. begin + count) */
    uint32_t child[2];     /* inner: ids of the children */
    uint8_t axis;          /* inner: split axis */
    bool leaf;
} tb__bnode;

/* A reference as the build moves it: its box and its position in the
 * input, 32 bytes, partitioned in place so that every pass over a node's
 * references reads memory in order (an index array into the references
 * would make each of those reads a cache miss). */
typedef struct tb__bref {
    _Alignas(16) float lo[3];
    uint32_t id; /* the reference: position in acc->prims */
    float hi[3];
    uint32_t pad;
} tb__bref;

_Static_assert(sizeof(tb__bref) == 32, "tb__bref is 32 bytes");

typedef struct tb__builder {
    tb__bref *refs;             /* the references, partitioned in place */
    tb__bnode *nodes;           /* room for 2n - 1 nodes */
    _Atomic uint32_t nnodes;
    int bins, max_leaf;
    double cost_node, cost_prim;
    atomic_int oom;             /* a median split could not allocate */
} tb__builder;

/* How a node measures its children's chance of being hit: surface area, or,
 * for a node box of zero area, the sum of its extents, or, for a point, 1. */
enum { TB__MEASURE_AREA, TB__MEASURE_LENGTH, TB__MEASURE_ONE };

/* A box as four-lane vectors (the fourth lane is ignored). A union is
 * MINPS(b, a) = b < a ? b : a (MAXPS likewise) lane by lane: the scalar
 * union's test, so every bound is the value the scalar code gives. The
 * boxes hold no NaN (tb_accel_build refuses them). */
#if defined(__SSE2__)
typedef __m128 tb__f4;
typedef struct tb__box4 {
    __m128 lo, hi;
} tb__box4;
static inline tb__box4 tb__box4_empty(void) { return (tb__box4){_mm_set1_ps(INFINITY), _mm_set1_ps(-INFINITY)}; }
static inline void tb__box4_grow(tb__box4 *a, __m128 lo, __m128 hi)
{
    a->lo = _mm_min_ps(lo, a->lo);
    a->hi = _mm_max_ps(hi, a->hi);
}
static inline void tb__box4_add(tb__box4 *a, const tb__box4 *b) { tb__box4_grow(a, b->lo, b->hi); }
/* The fourth lane of lo holds the id's bits, a denormal float for most ids:
 * arithmetic on it (the centroid) would take a slow microcode path. Zeroed. */
static inline __m128 tb__ref_lo(const tb__bref *r)
{
    return _mm_and_ps(_mm_load_ps(r->lo), _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1)));
}
static inline __m128 tb__ref_hi(const tb__bref *r) { return _mm_load_ps(r->hi); }
/* The centroid as tb_aabb_centroid computes it: lo / 2 + hi / 2. */
static inline __m128 tb__ref_centroid(__m128 lo, __m128 hi)
{
    const __m128 half = _mm_set1_ps(0.5f);
    return _mm_add_ps(_mm_mul_ps(lo, half), _mm_mul_ps(hi, half));
}
static inline tb_aabb tb__box4_aabb(const tb__box4 *b)
{
    float lo[4], hi[4];
    _mm_storeu_ps(lo, b->lo);
    _mm_storeu_ps(hi, b->hi);
    return (tb_aabb){{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}};
}
static inline void tb__v4_store(float out[4], __m128 v) { _mm_storeu_ps(out, v); }
#else
typedef struct tb__v4 {
    float v[4];
} tb__v4;
typedef struct tb__box4 {
    tb__v4 lo, hi;
} tb__box4;
typedef tb__v4 tb__f4;
static inline tb__box4 tb__box4_empty(void)
{
    return (tb__box4){{{INFINITY, INFINITY, INFINITY, INFINITY}}, {{-INFINITY, -INFINITY, -INFINITY, -INFINITY}}};
}
static inline void tb__box4_grow(tb__box4 *a, tb__v4 lo, tb__v4 hi)
{
    for (int k = 0; k < 4; k++) {
        a->lo.v[k] = lo.v[k] < a->lo.v[k] ? lo.v[k] : a->lo.v[k];
        a->hi.v[k] = hi.v[k] > a->hi.v[k] ? hi.v[k] : a->hi.v[k];
    }
}
static inline void tb__box4_add(tb__box4 *a, const tb__box4 *b) { tb__box4_grow(a, b->lo, b->hi); }
static inline tb__v4 tb__ref_lo(const tb__bref *r) { return (tb__v4){{r->lo[0], r->lo[1], r->lo[2], 0.0f}}; }
static inline tb__v4 tb__ref_hi(const tb__bref *r) { return (tb__v4){{r->hi[0], r->hi[1], r->hi[2], 0.0f}}; }
static inline tb__v4 tb__ref_centroid(tb__v4 lo, tb__v4 hi)
{
    tb__v4 c;
    for (int k = 0; k < 4; k++)
        c.v[k] = lo.v[k] * 0.5f + hi.v[k] * 0.5f;
    return c;
}
static inline tb_aabb tb__box4_aabb(const tb__box4 *b)
{
    return (tb_aabb){{b->lo.v[0], b->lo.v[1], b->lo.v[2]}, {b->hi.v[0], b->hi.v[1], b->hi.v[2]}};
}
static inline void tb__v4_store(float out[4], tb__v4 v) { memcpy(out, v.v, sizeof v.v); }
#endif

/* The measure of box `b` (double: float areas of huge boxes overflow); 0
 * for an empty box. tb__measure4 computes the same from a tb__box4. */
static inline double tb__measure_ext(double ex, double ey, double ez, int mode)
{
    if (!(ex >= 0.0 && ey >= 0.0 && ez >= 0.0))
        return 0.0;
    switch (mode) {
    case TB__MEASURE_AREA:
        return ex * ey + ey * ez + ez * ex;
    case TB__MEASURE_LENGTH:
        return ex + ey + ez;
    default:
        return 1.0;
    }
}

static inline double tb__measure(const tb_aabb *b, int mode)
{
    return tb__measure_ext((double)b->hi.x - b->lo.x, (double)b->hi.y - b->lo.y, (double)b->hi.z - b->lo.z, mode);
}

static inline double tb__measure4(const tb__box4 *b, int mode)
{
#if defined(__SSE2__)
    __m128d e01 = _mm_sub_pd(_mm_cvtps_pd(b->hi), _mm_cvtps_pd(b->lo));
    __m128d e2 = _mm_sub_sd(_mm_cvtps_pd(_mm_movehl_ps(b->hi, b->hi)), _mm_cvtps_pd(_mm_movehl_ps(b->lo, b->lo)));
    double e[2];
    _mm_storeu_pd(e, e01);
    return tb__measure_ext(e[0], e[1], _mm_cvtsd_f64(e2), mode);
#else
    tb_aabb a = tb__box4_aabb(b);
    return tb__measure(&a, mode);
#endif
}

static int tb__measure_mode(const tb_aabb *b)
{
    if (tb__measure(b, TB__MEASURE_AREA) > 0.0)
        return TB__MEASURE_AREA;
    if (tb__measure(b, TB__MEASURE_LENGTH) > 0.0)
        return TB__MEASURE_LENGTH;
    return TB__MEASURE_ONE;
}

/* The bins of a node: per axis, the box and the number of the references
 * whose centroid falls in each. */
typedef struct tb__bins {
    tb__box4 box[TB__BVH_MAX_BINS][3]; /* [bin][axis]: the sweep takes the three axes at once */
    uint32_t cnt[TB__BVH_MAX_BINS][4]; /* [bin][axis]; the fourth is unused */
} tb__bins;

/* How a node's centroids map to bins: bin = trunc(clamp((c - lo) scale, 0,
 * nb - 1)) in float, for binning and partitioning alike. */
typedef struct tb__binning {
    float lo[3], scale[3];
    bool live[3]; /* the axis has extent: worth binning */
    int nb;       /* bins per axis */
} tb__binning;

static void tb__bins_clear(tb__bins *bn, int nb)
{
    for (int k = 0; k < nb; k++)
        for (int a = 0; a < 4; a++) {
            if (a < 3)
                bn->box[k][a] = tb__box4_empty();
            bn->cnt[k][a] = 0;
        }
}

/* The chosen SAH split of a node. */
typedef struct tb__split {
    bool ok;       /* a plane with references on both sides was found */
    int axis;
    int plane;     /* bins [0, plane) go to the first child */
    double cost;   /* SAH cost of splitting there */
    tb__binning g; /* the node's binning */
} tb__split;

/* The binning of a node's centroid box `cbox` in nb bins. */
static tb__binning tb__binning_make(const tb_aabb *cbox, int nb)
{
    tb__binning g = {.nb = nb};
    for (int a = 0; a < 3; a++) {
        float lo = tb_vec3_get(cbox->lo, a), ext = tb_vec3_get(cbox->hi, a) - lo;
        float scale = (float)nb / ext;
        g.live[a] = ext > 0.0f && isfinite(scale) && scale > 0.0f;
        g.lo[a] = g.live[a] ? lo : 0.0f;
        g.scale[a] = g.live[a] ? scale : 0.0f;
    }
    return g;
}

/* The bins of one reference's centroid on the three axes (a dead axis has
 * lo = scale = 0: bin 0, never looked at). tb__binner_t gives the clamped
 * t, whose truncation is the bin: bin < plane exactly when t < plane. */
#if defined(__SSE2__)
typedef struct tb__binner {
    __m128 lo, sc, top;
} tb__binner;
static inline tb__binner tb__binner_make(const tb__binning *g)
{
    return (tb__binner){_mm_setr_ps(g->lo[0], g->lo[1], g->lo[2], 0.0f),
                        _mm_setr_ps(g->scale[0], g->scale[1], g->scale[2], 0.0f), _mm_set1_ps((float)(g->nb - 1))};
}
/* MAXPS returns its second operand when the first is NaN: bin 0. */
static inline __m128 tb__binner_t(const tb__binner *q, __m128 c)
{
    return _mm_min_ps(_mm_max_ps(_mm_mul_ps(_mm_sub_ps(c, q->lo), q->sc), _mm_setzero_ps()), q->top);
}
static inline void tb__binner_bins(const tb__binner *q, __m128 c, int k[4])
{
    _mm_storeu_si128((__m128i *)k, _mm_cvttps_epi32(tb__binner_t(q, c)));
}
/* True if centroid c falls below `plane` on `axis`. */
static inline bool tb__binner_below(const tb__binner *q, __m128 c, __m128 plane, int axis)
{
    return (_mm_movemask_ps(_mm_cmplt_ps(tb__binner_t(q, c), plane)) >> axis) & 1;
}
static inline __m128 tb__binner_plane(int plane) { return _mm_set1_ps((float)plane); }
#else
typedef struct tb__binner {
    float lo[3], sc[3], top;
} tb__binner;
static inline tb__binner tb__binner_make(const tb__binning *g)
{
    tb__binner q = {.top = (float)(g->nb - 1)};
    for (int a = 0; a < 3; a++)
        q.lo[a] = g->lo[a], q.sc[a] = g->scale[a];
    return q;
}
static inline float tb__binner_t1(const tb__binner *q, float c, int a)
{
    float t = (c - q->lo[a]) * q->sc[a];
    t = t > 0.0f ? t : 0.0f;
    return t < q->top ? t : q->top;
}
static inline void tb__binner_bins(const tb__binner *q, tb__f4 c, int k[4])
{
    for (int a = 0; a < 3; a++)
        k[a] = (int)tb__binner_t1(q, c.v[a], a);
}
static inline bool tb__binner_below(const tb__binner *q, tb__f4 c, tb__f4 plane, int axis)
{
    return tb__binner_t1(q, c.v[axis], axis) < plane.v[0];
}
static inline tb__f4 tb__binner_plane(int plane) { return (tb__f4){{(float)plane, 0.0f, 0.0f, 0.0f}}; }
#endif

/* Adds reference r to the bins. */
static inline void tb__bins_add(tb__bins *bn, const tb__binner *q, const tb__bref *r)
{
    tb__f4 lo = tb__ref_lo(r), hi = tb__ref_hi(r);
    int k[4];
    tb__binner_bins(q, tb__ref_centroid(lo, hi), k);
    for (int a = 0; a < 3; a++) {
        bn->cnt[k[a]][a]++;
        tb__box4_grow(&bn->box[k[a]][a], lo, hi);
    }
}

/* Adds the bins of `from` to `to`. */
static void tb__bins_merge(tb__bins *to, const tb__bins *from, int nb)
{
    for (int k = 0; k < nb; k++)
        for (int a = 0; a < 3; a++) {
            to->cnt[k][a] += from->cnt[k][a];
            tb__box4_add(&to->box[k][a], &from->box[k][a]);
        }
}

/* Nodes with at least this many references bin every other reference into
 * a second set of bins, merged at the end: consecutive references often
 * fall in the same bins, and one set makes each update wait for the last. */
#define TB__BVH_TWO_SETS_MIN 256

/* Adds refs[begin, end) to the bins (cleared by the caller). */
static void tb__bins_fill(tb__bins *bn, const tb__binning *g, const tb__bref *refs, uint32_t begin, uint32_t end)
{
    const tb__binner q = tb__binner_make(g);
    uint32_t i = begin;
    if (end - begin >= TB__BVH_TWO_SETS_MIN) {
        tb__bins second;
        tb__bins_clear(&second, g->nb);
        for (; i + 1 < end; i += 2) {
            tb__bins_add(bn, &q, &refs[i]);
            tb__bins_add(&second, &q, &refs[i + 1]);
        }
        tb__bins_merge(bn, &second, g->nb);
    }
    for (; i < end; i++)
        tb__bins_add(bn, &q, &refs[i]);
}

/* Bins of a chunk of references filled by a task of a large node. */
#define TB__BVH_BIN_CHUNK 32768
/* Nodes with at least this many references bin in parallel (in fixed
 * chunks, merged in chunk order: the bins, so the tree, do not depend on
 * the thread count). */
#define TB__BVH_PAR_BIN_MIN (4 * TB__BVH_BIN_CHUNK)

/* Fills `bn` with refs[begin, end): serially, or for a large node as tasks
 * over fixed chunks whose bins are then merged. */
static void tb__bins_fill_node(tb__builder *b, tb__bins *bn, const tb__binning *g, uint32_t begin, uint32_t end)
{
    tb__bins_clear(bn, g->nb);
    uint32_t n = end - begin;
    size_t nchunks = (n + TB__BVH_BIN_CHUNK - 1) / TB__BVH_BIN_CHUNK;
    tb__bins *part = n >= TB__BVH_PAR_BIN_MIN && omp_in_parallel() ? malloc(nchunks * sizeof *part) : NULL;
    if (!part) {
        tb__bins_fill(bn, g, b->refs, begin, end);
        return;
    }
    const tb__bref *refs = b->refs;
    for (size_t c = 0; c < nchunks; c++) {
#pragma omp task default(none) firstprivate(c, part, g, refs, begin, end)
        {
            uint32_t cb = begin + (uint32_t)(c * TB__BVH_BIN_CHUNK);
            uint32_t ce = end - cb > TB__BVH_BIN_CHUNK ? cb + TB__BVH_BIN_CHUNK : end;
            tb__bins_clear(&part[c], g->nb);
            tb__bins_fill(&part[c], g, refs, cb, ce);
        }
    }
#pragma omp taskwait
    for (size_t c = 0; c < nchunks; c++)
        tb__bins_merge(bn, &part[c], g->nb);
    free(part);
}

/* The sweep in double (any node): per axis, every plane between bins,
 * right to left then left to right; the least cost wins with strict <
 * (first axis, then first plane). */
static void tb__sweep_f64(const tb__builder *b, const tb__bins *bn, tb__split *best, int mode, double node_measure)
{
    const int nb = best->g.nb;
    double rmeasure[TB__BVH_MAX_BINS];
    uint32_t rcount[TB__BVH_MAX_BINS];
    double best_x = INFINITY; /* the numerator of the best cost */
    for (int a = 0; a < 3; a++) {
        if (!best->g.live[a])
            continue;
        /* rmeasure[p], rcount[p]: the bins p .. nb-1 (the second child of plane p). */
        tb__box4 acc = tb__box4_empty();
        uint32_t n = 0;
        /* An empty bin changes neither side: its measure is the last one
         * (the union with an empty box is exact), and the plane after it
         * has the candidate of the plane before, which cannot win. */
        for (int p = nb - 1; p >= 1; p--) {
            rcount[p] = n += bn->cnt[p][a];
            if (bn->cnt[p][a] == 0 && p < nb - 1) {
                rmeasure[p] = rmeasure[p + 1];
                continue;
            }
            tb__box4_add(&acc, &bn->box[p][a]);
            rmeasure[p] = tb__measure4(&acc, mode);
        }
        acc = tb__box4_empty();
        n = 0;
        for (int p = 1; p < nb; p++) {
            if (bn->cnt[p - 1][a] == 0)
                continue;
            tb__box4_add(&acc, &bn->box[p - 1][a]);
            n += bn->cnt[p - 1][a];
            if (rcount[p] == 0)
                continue;
            /* The cost is a rounded, non-decreasing function of x, so it can
             * only beat the best if x does: the division is made then only,
             * and the choice is the one of comparing every cost. */
            double x = tb__measure4(&acc, mode) * n + rmeasure[p] * rcount[p];
            if (!(x < best_x))
                continue;
            double cost = b->cost_node + b->cost_prim * x / node_measure;
            if (cost < best->cost) {
                best->ok = true, best->axis = a, best->plane = p, best->cost = cost;
                best_x = x;
            }
        }
    }
}

#if defined(__SSE2__)
/* The measures of three boxes (one per axis of the sweep) from their
 * extents scaled by s: lane a is box a's. */
static inline __m128 tb__measure3(const tb__box4 acc[3], __m128 s, bool area)
{
    __m128 d0 = _mm_mul_ps(_mm_sub_ps(acc[0].hi, acc[0].lo), s);
    __m128 d1 = _mm_mul_ps(_mm_sub_ps(acc[1].hi, acc[1].lo), s);
    __m128 d2 = _mm_mul_ps(_mm_sub_ps(acc[2].hi, acc[2].lo), s);
    __m128 d3 = _mm_setzero_ps();
    _MM_TRANSPOSE4_PS(d0, d1, d2, d3); /* d0: the x extents of the three boxes, d1: y, d2: z */
    if (area)
        return _mm_add_ps(_mm_add_ps(_mm_mul_ps(d0, d1), _mm_mul_ps(d1, d2)), _mm_mul_ps(d2, d0));
    return _mm_add_ps(_mm_add_ps(d0, d1), d2);
}

/* The sweep in float, the three axes at once (SIMD lanes): the extents are
 * scaled by the power of two that brings the node's largest into [1/2, 1)
 * (so no measure overflows, and the sizes of the children relative to the
 * node keep float's precision); false (the double sweep then runs) for a
 * node whose box has no finite float extent, or a zero scaled measure. The
 * same rule as the double sweep: least n_L A(L) + n_R A(R), strict < (first
 * axis, then first plane). */
static bool tb__sweep_f32(const tb__builder *b, const tb__bins *bn, tb__split *best, const tb_aabb *bounds,
                          int mode)
{
    if (mode == TB__MEASURE_ONE)
        return false;
    const bool area = mode == TB__MEASURE_AREA;
    float ex = bounds->hi.x - bounds->lo.x, ey = bounds->hi.y - bounds->lo.y, ez = bounds->hi.z - bounds->lo.z;
    float m = fmaxf(ex, fmaxf(ey, ez));
    if (!(m > 0.0f && m <= FLT_MAX))
        return false;
    int e;
    frexpf(m, &e);
    float sc = ldexpf(1.0f, -e);
    if (!(sc > 0.0f && sc <= FLT_MAX))
        return false;
    ex *= sc, ey *= sc, ez *= sc;
    float node_measure = area ? ex * ey + ey * ez + ez * ex : ex + ey + ez;
    if (!(node_measure > 0.0f))
        return false;
    const int nb = best->g.nb;
    const __m128 vs = _mm_set1_ps(sc);
    _Alignas(16) float rmeasure[TB__BVH_MAX_BINS][4];
    _Alignas(16) int32_t rcount[TB__BVH_MAX_BINS][4];
    tb__box4 acc[3] = {tb__box4_empty(), tb__box4_empty(), tb__box4_empty()};
    __m128i n = _mm_setzero_si128();
    for (int p = nb - 1; p >= 1; p--) {
        for (int a = 0; a < 3; a++)
            tb__box4_add(&acc[a], &bn->box[p][a]);
        n = _mm_add_epi32(n, _mm_loadu_si128((const __m128i *)bn->cnt[p]));
        _mm_store_si128((__m128i *)rcount[p], n);
        _mm_store_ps(rmeasure[p], tb__measure3(acc, vs, area));
    }
    acc[0] = acc[1] = acc[2] = tb__box4_empty();
    n = _mm_setzero_si128();
    const __m128i zero = _mm_setzero_si128();
    __m128 best_x = _mm_set1_ps(INFINITY);
    __m128i best_p = zero;
    for (int p = 1; p < nb; p++) {
        for (int a = 0; a < 3; a++)
            tb__box4_add(&acc[a], &bn->box[p - 1][a]);
        n = _mm_add_epi32(n, _mm_loadu_si128((const __m128i *)bn->cnt[p - 1]));
        __m128i nr = _mm_load_si128((const __m128i *)rcount[p]);
        __m128 x = _mm_add_ps(_mm_mul_ps(tb__measure3(acc, vs, area), _mm_cvtepi32_ps(n)),
                              _mm_mul_ps(_mm_load_ps(rmeasure[p]), _mm_cvtepi32_ps(nr)));
        /* a plane with references on both sides that beats this axis' best so far */
        __m128i empty = _mm_or_si128(_mm_cmpeq_epi32(n, zero), _mm_cmpeq_epi32(nr, zero));
        __m128i win = _mm_andnot_si128(empty, _mm_castps_si128(_mm_cmplt_ps(x, best_x)));
        best_x = _mm_or_ps(_mm_and_ps(_mm_castsi128_ps(win), x), _mm_andnot_ps(_mm_castsi128_ps(win), best_x));
        best_p = _mm_or_si128(_mm_and_si128(win, _mm_set1_epi32(p)), _mm_andnot_si128(win, best_p));
    }
    _Alignas(16) float bx[4];
    _Alignas(16) int32_t bp[4];
    _mm_store_ps(bx, best_x);
    _mm_store_si128((__m128i *)bp, best_p);
    float least = INFINITY;
    for (int a = 0; a < 3; a++)
        if (best->g.live[a] && bx[a] < least) {
            least = bx[a];
            best->ok = true, best->axis = a, best->plane = bp[a];
        }
    if (best->ok)
        best->cost = b->cost_node + b->cost_prim * (double)least / (double)node_measure;
    return true;
}
#endif

/* Best binned SAH plane over the three axes. Kept out of line so that the
 * bin arrays live only while it runs, not in every frame of the recursion. */
static __attribute__((noinline)) tb__split tb__find_split(tb__builder *b, uint32_t begin, uint32_t end,
                                                          const tb_aabb *bounds, const tb_aabb *cbox, int mode,
                                                          double node_measure)
{
    tb__bins bn;
    /* No more bins than references: the sweeps cost O(bins) per node, and
     * most nodes are small. */
    int nb = end - begin < (uint32_t)b->bins ? (int)(end - begin) : b->bins;
    /* Large nodes: twice the bins. 32 cannot tell a small group at the
     * edge of a node's centroid range (a ground quad under a model) from its
     * neighbours: 8 % of SAH cost on a lat/long sphere on its ground, against
     * an exact sweep (test_bvh_sah_quality); the sweep's cost is nothing
     * next to binning 4096 references. */
    if (end - begin >= TB__BVH_WIDE_BINS_MIN)
        nb = 2 * b->bins < TB__BVH_MAX_BINS ? 2 * b->bins : TB__BVH_MAX_BINS;
    tb__split best = {.ok = false, .cost = INFINITY, .g = tb__binning_make(cbox, nb)};
    tb__bins_fill_node(b, &bn, &best.g, begin, end);
#if defined(__SSE2__)
    if (tb__sweep_f32(b, &bn, &best, bounds, mode))
        return best;
#else
    (void)bounds;
#endif
    tb__sweep_f64(b, &bn, &best, mode, node_measure);
    return best;
}

/* tb__find_split for a node of two references (about half of all nodes),
 * without the bins: on an axis where their centroids differ, the lower one
 * falls in bin 0 (t = 0) and the other in bin 1 (t about 2, clamped), so
 * every live axis offers the same plane, the sum of the two boxes'
 * measures, and the first live axis wins, as in the general sweep. */
static tb__split tb__find_split2(const tb__builder *b, uint32_t begin, const tb_aabb *cbox, int mode,
                                 double node_measure)
{
    tb__split s = {.ok = false, .cost = INFINITY, .g = tb__binning_make(cbox, 2)};
    for (int a = 0; a < 3; a++) {
        if (!s.g.live[a])
            continue;
        const tb__bref *r = &b->refs[begin];
        tb__box4 b0 = tb__box4_empty(), b1 = tb__box4_empty();
        tb__box4_grow(&b0, tb__ref_lo(&r[0]), tb__ref_hi(&r[0]));
        tb__box4_grow(&b1, tb__ref_lo(&r[1]), tb__ref_hi(&r[1]));
        double x = tb__measure4(&b0, mode) + tb__measure4(&b1, mode);
        s.ok = true, s.axis = a, s.plane = 1, s.cost = b->cost_node + b->cost_prim * x / node_measure;
        return s;
    }
    return s;
}

/* A reference's position along an axis, for the median split. */
typedef struct tb__key {
    float c;
    uint32_t id;  /* the reference (ties) */
    uint32_t pos; /* its place in the node's range */
} tb__key;

static int tb__key_cmp(const void *pa, const void *pb)
{
    const tb__key *a = pa, *b = pb;
    if (a->c != b->c)
        return a->c < b->c ? -1 : 1;
    return a->id < b->id ? -1 : (a->id > b->id);
}

/* Orders refs[begin, end) by centroid along `axis` (ties by reference), so
 * that the halves of a median split are spatially coherent. */
static void tb__sort_by_axis(tb__builder *b, uint32_t begin, uint32_t end, int axis)
{
    size_t n = end - begin;
    tb__key *k = malloc(n * sizeof *k);
    tb__bref *tmp = malloc(n * sizeof *tmp);
    if (!k || !tmp) {
        free(k);
        free(tmp);
        atomic_store(&b->oom, 1);
        return;
    }
    for (size_t i = 0; i < n; i++) {
        const tb__bref *r = &b->refs[begin + i];
        float c[4];
        tb__v4_store(c, tb__ref_centroid(tb__ref_lo(r), tb__ref_hi(r)));
        k[i] = (tb__key){c[axis], r->id, (uint32_t)i};
    }
    qsort(k, n, sizeof *k, tb__key_cmp);
    for (size_t i = 0; i < n; i++)
        tmp[i] = b->refs[begin + k[i].pos];
    memcpy(&b->refs[begin], tmp, n * sizeof *tmp);
    free(k);
    free(tmp);
}

/* The box and the centroid box of refs[begin, end). */
static void tb__range_bounds(const tb__bref *refs, uint32_t begin, uint32_t end, tb_aabb *bounds, tb_aabb *cbox)
{
    tb__box4 bb = tb__box4_empty(), cb = tb__box4_empty();
    for (uint32_t i = begin; i < end; i++) {
        tb__f4 lo = tb__ref_lo(&refs[i]), hi = tb__ref_hi(&refs[i]);
        tb__box4_grow(&bb, lo, hi);
        tb__f4 c = tb__ref_centroid(lo, hi);
        tb__box4_grow(&cb, c, c);
    }
    *bounds = tb__box4_aabb(&bb);
    *cbox = tb__box4_aabb(&cb);
}

/* Builds node `id` over refs[begin, end), whose box and centroid box are
 * `bounds` and `cbox` (the parent's partition computed them). */
static void tb__build_node(tb__builder *b, uint32_t id, uint32_t begin, uint32_t end, int depth, tb_aabb bounds,
                           tb_aabb cbox)
{
    tb__bnode *node = &b->nodes[id];
    uint32_t n = end - begin;
    node->bounds = bounds;
    node->begin = begin;
    node->count = n;
    node->leaf = true;
    node->axis = 0;
    if (n == 1)
        return;

    int mode = tb__measure_mode(&bounds);
    double leaf_cost = b->cost_prim * n;
    tb__split s = {.ok = false};
    if (depth < TB__BVH_SAH_MAX_DEPTH)
        s = n == 2 && b->bins >= 2 ? tb__find_split2(b, begin, &cbox, mode, tb__measure(&bounds, mode))
                                   : tb__find_split(b, begin, end, &bounds, &cbox, mode, tb__measure(&bounds, mode));
    bool split = (s.ok && s.cost < leaf_cost) || n > (uint32_t)b->max_leaf;
    if (!split)
        return;

    uint32_t mid;
    int axis;
    tb_aabb kb[2], kc[2];
    bool have_bounds = false;
    if (s.ok) {
        /* In-place partition: bins below the plane first. Every reference
         * is looked at once, so the children's boxes are gathered here. */
        axis = s.axis;
        tb__box4 lb = tb__box4_empty(), lc = tb__box4_empty(), rb = tb__box4_empty(), rc = tb__box4_empty();
        uint32_t i = begin, j = end;
        tb__bref *refs = b->refs;
        const tb__binner q = tb__binner_make(&s.g);
        const tb__f4 plane = tb__binner_plane(s.plane);
        while (i < j) {
            tb__f4 lo = tb__ref_lo(&refs[i]), hi = tb__ref_hi(&refs[i]);
            tb__f4 c4 = tb__ref_centroid(lo, hi);
            if (tb__binner_below(&q, c4, plane, axis)) {
                tb__box4_grow(&lb, lo, hi);
                tb__box4_grow(&lc, c4, c4);
                i++;
            } else {
                tb__bref r = refs[i];
                refs[i] = refs[--j];
                refs[j] = r;
                tb__box4_grow(&rb, lo, hi);
                tb__box4_grow(&rc, c4, c4);
            }
        }
        mid = i;
        kb[0] = tb__box4_aabb(&lb), kc[0] = tb__box4_aabb(&lc);
        kb[1] = tb__box4_aabb(&rb), kc[1] = tb__box4_aabb(&rc);
        have_bounds = true;
    } else {
        /* No SAH plane (all centroids in one point, or too deep): the median
         * along the longest centroid axis, or the middle of the range when the
         * centroids coincide. */
        axis = tb_aabb_largest_axis(&cbox);
        if (tb_vec3_get(tb_aabb_extent(&cbox), axis) > 0.0f)
            tb__sort_by_axis(b, begin, end, axis);
        mid = begin + n / 2;
    }
    if (mid == begin || mid == end) { /* cannot happen with a valid plane; keep the tree finite anyway */
        mid = begin + n / 2;
        have_bounds = false;
    }
    if (!have_bounds) {
        tb__range_bounds(b->refs, begin, mid, &kb[0], &kc[0]);
        tb__range_bounds(b->refs, mid, end, &kb[1], &kc[1]);
    }

    uint32_t l = atomic_fetch_add(&b->nnodes, 2);
    node->leaf = false;
    node->axis = (uint8_t)axis;
    node->child[0] = l;
    node->child[1] = l + 1;
    if (n >= TB__BVH_TASK_MIN) {
        tb_aabb b0 = kb[0], c0 = kc[0];
#pragma omp task default(none) firstprivate(b, l, begin, mid, depth, b0, c0)
        tb__build_node(b, l, begin, mid, depth + 1, b0, c0);
        tb__build_node(b, l + 1, mid, end, depth + 1, kb[1], kc[1]);
#pragma omp taskwait
    } else {
        tb__build_node(b, l, begin, mid, depth + 1, kb[0], kc[0]);
        tb__build_node(b, l + 1, mid, end, depth + 1, kb[1], kc[1]);
    }
}

/* Figures gathered while flattening. */
typedef struct tb__flat {
    tb_bvh_node *out;
    uint32_t next;
    size_t leaves;
    int depth, max_leaf;
    int mode;
    double root_measure, sah;
    double cost_node, cost_prim;
} tb__flat;

/* Writes the subtree of temporary node `id` depth-first from f->next; returns its index. */
static uint32_t tb__flatten(const tb__builder *b, uint32_t id, int depth, tb__flat *f)
{
    const tb__bnode *s = &b->nodes[id];
    uint32_t me = f->next++;
    tb_bvh_node *o = &f->out[me];
    memset(o, 0, sizeof *o);
    o->bounds = s->bounds;
    double p = f->root_measure > 0.0 ? tb__measure(&s->bounds, f->mode) / f->root_measure : 1.0;
    if (s->leaf) {
        o->offset = s->begin;
        o->count = (uint16_t)s->count;
        f->leaves++;
        if (depth > f->depth)
            f->depth = depth;
        if ((int)s->count > f->max_leaf)
            f->max_leaf = (int)s->count;
        f->sah += f->cost_prim * s->count * p;
        return me;
    }
    o->axis = s->axis;
    f->sah += f->cost_node * p;
    tb__flatten(b, s->child[0], depth + 1, f);
    uint32_t second = tb__flatten(b, s->child[1], depth + 1, f);
    o->offset = second;
    return me;
}

tb_status tb__bvh_build(tb_accel *acc, const tb_accel_options *opt)
{
    tb_timer_token timer = tb_timer_start(&tb__bvh_build_time);
    size_t n = acc->n;
    tb__builder b = {0};
    b.bins = opt->bvh_bins ? opt->bvh_bins : TB__BVH_DEFAULT_BINS;
    b.max_leaf = opt->bvh_max_leaf ? opt->bvh_max_leaf : TB__BVH_DEFAULT_MAX_LEAF;
    b.cost_node = opt->bvh_cost_node > 0.0f ? opt->bvh_cost_node : 1.0;
    b.cost_prim = opt->bvh_cost_prim > 0.0f ? opt->bvh_cost_prim : 1.0;
    atomic_init(&b.nnodes, 1);
    atomic_init(&b.oom, 0);
    b.refs = aligned_alloc(32, n * sizeof *b.refs);
    b.nodes = malloc((2 * n - 1) * sizeof *b.nodes);
    tb_bvh_node *nodes = NULL;
    tb_status st = TB_OK;
    if (!b.refs || !b.nodes) {
        st = tb_error(TB_ERR_NOMEM, "BVH: out of memory for %zu references", n);
        goto done;
    }
    for (size_t i = 0; i < n; i++) {
        const tb_aabb *bb = &acc->prims[i].bounds;
        b.refs[i] = (tb__bref){{bb->lo.x, bb->lo.y, bb->lo.z}, (uint32_t)i, {bb->hi.x, bb->hi.y, bb->hi.z}, 0};
    }
    tb_aabb root, rootc;
    tb__range_bounds(b.refs, 0, (uint32_t)n, &root, &rootc);

    if (n >= TB__BVH_TASK_MIN) {
        int threads = opt->threads > 0 ? opt->threads : omp_get_max_threads();
#pragma omp parallel num_threads(threads) default(none) shared(b, n, root, rootc)
#pragma omp single
        tb__build_node(&b, 0, 0, (uint32_t)n, 0, root, rootc);
    } else {
        tb__build_node(&b, 0, 0, (uint32_t)n, 0, root, rootc);
    }
    if (atomic_load(&b.oom)) {
        st = tb_error(TB_ERR_NOMEM, "BVH: out of memory while building");
        goto done;
    }

    uint32_t nnodes = atomic_load(&b.nnodes);
    nodes = malloc((size_t)nnodes * sizeof *nodes);
    if (!nodes) {
        st = tb_error(TB_ERR_NOMEM, "BVH: out of memory for %u nodes", nnodes);
        goto done;
    }
    tb__flat f = {.out = nodes, .cost_node = b.cost_node, .cost_prim = b.cost_prim};
    f.mode = tb__measure_mode(&b.nodes[0].bounds);
    f.root_measure = tb__measure(&b.nodes[0].bounds, f.mode);
    tb__flatten(&b, 0, 0, &f);
    /* The builder's nodes are done with: freed before anything else is
     * made, so they do not add to the build's peak. */
    free(b.nodes);
    b.nodes = NULL;

    /* Leaf ranges already are positions in the build order: the references
     * are gathered into it (new arrays: 36 bytes per reference more at this
     * point than a permutation in place, whose random writes made the whole
     * build about 20 % slower on 3*10^5 references). */
    {
        tb_accel_prim *prims = malloc(n * sizeof *prims);
        uint32_t *index = malloc(n * sizeof *index);
        if (!prims || !index) {
            free(prims);
            free(index);
            st = tb_error(TB_ERR_NOMEM, "BVH: out of memory for %zu references", n);
            goto done;
        }
        for (size_t i = 0; i < n; i++) {
            prims[i] = acc->prims[b.refs[i].id];
            index[i] = acc->index[b.refs[i].id];
        }
        free(acc->prims);
        free(acc->index);
        acc->prims = prims;
        acc->index = index;
    }
    acc->nodes = nodes;
    acc->nnodes = nnodes;
    nodes = NULL;
    free(b.refs);
    b.refs = NULL;

    acc->stats.bvh_nodes = nnodes;
    acc->stats.bvh_leaves = f.leaves;
    acc->stats.bvh_depth = f.depth;
    acc->stats.bvh_max_leaf_prims = f.max_leaf;
    acc->stats.bvh_sah_cost = f.sah;
    acc->stats.memory_bytes += (size_t)nnodes * sizeof(tb_bvh_node);
    tb_stat_add(&tb__bvh_memory, (int64_t)((size_t)nnodes * sizeof(tb_bvh_node)));
    st = tb__bvhw_build(acc, opt);
    if (st == TB_OK) {
        acc->stats.bvh_wide_nodes = acc->nwide;
        acc->stats.memory_bytes += acc->nwide * sizeof(tb__bvhw_node);
        tb_stat_add(&tb__bvh_memory, (int64_t)(acc->nwide * sizeof(tb__bvhw_node)));
        if (!opt->bvh_keep_binary) { /* the CPU traverses the wide tree alone */
            acc->stats.memory_bytes -= (size_t)nnodes * sizeof(tb_bvh_node);
            tb_stat_add(&tb__bvh_memory, -(int64_t)((size_t)nnodes * sizeof(tb_bvh_node)));
            free(acc->nodes);
            acc->nodes = NULL;
            acc->nnodes = 0;
        }
    }

done:
    free(nodes);
    free(b.refs);
    free(b.nodes);
    tb_timer_stop(timer);
    return st;
}

void tb__bvh_free(tb_accel *acc)
{
    if (acc->nodes)
        tb_stat_add(&tb__bvh_memory, -(int64_t)(acc->nnodes * sizeof(tb_bvh_node)));
    if (acc->wide)
        tb_stat_add(&tb__bvh_memory, -(int64_t)(acc->nwide * sizeof(tb__bvhw_node)));
    free(acc->nodes);
    free(acc->wide);
    free(acc->lanes);
    free(acc->lane_pos);
    acc->lanes = NULL;
    acc->lane_pos = NULL;
    acc->lanes_f32 = false;
    acc->nodes = NULL;
    acc->nnodes = 0;
    acc->wide = NULL;
    acc->nwide = 0;
}
