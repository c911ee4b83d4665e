/* Importer: Assimp materials, lights and cameras to their MID counterparts
 * (docs/import.md, "Materials", "Lights", "Camera"). MID is strict about
 * ranges, so every value outside one is clamped here with a warning naming
 * the material or light. */
#include "host/mid/import_internal.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include <assimp/version.h>

#include "util/math/vec.h"

#define TB__PI 3.14159265358979323846

void tb__import_warn(tb__import_warner *w, const char *fmt, ...)
{
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    w->count++;
    if (w->fn)
        w->fn(w->user, msg);
}

/* ------------------------------------------------------------------ colours */

/* Clamps c[0..2] into [lo, hi] (hi <= 0: no upper bound); NaN becomes lo.
 * One warning per attribute. */
static void tb__clamp_rgb(float c[3], float lo, float hi, const char *label, const char *attr,
                          tb__import_warner *w)
{
    float in[3] = {c[0], c[1], c[2]};
    bool changed = false;
    for (int i = 0; i < 3; i++) {
        float v = c[i];
        if (!(v >= lo))
            v = lo;
        else if (hi > 0 && v > hi)
            v = hi;
        if (v != c[i] || isnan(c[i]))
            changed = true;
        c[i] = v;
    }
    if (changed)
        tb__import_warn(w, "material '%s': %s [%g %g %g] outside [%g, %s]: clamped to [%g %g %g]", label, attr,
                        in[0], in[1], in[2], lo, hi > 0 ? "1" : "inf", c[0], c[1], c[2]);
}

static float tb__clamp1(float v, float lo, float hi, const char *label, const char *attr, tb__import_warner *w)
{
    float r = !(v >= lo) ? lo : (hi > 0 && v > hi) ? hi : v;
    if (r != v || isnan(v))
        tb__import_warn(w, "material '%s': %s %g outside [%g, %s]: clamped to %g", label, attr, v, lo,
                        hi > 0 ? "1" : "inf", r);
    return r;
}

static tb_mid_color tb__rgb(const float c[3])
{
    tb_mid_color col = tb_mid_color_grey(0);
    col.rgb[0] = c[0], col.rgb[1] = c[1], col.rgb[2] = c[2];
    return col;
}

static bool tb__nonzero(const float c[3]) { return c[0] != 0 || c[1] != 0 || c[2] != 0; }

/* A colour property as RGB; false if absent. */
static bool tb__get_rgb(const struct aiMaterial *am, const char *key, unsigned type, unsigned idx, float out[3])
{
    struct aiColor4D c;
    if (aiGetMaterialColor(am, key, type, idx, &c) != aiReturn_SUCCESS)
        return false;
    out[0] = c.r, out[1] = c.g, out[2] = c.b;
    return true;
}

/* A float property; false if absent. */
static bool tb__get_float(const struct aiMaterial *am, const char *key, unsigned type, unsigned idx, float *out)
{
    ai_real v;
    unsigned n = 1;
    if (aiGetMaterialFloatArray(am, key, type, idx, &v, &n) != aiReturn_SUCCESS || n < 1)
        return false;
    *out = (float)v;
    return true;
}

/* The first texture of `type` into `out` ("" if none). */
static void tb__get_tex(const struct aiMaterial *am, enum aiTextureType type, char out[TB__IMPORT_PATH_MAX])
{
    struct aiString s;
    out[0] = '\0';
    if (aiGetMaterialTextureCount(am, type) == 0)
        return;
    if (aiGetMaterialTexture(am, type, 0, &s, NULL, NULL, NULL, NULL, NULL, NULL) != aiReturn_SUCCESS)
        return;
    size_t n = s.length < TB__IMPORT_PATH_MAX - 1 ? s.length : TB__IMPORT_PATH_MAX - 1;
    memcpy(out, s.data, n);
    out[n] = '\0';
}

/* ---------------------------------------------------------------- materials */

/* The Phong-style keys (OBJ/MTL and most other formats). */
static void tb__map_phong(const struct aiMaterial *am, const char *label, tb__import_warner *w,
                          tb__import_material *out)
{
    tb_mid_material *m = &out->mat;
    float c[3], v;
    if (tb__get_rgb(am, AI_MATKEY_COLOR_DIFFUSE, c)) {
        tb__clamp_rgb(c, 0, 1, label, "diffuse (Kd)", w);
        m->diffuse = tb__rgb(c);
        m->set |= TB_MID_SET_DIFFUSE;
    }
    if (tb__get_rgb(am, AI_MATKEY_COLOR_SPECULAR, c)) {
        float s;
        if (tb__get_float(am, AI_MATKEY_SHININESS_STRENGTH, &s))
            for (int i = 0; i < 3; i++)
                c[i] = (float)((double)c[i] * s);
        tb__clamp_rgb(c, 0, 1, label, "specular (Ks)", w);
        if (tb__nonzero(c)) {
            m->specular = tb__rgb(c);
            m->set |= TB_MID_SET_SPECULAR;
            if (tb__get_float(am, AI_MATKEY_SHININESS, &v)) {
                m->exponent = tb__clamp1(v, 0, 0, label, "exponent (Ns)", w);
                m->set |= TB_MID_SET_EXPONENT;
            }
        }
    }
    float opacity;
    if (tb__get_float(am, AI_MATKEY_OPACITY, &opacity)) {
        opacity = tb__clamp1(opacity, 0, 1, label, "opacity (d, 1 - Tr)", w);
        float tf[3] = {1, 1, 1};
        if (tb__get_rgb(am, AI_MATKEY_COLOR_TRANSPARENT, tf))
            tb__clamp_rgb(tf, 0, 1, label, "transmission filter (Tf)", w);
        for (int i = 0; i < 3; i++)
            c[i] = (float)((double)tf[i] * (1.0 - (double)opacity));
        if (tb__nonzero(c)) {
            m->transmission = tb__rgb(c);
            m->set |= TB_MID_SET_TRANSMISSION;
        }
    }
    if (tb__get_float(am, AI_MATKEY_REFRACTI, &v) && v != 1.0f) {
        if (v > 0 && isfinite(v)) {
            m->ior = v;
            m->set |= TB_MID_SET_IOR;
        } else
            tb__import_warn(w, "material '%s': ior (Ni) %g is not positive: left at 1", label, v);
    }
    if (tb__get_rgb(am, AI_MATKEY_COLOR_EMISSIVE, c)) {
        float s;
        if (tb__get_float(am, AI_MATKEY_EMISSIVE_INTENSITY, &s))
            for (int i = 0; i < 3; i++)
                c[i] = (float)((double)c[i] * s);
        tb__clamp_rgb(c, 0, 0, label, "emission (Ke)", w);
        if (tb__nonzero(c)) {
            m->emission = tb__rgb(c);
            m->set |= TB_MID_SET_EMISSION;
        }
    }
    tb__get_tex(am, aiTextureType_DIFFUSE, out->tex[TB__TEX_DIFFUSE]);
    tb__get_tex(am, aiTextureType_SPECULAR, out->tex[TB__TEX_SPECULAR]);
    tb__get_tex(am, aiTextureType_EMISSIVE, out->tex[TB__TEX_EMISSION]);
}

/* Largest Phong exponent the roughness mapping gives (roughness near 0). */
#define TB__PBR_MAX_EXPONENT 10000.0

/* glTF metallic-roughness: the split of glTF 2.0's BRDF (appendix B) into a
 * Lambertian part and a Phong lobe of the same width. */
static void tb__map_pbr(const struct aiMaterial *am, const char *label, tb__import_warner *w,
                        tb__import_material *out)
{
    tb_mid_material *m = &out->mat;
    float base[3] = {1, 1, 1}, metal = 1, rough = 1, trans = 0, c[3];
    if (!tb__get_rgb(am, AI_MATKEY_BASE_COLOR, base))
        tb__get_rgb(am, AI_MATKEY_COLOR_DIFFUSE, base);
    tb__clamp_rgb(base, 0, 1, label, "baseColorFactor", w);
    tb__get_float(am, AI_MATKEY_METALLIC_FACTOR, &metal);
    metal = tb__clamp1(metal, 0, 1, label, "metallicFactor", w);
    tb__get_float(am, AI_MATKEY_ROUGHNESS_FACTOR, &rough);
    rough = tb__clamp1(rough, 0, 1, label, "roughnessFactor", w);
    tb__get_float(am, AI_MATKEY_TRANSMISSION_FACTOR, &trans);
    trans = tb__clamp1(trans, 0, 1, label, "transmissionFactor", w);
    double dm = metal, dt = trans;

    for (int i = 0; i < 3; i++)
        c[i] = (float)(base[i] * (1.0 - dm) * (1.0 - dt));
    m->diffuse = tb__rgb(c);
    m->set |= TB_MID_SET_DIFFUSE;
    for (int i = 0; i < 3; i++)
        c[i] = (float)(0.04 * (1.0 - dm) + base[i] * dm);
    m->specular = tb__rgb(c);
    m->set |= TB_MID_SET_SPECULAR;
    /* Blinn-Phong exponent of the same width as GGX with alpha = roughness^2
     * (Walter et al. 2007): n = 2 / alpha^2 - 2. */
    double a = (double)rough * rough, a2 = a * a;
    double n = a2 <= 2.0 / (TB__PBR_MAX_EXPONENT + 2.0) ? TB__PBR_MAX_EXPONENT : 2.0 / a2 - 2.0;
    m->exponent = (float)n;
    m->set |= TB_MID_SET_EXPONENT;
    for (int i = 0; i < 3; i++)
        c[i] = (float)(base[i] * dt * (1.0 - dm));
    if (tb__nonzero(c)) {
        m->transmission = tb__rgb(c);
        m->set |= TB_MID_SET_TRANSMISSION;
    }
    m->ior = 1.5f; /* glTF's dielectric (KHR_materials_ior is not read by Assimp 5.2) */
    m->set |= TB_MID_SET_IOR;
    if (tb__get_rgb(am, AI_MATKEY_COLOR_EMISSIVE, c)) {
        float s = 1;
        tb__get_float(am, AI_MATKEY_EMISSIVE_INTENSITY, &s);
        /* emissive (times KHR_materials_emissive_strength) read as radiance: M = pi L */
        for (int i = 0; i < 3; i++)
            c[i] = (float)((double)c[i] * s * TB__PI);
        tb__clamp_rgb(c, 0, 0, label, "emission (pi * emissiveFactor)", w);
        if (tb__nonzero(c)) {
            m->emission = tb__rgb(c);
            m->set |= TB_MID_SET_EMISSION;
        }
    }
    float opacity;
    if (tb__get_float(am, AI_MATKEY_OPACITY, &opacity) && opacity < 1)
        tb__import_warn(w, "material '%s': baseColor alpha %g is not represented in MID (opaque)", label, opacity);
    int shading;
    unsigned one = 1;
    if (aiGetMaterialIntegerArray(am, AI_MATKEY_SHADING_MODEL, &shading, &one) == aiReturn_SUCCESS &&
        shading == aiShadingMode_Unlit)
        tb__import_warn(w, "material '%s': unlit (KHR_materials_unlit) mapped as a lit material", label);
    tb__get_tex(am, aiTextureType_BASE_COLOR, out->tex[TB__TEX_DIFFUSE]);
    if (!out->tex[TB__TEX_DIFFUSE][0])
        tb__get_tex(am, aiTextureType_DIFFUSE, out->tex[TB__TEX_DIFFUSE]);
    tb__get_tex(am, aiTextureType_EMISSIVE, out->tex[TB__TEX_EMISSION]);
}

void tb__import_map_material(const struct aiMaterial *am, const char *label, tb__import_warner *w,
                             tb__import_material *out)
{
    memset(out, 0, sizeof *out);
    out->mat = tb_mid_material_default();
    float unused;
    out->pbr = tb__get_float(am, AI_MATKEY_METALLIC_FACTOR, &unused);
    if (out->pbr)
        tb__map_pbr(am, label, w, out);
    else
        tb__map_phong(am, label, w, out);
}

/* ------------------------------------------------------------------- lights */

static double tb__deg(double rad) { return rad * (180.0 / TB__PI); }

bool tb__import_map_light(const struct aiLight *al, bool photometric, const char *label, tb__import_warner *w,
                          tb_mid_light *out)
{
    tb_light_kind kind;
    switch (al->mType) {
    case aiLightSource_POINT: kind = TB_LIGHT_POINT; break;
    case aiLightSource_SPOT: kind = TB_LIGHT_SPOT; break;
    case aiLightSource_DIRECTIONAL: kind = TB_LIGHT_DIRECTIONAL; break;
    default:
        tb__import_warn(w, "light '%s': %s lights have no MID counterpart: skipped", label,
                        al->mType == aiLightSource_AMBIENT ? "ambient"
                        : al->mType == aiLightSource_AREA  ? "area"
                                                           : "undefined");
        return false;
    }
    *out = tb_mid_light_default(kind);
    out->position = (tb_dvec3){al->mPosition.x, al->mPosition.y, al->mPosition.z};
    if (kind != TB_LIGHT_POINT) {
        out->direction = (tb_dvec3){al->mDirection.x, al->mDirection.y, al->mDirection.z};
        double len = tb_dvec3_length(out->direction);
        if (!(len > 0) || !isfinite(len)) {
            tb__import_warn(w, "light '%s': direction is zero or not finite: skipped", label);
            return false;
        }
    }
    if (!(isfinite(out->position.x) && isfinite(out->position.y) && isfinite(out->position.z))) {
        tb__import_warn(w, "light '%s': position is not finite: skipped", label);
        return false;
    }
    double scale = photometric ? 1.0 / TB_IMPORT_LUMENS_PER_WATT : 1.0;
    float c[3];
    const double src[3] = {al->mColorDiffuse.r, al->mColorDiffuse.g, al->mColorDiffuse.b};
    bool clamped = false;
    for (int i = 0; i < 3; i++) {
        double v = src[i] * scale;
        if (!(v >= 0) || !isfinite(v))
            v = 0, clamped = true;
        c[i] = (float)v;
    }
    if (clamped)
        tb__import_warn(w, "light '%s': negative or non-finite colour [%g %g %g]: clamped to [%g %g %g]", label,
                        src[0], src[1], src[2], c[0], c[1], c[2]);
    out->intensity = tb__rgb(c);
    if (kind == TB_LIGHT_SPOT) {
        double outer = tb__deg(al->mAngleOuterCone), inner = tb__deg(al->mAngleInnerCone);
        if (!(outer > 0) || !(outer <= 90)) {
            double o = !(outer > 0) ? 1e-3 : 90;
            tb__import_warn(w, "light '%s': outer cone angle %g degrees outside (0, 90]: set to %g", label, outer,
                            o);
            outer = o;
        }
        if (!(inner >= 0))
            inner = 0;
        if (inner > outer)
            inner = outer;
        out->cone_angle = outer;
        out->cone_delta = outer - inner;
    }
    return true;
}

/* ------------------------------------------------------------------- camera */

static tb_dvec3 tb__xform_point(const double m[16], double x, double y, double z)
{
    return (tb_dvec3){m[0] * x + m[1] * y + m[2] * z + m[3], m[4] * x + m[5] * y + m[6] * z + m[7],
                      m[8] * x + m[9] * y + m[10] * z + m[11]};
}

static tb_dvec3 tb__xform_dir(const double m[16], double x, double y, double z)
{
    return (tb_dvec3){m[0] * x + m[1] * y + m[2] * z, m[4] * x + m[5] * y + m[6] * z,
                      m[8] * x + m[9] * y + m[10] * z};
}

static bool tb__finite_d3(tb_dvec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

bool tb__import_map_camera(const struct aiCamera *ac, const double world[16], bool gltf, const char *label,
                           tb__import_warner *w, tb_mid_camera *out)
{
    if (ac->mOrthographicWidth > 0 || !(ac->mHorizontalFOV > 0)) {
        tb__import_warn(w, "camera '%s': orthographic cameras have no MID counterpart: skipped", label);
        return false;
    }
    tb_dvec3 eye, dir, up;
    if (gltf) {
        eye = tb__xform_point(world, 0, 0, 0);
        dir = tb__xform_dir(world, 0, 0, -1);
        up = tb__xform_dir(world, 0, 1, 0);
    } else {
        eye = tb__xform_point(world, ac->mPosition.x, ac->mPosition.y, ac->mPosition.z);
        dir = tb__xform_dir(world, ac->mLookAt.x, ac->mLookAt.y, ac->mLookAt.z);
        up = tb__xform_dir(world, ac->mUp.x, ac->mUp.y, ac->mUp.z);
    }
    double aspect = ac->mAspect > 0 && isfinite(ac->mAspect) ? ac->mAspect : 0, a = aspect > 0 ? aspect : 1;
    double h = ac->mHorizontalFOV, yfov;
    if (gltf && (aiGetVersionMajor() < 5 || (aiGetVersionMajor() == 5 && aiGetVersionMinor() < 3)))
        yfov = h / a; /* Assimp 5.2's glTF importer stores yfov * aspect */
    else if (gltf)
        yfov = 2 * atan(tan(h / 2) / a); /* later versions: the full horizontal angle */
    else
        yfov = 2 * atan(tan(h) / a); /* aiCamera's documented meaning: half the horizontal angle */
    double fov = tb__deg(yfov);
    tb_dvec3 look = tb_dvec3_add(eye, dir);
    double dist = tb_dvec3_length(tb_dvec3_sub(look, eye));
    tb_dvec3 cr = tb_dvec3_cross(dir, up);
    if (!tb__finite_d3(eye) || !tb__finite_d3(look) || !(dist > 0) || !isfinite(dist) ||
        !(tb_dvec3_length(cr) > 1e-9 * tb_dvec3_length(dir) * tb_dvec3_length(up))) {
        tb__import_warn(w, "camera '%s': degenerate placement (zero view direction, or up parallel to it): skipped",
                        label);
        return false;
    }
    if (!(fov > 0 && fov < 180)) {
        tb__import_warn(w, "camera '%s': vertical field of view %g degrees outside (0, 180): skipped", label, fov);
        return false;
    }
    *out = tb_mid_camera_default();
    out->eye = eye;
    out->look_at = look;
    out->up = up;
    out->fov = fov;
    out->focal_length = 0;
    out->width = 512;
    out->height = 512;
    if (aspect > 0) {
        double hgt = round(512.0 / aspect);
        out->height = hgt < 1 ? 1 : hgt > 65536 ? 65536 : (int)hgt;
    }
    out->aperture = 0;
    out->focus_distance = dist;
    return true;
}
