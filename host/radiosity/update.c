/* The solver's per-shot update kernels, x86-64 baseline build (update_internal.h). */
#include <stdbool.h>

#define TB__RAD_UPDATE_NAME(x) tb__rad_update_##x
#include "host/radiosity/update_kernels_internal.h"

bool tb__rad_have_avx(void)
{
#if defined(TB_RAD_AVX)
    return __builtin_cpu_supports("avx");
#else
    return false;
#endif
}
