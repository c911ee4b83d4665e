/* Radiosity shots over ranks (radiosity.h): the gather of every rank's
 * form factors and the accounts of work and waiting. */
#include "host/dist/radiosity.h"
#include "host/dist/dist.h"
#include "host/dist/dist_internal.h"

#include <limits.h>
#include <sched.h>
#ifdef __linux__
#include <sys/prctl.h>
#endif
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#ifdef TB_HAVE_MPI
#include <mpi.h>
#endif

/* Microseconds a rank polls an exchange, giving up its core between polls
 * (sched_yield), before it sleeps, unless TB_DIST_SPIN_US says otherwise.
 * On a core of its own the yield returns at once, so the rank answers
 * within microseconds (a sleep costs tens of microseconds, and a rank woken
 * late delays every rank's next shot); on shared or loaded cores the yield
 * hands the core to whoever waits for it, the rank everyone waits for
 * included. A poll that kept the core (no yield) made a loaded job 3-4x
 * slower; the yielding one was the fastest there too (docs/distributed.md). */
#define TB__RADX_SPIN_US 1000

/* An exchange and its accounts. */
typedef struct tb__radx {
    tb_rad_exchange ex;  /* handed to the solver (ex.ctx == this) */
    int *counts, *displs; /* MPI's int counts and offsets per rank */
    double last;          /* clock when the previous gather returned (work runs from there) */
    double spin;          /* seconds an exchange is polled (yielding) before sleeping (TB__RADX_SPIN_US, TB_DIST_SPIN_US) */
#ifdef TB_HAVE_MPI
    MPI_Datatype type;    /* select: type_n contiguous doubles (type_n 0: none made) */
    size_t type_n;
    MPI_Op op;            /* select: tb__radx_pick, when op_made */
    bool op_made;
#endif
} tb__radx;

#ifdef TB_HAVE_MPI
/* Waits for req: polled for x->spin seconds, yielding the core between
 * polls, then with short, growing sleeps: a rank that is done early leaves
 * the core to one still casting rays (Open MPI's blocking collectives spin
 * without yielding, which on shared or oversubscribed cores slows the very
 * rank everyone waits for). Then the
 * accounts: work since the previous exchange, the wait, `bytes` sent and
 * `units` (receivers). */
static void tb__radx_wait(tb__radx *x, MPI_Request *req, double t0, uint64_t bytes, uint64_t units)
{
    int done = 0;
    for (unsigned i = 1; !done; i++) {
        MPI_Test(req, &done, MPI_STATUS_IGNORE);
        if (done)
            break;
        sched_yield(); /* about 0.5 us when no one else wants the core */
        if (i % 8 == 0 && tb__dist_now() - t0 >= x->spin) /* the clock now and then: it costs a poll */
            break;
    }
    for (long us = 5; !done;) {
        MPI_Test(req, &done, MPI_STATUS_IGNORE);
        if (done)
            break;
        /* 5 us doubling to 200 us: an exchange of a few kilobytes is
         * answered within microseconds when both ranks are there */
        struct timespec ts = {0, us * 1000L};
        nanosleep(&ts, NULL);
        us = us * 2 < 200 ? us * 2 : 200;
    }
    double t1 = tb__dist_now();
    tb__dist_account(t0 - x->last, t1 - t0, bytes, 1, units);
    x->last = t1;
}

/* Every rank's `n_mine` values of `type` (`size` bytes each) into all[], in
 * rank order (counts[r] from rank r); `units`: the receivers they are. */
static tb_status tb__radx_gather(tb__radx *x, const void *mine, size_t n_mine, void *all, const size_t *counts,
                                 MPI_Datatype type, size_t size, size_t units)
{
    double t0 = tb__dist_now();
    int R = x->ex.ranks, off = 0;
    for (int r = 0; r < R; r++) {
        if (counts[r] > (size_t)INT_MAX - (size_t)off)
            return tb_error(TB_ERR_UNSUPPORTED, "radiosity exchange: more than %d values", INT_MAX);
        x->counts[r] = (int)counts[r];
        x->displs[r] = off;
        off += (int)counts[r];
    }
    MPI_Request req;
    if (MPI_Iallgatherv(mine, (int)n_mine, type, all, x->counts, x->displs, type, MPI_COMM_WORLD, &req) !=
        MPI_SUCCESS)
        return tb_error(TB_ERR_IO, "radiosity exchange: MPI_Iallgatherv failed");
    /* bytes: this rank's values, delivered to every other rank */
    tb__radx_wait(x, &req, t0, (uint64_t)(n_mine * size) * (uint64_t)(x->ex.ranks - 1), units);
    return TB_OK;
}

/* The reduction of tb_rad_exchange.select on one buffer (an MPI datatype of
 * n contiguous doubles): the larger candidate (ties: the lower key) and the
 * sums of the tails. Commutative: the candidates are ordered strictly (keys
 * differ) and each tail value is nonzero on one rank at most. */
static void tb__radx_pick(void *in, void *inout, int *len, MPI_Datatype *type)
{
    int bytes = 0;
    MPI_Type_size(*type, &bytes);
    size_t n = (size_t)bytes / sizeof(double);
    for (int e = 0; e < *len; e++) {
        const double *a = (const double *)in + (size_t)e * n;
        double *b = (double *)inout + (size_t)e * n;
        size_t h = (size_t)a[0];
        if (a[1] > b[1] || (a[1] == b[1] && a[2] < b[2]))
            for (size_t k = 1; k < h && k < n; k++)
                b[k] = a[k];
        for (size_t k = h; k < n; k++)
            b[k] += a[k];
    }
}
#endif

/* Doubles gathered (tb__radx_gather); `units`: the receivers they are. */
static tb_status tb__radx_gatherd(void *ctx, const double *mine, size_t n_mine, double *all, const size_t *counts,
                                  size_t units)
{
#ifdef TB_HAVE_MPI
    return tb__radx_gather(ctx, mine, n_mine, all, counts, MPI_DOUBLE, sizeof *mine, units);
#else
    (void)ctx, (void)mine, (void)n_mine, (void)all, (void)counts, (void)units;
    return tb_error(TB_ERR_UNSUPPORTED, "radiosity exchange over ranks in a build without MPI");
#endif
}

static tb_status tb__radx_allgather(void *ctx, const double *mine, size_t n_mine, double *all, const size_t *counts,
                                    size_t receivers)
{
    return tb__radx_gatherd(ctx, mine, n_mine, all, counts, receivers);
}

static tb_status tb__radx_allgather_state(void *ctx, const double *mine, size_t n_mine, double *all,
                                          const size_t *counts)
{
    return tb__radx_gatherd(ctx, mine, n_mine, all, counts, 0);
}

static tb_status tb__radx_select(void *ctx, double *buf, size_t n)
{
#ifdef TB_HAVE_MPI
    tb__radx *x = ctx;
    double t0 = tb__dist_now();
    if (n > (size_t)INT_MAX)
        return tb_error(TB_ERR_UNSUPPORTED, "radiosity exchange: more than %d values", INT_MAX);
    if (x->type_n != n) { /* one datatype per buffer length (the same all solve long) */
        if (x->type_n)
            MPI_Type_free(&x->type);
        x->type_n = 0;
        if (MPI_Type_contiguous((int)n, MPI_DOUBLE, &x->type) != MPI_SUCCESS || MPI_Type_commit(&x->type) != MPI_SUCCESS)
            return tb_error(TB_ERR_IO, "radiosity exchange: MPI_Type_contiguous failed");
        x->type_n = n;
    }
    if (!x->op_made) {
        if (MPI_Op_create(tb__radx_pick, 1, &x->op) != MPI_SUCCESS)
            return tb_error(TB_ERR_IO, "radiosity exchange: MPI_Op_create failed");
        x->op_made = true;
    }
    MPI_Request req;
    if (MPI_Iallreduce(MPI_IN_PLACE, buf, 1, x->type, x->op, MPI_COMM_WORLD, &req) != MPI_SUCCESS)
        return tb_error(TB_ERR_IO, "radiosity exchange: MPI_Iallreduce failed");
    /* bytes: a reduction sends about its buffer once per rank */
    tb__radx_wait(x, &req, t0, (uint64_t)(n * sizeof *buf), 0);
    return TB_OK;
#else
    (void)ctx, (void)buf, (void)n;
    return tb_error(TB_ERR_UNSUPPORTED, "radiosity exchange over ranks in a build without MPI");
#endif
}

static tb_status tb__radx_allgatherf(void *ctx, const float *mine, size_t n_mine, float *all, const size_t *counts)
{
#ifdef TB_HAVE_MPI
    return tb__radx_gather(ctx, mine, n_mine, all, counts, MPI_FLOAT, sizeof *mine, n_mine);
#else
    (void)ctx, (void)mine, (void)n_mine, (void)all, (void)counts;
    return tb_error(TB_ERR_UNSUPPORTED, "radiosity exchange over ranks in a build without MPI");
#endif
}

static int tb__radx_agree(void *ctx, int flag)
{
    (void)ctx;
    return tb_dist_bcast_int(flag);
}

static tb_status tb__radx_agree_status(void *ctx, tb_status st)
{
    (void)ctx;
    return tb_dist_agree_status(st, NULL);
}

static tb_status tb__radx_report(void *ctx)
{
    (void)ctx;
    return tb_dist_report_stats("receivers");
}

static void tb__radx_fail(void *ctx, tb_status st)
{
    tb__radx *x = ctx;
    (void)st;
    fprintf(stderr, "testbed: rank %d of %d: %s; stopping every rank\n", x->ex.rank, x->ex.ranks, tb_last_error());
    tb_dist_abort(1);
}

tb_rad_exchange *tb_dist_rad_exchange_create(void)
{
    tb__radx *x = calloc(1, sizeof *x);
    int R = tb_dist_size();
    if (x) {
        x->counts = calloc((size_t)R, sizeof *x->counts);
        x->displs = calloc((size_t)R, sizeof *x->displs);
    }
    if (!x || !x->counts || !x->displs) {
        if (x)
            free(x->counts), free(x->displs), free(x);
        tb_error(TB_ERR_NOMEM, "out of memory for the radiosity exchange");
        return NULL;
    }
    x->last = tb__dist_now();
#if defined(TB_HAVE_MPI) && defined(__linux__)
    /* the waits' short sleeps (5 us and up) as asked, not 50 us late
     * (Linux's default timer slack; this thread's, and those made later) */
    if (R > 1)
        (void)prctl(PR_SET_TIMERSLACK, 1000UL, 0UL, 0UL, 0UL);
#endif
    x->spin = TB__RADX_SPIN_US * 1e-6;
    const char *e = getenv("TB_DIST_SPIN_US");
    if (e && *e) {
        char *end = NULL;
        double us = strtod(e, &end);
        if (*end || !(us >= 0.0 && us <= 1e7)) {
            free(x->counts), free(x->displs), free(x);
            tb_error(TB_ERR_ARG, "TB_DIST_SPIN_US='%s': not microseconds in 0..1e7", e);
            return NULL;
        }
        x->spin = us * 1e-6;
    }
    x->ex = (tb_rad_exchange){.ctx = x, .rank = tb_dist_rank(), .ranks = R, .allgather = tb__radx_allgather,
                              .allgatherf = tb__radx_allgatherf,
                              .allgather_state = tb__radx_allgather_state, .select = tb__radx_select,
                              .agree = tb__radx_agree, .agree_status = tb__radx_agree_status,
                              .report = tb__radx_report, .fail = tb__radx_fail};
    return &x->ex;
}

void tb_dist_rad_exchange_free(tb_rad_exchange *ex)
{
    if (!ex)
        return;
    tb__radx *x = ex->ctx;
#ifdef TB_HAVE_MPI
    if (x->type_n)
        MPI_Type_free(&x->type);
    if (x->op_made)
        MPI_Op_free(&x->op);
#endif
    free(x->counts);
    free(x->displs);
    free(x);
}
