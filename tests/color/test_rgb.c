/* util/color/srgb: the linear sRGB <-> XYZ matrices against IEC 61966-2-1,
 * their inverse relation, the D65 white, and the general primaries matrix. */
#include "tb_test.h"

#include <string.h>

#include "util/color/cie.h"
#include "util/color/srgb.h"
#include "util/math/mat.h"

/* IEC 61966-2-1 primaries (ITU-R BT.709) and D65 white, as chromaticities. */
static const double tb__prim[3][2] = {{0.64, 0.33}, {0.30, 0.60}, {0.15, 0.06}};
static const double tb__d65_xy[2] = {0.3127, 0.3290};

/* The standard's printed 4-digit matrices. */
static const double tb__iec_rgb_to_xyz[3][3] = {
    {0.4124, 0.3576, 0.1805}, {0.2126, 0.7152, 0.0722}, {0.0193, 0.1192, 0.9505}};
static const double tb__iec_xyz_to_rgb[3][3] = {
    {3.2406, -1.5372, -0.4986}, {-0.9689, 1.8758, 0.0415}, {0.0557, -0.2040, 1.0570}};

static void test_matrices_match_the_standard(void **state)
{
    (void)state;
    double m[3][3], inv[3][3];
    assert_int_equal(tb_rgb_to_xyz_matrix(tb__prim, tb__d65_xy, m), TB_OK);
    tb_mat3 fwd, bwd;
    memcpy(fwd.m, m, sizeof fwd.m);
    assert_int_equal(tb_mat3_inverse(&fwd, &bwd), TB_OK);
    memcpy(inv, bwd.m, sizeof inv);
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            /* The compiled constants are this derivation. */
            tb_assert_near(tb_srgb_to_xyz_matrix[r][c], m[r][c], 1e-15);
            tb_assert_near(tb_xyz_to_srgb_matrix[r][c], inv[r][c], 1e-14);
            /* The forward matrix rounds to the printed one. */
            tb_assert_near(tb_srgb_to_xyz_matrix[r][c], tb__iec_rgb_to_xyz[r][c], 0.5e-4 + 1e-12);
            /* The printed inverse is that of the rounded forward matrix: close, not equal. */
            tb_assert_near(tb_xyz_to_srgb_matrix[r][c], tb__iec_xyz_to_rgb[r][c], 4e-4);
        }
}

static void test_matrices_are_inverses(void **state)
{
    (void)state;
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            double a = 0.0, b = 0.0;
            for (int k = 0; k < 3; k++) {
                a += tb_srgb_to_xyz_matrix[r][k] * tb_xyz_to_srgb_matrix[k][c];
                b += tb_xyz_to_srgb_matrix[r][k] * tb_srgb_to_xyz_matrix[k][c];
            }
            tb_assert_near(a, r == c ? 1.0 : 0.0, 1e-14);
            tb_assert_near(b, r == c ? 1.0 : 0.0, 1e-14);
        }
    /* RGB white is the D65 chromaticity with Y = 1; luminance weights sum to 1. */
    const double one[3] = {1, 1, 1};
    double xyz[3], xy[2];
    tb_linear_srgb_to_xyz(one, xyz);
    tb_assert_near(xyz[1], 1.0, 1e-15);
    assert_int_equal(tb_xyz_to_xy(xyz, xy), TB_OK);
    tb_assert_near(xy[0], 0.3127, 1e-15);
    tb_assert_near(xy[1], 0.3290, 1e-15);
    tb_assert_near(tb_linear_srgb_luminance(one), 1.0, 1e-15);
    const double red[3] = {1, 0, 0};
    tb_linear_srgb_to_xyz(red, xyz);
    assert_int_equal(tb_xyz_to_xy(xyz, xy), TB_OK);
    tb_assert_near(xy[0], 0.64, 1e-15);
    tb_assert_near(xy[1], 0.33, 1e-15);
}

static void test_round_trip(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("srgb round trip", 21), 3);
    for (int i = 0; i < 1000; i++) {
        double xyz[3], rgb[3], back[3];
        for (int c = 0; c < 3; c++)
            xyz[c] = 2.0 * tb_rng_double(&rng);
        tb_xyz_to_linear_srgb(xyz, rgb);
        tb_linear_srgb_to_xyz(rgb, back);
        for (int c = 0; c < 3; c++)
            tb_assert_near(back[c], xyz[c], 1e-14);
        /* In place. */
        memcpy(back, xyz, sizeof back);
        tb_xyz_to_linear_srgb(back, back);
        for (int c = 0; c < 3; c++)
            assert_true(back[c] == rgb[c]);
    }
}

/* The D65 spectrum, normalised to Y = 1, is sRGB white. */
static void test_d65_spectrum_is_srgb_white(void **state)
{
    (void)state;
    double xyz[3], rgb[3];
    assert_int_equal(tb_illuminant_white_xyz(tb_illuminant_d65(), 1.0, xyz), TB_OK);
    tb_xyz_to_linear_srgb(xyz, rgb);
    print_message("[ measured ] D65 spectrum -> linear sRGB (%.6f, %.6f, %.6f)\n", rgb[0], rgb[1],
                  rgb[2]);
    for (int c = 0; c < 3; c++)
        tb_assert_near(rgb[c], 1.0, 1e-3);
}

static void test_matrix_errors(void **state)
{
    (void)state;
    double m[3][3];
    const double collinear[3][2] = {{0.2, 0.2}, {0.3, 0.3}, {0.4, 0.4}};
    const double flat[3][2] = {{0.64, 0.33}, {0.30, 0.0}, {0.15, 0.06}};
    tb_clear_error();
    assert_int_equal(tb_rgb_to_xyz_matrix(collinear, tb__d65_xy, m), TB_ERR_ARG);
    assert_non_null(strstr(tb_last_error(), "collinear"));
    assert_int_equal(tb_rgb_to_xyz_matrix(flat, tb__d65_xy, m), TB_ERR_ARG);
    const double white_nan[2] = {NAN, 0.33};
    assert_int_equal(tb_rgb_to_xyz_matrix(tb__prim, white_nan, m), TB_ERR_ARG);
}

/* The transfer curve is unchanged: the standard's break points. */
static void test_transfer_curve(void **state)
{
    (void)state;
    tb_assert_near(tb_srgb_encode(0.0031308f), 0.04045f, 1e-6);
    tb_assert_near(tb_srgb_encode(0.5f), 0.735356983, 1e-6);
    tb_assert_near(tb_srgb_decode(0.5f), 0.214041144, 1e-6);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_matrices_match_the_standard),
        cmocka_unit_test(test_matrices_are_inverses),
        cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_d65_spectrum_is_srgb_white),
        cmocka_unit_test(test_matrix_errors),
        cmocka_unit_test(test_transfer_curve),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
