/* Helpers shared by the Vulkan tests: a validated instance, the embedded test
 * kernels, and the "no validation message" check every test ends with. */
#ifndef TB_TESTS_GPU_GPU_TEST_H
#define TB_TESTS_GPU_GPU_TEST_H

#include "tb_test.h"

#include <stdio.h>
#include <string.h>

#include "host/gpu/gpu.h"
#include "host/render/scene.h"

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

/* A validated instance and the Vulkan device the tests run on. */
typedef struct gpu_test_env {
    tb_gpu_instance *inst;
    tb_gpu_device *dev;
} gpu_test_env;

/* Opens gpu_test_instance and the device `--device auto` would pick in
 * Vulkan mode, created with `desc` (NULL: defaults); fails the test if none. */
static inline void gpu_test_open(gpu_test_env *e, const tb_gpu_device_desc *desc)
{
    e->inst = gpu_test_instance();
    int idx = -1;
    char why[256];
    if (tb_gpu_pick_device(tb_gpu_device_info_at(e->inst, 0), tb_gpu_device_count(e->inst), TB_GPU_MODE_VULKAN, -1,
                           &idx, why, sizeof why))
        fail_msg("no Vulkan device: %s", why);
    e->dev = tb_gpu_device_create(e->inst, idx, desc);
    if (!e->dev)
        fail_msg("device: %s", tb_last_error());
}

/* Destroys the device, then fails if the validation layer reported anything. */
static inline void gpu_test_close(gpu_test_env *e)
{
    tb_gpu_device_destroy(e->dev);
    gpu_assert_clean(e->inst);
    tb_gpu_instance_destroy(e->inst);
}

/* cmocka group fixtures: one gpu_test_env (default device) for a file's
 * tests, passed to each as *state; the teardown checks the validation layer. */
static inline int gpu_test_setup(void **state)
{
    static gpu_test_env e;
    gpu_test_open(&e, NULL);
    *state = &e;
    return 0;
}

static inline int gpu_test_teardown(void **state)
{
    gpu_test_close(*state);
    return 0;
}

/* The scene in MID `text` (`name` for messages, files relative to `dir`,
 * NULL: the working folder); fails the test if it does not load. */
static inline tb_scene *gpu_test_load(const char *text, const char *name, const char *dir)
{
    FILE *fp = fmemopen((void *)text, strlen(text), "r");
    if (!fp)
        fail_msg("fmemopen failed");
    tb_scene *s = NULL;
    tb_status st = tb_scene_load_stream(fp, name, dir, NULL, &s);
    fclose(fp);
    if (st)
        fail_msg("scene: %s", tb_last_error());
    return s;
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
