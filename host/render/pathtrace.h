/* The unidirectional path tracer (docs/pathtrace.md): the ground truth the
 * other renderers are compared with. From each camera ray a path bounces
 * off the composite BSDF of every surface it meets (surface.h: Lambert,
 * normalised Phong, exact Blinn, GGX sampled from its visible normals,
 * smooth dielectric, with textures, patterns and bump maps), taking at each
 * non-specular vertex next-event estimation from every point, spot,
 * directional and IES light and one sample of the area light of all
 * emitters (triangles, polygons, analytic primitives, CSG objects), that
 * sample and the emission BSDF-sampled rays find weighted by the power
 * heuristic. Russian roulette ends paths after a few bounces without bias;
 * a hard cap of TB_PT_MAX_BOUNCES bounces only stops runaway paths.
 * Spectral and RGB scenes; deterministic for a seed, for any thread count
 * (tb_render's per-sample streams).
 *
 *     tb_pathtracer *pt;
 *     if (tb_pt_create(scene, NULL, &pt)) die(tb_last_error());
 *     tb_channels L = tb_pt_radiance(pt, &ray, &rng);
 *     tb_pt_free(pt);
 *
 * or the whole render: tb_render_path(scene, NULL, &ro, &img, NULL), or
 * tb_render_file with tb_pt_method (`testbed render --method path`). */
#ifndef TB_HOST_RENDER_PATHTRACE_H
#define TB_HOST_RENDER_PATHTRACE_H

#include <stdint.h>

#include "host/render/channels.h"
#include "host/render/render.h"
#include "host/render/render_file.h"
#include "host/render/scene.h"
#include "host/render/surface.h"
#include "util/base/error.h"
#include "util/image/image.h"
#include "util/math/ray.h"
#include "util/math/rng.h"

/* Bounces before Russian roulette starts (tb_pt_options.rr_depth 0). */
#define TB_PT_DEFAULT_RR_DEPTH 3
/* Hard cap on the bounces of any path: under Russian roulette only paths
 * between surfaces of albedo 1 get near it (docs/pathtrace.md). */
#define TB_PT_MAX_BOUNCES 1024

/* Path tracer options; a zeroed struct (or NULL) means the defaults. */
typedef struct tb_pt_options {
    int max_depth;      /* most bounces (1: direct light only); 0: no cap but TB_PT_MAX_BOUNCES (Russian roulette) */
    int rr_depth;       /* bounces before Russian roulette (0: TB_PT_DEFAULT_RR_DEPTH) */
    int texture_filter; /* image texture filter, a tb_tex_filter of host/render/texture.h (0: EWA) */
    int spp;            /* camera samples per pixel: scales the texture footprint as the ray tracer's (0: 1) */
} tb_pt_options;

/* A path tracer over a loaded scene (read-only once created, shareable by threads). */
typedef struct tb_pathtracer tb_pathtracer;

/* One path in flight: everything a bounce needs, plain values only (no
 * pointers), so a wavefront or GPU renderer can keep paths in buffers. */
typedef struct tb_pt_path {
    tb_ray ray;           /* the ray to trace next */
    tb_channels beta;     /* throughput: product of BSDF weights / roulette probabilities so far */
    tb_channels L;        /* radiance gathered so far */
    tb_vec3 prev_p;       /* the vertex the ray left (for the emitter's sampling density) */
    double prev_pdf;      /* solid-angle density of the ray's direction from the BSDF (MIS) */
    int depth;            /* bounces so far (camera ray: 0) */
    uint8_t prev_delta;   /* the ray left a delta lobe (or is the camera ray): emission counts fully */
    uint8_t done;         /* the path has ended */
} tb_pt_path;

/* `o` (NULL: defaults) checked and with its defaults filled in, into *out
 * (the GPU path tracer takes the same options). TB_ERR_ARG for negative
 * depths or depths beyond TB_PT_MAX_BOUNCES, negative spp. */
tb_status tb_pt_options_resolve(const tb_pt_options *o, tb_pt_options *out);

/* Prepares a path tracer for `s` (which must stay alive). TB_ERR_ARG for a
 * scene without an acceleration structure or bad options (negative depths,
 * unknown texture filter). */
tb_status tb_pt_create(const tb_scene *s, const tb_pt_options *o, tb_pathtracer **out);

/* Frees it; NULL is allowed. */
void tb_pt_free(tb_pathtracer *pt);

/* The options in effect (defaults filled in). */
tb_pt_options tb_pt_get_options(const tb_pathtracer *pt);

/* The path tracer's surfaces (materials made ready to shade). */
const tb_surfaces *tb_pt_surfaces(const tb_pathtracer *pt);

/* The path tracer's light set (next-event estimation and MIS densities). */
const tb_light_set *tb_pt_lights(const tb_pathtracer *pt);

/* Starts a path along `ray` (throughput 1, nothing gathered). */
tb_pt_path tb_pt_path_start(const tb_pathtracer *pt, const tb_ray *ray);

/* Advances the path by one vertex: the hit's emission (MIS-weighted), the
 * next-event estimates there, and the next ray (or done). rd: the camera
 * ray's offset rays {rx_o, rx_d, ry_o, ry_d} for the texture footprint of
 * the first hit (used at depth 0 only), or NULL. */
void tb_pt_path_step(const tb_pathtracer *pt, tb_pt_path *path, const tb_vec3 *rd, tb_rng *rng);

/* Radiance arriving along -ray->d at ray->o (scene channels), one path. */
tb_channels tb_pt_radiance(const tb_pathtracer *pt, const tb_ray *ray, tb_rng *rng);

/* A tb_aa_sample_fn (host/render/antialias.h): ctx is a tb_pathtracer; the
 * camera ray of film point (x, y) (pinhole, or the lens point from rng),
 * radiance written to out[0 .. scene->nchannels). */
void tb_pt_sample(void *ctx, double x, double y, tb_rng *rng, float *out);

/* Renders `s` with the path tracer (options po, NULL: defaults) through
 * tb_render (tiles, threads, passes, time budget, cancel as `o` says; o->rt
 * is ignored) into *out (linear sRGB). */
tb_status tb_render_path(const tb_scene *s, const tb_pt_options *po, const tb_render_options *o, tb_image **out,
                         tb_render_stats *st);

/* The path tracer as a renderer tb_render_file runs (render_file.h), method
 * name "path"; `po` (NULL: defaults) must outlive the tb_render_file call.
 * spp 0 in po takes the render's samples per pixel. */
tb_render_method tb_pt_method(const tb_pt_options *po);

#endif
