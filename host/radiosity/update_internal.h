/* The per-shot update of the ray-cast solver over its channels
 * (solver.c, tb__shoot): the vector part, over ranges of vertices and
 * elements, so that threads can share it and the CPU's widest vectors
 * (AVX where it has them) can do it. Every value is its own sum of the
 * same products in the same order: any split, and either instruction set,
 * gives the same bits (no fused multiply-add: the build has
 * -ffp-contract=off). */
#ifndef TB_RADIOSITY_UPDATE_INTERNAL_H
#define TB_RADIOSITY_UPDATE_INTERNAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* What one shot adds to every receiver (the arrays of tb_rad_solver). */
typedef struct tb__rad_update {
    size_t nc;             /* channels */
    const double *dBi;     /* nc: the shooter's unshot radiosity */
    const float *vff;      /* per vertex: F(v -> shooter) */
    const float *eff;      /* per element: F_ji */
    const uint32_t *pel;   /* the elements in shooter order */
    const uint32_t *pof;   /* per element: its shooter */
    uint32_t shooter;      /* whose elements receive nothing */
    const float *rho;      /* per element: nc reflectances */
    double *Hv, *He, *dB;  /* per vertex / element: nc values each; He or dB NULL: that one is left alone */
} tb__rad_update;

/* Hv[v] += dBi F(v) for the vertices v in [v0, v1) with F(v) != 0. */
void tb__rad_update_vertices(const tb__rad_update *u, size_t v0, size_t v1);

/* For the elements pel[q], q in [q0, q1), that receive (F_ji > 0, not the
 * shooter's): He[j] += dBi F_ji and dB[j] += rho_j dBi F_ji (only the one
 * of the two that is not NULL: the solver defers He, see tb__defer_flush). */
void tb__rad_update_elements(const tb__rad_update *u, size_t q0, size_t q1);

/* The same two, built with -mavx (update_avx.c; call only where the CPU has AVX). */
void tb__rad_update_vertices_avx(const tb__rad_update *u, size_t v0, size_t v1);
void tb__rad_update_elements_avx(const tb__rad_update *u, size_t q0, size_t q1);

/* Whether this CPU runs the _avx kernels (and this build has them). */
bool tb__rad_have_avx(void);

#endif
