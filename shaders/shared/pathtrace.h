/* Layouts of the Vulkan path tracer's wavefront (shaders/pathtrace.comp,
 * host/gpu/pathtrace.c; docs/gpu.md, "Path tracer"). The path state lives in
 * device buffers for the whole of a call: per path its ray (tb_gpu_ray), its
 * closest hit (tb_gpu_hit), a tb_gpu_pt_state (after a 32-byte header
 * holding the live-path count), its shadow rays, and the channel values
 * (throughput, radiance, pending light samples) stored word-major: value v
 * (TB_GPU_PT_BETA, _L, _PENDING + slot) of channel c of path i at
 * (v * nch + c) * n + i, so that neighbouring invocations touch neighbouring
 * words. The scene's tables are one array of 32-bit words (read as texels):
 * per material its diffuse, emitted radiance, specular and transmission
 * colours (nch each) and TB_GPU_PT_M_SCALARS words; per emitter its radiance
 * (nch); the emitters' CDF (nemitters + 1), pmf (nemitters) and top-level
 * object (nemitters, uints); per object TB_GPU_PT_O_WORDS uints; the CSG
 * leaf records (3 uints each); per delta light TB_GPU_PT_L_SCALARS words
 * and its intensity (nch). The shadow rays: slot k of path i at k * n + i. See shared/types.h for the rules. */
#ifndef TB_SHADERS_SHARED_PATHTRACE_H
#define TB_SHADERS_SHARED_PATHTRACE_H

#include "types.h"

/* The channel arrays of the value buffer. */
#define TB_GPU_PT_BETA 0u    /* throughput */
#define TB_GPU_PT_L 1u       /* radiance gathered */
#define TB_GPU_PT_PENDING 2u /* the pending light samples' contributions, one array per shadow slot (added to L
                                if the slot's ray is clear): slot 0 the area light, slot 1 + l delta light l */
#define TB_GPU_PT_NVALUES 3u /* arrays besides the PENDING ones of slots 1.. */

/* Shadow-ray slots per path: the area light and each point, spot or
 * directional light (the pending and clear masks are 32 bits wide). */
#define TB_GPU_PT_MAX_SLOTS 32u

/* The scene table's words per delta light before its intensity (nch):
 * kind (TB_GPU_LIGHT_* of shared/shade.h), position, axis, cos_total,
 * cos_falloff. */
#define TB_GPU_PT_L_KIND 0u
#define TB_GPU_PT_L_POSITION 1u
#define TB_GPU_PT_L_AXIS 4u
#define TB_GPU_PT_L_COS_TOTAL 7u
#define TB_GPU_PT_L_COS_FALLOFF 8u
#define TB_GPU_PT_L_SCALARS 9u

/* The scene table's words per material besides its 4 colours (diffuse,
 * emitted radiance, specular, transmission; nch each): the lobe selection
 * probabilities (TB_GPU_PT_M_PICK + slot of TB_GPU_PT_LOBE_*), the
 * dielectric's weight, the exponent, the index of refraction, the glossy
 * lobe's kind (TB_GPU_PT_GLOSSY_*), the lobes present (bit per slot) and
 * the GGX roughness. */
#define TB_GPU_PT_M_PICK 0u
#define TB_GPU_PT_M_DIELECTRIC 4u
#define TB_GPU_PT_M_EXPONENT 5u
#define TB_GPU_PT_M_IOR 6u
#define TB_GPU_PT_M_GLOSSY 7u
#define TB_GPU_PT_M_LOBES 8u
#define TB_GPU_PT_M_ALPHA 9u /* GGX: the roughness, at least TB_GGX_ALPHA_MIN */
#define TB_GPU_PT_M_PATTERNS 10u /* uint: the table word of its 3 pattern records, TB_GPU_PT_NONE without */
#define TB_GPU_PT_M_SCALARS 11u
/* A table word that refers to nothing. */
#define TB_GPU_PT_NONE 0xffffffffu
/* A material's pattern records (diffuse, specular, bump: shared/shade.h's
 * TB_GPU_PATTERN_* slots), each the 8 words of a tb_gpu_pattern whose `col`
 * is the table word of its colours a then b (nch each); kind
 * TB_GPU_PATTERN_NONE where the material has none. */
#define TB_GPU_PT_P_WORDS 8u
/* The scene table's words per object: its material (UINT32_MAX: none),
 * first emitter, emitter count, for a CSG tree the table word of its
 * first leaf record and its leaf count (a leaf record: first face, face
 * count, material; the hit's face picks the leaf, as tb_scene_hit_leaf),
 * and the table word of its parameterisation record (TB_GPU_PT_NONE: no
 * (u, v) on the device; only objects with a patterned material have one). */
#define TB_GPU_PT_O_WORDS 6u
#define TB_GPU_PT_O_PARAM 5u
/* A parameterisation record (host/object/param.h's (u, v) and tangents for
 * the kinds the kernel ports): kind, face base, the world-to-object affine
 * map (3 rows of 4 floats), the object-to-world linear part (3 rows of 3);
 * for polygons the face count, then per face the affine maps from the world
 * point to u and to v (4 floats each) and the world tangents dp/du, dp/dv
 * (3 each), fitted on the host from tb_param_from_point_world and checked
 * there (a face whose (u, v) is not affine over it is refused). */
#define TB_GPU_PT_Q_KIND 0u
#define TB_GPU_PT_Q_FACE_BASE 1u
#define TB_GPU_PT_Q_TO_OBJECT 2u
#define TB_GPU_PT_Q_TO_WORLD 14u
#define TB_GPU_PT_Q_NFACES 23u
#define TB_GPU_PT_Q_FACES 24u
#define TB_GPU_PT_Q_FACE_WORDS 14u
#define TB_GPU_PT_PARAM_SPHERE 1u
#define TB_GPU_PT_PARAM_CUBE 2u
#define TB_GPU_PT_PARAM_POLYGONS 3u

/* Lobe slots (the order of host/render/surface.c's tb_surface_bsdf.pick). */
#define TB_GPU_PT_LOBE_DIFFUSE 0u
#define TB_GPU_PT_LOBE_GLOSSY 1u
#define TB_GPU_PT_LOBE_MIRROR 2u /* the Whitted tracer's only: its probability is 0 here */
#define TB_GPU_PT_LOBE_DIELECTRIC 3u
/* Glossy lobe kinds. */
#define TB_GPU_PT_GLOSSY_NONE 0u
#define TB_GPU_PT_GLOSSY_PHONG 1u /* normalised Phong (TB_BSDF_PHONG_NORMALIZED) */
#define TB_GPU_PT_GLOSSY_BLINN 2u /* exactly normalised Blinn (TB_BSDF_BLINN_NORMALIZED_EXACT) */
#define TB_GPU_PT_GLOSSY_GGX 3u   /* GGX with Schlick's Fresnel of the specular colour (TB_BSDF_GGX) */

/* With the push constant `probe` (tb_gpu_pt_surfaces), the value arrays
 * that receive the first hit's diffuse and specular colours (channels) and
 * its shading normal (channels 0..2). */
#define TB_GPU_PT_PROBE_DIFFUSE 0u
#define TB_GPU_PT_PROBE_SPECULAR 1u
#define TB_GPU_PT_PROBE_NORMAL 2u

/* Kernel stages (specialization constant 1 of pathtrace.comp). */
#define TB_GPU_PT_STAGE_INIT 0u       /* radiance 0 */
#define TB_GPU_PT_STAGE_EXTEND 1u     /* closest hit of each live path's ray; a miss ends the path */
#define TB_GPU_PT_STAGE_SHADE 2u      /* the last light sample if clear, emission, light sample + shadow ray,
                                         BSDF sample, roulette */
#define TB_GPU_PT_STAGE_SHADOW 3u     /* any hit of the pending shadow rays: clear or blocked */
#define TB_GPU_PT_STAGE_ACCUMULATE 4u /* after the last bounce: the clear light samples of ended paths */
#define TB_GPU_PT_STAGES 5u


/* Bytes before the first tb_gpu_pt_state in the state buffer: word 0 is
 * the live paths counted by the last shade dispatch asked to count (the
 * host zeroes it before a submission). */
#define TB_GPU_PT_STATE_HEADER 32u

#ifndef TB_GPU_GLSL
typedef struct tb_gpu_pt_state tb_gpu_pt_state;
typedef struct tb_gpu_pt_push tb_gpu_pt_push;
#endif

/* One path's scalars; std430 size 48. The random stream is counter-based:
 * draw k of the path is a hash of (seed0, seed1, k). The previous vertex
 * (point, BSDF density, delta flag) weights emission the path's ray meets
 * against that vertex's light sample (MIS, as tb_pt_path). */
struct tb_gpu_pt_state {
    TB_GPU_UINT seed0;      /* from the camera sample's CPU stream (offset 0) */
    TB_GPU_UINT seed1;      /* offset 4 */
    TB_GPU_UINT counter;    /* numbers drawn so far (offset 8) */
    TB_GPU_UINT depth;      /* bounces so far; the camera ray is 0 (offset 12) */
    TB_GPU_UINT alive;      /* 1 while the path goes on (offset 16) */
    TB_GPU_UINT shadow;     /* bit k: slot k's shadow ray is still to trace (offset 20) */
    TB_GPU_UINT prev_delta; /* 1: the ray left the camera or a delta lobe (emission weight 1) (offset 24) */
    float prev_pdf;         /* the BSDF density of the ray's direction (offset 28) */
    float prev_px, prev_py, prev_pz; /* the previous vertex (offset 32) */
    TB_GPU_UINT clear;      /* bit k: slot k's shadow ray was traced and is clear: add its pending values
                               (offset 44) */
};

/* Push constants of every stage; size 48. */
struct tb_gpu_pt_push {
    TB_GPU_UINT n;          /* paths */
    TB_GPU_UINT nnodes;     /* BVH nodes (0: nothing on the device) */
    TB_GPU_UINT max_depth;  /* most bounces (0: only the hard cap) */
    TB_GPU_UINT rr_depth;   /* bounces before Russian roulette */
    TB_GPU_UINT max_bounces; /* the hard cap (TB_PT_MAX_BOUNCES) */
    TB_GPU_UINT count;      /* shade: 1 to count the live paths into the state buffer's header */
    TB_GPU_UINT light_base; /* the table word of the first delta light */
    TB_GPU_UINT perm;       /* the table word of Perlin's permutation (256 uints) */
    TB_GPU_UINT diffs;      /* 1: the rays buffer holds each camera ray's offset rays (x + 1 at n + i, y + 1 at
                               2n + i) for the footprint of the patterns at the first hit */
    float diff_scale;       /* their scale, max(1/8, 1/sqrt(spp)) (tb_surfaces') */
    TB_GPU_UINT probe;      /* 1: shade writes the first hit's surface (TB_GPU_PT_PROBE_*) and ends the path */
    TB_GPU_UINT pad1;
};

#ifndef TB_GPU_GLSL
_Static_assert(sizeof(tb_gpu_pt_state) == 48 && offsetof(tb_gpu_pt_state, counter) == 8 &&
                   offsetof(tb_gpu_pt_state, depth) == 12 && offsetof(tb_gpu_pt_state, alive) == 16 &&
                   offsetof(tb_gpu_pt_state, shadow) == 20 && offsetof(tb_gpu_pt_state, prev_pdf) == 28 &&
                   offsetof(tb_gpu_pt_state, prev_px) == 32 && offsetof(tb_gpu_pt_state, clear) == 44,
               "tb_gpu_pt_state follows the std430 offsets of its GLSL twin");
_Static_assert(sizeof(tb_gpu_pt_push) == 48 && offsetof(tb_gpu_pt_push, perm) == 28 &&
                   offsetof(tb_gpu_pt_push, diff_scale) == 36 && offsetof(tb_gpu_pt_push, max_bounces) == 16 &&
                   offsetof(tb_gpu_pt_push, count) == 20 && offsetof(tb_gpu_pt_push, light_base) == 24,
               "tb_gpu_pt_push follows the std430 offsets of its GLSL twin");
#endif

#endif
