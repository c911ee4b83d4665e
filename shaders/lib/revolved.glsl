// Ray against a revolved quadric solid in object space: cylinder, cone and
// conic (host/object's method, intersect_quadric.c tb__xings_revolved, in
// float): the surface x^2 + y^2 = c0 + c1 z + c2 z^2 clipped by the slab
// z0 <= z <= z1, with caps (discs at z0 and z1) or without (an open tube).
// As in C, the line's origin is first moved to its point nearest the
// centre (0, 0, (z0 + z1) / 2), the quadratic is solved by lib/quadratic.glsl
// (Kahan's discriminant), the solid is an interval (or two, for a cone's
// double nappe) clipped by the slab, and an end on a closed end of the slab
// (radius 0 there: a cone's apex) belongs to the side. Every step that C
// rounds is `precise` here. Tolerance against the double CPU path:
// docs/gpu.md (the table of "The GLSL library").
#ifndef TB_LIB_REVOLVED_GLSL
#define TB_LIB_REVOLVED_GLSL

#include "quadratic.glsl"
#include "xings.glsl"

// Face numbers of cylinder, cone and conic (host/object/param.h).
const uint TB_REVOLVED_SIDE = 0u;
const uint TB_REVOLVED_BOTTOM = 1u;
const uint TB_REVOLVED_TOP = 2u;

// The revolved solid: c = (c0, c1, c2), the slab [z0, z1], caps, and which
// ends close in a point (computed on the host in double, as C does).
struct tb_revolved {
    vec3 c;
    float z0, z1;
    bool caps, closed0, closed1;
};

// Outward normal of the side at p (tb__revolved_normal): the axis direction
// at an apex where the gradient vanishes.
vec3 tb_revolved_side_normal(vec3 c, vec3 p, float zmid)
{
    precise float nz = -(0.5 * c.y + c.z * p.z);
    vec3 n = vec3(p.x, p.y, nz);
    if (n.x == 0.0 && n.y == 0.0 && n.z == 0.0)
        n.z = p.z > zmid ? 1.0 : -1.0;
    return n;
}

// The crossings of the whole line o + t d with the solid (up to two
// intervals, in order of t), appended to x: ends on a missing cap (an open
// tube) are marked TB_XING_OPEN.
void tb_xings_revolved(vec3 o, vec3 d, tb_revolved q, inout tb_xl x)
{
    vec3 c = q.c;
    precise float zc = 0.5 * (q.z0 + q.z1);
    precise float dd = d.x * d.x + d.y * d.y + d.z * d.z;
    precise float ocz = o.z - zc;
    precise float od = o.x * d.x + o.y * d.y + ocz * d.z;
    precise float t0 = -od / dd;
    precise vec3 p0 = vec3(o.x + t0 * d.x, o.y + t0 * d.y, o.z + t0 * d.z);
    // Q(p0 + s d) = A s^2 + B s + C; the solid is Q <= 0.
    precise float A = d.x * d.x + d.y * d.y - c.z * d.z * d.z;
    precise float B = 2.0 * (p0.x * d.x + p0.y * d.y) - c.y * d.z - 2.0 * c.z * p0.z * d.z;
    precise float C = p0.x * p0.x + p0.y * p0.y - c.x - c.y * p0.z - c.z * p0.z * p0.z;
    float inf = tb_inf();
    float qa0 = 0.0, qb0 = 0.0, qa1 = 0.0, qb1 = 0.0;
    int nq = 0;
    if (A != 0.0) {
        float r0, r1;
        int nr = tb_quadratic(A, B, C, r0, r1);
        if (nr == 1)
            r1 = r0;
        if (A > 0.0) {
            if (nr > 0) {
                qa0 = r0;
                qb0 = r1;
                nq = 1;
            }
        } else if (nr > 0) {
            qa0 = -inf;
            qb0 = r0;
            qa1 = r1;
            qb1 = inf;
            nq = 2;
        } else if (C <= 0.0) {
            qa0 = -inf;
            qb0 = inf;
            nq = 1;
        }
    } else if (B != 0.0) {
        precise float s = -C / B;
        qa0 = B > 0.0 ? -inf : s;
        qb0 = B > 0.0 ? s : inf;
        nq = tb_isfinite(s) ? 1 : 0;
    } else if (C <= 0.0) {
        qa0 = -inf;
        qb0 = inf;
        nq = 1;
    }
    if (nq == 0)
        return;
    // The slab: its entry (sa) and exit (sb) ends.
    float sat, sbt;
    uint saf, sbf;
    if (d.z == 0.0) {
        if (!(p0.z >= q.z0 && p0.z <= q.z1))
            return;
        sat = -inf;
        saf = TB_REVOLVED_BOTTOM;
        sbt = inf;
        sbf = TB_REVOLVED_TOP;
    } else {
        precise float bt = (q.z0 - p0.z) / d.z;
        precise float tt = (q.z1 - p0.z) / d.z;
        uint bf = q.closed0 ? TB_REVOLVED_SIDE : TB_REVOLVED_BOTTOM;
        uint tf = q.closed1 ? TB_REVOLVED_SIDE : TB_REVOLVED_TOP;
        bool up = d.z > 0.0;
        sat = up ? bt : tt;
        saf = up ? bf : tf;
        sbt = up ? tt : bt;
        sbf = up ? tf : bf;
    }
    for (int i = 0; i < nq; ++i) {
        float qa = i == 0 ? qa0 : qa1, qb = i == 0 ? qb0 : qb1;
        float at = qa >= sat ? qa : sat, btt = qb <= sbt ? qb : sbt;
        uint af = qa >= sat ? TB_REVOLVED_SIDE : saf, bf = qb <= sbt ? TB_REVOLVED_SIDE : sbf;
        if (!(at <= btt) || !tb_isfinite(at) || !tb_isfinite(btt) || x.n > 2)
            continue;
        precise float ta = at + t0;
        precise float tb = btt + t0;
        // Without caps the surface is open: ends on the missing discs are not surface.
        x.t[x.n] = ta;
        x.f[x.n++] = af | (q.caps || af == TB_REVOLVED_SIDE ? 0u : TB_XING_OPEN);
        x.t[x.n] = tb;
        x.f[x.n++] = bf | (q.caps || bf == TB_REVOLVED_SIDE ? 0u : TB_XING_OPEN);
    }
}

// The first crossing with tmin <= t <= tmax of o + t d with the solid's
// surface: t, the face (TB_REVOLVED_*) and the object-space outward normal
// (not unit length). False if none.
bool tb_revolved_hit(vec3 o, vec3 d, tb_revolved q, float tmin, float tmax, out float t, out uint face, out vec3 n)
{
    tb_xl x;
    x.n = 0;
    tb_xings_revolved(o, d, q, x);
    n = vec3(0.0);
    if (!tb_xl_first(x, tmin, tmax, t, face))
        return false;
    n = face == TB_REVOLVED_SIDE ? tb_revolved_side_normal(q.c, o + t * d, 0.5 * (q.z0 + q.z1))
                                 : vec3(0.0, 0.0, face == TB_REVOLVED_TOP ? 1.0 : -1.0);
    return true;
}

#endif
