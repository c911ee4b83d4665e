/* The watertight ray/triangle test (Woop, Benthin and Wald, JCGT 2(1), 2013)
 * in double on world-space corners (docs/primitives.md, "Watertight
 * triangles"), shared as inline code by the object level's meshes
 * (intersect_mesh.c) and the acceleration structures' triangle references
 * (host/render/accel_internal.h), so both run the same arithmetic and a
 * scene query pays no call per triangle. */
#ifndef TB_HOST_OBJECT_WATERTIGHT_H
#define TB_HOST_OBJECT_WATERTIGHT_H

#include <math.h>
#include <stdbool.h>

#include "util/math/ray.h"

/* A world ray prepared for the test: the ray becomes the z axis of a
 * sheared space. */
typedef struct tb_wt_ray {
    double o[3];        /* origin (the float origin, exact in double) */
    int kx, ky, kz;     /* kz: the direction's largest component; kx, ky swapped when d[kz] < 0 (keeps the winding) */
    double sx, sy, sz;  /* shear: d[kx] / d[kz], d[ky] / d[kz], 1 / d[kz] */
} tb_wt_ray;

/* Prepares w for ray r. */
static inline void tb_wt_ray_init(tb_wt_ray *w, const tb_ray *r)
{
    const double d[3] = {r->d.x, r->d.y, r->d.z};
    w->o[0] = r->o.x;
    w->o[1] = r->o.y;
    w->o[2] = r->o.z;
    int kz = 0;
    if (fabs(d[1]) > fabs(d[kz]))
        kz = 1;
    if (fabs(d[2]) > fabs(d[kz]))
        kz = 2;
    int kx = (kz + 1) % 3, ky = (kx + 1) % 3;
    if (d[kz] < 0.0) { /* keep the winding direction */
        int t = kx;
        kx = ky;
        ky = t;
    }
    w->kx = kx;
    w->ky = ky;
    w->kz = kz;
    w->sx = d[kx] / d[kz];
    w->sy = d[ky] / d[kz];
    w->sz = 1.0 / d[kz];
}

/* The rare case of tb_wt_triangle: an edge function came out exactly 0.
 * Recomputes the signs exactly and applies the tie rule for rays through
 * edges and vertices (intersect_mesh.c); false if the triangle is missed. */
bool tb_wt_edge_ties(double U, double V, double W, double ax, double ay, double bx, double by, double cx, double cy);

/* The test on corners v0 v1 v2 (x y z each, world space); on a hit writes
 * the line parameter t and dir (+1: the ray meets the side from which the
 * corners run counter-clockwise) and, when uvw is not NULL, the edge
 * functions U V W: the crossing is (U v0 + V v1 + W v2) / (U + V + W), all
 * three of one sign or 0 (the barycentric weights, unnormalised). The ray's
 * [tmin, tmax] is not checked. */
static inline bool tb_wt_triangle(const tb_wt_ray *w, const double *v0, const double *v1, const double *v2,
                                  double *t, int *dir, double *uvw)
{
    /* Corners relative to the origin, permuted so the ray runs along z. */
    int kx = w->kx, ky = w->ky, kz = w->kz;
    double Az = v0[kz] - w->o[kz], Bz = v1[kz] - w->o[kz], Cz = v2[kz] - w->o[kz];
    double ax = (v0[kx] - w->o[kx]) - w->sx * Az, ay = (v0[ky] - w->o[ky]) - w->sy * Az;
    double bx = (v1[kx] - w->o[kx]) - w->sx * Bz, by = (v1[ky] - w->o[ky]) - w->sy * Bz;
    double cx = (v2[kx] - w->o[kx]) - w->sx * Cz, cy = (v2[ky] - w->o[ky]) - w->sy * Cz;
    /* Edge functions; an edge shared by two triangles gets exactly opposite
     * values in both (the same products of the same sheared corners). */
    double U = cx * by - cy * bx;
    double V = ax * cy - ay * cx;
    double W = bx * ay - by * ax;
    if ((U < 0.0 || V < 0.0 || W < 0.0) && (U > 0.0 || V > 0.0 || W > 0.0))
        return false;
    if ((U == 0.0 || V == 0.0 || W == 0.0) && !tb_wt_edge_ties(U, V, W, ax, ay, bx, by, cx, cy))
        return false;
    double det = U + V + W;
    if (det == 0.0)
        return false;
    double az = w->sz * Az, bz = w->sz * Bz, cz = w->sz * Cz;
    double T = U * az + V * bz + W * cz;
    *t = T / det;
    *dir = det > 0.0 ? 1 : -1;
    if (uvw) {
        uvw[0] = U;
        uvw[1] = V;
        uvw[2] = W;
    }
    return isfinite(*t);
}

#endif
