/* MID writer: the canonical form of docs/mid.md, section 12. */
#include "host/mid/mid_writer.h"

#include <locale.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "host/mid/mid_internal.h"

/* The output stream and the first problem met (writing goes on, the status
 * is reported at the end). */
typedef struct tb__w {
    FILE *fp;
    tb_status st;
    bool bump; /* writing the `bump` attribute (its noise() takes a height, not colours) */
} tb__w;

static void tb__bad(tb__w *w, const char *what)
{
    if (!w->st)
        w->st = tb_error(TB_ERR_ARG, "MID writer: %s", what);
}

static void tb__indent(tb__w *w, int level)
{
    for (int i = 0; i < level; i++)
        fputs("    ", w->fp);
}

/* The shortest %.Ng of a double that reads back exactly. */
static void tb__double(tb__w *w, double x)
{
    if (!isfinite(x)) {
        tb__bad(w, "a number is NaN or infinite");
        fputs("0", w->fp);
        return;
    }
    char buf[40];
    for (int p = 15; p <= 17; p++) {
        snprintf(buf, sizeof buf, "%.*g", p, x);
        if (strtod(buf, NULL) == x)
            break;
    }
    fputs(buf, w->fp);
}

/* The shortest %.Ng of a float that reads back exactly (through double, as
 * the reader converts it). */
static void tb__float(tb__w *w, float x)
{
    if (!isfinite(x)) {
        tb__bad(w, "a number is NaN or infinite");
        fputs("0", w->fp);
        return;
    }
    char buf[40];
    for (int p = 6; p <= 9; p++) {
        snprintf(buf, sizeof buf, "%.*g", p, (double)x);
        if ((float)strtod(buf, NULL) == x)
            break;
    }
    fputs(buf, w->fp);
}

static void tb__string(tb__w *w, const char *s)
{
    fputc('"', w->fp);
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        switch (*p) {
        case '"': fputs("\\\"", w->fp); break;
        case '\\': fputs("\\\\", w->fp); break;
        case '\n': fputs("\\n", w->fp); break;
        case '\t': fputs("\\t", w->fp); break;
        case '\r': fputs("\\r", w->fp); break;
        default:
            if (*p < 0x20 || *p == 0x7F)
                fprintf(w->fp, "\\u{%x}", *p);
            else
                fputc(*p, w->fp);
        }
    }
    fputc('"', w->fp);
}

static void tb__ref(tb__w *w, const tb_mid_ref *r)
{
    fputs("file(", w->fp);
    tb__string(w, r->text);
    fputc(')', w->fp);
}

static void tb__dvec(tb__w *w, const double *v, int n)
{
    fputc('[', w->fp);
    for (int i = 0; i < n; i++) {
        if (i)
            fputc(' ', w->fp);
        tb__double(w, v[i]);
    }
    fputc(']', w->fp);
}

static void tb__fvec(tb__w *w, const float *v, int n)
{
    fputc('[', w->fp);
    for (int i = 0; i < n; i++) {
        if (i)
            fputc(' ', w->fp);
        tb__float(w, v[i]);
    }
    fputc(']', w->fp);
}

static void tb__d3(tb__w *w, tb_dvec3 v)
{
    double d[3] = {v.x, v.y, v.z};
    tb__dvec(w, d, 3);
}

static void tb__bool(tb__w *w, bool b) { fputs(b ? "true" : "false", w->fp); }

/* "name = " on a fresh line. */
static void tb__key(tb__w *w, int level, const char *name)
{
    tb__indent(w, level);
    fprintf(w->fp, "%s = ", name);
}

/* A whole "name = number" line. */
static void tb__line_double(tb__w *w, int level, const char *name, double x)
{
    tb__key(w, level, name);
    tb__double(w, x);
    fputc('\n', w->fp);
}

/* A whole "name = true|false" line. */
static void tb__line_bool(tb__w *w, int level, const char *name, bool b)
{
    tb__key(w, level, name);
    tb__bool(w, b);
    fputc('\n', w->fp);
}

/* ------------------------------------------------------------ generic values */

static void tb__attrs(tb__w *w, const tb_mid_attr *a, int n, int level);

static bool tb__value_is_big(const tb_mid_value *v)
{
    return v->type == TB_MID_LIST || v->type == TB_MID_VECTOR || v->type == TB_MID_BLOCK;
}

/* A value; blocks and lists of lists span lines indented at `level`. */
static void tb__value(tb__w *w, const tb_mid_value *v, int level)
{
    switch (v->type) {
    case TB_MID_NUMBER: tb__double(w, v->number); break;
    case TB_MID_STRING: tb__string(w, v->text); break;
    case TB_MID_SYMBOL: fputs(v->text, w->fp); break;
    case TB_MID_VECTOR: tb__dvec(w, v->numbers, v->count); break;
    case TB_MID_LIST: {
        bool lines = false;
        for (int i = 0; i < v->count && !lines; i++)
            lines = tb__value_is_big(&v->items[i]);
        fputc('[', w->fp);
        for (int i = 0; i < v->count; i++) {
            if (lines) {
                fputc('\n', w->fp);
                tb__indent(w, level + 1);
            } else if (i)
                fputc(' ', w->fp);
            tb__value(w, &v->items[i], level + 1);
        }
        if (lines) {
            fputc('\n', w->fp);
            tb__indent(w, level);
        }
        fputc(']', w->fp);
        break;
    }
    case TB_MID_CALL:
        fprintf(w->fp, "%s(", v->name);
        for (int i = 0; i < v->count; i++) {
            if (i)
                fputs(", ", w->fp);
            tb__value(w, &v->items[i], level);
        }
        fputc(')', w->fp);
        break;
    case TB_MID_BLOCK:
        if (v->count == 0) {
            fputs("{}", w->fp);
            break;
        }
        fputs("{\n", w->fp);
        tb__attrs(w, v->attrs, v->count, level + 1);
        tb__indent(w, level);
        fputc('}', w->fp);
        break;
    case TB_MID_FILE: tb__ref(w, &v->ref); break;
    }
}

static void tb__attrs(tb__w *w, const tb_mid_attr *a, int n, int level)
{
    for (int i = 0; i < n; i++) {
        tb__key(w, level, a[i].name);
        tb__value(w, &a[i].value, level);
        fputc('\n', w->fp);
    }
}

/* ---------------------------------------------------------------- typed parts */

static void tb__color(tb__w *w, const tb_mid_color *c)
{
    switch (c->type) {
    case TB_MID_COLOR_RGB:
        if (c->rgb[0] == c->rgb[1] && c->rgb[1] == c->rgb[2])
            tb__float(w, c->rgb[0]);
        else
            tb__fvec(w, c->rgb, 3);
        break;
    case TB_MID_COLOR_SPECTRUM:
        fputs("spectrum(", w->fp);
        tb__fvec(w, c->nm, c->nsamples);
        fputs(", ", w->fp);
        tb__fvec(w, c->values, c->nsamples);
        fputc(')', w->fp);
        break;
    case TB_MID_COLOR_SPECTRUM_FILE:
        fputs("spectrum(", w->fp);
        tb__ref(w, &c->file);
        fputc(')', w->fp);
        break;
    }
}

static void tb__ops(tb__w *w, const tb_mid_op *ops, int n, int level)
{
    if (n == 0)
        return;
    tb__key(w, level, "transform");
    fputc('[', w->fp);
    for (int i = 0; i < n; i++) {
        const double *v = ops[i].v;
        if (i)
            fputc(' ', w->fp);
        switch (ops[i].kind) {
        case TB_MID_TRANSLATE:
            fputs("translate(", w->fp);
            tb__dvec(w, v, 3);
            break;
        case TB_MID_SCALE:
            fputs("scale(", w->fp);
            if (v[0] == v[1] && v[1] == v[2])
                tb__double(w, v[0]);
            else
                tb__dvec(w, v, 3);
            break;
        case TB_MID_ROTATE:
            fputs("rotate(", w->fp);
            tb__dvec(w, v, 3);
            fputs(", ", w->fp);
            tb__double(w, v[3]);
            break;
        case TB_MID_MATRIX:
            fputs("matrix(", w->fp);
            tb__dvec(w, v, 16);
            break;
        default: tb__bad(w, "unknown transform operation"); fputs("matrix(", w->fp); break;
        }
        fputc(')', w->fp);
    }
    fputs("]\n", w->fp);
}

/* A pattern's scale: one number, or [su sv] when they differ. */
static void tb__pattern_scale(tb__w *w, const tb_mid_pattern *p)
{
    if (p->scale_v == p->scale) {
        tb__double(w, p->scale);
        return;
    }
    const double s[2] = {p->scale, p->scale_v};
    tb__dvec(w, s, 2);
}

/* A pattern or bump map (docs/mid.md, 7.2): the space only when not uv. */
static void tb__pattern(tb__w *w, const tb_mid_pattern *p)
{
    switch (p->kind) {
    case TB_MID_PATTERN_CHECKER:
        fputs("checker(", w->fp);
        tb__pattern_scale(w, p);
        fputs(", ", w->fp);
        tb__color(w, &p->a);
        fputs(", ", w->fp);
        tb__color(w, &p->b);
        break;
    case TB_MID_PATTERN_NOISE:
        fputs("noise(", w->fp);
        tb__pattern_scale(w, p);
        fprintf(w->fp, ", %d, ", p->octaves);
        if (w->bump) {
            tb__double(w, p->height); /* a bump map has a height, a colour pattern two colours */
        } else {
            tb__color(w, &p->a);
            fputs(", ", w->fp);
            tb__color(w, &p->b);
        }
        break;
    case TB_MID_PATTERN_IMAGE:
        fputs("image(", w->fp);
        if (p->image.text)
            tb__ref(w, &p->image);
        else
            tb__bad(w, "an image bump without a file");
        fputs(", ", w->fp);
        tb__double(w, p->height);
        fputc(')', w->fp);
        return;
    default: tb__bad(w, "a pattern bit is set without a pattern"); return;
    }
    if (p->object_space)
        fputs(", object", w->fp);
    fputc(')', w->fp);
}

/* The attributes of a rendering block or material body, at `level`. */
static void tb__material_body(tb__w *w, const tb_mid_material *m, int level)
{
    if (m->base) {
        tb__key(w, level, "material");
        tb__string(w, m->base);
        fputc('\n', w->fp);
    }
    struct {
        unsigned bit;
        const char *name;
        const tb_mid_color *color;
        const float *number;
        const tb_mid_ref *ref;
    } fields[] = {
        {TB_MID_SET_DIFFUSE, "diffuse", &m->diffuse, NULL, NULL},
        {TB_MID_SET_SPECULAR, "specular", &m->specular, NULL, NULL},
        {TB_MID_SET_EXPONENT, "exponent", NULL, &m->exponent, NULL},
        {TB_MID_SET_TRANSMISSION, "transmission", &m->transmission, NULL, NULL},
        {TB_MID_SET_IOR, "ior", NULL, &m->ior, NULL},
        {TB_MID_SET_EMISSION, "emission", &m->emission, NULL, NULL},
        {TB_MID_SET_DIFFUSE_TEXTURE, "diffuse_texture", NULL, NULL, &m->diffuse_texture},
        {TB_MID_SET_SPECULAR_TEXTURE, "specular_texture", NULL, NULL, &m->specular_texture},
        {TB_MID_SET_TRANSMISSION_TEXTURE, "transmission_texture", NULL, NULL, &m->transmission_texture},
        {TB_MID_SET_EMISSION_TEXTURE, "emission_texture", NULL, NULL, &m->emission_texture},
    };
    for (size_t i = 0; i < sizeof fields / sizeof fields[0]; i++) {
        if (!(m->set & fields[i].bit))
            continue;
        tb__key(w, level, fields[i].name);
        if (fields[i].color)
            tb__color(w, fields[i].color);
        else if (fields[i].number)
            tb__float(w, *fields[i].number);
        else if (fields[i].ref->text)
            tb__ref(w, fields[i].ref);
        else
            tb__bad(w, "a texture bit is set without a file");
        fputc('\n', w->fp);
    }
    /* MID 1.1 */
    if (m->set & TB_MID_SET_MODEL) {
        tb__key(w, level, "model");
        fprintf(w->fp, "%s\n", tb_mid_model_name(m->model));
    }
    if (m->set & TB_MID_SET_ROUGHNESS) {
        tb__key(w, level, "roughness");
        tb__float(w, m->roughness);
        fputc('\n', w->fp);
    }
    const struct {
        unsigned bit;
        const char *name;
        const tb_mid_pattern *p;
    } pats[] = {
        {TB_MID_SET_DIFFUSE_PATTERN, "diffuse_pattern", &m->diffuse_pattern},
        {TB_MID_SET_SPECULAR_PATTERN, "specular_pattern", &m->specular_pattern},
        {TB_MID_SET_BUMP, "bump", &m->bump},
    };
    for (size_t i = 0; i < sizeof pats / sizeof pats[0]; i++) {
        if (!(m->set & pats[i].bit))
            continue;
        tb__key(w, level, pats[i].name);
        w->bump = pats[i].bit == TB_MID_SET_BUMP;
        tb__pattern(w, pats[i].p);
        w->bump = false;
        fputc('\n', w->fp);
    }
    tb__attrs(w, m->extra.items, m->extra.count, level);
}

/* A list of float n-vectors, one per line. */
static void tb__vec_lines(tb__w *w, const char *name, const float *v, int count, int n, int level)
{
    tb__key(w, level, name);
    fputc('[', w->fp);
    for (int i = 0; i < count; i++) {
        fputc('\n', w->fp);
        tb__indent(w, level + 1);
        tb__fvec(w, v + (size_t)i * (size_t)n, n);
    }
    fputc('\n', w->fp);
    tb__indent(w, level);
    fputs("]\n", w->fp);
}

static void tb__geometry(tb__w *w, const tb_mid_object *o, int level)
{
    const tb_mid_geometry *g = &o->geom;
    bool params = !(o->kind == TB_PRIM_SPHERE || o->kind == TB_PRIM_CUBE || tb_prim_is_csg(o->kind));
    if (!params && o->geometry_extra.count == 0)
        return;
    tb__key(w, level, "geometry");
    fputs("{\n", w->fp);
    int l = level + 1;
    switch (o->kind) {
    case TB_PRIM_CYLINDER:
        tb__line_bool(w, l, "caps", g->cylinder.caps);
        break;
    case TB_PRIM_CONE:
        tb__line_double(w, l, "top_radius", g->cone.top_radius);
        tb__line_bool(w, l, "caps", g->cone.caps);
        break;
    case TB_PRIM_PYRAMID:
        tb__line_double(w, l, "top", g->pyramid.top);
        tb__line_bool(w, l, "caps", g->pyramid.caps);
        break;
    case TB_PRIM_PRISM:
        if (g->prism.nprofile > 0)
            tb__vec_lines(w, "profile", (const float *)g->prism.profile, g->prism.nprofile, 2, l);
        else {
            tb__key(w, l, "sides");
            fprintf(w->fp, "%d\n", g->prism.sides);
        }
        tb__line_bool(w, l, "caps", g->prism.caps);
        break;
    case TB_PRIM_TORUS:
        tb__line_double(w, l, "major", g->torus.major);
        tb__line_double(w, l, "minor", g->torus.minor);
        break;
    case TB_PRIM_POLYGONS: {
        const tb_geom_polygons *p = &g->polygons;
        if (p->mesh.text) {
            tb__key(w, l, "mesh");
            tb__ref(w, &p->mesh);
            fputc('\n', w->fp);
            break;
        }
        tb__vec_lines(w, "vertices", (const float *)p->vertices, p->nvertices, 3, l);
        tb__key(w, l, "faces");
        fputc('[', w->fp);
        for (int f = 0; f < p->nfaces; f++) {
            fputc('\n', w->fp);
            tb__indent(w, l + 1);
            fputc('[', w->fp);
            for (int i = p->face_start[f]; i < p->face_start[f + 1]; i++)
                fprintf(w->fp, i > p->face_start[f] ? " %d" : "%d", p->indices[i]);
            fputc(']', w->fp);
        }
        fputc('\n', w->fp);
        tb__indent(w, l);
        fputs("]\n", w->fp);
        if (p->normals)
            tb__vec_lines(w, "normals", (const float *)p->normals, p->nvertices, 3, l);
        if (p->uvs)
            tb__vec_lines(w, "uvs", (const float *)p->uvs, p->nvertices, 2, l);
        break;
    }
    case TB_PRIM_CONIC: {
        tb__key(w, l, "coefficients");
        tb__dvec(w, g->conic.c, 3);
        fputc('\n', w->fp);
        double z[2] = {g->conic.z0, g->conic.z1};
        tb__key(w, l, "z_range");
        tb__dvec(w, z, 2);
        fputc('\n', w->fp);
        tb__line_bool(w, l, "caps", g->conic.caps);
        break;
    }
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH:
        tb__line_double(w, l, "width", g->arch.width);
        tb__line_double(w, l, "height", g->arch.height);
        break;
    default: break;
    }
    tb__attrs(w, o->geometry_extra.items, o->geometry_extra.count, l);
    tb__indent(w, level);
    fputs("}\n", w->fp);
}

/* "keyword "name" {" */
static void tb__open(tb__w *w, int level, const char *keyword, const char *name)
{
    tb__indent(w, level);
    fputs(keyword, w->fp);
    if (name) {
        fputc(' ', w->fp);
        tb__string(w, name);
    }
    fputs(" {\n", w->fp);
}

static void tb__close(tb__w *w, int level)
{
    tb__indent(w, level);
    fputs("}\n", w->fp);
}

static void tb__object(tb__w *w, const tb_mid_object *o, int level, int depth)
{
    if ((int)o->kind < 0 || (int)o->kind >= TB_PRIM_COUNT) {
        tb__bad(w, "unknown primitive kind");
        return;
    }
    if (depth > TB_MID_MAX_DEPTH) {
        tb__bad(w, "CSG nesting deeper than the format allows");
        return;
    }
    if (tb_prim_is_csg(o->kind) && o->nchildren < (o->kind == TB_PRIM_DIFFERENCE ? 2 : 1))
        tb__bad(w, "a CSG node has too few children");
    tb__open(w, level, tb_prim_kind_name(o->kind), o->name);
    int l = level + 1;
    tb__ops(w, o->ops, o->nops, l);
    tb__geometry(w, o, l);
    const tb_mid_material *m = &o->material;
    if (m->base || m->set || m->extra.count) {
        tb__key(w, l, "rendering");
        fputs("{\n", w->fp);
        tb__material_body(w, m, l + 1);
        tb__close(w, l);
    }
    tb__attrs(w, o->extra.items, o->extra.count, l);
    for (int i = 0; i < o->nchildren; i++)
        tb__object(w, &o->children[i], l, depth + 1);
    tb__close(w, level);
}

static void tb__light(tb__w *w, const tb_mid_light *li)
{
    tb__open(w, 0, tb_light_kind_name(li->kind), li->name);
    tb__ops(w, li->ops, li->nops, 1);
    if (li->kind != TB_LIGHT_DIRECTIONAL) {
        tb__key(w, 1, "position");
        tb__d3(w, li->position);
        fputc('\n', w->fp);
    }
    if (li->kind != TB_LIGHT_POINT) {
        tb__key(w, 1, "direction");
        tb__d3(w, li->direction);
        fputc('\n', w->fp);
    }
    tb__key(w, 1, li->kind == TB_LIGHT_DIRECTIONAL ? "irradiance" : "intensity");
    tb__color(w, &li->intensity);
    fputc('\n', w->fp);
    if (li->kind == TB_LIGHT_SPOT) {
        tb__line_double(w, 1, "cone_angle", li->cone_angle);
        tb__line_double(w, 1, "cone_delta", li->cone_delta);
    }
    if (li->kind != TB_LIGHT_DIRECTIONAL && li->ies.text) {
        tb__key(w, 1, "ies");
        tb__ref(w, &li->ies);
        fputc('\n', w->fp);
    }
    tb__attrs(w, li->extra.items, li->extra.count, 1);
    tb__close(w, 0);
}

static void tb__camera(tb__w *w, const tb_mid_camera *c)
{
    tb__open(w, 0, "camera", c->name);
    tb__key(w, 1, "eye");
    tb__d3(w, c->eye);
    fputc('\n', w->fp);
    tb__key(w, 1, "look_at");
    tb__d3(w, c->look_at);
    fputc('\n', w->fp);
    tb__key(w, 1, "up");
    tb__d3(w, c->up);
    fputc('\n', w->fp);
    if (c->focal_length > 0.0) {
        tb__key(w, 1, "focal_length");
        tb__double(w, c->focal_length);
    } else {
        tb__key(w, 1, "fov");
        tb__double(w, c->fov);
    }
    fputc('\n', w->fp);
    tb__key(w, 1, "film");
    tb__dvec(w, c->film, 2);
    fputc('\n', w->fp);
    tb__key(w, 1, "resolution");
    fprintf(w->fp, "[%d %d]\n", c->width, c->height);
    tb__line_double(w, 1, "aperture", c->aperture);
    tb__line_double(w, 1, "focus_distance", c->focus_distance);
    tb__attrs(w, c->extra.items, c->extra.count, 1);
    tb__close(w, 0);
}

static tb_status tb__finish(tb__w *w)
{
    if (w->st)
        return w->st;
    if (ferror(w->fp))
        return tb_error(TB_ERR_IO, "MID writer: write error");
    return TB_OK;
}

tb_status tb_mid_write_header(FILE *fp)
{
    fprintf(fp, "mid %d.%d\n", TB_MID_VERSION_MAJOR, TB_MID_VERSION_MINOR);
    return ferror(fp) ? tb_error(TB_ERR_IO, "MID writer: write error") : TB_OK;
}

static tb_status tb__write_item(FILE *fp, const tb_mid_item *item);

tb_status tb_mid_write_item(FILE *fp, const tb_mid_item *item)
{
    /* Numbers are written (and checked with strtod) in the "C" locale: a
     * MID file always has '.' as the decimal point. */
    locale_t c = tb__mid_c_locale(), old = c ? uselocale(c) : (locale_t)0;
    tb_status st = tb__write_item(fp, item);
    if (c)
        uselocale(old);
    return st;
}

static tb_status tb__write_item(FILE *fp, const tb_mid_item *item)
{
    tb__w w = {fp, TB_OK, false};
    switch (item->type) {
    case TB_MID_ITEM_OBJECT: tb__object(&w, item->object, 0, 1); break;
    case TB_MID_ITEM_MATERIAL:
        if (!item->material->name) {
            tb__bad(&w, "a material definition needs a name");
            break;
        }
        tb__open(&w, 0, "material", item->material->name);
        tb__material_body(&w, item->material, 1);
        tb__close(&w, 0);
        break;
    case TB_MID_ITEM_LIGHT: tb__light(&w, item->light); break;
    case TB_MID_ITEM_CAMERA: tb__camera(&w, item->camera); break;
    case TB_MID_ITEM_END: break;
    default: tb__bad(&w, "unknown item type"); break;
    }
    return tb__finish(&w);
}
