/* `testbed bench accel`: rays per second through the BVH, the uniform grid
 * and the plain list (brute force) of host/render/accel.h on synthetic
 * triangle scenes, with 1 and 2 threads (docs/performance.md,
 * "Acceleration"). A row of the benchmark table in cmd_bench.c.
 *
 * Scenes: "soup" (N random small triangles in [-1, 1]^3 whose total area,
 * about 10, does not depend on N) and "sphere" (a latitude/longitude sphere
 * of about N triangles over a two-triangle ground). Ray sets: "primary" (a
 * pinhole camera, coherent), "diffuse" (random origins in [-1, 1]^3, random
 * directions; closest hit) and "shadow" (segments between random points;
 * any hit). After timing, the answers of the three structures are compared
 * (the list only on the rays it traced): any difference is reported and
 * makes the command fail, so the benchmark doubles as a validator. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "commands.h"
#include "host/render/accel.h"
#include "util/math/float.h"
#include "util/math/rng.h"
#include "util/stats/stats.h"

/* A triangle as the callback wants it. */
typedef struct tb__btri {
    tb_vec3 v0, e1, e2; /* first vertex and the two edges from it */
} tb__btri;

typedef struct tb__bscene {
    const char *name;
    tb__btri *tris;
    tb_accel_prim *prims;
    size_t n;
} tb__bscene;

/* Moller-Trumbore in float: what a renderer's triangle callback does. */
static bool tb__btri_intersect(void *ctx, const tb_accel_prim *prim, uint32_t index, const tb_ray *r, tb_hit *hit)
{
    (void)prim;
    const tb__btri *t = &((const tb__bscene *)ctx)->tris[index];
    tb_vec3 p = tb_vec3_cross(r->d, t->e2);
    float det = tb_vec3_dot(t->e1, p);
    if (det == 0.0f)
        return false;
    float inv = 1.0f / det;
    tb_vec3 s = tb_vec3_sub(r->o, t->v0);
    float u = tb_vec3_dot(s, p) * inv;
    if (u < 0.0f || u > 1.0f)
        return false;
    tb_vec3 q = tb_vec3_cross(s, t->e1);
    float v = tb_vec3_dot(r->d, q) * inv;
    if (v < 0.0f || u + v > 1.0f)
        return false;
    float tt = tb_vec3_dot(t->e2, q) * inv;
    if (!(tt >= r->tmin && tt <= r->tmax))
        return false;
    hit->t = tt;
    hit->object = index;
    hit->face = 0;
    hit->u = u;
    hit->v = v;
    hit->ng = tb_vec3_normalize(tb_vec3_cross(t->e1, t->e2));
    return true;
}

static bool tb__btri_occluded(void *ctx, const tb_accel_prim *prim, uint32_t index, const tb_ray *r)
{
    tb_hit h;
    return tb__btri_intersect(ctx, prim, index, r, &h);
}

static void tb__bscene_add(tb__bscene *s, tb_vec3 a, tb_vec3 b, tb_vec3 c)
{
    size_t i = s->n++;
    s->tris[i] = (tb__btri){a, tb_vec3_sub(b, a), tb_vec3_sub(c, a)};
    tb_aabb box = tb_aabb_union_point(tb_aabb_from_points(a, b), c);
    /* The float test accepts points up to a few ulps outside the triangle:
     * widen the box by 1e-6 of the coordinates so that every point it
     * reports lies in the box (docs/accel.md, "Callback contract"). */
    tb_vec3 e = tb_vec3_scale(tb_vec3_add(tb_vec3_abs(box.lo), tb_vec3_abs(box.hi)), 1e-6f);
    box.lo = tb_vec3_sub(box.lo, e);
    box.hi = tb_vec3_add(box.hi, e);
    s->prims[i] = (tb_accel_prim){box, (uint32_t)i, 0};
}

static bool tb__bscene_alloc(tb__bscene *s, const char *name, size_t cap)
{
    s->name = name;
    s->n = 0;
    s->tris = malloc(cap * sizeof *s->tris);
    s->prims = malloc(cap * sizeof *s->prims);
    return s->tris && s->prims;
}

static float tb__buni(tb_rng *r, float lo, float hi) { return lo + (hi - lo) * tb_rng_float(r); }

/* N random triangles in [-1, 1]^3, edges about sqrt(8 / N) long. */
static bool tb__make_soup(tb__bscene *s, size_t n, tb_rng *r)
{
    if (!tb__bscene_alloc(s, "soup", n))
        return false;
    float size = sqrtf(8.0f / (float)n);
    for (size_t i = 0; i < n; i++) {
        tb_vec3 c = {tb__buni(r, -1, 1), tb__buni(r, -1, 1), tb__buni(r, -1, 1)};
        tb_vec3 v[3];
        for (int k = 0; k < 3; k++)
            v[k] = tb_vec3_add(c, (tb_vec3){tb__buni(r, -size, size), tb__buni(r, -size, size),
                                            tb__buni(r, -size, size)});
        tb__bscene_add(s, v[0], v[1], v[2]);
    }
    return true;
}

static tb_vec3 tb__sph(double t, double p)
{
    return (tb_vec3){(float)(sin(t) * cos(p)), (float)(sin(t) * sin(p)), (float)cos(t)};
}

/* A unit sphere in rings x 2 rings quads (about n triangles) over a ground square at z = -1. */
static bool tb__make_sphere(tb__bscene *s, size_t n)
{
    int rings = (int)sqrt((double)n / 4.0);
    if (rings < 2)
        rings = 2;
    int segs = 2 * rings;
    if (!tb__bscene_alloc(s, "sphere", (size_t)rings * (size_t)segs * 2 + 2))
        return false;
    for (int i = 0; i < rings; i++) {
        double t0 = TB_PI * i / rings, t1 = TB_PI * (i + 1) / rings;
        for (int j = 0; j < segs; j++) {
            double p0 = TB_2PI * j / segs, p1 = TB_2PI * (j + 1) / segs;
            tb_vec3 a = tb__sph(t0, p0), b = tb__sph(t1, p0), c = tb__sph(t1, p1), d = tb__sph(t0, p1);
            if (i > 0)
                tb__bscene_add(s, a, b, d);
            if (i < rings - 1)
                tb__bscene_add(s, b, c, d);
        }
    }
    tb__bscene_add(s, (tb_vec3){-4, -4, -1}, (tb_vec3){4, -4, -1}, (tb_vec3){4, 4, -1});
    tb__bscene_add(s, (tb_vec3){-4, -4, -1}, (tb_vec3){4, 4, -1}, (tb_vec3){-4, 4, -1});
    return true;
}

enum { TB__RAYS_PRIMARY, TB__RAYS_DIFFUSE, TB__RAYS_SHADOW, TB__NRAYSETS };
static const char *const tb__rayset_names[TB__NRAYSETS] = {"primary", "diffuse", "shadow"};

static tb_ray *tb__make_rays(int set, size_t n, tb_rng *r)
{
    tb_ray *rays = malloc(n * sizeof *rays);
    if (!rays)
        return NULL;
    size_t side = (size_t)ceil(sqrt((double)n));
    for (size_t i = 0; i < n; i++) {
        if (set == TB__RAYS_PRIMARY) {
            /* Camera at (0, -3, 0.5) looking along +y, 60 degree field, scanline order. */
            float x = ((float)(i % side) + 0.5f) / (float)side * 2 - 1;
            float y = ((float)(i / side) + 0.5f) / (float)side * 2 - 1;
            tb_vec3 d = tb_vec3_normalize((tb_vec3){x * 0.577f, 1.0f, -y * 0.577f - 0.15f});
            rays[i] = tb_ray_make((tb_vec3){0, -3, 0.5f}, d, 0, INFINITY);
            continue;
        }
        tb_vec3 o = {tb__buni(r, -1, 1), tb__buni(r, -1, 1), tb__buni(r, -1, 1)};
        if (set == TB__RAYS_DIFFUSE) {
            tb_vec3 d;
            do
                d = (tb_vec3){tb__buni(r, -1, 1), tb__buni(r, -1, 1), tb__buni(r, -1, 1)};
            while (tb_vec3_length(d) > 1.0f || tb_vec3_length(d) < 0.1f);
            rays[i] = tb_ray_make(o, tb_vec3_normalize(d), 0, INFINITY);
        } else {
            tb_vec3 p = {tb__buni(r, -1, 1), tb__buni(r, -1, 1), tb__buni(r, -1, 1)};
            rays[i] = tb_ray_make(o, tb_vec3_sub(p, o), 0, 1.0f);
        }
    }
    return rays;
}

static double tb__clock(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Traces rays[0..n) (closest or any hit) with `threads` threads; returns
 * wall seconds and (in *cpu) the process CPU seconds it took. */
static double tb__trace(const tb_accel *acc, const tb_ray *rays, size_t n, bool any, int threads, tb_hit *hits,
                        unsigned char *found, double *cpu)
{
    double c0 = tb__clock(CLOCK_PROCESS_CPUTIME_ID), w0 = tb__clock(CLOCK_MONOTONIC);
#pragma omp parallel for num_threads(threads) schedule(dynamic, 256)
    for (size_t i = 0; i < n; i++) {
        if (any)
            found[i] = tb_accel_occluded(acc, &rays[i]);
        else
            found[i] = tb_accel_intersect(acc, &rays[i], &hits[i]);
    }
    *cpu = tb__clock(CLOCK_PROCESS_CPUTIME_ID) - c0;
    return tb__clock(CLOCK_MONOTONIC) - w0;
}


/* Traversal steps (BVH nodes or grid voxels) and callback calls of each kind. */
static const char *const tb__step_counter[3] = {"BVH/nodes visited", "Grid/voxels visited", NULL};
static const char *const tb__test_counter[3] = {"BVH/primitives tested", "Grid/primitives tested",
                                                "List/primitives tested"};

/* A comma-separated list of whole numbers in [1, max]; returns the count or 0. */
static int tb__parse_list(const char *s, long max, long *out, int cap)
{
    int n = 0;
    while (s && *s) {
        if (n == cap || *s < '0' || *s > '9')
            return 0;
        errno = 0;
        char *end;
        long v = strtol(s, &end, 10);
        if (errno || v < 1 || v > max || (*end && *end != ','))
            return 0;
        out[n++] = v;
        s = *end == ',' ? end + 1 : NULL;
    }
    return n;
}

/* One scene: build the three structures, time every ray set, compare the
 * answers. Returns the number of differing answers, or -1 on failure. */
static long tb__bench_scene(tb__bscene *s, long nrays, const long *threads, int nthreads, uint64_t seed,
                            const bool use[3])
{
    tb_accel_callbacks cb = {tb__btri_intersect, tb__btri_occluded, s, NULL};
    tb_accel *acc[3] = {NULL, NULL, NULL};
    long bad = 0;
    for (int k = 0; k < 3; k++) {
        if (tb_accel_build((tb_accel_kind)k, s->prims, s->n, &cb, NULL, &acc[k])) {
            fprintf(stderr, "testbed bench accel: %s\n", tb_last_error());
            bad = -1;
            goto done;
        }
    }
    tb_accel_stats bs, gs;
    tb_accel_get_stats(acc[TB_ACCEL_BVH], &bs);
    tb_accel_get_stats(acc[TB_ACCEL_GRID], &gs);
    printf("# %s, %zu triangles: BVH %zu nodes (%zu 8-wide), depth %d, SAH cost %.2f, %.1f MiB, built in %.1f ms; "
           "grid %dx%dx%d, %zu refs, %.1f MiB, built in %.1f ms\n",
           s->name, s->n, bs.bvh_nodes, bs.bvh_wide_nodes, bs.bvh_depth, bs.bvh_sah_cost, (double)bs.memory_bytes / 1048576.0,
           bs.build_seconds * 1e3, gs.grid_res[0], gs.grid_res[1], gs.grid_res[2], gs.grid_refs,
           (double)gs.memory_bytes / 1048576.0, gs.build_seconds * 1e3);
    for (int set = 0; set < TB__NRAYSETS && bad >= 0; set++) {
        tb_rng rr;
        tb_rng_seed(&rr, seed, 100 + (uint64_t)set);
        size_t n = (size_t)nrays;
        tb_ray *rays = tb__make_rays(set, n, &rr);
        tb_hit *hits[3] = {NULL, NULL, NULL};
        unsigned char *found[3] = {NULL, NULL, NULL};
        size_t traced[3];
        bool ok = rays != NULL;
        for (int k = 0; k < 3 && ok; k++) {
            hits[k] = calloc(n, sizeof **hits);
            found[k] = calloc(n, 1);
            ok = hits[k] && found[k];
            /* Brute force costs n * N tests: it traces only the first 2e8 / N rays. */
            traced[k] = n;
            if (k == TB_ACCEL_LIST && (double)n * (double)s->n > 2e8)
                traced[k] = (size_t)fmax(1.0, 2e8 / (double)s->n);
        }
        if (!ok) {
            fprintf(stderr, "testbed bench accel: out of memory for %zu rays\n", n);
            bad = -1;
        }
        for (int k = 0; k < 3 && ok; k++) {
            for (int ti = 0; ti < nthreads && use[k]; ti++) {
                double cpu;
                int64_t steps0 = tb__step_counter[k] ? tb_stats_counter(tb__step_counter[k]) : 0;
                int64_t tests0 = tb_stats_counter(tb__test_counter[k]);
                double sec = tb__trace(acc[k], rays, traced[k], set == TB__RAYS_SHADOW, (int)threads[ti], hits[k],
                                       found[k], &cpu);
                double steps = (double)((tb__step_counter[k] ? tb_stats_counter(tb__step_counter[k]) : 0) - steps0);
                double tests = (double)(tb_stats_counter(tb__test_counter[k]) - tests0);
                size_t nh = 0;
                for (size_t i = 0; i < traced[k]; i++)
                    nh += found[k][i];
                double nr = (double)traced[k];
                printf("%-7s %8zu %-8s %-5s %7ld %9.4g %11.4g %7.1f %8.1f %8.1f\n", s->name, s->n,
                       tb__rayset_names[set], tb_accel_kind_name((tb_accel_kind)k), threads[ti], nr / sec * 1e-6,
                       nr / cpu * 1e-6, 100.0 * (double)nh / nr, steps / nr, tests / nr);
                fflush(stdout);
            }
        }
        /* Validation: the grid and the list answer as the BVH does. */
        for (int k = 1; k < 3 && ok && use[0]; k++) {
            if (!use[k])
                continue;
            for (size_t i = 0; i < traced[k]; i++) {
                bool diff = found[k][i] != found[0][i];
                if (!diff && found[0][i] && set != TB__RAYS_SHADOW)
                    diff = memcmp(&hits[k][i], &hits[0][i], sizeof(tb_hit)) != 0;
                if (diff) {
                    if (bad < 10)
                        fprintf(stderr, "testbed bench accel: %s %s ray %zu: %s and bvh differ\n", s->name,
                                tb__rayset_names[set], i, tb_accel_kind_name((tb_accel_kind)k));
                    bad++;
                }
            }
        }
        for (int k = 0; k < 3; k++) {
            free(hits[k]);
            free(found[k]);
        }
        free(rays);
    }
done:
    for (int k = 0; k < 3; k++)
        tb_accel_free(acc[k]);
    return bad;
}

/* A comma-separated list of whole numbers 1 .. max (TB_OPT_CUSTOM dest). */
typedef struct tb__blist {
    long *v;
    int n, cap;
    long max;
} tb__blist;

static int tb__parse_blist(const char *val, void *dest, char *why, size_t len)
{
    tb__blist *l = dest;
    int n = tb__parse_list(val, l->max, l->v, l->cap);
    if (!n) {
        snprintf(why, len, "expected up to %d numbers 1 .. %ld separated by commas, got '%s'", l->cap, l->max, val);
        return 1;
    }
    l->n = n;
    return 0;
}

/* --accel bvh,grid,list: which structures (TB_OPT_CUSTOM dest: bool[3]). */
static int tb__parse_kinds(const char *val, void *dest, char *why, size_t len)
{
    bool *use = dest, pick[3] = {false, false, false};
    char buf[64];
    snprintf(buf, sizeof buf, "%s", val);
    for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
        tb_accel_kind k;
        if (tb_accel_kind_from_name(tok, &k)) {
            snprintf(why, len, "%s", tb_last_error());
            return 1;
        }
        pick[k] = true;
    }
    memcpy(use, pick, sizeof pick);
    return 0;
}

int tb_cmd_bench_accel(int argc, char **argv)
{
    long sizes[8] = {1000, 100000}, threads[4] = {1, 2};
    int nrays_i = 200000, seed_i = 1;
    bool use[3] = {true, true, true}, no_stats = false, embree = false;
    const char *scene = NULL;
    int repeat = 3;
    tb__blist tris = {sizes, 2, 8, 100000000}, thr = {threads, 2, 4, 1024};
    const tb_opt opts[] = {
        {"tris", .type = TB_OPT_CUSTOM, .dest = &tris, .metavar = "N,...", .parse = tb__parse_blist,
         .help = "triangle soups and tessellated spheres of N triangles, up to 8 sizes\n"
                 "1 .. 10^8 (default 1000,100000)"},
        {"rays", .type = TB_OPT_INT, .dest = &nrays_i, .min = 1, .max = 100000000, .metavar = "N",
         .help = "rays per primary, diffuse and shadow set (default %D)"},
        {"threads", .type = TB_OPT_CUSTOM, .dest = &thr, .metavar = "T,...", .parse = tb__parse_blist,
         .help = "thread counts, up to 4 of 1 .. 1024 (default 1,2)"},
        {"accel", .type = TB_OPT_CUSTOM, .dest = use, .metavar = "K,...", .parse = tb__parse_kinds,
         .help = "the structures: bvh,grid,list (default all three)"},
        {"seed", .type = TB_OPT_INT, .dest = &seed_i, .min = 1, .max = 2147483647, .metavar = "S",
         .help = "random seed (default %D)"},
        {"no-stats", .type = TB_OPT_FLAG, .dest = &no_stats, .help = "turn the counters off"},
        {"scene", .type = TB_OPT_STRING, .dest = &scene, .metavar = "SCENE.mid",
         .help = "instead of the synthetic scenes: time the build of this scene's BVH\n"
                 "(tb_scene_rebuild_accel) at each --threads count, with its SAH cost"},
        {"embree", .type = TB_OPT_FLAG, .dest = &embree,
         .help = "with --scene: also Embree 3's builds at the same thread counts:\n"
                 "rtcCommitScene at RTC_BUILD_QUALITY_HIGH (time) and rtcBuildBVH\n"
                 "HIGH over the same boxes (time and SAH cost by the same formula)"},
        {"repeat", .type = TB_OPT_INT, .dest = &repeat, .min = 1, .max = 1000, .metavar = "R",
         .help = "with --scene: best of R builds each (default %D)"},
        {0},
    };
    const tb_cli cli = {
        .prog = "testbed bench accel",
        .err = "testbed bench accel: ",
        .usage = "[--tris N,...] [--rays N] [--threads T,...] [--accel K,...] [--seed S] [--no-stats]\n"
                 "       --scene SCENE.mid [--embree] [--threads T,...] [--repeat R] [--no-stats]",
        .intro = "\n"
                 "The BVH, the uniform grid and the plain list (host/render/accel.h) on triangle soups\n"
                 "and tessellated spheres: primary, diffuse and shadow ray sets; prints Mrays/s (wall\n"
                 "clock) and Mrays per CPU second, then checks that the structures gave the same\n"
                 "answers (exit status 1 if not).\n"
                 "With --scene: the build time (best of --repeat) and SAH cost of the scene's BVH at\n"
                 "each thread count, and with --embree Embree's (docs/performance.md, \"BVH build vs\n"
                 "Embree\").\n",
        .opts = opts,
    };
    int npos, prc = tb_cli_parse(&cli, argc, argv, &npos);
    if (prc != TB_CLI_OK)
        return prc;
    if (no_stats)
        tb_stats_set_enabled(0);
#ifndef TB_HAVE_EMBREE
    if (embree)
        return tb_cli_usage_error(&cli, "this testbed was built without Embree 3 (install libembree-dev and "
                                        "reconfigure); --embree is not available");
#endif
    if (embree && !scene)
        return tb_cli_usage_error(&cli, "--embree needs --scene");
    if (scene)
        return tb_bench_accel_scene(scene, threads, thr.n, repeat, embree);
    long nrays = nrays_i, seedv = seed_i;
    int nsizes = tris.n, nthreads = thr.n;
    printf("testbed bench accel: %ld rays per set; Mrays/s is wall-clock throughput, Mrays/CPU-s per second of\n"
           "process CPU time (equal to Mrays/s on an idle machine with one thread); steps are BVH nodes or\n"
           "grid voxels visited, tests are callback calls (0 with --no-stats)\n\n",
           nrays);
    printf("%-7s %8s %-8s %-5s %7s %9s %11s %7s %8s %8s\n", "scene", "tris", "rays", "accel", "threads", "Mrays/s",
           "Mrays/CPU-s", "hits %", "steps/ray", "tests/ray");
    long bad = 0;
    for (int si = 0; si < nsizes && bad >= 0; si++) {
        for (int sc = 0; sc < 2 && bad >= 0; sc++) {
            tb_rng r;
            /* The scene depends on its size, not on its place in the list. */
            tb_rng_seed(&r, (uint64_t)seedv, (uint64_t)sizes[si]);
            tb__bscene s = {0};
            bool ok = sc == 0 ? tb__make_soup(&s, (size_t)sizes[si], &r) : tb__make_sphere(&s, (size_t)sizes[si]);
            long b = -1;
            if (ok)
                b = tb__bench_scene(&s, nrays, threads, nthreads, (uint64_t)seedv, use);
            else
                fprintf(stderr, "testbed bench accel: out of memory for %ld triangles\n", sizes[si]);
            bad = b < 0 ? -1 : bad + b;
            free(s.tris);
            free(s.prims);
        }
    }
    if (bad < 0)
        return TB_EXIT_FAIL;
    if (bad) {
        fprintf(stderr, "testbed bench accel: %ld answers differ between the structures\n", bad);
        return TB_EXIT_FAIL;
    }
    return TB_EXIT_OK;
}
