// Paired test of lib/sphere.glsl: one ray/sphere pair per invocation.
#version 450
#extension GL_GOOGLE_include_directive : require
#include "cases.h"
#include "lib/sphere.glsl"

layout(local_size_x_id = 0) in;
layout(std430, binding = 0) readonly buffer In { tb_case_sphere cases[]; };
layout(std430, binding = 1) writeonly buffer Out { tb_case_box_out results[]; };
layout(push_constant) uniform Push { uint n; } pc;

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.n)
        return;
    tb_case_sphere c = cases[i];
    float t;
    bool hit = tb_sphere_intersect(c.ray.o, c.ray.d, c.radius, c.ray.tmin, c.ray.tmax, t);
    results[i] = tb_case_box_out(hit ? 1u : 0u, t, 0.0, 0u);
}
