/* Point, spot and directional lights as sources of the radiosity solution
 * (docs/radiosity.md, "Lights"). A light shoots its power once, directly to
 * the receivers the ray-cast solver uses (every mesh vertex, moved a hair
 * into its surface as the solver moves it), with visibility through a BVH
 * of the mesh's elements (shadows) and the light's distribution exactly as
 * the ray tracer evaluates it (tb_light_intensity: isotropic or IES, the
 * spot's cone and smoothstep falloff; a directional light's irradiance E):
 *
 *   vertex v:  E_v = I(w) cos_v / d^2 x visible   (directional: E cos_v x visible)
 *   element j: E_j = (1 / A_j) sum over cells of I(w_cell) Omega_cell x vis_cell
 *
 * where the cells cut the element's triangles (v0 v1 v2), (v0 v2 v3) into
 * n x n sub-triangles (n from the element's size over its distance to the
 * light), Omega_cell is the exact solid angle a cell subtends at the light
 * (so an isotropic light's element irradiance is exactly I Omega_j / A_j
 * and a closed room receives exactly 4 pi I) and vis_cell the corners'
 * visibility interpolated linearly (the solver's rule for partly hidden
 * elements). A directional light gives E cos_j times the area mean of that
 * interpolated visibility. Units are the ray tracer's: I in W/sr, E in
 * W/m^2, lengths in scene units, so irradiance I / d^2 is "W/m^2" with d in
 * scene units, like a point light in the ray tracer.
 *
 * Everything is per channel (RGB or spectral bands) and deterministic: each
 * receiver's value depends only on its own inputs, whatever the thread count. */
#ifndef TB_HOST_RADIOSITY_LIGHTS_H
#define TB_HOST_RADIOSITY_LIGHTS_H

#include <stddef.h>

#include "host/radiosity/radiosity.h"
#include "host/render/lights.h"

/* The lights of one radiosity mesh with their occluders (opaque). */
typedef struct tb_rad_lights tb_rad_lights;

/* Lights l[0..n) (copied; an IES table is kept by pointer and must outlive
 * the result) over mesh m (geometry up to date). The occluders are the
 * elements whose plane does not have the whole mesh and every light in front
 * (tb_rad_mesh_occluders with the lights' points added). TB_ERR_ARG for a
 * light whose channel count differs from the mesh's, a bad kind or a
 * negative or non-finite intensity; TB_ERR_NOMEM. */
tb_status tb_rad_lights_create(const tb_rad_mesh *m, const tb_light *l, int n, tb_rad_lights **out);

/* Frees; NULL is allowed. */
void tb_rad_lights_free(tb_rad_lights *L);

/* Number of lights. */
int tb_rad_lights_count(const tb_rad_lights *L);

/* Power of light k per channel, out[0..nchannels) (W, or W/nm, times scene
 * units^2 / m^2): tb_light_power; a directional light's is what crosses a
 * disc of the radius of the sphere around the mesh's bounding box. */
void tb_rad_lights_power(const tb_rad_lights *L, int k, double *out);

/* One shot of light k: irradiance at every receiver vertex, ev[nverts *
 * nchannels], and mean irradiance of every element, ee[nelems * nchannels]
 * (see the file comment). OpenMP inside. */
tb_status tb_rad_lights_shoot(const tb_rad_lights *L, int k, double *ev, double *ee);

#endif
