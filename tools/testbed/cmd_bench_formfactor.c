/* `testbed bench formfactor SCENE.mid [--shooters N] [--samples N]
 * [--repeat R] [--seed S] [--device N]`: ray-cast form factors per second of
 * the Vulkan kernel (tb_gpu_ff_batch, host/gpu/formfactor.h) and of the CPU
 * batch (tb_ff_raycast_batch, OpenMP over receivers) on the same shooters and
 * receivers of a scene meshed as for radiosity (ff_elements.h).
 * docs/performance.md, "Form-factor kernel". */
#include <errno.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include "cli_util.h"
#include "commands.h"
#include "ff_elements.h"
#include "host/gpu/formfactor.h"
#include "util/stats/stats.h"

/* User + system CPU seconds of the whole process. */
static double tb__ffb_cpu(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
           1e-6 * (double)(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

/* The work: shooters' sample points, normals and areas. */
typedef struct tb__ffb_work {
    const tb_ffe_set *e;
    size_t nshoot;
    int npts;
    tb_vec3 *pts; /* nshoot * npts */
    const uint32_t *shoot;
} tb__ffb_work;

/* The Vulkan batch with its kernel time added up (tb_gpu_ff_batch plus timing). */
typedef struct tb__ffb_gpu {
    tb_gpu_ff_scene *g;
    double kernel_s;
} tb__ffb_gpu;

static tb_status tb__ffb_gpu_batch(void *ctx, const tb_vec3 *pts, int npts, tb_vec3 ns, double area, const tb_vec3 *p,
                                   const tb_vec3 *n, size_t count, double *ff)
{
    tb__ffb_gpu *c = ctx;
    tb_gpu_ff_timing tm;
    tb_status st = tb_gpu_ff_raycast(c->g, pts, npts, ns, area, p, n, count, ff, NULL, &tm);
    c->kernel_s += tm.kernel_seconds;
    return st;
}

/* Every shot through `fn`; results of shooter j in out[j * nrecv ..]. Wall seconds, or -1 on an error. */
static double tb__ffb_run(const tb__ffb_work *w, tb_ff_batch_fn fn, void *ctx, double *out, double *cpu_s)
{
    double c0 = tb__ffb_cpu();
    int64_t t0 = tb_stats_now_ns();
    for (size_t j = 0; j < w->nshoot; ++j) {
        uint32_t el = w->shoot[j];
        if (fn(ctx, w->pts + j * (size_t)w->npts, w->npts, w->e->normal[el], w->e->area[el], w->e->rp, w->e->rn,
               w->e->nrecv, out + j * w->e->nrecv))
            return -1.0;
    }
    double s = (double)(tb_stats_now_ns() - t0) * 1e-9;
    *cpu_s = tb__ffb_cpu() - c0;
    return s;
}

int tb_cmd_bench_formfactor(int argc, char **argv)
{
    const char *path = NULL;
    int shooters_i = 16, samples_i = 16, repeat_i = 3, device_i = -1;
    uint64_t seed_u = 1;
    const tb_opt opts[] = {
        {"shooters", .type = TB_OPT_INT, .dest = &shooters_i, .min = 1, .max = 4096, .metavar = "N",
         .help = "shooters (default %D)"},
        {"samples", .type = TB_OPT_INT, .dest = &samples_i, .min = 1, .max = 4096, .metavar = "N",
         .help = "sample points per shooter (default %D)"},
        {"repeat", .type = TB_OPT_INT, .dest = &repeat_i, .min = 1, .max = 4096, .metavar = "R",
         .help = "timed runs per path (default %D)"},
        {"seed", .type = TB_OPT_UINT64, .dest = &seed_u, .max = 1099511627776.0, .metavar = "S",
         .help = "seed of the shooter choice and the sample points (default %D)"},
        {"device", .type = TB_OPT_INT, .dest = &device_i, .min = 0, .max = 4096, .metavar = "N",
         .help = "Vulkan device (testbed devices; default: the best one, lavapipe included)"},
        {0},
    };
    const tb_cli cli = {
        .prog = "testbed bench formfactor",
        .err = "testbed bench formfactor: ",
        .usage = "SCENE.mid [--shooters N] [--samples N] [--repeat R]\n"
                 "                                [--seed S] [--device N]",
        .intro = "\n"
                 "Ray-cast form factors (Wallace et al. 1989) per second, the Vulkan kernel against the CPU\n"
                 "batch (OpenMP over receivers), on the same work: the scene (e.g. scenes/cornell-box.mid)\n"
                 "meshed into elements as `testbed validate --kernel formfactor` does (edge: bounds\n"
                 "diagonal / 24; every element occludes), every element centroid and corner a receiver,\n"
                 "N shooters (emitting elements first, then random ones), each with S sample points.\n"
                 "Prints, for the best of R runs: form factors (receiver-shooter pairs) and sample\n"
                 "segments per second by wall clock, the process CPU seconds (the driver's threads\n"
                 "included), the kernel's device time (timestamp queries: the Vulkan path is timed\n"
                 "through tb_gpu_ff_raycast, which is tb_gpu_ff_batch plus timing), the ratio\n"
                 "vulkan/cpu, and the largest relative difference between the two (floor 1e-6) as a\n"
                 "sanity check. Pipeline creation is excluded (one untimed shot first).\n",
        .opts = opts,
        .pos = &path,
        .max_pos = 1,
        .min_pos = 1,
        .missing = "no SCENE.mid given",
    };
    int npos, prc = tb_cli_parse(&cli, argc, argv, &npos);
    if (prc != TB_CLI_OK)
        return prc;
    long shooters = shooters_i, samples = samples_i, repeat = repeat_i, seed = (long)seed_u, device = device_i;
    tb_scene *s;
    tb_gpu_session sess;
    if (!tb_cli_open_vulkan("testbed bench formfactor: ", path, device, &s, &sess))
        return TB_EXIT_FAIL;
    int rc = TB_EXIT_FAIL;
    tb_aabb b = s->bounds;
    double diag = sqrt(((double)b.hi.x - b.lo.x) * ((double)b.hi.x - b.lo.x) +
                       ((double)b.hi.y - b.lo.y) * ((double)b.hi.y - b.lo.y) +
                       ((double)b.hi.z - b.lo.z) * ((double)b.hi.z - b.lo.z));
    tb_ffe_set e = {0};
    tb_ff_occluders *occ = NULL;
    tb_gpu_ff_scene *g = NULL;
    uint32_t *shoot = NULL;
    tb__ffb_work w = {0};
    double *cf = NULL, *gf = NULL;
    if (tb_ffe_build(s, diag > 0.0 && isfinite(diag) ? diag / TB_FFE_EDGE_DIVISOR : 1.0, &e) ||
        tb_ff_occluders_build(e.polys, e.n, &occ) || !(g = tb_gpu_ff_scene_create(sess.device, e.polys, e.n))) {
        fprintf(stderr, "testbed bench formfactor: %s\n", tb_last_error());
        goto done;
    }
    if (e.n == 0) {
        fprintf(stderr, "testbed bench formfactor: %s gives no elements\n", path);
        goto done;
    }
    shoot = malloc((size_t)shooters * sizeof *shoot);
    w.pts = malloc((size_t)shooters * (size_t)samples * sizeof *w.pts);
    cf = malloc((size_t)shooters * e.nrecv * sizeof *cf);
    gf = malloc((size_t)shooters * e.nrecv * sizeof *gf);
    if (!shoot || !w.pts || !cf || !gf) {
        fprintf(stderr, "testbed bench formfactor: out of memory\n");
        goto done;
    }
    w.e = &e;
    w.npts = (int)samples;
    w.shoot = shoot;
    w.nshoot = tb_ffe_shooters(&e, s, (size_t)shooters, (uint64_t)seed, shoot);
    for (size_t j = 0; j < w.nshoot; ++j)
        if (tb_ff_sample_polygon(&e.polys[shoot[j]], w.npts, (uint64_t)seed * 1000003u + j, w.pts + j * (size_t)w.npts)) {
            fprintf(stderr, "testbed bench formfactor: %s\n", tb_last_error());
            goto done;
        }
    const tb_gpu_device_info *di = tb_gpu_device_info_of(sess.device);
    printf("testbed bench formfactor: %s: %zu elements (occluders: %zu triangles), %zu receivers, %zu shooters x %ld "
           "samples\n",
           path, e.n, tb_gpu_ff_scene_triangles(g), e.nrecv, w.nshoot, samples);
    printf("device %d (%s); CPU path: %d threads; best of %ld runs\n\n", sess.device_index, di->name,
           omp_get_max_threads(), repeat);
    /* One untimed shot: pipeline creation and the driver's first-dispatch compilation. */
    double warm = 0.0;
    if (tb_gpu_ff_batch(g, w.pts, w.npts, e.normal[shoot[0]], e.area[shoot[0]], e.rp, e.rn, 1, &warm)) {
        fprintf(stderr, "testbed bench formfactor: %s\n", tb_last_error());
        goto done;
    }
    double best[2] = {INFINITY, INFINITY}, cpu_at_best[2] = {0.0, 0.0}, kernel_at_best = NAN;
    tb__ffb_gpu gctx = {g, 0.0};
    for (long r = 0; r < repeat; ++r)
        for (int path_k = 0; path_k < 2; ++path_k) {
            double cs = 0.0;
            gctx.kernel_s = 0.0;
            double t = path_k == 0 ? tb__ffb_run(&w, tb_ff_raycast_batch, occ, cf, &cs)
                                   : tb__ffb_run(&w, tb__ffb_gpu_batch, &gctx, gf, &cs);
            if (t < 0.0) {
                fprintf(stderr, "testbed bench formfactor: %s\n", tb_last_error());
                goto done;
            }
            if (t < best[path_k]) {
                best[path_k] = t;
                cpu_at_best[path_k] = cs;
                if (path_k == 1)
                    kernel_at_best = gctx.kernel_s;
            }
        }
    double pairs = (double)w.nshoot * (double)e.nrecv, segs = pairs * (double)samples, worst = 0.0;
    for (size_t i = 0; i < w.nshoot * e.nrecv; ++i)
        worst = fmax(worst, fabs(gf[i] - cf[i]) / fmax(fabs(cf[i]), 1e-6));
    printf("%-8s %14s %14s %10s %12s\n", "path", "M FF/s", "M segments/s", "seconds", "CPU seconds");
    const char *names[2] = {"cpu", "vulkan"};
    for (int k = 0; k < 2; ++k)
        printf("%-8s %14.4f %14.3f %10.3f %12.3f\n", names[k], pairs / best[k] * 1e-6, segs / best[k] * 1e-6, best[k],
               cpu_at_best[k]);
    printf("kernel device time %.3f s: %.3f M segments/s (timestamps; the rest is packing, upload, download)\n",
           kernel_at_best, segs / kernel_at_best * 1e-6);
    printf("\nratio vulkan/cpu: %.3f (wall clock), %.3f (per CPU second)\n", best[0] / best[1],
           cpu_at_best[0] / cpu_at_best[1]);
    printf("largest relative difference vulkan vs cpu: %.3g (visibility flips of grazing segments: testbed validate)\n",
           worst);
    rc = TB_EXIT_OK;
done:
    tb_gpu_ff_scene_destroy(g);
    tb_ff_occluders_free(occ);
    tb_ffe_free(&e);
    tb_gpu_session_close(&sess);
    tb_scene_free(s);
    free(shoot), free(w.pts), free(cf), free(gf);
    return rc;
}
