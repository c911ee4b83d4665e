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
tb_status tb_rt_init(tb_raytracer *rt, const tb_scene *scene, const tb_rt_options *opt)
{
    memset(rt, 0, sizeof *rt);
    if (!scene || !scene->accel)
        return tb_error(TB_ERR_ARG, "raytrace: the scene has no acceleration structure");
    tb_rt_options o = opt ? *opt : (tb_rt_options){0};
    if (o.light_samples < 0 || o.light_samples > TB__RT_MAX_LIGHT_SAMPLES)
        return tb_error(TB_ERR_ARG, "raytrace: light samples must be in 0..%d", TB__RT_MAX_LIGHT_SAMPLES);
    if (!(o.min_weight >= 0.0 && o.min_weight < 1.0))
        return tb_error(TB_ERR_ARG, "raytrace: the adaptive depth control's weight must be in [0, 1), not %g",
                        o.min_weight);
    if (o.glossy_samples < 0 || o.glossy_samples > TB__RT_MAX_LIGHT_SAMPLES)
        return tb_error(TB_ERR_ARG, "raytrace: glossy samples must be in 0..%d", TB__RT_MAX_LIGHT_SAMPLES);
    rt->scene = scene;
    rt->max_depth = o.max_depth == 0 ? TB_RT_DEFAULT_MAX_DEPTH : (o.max_depth < 0 ? 0 : o.max_depth);
    rt->light_samples = o.light_samples == 0 ? TB_RT_DEFAULT_LIGHT_SAMPLES : o.light_samples;
    tb_stratified_dims(rt->light_samples, &rt->lsx, &rt->lsy);
    rt->glossy_samples = o.glossy_samples == 0 ? TB_RT_DEFAULT_GLOSSY_SAMPLES : o.glossy_samples;
    tb_stratified_dims(rt->glossy_samples, &rt->gsx, &rt->gsy);
    rt->indirect = o.indirect;
    rt->min_weight = o.min_weight;
    rt->indirect_ctx = o.indirect_ctx;
    tb_status st = tb_light_set_init(&rt->lights, scene);
    if (!st)
        st = tb_surfaces_create(scene, &(tb_surfaces_options){o.texture_filter, o.spp}, &rt->surfaces);
    if (st) {
        tb_rt_release(rt);
        return tb_error_context(st, "raytrace");
    }
    rt->texture_filter = o.texture_filter == 0 ? 3 : o.texture_filter; /* tb_surfaces_create checked it */
    rt->diff_scale = tb__surfaces_diff_scale(rt->surfaces);
    rt->textures = tb__surfaces_textures(rt->surfaces);
    rt->patterns = tb__surfaces_patterns(rt->surfaces);
    return TB_OK;
}

void tb_rt_release(tb_raytracer *rt)
{
    if (!rt)
        return;
    tb_light_set_release(&rt->lights);
    tb_surfaces_free(rt->surfaces);
    rt->surfaces = NULL;
    rt->textures = NULL;
    rt->patterns = NULL;
}

/* True if the shadow segment of light sample `ls` from the surface is blocked. */
static bool tb__shadowed(const tb_raytracer *rt, const tb_surface *sf, const tb_light_sample *ls)
{
    TB_STAT_INC(tb__rt_shadow_rays);
    return tb_light_set_occluded(&rt->lights, sf, ls);
}

bool tb__rt_hit_surface(const tb_raytracer *rt, const tb_hit *hit, tb_vec3 p, tb_vec3 ng, tb_vec3 n,
                        const tb_vec3 *rd, tb__rt_surface *g)
{
    tb_vec3 dpdu, dpdv, dpdxy[2] = {{0, 0, 0}, {0, 0, 0}};
    const tb_object *leaf = NULL;
    if (!tb__surface_tangents(rt->scene, hit, &dpdu, &dpdv, &leaf))
        return false;
    float fpv[4];
    const float *fp = NULL;
    if (rd && tb__rt_footprint(p, ng, dpdu, dpdv, rd, rt->diff_scale, fpv, dpdxy))
        fp = fpv;
    tb__surface_fill(leaf, hit, p, n, dpdu, dpdv, fp, dpdxy, g);
    return true;
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

/* True if a ray of weight w is left out by the adaptive depth control. */
static inline bool tb__below_weight(const tb_raytracer *rt, double w)
{
    return rt->min_weight > 0.0 && w < rt->min_weight;
}

/* rd: the camera ray's offset rays {rx_o, rx_d, ry_o, ry_d} (NULL past the
 * first hit: reflected and refracted rays are point sampled). mis: set for a
 * glossy ray, whose emission found is weighted against light sampling. w: the
 * ray's weight (1 for a camera ray), which the adaptive depth control reads.
 * The radiance goes to *out: its count and channels 0..nchannels-1 only (the
 * rest is left as it was), so that no call zeroes and copies the 132-byte
 * value (that was a quarter of this function's time on RGB scenes); every
 * channel gets the operations of the tb_channels_* functions it replaces. */
static void tb__trace(const tb_raytracer *rt, const tb_ray *ray, const tb_vec3 *rd, tb_rng *rng, int depth,
                      const tb__mis *mis, double w, tb_channels *out)
{
    const tb_scene *s = rt->scene;
    const int nch = s->nchannels;
    float *const Lv = out->v;
    out->n = nch;
    for (int k = 0; k < nch; k++)
        Lv[k] = 0.0f;
    tb_hit hit;
    /* (u, v) only when a material reads them (textures, patterns, bump maps). */
    if (!(rt->textures || rt->patterns ? tb_scene_intersect(s, ray, &hit) : tb_scene_intersect_no_uv(s, ray, &hit)))
        return;
    /* The surface record: point, normals, the material's colours with its
     * textures (filtered over the pixel's footprint at the camera ray's hit)
     * and patterns, and the bump-mapped shading normal. */
    tb_surface sf;
    if (!tb_surface_at(rt->surfaces, ray, &hit, rd, &sf))
        return;
    const tb_vec3 p = sf.p, wo = sf.wo, ng = sf.ng, n = sf.n;
    const bool front = sf.front;

    /* Emitters are one-sided: M / pi on the front side only. */
    if (sf.emits && front) {
        double w = 1.0;
        if (mis)
            w = tb_rt_mis_weight(rt, mis);
        const tb_channels M = tb_radiance_from_exitance(sf.emission);
        for (int k = 0; k < nch; k++) /* tb_channels_add_scaled */
            Lv[k] += M.v[k] * (float)w;
    }

    const tb_channels *diffuse = &sf.diffuse, *specular = &sf.specular, *transmission = &sf.transmission;
    bool has_diffuse = !tb__black_p(diffuse);
    bool has_specular = !tb__black_p(specular);
    bool has_transmission = !tb__black_p(transmission);

    /* The GGX lobe of model ggx: Schlick Fresnel with F0 = specular. */
    const bool ggx = has_specular && sf.model == TB_MID_MODEL_GGX;
    /* Set and read only when ggx (zeroing the lobe cost more than the rest of a miss). */
    tb_bsdf lobe;
    tb_frame frame;
    tb_vec3 wo_local = {0, 0, 1};
    if (ggx) {
        lobe = tb_bsdf_ggx(*specular, sf.roughness, TB_FRESNEL_SCHLICK, 1.0);
        frame = tb_frame_from_normal(n);
        wo_local = tb_frame_to_local(&frame, wo);
    }
    /* Glossy rays are traced (below) unless the material refracts or the
     * depth is exhausted; their count enters the MIS weights. */
    const bool glossy_rays = ggx && !has_transmission && depth < rt->max_depth;
    const int nglossy = glossy_rays ? (depth == 0 ? rt->glossy_samples : 1) : 0;

    /* Point, spot and directional lights: Lambert + the model's specular lobe. */
    if ((has_diffuse || has_specular) && s->nlights > 0) {
        for (int i = 0; i < s->nlights; i++) {
            /* tb_light_sample_li's L = intensity x ks, channel by channel,
             * without building its record (its operations, bit for bit). */
            const tb_light *light = &s->lights[i];
            tb_vec3 wi;
            float dist, ks;
            if (!tb_light_delta_at(light, p, &wi, &dist, &ks))
                continue;
            float Li[TB_CHANNELS_MAX];
            const int nl = light->intensity.n;
            bool dark = true;
            for (int k = 0; k < nl; k++) {
                Li[k] = light->intensity.v[k] * ks;
                dark = dark && Li[k] == 0.0f;
            }
            if (dark)
                continue;
            for (int k = nl; k < nch; k++)
                Li[k] = light->intensity.v[k];
            float cosi = tb_vec3_dot(n, wi);
            if (cosi <= 0.0f)
                continue;
            /* f = diffuse / pi + the specular lobe, channel by channel with
             * the operations of tb_channels_scale / add / add_scaled. */
            float f[TB_CHANNELS_MAX];
            const int nf = diffuse->n;
            for (int k = 0; k < nf; k++)
                f[k] = diffuse->v[k] * (float)(1.0 / TB_PI);
            if (ggx) {
                tb_channels b = tb_bsdf_eval(&lobe, wo_local, tb_frame_to_local(&frame, wi));
                for (int k = 0; k < nf; k++)
                    f[k] += b.v[k];
            } else if (has_specular) {
                float w = (float)tb_surface_phong_lobe(&sf, wi);
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
            TB_STAT_INC(tb__rt_shadow_rays);
            if (tb_light_set_occluded_delta(&rt->lights, &sf, wi, light->position, dist))
                continue;
            /* L + (f ls.L) cosi: tb_channels_add(L, scale(mul(f, ls.L), cosi)). */
            for (int k = 0; k < nch; k++)
                Lv[k] += (k < nf ? f[k] * Li[k] : 0.0f) * cosi;
        }
    }

    /* Area lights: stratified samples over all emitters (soft shadows). The
     * Phong/Blinn specular part of area lights arrives through the mirror ray
     * instead; the GGX lobe takes both, weighted by the power heuristic
     * against its glossy rays (which weight the emission they find likewise). */
    if ((has_diffuse || ggx) && rt->lights.has_area) {
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
            if (!tb_area_light_sample_at(&rt->lights.area, &at, u[2 * k], u[2 * k + 1], &ls) || ls.pdf <= 0.0)
                continue;
            float cosi = tb_vec3_dot(n, ls.wi);
            if (cosi <= 0.0f)
                continue;
            if (tb__shadowed(rt, &sf, &ls))
                continue;
            const float we = (float)(cosi / ls.pdf);
            for (int c = 0; c < nch; c++)
                E[c] += ls.L.v[c] * we;
            if (ggx) {
                tb_vec3 wi = tb_frame_to_local(&frame, ls.wi);
                double w = tb_power_heuristic(rt->light_samples * ls.pdf, nglossy * tb_bsdf_pdf(&lobe, wo_local, wi));
                G = tb_channels_add(G, tb_channels_scale(tb_channels_mul(tb_bsdf_eval(&lobe, wo_local, wi), ls.L),
                                                         (float)(cosi / ls.pdf * w)));
            }
        }
        /* L + diffuse (E / (pi N)): tb_channels_add(L, mul(diffuse, scale(E, ...))). */
        const float es = (float)(1.0 / (TB_PI * rt->light_samples));
        const int nd = diffuse->n;
        for (int c = 0; c < nch; c++)
            Lv[c] += c < nd ? diffuse->v[c] * (E[c] * es) : 0.0f;
        if (ggx)
            for (int c = 0; c < nch; c++) /* tb_channels_add_scaled */
                Lv[c] += G.v[c] * (float)(1.0 / rt->light_samples);
    }

    /* Indirect diffuse light from outside the tracer (the hybrid renderer):
     * L + diffuse (E / pi). */
    if (has_diffuse && rt->indirect) {
        const tb_rt_indirect_query q = {hit.object, hit.face, p, sf.nv, sf.org[front ? 0 : 1],
                                        depth};
        const tb_channels E = rt->indirect(rt->indirect_ctx, &q, rng);
        const int nd = diffuse->n;
        for (int c = 0; c < nch; c++)
            Lv[c] += c < nd ? diffuse->v[c] * (E.v[c] * (float)(1.0 / TB_PI)) : 0.0f;
    }

    if (depth >= rt->max_depth)
        return;
    if (has_transmission) {
        /* Smooth dielectric: Fresnel-weighted mirror ray, and the refracted ray
         * tinted by the transmission colour (R = 1 under total internal reflection). */
        tb_frame fr = tb_frame_from_normal(ng);
        tb_specular_split sp;
        tb_specular_dielectric(tb_frame_to_local(&fr, wo), sf.ior, &sp);
        const double wr = w * sp.R, wt = w * sp.T * tb_channels_max(*transmission);
        if (sp.R > 0.0 && !tb__below_weight(rt, wr)) {
            tb_ray r = tb_surface_spawn(&sf, tb_frame_to_world(&fr, sp.wr));
            TB_STAT_INC(tb__rt_secondary_rays);
            tb_channels Lr;
            tb__trace(rt, &r, NULL, rng, depth + 1, NULL, wr, &Lr);
            for (int k = 0; k < nch; k++) /* tb_channels_add_scaled */
                Lv[k] += Lr.v[k] * (float)sp.R;
        }
        if (sp.refracts && sp.T > 0.0 && !tb__below_weight(rt, wt)) {
            tb_ray r = tb_surface_spawn(&sf, tb_vec3_normalize(tb_frame_to_world(&fr, sp.wt)));
            TB_STAT_INC(tb__rt_secondary_rays);
            tb_channels Lt;
            tb__trace(rt, &r, NULL, rng, depth + 1, NULL, wt, &Lt);
            /* add(L, scale(mul(transmission, Lt), T)): mul and scale keep
             * transmission's count, whose channels beyond it pass unchanged */
            const int nt = transmission->n;
            for (int k = 0; k < nch; k++)
                Lv[k] += k < nt ? (transmission->v[k] * Lt.v[k]) * (float)sp.T : transmission->v[k];
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
            const double wg = w * tb_channels_max(bs.weight);
            if (tb__below_weight(rt, wg))
                continue;
            tb_ray r = tb_surface_spawn(&sf, wi);
            TB_STAT_INC(tb__rt_secondary_rays);
            const tb__mis mis_g = {p, wi, bs.pdf, (double)ns, (double)rt->light_samples};
            tb_channels Lr = {0};
            tb__trace(rt, &r, NULL, rng, depth + 1, &mis_g, wg, &Lr);
            Lg = tb_channels_add(Lg, tb_channels_mul(bs.weight, Lr));
        }
        for (int k = 0; k < nch; k++) /* tb_channels_add_scaled */
            Lv[k] += Lg.v[k] * (1.0f / (float)ns);
    } else if (has_specular) {
        /* Perfect mirror weighted by the specular colour (Whitted's k_s S). */
        tb_vec3 wr = tb_vec3_normalize(tb_reflect(wo, n));
        const double wm = w * tb_channels_max(*specular);
        /* a bumped normal can mirror into the surface */
        if ((tb_vec3_dot(wr, ng) > 0.0f) == front && !tb__below_weight(rt, wm)) {
            tb_ray r = tb_surface_spawn(&sf, wr);
            TB_STAT_INC(tb__rt_secondary_rays);
            tb_channels Lr;
            tb__trace(rt, &r, NULL, rng, depth + 1, NULL, wm, &Lr);
            /* add(L, mul(specular, Lr)): specular's channels beyond its count pass unchanged */
            const int ns = specular->n;
            for (int k = 0; k < nch; k++)
                Lv[k] += k < ns ? specular->v[k] * Lr.v[k] : specular->v[k];
        }
    }
}

tb_channels tb_rt_radiance(const tb_raytracer *rt, const tb_ray *ray, tb_rng *rng)
{
    tb_channels L = {0}; /* the channels past the count stay 0 */
    tb__trace(rt, ray, NULL, rng, 0, NULL, 1.0, &L);
    return L;
}

tb_channels tb_rt_radiance_at(const tb_raytracer *rt, const tb_ray *ray, tb_rng *rng, int depth,
                              const tb_rt_mis *mis)
{
    tb_channels L = {0};
    tb__trace(rt, ray, NULL, rng, depth, mis, 1.0, &L);
    return L;
}

double tb_rt_mis_weight(const tb_raytracer *rt, const tb_rt_mis *mis)
{
    if (!rt->lights.has_area)
        return 1.0;
    return tb_power_heuristic(mis->nb * mis->pdf, mis->nl * tb_light_set_pdf_dir(&rt->lights, mis->p, mis->w));
}

void tb_rt_sample(void *ctx, double x, double y, tb_rng *rng, float *out)
{
    const tb_raytracer *rt = ctx;
    const tb_camera *cam = &rt->scene->camera;
    float lu, lv;
    tb_camera_lens_numbers(cam, rng, &lu, &lv);
    TB_STAT_INC(tb__rt_camera_rays);
    tb_channels L; /* channels 0..nchannels-1 written, the only ones read */
    if (rt->textures || rt->patterns) {
        tb_camera_ray_diff cd;
        tb_camera_ray_differential(cam, x, y, lu, lv, &cd);
        const tb_vec3 rd[4] = {cd.rx_o, cd.rx_d, cd.ry_o, cd.ry_d};
        tb__trace(rt, &cd.ray, rd, rng, 0, NULL, 1.0, &L);
    } else {
        tb_ray r = tb_camera_ray(cam, x, y, lu, lv);
        tb__trace(rt, &r, NULL, rng, 0, NULL, 1.0, &L);
    }
    for (int i = 0; i < rt->scene->nchannels; i++)
        out[i] = L.v[i];
}
