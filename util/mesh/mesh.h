/* Element meshes for radiosity and rendering: a FED mesh turned into
 * triangles and quads, optionally subdivided to a maximum edge length or
 * element area while staying conforming (docs/meshing.md).
 *
 * Conformity comes from doing everything edge by edge: each FED edge is cut
 * into k = ceil(length / max_edge) equal parts once, by vertex index, and
 * both faces sharing it use those same vertices; a face then only adds
 * vertices inside itself. So no crack or T-junction can appear between
 * faces, and inside a face the fill is conforming by construction (regular
 * grids, or a triangulation refined by splitting edges together with both
 * their triangles). */
#ifndef TB_UTIL_MESH_MESH_H
#define TB_UTIL_MESH_MESH_H

#include <stdbool.h>
#include <stdint.h>

#include "util/base/error.h"
#include "util/container/array.h"
#include "util/math/vec.h"
#include "util/mesh/fed.h"

/* "No vertex / no element" in mesh indices. */
#define TB_MESH_NONE UINT32_MAX

/* Smallest interior angle a quad element may have, in degrees (and the
 * largest is 180 minus this). */
#define TB_MESH_QUAD_MIN_ANGLE 30.0

/* One element: a triangle or a quad. */
typedef struct tb_mesh_elem {
    uint32_t v[4];   /* vertices, counter-clockwise about the face's normal; v[3] == TB_MESH_NONE for a triangle */
    uint32_t face;   /* the FED face it lies on */
    uint32_t parent; /* the element it was split from, TB_MESH_NONE for elements made from a face */
} tb_mesh_elem;

/* A meshed surface. Vertex i < fed->nverts is FED vertex i (same index);
 * vertices made on FED edges and inside faces follow. */
typedef struct tb_mesh {
    tb_array positions; /* tb_vec3 */
    tb_array normals;   /* tb_vec3, one per vertex, or empty when the FED has none */
    tb_array uvs;       /* tb_vec2, one per vertex, or empty when the FED has none */
    tb_array elems;     /* tb_mesh_elem */
} tb_mesh;

/* How to mesh; a zeroed struct means "one element per face where possible,
 * otherwise triangles, no size limit". */
typedef struct tb_mesh_opts {
    double max_edge;   /* > 0: no element edge longer than this (to float rounding); 0: no limit */
    double max_area;   /* > 0: no element larger; enforced as an edge bound of sqrt(max_area) */
    bool quads;        /* pair triangles into quads that pass the quad criterion */
    double planar_tol; /* relative planarity tolerance; <= 0: TB_MESH_PLANAR_TOL */
} tb_mesh_opts;

/* An empty mesh. */
void tb_mesh_init(tb_mesh *m);

/* Frees a mesh's storage (it stays a valid empty mesh). */
void tb_mesh_free(tb_mesh *m);

/* Number of elements. */
static inline size_t tb_mesh_nelems(const tb_mesh *m) { return m->elems.len; }

/* Element i. */
static inline const tb_mesh_elem *tb_mesh_elem_at(const tb_mesh *m, size_t i)
{
    return &TB_ARRAY_AT(&m->elems, tb_mesh_elem, i);
}

/* Corners of element e: 3 or 4. */
static inline int tb_mesh_elem_size(const tb_mesh_elem *e) { return e->v[3] == TB_MESH_NONE ? 3 : 4; }

/* Area of element i (quads: half the length of the Newell normal). */
double tb_mesh_elem_area(const tb_mesh *m, size_t i);

/* Meshes every face of `fed` into `out` (emptied first):
 *  - the edge bound L = min(max_edge, sqrt(max_area)) (either may be absent)
 *    cuts each FED edge into k = ceil(length / L) equal parts;
 *  - a triangle whose three edges have the same k becomes the regular
 *    k x k subdivision; a planar convex quad whose opposite edges have the
 *    same k becomes a bilinear grid;
 *  - a non-planar quad is first split along tb_quad_split_diagonal;
 *  - any other face (holes, n-gons, mismatched k) is triangulated
 *    (tb_triangulate_3d) and then refined by longest-edge bisection of its
 *    interior edges until none is longer than L;
 *  - with opts->quads, adjacent triangles of a face are paired into quads
 *    that pass tb_mesh_quad_check, best first; grid quads that fail it are
 *    split.
 * TB_ERR_ARG if L would make more than 2^31 elements or is below the
 * float resolution of the mesh; TB_ERR_NOMEM. */
tb_status tb_mesh_from_fed(const tb_fed *fed, const tb_mesh_opts *opts, tb_mesh *out);

/* The elements as a FED mesh: face i = element i, with the same vertex
 * indices and positions, and with `attributes` the per-vertex normals and uvs
 * the mesh has. TB_ERR_FORMAT if an element is degenerate. */
tb_status tb_mesh_to_fed(const tb_mesh *m, bool attributes, tb_fed **out);

/* tb_mesh_to_fed without the attributes: its edges, edge uses and
 * vertex-face lists are the element adjacency (the neighbour across an edge,
 * the elements around a vertex) that adaptive refinement needs
 * (docs/meshing.md, "Adaptive refinement"). */
tb_status tb_mesh_adjacency(const tb_mesh *m, tb_fed **out);

/* The quad criterion (docs/meshing.md, "Quads"): the quad q[0..3] is
 * planar within rel_tol (<= 0: TB_MESH_PLANAR_TOL) and strictly convex,
 * with every interior angle, measured about its Newell normal, within
 * [TB_MESH_QUAD_MIN_ANGLE, 180 - TB_MESH_QUAD_MIN_ANGLE] degrees. On
 * success *score (if not NULL) is the largest deviation of an angle from 90
 * degrees, in radians (0 for a rectangle; lower is better). */
bool tb_mesh_quad_check(const tb_vec3 q[4], double rel_tol, double *score);

/* Appends a new vertex's normal and uv (for whichever of the two arrays m
 * has) as the combination of vertices idx[0..n): weights w[i], or equal weights
 * 1/n when w is NULL; the normal is renormalised (vertex idx[0]'s when the sum
 * is zero). Shared by meshing and refinement so both interpolate alike. */
tb_status tb_mesh_push_attributes(tb_mesh *m, int n, const uint32_t *idx, const double *w);

/* Is the quad of vertices v[0..3] of m strictly convex about its Newell
 * normal? (Slightly non-planar quads pass: refinement splits them as
 * bilinear patches.) */
bool tb_mesh_quad_convex(const tb_mesh *m, const uint32_t v[4]);

#endif
