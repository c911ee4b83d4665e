/* MIP-map construction and the plain lookups: level sizes; every level keeps
 * the mean of level 0 (exactly for power-of-two sizes with integer texels,
 * to float rounding for odd sizes); the odd-size 3-tap weights by hand;
 * bilinear and trilinear reproduce (bi)linear ramps exactly where they
 * should; level selection; wrap modes; EWA of a constant is the constant. */
#include "tb_test.h"

#include <string.h>

#include "host/render/texture.h"

static tb_image *random_image(tb_rng *rng, int w, int h, int ch, bool integers)
{
    tb_image *img = tb_image_create(w, h, ch, NULL);
    assert_non_null(img);
    for (size_t i = 0; i < (size_t)w * h * ch; i++)
        img->pixels[i] = integers ? (float)tb_rng_below(rng, 256) : 4.0f * tb_rng_float(rng);
    return img;
}

/* Mean of channel c of a level, in long double (exact for integer texels). */
static long double level_mean(const tb_mipmap *m, int l, int c)
{
    const tb_mip_level *lv = &m->levels[l];
    long double s = 0.0L;
    for (size_t i = 0; i < (size_t)lv->width * lv->height; i++)
        s += lv->texels[i * m->channels + c];
    return s / ((long double)lv->width * lv->height);
}

static void test_sizes_and_means(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("mip means", 21), 0);
    /* power-of-two sizes with integer texels: box averages of 2 or 4 values
     * are exact in float, so the means agree exactly */
    const int pot[][2] = {{64, 32}, {1, 128}, {256, 2}, {16, 16}, {1, 1}};
    for (size_t k = 0; k < sizeof pot / sizeof pot[0]; k++) {
        tb_image *img = random_image(&rng, pot[k][0], pot[k][1], 3, true);
        tb_mipmap *m = tb_mipmap_create(img);
        assert_non_null(m);
        int big = pot[k][0] > pot[k][1] ? pot[k][0] : pot[k][1], expect = 1;
        while ((1 << (expect - 1)) < big)
            expect++;
        assert_int_equal(m->nlevels, expect);
        for (int l = 0; l < m->nlevels; l++)
            for (int c = 0; c < 3; c++)
                assert_true(level_mean(m, l, c) == level_mean(m, 0, c));
        tb_mipmap_free(m);
        tb_image_free(img);
    }
    /* odd and mixed sizes: every level's mean equals level 0's to float
     * rounding of each texel (relative 2^-24 per rounding, a few roundings) */
    const int odd[][2] = {{37, 23}, {5, 129}, {1, 7}, {3, 3}, {255, 1}, {100, 75}, {7, 2}};
    for (size_t k = 0; k < sizeof odd / sizeof odd[0]; k++) {
        tb_image *img = random_image(&rng, odd[k][0], odd[k][1], 2, false);
        tb_mipmap *m = tb_mipmap_create(img);
        assert_non_null(m);
        int w = odd[k][0], h = odd[k][1];
        for (int l = 0; l < m->nlevels; l++) {
            assert_int_equal(m->levels[l].width, w);
            assert_int_equal(m->levels[l].height, h);
            w = w > 1 ? w / 2 : 1;
            h = h > 1 ? h / 2 : 1;
            for (int c = 0; c < 2; c++)
                tb_assert_near((double)level_mean(m, l, c), (double)level_mean(m, 0, c),
                               4e-7 * (double)level_mean(m, 0, c));
        }
        const tb_mip_level *top = &m->levels[m->nlevels - 1];
        assert_true(top->width == 1 && top->height == 1);
        tb_mipmap_free(m);
        tb_image_free(img);
    }
}

static void test_odd_weights_by_hand(void **state)
{
    (void)state;
    /* 5 texels -> 2: each output covers 2.5 inputs,
     * out0 = (x0 + x1 + x2/2) / 2.5, out1 = (x2/2 + x3 + x4) / 2.5 */
    tb_image *img = tb_image_create(5, 1, 1, NULL);
    const float x[5] = {1.0f, 2.0f, 4.0f, 8.0f, 16.0f};
    memcpy(img->pixels, x, sizeof x);
    tb_mipmap *m = tb_mipmap_create(img);
    assert_int_equal(m->nlevels, 3);
    tb_assert_near(m->levels[1].texels[0], (1.0 + 2.0 + 2.0) / 2.5, 1e-6);
    tb_assert_near(m->levels[1].texels[1], (2.0 + 8.0 + 16.0) / 2.5, 1e-6);
    tb_assert_near(m->levels[2].texels[0], 31.0 / 5.0, 1e-6);
    tb_mipmap_free(m);
    tb_image_free(img);
    /* 7 -> 3 (r = 7/3): out1 covers [7/3, 14/3): 2/3 x2 + x3 + 2/3 x4 */
    img = tb_image_create(1, 7, 1, NULL);
    for (int i = 0; i < 7; i++)
        img->pixels[i] = (float)(i * i);
    m = tb_mipmap_create(img);
    assert_int_equal(m->levels[1].height, 3);
    tb_assert_near(m->levels[1].texels[1], (2.0 / 3.0 * 4.0 + 9.0 + 2.0 / 3.0 * 16.0) / (7.0 / 3.0), 1e-5);
    tb_assert_near(m->levels[1].texels[0], (0.0 + 1.0 + 1.0 / 3.0 * 4.0) / (7.0 / 3.0), 1e-5);
    tb_mipmap_free(m);
    tb_image_free(img);
    /* too many channels */
    img = tb_image_create(2, 2, 5, NULL);
    assert_null(tb_mipmap_create(img));
    tb_image_free(img);
}

/* f(u, v) = a + b u + c v + d u v sampled at the texel centres of level 0. */
static tb_image *ramp(int w, int h, double a, double b, double c, double d)
{
    tb_image *img = tb_image_create(w, h, 1, NULL);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double u = (x + 0.5) / w, v = 1.0 - (y + 0.5) / h;
            tb_image_at(img, x, y)[0] = (float)(a + b * u + c * v + d * u * v);
        }
    return img;
}

static void test_bilinear_trilinear_exact(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("ramps", 5), 0);
    const double a = 0.25, b = 1.5, c = -0.75, d = 2.0;
    /* bilinear interpolation reproduces any a + b u + c v + d u v between
     * texel centres, at any size; the texels themselves are floats, so the
     * tolerance is a few float roundings of the values (|f| < 4) */
    tb_image *img = ramp(37, 20, a, b, c, d);
    tb_mipmap *m = tb_mipmap_create(img);
    for (int k = 0; k < 2000; k++) {
        double u = (0.5 + 36.0 * tb_rng_double(&rng)) / 37.0, v = (0.5 + 19.0 * tb_rng_double(&rng)) / 20.0;
        float out;
        tb_mipmap_bilinear(m, 0, (float)u, (float)v, (tb_tex_wrap)(k & 1), &out);
        /* (u, v) as the lookup sees them: rounded to float */
        double uf = (float)u, vf = (float)v;
        tb_assert_near(out, a + b * uf + c * vf + d * uf * vf, 2e-6);
    }
    tb_mipmap_free(m);
    tb_image_free(img);
    /* power of two: each level of a bilinear ramp is the same ramp sampled at
     * its own texel centres (the 2x2 box average of a bilinear function is
     * its value at the centre), so trilinear is exact for any footprint away
     * from the borders */
    img = ramp(256, 128, a, b, c, d);
    m = tb_mipmap_create(img);
    for (int l = 1; l < m->nlevels; l++) {
        const tb_mip_level *lv = &m->levels[l];
        for (int y = 0; y < lv->height; y++)
            for (int x = 0; x < lv->width; x++) {
                double u = (x + 0.5) / lv->width, v = 1.0 - (y + 0.5) / lv->height;
                tb_assert_near(lv->texels[y * lv->width + x], a + b * u + c * v + d * u * v, 2e-6);
            }
    }
    for (int k = 0; k < 2000; k++) {
        double u = 0.25 + 0.5 * tb_rng_double(&rng), v = 0.25 + 0.5 * tb_rng_double(&rng);
        double len = exp2(4.0 * tb_rng_double(&rng)) / 256.0, ang = 6.283 * tb_rng_double(&rng);
        tb_tex_footprint fp = {(float)(len * cos(ang)), (float)(len * sin(ang)),
                               (float)(-0.3 * len * sin(ang)), (float)(0.3 * len * cos(ang))};
        float out;
        tb_mipmap_trilinear(m, (float)u, (float)v, &fp, (tb_tex_wrap)(k & 1), &out);
        double uf = (float)u, vf = (float)v;
        tb_assert_near(out, a + b * uf + c * vf + d * uf * vf, 4e-6);
    }
    tb_mipmap_free(m);
    tb_image_free(img);
}

static void test_level_of(void **state)
{
    (void)state;
    tb_image *img = tb_image_create(256, 64, 1, NULL);
    tb_mipmap *m = tb_mipmap_create(img);
    assert_int_equal(m->nlevels, 9);
    tb_assert_near(tb_mipmap_level_of(m, 0.5f), 0.0, 0.0);
    tb_assert_near(tb_mipmap_level_of(m, 1.0f), 0.0, 0.0);
    for (double t = 1.0; t <= 256.0; t *= 1.37)
        tb_assert_near(tb_mipmap_level_of(m, (float)t), log2(t), 1e-6);
    tb_assert_near(tb_mipmap_level_of(m, 1e6f), 8.0, 0.0);
    tb_assert_near(tb_mipmap_level_of(m, NAN), 0.0, 0.0);
    tb_mipmap_free(m);
    tb_image_free(img);
    /* non-power-of-two: level l sits exactly at its texel size and the
     * continuous level increases with the width */
    img = tb_image_create(100, 37, 1, NULL);
    m = tb_mipmap_create(img);
    for (int l = 0; l < m->nlevels; l++) {
        double sx = 100.0 / m->levels[l].width, sy = 37.0 / m->levels[l].height;
        tb_assert_near(tb_mipmap_level_of(m, (float)fmax(sx, sy)), l, 1e-5);
    }
    float prev = -1.0f;
    for (double t = 0.5; t < 200.0; t *= 1.05) {
        float l = tb_mipmap_level_of(m, (float)t);
        assert_true(l >= prev);
        prev = l;
    }
    tb_mipmap_free(m);
    tb_image_free(img);
}

static void test_wrap_and_nearest(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, 3, 0);
    tb_image *img = random_image(&rng, 7, 5, 3, false);
    tb_mipmap *m = tb_mipmap_create(img);
    float a[3], b[3];
    for (int y = -12; y < 12; y++)
        for (int x = -15; x < 15; x++) {
            tb_mipmap_texel(m, 0, x, y, TB_TEX_REPEAT, a);
            const float *ref = tb_image_at(img, ((x % 7) + 7) % 7, ((y % 5) + 5) % 5);
            assert_memory_equal(a, ref, sizeof a);
            tb_mipmap_texel(m, 0, x, y, TB_TEX_CLAMP, b);
            ref = tb_image_at(img, x < 0 ? 0 : (x > 6 ? 6 : x), y < 0 ? 0 : (y > 4 ? 4 : y));
            assert_memory_equal(b, ref, sizeof b);
        }
    /* texel centres: nearest and bilinear give the texel; v runs up the image */
    for (int y = 0; y < 5; y++)
        for (int x = 0; x < 7; x++) {
            float u = (x + 0.5f) / 7.0f, v = 1.0f - (y + 0.5f) / 5.0f;
            tb_mipmap_nearest(m, 0, u, v, TB_TEX_REPEAT, a);
            assert_memory_equal(a, tb_image_at(img, x, y), sizeof a);
            tb_mipmap_bilinear(m, 0, u, v, TB_TEX_CLAMP, b);
            for (int c = 0; c < 3; c++)
                tb_assert_near(b[c], tb_image_at(img, x, y)[c], 2e-6);
        }
    /* bilinear across the repeat seam blends the last and first columns */
    tb_mipmap_bilinear(m, 0, 0.0f, 1.0f - 0.5f / 5.0f, TB_TEX_REPEAT, a);
    for (int c = 0; c < 3; c++)
        tb_assert_near(a[c], 0.5 * (tb_image_at(img, 6, 0)[c] + tb_image_at(img, 0, 0)[c]), 2e-6);
    tb_mipmap_bilinear(m, 0, 0.0f, 1.0f - 0.5f / 5.0f, TB_TEX_CLAMP, a);
    for (int c = 0; c < 3; c++)
        tb_assert_near(a[c], tb_image_at(img, 0, 0)[c], 2e-6);
    tb_mipmap_free(m);
    tb_image_free(img);
}

static void test_ewa_constant(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("ewa constant", 9), 0);
    const int sizes[][2] = {{64, 64}, {37, 23}, {200, 3}, {1, 50}};
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
        tb_image *img = tb_image_create(sizes[k][0], sizes[k][1], 3, NULL);
        for (size_t i = 0; i < (size_t)sizes[k][0] * sizes[k][1]; i++) {
            img->pixels[3 * i] = 0.7f;
            img->pixels[3 * i + 1] = 0.0f;
            img->pixels[3 * i + 2] = 13.5f;
        }
        tb_mipmap *m = tb_mipmap_create(img);
        for (int j = 0; j < 3000; j++) {
            float u = (float)(4.0 * tb_rng_double(&rng) - 2.0), v = (float)(4.0 * tb_rng_double(&rng) - 2.0);
            /* footprints from zero to many times the texture, any shape */
            double s1 = j % 10 == 0 ? 0.0 : exp2(-12.0 + 16.0 * tb_rng_double(&rng));
            double s2 = s1 * exp2(-10.0 * tb_rng_double(&rng));
            double ang = 6.283 * tb_rng_double(&rng);
            tb_tex_footprint fp = {(float)(s1 * cos(ang)), (float)(s1 * sin(ang)), (float)(-s2 * sin(ang)),
                                   (float)(s2 * cos(ang))};
            float out[3];
            tb_mipmap_ewa(m, u, v, &fp, (tb_tex_wrap)(j & 1), (j & 2) ? 8.0f : 32.0f, out);
            tb_assert_near(out[0], 0.7, 1e-6);
            tb_assert_near(out[1], 0.0, 0.0);
            tb_assert_near(out[2], 13.5, 2e-5);
            tb_mipmap_trilinear(m, u, v, &fp, (tb_tex_wrap)(j & 1), out);
            tb_assert_near(out[0], 0.7, 1e-6);
            tb_assert_near(out[2], 13.5, 2e-5);
        }
        tb_mipmap_free(m);
        tb_image_free(img);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sizes_and_means),
        cmocka_unit_test(test_odd_weights_by_hand),
        cmocka_unit_test(test_bilinear_trilinear_exact),
        cmocka_unit_test(test_level_of),
        cmocka_unit_test(test_wrap_and_nearest),
        cmocka_unit_test(test_ewa_constant),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
