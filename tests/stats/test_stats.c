/* util/stats: counters, distributions, ratios and timers summed exactly over
 * threads; the table report and JSON string escaping. */
#include "tb_test.h"

#include <omp.h>
#include <pthread.h>
#include <string.h>

#include "util/stats/stats.h"

TB_STAT_COUNTER(t_items, "Test/items");
TB_STAT_COUNTER(t_weighted, "Test/weighted");
TB_STAT_DISTRIBUTION(t_dist, "Test/dist");
TB_STAT_DISTRIBUTION(t_known, "Test/known");
TB_STAT_DISTRIBUTION(t_empty, "Test/empty distribution");
TB_STAT_RATIO(t_ratio, "Test/ratio");
TB_STAT_PERCENT(t_percent, "Test/percent");
TB_STAT_MEMORY(t_memory, "Test/memory");
TB_STAT_TIMER(t_timer, "Test/timer");
TB_STAT_COUNTER(t_thread, "Test/from exited threads");
/* Same name and kind as t_items in spirit of a second file: reported as one sum. */
TB_STAT_COUNTER(t_dup_a, "Test/duplicate");
TB_STAT_COUNTER(t_dup_b, "Test/duplicate");

static int64_t tb__get(const char *name, tb_stat_kind kind, int i)
{
    tb_stat_total t;
    assert_int_equal(tb_stats_get(name, kind, &t), TB_OK);
    return t.v[i];
}

static void test_counters_exact_over_omp_threads(void **state)
{
    (void)state;
    const int n = 200000;
    int64_t weighted = 0;
    for (int i = 0; i < n; i++)
        weighted += i % 7;
    omp_set_dynamic(0);
    /* Largest team first: LLVM libomp 14 leaks a little when a later team
     * outgrows an earlier one of 2+ threads, which fails the LeakSanitizer run. */
    const int counts[] = {8, 4, 3, 2, 1};
    for (size_t k = 0; k < sizeof counts / sizeof counts[0]; k++) {
        int nt = counts[k];
        tb_stats_reset();
        int team = 0, busy = 0;
#pragma omp parallel num_threads(nt) reduction(+ : busy)
        {
#pragma omp single
            team = omp_get_num_threads();
            int mine = 0;
            /* Static schedule: every thread gets a contiguous share, so each
             * one's minimum and maximum differ and the merge must pick right. */
#pragma omp for schedule(static)
            for (int i = 0; i < n; i++) {
                TB_STAT_INC(t_items);
                tb_stat_add(&t_weighted, i % 7);
                tb_stat_sample(&t_dist, i);
                mine++;
            }
            busy += mine > 0;
        }
        /* The work really was spread over nt threads. */
        assert_int_equal(team, nt);
        assert_int_equal(busy, nt);
        assert_int_equal(tb__get("Test/items", TB_STAT_KIND_COUNTER, 0), n);
        assert_int_equal(tb__get("Test/weighted", TB_STAT_KIND_COUNTER, 0), weighted);
        assert_int_equal(tb__get("Test/dist", TB_STAT_KIND_DISTRIBUTION, 0), n);
        assert_int_equal(tb__get("Test/dist", TB_STAT_KIND_DISTRIBUTION, 1), (int64_t)n * (n - 1) / 2);
        assert_int_equal(tb__get("Test/dist", TB_STAT_KIND_DISTRIBUTION, 2), 0);
        assert_int_equal(tb__get("Test/dist", TB_STAT_KIND_DISTRIBUTION, 3), n - 1);
    }
}

static void *tb__thread_body(void *arg)
{
    int n = *(const int *)arg;
    for (int i = 0; i < n; i++)
        TB_STAT_INC(t_thread);
    return NULL;
}

/* Counts of threads that have ended must survive them (folded at thread exit). */
static void test_counts_survive_thread_exit(void **state)
{
    (void)state;
    tb_stats_reset();
    pthread_t th[4];
    int per = 12345;
    for (int i = 0; i < 4; i++)
        assert_int_equal(pthread_create(&th[i], NULL, tb__thread_body, &per), 0);
    for (int i = 0; i < 4; i++)
        assert_int_equal(pthread_join(th[i], NULL), 0);
    TB_STAT_INC(t_thread); /* and this thread's own */
    assert_int_equal(tb__get("Test/from exited threads", TB_STAT_KIND_COUNTER, 0), 4 * per + 1);
    /* tb_stats_counter: the same total; 0 and no error for a name nobody declared */
    assert_int_equal(tb_stats_counter("Test/from exited threads"), 4 * per + 1);
    tb_clear_error();
    assert_int_equal(tb_stats_counter("Test/no such counter"), 0);
    assert_string_equal(tb_last_error(), "");
}

static void test_distribution_exact(void **state)
{
    (void)state;
    tb_stats_reset();
    const int64_t xs[] = {5, -3, 12, 7, 7};
    for (int i = 0; i < 5; i++)
        tb_stat_sample(&t_known, xs[i]);
    tb_stat_total t;
    assert_int_equal(tb_stats_get("Test/known", TB_STAT_KIND_DISTRIBUTION, &t), TB_OK);
    assert_int_equal(t.v[0], 5);
    assert_int_equal(t.v[1], 28);
    assert_int_equal(t.v[2], -3);
    assert_int_equal(t.v[3], 12);
    /* The report's mean (28 / 5 = 5.6) appears in the table. */
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    assert_non_null(f);
    assert_int_equal(tb_stats_print(f), TB_OK);
    fclose(f);
    assert_non_null(strstr(buf, "5.600 mean [min -3, max 12] over 5 samples"));
    assert_null(strstr(buf, "empty distribution")); /* nothing recorded: not shown */
    free(buf);
    assert_int_equal(tb_stats_get("Test/empty distribution", TB_STAT_KIND_DISTRIBUTION, &t), TB_OK);
    assert_int_equal(t.v[0], 0);
    assert_int_equal(tb_stats_get("Test/known", TB_STAT_KIND_COUNTER, &t), TB_ERR_NOT_FOUND);
}

static void test_ratio_percent_memory_duplicates(void **state)
{
    (void)state;
    tb_stats_reset();
    tb_stat_ratio_add(&t_ratio, 3, 4);
    tb_stat_ratio_add(&t_ratio, 1, 4);
    tb_stat_ratio_add(&t_percent, 1, 8);
    tb_stat_add(&t_memory, 3 * 1024 * 1024);
    tb_stat_add(&t_memory, -1024 * 1024);
    tb_stat_add(&t_dup_a, 2);
    tb_stat_add(&t_dup_b, 5);
    assert_int_equal(tb__get("Test/ratio", TB_STAT_KIND_RATIO, 0), 4);
    assert_int_equal(tb__get("Test/ratio", TB_STAT_KIND_RATIO, 1), 8);
    assert_int_equal(tb__get("Test/memory", TB_STAT_KIND_MEMORY, 0), 2 * 1024 * 1024);
    assert_int_equal(tb__get("Test/duplicate", TB_STAT_KIND_COUNTER, 0), 7);
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    assert_int_equal(tb_stats_print(f), TB_OK);
    fclose(f);
    assert_non_null(strstr(buf, "0.5000 (4 / 8)"));
    assert_non_null(strstr(buf, "12.50% (1 / 8)"));
    assert_non_null(strstr(buf, "2.00 MiB"));
    /* One line for the two same-named declarations. */
    char *first = strstr(buf, "duplicate");
    assert_non_null(first);
    assert_null(strstr(first + 1, "duplicate"));
    free(buf);
}

static int tb__scoped(int early)
{
    TB_TIMER_SCOPE(t_timer);
    if (early)
        return 1; /* the cleanup attribute stops the timer here too */
    return 0;
}

/* Timers: call counts exact, time accumulated and nonnegative (durations are
 * not asserted: the machine may be arbitrarily slow or fast). */
static void test_timers_count_calls(void **state)
{
    (void)state;
    tb_stats_reset();
    for (int i = 0; i < 3; i++) {
        tb_timer_token tok = tb_timer_start(&t_timer);
        volatile double x = 0;
        for (int j = 0; j < 1000; j++)
            x += j;
        (void)x;
        assert_true(tb_timer_stop(tok) >= 0.0);
    }
    tb__scoped(1);
    tb__scoped(0);
    assert_int_equal(tb__get("Test/timer", TB_STAT_KIND_TIMER, 0), 5);
    int64_t ns5 = tb__get("Test/timer", TB_STAT_KIND_TIMER, 1);
    assert_true(ns5 >= 0);
#pragma omp parallel for num_threads(4)
    for (int i = 0; i < 100; i++)
        tb_timer_stop(tb_timer_start(&t_timer));
    assert_int_equal(tb__get("Test/timer", TB_STAT_KIND_TIMER, 0), 105);
    assert_true(tb__get("Test/timer", TB_STAT_KIND_TIMER, 1) >= ns5); /* accumulates */
}

static void test_disable_and_reset(void **state)
{
    (void)state;
    tb_stats_reset();
    TB_STAT_INC(t_items);
    tb_stats_set_enabled(0);
    assert_false(tb_stats_enabled());
    TB_STAT_INC(t_items);
    tb_stat_sample(&t_known, 99);
    tb_timer_token tok = tb_timer_start(&t_timer);
    assert_null(tok.timer);
    assert_true(tb_timer_stop(tok) == 0.0);
    tb_stats_set_enabled(1);
    assert_int_equal(tb__get("Test/items", TB_STAT_KIND_COUNTER, 0), 1);
    assert_int_equal(tb__get("Test/known", TB_STAT_KIND_DISTRIBUTION, 0), 0);
    assert_int_equal(tb__get("Test/timer", TB_STAT_KIND_TIMER, 0), 0);
    tb_stats_reset();
    assert_int_equal(tb__get("Test/items", TB_STAT_KIND_COUNTER, 0), 0);
}

/* A stat registered at run time (not through the macros) counts as well. */
static void test_runtime_registration(void **state)
{
    (void)state;
    static tb_stat dyn = {"Test/registered at run time", TB_STAT_KIND_COUNTER, 0, NULL};
    tb_stat_add(&dyn, 3); /* first use registers */
    assert_int_equal(tb_stat_register(&dyn), TB_OK); /* twice is harmless */
    assert_int_equal(tb__get("Test/registered at run time", TB_STAT_KIND_COUNTER, 0), 3);
    tb_stat bad = {NULL, TB_STAT_KIND_COUNTER, 0, NULL};
    assert_int_equal(tb_stat_register(&bad), TB_ERR_ARG);
}

TB_STAT_COUNTER(g_alpha_one, "Alpha/one");
TB_STAT_COUNTER(g_beta_two, "Beta/two");
TB_STAT_COUNTER(g_alpha_three, "Alpha/three hundred");
TB_STAT_COUNTER(g_plain, "plain");
TB_STAT_COUNTER(g_unused, "Alpha/never touched");
TB_STAT_COUNTER(g_alp, "Alp/prefix of another category");

/* Index of the line that equals `s`, or -1. */
static int tb__find_line(char **lines, int n, const char *s)
{
    for (int i = 0; i < n; i++)
        if (strcmp(lines[i], s) == 0)
            return i;
    return -1;
}

/* Index of the line starting with `prefix`, or -1. */
static int tb__find_prefix(char **lines, int n, const char *prefix)
{
    for (int i = 0; i < n; i++)
        if (strncmp(lines[i], prefix, strlen(prefix)) == 0)
            return i;
    return -1;
}

static void test_table_groups_by_category(void **state)
{
    (void)state;
    tb_stats_reset();
    tb_stat_add(&g_alpha_one, 1);
    tb_stat_add(&g_beta_two, 22);
    tb_stat_add(&g_alpha_three, 300);
    tb_stat_add(&g_plain, 4444);
    tb_stat_add(&g_alp, 5);
    assert_int_equal(tb_stats_set_value("rays", 1000), TB_OK);
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    assert_int_equal(tb_stats_print(f), TB_OK);
    fclose(f);
    print_message("%s", buf);

    char *lines[256];
    int n = 0;
    for (char *save = NULL, *l = strtok_r(buf, "\n", &save); l && n < 256; l = strtok_r(NULL, "\n", &save))
        lines[n++] = l;
    int alpha = tb__find_line(lines, n, "  Alpha"), beta = tb__find_line(lines, n, "  Beta");
    int general = tb__find_line(lines, n, "  General");
    int alp = tb__find_line(lines, n, "  Alp");
    assert_true(alpha >= 0 && beta >= 0 && general >= 0 && alp >= 0);
    /* "Alp" sorts first and is a prefix of "Alpha": its group holds only its own entry. */
    assert_true(alp < alpha);
    assert_int_equal(tb__find_prefix(lines, n, "    prefix of another category "), alp + 1);
    assert_int_equal(alpha, alp + 2);
    int one = tb__find_prefix(lines, n, "    one "), three = tb__find_prefix(lines, n, "    three hundred ");
    int two = tb__find_prefix(lines, n, "    two "), plain = tb__find_prefix(lines, n, "    plain ");
    /* Each entry sits under its own category header, before the next header. */
    assert_true(alpha < one && alpha < three && one < beta && three < beta);
    assert_true(beta < two);
    assert_true(general < plain);
    for (int i = 0; i < n; i++) /* each header once */
        if (i != alpha)
            assert_string_not_equal(lines[i], "  Alpha");
    assert_int_equal(tb__find_prefix(lines, n, "    never touched"), -1);
    /* Values start in one column. */
    const char *vals[] = {"1", "22", "300", "4444"};
    int at[] = {one, two, three, plain};
    int col = -1;
    for (int i = 0; i < 4; i++) {
        size_t L = strlen(lines[at[i]]), V = strlen(vals[i]);
        assert_true(L > V);
        assert_string_equal(lines[at[i]] + L - V, vals[i]);
        assert_true(lines[at[i]][L - V - 1] == ' ');
        if (col < 0)
            col = (int)(L - V);
        assert_int_equal((int)(L - V), col);
    }
    int rays = tb__find_prefix(lines, n, "    rays ");
    assert_true(rays > tb__find_line(lines, n, "Run values:"));
    free(buf);
    tb_stats_reset();
}

static char *tb__json_string(const char *s)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    tb_json_write_string(f, s);
    fclose(f);
    return buf;
}

#define tb__assert_json(in, expected)                                                      \
    do {                                                                                   \
        char *got_ = tb__json_string(in);                                                  \
        assert_string_equal(got_, expected);                                               \
        free(got_);                                                                        \
    } while (0)

/* Expected strings follow RFC 8259 section 7 (escapes) and RFC 3629 (which
 * byte sequences are UTF-8). */
static void test_json_string_escapes(void **state)
{
    (void)state;
    tb__assert_json("plain", "\"plain\"");
    tb__assert_json("", "\"\"");
    tb__assert_json("a\"b\\c/d", "\"a\\\"b\\\\c/d\"");
    tb__assert_json("l1\nl2\r\t\b\f", "\"l1\\nl2\\r\\t\\b\\f\"");
    tb__assert_json("\x01\x1f\x7f", "\"\\u0001\\u001f\x7f\"");
    tb__assert_json("caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80", "\"caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80\"");
    tb__assert_json("\xff", "\"\\ufffd\"");                       /* never valid */
    tb__assert_json("\xc0\x80", "\"\\ufffd\\ufffd\"");             /* overlong NUL */
    tb__assert_json("\xed\xa0\x80", "\"\\ufffd\\ufffd\\ufffd\"");   /* surrogate U+D800 */
    tb__assert_json("\xf4\x90\x80\x80", "\"\\ufffd\\ufffd\\ufffd\\ufffd\""); /* > U+10FFFF */
    tb__assert_json("\xe2\x82", "\"\\ufffd\\ufffd\"");             /* truncated at the end */
    tb__assert_json(NULL, "\"\"");
}

static void test_values_refuse_reserved_keys(void **state)
{
    (void)state;
    assert_int_equal(tb_stats_set_value("counters", 1.0), TB_ERR_ARG);
    assert_int_equal(tb_stats_set_string("provenance", "x"), TB_ERR_ARG);
    assert_int_equal(tb_stats_set_value("", 1.0), TB_ERR_ARG);
    assert_int_equal(tb_stats_set_string("k", NULL), TB_ERR_ARG);
    assert_int_equal(tb_stats_set_value("k", 1.0), TB_OK);
    assert_int_equal(tb_stats_set_string("k", "replaced"), TB_OK);
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    assert_int_equal(tb_stats_write_json(f, NULL), TB_OK);
    fclose(f);
    assert_non_null(strstr(buf, "\"k\": \"replaced\""));
    assert_non_null(strstr(buf, "\"provenance\": null"));
    free(buf);
    tb_stats_reset();
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_counters_exact_over_omp_threads),
        cmocka_unit_test(test_counts_survive_thread_exit),
        cmocka_unit_test(test_distribution_exact),
        cmocka_unit_test(test_ratio_percent_memory_duplicates),
        cmocka_unit_test(test_timers_count_calls),
        cmocka_unit_test(test_disable_and_reset),
        cmocka_unit_test(test_runtime_registration),
        cmocka_unit_test(test_table_groups_by_category),
        cmocka_unit_test(test_json_string_escapes),
        cmocka_unit_test(test_values_refuse_reserved_keys),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
