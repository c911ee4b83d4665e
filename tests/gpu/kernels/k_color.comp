// Paired test of lib/color.glsl. OP (a specialization constant) picks the
// routine: 0 sRGB encode, 1 sRGB decode (per component of xyz), 2 linear sRGB
// -> XYZ, 3 XYZ -> linear sRGB.
#version 450
#extension GL_GOOGLE_include_directive : require
#include "cases.h"
#include "lib/color.glsl"

layout(local_size_x_id = 0) in;
layout(constant_id = 1) const int OP = 0;
layout(std430, binding = 0) readonly buffer In { tb_case_f4 cases[]; };
layout(std430, binding = 1) writeonly buffer Out { tb_case_f4 results[]; };
layout(push_constant) uniform Push { uint n; } pc;

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.n)
        return;
    vec3 v = vec3(cases[i].x, cases[i].y, cases[i].z);
    vec3 r;
    if (OP == 0)
        r = vec3(tb_srgb_encode(v.x), tb_srgb_encode(v.y), tb_srgb_encode(v.z));
    else if (OP == 1)
        r = vec3(tb_srgb_decode(v.x), tb_srgb_decode(v.y), tb_srgb_decode(v.z));
    else if (OP == 2)
        r = tb_linear_srgb_to_xyz(v);
    else
        r = tb_xyz_to_linear_srgb(v);
    results[i] = tb_case_f4(r.x, r.y, r.z, 0.0);
}
