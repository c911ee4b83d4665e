// Contraction probe: x*y + z written three ways. `precise` must round the
// product and the sum separately (as C does with -ffp-contract=off); the
// plain expression may be fused by the compiler; fma() may or may not be
// fused by the device (Vulkan allows both).
#version 450
#extension GL_GOOGLE_include_directive : require
#include "cases.h"

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
    precise float exact_order = c.x * c.y + c.z;
    float plain = c.x * c.y + c.z;
    float fused = fma(c.x, c.y, c.z);
    results[i] = tb_case_f4(exact_order, plain, fused, 0.0);
}
