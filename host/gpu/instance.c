/* Vulkan instance, validation messages, physical devices and their selection. */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "host/gpu/gpu_internal.h"

#define TB__VALIDATION_LAYER "VK_LAYER_KHRONOS_validation"

const char *tb_gpu_mode_name(tb_gpu_mode mode)
{
    switch (mode) {
    case TB_GPU_MODE_AUTO: return "auto";
    case TB_GPU_MODE_VULKAN: return "vulkan";
    case TB_GPU_MODE_CPU: return "cpu";
    }
    return "?";
}

tb_status tb_gpu_mode_parse(const char *name, tb_gpu_mode *out)
{
    static const tb_gpu_mode modes[] = {TB_GPU_MODE_AUTO, TB_GPU_MODE_VULKAN, TB_GPU_MODE_CPU};
    for (size_t i = 0; name && i < sizeof modes / sizeof modes[0]; i++)
        if (strcmp(name, tb_gpu_mode_name(modes[i])) == 0) {
            *out = modes[i];
            return TB_OK;
        }
    return tb_error(TB_ERR_ARG, "unknown backend '%s' (use auto, vulkan or cpu)", name ? name : "(null)");
}

const char *tb_gpu_backend_name(tb_gpu_backend backend)
{
    return backend == TB_GPU_BACKEND_VULKAN ? "vulkan" : "cpu";
}

const char *tb_gpu_device_type_name(tb_gpu_device_type type)
{
    switch (type) {
    case TB_GPU_DEVICE_DISCRETE: return "discrete GPU";
    case TB_GPU_DEVICE_INTEGRATED: return "integrated GPU";
    case TB_GPU_DEVICE_VIRTUAL: return "virtual GPU";
    case TB_GPU_DEVICE_CPU: return "CPU";
    case TB_GPU_DEVICE_OTHER: break;
    }
    return "other";
}

const char *tb_gpu_version_string(uint32_t v, char buf[16])
{
    snprintf(buf, 16, "%u.%u.%u", VK_API_VERSION_MAJOR(v) % 1000u, VK_API_VERSION_MINOR(v) % 1000u,
             VK_API_VERSION_PATCH(v) % 10000u);
    return buf;
}

/* ---------------------------------------------------------------- validation messages */

static VKAPI_ATTR VkBool32 VKAPI_CALL tb__vk_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                      VkDebugUtilsMessageTypeFlagsEXT types,
                                                      const VkDebugUtilsMessengerCallbackDataEXT *data,
                                                      void *user)
{
    (void)types;
    tb_gpu_instance *inst = user;
    bool error = (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) != 0;
    bool warning = (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) != 0;
    if (!error && !warning)
        return VK_FALSE;
    char text[1024];
    snprintf(text, sizeof text, "%s: %s: %s", error ? "error" : "warning",
             data && data->pMessageIdName ? data->pMessageIdName : "-",
             data && data->pMessage ? data->pMessage : "");
    pthread_mutex_lock(&inst->msg_lock);
    if (error)
        inst->errors++;
    else
        inst->warnings++;
    if (inst->nmessages < TB_GPU_MAX_MESSAGES) {
        char *copy = strdup(text);
        if (copy)
            inst->messages[inst->nmessages++] = copy;
    }
    pthread_mutex_unlock(&inst->msg_lock);
    if (!inst->quiet)
        fprintf(stderr, "vulkan validation %s\n", text);
    return VK_FALSE; /* never abort the call that triggered the message */
}

bool tb_gpu_validation_enabled(const tb_gpu_instance *inst) { return inst->validation; }

int tb_gpu_validation_errors(const tb_gpu_instance *inst)
{
    tb_gpu_instance *m = (tb_gpu_instance *)inst; /* the lock, not the data, changes */
    pthread_mutex_lock(&m->msg_lock);
    int n = m->errors;
    pthread_mutex_unlock(&m->msg_lock);
    return n;
}

int tb_gpu_validation_warnings(const tb_gpu_instance *inst)
{
    tb_gpu_instance *m = (tb_gpu_instance *)inst;
    pthread_mutex_lock(&m->msg_lock);
    int n = m->warnings;
    pthread_mutex_unlock(&m->msg_lock);
    return n;
}

int tb_gpu_validation_message_count(const tb_gpu_instance *inst)
{
    tb_gpu_instance *m = (tb_gpu_instance *)inst;
    pthread_mutex_lock(&m->msg_lock);
    int n = m->nmessages;
    pthread_mutex_unlock(&m->msg_lock);
    return n;
}

const char *tb_gpu_validation_message(const tb_gpu_instance *inst, int i)
{
    tb_gpu_instance *m = (tb_gpu_instance *)inst;
    pthread_mutex_lock(&m->msg_lock);
    const char *s = i >= 0 && i < m->nmessages ? m->messages[i] : NULL;
    pthread_mutex_unlock(&m->msg_lock);
    return s;
}

void tb_gpu_validation_clear(tb_gpu_instance *inst)
{
    pthread_mutex_lock(&inst->msg_lock);
    for (int i = 0; i < inst->nmessages; i++)
        free(inst->messages[i]);
    inst->nmessages = 0;
    inst->errors = inst->warnings = 0;
    pthread_mutex_unlock(&inst->msg_lock);
}

/* ---------------------------------------------------------------- instance */

static bool tb__env_on(const char *name)
{
    const char *v = getenv(name);
    return v && *v && strcmp(v, "0") != 0 && strcmp(v, "false") != 0 && strcmp(v, "no") != 0;
}

static bool tb__has_layer(const tb__vk_global *g, const char *layer)
{
    uint32_t n = 0;
    if (g->vkEnumerateInstanceLayerProperties(&n, NULL) != VK_SUCCESS || n == 0)
        return false;
    VkLayerProperties *p = calloc(n, sizeof *p);
    if (!p)
        return false;
    bool found = false;
    if (g->vkEnumerateInstanceLayerProperties(&n, p) >= 0)
        for (uint32_t i = 0; i < n && !found; i++)
            found = strcmp(p[i].layerName, layer) == 0;
    free(p);
    return found;
}

/* True if `ext` is offered by the loader/drivers (layer NULL) or by `layer`. */
static bool tb__has_instance_ext(const tb__vk_global *g, const char *layer, const char *ext)
{
    uint32_t n = 0;
    if (g->vkEnumerateInstanceExtensionProperties(layer, &n, NULL) != VK_SUCCESS || n == 0)
        return false;
    VkExtensionProperties *p = calloc(n, sizeof *p);
    if (!p)
        return false;
    bool found = false;
    if (g->vkEnumerateInstanceExtensionProperties(layer, &n, p) >= 0)
        for (uint32_t i = 0; i < n && !found; i++)
            found = strcmp(p[i].extensionName, ext) == 0;
    free(p);
    return found;
}

static bool tb__device_has_ext(const tb_gpu_instance *inst, VkPhysicalDevice pd, const char *ext)
{
    uint32_t n = 0;
    if (inst->fn.vkEnumerateDeviceExtensionProperties(pd, NULL, &n, NULL) != VK_SUCCESS || n == 0)
        return false;
    VkExtensionProperties *p = calloc(n, sizeof *p);
    if (!p)
        return false;
    bool found = false;
    if (inst->fn.vkEnumerateDeviceExtensionProperties(pd, NULL, &n, p) >= 0)
        for (uint32_t i = 0; i < n && !found; i++)
            found = strcmp(p[i].extensionName, ext) == 0;
    free(p);
    return found;
}

static void tb__copy_str(char *dst, size_t cap, const char *src)
{
    snprintf(dst, cap, "%s", src);
}

/* Fills inst->info[i] and inst->compute_family[i] for physical device i. */
static void tb__describe_device(tb_gpu_instance *inst, int i)
{
    VkPhysicalDevice pd = inst->phys[i];
    tb_gpu_device_info *d = &inst->info[i];
    memset(d, 0, sizeof *d);
    VkPhysicalDeviceProperties p;
    inst->fn.vkGetPhysicalDeviceProperties(pd, &p);
    tb__copy_str(d->name, sizeof d->name, p.deviceName);
    d->type = p.deviceType <= VK_PHYSICAL_DEVICE_TYPE_CPU ? (tb_gpu_device_type)p.deviceType
                                                          : TB_GPU_DEVICE_OTHER;
    d->vendor_id = p.vendorID;
    d->device_id = p.deviceID;
    d->api_version = p.apiVersion;
    d->driver_version = p.driverVersion;
    const VkPhysicalDeviceLimits *l = &p.limits;
    d->max_workgroup_invocations = l->maxComputeWorkGroupInvocations;
    for (int k = 0; k < 3; k++) {
        d->max_workgroup_size[k] = l->maxComputeWorkGroupSize[k];
        d->max_workgroup_count[k] = l->maxComputeWorkGroupCount[k];
    }
    d->max_shared_memory = l->maxComputeSharedMemorySize;
    d->max_push_constants = l->maxPushConstantsSize;
    d->max_storage_buffer_range = l->maxStorageBufferRange;
    d->max_texel_buffer_elements = l->maxTexelBufferElements;
    d->max_storage_buffers = l->maxPerStageDescriptorStorageBuffers;
    d->timestamp_period = l->timestampPeriod;

    /* Core 1.1/1.2 property structures may only be chained when both the
     * device and the instance speak that version. */
    uint32_t api = p.apiVersion < inst->api_version ? p.apiVersion : inst->api_version;
    if (api >= VK_API_VERSION_1_1) {
        VkPhysicalDeviceSubgroupProperties sub = {
            .sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
        VkPhysicalDeviceDriverProperties drv = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
        VkPhysicalDeviceFloatControlsProperties fc = {
            .sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FLOAT_CONTROLS_PROPERTIES};
        VkPhysicalDeviceProperties2 p2 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2,
                                          .pNext = &sub};
        if (api >= VK_API_VERSION_1_2) {
            sub.pNext = &drv;
            drv.pNext = &fc;
        }
        inst->fn.vkGetPhysicalDeviceProperties2(pd, &p2);
        d->subgroup_size = sub.subgroupSize;
        if (api >= VK_API_VERSION_1_2) {
            tb__copy_str(d->driver_name, sizeof d->driver_name, drv.driverName);
            tb__copy_str(d->driver_info, sizeof d->driver_info, drv.driverInfo);
            d->float_controls_known = true;
            d->denorm_preserve32 = fc.shaderDenormPreserveFloat32;
            d->rounding_rte32 = fc.shaderRoundingModeRTEFloat32;
            d->inf_nan_preserve32 = fc.shaderSignedZeroInfNanPreserveFloat32;
        }
    }

    /* The compute queue: the first family with compute, preferring one that
     * can write timestamps (per-kernel timing needs them). */
    uint32_t nfam = 0;
    inst->fn.vkGetPhysicalDeviceQueueFamilyProperties(pd, &nfam, NULL);
    VkQueueFamilyProperties *fam = nfam ? calloc(nfam, sizeof *fam) : NULL;
    uint32_t chosen = UINT32_MAX;
    if (fam) {
        inst->fn.vkGetPhysicalDeviceQueueFamilyProperties(pd, &nfam, fam);
        for (uint32_t f = 0; f < nfam; f++) {
            if (!(fam[f].queueFlags & VK_QUEUE_COMPUTE_BIT) || fam[f].queueCount == 0)
                continue;
            if (chosen == UINT32_MAX ||
                (fam[chosen].timestampValidBits == 0 && fam[f].timestampValidBits > 0))
                chosen = f;
        }
        if (chosen != UINT32_MAX) {
            d->timestamp_valid_bits = fam[chosen].timestampValidBits;
            /* TB_GPU_NO_TIMESTAMPS=1 makes a device look as if it had none
             * (timestampComputeAndGraphics false and this family without
             * them), so the tests run the untimed path on any driver. */
            d->timestamps = fam[chosen].timestampValidBits > 0 && p.limits.timestampPeriod > 0.0f &&
                            !tb__env_on("TB_GPU_NO_TIMESTAMPS");
        }
        free(fam);
    }
    inst->compute_family[i] = chosen;

    VkPhysicalDeviceMemoryProperties mem;
    inst->fn.vkGetPhysicalDeviceMemoryProperties(pd, &mem);
    d->heap_count = (int)(mem.memoryHeapCount < TB_GPU_MAX_HEAPS ? mem.memoryHeapCount : TB_GPU_MAX_HEAPS);
    const VkMemoryPropertyFlags hv = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    bool local_and_visible = false;
    for (int h = 0; h < d->heap_count; h++) {
        d->heaps[h].size = mem.memoryHeaps[h].size;
        d->heaps[h].device_local = (mem.memoryHeaps[h].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT) != 0;
    }
    for (uint32_t t = 0; t < mem.memoryTypeCount; t++) {
        VkMemoryPropertyFlags f = mem.memoryTypes[t].propertyFlags;
        uint32_t h = mem.memoryTypes[t].heapIndex;
        if ((f & hv) == hv && h < TB_GPU_MAX_HEAPS)
            d->heaps[h].host_visible = true;
        if ((f & hv) == hv && (f & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT))
            local_and_visible = true;
    }
    /* Mapped device memory is only used where it is ordinary RAM (integrated
     * GPUs, CPU drivers). On a discrete GPU a host-visible device-local type
     * (resizable BAR) is uncached PCIe memory: reading results back from it is
     * far slower than a staging copy. */
    d->unified_memory = local_and_visible &&
                        (d->type == TB_GPU_DEVICE_INTEGRATED || d->type == TB_GPU_DEVICE_CPU);

    d->usable = true;
    if (p.apiVersion < VK_API_VERSION_1_1) {
        d->usable = false;
        snprintf(d->unusable_reason, sizeof d->unusable_reason, "supports only Vulkan %u.%u (1.1 needed)",
                 VK_API_VERSION_MAJOR(p.apiVersion), VK_API_VERSION_MINOR(p.apiVersion));
    } else if (chosen == UINT32_MAX) {
        d->usable = false;
        snprintf(d->unusable_reason, sizeof d->unusable_reason, "has no compute queue");
    } else if (tb__device_has_ext(inst, pd, "VK_KHR_portability_subset")) {
        d->usable = false; /* would need the extension enabled and its limits respected */
        snprintf(d->unusable_reason, sizeof d->unusable_reason,
                 "is a portability-subset implementation (not supported)");
    }
}

/* The message for "no driver": says which environment variables were in effect. */
static tb_status tb__no_driver(VkResult r)
{
    const char *icd = getenv("VK_DRIVER_FILES");
    if (!icd || !*icd)
        icd = getenv("VK_ICD_FILENAMES");
    if (icd && *icd)
        return tb_error(TB_ERR_DEVICE, "no Vulkan driver (ICD) could be loaded from VK_DRIVER_FILES / "
                        "VK_ICD_FILENAMES=%s (%s); use the CPU backend", icd, tb__vk_result_text(r));
    return tb_error(TB_ERR_DEVICE, "no Vulkan driver (ICD) is installed (%s); install one (Debian: "
                    "mesa-vulkan-drivers provides lavapipe) or use the CPU backend", tb__vk_result_text(r));
}

tb_gpu_instance *tb_gpu_instance_create(const tb_gpu_instance_desc *desc)
{
    tb_gpu_instance_desc none = {0};
    if (!desc)
        desc = &none;
    const tb__vk_global *g = tb__vk_loader();
    if (!g)
        return NULL;
    uint32_t loader = VK_API_VERSION_1_0;
    if (g->vkEnumerateInstanceVersion && g->vkEnumerateInstanceVersion(&loader) != VK_SUCCESS)
        loader = VK_API_VERSION_1_0;
    if (loader < VK_API_VERSION_1_1) {
        char v[16];
        tb_error(TB_ERR_DEVICE, "the Vulkan loader supports only Vulkan %s; 1.1 is needed",
                 tb_gpu_version_string(loader, v));
        return NULL;
    }
    bool validation = desc->validation || tb__env_on("TB_VK_VALIDATION");
    if (validation && !tb__has_layer(g, TB__VALIDATION_LAYER)) {
        tb_error(TB_ERR_UNSUPPORTED, "Vulkan validation was requested but %s is not installed "
                 "(Debian: vulkan-validationlayers)", TB__VALIDATION_LAYER);
        return NULL;
    }

    tb_gpu_instance *inst = calloc(1, sizeof *inst);
    if (!inst) {
        tb_error(TB_ERR_NOMEM, "out of memory creating a Vulkan instance");
        return NULL;
    }
    pthread_mutex_init(&inst->msg_lock, NULL);
    inst->g = g;
    inst->loader_version = loader;
    inst->validation = validation;
    inst->quiet = desc->quiet;
    /* The highest version we may use; device features above a device's own
     * version are never touched (tb__describe_device). */
    uint32_t api = VK_API_VERSION_1_3;
    if (loader < api)
        api = VK_MAKE_API_VERSION(0, VK_API_VERSION_MAJOR(loader), VK_API_VERSION_MINOR(loader), 0);
    inst->api_version = api;

    const char *exts[2];
    uint32_t next = 0;
    const char *layers[1] = {TB__VALIDATION_LAYER};
    bool debug_utils = false, features = false;
    if (validation) {
        debug_utils = tb__has_instance_ext(g, NULL, VK_EXT_DEBUG_UTILS_EXTENSION_NAME) ||
                      tb__has_instance_ext(g, TB__VALIDATION_LAYER, VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
        if (!debug_utils) {
            tb_error(TB_ERR_UNSUPPORTED, "Vulkan validation needs %s, which neither the loader nor "
                     "the layer offers", VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
            free(inst);
            return NULL;
        }
        exts[next++] = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
        features = tb__has_instance_ext(g, TB__VALIDATION_LAYER, VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME);
        if (features)
            exts[next++] = VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME;
    }
    /* Synchronization validation finds missing barriers between kernels,
     * copies and host access: the hazards a compute layer can get wrong. */
    VkValidationFeatureEnableEXT enables[] = {VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT};
    VkValidationFeaturesEXT vf = {.sType = VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT,
                                  .enabledValidationFeatureCount = 1,
                                  .pEnabledValidationFeatures = enables};
    VkDebugUtilsMessengerCreateInfoEXT mci = {
        .sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT,
        .pNext = features ? &vf : NULL,
        .messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                           VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT,
        .messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                       VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                       VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT,
        .pfnUserCallback = tb__vk_message,
        .pUserData = inst};
    VkApplicationInfo app = {.sType = VK_STRUCTURE_TYPE_APPLICATION_INFO,
                             .pApplicationName = "testbed",
                             .pEngineName = "testbed",
                             .apiVersion = api};
    VkInstanceCreateInfo ci = {.sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO,
                               .pNext = validation ? &mci : NULL,
                               .pApplicationInfo = &app,
                               .enabledLayerCount = validation ? 1u : 0u,
                               .ppEnabledLayerNames = layers,
                               .enabledExtensionCount = next,
                               .ppEnabledExtensionNames = exts};
    VkResult r = g->vkCreateInstance(&ci, NULL, &inst->vk);
    if (r != VK_SUCCESS) {
        if (r == VK_ERROR_INCOMPATIBLE_DRIVER)
            tb__no_driver(r);
        else
            tb__gpu_fail(NULL, r, "vkCreateInstance");
        tb_gpu_validation_clear(inst);
        pthread_mutex_destroy(&inst->msg_lock);
        free(inst);
        return NULL;
    }
#define TB__VK_LOAD_INSTANCE(name) inst->fn.name = (PFN_##name)g->vkGetInstanceProcAddr(inst->vk, #name);
    TB__VK_INSTANCE_FNS(TB__VK_LOAD_INSTANCE)
    if (validation) {
        TB__VK_DEBUG_FNS(TB__VK_LOAD_INSTANCE)
    }
#undef TB__VK_LOAD_INSTANCE
    if (!inst->fn.vkDestroyInstance || !inst->fn.vkEnumeratePhysicalDevices ||
        !inst->fn.vkGetPhysicalDeviceProperties2 || !inst->fn.vkCreateDevice) {
        tb_error(TB_ERR_DEVICE, "the Vulkan loader lacks core 1.1 entry points");
        tb_gpu_instance_destroy(inst);
        return NULL;
    }
    if (validation) {
        mci.pNext = NULL; /* the validation features belong to vkCreateInstance only */
        if (!inst->fn.vkCreateDebugUtilsMessengerEXT ||
            (r = inst->fn.vkCreateDebugUtilsMessengerEXT(inst->vk, &mci, NULL, &inst->messenger)) != VK_SUCCESS) {
            tb__gpu_fail(NULL, inst->fn.vkCreateDebugUtilsMessengerEXT ? r : VK_ERROR_EXTENSION_NOT_PRESENT,
                         "vkCreateDebugUtilsMessengerEXT");
            tb_gpu_instance_destroy(inst);
            return NULL;
        }
    }

    uint32_t n = 0;
    r = inst->fn.vkEnumeratePhysicalDevices(inst->vk, &n, NULL);
    if (r == VK_ERROR_INITIALIZATION_FAILED) {
        tb__no_driver(r); /* the loader found manifests but no driver would start */
        tb_gpu_instance_destroy(inst);
        return NULL;
    }
    if (r != VK_SUCCESS) {
        tb__gpu_fail(NULL, r, "vkEnumeratePhysicalDevices");
        tb_gpu_instance_destroy(inst);
        return NULL;
    }
    if (n > 0) {
        inst->phys = calloc(n, sizeof *inst->phys);
        inst->info = calloc(n, sizeof *inst->info);
        inst->compute_family = calloc(n, sizeof *inst->compute_family);
        if (!inst->phys || !inst->info || !inst->compute_family) {
            tb_error(TB_ERR_NOMEM, "out of memory listing %u Vulkan devices", n);
            tb_gpu_instance_destroy(inst);
            return NULL;
        }
        r = inst->fn.vkEnumeratePhysicalDevices(inst->vk, &n, inst->phys);
        if (r < 0) {
            tb__gpu_fail(NULL, r, "vkEnumeratePhysicalDevices");
            tb_gpu_instance_destroy(inst);
            return NULL;
        }
    }
    inst->ndevices = (int)n;
    for (int i = 0; i < inst->ndevices; i++)
        tb__describe_device(inst, i);
    return inst;
}

void tb_gpu_instance_destroy(tb_gpu_instance *inst)
{
    if (!inst)
        return;
    if (inst->messenger && inst->fn.vkDestroyDebugUtilsMessengerEXT)
        inst->fn.vkDestroyDebugUtilsMessengerEXT(inst->vk, inst->messenger, NULL);
    if (inst->vk && inst->fn.vkDestroyInstance)
        inst->fn.vkDestroyInstance(inst->vk, NULL);
    tb_gpu_validation_clear(inst);
    pthread_mutex_destroy(&inst->msg_lock);
    free(inst->phys);
    free(inst->info);
    free(inst->compute_family);
    free(inst);
}

uint32_t tb_gpu_loader_version(const tb_gpu_instance *inst) { return inst->loader_version; }

int tb_gpu_device_count(const tb_gpu_instance *inst) { return inst->ndevices; }

const tb_gpu_device_info *tb_gpu_device_info_at(const tb_gpu_instance *inst, int index)
{
    return index >= 0 && index < inst->ndevices ? &inst->info[index] : NULL;
}

/* ---------------------------------------------------------------- selection */

/* Preference of a device type: higher is better. */
static int tb__type_rank(tb_gpu_device_type t)
{
    switch (t) {
    case TB_GPU_DEVICE_DISCRETE: return 4;
    case TB_GPU_DEVICE_INTEGRATED: return 3;
    case TB_GPU_DEVICE_VIRTUAL: return 2;
    case TB_GPU_DEVICE_CPU: return 1;
    case TB_GPU_DEVICE_OTHER: break;
    }
    return 0;
}

static void tb__reason(char *reason, size_t size, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void tb__reason(char *reason, size_t size, const char *fmt, ...)
{
    if (!reason || size == 0)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(reason, size, fmt, ap);
    va_end(ap);
}

tb_status tb_gpu_pick_device(const tb_gpu_device_info *infos, int n, tb_gpu_mode mode,
                             int requested, int *index, char *reason, size_t reason_size)
{
    *index = -1;
    if (mode == TB_GPU_MODE_CPU) {
        tb__reason(reason, reason_size, "the CPU backend was requested");
        return TB_OK;
    }
    if (requested >= 0) {
        if (requested >= n) {
            tb__reason(reason, reason_size, "--device %d does not exist (%d Vulkan device%s)",
                       requested, n, n == 1 ? "" : "s");
            return tb_error(TB_ERR_ARG, "--device %d does not exist (%d Vulkan device%s; see `testbed devices`)",
                            requested, n, n == 1 ? "" : "s");
        }
        const tb_gpu_device_info *d = &infos[requested];
        if (!d->usable) {
            tb__reason(reason, reason_size, "device %d (%s) %s", requested, d->name, d->unusable_reason);
            return tb_error(TB_ERR_DEVICE, "device %d (%s) cannot be used: it %s", requested, d->name,
                            d->unusable_reason);
        }
        *index = requested;
        tb__reason(reason, reason_size, "device %d (%s, %s) was requested with --device", requested,
                   d->name, tb_gpu_device_type_name(d->type));
        return TB_OK;
    }
    int best = -1;
    for (int i = 0; i < n; i++)
        if (infos[i].usable && (best < 0 || tb__type_rank(infos[i].type) > tb__type_rank(infos[best].type)))
            best = i;
    if (best < 0) {
        const char *what = n == 0 ? "no Vulkan devices" : "no usable Vulkan device";
        tb__reason(reason, reason_size, "%s; using the CPU path", what);
        if (mode == TB_GPU_MODE_VULKAN)
            return tb_error(TB_ERR_DEVICE, "--backend vulkan: %s (see `testbed devices`)", what);
        return TB_OK;
    }
    const tb_gpu_device_info *d = &infos[best];
    if (mode == TB_GPU_MODE_AUTO && tb__type_rank(d->type) <= tb__type_rank(TB_GPU_DEVICE_CPU)) {
        tb__reason(reason, reason_size,
                   "the best Vulkan device, %d (%s), is a %s driver, slower than the CPU path; "
                   "using the CPU path (--backend vulkan uses it anyway)",
                   best, d->name, d->type == TB_GPU_DEVICE_CPU ? "CPU" : "non-GPU");
        return TB_OK;
    }
    *index = best;
    tb__reason(reason, reason_size, "device %d (%s) is the best Vulkan device (%s)", best, d->name,
               tb_gpu_device_type_name(d->type));
    return TB_OK;
}
