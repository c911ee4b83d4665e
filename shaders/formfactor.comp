// Ray-cast form factors (Wallace, Elmquist and Haines 1989) from one shooter,
// given by sample points, to many receivers (differential areas), with
// visibility through a BVH over the occluder triangles (docs/gpu.md,
// "Form-factor kernel"). The GPU twin of tb_ff_raycast_batch
// (host/radiosity/formfactor.h); host side host/gpu/formfactor.c.
//
// TB_FF_LANES invocations per receiver: for each sample point s_k of the shooter
// (unit normal ns, each standing for da = area / npts), with d = s_k - p,
//     cos_r = n.d / r,  cos_s = -ns.d / r,  r^2 = d.d,
//     F += cos_s cos_r da / (pi r^2 + da)      (the disk approximation, eq. 5)
// over the samples in front of both surfaces whose segment is not blocked.
// Visibility: any occluder hit on p + t d for t in
// [TB_FF_SEGMENT_EPS, 1 - TB_FF_SEGMENT_EPS] (the CPU's rule), through the
// intersect kernel's traversal (lib/bvh_traverse.glsl) over triangles only.
#version 450
#extension GL_GOOGLE_include_directive : require

#include "shared/bvh.h"
#include "shared/formfactor.h"
#include "shared/ray.h"

layout(local_size_x_id = 0) in;
// Traversal stack entries: the BVH's depth rounded up to a multiple of 8.
layout(constant_id = 1) const int TB_STACK = 128;
// Occluders present: without them the traversal is compiled out.
layout(constant_id = 2) const bool TB_FF_OCCLUSION = true;
// Write one visibility bit per (receiver, sample) (testbed validate's
// per-segment comparison); the solver's calls leave it off.
layout(constant_id = 3) const bool TB_FF_VIS_BITS = false;
// Invocations per receiver: a power of two dividing the workgroup width.
layout(constant_id = 4) const uint TB_FF_LANES = 16u;

layout(std430, binding = 0) readonly buffer Receivers { tb_gpu_ff_receiver receivers[]; };
layout(std430, binding = 1) readonly buffer Samples { tb_gpu_ff_sample samples[]; };
// Nodes, triangles and references as texel buffers (RGBA32UI, RGBA32UI and
// R32UI views of the tb_gpu_bvh_node, tb_gpu_tri and uint arrays), as the
// intersect kernel binds them: branch-free gathers on lavapipe.
layout(binding = 2) uniform usamplerBuffer node_texels;
layout(binding = 3) uniform usamplerBuffer tri_texels;
layout(std430, binding = 4) readonly buffer Placed { tb_gpu_placed placed[]; };
layout(binding = 5) uniform usamplerBuffer ref_texels;
layout(std430, binding = 6) writeonly buffer Result { float ff[]; };
layout(std430, binding = 7) buffer Visible { uint vis_bits[]; };

layout(push_constant) uniform Push { tb_gpu_ff_push pc; };

// Occluders are triangles only (quads arrive as two).
#define TB_BVH_NODE_TEXELS node_texels
#define TB_BVH_TRI_TEXELS tri_texels
#define TB_BVH_PLACED placed
#define TB_BVH_REF_TEXELS ref_texels
#define TB_BVH_HAS_TRIANGLES TB_FF_OCCLUSION
#define TB_BVH_HAS_SPHERES false
#define TB_BVH_HAS_CUBES false
#define TB_BVH_HAS_QUADRICS false
#define TB_BVH_HAS_PLANAR false
#define TB_BVH_HAS_TORI false
#define TB_BVH_HAS_CSG false
#define TB_BVH_STACK TB_STACK
#include "lib/bvh_traverse.glsl"

// TB_FF_SEGMENT_EPS (host/radiosity/formfactor.h): 1e-4 rounded to float.
const float TB_FF_EPS = 1e-4;
const float TB_PI = 3.14159265358979323846;

// The partial sums of one workgroup's invocations.
shared float tb_part[gl_WorkGroupSize.x];

void main()
{
    // TB_FF_LANES consecutive invocations share a receiver, lane j taking
    // samples j, j + LANES, ...: the lanes of a SIMD group trace segments
    // from one point to neighbouring points of the shooter, which traverse
    // the same BVH nodes (coherent), where one receiver per lane would not.
    uint i = gl_GlobalInvocationID.x / TB_FF_LANES, lane = gl_GlobalInvocationID.x % TB_FF_LANES;
    float sum = 0.0;
    if (i < pc.count) {
        vec3 p = receivers[i].p, n = receivers[i].n;
        for (uint k = lane; k < pc.npts; k += TB_FF_LANES) {
            vec3 s = samples[k].p;
            precise vec3 d = s - p; // receiver -> sample, the CPU's segment direction
            precise float cr = n.x * d.x + n.y * d.y + n.z * d.z;                // r cos(receiver)
            precise float cs = -(pc.ns.x * d.x + pc.ns.y * d.y + pc.ns.z * d.z); // r cos(shooter)
            bool vis = cr > 0.0 && cs > 0.0;
            if (vis && TB_FF_OCCLUSION && pc.nnodes > 0u) {
                tb_gpu_ray r;
                r.o = p;
                r.d = d;
                r.tmin = TB_FF_EPS;
                r.tmax = 1.0 - TB_FF_EPS;
                vis = !tb_bvh_occluded(r, pc.nnodes);
            }
            if (vis) {
                precise float r2 = d.x * d.x + d.y * d.y + d.z * d.z;
                precise float term = (cr * cs) / r2 * pc.da / (TB_PI * r2 + pc.da); // the CPU's order
                sum += term;
                if (TB_FF_VIS_BITS) // the host zeroed the words
                    atomicOr(vis_bits[i * pc.vis_words + (k >> 5)], 1u << (k & 31u));
            }
        }
    }
    // The receiver's first lane adds the partial sums in lane order (a fixed
    // order: the result does not depend on scheduling).
    tb_part[gl_LocalInvocationID.x] = sum;
    barrier();
    if (i < pc.count && lane == 0u) {
        float total = 0.0;
        for (uint j = 0u; j < TB_FF_LANES; ++j)
            total += tb_part[gl_LocalInvocationID.x + j];
        ff[i] = total;
    }
}
