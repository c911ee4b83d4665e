/* Tiles over ranks (tiles.h). The MPI calls are made one thread at a time
 * (under the `mpi` lock: MPI_THREAD_SERIALIZED) by whichever thread gets
 * there: render threads between their tiles, and on rank 0 also a
 * communication thread of its own, mostly asleep, so that requests for
 * tiles are answered while rank 0's render threads are inside a tile (or
 * parked by the scheduler on a loaded machine). Rank 0 answers requests
 * and takes in the others' packed tiles (merging them into the film, which
 * orders them); a worker asks ahead, keeps its queue filled and sends its
 * finished tiles between tiles, and polls while it has nothing to render.
 * Where a thread waits it polls with short, growing sleeps rather than
 * block in MPI (Open MPI's blocking calls spin a core the renderer needs). */
#include "host/dist/tiles.h"
#include "host/dist/dist.h"
#include "host/dist/dist_internal.h"
#include "util/base/fault.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <omp.h>

#ifdef TB_HAVE_MPI
#include <mpi.h>
#endif

/* Microseconds a waiting thread sleeps between polls: from the first,
 * doubling while nothing moves up to the last (a small fraction of a tile's
 * time), back to the first once something does, so a burst of messages is
 * answered at once and an idle wait costs little CPU. */
#define TB__TILES_POLL_MIN_US 20
#define TB__TILES_POLL_MAX_US 400

/* Once rank 0 knows its tiles' time, its communication thread polls every
 * half tile (within these bounds) instead: its render threads answer
 * between their tiles anyway, it only stands in for one that is inside a
 * long tile or parked, and each wake-up costs CPU the renders need (on 2
 * cores, 20-400 µs polls were several wake-ups per tile). */
#define TB__TILES_COMM_MIN_US 50
#define TB__TILES_COMM_MAX_US 2000

/* Seconds of rendering a worker keeps queued (at least four tiles per
 * thread): more than the communication thread's longest poll, so a worker
 * with short tiles does not run dry waiting for an answer. */
#define TB__TILES_AHEAD_SECONDS 0.004

/* A finished tile on its way out of a worker (buf NULL: a skip). */
typedef struct tb__outgoing {
    int index;
    void *buf;
    size_t len;
} tb__outgoing;

/* One exchange: the pass's shared state. */
typedef struct tb__tiles {
    tb_tile_exchange ex;   /* the callbacks handed to the renderer (ex.ctx == this) */
    pthread_mutex_t lock;  /* every field below that two threads touch */
    pthread_mutex_t mpi;   /* held by the one thread making MPI calls; guards the MPI-side fields */
    int threads;           /* this rank's render threads */
    int ahead;             /* tiles a worker keeps queued: it asks for what its queue lacks */
    tb_film *film;         /* this pass's film */
    tb_progress *progress; /* rank 0: counts the pixels of remote tiles */
    const atomic_int *cancel; /* rank 0: set -> no more grants */
    double t_pass;         /* clock at begin_pass */
    double wait;           /* seconds render threads waited for tiles, and the end of the pass */
    uint64_t bytes, msgs, units; /* this pass's sends, and tiles rendered here */
    tb_status comm_err;    /* the first failure of the exchange itself (its message in comm_msg) */
    char comm_msg[512];
    /* rank 0 */
    int next, ntiles;      /* the next tile to hand out; tiles in the pass */
    int owed;              /* tiles granted to workers and not yet back */
    int workers_done;      /* workers told that the pass has no tiles left */
    bool comm_running;     /* rank 0's communication thread was started this pass */
    pthread_t comm;
    atomic_int comm_stop;  /* set by end_pass once the pass is over everywhere */
    void *rbuf;            /* (mpi) the receive buffer, and its bytes */
    size_t rcap;
    /* worker */
    int *queue, qhead, qlen, qcap; /* granted tiles not yet claimed (ring) */
    bool done;             /* rank 0 said no tiles are left */
    tb__outgoing *outbox;  /* finished tiles not yet handed to MPI */
    int nout, out_cap;
    bool asked;            /* (mpi) a request is out, its grant awaited in greq */
    int grant[2];          /* (mpi) the grant's first tile and count */
#ifdef TB_HAVE_MPI
    MPI_Request greq;      /* (mpi) */
    MPI_Request *sreq;     /* (mpi) sends in flight and their buffers */
#endif
    void **sbuf;
    int nsend, send_cap;
} tb__tiles;

/* Sleeps *us microseconds after a poll that moved nothing (and doubles it
 * for the next), or resets *us after one that moved something. */
static void tb__tiles_pause(int *us, int moved)
{
    if (moved) {
        *us = TB__TILES_POLL_MIN_US;
        return;
    }
    struct timespec ts = {0, *us * 1000L};
    nanosleep(&ts, NULL);
    *us = *us * 2 < TB__TILES_POLL_MAX_US ? *us * 2 : TB__TILES_POLL_MAX_US;
}

/* Wall seconds a render thread of this rank spends per tile so far this
 * pass (its waits left out), or 0 until each thread has had a tile. */
static double tb__tiles_tile_seconds(tb__tiles *t)
{
    pthread_mutex_lock(&t->lock);
    uint64_t units = t->units;
    double busy = tb__dist_now() - t->t_pass - t->wait;
    pthread_mutex_unlock(&t->lock);
    return units >= (uint64_t)t->threads && busy > 0.0 ? busy * t->threads / (double)units : 0.0;
}

#ifdef TB_HAVE_MPI

/* Records the exchange's first failure (`st`, message in tb_last_error()). */
static void tb__tiles_fail(tb__tiles *t, tb_status st)
{
    pthread_mutex_lock(&t->lock);
    if (!t->comm_err) {
        t->comm_err = st;
        snprintf(t->comm_msg, sizeof t->comm_msg, "%s", tb_last_error());
    }
    pthread_mutex_unlock(&t->lock);
}

/* Rank 0: one remote tile of `len` bytes from `src`, received into the
 * exchange's buffer and merged (after a failure: received and dropped, so
 * the pass still ends on every rank). MPI lock held. */
static tb_status tb__tiles_root_tile(tb__tiles *t, int src, int len)
{
    size_t n = len > 0 ? (size_t)len : 1;
    if (n > t->rcap) {
        void *b = realloc(t->rbuf, n);
        if (!b) {
            /* the message cannot be taken off the wire without a buffer:
             * nothing is left but to stop the job */
            fprintf(stderr, "testbed: rank 0 of %d: tile exchange: out of memory for a tile of %d bytes from "
                    "rank %d; stopping every rank\n", t->ex.ranks, len, src);
            tb_dist_abort(1);
        }
        t->rbuf = b, t->rcap = n;
    }
    MPI_Recv(t->rbuf, len, MPI_BYTE, src, TB__TAG_TILE, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    pthread_mutex_lock(&t->lock);
    bool failed = t->comm_err != TB_OK;
    pthread_mutex_unlock(&t->lock);
    if (failed)
        return TB_OK;
    bool inject = tb_fault("tile-merge");
    tb_film_tile *tile = inject ? NULL : tb_film_tile_unpack(t->film, t->rbuf, (size_t)len);
    if (inject)
        tb_error(TB_ERR_NOMEM, "out of memory unpacking a tile (injected: TB_FAULT)");
    if (!tile)
        return tb_error_context(inject ? TB_ERR_NOMEM : TB_ERR_FORMAT, "rank 0: merging a tile from rank %d", src);
    tb_tile_rect r = tb_film_tile_pixels(tile);
    tb_status st = tb_film_tile_submit(t->film, tile); /* thread-safe: the film orders the merges */
    if (!st && t->progress)
        tb_progress_add(t->progress, (int64_t)(r.x1 - r.x0) * (r.y1 - r.y0));
    return st;
}

/* Rank 0: one waiting message, if there is one (1: handled one). MPI lock
 * held. */
static int tb__tiles_root_one(tb__tiles *t)
{
    int flag = 0;
    MPI_Status ms;
    MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &ms);
    if (!flag)
        return 0;
    int src = ms.MPI_SOURCE;
    tb_status st = TB_OK;
    if (ms.MPI_TAG == TB__TAG_REQUEST) {
        int want = 0;
        MPI_Recv(&want, 1, MPI_INT, src, TB__TAG_REQUEST, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        pthread_mutex_lock(&t->lock);
        int left = t->ntiles - t->next;
        if ((t->cancel && atomic_load(t->cancel)) || t->comm_err)
            left = 0;
        /* guided: never more than a share of what is left, so the last
         * tiles spread over the ranks */
        int share = left / (2 * t->ex.ranks);
        int n = want < share ? want : share;
        if (n < 1)
            n = left > 0 ? 1 : 0;
        int g[2] = {t->next, n};
        t->next += n;
        t->owed += n;
        if (n == 0)
            t->workers_done++;
        t->bytes += sizeof g;
        t->msgs += 2;
        pthread_mutex_unlock(&t->lock);
        MPI_Send(g, 2, MPI_INT, src, TB__TAG_GRANT, MPI_COMM_WORLD);
    } else if (ms.MPI_TAG == TB__TAG_TILE) {
        int len = 0;
        MPI_Get_count(&ms, MPI_BYTE, &len);
        st = tb__tiles_root_tile(t, src, len);
        pthread_mutex_lock(&t->lock);
        t->owed--;
        t->msgs++;
        pthread_mutex_unlock(&t->lock);
    } else if (ms.MPI_TAG == TB__TAG_SKIP) {
        int index = -1;
        MPI_Recv(&index, 1, MPI_INT, src, TB__TAG_SKIP, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        pthread_mutex_lock(&t->lock);
        bool failed = t->comm_err != TB_OK;
        pthread_mutex_unlock(&t->lock);
        if (!failed)
            st = tb_film_tile_skip(t->film, index);
        pthread_mutex_lock(&t->lock);
        t->owed--;
        t->msgs++;
        pthread_mutex_unlock(&t->lock);
    } else {
        st = tb_error(TB_ERR_FORMAT, "tile exchange: unexpected message tag %d from rank %d", ms.MPI_TAG, src);
    }
    if (st)
        tb__tiles_fail(t, st);
    return 1;
}

/* A worker: moves a grant that came into the queue, hands finished tiles
 * to MPI, frees the sends that completed and asks for more tiles while the
 * queue is short. 1 if anything moved. MPI lock held. */
static int tb__tiles_worker_poll(tb__tiles *t)
{
    int moved = 0;
    if (t->asked) {
        int flag = 0;
        MPI_Test(&t->greq, &flag, MPI_STATUS_IGNORE);
        if (flag) {
            t->asked = false, moved = 1;
            pthread_mutex_lock(&t->lock);
            if (t->grant[1] == 0)
                t->done = true;
            if (t->qlen + t->grant[1] > t->qcap) {
                /* rank 0's first grant follows its own thread count, which
                 * may exceed this rank's: the queue grows (in order) */
                int cap = t->qlen + t->grant[1] + t->ahead;
                int *q = malloc(sizeof *q * (size_t)cap);
                if (!q) {
                    pthread_mutex_unlock(&t->lock);
                    fprintf(stderr, "testbed: rank %d of %d: tile exchange: out of memory for a queue of %d tiles; "
                            "stopping every rank\n", t->ex.rank, t->ex.ranks, cap);
                    tb_dist_abort(1);
                }
                for (int k = 0; k < t->qlen; k++)
                    q[k] = t->queue[(t->qhead + k) % t->qcap];
                free(t->queue);
                t->queue = q, t->qhead = 0, t->qcap = cap;
            }
            for (int k = 0; k < t->grant[1]; k++)
                t->queue[(t->qhead + t->qlen++) % t->qcap] = t->grant[0] + k;
            pthread_mutex_unlock(&t->lock);
        }
    }
    /* the outbox, whole */
    pthread_mutex_lock(&t->lock);
    int nout = t->nout;
    if (t->nsend + nout > t->send_cap) {
        int cap = 2 * (t->nsend + nout) + 16;
        MPI_Request *r = realloc(t->sreq, sizeof *r * (size_t)cap);
        void **b = r ? realloc(t->sbuf, sizeof *b * (size_t)cap) : NULL;
        if (r)
            t->sreq = r;
        if (b)
            t->sbuf = b, t->send_cap = cap;
        else
            nout = t->send_cap - t->nsend; /* what fits; the rest waits for a completed send */
    }
    for (int i = 0; i < nout; i++) {
        tb__outgoing *o = &t->outbox[i];
        if (o->buf) {
            MPI_Isend(o->buf, (int)o->len, MPI_BYTE, 0, TB__TAG_TILE, MPI_COMM_WORLD, &t->sreq[t->nsend]);
            t->sbuf[t->nsend++] = o->buf;
        } else {
            MPI_Send(&o->index, 1, MPI_INT, 0, TB__TAG_SKIP, MPI_COMM_WORLD);
        }
        moved = 1;
    }
    if (nout > 0) /* (the outbox is NULL until the first tile: no pointer arithmetic on it) */
        memmove(t->outbox, t->outbox + nout, sizeof *t->outbox * (size_t)(t->nout - nout));
    t->nout -= nout;
    pthread_mutex_unlock(&t->lock);
    int ahead = t->ahead;
    double tile = tb__tiles_tile_seconds(t);
    if (tile > 0.0 && TB__TILES_AHEAD_SECONDS * t->threads / tile > ahead) /* short tiles: more of them */
        ahead = TB__TILES_AHEAD_SECONDS * t->threads / tile < 64.0 * t->threads
                    ? (int)(TB__TILES_AHEAD_SECONDS * t->threads / tile) + 1
                    : 64 * t->threads;
    pthread_mutex_lock(&t->lock);
    bool ask = !t->asked && !t->done && t->qlen < ahead;
    int want = 2 * ahead - t->qlen; /* refill to twice the low mark: a request per `ahead` tiles, not per tile */
    pthread_mutex_unlock(&t->lock);
    /* sends that completed */
    for (int i = 0; i < t->nsend;) {
        int flag = 0;
        MPI_Test(&t->sreq[i], &flag, MPI_STATUS_IGNORE);
        if (flag) {
            free(t->sbuf[i]);
            t->sreq[i] = t->sreq[t->nsend - 1], t->sbuf[i] = t->sbuf[t->nsend - 1];
            t->nsend--, moved = 1;
        } else {
            i++;
        }
    }
    if (ask) {
        MPI_Send(&want, 1, MPI_INT, 0, TB__TAG_REQUEST, MPI_COMM_WORLD);
        MPI_Irecv(t->grant, 2, MPI_INT, 0, TB__TAG_GRANT, MPI_COMM_WORLD, &t->greq);
        t->asked = true, moved = 1;
        pthread_mutex_lock(&t->lock);
        t->bytes += sizeof want;
        t->msgs += 2;
        pthread_mutex_unlock(&t->lock);
    }
    return moved;
}

#endif

/* Whatever MPI has for this rank: rank 0 answers every waiting message, a
 * worker polls (tb__tiles_worker_poll). `block`: wait for the MPI lock,
 * else skip if another thread holds it (it is doing the same). 1 if
 * anything moved. */
static int tb__tiles_service(tb__tiles *t, bool block)
{
    int moved = 0;
#ifdef TB_HAVE_MPI
    if (t->ex.ranks < 2)
        return 0;
    if (block)
        pthread_mutex_lock(&t->mpi);
    else if (pthread_mutex_trylock(&t->mpi) != 0)
        return 0;
    if (t->ex.rank == 0) {
        while (tb__tiles_root_one(t))
            moved = 1;
    } else {
        moved = tb__tiles_worker_poll(t);
    }
    pthread_mutex_unlock(&t->mpi);
#else
    (void)t, (void)block;
#endif
    return moved;
}

/* Rank 0's communication thread: answers the others while this rank's
 * render threads are inside their tiles (they answer too, between tiles),
 * so a worker's queue never waits for one of rank 0's tiles to end, even
 * when the scheduler has parked rank 0's render thread. Mostly asleep:
 * polls with growing sleeps. */
static void *tb__tiles_root_comm(void *arg)
{
    tb__tiles *t = arg;
    for (int pause = TB__TILES_POLL_MIN_US; !atomic_load(&t->comm_stop);) {
        int moved = tb__tiles_service(t, true);
        double tile = tb__tiles_tile_seconds(t);
        if (tile > 0.0) { /* every half tile, whatever moved */
            double us = 0.5e6 * tile;
            int fixed = us < TB__TILES_COMM_MIN_US ? TB__TILES_COMM_MIN_US
                        : us > TB__TILES_COMM_MAX_US ? TB__TILES_COMM_MAX_US : (int)us;
            tb__tiles_pause(&fixed, 0);
        } else {
            tb__tiles_pause(&pause, moved);
        }
    }
    return NULL;
}

static tb_status tb__tiles_begin(void *ctx, tb_film *film, int pass, tb_progress *progress, const atomic_int *cancel)
{
    (void)pass;
    tb__tiles *t = ctx;
    t->film = film;
    t->progress = progress;
    t->cancel = cancel;
    t->next = 0;
    t->ntiles = tb_film_tile_count(film);
    t->owed = t->workers_done = 0;
    t->qhead = t->qlen = t->nout = 0;
    t->done = t->asked = false;
    t->comm_err = TB_OK;
    t->wait = 0;
    t->bytes = t->msgs = t->units = 0;
    t->t_pass = tb__dist_now();
#ifdef TB_HAVE_MPI
    /* the first grants go out unasked (a worker's first request is
     * implied), so no worker waits for rank 0 to finish a tile first */
    if (t->ex.ranks > 1) {
        pthread_mutex_lock(&t->mpi);
        if (t->ex.rank == 0) {
            for (int w = 1; w < t->ex.ranks; w++) {
                int left = t->ntiles - t->next;
                int share = left / (2 * t->ex.ranks);
                int n = t->ahead < share ? t->ahead : share > 0 ? share : left > 0 ? 1 : 0;
                int g[2] = {t->next, n};
                t->next += n, t->owed += n;
                if (n == 0)
                    t->workers_done++;
                t->bytes += sizeof g;
                t->msgs++;
                MPI_Send(g, 2, MPI_INT, w, TB__TAG_GRANT, MPI_COMM_WORLD);
            }
            atomic_store(&t->comm_stop, 0);
            if (pthread_create(&t->comm, NULL, tb__tiles_root_comm, t) == 0)
                t->comm_running = true;
            /* else the render threads answer between their tiles alone */
        } else {
            MPI_Irecv(t->grant, 2, MPI_INT, 0, TB__TAG_GRANT, MPI_COMM_WORLD, &t->greq);
            t->asked = true;
        }
        pthread_mutex_unlock(&t->mpi);
    }
#endif
    return TB_OK;
}

static int tb__tiles_claim(void *ctx, int *index)
{
    tb__tiles *t = ctx;
    int got = 0;
    if (t->ex.rank == 0) {
        /* between tiles: answer the others first */
        tb__tiles_service(t, false);
        pthread_mutex_lock(&t->lock);
        if (t->next < t->ntiles && !t->comm_err) {
            *index = t->next++;
            got = 1;
        }
    } else {
        tb__tiles_service(t, false);
        pthread_mutex_lock(&t->lock);
        double t0 = tb__dist_now();
        bool waited = false;
        for (int pause = TB__TILES_POLL_MIN_US; t->qlen == 0 && !t->done && !t->comm_err;) {
            pthread_mutex_unlock(&t->lock);
            tb__tiles_pause(&pause, tb__tiles_service(t, false));
            waited = true;
            pthread_mutex_lock(&t->lock);
        }
        if (waited) /* a rank's wait: its threads' waits over its threads */
            t->wait += (tb__dist_now() - t0) / t->threads;
        if (t->qlen > 0) {
            *index = t->queue[t->qhead];
            t->qhead = (t->qhead + 1) % t->qcap;
            t->qlen--;
            got = 1;
        }
    }
    if (got)
        t->units++;
    pthread_mutex_unlock(&t->lock);
    return got;
}

static tb_status tb__tiles_finish(void *ctx, tb_film *film, int index, tb_film_tile *tile)
{
    tb__tiles *t = ctx;
    if (t->ex.rank == 0)
        return tile ? tb_film_tile_submit(film, tile) : tb_film_tile_skip(film, index);
    tb__outgoing o = {.index = index};
    if (tile) {
        o.len = tb_film_tile_packed_size(tile);
        if (!(o.buf = malloc(o.len))) {
            tb_film_tile_free(tile);
            return tb_error(TB_ERR_NOMEM, "out of memory packing tile %d", index);
        }
        tb_film_tile_pack(tile, o.buf);
        tb_film_tile_free(tile);
    }
    pthread_mutex_lock(&t->lock);
    if (t->nout == t->out_cap) {
        int cap = 2 * t->out_cap + 16;
        tb__outgoing *p = realloc(t->outbox, sizeof *p * (size_t)cap);
        if (!p) {
            pthread_mutex_unlock(&t->lock);
            free(o.buf);
            return tb_error(TB_ERR_NOMEM, "out of memory queueing tile %d", index);
        }
        t->outbox = p, t->out_cap = cap;
    }
    t->outbox[t->nout++] = o;
    t->bytes += o.buf ? o.len : sizeof(int);
    t->msgs++;
    pthread_mutex_unlock(&t->lock);
    return TB_OK;
}

/* True once this rank's part of the pass is over: rank 0 has every tile
 * back and every worker told, a worker has been told and sent everything. */
static bool tb__tiles_over(tb__tiles *t)
{
    pthread_mutex_lock(&t->lock);
    bool over = t->ex.rank == 0 ? t->owed == 0 && t->workers_done == t->ex.ranks - 1
                                : t->done && t->nout == 0 && t->nsend == 0 && !t->asked;
    pthread_mutex_unlock(&t->lock);
    return over;
}

static tb_status tb__tiles_end(void *ctx, tb_film *film, tb_aa_stats *stats, tb_status mine)
{
    tb__tiles *t = ctx;
    tb_status st = mine;
    char why[512];
    snprintf(why, sizeof why, "%s", mine ? tb_last_error() : "");
    double t0 = tb__dist_now();
    /* this rank's threads are done: serve the others (rank 0) or send the
     * last tiles (a worker) until the pass is over everywhere */
    for (int pause = TB__TILES_POLL_MIN_US; t->ex.ranks > 1 && !tb__tiles_over(t);)
        tb__tiles_pause(&pause, tb__tiles_service(t, !t->comm_running));
    if (t->comm_running) {
        atomic_store(&t->comm_stop, 1);
        pthread_join(t->comm, NULL);
        t->comm_running = false;
    }
    t->wait += tb__dist_now() - t0;
    if (st)
        tb_error(st, "%s", why);
    else if (t->comm_err)
        st = tb_error(t->comm_err, "%s", t->comm_msg);
    /* rank 0: tiles never handed out (a cancel) are skipped */
    while (!st && t->ex.rank == 0 && t->next < t->ntiles) {
        st = tb_film_tile_skip(film, t->next++);
        stats->tiles_skipped++;
    }
    /* a failure anywhere stops every rank, with the failing rank's message */
    if (t->ex.ranks > 1) {
        int who = -1;
        st = tb_dist_agree_status(st, &who);
        if (st && who != t->ex.rank)
            tb_error_context(st, "rank %d", who);
    }
#ifdef TB_HAVE_MPI
    if (!st && t->ex.ranks > 1) {
        double t1 = tb__dist_now();
        uint64_t sums[5] = {stats->samples, stats->ring_samples, stats->pixels, stats->pixels_refined,
                            (uint64_t)stats->tiles_skipped};
        int mx = stats->max_spp_used;
        MPI_Allreduce(MPI_IN_PLACE, sums, 5, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
        MPI_Allreduce(MPI_IN_PLACE, &mx, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
        t->wait += tb__dist_now() - t1;
        t->msgs += 2;
        stats->samples = sums[0], stats->ring_samples = sums[1], stats->pixels = sums[2];
        stats->pixels_refined = sums[3], stats->tiles_skipped = (int)sums[4];
        stats->max_spp_used = mx;
    }
#endif
    /* work: the pass less the waits (for tiles, for the others at its end) */
    tb__dist_account(tb__dist_now() - t->t_pass - t->wait, t->wait, t->bytes, t->msgs, t->units);
    return st;
}

static int tb__tiles_agree(void *ctx, int flag)
{
    (void)ctx;
    return tb_dist_bcast_int(flag);
}

static tb_status tb__tiles_agree_status(void *ctx, tb_status st)
{
    (void)ctx;
    return tb_dist_agree_status(st, NULL);
}

static tb_status tb__tiles_report(void *ctx)
{
    (void)ctx;
    return tb_dist_report_stats("tiles");
}

tb_tile_exchange *tb_dist_tiles_create(int threads)
{
    tb__tiles *t = calloc(1, sizeof *t);
    if (!t) {
        tb_error(TB_ERR_NOMEM, "out of memory for the tile exchange");
        return NULL;
    }
    /* four tiles per thread: rank 0 answers a request between its own
     * tiles, so a worker's queue must last through one of rank 0's tiles
     * (which may take longer than the worker's) while the grant travels */
    t->threads = threads > 0 ? threads : omp_get_max_threads();
    t->ahead = 4 * t->threads;
    t->qcap = 2 * t->ahead + 2;
    t->queue = malloc(sizeof *t->queue * (size_t)t->qcap);
    if (!t->queue) {
        free(t);
        tb_error(TB_ERR_NOMEM, "out of memory for the tile exchange");
        return NULL;
    }
    pthread_mutex_init(&t->lock, NULL);
    pthread_mutex_init(&t->mpi, NULL);
    t->ex = (tb_tile_exchange){.ctx = t, .rank = tb_dist_rank(), .ranks = tb_dist_size(),
                               .begin_pass = tb__tiles_begin, .claim = tb__tiles_claim,
                               .finish = tb__tiles_finish, .end_pass = tb__tiles_end, .agree = tb__tiles_agree,
                               .agree_status = tb__tiles_agree_status, .report = tb__tiles_report};
    return &t->ex;
}

void tb_dist_tiles_free(tb_tile_exchange *ex)
{
    if (!ex)
        return;
    tb__tiles *t = ex->ctx;
    pthread_mutex_destroy(&t->lock);
    pthread_mutex_destroy(&t->mpi);
    for (int i = 0; i < t->nout; i++)
        free(t->outbox[i].buf);
    free(t->outbox);
    free(t->queue);
    free(t->rbuf);
#ifdef TB_HAVE_MPI
    free(t->sreq);
#endif
    free(t->sbuf);
    free(t);
}
