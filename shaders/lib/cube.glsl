// Ray/cube intersection in object space (the cube [-1,1]^3), host/object's
// method (intersect_planar.c) in float: the line from its point nearest the
// origin clipped by the six half-spaces in face order -x +x -y +y -z +z (the
// first face wins ties); the nearer end in [tmin, tmax]. All arithmetic that
// C rounds twice is `precise`.
#ifndef TB_LIB_CUBE_GLSL
#define TB_LIB_CUBE_GLSL

#include "xings.glsl"

// The smallest t in [tmin, tmax] where o + t d meets the cube's surface, and
// its face 0..5 (-x +x -y +y -z +z); false (t = 0, face = 0) if none.
bool tb_cube_hit(vec3 o, vec3 d, float tmin, float tmax, out float t, out uint face)
{
    tb_xl x;
    x.n = 0;
    tb_xings_cube(o, d, x);
    return tb_xl_first(x, tmin, tmax, t, face);
}

#endif
