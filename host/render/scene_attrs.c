/* Unknown MID attributes kept for renderers (docs/rendering.md, "Attributes
 * for renderers"). The reader's values die at its next item, so the scene
 * deep-copies them into one arena of its own. Only what has attributes is
 * stored, in side tables keyed by node address, material, light or camera:
 * the objects themselves do not grow, which matters for scenes of millions
 * of objects (docs/performance.md). */
#include "host/render/scene.h"

#include <stdlib.h>
#include <string.h>

#include "host/render/scene_internal.h"

/* Body and geometry-block attributes of one object node. */
typedef struct tb__node_attrs {
    tb_mid_attrs body, geometry;
} tb__node_attrs;

static const tb_mid_attrs tb__none = {NULL, 0};

/* ------------------------------------------------------------------ deep copies */

static bool tb__copy_value(tb_arena *ar, const tb_mid_value *src, tb_mid_value *dst);

static const char *tb__dup(tb_arena *ar, const char *s, bool *ok)
{
    if (!s)
        return NULL;
    char *d = tb_arena_strdup(ar, s);
    if (!d)
        *ok = false;
    return d;
}

static bool tb__copy_run(tb_arena *ar, const tb_mid_attr *src, int n, const tb_mid_attr **out)
{
    *out = NULL;
    if (n <= 0)
        return true;
    tb_mid_attr *d = tb_arena_alloc(ar, sizeof *d * (size_t)n);
    if (!d)
        return false;
    bool ok = true;
    for (int i = 0; i < n && ok; i++) {
        d[i].loc = src[i].loc;
        d[i].name = tb__dup(ar, src[i].name, &ok);
        ok = ok && tb__copy_value(ar, &src[i].value, &d[i].value);
    }
    *out = d;
    return ok;
}

static bool tb__copy_value(tb_arena *ar, const tb_mid_value *src, tb_mid_value *dst)
{
    *dst = *src;
    bool ok = true;
    dst->name = tb__dup(ar, src->name, &ok);
    switch (src->type) {
    case TB_MID_NUMBER:
        break;
    case TB_MID_STRING:
    case TB_MID_SYMBOL:
        dst->text = tb__dup(ar, src->text, &ok);
        break;
    case TB_MID_VECTOR:
        dst->numbers = NULL;
        if (src->count > 0) {
            double *d = tb_arena_alloc(ar, sizeof *d * (size_t)src->count);
            if (!d)
                return false;
            memcpy(d, src->numbers, sizeof *d * (size_t)src->count);
            dst->numbers = d;
        }
        break;
    case TB_MID_LIST:
    case TB_MID_CALL:
        dst->items = NULL;
        if (src->count > 0) {
            tb_mid_value *d = tb_arena_alloc(ar, sizeof *d * (size_t)src->count);
            if (!d)
                return false;
            for (int i = 0; i < src->count && ok; i++)
                ok = tb__copy_value(ar, &src->items[i], &d[i]);
            dst->items = d;
        }
        break;
    case TB_MID_BLOCK:
        ok = ok && tb__copy_run(ar, src->attrs, src->count, &dst->attrs);
        break;
    case TB_MID_FILE:
        dst->ref.text = tb__dup(ar, src->ref.text, &ok);
        dst->ref.path = tb__dup(ar, src->ref.path, &ok);
        break;
    }
    return ok;
}

tb_status tb__attrs_copy(tb__scene_attrs *a, tb_mid_attrs src, tb_mid_attrs *dst)
{
    *dst = tb__none;
    if (src.count <= 0)
        return TB_OK;
    if (!tb__copy_run(&a->arena, src.items, src.count, &dst->items))
        return tb_error(TB_ERR_NOMEM, "scene: out of memory for unknown attributes");
    dst->count = src.count;
    return TB_OK;
}

void tb__attrs_free(tb__scene_attrs *a)
{
    if (!a)
        return;
    for (int i = 0; i < a->npending; i++)
        free(a->pending[i].owned);
    free(a->pending);
    free(a->materials);
    free(a->lights);
    tb_htab_free(&a->nodes);
    tb_htab_free(&a->named);
    tb_arena_free(&a->arena);
    free(a);
}

/* ------------------------------------------------------------------ material keys */

typedef void (*tb__put_fn)(void *ctx, const void *p, size_t n);

static void tb__key_str(const char *s, tb__put_fn put, void *ctx)
{
    uint32_t n = s ? (uint32_t)strlen(s) + 1 : 0; /* 0: none; else the length with the terminator */
    put(ctx, &n, sizeof n);
    if (s)
        put(ctx, s, n);
}

static void tb__key_value(const tb_mid_value *v, tb__put_fn put, void *ctx)
{
    int32_t head[2] = {(int32_t)v->type, v->count};
    put(ctx, head, sizeof head);
    switch (v->type) {
    case TB_MID_NUMBER:
        put(ctx, &v->number, sizeof v->number);
        break;
    case TB_MID_STRING:
    case TB_MID_SYMBOL:
        tb__key_str(v->text, put, ctx);
        break;
    case TB_MID_VECTOR:
        if (v->count > 0)
            put(ctx, v->numbers, sizeof *v->numbers * (size_t)v->count);
        break;
    case TB_MID_CALL:
    case TB_MID_LIST:
        tb__key_str(v->name, put, ctx); /* NULL for a list */
        for (int i = 0; i < v->count; i++)
            tb__key_value(&v->items[i], put, ctx);
        break;
    case TB_MID_BLOCK:
        tb__attrs_key((tb_mid_attrs){v->attrs, v->count}, put, ctx);
        break;
    case TB_MID_FILE:
        tb__key_str(v->ref.text, put, ctx);
        tb__key_str(v->ref.path, put, ctx);
        break;
    }
}

void tb__attrs_key(tb_mid_attrs a, void (*put)(void *ctx, const void *p, size_t n), void *ctx)
{
    int32_t n = a.count;
    put(ctx, &n, sizeof n);
    for (int i = 0; i < a.count; i++) {
        tb__key_str(a.items[i].name, put, ctx);
        tb__key_value(&a.items[i].value, put, ctx);
    }
}

/* ------------------------------------------------------------------ effective material attributes */

static const tb_mid_attr *tb__find(tb_mid_attrs a, const char *name)
{
    for (int i = 0; i < a.count; i++)
        if (strcmp(a.items[i].name, name) == 0)
            return &a.items[i];
    return NULL;
}

/* `base` then `own`, own replacing same-named entries of base: the way a
 * rendering block's known attributes override the material it starts from.
 * *owned is the new array when one had to be made (else NULL). */
static tb_status tb__merge(tb_mid_attrs base, tb_mid_attrs own, tb_mid_attrs *out, tb_mid_attr **owned)
{
    *owned = NULL;
    if (base.count == 0 || own.count == 0) {
        *out = base.count ? base : own;
        return TB_OK;
    }
    tb_mid_attr *m = malloc(sizeof *m * ((size_t)base.count + (size_t)own.count));
    if (!m)
        return tb_error(TB_ERR_NOMEM, "scene: out of memory for unknown attributes");
    int n = 0;
    for (int i = 0; i < base.count; i++)
        if (!tb__find(own, base.items[i].name))
            m[n++] = base.items[i];
    memcpy(m + n, own.items, sizeof *m * (size_t)own.count);
    *out = (tb_mid_attrs){m, n + own.count};
    *owned = m;
    return TB_OK;
}

/* The effective attributes of named material `name` (none if it has none). */
static tb_mid_attrs tb__named(const tb_scene *s, const char *name)
{
    const tb__scene_attrs *a = tb__attrs_peek(s);
    uint64_t v;
    if (!a || !name || !tb_htab_get_str(&a->named, name, &v))
        return tb__none;
    return *(const tb_mid_attrs *)(uintptr_t)v;
}

tb_status tb__attrs_named_material(tb_scene *s, const tb_mid_material *def)
{
    if (!def->name)
        return TB_OK;
    tb_mid_attrs eff;
    tb_mid_attr *owned;
    tb_status st = tb__merge(tb__named(s, def->base), def->extra, &eff, &owned);
    if (st)
        return st;
    tb__scene_attrs *a = eff.count ? tb__attrs_store(s) : (tb__scene_attrs *)tb__attrs_peek(s);
    if (eff.count && !a)
        st = tb_error(TB_ERR_NOMEM, "scene: out of memory for unknown attributes");
    tb_mid_attrs *slot = a && eff.count ? tb_arena_alloc(&a->arena, sizeof *slot) : NULL;
    if (!st && eff.count && !slot)
        st = tb_error(TB_ERR_NOMEM, "scene: out of memory for unknown attributes");
    if (!st && slot && !(st = tb__attrs_copy(a, eff, slot)) &&
        tb_htab_put_str(&a->named, def->name, (uint64_t)(uintptr_t)slot))
        st = tb_error(TB_ERR_NOMEM, "scene: out of memory for unknown attributes");
    else if (!st && !slot && a)
        tb_htab_del_str(&a->named, def->name); /* a redefinition without attributes has none */
    free(owned);
    return st;
}

static tb_status tb__pend(tb_scene *s, const tb_mid_object *m, tb_mid_attrs inherited)
{
    const tb_mid_material *mat = &m->material;
    tb_mid_attrs start = mat->base ? tb__named(s, mat->base) : inherited;
    tb_mid_attrs eff;
    tb_mid_attr *owned;
    tb_status st = tb__merge(start, mat->extra, &eff, &owned);
    if (st)
        return st;
    if (eff.count) {
        tb__scene_attrs *a = tb__attrs_store(s);
        if (a && a->npending == a->cappending) {
            int nc = a->cappending ? 2 * a->cappending : 8;
            tb__attrs_pending *q = realloc(a->pending, sizeof *q * (size_t)nc);
            if (q) {
                a->pending = q;
                a->cappending = nc;
            }
        }
        if (!a || a->npending == a->cappending) {
            free(owned);
            return tb_error(TB_ERR_NOMEM, "scene: out of memory for unknown attributes");
        }
        a->pending[a->npending++] = (tb__attrs_pending){mat, eff, owned};
    }
    for (int i = 0; i < m->nchildren && !st; i++)
        st = tb__pend(s, &m->children[i], eff);
    return st;
}

tb_status tb__attrs_begin_object(tb_scene *s, const tb_mid_object *m)
{
    return tb__pend(s, m, tb__none);
}

tb_mid_attrs tb__attrs_of_material(tb_scene *s, const tb_mid_material *m)
{
    tb__scene_attrs *a = (tb__scene_attrs *)tb__attrs_peek(s);
    if (!a || a->npending == 0)
        return tb__none;
    /* The build visits nodes in pre-order, as they were pended: usually the next one. */
    if (a->cursor < a->npending && a->pending[a->cursor].mat == m)
        return a->pending[a->cursor++].attrs;
    for (int i = 0; i < a->npending; i++)
        if (a->pending[i].mat == m)
            return a->pending[i].attrs;
    return tb__none;
}

static tb_status tb__keep_nodes(tb__scene_attrs **a, tb_scene *s, const tb_mid_object *m, const tb_object *o)
{
    if (m->extra.count || m->geometry_extra.count) {
        if (!*a && !(*a = tb__attrs_store(s)))
            return tb_error(TB_ERR_NOMEM, "scene: out of memory for unknown attributes");
        tb__node_attrs *n = tb_arena_alloc(&(*a)->arena, sizeof *n);
        if (!n)
            return tb_error(TB_ERR_NOMEM, "scene: out of memory for unknown attributes");
        tb_status st;
        if ((st = tb__attrs_copy(*a, m->extra, &n->body)) || (st = tb__attrs_copy(*a, m->geometry_extra, &n->geometry)))
            return st;
        if (tb_htab_put(&(*a)->nodes, (uint64_t)(uintptr_t)o, (uint64_t)(uintptr_t)n))
            return tb_error(TB_ERR_NOMEM, "scene: out of memory for unknown attributes");
    }
    int n = m->nchildren < o->nchildren ? m->nchildren : o->nchildren;
    for (int i = 0; i < n; i++) {
        tb_status st = tb__keep_nodes(a, s, &m->children[i], &o->children[i]);
        if (st)
            return st;
    }
    return TB_OK;
}

tb_status tb__attrs_end_object(tb_scene *s, const tb_mid_object *m, const tb_object *o)
{
    tb__scene_attrs *a = (tb__scene_attrs *)tb__attrs_peek(s);
    if (a) {
        for (int i = 0; i < a->npending; i++)
            free(a->pending[i].owned);
        a->npending = a->cursor = 0;
    }
    return o ? tb__keep_nodes(&a, s, m, o) : TB_OK;
}

/* ------------------------------------------------------------------ lookups */

tb_mid_attrs tb_scene_node_attrs(const tb_scene *s, const tb_object *node, bool geometry)
{
    const tb__scene_attrs *a = s ? tb__attrs_peek(s) : NULL;
    uint64_t v;
    if (!a || !node || !tb_htab_get(&a->nodes, (uint64_t)(uintptr_t)node, &v))
        return tb__none;
    const tb__node_attrs *n = (const tb__node_attrs *)(uintptr_t)v;
    return geometry ? n->geometry : n->body;
}

tb_mid_attrs tb_scene_material_attrs(const tb_scene *s, int material)
{
    const tb__scene_attrs *a = s ? tb__attrs_peek(s) : NULL;
    if (!a || !a->materials || material < 0 || material >= s->nmaterials)
        return tb__none;
    return a->materials[material];
}

tb_mid_attrs tb_scene_light_attrs(const tb_scene *s, int light)
{
    const tb__scene_attrs *a = s ? tb__attrs_peek(s) : NULL;
    if (!a || light < 0 || light >= a->caplights)
        return tb__none;
    return a->lights[light];
}

tb_mid_attrs tb_scene_camera_attrs(const tb_scene *s)
{
    const tb__scene_attrs *a = s ? tb__attrs_peek(s) : NULL;
    return a ? a->camera : tb__none;
}

const tb_mid_value *tb_scene_attr_find(tb_mid_attrs attrs, const char *name)
{
    const tb_mid_attr *a = name ? tb__find(attrs, name) : NULL;
    return a ? &a->value : NULL;
}

const tb_mid_value *tb_scene_node_attr(const tb_scene *s, const tb_object *node, const char *name)
{
    const tb_mid_value *v = tb_scene_attr_find(tb_scene_node_attrs(s, node, false), name);
    return v ? v : tb_scene_attr_find(tb_scene_node_attrs(s, node, true), name);
}

const tb_mid_value *tb_scene_object_attr(const tb_scene *s, uint32_t object, const char *name)
{
    if (!s || object >= s->nobjects)
        return NULL;
    return tb_scene_node_attr(s, s->objects[object], name);
}

const tb_mid_value *tb_scene_material_attr(const tb_scene *s, int material, const char *name)
{
    return tb_scene_attr_find(tb_scene_material_attrs(s, material), name);
}

const tb_mid_value *tb_scene_light_attr(const tb_scene *s, int light, const char *name)
{
    return tb_scene_attr_find(tb_scene_light_attrs(s, light), name);
}

const tb_mid_value *tb_scene_camera_attr(const tb_scene *s, const char *name)
{
    return tb_scene_attr_find(tb_scene_camera_attrs(s), name);
}

const tb_mid_value *tb_scene_attr_field(const tb_mid_value *block, const char *name)
{
    if (!block || block->type != TB_MID_BLOCK)
        return NULL;
    return tb_scene_attr_find((tb_mid_attrs){block->attrs, block->count}, name);
}

double tb_scene_attr_number(const tb_mid_value *v, double def)
{
    return v && v->type == TB_MID_NUMBER ? v->number : def;
}

const char *tb_scene_attr_string(const tb_mid_value *v, const char *def)
{
    return v && (v->type == TB_MID_STRING || v->type == TB_MID_SYMBOL) ? v->text : def;
}

const double *tb_scene_attr_vector(const tb_mid_value *v, int n, const double *def)
{
    return v && v->type == TB_MID_VECTOR && v->count == n && n > 0 ? v->numbers : def;
}
