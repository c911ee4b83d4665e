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
    tb_object *mesh; /* the polygons as one polygons object (triangles only), NULL when there are none */
    tb_accel *acc;   /* BVH, one reference per triangle of mesh */
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
    if (!st) {
        tb_accel_callbacks cb = {tb__occ_intersect, tb__occ_occluded, occ->mesh};
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

void tb_ff_occluders_free(tb_ff_occluders *occ)
{
    if (!occ)
        return;
    tb_accel_free(occ->acc);
    tb_object_free(occ->mesh);
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
