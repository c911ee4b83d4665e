/* The Vulkan path tracer (pathtrace.h, docs/gpu.md "Path tracer"): tables and
 * path-state buffers on the device, the stage dispatches of
 * shaders/pathtrace.comp, and the render on host/render's pass driver. */
#include "host/gpu/pathtrace.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "host/gpu/intersect.h"
#include "host/gpu/render_internal.h"
#include "host/gpu/spirv.h"
#include "host/object/param.h"
#include "host/render/antialias.h"
#include "host/render/camera.h"
#include "host/render/features.h"
#include "host/render/lights.h"
#include "host/render/render_internal.h"
#include "host/render/sampling.h"
#include "host/render/surface.h"
#include "host/render/texture.h"
#include "shaders/shared/hit.h"
#include "shaders/shared/pathtrace.h"
#include "shaders/shared/ray.h"
#include "shaders/shared/shade.h"
#include "util/math/rng.h"
#include "util/stats/stats.h"

TB_STAT_COUNTER(tb__gpt_paths, "GPU path tracer/paths");
TB_STAT_COUNTER(tb__gpt_submits, "GPU path tracer/command buffers");

/* Paths per device batch (the buffers are sized for it once). */
#define TB__GPT_BATCH 65536u
/* Most bytes of the channel-value buffer (TB_GPU_PT_NVALUES + lights arrays of nch). */
#define TB__GPT_VALUES_MAX ((size_t)64 << 20)
/* Specialization constants of pathtrace.comp besides the stage (ids 2 .. 16). */
#define TB__GPT_SPEC 15
/* Most distance, in (u, v), between a polygon face's parameters and the
 * affine map fitted to them (the map is refused beyond it). */
#define TB__GPT_UV_FIT 1e-5

struct tb_gpu_pathtracer {
    tb_gpu_device *dev;
    const tb_scene *scene;
    tb_gpu_scene *gscene;
    tb_gpu_scene_bindings bind;
    tb_pt_options opt;
    int nch;
    size_t cap; /* paths per batch */
    uint32_t light_base; /* the table word of the first delta light */
    tb_gpu_buffer *b_rays, *b_states, *b_hits, *b_values, *b_shadows, *b_emitters, *b_table;
    tb_gpu_kernel *k[TB_GPU_PT_STAGES]; /* per TB_GPU_PT_STAGE_* */
    tb_gpu_pt_state *states; /* host staging of one batch */
    float *L;                /* host copy of one batch's radiance (word-major) */
    tb_gpu_pt_stats st;
    bool patterns;       /* some material has a colour pattern or a bump map (the kernel's HAS_PATTERNS) */
    uint32_t pattern_kinds; /* bit per TB_GPU_PATTERN_* */
    uint32_t perm_base;  /* the table word of Perlin's permutation */
};

static double tb__gpt_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* True if material m (an index, possibly none) has a colour pattern or a
 * bump map the kernel evaluates (a Lambert material's specular pattern is
 * ignored, as tb_surface_at ignores its specular colour). */
static bool tb__gpt_patterned(const tb_scene *s, int m)
{
    if (m < 0 || m >= s->nmaterials)
        return false;
    const tb_material *mt = &s->materials[m];
    return mt->diffuse_pattern->kind != TB_MID_PATTERN_NONE || mt->bump->kind != TB_MID_PATTERN_NONE ||
           (mt->specular_pattern->kind != TB_MID_PATTERN_NONE && mt->model != TB_MID_MODEL_LAMBERT);
}

/* Why object o's patterns are not in the kernel, or NULL: the device has
 * the (u, v) parameterisation of top-level spheres, cubes and polygons
 * only (a polygon face whose (u, v) is not affine is refused when the
 * tables are built: tb__gpt_param_record). */
static const char *tb__gpt_pattern_object(const tb_scene *s, const tb_object *o)
{
    if (tb_prim_is_csg(o->kind)) {
        for (int i = 0; i < o->nchildren; i++) {
            const tb_object *c = &o->children[i];
            if (tb_prim_is_csg(c->kind) ? tb__gpt_pattern_object(s, c) != NULL : tb__gpt_patterned(s, c->material))
                return "patterns or bump maps on a CSG tree's leaves are not in the kernel";
        }
        return NULL;
    }
    if (!tb__gpt_patterned(s, o->material))
        return NULL;
    if (o->nchildren > 0 || (o->kind != TB_PRIM_SPHERE && o->kind != TB_PRIM_CUBE && o->kind != TB_PRIM_POLYGONS))
        return "patterns or bump maps on objects other than spheres, cubes and polygons are not in the kernel "
               "(their (u, v) parameterisation is not ported)";
    return NULL;
}

const char *tb_gpu_pt_unsupported(const tb_scene *s)
{
    if (s->nlights > (int)TB_GPU_PT_MAX_SLOTS - 1)
        return "more than 31 point, spot and directional lights (the kernel has a shadow-ray slot per light)";
    for (int i = 0; i < s->nlights; i++)
        if (s->lights[i].ies)
            return "IES light distributions are not in the path-tracing kernel";
    for (int i = 0; i < s->nmaterials; i++) {
        const tb_material *m = &s->materials[i];
        if (m->diffuse_texture || m->specular_texture || m->transmission_texture || m->emission_texture)
            return "image textures are not in the kernel";
        if (m->bump->kind == TB_MID_PATTERN_IMAGE)
            return "bump maps from images are not in the kernel";
    }
    for (int i = 0; i < s->nemitters; i++) {
        const tb_emitter *e = &s->emitters[i];
        if (e->kind == TB_EMITTER_CUSTOM)
            return "custom emitters are not in the kernel";
        if (e->kind == TB_EMITTER_SPHERE && e->two_sided)
            return "two-sided sphere emitters are not in the kernel";
    }
    uint32_t *of = malloc((s->nobjects ? s->nobjects : 1) * sizeof *of);
    if (!of)
        return "out of memory";
    tb_object_features(s, of);
    const char *why = NULL;
    for (uint32_t i = 0; i < s->nobjects && !why; i++) {
        const bool csg = (of[i] & (TB_OBJ_FEAT_CSG_UNION | TB_OBJ_FEAT_CSG_INTERSECTION |
                                   TB_OBJ_FEAT_CSG_DIFFERENCE)) != 0;
        if (!csg && (s->objects[i]->material < 0 || s->objects[i]->material >= s->nmaterials))
            why = "an object without a material";
        else
            why = tb__gpt_pattern_object(s, s->objects[i]);
    }
    /* An emitting CSG object's emitters are facets of its tessellation,
     * pushed off the exact surface: the CPU counts a light sample by what
     * the exact geometry shows along its direction, which a shadow ray to
     * the facet point does not reproduce. */
    for (int k = 0; k < s->nemissive && !why; k++)
        if (tb_prim_is_csg(s->objects[s->emissive[k].object]->kind))
            why = "emitting CSG objects are not in the kernel (their area light is tessellated)";
    free(of);
    return why;
}

void tb_gpu_pt_destroy(tb_gpu_pathtracer *pt)
{
    if (!pt)
        return;
    tb_gpu_buffer *bs[] = {pt->b_rays,    pt->b_states,    pt->b_hits, pt->b_values,
                           pt->b_shadows, pt->b_emitters, pt->b_table};
    for (size_t i = 0; i < sizeof bs / sizeof *bs; i++)
        tb_gpu_buffer_destroy(bs[i]);
    tb_gpu_scene_destroy(pt->gscene);
    free(pt->states);
    free(pt->L);
    free(pt);
}

/* Material index m as the kernel reads it: UINT32_MAX for none (the path
 * ends there, as tb_surface_at fails on the CPU). */
static uint32_t tb__gpt_material_index(const tb_scene *s, int m)
{
    return m >= 0 && m < s->nmaterials ? (uint32_t)m : UINT32_MAX;
}

/* The leaves of CSG tree o (0 for a primitive at the top level: its
 * material is the object's): with `range`, per leaf its first face, face
 * count and material index (UINT32_MAX for none), in pre-order. */
static size_t tb__gpt_leaves_rec(const tb_scene *s, const tb_object *o, uint32_t *range, size_t k)
{
    if (!tb_prim_is_csg(o->kind)) {
        if (range) {
            range[3 * k] = o->face_base;
            range[3 * k + 1] = o->nfaces;
            range[3 * k + 2] = tb__gpt_material_index(s, o->material);
        }
        return k + 1;
    }
    for (int i = 0; i < o->nchildren; i++)
        k = tb__gpt_leaves_rec(s, &o->children[i], range, k);
    return k;
}

/* Material mt's scalar words (shared/pathtrace.h, TB_GPU_PT_M_*): the lobes
 * and selection probabilities of tb_surface_bsdf_init in TB_SURFACE_PHYSICAL
 * mode (the kernel takes no textures, patterns or bump maps, so they are the
 * same at every point of the material). */
static void tb__gpt_material(const tb_scene *s, const tb_material *mt, float *w)
{
    tb_surface sf;
    memset(&sf, 0, sizeof sf);
    sf.n = sf.nv = sf.ng = (tb_vec3){0.0f, 0.0f, 1.0f};
    sf.model = mt->model;
    sf.exponent = mt->exponent;
    sf.roughness = mt->roughness;
    sf.ior = mt->ior;
    sf.diffuse = mt->diffuse;
    /* as tb_surface_at: model lambert has no specular lobe */
    sf.specular = mt->model == TB_MID_MODEL_LAMBERT ? tb_channels_splat(s->nchannels, 0.0f) : mt->specular;
    sf.transmission = mt->transmission;
    tb_surface_bsdf b;
    tb_surface_bsdf_init(&sf, TB_SURFACE_PHYSICAL, &b);
    _Static_assert(TB_LOBE_DIFFUSE == 1u << TB_GPU_PT_LOBE_DIFFUSE && TB_LOBE_GLOSSY == 1u << TB_GPU_PT_LOBE_GLOSSY &&
                       TB_LOBE_MIRROR == 1u << TB_GPU_PT_LOBE_MIRROR &&
                       TB_LOBE_DIELECTRIC == 1u << TB_GPU_PT_LOBE_DIELECTRIC,
                   "the kernel's lobe bits are tb_lobe's");
    uint32_t lobes = b.lobes, glossy = TB_GPU_PT_GLOSSY_NONE;
    if (lobes & TB_LOBE_GLOSSY)
        glossy = b.glossy.kind == TB_BSDF_BLINN_NORMALIZED_EXACT ? TB_GPU_PT_GLOSSY_BLINN
                 : b.glossy.kind == TB_BSDF_PHONG_NORMALIZED     ? TB_GPU_PT_GLOSSY_PHONG
                 : b.glossy.kind == TB_BSDF_GGX                  ? TB_GPU_PT_GLOSSY_GGX
                                                                 : TB_GPU_PT_GLOSSY_NONE;
    else if (mt->model != TB_MID_MODEL_LAMBERT) /* the lobe a specular pattern may switch on at a point */
        glossy = mt->model == TB_MID_MODEL_GGX     ? TB_GPU_PT_GLOSSY_GGX
                 : mt->model == TB_MID_MODEL_BLINN ? TB_GPU_PT_GLOSSY_BLINN
                                                   : TB_GPU_PT_GLOSSY_PHONG;
    for (int k = 0; k < 4; k++)
        w[TB_GPU_PT_M_PICK + (uint32_t)k] = b.pick[k];
    w[TB_GPU_PT_M_DIELECTRIC] = b.dielectric;
    w[TB_GPU_PT_M_EXPONENT] = (float)mt->exponent;
    w[TB_GPU_PT_M_IOR] = (float)mt->ior;
    memcpy(&w[TB_GPU_PT_M_GLOSSY], &glossy, sizeof glossy); /* uints in the float table */
    memcpy(&w[TB_GPU_PT_M_LOBES], &lobes, sizeof lobes);
    w[TB_GPU_PT_M_ALPHA] = (float)fmax(mt->roughness, TB_GGX_ALPHA_MIN); /* tb__alpha of shading.c */
    const uint32_t none = TB_GPU_PT_NONE;
    memcpy(&w[TB_GPU_PT_M_PATTERNS], &none, sizeof none);
}

/* The table's words after the fixed part (patterns, the permutation,
 * parameterisation records), grown as they are added. */
typedef struct tb__gpt_words {
    float *w;
    size_t n, cap, base; /* base: the table word of w[0] */
    bool nomem;
} tb__gpt_words;

/* Appends k words (zero) and returns their first index in x->w (0 when out of memory: check x->nomem). */
static size_t tb__gpt_grow(tb__gpt_words *x, size_t k)
{
    if (x->n + k > x->cap) {
        size_t cap = x->cap ? 2 * x->cap : 1024;
        while (cap < x->n + k)
            cap *= 2;
        float *w = realloc(x->w, cap * sizeof *w);
        if (!w) {
            x->nomem = true;
            return 0;
        }
        x->w = w;
        x->cap = cap;
    }
    memset(x->w + x->n, 0, k * sizeof *x->w);
    x->n += k;
    return x->n - k;
}

static void tb__gpt_put_u32(float *w, uint32_t v) { memcpy(w, &v, sizeof v); }

/* Material mt's pattern records (TB_GPU_PT_P_WORDS each: diffuse, specular,
 * bump) and their colours; returns the table word of the first. */
static uint32_t tb__gpt_patterns(tb__gpt_words *x, const tb_material *mt, int nch, uint32_t *kinds)
{
    const size_t at = tb__gpt_grow(x, 3 * TB_GPU_PT_P_WORDS);
    const tb_material_pattern *pats[3] = {mt->diffuse_pattern, mt->specular_pattern, mt->bump};
    _Static_assert(TB_GPU_PATTERN_DIFFUSE == 0 && TB_GPU_PATTERN_SPECULAR == 1 && TB_GPU_PATTERN_BUMP == 2,
                   "the record order is the shade kernel's pattern slots");
    for (int k = 0; k < 3 && !x->nomem; k++) {
        const tb_material_pattern *pt = pats[k];
        if (!pt->kind || (k == 1 && mt->model == TB_MID_MODEL_LAMBERT))
            continue;
        const uint32_t kind = pt->kind == TB_MID_PATTERN_CHECKER ? TB_GPU_PATTERN_CHECKER : TB_GPU_PATTERN_NOISE;
        *kinds |= 1u << kind;
        size_t col = 0;
        if (k < 2) {
            col = tb__gpt_grow(x, 2 * (size_t)nch);
            for (int c = 0; c < nch && !x->nomem; c++) {
                x->w[col + (size_t)c] = pt->a.v[c];
                x->w[col + (size_t)nch + (size_t)c] = pt->b.v[c];
            }
        }
        if (x->nomem)
            break;
        float *r = x->w + at + (size_t)k * TB_GPU_PT_P_WORDS;
        tb__gpt_put_u32(&r[0], kind);
        r[1] = pt->scale;
        r[2] = pt->scale_v;
        tb__gpt_put_u32(&r[3], pt->object_space ? 1u : 0u);
        tb__gpt_put_u32(&r[4], (uint32_t)pt->octaves);
        r[5] = pt->height;
        tb__gpt_put_u32(&r[6], (uint32_t)(x->base + col));
    }
    return (uint32_t)(x->base + at);
}

/* The affine map u(p) = a . p + b over a polygon face (world points) from
 * its parameters at c and at points s[0..ns) inside the face; false when
 * the points are degenerate or the map misses one by more than TB__GPT_UV_FIT. */
static bool tb__gpt_affine_fit(tb_dvec3 c, double uc, const tb_dvec3 *sp, const double *us, int ns, double a[4])
{
    tb_dvec3 e1 = tb_dvec3_sub(sp[0], c), e2 = e1, nrm = {0, 0, 0};
    double best = 0.0;
    int j = 0;
    for (int k = 1; k < ns; k++) {
        tb_dvec3 e = tb_dvec3_sub(sp[k], c), x = tb_dvec3_cross(e1, e);
        double l = tb_dvec3_length(x);
        if (l > best)
            best = l, e2 = e, nrm = x, j = k;
    }
    if (!(best > 0.0))
        return false;
    nrm = tb_dvec3_scale(nrm, 1.0 / best);
    /* a = the dual basis of (e1, e2, nrm) applied to (du1, du2, 0) */
    tb_dvec3 d1 = tb_dvec3_cross(e2, nrm), d2 = tb_dvec3_cross(nrm, e1);
    double det = tb_dvec3_dot(e1, d1);
    if (!(fabs(det) > 0.0))
        return false;
    const double du1 = us[0] - uc, du2 = us[j] - uc;
    tb_dvec3 g = tb_dvec3_add(tb_dvec3_scale(d1, du1 / det), tb_dvec3_scale(d2, du2 / det));
    a[0] = g.x, a[1] = g.y, a[2] = g.z;
    a[3] = uc - tb_dvec3_dot(g, c);
    for (int k = 0; k < ns; k++)
        if (!(fabs(tb_dvec3_dot(g, sp[k]) + a[3] - us[k]) <= TB__GPT_UV_FIT))
            return false;
    return true;
}

/* Object o's parameterisation record (shared/pathtrace.h, TB_GPU_PT_Q_*);
 * returns its table word, or TB_GPU_PT_NONE with x->nomem or, for a polygon
 * face whose (u, v) the kernel cannot reproduce, an error set. */
static uint32_t tb__gpt_param_record(tb__gpt_words *x, const tb_object *o, tb_status *st)
{
    const bool poly = o->kind == TB_PRIM_POLYGONS;
    const tb_geom_polygons *pg = &o->geom.polygons;
    const int nf = poly ? pg->nfaces : 0;
    const size_t at = tb__gpt_grow(x, TB_GPU_PT_Q_FACES + (size_t)nf * TB_GPU_PT_Q_FACE_WORDS);
    if (x->nomem)
        return TB_GPU_PT_NONE;
    float *q = x->w + at;
    tb__gpt_put_u32(&q[TB_GPU_PT_Q_KIND], o->kind == TB_PRIM_SPHERE ? TB_GPU_PT_PARAM_SPHERE
                                          : o->kind == TB_PRIM_CUBE ? TB_GPU_PT_PARAM_CUBE
                                                                    : TB_GPU_PT_PARAM_POLYGONS);
    tb__gpt_put_u32(&q[TB_GPU_PT_Q_FACE_BASE], o->face_base);
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++) {
            q[TB_GPU_PT_Q_TO_OBJECT + (size_t)(4 * r + c)] = (float)o->to_world.inv.m[r][c];
            if (c < 3)
                q[TB_GPU_PT_Q_TO_WORLD + (size_t)(3 * r + c)] = (float)o->to_world.m.m[r][c];
        }
    tb__gpt_put_u32(&q[TB_GPU_PT_Q_NFACES], (uint32_t)nf);
    for (int f = 0; f < nf; f++) {
        const int i0 = pg->face_start[f], nv = pg->face_start[f + 1] - i0;
        tb_dvec3 *sp = malloc((size_t)nv * sizeof *sp);
        double *su = malloc(2 * (size_t)nv * sizeof *su);
        if (!sp || !su) {
            free(sp), free(su);
            x->nomem = true;
            return TB_GPU_PT_NONE;
        }
        /* the face's centroid and points halfway from it to each vertex: inside a convex face, so
         * tb_param_from_point_world gives this face's (u, v) there */
        tb_dvec3 c = {0, 0, 0};
        for (int k = 0; k < nv; k++) {
            sp[k] = tb_transform_dpoint(&o->to_world, tb_vec3_to_d(pg->vertices[pg->indices[i0 + k]]));
            c = tb_dvec3_add(c, sp[k]);
        }
        c = tb_dvec3_scale(c, 1.0 / nv);
        bool ok = nv >= 3;
        double uc = 0.0, vc = 0.0;
        int face = -1;
        ok = ok && !tb_param_from_point_world(o->kind, &o->geom, &o->to_world, c, f, &face, &uc, &vc) && face == f;
        for (int k = 0; k < nv && ok; k++) {
            sp[k] = tb_dvec3_scale(tb_dvec3_add(sp[k], c), 0.5);
            ok = !tb_param_from_point_world(o->kind, &o->geom, &o->to_world, sp[k], f, &face, &su[k], &su[nv + k]) &&
                 face == f;
        }
        double au[4], av[4];
        tb_dvec3 du = {0, 0, 0}, dv = {0, 0, 0}, du1, dv1;
        ok = ok && tb__gpt_affine_fit(c, uc, sp, su, nv, au) && tb__gpt_affine_fit(c, vc, sp, su + nv, nv, av);
        /* the tangents: constant over the face where (u, v) is affine; checked at a second point */
        ok = ok && !tb_param_eval_world(o->kind, &o->geom, &o->to_world, f, uc, vc, NULL, NULL, &du, &dv) &&
             !tb_param_eval_world(o->kind, &o->geom, &o->to_world, f, su[0], su[nv], NULL, NULL, &du1, &dv1) &&
             tb_dvec3_length(tb_dvec3_sub(du, du1)) <= 1e-9 * (1.0 + tb_dvec3_length(du)) &&
             tb_dvec3_length(tb_dvec3_sub(dv, dv1)) <= 1e-9 * (1.0 + tb_dvec3_length(dv));
        free(sp), free(su);
        if (!ok) {
            tb_clear_error();
            *st = tb_error(TB_ERR_UNSUPPORTED,
                           "object %u, face %d: its (u, v) is not an affine map over the face (non-convex or "
                           "with texture coordinates out of [0, 1]); the kernel's patterns need one",
                           o->index, f);
            return TB_GPU_PT_NONE;
        }
        float *r = q + TB_GPU_PT_Q_FACES + (size_t)f * TB_GPU_PT_Q_FACE_WORDS;
        const double w[14] = {au[0], au[1], au[2], au[3], av[0], av[1], av[2], av[3],
                              du.x,  du.y,  du.z,  dv.x,  dv.y,  dv.z};
        for (int k = 0; k < 14; k++)
            r[k] = (float)w[k];
    }
    return (uint32_t)(x->base + at);
}

/* The emitters and the scene's table (shared/pathtrace.h; pathtrace.comp's
 * bindings 9 and 10). */
static tb_status tb__gpt_tables(tb_gpu_pathtracer *pt, uint32_t *emitter_kinds)
{
    const tb_scene *s = pt->scene;
    const int nch = pt->nch, nm = s->nmaterials, ne = s->nemitters;
    tb_light_set ls;
    memset(&ls, 0, sizeof ls);
    tb_status st = tb_light_set_init(&ls, s);
    if (st)
        return st;
    const size_t ms = 4 * (size_t)nch + TB_GPU_PT_M_SCALARS;
    const size_t eb = (size_t)nm * ms, cb = eb + (size_t)ne * (size_t)nch, pb = cb + (size_t)ne + 1,
                 xb = pb + (size_t)ne, ob = xb + (size_t)ne;
    size_t nleaves = 0;
    for (uint32_t i = 0; i < s->nobjects; i++)
        nleaves += tb_prim_is_csg(s->objects[i]->kind) ? tb__gpt_leaves_rec(s, s->objects[i], NULL, 0) : 0;
    const size_t fb = ob + TB_GPU_PT_O_WORDS * (size_t)s->nobjects;
    const size_t lb = fb + 3 * nleaves, ls_words = TB_GPU_PT_L_SCALARS + (size_t)nch;
    size_t nt = lb + (size_t)s->nlights * ls_words;
    pt->light_base = (uint32_t)lb;
    tb__gpt_words x = {.base = nt};
    float *t = calloc(nt, sizeof *t);
    tb_gpu_emitter *em = calloc((size_t)(ne > 0 ? ne : 1), sizeof *em);
    if (!t || !em) {
        st = tb_error(TB_ERR_NOMEM, "GPU path tracer: out of memory");
        goto done;
    }
    for (int m = 0; m < nm; m++) {
        const tb_material *mt = &s->materials[m];
        tb_channels Le = mt->emits ? tb_radiance_from_exitance(mt->emission) : tb_channels_splat(nch, 0.0f);
        float *w = t + (size_t)m * ms;
        for (int c = 0; c < nch; c++) {
            w[c] = mt->diffuse.v[c];
            w[nch + c] = Le.v[c];
            w[2 * nch + c] = mt->model == TB_MID_MODEL_LAMBERT ? 0.0f : mt->specular.v[c]; /* as tb_surface_at */
            w[3 * nch + c] = mt->transmission.v[c];
        }
        tb__gpt_material(s, mt, w + 4 * nch);
        if (pt->patterns && tb__gpt_patterned(s, m))
            tb__gpt_put_u32(&w[4 * nch + TB_GPU_PT_M_PATTERNS], tb__gpt_patterns(&x, mt, nch, &pt->pattern_kinds));
    }
    if (pt->pattern_kinds & (1u << TB_GPU_PATTERN_NOISE)) {
        const size_t at = tb__gpt_grow(&x, 256);
        for (int k = 0; k < 256 && !x.nomem; k++)
            tb__gpt_put_u32(&x.w[at + (size_t)k], tb_noise_permutation()[k]);
        pt->perm_base = (uint32_t)(x.base + at);
    }
    *emitter_kinds = 0;
    double cdf = 0.0;
    for (int i = 0; i < ne; i++) {
        const tb_emitter *e = &s->emitters[i];
        em[i] = tb__gpu_emitter_record(e, ls.area.areas[i]);
        *emitter_kinds |= 1u << (uint32_t)e->kind;
        for (int c = 0; c < nch; c++)
            t[eb + (size_t)i * (size_t)nch + (size_t)c] = e->radiance.v[c];
        double pmf = tb_distrib1d_pmf(&ls.area.select, i);
        t[cb + (size_t)i] = (float)cdf;
        t[pb + (size_t)i] = (float)pmf;
        memcpy(&t[xb + (size_t)i], &e->object, sizeof e->object);
        cdf += pmf;
    }
    t[cb + (size_t)ne] = 1.0f;
    size_t leaf = 0;
    for (uint32_t i = 0; i < s->nobjects; i++) {
        const tb_object *o = s->objects[i];
        uint32_t w[TB_GPU_PT_O_WORDS] = {tb__gpt_material_index(s, o->material), 0, 0, 0, 0, TB_GPU_PT_NONE};
        if (pt->patterns && !tb_prim_is_csg(o->kind) && tb__gpt_patterned(s, o->material) &&
            (w[TB_GPU_PT_O_PARAM] = tb__gpt_param_record(&x, o, &st)) == TB_GPU_PT_NONE) {
            if (x.nomem)
                st = tb_error(TB_ERR_NOMEM, "GPU path tracer: out of memory");
            goto done;
        }
        if (tb_prim_is_csg(o->kind)) {
            uint32_t *range = malloc(3 * tb__gpt_leaves_rec(s, o, NULL, 0) * sizeof *range);
            if (!range) {
                st = tb_error(TB_ERR_NOMEM, "GPU path tracer: out of memory");
                goto done;
            }
            w[3] = (uint32_t)(fb + 3 * leaf); /* the table word of its first leaf */
            w[4] = (uint32_t)tb__gpt_leaves_rec(s, o, range, 0);
            memcpy(&t[fb + 3 * leaf], range, 3 * w[4] * sizeof *range);
            leaf += w[4];
            free(range);
        }
        memcpy(&t[ob + TB_GPU_PT_O_WORDS * (size_t)i], w, sizeof w);
    }
    for (int k = 0; k < s->nemissive; k++) {
        const tb_scene_emissive *x = &s->emissive[k];
        uint32_t w[2] = {(uint32_t)x->first_emitter, (uint32_t)x->nemitters};
        memcpy(&t[ob + TB_GPU_PT_O_WORDS * (size_t)x->object + 1], w, sizeof w);
    }
    for (int i = 0; i < s->nlights; i++) {
        const tb_light *l = &s->lights[i];
        float *w = t + lb + (size_t)i * ls_words;
        uint32_t kind = l->kind == TB_LIGHT_SPOT          ? TB_GPU_LIGHT_SPOT
                        : l->kind == TB_LIGHT_DIRECTIONAL ? TB_GPU_LIGHT_DIRECTIONAL
                                                          : TB_GPU_LIGHT_POINT;
        memcpy(&w[TB_GPU_PT_L_KIND], &kind, sizeof kind);
        const float pa[6] = {l->position.x, l->position.y, l->position.z, l->axis.x, l->axis.y, l->axis.z};
        memcpy(&w[TB_GPU_PT_L_POSITION], pa, sizeof pa);
        w[TB_GPU_PT_L_COS_TOTAL] = (float)l->cos_total;
        w[TB_GPU_PT_L_COS_FALLOFF] = (float)l->cos_falloff;
        for (int c = 0; c < nch; c++)
            w[TB_GPU_PT_L_SCALARS + (size_t)c] = l->intensity.v[c];
    }
    if (x.nomem) {
        st = tb_error(TB_ERR_NOMEM, "GPU path tracer: out of memory");
        goto done;
    }
    if (x.n > 0) {
        float *tt = realloc(t, (nt + x.n) * sizeof *t);
        if (!tt) {
            st = tb_error(TB_ERR_NOMEM, "GPU path tracer: out of memory");
            goto done;
        }
        t = tt;
        memcpy(t + nt, x.w, x.n * sizeof *t);
        nt += x.n;
    }
    pt->b_table = tb_gpu_buffer_create(pt->dev, nt * sizeof *t);
    pt->b_emitters = tb_gpu_buffer_create(pt->dev, (size_t)(ne > 0 ? ne : 1) * sizeof *em);
    if (!pt->b_table || !pt->b_emitters) {
        st = TB_ERR_DEVICE;
        goto done;
    }
    if ((st = tb_gpu_buffer_upload(pt->b_table, 0, t, nt * sizeof *t)) ||
        (st = tb_gpu_buffer_upload(pt->b_emitters, 0, em, (size_t)(ne > 0 ? ne : 1) * sizeof *em)))
        goto done;
done:
    free(t);
    free(em);
    free(x.w);
    tb_light_set_release(&ls);
    return st;
}

tb_status tb_gpu_pt_create(tb_gpu_device *dev, const tb_scene *s, const tb_pt_options *o, tb_gpu_pathtracer **out)
{
    *out = NULL;
    if (!s || !s->accel)
        return tb_error(TB_ERR_ARG, "GPU path tracer: the scene has no acceleration structure");
    tb_pt_options po;
    tb_status st = tb_pt_options_resolve(o, &po);
    if (st)
        return tb_error_context(st, "GPU path tracer");
    const char *why = tb_gpu_pt_unsupported(s);
    if (why)
        return tb_error(TB_ERR_UNSUPPORTED, "GPU path tracer: %s", why);
    tb_gpu_pathtracer *pt = calloc(1, sizeof *pt);
    if (!pt)
        return tb_error(TB_ERR_NOMEM, "GPU path tracer: out of memory");
    pt->dev = dev;
    pt->scene = s;
    pt->opt = po;
    pt->nch = s->nchannels;
    pt->cap = TB__GPT_BATCH;
    if (!(pt->gscene = tb_gpu_scene_create(dev, s))) {
        st = TB_ERR_DEVICE;
        goto fail;
    }
    tb_gpu_scene_info info;
    tb_gpu_scene_get_info(pt->gscene, &info);
    if (info.cpu_objects > 0) {
        for (uint32_t i = 0; i < s->nobjects; i++)
            if (!tb_gpu_scene_object_on_gpu(pt->gscene, i)) {
                st = tb_error(TB_ERR_UNSUPPORTED, "object %u is intersected on the CPU only (%s)",
                              i, tb_gpu_scene_object_route(pt->gscene, i));
                goto fail;
            }
    }
    tb_gpu_scene_get_bindings(pt->gscene, &pt->bind);
    for (int m = 0; m < s->nmaterials; m++)
        pt->patterns = pt->patterns || tb__gpt_patterned(s, m);
    uint32_t kinds = 0;
    if ((st = tb__gpt_tables(pt, &kinds)))
        goto fail;
    const size_t slots = 1 + (size_t)s->nlights;
    const size_t nv = ((size_t)TB_GPU_PT_NVALUES + slots - 1) * (size_t)pt->nch;
    /* fewer paths per batch where the channel values would pass 64 MiB
     * (many lights and bands), well inside every device's buffer limits */
    if (pt->cap * nv * sizeof(float) > TB__GPT_VALUES_MAX)
        pt->cap = TB__GPT_VALUES_MAX / (nv * sizeof(float));
    const size_t n = pt->cap;
    /* with patterns, each camera ray's two offset rays follow the batch's rays */
    pt->b_rays = tb_gpu_buffer_create(dev, (pt->patterns ? 3 : 1) * n * sizeof(tb_gpu_ray));
    pt->b_states = tb_gpu_buffer_create(dev, TB_GPU_PT_STATE_HEADER + n * sizeof(tb_gpu_pt_state));
    pt->b_hits = tb_gpu_buffer_create(dev, n * sizeof(tb_gpu_hit));
    pt->b_values = tb_gpu_buffer_create(dev, n * nv * sizeof(float));
    pt->b_shadows = tb_gpu_buffer_create(dev, slots * n * sizeof(tb_gpu_ray));
    pt->states = malloc(n * sizeof *pt->states);
    pt->L = malloc(n * (size_t)pt->nch * sizeof *pt->L);
    if (!pt->b_rays || !pt->b_states || !pt->b_hits || !pt->b_values || !pt->b_shadows) {
        st = TB_ERR_DEVICE;
        goto fail;
    }
    if (!pt->states || !pt->L) {
        st = tb_error(TB_ERR_NOMEM, "GPU path tracer: out of memory");
        goto fail;
    }
    const tb_gpu_scene_bindings *b = &pt->bind;
    tb_gpu_spec_constant spec[1 + TB__GPT_SPEC] = {
        {1, 0},
        {2, (uint32_t)pt->nch},
        {3, (uint32_t)(s->nmaterials > 0 ? s->nmaterials : 1)},
        {4, (uint32_t)s->nemitters},
        {5, kinds},
        {6, b->stack},
        {7, b->has_triangles},
        {8, b->has_spheres},
        {9, b->has_cubes},
        {10, b->has_quadrics},
        {11, b->has_planar},
        {12, b->has_tori},
        {13, (uint32_t)s->nlights},
        {14, b->has_csg},
        {15, pt->patterns},
        {16, pt->pattern_kinds},
    };
    static const char *const names[TB_GPU_PT_STAGES] = {"pathtrace init", "pathtrace extend", "pathtrace shade",
                                                        "pathtrace shadow", "pathtrace accumulate"};
    for (uint32_t stage = 0; stage < TB_GPU_PT_STAGES; stage++) {
        spec[0].value = stage;
        const bool trace = stage == TB_GPU_PT_STAGE_EXTEND || stage == TB_GPU_PT_STAGE_SHADOW;
        pt->k[stage] = tb_gpu_kernel_get(
            dev, &(tb_gpu_kernel_desc){.spirv = tb_gpu_builtin(trace ? "pathtrace_trace" : "pathtrace"),
                                       .name = names[stage],
                                       .buffers = 12,
                                       .kinds = {0, TB_GPU_BIND_TEXELS_RGBA32UI, TB_GPU_BIND_TEXELS_RGBA32UI, 0,
                                                 TB_GPU_BIND_TEXELS_R32UI, 0, 0, 0, 0, 0, TB_GPU_BIND_TEXELS_R32UI,
                                                 TB_GPU_BIND_TEXELS_R32UI},
                                       .push_size = sizeof(tb_gpu_pt_push),
                                       .spec = spec,
                                       .spec_count = 1 + TB__GPT_SPEC});
        if (!pt->k[stage]) {
            st = TB_ERR_DEVICE;
            goto fail;
        }
    }
    *out = pt;
    return TB_OK;
fail:
    tb_gpu_pt_destroy(pt);
    return tb_error_context(st, "GPU path tracer");
}

void tb_gpu_pt_get_stats(const tb_gpu_pathtracer *pt, tb_gpu_pt_stats *out) { *out = pt->st; }

/* A dispatch of `stage` over the batch's buffers. */
static tb_gpu_dispatch tb__gpt_dispatch(tb_gpu_pathtracer *pt, uint32_t stage, const tb_gpu_pt_push *push)
{
    const tb_gpu_scene_bindings *b = &pt->bind;
    return (tb_gpu_dispatch){pt->k[stage],
                             {pt->b_rays, b->nodes, b->tris, b->placed, b->refs, pt->b_states, pt->b_hits,
                              pt->b_values, pt->b_shadows, pt->b_emitters, pt->b_table, pt->b_values},
                             push,
                             push->n,
                             0.0};
}

/* Traces rays[0..n) (n <= cap) to the end of their paths; rx, ry: their
 * offset rays (NULL: none). */
static tb_status tb__gpt_batch(tb_gpu_pathtracer *pt, const tb_ray *rays, const tb_ray *rx, const tb_ray *ry,
                               const uint32_t *seeds, size_t n, float *out, bool probe)
{
    const int nch = pt->nch;
    _Static_assert(sizeof(tb_ray) == sizeof(tb_gpu_ray), "tb_ray is uploaded as tb_gpu_ray");
    for (size_t i = 0; i < n; i++)
        pt->states[i] = (tb_gpu_pt_state){.seed0 = seeds[2 * i], .seed1 = seeds[2 * i + 1], .alive = 1, .prev_delta = 1};
    const bool diffs = pt->patterns && rx && ry;
    tb_status st = tb_gpu_buffer_upload(pt->b_rays, 0, rays, n * sizeof *rays);
    if (!st && diffs)
        st = tb_gpu_buffer_upload(pt->b_rays, n * sizeof *rays, rx, n * sizeof *rays);
    if (!st && diffs)
        st = tb_gpu_buffer_upload(pt->b_rays, 2 * n * sizeof *rays, ry, n * sizeof *rays);
    if (!st)
        st = tb_gpu_buffer_upload(pt->b_states, TB_GPU_PT_STATE_HEADER, pt->states, n * sizeof *pt->states);
    if (st)
        return st;
    /* push constants: [0] every stage, [1] the last shade of a submission (counts) */
    tb_gpu_pt_push push[2];
    push[0] = (tb_gpu_pt_push){.n = (uint32_t)n,
                               .nnodes = pt->bind.nnodes,
                               .max_depth = (uint32_t)pt->opt.max_depth,
                               .rr_depth = (uint32_t)pt->opt.rr_depth,
                               .max_bounces = TB_PT_MAX_BOUNCES,
                               .light_base = pt->light_base,
                               .perm = pt->perm_base,
                               .diffs = diffs ? 1u : 0u,
                               /* tb_surfaces_create's scale of the offset rays */
                               .diff_scale = (float)fmax(0.125, 1.0 / sqrt(pt->opt.spp > 1 ? (double)pt->opt.spp : 1.0)),
                               .probe = probe ? 1u : 0u};
    push[1] = push[0];
    push[1].count = 1;
    tb_gpu_dispatch d[2 + 3 * TB_GPU_PT_BOUNCES_PER_SUBMIT];
    bool first = true;
    for (int bounce = 0; bounce <= TB_PT_MAX_BOUNCES;) {
        int nd = 0;
        if (first)
            d[nd++] = tb__gpt_dispatch(pt, TB_GPU_PT_STAGE_INIT, &push[0]);
        first = false;
        for (int k = 0; k < TB_GPU_PT_BOUNCES_PER_SUBMIT; k++, bounce++) {
            bool last = k == TB_GPU_PT_BOUNCES_PER_SUBMIT - 1;
            d[nd++] = tb__gpt_dispatch(pt, TB_GPU_PT_STAGE_EXTEND, &push[0]);
            d[nd++] = tb__gpt_dispatch(pt, TB_GPU_PT_STAGE_SHADE, &push[last ? 1 : 0]);
            d[nd++] = tb__gpt_dispatch(pt, TB_GPU_PT_STAGE_SHADOW, &push[0]);
        }
        /* the clear light samples, of ended paths and of live ones alike
         * (before their next shade): the last bounce needs no extra submission */
        d[nd++] = tb__gpt_dispatch(pt, TB_GPU_PT_STAGE_ACCUMULATE, &push[0]);
        const uint32_t zero = 0;
        if ((st = tb_gpu_buffer_upload(pt->b_states, 0, &zero, sizeof zero)))
            return st;
        if ((st = tb_gpu_run(pt->dev, d, nd)))
            return st;
        pt->st.submits++;
        pt->st.bounces += TB_GPU_PT_BOUNCES_PER_SUBMIT;
        pt->st.dispatches += (uint64_t)nd;
        TB_STAT_INC(tb__gpt_submits);
        for (int k = 0; k < nd; k++)
            pt->st.kernel_seconds += d[k].seconds;
        uint32_t alive = 0;
        if ((st = tb_gpu_buffer_download(pt->b_states, 0, &alive, sizeof alive)))
            return st;
        if (alive == 0)
            break;
    }
    if (probe)
        return TB_OK; /* tb_gpu_pt_surfaces reads the buffers */
    /* radiance: the TB_GPU_PT_L arrays, word-major */
    const size_t lo = (size_t)TB_GPU_PT_L * (size_t)nch * n * sizeof(float);
    if ((st = tb_gpu_buffer_download(pt->b_values, lo, pt->L, (size_t)nch * n * sizeof(float))))
        return st;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < nch; c++)
            out[i * (size_t)nch + (size_t)c] = pt->L[(size_t)c * n + i];
    return TB_OK;
}

tb_status tb_gpu_pt_radiance(tb_gpu_pathtracer *pt, const tb_ray *rays, const uint32_t *seeds, size_t n,
                             float *out)
{
    return tb_gpu_pt_radiance_diff(pt, rays, NULL, NULL, seeds, n, out);
}

tb_status tb_gpu_pt_radiance_diff(tb_gpu_pathtracer *pt, const tb_ray *rays, const tb_ray *rx, const tb_ray *ry,
                                  const uint32_t *seeds, size_t n, float *out)
{
    double t0 = tb__gpt_now();
    tb_status st = TB_OK;
    for (size_t at = 0; at < n && !st; at += pt->cap) {
        size_t m = n - at < pt->cap ? n - at : pt->cap;
        st = tb__gpt_batch(pt, rays + at, rx ? rx + at : NULL, ry ? ry + at : NULL, seeds + 2 * at, m,
                           out + at * (size_t)pt->nch, false);
    }
    pt->st.paths += n;
    tb_stat_add(&tb__gpt_paths, (int64_t)n);
    pt->st.wall_seconds += tb__gpt_now() - t0;
    return st;
}

tb_status tb_gpu_pt_surfaces(tb_gpu_pathtracer *pt, const tb_ray *rays, const tb_ray *rx, const tb_ray *ry, size_t n,
                             float *out)
{
    const size_t nch = (size_t)pt->nch, stride = 5 + 2 * nch;
    if (nch < 3)
        return tb_error(TB_ERR_ARG, "GPU path tracer: surfaces need at least 3 channels");
    tb_status st = TB_OK;
    uint32_t *seeds = calloc(2 * (pt->cap < n ? pt->cap : n) + 2, sizeof *seeds);
    tb_gpu_hit *hits = malloc((pt->cap < n ? pt->cap : n) * sizeof *hits + sizeof *hits);
    float *v = malloc(3 * nch * (pt->cap < n ? pt->cap : n) * sizeof *v + sizeof *v);
    if (!seeds || !hits || !v)
        st = tb_error(TB_ERR_NOMEM, "GPU path tracer: out of memory");
    for (size_t at = 0; at < n && !st; at += pt->cap) {
        const size_t m = n - at < pt->cap ? n - at : pt->cap;
        memset(hits, 0xff, m * sizeof *hits); /* a miss leaves its record alone: object TB_GPU_NO_HIT */
        if ((st = tb_gpu_buffer_upload(pt->b_hits, 0, hits, m * sizeof *hits)) ||
            (st = tb__gpt_batch(pt, rays + at, rx ? rx + at : NULL, ry ? ry + at : NULL, seeds, m, NULL, true)) ||
            (st = tb_gpu_buffer_download(pt->b_hits, 0, hits, m * sizeof *hits)) ||
            (st = tb_gpu_buffer_download(pt->b_values, 0, v, 3 * nch * m * sizeof *v)))
            break;
        for (size_t i = 0; i < m; i++) {
            float *o = out + (at + i) * stride;
            const bool hit = hits[i].object != TB_GPU_NO_HIT;
            o[0] = hit ? hits[i].u : NAN;
            o[1] = hit ? hits[i].v : NAN;
            for (size_t c = 0; c < 3; c++)
                o[2 + c] = hit ? v[(TB_GPU_PT_PROBE_NORMAL * nch + c) * m + i] : NAN;
            for (size_t c = 0; c < nch; c++) {
                o[5 + c] = hit ? v[(TB_GPU_PT_PROBE_DIFFUSE * nch + c) * m + i] : NAN;
                o[5 + nch + c] = hit ? v[(TB_GPU_PT_PROBE_SPECULAR * nch + c) * m + i] : NAN;
            }
        }
    }
    free(seeds), free(hits), free(v);
    return st;
}

/* ------------------------------------------------------------ the render */

/* The renderer as tb__render_drive runs it. */
typedef struct tb__gpt_engine {
    tb_gpu_pathtracer *pt;
    const tb_render_options *o;
    size_t cap;          /* samples per batch (whole tiles; at least one tile) */
    tb_ray *rays;
    tb_ray *rx, *ry;     /* the camera rays' offset rays (patterns only; else NULL) */
    uint32_t *seeds;
    double *xy;
    float *L;
    float *pxy;          /* a pixel's sample positions */
    tb_film_tile **tiles; /* the batch's tiles */
    int max_tiles;
} tb__gpt_engine;

static tb_status tb__gpt_start(void *ctx, const tb_film *film)
{
    tb__gpt_engine *e = ctx;
    const int spp = e->o->aa.spp;
    size_t tile_max = 0;
    for (int t = 0; t < tb_film_tile_count(film); t++) {
        tb_tile_rect rc = tb_film_tile_rect(film, t);
        size_t k = (size_t)(rc.x1 - rc.x0) * (size_t)(rc.y1 - rc.y0) * (size_t)spp;
        tile_max = k > tile_max ? k : tile_max;
    }
    e->cap = tile_max > TB__GPT_BATCH ? tile_max : TB__GPT_BATCH;
    e->max_tiles = tile_max > 0 ? (int)(e->cap / tile_max) + 1 : 1;
    e->rays = malloc(e->cap * sizeof *e->rays);
    if (e->pt->patterns) {
        e->rx = malloc(e->cap * sizeof *e->rx);
        e->ry = malloc(e->cap * sizeof *e->ry);
        if (!e->rx || !e->ry)
            return tb_error(TB_ERR_NOMEM, "GPU path tracer: out of memory");
    }
    e->seeds = malloc(e->cap * 2 * sizeof *e->seeds);
    e->xy = malloc(e->cap * 2 * sizeof *e->xy);
    e->L = malloc(e->cap * (size_t)e->pt->nch * sizeof *e->L);
    e->pxy = malloc((size_t)spp * 2 * sizeof *e->pxy);
    e->tiles = calloc((size_t)e->max_tiles, sizeof *e->tiles);
    if (!e->rays || !e->seeds || !e->xy || !e->L || !e->pxy || !e->tiles)
        return tb_error(TB_ERR_NOMEM, "GPU path tracer: out of memory");
    return TB_OK;
}

/* The camera samples of tile `tile` from sample q on, as the CPU path makes
 * them (tb_pt_sample): position, stream, lens numbers, camera ray; then two
 * words of the stream seed the device's. Returns the next q. */
static size_t tb__gpt_tile_rays(tb__gpt_engine *e, const tb_film_tile *tile, const tb_aa_options *aa, size_t q)
{
    const tb_camera *cam = &e->pt->scene->camera;
    tb_tile_rect rc = tb_film_tile_pixels(tile);
    for (int py = rc.y0; py < rc.y1; py++)
        for (int px = rc.x0; px < rc.x1; px++) {
            tb_pixel_sampler ps;
            tb_pixel_sampler_init(&ps, aa, px, py);
            int ns = tb_pixel_sampler_round(&ps, e->pxy);
            for (int j = 0; j < ns; j++, q++) {
                double x = (double)px + (double)e->pxy[2 * j], y = (double)py + (double)e->pxy[2 * j + 1];
                tb_rng rng;
                tb_aa_sample_rng(aa, px, py, (uint32_t)j, &rng);
                float lu, lv;
                tb_camera_lens_numbers(cam, &rng, &lu, &lv);
                if (e->rx) { /* as tb_pt_sample when the surfaces need differentials */
                    tb_camera_ray_diff cd;
                    tb_camera_ray_differential(cam, x, y, lu, lv, &cd);
                    e->rays[q] = cd.ray;
                    e->rx[q] = (tb_ray){cd.rx_o, 0.0f, cd.rx_d, INFINITY};
                    e->ry[q] = (tb_ray){cd.ry_o, 0.0f, cd.ry_d, INFINITY};
                } else {
                    e->rays[q] = tb_camera_ray(cam, x, y, lu, lv);
                }
                e->seeds[2 * q] = tb_rng_u32(&rng);
                e->seeds[2 * q + 1] = tb_rng_u32(&rng);
                e->xy[2 * q] = x;
                e->xy[2 * q + 1] = y;
            }
        }
    return q;
}

static tb_status tb__gpt_pass(void *ctx, tb__render_run *run, tb_film *film, const tb_aa_options *aa,
                              tb_aa_stats *as)
{
    tb__gpt_engine *e = ctx;
    as->max_spp_used = aa->spp;
    tb_status err = tb_film_begin_pass(film);
    const int ntiles = tb_film_tile_count(film);
    const size_t nch = (size_t)e->pt->nch;
    int t = 0;
    while (t < ntiles && !err) {
        if (tb__render_should_stop(run)) {
            for (int k = t; k < ntiles; k++)
                tb_film_tile_skip(film, k);
            as->tiles_skipped += ntiles - t;
            break;
        }
        /* whole tiles while they fit */
        int nt = 0;
        size_t q = 0;
        while (t + nt < ntiles && nt < e->max_tiles) {
            tb_tile_rect rc = tb_film_tile_rect(film, t + nt);
            size_t k = (size_t)(rc.x1 - rc.x0) * (size_t)(rc.y1 - rc.y0) * (size_t)aa->spp;
            if (nt > 0 && q + k > e->cap)
                break;
            if (!(e->tiles[nt] = tb_film_tile_create(film, t + nt))) {
                err = TB_ERR_NOMEM;
                break;
            }
            q = tb__gpt_tile_rays(e, e->tiles[nt], aa, q);
            nt++;
        }
        if (!err)
            err = tb_gpu_pt_radiance_diff(e->pt, e->rays, e->rx, e->ry, e->seeds, q, e->L);
        /* splat in the CPU path's order, merge in index order */
        size_t s = 0;
        for (int k = 0; k < nt; k++) {
            tb_tile_rect rc = tb_film_tile_pixels(e->tiles[k]);
            const double wt = 1.0 / (double)aa->spp;
            for (int py = rc.y0; py < rc.y1 && !err; py++)
                for (int px = rc.x0; px < rc.x1; px++) {
                    for (int j = 0; j < aa->spp; j++, s++)
                        tb_film_tile_add(e->tiles[k], e->xy[2 * s], e->xy[2 * s + 1], e->L + s * nch, wt);
                    tb_film_tile_record_samples(e->tiles[k], px, py, (uint32_t)aa->spp);
                }
            if (!err) {
                as->pixels += (uint64_t)(rc.x1 - rc.x0) * (uint64_t)(rc.y1 - rc.y0);
                if (run->progress)
                    tb_progress_add(run->progress, (int64_t)(rc.x1 - rc.x0) * (rc.y1 - rc.y0));
                err = tb_film_tile_submit(film, e->tiles[k]);
            } else {
                tb_film_tile_free(e->tiles[k]);
            }
            e->tiles[k] = NULL;
        }
        as->samples += q;
        t += nt;
    }
    return err;
}

tb_status tb_gpu_render_path(tb_gpu_device *dev, const tb_scene *s, const tb_pt_options *po,
                             const tb_render_options *o, tb_image **out, tb_render_stats *stats,
                             tb_gpu_pt_stats *gstats)
{
    *out = NULL;
    tb_status err = tb__render_check(o);
    if (err)
        return err;
    if (o->aa.adaptive)
        return tb_error(TB_ERR_UNSUPPORTED, "GPU path tracer: adaptive antialiasing is not implemented "
                                            "(use fixed --spp, or --backend cpu)");
    tb__gpt_engine e = {.o = o};
    /* the samples per pixel that scale the footprints: as the CPU path tracer's render takes them */
    tb_pt_options p = po ? *po : (tb_pt_options){0};
    if (p.spp == 0)
        p.spp = o->rt.spp > 0 ? o->rt.spp : o->aa.spp;
    if ((err = tb_gpu_pt_create(dev, s, &p, &e.pt)))
        return err;
    tb_render_stats rs;
    memset(&rs, 0, sizeof rs);
    err = tb__render_drive(s, o, &(tb__render_engine){.ctx = &e, .start = tb__gpt_start, .pass = tb__gpt_pass},
                           out, &rs);
    if (gstats)
        tb_gpu_pt_get_stats(e.pt, gstats);
    if (stats)
        *stats = rs;
    for (int k = 0; k < e.max_tiles && e.tiles; k++)
        tb_film_tile_free(e.tiles[k]);
    free(e.rays), free(e.rx), free(e.ry), free(e.seeds), free(e.xy), free(e.L), free(e.pxy), free(e.tiles);
    tb_gpu_pt_destroy(e.pt);
    return err;
}
