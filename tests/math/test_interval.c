/* util/math/interval.h: set operations on hand-worked intervals, and a seeded
 * check that interval arithmetic contains the exact result (float sums and
 * products of floats are exact in double, which serves as the oracle). */
#include "tb_test.h"

#include <float.h>
#include <math.h>

#include "util/math/interval.h"

static void test_interval_sets(void **state)
{
    (void)state;
    tb_interval e = tb_interval_empty(), a = tb_interval_make(1, 3), b = tb_interval_make(2, 5);
    assert_true(tb_interval_is_empty(e));
    assert_false(tb_interval_is_empty(a));
    assert_false(tb_interval_is_empty(tb_interval_point(4)));
    assert_true(tb_interval_is_empty(tb_interval_make(2, 1)));
    assert_true(tb_interval_is_empty(tb_interval_make(NAN, 1)));
    assert_true(tb_interval_contains(a, 1) && tb_interval_contains(a, 3) && tb_interval_contains(a, 2.5f));
    assert_false(tb_interval_contains(a, 3.0000002f) || tb_interval_contains(a, NAN));
    assert_false(tb_interval_contains(e, 0));
    tb_interval i = tb_interval_intersect(a, b);
    assert_true(i.lo == 2 && i.hi == 3);
    i = tb_interval_intersect(a, tb_interval_make(3, 4)); /* touching: one point */
    assert_true(i.lo == 3 && i.hi == 3 && !tb_interval_is_empty(i));
    i = tb_interval_intersect(a, tb_interval_make(4, 6));
    assert_true(tb_interval_is_empty(i));
    i = tb_interval_intersect(a, e);
    assert_true(tb_interval_is_empty(i));
    i = tb_interval_hull(a, tb_interval_make(6, 7)); /* the gap is included */
    assert_true(i.lo == 1 && i.hi == 7);
    i = tb_interval_hull(e, b);
    assert_true(i.lo == 2 && i.hi == 5);
    i = tb_interval_hull(a, tb_interval_make(5, 4)); /* another empty operand */
    assert_true(i.lo == 1 && i.hi == 3);
    assert_true(tb_interval_contains_interval(b, tb_interval_make(3, 4)));
    assert_false(tb_interval_contains_interval(a, b));
    assert_true(tb_interval_contains_interval(a, e));
    assert_true(tb_interval_width(b) == 3 && tb_interval_width(e) == 0);
    assert_true(tb_interval_mid(b) == 3.5f);
    assert_true(tb_interval_mid(tb_interval_make(FLT_MAX, FLT_MAX)) == FLT_MAX);
    tb_interval all = tb_interval_everything();
    assert_true(tb_interval_contains(all, -FLT_MAX) && tb_interval_contains(all, INFINITY));
}

static void test_interval_arith_hand(void **state)
{
    (void)state;
    tb_interval a = tb_interval_make(1, 2), b = tb_interval_make(-3, 4);
    /* Exact results, then one float outward on each side. */
    tb_interval s = tb_interval_add(a, b);
    assert_true(s.lo == tb_next_float_down(-2) && s.hi == tb_next_float_up(6));
    s = tb_interval_sub(a, b);
    assert_true(s.lo == tb_next_float_down(-3) && s.hi == tb_next_float_up(5));
    s = tb_interval_mul(a, b); /* products -3, 4, -6, 8 */
    assert_true(s.lo == tb_next_float_down(-6) && s.hi == tb_next_float_up(8));
    s = tb_interval_scale(a, -2);
    assert_true(s.lo == tb_next_float_down(-4) && s.hi == tb_next_float_up(-2));
    s = tb_interval_sqr(b); /* contains 0: [0, 16] */
    assert_true(s.lo == 0 && s.hi == tb_next_float_up(16));
    s = tb_interval_sqr(tb_interval_make(-3, -2));
    assert_true(s.lo == tb_next_float_down(4) && s.hi == tb_next_float_up(9));
    /* 0 * inf is taken as 0 at the bounds: [0, 1] * [1, inf] = [0, inf]. */
    s = tb_interval_mul(tb_interval_make(0, 1), tb_interval_make(1, INFINITY));
    assert_true(s.lo <= 0 && s.lo > -1e-44f && s.hi == INFINITY);
    /* 0.1 + 0.2 contains the real sum of the two floats. */
    s = tb_interval_add(tb_interval_point(0.1f), tb_interval_point(0.2f));
    double exact = (double)0.1f + (double)0.2f;
    assert_true(s.lo <= exact && s.hi >= exact && s.lo < s.hi);
}

static void test_interval_arith_random(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("interval_arith_random", 3), 10);
    for (int k = 0; k < 100000; ++k) {
        float v[4];
        for (int i = 0; i < 4; ++i)
            v[i] = ldexpf(2 * tb_rng_float(&r) - 1, (int)tb_rng_below(&r, 60) - 30);
        tb_interval a = tb_interval_make(fminf(v[0], v[1]), fmaxf(v[0], v[1]));
        tb_interval b = tb_interval_make(fminf(v[2], v[3]), fmaxf(v[2], v[3]));
        /* Points inside the operands, including their ends. */
        double x = (k & 1) ? a.lo : a.lo + (a.hi - a.lo) * tb_rng_double(&r);
        double y = (k & 2) ? b.hi : b.lo + (b.hi - b.lo) * tb_rng_double(&r);
        x = (float)x; /* keep them floats so the double results are exact */
        y = (float)y;
        if (x < a.lo || x > a.hi || y < b.lo || y > b.hi)
            continue;
        tb_interval s = tb_interval_add(a, b), d = tb_interval_sub(a, b), m = tb_interval_mul(a, b);
        tb_interval q = tb_interval_sqr(a);
        /* Sums of floats within 2^60 of each other, and products, are exact in double. */
        assert_true(s.lo <= x + y && x + y <= s.hi);
        assert_true(d.lo <= x - y && x - y <= d.hi);
        assert_true(m.lo <= x * y && x * y <= m.hi);
        assert_true(q.lo <= x * x && x * x <= q.hi);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_interval_sets),
        cmocka_unit_test(test_interval_arith_hand),
        cmocka_unit_test(test_interval_arith_random),
    };
    return cmocka_run_group_tests_name("util/math interval", tests, NULL, NULL);
}
