/* util/itembuf/itembuf: depth interpolation against the plane equation, the
 * depth test and its tie rule, ids of a mesh, accumulation per id, and bad
 * input. */
#include "itembuf_test.h"

#include <math.h>

#include "util/itembuf/itembuf.h"

/* Random triangles and quads (not on any grid) whose vertex depths lie on a
 * plane: every covered pixel holds the plane's value at its centre (up to
 * float rounding), every other pixel stays empty. */
static void test_itembuf_depth_plane(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("itembuf_depth_plane", 606), 1);
    const int W = 64, H = 48;
    tb_itembuf *buf = tb_itembuf_create(W, H);
    assert_non_null(buf);
    for (int trial = 0; trial < 200; trial++) {
        tb_itembuf_clear(buf);
        double ga = tb_rng_double(&rng) * 2 - 1, gb = tb_rng_double(&rng) * 2 - 1;
        double gc = 10 + tb_rng_double(&rng) * 100;
        int n = 3 + (int)tb_rng_below(&rng, 2);
        float xy[4][2], z[4];
        /* A convex quad: 4 points on an ellipse in angular order. */
        double cx = W * tb_rng_double(&rng), cy = H * tb_rng_double(&rng);
        double rx = 3 + 30 * tb_rng_double(&rng), ry = 3 + 30 * tb_rng_double(&rng);
        for (int k = 0; k < n; k++) {
            double a = 2 * TEST_PI * (k + 0.7 * tb_rng_double(&rng)) / n;
            xy[k][0] = (float)(cx + rx * cos(a));
            xy[k][1] = (float)(cy + ry * sin(a));
            z[k] = (float)(ga * xy[k][0] + gb * xy[k][1] + gc);
        }
        cover c;
        cover_init(&c, W, H);
        assert_int_equal(cover_polygon(&c, xy, n), TB_OK);
        assert_int_equal(tb_itembuf_draw_polygon(buf, xy, z, n, (uint32_t)trial), TB_OK);
        for (int j = 0; j < H; j++)
            for (int i = 0; i < W; i++) {
                uint32_t id = tb_itembuf_id(buf, i, j);
                float d = tb_itembuf_depth(buf, i, j);
                if (!c.count[j * W + i]) {
                    assert_int_equal(id, TB_ITEMBUF_EMPTY);
                    assert_true(isinf(d) && d > 0);
                    continue;
                }
                assert_int_equal(id, (uint32_t)trial);
                double expect = ga * (i + 0.5) + gb * (j + 0.5) + gc;
                /* Vertex depths are floats (relative error 6e-8 each). */
                tb_assert_near(d, expect, 2e-6 * (fabs(gc) + 100));
            }
        cover_free(&c);
    }
    tb_itembuf_free(buf);
}

/* A perspective view of a 3-D quad: with z/w per vertex, the item buffer
 * depth equals z/w of the 3-D point seen through each pixel centre. */
static void test_itembuf_perspective_depth(void **state)
{
    (void)state;
    const int W = 80, H = 60;
    const double f = 50.0, n_ = 1.0, fa = 100.0; /* focal length (pixels), near, far */
    /* Quad on the plane 0.3 x - 0.2 y + z = 8 (eye space, looking down +z). */
    const double P[4][3] = {{-3, -2, 0}, {3, -2, 0}, {3, 2, 0}, {-3, 2, 0}};
    float xy[4][2], zw[4];
    double pz[4];
    for (int k = 0; k < 4; k++) {
        pz[k] = 8 - 0.3 * P[k][0] + 0.2 * P[k][1];
        xy[k][0] = (float)(W / 2.0 + f * P[k][0] / pz[k]);
        xy[k][1] = (float)(H / 2.0 + f * P[k][1] / pz[k]);
        /* OpenGL-style depth: (A z + B) / z, linear in screen space. */
        double A = (fa + n_) / (fa - n_), B = -2 * fa * n_ / (fa - n_);
        zw[k] = (float)((A * pz[k] + B) / pz[k]);
    }
    tb_itembuf *buf = tb_itembuf_create(W, H);
    assert_non_null(buf);
    assert_int_equal(tb_itembuf_draw_polygon(buf, xy, zw, 4, 5), TB_OK);
    int covered = 0;
    for (int j = 0; j < H; j++)
        for (int i = 0; i < W; i++) {
            if (tb_itembuf_id(buf, i, j) != 5)
                continue;
            covered++;
            /* Ray through the centre: (u, v, 1) t meets the plane at
             * t = 8 / (1 + 0.3 u - 0.2 v). */
            double u = (i + 0.5 - W / 2.0) / f, v = (j + 0.5 - H / 2.0) / f;
            double z = 8 / (1 + 0.3 * u - 0.2 * v);
            double A = (fa + n_) / (fa - n_), B = -2 * fa * n_ / (fa - n_);
            tb_assert_near(tb_itembuf_depth(buf, i, j), (A * z + B) / z, 2e-6);
        }
    assert_true(covered > 200);
    tb_itembuf_free(buf);
}

/* Two tilted triangles crossing each other: each pixel keeps the nearer one
 * (by the plane equations), whatever the drawing order. */
static void test_itembuf_depth_test(void **state)
{
    (void)state;
    const int W = 40, H = 40;
    const float xy[3][2] = {{2, 3}, {37, 5}, {15, 38}};
    const float xy2[3][2] = {{4, 36}, {20, 1}, {38, 30}};
    float z1[3], z2[3];
    /* Planes z1 = 0.1 x + 5, z2 = -0.1 x + 0.05 y + 7: they cross at x ~ 10..20. */
    for (int k = 0; k < 3; k++) {
        z1[k] = 0.1f * xy[k][0] + 5;
        z2[k] = -0.1f * xy2[k][0] + 0.05f * xy2[k][1] + 7;
    }
    tb_itembuf *a = tb_itembuf_create(W, H), *b = tb_itembuf_create(W, H);
    assert_non_null(a);
    assert_non_null(b);
    assert_int_equal(tb_itembuf_draw_polygon(a, xy, z1, 3, 1), TB_OK);
    assert_int_equal(tb_itembuf_draw_polygon(a, xy2, z2, 3, 2), TB_OK);
    assert_int_equal(tb_itembuf_draw_polygon(b, xy2, z2, 3, 2), TB_OK);
    assert_int_equal(tb_itembuf_draw_polygon(b, xy, z1, 3, 1), TB_OK);
    assert_memory_equal(a->ids, b->ids, (size_t)W * H * sizeof(uint32_t));
    assert_memory_equal(a->depth, b->depth, (size_t)W * H * sizeof(float));
    int c1 = 3, n1 = 0, n2 = 0;
    for (int j = 0; j < H; j++)
        for (int i = 0; i < W; i++) {
            int in1 = ref_inside(xy, &c1, 1, TB_FILL_EVEN_ODD, i, j);
            int in2 = ref_inside(xy2, &c1, 1, TB_FILL_EVEN_ODD, i, j);
            double x = i + 0.5, y = j + 0.5, d1 = 0.1 * x + 5, d2 = -0.1 * x + 0.05 * y + 7;
            uint32_t id = tb_itembuf_id(a, i, j);
            if (!in1 && !in2) {
                assert_int_equal(id, TB_ITEMBUF_EMPTY);
            } else if (in1 && in2) {
                if (fabs(d1 - d2) > 1e-4) /* clear winner */
                    assert_int_equal(id, d1 < d2 ? 1u : 2u);
                n1 += id == 1;
                n2 += id == 2;
            } else {
                assert_int_equal(id, in1 ? 1u : 2u);
            }
        }
    assert_true(n1 > 20 && n2 > 20); /* the overlap really is split */
    tb_itembuf_free(a);
    tb_itembuf_free(b);
}

/* Equal depth: the lower id wins in either drawing order. */
static void test_itembuf_tie_rule(void **state)
{
    (void)state;
    const int W = 16, H = 16;
    const float sq[4][2] = {{1, 1}, {15, 1}, {15, 15}, {1, 15}};
    const float z[4] = {2.5f, 2.5f, 2.5f, 2.5f};
    tb_itembuf *buf = tb_itembuf_create(W, H);
    assert_non_null(buf);
    assert_int_equal(tb_itembuf_draw_polygon(buf, sq, z, 4, 9), TB_OK);
    assert_int_equal(tb_itembuf_draw_polygon(buf, sq, z, 4, 4), TB_OK);
    assert_int_equal(tb_itembuf_draw_polygon(buf, sq, z, 4, 7), TB_OK);
    assert_int_equal(tb_itembuf_id(buf, 5, 5), 4);
    tb_itembuf_clear(buf);
    assert_int_equal(tb_itembuf_draw_polygon(buf, sq, z, 4, 4), TB_OK);
    assert_int_equal(tb_itembuf_draw_polygon(buf, sq, z, 4, 9), TB_OK);
    assert_int_equal(tb_itembuf_id(buf, 5, 5), 4);
    /* NULL depth means depth 0 everywhere: in front of 2.5. */
    assert_int_equal(tb_itembuf_draw_polygon(buf, sq, NULL, 4, 11), TB_OK);
    assert_int_equal(tb_itembuf_id(buf, 5, 5), 11);
    assert_true(tb_itembuf_depth(buf, 5, 5) == 0.0f);
    /* A nearer polygon replaces, a farther one does not. */
    const float nearer[4] = {1, 1, 1, 1}, farther[4] = {3, 3, 3, 3};
    tb_itembuf_clear(buf);
    assert_int_equal(tb_itembuf_draw_polygon(buf, sq, z, 4, 1), TB_OK);
    assert_int_equal(tb_itembuf_draw_polygon(buf, sq, farther, 4, 0), TB_OK);
    assert_int_equal(tb_itembuf_id(buf, 5, 5), 1);
    assert_int_equal(tb_itembuf_draw_polygon(buf, sq, nearer, 4, 2), TB_OK);
    assert_int_equal(tb_itembuf_id(buf, 5, 5), 2);
    tb_itembuf_free(buf);
}

/* A random mesh drawn as items: each pixel holds the id of the one triangle
 * whose reference covers it; accumulate() counts and weighs them per id. */
static void test_itembuf_mesh_ids_and_accumulate(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("itembuf_mesh", 707), 2);
    const int W = 57, H = 41, nx = 7, ny = 5;
    float v[(7 + 1) * (5 + 1)][2];
    double cw = (W + 2.0) / nx, ch = (H + 2.0) / ny;
    for (int j = 0; j <= ny; j++)
        for (int i = 0; i <= nx; i++) {
            double x = -1 + i * cw, y = -1 + j * ch;
            if (i > 0 && i < nx)
                x += (tb_rng_double(&rng) - 0.5) * 0.4 * cw;
            if (j > 0 && j < ny)
                y += (tb_rng_double(&rng) - 0.5) * 0.4 * ch;
            v[j * (nx + 1) + i][0] = (float)(round(x * 2) / 2); /* half pixels: ties */
            v[j * (nx + 1) + i][1] = (float)(round(y * 2) / 2);
        }
    float tri[2 * 7 * 5][3][2];
    int nt = 0;
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++) {
            const int a = j * (nx + 1) + i, b = a + 1, c = a + nx + 2, d = a + nx + 1;
            const int t[2][3] = {{a, b, c}, {a, c, d}};
            for (int k = 0; k < 2; k++, nt++)
                for (int m = 0; m < 3; m++)
                    memcpy(tri[nt][m], v[t[k][m]], sizeof v[0]);
        }
    tb_itembuf *buf = tb_itembuf_create(W, H);
    assert_non_null(buf);
    /* Equal depths everywhere: only coverage decides (draw in reverse order). */
    for (int t = nt - 1; t >= 0; t--)
        assert_int_equal(tb_itembuf_draw_polygon(buf, tri[t], NULL, 3, (uint32_t)t), TB_OK);
    float *weights = malloc((size_t)W * H * sizeof *weights);
    double expect_count[70] = {0}, expect_sum[70] = {0};
    assert_non_null(weights);
    int three = 3;
    for (int j = 0; j < H; j++)
        for (int i = 0; i < W; i++) {
            weights[j * W + i] = (float)(1.0 / (1 + i + 2 * j));
            int owner = -1;
            for (int t = 0; t < nt; t++)
                if (ref_inside(tri[t], &three, 1, TB_FILL_EVEN_ODD, i, j)) {
                    assert_int_equal(owner, -1); /* the reference mesh is a tiling too */
                    owner = t;
                }
            assert_true(owner >= 0);
            assert_int_equal(tb_itembuf_id(buf, i, j), (uint32_t)owner);
            expect_count[owner] += 1;
            expect_sum[owner] += weights[j * W + i];
        }
    double count[70], sum[70];
    for (int t = 0; t < nt; t++)
        count[t] = sum[t] = 0.5; /* accumulate adds to what is there */
    assert_int_equal(tb_itembuf_accumulate(buf, NULL, count, (uint32_t)nt), TB_OK);
    assert_int_equal(tb_itembuf_accumulate(buf, weights, sum, (uint32_t)nt), TB_OK);
    double total = 0;
    for (int t = 0; t < nt; t++) {
        assert_true(count[t] == expect_count[t] + 0.5);
        tb_assert_near(sum[t], expect_sum[t] + 0.5, 1e-9);
        total += count[t] - 0.5;
    }
    assert_true(total == (double)W * H);
    /* Too few sums: refused, nothing added. */
    for (int t = 0; t < nt; t++)
        count[t] = 0;
    tb_clear_error();
    assert_int_equal(tb_itembuf_accumulate(buf, NULL, count, (uint32_t)nt - 1), TB_ERR_ARG);
    assert_true(strlen(tb_last_error()) > 0);
    for (int t = 0; t < nt; t++)
        assert_true(count[t] == 0);
    /* Empty pixels are skipped. */
    tb_itembuf_clear(buf);
    assert_int_equal(tb_itembuf_accumulate(buf, weights, count, 0), TB_OK);
    free(weights);
    tb_itembuf_free(buf);
}

/* A polygon with a hole drawn as one item: the hole keeps what is behind. */
static void test_itembuf_contours(void **state)
{
    (void)state;
    const int W = 24, H = 24;
    tb_itembuf *buf = tb_itembuf_create(W, H);
    assert_non_null(buf);
    const float back[4][2] = {{0, 0}, {24, 0}, {24, 24}, {0, 24}};
    const float zb[4] = {9, 9, 9, 9};
    assert_int_equal(tb_itembuf_draw_polygon(buf, back, zb, 4, 100), TB_OK);
    const float ring[8][2] = {{2, 2}, {22, 2}, {22, 22}, {2, 22}, {7, 7}, {17, 7}, {17, 17}, {7, 17}};
    const float zr[8] = {1, 1, 1, 1, 1, 1, 1, 1};
    const int counts[2] = {4, 4};
    assert_int_equal(tb_itembuf_draw_contours(buf, ring, zr, counts, 2, TB_FILL_EVEN_ODD, 3), TB_OK);
    double n[101] = {0};
    assert_int_equal(tb_itembuf_accumulate(buf, NULL, n, 101), TB_OK);
    assert_true(n[3] == 300);
    assert_true(n[100] == 576 - 300);
    assert_int_equal(tb_itembuf_id(buf, 12, 12), 100);
    assert_int_equal(tb_itembuf_id(buf, 3, 3), 3);
    tb_itembuf_free(buf);
}

static void test_itembuf_bad_input(void **state)
{
    (void)state;
    tb_clear_error();
    assert_null(tb_itembuf_create(0, 5));
    assert_true(strlen(tb_last_error()) > 0);
    assert_null(tb_itembuf_create(5, -1));
    assert_null(tb_itembuf_create(TB_SCAN_MAX_DIM + 1, 1));
    tb_itembuf_free(NULL);

    tb_itembuf *one = tb_itembuf_create(1, 1);
    assert_non_null(one);
    assert_int_equal(tb_itembuf_id(one, 0, 0), TB_ITEMBUF_EMPTY);
    const float tri[3][2] = {{-1, -1}, {3, -1}, {-1, 3}};
    const float z[3] = {1, 2, 3};
    assert_int_equal(tb_itembuf_draw_polygon(one, tri, z, 3, 0), TB_OK);
    assert_int_equal(tb_itembuf_id(one, 0, 0), 0);
    tb_assert_near(tb_itembuf_depth(one, 0, 0), 1 + 0.25 * 1.5 + 0.5 * 1.5, 1e-6);
    tb_itembuf_free(one);

    const int W = 8, H = 8;
    tb_itembuf *buf = tb_itembuf_create(W, H);
    assert_non_null(buf);
    const float sq[4][2] = {{0, 0}, {8, 0}, {8, 8}, {0, 8}};
    float zs[4] = {1, 1, 1, 1};
    /* NaN/inf depth, NaN vertex, reserved id: errors, nothing drawn. */
    zs[2] = NAN;
    assert_int_equal(tb_itembuf_draw_polygon(buf, sq, zs, 4, 1), TB_ERR_ARG);
    zs[2] = INFINITY;
    assert_int_equal(tb_itembuf_draw_polygon(buf, sq, zs, 4, 1), TB_ERR_ARG);
    zs[2] = 1;
    float bad[4][2] = {{0, 0}, {8, 0}, {8, NAN}, {0, 8}};
    assert_int_equal(tb_itembuf_draw_polygon(buf, bad, zs, 4, 1), TB_ERR_ARG);
    assert_int_equal(tb_itembuf_draw_polygon(buf, sq, zs, 4, TB_ITEMBUF_EMPTY), TB_ERR_ARG);
    assert_int_equal(tb_itembuf_draw_polygon(buf, sq, zs, -2, 1), TB_ERR_ARG);
    assert_int_equal(tb_itembuf_draw_polygon(NULL, sq, zs, 4, 1), TB_ERR_ARG);
    /* Degenerate shapes: fine, nothing drawn. */
    const float line[3][2] = {{0, 0}, {4, 4}, {8, 8}};
    const float dot[3][2] = {{4, 4}, {4, 4}, {4, 4}};
    assert_int_equal(tb_itembuf_draw_polygon(buf, line, zs, 3, 1), TB_OK);
    assert_int_equal(tb_itembuf_draw_polygon(buf, dot, zs, 3, 1), TB_OK);
    assert_int_equal(tb_itembuf_draw_polygon(buf, sq, zs, 2, 1), TB_OK);
    assert_int_equal(tb_itembuf_draw_polygon(buf, NULL, NULL, 0, 1), TB_OK);
    for (int k = 0; k < W * H; k++) {
        assert_int_equal(buf->ids[k], TB_ITEMBUF_EMPTY);
        assert_true(isinf(buf->depth[k]));
    }
    tb_itembuf_free(buf);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_itembuf_depth_plane),
        cmocka_unit_test(test_itembuf_perspective_depth),
        cmocka_unit_test(test_itembuf_depth_test),
        cmocka_unit_test(test_itembuf_tie_rule),
        cmocka_unit_test(test_itembuf_mesh_ids_and_accumulate),
        cmocka_unit_test(test_itembuf_contours),
        cmocka_unit_test(test_itembuf_bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
