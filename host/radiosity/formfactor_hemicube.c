/* The hemicube (Cohen and Greenberg 1985) drawn into item buffers
 * (util/itembuf): docs/formfactors.md, "Hemicube". */
#include "host/radiosity/formfactor_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "util/itembuf/itembuf.h"

#define TB__PI 3.14159265358979323846

/* Largest resolution accepted: the top face alone then holds 16 M pixels. */
#define TB__HC_MAX_RES 4096

struct tb_hemicube {
    int res;               /* top face res x res, sides res x res/2 */
    tb_itembuf *top, *side; /* the side buffer is reused for the four sides */
    float *wtop, *wside;   /* delta form factor of each pixel */
    tb_dvec3 *local;       /* scratch: polygon corners in the hemicube frame, TB_FF_MAX_VERTS per polygon */
    size_t cap;            /* polygons `local` has room for */
};

tb_hemicube *tb_hemicube_create(int res)
{
    if (res < 2 || res > TB__HC_MAX_RES || res % 2 != 0) {
        tb_error(TB_ERR_ARG, "tb_hemicube_create: resolution %d (need an even number in 2..%d)", res,
                 TB__HC_MAX_RES);
        return NULL;
    }
    tb_hemicube *hc = calloc(1, sizeof *hc);
    if (!hc) {
        tb_error(TB_ERR_NOMEM, "tb_hemicube_create: out of memory");
        return NULL;
    }
    int half = res / 2;
    hc->res = res;
    hc->top = tb_itembuf_create(res, res);
    hc->side = tb_itembuf_create(res, half);
    hc->wtop = malloc(sizeof(float) * (size_t)res * (size_t)res);
    hc->wside = malloc(sizeof(float) * (size_t)res * (size_t)half);
    if (!hc->top || !hc->side || !hc->wtop || !hc->wside) {
        tb_hemicube_free(hc);
        tb_error(TB_ERR_NOMEM, "tb_hemicube_create: out of memory for resolution %d", res);
        return NULL;
    }
    /* Delta form factors at the pixel centres. Top face z = 1, x and y in
     * [-1, 1]: dA / (pi (x^2 + y^2 + 1)^2). Side face (e.g. x = 1) with
     * screen coordinates (y, z), z in [0, 1] from the bottom row up:
     * z dA / (pi (y^2 + z^2 + 1)^2). */
    double pix = 2.0 / res, da = pix * pix;
    for (int j = 0; j < res; j++) {
        double y = 1.0 - (j + 0.5) * pix;
        for (int i = 0; i < res; i++) {
            double x = -1.0 + (i + 0.5) * pix;
            double s = x * x + y * y + 1.0;
            hc->wtop[(size_t)j * res + i] = (float)(da / (TB__PI * s * s));
        }
    }
    for (int j = 0; j < half; j++) {
        double z = 1.0 - (j + 0.5) * pix;
        for (int i = 0; i < res; i++) {
            double y = -1.0 + (i + 0.5) * pix;
            double s = y * y + z * z + 1.0;
            hc->wside[(size_t)j * res + i] = (float)(z * da / (TB__PI * s * s));
        }
    }
    return hc;
}

void tb_hemicube_free(tb_hemicube *hc)
{
    if (!hc)
        return;
    tb_itembuf_free(hc->top);
    tb_itembuf_free(hc->side);
    free(hc->wtop);
    free(hc->wside);
    free(hc->local);
    free(hc);
}

/* Most corners after clipping a polygon by the five planes of a face's
 * frustum. A clip outputs the inside corners plus two points per run of
 * outside corners, so m corners become at most m + floor(m / 2): a convex
 * polygon gains one per plane, but a twisted (non-planar) quad, which a
 * plane can cross four times, goes 4 -> 6 -> 9 -> 13 -> 19 -> 28. */
#define TB__HC_MAX_CLIP 28
_Static_assert(TB_FF_MAX_VERTS <= 4, "TB__HC_MAX_CLIP is the bound for quads");

/* Point where edge a-b crosses a plane (signed distances da > 0 > db or the
 * reverse), computed from the lexicographically smaller end so that an edge
 * shared by two polygons, walked in opposite directions, gives the same point
 * and the buffer's exactly-once coverage survives the clipping. */
static tb_dvec3 tb__hc_cross(tb_dvec3 a, double da, tb_dvec3 b, double db)
{
    bool swap = b.x < a.x || (b.x == a.x && (b.y < a.y || (b.y == a.y && b.z < a.z)));
    if (swap) {
        tb_dvec3 t = a;
        a = b;
        b = t;
        double s = da;
        da = db;
        db = s;
    }
    double t = da / (da - db);
    return tb_dvec3_add(a, tb_dvec3_scale(tb_dvec3_sub(b, a), t));
}

/* Clips polygon in[0..n) (face coordinates: x right, y up, z forward) to the
 * half-space px x + py y + pz z + pw >= 0; returns the new count. */
static int tb__hc_clip(const tb_dvec3 *in, int n, double px, double py, double pz, double pw, tb_dvec3 *out)
{
    int m = 0;
    double d0 = px * in[n - 1].x + py * in[n - 1].y + pz * in[n - 1].z + pw;
    tb_dvec3 a = in[n - 1];
    for (int k = 0; k < n; k++) {
        tb_dvec3 b = in[k];
        double d1 = px * b.x + py * b.y + pz * b.z + pw;
        if ((d0 > 0.0 && d1 < 0.0) || (d0 < 0.0 && d1 > 0.0))
            out[m++] = tb__hc_cross(a, d0, b, d1);
        if (d1 >= 0.0)
            out[m++] = b;
        a = b;
        d0 = d1;
    }
    return m;
}

/* The five faces: forward axis, right axis and up axis as indices into the
 * hemicube frame (0 u, 1 v, 2 w = normal) with signs. */
typedef struct tb__hc_face {
    int fwd, right, up;
    double sf, sr, su;
} tb__hc_face;

static const tb__hc_face tb__hc_faces[5] = {
    {2, 0, 1, 1.0, 1.0, 1.0},  /* top: looks along the normal */
    {0, 1, 2, 1.0, 1.0, 1.0},  /* +u */
    {1, 0, 2, 1.0, -1.0, 1.0}, /* +v */
    {0, 1, 2, -1.0, -1.0, 1.0}, /* -u */
    {1, 0, 2, -1.0, 1.0, 1.0}, /* -v */
};

/* Draws polygon `id` (corners c[0..n) in the hemicube frame) into face f's
 * buffer: clipped to the near plane and the face's frustum, projected
 * (screen depth -1/z: linear in screen space, smaller is nearer). */
static tb_status tb__hc_draw(tb_hemicube *hc, int f, const tb_dvec3 *c, int n, double near, uint32_t id)
{
    const tb__hc_face *fc = &tb__hc_faces[f];
    tb_dvec3 a[TB__HC_MAX_CLIP], b[TB__HC_MAX_CLIP];
    for (int k = 0; k < n; k++) {
        double q[3] = {c[k].x, c[k].y, c[k].z};
        a[k] = (tb_dvec3){fc->sr * q[fc->right], fc->su * q[fc->up], fc->sf * q[fc->fwd]};
    }
    /* Quick rejection: every corner outside one plane. */
    bool out_near = true, out_r = true, out_l = true, out_t = true, out_b = true;
    for (int k = 0; k < n; k++) {
        out_near = out_near && a[k].z < near;
        out_r = out_r && a[k].x > a[k].z;
        out_l = out_l && -a[k].x > a[k].z;
        out_t = out_t && a[k].y > a[k].z;
        out_b = out_b && (f == 0 ? -a[k].y > a[k].z : a[k].y < 0.0);
    }
    if (out_near || out_r || out_l || out_t || out_b)
        return TB_OK;
    int m = n;
    m = tb__hc_clip(a, m, 0.0, 0.0, 1.0, -near, b); /* z >= near */
    if (m < 3)
        return TB_OK;
    m = tb__hc_clip(b, m, -1.0, 0.0, 1.0, 0.0, a); /* x <= z */
    if (m < 3)
        return TB_OK;
    m = tb__hc_clip(a, m, 1.0, 0.0, 1.0, 0.0, b); /* -x <= z */
    if (m < 3)
        return TB_OK;
    m = tb__hc_clip(b, m, 0.0, -1.0, 1.0, 0.0, a); /* y <= z */
    if (m < 3)
        return TB_OK;
    if (f == 0)
        m = tb__hc_clip(a, m, 0.0, 1.0, 1.0, 0.0, b); /* -y <= z */
    else
        m = tb__hc_clip(a, m, 0.0, 1.0, 0.0, 0.0, b); /* y >= 0: above the tangent plane */
    if (m < 3)
        return TB_OK;
    float xy[TB__HC_MAX_CLIP][2], depth[TB__HC_MAX_CLIP];
    double half = 0.5 * hc->res;
    for (int k = 0; k < m; k++) {
        double iz = 1.0 / b[k].z;
        xy[k][0] = (float)((b[k].x * iz + 1.0) * half);
        xy[k][1] = (float)((1.0 - b[k].y * iz) * half);
        depth[k] = (float)(-iz);
    }
    return tb_itembuf_draw_polygon(f == 0 ? hc->top : hc->side, (const float(*)[2])xy, depth, m, id);
}

tb_status tb_hemicube_formfactors(tb_hemicube *hc, tb_vec3 center, tb_vec3 normal, const tb_ff_polygon *polys,
                                  size_t n, uint32_t skip, double *ff)
{
    if (!hc || (n > 0 && (!polys || !ff)))
        return tb_error(TB_ERR_ARG, "tb_hemicube_formfactors: NULL argument");
    if (n >= TB_ITEMBUF_EMPTY)
        return tb_error(TB_ERR_ARG, "tb_hemicube_formfactors: %zu polygons are too many", n);
    tb_dvec3 o = tb__ff_d(center), w = tb__ff_d(normal);
    double wl = tb_dvec3_length(w);
    if (!tb_dvec3_isfinite(o) || !(wl > 0.0) || !isfinite(wl))
        return tb_error(TB_ERR_ARG, "tb_hemicube_formfactors: centre or normal not finite, or zero normal");
    if (n == 0)
        return TB_OK;
    w = tb_dvec3_scale(w, 1.0 / wl);
    /* Tangent axes: u from the axis least aligned with w. */
    tb_dvec3 ax = fabs(w.x) <= fabs(w.y) && fabs(w.x) <= fabs(w.z) ? (tb_dvec3){1, 0, 0}
                  : fabs(w.y) <= fabs(w.z)                         ? (tb_dvec3){0, 1, 0}
                                                                   : (tb_dvec3){0, 0, 1};
    tb_dvec3 u = tb_dvec3_normalize(tb_dvec3_cross(ax, w));
    tb_dvec3 v = tb_dvec3_cross(w, u);

    if (n > hc->cap) {
        tb_dvec3 *l = realloc(hc->local, sizeof *l * TB_FF_MAX_VERTS * n);
        if (!l)
            return tb_error(TB_ERR_NOMEM, "tb_hemicube_formfactors: out of memory for %zu polygons", n);
        hc->local = l;
        hc->cap = n;
    }
    /* Corners in the hemicube frame; the near plane is relative to the
     * farthest corner (scale-free), the same for every polygon so that shared
     * edges are clipped identically. */
    double rmax = 0.0;
    for (size_t i = 0; i < n; i++) {
        ff[i] = 0.0;
        const tb_ff_polygon *pg = &polys[i];
        if (i == skip)
            continue;
        if (pg->n < 3 || pg->n > TB_FF_MAX_VERTS)
            return tb_error(TB_ERR_ARG, "tb_hemicube_formfactors: polygon %zu has %d corners (3 or 4)", i, pg->n);
        for (int k = 0; k < pg->n; k++) {
            tb_dvec3 r = tb_dvec3_sub(tb__ff_d(pg->v[k]), o);
            if (!tb_dvec3_isfinite(r))
                return tb_error(TB_ERR_ARG, "tb_hemicube_formfactors: polygon %zu has a non-finite corner", i);
            hc->local[TB_FF_MAX_VERTS * i + (size_t)k] =
                (tb_dvec3){tb_dvec3_dot(r, u), tb_dvec3_dot(r, v), tb_dvec3_dot(r, w)};
            rmax = fmax(rmax, tb_dvec3_length(r));
        }
    }
    double near = 1e-9 * rmax;
    if (!(near > 0.0))
        return TB_OK; /* every polygon skipped or collapsed onto the centre */

    for (int f = 0; f < 5; f++) {
        tb_itembuf *buf = f == 0 ? hc->top : hc->side;
        tb_itembuf_clear(buf);
        for (size_t i = 0; i < n; i++) {
            if (i == skip)
                continue;
            const tb_dvec3 *c = &hc->local[TB_FF_MAX_VERTS * i];
            bool above = false;
            for (int k = 0; k < polys[i].n; k++)
                above = above || c[k].z > 0.0;
            if (!above)
                continue;
            tb_status st = tb__hc_draw(hc, f, c, polys[i].n, near, (uint32_t)i);
            if (st)
                return tb_error_context(st, "tb_hemicube_formfactors: polygon %zu", i);
        }
        tb_status st = tb_itembuf_accumulate(buf, f == 0 ? hc->wtop : hc->wside, ff, (uint32_t)n);
        if (st)
            return st;
    }
    /* Polygons seen from behind (or edge-on) hide what lies behind them but
     * send nothing toward the centre. */
    for (size_t i = 0; i < n; i++) {
        if (i == skip || ff[i] == 0.0)
            continue;
        tb_dvec3 nn = tb__ff_newell(&polys[i]);
        double h = 0.0;
        for (int k = 0; k < polys[i].n; k++)
            h -= tb_dvec3_dot(tb_dvec3_sub(tb__ff_d(polys[i].v[k]), o), nn);
        if (!(h > 0.0))
            ff[i] = 0.0;
    }
    return TB_OK;
}
