// Robust ray/box slab test: the GLSL twin of tb_aabb_slab() and
// tb_aabb_intersect_ray() (util/math/aabb.h).
//
// Same steps as the C code, two differences forced by Vulkan's arithmetic:
//  1. An axis with d == 0 (either sign) is handled by a branch: the ray is
//     parallel to that slab and either inside it (no constraint) or outside
//     (miss). C reaches the same answer through (plane - o) * +-inf, which
//     is +-inf or NaN; Vulkan does not promise NaN, so the GPU may not lean
//     on it. The outcome is identical.
//  2. The outward widening is 2 gamma(9) instead of 2 gamma(3): 1/d is only
//     within 2.5 ulp on a Vulkan device (5u), and with the subtraction and
//     product (each within 2u even if the device rounds toward zero) a per-
//     axis t has relative error below 9u; widening by 18u covers that and
//     the widening's own rounding. So the test stays conservative on any
//     conformant device: it never misses a box the exact ray meets.
// Result: same hit/miss as C except for near misses within the wider margin;
// t0, t1 within a relative 40 u = 40 * 2^-24 (~2.4e-6) of C's values: the GPU
// value is within 9u + 18u + 2u of the exact one, C's within 10u
// (docs/gpu.md, "Tolerances").
#ifndef TB_LIB_AABB_GLSL
#define TB_LIB_AABB_GLSL

#include "float.glsl"

// 1 - 2 gamma(9) and 1 + 2 gamma(9) rounded to float: 1 -+ 18 * 2^-24 (bits
// 0x3f7fffee, 0x3f800009; the literals are their exact decimal values).
const float TB_SLAB_SHRINK = 0.99999892711639404;
const float TB_SLAB_GROW = 1.000001072883606;

// One axis of tb_aabb_slab (GLSL reserves "__", so helpers are not marked
// private by name); false if the ray misses the slab.
bool tb_aabb_slab_axis(float o, float d, float inv, float lo, float hi, inout float t0, inout float t1)
{
    if (d == 0.0)
        return o >= lo && o <= hi; // parallel: inside the slab for every t, or never
    bool neg = d < 0.0;
    precise float tn = ((neg ? hi : lo) - o) * inv;
    precise float tf = ((neg ? lo : hi) - o) * inv;
    tn = tn > 0.0 ? tn * TB_SLAB_SHRINK : tn * TB_SLAB_GROW;
    tf = tf > 0.0 ? tf * TB_SLAB_GROW : tf * TB_SLAB_SHRINK;
    if (tn > t0)
        t0 = tn;
    if (tf < t1)
        t1 = tf;
    return true;
}

// Slab test with d and a precomputed inv_d = 1/d (traversal loops compute it
// once per ray): true if the segment [tmin, tmax] of o + t d meets the closed
// box [lo, hi], and then [t0, t1] (within [tmin, tmax]) holds every t inside
// it. An empty box (lo > hi on an axis) is never hit.
bool tb_aabb_slab(vec3 lo, vec3 hi, vec3 o, vec3 d, vec3 inv_d, float tmin, float tmax,
                  out float t0, out float t1)
{
    float a = tmin, z = tmax;
    t0 = 0.0;
    t1 = 0.0;
    if (!(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z))
        return false;
    if (!tb_aabb_slab_axis(o.x, d.x, inv_d.x, lo.x, hi.x, a, z) ||
        !tb_aabb_slab_axis(o.y, d.y, inv_d.y, lo.y, hi.y, a, z) ||
        !tb_aabb_slab_axis(o.z, d.z, inv_d.z, lo.z, hi.z, a, z) || !(a <= z))
        return false;
    t0 = a;
    t1 = z;
    return true;
}

// inv_d = 1/d for tb_aabb_slab (components with d == 0 are never used).
vec3 tb_ray_inv_dir(vec3 d)
{
    return vec3(d.x != 0.0 ? 1.0 / d.x : 0.0, d.y != 0.0 ? 1.0 / d.y : 0.0, d.z != 0.0 ? 1.0 / d.z : 0.0);
}

// tb_aabb_slab for a ray record.
bool tb_aabb_intersect_ray(vec3 lo, vec3 hi, tb_gpu_ray r, out float t0, out float t1)
{
    return tb_aabb_slab(lo, hi, r.o, r.d, tb_ray_inv_dir(r.d), r.tmin, r.tmax, t0, t1);
}

#endif
