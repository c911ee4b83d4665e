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

static void tb__render_usage(FILE *out)
{
    fprintf(out,
            "usage: testbed render SCENE.mid -o OUT.{png,exr,pfm,rle} [options]\n"
            "  --method M           raytrace (default: the Whitted ray tracer) or radiosity (options:\n"
            "                       testbed render --method radiosity --help)\n"
            "  --spp N              samples per pixel (per pass; default 1)\n"
            "  --adaptive [T]       adaptive antialiasing (--max-spp N, --aa-criterion stderr|contrast)\n"
            "  --aa-pattern P       stratified (default) | sobol\n"
            "  --filter K[:R[:S]]   box (default) | tent | gaussian | mitchell\n"
            "  --threads N          OpenMP threads (the image does not depend on it)\n"
            "  --seed N             sample seed (default 0)\n"
            "  --backend B          cpu (the reference), vulkan or auto (default auto): vulkan runs the\n"
            "                       wavefront tracer (intersect + shade kernels) on any Vulkan device,\n"
            "                       lavapipe included, and fails if there is none; auto uses it only on a\n"
            "                       real GPU and otherwise, or if the device fails, the CPU path (says why).\n"
            "                       Same image as cpu within docs/accuracy.md's tolerance; hits the kernel\n"
            "                       cannot shade (textures, patterns, bump, GGX) run on the CPU: reported\n"
            "  --device N           Vulkan device N (testbed devices lists them; implies Vulkan in auto)\n"
            "  --accel bvh|grid|list  acceleration structure (default bvh)\n"
            "  --max-depth N        deepest reflected/refracted ray (default %d)\n"
            "  --light-samples N    area-light samples per shading point (default %d)\n"
            "  --glossy-samples N   rays sampled from a GGX lobe at a camera ray's hit (default %d; one deeper)\n"
            "  --texture-filter bilinear|trilinear|ewa  image texture filter over the pixel footprint (default ewa)\n"
            "  --passes N           progressive passes of --spp samples each (default 1)\n"
            "  --time-budget S      stop starting new tiles after S seconds\n"
            "  --exposure STOPS     PNG/RLE only: scale by 2^STOPS (default: mean luminance to 0.18)\n"
            "  --stats FILE.json    counters, times and provenance\n"
            "  --sample-map F.pfm   each pixel's camera sample count (grey PFM; adaptive: where samples went)\n"
            "  --report FILE.csv    a row per pass: seconds, spp, relMSE against --reference IMG\n"
            "Ctrl-C writes the image rendered so far and exits with status 130.\n",
            TB_RT_DEFAULT_MAX_DEPTH, TB_RT_DEFAULT_LIGHT_SAMPLES, TB_RT_DEFAULT_GLOSSY_SAMPLES);
}

static int tb__render_fail(const char *fmt, const char *arg)
{
    fprintf(stderr, "testbed render: ");
    fprintf(stderr, fmt, arg);
    fprintf(stderr, "\n");
    return TB_EXIT_FAIL;
}

static bool tb__parse_long(const char *s, long lo, long hi, long *out)
{
    char *end;
    long v = strtol(s, &end, 10);
    if (end == s || *end || v < lo || v > hi)
        return false;
    *out = v;
    return true;
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
    if (tb_wants_help(argc, argv)) {
        tb__render_usage(stdout);
        return TB_EXIT_OK;
    }
    const char *scene_path = NULL, *out_path = NULL, *stats_path = NULL, *report_path = NULL, *ref_path = NULL;
    const char *map_path = NULL;
    tb_render_options ro = tb_render_defaults();
    tb_accel_kind accel = TB_ACCEL_BVH;
    double exposure = NAN;
    long v;
    const char *backend = "auto";
    int gdevice = -1;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int r = tb_aa_parse_arg(argc, argv, &i, &ro.aa, &ro.filter);
        if (r < 0) {
            fprintf(stderr, "testbed render: %s\n", tb_last_error());
            return TB_EXIT_USAGE;
        }
        if (r > 0)
            continue;
        bool has = i + 1 < argc;
        if (!strcmp(a, "-o") && has)
            out_path = argv[++i];
        else if (!strcmp(a, "--threads") && has && tb__parse_long(argv[i + 1], 0, 4096, &v))
            ro.threads = (int)v, i++;
        else if (!strcmp(a, "--seed") && has) {
            char *end;
            unsigned long long s = strtoull(argv[++i], &end, 10);
            if (*end || end == argv[i])
                return tb__render_fail("bad --seed '%s'", argv[i]), TB_EXIT_USAGE;
            ro.aa.seed = s;
        } else if (!strcmp(a, "--accel") && has) {
            if (tb_accel_kind_from_name(argv[++i], &accel))
                return tb__render_fail("%s", tb_last_error()), TB_EXIT_USAGE;
        } else if (!strcmp(a, "--method") && has) {
            if (strcmp(argv[++i], "raytrace") != 0)
                return tb__render_fail("unknown --method '%s' (raytrace, radiosity)", argv[i]), TB_EXIT_USAGE;
        } else if (!strcmp(a, "--max-depth") && has && tb__parse_long(argv[i + 1], 0, 64, &v))
            ro.rt.max_depth = v == 0 ? -1 : (int)v, i++;
        else if (!strcmp(a, "--light-samples") && has && tb__parse_long(argv[i + 1], 1, 1024, &v))
            ro.rt.light_samples = (int)v, i++;
        else if (!strcmp(a, "--glossy-samples") && has && tb__parse_long(argv[i + 1], 1, 1024, &v))
            ro.rt.glossy_samples = (int)v, i++;
        else if (!strcmp(a, "--texture-filter") && has) {
            const char *f = argv[++i];
            if (!strcmp(f, "bilinear"))
                ro.rt.texture_filter = 1;
            else if (!strcmp(f, "trilinear"))
                ro.rt.texture_filter = 2;
            else if (!strcmp(f, "ewa"))
                ro.rt.texture_filter = 3;
            else
                return tb__render_fail("unknown --texture-filter '%s' (bilinear, trilinear, ewa)", f), TB_EXIT_USAGE;
        }
        else if (!strcmp(a, "--passes") && has && tb__parse_long(argv[i + 1], 1, 1 << 20, &v))
            ro.passes = (int)v, i++;
        else if (!strcmp(a, "--time-budget") && has) {
            char *end;
            ro.time_budget = strtod(argv[++i], &end);
            if (*end || !(ro.time_budget > 0.0))
                return tb__render_fail("bad --time-budget '%s'", argv[i]), TB_EXIT_USAGE;
        } else if (!strcmp(a, "--exposure") && has) {
            char *end;
            exposure = strtod(argv[++i], &end);
            if (*end || !isfinite(exposure))
                return tb__render_fail("bad --exposure '%s'", argv[i]), TB_EXIT_USAGE;
        } else if (!strcmp(a, "--stats") && has)
            stats_path = argv[++i];
        else if (!strcmp(a, "--sample-map") && has)
            map_path = argv[++i];
        else if (!strcmp(a, "--backend") && has)
            backend = argv[++i];
        else if (!strcmp(a, "--device") && has && tb__parse_long(argv[i + 1], 0, 1024, &v))
            gdevice = (int)v, i++;
        else if (!strcmp(a, "--report") && has)
            report_path = argv[++i];
        else if (!strcmp(a, "--reference") && has)
            ref_path = argv[++i];
        else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "testbed render: bad or incomplete option '%s'\n", a);
            tb__render_usage(stderr);
            return TB_EXIT_USAGE;
        } else if (!scene_path)
            scene_path = a;
        else
            return tb__render_fail("unexpected argument '%s'", a), TB_EXIT_USAGE;
    }
    if (!scene_path || !out_path) {
        tb__render_usage(stderr);
        return TB_EXIT_USAGE;
    }
    tb_image_format fmt = tb_image_format_from_path(out_path);
    if (fmt == TB_IMAGE_UNKNOWN)
        return tb__render_fail("unknown image format of '%s' (.png, .exr, .pfm, .rle)", out_path), TB_EXIT_USAGE;
    if (map_path && tb_image_format_from_path(map_path) != TB_IMAGE_PFM)
        return tb__render_fail("--sample-map writes a .pfm file, not '%s'", map_path), TB_EXIT_USAGE;
    if (!report_path != !ref_path)
        return tb__render_fail("%s", "--report and --reference go together"), TB_EXIT_USAGE;
    tb_gpu_mode gmode;
    if (tb_gpu_mode_parse(backend, &gmode))
        return tb__render_fail("--backend must be cpu, vulkan or auto, not '%s'", backend), TB_EXIT_USAGE;

    int rc = TB_EXIT_FAIL;
    tb_scene *scene = NULL;
    tb_image *img = NULL, *ref = NULL, *map = NULL;
    tb__report rep = {0};
    tb_scene_options so = {.accel = accel, .threads = ro.threads};
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
            tb__render_fail("cannot write '%s'", report_path);
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
    char opts[512];
    snprintf(opts, sizeof opts, "method=raytrace spp=%d passes=%d adaptive=%d filter=%s:%g accel=%s max_depth=%d "
             "light_samples=%d glossy_samples=%d threads=%d colour=%s backend=%s",
             ro.aa.spp, ro.passes, (int)ro.aa.adaptive, tb_filter_kind_name(ro.filter.kind), ro.filter.radius,
             tb_accel_kind_name(accel), ro.rt.max_depth == 0 ? TB_RT_DEFAULT_MAX_DEPTH : (ro.rt.max_depth < 0 ? 0 : ro.rt.max_depth),
             ro.rt.light_samples ? ro.rt.light_samples : TB_RT_DEFAULT_LIGHT_SAMPLES,
             ro.rt.glossy_samples ? ro.rt.glossy_samples : TB_RT_DEFAULT_GLOSSY_SAMPLES, nthreads,
             scene->spectral ? "spectral" : "rgb", on_gpu ? "vulkan" : "cpu");
    tb_provenance_set_seed(&prov, ro.aa.seed);
    if (strcmp(scene_path, "-") != 0)
        st = tb_provenance_hash_file(&prov, scene_path);
    if (!st)
        st = tb_provenance_set_options(&prov, opts);
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
