/* Robust geometric predicates in the plane.
 *
 * tb_orient2d answers "is c left of, right of, or on the line a->b?" with the
 * exact sign, for any double inputs whose pairwise products neither overflow
 * nor underflow (|coordinates| between about 2^-500 and 2^500, or zero; every
 * input converted from float qualifies). It is Shewchuk's adaptive scheme
 * (J. R. Shewchuk, "Adaptive precision floating-point arithmetic and fast
 * robust geometric predicates", DCG 18, 1997): the plain double determinant
 * with a forward error bound, and, only when the bound cannot decide, the
 * determinant evaluated exactly as a floating-point expansion. The build has
 * -ffp-contract=off, which the error bound and the exact arithmetic rely on
 * (a fused multiply-add would change the rounding the bound assumes).
 * See docs/meshing.md, "Predicates". */
#ifndef TB_UTIL_MESH_PREDICATES_H
#define TB_UTIL_MESH_PREDICATES_H

/* A value whose sign is the sign of the determinant
 *   | ax-cx  ay-cy |
 *   | bx-cx  by-cy |
 * i.e. positive if a, b, c turn counter-clockwise, negative if clockwise, and
 * exactly zero if they are collinear. The magnitude approximates twice the
 * signed triangle area (exact sign, approximate value). */
double tb_orient2d(double ax, double ay, double bx, double by, double cx, double cy);

/* The same determinant evaluated only in plain double arithmetic (no
 * fallback): fast, but its sign may be wrong for nearly collinear points.
 * Kept public so tests can show where the exact version matters. */
double tb_orient2d_fast(double ax, double ay, double bx, double by, double cx, double cy);

/* Exact sign of tb_orient2d: -1, 0 or +1. */
static inline int tb_orient2d_sign(double ax, double ay, double bx, double by, double cx, double cy)
{
    double d = tb_orient2d(ax, ay, bx, by, cx, cy);
    return (d > 0) - (d < 0);
}

#endif
