/* The acceleration interface: argument checks, the copy of the references,
 * dispatch to the BVH (bvh.c), the grid (grid.c) or the plain list (here),
 * and the figures every kind reports (docs/accel.md). */
#include "host/render/accel.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "host/render/accel_internal.h"
#include "util/stats/stats.h"

TB_STAT_COUNTER(tb__invalid_rays, "Accel/invalid rays");
TB_STAT_COUNTER(tb__list_rays, "List/rays");
TB_STAT_COUNTER(tb__list_tested, "List/primitives tested");

static const char *const tb__kind_names[] = {"bvh", "grid", "list"};

const char *tb_accel_kind_name(tb_accel_kind kind)
{
    if ((unsigned)kind >= sizeof tb__kind_names / sizeof tb__kind_names[0])
        return NULL;
    return tb__kind_names[kind];
}

tb_status tb_accel_kind_from_name(const char *name, tb_accel_kind *out)
{
    for (unsigned k = 0; name && k < sizeof tb__kind_names / sizeof tb__kind_names[0]; k++) {
        if (strcmp(name, tb__kind_names[k]) == 0) {
            *out = (tb_accel_kind)k;
            return TB_OK;
        }
    }
    return tb_error(TB_ERR_ARG, "unknown acceleration structure '%s' (expected bvh, grid or list)",
                    name ? name : "(null)");
}

/* A box is refused if a corner is NaN, or if it is non-empty with an
 * infinite corner; an empty box (lo > hi on some axis, e.g. tb_aabb_empty()
 * with its infinite corners, or an empty CSG intersection) is dropped. */
static bool tb__box_nan(const tb_aabb *b)
{
    return isnan(b->lo.x) || isnan(b->lo.y) || isnan(b->lo.z) || isnan(b->hi.x) || isnan(b->hi.y) ||
           isnan(b->hi.z);
}

static tb_status tb__check_options(const tb_accel_options *o)
{
    if (o->threads < 0)
        return tb_error(TB_ERR_ARG, "accel: threads must be >= 0 (got %d)", o->threads);
    if (o->bvh_bins != 0 && (o->bvh_bins < 2 || o->bvh_bins > 256))
        return tb_error(TB_ERR_ARG, "accel: bvh_bins must be 2..256 (got %d)", o->bvh_bins);
    if (o->bvh_max_leaf != 0 && (o->bvh_max_leaf < 1 || o->bvh_max_leaf > 255))
        return tb_error(TB_ERR_ARG, "accel: bvh_max_leaf must be 1..255 (got %d)", o->bvh_max_leaf);
    if (!(o->bvh_cost_node >= 0.0f && o->bvh_cost_node < INFINITY))
        return tb_error(TB_ERR_ARG, "accel: bvh_cost_node must be finite and >= 0");
    if (!(o->bvh_cost_prim >= 0.0f && o->bvh_cost_prim < INFINITY))
        return tb_error(TB_ERR_ARG, "accel: bvh_cost_prim must be finite and >= 0");
    if (!(o->grid_density >= 0.0 && o->grid_density <= 1e6))
        return tb_error(TB_ERR_ARG, "accel: grid_density must be 0..1e6");
    if (o->grid_max_res != 0 && (o->grid_max_res < 1 || o->grid_max_res > 1024))
        return tb_error(TB_ERR_ARG, "accel: grid_max_res must be 1..1024 (got %d)", o->grid_max_res);
    return TB_OK;
}

/* Where the build's triangle records come from: the caller's array
 * (cb->tris), else the callback (NULL: none). */
typedef struct tb__tri_src {
    const tb_accel_tri *tris;
    tb_accel_tri_fn fn;
    void *ctx;
} tb__tri_src;

/* The triangle record of input reference i (its reference p): the array's,
 * or one made by the callback into *tmp. */
static const tb_accel_tri *tb__accel_input_tri(const tb__tri_src *ts, const tb_accel_prim *p, uint32_t i,
                                               tb_accel_tri *tmp)
{
    if (ts->tris)
        return &ts->tris[i];
    ts->fn(ts->ctx, p, i, tmp);
    return tmp;
}

static tb_status tb__accel_build(tb_accel_kind kind, const tb_accel_prim *prims, tb_accel_prim **owned, size_t n,
                                 const tb_accel_callbacks *cb, tb__tri_src ts, const tb_accel_options *opt,
                                 tb_accel **out);

tb_status tb_accel_build(tb_accel_kind kind, const tb_accel_prim *prims, size_t n,
                         const tb_accel_callbacks *cb, const tb_accel_options *opt, tb_accel **out)
{
    return tb__accel_build(kind, prims, NULL, n, cb, (tb__tri_src){cb ? cb->tris : NULL, NULL, NULL}, opt, out);
}

tb_status tb_accel_build_owned(tb_accel_kind kind, tb_accel_prim *prims, size_t n, const tb_accel_callbacks *cb,
                               tb_accel_tri_fn tri, void *tri_ctx, const tb_accel_options *opt, tb_accel **out)
{
    tb_accel_prim *own = prims;
    tb__tri_src ts = {cb ? cb->tris : NULL, cb && cb->tris ? NULL : tri, tri_ctx};
    tb_status st = tb__accel_build(kind, prims, &own, n, cb, ts, opt, out);
    free(own); /* NULL once the structure took it */
    return st;
}

/* tb_accel_build; with `owned` (*owned == prims), that array becomes the
 * structure's own and *owned NULL (else the caller still owns it). */
static tb_status tb__accel_build(tb_accel_kind kind, const tb_accel_prim *prims, tb_accel_prim **owned, size_t n,
                                 const tb_accel_callbacks *cb, tb__tri_src ts, const tb_accel_options *opt,
                                 tb_accel **out)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "accel: NULL output");
    *out = NULL;
    if (!tb_accel_kind_name(kind))
        return tb_error(TB_ERR_ARG, "accel: unknown kind %d", (int)kind);
    if (!cb || !cb->intersect)
        return tb_error(TB_ERR_ARG, "accel: an intersect callback is required");
    if (n > 0 && !prims)
        return tb_error(TB_ERR_ARG, "accel: NULL references with n = %zu", n);
    if (n >= UINT32_MAX)
        return tb_error(TB_ERR_ARG, "accel: %zu references (at most %u)", n, UINT32_MAX - 1);
    tb_accel_options o = {0};
    if (opt)
        o = *opt;
    tb_status st = tb__check_options(&o);
    if (st)
        return st;
    size_t nkept = 0;
    for (size_t i = 0; i < n; i++) {
        bool empty = !tb__box_nan(&prims[i].bounds) && tb_aabb_is_empty(&prims[i].bounds);
        if (!empty && !(tb_isfinite3(prims[i].bounds.lo) && tb_isfinite3(prims[i].bounds.hi)))
            return tb_error(TB_ERR_ARG,
                            "accel: reference %zu has a NaN or infinite box corner "
                            "(%g %g %g)..(%g %g %g)",
                            i, (double)prims[i].bounds.lo.x, (double)prims[i].bounds.lo.y,
                            (double)prims[i].bounds.lo.z, (double)prims[i].bounds.hi.x,
                            (double)prims[i].bounds.hi.y, (double)prims[i].bounds.hi.z);
        if (!empty)
            nkept++;
    }

    int64_t t0 = tb_stats_now_ns();
    tb_accel *acc = calloc(1, sizeof *acc);
    if (!acc)
        return tb_error(TB_ERR_NOMEM, "accel: out of memory");
    acc->kind = kind;
    acc->cb = *cb;
    acc->cb.tris = NULL; /* copied below; the caller's array need not outlive the build */
    acc->n = nkept;
    acc->bounds = tb_aabb_empty();
    if (nkept > 0) {
        acc->prims = owned ? NULL : malloc(nkept * sizeof *acc->prims);
        acc->index = malloc(nkept * sizeof *acc->index);
        if ((!owned && !acc->prims) || !acc->index) {
            tb_accel_free(acc);
            return tb_error(TB_ERR_NOMEM, "accel: out of memory for %zu references", nkept);
        }
        tb_accel_prim *dst = owned ? *owned : acc->prims; /* owned: compacted in place (k <= i) */
        size_t k = 0;
        for (size_t i = 0; i < n; i++) {
            if (tb_aabb_is_empty(&prims[i].bounds))
                continue;
            dst[k] = prims[i];
            acc->index[k] = (uint32_t)i;
            acc->bounds = tb_aabb_union(acc->bounds, dst[k].bounds);
            k++;
        }
        if (owned) {
            tb_accel_prim *shrunk = nkept < n ? realloc(*owned, nkept * sizeof *dst) : *owned;
            acc->prims = shrunk ? shrunk : *owned;
            *owned = NULL;
        }
    }
    acc->stats.kind = kind;
    acc->stats.nprims = nkept;
    acc->stats.bounds = acc->bounds;
    acc->stats.memory_bytes = sizeof *acc + nkept * (sizeof *acc->prims + sizeof *acc->index);

    st = TB_OK;
    if (nkept > 0) {
        if (kind == TB_ACCEL_BVH)
            st = tb__bvh_build(acc, &o);
        else if (kind == TB_ACCEL_GRID)
            st = tb__grid_build(acc, &o);
    }
    /* Triangle references in stored order, so a leaf's lie side by side. */
    if (!st && nkept > 0 && (ts.tris || ts.fn)) {
        size_t ntri = 0;
        tb_accel_tri made;
        for (size_t k = 0; k < nkept; k++) {
            const tb_accel_tri *tr = tb__accel_input_tri(&ts, &acc->prims[k], acc->index[k], &made);
            ntri += tr->object != TB_ACCEL_TRI_NONE;
        }
        /* Records for the triangles only; a map from reference to record
         * unless every reference is one. */
        if (ntri > 0) {
            acc->tris = malloc(ntri * sizeof *acc->tris);
            acc->tri_of = ntri < nkept ? malloc(nkept * sizeof *acc->tri_of) : NULL;
            if (!acc->tris || (ntri < nkept && !acc->tri_of))
                st = tb_error(TB_ERR_NOMEM, "accel: out of memory for %zu triangle references", ntri);
            for (size_t k = 0, t = 0; !st && k < nkept; k++) {
                const tb_accel_tri *tr = tb__accel_input_tri(&ts, &acc->prims[k], acc->index[k], &made);
                if (acc->tri_of)
                    acc->tri_of[k] = tr->object != TB_ACCEL_TRI_NONE ? (uint32_t)t : TB_ACCEL_TRI_NONE;
                if (tr->object != TB_ACCEL_TRI_NONE)
                    acc->tris[t++] = *tr;
            }
            acc->stats.memory_bytes += ntri * sizeof *acc->tris + (acc->tri_of ? nkept * sizeof *acc->tri_of : 0);
            acc->stats.tri_bytes += ntri * sizeof *acc->tris;
        }
        if (!st && acc->tris && kind == TB_ACCEL_BVH && !o.bvh_no_pack)
            st = tb__bvhw_pack(acc);
    }
    if (st) {
        tb_accel_free(acc);
        return st;
    }
    acc->stats.build_seconds = (double)(tb_stats_now_ns() - t0) * 1e-9;
    *out = acc;
    return TB_OK;
}

static bool tb__list_intersect(const tb_accel *acc, tb__accel_best *best)
{
    for (size_t k = 0; k < acc->n; k++)
        tb__accel_test(acc, k, best);
    tb_stat_add(&tb__list_tested, (int64_t)acc->n);
    return best->found;
}

static bool tb__list_occluded(const tb_accel *acc, const tb_ray *ray)
{
    tb__accel_any q = tb__accel_any_start(ray);
    for (size_t k = 0; k < acc->n; k++) {
        if (tb__accel_test_any(acc, k, &q)) {
            tb_stat_add(&tb__list_tested, (int64_t)k + 1);
            return true;
        }
    }
    tb_stat_add(&tb__list_tested, (int64_t)acc->n);
    return false;
}

bool tb_accel_intersect(const tb_accel *acc, const tb_ray *ray, tb_hit *hit)
{
    return tb_accel_intersect_tri(acc, ray, hit, NULL);
}

bool tb_accel_intersect_tri(const tb_accel *acc, const tb_ray *ray, tb_hit *hit, tb_accel_tri_hit *tri)
{
    if (tri)
        tri->index = TB_ACCEL_TRI_NONE;
    if (!tb_ray_is_valid(ray)) {
        TB_STAT_INC(tb__invalid_rays);
        return false;
    }
    if (acc->n == 0)
        return false;
    /* Field by field: an initialiser would clear the whole record (a
     * rep stos costing more than a small query's traversal). */
    tb__accel_best best;
    best.ray = *ray;
    best.found = false;
    best.wready = false;
    bool found = false;
    switch (acc->kind) {
    case TB_ACCEL_BVH:
        found = tb__bvh_intersect(acc, ray, &best);
        break;
    case TB_ACCEL_GRID:
        found = tb__grid_intersect(acc, ray, &best);
        break;
    case TB_ACCEL_LIST:
        TB_STAT_INC(tb__list_rays);
        found = tb__list_intersect(acc, &best);
        break;
    }
    if (found) {
        *hit = best.hit;
        if (tri)
            *tri = best.tri;
    }
    return found;
}

bool tb_accel_occluded(const tb_accel *acc, const tb_ray *ray)
{
    if (!tb_ray_is_valid(ray)) {
        TB_STAT_INC(tb__invalid_rays);
        return false;
    }
    if (acc->n == 0)
        return false;
    switch (acc->kind) {
    case TB_ACCEL_BVH:
        return tb__bvh_occluded(acc, ray);
    case TB_ACCEL_GRID:
        return tb__grid_occluded(acc, ray);
    case TB_ACCEL_LIST:
        TB_STAT_INC(tb__list_rays);
        return tb__list_occluded(acc, ray);
    }
    return false;
}

void tb_accel_get_stats(const tb_accel *acc, tb_accel_stats *out) { *out = acc->stats; }

tb_accel_kind tb_accel_get_kind(const tb_accel *acc) { return acc->kind; }

const tb_bvh_node *tb_accel_bvh_nodes(const tb_accel *acc, size_t *count)
{
    if (acc->kind != TB_ACCEL_BVH) {
        if (count)
            *count = 0;
        return NULL;
    }
    if (count)
        *count = acc->nnodes;
    return acc->nodes;
}

const uint32_t *tb_accel_bvh_refs(const tb_accel *acc, size_t *count)
{
    if (acc->kind != TB_ACCEL_BVH) {
        if (count)
            *count = 0;
        return NULL;
    }
    if (count)
        *count = acc->n;
    return acc->index;
}

void tb_accel_free(tb_accel *acc)
{
    if (!acc)
        return;
    tb__bvh_free(acc);
    tb__grid_free(acc);
    free(acc->prims);
    free(acc->index);
    free(acc->tris);
    free(acc->tri_of);
    free(acc);
}
