/* Shading models, Fresnel and Snell (shading.h; formulas in docs/shading.md). */
#include "host/render/shading.h"

#include <math.h>

#include "host/render/sampling.h"
#include "util/math/float.h"

/* ------------------------------------------------------------------ frames */

tb_frame tb_frame_from_normal(tb_vec3 n)
{
    tb_frame f;
    f.n = n;
    tb_vec3_basis(n, &f.s, &f.t);
    return f;
}

tb_frame tb_frame_from_normal_tangent(tb_vec3 n, tb_vec3 s)
{
    tb_dvec3 nd = tb_vec3_to_d(n), sd = tb_vec3_to_d(s);
    tb_dvec3 p = tb_dvec3_sub(sd, tb_dvec3_scale(nd, tb_dvec3_dot(sd, nd)));
    double len2 = tb_dvec3_length2(p);
    if (!(len2 > 1e-12 * tb_dvec3_length2(sd)))
        return tb_frame_from_normal(n);
    p = tb_dvec3_scale(p, 1.0 / sqrt(len2));
    tb_frame f;
    f.n = n;
    f.s = tb_dvec3_to_f(p);
    f.t = tb_dvec3_to_f(tb_dvec3_cross(nd, p));
    return f;
}

tb_vec3 tb_frame_to_local(const tb_frame *f, tb_vec3 w)
{
    return tb_vec3_make(tb_vec3_dot(w, f->s), tb_vec3_dot(w, f->t), tb_vec3_dot(w, f->n));
}

tb_vec3 tb_frame_to_world(const tb_frame *f, tb_vec3 w)
{
    tb_dvec3 r = tb_dvec3_add(tb_dvec3_add(tb_dvec3_scale(tb_vec3_to_d(f->s), w.x),
                                           tb_dvec3_scale(tb_vec3_to_d(f->t), w.y)),
                              tb_dvec3_scale(tb_vec3_to_d(f->n), w.z));
    return tb_dvec3_to_f(r);
}

/* ---------------------------------------------------- Fresnel and Snell */

double tb_fresnel_dielectric(double cos_i, double eta)
{
    if (eta == 1.0)
        return 0.0;
    cos_i = tb_clamp(cos_i, -1.0, 1.0);
    if (cos_i < 0.0) {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    double sin2_i = (1.0 - cos_i) * (1.0 + cos_i);
    double sin2_t = sin2_i / (eta * eta);
    if (sin2_t >= 1.0)
        return 1.0; /* total internal reflection */
    double cos_t = sqrt(1.0 - sin2_t);
    double r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    double r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (r_parl * r_parl + r_perp * r_perp);
}

double tb_fresnel_schlick(double cos_i, double f0)
{
    double m = 1.0 - fmin(1.0, fabs(cos_i));
    double m2 = m * m;
    return f0 + (1.0 - f0) * (m2 * m2 * m);
}

double tb_fresnel_f0(double eta)
{
    double r = (eta - 1.0) / (eta + 1.0);
    return r * r;
}

tb_vec3 tb_reflect(tb_vec3 w, tb_vec3 n)
{
    tb_dvec3 wd = tb_vec3_to_d(w), nd = tb_vec3_to_d(n);
    return tb_dvec3_to_f(tb_dvec3_sub(tb_dvec3_scale(nd, 2.0 * tb_dvec3_dot(wd, nd)), wd));
}

/* Snell in double: wi and n as doubles; false under TIR. */
static bool tb__refract_d(tb_dvec3 wi, tb_dvec3 n, double eta, tb_dvec3 *wt, double *etap)
{
    double cos_i = tb_dvec3_dot(n, wi);
    if (cos_i < 0.0) {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = tb_dvec3_neg(n);
    }
    double sin2_i = fmax(0.0, (1.0 - cos_i) * (1.0 + cos_i));
    double sin2_t = sin2_i / (eta * eta);
    if (sin2_t >= 1.0)
        return false;
    double cos_t = sqrt(1.0 - sin2_t);
    /* wt = -wi / eta + (cos_i / eta - cos_t) n: tangential part scaled by 1/eta. */
    *wt = tb_dvec3_add(tb_dvec3_scale(wi, -1.0 / eta), tb_dvec3_scale(n, cos_i / eta - cos_t));
    if (etap)
        *etap = eta;
    return true;
}

bool tb_refract(tb_vec3 wi, tb_vec3 n, double eta, tb_vec3 *wt, double *etap)
{
    tb_dvec3 t;
    if (!tb__refract_d(tb_vec3_to_d(wi), tb_vec3_to_d(n), eta, &t, etap))
        return false;
    *wt = tb_dvec3_to_f(tb_dvec3_normalize(t));
    return true;
}

void tb_specular_dielectric(tb_vec3 wo, double eta, tb_specular_split *out)
{
    out->wr = tb_vec3_make(-wo.x, -wo.y, wo.z);
    out->R = tb_fresnel_dielectric(wo.z, eta);
    out->refracts = tb_refract(wo, tb_vec3_make(0.0f, 0.0f, 1.0f), eta, &out->wt, &out->etap);
    if (!out->refracts) {
        out->R = 1.0;
        out->wt = tb_vec3_make(0.0f, 0.0f, 0.0f);
        out->etap = wo.z >= 0.0f ? eta : 1.0 / eta;
    }
    out->T = 1.0 - out->R;
}

/* ------------------------------------------------------------------- GGX */

/* GGX D on a double normal (z > 0 else 0). The denominator is written
 * (x^2 + y^2) + z^2 alpha^2, the same as z^2 (alpha^2 - 1) + 1 for a unit m
 * but without its cancellation for narrow lobes. */
static double tb__ggx_D(double alpha, tb_dvec3 m)
{
    if (!(m.z > 0.0))
        return 0.0;
    double a2 = alpha * alpha;
    double t = (m.x * m.x + m.y * m.y) + m.z * m.z * a2;
    return a2 / (TB_PI * t * t);
}

/* GGX Lambda of a double direction, from |cos theta|. */
static double tb__ggx_lambda(double alpha, tb_dvec3 w)
{
    double z2 = w.z * w.z;
    if (z2 == 0.0)
        return INFINITY;
    double x = alpha * alpha * (w.x * w.x + w.y * w.y) / z2; /* alpha^2 tan^2 theta */
    /* (sqrt(1 + x) - 1) / 2 = x / (2 (sqrt(1 + x) + 1)): no cancellation for small x. */
    return x / (2.0 * (sqrt(1.0 + x) + 1.0));
}

static double tb__alpha(double alpha)
{
    return alpha > TB_GGX_ALPHA_MIN ? alpha : TB_GGX_ALPHA_MIN;
}

double tb_ggx_D(double alpha, tb_vec3 m) { return tb__ggx_D(tb__alpha(alpha), tb_vec3_to_d(m)); }

double tb_ggx_lambda(double alpha, tb_vec3 w) { return tb__ggx_lambda(tb__alpha(alpha), tb_vec3_to_d(w)); }

double tb_ggx_G1(double alpha, tb_vec3 w) { return 1.0 / (1.0 + tb_ggx_lambda(alpha, w)); }

double tb_ggx_G2(double alpha, tb_vec3 wo, tb_vec3 wi)
{
    return 1.0 / (1.0 + tb_ggx_lambda(alpha, wo) + tb_ggx_lambda(alpha, wi));
}

/* Heitz 2018, listing 1 (isotropic alpha), in double. w is flipped to z >= 0. */
static tb_dvec3 tb__ggx_sample_vndf(double alpha, tb_dvec3 w, double u1, double u2)
{
    if (w.z < 0.0)
        w = tb_dvec3_neg(w);
    /* Stretch the view direction to the hemisphere configuration (alpha = 1). */
    tb_dvec3 vh = tb_dvec3_normalize(tb_dvec3_make(alpha * w.x, alpha * w.y, w.z));
    /* Orthonormal basis (vh is the pole; T1 horizontal). */
    double lensq = vh.x * vh.x + vh.y * vh.y;
    tb_dvec3 t1 = lensq > 0.0 ? tb_dvec3_scale(tb_dvec3_make(-vh.y, vh.x, 0.0), 1.0 / sqrt(lensq))
                              : tb_dvec3_make(1.0, 0.0, 0.0);
    tb_dvec3 t2 = tb_dvec3_cross(vh, t1);
    /* Uniform point on the disc, warped to the projected visible half disc. */
    double r = sqrt(u1), phi = TB_2PI * u2;
    double p1 = r * cos(phi), p2 = r * sin(phi);
    double s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * sqrt(fmax(0.0, 1.0 - p1 * p1)) + s * p2;
    /* Reproject onto the hemisphere and unstretch. */
    double pz = sqrt(fmax(0.0, 1.0 - p1 * p1 - p2 * p2));
    tb_dvec3 nh = tb_dvec3_add(tb_dvec3_add(tb_dvec3_scale(t1, p1), tb_dvec3_scale(t2, p2)),
                               tb_dvec3_scale(vh, pz));
    tb_dvec3 m = tb_dvec3_make(alpha * nh.x, alpha * nh.y, fmax(1e-12, nh.z));
    return tb_dvec3_normalize(m);
}

/* VNDF density of m seen from w (w flipped to z >= 0). */
static double tb__ggx_vndf_pdf(double alpha, tb_dvec3 w, tb_dvec3 m)
{
    if (w.z < 0.0)
        w = tb_dvec3_neg(w);
    double wm = tb_dvec3_dot(w, m);
    if (!(wm > 0.0) || !(w.z > 0.0))
        return 0.0;
    double g1 = 1.0 / (1.0 + tb__ggx_lambda(alpha, w));
    return g1 * wm * tb__ggx_D(alpha, m) / w.z;
}

tb_vec3 tb_ggx_sample_vndf(double alpha, tb_vec3 w, float u1, float u2)
{
    return tb_dvec3_to_f(tb__ggx_sample_vndf(tb__alpha(alpha), tb_vec3_to_d(w), u1, u2));
}

double tb_ggx_vndf_pdf(double alpha, tb_vec3 w, tb_vec3 m)
{
    return tb__ggx_vndf_pdf(tb__alpha(alpha), tb_vec3_to_d(w), tb_dvec3_normalize(tb_vec3_to_d(m)));
}

/* ------------------------------------------------------------ constructors */

tb_bsdf tb_bsdf_lambert(tb_channels reflectance)
{
    return (tb_bsdf){.kind = TB_BSDF_LAMBERT, .color = reflectance, .eta = 1.0};
}

tb_bsdf tb_bsdf_phong(tb_channels ks, double exponent, bool normalized)
{
    return (tb_bsdf){.kind = normalized ? TB_BSDF_PHONG_NORMALIZED : TB_BSDF_PHONG,
                     .color = ks, .exponent = exponent, .eta = 1.0};
}

tb_bsdf tb_bsdf_blinn(tb_channels ks, double exponent, tb_bsdf_kind kind)
{
    if (kind != TB_BSDF_BLINN_NORMALIZED && kind != TB_BSDF_BLINN_NORMALIZED_EXACT)
        kind = TB_BSDF_BLINN;
    return (tb_bsdf){.kind = kind, .color = ks, .exponent = exponent, .eta = 1.0};
}

tb_bsdf tb_bsdf_ggx(tb_channels color, double alpha, tb_fresnel_kind fresnel, double eta)
{
    return (tb_bsdf){.kind = TB_BSDF_GGX, .color = color, .alpha = alpha, .eta = eta,
                     .fresnel = fresnel};
}

tb_bsdf tb_bsdf_ggx_dielectric(tb_channels color, double alpha, double eta)
{
    return (tb_bsdf){.kind = TB_BSDF_GGX_DIELECTRIC, .color = color, .alpha = alpha, .eta = eta,
                     .fresnel = TB_FRESNEL_DIELECTRIC};
}

double tb_bsdf_lobe_norm(tb_bsdf_kind kind, double n)
{
    switch (kind) {
    case TB_BSDF_PHONG_NORMALIZED:
        return (n + 2.0) * TB_INV_2PI;
    case TB_BSDF_BLINN_NORMALIZED:
        return (n + 8.0) / (8.0 * TB_PI);
    case TB_BSDF_BLINN_NORMALIZED_EXACT:
        return (n + 2.0) * (n + 4.0) / (8.0 * TB_PI * (exp2(-0.5 * n) + n));
    default:
        return 1.0;
    }
}

/* ------------------------------------------------------------------ models */

/* Everything eval and pdf need, computed once in double. */
typedef struct tb__eval {
    double scalar;       /* f = color * scalar (GGX Schlick: f = F(color) * scalar) */
    double pdf;          /* density of the sampler */
    double schlick_cos;  /* GGX Schlick: |wo . h|; -1 when not used */
} tb__eval;

static bool tb__is_phong(tb_bsdf_kind k) { return k == TB_BSDF_PHONG || k == TB_BSDF_PHONG_NORMALIZED; }

static bool tb__is_blinn(tb_bsdf_kind k)
{
    return k == TB_BSDF_BLINN || k == TB_BSDF_BLINN_NORMALIZED || k == TB_BSDF_BLINN_NORMALIZED_EXACT;
}

/* Evaluates the scalar part of f and the pdf for (wo, wi), both unit. */
static tb__eval tb__evaluate(const tb_bsdf *b, tb_dvec3 wo, tb_dvec3 wi)
{
    tb__eval e = {0.0, 0.0, -1.0};
    double co = wo.z, ci = wi.z;
    if (co == 0.0 || ci == 0.0)
        return e;
    bool same = (co > 0.0) == (ci > 0.0);
    double n = b->exponent;

    if (b->kind == TB_BSDF_LAMBERT) {
        if (!same)
            return e;
        e.scalar = TB_INV_PI;
        e.pdf = fabs(ci) * TB_INV_PI;
        return e;
    }
    if (tb__is_phong(b->kind)) {
        if (!same)
            return e;
        /* cos alpha = R(wo) . wi with R the mirror about the tangent plane:
         * symmetric in wo and wi (reciprocity). */
        double c = fmin(1.0, -wo.x * wi.x - wo.y * wi.y + wo.z * wi.z);
        if (!(c > 0.0))
            return e;
        double p = pow(c, n);
        e.scalar = tb_bsdf_lobe_norm(b->kind, n) * p;
        e.pdf = (n + 1.0) * TB_INV_2PI * p;
        return e;
    }
    if (tb__is_blinn(b->kind)) {
        if (!same)
            return e;
        tb_dvec3 h = tb_dvec3_add(wo, wi);
        double len = tb_dvec3_length(h);
        if (!(len > 0.0))
            return e;
        h = tb_dvec3_scale(h, 1.0 / len);
        double ch = fmin(1.0, fabs(h.z));
        double p = pow(ch, n);
        e.scalar = tb_bsdf_lobe_norm(b->kind, n) * p;
        /* h sampled with (n + 1)/(2 pi) cos^n; dwh/dwi = 1 / (4 wo.h). */
        double oh = tb_dvec3_dot(wo, h);
        if (oh > 0.0)
            e.pdf = (n + 1.0) * TB_INV_2PI * p / (4.0 * oh);
        return e;
    }

    double alpha = tb__alpha(b->alpha);
    if (b->kind == TB_BSDF_GGX) {
        if (!same)
            return e;
        if (co < 0.0) { /* two-sided: work on the upper side */
            wo = tb_dvec3_neg(wo);
            wi = tb_dvec3_neg(wi);
            co = -co;
            ci = -ci;
        }
        tb_dvec3 h = tb_dvec3_add(wo, wi);
        double len = tb_dvec3_length(h);
        if (!(len > 0.0))
            return e;
        h = tb_dvec3_scale(h, 1.0 / len);
        double oh = tb_dvec3_dot(wo, h);
        double D = tb__ggx_D(alpha, h);
        double G = 1.0 / (1.0 + tb__ggx_lambda(alpha, wo) + tb__ggx_lambda(alpha, wi));
        double F = 1.0;
        if (b->fresnel == TB_FRESNEL_DIELECTRIC)
            F = tb_fresnel_dielectric(oh, b->eta);
        else if (b->fresnel == TB_FRESNEL_SCHLICK)
            e.schlick_cos = oh;
        e.scalar = F * D * G / (4.0 * co * ci);
        if (oh > 0.0)
            e.pdf = tb__ggx_vndf_pdf(alpha, wo, h) / (4.0 * oh);
        return e;
    }

    if (b->kind == TB_BSDF_GGX_DIELECTRIC) {
        double eta = b->eta;
        double etap = 1.0; /* n on wi's side / n on wo's side (1 for reflection) */
        if (!same)
            etap = co > 0.0 ? eta : 1.0 / eta;
        /* Generalised half vector (Walter et al. 2007, eq. 16), facing +z. */
        tb_dvec3 m = tb_dvec3_add(tb_dvec3_scale(wi, etap), wo);
        double len = tb_dvec3_length(m);
        if (!(len > 0.0))
            return e;
        m = tb_dvec3_scale(m, 1.0 / len);
        if (m.z < 0.0)
            m = tb_dvec3_neg(m);
        double om = tb_dvec3_dot(wo, m), im = tb_dvec3_dot(wi, m);
        /* Microfacets seen from behind by either direction contribute nothing. */
        if (om * co <= 0.0 || im * ci <= 0.0)
            return e;
        double F = tb_fresnel_dielectric(om, eta);
        double D = tb__ggx_D(alpha, m);
        double G = 1.0 / (1.0 + tb__ggx_lambda(alpha, wo) + tb__ggx_lambda(alpha, wi));
        double vpdf = tb__ggx_vndf_pdf(alpha, wo, m);
        if (same) {
            e.scalar = F * D * G / (4.0 * fabs(co * ci));
            e.pdf = F * vpdf / (4.0 * fabs(om));
        } else {
            double s = im + om / etap;
            double denom = s * s;
            if (!(denom > 0.0))
                return e;
            /* Radiance form: divided by etap^2 (radiance is compressed into
             * the smaller solid angle of the denser side). */
            e.scalar = (1.0 - F) * D * G * fabs(im * om / (denom * co * ci)) / (etap * etap);
            e.pdf = (1.0 - F) * vpdf * fabs(im) / denom;
        }
        return e;
    }
    return e;
}

/* color * scalar, or Schlick's per-channel Fresnel times scalar. */
static tb_channels tb__apply(const tb_bsdf *b, const tb__eval *e)
{
    tb_channels f = b->color;
    if (e->scalar == 0.0) {
        for (int i = 0; i < f.n; i++)
            f.v[i] = 0.0f;
        return f;
    }
    for (int i = 0; i < f.n; i++) {
        double c = b->color.v[i];
        if (e->schlick_cos >= 0.0)
            c = tb_fresnel_schlick(e->schlick_cos, c);
        f.v[i] = (float)(c * e->scalar);
    }
    return f;
}

static tb_dvec3 tb__unit(tb_vec3 v) { return tb_dvec3_normalize(tb_vec3_to_d(v)); }

tb_channels tb_bsdf_eval(const tb_bsdf *b, tb_vec3 wo, tb_vec3 wi)
{
    tb__eval e = tb__evaluate(b, tb__unit(wo), tb__unit(wi));
    return tb__apply(b, &e);
}

double tb_bsdf_pdf(const tb_bsdf *b, tb_vec3 wo, tb_vec3 wi)
{
    return tb__evaluate(b, tb__unit(wo), tb__unit(wi)).pdf;
}

/* Finishes a sample at direction wi (double): f, pdf and weight from the
 * shared evaluation, so sample and eval/pdf agree exactly. */
static bool tb__finish(const tb_bsdf *b, tb_dvec3 wo, tb_dvec3 wi, tb_bsdf_sampled *s)
{
    wi = tb_dvec3_normalize(wi);
    tb_vec3 wif = tb_dvec3_to_f(wi);
    if (wif.z == 0.0f || (wif.z > 0.0f) != (wi.z > 0.0))
        return false;
    /* f and pdf at the double direction; the float one the caller gets
     * differs by a rounding, so tb_bsdf_pdf(wo, s->wi) agrees to ~1e-7. */
    tb__eval e = tb__evaluate(b, wo, wi);
    if (!(e.pdf > 0.0) || !(e.scalar > 0.0) || !isfinite(e.pdf))
        return false;
    s->wi = wif;
    s->f = tb__apply(b, &e);
    s->pdf = e.pdf;
    s->transmitted = (wi.z > 0.0) != (wo.z > 0.0);
    s->weight = s->f;
    double k = fabs(wi.z) / e.pdf;
    for (int i = 0; i < s->weight.n; i++)
        s->weight.v[i] = (float)(s->f.v[i] * k);
    return true;
}

bool tb_bsdf_sample(const tb_bsdf *b, tb_vec3 wo_f, float uc, float u1, float u2, tb_bsdf_sampled *s)
{
    *s = (tb_bsdf_sampled){0};
    s->f = tb_channels_splat(b->color.n, 0.0f);
    s->weight = s->f;
    tb_dvec3 wo = tb__unit(wo_f);
    if (!(wo.z != 0.0) || !tb_dvec3_isfinite(wo))
        return false;
    double side = wo.z > 0.0 ? 1.0 : -1.0;
    tb_dvec3 wi;

    if (b->kind == TB_BSDF_LAMBERT) {
        wi = tb_vec3_to_d(tb_sample_cosine_hemisphere(u1, u2));
        wi.z *= side;
    } else if (tb__is_phong(b->kind)) {
        tb_vec3 r = tb_dvec3_to_f(tb_dvec3_make(-wo.x, -wo.y, wo.z));
        tb_frame fr = tb_frame_from_normal(r);
        tb_vec3 l = tb_sample_power_cosine(u1, u2, b->exponent);
        wi = tb_vec3_to_d(tb_frame_to_world(&fr, l));
    } else if (tb__is_blinn(b->kind)) {
        tb_dvec3 h = tb_vec3_to_d(tb_sample_power_cosine(u1, u2, b->exponent));
        h.z *= side;
        double oh = tb_dvec3_dot(wo, h);
        if (!(oh > 0.0))
            return false;
        wi = tb_dvec3_sub(tb_dvec3_scale(h, 2.0 * oh), wo);
    } else if (b->kind == TB_BSDF_GGX) {
        double alpha = tb__alpha(b->alpha);
        /* The sampler flips wo to -wo below the surface: flip m back the same way. */
        tb_dvec3 m = tb_dvec3_scale(tb__ggx_sample_vndf(alpha, wo, u1, u2), side);
        double om = tb_dvec3_dot(wo, m);
        wi = tb_dvec3_sub(tb_dvec3_scale(m, 2.0 * om), wo);
    } else if (b->kind == TB_BSDF_GGX_DIELECTRIC) {
        double alpha = tb__alpha(b->alpha);
        tb_dvec3 m = tb__ggx_sample_vndf(alpha, wo, u1, u2); /* m.z > 0 */
        double om = tb_dvec3_dot(wo, m);
        double F = tb_fresnel_dielectric(om, b->eta);
        if (uc < F) {
            wi = tb_dvec3_sub(tb_dvec3_scale(m, 2.0 * om), wo);
        } else if (!tb__refract_d(wo, m, b->eta, &wi, NULL)) {
            return false;
        }
        /* A reflection that ends below the surface, or a refraction that
         * ends above it, would be read back by eval/pdf as the other event
         * with another microfacet normal: refuse it (as pbrt-v4 does). */
        if ((uc < F) != ((wi.z > 0.0) == (wo.z > 0.0)))
            return false;
    } else {
        return false;
    }
    if (!tb__finish(b, wo, wi, s)) {
        *s = (tb_bsdf_sampled){0};
        s->f = tb_channels_splat(b->color.n, 0.0f);
        s->weight = s->f;
        return false;
    }
    return true;
}
