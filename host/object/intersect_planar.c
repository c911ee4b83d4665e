/* Crossings of a line with the primitives bounded by planes (and one
 * cylinder): cube, pyramid, prism, square arch and round arch.
 *
 * Convex solids (cube, pyramid, convex prisms, and the arches' openings) are
 * clipped by their half-spaces n . p <= c in turn (Cyrus-Beck / Kay-Kajiya):
 * the entry is the last plane entered, the exit the first plane left, so
 * edges and corners are watertight by construction and a tie goes to the
 * plane with the lower face ID. A prism with a non-convex profile counts
 * crossings of the profile's edges by the sides of the profile's vertices
 * relative to the line (a vertex exactly on the line counts as being on its
 * left), so a line through a vertex is counted once, never twice or zero
 * times. An arch is its block minus its opening, both convex, as intervals.
 * Double precision, object space, with the line's origin first moved to the
 * point nearest the primitive's centre. */
#include <math.h>
#include <stdlib.h>

#include "host/object/intersect_internal.h"
#include "host/object/param.h"
#include "util/math/float.h"
#include "util/roots/roots.h"

typedef struct tb__end {
    double t;
    uint32_t face;
    tb_dvec3 n;
} tb__end;

/* The line shifted to the point nearest the origin: o + t d = p0 + (t - t0) d. */
typedef struct tb__line {
    tb_dvec3 p0, d;
    double t0;
} tb__line;

static tb__line tb__line_near(const tb__oray *r, tb_dvec3 centre)
{
    tb__line l;
    l.d = r->d;
    tb_dvec3 oc = tb_dvec3_sub(r->o, centre);
    l.t0 = -tb_dvec3_dot(oc, r->d) / tb_dvec3_dot(r->d, r->d);
    l.p0 = (tb_dvec3){r->o.x + l.t0 * r->d.x, r->o.y + l.t0 * r->d.y, r->o.z + l.t0 * r->d.z};
    return l;
}

/* Clips [*a, *b] by the half-space n . p <= c (p on the line at s from p0).
 * A line parallel to the plane is inside when on the plane (closed solids).
 * Returns false when the line is entirely outside. */
static bool tb__clip(const tb__line *l, tb_dvec3 n, double c, uint32_t face, tb__end *a, tb__end *b)
{
    double den = tb_dvec3_dot(n, l->d);
    double num = c - tb_dvec3_dot(n, l->p0);
    if (den == 0.0)
        return num >= 0.0;
    double s = num / den;
    if (den < 0.0) {
        if (s > a->t)
            *a = (tb__end){s, face, n};
    } else if (s < b->t) {
        *b = (tb__end){s, face, n};
    }
    return true;
}

static void tb__push(tb__xbuf *out, const tb_object *o, const tb__line *l, const tb__end *e, int dir)
{
    tb__xing x = {e->t + l->t0, e->n, o, e->face, 0, dir};
    tb__xbuf_push(out, &x);
}

/* Pushes [a, b] if non-empty and finite; `keep_a`/`keep_b` say whether each end is surface. */
static void tb__push_interval(tb__xbuf *out, const tb_object *o, const tb__line *l, const tb__end *a,
                              const tb__end *b, bool keep_a, bool keep_b)
{
    if (!(a->t <= b->t) || !isfinite(a->t) || !isfinite(b->t))
        return;
    if (keep_a)
        tb__push(out, o, l, a, +1);
    if (keep_b)
        tb__push(out, o, l, b, -1);
}

static const tb__end tb__all_a = {-INFINITY, 0, {0, 0, 0}};
static const tb__end tb__all_b = {INFINITY, 0, {0, 0, 0}};

/* The cube [-1,1]^3 clipped on [*a, *b]; faces -x +x -y +y -z +z = 0..5. */
static bool tb__clip_cube(const tb__line *l, tb__end *a, tb__end *b)
{
    static const tb_dvec3 n[6] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
    for (uint32_t f = 0; f < 6; f++)
        if (!tb__clip(l, n[f], 1.0, f, a, b))
            return false;
    return true;
}

/* ------------------------------------------------------------------ cube */

void tb__xings_cube(const tb_object *o, const tb__oray *r, tb__xbuf *out)
{
    tb__line l = tb__line_near(r, (tb_dvec3){0, 0, 0});
    tb__end a = tb__all_a, b = tb__all_b;
    if (tb__clip_cube(&l, &a, &b))
        tb__push_interval(out, o, &l, &a, &b, true, true);
}

/* ------------------------------------------------------------------ pyramid */

void tb__xings_pyramid(const tb_object *o, const tb__oray *r, tb__xbuf *out)
{
    double top = o->geom.pyramid.top;
    bool caps = o->geom.pyramid.caps;
    /* Side facing +x: x <= a + b z through x = 1 at z = -1 and x = top at z = 1. */
    double a0 = 0.5 * (1.0 + top), b0 = 0.5 * (top - 1.0);
    tb__line l = tb__line_near(r, (tb_dvec3){0, 0, 0});
    tb__end a = tb__all_a, b = tb__all_b;
    bool in = tb__clip(&l, (tb_dvec3){-1, 0, -b0}, a0, TB_FACE_PYRAMID_NEG_X, &a, &b) &&
              tb__clip(&l, (tb_dvec3){1, 0, -b0}, a0, TB_FACE_PYRAMID_POS_X, &a, &b) &&
              tb__clip(&l, (tb_dvec3){0, -1, -b0}, a0, TB_FACE_PYRAMID_NEG_Y, &a, &b) &&
              tb__clip(&l, (tb_dvec3){0, 1, -b0}, a0, TB_FACE_PYRAMID_POS_Y, &a, &b) &&
              tb__clip(&l, (tb_dvec3){0, 0, -1}, 1.0, TB_FACE_PYRAMID_BOTTOM, &a, &b) &&
              /* z <= 1 only bounds a frustum; the sides alone close a pointed pyramid. */
              (top == 0.0 || tb__clip(&l, (tb_dvec3){0, 0, 1}, 1.0, TB_FACE_PYRAMID_TOP, &a, &b));
    if (!in)
        return;
    bool keep_a = caps || (a.face != TB_FACE_PYRAMID_BOTTOM && a.face != TB_FACE_PYRAMID_TOP);
    bool keep_b = caps || (b.face != TB_FACE_PYRAMID_BOTTOM && b.face != TB_FACE_PYRAMID_TOP);
    tb__push_interval(out, o, &l, &a, &b, keep_a, keep_b);
}

/* ------------------------------------------------------------------ prism */

void tb__prism_vertex(int n, int k, double *x, double *y)
{
    /* Quarter turns exactly (so the vertices on the axes of n = 4, 8, ...
     * are exact), the rest from the angle 2 pi k / n. */
    double a = TB_2PI * ((double)k / (double)n);
    *x = cos(a);
    *y = sin(a);
    if (4 * k % n == 0) { /* a multiple of 90 degrees */
        static const double cx[4] = {1, 0, -1, 0}, cy[4] = {0, 1, 0, -1};
        int q = 4 * k / n % 4;
        *x = cx[q];
        *y = cy[q];
    }
}

/* Outward normal (x, y, 0) and plane constant of side k (edge P_k -> P_k+1). */
static void tb__prism_side(const tb_object *o, const double *pk, const double *pk1, tb_dvec3 *n, double *c)
{
    double ex = pk1[0] - pk[0], ey = pk1[1] - pk[1];
    *n = (tb_dvec3){o->profile_orient * ey, -o->profile_orient * ex, 0.0};
    *c = n->x * pk[0] + n->y * pk[1];
}

/* Sides k0 - 2 .. k0 + 2 of the large regular prism. Side k lies on the
 * line through vertices k and k + 1, at distance cos(pi/n) from the axis
 * with outward normal at the mid angle 2 pi (k + 1/2) / n; the five normals
 * come from one sine and cosine by rotation (error a few ulps). */
static bool tb__clip_regular_sides(const tb_object *o, const tb__line *l, int k0, tb__end *a, tb__end *b)
{
    int n = o->geom.prism.sides;
    double step = TB_2PI / n, c = cos(TB_PI / n), cd = cos(step), sd = sin(step);
    int k = ((k0 - 2) % n + n) % n;
    double ang = step * (k + 0.5), nx = cos(ang), ny = sin(ang);
    for (int j = 0; j < 5; j++) {
        if (!tb__clip(l, (tb_dvec3){nx, ny, 0.0}, c, TB_FACE_PRISM_SIDE0 + (uint32_t)k, a, b))
            return false;
        double rx = nx * cd - ny * sd, ry = ny * cd + nx * sd;
        nx = rx;
        ny = ry;
        k = k + 1 == n ? 0 : k + 1;
    }
    return true;
}

/* Sector (0 .. n-1) of the direction (x, y) for the regular n-gon. */
static int tb__sector(int n, double x, double y)
{
    double ang = atan2(y, x);
    if (ang < 0.0)
        ang += TB_2PI;
    int k = (int)floor(ang / TB_2PI * n);
    return k < 0 ? 0 : (k >= n ? n - 1 : k);
}

/* A regular prism with many sides: only the sides next to where the line
 * crosses the circumscribed circle can bound it. Between the circle and the
 * polygon lie n circular segments, each cut off by one side and touching its
 * neighbours only at vertices; a line entering the circle at angle phi stays
 * in the segment of phi until it meets that segment's side (or leaves the
 * circle), so the entry side is the one of phi's sector, and likewise for the
 * exit. Two sectors on either side are also tested, for rounding. */
static bool tb__clip_regular(const tb_object *o, const tb__line *l, tb__end *a, tb__end *b)
{
    int n = o->geom.prism.sides;
    double A = l->d.x * l->d.x + l->d.y * l->d.y;
    if (A == 0.0) { /* parallel to the axis: is the point inside the polygon? */
        return tb__clip_regular_sides(o, l, tb__sector(n, l->p0.x, l->p0.y), a, b);
    }
    /* Circle crossings of the 2D line, from its point nearest the axis
     * (p0 is the 3D line's point nearest the origin, not the same point). */
    double s2 = -(l->p0.x * l->d.x + l->p0.y * l->d.y) / A;
    double qx = l->p0.x + s2 * l->d.x, qy = l->p0.y + s2 * l->d.y;
    double h2 = 1.0 - (qx * qx + qy * qy);
    if (h2 < 0.0)
        return false;
    double h = sqrt(h2 / A);
    int kin = tb__sector(n, qx - h * l->d.x, qy - h * l->d.y);
    int kout = tb__sector(n, qx + h * l->d.x, qy + h * l->d.y);
    return tb__clip_regular_sides(o, l, kin, a, b) && tb__clip_regular_sides(o, l, kout, a, b);
}

/* Side of vertex (px, py) relative to the 2D line q + s d: true if left or on. */
static bool tb__left(double qx, double qy, double dx, double dy, double px, double py)
{
    return dx * (py - qy) - dy * (px - qx) >= 0.0;
}

/* Crossings of the 2D line p0 + s d with a simple (possibly non-convex)
 * profile, as sorted (s, edge) pairs; returns their count (even). */
typedef struct tb__pcross {
    double s;
    int edge;
} tb__pcross;

static int tb__pcross_cmp(const void *a, const void *b)
{
    double x = ((const tb__pcross *)a)->s, y = ((const tb__pcross *)b)->s;
    return (x > y) - (x < y);
}

static void tb__xings_profile(const tb_object *o, const tb__line *l, tb__xbuf *out, bool caps)
{
    const double *P = o->profile;
    int n = o->nprofile;
    double dx = l->d.x, dy = l->d.y;
    /* The z slab. */
    tb__end za = tb__all_a, zb = tb__all_b;
    if (!tb__clip(l, (tb_dvec3){0, 0, -1}, 1.0, TB_FACE_PRISM_BOTTOM, &za, &zb) ||
        !tb__clip(l, (tb_dvec3){0, 0, 1}, 1.0, TB_FACE_PRISM_TOP, &za, &zb))
        return;
    if (dx == 0.0 && dy == 0.0) {
        /* Parallel to the axis: crossing number of a ray from p0 along +x. */
        bool in = false;
        bool sp = tb__left(l->p0.x, l->p0.y, 1.0, 0.0, P[0], P[1]);
        for (int k = 0; k < n; k++) {
            const double *q = &P[2 * ((k + 1) % n)];
            bool sq = tb__left(l->p0.x, l->p0.y, 1.0, 0.0, q[0], q[1]);
            if (sp != sq) {
                const double *p = &P[2 * k];
                double x = p[0] + (l->p0.y - p[1]) * (q[0] - p[0]) / (q[1] - p[1]);
                if (x >= l->p0.x)
                    in = !in;
            }
            sp = sq;
        }
        if (in)
            tb__push_interval(out, o, l, &za, &zb, caps, caps);
        return;
    }
    tb__pcross local[16], *cr = local;
    if (n > 16 && !(cr = malloc(sizeof(tb__pcross) * (size_t)n))) {
        out->oom = true;
        return;
    }
    int nc = 0;
    bool sp = tb__left(l->p0.x, l->p0.y, dx, dy, P[0], P[1]);
    for (int k = 0; k < n; k++) {
        const double *p = &P[2 * k], *q = &P[2 * ((k + 1) % n)];
        bool sq = tb__left(l->p0.x, l->p0.y, dx, dy, q[0], q[1]);
        if (sp != sq) {
            double ex = q[0] - p[0], ey = q[1] - p[1];
            double den = dx * ey - dy * ex;
            double s = ((p[0] - l->p0.x) * ey - (p[1] - l->p0.y) * ex) / den;
            if (!isfinite(s))
                s = ((p[0] + q[0]) * 0.5 - l->p0.x) * dx / (dx * dx + dy * dy) +
                    ((p[1] + q[1]) * 0.5 - l->p0.y) * dy / (dx * dx + dy * dy);
            cr[nc++] = (tb__pcross){s, k};
        }
        sp = sq;
    }
    qsort(cr, (size_t)nc, sizeof *cr, tb__pcross_cmp);
    for (int i = 0; i + 1 < nc; i += 2) {
        tb__end a, b;
        for (int j = 0; j < 2; j++) {
            int k = cr[i + j].edge;
            tb_dvec3 nn;
            double c;
            tb__prism_side(o, &P[2 * k], &P[2 * ((k + 1) % n)], &nn, &c);
            tb__end e = {cr[i + j].s, TB_FACE_PRISM_SIDE0 + (uint32_t)k, nn};
            if (j == 0)
                a = e;
            else
                b = e;
        }
        if (za.t > a.t)
            a = za;
        if (zb.t < b.t)
            b = zb;
        bool keep_a = caps || a.face >= TB_FACE_PRISM_SIDE0, keep_b = caps || b.face >= TB_FACE_PRISM_SIDE0;
        tb__push_interval(out, o, l, &a, &b, keep_a, keep_b);
    }
    if (cr != local)
        free(cr);
}

void tb__xings_prism(const tb_object *o, const tb__oray *r, tb__xbuf *out)
{
    bool caps = o->geom.prism.caps;
    tb__line l = tb__line_near(r, (tb_dvec3){0, 0, 0});
    if (!o->profile_convex) {
        tb__xings_profile(o, &l, out, caps);
        return;
    }
    tb__end a = tb__all_a, b = tb__all_b;
    if (!tb__clip(&l, (tb_dvec3){0, 0, -1}, 1.0, TB_FACE_PRISM_BOTTOM, &a, &b) ||
        !tb__clip(&l, (tb_dvec3){0, 0, 1}, 1.0, TB_FACE_PRISM_TOP, &a, &b))
        return;
    if (o->nprofile == 0) {
        if (!tb__clip_regular(o, &l, &a, &b))
            return;
    } else {
        int n = o->nprofile;
        for (int k = 0; k < n; k++) {
            tb_dvec3 nn;
            double c;
            tb__prism_side(o, &o->profile[2 * k], &o->profile[2 * ((k + 1) % n)], &nn, &c);
            if (!tb__clip(&l, nn, c, TB_FACE_PRISM_SIDE0 + (uint32_t)k, &a, &b))
                return;
        }
    }
    bool keep_a = caps || a.face >= TB_FACE_PRISM_SIDE0, keep_b = caps || b.face >= TB_FACE_PRISM_SIDE0;
    tb__push_interval(out, o, &l, &a, &b, keep_a, keep_b);
}

/* ------------------------------------------------------------------ arches */

/* Interval of the line inside the arch's opening (a convex region, unbounded
 * in y and downward in z); false if the line misses it. The ends carry the
 * opening's faces with the opening's outward normals (the caller negates them:
 * the solid's outward normal there points into the opening). */
static bool tb__arch_opening(const tb_object *o, const tb__line *l, tb__end *a, tb__end *b)
{
    double hw = 0.5 * o->geom.arch.width, h = o->geom.arch.height;
    *a = tb__all_a;
    *b = tb__all_b;
    /* The walls |x| <= w/2: the left wall (x = -w/2) bounds the opening's -x side. */
    if (!tb__clip(l, (tb_dvec3){-1, 0, 0}, hw, TB_FACE_ARCH_INNER_LEFT, a, b) ||
        !tb__clip(l, (tb_dvec3){1, 0, 0}, hw, TB_FACE_ARCH_INNER_RIGHT, a, b))
        return false;
    if (o->kind == TB_PRIM_SQUARE_ARCH)
        return tb__clip(l, (tb_dvec3){0, 0, 1}, -1.0 + h, TB_FACE_ARCH_CEILING, a, b) && a->t <= b->t;

    /* Round arch: within the walls, below zs or inside the vault's circle
     * x^2 + (z - zs)^2 <= (w/2)^2. The two pieces overlap (the region is
     * convex), so the opening is their hull. */
    double zs = -1.0 + h - hw;
    tb__end ha = *a, hb = *b; /* walls and z <= zs */
    bool hin = tb__clip(l, (tb_dvec3){0, 0, 1}, zs, TB_FACE_ARCH_CEILING, &ha, &hb) && ha.t <= hb.t;
    tb__end ca = *a, cb = *b; /* walls and circle */
    bool cin = false;
    double A = l->d.x * l->d.x + l->d.z * l->d.z;
    double px = l->p0.x, pz = l->p0.z - zs;
    if (A == 0.0) {
        cin = px * px + pz * pz <= hw * hw && ca.t <= cb.t;
    } else {
        /* Nearest point of the 2D line to the vault's axis, for accuracy. */
        double s2 = -(px * l->d.x + pz * l->d.z) / A;
        double qx = px + s2 * l->d.x, qz = pz + s2 * l->d.z;
        double root[2];
        int nr = tb_quadratic(A, 2.0 * (qx * l->d.x + qz * l->d.z), qx * qx + qz * qz - hw * hw, root);
        if (nr > 0) {
            if (nr == 1)
                root[1] = root[0];
            double c0 = s2 + root[0], c1 = s2 + root[1];
            if (c0 > ca.t)
                ca = (tb__end){c0, TB_FACE_ARCH_CEILING, {px + c0 * l->d.x, 0.0, pz + c0 * l->d.z}};
            if (c1 < cb.t)
                cb = (tb__end){c1, TB_FACE_ARCH_CEILING, {px + c1 * l->d.x, 0.0, pz + c1 * l->d.z}};
            cin = ca.t <= cb.t;
        }
    }
    /* The plane z = zs lies inside the opening, never on its boundary: an end
     * that lands there by rounding is where the vault meets a wall, and takes
     * the vault's (horizontal) normal. */
    if (hin && ha.face == TB_FACE_ARCH_CEILING)
        ha.n = (tb_dvec3){px + ha.t * l->d.x, 0.0, 0.0};
    if (hin && hb.face == TB_FACE_ARCH_CEILING)
        hb.n = (tb_dvec3){px + hb.t * l->d.x, 0.0, 0.0};
    if (!hin && !cin)
        return false;
    if (hin && cin) {
        *a = ha.t <= ca.t ? ha : ca;
        *b = hb.t >= cb.t ? hb : cb;
    } else if (hin) {
        *a = ha;
        *b = hb;
    } else {
        *a = ca;
        *b = cb;
    }
    for (int i = 0; i < 2; i++) { /* only a point on the vault's axis could give a zero normal */
        tb__end *e = i ? b : a;
        if (e->n.x == 0.0 && e->n.y == 0.0 && e->n.z == 0.0)
            e->n = (tb_dvec3){0, 0, 1};
    }
    return true;
}

void tb__xings_arch(const tb_object *o, const tb__oray *r, tb__xbuf *out)
{
    tb__line l = tb__line_near(r, (tb_dvec3){0, 0, 0});
    tb__end a = tb__all_a, b = tb__all_b;
    /* The block: arch faces 0..5 are numbered as the cube's. */
    if (!tb__clip_cube(&l, &a, &b) || !(a.t <= b.t))
        return;
    tb__end sa, sb;
    if (!tb__arch_opening(o, &l, &sa, &sb)) {
        tb__push_interval(out, o, &l, &a, &b, true, true);
        return;
    }
    sa.n = tb_dvec3_neg(sa.n);
    sb.n = tb_dvec3_neg(sb.n);
    /* Block [a, b] minus opening (sa, sb): the pieces [a, min(b, sa)] and
     * [max(a, sb), b]; a piece of zero length (the line touching the rim of
     * the opening) is dropped. */
    if (sa.t > a.t)
        tb__push_interval(out, o, &l, &a, sa.t < b.t ? &sa : &b, true, true);
    if (sb.t < b.t)
        tb__push_interval(out, o, &l, sb.t > a.t ? &sb : &a, &b, true, true);
}
