/* util/container/hash_table: hash function reference values, edge cases, and
 * long random sequences compared with a direct-address table. */
#include "container_test.h"

#include <stdint.h>
#include <string.h>

#include "util/container/hash_table.h"

/* SplitMix64 (Vigna's reference generator) with seed 1234567 outputs
 * 6457827717110365317, 3203168211198807973, ...; output k is the finaliser of
 * seed + k * golden, which is what tb_hash_u64 computes for seed + (k-1)*golden.
 * FNV-1a 64 of "a" is 0xaf63dc4c8601ec8c and of "" the offset basis. */
static void test_hash_functions_reference(void **state)
{
    (void)state;
    const uint64_t golden = 0x9e3779b97f4a7c15ull;
    assert_true(tb_hash_u64(1234567) == 6457827717110365317ull);
    assert_true(tb_hash_u64(1234567 + golden) == 3203168211198807973ull);
    assert_true(tb_hash_bytes("a", 1) == tb_hash_u64(0xaf63dc4c8601ec8cull));
    assert_true(tb_hash_bytes("", 0) == tb_hash_u64(0xcbf29ce484222325ull));
    assert_true(tb_hash_str("foobar") == tb_hash_u64(0x85944171f73967e8ull));
    assert_true(tb_hash_str("a") == tb_hash_bytes("a", 1));

    /* Avalanche: flipping one input bit flips about half of the output bits. */
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("hash_avalanche", 5), 4);
    double flips = 0;
    int n = 0;
    for (int t = 0; t < 2000; t++) {
        uint64_t x = (uint64_t)tb_rng_u32(&rng) << 32 | tb_rng_u32(&rng);
        for (int b = 0; b < 64; b++, n++)
            flips += __builtin_popcountll(tb_hash_u64(x) ^ tb_hash_u64(x ^ (1ull << b)));
    }
    tb_assert_near(flips / n, 32.0, 0.5);
}

static void test_htab_edge_cases(void **state)
{
    (void)state;
    tb_htab h;
    tb_htab_init(&h, TB_HTAB_U64);
    uint64_t v = 0;
    size_t it = 0;
    tb_htab_entry e;
    /* Empty table. */
    assert_false(tb_htab_get(&h, 0, &v));
    assert_false(tb_htab_del(&h, 0));
    assert_false(tb_htab_next(&h, &it, &e));
    assert_int_equal(h.count, 0);
    /* Single entry, replace, delete the only entry. */
    assert_int_equal(tb_htab_put(&h, 0, 10), TB_OK);
    assert_true(tb_htab_get(&h, 0, &v));
    assert_true(v == 10);
    assert_int_equal(tb_htab_put(&h, 0, 11), TB_OK); /* duplicate key replaces */
    assert_int_equal(h.count, 1);
    assert_true(tb_htab_get(&h, 0, &v));
    assert_true(v == 11);
    assert_true(tb_htab_get(&h, 0, NULL));
    assert_true(tb_htab_del(&h, 0));
    assert_false(tb_htab_del(&h, 0));
    assert_false(tb_htab_get(&h, 0, &v));
    assert_int_equal(h.count, 0);
    /* Extreme keys, and the key whose mixed hash is 0 (stored as 1). */
    const uint64_t keys[] = {UINT64_MAX, 1ull << 63, 0x61c8864680b583ebull /* = -golden */, 1};
    for (int i = 0; i < 4; i++)
        assert_int_equal(tb_htab_put(&h, keys[i], (uint64_t)i), TB_OK);
    for (int i = 0; i < 4; i++) {
        assert_true(tb_htab_get(&h, keys[i], &v));
        assert_true(v == (uint64_t)i);
    }
    /* Iteration visits each entry once. */
    int seen = 0;
    it = 0;
    while (tb_htab_next(&h, &it, &e)) {
        assert_null(e.str);
        assert_true(e.key == keys[e.value]);
        seen |= 1 << e.value;
    }
    assert_int_equal(seen, 15);
    /* Wrong key kind. */
    assert_int_equal(tb_htab_put_str(&h, "x", 1), TB_ERR_ARG);
    assert_false(tb_htab_get_str(&h, "x", &v));
    assert_false(tb_htab_del_str(&h, "x"));
    /* Clear keeps working storage. */
    size_t cap = h.cap;
    tb_htab_clear(&h);
    assert_int_equal(h.count, 0);
    assert_int_equal(h.cap, cap);
    assert_false(tb_htab_get(&h, UINT64_MAX, NULL));
    /* Reserve: no growth while filling up to the reserved count. */
    assert_int_equal(tb_htab_reserve(&h, 1000), TB_OK);
    cap = h.cap;
    for (uint64_t k = 0; k < 1000; k++)
        assert_int_equal(tb_htab_put(&h, k, k), TB_OK);
    assert_int_equal(h.cap, cap);
    assert_true(h.count * 5 <= h.cap * 4); /* load <= 0.8 */
    /* Impossible reservations fail cleanly and leave the table intact. */
    const size_t huge[] = {SIZE_MAX, SIZE_MAX / 2, (size_t)PTRDIFF_MAX / 24 + 1};
    for (int i = 0; i < 3; i++) {
        tb_clear_error();
        assert_int_equal(tb_htab_reserve(&h, huge[i]), TB_ERR_NOMEM);
        assert_true(strlen(tb_last_error()) > 0);
    }
    assert_int_equal(h.count, 1000);
    assert_true(tb_htab_get(&h, 999, &v) && v == 999);
    tb_htab_free(&h);
    tb_htab_free(&h);
    tb_htab_free(NULL);
}

static void test_htab_string_keys(void **state)
{
    (void)state;
    tb_htab h;
    tb_htab_init(&h, TB_HTAB_STR);
    char buf[32];
    strcpy(buf, "alpha");
    assert_int_equal(tb_htab_put_str(&h, buf, 1), TB_OK);
    strcpy(buf, "beta"); /* the table kept its own copy */
    uint64_t v;
    assert_true(tb_htab_get_str(&h, "alpha", &v) && v == 1);
    assert_false(tb_htab_get_str(&h, "beta", &v));
    assert_int_equal(tb_htab_put_str(&h, "", 2), TB_OK); /* empty string is a key */
    assert_int_equal(tb_htab_put_str(&h, "alpha", 3), TB_OK);
    assert_int_equal(h.count, 2);
    assert_true(tb_htab_get_str(&h, "alpha", &v) && v == 3);
    assert_true(tb_htab_get_str(&h, "", &v) && v == 2);
    assert_false(tb_htab_get_str(&h, "alph", &v));
    assert_false(tb_htab_get_str(&h, "alphaa", &v));
    assert_int_equal(tb_htab_put_str(&h, NULL, 1), TB_ERR_ARG);
    assert_int_equal(tb_htab_put(&h, 5, 1), TB_ERR_ARG);
    assert_false(tb_htab_get(&h, 5, &v));
    size_t it = 0;
    tb_htab_entry e;
    int n = 0;
    while (tb_htab_next(&h, &it, &e)) {
        assert_non_null(e.str);
        assert_true(strcmp(e.str, "alpha") == 0 ? e.value == 3 : strcmp(e.str, "") == 0 && e.value == 2);
        n++;
    }
    assert_int_equal(n, 2);
    assert_true(tb_htab_del_str(&h, ""));
    assert_false(tb_htab_del_str(&h, ""));
    assert_int_equal(h.count, 1);
    tb_htab_free(&h);
}

/* Integer keys in three patterns: consecutive, only high bits varying (a weak
 * hash would send all to one slot), and scattered. All are bijections of k. */
static uint64_t key_of(int pattern, uint32_t k)
{
    switch (pattern) {
    case 0: return k;
    case 1: return (uint64_t)k << 40;
    default: return (uint64_t)k * 0xd6e8feb86659fd93ull;
    }
}

#define UNIVERSE (1u << 17)

static void check_iteration(const tb_htab *h, int pattern, const uint8_t *present,
                            const uint64_t *value, size_t nref)
{
    static uint8_t seen[UNIVERSE];
    memset(seen, 0, sizeof seen);
    size_t it = 0, n = 0;
    tb_htab_entry e;
    while (tb_htab_next(h, &it, &e)) {
        /* Recover k: the value stores it in its low 32 bits. */
        uint32_t k = (uint32_t)e.value;
        assert_true(k < UNIVERSE);
        assert_true(e.key == key_of(pattern, k));
        assert_true(present[k]);
        assert_true(value[k] == e.value);
        assert_false(seen[k]);
        seen[k] = 1;
        n++;
    }
    assert_int_equal(n, nref);
    assert_int_equal(h->count, nref);
}

static void test_htab_random_vs_direct_table(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("htab_random", 0x4a54ab1e), 5);
    static uint8_t present[UNIVERSE];
    static uint64_t value[UNIVERSE];
    size_t nops = tb_container_test_n(1000000);
    for (int pattern = 0; pattern < 3; pattern++) {
        memset(present, 0, sizeof present);
        size_t nref = 0;
        tb_htab h;
        tb_htab_init(&h, TB_HTAB_U64);
        /* Universe size varies by phase so the table both grows and churns. */
        uint32_t universe = pattern == 1 ? 5000 : UNIVERSE;
        for (size_t op = 0; op < nops / 3 + 1; op++) {
            uint32_t k = tb_rng_below(&rng, universe);
            uint64_t key = key_of(pattern, k);
            uint32_t r = tb_rng_below(&rng, 100);
            uint64_t v;
            if (r < 45) {
                v = (uint64_t)tb_rng_u32(&rng) << 32 | k;
                assert_int_equal(tb_htab_put(&h, key, v), TB_OK);
                nref += !present[k];
                present[k] = 1;
                value[k] = v;
            } else if (r < 75) {
                assert_int_equal(tb_htab_del(&h, key), present[k]);
                nref -= present[k];
                present[k] = 0;
            } else {
                bool found = tb_htab_get(&h, key, &v);
                assert_int_equal(found, present[k]);
                if (found)
                    assert_true(v == value[k]);
            }
            assert_int_equal(h.count, nref);
            if (op % 100000 == 0)
                check_iteration(&h, pattern, present, value, nref);
        }
        check_iteration(&h, pattern, present, value, nref);
        tb_htab_free(&h);
    }
}

/* 10^6 distinct keys inserted, all found, half deleted, the rest still found. */
static void test_htab_million_entries(void **state)
{
    (void)state;
    size_t n = tb_container_test_n(1000000);
    tb_htab h;
    tb_htab_init(&h, TB_HTAB_U64);
    for (uint64_t k = 0; k < n; k++)
        assert_int_equal(tb_htab_put(&h, k * 0xd6e8feb86659fd93ull, k), TB_OK);
    assert_int_equal(h.count, n);
    assert_true(h.count * 5 <= h.cap * 4);
    uint64_t v;
    for (uint64_t k = 0; k < n; k++) {
        assert_true(tb_htab_get(&h, k * 0xd6e8feb86659fd93ull, &v));
        assert_true(v == k);
    }
    for (uint64_t k = 0; k < n; k += 2)
        assert_true(tb_htab_del(&h, k * 0xd6e8feb86659fd93ull));
    for (uint64_t k = 0; k < n; k++)
        assert_int_equal(tb_htab_get(&h, k * 0xd6e8feb86659fd93ull, &v), k & 1);
    assert_int_equal(h.count, n / 2);
    tb_htab_free(&h);
}

static void test_htab_random_strings(void **state)
{
    (void)state;
    enum { U = 1 << 14 };
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("htab_strings", 0x57a1), 6);
    static uint8_t present[U];
    static uint64_t value[U];
    memset(present, 0, sizeof present);
    size_t nref = 0, max_live = 0;
    tb_htab h;
    tb_htab_init(&h, TB_HTAB_STR);
    char key[48];
    size_t nops = tb_container_test_n(300000);
    for (size_t op = 0; op < nops; op++) {
        uint32_t k = tb_rng_below(&rng, U);
        /* Keys of varied length sharing long prefixes. */
        snprintf(key, sizeof key, "patch/%.*s%u", (int)(k % 23), "xxxxxxxxxxxxxxxxxxxxxxx", k);
        uint32_t r = tb_rng_below(&rng, 100);
        uint64_t v;
        if (r < 40) {
            v = tb_rng_u32(&rng);
            assert_int_equal(tb_htab_put_str(&h, key, v), TB_OK);
            nref += !present[k];
            present[k] = 1;
            value[k] = v;
        } else if (r < 80) {
            assert_int_equal(tb_htab_del_str(&h, key), present[k]);
            nref -= present[k];
            present[k] = 0;
        } else {
            bool found = tb_htab_get_str(&h, key, &v);
            assert_int_equal(found, present[k]);
            if (found)
                assert_true(v == value[k]);
        }
        assert_int_equal(h.count, nref);
        if (h.live_bytes > max_live)
            max_live = h.live_bytes;
        /* Deleted keys are reclaimed: the arena never holds much more than
         * twice the largest live key set plus a chunk. */
        assert_true(h.live_bytes + h.dead_bytes <= 2 * max_live + 8192);
        assert_true(tb_arena_capacity(&h.strings) <= 2 * max_live + 8192 + 2 * TB_ARENA_DEFAULT_CHUNK);
    }
    /* Every reference key is found, every other key is absent. */
    for (uint32_t k = 0; k < U; k++) {
        snprintf(key, sizeof key, "patch/%.*s%u", (int)(k % 23), "xxxxxxxxxxxxxxxxxxxxxxx", k);
        uint64_t v;
        assert_int_equal(tb_htab_get_str(&h, key, &v), present[k]);
        if (present[k])
            assert_true(v == value[k]);
    }
    size_t it = 0, n = 0;
    tb_htab_entry e;
    while (tb_htab_next(&h, &it, &e)) {
        unsigned k;
        assert_int_equal(sscanf(e.str, "patch/%*[x]%u", &k) == 1 || sscanf(e.str, "patch/%u", &k) == 1, 1);
        assert_true(k < U && present[k] && value[k] == e.value);
        n++;
    }
    assert_int_equal(n, nref);
    tb_htab_free(&h);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hash_functions_reference),
        cmocka_unit_test(test_htab_edge_cases),
        cmocka_unit_test(test_htab_string_keys),
        cmocka_unit_test(test_htab_random_vs_direct_table),
        cmocka_unit_test(test_htab_million_entries),
        cmocka_unit_test(test_htab_random_strings),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
