/* tb_gpu_renderer_create (render.h): the scene's materials, colours, lights,
 * emitters and image textures as the shade kernel's tables on the device,
 * the buffers of one shade dispatch, and the geometry (tb_gpu_scene). */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "host/gpu/render_internal.h"
#include "host/render/raytrace_internal.h"
#include "host/render/shading.h"
#include "host/render/texture.h"

double tb__gr_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void tb_gpu_renderer_destroy(tb_gpu_renderer *r)
{
    if (!r)
        return;
    tb_gpu_buffer_destroy(r->b_items);
    tb_gpu_buffer_destroy(r->b_lightu);
    tb_gpu_buffer_destroy(r->b_emitters);
    tb_gpu_buffer_destroy(r->b_lights);
    tb_gpu_buffer_destroy(r->b_materials);
    tb_gpu_buffer_destroy(r->b_colours);
    tb_gpu_buffer_destroy(r->b_rays);
    tb_gpu_buffer_destroy(r->b_values);
    tb_gpu_buffer_destroy(r->b_surf);
    tb_gpu_buffer_destroy(r->b_texinfo);
    tb_gpu_buffer_destroy(r->b_texels);
    tb_gpu_scene_destroy(r->gscene);
    tb_rt_release(&r->rt);
    if (r->route)
        for (int i = 0; i < r->scene->nmaterials; i++)
            free(r->route[i]);
    free(r->route);
    free(r->features);
    free(r->mflags);
    free(r->mpat);
    free(r->pat_col);
    free(r->surf);
    free(r->col);
    free(r->items);
    free(r->lightu);
    free(r->orays);
    free(r->ovals);
    free(r);
}

void tb_gpu_renderer_stats(const tb_gpu_renderer *r, tb_gpu_render_stats *out) { *out = r->st; }

/* A zero-size-safe device buffer holding `n` bytes of `data`. */
static tb_gpu_buffer *tb__upload(tb_gpu_device *dev, const void *data, size_t n)
{
    tb_gpu_buffer *b = tb_gpu_buffer_create(dev, n ? n : 16);
    if (b && n && tb_gpu_buffer_upload(b, 0, data, n)) {
        tb_gpu_buffer_destroy(b);
        return NULL;
    }
    return b;
}

/* The per-material arrays (zeroed). */
static bool tb__alloc_materials(tb_gpu_renderer *r)
{
    const size_t nm = (size_t)(r->scene->nmaterials > 0 ? r->scene->nmaterials : 1);
    r->route = calloc(nm, sizeof *r->route);
    r->features = calloc(nm, sizeof *r->features);
    r->mflags = calloc(nm, 1);
    r->mpat = calloc(nm, 1);
    r->pat_col = calloc(nm * 2, sizeof *r->pat_col);
    return r->route && r->features && r->mflags && r->mpat && r->pat_col;
}

/* The kernel's specialization and the sizes of an item's outputs. */
static void tb__plan_kernel(tb_gpu_renderer *r)
{
    const tb__gr_uses *u = &r->uses;
    r->nsamples = r->rt.lights.has_area ? r->rt.light_samples : 0;
    r->S = r->nlights + r->nsamples;
    /* GGX: a fourth word per shadow ray (Schlick's white part) and up to
     * glossy_samples glossy rays per item (at a camera ray's hit) */
    r->sw = u->ggx ? 4 : 3;
    r->nglossy = u->ggx ? r->rt.glossy_samples : 0;
    r->lu_per = r->nsamples + r->nglossy;
    /* a hit pushes at most 2 rays (dielectric) and nets +1 per level, the
     * camera ray's GGX hit nglossy */
    r->cap_stack = r->rt.max_depth + 2 + (r->nglossy > 1 ? r->nglossy - 1 : 0);
    r->pw0 = u->colour_pattern ? 2 : 0;
    r->pw = r->pw0 + (u->texture ? 6 : 0);
    r->any_surface = u->colour_pattern || u->bump || u->texture;
    tb_gpu_spec_constant spec[TB__GR_SPEC] = {
        {1, (uint32_t)r->nch},   {2, (uint32_t)r->nlights},       {3, (uint32_t)r->nsamples},
        {4, u->spot},            {5, u->phong},                   {6, u->mirror},
        {7, u->dielectric},      {8, u->emission},                {9, u->emitter_kinds},
        {10, u->ies},            {11, u->ggx},                    {12, (uint32_t)r->nglossy},
        {13, u->colour_pattern}, {14, u->bump},                   {15, u->pattern_kinds},
        {16, u->texture},        {17, (uint32_t)r->rt.texture_filter}};
    memcpy(r->spec, spec, sizeof spec);
}

/* The host copies of the kernel's tables (shared/shade.h). */
typedef struct tb__tables {
    float *col;                 /* the colour table */
    size_t ncol;
    size_t pat_at;              /* next pattern colour pair */
    size_t ies_at;              /* next IES record */
    tb_gpu_shade_material *mats;
    tb_gpu_delta_light *lts;
    tb_gpu_emitter *ems;
    uint32_t *tinfo;            /* texture records (NULL without textures) */
    float *texels;              /* their levels' texels */
    size_t ninfo, ntexels;
} tb__tables;

static void tb__tables_free(tb__tables *t)
{
    free(t->col), free(t->mats), free(t->lts), free(t->ems), free(t->tinfo), free(t->texels);
}

/* The colour table's layout: materials' 4 x nch, lights' and emitters' nch
 * each, then the pattern colours (a, b of each diffuse and specular
 * pattern), the noise permutation and the IES records (one per distinct
 * table). */
static void tb__layout_colours(tb_gpu_renderer *r, tb__tables *t)
{
    const tb_scene *s = r->scene;
    const int nm = s->nmaterials;
    const size_t nch = (size_t)r->nch;
    size_t ncol = (size_t)nm * 4 * nch + (size_t)s->nlights * nch + (size_t)s->nemitters * nch;
    t->pat_at = ncol;
    for (int i = 0; i < nm; i++)
        for (int k = 0; k < 2; k++)
            if (!r->route[i] && r->mpat[i] &&
                (k == 0 ? s->materials[i].diffuse_pattern->kind : s->materials[i].specular_pattern->kind))
                ncol += 2 * nch;
    r->perm_col = (uint32_t)ncol;
    if (r->uses.pattern_kinds & (1u << TB_GPU_PATTERN_NOISE))
        ncol += 256;
    t->ies_at = ncol;
    for (int i = 0; i < s->nlights; i++) {
        const tb_ies *q = s->lights[i].ies;
        bool seen = false;
        for (int k = 0; k < i && q && !seen; k++)
            seen = s->lights[k].ies == q;
        if (q && !seen)
            ncol += 4 + (size_t)q->nv + (size_t)q->nh + (size_t)q->nv * (size_t)q->nh;
    }
    t->ncol = ncol;
    r->light_col = (uint32_t)((size_t)nm * 4 * nch);
    r->emitter_col = r->light_col + (uint32_t)((size_t)s->nlights * nch);
}

/* The pattern records of a material the kernel shades, their colours into
 * the table. */
static void tb__fill_patterns(tb_gpu_renderer *r, tb__tables *t, int i)
{
    const tb_material *m = &r->scene->materials[i];
    const int nch = r->nch;
    const tb_material_pattern *pats[3] = {m->diffuse_pattern, m->specular_pattern, m->bump};
    for (int k = 0; k < 3; k++) {
        const tb_material_pattern *pt = pats[k];
        if (!pt->kind || (k == 1 && m->model == TB_MID_MODEL_LAMBERT))
            continue;
        tb_gpu_pattern *g = &t->mats[i].pattern[k];
        *g = (tb_gpu_pattern){.kind = pt->kind == TB_MID_PATTERN_CHECKER ? TB_GPU_PATTERN_CHECKER
                                                                         : TB_GPU_PATTERN_NOISE,
                              .su = pt->scale, .sv = pt->scale_v, .solid = pt->object_space,
                              .octaves = pt->octaves, .height = pt->height};
        if (k < 2) {
            g->col = (uint32_t)t->pat_at;
            r->pat_col[2 * i + k] = (uint32_t)t->pat_at;
            for (int c = 0; c < nch; c++) {
                t->col[t->pat_at + (size_t)c] = pt->a.v[c];
                t->col[t->pat_at + (size_t)nch + (size_t)c] = pt->b.v[c];
            }
            t->pat_at += 2 * (size_t)nch;
        }
    }
}

/* Material records, their colours and patterns, the noise permutation. */
static void tb__fill_materials(tb_gpu_renderer *r, tb__tables *t)
{
    const tb_scene *s = r->scene;
    const int nch = r->nch;
    for (int i = 0; i < s->nmaterials; i++) {
        const tb_material *m = &s->materials[i];
        tb_bsdf_kind lobe = m->model == TB_MID_MODEL_BLINN ? TB_BSDF_BLINN_NORMALIZED_EXACT : TB_BSDF_PHONG_NORMALIZED;
        t->mats[i] = (tb_gpu_shade_material){m->exponent, m->ior, (float)tb_bsdf_lobe_norm(lobe, m->exponent),
                                             r->mflags[i], (float)fmax((double)m->roughness, TB_GGX_ALPHA_MIN),
                                             0.0f, 0.0f, 0.0f, {{0}}, {0, 0, 0, 0}};
        if (!r->route[i] && r->mpat[i])
            tb__fill_patterns(r, t, i);
        const tb_channels *c4[4] = {&m->diffuse, &m->specular, &m->transmission, &m->emission};
        if (i == 0 && (r->uses.pattern_kinds & (1u << TB_GPU_PATTERN_NOISE)))
            for (int k = 0; k < 256; k++)
                t->col[r->perm_col + (size_t)k] = (float)tb_noise_permutation()[k];
        /* the specular colour of a material without a specular term is 0 */
        for (int k = 0; k < 4; k++)
            for (int c = 0; c < nch; c++)
                t->col[((size_t)i * 4 + (size_t)k) * (size_t)nch + (size_t)c] =
                    k == 1 && !(r->mflags[i] & TB_GPU_MAT_SPECULAR) ? 0.0f : c4[k]->v[c];
    }
}

/* Delta-light records, their intensities and IES tables. */
static void tb__fill_lights(tb_gpu_renderer *r, tb__tables *t)
{
    const tb_scene *s = r->scene;
    for (int i = 0; i < s->nlights; i++) {
        const tb_light *l = &s->lights[i];
        uint32_t kind = l->kind == TB_LIGHT_SPOT          ? TB_GPU_LIGHT_SPOT
                        : l->kind == TB_LIGHT_DIRECTIONAL ? TB_GPU_LIGHT_DIRECTIONAL
                                                          : TB_GPU_LIGHT_POINT;
        t->lts[i] = (tb_gpu_delta_light){.position = l->position, .kind = kind, .axis = l->axis,
                                         .cos_total = (float)l->cos_total, .xaxis = l->xaxis,
                                         .cos_falloff = (float)l->cos_falloff,
                                         .black = tb_channels_is_black(l->intensity), .ies = TB_GPU_NO_IES};
        if (l->ies && kind != TB_GPU_LIGHT_DIRECTIONAL) {
            int k = 0;
            while (k < i && s->lights[k].ies != l->ies)
                k++;
            if (k < i) {
                t->lts[i].ies = t->lts[k].ies;
            } else {
                const tb_ies *q = l->ies;
                float *rec = t->col + t->ies_at;
                t->lts[i].ies = (uint32_t)t->ies_at;
                rec[0] = (float)q->nv;
                rec[1] = (float)q->nh;
                rec[2] = (float)q->symmetry;
                rec[3] = (float)(1.0 / q->max_candela);
                for (int v = 0; v < q->nv; v++)
                    rec[4 + v] = (float)q->v_angles[v];
                for (int h = 0; h < q->nh; h++)
                    rec[4 + q->nv + h] = (float)q->h_angles[h];
                for (int c = 0; c < q->nv * q->nh; c++)
                    rec[4 + q->nv + q->nh + c] = (float)q->candela[c];
                t->ies_at += 4 + (size_t)q->nv + (size_t)q->nh + (size_t)q->nv * (size_t)q->nh;
            }
        }
        for (int c = 0; c < r->nch; c++)
            t->col[r->light_col + (size_t)i * (size_t)r->nch + (size_t)c] = l->intensity.v[c];
    }
}

tb_gpu_emitter tb__gpu_emitter_record(const tb_emitter *e, double area)
{
    tb_gpu_emitter g = {.v0 = e->v[0], .kind = (uint32_t)e->kind, .v1 = e->v[1], .radius = e->radius,
                        .v2 = e->v[2], .two_sided = e->two_sided};
    if (e->kind == TB_EMITTER_TRIANGLE || e->kind == TB_EMITTER_PARALLELOGRAM) {
        tb_dvec3 e1 = tb_dvec3_sub(tb_vec3_to_d(e->v[1]), tb_vec3_to_d(e->v[0]));
        tb_dvec3 e2 = tb_dvec3_sub(tb_vec3_to_d(e->v[2]), tb_vec3_to_d(e->v[0]));
        g.normal = tb_dvec3_to_f(tb_dvec3_normalize(tb_dvec3_cross(e1, e2)));
    }
    g.inv_area = (float)(1.0 / area);
    return g;
}

/* Emitter records and their radiances. */
static void tb__fill_emitters(tb_gpu_renderer *r, tb__tables *t)
{
    const tb_scene *s = r->scene;
    for (int i = 0; i < s->nemitters; i++) {
        const tb_emitter *e = &s->emitters[i];
        t->ems[i] = tb__gpu_emitter_record(e, r->rt.lights.has_area ? r->rt.lights.area.areas[i] : tb_emitter_area(e));
        for (int c = 0; c < r->nch; c++)
            t->col[r->emitter_col + (size_t)i * (size_t)r->nch + (size_t)c] = e->radiance.v[c];
    }
}

/* Image textures: a record per distinct image (shared/shade.h), its levels'
 * texels one after the other; the materials' texture slots. */
static bool tb__fill_textures(tb_gpu_renderer *r, tb__tables *t)
{
    const tb_scene *s = r->scene;
    const int nm = s->nmaterials;
    const tb__rt_textures *tx = r->rt.textures;
    if (r->uses.texture) {
        size_t cap_info = 0;
        for (int q = 0; q < 4 * nm; q++) {
            const tb_mipmap *m = tb__rt_texture_mip(tx, q);
            cap_info += m ? TB_GPU_TEX_HEADER + TB_GPU_TEX_PER_LEVEL * (size_t)m->nlevels : 0;
        }
        t->tinfo = malloc(cap_info * sizeof *t->tinfo);
        t->texels = malloc((r->tex_floats ? r->tex_floats : 1) * sizeof *t->texels);
        if (!t->tinfo || !t->texels)
            return false;
    }
    for (int i = 0; i < nm; i++)
        for (int k = 0; k < 4; k++) {
            tb_gpu_shade_material *mat = &t->mats[i];
            mat->tex[k] = TB_GPU_NO_TEXTURE;
            const tb_mipmap *m = r->route[i] || (k == 1 && s->materials[i].model == TB_MID_MODEL_LAMBERT)
                                     ? NULL
                                     : tb__rt_texture_mip(tx, k * nm + i);
            if (!m || !r->uses.texture)
                continue;
            /* an image already copied for another slot: its record */
            for (int q = 0; q < k * nm + i && mat->tex[k] == TB_GPU_NO_TEXTURE; q++)
                if (tb__rt_texture_mip(tx, q) == m && !r->route[q % nm] &&
                    t->mats[q % nm].tex[q / nm] != TB_GPU_NO_TEXTURE)
                    mat->tex[k] = t->mats[q % nm].tex[q / nm];
            if (mat->tex[k] != TB_GPU_NO_TEXTURE)
                continue;
            mat->tex[k] = (uint32_t)t->ninfo;
            uint32_t *rec = t->tinfo + t->ninfo;
            rec[0] = (uint32_t)m->channels, rec[1] = (uint32_t)m->nlevels;
            rec[2] = (uint32_t)m->width, rec[3] = (uint32_t)m->height;
            for (int l = 0; l < m->nlevels; l++) {
                size_t n = (size_t)m->levels[l].width * (size_t)m->levels[l].height * (size_t)m->channels;
                rec[TB_GPU_TEX_HEADER + TB_GPU_TEX_PER_LEVEL * (size_t)l] = (uint32_t)m->levels[l].width;
                rec[TB_GPU_TEX_HEADER + TB_GPU_TEX_PER_LEVEL * (size_t)l + 1] = (uint32_t)m->levels[l].height;
                rec[TB_GPU_TEX_HEADER + TB_GPU_TEX_PER_LEVEL * (size_t)l + 2] = (uint32_t)t->ntexels;
                memcpy(t->texels + t->ntexels, m->levels[l].texels, n * sizeof *t->texels);
                t->ntexels += n;
            }
            t->ninfo += TB_GPU_TEX_HEADER + TB_GPU_TEX_PER_LEVEL * (size_t)m->nlevels;
        }
    return true;
}

/* The kernel's tables on the device; the colour table stays with the
 * renderer (the host applies the shadow rays' colours). */
static tb_status tb__upload_tables(tb_gpu_renderer *r)
{
    const tb_scene *s = r->scene;
    tb__tables t = {0};
    tb__layout_colours(r, &t);
    t.col = calloc(t.ncol ? t.ncol : 1, sizeof *t.col);
    t.mats = calloc((size_t)(s->nmaterials > 0 ? s->nmaterials : 1), sizeof *t.mats);
    t.lts = calloc((size_t)(s->nlights > 0 ? s->nlights : 1), sizeof *t.lts);
    t.ems = calloc((size_t)(s->nemitters > 0 ? s->nemitters : 1), sizeof *t.ems);
    if (!t.col || !t.mats || !t.lts || !t.ems) {
        tb__tables_free(&t);
        return tb_error(TB_ERR_NOMEM, "GPU render: out of memory");
    }
    tb__fill_materials(r, &t);
    tb__fill_lights(r, &t);
    tb__fill_emitters(r, &t);
    if (!tb__fill_textures(r, &t)) {
        tb__tables_free(&t);
        return tb_error(TB_ERR_NOMEM, "GPU render: out of memory");
    }
    tb_gpu_device *dev = r->dev;
    r->b_texinfo = tb__upload(dev, t.tinfo, t.ninfo * sizeof *t.tinfo);
    r->b_texels = r->b_texinfo ? tb__upload(dev, t.texels, t.ntexels * sizeof *t.texels) : NULL;
    r->b_materials = r->b_texels ? tb__upload(dev, t.mats, (size_t)s->nmaterials * sizeof *t.mats) : NULL;
    r->b_colours = r->b_materials ? tb__upload(dev, t.col, t.ncol * sizeof *t.col) : NULL;
    r->b_lights = r->b_colours ? tb__upload(dev, t.lts, (size_t)s->nlights * sizeof *t.lts) : NULL;
    r->b_emitters = r->b_lights ? tb__upload(dev, t.ems, (size_t)s->nemitters * sizeof *t.ems) : NULL;
    r->col = t.col;
    t.col = NULL;
    tb__tables_free(&t);
    return r->b_emitters ? TB_OK : TB_ERR_DEVICE;
}

/* The host staging and device buffers of one shade dispatch (chunk items). */
static tb_status tb__alloc_chunk(tb_gpu_renderer *r)
{
    const size_t NR = TB_GPU_SHADE_RAYS((size_t)r->S, (size_t)r->nglossy),
                 NV = TB_GPU_SHADE_VALUES((size_t)r->S, (size_t)r->nch, (size_t)r->sw, (size_t)r->nglossy,
                                          (size_t)r->pw);
    size_t per = NR * sizeof(tb_gpu_ray) + NV * sizeof(float) + sizeof(tb_gpu_shade_item) +
                 (size_t)r->lu_per * sizeof(tb_gpu_light_u) + (r->any_surface ? sizeof(tb_gpu_surface) : 0);
    r->chunk = TB__GR_CHUNK_BYTES / per;
    if (r->chunk > 65536)
        r->chunk = 65536;
    if (r->chunk < 64)
        r->chunk = 64;
    size_t nr = r->chunk * NR, nv = r->chunk * NV;
    size_t nlu = r->chunk * (size_t)(r->lu_per > 0 ? r->lu_per : 1);
    r->items = malloc(r->chunk * sizeof *r->items);
    r->lightu = calloc(nlu, sizeof *r->lightu); /* items without area samples leave theirs unset */
    r->orays = malloc(nr * sizeof *r->orays);
    r->ovals = malloc(nv * sizeof *r->ovals);
    r->surf = r->any_surface ? calloc(r->chunk, sizeof *r->surf) : NULL;
    if (!r->items || !r->lightu || !r->orays || !r->ovals || (r->any_surface && !r->surf))
        return tb_error(TB_ERR_NOMEM, "GPU render: out of memory");
    tb_gpu_device *dev = r->dev;
    r->b_items = tb_gpu_buffer_create(dev, r->chunk * sizeof *r->items);
    r->b_lightu = r->b_items ? tb_gpu_buffer_create(dev, nlu * sizeof *r->lightu) : NULL;
    r->b_rays = r->b_lightu ? tb_gpu_buffer_create(dev, nr * sizeof(tb_gpu_ray)) : NULL;
    r->b_values = r->b_rays ? tb_gpu_buffer_create(dev, nv * sizeof(float)) : NULL;
    r->b_surf = r->b_values ? tb_gpu_buffer_create(dev, r->any_surface ? r->chunk * sizeof *r->surf : 16) : NULL;
    return r->b_surf ? TB_OK : TB_ERR_DEVICE;
}

tb_status tb_gpu_renderer_create(tb_gpu_device *dev, const tb_scene *s, const tb_rt_options *opt,
                                 tb_gpu_renderer **out)
{
    *out = NULL;
    tb_gpu_renderer *r = calloc(1, sizeof *r);
    if (!r)
        return tb_error(TB_ERR_NOMEM, "GPU render: out of memory");
    r->dev = dev;
    r->scene = s;
    tb_status st = tb_rt_init(&r->rt, s, opt);
    if (st) {
        free(r);
        return st;
    }
    r->nch = s->nchannels;
    r->nlights = s->nlights;
    if (!tb__alloc_materials(r))
        st = tb_error(TB_ERR_NOMEM, "GPU render: out of memory");
    if (!st)
        st = tb__gr_route_materials(r); /* render_route.c */
    if (!st) {
        tb__plan_kernel(r);
        st = tb__upload_tables(r);
    }
    if (!st)
        st = tb__alloc_chunk(r);
    if (!st && !(r->gscene = tb_gpu_scene_create(dev, s)))
        st = TB_ERR_DEVICE;
    if (st) {
        tb_gpu_renderer_destroy(r);
        return st;
    }
    *out = r;
    return TB_OK;
}
