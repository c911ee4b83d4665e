/* The scene as the intersect kernel (shaders/intersect.comp) reads it: BVH
 * nodes converted from the CPU BVH (host/render/accel.h, tb_bvh_node), leaf
 * references (TB_GPU_REF_*), world-space triangles and placed analytic
 * objects (every MID primitive kind). Built by
 * host/gpu/intersect.c. See shared/types.h for the layout rules. */
#ifndef TB_SHADERS_SHARED_BVH_H
#define TB_SHADERS_SHARED_BVH_H

#include "types.h"

#ifndef TB_GPU_GLSL
typedef struct tb_gpu_bvh_node tb_gpu_bvh_node;
typedef struct tb_gpu_tri tb_gpu_tri;
typedef struct tb_gpu_placed tb_gpu_placed;
#endif

/* A leaf reference (one uint): a triangle index (kind bits 0), or a kind
 * (TB_GPU_REF_*: the three top bits, compare ref & TB_GPU_REF_KIND with
 * them) | an index into the placed-primitive array. Leaves list their
 * references in ascending kind order (triangles, cubes, spheres, planar,
 * revolved, tori), which is the order the traversal tests them in.
 * A revolved object (cylinder, cone, conic) takes two placed records: its
 * tb_gpu_placed, then its shape in the same 64 bytes: r0 = (c0, c1, c2) of
 * r^2 = c0 + c1 z + c2 z^2, w0 = z0, r1.x = z1, r1.y = the bits of a uint
 * TB_GPU_REVOLVED_* flags, the rest 0. A torus takes two: then r0 = (R, r, 0).
 * A planar object (pyramid, prism, arch) takes two, plus for a prism one
 * record per 8 profile vertices: r0.x = the bits of its TB_GPU_PLANAR_*
 * subtype, r0.y = the pyramid's top or the arch's width, r0.z = the arch's
 * height, w0 = the bits of TB_GPU_PLANAR_* flags, r1.x = the prism
 * profile's orientation (+1 counter-clockwise, -1), r1.y = the bits of its
 * vertex count; then the vertices as (x, y) float pairs, 16 floats per
 * record in member order (r0.x r0.y r0.z w0 r1.x ... sign).
 * Every placed object's second record has in r2 the object's origin in
 * world space, c, rounded to float; the first record's map is then applied
 * to (p - c) (its w0 w1 w2 are the map of c, about 0), so that no large
 * translation cancels in float far from the world origin.
 * A CSG tree (TB_GPU_REF_CSG) is a header record (r0.x = the bits of the
 * op count; object, face = its first face ID, ref as a placed object's),
 * then its post-order program, 16 uint words per record (member order): a
 * leaf's reference (kind bits non-zero: the leaf is a placed object of its
 * own, whose record holds the tree's object and reference index, the
 * leaf's face base and flip sign; a polygons leaf, TB_GPU_REF_MESH, is one
 * record: r0.x, r0.y = the bits of its first triangle's index and its
 * triangle count in the triangle array), or a node: TB_GPU_CSG_* << 8 | its
 * child count (<= TB_GPU_CSG_CHILDREN). lib/csg.glsl evaluates it with a
 * pool of TB_GPU_CSG_POOL crossings in at most TB_GPU_CSG_LISTS lists;
 * the host refuses a tree that could need more. */
#define TB_GPU_REF_CSG 0x20000000u
#define TB_GPU_REF_CUBE 0x40000000u
#define TB_GPU_REF_MESH 0x60000000u /* a CSG tree's polygons leaf only (never in a BVH leaf) */
#define TB_GPU_REF_SPHERE 0x80000000u
#define TB_GPU_REF_PLANAR 0xa0000000u
#define TB_GPU_REF_REVOLVED 0xc0000000u
#define TB_GPU_REF_TORUS 0xe0000000u
#define TB_GPU_REF_KIND 0xe0000000u
#define TB_GPU_REF_INDEX 0x1fffffffu
/* CSG node operations and the kernel's per-ray bounds. */
#define TB_GPU_CSG_UNION 1u
#define TB_GPU_CSG_INTERSECTION 2u
#define TB_GPU_CSG_DIFFERENCE 3u
#define TB_GPU_CSG_POOL 128    /* crossings of all pending lists of one ray */
#define TB_GPU_CSG_LISTS 16    /* pending lists (children evaluated, not yet merged) */
#define TB_GPU_CSG_CHILDREN 32 /* children of one node */
/* Subtypes and flags of a planar shape record. */
#define TB_GPU_PLANAR_PYRAMID 0u
#define TB_GPU_PLANAR_PRISM 1u
#define TB_GPU_PLANAR_SQUARE_ARCH 2u
#define TB_GPU_PLANAR_ROUND_ARCH 3u
#define TB_GPU_PLANAR_CAPS 1u   /* closed by its end faces */
#define TB_GPU_PLANAR_CONVEX 2u /* prism: a convex profile (clipped by its sides, else crossings are paired) */
/* Flags of a revolved object's shape record. */
#define TB_GPU_REVOLVED_CAPS 1u    /* closed by discs at z0 and z1 */
#define TB_GPU_REVOLVED_CLOSED0 2u /* radius 0 at z0 (an apex): crossings there are the side's */
#define TB_GPU_REVOLVED_CLOSED1 4u /* radius 0 at z1 */

/* One child record, 32 bytes; an inner node of the GPU BVH is two of them
 * (its children, records 2i and 2i + 1 of inner node i), so one fetch of 64
 * bytes gives both children's boxes and a traversal step tests both (Aila
 * and Laine, "Understanding the Efficiency of Ray Traversal on GPUs", 2009).
 * Converted from the CPU BVH (host/gpu/intersect.c): inner node 0 holds the
 * root's children (or, when the root is a leaf, the root and an empty box);
 * record 2i is the CPU's first child, 2i + 1 its second. The box words are
 * next to the vec3s so that std430 and C agree. */
struct tb_gpu_bvh_node {
    TB_GPU_VEC3 lo;     /* the child's box, low corner (offset 0); lo > hi: an empty box, never hit */
    TB_GPU_UINT offset; /* child inner: its inner-node index; child leaf: its first leaf reference (offset 12) */
    TB_GPU_VEC3 hi;     /* box, high corner (offset 16) */
    TB_GPU_UINT count;  /* low 16 bits: the child leaf's references (>= 1), 0 for an inner child; bits
                           16-17: the parent's split axis, which orders the two (offset 28) */
};

/* One triangle, 64 bytes: world-space vertices (the object's float vertices
 * mapped by its transform in double, rounded once), and what the hit record
 * needs: the CPU's geometric normal of that triangle (computed on the host
 * exactly as the CPU path does), the object, the face ID and the reference
 * index of the CPU BVH (the last key of the tie rule, docs/accel.md). */
struct tb_gpu_tri {
    TB_GPU_VEC3 v0;     /* offset 0 */
    TB_GPU_UINT object; /* top-level object index (offset 12) */
    TB_GPU_VEC3 v1;     /* offset 16 */
    TB_GPU_UINT face;   /* face ID, as in tb_hit (offset 28) */
    TB_GPU_VEC3 v2;     /* offset 32 */
    TB_GPU_UINT ref;    /* index of this triangle's reference in tb_scene.prims (offset 44) */
    TB_GPU_VEC3 ng;     /* unit geometric normal, world space, out of the solid (offset 48) */
    TB_GPU_UINT pad0;   /* zero (offset 60) */
};

/* One placed analytic object (a top-level MID sphere or cube: the unit
 * sphere or the cube [-1,1]^3 placed by its transform), 64 bytes: the rows of the world-to-object affine map in float
 * (p_obj.x = dot(r0, p) + w0 ...), which also give the world normal
 * r0 n.x + r1 n.y + r2 n.z (the inverse transpose), and the hit record's keys. */
struct tb_gpu_placed {
    TB_GPU_VEC3 r0;     /* offset 0 */
    float w0;           /* offset 12 */
    TB_GPU_VEC3 r1;     /* offset 16 */
    float w1;           /* offset 28 */
    TB_GPU_VEC3 r2;     /* offset 32 */
    float w2;           /* offset 44 */
    TB_GPU_UINT object; /* offset 48 */
    TB_GPU_UINT face;   /* face ID of the primitive's first face (face_base) (offset 52) */
    TB_GPU_UINT ref;    /* index of its reference in tb_scene.prims (offset 56) */
    float sign;         /* +1, or -1 when the object's normals are flipped (offset 60) */
};

#ifndef TB_GPU_GLSL
_Static_assert(sizeof(tb_gpu_placed) == 64, "tb_gpu_placed is 64 bytes");
_Static_assert(offsetof(tb_gpu_placed, w0) == 12 && offsetof(tb_gpu_placed, r1) == 16 &&
                   offsetof(tb_gpu_placed, r2) == 32 && offsetof(tb_gpu_placed, w2) == 44 &&
                   offsetof(tb_gpu_placed, object) == 48 && offsetof(tb_gpu_placed, sign) == 60,
               "tb_gpu_placed follows the std430 offsets of its GLSL twin");
_Static_assert(sizeof(tb_gpu_bvh_node) == 32, "tb_gpu_bvh_node is 32 bytes");
_Static_assert(offsetof(tb_gpu_bvh_node, offset) == 12 && offsetof(tb_gpu_bvh_node, hi) == 16 &&
                   offsetof(tb_gpu_bvh_node, count) == 28,
               "tb_gpu_bvh_node follows the std430 offsets of its GLSL twin");
_Static_assert(sizeof(tb_gpu_tri) == 64, "tb_gpu_tri is 64 bytes");
_Static_assert(offsetof(tb_gpu_tri, object) == 12 && offsetof(tb_gpu_tri, v1) == 16 &&
                   offsetof(tb_gpu_tri, face) == 28 && offsetof(tb_gpu_tri, v2) == 32 &&
                   offsetof(tb_gpu_tri, ref) == 44 && offsetof(tb_gpu_tri, ng) == 48 &&
                   offsetof(tb_gpu_tri, pad0) == 60,
               "tb_gpu_tri follows the std430 offsets of its GLSL twin");
#endif

#endif
