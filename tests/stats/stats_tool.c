/* Driver for the util/stats script tests (and a quick overhead measurement):
 *
 *   stats_tool sha256 FILE...        print "<hex>  <file>" like sha256sum
 *   stats_tool json OUT SCENE ARG... write a report of a known workload to OUT
 *   stats_tool bench [N]             time N counter increments, 1 and all threads
 */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util/stats/provenance.h"
#include "util/stats/stats.h"

TB_STAT_COUNTER(tool_items, "Tool/items");
TB_STAT_COUNTER(tool_odd, "Tool/odd \"name\" \\ with\ttab");
TB_STAT_DISTRIBUTION(tool_sizes, "Tool/sizes");
TB_STAT_RATIO(tool_ratio, "Tool/hits per ray");
TB_STAT_PERCENT(tool_percent, "Tool/shadow rays blocked");
TB_STAT_MEMORY(tool_memory, "Tool/memory");
TB_STAT_TIMER(tool_phase, "Tool/phase");
TB_STAT_COUNTER(tool_unused, "Tool/never touched");
TB_STAT_COUNTER(bench_counter, "Bench/increments");

static int tb__sha256(int argc, char **argv)
{
    int bad = 0;
    for (int i = 2; i < argc; i++) {
        char hex[TB_SHA256_HEX_SIZE];
        if (tb_sha256_file(argv[i], hex)) {
            fprintf(stderr, "stats_tool: %s\n", tb_last_error());
            bad = 1;
            continue;
        }
        printf("%s  %s\n", hex, argv[i]);
    }
    return bad;
}

static int tb__json(int argc, char **argv)
{
    if (argc < 4) {
        fprintf(stderr, "usage: stats_tool json OUT SCENE [ARG...]\n");
        return 2;
    }
#pragma omp parallel for num_threads(4)
    for (int i = 0; i < 1000; i++)
        TB_STAT_INC(tool_items);
    tb_stat_add(&tool_odd, 7);
    for (int i = 1; i <= 10; i++)
        tb_stat_sample(&tool_sizes, i);
    tb_stat_ratio_add(&tool_ratio, 3, 2);
    tb_stat_ratio_add(&tool_percent, 1, 4);
    tb_stat_add(&tool_memory, 4096);
    for (int i = 0; i < 3; i++)
        tb_timer_stop(tb_timer_start(&tool_phase));

    tb_provenance p;
    if (tb_provenance_init(&p, argc, argv) || tb_provenance_hash_file(&p, argv[3])) {
        fprintf(stderr, "stats_tool: %s\n", tb_last_error());
        return 1;
    }
    tb_provenance_set_seed(&p, 42);
    tb_provenance_set_options(&p, "spp=4 \"quoted\"");
    tb_stats_set_value("rays", 1000);
    tb_stats_set_value("seconds", 0.5);
    tb_stats_set_value("rays_per_second", 1000 / 0.5);
    tb_stats_set_value("third", 1.0 / 3.0);
    tb_stats_set_value("not_a_number", 0.0 / 0.0);
    tb_stats_set_string("note", "quote \" backslash \\ newline \n tab \t bell \a caf\xc3\xa9");
    tb_stats_set_string("bad_utf8", "x\xffy");
    tb_status st = tb_stats_write_json_file(argv[2], &p);
    tb_provenance_free(&p);
    if (st) {
        fprintf(stderr, "stats_tool: %s\n", tb_last_error());
        return 1;
    }
    return 0;
}

static int tb__bench(int argc, char **argv)
{
    long n = argc > 2 ? atol(argv[2]) : 100000000L;
    int64_t t0 = tb_stats_now_ns();
    for (long i = 0; i < n; i++)
        TB_STAT_INC(bench_counter);
    int64_t t1 = tb_stats_now_ns();
    int nt = omp_get_max_threads();
#pragma omp parallel for
    for (long i = 0; i < n; i++)
        TB_STAT_INC(bench_counter);
    int64_t t2 = tb_stats_now_ns();
    tb_stat_total t;
    tb_stats_get("Bench/increments", TB_STAT_KIND_COUNTER, &t);
    printf("1 thread: %.2f ns/increment; %d threads: %.2f ns/increment (wall / n); total %lld (expect %ld)\n",
           (double)(t1 - t0) / (double)n, nt, (double)(t2 - t1) / (double)n, (long long)t.v[0], 2 * n);
    return t.v[0] == 2 * n ? 0 : 1;
}

int main(int argc, char **argv)
{
    if (argc >= 2 && strcmp(argv[1], "sha256") == 0)
        return tb__sha256(argc, argv);
    if (argc >= 2 && strcmp(argv[1], "json") == 0)
        return tb__json(argc, argv);
    if (argc >= 2 && strcmp(argv[1], "bench") == 0)
        return tb__bench(argc, argv);
    fprintf(stderr, "usage: stats_tool sha256 FILE... | json OUT SCENE [ARG...] | bench [N]\n");
    return 2;
}
