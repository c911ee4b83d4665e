/* `testbed render SCENE.mid -o OUT`: the Whitted ray tracer over a MID scene
 * (host/render/raytrace.h, render.h; docs/raytrace.md). */
#include <math.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <omp.h>

#include "cli_util.h"
#include "commands.h"
#include "host/gpu/gpu.h"
#include "host/gpu/render.h"
#include "host/render/render.h"
#include "host/render/scene.h"
#include "util/image/compare.h"
#include "util/image/image.h"
#include "util/stats/provenance.h"
#include "util/stats/stats.h"

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

/* The --report state. */
typedef struct tb__report {
    FILE *fp;
    const tb_image *reference;
    const tb_scene *scene;
    bool failed;
} tb__report;

static int tb__report_pass(void *ctx, int pass, int spp_total, double seconds, const tb_film *film)
{
    tb__report *r = ctx;
    (void)pass;
    tb_image *img = tb_render_resolve(r->scene, film);
    tb_compare_result res;
    if (!img || tb_image_compare(img, r->reference, NULL, &res)) {
        fprintf(stderr, "testbed render: report: %s\n", tb_last_error());
        tb_image_free(img);
        r->failed = true;
        return 1;
    }
    tb_image_free(img);
    fprintf(r->fp, "%.6f,%d,%.9g\n", seconds, spp_total, res.all.relmse);
    fflush(r->fp);
    return 0;
}

int tb_cmd_render(int argc, char **argv)
{
    /* --method radiosity is another renderer with options of its own */
    for (int i = 1; i + 1 < argc && strcmp(argv[i], "--"); i++)
        if (!strcmp(argv[i], "--method") && !strcmp(argv[i + 1], "radiosity"))
            return tb_cmd_render_radiosity(argc, argv);
    const char *scene_path = NULL, *out_path = NULL, *stats_path = NULL, *report_path = NULL, *ref_path = NULL;
    const char *map_path = NULL;
    tb_render_options ro = tb_render_defaults();
    int accel = TB_ACCEL_BVH, method = 0, backend = TB_GPU_MODE_AUTO, gdevice = -1;
    int criterion = (int)ro.aa.criterion, pattern = (int)ro.aa.pattern, texture_filter = 3;
    int max_depth = TB_RT_DEFAULT_MAX_DEPTH, light_samples = TB_RT_DEFAULT_LIGHT_SAMPLES;
    int glossy_samples = TB_RT_DEFAULT_GLOSSY_SAMPLES;
    bool depth_seen = false, light_seen = false, glossy_seen = false, tf_seen = false, adaptive = false;
    double exposure = NAN;
    static const tb_opt_choice methods[] = {{"raytrace", 0}, {"radiosity", 1}, {NULL, 0}};
    static const tb_opt_choice criteria[] = {{"stderr", TB_AA_STDERR}, {"contrast", TB_AA_CONTRAST}, {NULL, 0}};
    static const tb_opt_choice patterns[] = {{"stratified", TB_AA_STRATIFIED}, {"sobol", TB_AA_SOBOL}, {NULL, 0}};
    static const tb_opt_choice tex_filters[] = {{"bilinear", 1}, {"trilinear", 2}, {"ewa", 3}, {NULL, 0}};
    const tb_opt opts[] = {
        {.short_name = 'o', .type = TB_OPT_STRING, .dest = &out_path, .metavar = "OUT",
         .help = "the image: .png, .exr, .pfm or .rle"},
        {"method", .type = TB_OPT_CHOICE, .dest = &method, .choices = methods, .metavar = "M",
         .help = "raytrace (default: the Whitted ray tracer) or radiosity (options:\n"
                 "testbed render --method radiosity --help)"},
        {"spp", .type = TB_OPT_INT, .dest = &ro.aa.spp, .min = 1, .max = TB_AA_MAX_SPP, .metavar = "N",
         .help = "samples per pixel (per pass; default %D)"},
        {"adaptive", .type = TB_OPT_DOUBLE, .dest = &ro.aa.threshold, .min = 0, .max = INFINITY, .metavar = "T",
         .flags = TB_OPTF_OPEN_MIN | TB_OPTF_OPTIONAL, .seen = &adaptive,
         .help = "adaptive antialiasing (--max-spp N, --aa-criterion stderr|contrast)"},
        {"max-spp", .type = TB_OPT_INT, .dest = &ro.aa.max_spp, .min = 1, .max = TB_AA_MAX_SPP, .metavar = "N",
         .help = "adaptive: most samples per pixel (default 16)"},
        {"aa-criterion", .type = TB_OPT_CHOICE, .dest = &criterion, .choices = criteria,
         .help = "adaptive: refine where the standard error or the contrast is high (default %D)"},
        {"aa-pattern", .type = TB_OPT_CHOICE, .dest = &pattern, .choices = patterns,
         .help = "sample pattern (default %D)"},
        {"filter", .type = TB_OPT_CUSTOM, .dest = &ro.filter, .metavar = "K[:R[:S]]", .parse = tb__render_filter,
         .help = "box (default) | tent | gaussian | mitchell"},
        {"threads", .type = TB_OPT_INT, .dest = &ro.threads, .min = 0, .max = 4096, .metavar = "N",
         .help = "OpenMP threads (the image does not depend on it)"},
        {"seed", .type = TB_OPT_UINT64, .dest = &ro.aa.seed, .metavar = "N", .help = "sample seed (default %D)"},
        {"backend", .type = TB_OPT_CHOICE, .dest = &backend, .choices = tb_cli_backends, .metavar = "B",
         .help = "cpu (the reference), vulkan or auto (default %D): vulkan runs the\n"
                 "wavefront tracer (intersect + shade kernels) on any Vulkan device,\n"
                 "lavapipe included, and fails if there is none; auto uses it only on a\n"
                 "real GPU and otherwise, or if the device fails, the CPU path (says why).\n"
                 "Same image as cpu within docs/accuracy.md's tolerance; hits the kernel\n"
                 "cannot shade (textures, patterns, bump, GGX) run on the CPU: reported"},
        {"device", .type = TB_OPT_INT, .dest = &gdevice, .min = 0, .max = 1024, .metavar = "N",
         .help = "Vulkan device N (testbed devices lists them; implies Vulkan in auto)"},
        {"accel", .type = TB_OPT_CHOICE, .dest = &accel, .choices = tb_cli_accels,
         .help = "acceleration structure (default %D)"},
        {"max-depth", .type = TB_OPT_INT, .dest = &max_depth, .min = 0, .max = 64, .metavar = "N", .seen = &depth_seen,
         .help = "deepest reflected/refracted ray (default %D)"},
        {"light-samples", .type = TB_OPT_INT, .dest = &light_samples, .min = 1, .max = 1024, .metavar = "N",
         .seen = &light_seen, .help = "area-light samples per shading point (default %D)"},
        {"glossy-samples", .type = TB_OPT_INT, .dest = &glossy_samples, .min = 1, .max = 1024, .metavar = "N",
         .seen = &glossy_seen, .help = "rays sampled from a GGX lobe at a camera ray's hit (default %D; one deeper)"},
        {"texture-filter", .type = TB_OPT_CHOICE, .dest = &texture_filter, .choices = tex_filters, .seen = &tf_seen,
         .help = "image texture filter over the pixel footprint (default %D)"},
        {"passes", .type = TB_OPT_INT, .dest = &ro.passes, .min = 1, .max = 1 << 20, .metavar = "N",
         .help = "progressive passes of --spp samples each (default %D)"},
        {"time-budget", .type = TB_OPT_DOUBLE, .dest = &ro.time_budget, .min = 0, .max = INFINITY, .metavar = "S",
         .flags = TB_OPTF_OPEN_MIN, .help = "stop starting new tiles after S seconds"},
        {"exposure", .type = TB_OPT_DOUBLE, .dest = &exposure, .min = -INFINITY, .max = INFINITY, .metavar = "STOPS",
         .help = "PNG/RLE only: scale by 2^STOPS (default: mean luminance to 0.18)"},
        {"stats", .type = TB_OPT_STRING, .dest = &stats_path, .metavar = "FILE.json",
         .help = "counters, times and provenance"},
        {"sample-map", .type = TB_OPT_STRING, .dest = &map_path, .metavar = "F.pfm",
         .help = "each pixel's camera sample count (grey PFM; adaptive: where samples went)"},
        {"report", .type = TB_OPT_STRING, .dest = &report_path, .metavar = "FILE.csv",
         .help = "a row per pass: seconds, spp, relMSE against --reference IMG"},
        {"reference", .type = TB_OPT_STRING, .dest = &ref_path, .metavar = "IMG",
         .help = "the reference image of --report"},
        {0},
    };
    const tb_cli cli = {
        .prog = "testbed render",
        .err = "testbed render: ",
        .usage = "SCENE.mid -o OUT.{png,exr,pfm,rle} [options]",
        .opts = opts,
        .outro = "Ctrl-C writes the image rendered so far and exits with status 130.",
        .pos = &scene_path,
        .max_pos = 1,
    };
    int npos, prc = tb_cli_parse(&cli, argc, argv, &npos);
    if (prc != TB_CLI_OK)
        return prc;
    if (!scene_path)
        return tb_cli_usage_error(&cli, "no SCENE.mid given");
    if (!out_path)
        return tb_cli_usage_error(&cli, "no output given (-o OUT)");
    ro.aa.adaptive = ro.aa.adaptive || adaptive;
    ro.aa.criterion = (tb_aa_criterion)criterion;
    ro.aa.pattern = (tb_aa_pattern)pattern;
    if (depth_seen)
        ro.rt.max_depth = max_depth == 0 ? -1 : max_depth;
    if (light_seen)
        ro.rt.light_samples = light_samples;
    if (glossy_seen)
        ro.rt.glossy_samples = glossy_samples;
    if (tf_seen)
        ro.rt.texture_filter = texture_filter;
    tb_image_format fmt = tb_image_format_from_path(out_path);
    if (fmt == TB_IMAGE_UNKNOWN)
        return tb_cli_usage_error(&cli, "unknown image format of '%s' (.png, .exr, .pfm, .rle)", out_path);
    if (map_path && tb_image_format_from_path(map_path) != TB_IMAGE_PFM)
        return tb_cli_usage_error(&cli, "--sample-map writes a .pfm file, not '%s'", map_path);
    if (!report_path != !ref_path)
        return tb_cli_usage_error(&cli, "--report and --reference go together");
    tb_gpu_mode gmode = (tb_gpu_mode)backend;
    tb_accel_kind accel_kind = (tb_accel_kind)accel;

    int rc = TB_EXIT_FAIL;
    tb_scene *scene = NULL;
    tb_image *img = NULL, *ref = NULL, *map = NULL;
    tb__report rep = {0};
    tb_scene_options so = {.accel = accel_kind, .threads = ro.threads};
    if (tb_scene_load(scene_path, &so, &scene)) {
        fprintf(stderr, "testbed render: %s\n", tb_last_error());
        goto done;
    }
    if (ref_path) {
        if (tb_image_read(ref_path, NULL, &ref)) {
            fprintf(stderr, "testbed render: %s\n", tb_last_error());
            goto done;
        }
        rep.fp = fopen(report_path, "w");
        if (!rep.fp) {
            fprintf(stderr, "testbed render: cannot write '%s'\n", report_path);
            goto done;
        }
        fprintf(rep.fp, "seconds,spp,relmse\n");
        rep.reference = ref;
        rep.scene = scene;
        ro.on_pass = tb__report_pass;
        ro.on_pass_ctx = &rep;
    }
    struct sigaction sa, old_sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = tb__render_on_sigint;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old_sa);
    ro.cancel = &tb__render_interrupt;
    ro.progress = true;
    /* Tells a script that Ctrl-C now writes the partial image. */
    fprintf(stderr, "testbed render: rendering %s (Ctrl-C writes the image so far)\n", scene_path);
    tb_render_stats rs;
    if (map_path) {
        map = tb_image_create(scene->camera.width, scene->camera.height, 1, NULL);
        ro.sample_counts = map ? calloc((size_t)map->width * (size_t)map->height, sizeof *ro.sample_counts) : NULL;
        if (!ro.sample_counts) {
            fprintf(stderr, "testbed render: out of memory for --sample-map\n");
            sigaction(SIGINT, &old_sa, NULL);
            goto done;
        }
    }
    ro.rt.spp = ro.aa.spp; /* scales the texture footprints (docs/raytrace.md) */
    /* The Vulkan wavefront tracer (docs/gpu.md, "Shade kernel and wavefront
     * renderer"); auto falls back to the CPU path on any Vulkan failure. */
    tb_gpu_session gsess;
    tb_gpu_render_stats gs = {0};
    tb_status st = tb_gpu_backend_choose(gmode, gdevice, false, &gsess);
    if (st) {
        fprintf(stderr, "testbed render: %s\n", tb_last_error());
        sigaction(SIGINT, &old_sa, NULL);
        goto done;
    }
    fprintf(stderr, "testbed render: backend %s: %s\n", tb_gpu_backend_name(gsess.backend), gsess.reason);
    bool on_gpu = gsess.backend == TB_GPU_BACKEND_VULKAN;
    if (on_gpu) {
        st = tb_gpu_render_raytrace(gsess.device, scene, &ro, &img, &rs, &gs);
        if (st && gmode == TB_GPU_MODE_AUTO && gdevice < 0) {
            fprintf(stderr, "testbed render: the Vulkan renderer failed (%s); using the CPU path\n", tb_last_error());
            on_gpu = false;
        } else if (st) {
            fprintf(stderr, "testbed render: --backend %s: %s\n", tb_gpu_mode_name(gmode), tb_last_error());
            tb_gpu_session_close(&gsess);
            sigaction(SIGINT, &old_sa, NULL);
            goto done;
        }
    }
    tb_gpu_session_close(&gsess);
    if (!on_gpu)
        st = tb_render_raytrace(scene, &ro, &img, &rs);
    sigaction(SIGINT, &old_sa, NULL);
    bool sigint = atomic_load(&tb__render_interrupt) != 0;
    if (st || rep.failed) {
        if (st)
            fprintf(stderr, "testbed render: %s\n", tb_last_error());
        goto done;
    }

    /* Provenance in the image and the stats file. */
    tb_provenance prov;
    char **full = malloc(sizeof *full * ((size_t)argc + 2));
    if (!full) {
        fprintf(stderr, "testbed render: out of memory\n");
        goto done;
    }
    full[0] = "testbed";
    memcpy(full + 1, argv, sizeof *full * (size_t)argc);
    full[argc + 1] = NULL;
    st = tb_provenance_init(&prov, argc + 1, full);
    free(full);
    if (st) {
        fprintf(stderr, "testbed render: %s\n", tb_last_error());
        goto done;
    }
    int nthreads = ro.threads > 0 ? ro.threads : omp_get_max_threads();
    char popts[512];
    snprintf(popts, sizeof popts, "method=raytrace spp=%d passes=%d adaptive=%d filter=%s:%g accel=%s max_depth=%d "
             "light_samples=%d glossy_samples=%d threads=%d colour=%s backend=%s",
             ro.aa.spp, ro.passes, (int)ro.aa.adaptive, tb_filter_kind_name(ro.filter.kind), ro.filter.radius,
             tb_accel_kind_name(accel_kind), ro.rt.max_depth == 0 ? TB_RT_DEFAULT_MAX_DEPTH : (ro.rt.max_depth < 0 ? 0 : ro.rt.max_depth),
             ro.rt.light_samples ? ro.rt.light_samples : TB_RT_DEFAULT_LIGHT_SAMPLES,
             ro.rt.glossy_samples ? ro.rt.glossy_samples : TB_RT_DEFAULT_GLOSSY_SAMPLES, nthreads,
             scene->spectral ? "spectral" : "rgb", on_gpu ? "vulkan" : "cpu");
    tb_provenance_set_seed(&prov, ro.aa.seed);
    if (strcmp(scene_path, "-") != 0)
        st = tb_provenance_hash_file(&prov, scene_path);
    if (!st)
        st = tb_provenance_set_options(&prov, popts);
    if (!st)
        st = tb_provenance_to_attrs(&prov, img);
    if (!st && stats_path) {
        st = tb_stats_set_value("seconds", rs.seconds);
        if (!st)
            st = tb_stats_set_value("samples", (double)rs.aa.samples);
        if (!st && ro.aa.adaptive)
            st = tb_stats_set_value("pixels_refined", (double)rs.aa.pixels_refined);
        if (!st && ro.aa.adaptive)
            st = tb_stats_set_value("ring_samples", (double)rs.aa.ring_samples);
        if (!st && ro.aa.adaptive)
            st = tb_stats_set_value("max_spp_used", (double)rs.aa.max_spp_used);
        if (!st)
            st = tb_stats_set_value("passes", (double)rs.passes_done);
        if (!st)
            st = tb_stats_set_value("interrupted", rs.interrupted ? 1.0 : 0.0);
        if (!st)
            st = tb_stats_set_value("samples_per_second", rs.seconds > 0 ? (double)rs.aa.samples / rs.seconds : 0.0);
        if (!st && on_gpu) {
            st = tb_stats_set_value("gpu_shaded_hits", (double)gs.gpu_shaded);
            if (!st)
                st = tb_stats_set_value("cpu_routed_hits", (double)gs.cpu_shaded);
            if (!st)
                st = tb_stats_set_value("shadow_rays", (double)gs.shadow_rays);
            if (!st)
                st = tb_stats_set_value("waves", (double)gs.waves);
            if (!st)
                st = tb_stats_set_value("shade_kernel_seconds", gs.shade_seconds);
        }
        if (!st)
            st = tb_stats_write_json_file(stats_path, &prov);
    }
    tb_provenance_free(&prov);
    if (st) {
        fprintf(stderr, "testbed render: %s\n", tb_last_error());
        goto done;
    }

    tb_image_write_options wo = {0};
    if (fmt == TB_IMAGE_PNG || fmt == TB_IMAGE_RLE) {
        if (isnan(exposure)) {
            /* Automatic: the mean Rec. 709 luminance to 0.18. */
            double sum = 0.0;
            size_t npix = (size_t)img->width * (size_t)img->height;
            for (size_t k = 0; k < npix; k++) {
                const float *px = img->pixels + k * 3;
                sum += 0.2126 * px[0] + 0.7152 * px[1] + 0.0722 * px[2];
            }
            double mean = sum / (double)npix;
            exposure = mean > 0.0 ? log2(0.18 / mean) : 0.0;
        }
        wo.exposure = (float)exposure;
        char ex[64];
        snprintf(ex, sizeof ex, "%.6g", exposure);
        if (tb_image_set_attr(img, "exposure", ex)) {
            fprintf(stderr, "testbed render: %s\n", tb_last_error());
            goto done;
        }
    }
    if (tb_image_write(out_path, img, &wo)) {
        fprintf(stderr, "testbed render: %s\n", tb_last_error());
        goto done;
    }
    if (map) {
        for (size_t k = 0; k < (size_t)map->width * (size_t)map->height; k++)
            map->pixels[k] = (float)ro.sample_counts[k];
        if (tb_image_write(map_path, map, NULL)) {
            fprintf(stderr, "testbed render: %s\n", tb_last_error());
            remove(out_path);
            goto done;
        }
    }
    printf("testbed render: %s: %dx%d, %llu samples, %.3f s (%d threads, %s)%s; wrote %s\n", scene_path, img->width,
           img->height, (unsigned long long)rs.aa.samples, rs.seconds, nthreads, scene->spectral ? "spectral" : "rgb",
           rs.interrupted ? ", INTERRUPTED (partial image)" : "", out_path);
    if (on_gpu)
        printf("testbed render: vulkan: %llu hits shaded by the kernel, %llu routed to the CPU path%s%s%s, "
               "%llu shadow rays, %llu waves; wavefront %.3f s: intersect + occlusion %.3f s, shade %.3f s "
               "(kernel %.3f s), routed %.3f s\n",
               (unsigned long long)gs.gpu_shaded, (unsigned long long)gs.cpu_shaded,
               gs.routed_materials ? " (" : "", gs.routed_reason,
               gs.routed_materials ? (gs.routed_materials > 1 ? ", ...)" : ")") : "",
               (unsigned long long)gs.shadow_rays, (unsigned long long)gs.waves, gs.wave_seconds, gs.trace_seconds,
               gs.shade_wall_seconds, gs.shade_seconds, gs.cpu_seconds);
    rc = sigint ? 130 : TB_EXIT_OK;
done:
    if (rep.fp)
        fclose(rep.fp);
    tb_image_free(ref);
    tb_image_free(img);
    tb_image_free(map);
    free(ro.sample_counts);
    tb_scene_free(scene);
    return rc;
}
