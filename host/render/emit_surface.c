/* Analytic area emitters over a primitive's exact surface (emit_surface.h,
 * docs/lights.md "Analytic surface emitters"). */
#include "host/render/emit_surface.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "host/object/intersect.h"
#include "host/object/param.h"
#include "host/render/sampling.h"
#include "util/math/float.h"

/* 8-point Gauss-Legendre on [0, 1]: nodes and weights (a direction in
 * which J is constant takes the midpoint alone). */
static const double tb__gl_x[8] = {0.019855071751231856, 0.10166676129318658, 0.2372337950418355,
                                   0.40828267875217511,  0.59171732124782495, 0.7627662049581645,
                                   0.89833323870681348,  0.9801449282487682};
static const double tb__gl_w[8] = {0.050614268145188088, 0.11119051722668723, 0.15685332293894369,
                                   0.181341891689181,    0.181341891689181,   0.15685332293894369,
                                   0.11119051722668723,  0.050614268145188088};
static const double tb__mid_x[1] = {0.5}, tb__mid_w[1] = {1.0};

/* Sub-points per cell direction of the coverage estimate of a partial face. */
#define TB__COVER 4
/* A point is on a partial face when its object-space distance to it is at most this. */
#define TB__ON_FACE 1e-9

typedef struct tb__sface {
    int face;       /* face ID of the primitive */
    int nu, nv;     /* table size: columns (u) and rows (v) */
    int rows;       /* index of its first row in row_cdf's rows (rows of face f: rows .. rows + nv - 1) */
} tb__sface;

struct tb_surface_emitter {
    const tb_object *obj;
    int nfaces;          /* present faces with area */
    int nids;            /* face IDs of the kind (size of local) */
    bool partial;        /* the kind has faces only partly covering their (u, v) square */
    int ncells;
    double area;         /* world area */
    tb__sface *faces;    /* nfaces */
    int *local;          /* per face ID: index in faces, or -1 */
    double *face_cdf;    /* nfaces + 1 */
    double *row_cdf;     /* per face: nv + 1 entries, at offset faces[f].rows + f */
    double *col_cdf;     /* per row r (global): nu + 1 entries, at col_off[r] */
    int *col_off;        /* per row (global) */
};

/* First index i with cdf[i] <= u < cdf[i + 1] among n items (cdf has n + 1
 * entries, cdf[n] = 1), its probability and u rescaled within its slice. */
static int tb__pick(const double *cdf, int n, double u, double *p, double *ur)
{
    if (!(u >= 0.0))
        u = 0.0;
    if (u >= 1.0)
        u = 0x1.fffffffffffffp-1;
    int i = tb_cdf_search(cdf, n, u);
    double w = cdf[i + 1] - cdf[i];
    *p = w;
    double r = w > 0.0 ? (u - cdf[i]) / w : 0.0;
    *ur = r < 1.0 ? (r > 0.0 ? r : 0.0) : 0x1.fffffffffffffp-1;
    return i;
}

/* Turns weights w[0..n) into a cdf[0..n] (normalised; uniform if they sum to 0). */
static void tb__cdf(const double *w, int n, double *cdf)
{
    double sum = 0.0;
    for (int i = 0; i < n; i++)
        sum += w[i];
    cdf[0] = 0.0;
    double acc = 0.0;
    for (int i = 0; i < n; i++) {
        acc += w[i];
        cdf[i + 1] = sum > 0.0 ? acc / sum : (double)(i + 1) / n;
    }
    cdf[n] = 1.0;
}

/* Kinds with faces only partly covering their (u, v) square. */
static bool tb__partial_kind(tb_prim_kind k)
{
    return k == TB_PRIM_PRISM || k == TB_PRIM_SQUARE_ARCH || k == TB_PRIM_ROUND_ARCH;
}

/* World point, normal and area element of face f at (u, v); *on false when
 * the object-space point is off a partial face. False if it cannot be evaluated. */
static bool tb__eval(const tb_object *o, int face, double u, double v, tb_dvec3 *p, tb_dvec3 *n, double *J,
                     bool *on)
{
    tb_dvec3 op, on_, du, dv;
    if (tb_param_eval(o->kind, &o->geom, face, u, v, &op, &on_, &du, &dv)) {
        tb_clear_error();
        return false;
    }
    if (on)
        *on = !tb__partial_kind(o->kind) || tb_param_face_distance(o->kind, &o->geom, face, op) <= TB__ON_FACE;
    tb_dvec3 wu = tb_transform_dvector(&o->to_world, du), wv = tb_transform_dvector(&o->to_world, dv);
    *J = tb_dvec3_length(tb_dvec3_cross(wu, wv));
    if (p)
        *p = tb_transform_dpoint(&o->to_world, op);
    if (n) {
        tb_dvec3 w = tb_transform_dnormal(&o->to_world, on_);
        double l = tb_dvec3_length(w);
        *n = l > 0.0 ? tb_dvec3_scale(w, 1.0 / l) : w;
    }
    return isfinite(*J);
}

/* Area element at (u, v), 0 where it cannot be evaluated. */
static double tb__J(const tb_object *o, int face, double u, double v)
{
    double J;
    return tb__eval(o, face, u, v, NULL, NULL, &J, NULL) ? J : 0.0;
}

/* One face's table: sizes (nu, nv) and per-cell weights (row by row) into
 * w (TB_SURF_CELLS^2 room); *area its area estimate. */
static void tb__face_table(const tb_object *o, int face, int *nu, int *nv, double *w, double *area)
{
    enum { G = TB_SURF_CELLS };
    /* J at the cell centres: does it vary along u, along v? */
    static const double rel = 1e-9;
    double Jc[G][G], jmax = 0.0;
    bool off = false;
    for (int j = 0; j < G; j++)
        for (int i = 0; i < G; i++) {
            double J;
            bool on = true;
            if (!tb__eval(o, face, (i + 0.5) / G, (j + 0.5) / G, NULL, NULL, &J, &on))
                J = 0.0;
            Jc[j][i] = J;
            jmax = fmax(jmax, J);
            off = off || !on;
        }
    bool vu = off, vv = off;
    for (int j = 0; j < G && !vu; j++)
        for (int i = 1; i < G; i++)
            if (fabs(Jc[j][i] - Jc[j][0]) > rel * jmax)
                vu = true;
    for (int i = 0; i < G && !vv; i++)
        for (int j = 1; j < G; j++)
            if (fabs(Jc[j][i] - Jc[0][i]) > rel * jmax)
                vv = true;
    *nu = vu ? G : 1;
    *nv = vv ? G : 1;
    *area = 0.0;
    for (int j = 0; j < *nv; j++)
        for (int i = 0; i < *nu; i++) {
            double u0 = (double)i / *nu, v0 = (double)j / *nv, du = 1.0 / *nu, dv = 1.0 / *nv, s = 0.0;
            const int na = vu ? 8 : 1, nb = vv ? 8 : 1;
            const double *xa = vu ? tb__gl_x : tb__mid_x, *wa = vu ? tb__gl_w : tb__mid_w;
            const double *xb = vv ? tb__gl_x : tb__mid_x, *wb = vv ? tb__gl_w : tb__mid_w;
            for (int b = 0; b < nb; b++)
                for (int a = 0; a < na; a++)
                    s += wa[a] * wb[b] * tb__J(o, face, u0 + du * xa[a], v0 + dv * xb[b]);
            s *= du * dv;
            double wt = s;
            if (off) {
                /* the share of the cell on the face; every cell keeps a
                 * positive weight so no sliver of the face goes unsampled */
                int k = 0;
                for (int b = 0; b < TB__COVER; b++)
                    for (int a = 0; a < TB__COVER; a++) {
                        double J;
                        bool on = false;
                        (void)tb__eval(o, face, u0 + du * (a + 0.5) / TB__COVER, v0 + dv * (b + 0.5) / TB__COVER,
                                       NULL, NULL, &J, &on);
                        k += on;
                    }
                const int m = TB__COVER * TB__COVER;
                s *= (double)k / m;
                wt *= (k + 1.0) / (m + 1.0);
            }
            w[j * *nu + i] = wt;
            *area += s;
        }
    if (o->kind == TB_PRIM_PRISM && (face == TB_FACE_PRISM_BOTTOM || face == TB_FACE_PRISM_TOP)) {
        /* a cap exactly: the vector area of its polygon in world space */
        const int n = tb_param_prism_npoints(&o->geom.prism);
        const double z = face == TB_FACE_PRISM_TOP ? 1.0 : -1.0;
        tb_dvec3 sum = {0.0, 0.0, 0.0}, first = {0.0, 0.0, 0.0}, prev = first;
        for (int k = 0; k <= n; k++) {
            double x, y;
            tb_param_prism_point(&o->geom.prism, k, &x, &y);
            tb_dvec3 q = tb_transform_dpoint(&o->to_world, (tb_dvec3){x, y, z});
            if (k == 0)
                first = q;
            else
                sum = tb_dvec3_add(sum, tb_dvec3_cross(tb_dvec3_sub(prev, first), tb_dvec3_sub(q, first)));
            prev = q;
        }
        *area = 0.5 * tb_dvec3_length(sum);
    }
}

tb_status tb_surface_emitter_make(const tb_object *o, tb_surface_emitter **out)
{
    *out = NULL;
    if (!o || tb_prim_is_csg(o->kind) || o->kind == TB_PRIM_POLYGONS)
        return tb_error(TB_ERR_ARG, "surface emitter: needs an analytic primitive");
    const int nids = tb_param_face_count(o->kind, &o->geom);
    if (nids < 1)
        return tb_error(TB_ERR_ARG, "surface emitter: %s has no faces", tb_prim_kind_name(o->kind));
    enum { G = TB_SURF_CELLS };
    tb__sface *fs = malloc(sizeof *fs * (size_t)nids);
    double *w = malloc(sizeof *w * (size_t)nids * G * G);
    if (!fs || !w) {
        free(fs);
        free(w);
        return tb_error(TB_ERR_NOMEM, "surface emitter: out of memory");
    }
    int nf = 0, nrows = 0, ncells = 0;
    double area = 0.0;
    for (int f = 0; f < nids; f++) {
        if (!tb_param_face_present(o->kind, &o->geom, f))
            continue;
        int nu, nv;
        double a;
        tb__face_table(o, f, &nu, &nv, w + (size_t)ncells, &a);
        double sum = 0.0;
        for (int c = 0; c < nu * nv; c++)
            sum += w[ncells + c];
        if (!(sum > 0.0) || !(a > 0.0))
            continue; /* a face of no area (a degenerate cap): nothing to sample */
        fs[nf] = (tb__sface){f, nu, nv, nrows};
        area += a;
        nf++;
        nrows += nv;
        ncells += nu * nv;
    }
    if (nf == 0 || !(area > 0.0) || !isfinite(area)) {
        free(fs);
        free(w);
        return tb_error(TB_ERR_ARG, "surface emitter: %s has no area", tb_prim_kind_name(o->kind));
    }
    /* one block: struct, faces, local, cdfs, column offsets */
    size_t bytes = sizeof(tb_surface_emitter) + sizeof(tb__sface) * (size_t)nf + sizeof(int) * (size_t)nids +
                   sizeof(int) * (size_t)nrows +
                   sizeof(double) * ((size_t)nf + 1 + (size_t)nrows + (size_t)nf + (size_t)ncells + (size_t)nrows);
    char *blk = malloc(bytes);
    if (!blk) {
        free(fs);
        free(w);
        return tb_error(TB_ERR_NOMEM, "surface emitter: out of memory");
    }
    tb_surface_emitter *se = (tb_surface_emitter *)blk;
    char *q = blk + sizeof *se;
    se->face_cdf = (double *)q;
    q += sizeof(double) * ((size_t)nf + 1);
    se->row_cdf = (double *)q;
    q += sizeof(double) * ((size_t)nrows + (size_t)nf);
    se->col_cdf = (double *)q;
    q += sizeof(double) * ((size_t)ncells + (size_t)nrows);
    se->faces = (tb__sface *)q;
    q += sizeof(tb__sface) * (size_t)nf;
    se->local = (int *)q;
    q += sizeof(int) * (size_t)nids;
    se->col_off = (int *)q;
    se->obj = o;
    se->nfaces = nf;
    se->nids = nids;
    se->partial = o->kind == TB_PRIM_SQUARE_ARCH || o->kind == TB_PRIM_ROUND_ARCH; /* prism caps are exact */
    se->ncells = ncells;
    se->area = area;
    memcpy(se->faces, fs, sizeof *fs * (size_t)nf);
    for (int f = 0; f < nids; f++)
        se->local[f] = -1;
    /* faces by weight, rows by their sums, columns within each row */
    double *fw = malloc(sizeof *fw * (size_t)(nf + nrows));
    if (!fw) {
        free(blk);
        free(fs);
        free(w);
        return tb_error(TB_ERR_NOMEM, "surface emitter: out of memory");
    }
    int cell = 0, row = 0, coff = 0;
    for (int f = 0; f < nf; f++) {
        const tb__sface *F = &se->faces[f];
        se->local[F->face] = f;
        double *rw = fw + nf;
        double fsum = 0.0;
        for (int j = 0; j < F->nv; j++) {
            double rs = 0.0;
            for (int i = 0; i < F->nu; i++)
                rs += w[cell + j * F->nu + i];
            rw[j] = rs;
            fsum += rs;
            se->col_off[row + j] = coff;
            tb__cdf(w + cell + j * F->nu, F->nu, se->col_cdf + coff);
            coff += F->nu + 1;
        }
        tb__cdf(rw, F->nv, se->row_cdf + F->rows + f);
        /* faces chosen by their share of the (weighted) table: the same
         * measure as within the face, so the density is continuous across
         * faces where J is */
        fw[f] = fsum;
        cell += F->nu * F->nv;
        row += F->nv;
    }
    tb__cdf(fw, nf, se->face_cdf);
    free(fw);
    free(fs);
    free(w);
    *out = se;
    return TB_OK;
}

void tb_surface_emitter_free(tb_surface_emitter *se) { free(se); }

double tb_surface_emitter_area(const tb_surface_emitter *se) { return se->area; }

bool tb_surface_emitter_partial(const tb_surface_emitter *se) { return se->partial; }

void tb_surface_emitter_set_area(tb_surface_emitter *se, double area) { se->area = area; }

int tb_surface_emitter_cells(const tb_surface_emitter *se) { return se->ncells; }

const tb_object *tb_surface_emitter_object(const tb_surface_emitter *se) { return se->obj; }

size_t tb_surface_emitter_bytes(const tb_surface_emitter *se, size_t per_alloc)
{
    int nrows = 0;
    for (int f = 0; f < se->nfaces; f++)
        nrows += se->faces[f].nv;
    return sizeof *se + sizeof(tb__sface) * (size_t)se->nfaces + sizeof(int) * (size_t)(se->nids + nrows) +
           sizeof(double) * ((size_t)se->nfaces * 2 + 1 + (size_t)nrows * 2 + (size_t)se->ncells) + per_alloc;
}

/* Density on the (u, v) square of face f (local index) at cell (i, j). */
static double tb__pdf_uv_cell(const tb_surface_emitter *se, int f, int i, int j)
{
    const tb__sface *F = &se->faces[f];
    const double *rc = se->row_cdf + F->rows + f, *cc = se->col_cdf + se->col_off[F->rows + j];
    double pf = se->face_cdf[f + 1] - se->face_cdf[f], pr = rc[j + 1] - rc[j], pc = cc[i + 1] - cc[i];
    return pf * pr * pc * F->nu * F->nv;
}

double tb_surface_emitter_pdf_uv(const tb_surface_emitter *se, int face, double u, double v)
{
    if (face < 0 || face >= se->nids || se->local[face] < 0 || !(u >= 0.0 && u <= 1.0 && v >= 0.0 && v <= 1.0))
        return 0.0;
    const int f = se->local[face];
    const tb__sface *F = &se->faces[f];
    int i = (int)(u * F->nu), j = (int)(v * F->nv);
    i = i < F->nu ? i : F->nu - 1;
    j = j < F->nv ? j : F->nv - 1;
    double J = tb__J(se->obj, face, u, v);
    if (!(J > 0.0))
        return 0.0;
    return tb__pdf_uv_cell(se, f, i, j) / J;
}

bool tb_surface_emitter_sample(void *ctx, float u1, float u2, tb_vec3 *q, tb_vec3 *n, double *pdf_area)
{
    const tb_surface_emitter *se = ctx;
    double pf, pr, pc, r1, r2, r3;
    int f = tb__pick(se->face_cdf, se->nfaces, u1, &pf, &r1);
    const tb__sface *F = &se->faces[f];
    int j = tb__pick(se->row_cdf + F->rows + f, F->nv, u2, &pr, &r2);
    int i = tb__pick(se->col_cdf + se->col_off[F->rows + j], F->nu, r1, &pc, &r3);
    double u = fmin((i + r3) / F->nu, 1.0), v = fmin((j + r2) / F->nv, 1.0);
    tb_dvec3 p, nn;
    double J;
    bool on = true;
    if (!tb__eval(se->obj, F->face, u, v, &p, &nn, &J, &on) || !on || !(J > 0.0))
        return false;
    *pdf_area = pf * pr * pc * F->nu * F->nv / J;
    *q = tb_dvec3_to_f(p);
    *n = tb_dvec3_to_f(nn);
    return isfinite(*pdf_area);
}

double tb_surface_emitter_pdf(void *ctx, tb_vec3 q)
{
    const tb_surface_emitter *se = ctx;
    const tb_object *o = se->obj;
    int face;
    double u, v;
    if (tb_param_from_point_world(o->kind, &o->geom, &o->to_world, tb_vec3_to_d(q), -1, &face, &u, &v)) {
        tb_clear_error();
        return 0.0;
    }
    return tb_surface_emitter_pdf_uv(se, face, u, v);
}

bool tb_surface_emitter_intersect(void *ctx, tb_vec3 o, tb_vec3 d, double tmin, double *t, tb_vec3 *q, tb_vec3 *n)
{
    const tb_surface_emitter *se = ctx;
    tb_ray r = tb_ray_make(o, d, (float)tmin, INFINITY);
    if ((double)r.tmin < tmin)
        r.tmin = nextafterf(r.tmin, INFINITY);
    tb_hit h;
    if (!tb_object_intersect(se->obj, &r, &h))
        return false;
    *t = h.t;
    *q = tb_dvec3_to_f(tb_dvec3_add(tb_vec3_to_d(o), tb_dvec3_scale(tb_vec3_to_d(d), h.t)));
    *n = h.ng;
    return true;
}

tb_emitter tb_emitter_surface(tb_surface_emitter *se, tb_channels L)
{
    return (tb_emitter){.kind = TB_EMITTER_CUSTOM,
                        .radiance = L,
                        .object = se->obj->index,
                        .face = se->obj->face_base,
                        .area = se->area,
                        .sample = tb_surface_emitter_sample,
                        .pdf = tb_surface_emitter_pdf,
                        .intersect = tb_surface_emitter_intersect,
                        .ctx = se};
}

bool tb_emitter_is_surface(const tb_emitter *e)
{
    return e->kind == TB_EMITTER_CUSTOM && e->sample == tb_surface_emitter_sample;
}

bool tb_surface_emitter_convex(const tb_surface_emitter *se)
{
    switch (se->obj->kind) {
    case TB_PRIM_SPHERE:
    case TB_PRIM_CUBE:
    case TB_PRIM_CYLINDER:
    case TB_PRIM_CONE:
    case TB_PRIM_PYRAMID:
        return true;
    case TB_PRIM_PRISM:
        return se->obj->geom.prism.sides > 0;
    default:
        return false;
    }
}
