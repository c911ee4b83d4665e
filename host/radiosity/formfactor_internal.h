/* Internals shared by the form-factor files (formfactor.c, formfactor_raycast.c,
 * formfactor_hemicube.c). Not installed. */
#ifndef TB_HOST_RADIOSITY_FORMFACTOR_INTERNAL_H
#define TB_HOST_RADIOSITY_FORMFACTOR_INTERNAL_H

#include "host/radiosity/formfactor.h"
#include "util/math/vec.h"

/* A float vector in double (exact). */
static inline tb_dvec3 tb__ff_d(tb_vec3 a) { return (tb_dvec3){a.x, a.y, a.z}; }

/* Newell's vector of the polygon in double: twice the area times the unit
 * normal (zero for a degenerate polygon or n outside 3..4). */
tb_dvec3 tb__ff_newell(const tb_ff_polygon *poly);

/* True if the polygon has 3 or 4 finite corners and an area that is not
 * negligible against its longest edge (area > 1e-12 * edge^2). */
bool tb__ff_polygon_ok(const tb_ff_polygon *poly);

/* tb_ff_point_polygon; when it is positive, *seen (if not NULL) is a point
 * inside the part of the polygon in front of p's tangent plane (the mean of
 * the clipped polygon's corners), else p. */
double tb__ff_point_polygon_ex(tb_vec3 p, tb_vec3 n, const tb_ff_polygon *poly, tb_vec3 *seen);

#endif
