/* Helpers shared by the container tests. */
#ifndef TB_TESTS_CONTAINER_CONTAINER_TEST_H
#define TB_TESTS_CONTAINER_CONTAINER_TEST_H

#include "tb_test.h"

/* Operation count of the randomized comparisons: `n` (10^6 in the normal
 * build), divided by $TB_CONTAINER_TEST_DIVISOR when set (e.g. for a slow
 * debugging build). */
static inline size_t tb_container_test_n(size_t n)
{
    const char *env = getenv("TB_CONTAINER_TEST_DIVISOR");
    unsigned long d = env ? strtoul(env, NULL, 0) : 1;
    return d > 1 ? n / d : n;
}

#endif
