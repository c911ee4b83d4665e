/* The scene as the intersect kernel (shaders/intersect.comp) reads it: BVH
 * nodes converted from the CPU BVH (host/render/accel.h, tb_bvh_node) and
 * world-space triangles in leaf order. Built by host/gpu/intersect.c. See
 * shared/types.h for the layout rules. */
#ifndef TB_SHADERS_SHARED_BVH_H
#define TB_SHADERS_SHARED_BVH_H

#include "types.h"

#ifndef TB_GPU_GLSL
typedef struct tb_gpu_bvh_node tb_gpu_bvh_node;
typedef struct tb_gpu_tri tb_gpu_tri;
#endif

/* One BVH node, 32 bytes: the CPU node's box with the two words moved next to
 * the vec3s so that std430 and C agree. Depth-first order, node 0 the root;
 * an inner node's first child is the next node. */
struct tb_gpu_bvh_node {
    TB_GPU_VEC3 lo;     /* box, low corner (offset 0) */
    TB_GPU_UINT offset; /* inner: index of the second child; leaf: first triangle (offset 12) */
    TB_GPU_VEC3 hi;     /* box, high corner (offset 16) */
    TB_GPU_UINT count;  /* leaf: number of triangles (>= 1); 0 marks an inner node (offset 28) */
};

/* One triangle, 64 bytes: world-space vertices (the object's float vertices
 * mapped by its transform in double, rounded once), and what the hit record
 * needs: the CPU's geometric normal of that triangle (computed on the host
 * exactly as the CPU path does), the object, the face ID and the reference
 * index of the CPU BVH (the last key of the tie rule, docs/accel.md). */
struct tb_gpu_tri {
    TB_GPU_VEC3 v0;     /* offset 0 */
    TB_GPU_UINT object; /* top-level object index (offset 12) */
    TB_GPU_VEC3 v1;     /* offset 16 */
    TB_GPU_UINT face;   /* face ID, as in tb_hit (offset 28) */
    TB_GPU_VEC3 v2;     /* offset 32 */
    TB_GPU_UINT ref;    /* index of this triangle's reference in tb_scene.prims (offset 44) */
    TB_GPU_VEC3 ng;     /* unit geometric normal, world space, out of the solid (offset 48) */
    TB_GPU_UINT pad0;   /* zero (offset 60) */
};

#ifndef TB_GPU_GLSL
_Static_assert(sizeof(tb_gpu_bvh_node) == 32, "tb_gpu_bvh_node is 32 bytes");
_Static_assert(offsetof(tb_gpu_bvh_node, offset) == 12 && offsetof(tb_gpu_bvh_node, hi) == 16 &&
                   offsetof(tb_gpu_bvh_node, count) == 28,
               "tb_gpu_bvh_node follows the std430 offsets of its GLSL twin");
_Static_assert(sizeof(tb_gpu_tri) == 64, "tb_gpu_tri is 64 bytes");
_Static_assert(offsetof(tb_gpu_tri, object) == 12 && offsetof(tb_gpu_tri, v1) == 16 &&
                   offsetof(tb_gpu_tri, face) == 28 && offsetof(tb_gpu_tri, v2) == 32 &&
                   offsetof(tb_gpu_tri, ref) == 44 && offsetof(tb_gpu_tri, ng) == 48 &&
                   offsetof(tb_gpu_tri, pad0) == 60,
               "tb_gpu_tri follows the std430 offsets of its GLSL twin");
#endif

#endif
