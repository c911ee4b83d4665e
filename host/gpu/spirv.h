/* SPIR-V modules embedded at build time. CMake compiles every shaders/<name>.comp
 * to SPIR-V and embeds it into the library (host/gpu/module.cmake,
 * tb_gpu_add_shaders); programs with kernels of their own (the paired kernel
 * tests) embed theirs the same way into their executable. */
#ifndef TB_HOST_GPU_SPIRV_H
#define TB_HOST_GPU_SPIRV_H

#include <stddef.h>
#include <stdint.h>

/* One compiled compute shader. */
typedef struct tb_gpu_spirv {
    const char *name;      /* file name without .comp, e.g. "selftest" */
    const uint32_t *words; /* the module, host byte order */
    size_t size;           /* in bytes (a multiple of 4) */
} tb_gpu_spirv;

/* The library's own kernels (every shaders/<name>.comp), in file-name order. */
extern const tb_gpu_spirv tb_gpu_builtin_spirv[];
/* Number of entries of tb_gpu_builtin_spirv. */
extern const int tb_gpu_builtin_spirv_count;

/* The entry called `name` in table[0..count-1], or NULL. */
const tb_gpu_spirv *tb_gpu_spirv_find(const tb_gpu_spirv *table, int count, const char *name);

/* The library kernel called `name` (shaders/<name>.comp), or NULL. */
const tb_gpu_spirv *tb_gpu_builtin(const char *name);

#endif
