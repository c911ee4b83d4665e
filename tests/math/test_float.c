/* util/math/float.h: next_float, gamma, ulp distance, bit casts, clamps,
 * safe square roots, difference of products, constants. Expected values are
 * written as hex float literals worked out by hand from the IEEE formats. */
#include "tb_test.h"

#include <float.h>
#include <math.h>
#include <stdint.h>

#include "util/math/float.h"

/* Bitwise equality: tells -0 from +0. */
#define assert_float_bits(a, b) assert_int_equal(tb_float_to_bits(a), tb_float_to_bits(b))
#define assert_double_bits(a, b) assert_int_equal(tb_double_to_bits(a), tb_double_to_bits(b))

static void test_next_float_up_down(void **state)
{
    (void)state;
    const float den = 0x1p-149f;             /* smallest positive denormal */
    const float max_den = 0x1.fffffcp-127f;  /* largest denormal */
    /* Zeros of both signs step to the smallest denormal of the step's sign. */
    assert_float_bits(tb_next_float_up(0.0f), den);
    assert_float_bits(tb_next_float_up(-0.0f), den);
    assert_float_bits(tb_next_float_down(0.0f), -den);
    assert_float_bits(tb_next_float_down(-0.0f), -den);
    /* Toward zero from the smallest denormals lands on the zero of that sign. */
    assert_float_bits(tb_next_float_down(den), 0.0f);
    assert_float_bits(tb_next_float_up(-den), -0.0f);
    assert_float_bits(tb_next_float_up(den), 2 * den);
    assert_float_bits(tb_next_float_down(-den), -2 * den);
    /* Across the denormal / normal boundary. */
    assert_float_bits(tb_next_float_up(max_den), FLT_MIN);
    assert_float_bits(tb_next_float_down(FLT_MIN), max_den);
    assert_float_bits(tb_next_float_down(-max_den), -FLT_MIN);
    /* Around 1 the spacing is 2^-23 above and 2^-24 below. */
    assert_float_bits(tb_next_float_up(1.0f), 1.0f + 0x1p-23f);
    assert_float_bits(tb_next_float_down(1.0f), 1.0f - 0x1p-24f);
    assert_float_bits(tb_next_float_up(-1.0f), -1.0f + 0x1p-24f);
    assert_float_bits(tb_next_float_down(-1.0f), -1.0f - 0x1p-23f);
    /* Top of the range and infinities. */
    assert_float_bits(tb_next_float_up(FLT_MAX), INFINITY);
    assert_float_bits(tb_next_float_down(INFINITY), FLT_MAX);
    assert_float_bits(tb_next_float_up(INFINITY), INFINITY);
    assert_float_bits(tb_next_float_down(-INFINITY), -INFINITY);
    assert_float_bits(tb_next_float_up(-INFINITY), -FLT_MAX);
    assert_float_bits(tb_next_float_down(-FLT_MAX), -INFINITY);
    assert_float_bits(tb_next_float_down(FLT_MAX), 0x1.fffffcp127f);
    /* NaN stays NaN. */
    assert_true(isnan(tb_next_float_up(NAN)));
    assert_true(isnan(tb_next_float_down(NAN)));
}

/* Directed rounding from double: exact values stay, others go to the float
 * neighbour on the asked side, beyond the float range to +-FLT_MAX or +-inf. */
static void test_float_round_down_up(void **state)
{
    (void)state;
    assert_float_bits(tb_float_round_down(1.0), 1.0f);
    assert_float_bits(tb_float_round_up(1.0), 1.0f);
    assert_float_bits(tb_float_round_down(-0.0), -0.0f);
    assert_float_bits(tb_float_round_up(0.0), 0.0f);
    /* 1 + 2^-30 lies between 1 and 1 + 2^-23; (float) rounds it to 1. */
    assert_float_bits(tb_float_round_down(1.0 + 0x1p-30), 1.0f);
    assert_float_bits(tb_float_round_up(1.0 + 0x1p-30), 1.0f + 0x1p-23f);
    assert_float_bits(tb_float_round_down(-1.0 - 0x1p-30), -1.0f - 0x1p-23f);
    assert_float_bits(tb_float_round_up(-1.0 - 0x1p-30), -1.0f);
    /* 1 - 2^-26 rounds to 1 by (float): down must step below. */
    assert_float_bits(tb_float_round_down(1.0 - 0x1p-26), 1.0f - 0x1p-24f);
    assert_float_bits(tb_float_round_up(1.0 - 0x1p-26), 1.0f);
    /* Below the smallest denormal. */
    assert_float_bits(tb_float_round_down(0x1p-160), 0.0f);
    assert_float_bits(tb_float_round_up(0x1p-160), 0x1p-149f);
    assert_float_bits(tb_float_round_down(-0x1p-160), -0x1p-149f);
    /* Beyond the float range. */
    assert_float_bits(tb_float_round_down(1e39), FLT_MAX);
    assert_float_bits(tb_float_round_up(1e39), INFINITY);
    assert_float_bits(tb_float_round_down(-1e39), -INFINITY);
    assert_float_bits(tb_float_round_up(-1e39), -FLT_MAX);
    assert_float_bits(tb_float_round_up(INFINITY), INFINITY);
    assert_true(isnan(tb_float_round_down(NAN)) && isnan(tb_float_round_up(NAN)));
    assert_float_bits(tb_float_round_up(0x1.fffffep127 + 0x1p100), INFINITY); /* FLT_MAX steps to +inf */
    assert_float_bits(tb_float_round_down(-0x1.fffffep127 - 0x1p100), -INFINITY);
    assert_float_bits(tb_float_round_up(-0x1p-160), -0.0f);
    /* The defining property on 10^5 doubles of every sign and exponent that
     * floats reach (and beyond): r = round_up(v) >= v > the float below r
     * (likewise down), which the bit-step fast paths must keep. */
    uint64_t x = 0x9e3779b97f4a7c15ull;
    for (int i = 0; i < 100000; i++) {
        x = x * 6364136223846793005ull + 1442695040888963407ull;
        int e = (int)((x >> 11) % 320) - 170; /* 2^-170 .. 2^149 */
        double v = ldexp(1.0 + (double)(x >> 12) * 0x1p-52, e) * ((x >> 63) ? -1.0 : 1.0);
        float up = tb_float_round_up(v), dn = tb_float_round_down(v);
        if (!((double)up >= v && (double)tb_next_float_down(up) < v))
            fail_msg("round_up(%a) = %a", v, (double)up);
        if (!((double)dn <= v && (double)tb_next_float_up(dn) > v))
            fail_msg("round_down(%a) = %a", v, (double)dn);
    }
}

static void test_next_double_up_down(void **state)
{
    (void)state;
    const double den = 0x1p-1074;
    assert_double_bits(tb_next_double_up(0.0), den);
    assert_double_bits(tb_next_double_up(-0.0), den);
    assert_double_bits(tb_next_double_down(0.0), -den);
    assert_double_bits(tb_next_double_down(-0.0), -den);
    assert_double_bits(tb_next_double_down(den), 0.0);
    assert_double_bits(tb_next_double_up(-den), -0.0);
    assert_double_bits(tb_next_double_up(0x1.ffffffffffffep-1023), DBL_MIN);
    assert_double_bits(tb_next_double_up(1.0), 1.0 + 0x1p-52);
    assert_double_bits(tb_next_double_down(1.0), 1.0 - 0x1p-53);
    assert_double_bits(tb_next_double_up(DBL_MAX), INFINITY);
    assert_double_bits(tb_next_double_down(INFINITY), DBL_MAX);
    assert_double_bits(tb_next_double_up(INFINITY), INFINITY);
    assert_double_bits(tb_next_double_up(-INFINITY), -DBL_MAX);
    assert_double_bits(tb_next_double_down(-INFINITY), -INFINITY);
    assert_true(isnan(tb_next_double_up(NAN)));
    /* Agrees with C's nextafter away from the special cases it treats alike. */
    const double v[] = {1e-300, -3.5, 7e200, 0x1p-1060, -0x1p-1070};
    for (size_t i = 0; i < sizeof v / sizeof v[0]; ++i) {
        assert_double_bits(tb_next_double_up(v[i]), nextafter(v[i], INFINITY));
        assert_double_bits(tb_next_double_down(v[i]), nextafter(v[i], -INFINITY));
    }
}

static void test_gamma(void **state)
{
    (void)state;
    /* n u / (1 - n u), u = 2^-24, evaluated here in double (exact to ~1e-16). */
    for (int n = 1; n <= 10; ++n) {
        double u = 0x1p-24, want = n * u / (1.0 - n * u);
        tb_assert_near(tb_gamma(n), want, want * 0x1p-23);
    }
    /* gamma(3) = 3 * 2^-24 / (1 - 3 * 2^-24) = 1.78813981e-07. */
    tb_assert_near(tb_gamma(3), 1.7881398e-07, 1e-13);
    /* The property it exists for: (1 + u)^n <= 1 + gamma(n), (1 - u)^n >= 1 - gamma(n). */
    for (int n = 1; n <= 8; ++n) {
        double up = 1.0, dn = 1.0;
        for (int i = 0; i < n; ++i) {
            up *= 1.0 + 0x1p-24;
            dn *= 1.0 - 0x1p-24;
        }
        assert_true(up <= 1.0 + (double)tb_gamma(n));
        assert_true(dn >= 1.0 - (double)tb_gamma(n));
    }
    double du = 0x1p-53;
    tb_assert_near(tb_dgamma(2), 2 * du / (1 - 2 * du), 1e-30);
}

static void test_ulp_distance_and_bits(void **state)
{
    (void)state;
    assert_int_equal(tb_float_to_bits(1.0f), 0x3f800000u);
    assert_int_equal(tb_float_to_bits(-0.0f), 0x80000000u);
    assert_int_equal(tb_float_to_bits(-2.0f), 0xc0000000u);
    assert_true(tb_bits_to_float(0x7f800000u) == INFINITY);
    assert_true(tb_bits_to_float(0x00000001u) == 0x1p-149f);
    assert_int_equal(tb_double_to_bits(1.0), 0x3ff0000000000000ull);
    assert_true(tb_bits_to_double(0xbff8000000000000ull) == -1.5);

    assert_int_equal(tb_ulp_distance(1.0f, 1.0f), 0);
    assert_int_equal(tb_ulp_distance(0.0f, -0.0f), 0);
    assert_int_equal(tb_ulp_distance(1.0f, 1.0f + 0x1p-23f), 1);
    assert_int_equal(tb_ulp_distance(1.0f + 0x1p-23f, 1.0f), 1);
    assert_int_equal(tb_ulp_distance(1.0f, 2.0f), 1u << 23);
    assert_int_equal(tb_ulp_distance(-0x1p-149f, 0x1p-149f), 2);
    assert_int_equal(tb_ulp_distance(FLT_MAX, INFINITY), 1);
    assert_int_equal(tb_ulp_distance(-1.0f, 1.0f), 2u * 0x3f800000u);
    assert_int_equal(tb_ulp_distance(-INFINITY, INFINITY), 2u * 0x7f800000u);
    assert_int_equal(tb_ulp_distance(NAN, 1.0f), UINT32_MAX);
    assert_int_equal(tb_ulp_distance(1.0f, NAN), UINT32_MAX);
}

static void test_clamp_sqrt_finite(void **state)
{
    (void)state;
    assert_true(tb_clampf(2.0f, 0.0f, 1.0f) == 1.0f);
    assert_true(tb_clampf(-2.0f, 0.0f, 1.0f) == 0.0f);
    assert_true(tb_clampf(0.25f, 0.0f, 1.0f) == 0.25f);
    assert_true(tb_clampf(NAN, 0.0f, 1.0f) == 0.0f);
    assert_true(tb_clamp(5.0, -1.0, 3.0) == 3.0);
    assert_true(tb_clamp(NAN, -1.0, 3.0) == -1.0);

    assert_true(tb_safe_sqrtf(-1e-9f) == 0.0f);
    assert_true(tb_safe_sqrtf(4.0f) == 2.0f);
    assert_true(isnan(tb_safe_sqrtf(NAN)));
    assert_true(tb_safe_sqrt(-1e-300) == 0.0);
    assert_true(tb_safe_sqrt(9.0) == 3.0);
    assert_true(isnan(tb_safe_sqrt(NAN)));
    assert_true(tb_safe_acos(1.0 + 1e-12) == 0.0);
    tb_assert_near(tb_safe_asin(-1.5), -TB_PI_2, 0.0);

    assert_true(tb_isfinite3((tb_vec3){1, -2, 1e38f}));
    assert_false(tb_isfinite3((tb_vec3){1, NAN, 0}));
    assert_false(tb_isfinite3((tb_vec3){1, 0, -INFINITY}));

    tb_assert_near(tb_radians(180.0), TB_PI, 0.0);
    tb_assert_near(tb_degrees(TB_PI_2), 90.0, 1e-13);
}

static void test_constants(void **state)
{
    (void)state;
    /* glibc's acos(-1) and atan are correctly rounded at these points. */
    assert_true(TB_PI == acos(-1.0));
    assert_true(TB_PI_2 == 2.0 * atan(1.0));
    assert_true(TB_PI_4 == atan(1.0));
    assert_true(TB_2PI == 2.0 * acos(-1.0));
    assert_true(TB_PIF == (float)acos(-1.0));
    tb_assert_near(TB_INV_PI, 1.0 / acos(-1.0), 1e-17);
    tb_assert_near(TB_INV_2PI, 0.5 / acos(-1.0), 1e-17);
    tb_assert_near(TB_INV_4PI, 0.25 / acos(-1.0), 1e-17);
    assert_true(TB_SQRT2 == sqrt(2.0));
}

static void test_difference_of_products(void **state)
{
    (void)state;
    /* (1 + 2^-27)(1 - 2^-27) - 1*1 = -2^-54 exactly; the naive double formula
     * rounds the product to 1 and returns 0. */
    double a = 1.0 + 0x1p-27, b = 1.0 - 0x1p-27;
    volatile double naive = a * b; /* no chance of contraction */
    assert_true(naive - 1.0 == 0.0);
    assert_true(tb_diff_of_products(a, b, 1.0, 1.0) == -0x1p-54);
    assert_true(tb_diff_of_products(1.0, 1.0, a, b) == 0x1p-54);
    /* Float: (1 + 2^-13)(1 - 2^-13) - 1 = -2^-26. */
    float af = 1.0f + 0x1p-13f, bf = 1.0f - 0x1p-13f;
    assert_true(tb_diff_of_productsf(af, bf, 1.0f, 1.0f) == -0x1p-26f);
    assert_true(tb_diff_of_productsf(3.0f, 4.0f, 2.0f, 5.0f) == 2.0f);

    /* Random float inputs: the reference a*b - c*d in double has exact
     * products (24 + 24 bits) and one rounding in the subtraction, so it is
     * within 1/2 float ulp + 2^-53 relative of the truth; Kahan's bound is
     * 1.5 ulp, hence at most 2 ulps between them. */
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("diff_of_products", 7), 1);
    uint32_t worst = 0;
    for (int i = 0; i < 100000; ++i) {
        float v[4];
        for (int k = 0; k < 4; ++k)
            v[k] = ldexpf(tb_rng_float(&r) * 2.0f - 1.0f, (int)tb_rng_below(&r, 20) - 10);
        /* Make half the cases nearly cancel. */
        if (i & 1) {
            v[2] = v[0] * (1.0f + (tb_rng_float(&r) - 0.5f) * 1e-5f);
            v[3] = v[1];
        }
        double ref = (double)v[0] * v[1] - (double)v[2] * v[3];
        float got = tb_diff_of_productsf(v[0], v[1], v[2], v[3]);
        uint32_t d = tb_ulp_distance(got, (float)ref);
        if (d > worst)
            worst = d;
    }
    print_message("[ info     ] diff_of_productsf: worst distance to reference %u ulp\n", worst);
    assert_true(worst <= 2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_next_float_up_down),
        cmocka_unit_test(test_next_double_up_down),
        cmocka_unit_test(test_float_round_down_up),
        cmocka_unit_test(test_gamma),
        cmocka_unit_test(test_ulp_distance_and_bits),
        cmocka_unit_test(test_clamp_sqrt_finite),
        cmocka_unit_test(test_constants),
        cmocka_unit_test(test_difference_of_products),
    };
    return cmocka_run_group_tests_name("util/math float", tests, NULL, NULL);
}
