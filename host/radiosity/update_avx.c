/* The solver's per-shot update kernels built with -mavx (module.cmake):
 * twice the doubles per instruction of the baseline build, the same bits. */
#include "host/radiosity/update_kernels_internal.h"

void tb__rad_update_vertices_avx(const tb__rad_update *u, size_t v0, size_t v1)
{
    tb__rad_update_vertices_body(u, v0, v1);
}

void tb__rad_update_elements_avx(const tb__rad_update *u, size_t q0, size_t q1)
{
    tb__rad_update_elements_body(u, q0, q1);
}
