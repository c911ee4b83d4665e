/* Reconstruction filters: each kind integrates to 1 (by quadrature, not by
 * the normalisation formula under test), is symmetric, vanishes outside its
 * stated support, and Mitchell-Netravali has its negative lobes and the
 * published values; option parsing and its errors. */
#include "tb_test.h"

#include "util/math/float.h"

#include <string.h>

#include "host/render/film.h"

/* Midpoint rule over the support [-r, r] with n intervals, n a multiple of
 * 4 so the kinks and joins (0, +-r/2) fall on interval ends: the rule is
 * exact on the box and the tent and O(h^2) on the smooth pieces. (Outside
 * the support the filter is tested to be zero.) */
static double integrate1(const tb_filter *f, int n)
{
    double a = -f->radius, b = f->radius, h = (b - a) / n, s = 0.0;
    for (int i = 0; i < n; i++)
        s += tb_filter_eval1(f, a + (i + 0.5) * h);
    return s * h;
}

static void test_integrate_to_one(void **state)
{
    (void)state;
    const double radii[] = {0.0, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0};
    for (int k = 0; k < TB_FILTER_KIND_COUNT; k++) {
        for (size_t ri = 0; ri < sizeof radii / sizeof radii[0]; ri++) {
            tb_filter f;
            assert_int_equal(tb_filter_init(&f, (tb_filter_kind)k, radii[ri], 0.0), TB_OK);
            double r = f.radius;
            if (radii[ri] == 0.0)
                tb_assert_near(r, tb_filter_default_radius((tb_filter_kind)k), 0.0);
            double i1 = integrate1(&f, 400000);
            tb_assert_near(i1, 1.0, 1e-9);
            /* 2D over the square [-r, r]^2 by a coarser midpoint rule */
            int n = 400;
            double a = -r, h = 2.0 * r / n, s = 0.0;
            for (int i = 0; i < n; i++)
                for (int j = 0; j < n; j++)
                    s += tb_filter_eval(&f, a + (i + 0.5) * h, a + (j + 0.5) * h);
            tb_assert_near(s * h * h, 1.0, 1e-5);
        }
    }
    /* A Gaussian with a wide sigma is still normalised (the clipped tail matters). */
    tb_filter g;
    assert_int_equal(tb_filter_init(&g, TB_FILTER_GAUSSIAN, 2.0, 1.5), TB_OK);
    tb_assert_near(integrate1(&g, 400000), 1.0, 1e-9);
}

static void test_symmetry_and_support(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("filter symmetry", 7), 0);
    for (int k = 0; k < TB_FILTER_KIND_COUNT; k++) {
        tb_filter f;
        assert_int_equal(tb_filter_init(&f, (tb_filter_kind)k, 0.5 + 2.5 * tb_rng_double(&rng), 0.0), TB_OK);
        double r = f.radius;
        for (int i = 0; i < 20000; i++) {
            double x = (2.0 * tb_rng_double(&rng) - 1.0) * (r + 2.0);
            double y = (2.0 * tb_rng_double(&rng) - 1.0) * (r + 2.0);
            if (fabs(x) != r)
                assert_true(tb_filter_eval1(&f, x) == tb_filter_eval1(&f, -x));
            assert_true(tb_filter_eval(&f, x, y) == tb_filter_eval(&f, y, x));
            if (fabs(x) > r)
                assert_true(tb_filter_eval1(&f, x) == 0.0);
            /* inside the support: positive except in Mitchell's negative lobes */
            if (fabs(x) < 0.999 * r && k != TB_FILTER_MITCHELL)
                assert_true(tb_filter_eval1(&f, x) > 0.0);
        }
        /* separable */
        tb_assert_near(tb_filter_eval(&f, 0.3 * r, -0.2 * r),
                       tb_filter_eval1(&f, 0.3 * r) * tb_filter_eval1(&f, -0.2 * r), 1e-15);
    }
    /* The box is half-open: a sample on a pixel border goes to exactly one side. */
    tb_filter box;
    tb_filter_init(&box, TB_FILTER_BOX, 0.5, 0.0);
    assert_true(tb_filter_eval1(&box, -0.5) == 1.0);
    assert_true(tb_filter_eval1(&box, 0.5) == 0.0);
    /* tent and box values by hand */
    tb_filter tent;
    tb_filter_init(&tent, TB_FILTER_TENT, 2.0, 0.0);
    tb_assert_near(tb_filter_eval1(&tent, 0.0), 0.5, 1e-15);
    tb_assert_near(tb_filter_eval1(&tent, 1.0), 0.25, 1e-15);
    tb_assert_near(tb_filter_eval1(&box, 0.2), 1.0, 1e-15);
}

static void test_mitchell_lobes(void **state)
{
    (void)state;
    tb_filter m;
    assert_int_equal(tb_filter_init(&m, TB_FILTER_MITCHELL, 2.0, 0.0), TB_OK);
    /* Mitchell-Netravali B = C = 1/3 at radius 2 is the unscaled kernel:
     * k(0) = (6 - 2B)/6 = 8/9, k(1) = B/6 = 1/18, k(1.5) = -5/144 (by hand from
     * the second piece), k(2) = 0 */
    tb_assert_near(tb_filter_eval1(&m, 0.0), 8.0 / 9.0, 1e-14);
    tb_assert_near(tb_filter_eval1(&m, 1.0), 1.0 / 18.0, 1e-14);
    tb_assert_near(tb_filter_eval1(&m, 1.5), -5.0 / 144.0, 1e-14);
    tb_assert_near(tb_filter_eval1(&m, 2.0), 0.0, 1e-14);
    /* negative everywhere strictly inside the outer lobe, between its zero
     * crossing and the edge */
    double minv = 0.0;
    for (double x = 1.2; x < 2.0; x += 0.01) {
        double v = tb_filter_eval1(&m, x);
        assert_true(v < 0.0);
        minv = fmin(minv, v);
    }
    assert_true(minv < -0.03);
    /* the family interpolates a constant: sum over integer shifts is 1 */
    for (double x = 0.0; x < 1.0; x += 0.0625) {
        double s = 0.0;
        for (int i = -3; i <= 3; i++)
            s += tb_filter_eval1(&m, x - i);
        tb_assert_near(s, 1.0, 1e-14);
    }
    /* scaled to radius 3: negative lobe moves out to 3/4 of the radius */
    tb_filter m3;
    tb_filter_init(&m3, TB_FILTER_MITCHELL, 3.0, 0.0);
    tb_assert_near(tb_filter_eval1(&m3, 2.25), -5.0 / 144.0 * (2.0 / 3.0), 1e-14);
}

static void test_parse(void **state)
{
    (void)state;
    tb_filter f;
    assert_int_equal(tb_filter_parse("box", &f), TB_OK);
    assert_true(f.kind == TB_FILTER_BOX && f.radius == 0.5);
    assert_int_equal(tb_filter_parse("tent:1.5", &f), TB_OK);
    assert_true(f.kind == TB_FILTER_TENT && f.radius == 1.5);
    assert_int_equal(tb_filter_parse("gaussian:2:0.7", &f), TB_OK);
    assert_true(f.kind == TB_FILTER_GAUSSIAN && f.radius == 2.0 && f.sigma == 0.7);
    assert_int_equal(tb_filter_parse("gaussian", &f), TB_OK);
    assert_true(f.radius == 1.5 && f.sigma == 0.5);
    assert_int_equal(tb_filter_parse("mitchell:2.5", &f), TB_OK);
    assert_true(f.kind == TB_FILTER_MITCHELL && f.radius == 2.5);
    const char *bad[] = {"", "foo", "box:", "box:-1", "box:0", "box:abc", "box:1:2",
                         "gaussian:1:2:3", "mitchell:1x", "tent:nan", "box:20", "boxx"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        assert_int_equal(tb_filter_parse(bad[i], &f), TB_ERR_ARG);
        assert_true(strlen(tb_last_error()) > 0);
    }
    tb_filter_parse("foo", &f);
    assert_non_null(strstr(tb_last_error(), "unknown kind"));
    tb_filter_parse("box:20", &f);
    assert_non_null(strstr(tb_last_error(), "exceeds"));
    assert_int_equal(tb_filter_init(&f, (tb_filter_kind)9, 1.0, 0.0), TB_ERR_ARG);
    assert_int_equal(tb_filter_init(&f, TB_FILTER_BOX, NAN, 0.0), TB_ERR_ARG);
    assert_string_equal(tb_filter_kind_name(TB_FILTER_MITCHELL), "mitchell");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_integrate_to_one),
        cmocka_unit_test(test_symmetry_and_support),
        cmocka_unit_test(test_mitchell_lobes),
        cmocka_unit_test(test_parse),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
