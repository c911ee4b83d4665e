/* util/container/array: edge cases, overflow checks, and a long random
 * sequence of operations compared with a naive fixed-size array. */
#include "container_test.h"

#include <stdint.h>
#include <string.h>

#include "util/container/array.h"

/* 12 bytes: not a power of two, so index arithmetic is exercised. */
typedef struct elem3 {
    uint32_t a, b, c;
} elem3;

static elem3 mk(uint32_t v)
{
    return (elem3){v, ~v, v * 2654435761u};
}

static void assert_elem(elem3 e, uint32_t v)
{
    assert_int_equal(e.a, v);
    assert_int_equal(e.b, ~v);
    assert_int_equal(e.c, v * 2654435761u);
}

static void test_array_basics(void **state)
{
    (void)state;
    tb_array a = TB_ARRAY_INIT(elem3);
    assert_int_equal(a.len, 0);
    elem3 e;
    tb_clear_error();
    assert_int_equal(tb_array_pop(&a, &e), TB_ERR_ARG); /* empty */
    assert_true(strlen(tb_last_error()) > 0);
    assert_int_equal(tb_array_remove(&a, 0, NULL), TB_ERR_ARG);
    assert_int_equal(tb_array_insert(&a, 1, NULL), TB_ERR_ARG); /* past the end */

    /* Single element: push, read, pop back to empty. */
    assert_int_equal(TB_ARRAY_PUSH(&a, elem3, mk(7)), TB_OK);
    assert_int_equal(a.len, 1);
    assert_elem(TB_ARRAY_AT(&a, elem3, 0), 7);
    assert_int_equal(tb_array_pop(&a, &e), TB_OK);
    assert_elem(e, 7);
    assert_int_equal(a.len, 0);

    /* Insert at front, middle and end; remove the last and the first. */
    assert_int_equal(tb_array_insert(&a, 0, (elem3[1]){mk(2)}), TB_OK);
    assert_int_equal(tb_array_insert(&a, 0, (elem3[1]){mk(0)}), TB_OK);
    assert_int_equal(tb_array_insert(&a, 1, (elem3[1]){mk(1)}), TB_OK);
    assert_int_equal(tb_array_insert(&a, 3, (elem3[1]){mk(3)}), TB_OK);
    assert_int_equal(a.len, 4);
    for (uint32_t i = 0; i < 4; i++)
        assert_elem(*(elem3 *)tb_array_at(&a, i), i);
    assert_int_equal(tb_array_remove(&a, 3, &e), TB_OK);
    assert_elem(e, 3);
    assert_int_equal(tb_array_remove(&a, 0, &e), TB_OK);
    assert_elem(e, 0);
    assert_int_equal(a.len, 2);
    assert_elem(TB_ARRAY_AT(&a, elem3, 0), 1);
    assert_elem(TB_ARRAY_AT(&a, elem3, 1), 2);
    assert_int_equal(tb_array_remove(&a, 2, NULL), TB_ERR_ARG);

    /* Resize up zero-fills, down truncates; clear keeps the storage. */
    assert_int_equal(tb_array_resize(&a, 5), TB_OK);
    for (size_t i = 2; i < 5; i++) {
        elem3 z = TB_ARRAY_AT(&a, elem3, i);
        assert_true(z.a == 0 && z.b == 0 && z.c == 0);
    }
    assert_int_equal(tb_array_resize(&a, 1), TB_OK);
    assert_int_equal(a.len, 1);
    assert_elem(TB_ARRAY_AT(&a, elem3, 0), 1);
    size_t cap = a.cap;
    tb_array_clear(&a);
    assert_int_equal(a.len, 0);
    assert_int_equal(a.cap, cap);

    /* reserve never shrinks. */
    assert_int_equal(tb_array_reserve(&a, 100), TB_OK);
    assert_true(a.cap >= 100);
    assert_int_equal(tb_array_reserve(&a, 3), TB_OK);
    assert_true(a.cap >= 100);

    /* push_n, and a NULL push of zero bytes. */
    elem3 three[3] = {mk(10), mk(11), mk(12)};
    assert_int_equal(tb_array_push_n(&a, three, 3), TB_OK);
    assert_int_equal(tb_array_push_n(&a, NULL, 0), TB_OK);
    assert_int_equal(tb_array_push(&a, NULL), TB_OK);
    assert_int_equal(a.len, 4);
    assert_elem(TB_ARRAY_AT(&a, elem3, 2), 12);
    assert_int_equal(TB_ARRAY_AT(&a, elem3, 3).a, 0);

    tb_array_free(&a);
    assert_null(a.data);
    assert_int_equal(a.len, 0);
    /* Reusable after free. */
    assert_int_equal(TB_ARRAY_PUSH(&a, elem3, mk(5)), TB_OK);
    tb_array_free(&a);
    tb_array_free(NULL);
}

static void test_array_growth(void **state)
{
    (void)state;
    tb_array a;
    tb_array_init(&a, sizeof(uint64_t));
    size_t reallocs = 0, cap = a.cap;
    for (uint64_t i = 0; i < 200000; i++) {
        assert_int_equal(TB_ARRAY_PUSH(&a, uint64_t, i * i), TB_OK);
        assert_true(a.cap >= a.len);
        if (a.cap != cap) {
            reallocs++;
            cap = a.cap;
        }
    }
    /* Geometric growth: a logarithmic number of reallocations. */
    assert_true(reallocs <= 20);
    for (uint64_t i = 0; i < 200000; i++)
        assert_true(TB_ARRAY_AT(&a, uint64_t, i) == i * i);
    tb_array_free(&a);
}

/* Pushing or inserting one of the array's own elements while it grows. */
static void test_array_self_reference(void **state)
{
    (void)state;
    tb_array a = TB_ARRAY_INIT(elem3);
    assert_int_equal(TB_ARRAY_PUSH(&a, elem3, mk(1)), TB_OK);
    for (int i = 0; i < 100; i++) {
        /* Element 0 appended: the storage moves whenever len == cap. */
        assert_int_equal(tb_array_push(&a, tb_array_at(&a, 0)), TB_OK);
    }
    for (size_t i = 0; i < a.len; i++)
        assert_elem(TB_ARRAY_AT(&a, elem3, i), 1);
    /* Insert before an element, copying that same element (it shifts up). */
    TB_ARRAY_AT(&a, elem3, 50) = mk(99);
    size_t len = a.len;
    for (int k = 0; k < 40; k++) {
        assert_int_equal(tb_array_insert(&a, 50, tb_array_at(&a, 50)), TB_OK);
    }
    assert_int_equal(a.len, len + 40);
    for (size_t i = 0; i < a.len; i++)
        assert_elem(TB_ARRAY_AT(&a, elem3, i), i >= 50 && i <= 90 ? 99 : 1);
    /* Distinct values: insert at the front a copy of an element behind the
     * insertion point, which moves up by one slot during the insertion. */
    tb_array d = TB_ARRAY_INIT(elem3);
    for (uint32_t i = 0; i < 8; i++) /* exactly full: the insert also reallocates */
        assert_int_equal(TB_ARRAY_PUSH(&d, elem3, mk(i)), TB_OK);
    assert_int_equal(d.cap, 8);
    assert_int_equal(tb_array_insert(&d, 0, tb_array_at(&d, 5)), TB_OK);
    assert_int_equal(tb_array_insert(&d, 3, tb_array_at(&d, 1)), TB_OK);
    const uint32_t want[10] = {5, 0, 1, 0, 2, 3, 4, 5, 6, 7};
    for (size_t i = 0; i < 10; i++)
        assert_elem(TB_ARRAY_AT(&d, elem3, i), want[i]);
    tb_array_free(&d);
    /* Append a slice of itself. */
    len = a.len;
    assert_int_equal(tb_array_push_n(&a, tb_array_at(&a, 0), len), TB_OK);
    assert_int_equal(a.len, 2 * len);
    for (size_t i = 0; i < len; i++)
        assert_memory_equal(tb_array_at(&a, i), tb_array_at(&a, i + len), sizeof(elem3));
    tb_array_free(&a);
}

/* Requests whose byte size overflows fail with TB_ERR_NOMEM before any
 * allocation, and leave the array as it was. */
static void test_array_overflow(void **state)
{
    (void)state;
    tb_array a = TB_ARRAY_INIT(elem3);
    assert_int_equal(TB_ARRAY_PUSH(&a, elem3, mk(3)), TB_OK);
    size_t cap = a.cap;
    const size_t huge[] = {
        SIZE_MAX,
        SIZE_MAX / 2,
        SIZE_MAX / sizeof(elem3) + 1,   /* count * 12 wraps around */
        (size_t)PTRDIFF_MAX / sizeof(elem3) + 1,
    };
    for (size_t k = 0; k < sizeof huge / sizeof huge[0]; k++) {
        tb_clear_error();
        assert_int_equal(tb_array_reserve(&a, huge[k]), TB_ERR_NOMEM);
        assert_true(strlen(tb_last_error()) > 0);
        assert_int_equal(tb_array_resize(&a, huge[k]), TB_ERR_NOMEM);
        elem3 dummy = mk(0);
        assert_int_equal(tb_array_push_n(&a, &dummy, huge[k]), TB_ERR_NOMEM);
        assert_int_equal(a.len, 1);
        assert_int_equal(a.cap, cap);
        assert_elem(TB_ARRAY_AT(&a, elem3, 0), 3);
    }
    /* len + extra wrapping around SIZE_MAX. */
    tb_array b = TB_ARRAY_INIT(char);
    assert_int_equal(tb_array_resize(&b, 10), TB_OK);
    char c = 'x';
    assert_int_equal(tb_array_push_n(&b, &c, SIZE_MAX - 5), TB_ERR_NOMEM);
    assert_int_equal(b.len, 10);
    /* An uninitialised (zero element size) array is refused, not divided by. */
    tb_array z = {0};
    assert_int_equal(tb_array_reserve(&z, 4), TB_ERR_ARG);
    assert_int_equal(tb_array_push(&z, &c), TB_ERR_ARG);
    tb_array_free(&a);
    tb_array_free(&b);
}

/* Reference: a fixed-capacity array whose shifts are explicit loops. */
#define REF_MAX 1024
typedef struct ref_array {
    elem3 v[REF_MAX + 1];
    size_t n;
} ref_array;

static void test_array_random_vs_reference(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("array_random", 0xa77a5eed), 1);
    static ref_array ref;
    ref.n = 0;
    tb_array a = TB_ARRAY_INIT(elem3);
    size_t nops = tb_container_test_n(1000000);
    uint32_t next = 1;
    for (size_t op = 0; op < nops; op++) {
        uint32_t r = tb_rng_below(&rng, 100);
        /* Above 3/4 of the reference capacity, only shrink. */
        if (ref.n >= REF_MAX * 3 / 4 && r < 55)
            r += 45;
        if (r < 25) { /* push */
            elem3 e = mk(next++);
            assert_int_equal(tb_array_push(&a, &e), TB_OK);
            ref.v[ref.n++] = e;
        } else if (r < 50) { /* insert at a random index */
            size_t i = tb_rng_below(&rng, (uint32_t)ref.n + 1);
            elem3 e = mk(next++);
            assert_int_equal(tb_array_insert(&a, i, &e), TB_OK);
            for (size_t k = ref.n; k > i; k--)
                ref.v[k] = ref.v[k - 1];
            ref.v[i] = e;
            ref.n++;
        } else if (r < 54) { /* resize to a nearby length */
            size_t len = ref.n + tb_rng_below(&rng, 9);
            len = len >= 4 ? len - 4 : 0;
            assert_int_equal(tb_array_resize(&a, len), TB_OK);
            for (size_t k = ref.n; k < len; k++)
                ref.v[k] = (elem3){0, 0, 0};
            ref.n = len;
        } else if (r < 75) { /* pop */
            elem3 e;
            if (ref.n == 0) {
                assert_int_equal(tb_array_pop(&a, &e), TB_ERR_ARG);
            } else {
                assert_int_equal(tb_array_pop(&a, &e), TB_OK);
                ref.n--;
                assert_memory_equal(&e, &ref.v[ref.n], sizeof e);
            }
        } else if (r < 99 || ref.n == 0) { /* remove at a random index */
            if (ref.n == 0) {
                assert_int_equal(tb_array_remove(&a, 0, NULL), TB_ERR_ARG);
                continue;
            }
            size_t i = tb_rng_below(&rng, (uint32_t)ref.n);
            elem3 e;
            assert_int_equal(tb_array_remove(&a, i, &e), TB_OK);
            assert_memory_equal(&e, &ref.v[i], sizeof e);
            for (size_t k = i; k + 1 < ref.n; k++)
                ref.v[k] = ref.v[k + 1];
            ref.n--;
        } else if (tb_rng_below(&rng, 100) == 0) { /* rarely: clear */
            tb_array_clear(&a);
            ref.n = 0;
        }
        assert_int_equal(a.len, ref.n);
        if (ref.n) {
            size_t i = tb_rng_below(&rng, (uint32_t)ref.n);
            assert_memory_equal(tb_array_at(&a, i), &ref.v[i], sizeof(elem3));
        }
        if (op % 4096 == 0 && ref.n)
            assert_memory_equal(a.data, ref.v, ref.n * sizeof(elem3));
    }
    if (ref.n)
        assert_memory_equal(a.data, ref.v, ref.n * sizeof(elem3));
    tb_array_free(&a);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_array_basics),
        cmocka_unit_test(test_array_growth),
        cmocka_unit_test(test_array_self_reference),
        cmocka_unit_test(test_array_overflow),
        cmocka_unit_test(test_array_random_vs_reference),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
