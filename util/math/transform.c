#include "util/math/transform.h"

#include <math.h>

#include "util/math/float.h"

tb_transform tb_transform_identity(void)
{
    return (tb_transform){tb_mat4_identity(), tb_mat4_identity()};
}

tb_transform tb_transform_translate(tb_dvec3 t)
{
    tb_transform r = tb_transform_identity();
    r.m.m[0][3] = t.x;
    r.m.m[1][3] = t.y;
    r.m.m[2][3] = t.z;
    r.inv.m[0][3] = -t.x;
    r.inv.m[1][3] = -t.y;
    r.inv.m[2][3] = -t.z;
    return r;
}

tb_status tb_transform_scale(tb_dvec3 s, tb_transform *out)
{
    if (!tb_dvec3_isfinite(s))
        return tb_error(TB_ERR_ARG, "scale (%g, %g, %g) is not finite", s.x, s.y, s.z);
    if (s.x == 0.0 || s.y == 0.0 || s.z == 0.0)
        return tb_error(TB_ERR_ARG, "scale (%g, %g, %g) has a zero factor (not invertible)", s.x,
                        s.y, s.z);
    /* The same verdict tb_mat4_inverse gives for the diagonal matrix:
     * reciprocal condition number min|s| / max|s|. */
    tb_dvec3 a = tb_dvec3_abs(s);
    double smax = tb_dvec3_max_comp(a), smin = fmin(a.x, fmin(a.y, a.z));
    if (!(smin / smax >= TB_MAT_RCOND_MIN))
        return tb_error(TB_ERR_NUMERIC,
                        "scale (%g, %g, %g) is ill-conditioned: smallest / largest factor "
                        "%.3g < %.3g",
                        s.x, s.y, s.z, smin / smax, TB_MAT_RCOND_MIN);
    tb_transform r = tb_transform_identity();
    r.m.m[0][0] = s.x;
    r.m.m[1][1] = s.y;
    r.m.m[2][2] = s.z;
    r.inv.m[0][0] = 1.0 / s.x;
    r.inv.m[1][1] = 1.0 / s.y;
    r.inv.m[2][2] = 1.0 / s.z;
    if (!tb_mat4_isfinite(&r.inv))
        return tb_error(TB_ERR_NUMERIC, "scale (%g, %g, %g) has no finite inverse", s.x, s.y, s.z);
    *out = r;
    return TB_OK;
}

/* The rotation with unit axis a, given its sine and cosine (Rodrigues). */
static tb_transform tb__rotation(double s, double c, tb_dvec3 a)
{
    tb_transform r = tb_transform_identity();
    double (*m)[4] = r.m.m;
    double k = 1.0 - c;
    m[0][0] = a.x * a.x * k + c;
    m[0][1] = a.x * a.y * k - a.z * s;
    m[0][2] = a.x * a.z * k + a.y * s;
    m[1][0] = a.x * a.y * k + a.z * s;
    m[1][1] = a.y * a.y * k + c;
    m[1][2] = a.y * a.z * k - a.x * s;
    m[2][0] = a.x * a.z * k - a.y * s;
    m[2][1] = a.y * a.z * k + a.x * s;
    m[2][2] = a.z * a.z * k + c;
    /* A rotation's inverse is its transpose: exact, and orthogonal to
     * rounding just as m is. */
    r.inv = tb_mat4_transpose(&r.m);
    return r;
}

static tb_status tb__rotate_sc(double s, double c, tb_dvec3 axis, tb_transform *out)
{
    if (!tb_dvec3_isfinite(axis))
        return tb_error(TB_ERR_ARG, "rotation axis (%g, %g, %g) is not finite", axis.x, axis.y,
                        axis.z);
    /* Scale by the largest component first so that tiny or huge axes do not
     * under/overflow when squared. */
    double big = tb_dvec3_max_comp(tb_dvec3_abs(axis));
    if (big == 0.0)
        return tb_error(TB_ERR_ARG, "rotation axis is the zero vector");
    tb_dvec3 a = tb_dvec3_normalize(tb_dvec3_scale(axis, 1.0 / big));
    *out = tb__rotation(s, c, a);
    return TB_OK;
}

tb_status tb_transform_rotate(double radians, tb_dvec3 axis, tb_transform *out)
{
    if (!isfinite(radians))
        return tb_error(TB_ERR_ARG, "rotation angle %g is not finite", radians);
    return tb__rotate_sc(sin(radians), cos(radians), axis, out);
}

/* sin and cos of an angle in degrees, exact at multiples of 90: the angle is
 * reduced to r in [-45, 45] plus a quadrant q before converting to radians. */
static void tb__sincos_deg(double deg, double *s, double *c)
{
    double r = fmod(deg, 360.0); /* exact */
    double q = nearbyint(r / 90.0);
    r -= q * 90.0; /* exact (Sterbenz): r and q*90 are within a factor of 2 */
    double sr = sin(tb_radians(r)), cr = cos(tb_radians(r));
    int quad = ((int)q % 4 + 4) % 4;
    switch (quad) {
    case 0: *s = sr; *c = cr; break;
    case 1: *s = cr; *c = -sr; break;
    case 2: *s = -sr; *c = -cr; break;
    default: *s = -cr; *c = sr; break;
    }
}

tb_status tb_transform_rotate_deg(double degrees, tb_dvec3 axis, tb_transform *out)
{
    if (!isfinite(degrees))
        return tb_error(TB_ERR_ARG, "rotation angle %g is not finite", degrees);
    double s, c;
    tb__sincos_deg(degrees, &s, &c);
    return tb__rotate_sc(s, c, axis, out);
}

tb_transform tb_transform_rotate_x(double radians)
{
    return tb__rotation(sin(radians), cos(radians), (tb_dvec3){1, 0, 0});
}

tb_transform tb_transform_rotate_y(double radians)
{
    return tb__rotation(sin(radians), cos(radians), (tb_dvec3){0, 1, 0});
}

tb_transform tb_transform_rotate_z(double radians)
{
    return tb__rotation(sin(radians), cos(radians), (tb_dvec3){0, 0, 1});
}

tb_status tb_transform_look_at(tb_dvec3 eye, tb_dvec3 target, tb_dvec3 up, tb_transform *out)
{
    if (!tb_dvec3_isfinite(eye) || !tb_dvec3_isfinite(target) || !tb_dvec3_isfinite(up))
        return tb_error(TB_ERR_ARG, "look-at: eye, target and up must be finite");
    tb_dvec3 view = tb_dvec3_sub(target, eye);
    if (tb_dvec3_length2(view) == 0.0 || !tb_dvec3_isfinite(view))
        return tb_error(TB_ERR_ARG, "look-at: eye (%g, %g, %g) and target coincide (or are too far apart)",
                        eye.x, eye.y, eye.z);
    double ub = tb_dvec3_max_comp(tb_dvec3_abs(up));
    if (ub == 0.0)
        return tb_error(TB_ERR_ARG, "look-at: up is the zero vector");
    tb_dvec3 f = tb_dvec3_normalize(view);
    tb_dvec3 u = tb_dvec3_normalize(tb_dvec3_scale(up, 1.0 / ub));
    tb_dvec3 x = tb_dvec3_cross(f, u);
    /* |x| is the sine of the angle between view and up. */
    double sx = tb_dvec3_length(x);
    if (!(sx > 1e-12))
        return tb_error(TB_ERR_ARG,
                        "look-at: up (%g, %g, %g) is parallel to the view direction (%g, %g, %g)",
                        up.x, up.y, up.z, f.x, f.y, f.z);
    x = tb_dvec3_scale(x, 1.0 / sx);
    tb_dvec3 y = tb_dvec3_cross(x, f);
    tb_dvec3 z = tb_dvec3_neg(f);
    tb_transform r;
    /* Columns are the camera axes in world space; the last column is eye. */
    r.m = (tb_mat4){{{x.x, y.x, z.x, eye.x},
                     {x.y, y.y, z.y, eye.y},
                     {x.z, y.z, z.z, eye.z},
                     {0, 0, 0, 1}}};
    /* Inverse of a rigid motion [R e]: [R^T  -R^T e]. */
    r.inv = (tb_mat4){{{x.x, x.y, x.z, -tb_dvec3_dot(x, eye)},
                       {y.x, y.y, y.z, -tb_dvec3_dot(y, eye)},
                       {z.x, z.y, z.z, -tb_dvec3_dot(z, eye)},
                       {0, 0, 0, 1}}};
    *out = r;
    return TB_OK;
}

tb_status tb_transform_from_matrix(const tb_mat4 *m, tb_transform *out)
{
    tb_mat4 inv;
    tb_status st = tb_mat4_inverse(m, &inv);
    if (st)
        return tb_error_context(st, "transform from matrix");
    out->m = *m;
    out->inv = inv;
    return TB_OK;
}

tb_transform tb_transform_compose(const tb_transform *a, const tb_transform *b)
{
    return (tb_transform){tb_mat4_mul(&a->m, &b->m), tb_mat4_mul(&b->inv, &a->inv)};
}

tb_transform tb_transform_inverse(const tb_transform *t)
{
    return (tb_transform){t->inv, t->m};
}

bool tb_transform_swaps_handedness(const tb_transform *t)
{
    tb_mat3 l = tb_mat4_linear(&t->m);
    return tb_mat3_det(&l) < 0.0;
}

bool tb_transform_is_identity(const tb_transform *t)
{
    tb_mat4 i = tb_mat4_identity();
    return tb_mat4_equal(&t->m, &i);
}

tb_dvec3 tb_transform_dpoint(const tb_transform *t, tb_dvec3 p) { return tb_mat4_mul_point(&t->m, p); }

tb_dvec3 tb_transform_dvector(const tb_transform *t, tb_dvec3 v) { return tb_mat4_mul_vec(&t->m, v); }

tb_dvec3 tb_transform_dnormal(const tb_transform *t, tb_dvec3 n)
{
    const double(*m)[4] = t->inv.m; /* transposed use: column i of inv */
    return (tb_dvec3){m[0][0] * n.x + m[1][0] * n.y + m[2][0] * n.z,
                      m[0][1] * n.x + m[1][1] * n.y + m[2][1] * n.z,
                      m[0][2] * n.x + m[1][2] * n.y + m[2][2] * n.z};
}

tb_vec3 tb_transform_point(const tb_transform *t, tb_vec3 p)
{
    return tb_dvec3_to_f(tb_transform_dpoint(t, tb_vec3_to_d(p)));
}

tb_vec3 tb_transform_vector(const tb_transform *t, tb_vec3 v)
{
    return tb_dvec3_to_f(tb_transform_dvector(t, tb_vec3_to_d(v)));
}

tb_vec3 tb_transform_normal(const tb_transform *t, tb_vec3 n)
{
    return tb_dvec3_to_f(tb_transform_dnormal(t, tb_vec3_to_d(n)));
}

tb_ray tb_transform_ray(const tb_transform *t, const tb_ray *r)
{
    return (tb_ray){tb_transform_point(t, r->o), r->tmin, tb_transform_vector(t, r->d), r->tmax};
}

/* Accumulates v = s + e with error-free transformations (Knuth's TwoSum,
 * fma-based TwoProduct), so that the rounding to float can be done in the
 * right direction even when the double sum itself is inexact, and is exact
 * (no needless widening) whenever the double arithmetic was. */
typedef struct tb__xsum {
    double s;    /* double sum so far */
    double e;    /* sum of the exact rounding errors: value ~ s + e */
    double eabs; /* sum of |errors|: bounds the rounding of e itself */
    bool inf;    /* a term was infinite: no error terms, s is +-inf */
} tb__xsum;

static void tb__xsum_add(tb__xsum *x, double v, double ev)
{
    if (!isfinite(v) || x->inf || !isfinite(x->s)) {
        x->inf = true;
        x->s += v;
        return;
    }
    double s = x->s + v;
    double bp = s - x->s;
    double es = (x->s - (s - bp)) + (v - bp); /* TwoSum: exact x->s + v - s */
    x->s = s;
    x->e += es + ev;
    x->eabs += fabs(es) + fabs(ev);
}

/* Adds m * c exactly (product error from fma). A zero coefficient adds
 * nothing, even for an infinite c (0 * inf would be NaN). */
static void tb__xsum_mad(tb__xsum *x, double m, double c)
{
    if (m == 0.0)
        return;
    double p = m * c;
    double ep = isfinite(p) ? fma(m, c, -p) : 0.0;
    tb__xsum_add(x, p, ep);
}

/* Largest float <= s + e (the true value, to within eabs 2^-50). */
static float tb__xsum_down(const tb__xsum *x)
{
    if (isnan(x->s))
        return -INFINITY;
    float f = (float)x->s;
    if (x->inf)
        return f;
    double d = (double)f - x->s; /* exact (Sterbenz, or f = 0) unless f is inf */
    if (!(d <= x->e - x->eabs * 0x1p-50))
        f = tb_next_float_down(f);
    return f;
}

/* Smallest float >= s + e. */
static float tb__xsum_up(const tb__xsum *x)
{
    if (isnan(x->s))
        return INFINITY;
    float f = (float)x->s;
    if (x->inf)
        return f;
    double d = (double)f - x->s;
    if (!(d >= x->e + x->eabs * 0x1p-50))
        f = tb_next_float_up(f);
    return f;
}

/* Projective case: the 8 corners, each divided by its w. */
static tb_aabb tb__transform_aabb_corners(const tb_transform *t, const tb_aabb *b)
{
    const double(*m)[4] = t->m.m;
    tb_aabb r = tb_aabb_empty();
    for (int i = 0; i < 8; ++i) {
        tb_dvec3 p = {(i & 1) ? b->hi.x : b->lo.x, (i & 2) ? b->hi.y : b->lo.y,
                      (i & 4) ? b->hi.z : b->lo.z};
        double w = m[3][0] * p.x + m[3][1] * p.y + m[3][2] * p.z + m[3][3];
        if (!(w > 0.0) || !tb_dvec3_isfinite(p)) {
            /* The image wraps through infinity: only the whole space bounds it. */
            return (tb_aabb){{-INFINITY, -INFINITY, -INFINITY}, {INFINITY, INFINITY, INFINITY}};
        }
        tb_dvec3 q = tb_mat4_mul_point(&t->m, p);
        /* Each coordinate went through ~8 roundings in double; one float ulp
         * outward covers that with a wide margin. */
        tb_vec3 f = tb_dvec3_to_f(q);
        r = tb_aabb_union_point(r, (tb_vec3){tb_next_float_down(f.x), tb_next_float_down(f.y),
                                             tb_next_float_down(f.z)});
        r = tb_aabb_union_point(r, (tb_vec3){tb_next_float_up(f.x), tb_next_float_up(f.y),
                                             tb_next_float_up(f.z)});
    }
    return r;
}

tb_aabb tb_transform_aabb(const tb_transform *t, const tb_aabb *b)
{
    if (tb_aabb_is_empty(b))
        return tb_aabb_empty();
    if (!tb_mat4_is_affine(&t->m))
        return tb__transform_aabb_corners(t, b);
    /* Arvo: along output axis i, the extreme values of sum_j m_ij p_j over the
     * box come from picking p_j = lo_j or hi_j by the sign of m_ij. */
    const double(*m)[4] = t->m.m;
    double lo[3] = {b->lo.x, b->lo.y, b->lo.z}, hi[3] = {b->hi.x, b->hi.y, b->hi.z};
    float rlo[3], rhi[3];
    for (int i = 0; i < 3; ++i) {
        tb__xsum a = {m[i][3], 0.0, 0.0, !isfinite(m[i][3])};
        tb__xsum z = a;
        for (int j = 0; j < 3; ++j) {
            double c = m[i][j];
            tb__xsum_mad(&a, c, c >= 0.0 ? lo[j] : hi[j]);
            tb__xsum_mad(&z, c, c >= 0.0 ? hi[j] : lo[j]);
        }
        rlo[i] = tb__xsum_down(&a);
        rhi[i] = tb__xsum_up(&z);
    }
    return (tb_aabb){{rlo[0], rlo[1], rlo[2]}, {rhi[0], rhi[1], rhi[2]}};
}
