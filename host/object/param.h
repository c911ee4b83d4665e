/* Parametric coordinates of every primitive: a face ID and (u, v) in [0,1]^2
 * per point of the surface, both ways (docs/primitives.md, "Parametric
 * coordinates", has the formulas of every face).
 *
 * Everything works in the primitive's canonical object space (docs/mid.md,
 * section 6.3) on (kind, geometry); the _world wrappers take points from and
 * give results in world space through the object's transform.
 *
 * Conventions shared by all kinds:
 *  - dp/du x dp/dv points out of the solid (for polygons: to the front side),
 *    so (u, v) is a right-handed frame seen from outside;
 *  - surfaces of revolution about z (sphere, cylinder, cone, conic, torus) take
 *    u = phi / 2 pi with phi = atan2(y, x) in [0, 2 pi): u = 0 on the +x half
 *    plane (the seam), increasing counter-clockwise seen from +z;
 *  - along a closed profile v runs from the bottom to the top: bottom cap from
 *    its centre (v = 0) to its rim (v = 1), the side from bottom (0) to top
 *    (1), the top cap from its rim (0) to its centre (1);
 *  - at a pole or a cap centre (where u is undefined) tb_param_from_point
 *    returns u = 0, and tb_param_eval returns the limit normal and a zero
 *    dp/du there.
 * Scalars are double throughout: the round trip is exact to ~1e-15 relative.
 */
#ifndef TB_HOST_OBJECT_PARAM_H
#define TB_HOST_OBJECT_PARAM_H

#include <stdbool.h>

#include "host/mid/mid.h"
#include "util/base/error.h"
#include "util/math/transform.h"
#include "util/math/vec.h"

/* ------------------------------------------------------------------ face IDs */

/* sphere: one face. */
enum { TB_FACE_SPHERE = 0 };

/* cube: one face per side, numbered -x, +x, -y, +y, -z, +z. */
enum {
    TB_FACE_CUBE_NEG_X = 0,
    TB_FACE_CUBE_POS_X = 1,
    TB_FACE_CUBE_NEG_Y = 2,
    TB_FACE_CUBE_POS_Y = 3,
    TB_FACE_CUBE_NEG_Z = 4,
    TB_FACE_CUBE_POS_Z = 5,
};

/* cylinder: side, and the caps when geometry.cylinder.caps. */
enum {
    TB_FACE_CYLINDER_SIDE = 0,
    TB_FACE_CYLINDER_BOTTOM = 1, /* disc at z = -1 */
    TB_FACE_CYLINDER_TOP = 2,    /* disc at z = +1 */
};

/* cone (and frustum): side, base, and top disc when top_radius > 0. */
enum {
    TB_FACE_CONE_SIDE = 0,
    TB_FACE_CONE_BOTTOM = 1, /* base disc at z = -1, radius 1 */
    TB_FACE_CONE_TOP = 2,    /* top disc at z = 1, radius top_radius (frustum with caps only) */
};

/* pyramid (and frustum): the four sides as the cube's, base and top square. */
enum {
    TB_FACE_PYRAMID_NEG_X = 0, /* side facing -x */
    TB_FACE_PYRAMID_POS_X = 1,
    TB_FACE_PYRAMID_NEG_Y = 2,
    TB_FACE_PYRAMID_POS_Y = 3,
    TB_FACE_PYRAMID_BOTTOM = 4, /* base square at z = -1 */
    TB_FACE_PYRAMID_TOP = 5,    /* top square at z = 1 (frustum with caps only) */
};

/* prism: caps first, then side k = TB_FACE_PRISM_SIDE0 + k for the edge from
 * profile point k to k + 1 (mod n), in the order the profile (or the regular
 * polygon, k = 0..sides-1) gives its points. */
enum {
    TB_FACE_PRISM_BOTTOM = 0, /* z = -1 */
    TB_FACE_PRISM_TOP = 1,    /* z = +1 */
    TB_FACE_PRISM_SIDE0 = 2,
};

/* torus: one face. */
enum { TB_FACE_TORUS = 0 };

/* conic: side, and the caps at z0 / z1 where the radius there is > 0. */
enum {
    TB_FACE_CONIC_SIDE = 0,
    TB_FACE_CONIC_BOTTOM = 1, /* disc at z0 */
    TB_FACE_CONIC_TOP = 2,    /* disc at z1 */
};

/* square_arch and round_arch: the six outer faces numbered as the cube's (the
 * -y/+y faces and the bottom have the opening cut out), then the opening. */
enum {
    TB_FACE_ARCH_NEG_X = 0,
    TB_FACE_ARCH_POS_X = 1,
    TB_FACE_ARCH_NEG_Y = 2,       /* front, y = -1 */
    TB_FACE_ARCH_POS_Y = 3,       /* back, y = +1 */
    TB_FACE_ARCH_BOTTOM = 4,      /* z = -1: the two feet */
    TB_FACE_ARCH_TOP = 5,         /* z = +1 */
    TB_FACE_ARCH_INNER_LEFT = 6,  /* wall x = -w/2 of the opening (faces +x) */
    TB_FACE_ARCH_INNER_RIGHT = 7, /* wall x = +w/2 of the opening (faces -x) */
    TB_FACE_ARCH_CEILING = 8,     /* square: flat ceiling z = -1 + h; round: the half-cylinder vault */
};

/* Number of arch face IDs (0 .. TB_FACE_ARCH_CEILING). */
#define TB_FACE_ARCH_COUNT 9

/* polygons: the face ID is the polygon's index (0 .. nfaces - 1). */

/* --------------------------------------------------------------- functions */

/* TB_OK if `geom` holds valid parameters for `kind` (docs/mid.md, 6.3: the
 * ranges the reader enforces), else TB_ERR_ARG with a message;
 * TB_ERR_UNSUPPORTED for polygons given as a FED mesh file (the functions
 * here take inline polygons; the object level converts a loaded mesh). */
tb_status tb_param_check(tb_prim_kind kind, const tb_mid_geometry *geom);

/* Number of points of a prism's polygon (sides, or profile points). */
int tb_param_prism_npoints(const tb_geom_prism *g);

/* Point k (taken mod n) of a prism's polygon: (cos 2 pi k/n, sin 2 pi k/n) for
 * a regular one (exactly (1, 0) for k = 0), else profile[k]. The one formula
 * param, bounds and polygonize all use. */
void tb_param_prism_point(const tb_geom_prism *g, int k, double *x, double *y);

/* True if the prism's polygon turns counter-clockwise (positive area). */
bool tb_param_prism_ccw(const tb_geom_prism *g);

/* r^2 = c0 + c1 z + c2 z^2 of a conic at height z, by compensated Horner
 * evaluation (error-free products and sums): accurate to a few ulps of the
 * result even where the terms cancel (near a pole or a narrow waist), where
 * plain evaluation would leave r off by sqrt of the rounding. A value within
 * 1e-12 of |c0| + |c1 z| + |c2 z^2| is returned as 0 (the MID reader's rule,
 * docs/mid.md 6.3): a pole or apex the coefficients meant stays a point. */
double tb_param_conic_r2(const tb_geom_conic *c, double z);

/* Number of face IDs of the primitive: valid IDs are 0 .. count - 1 (some may
 * be absent, see tb_param_face_present). 0 for CSG kinds and bad input. */
int tb_param_face_count(tb_prim_kind kind, const tb_mid_geometry *geom);

/* True if face `face` is part of the surface for these parameters (a cap with
 * caps = false, a cone's top with top_radius = 0, a conic cap where r = 0 and
 * a round arch's inner walls when h = w/2 are absent). */
bool tb_param_face_present(tb_prim_kind kind, const tb_mid_geometry *geom, int face);

/* Point -> (face, u, v). p is an object-space point on (or near) the surface.
 * With face_hint >= 0 (e.g. the face an intersection routine already knows)
 * that face's parameterisation is used directly; with -1 the face nearest to
 * p is chosen (ties go to the lower ID). The (u, v) of a point off the face is
 * that of its nearest point on the face (approximately, for points far from
 * it). u and v are clamped to [0, 1]. TB_ERR_ARG for a CSG kind, a
 * non-finite p, a bad hint or invalid geometry; TB_ERR_UNSUPPORTED for
 * polygons given as a FED mesh file (use the object's loaded mesh). */
tb_status tb_param_from_point(tb_prim_kind kind, const tb_mid_geometry *geom, tb_dvec3 p,
                              int face_hint, int *face, double *u, double *v);

/* (face, u, v) -> point p, unit outward normal n, and the tangents dp/du,
 * dp/dv (any output pointer may be NULL). u and v must lie in [0, 1]. For
 * faces whose (u, v) square is larger than the face (arch faces with the
 * opening, prism caps, polygons: see docs/primitives.md) the point is on the
 * face's plane, inside the face only for (u, v) in its domain. Errors as for
 * tb_param_from_point, plus TB_ERR_ARG for an absent face or u, v outside
 * [0, 1]. */
tb_status tb_param_eval(tb_prim_kind kind, const tb_mid_geometry *geom, int face, double u, double v,
                        tb_dvec3 *p, tb_dvec3 *n, tb_dvec3 *dpdu, tb_dvec3 *dpdv);

/* Distance from object-space p to face `face` (0 on the face). Used to pick
 * the nearest face; exact for points whose nearest face point is interior to
 * the face, an upper bound otherwise. INFINITY for an absent or bad face. */
double tb_param_face_distance(tb_prim_kind kind, const tb_mid_geometry *geom, int face, tb_dvec3 p);

/* tb_param_from_point for a world-space point of an object placed by
 * `to_world` (object to world). */
tb_status tb_param_from_point_world(tb_prim_kind kind, const tb_mid_geometry *geom,
                                    const tb_transform *to_world, tb_dvec3 p_world, int face_hint,
                                    int *face, double *u, double *v);

/* tb_param_eval with world-space results: the point and tangents transformed
 * by to_world, the normal by its inverse transpose and renormalised (still
 * outward under a mirroring transform). */
tb_status tb_param_eval_world(tb_prim_kind kind, const tb_mid_geometry *geom,
                              const tb_transform *to_world, int face, double u, double v,
                              tb_dvec3 *p, tb_dvec3 *n, tb_dvec3 *dpdu, tb_dvec3 *dpdv);

/* A planar polygon's (u, v) frame: origin o (its first corner), unit axes
 * e1 (along its first non-zero edge, in the plane) and e2 = n x e1, the unit
 * Newell normal n, and the bounding rectangle [s0, s0 + ds] x [t0, t0 + dt]
 * of its corners in (e1, e2) coordinates. Exposed so a caller may memoise
 * it (host/render/scene_mesh.c) and still get tb_param_from_point's (u, v)
 * bit for bit. */
#define TB_POLY_FRAME_CORNERS 8

typedef struct tb_poly_frame {
    tb_dvec3 o, e1, e2, n;
    double s0, ds, t0, dt;
    int ncst;                               /* corners whose (s, t) are kept below: nv if nv <= 8, else 0 */
    double cst[TB_POLY_FRAME_CORNERS][2];   /* corner i's (s, t), as the (u, v) functions would recompute them */
} tb_poly_frame;

/* The frame of the loop of nv >= 3 corners v[idx[i]] (v[i] when idx is NULL);
 * false when the loop has no area (its Newell normal is zero or not finite).
 * The functions below take the frame with the same loop it was made from. */
bool tb_poly_frame_make(const tb_vec3 *v, const int *idx, int nv, tb_poly_frame *f);

/* (u, v) of p for a polygon without uvs, as tb_param_from_point gives it:
 * the nearest point of the loop (v, idx, nv as for tb_poly_frame_make) in
 * the frame's plane, scaled to the frame's rectangle and clamped to [0, 1]. */
void tb_poly_frame_uv(const tb_poly_frame *f, const tb_vec3 *v, const int *idx, int nv, tb_dvec3 p, double *u,
                      double *w);

/* Whether the loop (v, idx, nv as for tb_poly_frame_make) turns the same way
 * at every corner in the frame's plane, as tb_param_from_point decides it
 * (a convex loop is split as the fan from corner 0, else ear-clipped). */
bool tb_poly_frame_convex(const tb_poly_frame *f, const tb_vec3 *v, const int *idx, int nv);

/* (u, v) of p for a convex polygon with per-vertex uvs (uvs indexed like v),
 * as tb_param_from_point gives it: the nearest point of the loop, then the
 * uvs of the fan triangle holding it (or coming closest), clamped to [0, 1].
 * Exposed for the same memo as tb_poly_frame_uv. */
void tb_poly_fan_uv(const tb_poly_frame *f, const tb_vec3 *v, const int *idx, const tb_vec2 *uvs, int nv,
                    tb_dvec3 p, double *u, double *w);

#endif
