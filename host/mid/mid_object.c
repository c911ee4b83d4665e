/* The MID object model: names, defaults, transform composition, equality. */
#include "host/mid/mid.h"

#include <math.h>
#include <pthread.h>
#include <string.h>

#include "host/mid/mid_internal.h"

static const char *const tb__keywords[TB__K_COUNT] = {
    [TB_PRIM_SPHERE] = "sphere",
    [TB_PRIM_CUBE] = "cube",
    [TB_PRIM_CYLINDER] = "cylinder",
    [TB_PRIM_CONE] = "cone",
    [TB_PRIM_PYRAMID] = "pyramid",
    [TB_PRIM_PRISM] = "prism",
    [TB_PRIM_TORUS] = "torus",
    [TB_PRIM_POLYGONS] = "polygons",
    [TB_PRIM_CONIC] = "conic",
    [TB_PRIM_SQUARE_ARCH] = "square_arch",
    [TB_PRIM_ROUND_ARCH] = "round_arch",
    [TB_PRIM_UNION] = "union",
    [TB_PRIM_INTERSECTION] = "intersection",
    [TB_PRIM_DIFFERENCE] = "difference",
    [TB__K_MATERIAL] = "material",
    [TB__K_POINT_LIGHT] = "point_light",
    [TB__K_SPOT_LIGHT] = "spot_light",
    [TB__K_DIRECTIONAL_LIGHT] = "directional_light",
    [TB__K_CAMERA] = "camera",
};

static locale_t tb__c_locale;
static pthread_once_t tb__c_locale_once = PTHREAD_ONCE_INIT;

static void tb__c_locale_make(void) { tb__c_locale = newlocale(LC_NUMERIC_MASK, "C", (locale_t)0); }

locale_t tb__mid_c_locale(void)
{
    pthread_once(&tb__c_locale_once, tb__c_locale_make);
    return tb__c_locale;
}

int tb__mid_keyword(const char *name)
{
    for (int k = 0; k < TB__K_COUNT; k++)
        if (strcmp(name, tb__keywords[k]) == 0)
            return k;
    return -1;
}

int tb__mid_keyword_n(const char *s, size_t n)
{
    for (int k = 0; k < TB__K_COUNT; k++)
        if (n > 0 && tb__keywords[k][0] == s[0] && strncmp(s, tb__keywords[k], n) == 0 &&
            tb__keywords[k][n] == '\0')
            return k;
    return -1;
}

const char *tb__mid_keyword_name(int k) { return k >= 0 && k < TB__K_COUNT ? tb__keywords[k] : "?"; }

const char *tb_prim_kind_name(tb_prim_kind k)
{
    return (int)k >= 0 && (int)k < TB_PRIM_COUNT ? tb__keywords[k] : "?";
}

const char *tb_light_kind_name(tb_light_kind k)
{
    switch (k) {
    case TB_LIGHT_POINT: return "point_light";
    case TB_LIGHT_SPOT: return "spot_light";
    case TB_LIGHT_DIRECTIONAL: return "directional_light";
    }
    return "?";
}

/* ------------------------------------------------------------------ defaults */

tb_mid_geometry tb_mid_geometry_default(tb_prim_kind k)
{
    tb_mid_geometry g;
    memset(&g, 0, sizeof g);
    switch (k) {
    case TB_PRIM_CYLINDER: g.cylinder.caps = true; break;
    case TB_PRIM_CONE: g.cone = (tb_geom_cone){0.0, true}; break;
    case TB_PRIM_PYRAMID: g.pyramid = (tb_geom_pyramid){0.0, true}; break;
    case TB_PRIM_PRISM: g.prism = (tb_geom_prism){3, 0, NULL, true}; break;
    case TB_PRIM_TORUS: g.torus = (tb_geom_torus){1.0, 0.25}; break;
    case TB_PRIM_CONIC: g.conic = (tb_geom_conic){{1.0, 0.0, -1.0}, -1.0, 1.0, true}; break;
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH: g.arch = (tb_geom_arch){1.0, 1.5}; break;
    default: break;
    }
    return g;
}

tb_mid_color tb_mid_color_grey(float v)
{
    tb_mid_color c;
    memset(&c, 0, sizeof c);
    c.type = TB_MID_COLOR_RGB;
    c.rgb[0] = c.rgb[1] = c.rgb[2] = v;
    return c;
}

const tb_mid_material tb__mid_default_material = {
    .diffuse = {.type = TB_MID_COLOR_RGB, .rgb = {0.5f, 0.5f, 0.5f}},
    .specular = {.type = TB_MID_COLOR_RGB},
    .transmission = {.type = TB_MID_COLOR_RGB},
    .emission = {.type = TB_MID_COLOR_RGB},
    .exponent = 20.0f,
    .ior = 1.0f,
    .model = TB_MID_MODEL_PHONG,
    .roughness = 0.2f,
};

const char *tb_mid_model_name(tb_mid_model m)
{
    static const char *const names[TB_MID_MODEL_COUNT] = {"phong", "blinn", "lambert", "ggx"};
    return (unsigned)m < TB_MID_MODEL_COUNT ? names[m] : "?";
}

const tb_transform tb__mid_identity = {
    {{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}},
    {{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}},
};

tb_mid_material tb_mid_material_default(void) { return tb__mid_default_material; }

bool tb_mid_material_emits(const tb_mid_material *m)
{
    const tb_mid_color *e = &m->emission;
    switch (e->type) {
    case TB_MID_COLOR_RGB: return e->rgb[0] > 0.0f || e->rgb[1] > 0.0f || e->rgb[2] > 0.0f;
    case TB_MID_COLOR_SPECTRUM:
        for (int i = 0; i < e->nsamples; i++)
            if (e->values[i] > 0.0f)
                return true;
        return false;
    case TB_MID_COLOR_SPECTRUM_FILE: return true;
    }
    return false;
}

tb_mid_light tb_mid_light_default(tb_light_kind k)
{
    tb_mid_light l;
    memset(&l, 0, sizeof l);
    l.kind = k;
    l.to_world = tb_transform_identity();
    l.position = (tb_dvec3){0.0, 0.0, 0.0};
    l.direction = (tb_dvec3){0.0, 0.0, -1.0};
    l.intensity = tb_mid_color_grey(1.0f);
    l.cone_angle = 30.0;
    l.cone_delta = 5.0;
    return l;
}

tb_mid_camera tb_mid_camera_default(void)
{
    tb_mid_camera c;
    memset(&c, 0, sizeof c);
    c.eye = (tb_dvec3){0.0, 0.0, 0.0};
    c.look_at = (tb_dvec3){0.0, 0.0, -1.0};
    c.up = (tb_dvec3){0.0, 1.0, 0.0};
    c.fov = 45.0;
    c.focal_length = 0.0;
    c.film[0] = 36.0;
    c.film[1] = 24.0;
    c.width = c.height = 512;
    c.aperture = 0.0;
    c.focus_distance = 1.0;
    return c;
}

double tb_mid_camera_fov(double f, const double film[2], int res_w, int res_h)
{
    /* The largest centred part of the film with the image's aspect ratio. */
    double h = fmin(film[1], film[0] * (double)res_h / (double)res_w);
    return 2.0 * atan(h / (2.0 * f)) * (180.0 / 3.14159265358979323846);
}

/* ---------------------------------------------------------------- transforms */

/* True if every entry of t and its inverse is finite (x - x is 0 for a
 * finite x and NaN for an infinite or NaN one). */
static bool tb__transform_finite(const tb_transform *t)
{
    double s = 0.0;
    for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++)
            s += (t->m.m[r][c] - t->m.m[r][c]) + (t->inv.m[r][c] - t->inv.m[r][c]);
    return s == 0.0;
}

tb_status tb_mid_ops_transform(const tb_mid_op *ops, int n, tb_transform *out, int *bad)
{
    tb_transform total = tb__mid_identity;
    for (int i = 0; i < n; i++) {
        const double *v = ops[i].v;
        tb_transform t;
        tb_status st = TB_OK;
        switch (ops[i].kind) {
        case TB_MID_TRANSLATE: t = tb_transform_translate((tb_dvec3){v[0], v[1], v[2]}); break;
        case TB_MID_SCALE: st = tb_transform_scale((tb_dvec3){v[0], v[1], v[2]}, &t); break;
        case TB_MID_ROTATE: st = tb_transform_rotate_deg(v[3], (tb_dvec3){v[0], v[1], v[2]}, &t); break;
        case TB_MID_MATRIX: {
            tb_mat4 m = tb_mat4_from_rows(v);
            if (!tb_mat4_is_affine(&m))
                st = tb_error(TB_ERR_ARG, "matrix is not affine (last row must be 0 0 0 1)");
            else
                st = tb_transform_from_matrix(&m, &t);
            break;
        }
        default: st = tb_error(TB_ERR_ARG, "unknown transform operation %d", (int)ops[i].kind); break;
        }
        if (st) {
            if (bad)
                *bad = i;
            return st;
        }
        /* ops[i] after the ones before (the first needs no product: I * t = t exactly). */
        total = i == 0 ? t : tb_transform_compose(&t, &total);
    }
    /* One operation is finite by construction; a product may overflow. */
    if (n > 1 && !tb__transform_finite(&total)) {
        if (bad)
            *bad = n;
        return tb_error(TB_ERR_NUMERIC, "the composed transform overflows");
    }
    *out = total;
    return TB_OK;
}

/* ----------------------------------------------------------------- equality */

static bool tb__str_eq(const char *a, const char *b)
{
    if (!a || !b)
        return a == b;
    return strcmp(a, b) == 0;
}

static bool tb__ref_eq(const tb_mid_ref *a, const tb_mid_ref *b)
{
    return tb__str_eq(a->text, b->text) && (!a->text || tb__str_eq(a->path, b->path));
}

static bool tb__attrs_eq(const tb_mid_attr *a, int na, const tb_mid_attr *b, int nb)
{
    if (na != nb)
        return false;
    for (int i = 0; i < na; i++)
        if (!tb__str_eq(a[i].name, b[i].name) || !tb_mid_value_equal(&a[i].value, &b[i].value))
            return false;
    return true;
}

bool tb_mid_value_equal(const tb_mid_value *a, const tb_mid_value *b)
{
    if (a->type != b->type || (a->type != TB_MID_NUMBER && a->type != TB_MID_STRING &&
                               a->type != TB_MID_SYMBOL && a->type != TB_MID_FILE && a->count != b->count))
        return false;
    switch (a->type) {
    case TB_MID_NUMBER: return a->number == b->number;
    case TB_MID_STRING:
    case TB_MID_SYMBOL: return tb__str_eq(a->text, b->text);
    case TB_MID_VECTOR:
        for (int i = 0; i < a->count; i++)
            if (a->numbers[i] != b->numbers[i])
                return false;
        return true;
    case TB_MID_CALL:
        if (!tb__str_eq(a->name, b->name))
            return false;
        /* fall through */
    case TB_MID_LIST:
        for (int i = 0; i < a->count; i++)
            if (!tb_mid_value_equal(&a->items[i], &b->items[i]))
                return false;
        return true;
    case TB_MID_BLOCK: return tb__attrs_eq(a->attrs, a->count, b->attrs, b->count);
    case TB_MID_FILE: return tb__ref_eq(&a->ref, &b->ref);
    }
    return false;
}

static bool tb__xattrs_eq(const tb_mid_attrs *a, const tb_mid_attrs *b)
{
    return tb__attrs_eq(a->items, a->count, b->items, b->count);
}

static bool tb__refs_eq(const tb_mid_ref *a, int na, const tb_mid_ref *b, int nb)
{
    if (na != nb)
        return false;
    for (int i = 0; i < na; i++)
        if (!tb__ref_eq(&a[i], &b[i]))
            return false;
    return true;
}

static bool tb__color_eq(const tb_mid_color *a, const tb_mid_color *b)
{
    if (a->type != b->type)
        return false;
    switch (a->type) {
    case TB_MID_COLOR_RGB: return a->rgb[0] == b->rgb[0] && a->rgb[1] == b->rgb[1] && a->rgb[2] == b->rgb[2];
    case TB_MID_COLOR_SPECTRUM:
        if (a->nsamples != b->nsamples)
            return false;
        for (int i = 0; i < a->nsamples; i++)
            if (a->nm[i] != b->nm[i] || a->values[i] != b->values[i])
                return false;
        return true;
    case TB_MID_COLOR_SPECTRUM_FILE: return tb__ref_eq(&a->file, &b->file);
    }
    return false;
}

/* Patterns compare the fields their kind uses. */
static bool tb__pattern_eq(const tb_mid_pattern *a, const tb_mid_pattern *b)
{
    if (a->kind != b->kind)
        return false;
    switch (a->kind) {
    case TB_MID_PATTERN_NONE: return true;
    case TB_MID_PATTERN_CHECKER:
    case TB_MID_PATTERN_NOISE:
        if (a->object_space != b->object_space || a->scale != b->scale || a->scale_v != b->scale_v)
            return false;
        if (a->kind == TB_MID_PATTERN_NOISE && a->octaves != b->octaves)
            return false;
        /* colour patterns carry colours, noise bumps a height */
        if (a->kind == TB_MID_PATTERN_NOISE && a->height != b->height)
            return false;
        return tb__color_eq(&a->a, &b->a) && tb__color_eq(&a->b, &b->b);
    case TB_MID_PATTERN_IMAGE: return a->height == b->height && tb__ref_eq(&a->image, &b->image);
    }
    return false;
}

static bool tb__material_eq(const tb_mid_material *a, const tb_mid_material *b)
{
    if (a->model != b->model || a->roughness != b->roughness || !tb__pattern_eq(&a->diffuse_pattern, &b->diffuse_pattern) ||
        !tb__pattern_eq(&a->specular_pattern, &b->specular_pattern) || !tb__pattern_eq(&a->bump, &b->bump))
        return false;
    return tb__str_eq(a->name, b->name) && tb__str_eq(a->base, b->base) && a->set == b->set &&
           tb__color_eq(&a->diffuse, &b->diffuse) && tb__color_eq(&a->specular, &b->specular) &&
           tb__color_eq(&a->transmission, &b->transmission) && tb__color_eq(&a->emission, &b->emission) &&
           a->exponent == b->exponent && a->ior == b->ior &&
           tb__ref_eq(&a->diffuse_texture, &b->diffuse_texture) &&
           tb__ref_eq(&a->specular_texture, &b->specular_texture) &&
           tb__ref_eq(&a->transmission_texture, &b->transmission_texture) &&
           tb__ref_eq(&a->emission_texture, &b->emission_texture) && tb__xattrs_eq(&a->extra, &b->extra) &&
           tb__refs_eq(a->refs, a->nrefs, b->refs, b->nrefs);
}

static bool tb__ops_eq(const tb_mid_op *a, int na, const tb_mid_op *b, int nb)
{
    if (na != nb)
        return false;
    for (int i = 0; i < na; i++) {
        if (a[i].kind != b[i].kind)
            return false;
        int n = a[i].kind == TB_MID_MATRIX ? 16 : a[i].kind == TB_MID_ROTATE ? 4 : 3;
        for (int j = 0; j < n; j++)
            if (a[i].v[j] != b[i].v[j])
                return false;
    }
    return true;
}

static bool tb__transform_eq(const tb_transform *a, const tb_transform *b)
{
    return tb_mat4_equal(&a->m, &b->m) && tb_mat4_equal(&a->inv, &b->inv);
}

static bool tb__geom_eq(tb_prim_kind k, const tb_mid_geometry *a, const tb_mid_geometry *b)
{
    switch (k) {
    case TB_PRIM_CYLINDER: return a->cylinder.caps == b->cylinder.caps;
    case TB_PRIM_CONE: return a->cone.top_radius == b->cone.top_radius && a->cone.caps == b->cone.caps;
    case TB_PRIM_PYRAMID: return a->pyramid.top == b->pyramid.top && a->pyramid.caps == b->pyramid.caps;
    case TB_PRIM_PRISM: {
        const tb_geom_prism *p = &a->prism, *q = &b->prism;
        if (p->sides != q->sides || p->nprofile != q->nprofile || p->caps != q->caps)
            return false;
        for (int i = 0; i < p->nprofile; i++)
            if (p->profile[i].x != q->profile[i].x || p->profile[i].y != q->profile[i].y)
                return false;
        return true;
    }
    case TB_PRIM_TORUS: return a->torus.major == b->torus.major && a->torus.minor == b->torus.minor;
    case TB_PRIM_POLYGONS: {
        const tb_geom_polygons *p = &a->polygons, *q = &b->polygons;
        if (!tb__ref_eq(&p->mesh, &q->mesh) || p->nvertices != q->nvertices || p->nfaces != q->nfaces ||
            !p->normals != !q->normals || !p->uvs != !q->uvs)
            return false;
        for (int i = 0; i < p->nvertices; i++) {
            if (!tb_vec3_equal(p->vertices[i], q->vertices[i]))
                return false;
            if (p->normals && !tb_vec3_equal(p->normals[i], q->normals[i]))
                return false;
            if (p->uvs && (p->uvs[i].x != q->uvs[i].x || p->uvs[i].y != q->uvs[i].y))
                return false;
        }
        if (p->nfaces == 0)
            return true;
        for (int f = 0; f <= p->nfaces; f++)
            if (p->face_start[f] != q->face_start[f])
                return false;
        for (int i = 0; i < p->face_start[p->nfaces]; i++)
            if (p->indices[i] != q->indices[i])
                return false;
        return true;
    }
    case TB_PRIM_CONIC:
        return a->conic.c[0] == b->conic.c[0] && a->conic.c[1] == b->conic.c[1] &&
               a->conic.c[2] == b->conic.c[2] && a->conic.z0 == b->conic.z0 && a->conic.z1 == b->conic.z1 &&
               a->conic.caps == b->conic.caps;
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH: return a->arch.width == b->arch.width && a->arch.height == b->arch.height;
    default: return true; /* no parameters */
    }
}

static bool tb__object_eq(const tb_mid_object *a, const tb_mid_object *b)
{
    if (a->kind != b->kind || !tb__str_eq(a->name, b->name) || !tb__ops_eq(a->ops, a->nops, b->ops, b->nops) ||
        !tb__transform_eq(&a->to_world, &b->to_world) || !tb__geom_eq(a->kind, &a->geom, &b->geom) ||
        !tb__xattrs_eq(&a->geometry_extra, &b->geometry_extra) || !tb__material_eq(&a->material, &b->material) ||
        !tb__xattrs_eq(&a->extra, &b->extra) || !tb__refs_eq(a->refs, a->nrefs, b->refs, b->nrefs) ||
        a->nchildren != b->nchildren)
        return false;
    for (int i = 0; i < a->nchildren; i++)
        if (!tb__object_eq(&a->children[i], &b->children[i]))
            return false;
    return true;
}

static bool tb__dvec3_eq(tb_dvec3 a, tb_dvec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

static bool tb__light_eq(const tb_mid_light *a, const tb_mid_light *b)
{
    return a->kind == b->kind && tb__str_eq(a->name, b->name) && tb__ops_eq(a->ops, a->nops, b->ops, b->nops) &&
           tb__transform_eq(&a->to_world, &b->to_world) && tb__dvec3_eq(a->position, b->position) &&
           tb__dvec3_eq(a->direction, b->direction) && tb__color_eq(&a->intensity, &b->intensity) &&
           a->cone_angle == b->cone_angle && a->cone_delta == b->cone_delta && tb__ref_eq(&a->ies, &b->ies) &&
           tb__xattrs_eq(&a->extra, &b->extra) && tb__refs_eq(a->refs, a->nrefs, b->refs, b->nrefs);
}

static bool tb__camera_eq(const tb_mid_camera *a, const tb_mid_camera *b)
{
    return tb__str_eq(a->name, b->name) && tb__dvec3_eq(a->eye, b->eye) && tb__dvec3_eq(a->look_at, b->look_at) &&
           tb__dvec3_eq(a->up, b->up) && a->fov == b->fov && a->focal_length == b->focal_length &&
           a->film[0] == b->film[0] && a->film[1] == b->film[1] && a->width == b->width &&
           a->height == b->height && a->aperture == b->aperture && a->focus_distance == b->focus_distance &&
           tb__xattrs_eq(&a->extra, &b->extra) && tb__refs_eq(a->refs, a->nrefs, b->refs, b->nrefs);
}

bool tb_mid_item_equal(const tb_mid_item *a, const tb_mid_item *b)
{
    if (a->type != b->type)
        return false;
    switch (a->type) {
    case TB_MID_ITEM_END: return true;
    case TB_MID_ITEM_OBJECT: return tb__object_eq(a->object, b->object);
    case TB_MID_ITEM_MATERIAL: return tb__material_eq(a->material, b->material);
    case TB_MID_ITEM_LIGHT: return tb__light_eq(a->light, b->light);
    case TB_MID_ITEM_CAMERA: return tb__camera_eq(a->camera, b->camera);
    }
    return false;
}
