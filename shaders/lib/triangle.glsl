// Ray/triangle intersection: Woop, Benthin and Wald's watertight test
// ("Watertight Ray/Triangle Intersection", JCGT 2013), the CPU's method
// (host/render/scene_mesh.c), in float. The per-ray part (the permutation of
// the axes that makes d's largest component z, and the shear) is computed
// once by tb_wray_init; tb_tri_hit is then called per triangle.
//
// Watertight: a ray through an edge or vertex shared by two triangles hits
// at least one of them (the edge functions U, V, W are evaluated identically
// for both). All arithmetic is `precise` (no fused multiply-adds), as the C
// build (-ffp-contract=off). Tolerance against the CPU: docs/gpu.md.
#ifndef TB_LIB_TRIANGLE_GLSL
#define TB_LIB_TRIANGLE_GLSL

#include "float.glsl"

// The ray prepared for the watertight test.
struct tb_wray {
    vec3 o;          // ray origin
    int kx, ky, kz;  // axis permutation: kz the largest |d| component
    float sx, sy, sz; // shear constants d[kx]/d[kz], d[ky]/d[kz], 1/d[kz]
};

// The per-ray precomputation for ray o + t d (d not zero).
tb_wray tb_wray_init(vec3 o, vec3 d)
{
    tb_wray w;
    w.o = o;
    vec3 a = abs(d);
    int kz = a.x > a.y ? (a.x > a.z ? 0 : 2) : (a.y > a.z ? 1 : 2);
    int kx = kz == 2 ? 0 : kz + 1;
    int ky = kx == 2 ? 0 : kx + 1;
    if (d[kz] < 0.0) { // keep the winding: swap kx and ky
        int t = kx;
        kx = ky;
        ky = t;
    }
    w.kx = kx;
    w.ky = ky;
    w.kz = kz;
    w.sx = d[kx] / d[kz];
    w.sy = d[ky] / d[kz];
    w.sz = 1.0 / d[kz];
    return w;
}

// The watertight test against triangle (v0, v1, v2), both sides; true and
// the ray parameter t (finite, not range-checked: the caller compares it
// with its [tmin, tmax]) on a hit, false (t = 0) otherwise.
bool tb_tri_hit(tb_wray w, vec3 v0, vec3 v1, vec3 v2, out float t)
{
    t = 0.0;
    precise vec3 A = v0 - w.o, B = v1 - w.o, C = v2 - w.o;
    precise float ax = A[w.kx] - w.sx * A[w.kz], ay = A[w.ky] - w.sy * A[w.kz];
    precise float bx = B[w.kx] - w.sx * B[w.kz], by = B[w.ky] - w.sy * B[w.kz];
    precise float cx = C[w.kx] - w.sx * C[w.kz], cy = C[w.ky] - w.sy * C[w.kz];
    precise float U = cx * by - cy * bx;
    precise float V = ax * cy - ay * cx;
    precise float W = bx * ay - by * ax;
    if ((U < 0.0 || V < 0.0 || W < 0.0) && (U > 0.0 || V > 0.0 || W > 0.0))
        return false;
    precise float det = U + V + W;
    if (det == 0.0)
        return false;
    precise float T = U * (w.sz * A[w.kz]) + V * (w.sz * B[w.kz]) + W * (w.sz * C[w.kz]);
    t = T / det;
    return tb_isfinite(t);
}

#endif
