/* Meshing FED faces into conforming triangle/quad elements: edge splitting,
 * regular grids, triangulation + longest-edge bisection, and quad pairing
 * (docs/meshing.md, "Subdivision" and "Quads"). */
#include "util/mesh/mesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "util/container/hash_table.h"
#include "util/container/pqueue.h"
#include "util/math/float.h"
#include "util/mesh/polygon.h"
#include "util/mesh/triangulate.h"

void tb_mesh_init(tb_mesh *m)
{
    tb_array_init(&m->positions, sizeof(tb_vec3));
    tb_array_init(&m->normals, sizeof(tb_vec3));
    tb_array_init(&m->uvs, sizeof(tb_vec2));
    tb_array_init(&m->elems, sizeof(tb_mesh_elem));
}

void tb_mesh_free(tb_mesh *m)
{
    tb_array_free(&m->positions);
    tb_array_free(&m->normals);
    tb_array_free(&m->uvs);
    tb_array_free(&m->elems);
}

static inline tb_vec3 tb__pos(const tb_mesh *m, uint32_t i) { return TB_ARRAY_AT(&m->positions, tb_vec3, i); }

double tb_mesh_elem_area(const tb_mesh *m, size_t i)
{
    const tb_mesh_elem *e = tb_mesh_elem_at(m, i);
    tb_vec3 q[4];
    int n = tb_mesh_elem_size(e);
    for (int k = 0; k < n; k++)
        q[k] = tb__pos(m, e->v[k]);
    tb_dvec3 nv = tb_polygon_newell(q, NULL, (uint32_t)n);
    return 0.5 * sqrt(nv.x * nv.x + nv.y * nv.y + nv.z * nv.z);
}

tb_status tb_mesh_to_fed(const tb_mesh *m, bool attributes, tb_fed **out)
{
    *out = NULL;
    size_t ne = m->elems.len, nv = m->positions.len;
    if (ne > TB_FED_MAX_COUNT || nv > TB_FED_MAX_COUNT)
        return tb_error(TB_ERR_ARG, "mesh to FED: too many elements or vertices");
    uint32_t *sizes = malloc(sizeof(uint32_t) * (ne + 1)), *corners = malloc(sizeof(uint32_t) * (4 * ne + 1));
    if (!sizes || !corners) {
        free(sizes), free(corners);
        return tb_error(TB_ERR_NOMEM, "mesh to FED: out of memory");
    }
    uint32_t nc = 0;
    for (size_t i = 0; i < ne; i++) {
        const tb_mesh_elem *e = tb_mesh_elem_at(m, i);
        sizes[i] = (uint32_t)tb_mesh_elem_size(e);
        for (uint32_t k = 0; k < sizes[i]; k++)
            corners[nc++] = e->v[k];
    }
    tb_fed_desc d = {.nverts = (uint32_t)nv,
                     .positions = m->positions.data,
                     .normals = attributes && m->normals.len == nv ? m->normals.data : NULL,
                     .uvs = attributes && m->uvs.len == nv ? m->uvs.data : NULL,
                     .nfaces = (uint32_t)ne,
                     .nloops = (uint32_t)ne,
                     .loop_sizes = sizes,
                     .corners = corners};
    tb_status st = tb_fed_build(&d, out, NULL);
    free(sizes), free(corners);
    return st;
}

tb_status tb_mesh_adjacency(const tb_mesh *m, tb_fed **out) { return tb_mesh_to_fed(m, false, out); }

bool tb_mesh_quad_check(const tb_vec3 q[4], double rel_tol, double *score)
{
    if (!tb_polygon_is_planar(q, NULL, 4, rel_tol))
        return false;
    tb_dvec3 n = tb_polygon_newell(q, NULL, 4);
    double len = sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
    if (!(len > 0))
        return false;
    n.x /= len, n.y /= len, n.z /= len;
    const double lo = tb_radians(TB_MESH_QUAD_MIN_ANGLE), hi = TB_PI - lo;
    double worst = 0;
    for (int i = 0; i < 4; i++) {
        tb_vec3 p = q[i], nx = q[(i + 1) % 4], pv = q[(i + 3) % 4];
        double ux = (double)nx.x - p.x, uy = (double)nx.y - p.y, uz = (double)nx.z - p.z;
        double wx = (double)pv.x - p.x, wy = (double)pv.y - p.y, wz = (double)pv.z - p.z;
        double cr = (uy * wz - uz * wy) * n.x + (uz * wx - ux * wz) * n.y + (ux * wy - uy * wx) * n.z;
        double dt = ux * wx + uy * wy + uz * wz;
        if (!(cr > 0))
            return false; /* reflex or flat corner: not strictly convex */
        double ang = atan2(cr, dt);
        if (ang < lo || ang > hi)
            return false;
        worst = fmax(worst, fabs(ang - TB_PI_2));
    }
    if (score)
        *score = worst;
    return true;
}

/* ------------------------------------------------------------------ context */

typedef struct tb__mctx {
    const tb_fed *fed;
    tb_mesh *out;
    double L;           /* edge bound (INFINITY: none) */
    double tol;         /* planarity tolerance */
    bool quads;
    uint32_t *edge_k;     /* per FED edge: parts it is cut into */
    uint32_t *edge_first; /* per FED edge: its first inner vertex (the rest follow, from v[0] to v[1]) */
    tb_array ring;        /* uint32_t: boundary vertices of the face being meshed */
    tb_array ring_sizes;  /* uint32_t */
    tb_array tris;        /* tb_tri: the face's triangles */
    tb_status err;        /* first failure inside a helper without a status */
} tb__mctx;

tb_status tb_mesh_push_attributes(tb_mesh *m, int n, const uint32_t *idx, const double *w)
{
    tb_status st = TB_OK;
    /* With w NULL the weight 1 multiplies exactly: plain sums, and the uv
     * mean is one scaling at the end (as refine.c's midpoints always had). */
    if (m->normals.len) {
        double nx = 0, ny = 0, nz = 0;
        for (int i = 0; i < n; i++) {
            tb_vec3 q = TB_ARRAY_AT(&m->normals, tb_vec3, idx[i]);
            double wi = w ? w[i] : 1.0;
            nx += wi * q.x, ny += wi * q.y, nz += wi * q.z;
        }
        double len = sqrt(nx * nx + ny * ny + nz * nz);
        tb_vec3 q = len > 0 ? (tb_vec3){(float)(nx / len), (float)(ny / len), (float)(nz / len)}
                            : TB_ARRAY_AT(&m->normals, tb_vec3, idx[0]);
        st = tb_array_push(&m->normals, &q);
    }
    if (!st && m->uvs.len) {
        double u = 0, v = 0;
        for (int i = 0; i < n; i++) {
            tb_vec2 q = TB_ARRAY_AT(&m->uvs, tb_vec2, idx[i]);
            double wi = w ? w[i] : 1.0;
            u += wi * q.x, v += wi * q.y;
        }
        double s = w ? 1.0 : 1.0 / n;
        tb_vec2 q = {(float)(u * s), (float)(v * s)};
        st = tb_array_push(&m->uvs, &q);
    }
    return st;
}

/* A new vertex: the affine combination sum w[i] * vertex idx[i] of
 * position, normal (renormalised) and uv. Returns its index. */
static uint32_t tb__vertex(tb__mctx *c, int n, const uint32_t *idx, const double *w)
{
    tb_mesh *m = c->out;
    if (m->positions.len >= TB_FED_MAX_COUNT) {
        if (!c->err)
            c->err = tb_error(TB_ERR_ARG, "meshing: more than %u vertices", TB_FED_MAX_COUNT);
        return 0;
    }
    /* Position relative to the first vertex, so that a combination of equal
     * points is that point exactly. */
    tb_vec3 p0 = tb__pos(m, idx[0]);
    double x = 0, y = 0, z = 0;
    for (int i = 1; i < n; i++) {
        tb_vec3 p = tb__pos(m, idx[i]);
        x += w[i] * ((double)p.x - p0.x);
        y += w[i] * ((double)p.y - p0.y);
        z += w[i] * ((double)p.z - p0.z);
    }
    tb_vec3 p = {(float)(p0.x + x), (float)(p0.y + y), (float)(p0.z + z)};
    tb_status st = tb_array_push(&m->positions, &p);
    if (!st)
        st = tb_mesh_push_attributes(m, n, idx, w);
    if (st && !c->err)
        c->err = st;
    return (uint32_t)(m->positions.len - 1);
}

static void tb__emit(tb__mctx *c, uint32_t a, uint32_t b, uint32_t d, uint32_t e, uint32_t face)
{
    tb_mesh_elem el = {{a, b, d, e}, face, TB_MESH_NONE};
    tb_status st = tb_array_push(&c->out->elems, &el);
    if (st && !c->err)
        c->err = st;
}

/* Parts a segment of length len is cut into. */
static uint32_t tb__parts(const tb__mctx *c, double len)
{
    if (!isfinite(c->L))
        return 1;
    double k = ceil(len / c->L);
    return k < 1 ? 1 : (uint32_t)k; /* bounded by the size check in tb_mesh_from_fed */
}

static double tb__dist(const tb_mesh *m, uint32_t a, uint32_t b)
{
    tb_vec3 p = tb__pos(m, a), q = tb__pos(m, b);
    double dx = (double)q.x - p.x, dy = (double)q.y - p.y, dz = (double)q.z - p.z;
    return sqrt(dx * dx + dy * dy + dz * dz);
}

/* One side of a face: from vertex a to vertex b in k parts, whose inner
 * vertices are first .. first + k - 2 in the direction `rev` says. */
typedef struct tb__side {
    uint32_t a, b, k, first;
    bool rev; /* the inner vertices run from b to a */
} tb__side;

/* Inner vertex j (1 .. k-1, counted from a) of a side. */
static inline uint32_t tb__side_pt(const tb__side *s, uint32_t j)
{
    return s->rev ? s->first + (s->k - 1 - j) : s->first + (j - 1);
}

/* The side along FED edge e, walked from vertex a. */
static tb__side tb__edge_side(const tb__mctx *c, uint32_t e, uint32_t a)
{
    const tb_fed_edge *ed = &c->fed->edges[e];
    return (tb__side){a, ed->v[0] == a ? ed->v[1] : ed->v[0], c->edge_k[e], c->edge_first[e], ed->v[0] != a};
}

/* A new side from a to b with its own inner vertices (a diagonal). */
static tb__side tb__new_side(tb__mctx *c, uint32_t a, uint32_t b)
{
    tb__side s = {a, b, tb__parts(c, tb__dist(c->out, a, b)), (uint32_t)c->out->positions.len, false};
    for (uint32_t j = 1; j < s.k; j++) {
        double t = (double)j / s.k;
        tb__vertex(c, 2, (uint32_t[]){a, b}, (double[]){1 - t, t});
    }
    return s;
}

/* ------------------------------------------------------------ quad pairing */

/* A candidate quad: triangles i < j over a shared edge and the quad they make. */
typedef struct tb__cand {
    double score; /* tb_mesh_quad_check's score: lower is better */
    uint32_t i, j;
    uint32_t q[4];
} tb__cand;

static int tb__cand_cmp(const void *x, const void *y)
{
    const tb__cand *a = x, *b = y;
    if (a->score != b->score)
        return a->score < b->score ? -1 : 1;
    if (a->i != b->i)
        return a->i < b->i ? -1 : 1;
    return (a->j > b->j) - (a->j < b->j);
}

/* Emits the face's triangles, paired into quads where the criterion allows. */
static void tb__emit_tris(tb__mctx *c, uint32_t face)
{
    const tb_tri *t = c->tris.data;
    uint32_t n = (uint32_t)c->tris.len;
    if (!c->quads || n < 2) {
        for (uint32_t i = 0; i < n; i++)
            tb__emit(c, t[i].v[0], t[i].v[1], t[i].v[2], TB_MESH_NONE, face);
        return;
    }
    /* Candidate pairs over shared edges, best first; greedy matching. */
    tb_htab h;
    tb_htab_init(&h, TB_HTAB_U64);
    tb__cand *cand = malloc(sizeof(tb__cand) * ((size_t)3 * n / 2 + 1));
    uint32_t *partner = malloc(sizeof(uint32_t) * n);
    uint32_t (*quad)[4] = malloc(sizeof *quad * n);
    size_t nc = 0;
    tb_status st = (!cand || !partner || !quad) ? tb_error(TB_ERR_NOMEM, "meshing: out of memory") : TB_OK;
    for (uint32_t i = 0; i < n && !st; i++) {
        partner[i] = TB_MESH_NONE;
        for (int s = 0; s < 3 && !st; s++) {
            uint32_t a = t[i].v[s], b = t[i].v[(s + 1) % 3];
            uint64_t key = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a, other;
            if (!tb_htab_get(&h, key, &other)) {
                st = tb_htab_put(&h, key, (uint64_t)i * 3 + (uint64_t)s);
                continue;
            }
            uint32_t j = (uint32_t)(other / 3), sj = (uint32_t)(other % 3);
            if (t[j].v[sj] != b || t[j].v[(sj + 1) % 3] != a)
                continue; /* same direction: not a consistent pair */
            uint32_t q[4] = {a, t[j].v[(sj + 2) % 3], b, t[i].v[(s + 2) % 3]};
            tb_vec3 qp[4];
            for (int k = 0; k < 4; k++)
                qp[k] = tb__pos(c->out, q[k]);
            double score;
            if (tb_mesh_quad_check(qp, c->tol, &score)) {
                tb__cand *r = &cand[nc++];
                *r = (tb__cand){score, j, i, {q[0], q[1], q[2], q[3]}};
            }
        }
    }
    if (!st) {
        qsort(cand, nc, sizeof(tb__cand), tb__cand_cmp);
        for (size_t k = 0; k < nc; k++) {
            uint32_t i = cand[k].i, j = cand[k].j;
            if (partner[i] != TB_MESH_NONE || partner[j] != TB_MESH_NONE)
                continue;
            partner[i] = j;
            partner[j] = i;
            memcpy(quad[i], cand[k].q, sizeof cand[k].q);
        }
        for (uint32_t i = 0; i < n; i++) {
            if (partner[i] == TB_MESH_NONE)
                tb__emit(c, t[i].v[0], t[i].v[1], t[i].v[2], TB_MESH_NONE, face);
            else if (partner[i] > i)
                tb__emit(c, quad[i][0], quad[i][1], quad[i][2], quad[i][3], face);
        }
    }
    if (st && !c->err)
        c->err = st;
    tb_htab_free(&h);
    free(cand);
    free(partner);
    free(quad);
}

static tb_status tb__refine(tb__mctx *c);

/* --------------------------------------------------------- regular patterns */

static void tb__push_tri(tb__mctx *c, uint32_t a, uint32_t b, uint32_t d)
{
    tb_tri t = {{a, b, d}};
    tb_status st = tb_array_push(&c->tris, &t);
    if (st && !c->err)
        c->err = st;
}

/* The regular k x k subdivision of a triangle whose three sides have k parts. */
static void tb__grid_triangle(tb__mctx *c, const tb__side s[3], uint32_t face)
{
    uint32_t k = s[0].k;
    uint32_t A = s[0].a, B = s[1].a, C = s[2].a;
    /* P(i, j) = A + (B - A) i/k + (C - A) j/k, for i + j <= k, stored row by row. */
    size_t np = (size_t)(k + 1) * (k + 2) / 2;
    uint32_t *P = malloc(sizeof(uint32_t) * np), *row = malloc(sizeof(uint32_t) * (k + 2));
    if (!P || !row) {
        free(P), free(row);
        if (!c->err)
            c->err = tb_error(TB_ERR_NOMEM, "meshing: out of memory");
        return;
    }
    for (uint32_t j = 0, at = 0; j <= k; j++) {
        row[j] = at;
        at += k + 1 - j;
    }
#define TB__P(i, j) P[row[j] + (i)]
    for (uint32_t j = 0; j <= k; j++)
        for (uint32_t i = 0; i + j <= k; i++) {
            uint32_t v;
            if (j == 0)
                v = i == 0 ? A : (i == k ? B : tb__side_pt(&s[0], i)); /* A -> B */
            else if (i + j == k)
                v = j == k ? C : tb__side_pt(&s[1], j);                /* B -> C */
            else if (i == 0)
                v = tb__side_pt(&s[2], k - j);                         /* C -> A */
            else
                v = tb__vertex(c, 3, (uint32_t[]){A, B, C},
                               (double[]){1 - (double)(i + j) / k, (double)i / k, (double)j / k});
            TB__P(i, j) = v;
        }
    /* The pattern's rows of parallelograms are the natural quads: each cell
     * (i, j) pairs its two triangles over the diagonal P(i+1, j)-P(i, j+1)
     * when the parallelogram passes the criterion; the rest stay triangles. */
    c->tris.len = 0;
    for (uint32_t j = 0; j < k; j++)
        for (uint32_t i = 0; i + j < k; i++) {
            uint32_t a = TB__P(i, j), b = TB__P(i + 1, j), d = TB__P(i, j + 1);
            if (i + j + 1 < k) {
                uint32_t e = TB__P(i + 1, j + 1);
                tb_vec3 qp[4] = {tb__pos(c->out, a), tb__pos(c->out, b), tb__pos(c->out, e), tb__pos(c->out, d)};
                if (c->quads && tb_mesh_quad_check(qp, c->tol, NULL)) {
                    tb__emit(c, a, b, e, d, face);
                    continue;
                }
                tb__push_tri(c, b, e, d);
            }
            tb__push_tri(c, a, b, d);
        }
    bool quads = c->quads;
    c->quads = false; /* whatever did not pair as a parallelogram stays triangles */
    tb__emit_tris(c, face);
    c->quads = quads;
#undef TB__P
    free(P), free(row);
}

/* The bilinear ku x kv grid of a planar convex quad with matching opposite sides. */
static void tb__grid_quad(tb__mctx *c, const tb__side s[4], uint32_t face)
{
    uint32_t ku = s[0].k, kv = s[1].k;
    uint32_t A = s[0].a, B = s[1].a, C = s[2].a, D = s[3].a;
    uint32_t *P = malloc(sizeof(uint32_t) * (size_t)(ku + 1) * (kv + 1));
    if (!P) {
        if (!c->err)
            c->err = tb_error(TB_ERR_NOMEM, "meshing: out of memory");
        return;
    }
#define TB__Q(i, j) P[(size_t)(j) * (ku + 1) + (i)]
    for (uint32_t j = 0; j <= kv; j++)
        for (uint32_t i = 0; i <= ku; i++) {
            uint32_t v;
            if (j == 0)
                v = i == 0 ? A : (i == ku ? B : tb__side_pt(&s[0], i));
            else if (i == ku)
                v = j == kv ? C : tb__side_pt(&s[1], j);
            else if (j == kv)
                v = i == 0 ? D : tb__side_pt(&s[2], ku - i);
            else if (i == 0)
                v = tb__side_pt(&s[3], kv - j);
            else {
                double u = (double)i / ku, w = (double)j / kv;
                v = tb__vertex(c, 4, (uint32_t[]){A, B, C, D},
                               (double[]){(1 - u) * (1 - w), u * (1 - w), u * w, (1 - u) * w});
            }
            TB__Q(i, j) = v;
        }
    /* Cells that pass the quad criterion (when quads are wanted) are
     * elements; the others are split along their shorter diagonal, and the
     * diagonals are then bisected where longer than the bound (they are
     * interior to the face, so this cannot affect a neighbour). */
    c->tris.len = 0;
    for (uint32_t j = 0; j < kv; j++)
        for (uint32_t i = 0; i < ku; i++) {
            uint32_t q[4] = {TB__Q(i, j), TB__Q(i + 1, j), TB__Q(i + 1, j + 1), TB__Q(i, j + 1)};
            tb_vec3 qp[4];
            for (int k = 0; k < 4; k++)
                qp[k] = tb__pos(c->out, q[k]);
            if (c->quads && tb_mesh_quad_check(qp, c->tol, NULL)) {
                tb__emit(c, q[0], q[1], q[2], q[3], face);
            } else {
                uint32_t t[6];
                tb_quad_split_corners(tb_quad_split_diagonal(qp[0], qp[1], qp[2], qp[3]), t);
                tb__push_tri(c, q[t[0]], q[t[1]], q[t[2]]);
                tb__push_tri(c, q[t[3]], q[t[4]], q[t[5]]);
            }
        }
    tb_status st = tb__refine(c);
    if (st && !c->err)
        c->err = st;
    if (!c->err)
        tb__emit_tris(c, face);
#undef TB__Q
    free(P);
}

/* ------------------------------------------------ longest-edge refinement */

typedef struct tb__redge {
    uint32_t a, b;
    uint32_t t[2]; /* its triangles (t[1] NONE on the face boundary) */
} tb__redge;

/* The face's triangles (c->tris) with an edge map, for splitting edges
 * together with all their triangles. */
typedef struct tb__refiner {
    tb__mctx *c;
    tb_htab map;    /* vertex pair -> edge id */
    tb_array edges; /* tb__redge */
    tb_pqueue pq;   /* interior edges longer than L, longest first */
} tb__refiner;

static inline uint64_t tb__key(uint32_t a, uint32_t b)
{
    return a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
}

/* Records that triangle t uses edge a-b; queues the edge once it is interior and too long. */
static tb_status tb__use_edge(tb__refiner *r, uint32_t a, uint32_t b, uint32_t t)
{
    uint64_t key = tb__key(a, b), id;
    if (tb_htab_get(&r->map, key, &id)) {
        tb__redge *e = &TB_ARRAY_AT(&r->edges, tb__redge, id);
        e->t[1] = t;
        double len = tb__dist(r->c->out, a, b);
        return len > r->c->L ? tb_pqueue_set(&r->pq, (uint32_t)id, len) : TB_OK;
    }
    tb__redge e = {a, b, {t, TB_MESH_NONE}};
    tb_status st = tb_array_push(&r->edges, &e);
    return st ? st : tb_htab_put(&r->map, key, r->edges.len - 1);
}

/* In edge a-b, replaces triangle `from` by `to`. */
static void tb__retarget(tb__refiner *r, uint32_t a, uint32_t b, uint32_t from, uint32_t to)
{
    uint64_t id;
    if (!tb_htab_get(&r->map, tb__key(a, b), &id))
        return;
    tb__redge *e = &TB_ARRAY_AT(&r->edges, tb__redge, id);
    for (int k = 0; k < 2; k++)
        if (e->t[k] == from)
            e->t[k] = to;
}

static tb_status tb__refiner_begin(tb__refiner *r, tb__mctx *c)
{
    *r = (tb__refiner){.c = c};
    tb_htab_init(&r->map, TB_HTAB_U64);
    tb_array_init(&r->edges, sizeof(tb__redge));
    tb_pqueue_init(&r->pq);
    tb_status st = TB_OK;
    for (uint32_t i = 0; i < c->tris.len && !st; i++) {
        tb_tri t = TB_ARRAY_AT(&c->tris, tb_tri, i);
        for (int s = 0; s < 3 && !st; s++)
            st = tb__use_edge(r, t.v[s], t.v[(s + 1) % 3], i);
    }
    return st;
}

static void tb__refiner_end(tb__refiner *r)
{
    tb_htab_free(&r->map);
    tb_array_free(&r->edges);
    tb_pqueue_free(&r->pq);
}

/* Splits edge x-y at vertex m, together with each triangle using it: a
 * triangle (u v w) with the edge as u -> v becomes (u m w) and (m v w). */
static tb_status tb__split_edge(tb__refiner *r, uint32_t x, uint32_t y, uint32_t m)
{
    tb__mctx *c = r->c;
    uint64_t id;
    if (!tb_htab_get(&r->map, tb__key(x, y), &id))
        return TB_OK; /* cannot happen: the map is kept exact */
    tb__redge e = TB_ARRAY_AT(&r->edges, tb__redge, id);
    tb_htab_del(&r->map, tb__key(x, y));
    tb_pqueue_remove(&r->pq, (uint32_t)id);
    tb_status st = TB_OK;
    for (int k = 0; k < 2 && !st && e.t[k] != TB_MESH_NONE; k++) {
        uint32_t t = e.t[k];
        tb_tri T = TB_ARRAY_AT(&c->tris, tb_tri, t);
        int s = 0;
        while (s < 3 && !((T.v[s] == x && T.v[(s + 1) % 3] == y) || (T.v[s] == y && T.v[(s + 1) % 3] == x)))
            s++;
        if (s == 3)
            continue;
        uint32_t u = T.v[s], v = T.v[(s + 1) % 3], w = T.v[(s + 2) % 3];
        uint32_t nt = (uint32_t)c->tris.len;
        TB_ARRAY_AT(&c->tris, tb_tri, t) = (tb_tri){{u, m, w}};
        tb__push_tri(c, m, v, w);
        tb__retarget(r, v, w, t, nt);
        if (!(st = tb__use_edge(r, u, m, t)) && !(st = tb__use_edge(r, m, v, nt)) &&
            !(st = tb__use_edge(r, m, w, t)))
            st = tb__use_edge(r, m, w, nt);
    }
    return st ? st : c->err;
}

/* Splits interior edges longer than L, longest first, each together with
 * both its triangles (Rivara's longest-edge bisection: the longest edge in
 * the face is the longest edge of both its triangles, so triangle shapes
 * stay bounded). Face boundary edges are never split here: they are already
 * at most L long and shared with the neighbouring face. */
static tb_status tb__refine_run(tb__refiner *r)
{
    tb__mctx *c = r->c;
    tb_status st = TB_OK;
    uint32_t id;
    while (!st && !c->err && tb_pqueue_pop(&r->pq, &id, NULL)) {
        tb__redge e = TB_ARRAY_AT(&r->edges, tb__redge, id);
        if (e.t[1] == TB_MESH_NONE)
            continue;
        uint32_t m = tb__vertex(c, 2, (uint32_t[]){e.a, e.b}, (double[]){0.5, 0.5});
        st = tb__split_edge(r, e.a, e.b, m);
    }
    return st ? st : c->err;
}

/* Refines c->tris (all boundary edges already short enough). */
static tb_status tb__refine(tb__mctx *c)
{
    if (!isfinite(c->L))
        return TB_OK;
    tb__refiner r;
    tb_status st = tb__refiner_begin(&r, c);
    if (!st)
        st = tb__refine_run(&r);
    tb__refiner_end(&r);
    return st;
}

/* --------------------------------------------------------------- the faces */

/* Any face given as loops of sides: the polygon of the sides' end points is
 * triangulated, then each side is split at its inner vertices (fanning the
 * triangle on it), then long interior edges are bisected. Triangulating the
 * coarse polygon, not the one with the inner vertices, keeps the exact
 * triangulator away from the nearly collinear runs of inner vertices (it
 * would clip slivers between them). */
static void tb__general(tb__mctx *c, const tb__side *sides, const uint32_t *loop_sides, uint32_t nloops,
                        uint32_t face)
{
    c->ring.len = 0;
    c->ring_sizes.len = 0;
    c->tris.len = 0;
    tb_status st = TB_OK;
    uint32_t n = 0;
    for (uint32_t l = 0; l < nloops && !st; l++) {
        for (uint32_t i = 0; i < loop_sides[l] && !st; i++)
            st = tb_array_push(&c->ring, &sides[n + i].a);
        n += loop_sides[l];
        if (!st)
            st = tb_array_push(&c->ring_sizes, &loop_sides[l]);
    }
    if (!st)
        st = tb_triangulate_3d(c->out->positions.data, c->ring.data, c->ring_sizes.data, nloops, &c->tris, NULL);
    if (!st && isfinite(c->L)) {
        tb__refiner r;
        st = tb__refiner_begin(&r, c);
        for (uint32_t i = 0; i < n && !st; i++) {
            uint32_t from = sides[i].a;
            for (uint32_t j = 1; j < sides[i].k && !st; j++) {
                uint32_t p = tb__side_pt(&sides[i], j);
                st = tb__split_edge(&r, from, sides[i].b, p);
                from = p;
            }
        }
        if (!st)
            st = tb__refine_run(&r);
        tb__refiner_end(&r);
    }
    if (st) {
        if (!c->err)
            c->err = st;
        return;
    }
    tb__emit_tris(c, face);
}

/* A triangle given by its sides: the regular pattern if the sides agree. */
static void tb__triangle(tb__mctx *c, const tb__side s[3], uint32_t face)
{
    if (s[0].k == s[1].k && s[1].k == s[2].k) {
        tb__grid_triangle(c, s, face);
        return;
    }
    const uint32_t three = 3;
    tb__general(c, s, &three, 1, face);
}

bool tb_mesh_quad_convex(const tb_mesh *m, const uint32_t v[4])
{
    tb_vec3 q[4];
    for (int k = 0; k < 4; k++)
        q[k] = tb__pos(m, v[k]);
    tb_dvec3 n = tb_polygon_newell(q, NULL, 4);
    for (int i = 0; i < 4; i++) {
        tb_vec3 a = q[(i + 3) % 4], b = q[i], d = q[(i + 1) % 4];
        double ux = (double)b.x - a.x, uy = (double)b.y - a.y, uz = (double)b.z - a.z;
        double wx = (double)d.x - b.x, wy = (double)d.y - b.y, wz = (double)d.z - b.z;
        if (!((uy * wz - uz * wy) * n.x + (uz * wx - ux * wz) * n.y + (ux * wy - uy * wx) * n.z > 0))
            return false;
    }
    return true;
}

static void tb__face(tb__mctx *c, uint32_t f)
{
    const tb_fed *m = c->fed;
    uint32_t l0 = m->face_loops[f];
    uint32_t n0 = tb_fed_loop_size(m, l0);
    bool one_loop = tb_fed_face_nloops(m, f) == 1;
    if (one_loop && (n0 == 3 || n0 == 4)) {
        tb__side s[4];
        uint32_t v[4];
        for (uint32_t i = 0; i < n0; i++) {
            uint32_t cr = m->loop_corners[l0] + i;
            v[i] = m->corner_vert[cr];
            s[i] = tb__edge_side(c, m->corner_edge[cr], v[i]);
        }
        if (n0 == 3) {
            tb__triangle(c, s, f);
            return;
        }
        if (!tb_polygon_is_planar(m->positions, v, 4, c->tol)) {
            /* Non-planar quad: two triangles along the chosen diagonal,
             * which gets vertices of its own like any edge. */
            uint32_t t[6];
            tb_quad_diagonal dg = tb_quad_split_diagonal(m->positions[v[0]], m->positions[v[1]],
                                                         m->positions[v[2]], m->positions[v[3]]);
            tb_quad_split_corners(dg, t);
            uint32_t d0 = dg == TB_QUAD_DIAG_02 ? 0 : 1, d1 = d0 + 2;
            tb__side diag = tb__new_side(c, v[d0], v[d1]), back = diag;
            back.a = diag.b, back.b = diag.a, back.rev = !diag.rev;
            for (int h = 0; h < 2; h++) {
                tb__side ts[3];
                for (int k = 0; k < 3; k++) {
                    uint32_t i = t[3 * h + k], j = t[3 * h + (k + 1) % 3];
                    ts[k] = (i == d0 && j == d1) ? diag : ((i == d1 && j == d0) ? back : s[i]);
                }
                tb__triangle(c, ts, f);
            }
            return;
        }
        if (s[0].k == s[2].k && s[1].k == s[3].k && tb_mesh_quad_convex(c->out, v)) {
            tb__grid_quad(c, s, f);
            return;
        }
    }
    /* General: every loop as its sides. */
    uint32_t nsides = tb_fed_face_corner_end(m, f) - tb_fed_face_corner_begin(m, f);
    uint32_t nl = tb_fed_face_nloops(m, f);
    tb__side *sides = malloc(sizeof(tb__side) * nsides);
    uint32_t *loop_sides = malloc(sizeof(uint32_t) * nl);
    if (!sides || !loop_sides) {
        free(sides), free(loop_sides);
        if (!c->err)
            c->err = tb_error(TB_ERR_NOMEM, "meshing: out of memory");
        return;
    }
    uint32_t k = 0;
    for (uint32_t l = l0; l < m->face_loops[f + 1]; l++) {
        loop_sides[l - l0] = tb_fed_loop_size(m, l);
        for (uint32_t cr = m->loop_corners[l]; cr < m->loop_corners[l + 1]; cr++)
            sides[k++] = tb__edge_side(c, m->corner_edge[cr], m->corner_vert[cr]);
    }
    tb__general(c, sides, loop_sides, nl, f);
    free(sides), free(loop_sides);
}

/* Gives opposite sides of every planar convex quad face the same number of
 * parts, the larger of the two, so the face is meshed as a grid. Each edge
 * is cut by its own length, so a quad whose opposite sides differ slightly
 * (the published Cornell box floor: 552.8 and 549.6 mm) could get 11 and 10
 * parts and fall to triangulation plus bisection: several times the
 * elements of a finer grid, and element counts that jump as the bound
 * shrinks. Counts only grow, so the sweeps end; edges are shared, so a
 * change is carried to the neighbouring faces by the next sweep. */
static void tb__match_quad_sides(tb__mctx *c)
{
    const tb_fed *m = c->fed;
    for (bool changed = true; changed;) {
        changed = false;
        for (uint32_t f = 0; f < m->nfaces; f++) {
            uint32_t l0 = m->face_loops[f];
            if (tb_fed_face_nloops(m, f) != 1 || tb_fed_loop_size(m, l0) != 4)
                continue;
            uint32_t v[4], e[4];
            for (uint32_t i = 0; i < 4; i++) {
                uint32_t cr = m->loop_corners[l0] + i;
                v[i] = m->corner_vert[cr];
                e[i] = m->corner_edge[cr];
            }
            if (!tb_polygon_is_planar(m->positions, v, 4, c->tol) || !tb_mesh_quad_convex(c->out, v))
                continue;
            for (uint32_t i = 0; i < 2; i++) {
                uint32_t a = c->edge_k[e[i]], b = c->edge_k[e[i + 2]];
                if (a != b) {
                    c->edge_k[e[i]] = c->edge_k[e[i + 2]] = a > b ? a : b;
                    changed = true;
                }
            }
        }
    }
}

tb_status tb_mesh_from_fed(const tb_fed *fed, const tb_mesh_opts *opts, tb_mesh *out)
{
    static const tb_mesh_opts defaults = {0};
    if (!opts)
        opts = &defaults;
    tb_mesh_free(out);
    tb_mesh_init(out);
    tb__mctx c = {.fed = fed, .out = out, .quads = opts->quads};
    c.tol = opts->planar_tol > 0 ? opts->planar_tol : TB_MESH_PLANAR_TOL;
    c.L = INFINITY;
    if (opts->max_edge > 0)
        c.L = opts->max_edge;
    if (opts->max_area > 0)
        c.L = fmin(c.L, sqrt(opts->max_area));
    if (isnan(opts->max_edge) || isnan(opts->max_area))
        return tb_error(TB_ERR_ARG, "meshing: max_edge or max_area is NaN");

    /* Refuse bounds that would make absurd meshes before making anything:
     * one that float coordinates cannot resolve, and one making more than
     * 2^31 elements. A face whose boundary is cut into P parts gets at most
     * about P^2 elements from any of the patterns. */
    double maxabs = 0;
    for (uint32_t v = 0; v < fed->nverts; v++) {
        tb_vec3 p = fed->positions[v];
        maxabs = fmax(maxabs, fmax(fabs(p.x), fmax(fabs(p.y), fabs(p.z))));
    }
    if (isfinite(c.L) && c.L < 1e-6 * maxabs)
        return tb_error(TB_ERR_ARG, "meshing: edge bound %g is below the float resolution of a mesh reaching %g",
                        c.L, maxabs);
    double estimate = 0;
    for (uint32_t f = 0; f < fed->nfaces && isfinite(c.L); f++) {
        double per = 0;
        for (uint32_t cr = tb_fed_face_corner_begin(fed, f); cr < tb_fed_face_corner_end(fed, f); cr++) {
            const tb_fed_edge *e = &fed->edges[fed->corner_edge[cr]];
            tb_vec3 p = fed->positions[e->v[0]], q = fed->positions[e->v[1]];
            double dx = (double)q.x - p.x, dy = (double)q.y - p.y, dz = (double)q.z - p.z;
            per += sqrt(dx * dx + dy * dy + dz * dz);
        }
        double k = per / c.L + 1;
        estimate += k * k; /* the elements of a face are bounded by the square of its boundary parts */
    }
    if (estimate > (double)TB_FED_MAX_COUNT)
        return tb_error(TB_ERR_ARG, "meshing: edge bound %g would make about %.3g elements (at most %u)", c.L,
                        estimate, TB_FED_MAX_COUNT);

    tb_status st = TB_OK;
    c.edge_k = malloc(sizeof(uint32_t) * ((size_t)fed->nedges + 1));
    c.edge_first = malloc(sizeof(uint32_t) * ((size_t)fed->nedges + 1));
    tb_array_init(&c.ring, sizeof(uint32_t));
    tb_array_init(&c.ring_sizes, sizeof(uint32_t));
    tb_array_init(&c.tris, sizeof(tb_tri));
    if (!c.edge_k || !c.edge_first)
        st = tb_error(TB_ERR_NOMEM, "meshing: out of memory");
    if (!st && fed->nverts)
        st = tb_array_push_n(&out->positions, fed->positions, fed->nverts);
    if (!st && fed->normals && fed->nverts)
        st = tb_array_push_n(&out->normals, fed->normals, fed->nverts);
    if (!st && fed->uvs && fed->nverts)
        st = tb_array_push_n(&out->uvs, fed->uvs, fed->nverts);
    for (uint32_t e = 0; e < fed->nedges && !st; e++)
        c.edge_k[e] = tb__parts(&c, tb__dist(out, fed->edges[e].v[0], fed->edges[e].v[1]));
    if (!st)
        tb__match_quad_sides(&c);
    /* Edge points, computed once per edge from v[0] toward v[1]. */
    for (uint32_t e = 0; e < fed->nedges && !st && !c.err; e++) {
        const tb_fed_edge *ed = &fed->edges[e];
        c.edge_first[e] = (uint32_t)out->positions.len;
        for (uint32_t j = 1; j < c.edge_k[e]; j++) {
            double t = (double)j / c.edge_k[e];
            tb__vertex(&c, 2, (uint32_t[]){ed->v[0], ed->v[1]}, (double[]){1 - t, t});
        }
    }
    for (uint32_t f = 0; f < fed->nfaces && !st && !c.err; f++)
        tb__face(&c, f);
    if (!st)
        st = c.err;
    free(c.edge_k);
    free(c.edge_first);
    tb_array_free(&c.ring);
    tb_array_free(&c.ring_sizes);
    tb_array_free(&c.tris);
    if (st) {
        tb_mesh_free(out);
        tb_mesh_init(out);
    }
    return st;
}
