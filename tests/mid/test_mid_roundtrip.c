/* Property test: read(write(x)) == x for random scenes x built directly as
 * object models (every kind, nested CSG, named materials with overrides,
 * lights, a camera, unknown attributes with nested values, strings with
 * escapes and UTF-8, file references), and write(read(write(x))) ==
 * write(x) byte for byte (the canonical form is a fixed point).
 *
 * The generator follows the rules of docs/mid.md: a rendering block starts
 * from its base material or the inherited one, references are listed in the
 * writer's order, a transform is the operations composed in order. */
#include "tb_test.h"

#include <locale.h>
#include <string.h>

#include "host/mid/mid_reader.h"
#include "host/mid/mid_writer.h"
#include "util/container/arena.h"

#define DATA TB_TESTS_DIR "/mid/data"

typedef struct gen {
    tb_rng rng;
    tb_arena *a;
    const tb_mid_material *mats[32]; /* named materials defined so far */
    int nmats;
    int serial;                      /* for unique names */
} gen;

static uint32_t below(gen *g, uint32_t n) { return tb_rng_below(&g->rng, n); }
static bool chance(gen *g, int percent) { return below(g, 100) < (uint32_t)percent; }
static double uniform(gen *g, double lo, double hi) { return lo + (hi - lo) * tb_rng_double(&g->rng); }

static void *alloc(gen *g, size_t n)
{
    void *p = tb_arena_alloc_zero(g->a, n ? n : 1);
    assert_non_null(p);
    return p;
}

/* A double of any kind the writer must reproduce: integers, short decimals,
 * full-precision values over a wide range of exponents, negatives. */
static double any_double(gen *g)
{
    switch (below(g, 4)) {
    case 0: return (double)((int)below(g, 41) - 20);
    case 1: return (double)((int)below(g, 2001) - 1000) / 8.0;
    case 2: return uniform(g, -1000.0, 1000.0);
    default: return ldexp(uniform(g, -1.0, 1.0), (int)below(g, 80) - 40);
    }
}

static float any_float(gen *g, double lo, double hi)
{
    return chance(g, 30) ? (float)(lo + (double)below(g, 5) * (hi - lo) / 4.0) : (float)uniform(g, lo, hi);
}

static char *dup(gen *g, const char *s)
{
    char *d = alloc(g, strlen(s) + 1);
    strcpy(d, s);
    return d;
}

/* A string with quotes, backslashes, control characters, UTF-8 and '#'. */
static char *any_string(gen *g)
{
    static const char *const pieces[] = {"a", "Z", " ", "\"", "\\", "\n", "\t", "\r", "\x01", "\x1f", "\x7f",
                                         "\xC3\xA9", "\xF0\x9F\x98\x80", "\xE4\xB8\xAD", "#", "{", "file(", "0"};
    char buf[256] = "";
    int n = (int)below(g, 10);
    for (int i = 0; i < n; i++)
        strcat(buf, pieces[below(g, sizeof pieces / sizeof pieces[0])]);
    return dup(g, buf);
}

/* An identifier no scope knows: x_<letters><serial>. */
static char *unknown_name(gen *g)
{
    char buf[32];
    snprintf(buf, sizeof buf, "x_%c%c%d", 'a' + (int)below(g, 26), 'a' + (int)below(g, 26), g->serial++);
    return dup(g, buf);
}

static tb_mid_ref any_ref(gen *g)
{
    static const char *const texts[] = {"checker.png", "./checker.png", "../data/checker.png", DATA "/checker.png"};
    const char *t = texts[below(g, 4)];
    tb_mid_ref r;
    r.text = dup(g, t);
    if (t[0] == '/')
        r.path = r.text;
    else {
        char buf[1024];
        snprintf(buf, sizeof buf, "%s/%s", DATA, t);
        r.path = dup(g, buf);
    }
    return r;
}

static void any_value(gen *g, tb_mid_value *v, int depth);

static tb_mid_attrs any_attrs(gen *g, int max, int depth)
{
    int n = (int)below(g, (uint32_t)max + 1);
    tb_mid_attr *a = alloc(g, (size_t)n * sizeof *a);
    for (int i = 0; i < n; i++) {
        a[i].name = unknown_name(g);
        any_value(g, &a[i].value, depth + 1);
    }
    return (tb_mid_attrs){a, n};
}

static void any_value(gen *g, tb_mid_value *v, int depth)
{
    memset(v, 0, sizeof *v);
    int type = (int)below(g, depth >= 4 ? 3 : 8);
    switch (type) {
    case 0: v->type = TB_MID_NUMBER; v->number = any_double(g); break;
    case 1: v->type = TB_MID_STRING; v->text = any_string(g); break;
    case 2: {
        static const char *const syms[] = {"true", "false", "a", "spectrum", "x_1", "_"};
        v->type = TB_MID_SYMBOL;
        v->text = dup(g, syms[below(g, 6)]);
        break;
    }
    case 3: {
        v->type = TB_MID_VECTOR;
        v->count = (int)below(g, 5);
        double *d = alloc(g, (size_t)v->count * sizeof *d);
        for (int i = 0; i < v->count; i++)
            d[i] = any_double(g);
        v->numbers = v->count ? d : NULL;
        break;
    }
    case 4:
    case 5: {
        /* A list must hold a non-number (a list of numbers reads as a vector);
         * a call may hold anything. */
        v->type = type == 4 ? TB_MID_LIST : TB_MID_CALL;
        v->count = (int)below(g, 3) + (type == 4);
        tb_mid_value *it = alloc(g, (size_t)v->count * sizeof *it);
        for (int i = 0; i < v->count; i++) {
            do
                any_value(g, &it[i], depth + 1);
            while (type == 4 && i == 0 && it[0].type == TB_MID_NUMBER);
        }
        v->items = v->count ? it : NULL;
        if (type == 5) {
            static const char *const names[] = {"f", "rgb", "translate", "spectrum", "x_call"};
            v->name = dup(g, names[below(g, 5)]);
        }
        break;
    }
    case 6: {
        tb_mid_attrs a = any_attrs(g, 3, depth);
        v->type = TB_MID_BLOCK;
        v->attrs = a.items;
        v->count = a.count;
        break;
    }
    default: v->type = TB_MID_FILE; v->ref = any_ref(g); break;
    }
}

/* ------------------------------------------------------- references, in order */

typedef struct refs {
    tb_mid_ref items[256];
    int n;
} refs;

static void add_ref(refs *r, const tb_mid_ref *x)
{
    if (x->text) {
        assert_true(r->n < 256);
        r->items[r->n++] = *x;
    }
}

static void value_refs(refs *r, const tb_mid_value *v)
{
    switch (v->type) {
    case TB_MID_FILE: add_ref(r, &v->ref); break;
    case TB_MID_LIST:
    case TB_MID_CALL:
        for (int i = 0; i < v->count; i++)
            value_refs(r, &v->items[i]);
        break;
    case TB_MID_BLOCK:
        for (int i = 0; i < v->count; i++)
            value_refs(r, &v->attrs[i].value);
        break;
    default: break;
    }
}

static void attrs_refs(refs *r, const tb_mid_attrs *x)
{
    for (int i = 0; i < x->count; i++)
        value_refs(r, &x->items[i].value);
}

static void color_ref(refs *r, const tb_mid_color *c)
{
    if (c->type == TB_MID_COLOR_SPECTRUM_FILE)
        add_ref(r, &c->file);
}

static void material_refs(refs *r, const tb_mid_material *m)
{
    if (m->set & TB_MID_SET_DIFFUSE)
        color_ref(r, &m->diffuse);
    if (m->set & TB_MID_SET_SPECULAR)
        color_ref(r, &m->specular);
    if (m->set & TB_MID_SET_TRANSMISSION)
        color_ref(r, &m->transmission);
    if (m->set & TB_MID_SET_EMISSION)
        color_ref(r, &m->emission);
    if (m->set & TB_MID_SET_DIFFUSE_TEXTURE)
        add_ref(r, &m->diffuse_texture);
    if (m->set & TB_MID_SET_SPECULAR_TEXTURE)
        add_ref(r, &m->specular_texture);
    if (m->set & TB_MID_SET_TRANSMISSION_TEXTURE)
        add_ref(r, &m->transmission_texture);
    if (m->set & TB_MID_SET_EMISSION_TEXTURE)
        add_ref(r, &m->emission_texture);
    const tb_mid_pattern *pats[3] = {&m->diffuse_pattern, &m->specular_pattern, &m->bump};
    const unsigned bits[3] = {TB_MID_SET_DIFFUSE_PATTERN, TB_MID_SET_SPECULAR_PATTERN, TB_MID_SET_BUMP};
    for (int i = 0; i < 3; i++) {
        if (!(m->set & bits[i]))
            continue;
        if (pats[i]->kind == TB_MID_PATTERN_IMAGE)
            add_ref(r, &pats[i]->image);
        else if (i < 2) {
            color_ref(r, &pats[i]->a);
            color_ref(r, &pats[i]->b);
        }
    }
    attrs_refs(r, &m->extra);
}

static void take_refs(gen *g, const refs *r, const tb_mid_ref **out, int *n)
{
    tb_mid_ref *x = alloc(g, (size_t)r->n * sizeof *x);
    memcpy(x, r->items, (size_t)r->n * sizeof *x);
    *out = r->n ? x : NULL;
    *n = r->n;
}

/* --------------------------------------------------------------- materials */

static tb_mid_color any_color(gen *g, double hi)
{
    tb_mid_color c = tb_mid_color_grey(any_float(g, 0.0, hi));
    switch (below(g, 4)) {
    case 0: break; /* grey */
    case 1:
        for (int i = 0; i < 3; i++)
            c.rgb[i] = any_float(g, 0.0, hi);
        break;
    case 2: {
        c.type = TB_MID_COLOR_SPECTRUM;
        c.nsamples = 2 + (int)below(g, 6);
        float *nm = alloc(g, (size_t)c.nsamples * sizeof *nm), *val = alloc(g, (size_t)c.nsamples * sizeof *val);
        float l = any_float(g, 300.0, 400.0);
        for (int i = 0; i < c.nsamples; i++) {
            nm[i] = l;
            l += (float)(1 + below(g, 50)) + (float)tb_rng_double(&g->rng);
            val[i] = any_float(g, 0.0, hi);
        }
        c.nm = nm;
        c.values = val;
        break;
    }
    default:
        c.type = TB_MID_COLOR_SPECTRUM_FILE;
        c.file = any_ref(g);
        break;
    }
    return c;
}

/* A procedural pattern (MID 1.1 diffuse_pattern, specular_pattern) or, with
 * `bump`, a bump map: every form and optional argument. */
static tb_mid_pattern any_pattern(gen *g, bool bump)
{
    tb_mid_pattern p;
    memset(&p, 0, sizeof p);
    p.scale = chance(g, 30) ? (double)(1 + below(g, 64)) : ldexp(uniform(g, 0.5, 1.0), (int)below(g, 40) - 20);
    p.object_space = chance(g, 40);
    p.scale_v = p.object_space || chance(g, 50) ? p.scale : uniform(g, 0.25, 64.0);
    if (bump) {
        p.height = any_double(g);
        if (chance(g, 40)) {
            p.kind = TB_MID_PATTERN_IMAGE;
            p.image = any_ref(g);
            p.scale = p.scale_v = 0.0;
            p.object_space = false;
        } else {
            p.kind = TB_MID_PATTERN_NOISE;
            p.octaves = 1 + (int)below(g, 16);
        }
        return p;
    }
    p.a = any_color(g, 1.0);
    p.b = any_color(g, 1.0);
    if (chance(g, 50)) {
        p.kind = TB_MID_PATTERN_CHECKER;
    } else {
        p.kind = TB_MID_PATTERN_NOISE;
        p.octaves = 1 + (int)below(g, 16);
    }
    return p;
}

/* Clears what describes a block, as the reader does for an inherited material. */
static void unset(tb_mid_material *m)
{
    m->name = m->base = NULL;
    m->set = 0;
    m->extra = (tb_mid_attrs){NULL, 0};
    m->refs = NULL;
    m->nrefs = 0;
}

/* A rendering block over `inherited` (or a base material). */
static tb_mid_material any_rendering(gen *g, const tb_mid_material *inherited)
{
    tb_mid_material m = *inherited;
    unset(&m);
    if (g->nmats && chance(g, 50)) {
        const tb_mid_material *b = g->mats[below(g, (uint32_t)g->nmats)];
        m = *b;
        unset(&m);
        m.base = b->name;
    }
    if (chance(g, 40)) { m.diffuse = any_color(g, 1.0); m.set |= TB_MID_SET_DIFFUSE; }
    if (chance(g, 30)) { m.specular = any_color(g, 1.0); m.set |= TB_MID_SET_SPECULAR; }
    if (chance(g, 30)) { m.exponent = any_float(g, 0.0, 1000.0); m.set |= TB_MID_SET_EXPONENT; }
    if (chance(g, 20)) { m.transmission = any_color(g, 1.0); m.set |= TB_MID_SET_TRANSMISSION; }
    if (chance(g, 20)) { m.ior = any_float(g, 1.0, 3.0); m.set |= TB_MID_SET_IOR; }
    if (chance(g, 20)) { m.emission = any_color(g, 100.0); m.set |= TB_MID_SET_EMISSION; }
    if (chance(g, 10)) { m.diffuse_texture = any_ref(g); m.set |= TB_MID_SET_DIFFUSE_TEXTURE; }
    if (chance(g, 10)) { m.specular_texture = any_ref(g); m.set |= TB_MID_SET_SPECULAR_TEXTURE; }
    if (chance(g, 10)) { m.transmission_texture = any_ref(g); m.set |= TB_MID_SET_TRANSMISSION_TEXTURE; }
    if (chance(g, 10)) { m.emission_texture = any_ref(g); m.set |= TB_MID_SET_EMISSION_TEXTURE; }
    if (chance(g, 20)) { m.model = (tb_mid_model)below(g, TB_MID_MODEL_COUNT); m.set |= TB_MID_SET_MODEL; }
    if (chance(g, 20)) { m.roughness = any_float(g, 0.0, 1.0); m.set |= TB_MID_SET_ROUGHNESS; }
    if (chance(g, 15)) { m.diffuse_pattern = any_pattern(g, false); m.set |= TB_MID_SET_DIFFUSE_PATTERN; }
    if (chance(g, 15)) { m.specular_pattern = any_pattern(g, false); m.set |= TB_MID_SET_SPECULAR_PATTERN; }
    if (chance(g, 15)) { m.bump = any_pattern(g, true); m.set |= TB_MID_SET_BUMP; }
    if (chance(g, 20))
        m.extra = any_attrs(g, 2, 1);
    refs r = {.n = 0};
    material_refs(&r, &m);
    take_refs(g, &r, &m.refs, &m.nrefs);
    return m;
}

/* -------------------------------------------------------------- transforms */

static tb_dvec3 nonzero_vec(gen *g)
{
    tb_dvec3 v;
    do
        v = (tb_dvec3){uniform(g, -1, 1), uniform(g, -1, 1), uniform(g, -1, 1)};
    while (tb_dvec3_length(v) < 0.1);
    return v;
}

static double factor(gen *g) { return (chance(g, 20) ? -1.0 : 1.0) * uniform(g, 0.1, 10.0); }

static void any_ops(gen *g, const tb_mid_op **ops_out, int *n_out, tb_transform *local)
{
    int n = (int)below(g, 4);
    tb_mid_op *ops = alloc(g, (size_t)n * sizeof *ops);
    for (int i = 0; i < n; i++) {
        tb_mid_op *o = &ops[i];
        switch (below(g, 4)) {
        case 0:
            o->kind = TB_MID_TRANSLATE;
            for (int j = 0; j < 3; j++)
                o->v[j] = any_double(g);
            break;
        case 1:
            o->kind = TB_MID_SCALE;
            o->v[0] = factor(g);
            o->v[1] = chance(g, 50) ? o->v[0] : factor(g);
            o->v[2] = chance(g, 50) ? o->v[0] : factor(g);
            break;
        case 2: {
            o->kind = TB_MID_ROTATE;
            tb_dvec3 a = chance(g, 30) ? (tb_dvec3){0, 0, 1} : nonzero_vec(g);
            o->v[0] = a.x, o->v[1] = a.y, o->v[2] = a.z;
            o->v[3] = chance(g, 30) ? 90.0 * (int)below(g, 9) - 360.0 : uniform(g, -720, 720);
            break;
        }
        default: {
            /* An affine matrix from a random rotation, scale and translation. */
            tb_mid_op parts[3];
            memset(parts, 0, sizeof parts);
            tb_dvec3 a = nonzero_vec(g);
            parts[0] = (tb_mid_op){TB_MID_ROTATE, {a.x, a.y, a.z, uniform(g, -180, 180)}};
            parts[1] = (tb_mid_op){TB_MID_SCALE, {factor(g), factor(g), factor(g)}};
            parts[2] = (tb_mid_op){TB_MID_TRANSLATE, {any_double(g), any_double(g), any_double(g)}};
            tb_transform t;
            assert_int_equal(tb_mid_ops_transform(parts, 3, &t, NULL), TB_OK);
            o->kind = TB_MID_MATRIX;
            for (int r = 0; r < 4; r++)
                for (int c = 0; c < 4; c++)
                    o->v[r * 4 + c] = t.m.m[r][c];
            break;
        }
        }
    }
    assert_int_equal(tb_mid_ops_transform(ops, n, local, NULL), TB_OK);
    *ops_out = n ? ops : NULL;
    *n_out = n;
}

/* ----------------------------------------------------------------- objects */

static void any_geometry(gen *g, tb_mid_object *o)
{
    tb_mid_geometry *geo = &o->geom;
    *geo = tb_mid_geometry_default(o->kind);
    switch (o->kind) {
    case TB_PRIM_CYLINDER: geo->cylinder.caps = chance(g, 50); break;
    case TB_PRIM_CONE:
        geo->cone.top_radius = chance(g, 40) ? 0.0 : uniform(g, 0.0, 3.0);
        geo->cone.caps = chance(g, 50);
        break;
    case TB_PRIM_PYRAMID:
        geo->pyramid.top = chance(g, 40) ? 0.0 : uniform(g, 0.0, 3.0);
        geo->pyramid.caps = chance(g, 50);
        break;
    case TB_PRIM_PRISM:
        geo->prism.caps = chance(g, 50);
        if (chance(g, 50)) {
            geo->prism.sides = 3 + (int)below(g, 20);
        } else {
            /* A star-shaped polygon around the origin: simple, non-zero area. */
            int n = 3 + (int)below(g, 8);
            tb_vec2 *p = alloc(g, (size_t)n * sizeof *p);
            for (int i = 0; i < n; i++) {
                double t = 2.0 * 3.14159265358979 * i / n, rad = uniform(g, 0.2, 2.0);
                p[i] = (tb_vec2){(float)(rad * cos(t)), (float)(rad * sin(t))};
            }
            geo->prism.sides = 0;
            geo->prism.nprofile = n;
            geo->prism.profile = p;
        }
        break;
    case TB_PRIM_TORUS:
        geo->torus.major = uniform(g, 0.5, 3.0);
        geo->torus.minor = geo->torus.major * uniform(g, 0.05, 0.95);
        break;
    case TB_PRIM_POLYGONS: {
        tb_geom_polygons *p = &geo->polygons;
        if (chance(g, 25)) {
            p->mesh = any_ref(g);
            break;
        }
        int nv = 3 + (int)below(g, 6);
        tb_vec3 *v = alloc(g, (size_t)nv * sizeof *v);
        for (int i = 0; i < nv; i++)
            v[i] = (tb_vec3){any_float(g, -10, 10), any_float(g, -10, 10), any_float(g, -10, 10)};
        int nf = 1 + (int)below(g, 3), total = 0;
        int *start = alloc(g, (size_t)(nf + 1) * sizeof *start);
        int *idx = alloc(g, (size_t)nf * (size_t)nv * sizeof *idx);
        for (int f = 0; f < nf; f++) {
            start[f] = total;
            int k = 3 + (int)below(g, (uint32_t)nv - 2);
            for (int j = 0; j < k; j++)
                idx[total++] = (int)below(g, (uint32_t)nv);
        }
        start[nf] = total;
        p->nvertices = nv;
        p->vertices = v;
        p->nfaces = nf;
        p->face_start = start;
        p->indices = idx;
        if (chance(g, 40)) {
            tb_vec3 *nrm = alloc(g, (size_t)nv * sizeof *nrm);
            for (int i = 0; i < nv; i++)
                nrm[i] = (tb_vec3){any_float(g, -1, 1), any_float(g, -1, 1), 1.0f};
            p->normals = nrm;
        }
        if (chance(g, 40)) {
            tb_vec2 *uv = alloc(g, (size_t)nv * sizeof *uv);
            for (int i = 0; i < nv; i++)
                uv[i] = (tb_vec2){any_float(g, 0, 1), any_float(g, 0, 1)};
            p->uvs = uv;
        }
        break;
    }
    case TB_PRIM_CONIC: {
        tb_geom_conic *c = &geo->conic;
        c->caps = chance(g, 50);
        if (chance(g, 50)) {
            /* r^2 >= c0 - |c1| > 0 on [-1, 1]: paraboloids, hyperboloids, cylinders. */
            c->c[1] = uniform(g, -1.0, 1.0);
            c->c[0] = fabs(c->c[1]) + uniform(g, 0.1, 2.0);
            c->c[2] = chance(g, 30) ? 0.0 : uniform(g, 0.0, 2.0);
            c->z0 = -1.0;
            c->z1 = 1.0;
        } else {
            /* Part of an ellipsoid r^2 = a - b z^2, inside its poles. */
            double a = uniform(g, 0.5, 2.0), b = uniform(g, 0.5, 2.0), zmax = 0.9 * sqrt(a / b);
            c->c[0] = a;
            c->c[1] = 0.0;
            c->c[2] = -b;
            c->z0 = -zmax * uniform(g, 0.1, 1.0);
            c->z1 = zmax * uniform(g, 0.1, 1.0);
        }
        break;
    }
    case TB_PRIM_SQUARE_ARCH:
        geo->arch.width = uniform(g, 0.1, 1.9);
        geo->arch.height = uniform(g, 0.1, 1.9);
        break;
    case TB_PRIM_ROUND_ARCH:
        geo->arch.width = uniform(g, 0.1, 1.9);
        geo->arch.height = uniform(g, geo->arch.width / 2.0, 1.95);
        break;
    default: break;
    }
    if (chance(g, 20))
        o->geometry_extra = any_attrs(g, 2, 1);
}

static void any_object(gen *g, tb_mid_object *o, int depth, const tb_transform *parent,
                       const tb_mid_material *inherited)
{
    memset(o, 0, sizeof *o);
    o->kind = (tb_prim_kind)below(g, depth < 3 ? TB_PRIM_COUNT : TB_PRIM_UNION);
    o->name = chance(g, 50) ? any_string(g) : NULL;
    tb_transform local;
    any_ops(g, &o->ops, &o->nops, &local);
    o->to_world = tb_transform_compose(parent, &local);
    any_geometry(g, o);
    if (chance(g, 35)) {
        o->material = *inherited;
        unset(&o->material);
    } else
        o->material = any_rendering(g, inherited);
    if (chance(g, 25))
        o->extra = any_attrs(g, 3, 1);
    refs r = {.n = 0};
    if (o->kind == TB_PRIM_POLYGONS)
        add_ref(&r, &o->geom.polygons.mesh);
    attrs_refs(&r, &o->geometry_extra);
    material_refs(&r, &o->material);
    attrs_refs(&r, &o->extra);
    take_refs(g, &r, &o->refs, &o->nrefs);
    if (tb_prim_is_csg(o->kind)) {
        int n = (int)below(g, 3) + (o->kind == TB_PRIM_DIFFERENCE ? 2 : 1);
        tb_mid_object *ch = alloc(g, (size_t)n * sizeof *ch);
        for (int i = 0; i < n; i++)
            any_object(g, &ch[i], depth + 1, &o->to_world, &o->material);
        o->children = ch;
        o->nchildren = n;
    }
}

static tb_mid_item any_item(gen *g, bool *camera_done)
{
    tb_mid_item it;
    memset(&it, 0, sizeof it);
    uint32_t pick = below(g, 100);
    if (pick < 15 && g->nmats < 32) {
        tb_mid_material def = tb_mid_material_default();
        tb_mid_material *m = alloc(g, sizeof *m);
        *m = any_rendering(g, &def);
        char name[64];
        snprintf(name, sizeof name, "m%d", g->serial++);
        char *full = alloc(g, strlen(name) + 40);
        sprintf(full, "%s%s", name, chance(g, 50) ? "" : " \"quoted\" \\ name");
        m->name = full;
        g->mats[g->nmats++] = m;
        it.type = TB_MID_ITEM_MATERIAL;
        it.material = m;
    } else if (pick < 25) {
        tb_mid_light *l = alloc(g, sizeof *l);
        *l = tb_mid_light_default((tb_light_kind)below(g, 3));
        l->name = chance(g, 50) ? any_string(g) : NULL;
        tb_transform local, id = tb_transform_identity();
        any_ops(g, &l->ops, &l->nops, &local);
        l->to_world = tb_transform_compose(&id, &local);
        l->position = (tb_dvec3){any_double(g), any_double(g), any_double(g)};
        if (l->kind == TB_LIGHT_DIRECTIONAL)
            l->position = (tb_dvec3){0, 0, 0};
        if (l->kind != TB_LIGHT_POINT)
            l->direction = nonzero_vec(g);
        l->intensity = any_color(g, 1000.0);
        if (l->kind == TB_LIGHT_SPOT) {
            l->cone_angle = uniform(g, 1.0, 90.0);
            l->cone_delta = uniform(g, 0.0, l->cone_angle);
        }
        if (l->kind != TB_LIGHT_DIRECTIONAL && chance(g, 30))
            l->ies = any_ref(g);
        if (chance(g, 30))
            l->extra = any_attrs(g, 2, 1);
        refs r = {.n = 0};
        color_ref(&r, &l->intensity);
        add_ref(&r, &l->ies);
        attrs_refs(&r, &l->extra);
        take_refs(g, &r, &l->refs, &l->nrefs);
        it.type = TB_MID_ITEM_LIGHT;
        it.light = l;
    } else if (pick < 30 && !*camera_done) {
        tb_mid_camera *c = alloc(g, sizeof *c);
        *c = tb_mid_camera_default();
        c->name = chance(g, 50) ? any_string(g) : NULL;
        c->eye = (tb_dvec3){any_double(g), any_double(g), any_double(g)};
        tb_dvec3 d = nonzero_vec(g), up;
        c->look_at = tb_dvec3_add(c->eye, tb_dvec3_scale(d, uniform(g, 1.0, 100.0)));
        do
            up = nonzero_vec(g);
        while (tb_dvec3_length(tb_dvec3_cross(tb_dvec3_normalize(up), tb_dvec3_normalize(d))) < 0.2);
        c->up = up;
        c->width = 1 + (int)below(g, 4096);
        c->height = 1 + (int)below(g, 4096);
        c->film[0] = uniform(g, 10, 50);
        c->film[1] = uniform(g, 10, 50);
        if (chance(g, 50)) {
            c->focal_length = uniform(g, 10.0, 200.0);
            c->fov = tb_mid_camera_fov(c->focal_length, c->film, c->width, c->height);
        } else
            c->fov = uniform(g, 1.0, 170.0);
        c->aperture = chance(g, 50) ? 0.0 : uniform(g, 0.0, 0.1);
        c->focus_distance = uniform(g, 0.5, 100.0);
        if (chance(g, 30))
            c->extra = any_attrs(g, 2, 1);
        refs r = {.n = 0};
        attrs_refs(&r, &c->extra);
        take_refs(g, &r, &c->refs, &c->nrefs);
        *camera_done = true;
        it.type = TB_MID_ITEM_CAMERA;
        it.camera = c;
    } else {
        tb_mid_object *o = alloc(g, sizeof *o);
        tb_transform id = tb_transform_identity();
        tb_mid_material def = tb_mid_material_default();
        any_object(g, o, 0, &id, &def);
        it.type = TB_MID_ITEM_OBJECT;
        it.object = o;
    }
    return it;
}

/* Writes header + items to memory. */
static char *write_scene(const tb_mid_item *items, int n, size_t *len)
{
    char *buf = NULL;
    FILE *fp = open_memstream(&buf, len);
    assert_non_null(fp);
    assert_int_equal(tb_mid_write_header(fp), TB_OK);
    for (int i = 0; i < n; i++)
        if (tb_mid_write_item(fp, &items[i]))
            fail_msg("write: %s", tb_last_error());
    fclose(fp);
    return buf;
}

static void test_roundtrip_random_scenes(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("mid round trip", 0x5EED0003);
    for (int scene = 0; scene < 300; scene++) {
        tb_arena arena;
        tb_arena_init(&arena, 0);
        gen g = {.a = &arena};
        tb_rng_seed(&g.rng, seed, (uint64_t)scene);
        bool camera = false;
        int n = 1 + (int)below(&g, 25);
        tb_mid_item *items = alloc(&g, (size_t)n * sizeof *items);
        for (int i = 0; i < n; i++)
            items[i] = any_item(&g, &camera);

        size_t len;
        char *text = write_scene(items, n, &len);
        /* Read back, compare item by item, and write what was read again. */
        FILE *in = fmemopen(text, len, "rb");
        tb_mid_reader *r;
        assert_int_equal(tb_mid_reader_open_stream(&r, in, "roundtrip.mid", DATA), TB_OK);
        char *again = NULL;
        size_t again_len;
        FILE *out = open_memstream(&again, &again_len);
        tb_mid_write_header(out);
        for (int i = 0; i <= n; i++) {
            tb_mid_item it;
            if (tb_mid_reader_next(r, &it))
                fail_msg("scene %d: %s\n%s", scene, tb_last_error(), text);
            if (i == n) {
                assert_int_equal(it.type, TB_MID_ITEM_END);
                break;
            }
            if (!tb_mid_item_equal(&items[i], &it))
                fail_msg("scene %d (stream %llu), item %d differs after reading back:\n%s", scene,
                         (unsigned long long)scene, i, text);
            assert_int_equal(tb_mid_write_item(out, &it), TB_OK);
        }
        fclose(out);
        tb_mid_reader_close(r);
        fclose(in);
        if (again_len != len || memcmp(again, text, len) != 0)
            fail_msg("scene %d: canonical text changed on the second write:\n%s\n----\n%s", scene, text, again);
        free(again);
        free(text);
        tb_arena_free(&arena);
    }
}

/* The writer refuses what the format cannot hold. */
static void test_writer_refusals(void **state)
{
    (void)state;
    char *buf = NULL;
    size_t len;
    FILE *fp = open_memstream(&buf, &len);
    tb_mid_object o;
    memset(&o, 0, sizeof o);
    o.kind = TB_PRIM_UNION; /* no children */
    o.to_world = tb_transform_identity();
    o.material = tb_mid_material_default();
    tb_mid_item it = {.type = TB_MID_ITEM_OBJECT, .object = &o};
    assert_int_equal(tb_mid_write_item(fp, &it), TB_ERR_ARG);
    o.kind = TB_PRIM_TORUS;
    o.geom = tb_mid_geometry_default(TB_PRIM_TORUS);
    o.geom.torus.minor = NAN;
    assert_int_equal(tb_mid_write_item(fp, &it), TB_ERR_ARG);
    o.geom.torus.minor = 0.5;
    assert_int_equal(tb_mid_write_item(fp, &it), TB_OK);
    fclose(fp);
    free(buf);
}

/* The canonical text of the MID 1.1 attributes (docs/mid.md, section 12):
 * after the 1.0 attributes, in the order of the table in 7.2; the space
 * argument only when it is `object`; a bump's noise() with its height. */
static void test_writer_canonical_11(void **state)
{
    (void)state;
    const char *in = "mid 1.1\n"
                     "material \"m\" { bump = noise(16, 3, -0.01, uv) diffuse_pattern = checker([8 4], 0.1, [1 0.5 0.25])\n"
                     "  roughness = 0.35 model = ggx specular = 0.9 specular_pattern = noise(2.5 4 0 1 object) }\n"
                     "sphere { rendering = { bump = image(file(\"checker.png\"), 0.002) model = lambert } }\n";
    const char *want = "material \"m\" {\n"
                       "    specular = 0.9\n"
                       "    model = ggx\n"
                       "    roughness = 0.35\n"
                       "    diffuse_pattern = checker([8 4], 0.1, [1 0.5 0.25])\n"
                       "    specular_pattern = noise(2.5, 4, 0, 1, object)\n"
                       "    bump = noise(16, 3, -0.01)\n"
                       "}\n"
                       "sphere {\n"
                       "    rendering = {\n"
                       "        model = lambert\n"
                       "        bump = image(file(\"checker.png\"), 0.002)\n"
                       "    }\n"
                       "}\n";
    FILE *fp = fmemopen((void *)in, strlen(in), "r");
    assert_non_null(fp);
    tb_mid_reader *r;
    assert_int_equal(tb_mid_reader_open_stream(&r, fp, "c.mid", DATA), TB_OK);
    char *buf = NULL;
    size_t len;
    FILE *out = open_memstream(&buf, &len);
    tb_mid_item it;
    tb_status st;
    while (!(st = tb_mid_reader_next(r, &it)) && it.type != TB_MID_ITEM_END)
        assert_int_equal(tb_mid_write_item(out, &it), TB_OK);
    if (st)
        fail_msg("%s", tb_last_error());
    fclose(out);
    assert_string_equal(buf, want);
    free(buf);
    tb_mid_reader_close(r);
    fclose(fp);
}

/* A program running in a locale with a decimal comma still reads and writes
 * '.' (the file format does not depend on the reader's locale). The locale
 * is generated with localedef, and the test first checks that it is active. */
static void test_comma_decimal_locale(void **state)
{
    (void)state;
    char dir[512], cmd[1200];
    snprintf(dir, sizeof dir, "%s/mid_locale", tb_test_tmpdir());
    snprintf(cmd, sizeof cmd, "mkdir -p '%s' && localedef -i de_DE -f UTF-8 '%s/de_DE.UTF-8'", dir, dir);
    assert_int_equal(system(cmd), 0);
    setenv("LOCPATH", dir, 1);
    assert_non_null(setlocale(LC_NUMERIC, "de_DE.UTF-8"));
    char probe[16];
    snprintf(probe, sizeof probe, "%.1f", 0.5);
    assert_string_equal(probe, "0,5"); /* the comma locale is in effect */

    /* 34 significant digits take the strtod path of the reader. */
    const char *text = "mid 1\nsphere { transform = [scale(0.5) translate([1.25 -2.5e-3 0.1000000000000000055511151231257827])] }\n";
    FILE *fp = fmemopen((void *)text, strlen(text), "rb");
    tb_mid_reader *r;
    assert_int_equal(tb_mid_reader_open_stream(&r, fp, "l.mid", NULL), TB_OK);
    tb_mid_item it;
    assert_int_equal(tb_mid_reader_next(r, &it), TB_OK);
    const tb_mid_op *ops = it.object->ops;
    assert_true(ops[0].v[0] == 0.5 && ops[1].v[0] == 1.25 && ops[1].v[1] == -0.0025 && ops[1].v[2] == 0.1);
    char *out = NULL;
    size_t len;
    FILE *w = open_memstream(&out, &len);
    assert_int_equal(tb_mid_write_item(w, &it), TB_OK);
    fclose(w);
    assert_non_null(strstr(out, "transform = [scale(0.5) translate([1.25 -0.0025 0.1])]"));
    free(out);
    tb_mid_reader_close(r);
    fclose(fp);
    snprintf(probe, sizeof probe, "%.1f", 0.5);
    assert_string_equal(probe, "0,5"); /* the program's locale is left as it was */
    setlocale(LC_NUMERIC, "C");
    unsetenv("LOCPATH");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_roundtrip_random_scenes),
        cmocka_unit_test(test_writer_refusals),
        cmocka_unit_test(test_writer_canonical_11),
        cmocka_unit_test(test_comma_decimal_locale),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
