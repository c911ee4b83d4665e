/* The Vulkan ray tracer: a wavefront version of the CPU Whitted tracer
 * (host/render/raytrace.h) built on the intersect kernel (intersect.h) and
 * the shade kernel (shaders/shade.comp); docs/gpu.md, "Shade kernel and
 * wavefront renderer".
 *
 * Each wave takes, for every sample still active, the ray on top of that
 * sample's stack (camera ray first), intersects all of them with
 * tb_gpu_intersect, shades the hits with the shade kernel (emission, delta
 * lights, area-light samples, mirror and refracted rays), traces the shadow
 * rays with tb_gpu_occluded, adds the unblocked contributions and pushes the
 * secondary rays (refracted first, so the mirror ray is taken next). Taking
 * the top of each sample's stack visits a sample's rays in the CPU path's
 * depth-first order, so the light samples drawn on the host from the
 * sample's own stream (tb_aa_sample_rng) are exactly the CPU path's numbers:
 * the images agree sample by sample up to float rounding and the rare rays
 * whose hit differs between the float and the double intersection.
 *
 * Hits the kernel cannot shade are ROUTED to the CPU path with their whole
 * subtree (tb_rt_radiance with the same stream): those on a material whose
 * shading features (host/render/features.h) include one outside
 * TB_GPU_SHADE_FEATURES, e.g. image bump maps, colours black in some places
 * only, image textures in spectral scenes, or diffuse and GGX materials lit
 * by emitters the kernel does not sample (custom, two-sided spheres). They
 * are counted in tb_gpu_render_stats and reported by
 * `testbed render --backend vulkan`.
 *
 *     tb_gpu_renderer *r;
 *     if (tb_gpu_renderer_create(dev, scene, &rt_options, &r)) die(tb_last_error());
 *     tb_gpu_radiance(r, rays, rngs, n, out);     (= tb_rt_radiance per ray)
 *     tb_gpu_renderer_destroy(r);
 *     tb_gpu_render_raytrace(dev, scene, &render_options, &img, &rs, &gs);
 *
 * Used from one thread at a time (the device's command buffer). */
#ifndef TB_HOST_GPU_RENDER_H
#define TB_HOST_GPU_RENDER_H

#include <stddef.h>
#include <stdint.h>

#include "host/gpu/gpu.h"
#include "host/gpu/intersect.h"
#include "host/render/features.h"
#include "host/render/render.h"
#include "host/render/scene.h"
#include "util/math/rng.h"

/* The shading features the shade kernel implements (host/render/features.h);
 * a material with any other is routed to the CPU path. Image textures are
 * dropped from it for a scene whose images exceed the device's
 * storage-buffer limit. */
#define TB_GPU_SHADE_FEATURES                                                                                  \
    ((uint32_t)(TB_FEAT_TEXTURE | TB_FEAT_DIFFUSE | TB_FEAT_SPECULAR | TB_FEAT_TRANSMISSION | TB_FEAT_EMISSION |  \
                TB_FEAT_BLINN | TB_FEAT_GGX | TB_FEAT_PATTERN_CHECKER | TB_FEAT_PATTERN_NOISE |                  \
                TB_FEAT_BUMP_NOISE | TB_FEAT_LIT_TRIANGLE | TB_FEAT_LIT_PARALLELOGRAM | TB_FEAT_LIT_DISC |       \
                TB_FEAT_LIT_SPHERE))

/* Why a material with shading features `features` is not shaded by a kernel
 * supporting `supported` (a short phrase for the first unsupported feature
 * in TB_FEATURES order), or NULL when it is shaded there. */
const char *tb_gpu_route_reason(uint32_t features, uint32_t supported);

/* What the wavefront did (summed over calls on one renderer). */
typedef struct tb_gpu_render_stats {
    uint64_t samples;      /* camera samples (tb_gpu_render_raytrace) */
    uint64_t rays;         /* camera and secondary rays intersected on the device */
    uint64_t shadow_rays;  /* shadow rays traced by the occlusion kernel */
    uint64_t gpu_shaded;   /* hits shaded by the shade kernel */
    uint64_t cpu_shaded;   /* hits routed to the CPU path (with their subtrees) */
    uint64_t waves;        /* intersect -> shade -> occlude rounds */
    double shade_seconds;  /* device time of the shade kernel (NaN without timestamps) */
    double trace_seconds;  /* host wall time in tb_gpu_intersect and tb_gpu_occluded */
    double cpu_seconds;    /* host wall time shading routed hits */
    double shade_wall_seconds; /* host wall time of the shade dispatches with their uploads and downloads */
    double wave_seconds;   /* host wall time of the whole wavefront (all of the above and the host's own work) */
    int routed_materials;  /* materials the kernel does not shade */
    char routed_reason[256]; /* the first routed material and why ("" if none) */
} tb_gpu_render_stats;

/* A scene prepared for the wavefront (opaque). */
typedef struct tb_gpu_renderer tb_gpu_renderer;

/* Uploads the scene's geometry (tb_gpu_scene_create), lights, emitters and
 * materials to `dev` and prepares the CPU tracer used for routed hits
 * (options as tb_rt_init) into *out. TB_ERR_DEVICE, TB_ERR_NOMEM, or the
 * tracer's errors; *out is NULL on failure. */
tb_status tb_gpu_renderer_create(tb_gpu_device *dev, const tb_scene *scene, const tb_rt_options *opt,
                                 tb_gpu_renderer **out);

/* Frees the renderer; NULL is ignored. */
void tb_gpu_renderer_destroy(tb_gpu_renderer *r);

/* Why the kernel does not shade material m of the renderer's scene (a short
 * phrase), or NULL when it does. */
const char *tb_gpu_renderer_material_route(const tb_gpu_renderer *r, int m);

/* Radiance along each of rays[0..n) (scene channels, out[i * nchannels ..]):
 * what tb_rt_radiance(rt, &rays[i], &rngs[i]) gives, within float
 * tolerance, drawing the same numbers from rngs[i] (advanced as the CPU
 * path would). */
tb_status tb_gpu_radiance(tb_gpu_renderer *r, const tb_ray *rays, tb_rng *rngs, size_t n, float *out);

/* The stats so far. */
void tb_gpu_renderer_stats(const tb_gpu_renderer *r, tb_gpu_render_stats *out);

/* tb_render_raytrace on the device: the same tiles, sample positions,
 * per-sample streams, filter and merge order as the CPU path, radiance from
 * the wavefront. Adaptive antialiasing makes the CPU path's decisions in
 * rounds (the criterion on the host from the kernel's values; a value at the
 * threshold can decide otherwise: docs/accuracy.md). `stats` and `gstats`
 * may be NULL. */
tb_status tb_gpu_render_raytrace(tb_gpu_device *dev, const tb_scene *s, const tb_render_options *o,
                                 tb_image **out, tb_render_stats *stats, tb_gpu_render_stats *gstats);

#endif
