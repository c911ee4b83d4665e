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

/* ------------------------------------------------------------ resolution */

/* The resolved options, in object space. */
typedef struct tb__res {
    double edge;  /* longest edge, object units; 0: none */
    double angle; /* largest facet-normal angle, radians; 0: none */
    int maxseg;   /* segments per direction */
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

/* A quad (or triangle, n = 3) given by (u, v) corners. */
static void tb__mb_poly_uv(tb__mb *m, int face, const double (*uv)[2], int n)
{
    uint32_t c[4];
    for (int i = 0; i < n; i++)
        c[i] = tb__mb_uv(m, face, uv[i][0], uv[i][1]);
    tb__mb_poly_oriented(m, face, c, n);
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
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++) {
            double q[4][2] = {{us[i], vs[j]}, {us[i + 1], vs[j]}, {us[i + 1], vs[j + 1]}, {us[i], vs[j + 1]}};
            tb__mb_poly_uv(m, face, q, 4);
        }
}

/* The quads of the planar grid o + a[i] ea + b[j] eb on a flat face. */
static void tb__mb_grid_plane(tb__mb *m, int face, tb_dvec3 o, tb_dvec3 ea, const double *a, int na, tb_dvec3 eb,
                              const double *b, int nb)
{
    for (int j = 0; j < nb; j++)
        for (int i = 0; i < na; i++) {
            tb_dvec3 q[4];
            double ai[4] = {a[i], a[i + 1], a[i + 1], a[i]}, bj[4] = {b[j], b[j], b[j + 1], b[j + 1]};
            for (int k = 0; k < 4; k++)
                q[k] = tb_dvec3_add(o, tb_dvec3_add(tb_dvec3_scale(ea, ai[k]), tb_dvec3_scale(eb, bj[k])));
            tb__mb_poly_pts(m, face, q, 4);
        }
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
    tb__bp vs;
    if (!tb__bp_uniform(&vs, 0.0, 1.0, tb__seg_line(r, R))) {
        m->st = tb_error(TB_ERR_NOMEM, "polygonize: out of memory");
        return;
    }
    tb__mb_grid_uv(m, face, us->x, us->n, vs.x, vs.n);
    tb__bp_free(&vs);
}

static tb_status tb__nomem(void) { return tb_error(TB_ERR_NOMEM, "polygonize: out of memory"); }

static void tb__sphere(tb__mb *m, const tb__res *r)
{
    tb__bp us, vs;
    if (!tb__bp_uniform(&us, 0, 1, tb__seg_arc(r, 1.0, TB_2PI, 3)) ||
        !tb__bp_uniform(&vs, 0, 1, tb__seg_arc(r, 1.0, TB_PI, 2))) {
        m->st = tb__nomem();
    } else {
        tb__mb_grid_uv(m, TB_FACE_SPHERE, us.x, us.n, vs.x, vs.n);
    }
    tb__bp_free(&us), tb__bp_free(&vs);
}

/* Cylinder and cone frustum: radius 1 at z = -1, r at z = 1. */
static void tb__cone(tb__mb *m, const tb__res *r, double top, bool caps)
{
    tb__bp us, vs;
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
    tb__bp us, vs;
    if (!tb__bp_uniform(&us, 0, 1, tb__seg_arc(r, t->major + t->minor, TB_2PI, 3)) ||
        !tb__bp_uniform(&vs, 0, 1, tb__seg_arc(r, t->minor, TB_2PI, 3))) {
        m->st = tb__nomem();
    } else {
        tb__mb_grid_uv(m, TB_FACE_TORUS, us.x, us.n, vs.x, vs.n);
    }
    tb__bp_free(&us), tb__bp_free(&vs);
}

/* Cube and pyramid frustum (top half-size t; t = 1 the cube). */
static void tb__pyramid(tb__mb *m, const tb__res *r, double t, bool bottom, bool top)
{
    tb__bp hs, vs, ht;
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

/* A polygon face given as one loop of points on a flat face: triangulated
 * (util/mesh), every point kept. `xy` are plane coordinates of the points. */
static void tb__flat_loop(tb__mb *m, int face, const tb_dvec3 *pts, const double *xy, uint32_t n)
{
    tb_array tris;
    tb_array_init(&tris, sizeof(tb_tri));
    tb_status st = tb_triangulate_2d(xy, &n, 1, &tris, NULL);
    if (st) {
        m->st = st;
        tb_array_free(&tris);
        return;
    }
    uint32_t *ids = malloc(sizeof(uint32_t) * n);
    if (!ids) {
        m->st = tb__nomem();
        tb_array_free(&tris);
        return;
    }
    for (uint32_t i = 0; i < n; i++)
        ids[i] = tb__mb_pt(m, face, pts[i]);
    for (size_t k = 0; k < tris.len && !m->st; k++) {
        const tb_tri *t = &TB_ARRAY_AT(&tris, tb_tri, k);
        uint32_t c[3] = {ids[t->v[0]], ids[t->v[1]], ids[t->v[2]]};
        tb__mb_poly_oriented(m, face, c, 3);
    }
    free(ids);
    tb_array_free(&tris);
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
                tb__flat_loop(m, f, pts, xy, nr);
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
    double z = za;
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
            if (lo > z)
                hi = lo; /* else a step too small to satisfy: take the tiny one */
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
static bool tb__conic_profile(const tb_geom_conic *c, const tb__res *r, tb_array *zs)
{
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
            double diff = fabs(atan2(d.z - b.z, d.x - b.x) - atan2(b.z - a.z, b.x - a.x));
            if (diff > TB_PI)
                diff = TB_2PI - diff;
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
    if (!tb__bp_uniform(&us, 0, 1, tb__seg_arc(r, tb_safe_sqrt(q), TB_2PI, 3)) || !tb__conic_profile(c, r, &zs)) {
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

static void tb__polygons(tb__mb *m, const tb__res *r)
{
    const tb_geom_polygons *g = &m->g->polygons;
    tb_array pts, xy;
    tb_array_init(&pts, sizeof(uint32_t));
    tb_array_init(&xy, sizeof(double) * 2);
    for (int f = 0; f < g->nfaces && !m->st; f++) {
        int b = g->face_start[f], nv = g->face_start[f + 1] - b;
        tb_dvec3 nrm;
        if ((m->st = tb_param_eval(m->kind, m->g, f, 0.5, 0.5, NULL, &nrm, NULL, NULL)))
            break;
        tb_dvec3 e1, e2;
        tb_dvec3_basis(nrm, &e1, &e2);
        tb_array_clear(&pts), tb_array_clear(&xy);
        for (int i = 0; i < nv && !m->st; i++) {
            int ia = g->indices[b + i], ib = g->indices[b + (i + 1) % nv];
            /* Sample shared edges from the lower vertex index, so that both
             * polygons using an edge compute the same points. */
            int lo = ia < ib ? ia : ib, hi = ia < ib ? ib : ia;
            tb_dvec3 pl = tb_vec3_to_d(g->vertices[lo]), ph = tb_vec3_to_d(g->vertices[hi]);
            int ns = tb__seg_line(r, tb_dvec3_length(tb_dvec3_sub(ph, pl)));
            for (int s = 0; s < ns && !m->st; s++) {
                int k = ia < ib ? s : ns - s; /* sample k of ns from lo */
                double t = (double)k / ns;
                tb_dvec3 p = k == 0 ? pl : k == ns ? ph : tb_dvec3_lerp(pl, ph, t);
                /* attributes: the vertex's own at corners, else interpolated along the edge */
                int f2;
                double u, v;
                tb_dvec3 n = nrm;
                if ((m->st = tb_param_from_point(m->kind, m->g, p, f, &f2, &u, &v)))
                    break;
                if (g->uvs && (k == 0 || k == ns)) {
                    tb_vec2 uv = g->uvs[k == 0 ? lo : hi];
                    u = uv.x, v = uv.y;
                } else if (g->uvs) {
                    tb_vec2 a = g->uvs[lo], c = g->uvs[hi];
                    u = a.x + (c.x - a.x) * t, v = a.y + (c.y - a.y) * t;
                }
                if (g->normals) {
                    tb_dvec3 na = tb_vec3_to_d(g->normals[lo]), nc = tb_vec3_to_d(g->normals[hi]);
                    tb_dvec3 w = tb_dvec3_lerp(na, nc, t);
                    if (tb_dvec3_length(w) > 0.0)
                        n = tb_dvec3_normalize(w);
                }
                uint32_t id = tb__mb_raw(m, f, p, n, u, v);
                double q[2] = {tb_dvec3_dot(p, e1), tb_dvec3_dot(p, e2)};
                if (!m->st)
                    m->st = tb_array_push(&pts, &id);
                if (!m->st)
                    m->st = tb_array_push(&xy, q);
            }
        }
        if (m->st)
            break;
        uint32_t n = (uint32_t)pts.len;
        tb_array tris;
        tb_array_init(&tris, sizeof(tb_tri));
        /* e1 x e2 = nrm, so loops turning counter-clockwise in (e1, e2) face the front */
        m->st = tb_triangulate_2d((const double *)xy.data, &n, 1, &tris, NULL);
        for (size_t k = 0; k < tris.len && !m->st; k++) {
            const tb_tri *t = &TB_ARRAY_AT(&tris, tb_tri, k);
            const uint32_t *ids = (const uint32_t *)pts.data;
            uint32_t c[3] = {ids[t->v[0]], ids[t->v[1]], ids[t->v[2]]};
            tb__mb_loop(m, f, c, 3, false);
        }
        tb_array_free(&tris);
    }
    tb_array_free(&pts);
    tb_array_free(&xy);
}

/* ---------------------------------------------------------------- welding */

/* Cell key of a point for the weld hash (cells of size `cell`). */
static uint64_t tb__cell_key(int64_t ix, int64_t iy, int64_t iz)
{
    return tb_hash_u64(tb_hash_u64(tb_hash_u64((uint64_t)ix) ^ (uint64_t)iy) ^ (uint64_t)iz);
}

/* Welds pre-weld vertices closer than eps (in every coordinate): weld[i] is
 * the welded index of pv i, rep[w] the first pv of welded vertex w. */
static tb_status tb__weld(const tb__mb *m, double eps, uint32_t *weld, tb_array *rep)
{
    const tb__pvert *pv = (const tb__pvert *)m->pv.data;
    size_t n = m->pv.len;
    double cell = 2.0 * eps;
    tb_htab h;
    tb_htab_init(&h, TB_HTAB_U64);
    tb_array next; /* per welded vertex: the next one in its cell's list, UINT32_MAX at the end */
    tb_array_init(&next, sizeof(uint32_t));
    tb_status st = tb_htab_reserve(&h, n / 2 + 16);
    for (size_t i = 0; i < n && !st; i++) {
        tb_dvec3 p = pv[i].p;
        int64_t ix = (int64_t)floor(p.x / cell), iy = (int64_t)floor(p.y / cell), iz = (int64_t)floor(p.z / cell);
        uint32_t found = UINT32_MAX;
        for (int d = 0; d < 27 && found == UINT32_MAX; d++) {
            uint64_t head;
            if (!tb_htab_get(&h, tb__cell_key(ix + d % 3 - 1, iy + d / 3 % 3 - 1, iz + d / 9 - 1), &head))
                continue;
            for (uint32_t w = (uint32_t)head; w != UINT32_MAX; w = TB_ARRAY_AT(&next, uint32_t, w)) {
                tb_dvec3 q = pv[TB_ARRAY_AT(rep, uint32_t, w)].p;
                if (fabs(q.x - p.x) <= eps && fabs(q.y - p.y) <= eps && fabs(q.z - p.z) <= eps) {
                    found = w;
                    break;
                }
            }
        }
        if (found == UINT32_MAX) {
            found = (uint32_t)rep->len;
            uint32_t pi = (uint32_t)i, head = UINT32_MAX;
            uint64_t key = tb__cell_key(ix, iy, iz), old;
            if (tb_htab_get(&h, key, &old))
                head = (uint32_t)old;
            st = tb_array_push(rep, &pi);
            if (!st)
                st = tb_array_push(&next, &head);
            if (!st)
                st = tb_htab_put(&h, key, found);
        }
        weld[i] = found;
    }
    tb_htab_free(&h);
    tb_array_free(&next);
    return st;
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
    double eps = 2e-7 * size;
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
        if (k >= 3) {
            st = tb_array_push(&loops, &k);
            for (uint32_t c = 0; c < k && !st; c++) {
                uint32_t i = buf[c], w = weld[i], r0 = TB_ARRAY_AT(&rep, uint32_t, w), id = UINT32_MAX;
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
    tb__res r = {o.max_edge, o.max_angle, o.max_segments ? o.max_segments : TB_POLY_DEFAULT_SEGMENTS};
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
