// Crossing lists of a line with a solid, shared by the placed primitives
// (lib/planar.glsl, lib/revolved.glsl, lib/torus.glsl) and CSG
// (lib/csg.glsl): the line moved to its point nearest the primitive's
// centre, Cyrus-Beck clipping by half-spaces (host/object's tb__clip), and up
// to two intervals of crossings in order of t.
#ifndef TB_LIB_XINGS_GLSL
#define TB_LIB_XINGS_GLSL

#include "float.glsl"

// A face number with this bit is an end that is not surface (an open
// primitive's missing cap): it bounds the interval but is never hit.
const uint TB_XING_OPEN = 0x80000000u;

// Up to four crossings of a line, sorted by t: the ends of at most two
// intervals inside the solid (entries at even positions).
struct tb_xl {
    float t[4];
    uint f[4];
    int n;
};

// The line o + t d moved to its point nearest the origin: p0 + s d, t = s + t0.
struct tb_line {
    vec3 p0, d;
    float t0;
};

tb_line tb_line_near(vec3 o, vec3 d)
{
    tb_line l;
    l.d = d;
    precise float dd = d.x * d.x + d.y * d.y + d.z * d.z;
    precise float od = o.x * d.x + o.y * d.y + o.z * d.z;
    precise float t0 = -od / dd;
    l.t0 = t0;
    precise vec3 p0 = vec3(o.x + t0 * d.x, o.y + t0 * d.y, o.z + t0 * d.z);
    l.p0 = p0;
    return l;
}

// One end of an interval: s on the line and its face.
struct tb_end {
    float s;
    uint f;
};

// Clips [a, b] by the half-space n . p <= c (tb__clip): false when the line
// lies outside; a line parallel to the plane is inside when on it.
bool tb_clip(tb_line l, vec3 n, float c, uint face, inout tb_end a, inout tb_end b)
{
    precise float den = n.x * l.d.x + n.y * l.d.y + n.z * l.d.z;
    precise float num = c - (n.x * l.p0.x + n.y * l.p0.y + n.z * l.p0.z);
    if (den == 0.0)
        return num >= 0.0;
    float s = num / den;
    if (den < 0.0) {
        if (s > a.s)
            a = tb_end(s, face);
    } else if (s < b.s) {
        b = tb_end(s, face);
    }
    return true;
}

tb_end tb_end_lo() { return tb_end(-tb_inf(), 0u); }
tb_end tb_end_hi() { return tb_end(tb_inf(), 0u); }

// Appends [a, b] (t = s + t0) if non-empty and finite; an end whose `keep`
// is false is marked TB_XING_OPEN (tb__push_interval).
void tb_xl_interval(inout tb_xl x, tb_line l, tb_end a, tb_end b, bool keep_a, bool keep_b)
{
    if (!(a.s <= b.s) || !tb_isfinite(a.s) || !tb_isfinite(b.s) || x.n > 2)
        return;
    precise float ta = a.s + l.t0;
    precise float tb = b.s + l.t0;
    x.t[x.n] = ta;
    x.f[x.n++] = a.f | (keep_a ? 0u : TB_XING_OPEN);
    x.t[x.n] = tb;
    x.f[x.n++] = b.f | (keep_b ? 0u : TB_XING_OPEN);
}

// The first surface crossing of x with tmin <= t <= tmax.
bool tb_xl_first(tb_xl x, float tmin, float tmax, out float t, out uint face)
{
    t = 0.0;
    face = 0u;
    for (int i = 0; i < x.n; ++i)
        if ((x.f[i] & TB_XING_OPEN) == 0u && x.t[i] >= tmin && x.t[i] <= tmax) {
            t = x.t[i];
            face = x.f[i];
            return true;
        }
    return false;
}

// The cube [-1,1]^3 clipped on [a, b]; faces -x +x -y +y -z +z = 0..5.
bool tb_clip_block(tb_line l, inout tb_end a, inout tb_end b)
{
    for (uint f = 0u; f < 6u; ++f) {
        vec3 n = vec3(0.0);
        n[f >> 1] = (f & 1u) != 0u ? 1.0 : -1.0;
        if (!tb_clip(l, n, 1.0, f, a, b))
            return false;
    }
    return true;
}

// The cube [-1,1]^3 (tb__xings_cube).
void tb_xings_cube(vec3 o, vec3 d, inout tb_xl x)
{
    tb_line l = tb_line_near(o, d);
    tb_end a = tb_end_lo(), b = tb_end_hi();
    if (tb_clip_block(l, a, b))
        tb_xl_interval(x, l, a, b, true, true);
}

#endif
