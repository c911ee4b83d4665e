/* Surfaces, materials and lights for any renderer (docs/rendering.md,
 * "Surfaces, BSDFs and lights"): from a hit (host/object/hit.h) and its ray
 * to the SURFACE RECORD (point, geometric and shading normal, uv, tangents,
 * the material's colours with its textures and patterns applied and its
 * bump map in the shading normal), the COMPOSITE BSDF of that material
 * (Lambert + the model's specular lobe + perfect mirror + smooth dielectric,
 * built on host/render/shading.h) with eval / sample / pdf, and the LIGHT
 * SET (the scene's point, spot, directional and IES lights and the area
 * light of every exact emitter) with sample / pdf / shadow test and the
 * emitted radiance and sampling density of an emitter a ray hits, so a
 * renderer can weight BSDF-sampled hits by multiple importance sampling.
 * The Whitted ray tracer (raytrace.h) and the path tracer (pathtrace.h) are
 * built on it.
 *
 *     tb_surfaces *ss;  tb_light_set ls;
 *     tb_surfaces_create(scene, NULL, &ss);  tb_light_set_init(&ls, scene);
 *     tb_surface sf;
 *     if (tb_scene_intersect(scene, &ray, &hit) && tb_surface_at(ss, &ray, &hit, NULL, &sf)) {
 *         tb_surface_bsdf b;
 *         tb_surface_bsdf_init(&sf, TB_SURFACE_PHYSICAL, &b);
 *         tb_light_sample l;
 *         if (tb_light_set_sample(&ls, ls.nlights, sf.p, u1, u2, &l) && !tb_light_set_occluded(&ls, &sf, &l))
 *             L += tb_surface_bsdf_eval(&b, sf.wo, l.wi) * l.L * |l.wi . sf.n| / l.pdf;
 *     }
 *
 * Directions are world-space unit vectors pointing away from the surface
 * (wo toward the viewer, wi toward the light). Colours are in the scene's
 * representation (scene->nchannels: RGB or spectral bands). Every struct
 * here except tb_surfaces is a plain value without pointers into the
 * per-path state (tb_surface, tb_surface_bsdf, tb_surface_sample): such
 * values can live in GPU buffers. */
#ifndef TB_HOST_RENDER_SURFACE_H
#define TB_HOST_RENDER_SURFACE_H

#include <stdbool.h>
#include <stdint.h>

#include "host/object/hit.h"
#include "host/render/channels.h"
#include "host/render/lights.h"
#include "host/render/scene.h"
#include "host/render/shading.h"
#include "util/base/error.h"
#include "util/math/ray.h"
#include "util/math/vec.h"

/* ------------------------------------------------------------ surfaces */

/* The scene's materials made ready to shade: texture images loaded,
 * patterns and bump maps built (read-only once created, shareable by threads). */
typedef struct tb_surfaces tb_surfaces;

/* Options of tb_surfaces_create; a zeroed struct (or NULL) means the defaults. */
typedef struct tb_surfaces_options {
    int texture_filter; /* image texture filter, a tb_tex_filter of host/render/texture.h (0: EWA) */
    int spp;            /* camera samples per pixel: footprints are scaled by max(1/8, 1/sqrt(spp)) (0: 1) */
} tb_surfaces_options;

/* Loads the textures and builds the patterns of every material of `s`
 * (which must outlive the result). TB_ERR_ARG for an unknown filter; the
 * image readers' errors. */
tb_status tb_surfaces_create(const tb_scene *s, const tb_surfaces_options *o, tb_surfaces **out);

/* Frees it; NULL is allowed. */
void tb_surfaces_free(tb_surfaces *ss);

/* True if some material has an image texture or a pattern or bump map: a
 * camera ray's differentials then refine the hit's footprint (tb_surface_at). */
bool tb_surfaces_need_differentials(const tb_surfaces *ss);

/* The surface record of a hit. */
typedef struct tb_surface {
    tb_vec3 p;              /* world hit point (tb_object_hit_point) */
    tb_vec3 perr;           /* bound on p's rounding error, per component */
    tb_vec3 ng;             /* unit geometric normal, outward (the hit's) */
    bool front;             /* the ray arrived on ng's side */
    tb_vec3 nv;             /* ng turned to the viewer's side */
    tb_vec3 n;              /* unit shading normal on the viewer's side (nv perturbed by the bump map) */
    tb_vec3 wo;             /* unit direction toward the viewer (-ray direction) */
    tb_vec3 org[2];         /* ray origins spawned from p on ng's side [0] and the other side [1] */
    float u, v;             /* surface parameters of the hit */
    bool has_tangents;      /* dpdu, dpdv are set (computed only when a texture or pattern needs them) */
    tb_vec3 dpdu, dpdv;     /* world tangents */
    bool has_fp;            /* fp holds the (u, v) footprint of the camera ray's pixel */
    float fp[4];            /* du/dx, dv/dx, du/dy, dv/dy */
    uint32_t object, face;  /* the hit's top-level object and face */
    int material;           /* index into scene->materials */
    tb_mid_model model;     /* the material's specular model */
    float exponent, roughness, ior; /* Phong/Blinn exponent, GGX alpha, index of refraction of the inside */
    bool emits;             /* the material emits (emission is meaningful) */
    tb_channels diffuse;    /* Lambert reflectance, pattern and texture applied */
    tb_channels specular;   /* specular colour (black for model lambert), pattern and texture applied */
    tb_channels transmission; /* smooth-dielectric transmittance, texture applied */
    tb_channels emission;   /* radiant exitance M, texture applied (radiance M / pi on the front side) */
} tb_surface;

/* Fills *out for `hit`, the closest hit of `ray` in ss's scene. rd: the
 * camera ray's offset rays {rx_o, rx_d, ry_o, ry_d} (texture footprints),
 * or NULL to point sample. False if the hit has no material. */
bool tb_surface_at(const tb_surfaces *ss, const tb_ray *ray, const tb_hit *hit, const tb_vec3 *rd, tb_surface *out);

/* A ray leaving the surface in unit direction w (origin offset to w's side). */
tb_ray tb_surface_spawn(const tb_surface *sf, tb_vec3 w);

/* Radiance the surface emits toward the viewer: emission / pi on the front
 * side of an emitting material, black otherwise (emitters are one-sided). */
tb_channels tb_surface_emitted(const tb_surface *sf);

/* The Phong or Blinn lobe of the material without its colour, f / ks:
 * normalised Phong (n + 2) / (2 pi) cos^n, or exactly normalised
 * Blinn-Phong, for wi about the shading normal. 0 for other models. */
double tb_surface_phong_lobe(const tb_surface *sf, tb_vec3 wi);

/* ---------------------------------------------------------------- BSDF */

/* Lobes of the composite BSDF (bit flags). */
typedef enum tb_lobe {
    TB_LOBE_DIFFUSE = 1u,    /* Lambert, diffuse / pi */
    TB_LOBE_GLOSSY = 2u,     /* the model's specular lobe: normalised Phong, exact Blinn, or GGX */
    TB_LOBE_MIRROR = 4u,     /* perfect mirror weighted by the specular colour (delta) */
    TB_LOBE_DIELECTRIC = 8u, /* smooth dielectric: Fresnel mirror + refraction tinted by transmission (delta) */
} tb_lobe;

/* The delta lobes: no density, never evaluated, only sampled. */
#define TB_LOBE_DELTA (TB_LOBE_MIRROR | TB_LOBE_DIELECTRIC)

/* How the specular colour of a Phong or Blinn material is read. */
typedef enum tb_surface_mode {
    TB_SURFACE_PHYSICAL = 0, /* as its normalised lobe (a true BSDF; the path tracer) */
    TB_SURFACE_WHITTED,      /* as a perfect mirror (Whitted's k_s S; the ray tracer's reflected rays) */
} tb_surface_mode;

/* The most lobes a composite BSDF has. */
#define TB_SURFACE_MAX_LOBES 3

/* The composite BSDF of a surface: a sum of lobes, sampled by choosing a
 * lobe in proportion to its mean colour. */
typedef struct tb_surface_bsdf {
    unsigned lobes;          /* tb_lobe bits present */
    tb_frame frame;          /* shading frame: z is the shading normal on the viewer's side */
    tb_vec3 nv;              /* geometric normal on the viewer's side: reflection stays on this side */
    tb_vec3 ng;              /* outward geometric normal: the dielectric's interface */
    tb_channels diffuse;     /* Lambert reflectance */
    tb_bsdf glossy;          /* the glossy lobe (shading.h) */
    tb_channels mirror;      /* mirror reflectance */
    tb_channels transmission; /* dielectric transmittance (the Fresnel reflection is untinted) */
    double ior;              /* dielectric: n_inside / n_outside */
    float dielectric;        /* dielectric's share, 1 - max(diffuse): the composite's albedo stays <= 1 */
    float pick[4];           /* selection probability of diffuse, glossy, mirror, dielectric */
} tb_surface_bsdf;

/* The composite BSDF of sf under `mode`. Lobes whose colour is black are
 * left out. A transmitting material is diffuse + smooth dielectric (its
 * specular colour is the ray tracer's highlight only), the dielectric
 * weighted by 1 - max(diffuse). */
void tb_surface_bsdf_init(const tb_surface *sf, tb_surface_mode mode, tb_surface_bsdf *b);

/* f(wo, wi) of the non-delta lobes (1/sr): zero when wi and wo lie on
 * opposite sides of the geometric surface. */
tb_channels tb_surface_bsdf_eval(const tb_surface_bsdf *b, tb_vec3 wo, tb_vec3 wi);

/* Solid-angle density with which tb_surface_bsdf_sample returns wi through
 * its non-delta lobes (their selection probabilities included). */
double tb_surface_bsdf_pdf(const tb_surface_bsdf *b, tb_vec3 wo, tb_vec3 wi);

/* A sampled direction. */
typedef struct tb_surface_sample {
    tb_vec3 wi;         /* unit world direction */
    tb_channels weight; /* f |wi . n| / pdf (delta lobes: their reflectance or transmittance / probability) */
    double pdf;         /* non-delta: tb_surface_bsdf_pdf(wo, wi); delta: the discrete probability */
    unsigned lobe;      /* the lobe sampled (a tb_lobe bit) */
    bool delta;         /* a delta lobe: no density, MIS does not apply */
    bool transmitted;   /* wi is on the other side of the geometric surface */
} tb_surface_sample;

/* Samples wi given wo from uniform numbers in [0, 1): uc picks the lobe
 * (and reflection or refraction of the dielectric), u1, u2 the direction.
 * False when no direction results (no lobe, the lobe's sample fell below the
 * horizon or onto the wrong side of the geometric surface): the path ends
 * there, which is unbiased as f is zero there. */
bool tb_surface_bsdf_sample(const tb_surface_bsdf *b, tb_vec3 wo, float uc, float u1, float u2,
                            tb_surface_sample *out);

/* -------------------------------------------------------------- lights */

/* Emitters per bounding sphere of tb_light_set.blocks. */
#define TB_LIGHT_SET_BLOCK 32

/* Every light of a scene: the point, spot and directional lights (with
 * their IES tables) as lights 0 .. nlights-1, and, as light nlights when
 * has_area, the area light made of every exact emitter (scene->emitters). */
typedef struct tb_light_set {
    const tb_scene *scene;  /* not owned */
    int nlights;            /* delta lights (scene->lights) */
    bool has_area;          /* area below is set up (the scene has emitters) */
    tb_area_light area;     /* every emitter of the scene as one light */
    int *emissive_of;       /* per top-level object: its index in scene->emissive, or -1 */
    double *blocks;         /* per TB_LIGHT_SET_BLOCK emitters: a bounding sphere (x, y, z, r), so that a line
                               skips the facets of a tessellated emitter it cannot cross */
} tb_light_set;

/* Prepares the light set of `scene` (which must outlive it). TB_ERR_NOMEM,
 * and tb_area_light_init's errors. */
tb_status tb_light_set_init(tb_light_set *ls, const tb_scene *scene);

/* Frees what tb_light_set_init allocated (harmless on a zeroed struct). */
void tb_light_set_release(tb_light_set *ls);

/* Lights a renderer can sample: nlights + (has_area ? 1 : 0). */
int tb_light_set_count(const tb_light_set *ls);

/* Samples light `light` (0 .. count-1) as seen from p: a delta light
 * (u1, u2 unused, pdf 1, `delta` set) or a point on the area light
 * (tb_area_light_sample). False when it gives no light at p. */
bool tb_light_set_sample(const tb_light_set *ls, int light, tb_vec3 p, float u1, float u2, tb_light_sample *out);

/* True if the shadow segment from sf toward the light sample is blocked
 * (leaving from sf's origin on wi's side; a plain sphere emitter does not
 * block the way to its own visible cap). */
bool tb_light_set_occluded(const tb_light_set *ls, const tb_surface *sf, const tb_light_sample *s);

/* tb_light_set_occluded for a point, spot or directional light's sample
 * given by its parts (tb_light_delta_at): direction wi, the light's position
 * and distance (INFINITY: directional). */
bool tb_light_set_occluded_delta(const tb_light_set *ls, const tb_surface *sf, tb_vec3 wi, tb_vec3 point, float dist);

/* The area-light sample `s` taken at sf, seen on the exact geometry: true
 * when the ray from sf toward s->wi meets first the front side of an
 * emitting part of the object the sample's emitter stands for; then *Le is
 * that surface's emitted radiance (emission texture included; ss may be
 * NULL: untextured) and *pdf the density of the direction s->wi, summed
 * over every emitter of that object the line crosses (as
 * tb_light_set_emitter_pdf). Curved and CSG emitters are sampled through
 * their tessellation, whose facets leave gaps, overhang the exact
 * silhouette and overlap along CSG seams: estimating f Le |cos| / pdf with
 * this test and density counts each direction that reaches the exact
 * emitter once, and the same emission a BSDF-sampled ray finds there is
 * weighted with the same density, so MIS weights sum to one on the exact
 * surface (docs/pathtrace.md). */
bool tb_light_set_visible_emitter(const tb_light_set *ls, const tb_surfaces *ss, const tb_surface *sf,
                                  const tb_light_sample *s, tb_channels *Le, double *pdf);

/* Solid-angle density of the area light's sampler at p for direction w,
 * summed over every emitter the line crosses (the ray tracer's MIS weight
 * of glossy rays). 0 without area light. */
double tb_light_set_pdf_dir(const tb_light_set *ls, tb_vec3 p, tb_vec3 w);

/* Solid-angle density with which the area light, sampled at p, returns the
 * direction of the emitting point the surface record `hit` is at, through
 * the emitters of hit's object: the sum over those the line p -> hit.p
 * crosses on a side the sampler returns (curved and CSG emitters are
 * sampled through their tessellation). 0 if none. For multiple importance
 * sampling of BSDF-sampled rays that meet an emitter. */
double tb_light_set_emitter_pdf(const tb_light_set *ls, tb_vec3 p, const tb_surface *hit);

/* Veach's power heuristic of a sample of density a against b: a^2 / (a^2 + b^2) (0 when a is 0). */
double tb_power_heuristic(double a, double b);

#endif
