/* Lookup in the tables of embedded SPIR-V modules. */
#include "host/gpu/spirv.h"

#include <string.h>

const tb_gpu_spirv *tb_gpu_spirv_find(const tb_gpu_spirv *table, int count, const char *name)
{
    for (int i = 0; name && i < count; i++)
        if (table[i].name && strcmp(table[i].name, name) == 0)
            return &table[i];
    return NULL;
}

const tb_gpu_spirv *tb_gpu_builtin(const char *name)
{
    return tb_gpu_spirv_find(tb_gpu_builtin_spirv, tb_gpu_builtin_spirv_count, name);
}
