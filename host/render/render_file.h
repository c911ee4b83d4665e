/* The whole ray-tracer workflow as one call: load a MID scene, render it
 * (progressive passes, antialiasing, time budget, cancel flag, optionally a
 * convergence report against a reference image and a per-pixel sample map)
 * and write the image with its provenance and, if asked, the stats JSON.
 * `testbed render` and tools/examples/render_file.c are thin layers over it
 * (docs/raytrace.md, "One call").
 *
 *     tb_render_file_options o = tb_render_file_defaults();
 *     o.render.aa.spp = 16;
 *     o.image_path = "out.exr";
 *     if (tb_render_file("scene.mid", &o, NULL)) die(tb_last_error());
 *
 * host/render may not use host/gpu: a caller that wants the Vulkan renderer
 * supplies it as `backend` (the command's calls tb_gpu_render_raytrace, or
 * with --method path tb_gpu_render_path). */
#ifndef TB_HOST_RENDER_RENDER_FILE_H
#define TB_HOST_RENDER_RENDER_FILE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "host/render/antialias.h"
#include "host/render/render.h"
#include "host/render/scene.h"
#include "util/base/error.h"
#include "util/image/image.h"

/* A renderer in place of the CPU path: renders `s` as tb_render_raytrace
 * would (options `o`, the call's own, already complete) into *out and
 * *stats. TB_OK with *out NULL hands the render to the CPU path (no device,
 * or a fallback); an error fails the call. */
typedef tb_status (*tb_render_backend_fn)(void *user, const tb_scene *s, const tb_render_options *o, tb_image **out,
                                          tb_render_stats *stats);

/* A CPU renderer that tb_render_file runs in place of the Whitted ray
 * tracer (the path tracer of pathtrace.h, the hybrid renderer of
 * host/hybrid): it prepares a per-sample function for the loaded scene,
 * which tb_render then drives. */
typedef struct tb_render_method {
    const char *name; /* the provenance's method= ("path", "hybrid") */
    /* Prepares the renderer for scene s and options o: sets *sample and *ctx
     * for tb_render and writes its own options ("key=value ...", for the
     * provenance) into desc[0 .. ndesc). */
    tb_status (*init)(void *user, const tb_scene *s, const tb_render_options *o, tb_aa_sample_fn *sample,
                      void **ctx, char *desc, size_t ndesc);
    /* Frees what init made (called once init succeeded, on every path). */
    void (*release)(void *user, void *ctx);
    /* Adds its own values to the stats JSON after the render's (NULL: none). */
    tb_status (*stats)(void *user, void *ctx);
    void *user; /* passed to the three functions */
} tb_render_method;

/* Adds the backend's own values to the stats JSON (tb_stats_set_value),
 * after the render's; called only when the backend made the image. */
typedef tb_status (*tb_render_backend_stats_fn)(void *user);

/* Called with `starting` true once the scene (and the reference) are loaded,
 * right before the render, and with false right after it, on every path:
 * e.g. to install and remove a SIGINT handler that sets render.cancel. */
typedef void (*tb_render_hook_fn)(void *user, bool starting);

/* What tb_render_file does; tb_render_file_defaults() gives the defaults. */
typedef struct tb_render_file_options {
    tb_render_options render;   /* passes, antialiasing, filter, threads, tracer, time budget, cancel, progress;
                                 * on_pass and sample_counts are replaced when report_path / sample_map_path
                                 * are given */
    tb_scene_options scene;     /* acceleration structure, colours; threads 0: render.threads */
    double exposure;            /* PNG/RLE image: stops; NAN: mean luminance to 0.18 */
    const char *image_path;     /* the image (.png .exr .pfm .rle); required */
    const char *stats_path;     /* counters, times and provenance as JSON, or NULL */
    const char *sample_map_path; /* each pixel's camera sample count as a grey .pfm, or NULL */
    const char *report_path;    /* a row seconds,spp,relmse per pass against reference_path, or NULL */
    const char *reference_path; /* the reference image of report_path */
    int argc;                   /* the command line recorded in the provenance (argv[0]: the program) */
    char **argv;                /* NULL: an empty command line */
    const tb_render_method *method; /* NULL: the Whitted ray tracer (tb_render_raytrace) */
    tb_render_backend_fn backend; /* NULL: the CPU path; with a method it must render that method */
    tb_render_backend_stats_fn backend_stats; /* NULL: none */
    void *backend_user;
    const char *backend_name;   /* the provenance's backend= when the backend made the image ("vulkan") */
    tb_render_hook_fn on_render; /* NULL: none */
    void *on_render_user;
} tb_render_file_options;

/* What tb_render_file did. */
typedef struct tb_render_file_result {
    tb_render_stats stats; /* samples, passes, seconds; interrupted: some tiles skipped (partial image) */
    int width, height;     /* of the image */
    int threads;           /* OpenMP threads used */
    bool spectral;         /* spectral bands, else RGB */
    bool backend;          /* the backend made the image (else the CPU path) */
} tb_render_file_result;

/* The defaults: tb_render_defaults(), a BVH, automatic exposure, the CPU
 * path, no outputs (set image_path). */
tb_render_file_options tb_render_file_defaults(void);

/* Loads the scene at scene_path ("-": standard input), renders it as `opt`
 * says and writes the image (with provenance attributes), the sample map and
 * the stats; the report rows are written as the passes finish. An
 * interrupted render (cancel, time budget) still writes what it has and
 * returns TB_OK (out->stats.interrupted). TB_ERR_ARG for options that do not
 * fit (no image, unknown formats, a report without its reference, a
 * backend with a method); the
 * loader's, renderer's, backend's and writers' errors. `out` (may be NULL)
 * is filled on success. */
tb_status tb_render_file(const char *scene_path, const tb_render_file_options *opt, tb_render_file_result *out);

#endif
