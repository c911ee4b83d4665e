/* Adaptive subdivision for the radiosity solver (Cohen, Greenberg, Immel
 * and Brock 1986, "An efficient radiosity approach for realistic image
 * synthesis"; docs/radiosity.md, "Adaptive subdivision"):
 *
 *     tb_rad_adapt_options a = {.threshold = 0.1, .max_levels = 4};
 *     tb_rad_solver *s;
 *     tb_rad_adapt_solve(&mesh, &opt, &stop, &a, &s, &stats);
 *     ... s is an ordinary solver over the refined mesh, now also in mesh ...
 *
 * Rounds of: solve (tb_rad_solver_run to `stop`), mark the elements whose
 * reflected radiosity varies too much across their corners, refine them
 * conformingly (util/mesh/refine.h), carry the solution over to the new
 * mesh, and continue shooting. The patches (the elements of the input
 * mesh) keep what they shot; what a new receiver point has received from
 * them is gathered again, so the refined elements see the shadow edges
 * the coarse ones averaged away. */
#ifndef TB_HOST_RADIOSITY_ADAPTIVE_H
#define TB_HOST_RADIOSITY_ADAPTIVE_H

#include <stddef.h>
#include <stdint.h>

#include "host/radiosity/radiosity.h"
#include "util/base/error.h"
#include "util/container/array.h"

/* Default number of refinement levels below the input mesh. */
#define TB_RAD_ADAPT_DEFAULT_LEVELS 4

/* Most refinement levels (util/mesh/refine.h's TB_MESH_REFINE_MAX_LEVEL). */
#define TB_RAD_ADAPT_MAX_LEVELS 60

/* Adaptive subdivision options. */
typedef struct tb_rad_adapt_options {
    double threshold; /* > 0: split an element whose corner luminances of reflected radiosity differ by more
                         than this fraction of the largest element luminance of reflected radiosity */
    int max_levels;   /* splits below an input element at most (0: TB_RAD_ADAPT_DEFAULT_LEVELS; <= TB_RAD_ADAPT_MAX_LEVELS) */
    double min_area;  /* elements of at most this area are never split (0: no limit) */
} tb_rad_adapt_options;

/* What tb_rad_adapt_solve did. */
typedef struct tb_rad_adapt_stats {
    int rounds;                /* refinement rounds done (0: nothing was marked) */
    size_t elems_in, elems_out;/* element counts of the input and the final mesh */
    size_t marked;             /* elements marked over all rounds */
    size_t gathered;           /* receivers (vertices, or elements with the hemicube) gathered anew */
    uint64_t shots;            /* shots over all rounds */
    double seconds;            /* wall seconds over all rounds, solving and refining */
} tb_rad_adapt_stats;

/* The subdivision criterion on a solver's current solution: appends to
 * `marked` (uint32_t, emptied first) every element i with level[i] <
 * max_levels (level NULL: all at 0), area > min_area and
 * (max - min over its corners of Y(rho H_v)) > threshold * max over the
 * elements of Y(rho H_e), Y the luminance of the channels (linear sRGB
 * for RGB, CIE Y of the bands when spectral). Emission is left out:
 * emitters are uniform and would dwarf the reflected light. */
tb_status tb_rad_adapt_mark(const tb_rad_solver *s, double threshold, double min_area, const uint32_t *level,
                            int max_levels, tb_array *marked);

/* Solves `mesh` adaptively (see the top of this file) with solver options
 * `opt` and stop condition `stop` in every round, returns the final
 * solver in *out (free with tb_rad_solver_free) and replaces *mesh by the
 * refined mesh (a copy of the solver's). Elements of the refined mesh have
 * the object, reflectance and emission of the element they were split from
 * and, as `parent`, the input element they lie in (TB_RAD_NONE for input
 * elements left whole); the input's vertices keep their indices.
 * Deterministic: the marks, the refinement and the gathering do not depend
 * on the thread count. TB_ERR_ARG for bad options or a mesh the refiner
 * refuses (it must be conforming, with convex quads); the solver's
 * errors; on failure *mesh is unchanged. `stats` may be NULL. */
tb_status tb_rad_adapt_solve(tb_rad_mesh *mesh, const tb_rad_options *opt, const tb_rad_stop *stop,
                             const tb_rad_adapt_options *aopt, tb_rad_solver **out, tb_rad_adapt_stats *stats);

struct tb_rad_persist;

/* tb_rad_adapt_solve with checkpoints (host/radiosity/render.h): a saved
 * state (persist->load) is continued: the mesh is rebuilt by the saved
 * rounds' refinements of the input mesh (each round's marked elements) and
 * the solver takes the saved state, so the end is that of an uninterrupted
 * solve, bit for bit; persist->save gets the rounds after every shot and
 * after the last. persist NULL: tb_rad_adapt_solve. */
tb_status tb_rad_adapt_solve_persist(tb_rad_mesh *mesh, const tb_rad_options *opt, const tb_rad_stop *stop,
                                     const tb_rad_adapt_options *aopt, const struct tb_rad_persist *persist,
                                     tb_rad_solver **out, tb_rad_adapt_stats *stats);

#endif
