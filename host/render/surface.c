/* Surface records, composite BSDFs and light sets (surface.h,
 * docs/rendering.md "Surfaces, BSDFs and lights"). */
#include "host/render/surface.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "host/object/intersect.h"
#include "host/object/param.h"
#include "host/render/emit_surface.h"
#include "host/render/raytrace_internal.h"
#include "host/render/sampling.h"
#include "util/color/bands.h"
#include "util/math/float.h"
#include "util/stats/stats.h"

/* Surface records made: the shading cost term of testbed predict (docs/predict.md). */
TB_STAT_COUNTER(tb__surface_hits, "Surface/hits shaded");

/* texture.h's TB_TEX_EWA (raytrace_texture.c checks the value against the enum). */
#define TB__SF_TEX_EWA 3

/* The textured colours of a material, in the order of the texture table. */
enum { TB__SF_SLOT_DIFFUSE, TB__SF_SLOT_SPECULAR, TB__SF_SLOT_TRANSMISSION, TB__SF_SLOT_EMISSION, TB__SF_NSLOTS };

struct tb_surfaces {
    const tb_scene *scene;     /* not owned */
    tb__rt_textures *textures; /* NULL when no material has a texture */
    tb__rt_patterns *patterns; /* NULL when no material has a pattern or bump map */
    int texture_filter;        /* tb_tex_filter in effect */
    float diff_scale;          /* scale of the camera ray differentials, max(1/8, 1/sqrt(spp)) */
};

tb_status tb_surfaces_create(const tb_scene *s, const tb_surfaces_options *opt, tb_surfaces **out)
{
    *out = NULL;
    tb_surfaces_options o = opt ? *opt : (tb_surfaces_options){0};
    if (!s)
        return tb_error(TB_ERR_ARG, "surfaces: no scene");
    if (o.texture_filter < 0 || o.texture_filter > TB__SF_TEX_EWA)
        return tb_error(TB_ERR_ARG, "surfaces: unknown texture filter %d", o.texture_filter);
    tb_surfaces *ss = calloc(1, sizeof *ss);
    if (!ss)
        return tb_error(TB_ERR_NOMEM, "surfaces: out of memory");
    ss->scene = s;
    ss->texture_filter = o.texture_filter == 0 ? TB__SF_TEX_EWA : o.texture_filter;
    ss->diff_scale = (float)fmax(0.125, 1.0 / sqrt(o.spp > 1 ? (double)o.spp : 1.0));
    tb_status st = tb__rt_patterns_init(s, ss->texture_filter, &ss->patterns);
    const int nm = s->nmaterials;
    bool any_tex = false;
    for (int i = 0; i < nm && !st; i++) {
        const tb_material *mi = &s->materials[i];
        any_tex = any_tex || mi->diffuse_texture || mi->specular_texture || mi->transmission_texture ||
                  mi->emission_texture;
    }
    if (!st && any_tex) {
        /* Texture index slot * nmaterials + material (the TB__SF_SLOT_* order). */
        const char **paths = calloc((size_t)(TB__SF_NSLOTS * nm), sizeof *paths);
        if (!paths) {
            st = tb_error(TB_ERR_NOMEM, "surfaces: out of memory");
        } else {
            for (int i = 0; i < nm; i++) {
                const tb_material *mi = &s->materials[i];
                paths[TB__SF_SLOT_DIFFUSE * nm + i] = mi->diffuse_texture;
                paths[TB__SF_SLOT_SPECULAR * nm + i] = mi->specular_texture;
                paths[TB__SF_SLOT_TRANSMISSION * nm + i] = mi->transmission_texture;
                paths[TB__SF_SLOT_EMISSION * nm + i] = mi->emission_texture;
            }
            st = tb__rt_textures_load(TB__SF_NSLOTS * nm, paths, &ss->textures);
            free(paths);
        }
    }
    if (st) {
        tb_surfaces_free(ss);
        return st;
    }
    *out = ss;
    return TB_OK;
}

void tb_surfaces_free(tb_surfaces *ss)
{
    if (!ss)
        return;
    tb__rt_textures_free(ss->textures);
    tb__rt_patterns_free(ss->patterns);
    free(ss);
}

bool tb_surfaces_need_differentials(const tb_surfaces *ss) { return ss->textures || ss->patterns; }

const tb__rt_textures *tb__surfaces_textures(const tb_surfaces *ss) { return ss ? ss->textures : NULL; }

const tb__rt_patterns *tb__surfaces_patterns(const tb_surfaces *ss) { return ss ? ss->patterns : NULL; }

float tb__surfaces_diff_scale(const tb_surfaces *ss) { return ss->diff_scale; }

bool tb__surface_tangents(const tb_scene *s, const tb_hit *hit, tb_vec3 *dpdu, tb_vec3 *dpdv, const tb_object **leaf)
{
    const tb_object *o = s->objects[hit->object];
    while (o && o->nchildren > 0) {
        const tb_object *next = NULL;
        for (int i = 0; i < o->nchildren && !next; i++) {
            const tb_object *c = &o->children[i];
            if (hit->face >= c->face_base && hit->face < c->face_base + c->nfaces)
                next = c;
        }
        o = next;
    }
    if (!o)
        return false;
    tb_dvec3 du, dv;
    double u = fmin(fmax((double)hit->u, 0.0), 1.0), v = fmin(fmax((double)hit->v, 0.0), 1.0);
    if (tb_param_eval_world(o->kind, &o->geom, &o->to_world, (int)(hit->face - o->face_base), u, v, NULL, NULL,
                            &du, &dv)) {
        tb_clear_error();
        return false;
    }
    *dpdu = (tb_vec3){(float)du.x, (float)du.y, (float)du.z};
    *dpdv = (tb_vec3){(float)dv.x, (float)dv.y, (float)dv.z};
    if (leaf)
        *leaf = o;
    return true;
}

void tb__surface_fill(const tb_object *leaf, const tb_hit *hit, tb_vec3 p, tb_vec3 n, tb_vec3 dpdu, tb_vec3 dpdv,
                      const float *fp, const tb_vec3 dpdxy[2], tb__rt_surface *g)
{
    const tb_transform inv = tb_transform_inverse(&leaf->to_world);
    *g = (tb__rt_surface){.u = hit->u, .v = hit->v, .has_fp = fp != NULL, .p = p, .n = n, .dpdu = dpdu,
                          .dpdv = dpdv};
    if (fp)
        memcpy(g->fp, fp, sizeof g->fp);
    g->po = tb_transform_point(&inv, p);
    g->po_du = tb_transform_vector(&inv, dpdu);
    g->po_dv = tb_transform_vector(&inv, dpdv);
    if (fp) {
        g->po_dx = tb_transform_vector(&inv, dpdxy[0]);
        g->po_dy = tb_transform_vector(&inv, dpdxy[1]);
    }
}

/* Material m's `slot` pattern colour (0 diffuse, 1 specular) at g into *c, a
 * + f (b - a) per channel; *c untouched without one (or g NULL). */
static void tb__patterned(const tb_surfaces *ss, const tb_material *m, int slot, const tb__rt_surface *g,
                          tb_channels *c)
{
    double f;
    if (!g || !tb__rt_pattern_factor(ss->patterns, (int)(m - ss->scene->materials), slot, g, &f))
        return;
    const tb_material_pattern *p = slot == 0 ? m->diffuse_pattern : m->specular_pattern;
    tb_channels r = p->a;
    for (int k = 0; k < r.n; k++)
        r.v[k] = (float)((double)p->a.v[k] + f * ((double)p->b.v[k] - (double)p->a.v[k]));
    *c = r;
}

/* *c times texture `slot` of material m at (u, v) (footprint fp, NULL: point
 * sample); untouched without such a texture. */
static void tb__textured(const tb_surfaces *ss, const tb_material *m, int slot, float u, float v, const float *fp,
                         tb_channels *c)
{
    const tb_scene *s = ss->scene;
    double rgb[3];
    if (!ss->textures)
        return;
    int i = slot * s->nmaterials + (int)(m - s->materials);
    if (!tb__rt_texture_rgb(ss->textures, i, ss->texture_filter, u, v, fp, rgb))
        return;
    tb_channels t;
    if (s->spectral) {
        double bv[TB_CHANNELS_MAX];
        if (tb_bands_from_rgb_reflectance(&s->bands, rgb, bv))
            return;
        t = tb_channels_splat(s->nchannels, 0.0f);
        for (int k = 0; k < t.n; k++)
            t.v[k] = (float)bv[k];
    } else {
        t = tb_channels_rgb((float)rgb[0], (float)rgb[1], (float)rgb[2]);
    }
    *c = tb_channels_mul(*c, t);
}

bool tb_surface_at(const tb_surfaces *ss, const tb_ray *ray, const tb_hit *hit, const tb_vec3 *rd, tb_surface *sf)
{
    const tb_scene *s = ss->scene;
    const tb_material *m = tb_scene_hit_material(s, hit);
    if (!m)
        return false;
    TB_STAT_INC(tb__surface_hits);
    tb_vec3 p, perr;
    if (!tb_object_hit_point(s->objects[hit->object], ray, hit, &p, &perr)) {
        /* Fallback (should not happen): the float point with a generous bound. */
        p = tb_vec3_add(ray->o, tb_vec3_scale(ray->d, hit->t));
        tb_vec3 a = tb_vec3_abs(p);
        perr = tb_vec3_scale(tb_vec3_add(a, tb_vec3_splat(1.0f)), 1e-5f);
    }
    tb_vec3 d = tb_vec3_normalize(ray->d);
    sf->p = p;
    sf->perr = perr;
    sf->wo = tb_vec3_neg(d);
    sf->ng = hit->ng;
    sf->front = tb_vec3_dot(d, hit->ng) < 0.0f;
    sf->nv = sf->front ? hit->ng : tb_vec3_neg(hit->ng);
    sf->n = sf->nv;
    tb_spawn_ray_origins(p, perr, hit->ng, &sf->org[0], &sf->org[1]);
    sf->u = hit->u;
    sf->v = hit->v;
    sf->object = hit->object;
    sf->face = hit->face;
    sf->material = (int)(m - s->materials);
    sf->model = m->model;
    sf->exponent = m->exponent;
    sf->roughness = m->roughness;
    sf->ior = m->ior;
    sf->emits = m->emits;

    /* The pixel's footprint in (u, v) for the texture filters, and the
     * surface geometry of the patterns and bump maps. */
    float fpv[4];
    const float *fp = NULL;
    const tb_object *leaf = NULL;
    const bool patterned = ss->patterns && (m->diffuse_pattern->kind || m->specular_pattern->kind || m->bump->kind);
    sf->has_tangents = (ss->textures || patterned) && tb__surface_tangents(s, hit, &sf->dpdu, &sf->dpdv, &leaf);
    if (!sf->has_tangents)
        sf->dpdu = sf->dpdv = (tb_vec3){0, 0, 0};
    tb_vec3 dpdxy[2] = {{0, 0, 0}, {0, 0, 0}};
    if (sf->has_tangents && rd && tb__rt_footprint(p, hit->ng, sf->dpdu, sf->dpdv, rd, ss->diff_scale, fpv, dpdxy))
        fp = fpv;
    sf->has_fp = fp != NULL;
    if (fp)
        memcpy(sf->fp, fp, sizeof sf->fp);
    else
        memset(sf->fp, 0, sizeof sf->fp);
    tb__rt_surface surf, *g = NULL;
    if (patterned && sf->has_tangents) {
        tb__surface_fill(leaf, hit, p, sf->nv, sf->dpdu, sf->dpdv, fp, dpdxy, &surf);
        g = &surf;
        tb_vec3 nb;
        if (m->bump->kind && tb__rt_bump(ss->patterns, m, sf->material, g, &nb))
            sf->n = nb; /* the shading normal; rays still leave by the geometric one */
    }

    /* The colours: pattern (replacing the material's), then texture (multiplying). */
    sf->emission = m->emission;
    if (m->emits)
        tb__textured(ss, m, TB__SF_SLOT_EMISSION, hit->u, hit->v, fp, &sf->emission);
    sf->diffuse = m->diffuse;
    tb__patterned(ss, m, 0, g, &sf->diffuse);
    tb__textured(ss, m, TB__SF_SLOT_DIFFUSE, hit->u, hit->v, fp, &sf->diffuse);
    if (m->model == TB_MID_MODEL_LAMBERT) {
        sf->specular = tb_channels_splat(s->nchannels, 0.0f);
    } else {
        sf->specular = m->specular;
        tb__patterned(ss, m, 1, g, &sf->specular);
        tb__textured(ss, m, TB__SF_SLOT_SPECULAR, hit->u, hit->v, fp, &sf->specular);
    }
    sf->transmission = m->transmission;
    tb__textured(ss, m, TB__SF_SLOT_TRANSMISSION, hit->u, hit->v, fp, &sf->transmission);
    return true;
}

tb_ray tb_surface_spawn(const tb_surface *sf, tb_vec3 w)
{
    tb_ray r;
    r.o = tb_spawn_ray_origin(sf->p, sf->perr, sf->ng, w);
    r.d = w;
    r.tmin = 0.0f;
    r.tmax = INFINITY;
    return r;
}

tb_channels tb_surface_emitted(const tb_surface *sf)
{
    if (!sf->emits || !sf->front)
        return tb_channels_splat(sf->emission.n, 0.0f);
    return tb_radiance_from_exitance(sf->emission);
}

double tb_surface_phong_lobe(const tb_surface *sf, tb_vec3 wi)
{
    double c;
    const tb_vec3 n = sf->n, wo = sf->wo;
    if (sf->model == TB_MID_MODEL_BLINN) {
        tb_vec3 h = tb_vec3_add(wo, wi);
        float len = tb_vec3_length(h);
        if (!(len > 0.0f))
            return 0.0;
        c = (double)tb_vec3_dot(n, h) / len;
        return c > 0.0 ? tb_bsdf_lobe_norm(TB_BSDF_BLINN_NORMALIZED_EXACT, sf->exponent) * pow(c, sf->exponent) : 0.0;
    }
    if (sf->model != TB_MID_MODEL_PHONG)
        return 0.0;
    c = tb_vec3_dot(tb_reflect(wo, n), wi);
    return c > 0.0 ? tb_bsdf_lobe_norm(TB_BSDF_PHONG_NORMALIZED, sf->exponent) * pow(c, sf->exponent) : 0.0;
}

/* ---------------------------------------------------------------- BSDF */

/* Lobe slots of tb_surface_bsdf.pick. */
enum { TB__SF_DIFFUSE, TB__SF_GLOSSY, TB__SF_MIRROR, TB__SF_DIELECTRIC };

/* Mean of the channels, at least 0 (a lobe's selection weight). */
static double tb__weight(const tb_channels *c)
{
    double s = 0.0;
    for (int k = 0; k < c->n; k++)
        s += c->v[k] > 0.0f ? (double)c->v[k] : 0.0;
    return c->n > 0 ? s / c->n : 0.0;
}

void tb_surface_bsdf_init(const tb_surface *sf, tb_surface_mode mode, tb_surface_bsdf *b)
{
    memset(b, 0, sizeof *b);
    b->frame = tb_frame_from_normal(sf->n);
    b->nv = sf->nv;
    b->ng = sf->ng;
    b->diffuse = sf->diffuse;
    b->mirror = tb_channels_splat(sf->diffuse.n, 0.0f);
    b->transmission = sf->transmission;
    b->ior = sf->ior;
    double w[4] = {0, 0, 0, 0};
    if (!tb_channels_is_black(sf->diffuse)) {
        b->lobes |= TB_LOBE_DIFFUSE;
        w[TB__SF_DIFFUSE] = tb__weight(&sf->diffuse);
    }
    const bool transmits = !tb_channels_is_black(sf->transmission);
    /* A transmitting material is a smooth dielectric: its specular colour
     * only stands for the dielectric's highlight in the ray tracer (as a
     * lobe of its own it would make glass return more than it receives, and
     * light trapped by total internal reflection grow without bound). */
    if (!transmits && !tb_channels_is_black(sf->specular)) {
        double ks = tb__weight(&sf->specular);
        if (sf->model == TB_MID_MODEL_GGX) {
            b->lobes |= TB_LOBE_GLOSSY;
            b->glossy = tb_bsdf_ggx(sf->specular, sf->roughness, TB_FRESNEL_SCHLICK, 1.0);
            w[TB__SF_GLOSSY] = ks;
        } else if (mode == TB_SURFACE_WHITTED) {
            b->lobes |= TB_LOBE_MIRROR;
            b->mirror = sf->specular;
            w[TB__SF_MIRROR] = ks;
        } else {
            b->lobes |= TB_LOBE_GLOSSY;
            b->glossy = sf->model == TB_MID_MODEL_BLINN
                            ? tb_bsdf_blinn(sf->specular, sf->exponent, TB_BSDF_BLINN_NORMALIZED_EXACT)
                            : tb_bsdf_phong(sf->specular, sf->exponent, true);
            w[TB__SF_GLOSSY] = ks;
        }
    }
    if (transmits) {
        /* the dielectric takes what the diffuse part leaves, so the albedo stays <= 1 */
        float dmax = tb_channels_max(sf->diffuse);
        b->dielectric = dmax > 0.0f ? (dmax < 1.0f ? 1.0f - dmax : 0.0f) : 1.0f;
        if (b->dielectric > 0.0f) {
            b->lobes |= TB_LOBE_DIELECTRIC;
            /* the Fresnel reflection is white: weight at least half */
            w[TB__SF_DIELECTRIC] = b->dielectric * fmax(tb__weight(&sf->transmission), 0.5);
        }
    }
    double sum = w[0] + w[1] + w[2] + w[3];
    for (int k = 0; k < 4; k++)
        b->pick[k] = sum > 0.0 ? (float)(w[k] / sum) : 0.0f;
    if (!(sum > 0.0))
        b->lobes = 0;
}

/* True if wo and wi are on the same side of the geometric surface. */
static bool tb__same_side(const tb_surface_bsdf *b, tb_vec3 wo, tb_vec3 wi)
{
    return (tb_vec3_dot(wo, b->nv) > 0.0f) == (tb_vec3_dot(wi, b->nv) > 0.0f);
}

tb_channels tb_surface_bsdf_eval(const tb_surface_bsdf *b, tb_vec3 wo, tb_vec3 wi)
{
    tb_channels f = tb_channels_splat(b->diffuse.n, 0.0f);
    if (!(b->lobes & (TB_LOBE_DIFFUSE | TB_LOBE_GLOSSY)) || !tb__same_side(b, wo, wi))
        return f;
    const tb_vec3 lo = tb_frame_to_local(&b->frame, wo), li = tb_frame_to_local(&b->frame, wi);
    if (b->lobes & TB_LOBE_DIFFUSE) {
        tb_bsdf d = tb_bsdf_lambert(b->diffuse);
        f = tb_bsdf_eval(&d, lo, li);
    }
    if (b->lobes & TB_LOBE_GLOSSY)
        f = tb_channels_add(f, tb_bsdf_eval(&b->glossy, lo, li));
    return f;
}

double tb_surface_bsdf_pdf(const tb_surface_bsdf *b, tb_vec3 wo, tb_vec3 wi)
{
    if (!(b->lobes & (TB_LOBE_DIFFUSE | TB_LOBE_GLOSSY)) || !tb__same_side(b, wo, wi))
        return 0.0;
    const tb_vec3 lo = tb_frame_to_local(&b->frame, wo), li = tb_frame_to_local(&b->frame, wi);
    double pdf = 0.0;
    if (b->lobes & TB_LOBE_DIFFUSE) {
        tb_bsdf d = tb_bsdf_lambert(b->diffuse);
        pdf += b->pick[TB__SF_DIFFUSE] * tb_bsdf_pdf(&d, lo, li);
    }
    if (b->lobes & TB_LOBE_GLOSSY)
        pdf += b->pick[TB__SF_GLOSSY] * tb_bsdf_pdf(&b->glossy, lo, li);
    return pdf;
}

bool tb_surface_bsdf_sample(const tb_surface_bsdf *b, tb_vec3 wo, float uc, float u1, float u2,
                            tb_surface_sample *out)
{
    memset(out, 0, sizeof *out);
    out->weight = tb_channels_splat(b->diffuse.n, 0.0f);
    if (!b->lobes)
        return false;
    /* the lobe: the first whose cumulative probability exceeds uc */
    int k = 0;
    float lo = 0.0f;
    for (k = 0; k < 3; k++) {
        if (uc < lo + b->pick[k])
            break;
        lo += b->pick[k];
    }
    while (k > 0 && b->pick[k] <= 0.0f)
        k--; /* uc at the top end by rounding: the last lobe present */
    const float pk = b->pick[k];
    float ur = pk > 0.0f ? fminf((uc - lo) / pk, 0x1.fffffep-1f) : 0.0f; /* uc rescaled to [0, 1) */
    if (ur < 0.0f)
        ur = 0.0f;
    if (k == TB__SF_MIRROR) {
        tb_vec3 wr = tb_vec3_normalize(tb_reflect(wo, b->frame.n));
        if ((tb_vec3_dot(wr, b->nv) > 0.0f) != (tb_vec3_dot(wo, b->nv) > 0.0f))
            return false; /* a bumped normal can mirror into the surface */
        out->wi = wr;
        out->weight = tb_channels_scale(b->mirror, 1.0f / pk);
        out->pdf = pk;
        out->lobe = TB_LOBE_MIRROR;
        out->delta = true;
        return true;
    }
    if (k == TB__SF_DIELECTRIC) {
        tb_frame fr = tb_frame_from_normal(b->ng);
        tb_specular_split sp;
        tb_specular_dielectric(tb_frame_to_local(&fr, wo), b->ior, &sp);
        out->lobe = TB_LOBE_DIELECTRIC;
        out->delta = true;
        if (ur < sp.R || !sp.refracts) {
            if (!(sp.R > 0.0))
                return false;
            out->wi = tb_frame_to_world(&fr, sp.wr);
            out->pdf = pk * sp.R;
            out->weight = tb_channels_splat(b->diffuse.n, b->dielectric / pk);
            return true;
        }
        out->wi = tb_vec3_normalize(tb_frame_to_world(&fr, sp.wt));
        out->pdf = pk * sp.T;
        out->weight = tb_channels_scale(b->transmission, b->dielectric / pk);
        out->transmitted = true;
        return true;
    }
    /* a non-delta lobe: its direction, weighted by the whole mixture */
    const tb_vec3 lwo = tb_frame_to_local(&b->frame, wo);
    tb_bsdf_sampled s;
    tb_bsdf d = tb_bsdf_lambert(b->diffuse);
    if (!tb_bsdf_sample(k == TB__SF_DIFFUSE ? &d : &b->glossy, lwo, ur, u1, u2, &s))
        return false;
    tb_vec3 wi = tb_vec3_normalize(tb_frame_to_world(&b->frame, s.wi));
    if (!tb__same_side(b, wo, wi))
        return false; /* a bumped normal can send the ray into the surface: no light there */
    double pdf = tb_surface_bsdf_pdf(b, wo, wi);
    if (!(pdf > 0.0) || !isfinite(pdf))
        return false;
    tb_channels f = tb_surface_bsdf_eval(b, wo, wi);
    out->wi = wi;
    out->pdf = pdf;
    out->lobe = k == TB__SF_DIFFUSE ? TB_LOBE_DIFFUSE : TB_LOBE_GLOSSY;
    out->weight = tb_channels_scale(f, (float)(fabs((double)s.wi.z) / pdf));
    return !tb_channels_is_black(out->weight);
}

/* -------------------------------------------------------------- lights */

/* Grows the box lo..hi by the point q. */
static void tb__grow(double lo[3], double hi[3], tb_vec3 q)
{
    const double v[3] = {q.x, q.y, q.z};
    for (int k = 0; k < 3; k++) {
        lo[k] = fmin(lo[k], v[k]);
        hi[k] = fmax(hi[k], v[k]);
    }
}

/* The bounding spheres of the emitters in blocks of TB_LIGHT_SET_BLOCK
 * (a custom emitter's is infinite); nonzero when out of memory. */
static int tb__blocks_init(tb_light_set *ls)
{
    const int n = ls->area.n, nb = (n + TB_LIGHT_SET_BLOCK - 1) / TB_LIGHT_SET_BLOCK;
    ls->blocks = malloc((size_t)(nb > 0 ? nb : 1) * 4 * sizeof *ls->blocks);
    if (!ls->blocks)
        return 1;
    for (int b = 0; b < nb; b++) {
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        bool unbounded = false;
        for (int i = b * TB_LIGHT_SET_BLOCK; i < n && i < (b + 1) * TB_LIGHT_SET_BLOCK; i++) {
            const tb_emitter *e = &ls->area.emitters[i];
            switch (e->kind) {
            case TB_EMITTER_TRIANGLE:
                for (int k = 0; k < 3; k++)
                    tb__grow(lo, hi, e->v[k]);
                break;
            case TB_EMITTER_PARALLELOGRAM:
                for (int k = 0; k < 3; k++)
                    tb__grow(lo, hi, e->v[k]);
                tb__grow(lo, hi, tb_vec3_sub(tb_vec3_add(e->v[1], e->v[2]), e->v[0]));
                break;
            case TB_EMITTER_DISC:
            case TB_EMITTER_SPHERE:
                tb__grow(lo, hi, tb_vec3_sub(e->v[0], tb_vec3_splat(e->radius)));
                tb__grow(lo, hi, tb_vec3_add(e->v[0], tb_vec3_splat(e->radius)));
                break;
            default: unbounded = true; break;
            }
        }
        double *sp = &ls->blocks[4 * b];
        double d2 = 0.0;
        for (int k = 0; k < 3; k++) {
            sp[k] = 0.5 * (lo[k] + hi[k]);
            d2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
        }
        /* half the diagonal, widened for the rounding of the tests */
        sp[3] = unbounded || !isfinite(d2) ? INFINITY : 0.5 * sqrt(d2) * (1.0 + 1e-6) + 1e-9;
    }
    return 0;
}

/* False if the half-line p + t w (t > 0, w unit) certainly misses block b's sphere. */
static bool tb__block_hit(const tb_light_set *ls, int b, tb_vec3 p, tb_vec3 w)
{
    const double *sp = &ls->blocks[4 * b];
    if (isinf(sp[3]))
        return true;
    const double c[3] = {sp[0] - p.x, sp[1] - p.y, sp[2] - p.z};
    const double c2 = c[0] * c[0] + c[1] * c[1] + c[2] * c[2], r2 = sp[3] * sp[3];
    if (c2 <= r2)
        return true; /* p inside the sphere */
    const double proj = c[0] * w.x + c[1] * w.y + c[2] * w.z;
    if (proj <= 0.0)
        return false; /* the sphere is behind p */
    const double ww = (double)w.x * w.x + (double)w.y * w.y + (double)w.z * w.z;
    return c2 - proj * proj / ww <= r2;
}

tb_status tb_light_set_init(tb_light_set *ls, const tb_scene *s)
{
    memset(ls, 0, sizeof *ls);
    ls->scene = s;
    ls->nlights = s->nlights;
    if (s->nemitters > 0) {
        /* The scene outlives the light set: its emitters are read in place. */
        tb_status st = tb_area_light_init_shared(&ls->area, s->emitters, s->nemitters);
        if (st)
            return st;
        ls->has_area = true;
        ls->emissive_of = malloc((s->nobjects ? s->nobjects : 1) * sizeof *ls->emissive_of);
        if (!ls->emissive_of) {
            tb_light_set_release(ls);
            return tb_error(TB_ERR_NOMEM, "lights: out of memory");
        }
        for (uint32_t i = 0; i < s->nobjects; i++)
            ls->emissive_of[i] = -1;
        if (tb__blocks_init(ls)) {
            tb_light_set_release(ls);
            return tb_error(TB_ERR_NOMEM, "lights: out of memory");
        }
        for (int k = 0; k < s->nemissive; k++)
            if (s->emissive[k].object < s->nobjects)
                ls->emissive_of[s->emissive[k].object] = k;
    }
    return TB_OK;
}

void tb_light_set_release(tb_light_set *ls)
{
    if (!ls)
        return;
    if (ls->has_area)
        tb_area_light_release(&ls->area);
    ls->has_area = false;
    free(ls->emissive_of);
    ls->emissive_of = NULL;
    free(ls->blocks);
    ls->blocks = NULL;
}

int tb_light_set_count(const tb_light_set *ls) { return ls->nlights + (ls->has_area ? 1 : 0); }

bool tb_light_set_sample(const tb_light_set *ls, int light, tb_vec3 p, float u1, float u2, tb_light_sample *out)
{
    if (light >= 0 && light < ls->nlights)
        return tb_light_sample_li(&ls->scene->lights[light], p, out);
    if (light == ls->nlights && ls->has_area)
        return tb_area_light_sample(&ls->area, p, u1, u2, out) && out->pdf > 0.0;
    memset(out, 0, sizeof *out);
    return false;
}

/* The top-level object a shadow ray to a sample of emitter i may leave out:
 * a sphere emitter's own object when that is a plain sphere (convex: it
 * cannot block the segment from outside to a point of its visible cap);
 * UINT32_MAX otherwise. */
static uint32_t tb__self_object(const tb_light_set *ls, int i)
{
    if (!ls->has_area || i < 0 || i >= ls->area.n)
        return UINT32_MAX;
    const tb_emitter *e = &ls->area.emitters[i];
    const tb_scene *s = ls->scene;
    if (e->object >= s->nobjects)
        return UINT32_MAX;
    if (e->kind == TB_EMITTER_SPHERE)
        return s->objects[e->object]->kind == TB_PRIM_SPHERE ? e->object : UINT32_MAX;
    /* An analytic emitter over a convex primitive's surface: a point of it
     * facing p sees p on the outer side of its tangent plane, so the
     * segment cannot cross the surface (in float it could graze it at the
     * silhouette: a spurious self-shadow). */
    return tb_emitter_is_surface(e) && tb_surface_emitter_convex(e->ctx) ? e->object : UINT32_MAX;
}

/* The shadow segment from sf toward `point` along wi (dist INFINITY: the
 * ray along wi), with top-level object `skip` left out. */
static inline bool tb__occluded(const tb_light_set *ls, const tb_surface *sf, tb_vec3 wi, tb_vec3 point, float dist,
                                uint32_t skip)
{
    tb_ray r;
    r.o = sf->org[tb_spawn_front(sf->ng, wi) ? 0 : 1];
    r.tmin = 0.0f;
    if (isinf(dist)) {
        r.d = wi;
        r.tmax = INFINITY;
    } else {
        r.d = tb_vec3_sub(point, r.o);
        r.tmax = 1.0f - TB_SHADOW_EPSILON;
    }
    return tb_scene_occluded_except(ls->scene, &r, skip);
}

bool tb_light_set_occluded(const tb_light_set *ls, const tb_surface *sf, const tb_light_sample *s)
{
    return tb__occluded(ls, sf, s->wi, s->point, s->dist, s->delta ? UINT32_MAX : tb__self_object(ls, s->emitter));
}

bool tb_light_set_occluded_delta(const tb_light_set *ls, const tb_surface *sf, tb_vec3 wi, tb_vec3 point, float dist)
{
    return tb__occluded(ls, sf, wi, point, dist, UINT32_MAX);
}

/* Solid-angle density with which the area light, sampled at p, returns
 * direction w through the emitters of top-level object `object`: the sum
 * over those the line crosses (a facet seen from behind adds 0). */
static double tb__object_pdf(const tb_light_set *ls, uint32_t object, tb_vec3 p, tb_vec3 w)
{
    if (!ls->has_area || object >= ls->scene->nobjects || ls->emissive_of[object] < 0)
        return 0.0;
    const tb_scene_emissive *em = &ls->scene->emissive[ls->emissive_of[object]];
    double pdf = 0.0;
    const int end = em->first_emitter + em->nemitters;
    for (int i = em->first_emitter; i < end; i++) {
        const bool block_start = i == em->first_emitter || i % TB_LIGHT_SET_BLOCK == 0;
        if (block_start && !tb__block_hit(ls, i / TB_LIGHT_SET_BLOCK, p, w)) {
            i = (i / TB_LIGHT_SET_BLOCK + 1) * TB_LIGHT_SET_BLOCK - 1; /* the rest of the block */
            continue;
        }
        pdf += tb_area_light_pdf_line(&ls->area, i, p, w);
    }
    return pdf;
}

bool tb_light_set_visible_emitter(const tb_light_set *ls, const tb_surfaces *ss, const tb_surface *sf,
                                  const tb_light_sample *s, tb_channels *Le, double *pdf)
{
    if (!ls->has_area || s->delta || s->emitter < 0 || s->emitter >= ls->area.n)
        return false;
    const tb_scene *sc = ls->scene;
    tb_ray r;
    r.o = sf->org[tb_spawn_front(sf->ng, s->wi) ? 0 : 1];
    r.d = s->wi;
    r.tmin = 0.0f;
    r.tmax = INFINITY;
    tb_hit hit;
    if (!tb_scene_intersect(sc, &r, &hit) || hit.object != ls->area.emitters[s->emitter].object)
        return false;
    if (!(tb_vec3_dot(s->wi, hit.ng) < 0.0f))
        return false; /* its back side: emitters are one-sided */
    const tb_material *m = tb_scene_hit_material(sc, &hit);
    if (!m || !m->emits)
        return false; /* a non-emitting part of the object (a CSG leaf of another material) */
    *pdf = tb__object_pdf(ls, hit.object, sf->p, s->wi);
    if (!(*pdf > 0.0))
        return false;
    if (ss && ss->textures) {
        tb_surface e;
        if (!tb_surface_at(ss, &r, &hit, NULL, &e))
            return false;
        *Le = tb_surface_emitted(&e);
    } else {
        *Le = tb_radiance_from_exitance(m->emission);
    }
    return true;
}

double tb_light_set_pdf_dir(const tb_light_set *ls, tb_vec3 p, tb_vec3 w)
{
    double pdf = 0.0;
    for (int i = 0; ls->has_area && i < ls->area.n; i++)
        pdf += tb_area_light_pdf_line(&ls->area, i, p, w);
    return pdf;
}

double tb_light_set_emitter_pdf(const tb_light_set *ls, tb_vec3 p, const tb_surface *hit)
{
    tb_vec3 w = tb_vec3_sub(hit->p, p);
    float len = tb_vec3_length(w);
    if (!(len > 0.0f))
        return 0.0;
    return tb__object_pdf(ls, hit->object, p, tb_vec3_scale(w, 1.0f / len));
}

double tb_power_heuristic(double a, double b) { return a > 0.0 ? a * a / (a * a + b * b) : 0.0; }
