/* The Vulkan form-factor kernel's host side (formfactor.h; docs/gpu.md,
 * "Form-factor kernel"). */
#include "host/gpu/formfactor.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "host/render/accel.h"
#include "shaders/shared/bvh.h"
#include "shaders/shared/formfactor.h"
#include "util/stats/stats.h"

TB_STAT_COUNTER(tb__n_gpu_ff, "GPU formfactor/form factors");
TB_STAT_COUNTER(tb__n_gpu_ff_segments, "GPU formfactor/sample-receiver pairs");

struct tb_gpu_ff_scene {
    tb_gpu_device *dev;
    tb_gpu_buffer *nodes, *tris, *refs; /* the occluders (1-record placeholders when there are none) */
    tb_gpu_buffer *placed;              /* the traversal's analytic objects: none, a 1-record placeholder */
    tb_gpu_buffer *recv, *result;       /* one chunk of receivers and form factors */
    tb_gpu_buffer *samples, *vis;       /* grown on demand */
    size_t samples_cap, vis_cap;        /* their sizes in records / words */
    uint32_t nnodes, ntris, stack;
    tb_gpu_ff_receiver *recv_host;      /* one chunk, packed on the host */
    float *ff_host;
    uint32_t *zeros;                    /* vis_cap zero words: the visibility bits' initial value */
};

/* Most invocations per receiver (shaders/formfactor.comp, TB_FF_LANES) when
 * the device does not say its subgroup size. */
#define TB__FF_DEFAULT_LANES 8u

/* tb_accel_build wants an intersect callback; this BVH is converted for the
 * kernel and never traversed on the host. */
static bool tb__ff_no_intersect(void *ctx, const tb_accel_prim *prim, uint32_t index, const tb_ray *ray, tb_hit *hit)
{
    (void)ctx;
    (void)prim;
    (void)index;
    (void)ray;
    (void)hit;
    return false;
}

/* CPU node c as the child record of a node split along `axis` (shared/bvh.h):
 * a leaf keeps its first reference and count, an inner node gets its pair number. */
static tb_gpu_bvh_node tb__child(const tb_bvh_node *nodes, size_t c, const uint32_t *pair, uint32_t axis)
{
    const tb_bvh_node *n = &nodes[c];
    return (tb_gpu_bvh_node){n->bounds.lo, n->count ? n->offset : pair[c], n->bounds.hi,
                             (uint32_t)n->count | axis << 16};
}

/* Triangles of the occluders and a BVH over them, uploaded in leaf order. */
static tb_status tb__upload_occluders(tb_gpu_ff_scene *g, const tb_ff_polygon *polys, size_t n)
{
    size_t nt = 0;
    for (size_t i = 0; i < n; ++i) {
        if (polys[i].n != 3 && polys[i].n != 4)
            return tb_error(TB_ERR_ARG, "occluder %zu has %d corners (3 or 4 expected)", i, polys[i].n);
        nt += (size_t)polys[i].n - 2;
    }
    if (nt >= UINT32_MAX / 2)
        return tb_error(TB_ERR_ARG, "too many occluder triangles (%zu)", nt);
    tb_gpu_tri *tri = calloc(nt ? nt : 1, sizeof *tri);
    tb_accel_prim *prims = calloc(nt ? nt : 1, sizeof *prims);
    if (!tri || !prims) {
        free(tri), free(prims);
        return tb_error(TB_ERR_NOMEM, "out of memory for %zu occluder triangles", nt);
    }
    size_t k = 0;
    for (size_t i = 0; i < n; ++i) {
        const tb_ff_polygon *q = &polys[i];
        for (int j = 1; j + 1 < q->n; ++j, ++k) {
            tri[k] = (tb_gpu_tri){.v0 = q->v[0], .object = (uint32_t)i, .v1 = q->v[j], .v2 = q->v[j + 1], .ref = (uint32_t)k};
            tb_vec3 a = q->v[0], b = q->v[j], c = q->v[j + 1];
            if (!isfinite(a.x + a.y + a.z + b.x + b.y + b.z + c.x + c.y + c.z)) {
                free(tri), free(prims);
                return tb_error(TB_ERR_ARG, "occluder %zu has a non-finite corner", i);
            }
            tb_aabb box = tb_aabb_union_point(tb_aabb_from_points(a, b), c);
            prims[k] = (tb_accel_prim){box, (uint32_t)i, (uint32_t)j - 1u};
        }
    }
    tb_gpu_bvh_node *gn = NULL;
    tb_gpu_tri *gt = NULL;
    uint32_t *pair = NULL, npairs = 0;
    uint32_t *gr = NULL;
    size_t nn = 0, nr = 0;
    tb_accel *acc = NULL;
    tb_status st = TB_OK;
    if (nt) {
        tb_accel_callbacks cb = {tb__ff_no_intersect, NULL, NULL, NULL};
        tb_accel_options ao = {.bvh_keep_binary = 1}; /* converted below */
        st = tb_accel_build(TB_ACCEL_BVH, prims, nt, &cb, &ao, &acc);
    }
    if (!st && acc) {
        tb_accel_stats ast;
        tb_accel_get_stats(acc, &ast);
        /* One stack entry per level suffices. */
        g->stack = ((uint32_t)(ast.bvh_depth > 0 ? ast.bvh_depth : 1) + 7u) / 8u * 8u;
        const tb_bvh_node *nodes = tb_accel_bvh_nodes(acc, &nn);
        const uint32_t *order = tb_accel_bvh_refs(acc, &nr);
        /* The child-pair layout of shared/bvh.h: the k-th inner node of the
         * CPU's depth-first order becomes records 2k and 2k + 1, its two
         * children; a root that is a leaf pairs with an empty box. */
        pair = calloc(nn ? nn : 1, sizeof *pair);
        for (size_t i = 0; pair && i < nn; ++i)
            pair[i] = nodes[i].count ? UINT32_MAX : npairs++;
        if (nn && !npairs)
            npairs = 1;
        gn = calloc(2 * (npairs ? npairs : 1), sizeof *gn);
        gt = calloc(nr ? nr : 1, sizeof *gt);
        gr = calloc(nr ? nr : 1, sizeof *gr);
        if (!pair || !gn || !gt || !gr) {
            st = tb_error(TB_ERR_NOMEM, "out of memory for the occluder BVH");
        } else {
            if (nn && nodes[0].count) { /* a lone leaf: it, and a box no segment meets */
                gn[0] = tb__child(nodes, 0, pair, 0);
                gn[1] = (tb_gpu_bvh_node){{1.0f, 1.0f, 1.0f}, 0u, {-1.0f, -1.0f, -1.0f}, 1u};
            }
            for (size_t i = 0; i < nn; ++i)
                if (!nodes[i].count) {
                    gn[2 * (size_t)pair[i]] = tb__child(nodes, i + 1, pair, nodes[i].axis);
                    gn[2 * (size_t)pair[i] + 1] = tb__child(nodes, nodes[i].offset, pair, nodes[i].axis);
                }
            for (size_t i = 0; i < nr; ++i) { /* triangles in leaf order: reference i is triangle i */
                gt[i] = tri[order[i]];
                gr[i] = (uint32_t)i;
            }
        }
    }
    free(tri), free(prims), free(pair);
    g->nnodes = npairs;
    g->ntris = (uint32_t)nr;
    if (!st) {
        g->nodes = tb_gpu_buffer_create(g->dev, 2 * (npairs ? npairs : 1) * sizeof(tb_gpu_bvh_node));
        g->tris = g->nodes ? tb_gpu_buffer_create(g->dev, (nr ? nr : 1) * sizeof(tb_gpu_tri)) : NULL;
        g->refs = g->tris ? tb_gpu_buffer_create(g->dev, (nr ? nr : 1) * sizeof(uint32_t)) : NULL;
        g->placed = g->refs ? tb_gpu_buffer_create(g->dev, sizeof(tb_gpu_placed)) : NULL;
        if (!g->placed)
            st = TB_ERR_DEVICE;
    }
    if (!st && npairs)
        st = tb_gpu_buffer_upload(g->nodes, 0, gn, 2 * (size_t)npairs * sizeof *gn);
    if (!st && nr)
        st = tb_gpu_buffer_upload(g->tris, 0, gt, nr * sizeof *gt);
    if (!st && nr)
        st = tb_gpu_buffer_upload(g->refs, 0, gr, nr * sizeof *gr);
    free(gn), free(gt), free(gr), tb_accel_free(acc);
    return st;
}

tb_gpu_ff_scene *tb_gpu_ff_scene_create(tb_gpu_device *dev, const tb_ff_polygon *occluders, size_t n)
{
    if (!dev || (n && !occluders)) {
        tb_error(TB_ERR_ARG, "tb_gpu_ff_scene_create: NULL device or occluders");
        return NULL;
    }
    tb_gpu_ff_scene *g = calloc(1, sizeof *g);
    if (!g) {
        tb_error(TB_ERR_NOMEM, "out of memory for the form-factor scene");
        return NULL;
    }
    g->dev = dev;
    g->stack = 8;
    tb_status st = tb__upload_occluders(g, occluders, n);
    if (!st) {
        g->recv_host = malloc(TB_GPU_FF_CHUNK * sizeof *g->recv_host);
        g->ff_host = malloc(TB_GPU_FF_CHUNK * sizeof *g->ff_host);
        if (!g->recv_host || !g->ff_host)
            st = tb_error(TB_ERR_NOMEM, "out of memory for the form-factor scene");
    }
    if (!st) {
        g->recv = tb_gpu_buffer_create(dev, TB_GPU_FF_CHUNK * sizeof(tb_gpu_ff_receiver));
        g->result = g->recv ? tb_gpu_buffer_create(dev, TB_GPU_FF_CHUNK * sizeof(float)) : NULL;
        g->vis = g->result ? tb_gpu_buffer_create(dev, sizeof(uint32_t)) : NULL;
        g->vis_cap = 1;
        if (!g->vis)
            st = TB_ERR_DEVICE;
    }
    if (st) {
        tb_gpu_ff_scene_destroy(g);
        return NULL;
    }
    return g;
}

void tb_gpu_ff_scene_destroy(tb_gpu_ff_scene *g)
{
    if (!g)
        return;
    tb_gpu_buffer_destroy(g->nodes);
    tb_gpu_buffer_destroy(g->tris);
    tb_gpu_buffer_destroy(g->refs);
    tb_gpu_buffer_destroy(g->placed);
    tb_gpu_buffer_destroy(g->recv);
    tb_gpu_buffer_destroy(g->result);
    tb_gpu_buffer_destroy(g->samples);
    tb_gpu_buffer_destroy(g->vis);
    free(g->recv_host);
    free(g->zeros);
    free(g->ff_host);
    free(g);
}

size_t tb_gpu_ff_scene_triangles(const tb_gpu_ff_scene *g) { return g ? g->ntris : 0; }

/* Makes *buf hold at least `need` records of `size` bytes (its contents are not kept). */
static tb_status tb__reserve(tb_gpu_device *dev, tb_gpu_buffer **buf, size_t *cap, size_t need, size_t size)
{
    if (*buf && *cap >= need)
        return TB_OK;
    tb_gpu_buffer_destroy(*buf);
    *cap = 0;
    *buf = tb_gpu_buffer_create(dev, need * size);
    if (!*buf)
        return TB_ERR_DEVICE;
    *cap = need;
    return TB_OK;
}

tb_status tb_gpu_ff_raycast(tb_gpu_ff_scene *g, const tb_vec3 *pts, int npts, tb_vec3 ns, double area,
                            const tb_vec3 *p, const tb_vec3 *n, size_t count, double *ff, uint32_t *visible,
                            tb_gpu_ff_timing *timing)
{
    int64_t t0 = tb_stats_now_ns();
    if (timing)
        *timing = (tb_gpu_ff_timing){0.0, 0.0, 0};
    if (!g)
        return tb_error(TB_ERR_ARG, "tb_gpu_ff_raycast: NULL scene");
    if (npts < 0 || (npts > 0 && !pts))
        return tb_error(TB_ERR_ARG, "tb_gpu_ff_raycast: %d sample points%s", npts, npts < 0 ? "" : " but NULL");
    if (!(area >= 0.0) || !isfinite(area))
        return tb_error(TB_ERR_ARG, "tb_gpu_ff_raycast: shooter area %g is not a finite number >= 0", area);
    if (count == 0)
        return TB_OK;
    if (!p || !n || !ff)
        return tb_error(TB_ERR_ARG, "tb_gpu_ff_raycast: NULL receivers or results");
    if (npts == 0 || area == 0.0) { /* no samples or no area: nothing is exchanged (as tb_ff_raycast) */
        memset(ff, 0, count * sizeof *ff);
        if (visible)
            memset(visible, 0, count * (((size_t)npts + 31) / 32) * sizeof *visible);
        return TB_OK;
    }
    uint32_t words = visible ? ((uint32_t)npts + 31u) / 32u : 0u;
    tb_status st = tb__reserve(g->dev, &g->samples, &g->samples_cap, (size_t)npts, sizeof(tb_gpu_ff_sample));
    if (!st && visible && g->vis_cap < TB_GPU_FF_CHUNK * words) {
        st = tb__reserve(g->dev, &g->vis, &g->vis_cap, TB_GPU_FF_CHUNK * words, sizeof(uint32_t));
        free(g->zeros);
        g->zeros = st ? NULL : calloc(TB_GPU_FF_CHUNK * words, sizeof *g->zeros);
        if (!st && !g->zeros)
            st = tb_error(TB_ERR_NOMEM, "out of memory for visibility bits");
    }
    if (st)
        return st;
    tb_gpu_ff_sample *smp = malloc((size_t)npts * sizeof *smp);
    if (!smp)
        return tb_error(TB_ERR_NOMEM, "out of memory for %d sample points", npts);
    for (int k = 0; k < npts; ++k)
        smp[k] = (tb_gpu_ff_sample){pts[k], 0u};
    st = tb_gpu_buffer_upload(g->samples, 0, smp, (size_t)npts * sizeof *smp);
    free(smp);
    if (st)
        return st;
    bool occl = g->nnodes > 0;
    /* Lanes per receiver: the samples' count rounded up to a power of two, at
     * most one subgroup (one SIMD group traces one receiver's segments) and
     * 16. On lavapipe (subgroups of 8) 8 lanes ran 13 % faster per CPU second
     * than 16, and 2 or 16 slowest (docs/gpu.md). */
    uint32_t sg = tb_gpu_device_info_of(g->dev)->subgroup_size, max_lanes = TB__FF_DEFAULT_LANES;
    if (sg >= 1 && (sg & (sg - 1)) == 0)
        max_lanes = sg < 16 ? sg : 16;
    uint32_t lanes = 1;
    while (lanes < (uint32_t)npts && lanes < max_lanes)
        lanes *= 2;
    /* The device's default width in whole receivers (lanes divide it: both
     * are powers of two or the width is a multiple of the subgroup); one
     * float of shared memory per invocation, far below Vulkan's 16 KiB minimum. */
    uint32_t wg = tb_gpu_default_workgroup(tb_gpu_device_info_of(g->dev));
    wg = wg >= lanes ? wg / lanes * lanes : lanes;
    tb_gpu_spec_constant spec[4] = {{1, g->stack}, {2, occl}, {3, visible != NULL}, {4, lanes}};
    tb_gpu_kernel *k = tb_gpu_kernel_get(g->dev, &(tb_gpu_kernel_desc){.spirv = tb_gpu_builtin("formfactor"),
                                                                        .buffers = 8,
                                                                        .kinds = {0, 0, TB_GPU_BIND_TEXELS_RGBA32UI,
                                                                                  TB_GPU_BIND_TEXELS_RGBA32UI, 0,
                                                                                  TB_GPU_BIND_TEXELS_R32UI, 0, 0},
                                                                        .push_size = sizeof(tb_gpu_ff_push),
                                                                        .spec = spec,
                                                                        .workgroup_size = wg,
                                                                        .spec_count = 4});
    if (!k)
        return TB_ERR_DEVICE;
    double da = area / npts, ks = 0.0;
    int nd = 0;
    for (size_t at = 0; at < count; at += TB_GPU_FF_CHUNK) {
        size_t m = count - at < TB_GPU_FF_CHUNK ? count - at : TB_GPU_FF_CHUNK;
        for (size_t i = 0; i < m; ++i)
            g->recv_host[i] = (tb_gpu_ff_receiver){p[at + i], 0u, n[at + i], 0u};
        if ((st = tb_gpu_buffer_upload(g->recv, 0, g->recv_host, m * sizeof *g->recv_host)))
            return st;
        tb_gpu_ff_push push = {ns, (float)da, (uint32_t)m, (uint32_t)npts, g->nnodes, words};
        if (visible && (st = tb_gpu_buffer_upload(g->vis, 0, g->zeros, m * words * sizeof(uint32_t))))
            return st; /* the kernel ORs the bits in */
        tb_gpu_dispatch d = {k,    {g->recv, g->samples, g->nodes, g->tris, g->placed, g->refs, g->result, g->vis},
                             &push, m * lanes, 0.0};
        if ((st = tb_gpu_run(g->dev, &d, 1)))
            return st;
        ks += d.seconds;
        ++nd;
        if ((st = tb_gpu_buffer_download(g->result, 0, g->ff_host, m * sizeof *g->ff_host)))
            return st;
        for (size_t i = 0; i < m; ++i)
            ff[at + i] = g->ff_host[i];
        if (visible && (st = tb_gpu_buffer_download(g->vis, 0, visible + at * words, m * words * sizeof(uint32_t))))
            return st;
    }
    tb_stat_add(&tb__n_gpu_ff, (int64_t)count);
    tb_stat_add(&tb__n_gpu_ff_segments, (int64_t)count * npts);
    if (timing) {
        timing->kernel_seconds = ks;
        timing->dispatches = nd;
        timing->seconds = (double)(tb_stats_now_ns() - t0) * 1e-9;
    }
    return TB_OK;
}

tb_status tb_gpu_ff_batch(void *ctx, const tb_vec3 *pts, int npts, tb_vec3 ns, double area, const tb_vec3 *p,
                          const tb_vec3 *n, size_t count, double *ff)
{
    return tb_gpu_ff_raycast(ctx, pts, npts, ns, area, p, n, count, ff, NULL, NULL);
}
