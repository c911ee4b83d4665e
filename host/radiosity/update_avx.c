/* The solver's per-shot update kernels built with -mavx (module.cmake):
 * twice the doubles per instruction of the baseline build, the same bits. */
#define TB__RAD_UPDATE_NAME(x) tb__rad_update_##x##_avx
#include "host/radiosity/update_kernels_internal.h"
