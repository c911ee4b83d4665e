/* `testbed predict SCENE [render options] [--costs COSTS.json] [--json]`:
 * the wall time and peak memory `testbed render` would take, from the cost
 * model that `testbed calibrate` fits (host/render/predict.h,
 * docs/predict.md). The scene is loaded once and a pilot (a low-resolution
 * render, or for radiosity a one-sample solve on a coarser mesh) counts the
 * work. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli_util.h"
#include "commands.h"
#include "host/gpu/gpu.h"
#include "host/gpu/pathtrace.h"
#include "host/radiosity/predict.h"
#include "host/render/pathtrace.h"
#include "host/render/predict.h"
#include "host/render/raytrace.h"

/* Prints the human-readable prediction. */
static void tb__predict_print(const char *scene, const tb_costs *c, const tb_predict_stats *f,
                              const tb_prediction *p)
{
    printf("testbed predict: %s, %s: %.3g s, peak memory %.1f MiB (costs of %d thread%s%s%s)\n", scene,
           tb_predict_method_name(f->method), p->seconds, p->peak_rss_bytes / 1048576.0, c->threads,
           c->threads == 1 ? "" : "s", c->created[0] ? ", calibrated " : "", c->created);
    int nterms;
    const tb_cost_term *terms = tb_cost_terms(&nterms);
    for (int m = 0; m < TB_PM_COUNT; m++) {
        if (p->module[m] == 0.0)
            continue;
        if (m == TB_PM_MEMORY)
            printf("  %-10s %10.1f MiB\n", tb_pmodule_name((tb_pmodule)m), p->module[m] / 1048576.0);
        else
            printf("  %-10s %10.3f s  %5.1f%%\n", tb_pmodule_name((tb_pmodule)m), p->module[m],
                   p->seconds > 0 ? 100.0 * p->module[m] / p->seconds : 0.0);
        for (int i = 0; i < nterms; i++)
            if (terms[i].module == (tb_pmodule)m && p->term[i] != 0.0) {
                if (m == TB_PM_MEMORY)
                    printf("    %-34s %10.1f MiB\n", terms[i].name, p->term[i] / 1048576.0);
                else
                    printf("    %-34s %10.3f s\n", terms[i].name, p->term[i]);
            }
    }
    if (f->method == TB_PREDICT_RADIOSITY)
        printf("  radiosity: %.0f elements, %.0f shots%s; pilot %.2f s\n", f->f[TB_PF_RAD_ELEMENTS], f->rad_shots,
               f->rad_extrapolated ? " (extrapolated from the pilot's decay)" : "", f->pilot_seconds);
    else
        printf("  per pixel: %.2f camera samples, %.2f rays, %.2f occlusion rays, %.2f hits; pilot %.2f s\n",
               f->f[TB_PF_SAMPLES] / f->f[TB_PF_PIXELS], f->f[TB_PF_RAYS] / f->f[TB_PF_PIXELS],
               f->f[TB_PF_OCC_RAYS] / f->f[TB_PF_PIXELS], f->f[TB_PF_HITS] / f->f[TB_PF_PIXELS], f->pilot_seconds);
}

/* What decides whether `testbed render` probes the Vulkan device (cmd_render.c,
 * tb__render_gpu): any backend but cpu, for the ray tracer always, for the path
 * tracer (not adaptive) when its Vulkan kernel takes the scene. */
typedef struct tb__predict_backend {
    int mode;      /* tb_gpu_mode */
    bool path;     /* --method path */
    bool adaptive; /* path: --adaptive (rendered on the CPU without asking) */
} tb__predict_backend;

static bool tb__predict_probes(const tb_scene *s, void *user)
{
    const tb__predict_backend *b = user;
    if (b->mode == TB_GPU_MODE_CPU)
        return false;
    if (!b->path)
        return true;
    return !b->adaptive && tb_gpu_pt_unsupported(s) == NULL;
}

int tb_cmd_predict(int argc, char **argv)
{
    const char *scene_path = NULL, *costs_path = NULL, *ignored = NULL;
    bool json = false, adaptive = false, spp_seen = false, edge_given = false, area_given = false;
    enum { TB__RT, TB__PATH, TB__RAD };
    static const tb_opt_choice methods[] = {{"raytrace", TB__RT}, {"path", TB__PATH}, {"radiosity", TB__RAD},
                                            {NULL, 0}};
    static const tb_opt_choice ffs[] = {{"raycast", TB_RAD_FF_RAYCAST}, {"hemicube", TB_RAD_FF_HEMICUBE}, {NULL, 0}};
    int method = TB__RT, accel = TB_ACCEL_BVH, max_depth = -2, rr_depth = TB_PT_DEFAULT_RR_DEPTH;
    int light_samples = TB_RT_DEFAULT_LIGHT_SAMPLES, glossy_samples = TB_RT_DEFAULT_GLOSSY_SAMPLES;
    int pilot = 4, ff = TB_RAD_FF_RAYCAST, max_shots = 0, rad_spp = 4;
    double pilot_seconds = 10.0;
    tb_render_file_options rf = tb_render_file_defaults();
    tb_render_options *ro = &rf.render;
    tb_rad_render_options rad = tb_rad_render_defaults();
    rad.solver.samples = TB_RAD_DEFAULT_SAMPLES;
    rad.solver.hemicube_res = TB_RAD_DEFAULT_HEMICUBE_RES;
    int threads = 0, backend = TB_GPU_MODE_AUTO;
    const tb_opt opts[] = {
        {"method", .type = TB_OPT_CHOICE, .dest = &method, .choices = methods, .metavar = "M",
         .help = "raytrace (default), path or radiosity, as testbed render"},
        {"costs", .type = TB_OPT_STRING, .dest = &costs_path, .metavar = "COSTS.json",
         .help = "the per-unit costs testbed calibrate wrote (default: $XDG_CACHE_HOME/testbed/\n"
                 "costs.json, or ~/.cache/testbed/costs.json)"},
        {"json", .type = TB_OPT_FLAG, .dest = &json,
         .help = "print {\"seconds\": ..., \"peak_rss_bytes\": ..., \"modules\": {...}, ...} instead"},
        {"pilot", .type = TB_OPT_INT, .dest = &pilot, .min = 1, .max = 1024, .metavar = "D",
         .help = "raytrace/path: the pilot renders width/D x height/D pixels (default %D)"},
        {"pilot-seconds", .type = TB_OPT_DOUBLE, .dest = &pilot_seconds, .min = 0, .max = 1e6, .metavar = "S",
         .flags = TB_OPTF_OPEN_MIN,
         .help = "radiosity: most seconds of pilot shooting before extrapolating (default %D)"},
        {"threads", .type = TB_OPT_INT, .dest = &threads, .min = 0, .max = 4096, .metavar = "N",
         .help = "OpenMP threads of the render (and the pilot)"},
        /* the render's options that change its cost */
        {"spp", .type = TB_OPT_INT, .dest = &ro->aa.spp, .min = 1, .max = TB_AA_MAX_SPP, .metavar = "N",
         .seen = &spp_seen, .help = "samples per pixel (radiosity: image rays per pixel, default 4)"},
        {"passes", .type = TB_OPT_INT, .dest = &ro->passes, .min = 1, .max = 1 << 20, .metavar = "N",
         .help = "progressive passes"},
        {"adaptive", .type = TB_OPT_DOUBLE, .dest = &ro->aa.threshold, .min = 0, .max = INFINITY, .metavar = "T",
         .flags = TB_OPTF_OPEN_MIN | TB_OPTF_OPTIONAL, .seen = &adaptive, .help = "adaptive antialiasing"},
        {"max-spp", .type = TB_OPT_INT, .dest = &ro->aa.max_spp, .min = 1, .max = TB_AA_MAX_SPP, .metavar = "N",
         .help = "adaptive: most samples per pixel"},
        {"seed", .type = TB_OPT_UINT64, .dest = &ro->aa.seed, .metavar = "N", .help = "sample seed"},
        {"backend", .type = TB_OPT_CHOICE, .dest = &backend, .choices = tb_cli_backends, .metavar = "B",
         .help = "auto (default) or cpu: auto probes the Vulkan device first (a real GPU is\n"
                 "not modelled: the prediction is the CPU render's)"},
        {"accel", .type = TB_OPT_CHOICE, .dest = &accel, .choices = tb_cli_accels,
         .help = "acceleration structure (the costs are fitted with bvh)"},
        {"max-depth", .type = TB_OPT_INT, .dest = &max_depth, .min = 0, .max = TB_PT_MAX_BOUNCES, .metavar = "N",
         .help = "deepest ray (raytrace) or most bounces (path)"},
        {"rr-depth", .type = TB_OPT_INT, .dest = &rr_depth, .min = 1, .max = TB_PT_MAX_BOUNCES, .metavar = "N",
         .help = "path: bounces before Russian roulette"},
        {"light-samples", .type = TB_OPT_INT, .dest = &light_samples, .min = 1, .max = 1024, .metavar = "N",
         .help = "raytrace: area-light samples per shading point"},
        {"glossy-samples", .type = TB_OPT_INT, .dest = &glossy_samples, .min = 1, .max = 1024, .metavar = "N",
         .help = "raytrace: rays sampled from a GGX lobe at a camera ray's hit"},
        {"formfactor", .type = TB_OPT_CHOICE, .dest = &ff, .choices = ffs, .metavar = "M",
         .help = "radiosity: raycast (default) | hemicube"},
        {"samples", .type = TB_OPT_INT, .dest = &rad.solver.samples, .min = 1, .max = 65536, .metavar = "N",
         .help = "radiosity: ray-cast sample points per shooter (default %D)"},
        {"hemicube-res", .type = TB_OPT_INT, .dest = &rad.solver.hemicube_res, .min = 2, .max = 8192,
         .metavar = "N", .help = "radiosity: hemicube resolution (default %D)"},
        {"threshold", .type = TB_OPT_DOUBLE, .dest = &rad.stop.threshold, .min = 0, .max = 1, .metavar = "X",
         .flags = TB_OPTF_OPEN_MIN | TB_OPTF_OPEN_MAX, .help = "radiosity: unshot fraction to stop at (default %D)"},
        {"max-shots", .type = TB_OPT_INT, .dest = &max_shots, .min = 1, .max = 0x7fffffff, .metavar = "N",
         .help = "radiosity: stop after N shots"},
        {"max-edge", .type = TB_OPT_DOUBLE, .dest = &rad.mesh.max_edge, .min = 0, .max = 1e30, .metavar = "L",
         .seen = &edge_given, .help = "radiosity: longest element edge"},
        {"max-area", .type = TB_OPT_DOUBLE, .dest = &rad.mesh.max_area, .min = 0, .max = 1e30, .metavar = "A",
         .flags = TB_OPTF_OPEN_MIN, .seen = &area_given, .help = "radiosity: largest element area"},
        {"patch-edge", .type = TB_OPT_DOUBLE, .dest = &rad.mesh.patch_edge, .min = 0, .max = 1e30, .metavar = "L",
         .flags = TB_OPTF_OPEN_MIN, .help = "radiosity: two levels, patches with edges up to L"},
        /* accepted so a render's command line can be pasted; they do not change the prediction */
        {.short_name = 'o', .type = TB_OPT_STRING, .dest = &ignored, .metavar = "OUT",
         .help = "accepted and ignored (the prediction assumes an image is written)"},
        {"stats", .type = TB_OPT_STRING, .dest = &ignored, .metavar = "FILE.json", .help = "accepted and ignored"},
        {"exposure", .type = TB_OPT_STRING, .dest = &ignored, .metavar = "STOPS", .help = "accepted and ignored"},
        {0},
    };
    const tb_cli cli = {
        .prog = "testbed predict",
        .err = "testbed predict: ",
        .usage = "SCENE.mid [--method raytrace|path|radiosity] [render options] [--costs COSTS.json] [--json]",
        .intro = "Predicts the wall time and peak resident memory of `testbed render SCENE` with the same\n"
                 "options, with a per-module breakdown, from this machine's costs (testbed calibrate).\n"
                 "The scene is loaded once; a pilot counts the work: raytrace/path render the image at\n"
                 "1/D of the resolution (--pilot), radiosity solves on a 4x coarser mesh with one sample\n"
                 "point per shooter to count the shots per shooter (--pilot-seconds, then the count is\n"
                 "extrapolated). docs/predict.md.",
        .opts = opts,
        .outro = "Exit status: 0 predicted, 1 bad scene or costs, 2 usage error.",
        .pos = &scene_path,
        .max_pos = 1,
        .min_pos = 1,
        .missing = "no SCENE.mid given",
    };
    int npos, prc = tb_cli_parse(&cli, argc, argv, &npos);
    if (prc != TB_CLI_OK)
        return prc;
    char def[4096];
    if (!costs_path) {
        if (tb_cli_default_costs_path(def, sizeof def) != 0)
            return tb_cli_usage_error(&cli, "no --costs given and neither XDG_CACHE_HOME nor HOME is set");
        costs_path = def;
    }
    if (backend == TB_GPU_MODE_VULKAN)
        return tb_cli_usage_error(&cli, "--backend vulkan is not modelled (the costs are the CPU renderers')");
    tb_costs costs;
    if (tb_costs_read(costs_path, &costs)) {
        fprintf(stderr, "testbed predict: %s\n", tb_last_error());
        if (!strcmp(costs_path, def))
            fprintf(stderr, "testbed predict: run `testbed calibrate` first (it writes %s), or give --costs\n",
                    costs_path);
        return TB_EXIT_FAIL;
    }
    tb_predict_stats f;
    tb_status st;
    if (method == TB__RAD) {
        rad.solver.ff = (tb_rad_ff_method)ff;
        rad.stop.max_shots = (uint64_t)max_shots;
        rad.mesh_given = edge_given || area_given;
        rad.threads = threads;
        rad.spp = spp_seen ? ro->aa.spp : rad_spp;
        rad.image_path = "predict"; /* an image is assumed, as the render with -o */
        st = tb_rad_predict_scene(scene_path, &rad, pilot_seconds, &f);
    } else {
        ro->aa.adaptive = ro->aa.adaptive || adaptive;
        ro->threads = threads;
        tb_pt_options po = {0};
        if (method == TB__PATH) {
            po.max_depth = max_depth >= 0 ? max_depth : 0;
            po.rr_depth = rr_depth;
        } else {
            if (max_depth > 64)
                return tb_cli_usage_error(&cli, "--max-depth: the ray tracer's deepest ray is at most 64");
            if (max_depth >= 0)
                ro->rt.max_depth = max_depth == 0 ? -1 : max_depth;
            ro->rt.light_samples = light_samples;
            ro->rt.glossy_samples = glossy_samples;
        }
        tb__predict_backend be = {.mode = backend, .path = method == TB__PATH, .adaptive = ro->aa.adaptive};
        tb_predict_options o = {.method = method == TB__PATH ? TB_PREDICT_PATH : TB_PREDICT_RAYTRACE,
                                .render = *ro,
                                .accel = (tb_accel_kind)accel,
                                .path_options = &po,
                                .pilot_divisor = pilot,
                                .vulkan_probe = tb__predict_probes,
                                .vulkan_probe_user = &be};
        st = tb_predict_scene(scene_path, &o, &f);
    }
    if (st) {
        fprintf(stderr, "testbed predict: %s\n", tb_last_error());
        return TB_EXIT_FAIL;
    }
    tb_prediction p;
    tb_predict_eval(&costs, &f, &p);
    if (json)
        tb_prediction_write_json(stdout, &costs, &f, &p);
    else
        tb__predict_print(scene_path, &costs, &f, &p);
    return TB_EXIT_OK;
}
