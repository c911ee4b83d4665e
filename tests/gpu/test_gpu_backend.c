/* tb_gpu_backend_choose: auto / vulkan / cpu with and without a working
 * Vulkan. Run three times by CTest:
 *   gpu_backend            Vulkan works (lavapipe): auto picks the CPU path
 *                          (lavapipe is a CPU driver), vulkan opens it;
 *   gpu_backend no-icd     VK_ICD_FILENAMES/VK_DRIVER_FILES name a missing
 *                          manifest, so no driver loads: auto falls back with
 *                          the reason, vulkan fails with a clear message;
 *   gpu_backend no-loader  TB_VULKAN_LOADER names a missing library: the
 *                          same, with a message about the loader. */
#include "gpu_test.h"

static const char *tb__scenario = "normal";

static void test_cpu_mode(void **state)
{
    (void)state;
    tb_gpu_session s;
    assert_int_equal(tb_gpu_backend_choose(TB_GPU_MODE_CPU, 0, true, &s), TB_OK);
    assert_int_equal(s.backend, TB_GPU_BACKEND_CPU);
    assert_null(s.instance);
    assert_null(s.device);
    assert_int_equal(s.device_index, -1);
    assert_string_equal(s.reason, "the CPU backend was requested");
    tb_gpu_session_close(&s);
}

static void test_working_vulkan(void **state)
{
    (void)state;
    /* What the system has, from an independent look at the instance. */
    tb_gpu_instance *inst = gpu_test_instance();
    const tb_gpu_device_info *d0 = tb_gpu_device_info_at(inst, 0);
    bool real_gpu = false;
    for (int i = 0; i < tb_gpu_device_count(inst); i++) {
        tb_gpu_device_type t = tb_gpu_device_info_at(inst, i)->type;
        real_gpu = real_gpu || t == TB_GPU_DEVICE_DISCRETE || t == TB_GPU_DEVICE_INTEGRATED ||
                   t == TB_GPU_DEVICE_VIRTUAL;
    }
    print_message("[ info     ] device 0: %s (%s)\n", d0->name, tb_gpu_device_type_name(d0->type));

    tb_gpu_session s;
    assert_int_equal(tb_gpu_backend_choose(TB_GPU_MODE_AUTO, -1, true, &s), TB_OK);
    print_message("[ info     ] auto: %s\n", s.reason);
    if (real_gpu) {
        assert_int_equal(s.backend, TB_GPU_BACKEND_VULKAN);
    } else {
        /* lavapipe only: the CPU path, saying why */
        assert_int_equal(s.backend, TB_GPU_BACKEND_CPU);
        assert_null(s.device);
        assert_non_null(strstr(s.reason, "CPU driver"));
        assert_non_null(strstr(s.reason, "using the CPU path"));
    }
    tb_gpu_session_close(&s);

    assert_int_equal(tb_gpu_backend_choose(TB_GPU_MODE_VULKAN, -1, true, &s), TB_OK);
    assert_int_equal(s.backend, TB_GPU_BACKEND_VULKAN);
    assert_non_null(s.instance);
    assert_non_null(s.device);
    assert_true(s.device_index >= 0);
    assert_int_equal(tb_gpu_device_self_test(s.device, 256, NULL), TB_OK); /* it really runs */
    gpu_assert_clean(s.instance);
    tb_gpu_session_close(&s);
    assert_null(s.device);

    /* an explicit --device is honoured in auto mode too */
    assert_int_equal(tb_gpu_backend_choose(TB_GPU_MODE_AUTO, 0, true, &s), TB_OK);
    assert_int_equal(s.backend, TB_GPU_BACKEND_VULKAN);
    assert_int_equal(s.device_index, 0);
    assert_string_equal(tb_gpu_device_info_of(s.device)->name, d0->name);
    tb_gpu_session_close(&s);

    /* a device that does not exist is a usage error in both modes */
    int n = tb_gpu_device_count(inst);
    gpu_assert_error(tb_gpu_backend_choose(TB_GPU_MODE_VULKAN, n, false, &s), TB_ERR_ARG, "does not exist");
    assert_int_equal(s.backend, TB_GPU_BACKEND_CPU);
    gpu_assert_error(tb_gpu_backend_choose(TB_GPU_MODE_AUTO, n + 5, false, &s), TB_ERR_ARG, "does not exist");
    gpu_assert_clean(inst);
    tb_gpu_instance_destroy(inst);
}

/* No Vulkan: `expect` is a phrase of the message. */
static void check_no_vulkan(const char *expect)
{
    assert_null(tb_gpu_instance_create(NULL));
    assert_int_equal(tb_last_error()[0] != '\0', 1);
    if (!strstr(tb_last_error(), expect))
        fail_msg("instance error \"%s\" does not mention \"%s\"", tb_last_error(), expect);

    tb_gpu_session s;
    tb_clear_error();
    assert_int_equal(tb_gpu_backend_choose(TB_GPU_MODE_AUTO, -1, false, &s), TB_OK);
    assert_int_equal(s.backend, TB_GPU_BACKEND_CPU);
    assert_null(s.instance);
    print_message("[ info     ] auto: %s\n", s.reason);
    assert_non_null(strstr(s.reason, "using the CPU path"));
    assert_non_null(strstr(s.reason, expect));
    /* with --device too: there is nothing to check it against */
    assert_int_equal(tb_gpu_backend_choose(TB_GPU_MODE_AUTO, 3, true, &s), TB_OK);
    assert_int_equal(s.backend, TB_GPU_BACKEND_CPU);

    gpu_assert_error(tb_gpu_backend_choose(TB_GPU_MODE_VULKAN, -1, false, &s), TB_ERR_DEVICE,
                     "--backend vulkan: Vulkan is not available");
    print_message("[ info     ] vulkan: %s\n", tb_last_error());
    assert_non_null(strstr(tb_last_error(), expect));
    assert_int_equal(s.backend, TB_GPU_BACKEND_CPU);
    assert_null(s.device);
    tb_gpu_session_close(&s); /* harmless on the CPU backend */
}

static void test_no_driver(void **state)
{
    (void)state;
    check_no_vulkan("no Vulkan driver (ICD) could be loaded");
}

static void test_no_loader(void **state)
{
    (void)state;
    check_no_vulkan("Vulkan loader /nonexistent/libvulkan.so.1 not found");
}

int main(int argc, char **argv)
{
    if (argc > 1)
        tb__scenario = argv[1];
    const struct CMUnitTest normal[] = {
        cmocka_unit_test(test_cpu_mode),
        cmocka_unit_test(test_working_vulkan),
    };
    const struct CMUnitTest no_icd[] = {
        cmocka_unit_test(test_cpu_mode),
        cmocka_unit_test(test_no_driver),
    };
    const struct CMUnitTest no_loader[] = {
        cmocka_unit_test(test_cpu_mode),
        cmocka_unit_test(test_no_loader),
    };
    if (strcmp(tb__scenario, "normal") == 0)
        return cmocka_run_group_tests(normal, NULL, NULL);
    if (strcmp(tb__scenario, "no-icd") == 0)
        return cmocka_run_group_tests(no_icd, NULL, NULL);
    if (strcmp(tb__scenario, "no-loader") == 0)
        return cmocka_run_group_tests(no_loader, NULL, NULL);
    fprintf(stderr, "usage: gpu_backend [normal|no-icd|no-loader]\n");
    return 2;
}
