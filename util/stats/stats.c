#include "util/stats/stats.h"

#include <inttypes.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "util/base/outfile.h"
#include "util/stats/provenance.h"

_Thread_local tb__stat_block *tb__stat_tls;
atomic_int tb__stats_on = 1;

/* Totals of one slot (same layout as a cell, without atomics). */
typedef struct tb__total {
    int64_t v[4];
} tb__total;

/* A run-level value for the top of the JSON report. */
typedef struct tb__value {
    char *key;
    char *str;     /* string value, or NULL for a number */
    double num;
} tb__value;

/* The registry. The lock guards everything here; the hot path never takes it
 * (only a thread's first update, registration, thread exit and reports do). */
static pthread_mutex_t tb__lock = PTHREAD_MUTEX_INITIALIZER;
static tb_stat *tb__head, *tb__tail;   /* registered stats, in registration order */
static unsigned tb__nslots;            /* slots handed out; slot numbers are 1..tb__nslots */
static tb__stat_block *tb__blocks;     /* blocks of live threads */
static tb__total *tb__retired;         /* per slot: totals left by threads that exited */
static size_t tb__retired_cap;
static tb__value *tb__values;
static size_t tb__nvalues, tb__values_cap;

static pthread_once_t tb__key_once = PTHREAD_ONCE_INIT;
static pthread_key_t tb__key;
static int tb__key_ok;

/* Adds the state `src` of a stat of kind `kind` to the totals `dst`. */
static void tb__combine(tb_stat_kind kind, int64_t dst[4], const int64_t src[4])
{
    if (kind == TB_STAT_KIND_DISTRIBUTION) {
        if (src[0] == 0)
            return;
        if (dst[0] == 0) {
            memcpy(dst, src, 4 * sizeof dst[0]);
            return;
        }
        dst[0] += src[0];
        dst[1] += src[1];
        if (src[2] < dst[2])
            dst[2] = src[2];
        if (src[3] > dst[3])
            dst[3] = src[3];
        return;
    }
    for (int i = 0; i < 4; i++)
        dst[i] += src[i];
}

/* Relaxed reads of a cell another thread may be writing. */
static void tb__load_cell(tb__stat_cell *c, int64_t out[4])
{
    for (int i = 0; i < 4; i++)
        out[i] = atomic_load_explicit(&c->v[i], memory_order_relaxed);
}

/* Adds the block's cell of `s` (if it has one) to `dst`. Lock held. */
static void tb__add_block(const tb__stat_block *b, const tb_stat *s, int64_t dst[4])
{
    unsigned slot = atomic_load_explicit(&((tb_stat *)s)->slot, memory_order_relaxed);
    tb__stat_cell *chunk = atomic_load_explicit(&((tb__stat_block *)b)->chunks[slot / TB__STAT_CHUNK],
                                                memory_order_acquire);
    if (!chunk)
        return;
    int64_t v[4];
    tb__load_cell(&chunk[slot % TB__STAT_CHUNK], v);
    tb__combine(s->kind, dst, v);
}

/* Folds an exiting thread's counts into the retired totals and frees its block,
 * so work done by threads that have ended is still reported. */
static void tb__thread_exit(void *arg)
{
    tb__stat_block *b = arg;
    pthread_mutex_lock(&tb__lock);
    for (tb_stat *s = tb__head; s; s = s->next)
        tb__add_block(b, s, tb__retired[atomic_load_explicit(&s->slot, memory_order_relaxed)].v);
    for (tb__stat_block **pp = &tb__blocks; *pp; pp = &(*pp)->next) {
        if (*pp == b) {
            *pp = b->next;
            break;
        }
    }
    pthread_mutex_unlock(&tb__lock);
    for (int i = 0; i < TB__STAT_MAX_CHUNKS; i++)
        free(atomic_load_explicit(&b->chunks[i], memory_order_relaxed));
    free(b);
    if (tb__stat_tls == b)
        tb__stat_tls = NULL;
}

static void tb__make_key(void)
{
    tb__key_ok = pthread_key_create(&tb__key, tb__thread_exit) == 0;
}

tb_status tb_stat_register(tb_stat *s)
{
    if (!s || !s->name)
        return tb_error(TB_ERR_ARG, "statistic without a name");
    pthread_mutex_lock(&tb__lock);
    if (atomic_load_explicit(&s->slot, memory_order_relaxed)) {
        pthread_mutex_unlock(&tb__lock);
        return TB_OK;
    }
    unsigned slot = tb__nslots + 1;
    if (slot >= (unsigned)TB__STAT_CHUNK * TB__STAT_MAX_CHUNKS) {
        pthread_mutex_unlock(&tb__lock);
        return tb_error(TB_ERR_NOMEM, "statistic '%s': more than %d statistics", s->name,
                        TB__STAT_CHUNK * TB__STAT_MAX_CHUNKS - 1);
    }
    /* Grow the retired totals now so a thread exit never has to allocate. */
    if (slot >= tb__retired_cap) {
        size_t cap = tb__retired_cap ? 2 * tb__retired_cap : 64;
        while (cap <= slot)
            cap *= 2;
        tb__total *r = realloc(tb__retired, cap * sizeof *r);
        if (!r) {
            pthread_mutex_unlock(&tb__lock);
            return tb_error(TB_ERR_NOMEM, "statistic '%s': out of memory", s->name);
        }
        memset(r + tb__retired_cap, 0, (cap - tb__retired_cap) * sizeof *r);
        tb__retired = r;
        tb__retired_cap = cap;
    }
    tb__nslots = slot;
    s->next = NULL;
    if (tb__tail)
        tb__tail->next = s;
    else
        tb__head = s;
    tb__tail = s;
    atomic_store_explicit(&s->slot, slot, memory_order_release);
    pthread_mutex_unlock(&tb__lock);
    return TB_OK;
}

tb__stat_cell *tb__stat_cell_slow(tb_stat *s)
{
    unsigned slot = atomic_load_explicit(&s->slot, memory_order_acquire);
    if (!slot) {
        if (tb_stat_register(s) != TB_OK)
            return NULL;
        slot = atomic_load_explicit(&s->slot, memory_order_acquire);
    }
    tb__stat_block *b = tb__stat_tls;
    if (!b) {
        b = calloc(1, sizeof *b);
        if (!b)
            return NULL;
        pthread_once(&tb__key_once, tb__make_key);
        pthread_mutex_lock(&tb__lock);
        b->next = tb__blocks;
        tb__blocks = b;
        pthread_mutex_unlock(&tb__lock);
        tb__stat_tls = b;
        if (tb__key_ok)
            pthread_setspecific(tb__key, b);
    }
    unsigned k = slot / TB__STAT_CHUNK;
    tb__stat_cell *c = atomic_load_explicit(&b->chunks[k], memory_order_relaxed);
    if (!c) {
        /* Cache-line aligned, so no two threads' cells share a line. */
        c = aligned_alloc(64, TB__STAT_CHUNK * sizeof *c);
        if (!c)
            return NULL;
        for (int i = 0; i < TB__STAT_CHUNK; i++)
            for (int j = 0; j < 4; j++)
                atomic_init(&c[i].v[j], 0);
        atomic_store_explicit(&b->chunks[k], c, memory_order_release);
    }
    return &c[slot % TB__STAT_CHUNK];
}

int64_t tb_stats_now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

void tb_stats_set_enabled(int on)
{
    atomic_store_explicit(&tb__stats_on, on != 0, memory_order_relaxed);
}

void tb_stats_reset(void)
{
    pthread_mutex_lock(&tb__lock);
    for (tb__stat_block *b = tb__blocks; b; b = b->next) {
        for (int k = 0; k < TB__STAT_MAX_CHUNKS; k++) {
            tb__stat_cell *c = atomic_load_explicit(&b->chunks[k], memory_order_acquire);
            if (!c)
                continue;
            for (int i = 0; i < TB__STAT_CHUNK; i++)
                for (int j = 0; j < 4; j++)
                    atomic_store_explicit(&c[i].v[j], 0, memory_order_relaxed);
        }
    }
    if (tb__retired)
        memset(tb__retired, 0, tb__retired_cap * sizeof *tb__retired);
    for (size_t i = 0; i < tb__nvalues; i++) {
        free(tb__values[i].key);
        free(tb__values[i].str);
    }
    free(tb__values);
    tb__values = NULL;
    tb__nvalues = tb__values_cap = 0;
    pthread_mutex_unlock(&tb__lock);
}

/* ---------------------------------------------------------------- run-level values */

static const char *const tb__reserved_keys[] = {
    "schema", "provenance", "counters", "memory", "distributions", "ratios", "percentages", "timers",
};

/* Sets key to a copy of `str` (string) or to `num` (str == NULL). */
static tb_status tb__set_value(const char *key, const char *str, double num)
{
    if (!key || !*key)
        return tb_error(TB_ERR_ARG, "stats value with an empty key");
    for (size_t i = 0; i < sizeof tb__reserved_keys / sizeof tb__reserved_keys[0]; i++)
        if (strcmp(key, tb__reserved_keys[i]) == 0)
            return tb_error(TB_ERR_ARG, "stats value '%s': the report uses this key itself", key);
    char *copy = NULL;
    if (str) {
        size_t n = strlen(str) + 1;
        copy = malloc(n);
        if (!copy)
            return tb_error(TB_ERR_NOMEM, "stats value '%s': out of memory", key);
        memcpy(copy, str, n);
    }
    pthread_mutex_lock(&tb__lock);
    for (size_t i = 0; i < tb__nvalues; i++) {
        if (strcmp(tb__values[i].key, key) == 0) {
            free(tb__values[i].str);
            tb__values[i].str = copy;
            tb__values[i].num = num;
            pthread_mutex_unlock(&tb__lock);
            return TB_OK;
        }
    }
    size_t kn = strlen(key) + 1;
    char *kcopy = malloc(kn);
    if (kcopy && tb__nvalues == tb__values_cap) {
        size_t cap = tb__values_cap ? 2 * tb__values_cap : 16;
        tb__value *v = realloc(tb__values, cap * sizeof *v);
        if (v) {
            tb__values = v;
            tb__values_cap = cap;
        }
    }
    if (!kcopy || tb__nvalues == tb__values_cap) {
        pthread_mutex_unlock(&tb__lock);
        free(kcopy);
        free(copy);
        return tb_error(TB_ERR_NOMEM, "stats value '%s': out of memory", key);
    }
    memcpy(kcopy, key, kn);
    tb__values[tb__nvalues++] = (tb__value){kcopy, copy, num};
    pthread_mutex_unlock(&tb__lock);
    return TB_OK;
}

tb_status tb_stats_set_value(const char *key, double value)
{
    return tb__set_value(key, NULL, value);
}

tb_status tb_stats_set_string(const char *key, const char *value)
{
    if (!value)
        return tb_error(TB_ERR_ARG, "stats value '%s': NULL string", key ? key : "");
    return tb__set_value(key, value, 0.0);
}

tb_status tb_stats_get_value(const char *key, double *out)
{
    pthread_mutex_lock(&tb__lock);
    for (size_t i = 0; key && i < tb__nvalues; i++)
        if (!tb__values[i].str && strcmp(tb__values[i].key, key) == 0) {
            *out = tb__values[i].num;
            pthread_mutex_unlock(&tb__lock);
            return TB_OK;
        }
    pthread_mutex_unlock(&tb__lock);
    return tb_error(TB_ERR_NOT_FOUND, "stats value '%s' is not set", key ? key : "");
}

/* ---------------------------------------------------------------- snapshots */

static int tb__cmp_total(const void *a, const void *b)
{
    const tb_stat_total *x = a, *y = b;
    int c = strcmp(x->name, y->name);
    if (c)
        return c;
    return (int)x->kind - (int)y->kind;
}

/* All statistics summed over threads, sorted by name and merged by name+kind.
 * Caller frees *out. */
static tb_status tb__snapshot(tb_stat_total **out, size_t *n)
{
    *out = NULL;
    *n = 0;
    pthread_mutex_lock(&tb__lock);
    size_t cap = tb__nslots ? tb__nslots : 1;
    tb_stat_total *t = calloc(cap, sizeof *t);
    if (!t) {
        pthread_mutex_unlock(&tb__lock);
        return tb_error(TB_ERR_NOMEM, "stats report: out of memory");
    }
    size_t m = 0;
    for (tb_stat *s = tb__head; s; s = s->next, m++) {
        unsigned slot = atomic_load_explicit(&s->slot, memory_order_relaxed);
        t[m].name = s->name;
        t[m].kind = s->kind;
        memcpy(t[m].v, tb__retired[slot].v, sizeof t[m].v);
        for (tb__stat_block *b = tb__blocks; b; b = b->next)
            tb__add_block(b, s, t[m].v);
    }
    pthread_mutex_unlock(&tb__lock);
    qsort(t, m, sizeof *t, tb__cmp_total);
    size_t k = 0;
    for (size_t i = 0; i < m; i++) {
        if (k > 0 && t[k - 1].kind == t[i].kind && strcmp(t[k - 1].name, t[i].name) == 0)
            tb__combine(t[i].kind, t[k - 1].v, t[i].v);
        else
            t[k++] = t[i];
    }
    *out = t;
    *n = k;
    return TB_OK;
}

tb_status tb_stats_get(const char *name, tb_stat_kind kind, tb_stat_total *out)
{
    if (!name || !out)
        return tb_error(TB_ERR_ARG, "tb_stats_get: NULL argument");
    tb_stat_total *t;
    size_t n;
    tb_status st = tb__snapshot(&t, &n);
    if (st)
        return st;
    for (size_t i = 0; i < n; i++) {
        if (t[i].kind == kind && strcmp(t[i].name, name) == 0) {
            *out = t[i];
            free(t);
            return TB_OK;
        }
    }
    free(t);
    return tb_error(TB_ERR_NOT_FOUND, "no statistic '%s' of that kind", name);
}

int64_t tb_stats_counter(const char *name)
{
    tb_stat_total t;
    if (tb_stats_get(name, TB_STAT_KIND_COUNTER, &t) != TB_OK) {
        tb_clear_error();
        return 0;
    }
    return t.v[0];
}

/* ---------------------------------------------------------------- table */

/* Columns a UTF-8 string takes on a terminal (code points, not bytes). */
static int tb__width(const char *s, size_t n)
{
    int w = 0;
    for (size_t i = 0; i < n && s[i]; i++)
        if (((unsigned char)s[i] & 0xC0) != 0x80)
            w++;
    return w;
}

/* Category (before the first '/') and label (after it); names without '/' go
 * to the category "General". */
static void tb__split(const char *name, const char **cat, size_t *catlen, const char **label)
{
    const char *slash = strchr(name, '/');
    if (slash) {
        *cat = name;
        *catlen = (size_t)(slash - name);
        *label = slash + 1;
    } else {
        *cat = "General";
        *catlen = 7;
        *label = name;
    }
}

static int tb__recorded(const tb_stat_total *t)
{
    return t->v[0] != 0 || t->v[1] != 0;
}

/* A duration in the unit that keeps 3-4 significant digits. */
static void tb__fmt_seconds(char *buf, size_t n, double s)
{
    if (s >= 1.0 || s == 0.0)
        snprintf(buf, n, "%.3f s", s);
    else if (s >= 1e-3)
        snprintf(buf, n, "%.3f ms", s * 1e3);
    else if (s >= 1e-6)
        snprintf(buf, n, "%.3f us", s * 1e6);
    else
        snprintf(buf, n, "%.1f ns", s * 1e9);
}

static void tb__fmt_value(char *buf, size_t n, const tb_stat_total *t)
{
    const int64_t *v = t->v;
    switch (t->kind) {
    case TB_STAT_KIND_COUNTER:
        snprintf(buf, n, "%" PRId64, v[0]);
        break;
    case TB_STAT_KIND_MEMORY: {
        double b = (double)v[0], a = fabs(b);
        if (a >= 1024.0 * 1024.0 * 1024.0)
            snprintf(buf, n, "%.2f GiB", b / (1024.0 * 1024.0 * 1024.0));
        else if (a >= 1024.0 * 1024.0)
            snprintf(buf, n, "%.2f MiB", b / (1024.0 * 1024.0));
        else if (a >= 1024.0)
            snprintf(buf, n, "%.2f KiB", b / 1024.0);
        else
            snprintf(buf, n, "%" PRId64 " B", v[0]);
        break;
    }
    case TB_STAT_KIND_DISTRIBUTION:
        snprintf(buf, n, "%.3f mean [min %" PRId64 ", max %" PRId64 "] over %" PRId64 " samples",
                 (double)v[1] / (double)v[0], v[2], v[3], v[0]);
        break;
    case TB_STAT_KIND_RATIO:
        if (v[1])
            snprintf(buf, n, "%.4f (%" PRId64 " / %" PRId64 ")", (double)v[0] / (double)v[1], v[0], v[1]);
        else
            snprintf(buf, n, "- (%" PRId64 " / 0)", v[0]);
        break;
    case TB_STAT_KIND_PERCENT:
        if (v[1])
            snprintf(buf, n, "%.2f%% (%" PRId64 " / %" PRId64 ")", 100.0 * (double)v[0] / (double)v[1],
                     v[0], v[1]);
        else
            snprintf(buf, n, "- (%" PRId64 " / 0)", v[0]);
        break;
    case TB_STAT_KIND_TIMER: {
        char total[32], mean[32];
        tb__fmt_seconds(total, sizeof total, (double)v[1] * 1e-9);
        tb__fmt_seconds(mean, sizeof mean, (double)v[1] * 1e-9 / (double)v[0]);
        snprintf(buf, n, "%s in %" PRId64 " calls (%s per call)", total, v[0], mean);
        break;
    }
    }
}

tb_status tb_stats_print(FILE *out)
{
    tb_stat_total *t;
    size_t n;
    tb_status st = tb__snapshot(&t, &n);
    if (st)
        return st;
    /* Keep the recorded entries; one label column width for the whole table. */
    int width = 0;
    size_t shown = 0;
    for (size_t i = 0; i < n; i++) {
        if (!tb__recorded(&t[i]))
            continue;
        const char *cat, *label;
        size_t catlen;
        tb__split(t[i].name, &cat, &catlen, &label);
        int w = tb__width(label, strlen(label));
        if (w > width)
            width = w;
        t[shown++] = t[i];
    }
    pthread_mutex_lock(&tb__lock);
    for (size_t i = 0; i < tb__nvalues; i++) {
        int w = tb__width(tb__values[i].key, strlen(tb__values[i].key));
        if (w > width)
            width = w;
    }
    pthread_mutex_unlock(&tb__lock);

    fprintf(out, "Statistics:\n");
    if (shown == 0)
        fprintf(out, "  (none recorded)\n");
    /* Categories in order of first appearance in the sorted list; a category's
     * entries are printed together, so "General" ones are gathered too. */
    char *done = calloc(shown ? shown : 1, 1);
    if (!done) {
        free(t);
        return tb_error(TB_ERR_NOMEM, "stats report: out of memory");
    }
    for (size_t i = 0; i < shown; i++) {
        if (done[i])
            continue;
        const char *cat, *label;
        size_t catlen;
        tb__split(t[i].name, &cat, &catlen, &label);
        fprintf(out, "  %.*s\n", (int)catlen, cat);
        for (size_t j = i; j < shown; j++) {
            const char *cat2, *label2;
            size_t catlen2;
            tb__split(t[j].name, &cat2, &catlen2, &label2);
            if (done[j] || catlen2 != catlen || memcmp(cat, cat2, catlen) != 0)
                continue;
            done[j] = 1;
            char value[256];
            tb__fmt_value(value, sizeof value, &t[j]);
            int pad = width - tb__width(label2, strlen(label2));
            fprintf(out, "    %s%*s  %s\n", label2, pad, "", value);
        }
    }
    free(done);
    free(t);

    pthread_mutex_lock(&tb__lock);
    if (tb__nvalues)
        fprintf(out, "Run values:\n");
    for (size_t i = 0; i < tb__nvalues; i++) {
        const tb__value *v = &tb__values[i];
        int pad = width - tb__width(v->key, strlen(v->key));
        if (v->str)
            fprintf(out, "    %s%*s  %s\n", v->key, pad, "", v->str);
        else
            fprintf(out, "    %s%*s  %.6g\n", v->key, pad, "", v->num);
    }
    pthread_mutex_unlock(&tb__lock);
    if (ferror(out))
        return tb_error(TB_ERR_IO, "stats report: write failed");
    return TB_OK;
}

/* ---------------------------------------------------------------- JSON */

/* Length of the valid UTF-8 sequence at s (1-4), or 0 if invalid (RFC 3629:
 * no overlong forms, no surrogates, nothing above U+10FFFF). */
static int tb__utf8_len(const unsigned char *s)
{
    unsigned char c = s[0];
    if (c < 0x80)
        return 1;
    int n;
    unsigned char lo = 0x80, hi = 0xBF; /* allowed range of the second byte */
    if (c >= 0xC2 && c <= 0xDF)
        n = 2;
    else if (c >= 0xE0 && c <= 0xEF) {
        n = 3;
        if (c == 0xE0)
            lo = 0xA0;
        else if (c == 0xED)
            hi = 0x9F;
    } else if (c >= 0xF0 && c <= 0xF4) {
        n = 4;
        if (c == 0xF0)
            lo = 0x90;
        else if (c == 0xF4)
            hi = 0x8F;
    } else
        return 0;
    if (s[1] < lo || s[1] > hi)
        return 0;
    for (int i = 2; i < n; i++)
        if (s[i] < 0x80 || s[i] > 0xBF)
            return 0;
    return n;
}

void tb_json_write_string(FILE *out, const char *str)
{
    const unsigned char *s = (const unsigned char *)(str ? str : "");
    fputc('"', out);
    while (*s) {
        unsigned char c = *s;
        switch (c) {
        case '"': fputs("\\\"", out); s++; continue;
        case '\\': fputs("\\\\", out); s++; continue;
        case '\b': fputs("\\b", out); s++; continue;
        case '\f': fputs("\\f", out); s++; continue;
        case '\n': fputs("\\n", out); s++; continue;
        case '\r': fputs("\\r", out); s++; continue;
        case '\t': fputs("\\t", out); s++; continue;
        default: break;
        }
        if (c < 0x20) {
            fprintf(out, "\\u%04x", c);
            s++;
            continue;
        }
        int n = tb__utf8_len(s);
        if (n == 0) {
            fputs("\\ufffd", out);
            s++;
            continue;
        }
        fwrite(s, 1, (size_t)n, out);
        s += n;
    }
    fputc('"', out);
}

/* A finite double in the shortest of %.15g/%.16g/%.17g that reads back
 * exactly; null for NaN and infinities (JSON has no spelling for them). */
static void tb__json_double(FILE *out, double x)
{
    if (!isfinite(x)) {
        fputs("null", out);
        return;
    }
    char buf[40];
    for (int prec = 15; prec <= 17; prec++) {
        snprintf(buf, sizeof buf, "%.*g", prec, x);
        if (strtod(buf, NULL) == x)
            break;
    }
    fputs(buf, out);
}

static void tb__json_ratio(FILE *out, int64_t num, int64_t den, double scale)
{
    if (den)
        tb__json_double(out, scale * (double)num / (double)den);
    else
        fputs("null", out);
}

/* Writes the entries of `kind` as one section object. */
static void tb__json_section(FILE *out, const char *section, const tb_stat_total *t, size_t n,
                             tb_stat_kind kind)
{
    fprintf(out, "  \"%s\": {", section);
    int first = 1;
    for (size_t i = 0; i < n; i++) {
        if (t[i].kind != kind)
            continue;
        const int64_t *v = t[i].v;
        fputs(first ? "\n    " : ",\n    ", out);
        first = 0;
        tb_json_write_string(out, t[i].name);
        fputs(": ", out);
        switch (kind) {
        case TB_STAT_KIND_COUNTER:
        case TB_STAT_KIND_MEMORY:
            fprintf(out, "%" PRId64, v[0]);
            break;
        case TB_STAT_KIND_DISTRIBUTION:
            fprintf(out, "{\"count\": %" PRId64 ", \"sum\": %" PRId64 ", ", v[0], v[1]);
            if (v[0]) {
                fprintf(out, "\"min\": %" PRId64 ", \"max\": %" PRId64 ", \"mean\": ", v[2], v[3]);
                tb__json_ratio(out, v[1], v[0], 1.0);
            } else {
                fputs("\"min\": null, \"max\": null, \"mean\": null", out);
            }
            fputc('}', out);
            break;
        case TB_STAT_KIND_RATIO:
            fprintf(out, "{\"num\": %" PRId64 ", \"den\": %" PRId64 ", \"ratio\": ", v[0], v[1]);
            tb__json_ratio(out, v[0], v[1], 1.0);
            fputc('}', out);
            break;
        case TB_STAT_KIND_PERCENT:
            fprintf(out, "{\"num\": %" PRId64 ", \"den\": %" PRId64 ", \"percent\": ", v[0], v[1]);
            tb__json_ratio(out, v[0], v[1], 100.0);
            fputc('}', out);
            break;
        case TB_STAT_KIND_TIMER:
            fprintf(out, "{\"calls\": %" PRId64 ", \"seconds\": ", v[0]);
            tb__json_double(out, (double)v[1] * 1e-9);
            fputs(", \"mean_seconds\": ", out);
            if (v[0])
                tb__json_double(out, (double)v[1] * 1e-9 / (double)v[0]);
            else
                fputs("null", out);
            fputc('}', out);
            break;
        }
    }
    fputs(first ? "}" : "\n  }", out);
}

tb_status tb_stats_write_json(FILE *out, const tb_provenance *prov)
{
    tb_stat_total *t;
    size_t n;
    tb_status st = tb__snapshot(&t, &n);
    if (st)
        return st;
    fputs("{\n  \"schema\": \"testbed-stats-1\",\n  \"provenance\": ", out);
    if (prov)
        tb_provenance_write_json(out, prov, 2);
    else
        fputs("null", out);
    static const struct {
        const char *section;
        tb_stat_kind kind;
    } sections[] = {
        {"counters", TB_STAT_KIND_COUNTER},       {"memory", TB_STAT_KIND_MEMORY},
        {"distributions", TB_STAT_KIND_DISTRIBUTION}, {"ratios", TB_STAT_KIND_RATIO},
        {"percentages", TB_STAT_KIND_PERCENT},    {"timers", TB_STAT_KIND_TIMER},
    };
    for (size_t i = 0; i < sizeof sections / sizeof sections[0]; i++) {
        fputs(",\n", out);
        tb__json_section(out, sections[i].section, t, n, sections[i].kind);
    }
    free(t);
    pthread_mutex_lock(&tb__lock);
    for (size_t i = 0; i < tb__nvalues; i++) {
        fputs(",\n  ", out);
        tb_json_write_string(out, tb__values[i].key);
        fputs(": ", out);
        if (tb__values[i].str)
            tb_json_write_string(out, tb__values[i].str);
        else
            tb__json_double(out, tb__values[i].num);
    }
    pthread_mutex_unlock(&tb__lock);
    fputs("\n}\n", out);
    if (ferror(out))
        return tb_error(TB_ERR_IO, "stats JSON: write failed");
    return TB_OK;
}

tb_status tb_stats_write_json_file(const char *path, const tb_provenance *prov)
{
    tb_outfile of;
    tb_status st = tb_outfile_open(&of, path);
    if (st)
        return st;
    st = tb_stats_write_json(of.fp, prov);
    if (st) {
        tb_outfile_abort(&of);
        return tb_error_context(st, "%s", path);
    }
    return tb_outfile_commit(&of);
}
