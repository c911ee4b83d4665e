// The shade kernel of the wavefront ray tracer (host/gpu/render.c; docs/gpu.md,
// "Shade kernel and wavefront renderer"): for each shading point (a ray and
// its closest hit from the intersect kernel) it evaluates what the CPU ray
// tracer's tb__trace evaluates (host/render/raytrace.c):
//  - the emission M / pi of an emitter seen from its front side;
//  - point, spot and directional lights: Lambert + the normalised Phong or the
//    exactly normalised Blinn-Phong lobe,
//    one shadow ray each;
//  - the area light (every emitter of the scene): the light samples the host
//    drew from the sample's own stream (emitter chosen by the double CDF),
//    the point on the emitter, its solid-angle density and the Lambert
//    estimate, one shadow ray each;
//  - the GGX lobe of model ggx (shading.c's tb_bsdf_ggx with Schlick
//    Fresnel, F0 = the specular colour): its value for every light and
//    light sample, the light samples weighted by the power heuristic
//    against the glossy rays, and the glossy rays themselves (Heitz's VNDF
//    sampling from the host's numbers, weight F G2 / G1, density);
//  - the secondary rays: Fresnel-weighted mirror and refracted rays of a
//    smooth dielectric (total internal reflection: R = 1), or the perfect
//    mirror weighted by the specular colour, or the glossy rays.
// Shadow contributions are written unoccluded as two scalars a, b per shadow
// ray (the contribution is (diffuse a + specular b) x the light's colour):
// the host traces the shadow rays through the occlusion kernel and applies
// the colours of the unblocked ones, so the kernel writes 3 words per shadow
// ray instead of one per channel (31 bands: the kernel ran 4x slower). Everything
// is in float (the CPU path works in double in places): docs/accuracy.md,
// "Shade kernel", gives the resulting image tolerance.
//
// Specialization constants switch on only what the scene uses: the number of
// channels (3 RGB or the spectral bands), delta lights, light samples, spot
// cones, Phong highlights, mirrors, dielectrics, emission, emitter kinds,
// IES tables, GGX lobes and their glossy rays.
#version 450
#extension GL_GOOGLE_include_directive : require

#include "shared/ray.h"
#include "shared/shade.h"
#include "lib/ggx.glsl"

layout(local_size_x_id = 0) in;
layout(constant_id = 1) const int NCH = 3;              // channels (RGB or render bands)
layout(constant_id = 2) const int NLIGHTS = 0;          // point, spot and directional lights
layout(constant_id = 3) const int NSAMPLES = 0;         // area-light samples per point (0: no area light)
layout(constant_id = 4) const bool HAS_SPOT = false;    // some light is a spot
layout(constant_id = 5) const bool HAS_PHONG = false;   // some material has a specular colour (highlights)
layout(constant_id = 6) const bool HAS_MIRROR = false;  // some material is a mirror (specular, no transmission)
layout(constant_id = 7) const bool HAS_DIELECTRIC = false; // some material transmits
layout(constant_id = 8) const bool HAS_EMISSION = false;   // some material emits
layout(constant_id = 9) const uint EMITTER_KINDS = 1u;  // bit k: an emitter of kind k exists
layout(constant_id = 10) const bool HAS_IES = false;    // some light has an IES distribution
layout(constant_id = 11) const bool HAS_GGX = false;    // some material has a GGX lobe
layout(constant_id = 12) const int NGLOSSY = 0;         // most glossy rays per item (0: no GGX)
layout(constant_id = 13) const bool HAS_COLOR_PATTERN = false; // some material has a diffuse or specular pattern
layout(constant_id = 14) const bool HAS_BUMP = false;   // some material has a (noise) bump map
layout(constant_id = 15) const uint PATTERN_KINDS = 0u; // bit k: a pattern or bump of kind k (TB_GPU_PATTERN_*) exists
layout(constant_id = 16) const bool HAS_TEXTURE = false; // some material has an image texture
layout(constant_id = 17) const int TEX_FILTER = 3;      // their filter (TB_TEX_*: the tracer's, EWA by default)

const int S = NLIGHTS + NSAMPLES;  // shadow rays per item
const int SW = HAS_GGX ? 4 : 3;    // words per shadow ray: flag, a, b (and c with GGX)
const int SLOT = NCH + 1;          // floats per colour slot (flag and channels)
const int PW0 = HAS_COLOR_PATTERN ? 2 : 0; // pattern words per item: the diffuse and specular blend factors
const int PW = PW0 + (HAS_TEXTURE ? 6 : 0); // and the diffuse and specular texture RGB
const float PI = 3.14159265358979323846;
const float INV_PI = 0.318309886183790671537767526745028724;
const float SHADOW_EPSILON = 1e-4;  // TB_SHADOW_EPSILON

layout(std430, binding = 0) readonly buffer Items { tb_gpu_shade_item items[]; };
layout(std430, binding = 1) readonly buffer LightU { tb_gpu_light_u lightu[]; };
layout(std430, binding = 2) readonly buffer Emitters { tb_gpu_emitter emitters[]; };
layout(std430, binding = 3) readonly buffer Lights { tb_gpu_delta_light lights[]; };
layout(std430, binding = 4) readonly buffer Materials { tb_gpu_shade_material materials[]; };
layout(std430, binding = 5) readonly buffer Colours { float colours[]; };
layout(std430, binding = 6) writeonly buffer OutRays { tb_gpu_ray out_rays[]; };
layout(std430, binding = 7) writeonly buffer OutValues { float out_values[]; };
layout(std430, binding = 8) readonly buffer Surfaces { tb_gpu_surface surfaces[]; };
layout(std430, binding = 9) readonly buffer TexInfo { uint texinfo[]; };
layout(std430, binding = 10) readonly buffer Texels { float texels[]; };

layout(push_constant) uniform Push {
    uint items;
    uint perm; // float offset of the noise permutation in the colour table
    uint pad1, pad2;
} pc;

int tb_perm(int i) { return int(colours[pc.perm + uint(i & 255)]); }
#include "lib/pattern.glsl"
uint tb_texinfo(uint i) { return texinfo[i]; }
float tb_texel(uint i) { return texels[i]; }
#include "lib/texture.glsl"
#include "lib/emitter.glsl"

// The interval i of a[base .. base + n) with a[i] <= x (tb__interval in host/render/ies.c).
int ies_interval(uint base, int n, float x)
{
    int lo = 0, hi = n - 2;
    while (lo < hi) {
        int mid = lo + (hi - lo + 1) / 2;
        if (colours[base + uint(mid)] <= x)
            lo = mid;
        else
            hi = mid - 1;
    }
    return lo;
}

// tb_ies_normalized (host/render/ies.c) of the record at `rec` for the
// photometric-frame direction w: the candela table interpolated bilinearly
// in (vertical, horizontal) degrees, horizontal angles reduced by the
// table's symmetry, divided by the maximum.
float ies_normalized(uint rec, vec3 w)
{
    int nv = int(colours[rec]), nh = int(colours[rec + 1u]), sym = int(colours[rec + 2u]);
    float inv_max = colours[rec + 3u];
    uint va = rec + 4u, ha = va + uint(nv), cd = ha + uint(nh);
    float v = degrees(atan(length(w.xy), -w.z));
    float h = degrees(atan(w.y, w.x));
    if (h < 0.0)
        h += 360.0;
    if (h >= 360.0)
        h = 0.0;
    if (!(v >= colours[va] && v <= colours[va + uint(nv - 1)]))
        return 0.0;
    int i = ies_interval(va, nv, v);
    float t = (v - colours[va + uint(i)]) / (colours[va + uint(i + 1)] - colours[va + uint(i)]);
    if (nh == 1 || sym == 1) // rotational
        return ((1.0 - t) * colours[cd + uint(i)] + t * colours[cd + uint(i + 1)]) * inv_max;
    if (sym == 2) { // quadrant
        if (h > 180.0)
            h = 360.0 - h;
        if (h > 90.0)
            h = 180.0 - h;
    } else if (sym == 3) { // bilateral
        if (h > 180.0)
            h = 360.0 - h;
    } else if (sym == 4) { // bilateral about 90-270
        if (h < 90.0)
            h = 180.0 - h;
        else if (h > 270.0)
            h = 540.0 - h;
    }
    h = clamp(h, colours[ha], colours[ha + uint(nh - 1)]);
    int j = ies_interval(ha, nh, h);
    float sj = (h - colours[ha + uint(j)]) / (colours[ha + uint(j + 1)] - colours[ha + uint(j)]);
    uint r0 = cd + uint(j * nv + i), r1 = cd + uint((j + 1) * nv + i);
    float lo = (1.0 - t) * colours[r0] + t * colours[r0 + 1u];
    float hi = (1.0 - t) * colours[r1] + t * colours[r1 + 1u];
    return ((1.0 - sj) * lo + sj * hi) * inv_max;
}


// Outputs are stored slot-major (slot k of item i at k * items + i), so that
// neighbouring invocations write neighbouring words: contiguous stores on a
// SIMD CPU driver such as lavapipe instead of scatters 1 KiB apart.
uint g_item;
void write_ray(int k, vec3 o, vec3 d, float tmax)
{
    uint at = uint(k) * pc.items + g_item;
    out_rays[at].o = o;
    out_rays[at].tmin = 0.0;
    out_rays[at].d = d;
    out_rays[at].tmax = tmax;
}
// Word c of shadow slot s (c = 0: the validity flag, 1: a, 2: b; the
// contribution is (diffuse a + specular b) times the light's colour, applied
// by the host when the shadow ray is unblocked).
void sput(int s, int c, float x) { out_values[uint(s * SW + c) * pc.items + g_item] = x; }
// Word c of colour slot k (0 emission, 1 mirror, 2 refracted, 3 + k glossy
// ray k; c = 0: the validity flag, 1 + channel: the values), after the
// shadow slots.
void put(int k, int c, float x) { out_values[uint(SW * S + k * SLOT + c) * pc.items + g_item] = x; }
// The density of glossy ray k, after the colour slots.
void gput(int k, float x) { out_values[uint(SW * S + (3 + NGLOSSY) * SLOT + k) * pc.items + g_item] = x; }
// Pattern word k (0: diffuse, 1: specular blend factor, -1 without a pattern), after the densities.
void fput(int k, float x) { out_values[uint(SW * S + (3 + NGLOSSY) * SLOT + NGLOSSY + k) * pc.items + g_item] = x; }

// patterns: pattern_value and bump_normal (lib/pattern_eval.glsl, shared with
// the path tracer)
#include "lib/pattern_eval.glsl"

// The specular colour of the item in channel c: the material's, or its
// pattern's blend a + f (b - a).
uint g_mc;       // the material's colours in the colour table
float g_fs;      // the specular pattern's blend factor (-1: none)
uint g_spec_col; // the pattern's colours
vec3 g_tex[4];   // the textures' RGB at the hit (1 without a texture)
float spec_colour(int c)
{
    float k = colours[g_mc + uint(NCH + c)];
    if (HAS_COLOR_PATTERN && g_fs >= 0.0) {
        float a = colours[g_spec_col + uint(c)], b = colours[g_spec_col + uint(NCH + c)];
        k = a + g_fs * (b - a);
    }
    return HAS_TEXTURE ? k * g_tex[TB_GPU_TEX_SPECULAR][c % 3] : k;
}

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.items)
        return;
    g_item = i;
    tb_gpu_shade_item it = items[i];
    for (int k = 0; k < S; k++)
        sput(k, 0, 0.0);
    for (int k = 0; k < 3 + NGLOSSY; k++)
        put(k, 0, 0.0);
    for (int k = 0; k < PW; k++)
        fput(k, -1.0);

    tb_gpu_shade_material m = materials[it.material];
    uint mc = it.material * uint(4 * NCH); // diffuse, specular, transmission, emission
    vec3 p = it.o + it.t * it.d;
    // The float hit point's error: the kernel's t is within a few ulps and
    // p = o + t d adds two roundings; 2^-17 of the magnitudes is a wide margin.
    vec3 perr = (abs(it.o) + abs(it.t * it.d)) * (1.0 / 131072.0);
    vec3 dir = normalize(it.d);
    vec3 wo = -dir;
    vec3 ng = it.ng;
    bool front = dot(dir, ng) < 0.0;
    vec3 n = front ? ng : -ng;
    g_mc = mc;
    g_fs = -1.0;
    for (int k = 0; k < 4; k++)
        g_tex[k] = vec3(1.0);
    if ((HAS_COLOR_PATTERN || HAS_BUMP || HAS_TEXTURE) && (it.flags & TB_GPU_SHADE_SURFACE) != 0u) {
        tb_gpu_surface g = surfaces[i];
        if (HAS_TEXTURE) {
            // image textures at the hit's (u, v) over the camera ray's footprint
            // (raytrace.c's tb__textured; a grey image gives one value for all three)
            vec4 fp = vec4(g.fp0, g.fp1, g.fp2, g.fp3);
            for (int k = 0; k < 4; k++) {
                if (m.tex[k] == TB_GPU_NO_TEXTURE)
                    continue;
                vec4 t = tb_tex_lookup(m.tex[k], TEX_FILTER, g.u, g.v, fp);
                g_tex[k] = tb_tex_channels(m.tex[k]) >= 3 ? t.rgb : vec3(t.x);
            }
            for (int k = 0; k < 2; k++) {
                bool has = m.tex[k] != TB_GPU_NO_TEXTURE;
                for (int c = 0; c < 3; c++)
                    fput(PW0 + 3 * k + c, has ? g_tex[k][c] : -1.0);
            }
        }
        if (HAS_BUMP && m.pattern[TB_GPU_PATTERN_BUMP].kind != TB_GPU_PATTERN_NONE)
            n = bump_normal(m.pattern[TB_GPU_PATTERN_BUMP], g, n); // rays still leave by ng
        if (HAS_COLOR_PATTERN) {
            vec4 fp = vec4(g.fp0, g.fp1, g.fp2, g.fp3);
            float fd = -1.0;
            for (int k = 0; k < 2; k++) {
                tb_gpu_pattern pt = m.pattern[k];
                if (pt.kind == TB_GPU_PATTERN_NONE)
                    continue;
                float f = clamp(pattern_value(pt, false, g.u, g.v, fp, g.po, g.po_dx, g.po_dy), 0.0, 1.0);
                if (k == 0) {
                    fd = f;
                } else {
                    g_fs = f;
                    g_spec_col = pt.col;
                }
            }
            fput(0, fd);
            fput(1, g_fs);
        }
    }
    bool has_diffuse = (m.flags & TB_GPU_MAT_DIFFUSE) != 0u;
    bool has_specular = (m.flags & TB_GPU_MAT_SPECULAR) != 0u;
    bool has_transmission = (m.flags & TB_GPU_MAT_TRANSMISSION) != 0u;
    // The GGX lobe in the frame of the shading normal (tb_frame_from_normal).
    bool ggx = HAS_GGX && (m.flags & TB_GPU_MAT_GGX) != 0u;
    vec3 fs = vec3(0.0), ft = vec3(0.0), wol = vec3(0.0, 0.0, 1.0);
    if (ggx) {
        basis(n, fs, ft);
        wol = vec3(dot(wo, fs), dot(wo, ft), dot(wo, n));
        wol = normalize(wol);
    }
    int nglossy = ggx ? int(it.glossy) : 0;

    // Emission: one-sided emitters, M / pi on the front.
    if (HAS_EMISSION && (m.flags & TB_GPU_MAT_EMITS) != 0u && front) {
        put(0, 0, 1.0);
        for (int c = 0; c < NCH; c++)
            put(0, 1 + c, (HAS_TEXTURE ? colours[mc + uint(3 * NCH + c)] * g_tex[TB_GPU_TEX_EMISSION][c % 3]
                                        : colours[mc + uint(3 * NCH + c)]) * INV_PI);
    }

    // Point, spot and directional lights.
    if (NLIGHTS > 0 && (has_diffuse || has_specular)) {
        vec3 wr = 2.0 * dot(wo, n) * n - wo;
        for (int l = 0; l < NLIGHTS; l++) {
            tb_gpu_delta_light lt = lights[l];
            vec3 wi;
            float scale, tmax;
            vec3 target;
            if (lt.kind == TB_GPU_LIGHT_DIRECTIONAL) {
                wi = -lt.axis;
                scale = 1.0;
                tmax = 1.0 / 0.0;
            } else {
                vec3 dl = lt.position - p;
                float dist = length(dl);
                if (!(dist > 0.0) || isinf(dist))
                    continue;
                wi = dl / dist;
                float k = 1.0;
                if (HAS_SPOT && lt.kind == TB_GPU_LIGHT_SPOT)
                    k = spot_falloff(lt.cos_total, lt.cos_falloff, dot(-wi, lt.axis));
                if (HAS_IES && lt.ies != TB_GPU_NO_IES && k > 0.0) {
                    // photometric frame: x, y = x cross nadir, z = -nadir (tb__shape)
                    vec3 wl = -wi;
                    vec3 y = cross(lt.xaxis, lt.axis);
                    k *= ies_normalized(lt.ies, vec3(dot(wl, lt.xaxis), dot(wl, y), -dot(wl, lt.axis)));
                }
                if (!(k > 0.0))
                    continue;
                scale = k / (dist * dist);
                tmax = 1.0 - SHADOW_EPSILON;
            }
            float cosi = dot(n, wi);
            if (cosi <= 0.0)
                continue;
            float spec = 0.0, white = 0.0;
            if (ggx) {
                vec3 e = tb_ggx_eval(m.alpha, wol, normalize(vec3(dot(wi, fs), dot(wi, ft), dot(wi, n))));
                spec = e.x * (1.0 - e.y);
                white = e.x * e.y;
            } else if (HAS_PHONG && has_specular) {
                float ca;
                if ((m.flags & TB_GPU_MAT_BLINN) != 0u) {
                    // exactly normalised Blinn-Phong: the half vector (raytrace.c's tb__lobe)
                    vec3 h = wo + wi;
                    float len = length(h);
                    ca = len > 0.0 ? dot(n, h) / len : 0.0;
                } else {
                    ca = dot(wr, wi);
                }
                if (ca > 0.0)
                    spec = m.knorm * pow(ca, m.exponent);
            }
            if (lt.black != 0u || !(scale > 0.0))
                continue; // no light (tb_light_sample_li is false)
            sput(l, 0, 1.0);
            sput(l, 1, INV_PI * scale * cosi);
            sput(l, 2, spec * scale * cosi);
            if (HAS_GGX)
                sput(l, 3, white * scale * cosi);
            vec3 o = spawn_origin(p, perr, ng, wi);
            write_ray(l, o, lt.kind == TB_GPU_LIGHT_DIRECTIONAL ? wi : lt.position - o, tmax);
        }
    }

    // The area light: the host's samples (tb_area_light_sample).
    if (NSAMPLES > 0 && (it.flags & TB_GPU_SHADE_AREA) != 0u) {
        float norm = 1.0 / (3.14159265358979323846 * float(NSAMPLES));
        for (int k = 0; k < NSAMPLES; k++) {
            tb_gpu_light_u lu = lightu[it.light_base + uint(k)];
            tb_gpu_emitter e = emitters[lu.emitter];
            vec3 q;
            float pdf_sa;
            if (!sample_emitter(e, p, lu.u1, lu.u2, q, pdf_sa))
                continue;
            vec3 dq = q - p;
            float dist = length(dq);
            float pdf = lu.pmf * pdf_sa;
            if (!(dist > 0.0) || !(pdf > 0.0))
                continue;
            vec3 wi = dq / dist;
            float cosi = dot(n, wi);
            if (cosi <= 0.0)
                continue;
            float w = cosi / pdf;
            sput(NLIGHTS + k, 0, 1.0);
            sput(NLIGHTS + k, 1, w * norm);
            sput(NLIGHTS + k, 2, 0.0);
            if (HAS_GGX) {
                float spec = 0.0, white = 0.0;
                if (ggx) {
                    // the lobe, weighted against the glossy rays (power heuristic)
                    vec3 e = tb_ggx_eval(m.alpha, wol, normalize(vec3(dot(wi, fs), dot(wi, ft), dot(wi, n))));
                    float mw = power_heuristic(float(NSAMPLES) * pdf, float(nglossy) * e.z);
                    float k2 = w * mw / float(NSAMPLES);
                    spec = e.x * (1.0 - e.y) * k2;
                    white = e.x * e.y * k2;
                }
                sput(NLIGHTS + k, 2, spec);
                sput(NLIGHTS + k, 3, white);
            }
            vec3 o = spawn_origin(p, perr, ng, wi);
            write_ray(NLIGHTS + k, o, q - o, 1.0 - SHADOW_EPSILON);
        }
    }

    // Secondary rays.
    if ((it.flags & TB_GPU_SHADE_SPAWN) == 0u)
        return;
    const int vm = 1, vt = 2; // colour slots of the mirror and the refracted ray
    if (HAS_DIELECTRIC && has_transmission) {
        float cos_i = dot(wo, ng);
        float R = fresnel_dielectric(cos_i, m.ior);
        float etap = cos_i < 0.0 ? 1.0 / m.ior : m.ior;
        vec3 nn = cos_i < 0.0 ? -ng : ng;
        float c = abs(cos_i);
        float sin2_t = (1.0 - c) * (1.0 + c) / (etap * etap);
        bool refracts = sin2_t < 1.0;
        if (!refracts)
            R = 1.0;
        float T = 1.0 - R;
        if (R > 0.0) {
            vec3 w = 2.0 * cos_i * ng - wo;
            write_ray(S, spawn_origin(p, perr, ng, w), w, 1.0 / 0.0);
            put(vm, 0, 1.0);
            for (int k = 0; k < NCH; k++)
                put(vm, 1 + k, R);
        }
        if (refracts && T > 0.0) {
            float cos_t = sqrt(1.0 - sin2_t);
            vec3 w = normalize(-wo / etap + (c / etap - cos_t) * nn);
            write_ray(S + 1, spawn_origin(p, perr, ng, w), w, 1.0 / 0.0);
            put(vt, 0, 1.0);
            for (int k = 0; k < NCH; k++)
                put(vt, 1 + k, (HAS_TEXTURE ? colours[mc + uint(2 * NCH + k)] * g_tex[TB_GPU_TEX_TRANSMISSION][k % 3]
                                            : colours[mc + uint(2 * NCH + k)]) * T);
        }
    } else if (HAS_GGX && ggx) {
        // Glossy rays from the host's numbers (tb_bsdf_sample of the lobe,
        // then raytrace.c's test that the ray leaves on the viewer's side).
        for (int k = 0; k < NGLOSSY; k++) {
            if (k >= nglossy)
                break;
            tb_gpu_light_u gu = lightu[it.light_base + uint(NSAMPLES + k)];
            float side = wol.z > 0.0 ? 1.0 : -1.0;
            vec3 mh = tb_ggx_sample_vndf(m.alpha, wol, gu.u1, gu.u2) * side;
            vec3 wil = normalize(2.0 * dot(wol, mh) * mh - wol);
            if (wil.z == 0.0)
                continue;
            vec3 e = tb_ggx_eval(m.alpha, wol, wil);
            if (!(e.z > 0.0) || !(e.x > 0.0) || isinf(e.z))
                continue;
            vec3 w = normalize(fs * wil.x + ft * wil.y + n * wil.z);
            if ((dot(w, ng) > 0.0) != front)
                continue; // a bumped normal can send the ray into the surface
            write_ray(S + 2 + k, spawn_origin(p, perr, ng, w), w, 1.0 / 0.0);
            float q = e.x * abs(wil.z) / e.z; // F G2 / G1 without F
            put(3 + k, 0, 1.0);
            for (int c = 0; c < NCH; c++) {
                float f0 = spec_colour(c);
                put(3 + k, 1 + c, (f0 * (1.0 - e.y) + e.y) * q);
            }
            gput(k, e.z);
        }
    } else if (HAS_MIRROR && has_specular) {
        vec3 w = normalize(2.0 * dot(wo, n) * n - wo);
        if ((dot(w, ng) > 0.0) != front)
            return; // rounded into the surface at grazing incidence: raytrace.c traces nothing either
        write_ray(S, spawn_origin(p, perr, ng, w), w, 1.0 / 0.0);
        put(vm, 0, 1.0);
        for (int k = 0; k < NCH; k++)
            put(vm, 1 + k, spec_colour(k));
    }
}
