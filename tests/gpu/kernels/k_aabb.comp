// Paired test of lib/aabb.glsl: one ray/box pair per invocation.
#version 450
#extension GL_GOOGLE_include_directive : require
#include "cases.h"
#include "lib/aabb.glsl"

layout(local_size_x_id = 0) in;
layout(std430, binding = 0) readonly buffer In { tb_case_box cases[]; };
layout(std430, binding = 1) writeonly buffer Out { tb_case_box_out results[]; };
layout(push_constant) uniform Push { uint n; } pc;

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.n)
        return;
    tb_case_box c = cases[i];
    float t0, t1;
    bool hit = tb_aabb_intersect_ray(c.lo, c.hi, c.ray, t0, t1);
    results[i] = tb_case_box_out(hit ? 1u : 0u, t0, t1, 0u);
}
