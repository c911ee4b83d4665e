/* `testbed devices`: what Vulkan sees, and which device --backend auto and
 * --backend vulkan would use. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "commands.h"
#include "host/gpu/gpu.h"
#include "util/stats/stats.h"

/* Words per device for --check (256 KiB: quick even under validation). */
#define TB__SELF_TEST_WORDS 65536u

static const char *tb__type_key(tb_gpu_device_type t)
{
    switch (t) {
    case TB_GPU_DEVICE_DISCRETE: return "discrete";
    case TB_GPU_DEVICE_INTEGRATED: return "integrated";
    case TB_GPU_DEVICE_VIRTUAL: return "virtual";
    case TB_GPU_DEVICE_CPU: return "cpu";
    case TB_GPU_DEVICE_OTHER: break;
    }
    return "other";
}

static void tb__size(char *buf, size_t cap, uint64_t n)
{
    if (n >= (1ull << 30))
        snprintf(buf, cap, "%.2f GiB", (double)n / (double)(1ull << 30));
    else if (n >= (1ull << 20))
        snprintf(buf, cap, "%.2f MiB", (double)n / (double)(1ull << 20));
    else if (n >= 1024)
        snprintf(buf, cap, "%.2f KiB", (double)n / 1024.0);
    else
        snprintf(buf, cap, "%llu bytes", (unsigned long long)n);
}

/* Result of --check on one device. */
typedef struct tb__check {
    bool ran;         /* the test was attempted */
    bool ok;          /* every word right */
    double seconds;   /* kernel time, NaN without timestamps */
    char error[512];  /* why it failed */
} tb__check;

static void tb__run_check(tb_gpu_instance *inst, int i, tb__check *c)
{
    c->ran = true;
    c->ok = false;
    c->seconds = NAN;
    tb_gpu_device *dev = tb_gpu_device_create(inst, i, NULL);
    tb_status st = dev ? tb_gpu_device_self_test(dev, TB__SELF_TEST_WORDS, &c->seconds) : tb_error_context(TB_ERR_DEVICE, "opening the device");
    if (st)
        snprintf(c->error, sizeof c->error, "%s", tb_last_error());
    else
        c->ok = true;
    tb_gpu_device_destroy(dev);
}

static void tb__json_u32s(FILE *out, const uint32_t *v)
{
    fprintf(out, "[%u, %u, %u]", v[0], v[1], v[2]);
}

static void tb__print_json(FILE *out, tb_gpu_instance *inst, const char *error, int vk_index,
                           const char *vk_reason, int auto_index, const char *auto_reason,
                           const tb__check *checks)
{
    char v[16];
    int n = inst ? tb_gpu_device_count(inst) : 0;
    fputs("{\n  \"loader_version\": ", out);
    if (inst)
        tb_json_write_string(out, tb_gpu_version_string(tb_gpu_loader_version(inst), v));
    else
        fputs("null", out);
    fputs(",\n  \"error\": ", out);
    if (error)
        tb_json_write_string(out, error);
    else
        fputs("null", out);
    fputs(",\n  \"devices\": [", out);
    for (int i = 0; i < n; i++) {
        const tb_gpu_device_info *d = tb_gpu_device_info_at(inst, i);
        fprintf(out, "%s\n    {\"index\": %d, \"name\": ", i ? "," : "", i);
        tb_json_write_string(out, d->name);
        fprintf(out, ", \"type\": \"%s\", \"vendor_id\": %u, \"device_id\": %u, \"api_version\": ",
                tb__type_key(d->type), d->vendor_id, d->device_id);
        tb_json_write_string(out, tb_gpu_version_string(d->api_version, v));
        fputs(",\n     \"driver_name\": ", out);
        tb_json_write_string(out, d->driver_name);
        fputs(", \"driver_info\": ", out);
        tb_json_write_string(out, d->driver_info);
        fprintf(out, ", \"driver_version\": %u,\n     \"subgroup_size\": %u, \"max_workgroup_invocations\": %u, "
                     "\"max_workgroup_size\": ", d->driver_version, d->subgroup_size, d->max_workgroup_invocations);
        tb__json_u32s(out, d->max_workgroup_size);
        fputs(", \"max_workgroup_count\": ", out);
        tb__json_u32s(out, d->max_workgroup_count);
        fprintf(out, ",\n     \"max_shared_memory\": %u, \"max_push_constants\": %u, "
                     "\"max_storage_buffer_range\": %llu, \"max_storage_buffers\": %u,\n     \"heaps\": [",
                d->max_shared_memory, d->max_push_constants, (unsigned long long)d->max_storage_buffer_range,
                d->max_storage_buffers);
        for (int h = 0; h < d->heap_count; h++)
            fprintf(out, "%s{\"size\": %llu, \"device_local\": %s, \"host_visible\": %s}", h ? ", " : "",
                    (unsigned long long)d->heaps[h].size, d->heaps[h].device_local ? "true" : "false",
                    d->heaps[h].host_visible ? "true" : "false");
        fprintf(out, "], \"unified_memory\": %s,\n     \"timestamps\": %s, \"timestamp_valid_bits\": %u, "
                     "\"timestamp_period_ns\": %.9g,\n     \"float_controls\": ",
                d->unified_memory ? "true" : "false", d->timestamps ? "true" : "false",
                d->timestamp_valid_bits, (double)d->timestamp_period);
        if (d->float_controls_known)
            fprintf(out, "{\"denorm_preserve32\": %s, \"rounding_rte32\": %s, \"inf_nan_preserve32\": %s}",
                    d->denorm_preserve32 ? "true" : "false", d->rounding_rte32 ? "true" : "false",
                    d->inf_nan_preserve32 ? "true" : "false");
        else
            fputs("null", out);
        fprintf(out, ",\n     \"usable\": %s, \"unusable_reason\": ", d->usable ? "true" : "false");
        if (d->usable)
            fputs("null", out);
        else
            tb_json_write_string(out, d->unusable_reason);
        if (checks && checks[i].ran) {
            fprintf(out, ",\n     \"self_test\": {\"ok\": %s, \"seconds\": ", checks[i].ok ? "true" : "false");
            if (isfinite(checks[i].seconds))
                fprintf(out, "%.9g", checks[i].seconds);
            else
                fputs("null", out);
            fputs(", \"error\": ", out);
            if (checks[i].ok)
                fputs("null", out);
            else
                tb_json_write_string(out, checks[i].error);
            fputs("}", out);
        }
        fputs("}", out);
    }
    fputs(n ? "\n  ],\n" : "],\n", out);
    fputs("  \"vulkan\": {\"device\": ", out);
    if (vk_index >= 0)
        fprintf(out, "%d", vk_index);
    else
        fputs("null", out);
    fputs(", \"reason\": ", out);
    tb_json_write_string(out, vk_reason);
    fprintf(out, "},\n  \"auto\": {\"backend\": \"%s\", \"device\": ", auto_index >= 0 ? "vulkan" : "cpu");
    if (auto_index >= 0)
        fprintf(out, "%d", auto_index);
    else
        fputs("null", out);
    fputs(", \"reason\": ", out);
    tb_json_write_string(out, auto_reason);
    fputs("}\n}\n", out);
}

static void tb__print_text(FILE *out, tb_gpu_instance *inst, int vk_index, const char *vk_reason,
                           int auto_index, const char *auto_reason, const tb__check *checks)
{
    char v[16], sz[32];
    int n = tb_gpu_device_count(inst);
    fprintf(out, "Vulkan loader %s, %d device%s%s\n", tb_gpu_version_string(tb_gpu_loader_version(inst), v), n,
            n == 1 ? "" : "s", n ? ":" : "");
    for (int i = 0; i < n; i++) {
        const tb_gpu_device_info *d = tb_gpu_device_info_at(inst, i);
        char marks[64] = "";
        if (i == auto_index && i == vk_index)
            snprintf(marks, sizeof marks, "  [auto, vulkan]");
        else if (i == vk_index)
            snprintf(marks, sizeof marks, "  [vulkan]");
        else if (i == auto_index)
            snprintf(marks, sizeof marks, "  [auto]");
        fprintf(out, "\n%c %d  %s  (%s)%s\n", i == auto_index || i == vk_index ? '*' : ' ', i, d->name,
                tb_gpu_device_type_name(d->type), marks);
        if (d->driver_name[0])
            fprintf(out, "     driver       %s, %s\n", d->driver_name, d->driver_info);
        else
            fprintf(out, "     driver       version %u (vendor 0x%04x)\n", d->driver_version, d->vendor_id);
        fprintf(out, "     Vulkan       %s\n", tb_gpu_version_string(d->api_version, v));
        if (d->subgroup_size)
            fprintf(out, "     subgroup     %u invocations\n", d->subgroup_size);
        else
            fprintf(out, "     subgroup     unknown\n");
        fprintf(out, "     workgroup    at most %u invocations, %u x %u x %u; %u x %u x %u groups\n",
                d->max_workgroup_invocations, d->max_workgroup_size[0], d->max_workgroup_size[1],
                d->max_workgroup_size[2], d->max_workgroup_count[0], d->max_workgroup_count[1],
                d->max_workgroup_count[2]);
        for (int h = 0; h < d->heap_count; h++) {
            tb__size(sz, sizeof sz, d->heaps[h].size);
            fprintf(out, "     %s heap %d: %s%s%s\n", h ? "            " : "memory      ", h, sz,
                    d->heaps[h].device_local ? ", device-local" : "",
                    d->heaps[h].host_visible ? ", host-visible" : "");
        }
        fprintf(out, "     buffers      %s\n", d->unified_memory ? "mapped (unified memory, no staging copies)"
                                                                   : "device-local, filled through staging copies");
        tb__size(sz, sizeof sz, d->max_storage_buffer_range);
        fprintf(out, "     limits       storage buffer %s, %u per stage; push constants %u bytes; "
                     "shared memory %u bytes\n", sz, d->max_storage_buffers, d->max_push_constants,
                d->max_shared_memory);
        if (d->timestamps)
            fprintf(out, "     timestamps   yes: %u valid bits, %.6g ns per tick\n", d->timestamp_valid_bits,
                    (double)d->timestamp_period);
        else
            fprintf(out, "     timestamps   no (kernel times are not measured)\n");
        if (d->float_controls_known)
            fprintf(out, "     float32      denormals kept: %s; round-to-nearest-even: %s; "
                         "inf/NaN/-0 kept: %s\n", d->denorm_preserve32 ? "can be" : "no",
                    d->rounding_rte32 ? "can be" : "no", d->inf_nan_preserve32 ? "can be" : "no");
        if (!d->usable)
            fprintf(out, "     not usable:  it %s\n", d->unusable_reason);
        if (checks && checks[i].ran) {
            if (checks[i].ok && isfinite(checks[i].seconds))
                fprintf(out, "     self-test    ok (%u words in %.3f ms)\n", TB__SELF_TEST_WORDS,
                        checks[i].seconds * 1e3);
            else if (checks[i].ok)
                fprintf(out, "     self-test    ok\n");
            else
                fprintf(out, "     self-test    FAILED: %s\n", checks[i].error);
        }
    }
    fprintf(out, "\n--backend vulkan: %s\n", vk_reason);
    fprintf(out, "--backend auto:   %s\n", auto_reason);
}

int tb_cmd_devices(int argc, char **argv)
{
    bool json = false, check = false, validation = false;
    const tb_opt opts[] = {
        {"json", .type = TB_OPT_FLAG, .dest = &json, .help = "print JSON instead of text"},
        {"check", .type = TB_OPT_FLAG, .dest = &check,
         .help = "run a self-test kernel on every usable device and report\n"
                 "whether its results are right (and its time)"},
        {"validation", .type = TB_OPT_FLAG, .dest = &validation,
         .help = "run with the Khronos validation layer (also: TB_VK_VALIDATION=1);\n"
                 "any validation message makes the exit status 1"},
        {0},
    };
    const tb_cli cli = {
        .prog = "testbed devices",
        .err = "testbed devices: error: ",
        .usage = "[options]",
        .intro = "\n"
                 "Lists the Vulkan devices the loader sees: index, name, type, driver, Vulkan\n"
                 "version, subgroup size, workgroup limits, memory heaps, timestamp support and\n"
                 "float controls. Marks the device that --backend vulkan uses and says what\n"
                 "--backend auto chooses (Vulkan only on a discrete, integrated or virtual GPU;\n"
                 "otherwise the CPU path, which is faster than a CPU Vulkan driver such as lavapipe).\n",
        .opts = opts,
        .outro = "\n"
                 "Environment: TB_VULKAN_LOADER (loader library, default libvulkan.so.1),\n"
                 "VK_DRIVER_FILES / VK_ICD_FILENAMES (which drivers the loader loads).\n"
                 "\n"
                 "Exit status: 0 listed (also when there is no Vulkan loader, driver or device:\n"
                 "that is reported, and the CPU path is used), 1 a --check self-test failed or\n"
                 "--validation reported a message, 2 usage error.",
    };
    int npos, prc = tb_cli_parse(&cli, argc, argv, &npos);
    if (prc != TB_CLI_OK)
        return prc;
    /* Messages go to stderr as they come (quiet = false) and are counted. */
    tb_gpu_instance *inst = tb_gpu_instance_create(&(tb_gpu_instance_desc){.validation = validation});
    if (!inst) {
        /* No loader, no driver: a normal state for a machine without Vulkan.
         * The listing is empty and the CPU path is what every command uses. */
        char error[512];
        snprintf(error, sizeof error, "%s", tb_last_error());
        if (json) {
            char vk[600], reason[600];
            snprintf(vk, sizeof vk, "fails: Vulkan is not available: %s", error);
            snprintf(reason, sizeof reason, "using the CPU path: Vulkan is not available: %s", error);
            tb__print_json(stdout, NULL, error, -1, vk, -1, reason, NULL);
        } else {
            printf("no Vulkan devices: %s\n--backend auto uses the CPU path; --backend vulkan fails.\n", error);
        }
        return TB_EXIT_OK;
    }
    int n = tb_gpu_device_count(inst);
    const tb_gpu_device_info *infos = n ? tb_gpu_device_info_at(inst, 0) : NULL;
    char vk_reason[512], auto_reason[512];
    int vk_index = -1, auto_index = -1;
    if (tb_gpu_pick_device(infos, n, TB_GPU_MODE_VULKAN, -1, &vk_index, vk_reason, sizeof vk_reason))
        snprintf(vk_reason, sizeof vk_reason, "fails: %s", tb_last_error());
    tb_gpu_pick_device(infos, n, TB_GPU_MODE_AUTO, -1, &auto_index, auto_reason, sizeof auto_reason);
    int status = TB_EXIT_OK;
    tb__check checks[64];
    memset(checks, 0, sizeof checks);
    if (check)
        for (int i = 0; i < n && i < 64; i++)
            if (tb_gpu_device_info_at(inst, i)->usable) {
                tb__run_check(inst, i, &checks[i]);
                if (!checks[i].ok)
                    status = TB_EXIT_FAIL;
            }
    if (json)
        tb__print_json(stdout, inst, NULL, vk_index, vk_reason, auto_index, auto_reason, check ? checks : NULL);
    else if (n == 0)
        printf("no Vulkan devices: the loader (Vulkan %s) found no device.\n--backend auto uses the CPU path; "
               "--backend vulkan fails.\n", tb_gpu_version_string(tb_gpu_loader_version(inst), (char[16]){0}));
    else
        tb__print_text(stdout, inst, vk_index, vk_reason, auto_index, auto_reason, check ? checks : NULL);
    if (tb_gpu_validation_enabled(inst)) {
        int e = tb_gpu_validation_errors(inst), w = tb_gpu_validation_warnings(inst);
        fprintf(stderr, "validation: %d error%s, %d warning%s\n", e, e == 1 ? "" : "s", w, w == 1 ? "" : "s");
        if (e + w > 0)
            status = TB_EXIT_FAIL;
    }
    tb_gpu_instance_destroy(inst);
    return status;
}
