/* Shading models (BRDFs and BTDFs), Fresnel equations and the perfect
 * specular helpers of Whitted ray tracing (docs/shading.md has every formula).
 *
 * Every model works in a LOCAL SHADING FRAME whose z axis is the shading
 * normal (tb_frame converts), with both directions pointing AWAY from the
 * surface: wo toward the viewer (where light leaves), wi toward the light
 * (where it arrives). A model is a plain tb_bsdf value with three functions:
 *
 *     f   = tb_bsdf_eval(&b, wo, wi);            // f(wo, wi), per channel, 1/sr
 *     pdf = tb_bsdf_pdf(&b, wo, wi);             // density of wi given wo, solid angle
 *     if (tb_bsdf_sample(&b, wo, uc, u1, u2, &s))  // wi from uniform numbers
 *         L += s.weight * Li(s.wi);              // weight = f |cos theta_i| / pdf
 *
 * Reflection models are two-sided: they reflect when wo and wi lie on the
 * same side of the surface (either side, mirror-symmetric about the tangent
 * plane) and are zero otherwise. The rough dielectric also transmits. The
 * eval/pdf/sample triple of each model is consistent: the chi-square tests in
 * tests/render/test_shading_sampling.c compare sampled directions with the
 * integrated pdf.
 *
 * Scalars are computed in double and rounded to float once per channel. */
#ifndef TB_HOST_RENDER_SHADING_H
#define TB_HOST_RENDER_SHADING_H

#include <stdbool.h>

#include "host/render/channels.h"
#include "util/math/vec.h"

/* ------------------------------------------------------------------ frames */

/* An orthonormal right-handed frame (s, t, n): the local shading frame. */
typedef struct tb_frame {
    tb_vec3 s, t, n; /* tangent, bitangent, normal (local x, y, z) */
} tb_frame;

/* The frame around the unit normal n (tangents from tb_vec3_basis: arbitrary
 * but continuous, fine for isotropic models). */
tb_frame tb_frame_from_normal(tb_vec3 n);

/* The frame with normal n and first tangent along the part of `s` orthogonal
 * to n (for anisotropic work and parameterised surfaces); falls back to
 * tb_frame_from_normal when s is (nearly) parallel to n. */
tb_frame tb_frame_from_normal_tangent(tb_vec3 n, tb_vec3 s);

/* World direction w in frame f: (w.s, w.t, w.n). */
tb_vec3 tb_frame_to_local(const tb_frame *f, tb_vec3 w);

/* Local direction w to world: w.x s + w.y t + w.z n. */
tb_vec3 tb_frame_to_world(const tb_frame *f, tb_vec3 w);

/* ---------------------------------------------------- Fresnel and Snell */

/* Unpolarised Fresnel reflectance of a smooth dielectric interface (the exact
 * equations, not Schlick). cos_i is the cosine between the incident direction
 * (pointing away from the surface) and the normal, eta = n_inside / n_outside
 * where the normal points outside. cos_i < 0 means the light arrives from the
 * inside: the roles swap (eta -> 1/eta). Returns 1 under total internal
 * reflection; ((eta-1)/(eta+1))^2 at normal incidence; 1 at grazing incidence
 * (cos_i = 0). eta = 1 gives 0 everywhere (no interface). */
double tb_fresnel_dielectric(double cos_i, double eta);

/* Schlick's approximation f0 + (1 - f0) (1 - |cos_i|)^5. */
double tb_fresnel_schlick(double cos_i, double f0);

/* Reflectance at normal incidence of an interface with relative index eta:
 * ((eta - 1) / (eta + 1))^2. */
double tb_fresnel_f0(double eta);

/* Mirror reflection of w about the unit normal n: 2 (w.n) n - w (w pointing
 * away from the surface, the result too). */
tb_vec3 tb_reflect(tb_vec3 w, tb_vec3 n);

/* Snell refraction of wi (pointing away from the surface, on either side)
 * through the interface with unit normal n (pointing outside) and eta =
 * n_inside / n_outside. On success *wt is the unit transmitted direction
 * (pointing away from the surface on the other side) and *etap (if not NULL)
 * the relative index n_t / n_i seen from wi's side; false under total
 * internal reflection. Exactly: sin theta_t = sin theta_i / etap. */
bool tb_refract(tb_vec3 wi, tb_vec3 n, double eta, tb_vec3 *wt, double *etap);

/* What a smooth dielectric does with wo (local frame, normal +z, eta = n_inside
 * / n_outside): the mirror direction with its Fresnel reflectance R, and,
 * unless totally reflected, the refracted direction with T = 1 - R. T is the
 * fraction of power; radiance carried across is multiplied by T / etap^2
 * (etap = n_t / n_i), which a renderer applies when it tracks radiance in
 * media of different index (docs/shading.md, "Whitted helpers"). */
typedef struct tb_specular_split {
    tb_vec3 wr;    /* mirror direction */
    double R;      /* Fresnel reflectance, in [0, 1] */
    bool refracts; /* false under total internal reflection (then R = 1, T = 0) */
    tb_vec3 wt;    /* refracted direction (valid when refracts) */
    double T;      /* 1 - R */
    double etap;   /* n_t / n_i seen from wo's side */
} tb_specular_split;

/* Fills *out for wo as described above. */
void tb_specular_dielectric(tb_vec3 wo, double eta, tb_specular_split *out);

/* ------------------------------------------------------- GGX (microfacets) */

/* Trowbridge-Reitz (GGX) normal distribution D(m) for a microfacet normal m
 * (local frame, unit) with roughness alpha: alpha^2 / (pi (m.z^2 (alpha^2 -
 * 1) + 1)^2) for m.z > 0, 0 otherwise. Integrates to 1 against m.z dm. */
double tb_ggx_D(double alpha, tb_vec3 m);

/* Smith Lambda(w) of GGX: (sqrt(1 + alpha^2 tan^2 theta) - 1) / 2 (using |cos theta|). */
double tb_ggx_lambda(double alpha, tb_vec3 w);

/* Smith masking G1(w) = 1 / (1 + Lambda(w)). */
double tb_ggx_G1(double alpha, tb_vec3 w);

/* Height-correlated masking-shadowing G2 = 1 / (1 + Lambda(wo) + Lambda(wi)). */
double tb_ggx_G2(double alpha, tb_vec3 wo, tb_vec3 wi);

/* Samples a microfacet normal from the distribution of normals VISIBLE from
 * w (Heitz 2018, "Sampling the GGX distribution of visible normals", JCGT
 * 7(4)); w on either side, the normal returned has z > 0. */
tb_vec3 tb_ggx_sample_vndf(double alpha, tb_vec3 w, float u1, float u2);

/* Density of tb_ggx_sample_vndf: G1(w) max(0, w'.m) D(m) / |w.z|, where w' is
 * w flipped to z > 0. */
double tb_ggx_vndf_pdf(double alpha, tb_vec3 w, tb_vec3 m);

/* Smallest roughness the GGX models use (smaller values are raised to it:
 * below this the lobe is narrower than float directions can resolve). */
#define TB_GGX_ALPHA_MIN 1e-3

/* ------------------------------------------------------------------ models */

/* The shading models. */
typedef enum tb_bsdf_kind {
    TB_BSDF_LAMBERT = 0,          /* color / pi */
    TB_BSDF_PHONG,                /* color cos^n(alpha), alpha between wi and the mirror direction of wo */
    TB_BSDF_PHONG_NORMALIZED,     /* color (n + 2) / (2 pi) cos^n(alpha) */
    TB_BSDF_BLINN,                /* color cos^n(theta_h), h the half vector of wo and wi */
    TB_BSDF_BLINN_NORMALIZED,     /* color (n + 8) / (8 pi) cos^n(theta_h) (the usual approximation) */
    TB_BSDF_BLINN_NORMALIZED_EXACT, /* color (n+2)(n+4) / (8 pi (n + 2^(-n/2))) cos^n(theta_h) */
    TB_BSDF_GGX,                  /* microfacet reflection: color F D G2 / (4 |cos_o cos_i|) */
    TB_BSDF_GGX_DIELECTRIC,       /* rough dielectric, reflection + transmission (Walter et al. 2007) */
} tb_bsdf_kind;

/* Number of tb_bsdf_kind values. */
#define TB_BSDF_KIND_COUNT 8

/* Fresnel term of TB_BSDF_GGX. */
typedef enum tb_fresnel_kind {
    TB_FRESNEL_NONE = 0,   /* F = 1 (a white furnace lobe) */
    TB_FRESNEL_SCHLICK,    /* F = color + (1 - color)(1 - cos)^5: color is the normal-incidence reflectance */
    TB_FRESNEL_DIELECTRIC, /* F = exact dielectric reflectance for eta, times color */
} tb_fresnel_kind;

/* One shading model with its parameters (plain value; build with the
 * constructors below or fill by hand). */
typedef struct tb_bsdf {
    tb_bsdf_kind kind;
    tb_channels color;       /* Lambert: reflectance; Phong/Blinn: specular coefficient ks; GGX: tint (Schlick: F0) */
    double exponent;         /* Phong/Blinn exponent n >= 0 */
    double alpha;            /* GGX roughness (Trowbridge-Reitz width), TB_GGX_ALPHA_MIN..1 sensible */
    double eta;              /* GGX: n_inside / n_outside (dielectric Fresnel and transmission) */
    tb_fresnel_kind fresnel; /* GGX reflection only */
} tb_bsdf;

/* Lambert: f = reflectance / pi. */
tb_bsdf tb_bsdf_lambert(tb_channels reflectance);

/* Phong, plain (ks cos^n) or normalised ((n + 2) / (2 pi) ks cos^n). */
tb_bsdf tb_bsdf_phong(tb_channels ks, double exponent, bool normalized);

/* Blinn-Phong: plain (TB_BSDF_BLINN), (n + 8) / (8 pi) (TB_BSDF_BLINN_NORMALIZED)
 * or exact (TB_BSDF_BLINN_NORMALIZED_EXACT): pass the kind. */
tb_bsdf tb_bsdf_blinn(tb_channels ks, double exponent, tb_bsdf_kind kind);

/* GGX reflection with the given Fresnel term. */
tb_bsdf tb_bsdf_ggx(tb_channels color, double alpha, tb_fresnel_kind fresnel, double eta);

/* GGX rough dielectric (reflection and transmission), color tints both. */
tb_bsdf tb_bsdf_ggx_dielectric(tb_channels color, double alpha, double eta);

/* The normalisation factor k of a Phong/Blinn kind with exponent n (the lobe
 * is color * k * cos^n): 1 for the plain kinds. */
double tb_bsdf_lobe_norm(tb_bsdf_kind kind, double n);

/* f(wo, wi) in 1/sr, per channel (local frame, both unit and pointing away). */
tb_channels tb_bsdf_eval(const tb_bsdf *b, tb_vec3 wo, tb_vec3 wi);

/* Density (solid angle) with which tb_bsdf_sample returns wi given wo. For
 * models whose lobe can reach below the horizon (Phong, Blinn, GGX) the
 * samples that would go there are refused, so the density integrates to the
 * fraction of successful samples (< 1), not to 1. */
double tb_bsdf_pdf(const tb_bsdf *b, tb_vec3 wo, tb_vec3 wi);

/* A sampled direction. */
typedef struct tb_bsdf_sampled {
    tb_vec3 wi;         /* unit, local frame */
    tb_channels f;      /* f(wo, wi) */
    double pdf;         /* tb_bsdf_pdf(wo, wi) */
    tb_channels weight; /* f |wi.z| / pdf */
    bool transmitted;   /* wi is on the other side of the surface */
} tb_bsdf_sampled;

/* Samples wi given wo from uniform numbers in [0,1): uc chooses between
 * reflection and transmission (rough dielectric only; the other models ignore
 * it), (u1, u2) place the direction. Returns false (and *s zeroed with
 * pdf 0) when no direction results: the lobe sample fell below the horizon,
 * wo lies in the tangent plane, or f is zero there. */
bool tb_bsdf_sample(const tb_bsdf *b, tb_vec3 wo, float uc, float u1, float u2, tb_bsdf_sampled *s);

#endif
