/* The Whitted ray tracer (docs/raytrace.md): closest hits through the
 * scene's acceleration structure, direct lighting from point, spot and
 * directional lights (shadow rays) and from area lights (every emissive
 * object, curved and CSG ones through their tessellation; stratified
 * samples: soft shadows),
 * Lambert + normalised Phong from the MID material, perfect mirror
 * reflection weighted by the specular colour, and refraction with exact
 * Fresnel reflectance and total internal reflection for materials with a
 * transmission colour. A material's diffuse, specular, transmission and
 * emission textures multiply those colours by the image's linear RGB at the
 * hit's (u, v) (Smits-upsampled in spectral scenes), filtered over the
 * pixel's footprint from camera ray differentials (EWA by default;
 * docs/raytrace.md). MID 1.1 materials: the specular term's model (Phong,
 * exactly normalised Blinn-Phong, none for Lambert, or a GGX lobe whose
 * reflections are glossy rays sampled from it, combined with the area-light
 * samples by multiple importance sampling), checker and noise patterns
 * in (u, v) or object space (footprint-filtered), and bump maps from noise
 * or a height image. No indirect diffuse light of its own: an optional
 * callback (tb_rt_options.indirect) supplies it, as the hybrid renderer does.
 *
 *     tb_raytracer rt;
 *     if (tb_rt_init(&rt, scene, NULL)) die(tb_last_error());
 *     tb_channels L = tb_rt_radiance(&rt, &ray, &rng);
 *     tb_rt_release(&rt);
 *
 * Values are in the scene's colour representation (linear RGB or spectral
 * render bands: scene->nchannels). */
#ifndef TB_HOST_RENDER_RAYTRACE_H
#define TB_HOST_RENDER_RAYTRACE_H

#include <stdbool.h>
#include <stdint.h>

#include "host/render/channels.h"
#include "host/render/lights.h"
#include "host/render/scene.h"
#include "host/render/surface.h"
#include "util/base/error.h"
#include "util/math/ray.h"
#include "util/math/rng.h"

/* Default Whitted recursion depth (camera ray = depth 0). */
#define TB_RT_DEFAULT_MAX_DEPTH 5
/* Default area-light samples per shading point. */
#define TB_RT_DEFAULT_LIGHT_SAMPLES 4
/* Default glossy (GGX) rays at a camera ray's hit (one at deeper hits). */
#define TB_RT_DEFAULT_GLOSSY_SAMPLES 4

/* Where the tracer asks for indirect diffuse light: a diffuse hit seen by a
 * ray at recursion depth `depth` (camera ray: 0). */
typedef struct tb_rt_indirect_query {
    uint32_t object; /* top-level object index (hit.object) */
    uint32_t face;   /* hit.face */
    tb_vec3 p;       /* world hit point */
    tb_vec3 n;       /* unit geometric normal on the side the ray came from (before any bump) */
    tb_vec3 origin;  /* a ray origin spawned from p on n's side (for rays leaving the hit) */
    int depth;       /* recursion depth of the ray that found the hit */
} tb_rt_indirect_query;

/* Indirect diffuse irradiance (W/m^2 per scene channel) arriving at the hit
 * `q`, light the tracer does not compute itself (the hybrid renderer's
 * radiosity solution, host/hybrid): the tracer adds diffuse / pi times it.
 * Called from several threads at once; `rng` is the sample's stream. */
typedef tb_channels (*tb_rt_indirect_fn)(void *ctx, const tb_rt_indirect_query *q, tb_rng *rng);

/* Ray tracer options; a zeroed struct (or NULL) means the defaults. */
typedef struct tb_rt_options {
    int max_depth;     /* deepest reflected/refracted ray (0: TB_RT_DEFAULT_MAX_DEPTH; < 0: camera rays only) */
    int light_samples; /* area-light samples per shading point, stratified (0: the default) */
    int texture_filter; /* image texture filter, a tb_tex_filter value of host/render/texture.h (0: EWA) */
    int spp;           /* camera samples per pixel: differentials are scaled by max(1/8, 1/sqrt(spp)) (0: 1) */
    int glossy_samples; /* rays sampled from a GGX lobe at a camera ray's hit, stratified (0: the default) */
    tb_rt_indirect_fn indirect; /* NULL: no indirect diffuse light (Whitted); else asked at every diffuse hit */
    void *indirect_ctx;         /* passed to indirect */
    double min_weight; /* adaptive depth control (POV-Ray's adc_bailout): a reflected or refracted ray whose
                        * weight (product of the mirror, Fresnel and transmission weights on its way from the
                        * camera, largest channel) is below it is not traced; 0: every ray to max_depth */
} tb_rt_options;

/* A ray tracer over a loaded scene (read-only after init, shareable by threads). */
/* Private: the images of the materials' textures (raytrace_texture.c). */
typedef struct tb__rt_textures tb__rt_textures;
/* Private: the materials' procedural patterns and bump maps (raytrace_pattern.c). */
typedef struct tb__rt_patterns tb__rt_patterns;

typedef struct tb_raytracer {
    const tb_scene *scene;  /* not owned */
    int max_depth;          /* in effect */
    int light_samples;      /* in effect */
    int lsx, lsy;           /* strata of the light samples (lsx * lsy = light_samples) */
    tb_light_set lights;    /* the scene's lights; lights.area: every exact emitter as one light */
    tb_surfaces *surfaces;  /* owned: the materials' textures, patterns and bump maps (surface.h) */
    const tb__rt_textures *textures; /* surfaces' images (not owned); NULL when no material has a texture */
    int texture_filter;     /* tb_tex_filter value in effect */
    float diff_scale;       /* scale of the camera ray differentials, max(1/8, 1/sqrt(spp)) */
    const tb__rt_patterns *patterns; /* surfaces' patterns (not owned); NULL when no material has one */
    int glossy_samples;     /* in effect */
    int gsx, gsy;           /* strata of the glossy samples */
    tb_rt_indirect_fn indirect; /* from the options (NULL: none) */
    void *indirect_ctx;
    double min_weight;      /* in effect (0: off) */
} tb_raytracer;

/* Prepares a tracer for `scene` (which must stay alive). TB_ERR_ARG for bad
 * options or a scene without an acceleration structure. */
tb_status tb_rt_init(tb_raytracer *rt, const tb_scene *scene, const tb_rt_options *opt);

/* Frees what tb_rt_init allocated (harmless on a zeroed struct). */
void tb_rt_release(tb_raytracer *rt);

/* Radiance arriving along -ray->d at ray->o (scene channels); `rng` gives
 * the light-sample jitter. Black on a miss. */
tb_channels tb_rt_radiance(const tb_raytracer *rt, const tb_ray *ray, tb_rng *rng);

/* What a glossy (GGX) ray carries to weight the emission it finds against
 * the area-light samples of the point it left (power heuristic). */
typedef struct tb_rt_mis {
    tb_vec3 p;       /* the shading point the ray left, where the light samples are taken from */
    tb_vec3 w;       /* the ray's unit direction */
    double pdf;      /* the lobe's density of w */
    double nb, nl;   /* glossy rays and light samples taken there */
} tb_rt_mis;

/* tb_rt_radiance for a ray at recursion depth `depth` (camera ray: 0), with
 * `mis` set for a glossy ray (NULL otherwise): what the tracer computes for
 * that ray inside its recursion (the wavefront renderer hands such rays
 * over, host/gpu/render_wavefront.c). */
tb_channels tb_rt_radiance_at(const tb_raytracer *rt, const tb_ray *ray, tb_rng *rng, int depth,
                              const tb_rt_mis *mis);

/* The power-heuristic weight of emission found by the glossy ray `mis`
 * (1 when the scene has no area light). */
double tb_rt_mis_weight(const tb_raytracer *rt, const tb_rt_mis *mis);

/* A tb_aa_sample_fn (host/render/antialias.h): ctx is a tb_raytracer; the
 * camera ray of film point (x, y) (pinhole, or the lens point from rng),
 * radiance written to out[0 .. scene->nchannels). */
void tb_rt_sample(void *ctx, double x, double y, tb_rng *rng, float *out);

#endif
