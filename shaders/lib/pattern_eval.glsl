// The patterns of a hit as the CPU's surface records evaluate them
// (raytrace_pattern.c): a pattern's value over a footprint (tb_texture_eval
// of the one-channel pattern texture) and the noise bump's shading normal
// (tb_bump_map through tb__rt_bump), from a tb_gpu_surface record
// (shared/shade.h). Used by the shade kernel (records built on the host)
// and the path tracer (records built on the device, lib/pathtrace.glsl).
// The includer defines `int tb_perm(int i)` (lib/pattern.glsl) and the
// constant `uint PATTERN_KINDS` (bit k: patterns of kind k, TB_GPU_PATTERN_*,
// exist; the others' code is compiled out).
#ifndef TB_LIB_PATTERN_EVAL_GLSL
#define TB_LIB_PATTERN_EVAL_GLSL

#include "shared/shade.h"
#include "pattern.glsl"

// The value of pattern pt (raytrace_pattern.c's one-channel texture: a blend
// factor in [0, 1]; a noise bump's fBm in [-1, 1]) at (u, v) with footprint
// fp (du/dx, dv/dx, du/dy, dv/dy; zero: none) or, in object space, at po
// with its change per pixel dpdx, dpdy (tb_texture_eval).
float pattern_value(tb_gpu_pattern pt, bool bump, float u, float v, vec4 fp, vec3 po, vec3 dpdx, vec3 dpdy)
{
    float s = pt.su * u, r = pt.sv * v;
    vec4 f4 = vec4(pt.su * fp.x, pt.sv * fp.y, pt.su * fp.z, pt.sv * fp.w);
    if ((PATTERN_KINDS & (1u << TB_GPU_PATTERN_CHECKER)) != 0u && pt.kind == TB_GPU_PATTERN_CHECKER) {
        // box-filtered: the footprint's bounding box (in cells)
        if (pt.solid != 0u) {
            vec3 c = po * pt.su;
            vec3 h = (abs(dpdx) + abs(dpdy)) * (0.5 * abs(pt.su));
            return tb_checker3_box_average(c - h, c + h);
        }
        float hs = 0.5 * (abs(f4.x) + abs(f4.z)), ht = 0.5 * (abs(f4.y) + abs(f4.w));
        return tb_checker_box_average(s - hs, s + hs, r - ht, r + ht);
    }
    if ((PATTERN_KINDS & (1u << TB_GPU_PATTERN_NOISE)) != 0u && pt.kind == TB_GPU_PATTERN_NOISE) {
        vec3 p = vec3(s, r, 0.0), dx = vec3(f4.x, f4.y, 0.0), dy = vec3(f4.z, f4.w, 0.0);
        if (pt.solid != 0u) {
            p = po * pt.su;
            dx = dpdx * pt.su;
            dy = dpdy * pt.su;
        }
        float f = clamp(0.5 + 0.5 * tb_fbm3(p, dx, dy, 0.5, pt.octaves), 0.0, 1.0);
        return bump ? -1.0 + f * 2.0 : f;
    }
    return 0.0;
}

// The bump-mapped shading normal (texture_proc.c's tb_bump_map through
// raytrace_pattern.c's tb__rt_bump): the height at the point and one step
// along u and v (the footprint's size, else 1/2048), the tangents tilted by
// the differences; on n's side; n itself for degenerate steps or tangents.
vec3 bump_normal(tb_gpu_pattern pt, tb_gpu_surface g, vec3 n)
{
    vec3 bn = dot(cross(g.dpdu, g.dpdv), n) < 0.0 ? -n : n;
    vec4 fp = vec4(g.fp0, g.fp1, g.fp2, g.fp3);
    float du = 0.5 * (abs(fp.x) + abs(fp.z)), dv = 0.5 * (abs(fp.y) + abs(fp.w));
    if (!(du > 0.0) || isinf(du))
        du = 1.0 / 2048.0;
    if (!(dv > 0.0) || isinf(dv))
        dv = 1.0 / 2048.0;
    bool solid = pt.solid != 0u;
    vec3 P = solid ? g.po : vec3(0.0), dx = solid ? g.po_dx : vec3(0.0), dy = solid ? g.po_dy : vec3(0.0);
    bool tsp = solid && (any(notEqual(g.po_du, vec3(0.0))) || any(notEqual(g.po_dv, vec3(0.0))));
    vec3 tdu = tsp ? g.po_du : g.dpdu, tdv = tsp ? g.po_dv : g.dpdv;
    float uu = g.u + du, vv = g.v + dv;
    float du_eff = uu - g.u, dv_eff = vv - g.v;
    if (du_eff == 0.0 || dv_eff == 0.0)
        return n;
    float h = pt.height * pattern_value(pt, true, g.u, g.v, fp, P, dx, dy);
    float hu = pt.height * pattern_value(pt, true, uu, g.v, fp, P + tdu * du, dx, dy);
    float hv = pt.height * pattern_value(pt, true, g.u, vv, fp, P + tdv * dv, dx, dy);
    vec3 pu = g.dpdu + bn * ((hu - h) / du_eff);
    vec3 pv = g.dpdv + bn * ((hv - h) / dv_eff);
    vec3 nn = cross(pu, pv);
    float len = length(nn);
    if (!(len > 0.0) || isinf(len))
        return n;
    nn /= len;
    if (dot(nn, bn) < 0.0)
        nn = -nn;
    return dot(nn, n) < 0.0 ? -nn : nn;
}

#endif
