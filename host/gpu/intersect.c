/* The Vulkan intersect kernel over a scene, with per-object routing of the
 * kinds the kernel does not implement to the CPU path (intersect.h,
 * docs/gpu.md "Intersect kernel"). */
#include "host/gpu/intersect.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "host/object/intersect.h"
#include "host/object/intersect_internal.h"
#include "host/object/param.h"
#include "shaders/shared/bvh.h"
#include "shaders/shared/hit.h"
#include "shaders/shared/ray.h"
#include "util/math/mat.h"
#include "util/math/transform.h"
#include "util/stats/stats.h"

TB_STAT_COUNTER(tb__n_gpu_rays, "GPU intersect/rays");
TB_STAT_COUNTER(tb__n_gpu_routed_tests, "GPU intersect/rays tested on the CPU for routed objects");

/* A NULL from a host/gpu constructor has set the message; its status is TB_ERR_DEVICE or TB_ERR_ARG. */
/* Rays per dispatch (8 MiB of rays and of hits). */
#define TB__GPU_CHUNK ((size_t)1 << 18)

struct tb_gpu_scene {
    tb_gpu_device *dev;
    const tb_scene *scene;
    uint32_t *features;      /* per object: its object features (tb_object_features) */
    uint32_t supported;      /* the object features intersected by the kernel (tb_gpu_intersect_supported) */
    bool *on_gpu;            /* per object: features within `supported` */
    tb_gpu_scene_info info;
    tb_accel *cpu_accel;     /* BVH over the routed objects' references (NULL if none) */
    tb_gpu_buffer *nodes, *tris, *placed, *refs, *rays, *hits; /* placed: spheres and cubes */
    uint32_t nnodes, ntris, nspheres, ncubes, nquadrics, nplanar, ntori, ncsg;
    uint32_t stack;          /* traversal stack entries: the GPU BVH's depth, rounded up to a multiple of 8 */
};

/* The build needs a callback; the GPU BVH is only read, never traversed here. */
static bool tb__never(void *ctx, const tb_accel_prim *p, uint32_t i, const tb_ray *r, tb_hit *h)
{
    (void)ctx, (void)p, (void)i, (void)r, (void)h;
    return false;
}

static bool tb__cpu_isect(void *ctx, const tb_accel_prim *p, uint32_t i, const tb_ray *r, tb_hit *h)
{
    (void)i;
    const tb_scene *s = ctx;
    return tb_object_intersect(s->objects[p->object], r, h);
}

static bool tb__cpu_occl(void *ctx, const tb_accel_prim *p, uint32_t i, const tb_ray *r)
{
    (void)i;
    const tb_scene *s = ctx;
    return tb_object_occluded(s->objects[p->object], r);
}

/* The CPU path's normal of triangle `tri` (host/render/scene_mesh.c). */
static tb_vec3 tb__tri_normal(const tb_object *o, tb_vec3 v0, tb_vec3 v1, tb_vec3 v2)
{
    tb_dvec3 e1 = {(double)v1.x - v0.x, (double)v1.y - v0.y, (double)v1.z - v0.z};
    tb_dvec3 e2 = {(double)v2.x - v0.x, (double)v2.y - v0.y, (double)v2.z - v0.z};
    tb_dvec3 n = tb_dvec3_cross(e1, e2);
    if (n.x == 0.0 && n.y == 0.0 && n.z == 0.0)
        n.z = 1.0;
    tb_dvec3 nw = tb_transform_dnormal(&o->to_world, n);
    double len = tb_dvec3_length(nw);
    tb_vec3 ng = {0.0f, 0.0f, 1.0f};
    if (len > 0.0 && isfinite(len)) {
        double sc = (o->flip ? -1.0 : 1.0) / len;
        ng = (tb_vec3){(float)(nw.x * sc), (float)(nw.y * sc), (float)(nw.z * sc)};
    }
    return ng;
}

static tb_vec3 tb__world(const tb_object *o, tb_vec3 v)
{
    tb_dvec3 p = tb_mat4_mul_point(&o->to_world.m, (tb_dvec3){v.x, v.y, v.z});
    return (tb_vec3){(float)p.x, (float)p.y, (float)p.z};
}

/* Writes triangle `tri` of polygons object o as the kernel reads it (world
 * space, the CPU's normal), with the hit record's object and reference index. */
static void tb__write_tri(const tb_object *o, uint32_t object, uint32_t ref, uint32_t tri, tb_gpu_tri *q)
{
    const tb_object_mesh *m = o->mesh;
    const uint32_t *tv = &m->tris[3 * (size_t)tri];
    tb_vec3 a = m->vertices[tv[0]], b = m->vertices[tv[1]], c = m->vertices[tv[2]];
    q->v0 = tb__world(o, a);
    q->v1 = tb__world(o, b);
    q->v2 = tb__world(o, c);
    q->object = object;
    q->face = o->face_base + m->tri_face[tri];
    q->ref = ref;
    q->ng = tb__tri_normal(o, a, b, c);
    q->pad0 = 0;
}

/* The references tb__build_gpu encodes: triangles, and every primitive kind
 * as a whole placed object; a bit joins the kernel's mask with its encoding here. */
_Static_assert(TB_GPU_INTERSECT_FEATURES ==
                   (uint32_t)(TB_OBJ_FEAT_TRIANGLES | TB_OBJ_FEAT_SPHERE | TB_OBJ_FEAT_CUBE | TB_OBJ_FEAT_CYLINDER |
                              TB_OBJ_FEAT_CONE | TB_OBJ_FEAT_CONIC | TB_OBJ_FEAT_PYRAMID | TB_OBJ_FEAT_PRISM |
                              TB_OBJ_FEAT_TORUS | TB_OBJ_FEAT_SQUARE_ARCH | TB_OBJ_FEAT_ROUND_ARCH |
                              TB_OBJ_FEAT_CSG_UNION | TB_OBJ_FEAT_CSG_INTERSECTION | TB_OBJ_FEAT_CSG_DIFFERENCE),
               "tb__build_gpu encodes exactly the kinds of TB_GPU_INTERSECT_FEATURES");

/* The leaf reference kind (TB_GPU_REF_*) of a placed primitive. */
static uint32_t tb__ref_kind(tb_prim_kind k)
{
    switch (k) {
    case TB_PRIM_CUBE: return TB_GPU_REF_CUBE;
    case TB_PRIM_SPHERE: return TB_GPU_REF_SPHERE;
    case TB_PRIM_CYLINDER:
    case TB_PRIM_CONE:
    case TB_PRIM_CONIC: return TB_GPU_REF_REVOLVED;
    case TB_PRIM_TORUS: return TB_GPU_REF_TORUS;
    case TB_PRIM_POLYGONS: return TB_GPU_REF_MESH; /* a CSG leaf (top-level ones are triangle references) */
    case TB_PRIM_UNION:
    case TB_PRIM_INTERSECTION:
    case TB_PRIM_DIFFERENCE: return TB_GPU_REF_CSG;
    default: return TB_GPU_REF_PLANAR; /* pyramid, prism, arches */
    }
}

/* Placed objects written so far, by kind (CSG leaves count as their kind). */
typedef struct tb__kind_counts {
    uint32_t spheres, cubes, quadrics, planar, tori, csg;
} tb__kind_counts;

/* Where tb__write_placed writes: placed records gs[*ns..], and a CSG
 * polygons leaf's triangles gt[*nt..]; the counts of top-level kinds. */
typedef struct tb__writer {
    tb_gpu_placed *gs;
    tb_gpu_tri *gt;
    uint32_t ns, nt;
    tb__kind_counts cnt;
} tb__writer;

/* Profile vertices of a prism as the kernel tests it: the used profile, or
 * the regular polygon's (tb__prism_vertex) for a large regular prism. */
static int tb__prism_nv(const tb_object *o)
{
    return o->nprofile > 0 ? o->nprofile : o->geom.prism.sides;
}

/* Ops of the post-order program of CSG tree o (a leaf is one). */
static uint32_t tb__csg_ops(const tb_object *o)
{
    uint32_t n = 1;
    for (int i = 0; tb_prim_is_csg(o->kind) && i < o->nchildren; ++i)
        n += tb__csg_ops(&o->children[i]);
    return n;
}

static size_t tb__placed_records(const tb_object *o);

/* Triangles of the polygons leaves of CSG tree o (0 for a primitive). */
static size_t tb__mesh_leaf_tris(const tb_object *o)
{
    if (!tb_prim_is_csg(o->kind))
        return o->kind == TB_PRIM_POLYGONS && o->parent && o->mesh ? o->mesh->ntris : 0;
    size_t n = 0;
    for (int i = 0; i < o->nchildren; ++i)
        n += tb__mesh_leaf_tris(&o->children[i]);
    return n;
}

/* Placed records of the leaves of CSG node o. */
static size_t tb__leaf_records(const tb_object *o)
{
    size_t n = 0;
    for (int i = 0; i < o->nchildren; ++i)
        n += tb_prim_is_csg(o->children[i].kind) ? tb__leaf_records(&o->children[i])
                                                 : tb__placed_records(&o->children[i]);
    return n;
}

/* Placed records of object o (shared/bvh.h). */
static size_t tb__placed_records(const tb_object *o)
{
    switch (tb__ref_kind(o->kind)) {
    case TB_GPU_REF_PLANAR: return 2 + (o->kind == TB_PRIM_PRISM ? ((size_t)tb__prism_nv(o) + 7) / 8 : 0);
    case TB_GPU_REF_MESH: return 1;
    case TB_GPU_REF_CSG: return 1 + (tb__csg_ops(o) + 15) / 16 + tb__leaf_records(o);
    default: return 2;
    }
}

/* The most crossings of a line with primitive o (a closed CSG leaf): one
 * interval for a convex solid, two for a revolved quadric (a cone's two
 * nappes), a torus or an arch, one per profile edge for a non-convex
 * prism; 0 for a kind the kernel has no CSG leaf of (polygons). */
static int tb__leaf_xings(const tb_object *o)
{
    switch (o->kind) {
    case TB_PRIM_SPHERE:
    case TB_PRIM_CUBE:
    case TB_PRIM_PYRAMID: return 2;
    case TB_PRIM_PRISM: return o->nprofile > 0 && !o->profile_convex ? tb__prism_nv(o) / 2 * 2 : 2;
    case TB_PRIM_CYLINDER:
    case TB_PRIM_CONE:
    case TB_PRIM_CONIC:
    case TB_PRIM_TORUS:
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH: return 4;
    case TB_PRIM_POLYGONS: return o->mesh ? (int)o->mesh->ntris : 0; /* every triangle crossed, before the winding */
    default: return 0;
    }
}

/* The kernel's storage for CSG tree o, as lib/csg.glsl evaluates it: walks
 * the program, with *pool the crossings and *lists the lists pending, and
 * their peaks; returns the most crossings of o's list, or -1 (with a message
 * naming the limit) if o has a leaf or node the kernel cannot take. */
static int tb__csg_plan(const tb_object *o, int *pool, int *lists, int *pool_peak, int *lists_peak)
{
    int out = 0;
    if (!tb_prim_is_csg(o->kind)) {
        if (!(out = tb__leaf_xings(o))) {
            tb_error(TB_ERR_ARG, "a %s leaf (the kernel's CSG leaves are the analytic primitives)",
                     tb_prim_kind_name(o->kind));
            return -1;
        }
    } else {
        if (o->nchildren > (int)TB_GPU_CSG_CHILDREN) {
            tb_error(TB_ERR_ARG, "a node of %d children (at most %u)", o->nchildren, TB_GPU_CSG_CHILDREN);
            return -1;
        }
        for (int i = 0; i < o->nchildren; ++i) {
            int c = tb__csg_plan(&o->children[i], pool, lists, pool_peak, lists_peak);
            if (c < 0)
                return -1;
            out += c;
        }
        /* the merge replaces the children's lists by one of at most their sum */
        *pool -= out;
        *lists -= o->nchildren;
    }
    *pool += out;
    *lists += 1;
    *pool_peak = *pool > *pool_peak ? *pool : *pool_peak;
    *lists_peak = *lists > *lists_peak ? *lists : *lists_peak;
    return out;
}

/* Checks that the kernel can evaluate CSG tree o within its per-ray bounds
 * (TB_GPU_CSG_POOL crossings, TB_GPU_CSG_LISTS lists); else an error naming
 * the object. */
static tb_status tb__csg_check(const tb_object *o)
{
    int pool = 0, lists = 0, pool_peak = 0, lists_peak = 0;
    const char *name = o->name ? o->name : "";
    if (tb__csg_plan(o, &pool, &lists, &pool_peak, &lists_peak) < 0) {
        char why[128];
        snprintf(why, sizeof why, "%s", tb_last_error());
        return tb_error(TB_ERR_ARG, "object %u (\"%s\"): CSG tree beyond the Vulkan intersect kernel: %s", o->index,
                        name, why);
    }
    if (pool_peak > (int)TB_GPU_CSG_POOL || lists_peak > (int)TB_GPU_CSG_LISTS)
        return tb_error(TB_ERR_ARG,
                        "object %u (\"%s\"): CSG tree beyond the Vulkan intersect kernel: up to %d crossings in %d "
                        "pending lists per ray, the kernel holds %u in %u (docs/gpu.md, \"CSG\"); use --backend cpu",
                        o->index, name, pool_peak, lists_peak, TB_GPU_CSG_POOL, TB_GPU_CSG_LISTS);
    return TB_OK;
}

static uint32_t tb__write_placed(const tb_object *o, uint32_t object, uint32_t ref, tb__writer *wr);

/* Writes CSG tree o's post-order program to prog[*at..] and its leaves'
 * records (tb__write_placed). */
static void tb__csg_program(const tb_object *o, uint32_t object, uint32_t ref, tb__writer *wr, uint32_t *prog,
                            uint32_t *at)
{
    if (!tb_prim_is_csg(o->kind)) {
        prog[(*at)++] = tb__write_placed(o, object, ref, wr);
        return;
    }
    for (int i = 0; i < o->nchildren; ++i)
        tb__csg_program(&o->children[i], object, ref, wr, prog, at);
    uint32_t op = o->kind == TB_PRIM_UNION          ? TB_GPU_CSG_UNION
                  : o->kind == TB_PRIM_INTERSECTION ? TB_GPU_CSG_INTERSECTION
                                                    : TB_GPU_CSG_DIFFERENCE;
    prog[(*at)++] = op << 8 | (uint32_t)o->nchildren;
}

/* Writes the shape record of planar object o (and a prism's vertex records)
 * to e[0..); returns how many. */
static size_t tb__planar_records(const tb_object *o, tb_gpu_placed *e)
{
    float f[16] = {0};
    uint32_t sub = 0, flags = 0, nv = 0;
    if (o->kind == TB_PRIM_PYRAMID) {
        sub = TB_GPU_PLANAR_PYRAMID;
        f[1] = (float)o->geom.pyramid.top;
        flags = o->geom.pyramid.caps ? TB_GPU_PLANAR_CAPS : 0u;
    } else if (o->kind == TB_PRIM_PRISM) {
        sub = TB_GPU_PLANAR_PRISM;
        nv = (uint32_t)tb__prism_nv(o);
        flags = (o->geom.prism.caps ? TB_GPU_PLANAR_CAPS : 0u) |
                (o->nprofile == 0 || o->profile_convex ? TB_GPU_PLANAR_CONVEX : 0u);
        f[4] = o->nprofile > 0 ? (float)o->profile_orient : 1.0f;
    } else {
        sub = o->kind == TB_PRIM_ROUND_ARCH ? TB_GPU_PLANAR_ROUND_ARCH : TB_GPU_PLANAR_SQUARE_ARCH;
        f[1] = (float)o->geom.arch.width;
        f[2] = (float)o->geom.arch.height;
    }
    memcpy(&f[0], &sub, sizeof sub);
    memcpy(&f[3], &flags, sizeof flags);
    memcpy(&f[5], &nv, sizeof nv);
    _Static_assert(sizeof(tb_gpu_placed) == sizeof f, "a placed record is 16 floats");
    memcpy(&e[0], f, sizeof f);
    for (uint32_t k = 0; k < nv; ++k) {
        double x, y;
        if (o->nprofile > 0) {
            x = o->profile[2 * k];
            y = o->profile[2 * k + 1];
        } else {
            tb__prism_vertex((int)nv, (int)k, &x, &y);
        }
        float v[2] = {(float)x, (float)y};
        memcpy((float *)(void *)&e[1 + k / 8] + 2 * (k % 8), v, sizeof v);
    }
    return 1 + (nv + 7) / 8;
}

/* Placed objects written so far, by kind (CSG leaves count as their kind). */

/* Writes the placed records of primitive or CSG tree o at gs[*ns..] (object
 * index `object` and reference index `ref` in the hit record: a CSG leaf
 * carries its root's) and returns its leaf reference (TB_GPU_REF_* | index). */
static uint32_t tb__write_placed(const tb_object *o, uint32_t object, uint32_t ref, tb__writer *wr)
{
    tb_gpu_placed *gs = wr->gs;
    uint32_t *ns = &wr->ns;
    tb__kind_counts *cnt = &wr->cnt;
    const uint32_t qi = *ns;
    if (o->kind == TB_PRIM_POLYGONS) { /* a CSG leaf: its triangles, tested all (lib/csg.glsl) */
        const tb_object_mesh *m = o->mesh;
        uint32_t first = wr->nt;
        for (uint32_t i = 0; i < m->ntris; ++i)
            tb__write_tri(o, object, ref, i, &wr->gt[wr->nt++]);
        memcpy(&gs[qi].r0.x, &first, sizeof first);
        memcpy(&gs[qi].r0.y, &m->ntris, sizeof m->ntris);
        gs[qi].object = object;
        gs[qi].face = o->face_base;
        gs[qi].ref = ref;
        gs[qi].sign = o->flip ? -1.0f : 1.0f;
        (*ns)++;
        return TB_GPU_REF_MESH | qi;
    }
    if (tb_prim_is_csg(o->kind)) {
        /* The header, the program's records, then the leaves' records: the
         * program is written after the leaves, whose indices it holds. */
        uint32_t nops = tb__csg_ops(o);
        uint32_t *prog = calloc(nops, sizeof *prog);
        if (!prog)
            return UINT32_MAX;
        *ns += 1 + (nops + 15) / 16;
        uint32_t at = 0;
        tb__kind_counts top = *cnt; /* the counts are of top-level objects */
        tb__csg_program(o, object, ref, wr, prog, &at);
        *cnt = top;
        tb_gpu_placed *h = &gs[qi];
        memcpy(&h->r0.x, &nops, sizeof nops);
        h->object = object;
        h->face = o->face_base;
        h->ref = ref;
        h->sign = 1.0f;
        for (uint32_t i = 0; i < nops; ++i)
            memcpy((uint32_t *)(void *)&gs[qi + 1 + i / 16] + i % 16, &prog[i], sizeof prog[i]);
        free(prog);
        cnt->csg++;
        return TB_GPU_REF_CSG | qi;
    }
    /* The map applied to (p - c), c the object's origin in world space
     * rounded to float: for an origin near the object the subtraction is
     * exact and no large translation cancels, so far from the world origin
     * the object-space ray keeps its digits. */
    const tb_mat4 *w = &o->to_world.inv;
    const tb_mat4 *m = &o->to_world.m;
    tb_gpu_placed *q = &gs[qi];
    float c[3] = {(float)m->m[0][3], (float)m->m[1][3], (float)m->m[2][3]};
    float wc[3];
    for (int i = 0; i < 3; ++i)
        wc[i] = (float)(w->m[i][0] * c[0] + w->m[i][1] * c[1] + w->m[i][2] * c[2] + w->m[i][3]);
    q->r0 = (tb_vec3){(float)w->m[0][0], (float)w->m[0][1], (float)w->m[0][2]};
    q->r1 = (tb_vec3){(float)w->m[1][0], (float)w->m[1][1], (float)w->m[1][2]};
    q->r2 = (tb_vec3){(float)w->m[2][0], (float)w->m[2][1], (float)w->m[2][2]};
    q->w0 = wc[0];
    q->w1 = wc[1];
    q->w2 = wc[2];
    q->object = object;
    q->face = o->face_base; /* every kind's first face is 0 */
    q->ref = ref;
    q->sign = o->flip ? -1.0f : 1.0f;
    uint32_t kind = tb__ref_kind(o->kind);
    (*ns)++;
    if (kind == TB_GPU_REF_REVOLVED) { /* the shape record (shared/bvh.h), closed ends as C decides them */
        const double *cc = o->conic;
        double z0 = o->zrange[0], z1 = o->zrange[1];
        bool caps = o->kind == TB_PRIM_CYLINDER ? o->geom.cylinder.caps
                    : o->kind == TB_PRIM_CONE   ? o->geom.cone.caps
                                                : o->geom.conic.caps;
        double sz0 = fabs(cc[0]) + fabs(cc[1] * z0) + fabs(cc[2] * z0 * z0);
        double sz1 = fabs(cc[0]) + fabs(cc[1] * z1) + fabs(cc[2] * z1 * z1);
        uint32_t flags = (caps ? TB_GPU_REVOLVED_CAPS : 0u) |
                         (cc[0] + cc[1] * z0 + cc[2] * z0 * z0 <= 1e-12 * sz0 ? TB_GPU_REVOLVED_CLOSED0 : 0u) |
                         (cc[0] + cc[1] * z1 + cc[2] * z1 * z1 <= 1e-12 * sz1 ? TB_GPU_REVOLVED_CLOSED1 : 0u);
        tb_gpu_placed *e = &gs[(*ns)++];
        e->r0 = (tb_vec3){(float)cc[0], (float)cc[1], (float)cc[2]};
        e->w0 = (float)z0;
        float f1;
        memcpy(&f1, &flags, sizeof f1);
        e->r1 = (tb_vec3){(float)z1, f1, 0.0f};
        cnt->quadrics++;
    } else if (kind == TB_GPU_REF_TORUS) {
        gs[(*ns)++].r0 = (tb_vec3){(float)o->geom.torus.major, (float)o->geom.torus.minor, 0.0f};
        cnt->tori++;
    } else if (kind == TB_GPU_REF_PLANAR) {
        *ns += (uint32_t)tb__planar_records(o, &gs[*ns]);
        cnt->planar++;
    } else {
        (*ns)++; /* a sphere's or cube's second record holds only the centre */
        cnt->cubes += kind == TB_GPU_REF_CUBE;
        cnt->spheres += kind == TB_GPU_REF_SPHERE;
    }
    gs[qi + 1].r2 = (tb_vec3){c[0], c[1], c[2]};
    return kind | qi;
}

/* Builds the GPU arrays: a BVH over the triangle references and the triangles in leaf order. */
static tb_status tb__build_gpu(tb_gpu_scene *g, const tb_accel_prim *refs, const uint32_t *scene_ref, size_t n)
{
    const tb_scene *s = g->scene;
    tb_accel *acc = NULL;
    tb_accel_callbacks cb = {tb__never, NULL, NULL, NULL};
    tb_accel_options ao = {.bvh_keep_binary = 1}; /* converted below */
    tb_status st = tb_accel_build(TB_ACCEL_BVH, refs, n, &cb, &ao, &acc);
    if (st)
        return st;
    size_t nn = 0, nr = 0;
    tb_accel_stats ast;
    tb_accel_get_stats(acc, &ast);
    /* At most one entry per level is on the stack: depth entries suffice. */
    g->stack = ((uint32_t)(ast.bvh_depth > 0 ? ast.bvh_depth : 1) + 7u) / 8u * 8u;
    const tb_bvh_node *nodes = tb_accel_bvh_nodes(acc, &nn);
    const uint32_t *order = tb_accel_bvh_refs(acc, &nr);
    /* GPU node i: the child records 2i, 2i + 1 of the CPU's inner node number i
     * (shared/bvh.h); a lone leaf root gets one node of its own. */
    size_t ni = 0;
    uint32_t *inner = calloc(nn ? nn : 1, sizeof *inner);
    for (size_t i = 0; inner && i < nn; ++i)
        inner[i] = nodes[i].count == 0 ? (uint32_t)ni++ : UINT32_MAX;
    size_t ngn = ni ? ni : 1;
    tb_gpu_bvh_node *gn = calloc(2 * ngn, sizeof *gn);
    size_t ntri = 0; /* triangle references, and the triangles of CSG trees' polygons leaves */
    for (size_t k = 0; k < nr; ++k) {
        const tb_accel_prim *p = &refs[order[k]];
        ntri += p->sub == TB_SCENE_WHOLE_OBJECT ? tb__mesh_leaf_tris(s->objects[p->object]) : 1;
    }
    tb_gpu_tri *gt = calloc(ntri ? ntri : 1, sizeof *gt);
    size_t nplaced = 0; /* placed records (shared/bvh.h): one to two per object, more for a prism's profile */
    for (size_t k = 0; k < nr; ++k)
        if (refs[order[k]].sub == TB_SCENE_WHOLE_OBJECT)
            nplaced += tb__placed_records(s->objects[refs[order[k]].object]);
    tb_gpu_placed *gs = calloc(nplaced ? nplaced : 1, sizeof *gs);
    uint32_t *gr = calloc(nr ? nr : 1, sizeof *gr);
    if (!inner || !gn || !gt || !gs || !gr) {
        free(inner), free(gn), free(gt), free(gs), free(gr), tb_accel_free(acc);
        return tb_error(TB_ERR_NOMEM, "out of memory for the GPU scene");
    }
    /* The record of CPU node c as a child of a node split along `axis`. */
#define TB__CHILD(rec, c, axis)                                                                               \
    do {                                                                                                      \
        (rec)->lo = (c)->bounds.lo;                                                                           \
        (rec)->hi = (c)->bounds.hi;                                                                           \
        (rec)->offset = (c)->count ? (c)->offset : inner[(c) - nodes];                                        \
        (rec)->count = (uint32_t)(c)->count | (uint32_t)(axis) << 16;                                         \
    } while (0)
    if (nn > 0 && ni == 0) { /* the root is a leaf: it and an empty box */
        TB__CHILD(&gn[0], &nodes[0], 0u);
        gn[1] = (tb_gpu_bvh_node){{1.0f, 1.0f, 1.0f}, 0u, {-1.0f, -1.0f, -1.0f}, 1u};
    }
    for (size_t i = 0; i < nn; ++i) {
        const tb_bvh_node *c = &nodes[i];
        if (c->count != 0)
            continue;
        TB__CHILD(&gn[2 * (size_t)inner[i]], &nodes[i + 1], c->axis);
        TB__CHILD(&gn[2 * (size_t)inner[i] + 1], &nodes[c->offset], c->axis);
    }
#undef TB__CHILD
    free(inner);
    /* triangles, placed records, cubes, revolved objects, planar objects, tori */
    tb__writer wr = {gs, gt, 0, 0, {0}};
    for (size_t k = 0; k < nr; ++k) { /* triangles first: a CSG tree's mesh leaves go after them */
        const tb_accel_prim *p = &refs[order[k]];
        if (p->sub != TB_SCENE_WHOLE_OBJECT) {
            tb__write_tri(s->objects[p->object], s->objects[p->object]->index, scene_ref[order[k]], p->sub, &gt[wr.nt]);
            gr[k] = wr.nt++;
        }
    }
    for (size_t k = 0; k < nr; ++k) { /* a placed analytic object or a CSG tree */
        const tb_accel_prim *p = &refs[order[k]];
        const tb_object *o = s->objects[p->object];
        if (p->sub == TB_SCENE_WHOLE_OBJECT)
            gr[k] = tb__write_placed(o, o->index, scene_ref[order[k]], &wr);
    }
    const uint32_t nt = wr.nt, ns = wr.ns;
    const tb__kind_counts cnt = wr.cnt;
    /* Each leaf lists its references by kind (stable): triangles, cubes,
     * spheres, planar objects, revolved objects, tori (the kind bits'
     * order), so the kernel tests each kind in a loop of its own
     * (lib/bvh_traverse.glsl). */
    for (size_t i = 0; i < nn; ++i) {
        const tb_bvh_node *c = &nodes[i];
        if (c->count < 2)
            continue;
        uint32_t tmp[64], *buf = c->count <= 64 ? tmp : malloc(c->count * sizeof *buf);
        if (!buf) {
            free(gn), free(gt), free(gs), free(gr), tb_accel_free(acc);
            return tb_error(TB_ERR_NOMEM, "out of memory for the GPU scene");
        }
        uint32_t m = 0;
        for (uint32_t kind = 0; kind < 8; ++kind)
            for (uint32_t j = 0; j < c->count; ++j)
                if (gr[c->offset + j] >> 29 == kind)
                    buf[m++] = gr[c->offset + j];
        memcpy(&gr[c->offset], buf, c->count * sizeof *buf);
        if (buf != tmp)
            free(buf);
    }
    g->nnodes = nn ? (uint32_t)ngn : 0u;
    g->ntris = nt;
    g->nspheres = cnt.spheres;
    g->ncubes = cnt.cubes;
    g->nquadrics = cnt.quadrics;
    g->nplanar = cnt.planar;
    g->ntori = cnt.tori;
    g->ncsg = cnt.csg;
    g->info.gpu_nodes = nn ? ngn : 0;
    g->info.gpu_bytes = 2 * ngn * sizeof *gn + nt * sizeof *gt + ns * sizeof *gs + nr * sizeof *gr;
    g->nodes = tb_gpu_buffer_create(g->dev, 2 * ngn * sizeof *gn);
    g->tris = g->nodes ? tb_gpu_buffer_create(g->dev, (nt ? nt : 1) * sizeof *gt) : NULL;
    g->placed = g->tris ? tb_gpu_buffer_create(g->dev, (ns ? ns : 1) * sizeof *gs) : NULL;
    g->refs = g->placed ? tb_gpu_buffer_create(g->dev, (nr ? nr : 1) * sizeof *gr) : NULL;
    st = !g->refs ? TB_ERR_DEVICE : TB_OK;
    if (!st && nn)
        st = tb_gpu_buffer_upload(g->nodes, 0, gn, 2 * ngn * sizeof *gn);
    if (!st && nt)
        st = tb_gpu_buffer_upload(g->tris, 0, gt, nt * sizeof *gt);
    if (!st && ns)
        st = tb_gpu_buffer_upload(g->placed, 0, gs, ns * sizeof *gs);
    if (!st && nr)
        st = tb_gpu_buffer_upload(g->refs, 0, gr, nr * sizeof *gr);
    free(gn), free(gt), free(gs), free(gr), tb_accel_free(acc);
    return st;
}

tb_gpu_scene *tb_gpu_scene_create(tb_gpu_device *dev, const tb_scene *scene)
{
    return tb_gpu_scene_create_ex(dev, scene, NULL);
}

uint32_t tb_gpu_intersect_supported(const tb_gpu_device *dev, tb_gpu_quadrics quadrics)
{
    /* Every device runs every kind in the kernel (the same code on lavapipe
     * and on a GPU); TB_GPU_QUADRICS_CPU routes quadrics for comparisons. */
    (void)dev;
    return quadrics == TB_GPU_QUADRICS_CPU ? TB_GPU_INTERSECT_FEATURES & ~TB_GPU_QUADRIC_FEATURES
                                           : TB_GPU_INTERSECT_FEATURES;
}

const char *tb_gpu_object_route_reason(uint32_t features, uint32_t supported)
{
    uint32_t f = tb_feature_first(features & ~supported);
    /* the kernel's own words where a feature's name alone does not say why */
    switch (f) {
    case 0:
        return NULL;
    case TB_OBJ_FEAT_CYLINDER:
        return "cylinder (quadrics on the CPU path: TB_GPU_QUADRICS_CPU)";
    case TB_OBJ_FEAT_CONE:
        return "cone (quadrics on the CPU path: TB_GPU_QUADRICS_CPU)";
    case TB_OBJ_FEAT_CONIC:
        return "conic (quadrics on the CPU path: TB_GPU_QUADRICS_CPU)";
    default:
        return tb_object_feature_name(f);
    }
}

tb_gpu_scene *tb_gpu_scene_create_ex(tb_gpu_device *dev, const tb_scene *scene, const tb_gpu_scene_desc *desc)
{
    if (!dev || !scene) {
        tb_error(TB_ERR_ARG, "tb_gpu_scene_create: NULL device or scene");
        return NULL;
    }
    tb_gpu_scene *g = calloc(1, sizeof *g);
    uint32_t *features = calloc(scene->nobjects ? scene->nobjects : 1, sizeof *features);
    bool *on_gpu = calloc(scene->nobjects ? scene->nobjects : 1, sizeof *on_gpu);
    tb_accel_prim *gref = calloc(scene->nprims ? scene->nprims : 1, sizeof *gref);
    tb_accel_prim *cref = calloc(scene->nprims ? scene->nprims : 1, sizeof *cref);
    uint32_t *gidx = calloc(scene->nprims ? scene->nprims : 1, sizeof *gidx);
    if (!g || !features || !on_gpu || !gref || !cref || !gidx) {
        free(g), free(features), free(on_gpu), free(gref), free(cref), free(gidx);
        tb_error(TB_ERR_NOMEM, "out of memory for the GPU scene");
        return NULL;
    }
    g->dev = dev;
    g->scene = scene;
    g->features = features;
    g->on_gpu = on_gpu;
    /* Routing by data: an object goes to the kernel iff every feature of it is
     * one the kernel implements here; its references follow it (triangles of a
     * mesh, or the whole object: tb__build_gpu encodes those the mask admits). */
    g->supported = tb_gpu_intersect_supported(dev, desc ? desc->quadrics : TB_GPU_QUADRICS_AUTO);
    tb_object_features(scene, features);
    for (uint32_t i = 0; i < scene->nobjects; ++i) {
        on_gpu[i] = !(features[i] & ~g->supported);
        /* A CSG tree beyond the kernel's per-ray bounds is refused, not routed. */
        if (on_gpu[i] && tb_prim_is_csg(scene->objects[i]->kind) && tb__csg_check(scene->objects[i])) {
            free(gref), free(cref), free(gidx);
            tb_gpu_scene_destroy(g);
            return NULL;
        }
        if (on_gpu[i])
            g->info.gpu_objects++;
        else
            g->info.cpu_objects++;
    }
    /* The scene's references (made again: the scene drops its array once its structure is built). */
    tb_accel_prim *refs;
    if (tb_scene_refs(scene, &refs)) {
        free(gref), free(cref), free(gidx);
        tb_gpu_scene_destroy(g);
        return NULL;
    }
    size_t ng = 0, nc = 0;
    for (size_t i = 0; i < scene->nprims; ++i) {
        const tb_accel_prim *p = &refs[i];
        if (on_gpu[p->object]) {
            gidx[ng] = (uint32_t)i;
            gref[ng++] = *p;
        } else {
            cref[nc++] = *p;
        }
    }
    free(refs);
    tb_status st = tb__build_gpu(g, gref, gidx, ng);
    g->info.gpu_triangles = g->ntris;
    g->info.gpu_spheres = g->nspheres;
    g->info.gpu_cubes = g->ncubes;
    g->info.gpu_quadrics = g->nquadrics;
    g->info.gpu_planar = g->nplanar;
    g->info.gpu_tori = g->ntori;
    g->info.gpu_csg = g->ncsg;
    if (!st && nc) {
        tb_accel_callbacks cb = {tb__cpu_isect, tb__cpu_occl, (void *)scene, NULL};
        st = tb_accel_build(TB_ACCEL_BVH, cref, nc, &cb, NULL, &g->cpu_accel);
    }
    if (!st) {
        g->rays = tb_gpu_buffer_create(dev, TB__GPU_CHUNK * sizeof(tb_gpu_ray));
        g->hits = g->rays ? tb_gpu_buffer_create(dev, TB__GPU_CHUNK * sizeof(tb_gpu_hit)) : NULL;
        if (!g->hits)
            st = TB_ERR_DEVICE;
    }
    free(gref), free(cref), free(gidx);
    if (st) {
        tb_gpu_scene_destroy(g);
        return NULL;
    }
    return g;
}

void tb_gpu_scene_destroy(tb_gpu_scene *g)
{
    if (!g)
        return;
    tb_gpu_buffer_destroy(g->nodes);
    tb_gpu_buffer_destroy(g->tris);
    tb_gpu_buffer_destroy(g->placed);
    tb_gpu_buffer_destroy(g->refs);
    tb_gpu_buffer_destroy(g->rays);
    tb_gpu_buffer_destroy(g->hits);
    tb_accel_free(g->cpu_accel);
    free(g->on_gpu);
    free(g->features);
    free(g);
}

void tb_gpu_scene_get_info(const tb_gpu_scene *g, tb_gpu_scene_info *out) { *out = g->info; }

void tb_gpu_scene_get_bindings(const tb_gpu_scene *g, tb_gpu_scene_bindings *out)
{
    *out = (tb_gpu_scene_bindings){g->nodes,          g->tris,          g->placed,        g->refs,
                                   g->nnodes,         g->stack,         g->ntris > 0,     g->nspheres > 0,
                                   g->ncubes > 0,     g->nquadrics > 0, g->nplanar > 0,   g->ntori > 0,
                                   g->ncsg > 0};
}

bool tb_gpu_scene_object_on_gpu(const tb_gpu_scene *g, uint32_t object)
{
    return object < g->scene->nobjects && g->on_gpu[object];
}

const char *tb_gpu_scene_object_route(const tb_gpu_scene *g, uint32_t object)
{
    return object < g->scene->nobjects ? tb_gpu_object_route_reason(g->features[object], g->supported) : NULL;
}

/* Runs the kernel over rays[0..n) (any_hit 0 or 1) into hits. */
static tb_status tb__run(tb_gpu_scene *g, const tb_ray *rays, size_t n, uint32_t any_hit, tb_hit *hits,
                         double *kernel_seconds)
{
    if (g->ntris == 0 && g->nspheres == 0 && g->ncubes == 0 && g->nquadrics == 0 && g->nplanar == 0 &&
        g->ntori == 0 && g->ncsg == 0) {
        for (size_t i = 0; i < n; ++i)
            hits[i] = (tb_hit){INFINITY, TB_GPU_NO_HIT, TB_GPU_NO_HIT, 0.0f, 0.0f, {0.0f, 0.0f, 0.0f}};
        return TB_OK;
    }
    /* Only the kinds the scene has are compiled in. */
    tb_gpu_spec_constant spec[8] = {{1, g->ntris > 0},  {2, g->stack},         {3, g->nspheres > 0},
                                    {4, g->ncubes > 0}, {5, g->nquadrics > 0}, {6, g->nplanar > 0},
                                    {7, g->ntori > 0},  {8, g->ncsg > 0}};
    tb_gpu_kernel *k = tb_gpu_kernel_get(g->dev, &(tb_gpu_kernel_desc){.spirv = tb_gpu_builtin("intersect"),
                                                                        .buffers = 6,
                                                                        .kinds = {0, TB_GPU_BIND_TEXELS_RGBA32UI,
                                                                                  TB_GPU_BIND_TEXELS_RGBA32UI, 0, 0,
                                                                                  TB_GPU_BIND_TEXELS_R32UI},
                                                                        .push_size = 16,
                                                                        .spec = spec,
                                                                        .spec_count = 8});
    if (!k)
        return TB_ERR_DEVICE;
    for (size_t at = 0; at < n; at += TB__GPU_CHUNK) {
        size_t m = n - at < TB__GPU_CHUNK ? n - at : TB__GPU_CHUNK;
        tb_status st = tb_gpu_buffer_upload(g->rays, 0, rays + at, m * sizeof(tb_ray));
        if (st)
            return st;
        uint32_t push[4] = {(uint32_t)m, any_hit, g->nnodes, 0};
        tb_gpu_dispatch d = {k, {g->rays, g->nodes, g->tris, g->hits, g->placed, g->refs}, push, m, 0.0};
        if ((st = tb_gpu_run(g->dev, &d, 1)))
            return st;
        *kernel_seconds += d.seconds;
        if ((st = tb_gpu_buffer_download(g->hits, 0, hits + at, m * sizeof(tb_hit))))
            return st;
    }
    tb_stat_add(&tb__n_gpu_rays, (int64_t)n);
    return TB_OK;
}

_Static_assert(sizeof(tb_hit) == sizeof(tb_gpu_hit), "GPU hits download into tb_hit");

/* The primitive of object o that owns face ID `face` (o itself unless a CSG tree). */
static const tb_object *tb__face_leaf(const tb_object *o, uint32_t face)
{
    while (tb_prim_is_csg(o->kind)) {
        const tb_object *next = NULL;
        for (int i = 0; i < o->nchildren && !next; ++i)
            if (face >= o->children[i].face_base && face - o->children[i].face_base < o->children[i].nfaces)
                next = &o->children[i];
        if (!next)
            break;
        o = next;
    }
    return o;
}

/* Relative t within which a routed object's hit (double, rounded once) and a
 * GPU triangle's hit (float) count as a tie. The float t of a triangle is off
 * by a few ulps, so without it coincident surfaces (a box standing on a
 * floor) would be decided by those ulps instead of by the tie rule. 2^-18
 * (64 ulps) covers the float triangle test's error on the bundled scenes. */
#define TB__TIE_TOL 3.814697265625e-6 /* 2^-18, as TB_TIE_TOL in shaders/intersect.comp */

/* True if routed hit a (CPU) precedes GPU hit b: smaller t beyond the tie
 * tolerance, else the tie rule (object, face); routed and GPU objects never
 * share an object, so the reference key is not needed. */
static bool tb__precedes(const tb_hit *a, const tb_hit *b)
{
    double tol = TB__TIE_TOL * fabs((double)b->t);
    if (fabs((double)a->t - b->t) > tol)
        return a->t < b->t;
    if (a->object != b->object)
        return a->object < b->object;
    return a->face < b->face;
}

tb_status tb_gpu_intersect(tb_gpu_scene *g, const tb_ray *rays, size_t n, tb_hit *hits,
                           tb_gpu_intersect_timing *timing)
{
    int64_t t0 = tb_stats_now_ns();
    double ks = 0.0;
    tb_status st = tb__run(g, rays, n, 0u, hits, &ks);
    if (st)
        return st;
    int64_t t1 = tb_stats_now_ns();
    const tb_scene *s = g->scene;
    int64_t routed = 0;
#pragma omp parallel for schedule(dynamic, 256) reduction(+ : routed)
    for (size_t i = 0; i < n; ++i) {
        tb_hit *h = &hits[i];
        bool gpu_hit = h->object != TB_GPU_NO_HIT;
        if (g->cpu_accel && tb_ray_is_valid(&rays[i])) {
            tb_ray r = rays[i];
            if (gpu_hit) /* up to the tie tolerance beyond the GPU hit, within the ray's range */
                r.tmax = fminf(r.tmax, (float)((double)h->t + TB__TIE_TOL * fabs((double)h->t)));
            tb_hit c;
            ++routed;
            if (tb_accel_intersect(g->cpu_accel, &r, &c) && (!gpu_hit || tb__precedes(&c, h))) {
                *h = c;
                continue;
            }
        }
        if (gpu_hit) {
            /* (u, v) of the winning face, as the CPU path computes them from the point (of a CSG tree's leaf). */
            const tb_object *o = tb__face_leaf(s->objects[h->object], h->face);
            tb_dvec3 ro = tb_mat4_mul_point(&o->to_world.inv, (tb_dvec3){rays[i].o.x, rays[i].o.y, rays[i].o.z});
            tb_dvec3 rd = tb_mat4_mul_vec(&o->to_world.inv, (tb_dvec3){rays[i].d.x, rays[i].d.y, rays[i].d.z});
            double t = h->t;
            tb_dvec3 p = {ro.x + t * rd.x, ro.y + t * rd.y, ro.z + t * rd.z};
            int face = (int)(h->face - o->face_base), pf = face;
            double u = 0.0, v = 0.0;
            if (tb_param_from_point(o->kind, &o->geom, p, face, &pf, &u, &v) != TB_OK)
                u = v = 0.0;
            h->u = (float)u;
            h->v = (float)v;
        }
    }
    tb_stat_add(&tb__n_gpu_routed_tests, routed);
    if (timing) {
        timing->kernel_seconds = ks;
        timing->gpu_seconds = (double)(t1 - t0) * 1e-9;
        timing->cpu_seconds = (double)(tb_stats_now_ns() - t1) * 1e-9;
    }
    return TB_OK;
}

tb_status tb_gpu_occluded(tb_gpu_scene *g, const tb_ray *rays, size_t n, uint8_t *occluded,
                          tb_gpu_intersect_timing *timing)
{
    tb_hit *hits = malloc((n ? n : 1) * sizeof *hits);
    if (!hits)
        return tb_error(TB_ERR_NOMEM, "out of memory for %zu hits", n);
    int64_t t0 = tb_stats_now_ns();
    double ks = 0.0;
    tb_status st = tb__run(g, rays, n, 1u, hits, &ks);
    if (st) {
        free(hits);
        return st;
    }
    int64_t t1 = tb_stats_now_ns();
#pragma omp parallel for schedule(dynamic, 256)
    for (size_t i = 0; i < n; ++i) {
        bool o = hits[i].object != TB_GPU_NO_HIT;
        if (!o && g->cpu_accel)
            o = tb_accel_occluded(g->cpu_accel, &rays[i]);
        occluded[i] = o ? 1 : 0;
    }
    free(hits);
    if (timing) {
        timing->kernel_seconds = ks;
        timing->gpu_seconds = (double)(t1 - t0) * 1e-9;
        timing->cpu_seconds = (double)(tb_stats_now_ns() - t1) * 1e-9;
    }
    return TB_OK;
}
