// Closest hit (or any hit) of each of an array of rays with the scene's
// GPU-resident geometry: one invocation per ray, the traversal of
// lib/bvh_traverse.glsl over the buffers host/gpu/intersect.c uploads (a BVH
// converted from the CPU BVH, shared/bvh.h, over world-space triangles and
// placed objects of every other MID primitive kind; docs/gpu.md,
// "Intersect kernel").
//
// Triangles: lib/triangle.glsl (the CPU's watertight test in float, world
// space). Placed objects: the ray mapped to object space by the float
// world-to-object map, then lib/sphere.glsl, lib/cube.glsl, lib/revolved.glsl,
// lib/planar.glsl (pyramid, prism, arches), lib/torus.glsl. Hit records are
// tb_gpu_hit (shared/hit.h); (u, v) are left 0 and filled by the host.
#version 450
#extension GL_GOOGLE_include_directive : require

#include "shared/bvh.h"
#include "shared/hit.h"
#include "shared/ray.h"

layout(local_size_x_id = 0) in;
// Primitive kinds present in the scene: a kind the scene lacks is compiled out.
layout(constant_id = 1) const bool TB_HAS_TRIANGLES = true;
layout(constant_id = 3) const bool TB_HAS_SPHERES = false;
layout(constant_id = 4) const bool TB_HAS_CUBES = false;
layout(constant_id = 5) const bool TB_HAS_QUADRICS = false; // cylinders, cones, conics
layout(constant_id = 6) const bool TB_HAS_PLANAR = false;   // pyramids, prisms, arches
layout(constant_id = 7) const bool TB_HAS_TORI = false;
layout(constant_id = 8) const bool TB_HAS_CSG = false;
// Traversal stack entries: the host sets the BVH's depth (rounded up to a
// multiple of 8); one entry per level is enough, since every inner node
// pushes one child and continues with the other. The CPU BVH's depth is
// below 96 (docs/accel.md).
layout(constant_id = 2) const int TB_STACK = 128;

layout(std430, binding = 0) readonly buffer Rays { tb_gpu_ray rays[]; };
// Nodes, triangles and references as texel buffers (RGBA32UI, RGBA32UI,
// R32UI views of the tb_gpu_bvh_node, tb_gpu_tri and uint arrays): their
// loads are branch-free gathers on lavapipe (lib/bvh_traverse.glsl).
layout(binding = 1) uniform usamplerBuffer node_texels;
layout(binding = 2) uniform usamplerBuffer tri_texels;
layout(std430, binding = 3) writeonly buffer Hits { tb_gpu_hit hits[]; };
layout(std430, binding = 4) readonly buffer Placed { tb_gpu_placed placed[]; };
layout(binding = 5) uniform usamplerBuffer ref_texels;

layout(push_constant) uniform Push {
    uint n;        // rays
    uint any_hit;  // 1: occlusion (stop at the first hit found), 0: closest hit
    uint nnodes;   // 0: empty scene
    uint pad;
} pc;

#define TB_BVH_NODE_TEXELS node_texels
#define TB_BVH_TRI_TEXELS tri_texels
#define TB_BVH_PLACED placed
#define TB_BVH_REF_TEXELS ref_texels
#define TB_BVH_HAS_TRIANGLES TB_HAS_TRIANGLES
#define TB_BVH_HAS_SPHERES TB_HAS_SPHERES
#define TB_BVH_HAS_CUBES TB_HAS_CUBES
#define TB_BVH_HAS_QUADRICS TB_HAS_QUADRICS
#define TB_BVH_HAS_PLANAR TB_HAS_PLANAR
#define TB_BVH_HAS_TORI TB_HAS_TORI
#define TB_BVH_HAS_CSG TB_HAS_CSG
#define TB_BVH_STACK TB_STACK
#include "lib/bvh_traverse.glsl"

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.n)
        return;
    tb_gpu_ray r = rays[i];
    tb_bvh_hit b;
    bool have = tb_bvh_traverse(r, pc.nnodes, pc.any_hit != 0u, b);
    tb_gpu_hit h;
    h.t = have ? b.t : tb_inf();
    h.object = have ? b.object : TB_GPU_NO_HIT;
    h.face = have ? b.face : TB_GPU_NO_HIT;
    h.u = 0.0;
    h.v = 0.0;
    vec3 ng = have ? tb_bvh_normal(r, b) : vec3(0.0);
    h.ng[0] = ng.x;
    h.ng[1] = ng.y;
    h.ng[2] = ng.z;
    hits[i] = h;
}
