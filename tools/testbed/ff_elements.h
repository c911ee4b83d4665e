/* A scene as the radiosity renderer sees it, for `testbed validate --kernel
 * formfactor` and `testbed bench formfactor`: every object polygonized in
 * world space (tb_polygonize_object) and meshed into planar triangle and quad
 * elements (tb_mesh_from_fed), receivers at the element centroids and
 * corners, and a choice of shooters (docs/gpu.md, "Form-factor kernel"). */
#ifndef TB_TOOLS_TESTBED_FF_ELEMENTS_H
#define TB_TOOLS_TESTBED_FF_ELEMENTS_H

#include <stddef.h>
#include <stdint.h>

#include "host/gpu/gpu.h"
#include "host/radiosity/formfactor.h"
#include "host/render/scene.h"

/* Elements (also the occluders) and receivers of a scene. */
typedef struct tb_ffe_set {
    size_t n;             /* elements */
    tb_ff_polygon *polys; /* n elements, counter-clockwise seen from the front */
    tb_vec3 *normal;      /* n unit normals (tb_ff_polygon_frame) */
    double *area;         /* n areas */
    uint32_t *object;     /* n top-level object indices */
    size_t nrecv;         /* receivers */
    tb_vec3 *rp, *rn;     /* nrecv points and unit normals: element centroids, then element corners
                             (each mesh vertex once, with the normal of the first element using it) */
    uint32_t skipped;     /* objects that could not be polygonized (reported, not used) */
} tb_ffe_set;

/* Default element edge: the scene's bounding-box diagonal over this (the
 * Cornell box: about 1,200 elements). */
#define TB_FFE_EDGE_DIVISOR 24.0

/* Meshes every object of `s` with elements no longer than max_edge (world
 * units, > 0) along any edge; objects that cannot be polygonized are
 * counted in `skipped`, and a scene may give no element (n = 0).
 * TB_ERR_ARG for a bad max_edge, TB_ERR_NOMEM. Free with tb_ffe_free. */
tb_status tb_ffe_build(const tb_scene *s, double max_edge, tb_ffe_set *out);

/* Frees the arrays. */
void tb_ffe_free(tb_ffe_set *e);

/* Keeps at most `max` receivers, a random subset (PCG32, `seed`) in their
 * original order; nothing changes when there are not more. */
void tb_ffe_subsample(tb_ffe_set *e, size_t max, uint64_t seed);

/* Picks up to `count` distinct shooters (element indices) into out: first
 * elements of emissive objects (the first shots of a radiosity solution),
 * at most half of them (rounded up), then elements drawn at random (PCG32,
 * `seed`).
 * Returns how many were chosen (min(count, e->n)). */
size_t tb_ffe_shooters(const tb_ffe_set *e, const tb_scene *s, size_t count, uint64_t seed, uint32_t *out);

/* `testbed validate --kernel formfactor` on a loaded scene with the session's
 * device (cmd_validate_formfactor.c): prints the agreement figures, sets *ok
 * when they are within tolerance; returns TB_EXIT_FAIL on an error (message
 * printed), else TB_EXIT_OK. */
int tb_validate_formfactor(const tb_scene *s, tb_gpu_session *sess, long shooters, long samples, long receivers,
                           long seed, bool *ok);

#endif
