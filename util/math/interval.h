/* Closed float intervals [lo, hi]: parameter ranges along rays (clipping a
 * ray against a box or a CSG operand) and a minimal interval arithmetic for
 * error bounds, whose results always contain the exact real result. */
#ifndef TB_UTIL_MATH_INTERVAL_H
#define TB_UTIL_MATH_INTERVAL_H

#include <math.h>
#include <stdbool.h>

#include "util/math/float.h"

/* The closed set { t : lo <= t <= hi }; empty when lo > hi (or a bound is NaN). */
typedef struct tb_interval {
    float lo; /* lower bound, may be -inf */
    float hi; /* upper bound, may be +inf */
} tb_interval;

/* [lo, hi]. */
static inline tb_interval tb_interval_make(float lo, float hi) { return (tb_interval){lo, hi}; }
/* [v, v]: an exactly known value. */
static inline tb_interval tb_interval_point(float v) { return (tb_interval){v, v}; }
/* The empty interval [+inf, -inf] (identity of hull). */
static inline tb_interval tb_interval_empty(void) { return (tb_interval){INFINITY, -INFINITY}; }
/* (-inf, +inf). */
static inline tb_interval tb_interval_everything(void) { return (tb_interval){-INFINITY, INFINITY}; }
/* True if no t lies in a. */
static inline bool tb_interval_is_empty(tb_interval a) { return !(a.lo <= a.hi); }
/* True if t lies in the closed interval a. */
static inline bool tb_interval_contains(tb_interval a, float t) { return t >= a.lo && t <= a.hi; }
/* True if b is a subset of a (an empty b is a subset of everything). */
static inline bool tb_interval_contains_interval(tb_interval a, tb_interval b)
{
    return tb_interval_is_empty(b) || (b.lo >= a.lo && b.hi <= a.hi);
}
/* a intersected with b (empty if they do not meet; touching gives one point). */
static inline tb_interval tb_interval_intersect(tb_interval a, tb_interval b)
{
    return (tb_interval){fmaxf(a.lo, b.lo), fminf(a.hi, b.hi)};
}
/* The smallest interval holding a and b (the gap between them included).
 * An empty operand changes nothing. */
static inline tb_interval tb_interval_hull(tb_interval a, tb_interval b)
{
    if (tb_interval_is_empty(a))
        return b;
    if (tb_interval_is_empty(b))
        return a;
    return (tb_interval){fminf(a.lo, b.lo), fmaxf(a.hi, b.hi)};
}
/* hi - lo (0 for an empty interval). */
static inline float tb_interval_width(tb_interval a) { return tb_interval_is_empty(a) ? 0.0f : a.hi - a.lo; }
/* The midpoint lo/2 + hi/2 (no overflow for huge bounds). */
static inline float tb_interval_mid(tb_interval a) { return 0.5f * a.lo + 0.5f * a.hi; }

/* Interval arithmetic. Each bound is computed with round-to-nearest and then
 * moved one float outward (tb_next_float_down/up), which contains the exact
 * result because one rounding errs by at most half an ulp. This widens by
 * one ulp even when the operation was exact: cheap rather than tight.
 * Operands must be non-empty. */

/* a + b, rounded outward. */
static inline tb_interval tb_interval_add(tb_interval a, tb_interval b)
{
    return (tb_interval){tb_next_float_down(a.lo + b.lo), tb_next_float_up(a.hi + b.hi)};
}
/* a - b, rounded outward. */
static inline tb_interval tb_interval_sub(tb_interval a, tb_interval b)
{
    return (tb_interval){tb_next_float_down(a.lo - b.hi), tb_next_float_up(a.hi - b.lo)};
}
/* Product of two bounds, treating 0 * inf as 0 (the bound of a product of a
 * finite value near 0 and a large one stays finite in the limit). */
static inline float tb__interval_mulb(float x, float y)
{
    return (x == 0.0f || y == 0.0f) ? 0.0f : x * y;
}
/* a * b, rounded outward: the extremes of the four bound products. */
static inline tb_interval tb_interval_mul(tb_interval a, tb_interval b)
{
    float p0 = tb__interval_mulb(a.lo, b.lo), p1 = tb__interval_mulb(a.lo, b.hi);
    float p2 = tb__interval_mulb(a.hi, b.lo), p3 = tb__interval_mulb(a.hi, b.hi);
    float lo = fminf(fminf(p0, p1), fminf(p2, p3));
    float hi = fmaxf(fmaxf(p0, p1), fmaxf(p2, p3));
    return (tb_interval){tb_next_float_down(lo), tb_next_float_up(hi)};
}
/* a * s for a scalar s, rounded outward. */
static inline tb_interval tb_interval_scale(tb_interval a, float s)
{
    return tb_interval_mul(a, tb_interval_point(s));
}
/* a^2 (tighter than a * a when a contains 0: never negative). */
static inline tb_interval tb_interval_sqr(tb_interval a)
{
    float l = fabsf(a.lo), h = fabsf(a.hi);
    if (l > h) {
        float t = l;
        l = h;
        h = t;
    }
    if (a.lo <= 0.0f && a.hi >= 0.0f)
        l = 0.0f;
    float lo = l * l;
    return (tb_interval){lo == 0.0f ? 0.0f : tb_next_float_down(lo), tb_next_float_up(h * h)};
}

#endif
