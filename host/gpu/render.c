/* The wavefront Vulkan ray tracer (render.h; docs/gpu.md, "Shade kernel and
 * wavefront renderer"). */
#include "host/gpu/render.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "host/object/intersect.h"
#include "host/render/camera.h"
#include "host/render/raytrace.h"
#include "host/render/sampling.h"
#include "host/render/shading.h"
#include "host/render/texture.h"
#include "shaders/shared/hit.h"
#include "shaders/shared/ray.h"
#include "shaders/shared/shade.h"
#include "util/base/progress.h"
#include "util/stats/stats.h"

TB_STAT_COUNTER(tb__gr_rays, "GPU render/rays intersected");
TB_STAT_COUNTER(tb__gr_shadow, "GPU render/shadow rays");
TB_STAT_COUNTER(tb__gr_gpu_shaded, "GPU render/hits shaded by the kernel");
TB_STAT_COUNTER(tb__gr_cpu_shaded, "GPU render/hits routed to the CPU path");

/* Most light samples per point (raytrace.c's stack array). */
#define TB__GR_MAX_LIGHT_SAMPLES 1024
/* Largest output of one shade dispatch, bytes (rays plus values). */
#define TB__GR_CHUNK_BYTES (24u << 20)

struct tb_gpu_renderer {
    tb_gpu_device *dev;
    const tb_scene *scene;
    tb_gpu_scene *gscene;
    tb_raytracer rt;      /* the CPU tracer: routed hits, light-sample strata, the area light's CDF */
    int nch;              /* channels */
    int nlights;          /* delta lights */
    int nsamples;         /* area-light samples per point (0: no area light) */
    int S;                /* shadow slots per item */
    int sw;               /* words per shadow slot (3, or 4 with GGX: shared/shade.h) */
    int nglossy;          /* most glossy rays per item (0: no GGX material) */
    int lu_per;           /* light-sample buffer entries per item: nsamples + nglossy */
    int cap_stack;        /* stack entries per path */
    int pw0;              /* pattern words per item (2 with colour patterns, else 0) */
    int pw;               /* pattern and texture words per item (pw0, and 6 with textures) */
    bool any_surface;     /* some material has a pattern or a bump map: items carry surface records */
    uint8_t *mpat;        /* per material: its hits need a surface record: 1 for a pattern or bump map
                             (routed without tangents), 2 for image textures only */
    uint32_t *pat_col;    /* per material: colour-table offsets of its diffuse and specular pattern colours
                             (a, then b; 0: no pattern) */
    char **route;         /* per material: why it is routed, or NULL */
    uint8_t *mflags;      /* per material: TB_GPU_MAT_* */
    tb_gpu_spec_constant spec[17];
    tb_gpu_buffer *b_texinfo, *b_texels; /* image textures: records and MIP pyramids */
    tb_gpu_buffer *b_surf;  /* surface records of one chunk (item j's at j) */
    tb_gpu_buffer *b_items, *b_lightu, *b_emitters, *b_lights, *b_materials, *b_colours, *b_rays, *b_values;
    size_t chunk;         /* items per shade dispatch */
    uint32_t light_col, emitter_col, perm_col;
    float *col;           /* the colour table (as uploaded): the host applies the shadow rays' colours */
    int threads;          /* OpenMP threads of the host's loops (0: OpenMP's default) */
    /* host staging of one chunk */
    tb_gpu_shade_item *items;
    tb_gpu_light_u *lightu;
    tb_gpu_surface *surf;
    tb_ray *orays;
    float *ovals;
    tb_gpu_render_stats st;
};

static double tb__now(void)
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

static char *tb__strdup(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d)
        memcpy(d, s, n);
    return d;
}

/* Bit c (c < 3) set if channel c of the image (its only channel if grey)
 * is positive in every texel of every level: then so is every filtered
 * value (nearest, bilinear, trilinear and EWA weights are convex). */
static unsigned tb__texture_positive(const tb_mipmap *t)
{
    unsigned pos = 7;
    for (int l = 0; l < t->nlevels && pos; l++) {
        size_t n = (size_t)t->levels[l].width * (size_t)t->levels[l].height;
        for (size_t x = 0; x < n && pos; x++)
            for (int c = 0; c < 3; c++)
                if (!(t->levels[l].texels[x * (size_t)t->channels + (size_t)(t->channels >= 3 ? c : 0)] > 0.0f))
                    pos &= ~(1u << c);
    }
    return pos;
}

/* Whether colour slot k (0 diffuse, 1 specular, 2 transmission) of a
 * material is black at a hit, after its pattern (a + f (b - a), f in
 * [0, 1]) and its texture `tex` (NULL: none): 0 everywhere, 1 nowhere, -1
 * in some places only. The CPU tracer draws light samples, and spawns
 * mirror, glossy and refracted rays, only for non-black colours, so for the
 * kernel this must not depend on the hit. */
static int tb__colour_class(const tb_material *m, int k, const tb_mipmap *tex)
{
    const tb_channels *base = k == 0 ? &m->diffuse : k == 1 ? &m->specular : &m->transmission;
    const tb_material_pattern *p = k == 0 ? &m->diffuse_pattern : k == 1 ? &m->specular_pattern : NULL;
    bool black = true, positive = false;
    unsigned pos = 0; /* channels < 3 positive everywhere */
    for (int c = 0; c < base->n; c++) {
        bool pc = p && p->kind ? p->a.v[c] > 0.0f && p->b.v[c] > 0.0f : base->v[c] > 0.0f;
        black = black && (p && p->kind ? p->a.v[c] == 0.0f && p->b.v[c] == 0.0f : base->v[c] == 0.0f);
        positive = positive || pc;
        if (pc && c < 3)
            pos |= 1u << c;
    }
    if (black)
        return 0;
    if (tex)
        return pos & tb__texture_positive(tex) ? 1 : -1;
    if (p && p->kind)
        return positive ? 1 : -1;
    return 1; /* a constant, not black */
}

/* A colour pattern the kernel evaluates: none, checker or noise. */
static bool tb__pattern_ok(const tb_material_pattern *p)
{
    return p->kind == TB_MID_PATTERN_NONE || p->kind == TB_MID_PATTERN_CHECKER || p->kind == TB_MID_PATTERN_NOISE;
}

const char *tb_gpu_renderer_material_route(const tb_gpu_renderer *r, int m)
{
    return m >= 0 && m < r->scene->nmaterials ? r->route[m] : NULL;
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
    const int nm = s->nmaterials, nch = s->nchannels;
    r->nch = nch;
    r->nlights = s->nlights;
    r->nsamples = r->rt.has_area ? r->rt.light_samples : 0;
    r->S = r->nlights + r->nsamples;
    r->route = calloc((size_t)(nm > 0 ? nm : 1), sizeof *r->route);
    r->mflags = calloc((size_t)(nm > 0 ? nm : 1), 1);
    r->mpat = calloc((size_t)(nm > 0 ? nm : 1), 1);
    r->pat_col = calloc((size_t)(nm > 0 ? nm : 1) * 2, sizeof *r->pat_col);
    if (!r->route || !r->mflags || !r->mpat || !r->pat_col)
        goto nomem;

    /* What the kernel cannot do, scene-wide. */
    bool ies = false, bad_emitter = false, spot = false;
    for (int i = 0; i < s->nlights; i++) {
        ies = ies || s->lights[i].ies;
        spot = spot || s->lights[i].kind == TB_LIGHT_SPOT;
    }
    uint32_t kinds = 0;
    for (int i = 0; i < s->nemitters; i++) {
        const tb_emitter *e = &s->emitters[i];
        if (e->kind == TB_EMITTER_CUSTOM || (e->kind == TB_EMITTER_SPHERE && e->two_sided) ||
            (int)e->kind > TB_EMITTER_SPHERE)
            bad_emitter = true;
        else
            kinds |= 1u << e->kind;
    }
    bool any_phong = false, any_mirror = false, any_dielectric = false, any_emission = false, any_ggx = false;
    bool any_colour_pattern = false, any_bump = false, any_texture = false;
    uint32_t pattern_kinds = 0;
    /* image textures: the MIP pyramids of all distinct images in one texel
     * buffer, which must fit the device's storage-buffer limit */
    size_t tex_floats = 0;
    if (r->rt.textures && !s->spectral) {
        for (int q = 0; q < 4 * nm; q++) {
            const tb_mipmap *t = tb__rt_texture_mip(r->rt.textures, q);
            bool seen = false;
            for (int q2 = 0; q2 < q && t && !seen; q2++)
                seen = tb__rt_texture_mip(r->rt.textures, q2) == t;
            for (int l = 0; t && !seen && l < t->nlevels; l++)
                tex_floats += (size_t)t->levels[l].width * (size_t)t->levels[l].height * (size_t)t->channels;
        }
    }
    const bool tex_too_big = tex_floats * sizeof(float) > tb_gpu_device_info_of(dev)->max_storage_buffer_range;
    for (int i = 0; i < nm; i++) {
        const tb_material *m = &s->materials[i];
        uint8_t f = 0;
        /* a colour pattern replaces the colour; whether it is black decides
         * which numbers the point draws, so it must not depend on the hit */
        const bool lambert = m->model == TB_MID_MODEL_LAMBERT;
        const tb_mipmap *tex[4];
        bool any_tex_here = false;
        for (int k = 0; k < 4; k++) {
            tex[k] = k == 1 && lambert ? NULL : tb__rt_texture_mip(r->rt.textures, k * nm + i);
            any_tex_here = any_tex_here || tex[k];
        }
        int dcls = tb__colour_class(m, 0, tex[0]), scls = lambert ? 0 : tb__colour_class(m, 1, tex[1]);
        int tcls = tb__colour_class(m, 2, tex[2]);
        if (dcls == 1)
            f |= TB_GPU_MAT_DIFFUSE;
        /* model lambert: the specular colour is ignored (raytrace.c) */
        if (scls == 1)
            f |= TB_GPU_MAT_SPECULAR;
        if (m->model == TB_MID_MODEL_BLINN)
            f |= TB_GPU_MAT_BLINN;
        if (m->model == TB_MID_MODEL_GGX && (f & TB_GPU_MAT_SPECULAR))
            f |= TB_GPU_MAT_GGX;
        if (tcls == 1)
            f |= TB_GPU_MAT_TRANSMISSION;
        if (m->emits)
            f |= TB_GPU_MAT_EMITS;
        r->mflags[i] = f;
        const char *why = NULL;
        if (any_tex_here && s->spectral)
            why = "image texture in a spectral scene (the kernel has no RGB-to-spectrum upsampling)";
        else if (any_tex_here && tex_too_big)
            why = "image textures larger than the device's storage-buffer limit";
        else if (!tb__pattern_ok(&m->diffuse_pattern) || (!lambert && !tb__pattern_ok(&m->specular_pattern)))
            why = "procedural pattern of an unknown kind";
        else if (dcls < 0 || scls < 0 || tcls < 0)
            why = "colour (pattern or image texture) black in some places only (the numbers a point draws would "
                  "depend on it)";
        else if (m->bump.kind && m->bump.kind != TB_MID_PATTERN_NOISE)
            why = m->bump.kind == TB_MID_PATTERN_IMAGE ? "bump map from an image" : "bump map of an unknown kind";
        else if (m->model != TB_MID_MODEL_PHONG && m->model != TB_MID_MODEL_BLINN &&
                 m->model != TB_MID_MODEL_LAMBERT && m->model != TB_MID_MODEL_GGX)
            why = "reflection model";
        else if (bad_emitter && (f & (TB_GPU_MAT_DIFFUSE | TB_GPU_MAT_GGX)))
            why = "lit by an emitter the kernel does not sample (custom or two-sided sphere)";
        if (why) {
            char buf[sizeof r->st.routed_reason];
            snprintf(buf, sizeof buf, "material %d%s%s%s: %s", i, m->name ? " (" : "", m->name ? m->name : "",
                     m->name ? ")" : "", why);
            if (!(r->route[i] = tb__strdup(buf)))
                goto nomem;
            if (r->st.routed_materials++ == 0)
                memcpy(r->st.routed_reason, buf, sizeof buf);
            continue;
        }
        any_phong = any_phong || ((f & TB_GPU_MAT_SPECULAR) && !(f & TB_GPU_MAT_GGX) && s->nlights > 0);
        any_mirror = any_mirror ||
                     ((f & TB_GPU_MAT_SPECULAR) && !(f & TB_GPU_MAT_TRANSMISSION) && !(f & TB_GPU_MAT_GGX));
        any_ggx = any_ggx || (f & TB_GPU_MAT_GGX);
        const tb_material_pattern *pats[3] = {&m->diffuse_pattern, lambert ? NULL : &m->specular_pattern, &m->bump};
        for (int k = 0; k < 3; k++)
            if (pats[k] && pats[k]->kind) {
                r->mpat[i] = 1;
                pattern_kinds |= 1u << (pats[k]->kind == TB_MID_PATTERN_CHECKER ? TB_GPU_PATTERN_CHECKER
                                                                                : TB_GPU_PATTERN_NOISE);
                if (k < 2)
                    any_colour_pattern = true;
                else
                    any_bump = true;
            }
        if (any_tex_here) {
            any_texture = true;
            if (!r->mpat[i])
                r->mpat[i] = 2; /* textures only: without tangents, a lookup without footprint */
        }
        any_dielectric = any_dielectric || (f & TB_GPU_MAT_TRANSMISSION);
        any_emission = any_emission || (f & TB_GPU_MAT_EMITS);
    }
    if (!kinds)
        kinds = 1; /* no emitter: the constant only prunes code */
    /* GGX: a fourth word per shadow ray (Schlick's white part) and up to
     * glossy_samples glossy rays per item (at a camera ray's hit) */
    r->sw = any_ggx ? 4 : 3;
    r->nglossy = any_ggx ? r->rt.glossy_samples : 0;
    r->lu_per = r->nsamples + r->nglossy;
    /* a hit pushes at most 2 rays (dielectric) and nets +1 per level, the
     * camera ray's GGX hit nglossy */
    r->cap_stack = r->rt.max_depth + 2 + (r->nglossy > 1 ? r->nglossy - 1 : 0);
    r->pw0 = any_colour_pattern ? 2 : 0;
    r->pw = r->pw0 + (any_texture ? 6 : 0);
    r->any_surface = any_colour_pattern || any_bump || any_texture;
    tb_gpu_spec_constant spec[17] = {{1, (uint32_t)nch},  {2, (uint32_t)r->nlights}, {3, (uint32_t)r->nsamples},
                                     {4, spot},           {5, any_phong},            {6, any_mirror},
                                     {7, any_dielectric}, {8, any_emission},         {9, kinds},
                                     {10, ies},           {11, any_ggx},             {12, (uint32_t)r->nglossy},
                                     {13, any_colour_pattern}, {14, any_bump},       {15, pattern_kinds},
                                     {16, any_texture},   {17, (uint32_t)r->rt.texture_filter}};
    memcpy(r->spec, spec, sizeof spec);

    /* Tables: materials (scalars), colours (materials' 4 x nch, lights' and
     * emitters' nch each), lights, emitters. */
    size_t ncol = (size_t)nm * 4 * (size_t)nch + (size_t)s->nlights * (size_t)nch + (size_t)s->nemitters * (size_t)nch;
    size_t pat_at = ncol; /* pattern colours follow: a, b of each diffuse and specular pattern */
    for (int i = 0; i < nm; i++)
        for (int k = 0; k < 2; k++)
            if (!r->route[i] && r->mpat[i] && (k == 0 ? s->materials[i].diffuse_pattern.kind
                                                       : s->materials[i].specular_pattern.kind))
                ncol += 2 * (size_t)nch;
    r->perm_col = (uint32_t)ncol; /* the noise permutation follows */
    if (pattern_kinds & (1u << TB_GPU_PATTERN_NOISE))
        ncol += 256;
    size_t ies_at = ncol; /* IES records follow (shared/shade.h), one per distinct table */
    for (int i = 0; i < s->nlights; i++) {
        const tb_ies *t = s->lights[i].ies;
        bool seen = false;
        for (int k = 0; k < i && t && !seen; k++)
            seen = s->lights[k].ies == t;
        if (t && !seen)
            ncol += 4 + (size_t)t->nv + (size_t)t->nh + (size_t)t->nv * (size_t)t->nh;
    }
    float *col = calloc(ncol ? ncol : 1, sizeof *col);
    tb_gpu_shade_material *mats = calloc((size_t)(nm > 0 ? nm : 1), sizeof *mats);
    tb_gpu_delta_light *lts = calloc((size_t)(s->nlights > 0 ? s->nlights : 1), sizeof *lts);
    tb_gpu_emitter *ems = calloc((size_t)(s->nemitters > 0 ? s->nemitters : 1), sizeof *ems);
    if (!col || !mats || !lts || !ems) {
        free(col), free(mats), free(lts), free(ems);
        goto nomem;
    }
    for (int i = 0; i < nm; i++) {
        const tb_material *m = &s->materials[i];
        tb_bsdf_kind lobe = m->model == TB_MID_MODEL_BLINN ? TB_BSDF_BLINN_NORMALIZED_EXACT : TB_BSDF_PHONG_NORMALIZED;
        mats[i] = (tb_gpu_shade_material){m->exponent, m->ior, (float)tb_bsdf_lobe_norm(lobe, m->exponent),
                                           r->mflags[i], (float)fmax((double)m->roughness, TB_GGX_ALPHA_MIN),
                                           0.0f, 0.0f, 0.0f, {{0}}, {0, 0, 0, 0}};
        if (!r->route[i] && r->mpat[i]) {
            const tb_material_pattern *pats[3] = {&m->diffuse_pattern, &m->specular_pattern, &m->bump};
            for (int k = 0; k < 3; k++) {
                const tb_material_pattern *pt = pats[k];
                if (!pt->kind || (k == 1 && m->model == TB_MID_MODEL_LAMBERT))
                    continue;
                tb_gpu_pattern *g = &mats[i].pattern[k];
                *g = (tb_gpu_pattern){.kind = pt->kind == TB_MID_PATTERN_CHECKER ? TB_GPU_PATTERN_CHECKER
                                                                                 : TB_GPU_PATTERN_NOISE,
                                      .su = pt->scale, .sv = pt->scale_v, .solid = pt->object_space,
                                      .octaves = pt->octaves, .height = pt->height};
                if (k < 2) {
                    g->col = (uint32_t)pat_at;
                    r->pat_col[2 * i + k] = (uint32_t)pat_at;
                    for (int c = 0; c < nch; c++) {
                        col[pat_at + (size_t)c] = pt->a.v[c];
                        col[pat_at + (size_t)nch + (size_t)c] = pt->b.v[c];
                    }
                    pat_at += 2 * (size_t)nch;
                }
            }
        }
        const tb_channels *c4[4] = {&m->diffuse, &m->specular, &m->transmission, &m->emission};
        if (i == 0 && (pattern_kinds & (1u << TB_GPU_PATTERN_NOISE)))
            for (int k = 0; k < 256; k++)
                col[r->perm_col + (size_t)k] = (float)tb_noise_permutation()[k];
        for (int k = 0; k < 4; k++)
            for (int c = 0; c < nch; c++)
                col[((size_t)i * 4 + (size_t)k) * (size_t)nch + (size_t)c] =
                    k == 1 && !(r->mflags[i] & TB_GPU_MAT_SPECULAR) ? 0.0f : c4[k]->v[c];
    }
    r->light_col = (uint32_t)((size_t)nm * 4 * (size_t)nch);
    r->emitter_col = r->light_col + (uint32_t)((size_t)s->nlights * (size_t)nch);
    for (int i = 0; i < s->nlights; i++) {
        const tb_light *l = &s->lights[i];
        uint32_t kind = l->kind == TB_LIGHT_SPOT          ? TB_GPU_LIGHT_SPOT
                        : l->kind == TB_LIGHT_DIRECTIONAL ? TB_GPU_LIGHT_DIRECTIONAL
                                                          : TB_GPU_LIGHT_POINT;
        lts[i] = (tb_gpu_delta_light){.position = l->position, .kind = kind, .axis = l->axis,
                                      .cos_total = (float)l->cos_total, .xaxis = l->xaxis,
                                      .cos_falloff = (float)l->cos_falloff,
                                      .black = tb_channels_is_black(l->intensity), .ies = TB_GPU_NO_IES};
        if (l->ies && kind != TB_GPU_LIGHT_DIRECTIONAL) {
            int k = 0;
            while (k < i && s->lights[k].ies != l->ies)
                k++;
            if (k < i) {
                lts[i].ies = lts[k].ies;
            } else {
                const tb_ies *t = l->ies;
                float *rec = col + ies_at;
                lts[i].ies = (uint32_t)ies_at;
                rec[0] = (float)t->nv;
                rec[1] = (float)t->nh;
                rec[2] = (float)t->symmetry;
                rec[3] = (float)(1.0 / t->max_candela);
                for (int v = 0; v < t->nv; v++)
                    rec[4 + v] = (float)t->v_angles[v];
                for (int h = 0; h < t->nh; h++)
                    rec[4 + t->nv + h] = (float)t->h_angles[h];
                for (int c = 0; c < t->nv * t->nh; c++)
                    rec[4 + t->nv + t->nh + c] = (float)t->candela[c];
                ies_at += 4 + (size_t)t->nv + (size_t)t->nh + (size_t)t->nv * (size_t)t->nh;
            }
        }
        for (int c = 0; c < nch; c++)
            col[r->light_col + (size_t)i * (size_t)nch + (size_t)c] = l->intensity.v[c];
    }
    for (int i = 0; i < s->nemitters; i++) {
        const tb_emitter *e = &s->emitters[i];
        tb_gpu_emitter g = {.v0 = e->v[0], .kind = (uint32_t)e->kind, .v1 = e->v[1], .radius = e->radius,
                            .v2 = e->v[2], .two_sided = e->two_sided};
        if (e->kind == TB_EMITTER_TRIANGLE || e->kind == TB_EMITTER_PARALLELOGRAM) {
            tb_dvec3 e1 = tb_dvec3_sub(tb_vec3_to_d(e->v[1]), tb_vec3_to_d(e->v[0]));
            tb_dvec3 e2 = tb_dvec3_sub(tb_vec3_to_d(e->v[2]), tb_vec3_to_d(e->v[0]));
            g.normal = tb_dvec3_to_f(tb_dvec3_normalize(tb_dvec3_cross(e1, e2)));
        }
        double area = r->rt.has_area ? r->rt.area.areas[i] : tb_emitter_area(e);
        g.inv_area = (float)(1.0 / area);
        ems[i] = g;
        for (int c = 0; c < nch; c++)
            col[r->emitter_col + (size_t)i * (size_t)nch + (size_t)c] = e->radiance.v[c];
    }
    /* Image textures: a record per distinct image (shared/shade.h), its
     * levels' texels one after the other. */
    uint32_t *tinfo = NULL;
    float *texels = NULL;
    size_t ninfo = 0, ntexels = 0;
    if (any_texture) {
        size_t cap_info = 0;
        for (int q = 0; q < 4 * nm; q++) {
            const tb_mipmap *t = tb__rt_texture_mip(r->rt.textures, q);
            cap_info += t ? TB_GPU_TEX_HEADER + TB_GPU_TEX_PER_LEVEL * (size_t)t->nlevels : 0;
        }
        tinfo = malloc(cap_info * sizeof *tinfo);
        texels = malloc((tex_floats ? tex_floats : 1) * sizeof *texels);
        if (!tinfo || !texels) {
            free(tinfo), free(texels), free(col), free(mats), free(lts), free(ems);
            goto nomem;
        }
    }
    for (int i = 0; i < nm; i++)
        for (int k = 0; k < 4; k++) {
            mats[i].tex[k] = TB_GPU_NO_TEXTURE;
            const tb_mipmap *t = r->route[i] || (k == 1 && s->materials[i].model == TB_MID_MODEL_LAMBERT)
                                     ? NULL
                                     : tb__rt_texture_mip(r->rt.textures, k * nm + i);
            if (!t || !any_texture)
                continue;
            /* an image already copied for another slot: its record */
            for (int q = 0; q < k * nm + i && mats[i].tex[k] == TB_GPU_NO_TEXTURE; q++)
                if (tb__rt_texture_mip(r->rt.textures, q) == t && !r->route[q % nm] &&
                    mats[q % nm].tex[q / nm] != TB_GPU_NO_TEXTURE)
                    mats[i].tex[k] = mats[q % nm].tex[q / nm];
            if (mats[i].tex[k] != TB_GPU_NO_TEXTURE)
                continue;
            mats[i].tex[k] = (uint32_t)ninfo;
            uint32_t *rec = tinfo + ninfo;
            rec[0] = (uint32_t)t->channels, rec[1] = (uint32_t)t->nlevels;
            rec[2] = (uint32_t)t->width, rec[3] = (uint32_t)t->height;
            for (int l = 0; l < t->nlevels; l++) {
                size_t n = (size_t)t->levels[l].width * (size_t)t->levels[l].height * (size_t)t->channels;
                rec[TB_GPU_TEX_HEADER + TB_GPU_TEX_PER_LEVEL * (size_t)l] = (uint32_t)t->levels[l].width;
                rec[TB_GPU_TEX_HEADER + TB_GPU_TEX_PER_LEVEL * (size_t)l + 1] = (uint32_t)t->levels[l].height;
                rec[TB_GPU_TEX_HEADER + TB_GPU_TEX_PER_LEVEL * (size_t)l + 2] = (uint32_t)ntexels;
                memcpy(texels + ntexels, t->levels[l].texels, n * sizeof *texels);
                ntexels += n;
            }
            ninfo += TB_GPU_TEX_HEADER + TB_GPU_TEX_PER_LEVEL * (size_t)t->nlevels;
        }
    r->b_texinfo = tb__upload(dev, tinfo, ninfo * sizeof *tinfo);
    r->b_texels = r->b_texinfo ? tb__upload(dev, texels, ntexels * sizeof *texels) : NULL;
    free(tinfo), free(texels);
    if (!r->b_texels) {
        free(col), free(mats), free(lts), free(ems);
        goto fail;
    }
    r->b_materials = tb__upload(dev, mats, (size_t)nm * sizeof *mats);
    r->b_colours = r->b_materials ? tb__upload(dev, col, ncol * sizeof *col) : NULL;
    r->b_lights = r->b_colours ? tb__upload(dev, lts, (size_t)s->nlights * sizeof *lts) : NULL;
    r->b_emitters = r->b_lights ? tb__upload(dev, ems, (size_t)s->nemitters * sizeof *ems) : NULL;
    r->col = col;
    free(mats), free(lts), free(ems);
    if (!r->b_emitters)
        goto fail;

    /* Chunk buffers. */
    const size_t NR = TB_GPU_SHADE_RAYS((size_t)r->S, (size_t)r->nglossy),
                 NV = TB_GPU_SHADE_VALUES((size_t)r->S, (size_t)nch, (size_t)r->sw, (size_t)r->nglossy,
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
        goto nomem;
    r->b_items = tb_gpu_buffer_create(dev, r->chunk * sizeof *r->items);
    r->b_lightu = r->b_items ? tb_gpu_buffer_create(dev, nlu * sizeof *r->lightu) : NULL;
    r->b_rays = r->b_lightu ? tb_gpu_buffer_create(dev, nr * sizeof(tb_gpu_ray)) : NULL;
    r->b_values = r->b_rays ? tb_gpu_buffer_create(dev, nv * sizeof(float)) : NULL;
    r->b_surf = r->b_values ? tb_gpu_buffer_create(dev, r->any_surface ? r->chunk * sizeof *r->surf : 16) : NULL;
    if (!r->b_surf)
        goto fail;
    r->gscene = tb_gpu_scene_create(dev, s);
    if (!r->gscene)
        goto fail;
    *out = r;
    return TB_OK;
nomem:
    st = tb_error(TB_ERR_NOMEM, "GPU render: out of memory");
    tb_gpu_renderer_destroy(r);
    return st;
fail:
    tb_gpu_renderer_destroy(r);
    return TB_ERR_DEVICE;
}

void tb_gpu_renderer_stats(const tb_gpu_renderer *r, tb_gpu_render_stats *out) { *out = r->st; }

/* ------------------------------------------------------------ the wavefront */

/* Per-path state of one tb__wavefront call. A path is one camera sample (or
 * one ray of tb_gpu_radiance); its stack holds the rays still to trace, each
 * with its depth and throughput. */
typedef struct tb__paths {
    size_t n;
    int cap;            /* stack entries per path */
    int nch;
    tb_ray *ray;        /* [path * cap + k] */
    int *depth;
    float *thr;         /* [(path * cap + k) * nch + c] */
    tb_rt_mis *mis;     /* a glossy ray's weighting context (nb = 0: not a glossy ray) */
    int *top;           /* entries on each stack */
    tb_rng *rng;        /* the paths' streams (caller's) */
    float *L;           /* [path * nch + c] (caller's) */
    /* renderer: film positions and the streams before the lens draws, so a
     * camera ray whose hit is routed is traced as tb_rt_sample traces it
     * (with ray differentials for its textures) */
    const double *xy;   /* NULL: plain rays */
    const tb_rng *rng0;
} tb__paths;

static void tb__push(tb__paths *P, size_t p, const tb_ray *ray, int depth, const float *thr, const tb_rt_mis *mis)
{
    int k = P->top[p]++;
    size_t e = p * (size_t)P->cap + (size_t)k;
    P->ray[e] = *ray;
    P->depth[e] = depth;
    if (mis)
        P->mis[e] = *mis;
    else
        P->mis[e].nb = 0.0;
    memcpy(P->thr + e * (size_t)P->nch, thr, sizeof(float) * (size_t)P->nch);
}

/* One wave's active paths (popped entries). */
typedef struct tb__wave {
    size_t n;
    size_t *path;
    tb_ray *ray;
    int *depth;
    float *thr;       /* [a * nch + c] */
    tb_rt_mis *mis;   /* glossy rays' weighting (nb = 0: none) */
    tb_hit *hit;
    size_t *item_of;  /* items: index into the wave */
    size_t *routed;   /* routed hits: index into the wave */
    int *mat;         /* material of each hit */
    size_t *sstart;   /* item j's shadow rays are shadow[sstart[j] .. sstart[j + 1]) */
    tb_gpu_surface *surf; /* surface records of hits on patterned materials (any_surface only) */
    uint8_t *sok;     /* 1: surf[a] is set; 0: none needed; 2: needed but the hit has no tangents (routed) */
    tb_ray *shadow;   /* shadow rays of one chunk */
    size_t *shadow_src; /* value slot index (chunk-local) of each shadow ray */
    uint8_t *occl;
} tb__wave;

/* Runs the shade kernel on r->items[0..ni) and handles its outputs for the
 * wave entries w->item_of[base ..]. */
static tb_status tb__shade_chunk(tb_gpu_renderer *r, tb__paths *P, tb__wave *w, size_t base, size_t ni,
                                 size_t nlu)
{
    const int nch = r->nch, S = r->S, G = r->nglossy;
    const size_t SW = (size_t)r->sw, NR = TB_GPU_SHADE_RAYS((size_t)S, (size_t)G),
                 NV = TB_GPU_SHADE_VALUES((size_t)S, (size_t)nch, SW, (size_t)G, (size_t)r->pw),
                 SL = (size_t)nch + 1;
    double w0 = tb__now();
    tb_status st = tb_gpu_buffer_upload(r->b_items, 0, r->items, ni * sizeof *r->items);
    if (!st && nlu)
        st = tb_gpu_buffer_upload(r->b_lightu, 0, r->lightu, nlu * sizeof *r->lightu);
    if (!st && r->any_surface) /* records of items without the flag are not read */
        st = tb_gpu_buffer_upload(r->b_surf, 0, r->surf, ni * sizeof *r->surf);
    if (st)
        return st;
    tb_gpu_kernel *k = tb_gpu_kernel_get(r->dev, &(tb_gpu_kernel_desc){.spirv = tb_gpu_builtin("shade"),
                                                                        .buffers = 11,
                                                                        .push_size = sizeof(tb_gpu_shade_push),
                                                                        .spec = r->spec,
                                                                        .spec_count = 17});
    if (!k)
        return TB_ERR_DEVICE;
    tb_gpu_shade_push push = {(uint32_t)ni, r->perm_col, 0, 0};
    tb_gpu_dispatch d = {k,
                         {r->b_items, r->b_lightu, r->b_emitters, r->b_lights, r->b_materials, r->b_colours,
                          r->b_rays, r->b_values, r->b_surf, r->b_texinfo, r->b_texels},
                         &push,
                         ni,
                         0.0};
    if ((st = tb_gpu_run(r->dev, &d, 1)))
        return st;
    r->st.shade_seconds += d.seconds;
    if ((st = tb_gpu_buffer_download(r->b_rays, 0, r->orays, ni * NR * sizeof(tb_gpu_ray))) ||
        (st = tb_gpu_buffer_download(r->b_values, 0, r->ovals, ni * NV * sizeof(float))))
        return st;
    r->st.shade_wall_seconds += tb__now() - w0;

    /* Emission, secondary rays; shadow rays collected. The outputs are
     * word-major (shared/shade.h): word w of item j at w ni + j; shadow slot
     * s's words (flag, a, b[, c]) are SW s .. SW s + SW - 1, colour slot k's
     * (flag, channels) follow from SW S + k SL, the glossy densities from
     * SW S + (3 + G) SL; ray slot k at k ni + j. */
#define TB__W(j, w) r->ovals[(size_t)(w) * ni + (j)]
#define TB__C(j, k, c) TB__W(j, SW * (size_t)S + (size_t)(k) * SL + (size_t)(c))
#define TB__PDF(j, k) TB__W(j, SW * (size_t)S + (3 + (size_t)G) * SL + (size_t)(k))
#define TB__PAT(j, k) TB__W(j, SW * (size_t)S + (3 + (size_t)G) * SL + (size_t)G + (size_t)(k))
    /* shadow rays of the chunk in item order (sequential: it compacts) */
    size_t ns = 0;
    for (size_t j = 0; j < ni; j++) {
        w->sstart[j] = ns;
        for (int s = 0; s < S; s++)
            if (TB__W(j, SW * (size_t)s) != 0.0f) {
                w->shadow[ns] = r->orays[(size_t)s * ni + j];
                w->shadow_src[ns++] = j * (size_t)S + (size_t)s;
            }
    }
    w->sstart[ni] = ns;
    const int nthreads = r->threads > 0 ? r->threads : omp_get_max_threads();
    /* items belong to distinct paths: any thread order gives the same sums */
#pragma omp parallel for schedule(static) num_threads(nthreads)
    for (size_t j = 0; j < ni; j++) {
        size_t a = w->item_of[base + j], p = w->path[a];
        const float *thr = w->thr + a * (size_t)nch;
        float *L = P->L + p * (size_t)nch;
        float tmp[TB_CHANNELS_MAX];
        if (TB__C(j, 0, 0) != 0.0f) {
            /* a glossy ray's emission is weighted against the light samples
             * of the point it left (power heuristic), in double as on the
             * CPU path */
            float wm = w->mis[a].nb > 0.0 ? (float)tb_rt_mis_weight(&r->rt, &w->mis[a]) : 1.0f;
            for (int c = 0; c < nch; c++)
                L[c] += thr[c] * (TB__C(j, 0, 1 + c) * wm);
        }
        /* refracted first, so the mirror ray is on top (the CPU traces it first) */
        for (int k = 2; k >= 1; k--) {
            if (TB__C(j, k, 0) == 0.0f)
                continue;
            for (int c = 0; c < nch; c++)
                tmp[c] = thr[c] * TB__C(j, k, 1 + c);
            tb__push(P, p, &r->orays[(size_t)(S + k - 1) * ni + j], w->depth[a] + 1, tmp, NULL);
        }
        /* glossy rays, the last first so that ray 0 is on top (the CPU
         * traces them in order), each weighted 1 / (rays sampled) */
        const tb_gpu_shade_item *it = &r->items[j];
        if (it->glossy > 0) {
            tb_rt_mis mis = {.p = tb_vec3_add(it->o, tb_vec3_scale(it->d, it->t)),
                             .nb = (double)it->glossy, .nl = (double)r->rt.light_samples};
            float inv = 1.0f / (float)it->glossy;
            for (int k = (int)it->glossy - 1; k >= 0; k--) {
                if (TB__C(j, 3 + k, 0) == 0.0f)
                    continue;
                const tb_ray *gr = &r->orays[(size_t)(S + 2 + k) * ni + j];
                for (int c = 0; c < nch; c++)
                    tmp[c] = thr[c] * (TB__C(j, 3 + k, 1 + c) * inv);
                mis.w = gr->d;
                mis.pdf = TB__PDF(j, k);
                tb__push(P, p, gr, w->depth[a] + 1, tmp, &mis);
            }
        }
    }
    if (ns) {
        double t0 = tb__now();
        st = tb_gpu_occluded(r->gscene, w->shadow, ns, w->occl, NULL);
        r->st.trace_seconds += tb__now() - t0;
        if (st)
            return st;
        r->st.shadow_rays += ns;
        tb_stat_add(&tb__gr_shadow, (int64_t)ns);
        /* An unblocked shadow ray adds (diffuse a + specular b) x its light's
         * colour (the light's intensity, or the sampled emitter's radiance). */
#pragma omp parallel for schedule(static) num_threads(nthreads)
        for (size_t j = 0; j < ni; j++) {
            size_t a = w->item_of[base + j], p = w->path[a];
            const tb_gpu_shade_item *it = &r->items[j];
            const float *thr = w->thr + a * (size_t)nch;
            const float *dif = r->col + (size_t)it->material * 4 * (size_t)nch, *spec = dif + nch;
            /* colour patterns: the blend a + f (b - a) of the kernel's
             * factors, in double as the CPU tracer blends */
            float pdif[TB_CHANNELS_MAX], pspec[TB_CHANNELS_MAX];
            for (int k = 0; k < r->pw0; k++) {
                float f = TB__PAT(j, k);
                if (f < 0.0f)
                    continue;
                const float *pa = r->col + r->pat_col[2 * (size_t)it->material + (size_t)k], *pb = pa + nch;
                float *out = k == 0 ? pdif : pspec;
                for (int c = 0; c < nch; c++)
                    out[c] = (float)((double)pa[c] + (double)f * ((double)pb[c] - (double)pa[c]));
                if (k == 0)
                    dif = pdif;
                else
                    spec = pspec;
            }
            /* image textures: times the texture's RGB (RGB scenes only) */
            for (int k = 0; r->pw > r->pw0 && k < 2; k++) {
                if (TB__PAT(j, (size_t)r->pw0 + 3 * (size_t)k) < 0.0f)
                    continue;
                const float *src = k == 0 ? dif : spec;
                float *out = k == 0 ? pdif : pspec;
                for (int c = 0; c < nch; c++)
                    out[c] = src[c] * TB__PAT(j, (size_t)r->pw0 + 3 * (size_t)k + (size_t)c);
                if (k == 0)
                    dif = pdif;
                else
                    spec = pspec;
            }
            float *L = P->L + p * (size_t)nch;
            for (size_t q = w->sstart[j]; q < w->sstart[j + 1]; q++) {
                if (w->occl[q])
                    continue;
                size_t k = w->shadow_src[q] % (size_t)S;
                const float *lc =
                    k < (size_t)r->nlights
                        ? r->col + r->light_col + k * (size_t)nch
                        : r->col + r->emitter_col +
                              (size_t)r->lightu[it->light_base + (k - (size_t)r->nlights)].emitter * (size_t)nch;
                float ca = TB__W(j, SW * k + 1), cb = TB__W(j, SW * k + 2), cc = SW > 3 ? TB__W(j, SW * k + 3) : 0.0f;
                for (int c = 0; c < nch; c++)
                    L[c] += thr[c] * ((dif[c] * ca + spec[c] * cb + cc) * lc[c]);
            }
        }
    }
#undef TB__PAT
#undef TB__PDF
#undef TB__C
#undef TB__W
    return TB_OK;
}

/* The surface record of wave entry a (a hit on a patterned material), as
 * the CPU tracer builds it at that hit: the hit point from the object,
 * the camera ray's differentials for a camera ray of the renderer (the
 * lens numbers again from the sample's stream). 1 if set, 2 if the hit has
 * no tangents (the CPU then shades without the patterns: the hit is routed). */
static uint8_t tb__surface(const tb_gpu_renderer *r, const tb__paths *P, tb__wave *w, size_t a)
{
    const tb_scene *s = r->scene;
    const tb_hit *h = &w->hit[a];
    const tb_ray *ray = &w->ray[a];
    tb_vec3 p, perr;
    if (!tb_object_hit_point(s->objects[h->object], ray, h, &p, &perr))
        p = tb_vec3_add(ray->o, tb_vec3_scale(ray->d, h->t)); /* raytrace.c's fallback */
    tb_vec3 d = tb_vec3_normalize(ray->d);
    tb_vec3 n = tb_vec3_dot(d, h->ng) < 0.0f ? h->ng : tb_vec3_neg(h->ng);
    tb_vec3 rd[4];
    const tb_vec3 *rdp = NULL;
    size_t path = w->path[a];
    if (w->depth[a] == 0 && P->xy) {
        tb_rng rng0 = P->rng0[path];
        float lu = 0.5f, lv = 0.5f;
        if (s->camera.lens_radius > 0.0) {
            lu = tb_rng_float(&rng0);
            lv = tb_rng_float(&rng0);
        }
        tb_camera_ray_diff cd;
        tb_camera_ray_differential(&s->camera, P->xy[2 * path], P->xy[2 * path + 1], lu, lv, &cd);
        rd[0] = cd.rx_o, rd[1] = cd.rx_d, rd[2] = cd.ry_o, rd[3] = cd.ry_d;
        rdp = rd;
    }
    tb__rt_surface g;
    if (!tb__rt_hit_surface(&r->rt, h, p, h->ng, n, rdp, &g)) {
        if (r->mpat[w->mat[a]] != 2)
            return 2;
        /* textures only: the CPU looks them up at (u, v) without a footprint */
        w->surf[a] = (tb_gpu_surface){.u = h->u, .v = h->v};
        return 1;
    }
    w->surf[a] = (tb_gpu_surface){.po = g.po, .u = g.u, .po_du = g.po_du, .v = g.v, .po_dv = g.po_dv,
                                  .has_fp = g.has_fp, .po_dx = g.po_dx, .po_dy = g.po_dy, .dpdu = g.dpdu,
                                  .dpdv = g.dpdv};
    if (g.has_fp) {
        w->surf[a].fp0 = g.fp[0];
        w->surf[a].fp1 = g.fp[1];
        w->surf[a].fp2 = g.fp[2];
        w->surf[a].fp3 = g.fp[3];
    }
    return 1;
}

/* Traces every path's stack empty. */
static tb_status tb__wavefront(tb_gpu_renderer *r, tb__paths *P)
{
    const tb_scene *s = r->scene;
    const int nch = r->nch;
    const size_t n = P->n, S = (size_t)r->S;
    tb__wave w = {0};
    w.path = malloc(n * sizeof *w.path);
    w.ray = malloc(n * sizeof *w.ray);
    w.depth = malloc(n * sizeof *w.depth);
    w.thr = malloc(n * (size_t)nch * sizeof *w.thr);
    w.mis = malloc(n * sizeof *w.mis);
    w.surf = r->any_surface ? malloc(n * sizeof *w.surf) : NULL;
    w.sok = r->any_surface ? malloc(n ? n : 1) : NULL;
    w.hit = malloc(n * sizeof *w.hit);
    w.item_of = malloc(n * sizeof *w.item_of);
    w.routed = malloc(n * sizeof *w.routed);
    w.mat = malloc(n * sizeof *w.mat);
    w.sstart = malloc((r->chunk + 1) * sizeof *w.sstart);
    w.shadow = malloc(r->chunk * (S ? S : 1) * sizeof *w.shadow);
    w.shadow_src = malloc(r->chunk * (S ? S : 1) * sizeof *w.shadow_src);
    w.occl = malloc(r->chunk * (S ? S : 1));
    tb_status st = TB_OK;
    if (!w.path || !w.ray || !w.depth || !w.thr || !w.mis || (r->any_surface && (!w.surf || !w.sok)) || !w.hit ||
        !w.item_of || !w.routed || !w.mat || !w.sstart || !w.shadow || !w.shadow_src || !w.occl)
        st = tb_error(TB_ERR_NOMEM, "GPU render: out of memory for %zu paths", n);
    const int nthreads = r->threads > 0 ? r->threads : omp_get_max_threads();
    double wave0 = tb__now();
    while (!st) {
        /* pop the top of every active path */
        w.n = 0;
        for (size_t p = 0; p < n; p++) {
            if (P->top[p] == 0)
                continue;
            size_t e = p * (size_t)P->cap + (size_t)(--P->top[p]);
            w.path[w.n] = p;
            w.ray[w.n] = P->ray[e];
            w.depth[w.n] = P->depth[e];
            w.mis[w.n] = P->mis[e];
            memcpy(w.thr + w.n * (size_t)nch, P->thr + e * (size_t)nch, sizeof(float) * (size_t)nch);
            w.n++;
        }
        if (w.n == 0)
            break;
        r->st.waves++;
        double t0 = tb__now();
        st = tb_gpu_intersect(r->gscene, w.ray, w.n, w.hit, NULL);
        r->st.trace_seconds += tb__now() - t0;
        if (st)
            break;
        r->st.rays += w.n;
        tb_stat_add(&tb__gr_rays, (int64_t)w.n);
        /* Materials, and the surface records of patterned hits (in parallel:
         * each entry its own). */
#pragma omp parallel for schedule(dynamic, 64) num_threads(nthreads)
        for (size_t a = 0; a < w.n; a++) {
            const tb_hit *h = &w.hit[a];
            const tb_material *m = h->object == TB_GPU_NO_HIT ? NULL : tb_scene_hit_material(s, h);
            w.mat[a] = m ? (int)(m - s->materials) : -1;
            if (r->any_surface)
                w.sok[a] = m && !r->route[w.mat[a]] && r->mpat[w.mat[a]] ? tb__surface(r, P, &w, a) : 0;
        }
        /* Classify the hits: kernel items and routed hits (wave indices). */
        size_t nit = 0, nrt = 0;
        for (size_t a = 0; a < w.n; a++) {
            if (w.mat[a] < 0)
                continue;
            if (r->route[w.mat[a]] || (r->any_surface && w.sok[a] == 2))
                w.routed[nrt++] = a;
            else
                w.item_of[nit++] = a;
        }
        /* Routed hits: the CPU path for the ray and everything it spawns, with
         * the path's stream (paths are distinct: any thread order gives the
         * same sums). */
        double c0 = tb__now();
#pragma omp parallel for schedule(dynamic, 16) num_threads(nthreads)
        for (size_t q = 0; q < nrt; q++) {
            size_t a = w.routed[q], p = w.path[a];
            float tmp[TB_CHANNELS_MAX];
            if (w.depth[a] == 0 && P->xy) {
                tb_rng rng0 = P->rng0[p];
                tb_rt_sample(&r->rt, P->xy[2 * p], P->xy[2 * p + 1], &rng0, tmp);
                P->rng[p] = rng0;
            } else {
                tb_channels Lc = tb_rt_radiance_at(&r->rt, &w.ray[a], &P->rng[p], w.depth[a],
                                                   w.mis[a].nb > 0.0 ? &w.mis[a] : NULL);
                memcpy(tmp, Lc.v, sizeof(float) * (size_t)nch);
            }
            float *L = P->L + p * (size_t)nch;
            const float *thr = w.thr + a * (size_t)nch;
            for (int c = 0; c < nch; c++)
                L[c] += thr[c] * tmp[c];
        }
        if (nrt)
            r->st.cpu_seconds += tb__now() - c0;
        r->st.cpu_shaded += nrt;
        tb_stat_add(&tb__gr_cpu_shaded, (int64_t)nrt);
        r->st.gpu_shaded += nit;
        tb_stat_add(&tb__gr_gpu_shaded, (int64_t)nit);
        /* Kernel items in chunks; item j's light samples at j * nsamples. */
        for (size_t base = 0; base < nit && !st; base += r->chunk) {
            size_t ni = nit - base < r->chunk ? nit - base : r->chunk;
#pragma omp parallel for schedule(static) num_threads(nthreads)
            for (size_t j = 0; j < ni; j++) {
                size_t a = w.item_of[base + j], p = w.path[a];
                const tb_hit *h = &w.hit[a];
                int mi = w.mat[a];
                tb_gpu_shade_item *item = &r->items[j];
                *item = (tb_gpu_shade_item){.o = w.ray[a].o, .t = h->t, .d = w.ray[a].d, .material = (uint32_t)mi,
                                            .ng = h->ng, .light_base = (uint32_t)(j * (size_t)r->lu_per)};
                if (w.depth[a] < r->rt.max_depth)
                    item->flags |= TB_GPU_SHADE_SPAWN;
                if (r->any_surface && w.sok[a] == 1) {
                    item->flags |= TB_GPU_SHADE_SURFACE;
                    r->surf[j] = w.surf[a];
                }
                const uint8_t mf = r->mflags[mi];
                if (r->nsamples > 0 && (mf & (TB_GPU_MAT_DIFFUSE | TB_GPU_MAT_GGX))) {
                    /* the CPU path's numbers: strata from the sample's stream, the
                     * emitter by the double CDF (tb_area_light_sample) */
                    float u[2 * TB__GR_MAX_LIGHT_SAMPLES];
                    item->flags |= TB_GPU_SHADE_AREA;
                    tb_stratified_2d(&P->rng[p], r->rt.lsx, r->rt.lsy, u);
                    for (int k = 0; k < r->nsamples; k++) {
                        double pmf, ur;
                        int e = tb_distrib1d_sample_discrete(&r->rt.area.select, u[2 * k], &pmf, &ur);
                        float u1r = (float)ur;
                        if (u1r >= 1.0f)
                            u1r = 0x1.fffffep-1f;
                        r->lightu[item->light_base + (uint32_t)k] =
                            (tb_gpu_light_u){(uint32_t)e, u1r, u[2 * k + 1], (float)pmf};
                    }
                }
                /* glossy rays (raytrace.c): below the depth limit, not on a
                 * dielectric; glossy_samples of them at a camera ray's hit,
                 * one deeper; their strata drawn after the light samples */
                if ((mf & TB_GPU_MAT_GGX) && !(mf & TB_GPU_MAT_TRANSMISSION) && w.depth[a] < r->rt.max_depth) {
                    float u[2 * TB__GR_MAX_LIGHT_SAMPLES];
                    int nx = w.depth[a] == 0 ? r->rt.gsx : 1, ny = w.depth[a] == 0 ? r->rt.gsy : 1;
                    item->glossy = (uint32_t)(nx * ny);
                    tb_stratified_2d(&P->rng[p], nx, ny, u);
                    for (int k = 0; k < nx * ny; k++)
                        r->lightu[item->light_base + (uint32_t)(r->nsamples + k)] =
                            (tb_gpu_light_u){0, u[2 * k], u[2 * k + 1], 0.0f};
                }
            }
            st = tb__shade_chunk(r, P, &w, base, ni, ni * (size_t)r->lu_per);
        }
    }
    r->st.wave_seconds += tb__now() - wave0;
    free(w.path), free(w.ray), free(w.depth), free(w.thr), free(w.hit), free(w.item_of), free(w.shadow),
        free(w.shadow_src), free(w.occl), free(w.routed), free(w.mat), free(w.sstart), free(w.mis), free(w.surf),
        free(w.sok);
    return st;
}

/* Allocates the stacks of n paths. */
static tb_status tb__paths_alloc(tb__paths *P, size_t n, int cap, int nch)
{
    memset(P, 0, sizeof *P);
    P->n = n;
    P->cap = cap;
    P->nch = nch;
    P->ray = malloc(n * (size_t)cap * sizeof *P->ray);
    P->depth = malloc(n * (size_t)cap * sizeof *P->depth);
    P->thr = malloc(n * (size_t)cap * (size_t)nch * sizeof *P->thr);
    P->mis = malloc(n * (size_t)cap * sizeof *P->mis);
    P->top = calloc(n ? n : 1, sizeof *P->top);
    if (!P->ray || !P->depth || !P->thr || !P->mis || !P->top)
        return tb_error(TB_ERR_NOMEM, "GPU render: out of memory for %zu paths", n);
    return TB_OK;
}

static void tb__paths_free(tb__paths *P)
{
    free(P->ray), free(P->depth), free(P->thr), free(P->mis), free(P->top);
}

tb_status tb_gpu_radiance(tb_gpu_renderer *r, const tb_ray *rays, tb_rng *rngs, size_t n, float *out)
{
    tb__paths P;
    tb_status st = tb__paths_alloc(&P, n, r->cap_stack, r->nch);
    float one[TB_CHANNELS_MAX];
    for (int c = 0; c < TB_CHANNELS_MAX; c++)
        one[c] = 1.0f;
    if (!st) {
        P.rng = rngs;
        P.L = out;
        memset(out, 0, n * (size_t)r->nch * sizeof *out);
        for (size_t i = 0; i < n; i++)
            tb__push(&P, i, &rays[i], 0, one, NULL);
        st = tb__wavefront(r, &P);
    }
    tb__paths_free(&P);
    return st;
}

/* ------------------------------------------------------------ the render */

/* Host memory for the paths of one wavefront batch (stacks, streams,
 * radiance, the wave's arrays): the batch takes rows of tiles, in the CPU
 * path's order, until its samples would need more (at least one row). */
#define TB__GR_BATCH_BYTES ((size_t)256 << 20)
/* ... and at most this many samples (enough to keep a device busy). */
#define TB__GR_BATCH_MAX 65536

/* A run of rows of one film tile within a batch. */
typedef struct tb__seg {
    int slot;      /* its tile buffer in tiles[] */
    int y0, y1;    /* rows */
    size_t base;   /* its first sample in the batch */
    bool last;     /* the tile's last rows: submit it after this batch */
} tb__seg;

/* ------------------------------------------------- adaptive antialiasing */

/* Adaptive antialiasing makes the CPU path's decisions (antialias.c,
 * tb__render_tile) in rounds: the first round of every pixel of a batch's
 * tiles and of each tile's one-pixel ring, the criterion on the host from
 * the wavefront's values, then a round for every pixel that still needs
 * one, and so on up to max_spp. Each tile evaluates its own ring (as on the
 * CPU path, so ring_samples agree), and every sample keeps the CPU's
 * position, stream and index. */

/* One camera sample to evaluate: its film position, pixel, index in the
 * pixel (its stream) and where its value goes. */
typedef struct tb__aa_req {
    double x, y;
    int px, py;
    uint32_t j;
    float *dst;
} tb__aa_req;

/* The adaptive state of one tile of a batch. */
typedef struct tb__aa_tile {
    tb_film_tile *tile;
    tb_tile_rect r, g;        /* its pixels; with the ring (clipped to the image) */
    float *ring_vals;         /* first-round values of every pixel of g (spp x nch each) */
    unsigned char *ring_flag; /* the first round fails the criterion */
    tb_pixel_sampler *ps;     /* per pixel of r: its sampler (rounds taken) */
    int *n, *cap, *rounds;    /* per pixel: samples so far, room, rounds */
    unsigned char *more;      /* per pixel: another round is due */
    float **vals, **xy;       /* per pixel: values (n x nch) and positions in the pixel (n x 2) */
} tb__aa_tile;

static void tb__aa_tile_free(tb__aa_tile *a)
{
    size_t np = (size_t)(a->r.x1 - a->r.x0) * (size_t)(a->r.y1 - a->r.y0);
    for (size_t i = 0; (a->vals || a->xy) && i < np; i++) {
        if (a->vals)
            free(a->vals[i]);
        if (a->xy)
            free(a->xy[i]);
    }
    tb_film_tile_free(a->tile);
    free(a->ring_vals), free(a->ring_flag), free(a->ps), free(a->n), free(a->cap), free(a->rounds), free(a->more),
        free(a->vals), free(a->xy);
    memset(a, 0, sizeof *a);
}

/* The shared state of an adaptive render. */
typedef struct tb__aa_ctx {
    tb_gpu_renderer *r;
    tb__paths *P;
    const tb_camera *cam;
    const tb_aa_options *aa;
    double *xy;         /* P's film positions (cap) */
    tb_rng *rng, *rng0; /* P's streams (cap) */
    size_t cap;         /* samples per wavefront call */
    int nth, nch, spp, max_spp;
    float lum[TB_FILM_MAX_CHANNELS];
} tb__aa_ctx;

/* Evaluates the samples reqs[0..n) with the wavefront, cap at a time. */
static tb_status tb__aa_eval(tb__aa_ctx *c, const tb__aa_req *reqs, size_t n)
{
    float one[TB_CHANNELS_MAX];
    for (int k = 0; k < TB_CHANNELS_MAX; k++)
        one[k] = 1.0f;
    tb__paths *P = c->P;
    for (size_t b = 0; b < n; b += c->cap) {
        size_t m = n - b < c->cap ? n - b : c->cap;
        /* camera rays as tb_rt_sample makes them (the lens numbers first) */
#pragma omp parallel for schedule(static) num_threads(c->nth)
        for (size_t q = 0; q < m; q++) {
            const tb__aa_req *rq = &reqs[b + q];
            c->xy[2 * q] = rq->x;
            c->xy[2 * q + 1] = rq->y;
            tb_aa_sample_rng(c->aa, rq->px, rq->py, rq->j, &c->rng[q]);
            c->rng0[q] = c->rng[q];
            float lu = 0.5f, lv = 0.5f;
            if (c->cam->lens_radius > 0.0) {
                lu = tb_rng_float(&c->rng[q]);
                lv = tb_rng_float(&c->rng[q]);
            }
            tb_ray ray = tb_camera_ray(c->cam, rq->x, rq->y, lu, lv);
            P->top[q] = 0;
            tb__push(P, q, &ray, 0, one, NULL);
        }
        P->n = m;
        memset(P->L, 0, m * (size_t)c->nch * sizeof *P->L);
        tb_status st = tb__wavefront(c->r, P);
        if (st)
            return st;
#pragma omp parallel for schedule(static) num_threads(c->nth)
        for (size_t q = 0; q < m; q++)
            memcpy(reqs[b + q].dst, P->L + q * (size_t)c->nch, sizeof(float) * (size_t)c->nch);
    }
    return TB_OK;
}

/* Makes room for `need` samples of pixel i of tile a. */
static bool tb__aa_reserve(tb__aa_tile *a, size_t i, int need, int max_spp, int nch)
{
    if (need <= a->cap[i])
        return true;
    int nc = a->cap[i] * 2 > need ? a->cap[i] * 2 : need;
    if (nc > max_spp)
        nc = max_spp;
    float *v = realloc(a->vals[i], (size_t)nc * (size_t)nch * sizeof *v);
    if (!v)
        return false;
    a->vals[i] = v;
    float *xy = realloc(a->xy[i], (size_t)nc * 2 * sizeof *xy);
    if (!xy)
        return false;
    a->xy[i] = xy;
    a->cap[i] = nc;
    return true;
}

/* Renders tiles tl[0..nt) (created, in index order) adaptively and splats
 * them; stats into *as. */
static tb_status tb__aa_batch(tb__aa_ctx *c, const tb_film *film, tb__aa_tile *tl, int nt, tb_aa_stats *as)
{
    const int spp = c->spp, nch = c->nch, W = tb_film_width(film), H = tb_film_height(film);
    const tb_aa_options *aa = c->aa;
    size_t nreq = 0;
    for (int k = 0; k < nt; k++) {
        tb__aa_tile *a = &tl[k];
        a->r = tb_film_tile_pixels(a->tile);
        a->g = (tb_tile_rect){a->r.x0 > 0 ? a->r.x0 - 1 : 0, a->r.y0 > 0 ? a->r.y0 - 1 : 0,
                              a->r.x1 < W ? a->r.x1 + 1 : a->r.x1, a->r.y1 < H ? a->r.y1 + 1 : a->r.y1};
        size_t ng = (size_t)(a->g.x1 - a->g.x0) * (size_t)(a->g.y1 - a->g.y0);
        size_t np = (size_t)(a->r.x1 - a->r.x0) * (size_t)(a->r.y1 - a->r.y0);
        a->ring_vals = malloc(ng * (size_t)spp * (size_t)nch * sizeof *a->ring_vals);
        a->ring_flag = malloc(ng);
        a->ps = malloc(np * sizeof *a->ps);
        a->n = calloc(np, sizeof *a->n);
        a->cap = calloc(np, sizeof *a->cap);
        a->rounds = calloc(np, sizeof *a->rounds);
        a->more = calloc(np, 1);
        a->vals = calloc(np, sizeof *a->vals);
        a->xy = calloc(np, sizeof *a->xy);
        if (!a->ring_vals || !a->ring_flag || !a->ps || !a->n || !a->cap || !a->rounds || !a->more || !a->vals ||
            !a->xy)
            return tb_error(TB_ERR_NOMEM, "GPU render: out of memory for adaptive antialiasing");
        nreq += ng * (size_t)spp;
    }
    tb__aa_req *reqs = malloc((nreq ? nreq : 1) * sizeof *reqs);
    float *pxy = malloc((size_t)spp * 2 * sizeof *pxy);
    tb_status st = reqs && pxy ? TB_OK : tb_error(TB_ERR_NOMEM, "GPU render: out of memory for adaptive antialiasing");
    /* the first round of every pixel of each tile and its ring */
    size_t q = 0;
    for (int k = 0; k < nt && !st; k++) {
        tb__aa_tile *a = &tl[k];
        int gw = a->g.x1 - a->g.x0, rw = a->r.x1 - a->r.x0;
        for (int py = a->g.y0; py < a->g.y1 && !st; py++)
            for (int px = a->g.x0; px < a->g.x1; px++) {
                size_t gi = (size_t)(py - a->g.y0) * (size_t)gw + (size_t)(px - a->g.x0);
                bool own = px >= a->r.x0 && px < a->r.x1 && py >= a->r.y0 && py < a->r.y1;
                tb_pixel_sampler tmp, *ps = &tmp;
                float *xy = pxy;
                if (own) {
                    size_t i = (size_t)(py - a->r.y0) * (size_t)rw + (size_t)(px - a->r.x0);
                    if (!tb__aa_reserve(a, i, spp, c->max_spp, nch)) {
                        st = tb_error(TB_ERR_NOMEM, "GPU render: out of memory for adaptive antialiasing");
                        break;
                    }
                    ps = &a->ps[i];
                    xy = a->xy[i];
                } else {
                    as->ring_samples += (uint64_t)spp;
                }
                tb_pixel_sampler_init(ps, aa, px, py);
                tb_pixel_sampler_round(ps, xy);
                for (int j = 0; j < spp; j++)
                    reqs[q++] = (tb__aa_req){(double)px + (double)xy[2 * j], (double)py + (double)xy[2 * j + 1],
                                             px, py, (uint32_t)j,
                                             a->ring_vals + (gi * (size_t)spp + (size_t)j) * (size_t)nch};
            }
    }
    if (!st)
        st = tb__aa_eval(c, reqs, q);
    /* the criterion on the first rounds; a pixel refines if its own first
     * round or a neighbour's fails it */
    if (!st) {
#pragma omp parallel for schedule(dynamic, 1) num_threads(c->nth)
        for (int k = 0; k < nt; k++) {
            tb__aa_tile *a = &tl[k];
            int gw = a->g.x1 - a->g.x0, rw = a->r.x1 - a->r.x0;
            size_t ng = (size_t)gw * (size_t)(a->g.y1 - a->g.y0);
            for (size_t gi = 0; gi < ng; gi++)
                a->ring_flag[gi] =
                    tb_aa_needs_more(aa, nch, c->lum, a->ring_vals + gi * (size_t)spp * (size_t)nch, spp);
            for (int py = a->r.y0; py < a->r.y1; py++)
                for (int px = a->r.x0; px < a->r.x1; px++) {
                    size_t i = (size_t)(py - a->r.y0) * (size_t)rw + (size_t)(px - a->r.x0);
                    size_t gi = (size_t)(py - a->g.y0) * (size_t)gw + (size_t)(px - a->g.x0);
                    memcpy(a->vals[i], a->ring_vals + gi * (size_t)spp * (size_t)nch,
                           sizeof(float) * (size_t)spp * (size_t)nch);
                    a->n[i] = spp;
                    a->rounds[i] = 1;
                    bool more = false;
                    for (int dy = -1; dy <= 1 && !more; dy++)
                        for (int dx = -1; dx <= 1 && !more; dx++) {
                            int qx = px + dx, qy = py + dy;
                            if (qx >= a->g.x0 && qx < a->g.x1 && qy >= a->g.y0 && qy < a->g.y1)
                                more = a->ring_flag[(size_t)(qy - a->g.y0) * (size_t)gw + (size_t)(qx - a->g.x0)];
                        }
                    a->more[i] = more && spp + spp <= c->max_spp;
                }
        }
    }
    /* further rounds for the pixels that need them, until none does */
    while (!st) {
        q = 0;
        for (int k = 0; k < nt && !st; k++) {
            tb__aa_tile *a = &tl[k];
            int rw = a->r.x1 - a->r.x0;
            size_t np = (size_t)rw * (size_t)(a->r.y1 - a->r.y0);
            for (size_t i = 0; i < np; i++) {
                if (!a->more[i])
                    continue;
                int n = a->n[i], px = a->r.x0 + (int)(i % (size_t)rw), py = a->r.y0 + (int)(i / (size_t)rw);
                if (!tb__aa_reserve(a, i, n + spp, c->max_spp, nch)) {
                    st = tb_error(TB_ERR_NOMEM, "GPU render: out of memory for adaptive antialiasing");
                    break;
                }
                tb_pixel_sampler_round(&a->ps[i], a->xy[i] + 2 * (size_t)n);
                for (int j = n; j < n + spp; j++)
                    reqs[q++] = (tb__aa_req){(double)px + (double)a->xy[i][2 * j],
                                             (double)py + (double)a->xy[i][2 * j + 1], px, py, (uint32_t)j,
                                             a->vals[i] + (size_t)j * (size_t)nch};
            }
        }
        if (st || q == 0)
            break;
        if ((st = tb__aa_eval(c, reqs, q)))
            break;
#pragma omp parallel for schedule(dynamic, 1) num_threads(c->nth)
        for (int k = 0; k < nt; k++) {
            tb__aa_tile *a = &tl[k];
            size_t np = (size_t)(a->r.x1 - a->r.x0) * (size_t)(a->r.y1 - a->r.y0);
            for (size_t i = 0; i < np; i++) {
                if (!a->more[i])
                    continue;
                int n = a->n[i] += spp;
                a->rounds[i]++;
                a->more[i] = tb_aa_needs_more(aa, nch, c->lum, a->vals[i], n) && n + spp <= c->max_spp;
            }
        }
    }
    free(reqs), free(pxy);
    if (st)
        return st;
    /* splat in the CPU path's order: pixels in scanline order, each with
     * weight 1 / (its sample count) */
    uint64_t samples = 0, pixels = 0, refined = 0;
    int max_used = 0;
#pragma omp parallel for schedule(dynamic, 1) num_threads(c->nth) reduction(+ : samples, pixels, refined) \
    reduction(max : max_used)
    for (int k = 0; k < nt; k++) {
        tb__aa_tile *a = &tl[k];
        int rw = a->r.x1 - a->r.x0;
        size_t np = (size_t)rw * (size_t)(a->r.y1 - a->r.y0);
        for (size_t i = 0; i < np; i++) {
            int n = a->n[i], px = a->r.x0 + (int)(i % (size_t)rw), py = a->r.y0 + (int)(i / (size_t)rw);
            double wt = 1.0 / (double)n;
            for (int j = 0; j < n; j++)
                tb_film_tile_add(a->tile, (double)px + (double)a->xy[i][2 * j],
                                 (double)py + (double)a->xy[i][2 * j + 1], a->vals[i] + (size_t)j * (size_t)nch, wt);
            tb_film_tile_record_samples(a->tile, px, py, (uint32_t)n);
            samples += (uint64_t)n;
            pixels++;
            refined += a->rounds[i] > 1;
            max_used = n > max_used ? n : max_used;
        }
    }
    as->samples += samples;
    as->pixels += pixels;
    as->pixels_refined += refined;
    if (max_used > as->max_spp_used)
        as->max_spp_used = max_used;
    return TB_OK;
}

tb_status tb_gpu_render_raytrace(tb_gpu_device *dev, const tb_scene *s, const tb_render_options *o,
                                 tb_image **out, tb_render_stats *stats, tb_gpu_render_stats *gstats)
{
    *out = NULL;
    tb_render_stats rs;
    memset(&rs, 0, sizeof rs);
    if (o->passes < 1)
        return tb_error(TB_ERR_ARG, "render: passes must be at least 1");
    tb_status err = tb_aa_check(&o->aa);
    if (err)
        return err;
    tb_gpu_renderer *r;
    if ((err = tb_gpu_renderer_create(dev, s, &o->rt, &r)))
        return err;
    r->threads = o->threads;
    const int nch = s->nchannels;
    tb_film_desc fd = {.width = s->camera.width, .height = s->camera.height, .channels = nch, .filter = &o->filter};
    tb_film *film = tb_film_create(&fd);
    int ntiles = film ? tb_film_tile_count(film) : 0;
    int spp = o->aa.spp;
    tb_tile_rect t0r = film ? tb_film_tile_rect(film, 0) : (tb_tile_rect){0};
    const size_t tw = (size_t)(t0r.x1 - t0r.x0), th = (size_t)(t0r.y1 - t0r.y0);
    const int cap_stack = r->cap_stack;
    /* bytes per path: stack entries (ray, depth, MIS context, throughput),
     * streams, film position, radiance, and the wave's copies and surface
     * records */
    size_t per_path =
        (size_t)cap_stack * (sizeof(tb_ray) + sizeof(int) + sizeof(tb_rt_mis) + (size_t)nch * sizeof(float)) +
        2 * sizeof(tb_rng) + 2 * sizeof(double) + 2 * (size_t)nch * sizeof(float) + sizeof(tb_ray) + sizeof(tb_hit) +
        sizeof(tb_rt_mis) + 4 * sizeof(size_t) + 2 * sizeof(int) + (r->any_surface ? sizeof(tb_gpu_surface) + 1 : 0);
    size_t budget = TB__GR_BATCH_BYTES / per_path;
    if (budget > TB__GR_BATCH_MAX)
        budget = TB__GR_BATCH_MAX;
    size_t row_samples = tw * (size_t)spp;
    size_t cap = budget > row_samples ? budget - budget % row_samples : row_samples; /* whole rows */
    if (o->aa.adaptive)
        cap = budget; /* adaptive rounds go through the wavefront in pieces of any size */
    int max_slots = (int)(cap / row_samples / (th ? th : 1)) + 2; /* tiles a batch can touch */
    size_t max_segs = cap / row_samples + 2;
    tb__paths P = {0};
    tb_film_tile **tiles = calloc((size_t)max_slots, sizeof *tiles);
    tb__seg *segs = malloc(max_segs * sizeof *segs);
    double *xy = malloc(cap * 2 * sizeof *xy);
    tb_rng *rng = malloc(cap * sizeof *rng), *rng0 = malloc(cap * sizeof *rng0);
    int maxth = omp_get_max_threads() > o->threads ? omp_get_max_threads() : o->threads;
    float *L = malloc(cap * (size_t)nch * sizeof *L);
    float *pxys = malloc((size_t)maxth * (size_t)spp * 2 * sizeof *pxys); /* per thread: a pixel's positions */
    if (!film || !tiles || !segs || !xy || !rng || !rng0 || !L || !pxys)
        err = tb_error(TB_ERR_NOMEM, "GPU render: out of memory");
    if (!err)
        err = tb__paths_alloc(&P, cap, cap_stack, nch);
    P.rng = rng;
    P.rng0 = rng0;
    P.xy = xy;
    P.L = L;
    float one[TB_CHANNELS_MAX];
    for (int c = 0; c < TB_CHANNELS_MAX; c++)
        one[c] = 1.0f;
    const tb_camera *cam = &s->camera;
    const int nth = o->threads > 0 ? o->threads : omp_get_max_threads();
    double tstart = tb__now();
    tb_progress prog;
    bool use_prog = o->progress && film &&
                    tb_progress_start(&prog, "render", (int64_t)fd.width * fd.height * o->passes, NULL, 0) == TB_OK;
    tb_aa_options aa = o->aa;
    bool stop = o->cancel && atomic_load(o->cancel);
    for (int pass = 0; pass < o->passes && !err && !stop; pass++) {
        aa.pass = o->aa.pass + (uint32_t)pass;
        if (pass > 0 && (err = tb_film_begin_pass(film)))
            break;
        if (aa.adaptive) {
            /* batches of whole tiles whose first rounds (with their rings)
             * fit one wavefront call (at least one tile) */
            tb__aa_ctx ac = {.r = r, .P = &P, .cam = cam, .aa = &aa, .xy = xy, .rng = rng, .rng0 = rng0, .cap = cap,
                             .nth = nth, .nch = nch, .spp = spp, .max_spp = tb_aa_max_spp(&aa)};
            tb_aa_luminance_weights(nch, ac.lum);
            tb__aa_tile *tl = calloc((size_t)(ntiles > 0 ? ntiles : 1), sizeof *tl);
            if (!tl) {
                err = tb_error(TB_ERR_NOMEM, "GPU render: out of memory");
                break;
            }
            int t = 0;
            while (t < ntiles && !err) {
                stop = stop || (o->cancel && atomic_load(o->cancel)) ||
                       (o->time_budget > 0.0 && tb__now() - tstart > o->time_budget);
                if (stop) {
                    for (int k = t; k < ntiles; k++)
                        tb_film_tile_skip(film, k);
                    rs.aa.tiles_skipped += ntiles - t;
                    rs.interrupted = true;
                    break;
                }
                int nt = 0;
                size_t first = 0;
                while (t + nt < ntiles) {
                    tb_tile_rect rc = tb_film_tile_rect(film, t + nt);
                    size_t ring = (size_t)(rc.x1 - rc.x0 + 2) * (size_t)(rc.y1 - rc.y0 + 2) * (size_t)spp;
                    if (nt > 0 && first + ring > cap)
                        break;
                    if (!(tl[nt].tile = tb_film_tile_create(film, t + nt))) {
                        err = TB_ERR_NOMEM;
                        break;
                    }
                    first += ring;
                    nt++;
                }
                if (!err)
                    err = tb__aa_batch(&ac, film, tl, nt, &rs.aa);
                for (int k = 0; k < nt; k++) {
                    if (!err) {
                        tb_tile_rect rc = tl[k].r;
                        if (use_prog)
                            tb_progress_add(&prog, (int64_t)(rc.x1 - rc.x0) * (rc.y1 - rc.y0));
                        err = tb_film_tile_submit(film, tl[k].tile);
                        tl[k].tile = NULL;
                    }
                    tb__aa_tile_free(&tl[k]);
                }
                t += nt;
            }
            free(tl);
            if (err || stop)
                break;
            rs.passes_done++;
            if (o->on_pass && o->on_pass(o->on_pass_ctx, pass, spp * (pass + 1), tb__now() - tstart, film))
                break;
            continue;
        }
        /* t: the tile being filled, row: its next row (tiles[0] is its buffer
         * when a batch starts in its middle) */
        int t = 0, row = ntiles > 0 ? tb_film_tile_rect(film, 0).y0 : 0;
        while (t < ntiles && !err) {
            stop = stop || (o->cancel && atomic_load(o->cancel)) ||
                   (o->time_budget > 0.0 && tb__now() - tstart > o->time_budget);
            if (stop) {
                /* a tile cut short is skipped whole, as the CPU path skips tiles */
                tb_film_tile_free(tiles[0]);
                tiles[0] = NULL;
                for (int k = t; k < ntiles; k++)
                    tb_film_tile_skip(film, k);
                rs.aa.tiles_skipped += ntiles - t;
                rs.interrupted = true;
                break;
            }
            /* the batch: rows of tiles in order, whole rows, at most cap
             * samples; a tile begun in the previous batch is in tiles[0] */
            int nseg = 0, nslot = tiles[0] ? 1 : 0;
            size_t np = 0;
            while (t < ntiles && np + row_samples <= cap) {
                tb_tile_rect rc = tb_film_tile_rect(film, t);
                int slot = 0;
                if (row == rc.y0) {
                    if (nslot == max_slots)
                        break;
                    if (!(tiles[nslot] = tb_film_tile_create(film, t))) {
                        err = TB_ERR_NOMEM;
                        break;
                    }
                    slot = nslot++;
                }
                size_t rs_ = (size_t)(rc.x1 - rc.x0) * (size_t)spp;
                size_t fit = (cap - np) / rs_;
                int y1 = fit >= (size_t)(rc.y1 - row) ? rc.y1 : row + (int)fit;
                segs[nseg++] = (tb__seg){slot, row, y1, np, y1 == rc.y1};
                np += (size_t)(y1 - row) * rs_;
                if (y1 < rc.y1) {
                    row = y1;
                    break; /* the batch is full in this tile's middle */
                }
                t++;
                row = t < ntiles ? tb_film_tile_rect(film, t).y0 : 0;
            }
            if (err)
                break;
            /* camera rays, in the CPU path's order */
#pragma omp parallel for schedule(dynamic, 1) num_threads(nth)
            for (int g = 0; g < nseg; g++) {
                const tb__seg *sg = &segs[g];
                tb_tile_rect rc = tb_film_tile_pixels(tiles[sg->slot]);
                size_t q = sg->base;
                float *pxy = pxys + (size_t)omp_get_thread_num() * 2 * (size_t)spp;
                for (int py = sg->y0; py < sg->y1; py++)
                    for (int px = rc.x0; px < rc.x1; px++) {
                        tb_pixel_sampler ps;
                        tb_pixel_sampler_init(&ps, &aa, px, py);
                        int ns = tb_pixel_sampler_round(&ps, pxy);
                        for (int j = 0; j < ns; j++, q++) {
                            double x = (double)px + (double)pxy[2 * j], y = (double)py + (double)pxy[2 * j + 1];
                            xy[2 * q] = x;
                            xy[2 * q + 1] = y;
                            tb_aa_sample_rng(&aa, px, py, (uint32_t)j, &rng[q]);
                            rng0[q] = rng[q];
                            float lu = 0.5f, lv = 0.5f;
                            if (cam->lens_radius > 0.0) {
                                lu = tb_rng_float(&rng[q]);
                                lv = tb_rng_float(&rng[q]);
                            }
                            tb_ray ray = tb_camera_ray(cam, x, y, lu, lv);
                            P.top[q] = 0;
                            tb__push(&P, q, &ray, 0, one, NULL);
                        }
                    }
            }
            P.n = np;
            memset(L, 0, np * (size_t)nch * sizeof *L);
            if ((err = tb__wavefront(r, &P)))
                break;
            /* splat in the CPU path's order (each tile its own buffer: the
             * segments of a batch are in distinct tiles), tiles merged in
             * index order */
#pragma omp parallel for schedule(dynamic, 1) num_threads(nth)
            for (int g = 0; g < nseg; g++) {
                const tb__seg *sg = &segs[g];
                tb_tile_rect rc = tb_film_tile_pixels(tiles[sg->slot]);
                size_t q = sg->base;
                double wt = 1.0 / (double)spp;
                for (int py = sg->y0; py < sg->y1; py++)
                    for (int px = rc.x0; px < rc.x1; px++) {
                        for (int j = 0; j < spp; j++, q++)
                            tb_film_tile_add(tiles[sg->slot], xy[2 * q], xy[2 * q + 1], L + q * (size_t)nch, wt);
                        tb_film_tile_record_samples(tiles[sg->slot], px, py, (uint32_t)spp);
                    }
            }
            int keep = -1; /* a tile left unfinished moves to slot 0 for the next batch */
            for (int g = 0; g < nseg; g++) {
                tb__seg *sg = &segs[g];
                tb_tile_rect rc = tb_film_tile_pixels(tiles[sg->slot]);
                rs.aa.pixels += (uint64_t)(rc.x1 - rc.x0) * (uint64_t)(sg->y1 - sg->y0);
                if (use_prog)
                    tb_progress_add(&prog, (int64_t)(rc.x1 - rc.x0) * (sg->y1 - sg->y0));
                if (!sg->last) {
                    keep = sg->slot;
                    continue;
                }
                tb_status e2 = tb_film_tile_submit(film, tiles[sg->slot]);
                tiles[sg->slot] = NULL;
                if (e2 && !err)
                    err = e2;
            }
            if (keep > 0) {
                tiles[0] = tiles[keep];
                tiles[keep] = NULL;
            }
            rs.aa.samples += np;
        }
        if (err || stop)
            break;
        rs.passes_done++;
        if (o->on_pass && o->on_pass(o->on_pass_ctx, pass, spp * (pass + 1), tb__now() - tstart, film))
            break;
    }
    for (int k = 0; k < max_slots && tiles; k++)
        tb_film_tile_free(tiles[k]);
    if (!o->aa.adaptive)
        rs.aa.max_spp_used = spp;
    rs.seconds = tb__now() - tstart;
    if (use_prog)
        tb_progress_finish(&prog);
    if (!err) {
        *out = tb_render_resolve(s, film);
        if (!*out)
            err = TB_ERR_NOMEM;
    }
    if (!err && o->sample_counts)
        tb_render_sample_counts(film, o->sample_counts);
    r->st.samples += rs.aa.samples;
    if (gstats)
        *gstats = r->st;
    if (stats)
        *stats = rs;
    tb__paths_free(&P);
    free(tiles), free(segs), free(xy), free(rng), free(rng0), free(L), free(pxys);
    tb_film_free(film);
    tb_gpu_renderer_destroy(r);
    return err;
}
