/* Scene -> radiosity elements and receivers (ff_elements.h). */
#include "ff_elements.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "host/object/object.h"
#include "host/object/polygonize.h"
#include "util/math/mat.h"
#include "util/container/array.h"
#include "util/math/rng.h"
#include "util/mesh/mesh.h"

void tb_ffe_free(tb_ffe_set *e)
{
    free(e->polys), free(e->normal), free(e->area), free(e->object), free(e->rp), free(e->rn);
    memset(e, 0, sizeof *e);
}

/* Reallocates array P to N elements; on failure P keeps its old block and
 * OK becomes false (so every array can be tried and freed later). */
#define TB__RESIZE(P, N, OK)                                  \
    do {                                                      \
        void *tb__q = realloc((P), (N) * sizeof *(P));        \
        if (tb__q)                                            \
            (P) = tb__q;                                      \
        else                                                  \
            (OK) = false;                                     \
    } while (0)

/* The capacity (256, doubled) that holds `need` when `cap` does not. */
static size_t tb__cap_for(size_t cap, size_t need)
{
    size_t c = cap ? 2 * cap : 256;
    while (c < need)
        c *= 2;
    return c;
}

/* Grows the arrays to hold `need` elements / receivers. */
static bool tb__grow(tb_ffe_set *e, size_t need, size_t *cap, size_t need_r, size_t *cap_r)
{
    if (need > *cap) {
        size_t c = tb__cap_for(*cap, need);
        bool ok = true;
        TB__RESIZE(e->polys, c, ok);
        TB__RESIZE(e->normal, c, ok);
        TB__RESIZE(e->area, c, ok);
        TB__RESIZE(e->object, c, ok);
        if (!ok)
            return false;
        *cap = c;
    }
    if (need_r > *cap_r) {
        size_t c = tb__cap_for(*cap_r, need_r);
        bool ok = true;
        TB__RESIZE(e->rp, c, ok);
        TB__RESIZE(e->rn, c, ok);
        if (!ok)
            return false;
        *cap_r = c;
    }
    return true;
}

/* The faces of an inline polygons object in world space; TB_ERR_UNSUPPORTED
 * for a FED file (or anything tb_fed_build refuses). */
static tb_status tb__polygons_fed(const tb_object *o, tb_fed **out)
{
    const tb_geom_polygons *g = &o->geom.polygons;
    if (g->mesh.text || g->nvertices <= 0 || g->nfaces <= 0 || !g->vertices || !g->face_start || !g->indices)
        return TB_ERR_UNSUPPORTED;
    tb_vec3 *pos = malloc((size_t)g->nvertices * sizeof *pos);
    uint32_t *sizes = malloc((size_t)g->nfaces * sizeof *sizes);
    uint32_t *corners = malloc((size_t)g->face_start[g->nfaces] * sizeof *corners + 1);
    tb_status st = TB_ERR_NOMEM;
    if (pos && sizes && corners) {
        for (int v = 0; v < g->nvertices; ++v) {
            tb_vec3 q = g->vertices[v];
            tb_dvec3 w = tb_mat4_mul_point(&o->to_world.m, (tb_dvec3){q.x, q.y, q.z});
            pos[v] = (tb_vec3){(float)w.x, (float)w.y, (float)w.z};
        }
        for (int f = 0; f < g->nfaces; ++f)
            sizes[f] = (uint32_t)(g->face_start[f + 1] - g->face_start[f]);
        for (int k = 0; k < g->face_start[g->nfaces]; ++k)
            corners[k] = (uint32_t)g->indices[k];
        tb_fed_desc d = {.nverts = (uint32_t)g->nvertices,
                         .positions = pos,
                         .nfaces = (uint32_t)g->nfaces,
                         .nloops = (uint32_t)g->nfaces,
                         .loop_sizes = sizes,
                         .corners = corners};
        st = tb_fed_build(&d, out, NULL) == TB_OK ? TB_OK : TB_ERR_UNSUPPORTED;
    }
    free(pos), free(sizes), free(corners);
    return st;
}

tb_status tb_ffe_build(const tb_scene *s, double max_edge, tb_ffe_set *out)
{
    memset(out, 0, sizeof *out);
    if (!(max_edge > 0.0) || !isfinite(max_edge))
        return tb_error(TB_ERR_ARG, "element edge %g must be a positive number", max_edge);
    size_t cap = 0, cap_r = 0;
    /* Corners go after the centroids: gather them apart first. */
    tb_array cp, cn;
    tb_array_init(&cp, sizeof(tb_vec3));
    tb_array_init(&cn, sizeof(tb_vec3));
    tb_status st = TB_OK;
    for (uint32_t oi = 0; oi < s->nobjects && !st; ++oi) {
        /* Inline polygons as their own faces (quads stay quads, so the meshing
         * grids them instead of refining triangles), mapped to world space;
         * every other object through tb_polygonize_object. */
        const tb_object *o = s->objects[oi];
        tb_fed *fed = NULL;
        if (o->kind != TB_PRIM_POLYGONS || tb__polygons_fed(o, &fed) != TB_OK) {
            if (tb_polygonize_object(o, NULL, max_edge, &fed) != TB_OK) {
                out->skipped++;
                continue;
            }
        }
        tb_mesh m;
        tb_mesh_init(&m);
        /* Quads within 1 % of planar are gridded like planar ones (the Cornell
         * box's red wall is 3.2 mm off over 556 mm): splitting it would give
         * two triangles with unequal edge cuts, refined into thousands. */
        tb_mesh_opts mo = {.max_edge = max_edge, .quads = true, .planar_tol = 1e-2};
        if (tb_mesh_from_fed(fed, &mo, &m) != TB_OK) {
            out->skipped++;
            tb_fed_free(fed);
            tb_mesh_free(&m);
            continue;
        }
        size_t nv = m.positions.len, ne = tb_mesh_nelems(&m);
        bool *seen = calloc(nv ? nv : 1, sizeof *seen);
        if (!seen || !tb__grow(out, out->n + ne, &cap, out->n + ne, &cap_r)) {
            free(seen);
            tb_fed_free(fed);
            tb_mesh_free(&m);
            st = tb_error(TB_ERR_NOMEM, "out of memory for the elements");
            break;
        }
        for (size_t i = 0; i < ne; ++i) {
            const tb_mesh_elem *me = tb_mesh_elem_at(&m, i);
            tb_ff_polygon q = {.n = tb_mesh_elem_size(me)};
            double cx = 0.0, cy = 0.0, cz = 0.0;
            for (int k = 0; k < q.n; ++k) {
                q.v[k] = TB_ARRAY_AT(&m.positions, tb_vec3, me->v[k]);
                cx += q.v[k].x, cy += q.v[k].y, cz += q.v[k].z;
            }
            tb_vec3 nrm;
            double area;
            tb_ff_polygon_frame(&q, &nrm, &area);
            if (!(area > 0.0) || !isfinite(area) || !isfinite(nrm.x + nrm.y + nrm.z))
                continue; /* a degenerate element receives and shoots nothing */
            size_t j = out->n++;
            out->polys[j] = q;
            out->normal[j] = nrm;
            out->area[j] = area;
            out->object[j] = oi;
            /* The vertex mean: inside a convex element, which is what a receiver needs. */
            out->rp[out->nrecv] = (tb_vec3){(float)(cx / q.n), (float)(cy / q.n), (float)(cz / q.n)};
            out->rn[out->nrecv++] = nrm;
            for (int k = 0; k < q.n; ++k) {
                if (seen[me->v[k]])
                    continue;
                seen[me->v[k]] = true;
                if (tb_array_push(&cp, &q.v[k]) || tb_array_push(&cn, &nrm)) {
                    st = tb_error(TB_ERR_NOMEM, "out of memory for the receivers");
                    break;
                }
            }
        }
        free(seen);
        tb_fed_free(fed);
        tb_mesh_free(&m);
    }
    if (!st && !tb__grow(out, out->n, &cap, out->nrecv + cp.len, &cap_r))
        st = tb_error(TB_ERR_NOMEM, "out of memory for the receivers");
    if (!st && cp.len) {
        memcpy(out->rp + out->nrecv, cp.data, cp.len * sizeof(tb_vec3));
        memcpy(out->rn + out->nrecv, cn.data, cn.len * sizeof(tb_vec3));
        out->nrecv += cp.len;
    }
    tb_array_free(&cp);
    tb_array_free(&cn);
    if (st)
        tb_ffe_free(out);
    return st;
}

void tb_ffe_subsample(tb_ffe_set *e, size_t max, uint64_t seed)
{
    if (e->nrecv <= max)
        return;
    uint32_t *idx = malloc(e->nrecv * sizeof *idx);
    if (!idx) { /* keep the first max: still a valid (if less spread) set */
        e->nrecv = max;
        return;
    }
    for (size_t i = 0; i < e->nrecv; ++i)
        idx[i] = (uint32_t)i;
    tb_rng rng;
    tb_rng_seed(&rng, seed, 13);
    for (size_t i = 0; i < max; ++i) { /* a partial Fisher-Yates shuffle */
        size_t j = i + (size_t)(tb_rng_double(&rng) * (double)(e->nrecv - i));
        if (j >= e->nrecv)
            j = e->nrecv - 1;
        uint32_t t = idx[i];
        idx[i] = idx[j];
        idx[j] = t;
    }
    /* Back in the original order (neighbouring receivers stay neighbours in a workgroup). */
    bool *keep = calloc(e->nrecv, sizeof *keep);
    if (keep) {
        for (size_t i = 0; i < max; ++i)
            keep[idx[i]] = true;
        size_t m = 0;
        for (size_t i = 0; i < e->nrecv; ++i)
            if (keep[i]) {
                e->rp[m] = e->rp[i];
                e->rn[m++] = e->rn[i];
            }
    }
    e->nrecv = max;
    free(keep);
    free(idx);
}

size_t tb_ffe_shooters(const tb_ffe_set *e, const tb_scene *s, size_t count, uint64_t seed, uint32_t *out)
{
    if (count > e->n)
        count = e->n;
    bool *used = calloc(e->n ? e->n : 1, sizeof *used);
    if (!used)
        return 0;
    tb_rng rng;
    tb_rng_seed(&rng, seed, 11);
    size_t m = 0;
    /* Emitting elements first (at most half), drawn from their own list. */
    uint32_t *em = malloc((e->n ? e->n : 1) * sizeof *em);
    if (!em) {
        free(used);
        return 0;
    }
    size_t nem = 0;
    for (size_t i = 0; i < e->n; ++i)
        for (int k = 0; k < s->nemissive; ++k)
            if (s->emissive[k].object == e->object[i]) {
                em[nem++] = (uint32_t)i;
                break;
            }
    size_t want = nem < (count + 1) / 2 ? nem : (count + 1) / 2;
    while (m < want) {
        size_t j = m + (size_t)(tb_rng_double(&rng) * (double)(nem - m));
        if (j >= nem)
            j = nem - 1;
        uint32_t t = em[m]; /* a partial Fisher-Yates shuffle */
        em[m] = em[j];
        em[j] = t;
        used[em[m]] = true;
        out[m] = em[m];
        ++m;
    }
    free(em);
    while (m < count) {
        size_t i = (size_t)(tb_rng_double(&rng) * (double)e->n);
        if (i >= e->n || used[i])
            continue;
        used[i] = true;
        out[m++] = (uint32_t)i;
    }
    free(used);
    return m;
}
