/* The small hit record of a ray/object intersection, and the offset that lets a
 * ray leave a surface without hitting it again (docs/primitives.md,
 * "Intersection" and "Robustness").
 *
 * The hit holds only what traversal and the `testbed trace` HITS file need
 * (32 bytes, like pbrt-v4's basic intersection or Embree's RTCHit): the full
 * surface record (shading normal, dp/du, dp/dv, texture coordinates) is
 * derived afterwards from (object, face, u, v) by host/object/param.h. */
#ifndef TB_HOST_OBJECT_HIT_H
#define TB_HOST_OBJECT_HIT_H

#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "util/math/float.h"
#include "util/math/vec.h"

/* One hit: also the 32-byte record of HITS files (t, object, face, u, v,
 * ng.x, ng.y, ng.z, each 4 bytes, native byte order).
 *
 * ng is the unit geometric normal in world space pointing OUT of the solid
 * (for polygons: to the front side, from which the vertices turn
 * counter-clockwise), whichever side the ray came from; it is never flipped
 * toward the ray (compare its sign with the ray direction to know the side).
 * For a surface subtracted by a CSG difference it points out of the result,
 * i.e. into the subtracted child. Under a mirroring transform it still points
 * out of the (mirrored) solid. */
typedef struct tb_hit {
    float t;         /* ray parameter of the hit (units of |d|, as the ray's tmin/tmax) */
    uint32_t object; /* index of the top-level object (MID order, from 0) */
    uint32_t face;   /* face ID (host/object/param.h); in a CSG tree offset by the leaf's face base */
    float u, v;      /* parametric coordinates of the hit on that face, in [0, 1] */
    tb_vec3 ng;      /* unit geometric normal, world space, out of the solid (see above) */
} tb_hit;

_Static_assert(sizeof(tb_hit) == 32, "tb_hit is the 32-byte HITS file record");
_Static_assert(offsetof(tb_hit, object) == 4 && offsetof(tb_hit, face) == 8 &&
                   offsetof(tb_hit, u) == 12 && offsetof(tb_hit, v) == 16 &&
                   offsetof(tb_hit, ng) == 20,
               "tb_hit field order is t object face u v nx ny nz");

/* Origin for a ray leaving the surface point p (world space, with absolute
 * error bound perr per component, as tb_object_hit_point() gives them) in
 * direction w, given the geometric normal ng (unit). The origin is moved off
 * the surface along ng, to the side w points to, by d = |ng| . perr (the
 * largest error of p in the normal direction), then every moved component is
 * stepped one more float away. This is pbrt-v4's OffsetRayOrigin (Pharr,
 * Jakob, Humphreys, "Physically Based Rendering", 4th ed., section 6.8.6):
 * the new origin lies strictly on w's side of the tangent plane through any
 * point of the error box, so a ray leaving a convex surface cannot hit it
 * again at t >= 0. Use tmin = 0 with the returned origin. */
static inline tb_vec3 tb_spawn_ray_origin(tb_vec3 p, tb_vec3 perr, tb_vec3 ng, tb_vec3 w)
{
    /* d in double, rounded up: the offset must never come out smaller than the bound. */
    double dd = fabs((double)ng.x) * perr.x + fabs((double)ng.y) * perr.y +
                fabs((double)ng.z) * perr.z;
    const float d = tb_float_round_up(dd);
    double side = (double)w.x * ng.x + (double)w.y * ng.y + (double)w.z * ng.z;
    float s = side < 0.0 ? -d : d;
    float off[3] = {s * ng.x, s * ng.y, s * ng.z};
    float po[3] = {p.x + off[0], p.y + off[1], p.z + off[2]};
    /* The steps take the next bit pattern without a branch on the signs
     * (those were mispredicted about half the time); zeros, infinities and
     * NaN go through tb_next_float_up/down. */
    for (int i = 0; i < 3; i++) {
        const float q = po[i];
        if ((off[i] > 0.0f || off[i] < 0.0f) && q != 0.0f && isfinite(q)) {
            /* up (off > 0) or down, i.e. away from 0 when off and q agree in sign, else toward it */
            const uint32_t toward = (uint32_t)((off[i] > 0.0f) != (q > 0.0f));
            po[i] = tb_bits_to_float(tb_float_to_bits(q) + 1u - 2u * toward);
        } else if (off[i] > 0.0f) {
            po[i] = tb_next_float_up(q);
        } else if (off[i] < 0.0f) {
            po[i] = tb_next_float_down(q);
        }
    }
    return (tb_vec3){po[0], po[1], po[2]};
}

/* The two origins tb_spawn_ray_origin(p, perr, ng, w) can return for the
 * point: *front for every w with w . ng >= 0 (in double, as it computes
 * it), *back for w . ng < 0. A shading point's many shadow rays then pick
 * one by that sign instead of repeating the offset arithmetic. */
static inline void tb_spawn_ray_origins(tb_vec3 p, tb_vec3 perr, tb_vec3 ng, tb_vec3 *front, tb_vec3 *back)
{
    *front = tb_spawn_ray_origin(p, perr, ng, ng);
    /* -ng . ng < 0 in double unless ng = 0, where both sides give p offset by +0. */
    *back = tb_spawn_ray_origin(p, perr, ng, (tb_vec3){-ng.x, -ng.y, -ng.z});
}

/* The side test of tb_spawn_ray_origin: true if w leaves on ng's side
 * (w . ng >= 0 in double), i.e. tb_spawn_ray_origins' *front applies. */
static inline bool tb_spawn_front(tb_vec3 ng, tb_vec3 w)
{
    double side = (double)w.x * ng.x + (double)w.y * ng.y + (double)w.z * ng.z;
    return !(side < 0.0);
}

#endif
