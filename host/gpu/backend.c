/* Choosing between the Vulkan kernels and the CPU path (--backend, --device). */
#include <stdio.h>
#include <string.h>

#include "host/gpu/gpu_internal.h"

/* The CPU backend with `reason` set. */
static void tb__cpu(tb_gpu_session *out)
{
    out->backend = TB_GPU_BACKEND_CPU;
    out->instance = NULL;
    out->device = NULL;
    out->device_index = -1;
}

tb_status tb_gpu_backend_choose(tb_gpu_mode mode, int device, bool validation, tb_gpu_session *out)
{
    memset(out, 0, sizeof *out);
    tb__cpu(out);
    if (mode == TB_GPU_MODE_CPU) {
        snprintf(out->reason, sizeof out->reason, "the CPU backend was requested");
        return TB_OK;
    }
    tb_gpu_instance_desc idesc = {.validation = validation};
    tb_gpu_instance *inst = tb_gpu_instance_create(&idesc);
    if (!inst) {
        char why[400];
        snprintf(why, sizeof why, "%s", tb_last_error());
        if (mode == TB_GPU_MODE_VULKAN) {
            snprintf(out->reason, sizeof out->reason, "Vulkan is not available: %s", why);
            return tb_error(TB_ERR_DEVICE, "--backend vulkan: %s", out->reason);
        }
        snprintf(out->reason, sizeof out->reason, "using the CPU path: Vulkan is not available: %s", why);
        tb_clear_error();
        return TB_OK;
    }
    int index;
    tb_status st = tb_gpu_pick_device(inst->info, inst->ndevices, mode, device, &index, out->reason,
                                      sizeof out->reason);
    if (st || index < 0) {
        tb_gpu_instance_destroy(inst);
        return st;
    }
    tb_gpu_device *dev = tb_gpu_device_create(inst, index, NULL);
    if (!dev) {
        char why[384];
        snprintf(why, sizeof why, "%s", tb_last_error());
        tb_gpu_instance_destroy(inst);
        if (mode == TB_GPU_MODE_VULKAN) {
            snprintf(out->reason, sizeof out->reason, "Vulkan device %d could not be opened: %s", index, why);
            return tb_error(TB_ERR_DEVICE, "--backend vulkan: %s", out->reason);
        }
        snprintf(out->reason, sizeof out->reason, "using the CPU path: Vulkan device %d could not be opened: %s",
                 index, why);
        tb_clear_error();
        return TB_OK;
    }
    out->backend = TB_GPU_BACKEND_VULKAN;
    out->instance = inst;
    out->device = dev;
    out->device_index = index;
    return TB_OK;
}

void tb_gpu_session_close(tb_gpu_session *s)
{
    if (!s)
        return;
    tb_gpu_device_destroy(s->device);
    tb_gpu_instance_destroy(s->instance);
    tb__cpu(s);
}
