/* Polygons: triangulation once at build time, a BVH over the triangles, and
 * the watertight ray/triangle test of Woop, Benthin and Wald ("Watertight
 * Ray/Triangle Intersection", JCGT 2(1), 2013), evaluated in double in world
 * space: the vertices are mapped to world space once at build time (in
 * double), so the test takes the world ray as it is, and a query that tests
 * triangles of several meshes prepares the ray once (the scene level tests
 * each triangle on its own, tb_object_triangle_crossing). The line parameter
 * t is the same in both spaces (the object ray's direction is not
 * normalised), so hit points and normals are still computed in object space.
 *
 * Watertightness: the ray is made the z axis of a sheared space; a vertex's
 * sheared coordinates are computed once per vertex, and the edge function of
 * an edge shared by two triangles is computed from the same two vertices in
 * the same products, so the two triangles see exactly opposite values and a
 * ray cannot slip between them. When an edge function comes out exactly 0 in
 * double, its sign is recomputed exactly (Shewchuk's orient2d, util/mesh), and
 * if it is truly 0 (the ray passes exactly through the edge or a vertex) a
 * tie rule claims the point for exactly one of the triangles around it: the
 * one the ray would hit if shifted by (eps, eps^2) in the sheared plane (a
 * symbolic perturbation, like the top-left rule of rasterisers). So each
 * crossing of a closed mesh is counted exactly once, which the CSG winding
 * count relies on. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "host/object/intersect.h"
#include "host/object/intersect_internal.h"
#include "host/object/param.h"
#include "host/object/watertight.h"
#include "util/container/array.h"
#include "util/math/float.h"
#include "util/mesh/fed.h"
#include "util/mesh/predicates.h"
#include "util/mesh/triangulate.h"

/* Triangles per leaf (at most). */
#define TB__BVH_LEAF 4
/* SAH bins per split. */
#define TB__BVH_BINS 16
/* Traversal stack depth (the build falls back to median splits long before). */
#define TB__BVH_STACK 128
/* Depth after which the build stops trusting SAH and splits at the median. */
#define TB__BVH_SAH_DEPTH 60

/* ------------------------------------------------------------------ build */

void tb__mesh_free(tb_object_mesh *m)
{
    if (!m)
        return;
    free(m->wvertices); /* (vertices are the geometry's) */
    free(m->tris);
    free(m->tri_face);
    free(m->tri_uv);
    free(m->wnormal);
    free(m->nodes);
    free(m);
}

typedef struct tb__bprim {
    float lo[3], hi[3];
    float c[3]; /* centroid */
} tb__bprim;

typedef struct tb__bctx {
    tb__bprim *prims;
    uint32_t *order; /* triangle index per position */
    tb_object_bvh_node *nodes;
    uint32_t nnodes;
} tb__bctx;

static float tb__area(const float lo[3], const float hi[3])
{
    float e0 = hi[0] - lo[0], e1 = hi[1] - lo[1], e2 = hi[2] - lo[2];
    if (!(e0 >= 0.0f))
        return 0.0f;
    return e0 * e1 + e1 * e2 + e2 * e0;
}

static void tb__grow(float lo[3], float hi[3], const float plo[3], const float phi[3])
{
    for (int i = 0; i < 3; i++) { /* comparisons, not fminf/fmaxf (library calls); boxes hold no NaN */
        lo[i] = plo[i] < lo[i] ? plo[i] : lo[i];
        hi[i] = phi[i] > hi[i] ? phi[i] : hi[i];
    }
}

typedef struct tb__kv {
    float key;
    uint32_t idx;
} tb__kv;

static int tb__kv_cmp(const void *pa, const void *pb)
{
    const tb__kv *a = pa, *b = pb;
    if (a->key != b->key)
        return a->key < b->key ? -1 : 1;
    return (a->idx > b->idx) - (a->idx < b->idx);
}

/* Median split of order[begin, end) along axis (by centroid, then index: deterministic). */
static uint32_t tb__median(tb__bctx *c, uint32_t begin, uint32_t end, int axis)
{
    uint32_t n = end - begin;
    tb__kv *tmp = malloc(sizeof *tmp * n);
    if (!tmp)
        return begin + n / 2; /* unsorted halves still give a valid (if poor) tree */
    for (uint32_t i = 0; i < n; i++)
        tmp[i] = (tb__kv){c->prims[c->order[begin + i]].c[axis], c->order[begin + i]};
    qsort(tmp, n, sizeof *tmp, tb__kv_cmp);
    for (uint32_t i = 0; i < n; i++)
        c->order[begin + i] = tmp[i].idx;
    free(tmp);
    return begin + n / 2;
}

static uint32_t tb__build_node(tb__bctx *c, uint32_t begin, uint32_t end, int depth)
{
    uint32_t id = c->nnodes++;
    tb_object_bvh_node *nd = &c->nodes[id];
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    float clo[3] = {INFINITY, INFINITY, INFINITY}, chi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = begin; i < end; i++) {
        const tb__bprim *p = &c->prims[c->order[i]];
        tb__grow(lo, hi, p->lo, p->hi);
        tb__grow(clo, chi, p->c, p->c);
    }
    /* Widen by one float outward: the double ray/triangle test may accept a
     * point a double rounding outside the float box; one float is far more. */
    for (int i = 0; i < 3; i++) {
        nd->lo[i] = tb_next_float_down(lo[i]);
        nd->hi[i] = tb_next_float_up(hi[i]);
    }
    uint32_t n = end - begin;
    if (n <= TB__BVH_LEAF) {
        nd->index = begin;
        nd->count = (uint16_t)n;
        nd->axis = 0;
        return id;
    }
    int axis = 0;
    float ext[3] = {chi[0] - clo[0], chi[1] - clo[1], chi[2] - clo[2]};
    if (ext[1] > ext[axis])
        axis = 1;
    if (ext[2] > ext[axis])
        axis = 2;
    uint32_t mid = begin;
    if (ext[axis] > 0.0f && depth < TB__BVH_SAH_DEPTH) {
        /* Binned SAH (Wald 2007) on the widest centroid axis. */
        uint32_t cnt[TB__BVH_BINS] = {0};
        float blo[TB__BVH_BINS][3], bhi[TB__BVH_BINS][3];
        for (int b = 0; b < TB__BVH_BINS; b++)
            for (int i = 0; i < 3; i++) {
                blo[b][i] = INFINITY;
                bhi[b][i] = -INFINITY;
            }
        float k = (float)TB__BVH_BINS / ext[axis];
        for (uint32_t i = begin; i < end; i++) {
            const tb__bprim *p = &c->prims[c->order[i]];
            int b = (int)((p->c[axis] - clo[axis]) * k);
            b = b < 0 ? 0 : (b >= TB__BVH_BINS ? TB__BVH_BINS - 1 : b);
            cnt[b]++;
            tb__grow(blo[b], bhi[b], p->lo, p->hi);
        }
        float rarea[TB__BVH_BINS];
        uint32_t rcnt[TB__BVH_BINS];
        float alo[3] = {INFINITY, INFINITY, INFINITY}, ahi[3] = {-INFINITY, -INFINITY, -INFINITY};
        uint32_t acc = 0;
        for (int b = TB__BVH_BINS - 1; b > 0; b--) {
            tb__grow(alo, ahi, blo[b], bhi[b]);
            acc += cnt[b];
            rarea[b] = tb__area(alo, ahi);
            rcnt[b] = acc;
        }
        float best = INFINITY;
        int best_b = -1;
        for (int i = 0; i < 3; i++) {
            alo[i] = INFINITY;
            ahi[i] = -INFINITY;
        }
        acc = 0;
        for (int b = 1; b < TB__BVH_BINS; b++) {
            tb__grow(alo, ahi, blo[b - 1], bhi[b - 1]);
            acc += cnt[b - 1];
            if (acc == 0 || rcnt[b] == 0)
                continue;
            float cost = tb__area(alo, ahi) * (float)acc + rarea[b] * (float)rcnt[b];
            if (cost < best) {
                best = cost;
                best_b = b;
            }
        }
        if (best_b > 0) {
            /* Partition in place: bins below best_b to the left. */
            uint32_t i = begin, j = end;
            while (i < j) {
                const tb__bprim *p = &c->prims[c->order[i]];
                int b = (int)((p->c[axis] - clo[axis]) * k);
                b = b < 0 ? 0 : (b >= TB__BVH_BINS ? TB__BVH_BINS - 1 : b);
                if (b < best_b) {
                    i++;
                } else {
                    uint32_t t = c->order[i];
                    c->order[i] = c->order[--j];
                    c->order[j] = t;
                }
            }
            mid = i;
        }
    }
    if (mid == begin || mid == end) {
        if (n <= 0xffff && ext[axis] == 0.0f && n <= 4 * TB__BVH_LEAF) {
            nd->index = begin;
            nd->count = (uint16_t)n;
            nd->axis = 0;
            return id;
        }
        mid = tb__median(c, begin, end, axis);
    }
    tb__build_node(c, begin, mid, depth + 1);
    uint32_t right = tb__build_node(c, mid, end, depth + 1);
    nd = &c->nodes[id];
    nd->index = right;
    nd->count = 0;
    nd->axis = (uint16_t)axis;
    return id;
}

/* Directed edge key: (min << 32 | max) << 1 | (a < b). */
static int tb__cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* True if every polygon edge is matched by exactly one edge running the other way. */
static bool tb__polygons_closed(const tb_geom_polygons *g)
{
    size_t n = (size_t)g->face_start[g->nfaces];
    uint64_t *e = malloc(sizeof *e * (n ? n : 1));
    if (!e)
        return false;
    size_t m = 0;
    for (int f = 0; f < g->nfaces; f++) {
        int s = g->face_start[f], t = g->face_start[f + 1];
        for (int i = s; i < t; i++) {
            uint64_t a = (uint64_t)g->indices[i], b = (uint64_t)g->indices[i + 1 < t ? i + 1 : s];
            if (a == b)
                continue;
            uint64_t lo = a < b ? a : b, hi = a < b ? b : a;
            e[m++] = ((lo << 32 | hi) << 1) | (a < b ? 1u : 0u);
        }
    }
    qsort(e, m, sizeof *e, tb__cmp_u64);
    bool closed = m > 0;
    for (size_t i = 0; i < m && closed;) {
        size_t j = i;
        while (j < m && e[j] >> 1 == e[i] >> 1)
            j++;
        if (j - i != 2 || (e[i] & 1) == (e[i + 1] & 1))
            closed = false;
        i = j;
    }
    free(e);
    return closed;
}

/* The (u, v) at the corners of the nt triangles tv[] (all of face f) as
 * floats (u0 v0 u1 v1 u2 v2 per triangle): where f's (u, v) is affine over
 * each triangle, the exact (u, v) of its corners, so a hit's barycentric mix
 * is tb_param_from_point's (u, v) of the hit point up to rounding. A face
 * without uvs: the frame projection (affine; param's nearest-point step does
 * nothing for points of the triangles, which lie in the loop); no area: 0,
 * param's error answer. A triangle with uvs: its uvs. More corners with uvs:
 * param's fan or ear clipping need not be the mesh's triangles, so false
 * (the hit point path). */
static bool tb__corner_uv(const tb_geom_polygons *g, int f, const uint32_t *tv, size_t nt, float *out)
{
    int b = g->face_start[f], nv = g->face_start[f + 1] - b;
    if (g->uvs) {
        if (nv != 3)
            return false;
        for (size_t i = 0; i < nt; i++)
            for (int k = 0; k < 3; k++) {
                tb_vec2 uv = g->uvs[tv[3 * i + k]];
                out[6 * i + 2 * k] = uv.x;
                out[6 * i + 2 * k + 1] = uv.y;
            }
        return true;
    }
    tb_poly_frame fr;
    bool ok = tb_poly_frame_make(g->vertices, &g->indices[b], nv, &fr);
    for (size_t i = 0; i < nt; i++)
        for (int k = 0; k < 3; k++) {
            double u = 0.0, v = 0.0;
            if (ok)
                tb_poly_frame_uv(&fr, g->vertices, &g->indices[b], nv, tb_vec3_to_d(g->vertices[tv[3 * i + k]]), &u,
                                 &v);
            out[6 * i + 2 * k] = (float)u;
            out[6 * i + 2 * k + 1] = (float)v;
        }
    return true;
}

static tb_dvec3 tb__tri_normal(const tb_object_mesh *m, uint32_t i);

/* Triangle tri's unit world normal: its object-space normal by the inverse
 * transpose, normalised in double, negated for a flipped leaf. */
static tb_vec3 tb__tri_world_normal(const tb_object *o, uint32_t tri)
{
    tb_dvec3 nw = tb_transform_dnormal(&o->to_world, tb__tri_normal(o->mesh, tri));
    double len = tb_dvec3_length(nw);
    if (!(len > 0.0) || !isfinite(len))
        return (tb_vec3){0.0f, 0.0f, 1.0f};
    double s = (o->flip ? -1.0 : 1.0) / len;
    return (tb_vec3){(float)(nw.x * s), (float)(nw.y * s), (float)(nw.z * s)};
}

tb_status tb__mesh_build(tb_object *o)
{
    const tb_geom_polygons *g = &o->geom.polygons;
    tb_object_mesh *m = calloc(1, sizeof *m);
    if (!m)
        return tb_error(TB_ERR_NOMEM, "polygons: out of memory");
    o->mesh = m;
    m->nvertices = (uint32_t)g->nvertices;
    m->vertices = g->vertices;
    m->wvertices = malloc(sizeof(double) * 3 * (g->nvertices ? (size_t)g->nvertices : 1));
    if (!m->wvertices)
        return tb_error(TB_ERR_NOMEM, "polygons: out of memory");
    for (int i = 0; i < g->nvertices; i++) {
        tb_dvec3 w = tb_transform_dpoint(&o->to_world, tb_vec3_to_d(g->vertices[i]));
        m->wvertices[3 * (size_t)i] = w.x, m->wvertices[3 * (size_t)i + 1] = w.y, m->wvertices[3 * (size_t)i + 2] = w.z;
    }
    /* A mirroring transform turns counter-clockwise into clockwise: the
     * world-space determinant's sign then means the opposite side. */
    m->wsign = tb_transform_swaps_handedness(&o->to_world) ? -1 : 1;

    /* Triangulate: triangles as they are, larger polygons (and FED faces
     * with holes) by ear clipping. */
    const tb_fed *fed = o->fed ? o->fed->fed : NULL;
    tb_array tris, faces, tmp;
    tb_array_init(&tris, sizeof(uint32_t) * 3);
    tb_array_init(&faces, sizeof(uint32_t));
    tb_array_init(&tmp, sizeof(tb_tri));
    uint32_t *idx = NULL, *rings = NULL;
    size_t idx_cap = 0, rings_cap = 0;
    tb_status st = TB_OK;
    for (int f = 0; f < g->nfaces && !st; f++) {
        uint32_t nv, nrings = 1;
        if (fed) {
            uint32_t l0 = fed->face_loops[f], l1 = fed->face_loops[f + 1];
            nrings = l1 - l0;
            nv = fed->loop_corners[l1] - fed->loop_corners[l0];
        } else {
            nv = (uint32_t)(g->face_start[f + 1] - g->face_start[f]);
        }
        if (nv > idx_cap || nrings > rings_cap) {
            uint32_t *ni = realloc(idx, sizeof *idx * (nv > idx_cap ? nv : idx_cap));
            if (ni)
                idx = ni;
            uint32_t *nr = realloc(rings, sizeof *rings * (nrings > rings_cap ? nrings : rings_cap));
            if (nr)
                rings = nr;
            if (!ni || !nr) {
                st = tb_error(TB_ERR_NOMEM, "polygons: out of memory");
                break;
            }
            idx_cap = nv > idx_cap ? nv : idx_cap;
            rings_cap = nrings > rings_cap ? nrings : rings_cap;
        }
        if (fed) {
            uint32_t l0 = fed->face_loops[f];
            memcpy(idx, &fed->corner_vert[fed->loop_corners[l0]], sizeof *idx * nv);
            for (uint32_t i = 0; i < nrings; i++)
                rings[i] = tb_fed_loop_size(fed, l0 + i);
        } else {
            for (uint32_t i = 0; i < nv; i++)
                idx[i] = (uint32_t)g->indices[g->face_start[f] + (int)i];
            rings[0] = nv;
        }
        tb_array_clear(&tmp);
        if (nv == 3 && nrings == 1) {
            tb_tri t = {{idx[0], idx[1], idx[2]}};
            st = tb_array_push(&tmp, &t);
        } else {
            st = tb_triangulate_3d(m->vertices, idx, rings, nrings, &tmp, NULL);
            if (st)
                tb_error_context(st, "polygons: face %d", f);
        }
        for (size_t i = 0; i < tmp.len && !st; i++) {
            const tb_tri *t = &TB_ARRAY_AT(&tmp, tb_tri, i);
            uint32_t ff = (uint32_t)f;
            if (!(st = tb_array_push(&tris, t->v)))
                st = tb_array_push(&faces, &ff);
        }
    }
    free(idx);
    free(rings);
    tb_array_free(&tmp);
    if (st) {
        tb_array_free(&tris);
        tb_array_free(&faces);
        return st;
    }
    m->ntris = (uint32_t)tris.len;
    m->closed = fed ? tb_fed_is_closed(fed) : tb__polygons_closed(g);

    /* BVH. */
    size_t nt = tris.len;
    const uint32_t *tv = tris.data;
    tb__bctx c = {0};
    c.prims = malloc(sizeof *c.prims * (nt ? nt : 1));
    c.order = malloc(sizeof *c.order * (nt ? nt : 1));
    c.nodes = malloc(sizeof *c.nodes * (nt ? 2 * nt : 1));
    m->tris = malloc(sizeof(uint32_t) * 3 * (nt ? nt : 1));
    m->tri_face = malloc(sizeof(uint32_t) * (nt ? nt : 1));
    /* Corner (u, v) kept only for the frame projection (no uvs), a frame per face. */
    float *uv0 = g->uvs ? NULL : malloc(sizeof(float) * 6 * (nt ? nt : 1));
    m->tri_uv = g->uvs ? NULL : malloc(sizeof(float) * 6 * (nt ? nt : 1));
    if (!c.prims || !c.order || !c.nodes || !m->tris || !m->tri_face || (!g->uvs && (!uv0 || !m->tri_uv))) {
        free(c.prims);
        free(c.order);
        free(c.nodes);
        free(uv0);
        tb_array_free(&tris);
        tb_array_free(&faces);
        return tb_error(TB_ERR_NOMEM, "polygons: out of memory for %zu triangles", nt);
    }
    for (size_t i = 0; i < nt; i++) {
        tb__bprim *p = &c.prims[i];
        for (int a = 0; a < 3; a++) {
            p->lo[a] = INFINITY;
            p->hi[a] = -INFINITY;
        }
        for (int k = 0; k < 3; k++) {
            /* World positions rounded outward to float, so the box holds them. */
            const double *v = &m->wvertices[3 * (size_t)tv[3 * i + k]];
            float lo[3] = {tb_float_round_down(v[0]), tb_float_round_down(v[1]), tb_float_round_down(v[2])};
            float hi[3] = {tb_float_round_up(v[0]), tb_float_round_up(v[1]), tb_float_round_up(v[2])};
            tb__grow(p->lo, p->hi, lo, hi);
        }
        for (int a = 0; a < 3; a++)
            p->c[a] = 0.5f * p->lo[a] + 0.5f * p->hi[a];
        c.order[i] = (uint32_t)i;
    }
    /* A face's triangles are consecutive here. */
    for (size_t i = 0; uv0 && i < nt;) {
        uint32_t f = TB_ARRAY_AT(&faces, uint32_t, i);
        size_t j = i;
        while (j < nt && TB_ARRAY_AT(&faces, uint32_t, j) == f)
            j++;
        tb__corner_uv(g, (int)f, &tv[3 * i], j - i, &uv0[6 * i]);
        i = j;
    }
    if (nt > 0)
        tb__build_node(&c, 0, (uint32_t)nt, 0);
    for (size_t i = 0; i < nt; i++) {
        uint32_t t = c.order[i];
        memcpy(&m->tris[3 * i], &tv[3 * t], sizeof(uint32_t) * 3);
        m->tri_face[i] = TB_ARRAY_AT(&faces, uint32_t, t);
        if (uv0)
            memcpy(&m->tri_uv[6 * i], &uv0[6 * (size_t)t], sizeof(float) * 6);
    }
    free(uv0);
    m->nnodes = c.nnodes;
    m->nodes = c.nodes;
    free(c.prims);
    free(c.order);
    tb_array_free(&tris);
    tb_array_free(&faces);
    o->closed = m->closed;
    /* Hits report the normal of the triangle they land on: computed once. */
    m->wnormal = malloc(sizeof *m->wnormal * (nt ? nt : 1));
    if (!m->wnormal)
        return tb_error(TB_ERR_NOMEM, "polygons: out of memory for %zu triangles", nt);
    for (size_t i = 0; i < nt; i++)
        m->wnormal[i] = tb__tri_world_normal(o, (uint32_t)i);
    return TB_OK;
}

/* ------------------------------------------------------------------ traversal */

/* The ray prepared for the watertight test and the box test. */
typedef struct tb__wray {
    tb_wt_ray t;           /* the triangle test's part */
    double d[3];           /* direction (near child first) */
    double inv[3];         /* 1 / d */
    int nearp[3], farp[3]; /* per axis: index into a node's lo[]/hi[] pair of the near and far plane */
} tb__wray;

static void tb__wray_init(tb__wray *w, const tb_ray *r)
{
    tb_wt_ray_init(&w->t, r);
    w->d[0] = r->d.x;
    w->d[1] = r->d.y;
    w->d[2] = r->d.z;
    for (int i = 0; i < 3; i++) {
        w->inv[i] = 1.0 / w->d[i];
        bool neg = signbit(w->inv[i]);
        w->nearp[i] = i + (neg ? 3 : 0);
        w->farp[i] = i + (neg ? 0 : 3);
    }
}

/* Slab test of a node's box in double; the near/far plane is chosen by the
 * sign bit of 1/d so a zero component works (a NaN from 0 * inf, the origin
 * exactly on a plane, leaves the interval unchanged: inside a closed box).
 * Each plane's t has a relative error of at most 3 double roundings, and the
 * triangle test may accept a point a few roundings (relative to its distance
 * from the origin) outside its triangle, so the slab is widened by a
 * relative 2^-48 at both ends (Ize 2013, in double). */
static bool tb__box(const tb_object_bvh_node *nd, const tb__wray *w, double tmin, double tmax)
{
    const float *b = nd->b; /* plane j (0 lo, 1 hi) of axis i is b[i + 3 j] */
    const double *o = w->t.o;
    double t0 = (b[w->nearp[0]] - o[0]) * w->inv[0], t1 = (b[w->farp[0]] - o[0]) * w->inv[0];
    double a1 = (b[w->nearp[1]] - o[1]) * w->inv[1], b1 = (b[w->farp[1]] - o[1]) * w->inv[1];
    double a2 = (b[w->nearp[2]] - o[2]) * w->inv[2], b2 = (b[w->farp[2]] - o[2]) * w->inv[2];
    /* Written so that a NaN (0 * inf) never wins a comparison. */
    if (!(t0 >= -INFINITY))
        t0 = -INFINITY;
    if (!(t1 <= INFINITY))
        t1 = INFINITY;
    if (a1 > t0)
        t0 = a1;
    if (a2 > t0)
        t0 = a2;
    if (b1 < t1)
        t1 = b1;
    if (b2 < t1)
        t1 = b2;
    if (t0 > -INFINITY && t0 < INFINITY)
        t0 -= fabs(t0) * 0x1p-48;
    if (t1 > -INFINITY && t1 < INFINITY)
        t1 += fabs(t1) * 0x1p-48;
    return t0 <= t1 && t0 <= tmax && t1 >= tmin;
}

/* Sign of the edge function E(P, Q) = Qx Py - Qy Px, exact. */
static int tb__edge_sign(double e, double px, double py, double qx, double qy)
{
    if (e != 0.0)
        return e > 0.0 ? 1 : -1;
    return -tb_orient2d_sign(px, py, qx, qy, 0.0, 0.0);
}

/* Tie rule for an edge P -> Q through the ray: claimed if the ray shifted by
 * (eps, eps^2) would be inside, i.e. s (Q - P) has y > 0, or y == 0 and x < 0. */
static bool tb__claims(int s, double px, double py, double qx, double qy)
{
    double ex = s * (qx - px), ey = s * (qy - py);
    return ey > 0.0 || (ey == 0.0 && ex < 0.0);
}

bool tb_wt_edge_ties(double U, double V, double W, double ax, double ay, double bx, double by, double cx, double cy)
{
    int su = tb__edge_sign(U, bx, by, cx, cy);
    int sv = tb__edge_sign(V, cx, cy, ax, ay);
    int sw = tb__edge_sign(W, ax, ay, bx, by);
    if ((su < 0 || sv < 0 || sw < 0) && (su > 0 || sv > 0 || sw > 0))
        return false;
    int s = su + sv + sw > 0 ? 1 : (su + sv + sw < 0 ? -1 : 0);
    if (s == 0)
        return false; /* the triangle is edge-on to the ray */
    return !((su == 0 && !tb__claims(s, bx, by, cx, cy)) || (sv == 0 && !tb__claims(s, cx, cy, ax, ay)) ||
             (sw == 0 && !tb__claims(s, ax, ay, bx, by)));
}

static tb_dvec3 tb__tri_normal(const tb_object_mesh *m, uint32_t i)
{
    const uint32_t *t = &m->tris[3 * i];
    tb_vec3 v0 = m->vertices[t[0]], v1 = m->vertices[t[1]], v2 = m->vertices[t[2]];
    tb_dvec3 e1 = {(double)v1.x - v0.x, (double)v1.y - v0.y, (double)v1.z - v0.z};
    tb_dvec3 e2 = {(double)v2.x - v0.x, (double)v2.y - v0.y, (double)v2.z - v0.z};
    tb_dvec3 n = tb_dvec3_cross(e1, e2);
    if (n.x == 0.0 && n.y == 0.0 && n.z == 0.0)
        n.z = 1.0;
    return n;
}

/* Visits triangles whose boxes the ray passes within [tmin, *tmax]; `mode`
 * 0: closest (shrinks *tmax), 1: any (stops), 2: all (collects into out). */
static bool tb__traverse(const tb_object *o, const tb_ray *ray, double tmin, double *tmax, int mode, tb__xing *hit,
                         tb__xbuf *out)
{
    const tb_object_mesh *m = o->mesh;
    if (!m || m->nnodes == 0)
        return false;
    tb__wray w;
    tb__wray_init(&w, ray);
    uint32_t stack[TB__BVH_STACK];
    int sp = 0;
    stack[sp++] = 0;
    bool found = false;
    double bmin = tb_next_float_down((float)tmin), tlast = *tmax, bmax = tb_next_float_up((float)tlast);
    while (sp > 0) {
        const tb_object_bvh_node *nd = &m->nodes[stack[--sp]];
        /* Hits are accepted on their float t, so the boxes are tested one float wider. */
        if (*tmax != tlast) {
            tlast = *tmax;
            bmax = tb_next_float_up((float)tlast);
        }
        if (!tb__box(nd, &w, bmin, bmax))
            continue;
        if (nd->count == 0) {
            uint32_t left = (uint32_t)(nd - m->nodes) + 1, right = nd->index;
            if (sp + 2 > TB__BVH_STACK)
                continue; /* cannot happen for trees built here (depth is bounded) */
            /* Near child on top. */
            if (w.d[nd->axis] < 0.0) {
                stack[sp++] = left;
                stack[sp++] = right;
            } else {
                stack[sp++] = right;
                stack[sp++] = left;
            }
            continue;
        }
        for (uint32_t i = nd->index; i < nd->index + nd->count; i++) {
            const uint32_t *tv = &m->tris[3 * i];
            double t;
            int dir;
            if (!tb_wt_triangle(&w.t, &m->wvertices[3 * (size_t)tv[0]], &m->wvertices[3 * (size_t)tv[1]],
                         &m->wvertices[3 * (size_t)tv[2]], &t, &dir, NULL))
                continue;
            dir *= m->wsign;
            if (!((float)t >= tmin && (float)t <= *tmax)) /* on the float t, as intersect.c */
                continue;
            bool had = found;
            found = true;
            tb__xing x = {t, {0, 0, 0}, o, m->tri_face[i], i, dir};
            if (mode == 1)
                return true;
            if (mode == 0) {
                /* The closest hit is the least in the scene's tie rule
                 * (docs/accel.md): float t, then face, then triangle, so the
                 * order the BVH meets triangles hit at one float t (a ray
                 * through a fold of a non-planar polygon crosses both of its
                 * triangles there) does not decide, and the record is the
                 * scene's per-triangle one. tmax keeps the best float t, so
                 * later triangles tying with it are still tested. */
                if (had && (float)t == (float)hit->t &&
                    (x.face > hit->face || (x.face == hit->face && i > hit->tri)))
                    continue;
                x.n = tb__tri_normal(m, i);
                *tmax = (float)t;
                *hit = x;
            } else {
                x.n = tb__tri_normal(m, i);
                tb__xbuf_push(out, &x);
            }
        }
    }
    return found;
}

bool tb__mesh_closest(const tb_object *o, const tb_ray *ray, double tmin, double tmax, tb__xing *hit)
{
    return tb__traverse(o, ray, tmin, &tmax, 0, hit, NULL);
}

bool tb__mesh_any(const tb_object *o, const tb_ray *ray, double tmin, double tmax)
{
    return tb__traverse(o, ray, tmin, &tmax, 1, NULL, NULL);
}

static int tb__xing_cmp(const void *pa, const void *pb)
{
    const tb__xing *a = pa, *b = pb;
    if (a->t != b->t)
        return a->t < b->t ? -1 : 1;
    return (a->tri > b->tri) - (a->tri < b->tri);
}

void tb__xings_mesh(const tb_object *o, const tb__oray *r, tb__xbuf *out)
{
    tb__xbuf all;
    tb__xbuf_init(&all);
    double tmax = INFINITY;
    tb__traverse(o, r->world, -INFINITY, &tmax, 2, NULL, &all);
    if (all.oom)
        out->oom = true;
    qsort(all.x, (size_t)all.n, sizeof *all.x, tb__xing_cmp);
    if (!o->mesh->closed) {
        for (int i = 0; i < all.n; i++)
            tb__xbuf_push(out, &all.x[i]);
    } else {
        /* Winding number along the line: inside where it is positive. Each
         * crossing is counted exactly once (see the top of the file), so a
         * closed mesh gives whole intervals even through edges and vertices. */
        int wnd = 0;
        for (int i = 0; i < all.n; i++) {
            int next = wnd + all.x[i].dir;
            if (wnd <= 0 && next > 0) {
                tb__xing x = all.x[i];
                x.dir = +1;
                tb__xbuf_push(out, &x);
            } else if (wnd > 0 && next <= 0) {
                tb__xing x = all.x[i];
                x.dir = -1;
                tb__xbuf_push(out, &x);
            }
            wnd = next;
        }
        if (wnd > 0 && out->n % 2 == 1) { /* unbalanced (a lost crossing): close the interval */
            tb__xing x = out->x[out->n - 1];
            x.dir = -1;
            tb__xbuf_push(out, &x);
        }
    }
    tb__xbuf_free(&all);
}

/* ------------------------------------------------------------ one triangle */

/* A thread's last prepared ray: callers of the one-triangle functions below
 * (the ray-cast form factors' triangle references, the winner's (u, v)
 * after a mesh query) ask with one ray again and again, and preparing it
 * costs about as much as a test. It depends on the world ray only (the test is in world space),
 * whichever mesh asks. */
typedef struct tb__wt_memo {
    bool valid;
    tb_vec3 o, d; /* the key: what the preparation depends on, compared bit for bit */
    tb_wt_ray w;
} tb__wt_memo;

static _Thread_local tb__wt_memo tb__memo;

/* The prepared ray for `ray`, from the memo when it holds that ray (then it
 * is what tb_wt_ray_init gives), else prepared now and kept. */
static const tb_wt_ray *tb__memo_ray(const tb_ray *ray)
{
    tb__wt_memo *c = &tb__memo;
    if (!c->valid || memcmp(&c->o, &ray->o, sizeof c->o) != 0 || memcmp(&c->d, &ray->d, sizeof c->d) != 0) {
        tb_wt_ray_init(&c->w, ray);
        c->o = ray->o;
        c->d = ray->d;
        c->valid = true;
    }
    return &c->w;
}

bool tb_object_triangle_crossing(const tb_object *o, uint32_t tri, const tb_ray *ray, double *t)
{
    const tb_object_mesh *m = o->mesh;
    if (!m || tri >= m->ntris)
        return false;
    const tb_wt_ray *w = tb__memo_ray(ray);
    const uint32_t *tv = &m->tris[3 * (size_t)tri];
    int dir;
    return tb_wt_triangle(w, &m->wvertices[3 * (size_t)tv[0]], &m->wvertices[3 * (size_t)tv[1]],
                   &m->wvertices[3 * (size_t)tv[2]], t, &dir, NULL);
}


bool tb__mesh_tri_weights(const tb_object *o, uint32_t tri, const tb_ray *ray, double uvw[3])
{
    const tb_object_mesh *m = o->mesh;
    const tb_wt_ray *w = tb__memo_ray(ray);
    const uint32_t *tv = &m->tris[3 * (size_t)tri];
    double t;
    int dir;
    return tb_wt_triangle(w, &m->wvertices[3 * (size_t)tv[0]], &m->wvertices[3 * (size_t)tv[1]],
                          &m->wvertices[3 * (size_t)tv[2]], &t, &dir, uvw);
}

bool tb_object_triangle_uv(const tb_object *obj, uint32_t tri, const double uvw[3], double *u, double *v)
{
    const tb_object_mesh *m = obj->mesh;
    float cc[6];
    const float *c = cc;
    if (m->tri_uv)
        c = &m->tri_uv[6 * (size_t)tri];
    else if (!tb__corner_uv(&obj->geom.polygons, (int)m->tri_face[tri], &m->tris[3 * (size_t)tri], 1, cc))
        return false;
    /* U V W share one sign (or are 0) and det is their sum: a convex mix,
     * with one division. */
    double inv = 1.0 / (uvw[0] + uvw[1] + uvw[2]);
    double su = (uvw[0] * c[0] + uvw[1] * c[2] + uvw[2] * c[4]) * inv;
    double sv = (uvw[0] * c[1] + uvw[1] * c[3] + uvw[2] * c[5]) * inv;
    /* Rounding may step past the corners' range by an ulp: [0, 1] as param. */
    *u = su < 0.0 ? 0.0 : su > 1.0 ? 1.0 : su;
    *v = sv < 0.0 ? 0.0 : sv > 1.0 ? 1.0 : sv;
    return true;
}
