/* Storage buffers. Where device memory is ordinary host RAM (integrated GPUs,
 * lavapipe) a buffer is allocated host-visible and coherent and stays mapped,
 * so upload and download are memcpy. Otherwise (discrete GPUs, or
 * force_staging) it lives in device-local memory and data goes through a
 * host-visible staging buffer with a copy command. One allocation per buffer:
 * the kernels use a handful of large buffers, far below any driver's
 * maxMemoryAllocationCount (>= 4096). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "host/gpu/gpu_internal.h"
#include "util/stats/stats.h"

TB_STAT_MEMORY(tb__gpu_buffer_bytes, "GPU/buffer memory");
TB_STAT_MEMORY(tb__gpu_uploaded, "GPU/uploaded");
TB_STAT_MEMORY(tb__gpu_downloaded, "GPU/downloaded");

/* A memory type in `bits` with all of `need`, preferring one that also has
 * `want`; UINT32_MAX if none. */
static uint32_t tb__memory_type(const tb_gpu_device *dev, uint32_t bits, VkMemoryPropertyFlags need,
                                VkMemoryPropertyFlags want)
{
    uint32_t fallback = UINT32_MAX;
    for (uint32_t t = 0; t < dev->mem.memoryTypeCount; t++) {
        VkMemoryPropertyFlags f = dev->mem.memoryTypes[t].propertyFlags;
        if (!(bits & (1u << t)) || (f & need) != need)
            continue;
        if ((f & want) == want)
            return t;
        if (fallback == UINT32_MAX)
            fallback = t;
    }
    return fallback;
}

static void tb__bytes(char *buf, size_t cap, uint64_t n)
{
    if (n >= (1ull << 30))
        snprintf(buf, cap, "%.2f GiB", (double)n / (double)(1ull << 30));
    else if (n >= (1ull << 20))
        snprintf(buf, cap, "%.2f MiB", (double)n / (double)(1ull << 20));
    else
        snprintf(buf, cap, "%llu bytes", (unsigned long long)n);
}

tb_gpu_buffer *tb__gpu_buffer_new(tb_gpu_device *dev, size_t size, VkBufferUsageFlags usage, bool host_visible)
{
    tb_gpu_buffer *b = calloc(1, sizeof *b);
    if (!b) {
        tb_error(TB_ERR_NOMEM, "out of memory creating a GPU buffer");
        return NULL;
    }
    b->dev = dev;
    b->size = size;
    /* Whole words: fills and copies work on 4-byte units. */
    VkDeviceSize vksize = ((VkDeviceSize)size + 3u) & ~(VkDeviceSize)3u;
    VkBufferCreateInfo bci = {.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO,
                              .size = vksize,
                              .usage = usage,
                              .sharingMode = VK_SHARING_MODE_EXCLUSIVE};
    VkResult r = dev->fn.vkCreateBuffer(dev->vk, &bci, NULL, &b->vk);
    if (r != VK_SUCCESS) {
        tb__gpu_fail(dev, r, "vkCreateBuffer");
        free(b);
        return NULL;
    }
    VkMemoryRequirements req;
    dev->fn.vkGetBufferMemoryRequirements(dev->vk, b->vk, &req);
    const VkMemoryPropertyFlags hv = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    uint32_t type;
    if (host_visible) /* a mapped buffer wants device-local RAM; a staging buffer takes any */
        type = tb__memory_type(dev, req.memoryTypeBits, hv, dev->mapped ? VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT : 0);
    else
        type = tb__memory_type(dev, req.memoryTypeBits, 0, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
    if (type == UINT32_MAX) {
        tb_error(TB_ERR_DEVICE, "Vulkan device %d (%s) has no %s memory type for a storage buffer",
                 dev->index, dev->info->name, host_visible ? "host-visible coherent" : "suitable");
        dev->fn.vkDestroyBuffer(dev->vk, b->vk, NULL);
        free(b);
        return NULL;
    }
    uint32_t heap = dev->mem.memoryTypes[type].heapIndex;
    if (req.size > dev->mem.memoryHeaps[heap].size) {
        char want[32], have[32];
        tb__bytes(want, sizeof want, req.size);
        tb__bytes(have, sizeof have, dev->mem.memoryHeaps[heap].size);
        tb_error(TB_ERR_DEVICE, "out of device memory: a buffer of %s does not fit in memory heap %u "
                 "(%s) of device %d (%s)", want, heap, have, dev->index, dev->info->name);
        dev->fn.vkDestroyBuffer(dev->vk, b->vk, NULL);
        free(b);
        return NULL;
    }
    VkMemoryAllocateInfo mai = {.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO,
                                .allocationSize = req.size,
                                .memoryTypeIndex = type};
    r = dev->fn.vkAllocateMemory(dev->vk, &mai, NULL, &b->memory);
    if (r != VK_SUCCESS) {
        char what[96], want[32];
        tb__bytes(want, sizeof want, req.size);
        snprintf(what, sizeof what, "allocating %s of GPU memory", want);
        tb__gpu_fail(dev, r, what);
        dev->fn.vkDestroyBuffer(dev->vk, b->vk, NULL);
        free(b);
        return NULL;
    }
    if ((r = dev->fn.vkBindBufferMemory(dev->vk, b->vk, b->memory, 0)) != VK_SUCCESS ||
        (host_visible && (r = dev->fn.vkMapMemory(dev->vk, b->memory, 0, VK_WHOLE_SIZE, 0, &b->map)) != VK_SUCCESS)) {
        tb__gpu_fail(dev, r, host_visible ? "binding or mapping GPU memory" : "vkBindBufferMemory");
        dev->fn.vkDestroyBuffer(dev->vk, b->vk, NULL);
        dev->fn.vkFreeMemory(dev->vk, b->memory, NULL);
        free(b);
        return NULL;
    }
    b->allocated = req.size;
    tb_stat_add(&tb__gpu_buffer_bytes, (int64_t)req.size);
    dev->nbuffers++;
    return b;
}

tb_gpu_buffer *tb_gpu_buffer_create(tb_gpu_device *dev, size_t size)
{
    if (!dev) {
        tb_error(TB_ERR_ARG, "tb_gpu_buffer_create: no device");
        return NULL;
    }
    if (tb__gpu_check_alive(dev))
        return NULL;
    if (size == 0) {
        tb_error(TB_ERR_ARG, "tb_gpu_buffer_create: size 0");
        return NULL;
    }
    if ((uint64_t)size > dev->info->max_storage_buffer_range) {
        char want[32], have[32];
        tb__bytes(want, sizeof want, size);
        tb__bytes(have, sizeof have, dev->info->max_storage_buffer_range);
        tb_error(TB_ERR_DEVICE, "a storage buffer of %s exceeds the limit of device %d (%s): "
                 "maxStorageBufferRange is %s", want, dev->index, dev->info->name, have);
        return NULL;
    }
    /* Any buffer may also be bound as a texel buffer (tb_gpu_binding_kind). */
    VkBufferUsageFlags usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT |
                               VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    tb_gpu_buffer *b = tb__gpu_buffer_new(dev, size, usage, dev->mapped);
    if (!b)
        return NULL;
    /* Zero-filled, so a kernel that leaves an element unwritten reads back 0,
     * the same on every device. */
    if (b->map) {
        memset(b->map, 0, (size + 3u) & ~(size_t)3u);
        return b;
    }
    tb_status st = tb__gpu_begin(dev);
    if (!st) {
        tb__gpu_barrier(dev, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                        VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT,
                        VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
        dev->fn.vkCmdFillBuffer(dev->cmd, b->vk, 0, VK_WHOLE_SIZE, 0u);
        st = tb__gpu_submit_wait(dev, "clearing a new buffer");
    }
    if (st) {
        tb_gpu_buffer_destroy(b);
        return NULL;
    }
    return b;
}

void tb_gpu_buffer_destroy(tb_gpu_buffer *b)
{
    if (!b)
        return;
    tb_gpu_device *dev = b->dev;
    /* After a timeout a kernel may still be using the buffer. */
    if (dev->lost)
        dev->fn.vkDeviceWaitIdle(dev->vk);
    if (b->map)
        dev->fn.vkUnmapMemory(dev->vk, b->memory);
    for (int k = 0; k < 3; k++)
        if (b->views[k])
            dev->fn.vkDestroyBufferView(dev->vk, b->views[k], NULL);
    dev->fn.vkDestroyBuffer(dev->vk, b->vk, NULL);
    dev->fn.vkFreeMemory(dev->vk, b->memory, NULL);
    tb_stat_add(&tb__gpu_buffer_bytes, -(int64_t)b->allocated);
    dev->nbuffers--;
    free(b);
}

size_t tb_gpu_buffer_size(const tb_gpu_buffer *b) { return b->size; }

VkBufferView tb__gpu_buffer_view(tb_gpu_buffer *b, int kind)
{
    if (b->views[kind])
        return b->views[kind];
    tb_gpu_device *dev = b->dev;
    bool rgba = kind == TB_GPU_BIND_TEXELS_RGBA32UI;
    uint64_t texel = rgba ? 16u : 4u, n = (uint64_t)b->size / texel;
    if (n == 0 || n > dev->info->max_texel_buffer_elements) {
        tb_error(TB_ERR_DEVICE, "a texel buffer of %llu texels exceeds the limit of device %d (%s): "
                 "maxTexelBufferElements is %llu", (unsigned long long)n, dev->index, dev->info->name,
                 (unsigned long long)dev->info->max_texel_buffer_elements);
        return VK_NULL_HANDLE;
    }
    VkBufferViewCreateInfo ci = {.sType = VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO,
                                 .buffer = b->vk,
                                 .format = rgba ? VK_FORMAT_R32G32B32A32_UINT : VK_FORMAT_R32_UINT,
                                 .offset = 0,
                                 .range = n * texel};
    VkResult r = dev->fn.vkCreateBufferView(dev->vk, &ci, NULL, &b->views[kind]);
    if (r != VK_SUCCESS) {
        b->views[kind] = VK_NULL_HANDLE;
        tb__gpu_fail(dev, r, "vkCreateBufferView");
        return VK_NULL_HANDLE;
    }
    return b->views[kind];
}

static tb_status tb__range(const tb_gpu_buffer *b, size_t offset, size_t n, const void *p, const char *what)
{
    if (!b)
        return tb_error(TB_ERR_ARG, "%s: no buffer", what);
    if (n > 0 && !p)
        return tb_error(TB_ERR_ARG, "%s: NULL data pointer", what);
    if (offset > b->size || n > b->size - offset)
        return tb_error(TB_ERR_ARG, "%s: bytes [%zu, %zu) outside the buffer of %zu bytes", what, offset,
                        offset + n, b->size);
    return tb__gpu_check_alive(b->dev);
}

/* The device's staging buffer, at least min(n, dev->staging_max) bytes. */
static tb_gpu_buffer *tb__staging(tb_gpu_device *dev, size_t n)
{
    size_t want = n < dev->staging_max ? n : dev->staging_max;
    if (dev->staging && dev->staging->size >= want)
        return dev->staging;
    if (want < ((size_t)1 << 20) && dev->staging_max >= ((size_t)1 << 20))
        want = (size_t)1 << 20; /* small transfers share one buffer */
    tb_gpu_buffer *s = tb__gpu_buffer_new(dev, want, VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT, true);
    if (!s)
        return NULL;
    dev->nbuffers--; /* owned by the device, not counted as a user buffer */
    if (dev->staging) {
        dev->nbuffers++;
        tb_gpu_buffer_destroy(dev->staging);
    }
    dev->staging = s;
    return s;
}

tb_status tb_gpu_buffer_upload(tb_gpu_buffer *b, size_t offset, const void *src, size_t n)
{
    tb_status st = tb__range(b, offset, n, src, "tb_gpu_buffer_upload");
    if (st || n == 0)
        return st;
    tb_gpu_device *dev = b->dev;
    tb_stat_add(&tb__gpu_uploaded, (int64_t)n);
    if (b->map) {
        memcpy((char *)b->map + offset, src, n);
        return TB_OK;
    }
    tb_gpu_buffer *s = tb__staging(dev, n);
    if (!s)
        return tb_error_context(TB_ERR_DEVICE, "uploading %zu bytes", n);
    for (size_t done = 0; done < n;) {
        size_t chunk = n - done < s->size ? n - done : s->size;
        memcpy(s->map, (const char *)src + done, chunk);
        if ((st = tb__gpu_begin(dev)))
            return st;
        /* Earlier kernels and copies may still read or write the target. */
        tb__gpu_barrier(dev, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                        VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT,
                        VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT);
        VkBufferCopy region = {.srcOffset = 0, .dstOffset = offset + done, .size = chunk};
        dev->fn.vkCmdCopyBuffer(dev->cmd, s->vk, b->vk, 1, &region);
        if ((st = tb__gpu_submit_wait(dev, "an upload")))
            return st;
        done += chunk;
    }
    return TB_OK;
}

tb_status tb_gpu_buffer_download(tb_gpu_buffer *b, size_t offset, void *dst, size_t n)
{
    tb_status st = tb__range(b, offset, n, dst, "tb_gpu_buffer_download");
    if (st || n == 0)
        return st;
    tb_gpu_device *dev = b->dev;
    tb_stat_add(&tb__gpu_downloaded, (int64_t)n);
    if (b->map) {
        /* tb_gpu_run ends with a barrier making kernel writes visible to the host. */
        memcpy(dst, (const char *)b->map + offset, n);
        return TB_OK;
    }
    tb_gpu_buffer *s = tb__staging(dev, n);
    if (!s)
        return tb_error_context(TB_ERR_DEVICE, "downloading %zu bytes", n);
    for (size_t done = 0; done < n;) {
        size_t chunk = n - done < s->size ? n - done : s->size;
        if ((st = tb__gpu_begin(dev)))
            return st;
        tb__gpu_barrier(dev, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                        VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT,
                        VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT);
        VkBufferCopy region = {.srcOffset = offset + done, .dstOffset = 0, .size = chunk};
        dev->fn.vkCmdCopyBuffer(dev->cmd, b->vk, s->vk, 1, &region);
        tb__gpu_barrier(dev, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                        VK_PIPELINE_STAGE_HOST_BIT, VK_ACCESS_HOST_READ_BIT);
        if ((st = tb__gpu_submit_wait(dev, "a download")))
            return st;
        memcpy((char *)dst + done, s->map, chunk);
        done += chunk;
    }
    return TB_OK;
}
