/* Ray-cast form factors (Wallace, Elmquist and Haines 1989) and the
 * occluders they test visibility against (docs/formfactors.md). */
#include "host/radiosity/formfactor_internal.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>

#include "host/object/bounds.h"
#include "host/object/intersect.h"
#include "host/object/object.h"
#include "host/render/accel.h"
#include "util/math/transform.h"
#include "util/stats/stats.h"

TB_STAT_COUNTER(tb__ff_shafts, "Form factors/shafts");
TB_STAT_COUNTER(tb__ff_shafts_full, "Form factors/shafts with too many occluders");
TB_STAT_COUNTER(tb__ff_shaft_tris, "Form factors/occluders listed in shafts");
TB_STAT_COUNTER(tb__ff_shafts_empty, "Form factors/shafts with no occluder");

#define TB__PI 3.14159265358979323846

double tb_ff_raycast(const tb_vec3 *pts, int npts, tb_vec3 ns, double area, tb_vec3 p, tb_vec3 n,
                     tb_ff_visible_fn visible, void *ctx)
{
    if (!pts || npts < 1 || !(area > 0.0))
        return 0.0;
    double da = area / npts;
    tb_dvec3 pd = tb__ff_d(p), nd = tb__ff_d(n), nsd = tb__ff_d(ns);
    double sum = 0.0;
    for (int k = 0; k < npts; k++) {
        tb_dvec3 d = tb_dvec3_sub(tb__ff_d(pts[k]), pd); /* receiver -> sample */
        double r2 = tb_dvec3_length2(d);
        if (!(r2 > 0.0))
            continue;
        double cr = tb_dvec3_dot(nd, d);  /* r cos(receiver) */
        double cs = -tb_dvec3_dot(nsd, d); /* r cos(shooter) */
        if (!(cr > 0.0 && cs > 0.0))
            continue; /* behind either surface: no exchange, no ray */
        if (visible && !visible(ctx, p, pts[k]))
            continue;
        /* cos_r cos_s dA / (pi r^2 + dA): the form factor of a disk of area dA
         * facing the receiver, bounded where r is small. */
        sum += (cr * cs / r2) * da / (TB__PI * r2 + da);
    }
    return sum;
}

double tb_ff_raycast_visible_fraction(const tb_vec3 *pts, int npts, tb_vec3 ns, double area, tb_vec3 p, tb_vec3 n,
                                      tb_ff_visible_fn visible, void *ctx)
{
    if (!pts || npts < 1 || !(area > 0.0))
        return -1.0;
    double da = area / npts;
    tb_dvec3 pd = tb__ff_d(p), nd = tb__ff_d(n), nsd = tb__ff_d(ns);
    double all = 0.0, seen = 0.0;
    for (int k = 0; k < npts; k++) {
        tb_dvec3 d = tb_dvec3_sub(tb__ff_d(pts[k]), pd);
        double r2 = tb_dvec3_length2(d);
        if (!(r2 > 0.0))
            continue;
        double cr = tb_dvec3_dot(nd, d), cs = -tb_dvec3_dot(nsd, d);
        if (!(cr > 0.0 && cs > 0.0))
            continue;
        /* the same weight as tb_ff_raycast's, so with one visibility
         * pattern the fraction is Wallace's occluded over unoccluded sum */
        double w = (cr * cs / r2) * da / (TB__PI * r2 + da);
        all += w;
        if (!visible || visible(ctx, p, pts[k]))
            seen += w;
    }
    if (!(all > 0.0))
        return -1.0;
    double f = seen / all;
    return f > 1.0 ? 1.0 : f;
}

double tb_ff_raycast_exact(const tb_ff_polygon *shooter, const tb_vec3 *pts, int npts, tb_vec3 p, tb_vec3 n,
                           tb_ff_visible_fn visible, void *ctx)
{
    tb_vec3 inside;
    double exact = tb__ff_point_polygon_ex(p, n, shooter, &inside);
    if (!(exact > 0.0) || !visible)
        return exact > 0.0 ? exact : 0.0; /* no exchange, or nothing to hide it: no rays */
    tb_vec3 ns;
    double area;
    tb_ff_polygon_frame(shooter, &ns, &area);
    double frac = tb_ff_raycast_visible_fraction(pts, npts, ns, area, p, n, visible, ctx);
    if (frac < 0.0) {
        /* No sample is in front of the receiver (the tangent plane leaves a
         * sliver between them): one ray to the middle of the part it sees
         * decides, rather than guessing "visible" (light through walls) or
         * "hidden" (a dark seam next to the shooter). */
        frac = visible(ctx, p, inside) ? 1.0 : 0.0;
    }
    return exact * frac;
}

tb_status tb_ff_raycast_exact_batch(void *ctx, const tb_ff_polygon *shooter, const tb_vec3 *pts, int npts,
                                    const tb_vec3 *p, const tb_vec3 *n, size_t count, double *ff)
{
    if (count == 0)
        return TB_OK;
    if (!shooter || !p || !n || !ff || (npts > 0 && !pts))
        return tb_error(TB_ERR_ARG, "tb_ff_raycast_exact_batch: NULL argument");
    if (npts < 0)
        return tb_error(TB_ERR_ARG, "tb_ff_raycast_exact_batch: npts %d", npts);
    if (count > (size_t)PTRDIFF_MAX)
        return tb_error(TB_ERR_ARG, "tb_ff_raycast_exact_batch: %zu receivers are too many", count);
    tb_ff_visible_fn vis = ctx ? tb_ff_occluders_visible : NULL;
    ptrdiff_t cnt = (ptrdiff_t)count;
    /* per-receiver values: independent of the schedule and thread count */
#pragma omp parallel for schedule(dynamic, 64)
    for (ptrdiff_t i = 0; i < cnt; i++)
        ff[i] = tb_ff_raycast_exact(shooter, pts, npts, p[i], n[i], vis, ctx);
    return TB_OK;
}

/* ------------------------------------------------------------ occluders */

struct tb_ff_occluders {
    tb_object *mesh;       /* the polygons as one polygons object (triangles only), NULL when there are none */
    tb_accel *acc;         /* BVH, one reference per triangle of mesh */
    float (*tri_box)[6];   /* per triangle of mesh: bounds (lo xyz, hi xyz) */
    double (*tri_plane)[4]; /* per triangle: unit normal and offset (n . x = d; all 0 if degenerate) */
    double (*tri_edge)[3][4]; /* per triangle: planes through its edges along the normal, unit normals inward
                                 (e . x >= d inside; all 0 if degenerate) */
    float scale;           /* largest coordinate magnitude of the triangles */
};

/* Triangle `prim->sub` of the mesh: the object level's watertight test. */
static bool tb__occ_intersect(void *ctx, const tb_accel_prim *prim, uint32_t index, const tb_ray *ray, tb_hit *hit)
{
    (void)index;
    const tb_object *o = ctx;
    double t;
    if (!tb_object_triangle_crossing(o, prim->sub, ray, &t))
        return false;
    float tf = (float)t;
    if (!(tf >= ray->tmin && tf <= ray->tmax))
        return false;
    hit->t = tf;
    hit->object = prim->object;
    hit->face = prim->sub;
    hit->u = hit->v = 0.0f;
    hit->ng = tb_object_triangle_normal(o, prim->sub);
    return true;
}

static bool tb__occ_occluded(void *ctx, const tb_accel_prim *prim, uint32_t index, const tb_ray *ray)
{
    (void)index;
    const tb_object *o = ctx;
    double t;
    if (!tb_object_triangle_crossing(o, prim->sub, ray, &t))
        return false;
    float tf = (float)t;
    return tf >= ray->tmin && tf <= ray->tmax;
}

tb_status tb_ff_occluders_build(const tb_ff_polygon *polys, size_t n, tb_ff_occluders **out)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "tb_ff_occluders_build: NULL output");
    *out = NULL;
    if (n > 0 && !polys)
        return tb_error(TB_ERR_ARG, "tb_ff_occluders_build: NULL polygons");
    if (n > (size_t)(INT_MAX / 8))
        return tb_error(TB_ERR_ARG, "tb_ff_occluders_build: %zu polygons are too many", n);
    tb_ff_occluders *occ = calloc(1, sizeof *occ);
    if (!occ)
        return tb_error(TB_ERR_NOMEM, "tb_ff_occluders_build: out of memory");
    size_t nv = 0, nf = 0;
    for (size_t i = 0; i < n; i++) {
        if (polys[i].n < 3 || polys[i].n > TB_FF_MAX_VERTS) {
            free(occ);
            return tb_error(TB_ERR_ARG, "tb_ff_occluders_build: polygon %zu has %d corners (3 or 4)", i,
                            polys[i].n);
        }
        nv += (size_t)polys[i].n;
        nf += (size_t)polys[i].n - 2;
    }
    if (n == 0) {
        *out = occ; /* nothing occludes */
        return TB_OK;
    }

    /* One polygons object whose faces are the triangles (quads split along
     * v0-v2, the diagonal tb_ff_sample_polygon also uses), so the object level
     * does no triangulation and the triangles' own test is reused. */
    tb_vec3 *verts = malloc(sizeof *verts * nv);
    int *start = malloc(sizeof *start * (nf + 1));
    int *idx = malloc(sizeof *idx * 3 * nf);
    tb_status st = TB_OK;
    if (!verts || !start || !idx) {
        st = tb_error(TB_ERR_NOMEM, "tb_ff_occluders_build: out of memory for %zu polygons", n);
        goto done;
    }
    size_t vi = 0, fi = 0;
    for (size_t i = 0; i < n; i++) {
        int base = (int)vi;
        for (int k = 0; k < polys[i].n; k++)
            verts[vi++] = polys[i].v[k];
        for (int k = 1; k + 1 < polys[i].n; k++) {
            start[fi] = (int)(3 * fi);
            idx[3 * fi + 0] = base;
            idx[3 * fi + 1] = base + k;
            idx[3 * fi + 2] = base + k + 1;
            fi++;
        }
    }
    start[nf] = (int)(3 * nf);
    tb_mid_object m = {0};
    m.kind = TB_PRIM_POLYGONS;
    m.to_world = tb_transform_identity();
    m.geom.polygons.nvertices = (int)nv;
    m.geom.polygons.vertices = verts;
    m.geom.polygons.nfaces = (int)nf;
    m.geom.polygons.face_start = start;
    m.geom.polygons.indices = idx;
    if ((st = tb_object_from_mid(&m, 0, NULL, NULL, &occ->mesh))) {
        tb_error_context(st, "tb_ff_occluders_build");
        goto done;
    }

    /* Face f of the object is triangle f; the mesh stores its triangles in
     * its own BVH order, each remembering its face. */
    const tb_object_mesh *mesh = occ->mesh->mesh;
    uint32_t *face_poly = malloc(sizeof *face_poly * nf);
    tb_accel_prim *prims = malloc(sizeof *prims * (mesh->ntris ? mesh->ntris : 1));
    if (!face_poly || !prims) {
        free(face_poly);
        free(prims);
        st = tb_error(TB_ERR_NOMEM, "tb_ff_occluders_build: out of memory for %zu polygons", n);
        goto done;
    }
    fi = 0;
    for (size_t i = 0; i < n; i++)
        for (int k = 1; k + 1 < polys[i].n; k++)
            face_poly[fi++] = (uint32_t)i;
    for (uint32_t t = 0; t < mesh->ntris && !st; t++) {
        const uint32_t *tv = &mesh->tris[3 * (size_t)t];
        tb_vec3 tri[3] = {mesh->vertices[tv[0]], mesh->vertices[tv[1]], mesh->vertices[tv[2]]};
        st = tb_bounds_points(tri, 3, NULL, &prims[t].bounds);
        prims[t].object = face_poly[mesh->tri_face[t]];
        prims[t].sub = t;
    }
    free(face_poly);
    /* Bounds and planes for tb_ff_occluders_shaft and _visible_among. */
    occ->tri_box = malloc(sizeof *occ->tri_box * (mesh->ntris ? mesh->ntris : 1));
    occ->tri_plane = malloc(sizeof *occ->tri_plane * (mesh->ntris ? mesh->ntris : 1));
    occ->tri_edge = malloc(sizeof *occ->tri_edge * (mesh->ntris ? mesh->ntris : 1));
    if (!st && (!occ->tri_box || !occ->tri_plane || !occ->tri_edge))
        st = tb_error(TB_ERR_NOMEM, "tb_ff_occluders_build: out of memory for %zu polygons", n);
    for (uint32_t t = 0; t < mesh->ntris && !st; t++) {
        const uint32_t *tv = &mesh->tris[3 * (size_t)t];
        tb_vec3 v0 = mesh->vertices[tv[0]], v1 = mesh->vertices[tv[1]], v2 = mesh->vertices[tv[2]];
        tb_vec3 lo = tb_vec3_min(v0, tb_vec3_min(v1, v2)), hi = tb_vec3_max(v0, tb_vec3_max(v1, v2));
        float *b = occ->tri_box[t];
        b[0] = lo.x, b[1] = lo.y, b[2] = lo.z, b[3] = hi.x, b[4] = hi.y, b[5] = hi.z;
        for (int x = 0; x < 6; x++)
            occ->scale = fmaxf(occ->scale, fabsf(b[x]));
        tb_dvec3 e1 = tb_dvec3_sub(tb__ff_d(v1), tb__ff_d(v0)), e2 = tb_dvec3_sub(tb__ff_d(v2), tb__ff_d(v0));
        tb_dvec3 nn = tb_dvec3_cross(e1, e2);
        double len = tb_dvec3_length(nn);
        double *pl = occ->tri_plane[t];
        if (len > 0.0 && isfinite(len)) {
            nn = tb_dvec3_scale(nn, 1.0 / len);
            pl[0] = nn.x, pl[1] = nn.y, pl[2] = nn.z;
            pl[3] = tb_dvec3_dot(nn, tb__ff_d(v0));
            tb_dvec3 c[3] = {tb__ff_d(v0), tb__ff_d(v1), tb__ff_d(v2)};
            for (int k = 0; k < 3; k++) {
                tb_dvec3 e = tb_dvec3_cross(nn, tb_dvec3_sub(c[(k + 1) % 3], c[k])); /* inward (counter-clockwise) */
                double el = tb_dvec3_length(e);
                double *ep = occ->tri_edge[t][k];
                if (el > 0.0 && isfinite(el)) {
                    e = tb_dvec3_scale(e, 1.0 / el);
                    ep[0] = e.x, ep[1] = e.y, ep[2] = e.z, ep[3] = tb_dvec3_dot(e, c[k]);
                } else {
                    ep[0] = ep[1] = ep[2] = ep[3] = 0.0;
                }
            }
        } else {
            pl[0] = pl[1] = pl[2] = pl[3] = 0.0; /* never rejects */
            for (int k = 0; k < 3; k++)
                for (int x = 0; x < 4; x++)
                    occ->tri_edge[t][k][x] = 0.0;
        }
    }
    if (!st) {
        tb_accel_callbacks cb = {tb__occ_intersect, tb__occ_occluded, occ->mesh, NULL};
        st = tb_accel_build(TB_ACCEL_BVH, prims, mesh->ntris, &cb, NULL, &occ->acc);
        if (st)
            tb_error_context(st, "tb_ff_occluders_build");
    }
    free(prims);
done:
    free(verts);
    free(start);
    free(idx);
    if (st) {
        tb_ff_occluders_free(occ);
        return st;
    }
    *out = occ;
    return TB_OK;
}

bool tb_ff_occluders_visible(void *ctx, tb_vec3 a, tb_vec3 b)
{
    const tb_ff_occluders *occ = ctx;
    if (!occ || !occ->acc)
        return true;
    tb_ray ray = tb_ray_make(a, tb_vec3_sub(b, a), TB_FF_SEGMENT_EPS, 1.0f - TB_FF_SEGMENT_EPS);
    return !tb_accel_occluded(occ->acc, &ray);
}

/* The rejection tests below allow this much (times the largest coordinate
 * magnitude) for rounding. The only inexact step between them and the
 * triangle test is the ray's direction, b - a rounded to float (at most
 * 2^-24 of 2 magnitudes per component); everything else is exact or double. */
#define TB__SHAFT_MARGIN 2e-6

/* fmax and fmin for numbers (no NaN here), inlined rather than libm calls. */
static inline double tb__fmax(double a, double b) { return a > b ? a : b; }
static inline double tb__fmin(double a, double b) { return a < b ? a : b; }

/* One side plane of a shaft, parallel to axis 3 - i - j: n0 x_i + n1 x_j <= c inside. */
typedef struct tb__shaft_plane {
    double n0, n1, c; /* c includes the rounding allowance */
    int i, j;         /* the box bounds (0..5) nearest the inside along the normal */
} tb__shaft_plane;

typedef struct tb__shaft_geom {
    double u[6]; /* union of the two boxes */
    double ulo[3], uhi[3]; /* the union widened by m (u[x] - m, u[x + 3] + m) */
    tb__shaft_plane pl[12];
    int np;
    double m;
} tb__shaft_geom;

/* Which box reaches furthest on side `hi` of `axis`: 0 a, 1 b, -1 a tie. */
static int tb__shaft_extremal(const float *a, const float *b, int axis, int hi)
{
    float x = a[axis + 3 * hi], y = b[axis + 3 * hi];
    if (x == y)
        return -1;
    return (hi ? x > y : x < y) ? 0 : 1;
}

/* False only if box bx (lo xyz, hi xyz) is outside the shaft by more than the margin. */
static inline bool tb__shaft_meets(const tb__shaft_geom *g, const float *bx)
{
    for (int x = 0; x < 3; x++)
        if (bx[x] > g->uhi[x] || bx[x + 3] < g->ulo[x])
            return false;
    for (int k = 0; k < g->np; k++) {
        const tb__shaft_plane *p = &g->pl[k];
        if (p->n0 * bx[p->i] + p->n1 * bx[p->j] > p->c)
            return false;
    }
    return true;
}

/* False only if no segment from a point of box ra to a point of box rb
 * (each a point for one segment) can cross triangle t at a ray parameter in
 * [TB_FF_SEGMENT_EPS, 1 - TB_FF_SEGMENT_EPS], m allowed for rounding: both
 * ends on one side of its plane; or the crossing parameter, from the ends'
 * distances to the plane, outside that range; or the part of the segments
 * where they can cross missing the triangle's bounds. */
static bool tb__tri_may_block(const tb_ff_occluders *occ, uint32_t t, const float *ra, const float *rb,
                              const tb_vec3 *apts, size_t na, const tb_vec3 *bpts, size_t nb, double m)
{
    const double *pl = occ->tri_plane[t];
    double a0 = -pl[3], a1 = -pl[3], b0 = -pl[3], b1 = -pl[3]; /* plane distance ranges over the boxes */
    if (!apts || !bpts) /* (the points, where given, replace them) */
        for (int x = 0; x < 3; x++) {
            int l = pl[x] >= 0.0 ? x : x + 3, h = pl[x] >= 0.0 ? x + 3 : x;
            a0 += pl[x] * ra[l], a1 += pl[x] * ra[h];
            b0 += pl[x] * rb[l], b1 += pl[x] * rb[h];
        }
    if (apts) { /* the points themselves: far tighter than their box when it is tilted */
        a0 = INFINITY, a1 = -INFINITY;
        for (size_t k = 0; k < na; k++) {
            double f = pl[0] * apts[k].x + pl[1] * apts[k].y + pl[2] * apts[k].z - pl[3];
            a0 = tb__fmin(a0, f), a1 = tb__fmax(a1, f);
        }
    }
    if (bpts) {
        b0 = INFINITY, b1 = -INFINITY;
        for (size_t k = 0; k < nb; k++) {
            double f = pl[0] * bpts[k].x + pl[1] * bpts[k].y + pl[2] * bpts[k].z - pl[3];
            b0 = tb__fmin(b0, f), b1 = tb__fmax(b1, f);
        }
    }
    if ((a0 > m && b0 > m) || (a1 < -m && b1 < -m))
        return false;
    /* crossing at |Fa| / (|Fa| + |Fb|): bounds from the extreme distances */
    double amax = tb__fmax(fabs(a0), fabs(a1)) + m, bmax = tb__fmax(fabs(b0), fabs(b1)) + m;
    double amin = a0 > 0.0 || a1 < 0.0 ? tb__fmin(fabs(a0), fabs(a1)) - m : 0.0;
    double bmin = b0 > 0.0 || b1 < 0.0 ? tb__fmin(fabs(b0), fabs(b1)) - m : 0.0;
    amin = tb__fmax(amin, 0.0), bmin = tb__fmax(bmin, 0.0);
    double thi = amax + bmin > 0.0 ? amax / (amax + bmin) : 1.0;
    double tlo = amin / (amin + bmax);
    /* the triangle test rounds its parameter to float: a little slack */
    tlo = tb__fmax(tlo, (double)TB_FF_SEGMENT_EPS - 1e-6);
    thi = tb__fmin(thi, 1.0 - (double)TB_FF_SEGMENT_EPS + 1e-6);
    if (tlo > thi)
        return false;
    const float *bx = occ->tri_box[t];
    double lo[3], hi[3]; /* bounds of the points where the segments can meet the plane */
    for (int x = 0; x < 3; x++) {
        double p = (1.0 - tlo) * ra[x] + tlo * rb[x], q = (1.0 - thi) * ra[x] + thi * rb[x];
        double P = (1.0 - tlo) * ra[x + 3] + tlo * rb[x + 3], Q = (1.0 - thi) * ra[x + 3] + thi * rb[x + 3];
        lo[x] = tb__fmin(p, q), hi[x] = tb__fmax(P, Q);
        if (bx[x] > hi[x] + m || bx[x + 3] < lo[x] - m)
            return false;
    }
    for (int k = 0; k < 3; k++) { /* all of them outside one edge? */
        const double *e = occ->tri_edge[t][k];
        double v = -e[3];
        for (int x = 0; x < 3; x++)
            v += e[x] * (e[x] > 0.0 ? hi[x] : lo[x]);
        if (v < -m)
            return false;
    }
    return true;
}

/* tb__tri_may_block for one segment a -> b (both boxes points). */
static inline bool tb__seg_may_block(const tb_ff_occluders *occ, uint32_t t, tb_vec3 a, tb_vec3 b, double m)
{
    const double *pl = occ->tri_plane[t];
    double fa = pl[0] * a.x + pl[1] * a.y + pl[2] * a.z - pl[3];
    double fb = pl[0] * b.x + pl[1] * b.y + pl[2] * b.z - pl[3];
    if ((fa > m && fb > m) || (fa < -m && fb < -m))
        return false;
    double aa = fabs(fa), ab = fabs(fb);
    double amax = aa + m, amin = aa > m ? aa - m : 0.0, bmax = ab + m, bmin = ab > m ? ab - m : 0.0;
    double thi = amax / (amax + bmin), tlo = amin / (amin + bmax);
    tlo = tb__fmax(tlo, (double)TB_FF_SEGMENT_EPS - 1e-6);
    thi = tb__fmin(thi, 1.0 - (double)TB_FF_SEGMENT_EPS + 1e-6);
    if (tlo > thi)
        return false;
    /* where the segment can meet the plane: outside one edge at both ends? */
    double d[3] = {(double)b.x - a.x, (double)b.y - a.y, (double)b.z - a.z};
    double p[3] = {a.x + tlo * d[0], a.y + tlo * d[1], a.z + tlo * d[2]};
    double q[3] = {a.x + thi * d[0], a.y + thi * d[1], a.z + thi * d[2]};
    for (int k = 0; k < 3; k++) {
        const double *e = occ->tri_edge[t][k];
        if (e[0] * p[0] + e[1] * p[1] + e[2] * p[2] - e[3] < -m && e[0] * q[0] + e[1] * q[1] + e[2] * q[2] - e[3] < -m)
            return false;
    }
    return true;
}

bool tb_ff_occluders_shaft(const tb_ff_occluders *occ, const float a[6], const tb_vec3 *apts, size_t na,
                           const float b[6], const tb_vec3 *bpts, size_t nb, tb_ff_shaft *sh)
{
    sh->occ = occ;
    sh->n = 0;
    sh->margin = 0.0;
    const tb_object_mesh *mesh = occ && occ->mesh ? occ->mesh->mesh : NULL;
    if (!mesh || mesh->nnodes == 0)
        return true; /* nothing occludes */
    float mag = occ->scale;
    for (int x = 0; x < 6; x++)
        mag = fmaxf(mag, fmaxf(fabsf(a[x]), fabsf(b[x])));
    if (!isfinite(mag))
        return false;
    tb__shaft_geom g;
    g.m = TB__SHAFT_MARGIN * mag;
    sh->margin = g.m;
    for (int x = 0; x < 3; x++) {
        g.u[x] = tb__fmin(a[x], b[x]), g.u[x + 3] = tb__fmax(a[x + 3], b[x + 3]);
        g.ulo[x] = g.u[x] - g.m, g.uhi[x] = g.u[x + 3] + g.m;
    }
    /* Haines and Wallace: where one box reaches furthest on side si of axis
     * i and the other on side sj of axis j, the hull of the two has a face
     * through their (si, sj) edges, parallel to the third axis. */
    g.np = 0;
    static const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
    for (int q = 0; q < 3; q++) {
        int i = pairs[q][0], j = pairs[q][1];
        for (int si = 0; si < 2; si++)
            for (int sj = 0; sj < 2; sj++) {
                int ei = tb__shaft_extremal(a, b, i, si), ej = tb__shaft_extremal(a, b, j, sj);
                if (ei < 0 || ej < 0 || ei == ej)
                    continue;
                double pa0 = a[i + 3 * si], pa1 = a[j + 3 * sj], pb0 = b[i + 3 * si], pb1 = b[j + 3 * sj];
                double n0 = pb1 - pa1, n1 = -(pb0 - pa0);
                if (n0 * (si ? 1.0 : -1.0) + n1 * (sj ? 1.0 : -1.0) < 0.0)
                    n0 = -n0, n1 = -n1; /* outward: toward the (si, sj) corner */
                tb__shaft_plane *p = &g.pl[g.np++];
                p->n0 = n0, p->n1 = n1;
                p->i = n0 > 0.0 ? i : i + 3, p->j = n1 > 0.0 ? j : j + 3;
                p->c = n0 * pa0 + n1 * pa1 + g.m * (fabs(n0) + fabs(n1));
            }
    }
    uint32_t stack[64];
    int sp = 0;
    stack[sp++] = 0;
    while (sp > 0) {
        uint32_t k = stack[--sp];
        const tb_object_bvh_node *nd = &mesh->nodes[k];
        if (!tb__shaft_meets(&g, nd->b))
            continue;
        if (nd->count > 0) {
            for (uint32_t t = nd->index; t < nd->index + nd->count; t++) {
                if (!tb__shaft_meets(&g, occ->tri_box[t]) || !tb__tri_may_block(occ, t, a, b, apts, na, bpts, nb, g.m))
                    continue;
                if (sh->n == TB_FF_SHAFT_MAX) {
                    TB_STAT_INC(tb__ff_shafts_full);
                    return false;
                }
                sh->tris[sh->n++] = t;
            }
        } else {
            if (sp + 2 > (int)(sizeof stack / sizeof stack[0]))
                return false;
            stack[sp++] = nd->index;
            stack[sp++] = k + 1;
        }
    }
    TB_STAT_INC(tb__ff_shafts);
    tb_stat_add(&tb__ff_shaft_tris, (int64_t)sh->n);
    if (sh->n == 0)
        TB_STAT_INC(tb__ff_shafts_empty);
    return true;
}

bool tb_ff_shaft_visible(void *ctx, tb_vec3 a, tb_vec3 b)
{
    tb_ff_shaft *sh = ctx;
    if (sh->n == 0)
        return true;
    const tb_ff_occluders *occ = sh->occ;
    tb_ray ray = tb_ray_make(a, tb_vec3_sub(b, a), TB_FF_SEGMENT_EPS, 1.0f - TB_FF_SEGMENT_EPS);
    if (!tb_ray_is_valid(&ray))
        return true; /* as tb_accel_occluded */
    float m = (float)sh->margin;
    float lo[3] = {(a.x < b.x ? a.x : b.x) - m, (a.y < b.y ? a.y : b.y) - m, (a.z < b.z ? a.z : b.z) - m};
    float hi[3] = {(a.x > b.x ? a.x : b.x) + m, (a.y > b.y ? a.y : b.y) + m, (a.z > b.z ? a.z : b.z) + m};
    for (size_t k = 0; k < sh->n; k++) {
        uint32_t t = sh->tris[k];
        const float *bx = occ->tri_box[t];
        if (bx[0] > hi[0] || bx[1] > hi[1] || bx[2] > hi[2] || bx[3] < lo[0] || bx[4] < lo[1] || bx[5] < lo[2])
            continue;
        if (!tb__seg_may_block(occ, t, a, b, sh->margin))
            continue;
        double tt;
        if (!tb_object_triangle_crossing(occ->mesh, t, &ray, &tt))
            continue;
        float tf = (float)tt;
        if (tf >= ray.tmin && tf <= ray.tmax) {
            /* a shadow cache (Haines and Greenberg 1986): the next segment,
             * a neighbour's, tries this blocker first */
            sh->tris[k] = sh->tris[0];
            sh->tris[0] = t;
            return false;
        }
    }
    return true;
}

void tb_ff_occluders_free(tb_ff_occluders *occ)
{
    if (!occ)
        return;
    tb_accel_free(occ->acc);
    tb_object_free(occ->mesh);
    free(occ->tri_box);
    free(occ->tri_plane);
    free(occ->tri_edge);
    free(occ);
}

/* ------------------------------------------------------------ batch */

tb_status tb_ff_raycast_batch(void *ctx, const tb_vec3 *pts, int npts, tb_vec3 ns, double area, const tb_vec3 *p,
                              const tb_vec3 *n, size_t count, double *ff)
{
    if (count == 0)
        return TB_OK;
    if (!p || !n || !ff || (npts > 0 && !pts))
        return tb_error(TB_ERR_ARG, "tb_ff_raycast_batch: NULL argument");
    if (npts < 0 || !(area >= 0.0) || !isfinite(area))
        return tb_error(TB_ERR_ARG, "tb_ff_raycast_batch: npts %d, area %g", npts, area);
    if (count > (size_t)PTRDIFF_MAX)
        return tb_error(TB_ERR_ARG, "tb_ff_raycast_batch: %zu receivers are too many", count);
    tb_ff_visible_fn vis = ctx ? tb_ff_occluders_visible : NULL;
    ptrdiff_t cnt = (ptrdiff_t)count;
    /* Each receiver's value depends only on its own inputs, so the schedule
     * cannot change the results. */
#pragma omp parallel for schedule(dynamic, 64)
    for (ptrdiff_t i = 0; i < cnt; i++)
        ff[i] = tb_ff_raycast(pts, npts, ns, area, p[i], n[i], vis, ctx);
    return TB_OK;
}
