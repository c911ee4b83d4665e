/* host/gpu: device selection (on synthetic device lists), the instance and
 * what it reports, buffers on both memory paths (mapped and staging, chunked
 * copies), kernels (specialization and push constants, workgroup widths, the
 * kernel cache), multi-dispatch ordering, timestamps and their statistics,
 * every refused description, the validation messenger itself, a lost device
 * and a submission timeout. All under the validation layer. */
#include "gpu_test.h"

#include "host/gpu/gpu_internal.h"
#include "util/stats/stats.h"

/* ---------------------------------------------------------------- pure selection logic */

static tb_gpu_device_info fake(tb_gpu_device_type type, bool usable)
{
    tb_gpu_device_info d;
    memset(&d, 0, sizeof d);
    snprintf(d.name, sizeof d.name, "fake %s", tb_gpu_device_type_name(type));
    d.type = type;
    d.usable = usable;
    if (!usable)
        snprintf(d.unusable_reason, sizeof d.unusable_reason, "has no compute queue");
    return d;
}

static int pick(const tb_gpu_device_info *d, int n, tb_gpu_mode mode, int requested, char *reason)
{
    int index = -99;
    tb_status st = tb_gpu_pick_device(d, n, mode, requested, &index, reason, 256);
    if (st)
        fail_msg("pick failed unexpectedly: %s", tb_last_error());
    return index;
}

static void test_pick_order(void **state)
{
    (void)state;
    char why[256];
    tb_gpu_device_info all[4] = {fake(TB_GPU_DEVICE_CPU, true), fake(TB_GPU_DEVICE_INTEGRATED, true),
                                 fake(TB_GPU_DEVICE_DISCRETE, true), fake(TB_GPU_DEVICE_VIRTUAL, true)};
    /* discrete > integrated > virtual > CPU, whatever the enumeration order */
    assert_int_equal(pick(all, 4, TB_GPU_MODE_AUTO, -1, why), 2);
    assert_int_equal(pick(all, 4, TB_GPU_MODE_VULKAN, -1, why), 2);
    assert_non_null(strstr(why, "discrete"));
    tb_gpu_device_info no_discrete[3] = {fake(TB_GPU_DEVICE_VIRTUAL, true), fake(TB_GPU_DEVICE_CPU, true),
                                         fake(TB_GPU_DEVICE_INTEGRATED, true)};
    assert_int_equal(pick(no_discrete, 3, TB_GPU_MODE_AUTO, -1, why), 2);
    tb_gpu_device_info virt[2] = {fake(TB_GPU_DEVICE_CPU, true), fake(TB_GPU_DEVICE_VIRTUAL, true)};
    assert_int_equal(pick(virt, 2, TB_GPU_MODE_AUTO, -1, why), 1); /* a virtual GPU is a real GPU */
    /* ties: the first in enumeration order */
    tb_gpu_device_info twins[2] = {fake(TB_GPU_DEVICE_INTEGRATED, true), fake(TB_GPU_DEVICE_INTEGRATED, true)};
    assert_int_equal(pick(twins, 2, TB_GPU_MODE_VULKAN, -1, why), 0);
    /* unusable devices are skipped */
    tb_gpu_device_info broken[2] = {fake(TB_GPU_DEVICE_DISCRETE, false), fake(TB_GPU_DEVICE_INTEGRATED, true)};
    assert_int_equal(pick(broken, 2, TB_GPU_MODE_AUTO, -1, why), 1);
}

static void test_pick_cpu_drivers(void **state)
{
    (void)state;
    char why[256];
    tb_gpu_device_info cpu[1] = {fake(TB_GPU_DEVICE_CPU, true)};
    /* auto never runs the kernels on a CPU driver; vulkan does */
    assert_int_equal(pick(cpu, 1, TB_GPU_MODE_AUTO, -1, why), -1);
    assert_non_null(strstr(why, "CPU path"));
    assert_int_equal(pick(cpu, 1, TB_GPU_MODE_VULKAN, -1, why), 0);
    tb_gpu_device_info other[1] = {fake(TB_GPU_DEVICE_OTHER, true)};
    assert_int_equal(pick(other, 1, TB_GPU_MODE_AUTO, -1, why), -1);
    assert_int_equal(pick(other, 1, TB_GPU_MODE_VULKAN, -1, why), 0);
    /* an explicit --device is used even in auto mode */
    tb_gpu_device_info two[2] = {fake(TB_GPU_DEVICE_DISCRETE, true), fake(TB_GPU_DEVICE_CPU, true)};
    assert_int_equal(pick(two, 2, TB_GPU_MODE_AUTO, 1, why), 1);
    assert_non_null(strstr(why, "--device"));
    /* cpu mode ignores devices */
    assert_int_equal(pick(two, 2, TB_GPU_MODE_CPU, 0, why), -1);
    /* no devices: auto falls back, vulkan fails */
    assert_int_equal(pick(NULL, 0, TB_GPU_MODE_AUTO, -1, why), -1);
    assert_non_null(strstr(why, "no Vulkan devices"));
}

/* The default workgroup width from synthetic limits: 64 in whole subgroups,
 * within the device's limit, never an assumption about lavapipe's 8. */
static void test_default_workgroup(void **state)
{
    (void)state;
    static const struct {
        uint32_t sg, size_x, invocations, want;
    } c[] = {
        {8, 1024, 1024, 64},  {16, 1024, 1024, 64}, {32, 1024, 1024, 64}, {64, 1024, 1024, 64},
        {128, 1024, 1024, 128}, {0, 1024, 1024, 64}, {48, 1024, 1024, 96},  {32, 1024, 48, 32},
        {64, 40, 1024, 40},   {1, 128, 128, 64},
    };
    for (size_t i = 0; i < sizeof c / sizeof c[0]; ++i) {
        tb_gpu_device_info d = {.subgroup_size = c[i].sg,
                                .max_workgroup_size = {c[i].size_x, 1, 1},
                                .max_workgroup_invocations = c[i].invocations};
        if (tb_gpu_default_workgroup(&d) != c[i].want)
            fail_msg("subgroup %u, limits %u/%u: width %u, want %u", c[i].sg, c[i].size_x, c[i].invocations,
                     tb_gpu_default_workgroup(&d), c[i].want);
        assert_true(tb_gpu_default_workgroup(&d) <= tb_gpu_workgroup_limit(&d));
    }
}

static void test_pick_errors(void **state)
{
    (void)state;
    int index = 7;
    char why[256];
    tb_gpu_device_info two[2] = {fake(TB_GPU_DEVICE_DISCRETE, true), fake(TB_GPU_DEVICE_INTEGRATED, false)};
    gpu_assert_error(tb_gpu_pick_device(two, 2, TB_GPU_MODE_VULKAN, 2, &index, why, sizeof why), TB_ERR_ARG,
                     "--device 2 does not exist (2 Vulkan devices");
    assert_int_equal(index, -1);
    gpu_assert_error(tb_gpu_pick_device(two, 2, TB_GPU_MODE_AUTO, 1, &index, why, sizeof why), TB_ERR_DEVICE,
                     "cannot be used: it has no compute queue");
    gpu_assert_error(tb_gpu_pick_device(NULL, 0, TB_GPU_MODE_VULKAN, -1, &index, why, sizeof why),
                     TB_ERR_DEVICE, "--backend vulkan: no Vulkan devices");
    tb_gpu_device_info dead[1] = {fake(TB_GPU_DEVICE_DISCRETE, false)};
    gpu_assert_error(tb_gpu_pick_device(dead, 1, TB_GPU_MODE_VULKAN, -1, &index, why, sizeof why),
                     TB_ERR_DEVICE, "no usable Vulkan device");
    assert_int_equal(tb_gpu_pick_device(dead, 1, TB_GPU_MODE_AUTO, -1, &index, NULL, 0), TB_OK);
    assert_int_equal(index, -1);
}

static void test_mode_names(void **state)
{
    (void)state;
    tb_gpu_mode m = TB_GPU_MODE_CPU;
    assert_int_equal(tb_gpu_mode_parse("auto", &m), TB_OK);
    assert_int_equal(m, TB_GPU_MODE_AUTO);
    assert_int_equal(tb_gpu_mode_parse("vulkan", &m), TB_OK);
    assert_int_equal(m, TB_GPU_MODE_VULKAN);
    assert_int_equal(tb_gpu_mode_parse("cpu", &m), TB_OK);
    assert_int_equal(m, TB_GPU_MODE_CPU);
    gpu_assert_error(tb_gpu_mode_parse("gpu", &m), TB_ERR_ARG, "use auto, vulkan or cpu");
    assert_string_equal(tb_gpu_backend_name(TB_GPU_BACKEND_VULKAN), "vulkan");
    char v[16];
    assert_string_equal(tb_gpu_version_string(VK_MAKE_API_VERSION(0, 1, 3, 239), v), "1.3.239");
}

/* ---------------------------------------------------------------- instance and device */

static void test_instance_reports(void **state)
{
    (void)state;
    tb_gpu_instance *inst = gpu_test_instance();
    assert_true(tb_gpu_validation_enabled(inst));
    assert_true(tb_gpu_loader_version(inst) >= VK_API_VERSION_1_1);
    assert_null(tb_gpu_device_info_at(inst, -1));
    assert_null(tb_gpu_device_info_at(inst, tb_gpu_device_count(inst)));
    for (int i = 0; i < tb_gpu_device_count(inst); i++) {
        const tb_gpu_device_info *d = tb_gpu_device_info_at(inst, i);
        assert_true(d->name[0] != '\0');
        if (!d->usable)
            continue;
        /* Vulkan's required minimums (spec, "Required Limits") */
        assert_true(d->api_version >= VK_API_VERSION_1_1);
        assert_true(d->max_workgroup_invocations >= 128);
        assert_true(d->max_workgroup_size[0] >= 128);
        assert_true(d->max_workgroup_count[0] >= 65535);
        assert_true(d->max_push_constants >= 128);
        assert_true(d->max_storage_buffer_range >= (1u << 27));
        assert_true(d->max_storage_buffers >= 4);
        assert_true(d->subgroup_size >= 1 && (d->subgroup_size & (d->subgroup_size - 1)) == 0);
        assert_true(d->heap_count >= 1);
        bool local = false;
        for (int h = 0; h < d->heap_count; h++)
            local = local || d->heaps[h].device_local;
        assert_true(local); /* every device has a device-local heap */
        if (d->timestamps)
            assert_true(d->timestamp_valid_bits >= 36 && d->timestamp_valid_bits <= 64 &&
                        d->timestamp_period > 0.0f);
    }
    gpu_assert_clean(inst);
    tb_gpu_instance_destroy(inst);
}

/* The device the tests run on: the one --backend vulkan picks. */
static tb_gpu_device *open_device(tb_gpu_instance *inst, bool staging, uint32_t timeout_ms)
{
    int index = -1;
    if (tb_gpu_pick_device(tb_gpu_device_info_at(inst, 0), tb_gpu_device_count(inst), TB_GPU_MODE_VULKAN, -1,
                           &index, NULL, 0))
        fail_msg("no usable device: %s", tb_last_error());
    tb_gpu_device *dev = tb_gpu_device_create(inst, index,
                                              &(tb_gpu_device_desc){.force_staging = staging, .timeout_ms = timeout_ms});
    if (!dev)
        fail_msg("device %d: %s", index, tb_last_error());
    return dev;
}

static void test_device_errors(void **state)
{
    (void)state;
    tb_gpu_instance *inst = gpu_test_instance();
    assert_null(tb_gpu_device_create(inst, tb_gpu_device_count(inst), NULL));
    assert_int_equal(tb_last_error()[0] != '\0', 1);
    assert_non_null(strstr(tb_last_error(), "does not exist"));
    assert_null(tb_gpu_device_create(NULL, 0, NULL));
    gpu_assert_clean(inst);
    tb_gpu_instance_destroy(inst);
}

/* Upload a pattern at an unaligned offset, read back whole and in part. */
static void check_buffer_roundtrip(tb_gpu_device *dev)
{
    enum { N = 4099 }; /* not a multiple of 4 */
    unsigned char in[N], out[N];
    tb_gpu_buffer *b = tb_gpu_buffer_create(dev, N);
    assert_non_null(b);
    assert_int_equal(tb_gpu_buffer_size(b), N);
    memset(out, 0xab, N);
    assert_int_equal(tb_gpu_buffer_download(b, 0, out, N), TB_OK);
    for (int i = 0; i < N; i++)
        if (out[i] != 0)
            fail_msg("new buffer byte %d is %d, not 0", i, out[i]);
    for (int i = 0; i < N; i++)
        in[i] = (unsigned char)(i * 7 + 3);
    assert_int_equal(tb_gpu_buffer_upload(b, 3, in, N - 3), TB_OK);
    assert_int_equal(tb_gpu_buffer_download(b, 0, out, N), TB_OK);
    assert_int_equal(out[0] | out[1] | out[2], 0);
    assert_memory_equal(out + 3, in, N - 3);
    memset(out, 0, N);
    assert_int_equal(tb_gpu_buffer_download(b, 1001, out, 17), TB_OK);
    assert_memory_equal(out, in + 998, 17);
    assert_int_equal(tb_gpu_buffer_upload(b, 0, in, 0), TB_OK); /* empty copies are fine */
    gpu_assert_error(tb_gpu_buffer_upload(b, 4000, in, 100), TB_ERR_ARG, "outside the buffer of 4099 bytes");
    gpu_assert_error(tb_gpu_buffer_download(b, N + 1, out, 0), TB_ERR_ARG, "outside");
    gpu_assert_error(tb_gpu_buffer_download(b, 0, NULL, 4), TB_ERR_ARG, "NULL");
    tb_gpu_buffer_destroy(b);
}

static void test_buffers(void **state)
{
    (void)state;
    tb_gpu_instance *inst = gpu_test_instance();
    for (int staging = 0; staging < 2; staging++) {
        tb_gpu_device *dev = open_device(inst, staging, 0);
        assert_int_equal(tb_gpu_device_uses_mapped_buffers(dev),
                         !staging && tb_gpu_device_info_of(dev)->unified_memory);
        check_buffer_roundtrip(dev);
        assert_null(tb_gpu_buffer_create(dev, 0));
        assert_non_null(strstr(tb_last_error(), "size 0"));
        size_t too_big = (size_t)tb_gpu_device_info_of(dev)->max_storage_buffer_range + 1;
        assert_null(tb_gpu_buffer_create(dev, too_big));
        assert_non_null(strstr(tb_last_error(), "maxStorageBufferRange"));
        tb_gpu_device_destroy(dev);
    }
    gpu_assert_clean(inst);
    tb_gpu_instance_destroy(inst);
}

static void test_staging_chunks(void **state)
{
    (void)state;
    tb_gpu_instance *inst = gpu_test_instance();
    tb_gpu_device *dev = open_device(inst, true, 0);
    dev->staging_max = 4096; /* 10 chunks for the 40 000 bytes below */
    enum { N = 10000 };
    uint32_t *in = malloc(N * sizeof *in), *out = malloc(N * sizeof *out);
    assert_true(in && out);
    for (uint32_t i = 0; i < N; i++)
        in[i] = i * 2654435761u;
    tb_gpu_buffer *b = tb_gpu_buffer_create(dev, N * sizeof *in);
    assert_non_null(b);
    assert_int_equal(tb_gpu_buffer_upload(b, 0, in, N * sizeof *in), TB_OK);
    assert_int_equal(tb_gpu_buffer_download(b, 0, out, N * sizeof *out), TB_OK);
    assert_memory_equal(in, out, N * sizeof *in);
    assert_int_equal(dev->staging->size, 4096);
    tb_gpu_buffer_destroy(b);
    free(in);
    free(out);
    tb_gpu_device_destroy(dev);
    gpu_assert_clean(inst);
    tb_gpu_instance_destroy(inst);
}

static void test_self_test(void **state)
{
    (void)state;
    tb_gpu_instance *inst = gpu_test_instance();
    for (int staging = 0; staging < 2; staging++) {
        tb_gpu_device *dev = open_device(inst, staging, 0);
        double s = -1.0;
        assert_int_equal(tb_gpu_device_self_test(dev, 1000, &s), TB_OK);
        if (tb_gpu_device_info_of(dev)->timestamps)
            assert_true(s >= 0.0);
        else
            assert_true(isnan(s));
        tb_gpu_device_destroy(dev);
    }
    gpu_assert_clean(inst);
    tb_gpu_instance_destroy(inst);
}

/* ---------------------------------------------------------------- kernels */

static tb_gpu_kernel *selftest_kernel(tb_gpu_device *dev, uint32_t mul, uint32_t wg)
{
    tb_gpu_spec_constant spec = {1, mul};
    return tb_gpu_kernel_get(dev, &(tb_gpu_kernel_desc){.spirv = tb_gpu_builtin("selftest"),
                                                        .buffers = 1,
                                                        .push_size = 8,
                                                        .workgroup_size = wg,
                                                        .spec = &spec,
                                                        .spec_count = 1});
}

static int64_t stat_value(const char *name, tb_stat_kind kind)
{
    tb_stat_total t;
    if (tb_stats_get(name, kind, &t) != TB_OK)
        return 0; /* not registered yet: nothing counted */
    return t.v[0];
}

static void test_kernel_cache(void **state)
{
    (void)state;
    tb_gpu_instance *inst = gpu_test_instance();
    tb_gpu_device *dev = open_device(inst, false, 0);
    int64_t compiled = stat_value("GPU/pipelines compiled", TB_STAT_KIND_COUNTER);
    int64_t reused = stat_value("GPU/pipeline requests served by the kernel cache", TB_STAT_KIND_COUNTER);
    tb_gpu_kernel *a = selftest_kernel(dev, 3, 0);
    assert_non_null(a);
    assert_string_equal(tb_gpu_kernel_name(a), "selftest");
    assert_int_equal(tb_gpu_kernel_workgroup_size(a), TB_GPU_DEFAULT_WORKGROUP);
    assert_ptr_equal(selftest_kernel(dev, 3, 0), a);                    /* same description: cached */
    assert_ptr_equal(selftest_kernel(dev, 3, TB_GPU_DEFAULT_WORKGROUP), a); /* 0 means the default */
    tb_gpu_kernel *b = selftest_kernel(dev, 5, 0);                      /* other constant: new */
    tb_gpu_kernel *c = selftest_kernel(dev, 3, 32);                     /* other width: new */
    assert_true(b && c && b != a && c != a && b != c);
    assert_int_equal(stat_value("GPU/pipelines compiled", TB_STAT_KIND_COUNTER) - compiled, 3);
    assert_int_equal(stat_value("GPU/pipeline requests served by the kernel cache", TB_STAT_KIND_COUNTER) - reused, 2);
    /* a kernel of another device is another pipeline */
    tb_gpu_device *other = open_device(inst, true, 0);
    tb_gpu_kernel *d = selftest_kernel(other, 3, 0);
    assert_true(d && d != a);
    tb_gpu_device_destroy(other);
    tb_gpu_device_destroy(dev);
    gpu_assert_clean(inst);
    tb_gpu_instance_destroy(inst);
}

/* Runs selftest with workgroup width wg over n words of a buffer of n + 64
 * words: exactly the first n change (the kernel guards i < n). */
static void check_width(tb_gpu_device *dev, uint32_t wg, uint32_t n)
{
    uint32_t total = n + 64, mul = 7, add = 11;
    uint32_t *v = malloc(total * sizeof *v);
    assert_non_null(v);
    for (uint32_t i = 0; i < total; i++)
        v[i] = i;
    tb_gpu_buffer *b = tb_gpu_buffer_create(dev, total * sizeof *v);
    tb_gpu_kernel *k = selftest_kernel(dev, mul, wg);
    assert_true(b && k);
    assert_int_equal(tb_gpu_kernel_workgroup_size(k), wg);
    assert_int_equal(tb_gpu_buffer_upload(b, 0, v, total * sizeof *v), TB_OK);
    uint32_t push[2] = {n, add};
    tb_gpu_dispatch d = {.kernel = k, .buffers = {b}, .push = push, .items = n};
    assert_int_equal(tb_gpu_run(dev, &d, 1), TB_OK);
    assert_int_equal(tb_gpu_buffer_download(b, 0, v, total * sizeof *v), TB_OK);
    for (uint32_t i = 0; i < total; i++) {
        uint32_t want = i < n ? i * mul + add : i;
        if (v[i] != want)
            fail_msg("width %u, n %u: word %u is %u, want %u", wg, n, i, v[i], want);
    }
    tb_gpu_buffer_destroy(b);
    free(v);
}

static void test_workgroup_widths(void **state)
{
    (void)state;
    tb_gpu_instance *inst = gpu_test_instance();
    tb_gpu_device *dev = open_device(inst, false, 0);
    const uint32_t widths[] = {1, 7, 64, 256};
    const uint32_t counts[] = {1, 100, 1000, 4097};
    for (size_t w = 0; w < 4; w++)
        for (size_t c = 0; c < 4; c++)
            check_width(dev, widths[w], counts[c]);
    tb_gpu_device_destroy(dev);
    gpu_assert_clean(inst);
    tb_gpu_instance_destroy(inst);
}

/* Four dispatches in one submission on one buffer: each must see the
 * previous one's writes (barriers), the empty one changes nothing, and each
 * is timed and counted. */
static void test_dispatch_chain(void **state)
{
    (void)state;
    tb_gpu_instance *inst = gpu_test_instance();
    for (int staging = 0; staging < 2; staging++) {
        tb_gpu_device *dev = open_device(inst, staging, 0);
        enum { N = 5000 };
        uint32_t v[N];
        for (uint32_t i = 0; i < N; i++)
            v[i] = i * 40503u;
        tb_gpu_buffer *b = tb_gpu_buffer_create(dev, sizeof v);
        tb_gpu_kernel *k3 = selftest_kernel(dev, 3, 0), *k5 = selftest_kernel(dev, 5, 128);
        assert_true(b && k3 && k5);
        assert_int_equal(tb_gpu_buffer_upload(b, 0, v, sizeof v), TB_OK);
        uint32_t p1[2] = {N, 1}, p2[2] = {N, 2}, p3[2] = {N / 2, 3}, p4[2] = {N, 99};
        tb_gpu_dispatch d[4] = {{.kernel = k3, .buffers = {b}, .push = p1, .items = N},
                                {.kernel = k5, .buffers = {b}, .push = p2, .items = N},
                                {.kernel = k3, .buffers = {b}, .push = p3, .items = N},
                                {.kernel = k5, .buffers = {b}, .push = p4, .items = 0}};
        tb_stat_total before;
        bool had = tb_stats_get("GPU/kernel selftest (ns)", TB_STAT_KIND_DISTRIBUTION, &before) == TB_OK;
        int64_t dispatches = stat_value("GPU/dispatches", TB_STAT_KIND_COUNTER);
        assert_int_equal(tb_gpu_run(dev, d, 4), TB_OK);
        uint32_t out[N];
        assert_int_equal(tb_gpu_buffer_download(b, 0, out, sizeof out), TB_OK);
        for (uint32_t i = 0; i < N; i++) {
            uint32_t want = (v[i] * 3u + 1u) * 5u + 2u;
            if (i < N / 2)
                want = want * 3u + 3u; /* the third dispatch covers the first half */
            if (out[i] != want)
                fail_msg("word %u is %u, want %u", i, out[i], want);
        }
        assert_int_equal(stat_value("GPU/dispatches", TB_STAT_KIND_COUNTER) - dispatches, 4);
        tb_stat_total after;
        assert_int_equal(tb_stats_get("GPU/kernel selftest (ns)", TB_STAT_KIND_DISTRIBUTION, &after), TB_OK);
        if (tb_gpu_device_info_of(dev)->timestamps) {
            for (int i = 0; i < 4; i++)
                assert_true(d[i].seconds >= 0.0 && d[i].seconds < 60.0);
            assert_int_equal(after.v[0] - (had ? before.v[0] : 0), 4); /* one sample per dispatch */
        } else {
            for (int i = 0; i < 4; i++)
                assert_true(isnan(d[i].seconds));
        }
        assert_int_equal(tb_gpu_run(dev, d, 0), TB_OK); /* nothing to do */
        tb_gpu_buffer_destroy(b);
        tb_gpu_device_destroy(dev);
    }
    gpu_assert_clean(inst);
    tb_gpu_instance_destroy(inst);
}

static void test_kernel_refusals(void **state)
{
    (void)state;
    tb_gpu_instance *inst = gpu_test_instance();
    tb_gpu_device *dev = open_device(inst, false, 0);
    const tb_gpu_spirv *self = tb_gpu_builtin("selftest");
    assert_non_null(self);
    tb_gpu_kernel_desc base = {.spirv = self, .buffers = 1, .push_size = 8};
    tb_gpu_kernel_desc d;

    static const uint32_t junk[8] = {0xdeadbeefu, 1, 2, 3, 4, 5, 6, 7};
    tb_gpu_spirv not_spirv = {"junk", junk, sizeof junk};
    d = base;
    d.spirv = &not_spirv;
    assert_null(tb_gpu_kernel_get(dev, &d));
    assert_non_null(strstr(tb_last_error(), "not a SPIR-V module"));
    tb_gpu_spirv cut = {"cut", self->words, 18};
    d.spirv = &cut;
    assert_null(tb_gpu_kernel_get(dev, &d));
    assert_non_null(strstr(tb_last_error(), "not a SPIR-V module"));
    d.spirv = NULL;
    assert_null(tb_gpu_kernel_get(dev, &d));
    assert_non_null(strstr(tb_last_error(), "no SPIR-V module"));

    d = base;
    d.spirv = gpu_test_kernel("k_fixed_wg");
    assert_null(tb_gpu_kernel_get(dev, &d));
    assert_non_null(strstr(tb_last_error(), "local_size_x_id = 0"));

    d = base;
    d.buffers = TB_GPU_MAX_BUFFERS + 1;
    assert_null(tb_gpu_kernel_get(dev, &d));
    assert_non_null(strstr(tb_last_error(), "storage buffers"));
    d = base;
    d.push_size = 6;
    assert_null(tb_gpu_kernel_get(dev, &d));
    assert_non_null(strstr(tb_last_error(), "push constants"));
    d.push_size = tb_gpu_device_info_of(dev)->max_push_constants + 4;
    assert_null(tb_gpu_kernel_get(dev, &d));
    assert_non_null(strstr(tb_last_error(), "push constants"));
    d = base;
    d.workgroup_size = tb_gpu_device_info_of(dev)->max_workgroup_invocations + 1;
    assert_null(tb_gpu_kernel_get(dev, &d));
    assert_non_null(strstr(tb_last_error(), "exceeds the limit"));
    tb_gpu_spec_constant zero = {0, 64}, twice[2] = {{1, 2}, {1, 3}};
    d = base;
    d.spec = &zero;
    d.spec_count = 1;
    assert_null(tb_gpu_kernel_get(dev, &d));
    assert_non_null(strstr(tb_last_error(), "constant_id 0 is the workgroup width"));
    d.spec = twice;
    d.spec_count = 2;
    assert_null(tb_gpu_kernel_get(dev, &d));
    assert_non_null(strstr(tb_last_error(), "constant_id 1 given twice"));
    d.spec_count = TB_GPU_MAX_SPEC + 1;
    assert_null(tb_gpu_kernel_get(dev, &d));
    assert_non_null(strstr(tb_last_error(), "specialization constants"));

    /* dispatches that cannot run */
    tb_gpu_kernel *k = tb_gpu_kernel_get(dev, &base);
    assert_non_null(k);
    tb_gpu_buffer *b = tb_gpu_buffer_create(dev, 64);
    assert_non_null(b);
    uint32_t push[2] = {16, 1};
    tb_gpu_dispatch bad = {.kernel = k, .push = push, .items = 16};
    gpu_assert_error(tb_gpu_run(dev, &bad, 1), TB_ERR_ARG, "buffer 0 is missing");
    bad.buffers[0] = b;
    bad.push = NULL;
    gpu_assert_error(tb_gpu_run(dev, &bad, 1), TB_ERR_ARG, "8 bytes of push constants expected");
    bad.push = push;
    bad.items = (uint64_t)tb_gpu_device_info_of(dev)->max_workgroup_count[0] * tb_gpu_kernel_workgroup_size(k) + 1;
    gpu_assert_error(tb_gpu_run(dev, &bad, 1), TB_ERR_ARG, "split the work");
    bad.kernel = NULL;
    gpu_assert_error(tb_gpu_run(dev, &bad, 1), TB_ERR_ARG, "no kernel");
    gpu_assert_error(tb_gpu_run(dev, NULL, 1), TB_ERR_ARG, "bad arguments");
    tb_gpu_buffer_destroy(b);
    tb_gpu_device_destroy(dev);
    /* the refusals happen before Vulkan sees anything */
    gpu_assert_clean(inst);
    tb_gpu_instance_destroy(inst);
}

/* ---------------------------------------------------------------- validation, lost devices, timeouts */

/* The "fail on any validation message" rule is only worth something if the
 * messenger does catch messages: provoke one. */
static void test_messenger_catches_errors(void **state)
{
    (void)state;
    tb_gpu_instance *inst = gpu_test_instance();
    tb_gpu_device *dev = open_device(inst, false, 0);
    gpu_assert_clean(inst);
    /* A fence create info with the wrong sType: the layer reports it, the
     * driver (which ignores sType) still makes a fence. */
    VkFenceCreateInfo wrong = {.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    VkFence fence = VK_NULL_HANDLE;
    if (dev->fn.vkCreateFence(dev->vk, &wrong, NULL, &fence) == VK_SUCCESS)
        dev->fn.vkDestroyFence(dev->vk, fence, NULL);
    assert_true(tb_gpu_validation_errors(inst) >= 1);
    assert_true(tb_gpu_validation_message_count(inst) >= 1);
    const char *m = tb_gpu_validation_message(inst, 0);
    assert_non_null(m);
    if (!strstr(m, "error: ") || !strstr(m, "sType"))
        fail_msg("unexpected message: %s", m);
    assert_null(tb_gpu_validation_message(inst, tb_gpu_validation_message_count(inst)));
    tb_gpu_validation_clear(inst);
    assert_int_equal(tb_gpu_validation_errors(inst) + tb_gpu_validation_message_count(inst), 0);
    tb_gpu_device_destroy(dev);
    gpu_assert_clean(inst);
    tb_gpu_instance_destroy(inst);
}

static void test_result_texts(void **state)
{
    (void)state;
    assert_non_null(strstr(tb__vk_result_text(VK_ERROR_DEVICE_LOST), "device was lost"));
    assert_non_null(strstr(tb__vk_result_text(VK_ERROR_OUT_OF_DEVICE_MEMORY), "out of device memory"));
    assert_non_null(strstr(tb__vk_result_text(VK_ERROR_INCOMPATIBLE_DRIVER), "no compatible Vulkan driver"));
    assert_non_null(strstr(tb__vk_result_text((VkResult)-123456), "unknown error"));
    gpu_assert_error(tb__gpu_fail(NULL, VK_ERROR_OUT_OF_DEVICE_MEMORY, "allocating 1 GiB"), TB_ERR_DEVICE,
                     "allocating 1 GiB failed: VK_ERROR_OUT_OF_DEVICE_MEMORY");
}

/* After VK_ERROR_DEVICE_LOST every call on the device fails cleanly. (A real
 * loss cannot be provoked on purpose; the error path is the one any call
 * takes when the driver returns it.) */
static void test_device_lost(void **state)
{
    (void)state;
    tb_gpu_instance *inst = gpu_test_instance();
    tb_gpu_device *dev = open_device(inst, false, 0);
    tb_gpu_buffer *b = tb_gpu_buffer_create(dev, 64);
    tb_gpu_kernel *k = selftest_kernel(dev, 3, 0);
    assert_true(b && k);
    assert_false(tb_gpu_device_is_lost(dev));
    gpu_assert_error(tb__gpu_fail(dev, VK_ERROR_DEVICE_LOST, "vkQueueSubmit"), TB_ERR_DEVICE,
                     "VK_ERROR_DEVICE_LOST");
    assert_true(tb_gpu_device_is_lost(dev));
    uint32_t push[2] = {16, 1}, v[16];
    tb_gpu_dispatch d = {.kernel = k, .buffers = {b}, .push = push, .items = 16};
    gpu_assert_error(tb_gpu_run(dev, &d, 1), TB_ERR_DEVICE, "was lost earlier");
    gpu_assert_error(tb_gpu_buffer_download(b, 0, v, sizeof v), TB_ERR_DEVICE, "was lost earlier");
    gpu_assert_error(tb_gpu_buffer_upload(b, 0, v, sizeof v), TB_ERR_DEVICE, "was lost earlier");
    assert_null(tb_gpu_buffer_create(dev, 64));
    assert_non_null(strstr(tb_last_error(), "use the CPU backend"));
    assert_null(selftest_kernel(dev, 9, 0));
    tb_gpu_buffer_destroy(b);
    tb_gpu_device_destroy(dev);
    gpu_assert_clean(inst);
    tb_gpu_instance_destroy(inst);
}

/* A kernel that outlives the device's timeout: the run reports it, the
 * device counts as lost, and destroying everything waits for the kernel.
 * The kernel spins until the host sets word 64 of its buffer, so it cannot
 * finish within the 1 ms however late this thread gets to wait (a kernel of
 * fixed length did, now and then, on a loaded machine: the thread was
 * descheduled between submit and wait for longer than the kernel ran). */
static void test_timeout(void **state)
{
    (void)state;
    tb_gpu_instance *inst = gpu_test_instance();
    tb_gpu_device *dev = open_device(inst, false, 1 /* ms */);
    tb_gpu_buffer *b = tb_gpu_buffer_create(dev, 65 * sizeof(uint32_t)); /* zeroed: the flag is clear */
    tb_gpu_kernel *k = tb_gpu_kernel_get(dev, &(tb_gpu_kernel_desc){.spirv = gpu_test_kernel("k_spin"),
                                                                    .buffers = 1,
                                                                    .push_size = 8});
    assert_true(b && k);
    /* the safety bound, 2^30 dependent steps, is seconds on any device */
    uint32_t push[2] = {64, 1u << 30};
    tb_gpu_dispatch d = {.kernel = k, .buffers = {b}, .push = push, .items = 64};
    gpu_assert_error(tb_gpu_run(dev, &d, 1), TB_ERR_DEVICE, "did not finish within");
    assert_true(tb_gpu_device_is_lost(dev));
    /* Release the kernel: a mapped buffer is written directly (lavapipe's
     * always are); where it is not, the upload needs the lost device and
     * fails, and the kernel runs to its bound. */
    uint32_t one = 1;
    if (tb_gpu_buffer_upload(b, 64 * sizeof(uint32_t), &one, sizeof one) != TB_OK)
        tb_clear_error();
    tb_gpu_buffer_destroy(b); /* waits for the kernel first */
    tb_gpu_device_destroy(dev);
    gpu_assert_clean(inst);
    tb_gpu_instance_destroy(inst);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pick_order),
        cmocka_unit_test(test_pick_cpu_drivers),
        cmocka_unit_test(test_pick_errors),
        cmocka_unit_test(test_default_workgroup),
        cmocka_unit_test(test_mode_names),
        cmocka_unit_test(test_instance_reports),
        cmocka_unit_test(test_device_errors),
        cmocka_unit_test(test_buffers),
        cmocka_unit_test(test_staging_chunks),
        cmocka_unit_test(test_self_test),
        cmocka_unit_test(test_kernel_cache),
        cmocka_unit_test(test_workgroup_widths),
        cmocka_unit_test(test_dispatch_chain),
        cmocka_unit_test(test_kernel_refusals),
        cmocka_unit_test(test_messenger_catches_errors),
        cmocka_unit_test(test_result_texts),
        cmocka_unit_test(test_device_lost),
        cmocka_unit_test(test_timeout),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
