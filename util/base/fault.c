/* Fault injection for tests (fault.h). */
#include "util/base/fault.h"

#ifdef TB_FAULT_INJECTION
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

/* This process's MPI rank as the launcher announced it, or -1. */
static int tb__fault_rank(void)
{
    const char *v = getenv("OMPI_COMM_WORLD_RANK");
    if (!v || !*v)
        v = getenv("PMIX_RANK");
    return v && *v ? atoi(v) : -1;
}

/* Passes per point (a few distinct points are enough for tests). */
#define TB__FAULT_SLOTS 8
static struct {
    const char *point;
    long passes;
} tb__fault_count[TB__FAULT_SLOTS];
static int tb__fault_used;
static pthread_mutex_t tb__fault_lock = PTHREAD_MUTEX_INITIALIZER;

/* Counts a pass of `point`: its number, from 1. */
static long tb__fault_pass(const char *point)
{
    pthread_mutex_lock(&tb__fault_lock);
    int i = 0;
    while (i < tb__fault_used && strcmp(tb__fault_count[i].point, point) != 0)
        i++;
    long n = 1;
    if (i < TB__FAULT_SLOTS) {
        if (i == tb__fault_used)
            tb__fault_count[tb__fault_used++].point = point;
        n = ++tb__fault_count[i].passes;
    }
    pthread_mutex_unlock(&tb__fault_lock);
    return n;
}

bool tb_fault(const char *point)
{
    const char *spec = getenv("TB_FAULT");
    if (!spec || !*spec)
        return false;
    size_t plen = strlen(point);
    for (const char *p = spec; *p;) {
        const char *end = strchr(p, ',');
        size_t n = end ? (size_t)(end - p) : strlen(p);
        if (n >= plen && strncmp(p, point, plen) == 0 && (n == plen || p[plen] == '@' || p[plen] == ':')) {
            const char *q = p + plen;
            int rank = -1;
            long from = 1;
            if (*q == '@')
                rank = (int)strtol(q + 1, (char **)&q, 10);
            if (*q == ':')
                from = strtol(q + 1, NULL, 10);
            if (rank >= 0 && rank != tb__fault_rank())
                return false;
            return tb__fault_pass(point) >= from;
        }
        p += n;
        if (*p == ',')
            p++;
    }
    return false;
}
#else
bool tb_fault(const char *point)
{
    (void)point;
    return false;
}
#endif
