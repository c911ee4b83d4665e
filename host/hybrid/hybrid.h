/* The hybrid radiosity + ray-tracing renderer (docs/hybrid.md), two passes
 * in the manner of Wallace, Cohen and Greenberg (1987) and Sillion and
 * Puech (1989):
 *   1. radiosity (host/radiosity): the view-independent diffuse
 *      interreflection, solved on a mesh of the scene;
 *   2. the Whitted ray tracer (host/render/raytrace.h) from the eye:
 *      specular reflection and refraction, direct light by shadow rays, and
 *      at every diffuse hit the INDIRECT diffuse light of the solution
 *      through the tracer's indirect callback, so no light is counted twice.
 *
 *     tb_hybrid *h;
 *     tb_hybrid_options ho = tb_hybrid_defaults();
 *     if (tb_hybrid_create(scene, &ho, &h)) die(tb_last_error());   // meshes and solves
 *     tb_render_options ro = tb_render_defaults();
 *     tb_image *img;
 *     if (tb_render_hybrid(h, &ro, &img, NULL)) die(tb_last_error());
 *     tb_hybrid_free(h);
 *
 * Deterministic for any thread count, as both passes are. */
#ifndef TB_HOST_HYBRID_HYBRID_H
#define TB_HOST_HYBRID_HYBRID_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "host/radiosity/locate.h"
#include "host/radiosity/radiosity.h"
#include "host/render/raytrace.h"
#include "host/render/render.h"
#include "host/render/render_file.h"
#include "host/render/scene.h"
#include "util/base/error.h"

/* Default gather rays per diffuse hit (mode TB_HYBRID_GATHER). */
#define TB_HYBRID_DEFAULT_GATHER_RAYS 16
/* The most gather rays per diffuse hit. */
#define TB_HYBRID_MAX_GATHER_RAYS 1024

/* Where the indirect diffuse light at a diffuse hit comes from. */
typedef enum tb_hybrid_mode {
    TB_HYBRID_INTERPOLATED = 0, /* the solution's irradiance at the hit minus its direct part, interpolated */
    TB_HYBRID_GATHER,           /* one-bounce final gather: rays reading the reflected radiosity B - E */
} tb_hybrid_mode;

/* What the hybrid does; tb_hybrid_defaults() gives the defaults. */
typedef struct tb_hybrid_options {
    tb_hybrid_mode mode;       /* indirect light by interpolation or by final gather */
    int gather_rays;           /* gather: cosine-distributed, stratified rays per diffuse hit (0: the default) */
    tb_rad_mesh_options mesh;  /* element size; used as given if mesh_given */
    bool mesh_given;           /* false: tb_rad_default_mesh_options(scene) (the radiosity command's default) */
    tb_rad_options solver;     /* form factors, samples per shooter, seed (lights are the scene's) */
    tb_rad_stop stop;          /* when the radiosity pass stops shooting (threshold, time budget) */
    FILE *log;                 /* one line about the radiosity pass, or NULL */
    const char *log_prefix;    /* starts the log line */
} tb_hybrid_options;

/* What the radiosity pass did. */
typedef struct tb_hybrid_stats {
    size_t elements, vertices; /* of the mesh */
    uint64_t shots;            /* of the full solution */
    uint64_t direct_shots;     /* of the direct-only solve (the emitters' and lights' first shots) */
    double mesh_seconds;       /* meshing the scene (0 for a given mesh) */
    double solve_seconds;      /* shooting the full solution */
    double direct_seconds;     /* shooting the direct-only solution (mode interpolated) */
    double unshot_fraction;    /* left unshot by the full solution (its ambient term stands for it) */
} tb_hybrid_stats;

/* The hybrid's radiosity pass (opaque): read-only once made, shareable by threads. */
typedef struct tb_hybrid tb_hybrid;

/* Interpolated mode, a mesh of the scene's default size, the radiosity
 * command's solver defaults (ray-cast form factors, threshold
 * TB_RAD_DEFAULT_THRESHOLD). */
tb_hybrid_options tb_hybrid_defaults(void);

/* The radiosity pass over `scene` (which must outlive the hybrid): meshes
 * it, solves the full solution and, in interpolated mode, the direct-only
 * one (docs/hybrid.md). TB_ERR_ARG for bad options; the mesher's and
 * solver's errors. */
tb_status tb_hybrid_create(const tb_scene *scene, const tb_hybrid_options *opt, tb_hybrid **out);

/* tb_hybrid_create over a mesh the caller made (e.g. finer, or with other
 * reflectances; copied): it must be of `scene`'s objects (elements carry
 * their top-level object index) and channels. */
tb_status tb_hybrid_create_from_mesh(const tb_scene *scene, const tb_rad_mesh *mesh, const tb_hybrid_options *opt,
                                     tb_hybrid **out);

/* Frees a hybrid; NULL is allowed. */
void tb_hybrid_free(tb_hybrid *h);

/* The full radiosity solution. */
const tb_rad_solver *tb_hybrid_solver(const tb_hybrid *h);

/* The direct-only solution (the same mesh with reflectance 0: only the
 * emitters' and lights' first shots), or NULL in gather mode. */
const tb_rad_solver *tb_hybrid_direct_solver(const tb_hybrid *h);

/* The hit -> element locator over the solution's mesh. */
const tb_rad_locator *tb_hybrid_locator(const tb_hybrid *h);

/* What the radiosity pass did. */
tb_hybrid_stats tb_hybrid_get_stats(const tb_hybrid *h);

/* What one ray gathers from the solution, in radiosity units (pi times
 * radiance), out[0 .. nchannels): the reflected radiosity B - E of the
 * element it lands on (front sides; emission left out), plus what mirrors
 * and smooth dielectrics send along it (docs/hybrid.md, "Two modes").
 * Zeros for a miss. */
void tb_hybrid_gather_ray(const tb_hybrid *h, const tb_ray *ray, double *out);

/* The tracer's indirect callback (tb_rt_indirect_fn) with ctx a tb_hybrid:
 * the indirect diffuse irradiance at q as the hybrid's mode computes it. */
tb_channels tb_hybrid_indirect(void *ctx, const tb_rt_indirect_query *q, tb_rng *rng);

/* A Whitted ray tracer with options `rt` (NULL: defaults) whose indirect
 * callback is the hybrid's: its per-sample function is tb_rt_sample with
 * ctx = out. Release it with tb_rt_release before freeing the hybrid. */
tb_status tb_hybrid_tracer_init(const tb_hybrid *h, const tb_rt_options *rt, tb_raytracer *out);

/* Renders the hybrid's scene through tb_render (tiles, threads, passes,
 * time budget as `o` says; o->rt are the tracer's options, its indirect
 * callback replaced by the hybrid's) into *out (linear sRGB). */
tb_status tb_render_hybrid(const tb_hybrid *h, const tb_render_options *o, tb_image **out, tb_render_stats *stats);

/* What tb_hybrid_method's renderer keeps between its calls: the options in,
 * the radiosity pass's figures out. */
typedef struct tb_hybrid_method_state {
    tb_hybrid_options opt; /* the radiosity pass and the mode */
    tb_hybrid_stats stats; /* filled once tb_render_file has run init */
} tb_hybrid_method_state;

/* The hybrid as a renderer tb_render_file runs in place of the ray tracer
 * (render_file.h): init makes the radiosity pass of the loaded scene and
 * the tracer, release frees them, stats adds the radiosity pass's figures to
 * the stats JSON. `state` must outlive the tb_render_file call. */
tb_render_method tb_hybrid_method(tb_hybrid_method_state *state);

#endif
