/* Tiles over ranks (tiles.h). During a pass every MPI call of a rank is
 * made by one communication thread of its own (MPI_THREAD_SERIALIZED: the
 * main thread's collectives come after it has been joined), so messages
 * move while the OpenMP threads render: rank 0's thread grants tile ranges
 * and receives packed tiles (merging them into the film, which orders
 * them), a worker's thread asks ahead, keeps its queue filled and sends its
 * finished tiles. The render threads only touch the queue and the outbox,
 * under the exchange's lock. The threads poll with short, growing sleeps
 * rather than block in MPI (Open MPI's blocking calls spin a core the
 * renderer needs). */
#include "host/dist/tiles.h"
#include "host/dist/dist.h"
#include "host/dist/dist_internal.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <omp.h>

#ifdef TB_HAVE_MPI
#include <mpi.h>
#endif

/* Microseconds a communication thread sleeps when nothing moved: from the
 * first, doubling while nothing moves up to the last (a small fraction of
 * a tile's time), back to the first once something does, so a burst of
 * messages is answered at once and an idle wait costs little CPU. */
#define TB__TILES_POLL_MIN_US 20
#define TB__TILES_POLL_MAX_US 400

/* A finished tile on its way out of a worker (buf NULL: a skip). */
typedef struct tb__outgoing {
    int index;
    void *buf;
    size_t len;
} tb__outgoing;

/* One exchange: the pass's shared state, guarded by `lock`. */
typedef struct tb__tiles {
    tb_tile_exchange ex;   /* the callbacks handed to the renderer (ex.ctx == this) */
    pthread_mutex_t lock;  /* every field below that two threads touch */
    pthread_cond_t moved;  /* a worker's queue got tiles, or rank 0 said there are none left */
    int ahead;             /* tiles a worker asks for at a time and keeps queued (twice its threads) */
    tb_film *film;         /* this pass's film */
    tb_progress *progress; /* rank 0: counts the pixels of remote tiles */
    const atomic_int *cancel; /* rank 0: set -> no more grants */
    double t_pass;         /* clock at begin_pass */
    double wait;           /* seconds render threads waited for tiles, and the end of the pass */
    uint64_t bytes, msgs, units; /* this pass's sends, and tiles rendered here */
    bool comm_running;     /* the communication thread was started this pass */
    pthread_t comm;
    bool local_done;       /* this rank's render threads have all left the pass */
    tb_status comm_err;    /* the communication thread's failure (its message in comm_msg) */
    char comm_msg[512];
    /* rank 0 */
    int next, ntiles;      /* the next tile to hand out; tiles in the pass */
    int owed;              /* tiles granted to workers and not yet back */
    int workers_done;      /* workers told that the pass has no tiles left */
    /* worker */
    int *queue, qhead, qlen, qcap; /* granted tiles not yet claimed (ring) */
    bool done;             /* rank 0 said no tiles are left */
    tb__outgoing *outbox;  /* finished tiles for the communication thread to send */
    int nout, out_cap;
} tb__tiles;

#ifdef TB_HAVE_MPI

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

/* Records the communication thread's first failure. Lock held. */
static void tb__tiles_fail(tb__tiles *t, tb_status st)
{
    if (!t->comm_err) {
        t->comm_err = st;
        snprintf(t->comm_msg, sizeof t->comm_msg, "%s", tb_last_error());
    }
}

/* Rank 0: one waiting message, if there is one (1: handled one). The
 * communication thread, lock not held (taken for the shared fields). */
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
        if (t->cancel && atomic_load(t->cancel))
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
        void *buf = malloc(len > 0 ? (size_t)len : 1);
        if (!buf) {
            st = tb_error(TB_ERR_NOMEM, "out of memory for a tile of %d bytes from rank %d", len, src);
        } else {
            MPI_Recv(buf, len, MPI_BYTE, src, TB__TAG_TILE, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
            tb_film_tile *tile = tb_film_tile_unpack(t->film, buf, (size_t)len);
            free(buf);
            if (!tile) {
                st = tb_error_context(TB_ERR_FORMAT, "tile from rank %d", src);
            } else {
                tb_tile_rect r = tb_film_tile_pixels(tile);
                st = tb_film_tile_submit(t->film, tile); /* thread-safe: the film orders the merges */
                if (!st && t->progress)
                    tb_progress_add(t->progress, (int64_t)(r.x1 - r.x0) * (r.y1 - r.y0));
            }
        }
        pthread_mutex_lock(&t->lock);
        t->owed--;
        t->msgs++;
        pthread_mutex_unlock(&t->lock);
    } else if (ms.MPI_TAG == TB__TAG_SKIP) {
        int index = -1;
        MPI_Recv(&index, 1, MPI_INT, src, TB__TAG_SKIP, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        st = tb_film_tile_skip(t->film, index);
        pthread_mutex_lock(&t->lock);
        t->owed--;
        t->msgs++;
        pthread_mutex_unlock(&t->lock);
    } else {
        st = tb_error(TB_ERR_FORMAT, "tile exchange: unexpected message tag %d from rank %d", ms.MPI_TAG, src);
    }
    if (st) {
        pthread_mutex_lock(&t->lock);
        tb__tiles_fail(t, st);
        pthread_mutex_unlock(&t->lock);
    }
    return 1;
}

/* Rank 0's communication thread: answers until every worker has been told
 * the pass is over, every granted tile is back and this rank's own
 * threads are done. */
static void *tb__tiles_root_comm(void *arg)
{
    tb__tiles *t = arg;
    int pause = TB__TILES_POLL_MIN_US;
    for (;;) {
        int moved = 0;
        while (tb__tiles_root_one(t))
            moved = 1;
        pthread_mutex_lock(&t->lock);
        bool over = t->comm_err || (t->local_done && t->owed == 0 && t->workers_done == t->ex.ranks - 1);
        pthread_mutex_unlock(&t->lock);
        if (over)
            return NULL;
        tb__tiles_pause(&pause, moved);
    }
}

/* A worker's communication thread: keeps a request for tiles in flight
 * while its queue is short, moves grants into the queue, sends finished
 * tiles, and ends once rank 0 said there are no more tiles, the render
 * threads are done and every tile has left. */
static void *tb__tiles_worker_comm(void *arg)
{
    tb__tiles *t = arg;
    int grant[2] = {0, 0};
    MPI_Request greq = MPI_REQUEST_NULL;
    bool asked = false;
    int nsend = 0, send_cap = 0;
    MPI_Request *sreq = NULL;
    void **sbuf = NULL;
    int pause = TB__TILES_POLL_MIN_US;
    for (;;) {
        int moved = 0;
        /* the grant in flight */
        if (asked) {
            int flag = 0;
            MPI_Test(&greq, &flag, MPI_STATUS_IGNORE);
            if (flag) {
                asked = false, moved = 1;
                pthread_mutex_lock(&t->lock);
                if (grant[1] == 0)
                    t->done = true;
                for (int k = 0; k < grant[1]; k++)
                    t->queue[(t->qhead + t->qlen++) % t->qcap] = grant[0] + k;
                pthread_cond_broadcast(&t->moved);
                pthread_mutex_unlock(&t->lock);
            }
        }
        /* take the outbox */
        pthread_mutex_lock(&t->lock);
        int nout = t->nout;
        tb__outgoing out[64];
        if (nout > 64)
            nout = 64;
        memcpy(out, t->outbox, sizeof *out * (size_t)nout);
        memmove(t->outbox, t->outbox + nout, sizeof *out * (size_t)(t->nout - nout));
        t->nout -= nout;
        bool ask = !asked && !t->done && t->qlen < t->ahead;
        bool finished = t->done && t->local_done && t->nout == 0;
        pthread_mutex_unlock(&t->lock);
        if (nsend + nout > send_cap) {
            int cap = 2 * (nsend + nout) + 16;
            MPI_Request *r = realloc(sreq, sizeof *r * (size_t)cap);
            void **b = r ? realloc(sbuf, sizeof *b * (size_t)cap) : NULL;
            if (r)
                sreq = r;
            if (!r || !b) {
                pthread_mutex_lock(&t->lock);
                tb__tiles_fail(t, tb_error(TB_ERR_NOMEM, "out of memory for tiles in flight"));
                pthread_mutex_unlock(&t->lock);
                break;
            }
            sbuf = b, send_cap = cap;
        }
        for (int i = 0; i < nout; i++) {
            if (out[i].buf) {
                MPI_Isend(out[i].buf, (int)out[i].len, MPI_BYTE, 0, TB__TAG_TILE, MPI_COMM_WORLD, &sreq[nsend]);
                sbuf[nsend++] = out[i].buf;
            } else {
                MPI_Send(&out[i].index, 1, MPI_INT, 0, TB__TAG_SKIP, MPI_COMM_WORLD);
            }
            moved = 1;
        }
        /* sends that completed */
        for (int i = 0; i < nsend;) {
            int flag = 0;
            MPI_Test(&sreq[i], &flag, MPI_STATUS_IGNORE);
            if (flag) {
                free(sbuf[i]);
                sreq[i] = sreq[nsend - 1], sbuf[i] = sbuf[nsend - 1];
                nsend--, moved = 1;
            } else {
                i++;
            }
        }
        if (ask) {
            int want = t->ahead;
            MPI_Send(&want, 1, MPI_INT, 0, TB__TAG_REQUEST, MPI_COMM_WORLD);
            MPI_Irecv(grant, 2, MPI_INT, 0, TB__TAG_GRANT, MPI_COMM_WORLD, &greq);
            asked = true, moved = 1;
            pthread_mutex_lock(&t->lock);
            t->bytes += sizeof want;
            t->msgs += 2;
            pthread_mutex_unlock(&t->lock);
        }
        if (finished && nout == 0 && !asked) {
            MPI_Waitall(nsend, sreq, MPI_STATUSES_IGNORE);
            for (int i = 0; i < nsend; i++)
                free(sbuf[i]);
            nsend = 0;
            break;
        }
        tb__tiles_pause(&pause, moved);
    }
    free(sreq);
    free(sbuf);
    return NULL;
}

#endif

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
    t->done = t->local_done = false;
    t->comm_err = TB_OK;
    t->wait = 0;
    t->bytes = t->msgs = t->units = 0;
    t->t_pass = tb__dist_now();
    t->comm_running = false;
#ifdef TB_HAVE_MPI
    if (t->ex.ranks > 1) {
        if (pthread_create(&t->comm, NULL, t->ex.rank == 0 ? tb__tiles_root_comm : tb__tiles_worker_comm, t) != 0)
            return tb_error(TB_ERR_NOMEM, "tile exchange: cannot start the communication thread");
        t->comm_running = true;
    }
#endif
    return TB_OK;
}

static int tb__tiles_claim(void *ctx, int *index)
{
    tb__tiles *t = ctx;
    int got = 0;
    pthread_mutex_lock(&t->lock);
    if (t->ex.rank == 0) {
        if (t->next < t->ntiles) {
            *index = t->next++;
            got = 1;
        }
    } else {
        double t0 = tb__dist_now();
        bool waited = false;
        while (t->qlen == 0 && !t->done && !t->comm_err) {
            pthread_cond_wait(&t->moved, &t->lock);
            waited = true;
        }
        if (waited)
            t->wait += tb__dist_now() - t0;
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

static tb_status tb__tiles_end(void *ctx, tb_film *film, tb_aa_stats *stats, tb_status mine)
{
    tb__tiles *t = ctx;
    tb_status st = mine;
    char why[512];
    snprintf(why, sizeof why, "%s", mine ? tb_last_error() : "");
    double t0 = tb__dist_now();
    pthread_mutex_lock(&t->lock);
    t->local_done = true;
    pthread_mutex_unlock(&t->lock);
    if (t->comm_running) {
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
    /* two tiles per thread: one rendering, one waiting, while the next
     * grant travels */
    t->ahead = 2 * (threads > 0 ? threads : omp_get_max_threads());
    t->qcap = 2 * t->ahead + 2;
    t->queue = malloc(sizeof *t->queue * (size_t)t->qcap);
    if (!t->queue) {
        free(t);
        tb_error(TB_ERR_NOMEM, "out of memory for the tile exchange");
        return NULL;
    }
    pthread_mutex_init(&t->lock, NULL);
    pthread_cond_init(&t->moved, NULL);
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
    pthread_cond_destroy(&t->moved);
    for (int i = 0; i < t->nout; i++)
        free(t->outbox[i].buf);
    free(t->outbox);
    free(t->queue);
    free(t);
}
