/* Internals shared by object.c, intersect*.c and csg.c: the crossings of a
 * line with a primitive, computed in the primitive's object space in double
 * (docs/primitives.md, "Intersection"). Not installed. */
#ifndef TB_HOST_OBJECT_INTERSECT_INTERNAL_H
#define TB_HOST_OBJECT_INTERSECT_INTERNAL_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>

#include "host/object/object.h"
#include "util/math/mat.h"
#include "util/math/vec.h"
#include "util/stats/stats.h"

/* A ray in object space, in double: the world ray's origin and direction
 * mapped by the inverse transform without rounding (the direction is not
 * normalised, so t means the same as in world space). */
typedef struct tb__oray {
    tb_dvec3 o, d;
    const tb_ray *world; /* the world ray it came from (tb__xings_mesh tests in world space) */
} tb__oray;

/* One crossing of the line o + t d with a primitive's surface. */
typedef struct tb__xing {
    double t;              /* line parameter */
    tb_dvec3 n;            /* outward normal in the leaf's object space (any length, non-zero) */
    const tb_object *leaf; /* the primitive */
    uint32_t face;         /* face ID within the leaf */
    uint32_t tri;          /* polygons: the triangle hit; 0 otherwise */
    int dir;               /* +1: the line enters the solid here (hits the outside); -1: leaves it */
} tb__xing;

/* A growable list of crossings with room for a few on the stack. */
typedef struct tb__xbuf {
    tb__xing *x;
    int n, cap;
    bool oom;              /* an allocation failed: the list is incomplete */
    tb__xing local[8];
} tb__xbuf;

/* An empty list. */
static inline void tb__xbuf_init(tb__xbuf *b)
{
    b->x = b->local;
    b->n = 0;
    b->cap = (int)(sizeof b->local / sizeof b->local[0]);
    b->oom = false;
}

/* Grows b (slow path of tb__xbuf_push); false when out of memory. */
bool tb__xbuf_grow(tb__xbuf *b);

/* Appends x (sets b->oom and drops it when out of memory). */
static inline void tb__xbuf_push(tb__xbuf *b, const tb__xing *x)
{
    if (b->n == b->cap && !tb__xbuf_grow(b))
        return;
    b->x[b->n++] = *x;
}

/* Frees heap storage (inline: most lists never leave the stack). */
static inline void tb__xbuf_free(tb__xbuf *b)
{
    if (b->x != b->local)
        free(b->x);
    tb__xbuf_init(b);
}

/* Every crossing of the whole line (t from -inf to +inf) with primitive
 * `leaf`, sorted by t. For a closed solid they alternate +1, -1, starting
 * with +1 (the intervals inside the solid; a tangent touch gives an empty
 * interval [t, t]); for an open surface they are the surface points, with dir
 * telling which side was hit. */
void tb__prim_xings(const tb_object *leaf, const tb__oray *r, tb__xbuf *out);

/* Per family (called by tb__prim_xings). */
void tb__xings_sphere(const tb_object *o, const tb__oray *r, tb__xbuf *out);
void tb__xings_revolved(const tb_object *o, const tb__oray *r, tb__xbuf *out); /* cylinder, cone, conic */
void tb__xings_torus(const tb_object *o, const tb__oray *r, tb__xbuf *out);
void tb__xings_cube(const tb_object *o, const tb__oray *r, tb__xbuf *out);
void tb__xings_pyramid(const tb_object *o, const tb__oray *r, tb__xbuf *out);
void tb__xings_prism(const tb_object *o, const tb__oray *r, tb__xbuf *out);
void tb__xings_arch(const tb_object *o, const tb__oray *r, tb__xbuf *out);
void tb__xings_mesh(const tb_object *o, const tb__oray *r, tb__xbuf *out);

/* True if a crossing of the line with primitive o (not CSG, not polygons)
 * has t, rounded to float, in [tmin, tmax]: what tb__closest would find,
 * without building the list or the normals for the kinds below (any-hit
 * queries; intersect.c). Counted per kind as tb__prim_xings. */
bool tb__prim_any(const tb_object *o, const tb__oray *r, double tmin, double tmax);
/* Per family: the same for a sphere, and for cylinder, cone and conic (intersect_quadric.c, uncounted). */
bool tb__any_sphere(const tb_object *o, const tb__oray *r, double tmin, double tmax);
bool tb__any_revolved(const tb_object *o, const tb__oray *r, double tmin, double tmax);
/* True when the torus certainly has no crossing the any-hit test would take
 * (float t in [tmin, tmax]), decided without solving its quartic; false when
 * that is not certain (tb__xings_torus then decides). */
bool tb__torus_clear(const tb_object *o, const tb__oray *r, double tmin, double tmax);

/* Sets o->zclosed of a cylinder, cone or conic (after conic and zrange;
 * object.c), once instead of at every ray. */
void tb__revolved_prepare(tb_object *o);

/* Closest triangle hit of the world ray with t in [tmin, tmax] (polygons,
 * tested in world space: no object ray needed); false if none. */
bool tb__mesh_closest(const tb_object *o, const tb_ray *ray, double tmin, double tmax, tb__xing *hit);
/* True if any triangle is hit with t in [tmin, tmax]. */
bool tb__mesh_any(const tb_object *o, const tb_ray *ray, double tmin, double tmax);

/* The watertight test's edge functions U V W (tb_wt_triangle's uvw) for the
 * world ray's crossing of triangle `tri` of polygons object o; false if it
 * does not cross (not for a triangle a query of that ray reported). */
bool tb__mesh_tri_weights(const tb_object *o, uint32_t tri, const tb_ray *ray, double uvw[3]);

/* Triangulates o->geom.polygons into o->mesh and builds its BVH (object.c
 * calls it after copying the polygons). */
tb_status tb__mesh_build(tb_object *o);
/* Frees a mesh (NULL allowed). */
void tb__mesh_free(tb_object_mesh *m);

/* Vertex k of the regular n-gon (cos 2 pi k/n, sin 2 pi k/n). */
void tb__prism_vertex(int n, int k, double *x, double *y);

/* Face IDs of a primitive (as tb_param_face_count). */
uint32_t tb__face_count(tb_prim_kind kind, const tb_mid_geometry *g);

/* Distance (object units, approximate to first order) from p to the surface
 * of face `face` (triangle `tri` for polygons) of primitive o: used to bound
 * the error of a recomputed hit point. */
double tb__face_residual(const tb_object *o, uint32_t face, uint32_t tri, tb_dvec3 p);

/* The crossings of a CSG node (or a primitive) with the whole line, in the
 * same form as tb__prim_xings: intervals of the solid, sorted (csg.c). */
void tb__csg_xings(const tb_object *node, const tb_ray *world_ray, tb__xbuf *out);
/* As tb__csg_xings when only the first crossing whose t, rounded to float,
 * lies in [tmin, tmax] matters: the list holds that same crossing (the
 * first in range; none if there is none) with less work: the sweep stops
 * there, and is skipped when no child has a crossing in range (csg.c). */
void tb__csg_xings_in(const tb_object *node, const tb_ray *world_ray, double tmin, double tmax, tb__xbuf *out);

/* The "Intersect/<kind>" counters, by kind (intersect.c). */
extern tb_stat *const tb__kind_counters[TB_PRIM_COUNT];

/* Adds one to the "Intersect/<kind>" counter (inline: once per primitive
 * or node a ray tests). */
static inline void tb__count_kind(tb_prim_kind k)
{
    if ((int)k >= 0 && (int)k < TB_PRIM_COUNT)
        tb_stat_add(tb__kind_counters[k], 1);
}

/* The world ray in o's object space (inline: it runs for every primitive a
 * ray tests). */
static inline tb__oray tb__object_ray(const tb_object *o, const tb_ray *r)
{
    /* tb_mat4_mul_point / tb_mat4_mul_vec written out with the same
     * operations in the same order (so bit for bit the same), without the
     * calls: this runs for every primitive a ray tests. The inverse of an
     * accepted transform is affine (projective ones are rejected when the
     * object is built, which records it in inv_affine), so its w row is
     * 0 0 0 1 and mul_point's w is exactly 1 for a finite origin; anything
     * else takes the general path. */
    const double(*m)[4] = o->to_world.inv.m;
    double ox = r->o.x, oy = r->o.y, oz = r->o.z, dx = r->d.x, dy = r->d.y, dz = r->d.z;
    tb__oray q;
    /* ox + oy + oz is finite exactly when all three are: they are floats, so
     * their double sum cannot overflow. One test instead of three. */
    if (o->inv_affine && isfinite(ox + oy + oz)) {
        q.o = (tb_dvec3){m[0][0] * ox + m[0][1] * oy + m[0][2] * oz + m[0][3],
                         m[1][0] * ox + m[1][1] * oy + m[1][2] * oz + m[1][3],
                         m[2][0] * ox + m[2][1] * oy + m[2][2] * oz + m[2][3]};
    } else {
        q.o = tb_mat4_mul_point(&o->to_world.inv, (tb_dvec3){ox, oy, oz});
    }
    q.world = r;
    q.d = (tb_dvec3){m[0][0] * dx + m[0][1] * dy + m[0][2] * dz, m[1][0] * dx + m[1][1] * dy + m[1][2] * dz,
                     m[2][0] * dx + m[2][1] * dy + m[2][2] * dz};
    return q;
}

/* Counts object teardowns (tb__object_clear): per-thread memos that keep
 * pointers into an object tree (tb_object_hit_point's crossing) are valid
 * only while it is unchanged, since a later object may reuse the address. */
extern _Atomic unsigned long tb__object_generation;

#endif
