// Routines the Vulkan renderers' kernels share (shaders/shade.comp,
// lib/pathtrace.glsl): spawn points off a surface, an orthonormal basis, the
// concentric disc map, points on area-light emitters, the spot falloff, the
// dielectric Fresnel reflectance and the power heuristic, each the GLSL twin
// of a C routine named at it. The includer defines EMITTER_KINDS first (a
// const uint, bit k: an emitter of kind k, TB_GPU_EMITTER_*, exists; the
// others are compiled out) and includes shared/shade.h (tb_gpu_emitter).
#ifndef TB_LIB_EMITTER_GLSL
#define TB_LIB_EMITTER_GLSL

const float TB_EMITTER_TWO_PI = 6.28318530717958647692528676655900576;

// The next float above / below x (x finite).
float next_up(float x)
{
    if (x == 0.0)
        return uintBitsToFloat(1u);
    uint b = floatBitsToUint(x);
    return uintBitsToFloat(x > 0.0 ? b + 1u : b - 1u);
}
float next_down(float x) { return -next_up(-x); }

// tb_spawn_ray_origin (host/object/hit.h): p moved off the surface along ng
// to w's side by the error bound perr, then one float further.
vec3 spawn_origin(vec3 p, vec3 perr, vec3 ng, vec3 w)
{
    float d = next_up(dot(abs(ng), perr));
    float s = dot(w, ng) < 0.0 ? -d : d;
    vec3 off = s * ng;
    vec3 po = p + off;
    for (int i = 0; i < 3; i++) {
        if (off[i] > 0.0)
            po[i] = next_up(po[i]);
        else if (off[i] < 0.0)
            po[i] = next_down(po[i]);
    }
    return po;
}

// tb_dvec3_basis (util/math/vec.h): Duff et al.'s orthonormal basis; the
// sign is copysign's (-0 counts as negative), as in the C code.
void basis(vec3 n, out vec3 b1, out vec3 b2)
{
    float sgn = (floatBitsToUint(n.z) & 0x80000000u) != 0u ? -1.0 : 1.0;
    float a = -1.0 / (sgn + n.z);
    float b = n.x * n.y * a;
    b1 = vec3(1.0 + sgn * n.x * n.x * a, sgn * b, -sgn * n.x);
    b2 = vec3(b, sgn + n.y * n.y * a, -n.y);
}

// Shirley's concentric map of [0, 1)^2 onto the unit disc
// (tb_sample_disk_concentric, host/render/sampling.c).
vec2 tb_concentric_disc(float u1, float u2)
{
    const float PI_4 = 0.785398163397448309615660845819875721;
    const float PI_2 = 1.57079632679489661923132169163975144;
    float ox = 2.0 * u1 - 1.0, oy = 2.0 * u2 - 1.0;
    vec2 dk = vec2(0.0);
    if (ox != 0.0 || oy != 0.0) {
        float r, th;
        if (abs(ox) > abs(oy)) {
            r = ox;
            th = PI_4 * (oy / ox);
        } else {
            r = oy;
            th = PI_2 - PI_4 * (ox / oy);
        }
        dk = vec2(r * cos(th), r * sin(th));
    }
    return dk;
}

// A point on emitter e seen from p (tb__sample_emitter in host/render/lights.c):
// false if it gives no light.
bool sample_emitter(tb_gpu_emitter e, vec3 p, float u1, float u2, out vec3 q, out float pdf_sa)
{
    float pdf_a = e.inv_area;
    vec3 nq;
    if ((EMITTER_KINDS & (1u << TB_GPU_EMITTER_TRIANGLE)) != 0u && e.kind == TB_GPU_EMITTER_TRIANGLE) {
        float su = sqrt(u1);
        float b0 = 1.0 - su, b1 = u2 * su, b2 = 1.0 - b0 - b1;
        q = e.v0 * b0 + e.v1 * b1 + e.v2 * b2;
        nq = e.normal;
    } else if ((EMITTER_KINDS & (1u << TB_GPU_EMITTER_PARALLELOGRAM)) != 0u &&
               e.kind == TB_GPU_EMITTER_PARALLELOGRAM) {
        q = e.v0 + (e.v1 - e.v0) * u1 + (e.v2 - e.v0) * u2;
        nq = e.normal;
    } else if ((EMITTER_KINDS & (1u << TB_GPU_EMITTER_DISC)) != 0u && e.kind == TB_GPU_EMITTER_DISC) {
        vec2 dk = tb_concentric_disc(u1, u2);
        vec3 b1, b2;
        basis(e.v1, b1, b2);
        q = e.v0 + b1 * (e.radius * dk.x) + b2 * (e.radius * dk.y);
        nq = e.v1;
    } else if ((EMITTER_KINDS & (1u << TB_GPU_EMITTER_SPHERE)) != 0u && e.kind == TB_GPU_EMITTER_SPHERE) {
        vec3 pc_ = p - e.v0;
        float r = e.radius, dc = length(pc_);
        if (!(dc > r * (1.0 + 1e-6)))
            return false; // inside: the host routes scenes with two-sided spheres to the CPU
        float s2max = (r / dc) * (r / dc);
        float omc_max = s2max / (1.0 + sqrt(max(0.0, 1.0 - s2max)));
        float omc = u1 * omc_max;
        float ct = 1.0 - omc, s2 = omc * (2.0 - omc);
        float cos_alpha = s2 / sqrt(s2max) + ct * sqrt(max(0.0, 1.0 - s2 / s2max));
        float sin_alpha = sqrt(max(0.0, 1.0 - cos_alpha * cos_alpha));
        float phi = TB_EMITTER_TWO_PI * u2;
        vec3 axis = pc_ / dc, b1, b2;
        basis(axis, b1, b2);
        nq = normalize(b1 * (sin_alpha * cos(phi)) + b2 * (sin_alpha * sin(phi)) + axis * cos_alpha);
        q = e.v0 + nq * r;
        pdf_sa = 1.0 / (TB_EMITTER_TWO_PI * omc_max);
        return pdf_sa > 0.0 && !isinf(pdf_sa);
    } else {
        return false;
    }
    vec3 d = q - p;
    float d2 = dot(d, d);
    float cq = -dot(nq, d) / sqrt(d2);
    if (!(d2 > 0.0) || cq == 0.0 || (cq < 0.0 && e.two_sided == 0u))
        return false;
    pdf_sa = pdf_a * d2 / abs(cq);
    return !isinf(pdf_sa) && !isnan(pdf_sa);
}

// tb_spot_falloff (host/render/lights.c).
float spot_falloff(float cos_total, float cos_falloff, float c)
{
    if (c <= cos_total)
        return 0.0;
    if (c >= cos_falloff)
        return 1.0;
    float t = (c - cos_total) / (cos_falloff - cos_total);
    return t * t * (3.0 - 2.0 * t);
}

// tb_fresnel_dielectric (host/render/shading.c), in float.
float fresnel_dielectric(float cos_i, float eta)
{
    if (eta == 1.0)
        return 0.0;
    cos_i = clamp(cos_i, -1.0, 1.0);
    if (cos_i < 0.0) {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    float sin2_t = (1.0 - cos_i) * (1.0 + cos_i) / (eta * eta);
    if (sin2_t >= 1.0)
        return 1.0;
    float cos_t = sqrt(1.0 - sin2_t);
    float r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    float r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (r_parl * r_parl + r_perp * r_perp);
}

// The power heuristic (raytrace.c's tb__power).
float power_heuristic(float a, float b) { return a > 0.0 ? a * a / (a * a + b * b) : 0.0; }

#endif
