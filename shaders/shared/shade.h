/* Layouts of the shade kernel (shaders/shade.comp, host/gpu/render.c;
 * docs/gpu.md, "Shade kernel and wavefront renderer"). See shared/types.h
 * for the layout rules; the C side asserts every size and offset.
 *
 * Per shading point the host writes one tb_gpu_shade_item (the ray, its hit
 * and the material) and, when the point samples the area light, light
 * samples (tb_gpu_light_u: the emitter chosen and the remapped numbers, drawn
 * on the host from the sample's own stream so that the GPU uses exactly the
 * CPU path's numbers), followed by the numbers of its glossy (GGX) rays,
 * drawn likewise (u1, u2 of a tb_gpu_light_u). The kernel writes, per item,
 * TB_GPU_SHADE_RAYS(S, G) output rays (S shadow rays, the mirror and the
 * refracted ray, then G glossy rays) and TB_GPU_SHADE_VALUES(S, channels,
 * SW, G) floats: per shadow ray SW words, a validity flag and scalars a, b
 * (and c when the scene has GGX materials: SW = 4; its unblocked
 * contribution is (diffuse a + specular b + c) times the light's or
 * emitter's colour; c is the Schlick Fresnel's white part), then 3 + G
 * colour slots (emission, mirror weight, refraction weight, glossy weights)
 * of a validity flag and the channel values, then G glossy densities.
 * Everything is stored word-major for n items (word w of item j at w n + j;
 * ray slot k at k n + j), so neighbouring invocations write neighbouring
 * words. */
#ifndef TB_SHADERS_SHARED_SHADE_H
#define TB_SHADERS_SHARED_SHADE_H

#include "types.h"

/* tb_gpu_shade_item.flags: sample the area light at this point. */
#define TB_GPU_SHADE_AREA 1u
/* tb_gpu_shade_item.flags: spawn mirror / refracted rays (depth < max depth). */
#define TB_GPU_SHADE_SPAWN 2u

/* tb_gpu_shade_material.flags bits: which colours are not black. */
#define TB_GPU_MAT_DIFFUSE 1u
#define TB_GPU_MAT_SPECULAR 2u
#define TB_GPU_MAT_TRANSMISSION 4u
#define TB_GPU_MAT_EMITS 8u
/* tb_gpu_shade_material.flags: the highlight is Blinn-Phong (half vector), else Phong. */
#define TB_GPU_MAT_BLINN 16u
/* tb_gpu_shade_material.flags: the specular lobe is GGX (Schlick Fresnel, F0 = specular;
 * glossy rays instead of the mirror ray). */
#define TB_GPU_MAT_GGX 32u

/* Emitter kinds (the order of host/render/lights.h's tb_emitter_kind). */
#define TB_GPU_EMITTER_TRIANGLE 0u
#define TB_GPU_EMITTER_PARALLELOGRAM 1u
#define TB_GPU_EMITTER_DISC 2u
#define TB_GPU_EMITTER_SPHERE 3u

/* Delta light kinds (host/scene/mid.h's tb_light_kind values are mapped to these). */
#define TB_GPU_LIGHT_POINT 0u
#define TB_GPU_LIGHT_SPOT 1u
#define TB_GPU_LIGHT_DIRECTIONAL 2u

#ifndef TB_GPU_GLSL
typedef struct tb_gpu_shade_item tb_gpu_shade_item;
typedef struct tb_gpu_light_u tb_gpu_light_u;
typedef struct tb_gpu_emitter tb_gpu_emitter;
typedef struct tb_gpu_delta_light tb_gpu_delta_light;
typedef struct tb_gpu_shade_material tb_gpu_shade_material;
#endif

/* One shading point; std430 size 64. */
struct tb_gpu_shade_item {
    TB_GPU_VEC3 o;           /* ray origin (offset 0) */
    float t;                 /* hit distance (offset 12) */
    TB_GPU_VEC3 d;           /* ray direction, any length (offset 16) */
    TB_GPU_UINT material;    /* index into the material table (offset 28) */
    TB_GPU_VEC3 ng;          /* unit geometric normal of the hit (offset 32) */
    TB_GPU_UINT flags;       /* TB_GPU_SHADE_* (offset 44) */
    TB_GPU_UINT light_base;  /* first of its light samples in the light-sample buffer (offset 48) */
    TB_GPU_UINT glossy;      /* glossy rays to sample (GGX), their numbers after the light samples (offset 52) */
    TB_GPU_UINT pad1, pad2;
};

/* One area-light sample: the emitter chosen on the host (double CDF, as
 * tb_area_light_sample) and the numbers for the point on it; size 16. */
struct tb_gpu_light_u {
    TB_GPU_UINT emitter; /* index into the emitter table */
    float u1;            /* u1 remapped within the emitter's slice (offset 4) */
    float u2;            /* offset 8 */
    float pmf;           /* probability of choosing the emitter (offset 12) */
};

/* One emitter; std430 size 64. */
struct tb_gpu_emitter {
    TB_GPU_VEC3 v0;      /* triangle/parallelogram corner; disc, sphere centre (offset 0) */
    TB_GPU_UINT kind;    /* TB_GPU_EMITTER_* (offset 12) */
    TB_GPU_VEC3 v1;      /* second point; disc: unit normal (offset 16) */
    float radius;        /* disc, sphere (offset 28) */
    TB_GPU_VEC3 v2;      /* third point (offset 32) */
    TB_GPU_UINT two_sided; /* offset 44 */
    TB_GPU_VEC3 normal;  /* triangle, parallelogram: unit front normal (double, rounded once) (offset 48) */
    float inv_area;      /* 1 / area, from the host's double area (offset 60) */
};

/* tb_gpu_delta_light.ies of a light without an IES distribution. */
#define TB_GPU_NO_IES 0xffffffffu

/* One point, spot or directional light; std430 size 64. An IES
 * distribution is a record in the colour table at float offset `ies`:
 * nv, nh, symmetry (host/render/ies.h's tb_ies_symmetry), 1 / max candela,
 * then nv vertical angles, nh horizontal angles and nh x nv candela values
 * (degrees and cd, rounded to float; the counts are exact as floats). */
struct tb_gpu_delta_light {
    TB_GPU_VEC3 position;  /* point, spot (offset 0) */
    TB_GPU_UINT kind;      /* TB_GPU_LIGHT_* (offset 12) */
    TB_GPU_VEC3 axis;      /* spot: beam axis; directional: direction light travels;
                              point: the IES nadir (offset 16) */
    float cos_total;       /* spot (offset 28) */
    TB_GPU_VEC3 xaxis;     /* IES horizontal angle 0 (offset 32) */
    float cos_falloff;     /* spot (offset 44) */
    TB_GPU_UINT black;     /* 1 if the intensity is 0 in every channel: no light (offset 48) */
    TB_GPU_UINT ies;       /* float offset of its IES record in the colour table, or TB_GPU_NO_IES (offset 52) */
    TB_GPU_UINT pad0, pad1;
};

/* The scalar part of a material (its colours are in the colour table); size 32. */
struct tb_gpu_shade_material {
    float exponent; /* Phong exponent */
    float ior;      /* index of refraction of the inside (offset 4) */
    float knorm;    /* lobe normalisation: Phong (n + 2) / (2 pi), or Blinn's exact one, from the host's double (offset 8) */
    TB_GPU_UINT flags; /* TB_GPU_MAT_* (offset 12) */
    float alpha;    /* GGX width, clamped below to TB_GGX_ALPHA_MIN as shading.c does (offset 16) */
    float pad0, pad1, pad2;
};

/* Push constants of the shade kernel; size 16. */
#ifndef TB_GPU_GLSL
typedef struct tb_gpu_shade_push {
    uint32_t items;       /* shading points */
    uint32_t pad0, pad1, pad2;
} tb_gpu_shade_push;
#endif

/* Output slots per item for S shadow rays and G glossy rays: S, a mirror and
 * a refracted ray, G glossy rays. */
#define TB_GPU_SHADE_RAYS(S, G) ((S) + 2u + (G))
/* Output floats per item for S shadow rays of SW words, `ch` channels and G
 * glossy rays: SW per shadow ray (flag, a, b[, c]), then 3 + G colour slots
 * (emission, mirror, refracted, glossy) of a flag and the channels, then G
 * glossy densities. */
#define TB_GPU_SHADE_VALUES(S, ch, SW, G) ((SW) * (S) + (3u + (G)) * ((ch) + 1u) + (G))

#ifndef TB_GPU_GLSL
_Static_assert(sizeof(tb_gpu_shade_item) == 64, "tb_gpu_shade_item is 64 bytes");
_Static_assert(offsetof(tb_gpu_shade_item, t) == 12 && offsetof(tb_gpu_shade_item, d) == 16 &&
                   offsetof(tb_gpu_shade_item, material) == 28 && offsetof(tb_gpu_shade_item, ng) == 32 &&
                   offsetof(tb_gpu_shade_item, flags) == 44 && offsetof(tb_gpu_shade_item, light_base) == 48 &&
                   offsetof(tb_gpu_shade_item, glossy) == 52,
               "tb_gpu_shade_item follows the std430 offsets of its GLSL twin");
_Static_assert(sizeof(tb_gpu_light_u) == 16 && offsetof(tb_gpu_light_u, u1) == 4 &&
                   offsetof(tb_gpu_light_u, u2) == 8 && offsetof(tb_gpu_light_u, pmf) == 12,
               "tb_gpu_light_u follows the std430 offsets of its GLSL twin");
_Static_assert(sizeof(tb_gpu_emitter) == 64 && offsetof(tb_gpu_emitter, kind) == 12 &&
                   offsetof(tb_gpu_emitter, v1) == 16 && offsetof(tb_gpu_emitter, radius) == 28 &&
                   offsetof(tb_gpu_emitter, v2) == 32 && offsetof(tb_gpu_emitter, two_sided) == 44 &&
                   offsetof(tb_gpu_emitter, normal) == 48 && offsetof(tb_gpu_emitter, inv_area) == 60,
               "tb_gpu_emitter follows the std430 offsets of its GLSL twin");
_Static_assert(sizeof(tb_gpu_delta_light) == 64 && offsetof(tb_gpu_delta_light, kind) == 12 &&
                   offsetof(tb_gpu_delta_light, axis) == 16 && offsetof(tb_gpu_delta_light, cos_total) == 28 &&
                   offsetof(tb_gpu_delta_light, xaxis) == 32 && offsetof(tb_gpu_delta_light, cos_falloff) == 44 &&
                   offsetof(tb_gpu_delta_light, black) == 48 && offsetof(tb_gpu_delta_light, ies) == 52,
               "tb_gpu_delta_light follows the std430 offsets of its GLSL twin");
_Static_assert(sizeof(tb_gpu_shade_material) == 32 && offsetof(tb_gpu_shade_material, ior) == 4 &&
                   offsetof(tb_gpu_shade_material, knorm) == 8 && offsetof(tb_gpu_shade_material, flags) == 12 &&
                   offsetof(tb_gpu_shade_material, alpha) == 16,
               "tb_gpu_shade_material follows the std430 offsets of its GLSL twin");
_Static_assert(sizeof(tb_gpu_shade_push) == 16, "tb_gpu_shade_push is 16 bytes");
#endif

#endif
