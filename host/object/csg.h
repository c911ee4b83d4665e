/* CSG: union, intersection and difference of solids through interval lists
 * along the ray (docs/primitives.md, "CSG").
 *
 * Every child gives the sorted intervals of the ray's whole line inside it,
 * with the surface (leaf primitive, face, normal) at each end; a node sweeps
 * its children's ends in order of t and keeps an end where the node's own
 * membership changes. The rules for surfaces that coincide are fixed:
 *
 *  - Ends of different children closer than TB_CSG_COINCIDENT_REL (relative,
 *    see below) are one event: all their changes are applied together, and
 *    the node reports an end only if its membership differs before and after
 *    the whole batch. So A u A = A, A n A = A, A - A is empty, two solids
 *    sharing a face have no surface inside their union, and a solid minus one
 *    that shares a face with it from inside leaves that face open.
 *  - When a batch changes the membership, the surface reported is that of the
 *    lowest-numbered child (MID order) whose own change agrees with the
 *    node's (an entry, or for a subtracted child an exit); within that child,
 *    the first end in t.
 *  - A subtracted child's surfaces are reported with their normals flipped,
 *    so the normal always points out of the result.
 *  - The same batching also removes a child's own intervals shorter than the
 *    tolerance (a tangent touch, or a sliver thinner than it).
 *
 * Children must be closed solids (checked when the object is built). */
#ifndef TB_HOST_OBJECT_CSG_H
#define TB_HOST_OBJECT_CSG_H

#include "host/object/object.h"
#include "util/math/ray.h"

/* Two crossings at t1 <= t2 coincide when t2 - t1 <= TB_CSG_COINCIDENT_REL *
 * (|o|max / |d|max + |t1|), o and d the world ray's origin and direction
 * (max-norms): about 10^4 times the double rounding of the intersection
 * computations, far below float resolution. */
#define TB_CSG_COINCIDENT_REL 0x1p-40

/* The intervals of the ray's whole line (t from -inf to +inf; tmin and tmax
 * are ignored) inside the solid `obj` (a closed primitive or a CSG tree), as
 * sorted pairs t_in[i] <= t_out[i]; at most `max` are written, and the number
 * of intervals is returned (it may exceed max). 0 for an invalid ray, an
 * object that is not a closed solid, or when out of memory. */
int tb_object_intervals(const tb_object *obj, const tb_ray *ray, float *t_in, float *t_out, int max);

#endif
