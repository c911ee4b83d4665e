/* Lazily tessellated CSG emitters (emit_csg.h, docs/lights.md "CSG emitters"). */
#include "host/render/emit_csg.h"

#include <math.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "host/render/scene_internal.h"
#include "util/container/array.h"
#include "util/stats/stats.h"

TB_STAT_COUNTER(tb__n_built, "Emitters/CSG tessellations built");
TB_STAT_COUNTER(tb__n_tris, "Emitters/CSG tessellation triangles");
TB_STAT_COUNTER(tb__n_over, "Emitters/CSG tessellations over budget");
TB_STAT_COUNTER(tb__n_failed, "Emitters/CSG tessellations failed");
TB_STAT_COUNTER(tb__n_coarsened, "Emitters/CSG tessellations coarsened");

/* The levels, finest first: angular tolerance (degrees), CSG refinement
 * edge (fraction of the world box diagonal), segments per face direction.
 * Level 0 is close to the eager tessellation (4 degrees, 0.02, 4096) at a
 * fraction of its triangles; each next level about halves the count. */
static const struct {
    double angle_deg, edge;
    int segments;
} tb__levels[TB_CSG_EMIT_LEVELS] = {{8.0, 0.03, 64}, {12.0, 0.045, 40}, {18.0, 0.07, 24}, {27.0, 0.1, 16}};

/* Triangles per block of the line query's bounding spheres. */
#define TB__BLOCK 32

enum { TB__UNBUILT, TB__BUILDING, TB__READY, TB__FAILED };

struct tb_csg_emitter {
    const tb_object *obj;
    tb_channels L;
    double proxy;        /* selection area */
    _Atomic int state;   /* TB__UNBUILT .. TB__FAILED; the fields below are read after TB__READY */
    int ntris, level, nblocks;
    double area;         /* of the tessellation */
    float *v;            /* 9 floats per triangle: its corners, front side counter-clockwise */
    double *cdf;         /* ntris + 1: cumulative area / area */
    double *blocks;      /* 4 per block: centre, radius */
};

tb_status tb_csg_emitter_make(const tb_object *o, tb_channels L, tb_csg_emitter **out)
{
    *out = NULL;
    if (!o || !tb_prim_is_csg(o->kind))
        return tb_error(TB_ERR_ARG, "CSG emitter: needs a CSG node");
    tb_aabb box;
    tb_status st = tb__scene_object_bounds(o, &box);
    if (st)
        return st;
    double ext[3] = {(double)box.hi.x - box.lo.x, (double)box.hi.y - box.lo.y, (double)box.hi.z - box.lo.z};
    double proxy = (TB_PI / 6.0) * 2.0 * (ext[0] * ext[1] + ext[1] * ext[2] + ext[2] * ext[0]);
    if (!(proxy > 0.0) || !isfinite(proxy))
        return tb_error(TB_ERR_ARG, "CSG emitter: bounds of no area");
    tb_csg_emitter *ce = calloc(1, sizeof *ce);
    if (!ce)
        return tb_error(TB_ERR_NOMEM, "CSG emitter: out of memory");
    ce->obj = o;
    ce->L = L;
    ce->proxy = proxy;
    atomic_init(&ce->state, TB__UNBUILT);
    *out = ce;
    return TB_OK;
}

void tb_csg_emitter_free(tb_csg_emitter *ce)
{
    if (!ce)
        return;
    free(ce->v);
    free(ce->cdf);
    free(ce->blocks);
    free(ce);
}

/* Compact form of the triangle emitters in `tris`; false when out of memory
 * or none has area. */
static bool tb__store(tb_csg_emitter *ce, const tb_array *tris)
{
    const int n = (int)tris->len, nb = (n + TB__BLOCK - 1) / TB__BLOCK;
    ce->v = malloc(sizeof *ce->v * 9 * (size_t)(n ? n : 1));
    ce->cdf = malloc(sizeof *ce->cdf * ((size_t)n + 1));
    ce->blocks = malloc(sizeof *ce->blocks * 4 * (size_t)(nb ? nb : 1));
    if (!ce->v || !ce->cdf || !ce->blocks)
        return false;
    double acc = 0.0;
    ce->cdf[0] = 0.0;
    for (int i = 0; i < n; i++) {
        const tb_emitter *e = tb_array_at(tris, (size_t)i);
        for (int k = 0; k < 3; k++) {
            ce->v[9 * i + 3 * k + 0] = e->v[k].x;
            ce->v[9 * i + 3 * k + 1] = e->v[k].y;
            ce->v[9 * i + 3 * k + 2] = e->v[k].z;
        }
        acc += tb_emitter_area(e);
        ce->cdf[i + 1] = acc;
    }
    if (!(acc > 0.0) || !isfinite(acc))
        return false;
    for (int i = 1; i <= n; i++)
        ce->cdf[i] /= acc;
    ce->cdf[n] = 1.0;
    for (int b = 0; b < nb; b++) {
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (int i = b * TB__BLOCK; i < n && i < (b + 1) * TB__BLOCK; i++)
            for (int k = 0; k < 9; k++) {
                lo[k % 3] = fmin(lo[k % 3], ce->v[9 * i + k]);
                hi[k % 3] = fmax(hi[k % 3], ce->v[9 * i + k]);
            }
        double d2 = 0.0;
        for (int k = 0; k < 3; k++) {
            ce->blocks[4 * b + k] = 0.5 * (lo[k] + hi[k]);
            d2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
        }
        /* half the diagonal, widened for the rounding of the tests */
        ce->blocks[4 * b + 3] = 0.5 * sqrt(d2) * (1.0 + 1e-6) + 1e-9;
    }
    ce->ntris = n;
    ce->nblocks = nb;
    ce->area = acc;
    return true;
}

/* The build itself (one thread): the finest level within the budget. */
static bool tb__build(tb_csg_emitter *ce)
{
    tb_array tris;
    tb_array_init(&tris, sizeof(tb_emitter));
    bool ok = false;
    for (int l = 0; l < TB_CSG_EMIT_LEVELS; l++) {
        tris.len = 0;
        int n = 0;
        double angle = tb__levels[l].angle_deg * (TB_PI / 180.0);
        if (tb__scene_tess_emitters(ce->obj, ce->L, angle, tb__levels[l].edge, tb__levels[l].segments, &tris, &n)) {
            tb_clear_error(); /* out of memory: the emitter gives no light (Emitters/CSG tessellations failed) */
            break;
        }
        if (n == 0)
            break; /* nothing to tessellate: a coarser level has nothing either */
        ce->level = l;
        if (n <= TB_CSG_EMIT_MAX_TRIS || l == TB_CSG_EMIT_LEVELS - 1) {
            if (n > TB_CSG_EMIT_MAX_TRIS)
                tb_stat_add(&tb__n_over, 1);
            if (l > 0)
                tb_stat_add(&tb__n_coarsened, 1);
            ok = tb__store(ce, &tris);
            break;
        }
    }
    tb_array_free(&tris);
    if (!ok) {
        free(ce->v);
        free(ce->cdf);
        free(ce->blocks);
        ce->v = NULL;
        ce->cdf = ce->blocks = NULL;
        ce->ntris = ce->nblocks = 0;
        ce->area = 0.0;
        tb_stat_add(&tb__n_failed, 1);
        return false;
    }
    tb_stat_add(&tb__n_built, 1);
    tb_stat_add(&tb__n_tris, ce->ntris);
    return true;
}

bool tb_csg_emitter_build(tb_csg_emitter *ce)
{
    int s = atomic_load_explicit(&ce->state, memory_order_acquire);
    if (s >= TB__READY)
        return s == TB__READY;
    int expect = TB__UNBUILT;
    if (atomic_compare_exchange_strong_explicit(&ce->state, &expect, TB__BUILDING, memory_order_acq_rel,
                                                memory_order_acquire)) {
        s = tb__build(ce) ? TB__READY : TB__FAILED;
        atomic_store_explicit(&ce->state, s, memory_order_release);
        return s == TB__READY;
    }
    /* another thread builds it: a fraction of a second at most */
    while ((s = atomic_load_explicit(&ce->state, memory_order_acquire)) == TB__BUILDING)
        sched_yield();
    return s == TB__READY;
}

bool tb_csg_emitter_built(const tb_csg_emitter *ce)
{
    return atomic_load_explicit(&((tb_csg_emitter *)ce)->state, memory_order_acquire) >= TB__READY;
}

double tb_csg_emitter_proxy_area(const tb_csg_emitter *ce) { return ce->proxy; }

double tb_csg_emitter_area(tb_csg_emitter *ce) { return tb_csg_emitter_build(ce) ? ce->area : 0.0; }

int tb_csg_emitter_triangles(tb_csg_emitter *ce) { return tb_csg_emitter_build(ce) ? ce->ntris : 0; }

int tb_csg_emitter_level(tb_csg_emitter *ce) { return tb_csg_emitter_build(ce) ? ce->level : -1; }

size_t tb_csg_emitter_unbuilt_bytes(void) { return sizeof(tb_csg_emitter); }

size_t tb_csg_emitter_bytes(const tb_csg_emitter *ce)
{
    if (!tb_csg_emitter_built(ce))
        return sizeof *ce;
    return sizeof *ce + (size_t)ce->ntris * (9 * sizeof(float) + sizeof(double)) + sizeof(double) +
           (size_t)ce->nblocks * 4 * sizeof(double);
}

/* Triangle i as a triangle emitter (radiance L). */
static tb_emitter tb__tri(const tb_csg_emitter *ce, int i)
{
    const float *p = ce->v + 9 * (size_t)i;
    return tb_emitter_triangle((tb_vec3){p[0], p[1], p[2]}, (tb_vec3){p[3], p[4], p[5]}, (tb_vec3){p[6], p[7], p[8]},
                               ce->L);
}

/* Sampler callback: a triangle by area from u1, a uniform point on it. */
static bool tb__sample(void *ctx, float u1, float u2, tb_vec3 *q, tb_vec3 *n, double *pdf_area)
{
    tb_csg_emitter *ce = ctx;
    if (!tb_csg_emitter_build(ce))
        return false;
    double u = u1 >= 0.0f ? (u1 < 1.0f ? u1 : 0x1.fffffep-1) : 0.0;
    int i = tb_cdf_search(ce->cdf, ce->ntris, u);
    double w = ce->cdf[i + 1] - ce->cdf[i];
    double r = w > 0.0 ? (u - ce->cdf[i]) / w : 0.0;
    float ur = r < 1.0 ? (r > 0.0 ? (float)r : 0.0f) : 0x1.fffffep-1f;
    if (ur >= 1.0f)
        ur = 0x1.fffffep-1f;
    const float *p = ce->v + 9 * (size_t)i;
    tb_dvec3 a = {p[0], p[1], p[2]}, b = {p[3], p[4], p[5]}, c = {p[6], p[7], p[8]};
    tb_vec2 bc = tb_sample_triangle(ur, u2);
    double b0 = bc.x, b1 = bc.y, b2 = 1.0 - b0 - b1;
    tb_dvec3 x = tb_dvec3_add(tb_dvec3_add(tb_dvec3_scale(a, b0), tb_dvec3_scale(b, b1)), tb_dvec3_scale(c, b2));
    tb_dvec3 nn = tb_dvec3_normalize(tb_dvec3_cross(tb_dvec3_sub(b, a), tb_dvec3_sub(c, a)));
    *q = tb_dvec3_to_f(x);
    *n = tb_dvec3_to_f(nn);
    *pdf_area = 1.0 / ce->area;
    return true;
}

/* Density callback: uniform by area over the tessellation (the renderer
 * asks it at points the line query found on it). */
static double tb__pdf(void *ctx, tb_vec3 q)
{
    (void)q;
    tb_csg_emitter *ce = ctx;
    return tb_csg_emitter_build(ce) ? 1.0 / ce->area : 0.0;
}

/* Line callback: the nearest crossing of o + t d with a triangle at t > tmin. */
static bool tb__intersect(void *ctx, tb_vec3 o, tb_vec3 d, double tmin, double *t, tb_vec3 *q, tb_vec3 *n)
{
    tb_csg_emitter *ce = ctx;
    if (!tb_csg_emitter_build(ce))
        return false;
    const double dd = (double)d.x * d.x + (double)d.y * d.y + (double)d.z * d.z;
    double best = INFINITY;
    for (int b = 0; b < ce->nblocks; b++) {
        /* the block's sphere against the half-line t > tmin (t >= 0) */
        const double *sp = &ce->blocks[4 * b];
        const double c[3] = {sp[0] - o.x, sp[1] - o.y, sp[2] - o.z};
        const double c2 = c[0] * c[0] + c[1] * c[1] + c[2] * c[2], r2 = sp[3] * sp[3];
        const double proj = c[0] * d.x + c[1] * d.y + c[2] * d.z;
        if (c2 > r2 && (proj <= 0.0 || c2 - proj * proj / dd > r2))
            continue;
        for (int i = b * TB__BLOCK; i < ce->ntris && i < (b + 1) * TB__BLOCK; i++) {
            tb_emitter e = tb__tri(ce, i);
            double ti;
            tb_vec3 qi, ni;
            if (tb_emitter_intersect(&e, o, d, &ti, &qi, &ni) && ti > tmin && ti < best) {
                best = ti;
                *q = qi;
                *n = ni;
            }
        }
    }
    if (!(best < INFINITY))
        return false;
    *t = best;
    return true;
}

tb_emitter tb_emitter_csg(tb_csg_emitter *ce)
{
    return (tb_emitter){.kind = TB_EMITTER_CUSTOM,
                        .radiance = ce->L,
                        .object = ce->obj->index,
                        .face = ce->obj->face_base,
                        .area = ce->proxy,
                        .sample = tb__sample,
                        .pdf = tb__pdf,
                        .intersect = tb__intersect,
                        .ctx = ce};
}

bool tb_emitter_is_csg(const tb_emitter *e) { return e->kind == TB_EMITTER_CUSTOM && e->sample == tb__sample; }
