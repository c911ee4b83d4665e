/* util/container/pqueue: order and tie rule, updates in both directions,
 * removal, and random sequences compared with a linear scan and a sort. */
#include "container_test.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "util/container/pqueue.h"

static void expect_pop(tb_pqueue *q, uint32_t key, double prio)
{
    uint32_t k;
    double p;
    assert_true(tb_pqueue_pop(q, &k, &p));
    assert_int_equal(k, key);
    assert_true(p == prio);
}

static void test_pqueue_basics(void **state)
{
    (void)state;
    tb_pqueue q;
    tb_pqueue_init(&q);
    uint32_t k;
    double p;
    /* Empty. */
    assert_false(tb_pqueue_peek(&q, &k, &p));
    assert_false(tb_pqueue_pop(&q, &k, &p));
    assert_false(tb_pqueue_remove(&q, 0));
    assert_false(tb_pqueue_get(&q, 123456, &p));
    assert_int_equal(tb_pqueue_size(&q), 0);
    /* Single key. */
    assert_int_equal(tb_pqueue_set(&q, 42, 1.5), TB_OK);
    assert_true(tb_pqueue_peek(&q, &k, &p));
    assert_int_equal(k, 42);
    assert_true(p == 1.5);
    assert_int_equal(tb_pqueue_size(&q), 1);
    expect_pop(&q, 42, 1.5);
    assert_int_equal(tb_pqueue_size(&q), 0);
    assert_false(tb_pqueue_get(&q, 42, NULL));
    /* Remove the only key. */
    assert_int_equal(tb_pqueue_set(&q, 7, 0.0), TB_OK);
    assert_true(tb_pqueue_remove(&q, 7));
    assert_false(tb_pqueue_remove(&q, 7));
    assert_false(tb_pqueue_peek(&q, NULL, NULL));

    /* Order, and ties broken by the lower key whatever the insertion order. */
    const uint32_t keys[] = {9, 3, 5, 1, 8};
    const double prios[] = {2.0, 2.0, 7.0, 2.0, -1.0};
    for (int i = 0; i < 5; i++)
        assert_int_equal(tb_pqueue_set(&q, keys[i], prios[i]), TB_OK);
    expect_pop(&q, 5, 7.0);
    expect_pop(&q, 1, 2.0);
    expect_pop(&q, 3, 2.0);
    expect_pop(&q, 9, 2.0);
    expect_pop(&q, 8, -1.0);
    for (int i = 4; i >= 0; i--)
        assert_int_equal(tb_pqueue_set(&q, keys[i], prios[i]), TB_OK);
    expect_pop(&q, 5, 7.0);
    expect_pop(&q, 1, 2.0);
    tb_pqueue_clear(&q);
    assert_int_equal(tb_pqueue_size(&q), 0);
    assert_false(tb_pqueue_get(&q, 3, NULL));

    /* -0.0 equals +0.0: the key decides. */
    assert_int_equal(tb_pqueue_set(&q, 4, -0.0), TB_OK);
    assert_int_equal(tb_pqueue_set(&q, 2, 0.0), TB_OK);
    assert_int_equal(tb_pqueue_set(&q, 3, -0.0), TB_OK);
    assert_true(tb_pqueue_peek(&q, &k, NULL));
    assert_int_equal(k, 2);
    tb_pqueue_clear(&q);

    /* Updates up and down, duplicate set with the same value. */
    for (uint32_t i = 0; i < 10; i++)
        assert_int_equal(tb_pqueue_set(&q, i, (double)i), TB_OK);
    assert_int_equal(tb_pqueue_set(&q, 0, 100.0), TB_OK); /* increase to the top */
    assert_int_equal(tb_pqueue_set(&q, 9, -5.0), TB_OK);  /* decrease to the bottom */
    assert_int_equal(tb_pqueue_set(&q, 5, 5.0), TB_OK);   /* unchanged */
    assert_int_equal(tb_pqueue_size(&q), 10);
    assert_true(tb_pqueue_get(&q, 9, &p) && p == -5.0);
    assert_true(tb_pqueue_remove(&q, 4)); /* from the middle */
    expect_pop(&q, 0, 100.0);
    for (uint32_t i = 8; i >= 1; i--)
        if (i != 4)
            expect_pop(&q, i, (double)i);
    expect_pop(&q, 9, -5.0);
    assert_false(tb_pqueue_pop(&q, NULL, NULL));

    /* Infinities are ordinary priorities; NaN and too-large keys are refused. */
    assert_int_equal(tb_pqueue_set(&q, 1, -INFINITY), TB_OK);
    assert_int_equal(tb_pqueue_set(&q, 2, INFINITY), TB_OK);
    tb_clear_error();
    assert_int_equal(tb_pqueue_set(&q, 3, NAN), TB_ERR_ARG);
    assert_true(strlen(tb_last_error()) > 0);
    assert_int_equal(tb_pqueue_set(&q, 2, NAN), TB_ERR_ARG); /* update refused too */
    assert_int_equal(tb_pqueue_set(&q, UINT32_MAX, 1.0), TB_ERR_ARG);
    assert_int_equal(tb_pqueue_set(&q, TB_PQUEUE_MAX_KEY + 1, 1.0), TB_ERR_ARG);
    assert_int_equal(tb_pqueue_size(&q), 2);
    expect_pop(&q, 2, INFINITY);
    expect_pop(&q, 1, -INFINITY);
    assert_int_equal(tb_pqueue_reserve(&q, SIZE_MAX), TB_ERR_NOMEM);
    assert_int_equal(tb_pqueue_reserve(&q, 1000), TB_OK);
    tb_pqueue_free(&q);
    tb_pqueue_free(&q);
    tb_pqueue_free(NULL);
}

/* Reference for a small key universe: priority per key and a linear scan. */
#define NKEYS 256

typedef struct ref_pq {
    uint8_t present[NKEYS];
    double prio[NKEYS];
    size_t n;
} ref_pq;

/* Best key of the reference (highest priority, then lowest key), or -1. */
static int ref_best(const ref_pq *r)
{
    int best = -1;
    for (int k = 0; k < NKEYS; k++)
        if (r->present[k] && (best < 0 || r->prio[k] > r->prio[best]))
            best = k; /* strict >: the first (lowest) key wins ties */
    return best;
}

/* Priorities from a small set (many ties), or continuous. */
static double random_priority(tb_rng *rng)
{
    uint32_t r = tb_rng_below(rng, 4);
    if (r == 0)
        return tb_rng_double(rng) * 100.0 - 50.0;
    return (double)tb_rng_below(rng, 16) * 0.5 - 2.0;
}

static void test_pqueue_random_vs_scan(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("pqueue_scan", 0x9e9e), 7);
    static ref_pq ref;
    memset(&ref, 0, sizeof ref);
    tb_pqueue q;
    tb_pqueue_init(&q);
    size_t nops = tb_container_test_n(1000000);
    for (size_t op = 0; op < nops; op++) {
        uint32_t r = tb_rng_below(&rng, 100);
        uint32_t k = tb_rng_below(&rng, NKEYS);
        if (r < 50) { /* insert or update (up or down) */
            double p = random_priority(&rng);
            assert_int_equal(tb_pqueue_set(&q, k, p), TB_OK);
            ref.n += !ref.present[k];
            ref.present[k] = 1;
            ref.prio[k] = p;
        } else if (r < 65) { /* remove by key */
            assert_int_equal(tb_pqueue_remove(&q, k), ref.present[k]);
            ref.n -= ref.present[k];
            ref.present[k] = 0;
        } else if (r < 90) { /* pop */
            int best = ref_best(&ref);
            uint32_t key;
            double p;
            if (best < 0) {
                assert_false(tb_pqueue_pop(&q, &key, &p));
            } else {
                assert_true(tb_pqueue_pop(&q, &key, &p));
                assert_int_equal(key, (uint32_t)best);
                assert_true(p == ref.prio[best]);
                ref.present[best] = 0;
                ref.n--;
            }
        } else { /* get */
            double p;
            assert_int_equal(tb_pqueue_get(&q, k, &p), ref.present[k]);
            if (ref.present[k])
                assert_true(p == ref.prio[k]);
        }
        assert_int_equal(tb_pqueue_size(&q), ref.n);
        if (op % 16 == 0) {
            int best = ref_best(&ref);
            uint32_t key;
            assert_int_equal(tb_pqueue_peek(&q, &key, NULL), best >= 0);
            if (best >= 0)
                assert_int_equal(key, (uint32_t)best);
        }
    }
    tb_pqueue_free(&q);
}

typedef struct kp {
    uint32_t key;
    double prio;
} kp;

/* The documented order: priority descending, then key ascending. */
static int cmp_kp(const void *a, const void *b)
{
    const kp *x = a, *y = b;
    if (x->prio != y->prio)
        return x->prio > y->prio ? -1 : 1;
    return (x->key > y->key) - (x->key < y->key);
}

/* 10^6 keys: insert, update half of them at random (up and down), remove some,
 * then pop everything and compare with the sorted reference. */
static void test_pqueue_million_vs_sort(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("pqueue_sort", 0x50127), 8);
    size_t n = tb_container_test_n(1000000);
    double *prio = malloc(n * sizeof *prio);
    uint8_t *present = calloc(n, 1);
    assert_non_null(prio);
    assert_non_null(present);
    tb_pqueue q;
    tb_pqueue_init(&q);
    /* Keys inserted in a random order (Fisher-Yates shuffle). */
    uint32_t *order = malloc(n * sizeof *order);
    assert_non_null(order);
    for (size_t i = 0; i < n; i++)
        order[i] = (uint32_t)i;
    for (size_t i = n; i > 1; i--) {
        size_t j = tb_rng_below(&rng, (uint32_t)i);
        uint32_t t = order[i - 1];
        order[i - 1] = order[j];
        order[j] = t;
    }
    for (size_t i = 0; i < n; i++) {
        uint32_t k = order[i];
        prio[k] = random_priority(&rng);
        present[k] = 1;
        assert_int_equal(tb_pqueue_set(&q, k, prio[k]), TB_OK);
    }
    for (size_t i = 0; i < n / 2; i++) {
        uint32_t k = tb_rng_below(&rng, (uint32_t)n);
        if (tb_rng_below(&rng, 8) == 0) {
            assert_int_equal(tb_pqueue_remove(&q, k), present[k]);
            present[k] = 0;
        } else {
            prio[k] = random_priority(&rng); /* re-inserts a removed key */
            present[k] = 1;
            assert_int_equal(tb_pqueue_set(&q, k, prio[k]), TB_OK);
        }
    }
    kp *ref = malloc(n * sizeof *ref);
    assert_non_null(ref);
    size_t m = 0;
    for (size_t k = 0; k < n; k++)
        if (present[k])
            ref[m++] = (kp){(uint32_t)k, prio[k]};
    qsort(ref, m, sizeof *ref, cmp_kp);
    assert_int_equal(tb_pqueue_size(&q), m);
    for (size_t i = 0; i < m; i++) {
        uint32_t key;
        double p;
        assert_true(tb_pqueue_pop(&q, &key, &p));
        if (key != ref[i].key || p != ref[i].prio)
            fail_msg("pop %zu: got key %u prio %g, expected key %u prio %g", i, key, p,
                     ref[i].key, ref[i].prio);
    }
    assert_false(tb_pqueue_pop(&q, NULL, NULL));
    tb_pqueue_free(&q);
    free(ref);
    free(order);
    free(prio);
    free(present);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pqueue_basics),
        cmocka_unit_test(test_pqueue_random_vs_scan),
        cmocka_unit_test(test_pqueue_million_vs_sort),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
