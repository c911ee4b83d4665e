/* The unidirectional path tracer (pathtrace.h, docs/pathtrace.md). */
#include "host/render/pathtrace.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "host/render/surface.h"
#include "util/stats/stats.h"

TB_STAT_COUNTER(tb__pt_paths, "Pathtrace/paths");
TB_STAT_COUNTER(tb__pt_bounces, "Pathtrace/bounces (rays after the camera ray)");
TB_STAT_COUNTER(tb__pt_shadow_rays, "Pathtrace/shadow rays");
TB_STAT_COUNTER(tb__pt_roulette, "Pathtrace/paths ended by Russian roulette");

struct tb_pathtracer {
    const tb_scene *scene; /* not owned */
    tb_pt_options opt;     /* in effect */
    tb_surfaces *surfaces; /* owned */
    tb_light_set lights;
};

tb_status tb_pt_options_resolve(const tb_pt_options *o, tb_pt_options *out)
{
    tb_pt_options po = o ? *o : (tb_pt_options){0};
    *out = po;
    if (po.max_depth < 0 || po.max_depth > TB_PT_MAX_BOUNCES)
        return tb_error(TB_ERR_ARG, "pathtrace: max depth %d not in 0..%d", po.max_depth, TB_PT_MAX_BOUNCES);
    if (po.rr_depth < 0 || po.rr_depth > TB_PT_MAX_BOUNCES)
        return tb_error(TB_ERR_ARG, "pathtrace: Russian roulette depth %d not in 0..%d", po.rr_depth,
                        TB_PT_MAX_BOUNCES);
    if (po.spp < 0)
        return tb_error(TB_ERR_ARG, "pathtrace: samples per pixel %d < 0", po.spp);
    if (po.rr_depth == 0)
        po.rr_depth = TB_PT_DEFAULT_RR_DEPTH;
    *out = po;
    return TB_OK;
}

tb_status tb_pt_create(const tb_scene *s, const tb_pt_options *o, tb_pathtracer **out)
{
    *out = NULL;
    if (!s || !s->accel)
        return tb_error(TB_ERR_ARG, "pathtrace: the scene has no acceleration structure");
    tb_pt_options po;
    tb_status rc = tb_pt_options_resolve(o, &po);
    if (rc)
        return rc;
    tb_pathtracer *pt = calloc(1, sizeof *pt);
    if (!pt)
        return tb_error(TB_ERR_NOMEM, "pathtrace: out of memory");
    pt->scene = s;
    pt->opt = po;
    tb_status st = tb_surfaces_create(s, &(tb_surfaces_options){po.texture_filter, po.spp}, &pt->surfaces);
    if (!st)
        st = tb_light_set_init(&pt->lights, s);
    if (st) {
        tb_pt_free(pt);
        return tb_error_context(st, "pathtrace");
    }
    *out = pt;
    return TB_OK;
}

void tb_pt_free(tb_pathtracer *pt)
{
    if (!pt)
        return;
    tb_surfaces_free(pt->surfaces);
    tb_light_set_release(&pt->lights);
    free(pt);
}

tb_pt_options tb_pt_get_options(const tb_pathtracer *pt) { return pt->opt; }

const tb_surfaces *tb_pt_surfaces(const tb_pathtracer *pt) { return pt->surfaces; }

const tb_light_set *tb_pt_lights(const tb_pathtracer *pt) { return &pt->lights; }

tb_pt_path tb_pt_path_start(const tb_pathtracer *pt, const tb_ray *ray)
{
    const int nc = pt->scene->nchannels;
    tb_pt_path p;
    memset(&p, 0, sizeof p);
    p.ray = *ray;
    p.beta = tb_channels_splat(nc, 1.0f);
    p.L = tb_channels_splat(nc, 0.0f);
    p.prev_delta = 1;
    TB_STAT_INC(tb__pt_paths);
    return p;
}

/* path->L += beta * f * Li * s, channel by channel. */
static void tb__gather(tb_pt_path *path, const tb_channels *f, const tb_channels *Li, double s)
{
    for (int c = 0; c < path->L.n; c++)
        path->L.v[c] += (float)((double)path->beta.v[c] * f->v[c] * Li->v[c] * s);
}

/* Next-event estimation at sf: every delta light, and one sample of the
 * area light weighted against the BSDF's sampling of the same direction. */
static void tb__next_event(const tb_pathtracer *pt, const tb_surface *sf, const tb_surface_bsdf *b, tb_pt_path *path,
                           tb_rng *rng)
{
    const tb_light_set *ls = &pt->lights;
    for (int i = 0; i < ls->nlights; i++) {
        tb_light_sample l;
        if (!tb_light_set_sample(ls, i, sf->p, 0.0f, 0.0f, &l) || tb_channels_is_black(l.L))
            continue;
        tb_channels f = tb_surface_bsdf_eval(b, sf->wo, l.wi);
        if (tb_channels_is_black(f))
            continue;
        TB_STAT_INC(tb__pt_shadow_rays);
        if (tb_light_set_occluded(ls, sf, &l))
            continue;
        tb__gather(path, &f, &l.L, fabs((double)tb_vec3_dot(l.wi, sf->n)));
    }
    if (!ls->has_area)
        return;
    const float u1 = tb_rng_float(rng), u2 = tb_rng_float(rng);
    tb_light_sample l;
    if (!tb_light_set_sample(ls, ls->nlights, sf->p, u1, u2, &l))
        return;
    tb_channels f = tb_surface_bsdf_eval(b, sf->wo, l.wi);
    if (tb_channels_is_black(f))
        return;
    /* the sample's direction must reach the exact emitter: the light a
     * BSDF-sampled ray finds there is weighted against this one */
    TB_STAT_INC(tb__pt_shadow_rays);
    tb_channels Le;
    double pl;
    if (!tb_light_set_visible_emitter(ls, pt->surfaces, sf, &l, &Le, &pl))
        return;
    const double w = tb_power_heuristic(pl, tb_surface_bsdf_pdf(b, sf->wo, l.wi));
    tb__gather(path, &f, &Le, fabs((double)tb_vec3_dot(l.wi, sf->n)) * w / pl);
}

void tb_pt_path_step(const tb_pathtracer *pt, tb_pt_path *path, const tb_vec3 *rd, tb_rng *rng)
{
    if (path->done)
        return;
    const tb_scene *s = pt->scene;
    tb_hit hit;
    tb_surface sf;
    if (!tb_scene_intersect(s, &path->ray, &hit) ||
        !tb_surface_at(pt->surfaces, &path->ray, &hit, path->depth == 0 ? rd : NULL, &sf)) {
        path->done = 1; /* no environment light: a miss ends the path */
        return;
    }
    /* Emission (one-sided), weighted against the light sample the previous
     * vertex took of the same point unless the ray left a delta lobe. */
    if (sf.emits && sf.front) {
        tb_channels Le = tb_surface_emitted(&sf);
        double w = 1.0;
        if (!path->prev_delta)
            w = tb_power_heuristic(path->prev_pdf, tb_light_set_emitter_pdf(&pt->lights, path->prev_p, &sf));
        const tb_channels one = tb_channels_splat(Le.n, 1.0f);
        tb__gather(path, &one, &Le, w);
    }
    if ((pt->opt.max_depth > 0 && path->depth >= pt->opt.max_depth) || path->depth >= TB_PT_MAX_BOUNCES) {
        path->done = 1;
        return;
    }
    tb_surface_bsdf b;
    tb_surface_bsdf_init(&sf, TB_SURFACE_PHYSICAL, &b);
    if (b.lobes & (TB_LOBE_DIFFUSE | TB_LOBE_GLOSSY))
        tb__next_event(pt, &sf, &b, path, rng);
    const float uc = tb_rng_float(rng), u1 = tb_rng_float(rng), u2 = tb_rng_float(rng);
    tb_surface_sample bs;
    if (!tb_surface_bsdf_sample(&b, sf.wo, uc, u1, u2, &bs)) {
        path->done = 1;
        return;
    }
    path->beta = tb_channels_mul(path->beta, bs.weight);
    if (!tb_channels_is_finite(path->beta) || tb_channels_is_black(path->beta)) {
        path->done = 1;
        return;
    }
    path->prev_delta = bs.delta;
    path->prev_pdf = bs.pdf;
    path->prev_p = sf.p;
    path->ray = tb_surface_spawn(&sf, bs.wi);
    path->depth++;
    TB_STAT_INC(tb__pt_bounces);
    /* Russian roulette: continue with probability q = min(1, max beta) and
     * divide by it (unbiased: the expected weight is unchanged). */
    if (path->depth >= pt->opt.rr_depth) {
        const double q = fmin(1.0, (double)tb_channels_max(path->beta));
        if (q < 1.0) {
            if (!((double)tb_rng_float(rng) < q)) {
                TB_STAT_INC(tb__pt_roulette);
                path->done = 1;
                return;
            }
            path->beta = tb_channels_scale(path->beta, (float)(1.0 / q));
        }
    }
}

/* The radiance of one path from `ray` (rd: its offset rays, or NULL). */
static tb_channels tb__radiance(const tb_pathtracer *pt, const tb_ray *ray, const tb_vec3 *rd, tb_rng *rng)
{
    tb_pt_path path = tb_pt_path_start(pt, ray);
    while (!path.done)
        tb_pt_path_step(pt, &path, rd, rng);
    return path.L;
}

tb_channels tb_pt_radiance(const tb_pathtracer *pt, const tb_ray *ray, tb_rng *rng)
{
    return tb__radiance(pt, ray, NULL, rng);
}

void tb_pt_sample(void *ctx, double x, double y, tb_rng *rng, float *out)
{
    const tb_pathtracer *pt = ctx;
    const tb_camera *cam = &pt->scene->camera;
    float lu, lv;
    tb_camera_lens_numbers(cam, rng, &lu, &lv);
    tb_channels L;
    if (tb_surfaces_need_differentials(pt->surfaces)) {
        tb_camera_ray_diff cd;
        tb_camera_ray_differential(cam, x, y, lu, lv, &cd);
        const tb_vec3 rd[4] = {cd.rx_o, cd.rx_d, cd.ry_o, cd.ry_d};
        L = tb__radiance(pt, &cd.ray, rd, rng);
    } else {
        tb_ray r = tb_camera_ray(cam, x, y, lu, lv);
        L = tb__radiance(pt, &r, NULL, rng);
    }
    for (int i = 0; i < pt->scene->nchannels; i++)
        out[i] = L.v[i];
}

tb_status tb_render_path(const tb_scene *s, const tb_pt_options *po, const tb_render_options *o, tb_image **out,
                         tb_render_stats *st)
{
    *out = NULL;
    tb_render_options ro = o ? *o : tb_render_defaults();
    tb_pt_options p = po ? *po : (tb_pt_options){0};
    if (p.spp == 0)
        p.spp = ro.aa.spp;
    tb_pathtracer *pt;
    tb_status rc = tb_pt_create(s, &p, &pt);
    if (rc)
        return rc;
    rc = tb_render(s, tb_pt_sample, pt, &ro, out, st);
    tb_pt_free(pt);
    return rc;
}

/* ----------------------------------------------------- tb_render_method */

static tb_status tb__pt_init(void *user, const tb_scene *s, const tb_render_options *o, tb_aa_sample_fn *sample,
                             void **ctx, char *desc, size_t ndesc)
{
    tb_pt_options p = user ? *(const tb_pt_options *)user : (tb_pt_options){0};
    if (p.spp == 0)
        p.spp = o->rt.spp > 0 ? o->rt.spp : o->aa.spp;
    if (p.texture_filter == 0)
        p.texture_filter = o->rt.texture_filter;
    tb_pathtracer *pt;
    tb_status st = tb_pt_create(s, &p, &pt);
    if (st)
        return st;
    snprintf(desc, ndesc, "max_depth=%d rr_depth=%d", pt->opt.max_depth, pt->opt.rr_depth);
    *sample = tb_pt_sample;
    *ctx = pt;
    return TB_OK;
}

static void tb__pt_release(void *user, void *ctx)
{
    (void)user;
    tb_pt_free(ctx);
}

tb_render_method tb_pt_method(const tb_pt_options *po)
{
    return (tb_render_method){
        .name = "path",
        .init = tb__pt_init,
        .release = tb__pt_release,
        .stats = NULL,
        .user = (void *)po,
    };
}
