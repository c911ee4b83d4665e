// Crossings of a line with the torus about z (major radius R, minor r) in
// object space, in float. As host/object (intersect_quadric.c) the work is
// in units of the bounding radius S = R + r along the unit direction, from
// the line's point p0 nearest the centre, so every quantity is O(1) whatever
// the torus's size or the ray origin's distance. Unlike C (a closed-form
// quartic solver, then Newton), the roots are isolated and refined by
// bisection, which float arithmetic keeps robust:
//  - the monic quartic f(s) of the scaled line (C's coefficients) has at
//    most three critical points; they split [-L, L] (the chord of the
//    bounding sphere, widened) into pieces where f is monotone. They are the
//    roots of f', found by bisection on the (at most three) pieces where f'
//    is monotone, split at the roots of f'' (a quadratic);
//  - on each piece a sign change of f is a crossing, refined by 30
//    bisection steps on h(s) = (rho - R)^2 + z^2 - r^2 (rho = |p.xy|), which
//    has f's sign and, unlike the expanded quartic, no cancellation for thin
//    tori: f = h ((rho + R)^2 + z^2 - r^2).
// A tangent ray (a double root) is a grazing case: it may be found or not
// (docs/gpu.md gives the tolerance).
#ifndef TB_LIB_TORUS_GLSL
#define TB_LIB_TORUS_GLSL

#include "planar.glsl"

// h at the scaled point p: negative inside the tube.
float tb_torus_h(vec3 p, float R, float r)
{
    precise float rho = sqrt(p.x * p.x + p.y * p.y);
    precise float q = rho - R;
    precise float h = q * q + p.z * p.z - r * r;
    return h;
}

// f'(s) = 4 s^3 + 3 c3 s^2 + 2 c2 s + c1 (Horner).
float tb_torus_df(vec4 c, float s)
{
    precise float v = ((4.0 * s + 3.0 * c.w) * s + 2.0 * c.z) * s + c.y;
    return v;
}

// The root of f' in [u, v] where f'(u), f'(v) differ in sign (bisection).
float tb_torus_crit(vec4 c, float u, float v)
{
    bool neg_u = tb_torus_df(c, u) < 0.0;
    for (int i = 0; i < 30; ++i) {
        float m = 0.5 * (u + v);
        if ((tb_torus_df(c, m) < 0.0) == neg_u)
            u = m;
        else
            v = m;
    }
    return 0.5 * (u + v);
}

// The crossings of o + t d (object space) with the torus (R, r): up to two
// intervals, face 0, appended to x in order of t.
void tb_xings_torus(vec3 o, vec3 d, float Rw, float rw, inout tb_xl x)
{
    precise float S = Rw + rw;
    precise float R = Rw / S;
    precise float r = rw / S;
    precise float len = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    precise vec3 D = d / len;
    precise vec3 os = o / S;
    precise float s0 = -(os.x * D.x + os.y * D.y + os.z * D.z);
    precise vec3 p0 = vec3(os.x + s0 * D.x, os.y + s0 * D.y, os.z + s0 * D.z);
    precise float pp = p0.x * p0.x + p0.y * p0.y + p0.z * p0.z;
    if (!(pp <= 1.0 + 1.0 / 65536.0))
        return; // misses the bounding sphere
    // Monic quartic coefficients (c0, c1, c2, c3), as C.
    precise float g = p0.x * D.x + p0.y * D.y + p0.z * D.z;
    precise float e = pp + R * R - r * r;
    precise float dxy = D.x * D.x + D.y * D.y;
    precise float c3 = 4.0 * g;
    precise float c2 = 4.0 * g * g + 2.0 * e - 4.0 * R * R * dxy;
    precise float c1 = 4.0 * g * e - 8.0 * R * R * (p0.x * D.x + p0.y * D.y);
    vec4 c = vec4(0.0, c1, c2, c3);
    // Beyond the bounding sphere's chord h > 0: the ends are outside.
    precise float L = sqrt(max(1.0 - pp, 0.0)) + 1.0 / 1024.0;
    // Pieces where f' is monotone: split at the roots of f'' = 12 s^2 + 6 c3 s + 2 c2.
    float q0, q1;
    int nq = tb_quadratic(12.0, 6.0 * c3, 2.0 * c2, q0, q1);
    float br[4];
    int nb = 0;
    br[nb++] = -L;
    if (nq > 0 && q0 > -L && q0 < L)
        br[nb++] = q0;
    if (nq > 1 && q1 > -L && q1 < L && q1 > br[nb - 1])
        br[nb++] = q1;
    br[nb++] = L;
    // Critical points of f: f' changes sign on a piece.
    float cut[5];
    int nc = 0;
    cut[nc++] = -L;
    for (int i = 0; i + 1 < nb; ++i) {
        float u = br[i], v = br[i + 1];
        if ((tb_torus_df(c, u) < 0.0) != (tb_torus_df(c, v) < 0.0))
            cut[nc++] = tb_torus_crit(c, u, v);
    }
    cut[nc++] = L;
    // One crossing at most on each monotone piece: a sign change of h.
    float root[4];
    int nr = 0;
    bool in_u = tb_torus_h(p0 + cut[0] * D, R, r) < 0.0;
    for (int i = 0; i + 1 < nc; ++i) {
        float u = cut[i], v = cut[i + 1];
        bool in_v = tb_torus_h(p0 + v * D, R, r) < 0.0;
        if (in_u != in_v && nr < 4) {
            float a = u, b = v;
            for (int k = 0; k < 30; ++k) {
                float m = 0.5 * (a + b);
                if ((tb_torus_h(p0 + m * D, R, r) < 0.0) == in_u)
                    a = m;
                else
                    b = m;
            }
            root[nr++] = 0.5 * (a + b);
        }
        in_u = in_v;
    }
    // Pairs of roots are the intervals inside (h > 0 at both ends of [-L, L]).
    precise float k = S / len;
    for (int i = 0; i + 1 < nr && x.n <= 2; i += 2) {
        precise float ta = (s0 + root[i]) * k;
        precise float tb = (s0 + root[i + 1]) * k;
        x.t[x.n] = ta;
        x.f[x.n++] = 0u;
        x.t[x.n] = tb;
        x.f[x.n++] = 0u;
    }
}

// Outward normal at the object-space point p (tb__torus_grad, not unit length).
vec3 tb_torus_normal(vec3 p, float R)
{
    float rho = sqrt(p.x * p.x + p.y * p.y);
    vec3 c = rho > 0.0 ? vec3(R * p.x / rho, R * p.y / rho, 0.0) : vec3(R, 0.0, 0.0);
    vec3 n = p - c;
    return n == vec3(0.0) ? vec3(0.0, 0.0, 1.0) : n;
}

#endif
