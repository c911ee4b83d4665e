/* A small Vulkan compute layer: instance and device selection, storage
 * buffers, compute kernels from embedded SPIR-V with specialization and push
 * constants, submission with per-kernel timestamps, and the choice between
 * the Vulkan and the CPU backend (docs/gpu.md).
 *
 *     tb_gpu_session s;
 *     if (tb_gpu_backend_choose(TB_GPU_MODE_AUTO, -1, false, &s)) ...error
 *     if (s.backend == TB_GPU_BACKEND_VULKAN) {
 *         tb_gpu_buffer *buf = tb_gpu_buffer_create(s.device, bytes);
 *         tb_gpu_kernel *k = tb_gpu_kernel_get(s.device, &(tb_gpu_kernel_desc){
 *             .spirv = tb_gpu_builtin("selftest"), .buffers = 1, .push_size = 8});
 *         tb_gpu_buffer_upload(buf, 0, data, bytes);
 *         tb_gpu_dispatch d = {k, {buf}, &push, n};
 *         tb_gpu_run(s.device, &d, 1);
 *         tb_gpu_buffer_download(buf, 0, data, bytes);
 *     }
 *     tb_gpu_session_close(&s);
 *
 * The Vulkan loader (libvulkan.so.1) is opened with dlopen() on first use, so
 * the library runs without it; every failure (no loader, no driver, no
 * device, out of memory, device lost) is a TB_ERR_DEVICE with a message.
 * Vulkan types do not appear here: the handles are opaque.
 *
 * Threads: an instance may be read from any thread; a device, its buffers and
 * kernels are used by one thread at a time. */
#ifndef TB_HOST_GPU_GPU_H
#define TB_HOST_GPU_GPU_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "host/gpu/spirv.h"
#include "util/base/error.h"

/* ---------------------------------------------------------------- backends */

/* Which implementation runs the kernels. */
typedef enum tb_gpu_backend {
    TB_GPU_BACKEND_CPU = 0, /* the C reference path */
    TB_GPU_BACKEND_VULKAN,  /* the compute shaders */
} tb_gpu_backend;

/* What the user asked for (--backend). */
typedef enum tb_gpu_mode {
    TB_GPU_MODE_AUTO = 0, /* Vulkan on a real GPU (discrete, integrated, virtual), else the CPU path */
    TB_GPU_MODE_VULKAN,   /* Vulkan on any device, CPU drivers (lavapipe) included; fail if none */
    TB_GPU_MODE_CPU,      /* the CPU path */
} tb_gpu_mode;

/* "auto", "vulkan" or "cpu" -> *out; TB_ERR_ARG (with the valid names) otherwise. */
tb_status tb_gpu_mode_parse(const char *name, tb_gpu_mode *out);
/* "auto", "vulkan", "cpu". */
const char *tb_gpu_mode_name(tb_gpu_mode mode);
/* "cpu", "vulkan". */
const char *tb_gpu_backend_name(tb_gpu_backend backend);

/* ---------------------------------------------------------------- devices */

/* Kind of device (the values of VkPhysicalDeviceType). */
typedef enum tb_gpu_device_type {
    TB_GPU_DEVICE_OTHER = 0,
    TB_GPU_DEVICE_INTEGRATED = 1,
    TB_GPU_DEVICE_DISCRETE = 2,
    TB_GPU_DEVICE_VIRTUAL = 3,
    TB_GPU_DEVICE_CPU = 4, /* a software driver such as Mesa's lavapipe (llvmpipe) */
} tb_gpu_device_type;

/* "discrete GPU", "integrated GPU", "virtual GPU", "CPU", "other". */
const char *tb_gpu_device_type_name(tb_gpu_device_type type);

/* Most memory heaps reported per device. */
#define TB_GPU_MAX_HEAPS 16

/* One memory heap of a device. */
typedef struct tb_gpu_heap {
    uint64_t size;     /* bytes */
    bool device_local; /* VK_MEMORY_HEAP_DEVICE_LOCAL_BIT */
    bool host_visible; /* some memory type on it is host-visible and coherent */
} tb_gpu_heap;

/* What a device is and can do, read once when the instance is created. */
typedef struct tb_gpu_device_info {
    char name[256];
    tb_gpu_device_type type;
    uint32_t vendor_id, device_id;
    uint32_t api_version;    /* VK_MAKE_API_VERSION encoding; see tb_gpu_version_string */
    uint32_t driver_version; /* vendor-specific encoding */
    char driver_name[256];   /* "" when the device cannot say (before Vulkan 1.2) */
    char driver_info[256];   /* driver build string, "" when unknown */
    uint32_t subgroup_size;  /* invocations per subgroup; 0 when unknown */
    uint32_t max_workgroup_invocations;
    uint32_t max_workgroup_size[3];
    uint32_t max_workgroup_count[3];
    uint32_t max_shared_memory;        /* bytes of shared memory per workgroup */
    uint32_t max_push_constants;       /* bytes */
    uint64_t max_storage_buffer_range; /* largest storage buffer a kernel can bind, bytes */
    uint64_t max_texel_buffer_elements; /* most texels a texel-buffer binding can address */
    uint32_t max_storage_buffers;      /* storage buffers per shader stage */
    int heap_count;
    tb_gpu_heap heaps[TB_GPU_MAX_HEAPS];
    bool unified_memory;          /* device-local memory is also host-visible: no staging copies */
    bool timestamps;              /* the compute queue writes timestamps */
    uint32_t timestamp_valid_bits; /* bits of a timestamp that count (0 = none) */
    float timestamp_period;       /* nanoseconds per timestamp tick */
    bool float_controls_known;    /* the three flags below were reported (Vulkan 1.2) */
    bool denorm_preserve32;       /* float denormals can be kept (else they may flush to 0) */
    bool rounding_rte32;          /* round-to-nearest-even can be requested for float */
    bool inf_nan_preserve32;      /* signed zeros, inf and NaN can be preserved for float */
    bool usable;                  /* host/gpu can run kernels on it */
    char unusable_reason[128];    /* why not, when !usable */
} tb_gpu_device_info;

/* "1.3.230" from a VK_MAKE_API_VERSION value; buf needs 16 bytes. Returns buf. */
const char *tb_gpu_version_string(uint32_t version, char buf[16]);

/* ---------------------------------------------------------------- instance */

/* A connection to the Vulkan loader with the list of devices it sees. */
typedef struct tb_gpu_instance tb_gpu_instance;

/* Options of tb_gpu_instance_create; all-zero is the default. */
typedef struct tb_gpu_instance_desc {
    bool validation; /* VK_LAYER_KHRONOS_validation + message recording (also on when $TB_VK_VALIDATION=1) */
    bool quiet;      /* do not echo validation messages to stderr (they are still recorded) */
} tb_gpu_instance_desc;

/* Opens the loader (libvulkan.so.1, or $TB_VULKAN_LOADER) and creates an
 * instance; `desc` may be NULL. NULL with TB_ERR_DEVICE when there is no
 * loader or no driver, TB_ERR_UNSUPPORTED when validation was asked for and
 * the layer is not installed. An instance that sees no device is not an
 * error: tb_gpu_device_count() is then 0. */
tb_gpu_instance *tb_gpu_instance_create(const tb_gpu_instance_desc *desc);

/* Destroys the instance (its devices must be destroyed first). NULL is ignored. */
void tb_gpu_instance_destroy(tb_gpu_instance *inst);

/* The loader's Vulkan version (VK_MAKE_API_VERSION encoding). */
uint32_t tb_gpu_loader_version(const tb_gpu_instance *inst);

/* Number of physical devices. */
int tb_gpu_device_count(const tb_gpu_instance *inst);

/* Description of device `index` (0 .. count-1), or NULL. */
const tb_gpu_device_info *tb_gpu_device_info_at(const tb_gpu_instance *inst, int index);

/* True if the instance runs with the validation layer. */
bool tb_gpu_validation_enabled(const tb_gpu_instance *inst);

/* Validation (and loader) messages of severity error seen so far. */
int tb_gpu_validation_errors(const tb_gpu_instance *inst);
/* ... and of severity warning (performance warnings included). */
int tb_gpu_validation_warnings(const tb_gpu_instance *inst);

/* Most messages kept; later ones are counted but not stored. */
#define TB_GPU_MAX_MESSAGES 32

/* Number of stored messages (<= TB_GPU_MAX_MESSAGES). */
int tb_gpu_validation_message_count(const tb_gpu_instance *inst);
/* Stored message i, "error: <id>: <text>" or "warning: ..."; NULL if out of range. */
const char *tb_gpu_validation_message(const tb_gpu_instance *inst, int i);
/* Forgets the messages and zeroes the counts. */
void tb_gpu_validation_clear(tb_gpu_instance *inst);

/* ---------------------------------------------------------------- selection */

/* The device `mode` uses among infos[0..n-1], or -1 for the CPU path.
 *  - TB_GPU_MODE_CPU: -1.
 *  - `requested` >= 0 (--device N): that device, in auto and vulkan mode;
 *    TB_ERR_ARG if it does not exist, TB_ERR_DEVICE if it cannot be used.
 *  - otherwise the best usable device: discrete GPU, then integrated, then
 *    virtual, then CPU driver, then other (the first in enumeration order on
 *    ties). In auto mode a CPU or "other" device is not used (-1): the C path
 *    is faster than a software Vulkan driver. In vulkan mode no usable device
 *    at all is TB_ERR_DEVICE.
 * `reason` (if not NULL) receives a sentence saying why, also on success. */
tb_status tb_gpu_pick_device(const tb_gpu_device_info *infos, int n, tb_gpu_mode mode,
                             int requested, int *index, char *reason, size_t reason_size);

/* ---------------------------------------------------------------- device */

/* A logical device with one compute queue, its command buffer, pipeline
 * cache and the kernels created on it. */
typedef struct tb_gpu_device tb_gpu_device;

/* Options of tb_gpu_device_create; all-zero is the default. */
typedef struct tb_gpu_device_desc {
    bool force_staging;  /* device-local buffers + staging copies even on unified memory */
    uint32_t timeout_ms; /* longest wait for one submission; 0 = 60 000 */
} tb_gpu_device_desc;

/* Creates device `index` of `inst` (desc may be NULL). NULL with TB_ERR_ARG
 * for a bad index, TB_ERR_DEVICE when the driver refuses. */
tb_gpu_device *tb_gpu_device_create(tb_gpu_instance *inst, int index, const tb_gpu_device_desc *desc);

/* Waits for the device to be idle and destroys it with its kernels. Buffers
 * must be destroyed first. NULL is ignored. */
void tb_gpu_device_destroy(tb_gpu_device *dev);

/* The device's description. */
const tb_gpu_device_info *tb_gpu_device_info_of(const tb_gpu_device *dev);

/* True once the device reported VK_ERROR_DEVICE_LOST or a submission timed
 * out; every later call on it fails with TB_ERR_DEVICE. */
bool tb_gpu_device_is_lost(const tb_gpu_device *dev);

/* True if buffers are host-visible (unified memory and no force_staging). */
bool tb_gpu_device_uses_mapped_buffers(const tb_gpu_device *dev);

/* Most invocations of a workgroup along x (maxComputeWorkGroupSize[0] and
 * maxComputeWorkGroupInvocations). */
uint32_t tb_gpu_workgroup_limit(const tb_gpu_device_info *info);

/* The workgroup width kernels get by default on this device: 64 rounded up
 * to whole subgroups, at most tb_gpu_workgroup_limit (docs/gpu.md). */
uint32_t tb_gpu_default_workgroup(const tb_gpu_device_info *info);

/* One line of the limits the kernels depend on (subgroup, workgroup,
 * shared memory, storage buffer, timestamps), snprintf's return value. */
int tb_gpu_limits_describe(const tb_gpu_device_info *info, char *buf, size_t n);

/* The same as --stats fields: gpu_device, gpu_subgroup_size,
 * gpu_workgroup_size, gpu_max_workgroup_invocations, gpu_max_shared_memory,
 * gpu_timestamp_period_ns (null without timestamps). */
tb_status tb_gpu_limits_to_stats(const tb_gpu_device_info *info);

/* ---------------------------------------------------------------- buffers */

/* A storage buffer in device memory. */
typedef struct tb_gpu_buffer tb_gpu_buffer;

/* A zero-filled storage buffer of `size` bytes (> 0). TB_ERR_DEVICE when the
 * size exceeds the device's limits or its memory. */
tb_gpu_buffer *tb_gpu_buffer_create(tb_gpu_device *dev, size_t size);

/* Destroys the buffer. NULL is ignored. */
void tb_gpu_buffer_destroy(tb_gpu_buffer *buf);

/* Size in bytes. */
size_t tb_gpu_buffer_size(const tb_gpu_buffer *buf);

/* Copies n bytes from src to the buffer at `offset` (waits until done). */
tb_status tb_gpu_buffer_upload(tb_gpu_buffer *buf, size_t offset, const void *src, size_t n);

/* Copies n bytes at `offset` of the buffer to dst (waits until done). */
tb_status tb_gpu_buffer_download(tb_gpu_buffer *buf, size_t offset, void *dst, size_t n);

/* ---------------------------------------------------------------- kernels */

/* Most storage buffers per kernel (set 0, bindings 0 .. buffers-1). */
#define TB_GPU_MAX_BUFFERS 12
/* Most specialization constants per kernel besides the workgroup size. */
#define TB_GPU_MAX_SPEC 24
/* Preferred workgroup width; the width used when a kernel description
 * leaves it 0 is tb_gpu_default_workgroup (this, in whole subgroups, within
 * the device's limits). */
#define TB_GPU_DEFAULT_WORKGROUP 64

/* How a kernel declares binding b (tb_gpu_kernel_desc.kinds[b]). A texel
 * buffer binding views the same tb_gpu_buffer through a format, and its
 * loads (texelFetch) are gathers without per-lane control flow on CPU
 * drivers such as lavapipe, where storage-buffer loads with per-lane
 * indices are scalar loops (docs/gpu.md, "Texel buffers"). */
typedef enum tb_gpu_binding_kind {
    TB_GPU_BIND_STORAGE = 0,     /* layout(std430) buffer { ... } */
    TB_GPU_BIND_TEXELS_RGBA32UI, /* uniform usamplerBuffer, 16-byte texels (texelFetch gives a uvec4) */
    TB_GPU_BIND_TEXELS_R32UI,    /* uniform usamplerBuffer, 4-byte texels (texelFetch(...).x) */
} tb_gpu_binding_kind;

/* A specialization constant: `layout(constant_id = id) const ...` in GLSL.
 * id 0 is reserved for the workgroup width (layout(local_size_x_id = 0)). */
typedef struct tb_gpu_spec_constant {
    uint32_t id;
    uint32_t value; /* 32 bits: uint, int, bool (0/1) or a float's bits (tb_float_to_bits) */
} tb_gpu_spec_constant;

/* What a kernel is: its module, its interface and its specialization. */
typedef struct tb_gpu_kernel_desc {
    const tb_gpu_spirv *spirv;         /* the module; entry point "main" */
    const char *name;                  /* for messages and timings; NULL = spirv->name */
    int buffers;                       /* buffers bound at set 0, bindings 0 .. buffers-1 */
    uint8_t kinds[TB_GPU_MAX_BUFFERS]; /* tb_gpu_binding_kind of each binding (0: storage buffer) */
    uint32_t push_size;                /* bytes of push constants, a multiple of 4 (0 = none) */
    uint32_t workgroup_size;           /* constant_id 0; 0 = TB_GPU_DEFAULT_WORKGROUP */
    const tb_gpu_spec_constant *spec;  /* other specialization constants (ids >= 1) */
    int spec_count;
} tb_gpu_kernel_desc;

/* A compute pipeline, owned by its device. */
typedef struct tb_gpu_kernel tb_gpu_kernel;

/* The kernel for `desc`, compiled on first request; later requests with an
 * equal description (same module, interface and constants) return the same
 * kernel without compiling again. It lives until the device is destroyed.
 * NULL with TB_ERR_ARG for an invalid description (not SPIR-V, too many
 * buffers, push constants beyond the device limit, workgroup too large). */
tb_gpu_kernel *tb_gpu_kernel_get(tb_gpu_device *dev, const tb_gpu_kernel_desc *desc);

/* The kernel's workgroup width (invocations per group along x). */
uint32_t tb_gpu_kernel_workgroup_size(const tb_gpu_kernel *k);

/* The kernel's name. */
const char *tb_gpu_kernel_name(const tb_gpu_kernel *k);

/* One kernel launch. */
typedef struct tb_gpu_dispatch {
    tb_gpu_kernel *kernel;
    tb_gpu_buffer *buffers[TB_GPU_MAX_BUFFERS]; /* bound at bindings 0 .. kernel's buffers-1 */
    const void *push;                           /* the kernel's push_size bytes (NULL if 0) */
    uint64_t items;    /* invocations: ceil(items / workgroup) groups along x; 0 = skip */
    double seconds;    /* out: device time from timestamps; NaN when the queue has none */
} tb_gpu_dispatch;

/* Records d[0..n-1] in order into one command buffer (each dispatch sees the
 * writes of the ones before it), submits it and waits. Each dispatch's device
 * time goes to d[i].seconds and to the statistic "GPU/kernel <name> (ns)"
 * (a distribution, util/stats); "GPU/dispatches" counts them. */
tb_status tb_gpu_run(tb_gpu_device *dev, tb_gpu_dispatch *d, int n);

/* Runs the library's selftest kernel on n words and compares every result
 * with the host's (TB_ERR_DEVICE on a wrong word); *seconds (may be NULL)
 * gets the kernel's device time (NaN without timestamps). */
tb_status tb_gpu_device_self_test(tb_gpu_device *dev, uint32_t n, double *seconds);

/* ---------------------------------------------------------------- choosing a backend */

/* The backend tb_gpu_backend_choose settled on, with the device it opened. */
typedef struct tb_gpu_session {
    tb_gpu_backend backend;
    tb_gpu_instance *instance; /* NULL on the CPU backend */
    tb_gpu_device *device;     /* NULL on the CPU backend */
    int device_index;          /* -1 on the CPU backend */
    char reason[512];          /* why this backend (always set; print it with -v) */
} tb_gpu_session;

/* Chooses the backend for `mode` and `device` (--device N, or -1) as
 * tb_gpu_pick_device says, and opens the Vulkan device when it is chosen.
 * In auto mode every Vulkan failure (no loader, no driver, device creation
 * refused) falls back to the CPU backend with the failure in out->reason and
 * TB_OK. In vulkan mode such a failure is returned (TB_ERR_DEVICE, or
 * TB_ERR_ARG for a bad --device) and *out is the CPU backend. `validation`
 * enables the validation layer. Close with tb_gpu_session_close. */
tb_status tb_gpu_backend_choose(tb_gpu_mode mode, int device, bool validation, tb_gpu_session *out);

/* Destroys the session's device and instance (if any) and clears it. */
void tb_gpu_session_close(tb_gpu_session *s);

#endif
