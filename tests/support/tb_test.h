/* Helpers shared by the cmocka unit tests. */
#ifndef TB_TESTS_SUPPORT_TB_TEST_H
#define TB_TESTS_SUPPORT_TB_TEST_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <cmocka.h>

#include "util/math/rng.h"

/* Seed for property tests: $TB_TEST_SEED if set, else `fallback`. It is printed
 * so a failing run can be repeated with the same numbers. */
static inline uint64_t tb_test_seed(const char *test, uint64_t fallback)
{
    const char *env = getenv("TB_TEST_SEED");
    uint64_t seed = env ? strtoull(env, NULL, 0) : fallback;
    print_message("[ seed     ] %s: TB_TEST_SEED=%llu\n", test, (unsigned long long)seed);
    return seed;
}

/* A fresh scratch folder for one test's files (under the build tree). */
static inline const char *tb_test_tmpdir(void)
{
    const char *d = getenv("TB_TEST_TMPDIR");
    return d ? d : ".";
}

/* Path of a file in the source tree's tests/ folder. */
#define TB_TEST_SOURCE_DIR TB_TESTS_DIR

/* Asserts |a - b| <= tol, printing both values on failure. */
#define tb_assert_near(a, b, tol)                                                      \
    do {                                                                               \
        double tb__a = (double)(a), tb__b = (double)(b), tb__t = (double)(tol);        \
        if (!(fabs(tb__a - tb__b) <= tb__t))                                           \
            fail_msg("%s = %.17g, %s = %.17g, |diff| = %.3g > %.3g", #a, tb__a, #b,    \
                     tb__b, fabs(tb__a - tb__b), tb__t);                               \
    } while (0)

#endif
