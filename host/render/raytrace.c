/* The Whitted ray tracer (raytrace.h, docs/raytrace.md). */
#include "host/render/raytrace.h"
#include "host/render/raytrace_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "host/object/hit.h"
#include "host/object/intersect.h"
#include "host/object/param.h"
#include "host/render/sampling.h"
#include "host/render/shading.h"
#include "util/color/bands.h"
#include "util/math/float.h"
#include "util/stats/stats.h"

TB_STAT_COUNTER(tb__rt_camera_rays, "Raytrace/camera rays");
TB_STAT_COUNTER(tb__rt_secondary_rays, "Raytrace/reflected and refracted rays");
TB_STAT_COUNTER(tb__rt_shadow_rays, "Raytrace/shadow rays");

/* The most light samples a shading point takes (a stack array holds them). */
#define TB__RT_MAX_LIGHT_SAMPLES 1024
/* texture.h's TB_TEX_EWA (that header cannot be included with scene.h: see
 * raytrace_texture.c); checked there against the enum. */
#define TB__RT_TEX_EWA 3

/* The textured colours of a material, in the order of the texture table. */
enum { TB__RT_SLOT_DIFFUSE, TB__RT_SLOT_SPECULAR, TB__RT_SLOT_TRANSMISSION, TB__RT_SLOT_EMISSION, TB__RT_NSLOTS };

tb_status tb_rt_init(tb_raytracer *rt, const tb_scene *scene, const tb_rt_options *opt)
{
    memset(rt, 0, sizeof *rt);
    if (!scene || !scene->accel)
        return tb_error(TB_ERR_ARG, "raytrace: the scene has no acceleration structure");
    tb_rt_options o = opt ? *opt : (tb_rt_options){0};
    if (o.light_samples < 0 || o.light_samples > TB__RT_MAX_LIGHT_SAMPLES)
        return tb_error(TB_ERR_ARG, "raytrace: light samples must be in 0..%d", TB__RT_MAX_LIGHT_SAMPLES);
    rt->scene = scene;
    rt->max_depth = o.max_depth == 0 ? TB_RT_DEFAULT_MAX_DEPTH : (o.max_depth < 0 ? 0 : o.max_depth);
    rt->light_samples = o.light_samples == 0 ? TB_RT_DEFAULT_LIGHT_SAMPLES : o.light_samples;
    tb_stratified_dims(rt->light_samples, &rt->lsx, &rt->lsy);
    if (scene->nemitters > 0) {
        tb_status st = tb_area_light_init(&rt->area, scene->emitters, scene->nemitters);
        if (st)
            return st;
        rt->has_area = true;
    }
    if (o.texture_filter < 0 || o.texture_filter > TB__RT_TEX_EWA)
        return tb_error(TB_ERR_ARG, "raytrace: unknown texture filter %d", o.texture_filter);
    rt->texture_filter = o.texture_filter == 0 ? TB__RT_TEX_EWA : o.texture_filter;
    rt->diff_scale = (float)fmax(0.125, 1.0 / sqrt(o.spp > 1 ? (double)o.spp : 1.0));
    if (o.glossy_samples < 0 || o.glossy_samples > TB__RT_MAX_LIGHT_SAMPLES)
        return tb_error(TB_ERR_ARG, "raytrace: glossy samples must be in 0..%d", TB__RT_MAX_LIGHT_SAMPLES);
    rt->glossy_samples = o.glossy_samples == 0 ? TB_RT_DEFAULT_GLOSSY_SAMPLES : o.glossy_samples;
    tb_stratified_dims(rt->glossy_samples, &rt->gsx, &rt->gsy);
    rt->indirect = o.indirect;
    rt->indirect_ctx = o.indirect_ctx;
    tb_status pst = tb__rt_patterns_init(scene, rt->texture_filter, &rt->patterns);
    if (pst) {
        tb_rt_release(rt);
        return pst;
    }
    const int nm = scene->nmaterials;
    bool any_tex = false;
    for (int i = 0; i < nm; i++) {
        const tb_material *mi = &scene->materials[i];
        any_tex = any_tex || mi->diffuse_texture || mi->specular_texture || mi->transmission_texture ||
                  mi->emission_texture;
    }
    if (any_tex) {
        /* Texture index slot * nmaterials + material (the TB__RT_SLOT_* order). */
        const char **paths = calloc((size_t)(TB__RT_NSLOTS * nm), sizeof *paths);
        if (!paths) {
            tb_rt_release(rt);
            return tb_error(TB_ERR_NOMEM, "raytrace: out of memory");
        }
        for (int i = 0; i < nm; i++) {
            const tb_material *mi = &scene->materials[i];
            paths[TB__RT_SLOT_DIFFUSE * nm + i] = mi->diffuse_texture;
            paths[TB__RT_SLOT_SPECULAR * nm + i] = mi->specular_texture;
            paths[TB__RT_SLOT_TRANSMISSION * nm + i] = mi->transmission_texture;
            paths[TB__RT_SLOT_EMISSION * nm + i] = mi->emission_texture;
        }
        tb_status st = tb__rt_textures_load(TB__RT_NSLOTS * nm, paths, &rt->textures);
        free(paths);
        if (st) {
            tb_rt_release(rt);
            return st;
        }
    }
    return TB_OK;
}

void tb_rt_release(tb_raytracer *rt)
{
    if (!rt)
        return;
    if (rt->has_area)
        tb_area_light_release(&rt->area);
    rt->has_area = false;
    tb__rt_textures_free(rt->textures);
    rt->textures = NULL;
    tb__rt_patterns_free(rt->patterns);
    rt->patterns = NULL;
}

/* True if the shadow segment of light sample `s` from a surface point with
 * geometric normal ng is blocked. org: the point's two spawned origins
 * (tb_spawn_ray_origins: front, back), the one on ls->wi's side is
 * tb_spawn_ray_origin's for that direction. */
static bool tb__shadowed(const tb_scene *s, const tb_vec3 org[2], tb_vec3 ng, const tb_light_sample *ls,
                         uint32_t skip)
{
    tb_ray r;
    r.o = org[tb_spawn_front(ng, ls->wi) ? 0 : 1];
    r.tmin = 0.0f;
    if (isinf(ls->dist)) {
        r.d = ls->wi;
        r.tmax = INFINITY;
    } else {
        r.d = tb_vec3_sub(ls->point, r.o);
        r.tmax = 1.0f - TB_SHADOW_EPSILON;
    }
    TB_STAT_INC(tb__rt_shadow_rays);
    return tb_scene_occluded_except(s, &r, skip);
}

/* The top-level object a shadow ray to a sample of area-light emitter i may
 * leave out: a sphere emitter's own object when that is a plain sphere
 * (convex: it cannot block the segment from outside to a point of its
 * visible cap); UINT32_MAX otherwise. */
static uint32_t tb__self_object(const tb_raytracer *rt, int i)
{
    if (i < 0 || i >= rt->area.n)
        return UINT32_MAX;
    const tb_emitter *e = &rt->area.emitters[i];
    const tb_scene *s = rt->scene;
    if (e->kind != TB_EMITTER_SPHERE || e->object >= s->nobjects || s->objects[e->object]->kind != TB_PRIM_SPHERE)
        return UINT32_MAX;
    return e->object;
}

/* A ray leaving the surface point p in unit direction w. */
static tb_ray tb__spawn(tb_vec3 p, tb_vec3 perr, tb_vec3 ng, tb_vec3 w)
{
    tb_ray r;
    r.o = tb_spawn_ray_origin(p, perr, ng, w);
    r.d = w;
    r.tmin = 0.0f;
    r.tmax = INFINITY;
    return r;
}

/* World-space tangents dp/du, dp/dv at a hit: the CSG leaf holding the hit's
 * face, evaluated at (u, v). False if there is none. */
static bool tb__hit_tangents(const tb_scene *s, const tb_hit *hit, tb_vec3 *dpdu, tb_vec3 *dpdv,
                             const tb_object **leaf)
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
    if (tb_param_eval_world(o->kind, &o->geom, &o->to_world, (int)(hit->face - o->face_base), u, v, NULL,
                            NULL, &du, &dv)) {
        tb_clear_error();
        return false;
    }
    *dpdu = (tb_vec3){(float)du.x, (float)du.y, (float)du.z};
    *dpdv = (tb_vec3){(float)dv.x, (float)dv.y, (float)dv.z};
    if (leaf)
        *leaf = o;
    return true;
}

/* The surface record of patterns and bump maps at a hit (leaf: its CSG
 * leaf; fp, dpdxy: the footprint or NULL). */
static void tb__surface_fill(const tb_object *leaf, const tb_hit *hit, tb_vec3 p, tb_vec3 n, tb_vec3 dpdu,
                             tb_vec3 dpdv, const float *fp, const tb_vec3 dpdxy[2], tb__rt_surface *g)
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

bool tb__rt_hit_surface(const tb_raytracer *rt, const tb_hit *hit, tb_vec3 p, tb_vec3 ng, tb_vec3 n,
                        const tb_vec3 *rd, tb__rt_surface *g)
{
    tb_vec3 dpdu, dpdv, dpdxy[2] = {{0, 0, 0}, {0, 0, 0}};
    const tb_object *leaf = NULL;
    if (!tb__hit_tangents(rt->scene, hit, &dpdu, &dpdv, &leaf))
        return false;
    float fpv[4];
    const float *fp = NULL;
    if (rd && tb__rt_footprint(p, ng, dpdu, dpdv, rd, rt->diff_scale, fpv, dpdxy))
        fp = fpv;
    tb__surface_fill(leaf, hit, p, n, dpdu, dpdv, fp, dpdxy, g);
    return true;
}

/* The colour of material m's `slot` pattern (0 diffuse, 1 specular) at g, or
 * `base` without one: a + f (b - a) per channel. Returns base itself, or out
 * holding the patterned colour (no 132-byte copy for the common plain case). */
static const tb_channels *tb__patterned(const tb_raytracer *rt, const tb_material *m, int slot,
                                        const tb_channels *base, const tb__rt_surface *g, tb_channels *out)
{
    double f;
    if (!g || !tb__rt_pattern_factor(rt->patterns, (int)(m - rt->scene->materials), slot, g, &f))
        return base;
    const tb_material_pattern *p = slot == 0 ? &m->diffuse_pattern : &m->specular_pattern;
    tb_channels c = p->a;
    for (int k = 0; k < c.n; k++)
        c.v[k] = (float)((double)p->a.v[k] + f * ((double)p->b.v[k] - (double)p->a.v[k]));
    *out = c;
    return out;
}

/* The specular lobe of a non-Lambert model, without the colour: f / ks of
 * Phong (normalised) or Blinn-Phong (exactly normalised) for directions wo,
 * wi (world, unit, pointing away) about the shading normal n. */
static double tb__lobe(const tb_material *m, tb_vec3 n, tb_vec3 wo, tb_vec3 wi)
{
    double c;
    if (m->model == TB_MID_MODEL_BLINN) {
        tb_vec3 h = tb_vec3_add(wo, wi);
        float len = tb_vec3_length(h);
        if (!(len > 0.0f))
            return 0.0;
        c = (double)tb_vec3_dot(n, h) / len;
        return c > 0.0 ? tb_bsdf_lobe_norm(TB_BSDF_BLINN_NORMALIZED_EXACT, m->exponent) * pow(c, m->exponent) : 0.0;
    }
    c = tb_vec3_dot(tb_reflect(wo, n), wi);
    return c > 0.0 ? tb_bsdf_lobe_norm(TB_BSDF_PHONG_NORMALIZED, m->exponent) * pow(c, m->exponent) : 0.0;
}

/* `base` times texture `slot` of material m at the hit (footprint fp, NULL:
 * point sample), or `base` if there is no such texture. Returns base itself,
 * or out holding the product (out may be base). */
static const tb_channels *tb__textured(const tb_raytracer *rt, const tb_material *m, int slot,
                                       const tb_channels *base, const tb_hit *hit, const float *fp,
                                       tb_channels *out)
{
    const tb_scene *s = rt->scene;
    double rgb[3];
    if (!rt->textures)
        return base;
    int i = slot * s->nmaterials + (int)(m - s->materials);
    if (!tb__rt_texture_rgb(rt->textures, i, rt->texture_filter, hit->u, hit->v, fp, rgb))
        return base;
    tb_channels t;
    if (s->spectral) {
        double v[TB_CHANNELS_MAX];
        if (tb_bands_from_rgb_reflectance(&s->bands, rgb, v))
            return base;
        t = tb_channels_splat(s->nchannels, 0.0f);
        for (int k = 0; k < t.n; k++)
            t.v[k] = (float)v[k];
    } else {
        t = tb_channels_rgb((float)rgb[0], (float)rgb[1], (float)rgb[2]);
    }
    *out = tb_channels_mul(*base, t);
    return out;
}

/* tb_channels_is_black(*c), without the copy. */
static inline bool tb__black_p(const tb_channels *c)
{
    for (int k = 0; k < c->n; k++)
        if (c->v[k] != 0.0f)
            return false;
    return true;
}

/* What a glossy ray needs to weight the emission it finds against the light
 * samples of the same point (multiple importance sampling, power heuristic). */
typedef tb_rt_mis tb__mis;

/* Solid-angle density with which the area light's sampler, called at p,
 * returns direction w: the sum over the emitters the line crosses. */
static double tb__area_pdf_dir(const tb_raytracer *rt, tb_vec3 p, tb_vec3 w)
{
    double pdf = 0.0;
    for (int i = 0; i < rt->area.n; i++) {
        double t;
        tb_vec3 q, nq;
        if (tb_emitter_intersect(&rt->area.emitters[i], p, w, &t, &q, &nq))
            pdf += tb_area_light_pdf(&rt->area, i, p, q, nq);
    }
    return pdf;
}

/* The power heuristic weight of a sample of density a (x its count) against
 * the other strategy's b. */
static double tb__power(double a, double b)
{
    return a > 0.0 ? a * a / (a * a + b * b) : 0.0;
}

/* rd: the camera ray's offset rays {rx_o, rx_d, ry_o, ry_d} (NULL past the
 * first hit: reflected and refracted rays are point sampled). mis: set for a
 * glossy ray, whose emission found is weighted against light sampling. */
static tb_channels tb__trace(const tb_raytracer *rt, const tb_ray *ray, const tb_vec3 *rd, tb_rng *rng,
                             int depth, const tb__mis *mis)
{
    const tb_scene *s = rt->scene;
    const int nch = s->nchannels;
    tb_channels L = tb_channels_splat(nch, 0.0f);
    tb_hit hit;
    if (!tb_scene_intersect(s, ray, &hit))
        return L;
    const tb_material *m = tb_scene_hit_material(s, &hit);
    if (!m)
        return L;
    tb_vec3 p, perr;
    if (!tb_object_hit_point(s->objects[hit.object], ray, &hit, &p, &perr)) {
        /* Fallback (should not happen): the float point with a generous bound. */
        p = tb_vec3_add(ray->o, tb_vec3_scale(ray->d, hit.t));
        tb_vec3 a = tb_vec3_abs(p);
        perr = tb_vec3_scale(tb_vec3_add(a, tb_vec3_splat(1.0f)), 1e-5f);
    }
    tb_vec3 d = tb_vec3_normalize(ray->d);
    tb_vec3 wo = tb_vec3_neg(d);
    tb_vec3 ng = hit.ng;
    bool front = tb_vec3_dot(d, ng) < 0.0f;
    tb_vec3 n = front ? ng : tb_vec3_neg(ng); /* the normal on the viewer's side */

    /* The pixel's footprint in (u, v) for the texture filters, and the
     * surface geometry of the patterns and bump maps. */
    float fpv[4];
    const float *fp = NULL;
    tb_vec3 dpdu, dpdv;
    const tb_object *leaf = NULL;
    const bool patterned = rt->patterns && (m->diffuse_pattern.kind || m->specular_pattern.kind || m->bump.kind);
    bool tangents = (rt->textures || patterned) && tb__hit_tangents(s, &hit, &dpdu, &dpdv, &leaf);
    tb_vec3 dpdxy[2] = {{0, 0, 0}, {0, 0, 0}};
    if (tangents && rd && tb__rt_footprint(p, ng, dpdu, dpdv, rd, rt->diff_scale, fpv, dpdxy))
        fp = fpv;
    tb__rt_surface surf, *g = NULL;
    if (patterned && tangents) {
        tb__surface_fill(leaf, &hit, p, n, dpdu, dpdv, fp, dpdxy, &surf);
        g = &surf;
        tb_vec3 nb;
        if (m->bump.kind && tb__rt_bump(rt->patterns, m, (int)(m - s->materials), g, &nb))
            n = nb; /* the shading normal; rays still leave by the geometric one */
    }

    /* Emitters are one-sided: M / pi on the front side only. */
    if (m->emits && front) {
        double w = 1.0;
        if (mis)
            w = tb_rt_mis_weight(rt, mis);
        tb_channels em;
        L = tb_channels_add_scaled(
            L, tb_radiance_from_exitance(*tb__textured(rt, m, TB__RT_SLOT_EMISSION, &m->emission, &hit, fp, &em)),
            (float)w);
    }

    /* The material's colours by pointer: to the material's own, or to the
     * buffers below when a pattern or texture changes them. */
    tb_channels dbuf, sbuf, tbuf;
    const tb_channels *diffuse =
        tb__textured(rt, m, TB__RT_SLOT_DIFFUSE, tb__patterned(rt, m, 0, &m->diffuse, g, &dbuf), &hit, fp, &dbuf);
    const tb_channels *specular;
    if (m->model == TB_MID_MODEL_LAMBERT) {
        sbuf = tb_channels_splat(nch, 0.0f);
        specular = &sbuf;
    } else {
        specular = tb__textured(rt, m, TB__RT_SLOT_SPECULAR, tb__patterned(rt, m, 1, &m->specular, g, &sbuf),
                                &hit, fp, &sbuf);
    }
    const tb_channels *transmission =
        tb__textured(rt, m, TB__RT_SLOT_TRANSMISSION, &m->transmission, &hit, fp, &tbuf);
    bool has_diffuse = !tb__black_p(diffuse);
    bool has_specular = !tb__black_p(specular);
    bool has_transmission = !tb__black_p(transmission);

    /* The GGX lobe of model ggx: Schlick Fresnel with F0 = specular. */
    const bool ggx = has_specular && m->model == TB_MID_MODEL_GGX;
    tb_bsdf lobe = {0};
    tb_frame frame = {0};
    tb_vec3 wo_local = {0, 0, 1};
    if (ggx) {
        lobe = tb_bsdf_ggx(*specular, m->roughness, TB_FRESNEL_SCHLICK, 1.0);
        frame = tb_frame_from_normal(n);
        wo_local = tb_frame_to_local(&frame, wo);
    }
    /* Glossy rays are traced (below) unless the material refracts or the
     * depth is exhausted; their count enters the MIS weights. */
    const bool glossy_rays = ggx && !has_transmission && depth < rt->max_depth;
    const int nglossy = glossy_rays ? (depth == 0 ? rt->glossy_samples : 1) : 0;

    /* The shadow rays' origins, on either side of the surface. */
    tb_vec3 org[2];
    tb_spawn_ray_origins(p, perr, ng, &org[0], &org[1]);

    /* Point, spot and directional lights: Lambert + the model's specular lobe. */
    if ((has_diffuse || has_specular) && s->nlights > 0) {
        for (int i = 0; i < s->nlights; i++) {
            tb_light_sample ls;
            if (!tb_light_sample_li(&s->lights[i], p, &ls))
                continue;
            float cosi = tb_vec3_dot(n, ls.wi);
            if (cosi <= 0.0f || tb__black_p(&ls.L))
                continue;
            /* f = diffuse / pi + the specular lobe, channel by channel with
             * the operations of tb_channels_scale / add / add_scaled. */
            float f[TB_CHANNELS_MAX];
            const int nf = diffuse->n;
            for (int k = 0; k < nf; k++)
                f[k] = diffuse->v[k] * (float)(1.0 / TB_PI);
            if (ggx) {
                tb_channels b = tb_bsdf_eval(&lobe, wo_local, tb_frame_to_local(&frame, ls.wi));
                for (int k = 0; k < nf; k++)
                    f[k] += b.v[k];
            } else if (has_specular) {
                float w = (float)tb__lobe(m, n, wo, ls.wi);
                for (int k = 0; k < nf; k++)
                    f[k] += specular->v[k] * w;
            }
            /* A zero BRDF adds exactly +0 (ls.L is finite), so its shadow ray
             * is not traced: mirrors and glass (no diffuse part, a lobe of
             * exponent 10^4 that is 0 in float away from the reflection). */
            bool black = true;
            for (int k = 0; k < nf; k++)
                black = black && f[k] == 0.0f;
            if (black)
                continue;
            if (tb__shadowed(s, org, ng, &ls, UINT32_MAX))
                continue;
            /* L + (f ls.L) cosi: tb_channels_add(L, scale(mul(f, ls.L), cosi)). */
            for (int k = 0; k < nch; k++)
                L.v[k] += (k < nf ? f[k] * ls.L.v[k] : 0.0f) * cosi;
        }
    }

    /* Area lights: stratified samples over all emitters (soft shadows). The
     * Phong/Blinn specular part of area lights arrives through the mirror ray
     * instead; the GGX lobe takes both, weighted by the power heuristic
     * against its glossy rays (which weight the emission they find likewise). */
    if ((has_diffuse || ggx) && rt->has_area) {
        tb_channels G = tb_channels_splat(nch, 0.0f);
        float u[2 * TB__RT_MAX_LIGHT_SAMPLES];
        tb_stratified_2d(rng, rt->lsx, rt->lsy, u);
        /* E: the sum of L cos / pdf, channel by channel as tb_channels_add_scaled. */
        float E[TB_CHANNELS_MAX];
        for (int c = 0; c < nch; c++)
            E[c] = 0.0f;
        tb_area_light_at at; /* the per-point part of the sampler, computed once for all samples */
        tb_area_light_at_init(&at, p);
        for (int k = 0; k < rt->light_samples; k++) {
            tb_light_sample ls;
            if (!tb_area_light_sample_at(&rt->area, &at, u[2 * k], u[2 * k + 1], &ls) || ls.pdf <= 0.0)
                continue;
            float cosi = tb_vec3_dot(n, ls.wi);
            if (cosi <= 0.0f)
                continue;
            if (tb__shadowed(s, org, ng, &ls, tb__self_object(rt, ls.emitter)))
                continue;
            const float we = (float)(cosi / ls.pdf);
            for (int c = 0; c < nch; c++)
                E[c] += ls.L.v[c] * we;
            if (ggx) {
                tb_vec3 wi = tb_frame_to_local(&frame, ls.wi);
                double w = tb__power(rt->light_samples * ls.pdf, nglossy * tb_bsdf_pdf(&lobe, wo_local, wi));
                G = tb_channels_add(G, tb_channels_scale(tb_channels_mul(tb_bsdf_eval(&lobe, wo_local, wi), ls.L),
                                                         (float)(cosi / ls.pdf * w)));
            }
        }
        /* L + diffuse (E / (pi N)): tb_channels_add(L, mul(diffuse, scale(E, ...))). */
        const float es = (float)(1.0 / (TB_PI * rt->light_samples));
        const int nd = diffuse->n;
        for (int c = 0; c < nch; c++)
            L.v[c] += c < nd ? diffuse->v[c] * (E[c] * es) : 0.0f;
        if (ggx)
            L = tb_channels_add_scaled(L, G, (float)(1.0 / rt->light_samples));
    }

    /* Indirect diffuse light from outside the tracer (the hybrid renderer):
     * L + diffuse (E / pi). */
    if (has_diffuse && rt->indirect) {
        const tb_rt_indirect_query q = {hit.object, hit.face, p, front ? ng : tb_vec3_neg(ng), org[front ? 0 : 1],
                                        depth};
        const tb_channels E = rt->indirect(rt->indirect_ctx, &q, rng);
        const int nd = diffuse->n;
        for (int c = 0; c < nch; c++)
            L.v[c] += c < nd ? diffuse->v[c] * (E.v[c] * (float)(1.0 / TB_PI)) : 0.0f;
    }

    if (depth >= rt->max_depth)
        return L;
    if (has_transmission) {
        /* Smooth dielectric: Fresnel-weighted mirror ray, and the refracted ray
         * tinted by the transmission colour (R = 1 under total internal reflection). */
        tb_frame fr = tb_frame_from_normal(ng);
        tb_specular_split sp;
        tb_specular_dielectric(tb_frame_to_local(&fr, wo), m->ior, &sp);
        if (sp.R > 0.0) {
            tb_ray r = tb__spawn(p, perr, ng, tb_frame_to_world(&fr, sp.wr));
            TB_STAT_INC(tb__rt_secondary_rays);
            L = tb_channels_add_scaled(L, tb__trace(rt, &r, NULL, rng, depth + 1, NULL), (float)sp.R);
        }
        if (sp.refracts && sp.T > 0.0) {
            tb_ray r = tb__spawn(p, perr, ng, tb_vec3_normalize(tb_frame_to_world(&fr, sp.wt)));
            TB_STAT_INC(tb__rt_secondary_rays);
            tb_channels Lt = tb__trace(rt, &r, NULL, rng, depth + 1, NULL);
            L = tb_channels_add(L, tb_channels_scale(tb_channels_mul(*transmission, Lt), (float)sp.T));
        }
    } else if (glossy_rays) {
        /* Glossy reflection (distributed ray tracing): rays sampled from the
         * GGX lobe's visible normals, each weighted by F G2 / G1; the split
         * into several rays is done only at the camera ray's hit. */
        int ns = nglossy, nx = depth == 0 ? rt->gsx : 1, ny = depth == 0 ? rt->gsy : 1;
        float u[2 * TB__RT_MAX_LIGHT_SAMPLES];
        tb_stratified_2d(rng, nx, ny, u);
        tb_channels Lg = tb_channels_splat(nch, 0.0f);
        for (int k = 0; k < ns; k++) {
            tb_bsdf_sampled bs;
            if (!tb_bsdf_sample(&lobe, wo_local, 0.5f, u[2 * k], u[2 * k + 1], &bs))
                continue;
            tb_vec3 wi = tb_vec3_normalize(tb_frame_to_world(&frame, bs.wi));
            if ((tb_vec3_dot(wi, ng) > 0.0f) != front)
                continue; /* a bumped normal can send the ray into the surface: no light there */
            tb_ray r = tb__spawn(p, perr, ng, wi);
            TB_STAT_INC(tb__rt_secondary_rays);
            const tb__mis mis_g = {p, wi, bs.pdf, (double)ns, (double)rt->light_samples};
            Lg = tb_channels_add(Lg, tb_channels_mul(bs.weight, tb__trace(rt, &r, NULL, rng, depth + 1, &mis_g)));
        }
        L = tb_channels_add_scaled(L, Lg, 1.0f / (float)ns);
    } else if (has_specular) {
        /* Perfect mirror weighted by the specular colour (Whitted's k_s S). */
        tb_vec3 wr = tb_vec3_normalize(tb_reflect(wo, n));
        if ((tb_vec3_dot(wr, ng) > 0.0f) == front) { /* a bumped normal can mirror into the surface */
            tb_ray r = tb__spawn(p, perr, ng, wr);
            TB_STAT_INC(tb__rt_secondary_rays);
            L = tb_channels_add(L, tb_channels_mul(*specular, tb__trace(rt, &r, NULL, rng, depth + 1, NULL)));
        }
    }
    return L;
}

tb_channels tb_rt_radiance(const tb_raytracer *rt, const tb_ray *ray, tb_rng *rng)
{
    return tb__trace(rt, ray, NULL, rng, 0, NULL);
}

tb_channels tb_rt_radiance_at(const tb_raytracer *rt, const tb_ray *ray, tb_rng *rng, int depth,
                              const tb_rt_mis *mis)
{
    return tb__trace(rt, ray, NULL, rng, depth, mis);
}

double tb_rt_mis_weight(const tb_raytracer *rt, const tb_rt_mis *mis)
{
    if (!rt->has_area)
        return 1.0;
    return tb__power(mis->nb * mis->pdf, mis->nl * tb__area_pdf_dir(rt, mis->p, mis->w));
}

void tb_rt_sample(void *ctx, double x, double y, tb_rng *rng, float *out)
{
    const tb_raytracer *rt = ctx;
    const tb_camera *cam = &rt->scene->camera;
    float lu = 0.5f, lv = 0.5f;
    if (cam->lens_radius > 0.0) {
        lu = tb_rng_float(rng);
        lv = tb_rng_float(rng);
    }
    TB_STAT_INC(tb__rt_camera_rays);
    tb_channels L;
    if (rt->textures || rt->patterns) {
        tb_camera_ray_diff cd;
        tb_camera_ray_differential(cam, x, y, lu, lv, &cd);
        const tb_vec3 rd[4] = {cd.rx_o, cd.rx_d, cd.ry_o, cd.ry_d};
        L = tb__trace(rt, &cd.ray, rd, rng, 0, NULL);
    } else {
        tb_ray r = tb_camera_ray(cam, x, y, lu, lv);
        L = tb_rt_radiance(rt, &r, rng);
    }
    for (int i = 0; i < rt->scene->nchannels; i++)
        out[i] = L.v[i];
}
