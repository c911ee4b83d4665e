/* `testbed render SCENE.mid --method hybrid`: the hybrid radiosity +
 * ray-tracing renderer (docs/hybrid.md). Options -> tb_hybrid_options and
 * tb_render_file_options -> one library call (tb_render_file with the
 * hybrid as its method, host/hybrid/hybrid.h) -> one line of summary.
 * Called by tb_cmd_render (cmd_render.c) when --method hybrid is given. */
#include <math.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli_util.h"
#include "commands.h"
#include "dist_cli.h"
#include "host/gpu/gpu.h"
#include "host/hybrid/hybrid.h"
#include "host/render/render_file.h"
#include "options.h"
#include "util/image/image.h"
#include "util/stats/stats.h"

#define TB__HYB_STR2(x) #x
#define TB__HYB_STR(x) TB__HYB_STR2(x)

/* Set by SIGINT; the render stops at the next tile and writes what it has. */
static atomic_int tb__hyb_interrupt;

static void tb__hyb_on_sigint(int sig)
{
    (void)sig;
    atomic_store(&tb__hyb_interrupt, 1);
}

/* tb_render_hook_fn: Ctrl-C writes the partial image while the render runs
 * (the radiosity pass before it is not interruptible). */
static void tb__hyb_hook(void *user, bool starting)
{
    static struct sigaction old;
    if (!starting) {
        sigaction(SIGINT, &old, NULL);
        return;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = tb__hyb_on_sigint;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old);
    fprintf(stderr, "testbed render: hybrid on %s: radiosity pass, then the ray tracer (Ctrl-C writes the image "
                    "so far)\n", (const char *)user);
}

/* --filter KIND[:RADIUS[:SIGMA]] (a TB_OPT_CUSTOM parser). */
static int tb__hyb_filter(const char *val, void *dest, char *why, size_t len)
{
    if (tb_filter_parse(val, dest) == TB_OK)
        return 0;
    snprintf(why, len, "%s", tb_last_error());
    return 1;
}

int tb_cmd_render_hybrid(int argc, char **argv)
{
    tb_render_file_options o = tb_render_file_defaults();
    tb_render_options *ro = &o.render;
    tb_hybrid_method_state hs = {.opt = tb_hybrid_defaults()};
    tb_hybrid_options *ho = &hs.opt;
    ho->solver.samples = TB_RAD_DEFAULT_SAMPLES;
    ho->gather_rays = TB_HYBRID_DEFAULT_GATHER_RAYS;
    int method = 0, mode = TB_HYBRID_INTERPOLATED, backend = TB_GPU_MODE_CPU, accel = TB_ACCEL_BVH;
    int max_depth = TB_RT_DEFAULT_MAX_DEPTH, light_samples = TB_RT_DEFAULT_LIGHT_SAMPLES;
    int glossy_samples = TB_RT_DEFAULT_GLOSSY_SAMPLES;
    bool depth_seen = false, light_seen = false, glossy_seen = false, gather_seen = false;
    const char *ckpt_path = NULL, *resume_path = NULL;
    double ckpt_every = 0.0;
    bool edge_given = false, area_given = false;
    static const tb_opt_choice methods[] = {{"hybrid", 0}, {NULL, 0}};
    static const tb_opt_choice modes[] = {{"interpolated", TB_HYBRID_INTERPOLATED}, {"gather", TB_HYBRID_GATHER},
                                          {NULL, 0}};
    const tb_opt opts[] = {
        {.short_name = 'o', .type = TB_OPT_STRING, .dest = &o.image_path, .metavar = "OUT",
         .help = "the image: .png, .exr, .pfm or .rle"},
        {"method", .type = TB_OPT_CHOICE, .dest = &method, .choices = methods, .metavar = "hybrid",
         .help = "this renderer (testbed render --help: the ray tracer)"},
        {"hybrid-mode", .type = TB_OPT_CHOICE, .dest = &mode, .choices = modes, .metavar = "M",
         .help = "indirect diffuse light at a diffuse hit: interpolated (default: the\n"
                 "solution's irradiance there minus its direct part) or gather (a one-bounce\n"
                 "final gather reading the solution's reflected radiosity where rays land)"},
        {"gather-rays", .type = TB_OPT_INT, .dest = &ho->gather_rays, .min = 1, .max = TB_HYBRID_MAX_GATHER_RAYS,
         .metavar = "N", .seen = &gather_seen,
         .help = "gather: cosine-distributed, stratified rays per diffuse hit (default %D)"},
        {"max-edge", .type = TB_OPT_DOUBLE, .dest = &ho->mesh.max_edge, .min = 0, .max = 1e30, .metavar = "L",
         .seen = &edge_given,
         .help = "radiosity pass: longest element edge, scene units (default: the scene's\n"
                 "bounding-box diagonal / " TB__HYB_STR(TB_RAD_DEFAULT_EDGE_DIVISIONS) "; 0: faces whole)"},
        {"max-area", .type = TB_OPT_DOUBLE, .dest = &ho->mesh.max_area, .min = 0, .max = 1e30, .metavar = "A",
         .flags = TB_OPTF_OPEN_MIN, .seen = &area_given, .help = "radiosity pass: largest element area, units^2"},
        {"rad-samples", .type = TB_OPT_INT, .dest = &ho->solver.samples, .min = 1, .max = 65536, .metavar = "N",
         .help = "radiosity pass: ray-cast sample points per shooter (default %D)"},
        {"threshold", .type = TB_OPT_DOUBLE, .dest = &ho->stop.threshold, .min = 0, .max = 1, .metavar = "X",
         .flags = TB_OPTF_OPEN_MIN | TB_OPTF_OPEN_MAX,
         .help = "radiosity pass: stop when the unshot fraction of emitted power is below X\n(default %D)"},
        {"rad-seed", .type = TB_OPT_UINT64, .dest = &ho->solver.seed, .metavar = "N",
         .help = "radiosity pass: seed of the shooters' sample points (default %D)"},
        {"spp", .type = TB_OPT_INT, .dest = &ro->aa.spp, .min = 1, .max = TB_AA_MAX_SPP, .metavar = "N",
         .help = "samples per pixel (per pass; default %D)"},
        {"passes", .type = TB_OPT_INT, .dest = &ro->passes, .min = 1, .max = 1 << 20, .metavar = "N",
         .help = "progressive passes of --spp samples each (default %D)"},
        {"filter", .type = TB_OPT_CUSTOM, .dest = &ro->filter, .metavar = "K[:R[:S]]", .parse = tb__hyb_filter,
         .help = "box (default) | tent | gaussian | mitchell"},
        {"max-depth", .type = TB_OPT_INT, .dest = &max_depth, .min = 0, .max = 64, .metavar = "N", .seen = &depth_seen,
         .help = "deepest reflected/refracted ray (default %D)"},
        {"light-samples", .type = TB_OPT_INT, .dest = &light_samples, .min = 1, .max = 1024, .metavar = "N",
         .seen = &light_seen, .help = "area-light samples per shading point (default %D)"},
        {"glossy-samples", .type = TB_OPT_INT, .dest = &glossy_samples, .min = 1, .max = 1024, .metavar = "N",
         .seen = &glossy_seen, .help = "rays sampled from a GGX lobe at a camera ray's hit (default %D)"},
        {"threads", .type = TB_OPT_INT, .dest = &ro->threads, .min = 0, .max = 4096, .metavar = "N",
         .help = "OpenMP threads (the image does not depend on it)"},
        {"seed", .type = TB_OPT_UINT64, .dest = &ro->aa.seed, .metavar = "N", .help = "sample seed (default %D)"},
        {"time-budget", .type = TB_OPT_DOUBLE, .dest = &ro->time_budget, .min = 0, .max = INFINITY, .metavar = "S",
         .flags = TB_OPTF_OPEN_MIN, .help = "ray-tracing pass: stop starting new tiles after S seconds"},
        {"accel", .type = TB_OPT_CHOICE, .dest = &accel, .choices = tb_cli_accels,
         .help = "acceleration structure (default %D)"},
        {"backend", .type = TB_OPT_CHOICE, .dest = &backend, .choices = tb_cli_backends, .metavar = "B",
         .help = "cpu (default; auto means cpu): the hybrid runs on the CPU only"},
        {"exposure", .type = TB_OPT_DOUBLE, .dest = &o.exposure, .min = -INFINITY, .max = INFINITY, .metavar = "STOPS",
         .help = "PNG/RLE only: scale by 2^STOPS (default: mean luminance to 0.18)"},
        {"checkpoint", .type = TB_OPT_STRING, .dest = &ckpt_path, .metavar = "FILE",
         .help = "save the ray tracer's film and passes to FILE after passes (the\n"
                 "radiosity pass is solved again on --resume: it is deterministic)"},
        {"checkpoint-every", .type = TB_OPT_DOUBLE, .dest = &ckpt_every, .min = 0, .max = INFINITY, .metavar = "S",
         .help = "seconds between checkpoints (default 0: after every pass)"},
        {"resume", .type = TB_OPT_STRING, .dest = &resume_path, .metavar = "FILE",
         .help = "continue the render saved in FILE (--passes may grow)"},
        {"stats", .type = TB_OPT_STRING, .dest = &o.stats_path, .metavar = "FILE.json",
         .help = "counters, times (radiosity_seconds, ...) and provenance"},
        {"report", .type = TB_OPT_STRING, .dest = &o.report_path, .metavar = "FILE.csv",
         .help = "a row per pass: seconds, spp, relMSE against --reference IMG"},
        {"reference", .type = TB_OPT_STRING, .dest = &o.reference_path, .metavar = "IMG",
         .help = "the reference image of --report"},
        {0},
    };
    const char *scene_path = NULL;
    const tb_cli cli = {
        .prog = "testbed render",
        .err = "testbed render: ",
        .usage = "SCENE.mid --method hybrid -o OUT.{png,exr,pfm,rle} [options]",
        .intro = "The hybrid radiosity + ray-tracing renderer (docs/hybrid.md): a radiosity pass solves the\n"
                 "diffuse interreflection, then the Whitted ray tracer renders from the eye with direct light by\n"
                 "shadow rays and indirect diffuse light from the solution.",
        .outro = "Ctrl-C during the ray-tracing pass writes the image so far and exits with status 130.",
        .opts = opts,
        .pos = &scene_path,
        .max_pos = 1,
        .min_pos = 1,
        .missing = "no SCENE.mid given",
    };
    int npos, rc = tb_cli_parse(&cli, argc, argv, &npos);
    if (rc != TB_CLI_OK)
        return rc;
    if (backend == TB_GPU_MODE_VULKAN)
        return tb_cli_usage_error(&cli, "--backend vulkan: the hybrid renderer runs on the CPU only "
                                        "(use --backend cpu, or --method raytrace for the Vulkan ray tracer)");
    if (gather_seen && mode != TB_HYBRID_GATHER)
        return tb_cli_usage_error(&cli, "--gather-rays goes with --hybrid-mode gather");
    if (!o.image_path)
        return tb_cli_usage_error(&cli, "no output given (-o OUT)");
    if (tb_image_format_from_path(o.image_path) == TB_IMAGE_UNKNOWN)
        return tb_cli_usage_error(&cli, "unknown image format of '%s' (.png, .exr, .pfm, .rle)", o.image_path);
    if (!o.report_path != !o.reference_path)
        return tb_cli_usage_error(&cli, "--report and --reference go together");
    ho->mode = (tb_hybrid_mode)mode;
    ho->mesh_given = edge_given || area_given;
    ho->stop.progress = true; /* the radiosity pass's bar, on a terminal */
    ho->log = stderr;
    ho->log_prefix = "testbed render: ";
    if (depth_seen)
        ro->rt.max_depth = max_depth == 0 ? -1 : max_depth;
    if (light_seen)
        ro->rt.light_samples = light_samples;
    if (glossy_seen)
        ro->rt.glossy_samples = glossy_samples;
    ro->cancel = &tb__hyb_interrupt;
    o.scene.accel = (tb_accel_kind)accel;
    tb_render_method m = tb_hybrid_method(&hs);
    o.method = &m;
    /* under mpirun every rank solves the radiosity pass itself (the same
     * solution: it is deterministic) and the ray-tracing tiles are shared */
    bool root = tb_dist_rank() == 0;
    tb_tile_exchange *ex = NULL;
    tb_ckpt_render ck;
    tb_render_persist persist;
    if (!tb_cli_dist_render_setup("testbed render", scene_path, argc, argv, ro, ckpt_path, ckpt_every,
                                  resume_path, &ex, &ck, &persist))
        return TB_EXIT_FAIL;
    ro->progress = root;
    ho->stop.progress = root;
    if (!root)
        ho->log = NULL;
    else {
        o.on_render = tb__hyb_hook;
        o.on_render_user = (void *)scene_path;
    }

    /* the provenance records the whole command line */
    char **full = tb_cli_full_argv(argc, argv);
    if (!full) {
        fprintf(stderr, "testbed render: out of memory\n");
        tb_dist_tiles_free(ex);
        return TB_EXIT_FAIL;
    }
    o.argc = argc + 1, o.argv = full;
    tb_render_file_result res;
    const int stats_were = tb_cli_stats_where_written(o.stats_path);
    tb_status st = tb_render_file(scene_path, &o, &res);
    tb_stats_set_enabled(stats_were);
    free(full);
    tb_dist_tiles_free(ex);
    tb_cli_dist_summary("testbed render", "tiles", st == TB_OK);
    if (st) {
        if (root)
            fprintf(stderr, "testbed render: %s\n", tb_last_error());
        return TB_EXIT_FAIL;
    }
    if (!root)
        return TB_EXIT_OK;
    printf("testbed render: %s: hybrid (%s), radiosity %zu elements, %llu shots, %.3f s; ray tracing %dx%d, %llu "
           "samples, %.3f s (%d threads, %s)%s; wrote %s\n",
           scene_path, mode == TB_HYBRID_GATHER ? "gather" : "interpolated", hs.stats.elements,
           (unsigned long long)hs.stats.shots, hs.stats.solve_seconds + hs.stats.direct_seconds, res.width,
           res.height, (unsigned long long)res.stats.aa.samples, res.stats.seconds, res.threads,
           res.spectral ? "spectral" : "rgb", res.stats.interrupted ? ", INTERRUPTED (partial image)" : "",
           o.image_path);
    return atomic_load(&tb__hyb_interrupt) ? 130 : TB_EXIT_OK;
}
