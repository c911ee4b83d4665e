/* Conforming adaptive refinement of element meshes (docs/meshing.md,
 * "Adaptive refinement"): red-green refinement with a refinement tree.
 *
 * Marked elements are split "red" (a triangle into 4 by its edge
 * midpoints, a quad into 4 by its edge midpoints and centre), so red
 * children are similar to their parent (triangles exactly, quads tend to
 * parallelograms). The red elements form a 1-irregular mesh: an edge is
 * split at most once more than the edges around it, which is kept by
 * refining a coarser neighbour first when needed. Hanging midpoints are
 * then closed "green": a triangle with one split side is cut in 2 from the
 * midpoint; a quad with one split side is fanned into 3 triangles from it,
 * with two opposite ones cut into 2 quads, with two adjacent ones into the
 * corner triangle and a fan of 3 from the opposite corner. A leaf with
 * more split sides (a triangle with 2, a quad with 3 or 4) is refined red
 * instead. Green elements are never refined themselves: marking one
 * refines its red parent, which replaces
 * the closure (the green split is undone). So every element is a red
 * descendant of an input element, or one of its few green splits, and
 * element shapes stay bounded however often one spot is refined; no
 * T-vertex remains after each call.
 *
 * The refiner keeps the tree between calls, so it must be the only source
 * of the meshes it refines. Vertex indices are stable: vertices are only
 * ever appended. */
#ifndef TB_UTIL_MESH_REFINE_H
#define TB_UTIL_MESH_REFINE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "util/base/error.h"
#include "util/container/array.h"
#include "util/mesh/mesh.h"

/* Deepest red level an element may reach (the float resolution of the
 * coordinates usually stops refinement before). */
#define TB_MESH_REFINE_MAX_LEVEL 60

/* A refinement tree over a base mesh, and the current conforming mesh. */
typedef struct tb_mesh_refiner tb_mesh_refiner;

/* What one tb_mesh_refine call did. */
typedef struct tb_mesh_refine_stats {
    uint32_t marked;   /* distinct marked elements */
    uint32_t red;      /* red splits, all causes */
    uint32_t graded;   /* of which splits of a coarser neighbour to keep the mesh 1-irregular */
    uint32_t closure;  /* of which splits of a leaf with too many split sides to close green */
    uint32_t green;    /* green (closure) elements in the resulting mesh */
    uint32_t new_vertices;
} tb_mesh_refine_stats;

/* A refiner whose current mesh is a copy of `base`. `base` must be a
 * conforming element mesh (as tb_mesh_from_fed makes): TB_ERR_FORMAT for a
 * degenerate element (repeated vertex, zero-length edge, zero area), a quad
 * that is not strictly convex about its Newell normal (slightly non-planar
 * ones are accepted), a vertex index out of range, or
 * non-finite positions; TB_ERR_ARG for normal/uv arrays of the wrong
 * length; TB_ERR_NOMEM. */
tb_status tb_mesh_refiner_create(const tb_mesh *base, tb_mesh_refiner **out);

/* Frees a refiner (NULL is allowed). */
void tb_mesh_refiner_free(tb_mesh_refiner *r);

/* The current conforming mesh (owned by the refiner; valid until the next
 * tb_mesh_refine or tb_mesh_refiner_free). Element `parent` fields: for
 * elements made by the last tb_mesh_refine, the element of the previous
 * mesh they were split from; TB_MESH_NONE for elements carried over
 * unchanged; after creation, the base mesh's own values. */
const tb_mesh *tb_mesh_refiner_mesh(const tb_mesh_refiner *r);

/* Refines the elements `marked[0 .. nmarked-1]` (indices into the current
 * mesh, any order, repeats allowed) and rebuilds the current mesh, which
 * is conforming again. Marked red elements at TB_MESH_REFINE_MAX_LEVEL are
 * left as they are. If old_of_new is not NULL it becomes (uint32_t) for
 * every new element the previous element containing its centroid, so
 * per-element values can be carried over. The result depends only on the
 * set of marked elements. TB_ERR_ARG for an index out of range or an
 * element too small to split at float resolution, TB_ERR_NOMEM; on failure
 * the refiner and its mesh are unchanged. `stats` may be NULL. */
tb_status tb_mesh_refine(tb_mesh_refiner *r, const uint32_t *marked, size_t nmarked, tb_array *old_of_new,
                         tb_mesh_refine_stats *stats);

/* Red level of element i of the current mesh (0 for base elements; a green
 * element has its red parent's level). */
uint32_t tb_mesh_refiner_level(const tb_mesh_refiner *r, size_t i);

/* The base-mesh element that element i of the current mesh lies in. */
uint32_t tb_mesh_refiner_base(const tb_mesh_refiner *r, size_t i);

/* True if element i of the current mesh is a green (closure) element. */
bool tb_mesh_refiner_is_green(const tb_mesh_refiner *r, size_t i);

#endif
