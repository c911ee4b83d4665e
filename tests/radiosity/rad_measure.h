/* Element radiosities of a solved mesh and their error against a reference,
 * shared by the patches test and the patches benchmark (no cmocka here: the
 * benchmark is a plain program). */
#ifndef TB_TESTS_RADIOSITY_RAD_MEASURE_H
#define TB_TESTS_RADIOSITY_RAD_MEASURE_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "host/radiosity/radiosity.h"

/* Every element's radiosity, nchannels per element (malloc'ed); exits on out of memory. */
static inline double *tb_rad_test_radiosities(const tb_rad_solver *s)
{
    const tb_rad_mesh *m = tb_rad_solver_mesh(s);
    double *b = malloc(sizeof *b * m->nelems * (size_t)m->nchannels);
    if (!b) {
        fprintf(stderr, "tb_rad_test_radiosities: out of memory\n");
        exit(1);
    }
    for (size_t i = 0; i < m->nelems; i++)
        tb_rad_element_radiosity(s, i, false, b + i * (size_t)m->nchannels);
    return b;
}

/* NRMSE of b against ref over the reflected part (ref - E), all channels (as --report). */
static inline double tb_rad_test_nrmse(const tb_rad_mesh *m, const double *b, const double *ref)
{
    double num = 0.0, den = 0.0;
    for (size_t x = 0; x < m->nelems * (size_t)m->nchannels; x++) {
        num += (b[x] - ref[x]) * (b[x] - ref[x]);
        den += (ref[x] - m->emission[x]) * (ref[x] - m->emission[x]);
    }
    return sqrt(num / den);
}

#endif
