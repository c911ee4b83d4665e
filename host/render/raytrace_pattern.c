/* The ray tracer's procedural patterns and bump maps (MID 1.1 material
 * attributes diffuse_pattern, specular_pattern and bump; raytrace.h,
 * docs/raytrace.md). Each pattern becomes a one-channel texture of
 * host/render/texture.h whose value is the blend factor between the
 * pattern's two colours (the blend is linear, so filtering the factor is
 * filtering the colour, in any number of channels). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "host/render/raytrace_internal.h"
#include "host/render/texture.h"
#include "util/base/error.h"

/* Amplitude ratio between noise octaves. */
#define TB__RT_NOISE_OMEGA 0.5f

struct tb__rt_patterns {
    int n;                     /* materials */
    tb_texture *tex;           /* 3 per material: diffuse, specular, bump (kind CONSTANT = none) */
    bool *has;                 /* 3 per material */
    tb_texture_cache *cache;   /* bump images */
};

/* The one-channel texture of pattern `p` (a blend factor in [0, 1]; for a
 * noise bump, fBm clamped to [-1, 1]). */
static tb_status tb__pattern_texture(const tb_material_pattern *p, bool bump, int filter, tb_texture_cache *cache,
                                     tb_texture *out)
{
    const float zero = 0.0f, one = 1.0f, minus_one = -1.0f;
    switch (p->kind) {
    case TB_MID_PATTERN_CHECKER: *out = tb_texture_checker(1, &zero, &one, true); break;
    case TB_MID_PATTERN_NOISE:
        *out = tb_texture_noise(1, bump ? &minus_one : &zero, &one, TB_NOISE_FBM, p->octaves, TB__RT_NOISE_OMEGA);
        break;
    case TB_MID_PATTERN_IMAGE: {
        const tb_mipmap *mip;
        tb_image_read_options ro = {0};
        ro.encoding = TB_ENCODING_LINEAR; /* heights are data, not sRGB colours */
        tb_status st = tb_texture_cache_get(cache, NULL, p->image, &ro, &mip);
        if (st)
            return st;
        *out = tb_texture_image(mip, (tb_tex_filter)filter, TB_TEX_REPEAT);
        return TB_OK;
    }
    default: return tb_error(TB_ERR_ARG, "raytrace: unknown pattern kind %d", (int)p->kind);
    }
    out->su = p->scale; /* solid textures use su alone */
    out->sv = p->scale_v;
    out->solid = p->object_space;
    return TB_OK;
}

tb_status tb__rt_patterns_init(const tb_scene *s, int filter, tb__rt_patterns **out)
{
    *out = NULL;
    bool any = false;
    for (int i = 0; i < s->nmaterials; i++) {
        const tb_material *m = &s->materials[i];
        any = any || m->diffuse_pattern->kind || m->specular_pattern->kind || m->bump->kind;
    }
    if (!any)
        return TB_OK;
    tb__rt_patterns *P = calloc(1, sizeof *P);
    if (!P)
        return tb_error(TB_ERR_NOMEM, "raytrace: out of memory");
    P->n = s->nmaterials;
    P->tex = calloc((size_t)(3 * P->n), sizeof *P->tex);
    P->has = calloc((size_t)(3 * P->n), sizeof *P->has);
    P->cache = tb_texture_cache_create();
    if (!P->tex || !P->has || !P->cache) {
        tb__rt_patterns_free(P);
        return tb_error(TB_ERR_NOMEM, "raytrace: out of memory");
    }
    for (int i = 0; i < P->n; i++) {
        const tb_material *m = &s->materials[i];
        const tb_material_pattern *pats[3] = {m->diffuse_pattern, m->specular_pattern, m->bump};
        for (int k = 0; k < 3; k++) {
            if (pats[k]->kind == TB_MID_PATTERN_NONE)
                continue;
            tb_status st = tb__pattern_texture(pats[k], k == 2, filter, P->cache, &P->tex[3 * i + k]);
            if (st) {
                tb__rt_patterns_free(P);
                return st;
            }
            P->has[3 * i + k] = true;
        }
    }
    *out = P;
    return TB_OK;
}

void tb__rt_patterns_free(tb__rt_patterns *P)
{
    if (!P)
        return;
    tb_texture_cache_free(P->cache);
    free(P->tex);
    free(P->has);
    free(P);
}

/* The texture query of a surface: (u, v) with its footprint, and the point
 * of the texture's space (object space for solid textures). */
static tb_tex_query tb__query(const tb__rt_surface *g, bool solid)
{
    tb_tex_query q;
    memset(&q, 0, sizeof q);
    q.u = g->u;
    q.v = g->v;
    if (g->has_fp)
        q.fp = (tb_tex_footprint){g->fp[0], g->fp[1], g->fp[2], g->fp[3]};
    if (solid) {
        q.p = g->po;
        q.dpdx = g->po_dx;
        q.dpdy = g->po_dy;
    }
    return q;
}

bool tb__rt_pattern_factor(const tb__rt_patterns *P, int material, int slot, const tb__rt_surface *g, double *f)
{
    if (!P || material < 0 || material >= P->n || slot < 0 || slot > 1 || !P->has[3 * material + slot])
        return false;
    const tb_texture *t = &P->tex[3 * material + slot];
    tb_tex_query q = tb__query(g, t->solid);
    double x = tb_texture_eval1(t, &q);
    *f = x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x);
    return true;
}

bool tb__rt_bump(const tb__rt_patterns *P, const tb_material *m, int material, const tb__rt_surface *g,
                 tb_vec3 *n)
{
    if (!P || material < 0 || material >= P->n || !P->has[3 * material + 2])
        return false;
    const tb_texture *t = &P->tex[3 * material + 2];
    tb_bump_geom bg;
    memset(&bg, 0, sizeof bg);
    bg.n = g->n;
    bg.dpdu = g->dpdu;
    bg.dpdv = g->dpdv;
    /* dp/du x dp/dv must point along n: flip v's tangent on the back side */
    if (tb_vec3_dot(tb_vec3_cross(bg.dpdu, bg.dpdv), bg.n) < 0.0f)
        bg.n = tb_vec3_neg(bg.n);
    bg.u = g->u;
    bg.v = g->v;
    if (g->has_fp)
        bg.fp = (tb_tex_footprint){g->fp[0], g->fp[1], g->fp[2], g->fp[3]};
    if (t->solid) {
        bg.p = g->po;
        bg.tp_du = g->po_du;
        bg.tp_dv = g->po_dv;
        bg.dpdx = g->po_dx;
        bg.dpdy = g->po_dy;
    } else {
        bg.p = g->p;
    }
    tb_vec3 nb;
    if (!tb_bump_map(t, m->bump->height, &bg, &nb, NULL, NULL))
        return false;
    /* back to the viewer's side of the original normal */
    *n = tb_vec3_dot(nb, g->n) < 0.0f ? tb_vec3_neg(nb) : nb;
    return true;
}
