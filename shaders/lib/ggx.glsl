// The GGX microfacet lobe: the GLSL twins of shading.c's tb__ggx_D,
// tb__ggx_lambda, tb__ggx_sample_vndf (Heitz 2018), tb__ggx_vndf_pdf and the
// TB_BSDF_GGX case of tb__evaluate with Schlick Fresnel. The C code works in
// double, these in float; tests/gpu (test_gpu_kernels.c, k_shading) checks
// them against the C functions on exact inputs (tolerances in docs/gpu.md,
// "GLSL routine library").
#ifndef TB_LIB_GGX_GLSL
#define TB_LIB_GGX_GLSL

const float TB_GGX_PI = 3.14159265358979323846;

// tb__ggx_D: the denominator as (x^2 + y^2) + z^2 alpha^2 (no cancellation).
float tb_ggx_D(float a, vec3 m)
{
    if (!(m.z > 0.0))
        return 0.0;
    float a2 = a * a;
    float t = (m.x * m.x + m.y * m.y) + m.z * m.z * a2;
    return a2 / (TB_GGX_PI * t * t);
}

// tb__ggx_lambda, in the form without cancellation for small tan.
float tb_ggx_lambda(float a, vec3 w)
{
    float z2 = w.z * w.z;
    if (z2 == 0.0)
        return 1.0 / 0.0;
    float x = a * a * (w.x * w.x + w.y * w.y) / z2;
    return x / (2.0 * (sqrt(1.0 + x) + 1.0));
}

// tb__ggx_sample_vndf (Heitz 2018, listing 1), w flipped to z >= 0.
vec3 tb_ggx_sample_vndf(float a, vec3 w, float u1, float u2)
{
    if (w.z < 0.0)
        w = -w;
    vec3 vh = normalize(vec3(a * w.x, a * w.y, w.z));
    float lensq = vh.x * vh.x + vh.y * vh.y;
    vec3 t1 = lensq > 0.0 ? vec3(-vh.y, vh.x, 0.0) / sqrt(lensq) : vec3(1.0, 0.0, 0.0);
    vec3 t2 = cross(vh, t1);
    float r = sqrt(u1), phi = 2.0 * TB_GGX_PI * u2;
    float p1 = r * cos(phi), p2 = r * sin(phi);
    float s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * sqrt(max(0.0, 1.0 - p1 * p1)) + s * p2;
    float pz = sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2));
    vec3 nh = t1 * p1 + t2 * p2 + vh * pz;
    return normalize(vec3(a * nh.x, a * nh.y, max(1e-12, nh.z)));
}

// tb__ggx_vndf_pdf: density of m seen from w (w flipped to z >= 0).
float tb_ggx_vndf_pdf(float a, vec3 w, vec3 m)
{
    if (w.z < 0.0)
        w = -w;
    float wm = dot(w, m);
    if (!(wm > 0.0) || !(w.z > 0.0))
        return 0.0;
    return wm * tb_ggx_D(a, m) / ((1.0 + tb_ggx_lambda(a, w)) * w.z);
}

// The GGX (Schlick) lobe for unit local wo, wi (tb__evaluate's TB_BSDF_GGX):
// x = the scalar D G2 / (4 |cos_o cos_i|), y = Schlick's m^5 (the lobe's
// value per channel is (F0 (1 - y) + y) x), z = the sampling density.
vec3 tb_ggx_eval(float a, vec3 wo, vec3 wi)
{
    float co = wo.z, ci = wi.z;
    if (co == 0.0 || ci == 0.0 || (co > 0.0) != (ci > 0.0))
        return vec3(0.0);
    if (co < 0.0) { // two-sided: the upper side
        wo = -wo;
        wi = -wi;
        co = -co;
        ci = -ci;
    }
    vec3 h = wo + wi;
    float len = length(h);
    if (!(len > 0.0))
        return vec3(0.0);
    h /= len;
    float oh = dot(wo, h);
    float D = tb_ggx_D(a, h);
    float G = 1.0 / (1.0 + tb_ggx_lambda(a, wo) + tb_ggx_lambda(a, wi));
    float m = 1.0 - min(1.0, abs(oh)), m2 = m * m;
    float pdf = oh > 0.0 ? tb_ggx_vndf_pdf(a, wo, h) / (4.0 * oh) : 0.0;
    return vec3(D * G / (4.0 * co * ci), m2 * m2 * m, pdf);
}

#endif
