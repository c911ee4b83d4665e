/* Polygon frame, the exact point-to-polygon form factor and stratified
 * sample points on a polygon (docs/formfactors.md). */
#include "host/radiosity/formfactor_internal.h"

#include <math.h>
#include <stddef.h>

#include "util/math/rng.h"

#define TB__PI 3.14159265358979323846

tb_dvec3 tb__ff_newell(const tb_ff_polygon *poly)
{
    tb_dvec3 nn = {0.0, 0.0, 0.0};
    if (!poly || poly->n < 3 || poly->n > TB_FF_MAX_VERTS)
        return nn;
    /* Newell's sum over edges relative to v0: the same vector as the plain
     * sum, with smaller terms when the polygon is far from the origin. */
    tb_dvec3 o = tb__ff_d(poly->v[0]);
    for (int k = 1; k + 1 < poly->n; k++) {
        tb_dvec3 a = tb_dvec3_sub(tb__ff_d(poly->v[k]), o);
        tb_dvec3 b = tb_dvec3_sub(tb__ff_d(poly->v[k + 1]), o);
        nn = tb_dvec3_add(nn, tb_dvec3_cross(a, b));
    }
    return nn;
}

bool tb__ff_polygon_ok(const tb_ff_polygon *poly)
{
    if (!poly || poly->n < 3 || poly->n > TB_FF_MAX_VERTS)
        return false;
    double e2 = 0.0;
    for (int k = 0; k < poly->n; k++) {
        tb_dvec3 a = tb__ff_d(poly->v[k]);
        if (!tb_dvec3_isfinite(a))
            return false;
        tb_dvec3 e = tb_dvec3_sub(tb__ff_d(poly->v[(k + 1) % poly->n]), a);
        e2 = fmax(e2, tb_dvec3_length2(e));
    }
    double area2 = tb_dvec3_length(tb__ff_newell(poly)); /* twice the area */
    return isfinite(area2) && area2 > 2e-12 * e2;
}

void tb_ff_polygon_frame(const tb_ff_polygon *poly, tb_vec3 *normal, double *area)
{
    tb_dvec3 nn = tb__ff_newell(poly);
    double len = tb_dvec3_length(nn);
    bool ok = isfinite(len) && len > 0.0;
    if (normal)
        *normal = ok ? (tb_vec3){(float)(nn.x / len), (float)(nn.y / len), (float)(nn.z / len)}
                     : (tb_vec3){0.0f, 0.0f, 0.0f};
    if (area)
        *area = ok ? 0.5 * len : 0.0;
}

/* ------------------------------------------------------------ point to polygon */

/* Point where edge a-b crosses the plane (signed distances da, db of opposite
 * signs), computed from the lexicographically smaller end so that an edge
 * shared by two polygons (walked in opposite directions) gives the same point. */
static tb_dvec3 tb__cross_point(tb_dvec3 a, double da, tb_dvec3 b, double db)
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

/* Relative tolerance of "on a plane": the corners and p are floats, so a
 * point meant to lie on a plane is off by up to half an ulp of its
 * coordinates (6e-8 of their magnitude), and a float unit normal tilts a
 * plane by ~6e-8 times the distance. Without the snap, noise of that size
 * turns a receiver on a coplanar neighbour's edge into one an infinitesimal
 * distance in front of the polygon with the polygon in its tangent plane,
 * whose form factor is O(1) garbage, and makes a convex polygon cross the
 * tangent plane more than twice. */
#define TB__FF_PLANE_EPS 1e-7

double tb__ff_point_polygon_ex(tb_vec3 p, tb_vec3 n, const tb_ff_polygon *poly, tb_vec3 *seen)
{
    if (seen)
        *seen = p;
    if (!poly || poly->n < 3 || poly->n > TB_FF_MAX_VERTS)
        return 0.0;
    tb_dvec3 pd = tb__ff_d(p), nd = tb__ff_d(n);
    double nl = tb_dvec3_length(nd);
    if (!(nl > 0.0) || !isfinite(nl) || !tb_dvec3_isfinite(pd))
        return 0.0;
    nd = tb_dvec3_scale(nd, 1.0 / nl);
    tb_dvec3 ns = tb__ff_newell(poly);
    double nsl = tb_dvec3_length(ns);
    if (!(nsl > 0.0) || !isfinite(nsl))
        return 0.0;
    ns = tb_dvec3_scale(ns, 1.0 / nsl);

    /* Vertices relative to p; the tolerance scales with the polygon's
     * distance from p and with the coordinates' magnitude. */
    tb_dvec3 r[TB_FF_MAX_VERTS];
    double d[TB_FF_MAX_VERTS], h = 0.0, size = 0.0;
    double mag = fmax(fabs(pd.x), fmax(fabs(pd.y), fabs(pd.z)));
    for (int k = 0; k < poly->n; k++) {
        tb_dvec3 v = tb__ff_d(poly->v[k]);
        mag = fmax(mag, fmax(fabs(v.x), fmax(fabs(v.y), fabs(v.z))));
        r[k] = tb_dvec3_sub(v, pd);
        d[k] = tb_dvec3_dot(r[k], nd);
        h -= tb_dvec3_dot(r[k], ns) / poly->n;
        size = fmax(size, tb_dvec3_length(r[k]));
    }
    double eps = TB__FF_PLANE_EPS * (size + mag);
    /* p must be in front of the polygon's plane by more than the noise: on
     * the plane (a coplanar neighbour, a point on an edge) it sees nothing. */
    if (!(h > eps))
        return 0.0;
    bool any_front = false;
    for (int k = 0; k < poly->n; k++) {
        if (fabs(d[k]) <= eps)
            d[k] = 0.0;
        any_front = any_front || d[k] > 0.0;
    }
    if (!any_front)
        return 0.0;

    /* Clip to p's tangent plane (keep d >= 0): one plane turns 4 corners of
     * a planar convex polygon into at most 5, but a slightly twisted quad (a
     * whole Cornell box face) seen from near its plane can alternate sides,
     * d = (+ - + -): every corner and every edge's crossing, 2n points. */
    tb_dvec3 c[2 * TB_FF_MAX_VERTS];
    int m = 0;
    for (int k = 0; k < poly->n; k++) {
        int k1 = (k + 1) % poly->n;
        if (d[k] >= 0.0)
            c[m++] = r[k];
        if ((d[k] > 0.0 && d[k1] < 0.0) || (d[k] < 0.0 && d[k1] > 0.0))
            c[m++] = tb__cross_point(r[k], d[k], r[k1], d[k1]);
    }
    if (m < 3)
        return 0.0;

    /* Lambert's contour integral: each edge adds the angle it subtends times
     * the cosine between n and the normal of the plane through p and the
     * edge. atan2 of |a x b| and a . b keeps small and near-pi angles exact. */
    double sum = 0.0;
    for (int k = 0; k < m; k++) {
        tb_dvec3 a = c[k], b = c[(k + 1) % m];
        tb_dvec3 g = tb_dvec3_cross(a, b);
        double gl = tb_dvec3_length(g);
        if (!(gl > 0.0))
            continue; /* p on the edge's line: the edge subtends no solid angle */
        double gamma = atan2(gl, tb_dvec3_dot(a, b));
        sum += gamma * (tb_dvec3_dot(nd, g) / gl);
    }
    /* Counter-clockwise seen from the front, with p in front, the edge normals
     * a x b point away from n: the sum is negative. */
    double f = -sum / (2.0 * TB__PI);
    if (!(f > 0.0))
        return 0.0;
    if (seen) {
        /* The corners' mean is inside the convex clipped polygon. */
        tb_dvec3 c0 = {0.0, 0.0, 0.0};
        for (int k = 0; k < m; k++)
            c0 = tb_dvec3_add(c0, c[k]);
        c0 = tb_dvec3_add(pd, tb_dvec3_scale(c0, 1.0 / m));
        *seen = (tb_vec3){(float)c0.x, (float)c0.y, (float)c0.z};
    }
    return f;
}

double tb_ff_point_polygon(tb_vec3 p, tb_vec3 n, const tb_ff_polygon *poly)
{
    return tb__ff_point_polygon_ex(p, n, poly, NULL);
}

/* ------------------------------------------------------------ sample points */

/* Measure-preserving map of the unit square onto the triangle (Heitz 2019, "A
 * Low-Distortion Map Between Triangle and Square"): piecewise linear with a
 * constant Jacobian, so equal-area cells of the square become equal-area
 * pieces of the triangle. */
static tb_dvec3 tb__warp_triangle(tb_dvec3 v0, tb_dvec3 v1, tb_dvec3 v2, double u1, double u2)
{
    double b1, b2;
    if (u2 > u1) {
        b1 = 0.5 * u1;
        b2 = u2 - b1;
    } else {
        b2 = 0.5 * u2;
        b1 = u1 - b2;
    }
    return tb_dvec3_add(v0, tb_dvec3_add(tb_dvec3_scale(tb_dvec3_sub(v1, v0), b1),
                                         tb_dvec3_scale(tb_dvec3_sub(v2, v0), b2)));
}

/* Root in [0, 1] of (lin + q x / 2) x = u total, with the density lin + q x
 * positive on [0, 1] (the cancellation-free form of the quadratic formula). */
static double tb__invert_linear_cdf(double lin, double q, double u, double total)
{
    double rhs = u * total;
    double disc = lin * lin + 2.0 * q * rhs;
    double den = lin + sqrt(disc > 0.0 ? disc : 0.0);
    double x = den > 0.0 ? 2.0 * rhs / den : u;
    return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x);
}

/* The quad's parameters (s, t) of the bilinear patch
 * P = (1-s)(1-t) v0 + s(1-t) v1 + s t v2 + (1-s) t v3, drawn so that the
 * image of a uniform (u1, u2) is uniform on the quad: the patch's area
 * density J(s, t) = j0 + js s + jt t is linear for a planar quad, so s
 * follows its marginal and t its conditional density, both linear (inverted
 * in closed form). Square cells of u map to equal-area pieces of the quad;
 * for a parallelogram the map is the plain bilinear one. */
typedef struct tb__quad_map {
    tb_dvec3 v[4];
    double j0, js, jt;
} tb__quad_map;

static tb_dvec3 tb__warp_quad(const tb__quad_map *q, double u1, double u2)
{
    double s = tb__invert_linear_cdf(q->j0 + 0.5 * q->jt, q->js, u1, q->j0 + 0.5 * q->js + 0.5 * q->jt);
    double lin = q->j0 + q->js * s;
    double t = tb__invert_linear_cdf(lin, q->jt, u2, lin + 0.5 * q->jt);
    double w0 = (1.0 - s) * (1.0 - t), w1 = s * (1.0 - t), w2 = s * t, w3 = (1.0 - s) * t;
    tb_dvec3 p = tb_dvec3_scale(q->v[0], w0);
    p = tb_dvec3_add(p, tb_dvec3_scale(q->v[1], w1));
    p = tb_dvec3_add(p, tb_dvec3_scale(q->v[2], w2));
    return tb_dvec3_add(p, tb_dvec3_scale(q->v[3], w3));
}

/* The points of both sample calls: jittered (rng) or at the cells' centres (rng NULL). */
static tb_status tb__sample(const tb_ff_polygon *poly, int nsamples, tb_rng *rng, tb_vec3 *out)
{
    if (!poly || !out)
        return tb_error(TB_ERR_ARG, "NULL argument");
    if (nsamples < 1)
        return tb_error(TB_ERR_ARG, "nsamples %d < 1", nsamples);
    if (!tb__ff_polygon_ok(poly))
        return tb_error(TB_ERR_ARG, "degenerate polygon (%d corners, zero area or not finite)", poly->n);
    tb_dvec3 v[TB_FF_MAX_VERTS];
    for (int k = 0; k < poly->n; k++)
        v[k] = tb__ff_d(poly->v[k]);
    tb_dvec3 nn = tb__ff_newell(poly);

    /* The quad map needs J > 0 inside, i.e. at the four corners (J is
     * linear); a non-convex or folded quad is sampled as two triangles
     * instead (u1 split in proportion to their areas: still measure-preserving). */
    bool quad = false, two_tris = false;
    tb__quad_map qm;
    double split = 0.0;
    double ls = 1.0, lt = 1.0;
    if (poly->n == 4) {
        tb_dvec3 e0 = tb_dvec3_sub(v[1], v[0]), e1 = tb_dvec3_sub(v[2], v[3]);
        tb_dvec3 f0 = tb_dvec3_sub(v[3], v[0]), f1 = tb_dvec3_sub(v[2], v[1]);
        double ja = tb_dvec3_dot(tb_dvec3_cross(e0, f0), nn); /* J at (0, 0) */
        double jb = tb_dvec3_dot(tb_dvec3_cross(e0, f1), nn); /* (1, 0) */
        double jc = tb_dvec3_dot(tb_dvec3_cross(e1, f0), nn); /* (0, 1) */
        double jd = tb_dvec3_dot(tb_dvec3_cross(e1, f1), nn); /* (1, 1) */
        if (ja > 0.0 && jb > 0.0 && jc > 0.0 && jd > 0.0) {
            quad = true;
            for (int k = 0; k < 4; k++)
                qm.v[k] = v[k];
            qm.j0 = ja;
            qm.js = jb - ja;
            qm.jt = jc - ja;
            ls = 0.5 * (tb_dvec3_length(e0) + tb_dvec3_length(e1));
            lt = 0.5 * (tb_dvec3_length(f0) + tb_dvec3_length(f1));
        } else {
            /* Split along the diagonal whose triangles both face the normal. */
            double a1 = tb_dvec3_dot(tb_dvec3_cross(tb_dvec3_sub(v[1], v[0]), tb_dvec3_sub(v[2], v[0])), nn);
            double a2 = tb_dvec3_dot(tb_dvec3_cross(tb_dvec3_sub(v[2], v[0]), tb_dvec3_sub(v[3], v[0])), nn);
            if (!(a1 > 0.0 && a2 > 0.0)) {
                tb_dvec3 w[4] = {v[1], v[2], v[3], v[0]};
                for (int k = 0; k < 4; k++)
                    v[k] = w[k];
                a1 = tb_dvec3_dot(tb_dvec3_cross(tb_dvec3_sub(v[1], v[0]), tb_dvec3_sub(v[2], v[0])), nn);
                a2 = tb_dvec3_dot(tb_dvec3_cross(tb_dvec3_sub(v[2], v[0]), tb_dvec3_sub(v[3], v[0])), nn);
            }
            if (!(a1 >= 0.0 && a2 >= 0.0 && a1 + a2 > 0.0))
                return tb_error(TB_ERR_ARG, "self-intersecting quad");
            two_tris = true;
            split = a1 / (a1 + a2);
        }
    }

    /* Strata: ny rows of equal height share the nsamples cells as evenly as
     * possible; a row of c cells has height c / nsamples and cells 1 / c wide,
     * so every cell has area 1 / nsamples. ny ~ sqrt(nsamples lt / ls) keeps
     * the cells near square on the polygon. */
    double ny_f = sqrt((double)nsamples * lt / ls);
    int ny = (int)lround(ny_f);
    if (ny < 1)
        ny = 1;
    if (ny > nsamples)
        ny = nsamples;
    int idx = 0;
    for (int row = 0; row < ny; row++) {
        long long c0 = (long long)row * nsamples / ny, c1 = (long long)(row + 1) * nsamples / ny;
        int cells = (int)(c1 - c0);
        double y0 = (double)c0 / nsamples, h = (double)cells / nsamples;
        for (int col = 0; col < cells; col++) {
            double j2 = rng ? tb_rng_double(rng) : 0.5, j1 = rng ? tb_rng_double(rng) : 0.5;
            double u2 = y0 + h * j2;
            double u1 = (col + j1) / cells;
            if (u1 >= 1.0)
                u1 = nextafter(1.0, 0.0);
            if (u2 >= 1.0)
                u2 = nextafter(1.0, 0.0);
            tb_dvec3 q;
            if (quad) {
                q = tb__warp_quad(&qm, u1, u2);
            } else if (two_tris) {
                if (u1 < split)
                    q = tb__warp_triangle(v[0], v[1], v[2], u1 / split, u2);
                else
                    q = tb__warp_triangle(v[0], v[2], v[3], (u1 - split) / (1.0 - split), u2);
            } else {
                q = tb__warp_triangle(v[0], v[1], v[2], u1, u2);
            }
            out[idx++] = (tb_vec3){(float)q.x, (float)q.y, (float)q.z};
        }
    }
    return TB_OK;
}

tb_status tb_ff_sample_polygon(const tb_ff_polygon *poly, int nsamples, uint64_t seed, tb_vec3 *out)
{
    tb_rng rng;
    tb_rng_seed(&rng, seed, 0x666f726d66616374ull); /* stream "formfact" */
    tb_status st = tb__sample(poly, nsamples, &rng, out);
    return st ? tb_error_context(st, "tb_ff_sample_polygon") : TB_OK;
}

tb_status tb_ff_sample_polygon_centres(const tb_ff_polygon *poly, int nsamples, tb_vec3 *out)
{
    tb_status st = tb__sample(poly, nsamples, NULL, out);
    return st ? tb_error_context(st, "tb_ff_sample_polygon_centres") : TB_OK;
}
