/* `testbed bench gpu SCENE.mid [--rays N] [--repeat R] [--seed S] [--device N]`:
 * the intersect kernel (host/gpu/intersect.h) against the CPU path on the
 * three ray sets of `testbed bench rays` (primary, shadow, diffuse), in
 * Mrays/s per set, with the kernel's device time apart: per-dispatch
 * timestamps of each kernel (docs/gpu.md, "Measuring on a GPU";
 * docs/performance.md, "Vulkan"). On a real GPU this is the entry that
 * reports its Mrays/s. */
#include <errno.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include "bench_raysets.h"
#include "cli_util.h"
#include "commands.h"
#include "host/gpu/intersect.h"
#include "host/object/hit.h"
#include "host/object/intersect.h"
#include "host/render/lights.h"
#include "host/render/scene.h"
#include "util/math/rng.h"
#include "util/stats/stats.h"

enum { TB__GSET_PRIMARY, TB__GSET_SHADOW, TB__GSET_DIFFUSE, TB__GSETS };
static const char *const tb__gset_names[TB__GSETS] = {"primary", "shadow", "diffuse"};

/* The three sets (as `testbed bench rays` makes them, but primary rays in
 * scanline order: a renderer's order, which keeps neighbouring rays, and
 * so a SIMD group of the kernel, coherent). Returns false when out of memory. */
static bool tb__gmake_sets(const tb_scene *s, size_t np, uint64_t seed, tb_ray *sets[TB__GSETS], size_t n[TB__GSETS])
{
    for (int k = 0; k < TB__GSETS; k++) {
        sets[k] = malloc(sizeof(tb_ray) * (np ? np : 1));
        n[k] = 0;
        if (!sets[k])
            return false;
    }
    const tb_camera *c = &s->camera;
    double aspect = (double)c->width / (double)c->height;
    size_t w = (size_t)ceil(sqrt((double)np * aspect)), h = (np + w - 1) / w;
    for (size_t i = 0; i < np; i++) {
        double x = ((double)(i % w) + 0.5) * c->width / (double)w, y = ((double)(i / w) + 0.5) * c->height / (double)h;
        sets[TB__GSET_PRIMARY][n[TB__GSET_PRIMARY]++] = tb_camera_ray(c, x, y, 0.5f, 0.5f);
    }
    tb_area_light area = {0};
    bool use_area = s->nemitters > 0 && tb_area_light_init(&area, s->emitters, s->nemitters) == TB_OK;
    tb_rng rng;
    tb_rng_seed(&rng, seed, 0);
    tb_bench_secondary_rays(s, use_area ? &area : NULL, sets[TB__GSET_PRIMARY], n[TB__GSET_PRIMARY], &rng,
                            sets[TB__GSET_SHADOW], &n[TB__GSET_SHADOW], sets[TB__GSET_DIFFUSE], &n[TB__GSET_DIFFUSE]);
    tb_area_light_release(&area);
    return true;
}

/* CPU seconds used so far by every thread of the process (OpenMP's and the
 * Vulkan driver's: lavapipe runs kernels on its own threads in this process). */
static double tb__gcpu_seconds(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
           1e-6 * (double)ru.ru_stime.tv_usec;
}

static int tb__gcmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double tb__gmedian(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, tb__gcmp);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* The kernels the intersect path dispatches, whose timestamps are reported. */
static const char *const tb__gkernels[] = {"intersect"};
enum { TB__GKERNELS = sizeof tb__gkernels / sizeof tb__gkernels[0] };

/* Dispatch count and device nanoseconds (sum, min, max) recorded so far for
 * kernel k ("GPU/kernel <name> (ns)", host/gpu/kernel.c); zeros if none. */
static tb_stat_total tb__gkernel_total(int k)
{
    char name[96];
    snprintf(name, sizeof name, "GPU/kernel %s (ns)", tb__gkernels[k]);
    tb_stat_total t = {0};
    if (tb_stats_get(name, TB_STAT_KIND_DISTRIBUTION, &t))
        memset(&t, 0, sizeof t);
    return t;
}

/* Lists the Vulkan devices, marking the one measured, and its limits. */
static void tb__glist_devices(const tb_gpu_session *sess)
{
    int n = tb_gpu_device_count(sess->instance);
    printf("devices (testbed devices; --device N):\n");
    for (int i = 0; i < n; ++i) {
        const tb_gpu_device_info *d = tb_gpu_device_info_at(sess->instance, i);
        printf("  %c %d  %s (%s)%s%s\n", i == sess->device_index ? '*' : ' ', i, d->name,
               tb_gpu_device_type_name(d->type), d->usable ? "" : ": unusable: ", d->usable ? "" : d->unusable_reason);
    }
    char lim[512];
    tb_gpu_limits_describe(tb_gpu_device_info_of(sess->device), lim, sizeof lim);
    printf("device: %s\n", lim);
    const tb_gpu_device_info *d = tb_gpu_device_info_of(sess->device);
    if (!d->timestamps)
        printf("kernel timestamps: not available (compute queue: timestampValidBits %u, timestampPeriod %g%s): "
               "the kernel columns are nan; wall-clock figures only\n",
               d->timestamp_valid_bits, (double)d->timestamp_period,
               getenv("TB_GPU_NO_TIMESTAMPS") ? "; turned off by TB_GPU_NO_TIMESTAMPS" : "");
}

/* One timed pass of set k through the CPU path; wall seconds (CPU seconds in *cs). */
static double tb__gcpu(const tb_scene *s, int k, const tb_ray *rays, size_t n, tb_hit *hits, uint8_t *occ, double *cs)
{
    double c0 = tb__gcpu_seconds();
    int64_t t0 = tb_stats_now_ns();
    if (k == TB__GSET_SHADOW) {
#pragma omp parallel for schedule(dynamic, 256)
        for (size_t i = 0; i < n; ++i)
            occ[i] = tb_scene_occluded(s, &rays[i]) ? 1 : 0;
    } else {
#pragma omp parallel for schedule(dynamic, 256)
        for (size_t i = 0; i < n; ++i) {
            tb_hit h = {INFINITY, UINT32_MAX, UINT32_MAX, 0.0f, 0.0f, {0.0f, 0.0f, 0.0f}};
            tb_scene_intersect(s, &rays[i], &h);
            hits[i] = h;
        }
    }
    double sec = (double)(tb_stats_now_ns() - t0) * 1e-9;
    *cs = tb__gcpu_seconds() - c0;
    return sec;
}

/* One timed pass of set k through the Vulkan path; wall seconds (kernel device
 * seconds in *ks, CPU seconds of the process in *cs), < 0 on failure. */
static double tb__ggpu(tb_gpu_scene *g, int k, const tb_ray *rays, size_t n, tb_hit *hits, uint8_t *occ, double *ks,
                       double *cs)
{
    tb_gpu_intersect_timing tm = {0};
    double c0 = tb__gcpu_seconds();
    int64_t t0 = tb_stats_now_ns();
    tb_status st = k == TB__GSET_SHADOW ? tb_gpu_occluded(g, rays, n, occ, &tm) : tb_gpu_intersect(g, rays, n, hits, &tm);
    double sec = (double)(tb_stats_now_ns() - t0) * 1e-9;
    *cs = tb__gcpu_seconds() - c0;
    *ks = tm.kernel_seconds;
    return st ? -1.0 : sec;
}

int tb_cmd_bench_gpu(int argc, char **argv)
{
    const char *path = NULL;
    int nrays_i = 500000, repeat_i = 3, device_i = -1, quadrics = TB_GPU_QUADRICS_AUTO;
    uint64_t seed_u = 1;
    static const tb_opt_choice quadric_places[] = {
        {"auto", TB_GPU_QUADRICS_AUTO}, {"gpu", TB_GPU_QUADRICS_GPU}, {"cpu", TB_GPU_QUADRICS_CPU}, {NULL, 0}};
    const tb_opt opts[] = {
        {"rays", .type = TB_OPT_INT, .dest = &nrays_i, .min = 1, .max = 1 << 28, .metavar = "N",
         .help = "primary rays (default %D)"},
        {"repeat", .type = TB_OPT_INT, .dest = &repeat_i, .min = 1, .max = 1000, .metavar = "R",
         .help = "timed runs per set and path (default %D)"},
        {"seed", .type = TB_OPT_UINT64, .dest = &seed_u, .max = 4611686018427387904.0, .metavar = "S",
         .help = "seed of the shadow and diffuse sampling (default %D)"},
        {"device", .type = TB_OPT_INT, .dest = &device_i, .min = 0, .max = 1000, .metavar = "N",
         .help = "Vulkan device (testbed devices; default: the best one)"},
        {"quadrics", .type = TB_OPT_CHOICE, .dest = &quadrics, .choices = quadric_places,
         .help = "where cylinders, cones and conics run (default %D: in the\n"
                 "kernel except on a CPU driver such as lavapipe; tb_gpu_scene_desc)"},
        {0},
    };
    const tb_cli cli = {
        .prog = "testbed bench gpu",
        .err = "testbed bench gpu: error: ",
        .usage = "SCENE.mid [--rays N] [--repeat R] [--seed S] [--device N]\n"
                 "                         [--quadrics auto|gpu|cpu]",
        .intro = "\n"
                 "Times the Vulkan intersect kernel (tb_gpu_intersect / tb_gpu_occluded) and the CPU path\n"
                 "(tb_scene_intersect / tb_scene_occluded, OpenMP over rays) on the same rays:\n"
                 "  primary  N camera rays in scanline order over a grid of the film (closest hit)\n"
                 "  shadow   from each primary hit toward a point on a light (any hit)\n"
                 "  diffuse  from each primary hit, cosine-distributed about the normal (closest hit)\n"
                 "Prints per set the median over R runs of Mrays/s (wall clock) of both paths, their ratio,\n"
                 "and the kernel's own rate from its device time (timestamp queries), then Mrays per CPU\n"
                 "second of the process (all threads, the driver's included) and their ratio: on a shared\n"
                 "machine this ratio is steadier than the wall-clock one. Pipeline creation is\n"
                 "excluded (one untimed call first). The Vulkan path includes the upload, download and the\n"
                 "host's part (routed CPU objects, (u, v)). Rays on which the two paths disagree (object,\n"
                 "or occlusion) are counted as a sanity check; `testbed validate` gives the full figures.\n"
                 "First lists the Vulkan devices (* the one measured) and its limits; under each set, per\n"
                 "kernel: dispatches, device time per run and per dispatch (timestamp queries) and the\n"
                 "Mrays/s that time gives. Without timestamps (the device's compute queue has none) the\n"
                 "kernel figures are nan and say so. docs/gpu.md, \"Measuring on a GPU\".\n",
        .opts = opts,
        .pos = &path,
        .max_pos = 1,
        .min_pos = 1,
        .missing = "no SCENE.mid given",
    };
    int npos, prc = tb_cli_parse(&cli, argc, argv, &npos);
    if (prc != TB_CLI_OK)
        return prc;
    long nrays = nrays_i, repeat = repeat_i, seed = (long)seed_u, device = device_i;
    tb_gpu_scene_desc gdesc = {(tb_gpu_quadrics)quadrics};
    tb_scene *s;
    tb_gpu_session sess;
    if (!tb_cli_open_vulkan("testbed bench gpu: error: ", path, device, &s, &sess))
        return TB_EXIT_FAIL;
    int rc = TB_EXIT_FAIL;
    tb_ray *sets[TB__GSETS] = {NULL, NULL, NULL};
    size_t n[TB__GSETS];
    size_t np = (size_t)nrays;
    tb_hit *ch = malloc(np * sizeof *ch), *gh = malloc(np * sizeof *gh);
    uint8_t *co = malloc(np), *go = malloc(np);
    tb_gpu_scene *g = NULL;
    if (!ch || !gh || !co || !go || !tb__gmake_sets(s, np, (uint64_t)seed, sets, n)) {
        fprintf(stderr, "testbed bench gpu: error: out of memory for %zu rays\n", np);
        goto done;
    }
    if (!(g = tb_gpu_scene_create_ex(sess.device, s, &gdesc))) {
        fprintf(stderr, "testbed bench gpu: error: %s\n", tb_last_error());
        goto done;
    }
    tb_gpu_scene_info info;
    tb_gpu_scene_get_info(g, &info);
    tb__glist_devices(&sess);
    printf("scene: %s: %u objects (%u on the GPU, %u routed), %llu triangles, %u spheres, %u cubes, "
           "%u cylinders/cones/conics\n",
           path, s->nobjects, info.gpu_objects, info.cpu_objects,
           (unsigned long long)info.gpu_triangles, info.gpu_spheres, info.gpu_cubes, info.gpu_quadrics);
    printf("threads: %d, runs per figure: %ld (median)\n", omp_get_max_threads(), repeat);
    printf("%-8s %9s %12s %12s %14s %7s %14s %7s %9s\n", "set", "rays", "cpu Mrays/s", "vk Mrays/s",
           "kernel Mrays/s", "ratio", "cpu/vk Mr/cpu-s", "ratio", "disagree");
    size_t rb = (size_t)repeat * sizeof(double);
    double *tc = malloc(rb), *tg = malloc(rb), *tk = malloc(rb), *cc = malloc(rb), *cg = malloc(rb);
    if (!tc || !tg || !tk || !cc || !cg) {
        free(tc), free(tg), free(tk), free(cc), free(cg);
        fprintf(stderr, "testbed bench gpu: error: out of memory\n");
        goto done;
    }
    rc = TB_EXIT_OK;
    for (int k = 0; k < TB__GSETS && rc == TB_EXIT_OK; ++k) {
        size_t m = n[k];
        if (m == 0) {
            printf("%-8s %9s (no rays: no primary hits, or no lights for shadow rays)\n", tb__gset_names[k], "0");
            continue;
        }
        double ks = 0.0, cs = 0.0;
        if (tb__ggpu(g, k, sets[k], m < 4096 ? m : 4096, gh, go, &ks, &cs) < 0.0) { /* pipeline creation, untimed */
            fprintf(stderr, "testbed bench gpu: error: %s\n", tb_last_error());
            rc = TB_EXIT_FAIL;
            break;
        }
        tb_stat_total before[TB__GKERNELS];
        for (int q = 0; q < TB__GKERNELS; ++q)
            before[q] = tb__gkernel_total(q);
        for (long r = 0; r < repeat; ++r) {
            tc[r] = tb__gcpu(s, k, sets[k], m, ch, co, &cc[r]);
            tg[r] = tb__ggpu(g, k, sets[k], m, gh, go, &tk[r], &cg[r]);
            if (tg[r] < 0.0) {
                fprintf(stderr, "testbed bench gpu: error: %s\n", tb_last_error());
                rc = TB_EXIT_FAIL;
                break;
            }
        }
        if (rc != TB_EXIT_OK)
            break;
        size_t bad = 0;
        for (size_t i = 0; i < m; ++i)
            bad += k == TB__GSET_SHADOW ? co[i] != go[i] : ch[i].object != gh[i].object;
        double c = tb__gmedian(tc, (int)repeat), v = tb__gmedian(tg, (int)repeat), kk = tb__gmedian(tk, (int)repeat);
        double xc = tb__gmedian(cc, (int)repeat), xg = tb__gmedian(cg, (int)repeat);
        printf("%-8s %9zu %12.3f %12.3f %14.3f %7.3f %6.3f/%-7.3f %7.3f %9zu\n", tb__gset_names[k], m,
               1e-6 * (double)m / c, 1e-6 * (double)m / v, kk > 0.0 && isfinite(kk) ? 1e-6 * (double)m / kk : NAN,
               c / v, 1e-6 * (double)m / xc, 1e-6 * (double)m / xg, xc / xg, bad);
        /* Per kernel: the timestamps of its dispatches in the R timed runs. */
        for (int q = 0; q < TB__GKERNELS; ++q) {
            tb_stat_total a = tb__gkernel_total(q);
            int64_t nd = a.v[0] - before[q].v[0], ns = a.v[1] - before[q].v[1];
            if (nd <= 0) {
                printf("  kernel %-10s no timestamps recorded\n", tb__gkernels[q]);
                continue;
            }
            double per_run = (double)ns * 1e-9 / (double)repeat;
            printf("  kernel %-10s %lld dispatches per run, device time %.3f ms per run (%.1f%% of the Vulkan "
                   "wall time), %.3f ms per dispatch (min %.3f, max %.3f in this process), %.3f Mrays/s\n",
                   tb__gkernels[q], (long long)(nd / repeat), 1e3 * per_run, 100.0 * per_run / v,
                   1e-6 * (double)ns / (double)nd, 1e-6 * (double)a.v[2], 1e-6 * (double)a.v[3],
                   1e-6 * (double)m / per_run);
        }
    }
    free(tc), free(tg), free(tk), free(cc), free(cg);
done:
    for (int k = 0; k < TB__GSETS; ++k)
        free(sets[k]);
    free(ch), free(gh), free(co), free(go);
    tb_gpu_scene_destroy(g);
    tb_gpu_session_close(&sess);
    tb_scene_free(s);
    return rc;
}
