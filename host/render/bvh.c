/* Bounding volume hierarchy over primitive references (docs/accel.md, "BVH"):
 * binned SAH build (Wald 2007, "On fast construction of SAH-based bounding
 * volume hierarchies"), subtrees built as OpenMP tasks, flattened depth-first
 * into 32-byte nodes (the layout tb_accel_bvh_nodes exposes), then collapsed
 * into the 8-wide tree that the CPU queries traverse (bvh_wide.c). */
#include <omp.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "host/render/accel_internal.h"
#include "util/stats/stats.h"

TB_STAT_TIMER(tb__bvh_build_time, "BVH/build");
TB_STAT_MEMORY(tb__bvh_memory, "BVH/memory");

#define TB__BVH_MAX_BINS 256
#define TB__BVH_DEFAULT_BINS 32
#define TB__BVH_DEFAULT_MAX_LEAF 8
/* Subtrees with fewer references are built by the task that made them:
 * below this a task costs more than it saves. */
#define TB__BVH_TASK_MIN 4096

/* A node of the tree under construction (ids are handed out as tasks run, so
 * they depend on timing; the flattened layout does not). */
typedef struct tb__bnode {
    tb_aabb bounds;
    uint32_t begin, count; /* the node's references: order[begin .. begin + count) */
    uint32_t child[2];     /* inner: ids of the children */
    uint8_t axis;          /* inner: split axis */
    bool leaf;
} tb__bnode;

typedef struct tb__builder {
    const tb_accel_prim *prims; /* stored references, input order */
    tb_vec3 *cent;              /* their box centroids */
    uint32_t *order;            /* permutation of 0..n-1, partitioned in place */
    tb__bnode *nodes;           /* room for 2n - 1 nodes */
    _Atomic uint32_t nnodes;
    int bins, max_leaf;
    double cost_node, cost_prim;
    atomic_int oom;             /* a median split could not allocate */
} tb__builder;

/* How a node measures its children's chance of being hit: surface area, or,
 * for a node box of zero area, the sum of its extents, or, for a point, 1. */
enum { TB__MEASURE_AREA, TB__MEASURE_LENGTH, TB__MEASURE_ONE };

/* Box union without libm's fminf/fmaxf (a call each, and the build is made
 * of unions). The boxes hold no NaN (tb_accel_build refuses them). */
static inline void tb__grow(tb_aabb *acc, const tb_aabb *b)
{
    acc->lo.x = b->lo.x < acc->lo.x ? b->lo.x : acc->lo.x;
    acc->lo.y = b->lo.y < acc->lo.y ? b->lo.y : acc->lo.y;
    acc->lo.z = b->lo.z < acc->lo.z ? b->lo.z : acc->lo.z;
    acc->hi.x = b->hi.x > acc->hi.x ? b->hi.x : acc->hi.x;
    acc->hi.y = b->hi.y > acc->hi.y ? b->hi.y : acc->hi.y;
    acc->hi.z = b->hi.z > acc->hi.z ? b->hi.z : acc->hi.z;
}
static inline void tb__grow_point(tb_aabb *acc, tb_vec3 p)
{
    tb__grow(acc, &(tb_aabb){p, p});
}

/* The measure of box `b` (double: float areas of huge boxes overflow); 0
 * for an empty box. */
static inline double tb__measure(const tb_aabb *b, int mode)
{
    double ex = (double)b->hi.x - b->lo.x, ey = (double)b->hi.y - b->lo.y, ez = (double)b->hi.z - b->lo.z;
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

static int tb__measure_mode(const tb_aabb *b)
{
    if (tb__measure(b, TB__MEASURE_AREA) > 0.0)
        return TB__MEASURE_AREA;
    if (tb__measure(b, TB__MEASURE_LENGTH) > 0.0)
        return TB__MEASURE_LENGTH;
    return TB__MEASURE_ONE;
}

/* The bin of centroid coordinate c (same arithmetic for binning and partitioning). */
static inline int tb__bin(float c, double lo, double scale, int bins)
{
    double t = ((double)c - lo) * scale;
    if (!(t > 0.0))
        return 0;
    if (t >= (double)bins)
        return bins - 1;
    return (int)t;
}

/* The chosen SAH split of a node. */
typedef struct tb__split {
    bool ok;       /* a plane with references on both sides was found */
    int axis;
    int plane;     /* bins [0, plane) go to the first child */
    double cost;   /* SAH cost of splitting there */
    double lo, scale; /* binning of that axis */
    int bins;         /* bins used at this node */
} tb__split;

/* Best binned SAH plane over the three axes. Kept out of line so that the
 * bin arrays live only while it runs, not in every frame of the recursion. */
static __attribute__((noinline)) tb__split tb__find_split(const tb__builder *b, uint32_t begin, uint32_t end,
                                                          const tb_aabb *cbox, int mode, double node_measure)
{
    tb_aabb box[3][TB__BVH_MAX_BINS];
    uint32_t cnt[3][TB__BVH_MAX_BINS];
    double rmeasure[TB__BVH_MAX_BINS];
    uint32_t rcount[TB__BVH_MAX_BINS];
    double lo[3], scale[3];
    bool live[3];
    /* No more bins than references: the sweeps cost O(bins) per node, and
     * most nodes are small. */
    const int nb = end - begin < (uint32_t)b->bins ? (int)(end - begin) : b->bins;
    tb__split best = {.ok = false, .cost = INFINITY};

    for (int a = 0; a < 3; a++) {
        lo[a] = tb_vec3_get(cbox->lo, a);
        double ext = (double)tb_vec3_get(cbox->hi, a) - lo[a];
        scale[a] = (double)nb / ext;
        live[a] = ext > 0.0 && isfinite(scale[a]) && scale[a] > 0.0;
        for (int k = 0; k < nb; k++) {
            box[a][k] = tb_aabb_empty();
            cnt[a][k] = 0;
        }
    }
    for (uint32_t i = begin; i < end; i++) {
        uint32_t r = b->order[i];
        tb_vec3 c = b->cent[r];
        for (int a = 0; a < 3; a++) {
            if (!live[a])
                continue;
            int k = tb__bin(tb_vec3_get(c, a), lo[a], scale[a], nb);
            cnt[a][k]++;
            tb__grow(&box[a][k], &b->prims[r].bounds);
        }
    }
    for (int a = 0; a < 3; a++) {
        if (!live[a])
            continue;
        /* rmeasure[p], rcount[p]: the bins p .. nb-1 (the second child of plane p). */
        tb_aabb acc = tb_aabb_empty();
        uint32_t n = 0;
        for (int p = nb - 1; p >= 1; p--) {
            tb__grow(&acc, &box[a][p]);
            n += cnt[a][p];
            rmeasure[p] = tb__measure(&acc, mode);
            rcount[p] = n;
        }
        acc = tb_aabb_empty();
        n = 0;
        for (int p = 1; p < nb; p++) {
            tb__grow(&acc, &box[a][p - 1]);
            n += cnt[a][p - 1];
            if (n == 0 || rcount[p] == 0)
                continue;
            double cost = b->cost_node + b->cost_prim *
                                             (tb__measure(&acc, mode) * n + rmeasure[p] * rcount[p]) /
                                             node_measure;
            /* Strict <: on equal cost the first axis and plane win. */
            if (cost < best.cost) {
                best = (tb__split){true, a, p, cost, lo[a], scale[a], nb};
            }
        }
    }
    return best;
}

/* A reference's position along an axis, for the median split. */
typedef struct tb__key {
    float c;
    uint32_t r;
} tb__key;

static int tb__key_cmp(const void *pa, const void *pb)
{
    const tb__key *a = pa, *b = pb;
    if (a->c != b->c)
        return a->c < b->c ? -1 : 1;
    return a->r < b->r ? -1 : (a->r > b->r);
}

/* Orders order[begin, end) by centroid along `axis` (ties by reference), so
 * that the halves of a median split are spatially coherent. */
static void tb__sort_by_axis(tb__builder *b, uint32_t begin, uint32_t end, int axis)
{
    size_t n = end - begin;
    tb__key *k = malloc(n * sizeof *k);
    if (!k) {
        atomic_store(&b->oom, 1);
        return;
    }
    for (size_t i = 0; i < n; i++) {
        uint32_t r = b->order[begin + i];
        k[i] = (tb__key){tb_vec3_get(b->cent[r], axis), r};
    }
    qsort(k, n, sizeof *k, tb__key_cmp);
    for (size_t i = 0; i < n; i++)
        b->order[begin + i] = k[i].r;
    free(k);
}

static void tb__build_node(tb__builder *b, uint32_t id, uint32_t begin, uint32_t end, int depth)
{
    tb__bnode *node = &b->nodes[id];
    uint32_t n = end - begin;
    tb_aabb bounds = tb_aabb_empty(), cbox = tb_aabb_empty();
    for (uint32_t i = begin; i < end; i++) {
        uint32_t r = b->order[i];
        tb__grow(&bounds, &b->prims[r].bounds);
        tb__grow_point(&cbox, b->cent[r]);
    }
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
        s = tb__find_split(b, begin, end, &cbox, mode, tb__measure(&bounds, mode));
    bool split = (s.ok && s.cost < leaf_cost) || n > (uint32_t)b->max_leaf;
    if (!split)
        return;

    uint32_t mid;
    int axis;
    if (s.ok) {
        /* In-place partition: bins below the plane first. */
        axis = s.axis;
        uint32_t i = begin, j = end;
        while (i < j) {
            uint32_t r = b->order[i];
            if (tb__bin(tb_vec3_get(b->cent[r], axis), s.lo, s.scale, s.bins) < s.plane) {
                i++;
            } else {
                b->order[i] = b->order[--j];
                b->order[j] = r;
            }
        }
        mid = i;
    } else {
        /* No SAH plane (all centroids in one point, or too deep): the median
         * along the longest centroid axis, or the middle of the range when the
         * centroids coincide. */
        axis = tb_aabb_largest_axis(&cbox);
        if (tb_vec3_get(tb_aabb_extent(&cbox), axis) > 0.0f)
            tb__sort_by_axis(b, begin, end, axis);
        mid = begin + n / 2;
    }
    if (mid == begin || mid == end) /* cannot happen with a valid plane; keep the tree finite anyway */
        mid = begin + n / 2;

    uint32_t l = atomic_fetch_add(&b->nnodes, 2);
    node->leaf = false;
    node->axis = (uint8_t)axis;
    node->child[0] = l;
    node->child[1] = l + 1;
    if (n >= TB__BVH_TASK_MIN) {
#pragma omp task default(none) firstprivate(b, l, begin, mid, depth)
        tb__build_node(b, l, begin, mid, depth + 1);
        tb__build_node(b, l + 1, mid, end, depth + 1);
#pragma omp taskwait
    } else {
        tb__build_node(b, l, begin, mid, depth + 1);
        tb__build_node(b, l + 1, mid, end, depth + 1);
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
    b.prims = acc->prims;
    b.bins = opt->bvh_bins ? opt->bvh_bins : TB__BVH_DEFAULT_BINS;
    b.max_leaf = opt->bvh_max_leaf ? opt->bvh_max_leaf : TB__BVH_DEFAULT_MAX_LEAF;
    b.cost_node = opt->bvh_cost_node > 0.0f ? opt->bvh_cost_node : 1.0;
    b.cost_prim = opt->bvh_cost_prim > 0.0f ? opt->bvh_cost_prim : 1.0;
    atomic_init(&b.nnodes, 1);
    atomic_init(&b.oom, 0);
    b.cent = malloc(n * sizeof *b.cent);
    b.order = malloc(n * sizeof *b.order);
    b.nodes = malloc((2 * n - 1) * sizeof *b.nodes);
    tb_bvh_node *nodes = NULL;
    tb_accel_prim *prims = NULL;
    uint32_t *index = NULL;
    tb_status st = TB_OK;
    if (!b.cent || !b.order || !b.nodes) {
        st = tb_error(TB_ERR_NOMEM, "BVH: out of memory for %zu references", n);
        goto done;
    }
    for (size_t i = 0; i < n; i++) {
        b.cent[i] = tb_aabb_centroid(&acc->prims[i].bounds);
        b.order[i] = (uint32_t)i;
    }

    if (n >= TB__BVH_TASK_MIN) {
        int threads = opt->threads > 0 ? opt->threads : omp_get_max_threads();
#pragma omp parallel num_threads(threads) default(none) shared(b, n)
#pragma omp single
        tb__build_node(&b, 0, 0, (uint32_t)n, 0);
    } else {
        tb__build_node(&b, 0, 0, (uint32_t)n, 0);
    }
    if (atomic_load(&b.oom)) {
        st = tb_error(TB_ERR_NOMEM, "BVH: out of memory while building");
        goto done;
    }

    uint32_t nnodes = atomic_load(&b.nnodes);
    nodes = malloc((size_t)nnodes * sizeof *nodes);
    prims = malloc(n * sizeof *prims);
    index = malloc(n * sizeof *index);
    if (!nodes || !prims || !index) {
        st = tb_error(TB_ERR_NOMEM, "BVH: out of memory for %u nodes", nnodes);
        goto done;
    }
    tb__flat f = {.out = nodes, .cost_node = b.cost_node, .cost_prim = b.cost_prim};
    f.mode = tb__measure_mode(&b.nodes[0].bounds);
    f.root_measure = tb__measure(&b.nodes[0].bounds, f.mode);
    tb__flatten(&b, 0, 0, &f);

    /* Leaf ranges already are positions in `order`: store the references in that order. */
    for (size_t i = 0; i < n; i++) {
        prims[i] = acc->prims[b.order[i]];
        index[i] = acc->index[b.order[i]];
    }
    free(acc->prims);
    free(acc->index);
    acc->prims = prims;
    acc->index = index;
    prims = NULL;
    index = NULL;
    acc->nodes = nodes;
    acc->nnodes = nnodes;
    nodes = NULL;

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
    }

done:
    free(nodes);
    free(prims);
    free(index);
    free(b.cent);
    free(b.order);
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
    acc->lanes = NULL;
    acc->lanes_f32 = false;
    acc->nodes = NULL;
    acc->nnodes = 0;
    acc->wide = NULL;
    acc->nwide = 0;
}
