/* The Cornell Box wall reflectances (tests/color/data/, as published by the
 * Cornell Program of Computer Graphics) lit by D65: plausible colours, and the
 * same numbers as an independent computation, tests/color/cornell_reference.py
 * (plain python3: its own interpolation, a 0.001-nm midpoint rule and its own
 * sRGB matrix from the IEC primaries; run it to regenerate the values below). */
#include "tb_test.h"

#include "color_test_csv.h"
#include "util/color/bands.h"
#include "util/color/cie.h"
#include "util/color/srgb.h"

/* Output of tests/color/cornell_reference.py: XYZ (white Y = 1), linear sRGB. */
static const struct {
    const char *name;
    double xyz[3], rgb[3];
} tb__reference[3] = {
    {"white", {0.699833110, 0.736360486, 0.802441696}, {0.735963784, 0.736425065, 0.736889214}},
    {"green", {0.186173536, 0.305551023, 0.130882936}, {0.068374192, 0.398195121, 0.086371015}},
    {"red", {0.229697388, 0.143531547, 0.063829350}, {0.491953344, 0.049280219, 0.050966760}},
};

static tb_test_csv tb__csv;
static tb_bands tb__b;

static void tb__wall(int k, tb_spectrum *s)
{
    TB_TEST_READ_CSV("tests/color/data/cornell-box-reflectance.csv", &tb__csv);
    assert_string_equal(tb__csv.names[k + 1], tb__reference[k].name);
    assert_int_equal(tb_spectrum_init(s, tb__csv.rows, tb__csv.v[0], tb__csv.v[k + 1]), TB_OK);
}

static void test_matches_independent_reference(void **state)
{
    (void)state;
    for (int k = 0; k < 3; k++) {
        tb_spectrum s;
        double xyz[3], rgb[3];
        tb__wall(k, &s);
        assert_int_equal(tb_reflectance_to_xyz(&s, tb_illuminant_d65(), 1.0, xyz), TB_OK);
        tb_xyz_to_linear_srgb(xyz, rgb);
        print_message("[ measured ] %-5s linear sRGB (%.6f, %.6f, %.6f), sRGB 8-bit (%d, %d, %d)\n",
                      tb__reference[k].name, rgb[0], rgb[1], rgb[2],
                      (int)lrintf(255 * tb_srgb_encode((float)rgb[0])),
                      (int)lrintf(255 * tb_srgb_encode((float)rgb[1])),
                      (int)lrintf(255 * tb_srgb_encode((float)rgb[2])));
        for (int c = 0; c < 3; c++) {
            tb_assert_near(xyz[c], tb__reference[k].xyz[c], 1e-6);
            tb_assert_near(rgb[c], tb__reference[k].rgb[c], 1e-6);
        }
        tb_spectrum_release(&s);
    }
}

static void test_plausible_colours(void **state)
{
    (void)state;
    double rgb[3][3];
    for (int k = 0; k < 3; k++) {
        tb_spectrum s;
        double xyz[3];
        tb__wall(k, &s);
        assert_int_equal(tb_reflectance_to_xyz(&s, tb_illuminant_d65(), 1.0, xyz), TB_OK);
        tb_xyz_to_linear_srgb(xyz, rgb[k]);
        for (int c = 0; c < 3; c++) /* real surfaces: inside the sRGB gamut, below white */
            assert_true(rgb[k][c] > 0.0 && rgb[k][c] < 1.0);
        tb_spectrum_release(&s);
    }
    /* White is a neutral light grey (about 0.74 reflectance). */
    assert_true(fabs(rgb[0][0] - rgb[0][2]) < 0.01 && fabs(rgb[0][1] - rgb[0][2]) < 0.01);
    assert_true(rgb[0][1] > 0.7 && rgb[0][1] < 0.8);
    /* Green is green, red is red, each clearly dominated by its channel. */
    assert_true(rgb[1][1] > 4 * rgb[1][0] && rgb[1][1] > 4 * rgb[1][2]);
    assert_true(rgb[2][0] > 8 * rgb[2][1] && rgb[2][0] > 8 * rgb[2][2]);
}

/* A renderer working in the default bands (400-700 nm at 10 nm) gets the same
 * colours within 5e-3: the bands average the 4-nm data and D65 before
 * multiplying them (docs/color.md gives the measured errors). */
static void test_default_bands_agree(void **state)
{
    (void)state;
    assert_int_equal(tb_bands_init_default(&tb__b), TB_OK);
    double light[TB_BANDS_MAX], white[3];
    assert_int_equal(tb_bands_from_spectrum(&tb__b, tb_illuminant_d65(), light), TB_OK);
    tb_bands_to_xyz(&tb__b, light, white);
    for (int k = 0; k < 3; k++) {
        tb_spectrum s;
        double refl[TB_BANDS_MAX], lit[TB_BANDS_MAX], rgb[3], worst = 0.0;
        tb__wall(k, &s);
        assert_int_equal(tb_bands_from_spectrum(&tb__b, &s, refl), TB_OK);
        for (int i = 0; i < tb__b.n; i++)
            lit[i] = refl[i] * light[i];
        /* Normalised by the light's Y in the same bands, as a renderer would. */
        tb_bands_to_linear_srgb(&tb__b, lit, 1.0 / white[1], rgb);
        for (int c = 0; c < 3; c++)
            worst = fmax(worst, fabs(rgb[c] - tb__reference[k].rgb[c]));
        print_message("[ measured ] %-5s in 31 bands: max |linear sRGB error| %.5f\n",
                      tb__reference[k].name, worst);
        assert_true(worst < 5e-3);
        tb_spectrum_release(&s);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_matches_independent_reference),
        cmocka_unit_test(test_plausible_colours),
        cmocka_unit_test(test_default_bands_agree),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
