/* `testbed validate SCENE.mid [--kernel intersect|shade|formfactor|all] [--rays N]
 * [--shooters N] [--samples N] [--receivers N] [--seed S] [--device N] [--bench]`: the same rays through the CPU path and the Vulkan
 * path, agreement figures against the tolerances of docs/accuracy.md, exit 1
 * beyond them (docs/gpu.md, "testbed validate"). */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli_util.h"
#include "commands.h"
#include "ff_elements.h"
#include "validate_shade.h"
#include "host/gpu/intersect.h"
#include "host/render/scene.h"
#include "util/math/rng.h"
#include "util/stats/stats.h"

/* Tolerances (docs/accuracy.md, "Intersect kernel"). */
#define TB__TOL_HITMISS 1e-4  /* fraction of rays whose hit/miss may differ */
#define TB__TOL_OBJFACE 1e-3  /* fraction of rays hit by both whose object or face may differ */
#define TB__TOL_DT 1e-4       /* max relative |dt| where object and face agree */
#define TB__TOL_ANGLE 1e-3    /* max normal angle (radians) where object and face agree */
#define TB__TOL_OCCLUDED 1e-4 /* fraction of shadow rays whose answer may differ */

/* Random rays: camera rays and rays through the bounds. */
static void tb__make_rays(const tb_scene *s, uint64_t seed, tb_ray *rays, size_t n)
{
    tb_rng rng;
    tb_rng_seed(&rng, seed, 7);
    tb_aabb b = s->bounds;
    double c[3] = {0.5 * ((double)b.lo.x + b.hi.x), 0.5 * ((double)b.lo.y + b.hi.y), 0.5 * ((double)b.lo.z + b.hi.z)};
    double e[3] = {(double)b.hi.x - b.lo.x, (double)b.hi.y - b.lo.y, (double)b.hi.z - b.lo.z};
    double diag = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    if (!(diag > 0.0) || !isfinite(diag))
        diag = 1.0;
    for (size_t i = 0; i < n; ++i) {
        if (i % 2 == 0) {
            double x = tb_rng_double(&rng) * s->camera.width, y = tb_rng_double(&rng) * s->camera.height;
            rays[i] = tb_camera_ray(&s->camera, x, y, 0.5f, 0.5f);
            continue;
        }
        /* Origin on a sphere of radius diag around the centre, aimed at a point of the box. */
        double z = 2.0 * tb_rng_double(&rng) - 1.0, phi = 6.283185307179586 * tb_rng_double(&rng);
        double r = sqrt(1.0 - z * z);
        double o[3] = {c[0] + diag * r * cos(phi), c[1] + diag * r * sin(phi), c[2] + diag * z};
        double p[3];
        for (int k = 0; k < 3; ++k)
            p[k] = c[k] + (tb_rng_double(&rng) - 0.5) * e[k];
        rays[i] = (tb_ray){{(float)o[0], (float)o[1], (float)o[2]},
                           0.0f,
                           {(float)(p[0] - o[0]), (float)(p[1] - o[1]), (float)(p[2] - o[2])},
                           INFINITY};
    }
}

static double tb__angle(tb_vec3 a, tb_vec3 b)
{
    double d = (double)a.x * b.x + (double)a.y * b.y + (double)a.z * b.z;
    double cx = (double)a.y * b.z - (double)a.z * b.y, cy = (double)a.z * b.x - (double)a.x * b.z,
           cz = (double)a.x * b.y - (double)a.y * b.x;
    return atan2(sqrt(cx * cx + cy * cy + cz * cz), d);
}

static void tb__cpu_trace(const tb_scene *s, const tb_ray *rays, size_t n, tb_hit *hits)
{
#pragma omp parallel for schedule(dynamic, 256)
    for (size_t i = 0; i < n; ++i) {
        tb_hit h = {INFINITY, UINT32_MAX, UINT32_MAX, 0.0f, 0.0f, {0.0f, 0.0f, 0.0f}};
        tb_scene_intersect(s, &rays[i], &h);
        hits[i] = h;
    }
}

static const char *tb__verdict(bool ok) { return ok ? "ok" : "BEYOND TOLERANCE"; }

int tb_cmd_validate(int argc, char **argv)
{
    const char *scene_path = NULL;
    int kernel_k = 0, nrays_i = 100000, device_i = -1, shooters_i = 8, samples_i = 16, receivers_i = 2048;
    uint64_t seed_u = 1;
    bool bench = false;
    static const tb_opt_choice kernels[] = {
        {"intersect", 0}, {"shade", 1}, {"formfactor", 2}, {"all", 3}, {NULL, 0}};
    const tb_opt opts[] = {
        {"kernel", .type = TB_OPT_CHOICE, .dest = &kernel_k, .choices = kernels, .metavar = "K",
         .help = "intersect (default), shade, formfactor or all (every one)\n"
                 "shade: the image rendered by the CPU ray tracer and by the Vulkan wavefront\n"
                 "renderer (testbed render --backend vulkan) at 4 spp, seed S, at most 96 pixels\n"
                 "wide and --rays camera samples;\n"
                 "image NMSE against its tolerance, hits shaded by the kernel and routed\n"
                 "formfactor: the scene meshed into elements as for radiosity (edge: bounds\n"
                 "diagonal / 24); receivers at element centroids and corners; shooters: emitting\n"
                 "elements and random ones; every element occludes. Form factors of the CPU\n"
                 "batch and the kernel per (receiver, shooter) and visibility per segment"},
        {"shooters", .type = TB_OPT_INT, .dest = &shooters_i, .min = 1, .max = 4096, .metavar = "N",
         .help = "formfactor: shooters (default %D)"},
        {"samples", .type = TB_OPT_INT, .dest = &samples_i, .min = 1, .max = 4096, .metavar = "N",
         .help = "formfactor: sample points per shooter (default %D)"},
        {"receivers", .type = TB_OPT_INT, .dest = &receivers_i, .min = 1, .max = 1 << 26, .metavar = "N",
         .help = "formfactor: at most N receivers, a random subset (default %D)"},
        {"rays", .type = TB_OPT_INT, .dest = &nrays_i, .min = 1, .max = 1 << 30, .metavar = "N",
         .help = "rays (default %D)"},
        {"seed", .type = TB_OPT_UINT64, .dest = &seed_u, .max = 9223372036854774784.0, .metavar = "S",
         .help = "random seed (default %D)"},
        {"device", .type = TB_OPT_INT, .dest = &device_i, .min = 0, .max = 1000, .metavar = "N",
         .help = "Vulkan device (default: the best, lavapipe included)"},
        {"bench", .type = TB_OPT_FLAG, .dest = &bench,
         .help = "intersect: also time both paths on the same rays (Mrays/s, excluding pipeline\n"
                 "creation); form factors: testbed bench formfactor"},
        {0},
    };
    const tb_cli cli = {
        .prog = "testbed validate",
        .err = "testbed validate: error: ",
        .usage = "SCENE.mid [--kernel intersect|shade|formfactor|all] [--rays N] [--seed S]\n"
                 "                        [--shooters N] [--samples N] [--receivers N] [--device N] [--bench]",
        .intro = "\n"
                 "Runs the same rays through the CPU path and the Vulkan kernels and prints, per kernel,\n"
                 "the agreement against the tolerances of docs/accuracy.md; exit status 1 beyond them.\n"
                 "Rays: half camera primary rays through random film points, half random rays aimed\n"
                 "through the scene bounds; shadow rays are the same rays cut at a random tmax.\n"
                 "Objects of kinds the kernel does not implement are tested on the CPU (routed); the\n"
                 "report lists which objects ran where. TB_VK_VALIDATION=1 enables the validation layer.\n",
        .opts = opts,
        .pos = &scene_path,
        .max_pos = 1,
        .min_pos = 1,
        .missing = "no SCENE.mid given",
    };
    int npos, prc = tb_cli_parse(&cli, argc, argv, &npos);
    if (prc != TB_CLI_OK)
        return prc;
    const char *kernel = kernels[kernel_k].name;
    long nrays = nrays_i, seed = (long)seed_u, device = device_i, shooters = shooters_i, samples = samples_i;
    long receivers = receivers_i;
    tb_scene *s;
    tb_gpu_session sess;
    if (!tb_cli_open_vulkan("testbed validate: error: ", scene_path, device, &s, &sess))
        return TB_EXIT_FAIL;
    int rc = TB_EXIT_FAIL;
    size_t n = (size_t)nrays;
    tb_ray *rays = malloc(n * sizeof *rays), *shadow = malloc(n * sizeof *shadow);
    tb_hit *ch = malloc(n * sizeof *ch), *gh = malloc(n * sizeof *gh);
    uint8_t *co = malloc(n), *go = malloc(n);
    tb_gpu_scene *g = NULL;
    if (!rays || !shadow || !ch || !gh || !co || !go) {
        fprintf(stderr, "testbed validate: error: out of memory for %zu rays\n", n);
        goto done;
    }
    g = tb_gpu_scene_create(sess.device, s);
    if (!g) {
        fprintf(stderr, "testbed validate: error: %s\n", tb_last_error());
        goto done;
    }
    const tb_gpu_device_info *di = tb_gpu_device_info_of(sess.device);
    printf("device: %d (%s)%s\n", sess.device_index, di->name,
           tb_gpu_validation_enabled(sess.instance) ? ", validation layer on" : "");
    tb_gpu_scene_info info;
    tb_gpu_scene_get_info(g, &info);
    printf("scene: %s: %u objects; on the GPU: %llu triangles, %u spheres, %u cubes, %u cylinders/cones/conics, "
           "%u pyramids/prisms/arches, %u tori\n",
           scene_path, s->nobjects, (unsigned long long)info.gpu_triangles, info.gpu_spheres, info.gpu_cubes,
           info.gpu_quadrics, info.gpu_planar, info.gpu_tori);
    printf("routing: %u objects on the GPU, %u routed to the CPU path\n", info.gpu_objects, info.cpu_objects);
    for (uint32_t i = 0; i < s->nobjects; ++i)
        printf("  object %u (%s): %s\n", i, tb_prim_kind_name(s->objects[i]->kind),
               tb_gpu_scene_object_on_gpu(g, i) ? "gpu" : "cpu (routed)");
    bool ok = true;
    if (!strcmp(kernel, "formfactor") || !strcmp(kernel, "shade"))
        goto formfactor; /* the intersect kernel is not compared */

    tb__make_rays(s, (uint64_t)seed, rays, n);
    tb_rng rng;
    tb_rng_seed(&rng, (uint64_t)seed, 8);
    for (size_t i = 0; i < n; ++i) {
        shadow[i] = rays[i];
        shadow[i].tmax = (float)(tb_rng_double(&rng) * 2.0 * (double)tb_vec3_length(
                                     (tb_vec3){s->bounds.hi.x - s->bounds.lo.x, s->bounds.hi.y - s->bounds.lo.y,
                                               s->bounds.hi.z - s->bounds.lo.z}) /
                                 (double)tb_vec3_length(rays[i].d));
    }
    tb__cpu_trace(s, rays, n, ch);
#pragma omp parallel for schedule(dynamic, 256)
    for (size_t i = 0; i < n; ++i)
        co[i] = tb_scene_occluded(s, &shadow[i]) ? 1 : 0;
    tb_gpu_intersect_timing tm;
    if (tb_gpu_intersect(g, rays, n, gh, &tm) || tb_gpu_occluded(g, shadow, n, go, NULL)) {
        fprintf(stderr, "testbed validate: error: %s\n", tb_last_error());
        goto done;
    }
    size_t hitmiss = 0, both = 0, objface = 0, occl = 0;
    double max_dt = 0.0, max_angle = 0.0;
    for (size_t i = 0; i < n; ++i) {
        bool c = ch[i].object != UINT32_MAX, v = gh[i].object != UINT32_MAX;
        occl += co[i] != go[i];
        if (c != v) {
            if (hitmiss < 5)
                printf("  differs: ray %zu: cpu %s, vulkan %s\n", i, c ? "hit" : "miss", v ? "hit" : "miss");
            ++hitmiss;
            continue;
        }
        if (!c)
            continue;
        ++both;
        if (ch[i].object != gh[i].object || ch[i].face != gh[i].face) {
            if (objface < 5)
                printf("  differs: ray %zu: cpu t %.9g object %u face %u, vulkan t %.9g object %u face %u\n", i,
                       ch[i].t, ch[i].object, ch[i].face, gh[i].t, gh[i].object, gh[i].face);
            ++objface;
            continue;
        }
        double dt = fabs((double)gh[i].t - ch[i].t) / fmax(fabs((double)ch[i].t), 1e-30);
        max_dt = fmax(max_dt, dt);
        max_angle = fmax(max_angle, tb__angle(ch[i].ng, gh[i].ng));
    }
    double f_hm = (double)hitmiss / (double)n, f_of = both ? (double)objface / (double)both : 0.0;
    double f_oc = (double)occl / (double)n;
    bool ok_hm = f_hm <= TB__TOL_HITMISS, ok_of = f_of <= TB__TOL_OBJFACE, ok_dt = max_dt <= TB__TOL_DT,
         ok_an = max_angle <= TB__TOL_ANGLE, ok_oc = f_oc <= TB__TOL_OCCLUDED;
    printf("kernel intersect: %zu rays (seed %ld), %zu hit on both paths\n", n, seed, both);
    printf("  hit/miss agreement     %9.5f %%  (%zu differ; tolerance: at most %g of rays)  %s\n",
           100.0 * (1.0 - f_hm), hitmiss, TB__TOL_HITMISS, tb__verdict(ok_hm));
    printf("  object/face agreement  %9.5f %%  (%zu differ; tolerance: at most %g of common hits)  %s\n",
           100.0 * (1.0 - f_of), objface, TB__TOL_OBJFACE, tb__verdict(ok_of));
    printf("  max relative |dt|      %9.3g    (tolerance %g)  %s\n", max_dt, TB__TOL_DT, tb__verdict(ok_dt));
    printf("  max normal angle       %9.3g rad (tolerance %g)  %s\n", max_angle, TB__TOL_ANGLE, tb__verdict(ok_an));
    printf("  occlusion agreement    %9.5f %%  (%zu differ; tolerance: at most %g of rays)  %s\n",
           100.0 * (1.0 - f_oc), occl, TB__TOL_OCCLUDED, tb__verdict(ok_oc));
    ok = ok_hm && ok_of && ok_dt && ok_an && ok_oc;
formfactor:
    if (!strcmp(kernel, "formfactor") || !strcmp(kernel, "all")) { /* cmd_validate_formfactor.c */
        bool ff_ok = false;
        if (tb_validate_formfactor(s, &sess, shooters, samples, receivers, seed, &ff_ok))
            goto done;
        ok = ok && ff_ok;
    }
    if (!strcmp(kernel, "shade") || !strcmp(kernel, "all")) { /* cmd_validate_shade.c */
        bool sh_ok = false;
        if (tb_validate_shade(s, &sess, nrays, seed, &sh_ok))
            goto done;
        ok = ok && sh_ok;
    }
    if (tb_gpu_validation_enabled(sess.instance)) {
        int ve = tb_gpu_validation_errors(sess.instance), vw = tb_gpu_validation_warnings(sess.instance);
        printf("  validation layer       %d errors, %d warnings  %s\n", ve, vw, tb__verdict(ve + vw == 0));
        ok = ok && ve + vw == 0;
    }
    if (bench && strcmp(kernel, "formfactor") && strcmp(kernel, "shade")) {
        /* Both paths once more on the same rays; the pipeline exists already (created above). */
        int64_t t0 = tb_stats_now_ns();
        tb__cpu_trace(s, rays, n, ch);
        double cpu_s = (double)(tb_stats_now_ns() - t0) * 1e-9;
        t0 = tb_stats_now_ns();
        if (tb_gpu_intersect(g, rays, n, gh, &tm)) {
            fprintf(stderr, "testbed validate: error: %s\n", tb_last_error());
            goto done;
        }
        double gpu_s = (double)(tb_stats_now_ns() - t0) * 1e-9;
        printf("bench: %zu rays, %d threads\n", n, omp_get_max_threads());
        printf("  cpu path     %8.3f Mrays/s  (%.3f s)\n", (double)n / cpu_s * 1e-6, cpu_s);
        printf("  vulkan path  %8.3f Mrays/s  (%.3f s: kernel %.3f s device time, upload/dispatch/download %.3f s, "
               "routed CPU objects and (u, v) %.3f s)\n",
               (double)n / gpu_s * 1e-6, gpu_s, tm.kernel_seconds, tm.gpu_seconds, tm.cpu_seconds);
        printf("  ratio vulkan/cpu  %.3f\n", cpu_s / gpu_s);
    }
    rc = ok ? TB_EXIT_OK : TB_EXIT_FAIL;
done:
    tb_gpu_scene_destroy(g);
    tb_gpu_session_close(&sess);
    tb_scene_free(s);
    free(rays), free(shadow), free(ch), free(gh), free(co), free(go);
    return rc;
}
