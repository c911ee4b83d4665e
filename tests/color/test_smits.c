/* util/color/smits: the basis against the published table (CSV), white, and the
 * RGB -> spectrum -> RGB round trip within the bounds stated in docs/color.md. */
#include "tb_test.h"

#include <string.h>

#include "color_test_csv.h"
#include "util/color/cie.h"
#include "util/color/smits.h"
#include "util/color/srgb.h"
#include "util/math/mat.h"

/* Round-trip bounds documented in docs/color.md (max abs error per channel). */
#define TB__BOUND_E 0.01   /* Smits' own setting: illuminant E, sRGB primaries, E white */
#define TB__BOUND_D65 0.05 /* the renderer's: lit by D65, shown as sRGB */

static tb_test_csv tb__csv;

static void test_basis_equals_published_table(void **state)
{
    (void)state;
    TB_TEST_READ_CSV("util/color/smits1999-basis.csv", &tb__csv);
    assert_int_equal(tb__csv.rows, 10);
    assert_int_equal(tb__csv.cols, 2 + TB_SMITS_BASIS_COUNT);
    const char *names[TB_SMITS_BASIS_COUNT] = {"white", "cyan", "magenta", "yellow",
                                               "red",   "green", "blue"};
    for (int k = 0; k < TB_SMITS_BASIS_COUNT; k++) {
        assert_string_equal(tb__csv.names[2 + k], names[k]);
        const tb_spectrum *s = tb_smits_basis_spectrum((tb_smits_basis)k);
        assert_non_null(s);
        for (int i = 0; i < 10; i++) {
            double lo = tb__csv.v[0][i], hi = tb__csv.v[1][i], want = tb__csv.v[2 + k][i];
            tb_assert_near(hi - lo, 34.0, 0); /* 10 equal bins, 380-720 nm */
            /* Flat over the bin away from the 1-nm ramps at its edges. */
            for (double l = lo + 0.5; l <= hi - 0.5; l += 1.0)
                tb_assert_near(tb_spectrum_eval(s, l), want, 1e-15);
            /* The ramps keep each bin's area. */
            tb_assert_near(tb_spectrum_integral(s, lo, hi),
                           34.0 * want +
                               (i > 0 ? 0.125 * (tb__csv.v[2 + k][i - 1] - want) : 0.0) +
                               (i < 9 ? 0.125 * (tb__csv.v[2 + k][i + 1] - want) : 0.0),
                           1e-12);
        }
    }
    assert_null(tb_smits_basis_spectrum(TB_SMITS_BASIS_COUNT));
}

/* RGB white is the white basis: 1 within 1e-3 everywhere 360-830 nm. */
static void test_white_is_flat(void **state)
{
    (void)state;
    const double one[3] = {1, 1, 1};
    tb_spectrum s;
    assert_int_equal(tb_smits_reflectance(one, &s), TB_OK);
    assert_true(s.lambda[0] == 360.0 && s.lambda[s.n - 1] == 830.0);
    for (double l = 360; l <= 830; l += 0.25)
        tb_assert_near(tb_spectrum_eval(&s, l), 1.0, 1e-3);
    tb_spectrum_release(&s);
    /* Grey scales it. */
    const double grey[3] = {0.25, 0.25, 0.25};
    assert_int_equal(tb_smits_reflectance(grey, &s), TB_OK);
    for (double l = 360; l <= 830; l += 5)
        tb_assert_near(tb_spectrum_eval(&s, l), 0.25, 0.25e-3);
    tb_spectrum_release(&s);
}

/* RGB -> reflectance -> XYZ under `ill` (white Y = 1) -> RGB by `xyz_to_rgb`. */
static void tb__round_trip(const double rgb[3], const tb_spectrum *ill, const double m[3][3],
                           double out[3])
{
    tb_spectrum s;
    double xyz[3];
    assert_int_equal(tb_smits_reflectance(rgb, &s), TB_OK);
    assert_int_equal(tb_reflectance_to_xyz(&s, ill, 1.0, xyz), TB_OK);
    for (int r = 0; r < 3; r++)
        out[r] = m[r][0] * xyz[0] + m[r][1] * xyz[1] + m[r][2] * xyz[2];
    tb_spectrum_release(&s);
}

/* Max error over the primaries, secondaries, greys and `n` random in-gamut colours. */
static void tb__measure(const char *what, const tb_spectrum *ill, const double m[3][3], int n,
                        double *max_named, double *max_random)
{
    static const double named[][3] = {{1, 1, 1}, {0.5, 0.5, 0.5}, {0, 0, 0}, {1, 0, 0},
                                      {0, 1, 0}, {0, 0, 1},       {0, 1, 1}, {1, 0, 1},
                                      {1, 1, 0}, {0.8, 0.2, 0.1}};
    double out[3];
    *max_named = *max_random = 0.0;
    for (size_t i = 0; i < sizeof named / sizeof named[0]; i++) {
        tb__round_trip(named[i], ill, m, out);
        for (int c = 0; c < 3; c++)
            *max_named = fmax(*max_named, fabs(out[c] - named[i][c]));
    }
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed(what, 31), 4);
    for (int i = 0; i < n; i++) {
        double rgb[3] = {tb_rng_double(&rng), tb_rng_double(&rng), tb_rng_double(&rng)};
        tb__round_trip(rgb, ill, m, out);
        for (int c = 0; c < 3; c++)
            *max_random = fmax(*max_random, fabs(out[c] - rgb[c]));
    }
    print_message("[ measured ] %s: max |error| named colours %.4f, %d random %.4f\n", what,
                  *max_named, n, *max_random);
}

static void test_round_trip_equal_energy(void **state)
{
    (void)state;
    /* Smits' RGB space: sRGB primaries with an equal-energy white. */
    const double prim[3][2] = {{0.64, 0.33}, {0.30, 0.60}, {0.15, 0.06}};
    const double e_xy[2] = {1.0 / 3.0, 1.0 / 3.0};
    double named, random;
    tb_mat3 m, inv;
    assert_int_equal(tb_rgb_to_xyz_matrix(prim, e_xy, m.m), TB_OK);
    assert_int_equal(tb_mat3_inverse(&m, &inv), TB_OK);
    tb__measure("Smits round trip, illuminant E", tb_illuminant_e(), inv.m, 500, &named, &random);
    assert_true(named <= TB__BOUND_E);
    assert_true(random <= TB__BOUND_E);
    /* White comes back white. */
    const double one[3] = {1, 1, 1};
    double out[3];
    tb__round_trip(one, tb_illuminant_e(), inv.m, out);
    for (int c = 0; c < 3; c++)
        tb_assert_near(out[c], 1.0, 1e-3);
}

static void test_round_trip_d65_srgb(void **state)
{
    (void)state;
    double named, random;
    tb__measure("Smits round trip, D65 + sRGB", tb_illuminant_d65(), tb_xyz_to_srgb_matrix, 500,
                &named, &random);
    assert_true(named <= TB__BOUND_D65);
    assert_true(random <= TB__BOUND_D65);
    const double one[3] = {1, 1, 1};
    double out[3];
    tb__round_trip(one, tb_illuminant_d65(), tb_xyz_to_srgb_matrix, out);
    for (int c = 0; c < 3; c++)
        tb_assert_near(out[c], 1.0, 1e-3);
    /* The error is systematic, not noise: D65 is not the white Smits fitted for. */
    assert_true(named > TB__BOUND_E);
}

/* Emission = reflectance x illuminant / int illuminant ybar. */
static void test_emission(void **state)
{
    (void)state;
    const double one[3] = {1, 1, 1};
    tb_spectrum e;
    double xyz[3], rgb[3];
    assert_int_equal(tb_smits_emission(one, tb_illuminant_d65(), &e), TB_OK);
    assert_int_equal(tb_emission_to_xyz(&e, TB_EMISSION_RADIOMETRIC, xyz), TB_OK);
    tb_xyz_to_linear_srgb(xyz, rgb);
    tb_assert_near(xyz[1], 1.0, 1e-3);
    for (int c = 0; c < 3; c++)
        tb_assert_near(rgb[c], 1.0, 2e-3);
    tb_spectrum_release(&e);

    /* Linear in scale (a light of RGB (17, 12, 4)) and equal, up to the sampling
     * of the product, to the reflectance lit by the same illuminant. */
    const double light[3] = {17, 12, 4}, unit[3] = {17.0 / 17, 12.0 / 17, 4.0 / 17};
    double xyz_refl[3];
    tb_spectrum r;
    assert_int_equal(tb_smits_emission(light, tb_illuminant_e(), &e), TB_OK);
    assert_int_equal(tb_emission_to_xyz(&e, TB_EMISSION_RADIOMETRIC, xyz), TB_OK);
    assert_int_equal(tb_smits_reflectance(unit, &r), TB_OK);
    assert_int_equal(tb_reflectance_to_xyz(&r, tb_illuminant_e(), 17.0, xyz_refl), TB_OK);
    for (int c = 0; c < 3; c++)
        tb_assert_near(xyz[c], xyz_refl[c], 1e-4 * xyz_refl[c]);
    tb_spectrum_release(&r);
    tb_spectrum_release(&e);
}

static void test_errors(void **state)
{
    (void)state;
    tb_spectrum s;
    const double neg[3] = {0.5, -0.1, 0.2}, nan3[3] = {0.5, NAN, 0.2}, inf3[3] = {INFINITY, 0, 0};
    tb_clear_error();
    assert_int_equal(tb_smits_reflectance(neg, &s), TB_ERR_ARG);
    assert_non_null(strstr(tb_last_error(), ">= 0"));
    assert_null(s.lambda);
    assert_int_equal(tb_smits_reflectance(nan3, &s), TB_ERR_ARG);
    assert_int_equal(tb_smits_reflectance(inf3, &s), TB_ERR_ARG);
    const double ok[3] = {0.1, 0.2, 0.3};
    assert_int_equal(tb_smits_emission(ok, NULL, &s), TB_ERR_ARG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_basis_equals_published_table),
        cmocka_unit_test(test_white_is_flat),
        cmocka_unit_test(test_round_trip_equal_energy),
        cmocka_unit_test(test_round_trip_d65_srgb),
        cmocka_unit_test(test_emission),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
