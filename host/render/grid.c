/* Uniform grid over primitive references (docs/accel.md, "Grid"): automatic
 * resolution after pbrt-v1's GridAccel (3 cbrt(N) voxels along the longest
 * axis), references stored in every voxel their box touches, traversal by
 * 3D-DDA (Amanatides and Woo 1987, "A fast voxel traversal algorithm for ray
 * tracing") in double precision, without mailboxing. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "host/render/accel_internal.h"
#include "util/stats/stats.h"

TB_STAT_COUNTER(tb__grid_rays, "Grid/rays");
TB_STAT_COUNTER(tb__grid_shadow_rays, "Grid/occlusion rays");
TB_STAT_COUNTER(tb__grid_voxels_visited, "Grid/voxels visited");
TB_STAT_COUNTER(tb__grid_prims_tested, "Grid/primitives tested");
TB_STAT_TIMER(tb__grid_build_time, "Grid/build");
TB_STAT_MEMORY(tb__grid_memory, "Grid/memory");

#define TB__GRID_DEFAULT_DENSITY 3.0
#define TB__GRID_DEFAULT_MAX_RES 256
/* Budget: the resolution is halved while the grid would need more than this
 * many voxels, or more (voxel, reference) pairs than
 * TB__GRID_PAIRS_PER_PRIM * N + TB__GRID_PAIRS_PER_CELL * voxels (many
 * references that each span much of the grid), or more than TB__GRID_MAX_PAIRS. */
#define TB__GRID_MAX_CELLS ((size_t)1 << 26)
#define TB__GRID_PAIRS_PER_PRIM 32
#define TB__GRID_PAIRS_PER_CELL 8
#define TB__GRID_MAX_PAIRS ((size_t)1 << 28)
/* A box is inserted into every voxel within this fraction of a voxel of it:
 * covers the rounding of the double-precision voxel arithmetic, so a voxel
 * the DDA visits at a point of the box always lists the box. */
#define TB__GRID_PAD 0x1p-20

/* The voxel index of coordinate s (in voxel units), limited to [0, res). */
static inline int tb__voxel(double s, int res)
{
    if (!(s > 0.0))
        return 0;
    if (s >= (double)res)
        return res - 1;
    return (int)s;
}

/* The voxel ranges [i0, i1] per axis touched by box b (padded by TB__GRID_PAD). */
static void tb__grid_range(const tb__grid *g, const tb_aabb *b, int i0[3], int i1[3])
{
    for (int a = 0; a < 3; a++) {
        double s0 = ((double)tb_vec3_get(b->lo, a) - g->lo[a]) * g->inv_cell[a] - TB__GRID_PAD;
        double s1 = ((double)tb_vec3_get(b->hi, a) - g->lo[a]) * g->inv_cell[a] + TB__GRID_PAD;
        i0[a] = tb__voxel(s0, g->res[a]);
        i1[a] = tb__voxel(s1, g->res[a]);
    }
}

/* Sets the voxel size for resolution res over [g->lo, g->hi]. */
static void tb__grid_set_res(tb__grid *g, const int res[3])
{
    for (int a = 0; a < 3; a++) {
        g->res[a] = res[a];
        double w = g->hi[a] - g->lo[a];
        g->cell[a] = w / res[a];
        g->inv_cell[a] = res[a] / w;
    }
}

/* (voxel, reference) pairs the grid would store. */
static size_t tb__grid_count_pairs(const tb_accel *acc, const tb__grid *g)
{
    size_t pairs = 0;
    for (size_t k = 0; k < acc->n; k++) {
        int i0[3], i1[3];
        tb__grid_range(g, &acc->prims[k].bounds, i0, i1);
        pairs += (size_t)(i1[0] - i0[0] + 1) * (size_t)(i1[1] - i0[1] + 1) * (size_t)(i1[2] - i0[2] + 1);
    }
    return pairs;
}

tb_status tb__grid_build(tb_accel *acc, const tb_accel_options *opt)
{
    tb_timer_token timer = tb_timer_start(&tb__grid_build_time);
    tb__grid *g = &acc->grid;
    size_t n = acc->n;
    double density = opt->grid_density > 0.0 ? opt->grid_density : TB__GRID_DEFAULT_DENSITY;
    int max_res = opt->grid_max_res > 0 ? opt->grid_max_res : TB__GRID_DEFAULT_MAX_RES;

    /* The box to divide: the references' box, with flat axes given some
     * thickness (a voxel of zero width has no inverse), then padded so every
     * reference lies strictly inside. */
    double lo[3] = {acc->bounds.lo.x, acc->bounds.lo.y, acc->bounds.lo.z};
    double hi[3] = {acc->bounds.hi.x, acc->bounds.hi.y, acc->bounds.hi.z};
    double wmax = 0.0;
    for (int a = 0; a < 3; a++)
        wmax = fmax(wmax, hi[a] - lo[a]);
    for (int a = 0; a < 3; a++) {
        double wmin = fmax(wmax * 0x1p-8, (fabs(lo[a]) + fabs(hi[a])) * 0x1p-40);
        if (wmin == 0.0)
            wmin = 1.0;
        double w = hi[a] - lo[a];
        if (w < wmin) {
            lo[a] -= 0.5 * (wmin - w);
            hi[a] += 0.5 * (wmin - w);
        }
        double pad = (hi[a] - lo[a]) * 0x1p-16 + (fabs(lo[a]) + fabs(hi[a])) * 0x1p-40;
        g->lo[a] = lo[a] - pad;
        g->hi[a] = hi[a] + pad;
    }
    wmax = 0.0;
    for (int a = 0; a < 3; a++)
        wmax = fmax(wmax, g->hi[a] - g->lo[a]);

    /* pbrt-v1: density * cbrt(N) voxels along the longest axis, the others in proportion. */
    double per_unit = density * cbrt((double)n) / wmax;
    int res[3];
    for (int a = 0; a < 3; a++) {
        double r = round((g->hi[a] - g->lo[a]) * per_unit);
        res[a] = r < 1.0 ? 1 : (r > max_res ? max_res : (int)r);
    }
    size_t cells, pairs;
    for (;;) {
        tb__grid_set_res(g, res);
        cells = (size_t)res[0] * (size_t)res[1] * (size_t)res[2];
        pairs = tb__grid_count_pairs(acc, g);
        bool over = cells > TB__GRID_MAX_CELLS || pairs > TB__GRID_MAX_PAIRS ||
                    pairs > TB__GRID_PAIRS_PER_PRIM * n + TB__GRID_PAIRS_PER_CELL * cells;
        if (!over || (res[0] == 1 && res[1] == 1 && res[2] == 1))
            break;
        for (int a = 0; a < 3; a++)
            res[a] = res[a] > 1 ? res[a] / 2 : 1;
    }
    if (pairs >= UINT32_MAX) {
        tb_timer_stop(timer);
        return tb_error(TB_ERR_NOMEM, "grid: %zu (voxel, reference) pairs do not fit", pairs);
    }

    uint32_t *cursor = NULL;
    g->cell_start = calloc(cells + 1, sizeof *g->cell_start);
    g->cell_refs = malloc((pairs ? pairs : 1) * sizeof *g->cell_refs);
    cursor = malloc(cells * sizeof *cursor);
    if (!g->cell_start || !g->cell_refs || !cursor) {
        free(cursor);
        tb_timer_stop(timer);
        return tb_error(TB_ERR_NOMEM, "grid: out of memory for %zu voxels and %zu pairs", cells, pairs);
    }
    const size_t sy = (size_t)res[0], sz = (size_t)res[0] * (size_t)res[1];
    for (size_t k = 0; k < n; k++) {
        int i0[3], i1[3];
        tb__grid_range(g, &acc->prims[k].bounds, i0, i1);
        for (int z = i0[2]; z <= i1[2]; z++)
            for (int y = i0[1]; y <= i1[1]; y++)
                for (int x = i0[0]; x <= i1[0]; x++)
                    g->cell_start[(size_t)x + sy * y + sz * z + 1]++;
    }
    size_t nonempty = 0;
    for (size_t c = 0; c < cells; c++) {
        nonempty += g->cell_start[c + 1] != 0;
        g->cell_start[c + 1] += g->cell_start[c];
        cursor[c] = g->cell_start[c];
    }
    /* References in stored (= input) order, so each voxel's list is ascending. */
    for (size_t k = 0; k < n; k++) {
        int i0[3], i1[3];
        tb__grid_range(g, &acc->prims[k].bounds, i0, i1);
        for (int z = i0[2]; z <= i1[2]; z++)
            for (int y = i0[1]; y <= i1[1]; y++)
                for (int x = i0[0]; x <= i1[0]; x++)
                    g->cell_refs[cursor[(size_t)x + sy * y + sz * z]++] = (uint32_t)k;
    }
    free(cursor);
    g->nrefs = pairs;

    size_t bytes = (cells + 1) * sizeof *g->cell_start + pairs * sizeof *g->cell_refs;
    acc->stats.memory_bytes += bytes;
    tb_stat_add(&tb__grid_memory, (int64_t)bytes);
    for (int a = 0; a < 3; a++)
        acc->stats.grid_res[a] = res[a];
    acc->stats.grid_cells = cells;
    acc->stats.grid_nonempty = nonempty;
    acc->stats.grid_refs = pairs;
    /* The double box rounded outward to float. */
    acc->stats.grid_bounds = (tb_aabb){{tb_float_round_down(g->lo[0]), tb_float_round_down(g->lo[1]), tb_float_round_down(g->lo[2])},
                                       {tb_float_round_up(g->hi[0]), tb_float_round_up(g->hi[1]), tb_float_round_up(g->hi[2])}};
    tb_timer_stop(timer);
    return TB_OK;
}

void tb__grid_free(tb_accel *acc)
{
    tb__grid *g = &acc->grid;
    if (g->cell_start) {
        size_t cells = (size_t)g->res[0] * (size_t)g->res[1] * (size_t)g->res[2];
        tb_stat_add(&tb__grid_memory,
                    -(int64_t)((cells + 1) * sizeof *g->cell_start + g->nrefs * sizeof *g->cell_refs));
    }
    free(g->cell_start);
    free(g->cell_refs);
    g->cell_start = NULL;
    g->cell_refs = NULL;
}

/* t moved outward by the traversal tolerance, in double (as the float versions). */
static inline double tb__widen_lo(double t) { return t > 0.0 ? t * (1.0 - TB__ACCEL_T_TOL) : t * (1.0 + TB__ACCEL_T_TOL); }
static inline double tb__widen_hi(double t) { return t > 0.0 ? t * (1.0 + TB__ACCEL_T_TOL) : t * (1.0 - TB__ACCEL_T_TOL); }

/* The state of one 3D-DDA walk. Each voxel is visited over [t of entry,
 * min(tnext)]; the crossings are recomputed from the voxel index at each
 * step (not accumulated), so their error does not grow along the ray. */
typedef struct tb__dda {
    double o[3], d[3], inv[3];
    int idx[3], step[3];
    double tnext[3];  /* t at which the ray leaves the current voxel through each axis' next plane */
    double tstop;     /* walk ends once a voxel ends after this */
} tb__dda;

/* The ray's next crossing along axis a from voxel g->idx[a]. */
static inline double tb__dda_next(const tb__grid *g, const tb__dda *w, int a)
{
    if (w->step[a] > 0)
        return (g->lo[a] + (double)(w->idx[a] + 1) * g->cell[a] - w->o[a]) * w->inv[a];
    if (w->step[a] < 0)
        return (g->lo[a] + (double)w->idx[a] * g->cell[a] - w->o[a]) * w->inv[a];
    return INFINITY;
}

/* Clips the widened ray segment to the grid box and finds the first voxel;
 * false if the ray misses the grid. */
static bool tb__dda_start(const tb__grid *g, const tb_ray *ray, tb__dda *w)
{
    double t0 = tb__widen_lo(ray->tmin), t1 = tb__widen_hi(ray->tmax);
    float o[3] = {ray->o.x, ray->o.y, ray->o.z}, d[3] = {ray->d.x, ray->d.y, ray->d.z};
    for (int a = 0; a < 3; a++) {
        w->o[a] = o[a];
        w->d[a] = d[a];
        if (d[a] == 0.0f) {
            /* Parallel to the slabs of this axis: inside them or never. */
            if (w->o[a] < g->lo[a] || w->o[a] > g->hi[a])
                return false;
            w->inv[a] = 0.0;
            w->step[a] = 0;
            continue;
        }
        w->inv[a] = 1.0 / w->d[a];
        w->step[a] = d[a] > 0.0f ? 1 : -1;
        double ta = (g->lo[a] - w->o[a]) * w->inv[a], tb = (g->hi[a] - w->o[a]) * w->inv[a];
        if (ta > tb) {
            double s = ta;
            ta = tb;
            tb = s;
        }
        if (ta > t0)
            t0 = ta;
        if (tb < t1)
            t1 = tb;
    }
    if (!(t0 <= t1))
        return false;
    for (int a = 0; a < 3; a++) {
        double p = w->o[a] + t0 * w->d[a];
        w->idx[a] = tb__voxel((p - g->lo[a]) * g->inv_cell[a], g->res[a]);
        w->tnext[a] = tb__dda_next(g, w, a);
    }
    w->tstop = t1;
    return true;
}

/* Moves to the next voxel along the ray; false once the walk is over (the
 * current voxel ends after tstop, or the ray leaves the grid). */
static inline bool tb__dda_step(const tb__grid *g, tb__dda *w)
{
    /* The axis whose plane comes first; on equal t the lowest axis steps first,
     * and the next iteration takes the other (a corner visits both neighbours). */
    int a = 0;
    if (w->tnext[1] < w->tnext[a])
        a = 1;
    if (w->tnext[2] < w->tnext[a])
        a = 2;
    if (w->tnext[a] > w->tstop)
        return false;
    w->idx[a] += w->step[a];
    if (w->idx[a] < 0 || w->idx[a] >= g->res[a])
        return false;
    w->tnext[a] = tb__dda_next(g, w, a);
    return true;
}

bool tb__grid_intersect(const tb_accel *acc, const tb_ray *ray, tb__accel_best *best)
{
    const tb__grid *g = &acc->grid;
    tb__dda w;
    int64_t visited = 0, tested = 0;
    if (tb__dda_start(g, ray, &w)) {
        const size_t sy = (size_t)g->res[0], sz = (size_t)g->res[0] * (size_t)g->res[1];
        do {
            visited++;
            size_t c = (size_t)w.idx[0] + sy * (size_t)w.idx[1] + sz * (size_t)w.idx[2];
            for (uint32_t j = g->cell_start[c], e = g->cell_start[c + 1]; j < e; j++) {
                tested++;
                /* No voxel window on acceptance: a hit beyond this voxel is a real
                 * hit and only narrows the search; the walk stops only when the
                 * current voxel ends beyond the best t (docs/accel.md). */
                if (tb__accel_test(acc, g->cell_refs[j], best)) {
                    double stop = tb__widen_hi(best->ray.tmax);
                    if (stop < w.tstop)
                        w.tstop = stop;
                }
            }
        } while (tb__dda_step(g, &w));
    }
    TB_STAT_INC(tb__grid_rays);
    tb_stat_add(&tb__grid_voxels_visited, visited);
    tb_stat_add(&tb__grid_prims_tested, tested);
    return best->found;
}

bool tb__grid_occluded(const tb_accel *acc, const tb_ray *ray)
{
    const tb__grid *g = &acc->grid;
    tb__dda w;
    int64_t visited = 0, tested = 0;
    bool hit = false;
    tb__accel_any q = tb__accel_any_start(ray);
    if (tb__dda_start(g, ray, &w)) {
        const size_t sy = (size_t)g->res[0], sz = (size_t)g->res[0] * (size_t)g->res[1];
        do {
            visited++;
            size_t c = (size_t)w.idx[0] + sy * (size_t)w.idx[1] + sz * (size_t)w.idx[2];
            for (uint32_t j = g->cell_start[c], e = g->cell_start[c + 1]; j < e && !hit; j++) {
                tested++;
                hit = tb__accel_test_any(acc, g->cell_refs[j], &q);
            }
        } while (!hit && tb__dda_step(g, &w));
    }
    TB_STAT_INC(tb__grid_shadow_rays);
    tb_stat_add(&tb__grid_voxels_visited, visited);
    tb_stat_add(&tb__grid_prims_tested, tested);
    return hit;
}
