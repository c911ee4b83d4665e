// Ray/sphere intersection in object space (the sphere |p| = radius centred at
// the origin), by the method of host/object's sphere (intersect_quadric.c)
// in float instead of double:
//   t0 = -(o.d) / (d.d), p0 = o + t0 d    the point of the line nearest the centre,
//   (d.d) s^2 + 2 (p0.d) s + (p0.p0 - radius^2) = 0,   t = t0 + s.
// Solving from p0 rather than o keeps the constant term small for spheres far
// from the ray origin (|o|^2 - r^2 would lose every digit of r^2 in float:
// Haines et al., "Precision Improvements for Ray/Sphere Intersection", Ray
// Tracing Gems, 2019), and p0.d ~ 0 makes the discriminant free of
// cancellation, so an unfused fma() costs nothing here. All arithmetic is
// `precise` (no fused multiply-adds, as the C build). Tolerance against the
// double CPU path and against a float C twin: docs/gpu.md.
#ifndef TB_LIB_SPHERE_GLSL
#define TB_LIB_SPHERE_GLSL

#include "quadratic.glsl"
#include "xings.glsl"

// The crossings of the whole line o + t d with the sphere (one interval,
// face 0), appended to x.
void tb_xings_sphere(vec3 o, vec3 d, float radius, inout tb_xl x)
{
    precise float dd = d.x * d.x + d.y * d.y + d.z * d.z;
    precise float od = o.x * d.x + o.y * d.y + o.z * d.z;
    precise float t0 = -od / dd;
    precise vec3 p0 = vec3(o.x + t0 * d.x, o.y + t0 * d.y, o.z + t0 * d.z);
    precise float pd = p0.x * d.x + p0.y * d.y + p0.z * d.z;
    precise float pp = p0.x * p0.x + p0.y * p0.y + p0.z * p0.z;
    precise float b = 2.0 * pd;
    precise float c = pp - radius * radius;
    float s0, s1;
    int n = tb_quadratic(dd, b, c, s0, s1);
    if (n == 0 || x.n > 2)
        return;
    if (n == 1)
        s1 = s0;
    precise float ta = t0 + s0;
    precise float tb = t0 + s1;
    x.t[x.n] = ta;
    x.f[x.n++] = 0u;
    x.t[x.n] = tb;
    x.f[x.n++] = 0u;
}

// The smallest t with tmin <= t <= tmax (closed range) where o + t d lies on
// the sphere; false if there is none. A ray starting inside hits on its way out.
bool tb_sphere_intersect(vec3 o, vec3 d, float radius, float tmin, float tmax, out float t)
{
    tb_xl x;
    x.n = 0;
    tb_xings_sphere(o, d, radius, x);
    uint face;
    return tb_xl_first(x, tmin, tmax, t, face);
}

#endif
