// Paired test of lib/ggx.glsl and lib/pattern.glsl (shading_kernels.c). OP
// (a specialization constant) picks the routine; arguments a..h of each
// case, results in x, y, z, w:
//  0 D(a, m = (b, c, d))                1 Lambda(a, w = (b, c, d))
//  2 sample_vndf(a, w = (b, c, d), e, f) -> direction
//  3 vndf_pdf(a, w = (b, c, d), m = (e, f, g))
//  4 eval(a, wo = (b, c, d), wi = (e, f, g)) -> (scalar, m^5, pdf)
//  5 noise3(a, b, c)                    6 fbm3(p = (a, b, c), dpdx = (d, e, f), 0, omega 0.5, octaves g)
//  7 checker_box_average(a, b, c, d)    8 checker3_box_average((a, b, c), (d, e, f))
//  9 tex_lookup(record 0, filter h, u = a, v = b, fp = (c, d, e, f)) -> the texel value
// The noise permutation comes in binding 2 (tb_noise_permutation), as the
// shade kernel reads it from its colour table; a texture record (shared/shade.h)
// and its texels in bindings 3 and 4.
#version 450
#extension GL_GOOGLE_include_directive : require
#include "cases.h"
#include "lib/ggx.glsl"

layout(local_size_x_id = 0) in;
layout(constant_id = 1) const int OP = 0;
layout(std430, binding = 0) readonly buffer In { tb_case_f8 cases[]; };
layout(std430, binding = 1) writeonly buffer Out { tb_case_f4 results[]; };
layout(std430, binding = 2) readonly buffer Perm { float perm[]; };
layout(std430, binding = 3) readonly buffer TexInfo { uint texinfo[]; };
layout(std430, binding = 4) readonly buffer Texels { float texels[]; };
layout(push_constant) uniform Push { uint n; } pc;

int tb_perm(int i) { return int(perm[i & 255]); }
#include "lib/pattern.glsl"
uint tb_texinfo(uint i) { return texinfo[i]; }
float tb_texel(uint i) { return texels[i]; }
#include "lib/texture.glsl"

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.n)
        return;
    tb_case_f8 c = cases[i];
    vec3 v1 = vec3(c.b, c.c, c.d), v2 = vec3(c.e, c.f, c.g);
    vec4 r = vec4(0.0);
    if (OP == 0)
        r.x = tb_ggx_D(c.a, v1);
    else if (OP == 1)
        r.x = tb_ggx_lambda(c.a, v1);
    else if (OP == 2)
        r.xyz = tb_ggx_sample_vndf(c.a, v1, c.e, c.f);
    else if (OP == 3)
        r.x = tb_ggx_vndf_pdf(c.a, v1, normalize(v2));
    else if (OP == 4)
        r.xyz = tb_ggx_eval(c.a, v1, v2);
    else if (OP == 5)
        r.x = tb_noise3(vec3(c.a, c.b, c.c));
    else if (OP == 6)
        r.x = tb_fbm3(vec3(c.a, c.b, c.c), vec3(c.d, c.e, c.f), vec3(0.0), 0.5, int(c.g));
    else if (OP == 7)
        r.x = tb_checker_box_average(c.a, c.b, c.c, c.d);
    else if (OP == 8)
        r.x = tb_checker3_box_average(vec3(c.a, c.b, c.c), vec3(c.d, c.e, c.f));
    else
        r = tb_tex_lookup(0u, int(c.h), c.a, c.b, vec4(c.c, c.d, c.e, c.f));
    results[i] = tb_case_f4(r.x, r.y, r.z, r.w);
}
