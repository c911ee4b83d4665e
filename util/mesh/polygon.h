/* Geometry of single 3D polygons: Newell normal, area, planarity, projection
 * to the dominant plane, and the explicit split of non-planar quads
 * (docs/meshing.md, "Planarity" and "Non-planar quads"). All arithmetic is in
 * double on float inputs. */
#ifndef TB_UTIL_MESH_POLYGON_H
#define TB_UTIL_MESH_POLYGON_H

#include <stdbool.h>
#include <stdint.h>

#include "util/math/vec.h"

/* Default planarity tolerance, relative to the polygon's size (the diagonal
 * of its bounding box): far above float rounding of the coordinates (~6e-8
 * relative) and far below real modelling error (the Cornell box red wall is
 * off by ~1e-3 relative). */
#define TB_MESH_PLANAR_TOL 1e-5

/* Newell's normal of the loop pts[idx[0..n-1]] (idx NULL: pts[0..n-1]): twice
 * the vector area, pointing to the side from which the loop turns
 * counter-clockwise. Exact for planar loops; for non-planar ones the normal of
 * the best-fitting plane in Newell's sense. Accumulated relative to the first
 * vertex so that far-from-origin loops keep their digits. */
tb_dvec3 tb_polygon_newell(const tb_vec3 *pts, const uint32_t *idx, uint32_t n);

/* Largest distance of a vertex of the loop from the plane through its
 * centroid (mean of the vertices) perpendicular to its Newell normal. 0 for
 * fewer than 4 vertices; INFINITY if the Newell normal is zero. */
double tb_polygon_planarity(const tb_vec3 *pts, const uint32_t *idx, uint32_t n);

/* Diagonal of the loop's bounding box (its size for relative tolerances). */
double tb_polygon_size(const tb_vec3 *pts, const uint32_t *idx, uint32_t n);

/* True if tb_polygon_planarity <= rel_tol * tb_polygon_size (rel_tol <= 0:
 * TB_MESH_PLANAR_TOL). Triangles are always planar. */
bool tb_polygon_is_planar(const tb_vec3 *pts, const uint32_t *idx, uint32_t n, double rel_tol);

/* The dominant-plane projection for a normal: drop the axis where |n| is
 * largest and keep the other two in the order that makes loops that turn
 * counter-clockwise about n turn counter-clockwise in 2D. Coordinates are
 * copied unchanged (float values are exact in double), so exact predicates on
 * the projection decide exactly what they decide in 3D within that plane. */
typedef struct tb_projection {
    int u, v; /* 3D axes (0 = x, 1 = y, 2 = z) giving the 2D x and y */
} tb_projection;

/* The projection for normal n (a zero normal gives the xy plane). */
tb_projection tb_projection_for_normal(tb_dvec3 n);

/* Component `axis` of p, as double. */
static inline double tb_vec3_axis(tb_vec3 p, int axis)
{
    return axis == 0 ? (double)p.x : (axis == 1 ? (double)p.y : (double)p.z);
}

/* Which diagonal splits a quad p0 p1 p2 p3 into two triangles. */
typedef enum tb_quad_diagonal {
    TB_QUAD_DIAG_02 = 0, /* triangles (p0 p1 p2) and (p0 p2 p3) */
    TB_QUAD_DIAG_13 = 1, /* triangles (p0 p1 p3) and (p1 p2 p3) */
} tb_quad_diagonal;

/* The diagonal used to split a quad into two triangles. A diagonal is
 * admissible if both its triangles face the same way as the quad (their
 * normals have a positive dot product with the quad's Newell normal); this
 * rules out the diagonal outside a concave quad. Among admissible diagonals
 * the shorter is taken (squared lengths in double; a tie takes p0-p2); if
 * neither is admissible (a bow tie), the shorter. Used for every non-planar
 * quad and for planar quads that cannot stay quads. */
tb_quad_diagonal tb_quad_split_diagonal(tb_vec3 p0, tb_vec3 p1, tb_vec3 p2, tb_vec3 p3);

/* Writes the two triangles of the split along `d` as corner numbers 0..3
 * (counter-clockwise like the quad) to tri[0..5]. */
void tb_quad_split_corners(tb_quad_diagonal d, uint32_t tri[6]);

#endif
