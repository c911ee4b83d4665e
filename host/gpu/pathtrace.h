/* The Vulkan path tracer (`testbed render --method path --backend vulkan`;
 * docs/gpu.md, "Path tracer"): a wavefront over device buffers
 * (shaders/pathtrace.comp, layouts in shaders/shared/pathtrace.h) that
 * computes the CPU path tracer's radiance (host/render/pathtrace.h) for the
 * scenes whose materials and lights it implements: the composite BSDF's
 * Lambert, Phong, Blinn, GGX and smooth dielectric lobes, emission, point,
 * spot, directional and area lights, CSG trees, checker and noise patterns
 * and noise bump maps on spheres, cubes and polygons. The path state stays on the
 * device; the host records init, then extend -> shade -> shadow per bounce,
 * TB_GPU_PT_BOUNCES_PER_SUBMIT bounces to a command buffer, and reads back
 * one word (the live paths) between command buffers, not per bounce.
 * Statistically equal to the CPU path tracer, not sample by sample (another
 * random stream, the same estimator: see lib/pathtrace.glsl); tests/gpu/pt_equivalence.c
 * tests that per pixel.
 *
 *     const char *why = tb_gpu_pt_unsupported(scene);   (NULL: the kernel takes it)
 *     tb_gpu_render_path(dev, scene, &pt_options, &render_options, &img, &rs, &gs);
 *
 * Used from one thread at a time (the device's command buffer). */
#ifndef TB_HOST_GPU_PATHTRACE_H
#define TB_HOST_GPU_PATHTRACE_H

#include <stddef.h>
#include <stdint.h>

#include "host/gpu/gpu.h"
#include "host/render/pathtrace.h"
#include "host/render/render.h"
#include "host/render/scene.h"
#include "util/math/ray.h"

/* Bounces recorded into one command buffer between reads of the live count. */
#define TB_GPU_PT_BOUNCES_PER_SUBMIT 8

/* What the Vulkan path tracer did (summed over calls on one tracer). */
typedef struct tb_gpu_pt_stats {
    uint64_t paths;       /* camera paths traced */
    uint64_t submits;     /* command buffers submitted (each up to TB_GPU_PT_BOUNCES_PER_SUBMIT bounces) */
    uint64_t bounces;     /* bounce rounds recorded (extend + shade + shadow) */
    uint64_t dispatches;  /* kernel dispatches */
    double kernel_seconds; /* device time of all dispatches (NaN without timestamps) */
    double wall_seconds;  /* host wall time in tb_gpu_pt_radiance (uploads, submits, downloads) */
} tb_gpu_pt_stats;

/* Why the kernel cannot render `s` (a phrase naming the first missing
 * feature: a texture, an image bump map, a pattern on a kind whose (u, v) is
 * not ported, an IES light, more than 31 delta
 * lights, an emitter kind, an emitting CSG object), or NULL when it can. */
const char *tb_gpu_pt_unsupported(const tb_scene *s);

/* A scene prepared for the device path tracer (opaque). */
typedef struct tb_gpu_pathtracer tb_gpu_pathtracer;

/* Uploads the scene's geometry (tb_gpu_scene_create), materials and emitters
 * to `dev` (options as tb_pt_create; NULL: defaults) into *out.
 * TB_ERR_UNSUPPORTED with tb_gpu_pt_unsupported's reason for a scene the
 * kernel does not take; TB_ERR_ARG for bad options; TB_ERR_DEVICE,
 * TB_ERR_NOMEM. *out is NULL on failure. */
tb_status tb_gpu_pt_create(tb_gpu_device *dev, const tb_scene *s, const tb_pt_options *o, tb_gpu_pathtracer **out);

/* Frees it; NULL is ignored. */
void tb_gpu_pt_destroy(tb_gpu_pathtracer *pt);

/* One path per ray: the radiance along rays[i] (scene channels, out[i *
 * nchannels ..]) with the device stream seeded by seeds[2 i], seeds[2 i + 1].
 * An unbiased estimate of what tb_pt_radiance estimates. */
tb_status tb_gpu_pt_radiance(tb_gpu_pathtracer *pt, const tb_ray *rays, const uint32_t *seeds, size_t n,
                             float *out);
/* tb_gpu_pt_radiance with the camera rays' offset rays rx[i], ry[i] (of the
 * film points one pixel along x and y; NULL: none), from which patterns are
 * filtered over the first hit's footprint, as tb_pt_sample does. */
tb_status tb_gpu_pt_radiance_diff(tb_gpu_pathtracer *pt, const tb_ray *rays, const tb_ray *rx, const tb_ray *ry,
                                  const uint32_t *seeds, size_t n, float *out);

/* The surface at the first hit of each ray as the shade stage sees it, for
 * tests against tb_surface_at: per ray 5 + 2 nchannels floats at out[i *
 * (5 + 2 nch)]: the hit's (u, v), the shading normal (bump-mapped, on the
 * ray's side), the diffuse and the specular colours (patterns applied); NaN
 * for a miss. rx, ry as tb_gpu_pt_radiance_diff (NULL: none). At least 3
 * channels. */
tb_status tb_gpu_pt_surfaces(tb_gpu_pathtracer *pt, const tb_ray *rays, const tb_ray *rx, const tb_ray *ry, size_t n,
                             float *out);

/* The stats so far. */
void tb_gpu_pt_get_stats(const tb_gpu_pathtracer *pt, tb_gpu_pt_stats *out);

/* tb_render_path on the device: the same tiles, sample positions, camera
 * rays, filter and merge order as the CPU path (the pass driver of
 * host/render), radiance from the wavefront; each camera sample seeds its
 * device stream from its CPU stream (tb_aa_sample_rng), so the image is
 * deterministic for a seed. Adaptive antialiasing is TB_ERR_UNSUPPORTED.
 * `stats` and `gstats` may be NULL. */
tb_status tb_gpu_render_path(tb_gpu_device *dev, const tb_scene *s, const tb_pt_options *po,
                             const tb_render_options *o, tb_image **out, tb_render_stats *stats,
                             tb_gpu_pt_stats *gstats);

#endif
