/* The Vulkan loader, opened at run time.
 *
 * Why dlopen() rather than linking -lvulkan: a program linked against
 * libvulkan.so.1 does not start at all on a machine without it ("error while
 * loading shared libraries"), so it could neither print a useful message nor
 * fall back to the CPU path. Opening the loader on first use keeps every CPU
 * path working there, turns a missing loader into an ordinary TB_ERR_DEVICE,
 * and costs one dlopen. Only vkGetInstanceProcAddr is looked up with dlsym();
 * everything else comes through it, as the loader documentation recommends
 * (and as volk does). */
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "host/gpu/gpu_internal.h"

/* The SONAME of the loader on Linux (the unversioned .so is only in -dev packages). */
#define TB__VK_LOADER_NAME "libvulkan.so.1"

static pthread_once_t tb__loader_once = PTHREAD_ONCE_INIT;
static tb__vk_global tb__global;
static bool tb__loader_ok;
static char tb__loader_error[512];

static void tb__loader_open(void)
{
    /* $TB_VULKAN_LOADER names another loader (a newer build, or a missing
     * file to test the fallback). */
    const char *name = getenv("TB_VULKAN_LOADER");
    if (!name || !*name)
        name = TB__VK_LOADER_NAME;
    void *lib = dlopen(name, RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        const char *why = dlerror();
        snprintf(tb__loader_error, sizeof tb__loader_error,
                 "Vulkan loader %s not found (%s); install the Vulkan loader "
                 "(Debian: libvulkan1) or use the CPU backend",
                 name, why ? why : "dlopen failed");
        return;
    }
    /* dlsym returns void *; POSIX guarantees it converts to a function pointer. */
    void *sym = dlsym(lib, "vkGetInstanceProcAddr");
    if (!sym) {
        snprintf(tb__loader_error, sizeof tb__loader_error,
                 "%s is not a Vulkan loader: it has no vkGetInstanceProcAddr", name);
        dlclose(lib);
        return;
    }
    memcpy(&tb__global.vkGetInstanceProcAddr, &sym, sizeof sym);
#define TB__VK_LOAD_GLOBAL(name) \
    tb__global.name = (PFN_##name)tb__global.vkGetInstanceProcAddr(VK_NULL_HANDLE, #name);
    TB__VK_GLOBAL_FNS(TB__VK_LOAD_GLOBAL)
#undef TB__VK_LOAD_GLOBAL
    if (!tb__global.vkCreateInstance || !tb__global.vkEnumerateInstanceExtensionProperties ||
        !tb__global.vkEnumerateInstanceLayerProperties) {
        snprintf(tb__loader_error, sizeof tb__loader_error,
                 "Vulkan loader %s is incomplete (no vkCreateInstance)", name);
        dlclose(lib);
        return;
    }
    /* The library stays loaded until the process ends: drivers and layers
     * register exit handlers that must find their code in place. */
    tb__loader_ok = true;
}

const tb__vk_global *tb__vk_loader(void)
{
    pthread_once(&tb__loader_once, tb__loader_open);
    if (!tb__loader_ok) {
        tb_error(TB_ERR_DEVICE, "%s", tb__loader_error);
        return NULL;
    }
    return &tb__global;
}

const char *tb__vk_result_text(VkResult r)
{
    switch (r) {
    case VK_SUCCESS: return "VK_SUCCESS";
    case VK_NOT_READY: return "VK_NOT_READY";
    case VK_TIMEOUT: return "VK_TIMEOUT: the wait timed out (the device may be hung)";
    case VK_INCOMPLETE: return "VK_INCOMPLETE";
    case VK_ERROR_OUT_OF_HOST_MEMORY: return "VK_ERROR_OUT_OF_HOST_MEMORY: out of host memory";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY: return "VK_ERROR_OUT_OF_DEVICE_MEMORY: out of device memory";
    case VK_ERROR_INITIALIZATION_FAILED: return "VK_ERROR_INITIALIZATION_FAILED: the driver failed to initialise";
    case VK_ERROR_DEVICE_LOST:
        return "VK_ERROR_DEVICE_LOST: the device was lost (driver crash, GPU reset or a "
               "kernel that ran too long); its results are invalid";
    case VK_ERROR_MEMORY_MAP_FAILED: return "VK_ERROR_MEMORY_MAP_FAILED: memory could not be mapped";
    case VK_ERROR_LAYER_NOT_PRESENT: return "VK_ERROR_LAYER_NOT_PRESENT: a requested layer is not installed";
    case VK_ERROR_EXTENSION_NOT_PRESENT: return "VK_ERROR_EXTENSION_NOT_PRESENT: a requested extension is missing";
    case VK_ERROR_FEATURE_NOT_PRESENT: return "VK_ERROR_FEATURE_NOT_PRESENT: a requested feature is missing";
    case VK_ERROR_INCOMPATIBLE_DRIVER:
        return "VK_ERROR_INCOMPATIBLE_DRIVER: no compatible Vulkan driver (ICD) was found";
    case VK_ERROR_TOO_MANY_OBJECTS: return "VK_ERROR_TOO_MANY_OBJECTS: too many objects of one type";
    case VK_ERROR_FORMAT_NOT_SUPPORTED: return "VK_ERROR_FORMAT_NOT_SUPPORTED";
    case VK_ERROR_FRAGMENTED_POOL: return "VK_ERROR_FRAGMENTED_POOL";
    case VK_ERROR_OUT_OF_POOL_MEMORY: return "VK_ERROR_OUT_OF_POOL_MEMORY: a descriptor pool is exhausted";
    case VK_ERROR_INVALID_SHADER_NV: return "VK_ERROR_INVALID_SHADER_NV: the shader failed to compile";
    default: break;
    }
    return r < 0 ? "VK_ERROR (unknown error code)" : "VK result (unknown status code)";
}

tb_status tb__gpu_fail(tb_gpu_device *dev, VkResult r, const char *what)
{
    if (dev && (r == VK_ERROR_DEVICE_LOST || r == VK_TIMEOUT))
        dev->lost = true; /* a hung submission cannot be reused or freed safely */
    return tb_error(TB_ERR_DEVICE, "Vulkan: %s failed: %s (%d)", what, tb__vk_result_text(r), (int)r);
}

tb_status tb__gpu_check_alive(const tb_gpu_device *dev)
{
    if (dev->lost)
        return tb_error(TB_ERR_DEVICE, "Vulkan device %d (%s) was lost earlier; recreate it or "
                        "use the CPU backend", dev->index, dev->info->name);
    return TB_OK;
}
