/* Run statistics declared where the work happens (after pbrt-v4's STAT_COUNTER):
 *
 *     TB_STAT_COUNTER(tb__nodes_visited, "BVH/nodes visited");
 *     ...
 *     TB_STAT_INC(tb__nodes_visited);           // on the hot path
 *
 * A declaration registers itself before main() through a constructor, so no
 * central list names every counter. Updates go to per-thread storage (no lock,
 * no shared cache line), and a report sums all threads: tb_stats_print() for
 * people, tb_stats_write_json() for scripts. See docs/stats.md. */
#ifndef TB_UTIL_STATS_STATS_H
#define TB_UTIL_STATS_STATS_H

#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include "util/base/error.h"

struct tb_provenance;

/* What a statistic measures, which decides how it is updated and reported. */
typedef enum tb_stat_kind {
    TB_STAT_KIND_COUNTER = 0,  /* a sum of increments (tb_stat_add) */
    TB_STAT_KIND_MEMORY,       /* a sum of bytes, reported in KiB/MiB (tb_stat_add) */
    TB_STAT_KIND_DISTRIBUTION, /* integer samples: count, sum, min, max, mean (tb_stat_sample) */
    TB_STAT_KIND_RATIO,        /* numerator / denominator (tb_stat_ratio_add) */
    TB_STAT_KIND_PERCENT,      /* like a ratio, reported as 100 * num / den */
    TB_STAT_KIND_TIMER,        /* calls and accumulated seconds (tb_timer_start/stop) */
} tb_stat_kind;

/* A statistic's static descriptor; declare with the TB_STAT_* macros below. */
typedef struct tb_stat {
    const char *name;          /* "Category/what": the report groups by the part before '/' */
    tb_stat_kind kind;
    _Atomic unsigned slot;     /* index of this stat's cell in every thread's block; 0 = not registered */
    struct tb_stat *next;      /* registry list link (owned by the registry) */
} tb_stat;

/* The TB_STAT_* macros define a file-scope `static tb_stat var` and a
 * constructor that registers it before main(). Use at file scope, followed by a
 * semicolon. Two declarations with the same name and kind (in different files)
 * are reported as one sum. Caveat: when linking the static library, an object
 * file is only pulled in if the program references one of its symbols, so a
 * counter in an otherwise unused file is not registered (and has counted
 * nothing); counters in the file that does the work are always present. */
#define TB__STAT_DEFINE(var, name_, kind_)                                                 \
    static tb_stat var;                                                                    \
    __attribute__((constructor)) static void tb__stat_ctor_##var(void) { tb_stat_register(&var); } \
    static tb_stat var = {(name_), (kind_), 0, NULL}

/* A counter (sum of tb_stat_add increments). */
#define TB_STAT_COUNTER(var, name) TB__STAT_DEFINE(var, name, TB_STAT_KIND_COUNTER)
/* A memory counter in bytes (tb_stat_add; negative to record a release). */
#define TB_STAT_MEMORY(var, name) TB__STAT_DEFINE(var, name, TB_STAT_KIND_MEMORY)
/* An integer distribution (tb_stat_sample): count, sum, min, max, mean. */
#define TB_STAT_DISTRIBUTION(var, name) TB__STAT_DEFINE(var, name, TB_STAT_KIND_DISTRIBUTION)
/* A ratio num/den (tb_stat_ratio_add). */
#define TB_STAT_RATIO(var, name) TB__STAT_DEFINE(var, name, TB_STAT_KIND_RATIO)
/* A percentage 100 num/den (tb_stat_ratio_add). */
#define TB_STAT_PERCENT(var, name) TB__STAT_DEFINE(var, name, TB_STAT_KIND_PERCENT)
/* A timer (tb_timer_start / tb_timer_stop or TB_TIMER_SCOPE). */
#define TB_STAT_TIMER(var, name) TB__STAT_DEFINE(var, name, TB_STAT_KIND_TIMER)

/* Adds `s` to the registry (the macros call this; also usable for a tb_stat
 * built at run time, which must then live until the program ends). Registering
 * twice is harmless. TB_ERR_ARG for a NULL name, TB_ERR_NOMEM when full. */
tb_status tb_stat_register(tb_stat *s);

/* ---------------------------------------------------------------- hot path
 * Everything below up to the report functions is inline so that an update is a
 * thread-local load, add and store. Names with tb__ are internals. */

/* Cells per chunk of a thread's block, and chunks per block (max stats = product - 1). */
#define TB__STAT_CHUNK 64
#define TB__STAT_MAX_CHUNKS 256

/* One statistic's per-thread state; the meaning of v[] depends on the kind:
 * counter/memory v[0] = sum; distribution v[0..3] = count, sum, min, max;
 * ratio/percent v[0..1] = num, den; timer v[0..1] = calls, nanoseconds.
 * Only the owning thread writes; the report reads (hence relaxed atomics). */
typedef struct tb__stat_cell {
    _Atomic int64_t v[4];
} tb__stat_cell;

/* A thread's cells, in chunks that never move once allocated, so the report can
 * read them while the thread keeps counting. */
typedef struct tb__stat_block {
    _Atomic(tb__stat_cell *) chunks[TB__STAT_MAX_CHUNKS];
    struct tb__stat_block *next; /* list of live blocks (registry lock) */
} tb__stat_block;

extern _Thread_local tb__stat_block *tb__stat_tls; /* this thread's block, NULL until first use */
extern atomic_int tb__stats_on;                     /* the global enable switch */

/* Creates this thread's block / chunk (first use); NULL if the stat cannot be counted. */
tb__stat_cell *tb__stat_cell_slow(tb_stat *s);

/* This thread's cell for `s`, or NULL (registry full, out of memory). */
static inline tb__stat_cell *tb__stat_cell_of(tb_stat *s)
{
    unsigned slot = atomic_load_explicit(&s->slot, memory_order_relaxed);
    tb__stat_block *b = tb__stat_tls;
    if (slot && b) {
        tb__stat_cell *c = atomic_load_explicit(&b->chunks[slot / TB__STAT_CHUNK], memory_order_relaxed);
        if (c)
            return &c[slot % TB__STAT_CHUNK];
    }
    return tb__stat_cell_slow(s);
}

/* v += n on a cell only this thread writes: a plain load/add/store, no lock prefix. */
static inline void tb__stat_bump(_Atomic int64_t *v, int64_t n)
{
    atomic_store_explicit(v, atomic_load_explicit(v, memory_order_relaxed) + n, memory_order_relaxed);
}

/* Nonzero when statistics are being collected (the default). */
static inline int tb_stats_enabled(void)
{
    return atomic_load_explicit(&tb__stats_on, memory_order_relaxed);
}

/* Adds `n` to a counter or memory counter. */
static inline void tb_stat_add(tb_stat *s, int64_t n)
{
    if (!tb_stats_enabled())
        return;
    tb__stat_cell *c = tb__stat_cell_of(s);
    if (c)
        tb__stat_bump(&c->v[0], n);
}

/* Adds one to counter `var` (the variable, not its address). */
#define TB_STAT_INC(var) tb_stat_add(&(var), 1)

/* Records one sample `x` of a distribution. */
static inline void tb_stat_sample(tb_stat *s, int64_t x)
{
    if (!tb_stats_enabled())
        return;
    tb__stat_cell *c = tb__stat_cell_of(s);
    if (!c)
        return;
    int64_t count = atomic_load_explicit(&c->v[0], memory_order_relaxed);
    int64_t lo = atomic_load_explicit(&c->v[2], memory_order_relaxed);
    int64_t hi = atomic_load_explicit(&c->v[3], memory_order_relaxed);
    if (count == 0 || x < lo)
        atomic_store_explicit(&c->v[2], x, memory_order_relaxed);
    if (count == 0 || x > hi)
        atomic_store_explicit(&c->v[3], x, memory_order_relaxed);
    tb__stat_bump(&c->v[1], x);
    atomic_store_explicit(&c->v[0], count + 1, memory_order_relaxed);
}

/* Adds `num` to the numerator and `den` to the denominator of a ratio or percentage. */
static inline void tb_stat_ratio_add(tb_stat *s, int64_t num, int64_t den)
{
    if (!tb_stats_enabled())
        return;
    tb__stat_cell *c = tb__stat_cell_of(s);
    if (c) {
        tb__stat_bump(&c->v[0], num);
        tb__stat_bump(&c->v[1], den);
    }
}

/* ---------------------------------------------------------------- timers */

/* A running timing, returned by tb_timer_start and consumed by tb_timer_stop. */
typedef struct tb_timer_token {
    tb_stat *timer;    /* NULL when statistics were disabled at the start */
    int64_t start_ns;  /* CLOCK_MONOTONIC at the start */
} tb_timer_token;

/* CLOCK_MONOTONIC in nanoseconds (for timers and the progress bar). */
int64_t tb_stats_now_ns(void);

/* Starts timing one call of `timer`. */
static inline tb_timer_token tb_timer_start(tb_stat *timer)
{
    tb_timer_token t = {NULL, 0};
    if (tb_stats_enabled()) {
        t.timer = timer;
        t.start_ns = tb_stats_now_ns();
    }
    return t;
}

/* Adds the time since `t` was started and one call to its timer; returns the
 * elapsed seconds (0 if statistics were disabled at the start). */
static inline double tb_timer_stop(tb_timer_token t)
{
    if (!t.timer)
        return 0.0;
    int64_t ns = tb_stats_now_ns() - t.start_ns;
    if (ns < 0)
        ns = 0;
    tb__stat_cell *c = tb__stat_cell_of(t.timer);
    if (c) {
        tb__stat_bump(&c->v[0], 1);
        tb__stat_bump(&c->v[1], ns);
    }
    return (double)ns * 1e-9;
}

/* Cleanup handler behind TB_TIMER_SCOPE. */
static inline void tb__timer_scope_end(tb_timer_token *t) { (void)tb_timer_stop(*t); }

#define TB__CAT2(a, b) a##b
#define TB__CAT(a, b) TB__CAT2(a, b)
/* Times the rest of the enclosing block with `var` (a TB_STAT_TIMER); the
 * timer stops however the block is left (return, break, goto). */
#define TB_TIMER_SCOPE(var)                                                                \
    __attribute__((cleanup(tb__timer_scope_end), unused)) tb_timer_token TB__CAT(tb__scope_timer_, __LINE__) = \
        tb_timer_start(&(var))

/* ---------------------------------------------------------------- control */

/* Turns collection on (nonzero) or off; updates while off are dropped. */
void tb_stats_set_enabled(int on);

/* Zeroes every statistic in every thread and forgets the run-level values.
 * Exact only while no other thread is updating statistics. */
void tb_stats_reset(void);

/* ---------------------------------------------------------------- run-level values */

/* Sets (or replaces) a top-level number in the JSON report, e.g. "rays",
 * "rays_per_second". Keys used by the report itself ("provenance", "counters",
 * "memory", "distributions", "ratios", "percentages", "timers") are refused
 * (TB_ERR_ARG). A NaN or infinity is written as null. */
tb_status tb_stats_set_value(const char *key, double value);

/* Sets (or replaces) a top-level string in the JSON report. */
tb_status tb_stats_set_string(const char *key, const char *value);

/* The number set for `key` by tb_stats_set_value; TB_ERR_NOT_FOUND if none
 * (or it holds a string). */
tb_status tb_stats_get_value(const char *key, double *out);

/* ---------------------------------------------------------------- snapshots */

/* One statistic summed over all threads (and over same-named declarations). */
typedef struct tb_stat_total {
    const char *name;    /* the declared name (points at the descriptor's string) */
    tb_stat_kind kind;
    int64_t v[4];        /* as tb__stat_cell: sum | count,sum,min,max | num,den | calls,ns */
} tb_stat_total;

/* The current total of the statistic called `name` of kind `kind`; TB_ERR_NOT_FOUND
 * if none is registered. */
tb_status tb_stats_get(const char *name, tb_stat_kind kind, tb_stat_total *out);

/* The total of the counter called `name`, 0 if none is registered (no error set). */
int64_t tb_stats_counter(const char *name);

/* ---------------------------------------------------------------- reports */

/* Prints a table grouped by category (the name before the first '/'), with
 * aligned columns; statistics that recorded nothing are left out. */
tb_status tb_stats_print(FILE *out);

/* Writes the JSON report to `out`: {"provenance": {...} or null, "counters": {...},
 * "memory": {...}, "distributions": {...}, "ratios": {...}, "percentages": {...},
 * "timers": {...}, <run-level values>...}. `prov` may be NULL. */
tb_status tb_stats_write_json(FILE *out, const struct tb_provenance *prov);

/* tb_stats_write_json to `path`, all or nothing (util/base/outfile.h). */
tb_status tb_stats_write_json_file(const char *path, const struct tb_provenance *prov);

/* Writes `s` as a JSON string literal (quotes included): '"', '\\' and control
 * characters escaped, valid UTF-8 passed through, invalid bytes as U+FFFD. */
void tb_json_write_string(FILE *out, const char *s);

#endif
