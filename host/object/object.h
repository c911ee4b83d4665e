/* The persistent scene object: one top-level MID object (a primitive or a CSG
 * tree) copied out of the streaming reader, whose items die at its next read,
 * and prepared once for the object-level functions (intersect.h, csg.h,
 * param.h, bounds, polygonize).
 *
 *     tb_object *obj;
 *     if (tb_object_from_mid(item.object, index, NULL, NULL, &obj)) fail(tb_last_error());
 *     ... tb_object_intersect(obj, &ray, &hit) ...
 *     tb_object_free(obj);
 *
 * The struct is public so that the other object-level modules and the
 * renderers can read it; treat it as read-only after construction (a built
 * object may be shared by any number of threads). */
#ifndef TB_HOST_OBJECT_OBJECT_H
#define TB_HOST_OBJECT_OBJECT_H

#include <stdbool.h>
#include <stdint.h>

#include "host/mid/mid.h"
#include "util/base/error.h"
#include "util/math/aabb.h"
#include "util/math/transform.h"
#include "util/math/vec.h"

/* One node of a triangle mesh's bounding volume hierarchy (32 bytes). Inner
 * nodes have their left child right after them and the right child at
 * `index`; leaves hold triangles index .. index + count - 1. */
typedef struct tb_object_bvh_node {
    union {
        struct {
            float lo[3], hi[3]; /* box of the node's triangles, widened outward by one float */
        };
        float b[6]; /* the same: lo x y z, hi x y z */
    };
    uint32_t index;     /* inner: right child; leaf: first triangle */
    uint16_t count;     /* triangles in a leaf; 0 for an inner node */
    uint16_t axis;      /* inner: split axis (0 x, 1 y, 2 z), for front-to-back traversal */
} tb_object_bvh_node;

_Static_assert(sizeof(tb_object_bvh_node) == 32, "BVH nodes are 32 bytes");

/* The triangulated form of a polygons primitive, built once for intersection:
 * every polygon is split into triangles (util/mesh/triangulate.h) that
 * remember the polygon (face ID) they came from. The ray/triangle test runs
 * in world space (docs/primitives.md, "Watertight triangles"): the vertices
 * are transformed once here, so a ray needs no transform per mesh. */
typedef struct tb_object_mesh {
    uint32_t nvertices;
    const tb_vec3 *vertices;    /* object-space positions: the object's geom.polygons.vertices (borrowed, not a
                                   copy: the geometry lives as long as the mesh) */
    double *wvertices;          /* the same mapped to world space by to_world in double, x y z per
                                   vertex (what the test uses) */
    int wsign;                  /* +1, or -1 if to_world mirrors (swaps which side is counter-clockwise) */
    uint32_t ntris;
    uint32_t *tris;             /* 3 vertex indices per triangle, counter-clockwise seen from the front; BVH leaf order */
    uint32_t *tri_face;         /* polygon index (face ID) of each triangle */
    float *tri_uv;              /* geometry without uvs: the face's frame-projected (u, v) at each triangle's
                                   corners (u0 v0 u1 v1 u2 v2), too slow to derive per hit; NULL with uvs
                                   (tb_object_triangle_uv reads the vertices' uvs then) */
    tb_vec3 *wnormal;           /* unit world normal of each triangle, as hits report it (flip included): stored,
                                   as deriving it per hit cost 10-20 % of closest-hit speed on large meshes */
    uint32_t nnodes;
    tb_object_bvh_node *nodes;  /* BVH over the triangles' world boxes; node 0 is the root (nnodes == 0 when ntris == 0) */
    bool closed;                /* every polygon edge is matched by exactly one edge running the other way: a solid */
} tb_object_mesh;

typedef struct tb_object tb_object;

/* What only a polygons object read from a FED file carries, kept out of
 * tb_object (one pointer instead of 32 bytes in every object). */
typedef struct tb_object_fed_ref {
    struct tb_fed *fed;                /* the loaded mesh (util/mesh/fed.h) */
    struct tb__fed_shared *shared;     /* when fed and the geom arrays are borrowed from a tb_object_fed_cache
                                          entry (private); NULL when the object owns them */
    tb_mid_ref file;                   /* the reference as written and resolved (owned copies) */
} tb_object_fed_ref;

/* FED files shared by the objects built through one cache (a scene): each
 * resolved path is read once, and every polygons object referring to it
 * borrows the loaded mesh and its inline form (docs/fed.md, "Shared files").
 * Refcounted: the cache and each such object hold a reference, so objects
 * may outlive the cache. Not thread-safe: build and free the objects of one
 * cache from one thread at a time. */
typedef struct tb_object_fed_cache tb_object_fed_cache;

/* A primitive or a CSG node with its children. Fields are ordered so that
 * no padding is left, and the fields of one kind (revolved quadrics, prisms)
 * share storage, and a FED file's fields are a record of their own: 448 bytes on 64-bit targets (docs/performance.md, "Memory per
 * object"). */
struct tb_object {
    tb_prim_kind kind;
    uint32_t index;          /* index of the top-level object (MID order, from 0); children carry their root's */
    int material;            /* opaque material index from the build callback (-1 without one) */
    int nchildren;
    uint32_t face_base;      /* first face ID of this node within the top-level object's numbering (0 for a lone primitive) */
    uint32_t nfaces;         /* face IDs this node uses: tb_param_face_count for a primitive, the sum over children for CSG */
    bool closed;             /* a solid (closed surface), so usable inside CSG */
    bool flip;               /* a CSG leaf subtracted an odd number of times on its path: its normals point inward in the result */
    bool inv_affine;         /* to_world.inv's last row is exactly 0 0 0 1 (checked at build): the world -> object
                                ray mapping's fast path; false (the general path) for an object not built here */
    bool zclosed[2];         /* cylinder, cone, conic: the radius is zero at zrange[0] / [1] (an apex: no cap) */
    bool profile_convex;     /* prism: the profile is convex (clipped by planes, else crossings are counted) */
    char *name;              /* copy of the MID name, or NULL */
    tb_transform to_world;   /* object space to world (double, with inverse): the full product for children too */
    double scale;            /* Frobenius norm of the linear part of to_world (bounds world error from object error) */
    tb_mid_geometry geom;    /* deep copy of the parameters; pointers owned by the object. Polygons from a FED
                                file are given here in inline form (the file's vertices, and each face's outer
                                loop as a polygon; mesh.text NULL), so param and bounds work on them; the holes
                                are in `fed` */
    tb_object *children;     /* CSG nodes: the children, in MID order */
    const tb_object *parent; /* the CSG node holding this one, NULL at the top */
    tb_object_mesh *mesh;    /* polygons: the triangulated mesh; NULL for other kinds */
    tb_object_fed_ref *fed;  /* polygons from a FED file: the loaded mesh, its sharing and the reference
                                (owned record); NULL otherwise */
    /* Derived at build time for intersection (docs/primitives.md); only the
     * object's own kind's fields are meaningful (the others share storage). */
    union {
        struct {
            double conic[3];  /* cylinder, cone, conic: r^2 = conic[0] + conic[1] z + conic[2] z^2 */
            double zrange[2]; /* cylinder, cone, conic: the z range */
        };
        struct {
            double *profile;       /* prism: the profile points used by the test, as x y pairs (owned) */
            double profile_orient; /* prism: +1 if the profile turns counter-clockwise, -1 if clockwise */
            int nprofile;          /* prism: profile points used by the test (0: large regular prism, tested by
                                      sectors) */
        };
    };
};


_Static_assert(sizeof(void *) != 8 || sizeof(tb_object) == 448, "tb_object stays 448 bytes (no padding)");

/* Maps a resolved MID material to the renderer's material index; returns
 * TB_OK or an error (with tb_error) that aborts the build. */
typedef tb_status (*tb_object_material_fn)(void *user, const tb_mid_material *m, int *index);

/* Builds the persistent object of the streamed MID object `m` (deep copy:
 * `m` may die afterwards). `index` is its top-level index; `material` (may be
 * NULL: every material index is then -1) is called for each node. Polygons
 * are triangulated and a BVH built. Rejected with TB_ERR_ARG and a message:
 * non-finite, projective, singular or ill-conditioned transforms, parameters
 * outside their MID ranges, polygons with out-of-range indices or fewer than
 * three vertices, CSG nodes with too few children, and CSG children that are
 * not closed solids (open cylinders, cones, pyramids, prisms, conics without
 * caps, polygon meshes whose edges do not pair up). A polygons primitive
 * referring to a FED mesh file loads it (resolved path; the reader's errors,
 * TB_ERR_IO or TB_ERR_FORMAT, with the file named). *out is NULL on failure. */
tb_status tb_object_from_mid(const tb_mid_object *m, uint32_t index, tb_object_material_fn material,
                             void *user, tb_object **out);

/* tb_object_from_mid with FED files shared through `cache` (NULL: each
 * object reads its own copy): a file already read through the cache is not
 * read again. */
tb_status tb_object_from_mid_shared(const tb_mid_object *m, uint32_t index, tb_object_material_fn material,
                                    void *user, tb_object_fed_cache *cache, tb_object **out);

/* A new, empty FED cache; NULL when out of memory. */
tb_object_fed_cache *tb_object_fed_cache_new(void);

/* Drops the cache's references (files still used by objects stay until those are freed); NULL is allowed. */
void tb_object_fed_cache_free(tb_object_fed_cache *c);

/* FED files read through the cache so far. */
size_t tb_object_fed_cache_files(const tb_object_fed_cache *c);

/* Bytes held for them (the FED meshes and their inline forms), counted once however many objects share them. */
size_t tb_object_fed_cache_bytes(const tb_object_fed_cache *c);

/* Frees an object and its children; NULL is allowed. */
void tb_object_free(tb_object *obj);

/* How many objects (and CSG children) have been torn down so far: a memo that
 * keys on an object's address compares it, since a later object may reuse
 * the address. */
unsigned long tb_object_generation(void);

/* The CSG leaf (a primitive of the tree, or obj itself when it is a
 * primitive) owning face ID `face` of top-level object `obj`, and that face's
 * ID within the leaf (*local, may be NULL). NULL if no leaf has that face. */
const tb_object *tb_object_leaf_for_face(const tb_object *obj, uint32_t face, uint32_t *local);

#endif
