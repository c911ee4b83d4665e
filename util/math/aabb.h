/* Axis-aligned bounding boxes in float, closed on all sides, and the robust
 * ray/box slab test that bounding volume hierarchies are built on. */
#ifndef TB_UTIL_MATH_AABB_H
#define TB_UTIL_MATH_AABB_H

#include <math.h>
#include <stdbool.h>

#include "util/math/float.h"
#include "util/math/ray.h"
#include "util/math/vec.h"

/* The box lo <= p <= hi (component-wise). Empty when lo > hi on any axis. */
typedef struct tb_aabb {
    tb_vec3 lo; /* minimum corner */
    tb_vec3 hi; /* maximum corner */
} tb_aabb;

/* The empty box (lo = +inf, hi = -inf): the identity of union. */
static inline tb_aabb tb_aabb_empty(void)
{
    return (tb_aabb){{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
}
/* The smallest box holding a and b (in any order). */
static inline tb_aabb tb_aabb_from_points(tb_vec3 a, tb_vec3 b)
{
    return (tb_aabb){tb_vec3_min(a, b), tb_vec3_max(a, b)};
}
/* True if the box holds no point (lo > hi on some axis, or a NaN corner). */
static inline bool tb_aabb_is_empty(const tb_aabb *b)
{
    return !(b->lo.x <= b->hi.x && b->lo.y <= b->hi.y && b->lo.z <= b->hi.z);
}
/* b grown to hold p. */
static inline tb_aabb tb_aabb_union_point(tb_aabb b, tb_vec3 p)
{
    return (tb_aabb){tb_vec3_min(b.lo, p), tb_vec3_max(b.hi, p)};
}
/* The smallest box holding a and b (an empty operand changes nothing). */
static inline tb_aabb tb_aabb_union(tb_aabb a, tb_aabb b)
{
    return (tb_aabb){tb_vec3_min(a.lo, b.lo), tb_vec3_max(a.hi, b.hi)};
}
/* a intersected with b (empty if they do not overlap). */
static inline tb_aabb tb_aabb_intersection(tb_aabb a, tb_aabb b)
{
    return (tb_aabb){tb_vec3_max(a.lo, b.lo), tb_vec3_min(a.hi, b.hi)};
}
/* hi - lo (zero for an empty box). */
static inline tb_vec3 tb_aabb_extent(const tb_aabb *b)
{
    if (tb_aabb_is_empty(b))
        return (tb_vec3){0.0f, 0.0f, 0.0f};
    return tb_vec3_sub(b->hi, b->lo);
}
/* (lo + hi) / 2, computed as lo/2 + hi/2 so that huge boxes do not overflow.
 * Undefined (NaN) for an empty box. */
static inline tb_vec3 tb_aabb_centroid(const tb_aabb *b)
{
    return tb_vec3_add(tb_vec3_scale(b->lo, 0.5f), tb_vec3_scale(b->hi, 0.5f));
}
/* Surface area 2 (xy + yz + zx); 0 for an empty box (the SAH cost of an empty child). */
static inline float tb_aabb_surface_area(const tb_aabb *b)
{
    tb_vec3 e = tb_aabb_extent(b);
    return 2.0f * (e.x * e.y + e.y * e.z + e.z * e.x);
}
/* Volume; 0 for an empty box. */
static inline float tb_aabb_volume(const tb_aabb *b)
{
    tb_vec3 e = tb_aabb_extent(b);
    return e.x * e.y * e.z;
}
/* Axis (0, 1, 2) along which the box is longest; the first one on ties. */
static inline int tb_aabb_largest_axis(const tb_aabb *b) { return tb_vec3_max_dim(tb_aabb_extent(b)); }
/* True if p lies in the closed box. */
static inline bool tb_aabb_contains(const tb_aabb *b, tb_vec3 p)
{
    return p.x >= b->lo.x && p.x <= b->hi.x && p.y >= b->lo.y && p.y <= b->hi.y &&
           p.z >= b->lo.z && p.z <= b->hi.z;
}
/* True if `inner` lies in the closed box `outer` (an empty `inner` is in every box). */
static inline bool tb_aabb_contains_box(const tb_aabb *outer, const tb_aabb *inner)
{
    if (tb_aabb_is_empty(inner))
        return true;
    return tb_aabb_contains(outer, inner->lo) && tb_aabb_contains(outer, inner->hi);
}
/* True if the closed boxes share at least one point (touching counts). */
static inline bool tb_aabb_overlaps(const tb_aabb *a, const tb_aabb *b)
{
    return a->lo.x <= b->hi.x && a->hi.x >= b->lo.x && a->lo.y <= b->hi.y &&
           a->hi.y >= b->lo.y && a->lo.z <= b->hi.z && a->hi.z >= b->lo.z;
}
/* (p - lo) / (hi - lo): where p sits in the box, 0 at lo and 1 at hi per axis
 * (an axis of zero extent gives 0). Used for SAH binning. */
static inline tb_vec3 tb_aabb_offset(const tb_aabb *b, tb_vec3 p)
{
    tb_vec3 o = tb_vec3_sub(p, b->lo);
    if (b->hi.x > b->lo.x) o.x /= b->hi.x - b->lo.x; else o.x = 0.0f;
    if (b->hi.y > b->lo.y) o.y /= b->hi.y - b->lo.y; else o.y = 0.0f;
    if (b->hi.z > b->lo.z) o.z /= b->hi.z - b->lo.z; else o.z = 0.0f;
    return o;
}

/* One axis of the slab test. `near` and `far` are the planes the ray meets
 * first and last (chosen by the sign bit of inv, so -0 behaves like a tiny
 * negative number and +0 like a tiny positive one). The products are
 * +-inf when the direction component is +-0, and NaN only when the origin
 * lies exactly on that plane; a NaN fails both comparisons and leaves
 * [*t0, *t1] unchanged, which is right for a closed box: a ray inside a
 * face plane, moving parallel to it, is on the box along that axis. */
static inline void tb__aabb_slab(float o, float inv, float lo, float hi, float *t0, float *t1)
{
    /* Each t below has relative error <= gamma(3) (inv = 1/d, the
     * subtraction, the product); widening by 2 gamma(3) outward also covers
     * the rounding of the widening itself. Ize 2013, "Robust BVH ray
     * traversal"; pbrt-v3 Bounds3::IntersectP. Scaling rather than adding
     * |t| k keeps +-inf from turning into NaN. */
    const float k = 2.0f * tb_gamma(3);
    bool neg = signbit(inv);
    float tn = ((neg ? hi : lo) - o) * inv;
    float tf = ((neg ? lo : hi) - o) * inv;
    tn = tn > 0.0f ? tn * (1.0f - k) : tn * (1.0f + k);
    tf = tf > 0.0f ? tf * (1.0f + k) : tf * (1.0f - k);
    if (tn > *t0)
        *t0 = tn;
    if (tf < *t1)
        *t1 = tf;
}

/* Slab test with a precomputed inv_d = 1 / d (per component; +-inf for a
 * +-0 component): true if the segment [tmin, tmax] of o + t d meets the
 * closed box, and then [*t0, *t1] (within [tmin, tmax]) holds every t at
 * which it is inside. Conservative: rounding can only make the interval
 * larger, never miss a hit; each end lies within a relative
 * 2 gamma(3) + gamma(4) (~6e-7) of the exact value (rounding, widening and
 * the widening's own rounding; for results in the normal float range).
 * Never produces NaN.
 * An empty box is never hit. */
static inline bool tb_aabb_slab(const tb_aabb *b, tb_vec3 o, tb_vec3 inv_d, float tmin, float tmax,
                                float *t0, float *t1)
{
    float a = tmin, z = tmax;
    tb__aabb_slab(o.x, inv_d.x, b->lo.x, b->hi.x, &a, &z);
    tb__aabb_slab(o.y, inv_d.y, b->lo.y, b->hi.y, &a, &z);
    tb__aabb_slab(o.z, inv_d.z, b->lo.z, b->hi.z, &a, &z);
    if (!(a <= z) || tb_aabb_is_empty(b))
        return false;
    if (t0)
        *t0 = a;
    if (t1)
        *t1 = z;
    return true;
}

/* tb_aabb_slab for a ray (computes 1/d; see there). t0, t1 may be NULL. */
static inline bool tb_aabb_intersect_ray(const tb_aabb *b, const tb_ray *r, float *t0, float *t1)
{
    tb_vec3 inv = {1.0f / r->d.x, 1.0f / r->d.y, 1.0f / r->d.z};
    return tb_aabb_slab(b, r->o, inv, r->tmin, r->tmax, t0, t1);
}

#endif
