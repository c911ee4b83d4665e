/* Hit -> radiosity element (locate.h): one uniform grid per object over the
 * elements' boxes padded by their tolerance, so every element within
 * tolerance of a point is listed in the point's cell. */
#include "host/radiosity/locate.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The most cells of an object's grid per element: enough for a few elements
 * per cell on walls and spheres alike, bounded memory. */
#define TB__LOC_CELLS_PER_ELEM 4
/* The tolerance of an element as a fraction of its longest edge: well above
 * the chord height of a polygonized curve (about 1/30 of the edge at the
 * polygonizer's default 15 degrees), well below the element. */
#define TB__LOC_TOL_FRACTION 0.25

/* One object's grid. */
typedef struct tb__loc_grid {
    double lo[3];       /* grid origin */
    double h;           /* cell size (cubic cells) */
    int res[3];         /* cells per axis (0: the object has no elements) */
    uint32_t *start;    /* res0*res1*res2 + 1 offsets into list */
    uint32_t *list;     /* element indices per cell, ascending */
} tb__loc_grid;

struct tb_rad_locator {
    const tb_rad_mesh *m; /* not owned */
    uint32_t nobjects;    /* one past the largest object index */
    tb__loc_grid *grids;  /* nobjects */
    double *tol;          /* nelems: distance tolerance of each element */
};

void tb_rad_locator_free(tb_rad_locator *l)
{
    if (!l)
        return;
    for (uint32_t o = 0; o < l->nobjects && l->grids; o++) {
        free(l->grids[o].start);
        free(l->grids[o].list);
    }
    free(l->grids);
    free(l->tol);
    free(l);
}

static int tb__elem_n(const tb_rad_element *e)
{
    return e->v[3] == TB_RAD_NONE ? 3 : 4;
}

/* The padded box of element i, lo[3] and hi[3]. */
static void tb__elem_box(const tb_rad_locator *l, uint32_t i, double lo[3], double hi[3])
{
    const tb_rad_element *e = &l->m->elems[i];
    for (int a = 0; a < 3; a++)
        lo[a] = INFINITY, hi[a] = -INFINITY;
    for (int k = 0; k < tb__elem_n(e); k++) {
        const tb_vec3 p = l->m->verts[e->v[k]].p;
        const double c[3] = {p.x, p.y, p.z};
        for (int a = 0; a < 3; a++)
            lo[a] = fmin(lo[a], c[a]), hi[a] = fmax(hi[a], c[a]);
    }
    for (int a = 0; a < 3; a++)
        lo[a] -= l->tol[i], hi[a] += l->tol[i];
}

/* Cell index range [c0, c1] along each axis of a box. */
static void tb__cell_range(const tb__loc_grid *g, const double lo[3], const double hi[3], int c0[3], int c1[3])
{
    for (int a = 0; a < 3; a++) {
        double f0 = floor((lo[a] - g->lo[a]) / g->h), f1 = floor((hi[a] - g->lo[a]) / g->h);
        c0[a] = (int)fmax(0.0, fmin(f0, g->res[a] - 1.0));
        c1[a] = (int)fmax(0.0, fmin(f1, g->res[a] - 1.0));
    }
}

/* Builds object o's grid over its elements elem[0..n) (ascending). */
static tb_status tb__grid_build(tb_rad_locator *l, tb__loc_grid *g, const uint32_t *elem, uint32_t n)
{
    if (n == 0)
        return TB_OK;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, edge = 0.0;
    for (uint32_t j = 0; j < n; j++) {
        double bl[3], bh[3];
        tb__elem_box(l, elem[j], bl, bh);
        for (int a = 0; a < 3; a++)
            lo[a] = fmin(lo[a], bl[a]), hi[a] = fmax(hi[a], bh[a]);
        edge += l->tol[elem[j]] / TB__LOC_TOL_FRACTION;
    }
    /* Cells about the mean element size, coarsened until the grid is small. */
    double h = fmax(edge / n, 1e-12 * fmax(1.0, fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]))));
    double cap = (double)TB__LOC_CELLS_PER_ELEM * n + 64.0;
    for (;;) {
        double cells = 1.0;
        for (int a = 0; a < 3; a++)
            cells *= fmax(1.0, ceil((hi[a] - lo[a]) / h));
        if (cells <= cap)
            break;
        h *= 1.25;
    }
    for (int a = 0; a < 3; a++) {
        g->lo[a] = lo[a];
        g->res[a] = (int)fmax(1.0, ceil((hi[a] - lo[a]) / h));
    }
    g->h = h;
    size_t ncell = (size_t)g->res[0] * (size_t)g->res[1] * (size_t)g->res[2];
    g->start = calloc(ncell + 1, sizeof *g->start);
    if (!g->start)
        return tb_error(TB_ERR_NOMEM, "radiosity locator: out of memory");
    /* Two passes: count per cell (into start[c + 1]), then fill in
     * ascending element order with start[c + 1] as cell c's cursor; the
     * prefix sum makes start[c + 1] the beginning of cell c for the fill, and
     * the fill leaves it at cell c's end, the beginning of cell c + 1. */
    for (int pass = 0; pass < 2; pass++) {
        if (pass == 1) {
            uint32_t acc = 0;
            for (size_t c = 0; c < ncell; c++) {
                uint32_t k = g->start[c + 1];
                g->start[c + 1] = acc;
                acc += k;
            }
            g->list = malloc((acc ? acc : 1) * sizeof *g->list);
            if (!g->list)
                return tb_error(TB_ERR_NOMEM, "radiosity locator: out of memory");
        }
        for (uint32_t j = 0; j < n; j++) {
            double bl[3], bh[3];
            int c0[3], c1[3];
            tb__elem_box(l, elem[j], bl, bh);
            tb__cell_range(g, bl, bh, c0, c1);
            for (int z = c0[2]; z <= c1[2]; z++)
                for (int y = c0[1]; y <= c1[1]; y++)
                    for (int x = c0[0]; x <= c1[0]; x++) {
                        size_t c = ((size_t)z * (size_t)g->res[1] + (size_t)y) * (size_t)g->res[0] + (size_t)x;
                        if (pass == 0)
                            g->start[c + 1]++;
                        else
                            g->list[g->start[c + 1]++] = elem[j];
                    }
        }
    }
    return TB_OK;
}

tb_status tb_rad_locator_create(const tb_rad_mesh *m, tb_rad_locator **out)
{
    *out = NULL;
    if (!m || m->nelems == 0 || m->nelems >= UINT32_MAX)
        return tb_error(TB_ERR_ARG, "radiosity locator: empty mesh");
    tb_rad_locator *l = calloc(1, sizeof *l);
    if (!l)
        return tb_error(TB_ERR_NOMEM, "radiosity locator: out of memory");
    l->m = m;
    uint32_t nobj = 0;
    for (size_t i = 0; i < m->nelems; i++) {
        const tb_rad_element *e = &m->elems[i];
        for (int k = 0; k < tb__elem_n(e); k++)
            if (e->v[k] >= m->nverts) {
                tb_rad_locator_free(l);
                return tb_error(TB_ERR_ARG, "radiosity locator: element %zu has a vertex out of range", i);
            }
        if (e->object >= nobj)
            nobj = e->object + 1;
    }
    l->nobjects = nobj;
    l->grids = calloc(nobj, sizeof *l->grids);
    l->tol = malloc(m->nelems * sizeof *l->tol);
    uint32_t *count = calloc((size_t)nobj + 1, sizeof *count), *order = malloc(m->nelems * sizeof *order);
    tb_status st = l->grids && l->tol && count && order ? TB_OK : tb_error(TB_ERR_NOMEM, "radiosity locator: out of memory");
    for (size_t i = 0; i < m->nelems && !st; i++) {
        const tb_rad_element *e = &m->elems[i];
        int n = tb__elem_n(e);
        double longest = 0.0;
        for (int k = 0; k < n; k++)
            longest = fmax(longest, tb_vec3_distance(m->verts[e->v[k]].p, m->verts[e->v[(k + 1) % n]].p));
        l->tol[i] = TB__LOC_TOL_FRACTION * longest;
        count[e->object + 1]++;
    }
    /* The elements grouped by object, ascending within each (counting sort). */
    if (!st) {
        for (uint32_t o = 0; o < nobj; o++)
            count[o + 1] += count[o];
        for (size_t i = 0; i < m->nelems; i++)
            order[count[m->elems[i].object]++] = (uint32_t)i;
        /* count[o] is now the end of object o's run; its start is count[o - 1]. */
        for (uint32_t o = 0; o < nobj && !st; o++) {
            uint32_t b = o ? count[o - 1] : 0;
            st = tb__grid_build(l, &l->grids[o], order + b, count[o] - b);
        }
    }
    free(count);
    free(order);
    if (st) {
        tb_rad_locator_free(l);
        return st;
    }
    *out = l;
    return TB_OK;
}

/* The point of triangle (a, b, c) nearest to p (Ericson, Real-Time Collision
 * Detection, 5.1.5), as barycentric weights w[0..3) of a, b, c; returns the
 * squared distance. */
static double tb__closest_tri(const double p[3], const double a[3], const double b[3], const double c[3],
                              double w[3])
{
    double ab[3], ac[3], ap[3], bp[3], cp[3];
    for (int i = 0; i < 3; i++)
        ab[i] = b[i] - a[i], ac[i] = c[i] - a[i], ap[i] = p[i] - a[i], bp[i] = p[i] - b[i], cp[i] = p[i] - c[i];
#define TB__DOT(u, v) ((u)[0] * (v)[0] + (u)[1] * (v)[1] + (u)[2] * (v)[2])
    double d1 = TB__DOT(ab, ap), d2 = TB__DOT(ac, ap);
    double d3 = TB__DOT(ab, bp), d4 = TB__DOT(ac, bp);
    double d5 = TB__DOT(ab, cp), d6 = TB__DOT(ac, cp);
#undef TB__DOT
    double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
    if (d1 <= 0.0 && d2 <= 0.0)
        w[0] = 1, w[1] = 0, w[2] = 0;
    else if (d3 >= 0.0 && d4 <= d3)
        w[0] = 0, w[1] = 1, w[2] = 0;
    else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        double v = d1 / (d1 - d3);
        w[0] = 1 - v, w[1] = v, w[2] = 0;
    } else if (d6 >= 0.0 && d5 <= d6)
        w[0] = 0, w[1] = 0, w[2] = 1;
    else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        double t = d2 / (d2 - d6);
        w[0] = 1 - t, w[1] = 0, w[2] = t;
    } else if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
        double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        w[0] = 0, w[1] = 1 - t, w[2] = t;
    } else {
        double den = 1.0 / (va + vb + vc);
        double v = vb * den, t = vc * den;
        w[0] = 1 - v - t, w[1] = v, w[2] = t;
    }
    double d2sum = 0.0;
    for (int i = 0; i < 3; i++) {
        double q = w[0] * a[i] + w[1] * b[i] + w[2] * c[i] - p[i];
        d2sum += q * q;
    }
    return d2sum;
}

/* Squared distance from p to element i and the corner weights of its
 * nearest point (the display's triangles (v0 v1 v2) and (v0 v2 v3)). */
static double tb__elem_closest(const tb_rad_mesh *m, uint32_t i, const double p[3], double w[4])
{
    const tb_rad_element *e = &m->elems[i];
    double c[4][3];
    int n = tb__elem_n(e);
    for (int k = 0; k < n; k++) {
        tb_vec3 v = m->verts[e->v[k]].p;
        c[k][0] = v.x, c[k][1] = v.y, c[k][2] = v.z;
    }
    double t[3];
    double d = tb__closest_tri(p, c[0], c[1], c[2], t);
    w[0] = t[0], w[1] = t[1], w[2] = t[2], w[3] = 0.0;
    if (n == 4) {
        double d1 = tb__closest_tri(p, c[0], c[2], c[3], t);
        if (d1 < d) {
            d = d1;
            w[0] = t[0], w[1] = 0.0, w[2] = t[1], w[3] = t[2];
        }
    }
    return d;
}

bool tb_rad_locate(const tb_rad_locator *l, uint32_t object, tb_vec3 p, tb_vec3 n, tb_rad_location *out)
{
    if (!l || object >= l->nobjects)
        return false;
    const tb__loc_grid *g = &l->grids[object];
    if (g->res[0] == 0)
        return false;
    const double pd[3] = {p.x, p.y, p.z};
    int ci[3];
    for (int a = 0; a < 3; a++) {
        double f = floor((pd[a] - g->lo[a]) / g->h);
        if (!(f >= 0.0 && f < g->res[a])) /* outside the grid (or NaN): no element within tolerance */
            return false;
        ci[a] = (int)f;
    }
    size_t c = ((size_t)ci[2] * (size_t)g->res[1] + (size_t)ci[1]) * (size_t)g->res[0] + (size_t)ci[0];
    const tb_rad_mesh *m = l->m;
    const bool side = n.x != 0.0f || n.y != 0.0f || n.z != 0.0f;
    double best = INFINITY, bw[4] = {0};
    uint32_t bi = TB_RAD_NONE;
    /* The list is ascending and only a strictly nearer element replaces the
     * best: ties go to the lower index, whatever the cell. */
    for (uint32_t k = g->start[c]; k < g->start[c + 1]; k++) {
        uint32_t i = g->list[k];
        if (side && tb_vec3_dot(m->elems[i].normal, n) <= 0.0f)
            continue;
        double w[4];
        double d2 = tb__elem_closest(m, i, pd, w);
        if (d2 > l->tol[i] * l->tol[i] || !(d2 < best))
            continue;
        best = d2, bi = i;
        memcpy(bw, w, sizeof bw);
    }
    if (bi == TB_RAD_NONE)
        return false;
    const tb_rad_element *e = &m->elems[bi];
    out->element = bi;
    out->object = e->object;
    out->ncorners = tb__elem_n(e);
    double q[3] = {0, 0, 0};
    for (int k = 0; k < 4; k++) {
        out->v[k] = e->v[k];
        out->w[k] = bw[k];
        if (k < out->ncorners) {
            tb_vec3 v = m->verts[e->v[k]].p;
            q[0] += bw[k] * v.x, q[1] += bw[k] * v.y, q[2] += bw[k] * v.z;
        }
    }
    out->q = (tb_vec3){(float)q[0], (float)q[1], (float)q[2]};
    out->distance = sqrt(best);
    return true;
}

void tb_rad_location_interpolate(const tb_rad_location *loc, const double *values, int nc, double *out)
{
    for (int c = 0; c < nc; c++)
        out[c] = 0.0;
    for (int k = 0; k < loc->ncorners; k++)
        for (int c = 0; c < nc; c++)
            out[c] += loc->w[k] * values[(size_t)loc->v[k] * (size_t)nc + (size_t)c];
}

void tb_rad_location_radiosity(const tb_rad_solver *s, const tb_rad_location *loc, const double *ambient,
                               double *out)
{
    const tb_rad_mesh *m = tb_rad_solver_mesh(s);
    const int nc = m->nchannels;
    double h[TB_CHANNELS_MAX] = {0}, hv[TB_CHANNELS_MAX];
    for (int k = 0; k < loc->ncorners; k++) {
        tb_rad_vertex_irradiance(s, loc->v[k], hv);
        for (int c = 0; c < nc; c++)
            h[c] += loc->w[k] * hv[c];
    }
    const size_t x = (size_t)loc->element * (size_t)nc;
    for (int c = 0; c < nc; c++)
        out[c] = m->emission[x + (size_t)c] + m->rho[x + (size_t)c] * (h[c] + (ambient ? ambient[c] : 0.0));
}
