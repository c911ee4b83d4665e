/* The Vulkan intersect kernel over a loaded scene (docs/gpu.md, "Intersect
 * kernel"): the scene's triangles uploaded in world space with a BVH in the
 * GPU layout (shaders/shared/bvh.h), closest-hit and any-hit queries for
 * arrays of rays, giving the records the CPU path gives (tb_scene_intersect).
 *
 * Kinds on the GPU: triangles of polygons objects, every analytic primitive
 * and CSG trees of them (lib/csg.glsl): the kernel declares them as the
 * object features (host/render/features.h) it implements,
 * TB_GPU_INTERSECT_FEATURES. A CSG tree beyond the kernel's per-ray bounds
 * (TB_GPU_CSG_*, shaders/shared/bvh.h) makes tb_gpu_scene_create fail with a
 * message naming it. An object with a feature outside the mask (unmeshed
 * polygons; quadrics under TB_GPU_QUADRICS_CPU) is **routed to the CPU path
 * per object**: after the kernel, the host tests those objects (through a
 * CPU BVH over them alone) with tmax = the GPU hit's t and keeps the better
 * hit by the tie rule (docs/accel.md). tb_gpu_scene_object_on_gpu says where
 * each object runs, tb_gpu_scene_object_route why one is routed.
 *
 *     tb_gpu_scene *g = tb_gpu_scene_create(dev, scene);
 *     tb_gpu_intersect(g, rays, n, hits, NULL);
 *     tb_gpu_scene_destroy(g);
 *
 * Used from one thread at a time (it uses the device's command buffer). */
#ifndef TB_HOST_GPU_INTERSECT_H
#define TB_HOST_GPU_INTERSECT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "host/gpu/gpu.h"
#include "host/object/hit.h"
#include "host/render/features.h"
#include "host/render/scene.h"
#include "util/math/ray.h"

/* A scene uploaded to a device (opaque). */
typedef struct tb_gpu_scene tb_gpu_scene;

/* Where the work of a scene runs. */
typedef struct tb_gpu_scene_info {
    uint32_t gpu_objects;   /* objects intersected by the kernel (every kind, CSG trees) */
    uint64_t gpu_triangles; /* triangles of the polygons objects */
    uint32_t gpu_spheres;   /* sphere objects */
    uint32_t gpu_cubes;     /* cube objects */
    uint32_t gpu_quadrics;  /* cylinder, cone and conic objects */
    uint32_t gpu_planar;    /* pyramid, prism and arch objects */
    uint32_t gpu_tori;      /* torus objects */
    uint32_t gpu_csg;       /* CSG trees (lib/csg.glsl) */
    uint32_t cpu_objects;   /* objects routed to the CPU path (features outside the kernel's mask) */
    size_t gpu_nodes;       /* BVH nodes uploaded */
    size_t gpu_bytes;       /* bytes of nodes and triangles uploaded */
} tb_gpu_scene_info;

/* Timings of the last tb_gpu_intersect / tb_gpu_occluded call. */
typedef struct tb_gpu_intersect_timing {
    double kernel_seconds; /* device time of the kernel dispatches (timestamps; NaN without) */
    double gpu_seconds;    /* host wall time of upload + dispatch + download */
    double cpu_seconds;    /* host wall time of the routed CPU tests and merge (and u, v of triangle hits) */
} tb_gpu_intersect_timing;

/* Where cylinders, cones and conics are intersected (tb_gpu_scene_desc). */
typedef enum tb_gpu_quadrics {
    TB_GPU_QUADRICS_AUTO = 0, /* in the kernel (every device) */
    TB_GPU_QUADRICS_GPU,      /* in the kernel (lib/revolved.glsl) */
    TB_GPU_QUADRICS_CPU,      /* routed to the CPU path per object */
} tb_gpu_quadrics;

/* The object features (host/render/features.h) of cylinders, cones and
 * conics: in the kernel's mask only where tb_gpu_quadrics puts them on the GPU. */
#define TB_GPU_QUADRIC_FEATURES ((uint32_t)(TB_OBJ_FEAT_CYLINDER | TB_OBJ_FEAT_CONE | TB_OBJ_FEAT_CONIC))

/* The object features the intersect kernel implements: an object with any
 * other is routed to the CPU path (a new primitive kind's bit is outside it
 * until the kernel intersects the kind). */
#define TB_GPU_INTERSECT_FEATURES                                                                              \
    ((uint32_t)(TB_OBJ_FEAT_TRIANGLES | TB_OBJ_FEAT_SPHERE | TB_OBJ_FEAT_CUBE | TB_GPU_QUADRIC_FEATURES |        \
                TB_OBJ_FEAT_PYRAMID | TB_OBJ_FEAT_PRISM | TB_OBJ_FEAT_TORUS | TB_OBJ_FEAT_SQUARE_ARCH |         \
                TB_OBJ_FEAT_ROUND_ARCH | TB_OBJ_FEAT_CSG_UNION | TB_OBJ_FEAT_CSG_INTERSECTION |                 \
                TB_OBJ_FEAT_CSG_DIFFERENCE))

/* The object features a scene on `dev` with quadrics mode `quadrics` has
 * intersected by the kernel: TB_GPU_INTERSECT_FEATURES, without
 * TB_GPU_QUADRIC_FEATURES for TB_GPU_QUADRICS_CPU (the same on every device). */
uint32_t tb_gpu_intersect_supported(const tb_gpu_device *dev, tb_gpu_quadrics quadrics);

/* Why an object with features `features` is not intersected by a kernel
 * supporting `supported` (a short phrase for the first unsupported feature
 * in TB_OBJECT_FEATURES order), or NULL when it is intersected there. */
const char *tb_gpu_object_route_reason(uint32_t features, uint32_t supported);

/* Options of tb_gpu_scene_create_ex; zero-initialised = the defaults. */
typedef struct tb_gpu_scene_desc {
    tb_gpu_quadrics quadrics;
} tb_gpu_scene_desc;

/* Uploads the scene's geometry to `dev` (the scene must have been loaded with
 * an acceleration structure, and outlive the result). NULL with a status on
 * failure (TB_ERR_DEVICE from the device, TB_ERR_NOMEM; TB_ERR_ARG for a CSG tree beyond
 * the kernel's bounds, named in the message). */
tb_gpu_scene *tb_gpu_scene_create(tb_gpu_device *dev, const tb_scene *scene);

/* tb_gpu_scene_create with options (`desc` may be NULL: the defaults). */
tb_gpu_scene *tb_gpu_scene_create_ex(tb_gpu_device *dev, const tb_scene *scene, const tb_gpu_scene_desc *desc);

/* Frees the device buffers and the host data; NULL is ignored. */
void tb_gpu_scene_destroy(tb_gpu_scene *g);

/* What runs where. */
void tb_gpu_scene_get_info(const tb_gpu_scene *g, tb_gpu_scene_info *out);

/* What another kernel needs to traverse this scene's GPU geometry with
 * shaders/lib/bvh_traverse.glsl: the four buffers to bind (named there
 * TB_BVH_NODES, TB_BVH_TRIS, TB_BVH_PLACED, TB_BVH_REFS), the node count to
 * pass to tb_bvh_closest / tb_bvh_occluded, and values for its optional
 * TB_BVH_HAS_* / TB_BVH_STACK specialization. Objects not on the GPU
 * (tb_gpu_scene_object_on_gpu) are not in these buffers. */
typedef struct tb_gpu_scene_bindings {
    tb_gpu_buffer *nodes, *tris, *placed, *refs; /* never NULL (1-element buffers when empty) */
    uint32_t nnodes;                             /* 0: nothing on the GPU */
    uint32_t stack;                              /* traversal stack entries enough for this BVH */
    bool has_triangles, has_spheres, has_cubes, has_quadrics; /* kinds present (quadrics: cylinders, cones, conics) */
    bool has_planar, has_tori;                                /* pyramids, prisms, arches; tori */
    bool has_csg;                                             /* CSG trees */
} tb_gpu_scene_bindings;

/* Fills `out` with the scene's device buffers (owned by the scene: valid until
 * tb_gpu_scene_destroy). */
void tb_gpu_scene_get_bindings(const tb_gpu_scene *g, tb_gpu_scene_bindings *out);

/* True if object `object` is intersected on the GPU, false if on the CPU. */
bool tb_gpu_scene_object_on_gpu(const tb_gpu_scene *g, uint32_t object);

/* Why object `object` is routed to the CPU path (tb_gpu_object_route_reason
 * of its features), or NULL when it is intersected on the GPU or out of range. */
const char *tb_gpu_scene_object_route(const tb_gpu_scene *g, uint32_t object);

/* Closest hit of each of rays[0..n): hits[i] is the record tb_scene_intersect
 * gives (within the float tolerance of docs/accuracy.md), or a miss:
 * t = +inf, object = face = UINT32_MAX, u = v = 0, ng = 0. Invalid rays are
 * misses. `timing` may be NULL. */
tb_status tb_gpu_intersect(tb_gpu_scene *g, const tb_ray *rays, size_t n, tb_hit *hits,
                           tb_gpu_intersect_timing *timing);

/* Any hit: occluded[i] = 1 if something is hit with tmin <= t <= tmax, else 0. */
tb_status tb_gpu_occluded(tb_gpu_scene *g, const tb_ray *rays, size_t n, uint8_t *occluded,
                          tb_gpu_intersect_timing *timing);

#endif
