/* Small fixed-size vectors: float tb_vec2/3/4 for geometry and rays (the data
 * the kernels see), double tb_dvec3 for transforms and root finding, where
 * float would lose the digits the result needs (docs/math.md, "precision").
 * Everything here is a plain struct passed by value and a static inline
 * function: the compiler keeps them in registers. Operations are written out
 * in a fixed order and the build has -ffp-contract=off, so a result is the
 * same on every compiler (no silent FMA). */
#ifndef TB_UTIL_MATH_VEC_H
#define TB_UTIL_MATH_VEC_H

#include <math.h>
#include <stdbool.h>

/* Two floats (texture coordinates, pixel positions). */
typedef struct tb_vec2 {
    float x, y;
} tb_vec2;

/* Three floats: a point, a direction or a normal (the type says which by use). */
typedef struct tb_vec3 {
    float x, y, z;
} tb_vec3;

/* Four floats (homogeneous points, RGBA). */
typedef struct tb_vec4 {
    float x, y, z, w;
} tb_vec4;

/* Three doubles: transform and solver arithmetic. */
typedef struct tb_dvec3 {
    double x, y, z;
} tb_dvec3;

/* ------------------------------------------------------------------ tb_vec2 */

/* (x, y). */
static inline tb_vec2 tb_vec2_make(float x, float y) { return (tb_vec2){x, y}; }
/* a + b. */
static inline tb_vec2 tb_vec2_add(tb_vec2 a, tb_vec2 b) { return (tb_vec2){a.x + b.x, a.y + b.y}; }
/* a - b. */
static inline tb_vec2 tb_vec2_sub(tb_vec2 a, tb_vec2 b) { return (tb_vec2){a.x - b.x, a.y - b.y}; }
/* Component-wise a * b. */
static inline tb_vec2 tb_vec2_mul(tb_vec2 a, tb_vec2 b) { return (tb_vec2){a.x * b.x, a.y * b.y}; }
/* a * s. */
static inline tb_vec2 tb_vec2_scale(tb_vec2 a, float s) { return (tb_vec2){a.x * s, a.y * s}; }
/* a . b. */
static inline float tb_vec2_dot(tb_vec2 a, tb_vec2 b) { return a.x * b.x + a.y * b.y; }
/* |a|. */
static inline float tb_vec2_length(tb_vec2 a) { return sqrtf(tb_vec2_dot(a, a)); }
/* a + t (b - a). */
static inline tb_vec2 tb_vec2_lerp(tb_vec2 a, tb_vec2 b, float t)
{
    return (tb_vec2){a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)};
}

/* ------------------------------------------------------------------ tb_vec3 */

/* (x, y, z). */
static inline tb_vec3 tb_vec3_make(float x, float y, float z) { return (tb_vec3){x, y, z}; }
/* (s, s, s). */
static inline tb_vec3 tb_vec3_splat(float s) { return (tb_vec3){s, s, s}; }
/* a + b. */
static inline tb_vec3 tb_vec3_add(tb_vec3 a, tb_vec3 b)
{
    return (tb_vec3){a.x + b.x, a.y + b.y, a.z + b.z};
}
/* a - b. */
static inline tb_vec3 tb_vec3_sub(tb_vec3 a, tb_vec3 b)
{
    return (tb_vec3){a.x - b.x, a.y - b.y, a.z - b.z};
}
/* Component-wise a * b. */
static inline tb_vec3 tb_vec3_mul(tb_vec3 a, tb_vec3 b)
{
    return (tb_vec3){a.x * b.x, a.y * b.y, a.z * b.z};
}
/* Component-wise a / b (IEEE: x/0 is +-inf). */
static inline tb_vec3 tb_vec3_div(tb_vec3 a, tb_vec3 b)
{
    return (tb_vec3){a.x / b.x, a.y / b.y, a.z / b.z};
}
/* a * s. */
static inline tb_vec3 tb_vec3_scale(tb_vec3 a, float s)
{
    return (tb_vec3){a.x * s, a.y * s, a.z * s};
}
/* -a. */
static inline tb_vec3 tb_vec3_neg(tb_vec3 a) { return (tb_vec3){-a.x, -a.y, -a.z}; }
/* a . b, summed x, y, z in that order. */
static inline float tb_vec3_dot(tb_vec3 a, tb_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
/* |a . b|. */
static inline float tb_vec3_absdot(tb_vec3 a, tb_vec3 b) { return fabsf(tb_vec3_dot(a, b)); }
/* a x b (right-handed: x cross y = z). */
static inline tb_vec3 tb_vec3_cross(tb_vec3 a, tb_vec3 b)
{
    /* Products in double: each float product is exact there, so the only
     * errors are the double subtraction and the final rounding to float; the
     * result is within ~0.5 ulp even where the float formula cancels badly
     * (pbrt-v4 gets the same effect with difference-of-products). */
    double ax = a.x, ay = a.y, az = a.z, bx = b.x, by = b.y, bz = b.z;
    return (tb_vec3){(float)(ay * bz - az * by), (float)(az * bx - ax * bz),
                     (float)(ax * by - ay * bx)};
}
/* |a|^2. */
static inline float tb_vec3_length2(tb_vec3 a) { return tb_vec3_dot(a, a); }
/* |a|. */
static inline float tb_vec3_length(tb_vec3 a) { return sqrtf(tb_vec3_dot(a, a)); }
/* a / |a|; a must be non-zero (a zero vector gives NaN components). */
static inline tb_vec3 tb_vec3_normalize(tb_vec3 a) { return tb_vec3_scale(a, 1.0f / tb_vec3_length(a)); }
/* |a - b|. */
static inline float tb_vec3_distance(tb_vec3 a, tb_vec3 b) { return tb_vec3_length(tb_vec3_sub(a, b)); }
/* Component-wise minimum (fminf: a NaN component loses to a number). */
static inline tb_vec3 tb_vec3_min(tb_vec3 a, tb_vec3 b)
{
    return (tb_vec3){fminf(a.x, b.x), fminf(a.y, b.y), fminf(a.z, b.z)};
}
/* Component-wise maximum (fmaxf: a NaN component loses to a number). */
static inline tb_vec3 tb_vec3_max(tb_vec3 a, tb_vec3 b)
{
    return (tb_vec3){fmaxf(a.x, b.x), fmaxf(a.y, b.y), fmaxf(a.z, b.z)};
}
/* Component-wise |a|. */
static inline tb_vec3 tb_vec3_abs(tb_vec3 a) { return (tb_vec3){fabsf(a.x), fabsf(a.y), fabsf(a.z)}; }
/* a + t (b - a): exact at t = 0; at t = 1 within one rounding of b. */
static inline tb_vec3 tb_vec3_lerp(tb_vec3 a, tb_vec3 b, float t)
{
    return (tb_vec3){a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), a.z + t * (b.z - a.z)};
}
/* Largest component. */
static inline float tb_vec3_max_comp(tb_vec3 a) { return fmaxf(a.x, fmaxf(a.y, a.z)); }
/* Smallest component. */
static inline float tb_vec3_min_comp(tb_vec3 a) { return fminf(a.x, fminf(a.y, a.z)); }
/* Index (0, 1, 2) of the largest component; the first one on ties. */
static inline int tb_vec3_max_dim(tb_vec3 a)
{
    return (a.x >= a.y) ? (a.x >= a.z ? 0 : 2) : (a.y >= a.z ? 1 : 2);
}
/* Component i (0 = x, 1 = y, 2 = z). */
static inline float tb_vec3_get(tb_vec3 a, int i) { return i == 0 ? a.x : (i == 1 ? a.y : a.z); }
/* (a[i], a[j], a[k]): reorders axes (watertight triangle test, slab tests). */
static inline tb_vec3 tb_vec3_permute(tb_vec3 a, int i, int j, int k)
{
    return (tb_vec3){tb_vec3_get(a, i), tb_vec3_get(a, j), tb_vec3_get(a, k)};
}
/* Exact equality of all three components (-0 == +0, NaN != NaN). */
static inline bool tb_vec3_equal(tb_vec3 a, tb_vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

/* Duff, Burgess, Christensen, Hery, Kensler, Liani, Villemin 2017, "Building an
 * orthonormal basis, revisited" (JCGT 6(1)): for a unit vector n, sets b1, b2
 * so that (b1, b2, n) is a right-handed orthonormal frame. Branch-free apart
 * from copysign, and continuous everywhere except across the plane z = 0. */
static inline void tb_vec3_basis(tb_vec3 n, tb_vec3 *b1, tb_vec3 *b2)
{
    float sign = copysignf(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float b = n.x * n.y * a;
    *b1 = (tb_vec3){1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x};
    *b2 = (tb_vec3){b, sign + n.y * n.y * a, -n.y};
}

/* ------------------------------------------------------------------ tb_vec4 */

/* (x, y, z, w). */
static inline tb_vec4 tb_vec4_make(float x, float y, float z, float w) { return (tb_vec4){x, y, z, w}; }
/* (v.x, v.y, v.z, w). */
static inline tb_vec4 tb_vec4_from3(tb_vec3 v, float w) { return (tb_vec4){v.x, v.y, v.z, w}; }
/* (v.x, v.y, v.z), dropping w (no divide). */
static inline tb_vec3 tb_vec4_xyz(tb_vec4 v) { return (tb_vec3){v.x, v.y, v.z}; }
/* a + b. */
static inline tb_vec4 tb_vec4_add(tb_vec4 a, tb_vec4 b)
{
    return (tb_vec4){a.x + b.x, a.y + b.y, a.z + b.z, a.w + b.w};
}
/* a - b. */
static inline tb_vec4 tb_vec4_sub(tb_vec4 a, tb_vec4 b)
{
    return (tb_vec4){a.x - b.x, a.y - b.y, a.z - b.z, a.w - b.w};
}
/* Component-wise a * b. */
static inline tb_vec4 tb_vec4_mul(tb_vec4 a, tb_vec4 b)
{
    return (tb_vec4){a.x * b.x, a.y * b.y, a.z * b.z, a.w * b.w};
}
/* a * s. */
static inline tb_vec4 tb_vec4_scale(tb_vec4 a, float s)
{
    return (tb_vec4){a.x * s, a.y * s, a.z * s, a.w * s};
}
/* a . b. */
static inline float tb_vec4_dot(tb_vec4 a, tb_vec4 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z + a.w * b.w;
}
/* a + t (b - a). */
static inline tb_vec4 tb_vec4_lerp(tb_vec4 a, tb_vec4 b, float t)
{
    return (tb_vec4){a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), a.z + t * (b.z - a.z),
                     a.w + t * (b.w - a.w)};
}

/* ----------------------------------------------------------------- tb_dvec3 */

/* (x, y, z). */
static inline tb_dvec3 tb_dvec3_make(double x, double y, double z) { return (tb_dvec3){x, y, z}; }
/* a + b. */
static inline tb_dvec3 tb_dvec3_add(tb_dvec3 a, tb_dvec3 b)
{
    return (tb_dvec3){a.x + b.x, a.y + b.y, a.z + b.z};
}
/* a - b. */
static inline tb_dvec3 tb_dvec3_sub(tb_dvec3 a, tb_dvec3 b)
{
    return (tb_dvec3){a.x - b.x, a.y - b.y, a.z - b.z};
}
/* Component-wise a * b. */
static inline tb_dvec3 tb_dvec3_mul(tb_dvec3 a, tb_dvec3 b)
{
    return (tb_dvec3){a.x * b.x, a.y * b.y, a.z * b.z};
}
/* a * s. */
static inline tb_dvec3 tb_dvec3_scale(tb_dvec3 a, double s)
{
    return (tb_dvec3){a.x * s, a.y * s, a.z * s};
}
/* -a. */
static inline tb_dvec3 tb_dvec3_neg(tb_dvec3 a) { return (tb_dvec3){-a.x, -a.y, -a.z}; }
/* a . b. */
static inline double tb_dvec3_dot(tb_dvec3 a, tb_dvec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
/* a x b (right-handed). */
static inline tb_dvec3 tb_dvec3_cross(tb_dvec3 a, tb_dvec3 b)
{
    return (tb_dvec3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
/* |a|^2. */
static inline double tb_dvec3_length2(tb_dvec3 a) { return tb_dvec3_dot(a, a); }
/* |a|. */
static inline double tb_dvec3_length(tb_dvec3 a) { return sqrt(tb_dvec3_dot(a, a)); }
/* a / |a|; a must be non-zero (a zero vector gives NaN components). */
static inline tb_dvec3 tb_dvec3_normalize(tb_dvec3 a) { return tb_dvec3_scale(a, 1.0 / tb_dvec3_length(a)); }
/* Component-wise minimum. */
static inline tb_dvec3 tb_dvec3_min(tb_dvec3 a, tb_dvec3 b)
{
    return (tb_dvec3){fmin(a.x, b.x), fmin(a.y, b.y), fmin(a.z, b.z)};
}
/* Component-wise maximum. */
static inline tb_dvec3 tb_dvec3_max(tb_dvec3 a, tb_dvec3 b)
{
    return (tb_dvec3){fmax(a.x, b.x), fmax(a.y, b.y), fmax(a.z, b.z)};
}
/* Component-wise |a|. */
static inline tb_dvec3 tb_dvec3_abs(tb_dvec3 a) { return (tb_dvec3){fabs(a.x), fabs(a.y), fabs(a.z)}; }
/* Largest component. */
static inline double tb_dvec3_max_comp(tb_dvec3 a) { return fmax(a.x, fmax(a.y, a.z)); }
/* a + t (b - a). */
static inline tb_dvec3 tb_dvec3_lerp(tb_dvec3 a, tb_dvec3 b, double t)
{
    return (tb_dvec3){a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), a.z + t * (b.z - a.z)};
}
/* Component i (0 = x, 1 = y, 2 = z). */
static inline double tb_dvec3_get(tb_dvec3 a, int i) { return i == 0 ? a.x : (i == 1 ? a.y : a.z); }
/* True if all components are finite. */
static inline bool tb_dvec3_isfinite(tb_dvec3 a) { return isfinite(a.x) && isfinite(a.y) && isfinite(a.z); }

/* tb_vec3_basis in double: (b1, b2, n) right-handed orthonormal for unit n. */
static inline void tb_dvec3_basis(tb_dvec3 n, tb_dvec3 *b1, tb_dvec3 *b2)
{
    double sign = copysign(1.0, n.z);
    double a = -1.0 / (sign + n.z);
    double b = n.x * n.y * a;
    *b1 = (tb_dvec3){1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x};
    *b2 = (tb_dvec3){b, sign + n.y * n.y * a, -n.y};
}

/* ------------------------------------------------------------- conversions */

/* Exact widening float -> double. */
static inline tb_dvec3 tb_vec3_to_d(tb_vec3 a) { return (tb_dvec3){a.x, a.y, a.z}; }
/* Narrowing double -> float, each component rounded to nearest once. */
static inline tb_vec3 tb_dvec3_to_f(tb_dvec3 a) { return (tb_vec3){(float)a.x, (float)a.y, (float)a.z}; }

#endif
