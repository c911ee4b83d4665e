// The Vulkan path tracer's wavefront stages (host/gpu/pathtrace.c; docs/gpu.md,
// "Path tracer"), one pipeline per stage (specialization constant 1), the
// path state in device buffers (shared/pathtrace.h). Two modules include it:
// shaders/pathtrace.comp (init, shade, accumulate) and, with TB_PT_TRACE,
// shaders/pathtrace_trace.comp (extend, shadow: the ray traversal), so that
// no pipeline compiles the code of another. The host records init, then per
// bounce extend -> shade -> shadow, many bounces to one command buffer, and
// accumulate after them; nothing returns to the host between bounces. A
// light sample's contribution is not stored per channel: the shadow stage
// marks it clear, and the next shade (or accumulate) adds throughput x the
// emitter's radiance x its scale, so the shadow stage touches no channel
// values.
//
// The estimator is the CPU path tracer's (host/render/pathtrace.c) for the
// materials and lights this kernel takes: the composite BSDF of
// host/render/surface.c with Lambert, normalised Phong, exactly normalised
// Blinn, GGX (Schlick) and smooth dielectric lobes (the same lobe choice, sampling and
// densities), and area lights (triangle, parallelogram, disc and one-sided
// sphere emitters, chosen by the area light's power CDF). Per vertex: the
// emission of a front face, weighted by the power heuristic against the
// previous vertex's light sample unless the ray left the camera or a delta
// lobe; at vertices with a non-delta lobe one light sample with a shadow
// ray, weighted against the BSDF's density of its direction (MIS, the
// densities summed over the emitters of the object the line crosses, as
// tb_light_set's); a BSDF sample; Russian roulette from rr_depth on
// (continue with q = min(1, max throughput), divide by q). Only the random
// stream differs, so the images agree statistically
// (tests/gpu/pt_equivalence.c), not sample by sample.
//
// Random numbers: a counter-based stream per path, draw k = the pcg4d hash
// (Jarzynski and Olano 2020) of (seed0, seed1, k, salt), seeds drawn on the
// host from the camera sample's own CPU stream: deterministic for a seed.
#ifndef TB_LIB_PATHTRACE_GLSL
#define TB_LIB_PATHTRACE_GLSL

#include "shared/bvh.h"
#include "shared/hit.h"
#include "shared/pathtrace.h"
#include "shared/ray.h"
#include "shared/shade.h"

layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint STAGE = 0u;     // TB_GPU_PT_STAGE_*
layout(constant_id = 2) const int NCH = 3;         // channels (RGB or the render bands)
layout(constant_id = 3) const int NMAT = 1;        // materials
layout(constant_id = 4) const int NEMIT = 0;       // emitters of the area light (0: none)
layout(constant_id = 5) const uint EMITTER_KINDS = 0u; // bit k: an emitter of kind k (TB_GPU_EMITTER_*) exists
layout(constant_id = 6) const int TB_STACK = 128;  // traversal stack entries (tb_gpu_scene_bindings.stack)
layout(constant_id = 7) const bool TB_HAS_TRIANGLES = true;
layout(constant_id = 8) const bool TB_HAS_SPHERES = false;
layout(constant_id = 9) const bool TB_HAS_CUBES = false;
layout(constant_id = 10) const bool TB_HAS_QUADRICS = false;
layout(constant_id = 11) const bool TB_HAS_PLANAR = false;
layout(constant_id = 12) const bool TB_HAS_TORI = false;
layout(constant_id = 13) const int NLIGHTS = 0;    // point, spot and directional lights (shadow slots 1..)
layout(constant_id = 14) const bool HAS_CSG = false;
layout(constant_id = 15) const bool HAS_PATTERNS = false; // a material with a colour pattern or a noise bump
layout(constant_id = 16) const uint PATTERN_KINDS = 0u;   // bit k: patterns of kind k (TB_GPU_PATTERN_*)

layout(std430, binding = 0) buffer Rays { tb_gpu_ray rays[]; };
layout(binding = 1) uniform usamplerBuffer node_texels;
layout(binding = 2) uniform usamplerBuffer tri_texels;
layout(std430, binding = 3) readonly buffer Placed { tb_gpu_placed placed[]; };
layout(binding = 4) uniform usamplerBuffer ref_texels;
// The header's word 0 counts live paths (TB_GPU_PT_STATE_HEADER bytes).
layout(std430, binding = 5) buffer States {
    uint alive_count;
    uint header_pad[7];
    tb_gpu_pt_state states[];
};
layout(std430, binding = 6) buffer Hits { tb_gpu_hit hits[]; };
// Channel values, written here and read through value_texels (the same
// buffer as R32UI texels: gathers on CPU drivers, docs/gpu.md).
layout(std430, binding = 7) writeonly buffer Values { float values[]; };
layout(std430, binding = 8) buffer Shadows { tb_gpu_ray shadows[]; };
layout(std430, binding = 9) readonly buffer Emitters { tb_gpu_emitter emitters[]; };
// The scene's table (shared/pathtrace.h) as R32UI texels.
layout(binding = 10) uniform usamplerBuffer table_texels;
layout(binding = 11) uniform usamplerBuffer value_texels;

layout(push_constant) uniform Push {
    uint n;
    uint nnodes;
    uint max_depth;
    uint rr_depth;
    uint max_bounces;
    uint count;
    uint light_base;
    uint perm;
    uint diffs;
    float diff_scale;
    uint probe;
    uint pad1;
} pc;

#ifdef TB_PT_TRACE
#define TB_BVH_NODE_TEXELS node_texels
#define TB_BVH_TRI_TEXELS tri_texels
#define TB_BVH_PLACED placed
#define TB_BVH_REF_TEXELS ref_texels
#define TB_BVH_HAS_TRIANGLES TB_HAS_TRIANGLES
#define TB_BVH_HAS_SPHERES TB_HAS_SPHERES
#define TB_BVH_HAS_CUBES TB_HAS_CUBES
#define TB_BVH_HAS_QUADRICS TB_HAS_QUADRICS
#define TB_BVH_HAS_PLANAR TB_HAS_PLANAR
#define TB_BVH_HAS_TORI TB_HAS_TORI
#define TB_BVH_HAS_CSG HAS_CSG
#define TB_BVH_STACK TB_STACK
#include "lib/bvh_traverse.glsl"
#endif

const float INV_PI = 0.318309886183790671537767526745028724;
const float SHADOW_EPSILON = 1e-4; // TB_SHADOW_EPSILON
#include "emitter.glsl"
#include "ggx.glsl"

const int MSTRIDE = 4 * NCH + int(TB_GPU_PT_M_SCALARS); // table words per material
const int EMIT_BASE = NMAT * MSTRIDE;  // first emitter radiance in the table
const int CDF_BASE = EMIT_BASE + NEMIT * NCH;
const int PMF_BASE = CDF_BASE + NEMIT + 1;
const int EOBJ_BASE = PMF_BASE + NEMIT; // per emitter its top-level object
const int OBJ_BASE = EOBJ_BASE + NEMIT; // per object TB_GPU_PT_O_WORDS words

uint g_i;  // this invocation's path
uint g_n;  // paths
// The hit's diffuse and specular colours: the material's, or its patterns'
// (bsdf_load, then surface_patterns).
float g_kd[NCH];
float g_ks[NCH];

float tab(int i) { return uintBitsToFloat(texelFetch(table_texels, i).x); }
uint utab(int i) { return texelFetch(table_texels, i).x; }
float val(uint v, int c) { return uintBitsToFloat(texelFetch(value_texels, int((v * uint(NCH) + uint(c)) * g_n + g_i)).x); }
void set_val(uint v, int c, float x) { values[(v * uint(NCH) + uint(c)) * g_n + g_i] = x; }

// pcg4d (Jarzynski and Olano, "Hash Functions for GPU Rendering", JCGT 2020).
uvec4 pcg4d(uvec4 v)
{
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.w;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v.w += v.y * v.z;
    v ^= v >> 16u;
    v.x += v.y * v.w;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v.w += v.y * v.z;
    return v;
}

// The path's next number in [0, 1) (24 bits, as tb_rng_float).
float rnd(inout tb_gpu_pt_state st)
{
    uvec4 h = pcg4d(uvec4(st.seed0, st.seed1, st.counter, 0x5bd1e995u));
    st.counter++;
    return float(h.x >> 8u) * (1.0 / 16777216.0);
}

// The emitter whose CDF slice holds u (binary search, as
// tb_distrib1d_sample_discrete), its probability and u rescaled to [0, 1).
int pick_emitter(float u, out float pmf, out float ur)
{
    int lo = 0, hi = NEMIT - 1;
    while (lo < hi) {
        int mid = (lo + hi + 1) / 2;
        if (tab(CDF_BASE + mid) <= u)
            lo = mid;
        else
            hi = mid - 1;
    }
    while (lo > 0 && tab(PMF_BASE + lo) <= 0.0)
        lo--; // u at the top end by rounding: the last emitter with power
    pmf = tab(PMF_BASE + lo);
    ur = pmf > 0.0 ? min((u - tab(CDF_BASE + lo)) / pmf, uintBitsToFloat(0x3f7fffffu)) : 0.0;
    ur = max(ur, 0.0);
    return lo;
}

// The material of the hit: the object's, or for a CSG tree that of the leaf
// whose face range holds the hit's face (tb_scene_hit_material).
uint hit_material(uint obj, uint face)
{
    int ob = OBJ_BASE + int(TB_GPU_PT_O_WORDS) * int(obj);
    uint nr = HAS_CSG ? utab(ob + 4) : 0u;
    if (nr == 0u)
        return utab(ob);
    int lb = int(utab(ob + 3));
    for (int r = 0; r < int(nr); r++)
        if (face >= utab(lb + 3 * r) && face - utab(lb + 3 * r) < utab(lb + 3 * r + 1))
            return utab(lb + 3 * r + 2);
    return 0xffffffffu;
}

// ------------------------------------------------------ surface parameters
// (u, v), tangents and the object-space point of a hit, as host/object/param.c
// gives them (tb_param_from_point, tb_param_eval_world) for the kinds whose
// parameterisation is ported (spheres, cubes, polygons: the record of
// shared/pathtrace.h, TB_GPU_PT_Q_*); the host refuses a patterned material
// on any other kind. In float; the CPU works in double.

const float PT_PI = 3.14159265358979323846;

// The object's parameterisation record, or -1.
int param_record(uint obj)
{
    return HAS_PATTERNS ? int(utab(OBJ_BASE + int(TB_GPU_PT_O_WORDS) * int(obj) + int(TB_GPU_PT_O_PARAM))) : -1;
}

// Row k of the 3 x 4 (affine) or 3 x 3 (linear) map at table word b.
vec3 q_vec(int b) { return vec3(tab(b), tab(b + 1), tab(b + 2)); }

vec3 q_to_object(int q, vec3 p)
{
    int b = q + int(TB_GPU_PT_Q_TO_OBJECT);
    return vec3(dot(q_vec(b), p) + tab(b + 3), dot(q_vec(b + 4), p) + tab(b + 7), dot(q_vec(b + 8), p) + tab(b + 11));
}

vec3 q_to_object_vector(int q, vec3 v)
{
    int b = q + int(TB_GPU_PT_Q_TO_OBJECT);
    return vec3(dot(q_vec(b), v), dot(q_vec(b + 4), v), dot(q_vec(b + 8), v));
}

vec3 q_to_world_vector(int q, vec3 v)
{
    int b = q + int(TB_GPU_PT_Q_TO_WORLD);
    return vec3(dot(q_vec(b), v), dot(q_vec(b + 3), v), dot(q_vec(b + 6), v));
}

// u = phi / 2 pi in [0, 1) of the direction (x, y); 0 on the axis (tb__angle_u).
float angle_u(float x, float y)
{
    if (x == 0.0 && y == 0.0)
        return 0.0;
    float phi = atan(y, x);
    if (phi < 0.0)
        phi += 2.0 * PT_PI;
    float u = phi * (0.5 / PT_PI);
    return u < 1.0 ? u : 0.0;
}

// The outward axis a and lateral axis b of cube side `face` (0..3: -x, +x,
// -y, +y; tb__side_axes).
void side_axes(int face, out vec3 a, out vec3 b)
{
    if (face == 0) {
        a = vec3(-1.0, 0.0, 0.0);
        b = vec3(0.0, -1.0, 0.0);
    } else if (face == 1) {
        a = vec3(1.0, 0.0, 0.0);
        b = vec3(0.0, 1.0, 0.0);
    } else if (face == 2) {
        a = vec3(0.0, -1.0, 0.0);
        b = vec3(1.0, 0.0, 0.0);
    } else {
        a = vec3(0.0, 1.0, 0.0);
        b = vec3(-1.0, 0.0, 0.0);
    }
}

// (u, v) in [0, 1]^2 of world point p on face `face` (the hit's face ID) of
// record q (tb_param_from_point on the hit's face).
vec2 param_uv(int q, uint face, vec3 p)
{
    uint kind = utab(q + int(TB_GPU_PT_Q_KIND));
    int f = int(face - utab(q + int(TB_GPU_PT_Q_FACE_BASE)));
    vec2 uv;
    if (kind == TB_GPU_PT_PARAM_POLYGONS) {
        int fb = q + int(TB_GPU_PT_Q_FACES) + f * int(TB_GPU_PT_Q_FACE_WORDS);
        uv = vec2(dot(q_vec(fb), p) + tab(fb + 3), dot(q_vec(fb + 4), p) + tab(fb + 7));
    } else {
        vec3 o = q_to_object(q, p);
        if (kind == TB_GPU_PT_PARAM_SPHERE) {
            uv = vec2(angle_u(o.x, o.y), atan(length(o.xy), -o.z) * (1.0 / PT_PI));
        } else if (f < 4) { // cube side (tb__pyr_side_project with t = 1)
            vec3 a, b;
            side_axes(f, a, b);
            uv = vec2(0.5 * (dot(o, b) + 1.0), 0.5 * (o.z + 1.0));
        } else { // cube bottom (4) or top (5) (tb__rect_z_uv over [-1, 1]^2)
            uv = vec2(0.5 * (o.x + 1.0), f == 5 ? 0.5 * (o.y + 1.0) : 0.5 * (1.0 - o.y));
        }
    }
    return clamp(uv, 0.0, 1.0);
}

// The world tangents dp/du, dp/dv at (u, v) of the hit's face (tb_param_eval_world).
void param_tangents(int q, uint face, float u, float v, out vec3 dpdu, out vec3 dpdv)
{
    uint kind = utab(q + int(TB_GPU_PT_Q_KIND));
    int f = int(face - utab(q + int(TB_GPU_PT_Q_FACE_BASE)));
    if (kind == TB_GPU_PT_PARAM_POLYGONS) {
        int fb = q + int(TB_GPU_PT_Q_FACES) + f * int(TB_GPU_PT_Q_FACE_WORDS);
        dpdu = q_vec(fb + 8);
        dpdv = q_vec(fb + 11);
        return;
    }
    vec3 du, dv;
    if (kind == TB_GPU_PT_PARAM_SPHERE) { // tb__sphere_eval
        float phi = 2.0 * PT_PI * u, th = PT_PI * v;
        float cp = cos(phi), sp = sin(phi), ct = cos(th), st = sin(th);
        du = (v == 0.0 || v == 1.0) ? vec3(0.0) : vec3(-2.0 * PT_PI * st * sp, 2.0 * PT_PI * st * cp, 0.0);
        dv = vec3(PT_PI * ct * cp, PT_PI * ct * sp, PT_PI * st);
    } else if (f < 4) {
        vec3 a, b;
        side_axes(f, a, b);
        du = 2.0 * b;
        dv = vec3(0.0, 0.0, 2.0);
    } else {
        du = vec3(2.0, 0.0, 0.0);
        dv = vec3(0.0, f == 5 ? 2.0 : -2.0, 0.0);
    }
    dpdu = q_to_world_vector(q, du);
    dpdv = q_to_world_vector(q, dv);
}

// ------------------------------------------------------------- emitter pdf

// The point where the line p + t w (t > 0) meets emitter e, and the
// emitter's normal there (tb_emitter_intersect, host/render/lights.c).
bool emitter_hit(tb_gpu_emitter e, vec3 p, vec3 w, out vec3 q, out vec3 nq)
{
    float t;
    if (e.kind == TB_GPU_EMITTER_TRIANGLE || e.kind == TB_GPU_EMITTER_PARALLELOGRAM) {
        vec3 e1 = e.v1 - e.v0, e2 = e.v2 - e.v0;
        vec3 pv = cross(w, e2);
        float det = dot(e1, pv);
        if (det == 0.0)
            return false;
        vec3 tv = p - e.v0;
        float a = dot(tv, pv) / det;
        vec3 qv = cross(tv, e1);
        float b = dot(w, qv) / det;
        t = dot(e2, qv) / det;
        if (a < 0.0 || b < 0.0 || a > 1.0 || b > 1.0 || (e.kind == TB_GPU_EMITTER_TRIANGLE && a + b > 1.0))
            return false;
        nq = e.normal;
    } else if (e.kind == TB_GPU_EMITTER_DISC) {
        float dn = dot(w, e.v1);
        if (dn == 0.0)
            return false;
        t = dot(e.v0 - p, e.v1) / dn;
        vec3 x = p + w * t - e.v0;
        if (dot(x, x) > e.radius * e.radius)
            return false;
        nq = e.v1;
    } else if (e.kind == TB_GPU_EMITTER_SPHERE) {
        vec3 oc = p - e.v0;
        float a = dot(w, w), b = dot(oc, w);
        vec3 perp = oc - w * (b / a);
        float disc = e.radius * e.radius - dot(perp, perp);
        if (disc < 0.0)
            return false;
        float h = sqrt(a * disc);
        float q1 = -(b + (b < 0.0 ? -h : h));
        float t0 = q1 / a, t1 = q1 != 0.0 ? (dot(oc, oc) - e.radius * e.radius) / q1 : t0;
        float lo = min(t0, t1), hi = max(t0, t1);
        t = lo > 0.0 ? lo : hi;
        nq = normalize(p + w * t - e.v0);
    } else {
        return false;
    }
    if (!(t > 0.0) || isinf(t))
        return false;
    q = p + w * t;
    return true;
}

// The solid-angle density with which the area light, sampled at p, returns
// direction w through the emitters of top-level object `obj`: the sum over
// those the line crosses (tb_light_set's object pdf: selection probability
// times the cone density of a sphere, or 1 / area times d^2 / |cos|).
float object_pdf(uint obj, vec3 p, vec3 w)
{
    if (NEMIT == 0)
        return 0.0;
    int ob = OBJ_BASE + int(TB_GPU_PT_O_WORDS) * int(obj);
    int first = int(utab(ob + 1)), count = int(utab(ob + 2));
    float pdf = 0.0;
    for (int i = first; i < first + count; i++) {
        tb_gpu_emitter e = emitters[i];
        float pmf = tab(PMF_BASE + i);
        vec3 q, nq;
        if (!(pmf > 0.0) || !emitter_hit(e, p, w, q, nq))
            continue;
        if (e.kind == TB_GPU_EMITTER_SPHERE) {
            float dc = length(p - e.v0);
            if (dc > e.radius * (1.0 + 1e-6)) {
                float s2max = (e.radius / dc) * (e.radius / dc);
                float omc_max = s2max / (1.0 + sqrt(max(0.0, 1.0 - s2max)));
                pdf += pmf / (TB_EMITTER_TWO_PI * omc_max);
            }
            continue; // inside a one-sided sphere: 0 (two-sided ones are refused)
        }
        vec3 d = q - p;
        float d2 = dot(d, d);
        float cq = -dot(nq, d) / sqrt(d2);
        if (!(d2 > 0.0) || cq == 0.0 || (cq < 0.0 && e.two_sided == 0u))
            continue;
        pdf += pmf * e.inv_area * d2 / abs(cq);
    }
    return pdf;
}

// -------------------------------------------------------------------- BSDF
// The composite BSDF of host/render/surface.c (tb_surface_bsdf_*, mode
// TB_SURFACE_PHYSICAL) for the lobes the kernel takes: Lambert, normalised
// Phong, exactly normalised Blinn, GGX (lib/ggx.glsl) and the smooth dielectric; n is the normal
// facing wo (no bump maps), ng the geometric one.

struct bsdf_t {
    int mb;        // the material's first table word
    uint lobes;    // bit per TB_GPU_PT_LOBE_*
    uint glossy;   // TB_GPU_PT_GLOSSY_*
    float pick[4]; // selection probabilities per slot
    float dielectric, expo, ior, alpha;
    vec3 nv;       // the geometric normal on wo's side (n may be bumped): the same-side tests
};

bsdf_t bsdf_load(int m)
{
    bsdf_t b;
    b.mb = m * MSTRIDE;
    int sc = b.mb + 4 * NCH;
    for (int k = 0; k < 4; k++)
        b.pick[k] = tab(sc + int(TB_GPU_PT_M_PICK) + k);
    b.dielectric = tab(sc + int(TB_GPU_PT_M_DIELECTRIC));
    b.expo = tab(sc + int(TB_GPU_PT_M_EXPONENT));
    b.ior = tab(sc + int(TB_GPU_PT_M_IOR));
    b.glossy = utab(sc + int(TB_GPU_PT_M_GLOSSY));
    b.lobes = utab(sc + int(TB_GPU_PT_M_LOBES));
    b.alpha = tab(sc + int(TB_GPU_PT_M_ALPHA));
    for (int c = 0; c < NCH; c++) {
        g_kd[c] = tab(b.mb + c);
        g_ks[c] = tab(b.mb + 2 * NCH + c);
    }
    return b;
}

bool has_lobe(bsdf_t b, uint k) { return (b.lobes & (1u << k)) != 0u; }

// True if wo and wi are on different sides of the geometric surface
// (tb__same_side) or of the shading normal n (the lobes' own test).
bool sides_differ(bsdf_t b, vec3 n, vec3 wo, vec3 wi)
{
    return (dot(wo, b.nv) > 0.0) != (dot(wi, b.nv) > 0.0) || (dot(wo, n) > 0.0) != (dot(wi, n) > 0.0);
}

// The mean of the positive channels (tb__weight: a lobe's selection weight).
float lobe_weight(float k[NCH])
{
    float s = 0.0;
    for (int c = 0; c < NCH; c++)
        s += max(k[c], 0.0);
    return s / float(NCH);
}

// The lobes and their selection probabilities from the hit's colours
// g_kd, g_ks (tb_surface_bsdf_init, TB_SURFACE_PHYSICAL), for a material
// whose patterns change them from point to point; b.glossy is the model's
// lobe kind whatever the specular colour (pathtrace.c).
void bsdf_reinit(inout bsdf_t b)
{
    float w[4] = float[4](0.0, 0.0, 0.0, 0.0);
    uint lobes = 0u;
    bool kd = false, ks = false, kt = false;
    float dmax = 0.0, wt[NCH];
    for (int c = 0; c < NCH; c++) {
        kd = kd || g_kd[c] != 0.0;
        ks = ks || g_ks[c] != 0.0;
        wt[c] = tab(b.mb + 3 * NCH + c);
        kt = kt || wt[c] != 0.0;
        dmax = c == 0 ? g_kd[0] : max(dmax, g_kd[c]);
    }
    if (kd) {
        lobes |= 1u << TB_GPU_PT_LOBE_DIFFUSE;
        w[TB_GPU_PT_LOBE_DIFFUSE] = lobe_weight(g_kd);
    }
    if (!kt && ks && b.glossy != TB_GPU_PT_GLOSSY_NONE) {
        lobes |= 1u << TB_GPU_PT_LOBE_GLOSSY;
        w[TB_GPU_PT_LOBE_GLOSSY] = lobe_weight(g_ks);
    }
    if (kt) {
        b.dielectric = dmax > 0.0 ? (dmax < 1.0 ? 1.0 - dmax : 0.0) : 1.0;
        if (b.dielectric > 0.0) {
            lobes |= 1u << TB_GPU_PT_LOBE_DIELECTRIC;
            w[TB_GPU_PT_LOBE_DIELECTRIC] = b.dielectric * max(lobe_weight(wt), 0.5);
        }
    }
    float sum = w[0] + w[1] + w[2] + w[3];
    for (int k = 0; k < 4; k++)
        b.pick[k] = sum > 0.0 ? w[k] / sum : 0.0;
    b.lobes = sum > 0.0 ? lobes : 0u;
}

const uint NONDELTA = (1u << TB_GPU_PT_LOBE_DIFFUSE) | (1u << TB_GPU_PT_LOBE_GLOSSY);

// tb_bsdf_lobe_norm of the exactly normalised Blinn lobe.
float blinn_norm(float n) { return (n + 2.0) * (n + 4.0) / (8.0 * 3.14159265358979323846 * (exp2(-0.5 * n) + n)); }

// w in the shading frame of n (tb_frame_from_normal: the basis of n).
vec3 to_local(vec3 n, vec3 w)
{
    vec3 b1, b2;
    basis(n, b1, b2);
    return vec3(dot(w, b1), dot(w, b2), dot(w, n));
}

// The glossy lobe at (wo, wi), both on n's side: its scalar, Schlick's
// weight y (f = (specular colour (1 - y) + y) x scalar; y = 0 but for GGX)
// and its sampling density (tb_bsdf evaluate).
void glossy_eval(bsdf_t b, vec3 n, vec3 wo, vec3 wi, out float scalar, out float y, out float pdf)
{
    scalar = 0.0;
    y = 0.0;
    pdf = 0.0;
    float nn = b.expo;
    if (b.glossy == TB_GPU_PT_GLOSSY_GGX) {
        vec3 e = tb_ggx_eval(b.alpha, normalize(to_local(n, wo)), normalize(to_local(n, wi)));
        scalar = e.x;
        y = e.y;
        pdf = e.z;
    } else if (b.glossy == TB_GPU_PT_GLOSSY_PHONG) {
        // cos alpha = the mirror of wo about the tangent plane . wi
        float c = min(1.0, 2.0 * dot(wo, n) * dot(wi, n) - dot(wo, wi));
        if (!(c > 0.0))
            return;
        float p = pow(c, nn);
        scalar = (nn + 2.0) * (0.5 * INV_PI) * p;
        pdf = (nn + 1.0) * (0.5 * INV_PI) * p;
    } else if (b.glossy == TB_GPU_PT_GLOSSY_BLINN) {
        vec3 h = wo + wi;
        float len = length(h);
        if (!(len > 0.0))
            return;
        h /= len;
        float p = pow(min(1.0, abs(dot(h, n))), nn);
        scalar = blinn_norm(nn) * p;
        float oh = dot(wo, h);
        if (oh > 0.0)
            pdf = (nn + 1.0) * (0.5 * INV_PI) * p / (4.0 * oh);
    }
}

// The mixture's density of direction wi (tb_surface_bsdf_pdf).
float bsdf_pdf(bsdf_t b, vec3 n, vec3 wo, vec3 wi)
{
    if ((b.lobes & NONDELTA) == 0u || sides_differ(b, n, wo, wi))
        return 0.0;
    float pdf = 0.0;
    if (has_lobe(b, TB_GPU_PT_LOBE_DIFFUSE))
        pdf += b.pick[TB_GPU_PT_LOBE_DIFFUSE] * abs(dot(wi, n)) * INV_PI;
    if (has_lobe(b, TB_GPU_PT_LOBE_GLOSSY)) {
        float sc, y, gp;
        glossy_eval(b, n, wo, wi, sc, y, gp);
        pdf += b.pick[TB_GPU_PT_LOBE_GLOSSY] * gp;
    }
    return pdf;
}

// The mixture's value at (wo, wi) per channel (tb_surface_bsdf_eval); false
// if it is 0.
bool bsdf_eval(bsdf_t b, vec3 n, vec3 wo, vec3 wi, out float f[NCH])
{
    for (int c = 0; c < NCH; c++)
        f[c] = 0.0;
    if ((b.lobes & NONDELTA) == 0u || sides_differ(b, n, wo, wi) || dot(wi, n) == 0.0)
        return false;
    float kd = has_lobe(b, TB_GPU_PT_LOBE_DIFFUSE) ? INV_PI : 0.0, ks = 0.0, y = 0.0, gp;
    if (has_lobe(b, TB_GPU_PT_LOBE_GLOSSY))
        glossy_eval(b, n, wo, wi, ks, y, gp);
    bool any = false;
    for (int c = 0; c < NCH; c++) {
        f[c] = g_kd[c] * kd + (g_ks[c] * (1.0 - y) + y) * ks;
        any = any || f[c] > 0.0;
    }
    return any;
}

// A direction of the power-cosine lobe cos^n about +z (tb_sample_power_cosine):
// 1 - cos = -expm1(log(u1) / (n + 1)) keeps the digits of narrow lobes.
vec3 power_cosine(float u1, float u2, float n)
{
    float a = 1.0, c = 0.0;
    if (u1 > 0.0) {
        float lg = log(u1) / (n + 1.0);
        a = abs(lg) < 1e-3 ? -lg * (1.0 + lg * (0.5 + lg * (1.0 / 6.0))) : 1.0 - exp(lg);
        c = 1.0 - a;
    }
    float s = sqrt(max(0.0, a * (2.0 - a)));
    float phi = TB_EMITTER_TWO_PI * u2;
    return vec3(s * cos(phi), s * sin(phi), c);
}

vec3 to_world(vec3 n, vec3 l)
{
    vec3 b1, b2;
    basis(n, b1, b2);
    return b1 * l.x + b2 * l.y + n * l.z;
}

// One sample of the mixture (tb_surface_bsdf_sample): direction, weight
// f |cos| / pdf per channel (or the delta lobe's), density, delta flag.
bool bsdf_sample(bsdf_t b, vec3 n, vec3 ng, vec3 wo, float uc, float u1, float u2, out vec3 wi, out float w[NCH],
                 out float pdf, out bool delta)
{
    for (int c = 0; c < NCH; c++)
        w[c] = 0.0;
    wi = n;
    pdf = 0.0;
    delta = false;
    if (b.lobes == 0u)
        return false;
    int k = 0;
    float lo = 0.0;
    for (k = 0; k < 3; k++) {
        if (uc < lo + b.pick[k])
            break;
        lo += b.pick[k];
    }
    while (k > 0 && b.pick[k] <= 0.0)
        k--; // uc at the top end by rounding: the last lobe present
    float pk = b.pick[k];
    float ur = pk > 0.0 ? min((uc - lo) / pk, uintBitsToFloat(0x3f7fffffu)) : 0.0;
    ur = max(ur, 0.0);
    if (k == int(TB_GPU_PT_LOBE_DIELECTRIC)) {
        delta = true;
        float ci = dot(wo, ng); // the frame of the unflipped geometric normal
        float R = fresnel_dielectric(ci, b.ior);
        float eta = ci < 0.0 ? 1.0 / b.ior : b.ior;
        vec3 nn = ci < 0.0 ? -ng : ng;
        float c = abs(ci);
        float s2t = max(0.0, (1.0 - c) * (1.0 + c)) / (eta * eta);
        bool refracts = s2t < 1.0;
        if (!refracts)
            R = 1.0;
        if (ur < R || !refracts) {
            if (!(R > 0.0))
                return false;
            wi = 2.0 * ci * ng - wo;
            pdf = pk * R;
            for (int q = 0; q < NCH; q++)
                w[q] = b.dielectric / pk;
            return true;
        }
        wi = normalize(-wo / eta + (c / eta - sqrt(1.0 - s2t)) * nn);
        pdf = pk * (1.0 - R);
        for (int q = 0; q < NCH; q++)
            w[q] = tab(b.mb + 3 * NCH + q) * b.dielectric / pk;
        return true;
    }
    float side = dot(wo, n) > 0.0 ? 1.0 : -1.0;
    if (k == int(TB_GPU_PT_LOBE_DIFFUSE)) {
        vec2 dk = tb_concentric_disc(u1, u2);
        float z = sqrt(max(0.0, 1.0 - dot(dk, dk)));
        wi = to_world(n, vec3(dk, z * side));
    } else if (b.glossy == TB_GPU_PT_GLOSSY_GGX) {
        // the sampler flips wo below the surface: flip m back the same way
        vec3 lo = normalize(to_local(n, wo));
        vec3 mh = tb_ggx_sample_vndf(b.alpha, lo, u1, u2) * side;
        wi = to_world(n, 2.0 * dot(lo, mh) * mh - lo);
    } else if (b.glossy == TB_GPU_PT_GLOSSY_PHONG) {
        vec3 r = 2.0 * dot(wo, n) * n - wo;
        wi = to_world(normalize(r), power_cosine(u1, u2, b.expo));
    } else {
        vec3 h = to_world(n, power_cosine(u1, u2, b.expo) * vec3(1.0, 1.0, side));
        float oh = dot(wo, h);
        if (!(oh > 0.0))
            return false;
        wi = 2.0 * oh * h - wo;
    }
    wi = normalize(wi);
    float ci = dot(wi, n);
    if (ci == 0.0 || sides_differ(b, n, wo, wi))
        return false; // a bumped normal can send the ray into the surface: no light there
    pdf = bsdf_pdf(b, n, wo, wi);
    if (!(pdf > 0.0) || isinf(pdf))
        return false;
    float f[NCH];
    if (!bsdf_eval(b, n, wo, wi, f))
        return false;
    bool any = false;
    for (int q = 0; q < NCH; q++) {
        w[q] = f[q] * abs(ci) / pdf;
        any = any || w[q] > 0.0;
    }
    return any;
}

#ifndef TB_PT_TRACE
// ---------------------------------------------------------------- patterns
// The CPU path tracer's surface record for patterns and bump maps
// (host/render/surface.c, tb_surface_at): tangents and object-space point
// at the hit, at the camera ray's hit the footprint of its offset rays; the
// patterns' values and the bumped normal by lib/pattern_eval.glsl.

int tb_perm(int i) { return int(utab(int(pc.perm) + (i & 255))); }
#include "pattern_eval.glsl"

// Where the line o + t d (t >= 0) meets the plane dot(n, x) = dist (texture.c's tb__plane_hit).
bool plane_hit(vec3 n, float dist, vec3 o, vec3 d, out vec3 x)
{
    x = vec3(0.0);
    float den = dot(n, d);
    if (den == 0.0 || isinf(den) || isnan(den))
        return false;
    float t = (dist - dot(n, o)) / den;
    if (!(t >= 0.0) || isinf(t))
        return false;
    x = o + d * t;
    return !any(isinf(x)) && !any(isnan(x));
}

float clamp_deriv(float x) { return clamp(x, -1e8, 1e8); }

// The (u, v) footprint of the camera ray's offset rays rx, ry at p on the
// tangent plane of normal n, and the point's change per pixel dx, dy
// (tb_tex_footprint_from_rays, scaled as tb__rt_footprint); false: none.
bool footprint(vec3 p, vec3 n, vec3 du, vec3 dv, tb_gpu_ray rx, tb_gpu_ray ry, out vec4 fp, out vec3 dx,
               out vec3 dy)
{
    fp = vec4(0.0);
    dx = vec3(0.0);
    dy = vec3(0.0);
    float dist = dot(n, p);
    vec3 px, py;
    if (!plane_hit(n, dist, rx.o, rx.d, px) || !plane_hit(n, dist, ry.o, ry.d, py))
        return false;
    vec3 ex = px - p, ey = py - p;
    float uu = dot(du, du), uv = dot(du, dv), vv = dot(dv, dv);
    float det = uu * vv - uv * uv;
    if (!(det > 1e-12 * uu * vv) || isinf(det))
        return false;
    float bxu = dot(du, ex), bxv = dot(dv, ex), byu = dot(du, ey), byv = dot(dv, ey);
    float k = pc.diff_scale;
    fp = vec4(clamp_deriv((vv * bxu - uv * bxv) / det), clamp_deriv((uu * bxv - uv * bxu) / det),
              clamp_deriv((vv * byu - uv * byv) / det), clamp_deriv((uu * byv - uv * byu) / det)) * k;
    dx = ex * k;
    dy = ey * k;
    return true;
}

// Pattern record k (TB_GPU_PATTERN_DIFFUSE, _SPECULAR, _BUMP) at table word pw.
tb_gpu_pattern load_pattern(int pw, int k)
{
    int b = pw + k * int(TB_GPU_PT_P_WORDS);
    tb_gpu_pattern pt;
    pt.kind = utab(b);
    pt.su = tab(b + 1);
    pt.sv = tab(b + 2);
    pt.solid = utab(b + 3);
    pt.octaves = int(utab(b + 4));
    pt.height = tab(b + 5);
    pt.col = utab(b + 6);
    pt.pad0 = 0u;
    return pt;
}

// The surface record of hit h of ray r at p (tb__surface_fill): record q's
// (u, v) and tangents, the object-space point and its derivatives, and at
// the camera ray's hit (camera) the footprint of its offset rays.
tb_gpu_surface surface_at(int q, tb_gpu_hit h, vec3 p, vec3 ng, bool camera)
{
    tb_gpu_surface g;
    vec3 dpdu, dpdv;
    param_tangents(q, h.face, h.u, h.v, dpdu, dpdv);
    g.u = h.u;
    g.v = h.v;
    g.dpdu = dpdu;
    g.dpdv = dpdv;
    g.po = q_to_object(q, p);
    g.po_du = q_to_object_vector(q, dpdu);
    g.po_dv = q_to_object_vector(q, dpdv);
    g.po_dx = vec3(0.0);
    g.po_dy = vec3(0.0);
    g.has_fp = 0u;
    vec4 fp = vec4(0.0);
    vec3 dx, dy;
    if (camera && pc.diffs != 0u && footprint(p, ng, dpdu, dpdv, rays[g_n + g_i], rays[2u * g_n + g_i], fp, dx, dy)) {
        g.has_fp = 1u;
        g.po_dx = q_to_object_vector(q, dx);
        g.po_dy = q_to_object_vector(q, dy);
    }
    g.fp0 = fp.x;
    g.fp1 = fp.y;
    g.fp2 = fp.z;
    g.fp3 = fp.w;
    return g;
}

// The patterns of the hit's material (tb_surface_at): the bump-mapped
// shading normal into n (on its side), the diffuse and specular colours into
// g_kd, g_ks, and the lobes they give. Nothing without a record (the host
// gives one to every object with a patterned material).
void surface_patterns(inout bsdf_t b, tb_gpu_hit h, vec3 p, vec3 ng, bool camera, inout vec3 n)
{
    int pw = int(utab(b.mb + 4 * NCH + int(TB_GPU_PT_M_PATTERNS)));
    int q = param_record(h.object);
    if (pw < 0 || q < 0)
        return;
    tb_gpu_surface g = surface_at(q, h, p, ng, camera);
    tb_gpu_pattern bp = load_pattern(pw, TB_GPU_PATTERN_BUMP);
    if (bp.kind != TB_GPU_PATTERN_NONE)
        n = bump_normal(bp, g, n); // rays still leave by ng
    vec4 fp = vec4(g.fp0, g.fp1, g.fp2, g.fp3);
    bool any = false;
    for (int k = 0; k < 2; k++) {
        tb_gpu_pattern pt = load_pattern(pw, k);
        if (pt.kind == TB_GPU_PATTERN_NONE)
            continue;
        any = true;
        float f = clamp(pattern_value(pt, false, g.u, g.v, fp, g.po, g.po_dx, g.po_dy), 0.0, 1.0);
        for (int c = 0; c < NCH; c++) {
            float a = tab(int(pt.col) + c), bb = tab(int(pt.col) + NCH + c);
            if (k == 0)
                g_kd[c] = a + f * (bb - a);
            else
                g_ks[c] = a + f * (bb - a);
        }
    }
    if (any)
        bsdf_reinit(b);
}
#endif

// ------------------------------------------------------------------ stages

void stage_init()
{
    for (int c = 0; c < NCH; c++) {
        set_val(TB_GPU_PT_L, c, 0.0);
        set_val(TB_GPU_PT_BETA, c, 1.0);
    }
}

// Adds the path's clear light samples (the TB_GPU_PT_PENDING values of
// each slot marked clear).
void add_light_samples(inout tb_gpu_pt_state st)
{
    for (uint k = 0u; st.clear != 0u && k <= uint(NLIGHTS); k++) {
        if ((st.clear & (1u << k)) == 0u)
            continue;
        for (int c = 0; c < NCH; c++)
            set_val(TB_GPU_PT_L, c, val(TB_GPU_PT_L, c) + val(TB_GPU_PT_PENDING + k, c));
    }
    st.clear = 0u;
}

// Point, spot and directional lights at p (tb__next_event's loop): per light
// with light, f L |cos| into its slot's pending values and its shadow ray.
uint delta_lights(bsdf_t b, vec3 p, vec3 perr, vec3 n, vec3 ng, vec3 wo, float beta[NCH])
{
    uint mask = 0u;
    for (int l = 0; l < NLIGHTS; l++) {
        int lb = int(pc.light_base) + l * (int(TB_GPU_PT_L_SCALARS) + NCH);
        uint kind = utab(lb + int(TB_GPU_PT_L_KIND));
        vec3 axis = vec3(tab(lb + int(TB_GPU_PT_L_AXIS)), tab(lb + int(TB_GPU_PT_L_AXIS) + 1),
                         tab(lb + int(TB_GPU_PT_L_AXIS) + 2));
        vec3 wi;
        float scale;
        tb_gpu_ray sr;
        sr.tmin = 0.0;
        if (kind == TB_GPU_LIGHT_DIRECTIONAL) {
            wi = -axis;
            scale = 1.0;
            sr.o = spawn_origin(p, perr, ng, wi);
            sr.d = wi;
            sr.tmax = 1.0 / 0.0;
        } else {
            vec3 q = vec3(tab(lb + int(TB_GPU_PT_L_POSITION)), tab(lb + int(TB_GPU_PT_L_POSITION) + 1),
                          tab(lb + int(TB_GPU_PT_L_POSITION) + 2));
            vec3 dl = q - p;
            float dist = length(dl);
            if (!(dist > 0.0) || isinf(dist))
                continue;
            wi = dl / dist;
            float k = 1.0;
            if (kind == TB_GPU_LIGHT_SPOT)
                k = spot_falloff(tab(lb + int(TB_GPU_PT_L_COS_TOTAL)), tab(lb + int(TB_GPU_PT_L_COS_FALLOFF)),
                                 dot(-wi, axis));
            if (!(k > 0.0))
                continue;
            scale = k / (dist * dist);
            sr.o = spawn_origin(p, perr, ng, wi);
            sr.d = q - sr.o;
            sr.tmax = 1.0 - SHADOW_EPSILON;
        }
        float f[NCH];
        if (!bsdf_eval(b, n, wo, wi, f))
            continue;
        float s = scale * abs(dot(wi, n));
        bool any = false;
        for (int c = 0; c < NCH; c++) {
            float x = beta[c] * f[c] * tab(lb + int(TB_GPU_PT_L_SCALARS) + c) * s;
            set_val(TB_GPU_PT_PENDING + uint(1 + l), c, x);
            any = any || x > 0.0;
        }
        if (!any)
            continue;
        shadows[uint(1 + l) * g_n + g_i] = sr;
        mask |= 1u << uint(1 + l);
    }
    return mask;
}

void stage_shade()
{
    tb_gpu_pt_state st = states[g_i];
    if (st.alive == 0u)
        return;
    add_light_samples(st);
    tb_gpu_ray r = rays[g_i];
    tb_gpu_hit h = hits[g_i];
    vec3 ng = vec3(h.ng[0], h.ng[1], h.ng[2]);
    uint mi = hit_material(h.object, h.face);
    if (mi == 0xffffffffu) {
        st.alive = 0u; // no material: the CPU's tb_surface_at fails there and ends the path
        states[g_i] = st;
        return;
    }
    int m = int(mi);
    bsdf_t b = bsdf_load(m);
    vec3 d = normalize(r.d);
    bool front = dot(r.d, ng) < 0.0;
    vec3 p = r.o + h.t * r.d;
    vec3 perr = (abs(r.o) + abs(h.t * r.d)) * (1.0 / 131072.0);
    float beta[NCH];
    for (int c = 0; c < NCH; c++)
        beta[c] = val(TB_GPU_PT_BETA, c);

#ifndef TB_PT_TRACE
    if (pc.probe != 0u) { // tb_gpu_pt_surfaces: the hit's colours and shading normal; the path ends
        vec3 n = front ? ng : -ng;
        b.nv = n;
        if (HAS_PATTERNS)
            surface_patterns(b, h, p, ng, st.depth == 0u, n);
        for (int c = 0; c < NCH; c++) {
            set_val(TB_GPU_PT_PROBE_DIFFUSE, c, g_kd[c]);
            set_val(TB_GPU_PT_PROBE_SPECULAR, c, g_ks[c]);
            set_val(TB_GPU_PT_PROBE_NORMAL, c, c < 3 ? n[c] : 0.0);
        }
        st.alive = 0u;
        states[g_i] = st;
        return;
    }
#endif
    // Emission of a front face, weighted against the light sample the
    // previous vertex took of the same point unless the ray left the camera
    // or a delta lobe.
    if (front) {
        bool emits = false;
        for (int c = 0; c < NCH; c++)
            emits = emits || tab(b.mb + NCH + c) > 0.0;
        if (emits) {
            float w = 1.0;
            if (st.prev_delta == 0u) {
                vec3 pp = vec3(st.prev_px, st.prev_py, st.prev_pz);
                vec3 dw = p - pp;
                float len = length(dw);
                w = len > 0.0 ? power_heuristic(st.prev_pdf, object_pdf(h.object, pp, dw / len)) : 0.0;
            }
            for (int c = 0; c < NCH; c++)
                set_val(TB_GPU_PT_L, c, val(TB_GPU_PT_L, c) + beta[c] * tab(b.mb + NCH + c) * w);
        }
    }
    // (a patterned material's lobes are known at the point only: below)
    bool patterned = HAS_PATTERNS && utab(b.mb + 4 * NCH + int(TB_GPU_PT_M_PATTERNS)) != TB_GPU_PT_NONE;
    if ((pc.max_depth > 0u && st.depth >= pc.max_depth) || st.depth >= pc.max_bounces ||
        (b.lobes == 0u && !patterned)) {
        st.alive = 0u;
        states[g_i] = st;
        return;
    }
    vec3 n = front ? ng : -ng; // the normal facing the incoming ray
    vec3 wo = -d;
    b.nv = n;
#ifndef TB_PT_TRACE
    if (HAS_PATTERNS)
        surface_patterns(b, h, p, ng, st.depth == 0u, n);
#endif
    if (b.lobes == 0u) { // a pattern can make every colour black
        st.alive = 0u;
        states[g_i] = st;
        return;
    }

    // Next-event estimation at vertices with a non-delta lobe: every delta
    // light, then one sample of the area light, weighted against the BSDF's
    // sampling of the same direction; the shadow rays are traced by the
    // shadow stage, the contributions kept as pending per slot.
    uint pending = 0u;
    if (NLIGHTS > 0 && (b.lobes & NONDELTA) != 0u)
        pending = delta_lights(b, p, perr, n, ng, wo, beta);
    if (NEMIT > 0 && (b.lobes & NONDELTA) != 0u) {
        float u1 = rnd(st), u2 = rnd(st);
        float pmf, ur;
        int k = pick_emitter(u1, pmf, ur);
        vec3 q;
        float pdf_sa;
        if (pmf > 0.0 && sample_emitter(emitters[k], p, ur, u2, q, pdf_sa)) {
            vec3 dq = q - p;
            float dist = length(dq);
            vec3 wi = dq / dist;
            float f[NCH];
            if (dist > 0.0 && pmf * pdf_sa > 0.0 && bsdf_eval(b, n, wo, wi, f)) {
                float pl = object_pdf(utab(EOBJ_BASE + k), p, wi);
                if (pl > 0.0 && !isinf(pl)) {
                    float s = abs(dot(wi, n)) * power_heuristic(pl, bsdf_pdf(b, n, wo, wi)) / pl;
                    int eb = EMIT_BASE + k * NCH;
                    for (int c = 0; c < NCH; c++)
                        set_val(TB_GPU_PT_PENDING, c, beta[c] * f[c] * tab(eb + c) * s);
                    vec3 o = spawn_origin(p, perr, ng, wi);
                    tb_gpu_ray sr;
                    sr.o = o;
                    sr.tmin = 0.0;
                    sr.d = q - o;
                    sr.tmax = 1.0 - SHADOW_EPSILON;
                    shadows[g_i] = sr;
                    pending |= 1u;
                }
            }
        }
    }
    st.shadow = pending;

    // The BSDF sample (three numbers: the lobe, then the direction).
    float uc = rnd(st), u1 = rnd(st), u2 = rnd(st);
    vec3 wi;
    float w[NCH];
    float pdf;
    bool delta;
    bool go = bsdf_sample(b, n, ng, wo, uc, u1, u2, wi, w, pdf, delta);
    float bmax = 0.0;
    for (int c = 0; c < NCH; c++) {
        beta[c] *= w[c];
        bmax = max(bmax, beta[c]);
    }
    go = go && bmax > 0.0 && !isinf(bmax) && !isnan(bmax);
    st.depth++;
    // Russian roulette: continue with q = min(1, max throughput), divide by q.
    if (go && st.depth >= pc.rr_depth) {
        float q = min(1.0, bmax);
        if (q < 1.0) {
            if (!(rnd(st) < q))
                go = false;
            else
                for (int c = 0; c < NCH; c++)
                    beta[c] *= 1.0 / q;
        }
    }
    if (go) {
        for (int c = 0; c < NCH; c++)
            set_val(TB_GPU_PT_BETA, c, beta[c]);
        tb_gpu_ray nr;
        nr.o = spawn_origin(p, perr, ng, wi);
        nr.tmin = 0.0;
        nr.d = wi;
        nr.tmax = 1.0 / 0.0;
        rays[g_i] = nr;
        st.prev_delta = delta ? 1u : 0u;
        st.prev_pdf = pdf;
        st.prev_px = p.x;
        st.prev_py = p.y;
        st.prev_pz = p.z;
    }
    st.alive = go ? 1u : 0u;
    states[g_i] = st;
    if (go && pc.count != 0u)
        atomicAdd(alive_count, 1u);
}

void stage_accumulate()
{
    tb_gpu_pt_state st = states[g_i];
    if (st.clear == 0u)
        return;
    add_light_samples(st);
    states[g_i].clear = 0u;
}

#ifdef TB_PT_TRACE
void stage_extend()
{
    tb_gpu_pt_state st = states[g_i];
    if (st.alive == 0u)
        return;
    tb_gpu_ray r = rays[g_i];
    tb_bvh_hit b;
    tb_gpu_hit h;
    if (!tb_bvh_traverse(r, pc.nnodes, false, b)) {
        states[g_i].alive = 0u; // no environment light: a miss ends the path
        return;
    }
    h.t = b.t;
    h.object = b.object;
    h.face = b.face;
    h.u = 0.0;
    h.v = 0.0;
    int q = param_record(b.object);
    if (q >= 0) { // (u, v) only for the objects whose materials have patterns
        vec2 uv = param_uv(q, b.face, r.o + b.t * r.d);
        h.u = uv.x;
        h.v = uv.y;
    }
    vec3 ng = tb_bvh_normal(r, b);
    h.ng[0] = ng.x;
    h.ng[1] = ng.y;
    h.ng[2] = ng.z;
    hits[g_i] = h;
}

void stage_shadow()
{
    uint pending = states[g_i].shadow;
    if (pending == 0u)
        return;
    uint clear = 0u;
    for (uint k = 0u; k <= uint(NLIGHTS); k++) {
        if ((pending & (1u << k)) == 0u)
            continue;
        tb_bvh_hit b;
        if (!tb_bvh_traverse(shadows[k * g_n + g_i], pc.nnodes, true, b))
            clear |= 1u << k;
    }
    states[g_i].shadow = 0u;
    states[g_i].clear = clear;
}

#endif

void main()
{
    g_i = gl_GlobalInvocationID.x;
    g_n = pc.n;
    if (g_i >= g_n)
        return;
#ifdef TB_PT_TRACE
    if (STAGE == TB_GPU_PT_STAGE_EXTEND)
        stage_extend();
    else
        stage_shadow();
#else
    if (STAGE == TB_GPU_PT_STAGE_INIT)
        stage_init();
    else if (STAGE == TB_GPU_PT_STAGE_SHADE)
        stage_shade();
    else
        stage_accumulate();
#endif
}

#endif
