/* Image comparison: metrics on images whose answers are known exactly, SSIM
 * against an independent Python implementation, the NaN/Inf rule, channel
 * matching and the false-colour error image. */
#include <string.h>

#include "tb_test.h"
#include "util/color/srgb.h"
#include "util/image/compare.h"

static tb_image *constant(int w, int h, int nch, const char *const *names, const float *v)
{
    tb_image *img = tb_image_create(w, h, nch, names);
    assert_non_null(img);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            for (int c = 0; c < nch; c++)
                tb_image_at(img, x, y)[c] = v[c];
    return img;
}

/* SSIM of two constant images: the structure term is C2/C2 = 1, the
 * luminance term (2 mu_a mu_b + C1) / (mu_a^2 + mu_b^2 + C1). */
static double ssim_constant(double a, double b, double peak)
{
    double c1 = (0.01 * peak) * (0.01 * peak);
    return (2 * a * b + c1) / (a * a + b * b + c1);
}

/* A = B + a different constant offset per channel: every metric is known. */
static void test_constant_offset(void **state)
{
    (void)state;
    const float ref[3] = {0.5f, 0.5f, 0.5f};
    const float off[3] = {0.25f, 0.125f, -0.0625f};
    const float tst[3] = {ref[0] + off[0], ref[1] + off[1], ref[2] + off[2]};
    tb_image *b = constant(16, 12, 3, NULL, ref);
    tb_image *a = constant(16, 12, 3, NULL, tst);
    tb_compare_result r;
    assert_int_equal(tb_image_compare(a, b, NULL, &r), TB_OK);
    assert_int_equal(r.nchannels, 3);
    assert_string_equal(r.names[0], "R");
    assert_string_equal(r.names[2], "B");
    assert_int_equal(r.valid_pixels, 16 * 12);
    assert_int_equal(r.ssim_windows, 6 * 2);
    double mse_sum = 0, rel_sum = 0, ssim_sum = 0;
    for (int c = 0; c < 3; c++) {
        double d = off[c];
        tb_assert_near(r.channel[c].mse, d * d, 0);
        tb_assert_near(r.channel[c].rmse, fabs(d), 0);
        tb_assert_near(r.channel[c].relmse, d * d / (0.25 + 0.01), 1e-13);
        tb_assert_near(r.channel[c].psnr, -10.0 * log10(d * d), 1e-12);
        tb_assert_near(r.channel[c].max_abs, fabs(d), 0);
        assert_int_equal(r.channel[c].max_x, 0);
        assert_int_equal(r.channel[c].max_y, 0);
        tb_assert_near(r.channel[c].ssim, ssim_constant(tst[c], ref[c], 1.0), 1e-12);
        mse_sum += d * d;
        rel_sum += d * d / 0.26;
        ssim_sum += ssim_constant(tst[c], ref[c], 1.0);
    }
    tb_assert_near(r.all.mse, mse_sum / 3, 1e-16);
    tb_assert_near(r.all.rmse, sqrt(mse_sum / 3), 1e-16);
    tb_assert_near(r.all.relmse, rel_sum / 3, 1e-13);
    tb_assert_near(r.all.psnr, 10.0 * log10(1.0 / (mse_sum / 3)), 1e-12);
    tb_assert_near(r.all.ssim, ssim_sum / 3, 1e-12);
    tb_assert_near(r.all.max_abs, 0.25, 0);
    assert_int_equal(r.max_channel, 0);

    /* peak 2: PSNR grows by 10 log10(4), SSIM uses L = 2. */
    tb_compare_options o = {.peak = 2.0};
    tb_compare_result r2;
    assert_int_equal(tb_image_compare(a, b, &o, &r2), TB_OK);
    tb_assert_near(r2.all.psnr - r.all.psnr, 10.0 * log10(4.0), 1e-12);
    tb_assert_near(r2.channel[1].ssim, ssim_constant(tst[1], ref[1], 2.0), 1e-12);
    tb_image_free(a);
    tb_image_free(b);
}

static void test_identical(void **state)
{
    (void)state;
    tb_image *a = tb_image_create(20, 15, 3, NULL);
    for (size_t i = 0; i < 20 * 15 * 3; i++)
        a->pixels[i] = (float)((i * 7919) % 101) / 100.0f;
    tb_compare_result r;
    assert_int_equal(tb_image_compare(a, a, NULL, &r), TB_OK);
    assert_true(r.all.mse == 0.0);
    assert_true(isinf(r.all.psnr) && r.all.psnr > 0);
    assert_true(isinf(r.channel[2].psnr));
    tb_assert_near(r.all.ssim, 1.0, 1e-15);
    assert_true(r.all.max_abs == 0.0);
    tb_image_free(a);
}

/* relMSE divides by b^2 + 0.01 with b the reference (second) image. */
static void test_relmse_eps(void **state)
{
    (void)state;
    tb_image *a = tb_image_create(2, 1, 1, NULL), *b = tb_image_create(2, 1, 1, NULL);
    a->pixels[0] = 0.125f, a->pixels[1] = 1.5f;
    b->pixels[0] = 0.0f, b->pixels[1] = 1.0f;
    tb_compare_result r;
    assert_int_equal(tb_image_compare(a, b, NULL, &r), TB_OK);
    assert_string_equal(r.names[0], "Y");
    tb_assert_near(r.all.relmse, (0.015625 / 0.01 + 0.25 / 1.01) / 2, 1e-15);
    tb_assert_near(r.all.mse, (0.015625 + 0.25) / 2, 0);
    /* swapping the roles changes relMSE (b is the reference) */
    assert_int_equal(tb_image_compare(b, a, NULL, &r), TB_OK);
    tb_assert_near(r.all.relmse, (0.015625 / (0.015625 + 0.01) + 0.25 / (2.25 + 0.01)) / 2, 1e-15);
    /* too small for an 11x11 window: SSIM is NaN, the rest is defined */
    assert_true(isnan(r.all.ssim));
    assert_int_equal(r.ssim_windows, 0);
    tb_image_free(a);
    tb_image_free(b);
}

static void test_max_location(void **state)
{
    (void)state;
    const float z[3] = {0.1f, 0.2f, 0.3f};
    tb_image *a = constant(9, 7, 3, NULL, z), *b = constant(9, 7, 3, NULL, z);
    tb_image_at(a, 5, 3)[1] += 0.5f;
    tb_image_at(a, 1, 6)[2] -= 0.25f;
    tb_compare_result r;
    assert_int_equal(tb_image_compare(a, b, NULL, &r), TB_OK);
    assert_int_equal(r.max_channel, 1);
    assert_int_equal(r.all.max_x, 5);
    assert_int_equal(r.all.max_y, 3);
    assert_int_equal(r.channel[2].max_x, 1);
    assert_int_equal(r.channel[2].max_y, 6);
    tb_assert_near(r.channel[1].max_abs, (double)(0.2f + 0.5f) - (double)0.2f, 0);
    tb_image_free(a);
    tb_image_free(b);
}

/* NaN and Inf pixels are counted and excluded; the other pixels give the
 * same numbers as without them, and SSIM skips exactly the windows that
 * contain them. */
static void test_nonfinite(void **state)
{
    (void)state;
    const float ref[3] = {0.5f, 0.5f, 0.5f}, tst[3] = {0.75f, 0.5f, 0.5f};
    tb_image *a = constant(30, 20, 3, NULL, tst), *b = constant(30, 20, 3, NULL, ref);
    tb_image_at(a, 2, 2)[0] = NAN;
    tb_image_at(b, 25, 15)[2] = INFINITY;
    tb_image_at(a, 25, 15)[2] = 100.0f; /* excluded with its pixel, must not count */
    tb_compare_result r;
    assert_int_equal(tb_image_compare(a, b, NULL, &r), TB_OK);
    assert_int_equal(r.nonfinite_a, 1);
    assert_int_equal(r.nonfinite_b, 1);
    assert_int_equal(r.pixels, 600);
    assert_int_equal(r.valid_pixels, 598);
    tb_assert_near(r.channel[0].mse, 0.0625, 0);
    tb_assert_near(r.channel[2].mse, 0.0, 0);
    tb_assert_near(r.all.max_abs, 0.25, 0);
    /* windows (top-left corners 0..19 x 0..9): (2,2) lies in 3x3 of them,
     * (25,15) in 5x5, and no window holds both. */
    assert_int_equal(r.ssim_windows, 200 - 9 - 25);
    tb_assert_near(r.channel[0].ssim, ssim_constant(0.75, 0.5, 1.0), 1e-12);
    tb_assert_near(r.channel[2].ssim, 1.0, 1e-15);

    /* every pixel bad: metrics NaN, still a result */
    tb_image *n = constant(4, 4, 3, NULL, (const float[3]){NAN, 0, 0});
    tb_image *m = constant(4, 4, 3, NULL, ref);
    assert_int_equal(tb_image_compare(n, m, NULL, &r), TB_OK);
    assert_int_equal(r.valid_pixels, 0);
    assert_int_equal(r.nonfinite_a, 16);
    assert_true(isnan(r.all.mse) && isnan(r.all.psnr) && isnan(r.all.max_abs));
    assert_int_equal(r.all.max_x, -1);
    tb_image_free(n);
    tb_image_free(m);
    tb_image_free(a);
    tb_image_free(b);
}

static void test_channel_matching(void **state)
{
    (void)state;
    const float v[4] = {0.1f, 0.2f, 0.3f, 0.4f};
    const char *ya[] = {"Y", "A"};
    const char *zx[] = {"Z", "X"};
    const char *xq[] = {"X", "Q"};
    tb_image *rgba = constant(3, 3, 4, NULL, v), *rgb = constant(3, 3, 3, NULL, v);
    tb_image *grey = constant(3, 3, 2, ya, v), *other = constant(3, 3, 2, zx, v);
    tb_image *other2 = constant(3, 3, 2, xq, v), *small = constant(2, 3, 3, NULL, v);
    tb_compare_result r;
    tb_compare_options o = {0};

    assert_int_equal(tb_image_compare(rgba, rgb, NULL, &r), TB_OK);
    assert_int_equal(r.nchannels, 3); /* alpha ignored by default */
    o.include_alpha = 1;
    assert_int_equal(tb_image_compare(rgba, rgba, &o, &r), TB_OK);
    assert_int_equal(r.nchannels, 4);
    assert_string_equal(r.names[3], "A");
    assert_int_equal(tb_image_compare(rgba, rgb, &o, &r), TB_OK); /* only A has alpha */
    assert_int_equal(r.nchannels, 3);

    assert_int_equal(tb_image_compare(rgb, grey, NULL, &r), TB_ERR_ARG);
    assert_non_null(strstr(tb_last_error(), "no colour channel in common"));
    assert_int_equal(tb_image_compare(other, other2, NULL, &r), TB_OK); /* shared name X */
    assert_int_equal(r.nchannels, 1);
    assert_string_equal(r.names[0], "X");

    o = (tb_compare_options){.channels = "G, A"};
    assert_int_equal(tb_image_compare(rgba, rgba, &o, &r), TB_OK);
    assert_int_equal(r.nchannels, 2);
    assert_string_equal(r.names[0], "G");
    assert_string_equal(r.names[1], "A");
    o.channels = "R,Q";
    assert_int_equal(tb_image_compare(rgb, rgb, &o, &r), TB_ERR_ARG);
    assert_non_null(strstr(tb_last_error(), "\"Q\""));
    o.channels = "R,,G";
    assert_int_equal(tb_image_compare(rgb, rgb, &o, &r), TB_ERR_ARG);
    o.channels = "R,R";
    assert_int_equal(tb_image_compare(rgb, rgb, &o, &r), TB_ERR_ARG);

    assert_int_equal(tb_image_compare(rgb, small, NULL, &r), TB_ERR_ARG);
    assert_non_null(strstr(tb_last_error(), "size mismatch: A is 3x3, B is 2x3"));
    o = (tb_compare_options){.peak = -1};
    assert_int_equal(tb_image_compare(rgb, rgb, &o, &r), TB_ERR_ARG);
    tb_image *err = NULL;
    assert_int_equal(tb_compare_error_image(rgb, small, NULL, 0, &err, NULL), TB_ERR_ARG);
    assert_null(err);

    tb_image *imgs[] = {rgba, rgb, grey, other, other2, small};
    for (size_t i = 0; i < sizeof imgs / sizeof imgs[0]; i++)
        tb_image_free(imgs[i]);
}

/* The pair defined in compare_ssim_reference.py, built here from the same
 * integer formulas (exact binary fractions). */
static void ssim_pair(tb_image **a, tb_image **b)
{
    *a = tb_image_create(24, 20, 3, NULL);
    *b = tb_image_create(24, 20, 3, NULL);
    for (int y = 0; y < 20; y++)
        for (int x = 0; x < 24; x++)
            for (int c = 0; c < 3; c++) {
                double va = ((37 * x + 91 * y + 53 * c + (x * y) % 13) % 64) / 64.0;
                double vb = va + (((11 * x + 7 * y + 5 * c) % 9) - 4) / 16.0;
                tb_image_at(*a, x, y)[c] = (float)va;
                tb_image_at(*b, x, y)[c] = (float)vb;
            }
}

/* SSIM agrees with the independent Python implementation to 1e-6. */
static void test_ssim_matches_python(void **state)
{
    (void)state;
    static const double peaks[2] = {1.0, 2.0};
    for (int k = 0; k < 2; k++) {
        char cmd[1024];
        snprintf(cmd, sizeof cmd, "python3 '%s/image/compare_ssim_reference.py' --peak %g",
                 TB_TESTS_DIR, peaks[k]);
        FILE *p = popen(cmd, "r");
        assert_non_null(p);
        char out[1024] = {0};
        size_t n = fread(out, 1, sizeof out - 1, p);
        assert_int_equal(pclose(p), 0);
        assert_true(n > 0);
        double py[3], mean;
        const char *s = strstr(out, "\"ssim\": [");
        assert_non_null(s);
        assert_int_equal(sscanf(s, "\"ssim\": [%lf, %lf, %lf]", &py[0], &py[1], &py[2]), 3);
        s = strstr(out, "\"mean\": ");
        assert_non_null(s);
        assert_int_equal(sscanf(s, "\"mean\": %lf", &mean), 1);

        tb_image *a, *b;
        ssim_pair(&a, &b);
        tb_compare_options o = {.peak = peaks[k]};
        tb_compare_result r;
        assert_int_equal(tb_image_compare(a, b, &o, &r), TB_OK);
        print_message("[ ssim     ] peak %g: C %.12f %.12f %.12f, Python %.12f %.12f %.12f\n",
                      peaks[k], r.channel[0].ssim, r.channel[1].ssim, r.channel[2].ssim, py[0],
                      py[1], py[2]);
        for (int c = 0; c < 3; c++)
            tb_assert_near(r.channel[c].ssim, py[c], 1e-6);
        tb_assert_near(r.all.ssim, mean, 1e-6);
        assert_true(r.all.ssim < 0.9); /* the pair is far from identical */
        tb_image_free(a);
        tb_image_free(b);
    }
}

/* viridis endpoints (matplotlib's table, sRGB) stored as linear values. */
static void test_colormap(void **state)
{
    (void)state;
    float rgb[3];
    tb_compare_colormap(0.0, rgb);
    tb_assert_near(rgb[0], tb_srgb_decode(0.267004f), 1e-7);
    tb_assert_near(rgb[1], tb_srgb_decode(0.004874f), 1e-7);
    tb_assert_near(rgb[2], tb_srgb_decode(0.329415f), 1e-7);
    tb_compare_colormap(1.0, rgb);
    tb_assert_near(rgb[0], tb_srgb_decode(0.993248f), 1e-7);
    tb_assert_near(rgb[1], tb_srgb_decode(0.906157f), 1e-7);
    tb_assert_near(rgb[2], tb_srgb_decode(0.143936f), 1e-7);
    tb_compare_colormap(7.0, rgb); /* clamped */
    tb_assert_near(rgb[0], tb_srgb_decode(0.993248f), 1e-7);
    /* entry 128 of the 256-entry table */
    tb_compare_colormap(128.0 / 255.0, rgb);
    tb_assert_near(rgb[1], tb_srgb_decode(0.566949f), 1e-6);
    tb_compare_colormap(NAN, rgb);
    assert_true(rgb[0] == 1.0f && rgb[1] == 0.0f && rgb[2] == 1.0f);
    /* perceptually ordered: luminance rises strictly with t */
    double prev = -1.0;
    for (int i = 0; i <= 200; i++) {
        tb_compare_colormap(i / 200.0, rgb);
        double lum = 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
        if (!(lum > prev))
            fail_msg("luminance not increasing at t = %g", i / 200.0);
        prev = lum;
    }
}

static void test_error_image(void **state)
{
    (void)state;
    const float z[3] = {0.5f, 0.5f, 0.5f};
    tb_image *a = constant(7, 5, 3, NULL, z), *b = constant(7, 5, 3, NULL, z);
    float *p = tb_image_at(a, 4, 2);
    p[0] += 0.25f, p[1] += 0.25f, p[2] += 0.25f; /* per-pixel RMS error 0.25 */
    tb_image_at(a, 1, 1)[0] += 0.125f;             /* RMS 0.125 / sqrt(3) */
    tb_image_at(b, 6, 4)[1] = NAN;
    tb_image *e = NULL;
    double used = 0;
    assert_int_equal(tb_compare_error_image(a, b, NULL, 0, &e, &used), TB_OK);
    assert_int_equal(e->width, 7);
    assert_int_equal(e->height, 5);
    assert_int_equal(e->channels, 3);
    assert_string_equal(e->names[0], "R");
    tb_assert_near(used, 0.25, 1e-7);
    assert_non_null(tb_image_get_attr(e, "compare.scale"));
    float lo[3], hi[3], mid[3];
    tb_compare_colormap(0.0, lo);
    tb_compare_colormap(1.0, hi);
    tb_compare_colormap(0.125 / sqrt(3.0) / 0.25, mid);
    assert_memory_equal(tb_image_at(e, 0, 0), lo, sizeof lo);
    assert_memory_equal(tb_image_at(e, 4, 2), hi, sizeof hi);
    for (int c = 0; c < 3; c++)
        tb_assert_near(tb_image_at(e, 1, 1)[c], mid[c], 1e-6);
    const float *m = tb_image_at(e, 6, 4);
    assert_true(m[0] == 1.0f && m[1] == 0.0f && m[2] == 1.0f);
    tb_image_free(e);

    /* a fixed scale of twice the error puts the worst pixel mid-map */
    assert_int_equal(tb_compare_error_image(a, b, NULL, 0.5, &e, &used), TB_OK);
    tb_assert_near(used, 0.5, 0);
    tb_compare_colormap(0.5, mid);
    assert_memory_equal(tb_image_at(e, 4, 2), mid, sizeof mid);
    tb_image_free(e);

    /* identical images: all zero error, scale falls back to 1 */
    assert_int_equal(tb_compare_error_image(b, b, NULL, 0, &e, &used), TB_OK);
    tb_assert_near(used, 1.0, 0);
    assert_memory_equal(tb_image_at(e, 3, 3), lo, sizeof lo);
    tb_image_free(e);
    tb_image_free(a);
    tb_image_free(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_constant_offset),
        cmocka_unit_test(test_identical),
        cmocka_unit_test(test_relmse_eps),
        cmocka_unit_test(test_max_location),
        cmocka_unit_test(test_nonfinite),
        cmocka_unit_test(test_channel_matching),
        cmocka_unit_test(test_ssim_matches_python),
        cmocka_unit_test(test_colormap),
        cmocka_unit_test(test_error_image),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
