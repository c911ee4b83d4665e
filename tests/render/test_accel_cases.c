/* Hard cases of the acceleration structures, each a named test with an
 * answer known in advance: empty scene, one primitive, everything in one
 * point, 10^5 identical boxes, invalid rays, exact tmin/tmax, a callback that
 * ignores the range, build errors, the grid resolution rule. */
#include "tb_test.h"

#include <stdlib.h>
#include <string.h>

#include "host/render/accel.h"
#include "host/object/watertight.h"
#include "host/render/accel_internal.h"
#include "test_accel_prims.h"
#include "util/base/error.h"
#include "util/stats/stats.h"

static const tb_accel_kind kinds[] = {TB_ACCEL_BVH, TB_ACCEL_GRID, TB_ACCEL_LIST};
#define NKINDS 3

static tb_accel *build(tb_accel_kind k, tp_scene *s, const tb_accel_options *opt)
{
    tb_accel_callbacks cb = {tp_cb_intersect, tp_cb_occluded, s, NULL};
    tb_accel *acc = NULL;
    if (tb_accel_build(k, s->refs, s->n, &cb, opt, &acc))
        fail_msg("build %s: %s", tb_accel_kind_name(k), tb_last_error());
    return acc;
}

static tb_ray ray(float ox, float oy, float oz, float dx, float dy, float dz, float tmin, float tmax)
{
    return tb_ray_make((tb_vec3){ox, oy, oz}, (tb_vec3){dx, dy, dz}, tmin, tmax);
}

/* The hit of `r` on `acc`; fails unless found with the expected t and object. */
static void expect_hit(const tb_accel *acc, const tb_ray *r, float t, uint32_t object, uint32_t face)
{
    tb_hit h;
    if (!tb_accel_intersect(acc, r, &h))
        fail_msg("%s: expected a hit at t = %g, got a miss", tb_accel_kind_name(tb_accel_get_kind(acc)), (double)t);
    if (h.t != t || h.object != object || h.face != face)
        fail_msg("%s: expected t %a object %u face %u, got t %a object %u face %u",
                 tb_accel_kind_name(tb_accel_get_kind(acc)), (double)t, object, face, (double)h.t, h.object, h.face);
    assert_true(tb_accel_occluded(acc, r));
}

static void expect_miss(const tb_accel *acc, const tb_ray *r)
{
    tb_hit h, before;
    memset(&h, 0x5a, sizeof h);
    before = h;
    if (tb_accel_intersect(acc, r, &h))
        fail_msg("%s: expected a miss, got t %a object %u", tb_accel_kind_name(tb_accel_get_kind(acc)), (double)h.t,
                 h.object);
    assert_memory_equal(&h, &before, sizeof h); /* untouched on a miss */
    assert_false(tb_accel_occluded(acc, r));
}

static void test_empty_scene(void **state)
{
    (void)state;
    tp_scene none = {0};
    /* Only empty boxes (lo > hi): dropped, so also an empty structure. */
    tp_scene empties = {0};
    for (int i = 0; i < 3; i++) {
        tp_add_sphere(&empties, 0, 0, 0, 1, (uint32_t)i, 0);
        empties.refs[i].bounds = tb_aabb_empty();
    }
    tp_scene *scenes[2] = {&none, &empties};
    for (int sc = 0; sc < 2; sc++) {
        for (int k = 0; k < NKINDS; k++) {
            tb_accel *acc = build(kinds[k], scenes[sc], NULL);
            tb_accel_stats st;
            tb_accel_get_stats(acc, &st);
            assert_int_equal(st.nprims, 0);
            assert_int_equal(st.bvh_nodes, 0);
            assert_true(tb_aabb_is_empty(&st.bounds));
            tb_ray r = ray(0, 0, -5, 0, 0, 1, 0, INFINITY);
            expect_miss(acc, &r);
            size_t nn = 7;
            assert_null(tb_accel_bvh_nodes(acc, &nn));
            assert_int_equal(nn, 0);
            tb_accel_free(acc);
        }
    }
    tp_free(&empties);
}

static void test_one_primitive(void **state)
{
    (void)state;
    tp_scene s = {0};
    tp_add_sphere(&s, 1, 2, 3, 0.5f, 7, 3);
    for (int k = 0; k < NKINDS; k++) {
        tb_accel *acc = build(kinds[k], &s, NULL);
        /* Along +z through the centre: the sphere spans z = 2.5 .. 3.5. */
        tb_ray r = ray(1, 2, -10, 0, 0, 1, 0, INFINITY);
        expect_hit(acc, &r, 12.5f, 7, 3);
        /* From the centre: leaves through the surface at t = 0.5. */
        r = ray(1, 2, 3, 0, 0, 1, 0, INFINITY);
        expect_hit(acc, &r, 0.5f, 7, 3);
        /* From the centre backwards with tmin < 0: the entry at -0.5. */
        r = ray(1, 2, 3, 0, 0, 1, -1.0f, INFINITY);
        expect_hit(acc, &r, -0.5f, 7, 3);
        /* Passing beside it, and pointing away from it. */
        r = ray(1, 2.6f, -10, 0, 0, 1, 0, INFINITY);
        expect_miss(acc, &r);
        r = ray(1, 2, -10, 0, 0, -1, 0, INFINITY);
        expect_miss(acc, &r);
        /* Along an axis with -0 components, hitting the +x pole. */
        r = ray(10, 2, 3, -1, -0.0f, -0.0f, 0, INFINITY);
        expect_hit(acc, &r, 8.5f, 7, 3);
        tb_accel_stats st;
        tb_accel_get_stats(acc, &st);
        assert_int_equal(st.nprims, 1);
        if (kinds[k] == TB_ACCEL_BVH) {
            assert_int_equal(st.bvh_nodes, 1);
            assert_int_equal(st.bvh_depth, 0);
            /* One leaf with one reference: SAH cost = C_prim * 1 * area/area = 1. */
            assert_true(st.bvh_sah_cost == 1.0);
        }
        if (kinds[k] == TB_ACCEL_GRID) {
            /* 3 * cbrt(1) voxels along each axis of the (cubic) box. */
            assert_int_equal(st.grid_res[0], 3);
            assert_int_equal(st.grid_res[1], 3);
            assert_int_equal(st.grid_res[2], 3);
            assert_int_equal(st.grid_refs, 27);
        }
        tb_accel_free(acc);
    }
    tp_free(&s);
}

/* All references share one centroid (zero-extent centroid bounds): 1000
 * concentric spheres, and 1000 triangles collapsed to that very point. */
static void test_all_in_one_point(void **state)
{
    (void)state;
    tp_scene s = {0};
    /* Centred on the origin, so each box is symmetric and its centroid exactly 0. */
    for (int i = 0; i < 1000; i++)
        tp_add_sphere(&s, 0, 0, 0, (float)(i + 1) / 1000.0f, (uint32_t)(999 - i), 0);
    for (int i = 0; i < 1000; i++) {
        float v[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
        tp_add_triangle(&s, (const float(*)[3])v, 5000 + (uint32_t)i, 0);
    }
    for (int k = 0; k < NKINDS; k++) {
        tb_accel *acc = build(kinds[k], &s, NULL);
        /* From outside: the biggest sphere (r = 1, object 0) at distance 10 - 1. */
        tb_ray r = ray(0, 0, -10, 0, 0, 1, 0, INFINITY);
        expect_hit(acc, &r, 9.0f, 0, 0);
        /* From the centre: the smallest sphere (r = 0.001, object 999). */
        r = ray(0, 0, 0, 1, 0, 0, 0, INFINITY);
        expect_hit(acc, &r, 0.001f, 999, 0);
        tb_accel_stats st;
        tb_accel_get_stats(acc, &st);
        if (kinds[k] == TB_ACCEL_BVH) {
            /* No SAH plane exists: median splits, so a balanced tree of 2000
             * references in leaves of <= 8: depth ceil(log2(2000 / 8)) = 8. */
            assert_true(st.bvh_depth <= 8);
            assert_true(st.bvh_max_leaf_prims <= 8);
        }
        tb_accel_free(acc);
    }
    tp_free(&s);
}

/* 10^5 references with the same box (the same sphere under 10^5 object
 * numbers, the lowest one in the middle of the array): every structure must
 * still build in bounded memory and depth and return object 0. */
static void test_identical_boxes_1e5(void **state)
{
    (void)state;
    const uint32_t n = 100000;
    tp_scene s = {0};
    for (uint32_t i = 0; i < n; i++)
        tp_add_sphere(&s, 3, 3, 3, 1, (i + n / 2) % n, 0);
    for (int k = 0; k < NKINDS; k++) {
        tb_accel *acc = build(kinds[k], &s, NULL);
        tb_accel_stats st;
        tb_accel_get_stats(acc, &st);
        assert_int_equal(st.nprims, n);
        if (kinds[k] == TB_ACCEL_BVH) {
            /* ceil(log2(10^5 / 8)) = 14 with median splits. */
            assert_true(st.bvh_depth <= 14);
        }
        if (kinds[k] == TB_ACCEL_GRID) {
            /* The pair budget forces a coarse grid instead of 10^5 x res^3 pairs. */
            assert_true(st.grid_refs <= 32 * (size_t)n + 8 * st.grid_cells);
        }
        tb_ray r = ray(3, 3, -7, 0, 0, 1, 0, INFINITY);
        expect_hit(acc, &r, 9.0f, 0, 0);
        r = ray(3, 3, 3, 0, 1, 0, 0, INFINITY);
        expect_hit(acc, &r, 1.0f, 0, 0);
        r = ray(5, 5, -7, 0, 0, 1, 0, INFINITY);
        expect_miss(acc, &r);
        tb_accel_free(acc);
    }
    tp_free(&s);
}

static int64_t invalid_count(void)
{
    tb_stat_total t;
    if (tb_stats_get("Accel/invalid rays", TB_STAT_KIND_COUNTER, &t) != TB_OK)
        return -1;
    return t.v[0];
}

/* Sets float number f of the ray record (ox oy oz tmin dx dy dz tmax). */
static void set_field(tb_ray *r, int f, float v)
{
    switch (f) {
    case 0: r->o.x = v; break;
    case 1: r->o.y = v; break;
    case 2: r->o.z = v; break;
    case 3: r->tmin = v; break;
    case 4: r->d.x = v; break;
    case 5: r->d.y = v; break;
    case 6: r->d.z = v; break;
    default: r->tmax = v; break;
    }
}

/* Rays with NaN or infinite components, a zero direction or tmin > tmax
 * are never hit and are counted. */
static void test_invalid_rays(void **state)
{
    (void)state;
    tp_scene s = {0};
    tp_add_sphere(&s, 0, 0, 0, 1, 0, 0);
    const tb_ray good = ray(0, 0, -5, 0, 0, 1, 0, INFINITY);
    tb_ray bad[32];
    int nb = 0;
    for (int f = 0; f < 8; f++) {
        /* NaN in each of the eight floats. */
        tb_ray r = good;
        set_field(&r, f, NAN);
        bad[nb++] = r;
    }
    for (int f = 0; f < 3; f++) {
        tb_ray r = good;
        set_field(&r, f, INFINITY); /* origin */
        bad[nb++] = r;
        r = good;
        set_field(&r, 4 + f, -INFINITY); /* direction */
        bad[nb++] = r;
    }
    bad[nb++] = ray(0, 0, -5, 0, 0, 0, 0, INFINITY);            /* zero direction */
    bad[nb++] = ray(0, 0, -5, -0.0f, 0, -0.0f, 0, INFINITY);    /* negative zeros */
    bad[nb++] = ray(0, 0, -5, 0, 0, 1, 5, 4);                   /* tmin > tmax */
    bad[nb++] = ray(0, 0, -5, 0, 0, 1, -INFINITY, INFINITY);    /* infinite tmin */
    bad[nb++] = ray(0, 0, -5, 0, 0, 1, INFINITY, INFINITY);
    for (int k = 0; k < NKINDS; k++) {
        tb_accel *acc = build(kinds[k], &s, NULL);
        expect_hit(acc, &good, 4.0f, 0, 0);
        int64_t before = invalid_count();
        for (int i = 0; i < nb; i++) {
            assert_false(tb_ray_is_valid(&bad[i]));
            expect_miss(acc, &bad[i]);
        }
        /* expect_miss makes two queries per ray. */
        assert_int_equal(invalid_count() - before, 2 * nb);
        tb_accel_free(acc);
    }
    tp_free(&s);
}

/* tmin and tmax are inclusive and exact: the unit sphere seen from x = -5
 * has roots exactly 4 and 6; a triangle (object 3) in the plane x = -1 ties
 * with the sphere's entry (object 5) at t = 4, and the lower object wins. */
static void test_tmin_tmax_exact(void **state)
{
    (void)state;
    tp_scene s = {0};
    tp_add_sphere(&s, 0, 0, 0, 1, 5, 0);
    float tri[3][3] = {{-1, -1, -1}, {-1, 2, -1}, {-1, -1, 2}};
    tp_add_triangle(&s, (const float(*)[3])tri, 3, 9);
    const float four = 4.0f, six = 6.0f;
    const float below4 = tb_next_float_down(four), above4 = tb_next_float_up(four);
    const float below6 = tb_next_float_down(six), above6 = tb_next_float_up(six);
    for (int k = 0; k < NKINDS; k++) {
        tb_accel *acc = build(kinds[k], &s, NULL);
        tb_ray r = ray(-5, 0, 0, 1, 0, 0, 0, INFINITY);
        expect_hit(acc, &r, four, 3, 9);
        r.tmax = four;
        expect_hit(acc, &r, four, 3, 9);
        r.tmax = below4;
        expect_miss(acc, &r);
        r.tmin = four;
        r.tmax = four;
        expect_hit(acc, &r, four, 3, 9);
        r.tmin = above4;
        r.tmax = INFINITY;
        expect_hit(acc, &r, six, 5, 0);
        r.tmax = six;
        expect_hit(acc, &r, six, 5, 0);
        r.tmax = below6;
        expect_miss(acc, &r);
        r.tmin = above6;
        r.tmax = INFINITY;
        expect_miss(acc, &r);
        r.tmin = -10.0f;
        r.tmax = 100.0f;
        expect_hit(acc, &r, four, 3, 9);
        tb_accel_free(acc);
    }
    tp_free(&s);
}

/* A callback that ignores the range and reports t = 4 for every ray (or NaN):
 * the structures themselves must keep hits outside [tmin, tmax] out. */
static bool liar(void *ctx, const tb_accel_prim *prim, uint32_t index, const tb_ray *r, tb_hit *hit)
{
    (void)prim;
    (void)index;
    (void)r;
    *hit = (tb_hit){.t = *(const float *)ctx, .object = 1};
    return true;
}

/* Triangle references (tb_accel_tri): a random scene whose triangles are
 * given as records the structure tests itself and whose spheres go through
 * the callback. Every kind must return the brute-force answer over the same
 * tests (the watertight test of host/object/watertight.h on the records, the
 * spheres' callback; ties by (t, object, face, index)) bit for bit, with
 * u, v and the normal 0 on triangle hits, and tb_accel_intersect_tri's
 * details (reference, double t, direction, edge functions) those of that
 * reference's test; occlusion agrees with the closest hit. The callback must
 * never see a triangle (it aborts). */
typedef struct tt_ctx {
    tp_scene *s;
} tt_ctx;

static bool tt_sphere_only(void *ctx, const tb_accel_prim *prim, uint32_t index, const tb_ray *ray, tb_hit *hit)
{
    tp_scene *s = ((tt_ctx *)ctx)->s;
    if (s->prims[prim->sub].kind != TP_SPHERE || prim->sub != index)
        abort(); /* triangles belong to the structure */
    return tp_intersect_prim(&s->prims[prim->sub], ray, hit);
}

/* The record's test as the reference computes it: true with t and details if hit in range. */
static bool tt_tri(const tb_accel_tri *tr, const tb_ray *ray, tb_accel_tri_hit *d)
{
    tb_wt_ray w;
    tb_wt_ray_init(&w, ray);
    if (!tb_wt_triangle(&w, &tr->v[0], &tr->v[3], &tr->v[6], &d->t, &d->dir, d->uvw))
        return false;
    return (float)d->t >= ray->tmin && (float)d->t <= ray->tmax;
}

static void test_triangle_references(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("triangle_references", 77), 0);
    tp_scene s = {0};
    tp_random_scene(&s, &r, 3000, 1.0f, 0.0f);
    tb_accel_tri *tris = malloc(s.n * sizeof *tris);
    assert_non_null(tris);
    size_t ntri = 0;
    for (size_t i = 0; i < s.n; i++) {
        const tp_prim *p = &s.prims[i];
        tris[i].object = TB_ACCEL_TRI_NONE;
        if (p->kind != TP_TRIANGLE)
            continue;
        for (int j = 0; j < 9; j++)
            tris[i].v[j] = p->v[j / 3][j % 3];
        tris[i].object = p->object;
        tris[i].face = p->face;
        ntri++;
    }
    assert_true(ntri > s.n / 4);
    tt_ctx ctx = {&s};
    tb_accel_callbacks cb = {tt_sphere_only, NULL, &ctx, tris};
    tb_accel *acc[NKINDS];
    for (int k = 0; k < NKINDS; k++)
        assert_int_equal(tb_accel_build(kinds[k], s.refs, s.n, &cb, NULL, &acc[k]), TB_OK);
    /* Records are kept for the triangle references only, each reached from its reference. */
    for (int k = 0; k < NKINDS; k++) {
        size_t with = 0;
        for (size_t j = 0; j < acc[k]->n; j++) {
            tb_accel_tri tmp;
            const tb_accel_tri *tr = tb__accel_tri_at(acc[k], j, &tmp);
            with += tr != NULL;
            assert_true(!tr || tr->object == s.prims[acc[k]->index[j]].object);
        }
        assert_int_equal(with, ntri);
        assert_non_null(acc[k]->tri_of);
    }
    /* The structures copied the records: the caller's array may go. */
    tb_accel_tri *kept = malloc(s.n * sizeof *kept);
    assert_non_null(kept);
    memcpy(kept, tris, s.n * sizeof *kept);
    memset(tris, 0xFF, s.n * sizeof *tris);
    free(tris);
    long nrays = 20000, hits = 0, tri_hits = 0;
    for (long i = 0; i < nrays; i++) {
        tb_ray ray = tp_random_ray(&r, &s, 1.0f, 0.0f);
        /* Brute force. */
        bool found = false;
        tb_hit best = {0};
        uint32_t best_i = 0;
        tb_accel_tri_hit best_d = {TB_ACCEL_TRI_NONE, 0, 0, 0.0, {0, 0, 0}};
        if (tb_ray_is_valid(&ray)) {
            for (size_t j = 0; j < s.n; j++) {
                if (tb_aabb_is_empty(&s.refs[j].bounds))
                    continue;
                tb_hit h;
                tb_accel_tri_hit d = {(uint32_t)j, s.refs[j].sub, 0, 0.0, {0, 0, 0}};
                if (kept[j].object != TB_ACCEL_TRI_NONE) {
                    if (!tt_tri(&kept[j], &ray, &d))
                        continue;
                    h = (tb_hit){(float)d.t, kept[j].object, kept[j].face, 0.0f, 0.0f, {0.0f, 0.0f, 0.0f}};
                } else {
                    if (!tp_intersect_prim(&s.prims[j], &ray, &h))
                        continue;
                    d.index = TB_ACCEL_TRI_NONE;
                }
                if (!found || tb__accel_before(&h, (uint32_t)j, &best, best_i)) {
                    found = true;
                    best = h;
                    best_i = (uint32_t)j;
                    best_d = d;
                }
            }
        }
        hits += found;
        tri_hits += found && best_d.index != TB_ACCEL_TRI_NONE;
        for (int k = 0; k < NKINDS; k++) {
            tb_hit h;
            tb_accel_tri_hit d;
            memset(&d, 0xAB, sizeof d);
            bool f = tb_accel_intersect_tri(acc[k], &ray, &h, &d);
            assert_int_equal(f, found);
            assert_int_equal(tb_accel_occluded(acc[k], &ray), found);
            if (!f) {
                assert_int_equal(d.index, TB_ACCEL_TRI_NONE);
                continue;
            }
            assert_memory_equal(&h, &best, sizeof h);
            assert_int_equal(d.index, best_d.index);
            if (d.index != TB_ACCEL_TRI_NONE) {
                assert_int_equal(d.sub, best_d.sub);
                assert_int_equal(d.dir, best_d.dir);
                assert_memory_equal(&d.t, &best_d.t, sizeof d.t);
                assert_memory_equal(d.uvw, best_d.uvw, sizeof d.uvw);
            }
        }
    }
    print_message("[ tri refs ] %zu references (%zu triangles), %ld rays, %ld hits (%ld on triangles)\n", s.n, ntri,
                  nrays, hits, tri_hits);
    assert_true(tri_hits > nrays / 50); /* small triangles among spheres */
    assert_true(hits - tri_hits > nrays / 10);
    for (int k = 0; k < NKINDS; k++)
        tb_accel_free(acc[k]);
    free(kept);
    tp_free(&s);
}

/* Records made by tb_accel_build_owned's callback: counts the calls, and
 * checks that it is handed the reference the index names. */
typedef struct tt_tri_maker {
    const tp_scene *s;
    const tb_accel_prim *refs; /* the input, for the check */
    size_t calls;
} tt_tri_maker;

/* The record of test primitive p (object TB_ACCEL_TRI_NONE unless a triangle). */
static void tt_tri_record(const tp_prim *p, tb_accel_tri *out)
{
    *out = (tb_accel_tri){.object = TB_ACCEL_TRI_NONE};
    if (p->kind != TP_TRIANGLE)
        return;
    for (int j = 0; j < 9; j++)
        out->v[j] = p->v[j / 3][j % 3];
    out->object = p->object;
    out->face = p->face;
}

static void tt_make_tri(void *ctx, const tb_accel_prim *prim, uint32_t index, tb_accel_tri *out)
{
    tt_tri_maker *m = ctx;
    m->calls++;
    assert_memory_equal(prim, &m->refs[index], sizeof *prim);
    assert_false(tb_aabb_is_empty(&prim->bounds)); /* dropped references are never asked for */
    tt_tri_record(&m->s->prims[prim->sub], out);
}

/* tb_accel_build_owned (the structure takes the reference array, and makes
 * the triangle records through a callback after its tree is built) gives
 * the structure tb_accel_build gives with a copied array and records, bit
 * for bit, empty references dropped alike; a refused build frees the array. */
static void test_owned_build(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("owned_build", 91), 0);
    tp_scene s = {0};
    tp_random_scene(&s, &r, 5000, 1.0f, 0.0f);
    tb_accel_prim *in = malloc(s.n * sizeof *in);
    tb_accel_tri *tris = malloc(s.n * sizeof *tris);
    assert_non_null(in);
    assert_non_null(tris);
    memcpy(in, s.refs, s.n * sizeof *in);
    size_t ntri = 0, nempty = 0;
    for (size_t i = 0; i < s.n; i++) {
        if (i % 97 == 5) { /* some empty references, which both builds drop */
            in[i].bounds = tb_aabb_empty();
            nempty++;
        }
        tt_tri_record(&s.prims[i], &tris[i]);
        ntri += tris[i].object != TB_ACCEL_TRI_NONE;
    }
    assert_true(ntri > s.n / 4 && nempty > 10);
    tt_ctx ctx = {&s};
    for (int k = 0; k < NKINDS; k++) {
        tb_accel_callbacks cb_copy = {tt_sphere_only, NULL, &ctx, tris};
        tb_accel_callbacks cb_own = {tt_sphere_only, NULL, &ctx, NULL};
        tb_accel *a, *b;
        assert_int_equal(tb_accel_build(kinds[k], in, s.n, &cb_copy, NULL, &a), TB_OK);
        tb_accel_prim *owned = malloc(s.n * sizeof *owned);
        assert_non_null(owned);
        memcpy(owned, in, s.n * sizeof *owned);
        tt_tri_maker mk = {&s, in, 0};
        assert_int_equal(tb_accel_build_owned(kinds[k], owned, s.n, &cb_own, tt_make_tri, &mk, NULL, &b), TB_OK);
        assert_int_equal(a->n, s.n - nempty);
        assert_int_equal(b->n, a->n);
        assert_true(mk.calls >= b->n); /* every kept reference asked for, no dropped one */
        assert_memory_equal(a->prims, b->prims, a->n * sizeof *a->prims);
        assert_memory_equal(a->index, b->index, a->n * sizeof *a->index);
        for (size_t j = 0; j < a->n; j++) {
            tb_accel_tri ta, tb2;
            const tb_accel_tri *ra = tb__accel_tri_at(a, j, &ta), *rb = tb__accel_tri_at(b, j, &tb2);
            assert_int_equal(ra != NULL, rb != NULL);
            if (ra)
                assert_memory_equal(ra, rb, sizeof *ra);
        }
        assert_int_equal(a->nwide, b->nwide);
        if (a->nwide)
            assert_memory_equal(a->wide, b->wide, a->nwide * sizeof *a->wide);
        for (int i = 0; i < 2000; i++) {
            tb_ray ray = tp_random_ray(&r, &s, 1.0f, 0.0f);
            tb_hit ha, hb;
            tb_accel_tri_hit da, db;
            memset(&ha, 0, sizeof ha);
            memset(&hb, 0, sizeof hb);
            memset(&da, 0, sizeof da);
            memset(&db, 0, sizeof db);
            bool fa = tb_accel_intersect_tri(a, &ray, &ha, &da), fb = tb_accel_intersect_tri(b, &ray, &hb, &db);
            assert_int_equal(fa, fb);
            assert_memory_equal(&ha, &hb, sizeof ha);
            assert_memory_equal(&da, &db, sizeof da);
            assert_int_equal(tb_accel_occluded(a, &ray), tb_accel_occluded(b, &ray));
        }
        tb_accel_free(a);
        tb_accel_free(b);
    }
    /* Refused (a NaN corner): the array is freed by the build (the leak checker of the ASan build sees it). */
    tb_accel_prim *bad = malloc(s.n * sizeof *bad);
    assert_non_null(bad);
    memcpy(bad, in, s.n * sizeof *bad);
    bad[s.n / 2].bounds.hi.y = NAN;
    tb_accel_callbacks cb = {tt_sphere_only, NULL, &ctx, NULL};
    tb_accel *c = (tb_accel *)&cb;
    assert_int_equal(tb_accel_build_owned(TB_ACCEL_BVH, bad, s.n, &cb, tt_make_tri, NULL, NULL, &c), TB_ERR_ARG);
    assert_null(c);
    /* Nothing but empty references: an empty structure, the array freed. */
    tb_accel_prim *empty = malloc(3 * sizeof *empty);
    assert_non_null(empty);
    for (int i = 0; i < 3; i++)
        empty[i] = (tb_accel_prim){tb_aabb_empty(), 0, (uint32_t)i};
    assert_int_equal(tb_accel_build_owned(TB_ACCEL_BVH, empty, 3, &cb, tt_make_tri, NULL, NULL, &c), TB_OK);
    assert_int_equal(c->n, 0);
    tb_hit h;
    tb_ray ray = tb_ray_make(tb_vec3_make(0, 0, -5), tb_vec3_make(0, 0, 1), 0.0f, INFINITY);
    assert_false(tb_accel_intersect(c, &ray, &h));
    tb_accel_free(c);
    free(in);
    free(tris);
    tp_free(&s);
}

static void test_callback_range_not_trusted(void **state)
{
    (void)state;
    tp_scene s = {0};
    tp_add_sphere(&s, 0, 0, 0, 10, 1, 0);
    float t = 4.0f;
    tb_accel_callbacks cb = {liar, NULL, &t, NULL};
    for (int k = 0; k < NKINDS; k++) {
        tb_accel *acc;
        assert_int_equal(tb_accel_build(kinds[k], s.refs, s.n, &cb, NULL, &acc), TB_OK);
        t = 4.0f;
        tb_ray r = ray(-20, 0, 0, 1, 0, 0, 0, 3.0f);
        expect_miss(acc, &r);
        r = ray(-20, 0, 0, 1, 0, 0, 5.0f, 30.0f);
        expect_miss(acc, &r);
        r = ray(-20, 0, 0, 1, 0, 0, 0, 30.0f);
        expect_hit(acc, &r, 4.0f, 1, 0);
        t = NAN;
        expect_miss(acc, &r);
        tb_accel_free(acc);
    }
    tp_free(&s);
}

/* Box primitives whose surface is the box itself: the hit is the ray's
 * entry into the box, reported `shrink` (relative) too early. */
typedef struct boxprim {
    tb_aabb box;
    uint32_t object;
    double shrink;
} boxprim;

static bool box_intersect(void *ctx, const tb_accel_prim *prim, uint32_t index, const tb_ray *r, tb_hit *hit)
{
    (void)prim;
    const boxprim *b = &((const boxprim *)ctx)[index];
    double o[3] = {r->o.x, r->o.y, r->o.z}, d[3] = {r->d.x, r->d.y, r->d.z};
    double lo[3] = {b->box.lo.x, b->box.lo.y, b->box.lo.z}, hi[3] = {b->box.hi.x, b->box.hi.y, b->box.hi.z};
    double t0 = -INFINITY, t1 = INFINITY;
    for (int a = 0; a < 3; a++) {
        if (d[a] == 0.0) {
            if (o[a] < lo[a] || o[a] > hi[a])
                return false;
            continue;
        }
        double ta = (lo[a] - o[a]) / d[a], tb = (hi[a] - o[a]) / d[a];
        t0 = fmax(t0, fmin(ta, tb));
        t1 = fmin(t1, fmax(ta, tb));
    }
    if (!(t0 <= t1 && t0 > 0.0))
        return false;
    float t = (float)(t0 * (1.0 - b->shrink));
    if (!(t >= r->tmin && t <= r->tmax))
        return false;
    *hit = (tb_hit){.t = t, .object = b->object};
    return true;
}

/* The traversal tolerance (docs/accel.md, "Robustness"): a callback may
 * report t up to 2^-16 (relative) before the ray reaches its box. Box A
 * (object 0) reports its entry 2^-17 early, which puts it before the hit on
 * the thin box B (object 1) just in front of it, so A is the answer; but A's
 * box only starts after B's hit, and in the grid in the next voxel. A BVH
 * that prunes A's node with the unwidened best t, or a grid walk that stops
 * at B's voxel, returns B. */
static void test_t_tolerance(void **state)
{
    (void)state;
    boxprim bp[4] = {
        {{{-4.01f, -4.01f, -4.01f}, {-3.99f, -3.99f, -3.99f}}, 100, 0.0}, /* pin the grid box */
        {{{3.99f, 3.99f, 3.99f}, {4.01f, 4.01f, 4.01f}}, 101, 0.0},
        {{{0, -0.5f, -0.5f}, {1, 0.5f, 0.5f}}, 0, 0x1p-17},              /* A, placed below */
        {{{0, -0.5f, -0.5f}, {0, 0.5f, 0.5f}}, 1, 0.0},                  /* B, placed below */
    };
    tb_accel_callbacks cb = {box_intersect, NULL, bp, NULL};
    tb_accel_prim refs[4];
    for (int i = 0; i < 4; i++)
        refs[i] = (tb_accel_prim){bp[i].box, bp[i].object, 0};
    /* A voxel plane along x: the grid depends only on the frame and N, so
     * read it from a first build. */
    tb_accel *acc;
    assert_int_equal(tb_accel_build(TB_ACCEL_GRID, refs, 4, &cb, NULL, &acc), TB_OK);
    tb_accel_stats st;
    tb_accel_get_stats(acc, &st);
    tb_accel_free(acc);
    const int res = st.grid_res[0];
    assert_true(res >= 2);
    int k = res / 2;
    float b = st.grid_bounds.lo.x + (st.grid_bounds.hi.x - st.grid_bounds.lo.x) * (float)k / (float)st.grid_res[0];
    bp[2].box.lo.x = b + 1e-4f;
    bp[2].box.hi.x = b + 1.0f;
    bp[3].box.lo.x = b - 2e-4f;
    bp[3].box.hi.x = b - 1e-4f;
    for (int i = 2; i < 4; i++)
        refs[i].bounds = bp[i].box;
    tb_ray r = ray(-100, 0.1f, -0.2f, 1, 0, 0, 0, INFINITY);
    tb_hit ha, hb;
    assert_true(box_intersect(bp, &refs[2], 2, &r, &ha));
    assert_true(box_intersect(bp, &refs[3], 3, &r, &hb));
    assert_true(ha.t < hb.t);                       /* A is the answer, */
    assert_true(hb.t < 100.0f + bp[2].box.lo.x);    /* though its box starts after B's hit */
    for (int kk = 0; kk < NKINDS; kk++) {
        assert_int_equal(tb_accel_build(kinds[kk], refs, 4, &cb, NULL, &acc), TB_OK);
        expect_hit(acc, &r, ha.t, 0, 0);
        tb_accel_get_stats(acc, &st);
        if (kinds[kk] == TB_ACCEL_GRID) /* the same grid as the first build */
            assert_int_equal(st.grid_res[0], res);
        tb_accel_free(acc);
    }
}

/* The BVH's branch-free slab test answers exactly as util/math's
 * tb_aabb_slab on random boxes and rays, with signed zero directions,
 * origins on the box planes, flat boxes and random ranges. */
static void test_slab_matches_util(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("slab", 22);
    tb_rng r;
    tb_rng_seed(&r, seed, 3);
    const float vals[] = {-2, -1, -0.5f, 0, 0.5f, 1, 2};
    long agree_hit = 0;
    for (long i = 0; i < 400000; i++) {
        float lo[3], hi[3], o[3], d[3];
        for (int a = 0; a < 3; a++) {
            lo[a] = vals[tb_rng_below(&r, 7)];
            hi[a] = tb_rng_below(&r, 4) == 0 ? lo[a] : lo[a] + tp_uniform(&r, 0, 2);
            o[a] = tb_rng_below(&r, 3) == 0 ? (tb_rng_below(&r, 2) ? lo[a] : hi[a]) : tp_uniform(&r, -3, 3);
            unsigned m = tb_rng_below(&r, 6);
            d[a] = m == 0 ? 0.0f : m == 1 ? -0.0f : tp_uniform(&r, -1, 1);
        }
        if (tb_rng_below(&r, 2)) /* aimed at a point of the box (zero components stay zero) */
            for (int a = 0; a < 3; a++)
                if (d[a] != 0.0f)
                    d[a] = lo[a] + (hi[a] - lo[a]) * tb_rng_float(&r) - o[a];
        if (d[0] == 0.0f && d[1] == 0.0f && d[2] == 0.0f)
            d[0] = 1.0f;
        tb_aabb b = {{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}};
        tb_vec3 ov = {o[0], o[1], o[2]};
        tb_vec3 inv = {1.0f / d[0], 1.0f / d[1], 1.0f / d[2]};
        bool neg[3] = {signbit(inv.x) != 0, signbit(inv.y) != 0, signbit(inv.z) != 0};
        float tmin = tb_rng_below(&r, 2) ? 0.0f : tp_uniform(&r, -3, 3);
        float tmax = tb_rng_below(&r, 2) ? INFINITY : tmin + tp_uniform(&r, 0, 3);
        bool want = tb_aabb_slab(&b, ov, inv, tmin, tmax, NULL, NULL);
        bool got = tb__accel_slab(&b, ov, inv, neg, tmin, tmax);
        if (want != got)
            fail_msg("case %ld: box (%a %a %a)..(%a %a %a) o %a %a %a d %a %a %a [%a, %a]: util %d, accel %d", i,
                     (double)lo[0], (double)lo[1], (double)lo[2], (double)hi[0], (double)hi[1], (double)hi[2],
                     (double)o[0], (double)o[1], (double)o[2], (double)d[0], (double)d[1], (double)d[2],
                     (double)tmin, (double)tmax, want, got);
        agree_hit += want;
    }
    assert_true(agree_hit > 40000); /* both answers occur often */
    assert_true(agree_hit < 360000);
}

/* The wide node test (eight children: two SSE2 tests, or one AVX test
 * where the CPU has AVX) answers, lane for lane, exactly as the scalar
 * tb__accel_slab_t: the same met/missed bit and, when met, the same entry
 * distance bit for bit, on random boxes with flat sides, origins on the
 * planes of a child's box, signed zero directions and random ranges; an
 * unused slot (lo +inf, hi -inf) is never met. Both instruction sets. */
static void test_bvhw_slab_matches_scalar(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("slab8", 23);
    tb_rng r;
    tb_rng_seed(&r, seed, 4);
    const float vals[] = {-2, -1, -0.5f, 0, 0.5f, 1, 2};
    long met = 0, lanes = 0, avx_cases = 0;
    for (long i = 0; i < 100000; i++) {
        tb__bvhw_node nd;
        memset(&nd, 0, sizeof nd);
        tb_aabb b[TB__BVHW];
        int used = 1 + (int)tb_rng_below(&r, TB__BVHW);
        for (int c = 0; c < TB__BVHW; c++) {
            float lo[3], hi[3];
            for (int a = 0; a < 3; a++) {
                lo[a] = vals[tb_rng_below(&r, 7)];
                hi[a] = tb_rng_below(&r, 4) == 0 ? lo[a] : lo[a] + tp_uniform(&r, 0, 2);
            }
            b[c] = (tb_aabb){{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}};
            if (c >= used)
                b[c] = (tb_aabb){{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
            nd.box[0][c] = b[c].lo.x, nd.box[1][c] = b[c].hi.x;
            nd.box[2][c] = b[c].lo.y, nd.box[3][c] = b[c].hi.y;
            nd.box[4][c] = b[c].lo.z, nd.box[5][c] = b[c].hi.z;
        }
        nd.n = (uint8_t)used;
        float o[3], d[3];
        const tb_aabb *on = &b[tb_rng_below(&r, (uint32_t)used)];
        for (int a = 0; a < 3; a++) {
            o[a] = tb_rng_below(&r, 3) == 0 ? (tb_rng_below(&r, 2) ? tb_vec3_get(on->lo, a) : tb_vec3_get(on->hi, a))
                                            : tp_uniform(&r, -3, 3);
            unsigned m = tb_rng_below(&r, 6);
            d[a] = m == 0 ? 0.0f : m == 1 ? -0.0f : tp_uniform(&r, -1, 1);
        }
        if (tb_rng_below(&r, 2)) /* aimed at a point of one child's box (zero components stay zero) */
            for (int a = 0; a < 3; a++)
                if (d[a] != 0.0f)
                    d[a] = tb_vec3_get(on->lo, a) + (tb_vec3_get(on->hi, a) - tb_vec3_get(on->lo, a)) * tb_rng_float(&r) - o[a];
        if (d[0] == 0.0f && d[1] == 0.0f && d[2] == 0.0f)
            d[0] = -1.0f;
        tb_ray ry = ray(o[0], o[1], o[2], d[0], d[1], d[2], 0.0f, INFINITY);
        tb_vec3 inv = {1.0f / d[0], 1.0f / d[1], 1.0f / d[2]};
        bool neg[3] = {signbit(inv.x) != 0, signbit(inv.y) != 0, signbit(inv.z) != 0};
        float tmin = tb_rng_below(&r, 2) ? 0.0f : tp_uniform(&r, -3, 3);
        float tmax = tb_rng_below(&r, 2) ? INFINITY : tmin + tp_uniform(&r, 0, 3);
        float tn4[TB__BVHW];
        bool avx = tb__bvhw_have_avx() && (i & 1);
        avx_cases += avx;
        unsigned mask = tb__bvhw_slab_test(&nd, &ry, tmin, tmax, tn4, avx);
        assert_true(mask < 1u << TB__BVHW);
        for (int c = 0; c < TB__BVHW; c++) {
            float tn;
            bool want = tb__accel_slab_t(&b[c], ry.o, inv, neg, tmin, tmax, &tn);
            bool got = (mask >> c & 1u) != 0;
            if (c >= used)
                assert_false(got);
            if (want != got || (want && memcmp(&tn, &tn4[c], sizeof tn) != 0))
                fail_msg("case %ld child %d (%s): box (%a %a %a)..(%a %a %a) o %a %a %a d %a %a %a [%a, %a]: scalar "
                         "%d t %a, wide %d t %a",
                         i, c, avx ? "AVX" : "SSE2", (double)b[c].lo.x, (double)b[c].lo.y, (double)b[c].lo.z, (double)b[c].hi.x,
                         (double)b[c].hi.y, (double)b[c].hi.z, (double)o[0], (double)o[1], (double)o[2], (double)d[0],
                         (double)d[1], (double)d[2], (double)tmin, (double)tmax, want, (double)tn, got,
                         (double)tn4[c]);
            met += want;
            lanes += c < used;
        }
    }
    assert_true(met > lanes / 40); /* both answers occur often (a ray is aimed at one of up to 8 boxes) */
    assert_true(met < lanes * 9 / 10);
    print_message("[ slab8 ] %ld lanes, %ld met; %ld of 100000 nodes through the AVX test%s\n", lanes, met, avx_cases,
                  tb__bvhw_have_avx() ? "" : " (no AVX here)");
}

/* Checks the wide tree against the binary one it collapses: nodes in
 * depth-first order, reached once each; every reference in exactly one leaf
 * child, leaves as the binary ones (same ranges); each child's box exactly
 * the union of what lies below it; unused slots empty; each octant's order a
 * permutation of the children; fewer nodes than the binary inner nodes. */
static void check_bvhw(const tb_accel *acc, int max_leaf)
{
    tb_accel_stats st;
    tb_accel_get_stats(acc, &st);
    assert_int_equal(st.bvh_wide_nodes, acc->nwide);
    assert_true(acc->nwide >= 1 && acc->nwide <= (st.bvh_nodes - st.bvh_leaves > 0 ? st.bvh_nodes - st.bvh_leaves : 1));
    assert_true(((uintptr_t)acc->wide & 63u) == 0);
    assert_int_equal(acc->wide_avx, tb__bvhw_have_avx()); /* built with the default options */
    /* Binary leaves by first reference: the wide leaves must be exactly these. */
    uint16_t *bin_count = calloc(acc->n, sizeof *bin_count);
    char *seen = calloc(acc->n, 1), *reached = calloc(acc->nwide, 1);
    assert_true(bin_count && seen && reached);
    for (size_t i = 0; i < acc->nnodes; i++)
        if (acc->nodes[i].count)
            bin_count[acc->nodes[i].offset] = acc->nodes[i].count;
    for (size_t w = 0; w < acc->nwide; w++) {
        const tb__bvhw_node *nd = &acc->wide[w];
        assert_true(nd->n >= 1 && nd->n <= TB__BVHW);
        assert_int_equal(nd->used, (1u << nd->n) - 1u);
        if (w > 0)
            assert_true(reached[w]); /* parents come first (depth-first) */
        for (unsigned oct = 0; oct < 8; oct++) {
            unsigned used = 0;
            for (unsigned j = 0; j < nd->n; j++)
                used |= 1u << (nd->order[oct] >> (3 * j) & 7u);
            assert_int_equal(used, (1u << nd->n) - 1u);
            assert_int_equal(nd->order[oct] >> (3 * nd->n), 0);
        }
        for (int c = 0; c < TB__BVHW; c++) {
            tb_aabb box = {{nd->box[0][c], nd->box[2][c], nd->box[4][c]}, {nd->box[1][c], nd->box[3][c], nd->box[5][c]}};
            if (c >= nd->n) {
                assert_true(box.lo.x == INFINITY && box.lo.y == INFINITY && box.lo.z == INFINITY);
                assert_true(box.hi.x == -INFINITY && box.hi.y == -INFINITY && box.hi.z == -INFINITY);
                assert_int_equal(nd->count[c], 0);
                continue;
            }
            tb_aabb u = tb_aabb_empty();
            if (nd->count[c]) {
                uint32_t cnt = TB__BVHW_COUNT(nd->count[c]);
                assert_true(cnt >= 1 && cnt <= (uint32_t)max_leaf);
                assert_true(nd->child[c] + cnt <= acc->n);
                assert_int_equal(bin_count[nd->child[c]], cnt);
                for (uint32_t k = nd->child[c]; k < nd->child[c] + cnt; k++) {
                    assert_int_equal(seen[k], 0);
                    seen[k] = 1;
                    u = tb_aabb_union(u, acc->prims[k].bounds);
                }
            } else {
                uint32_t ch = nd->child[c];
                assert_true(ch > w && ch < acc->nwide);
                assert_int_equal(reached[ch], 0);
                reached[ch] = 1;
                const tb__bvhw_node *cn = &acc->wide[ch];
                for (int j = 0; j < cn->n; j++)
                    u = tb_aabb_union(u, (tb_aabb){{cn->box[0][j], cn->box[2][j], cn->box[4][j]},
                                                  {cn->box[1][j], cn->box[3][j], cn->box[5][j]}});
            }
            assert_true(tb_vec3_equal(u.lo, box.lo) && tb_vec3_equal(u.hi, box.hi));
        }
    }
    for (size_t k = 0; k < acc->n; k++)
        assert_int_equal(seen[k], 1);
    free(bin_count);
    free(seen);
    free(reached);
}

/* Half surface area in double (the collapse's measure). */
static double wide_area(const tb_aabb *b)
{
    double ex = (double)b->hi.x - b->lo.x, ey = (double)b->hi.y - b->lo.y, ez = (double)b->hi.z - b->lo.z;
    return ex * ey + ey * ez + ez * ex;
}

/* The sum of the areas of acc's wide nodes (each the union of its children's boxes). */
static double wide_total_area(const tb_accel *acc)
{
    double sum = 0.0;
    for (size_t w = 0; w < acc->nwide; w++) {
        const tb__bvhw_node *nd = &acc->wide[w];
        tb_aabb u = tb_aabb_empty();
        for (unsigned c = 0; c < nd->n; c++)
            u = tb_aabb_union(u, (tb_aabb){{nd->box[0][c], nd->box[2][c], nd->box[4][c]},
                                           {nd->box[1][c], nd->box[3][c], nd->box[5][c]}});
        sum += wide_area(&u);
    }
    return sum;
}

/* The greedy collapse the wide tree had before (open the inner child of
 * largest area until eight children): the sum of its nodes' areas. */
static double greedy_total_area(const tb_bvh_node *bin, uint32_t b)
{
    if (bin[b].count)
        return wide_area(&bin[b].bounds);
    uint32_t kids[8] = {b + 1, bin[b].offset};
    int nk = 2;
    while (nk < 8) {
        int best = -1;
        double best_a = -1.0;
        for (int i = 0; i < nk; i++)
            if (bin[kids[i]].count == 0 && wide_area(&bin[kids[i]].bounds) > best_a) {
                best = i;
                best_a = wide_area(&bin[kids[i]].bounds);
            }
        if (best < 0)
            break;
        uint32_t k = kids[best];
        memmove(&kids[best + 2], &kids[best + 1], (size_t)(nk - best - 1) * sizeof kids[0]);
        kids[best] = k + 1;
        kids[best + 1] = bin[k].offset;
        nk++;
    }
    double sum = wide_area(&bin[b].bounds);
    for (int i = 0; i < nk; i++)
        if (bin[kids[i]].count == 0)
            sum += greedy_total_area(bin, kids[i]);
    return sum;
}

/* Children of binary node b when the inner nodes flagged in `roots` start wide nodes. */
static int cut_children(const tb_bvh_node *bin, uint32_t b, const bool *roots)
{
    if (bin[b].count || roots[b])
        return 1;
    return cut_children(bin, b + 1, roots) + cut_children(bin, bin[b].offset, roots);
}

/* The least sum of wide-node areas over every way to collapse a small binary
 * tree (every subset of inner nodes as wide-node roots, each with at most 8
 * children), by exhaustion: an independent check of the dynamic programme. */
static double best_total_area(const tb_bvh_node *bin, size_t nnodes)
{
    uint32_t inner[64];
    int ni = 0;
    for (size_t i = 1; i < nnodes; i++)
        if (bin[i].count == 0)
            inner[ni++] = (uint32_t)i;
    assert_true(ni <= 20);
    bool roots[128] = {0};
    double best = INFINITY;
    for (uint32_t mask = 0; mask < (1u << ni); mask++) {
        for (int i = 0; i < ni; i++)
            roots[inner[i]] = mask >> i & 1u;
        roots[0] = true;
        bool ok = true;
        double sum = 0.0;
        for (size_t i = 0; i < nnodes && ok; i++) {
            if (!roots[i] || bin[i].count)
                continue;
            ok = cut_children(bin, (uint32_t)i + 1, roots) + cut_children(bin, bin[i].offset, roots) <= 8;
            sum += wide_area(&bin[i].bounds);
        }
        if (ok && sum < best)
            best = sum;
    }
    return best;
}

/* The collapse's choice: the least sum of wide-node areas (checked by
 * exhaustion on small trees), never more than the greedy collapse's. */
static void test_bvhw_collapse_optimal(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("bvhw_collapse", 33), 0);
    for (int trial = 0; trial < 30; trial++) {
        tp_scene s = {0};
        size_t n = 6 + tb_rng_below(&r, 9); /* up to 13 inner nodes with leaves of 1 */
        tp_random_scene(&s, &r, n, 1.0f, 0.0f);
        tb_accel *acc = build(TB_ACCEL_BVH, &s, &(tb_accel_options){.bvh_max_leaf = 1, .bvh_keep_binary = 1});
        if (acc->nnodes > 1) {
            double got = wide_total_area(acc), best = best_total_area(acc->nodes, acc->nnodes);
            assert_true(fabs(got - best) <= 1e-9 * best);
        }
        tb_accel_free(acc);
        tp_free(&s);
    }
    const size_t sizes[] = {1000, 20000};
    for (int i = 0; i < 2; i++) {
        tp_scene s = {0};
        tp_random_scene(&s, &r, sizes[i], 1.0f, 0.0f);
        tb_accel *acc = build(TB_ACCEL_BVH, &s, &(tb_accel_options){.bvh_keep_binary = 1});
        double got = wide_total_area(acc), greedy = greedy_total_area(acc->nodes, 0);
        print_message("[ bvhw collapse ] %zu references: wide-node area sum %.4g (greedy %.4g)\n", sizes[i], got,
                      greedy);
        assert_true(got <= greedy * (1.0 + 1e-12));
        tb_accel_free(acc);
        tp_free(&s);
    }
}

static void test_bvhw_structure(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("bvhw", 24);
    tb_rng r;
    tb_rng_seed(&r, seed, 5);
    const size_t sizes[] = {1, 2, 3, 5, 17, 1000, 20000};
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++)
        for (int max_leaf = 1; max_leaf <= 8; max_leaf += 7) {
            tp_scene s = {0};
            tp_random_scene(&s, &r, sizes[i], 1.0f, 0.0f);
            tb_accel *acc = build(TB_ACCEL_BVH, &s, &(tb_accel_options){.bvh_max_leaf = max_leaf, .bvh_keep_binary = 1});
            check_bvhw(acc, max_leaf);
            tb_accel_stats st;
            tb_accel_get_stats(acc, &st);
            /* Collapsing 8-wide keeps well under half of the binary inner nodes. */
            if (sizes[i] >= 1000)
                assert_true(5 * st.bvh_wide_nodes < 2 * (st.bvh_nodes - st.bvh_leaves));
            tb_accel_free(acc);
            tp_free(&s);
        }
}

/* The current total of counter `name` (0 when it has not been touched). */
static int64_t counter(const char *name)
{
    tb_stat_total t;
    return tb_stats_get(name, TB_STAT_KIND_COUNTER, &t) == TB_OK ? t.v[0] : 0;
}

/* The SSE2 and the AVX traversal of one tree (tb_accel_options.bvh_no_avx)
 * give the same answers, bit for bit, and visit the same nodes and test the
 * same references (the counters), closest and any hit, on random scenes
 * with the random rays of render_accel_compare. Where the CPU lacks AVX
 * both runs take the SSE2 path (the test then says so). */
static void test_bvhw_avx_matches_sse(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("bvhw_isa", 25);
    tb_rng r;
    tb_rng_seed(&r, seed, 6);
    tp_scene s = {0};
    tp_random_scene(&s, &r, 5000, 1.0f, 0.0f);
    tb_accel *fast = build(TB_ACCEL_BVH, &s, NULL);
    tb_accel *sse = build(TB_ACCEL_BVH, &s, &(tb_accel_options){.bvh_no_avx = 1});
    assert_false(sse->wide_avx);
    assert_int_equal(fast->wide_avx, tb__bvhw_have_avx());
    assert_int_equal(fast->nwide, sse->nwide);
    assert_memory_equal(fast->wide, sse->wide, fast->nwide * sizeof *fast->wide);
    int was = tb_stats_enabled();
    tb_stats_set_enabled(1);
    long hits = 0;
    for (long i = 0; i < 20000; i++) {
        tb_ray ry = tp_random_ray(&r, &s, 1.0f, 0.0f);
        tb_hit a, b;
        int64_t n0 = counter("BVH/nodes visited"), p0 = counter("BVH/primitives tested");
        bool fa = tb_accel_intersect(fast, &ry, &a);
        int64_t n1 = counter("BVH/nodes visited"), p1 = counter("BVH/primitives tested");
        bool fb = tb_accel_intersect(sse, &ry, &b);
        int64_t n2 = counter("BVH/nodes visited"), p2 = counter("BVH/primitives tested");
        assert_int_equal(fa, fb);
        if (fa)
            assert_memory_equal(&a, &b, sizeof a);
        assert_int_equal(n1 - n0, n2 - n1);
        assert_int_equal(p1 - p0, p2 - p1);
        assert_int_equal(tb_accel_occluded(fast, &ry), tb_accel_occluded(sse, &ry));
        hits += fa;
    }
    tb_stats_set_enabled(was);
    print_message("[ bvhw isa ] 20000 rays, %ld hits: AVX %s\n", hits,
                  tb__bvhw_have_avx() ? "and SSE2 traversals agree" : "not available here (SSE2 twice)");
    assert_true(hits > 2000);
    tb_accel_free(fast);
    tb_accel_free(sse);
    tp_free(&s);
}

/* tb__bvhw_pos against a search of the order word, for every child of
 * 20 000 random orders of 1 to 8 children. */
static void test_bvhw_order_position(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("bvhw_pos", 32), 0);
    long checked = 0;
    for (int trial = 0; trial < 20000; trial++) {
        unsigned n = 1 + tb_rng_below(&r, 8), perm[8];
        for (unsigned i = 0; i < n; i++)
            perm[i] = i;
        for (unsigned i = n; i-- > 1;) {
            unsigned j = tb_rng_below(&r, i + 1), t = perm[i];
            perm[i] = perm[j];
            perm[j] = t;
        }
        uint32_t ord = 0;
        for (unsigned i = 0; i < n; i++)
            ord |= (uint32_t)perm[i] << (3 * i);
        for (unsigned c = 0; c < n; c++) {
            unsigned want = 0;
            while (perm[want] != c)
                want++;
            assert_int_equal(tb__bvhw_pos(ord, c), 3 * want);
            checked++;
        }
    }
    print_message("[ bvhw pos ] %ld positions\n", checked);
}

/* A never-called callback: every reference of the packed-leaf scenes is a triangle. */
static bool pk_no_callback(void *ctx, const tb_accel_prim *prim, uint32_t index, const tb_ray *ray, tb_hit *hit)
{
    (void)ctx, (void)prim, (void)index, (void)ray, (void)hit;
    abort();
}

/* Appends triangle (a, b, c) to tris / refs (its box) as object obj, face
 * f; f32: its corners rounded to float. */
static void pk_add(tb_accel_tri *tris, tb_accel_prim *refs, size_t *n, const double a[3], const double b[3],
                   const double c[3], uint32_t obj, uint32_t f, bool f32)
{
    tb_accel_tri *t = &tris[*n];
    for (int j = 0; j < 3; j++) {
        t->v[j] = f32 ? (float)a[j] : a[j];
        t->v[3 + j] = f32 ? (float)b[j] : b[j];
        t->v[6 + j] = f32 ? (float)c[j] : c[j];
    }
    t->object = obj;
    t->face = f;
    tb_aabb box = tb_aabb_empty();
    for (int j = 0; j < 3; j++) {
        tb_vec3 p = {(float)t->v[3 * j], (float)t->v[3 * j + 1], (float)t->v[3 * j + 2]};
        /* Outward-rounded float box of the double corners. */
        tb_vec3 lo = {nextafterf(p.x, -INFINITY), nextafterf(p.y, -INFINITY), nextafterf(p.z, -INFINITY)};
        tb_vec3 hi = {nextafterf(p.x, INFINITY), nextafterf(p.y, INFINITY), nextafterf(p.z, INFINITY)};
        box = tb_aabb_union(box, (tb_aabb){lo, hi});
    }
    refs[*n] = (tb_accel_prim){box, obj, f};
    (*n)++;
}

/* Packed leaves (docs/accel.md "Packed leaves"), in both layouts (float
 * corners when all are floats, else double): on triangles only, with the
 * hard cases of the tie rule (a grid mesh whose shared edges and vertices
 * rays hit exactly, so edge functions come out 0), coincident duplicates,
 * zero-area and collinear triangles, huge and tiny scales, rays with
 * negative tmin (the node test's full widening), axis-parallel and grazing
 * rays, the packed traversal (AVX and SSE2) must give the one-by-one
 * traversal's hits bit for bit, with its (u, v) details, the same occlusion
 * answers and the same node and reference counts, for leaves of 1, 3 and 8
 * references (partial vectors). */
static void test_packed_leaves(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("packed_leaves", 31), 0);
    enum { G = 24, NT = 2 * G * G + 200 };
    tb_accel_tri *tris = malloc(NT * sizeof *tris);
    tb_accel_prim *refs = malloc(NT * sizeof *refs);
    assert_non_null(tris);
    assert_non_null(refs);
    long hits = 0, zero_rays = 0, total = 0;
    size_t n = 0;
    for (int variant = 0; variant < 2; variant++) {
        bool f32 = variant == 0;
        n = 0;
        /* A G x G grid of quads in z = 0 (object 0), two triangles each, corners on integers. */
        for (int y = 0; y < G; y++)
            for (int x = 0; x < G; x++) {
                double a[3] = {x, y, 0}, b[3] = {x + 1, y, 0}, c[3] = {x + 1, y + 1, 0}, d[3] = {x, y + 1, 0};
                pk_add(tris, refs, &n, a, b, c, 0, (uint32_t)(2 * (y * G + x)), f32);
                pk_add(tris, refs, &n, a, c, d, 0, (uint32_t)(2 * (y * G + x) + 1), f32);
            }
        /* Object 1: coincident copies of grid triangles, zero-area and collinear
         * triangles, and triangles at huge and tiny scales. */
        for (int i = 0; i < 40; i++) {
            const tb_accel_tri *t = &tris[tb_rng_below(&r, (uint32_t)(2 * G * G))];
            pk_add(tris, refs, &n, &t->v[0], &t->v[3], &t->v[6], 1, (uint32_t)i, f32);
        }
        for (int i = 0; i < 40; i++) {
            double p[3] = {tb_rng_float(&r) * G, tb_rng_float(&r) * G, tb_rng_float(&r) * 2 - 1};
            double q[3] = {p[0] + 1, p[1] + 0.5, p[2]}, m[3] = {p[0] + 2, p[1] + 1, p[2]};
            /* collinear, or two corners equal */
            pk_add(tris, refs, &n, p, q, i % 2 ? m : p, 1, (uint32_t)(100 + i), f32);
        }
        for (int i = 0; i < 60; i++) {
            double s = i % 2 ? 1e-6 : 1e6;
            double c0[3] = {tb_rng_float(&r) * G, tb_rng_float(&r) * G, 0.5 + tb_rng_float(&r)};
            double a[3] = {c0[0], c0[1], c0[2]}, b[3] = {c0[0] + s, c0[1], c0[2] + s};
            double c[3] = {c0[0], c0[1] + s, c0[2]};
            pk_add(tris, refs, &n, a, b, c, 1, (uint32_t)(200 + i), f32);
        }
        int leaves[] = {1, 3, 8};
        for (int li = 0; li < 3; li++) {
            tb_accel_callbacks cb = {pk_no_callback, NULL, NULL, tris};
            tb_accel *pk, *pk_sse, *one, *list;
            assert_int_equal(
                tb_accel_build(TB_ACCEL_BVH, refs, n, &cb, &(tb_accel_options){.bvh_max_leaf = leaves[li]}, &pk), TB_OK);
            assert_int_equal(tb_accel_build(TB_ACCEL_BVH, refs, n, &cb,
                                            &(tb_accel_options){.bvh_max_leaf = leaves[li], .bvh_no_avx = 1}, &pk_sse),
                             TB_OK);
            assert_int_equal(tb_accel_build(TB_ACCEL_BVH, refs, n, &cb,
                                            &(tb_accel_options){.bvh_max_leaf = leaves[li], .bvh_no_pack = 1}, &one),
                             TB_OK);
            assert_int_equal(tb_accel_build(TB_ACCEL_LIST, refs, n, &cb, NULL, &list), TB_OK);
            assert_null(one->lanes);
            assert_non_null(pk->lanes);
            assert_int_equal(pk->lanes_f32, f32); /* the 1e-6 offsets of the double variant are no floats */
            /* Every reference a triangle: the records gave way to the lanes, not so without packing. */
            assert_null(pk->tris);
            assert_non_null(pk->lane_pos);
            /* ... and so did the reference array (the lanes keep index and sub). */
            assert_null(pk->prims);
            assert_null(pk->index);
            assert_non_null(one->tris);
            assert_null(one->lane_pos);
            assert_int_equal(pk_sse->lanes_f32, f32);
            /* Every leaf is packed, its rows and identities as the records say. */
            for (size_t w = 0; w < pk->nwide; w++) {
                const tb__bvhw_node *nd = &pk->wide[w];
                for (unsigned c = 0; c < nd->n; c++) {
                    if (!nd->count[c])
                        continue;
                    assert_true(nd->count[c] & TB__BVHW_PACKED);
                    uint32_t s0 = nd->child[c], cnt = TB__BVHW_COUNT(nd->count[c]);
                    const float *bf = (const float *)pk->lanes + TB__LANE_ROWS_F * (size_t)s0;
                    const double *bd = (const double *)pk->lanes + TB__LANE_ROWS * (size_t)s0;
                    const tb__lane_ids *ids = f32 ? (const tb__lane_ids *)(bf + 9 * (size_t)cnt)
                                                  : (const tb__lane_ids *)(bd + 9 * (size_t)cnt);
                    for (uint32_t j = 0; j < cnt; j++) {
                        /* The unpacked tree is the same tree: its reference array gives the stored order. */
                        const tb_accel_tri *in = &tris[one->index[s0 + j]]; /* the caller's record */
                        tb_accel_tri tmp;
                        const tb_accel_tri *back = tb__accel_tri_at(pk, s0 + j, &tmp); /* read back from the lanes */
                        assert_non_null(back);
                        for (unsigned row = 0; row < 9; row++) {
                            double v = f32 ? (double)bf[row * cnt + j] : bd[row * cnt + j];
                            assert_memory_equal(&v, &in->v[row], sizeof(double));
                            assert_memory_equal(&back->v[row], &in->v[row], sizeof(double));
                        }
                        assert_int_equal(ids[j].object, in->object);
                        assert_int_equal(ids[j].face, in->face);
                        assert_int_equal(back->object, in->object);
                        assert_int_equal(back->face, in->face);
                        assert_int_equal(ids[j].index, one->index[s0 + j]);
                        assert_int_equal(ids[j].sub, one->prims[s0 + j].sub);
                        uint32_t idx, sub;
                        tb__accel_ids(pk, s0 + j, &idx, &sub);
                        assert_int_equal(idx, one->index[s0 + j]);
                        assert_int_equal(sub, one->prims[s0 + j].sub);
                    }
                }
            }
            int was = tb_stats_enabled();
            tb_stats_set_enabled(1);
            for (long i = 0; i < 3000; i++) {
                tb_ray ry;
                int kind = (int)(i % 6);
                float tmin = i % 5 == 0 ? -3.0f : (i % 5 == 1 ? 0.0f : 1e-3f);
                if (kind <= 1) { /* down onto a grid vertex or an edge's midpoint: edge functions 0 */
                    float x = (float)tb_rng_below(&r, G), y = (float)tb_rng_below(&r, G);
                    if (kind == 1)
                        x += 0.5f;
                    float dx = i % 7 == 0 ? 0.0f : tb_rng_float(&r) - 0.5f;
                    float dy = i % 11 == 0 ? 0.0f : tb_rng_float(&r) - 0.5f;
                    ry = ray(x - 3 * dx, y - 3 * dy, 3.0f, dx, dy, -1.0f, tmin, INFINITY);
                    zero_rays++;
                } else if (kind == 2) { /* grazing: in the grid's plane */
                    ry = ray(-1.0f, tb_rng_float(&r) * G, 0.0f, 1.0f, tb_rng_float(&r) - 0.5f, 0.0f, tmin, INFINITY);
                } else if (kind == 3) { /* axis-parallel */
                    ry = ray(tb_rng_float(&r) * G, tb_rng_float(&r) * G, -2.0f, 0.0f, 0.0f, 1.0f, tmin, 10.0f);
                } else { /* anywhere, short and long */
                    tb_vec3 o = {tb_rng_float(&r) * G, tb_rng_float(&r) * G, tb_rng_float(&r) * 4 - 2};
                    tb_vec3 d = {tb_rng_float(&r) - 0.5f, tb_rng_float(&r) - 0.5f, tb_rng_float(&r) - 0.5f};
                    ry = tb_ray_make(o, d, tmin, kind == 4 ? 2.0f : INFINITY);
                }
                tb_hit h[4];
                tb_accel_tri_hit d[4];
                bool f[4];
                int64_t nodes[3], prims[3];
                tb_accel *acc[4] = {pk, pk_sse, one, list};
                for (int k = 0; k < 4; k++) {
                    int64_t n0 = counter("BVH/nodes visited"), p0 = counter("BVH/primitives tested");
                    memset(&h[k], 0, sizeof h[k]);
                    memset(&d[k], 0, sizeof d[k]);
                    f[k] = tb_accel_intersect_tri(acc[k], &ry, &h[k], &d[k]);
                    if (k < 3) {
                        nodes[k] = counter("BVH/nodes visited") - n0;
                        prims[k] = counter("BVH/primitives tested") - p0;
                    }
                }
                for (int k = 1; k < 4; k++) {
                    assert_int_equal(f[k], f[0]);
                    if (f[0]) {
                        assert_memory_equal(&h[k], &h[0], sizeof h[0]);
                        /* Field by field: the record has padding after dir. */
                        assert_int_equal(d[k].index, d[0].index);
                        assert_int_equal(d[k].sub, d[0].sub);
                        assert_int_equal(d[k].dir, d[0].dir);
                        assert_memory_equal(&d[k].t, &d[0].t, sizeof d[0].t);
                        assert_memory_equal(d[k].uvw, d[0].uvw, sizeof d[0].uvw);
                    }
                }
                for (int k = 1; k < 3; k++) {
                    assert_int_equal(nodes[k], nodes[0]);
                    assert_int_equal(prims[k], prims[0]);
                }
                bool occ = tb_accel_occluded(list, &ry);
                for (int k = 0; k < 3; k++) {
                    int64_t p0 = counter("BVH/primitives tested");
                    assert_int_equal(tb_accel_occluded(acc[k], &ry), occ);
                    prims[k] = counter("BVH/primitives tested") - p0;
                }
                assert_int_equal(prims[1], prims[0]);
                assert_int_equal(prims[2], prims[0]);
                hits += f[0];
                total++;
            }
            tb_stats_set_enabled(was);
            /* Kept binary nodes keep the reference array too (tb_accel_bvh_refs, GPU conversions). */
            tb_accel *keep;
            assert_int_equal(tb_accel_build(TB_ACCEL_BVH, refs, n, &cb,
                                            &(tb_accel_options){.bvh_max_leaf = leaves[li], .bvh_keep_binary = 1},
                                            &keep),
                             TB_OK);
            size_t nrefs = 0;
            assert_non_null(keep->lane_pos);
            assert_non_null(tb_accel_bvh_refs(keep, &nrefs));
            assert_int_equal(nrefs, keep->n);
            assert_null(tb_accel_bvh_refs(pk, NULL));
            tb_accel_free(keep);
            tb_accel_free(pk);
            tb_accel_free(pk_sse);
            tb_accel_free(one);
            tb_accel_free(list);
        }
    }
    print_message("[ packed leaves ] %zu triangles, float and double layouts, %ld rays (%ld at vertices / edges), "
                  "%ld hits\n", n, total, zero_rays, hits);
    assert_true(hits > total / 3);
    free(tris);
    free(refs);
}

static void test_build_errors(void **state)
{
    (void)state;
    tp_scene s = {0};
    tp_add_sphere(&s, 0, 0, 0, 1, 0, 0);
    tp_add_sphere(&s, 1, 0, 0, 1, 1, 0);
    tb_accel_callbacks cb = {tp_cb_intersect, NULL, &s, NULL};
    tb_accel *acc = (tb_accel *)&s; /* must be reset to NULL on failure */

    s.refs[1].bounds.hi.y = NAN;
    assert_int_equal(tb_accel_build(TB_ACCEL_BVH, s.refs, s.n, &cb, NULL, &acc), TB_ERR_ARG);
    assert_null(acc);
    assert_non_null(strstr(tb_last_error(), "reference 1"));
    s.refs[1].bounds.hi.y = INFINITY;
    assert_int_equal(tb_accel_build(TB_ACCEL_GRID, s.refs, s.n, &cb, NULL, &acc), TB_ERR_ARG);
    assert_non_null(strstr(tb_last_error(), "infinite"));
    s.refs[1].bounds = tp_bounds(&s.prims[1]);

    assert_int_equal(tb_accel_build((tb_accel_kind)7, s.refs, s.n, &cb, NULL, &acc), TB_ERR_ARG);
    assert_non_null(strstr(tb_last_error(), "kind"));
    tb_accel_callbacks nocb = {NULL, NULL, NULL, NULL};
    assert_int_equal(tb_accel_build(TB_ACCEL_BVH, s.refs, s.n, &nocb, NULL, &acc), TB_ERR_ARG);
    assert_int_equal(tb_accel_build(TB_ACCEL_BVH, s.refs, s.n, NULL, NULL, &acc), TB_ERR_ARG);
    assert_int_equal(tb_accel_build(TB_ACCEL_BVH, NULL, 2, &cb, NULL, &acc), TB_ERR_ARG);
    assert_int_equal(tb_accel_build(TB_ACCEL_BVH, s.refs, s.n, &cb, NULL, NULL), TB_ERR_ARG);

    const tb_accel_options bad[] = {
        {.bvh_bins = 1},        {.bvh_bins = 257},          {.bvh_max_leaf = 256},
        {.bvh_max_leaf = -1},   {.bvh_cost_node = -1.0f},   {.bvh_cost_prim = NAN},
        {.grid_density = -2.0}, {.grid_density = INFINITY}, {.grid_max_res = 1025},
        {.threads = -1},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        acc = (tb_accel *)&s;
        assert_int_equal(tb_accel_build(TB_ACCEL_BVH, s.refs, s.n, &cb, &bad[i], &acc), TB_ERR_ARG);
        assert_null(acc);
        assert_true(strlen(tb_last_error()) > 0);
    }
    /* The extremes of every range are accepted. */
    tb_accel_options edge = {.bvh_bins = 2, .bvh_max_leaf = 1, .grid_max_res = 1, .grid_density = 0.5};
    for (int k = 0; k < NKINDS; k++) {
        assert_int_equal(tb_accel_build(kinds[k], s.refs, s.n, &cb, &edge, &acc), TB_OK);
        tb_ray r = ray(-5, 0, 0, 1, 0, 0, 0, INFINITY);
        expect_hit(acc, &r, 4.0f, 0, 0);
        tb_accel_free(acc);
    }
    tb_accel_free(NULL);
    tp_free(&s);
}

static void test_kind_names(void **state)
{
    (void)state;
    for (int k = 0; k < NKINDS; k++) {
        tb_accel_kind back;
        assert_int_equal(tb_accel_kind_from_name(tb_accel_kind_name(kinds[k]), &back), TB_OK);
        assert_int_equal(back, kinds[k]);
    }
    assert_string_equal(tb_accel_kind_name(TB_ACCEL_BVH), "bvh");
    assert_string_equal(tb_accel_kind_name(TB_ACCEL_GRID), "grid");
    assert_null(tb_accel_kind_name((tb_accel_kind)3));
    tb_accel_kind k;
    assert_int_equal(tb_accel_kind_from_name("kd-tree", &k), TB_ERR_ARG);
    assert_non_null(strstr(tb_last_error(), "kd-tree"));
    assert_int_equal(tb_accel_kind_from_name(NULL, &k), TB_ERR_ARG);
}

/* The resolution rule: round(density * cbrt(N) * width / longest width)
 * voxels per axis, at least 1, at most grid_max_res. */
static void test_grid_resolution(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("grid_resolution", 21);
    tb_rng r;
    tb_rng_seed(&r, seed, 1);
    /* 1000 small spheres in a box 4 x 2 x 0 (flat in z), corners pinned. */
    tp_scene s = {0};
    for (int i = 0; i < 1000; i++) {
        float x = i < 4 ? (float)(i & 1) * 4.0f : tp_uniform(&r, 0, 4);
        float y = i < 4 ? (float)(i >> 1) * 2.0f : tp_uniform(&r, 0, 2);
        float v[3][3] = {{x, y, 0}, {x + 0.0f, y, 0}, {x, y, 0}};
        tp_add_triangle(&s, (const float(*)[3])v, (uint32_t)i, 0);
    }
    struct {
        tb_accel_options opt;
        int res[3];
    } cases[] = {
        {{0}, {30, 15, 1}},                                   /* 3 * cbrt(1000) = 30 */
        {{.grid_density = 6.0}, {60, 30, 1}},
        {{.grid_density = 6.0, .grid_max_res = 40}, {40, 30, 1}},
        {{.grid_density = 0.1}, {1, 1, 1}},                   /* round(0.5) of y and z: at least 1 */
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        tb_accel *acc = build(TB_ACCEL_GRID, &s, &cases[c].opt);
        tb_accel_stats st;
        tb_accel_get_stats(acc, &st);
        for (int a = 0; a < 3; a++)
            if (st.grid_res[a] != cases[c].res[a])
                fail_msg("case %zu axis %d: resolution %d, expected %d", c, a, st.grid_res[a], cases[c].res[a]);
        assert_int_equal(st.grid_cells, (size_t)cases[c].res[0] * cases[c].res[1] * cases[c].res[2]);
        /* The grid box holds the references' box. */
        assert_true(tb_aabb_contains_box(&st.grid_bounds, &st.bounds));
        assert_true(st.grid_nonempty > 0 && st.grid_nonempty <= st.grid_cells);
        assert_true(st.grid_refs >= st.nprims);
        assert_true(st.memory_bytes > st.grid_refs * 4);
        assert_true(st.build_seconds >= 0.0);
        tb_accel_free(acc);
    }
    tp_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_empty_scene),
        cmocka_unit_test(test_one_primitive),
        cmocka_unit_test(test_all_in_one_point),
        cmocka_unit_test(test_identical_boxes_1e5),
        cmocka_unit_test(test_invalid_rays),
        cmocka_unit_test(test_tmin_tmax_exact),
        cmocka_unit_test(test_callback_range_not_trusted),
        cmocka_unit_test(test_triangle_references),
        cmocka_unit_test(test_owned_build),
        cmocka_unit_test(test_t_tolerance),
        cmocka_unit_test(test_slab_matches_util),
        cmocka_unit_test(test_bvhw_slab_matches_scalar),
        cmocka_unit_test(test_bvhw_structure),
        cmocka_unit_test(test_bvhw_collapse_optimal),
        cmocka_unit_test(test_bvhw_avx_matches_sse),
        cmocka_unit_test(test_bvhw_order_position),
        cmocka_unit_test(test_packed_leaves),
        cmocka_unit_test(test_build_errors),
        cmocka_unit_test(test_kind_names),
        cmocka_unit_test(test_grid_resolution),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
