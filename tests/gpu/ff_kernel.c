/* The Vulkan form-factor kernel (host/gpu/formfactor.h) against independent
 * double-precision computations of the same formula (Wallace et al. 1989,
 * eq. 5) and exact visibility on exactly representable geometry, against
 * Howell's value for parallel squares, and against the CPU batch
 * (tb_ff_raycast_batch, host/radiosity/formfactor.h) with and without
 * occluders. Runs with the validation layer and fails on any message. */
#include "gpu_test.h"

#include <math.h>
#include <stdlib.h>

#include "host/gpu/formfactor.h"
#include "host/radiosity/formfactor.h"
#include "util/math/rng.h"

#define TB__PI 3.14159265358979323846

/* The form-factor tests' device: `staging` forces the copies through staging
 * buffers (the discrete-GPU path) on a device that could map its memory. */
static void tb__open(gpu_test_env *e, bool staging)
{
    gpu_test_open(e, &(tb_gpu_device_desc){.force_staging = staging});
}

/* The formula in double on the same float inputs, `blocked` deciding visibility
 * (NULL: none): the independent reference of the paired tests. */
static double tb__ref(const tb_vec3 *s, int npts, tb_vec3 ns, double area, tb_vec3 p, tb_vec3 n,
                      bool (*blocked)(tb_vec3 s, tb_vec3 p), uint32_t *bits)
{
    double da = area / npts, f = 0.0;
    for (int k = 0; k < npts; ++k) {
        double d[3] = {(double)p.x - s[k].x, (double)p.y - s[k].y, (double)p.z - s[k].z};
        double cs = ns.x * d[0] + ns.y * d[1] + ns.z * d[2];
        double cr = -(n.x * d[0] + n.y * d[1] + n.z * d[2]);
        if (!(cs > 0.0 && cr > 0.0) || (blocked && blocked(s[k], p)))
            continue;
        double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        f += cs * cr / r2 * da / (TB__PI * r2 + da);
        if (bits)
            bits[k / 32] |= 1u << (k % 32);
    }
    return f;
}

/* The unit square at z = 1 facing down (-z), corners counter-clockwise seen from below. */
static const tb_ff_polygon tb__top = {{{0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1}}, 4};

/* 8 x 8 cell centres of the top square: multiples of 1/16, exact in float. */
static void tb__grid_samples(tb_vec3 s[64])
{
    for (int k = 0; k < 64; ++k)
        s[k] = (tb_vec3){(float)(k % 8) / 8.0f + 0.0625f, (float)(k / 8) / 8.0f + 0.0625f, 1.0f};
}

/* Receivers on z = 0: a 24 x 24 grid of multiples of 1/8 over [-1, 2)^2, normals
 * +z, tilted, or facing away (every fourth). */
static size_t tb__grid_receivers(tb_vec3 *p, tb_vec3 *n)
{
    static const tb_vec3 normals[4] = {{0, 0, 1}, {0.6f, 0, 0.8f}, {0, -0.8f, 0.6f}, {0, 0, -1}};
    size_t m = 0;
    for (int j = 0; j < 24; ++j)
        for (int i = 0; i < 24; ++i, ++m) {
            p[m] = (tb_vec3){-1.0f + (float)i / 8.0f, -1.0f + (float)j / 8.0f, 0.0f};
            n[m] = normals[m % 4];
        }
    return m;
}

/* Occluders at z = 1/2: an 8 x 8 checkerboard of squares of side 2/64 (every
 * third one replaced by a triangle with legs 4/64 and 2/64) with corners at
 * odd multiples of 1/64. A segment from a sample (odd multiples of 1/16,
 * z = 1) to a receiver (multiples of 1/8, z = 0) crosses z = 1/2 at an odd
 * multiple of 1/32, whose offsets a, b from a corner are odd multiples of
 * 1/64: never on an edge (a, b != 0, 2/64; a + 2b, odd, != 4/64). No
 * segment is grazing. */
#define TB__NOCC 32
static tb_ff_polygon tb__occ[TB__NOCC];

static void tb__make_occluders(void)
{
    int m = 0;
    for (int j = 0; j < 8; ++j)
        for (int i = 0; i < 8; ++i) {
            if ((i + j) % 2)
                continue;
            float x = (float)(8 * i + 1) / 64.0f, y = (float)(8 * j + 1) / 64.0f;
            float w = 2.0f / 64.0f;
            if (m % 3 == 2) { /* some triangles: legs 4/64 along x and 2/64 along y */
                tb__occ[m++] = (tb_ff_polygon){{{x, y, 0.5f}, {x + 2 * w, y, 0.5f}, {x, y + w, 0.5f}}, 3};
                continue;
            }
            tb__occ[m++] = (tb_ff_polygon){{{x, y, 0.5f}, {x + w, y, 0.5f}, {x + w, y + w, 0.5f}, {x, y + w, 0.5f}}, 4};
        }
    assert_int_equal(m, TB__NOCC);
}

/* Exact: where the segment s -> p crosses z = 1/2 (exactly (s + p) / 2), inside an occluder. */
static bool tb__blocked(tb_vec3 s, tb_vec3 p)
{
    double cx = 0.5 * ((double)s.x + p.x), cy = 0.5 * ((double)s.y + p.y);
    for (int m = 0; m < TB__NOCC; ++m) {
        const tb_ff_polygon *q = &tb__occ[m];
        double a = cx - q->v[0].x, b = cy - q->v[0].y, w = 2.0 / 64.0;
        bool in = q->n == 4 ? a > 0 && a < w && b > 0 && b < w : a > 0 && b > 0 && a + 2 * b < 2 * w;
        if (in)
            return true;
    }
    return false;
}

/* No occluders, exactly representable geometry: the kernel's float sums agree
 * with the double formula to float rounding (each term has relative error below
 * ~10u, u = 2^-24; a sum of 64 positive terms adds at most 63u): 2e-5 relative. */
static void tb__unoccluded(bool staging)
{
    gpu_test_env e;
    tb__open(&e, staging);
    tb_gpu_ff_scene *g = tb_gpu_ff_scene_create(e.dev, NULL, 0);
    assert_non_null(g);
    assert_int_equal(tb_gpu_ff_scene_triangles(g), 0);
    tb_vec3 s[64], p[576], n[576];
    tb__grid_samples(s);
    size_t m = tb__grid_receivers(p, n);
    double ff[576], cpu[576];
    uint32_t vis[576 * 2];
    tb_gpu_ff_timing tm;
    tb_vec3 ns = {0, 0, -1};
    assert_int_equal(tb_gpu_ff_raycast(g, s, 64, ns, 1.0, p, n, m, ff, vis, &tm), TB_OK);
    assert_int_equal(tm.dispatches, 1);
    assert_true(tm.seconds > 0.0);
    /* The CPU batch without occluders: the same formula (docs/formfactors.md). */
    assert_int_equal(tb_ff_raycast_batch(NULL, s, 64, ns, 1.0, p, n, m, cpu), TB_OK);
    size_t zero = 0;
    for (size_t i = 0; i < m; ++i) {
        uint32_t bits[2] = {0, 0};
        double r = tb__ref(s, 64, ns, 1.0, p[i], n[i], NULL, bits);
        tb_assert_near(ff[i], r, 2e-5 * r);
        tb_assert_near(cpu[i], r, 1e-12 * r);
        assert_int_equal(vis[2 * i], bits[0]);
        assert_int_equal(vis[2 * i + 1], bits[1]);
        zero += r == 0.0;
    }
    assert_true(zero >= m / 4 && zero < m); /* the receivers facing away, and only a few others */
    /* Through the tb_ff_batch_fn pointer the solver uses: the same numbers. */
    tb_ff_batch_fn fn = tb_gpu_ff_batch;
    double ff2[576];
    assert_int_equal(fn(g, s, 64, ns, 1.0, p, n, m, ff2), TB_OK);
    for (size_t i = 0; i < m; ++i)
        assert_true(ff2[i] == ff[i]);
    tb_gpu_ff_scene_destroy(g);
    gpu_test_close(&e);
}

static void test_ff_unoccluded(void **state)
{
    (void)state;
    tb__unoccluded(false);
}

/* The same on the staging path (device-local buffers and copies). */
static void test_ff_unoccluded_staging(void **state)
{
    (void)state;
    tb__unoccluded(true);
}

/* Occluders (quads and triangles, 32 of them, so the BVH has inner nodes),
 * no segment grazing an edge: the visibility of every (receiver, sample) pair
 * is the exact answer and the CPU's, and the form factors agree as above. */
static void test_ff_occluded(void **state)
{
    (void)state;
    tb__make_occluders();
    gpu_test_env e;
    tb__open(&e, false);
    tb_gpu_ff_scene *g = tb_gpu_ff_scene_create(e.dev, tb__occ, TB__NOCC);
    assert_non_null(g);
    size_t ntri = 0;
    for (int k = 0; k < TB__NOCC; ++k)
        ntri += (size_t)tb__occ[k].n - 2;
    assert_int_equal(tb_gpu_ff_scene_triangles(g), ntri);
    tb_vec3 s[64], p[576], n[576];
    tb__grid_samples(s);
    size_t m = tb__grid_receivers(p, n);
    double ff[576], cpu[576];
    uint32_t vis[576 * 2];
    tb_vec3 ns = {0, 0, -1};
    assert_int_equal(tb_gpu_ff_raycast(g, s, 64, ns, 1.0, p, n, m, ff, vis, NULL), TB_OK);
    tb_ff_occluders *occ = NULL;
    assert_int_equal(tb_ff_occluders_build(tb__occ, TB__NOCC, &occ), TB_OK);
    assert_int_equal(tb_ff_raycast_batch(occ, s, 64, ns, 1.0, p, n, m, cpu), TB_OK);
    size_t blocked = 0, pairs = 0;
    for (size_t i = 0; i < m; ++i) {
        uint32_t bits[2] = {0, 0}, all[2] = {0, 0};
        double r = tb__ref(s, 64, ns, 1.0, p[i], n[i], tb__blocked, bits);
        tb__ref(s, 64, ns, 1.0, p[i], n[i], NULL, all);
        if (vis[2 * i] != bits[0] || vis[2 * i + 1] != bits[1])
            fail_msg("receiver %zu (%g, %g): gpu visibility %08x%08x, exact %08x%08x", i, p[i].x, p[i].y,
                     vis[2 * i + 1], vis[2 * i], bits[1], bits[0]);
        for (int k = 0; k < 64; ++k) { /* the CPU's visibility rule gives the same answer */
            bool front = (all[k / 32] >> (k % 32)) & 1u;
            if (front) {
                ++pairs;
                bool v = tb_ff_occluders_visible(occ, p[i], s[k]);
                assert_int_equal(v, (bits[k / 32] >> (k % 32)) & 1u);
                blocked += !v;
            }
        }
        tb_assert_near(ff[i], r, 2e-5 * r);
        tb_assert_near(cpu[i], r, 1e-12 * r);
    }
    /* The occluders block a fair share: the test exercises both answers. */
    assert_true(blocked > pairs / 20 && blocked < pairs);
    tb_ff_occluders_free(occ);
    tb_gpu_ff_scene_destroy(g);
    gpu_test_close(&e);
}

/* One occluder (the BVH's root is a leaf): a square covering every segment
 * blocks them all; the same square moved above the shooter blocks none. */
static void test_ff_single_occluder(void **state)
{
    (void)state;
    gpu_test_env e;
    tb__open(&e, false);
    tb_vec3 s[64], p[576], n[576];
    tb__grid_samples(s);
    size_t m = tb__grid_receivers(p, n);
    double ff[576];
    uint32_t vis[576 * 2];
    tb_vec3 ns = {0, 0, -1};
    for (int above = 0; above < 2; ++above) {
        float z = above ? 2.0f : 0.5f;
        tb_ff_polygon q = {{{-4, -4, z}, {4, -4, z}, {4, 4, z}, {-4, 4, z}}, 4};
        tb_gpu_ff_scene *g = tb_gpu_ff_scene_create(e.dev, &q, 1);
        assert_non_null(g);
        assert_int_equal(tb_gpu_ff_scene_triangles(g), 2);
        assert_int_equal(tb_gpu_ff_raycast(g, s, 64, ns, 1.0, p, n, m, ff, vis, NULL), TB_OK);
        for (size_t i = 0; i < m; ++i) {
            uint32_t bits[2] = {0, 0};
            double r = above ? tb__ref(s, 64, ns, 1.0, p[i], n[i], NULL, bits) : 0.0;
            tb_assert_near(ff[i], r, 2e-5 * r);
            assert_int_equal(vis[2 * i], bits[0]);
            assert_int_equal(vis[2 * i + 1], bits[1]);
        }
        tb_gpu_ff_scene_destroy(g);
    }
    gpu_test_close(&e);
}

/* Howell's catalogue (C-11): directly opposed parallel unit squares one unit
 * apart, F = 0.199824. Receivers: the 32 x 32 cell centres of the bottom
 * square (the area-to-area factor is their mean, midpoint rule); shooter:
 * 64 jittered stratified samples of the top square (tb_ff_sample_polygon),
 * seeds 1-4. The estimator's own error is the CPU's (docs/accuracy.md,
 * "Radiosity form factors": with 64 samples a mean of -0.35 % over 16 seeds
 * and at most 1.16 %, mostly the bias of eq. 5's disk term): 1.5 % bounds it,
 * and the kernel is held to float rounding (2e-5) against the CPU batch on
 * the same samples. Measured: 0.03-0.58 % on these seeds. */
static void test_ff_howell_parallel_squares(void **state)
{
    (void)state;
    double x = 1.0, y = 1.0; /* a / c, b / c */
    double exact = 2.0 / (TB__PI * x * y) *
                   (log(sqrt((1 + x * x) * (1 + y * y) / (1 + x * x + y * y))) +
                    x * sqrt(1 + y * y) * atan(x / sqrt(1 + y * y)) + y * sqrt(1 + x * x) * atan(y / sqrt(1 + x * x)) -
                    x * atan(x) - y * atan(y));
    tb_assert_near(exact, 0.199824, 1e-6);
    gpu_test_env e;
    tb__open(&e, false);
    tb_gpu_ff_scene *g = tb_gpu_ff_scene_create(e.dev, NULL, 0);
    assert_non_null(g);
    enum { R = 32 * 32, NP = 64 };
    tb_vec3 p[R], n[R], s[NP];
    for (int i = 0; i < R; ++i) {
        p[i] = (tb_vec3){((float)(i % 32) + 0.5f) / 32.0f, ((float)(i / 32) + 0.5f) / 32.0f, 0.0f};
        n[i] = (tb_vec3){0, 0, 1};
    }
    double ff[R], cpu[R], worst = 0.0;
    for (uint64_t seed = 1; seed <= 4; ++seed) {
        assert_int_equal(tb_ff_sample_polygon(&tb__top, NP, seed, s), TB_OK);
        assert_int_equal(tb_gpu_ff_raycast(g, s, NP, (tb_vec3){0, 0, -1}, 1.0, p, n, R, ff, NULL, NULL), TB_OK);
        assert_int_equal(tb_ff_raycast_batch(NULL, s, NP, (tb_vec3){0, 0, -1}, 1.0, p, n, R, cpu), TB_OK);
        double sum = 0.0;
        for (int i = 0; i < R; ++i) {
            tb_assert_near(ff[i], cpu[i], 2e-5 * cpu[i]);
            sum += ff[i];
        }
        double rel = fabs(sum / R - exact) / exact;
        print_message("[ howell   ] seed %d: F = %.6f (exact %.6f), relative error %.2e\n", (int)seed, sum / R, exact,
                      rel);
        worst = fmax(worst, rel);
    }
    assert_true(worst <= 1.5e-2);
    tb_gpu_ff_scene_destroy(g);
    gpu_test_close(&e);
}

/* More receivers than one dispatch takes (TB_GPU_FF_CHUNK): two chunks, every
 * result in its place. */
static void test_ff_chunks(void **state)
{
    (void)state;
    gpu_test_env e;
    tb__open(&e, false);
    tb_gpu_ff_scene *g = tb_gpu_ff_scene_create(e.dev, NULL, 0);
    assert_non_null(g);
    size_t m = TB_GPU_FF_CHUNK + 1000;
    tb_vec3 *p = malloc(m * sizeof *p), *n = malloc(m * sizeof *n);
    double *ff = malloc(m * sizeof *ff);
    assert_true(p && n && ff);
    for (size_t i = 0; i < m; ++i) {
        p[i] = (tb_vec3){(float)(i % 256) / 64.0f - 1.5f, (float)(i / 256) / 64.0f - 1.5f, 0.0f};
        n[i] = (tb_vec3){0, 0, 1};
    }
    tb_vec3 s[4] = {{0.25f, 0.25f, 1}, {0.75f, 0.25f, 1}, {0.25f, 0.75f, 1}, {0.75f, 0.75f, 1}};
    tb_gpu_ff_timing tm;
    assert_int_equal(tb_gpu_ff_raycast(g, s, 4, (tb_vec3){0, 0, -1}, 1.0, p, n, m, ff, NULL, &tm), TB_OK);
    assert_int_equal(tm.dispatches, 2);
    for (size_t i = 0; i < m; ++i) {
        double r = tb__ref(s, 4, (tb_vec3){0, 0, -1}, 1.0, p[i], n[i], NULL, NULL);
        tb_assert_near(ff[i], r, 2e-5 * r);
    }
    free(p), free(n), free(ff);
    tb_gpu_ff_scene_destroy(g);
    gpu_test_close(&e);
}

/* Refused arguments give TB_ERR_ARG with a message; an empty batch is fine. */
static void test_ff_errors(void **state)
{
    (void)state;
    gpu_test_env e;
    tb__open(&e, false);
    tb_ff_polygon bad = {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, 5};
    assert_null(tb_gpu_ff_scene_create(e.dev, &bad, 1));
    gpu_assert_error(TB_ERR_ARG, TB_ERR_ARG, "5 corners");
    tb_ff_polygon nan = {{{0, 0, 0}, {NAN, 0, 0}, {0, 1, 0}}, 3};
    assert_null(tb_gpu_ff_scene_create(e.dev, &nan, 1));
    gpu_assert_error(TB_ERR_ARG, TB_ERR_ARG, "non-finite");
    assert_null(tb_gpu_ff_scene_create(NULL, NULL, 0));
    tb_gpu_ff_scene *g = tb_gpu_ff_scene_create(e.dev, NULL, 0);
    assert_non_null(g);
    tb_vec3 s = {0, 0, 1}, p = {0, 0, 0}, n = {0, 0, 1};
    double ff = -1.0;
    gpu_assert_error(tb_gpu_ff_raycast(g, &s, -1, n, 1.0, &p, &n, 1, &ff, NULL, NULL), TB_ERR_ARG, "sample points");
    gpu_assert_error(tb_gpu_ff_raycast(g, NULL, 1, n, 1.0, &p, &n, 1, &ff, NULL, NULL), TB_ERR_ARG, "NULL");
    /* No samples, or no area: zeros, as tb_ff_raycast_batch gives. */
    assert_int_equal(tb_gpu_ff_raycast(g, &s, 0, n, 1.0, &p, &n, 1, &ff, NULL, NULL), TB_OK);
    assert_true(ff == 0.0);
    ff = -1.0;
    assert_int_equal(tb_gpu_ff_raycast(g, &s, 1, (tb_vec3){0, 0, -1}, 0.0, &p, &n, 1, &ff, NULL, NULL), TB_OK);
    assert_true(ff == 0.0);
    ff = -1.0;
    gpu_assert_error(tb_gpu_ff_raycast(g, &s, 1, n, NAN, &p, &n, 1, &ff, NULL, NULL), TB_ERR_ARG, "area");
    gpu_assert_error(tb_gpu_ff_raycast(g, &s, 1, n, 1.0, NULL, &n, 1, &ff, NULL, NULL), TB_ERR_ARG, "NULL");
    assert_int_equal(tb_gpu_ff_raycast(g, &s, 1, n, 1.0, NULL, NULL, 0, NULL, NULL, NULL), TB_OK);
    assert_true(ff == -1.0);
    tb_gpu_ff_scene_destroy(g);
    gpu_test_close(&e);
}

int main(int argc, char **argv)
{
    (void)argc, (void)argv;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ff_unoccluded),
        cmocka_unit_test(test_ff_unoccluded_staging),
        cmocka_unit_test(test_ff_occluded),
        cmocka_unit_test(test_ff_single_occluder),
        cmocka_unit_test(test_ff_howell_parallel_squares),
        cmocka_unit_test(test_ff_chunks),
        cmocka_unit_test(test_ff_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
