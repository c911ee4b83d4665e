/* The persistent object: a deep copy of a streamed MID object, checked and
 * prepared once for intersection (docs/primitives.md). */
#include "host/object/object.h"
#include "util/base/str.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "host/object/intersect_internal.h"
#include "util/math/float.h"
#include "util/math/mat.h"
#include "util/mesh/fed.h"
#include "util/mesh/predicates.h"
#include "util/stats/stats.h"

TB_STAT_COUNTER(tb__n_fed_reads, "Object/FED files read");
TB_STAT_COUNTER(tb__n_fed_shared, "Object/FED references shared");

/* Largest regular prism tested edge by edge; above it the sector test is used. */
#define TB__PRISM_PROFILE_MAX 64

/* ------------------------------------------------------------------ helpers */

/* A copy of n elements of `size` bytes (NULL for n == 0 or src == NULL); *ok
 * is cleared when the allocation fails. */
static void *tb__dup(const void *src, size_t n, size_t size, bool *ok)
{
    if (!src || n == 0)
        return NULL;
    void *d = malloc(n * size);
    if (!d) {
        *ok = false;
        return NULL;
    }
    memcpy(d, src, n * size);
    return d;
}

static bool tb__finite(double v) { return isfinite(v); }

/* Transform check: finite, affine, and a linear part that tb_mat3_inverse
 * accepts (not singular, rcond >= TB_MAT_RCOND_MIN). The MID reader already
 * refuses such transforms; objects built by hand get the same check. */
static tb_status tb__check_transform(const tb_transform *t)
{
    if (!tb_mat4_isfinite(&t->m) || !tb_mat4_isfinite(&t->inv))
        return tb_error(TB_ERR_ARG, "object transform has a NaN or infinite entry");
    if (!tb_mat4_is_affine(&t->m) || !tb_mat4_is_affine(&t->inv))
        return tb_error(TB_ERR_ARG, "object transform is projective (intersection needs an affine one)");
    tb_mat3 l = tb_mat4_linear(&t->m), li;
    if (tb_mat3_inverse(&l, &li))
        return tb_error_context(TB_ERR_ARG, "object transform is degenerate");
    /* inv must really be the inverse (a hand-built transform could disagree). */
    tb_mat4 prod = tb_mat4_mul(&t->m, &t->inv);
    tb_mat4 id = tb_mat4_identity();
    if (!(tb_mat4_max_abs_diff(&prod, &id) <= 1e-6))
        return tb_error(TB_ERR_ARG, "object transform: inv is not the inverse of m");
    return TB_OK;
}

/* Signed area (shoelace) of n points x0 y0 x1 y1 ... */
static double tb__signed_area(const double *xy, int n)
{
    double a = 0.0;
    for (int i = 0; i < n; i++) {
        int j = (i + 1) % n;
        a += xy[2 * i] * xy[2 * j + 1] - xy[2 * j] * xy[2 * i + 1];
    }
    return 0.5 * a;
}

/* r^2 of a conic at z and the size of its terms (the MID reader's tolerance). */
static double tb__conic_r2(const double c[3], double z, double *size)
{
    *size = fabs(c[0]) + fabs(c[1] * z) + fabs(c[2] * z * z);
    return c[0] + c[1] * z + c[2] * z * z;
}

/* True if the conic's radius at z is zero to within rounding. */
static bool tb__conic_end_closed(const double c[3], double z)
{
    double size, r2 = tb__conic_r2(c, z, &size);
    return r2 <= 1e-12 * size;
}

uint32_t tb__face_count(tb_prim_kind kind, const tb_mid_geometry *g)
{
    switch (kind) {
    case TB_PRIM_SPHERE: return 1;
    case TB_PRIM_CUBE: return 6;
    case TB_PRIM_CYLINDER: return 3;
    case TB_PRIM_CONE: return 3;
    case TB_PRIM_PYRAMID: return 6;
    case TB_PRIM_PRISM: return 2u + (uint32_t)(g->prism.nprofile > 0 ? g->prism.nprofile : g->prism.sides);
    case TB_PRIM_TORUS: return 1;
    case TB_PRIM_POLYGONS: return (uint32_t)g->polygons.nfaces;
    case TB_PRIM_CONIC: return 3;
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH: return 9;
    default: return 0;
    }
}

/* ------------------------------------------------------------------ geometry */

/* ------------------------------------------------------------------ shared FED files */

/* One FED file read once for every object of a cache that refers to it: the
 * loaded mesh and its inline form (geometry arrays), owned here and lent to
 * the objects. Freed when its last holder (the cache or an object) lets go. */
struct tb__fed_shared {
    char *path;             /* the resolved path: the key */
    tb_fed *fed;
    tb_geom_polygons inl;   /* vertices, normals, uvs, face_start, indices (owned) */
    size_t refs;            /* the cache's reference and one per object */
    struct tb__fed_shared *next;
};

struct tb_object_fed_cache {
    struct tb__fed_shared *head;
    size_t files;           /* files read through this cache */
    size_t bytes;           /* their memory (FED mesh and inline form) */
};

tb_object_fed_cache *tb_object_fed_cache_new(void) { return calloc(1, sizeof(tb_object_fed_cache)); }

static void tb__fed_shared_release(struct tb__fed_shared *e)
{
    if (!e || --e->refs > 0)
        return;
    free((void *)e->inl.vertices);
    free((void *)e->inl.normals);
    free((void *)e->inl.uvs);
    free((void *)e->inl.face_start);
    free((void *)e->inl.indices);
    tb_fed_free(e->fed);
    free(e->path);
    free(e);
}

void tb_object_fed_cache_free(tb_object_fed_cache *c)
{
    if (!c)
        return;
    for (struct tb__fed_shared *e = c->head, *n; e; e = n) {
        n = e->next;
        tb__fed_shared_release(e);
    }
    free(c);
}

size_t tb_object_fed_cache_files(const tb_object_fed_cache *c) { return c ? c->files : 0; }

size_t tb_object_fed_cache_bytes(const tb_object_fed_cache *c) { return c ? c->bytes : 0; }

/* Reads the FED file at `path` and makes its inline form in g (vertices,
 * outer loops as polygons; owned by the caller, also on failure). */
static tb_status tb__read_fed(const char *path, const char *text, tb_fed **out, tb_geom_polygons *g)
{
    tb_fed *fed = NULL;
    tb_status st = tb_fed_read_file(path, &fed);
    if (st)
        return tb_error_context(st, "polygons: mesh file(\"%s\")", text);
    tb_stat_add(&tb__n_fed_reads, 1);
    *out = fed;
    if (fed->nfaces == 0)
        return tb_error(TB_ERR_ARG, "polygons: mesh file(\"%s\") has no faces", text);
    size_t nidx = 0;
    for (uint32_t f = 0; f < fed->nfaces; f++)
        nidx += tb_fed_loop_size(fed, tb_fed_face_outer(fed, f));
    if (nidx > (size_t)INT32_MAX)
        return tb_error(TB_ERR_ARG, "polygons: mesh file(\"%s\") is too large", text);
    bool ok = true;
    g->nvertices = (int)fed->nverts;
    g->nfaces = (int)fed->nfaces;
    g->vertices = tb__dup(fed->positions, fed->nverts, sizeof(tb_vec3), &ok);
    g->normals = tb__dup(fed->normals, fed->nverts, sizeof(tb_vec3), &ok);
    g->uvs = tb__dup(fed->uvs, fed->nverts, sizeof(tb_vec2), &ok);
    int *start = malloc(sizeof(int) * ((size_t)fed->nfaces + 1)), *idx = malloc(sizeof(int) * (nidx ? nidx : 1));
    g->face_start = start;
    g->indices = idx;
    if (!ok || !start || !idx)
        return tb_error(TB_ERR_NOMEM, "polygons: out of memory for mesh file(\"%s\")", text);
    int k = 0;
    for (uint32_t f = 0; f < fed->nfaces; f++) {
        uint32_t l = tb_fed_face_outer(fed, f), n = tb_fed_loop_size(fed, l);
        start[f] = k;
        for (uint32_t i = 0; i < n; i++)
            idx[k++] = (int)tb_fed_loop_vertex(fed, l, i);
    }
    start[fed->nfaces] = k;
    return TB_OK;
}

/* Bytes of a FED mesh's arrays and of its inline form. */
static size_t tb__fed_bytes(const tb_fed *f, const tb_geom_polygons *g)
{
    size_t nv = f->nverts, nf = f->nfaces, nl = f->nloops, nc = f->ncorners, ne = f->nedges;
    size_t n = sizeof *f + nv * sizeof(tb_vec3) * (1 + (f->normals != NULL)) + nv * sizeof(tb_vec2) * (f->uvs != NULL);
    n += nf * sizeof(int32_t) * ((f->face_ids != NULL) + (f->face_materials != NULL));
    n += sizeof(uint32_t) * ((nf + 1) + (nl + 1) + nl + 3 * nc + (ne + 1) + nc + (nv + 1));
    n += sizeof(tb_fed_edge) * ne;
    if (f->vert_faces)
        n += sizeof(uint32_t) * f->vert_faces[nv];
    n += (size_t)g->nvertices * (sizeof(tb_vec3) * (1 + (g->normals != NULL)) + sizeof(tb_vec2) * (g->uvs != NULL));
    n += ((size_t)g->nfaces + 1 + (size_t)g->face_start[g->nfaces]) * sizeof(int);
    return n;
}

/* Polygons from a FED file: load it (or, with a cache, take the copy read
 * for an earlier object), and give param and bounds the inline form. */
static tb_status tb__load_fed(tb_object *o, const tb_geom_polygons *src, tb_object_fed_cache *cache)
{
    tb_geom_polygons *g = &o->geom.polygons;
    const char *path = src->mesh.path ? src->mesh.path : src->mesh.text;
    tb_object_fed_ref *x = o->fed = calloc(1, sizeof *o->fed);
    if (!x)
        return tb_error(TB_ERR_NOMEM, "out of memory");
    x->file.text = tb_strdup(src->mesh.text);
    x->file.path = tb_strdup(src->mesh.path);
    if (!x->file.text || (src->mesh.path && !x->file.path))
        return tb_error(TB_ERR_NOMEM, "out of memory");
    if (!cache) {
        tb_status st = tb__read_fed(path, src->mesh.text, &x->fed, g);
        return st ? st : tb__mesh_build(o);
    }
    struct tb__fed_shared *e = cache->head;
    while (e && strcmp(e->path, path) != 0)
        e = e->next;
    if (e) {
        tb_stat_add(&tb__n_fed_shared, 1);
    } else {
        if (!(e = calloc(1, sizeof *e)) || !(e->path = tb_strdup(path))) {
            free(e);
            return tb_error(TB_ERR_NOMEM, "out of memory");
        }
        e->refs = 1;
        tb_status st = tb__read_fed(path, src->mesh.text, &e->fed, &e->inl);
        if (st) {
            tb__fed_shared_release(e);
            return st;
        }
        e->next = cache->head;
        cache->head = e;
        cache->files++;
        cache->bytes += tb__fed_bytes(e->fed, &e->inl);
    }
    e->refs++;
    x->shared = e;
    x->fed = e->fed;
    *g = e->inl;
    return tb__mesh_build(o);
}

static tb_status tb__copy_polygons(tb_object *o, const tb_geom_polygons *src, tb_object_fed_cache *cache)
{
    tb_geom_polygons *g = &o->geom.polygons;
    memset(g, 0, sizeof *g);
    if (src->mesh.text)
        return tb__load_fed(o, src, cache);
    if (src->nvertices < 0 || src->nfaces < 0 || (src->nvertices > 0 && !src->vertices) ||
        (src->nfaces > 0 && (!src->face_start || !src->indices)))
        return tb_error(TB_ERR_ARG, "polygons: inconsistent vertex or face arrays");
    if (src->nfaces == 0)
        return tb_error(TB_ERR_ARG, "polygons: no faces");
    for (int i = 0; i < src->nvertices; i++) {
        tb_vec3 v = src->vertices[i];
        if (!tb_isfinite3(v))
            return tb_error(TB_ERR_ARG, "polygons: vertex %d is not finite", i);
    }
    if (src->face_start[0] != 0)
        return tb_error(TB_ERR_ARG, "polygons: face_start[0] must be 0");
    for (int f = 0; f < src->nfaces; f++) {
        int a = src->face_start[f], b = src->face_start[f + 1];
        if (b - a < 3 || b < a)
            return tb_error(TB_ERR_ARG, "polygons: face %d has fewer than 3 vertices", f);
        for (int k = a; k < b; k++)
            if (src->indices[k] < 0 || src->indices[k] >= src->nvertices)
                return tb_error(TB_ERR_ARG, "polygons: face %d uses vertex %d, out of range [0, %d)", f,
                                src->indices[k], src->nvertices);
    }
    bool ok = true;
    size_t nidx = (size_t)src->face_start[src->nfaces];
    g->nvertices = src->nvertices;
    g->nfaces = src->nfaces;
    g->vertices = tb__dup(src->vertices, (size_t)src->nvertices, sizeof(tb_vec3), &ok);
    g->normals = tb__dup(src->normals, (size_t)src->nvertices, sizeof(tb_vec3), &ok);
    g->uvs = tb__dup(src->uvs, (size_t)src->nvertices, sizeof(tb_vec2), &ok);
    g->face_start = tb__dup(src->face_start, (size_t)src->nfaces + 1, sizeof(int), &ok);
    g->indices = tb__dup(src->indices, nidx, sizeof(int), &ok);
    if (!ok)
        return tb_error(TB_ERR_NOMEM, "polygons: out of memory copying %d vertices", src->nvertices);
    return tb__mesh_build(o);
}

/* Copies and checks the parameters of a primitive and derives the
 * intersection data. */
static tb_status tb__copy_geometry(tb_object *o, const tb_mid_geometry *src, tb_object_fed_cache *cache)
{
    tb_mid_geometry *g = &o->geom;
    switch (o->kind) {
    case TB_PRIM_SPHERE:
    case TB_PRIM_CUBE:
        o->closed = true;
        return TB_OK;
    case TB_PRIM_CYLINDER:
        g->cylinder = src->cylinder;
        o->conic[0] = 1.0;
        o->zrange[0] = -1.0;
        o->zrange[1] = 1.0;
        o->closed = g->cylinder.caps;
        return TB_OK;
    case TB_PRIM_CONE: {
        g->cone = src->cone;
        double rt = g->cone.top_radius;
        if (!(tb__finite(rt) && rt >= 0.0))
            return tb_error(TB_ERR_ARG, "cone: top_radius %g must be a number >= 0", rt);
        /* r(z) = a + b z is 1 at z = -1 and rt at z = 1; r^2 expanded. */
        double a = 0.5 * (1.0 + rt), b = 0.5 * (rt - 1.0);
        o->conic[0] = a * a;
        o->conic[1] = 2.0 * a * b;
        o->conic[2] = b * b;
        o->zrange[0] = -1.0;
        o->zrange[1] = 1.0;
        o->closed = g->cone.caps;
        return TB_OK;
    }
    case TB_PRIM_PYRAMID:
        g->pyramid = src->pyramid;
        if (!(tb__finite(g->pyramid.top) && g->pyramid.top >= 0.0))
            return tb_error(TB_ERR_ARG, "pyramid: top %g must be a number >= 0", g->pyramid.top);
        o->closed = g->pyramid.caps;
        return TB_OK;
    case TB_PRIM_PRISM: {
        const tb_geom_prism *p = &src->prism;
        g->prism = *p;
        g->prism.profile = NULL;
        o->closed = p->caps;
        int n;
        if (p->nprofile > 0) {
            if (p->sides != 0)
                return tb_error(TB_ERR_ARG, "prism: give either sides or a profile, not both");
            if (p->nprofile < 3 || !p->profile)
                return tb_error(TB_ERR_ARG, "prism: a profile needs at least 3 points");
            n = p->nprofile;
            bool ok = true;
            g->prism.profile = tb__dup(p->profile, (size_t)n, sizeof(tb_vec2), &ok);
            o->profile = malloc(sizeof(double) * 2 * (size_t)n);
            if (!ok || !o->profile)
                return tb_error(TB_ERR_NOMEM, "prism: out of memory for %d profile points", n);
            for (int i = 0; i < n; i++) {
                if (!(isfinite(p->profile[i].x) && isfinite(p->profile[i].y)))
                    return tb_error(TB_ERR_ARG, "prism: profile point %d is not finite", i);
                o->profile[2 * i] = p->profile[i].x;
                o->profile[2 * i + 1] = p->profile[i].y;
            }
        } else {
            if (p->sides < 3 || p->sides > 1000000)
                return tb_error(TB_ERR_ARG, "prism: sides %d outside 3 .. 1000000", p->sides);
            n = p->sides;
            if (n > TB__PRISM_PROFILE_MAX) {
                o->nprofile = 0; /* sector test, no point list */
                o->profile_orient = 1.0;
                o->profile_convex = true;
                return TB_OK;
            }
            o->profile = malloc(sizeof(double) * 2 * (size_t)n);
            if (!o->profile)
                return tb_error(TB_ERR_NOMEM, "prism: out of memory");
            for (int k = 0; k < n; k++)
                tb__prism_vertex(n, k, &o->profile[2 * k], &o->profile[2 * k + 1]);
        }
        o->nprofile = n;
        double area = tb__signed_area(o->profile, n);
        if (!(fabs(area) > 0.0) || !isfinite(area))
            return tb_error(TB_ERR_ARG, "prism: the profile has zero area");
        o->profile_orient = area > 0.0 ? 1.0 : -1.0;
        /* Convex when no turn goes against the orientation (exact signs). */
        o->profile_convex = true;
        for (int k = 0; k < n && o->profile_convex; k++) {
            const double *a = &o->profile[2 * ((k + n - 1) % n)], *b = &o->profile[2 * k],
                         *c = &o->profile[2 * ((k + 1) % n)];
            if (tb_orient2d_sign(a[0], a[1], b[0], b[1], c[0], c[1]) * o->profile_orient < 0)
                o->profile_convex = false;
        }
        return TB_OK;
    }
    case TB_PRIM_TORUS:
        g->torus = src->torus;
        if (!(tb__finite(g->torus.major) && g->torus.major > 0.0 && tb__finite(g->torus.minor) &&
              g->torus.minor > 0.0 && g->torus.minor < g->torus.major))
            return tb_error(TB_ERR_ARG, "torus: need 0 < minor (%g) < major (%g)", g->torus.minor,
                            g->torus.major);
        o->closed = true;
        return TB_OK;
    case TB_PRIM_POLYGONS:
        return tb__copy_polygons(o, &src->polygons, cache);
    case TB_PRIM_CONIC: {
        g->conic = src->conic;
        const tb_geom_conic *c = &g->conic;
        for (int i = 0; i < 3; i++)
            if (!tb__finite(c->c[i]))
                return tb_error(TB_ERR_ARG, "conic: coefficient %d is not finite", i);
        if (!(tb__finite(c->z0) && tb__finite(c->z1) && c->z0 < c->z1))
            return tb_error(TB_ERR_ARG, "conic: z_range [%g %g] must be finite and increasing", c->z0, c->z1);
        double zs[3] = {c->z0, c->z1, 0.0};
        int nz = 2;
        if (c->c[2] != 0.0) {
            double zv = -c->c[1] / (2.0 * c->c[2]);
            if (zv > c->z0 && zv < c->z1)
                zs[nz++] = zv;
        }
        double rmax = 0.0;
        for (int i = 0; i < nz; i++) {
            double size, r2 = tb__conic_r2(c->c, zs[i], &size);
            if (!isfinite(r2) || r2 < -1e-12 * size)
                return tb_error(TB_ERR_ARG, "conic: radius is imaginary or overflows at z = %g", zs[i]);
            rmax = fmax(rmax, r2);
        }
        if (!(rmax > 0.0))
            return tb_error(TB_ERR_ARG, "conic: radius is zero on the whole z range");
        memcpy(o->conic, c->c, sizeof o->conic);
        o->zrange[0] = c->z0;
        o->zrange[1] = c->z1;
        o->closed = (c->caps || tb__conic_end_closed(c->c, c->z0)) && (c->caps || tb__conic_end_closed(c->c, c->z1));
        return TB_OK;
    }
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH: {
        g->arch = src->arch;
        double w = g->arch.width, h = g->arch.height;
        if (!(w > 0.0 && w < 2.0 && h > 0.0 && h < 2.0))
            return tb_error(TB_ERR_ARG, "%s: need 0 < width (%g) < 2 and 0 < height (%g) < 2",
                            tb_prim_kind_name(o->kind), w, h);
        if (o->kind == TB_PRIM_ROUND_ARCH && !(h >= 0.5 * w))
            return tb_error(TB_ERR_ARG, "round_arch: height (%g) must be at least half the width (%g)", h, w);
        o->closed = true;
        return TB_OK;
    }
    default:
        return tb_error(TB_ERR_ARG, "object kind %d is not a primitive", (int)o->kind);
    }
}

/* ------------------------------------------------------------------ build */

static void tb__object_clear(tb_object *o);

static tb_status tb__build(tb_object *o, const tb_mid_object *m, uint32_t index, const tb_object *parent,
                           bool flip, uint32_t *face_next, tb_object_material_fn material, void *user,
                           tb_object_fed_cache *cache, int depth)
{
    memset(o, 0, sizeof *o);
    o->kind = m->kind;
    o->index = index;
    o->parent = parent;
    o->flip = flip;
    o->material = -1;
    o->to_world = m->to_world;
    if ((int)m->kind < 0 || (int)m->kind >= TB_PRIM_COUNT)
        return tb_error(TB_ERR_ARG, "object kind %d is out of range", (int)m->kind);
    if (depth > TB_MID_MAX_DEPTH)
        return tb_error(TB_ERR_ARG, "CSG tree deeper than %d levels", TB_MID_MAX_DEPTH);
    tb_status st = tb__check_transform(&o->to_world);
    if (st)
        return st;
    o->inv_affine = tb_mat4_is_affine(&o->to_world.inv);
    tb_mat3 l = tb_mat4_linear(&o->to_world.m);
    double s2 = 0.0;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            s2 += l.m[i][j] * l.m[i][j];
    o->scale = sqrt(s2);
    if (m->name && !(o->name = tb_strdup(m->name)))
        return tb_error(TB_ERR_NOMEM, "out of memory");
    if (material && (st = material(user, &m->material, &o->material)))
        return st;

    if (!tb_prim_is_csg(m->kind)) {
        if (m->nchildren > 0)
            return tb_error(TB_ERR_ARG, "%s: only CSG nodes may contain objects", tb_prim_kind_name(m->kind));
        if ((st = tb__copy_geometry(o, &m->geom, cache)))
            return tb_error_context(st, "%s", tb_prim_kind_name(m->kind));
        if (o->kind == TB_PRIM_CYLINDER || o->kind == TB_PRIM_CONE || o->kind == TB_PRIM_CONIC)
            tb__revolved_prepare(o);
        o->face_base = *face_next;
        o->nfaces = tb__face_count(o->kind, &o->geom);
        if (o->nfaces > UINT32_MAX - *face_next)
            return tb_error(TB_ERR_ARG, "CSG tree has more than 2^32 faces");
        *face_next += o->nfaces;
        return TB_OK;
    }

    int need = m->kind == TB_PRIM_DIFFERENCE ? 2 : 1;
    if (m->nchildren < need || !m->children)
        return tb_error(TB_ERR_ARG, "%s needs at least %d children, has %d", tb_prim_kind_name(m->kind), need,
                        m->nchildren);
    o->children = calloc((size_t)m->nchildren, sizeof(tb_object));
    if (!o->children)
        return tb_error(TB_ERR_NOMEM, "out of memory");
    o->nchildren = m->nchildren;
    o->face_base = *face_next;
    o->closed = true;
    for (int i = 0; i < m->nchildren; i++) {
        bool f = flip ^ (m->kind == TB_PRIM_DIFFERENCE && i > 0);
        st = tb__build(&o->children[i], &m->children[i], index, o, f, face_next, material, user, cache, depth + 1);
        if (st)
            return tb_error_context(st, "%s child %d", tb_prim_kind_name(m->kind), i);
        if (!o->children[i].closed)
            return tb_error(TB_ERR_ARG,
                            "%s child %d (%s) is not a closed solid (missing caps or an open mesh): "
                            "CSG needs solids",
                            tb_prim_kind_name(m->kind), i, tb_prim_kind_name(m->children[i].kind));
    }
    o->nfaces = *face_next - o->face_base;
    return TB_OK;
}

tb_status tb_object_from_mid(const tb_mid_object *m, uint32_t index, tb_object_material_fn material, void *user,
                             tb_object **out)
{
    return tb_object_from_mid_shared(m, index, material, user, NULL, out);
}

tb_status tb_object_from_mid_shared(const tb_mid_object *m, uint32_t index, tb_object_material_fn material,
                                    void *user, tb_object_fed_cache *cache, tb_object **out)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "tb_object_from_mid: NULL output");
    *out = NULL;
    if (!m)
        return tb_error(TB_ERR_ARG, "tb_object_from_mid: NULL object");
    tb_object *o = calloc(1, sizeof *o);
    if (!o)
        return tb_error(TB_ERR_NOMEM, "out of memory");
    uint32_t next = 0;
    tb_status st = tb__build(o, m, index, NULL, false, &next, material, user, cache, 0);
    if (st) {
        tb_object_free(o);
        return st;
    }
    *out = o;
    return TB_OK;
}

_Atomic unsigned long tb__object_generation;

unsigned long tb_object_generation(void) { return tb__object_generation; }

static void tb__object_clear(tb_object *o)
{
    tb__object_generation++; /* invalidates memos that point into objects */
    for (int i = 0; i < o->nchildren; i++)
        tb__object_clear(&o->children[i]);
    free(o->children);
    free(o->name);
    if (o->kind == TB_PRIM_PRISM)
        free(o->profile);
    if (o->kind == TB_PRIM_POLYGONS) {
        tb_geom_polygons *g = &o->geom.polygons;
        if (o->fed && o->fed->shared) {
            tb__fed_shared_release(o->fed->shared); /* the FED and inline arrays are its */
        } else {
            free((void *)g->vertices);
            free((void *)g->normals);
            free((void *)g->uvs);
            free((void *)g->face_start);
            free((void *)g->indices);
            if (o->fed)
                tb_fed_free(o->fed->fed);
        }
        if (o->fed) {
            free((void *)o->fed->file.text);
            free((void *)o->fed->file.path);
            free(o->fed);
        }
    } else if (o->kind == TB_PRIM_PRISM) {
        free((void *)o->geom.prism.profile);
    }
    tb__mesh_free(o->mesh);
    memset(o, 0, sizeof *o);
}

void tb_object_free(tb_object *obj)
{
    if (!obj)
        return;
    tb__object_clear(obj);
    free(obj);
}

const tb_object *tb_object_leaf_for_face(const tb_object *obj, uint32_t face, uint32_t *local)
{
    while (obj) {
        if (face < obj->face_base || face - obj->face_base >= obj->nfaces)
            return NULL;
        if (!tb_prim_is_csg(obj->kind)) {
            if (local)
                *local = face - obj->face_base;
            return obj;
        }
        const tb_object *next = NULL;
        for (int i = 0; i < obj->nchildren && !next; i++) {
            const tb_object *c = &obj->children[i];
            if (face >= c->face_base && face - c->face_base < c->nfaces)
                next = c;
        }
        obj = next;
    }
    return NULL;
}
