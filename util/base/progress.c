#include "util/base/progress.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#define TB__BAR_WIDTH 30

static int64_t tb__now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

tb_status tb_progress_start(tb_progress *p, const char *label, int64_t total, FILE *out, unsigned flags)
{
    if (!p || total < 0)
        return tb_error(TB_ERR_ARG, "tb_progress_start: bad arguments");
    memset(p, 0, sizeof *p);
    snprintf(p->label, sizeof p->label, "%s", label ? label : "");
    p->total = total;
    atomic_init(&p->done, 0);
    atomic_flag_clear(&p->drawing);
    p->start_ns = tb__now_ns();
    /* The first add draws at once; later ones every TB_PROGRESS_INTERVAL_NS. */
    atomic_init(&p->next_draw_ns, p->start_ns);
    if (!out)
        out = stderr;
    int draw = (flags & TB_PROGRESS_FORCE) != 0;
    if (!draw) {
        int fd = fileno(out);
        draw = fd >= 0 && isatty(fd) && !getenv("TB_NO_PROGRESS");
    }
    p->out = draw ? out : NULL;
    return TB_OK;
}

int tb_progress_active(const tb_progress *p) { return p->out != NULL; }

int64_t tb_progress_done(const tb_progress *p)
{
    return atomic_load_explicit(&((tb_progress *)p)->done, memory_order_relaxed);
}

/* "12.3 s", "4 min 05 s", "2 h 03 min": short and still exact enough for an ETA. */
static void tb__fmt_time(char *buf, size_t n, double s)
{
    if (s < 100.0)
        snprintf(buf, n, "%.1f s", s);
    else if (s < 3600.0)
        snprintf(buf, n, "%d min %02d s", (int)(s / 60.0), (int)s % 60);
    else
        snprintf(buf, n, "%d h %02d min", (int)(s / 3600.0), ((int)s / 60) % 60);
}

/* Draws one line for `done` units; `final` adds the newline and drops the ETA.
 * Only one thread at a time gets here (the `drawing` flag). */
static void tb__draw(tb_progress *p, int64_t done, int64_t now, int final)
{
    double frac = p->total > 0 ? (double)done / (double)p->total : 1.0;
    if (frac > 1.0)
        frac = 1.0;
    if (frac < 0.0)
        frac = 0.0;
    int fill = (int)(frac * TB__BAR_WIDTH);
    char bar[TB__BAR_WIDTH + 1];
    for (int i = 0; i < TB__BAR_WIDTH; i++)
        bar[i] = i < fill ? '#' : '.';
    bar[TB__BAR_WIDTH] = '\0';
    double elapsed = (double)(now - p->start_ns) * 1e-9;
    char el[32], eta[32];
    tb__fmt_time(el, sizeof el, elapsed);
    char line[256];
    int len;
    /* Floor, so 100% is shown only when all the work is done. */
    int pct = (int)(frac * 100.0);
    if (final) {
        len = snprintf(line, sizeof line, "%s [%s] %3d%%  %s elapsed", p->label, bar, pct, el);
    } else if (done > 0) {
        tb__fmt_time(eta, sizeof eta, elapsed * (1.0 - frac) / frac);
        len = snprintf(line, sizeof line, "%s [%s] %3d%%  %s elapsed, ETA %s", p->label, bar, pct, el, eta);
    } else {
        len = snprintf(line, sizeof line, "%s [%s] %3d%%  %s elapsed, ETA --", p->label, bar, pct, el);
    }
    if (len < 0)
        return;
    if (len >= (int)sizeof line)
        len = (int)sizeof line - 1;
    /* '\r' returns to the line start; spaces blank what a longer line left. */
    int pad = p->last_len > len ? p->last_len - len : 0;
    fprintf(p->out, "\r%s%*s%s", line, pad, "", final ? "\n" : "");
    fflush(p->out);
    p->last_len = len;
}

void tb_progress_add(tb_progress *p, int64_t n)
{
    int64_t done = atomic_fetch_add_explicit(&p->done, n, memory_order_relaxed) + n;
    if (!p->out)
        return;
    int64_t now = tb__now_ns();
    if (now < atomic_load_explicit(&p->next_draw_ns, memory_order_relaxed))
        return;
    /* Try-lock: a thread that finds someone drawing goes back to work. */
    if (atomic_flag_test_and_set_explicit(&p->drawing, memory_order_acquire))
        return;
    if (now >= atomic_load_explicit(&p->next_draw_ns, memory_order_relaxed)) {
        atomic_store_explicit(&p->next_draw_ns, now + TB_PROGRESS_INTERVAL_NS, memory_order_relaxed);
        tb__draw(p, done, now, 0);
    }
    atomic_flag_clear_explicit(&p->drawing, memory_order_release);
}

void tb_progress_finish(tb_progress *p)
{
    if (!p->out)
        return;
    /* Wait out a straggling redraw so the final line is the last one. */
    while (atomic_flag_test_and_set_explicit(&p->drawing, memory_order_acquire))
        ;
    tb__draw(p, atomic_load_explicit(&p->done, memory_order_relaxed), tb__now_ns(), 1);
    atomic_flag_clear_explicit(&p->drawing, memory_order_release);
    p->out = NULL; /* a second finish does nothing */
}
