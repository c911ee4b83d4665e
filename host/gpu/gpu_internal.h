/* host/gpu internals: the Vulkan entry points loaded at run time and the
 * structures behind the opaque handles of gpu.h. Not installed; the tests
 * include it to reach the raw handles (e.g. to provoke a validation error). */
#ifndef TB_HOST_GPU_GPU_INTERNAL_H
#define TB_HOST_GPU_GPU_INTERNAL_H

#define VK_NO_PROTOTYPES
#include <pthread.h>
#include <vulkan/vulkan_core.h>

#include "host/gpu/gpu.h"

/* Entry points loaded with vkGetInstanceProcAddr(NULL, ...). */
#define TB__VK_GLOBAL_FNS(X)                                                                \
    X(vkEnumerateInstanceVersion)                                                          \
    X(vkEnumerateInstanceLayerProperties)                                                  \
    X(vkEnumerateInstanceExtensionProperties)                                              \
    X(vkCreateInstance)

/* Entry points loaded with vkGetInstanceProcAddr(instance, ...). */
#define TB__VK_INSTANCE_FNS(X)                                                              \
    X(vkDestroyInstance)                                                                   \
    X(vkEnumeratePhysicalDevices)                                                          \
    X(vkGetPhysicalDeviceProperties)                                                       \
    X(vkGetPhysicalDeviceProperties2)                                                      \
    X(vkGetPhysicalDeviceQueueFamilyProperties)                                            \
    X(vkGetPhysicalDeviceMemoryProperties)                                                 \
    X(vkEnumerateDeviceExtensionProperties)                                                \
    X(vkCreateDevice)                                                                      \
    X(vkGetDeviceProcAddr)

/* Instance entry points of VK_EXT_debug_utils (only with validation). */
#define TB__VK_DEBUG_FNS(X)                                                                 \
    X(vkCreateDebugUtilsMessengerEXT)                                                      \
    X(vkDestroyDebugUtilsMessengerEXT)

/* Entry points loaded with vkGetDeviceProcAddr(device, ...). */
#define TB__VK_DEVICE_FNS(X)                                                                \
    X(vkDestroyDevice)                                                                     \
    X(vkGetDeviceQueue)                                                                    \
    X(vkDeviceWaitIdle)                                                                    \
    X(vkCreateBuffer)                                                                      \
    X(vkDestroyBuffer)                                                                     \
    X(vkCreateBufferView)                                                                  \
    X(vkDestroyBufferView)                                                                 \
    X(vkGetBufferMemoryRequirements)                                                       \
    X(vkAllocateMemory)                                                                    \
    X(vkFreeMemory)                                                                        \
    X(vkBindBufferMemory)                                                                  \
    X(vkMapMemory)                                                                         \
    X(vkUnmapMemory)                                                                       \
    X(vkCreateShaderModule)                                                                \
    X(vkDestroyShaderModule)                                                               \
    X(vkCreateDescriptorSetLayout)                                                         \
    X(vkDestroyDescriptorSetLayout)                                                        \
    X(vkCreatePipelineLayout)                                                              \
    X(vkDestroyPipelineLayout)                                                             \
    X(vkCreatePipelineCache)                                                               \
    X(vkDestroyPipelineCache)                                                              \
    X(vkCreateComputePipelines)                                                            \
    X(vkDestroyPipeline)                                                                   \
    X(vkCreateDescriptorPool)                                                              \
    X(vkDestroyDescriptorPool)                                                             \
    X(vkResetDescriptorPool)                                                               \
    X(vkAllocateDescriptorSets)                                                            \
    X(vkUpdateDescriptorSets)                                                              \
    X(vkCreateCommandPool)                                                                 \
    X(vkDestroyCommandPool)                                                                \
    X(vkAllocateCommandBuffers)                                                            \
    X(vkResetCommandBuffer)                                                                \
    X(vkBeginCommandBuffer)                                                                \
    X(vkEndCommandBuffer)                                                                  \
    X(vkCmdBindPipeline)                                                                   \
    X(vkCmdBindDescriptorSets)                                                             \
    X(vkCmdPushConstants)                                                                  \
    X(vkCmdDispatch)                                                                       \
    X(vkCmdPipelineBarrier)                                                                \
    X(vkCmdCopyBuffer)                                                                     \
    X(vkCmdFillBuffer)                                                                     \
    X(vkCmdResetQueryPool)                                                                 \
    X(vkCmdWriteTimestamp)                                                                 \
    X(vkCreateQueryPool)                                                                   \
    X(vkDestroyQueryPool)                                                                  \
    X(vkGetQueryPoolResults)                                                               \
    X(vkCreateFence)                                                                       \
    X(vkDestroyFence)                                                                      \
    X(vkResetFences)                                                                       \
    X(vkWaitForFences)                                                                     \
    X(vkQueueSubmit)

#define TB__VK_DECLARE(name) PFN_##name name;

/* Global entry points (from the loader). */
typedef struct tb__vk_global {
    PFN_vkGetInstanceProcAddr vkGetInstanceProcAddr;
    TB__VK_GLOBAL_FNS(TB__VK_DECLARE)
} tb__vk_global;

/* Instance entry points. */
typedef struct tb__vk_instance_fns {
    TB__VK_INSTANCE_FNS(TB__VK_DECLARE)
    TB__VK_DEBUG_FNS(TB__VK_DECLARE)
} tb__vk_instance_fns;

/* Device entry points. */
typedef struct tb__vk_device_fns {
    TB__VK_DEVICE_FNS(TB__VK_DECLARE)
} tb__vk_device_fns;

/* Opens the loader once per process (libvulkan.so.1, or $TB_VULKAN_LOADER)
 * and returns its global entry points; NULL with TB_ERR_DEVICE. */
const tb__vk_global *tb__vk_loader(void);

/* Short text for a VkResult ("VK_ERROR_DEVICE_LOST: the device was lost ..."). */
const char *tb__vk_result_text(VkResult r);

struct tb_gpu_instance {
    const tb__vk_global *g;
    VkInstance vk;
    tb__vk_instance_fns fn;
    uint32_t loader_version;
    uint32_t api_version;             /* what the instance was created with */
    bool validation;
    bool quiet;
    VkDebugUtilsMessengerEXT messenger;
    pthread_mutex_t msg_lock;         /* the callback may run on driver threads */
    int errors, warnings;
    int nmessages;
    char *messages[TB_GPU_MAX_MESSAGES];
    int ndevices;
    VkPhysicalDevice *phys;
    tb_gpu_device_info *info;
    uint32_t *compute_family;         /* queue family used per device (UINT32_MAX if none) */
};

/* A kernel and its cache key. */
typedef struct tb__gpu_kernel_key {
    uint64_t hash;                    /* FNV-1a of the SPIR-V words */
    size_t size;
    const uint32_t *words;
    int buffers;
    uint8_t kinds[TB_GPU_MAX_BUFFERS]; /* tb_gpu_binding_kind per binding */
    uint32_t push_size;
    uint32_t workgroup_size;
    int spec_count;
    tb_gpu_spec_constant spec[TB_GPU_MAX_SPEC];
} tb__gpu_kernel_key;

struct tb_gpu_kernel {
    tb_gpu_device *dev;
    tb__gpu_kernel_key key;
    char name[64];
    VkDescriptorSetLayout set_layout;
    VkPipelineLayout layout;
    VkPipeline pipeline;
    struct tb_stat *timing;           /* "GPU/kernel <name> (ns)" */
    struct tb_gpu_kernel *next;
};

struct tb_gpu_device {
    tb_gpu_instance *inst;
    int index;
    const tb_gpu_device_info *info;
    VkPhysicalDevice phys;
    VkDevice vk;
    tb__vk_device_fns fn;
    VkQueue queue;
    uint32_t family;
    VkPhysicalDeviceMemoryProperties mem;
    bool mapped;                      /* buffers live in host-visible device memory */
    bool lost;
    uint64_t timeout_ns;
    VkPipelineCache cache;
    VkCommandPool pool;
    VkCommandBuffer cmd;
    VkFence fence;
    VkQueryPool queries;              /* timestamps, 2 per dispatch; VK_NULL_HANDLE if none */
    uint32_t query_cap;
    VkDescriptorPool descriptors;
    uint32_t descriptor_cap;          /* sets the pool holds */
    struct tb_gpu_buffer *staging;    /* host-visible bounce buffer (staging path) */
    size_t staging_max;               /* largest staging buffer; bigger transfers go in chunks */
    struct tb_gpu_kernel *kernels;
    int nbuffers;                     /* live buffers, checked at destroy */
};

struct tb_gpu_buffer {
    tb_gpu_device *dev;
    VkBuffer vk;
    VkDeviceMemory memory;
    size_t size;                      /* as requested (the VkBuffer is rounded up to whole words) */
    uint64_t allocated;               /* bytes of device memory behind it */
    void *map;                        /* host address when mapped, else NULL */
    VkBufferView views[3];            /* per tb_gpu_binding_kind: texel view, made on first use */
};

/* The view of b for texel-buffer kind `kind` (created on first use, owned by
 * b); VK_NULL_HANDLE with TB_ERR_DEVICE set on failure. */
VkBufferView tb__gpu_buffer_view(tb_gpu_buffer *b, int kind);

/* Turns a failed VkResult into TB_ERR_DEVICE with "what: <result text>",
 * marking the device lost on VK_ERROR_DEVICE_LOST (dev may be NULL). */
tb_status tb__gpu_fail(tb_gpu_device *dev, VkResult r, const char *what);

/* TB_ERR_DEVICE if the device was lost earlier, else TB_OK. */
tb_status tb__gpu_check_alive(const tb_gpu_device *dev);

/* Begins the device's one command buffer (after the previous use finished). */
tb_status tb__gpu_begin(tb_gpu_device *dev);
/* Ends, submits and waits for the command buffer; `what` names it in errors. */
tb_status tb__gpu_submit_wait(tb_gpu_device *dev, const char *what);

/* A global memory barrier from all earlier work of src_stage to dst_stage. */
void tb__gpu_barrier(tb_gpu_device *dev, VkPipelineStageFlags src_stage, VkAccessFlags src,
                     VkPipelineStageFlags dst_stage, VkAccessFlags dst);

/* Creates a buffer in memory with `props` (buffers and staging alike). */
tb_gpu_buffer *tb__gpu_buffer_new(tb_gpu_device *dev, size_t size, VkBufferUsageFlags usage,
                                  bool host_visible);

/* Frees every kernel of the device (device destruction). */
void tb__gpu_kernels_destroy(tb_gpu_device *dev);

#endif
