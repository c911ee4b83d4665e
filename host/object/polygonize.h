/* Polygonal approximation of every primitive as a FED mesh (util/mesh/fed.h)
 * at a requested resolution (docs/primitives.md, "Tessellation").
 *
 * Each face of the mesh carries the parametric face ID it approximates
 * (fed->face_ids, host/object/param.h), every vertex lies on the analytic
 * surface (it is tb_param_eval of its (face, u, v), rounded to float) and
 * carries that point's unit normal and (u, v). Closed solids give closed,
 * consistently outward-oriented meshes: every edge used exactly twice, once
 * in each direction (tb_fed_is_closed), with vertices shared across seams,
 * poles and the edges between faces. The mesh is in object space. */
#ifndef TB_HOST_OBJECT_POLYGONIZE_H
#define TB_HOST_OBJECT_POLYGONIZE_H

#include <stdbool.h>

#include "host/mid/mid.h"
#include "util/base/error.h"
#include "util/math/transform.h"
#include "util/mesh/fed.h"

/* Default angular tolerance (radians) when neither limit is given: 15 degrees. */
#define TB_POLY_DEFAULT_ANGLE 0.2617993877991494

/* Default and largest number of segments along one parametric direction of
 * one face. */
#define TB_POLY_DEFAULT_SEGMENTS 4096
#define TB_POLY_MAX_SEGMENTS 4096

/* What resolution to tessellate at (zero fields mean "default"). */
typedef struct tb_poly_options {
    double max_edge;  /* longest mesh edge, > 0; 0: no length limit. Object-space units, or
                         world units when to_world is set */
    double max_angle; /* largest angle (radians) between the normals of adjacent facets of one
                         curved face; 0: TB_POLY_DEFAULT_ANGLE if max_edge is 0, else no limit */
    const tb_transform *to_world; /* if set, max_edge is measured in world space (through the
                                     transform's largest stretch); the mesh stays in object space */
    int max_segments; /* cap on segments per parametric direction of a face; 0: TB_POLY_DEFAULT_SEGMENTS */
    bool split;       /* false: one vertex per surface point (closed mesh; at a crease the normal
                         is the normalised sum of the faces' normals, (u, v) that of the lowest
                         face ID, u = 0 at a seam). true: one vertex per (point, face, u, v), so
                         every corner has its face's exact normal and (u, v); positions along
                         shared boundaries stay bit-identical (no cracks), but the FED edges
                         there are not shared (not tb_fed_is_closed) */
} tb_poly_options;

/* Tessellates the primitive. *out gets a new mesh (free with tb_fed_free).
 * opt NULL: defaults. TB_ERR_ARG for invalid geometry or options (negative
 * or non-finite limits), TB_ERR_UNSUPPORTED for CSG nodes (not tessellated;
 * see docs) and for polygons given as a FED mesh file (already a mesh),
 * TB_ERR_NOMEM. */
tb_status tb_polygonize(tb_prim_kind kind, const tb_mid_geometry *geom, const tb_poly_options *opt, tb_fed **out);


typedef struct tb_object tb_object;

/* Polygonal approximation of a built object (host/object/object.h), a
 * primitive or a CSG tree, in WORLD space (docs/primitives.md, "Tessellating
 * CSG trees"): every leaf is tessellated with `opt` (max_edge in world units),
 * each leaf triangle is kept, flipped (subtracted surfaces: normals out of
 * the result) or dropped by probing the tree along its normal, and triangles
 * whose samples disagree are split 4 ways, midpoints projected onto the
 * leaf's surface, until their longest world edge is at most csg_edge (> 0).
 * A lone primitive is emitted whole; polygons (FED holes included) come
 * from the object's triangulated mesh.
 * Guarantees: every output vertex is a point of a leaf's surface (a leaf
 * tessellation vertex or a projected midpoint, float), and every output
 * triangle whose samples all agree lies on the CSG boundary; along the curves
 * where surfaces meet, triangles of at most csg_edge are kept or dropped by
 * their centroid, so the result overshoots or leaves gaps there of width at
 * most csg_edge. A triangle soup: no vertex is shared, the mesh is not
 * watertight. Faces carry the tree's face IDs (leaf face_base + local face).
 * TB_ERR_ARG for a bad csg_edge or options, TB_ERR_NOMEM, and the errors of
 * tb_polygonize. */
tb_status tb_polygonize_object(const tb_object *obj, const tb_poly_options *opt, double csg_edge, tb_fed **out);

#endif
