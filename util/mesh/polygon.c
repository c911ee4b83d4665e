/* Newell normal, planarity and the non-planar quad rule. */
#include "util/mesh/polygon.h"

#include <math.h>
#include <stddef.h>

static inline tb_vec3 tb__pt(const tb_vec3 *pts, const uint32_t *idx, uint32_t i)
{
    return pts[idx ? idx[i] : i];
}

tb_dvec3 tb_polygon_newell(const tb_vec3 *pts, const uint32_t *idx, uint32_t n)
{
    tb_dvec3 nv = {0, 0, 0};
    if (n < 3)
        return nv;
    tb_vec3 o = tb__pt(pts, idx, 0);
    /* Relative to vertex 0: sum over edges (p_i x p_{i+1}) with p_i = P_i - o.
     * Differences of floats in double are exact unless the exponents differ
     * by more than 29, so the only error is in the products and the sum. */
    double px = 0, py = 0, pz = 0; /* previous vertex, relative (vertex 0 is the origin) */
    for (uint32_t i = 1; i <= n; i++) {
        double cx = 0, cy = 0, cz = 0;
        if (i < n) {
            tb_vec3 p = tb__pt(pts, idx, i);
            cx = (double)p.x - o.x;
            cy = (double)p.y - o.y;
            cz = (double)p.z - o.z;
        }
        nv.x += py * cz - pz * cy;
        nv.y += pz * cx - px * cz;
        nv.z += px * cy - py * cx;
        px = cx, py = cy, pz = cz;
    }
    return nv;
}

double tb_polygon_size(const tb_vec3 *pts, const uint32_t *idx, uint32_t n)
{
    if (n == 0)
        return 0.0;
    tb_vec3 p = tb__pt(pts, idx, 0);
    double lo[3] = {p.x, p.y, p.z}, hi[3] = {p.x, p.y, p.z};
    for (uint32_t i = 1; i < n; i++) {
        p = tb__pt(pts, idx, i);
        double c[3] = {p.x, p.y, p.z};
        for (int k = 0; k < 3; k++) {
            lo[k] = c[k] < lo[k] ? c[k] : lo[k];
            hi[k] = c[k] > hi[k] ? c[k] : hi[k];
        }
    }
    double dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
    return sqrt(dx * dx + dy * dy + dz * dz);
}

double tb_polygon_planarity(const tb_vec3 *pts, const uint32_t *idx, uint32_t n)
{
    if (n < 4)
        return 0.0;
    tb_dvec3 nv = tb_polygon_newell(pts, idx, n);
    double len = sqrt(nv.x * nv.x + nv.y * nv.y + nv.z * nv.z);
    if (!(len > 0.0))
        return INFINITY;
    tb_vec3 o = tb__pt(pts, idx, 0);
    double cx = 0, cy = 0, cz = 0;
    for (uint32_t i = 0; i < n; i++) {
        tb_vec3 p = tb__pt(pts, idx, i);
        cx += (double)p.x - o.x;
        cy += (double)p.y - o.y;
        cz += (double)p.z - o.z;
    }
    cx /= n, cy /= n, cz /= n;
    double worst = 0.0;
    for (uint32_t i = 0; i < n; i++) {
        tb_vec3 p = tb__pt(pts, idx, i);
        double d = ((p.x - o.x - cx) * nv.x + (p.y - o.y - cy) * nv.y + (p.z - o.z - cz) * nv.z) / len;
        worst = fabs(d) > worst ? fabs(d) : worst;
    }
    return worst;
}

bool tb_polygon_is_planar(const tb_vec3 *pts, const uint32_t *idx, uint32_t n, double rel_tol)
{
    if (n < 4)
        return true;
    if (!(rel_tol > 0.0))
        rel_tol = TB_MESH_PLANAR_TOL;
    return tb_polygon_planarity(pts, idx, n) <= rel_tol * tb_polygon_size(pts, idx, n);
}

tb_projection tb_projection_for_normal(tb_dvec3 n)
{
    double ax = fabs(n.x), ay = fabs(n.y), az = fabs(n.z);
    int axis = (az >= ax && az >= ay) ? 2 : (ax >= ay ? 0 : 1);
    double s = axis == 0 ? n.x : (axis == 1 ? n.y : n.z);
    /* Dropping axis k keeps (k+1, k+2) as a right-handed pair looking down
     * +k; if the normal points down -k, swapping them restores CCW. */
    int u = (axis + 1) % 3, v = (axis + 2) % 3;
    if (s < 0.0) {
        int t = u;
        u = v;
        v = t;
    }
    return (tb_projection){u, v};
}

/* (b - a) x (c - a) . n in double. */
static double tb__facing(tb_vec3 a, tb_vec3 b, tb_vec3 c, tb_dvec3 n)
{
    double ux = (double)b.x - a.x, uy = (double)b.y - a.y, uz = (double)b.z - a.z;
    double vx = (double)c.x - a.x, vy = (double)c.y - a.y, vz = (double)c.z - a.z;
    return (uy * vz - uz * vy) * n.x + (uz * vx - ux * vz) * n.y + (ux * vy - uy * vx) * n.z;
}

tb_quad_diagonal tb_quad_split_diagonal(tb_vec3 p0, tb_vec3 p1, tb_vec3 p2, tb_vec3 p3)
{
    double ax = (double)p2.x - p0.x, ay = (double)p2.y - p0.y, az = (double)p2.z - p0.z;
    double bx = (double)p3.x - p1.x, by = (double)p3.y - p1.y, bz = (double)p3.z - p1.z;
    double d02 = ax * ax + ay * ay + az * az;
    double d13 = bx * bx + by * by + bz * bz;
    tb_quad_diagonal shorter = d13 < d02 ? TB_QUAD_DIAG_13 : TB_QUAD_DIAG_02;
    const tb_vec3 q[4] = {p0, p1, p2, p3};
    tb_dvec3 n = tb_polygon_newell(q, NULL, 4);
    bool ok02 = tb__facing(p0, p1, p2, n) > 0 && tb__facing(p0, p2, p3, n) > 0;
    bool ok13 = tb__facing(p0, p1, p3, n) > 0 && tb__facing(p1, p2, p3, n) > 0;
    if (ok02 != ok13)
        return ok02 ? TB_QUAD_DIAG_02 : TB_QUAD_DIAG_13;
    return shorter;
}

void tb_quad_split_corners(tb_quad_diagonal d, uint32_t tri[6])
{
    static const uint32_t t02[6] = {0, 1, 2, 0, 2, 3};
    static const uint32_t t13[6] = {0, 1, 3, 1, 2, 3};
    const uint32_t *t = d == TB_QUAD_DIAG_13 ? t13 : t02;
    for (int i = 0; i < 6; i++)
        tri[i] = t[i];
}
