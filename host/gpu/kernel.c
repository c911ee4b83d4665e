/* Compute kernels (pipelines) and their submission.
 *
 * A kernel is a compute pipeline for one SPIR-V module with storage buffers at
 * set 0, bindings 0..n-1, optional push constants and specialization
 * constants; constant_id 0 is the workgroup width. Kernels are cached per
 * device by their full description, so asking again is a lookup: drivers
 * compile pipelines just in time (lavapipe takes milliseconds per pipeline),
 * and callers need not keep kernels around. The VkPipelineCache passed to
 * every creation lets the driver share compiled code between variants. */
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "host/gpu/gpu_internal.h"
#include "util/stats/stats.h"

TB_STAT_COUNTER(tb__gpu_dispatches, "GPU/dispatches");
TB_STAT_COUNTER(tb__gpu_compiled, "GPU/pipelines compiled");
TB_STAT_COUNTER(tb__gpu_reused, "GPU/pipeline requests served by the kernel cache");
TB_STAT_TIMER(tb__gpu_compile_time, "GPU/pipeline creation");

#define TB__SPIRV_MAGIC 0x07230203u

/* ---------------------------------------------------------------- per-kernel timing statistics */

/* A run-time statistic per kernel name, kept for the life of the process (the
 * stats registry holds pointers to it). */
typedef struct tb__kernel_stat {
    tb_stat stat;
    struct tb__kernel_stat *next;
    char name[];
} tb__kernel_stat;

static pthread_mutex_t tb__kstat_lock = PTHREAD_MUTEX_INITIALIZER;
static tb__kernel_stat *tb__kstats;

/* The distribution "GPU/kernel <name> (ns)", created on first use; NULL if out of memory. */
static tb_stat *tb__kernel_stat_for(const char *kernel)
{
    char full[128];
    snprintf(full, sizeof full, "GPU/kernel %s (ns)", kernel);
    pthread_mutex_lock(&tb__kstat_lock);
    tb__kernel_stat *s = tb__kstats;
    while (s && strcmp(s->name, full) != 0)
        s = s->next;
    if (!s) {
        size_t len = strlen(full) + 1;
        s = malloc(sizeof *s + len);
        if (s) {
            memcpy(s->name, full, len);
            s->stat.name = s->name;
            s->stat.kind = TB_STAT_KIND_DISTRIBUTION;
            atomic_init(&s->stat.slot, 0u);
            s->stat.next = NULL;
            s->next = tb__kstats;
            tb__kstats = s;
            tb_stat_register(&s->stat);
        }
    }
    pthread_mutex_unlock(&tb__kstat_lock);
    return s ? &s->stat : NULL;
}

/* ---------------------------------------------------------------- kernel creation */

static uint64_t tb__fnv1a(const uint32_t *words, size_t bytes)
{
    const unsigned char *p = (const unsigned char *)words;
    uint64_t h = 14695981039346656037ull;
    for (size_t i = 0; i < bytes; i++)
        h = (h ^ p[i]) * 1099511628211ull;
    return h;
}

static VkDescriptorType tb__descriptor_type(int kind)
{
    return kind == TB_GPU_BIND_STORAGE ? VK_DESCRIPTOR_TYPE_STORAGE_BUFFER : VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
}

static bool tb__key_equal(const tb__gpu_kernel_key *a, const tb__gpu_kernel_key *b)
{
    if (a->hash != b->hash || a->size != b->size || a->buffers != b->buffers ||
        a->push_size != b->push_size || a->workgroup_size != b->workgroup_size ||
        a->spec_count != b->spec_count || memcmp(a->kinds, b->kinds, sizeof a->kinds) != 0)
        return false;
    for (int i = 0; i < a->spec_count; i++)
        if (a->spec[i].id != b->spec[i].id || a->spec[i].value != b->spec[i].value)
            return false;
    return a->words == b->words || memcmp(a->words, b->words, a->size) == 0;
}

/* True if the module decorates a specialization constant with SpecId 0 (what
 * layout(local_size_x_id = 0) compiles to): the host then knows the
 * workgroup width it dispatches with. */
static bool tb__has_spec_id0(const uint32_t *w, size_t nwords)
{
    enum { OP_DECORATE = 71, DECORATION_SPEC_ID = 1 };
    for (size_t i = 5; i < nwords;) {
        uint32_t count = w[i] >> 16, op = w[i] & 0xffffu;
        if (count == 0 || i + count > nwords)
            return false; /* malformed; vkCreateShaderModule will say more */
        if (op == OP_DECORATE && count >= 4 && w[i + 2] == DECORATION_SPEC_ID && w[i + 3] == 0)
            return true;
        i += count;
    }
    return false;
}

static tb_status tb__check_desc(const tb_gpu_device *dev, const tb_gpu_kernel_desc *d, const char *name,
                                uint32_t *wg)
{
    const tb_gpu_device_info *info = dev->info;
    const tb_gpu_spirv *m = d->spirv;
    if (!m || !m->words)
        return tb_error(TB_ERR_ARG, "kernel %s: no SPIR-V module (is the shader built in?)", name);
    if (m->size < 20 || m->size % 4 != 0 || m->words[0] != TB__SPIRV_MAGIC)
        return tb_error(TB_ERR_ARG, "kernel %s: not a SPIR-V module (%zu bytes, first word 0x%08x)", name,
                        m->size, m->size >= 4 ? (unsigned)m->words[0] : 0u);
    if (!tb__has_spec_id0(m->words, m->size / 4))
        return tb_error(TB_ERR_ARG, "kernel %s: the shader must declare layout(local_size_x_id = 0) in; "
                        "(the host sets the workgroup width)", name);
    if (d->buffers < 0 || d->buffers > TB_GPU_MAX_BUFFERS || (uint32_t)d->buffers > info->max_storage_buffers)
        return tb_error(TB_ERR_ARG, "kernel %s: %d storage buffers (at most %d here)", name, d->buffers,
                        (int)(info->max_storage_buffers < TB_GPU_MAX_BUFFERS ? info->max_storage_buffers
                                                                             : TB_GPU_MAX_BUFFERS));
    for (int i = 0; i < d->buffers; i++)
        if (d->kinds[i] > TB_GPU_BIND_TEXELS_R32UI)
            return tb_error(TB_ERR_ARG, "kernel %s: binding %d has an unknown kind %d", name, i, d->kinds[i]);
    if (d->push_size % 4 != 0 || d->push_size > info->max_push_constants)
        return tb_error(TB_ERR_ARG, "kernel %s: %u bytes of push constants (a multiple of 4, at most %u "
                        "on device %d)", name, d->push_size, info->max_push_constants, dev->index);
    if (d->spec_count < 0 || d->spec_count > TB_GPU_MAX_SPEC || (d->spec_count > 0 && !d->spec))
        return tb_error(TB_ERR_ARG, "kernel %s: %d specialization constants (at most %d)", name,
                        d->spec_count, TB_GPU_MAX_SPEC);
    for (int i = 0; i < d->spec_count; i++) {
        if (d->spec[i].id == 0)
            return tb_error(TB_ERR_ARG, "kernel %s: constant_id 0 is the workgroup width; set "
                            "workgroup_size instead", name);
        for (int j = 0; j < i; j++)
            if (d->spec[j].id == d->spec[i].id)
                return tb_error(TB_ERR_ARG, "kernel %s: constant_id %u given twice", name, d->spec[i].id);
    }
    uint32_t limit = tb_gpu_workgroup_limit(info);
    *wg = d->workgroup_size;
    if (*wg == 0)
        *wg = tb_gpu_default_workgroup(info);
    if (*wg > limit)
        return tb_error(TB_ERR_ARG, "kernel %s: workgroup of %u exceeds the limit of %u on device %d (%s)",
                        name, *wg, limit, dev->index, info->name);
    return TB_OK;
}

static void tb__kernel_free(tb_gpu_device *dev, tb_gpu_kernel *k)
{
    if (k->pipeline)
        dev->fn.vkDestroyPipeline(dev->vk, k->pipeline, NULL);
    if (k->layout)
        dev->fn.vkDestroyPipelineLayout(dev->vk, k->layout, NULL);
    if (k->set_layout)
        dev->fn.vkDestroyDescriptorSetLayout(dev->vk, k->set_layout, NULL);
    free(k);
}

tb_gpu_kernel *tb_gpu_kernel_get(tb_gpu_device *dev, const tb_gpu_kernel_desc *d)
{
    if (!dev || !d) {
        tb_error(TB_ERR_ARG, "tb_gpu_kernel_get: no device or description");
        return NULL;
    }
    if (tb__gpu_check_alive(dev))
        return NULL;
    const char *name = d->name ? d->name : d->spirv && d->spirv->name ? d->spirv->name : "kernel";
    uint32_t wg = 0;
    if (tb__check_desc(dev, d, name, &wg))
        return NULL;
    tb__gpu_kernel_key key = {.hash = tb__fnv1a(d->spirv->words, d->spirv->size),
                              .size = d->spirv->size,
                              .words = d->spirv->words,
                              .buffers = d->buffers,
                              .push_size = d->push_size,
                              .workgroup_size = wg,
                              .spec_count = d->spec_count};
    memcpy(key.kinds, d->kinds, sizeof key.kinds);
    for (int i = 0; i < d->spec_count; i++)
        key.spec[i] = d->spec[i];
    for (tb_gpu_kernel *k = dev->kernels; k; k = k->next)
        if (tb__key_equal(&k->key, &key)) {
            TB_STAT_INC(tb__gpu_reused);
            return k;
        }

    tb_gpu_kernel *k = calloc(1, sizeof *k);
    if (!k) {
        tb_error(TB_ERR_NOMEM, "out of memory creating kernel %s", name);
        return NULL;
    }
    k->dev = dev;
    k->key = key;
    snprintf(k->name, sizeof k->name, "%s", name);
    tb_timer_token timer = tb_timer_start(&tb__gpu_compile_time);
    char what[128] = "";
    VkResult r = VK_SUCCESS;

    VkDescriptorSetLayoutBinding bindings[TB_GPU_MAX_BUFFERS];
    for (int i = 0; i < d->buffers; i++)
        bindings[i] = (VkDescriptorSetLayoutBinding){.binding = (uint32_t)i,
                                                     .descriptorType = tb__descriptor_type(d->kinds[i]),
                                                     .descriptorCount = 1,
                                                     .stageFlags = VK_SHADER_STAGE_COMPUTE_BIT};
    VkDescriptorSetLayoutCreateInfo dslci = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
                                             .bindingCount = (uint32_t)d->buffers,
                                             .pBindings = bindings};
    VkPushConstantRange push = {.stageFlags = VK_SHADER_STAGE_COMPUTE_BIT, .offset = 0, .size = d->push_size};
    VkShaderModuleCreateInfo smci = {.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO,
                                     .codeSize = d->spirv->size,
                                     .pCode = d->spirv->words};
    VkShaderModule module = VK_NULL_HANDLE;
    if ((r = dev->fn.vkCreateDescriptorSetLayout(dev->vk, &dslci, NULL, &k->set_layout)) != VK_SUCCESS) {
        snprintf(what, sizeof what, "creating the descriptor set layout of kernel %s", name);
        goto fail;
    }
    VkPipelineLayoutCreateInfo plci = {.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO,
                                       .setLayoutCount = 1,
                                       .pSetLayouts = &k->set_layout,
                                       .pushConstantRangeCount = d->push_size ? 1u : 0u,
                                       .pPushConstantRanges = &push};
    if ((r = dev->fn.vkCreatePipelineLayout(dev->vk, &plci, NULL, &k->layout)) != VK_SUCCESS) {
        snprintf(what, sizeof what, "creating the pipeline layout of kernel %s", name);
        goto fail;
    }
    if ((r = dev->fn.vkCreateShaderModule(dev->vk, &smci, NULL, &module)) != VK_SUCCESS) {
        snprintf(what, sizeof what, "creating the shader module of kernel %s", name);
        goto fail;
    }
    /* Specialization data: the workgroup width at id 0, then the caller's. */
    uint32_t values[TB_GPU_MAX_SPEC + 1];
    VkSpecializationMapEntry entries[TB_GPU_MAX_SPEC + 1];
    values[0] = wg;
    entries[0] = (VkSpecializationMapEntry){.constantID = 0, .offset = 0, .size = 4};
    for (int i = 0; i < d->spec_count; i++) {
        values[i + 1] = d->spec[i].value;
        entries[i + 1] = (VkSpecializationMapEntry){.constantID = d->spec[i].id,
                                                    .offset = (uint32_t)(4 * (i + 1)),
                                                    .size = 4};
    }
    VkSpecializationInfo si = {.mapEntryCount = (uint32_t)d->spec_count + 1,
                               .pMapEntries = entries,
                               .dataSize = 4 * ((size_t)d->spec_count + 1),
                               .pData = values};
    VkComputePipelineCreateInfo cpci = {
        .sType = VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO,
        .stage = {.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO,
                  .stage = VK_SHADER_STAGE_COMPUTE_BIT,
                  .module = module,
                  .pName = "main",
                  .pSpecializationInfo = &si},
        .layout = k->layout};
    r = dev->fn.vkCreateComputePipelines(dev->vk, dev->cache, 1, &cpci, NULL, &k->pipeline);
    dev->fn.vkDestroyShaderModule(dev->vk, module, NULL);
    if (r != VK_SUCCESS) {
        k->pipeline = VK_NULL_HANDLE;
        snprintf(what, sizeof what, "compiling kernel %s", name);
        goto fail;
    }
    tb_timer_stop(timer);
    TB_STAT_INC(tb__gpu_compiled);
    k->timing = tb__kernel_stat_for(k->name);
    k->next = dev->kernels;
    dev->kernels = k;
    return k;
fail:
    tb_timer_stop(timer);
    tb__gpu_fail(dev, r, what);
    tb__kernel_free(dev, k);
    return NULL;
}

uint32_t tb_gpu_kernel_workgroup_size(const tb_gpu_kernel *k) { return k->key.workgroup_size; }

const char *tb_gpu_kernel_name(const tb_gpu_kernel *k) { return k->name; }

void tb__gpu_kernels_destroy(tb_gpu_device *dev)
{
    while (dev->kernels) {
        tb_gpu_kernel *k = dev->kernels;
        dev->kernels = k->next;
        tb__kernel_free(dev, k);
    }
}

/* ---------------------------------------------------------------- submission */

/* Descriptor pool and query pool with room for n dispatches. */
static tb_status tb__reserve(tb_gpu_device *dev, uint32_t n)
{
    VkResult r;
    if (n > dev->descriptor_cap) {
        uint32_t cap = dev->descriptor_cap ? dev->descriptor_cap : 16;
        while (cap < n)
            cap *= 2;
        if (dev->descriptors)
            dev->fn.vkDestroyDescriptorPool(dev->vk, dev->descriptors, NULL);
        dev->descriptors = VK_NULL_HANDLE;
        dev->descriptor_cap = 0;
        VkDescriptorPoolSize size[2] = {{.type = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                                         .descriptorCount = cap * TB_GPU_MAX_BUFFERS},
                                        {.type = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER,
                                         .descriptorCount = cap * TB_GPU_MAX_BUFFERS}};
        VkDescriptorPoolCreateInfo ci = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO,
                                         .maxSets = cap,
                                         .poolSizeCount = 2,
                                         .pPoolSizes = size};
        if ((r = dev->fn.vkCreateDescriptorPool(dev->vk, &ci, NULL, &dev->descriptors)) != VK_SUCCESS)
            return tb__gpu_fail(dev, r, "vkCreateDescriptorPool");
        dev->descriptor_cap = cap;
    }
    if (dev->info->timestamps && 2 * n > dev->query_cap) {
        uint32_t cap = dev->query_cap ? dev->query_cap : 32;
        while (cap < 2 * n)
            cap *= 2;
        if (dev->queries)
            dev->fn.vkDestroyQueryPool(dev->vk, dev->queries, NULL);
        dev->queries = VK_NULL_HANDLE;
        dev->query_cap = 0;
        VkQueryPoolCreateInfo ci = {.sType = VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO,
                                    .queryType = VK_QUERY_TYPE_TIMESTAMP,
                                    .queryCount = cap};
        if ((r = dev->fn.vkCreateQueryPool(dev->vk, &ci, NULL, &dev->queries)) != VK_SUCCESS)
            return tb__gpu_fail(dev, r, "vkCreateQueryPool");
        dev->query_cap = cap;
    }
    return TB_OK;
}

static tb_status tb__check_dispatch(const tb_gpu_device *dev, const tb_gpu_dispatch *d, int i, uint32_t *groups)
{
    const tb_gpu_kernel *k = d->kernel;
    if (!k || k->dev != dev)
        return tb_error(TB_ERR_ARG, "dispatch %d: %s", i, k ? "kernel of another device" : "no kernel");
    for (int b = 0; b < k->key.buffers; b++)
        if (!d->buffers[b] || d->buffers[b]->dev != dev)
            return tb_error(TB_ERR_ARG, "dispatch %d (kernel %s): buffer %d is %s", i, k->name, b,
                            d->buffers[b] ? "of another device" : "missing");
    if (k->key.push_size && !d->push)
        return tb_error(TB_ERR_ARG, "dispatch %d (kernel %s): %u bytes of push constants expected", i,
                        k->name, k->key.push_size);
    uint64_t wg = k->key.workgroup_size;
    uint64_t g = (d->items + wg - 1) / wg;
    if (g > dev->info->max_workgroup_count[0])
        return tb_error(TB_ERR_ARG, "dispatch %d (kernel %s): %llu items need %llu workgroups, more than "
                        "the %u device %d allows in one dispatch; split the work", i, k->name,
                        (unsigned long long)d->items, (unsigned long long)g,
                        dev->info->max_workgroup_count[0], dev->index);
    *groups = (uint32_t)g;
    return TB_OK;
}

tb_status tb_gpu_run(tb_gpu_device *dev, tb_gpu_dispatch *d, int n)
{
    if (!dev || n < 0 || (n > 0 && !d))
        return tb_error(TB_ERR_ARG, "tb_gpu_run: bad arguments");
    tb_status st = tb__gpu_check_alive(dev);
    if (st || n == 0)
        return st;
    uint32_t *groups = malloc((size_t)n * sizeof *groups);
    VkDescriptorSetLayout *layouts = malloc((size_t)n * sizeof *layouts);
    VkDescriptorSet *sets = malloc((size_t)n * sizeof *sets);
    VkDescriptorBufferInfo *bufs = malloc((size_t)n * TB_GPU_MAX_BUFFERS * sizeof *bufs);
    VkWriteDescriptorSet *writes = malloc((size_t)n * TB_GPU_MAX_BUFFERS * sizeof *writes);
    VkBufferView *views = malloc((size_t)n * TB_GPU_MAX_BUFFERS * sizeof *views);
    uint64_t *stamps = malloc((size_t)n * 2 * sizeof *stamps);
    if (!groups || !layouts || !sets || !bufs || !writes || !views || !stamps) {
        st = tb_error(TB_ERR_NOMEM, "tb_gpu_run: out of memory for %d dispatches", n);
        goto done;
    }
    for (int i = 0; i < n; i++) {
        if ((st = tb__check_dispatch(dev, &d[i], i, &groups[i])))
            goto done;
        layouts[i] = d[i].kernel->set_layout;
    }
    if ((st = tb__reserve(dev, (uint32_t)n)))
        goto done;
    VkResult r;
    /* The previous run has finished (every submission is waited for), so its sets can go. */
    if ((r = dev->fn.vkResetDescriptorPool(dev->vk, dev->descriptors, 0)) != VK_SUCCESS) {
        st = tb__gpu_fail(dev, r, "vkResetDescriptorPool");
        goto done;
    }
    VkDescriptorSetAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
                                      .descriptorPool = dev->descriptors,
                                      .descriptorSetCount = (uint32_t)n,
                                      .pSetLayouts = layouts};
    if ((r = dev->fn.vkAllocateDescriptorSets(dev->vk, &ai, sets)) != VK_SUCCESS) {
        st = tb__gpu_fail(dev, r, "vkAllocateDescriptorSets");
        goto done;
    }
    uint32_t nw = 0;
    for (int i = 0; i < n; i++)
        for (int b = 0; b < d[i].kernel->key.buffers; b++) {
            int kind = d[i].kernel->key.kinds[b];
            bufs[nw] = (VkDescriptorBufferInfo){.buffer = d[i].buffers[b]->vk, .offset = 0, .range = VK_WHOLE_SIZE};
            views[nw] = VK_NULL_HANDLE;
            if (kind != TB_GPU_BIND_STORAGE && !(views[nw] = tb__gpu_buffer_view(d[i].buffers[b], kind))) {
                st = TB_ERR_DEVICE;
                goto done;
            }
            writes[nw] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET,
                                                .dstSet = sets[i],
                                                .dstBinding = (uint32_t)b,
                                                .descriptorCount = 1,
                                                .descriptorType = tb__descriptor_type(kind),
                                                .pBufferInfo = kind == TB_GPU_BIND_STORAGE ? &bufs[nw] : NULL,
                                                .pTexelBufferView = kind == TB_GPU_BIND_STORAGE ? NULL : &views[nw]};
            nw++;
        }
    if (nw)
        dev->fn.vkUpdateDescriptorSets(dev->vk, nw, writes, 0, NULL);

    if ((st = tb__gpu_begin(dev)))
        goto done;
    bool timed = dev->queries != VK_NULL_HANDLE;
    if (timed)
        dev->fn.vkCmdResetQueryPool(dev->cmd, dev->queries, 0, 2u * (uint32_t)n);
    /* Uploads, clears and earlier kernels are done before the first kernel. */
    tb__gpu_barrier(dev, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                    VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT,
                    VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
    for (int i = 0; i < n; i++) {
        tb_gpu_kernel *k = d[i].kernel;
        if (i > 0) /* each kernel sees what the ones before it wrote */
            tb__gpu_barrier(dev, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                            VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                            VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
        /* Both stamps wait for the compute work recorded before them, so the
         * difference is this kernel's execution. */
        if (timed)
            dev->fn.vkCmdWriteTimestamp(dev->cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, dev->queries, 2u * (uint32_t)i);
        if (groups[i] > 0) {
            dev->fn.vkCmdBindPipeline(dev->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, k->pipeline);
            dev->fn.vkCmdBindDescriptorSets(dev->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, k->layout, 0, 1, &sets[i], 0, NULL);
            if (k->key.push_size)
                dev->fn.vkCmdPushConstants(dev->cmd, k->layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, k->key.push_size,
                                           d[i].push);
            dev->fn.vkCmdDispatch(dev->cmd, groups[i], 1, 1);
        }
        if (timed)
            dev->fn.vkCmdWriteTimestamp(dev->cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, dev->queries,
                                        2u * (uint32_t)i + 1u);
    }
    /* Results are read by the host (mapped buffers) or copied out. */
    tb__gpu_barrier(dev, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                    VK_PIPELINE_STAGE_HOST_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                    VK_ACCESS_HOST_READ_BIT | VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT);
    char what[160];
    snprintf(what, sizeof what, "%d dispatch%s (first: kernel %s)", n, n == 1 ? "" : "es", d[0].kernel->name);
    if ((st = tb__gpu_submit_wait(dev, what)))
        goto done;
    tb_stat_add(&tb__gpu_dispatches, n);

    if (timed) {
        r = dev->fn.vkGetQueryPoolResults(dev->vk, dev->queries, 0, 2u * (uint32_t)n, (size_t)n * 2 * sizeof *stamps,
                                          stamps, sizeof *stamps, VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT);
        if (r != VK_SUCCESS) {
            st = tb__gpu_fail(dev, r, "reading kernel timestamps");
            goto done;
        }
        uint32_t bits = dev->info->timestamp_valid_bits;
        uint64_t mask = bits >= 64 ? ~0ull : (1ull << bits) - 1u;
        for (int i = 0; i < n; i++) {
            /* Masked difference: correct across one wrap of a narrow counter. */
            uint64_t ticks = (stamps[2 * i + 1] - stamps[2 * i]) & mask;
            double ns = (double)ticks * (double)dev->info->timestamp_period;
            d[i].seconds = ns * 1e-9;
            if (d[i].kernel->timing)
                tb_stat_sample(d[i].kernel->timing, (int64_t)llround(ns));
        }
    } else {
        for (int i = 0; i < n; i++)
            d[i].seconds = NAN;
    }
done:
    free(groups);
    free(layouts);
    free(sets);
    free(bufs);
    free(writes);
    free(views);
    free(stamps);
    return st;
}
