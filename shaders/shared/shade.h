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
/* tb_gpu_shade_item.flags: the item has a surface record (tb_gpu_surface at
 * the item's index in the chunk) for its patterns, bump map and textures. */
#define TB_GPU_SHADE_SURFACE 4u

/* tb_gpu_pattern.kind (host/mid/mid.h's tb_mid_pattern_kind; image bumps are routed). */
#define TB_GPU_PATTERN_NONE 0u
#define TB_GPU_PATTERN_CHECKER 1u
#define TB_GPU_PATTERN_NOISE 2u
/* tb_gpu_shade_material.tex of a colour without an image texture. */
#define TB_GPU_NO_TEXTURE 0xffffffffu
/* Texture slots of tb_gpu_shade_material.tex (raytrace.c's order). */
#define TB_GPU_TEX_DIFFUSE 0
#define TB_GPU_TEX_SPECULAR 1
#define TB_GPU_TEX_TRANSMISSION 2
#define TB_GPU_TEX_EMISSION 3
/* An image texture is a record of uints in the texture-info buffer:
 * channels, levels, width and height of level 0, then per level its width,
 * height and the offset of its texels (row-major from the top row,
 * `channels` floats each) in the texel buffer (shaders/lib/texture.glsl). */
#define TB_GPU_TEX_HEADER 4u
#define TB_GPU_TEX_PER_LEVEL 3u

/* Pattern slots of tb_gpu_shade_material.pattern. */
#define TB_GPU_PATTERN_DIFFUSE 0
#define TB_GPU_PATTERN_SPECULAR 1
#define TB_GPU_PATTERN_BUMP 2

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

/* Delta light kinds (host/mid/mid.h's tb_light_kind values are mapped to these). */
#define TB_GPU_LIGHT_POINT 0u
#define TB_GPU_LIGHT_SPOT 1u
#define TB_GPU_LIGHT_DIRECTIONAL 2u

#ifndef TB_GPU_GLSL
typedef struct tb_gpu_shade_item tb_gpu_shade_item;
typedef struct tb_gpu_light_u tb_gpu_light_u;
typedef struct tb_gpu_emitter tb_gpu_emitter;
typedef struct tb_gpu_delta_light tb_gpu_delta_light;
typedef struct tb_gpu_shade_material tb_gpu_shade_material;
typedef struct tb_gpu_pattern tb_gpu_pattern;
typedef struct tb_gpu_surface tb_gpu_surface;
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

/* A procedural pattern or bump map of a material (raytrace_pattern.c's
 * textures: checker box-filtered over the footprint, fBm noise of
 * `octaves` octaves, omega 1/2, lacunarity 1.99); size 32. */
struct tb_gpu_pattern {
    TB_GPU_UINT kind;    /* TB_GPU_PATTERN_* */
    float su;            /* scale of u (object space: of the point) (offset 4) */
    float sv;            /* scale of v (offset 8) */
    TB_GPU_UINT solid;   /* 1: object space (offset 12) */
    TB_GPU_INT octaves;  /* noise (offset 16) */
    float height;        /* bump: height of the unit value (offset 20) */
    TB_GPU_UINT col;     /* colour patterns: float offset of colour a in the colour table, b follows (offset 24) */
    TB_GPU_UINT pad0;
};

/* The geometry of a hit that patterns and bump maps need, computed on the
 * host as the CPU tracer computes it (raytrace.h's tb__rt_surface: the
 * primitive's tangents, the camera ray's footprint); size 112. */
struct tb_gpu_surface {
    TB_GPU_VEC3 po;      /* the point in the primitive's object space (offset 0) */
    float u;             /* offset 12 */
    TB_GPU_VEC3 po_du;   /* its change per unit u (offset 16) */
    float v;             /* offset 28 */
    TB_GPU_VEC3 po_dv;   /* per unit v (offset 32) */
    TB_GPU_UINT has_fp;  /* fp0..3 hold the footprint (du/dx, dv/dx, du/dy, dv/dy) (offset 44) */
    TB_GPU_VEC3 po_dx;   /* the point's change per pixel (zero: unknown) (offset 48) */
    float fp0;           /* offset 60 */
    TB_GPU_VEC3 po_dy;   /* offset 64 */
    float fp1;           /* offset 76 */
    TB_GPU_VEC3 dpdu;    /* world tangents (offset 80) */
    float fp2;           /* offset 92 */
    TB_GPU_VEC3 dpdv;    /* offset 96 */
    float fp3;           /* offset 108 */
};

/* The scalar part of a material (its colours are in the colour table); size 144. */
struct tb_gpu_shade_material {
    float exponent; /* Phong exponent */
    float ior;      /* index of refraction of the inside (offset 4) */
    float knorm;    /* lobe normalisation: Phong (n + 2) / (2 pi), or Blinn's exact one, from the host's double (offset 8) */
    TB_GPU_UINT flags; /* TB_GPU_MAT_* (offset 12) */
    float alpha;    /* GGX width, clamped below to TB_GGX_ALPHA_MIN as shading.c does (offset 16) */
    float pad0, pad1, pad2;
    tb_gpu_pattern pattern[3]; /* diffuse, specular, bump (TB_GPU_PATTERN_DIFFUSE ..) (offset 32) */
    TB_GPU_UINT tex[4];        /* image textures of diffuse, specular, transmission, emission: their
                                  records in the texture-info buffer, or TB_GPU_NO_TEXTURE (offset 128) */
};

/* Push constants of the shade kernel; size 16. */
#ifndef TB_GPU_GLSL
typedef struct tb_gpu_shade_push {
    uint32_t items;       /* shading points */
    uint32_t perm;        /* float offset of the noise permutation (256 values) in the colour table */
    uint32_t pad1, pad2;
} tb_gpu_shade_push;
#endif

/* Output slots per item for S shadow rays and G glossy rays: S, a mirror and
 * a refracted ray, G glossy rays. */
#define TB_GPU_SHADE_RAYS(S, G) ((S) + 2u + (G))
/* Output floats per item for S shadow rays of SW words, `ch` channels, G
 * glossy rays and PW pattern and texture words: SW per shadow ray (flag, a,
 * b[, c]), then 3 + G colour slots (emission, mirror, refracted, glossy) of
 * a flag and the channels, then G glossy densities, then PW: 2 when the
 * scene has colour patterns (the blend factors of the diffuse and specular
 * patterns, -1 without one), then 6 when it has image textures (the RGB
 * of the diffuse and the specular texture, first word -1 without one). */
#define TB_GPU_SHADE_VALUES(S, ch, SW, G, PW) ((SW) * (S) + (3u + (G)) * ((ch) + 1u) + (G) + (PW))

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
_Static_assert(sizeof(tb_gpu_pattern) == 32 && offsetof(tb_gpu_pattern, su) == 4 &&
                   offsetof(tb_gpu_pattern, sv) == 8 && offsetof(tb_gpu_pattern, solid) == 12 &&
                   offsetof(tb_gpu_pattern, octaves) == 16 && offsetof(tb_gpu_pattern, height) == 20 &&
                   offsetof(tb_gpu_pattern, col) == 24,
               "tb_gpu_pattern follows the std430 offsets of its GLSL twin");
_Static_assert(sizeof(tb_gpu_surface) == 112 && offsetof(tb_gpu_surface, u) == 12 &&
                   offsetof(tb_gpu_surface, po_du) == 16 && offsetof(tb_gpu_surface, v) == 28 &&
                   offsetof(tb_gpu_surface, po_dv) == 32 && offsetof(tb_gpu_surface, has_fp) == 44 &&
                   offsetof(tb_gpu_surface, po_dx) == 48 && offsetof(tb_gpu_surface, fp0) == 60 &&
                   offsetof(tb_gpu_surface, po_dy) == 64 && offsetof(tb_gpu_surface, fp1) == 76 &&
                   offsetof(tb_gpu_surface, dpdu) == 80 && offsetof(tb_gpu_surface, fp2) == 92 &&
                   offsetof(tb_gpu_surface, dpdv) == 96 && offsetof(tb_gpu_surface, fp3) == 108,
               "tb_gpu_surface follows the std430 offsets of its GLSL twin");
_Static_assert(sizeof(tb_gpu_shade_material) == 144 && offsetof(tb_gpu_shade_material, ior) == 4 &&
                   offsetof(tb_gpu_shade_material, knorm) == 8 && offsetof(tb_gpu_shade_material, flags) == 12 &&
                   offsetof(tb_gpu_shade_material, alpha) == 16 && offsetof(tb_gpu_shade_material, pattern) == 32 &&
                   offsetof(tb_gpu_shade_material, tex) == 128,
               "tb_gpu_shade_material follows the std430 offsets of its GLSL twin");
_Static_assert(sizeof(tb_gpu_shade_push) == 16, "tb_gpu_shade_push is 16 bytes");
#endif

#endif
