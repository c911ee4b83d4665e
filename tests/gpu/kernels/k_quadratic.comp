// Paired test of lib/quadratic.glsl: (a, b, c) -> (number of roots, r0, r1).
#version 450
#extension GL_GOOGLE_include_directive : require
#include "cases.h"
#include "lib/quadratic.glsl"

layout(local_size_x_id = 0) in;
layout(std430, binding = 0) readonly buffer In { tb_case_f4 cases[]; };
layout(std430, binding = 1) writeonly buffer Out { tb_case_f4 results[]; };
layout(push_constant) uniform Push { uint n; } pc;

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.n)
        return;
    tb_case_f4 c = cases[i];
    float r0, r1;
    int n = tb_quadratic(c.x, c.y, c.z, r0, r1);
    results[i] = tb_case_f4(float(n), r0, r1, 0.0);
}
