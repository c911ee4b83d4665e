/* util/color/cie: the compiled tables against their CSV files and against
 * published CIE values (sums, white points), normalisations, chromaticity. */
#include "tb_test.h"

#include <string.h>

#include "color_test_csv.h"
#include "util/color/cie.h"

static tb_test_csv tb__csv; /* big: keep off the stack */

/* The compiled CMF table is the CSV, number for number. */
static void test_cmf_table_equals_csv(void **state)
{
    (void)state;
    TB_TEST_READ_CSV("util/color/cie1931-2deg-5nm.csv", &tb__csv);
    assert_int_equal(tb__csv.cols, 4);
    const tb_spectrum *cmf[3] = {tb_cie_xbar(), tb_cie_ybar(), tb_cie_zbar()};
    for (int c = 0; c < 3; c++) {
        assert_int_equal(cmf[c]->n, tb__csv.rows);
        for (int i = 0; i < tb__csv.rows; i++) {
            assert_true(cmf[c]->lambda[i] == tb__csv.v[0][i]);
            assert_true(cmf[c]->value[i] == tb__csv.v[c + 1][i]);
        }
    }
    assert_int_equal(tb__csv.rows, 81); /* 380-780 nm at 5 nm */
    assert_true(tb__csv.v[0][0] == 380 && tb__csv.v[0][80] == 780);
}

static void test_d65_table_equals_csv(void **state)
{
    (void)state;
    TB_TEST_READ_CSV("util/color/cie-d65-5nm.csv", &tb__csv);
    const tb_spectrum *d65 = tb_illuminant_d65();
    assert_int_equal(d65->n, tb__csv.rows);
    assert_int_equal(tb__csv.rows, 107); /* 300-830 nm at 5 nm */
    for (int i = 0; i < tb__csv.rows; i++) {
        assert_true(d65->lambda[i] == tb__csv.v[0][i]);
        assert_true(d65->value[i] == tb__csv.v[1][i]);
        assert_true(tb__csv.v[0][i] == 300 + 5 * i);
    }
    /* The CIE normalisation: 100 at 560 nm. */
    assert_true(tb_spectrum_eval(d65, 560) == 100.0);
}

/* CIE 15 publishes the sums of the 5-nm table, 380-780 nm: ybar sums to
 * 21.371 (21.371327 to the table's digits). The three sums are equal to about
 * 1e-5 relative because the CMFs are scaled so that illuminant E has x = y = 1/3. */
static void test_published_sums(void **state)
{
    (void)state;
    TB_TEST_READ_CSV("util/color/cie1931-2deg-5nm.csv", &tb__csv);
    double sum[3] = {0, 0, 0};
    for (int i = 0; i < tb__csv.rows; i++)
        for (int c = 0; c < 3; c++)
            sum[c] += tb__csv.v[c + 1][i];
    tb_assert_near(sum[1], 21.371, 1e-3);
    tb_assert_near(sum[0], sum[1], 1e-3);
    tb_assert_near(sum[2], sum[1], 1e-3);

    /* The library's exact integral of the piecewise-linear ybar is the trapezoid
     * rule on the table: 5 * (sum - (first + last) / 2). */
    int last = tb__csv.rows - 1;
    double trap = 5.0 * (sum[1] - 0.5 * (tb__csv.v[2][0] + tb__csv.v[2][last]));
    tb_assert_near(tb_spectrum_integral(tb_cie_ybar(), 0, 1000), trap, 1e-11);
}

static void test_illuminant_e_is_white(void **state)
{
    (void)state;
    double xyz[3], xy[2];
    assert_int_equal(tb_illuminant_white_xyz(tb_illuminant_e(), 1.0, xyz), TB_OK);
    assert_true(xyz[1] == 1.0);
    assert_int_equal(tb_xyz_to_xy(xyz, xy), TB_OK);
    tb_assert_near(xy[0], 1.0 / 3.0, 1e-4);
    tb_assert_near(xy[1], 1.0 / 3.0, 1e-4);
}

/* CIE 15: the D65 white point of the 2-degree observer is (0.31272, 0.32903). */
static void test_d65_white_point(void **state)
{
    (void)state;
    double xyz[3], xy[2];
    assert_int_equal(tb_illuminant_white_xyz(tb_illuminant_d65(), 100.0, xyz), TB_OK);
    assert_int_equal(tb_xyz_to_xy(xyz, xy), TB_OK);
    print_message("[ measured ] D65 xy = (%.6f, %.6f), XYZ = (%.4f, %.4f, %.4f)\n", xy[0], xy[1],
                  xyz[0], xyz[1], xyz[2]);
    tb_assert_near(xy[0], 0.31272, 2e-4);
    tb_assert_near(xy[1], 0.32903, 2e-4);
    /* The widely published XYZ of D65 (Y = 100), from the 1 nm tables: 95.047,
     * 100, 108.883; the 5 nm tables integrated piecewise linearly give about 0.04 less Z. */
    tb_assert_near(xyz[0], 95.047, 0.05);
    tb_assert_near(xyz[2], 108.883, 0.05);
}

static void test_reflectance_normalisation(void **state)
{
    (void)state;
    tb_spectrum white, grey;
    assert_int_equal(tb_spectrum_init_constant(&white, 300, 830, 1.0), TB_OK);
    assert_int_equal(tb_spectrum_init_constant(&grey, 300, 830, 0.18), TB_OK);
    double w[3], g[3], d[3];
    assert_int_equal(tb_reflectance_to_xyz(&white, tb_illuminant_d65(), 1.0, w), TB_OK);
    tb_assert_near(w[1], 1.0, 1e-14);
    assert_int_equal(tb_illuminant_white_xyz(tb_illuminant_d65(), 1.0, d), TB_OK);
    for (int c = 0; c < 3; c++)
        tb_assert_near(w[c], d[c], 1e-14);
    assert_int_equal(tb_reflectance_to_xyz(&grey, tb_illuminant_d65(), 100.0, g), TB_OK);
    tb_assert_near(g[1], 18.0, 1e-12);
    for (int c = 0; c < 3; c++)
        tb_assert_near(g[c], 18.0 * w[c], 1e-12);

    tb_clear_error();
    assert_int_equal(tb_reflectance_to_xyz(&white, tb_illuminant_d65(), 0.0, w), TB_ERR_ARG);
    assert_non_null(strstr(tb_last_error(), "white Y"));
    /* An illuminant outside the CMF range has no luminance to normalise by. */
    tb_spectrum ir;
    assert_int_equal(tb_spectrum_init_constant(&ir, 800, 900, 1.0), TB_OK);
    assert_int_equal(tb_reflectance_to_xyz(&white, &ir, 1.0, w), TB_ERR_ARG);
    tb_spectrum_release(&ir);
    tb_spectrum_release(&grey);
    tb_spectrum_release(&white);
}

/* Emission: absolute scale. A flat 1 W/(sr m^2 nm) over 380-780 nm has
 * Y = int ybar (radiometric) and 683 times that in cd/m^2. */
static void test_emission_units(void **state)
{
    (void)state;
    tb_spectrum flat;
    assert_int_equal(tb_spectrum_init_constant(&flat, 380, 780, 1.0), TB_OK);
    double r[3], p[3];
    assert_int_equal(tb_emission_to_xyz(&flat, TB_EMISSION_RADIOMETRIC, r), TB_OK);
    assert_int_equal(tb_emission_to_xyz(&flat, TB_EMISSION_PHOTOMETRIC, p), TB_OK);
    tb_assert_near(r[1], tb_spectrum_integral(tb_cie_ybar(), 380, 780), 1e-12);
    tb_assert_near(r[1], 106.856, 2e-3); /* 5 * 21.371, less the half end samples */
    for (int c = 0; c < 3; c++)
        tb_assert_near(p[c], 683.0 * r[c], 1e-9);
    /* A monochromatic-ish line: a 1-nm triangle at 555 nm with area 1 W gives
     * about 683 lm (ybar(555) = 1.000 at the peak of V(lambda)). */
    const double ll[3] = {554.5, 555, 555.5}, lv[3] = {0, 2, 0};
    tb_spectrum line;
    assert_int_equal(tb_spectrum_init(&line, 3, ll, lv), TB_OK);
    assert_int_equal(tb_emission_to_xyz(&line, TB_EMISSION_PHOTOMETRIC, p), TB_OK);
    tb_assert_near(p[1], 683.0, 0.2); /* ybar bends by ~1e-3/nm around its peak */
    assert_int_equal(tb_emission_to_xyz(&line, (tb_emission_units)7, p), TB_ERR_ARG);
    tb_spectrum_release(&line);
    tb_spectrum_release(&flat);
}

static void test_chromaticity(void **state)
{
    (void)state;
    double xy[2], xyz[3];
    const double zero[3] = {0, 0, 0}, nan3[3] = {NAN, 1, 1};
    tb_clear_error();
    assert_int_equal(tb_xyz_to_xy(zero, xy), TB_ERR_ARG);
    assert_non_null(strstr(tb_last_error(), "no chromaticity"));
    assert_int_equal(tb_xyz_to_xy(nan3, xy), TB_ERR_ARG);
    const double in[2] = {0.25, 0.4};
    assert_int_equal(tb_xyY_to_xyz(in, 2.0, xyz), TB_OK);
    tb_assert_near(xyz[0], 1.25, 1e-15);
    tb_assert_near(xyz[1], 2.0, 1e-15);
    tb_assert_near(xyz[2], 1.75, 1e-15);
    assert_int_equal(tb_xyz_to_xy(xyz, xy), TB_OK);
    tb_assert_near(xy[0], 0.25, 1e-15);
    tb_assert_near(xy[1], 0.4, 1e-15);
    const double bad[2] = {0.3, 0.0};
    assert_int_equal(tb_xyY_to_xyz(bad, 1.0, xyz), TB_ERR_ARG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cmf_table_equals_csv),
        cmocka_unit_test(test_d65_table_equals_csv),
        cmocka_unit_test(test_published_sums),
        cmocka_unit_test(test_illuminant_e_is_white),
        cmocka_unit_test(test_d65_white_point),
        cmocka_unit_test(test_reflectance_normalisation),
        cmocka_unit_test(test_emission_units),
        cmocka_unit_test(test_chromaticity),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
