/* util/color/bands: band weights reproduce the exact spectral integrals. */
#include "tb_test.h"

#include <string.h>

#include "util/color/bands.h"
#include "util/color/cie.h"
#include "util/color/smits.h"
#include "util/color/srgb.h"

static tb_bands tb__b; /* 11 KB: keep off the stack */

static void test_default_bands(void **state)
{
    (void)state;
    assert_int_equal(tb_bands_init_default(&tb__b), TB_OK);
    assert_int_equal(tb__b.n, 31);
    for (int i = 0; i < tb__b.n; i++)
        assert_true(tb__b.lambda[i] == 400.0 + 10.0 * i);
    /* Band values all 1 are the constant 1 over 400-700 nm. */
    const tb_spectrum *cmf[3] = {tb_cie_xbar(), tb_cie_ybar(), tb_cie_zbar()};
    double ones[TB_BANDS_MAX], xyz[3];
    for (int i = 0; i < tb__b.n; i++)
        ones[i] = 1.0;
    tb_bands_to_xyz(&tb__b, ones, xyz);
    for (int c = 0; c < 3; c++)
        tb_assert_near(xyz[c], tb_spectrum_integral(cmf[c], 400, 700), 1e-12);
}

/* For a spectrum sampled on the bands, bands -> XYZ is tb_emission_to_xyz exactly. */
static void test_bands_match_spectral_xyz(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("bands xyz", 41), 5);
    const double ranges[3][3] = {{400, 700, 31}, {380, 780, 81}, {360, 830, 20}};
    for (int r = 0; r < 3; r++) {
        assert_int_equal(tb_bands_init_range(&tb__b, ranges[r][0], ranges[r][1], (int)ranges[r][2]),
                         TB_OK);
        for (int trial = 0; trial < 10; trial++) {
            double v[TB_BANDS_MAX], back[TB_BANDS_MAX], a[3], b[3];
            for (int i = 0; i < tb__b.n; i++)
                v[i] = 10.0 * tb_rng_double(&rng);
            tb_spectrum s;
            assert_int_equal(tb_spectrum_init(&s, tb__b.n, tb__b.lambda, v), TB_OK);
            assert_int_equal(tb_bands_from_spectrum(&tb__b, &s, back), TB_OK);
            for (int i = 0; i < tb__b.n; i++)
                assert_true(back[i] == v[i]);
            tb_bands_to_xyz(&tb__b, v, a);
            assert_int_equal(tb_emission_to_xyz(&s, TB_EMISSION_RADIOMETRIC, b), TB_OK);
            for (int c = 0; c < 3; c++)
                tb_assert_near(a[c], b[c], 1e-12 * b[c]);
            tb_spectrum_release(&s);
        }
    }
}

/* D65 on its own 5-nm grid: the bands hold the table; the white is sRGB white. */
static void test_d65_bands(void **state)
{
    (void)state;
    const tb_spectrum *d65 = tb_illuminant_d65();
    assert_int_equal(tb_bands_init(&tb__b, d65->n, d65->lambda), TB_OK);
    double v[TB_BANDS_MAX], xyz[3], rgb[3];
    assert_int_equal(tb_bands_from_spectrum(&tb__b, d65, v), TB_OK);
    for (int i = 0; i < d65->n; i++)
        assert_true(v[i] == d65->value[i]);
    tb_bands_to_xyz(&tb__b, v, xyz);
    tb_bands_to_linear_srgb(&tb__b, v, 1.0 / xyz[1], rgb);
    for (int c = 0; c < 3; c++)
        tb_assert_near(rgb[c], 1.0, 1e-3);
}

/* Smits in bands is the Smits spectrum resampled onto the bands. */
static void test_rgb_reflectance_bands(void **state)
{
    (void)state;
    assert_int_equal(tb_bands_init_default(&tb__b), TB_OK);
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("bands smits", 42), 6);
    for (int trial = 0; trial < 50; trial++) {
        double rgb[3] = {tb_rng_double(&rng), tb_rng_double(&rng), tb_rng_double(&rng)};
        double a[TB_BANDS_MAX], b[TB_BANDS_MAX];
        tb_spectrum s;
        assert_int_equal(tb_smits_reflectance(rgb, &s), TB_OK);
        assert_int_equal(tb_bands_from_spectrum(&tb__b, &s, a), TB_OK);
        assert_int_equal(tb_bands_from_rgb_reflectance(&tb__b, rgb, b), TB_OK);
        for (int i = 0; i < tb__b.n; i++)
            tb_assert_near(a[i], b[i], 1e-13);
        tb_spectrum_release(&s);
    }
    const double bad[3] = {0, NAN, 0};
    double v[TB_BANDS_MAX];
    assert_int_equal(tb_bands_from_rgb_reflectance(&tb__b, bad, v), TB_ERR_ARG);
}

static void test_errors(void **state)
{
    (void)state;
    double l[TB_BANDS_MAX + 1];
    for (int i = 0; i <= TB_BANDS_MAX; i++)
        l[i] = 380 + i;
    tb_clear_error();
    assert_int_equal(tb_bands_init(&tb__b, TB_BANDS_MAX + 1, l), TB_ERR_ARG);
    assert_non_null(strstr(tb_last_error(), "at most"));
    l[5] = l[4];
    assert_int_equal(tb_bands_init(&tb__b, 10, l), TB_ERR_ARG);
    assert_non_null(strstr(tb_last_error(), "bands: spectrum: wavelength 5"));
    assert_int_equal(tb_bands_init_range(&tb__b, 700, 400, 31), TB_ERR_ARG);
    assert_int_equal(tb_bands_init_range(&tb__b, 400, 700, 1), TB_ERR_ARG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_default_bands),
        cmocka_unit_test(test_bands_match_spectral_xyz),
        cmocka_unit_test(test_d65_bands),
        cmocka_unit_test(test_rgb_reflectance_bands),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
