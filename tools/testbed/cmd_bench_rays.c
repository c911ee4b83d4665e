/* `testbed bench rays SCENE.mid [--embree]`: rays per second of the scene's
 * acceleration structure (the CPU path: tb_scene_intersect / _occluded)
 * and, when built with Embree 3 (TB_HAVE_EMBREE), of Embree's single-ray API
 * on the same rays, with the agreement between the two (docs/performance.md,
 * "Rays: BVH vs Embree"). A row of the benchmark table in cmd_bench.c.
 *
 * Ray sets, made once from the scene and traced by both:
 *   primary  the scene camera's rays: every pixel centre, or N random film
 *            points with --rays N (closest hit);
 *   shadow   one per primary hit, from the spawned hit point
 *            (tb_spawn_ray_origin) to a point sampled on the area lights
 *            (tb_area_light_sample) or, with no emitters, on a light chosen
 *            at random (tb_light_sample_li); occlusion (any hit);
 *   diffuse  one per primary hit, cosine-distributed about the geometric
 *            normal on the side the camera ray came from (closest hit).
 *
 * In Embree every polygons object is one RTC_GEOMETRY_TYPE_TRIANGLE geometry
 * (world-space float vertices, geometry ID = object index, primitive ID =
 * triangle of obj->mesh) and every other object (analytic or CSG) a
 * one-primitive user geometry whose callbacks call tb_object_intersect /
 * tb_object_occluded, exactly the test our structure's leaves make. */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_embree.h"
#include "bench_raysets.h"
#include "cli_util.h"
#include "commands.h"
#include "host/object/hit.h"
#include "host/object/intersect.h"
#include "host/render/lights.h"
#include "host/render/scene.h"
#include "util/math/rng.h"
#include "util/stats/stats.h"

#ifdef TB_HAVE_EMBREE
#include <embree3/rtcore.h>
#endif

enum { TB__SET_PRIMARY, TB__SET_SHADOW, TB__SET_DIFFUSE, TB__NSETS };
static const char *const tb__set_names[TB__NSETS] = {"primary", "shadow", "diffuse"};

/* One answer, reduced to what the agreement check compares. */
typedef struct tb__answer {
    float t;         /* closest-hit t (0 for occlusion sets) */
    uint32_t object; /* UINT32_MAX: miss */
    uint32_t face;   /* face ID on that object */
} tb__answer;

typedef struct tb__rayset {
    tb_ray *rays;
    size_t n;
} tb__rayset;

static double tb__clock(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double tb__wall(void) { return tb__clock(CLOCK_MONOTONIC); }

/* This thread's CPU seconds. The tracing threads' CPU time is summed: on a
 * loaded (shared) machine rays per CPU second are the steadier figure
 * (wall-clock rates and scaling need an idle machine), and the process's CPU
 * time would also count Embree's idle TBB workers spinning after a build. */
static double tb__cpu(void) { return tb__clock(CLOCK_THREAD_CPUTIME_ID); }

/* ------------------------------------------------------------ our BVH */

/* Traces set `k` through the scene with `threads` threads; answers into out (may be NULL). Wall seconds. */
static double tb__trace_ours(const tb_scene *s, const tb__rayset *rs, int k, int threads, int passes,
                             tb__answer *out, double *cpu)
{
    double cpu_sum = 0.0, t0 = tb__wall();
    long n = (long)rs->n;
#pragma omp parallel num_threads(threads) reduction(+ : cpu_sum)
    {
    double c0 = tb__cpu();
    /* The passes without a barrier between them (nowait): a thread done
     * with its chunks of one pass takes chunks of the next. */
    for (int pass = 0; pass < passes; pass++)
#pragma omp for schedule(dynamic, 1024) nowait
    for (long i = 0; i < n; i++) {
        tb__answer a = {0.0f, UINT32_MAX, 0};
        if (k == TB__SET_SHADOW) {
            if (tb_scene_occluded(s, &rs->rays[i]))
                a.object = 0;
        } else {
            tb_hit h;
            if (tb_scene_intersect(s, &rs->rays[i], &h))
                a = (tb__answer){h.t, h.object, h.face};
        }
        if (out && pass == 0)
            out[i] = a;
    }
    cpu_sum += tb__cpu() - c0;
    }
    *cpu = cpu_sum;
    return tb__wall() - t0;
}

/* ------------------------------------------------------------ Embree */

#ifdef TB_HAVE_EMBREE
/* The intersect context handed to user geometries: Embree's, followed by the
 * face ID of the last user-geometry hit (the RTCHit has no room for it). */
typedef struct tb__ectx {
    struct RTCIntersectContext rtc; /* must be first */
    uint32_t face;           /* face of the closest user-geometry hit so far */
} tb__ectx;

typedef struct tb__embree {
    RTCDevice dev;
    RTCScene scene;
    const tb_scene *s;
    tb_accel_prim *refs; /* the scene's references (tb_scene_refs), user data of the geometries */
} tb__embree;

static void tb__user_bounds(const struct RTCBoundsFunctionArguments *args)
{
    const tb_accel_prim *p = args->geometryUserPtr;
    args->bounds_o->lower_x = p->bounds.lo.x, args->bounds_o->lower_y = p->bounds.lo.y;
    args->bounds_o->lower_z = p->bounds.lo.z;
    args->bounds_o->upper_x = p->bounds.hi.x, args->bounds_o->upper_y = p->bounds.hi.y;
    args->bounds_o->upper_z = p->bounds.hi.z;
}

static const tb_scene *tb__user_scene; /* set before any trace; read-only during traces */

static void tb__user_intersect(const struct RTCIntersectFunctionNArguments *args)
{
    if (!args->valid[0])
        return;
    const tb_accel_prim *p = args->geometryUserPtr;
    struct RTCRayHit *rh = (struct RTCRayHit *)args->rayhit; /* N == 1: the single-ray API */
    tb_ray r = tb_ray_make((tb_vec3){rh->ray.org_x, rh->ray.org_y, rh->ray.org_z},
                           (tb_vec3){rh->ray.dir_x, rh->ray.dir_y, rh->ray.dir_z}, rh->ray.tnear, rh->ray.tfar);
    tb_hit h;
    if (!tb_object_intersect(tb__user_scene->objects[p->object], &r, &h))
        return;
    rh->ray.tfar = h.t;
    rh->hit.u = h.u, rh->hit.v = h.v;
    rh->hit.Ng_x = h.ng.x, rh->hit.Ng_y = h.ng.y, rh->hit.Ng_z = h.ng.z;
    rh->hit.geomID = args->geomID;
    rh->hit.primID = args->primID;
    rh->hit.instID[0] = args->context->instID[0];
    ((tb__ectx *)args->context)->face = h.face;
}

static void tb__user_occluded(const struct RTCOccludedFunctionNArguments *args)
{
    if (!args->valid[0])
        return;
    const tb_accel_prim *p = args->geometryUserPtr;
    struct RTCRay *ray = (struct RTCRay *)args->ray;
    tb_ray r = tb_ray_make((tb_vec3){ray->org_x, ray->org_y, ray->org_z},
                           (tb_vec3){ray->dir_x, ray->dir_y, ray->dir_z}, ray->tnear, ray->tfar);
    if (tb_object_occluded(tb__user_scene->objects[p->object], &r))
        ray->tfar = -INFINITY;
}

/* Builds the Embree scene of `s`; 0 on failure (message printed). *user_objects counts user geometries. */
static int tb__embree_build(const tb_scene *s, tb__embree *e, bool robust, const char *config,
                            size_t *user_objects, double *build_seconds)
{
    *user_objects = 0;
    e->s = s;
    tb__user_scene = s;
    e->dev = rtcNewDevice(config);
    if (!e->dev) {
        fprintf(stderr, "testbed bench rays: rtcNewDevice(\"%s\") failed (error %d)\n", config,
                (int)rtcGetDeviceError(NULL));
        return 0;
    }
    double t0 = tb__wall();
    e->scene = rtcNewScene(e->dev);
    /* Robust mode: Embree's watertight traversal and triangle test (the
     * guarantee ours always gives), at its own cost. */
    if (robust)
        rtcSetSceneFlags(e->scene, RTC_SCENE_FLAG_ROBUST);
    /* The user geometries' boxes: the scene's whole-object references. */
    if (tb_scene_refs(s, &e->refs)) {
        fprintf(stderr, "testbed bench rays: %s\n", tb_last_error());
        return 0;
    }
    for (size_t i = 0; i < s->nprims; i++) {
        const tb_accel_prim *p = &e->refs[i];
        if (p->sub != TB_SCENE_WHOLE_OBJECT)
            continue;
        RTCGeometry g = rtcNewGeometry(e->dev, RTC_GEOMETRY_TYPE_USER);
        rtcSetGeometryUserPrimitiveCount(g, 1);
        rtcSetGeometryUserData(g, (void *)p);
        rtcSetGeometryBoundsFunction(g, tb__user_bounds, NULL);
        rtcSetGeometryIntersectFunction(g, tb__user_intersect);
        rtcSetGeometryOccludedFunction(g, tb__user_occluded);
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(e->scene, g, p->object);
        rtcReleaseGeometry(g);
        (*user_objects)++;
    }
    if (!tb_bench_embree_add_meshes(e->dev, e->scene, s, RTC_BUILD_QUALITY_MEDIUM, "testbed bench rays"))
        return 0;
    rtcCommitScene(e->scene);
    *build_seconds = tb__wall() - t0;
    enum RTCError err = rtcGetDeviceError(e->dev);
    if (err != RTC_ERROR_NONE) {
        fprintf(stderr, "testbed bench rays: Embree error %d while building the scene\n", (int)err);
        return 0;
    }
    return 1;
}

static void tb__embree_free(tb__embree *e)
{
    if (e->scene)
        rtcReleaseScene(e->scene);
    if (e->dev)
        rtcReleaseDevice(e->dev);
    free(e->refs);
    e->refs = NULL;
}

static double tb__trace_embree(const tb__embree *e, const tb__rayset *rs, int k, int threads, int passes,
                               tb__answer *out, double *cpu)
{
    double cpu_sum = 0.0, t0 = tb__wall();
    long n = (long)rs->n;
#pragma omp parallel num_threads(threads) reduction(+ : cpu_sum)
    {
    double c0 = tb__cpu();
    for (int pass = 0; pass < passes; pass++)
#pragma omp for schedule(dynamic, 1024) nowait
    for (long i = 0; i < n; i++) {
        const tb_ray *r = &rs->rays[i];
        tb__ectx ctx;
        rtcInitIntersectContext(&ctx.rtc);
        ctx.face = 0;
        tb__answer a = {0.0f, UINT32_MAX, 0};
        if (k == TB__SET_SHADOW) {
            struct RTCRay ray = {.org_x = r->o.x, .org_y = r->o.y, .org_z = r->o.z, .tnear = r->tmin,
                          .dir_x = r->d.x, .dir_y = r->d.y, .dir_z = r->d.z, .time = 0.0f,
                          .tfar = r->tmax, .mask = UINT32_MAX, .id = 0, .flags = 0};
            rtcOccluded1(e->scene, &ctx.rtc, &ray);
            if (ray.tfar < 0.0f)
                a.object = 0;
        } else {
            struct RTCRayHit rh;
            rh.ray = (struct RTCRay){.org_x = r->o.x, .org_y = r->o.y, .org_z = r->o.z, .tnear = r->tmin,
                              .dir_x = r->d.x, .dir_y = r->d.y, .dir_z = r->d.z, .time = 0.0f,
                              .tfar = r->tmax, .mask = UINT32_MAX, .id = 0, .flags = 0};
            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(e->scene, &ctx.rtc, &rh);
            if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
                const tb_object *obj = e->s->objects[rh.hit.geomID];
                uint32_t face = obj->mesh ? obj->mesh->tri_face[rh.hit.primID] : ctx.face;
                a = (tb__answer){rh.ray.tfar, rh.hit.geomID, face};
            }
        }
        if (out && pass == 0)
            out[i] = a;
    }
    cpu_sum += tb__cpu() - c0;
    }
    *cpu = cpu_sum;
    return tb__wall() - t0;
}
#endif /* TB_HAVE_EMBREE */

/* ------------------------------------------------------------ ray sets */

/* Makes the three ray sets; 0 on failure (message printed). */
static int tb__make_sets(const tb_scene *s, uint64_t nprimary, uint64_t seed, tb__rayset sets[TB__NSETS])
{
    const tb_camera *c = &s->camera;
    size_t np = nprimary ? (size_t)nprimary : (size_t)c->width * (size_t)c->height;
    for (int k = 0; k < TB__NSETS; k++) {
        sets[k].rays = malloc(sizeof(tb_ray) * np);
        sets[k].n = 0;
        if (!sets[k].rays) {
            fprintf(stderr, "testbed bench rays: out of memory for %zu rays\n", np);
            return 0;
        }
    }
    tb_rng rng;
    tb_rng_seed(&rng, seed, 0);
    for (size_t i = 0; i < np; i++) {
        double x, y;
        if (nprimary)
            x = c->width * (double)tb_rng_float(&rng), y = c->height * (double)tb_rng_float(&rng);
        else
            x = (double)(i % (size_t)c->width) + 0.5, y = (double)(i / (size_t)c->width) + 0.5;
        sets[TB__SET_PRIMARY].rays[sets[TB__SET_PRIMARY].n++] = tb_camera_ray(c, x, y, 0.5f, 0.5f);
    }
    tb_area_light area = {0};
    bool use_area = s->nemitters > 0;
    if (use_area && tb_area_light_init(&area, s->emitters, s->nemitters)) {
        printf("  (area lights unusable for shadow rays: %s; using the other lights)\n", tb_last_error());
        use_area = false;
    }
    size_t no_shadow = tb_bench_secondary_rays(s, use_area ? &area : NULL, sets[TB__SET_PRIMARY].rays, np, &rng,
                                               sets[TB__SET_SHADOW].rays, &sets[TB__SET_SHADOW].n,
                                               sets[TB__SET_DIFFUSE].rays, &sets[TB__SET_DIFFUSE].n);
    tb_area_light_release(&area);
    if (no_shadow)
        printf("  (%zu primary hits gave no shadow ray: behind a one-sided emitter or outside a spot cone)\n",
               no_shadow);
    return 1;
}


/* ------------------------------------------------------------ options */

/* Most thread counts --threads takes. */
#define TB__MAX_THREAD_COUNTS 8

/* --threads T,...: the thread counts of the timed runs (TB_OPT_CUSTOM dest). */
typedef struct tb__thread_counts {
    int v[TB__MAX_THREAD_COUNTS];
    int n;
} tb__thread_counts;

/* "1,2": up to 8 counts in 1 .. 256. Empty items are skipped ("1,,2" is 1,2),
 * as the strtok-based parser this one replaced did. */
static int tb__parse_threads(const char *val, void *dest, char *why, size_t why_len)
{
    tb__thread_counts tc = {.n = 0};
    bool bad = false;
    for (const char *p = val; *p && !bad;) {
        size_t len = strcspn(p, ","), i = 0;
        if (len > 0) {
            long v = 0;
            while (i < len && p[i] >= '0' && p[i] <= '9' && v <= 256) /* the bound keeps v from overflowing */
                v = 10 * v + (p[i++] - '0');
            bad = i < len || v < 1 || v > 256 || tc.n == TB__MAX_THREAD_COUNTS;
            if (!bad)
                tc.v[tc.n++] = (int)v;
        }
        p += len;
        p += *p == ',';
    }
    if (bad || tc.n == 0) {
        snprintf(why, why_len, "expected up to %d comma-separated thread counts in [1, 256], got '%s'",
                 TB__MAX_THREAD_COUNTS, val);
        return 1;
    }
    *(tb__thread_counts *)dest = tc;
    return 0;
}

/* What the command line asked for. */
typedef struct tb__rays_args {
    const char *path;
    bool embree, robust, no_stats;
    const char *embree_config; /* NULL: not given */
    int nrays;                 /* random primary rays; 0: one per pixel */
    uint64_t seed;
    int repeat;                /* timed rounds */
    double min_time;           /* seconds our single-thread run should last at least */
    tb__thread_counts threads;
} tb__rays_args;

/* Fills *a from argv; TB_CLI_OK, or the exit status to return now. */
static int tb__rays_parse(int argc, char **argv, tb__rays_args *a)
{
    *a = (tb__rays_args){.seed = 1, .repeat = 3, .min_time = 0.1, .threads = {{1, 2}, 2}};
    const tb_opt opts[] = {
        {"embree", .type = TB_OPT_FLAG, .dest = &a->embree,
         .help = "also trace with Embree (needs a build configured with Embree 3)"},
        {"embree-robust", .type = TB_OPT_FLAG, .dest = &a->robust,
         .help = "the same with Embree's robust mode (RTC_SCENE_FLAG_ROBUST: watertight\n"
                 "traversal and triangle test, as ours always is)"},
        {"embree-config", .type = TB_OPT_STRING, .dest = &a->embree_config, .metavar = "CFG",
         .help = "Embree's device configuration string (rtcNewDevice), e.g.\n"
                 "'max_isa=sse2' to compare at the instruction set ours is built for\n"
                 "(by default Embree picks the widest the CPU has: AVX2 or AVX-512);\n"
                 "'threads=1' is added unless CFG sets threads (the build's worker\n"
                 "threads would otherwise disturb the timed runs; tracing never uses them)"},
        {"rays", .type = TB_OPT_INT, .dest = &a->nrays, .min = 1, .max = 1 << 28, .metavar = "N",
         .flags = TB_OPTF_NO_SIGN,
         .help = "N random camera rays, 1 .. 2^28 (default: one per pixel at the file's\n"
                 "resolution)"},
        {"threads", .type = TB_OPT_CUSTOM, .dest = &a->threads, .metavar = "T,...", .parse = tb__parse_threads,
         .help = "comma-separated thread counts, up to 8 of 1 .. 256 (default 1,2)"},
        {"seed", .type = TB_OPT_UINT64, .dest = &a->seed, .metavar = "S", .help = "random seed (default %D)"},
        {"min-time", .type = TB_OPT_DOUBLE, .dest = &a->min_time, .min = 0.0, .max = 60.0, .metavar = "S",
         .help = "each timed run traces the set as many times as makes our single-thread\n"
                 "run last S seconds, 0 .. 60 (default %D; 0: once): thread start-up and\n"
                 "the last chunk's imbalance then weigh little in the scaling"},
        {"repeat", .type = TB_OPT_INT, .dest = &a->repeat, .min = 1, .max = 100, .metavar = "R",
         .flags = TB_OPTF_NO_SIGN,
         .help = "timed rounds, 1 .. 100, best kept per measurement (default %D); each\n"
                 "round runs every thread count, ours and Embree (who goes first\n"
                 "alternates by round), so a short disturbance spoils one round of each,\n"
                 "not every repeat of one"},
        {"no-stats", .type = TB_OPT_FLAG, .dest = &a->no_stats,
         .help = "turn the statistics counters (util/stats) off while tracing"},
        {0},
    };
    const tb_cli cli = {
        .prog = "testbed bench rays",
        .err = "testbed bench rays: ",
        .usage = "SCENE.mid [--embree | --embree-robust] [--embree-config CFG]\n"
                 "                                    [--rays N] [--threads T,...] [--seed S] [--repeat R]\n"
                 "                                    [--min-time S] [--no-stats]",
        .intro = "\n"
                 "Primary (the scene camera), shadow (primary hit to a point on a light, any hit) and\n"
                 "diffuse (cosine bounce from primary hits, closest hit) rays through the scene's BVH\n"
                 "and, with --embree, through Embree 3's single-ray API on the same rays (triangles as\n"
                 "triangle geometries, other objects as user geometries calling tb_object_intersect).\n"
                 "Prints Mrays/s (wall clock) and Mrays per CPU second of the tracing threads (best of\n"
                 "R runs each) per set and thread count, the ratios ours / Embree, the scaling from\n"
                 "the first to the last thread count, and the fraction of rays on which the two\n"
                 "disagree (hit/miss, object or face).\n",
        .opts = opts,
        .outro = "\nExit status: 0 done, 1 the scene could not be loaded or Embree failed, 2 usage error.",
        .pos = &a->path,
        .max_pos = 1,
        .min_pos = 1,
        .missing = "no SCENE.mid given",
    };
    int npos, rc = tb_cli_parse(&cli, argc, argv, &npos);
    if (rc != TB_CLI_OK)
        return rc;
    a->embree |= a->robust;
    if (a->embree_config && !a->embree)
        return tb_cli_usage_error(&cli, "--embree-config needs --embree or --embree-robust");
#ifndef TB_HAVE_EMBREE
    if (a->embree)
        return tb_cli_usage_error(&cli, "this testbed was built without Embree 3 (install libembree-dev and "
                                        "reconfigure); %s is not available",
                                  a->robust ? "--embree-robust" : "--embree");
#endif
    return TB_CLI_OK;
}

/* ------------------------------------------------------------ the run */

/* Everything a run makes, freed by tb__rays_run_free. */
typedef struct tb__rays_run {
    tb_scene *s;
    tb__rayset sets[TB__NSETS];
    tb__answer *ours, *theirs; /* answers of the first timed run of a set (round 0, first thread count) */
    bool embree;               /* Embree traces too */
#ifdef TB_HAVE_EMBREE
    tb__embree e;
#endif
} tb__rays_run;

static void tb__rays_run_free(tb__rays_run *run)
{
#ifdef TB_HAVE_EMBREE
    tb__embree_free(&run->e);
#endif
    free(run->ours);
    free(run->theirs);
    for (int k = 0; k < TB__NSETS; k++)
        free(run->sets[k].rays);
    if (run->s)
        tb_scene_free(run->s);
}

/* Loads the scene and prints its summary; false on failure (message printed). */
static bool tb__rays_load(const tb__rays_args *a, tb__rays_run *run)
{
    if (tb_scene_load(a->path, NULL, &run->s)) {
        run->s = NULL;
        fprintf(stderr, "testbed bench rays: %s\n", tb_last_error());
        return false;
    }
    const tb_scene *s = run->s;
    size_t user_objects = 0;
    for (uint32_t o = 0; o < s->nobjects; o++)
        user_objects += !s->objects[o]->mesh;
    printf("scene %s: %u objects (%zu non-mesh), %" PRIu64 " triangles, %d emitters, %d lights; BVH built in %.3f s\n",
           a->path, s->nobjects, user_objects, s->stats.triangles, s->nemitters, s->nlights, s->stats.accel_seconds);
    if (a->embree && user_objects)
        printf("  non-mesh objects go to Embree as user geometry calling tb_object_intersect (not Embree's own code)\n");
    return true;
}

#ifdef TB_HAVE_EMBREE
/* Builds Embree's scene and prints how; false on failure (message printed). */
static bool tb__rays_build_embree(const tb__rays_args *a, tb__rays_run *run)
{
    /* One build thread unless the configuration says otherwise: Embree's
     * tasking worker threads outlive the build (sleeping, waking now and
     * then) and cost the two-thread runs of both tracers 3-10 % on a 2-core
     * machine; rtcIntersect1 / rtcOccluded1 run on the caller's thread and
     * never use them (docs/performance.md, "Rays: BVH vs Embree"). */
    const char *user = a->embree_config;
    char cfg[512];
    if (user && strstr(user, "threads="))
        snprintf(cfg, sizeof cfg, "%s", user);
    else
        snprintf(cfg, sizeof cfg, "%s%sthreads=1", user ? user : "", user && *user ? "," : "");
    size_t nu;
    double bs;
    if (!tb__embree_build(run->s, &run->e, a->robust, cfg, &nu, &bs))
        return false;
    printf("Embree %d.%d.%d scene built in %.3f s (%zu user geometries%s, device config %s)\n", RTC_VERSION_MAJOR,
           RTC_VERSION_MINOR, RTC_VERSION_PATCH, bs, nu, a->robust ? ", RTC_SCENE_FLAG_ROBUST" : "", cfg);
    return true;
}
#endif

/* Makes the ray sets, room for the answers and (with --embree) Embree's
 * scene; false on failure (message printed). */
static bool tb__rays_build(const tb__rays_args *a, tb__rays_run *run)
{
    if (!tb__make_sets(run->s, (uint64_t)a->nrays, a->seed, run->sets))
        return false;
    size_t maxn = run->sets[TB__SET_PRIMARY].n; /* shadow and diffuse sets are never larger */
    run->ours = malloc(sizeof *run->ours * (maxn ? maxn : 1));
    run->theirs = malloc(sizeof *run->theirs * (maxn ? maxn : 1));
    if (!run->ours || !run->theirs) {
        fprintf(stderr, "testbed bench rays: out of memory\n");
        return false;
    }
#ifdef TB_HAVE_EMBREE
    if (a->embree && !tb__rays_build_embree(a, run))
        return false;
#endif
    return true;
}

/* The load average (rates mean little on a busy machine) and the table's head. */
static void tb__print_table_head(void)
{
    double load[3];
    tb_cli_load_average(load);
    printf("load average %.2f: wall-clock rates and scaling mean something only on an idle machine; rates per\n"
           "CPU second (Mrays/CPU-s) are the steadier comparison on a shared one\n",
           load[0]);
    printf("%-8s %8s %6s %3s %12s %12s %7s %12s %12s %7s\n", "set", "rays", "hit%", "thr", "ours Mr/s", "Embree Mr/s",
           "ratio", "ours Mr/CPUs", "Emb Mr/CPUs", "ratio");
}

/* ------------------------------------------------------------ one ray set */

/* The timings of one set: the best of the rounds per thread count and tracer. */
typedef struct tb__set_times {
    int passes; /* traces of the set per timed run */
    double wall_ours[TB__MAX_THREAD_COUNTS], cpu_ours[TB__MAX_THREAD_COUNTS];
    double wall_em[TB__MAX_THREAD_COUNTS], cpu_em[TB__MAX_THREAD_COUNTS];
    double nodes, tests; /* our BVH per ray (0 with --no-stats) */
} tb__set_times;

/* Passes per timed run: a set of ~200 000 rays takes 15-40 ms, of which
 * waking the threads and the last chunk's imbalance are a few %, enough to
 * move the scaling figure; every timed run traces the set `passes` times
 * (the same number for both tracers and every thread count), so that our
 * single-thread run lasts at least --min-time. */
static int tb__passes(const tb_scene *s, const tb__rayset *rs, int k, double min_time)
{
    double c, t = tb__trace_ours(s, rs, k, 1, 1, NULL, &c);
    return t > 0.0 && t < min_time ? (int)fmin(1000.0, ceil(min_time / t)) : 1;
}

/* Times set k. Repeats interleaved: each round runs every thread count, both
 * tracers, so a disturbance of a few milliseconds (a short set takes ~10 ms)
 * costs one round of each measurement, not all the repeats of one of them;
 * the best of the rounds is kept per measurement. Who goes first alternates
 * by round: the first run at a thread count finds the extra cores idle (a
 * vCPU the host has descheduled, a clock that has dropped), the second finds
 * them warm, and a fixed order gave the second tracer a few % more scaling.
 * The first run of each tracer keeps its answers in run->ours / ->theirs. */
static void tb__time_set(const tb__rays_args *a, const tb__rays_run *run, int k, tb__set_times *tm)
{
    const tb__rayset *rs = &run->sets[k];
    const tb__thread_counts *th = &a->threads;
    tm->passes = tb__passes(run->s, rs, k, a->min_time);
    tm->nodes = tm->tests = 0.0;
    for (int ti = 0; ti < th->n; ti++)
        tm->wall_ours[ti] = tm->cpu_ours[ti] = tm->wall_em[ti] = tm->cpu_em[ti] = INFINITY;
    double traced = (double)rs->n * tm->passes;
    for (int r = 0; r < a->repeat; r++)
        for (int ti = 0; ti < th->n; ti++)
            for (int turn = 0; turn < 2; turn++) {
                double c, t;
                bool first = ti == 0 && r == 0;
                bool theirs_now = (turn == 0) == (r % 2 == 1);
                if (!theirs_now) {
                    int64_t nodes0 = tb_stats_counter("BVH/nodes visited");
                    int64_t tests0 = tb_stats_counter("BVH/primitives tested");
                    t = tb__trace_ours(run->s, rs, k, th->v[ti], tm->passes, first ? run->ours : NULL, &c);
                    if (first) {
                        tm->nodes = (double)(tb_stats_counter("BVH/nodes visited") - nodes0) / traced;
                        tm->tests = (double)(tb_stats_counter("BVH/primitives tested") - tests0) / traced;
                    }
                    tm->wall_ours[ti] = fmin(t, tm->wall_ours[ti]);
                    tm->cpu_ours[ti] = fmin(c, tm->cpu_ours[ti]);
                }
#ifdef TB_HAVE_EMBREE
                else if (run->embree) {
                    t = tb__trace_embree(&run->e, rs, k, th->v[ti], tm->passes, first ? run->theirs : NULL, &c);
                    tm->wall_em[ti] = fmin(t, tm->wall_em[ti]);
                    tm->cpu_em[ti] = fmin(c, tm->cpu_em[ti]);
                }
#endif
            }
}

/* Prints set k's rows (one per thread count) and its notes: BVH work per
 * ray, passes, scaling and, with Embree, the agreement of the two tracers. */
static void tb__report_set(const tb__rays_args *a, const tb__rays_run *run, int k, const tb__set_times *tm)
{
    const tb__rayset *rs = &run->sets[k];
    const tb__thread_counts *th = &a->threads;
    const char *name = tb__set_names[k];
    size_t hits = 0, differ = 0;
    for (size_t i = 0; i < rs->n; i++) {
        hits += run->ours[i].object != UINT32_MAX;
        differ += run->embree &&
                  (run->ours[i].object != run->theirs[i].object || run->ours[i].face != run->theirs[i].face);
    }
    double traced = (double)rs->n * tm->passes, hit_pct = 100.0 * (double)hits / (double)rs->n;
    double rate_ours[TB__MAX_THREAD_COUNTS] = {0}, rate_em[TB__MAX_THREAD_COUNTS] = {0};
    for (int ti = 0; ti < th->n; ti++) {
        rate_ours[ti] = traced / tm->wall_ours[ti] * 1e-6;
        double cpu_ours = traced / tm->cpu_ours[ti] * 1e-6;
        if (run->embree) {
            rate_em[ti] = traced / tm->wall_em[ti] * 1e-6;
            double cpu_em = traced / tm->cpu_em[ti] * 1e-6;
            printf("%-8s %8zu %6.1f %3d %12.3f %12.3f %7.2f %12.3f %12.3f %7.2f\n", name, rs->n, hit_pct, th->v[ti],
                   rate_ours[ti], rate_em[ti], rate_ours[ti] / rate_em[ti], cpu_ours, cpu_em, cpu_ours / cpu_em);
        } else {
            printf("%-8s %8zu %6.1f %3d %12.3f %12s %7s %12.3f %12s %7s\n", name, rs->n, hit_pct, th->v[ti],
                   rate_ours[ti], "-", "-", cpu_ours, "-", "-");
        }
        fflush(stdout);
    }
    if (tm->nodes > 0.0)
        printf("%-8s our BVH per ray: %.1f nodes visited, %.1f references tested\n", name, tm->nodes, tm->tests);
    if (tm->passes > 1)
        printf("%-8s each timed run traced the set %d times (--min-time %.2g s)\n", name, tm->passes, a->min_time);
    if (th->n > 1) {
        int last = th->n - 1;
        printf("%-8s scaling %d -> %d threads: ours %.2fx", name, th->v[0], th->v[last], rate_ours[last] / rate_ours[0]);
        if (run->embree)
            printf(", Embree %.2fx", rate_em[last] / rate_em[0]);
        printf("\n");
    }
    if (run->embree)
        printf("%-8s agreement: %zu of %zu rays differ (%.4f%%) in hit/miss%s\n", name, differ, rs->n,
               100.0 * (double)differ / (double)rs->n, k == TB__SET_SHADOW ? "" : ", object or face");
}

/* Times and reports set k. */
static void tb__bench_set(const tb__rays_args *a, const tb__rays_run *run, int k)
{
    if (run->sets[k].n == 0) {
        printf("%-8s %8d  (no rays)\n", tb__set_names[k], 0);
        return;
    }
    tb__set_times tm;
    tb__time_set(a, run, k, &tm);
    tb__report_set(a, run, k, &tm);
}

/* ------------------------------------------------------------ command */

int tb_cmd_bench_rays(int argc, char **argv)
{
    tb__rays_args a;
    int rc = tb__rays_parse(argc, argv, &a);
    if (rc != TB_CLI_OK)
        return rc;
    if (a.no_stats)
        tb_stats_set_enabled(0); /* the BVH's per-ray counters (util/stats) cost time */
    tb__rays_run run = {.embree = a.embree};
    int status = TB_EXIT_FAIL;
    if (tb__rays_load(&a, &run) && tb__rays_build(&a, &run)) {
        tb__print_table_head();
        for (int k = 0; k < TB__NSETS; k++)
            tb__bench_set(&a, &run, k);
        status = TB_EXIT_OK;
    }
    tb__rays_run_free(&run);
    return status;
}
