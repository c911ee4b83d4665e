/* Progressive-refinement radiosity (docs/radiosity.md, "Solver"). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "host/radiosity/lights.h"
#include "host/radiosity/radiosity.h"
#include "host/radiosity/update_internal.h"
#include "util/base/fault.h"
#include "util/base/progress.h"
#include "util/container/pqueue.h"
#include "util/math/float.h"
#include "util/stats/stats.h"

/* How far (a fraction of the way to its elements' centroid) a receiver
 * vertex is moved into its surface (see tb_rad_solver_create). */
#define TB__RAD_RECEIVER_INSET 1e-3

static inline int tb__elem_size(const tb_rad_element *e) { return e->v[3] == TB_RAD_NONE ? 3 : 4; }

/* Blocks of shooters the unshot sum adds apart (then the blocks in order):
 * fixed, so the sum is the same however the shooters are split over
 * processes (each adds its blocks; tb_rad_exchange.select shares them). */
#define TB__RAD_UNSHOT_BLOCKS 64

/* Receivers within this many shooter radii (centroid to farthest corner)
 * get the near-field form factor (tb__near_field). */
#define TB__RAD_NEAR 4.0

TB_STAT_COUNTER(tb__rad_shots, "Radiosity/shots");
TB_STAT_COUNTER(tb__rad_ffs, "Radiosity/form factors");
TB_STAT_COUNTER(tb__rad_rays, "Radiosity/rays (receivers x samples)");
TB_STAT_COUNTER(tb__rad_cached, "Radiosity/shots from cached form factors");
TB_STAT_COUNTER(tb__rad_split_shots, "Radiosity/shots with the update split over ranks");
TB_STAT_COUNTER(tb__rad_facing_none, "Radiosity/receiver clusters facing no sample");
TB_STAT_TIMER(tb__rad_ff_time, "Radiosity/form factor time");
TB_STAT_TIMER(tb__rad_update_time, "Radiosity/update time");

struct tb_rad_solver {
    tb_rad_mesh m;          /* own copy */
    tb_rad_options opt;
    int nc;
    size_t nrecv;           /* receivers: vertices (ray cast) or elements (hemicube) */
    double *He;             /* nelems * nc: gathered irradiance of each element (what its unshot follows) */
    double *Hv;             /* nverts * nc: gathered irradiance at each vertex (display); hemicube: the
                               area-weighted mean of the elements around it */
    double *vert_area;      /* hemicube: area of the elements around each vertex */
    double *vvis;           /* ray cast: nverts, visible fraction of the vertices near the shooter (NaN: not near) */
    double *gnear;          /* ray cast: nelems, F_ji of the elements near the shooter (NaN: not near) */
    size_t *near_list;      /* ray cast: the elements gnear holds this shot */
    size_t nnear;
    double *dB;             /* nelems * nc: unshot radiosity */
    double *up;             /* nelems: tb__unshot_power of each element, kept up to date with dB (the
                               unshot fraction after every shot sums these, not nelems * nc values) */
    double *ff;             /* nrecv: form factors of one shot */
    tb_vec3 *rp, *rn;       /* ray cast: receiver positions and normals (the vertices) */
    tb_vec3 *pts;           /* ray cast: shooter sample points */
    tb_ff_polygon *polys;   /* every element */
    double *erad;           /* per element: its radius about its centroid (tb__radius2's root) */
    tb_ff_occluders *occ;   /* the CPU backend's, when the solver built it */
    float (*boxes)[6];      /* with occ: bounds of clusters of touching occluders (lo xyz, hi xyz, padded) */
    size_t nboxes;
    float box_pad;          /* with occ: the boxes' padding */
    uint32_t *corder;       /* with occ: the vertices in clusters of TB__RAD_CLUSTER, near ones together */
    float (*clbox)[6];      /* bounds of each cluster's receivers */
    tb_vec3 *crp;           /* the receiver positions in corder's order */
    size_t ncl;
    tb_hemicube *hc;
    tb_pqueue q;            /* shooters (patches) by unshot power; empty when `scan` */
    bool scan;              /* one level, one process: the next shooter is the element of most unshot
                               power found by a scan of `up` (tb__top), no queue kept: a shot changes
                               almost every element's power, and a scan costs less than that many
                               queue updates */
    /* Shooters (docs/radiosity.md, "Patches and elements"): the mesh's
     * patches, or its elements on one level (shooter k = element k). */
    size_t nsh;
    uint32_t *pof;          /* nelems: the shooter of each element */
    uint32_t *pstart, *pel; /* shooter k's elements: pel[pstart[k] .. pstart[k + 1]), ascending */
    tb_ff_polygon *spoly;   /* nsh: outlines (the elements' own polygons on one level) */
    double *sarea;          /* nsh: area, the sum of its elements' */
    tb_vec3 *scen, *snrm;   /* nsh: area centroid and unit normal */
    unsigned char *sdirty;  /* nsh: two levels: an element's unshot power changed this shot */
    float *vff, *eff;       /* one shooter's form factors: F(v -> i) per vertex (ray cast), F_ji per element */
    float **cache;          /* per shooter: its vff (nverts, ray cast) then eff (nelems), or NULL */
    size_t cache_bytes;     /* held by `cache` */
    uint64_t shots;
    double seconds;
    double emitted;
    double absorbed, escaped; /* at create (a continued solution's absorbed); the shots' add eabs, erec below */
    double *eabs, *erec;    /* nelems: power each element absorbed and received over the shots; the totals
                               sum them in element order when asked, so they do not depend on how the
                               elements are split over processes */
    double shot_total;      /* power shot (elements' and lights') */
    double total_area;
    double *rho_mean;       /* nc: area-weighted mean reflectance */
    uint32_t *rrow;         /* nelems: which of the distinct reflectance rows the element has, or NULL when
                               there are more than TB__RAD_MAX_ROWS */
    uint32_t *row_elem;     /* an element with each distinct row */
    double *row_dot;        /* per distinct row: sum_c rho[c] dBi[c] of the current shot */
    size_t nrows;
    bool avx;               /* the update's AVX kernels (tb__rad_have_avx) */
    /* Deferred channel sums (tb__defer_flush): inside tb_rad_solver_run a
     * shot of a cached shooter only logs (shooter, dBi) for Hv, He and, on
     * one level, dB (the next shooter's dBi is read through the log,
     * tb__pending_dB; with patches dB is updated at once); all threads then
     * replay the logged shots in order, from the shooters' cached form
     * factors. The serial part of a shot is left with the scalars per
     * element (received, absorbed, unshot power). */
    bool defer;             /* this run logs its shots */
    uint32_t *dlog;         /* TB__RAD_DEFER_MAX: the shooters of the logged shots, in order */
    double *dlog_dbi;       /* TB__RAD_DEFER_MAX * nc: their unshot radiosities */
    size_t ndlog;           /* shots logged and not yet replayed */
    /* point, spot and directional lights (the block at the end of this file) */
    tb_rad_lights *lights;  /* NULL: none */
    unsigned char *lshot;   /* nlights: shot yet */
    double *lpower;         /* nlights: power summed over channels */
    double lpending;        /* power of the lights not yet shot */
    /* over several processes (opt.exchange): this one's clusters' form
     * factors, everyone's gathered, and how many each process computes */
    double *xmine, *xall;
    size_t *xcounts;
    size_t *xcounts2;       /* values each process sends this shot: its form factors and its near vertices'
                               visible fractions */
    bool vnear_done;        /* this shot's vertices' near field is done (tb__batch did it) */
    /* the elements' near field shared out too (the elements near a shooter
     * are next to it, mostly one process's: computing them where they are
     * owned left the others waiting): the k-th near element's exact form
     * factor is computed by process k mod R and travels with the gather */
    double *enf;            /* per element: that form factor, when enf_done */
    uint32_t *enl;          /* this shot's near elements, in element order */
    bool enf_done;
    /* several shooters in flight: this process's shooter's form factors,
     * everyone's, and the counts (all equal) */
    float *xsev, *xsevall; /* the form factors are floats: sent as they are, half the bytes of doubles */
    size_t *xsevcounts;
    /* The update split over processes (tb__split_begin; docs/distributed.md):
     * this process updates its shooters' elements and its vertices; the
     * processes agree on the next shooter and the unshot sum each shot. */
    bool split;             /* inside a split tb_rad_solver_run */
    size_t k0, k1, v0, v1;  /* this process's shooters and vertices */
    size_t nblk;            /* blocks of shooters whose unshot powers are summed apart (fixed: min(nsh, 64)) */
    double *sel;            /* 3 + nc + nblk: tb_rad_exchange.select's buffer: count, power, key, dBi, blocks */
    double *xst;            /* state gathered at the end of a split solve */
    size_t *xstcounts;      /* values per process */
};

static tb_status tb__lights_init(tb_rad_solver *s, const tb_rad_state *state);
static tb_status tb__lights_step(tb_rad_solver *s, bool *shot);

static double tb__now(void) { return 1e-9 * (double)tb_stats_now_ns(); }

/* Seed of the sample points of shooter k (a SplitMix64 step: every
 * shooter gets an unrelated stream, whatever the thread count; the same
 * shooter always gets the same points, so its form factors can be cached). */
static uint64_t tb__shot_seed(uint64_t seed, uint64_t k)
{
    uint64_t z = seed + 0x9e3779b97f4a7c15ull * (k + 1);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* x[0] + ... + x[n-1] in four interleaved partial sums (a fixed order:
 * the same answer everywhere, without one long chain of dependent adds). */
static inline double tb__sum(const double *restrict x, size_t n)
{
    double a0 = 0.0, a1 = 0.0, a2 = 0.0, a3 = 0.0;
    size_t c = 0;
    for (; c + 4 <= n; c += 4)
        a0 += x[c], a1 += x[c + 1], a2 += x[c + 2], a3 += x[c + 3];
    for (; c < n; c++)
        a0 += x[c];
    return (a0 + a1) + (a2 + a3);
}

/* sum of rho[c] x[c] over n channels, summed as tb__sum does. */
static inline double tb__dot(const float *restrict rho, const double *restrict x, size_t n)
{
    double a0 = 0.0, a1 = 0.0, a2 = 0.0, a3 = 0.0;
    size_t c = 0;
    for (; c + 4 <= n; c += 4)
        a0 += rho[c] * x[c], a1 += rho[c + 1] * x[c + 1], a2 += rho[c + 2] * x[c + 2], a3 += rho[c + 3] * x[c + 3];
    for (; c < n; c++)
        a0 += rho[c] * x[c];
    return (a0 + a1) + (a2 + a3);
}

/* Unshot power of element i, summed over channels. */
static inline double tb__unshot_power(const tb_rad_solver *s, size_t i)
{
    return tb__sum(s->dB + i * (size_t)s->nc, (size_t)s->nc) * s->m.elems[i].area;
}

/* Shooter k's unshot power: the sum of its elements' (in element order). */
static double tb__shooter_power(const tb_rad_solver *s, size_t k)
{
    double p = 0.0;
    for (uint32_t q = s->pstart[k]; q < s->pstart[k + 1]; q++)
        p += s->up[s->pel[q]];
    return p;
}

/* The first shooter of block b of the unshot sum (b = nblk: nsh). */
static size_t tb__block_start(const tb_rad_solver *s, size_t b) { return b * s->nsh / s->nblk; }

/* Block b's unshot power: its shooters' elements' (pel order). */
static double tb__block_unshot(const tb_rad_solver *s, size_t b)
{
    double p = 0.0;
    for (uint32_t q = s->pstart[tb__block_start(s, b)]; q < s->pstart[tb__block_start(s, b + 1)]; q++)
        p += s->up[s->pel[q]];
    return p;
}

/* Shooter k's unshot radiosity per channel, the density it shoots: its
 * elements' unshot power over its area (one element: its unshot radiosity). */
static void tb__shooter_dbi(const tb_rad_solver *s, size_t k, double *dBi)
{
    size_t nc = (size_t)s->nc;
    uint32_t pa = s->pstart[k], pb = s->pstart[k + 1];
    for (size_t c = 0; c < nc; c++) {
        double p = 0.0;
        for (uint32_t q = pa; q < pb; q++) {
            size_t x = s->pel[q] * nc + c;
            p += pb - pa == 1 ? s->dB[x] : s->dB[x] * s->m.elems[s->pel[q]].area;
        }
        dBi[c] = pb - pa == 1 ? p : p / s->sarea[k];
    }
}

/* The elements this process updates, as a range of pel: all of them, or
 * in a split solve its shooters'. */
static void tb__owned(const tb_rad_solver *s, uint32_t *qa, uint32_t *qb)
{
    *qa = s->split ? s->pstart[s->k0] : 0;
    *qb = s->split ? s->pstart[s->k1] : (uint32_t)s->m.nelems;
}

/* Element j's unshot power changed: its shooter's priority follows (on two
 * levels at tb__queue_flush, once per shot). */
static inline void tb__queue_elem(tb_rad_solver *s, size_t j)
{
    if (s->scan)
        return;
    if (s->m.npatches == 0)
        tb_pqueue_set(&s->q, (uint32_t)j, s->up[j]);
    else
        s->sdirty[s->pof[j]] = 1;
}

/* Every shooter's priority from its elements' unshot powers. The queue is
 * a function of them (ties go to the lower key), so a rebuilt queue gives
 * the original's order. */
static void tb__queue_rebuild(tb_rad_solver *s)
{
    if (s->scan)
        return;
    for (size_t k = 0; k < s->nsh; k++) {
        double pw = tb__shooter_power(s, k);
        if (pw > 0.0)
            tb_pqueue_set(&s->q, (uint32_t)k, pw);
        else
            tb_pqueue_remove(&s->q, (uint32_t)k);
    }
}

/* The first shooter: the queue's, or with `scan` the element of most
 * unshot power, ties to the lower index (the queue's order), none if no
 * element has any (the queue would offer one of power 0, which no caller
 * shoots). */
static bool tb__top(const tb_rad_solver *s, uint32_t *key, double *pri)
{
    if (!s->scan)
        return tb_pqueue_peek(&s->q, key, pri);
    const double *restrict up = s->up;
    size_t ne = s->m.nelems, best = 0;
    double p = 0.0;
    for (size_t j = 0; j < ne; j++)
        if (up[j] > p)
            p = up[j], best = j;
    if (!(p > 0.0))
        return false;
    *key = (uint32_t)best, *pri = p;
    return true;
}

/* Two levels: the patches whose elements changed get their new sums. */
static void tb__queue_flush(tb_rad_solver *s)
{
    if (s->m.npatches == 0)
        return;
    for (size_t k = 0; k < s->nsh; k++)
        if (s->sdirty[k]) {
            s->sdirty[k] = 0;
            tb_pqueue_set(&s->q, (uint32_t)k, tb__shooter_power(s, k));
        }
}

/* The shooters: each element's patch, the patches' element lists, outlines,
 * areas (sums of their elements'), centroids and normals (area-weighted).
 * On one level shooter k is element k with its own geometry, bit for bit. */
static tb_status tb__shooters_init(tb_rad_solver *s)
{
    size_t ne = s->m.nelems, ns = s->nsh;
    for (size_t i = 0; i < ne; i++)
        s->pof[i] = s->m.npatches ? s->m.patch[i] : (uint32_t)i;
    for (size_t i = 0; i < ne; i++)
        s->pstart[s->pof[i] + 1]++;
    for (size_t k = 0; k < ns; k++)
        s->pstart[k + 1] += s->pstart[k];
    for (size_t k = 0; k < ns; k++)
        if (s->pstart[k + 1] == s->pstart[k])
            return tb_error(TB_ERR_ARG, "radiosity: patch %zu has no element", k);
    uint32_t *fill = malloc(sizeof *fill * (ns ? ns : 1));
    if (!fill)
        return tb_error(TB_ERR_NOMEM, "radiosity: out of memory");
    memcpy(fill, s->pstart, sizeof *fill * ns);
    for (size_t i = 0; i < ne; i++)
        s->pel[fill[s->pof[i]]++] = (uint32_t)i;
    free(fill);
    for (size_t k = 0; k < ns; k++) {
        uint32_t a = s->pstart[k], b = s->pstart[k + 1];
        if (b - a == 1) {
            const tb_rad_element *e = &s->m.elems[s->pel[a]];
            s->spoly[k] = s->polys[s->pel[a]];
            s->sarea[k] = e->area, s->scen[k] = e->centroid, s->snrm[k] = e->normal;
            continue;
        }
        double A = 0.0, c[3] = {0, 0, 0}, n[3] = {0, 0, 0};
        for (uint32_t q = a; q < b; q++) {
            const tb_rad_element *e = &s->m.elems[s->pel[q]];
            A += e->area;
            c[0] += e->area * e->centroid.x, c[1] += e->area * e->centroid.y, c[2] += e->area * e->centroid.z;
            n[0] += e->area * e->normal.x, n[1] += e->area * e->normal.y, n[2] += e->area * e->normal.z;
        }
        double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(l > 0.0))
            return tb_error(TB_ERR_ARG, "radiosity: patch %zu has no normal (its elements face opposite ways)", k);
        s->spoly[k] = s->m.patch_poly[k];
        s->sarea[k] = A;
        s->scen[k] = tb_vec3_make((float)(c[0] / A), (float)(c[1] / A), (float)(c[2] / A));
        s->snrm[k] = tb_vec3_make((float)(n[0] / l), (float)(n[1] / l), (float)(n[2] / l));
    }
    return TB_OK;
}

void tb_rad_solver_free(tb_rad_solver *s)
{
    if (!s)
        return;
    if (s->cache)
        for (size_t i = 0; i < s->nsh; i++)
            free(s->cache[i]);
    free(s->cache);
    free(s->dlog);
    free(s->dlog_dbi);
    tb_rad_mesh_free(&s->m);
    free(s->He);
    free(s->Hv);
    free(s->gnear);
    free(s->vvis);
    free(s->near_list);
    free(s->vert_area);
    free(s->dB);
    free(s->up);
    free(s->ff);
    free(s->vff);
    free(s->eff);

    free(s->rp);
    free(s->rn);
    free(s->pts);
    free(s->polys);
    free(s->erad);
    free(s->rho_mean);
    free(s->pof), free(s->pstart), free(s->pel), free(s->spoly), free(s->sarea), free(s->scen), free(s->snrm);
    free(s->sdirty);
    free(s->rrow);
    free(s->row_elem);
    free(s->row_dot);
    tb_ff_occluders_free(s->occ);
    free(s->boxes);
    free(s->corder);
    free(s->clbox);
    free(s->crp);
    tb_hemicube_free(s->hc);
    tb_pqueue_free(&s->q);
    tb_rad_lights_free(s->lights);
    free(s->xmine), free(s->xall), free(s->xcounts), free(s->xcounts2), free(s->enf), free(s->enl);
    free(s->xsev), free(s->xsevall), free(s->xsevcounts);
    free(s->eabs), free(s->erec), free(s->sel), free(s->xst), free(s->xstcounts);
    free(s->lshot);
    free(s->lpower);
    free(s);
}

const tb_rad_mesh *tb_rad_solver_mesh(const tb_rad_solver *s) { return &s->m; }

/* Squared distance from c to the farthest corner of p (p's radius about c;
 * a NaN distance is passed over, as fmax does). */
static double tb__radius2(const tb_ff_polygon *p, tb_vec3 c)
{
    double r2 = 0.0;
    for (int k = 0; k < p->n; k++) {
        double x = (double)tb_vec3_length2(tb_vec3_sub(p->v[k], c));
        r2 = x > r2 ? x : r2;
    }
    return r2;
}

static void *tb__calloc(size_t n, size_t size, bool *ok)
{
    void *p = calloc(n ? n : 1, size);
    if (!p)
        *ok = false;
    return p;
}

/* Bounds of the occluders in a few boxes: each polygon's box, padded by
 * 1e-5 of the scene's size, merged with every box it touches until none
 * touch (the Cornell box: one per block, the light, the red wall). A
 * segment that misses them all is visible without a trip through the BVH,
 * whose ray set-up costs more than the test (most segments in a room miss
 * the few things in it). */
static tb_status tb__occluder_boxes(tb_rad_solver *s, const tb_ff_polygon *occ, size_t nocc)
{
    if (nocc == 0)
        return TB_OK;
    tb_vec3 lo = s->m.verts[0].p, hi = lo;
    for (size_t v = 1; v < s->m.nverts; v++)
        lo = tb_vec3_min(lo, s->m.verts[v].p), hi = tb_vec3_max(hi, s->m.verts[v].p);
    float pad = 1e-5f * tb_vec3_length(tb_vec3_sub(hi, lo));
    float(*b)[6] = malloc(nocc * sizeof *b);
    if (!b)
        return tb_error(TB_ERR_NOMEM, "radiosity: out of memory");
    for (size_t k = 0; k < nocc; k++) {
        tb_vec3 l = occ[k].v[0], h = l;
        for (int q = 1; q < occ[k].n; q++)
            l = tb_vec3_min(l, occ[k].v[q]), h = tb_vec3_max(h, occ[k].v[q]);
        b[k][0] = l.x - pad, b[k][1] = l.y - pad, b[k][2] = l.z - pad;
        b[k][3] = h.x + pad, b[k][4] = h.y + pad, b[k][5] = h.z + pad;
    }
    size_t n = nocc;
    for (bool merged = true; merged;) {
        merged = false;
        for (size_t a = 0; a < n; a++)
            for (size_t c = a + 1; c < n; c++) {
                bool touch = true;
                for (int x = 0; x < 3; x++)
                    touch = touch && b[a][x] <= b[c][x + 3] && b[c][x] <= b[a][x + 3];
                if (!touch)
                    continue;
                for (int x = 0; x < 3; x++)
                    b[a][x] = fminf(b[a][x], b[c][x]), b[a][x + 3] = fmaxf(b[a][x + 3], b[c][x + 3]);
                memcpy(b[c], b[--n], sizeof b[c]);
                c = a; /* a grew: look again from a + 1 */
                merged = true;
            }
    }
    s->boxes = b;
    s->nboxes = n;
    s->box_pad = pad;
    return TB_OK;
}

/* Does the segment a -> b touch the box (slab test over t in [0, 1])? */
static inline bool tb__segment_box(tb_vec3 a, tb_vec3 b, const float *box)
{
    float t0 = 0.0f, t1 = 1.0f;
    float pa[3] = {a.x, a.y, a.z}, d[3] = {b.x - a.x, b.y - a.y, b.z - a.z};
    for (int x = 0; x < 3; x++) {
        if (d[x] == 0.0f) {
            if (pa[x] < box[x] || pa[x] > box[x + 3])
                return false;
            continue;
        }
        float inv = 1.0f / d[x];
        float u0 = (box[x] - pa[x]) * inv, u1 = (box[x + 3] - pa[x]) * inv;
        if (u0 > u1) {
            float t = u0;
            u0 = u1, u1 = t;
        }
        /* widen by float rounding: the test must never miss a box the segment touches */
        u0 -= 1e-5f, u1 += 1e-5f;
        t0 = u0 > t0 ? u0 : t0;
        t1 = u1 < t1 ? u1 : t1;
        if (t0 > t1)
            return false;
    }
    return true;
}

/* Most occluder boxes tb__batch lists per cluster (more: all are tested). */
#define TB__RAD_CLUSTER_BOXES 32

/* tb__visible's context: the solver and the occluder boxes one cluster's
 * segments can touch (box[0..n) indices into s->boxes; box NULL: all). */
typedef struct tb__vis_ctx {
    const tb_rad_solver *s;
    const uint16_t *box;
    size_t n;
} tb__vis_ctx;

/* A tb_ff_visible_fn over the solver's occluders: the boxes first, then
 * the BVH (the same answer as tb_ff_occluders_visible alone: every
 * occluder lies inside a box, so a segment that misses them all crosses
 * none). */
static bool tb__visible(void *ctx, tb_vec3 a, tb_vec3 b)
{
    const tb__vis_ctx *v = ctx;
    const tb_rad_solver *s = v->s;
    if (v->box) {
        for (size_t k = 0; k < v->n; k++)
            if (tb__segment_box(a, b, s->boxes[v->box[k]]))
                return tb_ff_occluders_visible(s->occ, a, b);
        return true;
    }
    for (size_t k = 0; k < s->nboxes; k++)
        if (tb__segment_box(a, b, s->boxes[k]))
            return tb_ff_occluders_visible(s->occ, a, b);
    return true;
}

/* The occluder boxes that meet the bounds of a cluster's segments, the
 * union lo..hi of its receivers' box and the sample points' (padded like
 * the boxes): the others cannot be touched by them. False (use them all)
 * if there are more than TB__RAD_CLUSTER_BOXES. */
static bool tb__cluster_boxes(const tb_rad_solver *s, const float *ca, const float *cb, tb__vis_ctx *v,
                              uint16_t *box)
{
    if (s->nboxes > UINT16_MAX)
        return false;
    float lo[3], hi[3];
    for (int x = 0; x < 3; x++) {
        float l = fminf(ca[x], cb[x]), h = fmaxf(ca[x + 3], cb[x + 3]);
        float pad = 1e-4f * (fabsf(l) + fabsf(h)) + s->box_pad;
        lo[x] = l - pad, hi[x] = h + pad;
    }
    size_t n = 0;
    for (size_t k = 0; k < s->nboxes; k++) {
        const float *b = s->boxes[k];
        if (b[0] > hi[0] || b[1] > hi[1] || b[2] > hi[2] || b[3] < lo[0] || b[4] < lo[1] || b[5] < lo[2])
            continue;
        if (n == TB__RAD_CLUSTER_BOXES)
            return false;
        box[n++] = (uint16_t)k;
    }
    v->box = box, v->n = n;
    return true;
}

/* Receivers per cluster: one shaft per cluster and shot. */
#define TB__RAD_CLUSTER 8

static int tb__cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* Spreads the low 10 bits of x to every third bit. */
static uint64_t tb__morton_bits(uint64_t x)
{
    x &= 0x3ff;
    x = (x | x << 16) & 0x30000ffull;
    x = (x | x << 8) & 0x300f00full;
    x = (x | x << 4) & 0x30c30c3ull;
    x = (x | x << 2) & 0x9249249ull;
    return x;
}

/* Receiver clusters for tb__batch: the vertices in Morton order of their
 * positions, cut into runs of TB__RAD_CLUSTER, each with its bounds. */
static tb_status tb__receiver_clusters(tb_rad_solver *s)
{
    size_t nv = s->m.nverts;
    tb_vec3 lo = s->rp[0], hi = lo;
    for (size_t v = 1; v < nv; v++)
        lo = tb_vec3_min(lo, s->rp[v]), hi = tb_vec3_max(hi, s->rp[v]);
    uint64_t *key = malloc(nv * sizeof *key);
    s->ncl = (nv + TB__RAD_CLUSTER - 1) / TB__RAD_CLUSTER;
    s->corder = malloc(nv * sizeof *s->corder);
    s->clbox = malloc(s->ncl * sizeof *s->clbox);
    s->crp = malloc(nv * sizeof *s->crp);
    if (!key || !s->corder || !s->clbox || !s->crp) {
        free(key);
        return tb_error(TB_ERR_NOMEM, "radiosity: out of memory");
    }
    float ext[3] = {hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}, org[3] = {lo.x, lo.y, lo.z};
    for (size_t v = 0; v < nv; v++) {
        float p[3] = {s->rp[v].x, s->rp[v].y, s->rp[v].z};
        uint64_t k = 0;
        for (int x = 0; x < 3; x++) {
            double f = ext[x] > 0.0f ? (p[x] - org[x]) / ext[x] : 0.0;
            f = f >= 0.0 ? (f <= 1.0 ? f : 1.0) : 0.0; /* NaN too: the order only affects speed */
            uint64_t q = (uint64_t)(f * 1023.0 + 0.5);
            k |= tb__morton_bits(q > 1023 ? 1023 : q) << x;
        }
        key[v] = k << 32 | (uint64_t)v; /* ties in vertex order */
    }
    qsort(key, nv, sizeof *key, tb__cmp_u64);
    for (size_t v = 0; v < nv; v++)
        s->corder[v] = (uint32_t)key[v], s->crp[v] = s->rp[s->corder[v]];
    free(key);
    for (size_t c = 0; c < s->ncl; c++) {
        size_t end = (c + 1) * TB__RAD_CLUSTER < nv ? (c + 1) * TB__RAD_CLUSTER : nv;
        tb_vec3 l = s->rp[s->corder[c * TB__RAD_CLUSTER]], h = l;
        for (size_t q = c * TB__RAD_CLUSTER + 1; q < end; q++)
            l = tb_vec3_min(l, s->rp[s->corder[q]]), h = tb_vec3_max(h, s->rp[s->corder[q]]);
        float *b = s->clbox[c];
        b[0] = l.x, b[1] = l.y, b[2] = l.z, b[3] = h.x, b[4] = h.y, b[5] = h.z;
    }
    return TB_OK;
}

/* Does a receiver of cluster [q0, q1) face a sample point that faces it
 * (tb_ff_raycast's test, in the same double arithmetic)? If none does, the
 * cluster needs no shaft: tb_ff_raycast tests no visibility there. */
static bool tb__cluster_faces(const tb_rad_solver *s, tb_vec3 ns, size_t q0, size_t q1)
{
    tb_dvec3 nsd = {ns.x, ns.y, ns.z};
    for (size_t q = q0; q < q1; q++) {
        uint32_t v = s->corder[q];
        tb_dvec3 pd = {s->rp[v].x, s->rp[v].y, s->rp[v].z}, nd = {s->rn[v].x, s->rn[v].y, s->rn[v].z};
        for (int k = 0; k < s->opt.samples; k++) {
            tb_dvec3 d = tb_dvec3_sub((tb_dvec3){s->pts[k].x, s->pts[k].y, s->pts[k].z}, pd);
            if (tb_dvec3_length2(d) > 0.0 && tb_dvec3_dot(nd, d) > 0.0 && -tb_dvec3_dot(nsd, d) > 0.0)
                return true;
        }
    }
    return false;
}

/* The shooter's data the vertices' near field needs (tb__near_vertex). */
typedef struct tb__near_shooter {
    const tb_ff_polygon *poly;
    tb_vec3 cen, nrm;
    double area, near2; /* area; squared distance within which a vertex is near */
} tb__near_shooter;

static double tb__radius2(const tb_ff_polygon *p, tb_vec3 c);

static tb__near_shooter tb__near_of(const tb_rad_solver *s, size_t sk)
{
    tb__near_shooter n = {&s->spoly[sk], s->scen[sk], s->snrm[sk], s->sarea[sk], 0.0};
    n.near2 = TB__RAD_NEAR * TB__RAD_NEAR * tb__radius2(n.poly, n.cen);
    return n;
}

/* Whether vertex v lies within TB__RAD_NEAR shooter radii (a NaN counts as near). */
static bool tb__vertex_near(const tb_rad_solver *s, size_t v, const tb__near_shooter *n)
{
    return !((double)tb_vec3_length2(tb_vec3_sub(s->rp[v], n->cen)) >= n->near2);
}

/* Vertex v's near field (tb__near_field): within TB__RAD_NEAR shooter radii
 * its sampled s->ff[v] becomes the exact unoccluded form factor times the
 * visible fraction the samples measured, kept in s->vvis[v] (NaN: not
 * near). Each vertex's own inputs only: any split over threads or
 * processes gives the same values. */
static void tb__near_vertex(tb_rad_solver *s, size_t v, const tb__near_shooter *n)
{
    s->vvis[v] = NAN;
    if (!tb__vertex_near(s, v, n))
        return;
    double exact = tb_ff_point_polygon(s->rp[v], s->rn[v], n->poly);
    if (!(exact >= 0.0) || !isfinite(exact))
        return;
    double open = tb_ff_raycast(s->pts, s->opt.samples, n->nrm, n->area, s->rp[v], s->rn[v], NULL, NULL);
    double vis = open > 0.0 ? s->ff[v] / open : 1.0;
    vis = vis > 1.0 ? 1.0 : vis;
    s->vvis[v] = vis;
    s->ff[v] = exact * vis;
}

/* Several processes: every process's clusters' form factors and, for the
 * vertices near the shooter, visible fractions (the near field done) into
 * s->ff and s->vvis on every process. Which vertices are near follows from
 * replicated data, so every process knows what each sends: its clusters'
 * values in cluster order, a near vertex's fraction after its form factor;
 * the gathered blocks come in rank order and unpack by the same rule. */
static tb_status tb__gather_clusters(tb_rad_solver *s, const tb_rad_exchange *ex, const tb__near_shooter *near,
                                     size_t nnear)
{
    size_t nv = s->m.nverts, ncl = s->ncl, R = (size_t)ex->ranks, n = 0;
    memset(s->xcounts2, 0, R * sizeof *s->xcounts2);
    for (size_t r = 0; r < R; r++)
        s->xcounts2[r] = nnear / R + (r < nnear % R);
    for (size_t c = 0; c < ncl; c++) {
        size_t q1 = (c + 1) * TB__RAD_CLUSTER < nv ? (c + 1) * TB__RAD_CLUSTER : nv;
        for (size_t q = c * TB__RAD_CLUSTER; q < q1; q++)
            s->xcounts2[c % R] += 1 + tb__vertex_near(s, s->corder[q], near);
    }
    for (size_t c = (size_t)ex->rank; c < ncl; c += R) {
        size_t q1 = (c + 1) * TB__RAD_CLUSTER < nv ? (c + 1) * TB__RAD_CLUSTER : nv;
        for (size_t q = c * TB__RAD_CLUSTER; q < q1; q++) {
            uint32_t v = s->corder[q];
            s->xmine[n++] = s->ff[v];
            if (tb__vertex_near(s, v, near))
                s->xmine[n++] = s->vvis[v];
        }
    }
    for (size_t k = (size_t)ex->rank; k < nnear; k += R)
        s->xmine[n++] = s->enf[s->enl[k]];
    tb_status st = ex->allgather(ex->ctx, s->xmine, n, s->xall, s->xcounts2, s->xcounts[ex->rank]);
    if (st)
        return st;
    size_t at = 0;
    for (size_t r = 0; r < R; r++) {
        for (size_t c = r; c < ncl; c += R) {
            size_t q1 = (c + 1) * TB__RAD_CLUSTER < nv ? (c + 1) * TB__RAD_CLUSTER : nv;
            for (size_t q = c * TB__RAD_CLUSTER; q < q1; q++) {
                uint32_t v = s->corder[q];
                s->ff[v] = s->xall[at++];
                s->vvis[v] = tb__vertex_near(s, v, near) ? s->xall[at++] : NAN;
            }
        }
        for (size_t k = r; k < nnear; k += R)
            s->enf[s->enl[k]] = s->xall[at++];
    }
    s->enf_done = true;
    return TB_OK;
}

/* Most shots the log holds (then it is replayed), and the receivers per
 * block of the replay: a block's Hv or He rows (64 x 31 channels x 8 bytes
 * = 16 KB) stay in the first-level cache while the logged shots stream by. */
#define TB__RAD_DEFER_MAX 256
#define TB__RAD_DEFER_BLOCK 64

/* Replay blocks: the vertices' (Hv), then the elements' in pel order (He). */
static size_t tb__defer_blocks(const tb_rad_solver *s)
{
    return (s->m.nverts + TB__RAD_DEFER_BLOCK - 1) / TB__RAD_DEFER_BLOCK +
           (s->m.nelems + TB__RAD_DEFER_BLOCK - 1) / TB__RAD_DEFER_BLOCK;
}

/* Replays every logged shot, in order, on block b: each value gets the sums
 * tb__shoot would have added, in the same order (the same bits). */
static void tb__defer_block(const tb_rad_solver *s, size_t b)
{
    size_t nv = s->m.nverts, ne = s->m.nelems, nvb = (nv + TB__RAD_DEFER_BLOCK - 1) / TB__RAD_DEFER_BLOCK;
    bool vert = b < nvb;
    size_t r0 = (vert ? b : b - nvb) * TB__RAD_DEFER_BLOCK, n = vert ? nv : ne;
    size_t r1 = r0 + TB__RAD_DEFER_BLOCK < n ? r0 + TB__RAD_DEFER_BLOCK : n;
    bool db = s->m.npatches == 0; /* one level: dB is deferred too */
    size_t nc = (size_t)s->nc;
    for (size_t e = 0; e < s->ndlog; e++) {
        uint32_t k = s->dlog[e];
        const float *c = s->cache[k]; /* vff (nverts) then eff (nelems) */
        tb__rad_update u = {nc, s->dlog_dbi + e * nc, c, c + nv, s->pel, s->pof, k, s->m.rho, s->Hv, s->He,
                            db ? s->dB : NULL};
        if (vert) {
            (s->avx ? tb__rad_update_vertices_avx : tb__rad_update_vertices)(&u, r0, r1);
            continue;
        }
        (s->avx ? tb__rad_update_elements_avx : tb__rad_update_elements)(&u, r0, r1);
        /* the shooter's own elements: unshot 0 from its shot on */
        for (size_t q = s->pstart[k]; db && q < s->pstart[k + 1]; q++)
            if (q >= r0 && q < r1)
                memset(s->dB + s->pel[q] * nc, 0, nc * sizeof *s->dB);
    }
}

/* Element j's unshot radiosity dB as the replay of the logged shots will
 * leave it (one level), into out[nc]: the same products in the same order,
 * without touching the state. */
static void tb__pending_dB(const tb_rad_solver *s, size_t j, double *out)
{
    size_t nc = (size_t)s->nc, nv = s->m.nverts;
    memcpy(out, s->dB + j * nc, nc * sizeof *out);
    const float *rho = s->m.rho + j * nc;
    for (size_t e = 0; e < s->ndlog; e++) {
        uint32_t k = s->dlog[e];
        if (s->pof[j] == k) {
            memset(out, 0, nc * sizeof *out);
            continue;
        }
        double g = s->cache[k][nv + j];
        if (!(g > 0.0))
            continue;
        const double *dBi = s->dlog_dbi + e * nc;
        for (size_t c = 0; c < nc; c++) {
            double dh = dBi[c] * g, r = rho[c];
            out[c] += r * dh;
        }
    }
}

/* Brings Hv, He and (one level) dB up to date: replays the logged shots over all threads
 * (one parallel loop; tb__batch does it inside its own when it runs). */
static void tb__defer_flush(tb_rad_solver *s)
{
    if (s->ndlog == 0)
        return;
    ptrdiff_t nb = (ptrdiff_t)tb__defer_blocks(s);
#pragma omp parallel for schedule(dynamic, 1)
    for (ptrdiff_t b = 0; b < nb; b++)
        tb__defer_block(s, (size_t)b);
    s->ndlog = 0;
}

/* tb__defer_flush outside a shot: its time counts as update time and as
 * the solver's. */
static void tb__defer_flush_timed(tb_rad_solver *s)
{
    if (s->ndlog == 0)
        return;
    double t0 = tb__now();
    tb_timer_token tt = tb_timer_start(&tb__rad_update_time);
    tb__defer_flush(s);
    (void)tb_timer_stop(tt);
    s->seconds += tb__now() - t0;
}

/* The CPU form factors of shooter i to every vertex: tb_ff_raycast over the
 * solver's occluders. Each cluster of receivers first lists the occluders
 * in the shaft between it and the sample points (most lists are empty: no
 * visibility test at all); a cluster with too many goes through tb__visible.
 * Either way a segment gets the BVH's answer, so each receiver's value
 * depends only on its own inputs: any schedule gives the same results. */
static bool tb__near_element(const tb_rad_solver *s, size_t j, tb_vec3 cen, double rad);
static double tb__near_element_ff(const tb_rad_solver *s, size_t sk, size_t j);

static tb_status tb__batch(tb_rad_solver *s, size_t k, bool share)
{
    const tb_vec3 nrm = s->snrm[k]; /* the shooter's (a patch's, or an element's) */
    const double area = s->sarea[k];
    float a[6] = {s->pts[0].x, s->pts[0].y, s->pts[0].z, s->pts[0].x, s->pts[0].y, s->pts[0].z};
    for (int k = 1; k < s->opt.samples; k++) {
        float p[3] = {s->pts[k].x, s->pts[k].y, s->pts[k].z};
        for (int x = 0; x < 3; x++)
            a[x] = fminf(a[x], p[x]), a[x + 3] = fmaxf(a[x + 3], p[x]);
    }
    ptrdiff_t ncl = (ptrdiff_t)s->ncl;
    size_t nv = s->m.nverts;
    /* several processes: this one's clusters are rank, rank + R, ... */
    const tb_rad_exchange *ex = s->xcounts && share ? s->opt.exchange : NULL;
    ptrdiff_t c0 = ex ? ex->rank : 0, dc = ex ? ex->ranks : 1;
    ptrdiff_t nmine = ncl > c0 ? (ncl - c0 + dc - 1) / dc : 0;
    /* the vertices' near field goes with their cluster: split over threads
     * and processes like the rays, not repeated whole on every process */
    const tb__near_shooter near = tb__near_of(s, k);
    /* the logged shots' replay shares the threads' wake-up (it writes Hv
     * and He, which the rays do not read) */
    ptrdiff_t nfb = s->ndlog ? (ptrdiff_t)tb__defer_blocks(s) : 0;
    /* one process: the near elements' exact form factors (tb__near_field)
     * too, each its own value (several processes share them out below) */
    ptrdiff_t nne = 0;
    if (!s->opt.exchange && !s->enf) {
        s->enf = malloc((s->m.nelems + 1) * sizeof *s->enf);
        s->enl = malloc((s->m.nelems + 1) * sizeof *s->enl);
        if (!s->enf || !s->enl) /* then tb__near_field computes them */
            free(s->enf), free(s->enl), s->enf = NULL, s->enl = NULL;
    }
    if (!s->opt.exchange && s->enf) {
        double rad = sqrt(tb__radius2(&s->spoly[k], s->scen[k]));
        for (size_t j = 0; j < s->m.nelems; j++)
            if (s->pof[j] != k && tb__near_element(s, j, s->scen[k], rad))
                s->enl[nne++] = (uint32_t)j;
    }
#pragma omp parallel
    {
#pragma omp for schedule(dynamic, 1) nowait
    for (ptrdiff_t b = 0; b < nfb; b++)
        tb__defer_block(s, (size_t)b);
#pragma omp for schedule(dynamic, 4) nowait
    for (ptrdiff_t q = 0; q < nne; q++)
        s->enf[s->enl[q]] = tb__near_element_ff(s, k, s->enl[q]);
#pragma omp for schedule(dynamic, 4)
    for (ptrdiff_t ci = 0; ci < nmine; ci++) {
        ptrdiff_t c = c0 + ci * dc;
        tb_ff_shaft sh;
        tb__vis_ctx vis = {s, NULL, 0};
        uint16_t vbox[TB__RAD_CLUSTER_BOXES];
        tb_ff_visible_fn fn = tb_ff_shaft_visible;
        void *ctx = &sh;
        size_t q0 = (size_t)c * TB__RAD_CLUSTER, q1 = q0 + TB__RAD_CLUSTER < nv ? q0 + TB__RAD_CLUSTER : nv;
        if (!tb__cluster_faces(s, nrm, q0, q1)) {
            fn = NULL, ctx = NULL; /* no exchange: tb_ff_raycast casts no ray */
            TB_STAT_INC(tb__rad_facing_none);
        }
        else if (!tb_ff_occluders_shaft(s->occ, s->clbox[c], s->crp + q0, q1 - q0, a, s->pts, (size_t)s->opt.samples,
                                        &sh)) {
            fn = tb__visible, ctx = &vis;
            if (!tb__cluster_boxes(s, s->clbox[c], a, &vis, vbox))
                vis.box = NULL;
        }
        else if (sh.n == 0)
            fn = NULL, ctx = NULL; /* nothing in the way: the same sum without tests */
        for (size_t q = q0; q < q1; q++) {
            uint32_t v = s->corder[q];
            s->ff[v] = tb_ff_raycast(s->pts, s->opt.samples, nrm, area, s->rp[v], s->rn[v], fn, ctx);
            tb__near_vertex(s, v, &near);
        }
    }
    }
    s->ndlog = 0;
    s->vnear_done = true;
    if (!s->opt.exchange && s->enf)
        s->enf_done = true;
    if (!ex)
        return TB_OK;
    /* the near elements (the same list on every process), and this one's share of their form factors */
    const tb_ff_polygon *poly = &s->spoly[k];
    double rad = sqrt(tb__radius2(poly, s->scen[k]));
    size_t nnear = 0;
    for (size_t j = 0; j < s->m.nelems; j++)
        if (s->pof[j] != k && tb__near_element(s, j, s->scen[k], rad))
            s->enl[nnear++] = (uint32_t)j;
    for (size_t q = (size_t)ex->rank; q < nnear; q += (size_t)ex->ranks)
        s->enf[s->enl[q]] = tb__near_element_ff(s, k, s->enl[q]);
    return tb__gather_clusters(s, ex, &near, nnear);
}

/* Most distinct reflectance rows the update shares dot products over. */
#define TB__RAD_MAX_ROWS 64

/* The distinct reflectance rows (one per material on most meshes), so that
 * a shot computes sum_c rho[c] dBi[c] once per row, not per element. Leaves
 * rrow NULL (per-element sums) if there are many or memory is short. */
static void tb__reflectance_rows(tb_rad_solver *s)
{
    size_t ne = s->m.nelems, nc = (size_t)s->nc;
    s->rrow = malloc(ne * sizeof *s->rrow);
    s->row_elem = malloc(TB__RAD_MAX_ROWS * sizeof *s->row_elem);
    s->row_dot = malloc(TB__RAD_MAX_ROWS * sizeof *s->row_dot);
    bool ok = s->rrow && s->row_elem && s->row_dot;
    s->nrows = 0;
    for (size_t j = 0; j < ne && ok; j++) {
        const float *r = s->m.rho + j * nc;
        size_t k = 0;
        while (k < s->nrows && memcmp(r, s->m.rho + (size_t)s->row_elem[k] * nc, nc * sizeof *r) != 0)
            k++;
        if (k == s->nrows) {
            if (k == TB__RAD_MAX_ROWS) {
                ok = false;
                break;
            }
            s->row_elem[s->nrows++] = (uint32_t)j;
        }
        s->rrow[j] = (uint32_t)k;
    }
    if (!ok) {
        free(s->rrow);
        s->rrow = NULL;
    }
}

/* Several processes: how many form factors each computes (its clusters'
 * receivers) and the buffers of the gather. */
static tb_status tb__exchange_init(tb_rad_solver *s, const tb_rad_exchange *ex)
{
    size_t nv = s->m.nverts, R = (size_t)ex->ranks;
    size_t ne = s->m.nelems;
    /* a form factor and a near vertex's visible fraction per vertex, a near
     * element's form factor per element */
    s->xmine = malloc((2 * nv + ne + 1) * sizeof *s->xmine);
    s->xall = malloc((2 * nv + ne + 1) * sizeof *s->xall);
    s->xcounts = calloc(R, sizeof *s->xcounts);
    s->xcounts2 = calloc(R, sizeof *s->xcounts2);
    s->enf = malloc((ne + 1) * sizeof *s->enf);
    s->enl = malloc((ne + 1) * sizeof *s->enl);
    if (!s->xmine || !s->xall || !s->xcounts || !s->xcounts2 || !s->enf || !s->enl)
        return tb_error(TB_ERR_NOMEM, "radiosity: out of memory for the exchange");
    for (size_t c = 0; c < s->ncl; c++) {
        size_t q1 = (c + 1) * TB__RAD_CLUSTER < nv ? (c + 1) * TB__RAD_CLUSTER : nv;
        s->xcounts[c % R] += q1 - c * TB__RAD_CLUSTER;
    }

    /* the split update: blocks of shooters and a range of vertices per process */
    if (!ex->select || !ex->allgather_state || ex->several)
        return TB_OK;
    size_t nc = (size_t)s->nc;
    s->sel = malloc((3 + nc + s->nblk) * sizeof *s->sel);
    s->xstcounts = malloc(R * sizeof *s->xstcounts);
    size_t most = 0;
    for (size_t r = 0; r < R; r++) {
        size_t ka = tb__block_start(s, r * s->nblk / R), kb = tb__block_start(s, (r + 1) * s->nblk / R);
        size_t els = s->pstart[kb] - s->pstart[ka], va = r * nv / R, vb = (r + 1) * nv / R;
        if (r == (size_t)ex->rank)
            s->k0 = ka, s->k1 = kb, s->v0 = va, s->v1 = vb;
        if (s->xstcounts)
            s->xstcounts[r] = els * (2 * nc + 3) + (vb - va) * nc;
        most += els * (2 * nc + 3) + (vb - va) * nc;
    }
    s->xst = malloc((most ? most : 1) * sizeof *s->xst);
    if (!s->sel || !s->xstcounts || !s->xst)
        return tb_error(TB_ERR_NOMEM, "radiosity: out of memory for the exchange");
    return TB_OK;
}

tb_status tb_rad_solver_create(const tb_rad_mesh *mesh, const tb_rad_state *state, const tb_rad_options *opt,
                               tb_rad_solver **out)
{
    *out = NULL;
    tb_rad_options o = {0};
    if (opt)
        o = *opt;
    if (o.ff != TB_RAD_FF_RAYCAST && o.ff != TB_RAD_FF_HEMICUBE)
        return tb_error(TB_ERR_ARG, "radiosity: unknown form-factor method %d", (int)o.ff);
    if (o.samples == 0)
        o.samples = TB_RAD_DEFAULT_SAMPLES;
    if (o.hemicube_res == 0)
        o.hemicube_res = TB_RAD_DEFAULT_HEMICUBE_RES;
    if (o.samples < 1 || o.samples > 65536)
        return tb_error(TB_ERR_ARG, "radiosity: samples per shooter %d not in 1..65536", o.samples);
    if (o.hemicube_res < 2 || o.hemicube_res > 8192)
        return tb_error(TB_ERR_ARG, "radiosity: hemicube resolution %d not in 2..8192", o.hemicube_res);
    if (!mesh || mesh->nelems == 0 || mesh->nverts == 0)
        return tb_error(TB_ERR_ARG, "radiosity: empty mesh");
    if (mesh->nelems > TB_PQUEUE_MAX_KEY)
        return tb_error(TB_ERR_ARG, "radiosity: too many elements (%zu)", mesh->nelems);
    if (mesh->npatches > 0) {
        if (!mesh->patch || !mesh->patch_poly || mesh->npatches > mesh->nelems)
            return tb_error(TB_ERR_ARG, "radiosity: %zu patches over %zu elements without their arrays",
                            mesh->npatches, mesh->nelems);
        for (size_t i = 0; i < mesh->nelems; i++)
            if (mesh->patch[i] >= mesh->npatches)
                return tb_error(TB_ERR_ARG, "radiosity: element %zu: patch %u out of range", i, mesh->patch[i]);
        for (size_t k = 0; k < mesh->npatches; k++)
            if (mesh->patch_poly[k].n < 3 || mesh->patch_poly[k].n > TB_FF_MAX_VERTS)
                return tb_error(TB_ERR_ARG, "radiosity: patch %zu has %d corners", k, mesh->patch_poly[k].n);
    }
    if (mesh->nchannels < 1 || mesh->nchannels > TB_CHANNELS_MAX)
        return tb_error(TB_ERR_ARG, "radiosity: %d channels not in 1..%d", mesh->nchannels, TB_CHANNELS_MAX);
    int nc = mesh->nchannels;
    size_t ne = mesh->nelems, nv = mesh->nverts;
    for (size_t i = 0; i < ne * (size_t)nc; i++) {
        if (!(mesh->rho[i] >= 0.0f && mesh->rho[i] < 1.0f))
            return tb_error(TB_ERR_ARG, "radiosity: element %zu: reflectance %g not in [0, 1)", i / (size_t)nc,
                            (double)mesh->rho[i]);
        if (!(mesh->emission[i] >= 0.0f) || !isfinite(mesh->emission[i]))
            return tb_error(TB_ERR_ARG, "radiosity: element %zu: bad emission %g", i / (size_t)nc,
                            (double)mesh->emission[i]);
    }
    for (size_t i = 0; i < ne; i++) {
        const tb_rad_element *e = &mesh->elems[i];
        for (int k = 0; k < 4; k++)
            if ((k < 3 || e->v[k] != TB_RAD_NONE) && e->v[k] >= nv)
                return tb_error(TB_ERR_ARG, "radiosity: element %zu: vertex %u out of range", i, e->v[k]);
        if (!(e->area > 0.0) || !isfinite(e->area))
            return tb_error(TB_ERR_ARG, "radiosity: element %zu: area %g (geometry not up to date?)", i, e->area);
    }

    tb_rad_solver *s = calloc(1, sizeof *s);
    if (!s)
        return tb_error(TB_ERR_NOMEM, "radiosity: out of memory");
    tb_pqueue_init(&s->q);
    s->opt = o;
    s->nc = nc;
    bool ok = true;
    s->m = *mesh;
    s->m.patch = NULL, s->m.patch_poly = NULL, s->m.npatches = 0; /* copied below */
    s->m.verts = tb__calloc(nv, sizeof *s->m.verts, &ok);
    s->m.elems = tb__calloc(ne, sizeof *s->m.elems, &ok);
    s->m.rho = tb__calloc(ne * (size_t)nc, sizeof *s->m.rho, &ok);
    s->m.emission = tb__calloc(ne * (size_t)nc, sizeof *s->m.emission, &ok);
    bool hemi = o.ff == TB_RAD_FF_HEMICUBE;
    s->nrecv = hemi ? ne : nv;
    s->He = tb__calloc(ne * (size_t)nc, sizeof *s->He, &ok);
    s->Hv = tb__calloc(nv * (size_t)nc, sizeof *s->Hv, &ok);
    s->dB = tb__calloc(ne * (size_t)nc, sizeof *s->dB, &ok);
    s->up = tb__calloc(ne, sizeof *s->up, &ok);
    s->eabs = tb__calloc(ne, sizeof *s->eabs, &ok);
    s->erec = tb__calloc(ne, sizeof *s->erec, &ok);
    s->ff = tb__calloc(s->nrecv, sizeof *s->ff, &ok);
    s->vff = tb__calloc(nv, sizeof *s->vff, &ok);
    s->eff = tb__calloc(ne, sizeof *s->eff, &ok);
    s->nsh = mesh->npatches > 0 ? mesh->npatches : ne;
    s->nblk = s->nsh < TB__RAD_UNSHOT_BLOCKS ? s->nsh : TB__RAD_UNSHOT_BLOCKS;
    if (!o.no_cache)
        s->cache = tb__calloc(s->nsh, sizeof *s->cache, &ok);
    s->pof = tb__calloc(ne, sizeof *s->pof, &ok);
    s->pstart = tb__calloc(s->nsh + 1, sizeof *s->pstart, &ok);
    s->pel = tb__calloc(ne, sizeof *s->pel, &ok);
    s->spoly = tb__calloc(s->nsh, sizeof *s->spoly, &ok);
    s->sarea = tb__calloc(s->nsh, sizeof *s->sarea, &ok);
    s->scen = tb__calloc(s->nsh, sizeof *s->scen, &ok);
    s->snrm = tb__calloc(s->nsh, sizeof *s->snrm, &ok);
    s->sdirty = tb__calloc(s->nsh, sizeof *s->sdirty, &ok);
    s->polys = tb__calloc(ne, sizeof *s->polys, &ok);
    s->erad = tb__calloc(ne, sizeof *s->erad, &ok);
    s->rho_mean = tb__calloc((size_t)nc, sizeof *s->rho_mean, &ok);
    if (hemi) {
        s->vert_area = tb__calloc(nv, sizeof *s->vert_area, &ok);
    } else {
        s->rp = tb__calloc(nv, sizeof *s->rp, &ok);
        s->rn = tb__calloc(nv, sizeof *s->rn, &ok);
        s->pts = tb__calloc((size_t)o.samples, sizeof *s->pts, &ok);
        s->gnear = tb__calloc(ne, sizeof *s->gnear, &ok);
        s->vvis = tb__calloc(nv, sizeof *s->vvis, &ok);
        s->near_list = tb__calloc(ne, sizeof *s->near_list, &ok);
    }
    if (!ok || tb_pqueue_reserve(&s->q, ne)) {
        tb_rad_solver_free(s);
        return tb_error(TB_ERR_NOMEM, "radiosity: out of memory");
    }
    memcpy(s->m.verts, mesh->verts, nv * sizeof *s->m.verts);
    memcpy(s->m.elems, mesh->elems, ne * sizeof *s->m.elems);
    memcpy(s->m.rho, mesh->rho, ne * (size_t)nc * sizeof *s->m.rho);
    memcpy(s->m.emission, mesh->emission, ne * (size_t)nc * sizeof *s->m.emission);
    for (size_t i = 0; i < ne; i++) {
        tb_rad_mesh_polygon(&s->m, i, &s->polys[i]);
        s->erad[i] = sqrt(tb__radius2(&s->polys[i], s->m.elems[i].centroid));
    }
    {
        tb_status st = tb_rad_mesh_copy_patches(&s->m, mesh, NULL);
        if (!st)
            st = tb__shooters_init(s);
        if (st) {
            tb_rad_solver_free(s);
            return st;
        }
    }

    /* state */
    if (state && state->gathered)
        memcpy(hemi ? s->He : s->Hv, state->gathered, s->nrecv * (size_t)nc * sizeof(double));
    if (!hemi && state && state->gathered_elems)
        memcpy(s->He, state->gathered_elems, ne * (size_t)nc * sizeof(double));
    else if (!hemi) {
        /* elements start from the mean of their corners */
        for (size_t i = 0; i < ne; i++) {
            const tb_rad_element *e = &s->m.elems[i];
            int n = e->v[3] == TB_RAD_NONE ? 3 : 4;
            for (int c = 0; c < nc; c++) {
                double h = 0.0;
                for (int k = 0; k < n; k++)
                    h += s->Hv[e->v[k] * (size_t)nc + (size_t)c];
                s->He[i * (size_t)nc + (size_t)c] = h / n;
            }
        }
    }
    for (size_t i = 0; i < ne * (size_t)nc; i++)
        s->dB[i] = state && state->unshot ? state->unshot[i] : (double)s->m.emission[i];
    double unshot = 0.0;
    for (size_t i = 0; i < ne; i++) {
        const tb_rad_element *e = &s->m.elems[i];
        s->total_area += e->area;
        for (int c = 0; c < nc; c++) {
            s->emitted += (double)s->m.emission[i * (size_t)nc + (size_t)c] * e->area;
            s->rho_mean[c] += (double)s->m.rho[i * (size_t)nc + (size_t)c] * e->area;
            double d = s->dB[i * (size_t)nc + (size_t)c];
            if (!(d >= 0.0) || !isfinite(d)) {
                tb_rad_solver_free(s);
                return tb_error(TB_ERR_ARG, "radiosity: element %zu: bad initial unshot radiosity %g", i, d);
            }
        }
        double p = tb__unshot_power(s, i);
        s->up[i] = p;
        unshot += p;
    }
    s->scan = mesh->npatches == 0 && !(o.exchange && o.exchange->ranks > 1);
    for (size_t k = 0; k < s->nsh && !s->scan; k++) {
        double p = tb__shooter_power(s, k);
        if (p > 0.0)
            tb_pqueue_set(&s->q, (uint32_t)k, p);
    }
    for (int c = 0; c < nc; c++)
        s->rho_mean[c] /= s->total_area;
    tb__reflectance_rows(s);
    s->avx = tb__rad_have_avx();
    if (o.nlights > 0) {
        tb_status st = tb__lights_init(s, state);
        if (st) {
            tb_rad_solver_free(s);
            return st;
        }
        unshot += s->lpending;
    }
    /* what is no longer unshot has been absorbed (the bookkeeping of a continued solution) */
    s->absorbed = s->emitted > unshot ? s->emitted - unshot : 0.0;
    if (hemi) {
        for (size_t i = 0; i < ne; i++) {
            const tb_rad_element *e = &s->m.elems[i];
            for (int k = 0; k < 4 && (k < 3 || e->v[k] != TB_RAD_NONE); k++)
                s->vert_area[e->v[k]] += e->area;
        }
        for (size_t i = 0; i < ne; i++) {
            const tb_rad_element *e = &s->m.elems[i];
            for (int k = 0; k < 4 && (k < 3 || e->v[k] != TB_RAD_NONE); k++) {
                double w = e->area / s->vert_area[e->v[k]];
                for (int c = 0; c < nc; c++)
                    s->Hv[e->v[k] * (size_t)nc + (size_t)c] += w * s->He[i * (size_t)nc + (size_t)c];
            }
        }
        s->hc = tb_hemicube_create(o.hemicube_res);
        if (!s->hc) {
            tb_status st = tb_error_context(TB_ERR_NOMEM, "radiosity: hemicube");
            tb_rad_solver_free(s);
            return st;
        }
    } else {
        /* Receivers sit a hair inside their surface: the point form factor
         * is discontinuous at an edge (a point on the floor's edge sees the
         * wall beside it edge-on and half its hemisphere behind it, so it
         * gets half the irradiance of a point just inside; a corner a
         * quarter), and the vertex stands for the limit from inside. Each
         * vertex moves TB__RAD_RECEIVER_INSET of the way to the area-weighted
         * centroid of its elements. */
        double *acc = calloc(nv * 4, sizeof *acc);
        if (!acc) {
            tb_rad_solver_free(s);
            return tb_error(TB_ERR_NOMEM, "radiosity: out of memory");
        }
        for (size_t i = 0; i < ne; i++) {
            const tb_rad_element *e = &s->m.elems[i];
            for (int k = 0; k < tb__elem_size(e); k++) {
                double *a = acc + (size_t)e->v[k] * 4;
                a[0] += e->area * e->centroid.x, a[1] += e->area * e->centroid.y, a[2] += e->area * e->centroid.z;
                a[3] += e->area;
            }
        }
        for (size_t v = 0; v < nv; v++) {
            tb_vec3 p = s->m.verts[v].p;
            const double *a = acc + v * 4;
            if (a[3] > 0.0) {
                double t = TB__RAD_RECEIVER_INSET;
                p = tb_vec3_make((float)(p.x + t * (a[0] / a[3] - p.x)), (float)(p.y + t * (a[1] / a[3] - p.y)),
                                 (float)(p.z + t * (a[2] / a[3] - p.z)));
            }
            s->rp[v] = p, s->rn[v] = s->m.verts[v].n;
        }
        free(acc);
        for (size_t i = 0; i < ne; i++)
            s->gnear[i] = NAN;
        if (!s->opt.batch) {
            s->opt.batch = tb_ff_raycast_batch;
            s->opt.batch_ctx = NULL;
            if (!o.no_occlusion) {
                /* the room's walls cannot occlude: build over the rest */
                tb_ff_polygon *occ = malloc(ne * sizeof *occ);
                if (!occ) {
                    tb_rad_solver_free(s);
                    return tb_error(TB_ERR_NOMEM, "radiosity: out of memory");
                }
                size_t nocc = tb_rad_mesh_occluders(&s->m, occ);
                tb_status st = tb_ff_occluders_build(occ, nocc, &s->occ);
                if (!st)
                    st = tb__occluder_boxes(s, occ, nocc);
                if (!st)
                    st = tb__receiver_clusters(s);
                if (!st && o.exchange && o.exchange->ranks > 1)
                    st = tb__exchange_init(s, o.exchange);
                free(occ);
                if (st) {
                    tb_rad_solver_free(s);
                    return st;
                }
                s->opt.batch_ctx = s->occ;
            }
        }
    }
    *out = s;
    return TB_OK;
}


static void tb__near_field(tb_rad_solver *s, size_t i);
static void tb__shoot(tb_rad_solver *s, uint32_t i, double t0);
static tb_status tb__cache_store(tb_rad_solver *s, size_t k);
static tb_status tb__step_several(tb_rad_solver *s, const tb_rad_exchange *ex, bool *shot);
static void tb__hemicube_near_patch(tb_rad_solver *s, size_t k);
static tb_status tb__shot_formfactors(tb_rad_solver *s, size_t i, bool share);
static tb_status tb__select(tb_rad_solver *s);

/* Most bytes of form factors kept for shooters shot again. */
#define TB__RAD_CACHE_BYTES ((size_t)512 << 20)

/* The form factors of shooter i, rounded to float (whether cached or not, so
 * that caching never changes an answer): s->vff[v] = F(v -> i) for every
 * vertex (ray cast) and s->eff[j] = F_ji for every element (0 for the
 * shooter's own elements). */
static tb_status tb__shooter_ff(tb_rad_solver *s, size_t k, bool share)
{
    size_t nv = s->m.nverts, ne = s->m.nelems;
    bool hemi = s->opt.ff == TB_RAD_FF_HEMICUBE;
    size_t nvf = hemi ? 0 : nv;
    if (s->cache && s->cache[k]) {
        memcpy(s->vff, s->cache[k], nvf * sizeof(float));
        memcpy(s->eff, s->cache[k] + nvf, ne * sizeof(float));
        tb_stat_add(&tb__rad_cached, 1);
        return TB_OK;
    }
    tb_status st = tb__shot_formfactors(s, k, share);
    if (st)
        return st;
    if (hemi) {
        for (size_t j = 0; j < ne; j++)
            s->eff[j] = s->pof[j] == k ? 0.0f : (float)(s->ff[j] * s->sarea[k] / s->m.elems[j].area);
        if (s->pstart[k + 1] - s->pstart[k] > 1)
            tb__hemicube_near_patch(s, k);
    } else {
        for (size_t v = 0; v < nv; v++)
            s->vff[v] = (float)s->ff[v];
        uint32_t qa, qb; /* a split solve: this process's elements only (the others' are not read) */
        tb__owned(s, &qa, &qb);
        for (uint32_t q = qa; q < qb; q++) {
            size_t j = s->pel[q];
            double g = s->gnear[j];
            if (isnan(g)) {
                /* F_ji: the element's mean of its corners' point form factors */
                const tb_rad_element *ej = &s->m.elems[j];
                int n = tb__elem_size(ej);
                g = 0.0;
                for (int k = 0; k < n; k++)
                    g += s->vff[ej->v[k]];
                g /= n;
            }
            s->eff[j] = s->pof[j] == k ? 0.0f : (float)g;
        }
        for (size_t k = 0; k < s->nnear; k++)
            s->gnear[s->near_list[k]] = NAN;
        s->nnear = 0;
    }
    return tb__cache_store(s, k);
}

/* Keeps s->vff and s->eff as shooter k's cached form factors, if it has
 * none yet and the cache has room (the same rule on every process). Over
 * several processes a failed allocation is an error: the caches must stay
 * the same everywhere, since a shooter cached everywhere is shot without an
 * exchange; in one process it only leaves the shooter uncached. */
static tb_status tb__cache_store(tb_rad_solver *s, size_t k)
{
    size_t nvf = s->opt.ff == TB_RAD_FF_HEMICUBE ? 0 : s->m.nverts, ne = s->m.nelems;
    size_t bytes = (nvf + ne) * sizeof(float);
    if (s->cache && !s->cache[k] && s->cache_bytes + bytes <= TB__RAD_CACHE_BYTES) {
        float *c = tb_fault("rad-cache") ? NULL : malloc(bytes);
        if (!c) {
            if (s->opt.exchange && s->opt.exchange->ranks > 1)
                return tb_error(TB_ERR_NOMEM, "radiosity: out of memory caching the form factors of shooter %zu "
                                "(%zu bytes)", k, bytes);
            return TB_OK;
        }
        memcpy(c, s->vff, nvf * sizeof(float));
        memcpy(c + nvf, s->eff, ne * sizeof(float));
        s->cache[k] = c;
        s->cache_bytes += bytes;
    }
    return TB_OK;
}

/* Form factors of one shot from shooter k: s->ff[r] for every receiver.
 * share: over several processes, each computes its receiver clusters and
 * they gather (else this process computes them all). */
static tb_status tb__shot_formfactors(tb_rad_solver *s, size_t k, bool share)
{
    tb_timer_token tt = tb_timer_start(&tb__rad_ff_time);
    tb_status st;
    if (s->opt.ff == TB_RAD_FF_HEMICUBE) {
        /* a one-element shooter is left out of its hemicube; a patch's own
         * elements lie in its plane (and get F = 0 in tb__shooter_ff) */
        uint32_t skip = s->pstart[k + 1] - s->pstart[k] == 1 ? s->pel[s->pstart[k]] : UINT32_MAX;
        st = tb_hemicube_formfactors(s->hc, s->scen[k], s->snrm[k], s->polys, s->m.nelems, skip, s->ff);
    } else {
        st = tb_ff_sample_polygon(&s->spoly[k], s->opt.samples, tb__shot_seed(s->opt.seed, k), s->pts);
        if (!st)
            st = s->boxes ? tb__batch(s, k, share)
                          : s->opt.batch(s->opt.batch_ctx, s->pts, s->opt.samples, s->snrm[k], s->sarea[k], s->rp,
                                         s->rn, s->m.nverts, s->ff);
        tb_stat_add(&tb__rad_rays, (int64_t)s->m.nverts * s->opt.samples);
        if (!st)
            tb__near_field(s, k);
        s->vnear_done = s->enf_done = false;
    }
    tb_stat_add(&tb__rad_ffs, (int64_t)s->nrecv);
    (void)tb_timer_stop(tt);
    return st;
}

/* Cells per side of the midpoint grid of tb__element_mean_ff. */
#define TB__RAD_NEAR_GRID 4

/* Bilinear point (u, v) of the quad q (a triangle as v0 v1 v2 v2). */
static tb_vec3 tb__bilerp(const tb_vec3 *q, double u, double v)
{
    double w[4] = {(1 - u) * (1 - v), u * (1 - v), u * v, (1 - u) * v};
    double x = 0, y = 0, z = 0;
    for (int k = 0; k < 4; k++)
        x += w[k] * q[k].x, y += w[k] * q[k].y, z += w[k] * q[k].z;
    return tb_vec3_make((float)x, (float)y, (float)z);
}

/* Two levels, near a patch: F_jp, the mean over element j of the exact
 * point-to-polygon form factor to the patch outline, by the midpoint rule on
 * a TB__RAD_NEAR_GRID^2 grid of j weighted by cell area. A patch is larger
 * than its receivers, so averaging over the small side (j) is the accurate
 * one; the shooter's few sample points over the whole patch left elements
 * along the edges of the furnace 6% off. */
static double tb__element_mean_ff(const tb_ff_polygon *pj, tb_vec3 nj, const tb_ff_polygon *shooter)
{
    tb_vec3 q[4] = {pj->v[0], pj->v[1], pj->v[2], pj->n == 4 ? pj->v[3] : pj->v[2]};
    const int n = TB__RAD_NEAR_GRID;
    double sum = 0.0, wsum = 0.0;
    for (int a = 0; a < n; a++)
        for (int b = 0; b < n; b++) {
            double u0 = (double)a / n, u1 = (double)(a + 1) / n, v0 = (double)b / n, v1 = (double)(b + 1) / n;
            tb_vec3 c[4] = {tb__bilerp(q, u0, v0), tb__bilerp(q, u1, v0), tb__bilerp(q, u1, v1), tb__bilerp(q, u0, v1)};
            double nn[3] = {0, 0, 0};
            for (int k = 0; k < 4; k++) {
                tb_vec3 p0 = c[k], p1 = c[(k + 1) % 4];
                nn[0] += ((double)p0.y - p1.y) * ((double)p0.z + p1.z);
                nn[1] += ((double)p0.z - p1.z) * ((double)p0.x + p1.x);
                nn[2] += ((double)p0.x - p1.x) * ((double)p0.y + p1.y);
            }
            double w = 0.5 * sqrt(nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2]);
            double f = tb_ff_point_polygon(tb__bilerp(q, 0.5 * (u0 + u1), 0.5 * (v0 + v1)), nj, shooter);
            if (f > 0.0 && isfinite(f))
                sum += w * f;
            wsum += w;
        }
    return wsum > 0.0 ? sum / wsum : 0.0;
}


/* Whether element j can come within TB__RAD_NEAR shooter radii `rad` of the
 * shooter's centroid cen: its centroid lies within that plus its own radius. */
static bool tb__near_element(const tb_rad_solver *s, size_t j, tb_vec3 cen, double rad)
{
    const tb_rad_element *ej = &s->m.elems[j];
    double lim = TB__RAD_NEAR * rad + s->erad[j];
    return !((double)tb_vec3_length2(tb_vec3_sub(ej->centroid, cen)) >= lim * lim); /* !(>=): a NaN counts as near */
}

/* The exact unoccluded form factor of near element j with shooter sk:
 * F_jp from a patch (two levels), else F_ij, the mean over the shot's
 * sample points (s->pts) of the point-to-polygon form factor to j. */
static double tb__near_element_ff(const tb_rad_solver *s, size_t sk, size_t j)
{
    const tb_ff_polygon *pj = &s->polys[j];
    if (s->pstart[sk + 1] - s->pstart[sk] > 1)
        return tb__element_mean_ff(pj, s->m.elems[j].normal, &s->spoly[sk]); /* F_jp itself */
    double f = 0.0;
    for (int k = 0; k < s->opt.samples; k++) {
        double x = tb_ff_point_polygon(s->pts[k], s->snrm[sk], pj);
        if (x > 0.0 && isfinite(x))
            f += x;
    }
    return f / s->opt.samples;
}

/* Two levels, hemicube: one hemicube at the patch's centroid stands for
 * the whole patch, which is poor for the elements next to it (the furnace's
 * edges were 7.5% off). Within TB__RAD_NEAR patch radii, F_jp becomes the
 * exact unoccluded mean over j (tb__element_mean_ff) times the fraction of
 * j the hemicube saw: its F_pj over the exact unoccluded form factor from
 * the centroid to j (1 where that is 0: nothing measured). */
static void tb__hemicube_near_patch(tb_rad_solver *s, size_t k)
{
    const tb_ff_polygon *poly = &s->spoly[k];
    const tb_vec3 cen = s->scen[k], nrm = s->snrm[k];
    double rad = sqrt(tb__radius2(poly, cen));
    for (size_t j = 0; j < s->m.nelems; j++) {
        if (s->pof[j] == k || !tb__near_element(s, j, cen, rad))
            continue;
        const tb_rad_element *ej = &s->m.elems[j];
        const tb_ff_polygon *pj = &s->polys[j];
        double open = tb_ff_point_polygon(cen, nrm, pj), vis = 1.0;
        if (open > 0.0 && isfinite(open))
            vis = fmin(1.0, s->ff[j] / open);
        s->eff[j] = (float)(tb__element_mean_ff(pj, ej->normal, poly) * vis);
    }
}

/* Near the shooter the sampled estimate (a disk per sample point) is poor:
 * a receiver at a shared edge sees the shooter at distances down to zero.
 * There (within TB__RAD_NEAR shooter radii of its centroid)
 *  - a vertex's form factor is the exact unoccluded point-to-polygon one
 *    times the visible fraction the samples measured (their occluded over
 *    their unoccluded estimate);
 *  - an element's F_ji, which moves the energy, is not the mean of its
 *    corners (the point form factor varies far from linearly across an
 *    element next to the shooter, and the corner mean loses up to a third
 *    of the power of a shooter in a corner) but, by reciprocity,
 *    A_i / A_j times F_ij, F_ij the mean over the shooter's sample points of
 *    the exact point-to-polygon form factor to j, times the mean visible
 *    fraction of j's corners; from a patch (two levels), F_jp directly as
 *    the mean over j of the exact form factor to the patch
 *    (tb__element_mean_ff), times the same visible fraction. */
static void tb__near_field(tb_rad_solver *s, size_t sk)
{
    const tb_ff_polygon *poly = &s->spoly[sk];
    const tb_vec3 cen = s->scen[sk];
    const double area = s->sarea[sk];
    double rad = sqrt(tb__radius2(poly, cen));
    if (!s->vnear_done) { /* (tb__batch does the vertices with their clusters) */
        const tb__near_shooter near = tb__near_of(s, sk);
        for (size_t v = 0; v < s->m.nverts; v++)
            tb__near_vertex(s, v, &near);
    }
    s->nnear = 0;
    uint32_t qa, qb; /* a split solve: this process's elements only */
    tb__owned(s, &qa, &qb);
    for (uint32_t q = qa; q < qb; q++) {
        size_t j = s->pel[q];
        if (s->pof[j] == sk || !tb__near_element(s, j, cen, rad))
            continue;
        const tb_rad_element *ej = &s->m.elems[j];
        const tb_ff_polygon *pj = &s->polys[j];
        bool patch = s->pstart[sk + 1] - s->pstart[sk] > 1;
        double f = s->enf_done ? s->enf[j] : tb__near_element_ff(s, sk, j);
        double vis = 0.0;
        for (int k = 0; k < pj->n; k++) {
            double x = s->vvis[ej->v[k]];
            vis += isnan(x) ? 1.0 : x;
        }
        vis /= pj->n;
        s->gnear[j] = (patch ? f : f * area / ej->area) * vis;
        s->near_list[s->nnear++] = j;
    }
}

tb_status tb_rad_solver_step(tb_rad_solver *s, bool *shot)
{
    if (shot)
        *shot = false;
    if (s->lights && s->lpending > 0.0) {
        bool done = false;
        tb_status st = tb__lights_step(s, &done);
        if (st || done) {
            if (shot)
                *shot = done;
            return st;
        }
    }
    const tb_rad_exchange *ex = s->opt.exchange;
    if (ex && ex->ranks > 1 && ex->several)
        return tb__step_several(s, ex, shot);
    uint32_t i; /* the shooter: a patch, or an element on one level */
    double pri;
    if (s->split) /* the processes agreed on it after the last shot */
        i = (uint32_t)s->sel[2], pri = s->sel[1];
    else if (!tb__top(s, &i, &pri))
        return TB_OK;
    if (!(pri > 0.0))
        return TB_OK;
    double t0 = tb__now();
    tb_status st = tb__shooter_ff(s, i, true);
    if (st)
        return st;
    tb__shoot(s, i, t0);
    if (s->split) {
        tb_stat_add(&tb__rad_split_shots, 1);
        if ((st = tb__select(s)))
            return st;
    }
    if (shot)
        *shot = true;
    return TB_OK;
}

/* A split solve: every process offers its best shooter (its unshot
 * radiosity per channel with it) and its blocks' unshot sums; all get the
 * best of all (ties: the lower key, as one queue would) and every block's
 * sum. Collective. */
static tb_status tb__select(tb_rad_solver *s)
{
    const tb_rad_exchange *ex = s->opt.exchange;
    size_t nc = (size_t)s->nc, h = 3 + nc, n = h + s->nblk;
    double *b = s->sel;
    memset(b, 0, n * sizeof *b);
    b[0] = (double)h;
    uint32_t k;
    double pri;
    if (tb_pqueue_peek(&s->q, &k, &pri)) {
        b[1] = pri, b[2] = (double)k;
        tb__shooter_dbi(s, k, b + 3);
    } else {
        b[1] = -INFINITY, b[2] = (double)UINT32_MAX; /* none: loses to any shooter */
    }
    size_t R = (size_t)ex->ranks, r = (size_t)ex->rank;
    for (size_t blk = r * s->nblk / R; blk < (r + 1) * s->nblk / R; blk++)
        b[h + blk] = tb__block_unshot(s, blk);
    return ex->select(ex->ctx, b, n);
}

/* Whether a run splits the update over the processes: ray cast over the
 * shared clusters in the deterministic mode, no lights (shot whole, on
 * every process), and nothing that reads the whole state between shots
 * (a report: checkpoints and --report rows keep the replicated update). */
static bool tb__can_split(const tb_rad_solver *s, bool report)
{
    const tb_rad_exchange *ex = s->opt.exchange;
    return ex && ex->ranks > 1 && !ex->several && s->sel && s->xcounts && !s->lights && !report;
}

/* Starts a split run (collective): the queue keeps this process's shooters
 * only, and the processes agree on the first shooter. */
static tb_status tb__split_begin(tb_rad_solver *s)
{
    for (size_t k = 0; k < s->nsh; k++)
        if (k < s->k0 || k >= s->k1)
            tb_pqueue_remove(&s->q, (uint32_t)k);
    s->split = true;
    return tb__select(s);
}

/* Ends a split run (collective): every process gets every element's and
 * vertex's state, the whole queue, and an empty cache (this run's entries
 * hold this process's elements only). */
static tb_status tb__split_end(tb_rad_solver *s)
{
    const tb_rad_exchange *ex = s->opt.exchange;
    size_t nc = (size_t)s->nc, R = (size_t)ex->ranks, nv = s->m.nverts;
    size_t nmine = s->xstcounts[ex->rank];
    double *mine = malloc((nmine ? nmine : 1) * sizeof *mine);
    if (!mine)
        return tb_error(TB_ERR_NOMEM, "radiosity: out of memory gathering the state");
    /* this process's part: per element (pel order) He, dB, up, eabs, erec; its vertices' Hv */
    size_t n = 0;
    for (uint32_t q = s->pstart[s->k0]; q < s->pstart[s->k1]; q++) {
        size_t j = s->pel[q];
        memcpy(mine + n, s->He + j * nc, nc * sizeof *mine), n += nc;
        memcpy(mine + n, s->dB + j * nc, nc * sizeof *mine), n += nc;
        mine[n++] = s->up[j], mine[n++] = s->eabs[j], mine[n++] = s->erec[j];
    }
    memcpy(mine + n, s->Hv + s->v0 * nc, (s->v1 - s->v0) * nc * sizeof *mine), n += (s->v1 - s->v0) * nc;
    tb_status st = ex->allgather_state(ex->ctx, mine, n, s->xst, s->xstcounts);
    free(mine);
    if (st)
        return st;
    const double *all = s->xst;
    for (size_t r = 0, at = 0; r < R; r++) {
        size_t ka = tb__block_start(s, r * s->nblk / R), kb = tb__block_start(s, (r + 1) * s->nblk / R);
        for (uint32_t q = s->pstart[ka]; q < s->pstart[kb]; q++) {
            size_t j = s->pel[q];
            memcpy(s->He + j * nc, all + at, nc * sizeof *all), at += nc;
            memcpy(s->dB + j * nc, all + at, nc * sizeof *all), at += nc;
            s->up[j] = all[at++], s->eabs[j] = all[at++], s->erec[j] = all[at++];
        }
        size_t va = r * nv / R, vb = (r + 1) * nv / R;
        memcpy(s->Hv + va * nc, all + at, (vb - va) * nc * sizeof *all), at += (vb - va) * nc;
    }
    s->split = false;
    tb__queue_rebuild(s);
    if (s->cache) {
        for (size_t k = 0; k < s->nsh; k++)
            free(s->cache[k]), s->cache[k] = NULL;
        s->cache_bytes = 0;
    }
    return TB_OK;
}

/* Shoots shooter i with the form factors in s->vff and s->eff: its unshot
 * power goes to every receiver, the queue follows. t0: the clock when the
 * shot began (its seconds). */
static void tb__shoot(tb_rad_solver *s, uint32_t i, double t0)
{
    int nc = s->nc;
    tb_timer_token tt = tb_timer_start(&tb__rad_update_time);
    /* the patch shoots its elements' unshot power as one density over its area */
    /* (a split solve: as its owner computed it for the selection) */
    double dBi[TB_CHANNELS_MAX];
    uint32_t pa = s->pstart[i], pb = s->pstart[i + 1];
    /* deferred (a cached shooter inside tb_rad_solver_run): this shot is
     * logged for Hv and He (and on one level dB; its own dBi comes from the
     * log); else whatever is logged is replayed first, then all of it now */
    bool defer = s->defer && !s->split && s->cache && s->cache[i];
    bool defer_db = defer && s->m.npatches == 0;
    if (!defer)
        tb__defer_flush(s);
    if (s->split)
        memcpy(dBi, s->sel + 3, (size_t)nc * sizeof *dBi);
    else if (defer_db)
        tb__pending_dB(s, i, dBi); /* one level: shooter i is element i, dBi its dB */
    else
        tb__shooter_dbi(s, i, dBi);
    for (uint32_t q = pa; q < pb && !defer_db; q++) /* (a replay zeroes them in order) */
        for (int c = 0; c < nc; c++)
            s->dB[s->pel[q] * (size_t)nc + (size_t)c] = 0.0;
    double shot_power = 0.0;
    for (int c = 0; c < nc; c++)
        shot_power += dBi[c] * s->sarea[i];
    s->shot_total += shot_power;
    /* receivers gather */
    if (s->opt.ff == TB_RAD_FF_HEMICUBE) {
        for (size_t j = 0; j < s->m.nelems; j++) {
            double g = s->eff[j]; /* F_ji */
            if (!(g > 0.0))
                continue;
            const tb_rad_element *ej = &s->m.elems[j];
            double rec = 0.0, abs_ = 0.0;
            for (int c = 0; c < nc; c++) {
                double dh = dBi[c] * g, rho = s->m.rho[j * (size_t)nc + (size_t)c];
                s->He[j * (size_t)nc + (size_t)c] += dh;
                s->dB[j * (size_t)nc + (size_t)c] += rho * dh;
                rec += dh * ej->area;
                abs_ += (1.0 - rho) * dh * ej->area;
                for (int k = 0; k < tb__elem_size(ej); k++)
                    s->Hv[ej->v[k] * (size_t)nc + (size_t)c] += dh * ej->area / s->vert_area[ej->v[k]];
            }
            s->erec[j] += rec;
            s->eabs[j] += abs_;
            s->up[j] = tb__unshot_power(s, j);
            tb__queue_elem(s, j);
        }
    } else {
        /* restrict: the arrays never overlap, which lets the channel loops
         * vectorise (the same operations in the same order). Serial: one
         * shot's update is a few tens of microseconds, about what waking
         * the other threads costs with passive waits, and under load a
         * parallel update was slower. */
        double *restrict Hv = s->Hv, *restrict He = s->He, *restrict dB = s->dB;
        const float *restrict rhos = s->m.rho;
        size_t ncs = (size_t)nc;
        double sum_dbi = tb__sum(dBi, ncs);
        if (s->rrow)
            for (size_t k = 0; k < s->nrows; k++)
                s->row_dot[k] = tb__dot(rhos + (size_t)s->row_elem[k] * ncs, dBi, ncs);
        size_t va = s->split ? s->v0 : 0, vb = s->split ? s->v1 : s->m.nverts;
        uint32_t qa, qb; /* each element's update is its own: any split gives the same values */
        tb__owned(s, &qa, &qb);
        /* the channel loops (update_internal.h: AVX where the CPU has it),
         * then the scalars per element */
        tb__rad_update u = {ncs, dBi, s->vff, s->eff, s->pel, s->pof, i, rhos, Hv, defer ? NULL : He,
                            defer_db ? NULL : dB};
        if (!defer)
            (s->avx ? tb__rad_update_vertices_avx : tb__rad_update_vertices)(&u, va, vb);
        if (!defer_db)
            (s->avx ? tb__rad_update_elements_avx : tb__rad_update_elements)(&u, qa, qb);
        if (defer) {
            s->dlog[s->ndlog] = i;
            memcpy(s->dlog_dbi + s->ndlog * ncs, dBi, ncs * sizeof *dBi);
            if (++s->ndlog == TB__RAD_DEFER_MAX)
                tb__defer_flush(s);
        }
        for (uint32_t q = qa; q < qb; q++) {
            size_t j = s->pel[q];
            double g = s->eff[j];
            if (s->pof[j] == i || !(g > 0.0)) /* the shooting patch's own elements get nothing */
                continue;
            double aj = s->m.elems[j].area;
            /* received: sum_c dBi g aj; reflected (what joins the unshot
             * power): sum_c rho dBi g aj, per distinct reflectance row */
            double rec = sum_dbi * g * aj;
            double refl = (s->rrow ? s->row_dot[s->rrow[j]] : tb__dot(rhos + j * ncs, dBi, ncs)) * g * aj;
            s->erec[j] += rec;
            s->eabs[j] += rec - refl;
            s->up[j] += refl; /* = tb__unshot_power(s, j) up to rounding */
            tb__queue_elem(s, j);
        }
    }
    tb__queue_flush(s);
    tb_pqueue_remove(&s->q, i);
    for (uint32_t q = pa; q < pb; q++)
        s->up[s->pel[q]] = 0.0; /* = tb__unshot_power: its dB is 0 */
    (void)tb_timer_stop(tt);
    s->shots++;
    tb_stat_add(&tb__rad_shots, 1);
    s->seconds += tb__now() - t0;
}

/* Several shooters in flight (Recker, George and Greenberg 1990), one per
 * process: the `ranks` shooters of most unshot power are taken at once,
 * each process computes one shooter's form factors whole, the processes
 * exchange them, and every process shoots them all in rank order. Fewer
 * exchanges, none of them waiting on the others' rays, but the shooters of
 * a group are chosen before the group's earlier shots are made: another
 * (deterministic, for a given number of processes) order than one process. */
static tb_status tb__step_several(tb_rad_solver *s, const tb_rad_exchange *ex, bool *shot)
{
    size_t R = (size_t)ex->ranks, nvf = s->opt.ff == TB_RAD_FF_HEMICUBE ? 0 : s->m.nverts, ne = s->m.nelems;
    size_t per = nvf + ne; /* values one shooter's form factors take */
    uint32_t keys[TB_RAD_MAX_IN_FLIGHT];
    size_t n = 0;
    double pri;
    double t0 = tb__now();
    while (n < R && n < TB_RAD_MAX_IN_FLIGHT && tb_pqueue_peek(&s->q, &keys[n], &pri) && pri > 0.0) {
        tb_pqueue_remove(&s->q, keys[n]);
        n++;
    }
    if (n == 0)
        return TB_OK;
    if (!s->xsev) {
        s->xsev = malloc(per * sizeof *s->xsev);
        s->xsevall = malloc(per * R * sizeof *s->xsevall);
        s->xsevcounts = malloc(R * sizeof *s->xsevcounts);
        if (!s->xsev || !s->xsevall || !s->xsevcounts)
            return tb_error(TB_ERR_NOMEM, "radiosity: out of memory for shooters in flight");
        for (size_t r = 0; r < R; r++)
            s->xsevcounts[r] = per;
    }
    /* every process keeps the same cache (each stores every gathered
     * shooter under the same byte limit), so each knows without asking
     * whether the whole group is cached: then there is nothing to compute
     * or exchange. (A malloc that fails on one process only would break
     * this; the processes would then wait for each other.) */
    bool all_cached = s->cache != NULL;
    for (size_t k = 0; k < n && all_cached; k++)
        all_cached = s->cache[keys[k]] != NULL;
    if (all_cached) {
        for (size_t k = 0; k < n; k++) {
            tb_status st = tb__shooter_ff(s, keys[k], false); /* from the cache */
            if (st)
                return st;
            tb__shoot(s, keys[k], k == 0 ? t0 : tb__now());
        }
        if (shot)
            *shot = true;
        return TB_OK;
    }
    /* this process's shooter (none: zeros) */
    size_t me = (size_t)ex->rank;
    if (me < n) {
        tb_status st = tb__shooter_ff(s, keys[me], false);
        if (st)
            return st;
        for (size_t v = 0; v < nvf; v++)
            s->xsev[v] = s->vff[v];
        for (size_t j = 0; j < ne; j++)
            s->xsev[nvf + j] = s->eff[j];
    } else {
        memset(s->xsev, 0, per * sizeof *s->xsev);
    }
    tb_status st = ex->allgatherf(ex->ctx, s->xsev, per, s->xsevall, s->xsevcounts);
    if (st)
        return st;
    for (size_t k = 0; k < n; k++) {
        const float *f = s->xsevall + k * per;
        memcpy(s->vff, f, nvf * sizeof *f);
        memcpy(s->eff, f + nvf, ne * sizeof *f);
        if ((st = tb__cache_store(s, keys[k])))
            return st;
        tb__shoot(s, keys[k], k == 0 ? t0 : tb__now());
    }
    if (shot)
        *shot = true;
    return TB_OK;
}

uint64_t tb_rad_solver_shots(const tb_rad_solver *s) { return s->shots; }

double tb_rad_solver_seconds(const tb_rad_solver *s) { return s->seconds; }

double tb_rad_unshot_fraction(const tb_rad_solver *s)
{
    if (!(s->emitted > 0.0))
        return 0.0;
    /* by blocks (a split solve: the sums the processes shared at its last shot) */
    double u = s->lpending;
    for (size_t b = 0; b < s->nblk; b++)
        u += s->split ? s->sel[3 + (size_t)s->nc + b] : tb__block_unshot(s, b);
    return u / s->emitted;
}

tb_rad_energy tb_rad_solver_energy(const tb_rad_solver *s)
{
    tb_rad_energy e = {.emitted = s->emitted, .absorbed = s->absorbed, .unshot = s->lpending};
    double rec = 0.0;
    for (size_t i = 0; i < s->m.nelems; i++) {
        e.unshot += tb__unshot_power(s, i);
        e.absorbed += s->eabs[i];
        rec += s->erec[i];
    }
    e.escaped = s->escaped + (s->shot_total - rec);
    return e;
}

tb_status tb_rad_solver_run(tb_rad_solver *s, const tb_rad_stop *stop, tb_rad_report_fn report, void *user,
                            uint64_t every)
{
    tb_rad_stop sp = {0};
    if (stop)
        sp = *stop;
    double thr = sp.threshold > 0.0 ? sp.threshold : TB_RAD_DEFAULT_THRESHOLD;
    if (!(thr < 1.0))
        return tb_error(TB_ERR_ARG, "radiosity: threshold %g not below 1", thr);
    if (!(sp.time_budget >= 0.0) || !isfinite(sp.time_budget))
        return tb_error(TB_ERR_ARG, "radiosity: bad time budget %g", sp.time_budget);
    tb_progress pr;
    /* progress in thousandths of the way from fraction 1 down to thr, on a log scale */
    tb_progress_start(&pr, "radiosity", 1000, NULL, 0);
    bool draw = sp.progress && tb_progress_active(&pr);
    int64_t drawn = 0;
    double t0 = tb__now();
    tb_status st = TB_OK;
    uint64_t n = 0;
    bool split = tb__can_split(s, report != NULL);
    if (split && (st = tb__split_begin(s))) {
        if (s->opt.exchange->fail)
            s->opt.exchange->fail(s->opt.exchange->ctx, st);
        return st;
    }
    /* the display sums deferred (tb__defer_flush) where every cached
     * shooter's form factors can be replayed: ray cast, one process */
    s->defer = !split && s->cache && s->opt.ff != TB_RAD_FF_HEMICUBE &&
               !(s->opt.exchange && s->opt.exchange->ranks > 1);
    if (s->defer && !s->dlog) {
        s->dlog = malloc(TB__RAD_DEFER_MAX * sizeof *s->dlog);
        s->dlog_dbi = malloc(TB__RAD_DEFER_MAX * (size_t)s->nc * sizeof *s->dlog_dbi);
        if (!s->dlog || !s->dlog_dbi) { /* then eager updates: the same values */
            free(s->dlog), free(s->dlog_dbi);
            s->dlog = NULL, s->dlog_dbi = NULL, s->defer = false;
        }
    }
    double frac = tb_rad_unshot_fraction(s);
    while (frac >= thr) {
        if (sp.max_shots > 0 && n >= sp.max_shots)
            break;
        if (sp.time_budget > 0.0) {
            /* a clock: over several processes rank 0's reading counts */
            int out_of_time = tb__now() - t0 >= sp.time_budget;
            if (s->opt.exchange && s->opt.exchange->ranks > 1)
                out_of_time = s->opt.exchange->agree(s->opt.exchange->ctx, out_of_time);
            if (out_of_time)
                break;
        }
        bool shot;
        if ((st = tb_rad_solver_step(s, &shot)))
            break;
        if (!shot)
            break;
        n++;
        frac = tb_rad_unshot_fraction(s);
        if (draw) {
            double x = frac > 0.0 ? log(frac) / log(thr) : 1.0;
            int64_t k = (int64_t)(1000.0 * (x < 0.0 ? 0.0 : x > 1.0 ? 1.0 : x));
            if (k > drawn)
                tb_progress_add(&pr, k - drawn), drawn = k;
        }
        if (report && every > 0 && n % every == 0) {
            tb__defer_flush_timed(s); /* the report reads the whole state */
            if ((st = report(user, s)))
                break;
        }
    }
    tb__defer_flush_timed(s);
    s->defer = false;
    if (draw)
        tb_progress_finish(&pr);
    if (!st && split)
        st = tb__split_end(s);
    if (!st && report && (every == 0 || n % every != 0))
        st = report(user, s);
    /* over several processes a failure here is this process's alone (the
     * others are inside an exchange, or shooting cached shooters): only
     * stopping the job stops them */
    if (st && s->opt.exchange && s->opt.exchange->ranks > 1 && s->opt.exchange->fail)
        s->opt.exchange->fail(s->opt.exchange->ctx, st);
    return st;
}

void tb_rad_ambient(const tb_rad_solver *s, double *out)
{
    int nc = s->nc;
    for (int c = 0; c < nc; c++)
        out[c] = 0.0;
    for (size_t i = 0; i < s->m.nelems; i++)
        for (int c = 0; c < nc; c++)
            out[c] += s->dB[i * (size_t)nc + (size_t)c] * s->m.elems[i].area;
    for (int c = 0; c < nc; c++)
        out[c] = out[c] / s->total_area / (1.0 - s->rho_mean[c]);
}

/* Gathered irradiance at vertex v, channel c. */
static inline double tb__Hv(const tb_rad_solver *s, uint32_t v, int c)
{
    return s->Hv[v * (size_t)s->nc + (size_t)c];
}

void tb_rad_element_radiosity(const tb_rad_solver *s, size_t i, bool ambient, double *out)
{
    int nc = s->nc;
    double amb[TB_CHANNELS_MAX] = {0};
    if (ambient)
        tb_rad_ambient(s, amb);
    for (int c = 0; c < nc; c++) {
        double h = s->He[i * (size_t)nc + (size_t)c];
        double rho = s->m.rho[i * (size_t)nc + (size_t)c];
        out[c] = s->m.emission[i * (size_t)nc + (size_t)c] + rho * (h + amb[c]);
    }
}

size_t tb_rad_solver_npatches(const tb_rad_solver *s) { return s->nsh; }

void tb_rad_patch_radiosity(const tb_rad_solver *s, size_t p, bool ambient, double *out)
{
    int nc = s->nc;
    double acc[TB_CHANNELS_MAX] = {0}, b[TB_CHANNELS_MAX];
    for (uint32_t q = s->pstart[p]; q < s->pstart[p + 1]; q++) {
        double a = s->m.elems[s->pel[q]].area;
        tb_rad_element_radiosity(s, s->pel[q], ambient, b);
        for (int c = 0; c < nc; c++)
            acc[c] += a * b[c];
    }
    for (int c = 0; c < nc; c++)
        out[c] = acc[c] / s->sarea[p];
}

double tb_rad_patch_unshot_power(const tb_rad_solver *s, size_t p)
{
    double pri;
    if (s->scan) /* (what the queue would hold: shot elements hold 0) */
        return s->up[p] > 0.0 ? s->up[p] : 0.0;
    return tb_pqueue_get(&s->q, (uint32_t)p, &pri) ? pri : 0.0;
}

void tb_rad_element_unshot(const tb_rad_solver *s, size_t i, double *out)
{
    for (int c = 0; c < s->nc; c++)
        out[c] = s->dB[i * (size_t)s->nc + (size_t)c];
}

void tb_rad_corner_radiosity_amb(const tb_rad_solver *s, size_t i, int k, const double *amb, double *out)
{
    int nc = s->nc;
    const tb_rad_element *e = &s->m.elems[i];
    for (int c = 0; c < nc; c++) {
        double rho = s->m.rho[i * (size_t)nc + (size_t)c];
        out[c] = s->m.emission[i * (size_t)nc + (size_t)c] + rho * (tb__Hv(s, e->v[k], c) + (amb ? amb[c] : 0.0));
    }
}

void tb_rad_corner_radiosity(const tb_rad_solver *s, size_t i, int k, bool ambient, double *out)
{
    double amb[TB_CHANNELS_MAX] = {0};
    if (ambient)
        tb_rad_ambient(s, amb);
    tb_rad_corner_radiosity_amb(s, i, k, amb, out);
}

void tb_rad_vertex_irradiance(const tb_rad_solver *s, size_t v, double *out)
{
    for (int c = 0; c < s->nc; c++)
        out[c] = tb__Hv(s, (uint32_t)v, c);
}

tb_rad_state tb_rad_solver_state(const tb_rad_solver *s)
{
    bool hemi = s->opt.ff == TB_RAD_FF_HEMICUBE;
    tb_rad_state st = {.gathered = hemi ? s->He : s->Hv, .gathered_elems = hemi ? NULL : s->He, .unshot = s->dB,
                       .lights_shot = s->lshot};
    return st;
}

tb_status tb_rad_formfactor(tb_rad_solver *s, size_t i, size_t j, double *f)
{
    *f = 0.0;
    if (i >= s->nsh || j >= s->m.nelems)
        return tb_error(TB_ERR_ARG, "radiosity: shooter or element index out of range");
    if (s->pof[j] == i)
        return TB_OK;
    /* exactly what a shot from i uses */
    tb_status st = tb__shooter_ff(s, i, false); /* this process alone: not collective */
    if (st)
        return st;
    *f = (double)s->eff[j] * s->m.elems[j].area / s->sarea[i];
    return TB_OK;
}

/* ------------------------------------------------------------------ lights
 * Point, spot and directional lights (host/radiosity/lights.h): each holds
 * its power until it is shot, once, straight to the receivers. */

/* The lights of the options over the solver's mesh; their power enters the
 * emitted power, and the unshot power until they are shot. */
static tb_status tb__lights_init(tb_rad_solver *s, const tb_rad_state *state)
{
    int n = s->opt.nlights, nc = s->nc;
    if (n < 0 || !s->opt.lights)
        return tb_error(TB_ERR_ARG, "radiosity: bad light list (%d lights)", n);
    tb_status st = tb_rad_lights_create(&s->m, s->opt.lights, n, &s->lights);
    if (st)
        return st;
    s->lshot = calloc((size_t)n, 1);
    s->lpower = calloc((size_t)n, sizeof *s->lpower);
    if (!s->lshot || !s->lpower)
        return tb_error(TB_ERR_NOMEM, "radiosity: out of memory");
    for (int k = 0; k < n; k++) {
        double p[TB_CHANNELS_MAX];
        tb_rad_lights_power(s->lights, k, p);
        for (int c = 0; c < nc; c++)
            s->lpower[k] += p[c];
        s->lshot[k] = state && state->lights_shot && state->lights_shot[k];
        s->emitted += s->lpower[k];
        if (!s->lshot[k])
            s->lpending += s->lpower[k];
    }
    s->opt.lights = NULL; /* copied into s->lights: the caller's array need not outlive the solver */
    return TB_OK;
}

/* Shoots the light not yet shot with the most power (ties: the lower index)
 * if that is at least the most unshot power of an element; *shot says if it did. */
static tb_status tb__lights_step(tb_rad_solver *s, bool *shot)
{
    *shot = false;
    int n = tb_rad_lights_count(s->lights), k = -1;
    for (int q = 0; q < n; q++)
        if (!s->lshot[q] && (k < 0 || s->lpower[q] > s->lpower[k]))
            k = q;
    uint32_t top;
    double pri;
    if (k < 0 || (tb__top(s, &top, &pri) && pri > s->lpower[k]))
        return TB_OK;
    tb__defer_flush_timed(s); /* the logged shots come first */
    double t0 = tb__now();
    int nc = s->nc;
    size_t nv = s->m.nverts, ne = s->m.nelems;
    double *ev = malloc(sizeof *ev * nv * (size_t)nc), *ee = malloc(sizeof *ee * ne * (size_t)nc);
    tb_status st = ev && ee ? TB_OK : tb_error(TB_ERR_NOMEM, "radiosity: out of memory");
    tb_timer_token tt = tb_timer_start(&tb__rad_ff_time);
    if (!st)
        st = tb_rad_lights_shoot(s->lights, k, ev, ee);
    (void)tb_timer_stop(tt);
    if (st) {
        free(ev), free(ee);
        return st;
    }
    tt = tb_timer_start(&tb__rad_update_time);
    bool hemi = s->opt.ff == TB_RAD_FF_HEMICUBE;
    for (size_t j = 0; j < ne; j++) {
        const tb_rad_element *ej = &s->m.elems[j];
        double rec = 0.0, abs_ = 0.0, aj = ej->area;
        for (int c = 0; c < nc; c++) {
            size_t x = j * (size_t)nc + (size_t)c;
            double dh = ee[x], rho = s->m.rho[x];
            if (!(dh > 0.0))
                continue;
            s->He[x] += dh;
            s->dB[x] += rho * dh;
            rec += dh * aj;
            abs_ += (1.0 - rho) * dh * aj;
            if (hemi) /* H_v: the area-weighted mean of the elements around v, as a hemicube shot keeps it */
                for (int q = 0; q < tb__elem_size(ej); q++)
                    s->Hv[ej->v[q] * (size_t)nc + (size_t)c] += dh * aj / s->vert_area[ej->v[q]];
        }
        if (!(rec > 0.0))
            continue;
        s->erec[j] += rec;
        s->eabs[j] += abs_;
        s->up[j] = tb__unshot_power(s, j);
        tb__queue_elem(s, j);
    }
    tb__queue_flush(s);
    if (!hemi)
        for (size_t x = 0; x < nv * (size_t)nc; x++)
            s->Hv[x] += ev[x];
    free(ev), free(ee);
    s->lshot[k] = 1;
    s->lpending = 0.0; /* summed afresh: no rounding drift */
    for (int q = 0; q < n; q++)
        if (!s->lshot[q])
            s->lpending += s->lpower[q];
    s->shot_total += s->lpower[k];
    (void)tb_timer_stop(tt);
    s->shots++;
    tb_stat_add(&tb__rad_shots, 1);
    s->seconds += tb__now() - t0;
    *shot = true;
    return TB_OK;
}

/* ---------------------------------------------------------------- packing */

/* Header: u64 nelems, nverts, nchannels, nlights, shooters, shots; f64
 * absorbed, escaped (at create), lpending, seconds, power shot. Then He,
 * Hv, dB, up, eabs, erec (doubles), lshot (bytes). */
#define TB__RAD_PACK_HEAD (6 * sizeof(uint64_t) + 5 * sizeof(double))

size_t tb_rad_solver_packed_size(const tb_rad_solver *s)
{
    size_t ne = s->m.nelems, nv = s->m.nverts, nc = (size_t)s->nc;
    return TB__RAD_PACK_HEAD + (ne * nc + nv * nc + ne * nc + 3 * ne) * sizeof(double) + (size_t)s->opt.nlights;
}

void tb_rad_solver_pack(const tb_rad_solver *s, void *buf)
{
    size_t ne = s->m.nelems, nv = s->m.nverts, nc = (size_t)s->nc;
    unsigned char *p = buf;
    uint64_t h[6] = {ne, nv, nc, (uint64_t)s->opt.nlights, s->nsh, s->shots};
    double d[5] = {s->absorbed, s->escaped, s->lpending, s->seconds, s->shot_total};
    memcpy(p, h, sizeof h), p += sizeof h;
    memcpy(p, d, sizeof d), p += sizeof d;
    memcpy(p, s->He, ne * nc * sizeof(double)), p += ne * nc * sizeof(double);
    memcpy(p, s->Hv, nv * nc * sizeof(double)), p += nv * nc * sizeof(double);
    memcpy(p, s->dB, ne * nc * sizeof(double)), p += ne * nc * sizeof(double);
    memcpy(p, s->up, ne * sizeof(double)), p += ne * sizeof(double);
    memcpy(p, s->eabs, ne * sizeof(double)), p += ne * sizeof(double);
    memcpy(p, s->erec, ne * sizeof(double)), p += ne * sizeof(double);
    if (s->opt.nlights > 0)
        memcpy(p, s->lshot, (size_t)s->opt.nlights);
}

tb_status tb_rad_solver_unpack(tb_rad_solver *s, const void *buf, size_t len)
{
    size_t ne = s->m.nelems, nv = s->m.nverts, nc = (size_t)s->nc;
    uint64_t h[6];
    double d[5];
    if (len < TB__RAD_PACK_HEAD)
        return tb_error(TB_ERR_FORMAT, "radiosity: packed state of %zu bytes is shorter than its header", len);
    const unsigned char *p = buf;
    memcpy(h, p, sizeof h), p += sizeof h;
    memcpy(d, p, sizeof d), p += sizeof d;
    if (h[0] != ne || h[1] != nv || h[2] != nc || h[3] != (uint64_t)s->opt.nlights || h[4] != s->nsh)
        return tb_error(TB_ERR_FORMAT,
                        "radiosity: packed state of %llu elements, %llu vertices, %llu channels, %llu lights, "
                        "%llu shooters; this solver has %zu, %zu, %zu, %d, %zu (another scene or meshing)",
                        (unsigned long long)h[0], (unsigned long long)h[1], (unsigned long long)h[2],
                        (unsigned long long)h[3], (unsigned long long)h[4], ne, nv, nc, s->opt.nlights, s->nsh);
    if (len != tb_rad_solver_packed_size(s))
        return tb_error(TB_ERR_FORMAT, "radiosity: packed state has %zu bytes, expected %zu", len,
                        tb_rad_solver_packed_size(s));
    s->shots = h[5];
    s->absorbed = d[0], s->escaped = d[1], s->lpending = d[2], s->seconds = d[3], s->shot_total = d[4];
    memcpy(s->He, p, ne * nc * sizeof(double)), p += ne * nc * sizeof(double);
    memcpy(s->Hv, p, nv * nc * sizeof(double)), p += nv * nc * sizeof(double);
    memcpy(s->dB, p, ne * nc * sizeof(double)), p += ne * nc * sizeof(double);
    memcpy(s->up, p, ne * sizeof(double)), p += ne * sizeof(double);
    memcpy(s->eabs, p, ne * sizeof(double)), p += ne * sizeof(double);
    memcpy(s->erec, p, ne * sizeof(double)), p += ne * sizeof(double);
    if (s->opt.nlights > 0)
        memcpy(s->lshot, p, (size_t)s->opt.nlights);
    tb__queue_rebuild(s);
    return TB_OK;
}
