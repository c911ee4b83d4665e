/* MID schema: turns the syntax tree of one top-level object into the typed
 * object model (docs/mid.md, sections 6 to 10), checking every known
 * attribute's shape and range and keeping unknown attributes. */
#include "host/mid/mid_internal.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define TB__ERR(r, loc, ...) TB__MID_ERR(r, loc, __VA_ARGS__)

/* Whether attribute or symbol name `s` is the literal `lit`. The first byte
 * is compared inline: most tests in an attribute dispatch fail on it, and a
 * strcmp call for each was about 5% of reading a file of small objects. */
#define TB__IS(s, lit) ((s)[0] == (lit)[0] && strcmp((s), (lit)) == 0)

static tb_status tb__nomem(tb_mid_reader *r) { return tb_error(TB_ERR_NOMEM, "%s: out of memory", r->lx.name); }

/* "found ..." text for a value. */
static const char *tb__desc(const tb_mid_value *v, char *buf, size_t n)
{
    switch (v->type) {
    case TB_MID_NUMBER: snprintf(buf, n, "%g", v->number); break;
    case TB_MID_STRING: snprintf(buf, n, "a string"); break;
    case TB_MID_SYMBOL: snprintf(buf, n, "'%.40s'", v->text); break;
    case TB_MID_VECTOR:
        if (v->count == 0)
            snprintf(buf, n, "an empty list");
        else
            snprintf(buf, n, "a list of %d number%s", v->count, v->count == 1 ? "" : "s");
        break;
    case TB_MID_LIST: snprintf(buf, n, "a list of %d values", v->count); break;
    case TB_MID_CALL: snprintf(buf, n, "%.40s(...)", v->name); break;
    case TB_MID_BLOCK: snprintf(buf, n, "a block"); break;
    case TB_MID_FILE: snprintf(buf, n, "a file reference"); break;
    }
    return buf;
}

#define TB__DESC(v) tb__desc((v), found, sizeof found)

/* ------------------------------------------------------------ value getters */

static tb_status tb__number(tb_mid_reader *r, const tb_mid_value *v, const char *what, double *out)
{
    char found[96];
    if (v->type != TB_MID_NUMBER)
        return TB__ERR(r, v->loc, "expected a number for '%s', found %s", what, TB__DESC(v));
    *out = v->number;
    return TB_OK;
}

/* A number for a float field. */
static tb_status tb__float_ok(tb_mid_reader *r, tb_mid_loc loc, const char *what, double x)
{
    if (fabs(x) > FLT_MAX)
        return TB__ERR(r, loc, "'%s' is out of range for a float, found %g", what, x);
    return TB_OK;
}

static tb_status tb__range_error(tb_mid_reader *r, tb_mid_loc loc, const char *what, const char *range, double x)
{
    return TB__ERR(r, loc, "'%s' must be %s, found %g", what, range, x);
}

static tb_status tb__bool(tb_mid_reader *r, const tb_mid_value *v, const char *what, bool *out)
{
    char found[96];
    if (v->type == TB_MID_SYMBOL && TB__IS(v->text, "true"))
        *out = true;
    else if (v->type == TB_MID_SYMBOL && TB__IS(v->text, "false"))
        *out = false;
    else
        return TB__ERR(r, v->loc, "expected true or false for '%s', found %s", what, TB__DESC(v));
    return TB_OK;
}

static const char *tb__vec_example(int n)
{
    switch (n) {
    case 2: return " [x y]";
    case 3: return " [x y z]";
    default: return "";
    }
}

/* A list of exactly n numbers. */
static tb_status tb__vec(tb_mid_reader *r, const tb_mid_value *v, const char *what, int n, double *out)
{
    char found[96];
    if (v->type != TB_MID_VECTOR || v->count != n)
        return TB__ERR(r, v->loc, "expected a %d-vector%s for '%s', found %s", n, tb__vec_example(n), what,
                       TB__DESC(v));
    memcpy(out, v->numbers, (size_t)n * sizeof *out);
    return TB_OK;
}

static tb_status tb__dvec3(tb_mid_reader *r, const tb_mid_value *v, const char *what, tb_dvec3 *out)
{
    double d[3];
    tb_status st = tb__vec(r, v, what, 3, d);
    if (!st)
        *out = (tb_dvec3){d[0], d[1], d[2]};
    return st;
}

/* An integer in [lo, hi]. */
static tb_status tb__int(tb_mid_reader *r, const tb_mid_value *v, const char *what, long lo, long hi, int *out)
{
    double x = 0.0;
    tb_status st = tb__number(r, v, what, &x);
    if (st)
        return st;
    if (x != floor(x))
        return TB__ERR(r, v->loc, "expected an integer for '%s', found %g", what, x);
    if (x < (double)lo || x > (double)hi)
        return TB__ERR(r, v->loc, "'%s' must be an integer from %ld to %ld, found %g", what, lo, hi, x);
    *out = (int)x;
    return TB_OK;
}

static tb_status tb__block(tb_mid_reader *r, const tb_mid_value *v, const char *what)
{
    char found[96];
    if (v->type != TB_MID_BLOCK)
        return TB__ERR(r, v->loc, "expected a block { ... } for '%s', found %s", what, TB__DESC(v));
    return TB_OK;
}

static tb_status tb__file(tb_mid_reader *r, const tb_mid_value *v, const char *what, tb_mid_ref *out)
{
    char found[96];
    if (v->type != TB_MID_FILE)
        return TB__ERR(r, v->loc, "expected a file reference file(\"path\") for '%s', found %s", what, TB__DESC(v));
    *out = v->ref;
    return TB_OK;
}

/* Unknown attributes of one block, collected in file order. */
typedef struct tb__extra {
    tb_mid_attr *items;
    int count, cap;
} tb__extra;

static tb_status tb__extra_push(tb_mid_reader *r, tb__extra *x, const tb_mid_attr *a)
{
    if (x->count == x->cap) {
        int cap = x->cap ? 2 * x->cap : 4;
        tb_mid_attr *n = tb__mid_alloc(r, (size_t)cap * sizeof *n);
        if (!n)
            return tb__nomem(r);
        if (x->count)
            memcpy(n, x->items, (size_t)x->count * sizeof *n);
        x->items = n;
        x->cap = cap;
    }
    x->items[x->count++] = *a;
    return TB_OK;
}

static tb_mid_attrs tb__extra_done(const tb__extra *x) { return (tb_mid_attrs){x->items, x->count}; }

/* ------------------------------------------------------------ file references */

/* Collects the file references anywhere inside a value. */
static tb_status tb__collect_refs(tb_mid_reader *r, const tb_mid_value *v)
{
    tb_status st;
    switch (v->type) {
    case TB_MID_FILE:
        if (tb__mid_push(&r->refs, &v->ref))
            return tb__nomem(r);
        return TB_OK;
    case TB_MID_LIST:
    case TB_MID_CALL:
        for (int i = 0; i < v->count; i++)
            if ((st = tb__collect_refs(r, &v->items[i])))
                return st;
        return TB_OK;
    case TB_MID_BLOCK:
        for (int i = 0; i < v->count; i++)
            if ((st = tb__collect_refs(r, &v->attrs[i].value)))
                return st;
        return TB_OK;
    default: return TB_OK;
    }
}

static tb_status tb__push_ref(tb_mid_reader *r, const tb_mid_ref *ref)
{
    if (ref->text && tb__mid_push(&r->refs, ref))
        return tb__nomem(r);
    return TB_OK;
}

static tb_status tb__push_color_ref(tb_mid_reader *r, const tb_mid_color *c)
{
    return c->type == TB_MID_COLOR_SPECTRUM_FILE ? tb__push_ref(r, &c->file) : TB_OK;
}

static tb_status tb__push_attrs_refs(tb_mid_reader *r, const tb_mid_attrs *x)
{
    for (int i = 0; i < x->count; i++) {
        tb_status st = tb__collect_refs(r, &x->items[i].value);
        if (st)
            return st;
    }
    return TB_OK;
}

/* Moves r->refs[first..] into the arena. */
static tb_status tb__take_refs(tb_mid_reader *r, size_t first, const tb_mid_ref **out, int *count)
{
    size_t n = r->refs.len - first;
    *out = NULL;
    *count = 0;
    if (n) {
        tb_mid_ref *refs = tb__mid_alloc(r, n * sizeof *refs);
        if (!refs)
            return tb__nomem(r);
        memcpy(refs, (tb_mid_ref *)r->refs.data + first, n * sizeof *refs);
        *out = refs;
        *count = (int)n;
    }
    r->refs.len = first;
    return TB_OK;
}

/* The references a rendering block wrote, in the order the writer writes them. */
static tb_status tb__push_material_refs(tb_mid_reader *r, const tb_mid_material *m)
{
    tb_status st;
    if ((m->set & TB_MID_SET_DIFFUSE) && (st = tb__push_color_ref(r, &m->diffuse)))
        return st;
    if ((m->set & TB_MID_SET_SPECULAR) && (st = tb__push_color_ref(r, &m->specular)))
        return st;
    if ((m->set & TB_MID_SET_TRANSMISSION) && (st = tb__push_color_ref(r, &m->transmission)))
        return st;
    if ((m->set & TB_MID_SET_EMISSION) && (st = tb__push_color_ref(r, &m->emission)))
        return st;
    if ((m->set & TB_MID_SET_DIFFUSE_TEXTURE) && (st = tb__push_ref(r, &m->diffuse_texture)))
        return st;
    if ((m->set & TB_MID_SET_SPECULAR_TEXTURE) && (st = tb__push_ref(r, &m->specular_texture)))
        return st;
    if ((m->set & TB_MID_SET_TRANSMISSION_TEXTURE) && (st = tb__push_ref(r, &m->transmission_texture)))
        return st;
    if ((m->set & TB_MID_SET_EMISSION_TEXTURE) && (st = tb__push_ref(r, &m->emission_texture)))
        return st;
    const tb_mid_pattern *pats[3] = {&m->diffuse_pattern, &m->specular_pattern, &m->bump};
    const unsigned bits[3] = {TB_MID_SET_DIFFUSE_PATTERN, TB_MID_SET_SPECULAR_PATTERN, TB_MID_SET_BUMP};
    for (int i = 0; i < 3; i++) {
        if (!(m->set & bits[i]))
            continue;
        const tb_mid_pattern *pt = pats[i];
        if (pt->kind == TB_MID_PATTERN_IMAGE) {
            if ((st = tb__push_ref(r, &pt->image)))
                return st;
        } else if (i < 2 && ((st = tb__push_color_ref(r, &pt->a)) || (st = tb__push_color_ref(r, &pt->b)))) {
            return st;
        }
    }
    return tb__push_attrs_refs(r, &m->extra);
}

/* ------------------------------------------------------------------ colours */

/* Range check of one channel or sample of a colour attribute: [0, hi]. */
static tb_status tb__check_channel(tb_mid_reader *r, tb_mid_loc loc, const char *what, double x, double hi)
{
    if (!(x >= 0.0 && x <= hi)) {
        char range[32];
        if (isinf(hi))
            snprintf(range, sizeof range, ">= 0");
        else
            snprintf(range, sizeof range, "in [0, %g]", hi);
        return tb__range_error(r, loc, what, range, x);
    }
    return tb__float_ok(r, loc, what, x);
}

static tb_status tb__color(tb_mid_reader *r, const tb_mid_value *v, const char *what, double hi, tb_mid_color *out)
{
    char found[96];
    tb_status st;
    memset(out, 0, sizeof *out);
    if (v->type == TB_MID_NUMBER) {
        if ((st = tb__check_channel(r, v->loc, what, v->number, hi)))
            return st;
        *out = tb_mid_color_grey((float)v->number);
        return TB_OK;
    }
    if (v->type == TB_MID_VECTOR && v->count == 3) {
        out->type = TB_MID_COLOR_RGB;
        for (int i = 0; i < 3; i++) {
            if ((st = tb__check_channel(r, v->loc, what, v->numbers[i], hi)))
                return st;
            out->rgb[i] = (float)v->numbers[i];
        }
        return TB_OK;
    }
    if (v->type == TB_MID_CALL && TB__IS(v->name, "spectrum")) {
        if (v->count == 1 && v->items[0].type == TB_MID_FILE) {
            out->type = TB_MID_COLOR_SPECTRUM_FILE;
            out->file = v->items[0].ref;
            return TB_OK;
        }
        if (v->count != 2 || v->items[0].type != TB_MID_VECTOR || v->items[1].type != TB_MID_VECTOR)
            return TB__ERR(r, v->loc,
                           "spectrum takes two lists or a file: spectrum([nm ...], [value ...]) or spectrum(file(\"...\"))");
        const tb_mid_value *l = &v->items[0], *s = &v->items[1];
        if (l->count != s->count)
            return TB__ERR(r, v->loc, "spectrum has %d wavelengths but %d values", l->count, s->count);
        if (l->count < 2)
            return TB__ERR(r, v->loc, "a spectrum needs at least 2 samples, found %d", l->count);
        float *nm = tb__mid_alloc(r, (size_t)l->count * sizeof *nm);
        float *val = tb__mid_alloc(r, (size_t)l->count * sizeof *val);
        if (!nm || !val)
            return tb__nomem(r);
        for (int i = 0; i < l->count; i++) {
            double w = l->numbers[i];
            if (!(w > 0.0) || w > FLT_MAX)
                return TB__ERR(r, l->loc, "spectrum wavelengths must be positive (nm), found %g", w);
            nm[i] = (float)w;
            if (i > 0 && !(nm[i] > nm[i - 1]))
                return TB__ERR(r, l->loc, "spectrum wavelengths must increase, found %g after %g", w,
                               l->numbers[i - 1]);
            if ((st = tb__check_channel(r, s->loc, what, s->numbers[i], hi)))
                return st;
            val[i] = (float)s->numbers[i];
        }
        out->type = TB_MID_COLOR_SPECTRUM;
        out->nsamples = l->count;
        out->nm = nm;
        out->values = val;
        return TB_OK;
    }
    return TB__ERR(r, v->loc, "expected a colour for '%s' (a number, [r g b] or spectrum(...)), found %s", what,
                   TB__DESC(v));
}

/* ---------------------------------------------------------------- transforms */

static tb_status tb__transform(tb_mid_reader *r, const tb_mid_value *v, const tb_mid_op **ops_out, int *nops_out,
                               tb_transform *local)
{
    char found[96];
    *ops_out = NULL;
    *nops_out = 0;
    *local = tb__mid_identity;
    if (v->type == TB_MID_VECTOR && v->count == 0)
        return TB_OK;
    if (v->type != TB_MID_LIST)
        return TB__ERR(r, v->loc,
                       "expected a list of transform operations for 'transform' (e.g. [scale(2) translate([0 0 1])]), found %s",
                       TB__DESC(v));
    tb_mid_op *ops = tb__mid_alloc(r, (size_t)v->count * sizeof *ops);
    if (!ops)
        return tb__nomem(r);
    for (int i = 0; i < v->count; i++) {
        const tb_mid_value *c = &v->items[i];
        tb_mid_op *op = &ops[i];
        memset(op, 0, sizeof *op);
        if (c->type != TB_MID_CALL)
            return TB__ERR(r, c->loc, "expected a transform operation (translate, scale, rotate or matrix), found %s",
                           TB__DESC(c));
        const tb_mid_value *a = c->items;
        if (TB__IS(c->name, "translate")) {
            if (c->count != 1 || a[0].type != TB_MID_VECTOR || a[0].count != 3)
                return TB__ERR(r, c->loc, "translate takes one 3-vector: translate([x y z])");
            op->kind = TB_MID_TRANSLATE;
            memcpy(op->v, a[0].numbers, 3 * sizeof(double));
        } else if (TB__IS(c->name, "scale")) {
            op->kind = TB_MID_SCALE;
            if (c->count == 1 && a[0].type == TB_MID_NUMBER)
                op->v[0] = op->v[1] = op->v[2] = a[0].number;
            else if (c->count == 1 && a[0].type == TB_MID_VECTOR && a[0].count == 3)
                memcpy(op->v, a[0].numbers, 3 * sizeof(double));
            else
                return TB__ERR(r, c->loc, "scale takes a number or a 3-vector: scale(s) or scale([x y z])");
            if (op->v[0] == 0.0 || op->v[1] == 0.0 || op->v[2] == 0.0)
                return TB__ERR(r, c->loc, "scale factors must be non-zero (a zero scale is singular)");
        } else if (TB__IS(c->name, "rotate")) {
            if (c->count != 2 || a[0].type != TB_MID_VECTOR || a[0].count != 3 || a[1].type != TB_MID_NUMBER)
                return TB__ERR(r, c->loc, "rotate takes an axis and an angle: rotate([x y z], degrees)");
            op->kind = TB_MID_ROTATE;
            memcpy(op->v, a[0].numbers, 3 * sizeof(double));
            op->v[3] = a[1].number;
            if (op->v[0] == 0.0 && op->v[1] == 0.0 && op->v[2] == 0.0)
                return TB__ERR(r, c->loc, "the rotation axis must be non-zero");
        } else if (TB__IS(c->name, "matrix")) {
            if (c->count != 1 || a[0].type != TB_MID_VECTOR || a[0].count != 16)
                return TB__ERR(r, c->loc,
                               "matrix takes one list of 16 numbers, row by row: matrix([m00 m01 ... m33])");
            op->kind = TB_MID_MATRIX;
            memcpy(op->v, a[0].numbers, 16 * sizeof(double));
            if (op->v[12] != 0.0 || op->v[13] != 0.0 || op->v[14] != 0.0 || op->v[15] != 1.0)
                return TB__ERR(r, c->loc, "the last row of a matrix must be 0 0 0 1 (MID transforms are affine)");
        } else
            return TB__ERR(r, c->loc,
                           "unknown transform operation '%.40s' (expected translate, scale, rotate or matrix)",
                           c->name);
    }
    int bad = 0;
    tb_status st = tb_mid_ops_transform(ops, v->count, local, &bad);
    if (st) {
        if (bad >= v->count)
            return TB__ERR(r, v->loc, "the composed transform overflows (its entries are not finite)");
        const tb_mid_value *c = &v->items[bad];
        return TB__ERR(r, c->loc, "%s is singular or ill-conditioned (reciprocal condition number below %g)",
                       c->name, TB_MAT_RCOND_MIN);
    }
    *ops_out = ops;
    *nops_out = v->count;
    return TB_OK;
}

/* parent * local, checked for overflow; a NULL parent is the identity (the
 * product would give back `local` exactly, and local is known finite). */
static tb_status tb__world(tb_mid_reader *r, tb_mid_loc loc, const tb_transform *parent, const tb_transform *local,
                           tb_transform *out)
{
    if (!parent) {
        *out = *local;
        return TB_OK;
    }
    *out = tb_transform_compose(parent, local);
    if (!tb_mat4_isfinite(&out->m) || !tb_mat4_isfinite(&out->inv))
        return TB__ERR(r, loc, "the transform overflows when composed with its parents' transforms");
    return TB_OK;
}

/* ----------------------------------------------------------------- geometry */

/* A list of n-vectors (n = 2 or 3) as floats; *count = its length. */
static tb_status tb__vec_list(tb_mid_reader *r, const tb_mid_value *v, const char *what, int n, float **out,
                              int *count)
{
    char found[96];
    /* Defined on every path, errors included: the callers' -O3 builds
     * cannot see that an error return is never TB_OK. */
    *out = NULL;
    *count = 0;
    if (v->type == TB_MID_VECTOR && v->count == 0)
        return TB_OK;
    if (v->type != TB_MID_LIST)
        return TB__ERR(r, v->loc, "expected a list of %d-vectors for '%s', e.g. [%s], found %s", n, what,
                       n == 2 ? "[0 0] [1 0] [0 1]" : "[0 0 0] [1 0 0] [0 1 0]", TB__DESC(v));
    float *f = tb__mid_alloc(r, (size_t)v->count * (size_t)n * sizeof *f);
    if (!f)
        return tb__nomem(r);
    for (int i = 0; i < v->count; i++) {
        const tb_mid_value *e = &v->items[i];
        if (e->type != TB_MID_VECTOR || e->count != n)
            return TB__ERR(r, e->loc, "'%s' element %d: expected a %d-vector%s, found %s", what, i, n,
                           tb__vec_example(n), TB__DESC(e));
        for (int j = 0; j < n; j++) {
            tb_status st = tb__float_ok(r, e->loc, what, e->numbers[j]);
            if (st)
                return st;
            f[i * n + j] = (float)e->numbers[j];
        }
    }
    *out = f;
    *count = v->count;
    return TB_OK;
}

/* faces = [[i j k ...] ...] over nv vertices. */
static tb_status tb__faces(tb_mid_reader *r, const tb_mid_value *v, int nv, tb_geom_polygons *p)
{
    char found[96];
    if (v->type == TB_MID_VECTOR && v->count == 0)
        return TB__ERR(r, v->loc, "'faces' needs at least one face");
    if (v->type != TB_MID_LIST)
        return TB__ERR(r, v->loc, "expected a list of faces for 'faces', e.g. [[0 1 2] [0 2 3]], found %s",
                       TB__DESC(v));
    int64_t total = 0;
    for (int f = 0; f < v->count; f++) {
        const tb_mid_value *e = &v->items[f];
        if (e->type != TB_MID_VECTOR)
            return TB__ERR(r, e->loc, "face %d: expected a list of vertex indices, found %s", f, TB__DESC(e));
        if (e->count < 3)
            return TB__ERR(r, e->loc, "face %d has %d vertices (a face needs at least 3)", f, e->count);
        total += e->count;
        if (total > INT32_MAX)
            return TB__ERR(r, e->loc, "more than %d face indices", INT32_MAX);
    }
    int *start = tb__mid_alloc(r, ((size_t)v->count + 1) * sizeof *start);
    int *idx = tb__mid_alloc(r, (size_t)total * sizeof *idx);
    if (!start || !idx)
        return tb__nomem(r);
    int k = 0;
    for (int f = 0; f < v->count; f++) {
        const tb_mid_value *e = &v->items[f];
        start[f] = k;
        for (int j = 0; j < e->count; j++) {
            double x = e->numbers[j];
            if (x != floor(x) || x < 0 || x >= nv)
                return TB__ERR(r, e->loc, "face %d: vertex index %g is not an integer from 0 to %d", f, x, nv - 1);
            idx[k++] = (int)x;
        }
    }
    start[v->count] = k;
    p->nfaces = v->count;
    p->face_start = start;
    p->indices = idx;
    return TB_OK;
}

static tb_status tb__polygons(tb_mid_reader *r, const tb_mid_value *g, tb_geom_polygons *p, tb__extra *extra)
{
    const tb_mid_value *vertices = NULL, *faces = NULL, *normals = NULL, *uvs = NULL, *mesh = NULL;
    tb_status st;
    for (int i = 0; i < g->count; i++) {
        const tb_mid_attr *a = &g->attrs[i];
        if (TB__IS(a->name, "vertices"))
            vertices = &a->value;
        else if (TB__IS(a->name, "faces"))
            faces = &a->value;
        else if (TB__IS(a->name, "normals"))
            normals = &a->value;
        else if (TB__IS(a->name, "uvs"))
            uvs = &a->value;
        else if (TB__IS(a->name, "mesh"))
            mesh = &a->value;
        else if ((st = tb__extra_push(r, extra, a)))
            return st;
    }
    if (mesh) {
        if (vertices || faces || normals || uvs) {
            const tb_mid_value *x = vertices ? vertices : faces ? faces : normals ? normals : uvs;
            return TB__ERR(r, x->loc,
                           "polygons takes either a 'mesh' file or inline 'vertices' and 'faces', not both");
        }
        return tb__file(r, mesh, "mesh", &p->mesh);
    }
    if (!vertices || !faces)
        return TB__ERR(r, g->loc, "polygons needs 'vertices' and 'faces', or a 'mesh' file");
    float *f;
    int n;
    if ((st = tb__vec_list(r, vertices, "vertices", 3, &f, &n)))
        return st;
    if (n < 3)
        return TB__ERR(r, vertices->loc, "'vertices' needs at least 3 vertices, found %d", n);
    p->vertices = (const tb_vec3 *)f;
    p->nvertices = n;
    if ((st = tb__faces(r, faces, n, p)))
        return st;
    if (normals) {
        int nn;
        if ((st = tb__vec_list(r, normals, "normals", 3, &f, &nn)))
            return st;
        if (nn != n)
            return TB__ERR(r, normals->loc, "'normals' has %d entries for %d vertices (one per vertex)", nn, n);
        p->normals = (const tb_vec3 *)f;
    }
    if (uvs) {
        int nu;
        if ((st = tb__vec_list(r, uvs, "uvs", 2, &f, &nu)))
            return st;
        if (nu != n)
            return TB__ERR(r, uvs->loc, "'uvs' has %d entries for %d vertices (one per vertex)", nu, n);
        p->uvs = (const tb_vec2 *)f;
    }
    return TB_OK;
}

/* r^2 = c0 + c1 z + c2 z^2 at z, and the size of its terms (for the rounding tolerance). */
static double tb__conic_r2(const double c[3], double z, double *size)
{
    *size = fabs(c[0]) + fabs(c[1] * z) + fabs(c[2] * z * z);
    return c[0] + c[1] * z + c[2] * z * z;
}

static tb_status tb__conic_check(tb_mid_reader *r, tb_mid_loc loc, const tb_geom_conic *g)
{
    if (!(g->z0 < g->z1))
        return TB__ERR(r, loc, "'z_range' must be increasing [z0 z1], found [%g %g]", g->z0, g->z1);
    double zs[3] = {g->z0, g->z1, 0.0};
    int n = 2;
    if (g->c[2] != 0.0) {
        double zv = -g->c[1] / (2.0 * g->c[2]) + 0.0; /* the parabola's vertex (+0.0: no -0 in messages) */
        if (zv > g->z0 && zv < g->z1)
            zs[n++] = zv;
    }
    double rmax = 0.0;
    for (int i = 0; i < n; i++) {
        double size, r2 = tb__conic_r2(g->c, zs[i], &size);
        if (!isfinite(r2) || !isfinite(size))
            return TB__ERR(r, loc, "conic radius overflows at z = %g", zs[i]);
        if (r2 < -1e-12 * size)
            return TB__ERR(r, loc, "conic radius is imaginary: c0 + c1 z + c2 z^2 = %g < 0 at z = %g", r2, zs[i]);
        rmax = fmax(rmax, r2);
    }
    if (!(rmax > 0.0))
        return TB__ERR(r, loc, "conic radius is zero on the whole z_range");
    return TB_OK;
}

/* A number >= 0 (hi_open: and < hi; else <= hi), for a double field. */
static tb_status tb__param(tb_mid_reader *r, const tb_mid_value *v, const char *what, bool positive, double hi,
                           double *out)
{
    double x = 0.0;
    tb_status st = tb__number(r, v, what, &x);
    if (st)
        return st;
    bool ok = positive ? x > 0.0 : x >= 0.0;
    if (!isinf(hi))
        ok = ok && x < hi;
    if (!ok) {
        char range[32];
        if (isinf(hi))
            snprintf(range, sizeof range, positive ? "> 0" : ">= 0");
        else
            snprintf(range, sizeof range, positive ? "in (0, %g)" : "in [0, %g)", hi);
        return tb__range_error(r, v->loc, what, range, x);
    }
    *out = x;
    return TB_OK;
}

static tb_status tb__geometry(tb_mid_reader *r, tb_prim_kind k, const tb_mid_value *g, tb_mid_object *o)
{
    tb_mid_geometry *geo = &o->geom;
    *geo = tb_mid_geometry_default(k);
    tb__extra extra = {0};
    tb_status st;
    if (k == TB_PRIM_POLYGONS) {
        if (!g)
            return TB__ERR(r, o->loc,
                           "polygons needs 'geometry = { vertices = [...] faces = [...] }' or "
                           "'geometry = { mesh = file(\"...\") }'");
        if ((st = tb__polygons(r, g, &geo->polygons, &extra)))
            return st;
        o->geometry_extra = tb__extra_done(&extra);
        return TB_OK;
    }
    if (!g)
        return TB_OK;
    const tb_mid_attr *sides = NULL;
    for (int i = 0; i < g->count; i++) {
        const tb_mid_attr *a = &g->attrs[i];
        const tb_mid_value *v = &a->value;
        const char *n = a->name;
        bool known = true;
        st = TB_OK;
        switch (k) {
        case TB_PRIM_CYLINDER:
            if (TB__IS(n, "caps"))
                st = tb__bool(r, v, n, &geo->cylinder.caps);
            else
                known = false;
            break;
        case TB_PRIM_CONE:
            if (TB__IS(n, "caps"))
                st = tb__bool(r, v, n, &geo->cone.caps);
            else if (TB__IS(n, "top_radius"))
                st = tb__param(r, v, n, false, INFINITY, &geo->cone.top_radius);
            else
                known = false;
            break;
        case TB_PRIM_PYRAMID:
            if (TB__IS(n, "caps"))
                st = tb__bool(r, v, n, &geo->pyramid.caps);
            else if (TB__IS(n, "top"))
                st = tb__param(r, v, n, false, INFINITY, &geo->pyramid.top);
            else
                known = false;
            break;
        case TB_PRIM_PRISM:
            if (TB__IS(n, "caps"))
                st = tb__bool(r, v, n, &geo->prism.caps);
            else if (TB__IS(n, "sides")) {
                st = tb__int(r, v, n, 3, 1000000, &geo->prism.sides);
                sides = a;
            } else if (TB__IS(n, "profile")) {
                float *f;
                int np;
                if ((st = tb__vec_list(r, v, n, 2, &f, &np)))
                    break;
                if (np < 3) {
                    st = TB__ERR(r, v->loc, "'profile' needs at least 3 points, found %d", np);
                    break;
                }
                double area = 0.0; /* shoelace, in double */
                for (int j = 0; j < np; j++) {
                    int j1 = (j + 1) % np;
                    area += (double)f[2 * j] * f[2 * j1 + 1] - (double)f[2 * j1] * f[2 * j + 1];
                }
                if (area == 0.0)
                    st = TB__ERR(r, v->loc, "'profile' encloses no area");
                geo->prism.profile = (const tb_vec2 *)f;
                geo->prism.nprofile = np;
            } else
                known = false;
            break;
        case TB_PRIM_TORUS:
            if (TB__IS(n, "major"))
                st = tb__param(r, v, n, true, INFINITY, &geo->torus.major);
            else if (TB__IS(n, "minor"))
                st = tb__param(r, v, n, true, INFINITY, &geo->torus.minor);
            else
                known = false;
            break;
        case TB_PRIM_CONIC:
            if (TB__IS(n, "caps"))
                st = tb__bool(r, v, n, &geo->conic.caps);
            else if (TB__IS(n, "coefficients"))
                st = tb__vec(r, v, n, 3, geo->conic.c);
            else if (TB__IS(n, "z_range")) {
                double z[2];
                if (!(st = tb__vec(r, v, n, 2, z))) {
                    geo->conic.z0 = z[0];
                    geo->conic.z1 = z[1];
                }
            } else
                known = false;
            break;
        case TB_PRIM_SQUARE_ARCH:
        case TB_PRIM_ROUND_ARCH:
            if (TB__IS(n, "width"))
                st = tb__param(r, v, n, true, 2.0, &geo->arch.width);
            else if (TB__IS(n, "height"))
                st = tb__param(r, v, n, true, 2.0, &geo->arch.height);
            else
                known = false;
            break;
        default: known = false; break;
        }
        if (!st && !known)
            st = tb__extra_push(r, &extra, a);
        if (st)
            return st;
    }
    /* Checks that involve several attributes. */
    switch (k) {
    case TB_PRIM_PRISM:
        if (geo->prism.nprofile > 0) {
            if (sides)
                return TB__ERR(r, sides->loc, "prism takes 'sides' or 'profile', not both");
            geo->prism.sides = 0;
        }
        break;
    case TB_PRIM_TORUS:
        if (!(geo->torus.minor < geo->torus.major))
            return TB__ERR(r, g->loc, "torus 'minor' (%g) must be less than 'major' (%g)", geo->torus.minor,
                           geo->torus.major);
        break;
    case TB_PRIM_CONIC:
        if ((st = tb__conic_check(r, g->loc, &geo->conic)))
            return st;
        break;
    case TB_PRIM_ROUND_ARCH:
        if (!(geo->arch.height >= geo->arch.width / 2.0))
            return TB__ERR(r, g->loc, "round arch 'height' (%g) must be at least half the 'width' (%g)",
                           geo->arch.height, geo->arch.width);
        break;
    default: break;
    }
    o->geometry_extra = tb__extra_done(&extra);
    return TB_OK;
}

/* ---------------------------------------------------------------- materials */

/* Clears what describes a block (not the resolved values). */
static void tb__material_unset(tb_mid_material *m, tb_mid_loc loc)
{
    m->name = NULL;
    m->base = NULL;
    m->set = 0;
    m->extra = (tb_mid_attrs){NULL, 0};
    m->refs = NULL;
    m->nrefs = 0;
    m->loc = loc;
}

/* The optional space argument of a pattern: the symbol uv or object. */
static tb_status tb__pattern_space(tb_mid_reader *r, const tb_mid_value *v, const char *fn, bool *object)
{
    char found[96];
    if (v->type == TB_MID_SYMBOL && TB__IS(v->text, "uv"))
        *object = false;
    else if (v->type == TB_MID_SYMBOL && TB__IS(v->text, "object"))
        *object = true;
    else
        return TB__ERR(r, v->loc, "expected uv or object for the space of %s(), found %s", fn, TB__DESC(v));
    return TB_OK;
}

/* The scale of a pattern: a number > 0, or [su sv] (both > 0) in uv space. */
static tb_status tb__pattern_scale(tb_mid_reader *r, const tb_mid_value *v, tb_mid_pattern *out)
{
    if (v->type == TB_MID_VECTOR && v->count == 2) {
        for (int i = 0; i < 2; i++)
            if (!(v->numbers[i] > 0.0))
                return TB__ERR(r, v->loc, "'scale' must be > 0, found %g", v->numbers[i]);
        out->scale = v->numbers[0];
        out->scale_v = v->numbers[1];
        return TB_OK;
    }
    tb_status st = tb__param(r, v, "scale", true, INFINITY, &out->scale);
    out->scale_v = out->scale;
    return st;
}

/* A 2-vector scale is for (u, v) only. */
static tb_status tb__pattern_scale_space(tb_mid_reader *r, const tb_mid_value *v, const tb_mid_pattern *p)
{
    if (p->object_space && p->scale_v != p->scale)
        return TB__ERR(r, v->loc, "a scale [su sv] applies to (u, v); object space takes one number");
    return TB_OK;
}

/* A procedural pattern (diffuse_pattern, specular_pattern) or, with `bump`,
 * a bump map (docs/mid.md, 7.2). */
static tb_status tb__pattern(tb_mid_reader *r, const tb_mid_value *v, const char *what, bool bump,
                             tb_mid_pattern *out)
{
    char found[96];
    tb_status st;
    memset(out, 0, sizeof *out);
    if (v->type != TB_MID_CALL)
        return TB__ERR(r, v->loc, "expected %s for '%s', found %s",
                       bump ? "noise(...) or image(...)" : "checker(...) or noise(...)", what, TB__DESC(v));
    const tb_mid_value *a = v->items;
    const int n = v->count;
    if (!bump && TB__IS(v->name, "checker")) {
        if (n != 3 && n != 4)
            return TB__ERR(r, v->loc,
                           "checker takes a scale, two colours and an optional space: checker(scale, a, b [, uv|object])");
        out->kind = TB_MID_PATTERN_CHECKER;
        if ((st = tb__pattern_scale(r, &a[0], out)) || (st = tb__color(r, &a[1], what, 1.0, &out->a)) ||
            (st = tb__color(r, &a[2], what, 1.0, &out->b)) ||
            (n == 4 && (st = tb__pattern_space(r, &a[3], "checker", &out->object_space))))
            return st;
        return tb__pattern_scale_space(r, &a[0], out);
    }
    if (TB__IS(v->name, "noise")) {
        int k = bump ? 3 : 4;
        if (n != k && n != k + 1)
            return TB__ERR(r, v->loc, "%s",
                           bump ? "noise takes a scale, an octave count, a height and an optional space: "
                                  "noise(scale, octaves, height [, uv|object])"
                                : "noise takes a scale, an octave count, two colours and an optional space: "
                                  "noise(scale, octaves, a, b [, uv|object])");
        out->kind = TB_MID_PATTERN_NOISE;
        if ((st = tb__pattern_scale(r, &a[0], out)) || (st = tb__int(r, &a[1], "octaves", 1, 16, &out->octaves)))
            return st;
        if (bump)
            st = tb__number(r, &a[2], "height", &out->height);
        else if (!(st = tb__color(r, &a[2], what, 1.0, &out->a)))
            st = tb__color(r, &a[3], what, 1.0, &out->b);
        if (!st && n == k + 1)
            st = tb__pattern_space(r, &a[k], "noise", &out->object_space);
        return st ? st : tb__pattern_scale_space(r, &a[0], out);
    }
    if (bump && TB__IS(v->name, "image")) {
        if (n != 2 || a[0].type != TB_MID_FILE)
            return TB__ERR(r, v->loc, "image takes a file and a height: image(file(\"heights.png\"), height)");
        out->kind = TB_MID_PATTERN_IMAGE;
        out->image = a[0].ref;
        return tb__number(r, &a[1], "height", &out->height);
    }
    return TB__ERR(r, v->loc, "unknown pattern '%.40s' for '%s' (expected %s)", v->name, what,
                   bump ? "noise or image" : "checker or noise");
}

/* A rendering block (or a material body): starts from `inherited`, or from
 * the material it names, and applies its attributes. */
static tb_status tb__rendering(tb_mid_reader *r, const tb_mid_attr *attrs, int n, tb_mid_loc loc,
                               const tb_mid_material *inherited, tb_mid_material *m)
{
    char found[96];
    tb_status st;
    /* The base material first, wherever it is written: the inherited one
     * or the one it names. Found before copying, so the 880-byte material is
     * copied once per object, not twice. */
    const tb_mid_material *start = inherited;
    const char *base = NULL;
    for (int i = 0; i < n; i++) {
        if (!TB__IS(attrs[i].name, "material"))
            continue;
        const tb_mid_value *v = &attrs[i].value;
        uint64_t p = 0;
        if (v->type != TB_MID_STRING)
            st = TB__ERR(r, v->loc, "expected a material name string for 'material', found %s", TB__DESC(v));
        else if (!tb_htab_get_str(&r->materials, v->text, &p))
            st = TB__ERR(r, v->loc, "unknown material '%.40s' (materials must be defined before use)", v->text);
        else {
            start = (const tb_mid_material *)(uintptr_t)p;
            base = v->text;
            continue;
        }
        *m = *inherited;
        tb__material_unset(m, loc);
        return st;
    }
    *m = *start;
    tb__material_unset(m, loc);
    m->base = base;
    tb__extra extra = {0};
    for (int i = 0; i < n; i++) {
        const tb_mid_attr *a = &attrs[i];
        const tb_mid_value *v = &a->value;
        const char *nm = a->name;
        double x = 0.0;
        st = TB_OK;
        if (TB__IS(nm, "material"))
            continue;
        else if (TB__IS(nm, "diffuse")) {
            st = tb__color(r, v, nm, 1.0, &m->diffuse);
            m->set |= TB_MID_SET_DIFFUSE;
        } else if (TB__IS(nm, "specular")) {
            st = tb__color(r, v, nm, 1.0, &m->specular);
            m->set |= TB_MID_SET_SPECULAR;
        } else if (TB__IS(nm, "transmission")) {
            st = tb__color(r, v, nm, 1.0, &m->transmission);
            m->set |= TB_MID_SET_TRANSMISSION;
        } else if (TB__IS(nm, "emission")) {
            st = tb__color(r, v, nm, INFINITY, &m->emission);
            m->set |= TB_MID_SET_EMISSION;
        } else if (TB__IS(nm, "exponent")) {
            if (!(st = tb__param(r, v, nm, false, INFINITY, &x)))
                st = tb__float_ok(r, v->loc, nm, x);
            m->exponent = (float)x;
            m->set |= TB_MID_SET_EXPONENT;
        } else if (TB__IS(nm, "ior")) {
            if (!(st = tb__param(r, v, nm, true, INFINITY, &x)))
                st = tb__float_ok(r, v->loc, nm, x);
            m->ior = (float)x;
            m->set |= TB_MID_SET_IOR;
        } else if (TB__IS(nm, "diffuse_texture")) {
            st = tb__file(r, v, nm, &m->diffuse_texture);
            m->set |= TB_MID_SET_DIFFUSE_TEXTURE;
        } else if (TB__IS(nm, "specular_texture")) {
            st = tb__file(r, v, nm, &m->specular_texture);
            m->set |= TB_MID_SET_SPECULAR_TEXTURE;
        } else if (TB__IS(nm, "transmission_texture")) {
            st = tb__file(r, v, nm, &m->transmission_texture);
            m->set |= TB_MID_SET_TRANSMISSION_TEXTURE;
        } else if (TB__IS(nm, "emission_texture")) {
            st = tb__file(r, v, nm, &m->emission_texture);
            m->set |= TB_MID_SET_EMISSION_TEXTURE;
        } else if (TB__IS(nm, "model")) {
            int k = 0;
            while (k < TB_MID_MODEL_COUNT &&
                   !(v->type == TB_MID_SYMBOL && strcmp(v->text, tb_mid_model_name((tb_mid_model)k)) == 0))
                k++;
            if (k == TB_MID_MODEL_COUNT)
                st = TB__ERR(r, v->loc, "expected phong, blinn, lambert or ggx for 'model', found %s", TB__DESC(v));
            m->model = (tb_mid_model)k;
            m->set |= TB_MID_SET_MODEL;
        } else if (TB__IS(nm, "roughness")) {
            if (!(st = tb__number(r, v, nm, &x)) && !(x >= 0.0 && x <= 1.0))
                st = tb__range_error(r, v->loc, nm, "in [0, 1]", x);
            m->roughness = (float)x;
            m->set |= TB_MID_SET_ROUGHNESS;
        } else if (TB__IS(nm, "diffuse_pattern")) {
            st = tb__pattern(r, v, nm, false, &m->diffuse_pattern);
            m->set |= TB_MID_SET_DIFFUSE_PATTERN;
        } else if (TB__IS(nm, "specular_pattern")) {
            st = tb__pattern(r, v, nm, false, &m->specular_pattern);
            m->set |= TB_MID_SET_SPECULAR_PATTERN;
        } else if (TB__IS(nm, "bump")) {
            st = tb__pattern(r, v, nm, true, &m->bump);
            m->set |= TB_MID_SET_BUMP;
        } else
            st = tb__extra_push(r, &extra, a);
        if (st)
            return st;
    }
    m->extra = tb__extra_done(&extra);
    size_t first = r->refs.len;
    if ((st = tb__push_material_refs(r, m)))
        return st;
    return tb__take_refs(r, first, &m->refs, &m->nrefs);
}

/* ------------------------------------------------------------ deep copies */

static char *tb__dup(tb_arena *a, const char *s) { return s ? tb_arena_strdup(a, s) : NULL; }

static bool tb__copy_ref(tb_arena *a, const tb_mid_ref *s, tb_mid_ref *d)
{
    d->text = tb__dup(a, s->text);
    d->path = tb__dup(a, s->path);
    return (!s->text || d->text) && (!s->path || d->path);
}

static bool tb__copy_attrs(tb_arena *a, const tb_mid_attr *s, int n, const tb_mid_attr **d);

static bool tb__copy_value(tb_arena *a, const tb_mid_value *s, tb_mid_value *d)
{
    *d = *s;
    switch (s->type) {
    case TB_MID_STRING:
    case TB_MID_SYMBOL: return (d->text = tb__dup(a, s->text)) != NULL;
    case TB_MID_VECTOR: {
        if (s->count == 0)
            return true;
        double *x = tb_arena_alloc(a, (size_t)s->count * sizeof *x);
        if (!x)
            return false;
        memcpy(x, s->numbers, (size_t)s->count * sizeof *x);
        d->numbers = x;
        return true;
    }
    case TB_MID_CALL:
        if (!(d->name = tb__dup(a, s->name)))
            return false;
        /* fall through */
    case TB_MID_LIST: {
        if (s->count == 0) {
            d->items = NULL;
            return true;
        }
        tb_mid_value *x = tb_arena_alloc(a, (size_t)s->count * sizeof *x);
        if (!x)
            return false;
        for (int i = 0; i < s->count; i++)
            if (!tb__copy_value(a, &s->items[i], &x[i]))
                return false;
        d->items = x;
        return true;
    }
    case TB_MID_BLOCK: return tb__copy_attrs(a, s->attrs, s->count, &d->attrs);
    case TB_MID_FILE: return tb__copy_ref(a, &s->ref, &d->ref);
    default: return true;
    }
}

static bool tb__copy_attrs(tb_arena *a, const tb_mid_attr *s, int n, const tb_mid_attr **d)
{
    *d = NULL;
    if (n == 0)
        return true;
    tb_mid_attr *x = tb_arena_alloc(a, (size_t)n * sizeof *x);
    if (!x)
        return false;
    for (int i = 0; i < n; i++) {
        x[i] = s[i];
        if (!(x[i].name = tb__dup(a, s[i].name)) || !tb__copy_value(a, &s[i].value, &x[i].value))
            return false;
    }
    *d = x;
    return true;
}

static bool tb__copy_refs(tb_arena *a, const tb_mid_ref *s, int n, const tb_mid_ref **d)
{
    *d = NULL;
    if (n == 0)
        return true;
    tb_mid_ref *x = tb_arena_alloc(a, (size_t)n * sizeof *x);
    if (!x)
        return false;
    for (int i = 0; i < n; i++)
        if (!tb__copy_ref(a, &s[i], &x[i]))
            return false;
    *d = x;
    return true;
}

static bool tb__copy_color(tb_arena *a, const tb_mid_color *s, tb_mid_color *d)
{
    *d = *s;
    if (s->type == TB_MID_COLOR_SPECTRUM) {
        float *nm = tb_arena_alloc(a, (size_t)s->nsamples * sizeof *nm);
        float *v = tb_arena_alloc(a, (size_t)s->nsamples * sizeof *v);
        if (!nm || !v)
            return false;
        memcpy(nm, s->nm, (size_t)s->nsamples * sizeof *nm);
        memcpy(v, s->values, (size_t)s->nsamples * sizeof *v);
        d->nm = nm;
        d->values = v;
    }
    return tb__copy_ref(a, &s->file, &d->file);
}

static bool tb__copy_pattern(tb_arena *a, const tb_mid_pattern *s, tb_mid_pattern *d)
{
    *d = *s;
    return tb__copy_color(a, &s->a, &d->a) && tb__copy_color(a, &s->b, &d->b) &&
           tb__copy_ref(a, &s->image, &d->image);
}

static bool tb__copy_material(tb_arena *a, const tb_mid_material *s, tb_mid_material *d)
{
    *d = *s;
    return (!s->name || (d->name = tb__dup(a, s->name))) && (!s->base || (d->base = tb__dup(a, s->base))) &&
           tb__copy_color(a, &s->diffuse, &d->diffuse) && tb__copy_color(a, &s->specular, &d->specular) &&
           tb__copy_color(a, &s->transmission, &d->transmission) &&
           tb__copy_color(a, &s->emission, &d->emission) &&
           tb__copy_ref(a, &s->diffuse_texture, &d->diffuse_texture) &&
           tb__copy_ref(a, &s->specular_texture, &d->specular_texture) &&
           tb__copy_ref(a, &s->transmission_texture, &d->transmission_texture) &&
           tb__copy_ref(a, &s->emission_texture, &d->emission_texture) &&
           tb__copy_pattern(a, &s->diffuse_pattern, &d->diffuse_pattern) &&
           tb__copy_pattern(a, &s->specular_pattern, &d->specular_pattern) &&
           tb__copy_pattern(a, &s->bump, &d->bump) &&
           tb__copy_attrs(a, s->extra.items, s->extra.count, &d->extra.items) &&
           tb__copy_refs(a, s->refs, s->nrefs, &d->refs);
}

/* ------------------------------------------------------------------ objects */

static tb_status tb__object(tb_mid_reader *r, const tb__mid_node *n, const tb_transform *parent,
                            const tb_mid_material *inherited, tb_mid_object *o)
{
    tb_status st;
    memset(o, 0, sizeof *o);
    tb_prim_kind k = (tb_prim_kind)n->keyword;
    o->kind = k;
    o->name = n->name;
    o->loc = n->loc;
    const tb_mid_value *geometry = NULL;
    const tb_mid_attr *rendering = NULL;
    tb_transform local = tb__mid_identity;
    tb__extra extra = {0};
    for (int i = 0; i < n->nattrs; i++) {
        const tb_mid_attr *a = &n->attrs[i];
        if (TB__IS(a->name, "transform"))
            st = tb__transform(r, &a->value, &o->ops, &o->nops, &local);
        else if (TB__IS(a->name, "geometry")) {
            st = tb__block(r, &a->value, "geometry");
            geometry = &a->value;
        } else if (TB__IS(a->name, "rendering")) {
            st = tb__block(r, &a->value, "rendering");
            rendering = a;
        } else
            st = tb__extra_push(r, &extra, a);
        if (st)
            return st;
    }
    o->extra = tb__extra_done(&extra);
    if ((st = tb__world(r, n->loc, parent, &local, &o->to_world)))
        return st;
    if ((st = tb__geometry(r, k, geometry, o)))
        return st;
    if (rendering) {
        if ((st = tb__rendering(r, rendering->value.attrs, rendering->value.count, rendering->loc, inherited,
                                &o->material)))
            return st;
    } else {
        o->material = *inherited;
        tb__material_unset(&o->material, n->loc);
    }
    /* The object's own references, in the order the writer writes them. */
    size_t first = r->refs.len;
    if ((k == TB_PRIM_POLYGONS && (st = tb__push_ref(r, &o->geom.polygons.mesh))) ||
        (st = tb__push_attrs_refs(r, &o->geometry_extra)) || (st = tb__push_material_refs(r, &o->material)) ||
        (st = tb__push_attrs_refs(r, &o->extra)) || (st = tb__take_refs(r, first, &o->refs, &o->nrefs)))
        return st;
    if (!tb_prim_is_csg(k))
        return TB_OK;
    if (k == TB_PRIM_DIFFERENCE && n->nchildren < 2)
        return TB__ERR(r, n->loc, "difference needs at least two child objects, found %d", n->nchildren);
    if (n->nchildren < 1)
        return TB__ERR(r, n->loc, "%s needs at least one child object", tb_prim_kind_name(k));
    tb_mid_object *ch = tb__mid_alloc(r, (size_t)n->nchildren * sizeof *ch);
    if (!ch)
        return tb__nomem(r);
    for (int i = 0; i < n->nchildren; i++)
        if ((st = tb__object(r, &n->children[i], &o->to_world, &o->material, &ch[i])))
            return st;
    o->children = ch;
    o->nchildren = n->nchildren;
    return TB_OK;
}

/* ------------------------------------------------------------------- lights */

static tb_status tb__light(tb_mid_reader *r, const tb__mid_node *n, tb_mid_light *l)
{
    tb_light_kind kind = n->keyword == TB__K_POINT_LIGHT  ? TB_LIGHT_POINT
                         : n->keyword == TB__K_SPOT_LIGHT ? TB_LIGHT_SPOT
                                                          : TB_LIGHT_DIRECTIONAL;
    *l = tb_mid_light_default(kind);
    l->name = n->name;
    l->loc = n->loc;
    tb__extra extra = {0};
    tb_transform local = tb__mid_identity;
    tb_mid_loc cone_loc = n->loc;
    bool spot = kind == TB_LIGHT_SPOT, dir = kind == TB_LIGHT_DIRECTIONAL;
    tb_status st;
    for (int i = 0; i < n->nattrs; i++) {
        const tb_mid_attr *a = &n->attrs[i];
        const tb_mid_value *v = &a->value;
        const char *nm = a->name;
        if (TB__IS(nm, "transform"))
            st = tb__transform(r, v, &l->ops, &l->nops, &local);
        else if (!dir && TB__IS(nm, "position"))
            st = tb__dvec3(r, v, nm, &l->position);
        else if ((spot || dir) && TB__IS(nm, "direction")) {
            if (!(st = tb__dvec3(r, v, nm, &l->direction)) && l->direction.x == 0.0 && l->direction.y == 0.0 &&
                l->direction.z == 0.0)
                st = TB__ERR(r, v->loc, "'direction' must be non-zero");
        } else if (!dir && TB__IS(nm, "intensity"))
            st = tb__color(r, v, nm, INFINITY, &l->intensity);
        else if (dir && TB__IS(nm, "irradiance"))
            st = tb__color(r, v, nm, INFINITY, &l->intensity);
        else if (spot && TB__IS(nm, "cone_angle")) {
            double x = 0.0;
            if (!(st = tb__number(r, v, nm, &x)) && !(x > 0.0 && x <= 90.0))
                st = tb__range_error(r, v->loc, nm, "in (0, 90]", x);
            l->cone_angle = x;
        } else if (spot && TB__IS(nm, "cone_delta")) {
            st = tb__param(r, v, nm, false, INFINITY, &l->cone_delta);
            cone_loc = v->loc;
        } else if (!dir && TB__IS(nm, "ies"))
            st = tb__file(r, v, nm, &l->ies);
        else
            st = tb__extra_push(r, &extra, a);
        if (st)
            return st;
    }
    if (spot && !(l->cone_delta <= l->cone_angle))
        return TB__ERR(r, cone_loc, "'cone_delta' (%g) must not exceed 'cone_angle' (%g)", l->cone_delta,
                       l->cone_angle);
    l->extra = tb__extra_done(&extra);
    size_t first = r->refs.len;
    if ((st = tb__push_color_ref(r, &l->intensity)) || (st = tb__push_ref(r, &l->ies)) ||
        (st = tb__push_attrs_refs(r, &l->extra)) || (st = tb__take_refs(r, first, &l->refs, &l->nrefs)))
        return st;
    return tb__world(r, n->loc, NULL, &local, &l->to_world);
}

/* ------------------------------------------------------------------- camera */

static tb_status tb__camera(tb_mid_reader *r, const tb__mid_node *n, tb_mid_camera *c)
{
    char found[96];
    *c = tb_mid_camera_default();
    c->name = n->name;
    c->loc = n->loc;
    tb__extra extra = {0};
    const tb_mid_value *fov = NULL, *focal = NULL, *focus = NULL;
    tb_status st;
    for (int i = 0; i < n->nattrs; i++) {
        const tb_mid_attr *a = &n->attrs[i];
        const tb_mid_value *v = &a->value;
        const char *nm = a->name;
        double x = 0.0;
        if (TB__IS(nm, "eye"))
            st = tb__dvec3(r, v, nm, &c->eye);
        else if (TB__IS(nm, "look_at"))
            st = tb__dvec3(r, v, nm, &c->look_at);
        else if (TB__IS(nm, "up"))
            st = tb__dvec3(r, v, nm, &c->up);
        else if (TB__IS(nm, "fov")) {
            if (!(st = tb__number(r, v, nm, &x)) && !(x > 0.0 && x < 180.0))
                st = tb__range_error(r, v->loc, nm, "in (0, 180)", x);
            c->fov = x;
            fov = v;
        } else if (TB__IS(nm, "focal_length")) {
            st = tb__param(r, v, nm, true, INFINITY, &c->focal_length);
            focal = v;
        } else if (TB__IS(nm, "film")) {
            if (!(st = tb__vec(r, v, nm, 2, c->film)) && !(c->film[0] > 0.0 && c->film[1] > 0.0))
                st = TB__ERR(r, v->loc, "'film' sizes must be > 0, found [%g %g]", c->film[0], c->film[1]);
        } else if (TB__IS(nm, "resolution")) {
            if (v->type != TB_MID_VECTOR || v->count != 2)
                st = TB__ERR(r, v->loc, "expected 2 integers [width height] for 'resolution', found %s",
                             TB__DESC(v));
            else {
                tb_mid_value e = *v;
                e.type = TB_MID_NUMBER;
                e.number = v->numbers[0];
                if (!(st = tb__int(r, &e, nm, 1, 65536, &c->width))) {
                    e.number = v->numbers[1];
                    st = tb__int(r, &e, nm, 1, 65536, &c->height);
                }
            }
        } else if (TB__IS(nm, "aperture"))
            st = tb__param(r, v, nm, false, INFINITY, &c->aperture);
        else if (TB__IS(nm, "focus_distance")) {
            st = tb__param(r, v, nm, true, INFINITY, &c->focus_distance);
            focus = v;
        } else
            st = tb__extra_push(r, &extra, a);
        if (st)
            return st;
    }
    c->extra = tb__extra_done(&extra);
    size_t first = r->refs.len;
    if ((st = tb__push_attrs_refs(r, &c->extra)) || (st = tb__take_refs(r, first, &c->refs, &c->nrefs)))
        return st;
    if (fov && focal)
        return TB__ERR(r, focal->loc, "give either 'fov' or 'focal_length', not both");
    if (focal)
        c->fov = tb_mid_camera_fov(c->focal_length, c->film, c->width, c->height);
    tb_dvec3 d = tb_dvec3_sub(c->look_at, c->eye);
    if (d.x == 0.0 && d.y == 0.0 && d.z == 0.0)
        return TB__ERR(r, n->loc, "camera 'eye' and 'look_at' must differ");
    double dist = tb_dvec3_length(d);
    if (!isfinite(dist))
        return TB__ERR(r, n->loc, "camera 'look_at' is too far from 'eye'");
    tb_transform view;
    if (tb_transform_look_at(c->eye, c->look_at, c->up, &view))
        return TB__ERR(r, n->loc, "camera 'up' must be non-zero and not parallel to the view direction");
    if (!focus)
        c->focus_distance = dist;
    return TB_OK;
}

/* -------------------------------------------------------------------- items */

tb_status tb__mid_interpret(tb_mid_reader *r, const tb__mid_node *n, tb_mid_item *item)
{
    tb_status st;
    memset(item, 0, sizeof *item);
    if (n->keyword < TB_PRIM_COUNT) {
        tb_mid_object *o = tb__mid_alloc(r, sizeof *o);
        if (!o)
            return tb__nomem(r);
        if ((st = tb__object(r, n, NULL, &tb__mid_default_material, o)))
            return st;
        item->type = TB_MID_ITEM_OBJECT;
        item->object = o;
        return TB_OK;
    }
    switch (n->keyword) {
    case TB__K_MATERIAL: {
        if (!n->name)
            return TB__ERR(r, n->loc, "a material needs a name: material \"NAME\" { ... }");
        uint64_t p;
        if (tb_htab_get_str(&r->materials, n->name, &p)) {
            const tb_mid_material *old = (const tb_mid_material *)(uintptr_t)p;
            return TB__ERR(r, n->loc, "material '%.40s' is already defined at %ld:%ld", n->name, old->loc.line,
                           old->loc.col);
        }
        tb_mid_material m;
        if ((st = tb__rendering(r, n->attrs, n->nattrs, n->loc, &tb__mid_default_material, &m)))
            return st;
        m.name = n->name;
        tb_mid_material *kept = tb_arena_alloc(&r->keep, sizeof *kept);
        if (!kept || !tb__copy_material(&r->keep, &m, kept))
            return tb__nomem(r);
        if (tb_htab_put_str(&r->materials, kept->name, (uint64_t)(uintptr_t)kept))
            return tb__nomem(r);
        item->type = TB_MID_ITEM_MATERIAL;
        item->material = kept;
        return TB_OK;
    }
    case TB__K_POINT_LIGHT:
    case TB__K_SPOT_LIGHT:
    case TB__K_DIRECTIONAL_LIGHT:
        if ((st = tb__light(r, n, &r->light)))
            return st;
        item->type = TB_MID_ITEM_LIGHT;
        item->light = &r->light;
        return TB_OK;
    case TB__K_CAMERA: {
        if (r->camera)
            return TB__ERR(r, n->loc, "a scene has one camera; another was defined at %ld:%ld",
                           r->camera->loc.line, r->camera->loc.col);
        tb_mid_camera c;
        if ((st = tb__camera(r, n, &c)))
            return st;
        tb_mid_camera *kept = tb_arena_alloc(&r->keep, sizeof *kept);
        if (!kept)
            return tb__nomem(r);
        *kept = c;
        if ((c.name && !(kept->name = tb__dup(&r->keep, c.name))) ||
            !tb__copy_attrs(&r->keep, c.extra.items, c.extra.count, &kept->extra.items) ||
            !tb__copy_refs(&r->keep, c.refs, c.nrefs, &kept->refs))
            return tb__nomem(r);
        r->camera = kept;
        item->type = TB_MID_ITEM_CAMERA;
        item->camera = kept;
        return TB_OK;
    }
    default: return tb_error(TB_ERR_FORMAT, "%s: internal error: unknown keyword %d", r->lx.name, n->keyword);
    }
}
