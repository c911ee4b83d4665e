// Closest hit (or any hit) of each ray with the scene's GPU-resident
// geometry: a BVH converted from the CPU BVH (shared/bvh.h) over world-space
// triangles, sphere and cube objects. One invocation per ray, fixed-size traversal stack. Objects of
// kinds this kernel does not implement are not in its BVH: host/gpu/intersect.c
// tests them on the CPU afterwards with tmax = this kernel's t and merges by
// the tie rule (docs/gpu.md, "Intersect kernel").
//
// Triangles: Woop, Benthin and Wald's watertight test (JCGT 2013), the CPU's
// method (host/render/scene_mesh.c), in float in world space. Spheres: the
// ray mapped to object space by the float world-to-object map, then
// lib/sphere.glsl (host/object's method in float); cubes likewise, clipped
// by their six planes (tb_cube_hit). Ties in t are
// broken as on the CPU (docs/accel.md, "Tie rule"): lower object, then face,
// then reference index. Hit records are tb_gpu_hit (shared/hit.h); (u, v) are
// left 0 and filled by the host for the winning triangle.
#version 450
#extension GL_GOOGLE_include_directive : require

#include "shared/bvh.h"
#include "shared/hit.h"
#include "shared/ray.h"
#include "lib/aabb.glsl"
#include "lib/sphere.glsl"

layout(local_size_x_id = 0) in;
// Primitive kinds present in the scene: a kind the scene lacks is compiled out.
layout(constant_id = 1) const bool TB_HAS_TRIANGLES = true;
layout(constant_id = 3) const bool TB_HAS_SPHERES = false;
layout(constant_id = 4) const bool TB_HAS_CUBES = false;
// Traversal stack entries: the host sets the BVH's depth (rounded up to a
// multiple of 8); one entry per level is enough, since every inner node
// pushes one child and continues with the other. The CPU BVH's depth is
// below 96 (docs/accel.md).
layout(constant_id = 2) const int TB_STACK = 128;

layout(std430, binding = 0) readonly buffer Rays { tb_gpu_ray rays[]; };
layout(std430, binding = 1) readonly buffer Nodes { tb_gpu_bvh_node nodes[]; };
layout(std430, binding = 2) readonly buffer Tris { tb_gpu_tri tris[]; };
layout(std430, binding = 3) writeonly buffer Hits { tb_gpu_hit hits[]; };
layout(std430, binding = 4) readonly buffer Placed { tb_gpu_placed placed[]; };
layout(std430, binding = 5) readonly buffer Refs { uint refs[]; };

layout(push_constant) uniform Push {
    uint n;        // rays
    uint any_hit;  // 1: occlusion (stop at the first hit found), 0: closest hit
    uint nnodes;   // 0: empty scene
    uint pad;
} pc;

// Traversal slack of the CPU BVH (TB__ACCEL_T_TOL = 2^-16): boxes are pruned
// with [tmin, best t] widened by this relative amount on each side.
const float TB_T_TOL = 1.52587890625e-5;

// The ray prepared for the watertight test.
struct tb_wray {
    vec3 o;
    int kx, ky, kz;
    float sx, sy, sz;
};

tb_wray tb_wray_init(vec3 o, vec3 d)
{
    tb_wray w;
    w.o = o;
    vec3 a = abs(d);
    int kz = a.x > a.y ? (a.x > a.z ? 0 : 2) : (a.y > a.z ? 1 : 2);
    int kx = kz == 2 ? 0 : kz + 1;
    int ky = kx == 2 ? 0 : kx + 1;
    if (d[kz] < 0.0) {
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

// The watertight test in float; t on a hit.
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

// Relative difference in t below which two hits are a tie (2^-18, 64 ulps):
// the float t of two coincident triangles (a light set into a ceiling)
// differ by a few ulps, so the CPU tie rule (lower object, face, reference)
// decides among hits this close, not the rounding. Must equal TB__TIE_TOL in
// host/gpu/intersect.c.
const float TB_TIE_TOL = 3.814697265625e-6;

// The cube [-1,1]^3, host/object's method (intersect_planar.c) in float: the
// line from its point nearest the origin clipped by the six half-spaces in
// face order -x +x -y +y -z +z (the first face wins ties); the nearer end in
// [tmin, tmax]. Writes t and the face 0..5.
bool tb_cube_hit(vec3 o, vec3 d, float tmin, float tmax, out float t, out uint face)
{
    t = 0.0;
    face = 0u;
    precise float dd = dot(d, d);
    precise float t0 = -dot(o, d) / dd;
    precise vec3 p0 = vec3(o.x + t0 * d.x, o.y + t0 * d.y, o.z + t0 * d.z);
    float a = -tb_inf(), b = tb_inf();
    uint fa = 0u, fb = 0u;
    for (uint f = 0u; f < 6u; ++f) {
        uint axis = f >> 1;
        float sg = (f & 1u) != 0u ? 1.0 : -1.0;
        float den = sg * d[axis];
        precise float num = 1.0 - sg * p0[axis];
        if (den == 0.0) {
            if (num < 0.0)
                return false;
            continue;
        }
        float sv = num / den;
        if (den < 0.0) {
            if (sv > a) {
                a = sv;
                fa = f;
            }
        } else if (sv < b) {
            b = sv;
            fb = f;
        }
    }
    if (!(a <= b) || !tb_isfinite(a) || !tb_isfinite(b))
        return false;
    precise float ta = a + t0;
    precise float tb = b + t0;
    if (ta >= tmin && ta <= tmax) {
        t = ta;
        face = fa;
        return true;
    }
    if (tb >= tmin && tb <= tmax) {
        t = tb;
        face = fb;
        return true;
    }
    return false;
}

// True if (t, object, face, ref) precedes the best so far (the CPU tie rule,
// with ties up to TB_TIE_TOL).
bool tb_better(float t, uint object, uint face, uint ref, bool have, float bt, uint bo, uint bf, uint br)
{
    if (!have)
        return true;
    if (abs(t - bt) > TB_TIE_TOL * abs(bt))
        return t < bt;
    if (object != bo)
        return object < bo;
    if (face != bf)
        return face < bf;
    return ref < br;
}

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.n)
        return;
    tb_gpu_ray r = rays[i];
    bool have = false;
    float bt = r.tmax;
    uint bo = TB_GPU_NO_HIT, bf = 0u, br = 0u, bref = 0u;
    bool valid = tb_isfinite(r.o.x) && tb_isfinite(r.o.y) && tb_isfinite(r.o.z) && tb_isfinite(r.d.x) &&
                 tb_isfinite(r.d.y) && tb_isfinite(r.d.z) && tb_isfinite(r.tmin) &&
                 !(r.d.x == 0.0 && r.d.y == 0.0 && r.d.z == 0.0) && r.tmin <= r.tmax;
    if ((TB_HAS_TRIANGLES || TB_HAS_SPHERES) && valid && pc.nnodes > 0u) {
        vec3 inv = tb_ray_inv_dir(r.d);
        tb_wray w = tb_wray_init(r.o, r.d);
        float lo_t = r.tmin - abs(r.tmin) * TB_T_TOL;
        uint stack[TB_STACK];
        int sp = 0;
        uint node = 0u;
        for (;;) {
            tb_gpu_bvh_node nd = nodes[node];
            float hi_t = bt + abs(bt) * TB_T_TOL;
            float t0, t1;
            bool enter = tb_aabb_slab(nd.lo, nd.hi, r.o, r.d, inv, lo_t, hi_t, t0, t1);
            if (enter) {
                uint count = nd.count & 0xffffu;
                if (count == 0u) {
                    // Inner: nearer child first (by the split axis and the ray's sign).
                    uint axis = nd.count >> 16;
                    uint first = node + 1u, second = nd.offset;
                    if (r.d[axis] < 0.0) {
                        uint s = first;
                        first = second;
                        second = s;
                    }
                    if (sp < TB_STACK)
                        stack[sp++] = second;
                    node = first;
                    continue;
                }
                for (uint k = nd.offset; k < nd.offset + count; ++k) {
                    uint ref = refs[k];
                    float t;
                    uint object, face, sref;
                    if (TB_HAS_CUBES && (ref & TB_GPU_REF_CUBE) != 0u) {
                        tb_gpu_placed sp = placed[ref & TB_GPU_REF_INDEX];
                        precise vec3 so = vec3(dot(sp.r0, r.o) + sp.w0, dot(sp.r1, r.o) + sp.w1, dot(sp.r2, r.o) + sp.w2);
                        precise vec3 sd = vec3(dot(sp.r0, r.d), dot(sp.r1, r.d), dot(sp.r2, r.d));
                        uint cf;
                        if (!tb_cube_hit(so, sd, r.tmin, r.tmax, t, cf))
                            continue;
                        object = sp.object;
                        face = sp.face + cf;
                        sref = sp.ref;
                    } else if (TB_HAS_SPHERES && (ref & TB_GPU_REF_SPHERE) != 0u) {
                        tb_gpu_placed sp = placed[ref & TB_GPU_REF_INDEX];
                        precise vec3 so = vec3(dot(sp.r0, r.o) + sp.w0, dot(sp.r1, r.o) + sp.w1, dot(sp.r2, r.o) + sp.w2);
                        precise vec3 sd = vec3(dot(sp.r0, r.d), dot(sp.r1, r.d), dot(sp.r2, r.d));
                        if (!tb_sphere_intersect(so, sd, 1.0, r.tmin, r.tmax, t))
                            continue;
                        object = sp.object;
                        face = sp.face;
                        sref = sp.ref;
                    } else if (TB_HAS_TRIANGLES && (ref & (TB_GPU_REF_SPHERE | TB_GPU_REF_CUBE)) == 0u) {
                        tb_gpu_tri tri = tris[ref];
                        if (!tb_tri_hit(w, tri.v0, tri.v1, tri.v2, t) || t < r.tmin || t > r.tmax)
                            continue;
                        object = tri.object;
                        face = tri.face;
                        sref = tri.ref;
                    } else {
                        continue;
                    }
                    if (tb_better(t, object, face, sref, have, bt, bo, bf, br)) {
                        have = true;
                        bt = t;
                        bo = object;
                        bf = face;
                        br = sref;
                        bref = ref;
                    }
                    if (pc.any_hit != 0u)
                        break;
                }
                if (have && pc.any_hit != 0u)
                    break;
            }
            if (sp == 0)
                break;
            node = stack[--sp];
        }
    }
    tb_gpu_hit h;
    h.t = have ? bt : tb_inf();
    h.object = have ? bo : TB_GPU_NO_HIT;
    h.face = have ? bf : TB_GPU_NO_HIT;
    h.u = 0.0;
    h.v = 0.0;
    if (have) {
        vec3 ng;
        if (TB_HAS_CUBES && (bref & TB_GPU_REF_CUBE) != 0u) {
            // The face's object-space normal -> world by the inverse transpose.
            tb_gpu_placed sp = placed[bref & TB_GPU_REF_INDEX];
            uint f = bf - sp.face;
            float sg = (f & 1u) != 0u ? 1.0 : -1.0;
            vec3 n = (f >> 1) == 0u ? sp.r0 : ((f >> 1) == 1u ? sp.r1 : sp.r2);
            ng = sp.sign * normalize(sg * n);
        } else if (TB_HAS_SPHERES && (bref & TB_GPU_REF_SPHERE) != 0u) {
            // Object-space point -> world normal by the inverse transpose.
            tb_gpu_placed sp = placed[bref & TB_GPU_REF_INDEX];
            vec3 so = vec3(dot(sp.r0, r.o) + sp.w0, dot(sp.r1, r.o) + sp.w1, dot(sp.r2, r.o) + sp.w2);
            vec3 sd = vec3(dot(sp.r0, r.d), dot(sp.r1, r.d), dot(sp.r2, r.d));
            vec3 p = so + bt * sd;
            ng = sp.sign * normalize(sp.r0 * p.x + sp.r1 * p.y + sp.r2 * p.z);
        } else {
            ng = tris[bref].ng;
        }
        h.ng[0] = ng.x;
        h.ng[1] = ng.y;
        h.ng[2] = ng.z;
    } else {
        h.ng[0] = 0.0;
        h.ng[1] = 0.0;
        h.ng[2] = 0.0;
    }
    hits[i] = h;
}
