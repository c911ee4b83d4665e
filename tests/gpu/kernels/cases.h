/* Input and output records of the paired kernel tests, shared by
 * test_gpu_kernels.c and the kernels in this folder (rules: shaders/shared/types.h). */
#ifndef TB_TESTS_GPU_KERNELS_CASES_H
#define TB_TESTS_GPU_KERNELS_CASES_H

#include "shared/ray.h"

#ifndef TB_GPU_GLSL
typedef struct tb_case_box tb_case_box;
typedef struct tb_case_box_out tb_case_box_out;
typedef struct tb_case_sphere tb_case_sphere;
typedef struct tb_case_f4 tb_case_f4;
typedef struct tb_case_f8 tb_case_f8;
#endif

/* A ray and a box (k_aabb). */
struct tb_case_box {
    tb_gpu_ray ray;  /* offset 0 */
    TB_GPU_VEC3 lo;  /* offset 32 */
    float pad0;
    TB_GPU_VEC3 hi;  /* offset 48 */
    float pad1;
};

/* A hit flag and an interval (k_aabb, k_sphere: t in t0). */
struct tb_case_box_out {
    TB_GPU_UINT hit;
    float t0;
    float t1;
    TB_GPU_UINT pad;
};

/* A ray and a sphere radius (k_sphere). */
struct tb_case_sphere {
    tb_gpu_ray ray;  /* offset 0 */
    float radius;    /* offset 32 */
    float pad0, pad1, pad2;
};

/* Four floats: quadratic coefficients, colours, fma probes (k_quadratic,
 * k_color, k_contract). */
struct tb_case_f4 {
    float x, y, z, w;
};

/* Eight floats: the arguments of a shading routine (k_shading). */
struct tb_case_f8 {
    float a, b, c, d, e, f, g, h;
};

#ifndef TB_GPU_GLSL
_Static_assert(sizeof(tb_case_f8) == 32, "tb_case_f8 layout");
_Static_assert(sizeof(tb_case_box) == 64 && offsetof(tb_case_box, lo) == 32 && offsetof(tb_case_box, hi) == 48,
               "tb_case_box layout");
_Static_assert(sizeof(tb_case_box_out) == 16, "tb_case_box_out layout");
_Static_assert(sizeof(tb_case_sphere) == 48 && offsetof(tb_case_sphere, radius) == 32, "tb_case_sphere layout");
_Static_assert(sizeof(tb_case_f4) == 16, "tb_case_f4 layout");
#endif

#endif
