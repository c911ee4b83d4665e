/* util/container/arena: alignment, large requests, scopes, and a random
 * sequence of allocations and releases checked for overlap and corruption. */
#include "container_test.h"

#include <stdalign.h>
#include <stdint.h>
#include <string.h>

#include "util/container/arena.h"
#include "util/container/array.h"

#if defined(__SANITIZE_ADDRESS__)
#define ARENA_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define ARENA_TEST_ASAN 1
#endif
#endif
#ifdef ARENA_TEST_ASAN
#include <sanitizer/asan_interface.h>
#endif

static int aligned(const void *p, size_t a)
{
    return ((uintptr_t)p & (a - 1)) == 0;
}

static void test_arena_alignment(void **state)
{
    (void)state;
    tb_arena a;
    tb_arena_init(&a, 4096);
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("arena_alignment", 11), 2);
    for (int i = 0; i < 2000; i++) {
        size_t size = tb_rng_below(&rng, 200);
        void *p = tb_arena_alloc(&a, size);
        assert_non_null(p);
        assert_true(aligned(p, alignof(max_align_t)));
        memset(p, 0xab, size);
        size_t align = (size_t)1 << tb_rng_below(&rng, 13); /* 1 .. 4096 */
        void *q = tb_arena_alloc_aligned(&a, size, align);
        assert_non_null(q);
        assert_true(aligned(q, align));
        memset(q, 0xcd, size);
    }
    /* An alignment larger than a chunk still works (own chunk). */
    void *big = tb_arena_alloc_aligned(&a, 10, (size_t)1 << 16);
    assert_non_null(big);
    assert_true(aligned(big, (size_t)1 << 16));
    /* Bad alignments are refused with a message. */
    tb_clear_error();
    assert_null(tb_arena_alloc_aligned(&a, 8, 0));
    assert_null(tb_arena_alloc_aligned(&a, 8, 24));
    assert_true(strlen(tb_last_error()) > 0);
    tb_arena_free(&a);
}

static void test_arena_edge_cases(void **state)
{
    (void)state;
    tb_arena a = {0}; /* a zeroed arena is usable */
    /* Size 0 still gives distinct pointers. */
    void *p0 = tb_arena_alloc(&a, 0), *p1 = tb_arena_alloc(&a, 0);
    assert_non_null(p0);
    assert_non_null(p1);
    assert_ptr_not_equal(p0, p1);
    char *s = tb_arena_strdup(&a, "radiosity");
    assert_string_equal(s, "radiosity");
    char *e = tb_arena_strdup(&a, "");
    assert_string_equal(e, "");
    unsigned char *z = tb_arena_alloc_zero(&a, 1000);
    for (int i = 0; i < 1000; i++)
        assert_int_equal(z[i], 0);
    /* Overflowing requests fail cleanly, without reaching malloc. */
    const size_t huge[] = {SIZE_MAX, SIZE_MAX - 8, (size_t)PTRDIFF_MAX, (size_t)PTRDIFF_MAX - 16};
    for (size_t k = 0; k < sizeof huge / sizeof huge[0]; k++) {
        tb_clear_error();
        assert_null(tb_arena_alloc(&a, huge[k]));
        assert_true(strlen(tb_last_error()) > 0);
        assert_null(tb_arena_alloc_aligned(&a, huge[k], 4096));
    }
    /* Earlier allocations are unharmed. */
    assert_string_equal(s, "radiosity");
    tb_arena_free(&a);
    assert_int_equal(tb_arena_capacity(&a), 0);
    tb_arena_free(&a); /* twice is harmless */
    tb_arena_free(NULL);
}

/* A request above a quarter chunk gets its own chunk, and the current chunk
 * keeps serving small requests right where it left off. */
static void test_arena_large_requests(void **state)
{
    (void)state;
    tb_arena a;
    tb_arena_init(&a, 1024);
    const size_t A = alignof(max_align_t);
    char *p1 = tb_arena_alloc(&a, A);
    assert_int_equal(tb_arena_capacity(&a), 1024);
    char *big = tb_arena_alloc(&a, 10000);
    assert_non_null(big);
    memset(big, 1, 10000);
    assert_int_equal(tb_arena_capacity(&a), 1024 + 10000);
    char *p2 = tb_arena_alloc(&a, A);
    assert_ptr_equal(p2, p1 + A);
    /* Just above a quarter: own chunk again. */
    char *q = tb_arena_alloc(&a, 1024 / 4 + 1);
    assert_non_null(q);
    assert_int_equal(tb_arena_capacity(&a), 1024 + 10000 + 1024 / 4 + 1);
    char *p3 = tb_arena_alloc(&a, A);
    assert_ptr_equal(p3, p2 + A);
    tb_arena_free(&a);
}

static void test_arena_mark_release_reset(void **state)
{
    (void)state;
    tb_arena a;
    tb_arena_init(&a, 1024);
    char *keep = tb_arena_strdup(&a, "kept");
    tb_arena_mark m = tb_arena_mark_get(&a);
    size_t cap0 = tb_arena_capacity(&a);
    char *first = tb_arena_alloc(&a, 64);
    for (int i = 0; i < 100; i++)
        assert_non_null(tb_arena_alloc(&a, 100));
    assert_non_null(tb_arena_alloc(&a, 5000)); /* a large chunk inside the scope */
    assert_true(tb_arena_capacity(&a) > cap0 + 5000);
    tb_arena_release(&a, m);
    /* Back to the mark: one spare chunk at most is kept. */
    assert_true(tb_arena_capacity(&a) <= cap0 + 1024);
    assert_string_equal(keep, "kept");
#ifdef ARENA_TEST_ASAN
    assert_true(__asan_address_is_poisoned(first));
#endif
    /* The next allocation reuses the released space. */
    char *again = tb_arena_alloc(&a, 64);
    assert_ptr_equal(again, first);

    /* Nested scopes: release the inner, then the outer. */
    tb_arena_mark outer = tb_arena_mark_get(&a);
    char *x = tb_arena_alloc(&a, 32);
    tb_arena_mark inner = tb_arena_mark_get(&a);
    char *y = tb_arena_alloc(&a, 32);
    tb_arena_release(&a, inner);
    assert_ptr_equal(tb_arena_alloc(&a, 32), y);
    tb_arena_release(&a, outer);
    assert_ptr_equal(tb_arena_alloc(&a, 32), x);

    /* A mark taken on an empty arena releases everything. */
    tb_arena b;
    tb_arena_init(&b, 512);
    tb_arena_mark empty = tb_arena_mark_get(&b);
    for (int i = 0; i < 50; i++)
        assert_non_null(tb_arena_alloc(&b, 100));
    tb_arena_release(&b, empty);
    assert_true(tb_arena_capacity(&b) <= 512);
    tb_arena_free(&b);

    /* Reset keeps exactly one chunk and reuses it. */
    for (int i = 0; i < 100; i++)
        assert_non_null(tb_arena_alloc(&a, 200));
    tb_arena_reset(&a);
    assert_int_equal(tb_arena_capacity(&a), 1024);
    assert_non_null(tb_arena_alloc(&a, 200));
    assert_int_equal(tb_arena_capacity(&a), 1024);
    tb_arena_free(&a);
}

/* One live allocation of the random test. */
typedef struct alloc_rec {
    unsigned char *p;
    size_t size;
    uint32_t tag;   /* fill pattern seed */
} alloc_rec;

static unsigned char pattern(uint32_t tag, size_t i)
{
    return (unsigned char)((tag * 2654435761u) >> 24 ^ (uint32_t)i * 31u);
}

static int cmp_rec(const void *a, const void *b)
{
    uintptr_t x = (uintptr_t)((const alloc_rec *)a)->p, y = (uintptr_t)((const alloc_rec *)b)->p;
    return x < y ? -1 : x > y;
}

static void check_all(const tb_array *recs)
{
    for (size_t k = 0; k < recs->len; k++) {
        const alloc_rec *r = tb_array_at(recs, k);
        for (size_t i = 0; i < r->size; i++)
            if (r->p[i] != pattern(r->tag, i))
                fail_msg("allocation %zu (tag %u) corrupted at byte %zu", k, r->tag, i);
    }
    /* No two live allocations overlap. */
    tb_array sorted = TB_ARRAY_INIT(alloc_rec);
    assert_int_equal(tb_array_push_n(&sorted, recs->data, recs->len), TB_OK);
    if (sorted.len > 1)
        qsort(sorted.data, sorted.len, sizeof(alloc_rec), cmp_rec);
    for (size_t k = 1; k < sorted.len; k++) {
        const alloc_rec *a = tb_array_at(&sorted, k - 1), *b = tb_array_at(&sorted, k);
        assert_true((uintptr_t)a->p + a->size <= (uintptr_t)b->p);
    }
    tb_array_free(&sorted);
}

static void test_arena_random_scopes(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("arena_random", 0xa4e4a), 3);
    tb_arena a;
    tb_arena_init(&a, 8192);
    tb_array recs = TB_ARRAY_INIT(alloc_rec);
    /* Stack of open scopes: the mark and the number of records before it. */
    tb_arena_mark marks[64];
    size_t nrecs_at[64];
    int depth = 0;
    size_t nops = tb_container_test_n(1000000);
    uint32_t tag = 0;
    for (size_t op = 0; op < nops; op++) {
        uint32_t r = tb_rng_below(&rng, 1000);
        if (r < 5 && depth < 64) {
            marks[depth] = tb_arena_mark_get(&a);
            nrecs_at[depth++] = recs.len;
        } else if (r < 10 && depth > 0) {
            depth--;
            tb_arena_release(&a, marks[depth]);
            recs.len = nrecs_at[depth];
        } else if (r == 10) {
            tb_arena_reset(&a);
            depth = 0;
            recs.len = 0;
        } else {
            /* Mostly small, sometimes large; various alignments. */
            size_t size = r < 20 ? 2000 + tb_rng_below(&rng, 20000) : tb_rng_below(&rng, 64);
            size_t align = (size_t)1 << tb_rng_below(&rng, 8);
            unsigned char *p = r & 1 ? tb_arena_alloc_aligned(&a, size, align)
                                     : tb_arena_alloc(&a, size);
            assert_non_null(p);
            assert_true(aligned(p, r & 1 ? align : alignof(max_align_t)));
            alloc_rec rec = {p, size, tag++};
            for (size_t i = 0; i < size; i++)
                p[i] = pattern(rec.tag, i);
            assert_int_equal(tb_array_push(&recs, &rec), TB_OK);
        }
        if (op % 4096 == 0)
            check_all(&recs);
    }
    check_all(&recs);
    tb_array_free(&recs);
    tb_arena_free(&a);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_arena_alignment),
        cmocka_unit_test(test_arena_edge_cases),
        cmocka_unit_test(test_arena_large_requests),
        cmocka_unit_test(test_arena_mark_release_reset),
        cmocka_unit_test(test_arena_random_scopes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
