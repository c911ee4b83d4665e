/* The solver's per-shot update kernels, x86-64 baseline build (update_internal.h). */
#include "host/radiosity/update_kernels_internal.h"

void tb__rad_update_vertices(const tb__rad_update *u, size_t v0, size_t v1) { tb__rad_update_vertices_body(u, v0, v1); }

void tb__rad_update_elements(const tb__rad_update *u, size_t q0, size_t q1) { tb__rad_update_elements_body(u, q0, q1); }

bool tb__rad_have_avx(void)
{
#if defined(TB_RAD_AVX)
    return __builtin_cpu_supports("avx");
#else
    return false;
#endif
}
