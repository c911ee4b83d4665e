/* The ray record of the GPU ray buffers: the same 32 bytes as tb_ray
 * (util/math/ray.h) and as the records of `testbed trace` ray files, so an
 * array of tb_ray is uploaded as it is. See shared/types.h for the rules. */
#ifndef TB_SHADERS_SHARED_RAY_H
#define TB_SHADERS_SHARED_RAY_H

#include "types.h"

#ifndef TB_GPU_GLSL
typedef struct tb_gpu_ray tb_gpu_ray;
#endif

/* The points o + t d for tmin <= t <= tmax; std430 size 32, alignment 16. */
struct tb_gpu_ray {
    TB_GPU_VEC3 o; /* origin (offset 0) */
    float tmin;    /* offset 12 */
    TB_GPU_VEC3 d; /* direction, not necessarily unit length (offset 16) */
    float tmax;    /* offset 28; +inf for an unbounded ray */
};

#ifndef TB_GPU_GLSL
#include "util/math/ray.h"
_Static_assert(sizeof(tb_gpu_ray) == 32, "tb_gpu_ray is 32 bytes");
_Static_assert(offsetof(tb_gpu_ray, o) == 0 && offsetof(tb_gpu_ray, tmin) == 12 &&
                   offsetof(tb_gpu_ray, d) == 16 && offsetof(tb_gpu_ray, tmax) == 28,
               "tb_gpu_ray follows the std430 offsets of its GLSL twin");
_Static_assert(sizeof(tb_gpu_ray) == sizeof(tb_ray) && offsetof(tb_gpu_ray, tmin) == offsetof(tb_ray, tmin) &&
                   offsetof(tb_gpu_ray, d) == offsetof(tb_ray, d) &&
                   offsetof(tb_gpu_ray, tmax) == offsetof(tb_ray, tmax),
               "tb_gpu_ray has the layout of tb_ray");
#endif

#endif
