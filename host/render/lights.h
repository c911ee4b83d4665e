/* Light sources (docs/lights.md): point, spot and directional lights as MID
 * defines them (docs/mid.md, section 9), optionally shaped by an IES file, and
 * AREA LIGHTS made of emitting surfaces (triangles, parallelograms, discs,
 * spheres, or any surface through callbacks).
 *
 * The renderer asks a light for a sample as seen from a shading point p and
 * traces the shadow segment itself:
 *
 *     tb_light_sample s;
 *     if (tb_light_sample_li(&light, p, &s) && !occluded(&s.shadow))
 *         Lo += f(wo, s.wi) * s.L * |cos theta_i| / s.pdf;
 *     if (tb_area_light_sample(&area, p, u1, u2, &s) && !occluded(&s.shadow))
 *         Lo += f(wo, s.wi) * s.L * |cos theta_i| / s.pdf;
 *
 * The same estimator serves both kinds: for a delta light (point, spot,
 * directional) s.pdf is 1 and s.L is the irradiance the light gives on a
 * surface facing it (I / d^2, or E); for an area light s.L is the emitted
 * radiance and s.pdf the solid-angle density of s.wi.
 *
 * Units (docs/lights.md, "Units"): intensity I in W/sr (per nm for
 * spectra), irradiance E in W/m^2, radiant exitance M in W/m^2, radiance L in
 * W/(m^2 sr); a diffuse emitter of exitance M has L = M / pi. */
#ifndef TB_HOST_RENDER_LIGHTS_H
#define TB_HOST_RENDER_LIGHTS_H

#include <stdbool.h>
#include <stdint.h>

#include "host/render/channels.h"
#include "host/render/ies.h"
#include "host/render/sampling.h"
#include "host/mid/mid.h"
#include "util/math/ray.h"
#include "util/math/rng.h"
#include "util/math/vec.h"

/* Shadow segments end this fraction of their length short of the light
 * point, so they do not hit the emitting surface itself (pbrt's ShadowEpsilon). */
#define TB_SHADOW_EPSILON 1e-4f

/* What a light sample gives the renderer. */
typedef struct tb_light_sample {
    tb_channels L;  /* area: emitted radiance toward p; point/spot: I(w) / d^2; directional: E */
    tb_vec3 wi;     /* unit direction from p toward the light */
    float dist;     /* distance from p to `point` (INFINITY for a directional light) */
    double pdf;     /* solid-angle density of wi (1 for delta lights, with `delta` set) */
    bool delta;     /* point, spot or directional: wi is the only direction */
    tb_vec3 point;  /* the light point: on the emitter, or the light's position */
    tb_vec3 normal; /* area lights: unit normal of the emitter at `point` (front side) */
    int emitter;    /* area lights: index of the emitter sampled; -1 otherwise */
    tb_ray shadow;  /* o = p, d = point - p (unit wi for directional), t in [0, 1 - TB_SHADOW_EPSILON]
                       (directional: [0, inf)); replace o by the spawned origin (host/object/hit.h)
                       and recompute d = point - o before tracing */
} tb_light_sample;

/* ------------------------------------------------------- delta lights */

/* A point, spot or directional light in world space. */
typedef struct tb_light {
    tb_light_kind kind;    /* TB_LIGHT_POINT, TB_LIGHT_SPOT, TB_LIGHT_DIRECTIONAL (host/mid/mid.h) */
    tb_vec3 position;      /* point, spot: world position */
    tb_vec3 axis;          /* unit: spot beam axis; directional: direction light travels;
                              point: the photometric nadir of an IES file (light-space -z) */
    tb_vec3 xaxis;         /* unit, perpendicular to axis: horizontal angle 0 of an IES file */
    tb_channels intensity; /* point, spot: W/sr (the IES maximum, the spot axis); directional: W/m^2 */
    double cos_total;      /* spot: cos(cone_angle): no light beyond */
    double cos_falloff;    /* spot: cos(cone_angle - cone_delta): full intensity within */
    const tb_ies *ies;     /* optional distribution, normalised to a maximum of 1 (not owned) */
} tb_light;

/* A point light of intensity I (W/sr) at p. */
tb_light tb_light_point(tb_vec3 p, tb_channels I);

/* A spot light at p with beam axis `axis` (any length), intensity I on the
 * axis, half-angle cone_angle and falloff width cone_delta (degrees, as MID). */
tb_light tb_light_spot(tb_vec3 p, tb_vec3 axis, tb_channels I, double cone_angle, double cone_delta);

/* A directional light: light travels along `dir` (any length) with
 * irradiance E (W/m^2) on a surface facing it. */
tb_light tb_light_directional(tb_vec3 dir, tb_channels E);

/* The light of a MID light item in world space: position and directions
 * through its transform, intensity through tb_channels_from_mid_color
 * (bands NULL: RGB), the IES distribution `ies` (the file m->ies names,
 * loaded by the caller with tb_ies_read; NULL for none; kept by pointer).
 * Orientation of an IES file (docs/mid.md, 9): a point light's nadir is its
 * light-space -z and horizontal angle 0 its light-space +x; a spot light's
 * nadir is its direction, and its +x is light-space +x turned by the
 * smallest rotation taking -z to the direction (by 180 degrees about x when
 * the direction is +z). TB_ERR_ARG for a bad item, errors of the colour
 * conversion otherwise. */
tb_status tb_light_from_mid(const tb_mid_light *m, const tb_bands *bands, const tb_ies *ies,
                            tb_light *out);

/* Spot falloff: 0 for cos_theta <= cos_total, 1 for cos_theta >= cos_falloff,
 * and in between the smoothstep 3t^2 - 2t^3 of t = (cos_theta - cos_total) /
 * (cos_falloff - cos_total) (pbrt-v4's SpotLight; a hard edge when equal). */
double tb_spot_falloff(double cos_total, double cos_falloff, double cos_theta);

/* Radiant intensity (W/sr) of a point or spot light toward the unit world
 * direction w (pointing away from the light): intensity x IES x falloff. */
tb_channels tb_light_intensity(const tb_light *l, tb_vec3 w);

/* The light as seen from p (see the file comment). False when it gives no
 * light at p (outside the spot cone, a zero of the IES table, p at the
 * light's position); *s is then zeroed with L black. */
bool tb_light_sample_li(const tb_light *l, tb_vec3 p, tb_light_sample *s);

/* The scalar part of tb_light_sample_li for the Whitted light loop: unit
 * direction *wi toward the light, distance *dist (INFINITY: directional) and
 * *scale, the float factor whose product with each intensity channel is the
 * sample's L (bit for bit: 1 for a directional light). False where
 * tb_light_sample_li gives no light for a reason other than a black L. */
bool tb_light_delta_at(const tb_light *l, tb_vec3 p, tb_vec3 *wi, float *dist, float *scale);

/* A direction for light leaving a point or spot light (photon emission):
 * uniform on the sphere (point) or in the cone (spot), or from the IES
 * distribution when there is one. *pdf is its solid-angle density and the
 * return value the intensity toward it. False for directional lights. */
bool tb_light_sample_emission(const tb_light *l, float u1, float u2, tb_vec3 *w, double *pdf,
                              tb_channels *intensity);

/* Total power (W) of the light: 4 pi I for a point light, 2 pi I ((1 - cos_falloff) +
 * (cos_falloff - cos_total) / 2) for a spot light (the smoothstep averages
 * 1/2 over its range in cos theta), I flux / max for an IES point light; a
 * spot light with an IES file by quadrature (2048 x 256 cells in (cos, phi)).
 * Directional lights send pi r^2 E through a disc of radius scene_radius. */
tb_channels tb_light_power(const tb_light *l, double scene_radius);

/* ---------------------------------------------------------- area lights */

/* Shapes an emitter can have. */
typedef enum tb_emitter_kind {
    TB_EMITTER_TRIANGLE = 0,  /* v[0], v[1], v[2]; front side the one they turn counter-clockwise from */
    TB_EMITTER_PARALLELOGRAM, /* v[0] + s (v[1] - v[0]) + t (v[2] - v[0]), s, t in [0,1]; front (v1-v0) x (v2-v0) */
    TB_EMITTER_DISC,          /* centre v[0], unit normal v[1] (front side), radius */
    TB_EMITTER_SPHERE,        /* centre v[0], radius; the front side is the outside */
    TB_EMITTER_CUSTOM,        /* any surface: the callbacks below */
} tb_emitter_kind;

/* Custom emitters: a point q with unit normal n (front side) sampled from
 * (u1, u2) with density *pdf_area per unit area; false if none. */
typedef bool (*tb_emitter_sample_fn)(void *ctx, float u1, float u2, tb_vec3 *q, tb_vec3 *n,
                                     double *pdf_area);
/* Custom emitters: the density per unit area of the sampler at surface point q. */
typedef double (*tb_emitter_pdf_fn)(void *ctx, tb_vec3 q);
/* Custom emitters (optional): the first crossing of the line o + t d with
 * the surface at t > tmin: t, point and front normal; false if none. Lets
 * a renderer find the emitter along a ray (tb_emitter_intersect,
 * tb_area_light_pdf_line). */
typedef bool (*tb_emitter_intersect_fn)(void *ctx, tb_vec3 o, tb_vec3 d, double tmin, double *t, tb_vec3 *q,
                                        tb_vec3 *n);

/* One emitting surface with uniform radiance. Textured emission is not
 * handled here (a renderer can split the surface). */
typedef struct tb_emitter {
    tb_emitter_kind kind;
    tb_vec3 v[3];            /* points / centre / normal by kind (see tb_emitter_kind) */
    float radius;            /* disc, sphere */
    tb_channels radiance;    /* L = M / pi, the same in every direction of the front hemisphere */
    bool two_sided;          /* also emits from the back side (MID emitters are one-sided) */
    uint32_t object, face;   /* the scene object and face it stands for (bookkeeping for the renderer) */
    double area;             /* custom: the surface area (the others compute theirs) */
    tb_emitter_sample_fn sample; /* custom */
    tb_emitter_pdf_fn pdf;       /* custom */
    tb_emitter_intersect_fn intersect; /* custom, optional (NULL: rays never find it) */
    void *ctx;                   /* custom */
} tb_emitter;

/* Emitter constructors (radiance L in W/(m^2 sr)). */
tb_emitter tb_emitter_triangle(tb_vec3 a, tb_vec3 b, tb_vec3 c, tb_channels L);
tb_emitter tb_emitter_parallelogram(tb_vec3 corner, tb_vec3 p1, tb_vec3 p2, tb_channels L);
tb_emitter tb_emitter_disc(tb_vec3 centre, tb_vec3 normal, float radius, tb_channels L);
tb_emitter tb_emitter_sphere(tb_vec3 centre, float radius, tb_channels L);

/* Radiance of a diffuse emitter of radiant exitance M: M / pi per channel. */
tb_channels tb_radiance_from_exitance(tb_channels M);

/* Surface area of the emitter. */
double tb_emitter_area(const tb_emitter *e);

/* Closest intersection of the ray o + t d (t > 0, d any length) with the
 * emitter's surface (either side), in double: t, point and front normal.
 * For tests and light-only scenes; a renderer finds emitters through its
 * acceleration structure. */
bool tb_emitter_intersect(const tb_emitter *e, tb_vec3 o, tb_vec3 d, double *t, tb_vec3 *q, tb_vec3 *n);

/* Radiance leaving emitter e at a point with front normal n toward the unit
 * direction w (away from the surface): its radiance on the front side (and on
 * the back if two-sided), black otherwise. */
tb_channels tb_emitter_radiance(const tb_emitter *e, tb_vec3 n, tb_vec3 w);

/* A set of emitters sampled as one light: an emitter is chosen in
 * proportion to its power (area x mean radiance, x 2 if two-sided), then a
 * point on it: uniformly by area for triangles, parallelograms and discs,
 * uniformly in the cone of directions it subtends for a sphere seen from
 * outside (by area from inside a two-sided sphere), by the callback for
 * custom surfaces. */
typedef struct tb_area_light {
    int n;                 /* emitters */
    tb_emitter *emitters;  /* copies of the emitters given (read-only); with tb_area_light_init_shared the
                              caller's array itself */
    bool shared;           /* emitters is the caller's (tb_area_light_init_shared): not freed here */
    double *areas;         /* their areas */
    tb_distrib1d select;   /* choice of emitter */
    double power;          /* total power: pi x sum of area x mean radiance (x 2 two-sided), W */
} tb_area_light;

/* Builds an area light from e[0..n) (copied). TB_ERR_ARG for n < 1, a
 * degenerate shape (zero area, zero normal), negative or non-finite
 * radiance, or when no emitter has power; TB_ERR_NOMEM. */
tb_status tb_area_light_init(tb_area_light *a, const tb_emitter *e, int n);

/* tb_area_light_init without copying the emitters: the light reads e[0..n),
 * which must not change or be freed while it is in use (a scene's emitters,
 * held once instead of twice: docs/performance.md, "Scale"). */
tb_status tb_area_light_init_shared(tb_area_light *a, const tb_emitter *e, int n);

/* Frees what tb_area_light_init allocated (harmless on a zeroed struct). */
void tb_area_light_release(tb_area_light *a);

/* Samples a point on the light as seen from p, from (u1, u2) in [0,1)^2
 * (u1 also chooses the emitter, keeping stratification). False, with *s
 * zeroed, when the sample gives no light: p behind a one-sided emitter, p
 * inside a one-sided sphere, p on the emitter. */
bool tb_area_light_sample(const tb_area_light *a, tb_vec3 p, float u1, float u2, tb_light_sample *s);

/* What tb_area_light_sample computes from the shading point alone, kept
 * for the next samples from the same point: the point, and for the last
 * sphere emitter sampled (emitter >= 0) its centre, the cone it subtends
 * and the frame about the axis p -> centre. Set up by
 * tb_area_light_at_init; filled by tb_area_light_sample_at. */
typedef struct tb_area_light_at {
    tb_vec3 pf;         /* the shading point */
    int emitter;        /* sphere emitter the fields below belong to; -1: none yet */
    bool outside;       /* p is outside that sphere (dc > r (1 + 1e-7)): the cone sampler applies */
    tb_dvec3 c, axis, b1, b2; /* centre, unit axis (p - c) / dc, and the basis about it */
    double dc;          /* distance p - centre */
    double s2max, sqrt_s2max, omc_max; /* sin^2, sin and 1 - cos of the cone's half-angle */
} tb_area_light_at;

/* Starts the samples of one shading point p (no emitter cached). */
void tb_area_light_at_init(tb_area_light_at *at, tb_vec3 p);

/* tb_area_light_sample(a, at->pf, u1, u2, s), bit for bit, reusing the
 * per-point values of the sphere emitter at holds (and caching them when it
 * samples another): a shading point's several samples compute them once. */
bool tb_area_light_sample_at(const tb_area_light *a, tb_area_light_at *at, float u1, float u2,
                             tb_light_sample *s);

/* Solid-angle density with which tb_area_light_sample returns the point q
 * (normal nq) of emitter `emitter` seen from p: for multiple importance
 * sampling when a BSDF-sampled ray hits an emitter. 0 where the sampler never
 * goes (behind a one-sided emitter, outside a sphere's visible cap). */
double tb_area_light_pdf(const tb_area_light *a, int emitter, tb_vec3 p, tb_vec3 q, tb_vec3 nq);

/* Solid-angle density with which tb_area_light_sample returns the unit
 * direction w from p through emitter `emitter`: tb_area_light_pdf summed
 * over every crossing of the half-line with the emitter's surface (one at
 * most for the flat kinds and the sphere; a custom emitter with an
 * intersect callback may have several, e.g. a torus). 0 if none. */
double tb_area_light_pdf_line(const tb_area_light *a, int emitter, tb_vec3 p, tb_vec3 w);

/* Answers whether a shadow segment is blocked (the renderer's closure). */
typedef bool (*tb_occluded_fn)(void *ctx, const tb_ray *shadow);

/* Irradiance at p on a surface with unit normal n (receiving on its front
 * side) from the area light, estimated with n_samples jittered stratified
 * samples (tb_stratified_dims grid, numbers from rng) and the estimator
 * L cos theta / pdf. `occluded` may be NULL (no occluders). This is the
 * soft-shadow estimate a Lambertian surface needs (reflected radiance =
 * reflectance / pi x irradiance). */
tb_channels tb_area_light_irradiance(const tb_area_light *a, tb_vec3 p, tb_vec3 n, int n_samples,
                                     tb_rng *rng, tb_occluded_fn occluded, void *ctx);

#endif
