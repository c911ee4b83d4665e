/* util/math/ray.h and aabb.h: ray validity, box operations on hand-worked
 * boxes, and the slab test: axis-parallel rays with +0 and -0 direction
 * components, rays starting inside, grazing rays along faces and edges, huge
 * and tiny boxes, and a seeded property test that the float interval always
 * contains the one computed in double. */
#include "tb_test.h"

#include <float.h>
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "util/math/aabb.h"
#include "util/math/float.h"
#include "util/math/ray.h"

#define assert_vec3_eq(v, X, Y, Z)                                                           \
    do {                                                                                     \
        tb_vec3 tb__v = (v);                                                                 \
        if (!(tb__v.x == (X) && tb__v.y == (Y) && tb__v.z == (Z)))                           \
            fail_msg("%s = (%.9g, %.9g, %.9g), want (%.9g, %.9g, %.9g)", #v, tb__v.x, tb__v.y, \
                     tb__v.z, (double)(X), (double)(Y), (double)(Z));                        \
    } while (0)

/* v[i] = x (named fields: indexing past &v->x would be undefined behaviour). */
static void set3(tb_vec3 *v, int i, float x)
{
    if (i == 0)
        v->x = x;
    else if (i == 1)
        v->y = x;
    else
        v->z = x;
}

static void test_ray_layout_and_at(void **state)
{
    (void)state;
    assert_int_equal(sizeof(tb_ray), 32);
    /* The ray file record: ox oy oz tmin dx dy dz tmax, 8 floats. */
    const float rec[8] = {1, 2, 3, 0.5f, 4, 5, 6, 9};
    tb_ray r;
    memcpy(&r, rec, sizeof r);
    assert_vec3_eq(r.o, 1, 2, 3);
    assert_vec3_eq(r.d, 4, 5, 6);
    assert_true(r.tmin == 0.5f && r.tmax == 9.0f);
    assert_vec3_eq(tb_ray_at(&r, 2.0f), 9, 12, 15);
    assert_vec3_eq(tb_ray_at(&r, 0.0f), 1, 2, 3);
    tb_ray m = tb_ray_make((tb_vec3){1, 2, 3}, (tb_vec3){4, 5, 6}, 0.5f, 9.0f);
    assert_memory_equal(&m, &r, sizeof r);
}

static void test_ray_validity(void **state)
{
    (void)state;
    tb_ray ok = tb_ray_make((tb_vec3){0, 0, 0}, (tb_vec3){0, 0, 1}, 0.0f, INFINITY);
    assert_true(tb_ray_is_valid(&ok));
    tb_ray r = ok;
    r.tmin = r.tmax = 3.0f; /* one point: allowed */
    assert_true(tb_ray_is_valid(&r));
    r = ok;
    r.tmin = -5.0f; /* negative start: allowed */
    assert_true(tb_ray_is_valid(&r));
    r = ok;
    r.d = (tb_vec3){0, 0x1p-149f, 0}; /* denormal but non-zero */
    assert_true(tb_ray_is_valid(&r));

    const float bad[] = {NAN, INFINITY, -INFINITY};
    for (int i = 0; i < 3; ++i) {
        for (int c = 0; c < 3; ++c) {
            r = ok;
            set3(&r.o, c, bad[i]);
            assert_false(tb_ray_is_valid(&r));
            r = ok;
            set3(&r.d, c, bad[i]);
            assert_false(tb_ray_is_valid(&r));
        }
    }
    r = ok;
    r.d = (tb_vec3){0, 0, 0};
    assert_false(tb_ray_is_valid(&r));
    r.d = (tb_vec3){-0.0f, 0.0f, -0.0f};
    assert_false(tb_ray_is_valid(&r));
    r = ok;
    r.tmin = 2.0f;
    r.tmax = 1.0f;
    assert_false(tb_ray_is_valid(&r));
    r = ok;
    r.tmin = NAN;
    assert_false(tb_ray_is_valid(&r));
    r = ok;
    r.tmax = NAN;
    assert_false(tb_ray_is_valid(&r));
    r = ok;
    r.tmin = -INFINITY;
    assert_false(tb_ray_is_valid(&r));
    r = ok;
    r.tmin = INFINITY;
    assert_false(tb_ray_is_valid(&r));
    r = ok;
    r.tmax = -INFINITY;
    assert_false(tb_ray_is_valid(&r));
}

static void test_aabb_ops(void **state)
{
    (void)state;
    tb_aabb e = tb_aabb_empty();
    assert_true(tb_aabb_is_empty(&e));
    assert_true(tb_aabb_surface_area(&e) == 0.0f);
    assert_true(tb_aabb_volume(&e) == 0.0f);
    assert_vec3_eq(tb_aabb_extent(&e), 0, 0, 0);
    assert_false(tb_aabb_contains(&e, (tb_vec3){0, 0, 0}));

    tb_aabb b = tb_aabb_union_point(e, (tb_vec3){1, 2, 3});
    assert_false(tb_aabb_is_empty(&b)); /* a single point is a (flat) box */
    assert_vec3_eq(b.lo, 1, 2, 3);
    assert_vec3_eq(b.hi, 1, 2, 3);
    b = tb_aabb_union_point(b, (tb_vec3){0, 4, 6});
    assert_vec3_eq(b.lo, 0, 2, 3);
    assert_vec3_eq(b.hi, 1, 4, 6);
    /* 1 x 2 x 3: area 2 (2 + 6 + 3) = 22, volume 6. */
    assert_vec3_eq(tb_aabb_extent(&b), 1, 2, 3);
    assert_true(tb_aabb_surface_area(&b) == 22.0f);
    assert_true(tb_aabb_volume(&b) == 6.0f);
    assert_vec3_eq(tb_aabb_centroid(&b), 0.5f, 3, 4.5f);
    assert_int_equal(tb_aabb_largest_axis(&b), 2);
    tb_aabb cube = {{0, 0, 0}, {2, 2, 2}};
    assert_int_equal(tb_aabb_largest_axis(&cube), 0); /* first on ties */
    /* Centroid of a huge box does not overflow. */
    tb_aabb huge = {{-FLT_MAX, -FLT_MAX, 0}, {FLT_MAX, FLT_MAX, FLT_MAX}};
    assert_vec3_eq(tb_aabb_centroid(&huge), 0, 0, FLT_MAX / 2);

    tb_aabb u = tb_aabb_union(b, cube);
    assert_vec3_eq(u.lo, 0, 0, 0);
    assert_vec3_eq(u.hi, 2, 4, 6);
    tb_aabb ue = tb_aabb_union(e, cube);
    assert_memory_equal(&ue, &cube, sizeof cube);
    tb_aabb x = tb_aabb_intersection(b, cube);
    assert_vec3_eq(x.lo, 0, 2, 3);
    assert_vec3_eq(x.hi, 1, 2, 2);
    assert_true(tb_aabb_is_empty(&x)); /* z: [3, 2] */
    tb_aabb pp = tb_aabb_from_points((tb_vec3){3, -1, 5}, (tb_vec3){1, 2, -5});
    assert_vec3_eq(pp.lo, 1, -1, -5);
    assert_vec3_eq(pp.hi, 3, 2, 5);

    /* Closed: faces, edges and corners are inside. */
    assert_true(tb_aabb_contains(&cube, (tb_vec3){0, 0, 0}));
    assert_true(tb_aabb_contains(&cube, (tb_vec3){2, 1, 2}));
    assert_false(tb_aabb_contains(&cube, (tb_vec3){2.0000002f, 1, 1}));
    assert_false(tb_aabb_contains(&cube, (tb_vec3){NAN, 1, 1}));
    tb_aabb inner = {{0.5f, 0.5f, 0.5f}, {2, 2, 1}};
    assert_true(tb_aabb_contains_box(&cube, &inner));
    assert_false(tb_aabb_contains_box(&inner, &cube));
    assert_true(tb_aabb_contains_box(&inner, &e));
    /* Overlap: touching along a face counts; a gap does not. */
    tb_aabb touch = {{2, 0, 0}, {3, 1, 1}}, apart = {{2.5f, 0, 0}, {3, 1, 1}};
    assert_true(tb_aabb_overlaps(&cube, &touch));
    assert_true(tb_aabb_overlaps(&touch, &cube));
    assert_false(tb_aabb_overlaps(&cube, &apart));
    assert_false(tb_aabb_overlaps(&cube, &e));
    assert_vec3_eq(tb_aabb_offset(&b, (tb_vec3){0.25f, 3, 6}), 0.25f, 0.5f, 1);
    tb_aabb flat = {{0, 0, 1}, {1, 1, 1}};
    assert_vec3_eq(tb_aabb_offset(&flat, (tb_vec3){0.5f, 0.5f, 1}), 0.5f, 0.5f, 0);
}

/* How far outside the exact value the slab test may place t0 and t1,
 * relative: gamma(3) of rounding, 2 gamma(3) of widening and the rounding
 * of the widening product, together below 2 gamma(3) + gamma(4). */
#define SLAB_K (2.0 * (double)tb_gamma(3) + (double)tb_gamma(4))

static bool hit(const tb_aabb *b, tb_vec3 o, tb_vec3 d, float *t0, float *t1)
{
    tb_ray r = tb_ray_make(o, d, 0.0f, INFINITY);
    return tb_aabb_intersect_ray(b, &r, t0, t1);
}

/* t0/t1 equal `want` up to the conservative widening, on the outside. */
static void assert_t_near(float t0, float t1, double w0, double w1)
{
    if (!(t0 <= w0 && t0 >= w0 - fabs(w0) * SLAB_K - 0x1p-149))
        fail_msg("t0 = %.9g, want %.9g (lower by a relative %.3g at most)", t0, w0, SLAB_K);
    if (!(t1 >= w1 && t1 <= w1 + fabs(w1) * SLAB_K + 0x1p-149))
        fail_msg("t1 = %.9g, want %.9g (higher by a relative %.3g at most)", t1, w1, SLAB_K);
}

static void test_slab_basic(void **state)
{
    (void)state;
    tb_aabb b = {{-1, -1, -1}, {1, 1, 1}};
    float t0 = NAN, t1 = NAN; /* NAN fails the checks if the test did not set them */
    assert_true(hit(&b, (tb_vec3){-5, 0, 0}, (tb_vec3){1, 0, 0}, &t0, &t1));
    assert_t_near(t0, t1, 4, 6);
    assert_true(hit(&b, (tb_vec3){5, 0.5f, 0}, (tb_vec3){-2, 0, 0}, &t0, &t1));
    assert_t_near(t0, t1, 2, 3);
    /* Diagonal through the corners (-1,-1,-1) and (1,1,1). */
    assert_true(hit(&b, (tb_vec3){-3, -3, -3}, (tb_vec3){1, 1, 1}, &t0, &t1));
    assert_t_near(t0, t1, 2, 4);
    /* Misses: beside the box, behind the origin, beyond tmax. */
    assert_false(hit(&b, (tb_vec3){-5, 1.5f, 0}, (tb_vec3){1, 0, 0}, &t0, &t1));
    assert_false(hit(&b, (tb_vec3){5, 0, 0}, (tb_vec3){1, 0, 0}, &t0, &t1));
    tb_ray shortr = tb_ray_make((tb_vec3){-5, 0, 0}, (tb_vec3){1, 0, 0}, 0.0f, 3.9f);
    assert_false(tb_aabb_intersect_ray(&b, &shortr, &t0, &t1));
    shortr.tmin = 6.1f;
    shortr.tmax = 100.0f;
    assert_false(tb_aabb_intersect_ray(&b, &shortr, &t0, &t1));
    /* The ray's own range clips the result. */
    tb_ray seg = tb_ray_make((tb_vec3){-5, 0, 0}, (tb_vec3){1, 0, 0}, 4.5f, 5.5f);
    assert_true(tb_aabb_intersect_ray(&b, &seg, &t0, &t1));
    assert_true(t0 == 4.5f && t1 == 5.5f);
    /* NULL outputs are allowed. */
    assert_true(tb_aabb_intersect_ray(&b, &seg, NULL, NULL));
    /* An empty box is never hit, from anywhere. */
    tb_aabb e = tb_aabb_empty();
    assert_false(hit(&e, (tb_vec3){0, 0, 0}, (tb_vec3){1, 0, 0}, &t0, &t1));
    assert_false(hit(&e, (tb_vec3){0, 0, 0}, (tb_vec3){0, 0, 0}, &t0, &t1));
    tb_aabb inverted = {{1, 1, 1}, {-1, -1, -1}};
    assert_false(hit(&inverted, (tb_vec3){-5, 0, 0}, (tb_vec3){1, 0, 0}, &t0, &t1));
}

static void test_slab_inside(void **state)
{
    (void)state;
    tb_aabb b = {{-1, -1, -1}, {1, 1, 1}};
    float t0 = NAN, t1 = NAN; /* NAN fails the checks if the test did not set them */
    assert_true(hit(&b, (tb_vec3){0, 0, 0}, (tb_vec3){0, 0, 1}, &t0, &t1));
    assert_true(t0 == 0.0f); /* clipped to tmin */
    assert_t_near(0, t1, 0, 1);
    /* With tmin = -inf the entry behind the origin shows. */
    tb_ray r = tb_ray_make((tb_vec3){0.5f, 0, 0}, (tb_vec3){1, 0, 0}, -INFINITY, INFINITY);
    assert_true(tb_aabb_intersect_ray(&b, &r, &t0, &t1));
    assert_t_near(t0, t1, -1.5, 0.5);
    /* On a corner, leaving: hits at t = 0 only. */
    assert_true(hit(&b, (tb_vec3){1, 1, 1}, (tb_vec3){1, 2, 3}, &t0, &t1));
    assert_true(t0 == 0.0f && t1 == 0.0f);
}

/* Direction components of +0 and -0: the ray is parallel to those slabs. */
static void test_slab_axis_parallel_signed_zeros(void **state)
{
    (void)state;
    tb_aabb b = {{-1, -1, -1}, {1, 1, 1}};
    const float zeros[2] = {0.0f, -0.0f};
    float t0 = NAN, t1 = NAN; /* NAN fails the checks if the test did not set them */
    for (int zy = 0; zy < 2; ++zy) {
        for (int zz = 0; zz < 2; ++zz) {
            tb_vec3 d = {1, zeros[zy], zeros[zz]};
            /* Inside the y and z slabs. */
            assert_true(hit(&b, (tb_vec3){-5, 0.5f, -0.5f}, d, &t0, &t1));
            assert_t_near(t0, t1, 4, 6);
            assert_false(isnan(t0) || isnan(t1));
            /* Outside the y slab, on either side. */
            assert_false(hit(&b, (tb_vec3){-5, 1.5f, 0}, d, &t0, &t1));
            assert_false(hit(&b, (tb_vec3){-5, -1.5f, 0}, d, &t0, &t1));
            assert_false(hit(&b, (tb_vec3){-5, 0, 1.0000001f}, d, &t0, &t1));
            /* Exactly on the face planes y = +-1 and z = +-1: grazing along a
             * face or an edge of a closed box is a hit (0 * inf is NaN there
             * and must not leak out). */
            const float on[2] = {1.0f, -1.0f};
            for (int s = 0; s < 2; ++s) {
                assert_true(hit(&b, (tb_vec3){-5, on[s], 0}, d, &t0, &t1));
                assert_t_near(t0, t1, 4, 6);
                assert_true(hit(&b, (tb_vec3){-5, 0, on[s]}, d, &t0, &t1));
                assert_t_near(t0, t1, 4, 6);
                assert_true(hit(&b, (tb_vec3){-5, on[s], on[1 - s]}, d, &t0, &t1));
                assert_t_near(t0, t1, 4, 6);
                assert_false(isnan(t0) || isnan(t1));
            }
            /* Negative x direction too. */
            tb_vec3 dn = {-1, zeros[zz], zeros[zy]};
            assert_true(hit(&b, (tb_vec3){5, 1, -1}, dn, &t0, &t1));
            assert_t_near(t0, t1, 4, 6);
        }
    }
    /* A ray along an axis with the other two components of both signs, from inside. */
    assert_true(hit(&b, (tb_vec3){0, 0, 0}, (tb_vec3){-0.0f, -0.0f, -1}, &t0, &t1));
    assert_t_near(0, t1, 0, 1);
    /* A flat box (zero thickness in z) is hit by rays in its plane and through it. */
    tb_aabb flat = {{-1, -1, 0}, {1, 1, 0}};
    assert_true(hit(&flat, (tb_vec3){-5, 0, 0}, (tb_vec3){1, 0, -0.0f}, &t0, &t1));
    assert_t_near(t0, t1, 4, 6);
    assert_true(hit(&flat, (tb_vec3){0, 0, 3}, (tb_vec3){0, 0, -1}, &t0, &t1));
    assert_t_near(t0, t1, 3, 3);
    assert_false(hit(&flat, (tb_vec3){-5, 0, 0x1p-149f}, (tb_vec3){1, 0, 0}, &t0, &t1));
}

static void test_slab_extreme_scales(void **state)
{
    (void)state;
    float t0 = NAN, t1 = NAN; /* NAN fails the checks if the test did not set them */
    /* Huge box, far origin. */
    tb_aabb big = {{-1e30f, -1e30f, -1e30f}, {1e30f, 1e30f, 1e30f}};
    assert_true(hit(&big, (tb_vec3){-3e30f, 0, 0}, (tb_vec3){1, 0, 0}, &t0, &t1));
    assert_t_near(t0, t1, (double)-1e30f + 3e30f, (double)1e30f + 3e30f);
    /* Exit at 4e38 is beyond FLT_MAX: t1 is +inf, t0 (2e38) is finite. */
    assert_true(hit(&big, (tb_vec3){-3e30f, 5e29f, -5e29f}, (tb_vec3){1e-8f, 0, -0.0f}, &t0, &t1));
    assert_true(t1 == INFINITY);
    assert_t_near(t0, t1, ((double)-1e30f + 3e30f) / (double)1e-8f, INFINITY);
    assert_false(hit(&big, (tb_vec3){-3e30f, 2e30f, 0}, (tb_vec3){1, 0, 0}, &t0, &t1));
    /* Faces near FLT_MAX: the differences overflow to inf, still no NaN. */
    tb_aabb max = {{-FLT_MAX, -FLT_MAX, -FLT_MAX}, {FLT_MAX, FLT_MAX, FLT_MAX}};
    assert_true(hit(&max, (tb_vec3){0, 0, 0}, (tb_vec3){0x1p-100f, 1, 0}, &t0, &t1));
    assert_true(t0 == 0.0f && t1 >= FLT_MAX && !isnan(t1));
    /* Tiny box seen from afar: t is about 1 on either side of 1 +- 1e-30. */
    tb_aabb tiny = {{-1e-30f, -1e-30f, -1e-30f}, {1e-30f, 1e-30f, 1e-30f}};
    assert_true(hit(&tiny, (tb_vec3){-1, 0, 0}, (tb_vec3){1, 0, 0}, &t0, &t1));
    assert_true(t0 <= 1.0f && t1 >= 1.0f);
    assert_false(hit(&tiny, (tb_vec3){-1, 2e-30f, 0}, (tb_vec3){1, 0, 0}, &t0, &t1));
    assert_true(hit(&tiny, (tb_vec3){-1, 1e-30f, 0}, (tb_vec3){1, 0, 0}, &t0, &t1)); /* grazing */
    /* Tiny box, tiny distances: t in [2e-30, 4e-30]. */
    assert_true(hit(&tiny, (tb_vec3){-3e-30f, 0, 0}, (tb_vec3){1, 0, 0}, &t0, &t1));
    assert_t_near(t0, t1, (double)-1e-30f + 3e-30f, (double)1e-30f + 3e-30f);
    /* Tiny direction: large t, no overflow trouble. */
    tb_aabb b = {{-1, -1, -1}, {1, 1, 1}};
    assert_true(hit(&b, (tb_vec3){-5, 0, 0}, (tb_vec3){1e-30f, 0, 0}, &t0, &t1));
    assert_t_near(t0, t1, 4 / (double)1e-30f, 6 / (double)1e-30f);
}

/* Reference slab test in double, with parallel slabs handled by a branch.
 * On a miss *t0 is NaN if a parallel slab excluded the ray, else [t0, t1]
 * is the (inverted) overlap. */
static bool ref_slab(const tb_aabb *b, tb_vec3 of, tb_vec3 df, double tmin, double tmax,
                     double *t0, double *t1)
{
    double o[3] = {of.x, of.y, of.z}, d[3] = {df.x, df.y, df.z};
    double lo[3] = {b->lo.x, b->lo.y, b->lo.z}, hi[3] = {b->hi.x, b->hi.y, b->hi.z};
    for (int i = 0; i < 3; ++i) {
        if (d[i] == 0.0) {
            if (o[i] < lo[i] || o[i] > hi[i]) {
                *t0 = *t1 = NAN;
                return false;
            }
            continue;
        }
        double a = (lo[i] - o[i]) / d[i], z = (hi[i] - o[i]) / d[i];
        if (a > z) {
            double t = a;
            a = z;
            z = t;
        }
        tmin = fmax(tmin, a);
        tmax = fmin(tmax, z);
    }
    *t0 = tmin;
    *t1 = tmax;
    return tmin <= tmax;
}

static float rnd(tb_rng *r, float a, float b) { return a + (b - a) * tb_rng_float(r); }

static void test_slab_conservative_random(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("slab_conservative_random", 17), 9);
    int hits = 0, grazing = 0, false_hits = 0, n = 200000;
    double worst = 0.0;
    for (int k = 0; k < n; ++k) {
        float s = ldexpf(1.0f, (int)tb_rng_below(&r, 40) - 20); /* scale 2^-20 .. 2^19 */
        tb_vec3 p = {rnd(&r, -s, s), rnd(&r, -s, s), rnd(&r, -s, s)};
        tb_vec3 q = {rnd(&r, -s, s), rnd(&r, -s, s), rnd(&r, -s, s)};
        tb_aabb b = tb_aabb_from_points(p, q);
        tb_vec3 o = {rnd(&r, -4 * s, 4 * s), rnd(&r, -4 * s, 4 * s), rnd(&r, -4 * s, 4 * s)};
        /* Aim at a corner, an edge point, a face point or the inside. */
        tb_vec3 target;
        float lo[3] = {b.lo.x, b.lo.y, b.lo.z}, hi[3] = {b.hi.x, b.hi.y, b.hi.z}, t[3];
        int kind = (int)tb_rng_below(&r, 4);
        for (int i = 0; i < 3; ++i) {
            bool pin = (int)i < kind; /* kind 3: corner, 2: edge, 1: face, 0: interior */
            t[i] = pin ? ((tb_rng_u32(&r) & 1) ? hi[i] : lo[i]) : rnd(&r, lo[i], hi[i]);
        }
        target = (tb_vec3){t[0], t[1], t[2]};
        tb_vec3 d = tb_vec3_sub(target, o);
        /* Zero some direction components (keeping the origin inside or on
         * that slab half of the time, so some of these rays graze). */
        for (int i = 0; i < 3; ++i) {
            if (tb_rng_below(&r, 6) == 0) {
                set3(&d, i, (tb_rng_u32(&r) & 1) ? 0.0f : -0.0f);
                uint32_t w = tb_rng_below(&r, 3);
                set3(&o, i, w == 0 ? lo[i] : (w == 1 ? hi[i] : tb_vec3_get(o, i)));
                grazing += w < 2;
            }
        }
        if (d.x == 0 && d.y == 0 && d.z == 0)
            continue;
        float tmin = (tb_rng_u32(&r) & 1) ? 0.0f : -INFINITY;
        double r0, r1;
        bool want = ref_slab(&b, o, d, tmin, INFINITY, &r0, &r1);
        float f0 = NAN, f1 = NAN;
        tb_ray ray = tb_ray_make(o, d, tmin, INFINITY);
        bool got = tb_aabb_intersect_ray(&b, &ray, &f0, &f1);
        if (want) {
            ++hits;
            if (!got)
                fail_msg("trial %d: missed; reference [%.17g, %.17g]", k, r0, r1);
            if (!(f0 <= r0 && f1 >= r1))
                fail_msg("trial %d: [%.9g, %.9g] does not contain reference [%.17g, %.17g]", k, f0,
                         f1, r0, r1);
            if (isfinite(r0) && r0 != 0)
                worst = fmax(worst, (r0 - f0) / fabs(r0));
            if (isfinite(r1) && r1 != 0)
                worst = fmax(worst, (f1 - r1) / fabs(r1));
        }
        if (got)
            assert_false(isnan(f0) || isnan(f1));
        if (got && !want) {
            /* A false hit is allowed only within the widening of a near miss. */
            ++false_hits;
            if (isnan(r0) || !(r0 - r1 <= 2 * SLAB_K * fmax(fabs(r0), fabs(r1))))
                fail_msg("trial %d: hit [%.9g, %.9g], but reference misses clearly [%.17g, %.17g]",
                         k, f0, f1, r0, r1);
        }
    }
    print_message("[ info     ] slab: %d rays, %d hits, %d near-miss hits, %d grazing set-ups, "
                  "worst relative widening %.3g (bound %.3g)\n",
                  n, hits, false_hits, grazing, worst, SLAB_K);
    assert_true(hits > n / 4);
    assert_true(worst <= SLAB_K); /* widened, but not needlessly */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ray_layout_and_at),
        cmocka_unit_test(test_ray_validity),
        cmocka_unit_test(test_aabb_ops),
        cmocka_unit_test(test_slab_basic),
        cmocka_unit_test(test_slab_inside),
        cmocka_unit_test(test_slab_axis_parallel_signed_zeros),
        cmocka_unit_test(test_slab_extreme_scales),
        cmocka_unit_test(test_slab_conservative_random),
    };
    return cmocka_run_group_tests_name("util/math ray/aabb", tests, NULL, NULL);
}
