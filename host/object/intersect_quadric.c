/* Crossings of a line with the curved primitives: sphere; cylinder, cone and
 * conic (one revolved quadric clipped by a z slab); torus (a quartic).
 *
 * Everything is double precision in object space. Before solving, the line's
 * origin is moved to the point of the line nearest to the primitive's centre,
 * so that the constant coefficient is small even for rays from far away (the
 * cancellation in |o|^2 - 1 is what loses digits in the textbook formula; see
 * Haines, Guenther, Akenine-Moller, "Precision Improvements for Ray/Sphere
 * Intersection", Ray Tracing Gems ch. 7). Quadratics use util/roots'
 * tb_quadratic (q = -(b + sign(b) sqrt(D))/2 with a Kahan discriminant).
 *
 * Solids are computed as intervals, and a solid's caps as the clip of the
 * quadric's interval by the slab z0 <= z <= z1: the rim where side and cap
 * meet is then watertight by construction (a ray cannot slip between a side
 * test and a cap test that disagree about the rim). */
#include <math.h>
#include <string.h>

#include "host/object/intersect_internal.h"
#include "host/object/param.h"
#include "util/roots/roots.h"

/* One end of an interval: where it is and on which face. */
typedef struct tb__end {
    double t;
    uint32_t face;
    tb_dvec3 n;
} tb__end;

static void tb__push(tb__xbuf *out, const tb_object *o, const tb__end *e, int dir)
{
    tb__xing x = {e->t, e->n, o, e->face, 0, dir};
    tb__xbuf_push(out, &x);
}

static tb_dvec3 tb__at(tb_dvec3 o, tb_dvec3 d, double s)
{
    return (tb_dvec3){o.x + s * d.x, o.y + s * d.y, o.z + s * d.z};
}

/* ------------------------------------------------------------------ sphere */

/* The line's nearest point to the centre, o + t0 d = p0, and the roots s of
 * |p0 + s d| = 1 (two, equal for a tangent); false if it misses. */
static inline bool tb__sphere_roots(const tb__oray *r, double *t0, tb_dvec3 *p0, double root[2])
{
    tb_dvec3 d = r->d;
    double dd = tb_dvec3_dot(d, d);
    *t0 = -tb_dvec3_dot(r->o, d) / dd;
    *p0 = tb__at(r->o, d, *t0);
    int n = tb_quadratic(dd, 2.0 * tb_dvec3_dot(*p0, d), tb_dvec3_dot(*p0, *p0) - 1.0, root);
    if (n == 0)
        return false;
    if (n == 1)
        root[1] = root[0];
    return true;
}

void tb__xings_sphere(const tb_object *o, const tb__oray *r, tb__xbuf *out)
{
    double t0, root[2];
    tb_dvec3 p0, d = r->d;
    if (!tb__sphere_roots(r, &t0, &p0, root))
        return;
    tb__end a = {t0 + root[0], TB_FACE_SPHERE, tb__at(p0, d, root[0])};
    tb__end b = {t0 + root[1], TB_FACE_SPHERE, tb__at(p0, d, root[1])};
    tb__push(out, o, &a, +1);
    tb__push(out, o, &b, -1);
}

/* True if float(t) of a crossing lies in [tmin, tmax]: tb__closest's test. */
static inline bool tb__t_in(double t, double tmin, double tmax)
{
    return (float)t >= tmin && (float)t <= tmax;
}

bool tb__any_sphere(const tb_object *o, const tb__oray *r, double tmin, double tmax)
{
    (void)o;
    double t0, root[2];
    tb_dvec3 p0;
    if (!tb__sphere_roots(r, &t0, &p0, root))
        return false;
    return tb__t_in(t0 + root[0], tmin, tmax) || tb__t_in(t0 + root[1], tmin, tmax);
}

/* ------------------------------------------- cylinder, cone, conic (revolved) */

/* Outward normal of x^2 + y^2 - (c0 + c1 z + c2 z^2) = 0 at p; the axis
 * direction at an apex where the gradient vanishes. */
static tb_dvec3 tb__revolved_normal(const double *c, tb_dvec3 p, double zmid)
{
    tb_dvec3 n = {p.x, p.y, -(0.5 * c[1] + c[2] * p.z)};
    if (n.x == 0.0 && n.y == 0.0 && n.z == 0.0)
        n.z = p.z > zmid ? 1.0 : -1.0;
    return n;
}

void tb__revolved_prepare(tb_object *o)
{
    /* An end where the radius is zero closes in a point: anything found
     * there belongs to the side. */
    const double *c = o->conic;
    for (int i = 0; i < 2; i++) {
        double z = o->zrange[i];
        double sz = fabs(c[0]) + fabs(c[1] * z) + fabs(c[2] * z * z);
        o->zclosed[i] = c[0] + c[1] * z + c[2] * z * z <= 1e-12 * sz;
    }
}

/* The crossings of a revolved solid, for tb__xings_revolved (out, with
 * normals) or tb__any_revolved (out NULL: true as soon as one has float t in
 * [tmin, tmax]; no normals). One body, so both see the same t. Inlined
 * into each with `out` known, which drops the normals of the second. */
static inline __attribute__((always_inline)) bool tb__revolved(const tb_object *o, const tb__oray *r,
                                                                tb__xbuf *out, double tmin, double tmax)
{
    const double *c = o->conic;
    double z0 = o->zrange[0], z1 = o->zrange[1], zc = 0.5 * (z0 + z1);
    bool caps;
    switch (o->kind) {
    case TB_PRIM_CYLINDER: caps = o->geom.cylinder.caps; break;
    case TB_PRIM_CONE: caps = o->geom.cone.caps; break;
    default: caps = o->geom.conic.caps; break;
    }
    tb_dvec3 d = r->d;
    double dd = tb_dvec3_dot(d, d);
    tb_dvec3 oc = {r->o.x, r->o.y, r->o.z - zc};
    double t0 = -tb_dvec3_dot(oc, d) / dd;
    tb_dvec3 p0 = tb__at(r->o, d, t0);

    /* Q(p0 + s d) = A s^2 + B s + C; the solid side is Q <= 0. */
    double A = d.x * d.x + d.y * d.y - c[2] * d.z * d.z;
    double B = 2.0 * (p0.x * d.x + p0.y * d.y) - c[1] * d.z - 2.0 * c[2] * p0.z * d.z;
    double C = p0.x * p0.x + p0.y * p0.y - c[0] - c[1] * p0.z - c[2] * p0.z * p0.z;
    double qa[2], qb[2];
    int nq = 0;
    if (A != 0.0) {
        double root[2];
        int n = tb_quadratic(A, B, C, root);
        if (n == 1)
            root[1] = root[0];
        if (A > 0.0) {
            if (n > 0) {
                qa[0] = root[0];
                qb[0] = root[1];
                nq = 1;
            }
        } else if (n > 0) {
            qa[0] = -INFINITY;
            qb[0] = root[0];
            qa[1] = root[1];
            qb[1] = INFINITY;
            nq = 2;
        } else if (C <= 0.0) {
            qa[0] = -INFINITY;
            qb[0] = INFINITY;
            nq = 1;
        }
    } else if (B != 0.0) {
        double s = -C / B;
        qa[0] = B > 0.0 ? -INFINITY : s;
        qb[0] = B > 0.0 ? s : INFINITY;
        nq = isfinite(s) ? 1 : 0;
    } else if (C <= 0.0) {
        qa[0] = -INFINITY;
        qb[0] = INFINITY;
        nq = 1;
    }
    if (nq == 0)
        return false;

    /* The slab z0 <= z <= z1. */
    tb__end sa, sb;
    if (d.z == 0.0) {
        if (!(p0.z >= z0 && p0.z <= z1))
            return false;
        sa = (tb__end){-INFINITY, TB_FACE_CYLINDER_BOTTOM, {0, 0, -1}};
        sb = (tb__end){INFINITY, TB_FACE_CYLINDER_TOP, {0, 0, 1}};
    } else {
        /* An end closed in a point (tb__revolved_prepare) belongs to the side. */
        bool closed0 = o->zclosed[0], closed1 = o->zclosed[1];
        tb__end bot = {(z0 - p0.z) / d.z, closed0 ? TB_FACE_CYLINDER_SIDE : TB_FACE_CYLINDER_BOTTOM, {0, 0, -1}};
        tb__end top = {(z1 - p0.z) / d.z, closed1 ? TB_FACE_CYLINDER_SIDE : TB_FACE_CYLINDER_TOP, {0, 0, 1}};
        sa = d.z > 0.0 ? bot : top;
        sb = d.z > 0.0 ? top : bot;
    }
    /* The face constants of cylinder, cone and conic agree: side 0, bottom 1, top 2. */
    _Static_assert((int)TB_FACE_CONE_SIDE == 0 && (int)TB_FACE_CONIC_SIDE == 0 && (int)TB_FACE_CYLINDER_SIDE == 0 &&
                       (int)TB_FACE_CONE_BOTTOM == 1 && (int)TB_FACE_CONIC_BOTTOM == 1 &&
                       (int)TB_FACE_CYLINDER_BOTTOM == 1 && (int)TB_FACE_CONE_TOP == 2 &&
                       (int)TB_FACE_CONIC_TOP == 2 && (int)TB_FACE_CYLINDER_TOP == 2,
                   "revolved primitives share face numbers");

    for (int i = 0; i < nq; i++) {
        tb__end a = {0}, b = {0}; /* normals only with out */
        if (qa[i] >= sa.t) {
            a.t = qa[i];
            a.face = TB_FACE_CYLINDER_SIDE;
            if (out)
                a.n = tb__revolved_normal(c, tb__at(p0, d, qa[i]), zc);
        } else {
            a = sa;
        }
        if (qb[i] <= sb.t) {
            b.t = qb[i];
            b.face = TB_FACE_CYLINDER_SIDE;
            if (out)
                b.n = tb__revolved_normal(c, tb__at(p0, d, qb[i]), zc);
        } else {
            b = sb;
        }
        if (!(a.t <= b.t) || !isfinite(a.t) || !isfinite(b.t))
            continue;
        a.t += t0;
        b.t += t0;
        /* Without caps the surface is open: ends on the missing discs are not surface. */
        bool keep_a = caps || a.face == TB_FACE_CYLINDER_SIDE, keep_b = caps || b.face == TB_FACE_CYLINDER_SIDE;
        if (!out) {
            if ((keep_a && tb__t_in(a.t, tmin, tmax)) || (keep_b && tb__t_in(b.t, tmin, tmax)))
                return true;
            continue;
        }
        if (keep_a)
            tb__push(out, o, &a, +1);
        if (keep_b)
            tb__push(out, o, &b, -1);
    }
    return false;
}

void tb__xings_revolved(const tb_object *o, const tb__oray *r, tb__xbuf *out)
{
    tb__revolved(o, r, out, 0.0, 0.0);
}

bool tb__any_revolved(const tb_object *o, const tb__oray *r, double tmin, double tmax)
{
    return tb__revolved(o, r, NULL, tmin, tmax);
}

/* ------------------------------------------------------------------ torus */

/* Signed distance from p to the torus with major R, minor r (about z). */
static double tb__torus_dist(tb_dvec3 p, double R, double r)
{
    double q = hypot(p.x, p.y) - R;
    return hypot(q, p.z) - r;
}

/* Its gradient (unit length except on the centre circle and the axis). */
static tb_dvec3 tb__torus_grad(tb_dvec3 p, double R)
{
    double rho = hypot(p.x, p.y);
    tb_dvec3 c = rho > 0.0 ? (tb_dvec3){R * p.x / rho, R * p.y / rho, 0.0} : (tb_dvec3){R, 0.0, 0.0};
    tb_dvec3 g = tb_dvec3_sub(p, c);
    double l = tb_dvec3_length(g);
    return l > 0.0 ? tb_dvec3_scale(g, 1.0 / l) : (tb_dvec3){0.0, 0.0, 1.0};
}

/* The torus quartic of tb__xings_torus: its scaled frame (S, R, rr, the
 * unit direction D, the line's point p0 nearest the centre at s0) and the
 * coefficients of Q(s), s the scaled length along D from p0. False when the
 * line misses the bounding sphere (no crossings). */
typedef struct tb__torus_line {
    double S, R, rr, len, s0;
    tb_dvec3 D, p0;
    double coef[5];
} tb__torus_line;

static bool tb__torus_line_init(const tb_object *o, const tb__oray *r, tb__torus_line *q)
{
    /* Work in units of the bounding radius S = R + r along the unit direction D,
     * from the point of the line nearest to the centre: every quantity the
     * quartic sees is then O(1) whatever the scale of the torus or the
     * distance of the ray origin. */
    double S = o->geom.torus.major + o->geom.torus.minor;
    double R = o->geom.torus.major / S, rr = o->geom.torus.minor / S;
    double len = tb_dvec3_length(r->d);
    tb_dvec3 D = tb_dvec3_scale(r->d, 1.0 / len);
    tb_dvec3 os = tb_dvec3_scale(r->o, 1.0 / S);
    double s0 = -tb_dvec3_dot(os, D);
    tb_dvec3 p0 = tb__at(os, D, s0);
    *q = (tb__torus_line){S, R, rr, len, s0, D, p0, {0}};
    if (tb_dvec3_dot(p0, p0) > 1.0 + 1e-9)
        return false; /* misses the bounding sphere */

    double g = tb_dvec3_dot(p0, D);
    double e = tb_dvec3_dot(p0, p0) + R * R - rr * rr;
    double dxy = D.x * D.x + D.y * D.y;
    q->coef[0] = 1.0;
    q->coef[1] = 4.0 * g;
    q->coef[2] = 4.0 * g * g + 2.0 * e - 4.0 * R * R * dxy;
    q->coef[3] = 4.0 * g * e - 8.0 * R * R * (p0.x * D.x + p0.y * D.y);
    q->coef[4] = e * e - 4.0 * R * R * (p0.x * p0.x + p0.y * p0.y);
    return true;
}

bool tb__torus_clear(const tb_object *o, const tb__oray *r, double tmin, double tmax)
{
    /* Q(s) = f(s) (d_c + r) ((rho + R)^2 + z^2 - r^2), f the signed distance
     * to the torus and d_c to its centre circle: the second and third factors
     * are >= r and R^2 - r^2 and <= 10 within the bounding sphere. Every root
     * tb__xings_torus reports has |Q| within ~1e-14 (the solver's rounding
     * band, then a polish that only lowers |f|), so |f| < 1e-11 there when
     * r (R^2 - r^2) >= 0.01, and |Q| < 1e-10 after the polish: none lies
     * where Q > 1e-9. That is certified on the s range of [tmin, tmax]
     * (widened for the rounding of t to float), cut to the bounding sphere,
     * by the Bernstein coefficients of Q (their minimum bounds Q from below),
     * halving the range where they do not suffice. Shadow rays leaving the
     * torus start ~1e-7 outside it, well above that bound. */
    tb__torus_line q;
    if (!tb__torus_line_init(o, r, &q))
        return true;
    if (!(q.rr * (q.R * q.R - q.rr * q.rr) >= 0.01) || !(q.len > 0.0) || !isfinite(q.len))
        return false; /* thin tori: the bound on |f| above is weaker */
    const double thr = 1e-9, k = q.S / q.len;
    double tlo = tmin - (0x1p-22 * fabs(tmin) + 0x1p-140), thi = tmax + (0x1p-22 * fabs(tmax) + 0x1p-140);
    double h = sqrt(fmax(0.0, 1.0 + 1e-9 - tb_dvec3_dot(q.p0, q.p0))) + 1e-6; /* |p| <= 1 at any root */
    double lo = fmax(tlo / k - q.s0, -h), hi = fmin(thi / k - q.s0, h);
    if (isnan(lo) || isnan(hi))
        return false;
    if (lo > hi)
        return true;
    /* Taylor shift to lo, then the Bernstein coefficients on [lo, hi]. */
    double a[5] = {q.coef[4], q.coef[3], q.coef[2], q.coef[1], q.coef[0]}; /* a[j]: of s^j */
    for (int i = 0; i < 4; i++)
        for (int j = 3; j >= i; j--)
            a[j] += lo * a[j + 1];
    double w = hi - lo, t[5], wp = 1.0;
    for (int j = 0; j < 5; j++, wp *= w)
        t[j] = a[j] * wp;
    /* Pending ranges as Bernstein coefficients; each split halves one. */
    double stack[8][5];
    int n = 1;
    stack[0][0] = t[0];
    stack[0][1] = t[0] + 0.25 * t[1];
    stack[0][2] = t[0] + 0.5 * t[1] + t[2] / 6.0;
    stack[0][3] = t[0] + 0.75 * t[1] + 0.5 * t[2] + 0.25 * t[3];
    stack[0][4] = t[0] + t[1] + t[2] + t[3] + t[4];
    for (int splits = 0; n > 0;) {
        double *b = stack[--n];
        if (!(b[0] > thr && b[4] > thr))
            return false; /* Q near 0 (or below) at an end: the solver decides */
        if (b[1] > thr && b[2] > thr && b[3] > thr)
            continue;
        if (++splits > 24 || n + 2 > 8)
            return false;
        /* de Casteljau at 1/2: left into stack[n], right into stack[n + 1] */
        double c[5][5];
        for (int i = 0; i < 5; i++)
            c[0][i] = b[i];
        for (int l = 1; l < 5; l++)
            for (int i = 0; i + l < 5; i++)
                c[l][i] = 0.5 * (c[l - 1][i] + c[l - 1][i + 1]);
        double left[5], right[5];
        for (int i = 0; i < 5; i++) {
            left[i] = c[i][0];
            right[i] = c[4 - i][i];
        }
        memcpy(stack[n], left, sizeof left);
        memcpy(stack[n + 1], right, sizeof right);
        n += 2;
    }
    return true;
}

void tb__xings_torus(const tb_object *o, const tb__oray *r, tb__xbuf *out)
{
    tb__torus_line q;
    if (!tb__torus_line_init(o, r, &q))
        return; /* misses the bounding sphere */
    const double S = q.S, R = q.R, rr = q.rr, len = q.len, s0 = q.s0, *coef = q.coef;
    const tb_dvec3 D = q.D, p0 = q.p0;
    double root[4];
    int n = tb_quartic(coef[0], coef[1], coef[2], coef[3], coef[4], root);
    if (n == 0)
        return;
    /* Newton polish on the distance function along the line (well scaled:
     * its gradient has unit length), which also removes the error the
     * expanded coefficients carry; a step is kept only if it brings the
     * point closer to the surface. */
    for (int i = 0; i < n; i++) {
        double s = root[i];
        double f = tb__torus_dist(tb__at(p0, D, s), R, rr);
        for (int it = 0; it < 3 && f != 0.0; it++) {
            tb_dvec3 p = tb__at(p0, D, s);
            double df = tb_dvec3_dot(tb__torus_grad(p, R), D);
            if (!(fabs(df) > 1e-8))
                break; /* grazing: the quartic root is the better answer */
            double s1 = s - f / df;
            double f1 = tb__torus_dist(tb__at(p0, D, s1), R, rr);
            if (!(fabs(f1) < fabs(f)))
                break;
            s = s1;
            f = f1;
        }
        root[i] = s;
    }
    for (int i = 1; i < n; i++) /* polishing may swap neighbours */
        for (int j = i; j > 0 && root[j] < root[j - 1]; j--) {
            double tmp = root[j];
            root[j] = root[j - 1];
            root[j - 1] = tmp;
        }

    /* Intervals: pairs of roots (a tangent root is reported twice); with an
     * odd count (a root lost to rounding at a tangency) classify the gaps by
     * the sign of the distance at their midpoints instead. */
    double ia[2], ib[2];
    int ni = 0;
    if (n % 2 == 0) {
        for (int i = 0; i + 1 < n; i += 2) {
            ia[ni] = root[i];
            ib[ni++] = root[i + 1];
        }
    } else {
        bool in = false;
        double start = 0.0;
        for (int i = 0; i < n; i++) {
            bool next_in = i + 1 < n && tb__torus_dist(tb__at(p0, D, 0.5 * (root[i] + root[i + 1])), R, rr) < 0.0;
            if (!in && next_in)
                start = root[i];
            else if (in && !next_in && ni < 2) {
                ia[ni] = start;
                ib[ni++] = root[i];
            }
            in = next_in;
        }
    }
    double k = S / len; /* scaled length along D -> ray parameter */
    for (int i = 0; i < ni; i++) {
        tb__end a = {(s0 + ia[i]) * k, TB_FACE_TORUS, tb__torus_grad(tb__at(p0, D, ia[i]), R)};
        tb__end b = {(s0 + ib[i]) * k, TB_FACE_TORUS, tb__torus_grad(tb__at(p0, D, ib[i]), R)};
        tb__push(out, o, &a, +1);
        tb__push(out, o, &b, -1);
    }
}
