// Closest-hit and any-hit (occlusion) traversal of the GPU scene that
// host/gpu/intersect.c uploads (shaders/shared/bvh.h): a BVH converted from
// the CPU BVH over world-space triangles, placed analytic objects of every
// kind and CSG trees of them (lib/csg.glsl), usable by any kernel that binds those buffers
// (tb_gpu_scene_bindings in host/gpu/intersect.h).
//
// GLSL has no buffer parameters, so the includer names its buffers by macros
// before the #include (its own set/binding numbers):
//
//     layout(std430, binding = 5) readonly buffer Nodes { tb_gpu_bvh_node nodes[]; };
//     layout(std430, binding = 6) readonly buffer Tris { tb_gpu_tri tris[]; };
//     layout(std430, binding = 7) readonly buffer Placed { tb_gpu_placed placed[]; };
//     layout(std430, binding = 8) readonly buffer Refs { uint refs[]; };
//     #define TB_BVH_NODES nodes
//     #define TB_BVH_TRIS tris
//     #define TB_BVH_PLACED placed
//     #define TB_BVH_REFS refs
//     #include "lib/bvh_traverse.glsl"
//
// Faster on CPU drivers (lavapipe), where a storage-buffer load with per-lane
// indices is a scalar loop with a branch per lane and component, while a
// texelFetch is a branch-free gather: bind the same buffers also (or
// instead) as texel buffers, tb_gpu_binding_kind TB_GPU_BIND_TEXELS_RGBA32UI
// for nodes and triangles, TB_GPU_BIND_TEXELS_R32UI for the references, and
// name them instead of (or besides) the arrays:
//
//     layout(binding = 5) uniform usamplerBuffer node_texels;
//     layout(binding = 6) uniform usamplerBuffer tri_texels;
//     layout(binding = 8) uniform usamplerBuffer ref_texels;
//     #define TB_BVH_NODE_TEXELS node_texels
//     #define TB_BVH_TRI_TEXELS tri_texels
//     #define TB_BVH_REF_TEXELS ref_texels
//
// Each of the three is independent (the array of a kind given as texels is
// then not needed); TB_BVH_PLACED is always an array.
//
// Optional, to compile out kinds the scene lacks (e.g. from specialization
// constants the host sets from tb_gpu_scene_bindings): TB_BVH_HAS_TRIANGLES,
// TB_BVH_HAS_SPHERES, TB_BVH_HAS_CUBES, TB_BVH_HAS_QUADRICS (cylinders,
// cones, conics), TB_BVH_HAS_PLANAR (pyramids, prisms, arches),
// TB_BVH_HAS_TORI, TB_BVH_HAS_CSG (each defaults to true: correct for
// every scene, only slower), and TB_BVH_STACK, the traversal stack entries
// (defaults to 96; the scene's depth, tb_gpu_scene_bindings.stack, is enough).
// Kinds added later get their own TB_BVH_HAS_* defaulting to true, so an
// includer never has to change for the kernel to stay correct.
//
// Then:
//     tb_bvh_hit h;
//     if (tb_bvh_closest(ray, nnodes, h)) ... h.t, h.object, h.face, tb_bvh_normal(ray, h)
//     if (tb_bvh_occluded(ray, nnodes)) ...  // anything with tmin <= t <= tmax
//
// Ties in t are broken as on the CPU (docs/accel.md, "Tie rule"): lower
// object, then face, then reference index, with ties up to TB_TIE_TOL.
// (u, v) are not computed here (host/gpu/intersect.c does it on the host).
#ifndef TB_LIB_BVH_TRAVERSE_GLSL
#define TB_LIB_BVH_TRAVERSE_GLSL

#include "shared/bvh.h"
#include "shared/hit.h"
#include "shared/ray.h"
#include "aabb.glsl"
#include "csg.glsl"
#include "cube.glsl"
#include "revolved.glsl"
#include "sphere.glsl"
#include "torus.glsl"
#include "triangle.glsl"

#if (!defined(TB_BVH_NODES) && !defined(TB_BVH_NODE_TEXELS)) || (!defined(TB_BVH_TRIS) && !defined(TB_BVH_TRI_TEXELS)) || \
    !defined(TB_BVH_PLACED) || (!defined(TB_BVH_REFS) && !defined(TB_BVH_REF_TEXELS))
#error "define TB_BVH_NODES, TB_BVH_TRIS, TB_BVH_PLACED and TB_BVH_REFS (or their _TEXELS) first"
#endif
#ifndef TB_BVH_HAS_TRIANGLES
#define TB_BVH_HAS_TRIANGLES true
#endif
#ifndef TB_BVH_HAS_SPHERES
#define TB_BVH_HAS_SPHERES true
#endif
#ifndef TB_BVH_HAS_CUBES
#define TB_BVH_HAS_CUBES true
#endif
#ifndef TB_BVH_HAS_QUADRICS
#define TB_BVH_HAS_QUADRICS true
#endif
#ifndef TB_BVH_HAS_PLANAR
#define TB_BVH_HAS_PLANAR true
#endif
#ifndef TB_BVH_HAS_TORI
#define TB_BVH_HAS_TORI true
#endif
#ifndef TB_BVH_HAS_CSG
#define TB_BVH_HAS_CSG true
#endif
#ifndef TB_BVH_STACK
#define TB_BVH_STACK 96
#endif
// Leaves whose placed objects wait for testing (tb_bvh_traverse): a longer
// list runs that code in fewer passes but prunes with a later best t (8 was
// 1.5x slower than 1 on a scene of primitives and CSG trees on lavapipe).
#ifndef TB_BVH_DEFER
#define TB_BVH_DEFER 1
#endif
// Any kind besides triangles present (their tests are deferred).
#define TB_BVH_HAS_PLACED_KINDS                                                                                      \
    (TB_BVH_HAS_SPHERES || TB_BVH_HAS_CUBES || TB_BVH_HAS_QUADRICS || TB_BVH_HAS_PLANAR || TB_BVH_HAS_TORI ||        \
     TB_BVH_HAS_CSG)

// Traversal slack of the CPU BVH (TB__ACCEL_T_TOL = 2^-16): boxes are pruned
// with [tmin, best t] widened by this relative amount on each side.
const float TB_T_TOL = 1.52587890625e-5;

// Relative difference in t below which two hits are a tie (2^-18, 64 ulps):
// the float t of two coincident triangles (a light set into a ceiling)
// differ by a few ulps, so the CPU tie rule (lower object, face, reference)
// decides among hits this close, not the rounding. Must equal TB__TIE_TOL in
// host/gpu/intersect.c.
const float TB_TIE_TOL = 3.814697265625e-6;

// A hit found by traversal.
struct tb_bvh_hit {
    float t;     // ray parameter
    uint object; // top-level object index
    uint face;   // face ID (host/object/param.h numbering, plus the object's face base)
    uint sref;   // index of the primitive's reference in the CPU scene (tie rule's last key)
    uint leaf;   // the GPU leaf reference (TB_GPU_REF_*), for tb_bvh_normal
};

// Child record `i` (tb_gpu_bvh_node: two 16-byte texels); records 2n and
// 2n + 1 are the children of inner node n.
void tb_bvh_fetch_node(uint i, out vec3 lo, out vec3 hi, out uint offset, out uint count)
{
#ifdef TB_BVH_NODE_TEXELS
    uvec4 a = texelFetch(TB_BVH_NODE_TEXELS, int(2u * i));
    uvec4 b = texelFetch(TB_BVH_NODE_TEXELS, int(2u * i + 1u));
    lo = uintBitsToFloat(a.xyz);
    offset = a.w;
    hi = uintBitsToFloat(b.xyz);
    count = b.w;
#else
    tb_gpu_bvh_node nd = TB_BVH_NODES[i];
    lo = nd.lo;
    offset = nd.offset;
    hi = nd.hi;
    count = nd.count;
#endif
}

// Leaf reference k.
uint tb_bvh_fetch_ref(uint k)
{
#ifdef TB_BVH_REF_TEXELS
    return texelFetch(TB_BVH_REF_TEXELS, int(k)).x;
#else
    return TB_BVH_REFS[k];
#endif
}

// Triangle i's vertices (tb_gpu_tri: four 16-byte texels).
void tb_bvh_fetch_tri(uint i, out vec3 v0, out vec3 v1, out vec3 v2)
{
#ifdef TB_BVH_TRI_TEXELS
    v0 = uintBitsToFloat(texelFetch(TB_BVH_TRI_TEXELS, int(4u * i)).xyz);
    v1 = uintBitsToFloat(texelFetch(TB_BVH_TRI_TEXELS, int(4u * i + 1u)).xyz);
    v2 = uintBitsToFloat(texelFetch(TB_BVH_TRI_TEXELS, int(4u * i + 2u)).xyz);
#else
    v0 = TB_BVH_TRIS[i].v0;
    v1 = TB_BVH_TRIS[i].v1;
    v2 = TB_BVH_TRIS[i].v2;
#endif
}

// Triangle i's keys: object, face, reference index.
uvec3 tb_bvh_fetch_tri_keys(uint i)
{
#ifdef TB_BVH_TRI_TEXELS
    return uvec3(texelFetch(TB_BVH_TRI_TEXELS, int(4u * i)).w, texelFetch(TB_BVH_TRI_TEXELS, int(4u * i + 1u)).w,
                 texelFetch(TB_BVH_TRI_TEXELS, int(4u * i + 2u)).w);
#else
    return uvec3(TB_BVH_TRIS[i].object, TB_BVH_TRIS[i].face, TB_BVH_TRIS[i].ref);
#endif
}

// Triangle i's unit geometric normal.
vec3 tb_bvh_fetch_tri_normal(uint i)
{
#ifdef TB_BVH_TRI_TEXELS
    return uintBitsToFloat(texelFetch(TB_BVH_TRI_TEXELS, int(4u * i + 3u)).xyz);
#else
    return TB_BVH_TRIS[i].ng;
#endif
}

// The shape of the revolved object whose placed record is idx (its second
// record, shared/bvh.h).
tb_revolved tb_bvh_revolved(uint idx)
{
    tb_gpu_placed s = TB_BVH_PLACED[idx + 1u];
    uint flags = floatBitsToUint(s.r1.y);
    tb_revolved q;
    q.c = s.r0;
    q.z0 = s.w0;
    q.z1 = s.r1.x;
    q.caps = (flags & TB_GPU_REVOLVED_CAPS) != 0u;
    q.closed0 = (flags & TB_GPU_REVOLVED_CLOSED0) != 0u;
    q.closed1 = (flags & TB_GPU_REVOLVED_CLOSED1) != 0u;
    return q;
}

// Word j (0..15, member order) of placed record `rec`: the payload of shape
// and program records (shared/bvh.h).
uint tb_bvh_placed_word(uint rec, uint j)
{
    tb_gpu_placed p = TB_BVH_PLACED[rec];
    uint q = j >> 2;
    uvec4 row = q == 0u ? floatBitsToUint(vec4(p.r0, p.w0))
                        : (q == 1u ? floatBitsToUint(vec4(p.r1, p.w1))
                                   : (q == 2u ? floatBitsToUint(vec4(p.r2, p.w2))
                                              : uvec4(p.object, p.face, p.ref, floatBitsToUint(p.sign))));
    return row[j & 3u];
}

// Profile vertex k of the prism whose vertices start at placed record
// `base` (8 per record, shared/bvh.h); declared by lib/planar.glsl.
vec2 tb_prism_vertex(uint base, uint k)
{
    uint rec = base + (k >> 3), j = 2u * (k & 7u);
    return uintBitsToFloat(uvec2(tb_bvh_placed_word(rec, j), tb_bvh_placed_word(rec, j + 1u)));
}

// The crossings of the whole object-space line so + t sd with the planar
// object whose placed record is idx, appended to x; false (x untouched) for
// a non-convex prism, whose crossings are walked instead (tb_prism_profile_pair).
bool tb_bvh_planar_xings(uint idx, tb_line l, inout tb_xl x)
{
    tb_gpu_placed s = TB_BVH_PLACED[idx + 1u];
    uint sub = floatBitsToUint(s.r0.x), flags = floatBitsToUint(s.w0);
    bool caps = (flags & TB_GPU_PLANAR_CAPS) != 0u;
    if (sub == TB_GPU_PLANAR_PYRAMID)
        tb_xings_pyramid(l, s.r0.y, caps, x);
    else if (sub == TB_GPU_PLANAR_PRISM && (flags & TB_GPU_PLANAR_CONVEX) == 0u)
        return false;
    else if (sub == TB_GPU_PLANAR_PRISM)
        tb_xings_prism_convex(l, idx + 2u, floatBitsToUint(s.r1.y), s.r1.x, caps, x);
    else
        tb_xings_arch(l, s.r0.y, s.r0.z, sub == TB_GPU_PLANAR_ROUND_ARCH, x);
    return true;
}

// The first surface crossing with tmin <= t <= tmax of the object-space
// line so + t sd with the planar object whose placed record is idx: t and
// the face within the object. False if none.
bool tb_bvh_planar_hit(uint idx, vec3 so, vec3 sd, float tmin, float tmax, out float t, out uint face)
{
    tb_line l = tb_line_near(so, sd);
    tb_xl x;
    x.n = 0;
    if (tb_bvh_planar_xings(idx, l, x))
        return tb_xl_first(x, tmin, tmax, t, face);
    tb_gpu_placed s = TB_BVH_PLACED[idx + 1u];
    bool caps = (floatBitsToUint(s.w0) & TB_GPU_PLANAR_CAPS) != 0u;
    return tb_prism_profile_hit(l, idx + 2u, floatBitsToUint(s.r1.y), caps, tmin, tmax, t, face);
}

// The same for the torus whose placed record is idx.
bool tb_bvh_torus_hit(uint idx, vec3 so, vec3 sd, float tmin, float tmax, out float t, out uint face)
{
    tb_gpu_placed s = TB_BVH_PLACED[idx + 1u];
    tb_xl x;
    x.n = 0;
    tb_xings_torus(so, sd, s.r0.x, s.r0.y, x);
    return tb_xl_first(x, tmin, tmax, t, face);
}

// Object-space outward normal (not unit length) of face f of the planar
// object whose placed record is idx, at the object-space point p.
vec3 tb_bvh_planar_normal(uint idx, uint f, vec3 p)
{
    tb_gpu_placed s = TB_BVH_PLACED[idx + 1u];
    uint sub = floatBitsToUint(s.r0.x);
    if (sub == TB_GPU_PLANAR_PYRAMID) {
        if (f >= TB_PYRAMID_BOTTOM)
            return vec3(0.0, 0.0, f == TB_PYRAMID_BOTTOM ? -1.0 : 1.0);
        vec3 n = vec3(0.0, 0.0, -0.5 * (s.r0.y - 1.0));
        n[f >> 1] = (f & 1u) != 0u ? 1.0 : -1.0;
        return n;
    }
    if (sub == TB_GPU_PLANAR_PRISM) {
        if (f < TB_PRISM_SIDE0)
            return vec3(0.0, 0.0, f == TB_PRISM_BOTTOM ? -1.0 : 1.0);
        uint nv = floatBitsToUint(s.r1.y), k = f - TB_PRISM_SIDE0;
        vec3 n;
        float c;
        tb_prism_side(tb_prism_vertex(idx + 2u, k), tb_prism_vertex(idx + 2u, k + 1u < nv ? k + 1u : 0u), s.r1.x, n,
                      c);
        return n;
    }
    return tb_arch_normal(f, p, s.r0.y, s.r0.z, sub == TB_GPU_PLANAR_ROUND_ARCH);
}

// The tmin with which a placed object is tested: r.tmin raised by a bound on
// the float error of a crossing's t near the origin (32 u times the size of
// the object-space origin and of the float world-to-object map's terms, in
// units of |d|). A ray spawned on such a surface by the CPU's error bounds
// (tb_spawn_ray_origin: offsets for double arithmetic) would otherwise find
// that surface again at t ~ 0 in float (measured: 1 % of diffuse rays off a
// sphere); crossings this close to the origin are not resolvable in float,
// as pbrt's conservative t bounds reject them.
float tb_bvh_placed_tmin(tb_gpu_placed sp, tb_gpu_ray r, vec3 ro, vec3 so, vec3 sd)
{
    vec3 ao = abs(ro);
    float e = dot(abs(sp.r0), ao) + abs(sp.w0) + dot(abs(sp.r1), ao) + abs(sp.w1) + dot(abs(sp.r2), ao) +
              abs(sp.w2) + abs(so.x) + abs(so.y) + abs(so.z);
    float len = sqrt(dot(sd, sd));
    float eps = len > 0.0 ? 32.0 * 5.9604644775390625e-8 * e / len : 0.0;
    return r.tmin + (tb_isfinite(eps) ? eps : 0.0);
}

// Ray r in the frame of the placed object at record idx: the map applied to
// (o - c), c the object's world origin (shared/bvh.h), so nothing large
// cancels far from the world origin; tlo as tb_bvh_placed_tmin.
void tb_bvh_object_ray(uint idx, tb_gpu_ray r, out tb_gpu_placed sp, out vec3 so, out vec3 sd, out float tlo)
{
    sp = TB_BVH_PLACED[idx];
    precise vec3 ro = r.o - TB_BVH_PLACED[idx + 1u].r2;
    precise vec3 o = vec3(dot(sp.r0, ro) + sp.w0, dot(sp.r1, ro) + sp.w1, dot(sp.r2, ro) + sp.w2);
    precise vec3 d = vec3(dot(sp.r0, r.d), dot(sp.r1, r.d), dot(sp.r2, r.d));
    so = o;
    sd = d;
    tlo = tb_bvh_placed_tmin(sp, r, ro, so, sd);
}

// Appends the crossings of r's whole line with the closed polygons leaf
// whose record is idx (tb__xings_mesh): every triangle crossed (the float
// watertight test, world space), in order of (t, triangle), reduced by the
// winding number to the intervals where it is positive. A crossing's leaf
// is its triangle's index (kind bits 0), for the face and the normal.
void tb_bvh_mesh_xings(uint idx, tb_gpu_ray r)
{
    tb_gpu_placed hd = TB_BVH_PLACED[idx];
    uint first = floatBitsToUint(hd.r0.x), n = floatBitsToUint(hd.r0.y);
    tb_wray w = tb_wray_init(r.o, r.d);
    int start = tb_cs_n;
    for (uint i = 0u; i < n; ++i) {
        vec3 v0, v1, v2;
        float t;
        tb_bvh_fetch_tri(first + i, v0, v1, v2);
        if (!tb_tri_hit(w, v0, v1, v2, t))
            continue;
        precise vec3 e1 = v1 - v0;
        precise vec3 e2 = v2 - v0;
        precise vec3 nn = cross(e1, e2);
        bool enter = dot(nn, r.d) < 0.0;
        tb_csg_push(t, first + i, (t < r.tmin ? 2u : 0u) | (enter ? 1u : 0u));
    }
    for (int i = start + 1; i < tb_cs_n; ++i) { // insertion sort by (t, triangle)
        float t = tb_cs_t[i];
        uint l = tb_cs_leaf[i], fd = tb_cs_fd[i];
        int j = i;
        while (j > start && (tb_cs_t[j - 1] > t || (tb_cs_t[j - 1] == t && tb_cs_leaf[j - 1] > l))) {
            tb_cs_t[j] = tb_cs_t[j - 1];
            tb_cs_leaf[j] = tb_cs_leaf[j - 1];
            tb_cs_fd[j] = tb_cs_fd[j - 1];
            --j;
        }
        tb_cs_t[j] = t;
        tb_cs_leaf[j] = l;
        tb_cs_fd[j] = fd;
    }
    int wnd = 0, nout = start;
    for (int i = start; i < tb_cs_n; ++i) {
        int next = wnd + ((tb_cs_fd[i] & 1u) != 0u ? 1 : -1);
        if ((wnd <= 0 && next > 0) || (wnd > 0 && next <= 0)) {
            tb_cs_t[nout] = tb_cs_t[i];
            tb_cs_leaf[nout] = tb_cs_leaf[i];
            tb_cs_fd[nout++] = (tb_cs_fd[i] & ~1u) | (next > 0 ? 1u : 0u);
        }
        wnd = next;
    }
    if (wnd > 0 && (nout - start) % 2 == 1) { // a lost crossing: close the interval, as C
        tb_cs_t[nout] = tb_cs_t[nout - 1];
        tb_cs_leaf[nout] = tb_cs_leaf[nout - 1];
        tb_cs_fd[nout] = tb_cs_fd[nout - 1] & ~1u;
        ++nout;
    }
    tb_cs_n = nout;
}

// Appends the crossings of r's whole line with CSG leaf `ref` (a placed
// object's reference) to the CSG pool (lib/csg.glsl).
void tb_bvh_leaf_xings(uint ref, tb_gpu_ray r)
{
    uint idx = ref & TB_GPU_REF_INDEX, kind = ref & TB_GPU_REF_KIND;
    if (kind == TB_GPU_REF_MESH) {
        tb_bvh_mesh_xings(idx, r);
        return;
    }
    tb_gpu_placed sp;
    vec3 so, sd;
    float tlo;
    tb_bvh_object_ray(idx, r, sp, so, sd, tlo);
    tb_xl x;
    x.n = 0;
    if (kind == TB_GPU_REF_CUBE) {
        tb_xings_cube(so, sd, x);
    } else if (kind == TB_GPU_REF_SPHERE) {
        tb_xings_sphere(so, sd, 1.0, x);
    } else if (kind == TB_GPU_REF_REVOLVED) {
        tb_xings_revolved(so, sd, tb_bvh_revolved(idx), x);
    } else if (kind == TB_GPU_REF_TORUS) {
        vec3 rr = TB_BVH_PLACED[idx + 1u].r0;
        tb_xings_torus(so, sd, rr.x, rr.y, x);
    } else {
        tb_line l = tb_line_near(so, sd);
        if (!tb_bvh_planar_xings(idx, l, x)) { // a non-convex prism: every interval in turn
            tb_gpu_placed s = TB_BVH_PLACED[idx + 1u];
            uint nv = floatBitsToUint(s.r1.y);
            tb_end za, zb;
            if (!tb_prism_slab(l, za, zb))
                return;
            if (l.d.x == 0.0 && l.d.y == 0.0) {
                if (tb_profile_inside(l, idx + 2u, nv))
                    tb_xl_interval(x, l, za, zb, true, true);
            } else {
                float sp0 = -tb_inf();
                uint ep0 = 0xffffffffu;
                for (uint i = 0u; i < nv && tb_prism_profile_pair(l, idx + 2u, nv, true, za, zb, sp0, ep0, x); i += 2u)
                    tb_csg_push_xl(x, ref, tlo);
                return;
            }
        }
    }
    tb_csg_push_xl(x, ref, tlo);
}

// The first crossing with r.tmin <= t <= tmax of r with the CSG tree whose
// header is placed record idx: t, the face ID (the leaf's face base plus the
// face within the leaf) and the leaf's reference (for tb_bvh_normal).
bool tb_bvh_csg_hit(uint idx, tb_gpu_ray r, float tmax, out float t, out uint face, out uint leaf)
{
    t = 0.0;
    face = 0u;
    leaf = 0u;
    uint nops = floatBitsToUint(TB_BVH_PLACED[idx].r0.x);
    vec3 ao = abs(r.o), ad = abs(r.d);
    float scale = max(max(ao.x, ao.y), ao.z) / max(max(ad.x, ad.y), ad.z);
    tb_cs_n = 0;
    tb_nls = 0;
    for (uint i = 0u; i < nops; ++i) {
        uint w = tb_bvh_placed_word(idx + 1u + (i >> 4), i & 15u);
        if ((w & TB_GPU_REF_KIND) != 0u) {
            tb_csg_open_list();
            tb_bvh_leaf_xings(w, r);
        } else {
            tb_csg_merge(w >> 8, int(w & 0xffu), scale);
        }
    }
    for (int i = 0; i < tb_cs_n; ++i)
        if ((tb_cs_fd[i] & 2u) == 0u && tb_cs_t[i] >= r.tmin && tb_cs_t[i] <= tmax) {
            t = tb_cs_t[i];
            leaf = tb_cs_leaf[i];
            face = (leaf & TB_GPU_REF_KIND) == 0u ? tb_bvh_fetch_tri_keys(leaf).y // a polygons leaf's triangle
                                                  : TB_BVH_PLACED[leaf & TB_GPU_REF_INDEX].face + (tb_cs_fd[i] >> 2);
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

// The rays the CPU path accepts (tb_ray_is_valid): finite origin, direction
// and tmin, a non-zero direction, tmin <= tmax. Others miss everything.
bool tb_bvh_ray_valid(tb_gpu_ray r)
{
    return tb_isfinite(r.o.x) && tb_isfinite(r.o.y) && tb_isfinite(r.o.z) && tb_isfinite(r.d.x) &&
           tb_isfinite(r.d.y) && tb_isfinite(r.d.z) && tb_isfinite(r.tmin) &&
           !(r.d.x == 0.0 && r.d.y == 0.0 && r.d.z == 0.0) && r.tmin <= r.tmax;
}

// The loops of tb_bvh_traverse share these bodies as macros (GLSL
// has no generics, and a function taking the best-hit state inout would copy
// it at every candidate in the hot loop).
//
// Takes candidate (T, object O, face F, reference RF) of leaf entry `ref` if
// it beats the best hit so far (tb_better); an any-hit query stops at it.
#define TB_BVH_TAKE(T, O, F, RF)                                                                                      \
    if (tb_better(T, O, F, RF, have, bt, bo, bf, br)) {                                                               \
        have = true;                                                                                                  \
        bt = T;                                                                                                       \
        bo = O;                                                                                                       \
        bf = F;                                                                                                       \
        br = RF;                                                                                                      \
        bref = ref;                                                                                                   \
    }                                                                                                                 \
    if (any_hit) {                                                                                                    \
        stop = true;                                                                                                  \
        break;                                                                                                        \
    }

// Pops stacked children until one's box is within [lo_t, hi_t] (its node
// becomes the current one); done when the stack runs out.
#define TB_BVH_POP()                                                                                                  \
    bool found = false;                                                                                               \
    while (sp > 0 && !found) {                                                                                        \
        vec3 plo, phi;                                                                                                \
        uint slot = stack[--sp];                                                                                      \
        tb_bvh_fetch_node(slot, plo, phi, cur_off, cur_count);                                                        \
        cur_count &= 0xffffu;                                                                                         \
        found = tb_aabb_slab(plo, phi, r.o, r.d, inv, lo_t, hi_t, t0, t1);                                            \
    }                                                                                                                 \
    done = !found;

// The leaf's run of placed objects of kind KIND from entry k on (each leaf
// lists them by kind, shared/bvh.h): the ray in the object's
// frame (so, sd), its lower bound tlo, then HIT, which sets t and the face
// offset cf (left 0 by kinds of one face).
#define TB_BVH_PLACED_RUN(KIND, HIT)                                                                                  \
    for (; k < end; ++k) {                                                                                            \
        uint ref = tb_bvh_fetch_ref(k);                                                                               \
        uint idx = ref & TB_GPU_REF_INDEX;                                                                            \
        if ((ref & TB_GPU_REF_KIND) != KIND)                                                                          \
            break;                                                                                                    \
        tb_gpu_placed sp;                                                                                             \
        vec3 so, sd;                                                                                                  \
        float t, tlo;                                                                                                 \
        tb_bvh_object_ray(idx, r, sp, so, sd, tlo);                                                                   \
        uint cf = 0u;                                                                                                 \
        vec3 nobj;                                                                                                    \
        if (!(HIT))                                                                                                   \
            continue;                                                                                                 \
        uint face = sp.face + cf;                                                                                     \
        TB_BVH_TAKE(t, sp.object, face, sp.ref)                                                                       \
    }

// The traversal: with any_hit false the closest hit by the tie rule, with
// any_hit true the first hit found (any t in [tmin, tmax]). nnodes is the
// node count (0 for a scene with nothing on the GPU). False on a miss.
bool tb_bvh_traverse(tb_gpu_ray r, uint nnodes, bool any_hit, out tb_bvh_hit h)
{
    bool have = false;
    float bt = r.tmax;
    uint bo = TB_GPU_NO_HIT, bf = 0u, br = 0u, bref = 0u;
    if ((TB_BVH_HAS_TRIANGLES || TB_BVH_HAS_SPHERES || TB_BVH_HAS_CUBES || TB_BVH_HAS_QUADRICS ||
         TB_BVH_HAS_PLANAR || TB_BVH_HAS_TORI || TB_BVH_HAS_CSG) &&
        nnodes > 0u &&
        tb_bvh_ray_valid(r)) {
        vec3 inv = tb_ray_inv_dir(r.d);
        tb_wray w = tb_wray_init(r.o, r.d);
        float lo_t = r.tmin - abs(r.tmin) * TB_T_TOL;
        // Aila and Laine's while-while traversal: a SIMD group (8 lanes on
        // lavapipe, which executes both sides of every branch under a mask)
        // first walks inner nodes until each lane stands at a leaf or is
        // done, then tests the leaves' primitives together, so the costly
        // primitive code runs with most lanes active. Each inner step tests
        // both children's boxes (one 64-byte fetch); the nearer hit child (by
        // the split axis and the ray's sign, as on the CPU) is taken and the
        // other pushed. A popped child is tested again against the best t so
        // far. The lane's child is (cur_off, cur_count): cur_count 0 an
        // inner node. Leaves list their references by kind (triangles,
        // cubes, spheres, planar, revolved objects, tori), so each kind's code runs in its
        // own loop.
        uint stack[TB_BVH_STACK];
        int sp = 0;
        bool done = false, stop = false;
        uint cur_off = 0u, cur_count = 0u;
        // Leaves' placed objects are not tested inside the walk's loop but
        // deferred (their leaf's entry range, up to TB_BVH_DEFER leaves):
        // the walk stops when the list is full or it ends, the deferred
        // objects are tested, and the walk resumes from its stack. lavapipe (Mesa
        // 22) runs every branch under a mask, with no jump over a branch no
        // lane takes, and every loop body at least once: the placed kinds'
        // code (CSG sweeps, tori, prisms) inside the walk's loop cost its
        // full length at every leaf visit, even where no lane held such an
        // object (docs/gpu.md, "Speed"). Deferred, it runs once per round.
        uint dq_k[TB_BVH_DEFER], dq_end[TB_BVH_DEFER];
        int nd = 0;
        for (;;) {
            for (;;) {
                // Inner nodes until a leaf (or the end).
                while (!done && cur_count == 0u) {
                    vec3 lo0, hi0, lo1, hi1;
                    uint off0, cnt0, off1, cnt1;
                    tb_bvh_fetch_node(2u * cur_off, lo0, hi0, off0, cnt0);
                    tb_bvh_fetch_node(2u * cur_off + 1u, lo1, hi1, off1, cnt1);
                    float hi_t = bt + abs(bt) * TB_T_TOL;
                    float t0, t1;
                    bool h0 = tb_aabb_slab(lo0, hi0, r.o, r.d, inv, lo_t, hi_t, t0, t1);
                    bool h1 = tb_aabb_slab(lo1, hi1, r.o, r.d, inv, lo_t, hi_t, t0, t1);
                    bool swap = r.d[cnt0 >> 16] < 0.0; // the second child first
                    bool hn = swap ? h1 : h0, hf = swap ? h0 : h1;
                    if (hn || hf) {
                        if (hn && hf && sp < TB_BVH_STACK)
                            stack[sp++] = 2u * cur_off + (swap ? 0u : 1u);
                        bool take1 = hn ? swap : !swap;
                        cur_off = take1 ? off1 : off0;
                        cur_count = (take1 ? cnt1 : cnt0) & 0xffffu;
                    } else {
                        // Pop children until one is still within reach.
                        TB_BVH_POP()
                    }
                }
                if (done)
                    break;
                // The leaf: triangles now, placed objects deferred.
                uint k = cur_off, end = cur_off + cur_count;
                if (TB_BVH_HAS_TRIANGLES) {
                    for (; k < end; ++k) {
                        uint ref = tb_bvh_fetch_ref(k);
                        if ((ref & TB_GPU_REF_KIND) != 0u)
                            break;
                        vec3 v0, v1, v2;
                        float t;
                        tb_bvh_fetch_tri(ref, v0, v1, v2);
                        if (!tb_tri_hit(w, v0, v1, v2, t) || t < r.tmin || t > r.tmax)
                            continue;
                        uvec3 keys = tb_bvh_fetch_tri_keys(ref);
                        TB_BVH_TAKE(t, keys.x, keys.y, keys.z)
                    }
                }
                if (stop)
                    break;
                if (TB_BVH_HAS_PLACED_KINDS && k < end) {
                    dq_k[nd] = k;
                    dq_end[nd] = end;
                    ++nd;
                }
                // Leaf done: back to the stack.
                cur_count = 0u;
                float hi_t = bt + abs(bt) * TB_T_TOL;
                float t0, t1;
                TB_BVH_POP()
                if (done || nd == TB_BVH_DEFER)
                    break;
            }
            // The deferred leaves' placed objects.
            for (int q = 0; TB_BVH_HAS_PLACED_KINDS && q < nd && !stop; ++q) {
                uint k = dq_k[q], end = dq_end[q];
                // CSG trees (listed after the triangles): the leaf's reference
                // stands for the tree in bref, so tb_bvh_normal finds the leaf.
                if (TB_BVH_HAS_CSG) {
                    for (; k < end; ++k) {
                        uint cref = tb_bvh_fetch_ref(k);
                        if ((cref & TB_GPU_REF_KIND) != TB_GPU_REF_CSG)
                            break;
                        uint cidx = cref & TB_GPU_REF_INDEX, face, ref;
                        float t;
                        if (!tb_bvh_csg_hit(cidx, r, r.tmax, t, face, ref))
                            continue;
                        tb_gpu_placed hd = TB_BVH_PLACED[cidx];
                        TB_BVH_TAKE(t, hd.object, face, hd.ref)
                    }
                }
                // One loop per kind (each leaf lists cubes, spheres, planar
                // objects, revolved objects, tori in that order): a kind's
                // code runs only while some lane has that kind left.
                if (TB_BVH_HAS_CUBES && !stop)
                    TB_BVH_PLACED_RUN(TB_GPU_REF_CUBE, tb_cube_hit(so, sd, tlo, r.tmax, t, cf))
                if (TB_BVH_HAS_SPHERES && !stop)
                    TB_BVH_PLACED_RUN(TB_GPU_REF_SPHERE, tb_sphere_intersect(so, sd, 1.0, tlo, r.tmax, t))
                if (TB_BVH_HAS_PLANAR && !stop)
                    TB_BVH_PLACED_RUN(TB_GPU_REF_PLANAR, tb_bvh_planar_hit(idx, so, sd, tlo, r.tmax, t, cf))
                if (TB_BVH_HAS_QUADRICS && !stop)
                    TB_BVH_PLACED_RUN(TB_GPU_REF_REVOLVED,
                                      tb_revolved_hit(so, sd, tb_bvh_revolved(idx), tlo, r.tmax, t, cf, nobj))
                if (TB_BVH_HAS_TORI && !stop)
                    TB_BVH_PLACED_RUN(TB_GPU_REF_TORUS, tb_bvh_torus_hit(idx, so, sd, tlo, r.tmax, t, cf))
            }
            nd = 0;
            if (done || stop)
                break;
        }
    }
    h.t = bt;
    h.object = bo;
    h.face = bf;
    h.sref = br;
    h.leaf = bref;
    return have;
}

// Closest hit of r (by the tie rule); false on a miss.
bool tb_bvh_closest(tb_gpu_ray r, uint nnodes, out tb_bvh_hit h) { return tb_bvh_traverse(r, nnodes, false, h); }

// True if anything on the GPU is hit with r.tmin <= t <= r.tmax (a shadow ray
// or a segment between two points: set tmax just short of the far end).
bool tb_bvh_occluded(tb_gpu_ray r, uint nnodes)
{
    tb_bvh_hit h;
    return tb_bvh_traverse(r, nnodes, true, h);
}

// The unit geometric normal (world space, out of the solid, flipped for
// objects with flipped normals) of a hit h of ray r found by tb_bvh_traverse.
vec3 tb_bvh_normal(tb_gpu_ray r, tb_bvh_hit h)
{
    uint kind = h.leaf & TB_GPU_REF_KIND, idx = h.leaf & TB_GPU_REF_INDEX;
    // CSG leaves are placed objects of these kinds without their TB_BVH_HAS_*.
    if ((TB_BVH_HAS_CUBES || TB_BVH_HAS_CSG) && kind == TB_GPU_REF_CUBE) {
        // The face's object-space normal -> world by the inverse transpose.
        tb_gpu_placed sp = TB_BVH_PLACED[idx];
        uint f = h.face - sp.face;
        float sg = (f & 1u) != 0u ? 1.0 : -1.0;
        vec3 n = (f >> 1) == 0u ? sp.r0 : ((f >> 1) == 1u ? sp.r1 : sp.r2);
        return sp.sign * normalize(sg * n);
    }
    if (((TB_BVH_HAS_SPHERES || TB_BVH_HAS_CSG) && kind == TB_GPU_REF_SPHERE) ||
        ((TB_BVH_HAS_QUADRICS || TB_BVH_HAS_CSG) && kind == TB_GPU_REF_REVOLVED) ||
        ((TB_BVH_HAS_PLANAR || TB_BVH_HAS_CSG) && kind == TB_GPU_REF_PLANAR) ||
        ((TB_BVH_HAS_TORI || TB_BVH_HAS_CSG) && kind == TB_GPU_REF_TORUS)) {
        // Object-space normal at the point -> world by the inverse transpose.
        tb_gpu_placed sp = TB_BVH_PLACED[idx];
        precise vec3 ro = r.o - TB_BVH_PLACED[idx + 1u].r2;
        precise vec3 so = vec3(dot(sp.r0, ro) + sp.w0, dot(sp.r1, ro) + sp.w1, dot(sp.r2, ro) + sp.w2);
        vec3 sd = vec3(dot(sp.r0, r.d), dot(sp.r1, r.d), dot(sp.r2, r.d));
        vec3 p = so + h.t * sd, n = p;
        if (kind == TB_GPU_REF_REVOLVED) {
            tb_revolved q = tb_bvh_revolved(idx);
            uint f = h.face - sp.face;
            n = f == TB_REVOLVED_SIDE ? tb_revolved_side_normal(q.c, p, 0.5 * (q.z0 + q.z1))
                                      : vec3(0.0, 0.0, f == TB_REVOLVED_TOP ? 1.0 : -1.0);
        } else if (kind == TB_GPU_REF_PLANAR) {
            n = tb_bvh_planar_normal(idx, h.face - sp.face, p);
        } else if (kind == TB_GPU_REF_TORUS) {
            n = tb_torus_normal(p, TB_BVH_PLACED[idx + 1u].r0.x);
        }
        return sp.sign * normalize(sp.r0 * n.x + sp.r1 * n.y + sp.r2 * n.z);
    }
    return tb_bvh_fetch_tri_normal(h.leaf);
}

#endif
