/* Scene assembly (docs/rendering.md): the streaming MID reader's items become
 * persistent objects, a deduplicated material table, lights, emissive
 * objects, the camera, world bounds and an acceleration structure.
 *
 * Colours are converted only once the whole file is read: whether the scene
 * is spectral depends on every material and light, and the reader hands
 * them out one at a time. Until then the material table and the lights keep
 * copies of their MID colours. */
#include "host/render/scene.h"
#include "util/base/str.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "host/object/intersect.h"
#include "host/render/ies.h"
#include "host/render/emit_surface.h"
#include "host/render/scene_internal.h"
#include "host/mid/mid_reader.h"
#include "util/container/hash_table.h"
#include "util/stats/stats.h"

/* ------------------------------------------------------------------ statistics */

TB_STAT_COUNTER(tb__n_sphere, "Scene/sphere objects");
TB_STAT_COUNTER(tb__n_cube, "Scene/cube objects");
TB_STAT_COUNTER(tb__n_cylinder, "Scene/cylinder objects");
TB_STAT_COUNTER(tb__n_cone, "Scene/cone objects");
TB_STAT_COUNTER(tb__n_pyramid, "Scene/pyramid objects");
TB_STAT_COUNTER(tb__n_prism, "Scene/prism objects");
TB_STAT_COUNTER(tb__n_torus, "Scene/torus objects");
TB_STAT_COUNTER(tb__n_polygons, "Scene/polygons objects");
TB_STAT_COUNTER(tb__n_conic, "Scene/conic objects");
TB_STAT_COUNTER(tb__n_square_arch, "Scene/square_arch objects");
TB_STAT_COUNTER(tb__n_round_arch, "Scene/round_arch objects");
TB_STAT_COUNTER(tb__n_union, "Scene/union objects");
TB_STAT_COUNTER(tb__n_intersection, "Scene/intersection objects");
TB_STAT_COUNTER(tb__n_difference, "Scene/difference objects");
TB_STAT_COUNTER(tb__n_tris, "Scene/triangle references");
TB_STAT_COUNTER(tb__n_refs, "Scene/references");
TB_STAT_COUNTER(tb__n_materials, "Scene/materials");
TB_STAT_COUNTER(tb__n_lights, "Scene/lights");
TB_STAT_COUNTER(tb__n_emissive, "Scene/emissive objects");
TB_STAT_TIMER(tb__t_load, "Scene/load");
TB_STAT_MEMORY(tb__m_objects, "Scene/memory of objects");
TB_STAT_MEMORY(tb__m_meshes, "Scene/memory of meshes");
TB_STAT_MEMORY(tb__m_fed, "Scene/memory of FED files");
TB_STAT_MEMORY(tb__m_emitters, "Scene/memory of emitters");
TB_STAT_MEMORY(tb__m_accel, "Scene/memory of acceleration");
TB_STAT_MEMORY(tb__m_total, "Scene/memory");
TB_STAT_MEMORY(tb__m_predicted, "Scene/memory predicted");
TB_STAT_RATIO(tb__r_per_object, "Scene/memory per object");
TB_STAT_RATIO(tb__r_per_tri, "Scene/memory per triangle");
TB_STAT_TIMER(tb__t_accel, "Scene/accel build");

static tb_stat *const tb__kind_counters[TB_PRIM_COUNT] = {
    &tb__n_sphere, &tb__n_cube, &tb__n_cylinder, &tb__n_cone, &tb__n_pyramid,
    &tb__n_prism, &tb__n_torus, &tb__n_polygons, &tb__n_conic, &tb__n_square_arch,
    &tb__n_round_arch, &tb__n_union, &tb__n_intersection, &tb__n_difference,
};

/* ------------------------------------------------------------------ storage */

/* A material as the file gave it, kept until the colours can be converted. */
typedef struct tb__mat_src {
    tb_mid_color color[4]; /* diffuse, specular, transmission, emission; sample arrays and paths owned */
    float exponent, ior;
    char *texture[4];      /* resolved paths (owned) or NULL: diffuse, specular, transmission, emission */
    char *name;            /* base material name (owned) or NULL */
    tb_mid_model model;
    float roughness;
    tb_mid_pattern *pat;   /* diffuse pattern, specular pattern, bump: colours and image path owned
                              (owned array of 3; NULL when all three are of kind NONE, as most are) */
    tb_mid_loc loc;        /* where the block or definition is */
    tb_mid_attrs extra;    /* effective unknown attributes (copies in the attribute store; part of the key) */
    bool emits;
    unsigned char *key;    /* the bytes that decide equality (owned) */
    size_t keylen;
    int next;              /* next entry with the same hash, or -1 */
} tb__mat_src;

/* A light as the file gave it (transform and colour; names owned). */
typedef struct tb__light_src {
    tb_mid_light l;        /* copy: pointers cleared except intensity samples and name (owned) */
    int ies;               /* index into priv->ies, or -1 */
} tb__light_src;

struct tb__scene_priv {
    tb__mat_src *mats;     /* every material a node used, before compaction; freed once converted */
    int nmats, capmats;
    char **mat_strs;       /* the strings the material table points to (names, paths), owned */
    size_t nmat_strs;
    tb_material_pattern *mat_pats; /* the patterns the table points to: [0] the one of kind NONE, then
                                      every pattern some material has */
    tb_htab mat_hash;      /* key hash -> first entry with that hash */
    tb__light_src *lights;
    int caplights;
    tb_ies **ies;          /* loaded IES files, one per distinct path */
    char **ies_paths;
    int nies, capies;
    size_t capobjects;
    int capemissive;
    const char *errname;   /* file name for messages */
    tb__scene_attrs *attrs;/* unknown attributes (scene_attrs.c); NULL until the first one */
    tb_object_fed_cache *feds; /* FED files read so far, shared by the objects (while loading) */
    size_t used;           /* bytes taken so far (objects, references at their build cost) */
    size_t limit;          /* stop past this many (0: no check) */
    bool budget;           /* limit is the caller's memory budget (else 90% of the available memory) */
};

/* Fails cleanly when the load has taken more than its limit (`what`: where). */
static tb_status tb__check_memory(const tb_scene *s, const char *what)
{
    const tb__scene_priv *p = s->priv;
    if (!p->limit || p->used <= p->limit)
        return TB_OK;
    return tb_error(TB_ERR_NOMEM,
                    "%s: out of memory: the scene would take more than %s of %.1f MiB (%.1f MiB taken %s, "
                    "%u objects read); nothing was rendered",
                    p->errname, p->budget ? "the memory budget" : "90% of the available memory",
                    (double)p->limit / 1048576.0, (double)p->used / 1048576.0, what, s->nobjects);
}

tb__scene_attrs *tb__attrs_store(tb_scene *s)
{
    tb__scene_priv *p = s->priv;
    if (!p->attrs && (p->attrs = calloc(1, sizeof *p->attrs)) != NULL) {
        tb_arena_init(&p->attrs->arena, 0);
        tb_htab_init(&p->attrs->nodes, TB_HTAB_U64);
        tb_htab_init(&p->attrs->named, TB_HTAB_STR);
    }
    return p->attrs;
}

const tb__scene_attrs *tb__attrs_peek(const tb_scene *s) { return s->priv ? s->priv->attrs : NULL; }

/* Grows *p (elements of `size` bytes) to hold at least `need`. */
static bool tb__grow(void **p, int *cap, int need, size_t size)
{
    if (need <= *cap)
        return true;
    int nc = *cap ? *cap * 2 : 16;
    while (nc < need)
        nc *= 2;
    void *q = realloc(*p, (size_t)nc * size);
    if (!q)
        return false;
    *p = q;
    *cap = nc;
    return true;
}

/* A "FILE:LINE:COL: error: what: <the last message>" error. */
static tb_status tb__located(tb_status st, const tb_scene *s, tb_mid_loc loc, const char *what)
{
    char msg[1024];
    snprintf(msg, sizeof msg, "%s", tb_last_error());
    return tb_error(st, "%s:%ld:%ld: error: %s: %s", s->priv->errname, loc.line, loc.col, what, msg);
}

/* ------------------------------------------------------------------ material keys */

typedef struct tb__bytes {
    unsigned char *p;
    size_t n, cap;
    bool oom;
} tb__bytes;

static void tb__put(tb__bytes *b, const void *v, size_t n)
{
    if (b->oom)
        return;
    if (b->n + n > b->cap) {
        size_t nc = b->cap ? b->cap * 2 : 256;
        while (nc < b->n + n)
            nc *= 2;
        unsigned char *q = realloc(b->p, nc);
        if (!q) {
            b->oom = true;
            return;
        }
        b->p = q;
        b->cap = nc;
    }
    memcpy(b->p + b->n, v, n);
    b->n += n;
}

/* tb__put for tb__attrs_key. */
static void tb__put_cb(void *ctx, const void *v, size_t n) { tb__put(ctx, v, n); }

static void tb__put_str(tb__bytes *b, const char *s)
{
    uint32_t n = s ? (uint32_t)strlen(s) + 1 : 0; /* 0: none; else the length with the terminator */
    tb__put(b, &n, sizeof n);
    if (s)
        tb__put(b, s, n);
}

static void tb__put_color(tb__bytes *b, const tb_mid_color *c)
{
    int32_t type = (int32_t)c->type;
    tb__put(b, &type, sizeof type);
    if (c->type == TB_MID_COLOR_RGB) {
        tb__put(b, c->rgb, sizeof c->rgb);
    } else if (c->type == TB_MID_COLOR_SPECTRUM) {
        int32_t n = c->nsamples;
        tb__put(b, &n, sizeof n);
        tb__put(b, c->nm, sizeof(float) * (size_t)n);
        tb__put(b, c->values, sizeof(float) * (size_t)n);
    } else {
        tb__put_str(b, c->file.path);
    }
}

/* The material's meaning as bytes: colours, exponent, ior, texture paths,
 * unknown attributes `extra` (not its name or where it was written). Two
 * blocks that differ only in unknown attributes stay two materials: a
 * renderer that reads them may shade them differently. */
static void tb__material_key(tb__bytes *b, const tb_mid_material *m, tb_mid_attrs extra)
{
    tb__attrs_key(extra, tb__put_cb, b);
    tb__put_color(b, &m->diffuse);
    tb__put_color(b, &m->specular);
    tb__put_color(b, &m->transmission);
    tb__put_color(b, &m->emission);
    tb__put(b, &m->exponent, sizeof m->exponent);
    tb__put(b, &m->ior, sizeof m->ior);
    tb__put_str(b, m->diffuse_texture.path);
    tb__put_str(b, m->specular_texture.path);
    tb__put_str(b, m->transmission_texture.path);
    tb__put_str(b, m->emission_texture.path);
    int32_t model = (int32_t)m->model;
    tb__put(b, &model, sizeof model);
    tb__put(b, &m->roughness, sizeof m->roughness);
    const tb_mid_pattern *pats[3] = {&m->diffuse_pattern, &m->specular_pattern, &m->bump};
    for (int i = 0; i < 3; i++) {
        const tb_mid_pattern *p = pats[i];
        int32_t head[3] = {(int32_t)p->kind, p->object_space, p->octaves};
        tb__put(b, head, sizeof head);
        if (p->kind == TB_MID_PATTERN_NONE)
            continue;
        tb__put(b, &p->scale, sizeof p->scale);
        tb__put(b, &p->scale_v, sizeof p->scale_v);
        tb__put(b, &p->height, sizeof p->height);
        tb__put_color(b, &p->a);
        tb__put_color(b, &p->b);
        tb__put_str(b, p->image.path);
    }
}

/* Deep copy of a colour; false when out of memory. */
static bool tb__copy_color(tb_mid_color *dst, const tb_mid_color *src)
{
    *dst = *src;
    dst->nm = dst->values = NULL;
    dst->file.text = dst->file.path = NULL;
    if (src->type == TB_MID_COLOR_SPECTRUM) {
        size_t n = (size_t)src->nsamples;
        float *nm = malloc(sizeof *nm * n), *v = malloc(sizeof *v * n);
        if (!nm || !v) {
            free(nm);
            free(v);
            return false;
        }
        memcpy(nm, src->nm, sizeof *nm * n);
        memcpy(v, src->values, sizeof *v * n);
        dst->nm = nm;
        dst->values = v;
    } else if (src->type == TB_MID_COLOR_SPECTRUM_FILE) {
        dst->file.text = tb_strdup(src->file.text);
        dst->file.path = tb_strdup(src->file.path);
        if (!dst->file.text || !dst->file.path)
            return false;
    }
    return true;
}

static void tb__free_color(tb_mid_color *c)
{
    free((void *)c->nm);
    free((void *)c->values);
    free((void *)c->file.text);
    free((void *)c->file.path);
    c->nm = c->values = NULL;
    c->file.text = c->file.path = NULL;
}

/* The build callback of tb_object_from_mid: the index of an equal material
 * in the table, or of a new entry. */
static tb_status tb__material_cb(void *user, const tb_mid_material *m, int *index)
{
    tb_scene *s = user;
    tb__scene_priv *p = s->priv;
    tb__bytes key = {0};
    tb_mid_attrs extra = tb__attrs_of_material(s, m);
    tb__material_key(&key, m, extra);
    if (key.oom) {
        free(key.p);
        return tb_error(TB_ERR_NOMEM, "scene: out of memory for a material");
    }
    uint64_t h = tb_hash_bytes(key.p, key.n), first;
    if (tb_htab_get(&p->mat_hash, h, &first)) {
        for (int i = (int)first; i >= 0; i = p->mats[i].next) {
            if (p->mats[i].keylen == key.n && memcmp(p->mats[i].key, key.p, key.n) == 0) {
                free(key.p);
                *index = i;
                return TB_OK;
            }
        }
    }
    if (!tb__grow((void **)&p->mats, &p->capmats, p->nmats + 1, sizeof *p->mats)) {
        free(key.p);
        return tb_error(TB_ERR_NOMEM, "scene: out of memory for a material");
    }
    int i = p->nmats;
    tb__mat_src *e = &p->mats[i];
    memset(e, 0, sizeof *e);
    unsigned char *fit = realloc(key.p, key.n ? key.n : 1); /* the buffer grew in steps of 2 from 256 bytes */
    e->key = fit ? fit : key.p;
    e->keylen = key.n;
    const tb_mid_color *cols[4] = {&m->diffuse, &m->specular, &m->transmission, &m->emission};
    const tb_mid_ref *tex[4] = {&m->diffuse_texture, &m->specular_texture, &m->transmission_texture,
                                &m->emission_texture};
    bool ok = true;
    for (int k = 0; k < 4; k++) {
        ok = tb__copy_color(&e->color[k], cols[k]) && ok;
        if (tex[k]->path)
            ok = (e->texture[k] = tb_strdup(tex[k]->path)) != NULL && ok;
    }
    if (m->base)
        ok = (e->name = tb_strdup(m->base)) != NULL && ok;
    const tb_mid_pattern *pats[3] = {&m->diffuse_pattern, &m->specular_pattern, &m->bump};
    bool any_pat = false;
    for (int k = 0; k < 3; k++)
        any_pat = any_pat || pats[k]->kind != TB_MID_PATTERN_NONE;
    if (any_pat)
        ok = (e->pat = calloc(3, sizeof *e->pat)) != NULL && ok;
    for (int k = 0; k < 3 && e->pat; k++) {
        tb_mid_pattern *d = &e->pat[k];
        *d = *pats[k];
        d->image.text = d->image.path = NULL;
        ok = tb__copy_color(&d->a, &pats[k]->a) && ok;
        ok = tb__copy_color(&d->b, &pats[k]->b) && ok;
        if (pats[k]->image.path)
            ok = (d->image.path = tb_strdup(pats[k]->image.path)) != NULL && ok;
    }
    e->model = m->model;
    e->roughness = m->roughness;
    e->exponent = m->exponent;
    e->ior = m->ior;
    e->loc = m->loc;
    e->emits = tb_mid_material_emits(m);
    e->next = -1;
    p->nmats++; /* counted even on failure, so tb_scene_free releases what was copied */
    if (!ok)
        return tb_error(TB_ERR_NOMEM, "scene: out of memory for a material");
    if (extra.count) {
        tb__scene_attrs *a = tb__attrs_store(s);
        if (!a)
            return tb_error(TB_ERR_NOMEM, "scene: out of memory for unknown attributes");
        tb_status st = tb__attrs_copy(a, extra, &e->extra);
        if (st)
            return st;
    }
    if (tb_htab_get(&p->mat_hash, h, &first)) {
        e->next = (int)first; /* new entries go first in their chain */
    }
    if (tb_htab_put(&p->mat_hash, h, (uint64_t)i))
        return tb_error(TB_ERR_NOMEM, "scene: out of memory for a material");
    *index = i;
    return TB_OK;
}

tb_status tb__scene_predict_materials(const tb_mid_object *m, tb_htab *set)
{
    tb__bytes key = {0};
    tb__material_key(&key, &m->material, (tb_mid_attrs){NULL, 0});
    if (key.oom) {
        free(key.p);
        return tb_error(TB_ERR_NOMEM, "scene: out of memory for a material");
    }
    uint64_t h = tb_hash_bytes(key.p, key.n);
    free(key.p);
    if (tb_htab_put(set, h, 1))
        return tb_error(TB_ERR_NOMEM, "scene: out of memory for a material");
    for (int i = 0; i < m->nchildren; i++) {
        tb_status st = tb__scene_predict_materials(&m->children[i], set);
        if (st)
            return st;
    }
    return TB_OK;
}

/* Pattern k of a material source (one of kind NONE when it has none). */
static const tb_mid_pattern *tb__src_pat(const tb__mat_src *e, int k)
{
    static const tb_mid_pattern none = {.kind = TB_MID_PATTERN_NONE};
    return e->pat ? &e->pat[k] : &none;
}

static void tb__free_mat_src(tb__mat_src *e)
{
    for (int k = 0; k < 4; k++) {
        tb__free_color(&e->color[k]);
        free(e->texture[k]);
    }
    for (int k = 0; k < 3; k++) {
        if (e->pat) {
            tb__free_color(&e->pat[k].a);
            tb__free_color(&e->pat[k].b);
            free((void *)e->pat[k].image.path);
        }
    }
    free(e->pat);
    free(e->name);
    free(e->key);
}

/* ------------------------------------------------------------------ objects */

/* The first leaf in pre-order whose material emits, or NULL. */
static const tb_object *tb__emitting_leaf(const tb_scene *s, const tb_object *o)
{
    if (tb_prim_is_csg(o->kind)) {
        for (int i = 0; i < o->nchildren; i++) {
            const tb_object *l = tb__emitting_leaf(s, &o->children[i]);
            if (l)
                return l;
        }
        return NULL;
    }
    return o->material >= 0 && s->priv->mats[o->material].emits ? o : NULL;
}

static tb_status tb__add_object(tb_scene *s, const tb_mid_object *m)
{
    tb__scene_priv *p = s->priv;
    if (s->nobjects == UINT32_MAX - 1)
        return tb_error(TB_ERR_ARG, "%s: more than 2^32 - 2 objects", p->errname);
    if (s->nobjects == p->capobjects) {
        size_t nc = p->capobjects ? 2 * p->capobjects : 64;
        tb_object **q = realloc(s->objects, nc * sizeof *q);
        if (!q)
            return tb_error(TB_ERR_NOMEM, "scene: out of memory for %u objects", s->nobjects);
        s->objects = q;
        p->capobjects = nc;
    }
    tb_object *o;
    char what[256];
    snprintf(what, sizeof what, "%s%s%s%s", tb_prim_kind_name(m->kind), m->name ? " '" : "",
             m->name ? m->name : "", m->name ? "'" : "");
    tb_status st = tb__attrs_begin_object(s, m);
    if (!st)
        st = tb_object_from_mid_shared(m, s->nobjects, tb__material_cb, s, p->feds, &o);
    tb_status st2 = tb__attrs_end_object(s, m, st ? NULL : o);
    if (!st && st2) {
        tb_object_free(o);
        return st2;
    }
    if (st)
        return tb__located(st, s, m->loc, what);
    s->objects[s->nobjects++] = o;
    size_t refs = o->kind == TB_PRIM_POLYGONS && o->mesh ? o->mesh->ntris : 1;
    p->used += tb__scene_object_bytes(o) + 2 * sizeof o + refs * TB__SCENE_BUILD_PER_REF;
    if ((st = tb__check_memory(s, "by this object")))
        return tb__located(st, s, m->loc, what);
    s->stats.objects_by_kind[o->kind]++;
    tb_stat_add(tb__kind_counters[o->kind], 1);
    if (o->kind == TB_PRIM_POLYGONS && o->mesh)
        s->stats.triangles += o->mesh->ntris;

    const tb_object *leaf = tb__emitting_leaf(s, o);
    if (leaf) {
        if (!tb__grow((void **)&s->emissive, &p->capemissive, s->nemissive + 1, sizeof *s->emissive))
            return tb_error(TB_ERR_NOMEM, "scene: out of memory for emissive objects");
        tb_scene_emissive *e = &s->emissive[s->nemissive];
        *e = (tb_scene_emissive){o->index, leaf->material, NAN, 0, 0};
        /* Only the areas that need no tessellation are computed here
         * (polygons, a sphere under a similarity); the others on demand,
         * tb_scene_emissive_area (docs/rendering.md, "Emissive objects"). */
        if (tb_prim_is_csg(o->kind) || !tb__scene_leaf_area_exact(o, &e->area))
            e->area = NAN;
        s->nemissive++;
    }
    return TB_OK;
}

tb_status tb_scene_emissive_area(const tb_scene *s, int i, double *area)
{
    if (!s || !area || i < 0 || i >= s->nemissive)
        return tb_error(TB_ERR_ARG, "scene: no emissive object %d", i);
    const tb_scene_emissive *e = &s->emissive[i];
    if (!isnan(e->area)) {
        *area = e->area;
        return TB_OK;
    }
    const tb_object *o = s->objects[e->object];
    if (tb_prim_is_csg(o->kind))
        return tb_error(TB_ERR_UNSUPPORTED, "scene: no area for CSG object %u", e->object);
    /* An analytic surface emitter holds its area (no tessellation). */
    if (e->nemitters == 1 && e->first_emitter < s->nemitters &&
        tb_emitter_is_surface(&s->emitters[e->first_emitter])) {
        *area = s->emitters[e->first_emitter].area;
        return TB_OK;
    }
    return tb__scene_leaf_area(o, area);
}

/* ------------------------------------------------------------------ lights */

static tb_status tb__add_light(tb_scene *s, const tb_mid_light *m)
{
    tb__scene_priv *p = s->priv;
    if (!tb__grow((void **)&p->lights, &p->caplights, s->nlights + 1, sizeof *p->lights))
        return tb_error(TB_ERR_NOMEM, "scene: out of memory for lights");
    tb__light_src *e = &p->lights[s->nlights];
    e->l = *m;
    e->l.nops = 0;
    e->l.ops = NULL;
    e->l.extra = (tb_mid_attrs){NULL, 0};
    e->l.nrefs = 0;
    e->l.refs = NULL;
    e->l.ies = (tb_mid_ref){NULL, NULL};
    e->l.name = NULL;
    e->ies = -1;
    bool ok = tb__copy_color(&e->l.intensity, &m->intensity);
    if (m->name)
        ok = (e->l.name = tb_strdup(m->name)) != NULL && ok;
    s->nlights++; /* counted even on failure, so tb_scene_free releases the copies */
    if (!ok)
        return tb_error(TB_ERR_NOMEM, "scene: out of memory for lights");
    if (m->extra.count) {
        tb__scene_attrs *a = tb__attrs_store(s);
        tb_mid_attrs *q = a ? realloc(a->lights, sizeof *q * (size_t)s->nlights) : NULL;
        if (!q)
            return tb_error(TB_ERR_NOMEM, "scene: out of memory for unknown attributes");
        for (int i = a->caplights; i < s->nlights; i++)
            q[i] = (tb_mid_attrs){NULL, 0};
        a->lights = q;
        a->caplights = s->nlights;
        tb_status st = tb__attrs_copy(a, m->extra, &a->lights[s->nlights - 1]);
        if (st)
            return st;
    }
    if (m->ies.path) {
        int k = 0;
        while (k < p->nies && strcmp(p->ies_paths[k], m->ies.path) != 0)
            k++;
        if (k == p->nies) {
            if (!tb__grow((void **)&p->ies, &p->capies, p->nies + 1, sizeof *p->ies)) {
                return tb_error(TB_ERR_NOMEM, "scene: out of memory for IES files");
            }
            char **q = realloc(p->ies_paths, sizeof *q * (size_t)p->capies);
            if (!q)
                return tb_error(TB_ERR_NOMEM, "scene: out of memory for IES files");
            p->ies_paths = q;
            tb_ies *ies;
            tb_status st = tb_ies_read(m->ies.path, &ies);
            if (st)
                return tb__located(st, s, m->loc, tb_light_kind_name(m->kind));
            p->ies[k] = ies;
            p->ies_paths[k] = tb_strdup(m->ies.path);
            p->nies++;
            if (!p->ies_paths[k])
                return tb_error(TB_ERR_NOMEM, "scene: out of memory for IES files");
        }
        e->ies = k;
    }
    return TB_OK;
}

/* ------------------------------------------------------------------ finishing */

/* Material indices of every node through `remap` (-1 stays -1). */
static void tb__remap_materials(tb_object *o, const int *remap)
{
    if (o->material >= 0)
        o->material = remap[o->material];
    for (int i = 0; i < o->nchildren; i++)
        tb__remap_materials(&o->children[i], remap);
}

static void tb__mark_used(const tb_object *o, bool *used)
{
    if (tb_prim_is_csg(o->kind)) {
        for (int i = 0; i < o->nchildren; i++)
            tb__mark_used(&o->children[i], used);
    } else if (o->material >= 0) {
        used[o->material] = true;
    }
}

static bool tb__is_spectral(const tb_mid_color *c) { return c->type != TB_MID_COLOR_RGB; }

/* Frees the source copies of the materials once the table holds them (about
 * 1 KB each, one per object in a scene of per-object colours: they would be
 * live through the acceleration build otherwise), keeping the strings the
 * table points to. */
static tb_status tb__drop_mat_srcs(tb__scene_priv *p, const bool *used)
{
    size_t n = 0;
    for (int i = 0; i < p->nmats; i++) {
        const tb__mat_src *e = &p->mats[i];
        n += used[i] ? (e->name != NULL) + (e->texture[0] != NULL) + (e->texture[1] != NULL) +
                           (e->texture[2] != NULL) + (e->texture[3] != NULL) +
                           (e->pat ? (e->pat[0].image.path != NULL) + (e->pat[1].image.path != NULL) +
                                         (e->pat[2].image.path != NULL)
                                   : 0)
                     : 0;
    }
    if (n && !(p->mat_strs = malloc(n * sizeof *p->mat_strs)))
        return tb_error(TB_ERR_NOMEM, "scene: out of memory for the material table");
    for (int i = 0; i < p->nmats; i++) {
        tb__mat_src *e = &p->mats[i];
        if (used[i]) { /* the table owns these now: tb__free_mat_src must not free them */
            char **keep[8] = {&e->name, &e->texture[0], &e->texture[1], &e->texture[2], &e->texture[3]};
            for (int k = 0; k < 3 && e->pat; k++)
                keep[5 + k] = (char **)&e->pat[k].image.path;
            for (int k = 0; k < (e->pat ? 8 : 5); k++)
                if (*keep[k]) {
                    p->mat_strs[p->nmat_strs++] = *keep[k];
                    *keep[k] = NULL;
                }
        }
        tb__free_mat_src(e);
    }
    free(p->mats);
    p->mats = NULL;
    p->nmats = p->capmats = 0;
    tb_htab_free(&p->mat_hash);
    return TB_OK;
}

/* Drops the materials no primitive uses (a CSG node's own material is only
 * inherited), decides the colour representation, converts every colour. */
static tb_status tb__finish_materials(tb_scene *s, const tb_scene_options *opt)
{
    tb__scene_priv *p = s->priv;
    bool *used = calloc((size_t)p->nmats + 1, sizeof *used);
    int *remap = malloc(sizeof *remap * ((size_t)p->nmats + 1));
    if (!used || !remap) {
        free(used);
        free(remap);
        return tb_error(TB_ERR_NOMEM, "scene: out of memory for the material table");
    }
    for (uint32_t i = 0; i < s->nobjects; i++)
        tb__mark_used(s->objects[i], used);
    int n = 0;
    for (int i = 0; i < p->nmats; i++)
        remap[i] = used[i] ? n++ : -1;
    for (uint32_t i = 0; i < s->nobjects; i++)
        tb__remap_materials(s->objects[i], remap);
    for (int i = 0; i < s->nemissive; i++)
        s->emissive[i].material = remap[s->emissive[i].material];

    bool spectral = false;
    for (int i = 0; i < p->nmats; i++)
        for (int k = 0; k < 4 && used[i]; k++)
            spectral = spectral || tb__is_spectral(&p->mats[i].color[k]) ||
                       (k < 2 && tb__src_pat(&p->mats[i], k)->kind != TB_MID_PATTERN_NONE &&
                        (tb__is_spectral(&p->mats[i].pat[k].a) || tb__is_spectral(&p->mats[i].pat[k].b)));
    for (int i = 0; i < s->nlights; i++)
        spectral = spectral || tb__is_spectral(&p->lights[i].l.intensity);
    if (opt->color == TB_SCENE_COLOR_RGB)
        spectral = false;
    else if (opt->color == TB_SCENE_COLOR_SPECTRAL)
        spectral = true;
    s->spectral = spectral;
    tb_status st = TB_OK;
    if (spectral) {
        if (opt->bands)
            s->bands = *opt->bands;
        else
            st = tb_bands_init_default(&s->bands);
        if (!st && (s->bands.n < 2 || s->bands.n > TB_CHANNELS_MAX))
            st = tb_error(TB_ERR_UNSUPPORTED, "scene: %d render bands (a colour holds 2..%d)", s->bands.n,
                          TB_CHANNELS_MAX);
        s->nchannels = s->bands.n;
    } else {
        s->nchannels = 3;
    }
    const tb_bands *bands = spectral ? &s->bands : NULL;

    s->materials = n ? calloc((size_t)n, sizeof *s->materials) : NULL;
    if (!st && n && !s->materials)
        st = tb_error(TB_ERR_NOMEM, "scene: out of memory for the material table");
    /* The patterns out of line: one of kind NONE shared by every material
     * without one, then one per pattern a used material has. */
    size_t npats = 1;
    for (int i = 0; i < p->nmats; i++)
        for (int k = 0; k < 3 && used[i]; k++)
            npats += tb__src_pat(&p->mats[i], k)->kind != TB_MID_PATTERN_NONE;
    if (!st && n && !(p->mat_pats = calloc(npats, sizeof *p->mat_pats)))
        st = tb_error(TB_ERR_NOMEM, "scene: out of memory for the material table");
    if (!st && n)
        p->mat_pats[0].a = p->mat_pats[0].b = tb_channels_splat(s->nchannels, 0.0f);
    size_t pat_next = 1;
    for (int i = 0; i < p->nmats && !st; i++) {
        if (!used[i])
            continue;
        const tb__mat_src *e = &p->mats[i];
        tb_material *m = &s->materials[remap[i]];
        tb_channels *out[4] = {&m->diffuse, &m->specular, &m->transmission, &m->emission};
        for (int k = 0; k < 4 && !st; k++) {
            st = tb_channels_from_mid_color(&e->color[k], bands, k == 3 ? TB_COLOR_EMISSION : TB_COLOR_REFLECTANCE,
                                            out[k]);
            if (st) {
                static const char *const names[4] = {"diffuse", "specular", "transmission", "emission"};
                char what[160];
                snprintf(what, sizeof what, "material%s%s%s, %s", e->name ? " '" : "", e->name ? e->name : "",
                         e->name ? "'" : "", names[k]);
                st = tb__located(st, s, e->loc, what);
            }
        }
        m->exponent = e->exponent;
        m->ior = e->ior;
        m->emits = e->emits;
        m->name = e->name;
        m->diffuse_texture = e->texture[0];
        m->specular_texture = e->texture[1];
        m->transmission_texture = e->texture[2];
        m->emission_texture = e->texture[3];
        m->model = e->model;
        m->roughness = e->roughness;
        const tb_material_pattern **mp[3] = {&m->diffuse_pattern, &m->specular_pattern, &m->bump};
        for (int k = 0; k < 3 && !st; k++) {
            const tb_mid_pattern *src = tb__src_pat(e, k);
            *mp[k] = &p->mat_pats[0];
            if (src->kind == TB_MID_PATTERN_NONE)
                continue;
            tb_material_pattern *d = &p->mat_pats[pat_next++];
            *mp[k] = d;
            d->kind = src->kind;
            d->object_space = src->object_space;
            d->scale = (float)src->scale;
            d->scale_v = (float)src->scale_v;
            d->octaves = src->octaves;
            d->height = (float)src->height;
            d->image = src->image.path;
            d->a = d->b = tb_channels_splat(s->nchannels, 0.0f);
            if (k < 2 &&
                ((st = tb_channels_from_mid_color(&src->a, bands, TB_COLOR_REFLECTANCE, &d->a)) ||
                 (st = tb_channels_from_mid_color(&src->b, bands, TB_COLOR_REFLECTANCE, &d->b)))) {
                char what[160];
                snprintf(what, sizeof what, "material%s%s%s, %s", e->name ? " '" : "", e->name ? e->name : "",
                         e->name ? "'" : "", k == 0 ? "diffuse_pattern" : "specular_pattern");
                st = tb__located(st, s, e->loc, what);
            }
        }
    }
    /* Unknown attributes move to the final numbering (only when some exist). */
    tb__scene_attrs *a = p->attrs;
    bool any = false;
    for (int i = 0; i < p->nmats && a; i++)
        any = any || (used[i] && p->mats[i].extra.count);
    if (!st && any && !(a->materials = calloc((size_t)n, sizeof *a->materials)))
        st = tb_error(TB_ERR_NOMEM, "scene: out of memory for unknown attributes");
    for (int i = 0; i < p->nmats && !st && any; i++)
        if (used[i])
            a->materials[remap[i]] = p->mats[i].extra;
    s->nmaterials = n;
    tb_stat_add(&tb__n_materials, n);
    if (!st)
        st = tb__drop_mat_srcs(p, used);
    free(used);
    free(remap);
    return st;
}

static tb_status tb__finish_lights(tb_scene *s)
{
    tb__scene_priv *p = s->priv;
    if (s->nlights == 0)
        return TB_OK;
    s->lights = calloc((size_t)s->nlights, sizeof *s->lights);
    if (!s->lights)
        return tb_error(TB_ERR_NOMEM, "scene: out of memory for lights");
    for (int i = 0; i < s->nlights; i++) {
        const tb__light_src *e = &p->lights[i];
        tb_status st = tb_light_from_mid(&e->l, s->spectral ? &s->bands : NULL, e->ies >= 0 ? p->ies[e->ies] : NULL,
                                         &s->lights[i]);
        if (st)
            return tb__located(st, s, e->l.loc, tb_light_kind_name(e->l.kind));
    }
    tb_stat_add(&tb__n_lights, s->nlights);
    return TB_OK;
}

/* The emitters of every emissive object: each object's made once (the
 * objects in parallel, each into its own array), then put together in
 * object order, so the result does not depend on the threads. */
static tb_status tb__finish_emitters(tb_scene *s, int threads, bool tessellate)
{
    int ne = s->nemissive;
    if (ne == 0)
        return TB_OK;
    tb_array *per = calloc((size_t)ne, sizeof *per);
    tb_status *sts = calloc((size_t)ne, sizeof *sts);
    size_t *tables = calloc((size_t)ne, sizeof *tables);
    if (!per || !sts || !tables) {
        free(per);
        free(sts);
        free(tables);
        return tb_error(TB_ERR_NOMEM, "scene: out of memory for emitters");
    }
    for (int i = 0; i < ne; i++)
        tb_array_init(&per[i], sizeof(tb_emitter));
    if (threads <= 0)
        threads = omp_get_max_threads();
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads) if (ne > 1)
    for (int i = 0; i < ne; i++) {
        tb_scene_emissive *e = &s->emissive[i];
        const tb_object *o = s->objects[e->object];
        tb_channels L = tb_radiance_from_exitance(s->materials[e->material].emission);
        sts[i] = tb__scene_leaf_emitters(o, L, tessellate, &per[i], &e->nemitters, &tables[i]);
    }
    tb_status st = TB_OK;
    size_t total = 0, table_bytes = 0;
    for (int i = 0; i < ne; i++) {
        if (!st && sts[i])
            st = tb_error(sts[i], "scene: out of memory for emitters");
        total += per[i].len;
        table_bytes += tables[i];
    }
    if (!st && total > (size_t)INT32_MAX)
        st = tb_error(TB_ERR_UNSUPPORTED, "scene: more than 2^31 - 1 emitters");
    if (!st) {
        /* The emitters and a renderer's area-light tables over them. */
        s->priv->used += total * (sizeof *s->emitters + 3 * sizeof(double)) + table_bytes;
        st = tb__check_memory(s, "with the emitters");
    }
    if (!st && total && !(s->emitters = malloc(sizeof *s->emitters * total)))
        st = tb_error(TB_ERR_NOMEM, "scene: out of memory for %zu emitters", total);
    int n = 0;
    for (int i = 0; i < ne; i++) {
        tb_scene_emissive *e = &s->emissive[i];
        if (!st) {
            e->first_emitter = n;
            e->nemitters = (int)per[i].len;
            if (per[i].len)
                memcpy(s->emitters + n, per[i].data, per[i].len * sizeof(tb_emitter));
            n += e->nemitters;
        } else {
            for (size_t k = 0; k < per[i].len; k++)
                tb__scene_free_emitter(tb_array_at(&per[i], k));
        }
        tb_array_free(&per[i]);
    }
    free(per);
    free(sts);
    free(tables);
    if (st)
        return st;
    s->nemitters = n;
    return TB_OK;
}

/* Number of acceleration references: one per triangle of a polygons object, one per other object. */
static size_t tb__count_prims(const tb_scene *s)
{
    size_t n = 0;
    for (uint32_t i = 0; i < s->nobjects; i++) {
        const tb_object *o = s->objects[i];
        n += o->kind == TB_PRIM_POLYGONS && o->mesh ? o->mesh->ntris : 1;
    }
    return n;
}

/* Fills prims[0 .. tb__count_prims(s)) with the references in build order;
 * *bounds (may be NULL) becomes their union. */
static tb_status tb__fill_prims(const tb_scene *s, tb_accel_prim *prims, tb_aabb *bounds)
{
    tb_aabb box = tb_aabb_empty();
    size_t k = 0;
    for (uint32_t i = 0; i < s->nobjects; i++) {
        const tb_object *o = s->objects[i];
        tb_status st;
        if (o->kind == TB_PRIM_POLYGONS && o->mesh) {
            for (uint32_t t = 0; t < o->mesh->ntris; t++) {
                tb_accel_prim *r = &prims[k++];
                r->object = i;
                r->sub = t;
                if ((st = tb__scene_tri_bounds(o, t, &r->bounds)))
                    return st;
                box = tb_aabb_union(box, r->bounds);
            }
        } else {
            tb_accel_prim *r = &prims[k++];
            r->object = i;
            r->sub = TB_SCENE_WHOLE_OBJECT;
            if ((st = tb__scene_object_bounds(o, &r->bounds)))
                return st;
            box = tb_aabb_union(box, r->bounds);
        }
    }
    if (bounds)
        *bounds = box;
    return TB_OK;
}

/* The acceleration references and the world bounds. The array lives until
 * the structure is built over it (which keeps its own copy). */
static tb_status tb__make_prims(tb_scene *s)
{
    size_t n = tb__count_prims(s);
    s->prims = n ? malloc(sizeof *s->prims * n) : NULL;
    if (n && !s->prims)
        return tb_error(TB_ERR_NOMEM, "scene: out of memory for %zu acceleration references", n);
    tb_status st = tb__fill_prims(s, s->prims, &s->bounds);
    if (st)
        return st;
    s->nprims = n;
    s->stats.nprims = n;
    tb_stat_add(&tb__n_tris, (int64_t)s->stats.triangles);
    tb_stat_add(&tb__n_refs, (int64_t)n);
    return TB_OK;
}

tb_status tb_scene_refs(const tb_scene *s, tb_accel_prim **out)
{
    *out = NULL;
    if (!s->nprims)
        return TB_OK;
    tb_accel_prim *p = malloc(sizeof *p * s->nprims);
    if (!p)
        return tb_error(TB_ERR_NOMEM, "scene: out of memory for %zu acceleration references", s->nprims);
    tb_status st = TB_OK;
    if (s->prims)
        memcpy(p, s->prims, sizeof *p * s->nprims);
    else
        st = tb__fill_prims(s, p, NULL);
    if (st) {
        free(p);
        return st;
    }
    *out = p;
    return TB_OK;
}

/* ------------------------------------------------------------------ accel callbacks */

/* False while this thread's current query is a tb_scene_intersect_no_uv. */
static _Thread_local bool tb__want_uv = true;

/* Whole objects only: the structure tests the triangle references itself
 * (tb_accel_tri, made by tb__scene_tri_make). */

static bool tb__cb_intersect(void *ctx, const tb_accel_prim *prim, uint32_t index, const tb_ray *ray, tb_hit *hit)
{
    (void)index;
    const tb_scene *s = ctx;
    const tb_object *o = s->objects[prim->object];
    return tb__want_uv ? tb_object_intersect(o, ray, hit) : tb_object_intersect_no_uv(o, ray, hit);
}

/* The object tb_scene_occluded_except leaves out of this thread's current
 * occlusion query (UINT32_MAX: none). */
static _Thread_local uint32_t tb__occ_skip = UINT32_MAX;

static bool tb__cb_occluded(void *ctx, const tb_accel_prim *prim, uint32_t index, const tb_ray *ray)
{
    (void)index;
    const tb_scene *s = ctx;
    if (prim->object == tb__occ_skip)
        return false;
    return tb_object_occluded(s->objects[prim->object], ray);
}

/* tb_accel_tri_fn: a reference's triangle record (object TB_ACCEL_TRI_NONE for a whole object). */
static void tb__scene_tri_cb(void *ctx, const tb_accel_prim *r, uint32_t index, tb_accel_tri *out)
{
    (void)index;
    const tb_scene *s = ctx;
    if (r->sub == TB_SCENE_WHOLE_OBJECT)
        *out = (tb_accel_tri){.object = TB_ACCEL_TRI_NONE};
    else
        tb__scene_tri_make(s->objects[r->object], r->sub, out);
}

tb_status tb_scene_rebuild_accel(tb_scene *s, tb_accel_kind kind, const tb_accel_options *opt)
{
    if (!s)
        return tb_error(TB_ERR_ARG, "scene: NULL argument");
    int64_t t0 = tb_stats_now_ns();
    tb_timer_token tt = tb_timer_start(&tb__t_accel);
    tb_accel_prim *prims = s->prims;
    if (!prims) { /* dropped after the last build: made again */
        tb_status st = tb_scene_refs(s, &prims);
        if (st) {
            tb_timer_stop(tt);
            return st;
        }
    }
    bool any_tri = false;
    for (size_t k = 0; k < s->nprims && !any_tri; k++)
        any_tri = prims[k].sub != TB_SCENE_WHOLE_OBJECT;
    /* The triangle references' corners: records the structure makes through
     * the callback once its tree is built, in its order (no array of them
     * through the build: 80 bytes per reference). None when there is no
     * triangle reference (the structure then keeps no record per reference:
     * every one goes to the callbacks, as a whole-object reference does). */
    tb_accel_callbacks cb = {tb__cb_intersect, tb__cb_occluded, s, NULL};
    /* The structure takes the scene's array as its own (tb_scene_refs makes
     * it again for the few that need it in the scene's order). */
    s->prims = NULL;
    tb_accel *acc;
    tb_status st = tb_accel_build_owned(kind, prims, s->nprims, &cb, any_tri ? tb__scene_tri_cb : NULL, s, opt, &acc);
    tb_timer_stop(tt);
    if (st)
        return tb_error_context(st, "scene");
    tb_accel_free(s->accel);
    s->accel = acc;
    s->stats.accel_seconds = (double)(tb_stats_now_ns() - t0) * 1e-9;
    return TB_OK;
}

/* ------------------------------------------------------------------ loading */

static tb_status tb__load(tb_mid_reader *r, const char *name, const tb_scene_options *opt, tb_scene **out)
{
    static const tb_scene_options defaults;
    if (!opt)
        opt = &defaults;
    int64_t t0 = tb_stats_now_ns();
    tb_timer_token tt = tb_timer_start(&tb__t_load);
    tb_scene *s = calloc(1, sizeof *s);
    tb__scene_priv *p = s ? calloc(1, sizeof *p) : NULL;
    if (!s || !p) {
        free(s);
        free(p);
        tb_timer_stop(tt);
        return tb_error(TB_ERR_NOMEM, "scene: out of memory");
    }
    s->priv = p;
    tb_htab_init(&p->mat_hash, TB_HTAB_U64);
    p->feds = tb_object_fed_cache_new();
    p->budget = opt->memory_budget > 0;
    p->limit = p->budget ? opt->memory_budget : tb_scene_available_memory() / 10 * 9;
    s->name = tb_strdup(name);
    p->errname = s->name ? s->name : "";
    tb_status st = s->name && p->feds ? TB_OK : tb_error(TB_ERR_NOMEM, "scene: out of memory");
    tb_mid_item it;
    while (!st && !(st = tb_mid_reader_next(r, &it)) && it.type != TB_MID_ITEM_END) {
        if (it.type == TB_MID_ITEM_OBJECT)
            st = tb__add_object(s, it.object);
        else if (it.type == TB_MID_ITEM_LIGHT)
            st = tb__add_light(s, it.light);
        else if (it.type == TB_MID_ITEM_MATERIAL)
            st = tb__attrs_named_material(s, it.material);
        /* Named materials matter only through the objects that use them
         * (their unknown attributes are remembered for those); the camera
         * is read at the end. */
    }
    if (!st) {
        const tb_mid_camera *cam = tb_mid_reader_camera(r);
        s->has_camera = cam != NULL;
        s->mid_camera = cam ? *cam : tb_mid_camera_default();
        s->mid_camera.name = NULL;
        s->mid_camera.extra = (tb_mid_attrs){NULL, 0};
        s->mid_camera.nrefs = 0;
        s->mid_camera.refs = NULL;
        st = tb_camera_from_mid(&s->mid_camera, 0, 0, &s->camera);
        if (st && cam)
            st = tb__located(st, s, cam->loc, "camera");
        if (!st && cam && cam->extra.count) {
            tb__scene_attrs *a = tb__attrs_store(s);
            st = a ? tb__attrs_copy(a, cam->extra, &a->camera)
                   : tb_error(TB_ERR_NOMEM, "scene: out of memory for unknown attributes");
        }
    }
    if (!st)
        st = tb__finish_materials(s, opt);
    if (!st)
        st = tb__finish_lights(s);
    if (!st && !opt->no_emitters)
        st = tb__finish_emitters(s, opt->threads, opt->tessellated_emitters);
    if (!st)
        tb_stat_add(&tb__n_emissive, s->nemissive);
    if (!st)
        st = tb__make_prims(s);
    /* The copies were needed only for the conversion; the shared FED files
     * live on with the objects that hold them. */
    tb_htab_free(&p->mat_hash);
    s->stats.fed_files = tb_object_fed_cache_files(p->feds);
    s->stats.fed_bytes = tb_object_fed_cache_bytes(p->feds);
    tb_object_fed_cache_free(p->feds);
    p->feds = NULL;
    s->stats.load_seconds = (double)(tb_stats_now_ns() - t0) * 1e-9;
    tb_timer_stop(tt);
    if (!st && !opt->no_accel) {
        tb_accel_options ao = opt->accel_opts;
        if (ao.threads == 0)
            ao.threads = opt->threads;
        st = tb_scene_rebuild_accel(s, opt->accel, &ao);
    }
    if (st) {
        tb_scene_free(s);
        return st;
    }
    tb_scene_memory_use mu;
    tb_scene_memory(s, &mu);
    tb_stat_add(&tb__m_objects, (int64_t)mu.objects);
    tb_stat_add(&tb__m_meshes, (int64_t)mu.meshes);
    tb_stat_add(&tb__m_fed, (int64_t)mu.fed);
    tb_stat_add(&tb__m_emitters, (int64_t)mu.emitters);
    tb_stat_add(&tb__m_accel, (int64_t)(mu.prims + mu.accel));
    tb_stat_add(&tb__m_total, (int64_t)mu.total);
    if (mu.nobjects)
        tb_stat_ratio_add(&tb__r_per_object, (int64_t)(mu.per_object * (double)mu.nobjects + 0.5), (int64_t)mu.nobjects);
    if (mu.triangles)
        tb_stat_ratio_add(&tb__r_per_tri, (int64_t)(mu.per_triangle * (double)mu.triangles + 0.5),
                          (int64_t)mu.triangles);
    *out = s;
    return TB_OK;
}

tb_status tb_scene_load(const char *path, const tb_scene_options *opt, tb_scene **out)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "scene: NULL argument");
    *out = NULL;
    if (!path)
        return tb_error(TB_ERR_ARG, "scene: NULL path");
    if (opt && opt->memory_budget && strcmp(path, "-") != 0) {
        /* Refuse before building anything: a streaming pass predicts the need. */
        tb_scene_memory_use u;
        tb_status pst = tb_scene_predict_memory(path, &u);
        if (pst)
            return pst;
        tb_stat_add(&tb__m_predicted, (int64_t)u.total);
        if (u.total > opt->memory_budget) {
            char parts[1024];
            tb__scene_memory_describe(&u, parts, sizeof parts);
            return tb_error(TB_ERR_NOMEM,
                            "%s: the scene needs about %.1f MiB, more than the memory budget of %.1f MiB: %s; "
                            "nothing was loaded",
                            path, (double)u.total / 1048576.0, (double)opt->memory_budget / 1048576.0, parts);
        }
    }
    tb_mid_reader *r;
    tb_status st = tb_mid_reader_open(&r, path);
    if (st)
        return st;
    st = tb__load(r, strcmp(path, "-") == 0 ? "<stdin>" : path, opt, out);
    tb_mid_reader_close(r);
    return st;
}

tb_status tb_scene_load_stream(FILE *fp, const char *name, const char *base_dir, const tb_scene_options *opt,
                               tb_scene **out)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "scene: NULL argument");
    *out = NULL;
    if (!fp)
        return tb_error(TB_ERR_ARG, "scene: NULL stream");
    if (!name)
        name = "<stream>";
    tb_mid_reader *r;
    tb_status st = tb_mid_reader_open_stream(&r, fp, name, base_dir);
    if (st)
        return st;
    st = tb__load(r, name, opt, out);
    tb_mid_reader_close(r);
    return st;
}

void tb_scene_free(tb_scene *s)
{
    if (!s)
        return;
    tb_accel_free(s->accel);
    for (uint32_t i = 0; i < s->nobjects; i++)
        tb_object_free(s->objects[i]);
    free(s->objects);
    free(s->materials);
    free(s->lights);
    free(s->emissive);
    for (int i = 0; i < s->nemitters; i++)
        tb__scene_free_emitter(&s->emitters[i]);
    free(s->emitters);
    free(s->prims);
    tb__scene_priv *p = s->priv;
    if (p) {
        for (int i = 0; i < p->nmats; i++)
            tb__free_mat_src(&p->mats[i]);
        free(p->mats);
        tb_htab_free(&p->mat_hash);
        for (size_t i = 0; i < p->nmat_strs; i++)
            free(p->mat_strs[i]);
        free(p->mat_strs);
        free(p->mat_pats);
        for (int i = 0; i < s->nlights; i++) {
            tb__free_color(&p->lights[i].l.intensity);
            free((void *)p->lights[i].l.name);
        }
        free(p->lights);
        for (int i = 0; i < p->nies; i++) {
            tb_ies_free(p->ies[i]);
            free(p->ies_paths[i]);
        }
        free(p->ies);
        free(p->ies_paths);
        tb__attrs_free(p->attrs);
        tb_object_fed_cache_free(p->feds);
        free(p);
    }
    free(s->name);
    free(s);
}

/* ------------------------------------------------------------------ queries */

bool tb_scene_intersect(const tb_scene *s, const tb_ray *ray, tb_hit *hit)
{
    if (!s || !s->accel)
        return false;
    tb_accel_tri_hit tri;
    if (!tb_accel_intersect_tri(s->accel, ray, hit, &tri))
        return false;
    if (tri.index != TB_ACCEL_TRI_NONE)
        tb__scene_tri_finish(s, ray, &tri, hit, true);
    return true;
}

bool tb_scene_intersect_no_uv(const tb_scene *s, const tb_ray *ray, tb_hit *hit)
{
    if (!s || !s->accel)
        return false;
    tb_accel_tri_hit tri;
    tb__want_uv = false;
    bool found = tb_accel_intersect_tri(s->accel, ray, hit, &tri);
    tb__want_uv = true;
    if (!found)
        return false;
    if (tri.index != TB_ACCEL_TRI_NONE)
        tb__scene_tri_finish(s, ray, &tri, hit, false);
    return true;
}

bool tb_scene_occluded(const tb_scene *s, const tb_ray *ray)
{
    return s && s->accel && tb_accel_occluded(s->accel, ray);
}

bool tb_scene_occluded_except(const tb_scene *s, const tb_ray *ray, uint32_t object)
{
    if (!s || !s->accel)
        return false;
    tb__occ_skip = object;
    bool blocked = tb_accel_occluded(s->accel, ray);
    tb__occ_skip = UINT32_MAX;
    return blocked;
}

const tb_object *tb_scene_hit_leaf(const tb_scene *s, const tb_hit *hit, uint32_t *local)
{
    if (!s || !hit || hit->object >= s->nobjects)
        return NULL;
    const tb_object *o = s->objects[hit->object];
    if (tb_prim_is_csg(o->kind))
        return tb_object_leaf_for_face(o, hit->face, local);
    if (local)
        *local = hit->face;
    return o;
}

const tb_material *tb_scene_hit_material(const tb_scene *s, const tb_hit *hit)
{
    const tb_object *leaf = tb_scene_hit_leaf(s, hit, NULL);
    if (!leaf || leaf->material < 0 || leaf->material >= s->nmaterials)
        return NULL;
    return &s->materials[leaf->material];
}

void tb_scene_print_summary(const tb_scene *s, FILE *out)
{
    if (!s || !out)
        return;
    fprintf(out, "scene %s: %u objects (", s->name, s->nobjects);
    bool first = true;
    for (int k = 0; k < TB_PRIM_COUNT; k++) {
        if (!s->stats.objects_by_kind[k])
            continue;
        fprintf(out, "%s%u %s", first ? "" : ", ", s->stats.objects_by_kind[k], tb_prim_kind_name((tb_prim_kind)k));
        first = false;
    }
    fprintf(out, "), %llu triangles, %d materials, %s colours (%d channels), %d lights, %d emissive objects "
                 "(%d emitters)\n",
            (unsigned long long)s->stats.triangles, s->nmaterials, s->spectral ? "spectral" : "RGB", s->nchannels,
            s->nlights, s->nemissive, s->nemitters);
    fprintf(out, "camera: %s%dx%d, fov %.6g x %.6g degrees%s\n", s->has_camera ? "" : "(default) ", s->camera.width,
            s->camera.height, s->camera.fov_x, s->camera.fov_y, s->camera.lens_radius > 0.0 ? ", thin lens" : "");
    if (!tb_aabb_is_empty(&s->bounds))
        fprintf(out, "bounds: [%g %g %g] - [%g %g %g]\n", s->bounds.lo.x, s->bounds.lo.y, s->bounds.lo.z,
                s->bounds.hi.x, s->bounds.hi.y, s->bounds.hi.z);
    if (s->accel) {
        tb_accel_stats as;
        tb_accel_get_stats(s->accel, &as);
        fprintf(out, "accel: %s over %zu references, built in %.3f ms", tb_accel_kind_name(as.kind), as.nprims,
                as.build_seconds * 1e3);
        if (as.kind == TB_ACCEL_BVH)
            fprintf(out, " (%zu nodes, %zu 8-wide, depth %d, SAH cost %.2f)", as.bvh_nodes, as.bvh_wide_nodes,
                    as.bvh_depth, as.bvh_sah_cost);
        else if (as.kind == TB_ACCEL_GRID)
            fprintf(out, " (%dx%dx%d voxels, %zu pairs)", as.grid_res[0], as.grid_res[1], as.grid_res[2],
                    as.grid_refs);
        fprintf(out, "\n");
    }
    fprintf(out, "load: %.3f ms\n", s->stats.load_seconds * 1e3);
    tb_scene_memory_use mu;
    tb_scene_memory(s, &mu);
    fprintf(out, "memory: %.1f MiB (objects %.1f, meshes %.1f, FED files %.1f, materials %.1f, emitters %.1f, "
                 "acceleration %.1f); %.0f bytes per object, %.0f per triangle\n",
            (double)mu.total / 1048576.0, (double)mu.objects / 1048576.0, (double)mu.meshes / 1048576.0,
            (double)mu.fed / 1048576.0, (double)mu.materials / 1048576.0, (double)mu.emitters / 1048576.0,
            (double)(mu.prims + mu.accel) / 1048576.0, mu.per_object, mu.per_triangle);
}
