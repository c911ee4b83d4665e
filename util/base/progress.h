/* A progress bar for long work, safe to update from many threads:
 *
 *     render [############..................]  42%  12.3 s elapsed, ETA 17.0 s
 *
 * It draws on stderr only when stderr is a terminal and TB_NO_PROGRESS is not
 * set, so logs and pipes stay clean; tests can force it onto any stream. */
#ifndef TB_UTIL_BASE_PROGRESS_H
#define TB_UTIL_BASE_PROGRESS_H

#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include "util/base/error.h"

/* Flags for tb_progress_start. */
enum {
    TB_PROGRESS_FORCE = 1, /* draw even if the stream is not a terminal or TB_NO_PROGRESS is set */
};

/* Minimum time between two redraws. */
#define TB_PROGRESS_INTERVAL_NS 100000000

/* One progress bar; fields are private, use the functions. */
typedef struct tb_progress {
    char label[64];
    int64_t total;                /* units of work in all (>= 0) */
    _Atomic int64_t done;         /* units finished so far */
    _Atomic int64_t next_draw_ns; /* the first tb_progress_add after this time redraws */
    atomic_flag drawing;          /* held by the thread that is drawing; others skip */
    int64_t start_ns;             /* CLOCK_MONOTONIC at tb_progress_start */
    FILE *out;                    /* where to draw; NULL when the bar is off */
    int last_len;                 /* length of the last line drawn (to blank leftovers) */
} tb_progress;

/* Starts a bar over `total` units labelled `label`. `out` NULL means stderr.
 * The bar is drawn if `flags` has TB_PROGRESS_FORCE, or if `out` is a terminal
 * and the environment variable TB_NO_PROGRESS is unset; otherwise every call
 * is a cheap no-op apart from counting. */
tb_status tb_progress_start(tb_progress *p, const char *label, int64_t total, FILE *out, unsigned flags);

/* Nonzero if `p` draws anything. */
int tb_progress_active(const tb_progress *p);

/* Adds `n` finished units (any thread, lock-free). Redraws at most every
 * TB_PROGRESS_INTERVAL_NS, from whichever thread gets there first; the others
 * never wait. Call it per tile or row, not per ray: the count is one shared atomic. */
void tb_progress_add(tb_progress *p, int64_t n);

/* Units finished so far. */
int64_t tb_progress_done(const tb_progress *p);

/* Draws the final line (elapsed time, no ETA) and a newline. Call once, after
 * every tb_progress_add has returned. */
void tb_progress_finish(tb_progress *p);

#endif
