/* Polygonal approximation of CSG trees (docs/primitives.md, "Tessellating
 * CSG trees"): every leaf is tessellated (tb_polygonize, or its triangulated
 * mesh for polygons), its triangles are classified against the whole tree by
 * short probe rays through the CSG intersection code, and triangles whose
 * samples classify differently are split 4 ways (midpoints projected back
 * onto the leaf's surface) down to the requested edge length. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "host/object/intersect.h"
#include "host/object/param.h"
#include "host/object/polygonize.h"
#include "util/container/array.h"
#include "util/mesh/triangulate.h"
#include "util/stats/stats.h"

/* Probe rays of CSG tessellation: the load-time cost term of testbed predict (docs/predict.md). */
TB_STAT_COUNTER(tb__csg_probes, "Polygonize/CSG probes");

/* How a point of a leaf's surface belongs to the tree's boundary. */
enum { TB__DROP = 0, TB__KEEP = 1, TB__FLIP = 2 };

/* Deepest 4-way split of one leaf triangle (4^12 pieces at most). */
#define TB__CSG_MAX_DEPTH 12

typedef struct tb__csg_ctx {
    const tb_object *root;
    double min_edge; /* world length below which a straddling triangle is not split further */
    double probe;    /* half length of the probe rays (world) */
    tb_array pos;    /* tb_vec3 world positions of output triangles, 3 per triangle */
    tb_array ids;    /* int32_t face ID per output triangle */
    tb_status err;
} tb__csg_ctx;

typedef struct tb__csg_leaf {
    const tb_object *o;
    int face;        /* local face ID of the triangle being processed */
} tb__csg_leaf;

static tb_dvec3 tb__mid(tb_dvec3 a, tb_dvec3 b) { return tb_dvec3_scale(tb_dvec3_add(a, b), 0.5); }

/* Moves an object-space point onto the leaf's face (planar faces and failures
 * keep it: a midpoint of a flat face is on it already). */
static tb_dvec3 tb__project(const tb__csg_leaf *L, tb_dvec3 p)
{
    const tb_object *o = L->o;
    if (o->kind == TB_PRIM_POLYGONS)
        return p;
    int f;
    double u, v;
    tb_dvec3 q;
    if (tb_param_from_point(o->kind, &o->geom, p, L->face, &f, &u, &v) ||
        tb_param_eval(o->kind, &o->geom, f, u, v, &q, NULL, NULL, NULL))
        return p;
    return q;
}

/* Classifies world point w of leaf L's surface, with n the world normal of
 * the facet around it (out of the leaf): the tree's closest hit along a short
 * ray crossing the surface there against n must be on L, and its normal then
 * says the orientation (a subtracted leaf's normal comes back flipped). A hit
 * on another leaf (a coincident surface the CSG rules give to a lower child,
 * or a surface closer than the probe) or none drops the point. */
static int tb__classify(const tb__csg_ctx *c, const tb_object *leaf, tb_dvec3 w, tb_dvec3 n)
{
    double h = c->probe;
    TB_STAT_INC(tb__csg_probes);
    tb_dvec3 o = tb_dvec3_add(w, tb_dvec3_scale(n, h));
    tb_ray ray = tb_ray_make((tb_vec3){(float)o.x, (float)o.y, (float)o.z},
                             (tb_vec3){(float)-n.x, (float)-n.y, (float)-n.z}, 0.0f, (float)(2.0 * h));
    tb_hit hit;
    if (!tb_object_intersect(c->root, &ray, &hit))
        return TB__DROP;
    if (hit.face < leaf->face_base || hit.face >= leaf->face_base + leaf->nfaces)
        return TB__DROP;
    double s = hit.ng.x * n.x + hit.ng.y * n.y + hit.ng.z * n.z;
    return s >= 0.0 ? TB__KEEP : TB__FLIP;
}

static void tb__emit(tb__csg_ctx *c, const tb__csg_leaf *L, const tb_dvec3 w[3], int cls)
{
    if (cls == TB__DROP || c->err)
        return;
    tb_vec3 f[3];
    for (int i = 0; i < 3; i++)
        f[i] = (tb_vec3){(float)w[i].x, (float)w[i].y, (float)w[i].z};
    /* Zero-area pieces (at poles, or collapsed by float rounding) would make
     * the FED mesh invalid. */
    tb_dvec3 e1 = {(double)f[1].x - f[0].x, (double)f[1].y - f[0].y, (double)f[1].z - f[0].z};
    tb_dvec3 e2 = {(double)f[2].x - f[0].x, (double)f[2].y - f[0].y, (double)f[2].z - f[0].z};
    double a2 = tb_dvec3_length(tb_dvec3_cross(e1, e2));
    double l2 = fmax(tb_dvec3_length2(e1), tb_dvec3_length2(e2));
    if (!(a2 > 1e-9 * l2))
        return;
    if (cls == TB__FLIP) {
        tb_vec3 t = f[1];
        f[1] = f[2], f[2] = t;
    }
    int32_t id = (int32_t)(L->o->face_base + (uint32_t)L->face);
    if (tb_array_push_n(&c->pos, f, 3) || tb_array_push(&c->ids, &id))
        c->err = TB_ERR_NOMEM;
}

/* One triangle (object-space corners p, world corners w, world facet normal
 * n): sampled at its corners, edge midpoints and centroid; all alike: emitted
 * or dropped whole; else split until its longest world edge is below
 * min_edge, where the centroid decides. */
static void tb__csg_tri(tb__csg_ctx *c, const tb__csg_leaf *L, const tb_dvec3 p[3], const tb_dvec3 w[3], int depth)
{
    const tb_transform *xf = &L->o->to_world;
    tb_dvec3 n = tb_dvec3_cross(tb_dvec3_sub(w[1], w[0]), tb_dvec3_sub(w[2], w[0]));
    double nl = tb_dvec3_length(n);
    if (!(nl > 0.0))
        return;
    n = tb_dvec3_scale(n, 1.0 / nl);
    /* A lone primitive is its own boundary (open surfaces too, whose probes
     * would say nothing about orientation). */
    if (c->root->nchildren == 0) {
        tb__emit(c, L, w, TB__KEEP);
        return;
    }
    /* Samples on the facet itself (not projected): the probe crosses the
     * surface within the tessellation's sagitta, covered by its length. */
    tb_dvec3 s[7] = {w[0], w[1], w[2], tb__mid(w[0], w[1]), tb__mid(w[1], w[2]), tb__mid(w[2], w[0]),
                     tb_dvec3_scale(tb_dvec3_add(tb_dvec3_add(w[0], w[1]), w[2]), 1.0 / 3.0)};
    int cls[7];
    bool same = true;
    for (int i = 0; i < 7; i++) {
        cls[i] = tb__classify(c, L->o, s[i], n);
        same = same && cls[i] == cls[0];
    }
    double edge = fmax(tb_dvec3_length(tb_dvec3_sub(w[1], w[0])),
                       fmax(tb_dvec3_length(tb_dvec3_sub(w[2], w[1])), tb_dvec3_length(tb_dvec3_sub(w[0], w[2]))));
    if (same || edge <= c->min_edge || depth >= TB__CSG_MAX_DEPTH) {
        tb__emit(c, L, w, same ? cls[0] : cls[6]);
        return;
    }
    tb_dvec3 m[3], mw[3];
    for (int i = 0; i < 3; i++) {
        m[i] = tb__project(L, tb__mid(p[i], p[(i + 1) % 3]));
        mw[i] = tb_transform_dpoint(xf, m[i]);
    }
    const tb_dvec3 sp[4][3] = {{p[0], m[0], m[2]}, {m[0], p[1], m[1]}, {m[2], m[1], p[2]}, {m[0], m[1], m[2]}};
    const tb_dvec3 sw[4][3] = {{w[0], mw[0], mw[2]}, {mw[0], w[1], mw[1]}, {mw[2], mw[1], w[2]}, {mw[0], mw[1], mw[2]}};
    for (int k = 0; k < 4 && !c->err; k++)
        tb__csg_tri(c, L, sp[k], sw[k], depth + 1);
}

/* The leaf's triangles in object space: polygons from their build-time
 * triangulation, other kinds tessellated and each face's outer loop
 * triangulated. */
static tb_status tb__csg_leaf_tris(tb__csg_ctx *c, const tb_object *o, const tb_poly_options *opt)
{
    tb__csg_leaf L = {o, 0};
    if (o->kind == TB_PRIM_POLYGONS) {
        const tb_object_mesh *m = o->mesh;
        for (uint32_t t = 0; m && t < m->ntris && !c->err; t++) {
            tb_dvec3 p[3], w[3];
            for (int i = 0; i < 3; i++) {
                tb_vec3 v = m->vertices[m->tris[3 * t + i]];
                p[i] = (tb_dvec3){v.x, v.y, v.z};
                w[i] = tb_transform_dpoint(&o->to_world, p[i]);
            }
            L.face = (int)m->tri_face[t];
            tb__csg_tri(c, &L, p, w, 0);
        }
        return c->err;
    }
    tb_poly_options lo = *opt;
    lo.to_world = &o->to_world;
    lo.split = false;
    tb_fed *fed = NULL;
    tb_status st = tb_polygonize(o->kind, &o->geom, &lo, &fed);
    if (st)
        return st;
    tb_array tris;
    tb_array_init(&tris, sizeof(tb_tri));
    for (uint32_t f = 0; f < fed->nfaces && !c->err; f++) {
        uint32_t l = fed->face_loops[f], c0 = fed->loop_corners[l];
        uint32_t size = fed->loop_corners[l + 1] - c0;
        tb_array_clear(&tris);
        st = tb_triangulate_3d(fed->positions, fed->corner_vert + c0, &size, 1, &tris, NULL);
        if (st)
            break;
        L.face = fed->face_ids ? fed->face_ids[f] : 0;
        for (size_t t = 0; t < tris.len && !c->err; t++) {
            const tb_tri *tr = tb_array_at(&tris, t);
            tb_dvec3 p[3], w[3];
            for (int i = 0; i < 3; i++) {
                tb_vec3 v = fed->positions[tr->v[i]];
                p[i] = (tb_dvec3){v.x, v.y, v.z};
                w[i] = tb_transform_dpoint(&o->to_world, p[i]);
            }
            tb__csg_tri(c, &L, p, w, 0);
        }
    }
    tb_array_free(&tris);
    tb_fed_free(fed);
    return st ? st : c->err;
}

static tb_status tb__csg_walk(tb__csg_ctx *c, const tb_object *o, const tb_poly_options *opt)
{
    if (o->nchildren == 0)
        return tb__csg_leaf_tris(c, o, opt);
    for (int i = 0; i < o->nchildren; i++) {
        tb_status st = tb__csg_walk(c, &o->children[i], opt);
        if (st)
            return st;
    }
    return TB_OK;
}

/* The world size of the tree: the largest box diagonal over its leaves'
 * to_world images of the unit scale (a cheap bound: scale of each leaf). */
static double tb__csg_scale(const tb_object *o)
{
    if (o->nchildren == 0)
        return o->scale;
    double s = 0.0;
    for (int i = 0; i < o->nchildren; i++)
        s = fmax(s, tb__csg_scale(&o->children[i]));
    return s;
}

tb_status tb_polygonize_object(const tb_object *obj, const tb_poly_options *opt, double csg_edge, tb_fed **out)
{
    *out = NULL;
    if (!obj)
        return tb_error(TB_ERR_ARG, "polygonize: no object");
    tb_poly_options o = opt ? *opt : (tb_poly_options){0};
    if (!(csg_edge > 0.0) || !isfinite(csg_edge))
        return tb_error(TB_ERR_ARG, "polygonize: CSG edge length %g must be positive and finite", csg_edge);
    tb__csg_ctx c;
    memset(&c, 0, sizeof c);
    c.root = obj;
    c.min_edge = csg_edge;
    /* Longer than the facets' distance from the surface (sagitta), much
     * shorter than the features: a quarter of the CSG edge length, at least
     * 1e-6 of the object's scale. */
    c.probe = fmax(0.25 * csg_edge, 1e-6 * tb__csg_scale(obj));
    tb_array_init(&c.pos, sizeof(tb_vec3));
    tb_array_init(&c.ids, sizeof(int32_t));
    tb_status st = tb__csg_walk(&c, obj, &o);
    if (!st) {
        uint32_t nt = (uint32_t)c.ids.len;
        uint32_t *sizes = malloc((nt ? nt : 1) * sizeof *sizes);
        uint32_t *corners = malloc((3 * (size_t)nt + 1) * sizeof *corners);
        if (!sizes || !corners) {
            st = tb_error(TB_ERR_NOMEM, "polygonize: out of memory");
        } else {
            for (uint32_t i = 0; i < nt; i++)
                sizes[i] = 3;
            for (uint32_t i = 0; i < 3 * nt; i++)
                corners[i] = i;
            tb_fed_desc d = {.nverts = 3 * nt, .positions = c.pos.data, .nfaces = nt, .nloops = nt,
                             .loop_sizes = sizes, .corners = corners, .face_ids = c.ids.data};
            tb_fed_issue issue;
            st = tb_fed_build(&d, out, &issue);
        }
        free(sizes);
        free(corners);
    } else if (st == TB_ERR_NOMEM) {
        tb_error(TB_ERR_NOMEM, "polygonize: out of memory");
    }
    tb_array_free(&c.pos);
    tb_array_free(&c.ids);
    return st;
}
