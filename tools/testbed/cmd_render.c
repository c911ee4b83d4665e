/* `testbed render SCENE.mid -o OUT`: the Whitted ray tracer over a MID scene
 * (docs/raytrace.md), or with --method path the path tracer
 * (docs/pathtrace.md). The workflow is one library call, tb_render_file
 * (host/render/render_file.h); this file holds the options, the Ctrl-C
 * handler, the Vulkan backend (host/render may not use host/gpu) and the
 * summary lines. */
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli_util.h"
#include "commands.h"
#include "dist_cli.h"
#include "host/gpu/gpu.h"
#include "host/gpu/pathtrace.h"
#include "host/gpu/render.h"
#include "host/render/pathtrace.h"
#include "host/render/predict.h"
#include "host/render/render_file.h"
#include "util/image/image.h"
#include "util/stats/stats.h"

#define TB__RENDER_STR2(x) #x
#define TB__RENDER_STR(x) TB__RENDER_STR2(x)

/* Set by SIGINT; the render stops at the next tile and writes what it has. */
static atomic_int tb__render_interrupt;

static void tb__render_on_sigint(int sig)
{
    (void)sig;
    atomic_store(&tb__render_interrupt, 1);
}

/* --filter KIND[:RADIUS[:SIGMA]] (a TB_OPT_CUSTOM parser). */
static int tb__render_filter(const char *val, void *dest, char *why, size_t len)
{
    if (tb_filter_parse(val, dest) == TB_OK)
        return 0;
    snprintf(why, len, "%s", tb_last_error());
    return 1;
}

/* --memory-budget BYTES: a whole number of bytes, or with a binary suffix
 * k, M, G or T (1 k = 1024 bytes): 512M, 2G. */
static int tb__render_budget(const char *val, void *dest, char *why, size_t len)
{
    char *end;
    errno = 0;
    double v = strtod(val, &end);
    double mul = 1.0;
    if (*end && !end[1]) {
        const char *units = "kMGT", *u = strchr(units, *end == 'K' ? 'k' : *end);
        if (u && *end)
            mul = ldexp(1.0, 10 * (int)(u - units + 1)), end++;
    }
    v *= mul;
    if (end == val || *end || errno || !(v >= 1.0) || v > 0x1p62 || v != floor(v)) {
        snprintf(why, len, "'%s' is not a number of bytes >= 1 (e.g. 1000000, 512M, 2G)", val);
        return 1;
    }
    *(size_t *)dest = (size_t)v;
    return 0;
}

/* The command's side of tb_render_file: the Ctrl-C handler around the
 * render and the Vulkan wavefront tracer as its backend. */
typedef struct tb__render_cmd {
    const char *scene_path;
    struct sigaction old_sa;   /* the SIGINT disposition before the render */
    tb_gpu_mode mode;          /* --backend */
    int device;                /* --device, or -1 */
    tb_gpu_render_stats gs;    /* what the wavefront did, when it made the image */
    tb_gpu_device_info info;   /* the device's limits, for --stats (when Vulkan ran) */
    const tb_pt_options *pt;   /* --method path: the path tracer's options (else NULL: the ray tracer) */
    tb_gpu_pt_stats ps;        /* what the device path tracer did, when it made the image */
} tb__render_cmd;

/* tb_render_hook_fn: Ctrl-C writes the partial image while the render runs. */
static void tb__render_hook(void *user, bool starting)
{
    tb__render_cmd *c = user;
    if (!starting) {
        sigaction(SIGINT, &c->old_sa, NULL);
        return;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = tb__render_on_sigint;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &c->old_sa);
    /* Tells a script that Ctrl-C now writes the partial image. */
    fprintf(stderr, "testbed render: rendering %s (Ctrl-C writes the image so far)\n", c->scene_path);
}

/* tb_render_backend_fn: the Vulkan wavefront tracer (docs/gpu.md, "Shade
 * kernel and wavefront renderer") or, with --method path, the Vulkan path
 * tracer (docs/gpu.md, "Path tracer"); auto falls back to the CPU path (*out
 * left NULL) on any Vulkan failure, and for the path tracer on a scene the
 * kernel does not take (saying why). */
static tb_status tb__render_gpu(void *user, const tb_scene *scene, const tb_render_options *ro, tb_image **out,
                                tb_render_stats *rs)
{
    tb__render_cmd *c = user;
    const char *why = c->pt ? tb_gpu_pt_unsupported(scene) : NULL;
    if (why && c->mode != TB_GPU_MODE_CPU) {
        if (c->mode == TB_GPU_MODE_VULKAN || c->device >= 0)
            return tb_error(TB_ERR_UNSUPPORTED, "--backend vulkan: the Vulkan path tracer does not take this scene: "
                                                "%s (use --backend cpu)", why);
        fprintf(stderr, "testbed render: backend cpu: the Vulkan path tracer does not take this scene: %s\n", why);
        return TB_OK;
    }
    /* opening Vulkan loads the driver's libraries (lavapipe: ~50 MiB, a fraction of a second) even when auto then
     * renders on the CPU: --stats says so, for the cost model (docs/predict.md) */
    if (c->mode != TB_GPU_MODE_CPU)
        tb_stats_set_value(TB_VULKAN_PROBE_KEY, 1.0);
    tb_gpu_session gsess;
    tb_status st = tb_gpu_backend_choose(c->mode, c->device, false, &gsess);
    if (st)
        return st;
    fprintf(stderr, "testbed render: backend %s: %s\n", tb_gpu_backend_name(gsess.backend), gsess.reason);
    if (gsess.backend == TB_GPU_BACKEND_VULKAN) {
        c->info = *tb_gpu_device_info_of(gsess.device);
        if (c->pt)
            st = tb_gpu_render_path(gsess.device, scene, c->pt, ro, out, rs, &c->ps);
        else
            st = tb_gpu_render_raytrace(gsess.device, scene, ro, out, rs, &c->gs);
    }
    tb_gpu_session_close(&gsess);
    if (st && c->mode == TB_GPU_MODE_AUTO && c->device < 0) {
        fprintf(stderr, "testbed render: the Vulkan renderer failed (%s); using the CPU path\n", tb_last_error());
        tb_image_free(*out);
        *out = NULL;
        return TB_OK;
    }
    return st ? tb_error_context(st, "--backend %s", tb_gpu_mode_name(c->mode)) : TB_OK;
}

/* tb_render_backend_stats_fn: the wavefront's counters in the stats JSON. */
static tb_status tb__render_gpu_stats(void *user)
{
    const tb__render_cmd *c = user;
    if (c->pt) {
        const tb_gpu_pt_stats *ps = &c->ps;
        tb_status st = tb_stats_set_value("gpu_paths", (double)ps->paths);
        if (!st)
            st = tb_stats_set_value("gpu_command_buffers", (double)ps->submits);
        if (!st)
            st = tb_stats_set_value("gpu_bounce_rounds", (double)ps->bounces);
        if (!st)
            st = tb_stats_set_value("gpu_dispatches", (double)ps->dispatches);
        if (!st)
            st = tb_stats_set_value("gpu_kernel_seconds", ps->kernel_seconds);
        return st;
    }
    const tb_gpu_render_stats *gs = &c->gs;
    tb_status st = tb_stats_set_value("gpu_shaded_hits", (double)gs->gpu_shaded);
    if (!st)
        st = tb_stats_set_value("cpu_routed_hits", (double)gs->cpu_shaded);
    if (!st)
        st = tb_stats_set_value("shadow_rays", (double)gs->shadow_rays);
    if (!st)
        st = tb_stats_set_value("waves", (double)gs->waves);
    if (!st)
        st = tb_stats_set_value("shade_kernel_seconds", gs->shade_seconds);
    if (!st && c->info.name[0])
        st = tb_gpu_limits_to_stats(&c->info);
    return st;
}

static int tb__cmd_render(int argc, char **argv);

int tb_cmd_render(int argc, char **argv)
{
    /* every method runs as one rank, or as a rank of an mpirun job */
    if (tb_dist_init(&argc, &argv)) {
        fprintf(stderr, "testbed render: %s\n", tb_last_error());
        return TB_EXIT_FAIL;
    }
    int rc = tb__cmd_render(argc, argv);
    tb_dist_finalize();
    return rc;
}

static int tb__cmd_render(int argc, char **argv)
{
    /* --method radiosity is another renderer with options of its own */
    for (int i = 1; i + 1 < argc && strcmp(argv[i], "--"); i++)
        if (!strcmp(argv[i], "--method") && !strcmp(argv[i + 1], "radiosity"))
            return tb_cmd_render_radiosity(argc, argv);
    /* --method hybrid likewise (cmd_render_hybrid.c) */
    for (int i = 1; i + 1 < argc && strcmp(argv[i], "--"); i++)
        if (!strcmp(argv[i], "--method") && !strcmp(argv[i + 1], "hybrid"))
            return tb_cmd_render_hybrid(argc, argv);
    const char *scene_path = NULL;
    tb_render_file_options o = tb_render_file_defaults();
    tb_render_options *ro = &o.render;
    int accel = TB_ACCEL_BVH, method = 0, backend = TB_GPU_MODE_AUTO, gdevice = -1;
    int criterion = (int)ro->aa.criterion, pattern = (int)ro->aa.pattern, texture_filter = 3;
    int max_depth = TB_RT_DEFAULT_MAX_DEPTH, light_samples = TB_RT_DEFAULT_LIGHT_SAMPLES;
    int glossy_samples = TB_RT_DEFAULT_GLOSSY_SAMPLES;
    int rr_depth = TB_PT_DEFAULT_RR_DEPTH;
    bool depth_seen = false, light_seen = false, glossy_seen = false, tf_seen = false, adaptive = false;
    bool rr_seen = false, adc_seen = false;
    double adc_bailout = 0.0;
    enum { TB__RAYTRACE, TB__RADIOSITY, TB__PATH, TB__HYBRID };
    static const tb_opt_choice methods[] = {
        {"raytrace", TB__RAYTRACE}, {"path", TB__PATH}, {"hybrid", TB__HYBRID},
        {"radiosity", TB__RADIOSITY}, {NULL, 0}};
    const char *ckpt_path = NULL, *resume_path = NULL;
    double ckpt_every = 0.0;
    static const tb_opt_choice criteria[] = {{"stderr", TB_AA_STDERR}, {"contrast", TB_AA_CONTRAST}, {NULL, 0}};
    static const tb_opt_choice patterns[] = {{"stratified", TB_AA_STRATIFIED}, {"sobol", TB_AA_SOBOL}, {NULL, 0}};
    static const tb_opt_choice tex_filters[] = {{"bilinear", 1}, {"trilinear", 2}, {"ewa", 3}, {NULL, 0}};
    const tb_opt opts[] = {
        {.short_name = 'o', .type = TB_OPT_STRING, .dest = &o.image_path, .metavar = "OUT",
         .help = "the image: .png, .exr, .pfm or .rle"},
        {"method", .type = TB_OPT_CHOICE, .dest = &method, .choices = methods, .metavar = "M",
         .help = "raytrace|path|hybrid|radiosity: raytrace (default: the Whitted ray\n"
                 "tracer), path (the path tracer, docs/pathtrace.md: the options here but\n"
                 "--light-samples and --glossy-samples), hybrid or radiosity\n"
                 "(their options: testbed render --method hybrid|radiosity --help)"},
        {"spp", .type = TB_OPT_INT, .dest = &ro->aa.spp, .min = 1, .max = TB_AA_MAX_SPP, .metavar = "N",
         .help = "samples per pixel (per pass; default %D)"},
        {"adaptive", .type = TB_OPT_DOUBLE, .dest = &ro->aa.threshold, .min = 0, .max = INFINITY, .metavar = "T",
         .flags = TB_OPTF_OPEN_MIN | TB_OPTF_OPTIONAL, .seen = &adaptive,
         .help = "adaptive antialiasing (--max-spp N, --aa-criterion stderr|contrast)"},
        {"max-spp", .type = TB_OPT_INT, .dest = &ro->aa.max_spp, .min = 1, .max = TB_AA_MAX_SPP, .metavar = "N",
         .help = "adaptive: most samples per pixel (default 16)"},
        {"aa-criterion", .type = TB_OPT_CHOICE, .dest = &criterion, .choices = criteria,
         .help = "adaptive: refine where the standard error or the contrast is high (default %D)"},
        {"aa-pattern", .type = TB_OPT_CHOICE, .dest = &pattern, .choices = patterns,
         .help = "sample pattern (default %D)"},
        {"filter", .type = TB_OPT_CUSTOM, .dest = &ro->filter, .metavar = "K[:R[:S]]", .parse = tb__render_filter,
         .help = "box (default) | tent | gaussian | mitchell"},
        {"threads", .type = TB_OPT_INT, .dest = &ro->threads, .min = 0, .max = 4096, .metavar = "N",
         .help = "OpenMP threads (the image does not depend on it)"},
        {"seed", .type = TB_OPT_UINT64, .dest = &ro->aa.seed, .metavar = "N", .help = "sample seed (default %D)"},
        {"backend", .type = TB_OPT_CHOICE, .dest = &backend, .choices = tb_cli_backends, .metavar = "B",
         .help = "cpu (the reference), vulkan or auto (default %D): vulkan runs the\n"
                 "wavefront tracer (intersect + shade kernels) on any Vulkan device,\n"
                 "lavapipe included, and fails if there is none; auto uses it only on a\n"
                 "real GPU and otherwise, or if the device fails, the CPU path (says why).\n"
                 "Same image as cpu within docs/accuracy.md's tolerance; materials with a\n"
                 "feature the kernel lacks (docs/gpu.md, \"Routing by feature mask\") are\n"
                 "shaded on the CPU (the summary line counts those hits and says why).\n"
                 "With --method path: the Vulkan path tracer (Lambert materials, area\n"
                 "lights; docs/gpu.md, \"Path tracer\"), statistically equal to cpu; a scene\n"
                 "with other features is refused by vulkan, rendered on the CPU by auto"},
        {"device", .type = TB_OPT_INT, .dest = &gdevice, .min = 0, .max = 1024, .metavar = "N",
         .help = "Vulkan device N (testbed devices lists them; implies Vulkan in auto)"},
        {"accel", .type = TB_OPT_CHOICE, .dest = &accel, .choices = tb_cli_accels,
         .help = "acceleration structure (default %D)"},
        {"max-depth", .type = TB_OPT_INT, .dest = &max_depth, .min = 0, .max = TB_PT_MAX_BOUNCES, .metavar = "N",
         .seen = &depth_seen,
         .help = "raytrace: deepest reflected/refracted ray (default %D, at most 64);\n"
                 "path: most bounces, a cap (default: none, Russian roulette; at most "
                 TB__RENDER_STR(TB_PT_MAX_BOUNCES) ")"},
        {"rr-depth", .type = TB_OPT_INT, .dest = &rr_depth, .min = 1, .max = TB_PT_MAX_BOUNCES, .metavar = "N",
         .seen = &rr_seen, .help = "path: bounces before Russian roulette (default %D)"},
        {"light-samples", .type = TB_OPT_INT, .dest = &light_samples, .min = 1, .max = 1024, .metavar = "N",
         .seen = &light_seen, .help = "area-light samples per shading point (default %D)"},
        {"glossy-samples", .type = TB_OPT_INT, .dest = &glossy_samples, .min = 1, .max = 1024, .metavar = "N",
         .seen = &glossy_seen, .help = "rays sampled from a GGX lobe at a camera ray's hit (default %D; one deeper)"},
        {"adc-bailout", .type = TB_OPT_DOUBLE, .dest = &adc_bailout, .min = 0, .max = 1, .metavar = "W",
         .flags = TB_OPTF_OPEN_MAX, .seen = &adc_seen,
         .help = "raytrace: adaptive depth control, POV-Ray's adc_bailout: a reflected or\n"
                 "refracted ray whose weight (product of the mirror, Fresnel and\n"
                 "transmission weights since the camera) is below W is not traced\n"
                 "(default 0: every ray to --max-depth; CPU backend)"},
        {"texture-filter", .type = TB_OPT_CHOICE, .dest = &texture_filter, .choices = tex_filters, .seen = &tf_seen,
         .help = "image texture filter over the pixel footprint (default %D)"},
        {"passes", .type = TB_OPT_INT, .dest = &ro->passes, .min = 1, .max = 1 << 20, .metavar = "N",
         .help = "progressive passes of --spp samples each (default %D)"},
        {"time-budget", .type = TB_OPT_DOUBLE, .dest = &ro->time_budget, .min = 0, .max = INFINITY, .metavar = "S",
         .flags = TB_OPTF_OPEN_MIN, .help = "stop starting new tiles after S seconds"},
        {"checkpoint", .type = TB_OPT_STRING, .dest = &ckpt_path, .metavar = "FILE",
         .help = "save the film and the passes done to FILE (atomically) after\n"
                 "passes, at most every --checkpoint-every seconds, and after the last"},
        {"checkpoint-every", .type = TB_OPT_DOUBLE, .dest = &ckpt_every, .min = 0, .max = INFINITY, .metavar = "S",
         .help = "seconds between checkpoints (default 0: after every pass)"},
        {"resume", .type = TB_OPT_STRING, .dest = &resume_path, .metavar = "FILE",
         .help = "continue the render saved in FILE (same scene and options; --passes\n"
                 "may grow): the image equals an uninterrupted run's bit for bit"},
        {"memory-budget", .type = TB_OPT_CUSTOM, .dest = &o.scene.memory_budget, .metavar = "BYTES",
         .parse = tb__render_budget,
         .help = "refuse, before loading, a scene predicted to need more (512M, 2G; docs/performance.md)"},
        {"exposure", .type = TB_OPT_DOUBLE, .dest = &o.exposure, .min = -INFINITY, .max = INFINITY, .metavar = "STOPS",
         .help = "PNG/RLE only: scale by 2^STOPS (default: mean luminance to 0.18)"},
        {"stats", .type = TB_OPT_STRING, .dest = &o.stats_path, .metavar = "FILE.json",
         .help = "counters, times and provenance"},
        {"sample-map", .type = TB_OPT_STRING, .dest = &o.sample_map_path, .metavar = "F.pfm",
         .help = "each pixel's camera sample count (grey PFM; adaptive: where samples went)"},
        {"report", .type = TB_OPT_STRING, .dest = &o.report_path, .metavar = "FILE.csv",
         .help = "a row per pass: seconds, spp, relMSE against --reference IMG"},
        {"reference", .type = TB_OPT_STRING, .dest = &o.reference_path, .metavar = "IMG",
         .help = "the reference image of --report"},
        {0},
    };
    const tb_cli cli = {
        .prog = "testbed render",
        .err = "testbed render: ",
        .usage = "SCENE.mid -o OUT.{png,exr,pfm,rle} [options]",
        .opts = opts,
        .outro = "Ctrl-C writes the image rendered so far and exits with status 130.\n"
                 "Under mpirun every rank renders tiles and rank 0 writes the image, the same\n"
                 "bits as one process (docs/distributed.md).",
        .pos = &scene_path,
        .max_pos = 1,
        .min_pos = 1,
        .missing = "no SCENE.mid given",
    };
    int npos, prc = tb_cli_parse(&cli, argc, argv, &npos);
    if (prc != TB_CLI_OK)
        return prc;
    ro->aa.adaptive = ro->aa.adaptive || adaptive;
    ro->aa.criterion = (tb_aa_criterion)criterion;
    ro->aa.pattern = (tb_aa_pattern)pattern;
    tb_pt_options po = {0};
    tb_render_method path_method = tb_pt_method(&po);
    if (method == TB__PATH) {
        if ((backend == TB_GPU_MODE_VULKAN || gdevice >= 0) && adaptive)
            return tb_cli_usage_error(&cli, "--backend vulkan: the Vulkan path tracer has no adaptive antialiasing; "
                                            "use --backend cpu or a fixed --spp");
        if (adc_seen)
            return tb_cli_usage_error(&cli, "--adc-bailout goes with --method raytrace");
        if (light_seen || glossy_seen)
            return tb_cli_usage_error(&cli, "--%s goes with --method raytrace (the path tracer takes one light "
                                            "sample per vertex and samples its BSDFs)",
                                      light_seen ? "light-samples" : "glossy-samples");
        po.max_depth = depth_seen ? max_depth : 0;
        po.rr_depth = rr_depth;
        o.method = &path_method;
    } else {
        if (rr_seen)
            return tb_cli_usage_error(&cli, "--rr-depth goes with --method path");
        if (depth_seen && max_depth > 64)
            return tb_cli_usage_error(&cli, "--max-depth: the ray tracer's deepest ray is at most 64, not %d",
                                      max_depth);
    }
    if (depth_seen && method != TB__PATH)
        ro->rt.max_depth = max_depth == 0 ? -1 : max_depth;
    if (light_seen)
        ro->rt.light_samples = light_samples;
    if (glossy_seen)
        ro->rt.glossy_samples = glossy_samples;
    if (tf_seen)
        ro->rt.texture_filter = texture_filter;
    ro->rt.min_weight = adc_bailout;
    if (adc_bailout > 0.0 && (backend == TB_GPU_MODE_VULKAN || gdevice >= 0))
        return tb_cli_usage_error(&cli, "--adc-bailout: the Vulkan renderer traces every ray; use --backend cpu");
    ro->cancel = &tb__render_interrupt;
    ro->progress = true;
    o.scene.accel = (tb_accel_kind)accel;
    /* what the library would refuse with TB_ERR_ARG is a usage error here */
    if (!o.image_path)
        return tb_cli_usage_error(&cli, "no output given (-o OUT)");
    if (tb_image_format_from_path(o.image_path) == TB_IMAGE_UNKNOWN)
        return tb_cli_usage_error(&cli, "unknown image format of '%s' (.png, .exr, .pfm, .rle)", o.image_path);
    if (o.sample_map_path && tb_image_format_from_path(o.sample_map_path) != TB_IMAGE_PFM)
        return tb_cli_usage_error(&cli, "--sample-map writes a .pfm file, not '%s'", o.sample_map_path);
    if (!o.report_path != !o.reference_path)
        return tb_cli_usage_error(&cli, "--report and --reference go together");
    tb__render_cmd cmd = {.scene_path = scene_path, .mode = (tb_gpu_mode)backend, .device = gdevice};
    bool root = tb_dist_rank() == 0;
    if (tb_dist_size() > 1 && (backend == TB_GPU_MODE_VULKAN || gdevice >= 0))
        return tb_cli_usage_error(&cli, "--backend vulkan renders in one process, not over %d ranks",
                                  tb_dist_size());
    tb_tile_exchange *ex = NULL;
    tb_ckpt_render ck;
    tb_render_persist persist;
    if (!tb_cli_dist_render_setup("testbed render", scene_path, argc, argv, ro, ckpt_path, ckpt_every,
                                  resume_path, &ex, &ck, &persist))
        return TB_EXIT_FAIL;
    ro->progress = root;
    if (method == TB__PATH)
        cmd.pt = &po;
    if (method != TB__PATH || !ro->aa.adaptive) { /* the Vulkan backends render in one process */
        if (tb_dist_size() == 1 && !(adc_bailout > 0.0)) /* the Vulkan renderer has no depth control */
            o.backend = tb__render_gpu;
        o.backend_stats = tb__render_gpu_stats;
        o.backend_user = &cmd;
        o.backend_name = "vulkan";
    }
    if (root) {
        o.on_render = tb__render_hook;
        o.on_render_user = &cmd;
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
    /* counters nobody reads cost a few percent: off unless --stats writes them */
    const int stats_were = tb_cli_stats_where_written(o.stats_path);
    tb_status st = tb_render_file(scene_path, &o, &res);
    tb_stats_set_enabled(stats_were);
    free(full);
    tb_dist_tiles_free(ex);
    /* collective: every rank gets here, failed or not */
    tb_cli_dist_summary("testbed render", "tiles", st == TB_OK);
    if (st) {
        /* every rank has the same error (the failing rank's); one says it */
        if (root)
            fprintf(stderr, "testbed render: %s\n", tb_last_error());
        return TB_EXIT_FAIL;
    }
    if (!root)
        return TB_EXIT_OK;
    printf("testbed render: %s: %s%dx%d, %llu samples, %.3f s (%d threads, %s)%s; wrote %s\n", scene_path,
           method == TB__PATH ? "path tracer, " : "", res.width,
           res.height, (unsigned long long)res.stats.aa.samples, res.stats.seconds, res.threads,
           res.spectral ? "spectral" : "rgb", res.stats.interrupted ? ", INTERRUPTED (partial image)" : "",
           o.image_path);
    const tb_gpu_render_stats *gs = &cmd.gs;
    const tb_gpu_pt_stats *ps = &cmd.ps;
    if (res.backend && cmd.pt)
        printf("testbed render: vulkan path tracer: %llu paths, %llu command buffers of up to %d bounces, "
               "%llu dispatches; kernels %.3f s, wavefront %.3f s\n",
               (unsigned long long)ps->paths, (unsigned long long)ps->submits, TB_GPU_PT_BOUNCES_PER_SUBMIT,
               (unsigned long long)ps->dispatches, ps->kernel_seconds, ps->wall_seconds);
    else if (res.backend)
        printf("testbed render: vulkan: %llu hits shaded by the kernel, %llu routed to the CPU path%s%s%s, "
               "%llu shadow rays, %llu waves; wavefront %.3f s: intersect + occlusion %.3f s, shade %.3f s "
               "(kernel %.3f s), routed %.3f s\n",
               (unsigned long long)gs->gpu_shaded, (unsigned long long)gs->cpu_shaded,
               gs->routed_materials ? " (" : "", gs->routed_reason,
               gs->routed_materials ? (gs->routed_materials > 1 ? ", ...)" : ")") : "",
               (unsigned long long)gs->shadow_rays, (unsigned long long)gs->waves, gs->wave_seconds,
               gs->trace_seconds, gs->shade_wall_seconds, gs->shade_seconds, gs->cpu_seconds);
    return atomic_load(&tb__render_interrupt) ? 130 : TB_EXIT_OK;
}
