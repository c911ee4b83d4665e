/* Bounding volumes of every primitive: the object-space box, the world-space
 * box under the object's transform, a bounding sphere, and the box of a CSG
 * node from its children's boxes (docs/primitives.md, "Bounds").
 *
 * Boxes come from the primitive's support function h(d) = max over the surface
 * of d . p, which is closed-form for every kind (ellipsoid rows for the
 * sphere, discs for cylinder and cone, the vertex of r(z) for the conic, the
 * Minkowski sum of circle and ball for the torus, vertices for polyhedra), so
 * the world box under an affine transform is exact, not the box of the
 * transformed object box. Computed in double, rounded outward to float. */
#ifndef TB_HOST_OBJECT_BOUNDS_H
#define TB_HOST_OBJECT_BOUNDS_H

#include <stddef.h>

#include "host/mid/mid.h"
#include "util/base/error.h"
#include "util/math/aabb.h"
#include "util/math/transform.h"
#include "util/math/vec.h"

/* Support function: max over the primitive's surface of dot(d, p), p in
 * object space, in double (-INFINITY for polygons without faces). TB_ERR_ARG
 * for a CSG kind, invalid geometry or a non-finite d; TB_ERR_UNSUPPORTED for
 * polygons given as a FED mesh file (use tb_bounds_points on the mesh). */
tb_status tb_bounds_support(tb_prim_kind kind, const tb_mid_geometry *geom, tb_dvec3 d, double *h);

/* The tightest object-space box of the primitive (exact up to the outward
 * rounding to float). Errors as tb_bounds_support. */
tb_status tb_bounds_object(tb_prim_kind kind, const tb_mid_geometry *geom, tb_aabb *out);

/* The tightest world-space box of the primitive placed by `to_world` (NULL:
 * identity): exact for every kind under an affine transform, up to the
 * outward rounding; for a projective matrix, the transformed object box. */
tb_status tb_bounds_world(tb_prim_kind kind, const tb_mid_geometry *geom, const tb_transform *to_world,
                          tb_aabb *out);

/* A world-space sphere holding the primitive (docs/primitives.md says how it
 * is chosen per kind: exact for polyhedra about the box centre, otherwise
 * the smaller of the box's circumsphere and the transformed object sphere).
 * Errors as tb_bounds_world. */
tb_status tb_bounds_sphere(tb_prim_kind kind, const tb_mid_geometry *geom, const tb_transform *to_world,
                           tb_dvec3 *center, double *radius);

/* The world box of points pts[0..n) under `to_world` (NULL: identity), e.g.
 * the vertices of a loaded FED mesh: exact up to outward rounding. Empty for
 * n == 0. TB_ERR_ARG for NULL pts with n > 0. */
tb_status tb_bounds_points(const tb_vec3 *pts, size_t n, const tb_transform *to_world, tb_aabb *out);

/* The float box of points already transformed to world in double whose
 * double box is [lo, hi] (non-empty): tb_bounds_points' padding for the
 * transform's roundings, then outward rounding, so that it equals
 * tb_bounds_points of the untransformed points bit for bit. */
tb_aabb tb_bounds_transformed(tb_dvec3 lo, tb_dvec3 hi);

/* A sphere about the world box centre of the points, with radius the largest
 * distance to a transformed point (rounded up). */
tb_status tb_bounds_points_sphere(const tb_vec3 *pts, size_t n, const tb_transform *to_world,
                                  tb_dvec3 *center, double *radius);

/* Box of a CSG node from its children's boxes (in the same space): union ->
 * union of the boxes, intersection -> their intersection (possibly empty),
 * difference -> the first child's box. Empty for n == 0 or a non-CSG kind. */
tb_aabb tb_bounds_csg(tb_prim_kind op, const tb_aabb *children, int n);

/* Largest singular value of the transform's linear part (its largest
 * stretch of a length), rounded up by a relative 1e-12; 1 for NULL. */
double tb_bounds_max_stretch(const tb_transform *t);

/* The double box [lo, hi] rounded outward to float. */
tb_aabb tb_bounds_round_out(tb_dvec3 lo, tb_dvec3 hi);

#endif
