/* `testbed bench accel --scene SCENE.mid [--embree]`: the build of a scene's
 * acceleration structure, ours against Embree 3's (docs/performance.md,
 * "BVH build vs Embree").
 *
 * Ours: tb_scene_rebuild_accel (what a render pays: triangle records, the
 * binary SAH tree, the 8-wide collapse, packed leaves), best of --repeat
 * builds per thread count; its SAH cost is that of the binary tree.
 * Embree, same thread count (device config threads=T):
 *   high   rtcCommitScene of the meshes (bench_embree.h) at
 *          RTC_BUILD_QUALITY_HIGH (spatial splits): its triangle BVH (its
 *          tree is internal: time only);
 *   med    the same at RTC_BUILD_QUALITY_MEDIUM, Embree's default, the scene
 *          `bench rays --embree` traces;
 *   bvh    rtcBuildBVH at RTC_BUILD_QUALITY_HIGH over our references' boxes
 *          (every reference, whole objects too), binary, leaves of at most 8,
 *          traversal and intersection cost 1: our builder's constants. No
 *          split callback, so no spatial splits: like ours, a partition of
 *          the references. Its SAH cost is computed over the tree it hands
 *          to our node callbacks by the same function that computes ours.
 * The SAH cost (docs/accel.md, "SAH cost"): sum over inner nodes of
 * A(node) / A(root) + sum over leaves of count * A(leaf) / A(root), A the
 * surface area. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_embree.h"
#include "cli_util.h"
#include "commands.h"
#include "host/render/accel.h"
#include "host/render/scene.h"

static double tb__now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Half the surface area of b, in double (as the builder measures). */
static double tb__half_area(const tb_aabb *b)
{
    double ex = (double)b->hi.x - b->lo.x, ey = (double)b->hi.y - b->lo.y, ez = (double)b->hi.z - b->lo.z;
    return ex * ey + ey * ez + ez * ex;
}

/* SAH cost of our binary tree from its node array (tb_accel_bvh_nodes). */
static double tb__sah_ours(const tb_accel *acc)
{
    size_t n;
    const tb_bvh_node *nodes = tb_accel_bvh_nodes(acc, &n);
    if (!nodes || n == 0)
        return 0.0;
    double root = tb__half_area(&nodes[0].bounds), sum = 0.0;
    for (size_t i = 0; i < n; i++) {
        double p = root > 0.0 ? tb__half_area(&nodes[i].bounds) / root : 1.0;
        sum += nodes[i].count ? nodes[i].count * p : p;
    }
    return sum;
}

/* A fingerprint of our tree: FNV-1a over the node array (zeros made
 * positive: the sign of a zero bound depends on the order of a union and
 * changes no answer) and the leaf order of the references. Equal
 * fingerprints: the same tree. */
static uint64_t tb__tree_hash(const tb_accel *acc)
{
    uint64_t h = 1469598103934665603ull;
    size_t n, nr;
    const tb_bvh_node *nodes = tb_accel_bvh_nodes(acc, &n);
    const uint32_t *refs = tb_accel_bvh_refs(acc, &nr);
    for (size_t i = 0; nodes && i < n; i++) {
        tb_bvh_node c = nodes[i];
        float *f = &c.bounds.lo.x;
        for (int k = 0; k < 6; k++)
            f[k] += 0.0f;
        const unsigned char *p = (const unsigned char *)&c;
        for (size_t k = 0; k < sizeof c; k++)
            h = (h ^ p[k]) * 1099511628211ull;
    }
    for (size_t i = 0; refs && i < nr; i++)
        h = (h ^ refs[i]) * 1099511628211ull;
    return h;
}

/* Our build at `threads` threads, best of `repeat`: seconds, and the tree's SAH cost. */
static bool tb__time_ours(tb_scene *s, int threads, int repeat, double *seconds, double *sah, uint64_t *hash)
{
    *seconds = INFINITY;
    tb_accel_options o = {.threads = threads, .bvh_keep_binary = 1}; /* the SAH and hash read the binary tree */
    for (int r = 0; r < repeat; r++) {
        double t0 = tb__now();
        if (tb_scene_rebuild_accel(s, TB_ACCEL_BVH, &o)) {
            fprintf(stderr, "testbed bench accel: %s\n", tb_last_error());
            return false;
        }
        *seconds = fmin(*seconds, tb__now() - t0);
    }
    *sah = tb__sah_ours(s->accel);
    *hash = tb__tree_hash(s->accel);
    return true;
}

#ifdef TB_HAVE_EMBREE
/* A node of the tree rtcBuildBVH hands to our callbacks. */
typedef struct tb__enode {
    unsigned count;            /* leaf: references; 0: inner node */
    tb_aabb box[2];            /* inner: the children's boxes; leaf: box[0] is the leaf's */
    struct tb__enode *child[2];
} tb__enode;

static void *tb__e_create_node(RTCThreadLocalAllocator alloc, unsigned n, void *user)
{
    (void)user;
    (void)n; /* maxBranchingFactor 2 */
    tb__enode *e = rtcThreadLocalAlloc(alloc, sizeof *e, 16);
    memset(e, 0, sizeof *e);
    return e;
}

static void tb__e_set_children(void *node, void **child, unsigned n, void *user)
{
    (void)user;
    for (unsigned i = 0; i < n && i < 2; i++)
        ((tb__enode *)node)->child[i] = child[i];
}

static tb_aabb tb__e_box(const struct RTCBounds *b)
{
    return (tb_aabb){{b->lower_x, b->lower_y, b->lower_z}, {b->upper_x, b->upper_y, b->upper_z}};
}

static void tb__e_set_bounds(void *node, const struct RTCBounds **b, unsigned n, void *user)
{
    (void)user;
    for (unsigned i = 0; i < n && i < 2; i++)
        ((tb__enode *)node)->box[i] = tb__e_box(b[i]);
}

static void *tb__e_create_leaf(RTCThreadLocalAllocator alloc, const struct RTCBuildPrimitive *p, size_t n,
                               void *user)
{
    (void)user;
    tb__enode *e = rtcThreadLocalAlloc(alloc, sizeof *e, 16);
    memset(e, 0, sizeof *e);
    e->count = (unsigned)n;
    e->box[0] = tb_aabb_empty();
    for (size_t i = 0; i < n; i++)
        e->box[0] = tb_aabb_union(e->box[0], (tb_aabb){{p[i].lower_x, p[i].lower_y, p[i].lower_z},
                                                       {p[i].upper_x, p[i].upper_y, p[i].upper_z}});
    return e;
}

/* SAH sum of the subtree `e` whose box is `box` (our formula, unnormalised). */
static double tb__e_sah(const tb__enode *e, const tb_aabb *box)
{
    if (e->count)
        return e->count * tb__half_area(&e->box[0]);
    return tb__half_area(box) + tb__e_sah(e->child[0], &e->box[0]) + tb__e_sah(e->child[1], &e->box[1]);
}

static RTCDevice tb__e_device(int threads)
{
    char cfg[64];
    snprintf(cfg, sizeof cfg, "threads=%d", threads);
    RTCDevice d = rtcNewDevice(cfg);
    if (!d)
        fprintf(stderr, "testbed bench accel: rtcNewDevice(\"%s\") failed\n", cfg);
    return d;
}

/* Embree's triangle scene build at `quality` and `threads`, best of `repeat`. */
static bool tb__time_embree_scene(const tb_scene *s, enum RTCBuildQuality quality, int threads, int repeat,
                                  double *seconds)
{
    *seconds = INFINITY;
    RTCDevice d = tb__e_device(threads);
    if (!d)
        return false;
    bool ok = true;
    for (int r = 0; r < repeat && ok; r++) {
        double t0 = tb__now();
        RTCScene sc = rtcNewScene(d);
        rtcSetSceneBuildQuality(sc, quality);
        ok = tb_bench_embree_add_meshes(d, sc, s, quality, "testbed bench accel");
        if (ok)
            rtcCommitScene(sc);
        double t = tb__now() - t0;
        rtcReleaseScene(sc);
        *seconds = fmin(*seconds, t);
        if (ok && rtcGetDeviceError(d) != RTC_ERROR_NONE) {
            fprintf(stderr, "testbed bench accel: Embree failed to build the scene\n");
            ok = false;
        }
    }
    rtcReleaseDevice(d);
    return ok;
}

/* rtcBuildBVH over our references' boxes at `threads`, best of `repeat`; the SAH cost of its tree. */
static bool tb__time_embree_bvh(const tb_scene *s, int threads, int repeat, double *seconds, double *sah)
{
    *seconds = INFINITY;
    *sah = 0.0;
    size_t n = 0;
    struct RTCBuildPrimitive *in = malloc(sizeof *in * (s->nprims ? s->nprims : 1));
    struct RTCBuildPrimitive *work = malloc(sizeof *work * (s->nprims ? s->nprims : 1));
    RTCDevice d = in && work ? tb__e_device(threads) : NULL;
    if (!d) {
        free(in);
        free(work);
        if (!in || !work)
            fprintf(stderr, "testbed bench accel: out of memory\n");
        return false;
    }
    tb_accel_prim *refs;
    if (tb_scene_refs(s, &refs)) {
        fprintf(stderr, "testbed bench accel: %s\n", tb_last_error());
        free(in);
        free(work);
        rtcReleaseDevice(d);
        return false;
    }
    tb_aabb root = tb_aabb_empty();
    for (size_t i = 0; i < s->nprims; i++) {
        const tb_aabb *b = &refs[i].bounds;
        if (tb_aabb_is_empty(b)) /* tb_accel_build drops these too */
            continue;
        root = tb_aabb_union(root, *b);
        in[n++] = (struct RTCBuildPrimitive){b->lo.x, b->lo.y, b->lo.z, 0, b->hi.x, b->hi.y, b->hi.z, (unsigned)i};
    }
    free(refs);
    bool ok = true;
    for (int r = 0; r < repeat && ok; r++) {
        memcpy(work, in, sizeof *in * n); /* the builder reorders its input */
        RTCBVH bvh = rtcNewBVH(d);
        struct RTCBuildArguments a = rtcDefaultBuildArguments();
        a.byteSize = sizeof a;
        a.buildQuality = RTC_BUILD_QUALITY_HIGH;
        a.maxBranchingFactor = 2;
        a.maxDepth = 1024;
        a.sahBlockSize = 1;
        a.minLeafSize = 1;
        a.maxLeafSize = 8;
        a.traversalCost = 1.0f;
        a.intersectionCost = 1.0f;
        a.bvh = bvh;
        a.primitives = work;
        a.primitiveCount = n;
        a.primitiveArrayCapacity = n;
        a.createNode = tb__e_create_node;
        a.setNodeChildren = tb__e_set_children;
        a.setNodeBounds = tb__e_set_bounds;
        a.createLeaf = tb__e_create_leaf;
        double t0 = tb__now();
        tb__enode *top = n ? rtcBuildBVH(&a) : NULL;
        *seconds = fmin(*seconds, tb__now() - t0);
        if (n && !top) {
            fprintf(stderr, "testbed bench accel: rtcBuildBVH failed (error %d)\n", (int)rtcGetDeviceError(d));
            ok = false;
        } else if (top) {
            double ra = tb__half_area(&root);
            *sah = tb__e_sah(top, &root) / (ra > 0.0 ? ra : 1.0);
        }
        rtcReleaseBVH(bvh);
    }
    rtcReleaseDevice(d);
    free(in);
    free(work);
    return ok;
}
#endif

int tb_bench_accel_scene(const char *path, const long *threads, int nthreads, int repeat, bool embree)
{
    tb_scene *s;
    if (tb_scene_load(path, NULL, &s)) {
        fprintf(stderr, "testbed bench accel: %s\n", tb_last_error());
        return TB_EXIT_FAIL;
    }
    uint64_t tris = s->stats.triangles;
    double load[3];
    tb_cli_load_average(load);
    printf("scene %s: %llu triangles, %zu references; best of %d builds; load average %.2f\n", path,
           (unsigned long long)tris, s->nprims, repeat, load[0]);
    printf("ours: tb_scene_rebuild_accel (SAH of the binary tree); embree-high / embree-med: rtcCommitScene\n"
           "at RTC_BUILD_QUALITY_HIGH / MEDIUM (the default; time only); embree-bvh: rtcBuildBVH HIGH over the same boxes, binary,\n"
           "leaves <= 8, costs 1/1 (SAH by the same formula); Mtri/s = references / seconds; tree: a\n"
           "fingerprint of our tree (nodes and leaf order: equal for every thread count)\n");
    printf("%-12s %7s %10s %10s %14s %10s\n", "builder", "threads", "seconds", "Mtri/s", "Mtri/s/thread", "SAH");
    int rc = TB_EXIT_OK;
    double mref = (double)s->nprims * 1e-6;
    for (int ti = 0; ti < nthreads && rc == TB_EXIT_OK; ti++) {
        int th = (int)threads[ti];
        double t, sah;
        uint64_t hash;
        if (!tb__time_ours(s, th, repeat, &t, &sah, &hash)) {
            rc = TB_EXIT_FAIL;
            break;
        }
        printf("%-12s %7d %10.4f %10.3f %14.3f %10.3f  tree %016llx\n", "ours", th, t, mref / t, mref / t / th, sah,
               (unsigned long long)hash);
        fflush(stdout);
#ifdef TB_HAVE_EMBREE
        if (!embree)
            continue;
        double te, tm, tb, sahe;
        if (!tb__time_embree_scene(s, RTC_BUILD_QUALITY_HIGH, th, repeat, &te) ||
            !tb__time_embree_scene(s, RTC_BUILD_QUALITY_MEDIUM, th, repeat, &tm) ||
            !tb__time_embree_bvh(s, th, repeat, &tb, &sahe)) {
            rc = TB_EXIT_FAIL;
            break;
        }
        printf("%-12s %7d %10.4f %10.3f %14.3f %10s\n", "embree-high", th, te, mref / te, mref / te / th, "-");
        printf("%-12s %7d %10.4f %10.3f %14.3f %10s\n", "embree-med", th, tm, mref / tm, mref / tm / th, "-");
        printf("%-12s %7d %10.4f %10.3f %14.3f %10.3f\n", "embree-bvh", th, tb, mref / tb, mref / tb / th, sahe);
        printf("build %d threads: ours / embree-high time %.2f, speed %.2fx; speed vs embree-med %.2fx; "
               "SAH ours / embree-bvh %.4f\n",
               th, t / te, te / t, tm / t, sah / sahe);
        fflush(stdout);
#else
        (void)embree;
#endif
    }
    tb_scene_free(s);
    return rc;
}
