/* The whole radiosity workflow as one call: load a MID scene, mesh it,
 * solve (one or two levels, optionally adaptive, against a time budget,
 * optionally writing a convergence report) and write the requested outputs
 * (image, patches CSV, vertex-coloured mesh, stats). `testbed render
 * --method radiosity` and tools/examples/radiosity.c are thin layers over
 * it (docs/radiosity.md, "One call"). */
#ifndef TB_HOST_RADIOSITY_RENDER_H
#define TB_HOST_RADIOSITY_RENDER_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "host/radiosity/adaptive.h"
#include "host/radiosity/radiosity.h"

/* Called once after meshing, before the solver is made: may install a
 * form-factor batch backend (opt->batch, opt->batch_ctx), e.g. the Vulkan
 * kernel, whose context the caller frees after tb_rad_render returns. */
typedef tb_status (*tb_rad_backend_fn)(void *user, const tb_rad_mesh *mesh, tb_rad_options *opt);

/* Saving and restoring a solve (checkpoints, host/dist/checkpoint.h). A
 * saved state is the solver's (tb_rad_solver_pack) and, with adaptive
 * subdivision, the refinement's own ahead of it (`extra`: the rounds done
 * and the elements each marked, from which the mesh is rebuilt). */
typedef struct tb_rad_persist {
    void *ctx; /* passed to both */
    /* Before the solve: the saved state, if any (*found), the same on every
     * process: *extra and *state (malloc'd, the caller frees them; *extra
     * NULL and *extra_len 0 when there is none). NULL: always a new solve. */
    tb_status (*load)(void *ctx, bool *found, void **extra, size_t *extra_len, void **state, size_t *state_len);
    /* After each shot (its own schedule, e.g. every N seconds) and with
     * `last` after the final one: may save `extra` (extra_len bytes; may be
     * NULL, 0) and the solver's state; `shots`: shots of the whole solve so
     * far (all rounds). Called on every process. NULL: never. An error stops
     * the solve. */
    tb_status (*save)(void *ctx, const tb_rad_solver *s, const void *extra, size_t extra_len, uint64_t shots,
                      bool last);
} tb_rad_persist;

/* What tb_rad_render does; tb_rad_render_defaults() gives the defaults. */
typedef struct tb_rad_render_options {
    tb_rad_options solver;     /* form factors, samples, seed (lights are the scene's, set by the call) */
    tb_rad_mesh_options mesh;  /* element and patch sizes, used as given if mesh_given */
    bool mesh_given;           /* false: tb_rad_default_mesh_options(scene) with mesh.patch_edge/patch_area */
    tb_rad_stop stop;          /* when to stop shooting */
    tb_rad_adapt_options adapt; /* adapt.threshold > 0: adaptive subdivision (tb_rad_adapt_solve) */
    int threads;               /* OpenMP threads; 0: the default (the answer does not depend on it) */
    int spp;                   /* image: rays per pixel on a regular sub-grid */
    double exposure;           /* PNG/RLE image: stops; NAN: mean luminance to 0.18 */
    const char *image_path;    /* the solution from the scene camera (.png .exr .pfm .rle), or NULL */
    const char *patches_path;  /* one CSV row per element (tb_rad_write_patches), or NULL */
    const char *mesh_path;     /* vertex-coloured mesh (.ply .gltf .glb), or NULL */
    const char *stats_path;    /* counters, times and provenance as JSON, or NULL */
    const char *report_path;   /* convergence rows against reference_path (not with adapt), or NULL */
    const char *reference_path; /* a patches CSV of the same mesh, with report_path */
    int argc;                  /* the command line recorded in the provenance (argv[0]: the program) */
    char **argv;
    tb_rad_backend_fn backend; /* NULL: form factors on the CPU */
    void *backend_user;
    const char *backend_name;  /* recorded in the provenance when backend installed a batch ("vulkan") */
    FILE *log;                 /* progress lines (mesh size, lights, rounds), or NULL for none */
    const char *log_prefix;    /* starts every log line ("testbed render: ") */
    const tb_rad_persist *persist; /* NULL: no checkpoints */
} tb_rad_render_options;

/* What tb_rad_render did. */
typedef struct tb_rad_render_result {
    size_t elements;        /* of the final (adapted) mesh */
    size_t vertices;
    uint64_t shots;         /* all of them, adaptive rounds included */
    double seconds;         /* wall seconds shooting (all rounds) */
    double unshot_fraction; /* unshot over emitted power at the end */
    int threads;            /* OpenMP threads used */
    bool spectral;          /* spectral bands, else RGB */
    bool batch;             /* form factors went through the backend's batch function */
} tb_rad_render_result;

/* The defaults: ray-cast form factors, default mesh, threshold
 * TB_RAD_DEFAULT_THRESHOLD, 4 rays per pixel, automatic exposure, no
 * outputs (set at least one path). */
tb_rad_render_options tb_rad_render_defaults(void);

/* Loads the scene at scene_path ("-": standard input), solves it as `opt`
 * says and writes the outputs, each whole or not at all. TB_ERR_ARG for
 * options that do not fit (nothing to write, unknown formats, an image of a
 * scene without a camera, a reference of another mesh); the loader's,
 * solver's and writers' errors. `out` (may be NULL) is filled on success. */
tb_status tb_rad_render(const char *scene_path, const tb_rad_render_options *opt, tb_rad_render_result *out);

#endif
