/* Point, spot and directional lights as radiosity sources (lights.h,
 * docs/radiosity.md "Lights"). */
#include "host/radiosity/lights.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "util/stats/stats.h"

/* How far (a fraction of the way to its elements' centroid) a receiver is
 * moved into its surface: the solver's TB__RAD_RECEIVER_INSET, so that a
 * light reaches the same points as the form factors do. */
#define TB__RADL_INSET 1e-3

/* Cells per element edge: about this many per unit of (element size over
 * distance to the light), at most TB__RADL_MAX_CELLS. */
#define TB__RADL_CELLS_PER_RATIO 4.0
#define TB__RADL_MAX_CELLS 32

#define TB__RADL_PI 3.14159265358979323846

TB_STAT_COUNTER(tb__radl_shots, "Radiosity/light shots");
TB_STAT_COUNTER(tb__radl_rays, "Radiosity/light shadow rays");
TB_STAT_TIMER(tb__radl_time, "Radiosity/light shot time");

struct tb_rad_lights {
    const tb_rad_mesh *m;   /* not owned: the caller's mesh (the solver's copy) */
    int n, nc;
    tb_light *l;            /* n lights */
    double *power;          /* n * nc */
    tb_vec3 *rp;            /* nverts: receiver points (inset as the solver's) */
    double dir_len;         /* directional lights: shadow segment length (beyond the mesh's box) */
    tb_ff_occluders *occ;
};

int tb_rad_lights_count(const tb_rad_lights *L) { return L ? L->n : 0; }

void tb_rad_lights_free(tb_rad_lights *L)
{
    if (!L)
        return;
    free(L->l);
    free(L->power);
    free(L->rp);
    tb_ff_occluders_free(L->occ);
    free(L);
}

static inline int tb__nk(const tb_rad_element *e) { return e->v[3] == TB_RAD_NONE ? 3 : 4; }

tb_status tb_rad_lights_create(const tb_rad_mesh *m, const tb_light *l, int n, tb_rad_lights **out)
{
    *out = NULL;
    if (!m || m->nverts == 0 || m->nelems == 0 || n < 0 || (n > 0 && !l))
        return tb_error(TB_ERR_ARG, "radiosity lights: empty mesh or bad light list");
    int nc = m->nchannels;
    for (int k = 0; k < n; k++) {
        const tb_light *q = &l[k];
        if (q->kind != TB_LIGHT_POINT && q->kind != TB_LIGHT_SPOT && q->kind != TB_LIGHT_DIRECTIONAL)
            return tb_error(TB_ERR_ARG, "radiosity lights: light %d: unknown kind %d", k, (int)q->kind);
        if (q->intensity.n != nc)
            return tb_error(TB_ERR_ARG, "radiosity lights: light %d has %d channels, the mesh %d", k,
                            q->intensity.n, nc);
        for (int c = 0; c < nc; c++)
            if (!(q->intensity.v[c] >= 0.0f) || !isfinite(q->intensity.v[c]))
                return tb_error(TB_ERR_ARG, "radiosity lights: light %d: bad intensity %g", k,
                                (double)q->intensity.v[c]);
        tb_vec3 p = q->kind == TB_LIGHT_DIRECTIONAL ? q->axis : q->position;
        if (!isfinite(p.x) || !isfinite(p.y) || !isfinite(p.z) ||
            (q->kind != TB_LIGHT_POINT && !(tb_vec3_length2(q->axis) > 0.0f)))
            return tb_error(TB_ERR_ARG, "radiosity lights: light %d: bad position or direction", k);
    }
    tb_rad_lights *L = calloc(1, sizeof *L);
    if (!L)
        return tb_error(TB_ERR_NOMEM, "radiosity lights: out of memory");
    size_t nv = m->nverts, ne = m->nelems;
    L->m = m, L->n = n, L->nc = nc;
    L->l = malloc(sizeof *L->l * (size_t)(n ? n : 1));
    L->power = malloc(sizeof *L->power * (size_t)(n ? n : 1) * (size_t)nc);
    L->rp = malloc(sizeof *L->rp * nv);
    double *acc = calloc(nv * 4, sizeof *acc);
    /* the mesh's vertices plus what the light segments end at */
    tb_rad_mesh ext = *m;
    ext.nverts = nv + 8 * (size_t)n;
    ext.verts = calloc(ext.nverts, sizeof *ext.verts);
    tb_ff_polygon *polys = malloc(sizeof *polys * ne);
    tb_status st = TB_OK;
    if (!L->l || !L->power || !L->rp || !acc || !ext.verts || !polys) {
        st = tb_error(TB_ERR_NOMEM, "radiosity lights: out of memory");
        goto done;
    }
    if (n)
        memcpy(L->l, l, sizeof *l * (size_t)n);

    /* receivers: as the solver places them (tb_rad_solver_create) */
    for (size_t i = 0; i < ne; i++) {
        const tb_rad_element *e = &m->elems[i];
        for (int k = 0; k < tb__nk(e); k++) {
            double *a = acc + (size_t)e->v[k] * 4;
            a[0] += e->area * e->centroid.x, a[1] += e->area * e->centroid.y, a[2] += e->area * e->centroid.z;
            a[3] += e->area;
        }
    }
    tb_vec3 lo = m->verts[0].p, hi = lo;
    for (size_t v = 0; v < nv; v++) {
        tb_vec3 p = m->verts[v].p;
        lo = tb_vec3_min(lo, p), hi = tb_vec3_max(hi, p);
        const double *a = acc + v * 4;
        if (a[3] > 0.0) {
            double t = TB__RADL_INSET;
            p = tb_vec3_make((float)(p.x + t * (a[0] / a[3] - p.x)), (float)(p.y + t * (a[1] / a[3] - p.y)),
                             (float)(p.z + t * (a[2] / a[3] - p.z)));
        }
        L->rp[v] = p;
    }
    double diag = tb_vec3_length(tb_vec3_sub(hi, lo));
    /* a directional light's segment leaves the mesh's box from any receiver */
    L->dir_len = 1.01 * diag + 1e-6;

    for (int k = 0; k < n; k++) {
        tb_channels P = tb_light_power(&L->l[k], 0.5 * diag);
        for (int c = 0; c < nc; c++)
            L->power[(size_t)k * (size_t)nc + (size_t)c] = (double)P.v[c];
    }

    /* Occluders: an element whose plane has every mesh point and every
     * segment end in front cannot block a segment (tb_rad_mesh_occluders).
     * A point light's segments end at its position; a directional light's
     * at receivers moved dir_len toward the light, inside the mesh's box so
     * moved, whose 8 corners are added. */
    memcpy(ext.verts, m->verts, sizeof *ext.verts * nv);
    size_t q = nv;
    for (int k = 0; k < n; k++) {
        const tb_light *lk = &L->l[k];
        if (lk->kind != TB_LIGHT_DIRECTIONAL) {
            ext.verts[q++].p = lk->position;
            continue;
        }
        tb_vec3 back = tb_vec3_scale(tb_vec3_normalize(lk->axis), -(float)L->dir_len);
        for (int b = 0; b < 8; b++) {
            tb_vec3 c = tb_vec3_make(b & 1 ? hi.x : lo.x, b & 2 ? hi.y : lo.y, b & 4 ? hi.z : lo.z);
            ext.verts[q++].p = tb_vec3_add(c, back);
        }
    }
    ext.nverts = q;
    size_t nocc = n ? tb_rad_mesh_occluders(&ext, polys) : 0;
    st = tb_ff_occluders_build(polys, nocc, &L->occ);
done:
    free(acc);
    free(ext.verts);
    free(polys);
    if (st) {
        tb_rad_lights_free(L);
        return st;
    }
    *out = L;
    return TB_OK;
}

void tb_rad_lights_power(const tb_rad_lights *L, int k, double *out)
{
    for (int c = 0; c < L->nc; c++)
        out[c] = L->power[(size_t)k * (size_t)L->nc + (size_t)c];
}

/* Is the light visible from receiver point p? */
static bool tb__lit(const tb_rad_lights *L, const tb_light *l, tb_vec3 p)
{
    tb_vec3 end = l->kind == TB_LIGHT_DIRECTIONAL
                      ? tb_vec3_sub(p, tb_vec3_scale(tb_vec3_normalize(l->axis), (float)L->dir_len))
                      : l->position;
    return tb_ff_occluders_visible(L->occ, p, end);
}

/* Irradiance at p (normal n) from light l, visibility not included:
 * out[0..nc). False if it is zero (p facing away, outside a cone, at the light). */
static bool tb__point_irradiance(const tb_light *l, int nc, tb_vec3 p, tb_vec3 n, double *out)
{
    for (int c = 0; c < nc; c++)
        out[c] = 0.0;
    if (l->kind == TB_LIGHT_DIRECTIONAL) {
        double cosr = -tb_dvec3_dot(tb_vec3_to_d(n), tb_dvec3_normalize(tb_vec3_to_d(l->axis)));
        if (!(cosr > 0.0))
            return false;
        for (int c = 0; c < nc; c++)
            out[c] = (double)l->intensity.v[c] * cosr;
        return true;
    }
    tb_dvec3 d = tb_dvec3_sub(tb_vec3_to_d(l->position), tb_vec3_to_d(p));
    double d2 = tb_dvec3_length2(d);
    if (!(d2 > 0.0))
        return false;
    double dist = sqrt(d2), cosr = tb_dvec3_dot(tb_vec3_to_d(n), d) / dist;
    if (!(cosr > 0.0))
        return false;
    tb_channels I = tb_light_intensity(l, tb_vec3_neg(tb_vec3_make((float)d.x, (float)d.y, (float)d.z)));
    bool any = false;
    for (int c = 0; c < nc; c++) {
        out[c] = (double)I.v[c] * cosr / d2;
        any |= out[c] > 0.0;
    }
    return any;
}

/* Solid angle of the triangle (a, b, c) (vectors from the eye), Van
 * Oosterom and Strackee (1983): tan(Omega / 2) = |a . (b x c)| / (abc +
 * (a.b) c + (a.c) b + (b.c) a). */
static double tb__solid_angle(tb_dvec3 a, tb_dvec3 b, tb_dvec3 c)
{
    double la = tb_dvec3_length(a), lb = tb_dvec3_length(b), lc = tb_dvec3_length(c);
    double num = fabs(tb_dvec3_dot(a, tb_dvec3_cross(b, c)));
    double den = la * lb * lc + tb_dvec3_dot(a, b) * lc + tb_dvec3_dot(a, c) * lb + tb_dvec3_dot(b, c) * la;
    return 2.0 * atan2(num, den);
}

/* Mean irradiance of element j from light l (file comment), out[0..nc);
 * vis: the corners' visibility (0 or 1) per vertex. */
static void tb__element_irradiance(const tb_rad_lights *L, const tb_light *l, size_t j, const unsigned char *vis,
                                   double *out)
{
    const tb_rad_element *e = &L->m->elems[j];
    int nc = L->nc, nk = tb__nk(e);
    for (int c = 0; c < nc; c++)
        out[c] = 0.0;
    tb_dvec3 nrm = tb_vec3_to_d(e->normal), cen = tb_vec3_to_d(e->centroid), P[4];
    double w[4];
    bool any = false;
    for (int k = 0; k < nk; k++) {
        P[k] = tb_vec3_to_d(L->m->verts[e->v[k]].p);
        w[k] = vis[e->v[k]] ? 1.0 : 0.0;
        any |= vis[e->v[k]] != 0;
    }
    if (!any)
        return;
    static const int tri[2][3] = {{0, 1, 2}, {0, 2, 3}};
    if (l->kind == TB_LIGHT_DIRECTIONAL) {
        double cosr = -tb_dvec3_dot(nrm, tb_dvec3_normalize(tb_vec3_to_d(l->axis)));
        if (!(cosr > 0.0))
            return;
        /* the area mean of the linearly interpolated visibility */
        double f = 0.0, a = 0.0;
        for (int t = 0; t < nk - 2; t++) {
            tb_dvec3 p0 = P[tri[t][0]], p1 = P[tri[t][1]], p2 = P[tri[t][2]];
            double at = 0.5 * tb_dvec3_length(tb_dvec3_cross(tb_dvec3_sub(p1, p0), tb_dvec3_sub(p2, p0)));
            f += at * (w[tri[t][0]] + w[tri[t][1]] + w[tri[t][2]]) / 3.0;
            a += at;
        }
        f = a > 0.0 ? f / a : 0.0;
        for (int c = 0; c < nc; c++)
            out[c] = (double)l->intensity.v[c] * cosr * f;
        return;
    }
    tb_dvec3 lp = tb_vec3_to_d(l->position);
    double h = tb_dvec3_dot(nrm, tb_dvec3_sub(lp, cen));
    if (!(h > 0.0))
        return; /* the light is behind the element (or in its plane) */
    double rad = 0.0;
    for (int k = 0; k < nk; k++)
        rad = fmax(rad, tb_dvec3_length(tb_dvec3_sub(P[k], cen)));
    double dist = tb_dvec3_length(tb_dvec3_sub(lp, cen)), dmin = fmax(dist - rad, h);
    double ang = 2.0 * rad / dmin; /* about the angle the element subtends (radians) */
    double cells = ceil(TB__RADL_CELLS_PER_RATIO * ang);
    /* where the intensity varies across the element, cells no wider than
     * an eighth of a spot's falloff band (the smoothstep) or 2 degrees of
     * an IES table */
    double step = INFINITY;
    if (l->ies)
        step = 2.0 * TB__RADL_PI / 180.0;
    if (l->kind == TB_LIGHT_SPOT) {
        double t_in = acos(fmin(1.0, l->cos_falloff)), t_out = acos(fmin(1.0, l->cos_total));
        /* the element's angular range about the beam axis */
        tb_dvec3 axis = tb_dvec3_normalize(tb_vec3_to_d(l->axis));
        double t_c = acos(fmax(-1.0, fmin(1.0, tb_dvec3_dot(tb_dvec3_sub(cen, lp), axis) / dist)));
        double t_r = rad < dist ? asin(rad / dist) : TB__RADL_PI;
        if (t_c + t_r >= t_in && t_c - t_r <= t_out)
            step = fmin(step, t_out > t_in ? (t_out - t_in) / 8.0 : 0.0);
    }
    if (step < INFINITY)
        cells = fmax(cells, step > 0.0 ? ceil(ang / step) : TB__RADL_MAX_CELLS);
    int n = cells < 1.0 ? 1 : cells > TB__RADL_MAX_CELLS ? TB__RADL_MAX_CELLS : (int)cells;
    double sum[TB_CHANNELS_MAX] = {0};
    for (int t = 0; t < nk - 2; t++) {
        int i0 = tri[t][0], i1 = tri[t][1], i2 = tri[t][2];
        if (w[i0] == 0.0 && w[i1] == 0.0 && w[i2] == 0.0)
            continue;
        /* corners relative to the light */
        tb_dvec3 a0 = tb_dvec3_sub(P[i0], lp), e1 = tb_dvec3_sub(P[i1], P[i0]), e2 = tb_dvec3_sub(P[i2], P[i0]);
        for (int i = 0; i < n; i++)
            for (int k = 0; k < n - i; k++)
                for (int down = 0; down < 2; down++) {
                    if (down && i + k >= n - 1)
                        continue;
                    /* the cell's corners in (u, v) units of 1/n along e1, e2 */
                    int cu[3], cv[3];
                    if (!down)
                        cu[0] = i, cv[0] = k, cu[1] = i + 1, cv[1] = k, cu[2] = i, cv[2] = k + 1;
                    else
                        cu[0] = i + 1, cv[0] = k, cu[1] = i + 1, cv[1] = k + 1, cu[2] = i, cv[2] = k + 1;
                    tb_dvec3 q[3];
                    for (int r = 0; r < 3; r++)
                        q[r] = tb_dvec3_add(a0, tb_dvec3_add(tb_dvec3_scale(e1, cu[r] / (double)n),
                                                             tb_dvec3_scale(e2, cv[r] / (double)n)));
                    double u = (cu[0] + cu[1] + cu[2]) / (3.0 * n), v = (cv[0] + cv[1] + cv[2]) / (3.0 * n);
                    double wv = w[i0] * (1.0 - u - v) + w[i1] * u + w[i2] * v;
                    if (!(wv > 0.0))
                        continue;
                    tb_dvec3 mid = tb_dvec3_scale(tb_dvec3_add(tb_dvec3_add(q[0], q[1]), q[2]), 1.0 / 3.0);
                    tb_channels I = tb_light_intensity(l, tb_vec3_make((float)mid.x, (float)mid.y, (float)mid.z));
                    double om = tb__solid_angle(q[0], q[1], q[2]) * wv;
                    for (int c = 0; c < nc; c++)
                        sum[c] += (double)I.v[c] * om;
                }
    }
    for (int c = 0; c < nc; c++)
        out[c] = sum[c] / e->area;
}

tb_status tb_rad_lights_shoot(const tb_rad_lights *L, int k, double *ev, double *ee)
{
    if (!L || k < 0 || k >= L->n)
        return tb_error(TB_ERR_ARG, "radiosity lights: no light %d", k);
    const tb_rad_mesh *m = L->m;
    const tb_light *l = &L->l[k];
    size_t nv = m->nverts, ne = m->nelems;
    int nc = L->nc;
    unsigned char *need = calloc(nv, 1), *vis = calloc(nv, 1);
    if (!need || !vis) {
        free(need), free(vis);
        return tb_error(TB_ERR_NOMEM, "radiosity lights: out of memory");
    }
    tb_timer_token tt = tb_timer_start(&tb__radl_time);
    /* visibility is needed at the corners of every element facing the light
     * (for its interpolated visibility) and at vertices facing it */
    for (size_t j = 0; j < ne; j++) {
        const tb_rad_element *e = &m->elems[j];
        double f = l->kind == TB_LIGHT_DIRECTIONAL
                       ? -tb_vec3_dot(e->normal, l->axis)
                       : tb_vec3_dot(e->normal, tb_vec3_sub(l->position, e->centroid));
        if (f > 0.0)
            for (int q = 0; q < tb__nk(e); q++)
                need[e->v[q]] = 1;
    }
    ptrdiff_t cnt = (ptrdiff_t)nv;
    int64_t rays = 0;
    /* each vertex's value depends only on its own inputs: any schedule gives the same results */
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : rays)
    for (ptrdiff_t v = 0; v < cnt; v++) {
        double *o = ev + (size_t)v * (size_t)nc;
        bool pos = tb__point_irradiance(l, nc, L->rp[v], m->verts[v].n, o);
        if (pos || need[v]) {
            vis[v] = tb__lit(L, l, L->rp[v]);
            rays++;
        }
        if (!vis[v])
            for (int c = 0; c < nc; c++)
                o[c] = 0.0;
    }
    cnt = (ptrdiff_t)ne;
#pragma omp parallel for schedule(dynamic, 16)
    for (ptrdiff_t j = 0; j < cnt; j++)
        tb__element_irradiance(L, l, (size_t)j, vis, ee + (size_t)j * (size_t)nc);
    free(need), free(vis);
    (void)tb_timer_stop(tt);
    tb_stat_add(&tb__radl_shots, 1);
    tb_stat_add(&tb__radl_rays, rays);
    return TB_OK;
}
