/* The hit record the intersection kernels write: 32 bytes, only what
 * traversal needs (the full surface record is built afterwards from it).
 * Byte for byte the CPU's tb_hit (host/object/hit.h) and the record of HITS
 * files; tests/gpu/test_gpu_kernels.c asserts the two layouts agree (this
 * header, at the shader level, does not include the object level). See
 * shared/types.h for the layout rules. */
#ifndef TB_SHADERS_SHARED_HIT_H
#define TB_SHADERS_SHARED_HIT_H

#include "types.h"

/* `object` of a ray that hit nothing. */
#define TB_GPU_NO_HIT 0xffffffffu

#ifndef TB_GPU_GLSL
typedef struct tb_gpu_hit tb_gpu_hit;
#endif

/* Closest hit of one ray; std430 size 32, alignment 4 (no vec3: ng is an
 * array of three floats, stride 4, so the record stays 32 bytes). */
struct tb_gpu_hit {
    float t;            /* ray parameter of the hit (offset 0) */
    TB_GPU_UINT object; /* object index, TB_GPU_NO_HIT for a miss (offset 4) */
    TB_GPU_UINT face;   /* face of the object's primitive (host/object/param.h numbering) (offset 8) */
    float u;            /* surface parameters of the face (offsets 12, 16) */
    float v;
    float ng[3];        /* unit geometric normal out of the solid (offsets 20, 24, 28) */
};

#ifndef TB_GPU_GLSL
_Static_assert(sizeof(tb_gpu_hit) == 32, "tb_gpu_hit is 32 bytes");
_Static_assert(offsetof(tb_gpu_hit, object) == 4 && offsetof(tb_gpu_hit, face) == 8 &&
                   offsetof(tb_gpu_hit, u) == 12 && offsetof(tb_gpu_hit, v) == 16 &&
                   offsetof(tb_gpu_hit, ng) == 20,
               "tb_gpu_hit follows the std430 offsets of its GLSL twin");
#endif

#endif
