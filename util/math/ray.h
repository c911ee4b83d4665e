/* A ray with its parametric range: the points o + t d for tmin <= t <= tmax.
 * The layout is fixed (32 bytes, ox oy oz tmin dx dy dz tmax) because it is
 * also the record of `testbed trace` ray files and of the GPU ray buffer. */
#ifndef TB_UTIL_MATH_RAY_H
#define TB_UTIL_MATH_RAY_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>

#include "util/math/vec.h"

/* A ray. d need not be unit length: t is measured in units of |d|. */
typedef struct tb_ray {
    tb_vec3 o;  /* origin */
    float tmin; /* start of the valid segment, in units of |d| */
    tb_vec3 d;  /* direction, non-zero */
    float tmax; /* end of the segment (+inf for an unbounded ray) */
} tb_ray;

_Static_assert(sizeof(tb_ray) == 32, "tb_ray must match the 32-byte ray file record");
_Static_assert(offsetof(tb_ray, tmin) == 12 && offsetof(tb_ray, d) == 16 &&
                   offsetof(tb_ray, tmax) == 28,
               "tb_ray field order is ox oy oz tmin dx dy dz tmax");

/* A ray from o along d over [tmin, tmax]. */
static inline tb_ray tb_ray_make(tb_vec3 o, tb_vec3 d, float tmin, float tmax)
{
    return (tb_ray){o, tmin, d, tmax};
}

/* o + t d, each component rounded twice (product, then sum: no FMA). */
static inline tb_vec3 tb_ray_at(const tb_ray *r, float t)
{
    return (tb_vec3){r->o.x + t * r->d.x, r->o.y + t * r->d.y, r->o.z + t * r->d.z};
}

/* True if the ray can be traced: origin and direction finite, direction not
 * zero, tmin and tmax not NaN, tmin finite (tmax may be +inf), and
 * tmin <= tmax. A ray with tmin == tmax is valid (it tests one point). */
static inline bool tb_ray_is_valid(const tb_ray *r)
{
    if (!(isfinite(r->o.x) && isfinite(r->o.y) && isfinite(r->o.z)))
        return false;
    if (!(isfinite(r->d.x) && isfinite(r->d.y) && isfinite(r->d.z)))
        return false;
    if (r->d.x == 0.0f && r->d.y == 0.0f && r->d.z == 0.0f)
        return false;
    if (!isfinite(r->tmin) || isnan(r->tmax))
        return false;
    return r->tmin <= r->tmax;
}

#endif
