// Ray/cube intersection in object space (the cube [-1,1]^3), host/object's
// method (intersect_planar.c) in float: the line from its point nearest the
// origin clipped by the six half-spaces in face order -x +x -y +y -z +z (the
// first face wins ties); the nearer end in [tmin, tmax]. All arithmetic that
// C rounds twice is `precise`.
#ifndef TB_LIB_CUBE_GLSL
#define TB_LIB_CUBE_GLSL

#include "float.glsl"

// The smallest t in [tmin, tmax] where o + t d meets the cube's surface, and
// its face 0..5 (-x +x -y +y -z +z); false (t = 0, face = 0) if none.
bool tb_cube_hit(vec3 o, vec3 d, float tmin, float tmax, out float t, out uint face)
{
    t = 0.0;
    face = 0u;
    precise float dd = dot(d, d);
    precise float t0 = -dot(o, d) / dd;
    precise vec3 p0 = vec3(o.x + t0 * d.x, o.y + t0 * d.y, o.z + t0 * d.z);
    float a = -tb_inf(), b = tb_inf();
    uint fa = 0u, fb = 0u;
    for (uint f = 0u; f < 6u; ++f) {
        uint axis = f >> 1;
        float sg = (f & 1u) != 0u ? 1.0 : -1.0;
        float den = sg * d[axis];
        precise float num = 1.0 - sg * p0[axis];
        if (den == 0.0) {
            if (num < 0.0)
                return false;
            continue;
        }
        float sv = num / den;
        if (den < 0.0) {
            if (sv > a) {
                a = sv;
                fa = f;
            }
        } else if (sv < b) {
            b = sv;
            fb = f;
        }
    }
    if (!(a <= b) || !tb_isfinite(a) || !tb_isfinite(b))
        return false;
    precise float ta = a + t0;
    precise float tb = b + t0;
    if (ta >= tmin && ta <= tmax) {
        t = ta;
        face = fa;
        return true;
    }
    if (tb >= tmin && tb <= tmax) {
        t = tb;
        face = fb;
        return true;
    }
    return false;
}

#endif
