/* Helpers shared by the Vulkan tests: a validated instance, the embedded test
 * kernels, and the "no validation message" check every test ends with. */
#ifndef TB_TESTS_GPU_GPU_TEST_H
#define TB_TESTS_GPU_GPU_TEST_H

#include "tb_test.h"

#include <string.h>

#include "host/gpu/gpu.h"

/* kernels/<name>.comp, embedded by tb_gpu_add_shaders (tests/gpu/CMakeLists.txt). */
extern const tb_gpu_spirv tb_test_spirv[];
extern const int tb_test_spirv_count;

/* The test kernel `name`; fails the test if it was not built in. */
static inline const tb_gpu_spirv *gpu_test_kernel(const char *name)
{
    const tb_gpu_spirv *m = tb_gpu_spirv_find(tb_test_spirv, tb_test_spirv_count, name);
    if (!m)
        fail_msg("test kernel %s is not embedded", name);
    return m;
}

/* An instance with the validation layer (messages recorded, not echoed:
 * gpu_assert_clean prints them). Fails the test if Vulkan or the layer is
 * missing: tools/setup.sh installs both, and lavapipe is the CI device. */
static inline tb_gpu_instance *gpu_test_instance(void)
{
    tb_gpu_instance *inst = tb_gpu_instance_create(&(tb_gpu_instance_desc){.validation = true, .quiet = true});
    if (!inst)
        fail_msg("no validated Vulkan instance: %s", tb_last_error());
    if (tb_gpu_device_count(inst) < 1)
        fail_msg("Vulkan sees no device (lavapipe: Debian mesa-vulkan-drivers)");
    return inst;
}

/* Fails (listing the messages) if the validation layer reported anything. */
static inline void gpu_assert_clean(tb_gpu_instance *inst)
{
    int e = tb_gpu_validation_errors(inst), w = tb_gpu_validation_warnings(inst);
    if (e + w == 0)
        return;
    for (int i = 0; i < tb_gpu_validation_message_count(inst); i++)
        print_error("  %s\n", tb_gpu_validation_message(inst, i));
    fail_msg("the validation layer reported %d error(s) and %d warning(s)", e, w);
}

/* Asserts `st` is `want` and the error message contains `part`. */
#define gpu_assert_error(st, want, part)                                                      \
    do {                                                                                      \
        tb_status gpu__st = (st);                                                             \
        if (gpu__st != (want) || !strstr(tb_last_error(), (part)))                            \
            fail_msg("%s: status %s, message \"%s\"; want %s and \"%s\"", #st,                \
                     tb_status_name(gpu__st), tb_last_error(), tb_status_name(want), (part)); \
    } while (0)

#endif
