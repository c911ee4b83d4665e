/* 3x3 and 4x4 matrices in double precision for composing and inverting scene
 * transforms, and a float 4x4 in column-major order for GPU upload.
 *
 * Conventions (docs/math.md): m[row][col], and matrices act on column vectors
 * on the right, p' = M p, so a translation sits in the last column
 * (m[0][3], m[1][3], m[2][3]) and A*B applies B first.
 *
 * Inversion rejects singular and ill-conditioned matrices with a relative
 * test (scale-free: multiplying M by any non-zero constant does not change
 * the verdict); see tb_mat4_inverse. */
#ifndef TB_UTIL_MATH_MAT_H
#define TB_UTIL_MATH_MAT_H

#include <stdbool.h>

#include "util/base/error.h"
#include "util/math/vec.h"

/* Inversion fails when the estimated reciprocal condition number
 * 1 / (||A||_inf ||A^-1||_inf) is below this: about 12 of double's 16 digits
 * would be lost, leaving fewer than float's 7 for the data the inverse is
 * applied to. */
#define TB_MAT_RCOND_MIN 1e-12

/* A 3x3 double matrix, m[row][col] (linear part of a transform, normal matrix). */
typedef struct tb_mat3 {
    double m[3][3];
} tb_mat3;

/* A 4x4 double matrix, m[row][col], acting on column vectors (p' = M p). */
typedef struct tb_mat4 {
    double m[4][4];
} tb_mat4;

/* A 4x4 float matrix in COLUMN-MAJOR order, element (row r, col c) at
 * m[c * 4 + r]: the layout GLSL mat4 has in std140/std430 buffers, so the
 * array can be copied to the GPU as is. */
typedef struct tb_mat4f {
    float m[16]; /* column-major: m[c*4 + r] */
} tb_mat4f;

/* ------------------------------------------------------------------ tb_mat3 */

/* The identity. */
tb_mat3 tb_mat3_identity(void);
/* a * b (apply b first). */
tb_mat3 tb_mat3_mul(const tb_mat3 *a, const tb_mat3 *b);
/* Transpose. */
tb_mat3 tb_mat3_transpose(const tb_mat3 *a);
/* Determinant (cofactor expansion along the first row). */
double tb_mat3_det(const tb_mat3 *a);
/* M v. */
tb_dvec3 tb_mat3_mul_vec(const tb_mat3 *a, tb_dvec3 v);
/* Sets *out = a^-1. TB_ERR_ARG for a non-finite entry; TB_ERR_NUMERIC (with a
 * message) when a is singular or its reciprocal condition number in the
 * infinity norm is below TB_MAT_RCOND_MIN. out may alias a; on failure *out
 * is left unchanged. */
tb_status tb_mat3_inverse(const tb_mat3 *a, tb_mat3 *out);

/* ------------------------------------------------------------------ tb_mat4 */

/* The identity. */
tb_mat4 tb_mat4_identity(void);
/* Rows given in reading order: m[r][c] = v[r*4 + c]. */
tb_mat4 tb_mat4_from_rows(const double v[16]);
/* a * b (apply b first). */
tb_mat4 tb_mat4_mul(const tb_mat4 *a, const tb_mat4 *b);
/* Transpose. */
tb_mat4 tb_mat4_transpose(const tb_mat4 *a);
/* Determinant (Laplace expansion in 2x2 minors). */
double tb_mat4_det(const tb_mat4 *a);
/* True if every entry is finite. */
bool tb_mat4_isfinite(const tb_mat4 *a);
/* True if the last row is exactly (0, 0, 0, 1). */
bool tb_mat4_is_affine(const tb_mat4 *a);
/* True if a == b entry by entry. */
bool tb_mat4_equal(const tb_mat4 *a, const tb_mat4 *b);
/* Largest |a[r][c] - b[r][c]|. */
double tb_mat4_max_abs_diff(const tb_mat4 *a, const tb_mat4 *b);
/* The upper-left 3x3 block (the linear part of an affine transform). */
tb_mat3 tb_mat4_linear(const tb_mat4 *a);
/* The affine matrix with linear part l and translation t. */
tb_mat4 tb_mat4_from_linear(const tb_mat3 *l, tb_dvec3 t);
/* M (p, 1) with the homogeneous divide by w when w != 1. */
tb_dvec3 tb_mat4_mul_point(const tb_mat4 *a, tb_dvec3 p);
/* M (v, 0): the upper-left 3x3 block applied to v. */
tb_dvec3 tb_mat4_mul_vec(const tb_mat4 *a, tb_dvec3 v);
/* Sets *out = a^-1. Affine matrices are inverted through their 3x3 linear
 * part (so a large translation does not make a well-scaled transform look
 * ill-conditioned, and the result keeps an exact (0 0 0 1) last row); other
 * matrices by Gauss-Jordan elimination with partial pivoting. TB_ERR_ARG
 * for a non-finite entry; TB_ERR_NUMERIC when the (linear part of the)
 * matrix is singular or its estimated reciprocal condition number
 * 1 / (||A||_inf ||A^-1||_inf) is below TB_MAT_RCOND_MIN. out may alias a;
 * on failure *out is left unchanged. */
tb_status tb_mat4_inverse(const tb_mat4 *a, tb_mat4 *out);
/* Rounded to float, transposed into column-major storage. */
tb_mat4f tb_mat4_to_f(const tb_mat4 *a);
/* Element (row r, col c) of a float matrix. */
static inline float tb_mat4f_at(const tb_mat4f *a, int r, int c) { return a->m[c * 4 + r]; }

#endif
