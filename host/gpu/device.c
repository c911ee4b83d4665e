/* Logical device: one compute queue, one command buffer reused for every
 * submission (each submission is waited for, so there is never more than one
 * in flight), a fence, and the pipeline cache. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "host/gpu/gpu_internal.h"
#include "util/stats/stats.h"

TB_STAT_TIMER(tb__gpu_wait_time, "GPU/submit and wait (host)");

tb_gpu_device *tb_gpu_device_create(tb_gpu_instance *inst, int index, const tb_gpu_device_desc *desc)
{
    tb_gpu_device_desc none = {0};
    if (!desc)
        desc = &none;
    if (!inst) {
        tb_error(TB_ERR_ARG, "tb_gpu_device_create: no instance");
        return NULL;
    }
    const tb_gpu_device_info *info = tb_gpu_device_info_at(inst, index);
    if (!info) {
        tb_error(TB_ERR_ARG, "Vulkan device %d does not exist (%d device%s)", index, inst->ndevices,
                 inst->ndevices == 1 ? "" : "s");
        return NULL;
    }
    if (!info->usable) {
        tb_error(TB_ERR_DEVICE, "Vulkan device %d (%s) cannot be used: it %s", index, info->name,
                 info->unusable_reason);
        return NULL;
    }
    tb_gpu_device *dev = calloc(1, sizeof *dev);
    if (!dev) {
        tb_error(TB_ERR_NOMEM, "out of memory creating a Vulkan device");
        return NULL;
    }
    dev->inst = inst;
    dev->index = index;
    dev->info = info;
    dev->phys = inst->phys[index];
    dev->family = inst->compute_family[index];
    dev->mapped = info->unified_memory && !desc->force_staging;
    dev->staging_max = (size_t)32 << 20;
    dev->timeout_ns = (uint64_t)(desc->timeout_ms ? desc->timeout_ms : 60000u) * 1000000u;
    inst->fn.vkGetPhysicalDeviceMemoryProperties(dev->phys, &dev->mem);

    float priority = 1.0f;
    VkDeviceQueueCreateInfo qci = {.sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO,
                                   .queueFamilyIndex = dev->family,
                                   .queueCount = 1,
                                   .pQueuePriorities = &priority};
    VkDeviceCreateInfo ci = {.sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO,
                             .queueCreateInfoCount = 1,
                             .pQueueCreateInfos = &qci};
    VkResult r = inst->fn.vkCreateDevice(dev->phys, &ci, NULL, &dev->vk);
    if (r != VK_SUCCESS) {
        char what[320];
        snprintf(what, sizeof what, "creating device %d (%s)", index, info->name);
        tb__gpu_fail(NULL, r, what);
        free(dev);
        return NULL;
    }
    bool complete = true;
#define TB__VK_LOAD_DEVICE(name)                                                        \
    dev->fn.name = (PFN_##name)inst->fn.vkGetDeviceProcAddr(dev->vk, #name);             \
    complete = complete && dev->fn.name != NULL;
    TB__VK_DEVICE_FNS(TB__VK_LOAD_DEVICE)
#undef TB__VK_LOAD_DEVICE
    if (!complete) {
        tb_error(TB_ERR_DEVICE, "Vulkan device %d (%s) lacks core 1.0 entry points", index, info->name);
        if (dev->fn.vkDestroyDevice)
            dev->fn.vkDestroyDevice(dev->vk, NULL);
        free(dev);
        return NULL;
    }
    dev->fn.vkGetDeviceQueue(dev->vk, dev->family, 0, &dev->queue);

    VkPipelineCacheCreateInfo pcci = {.sType = VK_STRUCTURE_TYPE_PIPELINE_CACHE_CREATE_INFO};
    VkCommandPoolCreateInfo cpci = {.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO,
                                    .flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT,
                                    .queueFamilyIndex = dev->family};
    VkFenceCreateInfo fci = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    if ((r = dev->fn.vkCreatePipelineCache(dev->vk, &pcci, NULL, &dev->cache)) != VK_SUCCESS) {
        tb__gpu_fail(NULL, r, "vkCreatePipelineCache");
        goto fail;
    }
    if ((r = dev->fn.vkCreateCommandPool(dev->vk, &cpci, NULL, &dev->pool)) != VK_SUCCESS) {
        tb__gpu_fail(NULL, r, "vkCreateCommandPool");
        goto fail;
    }
    VkCommandBufferAllocateInfo cbai = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO,
                                        .commandPool = dev->pool,
                                        .level = VK_COMMAND_BUFFER_LEVEL_PRIMARY,
                                        .commandBufferCount = 1};
    if ((r = dev->fn.vkAllocateCommandBuffers(dev->vk, &cbai, &dev->cmd)) != VK_SUCCESS) {
        tb__gpu_fail(NULL, r, "vkAllocateCommandBuffers");
        goto fail;
    }
    if ((r = dev->fn.vkCreateFence(dev->vk, &fci, NULL, &dev->fence)) != VK_SUCCESS) {
        tb__gpu_fail(NULL, r, "vkCreateFence");
        goto fail;
    }
    return dev;
fail:
    tb_gpu_device_destroy(dev);
    return NULL;
}

void tb_gpu_device_destroy(tb_gpu_device *dev)
{
    if (!dev)
        return;
    /* A timed-out submission may still be running: wait for it before
     * freeing anything it uses (an error here changes nothing). */
    dev->fn.vkDeviceWaitIdle(dev->vk);
    tb__gpu_kernels_destroy(dev);
    if (dev->staging) {
        tb_gpu_buffer *s = dev->staging;
        dev->staging = NULL;
        dev->nbuffers++; /* tb_gpu_buffer_destroy counts it down */
        tb_gpu_buffer_destroy(s);
    }
    if (dev->queries)
        dev->fn.vkDestroyQueryPool(dev->vk, dev->queries, NULL);
    if (dev->descriptors)
        dev->fn.vkDestroyDescriptorPool(dev->vk, dev->descriptors, NULL);
    if (dev->fence)
        dev->fn.vkDestroyFence(dev->vk, dev->fence, NULL);
    if (dev->pool)
        dev->fn.vkDestroyCommandPool(dev->vk, dev->pool, NULL);
    if (dev->cache)
        dev->fn.vkDestroyPipelineCache(dev->vk, dev->cache, NULL);
    if (dev->nbuffers > 0)
        fprintf(stderr, "tb_gpu_device_destroy: %d buffer%s still alive on device %d (leaked)\n",
                dev->nbuffers, dev->nbuffers == 1 ? "" : "s", dev->index);
    dev->fn.vkDestroyDevice(dev->vk, NULL);
    free(dev);
}

const tb_gpu_device_info *tb_gpu_device_info_of(const tb_gpu_device *dev) { return dev->info; }

bool tb_gpu_device_is_lost(const tb_gpu_device *dev) { return dev->lost; }

bool tb_gpu_device_uses_mapped_buffers(const tb_gpu_device *dev) { return dev->mapped; }

tb_status tb__gpu_begin(tb_gpu_device *dev)
{
    VkCommandBufferBeginInfo bi = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
                                   .flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT};
    VkResult r = dev->fn.vkBeginCommandBuffer(dev->cmd, &bi);
    return r == VK_SUCCESS ? TB_OK : tb__gpu_fail(dev, r, "vkBeginCommandBuffer");
}

tb_status tb__gpu_submit_wait(tb_gpu_device *dev, const char *what)
{
    char ctx[160];
    VkResult r = dev->fn.vkEndCommandBuffer(dev->cmd);
    if (r != VK_SUCCESS) {
        snprintf(ctx, sizeof ctx, "recording %s", what);
        return tb__gpu_fail(dev, r, ctx);
    }
    if ((r = dev->fn.vkResetFences(dev->vk, 1, &dev->fence)) != VK_SUCCESS)
        return tb__gpu_fail(dev, r, "vkResetFences");
    VkSubmitInfo si = {.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO,
                       .commandBufferCount = 1,
                       .pCommandBuffers = &dev->cmd};
    tb_timer_token t = tb_timer_start(&tb__gpu_wait_time);
    r = dev->fn.vkQueueSubmit(dev->queue, 1, &si, dev->fence);
    if (r != VK_SUCCESS) {
        tb_timer_stop(t);
        snprintf(ctx, sizeof ctx, "submitting %s", what);
        return tb__gpu_fail(dev, r, ctx);
    }
    r = dev->fn.vkWaitForFences(dev->vk, 1, &dev->fence, VK_TRUE, dev->timeout_ns);
    tb_timer_stop(t);
    if (r == VK_TIMEOUT) {
        dev->lost = true;
        return tb_error(TB_ERR_DEVICE, "Vulkan: %s did not finish within %.3g s on device %d (%s); "
                        "the device is treated as lost", what, (double)dev->timeout_ns * 1e-9,
                        dev->index, dev->info->name);
    }
    if (r != VK_SUCCESS) {
        snprintf(ctx, sizeof ctx, "waiting for %s", what);
        return tb__gpu_fail(dev, r, ctx);
    }
    return TB_OK;
}

void tb__gpu_barrier(tb_gpu_device *dev, VkPipelineStageFlags src_stage, VkAccessFlags src,
                     VkPipelineStageFlags dst_stage, VkAccessFlags dst)
{
    VkMemoryBarrier b = {.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER, .srcAccessMask = src, .dstAccessMask = dst};
    dev->fn.vkCmdPipelineBarrier(dev->cmd, src_stage, dst_stage, 0, 1, &b, 0, NULL, 0, NULL);
}
