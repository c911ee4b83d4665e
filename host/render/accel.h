/* Ray acceleration structures over primitive references: a bounding volume
 * hierarchy (binned SAH) and a uniform grid (3D-DDA) behind one interface,
 * plus a plain list that tests every reference (the reference answer).
 *
 * The structure knows nothing about primitive kinds. It is built over N
 * *references*, each a world-space box and an opaque (object, sub) pair: an
 * analytic primitive or a CSG object is one reference, a big mesh gives one
 * reference per triangle. Traversal calls the caller's intersection callback
 * for the references it cannot rule out by their boxes, except triangles
 * given as tb_accel_tri records, which it tests itself (watertight, in
 * double: the object level's own test).
 *
 *     tb_accel_prim *prims = ...;   // boxes + (object, sub)
 *     tb_accel_callbacks cb = {my_intersect, my_occluded, my_ctx, NULL};
 *     tb_accel *acc;
 *     if (tb_accel_build(TB_ACCEL_BVH, prims, n, &cb, NULL, &acc)) fail(tb_last_error());
 *     tb_hit hit;
 *     if (tb_accel_intersect(acc, &ray, &hit)) ... hit.t, hit.object, hit.face ...
 *     tb_accel_free(acc);
 *
 * Every kind returns the same hit, bit for bit, for the same ray: the
 * closest one, ties in t broken by the lower object index, then the lower
 * face ID, then the lower reference index (docs/accel.md, "Tie rule"). Built
 * structures are read-only: any number of threads may query one at once. */
#ifndef TB_HOST_RENDER_ACCEL_H
#define TB_HOST_RENDER_ACCEL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "host/object/hit.h"
#include "util/base/error.h"
#include "util/math/aabb.h"
#include "util/math/ray.h"

/* Which structure tb_accel_build makes. */
typedef enum tb_accel_kind {
    TB_ACCEL_BVH = 0,  /* bounding volume hierarchy, binned SAH (bvh.c) */
    TB_ACCEL_GRID = 1, /* uniform grid, 3D-DDA traversal (grid.c) */
    TB_ACCEL_LIST = 2, /* no structure: every reference is tested (for reference answers) */
} tb_accel_kind;

/* One primitive reference (32 bytes). */
typedef struct tb_accel_prim {
    tb_aabb bounds;  /* world box holding every point the callback can report for this reference */
    uint32_t object; /* opaque to the structure; by convention the top-level object index */
    uint32_t sub;    /* opaque; by convention the sub-primitive (e.g. triangle) within the object */
} tb_accel_prim;

_Static_assert(sizeof(tb_accel_prim) == 32, "tb_accel_prim is 32 bytes");

/* Closest hit of reference `prim` (number `index` in the array given to
 * tb_accel_build) with the ray, at ray->tmin <= t <= ray->tmax: fill *hit and
 * return true, or return false. The structure passes its own shortened copy of
 * the ray (tmax = the best t so far), so the result must not depend on tmax
 * other than by that filter (docs/accel.md, "Callback contract"). */
typedef bool (*tb_accel_intersect_fn)(void *ctx, const tb_accel_prim *prim, uint32_t index,
                                      const tb_ray *ray, tb_hit *hit);

/* True if reference `prim` is hit anywhere with ray->tmin <= t <= ray->tmax. */
typedef bool (*tb_accel_occluded_fn)(void *ctx, const tb_accel_prim *prim, uint32_t index,
                                     const tb_ray *ray);

/* A triangle reference the structure tests itself, without a callback
 * (docs/accel.md, "Triangle references"): the watertight test of
 * host/object/watertight.h in double on the world corners, the range checked
 * on the float t, the hit reported with hit.u, hit.v and hit.ng 0 (the
 * caller completes them from tb_accel_tri_hit). 80 bytes. */
typedef struct tb_accel_tri {
    double v[9];     /* world corners x y z, counter-clockwise seen from the front */
    uint32_t object; /* hit.object; TB_ACCEL_TRI_NONE: not a triangle, the callbacks test this reference */
    uint32_t face;   /* hit.face */
} tb_accel_tri;

_Static_assert(sizeof(tb_accel_tri) == 80, "tb_accel_tri is 80 bytes");

/* tb_accel_tri.object of a reference that is not a triangle. */
#define TB_ACCEL_TRI_NONE UINT32_MAX

/* The triangle record of reference `prim` (number `index` in the array
 * given to the build), made on demand at build: writes *out (object
 * TB_ACCEL_TRI_NONE for a reference that is not a triangle). */
typedef void (*tb_accel_tri_fn)(void *tri_ctx, const tb_accel_prim *prim, uint32_t index, tb_accel_tri *out);

/* How leaf references are intersected. */
typedef struct tb_accel_callbacks {
    tb_accel_intersect_fn intersect; /* required */
    tb_accel_occluded_fn occluded;   /* NULL: tb_accel_occluded uses `intersect` */
    void *ctx;                       /* passed to both */
    const tb_accel_tri *tris;        /* optional, one per reference (input numbering): those whose object is
                                        not TB_ACCEL_TRI_NONE are tested by the structure (copied at build) */
} tb_accel_callbacks;

/* What a closest hit on a triangle reference (tb_accel_tri) adds to the hit
 * record, for completing its (u, v) and normal. */
typedef struct tb_accel_tri_hit {
    uint32_t index;  /* input index of the reference; TB_ACCEL_TRI_NONE when the hit came from a callback */
    uint32_t sub;    /* the reference's tb_accel_prim.sub (so the caller need not look the reference up) */
    int dir;         /* +1: the ray meets the side from which the corners run counter-clockwise, else -1 */
    double t;        /* the line parameter in double (hit.t is it rounded to float) */
    double uvw[3];   /* the test's edge functions: the crossing is (U v0 + V v1 + W v2) / (U + V + W) */
} tb_accel_tri_hit;

/* Build options; a zeroed struct (or NULL) means every default. */
typedef struct tb_accel_options {
    int threads;           /* BVH build threads (0: OpenMP's default); the tree does not depend on it */
    int bvh_bins;          /* SAH bins per axis, 2..256 (0: 32) */
    int bvh_max_leaf;      /* most references in a leaf, 1..255 (0: 8) */
    float bvh_cost_node;   /* SAH cost of visiting an inner node (0: 1.0) */
    float bvh_cost_prim;   /* SAH cost of one reference test (0: 1.0) */
    int bvh_no_avx;        /* non-zero: traverse with the SSE2 node test even where the CPU has AVX (tests,
                              comparisons; the answers are the same) */
    int bvh_no_pack;       /* non-zero: test leaf triangles one by one instead of packed four (AVX) or two
                              (SSE2) at once (tests, comparisons; the answers are the same) */
    int bvh_keep_binary;   /* non-zero: keep the binary nodes once collapsed into the wide tree the CPU
                              traverses, for tb_accel_bvh_nodes (GPU conversion, tree comparisons); by
                              default they are freed (32 bytes per node) */
    double grid_density;   /* voxels along the longest axis = density * cbrt(N) (0: 3.0) */
    int grid_max_res;      /* most voxels along one axis, 1..1024 (0: 256) */
} tb_accel_options;

/* Figures about a built structure (tb_accel_get_stats). */
typedef struct tb_accel_stats {
    tb_accel_kind kind;
    size_t nprims;         /* references stored (references with an empty box are dropped) */
    double build_seconds;  /* wall-clock time of tb_accel_build */
    size_t memory_bytes;   /* heap bytes held by the structure */
    size_t tri_bytes;      /* the part of memory_bytes held for triangle references alone: their records
                              (tb_accel_tri; none when every reference is a packed triangle), packed corners
                              and their positions */
    tb_aabb bounds;        /* box of all stored references */
    /* BVH */
    size_t bvh_nodes;      /* nodes, inner and leaf */
    size_t bvh_leaves;
    int bvh_depth;         /* longest root-to-leaf path in edges (0: the root is a leaf) */
    int bvh_max_leaf_prims; /* references in the largest leaf */
    double bvh_sah_cost;   /* SAH cost of the tree (docs/accel.md, "SAH cost"), with the build's constants */
    size_t bvh_wide_nodes; /* nodes of the 8-wide tree the CPU queries traverse (the binary one collapsed) */
    /* grid */
    int grid_res[3];       /* voxels along x, y, z */
    size_t grid_cells;     /* res[0] * res[1] * res[2] */
    size_t grid_nonempty;  /* voxels holding at least one reference */
    size_t grid_refs;      /* (voxel, reference) pairs stored */
    tb_aabb grid_bounds;   /* the box the voxels divide (the references' box, slightly padded) */
} tb_accel_stats;

/* An acceleration structure (opaque). */
typedef struct tb_accel tb_accel;

/* Builds a structure of `kind` over prims[0..n) (copied: the array may be
 * freed afterwards). n == 0 gives an empty structure that is never hit.
 * TB_ERR_ARG (with a message) for an unknown kind, NULL arguments, a missing
 * intersect callback, options out of range, a reference box with a NaN or
 * infinite corner, or n >= 2^32 - 1; TB_ERR_NOMEM when memory runs out.
 * *out is NULL on failure. */
tb_status tb_accel_build(tb_accel_kind kind, const tb_accel_prim *prims, size_t n,
                         const tb_accel_callbacks *cb, const tb_accel_options *opt, tb_accel **out);

/* tb_accel_build that takes `prims` (from malloc, n elements) instead of
 * copying it: the structure keeps the array as its own, or frees it on
 * failure, so the caller's copy is not held beside the structure's through
 * the build (32 bytes per reference at its peak). With cb->tris NULL, `tri`
 * (may be NULL) makes the triangle records instead, one at a time once the
 * tree is built, so no array of them exists during the build (80 bytes per
 * reference). The same structure as tb_accel_build with the same records. */
tb_status tb_accel_build_owned(tb_accel_kind kind, tb_accel_prim *prims, size_t n, const tb_accel_callbacks *cb,
                               tb_accel_tri_fn tri, void *tri_ctx, const tb_accel_options *opt, tb_accel **out);

/* Closest hit with ray->tmin <= t <= ray->tmax (ties as in the file comment):
 * fills *hit and returns true, or returns false and leaves *hit unchanged.
 * Invalid rays (tb_ray_is_valid false: NaN, infinite origin or direction,
 * zero direction, tmin > tmax) are never hit and counted as
 * "Accel/invalid rays". */
bool tb_accel_intersect(const tb_accel *acc, const tb_ray *ray, tb_hit *hit);

/* tb_accel_intersect, and when the hit is on a triangle reference fills
 * *tri (tri->index is TB_ACCEL_TRI_NONE otherwise, or on a miss). */
bool tb_accel_intersect_tri(const tb_accel *acc, const tb_ray *ray, tb_hit *hit, tb_accel_tri_hit *tri);

/* True if anything is hit with ray->tmin <= t <= ray->tmax (stops at the
 * first hit found). False for invalid rays. */
bool tb_accel_occluded(const tb_accel *acc, const tb_ray *ray);

/* Fills *out with the structure's figures. */
void tb_accel_get_stats(const tb_accel *acc, tb_accel_stats *out);

/* The kind the structure was built as. */
tb_accel_kind tb_accel_get_kind(const tb_accel *acc);

/* "bvh", "grid" or "list" (NULL for an unknown kind). */
const char *tb_accel_kind_name(tb_accel_kind kind);

/* The kind called `name` ("bvh", "grid", "list"): TB_ERR_ARG if none is. */
tb_status tb_accel_kind_from_name(const char *name, tb_accel_kind *out);

/* Frees the structure; NULL is allowed. */
void tb_accel_free(tb_accel *acc);

/* ------------------------------------------------------------ BVH layout
 * The flattened tree, for code that converts it to another layout (GPU
 * buffers). Nodes are in depth-first order: node 0 is the root, an inner
 * node's first child follows it and its second child is at `offset`. */

/* One BVH node (32 bytes). */
typedef struct tb_bvh_node {
    tb_aabb bounds;  /* box of every reference below the node */
    uint32_t offset; /* inner: index of the second child; leaf: first reference in tb_accel_bvh_refs order */
    uint16_t count;  /* leaf: number of references (>= 1); 0 marks an inner node */
    uint8_t axis;    /* inner: split axis (0 x, 1 y, 2 z): the first child holds the lower centroids */
    uint8_t pad;     /* zero */
} tb_bvh_node;

_Static_assert(sizeof(tb_bvh_node) == 32, "tb_bvh_node is 32 bytes");

/* The BVH's binary nodes and their number: NULL and 0 for an empty BVH, another
 * kind, or a BVH built without tb_accel_options.bvh_keep_binary (the CPU
 * traverses the wide tree only; tb_accel_stats.bvh_nodes still counts them). */
const tb_bvh_node *tb_accel_bvh_nodes(const tb_accel *acc, size_t *count);

/* The input index of each reference in leaf order (leaf references
 * offset .. offset + count - 1 are refs[offset ..]); NULL for another kind,
 * and for a BVH of packed triangles only built without bvh_keep_binary (the
 * packed leaves keep the indices; the array is freed). */
const uint32_t *tb_accel_bvh_refs(const tb_accel *acc, size_t *count);

#endif
