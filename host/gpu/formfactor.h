/* The Vulkan form-factor kernel (shaders/formfactor.comp; docs/gpu.md,
 * "Form-factor kernel"): ray-cast form factors (Wallace, Elmquist and Haines
 * 1989) from one shooter's sample points to many receivers, with visibility
 * through a BVH over the occluder polygons, the GPU twin of
 * tb_ff_raycast_batch (host/radiosity/formfactor.h).
 *
 *     tb_gpu_ff_scene *g = tb_gpu_ff_scene_create(dev, polys, n);
 *     tb_ff_batch_fn fn = tb_gpu_ff_batch;       // a drop-in for tb_ff_raycast_batch
 *     fn(g, pts, npts, ns, area, p, n, count, ff);
 *     tb_gpu_ff_scene_destroy(g);
 *
 * Arithmetic is float (the CPU path is double): the tolerances are in
 * docs/accuracy.md ("Form-factor kernel"). Used from one thread at a time
 * (it uses the device's command buffer). */
#ifndef TB_HOST_GPU_FORMFACTOR_H
#define TB_HOST_GPU_FORMFACTOR_H

#include <stddef.h>
#include <stdint.h>

#include "host/gpu/gpu.h"
#include "host/radiosity/formfactor.h"
#include "util/base/error.h"
#include "util/math/vec.h"

/* Occluders uploaded to a device (opaque). */
typedef struct tb_gpu_ff_scene tb_gpu_ff_scene;

/* Receivers per dispatch: larger batches are split into chunks of this many. */
#define TB_GPU_FF_CHUNK ((size_t)1 << 16)

/* Timings of the last tb_gpu_ff_raycast call. */
typedef struct tb_gpu_ff_timing {
    double kernel_seconds; /* device time of the dispatches (timestamps; NaN without) */
    double seconds;        /* host wall time of the call (packing, upload, dispatch, download) */
    int dispatches;        /* chunks run */
} tb_gpu_ff_timing;

/* Uploads occluders[0..n) (n may be 0: nothing occludes) to `dev`: quads as
 * two triangles (v0 v1 v2, v0 v2 v3), a BVH built with host/render/accel.h
 * and converted to the GPU node layout (shaders/shared/bvh.h). NULL with a
 * status on failure (TB_ERR_ARG, TB_ERR_NOMEM, TB_ERR_DEVICE). */
tb_gpu_ff_scene *tb_gpu_ff_scene_create(tb_gpu_device *dev, const tb_ff_polygon *occluders, size_t n);

/* Frees the device buffers; NULL is ignored. */
void tb_gpu_ff_scene_destroy(tb_gpu_ff_scene *g);

/* Occluder triangles uploaded. */
size_t tb_gpu_ff_scene_triangles(const tb_gpu_ff_scene *g);

/* Form factors from the shooter (sample points pts[0..npts), unit normal ns,
 * `area`) to receivers p[i] with unit normals n[i], i < count: ff[i] as
 * tb_ff_raycast gives it (within float rounding, and up to visibility flips
 * of grazing segments). If `visible` is not NULL it receives, per receiver,
 * ceil(npts / 32) words of bits: bit k of word k / 32 is set when sample k
 * counted (in front of both surfaces and not blocked). `timing` may be NULL.
 * npts = 0 or area = 0 give zeros (as the CPU path). TB_ERR_ARG for
 * npts < 0, NULL arrays with count > 0 or an area that is negative or not
 * finite; TB_ERR_DEVICE from the device. */
tb_status tb_gpu_ff_raycast(tb_gpu_ff_scene *g, const tb_vec3 *pts, int npts, tb_vec3 ns, double area,
                            const tb_vec3 *p, const tb_vec3 *n, size_t count, double *ff, uint32_t *visible,
                            tb_gpu_ff_timing *timing);

/* A tb_ff_batch_fn: `ctx` is a tb_gpu_ff_scene (tb_gpu_ff_raycast without
 * visibility bits or timing). */
tb_status tb_gpu_ff_batch(void *ctx, const tb_vec3 *pts, int npts, tb_vec3 ns, double area, const tb_vec3 *p,
                          const tb_vec3 *n, size_t count, double *ff);

#endif
