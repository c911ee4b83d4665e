/* From a ray-tracer hit to the radiosity element under it (docs/hybrid.md,
 * "Hit to element"): the element of the hit object's mesh nearest to the
 * hit point, the weights of its corners at that point, and values
 * interpolated with them the way the display interpolates them
 * (tb_rad_render_image: linearly over the triangles (v0 v1 v2) and
 * (v0 v2 v3) of each element).
 *
 *     tb_rad_locator *loc;
 *     tb_rad_locator_create(tb_rad_solver_mesh(solver), &loc);
 *     tb_rad_location at;
 *     if (tb_rad_locate(loc, hit.object, p, n, &at))
 *         tb_rad_location_radiosity(solver, &at, ambient, b);   // B at p
 *     tb_rad_locator_free(loc);
 *
 * Curved objects are polygonized, so a point of the true surface lies off
 * its element by up to the chord height: the element chosen is the one
 * nearest to p (Euclidean distance to its triangles) among those of the
 * object that face n's way, within a tolerance of a quarter of the
 * element's longest edge. A locator is read-only after creation: any number
 * of threads may query it; answers do not depend on the order of queries. */
#ifndef TB_HOST_RADIOSITY_LOCATE_H
#define TB_HOST_RADIOSITY_LOCATE_H

#include <stdbool.h>
#include <stdint.h>

#include "host/radiosity/radiosity.h"
#include "util/base/error.h"
#include "util/math/vec.h"

/* A per-object spatial index over a mesh's elements (opaque). */
typedef struct tb_rad_locator tb_rad_locator;

/* Where a point lies on a radiosity mesh. */
typedef struct tb_rad_location {
    uint32_t element;  /* element index in the mesh */
    uint32_t object;   /* its top-level object */
    int ncorners;      /* 3 or 4 */
    uint32_t v[4];     /* the element's vertices (v[3] == TB_RAD_NONE for a triangle) */
    double w[4];       /* corner weights, >= 0, summing to 1 (w[3] == 0 for a triangle) */
    tb_vec3 q;         /* the point of the element nearest to p: sum w[k] v[k] */
    double distance;   /* |p - q| */
} tb_rad_location;

/* A locator over the elements of `m`, which must outlive it (e.g. the
 * solver's own mesh, tb_rad_solver_mesh). TB_ERR_ARG for an empty mesh
 * without geometry (tb_rad_mesh_update_geometry), TB_ERR_NOMEM. */
tb_status tb_rad_locator_create(const tb_rad_mesh *m, tb_rad_locator **out);

/* Frees a locator; NULL is allowed. */
void tb_rad_locator_free(tb_rad_locator *l);

/* The element of object `object` under world point p, seen from the side of
 * unit normal n (elements with normal . n <= 0 are skipped; n zero: no side
 * test), into *out. False when the object has no element within tolerance
 * of p (or no elements at all, or is out of range). */
bool tb_rad_locate(const tb_rad_locator *l, uint32_t object, tb_vec3 p, tb_vec3 n, tb_rad_location *out);

/* Interpolates per-vertex values at a location: out[c] = sum_k w[k]
 * values[v[k] * nc + c], c in [0, nc). */
void tb_rad_location_interpolate(const tb_rad_location *loc, const double *values, int nc, double *out);

/* Radiosity at a location, Gouraud-interpolated from the element's corner
 * values (tb_rad_corner_radiosity): E + rho (sum_k w[k] H_v[k] + ambient),
 * out[0..nchannels). ambient: the term of tb_rad_ambient (computed once by
 * the caller: it sums over the whole mesh), or NULL for none. */
void tb_rad_location_radiosity(const tb_rad_solver *s, const tb_rad_location *loc, const double *ambient,
                               double *out);

#endif
