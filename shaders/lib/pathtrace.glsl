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
// materials and lights this kernel takes: Lambert surfaces (two-sided, the
// normal facing the incoming ray) and area lights (triangle, parallelogram,
// disc and one-sided sphere emitters, chosen by the area light's power CDF).
// Per vertex: the emission of a front face seen by the camera ray, one light
// sample with a shadow ray, a cosine-weighted BSDF sample and Russian roulette
// from rr_depth on (continue with q = min(1, max throughput), divide by q).
// The CPU weights its light sample against BSDF sampling (MIS); on Lambert
// surfaces without delta lights this kernel takes the light from the light
// samples alone and counts emission only at the camera ray's hit: another
// unbiased estimator of the same radiance, so the images agree statistically
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
    uint pad0;
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
#define TB_BVH_HAS_CSG false
#define TB_BVH_STACK TB_STACK
#include "lib/bvh_traverse.glsl"
#endif

const float INV_PI = 0.318309886183790671537767526745028724;
const float SHADOW_EPSILON = 1e-4; // TB_SHADOW_EPSILON
#include "emitter.glsl"

const int EMIT_BASE = 2 * NMAT * NCH; // first emitter radiance in the table
const int CDF_BASE = EMIT_BASE + NEMIT * NCH;
const int PMF_BASE = CDF_BASE + NEMIT + 1;
const int DMAX_BASE = PMF_BASE + NEMIT; // per material its largest diffuse channel
const int OBJ_BASE = DMAX_BASE + NMAT;  // per object its material

uint g_i;  // this invocation's path
uint g_n;  // paths

float tab(int i) { return uintBitsToFloat(texelFetch(table_texels, i).x); }
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

void stage_init()
{
    for (int c = 0; c < NCH; c++)
        set_val(TB_GPU_PT_L, c, 0.0);
}

// Adds the path's clear light sample: throughput x radiance x scale.
void add_light_sample(inout tb_gpu_pt_state st)
{
    if (st.shadow != TB_GPU_PT_SHADOW_CLEAR)
        return;
    int eb = EMIT_BASE + int(st.emitter) * NCH;
    for (int c = 0; c < NCH; c++)
        set_val(TB_GPU_PT_L, c, val(TB_GPU_PT_L, c) + val(TB_GPU_PT_BETA, c) * tab(eb + c) * st.scale);
    st.shadow = TB_GPU_PT_SHADOW_NONE;
}

void stage_shade()
{
    tb_gpu_pt_state st = states[g_i];
    if (st.alive == 0u)
        return;
    add_light_sample(st);
    tb_gpu_ray r = rays[g_i];
    tb_gpu_hit h = hits[g_i];
    vec3 ng = vec3(h.ng[0], h.ng[1], h.ng[2]);
    int m = int(texelFetch(table_texels, OBJ_BASE + int(h.object)).x);
    int mb = m * 2 * NCH;
    bool front = dot(r.d, ng) < 0.0;
    // Emission of a front face, counted where no light sample could have
    // found it: at the camera ray's hit (throughput 1, radiance 0 so far).
    if (front && st.depth == 0u)
        for (int c = 0; c < NCH; c++)
            set_val(TB_GPU_PT_L, c, tab(mb + NCH + c));
    if (!(tab(DMAX_BASE + m) > 0.0) || (pc.max_depth > 0u && st.depth >= pc.max_depth) ||
        st.depth >= pc.max_bounces) {
        st.alive = 0u;
        states[g_i] = st;
        return;
    }
    vec3 n = front ? ng : -ng; // Lambert is two-sided: the normal faces the ray
    vec3 p = r.o + h.t * r.d;
    vec3 perr = (abs(r.o) + abs(h.t * r.d)) * (1.0 / 131072.0);

    // One sample of the area light, its shadow ray traced by the shadow stage.
    float scale = 0.0;
    if (NEMIT > 0) {
        float u1 = rnd(st), u2 = rnd(st);
        float pmf, ur;
        int k = pick_emitter(u1, pmf, ur);
        vec3 q;
        float pdf_sa;
        if (pmf > 0.0 && sample_emitter(emitters[k], p, ur, u2, q, pdf_sa)) {
            vec3 dq = q - p;
            float dist = length(dq);
            float pdf = pmf * pdf_sa;
            vec3 wi = dq / dist;
            float cosi = dot(n, wi);
            if (dist > 0.0 && pdf > 0.0 && cosi > 0.0) {
                // Lambert f = diffuse / pi; the diffuse colour goes into the
                // throughput below, so the scale holds the rest
                scale = INV_PI * cosi / pdf;
                vec3 o = spawn_origin(p, perr, ng, wi);
                tb_gpu_ray sr;
                sr.o = o;
                sr.tmin = 0.0;
                sr.d = q - o;
                sr.tmax = 1.0 - SHADOW_EPSILON;
                shadows[g_i] = sr;
                st.emitter = uint(k);
            }
        }
    }

    // The BSDF sample (three numbers, as the CPU's lobe choice + direction):
    // cosine-weighted about n, weight = the diffuse colour.
    rnd(st);
    float u1 = rnd(st), u2 = rnd(st);
    vec2 dk = tb_concentric_disc(u1, u2);
    float z = sqrt(max(0.0, 1.0 - dot(dk, dk)));
    vec3 b1, b2;
    basis(n, b1, b2);
    vec3 wi = normalize(b1 * dk.x + b2 * dk.y + n * z);
    bool go = z > 0.0 && dot(wi, n) > 0.0;
    float beta[NCH];
    float bmax = 0.0;
    for (int c = 0; c < NCH; c++) {
        beta[c] = (st.depth == 0u ? 1.0 : val(TB_GPU_PT_BETA, c)) * tab(mb + c);
        bmax = max(bmax, beta[c]);
    }
    go = go && bmax > 0.0 && !isinf(bmax) && !isnan(bmax);
    st.depth++;
    // Russian roulette: the throughput is divided by q, the light sample's
    // scale multiplied by it (its contribution is before the roulette).
    if (go && st.depth >= pc.rr_depth) {
        float q = min(1.0, bmax);
        if (q < 1.0) {
            if (!(rnd(st) < q)) {
                go = false;
            } else {
                for (int c = 0; c < NCH; c++)
                    beta[c] *= 1.0 / q;
                scale *= q;
            }
        }
    }
    st.shadow = scale > 0.0 ? TB_GPU_PT_SHADOW_PENDING : TB_GPU_PT_SHADOW_NONE;
    st.scale = scale;
    if (go || scale > 0.0)
        for (int c = 0; c < NCH; c++)
            set_val(TB_GPU_PT_BETA, c, beta[c]);
    if (go) {
        tb_gpu_ray nr;
        nr.o = spawn_origin(p, perr, ng, wi);
        nr.tmin = 0.0;
        nr.d = wi;
        nr.tmax = 1.0 / 0.0;
        rays[g_i] = nr;
    }
    st.alive = go ? 1u : 0u;
    states[g_i] = st;
    if (go && pc.count != 0u)
        atomicAdd(alive_count, 1u);
}

void stage_accumulate()
{
    tb_gpu_pt_state st = states[g_i];
    if (st.shadow != TB_GPU_PT_SHADOW_CLEAR)
        return;
    add_light_sample(st);
    states[g_i].shadow = st.shadow;
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
    vec3 ng = tb_bvh_normal(r, b);
    h.ng[0] = ng.x;
    h.ng[1] = ng.y;
    h.ng[2] = ng.z;
    hits[g_i] = h;
}

void stage_shadow()
{
    if (states[g_i].shadow != TB_GPU_PT_SHADOW_PENDING)
        return;
    tb_bvh_hit b;
    bool blocked = tb_bvh_traverse(shadows[g_i], pc.nnodes, true, b);
    states[g_i].shadow = blocked ? TB_GPU_PT_SHADOW_NONE : TB_GPU_PT_SHADOW_CLEAR;
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
