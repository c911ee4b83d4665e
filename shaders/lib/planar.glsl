// Crossings of a line with the primitives bounded by planes (and one
// cylinder): pyramid, prism, square arch and round arch, in object space:
// host/object's method (intersect_planar.c) in float, step for step. The
// line's origin is first moved to its point nearest the origin; convex
// solids are clipped by their half-spaces in face order (the entry is the
// last plane entered, the exit the first left; ties go to the lower face);
// a prism with a non-convex profile pairs the crossings of the profile's
// edges in order of s (a vertex on the line counts as on its left, so it is
// crossed once); an arch is its block minus its opening. Every step C rounds
// is `precise`. Tolerance against the double CPU path: docs/gpu.md.
//
// The includer defines the profile fetch first (its buffers):
//     vec2 tb_prism_vertex(uint base, uint k); // vertex k of the profile at `base`
#ifndef TB_LIB_PLANAR_GLSL
#define TB_LIB_PLANAR_GLSL

#include "quadratic.glsl"
#include "xings.glsl"

vec2 tb_prism_vertex(uint base, uint k);

// Face numbers (host/object/param.h).
const uint TB_PYRAMID_BOTTOM = 4u;
const uint TB_PYRAMID_TOP = 5u;
const uint TB_PRISM_BOTTOM = 0u;
const uint TB_PRISM_TOP = 1u;
const uint TB_PRISM_SIDE0 = 2u;
const uint TB_ARCH_INNER_LEFT = 6u;
const uint TB_ARCH_INNER_RIGHT = 7u;
const uint TB_ARCH_CEILING = 8u;

// Subtypes of a planar shape record (shared/bvh.h TB_GPU_PLANAR_*).
const uint TB_PLANAR_PYRAMID = 0u;
const uint TB_PLANAR_PRISM = 1u;
const uint TB_PLANAR_SQUARE_ARCH = 2u;
const uint TB_PLANAR_ROUND_ARCH = 3u;

// Pyramid (tb__xings_pyramid): the base square [-1,1]^2 at z = -1, the top
// square of half-side `top` at z = 1 (0: a point).
void tb_xings_pyramid(tb_line l, float top, bool caps, inout tb_xl x)
{
    precise float a0 = 0.5 * (1.0 + top);
    precise float b0 = 0.5 * (top - 1.0);
    tb_end a = tb_end_lo(), b = tb_end_hi();
    bool inside = tb_clip(l, vec3(-1.0, 0.0, -b0), a0, 0u, a, b) && tb_clip(l, vec3(1.0, 0.0, -b0), a0, 1u, a, b) &&
              tb_clip(l, vec3(0.0, -1.0, -b0), a0, 2u, a, b) && tb_clip(l, vec3(0.0, 1.0, -b0), a0, 3u, a, b) &&
              tb_clip(l, vec3(0.0, 0.0, -1.0), 1.0, TB_PYRAMID_BOTTOM, a, b) &&
              (top == 0.0 || tb_clip(l, vec3(0.0, 0.0, 1.0), 1.0, TB_PYRAMID_TOP, a, b));
    if (!inside)
        return;
    bool ka = caps || (a.f != TB_PYRAMID_BOTTOM && a.f != TB_PYRAMID_TOP);
    bool kb = caps || (b.f != TB_PYRAMID_BOTTOM && b.f != TB_PYRAMID_TOP);
    tb_xl_interval(x, l, a, b, ka, kb);
}

// Outward normal (x, y) and constant of the prism side from vertex p to q
// (tb__prism_side); `orient` +1 for a counter-clockwise profile, -1 else.
void tb_prism_side(vec2 p, vec2 q, float orient, out vec3 n, out float c)
{
    precise float ex = q.x - p.x;
    precise float ey = q.y - p.y;
    n = vec3(orient * ey, -orient * ex, 0.0);
    precise float cc = n.x * p.x + n.y * p.y;
    c = cc;
}

// The z slab of a prism: false if the line misses it.
bool tb_prism_slab(tb_line l, out tb_end za, out tb_end zb)
{
    za = tb_end_lo();
    zb = tb_end_hi();
    return tb_clip(l, vec3(0.0, 0.0, -1.0), 1.0, TB_PRISM_BOTTOM, za, zb) &&
           tb_clip(l, vec3(0.0, 0.0, 1.0), 1.0, TB_PRISM_TOP, za, zb);
}

// Convex prism (the profile's nv vertices at `base`): the z slab, then every side.
void tb_xings_prism_convex(tb_line l, uint base, uint nv, float orient, bool caps, inout tb_xl x)
{
    tb_end a, b;
    if (!tb_prism_slab(l, a, b))
        return;
    vec2 p = tb_prism_vertex(base, 0u), first = p;
    for (uint k = 0u; k < nv; ++k) {
        vec2 q = k + 1u < nv ? tb_prism_vertex(base, k + 1u) : first;
        vec3 n;
        float c;
        tb_prism_side(p, q, orient, n, c);
        if (!tb_clip(l, n, c, TB_PRISM_SIDE0 + k, a, b))
            return;
        p = q;
    }
    bool ka = caps || a.f >= TB_PRISM_SIDE0, kb = caps || b.f >= TB_PRISM_SIDE0;
    tb_xl_interval(x, l, a, b, ka, kb);
}

// Side of vertex v relative to the 2D line q + s d: true if left or on (tb__left).
bool tb_left(vec2 q, vec2 d, vec2 v)
{
    precise float r = d.x * (v.y - q.y) - d.y * (v.x - q.x);
    return r >= 0.0;
}

// The crossing of the 2D line p0 + s d with profile edge p -> q (tb__xings_profile).
float tb_edge_s(tb_line l, vec2 p, vec2 q)
{
    precise float ex = q.x - p.x;
    precise float ey = q.y - p.y;
    precise float den = l.d.x * ey - l.d.y * ex;
    precise float num = (p.x - l.p0.x) * ey - (p.y - l.p0.y) * ex;
    float s = num / den;
    if (!tb_isfinite(s)) {
        precise float dd = l.d.x * l.d.x + l.d.y * l.d.y;
        precise float sm = ((p.x + q.x) * 0.5 - l.p0.x) * l.d.x / dd + ((p.y + q.y) * 0.5 - l.p0.y) * l.d.y / dd;
        s = sm;
    }
    return s;
}

// The profile crossing that follows (s_prev, e_prev) in (s, edge) order, if
// any: one pass over the nv edges, so walking all crossings in order is
// O(nv) per crossing and needs no storage (profiles of any size).
bool tb_profile_next(tb_line l, uint base, uint nv, float s_prev, uint e_prev, out float s, out uint e)
{
    s = tb_inf();
    e = 0xffffffffu;
    bool found = false;
    vec2 p = tb_prism_vertex(base, 0u), first = p;
    bool sp = tb_left(l.p0.xy, l.d.xy, p);
    for (uint k = 0u; k < nv; ++k) {
        vec2 q = k + 1u < nv ? tb_prism_vertex(base, k + 1u) : first;
        bool sq = tb_left(l.p0.xy, l.d.xy, q);
        if (sp != sq) {
            float sk = tb_edge_s(l, p, q);
            bool after = sk > s_prev || (sk == s_prev && k > e_prev);
            bool before = !found || sk < s || (sk == s && k < e);
            if (after && before) {
                s = sk;
                e = k;
                found = true;
            }
        }
        p = q;
        sp = sq;
    }
    return found;
}

// Parallel to the axis: is p0 inside the profile (crossing number along +x)?
bool tb_profile_inside(tb_line l, uint base, uint nv)
{
    bool inside = false;
    vec2 p = tb_prism_vertex(base, 0u), first = p;
    bool sp = tb_left(l.p0.xy, vec2(1.0, 0.0), p);
    for (uint k = 0u; k < nv; ++k) {
        vec2 q = k + 1u < nv ? tb_prism_vertex(base, k + 1u) : first;
        bool sq = tb_left(l.p0.xy, vec2(1.0, 0.0), q);
        if (sp != sq) {
            precise float xx = p.x + (l.p0.y - p.y) * (q.x - p.x) / (q.y - p.y);
            if (xx >= l.p0.x)
                inside = !inside;
        }
        p = q;
        sp = sq;
    }
    return inside;
}

// The next interval of a non-convex prism after the crossing (sp, ep) (start
// with (-inf, uint max)): the next two profile crossings in order, clipped
// by the z slab [za, zb], in x (emptied first; it stays empty when the
// clipped interval is). False when the crossings have run out. Walking
// them in order needs no storage: profiles of any size.
bool tb_prism_profile_pair(tb_line l, uint base, uint nv, bool caps, tb_end za, tb_end zb, inout float sp,
                           inout uint ep, inout tb_xl x)
{
    x.n = 0;
    float s0, s1;
    uint e0, e1;
    if (!tb_profile_next(l, base, nv, sp, ep, s0, e0) || !tb_profile_next(l, base, nv, s0, e0, s1, e1))
        return false;
    sp = s1;
    ep = e1;
    tb_end a = tb_end(s0, TB_PRISM_SIDE0 + e0), b = tb_end(s1, TB_PRISM_SIDE0 + e1);
    if (za.s > a.s)
        a = za;
    if (zb.s < b.s)
        b = zb;
    tb_xl_interval(x, l, a, b, caps || a.f >= TB_PRISM_SIDE0, caps || b.f >= TB_PRISM_SIDE0);
    return true;
}

// Non-convex prism: the first surface crossing with tmin <= t <= tmax,
// walking the profile's crossings in order and pairing them into intervals,
// each clipped by the z slab (tb__xings_profile). False if none.
bool tb_prism_profile_hit(tb_line l, uint base, uint nv, bool caps, float tmin, float tmax, out float t,
                          out uint face)
{
    t = 0.0;
    face = 0u;
    tb_end za, zb;
    if (!tb_prism_slab(l, za, zb))
        return false;
    tb_xl x;
    x.n = 0;
    if (l.d.x == 0.0 && l.d.y == 0.0) {
        if (tb_profile_inside(l, base, nv))
            tb_xl_interval(x, l, za, zb, caps, caps);
        return tb_xl_first(x, tmin, tmax, t, face);
    }
    // At most nv crossings: nv / 2 intervals.
    float sp = -tb_inf();
    uint ep = 0xffffffffu;
    for (uint i = 0u; i < nv && tb_prism_profile_pair(l, base, nv, caps, za, zb, sp, ep, x); i += 2u) {
        if (tb_xl_first(x, tmin, tmax, t, face))
            return true;
        if (x.n > 0 && x.t[0] > tmax)
            break; // later intervals start later still
    }
    return false;
}

// Interval of the line inside the arch's opening (tb__arch_opening): false if
// it misses it. w: width, h: height of the opening; round: a vault.
bool tb_arch_opening(tb_line l, float w, float h, bool round_arch, out tb_end a, out tb_end b)
{
    precise float hw = 0.5 * w;
    a = tb_end_lo();
    b = tb_end_hi();
    if (!tb_clip(l, vec3(-1.0, 0.0, 0.0), hw, TB_ARCH_INNER_LEFT, a, b) ||
        !tb_clip(l, vec3(1.0, 0.0, 0.0), hw, TB_ARCH_INNER_RIGHT, a, b))
        return false;
    if (!round_arch) {
        precise float zc = -1.0 + h;
        return tb_clip(l, vec3(0.0, 0.0, 1.0), zc, TB_ARCH_CEILING, a, b) && a.s <= b.s;
    }
    precise float zs = -1.0 + h - hw;
    tb_end ha = a, hb = b;
    bool hin = tb_clip(l, vec3(0.0, 0.0, 1.0), zs, TB_ARCH_CEILING, ha, hb) && ha.s <= hb.s;
    tb_end ca = a, cb = b;
    bool cin = false;
    precise float A = l.d.x * l.d.x + l.d.z * l.d.z;
    float px = l.p0.x;
    precise float pz = l.p0.z - zs;
    if (A == 0.0) {
        precise float r2 = px * px + pz * pz;
        cin = r2 <= hw * hw && ca.s <= cb.s;
    } else {
        precise float s2 = -(px * l.d.x + pz * l.d.z) / A;
        precise float qx = px + s2 * l.d.x;
        precise float qz = pz + s2 * l.d.z;
        precise float B = 2.0 * (qx * l.d.x + qz * l.d.z);
        precise float C = qx * qx + qz * qz - hw * hw;
        float r0, r1;
        int nr = tb_quadratic(A, B, C, r0, r1);
        if (nr > 0) {
            if (nr == 1)
                r1 = r0;
            precise float c0 = s2 + r0;
            precise float c1 = s2 + r1;
            if (c0 > ca.s)
                ca = tb_end(c0, TB_ARCH_CEILING);
            if (c1 < cb.s)
                cb = tb_end(c1, TB_ARCH_CEILING);
            cin = ca.s <= cb.s;
        }
    }
    if (!hin && !cin)
        return false;
    if (hin && cin) {
        a = ha.s <= ca.s ? ha : ca;
        b = hb.s >= cb.s ? hb : cb;
    } else if (hin) {
        a = ha;
        b = hb;
    } else {
        a = ca;
        b = cb;
    }
    return true;
}

// Square or round arch (tb__xings_arch): the block [-1,1]^3 minus the opening.
void tb_xings_arch(tb_line l, float w, float h, bool round_arch, inout tb_xl x)
{
    tb_end a = tb_end_lo(), b = tb_end_hi();
    if (!tb_clip_block(l, a, b) || !(a.s <= b.s))
        return;
    tb_end sa, sb;
    if (!tb_arch_opening(l, w, h, round_arch, sa, sb)) {
        tb_xl_interval(x, l, a, b, true, true);
        return;
    }
    if (sa.s > a.s)
        tb_xl_interval(x, l, a, sa.s < b.s ? sa : b, true, true);
    if (sb.s < b.s)
        tb_xl_interval(x, l, sb.s > a.s ? sb : a, b, true, true);
}

// Object-space outward normal of face f of an arch at p (not unit length).
vec3 tb_arch_normal(uint f, vec3 p, float w, float h, bool round_arch)
{
    if (f < 6u) {
        vec3 n = vec3(0.0);
        n[f >> 1] = (f & 1u) != 0u ? 1.0 : -1.0;
        return n;
    }
    if (f == TB_ARCH_INNER_LEFT)
        return vec3(1.0, 0.0, 0.0);
    if (f == TB_ARCH_INNER_RIGHT)
        return vec3(-1.0, 0.0, 0.0);
    if (!round_arch)
        return vec3(0.0, 0.0, -1.0);
    // The vault: towards its axis (x = 0, z = zs); below zs (a rounding end
    // where the vault meets a wall) horizontal, as C.
    float zs = -1.0 + h - 0.5 * w;
    vec3 n = -vec3(p.x, 0.0, max(p.z - zs, 0.0));
    return n == vec3(0.0) ? vec3(0.0, 0.0, -1.0) : n;
}

#endif
