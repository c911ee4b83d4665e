/* Floating-point helpers for error-bounded geometry: stepping to the next
 * representable value, pbrt's gamma(n) error bound, ulp distance, bit casts,
 * clamps, safe square roots and Kahan's difference of products.
 * All inline; IEEE 754 binary32/binary64 with round-to-nearest is assumed
 * (checked below), which every target we build for provides. */
#ifndef TB_UTIL_MATH_FLOAT_H
#define TB_UTIL_MATH_FLOAT_H

#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "util/math/vec.h"

_Static_assert(sizeof(float) == 4 && FLT_MANT_DIG == 24, "binary32 float expected");
_Static_assert(sizeof(double) == 8 && DBL_MANT_DIG == 53, "binary64 double expected");

/* pi and friends, as double literals; use the F forms in float code. */
#define TB_PI 3.14159265358979323846
#define TB_2PI 6.28318530717958647692
#define TB_PI_2 1.57079632679489661923 /* pi / 2 */
#define TB_PI_4 0.78539816339744830962 /* pi / 4 */
#define TB_INV_PI 0.31830988618379067154
#define TB_INV_2PI 0.15915494309189533577
#define TB_INV_4PI 0.07957747154594766788
#define TB_SQRT2 1.41421356237309504880
#define TB_PIF ((float)TB_PI)
#define TB_INV_PIF ((float)TB_INV_PI)

/* Half the float machine epsilon, 2^-24: the relative error bound of one
 * correctly rounded float operation (pbrt's MachineEpsilon). */
#define TB_FLOAT_UNIT_ROUNDOFF 0x1p-24f
/* Half the double machine epsilon, 2^-53. */
#define TB_DOUBLE_UNIT_ROUNDOFF 0x1p-53

/* Degrees to radians. */
static inline double tb_radians(double deg) { return deg * (TB_PI / 180.0); }
/* Radians to degrees. */
static inline double tb_degrees(double rad) { return rad * (180.0 / TB_PI); }

/* The bits of f. */
static inline uint32_t tb_float_to_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}
/* The float with bits u. */
static inline float tb_bits_to_float(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}
/* The bits of d. */
static inline uint64_t tb_double_to_bits(double d)
{
    uint64_t u;
    memcpy(&u, &d, sizeof u);
    return u;
}
/* The double with bits u. */
static inline double tb_bits_to_double(uint64_t u)
{
    double d;
    memcpy(&d, &u, sizeof d);
    return d;
}

/* Smallest float > v. +inf and NaN are returned unchanged; both zeros step
 * to the smallest positive denormal; -denorm_min steps to -0. */
static inline float tb_next_float_up(float v)
{
    if (isinf(v) && v > 0.0f)
        return v;
    if (isnan(v))
        return v;
    if (v == -0.0f)
        v = 0.0f;
    uint32_t u = tb_float_to_bits(v);
    if (v >= 0.0f)
        ++u;
    else
        --u;
    return tb_bits_to_float(u);
}
/* Largest float < v. -inf and NaN are returned unchanged; both zeros step
 * to the smallest negative denormal; +denorm_min steps to +0. */
static inline float tb_next_float_down(float v)
{
    if (isinf(v) && v < 0.0f)
        return v;
    if (isnan(v))
        return v;
    if (v == 0.0f)
        v = -0.0f;
    uint32_t u = tb_float_to_bits(v);
    if (v > 0.0f)
        --u;
    else
        ++u;
    return tb_bits_to_float(u);
}
/* Smallest double > v (rules as tb_next_float_up). */
static inline double tb_next_double_up(double v)
{
    if ((isinf(v) && v > 0.0) || isnan(v))
        return v;
    if (v == -0.0)
        v = 0.0;
    uint64_t u = tb_double_to_bits(v);
    if (v >= 0.0)
        ++u;
    else
        --u;
    return tb_bits_to_double(u);
}
/* Largest double < v (rules as tb_next_float_down). */
static inline double tb_next_double_down(double v)
{
    if ((isinf(v) && v < 0.0) || isnan(v))
        return v;
    if (v == 0.0)
        v = -0.0;
    uint64_t u = tb_double_to_bits(v);
    if (v > 0.0)
        --u;
    else
        ++u;
    return tb_bits_to_double(u);
}

/* The largest float <= v (v rounded toward -inf to float; NaN stays NaN):
 * a conservative lower bound, e.g. for a box holding double points. */
static inline float tb_float_round_down(double v)
{
    float f = (float)v;
    /* A finite or infinite f < 0 steps down by the next bit pattern, added
     * without a branch (that one was mispredicted about half the time; -inf
     * is never above v). */
    if (f < 0.0f)
        return tb_bits_to_float(tb_float_to_bits(f) + (uint32_t)((double)f > v));
    return (double)f > v ? tb_next_float_down(f) : f;
}
/* The smallest float >= v (v rounded toward +inf to float; NaN stays NaN). */
static inline float tb_float_round_up(double v)
{
    float f = (float)v;
    if (f > 0.0f) /* as in tb_float_round_down: +inf is never below v */
        return tb_bits_to_float(tb_float_to_bits(f) + (uint32_t)((double)f < v));
    return (double)f < v ? tb_next_float_up(f) : f;
}

/* pbrt's gamma(n) = n u / (1 - n u) with u = 2^-24 (TB_FLOAT_UNIT_ROUNDOFF):
 * (1 +- u)^n lies within 1 +- gamma(n), so a value computed with n float
 * operations has relative error at most gamma(n) (Higham, "Accuracy and
 * Stability of Numerical Algorithms", 3.1). Valid for n u < 1. */
static inline float tb_gamma(int n)
{
    return ((float)n * TB_FLOAT_UNIT_ROUNDOFF) / (1.0f - (float)n * TB_FLOAT_UNIT_ROUNDOFF);
}
/* gamma(n) for double arithmetic: u = 2^-53. */
static inline double tb_dgamma(int n)
{
    return ((double)n * TB_DOUBLE_UNIT_ROUNDOFF) / (1.0 - (double)n * TB_DOUBLE_UNIT_ROUNDOFF);
}

/* Number of floats strictly between a and b plus one (0 when a == b, and
 * -0 == +0); UINT32_MAX if either is NaN. Counts across zero, so the
 * distance from -denorm_min to +denorm_min is 2. */
static inline uint32_t tb_ulp_distance(float a, float b)
{
    if (isnan(a) || isnan(b))
        return UINT32_MAX;
    /* Map the sign-magnitude bit patterns onto a monotone integer line. */
    uint32_t ua = tb_float_to_bits(a), ub = tb_float_to_bits(b);
    int64_t ia = (ua & 0x80000000u) ? -(int64_t)(ua & 0x7fffffffu) : (int64_t)ua;
    int64_t ib = (ub & 0x80000000u) ? -(int64_t)(ub & 0x7fffffffu) : (int64_t)ub;
    int64_t d = ia > ib ? ia - ib : ib - ia;
    return d > (int64_t)UINT32_MAX ? UINT32_MAX : (uint32_t)d;
}

/* True if all three components are finite (no NaN, no inf). */
static inline bool tb_isfinite3(tb_vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

/* v limited to [lo, hi]; NaN v gives lo. */
static inline float tb_clampf(float v, float lo, float hi) { return v >= lo ? (v <= hi ? v : hi) : lo; }
/* v limited to [lo, hi]; NaN v gives lo. */
static inline double tb_clamp(double v, double lo, double hi) { return v >= lo ? (v <= hi ? v : hi) : lo; }

/* sqrt(max(v, 0)): a value that should be >= 0 but came out as -1e-9 from
 * rounding gives 0, not NaN. NaN stays NaN. */
static inline float tb_safe_sqrtf(float v) { return sqrtf(v > 0.0f ? v : (v == v ? 0.0f : v)); }
/* sqrt(max(v, 0)) in double. */
static inline double tb_safe_sqrt(double v) { return sqrt(v > 0.0 ? v : (v == v ? 0.0 : v)); }
/* asin with the argument clamped to [-1, 1]. */
static inline double tb_safe_asin(double v) { return asin(tb_clamp(v, -1.0, 1.0)); }
/* acos with the argument clamped to [-1, 1]. */
static inline double tb_safe_acos(double v) { return acos(tb_clamp(v, -1.0, 1.0)); }

/* a*b - c*d with Kahan's algorithm (Jeannerod, Louvet, Muller 2013): error
 * at most 1.5 ulp even when the two products nearly cancel. Uses explicit
 * fmaf(), which is exact whether the CPU has FMA or libm emulates it. */
static inline float tb_diff_of_productsf(float a, float b, float c, float d)
{
    float cd = c * d;
    float err = fmaf(-c, d, cd); /* cd - c*d exactly */
    float dop = fmaf(a, b, -cd);
    return dop + err;
}
/* a*b - c*d in double, Kahan's algorithm with fma(). */
static inline double tb_diff_of_products(double a, double b, double c, double d)
{
    double cd = c * d;
    double err = fma(-c, d, cd);
    double dop = fma(a, b, -cd);
    return dop + err;
}

#endif
