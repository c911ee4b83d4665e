/* Polygonal approximation of every primitive (docs/primitives.md,
 * "Tessellation"): one function, a switch over all kinds.
 *
 * Each kind lays out polygons face by face, in the face's (u, v) or on its
 * plane, with the same sample points along every boundary two faces share
 * (one set of breakpoints per edge of the primitive). Every corner becomes a
 * vertex evaluated by tb_param_eval; vertices closer than a tolerance far
 * below any sample spacing are then welded, which joins seams, poles and the
 * edges between faces, and polygons that lose corners to welding (at poles)
 * become triangles or vanish. The result is built as a FED mesh. */
#include "host/object/polygonize.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "host/object/bounds.h"
#include "host/object/param.h"
#include "util/container/array.h"
#include "util/container/hash_table.h"
#include "util/math/float.h"
#include "util/mesh/polygon.h"
#include "util/mesh/triangulate.h"
#include "util/stats/stats.h"

TB_STAT_COUNTER(tb__poly_sphere, "Polygonize/sphere");
TB_STAT_COUNTER(tb__poly_cube, "Polygonize/cube");
TB_STAT_COUNTER(tb__poly_cylinder, "Polygonize/cylinder");
TB_STAT_COUNTER(tb__poly_cone, "Polygonize/cone");
TB_STAT_COUNTER(tb__poly_pyramid, "Polygonize/pyramid");
TB_STAT_COUNTER(tb__poly_prism, "Polygonize/prism");
TB_STAT_COUNTER(tb__poly_torus, "Polygonize/torus");
TB_STAT_COUNTER(tb__poly_polygons, "Polygonize/polygons");
TB_STAT_COUNTER(tb__poly_conic, "Polygonize/conic");
TB_STAT_COUNTER(tb__poly_square_arch, "Polygonize/square_arch");
TB_STAT_COUNTER(tb__poly_round_arch, "Polygonize/round_arch");
TB_STAT_COUNTER(tb__poly_faces, "Polygonize/faces made");

static void tb__count(tb_prim_kind kind)
{
    static tb_stat *const per_kind[] = {
        &tb__poly_sphere, &tb__poly_cube,  &tb__poly_cylinder, &tb__poly_cone,        &tb__poly_pyramid,
        &tb__poly_prism,  &tb__poly_torus, &tb__poly_polygons, &tb__poly_conic,       &tb__poly_square_arch,
        &tb__poly_round_arch,
    };
    if ((unsigned)kind < sizeof per_kind / sizeof per_kind[0])
        TB_STAT_INC(*per_kind[kind]);
}

static tb_dvec3 tb__v(double x, double y, double z) { return (tb_dvec3){x, y, z}; }

/* Vertices closer than this times the object's size (its box diagonal) are
 * welded: about 3 float ulps, so welded positions never round to one float,
 * and below the spacing of any layout within TB_POLY_MAX_SEGMENTS (the
 * tightest, a sphere's pole ring at 4096 x 4096, is 3.4e-7 of its size). */
#define TB__WELD_REL 2e-7

/* ------------------------------------------------------------ resolution */

/* The resolved options, in object space. */
typedef struct tb__res {
    double edge;  /* longest edge, object units; 0: none */
    double angle; /* largest facet-normal angle, radians; 0: none */
    int maxseg;   /* segments per direction */
    double floor; /* steps with chords this short count as resolved (1e-5 of the object's size) */
    double weld;  /* distance within which vertices are welded (2e-7 of the object's size) */
} tb__res;

/* Segments for a straight run of length L. */
static int tb__seg_line(const tb__res *r, double L)
{
    double n = r->edge > 0.0 ? ceil(L / r->edge - 1e-9) : 1.0;
    return n < 1.0 ? 1 : (n > r->maxseg ? r->maxseg : (int)n);
}

/* Segments for a circular arc of radius rho spanning angle th (at least nmin):
 * each step turns by at most the angle tolerance and its chord is at most the
 * edge limit. */
static int tb__seg_arc(const tb__res *r, double rho, double th, int nmin)
{
    double n = nmin;
    if (r->angle > 0.0)
        n = fmax(n, ceil(th / r->angle - 1e-9));
    if (r->edge > 0.0 && rho > 0.0 && r->edge < 2.0 * rho)
        n = fmax(n, ceil(th / (2.0 * asin(r->edge / (2.0 * rho))) - 1e-9));
    return n > r->maxseg ? r->maxseg : (int)n;
}

/* Largest angle between the normals of adjacent bands of a surface of
 * revolution whose profile is (rho[i], z[i]), i = 0..n (cyclic: the last
 * band also meets the first), cut into sectors of angle dphi. A band's facet
 * (a trapezoid, or a triangle at a pole) has its normal in the sector's
 * middle meridian plane, perpendicular to (cos(dphi/2) (rho1 - rho0), z1 - z0):
 * the profile chord with its radial part shortened, so adjacent bands can
 * differ slightly more than their chords do. */
static double tb__band_turn(const double *rho, const double *z, int n, double dphi, bool cyclic)
{
    double ch = cos(0.5 * dphi), worst = 0.0;
    /* bands i = 0..n-1 run from point i to point i + 1 (point n is point 0 when cyclic) */
    for (int i = 0; i + 1 < n + (cyclic ? 1 : 0); i++) {
        int a = i, b = i + 1, c = i + 2;
        if (cyclic)
            b %= n, c %= n;
        double x1 = ch * (rho[b] - rho[a]), z1 = z[b] - z[a], x2 = ch * (rho[c] - rho[b]), z2 = z[c] - z[b];
        worst = fmax(worst, atan2(fabs(x1 * z2 - z1 * x2), x1 * x2 + z1 * z2));
    }
    return worst;
}

/* Segments for a full (cyclic) or half circle profile of radius r about
 * (R, 0) (R = 0: the sphere's meridian), raised from n until adjacent bands
 * meet within the angle tolerance (see tb__band_turn). */
static int tb__profile_circle_segments(const tb__res *r, double R, double rad, double th, int n, double dphi)
{
    if (!(r->angle > 0.0))
        return n;
    for (; n < r->maxseg; n++) {
        double *rho = malloc(sizeof(double) * (size_t)(n + 1) * 2);
        if (!rho)
            return n;
        double *z = rho + n + 1;
        for (int i = 0; i <= n; i++) {
            double t = th * i / n;
            /* sphere (th = pi): from the south pole up; torus (th = 2 pi): from the outer equator */
            rho[i] = th < 4.0 ? sin(t) * rad : R + rad * cos(t);
            z[i] = th < 4.0 ? -cos(t) * rad : rad * sin(t);
        }
        double turn = tb__band_turn(rho, z, n, dphi, th >= 4.0);
        free(rho);
        if (turn <= r->angle)
            break;
    }
    return n;
}

/* ------------------------------------------------------------- the builder */

/* A vertex before welding: one per polygon corner, on one face. */
typedef struct tb__pvert {
    tb_dvec3 p, n;
    double u, v;
    int face;
} tb__pvert;

typedef struct tb__mb {
    tb_prim_kind kind;
    const tb_mid_geometry *g;
    tb_array pv;     /* tb__pvert */
    tb_array loop_n; /* uint32_t: corners of each polygon */
    tb_array corner; /* uint32_t: pv index of each corner */
    tb_array fid;    /* int32_t: face ID of each polygon */
    tb_status st;    /* first failure */
} tb__mb;

static void tb__mb_init(tb__mb *m, tb_prim_kind kind, const tb_mid_geometry *g)
{
    m->kind = kind, m->g = g, m->st = TB_OK;
    tb_array_init(&m->pv, sizeof(tb__pvert));
    tb_array_init(&m->loop_n, sizeof(uint32_t));
    tb_array_init(&m->corner, sizeof(uint32_t));
    tb_array_init(&m->fid, sizeof(int32_t));
}

static void tb__mb_free(tb__mb *m)
{
    tb_array_free(&m->pv);
    tb_array_free(&m->loop_n);
    tb_array_free(&m->corner);
    tb_array_free(&m->fid);
}

/* A vertex at (u, v) of `face` (rounding may step a breakpoint out of [0, 1]). */
static uint32_t tb__mb_uv(tb__mb *m, int face, double u, double v)
{
    tb__pvert q = {.u = tb_clamp(u, 0.0, 1.0), .v = tb_clamp(v, 0.0, 1.0), .face = face};
    if (!m->st)
        m->st = tb_param_eval(m->kind, m->g, face, q.u, q.v, &q.p, &q.n, NULL, NULL);
    if (!m->st)
        m->st = tb_array_push(&m->pv, &q);
    return (uint32_t)m->pv.len - 1;
}

/* A vertex at the point of `face` nearest p (p on the face up to rounding). */
static uint32_t tb__mb_pt(tb__mb *m, int face, tb_dvec3 p)
{
    int f;
    double u = 0.0, v = 0.0;
    if (!m->st)
        m->st = tb_param_from_point(m->kind, m->g, p, face, &f, &u, &v);
    return tb__mb_uv(m, face, u, v);
}

/* A vertex with given attributes (polygons keep their own vertices). */
static uint32_t tb__mb_raw(tb__mb *m, int face, tb_dvec3 p, tb_dvec3 n, double u, double v)
{
    tb__pvert q = {p, n, u, v, face};
    if (!m->st)
        m->st = tb_array_push(&m->pv, &q);
    return (uint32_t)m->pv.len - 1;
}

/* Adds a polygon over pv indices c[0..n), reversed first when `flip`. */
static void tb__mb_loop(tb__mb *m, int face, const uint32_t *c, int n, bool flip)
{
    if (m->st)
        return;
    uint32_t nn = (uint32_t)n;
    int32_t f = face;
    m->st = tb_array_push(&m->loop_n, &nn);
    for (int i = 0; i < n && !m->st; i++)
        m->st = tb_array_push(&m->corner, &c[flip ? n - 1 - i : i]);
    if (!m->st)
        m->st = tb_array_push(&m->fid, &f);
}

/* Adds a polygon over pv indices, turned so that it runs counter-clockwise
 * in (u, v): dp/du x dp/dv points out of every face, so that is outward. */
static void tb__mb_poly_oriented(tb__mb *m, int face, const uint32_t *c, int n)
{
    if (m->st)
        return;
    double a = 0.0;
    const tb__pvert *pv = (const tb__pvert *)m->pv.data;
    for (int i = 0; i < n; i++) {
        const tb__pvert *p = &pv[c[i]], *q = &pv[c[(i + 1) % n]];
        a += p->u * q->v - q->u * p->v;
    }
    tb__mb_loop(m, face, c, n, a < 0.0);
}

/* A polygon given by points on a flat face (n <= 4). */
static void tb__mb_poly_pts(tb__mb *m, int face, const tb_dvec3 *p, int n)
{
    uint32_t c[4];
    for (int i = 0; i < n; i++)
        c[i] = tb__mb_pt(m, face, p[i]);
    tb__mb_poly_oriented(m, face, c, n);
}

/* The quads of the (u, v) grid us[0..nu] x vs[0..nv]. */
static void tb__mb_grid_uv(tb__mb *m, int face, const double *us, int nu, const double *vs, int nv)
{
    /* one vertex per grid point (welding would merge repeats, but each costs memory) */
    uint32_t *id = malloc(sizeof(uint32_t) * (size_t)(nu + 1) * (size_t)(nv + 1));
    if (!id) {
        if (!m->st)
            m->st = tb_error(TB_ERR_NOMEM, "polygonize: out of memory");
        return;
    }
    for (int j = 0; j <= nv; j++)
        for (int i = 0; i <= nu; i++)
            id[j * (nu + 1) + i] = tb__mb_uv(m, face, us[i], vs[j]);
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++) {
            uint32_t c[4] = {id[j * (nu + 1) + i], id[j * (nu + 1) + i + 1], id[(j + 1) * (nu + 1) + i + 1],
                             id[(j + 1) * (nu + 1) + i]};
            tb__mb_poly_oriented(m, face, c, 4);
        }
    free(id);
}

/* The quads of the planar grid o + a[i] ea + b[j] eb on a flat face. */
static void tb__mb_grid_plane(tb__mb *m, int face, tb_dvec3 o, tb_dvec3 ea, const double *a, int na, tb_dvec3 eb,
                              const double *b, int nb)
{
    uint32_t *id = malloc(sizeof(uint32_t) * (size_t)(na + 1) * (size_t)(nb + 1));
    if (!id) {
        if (!m->st)
            m->st = tb_error(TB_ERR_NOMEM, "polygonize: out of memory");
        return;
    }
    for (int j = 0; j <= nb; j++)
        for (int i = 0; i <= na; i++)
            id[j * (na + 1) + i] =
                tb__mb_pt(m, face, tb_dvec3_add(o, tb_dvec3_add(tb_dvec3_scale(ea, a[i]), tb_dvec3_scale(eb, b[j]))));
    for (int j = 0; j < nb; j++)
        for (int i = 0; i < na; i++) {
            uint32_t c[4] = {id[j * (na + 1) + i], id[j * (na + 1) + i + 1], id[(j + 1) * (na + 1) + i + 1],
                             id[(j + 1) * (na + 1) + i]};
            tb__mb_poly_oriented(m, face, c, 4);
        }
    free(id);
}

/* ------------------------------------------------------------ breakpoints */

/* A scratch list of doubles. */
typedef struct tb__bp {
    double *x;
    int n; /* segments: x[0..n] */
} tb__bp;

static bool tb__bp_alloc(tb__bp *b, int n)
{
    b->n = n;
    b->x = malloc(sizeof(double) * (size_t)(n + 1));
    return b->x != NULL;
}

/* n uniform segments of [a, b] (ends exact). */
static bool tb__bp_uniform(tb__bp *bp, double a, double b, int n)
{
    if (!tb__bp_alloc(bp, n))
        return false;
    for (int i = 0; i <= n; i++)
        bp->x[i] = i == n ? b : a + (b - a) * i / n;
    return true;
}

/* a followed by b without its first point (a's last must equal b's first). */
static bool tb__bp_concat(tb__bp *out, const tb__bp *a, const tb__bp *b)
{
    if (!tb__bp_alloc(out, a->n + b->n))
        return false;
    memcpy(out->x, a->x, sizeof(double) * (size_t)(a->n + 1));
    memcpy(out->x + a->n + 1, b->x + 1, sizeof(double) * (size_t)b->n);
    return true;
}

static void tb__bp_free(tb__bp *b)
{
    free(b->x);
    b->x = NULL;
}

/* ---------------------------------------------------------------- kinds */

/* A disc cap with n_u spokes (shared with the side) and rings every edge length. */
static void tb__disc(tb__mb *m, const tb__res *r, int face, double R, const tb__bp *us)
{
    /* Rings at R j / n; the innermost one's spoke spacing 2 pi R / (n n_u) is
     * kept above 8 times the weld distance, or it would merge into the centre
     * unevenly (only at extreme resolutions, whose edges then exceed the limit). */
    int n = tb__seg_line(r, R);
    double nmax = TB_2PI * R / (us->n * 8.0 * r->weld);
    if (r->weld > 0.0 && n > nmax)
        n = nmax >= 1.0 ? (int)nmax : 1;
    tb__bp vs;
    if (!tb__bp_uniform(&vs, 0.0, 1.0, n)) {
        m->st = tb_error(TB_ERR_NOMEM, "polygonize: out of memory");
        return;
    }
    tb__mb_grid_uv(m, face, us->x, us->n, vs.x, vs.n);
    tb__bp_free(&vs);
}

static tb_status tb__nomem(void) { return tb_error(TB_ERR_NOMEM, "polygonize: out of memory"); }

static void tb__sphere(tb__mb *m, const tb__res *r)
{
    tb__bp us = {0}, vs = {0};
    int nu = tb__seg_arc(r, 1.0, TB_2PI, 3);
    int nv = tb__profile_circle_segments(r, 0.0, 1.0, TB_PI, tb__seg_arc(r, 1.0, TB_PI, 2), TB_2PI / nu);
    if (!tb__bp_uniform(&us, 0, 1, nu) || !tb__bp_uniform(&vs, 0, 1, nv)) {
        m->st = tb__nomem();
    } else {
        tb__mb_grid_uv(m, TB_FACE_SPHERE, us.x, us.n, vs.x, vs.n);
    }
    tb__bp_free(&us), tb__bp_free(&vs);
}

/* Cylinder and cone frustum: radius 1 at z = -1, r at z = 1. */
static void tb__cone(tb__mb *m, const tb__res *r, double top, bool caps)
{
    tb__bp us = {0}, vs = {0};
    double slant = hypot(2.0, 1.0 - top);
    if (!tb__bp_uniform(&us, 0, 1, tb__seg_arc(r, fmax(1.0, top), TB_2PI, 3)) ||
        !tb__bp_uniform(&vs, 0, 1, tb__seg_line(r, slant))) {
        m->st = tb__nomem();
    } else {
        tb__mb_grid_uv(m, TB_FACE_CONE_SIDE, us.x, us.n, vs.x, vs.n);
        if (caps) {
            tb__disc(m, r, TB_FACE_CONE_BOTTOM, 1.0, &us);
            if (top > 0.0)
                tb__disc(m, r, TB_FACE_CONE_TOP, top, &us);
        }
    }
    tb__bp_free(&us), tb__bp_free(&vs);
}

static void tb__torus(tb__mb *m, const tb__res *r)
{
    const tb_geom_torus *t = &m->g->torus;
    tb__bp us = {0}, vs = {0};
    int nu = tb__seg_arc(r, t->major + t->minor, TB_2PI, 3);
    int nv = tb__profile_circle_segments(r, t->major, t->minor, TB_2PI, tb__seg_arc(r, t->minor, TB_2PI, 3), TB_2PI / nu);
    if (!tb__bp_uniform(&us, 0, 1, nu) || !tb__bp_uniform(&vs, 0, 1, nv)) {
        m->st = tb__nomem();
    } else {
        tb__mb_grid_uv(m, TB_FACE_TORUS, us.x, us.n, vs.x, vs.n);
    }
    tb__bp_free(&us), tb__bp_free(&vs);
}

/* Cube and pyramid frustum (top half-size t; t = 1 the cube). */
static void tb__pyramid(tb__mb *m, const tb__res *r, double t, bool bottom, bool top)
{
    tb__bp hs = {0}, vs = {0}, ht = {0}; /* freed on every path, even after a failed allocation */
    double corner_edge = sqrt(2.0 * (1.0 - t) * (1.0 - t) + 4.0);
    if (!tb__bp_uniform(&hs, 0, 1, tb__seg_line(r, 2.0 * fmax(1.0, t))) ||
        !tb__bp_uniform(&vs, 0, 1, tb__seg_line(r, corner_edge)) || !tb__bp_uniform(&ht, -1, 1, hs.n)) {
        m->st = tb__nomem();
    } else {
        for (int f = 0; f < 4; f++)
            tb__mb_grid_uv(m, f, hs.x, hs.n, vs.x, vs.n);
        /* The caps on the same breakpoints as the sides' rims. */
        if (bottom)
            tb__mb_grid_plane(m, 4, tb__v(0, 0, -1), tb__v(1, 0, 0), ht.x, ht.n, tb__v(0, 1, 0), ht.x, ht.n);
        if (top)
            tb__mb_grid_plane(m, 5, tb__v(0, 0, 1), tb__v(t, 0, 0), ht.x, ht.n, tb__v(0, t, 0), ht.x, ht.n);
    }
    tb__bp_free(&hs), tb__bp_free(&vs), tb__bp_free(&ht);
}

/* ---------------------------------------------------------------- prism */

/* ------------------------------------------------- flat-region refinement */

/* Triangles of a flat region, refined by longest-edge bisection (Rivara's
 * LEPP: a triangle's longest edge is split together with the neighbour's when
 * it is the neighbour's longest too, else the neighbour is split first), so
 * the mesh stays conforming. Edges no longer than the limit are never split,
 * so a boundary already sampled at the limit keeps its points. */
typedef struct tb__tris {
    tb_array pts;     /* tb_dvec3 points */
    tb_array parents; /* uint32_t[2] per point: the edge a midpoint split, or UINT32_MAX */
    tb_array tris;    /* uint32_t[3], counter-clockwise */
    tb_array alive;   /* bool per triangle */
    tb_htab edges;    /* edge key -> 1 + triangle, 1 + second triangle << 32 */
} tb__tris;

static uint64_t tb__ekey(uint32_t a, uint32_t b) { return a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a; }

static double tb__len2(const tb__tris *t, uint32_t a, uint32_t b)
{
    const tb_dvec3 *p = (const tb_dvec3 *)t->pts.data;
    return tb_dvec3_length2(tb_dvec3_sub(p[a], p[b]));
}

/* Index 0..2 of triangle k's longest edge (from corner i to i + 1); ties go
 * to the larger edge key, so both triangles of an edge agree. */
static int tb__longest(const tb__tris *t, uint32_t k, double *len2)
{
    const uint32_t *v = &TB_ARRAY_AT(&t->tris, uint32_t, 3 * k);
    int best = 0;
    double bl = -1.0;
    uint64_t bk = 0;
    for (int i = 0; i < 3; i++) {
        double l = tb__len2(t, v[i], v[(i + 1) % 3]);
        uint64_t key = tb__ekey(v[i], v[(i + 1) % 3]);
        if (l > bl || (l == bl && key > bk))
            bl = l, best = i, bk = key;
    }
    *len2 = bl;
    return best;
}

/* Registers (or, with add false, removes) triangle k under its three edges. */
static tb_status tb__tris_link(tb__tris *t, uint32_t k, bool add)
{
    const uint32_t *v = &TB_ARRAY_AT(&t->tris, uint32_t, 3 * k);
    for (int i = 0; i < 3; i++) {
        uint64_t key = tb__ekey(v[i], v[(i + 1) % 3]), val = 0;
        tb_htab_get(&t->edges, key, &val);
        uint64_t lo = val & 0xffffffffu, hi = val >> 32, me = (uint64_t)k + 1;
        if (add) {
            if (lo == 0)
                lo = me;
            else
                hi = me;
        } else {
            if (lo == me)
                lo = hi, hi = 0;
            else if (hi == me)
                hi = 0;
        }
        tb_status st = tb_htab_put(&t->edges, key, lo | hi << 32);
        if (st)
            return st;
    }
    return TB_OK;
}

/* The other triangle on edge (a, b) than k, or UINT32_MAX. */
static uint32_t tb__neighbour(const tb__tris *t, uint32_t k, uint32_t a, uint32_t b)
{
    uint64_t val = 0;
    tb_htab_get(&t->edges, tb__ekey(a, b), &val);
    uint64_t lo = val & 0xffffffffu, hi = val >> 32;
    if (lo && lo - 1 != k)
        return (uint32_t)(lo - 1);
    if (hi && hi - 1 != k)
        return (uint32_t)(hi - 1);
    return UINT32_MAX;
}

static tb_status tb__tris_add(tb__tris *t, uint32_t a, uint32_t b, uint32_t c)
{
    uint32_t v[3] = {a, b, c};
    bool on = true;
    tb_status st = tb_array_push_n(&t->tris, v, 3);
    if (!st)
        st = tb_array_push(&t->alive, &on);
    if (!st)
        st = tb__tris_link(t, (uint32_t)t->alive.len - 1, true);
    return st;
}

/* Splits triangle k at point m on its edge i (corner i to i + 1). */
static tb_status tb__tris_split(tb__tris *t, uint32_t k, int i, uint32_t m)
{
    uint32_t v[3];
    memcpy(v, &TB_ARRAY_AT(&t->tris, uint32_t, 3 * k), sizeof v);
    tb_status st = tb__tris_link(t, k, false);
    TB_ARRAY_AT(&t->alive, bool, k) = false;
    uint32_t a = v[i], b = v[(i + 1) % 3], c = v[(i + 2) % 3];
    if (!st)
        st = tb__tris_add(t, a, m, c);
    if (!st)
        st = tb__tris_add(t, m, b, c);
    return st;
}

/* Refines until no edge is longer than `edge`. */
static tb_status tb__tris_refine(tb__tris *t, double edge)
{
    double e2 = edge * edge;
    tb_status st = TB_OK;
    for (size_t k = 0; k < t->alive.len && !st; k++) {
        for (int guard = 0; guard < 1000000 && !st && TB_ARRAY_AT(&t->alive, bool, k); guard++) {
            double l2;
            if (tb__longest(t, (uint32_t)k, &l2), l2 <= e2)
                break;
            /* walk the longest-edge propagation path to a terminal edge */
            uint32_t cur = (uint32_t)k;
            for (int hop = 0; hop < 100000; hop++) {
                int i = tb__longest(t, cur, &l2);
                const uint32_t *v = &TB_ARRAY_AT(&t->tris, uint32_t, 3 * cur);
                uint32_t a = v[i], b = v[(i + 1) % 3];
                uint32_t nb = tb__neighbour(t, cur, a, b);
                int j = -1;
                if (nb != UINT32_MAX) {
                    double l2n;
                    j = tb__longest(t, nb, &l2n);
                    const uint32_t *w = &TB_ARRAY_AT(&t->tris, uint32_t, 3 * nb);
                    if (tb__ekey(w[j], w[(j + 1) % 3]) != tb__ekey(a, b)) {
                        cur = nb; /* the neighbour has a longer edge: split that first */
                        continue;
                    }
                }
                /* terminal edge (a, b): one new midpoint for both triangles */
                const tb_dvec3 *p = (const tb_dvec3 *)t->pts.data;
                tb_dvec3 mid = tb_dvec3_scale(tb_dvec3_add(p[a], p[b]), 0.5);
                uint32_t par[2] = {a, b}, m = (uint32_t)t->pts.len;
                st = tb_array_push(&t->pts, &mid);
                if (!st)
                    st = tb_array_push(&t->parents, par);
                if (!st)
                    st = tb__tris_split(t, cur, i, m);
                if (!st && nb != UINT32_MAX)
                    st = tb__tris_split(t, nb, j, m);
                break;
            }
        }
    }
    return st;
}

static void tb__tris_init(tb__tris *t)
{
    tb_array_init(&t->pts, sizeof(tb_dvec3));
    tb_array_init(&t->parents, sizeof(uint32_t) * 2);
    tb_array_init(&t->tris, sizeof(uint32_t));
    tb_array_init(&t->alive, sizeof(bool));
    tb_htab_init(&t->edges, TB_HTAB_U64);
}

static void tb__tris_free(tb__tris *t)
{
    tb_array_free(&t->pts), tb_array_free(&t->parents), tb_array_free(&t->tris), tb_array_free(&t->alive);
    tb_htab_free(&t->edges);
}

/* Removes zero-area triangles: ear clipping may cut an "ear" (a, b, c) whose
 * middle corner c lies on the segment a-b (boundary samples along a straight
 * edge are collinear). The triangle across a-b is split at c instead, which
 * covers the same area without the sliver. */
static tb_status tb__tris_fix_flat(tb__tris *t)
{
    tb_status st = TB_OK;
    for (size_t k = 0; k < t->alive.len && !st; k++) {
        if (!TB_ARRAY_AT(&t->alive, bool, k))
            continue;
        const uint32_t *v = &TB_ARRAY_AT(&t->tris, uint32_t, 3 * k);
        const tb_dvec3 *p = (const tb_dvec3 *)t->pts.data;
        double l2;
        int i = tb__longest(t, (uint32_t)k, &l2);
        uint32_t a = v[i], b = v[(i + 1) % 3], c = v[(i + 2) % 3];
        double area2 = tb_dvec3_length(tb_dvec3_cross(tb_dvec3_sub(p[b], p[a]), tb_dvec3_sub(p[c], p[a])));
        if (area2 > 1e-12 * l2)
            continue;
        uint32_t nb = tb__neighbour(t, (uint32_t)k, a, b);
        if (nb == UINT32_MAX)
            continue;
        const uint32_t *w = &TB_ARRAY_AT(&t->tris, uint32_t, 3 * nb);
        int j = 0;
        while (j < 3 && tb__ekey(w[j], w[(j + 1) % 3]) != tb__ekey(a, b))
            j++;
        st = tb__tris_link(t, (uint32_t)k, false);
        TB_ARRAY_AT(&t->alive, bool, k) = false;
        if (!st)
            st = tb__tris_split(t, nb, j, c);
    }
    return st;
}

/* Triangulates the loop pts[0..n) (plane coordinates xy, counter-clockwise
 * or not) with util/mesh, every point kept, and refines to the edge limit. */
static tb_status tb__tris_of_loop(tb__tris *t, const tb_dvec3 *pts, const double *xy, uint32_t n, double edge)
{
    tb_array tri;
    tb_array_init(&tri, sizeof(tb_tri));
    tb_status st = tb_triangulate_2d(xy, &n, 1, &tri, NULL);
    uint32_t none[2] = {UINT32_MAX, UINT32_MAX};
    for (uint32_t i = 0; i < n && !st; i++) {
        st = tb_array_push(&t->pts, &pts[i]);
        if (!st)
            st = tb_array_push(&t->parents, none);
    }
    for (size_t k = 0; k < tri.len && !st; k++) {
        const tb_tri *q = &TB_ARRAY_AT(&tri, tb_tri, k);
        st = tb__tris_add(t, q->v[0], q->v[1], q->v[2]);
    }
    tb_array_free(&tri);
    if (!st)
        st = tb__tris_fix_flat(t);
    if (!st && edge > 0.0)
        st = tb__tris_refine(t, edge);
    return st;
}

/* A flat face's polygon: triangulated, refined, every vertex from param. */
static void tb__flat_loop(tb__mb *m, const tb__res *r, int face, const tb_dvec3 *pts, const double *xy, uint32_t n)
{
    tb__tris t;
    tb__tris_init(&t);
    m->st = tb__tris_of_loop(&t, pts, xy, n, r->edge);
    uint32_t *ids = m->st ? NULL : malloc(sizeof(uint32_t) * (t.pts.len ? t.pts.len : 1));
    if (!m->st && !ids)
        m->st = tb__nomem();
    for (size_t i = 0; i < t.pts.len && !m->st; i++)
        ids[i] = tb__mb_pt(m, face, TB_ARRAY_AT(&t.pts, tb_dvec3, i));
    for (size_t k = 0; k < t.alive.len && !m->st; k++) {
        if (!TB_ARRAY_AT(&t.alive, bool, k))
            continue;
        const uint32_t *v = &TB_ARRAY_AT(&t.tris, uint32_t, 3 * k);
        uint32_t c[3] = {ids[v[0]], ids[v[1]], ids[v[2]]};
        tb__mb_poly_oriented(m, face, c, 3);
    }
    free(ids);
    tb__tris_free(&t);
}

static void tb__prism(tb__mb *m, const tb__res *r)
{
    const tb_geom_prism *g = &m->g->prism;
    int n = tb_param_prism_npoints(g);
    bool ccw = tb_param_prism_ccw(g);
    tb__bp zs;
    if (!tb__bp_uniform(&zs, 0, 1, tb__seg_line(r, 2.0))) {
        m->st = tb__nomem();
        return;
    }
    /* Boundary samples of the polygon, counter-clockwise, edge by edge. */
    tb_array ring;
    tb_array_init(&ring, sizeof(double) * 2);
    for (int k = 0; k < n && !m->st; k++) {
        int kk = ccw ? k : n - 1 - k; /* side kk runs from point kk to kk + 1; walk it ccw */
        double ax, ay, bx, by;
        tb_param_prism_point(g, ccw ? kk : kk + 1, &ax, &ay);
        tb_param_prism_point(g, ccw ? kk + 1 : kk, &bx, &by);
        int ns = tb__seg_line(r, hypot(bx - ax, by - ay));
        tb__bp us;
        if (!tb__bp_uniform(&us, 0, 1, ns)) {
            m->st = tb__nomem();
            break;
        }
        tb__mb_grid_uv(m, TB_FACE_PRISM_SIDE0 + kk, us.x, us.n, zs.x, zs.n);
        for (int i = 0; i < ns && !m->st; i++) {
            double t = us.x[i], p[2] = {ax + (bx - ax) * t, ay + (by - ay) * t};
            m->st = tb_array_push(&ring, p);
        }
        tb__bp_free(&us);
    }
    tb__bp_free(&zs);
    if (!m->st && g->caps) {
        uint32_t nr = (uint32_t)ring.len;
        const double *xy = (const double *)ring.data;
        tb_dvec3 *pts = malloc(sizeof(tb_dvec3) * nr);
        if (!pts) {
            m->st = tb__nomem();
        } else if (g->sides > 0) {
            /* Regular polygon: rings about the centre through every boundary sample. */
            tb__bp ts;
            if (!tb__bp_uniform(&ts, 0, 1, tb__seg_line(r, 1.0))) {
                m->st = tb__nomem();
            } else {
                for (int f = TB_FACE_PRISM_BOTTOM; f <= TB_FACE_PRISM_TOP; f++) {
                    double z = f == TB_FACE_PRISM_TOP ? 1.0 : -1.0;
                    for (uint32_t i = 0; i < nr; i++)
                        for (int j = 0; j < ts.n; j++) {
                            const double *a = &xy[2 * i], *b = &xy[2 * ((i + 1) % nr)];
                            double t0 = ts.x[j], t1 = ts.x[j + 1];
                            tb_dvec3 q[4] = {tb__v(t0 * a[0], t0 * a[1], z), tb__v(t0 * b[0], t0 * b[1], z),
                                             tb__v(t1 * b[0], t1 * b[1], z), tb__v(t1 * a[0], t1 * a[1], z)};
                            tb__mb_poly_pts(m, f, q, 4);
                        }
                }
            }
            tb__bp_free(&ts);
        } else {
            for (int f = TB_FACE_PRISM_BOTTOM; f <= TB_FACE_PRISM_TOP; f++) {
                for (uint32_t i = 0; i < nr; i++)
                    pts[i] = tb__v(xy[2 * i], xy[2 * i + 1], f == TB_FACE_PRISM_TOP ? 1.0 : -1.0);
                tb__flat_loop(m, r, f, pts, xy, nr);
            }
        }
        free(pts);
    }
    tb_array_free(&ring);
}

/* ---------------------------------------------------------------- conic */

/* Angle of the profile's tangent (d rho, dz) at z, as the direction
 * (q'(z), 2 rho) up to a positive factor: in [0, pi]. At an apex (a double
 * root of q: rho = q' = 0) the limit from the side `side` (+1 above, -1
 * below) of the cone there, r ~ sqrt(c2) |z - z_a|. */
static double tb__conic_tau(const tb_geom_conic *c, double z, int side)
{
    double rho = tb_safe_sqrt(tb_param_conic_r2(c, z)), dq = c->c[1] + 2.0 * c->c[2] * z;
    if (rho == 0.0 && dq == 0.0 && c->c[2] > 0.0)
        return atan2(sqrt(c->c[2]), side > 0 ? c->c[2] : -c->c[2]);
    return atan2(2.0 * rho, dq);
}

static tb_dvec3 tb__conic_pt(const tb_geom_conic *c, double z) { return tb__v(tb_safe_sqrt(tb_param_conic_r2(c, z)), 0.0, z); }

/* True if the profile from za to zb turns by at most the angle tolerance and
 * its chord is within the edge limit. r(z) is convex or concave on the whole
 * range (no inflection), so the turning is |tau(zb) - tau(za)|. */
static bool tb__conic_step_ok(const tb_geom_conic *c, const tb__res *r, double za, double zb)
{
    tb_dvec3 pa = tb__conic_pt(c, za), pb = tb__conic_pt(c, zb);
    if (hypot(pb.x - pa.x, pb.z - pa.z) <= r->floor)
        return true; /* a tight waist or tip below what float vertices resolve */
    if (r->angle > 0.0 && fabs(tb__conic_tau(c, zb, -1) - tb__conic_tau(c, za, 1)) > r->angle)
        return false;
    if (r->edge > 0.0) {
        tb_dvec3 a = tb__conic_pt(c, za), b = tb__conic_pt(c, zb);
        if (hypot(b.x - a.x, b.z - a.z) > r->edge)
            return false;
    }
    return true;
}

/* Heights from za to zb along the profile (za already in zs): greedy
 * longest steps within the limits. */
static bool tb__conic_run(const tb_geom_conic *c, const tb__res *r, double za, double zb, tb_array *zs)
{
    /* Steps below 1e-7 of the range resolve nothing float vertices can show
     * (a pole rounded to a tiny waist would otherwise take thousands). */
    double z = za, minstep = 1e-7 * (c->z1 - c->z0);
    while (z < zb) {
        double lo = z, hi = zb;
        if ((int)zs->len < r->maxseg && !tb__conic_step_ok(c, r, z, hi)) {
            for (int it = 0; it < 80; it++) {
                double mid = 0.5 * (lo + hi);
                if (tb__conic_step_ok(c, r, z, mid))
                    lo = mid;
                else
                    hi = mid;
            }
            hi = fmin(fmax(lo, z + minstep), zb);
        }
        z = hi;
        if (tb_array_push(zs, &z))
            return false;
    }
    return true;
}

/* Heights along the profile: greedy runs (split at an interior apex, where
 * two cones meet at a crease), then steps split until the chords on either
 * side of each smooth sample differ by at most the angle tolerance. */
static bool tb__conic_profile(const tb_geom_conic *c, const tb__res *r, double dphi, tb_array *zs)
{
    double ch = cos(0.5 * dphi); /* see tb__band_turn */
    double z0 = c->z0, z1 = c->z1, pinch = NAN;
    if (c->c[2] > 0.0) {
        double zv = -c->c[1] / (2.0 * c->c[2]);
        if (zv > z0 && zv < z1 && tb_param_conic_r2(c, zv) <= 0.0)
            pinch = zv;
    }
    if (tb_array_push(zs, &z0))
        return false;
    if (isnan(pinch) ? !tb__conic_run(c, r, z0, z1, zs)
                     : !tb__conic_run(c, r, z0, pinch, zs) || !tb__conic_run(c, r, pinch, z1, zs))
        return false;
    if (!(r->angle > 0.0))
        return true;
    for (int pass = 0; pass < 64; pass++) {
        bool split = false;
        for (size_t i = 1; i + 1 < zs->len && (int)zs->len < r->maxseg; i++) {
            double *Z = (double *)zs->data;
            if (Z[i] == pinch)
                continue;
            tb_dvec3 a = tb__conic_pt(c, Z[i - 1]), b = tb__conic_pt(c, Z[i]), d = tb__conic_pt(c, Z[i + 1]);
            double x1 = ch * (b.x - a.x), z1 = b.z - a.z, x2 = ch * (d.x - b.x), z2 = d.z - b.z;
            double diff = atan2(fabs(x1 * z2 - z1 * x2), x1 * x2 + z1 * z2);
            if (diff <= r->angle)
                continue;
            /* split the step that turns more, at its middle */
            size_t k = fabs(tb__conic_tau(c, Z[i], -1) - tb__conic_tau(c, Z[i - 1], 1)) >=
                               fabs(tb__conic_tau(c, Z[i + 1], -1) - tb__conic_tau(c, Z[i], 1))
                           ? i - 1
                           : i;
            double mid = 0.5 * (Z[k] + Z[k + 1]);
            if (!(mid > Z[k] && mid < Z[k + 1]))
                continue;
            if (tb_array_insert(zs, k + 1, &mid))
                return false;
            split = true;
        }
        if (!split)
            break;
    }
    return true;
}

static void tb__conic(tb__mb *m, const tb__res *r)
{
    const tb_geom_conic *c = &m->g->conic;
    double dz = c->z1 - c->z0;
    /* Widest radius: at an end or at the vertex of q. */
    double q = fmax(tb_param_conic_r2(c, c->z0), tb_param_conic_r2(c, c->z1));
    if (c->c[2] < 0.0) {
        double zv = -c->c[1] / (2.0 * c->c[2]);
        if (zv > c->z0 && zv < c->z1)
            q = fmax(q, tb_param_conic_r2(c, zv));
    }
    tb__bp us;
    tb_array zs;
    tb_array_init(&zs, sizeof(double));
    int nu = tb__seg_arc(r, tb_safe_sqrt(q), TB_2PI, 3);
    if (!tb__bp_uniform(&us, 0, 1, nu) || !tb__conic_profile(c, r, TB_2PI / nu, &zs)) {
        m->st = tb__nomem();
    } else {
        double *Z = (double *)zs.data;
        for (size_t i = 0; i < zs.len; i++)
            Z[i] = i + 1 == zs.len ? 1.0 : (Z[i] - c->z0) / dz; /* heights -> v */
        tb__mb_grid_uv(m, TB_FACE_CONIC_SIDE, us.x, us.n, Z, (int)zs.len - 1);
        for (int f = TB_FACE_CONIC_BOTTOM; f <= TB_FACE_CONIC_TOP; f++)
            if (tb_param_face_present(m->kind, m->g, f))
                tb__disc(m, r, f, tb_safe_sqrt(tb_param_conic_r2(c, f == TB_FACE_CONIC_BOTTOM ? c->z0 : c->z1)), &us);
    }
    tb__bp_free(&us);
    tb_array_free(&zs);
}

/* ---------------------------------------------------------------- arches */

/* Level j of a column of the front face over the opening, from its bottom b
 * (on the vault or ceiling) to z = 1: the pillars' levels ztop where b = zw,
 * else the same fractions of the column's height. */
static double tb__arch_level(double b, double zw, const tb__bp *ztop, int j)
{
    if (b == zw)
        return ztop->x[j];
    if (j == 0)
        return b;
    if (j == ztop->n)
        return 1.0;
    return b + (1.0 - b) * (ztop->x[j] - zw) / (1.0 - zw);
}

static void tb__arch(tb__mb *m, const tb__res *r)
{
    bool round = m->kind == TB_PRIM_ROUND_ARCH;
    double a = 0.5 * m->g->arch.width, h = m->g->arch.height;
    double zw = round ? -1.0 + h - a : -1.0 + h; /* where the straight walls end */
    int nwall = zw > -1.0 ? tb__seg_line(r, zw + 1.0) : 0, ntop = tb__seg_line(r, 1.0 - zw);
    int nth = round ? tb__seg_arc(r, a, TB_PI, 2) : tb__seg_line(r, 2.0 * a);
    tb__bp xl = {0}, xr = {0}, xm = {0}, xlm = {0}, xall = {0}, ys = {0}, zwall = {0}, ztop = {0}, zall = {0},
           th = {0};
    bool ok = tb__bp_uniform(&xl, -1, -a, tb__seg_line(r, 1.0 - a)) && tb__bp_uniform(&xr, a, 1, xl.n) &&
              tb__bp_uniform(&ys, -1, 1, tb__seg_line(r, 2.0)) && tb__bp_uniform(&ztop, zw, 1, ntop) &&
              tb__bp_uniform(&th, 0, 1, nth) && tb__bp_alloc(&xm, nth);
    if (ok) {
        /* The opening's x breakpoints, increasing: the vault's samples (theta
         * from pi down to 0) or a uniform ceiling. */
        for (int i = 0; i <= nth; i++)
            xm.x[i] = i == 0 ? -a : i == nth ? a : round ? a * cos(TB_PI * th.x[nth - i]) : -a + 2.0 * a * i / nth;
        ok = tb__bp_concat(&xlm, &xl, &xm) && tb__bp_concat(&xall, &xlm, &xr);
    }
    if (ok && nwall > 0)
        ok = tb__bp_uniform(&zwall, -1, zw, nwall) && tb__bp_concat(&zall, &zwall, &ztop);
    else if (ok)
        ok = tb__bp_uniform(&zall, zw, 1, ntop); /* no walls: zw = -1, the same as ztop */
    if (!ok) {
        m->st = tb__nomem();
        goto done;
    }
    /* outer sides, top, feet */
    tb__mb_grid_plane(m, TB_FACE_ARCH_NEG_X, tb__v(-1, 0, 0), tb__v(0, 1, 0), ys.x, ys.n, tb__v(0, 0, 1), zall.x, zall.n);
    tb__mb_grid_plane(m, TB_FACE_ARCH_POS_X, tb__v(1, 0, 0), tb__v(0, 1, 0), ys.x, ys.n, tb__v(0, 0, 1), zall.x, zall.n);
    tb__mb_grid_plane(m, TB_FACE_ARCH_TOP, tb__v(0, 0, 1), tb__v(1, 0, 0), xall.x, xall.n, tb__v(0, 1, 0), ys.x, ys.n);
    tb__mb_grid_plane(m, TB_FACE_ARCH_BOTTOM, tb__v(0, 0, -1), tb__v(1, 0, 0), xl.x, xl.n, tb__v(0, 1, 0), ys.x, ys.n);
    tb__mb_grid_plane(m, TB_FACE_ARCH_BOTTOM, tb__v(0, 0, -1), tb__v(1, 0, 0), xr.x, xr.n, tb__v(0, 1, 0), ys.x, ys.n);
    /* front and back: pillars, then columns over the opening from its top to z = 1 */
    for (int f = TB_FACE_ARCH_NEG_Y; f <= TB_FACE_ARCH_POS_Y; f++) {
        double y = f == TB_FACE_ARCH_NEG_Y ? -1.0 : 1.0;
        tb__mb_grid_plane(m, f, tb__v(0, y, 0), tb__v(1, 0, 0), xl.x, xl.n, tb__v(0, 0, 1), zall.x, zall.n);
        tb__mb_grid_plane(m, f, tb__v(0, y, 0), tb__v(1, 0, 0), xr.x, xr.n, tb__v(0, 0, 1), zall.x, zall.n);
        for (int i = 0; i < nth; i++) {
            /* the column's bottom at each side: on the vault (theta = pi th[nth - i]) or the ceiling */
            double x[2] = {xm.x[i], xm.x[i + 1]}, b[2];
            for (int e = 0; e < 2; e++) {
                int k = i + e;
                b[e] = !round || k == 0 || k == nth ? zw : zw + a * sin(TB_PI * th.x[nth - k]);
            }
            for (int j = 0; j < ntop; j++) {
                double zz[2][2]; /* [side][level j, j + 1] */
                for (int e = 0; e < 2; e++)
                    for (int l = 0; l < 2; l++)
                        zz[e][l] = tb__arch_level(b[e], zw, &ztop, j + l);
                tb_dvec3 q[4] = {tb__v(x[0], y, zz[0][0]), tb__v(x[1], y, zz[1][0]), tb__v(x[1], y, zz[1][1]),
                                 tb__v(x[0], y, zz[0][1])};
                tb__mb_poly_pts(m, f, q, 4);
            }
        }
    }
    /* the opening: walls and ceiling or vault */
    if (nwall > 0) {
        tb__mb_grid_plane(m, TB_FACE_ARCH_INNER_LEFT, tb__v(-a, 0, 0), tb__v(0, 1, 0), ys.x, ys.n, tb__v(0, 0, 1),
                          zwall.x, zwall.n);
        tb__mb_grid_plane(m, TB_FACE_ARCH_INNER_RIGHT, tb__v(a, 0, 0), tb__v(0, 1, 0), ys.x, ys.n, tb__v(0, 0, 1),
                          zwall.x, zwall.n);
    }
    if (round) {
        tb__bp vs;
        if (!tb__bp_uniform(&vs, 0, 1, ys.n)) {
            m->st = tb__nomem();
            goto done;
        }
        tb__mb_grid_uv(m, TB_FACE_ARCH_CEILING, th.x, th.n, vs.x, vs.n);
        tb__bp_free(&vs);
    } else {
        tb__mb_grid_plane(m, TB_FACE_ARCH_CEILING, tb__v(0, 0, zw), tb__v(1, 0, 0), xm.x, xm.n, tb__v(0, 1, 0), ys.x, ys.n);
    }
done:
    tb__bp_free(&xl), tb__bp_free(&xr), tb__bp_free(&xm), tb__bp_free(&xlm), tb__bp_free(&xall);
    tb__bp_free(&ys), tb__bp_free(&zwall), tb__bp_free(&ztop), tb__bp_free(&zall), tb__bp_free(&th);
}

/* ---------------------------------------------------------------- polygons */

/* Attributes carried by a polygon's tessellation points. */
typedef struct tb__attr {
    double u, v;
    tb_dvec3 n;
} tb__attr;

static void tb__polygons(tb__mb *m, const tb__res *r)
{
    const tb_geom_polygons *g = &m->g->polygons;
    tb_array pts, xy, at;
    tb_array_init(&pts, sizeof(tb_dvec3));
    tb_array_init(&xy, sizeof(double) * 2);
    tb_array_init(&at, sizeof(tb__attr));
    for (int f = 0; f < g->nfaces && !m->st; f++) {
        int b = g->face_start[f], nv = g->face_start[f + 1] - b;
        tb_dvec3 nrm;
        if ((m->st = tb_param_eval(m->kind, m->g, f, 0.5, 0.5, NULL, &nrm, NULL, NULL)))
            break;
        tb_dvec3 e1, e2;
        tb_dvec3_basis(nrm, &e1, &e2); /* e1 x e2 = nrm: counter-clockwise in (e1, e2) is the front */
        tb_array_clear(&pts), tb_array_clear(&xy), tb_array_clear(&at);
        /* The boundary, each edge sampled at the edge limit from its lower
         * vertex index, so that polygons sharing an edge compute the same points. */
        for (int i = 0; i < nv && !m->st; i++) {
            int ia = g->indices[b + i], ib = g->indices[b + (i + 1) % nv];
            int lo = ia < ib ? ia : ib, hi = ia < ib ? ib : ia;
            tb_dvec3 pl = tb_vec3_to_d(g->vertices[lo]), ph = tb_vec3_to_d(g->vertices[hi]);
            int ns = tb__seg_line(r, tb_dvec3_length(tb_dvec3_sub(ph, pl)));
            for (int s = 0; s < ns && !m->st; s++) {
                int k = ia < ib ? s : ns - s; /* sample k of ns from lo */
                double t = (double)k / ns;
                tb_dvec3 p = k == 0 ? pl : k == ns ? ph : tb_dvec3_lerp(pl, ph, t);
                /* the vertex's own attributes at corners, interpolated along the edge between */
                tb__attr a = {0, 0, nrm};
                int f2;
                if ((m->st = tb_param_from_point(m->kind, m->g, p, f, &f2, &a.u, &a.v)))
                    break;
                if (g->uvs) {
                    tb_vec2 ua = g->uvs[lo], uc = g->uvs[hi];
                    a.u = k == 0 ? ua.x : k == ns ? uc.x : ua.x + (uc.x - ua.x) * t;
                    a.v = k == 0 ? ua.y : k == ns ? uc.y : ua.y + (uc.y - ua.y) * t;
                }
                if (g->normals) {
                    tb_dvec3 w = tb_dvec3_lerp(tb_vec3_to_d(g->normals[lo]), tb_vec3_to_d(g->normals[hi]), t);
                    if (tb_dvec3_length(w) > 0.0)
                        a.n = tb_dvec3_normalize(w);
                }
                double q[2] = {tb_dvec3_dot(p, e1), tb_dvec3_dot(p, e2)};
                m->st = tb_array_push(&pts, &p);
                if (!m->st)
                    m->st = tb_array_push(&xy, q);
                if (!m->st)
                    m->st = tb_array_push(&at, &a);
            }
        }
        if (m->st)
            break;
        tb__tris t;
        tb__tris_init(&t);
        m->st = tb__tris_of_loop(&t, (const tb_dvec3 *)pts.data, (const double *)xy.data, (uint32_t)pts.len, r->edge);
        /* points made by refinement: the mean of the edge they split */
        for (size_t i = at.len; i < t.pts.len && !m->st; i++) {
            const uint32_t *par = &TB_ARRAY_AT(&t.parents, uint32_t, 2 * i);
            tb__attr a0 = TB_ARRAY_AT(&at, tb__attr, par[0]), a1 = TB_ARRAY_AT(&at, tb__attr, par[1]);
            tb__attr a = {0.5 * (a0.u + a1.u), 0.5 * (a0.v + a1.v), tb_dvec3_add(a0.n, a1.n)};
            a.n = tb_dvec3_length(a.n) > 0.0 ? tb_dvec3_normalize(a.n) : nrm;
            m->st = tb_array_push(&at, &a);
        }
        uint32_t *ids = m->st ? NULL : malloc(sizeof(uint32_t) * (t.pts.len ? t.pts.len : 1));
        if (!m->st && !ids)
            m->st = tb__nomem();
        for (size_t i = 0; i < t.pts.len && !m->st; i++) {
            const tb__attr *a = &TB_ARRAY_AT(&at, tb__attr, i);
            ids[i] = tb__mb_raw(m, f, TB_ARRAY_AT(&t.pts, tb_dvec3, i), a->n, a->u, a->v);
        }
        for (size_t k = 0; k < t.alive.len && !m->st; k++) {
            if (!TB_ARRAY_AT(&t.alive, bool, k))
                continue;
            const uint32_t *v = &TB_ARRAY_AT(&t.tris, uint32_t, 3 * k);
            uint32_t c[3] = {ids[v[0]], ids[v[1]], ids[v[2]]};
            tb__mb_loop(m, f, c, 3, false);
        }
        free(ids);
        tb__tris_free(&t);
    }
    tb_array_free(&pts);
    tb_array_free(&xy);
    tb_array_free(&at);
}

/* ---------------------------------------------------------------- welding */

/* Cell key of a point for the weld hash (cells of size `cell`). */
static uint64_t tb__cell_key(int64_t ix, int64_t iy, int64_t iz)
{
    return tb_hash_u64(tb_hash_u64(tb_hash_u64((uint64_t)ix) ^ (uint64_t)iy) ^ (uint64_t)iz);
}

/* Hash key of an exact position (-0 taken as +0). */
static uint64_t tb__exact_key(tb_dvec3 p)
{
    double c[3] = {p.x + 0.0, p.y + 0.0, p.z + 0.0};
    uint64_t b[3];
    memcpy(b, c, sizeof b);
    return tb_hash_u64(tb_hash_u64(tb_hash_u64(b[0]) ^ b[1]) ^ b[2]);
}

static uint32_t tb__uf_find(uint32_t *par, uint32_t i)
{
    while (par[i] != i)
        par[i] = par[par[i]], i = par[i];
    return i;
}

/* Welds pre-weld vertices into clusters of points chained by distances of at
 * most eps (in every coordinate; union-find, so a ring too small to resolve
 * collapses whole, like a pole): weld[i] is the welded index of pv i, rep[w]
 * the first pv of welded vertex w, whose position it takes. */
static tb_status tb__weld(const tb__mb *m, double eps, uint32_t *weld, tb_array *rep)
{
    const tb__pvert *pv = (const tb__pvert *)m->pv.data;
    size_t n = m->pv.len;
    double cell = 2.0 * eps;
    uint32_t *par = malloc(sizeof(uint32_t) * (n ? n : 1)), *next = malloc(sizeof(uint32_t) * (n ? n : 1));
    tb_htab h;
    tb_htab_init(&h, TB_HTAB_U64);
    tb_status st = par && next ? tb_htab_reserve(&h, n / 2 + 16) : tb__nomem();
    tb_htab exact; /* exact position -> first pv there: most corners repeat a grid point */
    tb_htab_init(&exact, TB_HTAB_U64);
    if (!st)
        st = tb_htab_reserve(&exact, n / 3 + 16);
    for (size_t i = 0; i < n && !st; i++) {
        tb_dvec3 p = pv[i].p;
        par[i] = (uint32_t)i;
        uint64_t ek = tb__exact_key(p), first;
        if (tb_htab_get(&exact, ek, &first) && pv[first].p.x == p.x && pv[first].p.y == p.y && pv[first].p.z == p.z) {
            /* Everything within eps of p was met by that pv, or will meet it. */
            uint32_t a = tb__uf_find(par, (uint32_t)i), b = tb__uf_find(par, (uint32_t)first);
            par[a > b ? a : b] = a < b ? a : b;
            continue;
        }
        st = tb_htab_put(&exact, ek, i);
        /* Cells are 2 eps wide, so the eps box about p meets 2 per axis: this
         * one and the neighbour on the side p is nearer to. */
        double fx = p.x / cell, fy = p.y / cell, fz = p.z / cell;
        int64_t ix = (int64_t)floor(fx), iy = (int64_t)floor(fy), iz = (int64_t)floor(fz);
        int sx = fx - (double)ix < 0.5 ? -1 : 1, sy = fy - (double)iy < 0.5 ? -1 : 1, sz = fz - (double)iz < 0.5 ? -1 : 1;
        bool same = false; /* an earlier pv at exactly this point stands for it in the cell lists */
        for (int d = 0; d < 8 && !st; d++) {
            uint64_t head;
            if (!tb_htab_get(&h, tb__cell_key(ix + (d & 1 ? sx : 0), iy + (d & 2 ? sy : 0), iz + (d & 4 ? sz : 0)), &head))
                continue;
            for (uint32_t j = (uint32_t)head; j != UINT32_MAX; j = next[j]) {
                tb_dvec3 q = pv[j].p;
                if (fabs(q.x - p.x) <= eps && fabs(q.y - p.y) <= eps && fabs(q.z - p.z) <= eps) {
                    uint32_t a = tb__uf_find(par, (uint32_t)i), b = tb__uf_find(par, j);
                    if (a != b)
                        par[a > b ? a : b] = a < b ? a : b; /* the root is the cluster's first pv */
                    same |= q.x == p.x && q.y == p.y && q.z == p.z;
                }
            }
        }
        if (!same) {
            uint64_t key = tb__cell_key(ix, iy, iz), old;
            next[i] = tb_htab_get(&h, key, &old) ? (uint32_t)old : UINT32_MAX;
            st = tb_htab_put(&h, key, i);
        }
    }
    for (size_t i = 0; i < n && !st; i++) {
        uint32_t r = tb__uf_find(par, (uint32_t)i);
        if (r == i) {
            weld[i] = (uint32_t)rep->len;
            uint32_t pi = (uint32_t)i;
            st = tb_array_push(rep, &pi);
        } else {
            weld[i] = weld[r]; /* r < i: done */
        }
    }
    free(par);
    free(next);
    tb_htab_free(&h);
    tb_htab_free(&exact);
    return st;
}

/* True if a welded loop repeats a vertex or has (nearly) no area: FED
 * rejects loops of area below TB_FED_DEGENERATE_REL times their size squared;
 * drop those within 4 times that. */
static bool tb__loop_degenerate(const tb__pvert *pv, const uint32_t *weld, const tb_array *rep, const uint32_t *c,
                                uint32_t k)
{
    tb_vec3 q[64];
    for (uint32_t a = 0; a < k; a++) {
        for (uint32_t b = a + 1; b < k; b++)
            if (weld[c[a]] == weld[c[b]])
                return true;
        q[a] = tb_dvec3_to_f(pv[TB_ARRAY_AT(rep, uint32_t, weld[c[a]])].p);
    }
    double area = 0.5 * tb_dvec3_length(tb_polygon_newell(q, NULL, k)), size = tb_polygon_size(q, NULL, k);
    return !(area > 4.0 * TB_FED_DEGENERATE_REL * size * size);
}

/* Orders pre-weld vertices for choosing a welded vertex's (u, v): lowest face,
 * then u, then v. */
static bool tb__pv_before(const tb__pvert *a, const tb__pvert *b)
{
    if (a->face != b->face)
        return a->face < b->face;
    if (a->u != b->u)
        return a->u < b->u;
    return a->v < b->v;
}

/* Key of a split vertex: welded id, face, u, v. */
static uint64_t tb__split_key(uint32_t w, const tb__pvert *p)
{
    uint64_t ub, vb;
    memcpy(&ub, &p->u, 8), memcpy(&vb, &p->v, 8);
    return tb_hash_u64(tb_hash_u64(tb_hash_u64(((uint64_t)w << 20) ^ (uint64_t)(uint32_t)p->face) ^ ub) ^ vb);
}

/* Welds, cleans the polygons and builds the FED mesh. */
static tb_status tb__finish(tb__mb *m, bool split, double size, tb_fed **out)
{
    size_t npv = m->pv.len;
    const tb__pvert *pv = (const tb__pvert *)m->pv.data;
    uint32_t *weld = malloc(sizeof(uint32_t) * (npv ? npv : 1));
    tb_array rep, vpos, vnrm, vuv, loops, corners, fids, best, nsum, lastface;
    tb_array_init(&rep, sizeof(uint32_t));
    tb_array_init(&vpos, sizeof(tb_vec3));
    tb_array_init(&vnrm, sizeof(tb_vec3));
    tb_array_init(&vuv, sizeof(tb_vec2));
    tb_array_init(&loops, sizeof(uint32_t));
    tb_array_init(&corners, sizeof(uint32_t));
    tb_array_init(&fids, sizeof(int32_t));
    tb_array_init(&best, sizeof(uint32_t));
    tb_array_init(&nsum, sizeof(tb_dvec3));
    tb_array_init(&lastface, sizeof(int));
    tb_htab splitmap;
    tb_htab_init(&splitmap, TB_HTAB_U64);
    uint32_t *final = malloc(sizeof(uint32_t) * (npv ? npv : 1)); /* pv -> output vertex */
    tb_status st = weld && final ? TB_OK : tb__nomem();
    /* About float resolution of the object's size: far below any sample
     * spacing the segment caps allow, far above double rounding. */
    double eps = TB__WELD_REL * size;
    if (!st)
        st = tb__weld(m, eps, weld, &rep);
    size_t nw = rep.len;
    /* Per welded vertex: the pv giving its (u, v), and the sum of the normals
     * of the distinct faces meeting there. */
    if (!st)
        st = tb_array_resize(&best, nw);
    if (!st)
        st = tb_array_resize(&nsum, nw);
    if (!st)
        st = tb_array_resize(&lastface, nw);
    for (size_t w = 0; w < nw && !st; w++) {
        TB_ARRAY_AT(&best, uint32_t, w) = TB_ARRAY_AT(&rep, uint32_t, w);
        TB_ARRAY_AT(&lastface, int, w) = -1;
    }
    /* Each face's pre-weld vertices are made one after the other, so a change
     * of face among a welded vertex's members marks a face not summed yet. */
    for (size_t i = 0; i < npv && !st; i++) {
        uint32_t w = weld[i];
        uint32_t *b = &TB_ARRAY_AT(&best, uint32_t, w);
        if (tb__pv_before(&pv[i], &pv[*b]))
            *b = (uint32_t)i;
        int *lf = &TB_ARRAY_AT(&lastface, int, w);
        if (*lf != pv[i].face) {
            tb_dvec3 *s = &TB_ARRAY_AT(&nsum, tb_dvec3, w);
            *s = tb_dvec3_add(*s, pv[i].n);
            *lf = pv[i].face;
        }
    }
    /* Polygons: welded corners, repeats (at poles) removed; then each kept
     * corner's output vertex, made at first use: one per welded vertex, or
     * per (welded vertex, face, u, v) when splitting. */
    tb_array owner; /* split: the pv each output vertex was made from (to confirm hash hits) */
    tb_array_init(&owner, sizeof(uint32_t));
    for (size_t i = 0; i < npv; i++)
        final[i] = UINT32_MAX; /* welded mode: indexed by welded vertex */
    const uint32_t *ln = (const uint32_t *)m->loop_n.data, *cs = (const uint32_t *)m->corner.data;
    const int32_t *fi = (const int32_t *)m->fid.data;
    size_t c0 = 0;
    uint32_t tmp[64];
    for (size_t l = 0; l < m->loop_n.len && !st; l++) {
        uint32_t n = ln[l], k = 0;
        uint32_t *buf = n <= 64 ? tmp : malloc(sizeof(uint32_t) * n);
        if (!buf) {
            st = tb__nomem();
            break;
        }
        for (uint32_t i = 0; i < n; i++) {
            uint32_t pi = cs[c0 + i];
            if (k == 0 || weld[buf[k - 1]] != weld[pi])
                buf[k++] = pi;
        }
        while (k > 1 && weld[buf[k - 1]] == weld[buf[0]])
            k--;
        c0 += n;
        /* A loop that still repeats a vertex (two corners welded across it) or
         * has no area left is dropped; a quad whose float corners are not
         * planar becomes two triangles (util/mesh's diagonal choice). */
        uint32_t pieces[2][4], npieces = 0, psize = k;
        if (k >= 3 && k <= 64 && !tb__loop_degenerate(pv, weld, &rep, buf, k)) {
            tb_vec3 q[4];
            for (uint32_t c = 0; c < k && k == 4; c++)
                q[c] = tb_dvec3_to_f(pv[TB_ARRAY_AT(&rep, uint32_t, weld[buf[c]])].p);
            if (k == 4 && !tb_polygon_is_planar(q, NULL, 4, 0.0)) {
                uint32_t tri[6];
                tb_quad_split_corners(tb_quad_split_diagonal(q[0], q[1], q[2], q[3]), tri);
                for (int t = 0; t < 6; t++)
                    pieces[t / 3][t % 3] = buf[tri[t]];
                npieces = 2, psize = 3;
            } else {
                memcpy(pieces[0], buf, sizeof(uint32_t) * (k < 4 ? k : 4));
                npieces = 1;
            }
        }
        for (uint32_t pc = 0; pc < npieces && !st; pc++) {
            const uint32_t *piece = k <= 4 ? pieces[pc] : buf;
            uint32_t kk = psize;
            st = tb_array_push(&loops, &kk);
            for (uint32_t c = 0; c < kk && !st; c++) {
                uint32_t i = piece[c], w = weld[i], r0 = TB_ARRAY_AT(&rep, uint32_t, w), id = UINT32_MAX;
                uint64_t key = 0;
                const tb__pvert *src;
                if (split) {
                    key = tb__split_key(w, &pv[i]);
                    uint64_t have;
                    while (tb_htab_get(&splitmap, key, &have)) {
                        uint32_t o = TB_ARRAY_AT(&owner, uint32_t, have);
                        if (weld[o] == w && pv[o].face == pv[i].face && pv[o].u == pv[i].u && pv[o].v == pv[i].v) {
                            id = (uint32_t)have;
                            break;
                        }
                        key = tb_hash_u64(key + 1); /* another vertex under this key: probe on */
                    }
                    src = &pv[i];
                } else {
                    id = final[w];
                    src = &pv[TB_ARRAY_AT(&best, uint32_t, w)];
                }
                if (id == UINT32_MAX) {
                    id = (uint32_t)vpos.len;
                    tb_dvec3 nv = src->n;
                    if (!split) {
                        tb_dvec3 sum = TB_ARRAY_AT(&nsum, tb_dvec3, w);
                        double len = tb_dvec3_length(sum);
                        if (len > 0.0)
                            nv = tb_dvec3_scale(sum, 1.0 / len);
                        final[w] = id;
                    }
                    /* The representative's position: identical for every split copy. */
                    tb_vec3 pf = tb_dvec3_to_f(pv[r0].p), nf = tb_dvec3_to_f(nv);
                    tb_vec2 uvf = {(float)src->u, (float)src->v};
                    st = tb_array_push(&vpos, &pf);
                    if (!st)
                        st = tb_array_push(&vnrm, &nf);
                    if (!st)
                        st = tb_array_push(&vuv, &uvf);
                    if (!st && split)
                        st = tb_array_push(&owner, &i);
                    if (!st && split)
                        st = tb_htab_put(&splitmap, key, id);
                }
                if (!st)
                    st = tb_array_push(&corners, &id);
            }
            if (!st)
                st = tb_array_push(&fids, &fi[l]);
        }
        if (buf != tmp)
            free(buf);
    }
    tb_array_free(&owner);
    if (!st) {
        tb_fed_desc d = {
            .nverts = (uint32_t)vpos.len,
            .positions = (const tb_vec3 *)vpos.data,
            .normals = (const tb_vec3 *)vnrm.data,
            .uvs = (const tb_vec2 *)vuv.data,
            .nfaces = (uint32_t)loops.len,
            .nloops = (uint32_t)loops.len,
            .loop_sizes = (const uint32_t *)loops.data,
            .corners = (const uint32_t *)corners.data,
            .face_ids = (const int32_t *)fids.data,
        };
        st = tb_fed_build(&d, out, NULL);
        if (!st)
            tb_stat_add(&tb__poly_faces, (int64_t)loops.len);
    }
    free(weld);
    free(final);
    tb_array_free(&rep), tb_array_free(&vpos), tb_array_free(&vnrm), tb_array_free(&vuv);
    tb_array_free(&loops), tb_array_free(&corners), tb_array_free(&fids);
    tb_array_free(&best), tb_array_free(&nsum), tb_array_free(&lastface);
    tb_htab_free(&splitmap);
    return st;
}

/* ---------------------------------------------------------------- entry */

tb_status tb_polygonize(tb_prim_kind kind, const tb_mid_geometry *geom, const tb_poly_options *opt, tb_fed **out)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "polygonize: NULL output");
    *out = NULL;
    if (tb_prim_is_csg(kind))
        return tb_error(TB_ERR_UNSUPPORTED, "polygonize: CSG nodes are not tessellated (tessellate the children)");
    tb_status st = tb_param_check(kind, geom);
    if (st)
        return st;
    tb_poly_options o = opt ? *opt : (tb_poly_options){0};
    if (!(o.max_edge >= 0.0) || !(o.max_angle >= 0.0) || !isfinite(o.max_edge) || !isfinite(o.max_angle) ||
        o.max_segments < 0)
        return tb_error(TB_ERR_ARG, "polygonize: limits must be finite and >= 0 (max_edge %g, max_angle %g)",
                        o.max_edge, o.max_angle);
    tb__count(kind);
    tb__res r = {o.max_edge, o.max_angle, o.max_segments ? o.max_segments : TB_POLY_DEFAULT_SEGMENTS, 0.0, 0.0};
    if (r.maxseg > TB_POLY_MAX_SEGMENTS)
        r.maxseg = TB_POLY_MAX_SEGMENTS;
    if (r.edge > 0.0 && o.to_world)
        r.edge /= tb_bounds_max_stretch(o.to_world); /* an object edge of this length is at most max_edge in the world */
    if (r.angle == 0.0 && r.edge == 0.0)
        r.angle = TB_POLY_DEFAULT_ANGLE;
    tb_aabb box;
    if ((st = tb_bounds_object(kind, geom, &box)))
        return st;
    double size = tb_aabb_is_empty(&box) ? 1.0 : tb_dvec3_length(tb_dvec3_sub(tb_vec3_to_d(box.hi), tb_vec3_to_d(box.lo)));
    r.floor = 1e-5 * size;
    r.weld = TB__WELD_REL * size;

    tb__mb m;
    tb__mb_init(&m, kind, geom);
    switch (kind) {
    case TB_PRIM_SPHERE: tb__sphere(&m, &r); break;
    case TB_PRIM_CUBE: tb__pyramid(&m, &r, 1.0, true, true); break;
    case TB_PRIM_CYLINDER: tb__cone(&m, &r, 1.0, geom->cylinder.caps); break;
    case TB_PRIM_CONE: tb__cone(&m, &r, geom->cone.top_radius, geom->cone.caps); break;
    case TB_PRIM_PYRAMID:
        tb__pyramid(&m, &r, geom->pyramid.top, geom->pyramid.caps, geom->pyramid.caps && geom->pyramid.top > 0.0);
        break;
    case TB_PRIM_PRISM: tb__prism(&m, &r); break;
    case TB_PRIM_TORUS: tb__torus(&m, &r); break;
    case TB_PRIM_POLYGONS: tb__polygons(&m, &r); break;
    case TB_PRIM_CONIC: tb__conic(&m, &r); break;
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH: tb__arch(&m, &r); break;
    default: m.st = tb_error(TB_ERR_ARG, "polygonize: unknown kind %d", (int)kind); break;
    }
    st = m.st;
    if (!st)
        st = tb__finish(&m, o.split, size, out);
    tb__mb_free(&m);
    if (st)
        return tb_error_context(st, "polygonize %s", tb_prim_kind_name(kind));
    return TB_OK;
}
