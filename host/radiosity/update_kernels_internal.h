/* The bodies of the update kernels (update_internal.h), inlined by update.c
 * and by update_avx.c (built with -mavx): one source, two instruction sets. */
#ifndef TB_RADIOSITY_UPDATE_KERNELS_INTERNAL_H
#define TB_RADIOSITY_UPDATE_KERNELS_INTERNAL_H

#include "host/radiosity/update_internal.h"

static inline void tb__rad_update_vertices_body(const tb__rad_update *u, size_t v0, size_t v1)
{
    const size_t nc = u->nc;
    const double *restrict dBi = u->dBi;
    const float *restrict vff = u->vff;
    double *restrict Hv = u->Hv;
    for (size_t v = v0; v < v1; v++) {
        double f = vff[v];
        if (f != 0.0)
            for (size_t c = 0; c < nc; c++)
                Hv[v * nc + c] += dBi[c] * f;
    }
}

static inline void tb__rad_update_elements_body(const tb__rad_update *u, size_t q0, size_t q1)
{
    const size_t nc = u->nc;
    const double *restrict dBi = u->dBi;
    const float *restrict eff = u->eff, *restrict rho = u->rho;
    double *restrict He = u->He, *restrict dB = u->dB;
    /* one loop per kind of update (He and dB, one of them), the branch
     * outside: each value gets the same products in the same order */
    if (He && dB) {
        for (size_t q = q0; q < q1; q++) {
            size_t j = u->pel[q];
            double g = eff[j];
            if (u->pof[j] == u->shooter || !(g > 0.0))
                continue;
            for (size_t c = 0; c < nc; c++) {
                double dh = dBi[c] * g, r = rho[j * nc + c];
                He[j * nc + c] += dh;
                dB[j * nc + c] += r * dh;
            }
        }
    } else if (He) {
        for (size_t q = q0; q < q1; q++) {
            size_t j = u->pel[q];
            double g = eff[j];
            if (u->pof[j] == u->shooter || !(g > 0.0))
                continue;
            for (size_t c = 0; c < nc; c++)
                He[j * nc + c] += dBi[c] * g;
        }
    } else if (dB) {
        for (size_t q = q0; q < q1; q++) {
            size_t j = u->pel[q];
            double g = eff[j];
            if (u->pof[j] == u->shooter || !(g > 0.0))
                continue;
            for (size_t c = 0; c < nc; c++) {
                double dh = dBi[c] * g, r = rho[j * nc + c];
                dB[j * nc + c] += r * dh;
            }
        }
    }
}

#endif
