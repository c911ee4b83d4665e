/* The form-factor kernel's records (shaders/formfactor.comp, host side
 * host/gpu/formfactor.c): receivers (point + normal), shooter sample points
 * and the push constants of one shot. The occluders are uploaded in the
 * intersect kernel's scene layout (shared/bvh.h: BVH nodes, tb_gpu_tri, leaf
 * references) so that lib/bvh_traverse.glsl traverses them. See
 * shared/types.h for the layout rules. */
#ifndef TB_SHADERS_SHARED_FORMFACTOR_H
#define TB_SHADERS_SHARED_FORMFACTOR_H

#include "types.h"

#ifndef TB_GPU_GLSL
typedef struct tb_gpu_ff_receiver tb_gpu_ff_receiver;
typedef struct tb_gpu_ff_sample tb_gpu_ff_sample;
typedef struct tb_gpu_ff_push tb_gpu_ff_push;
#endif

/* One receiver, 32 bytes: a differential area at p with unit normal n. */
struct tb_gpu_ff_receiver {
    TB_GPU_VEC3 p;     /* offset 0 */
    TB_GPU_UINT pad0;  /* zero (offset 12) */
    TB_GPU_VEC3 n;     /* offset 16 */
    TB_GPU_UINT pad1;  /* zero (offset 28) */
};

/* One sample point of the shooter, 16 bytes. */
struct tb_gpu_ff_sample {
    TB_GPU_VEC3 p;    /* offset 0 */
    TB_GPU_UINT pad0; /* zero (offset 12) */
};

/* Push constants of one dispatch, 32 bytes: the shooter and the receiver range. */
struct tb_gpu_ff_push {
    TB_GPU_VEC3 ns;      /* the shooter's unit normal (offset 0) */
    float da;            /* area / npts: the area each sample stands for (offset 12) */
    TB_GPU_UINT count;   /* receivers in this dispatch (offset 16) */
    TB_GPU_UINT npts;    /* sample points (offset 20) */
    TB_GPU_UINT nnodes;  /* BVH nodes, 0: no occluders (offset 24) */
    TB_GPU_UINT vis_words; /* 32-bit words of visibility bits per receiver, 0: none written (offset 28) */
};

#ifndef TB_GPU_GLSL
_Static_assert(sizeof(tb_gpu_ff_receiver) == 32, "tb_gpu_ff_receiver is 32 bytes");
_Static_assert(offsetof(tb_gpu_ff_receiver, pad0) == 12 && offsetof(tb_gpu_ff_receiver, n) == 16 &&
                   offsetof(tb_gpu_ff_receiver, pad1) == 28,
               "tb_gpu_ff_receiver follows the std430 offsets of its GLSL twin");
_Static_assert(sizeof(tb_gpu_ff_sample) == 16, "tb_gpu_ff_sample is 16 bytes");
_Static_assert(sizeof(tb_gpu_ff_push) == 32, "tb_gpu_ff_push is 32 bytes");
_Static_assert(offsetof(tb_gpu_ff_push, da) == 12 && offsetof(tb_gpu_ff_push, count) == 16 &&
                   offsetof(tb_gpu_ff_push, npts) == 20 && offsetof(tb_gpu_ff_push, nnodes) == 24 &&
                   offsetof(tb_gpu_ff_push, vis_words) == 28,
               "tb_gpu_ff_push follows the std430 offsets of its GLSL twin");
#endif

#endif
