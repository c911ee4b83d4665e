/* Rigid, affine and projective transforms: a double matrix kept together with
 * its inverse, so that points, directions, normals, rays and boxes can be
 * moved both ways without ever inverting at render time.
 *
 * Conventions (docs/math.md): right-handed coordinates; column vectors,
 * p' = m p; tb_transform_compose(a, b) applies b FIRST, then a (like the
 * matrix product a.m * b.m); rotations are counter-clockwise looking down
 * the axis toward the origin (right-hand rule); the look-at camera looks
 * down its -z axis with +y up and +x to the right.
 *
 * Arithmetic is in double; float inputs are widened exactly and each float
 * result component is rounded once at the end. */
#ifndef TB_UTIL_MATH_TRANSFORM_H
#define TB_UTIL_MATH_TRANSFORM_H

#include <stdbool.h>

#include "util/base/error.h"
#include "util/math/aabb.h"
#include "util/math/mat.h"
#include "util/math/ray.h"
#include "util/math/vec.h"

/* A transform and its inverse. Invariant: inv = m^-1 (to rounding). */
typedef struct tb_transform {
    tb_mat4 m;   /* object (local) to world: p_world = m p_local */
    tb_mat4 inv; /* world to object */
} tb_transform;

/* The identity transform. */
tb_transform tb_transform_identity(void);
/* Translation by t. */
tb_transform tb_transform_translate(tb_dvec3 t);
/* Non-uniform scale by s (negative factors mirror). TB_ERR_ARG for a zero or
 * non-finite factor: a zero scale flattens space and has no inverse.
 * TB_ERR_NUMERIC when min|s| / max|s| < TB_MAT_RCOND_MIN (the verdict
 * tb_mat4_inverse gives for the same matrix); a uniform scale is always
 * accepted however small, since it loses no relative precision. */
tb_status tb_transform_scale(tb_dvec3 s, tb_transform *out);
/* Rotation by `radians` about `axis` through the origin (right-hand rule).
 * The axis need not be unit length; TB_ERR_ARG when it is zero or
 * non-finite, or the angle is non-finite. */
tb_status tb_transform_rotate(double radians, tb_dvec3 axis, tb_transform *out);
/* tb_transform_rotate with the angle in degrees. Multiples of 90 degrees give
 * exact 0 and +-1 sines and cosines (the angle is reduced in degrees first),
 * so rotate(90) maps axes onto axes exactly. */
tb_status tb_transform_rotate_deg(double degrees, tb_dvec3 axis, tb_transform *out);
/* Rotation by `radians` about +x (y toward z). */
tb_transform tb_transform_rotate_x(double radians);
/* Rotation by `radians` about +y (z toward x). */
tb_transform tb_transform_rotate_y(double radians);
/* Rotation by `radians` about +z (x toward y). */
tb_transform tb_transform_rotate_z(double radians);
/* Camera-to-world transform of a camera at `eye` looking at `target`: the
 * camera's origin goes to eye, its -z axis points toward target, its +y axis
 * is the part of `up` perpendicular to the view direction and +x = y cross z
 * (to the right on screen). A rigid motion: no scale, no mirroring. Its
 * inverse (inv) is the world-to-camera (view) matrix. TB_ERR_ARG when
 * eye == target, up is zero or parallel to the view direction, or an input
 * is not finite. */
tb_status tb_transform_look_at(tb_dvec3 eye, tb_dvec3 target, tb_dvec3 up, tb_transform *out);
/* The transform with matrix m (any invertible 4x4, projective allowed). Fails
 * as tb_mat4_inverse does (TB_ERR_NUMERIC for singular/ill-conditioned). */
tb_status tb_transform_from_matrix(const tb_mat4 *m, tb_transform *out);
/* a after b: applies b first, then a (matrix a.m * b.m, inverse b.inv * a.inv). */
tb_transform tb_transform_compose(const tb_transform *a, const tb_transform *b);
/* The inverse transform (swaps m and inv; exact, no arithmetic). */
tb_transform tb_transform_inverse(const tb_transform *t);
/* True if the transform mirrors space (det of the linear part < 0): triangle
 * winding and the sense of cross-product normals flip under it. */
bool tb_transform_swaps_handedness(const tb_transform *t);
/* True if m is exactly the identity. */
bool tb_transform_is_identity(const tb_transform *t);

/* m (p, 1), divided by w if the transform is projective. */
tb_vec3 tb_transform_point(const tb_transform *t, tb_vec3 p);
/* m (v, 0): directions and tangents (no translation). */
tb_vec3 tb_transform_vector(const tb_transform *t, tb_vec3 v);
/* inv^T (n, 0): a normal stays perpendicular to transformed tangents. Not
 * renormalised (the caller normalises if it needs unit length). */
tb_vec3 tb_transform_normal(const tb_transform *t, tb_vec3 n);
/* Double-precision point transform (no rounding to float). */
tb_dvec3 tb_transform_dpoint(const tb_transform *t, tb_dvec3 p);
/* Double-precision vector transform. */
tb_dvec3 tb_transform_dvector(const tb_transform *t, tb_dvec3 v);
/* Double-precision normal transform. */
tb_dvec3 tb_transform_dnormal(const tb_transform *t, tb_dvec3 n);
/* The ray with origin and direction transformed; tmin and tmax are kept, so
 * the point at parameter t maps to the point at the same t (the direction is
 * not renormalised). Affine transforms only: for a projective one the result
 * is meaningless. */
tb_ray tb_transform_ray(const tb_transform *t, const tb_ray *r);
/* A box holding the image of every point of b. Affine transforms use Arvo's
 * method (Graphics Gems 1990, "Transforming axis-aligned bounding boxes"),
 * which gives the same box as transforming the 8 corners; projective ones
 * transform the 8 corners (and give an infinite box if a corner reaches
 * w <= 0). Computed in double and rounded outward to float, so it is never
 * too small. An empty box stays empty. */
tb_aabb tb_transform_aabb(const tb_transform *t, const tb_aabb *b);

#endif
