/* Tiles over ranks (tiles.h): rank 0 grants tile ranges and merges packed
 * tiles; the other ranks ask ahead, render and send. Every MPI call is made
 * under the exchange's lock (MPI_THREAD_SERIALIZED). */
#include "host/dist/tiles.h"
#include "host/dist/dist.h"
#include "host/dist/dist_internal.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <omp.h>

#ifdef TB_HAVE_MPI
#include <mpi.h>
#endif

/* One exchange: the pass's state on rank 0 (what is granted and owed) and
 * on a worker (its queue of granted tiles and its request in flight). */
typedef struct tb__tiles {
    tb_tile_exchange ex;   /* the callbacks handed to the renderer (first: ex == this) */
    pthread_mutex_t lock;  /* every MPI call and the fields below */
    int ahead;             /* tiles a worker asks for at a time and keeps queued (twice its threads) */
    tb_film *film;         /* this pass's film */
    tb_progress *progress; /* rank 0: counts the pixels of remote tiles */
    const atomic_int *cancel; /* rank 0: set -> no more grants */
    double t_pass;         /* clock at begin_pass */
    double wait;           /* seconds blocked this pass */
    uint64_t bytes, msgs, units; /* this pass's sends and tiles rendered here */
    /* rank 0 */
    int next, ntiles;      /* the next tile to grant; tiles in the pass */
    int owed;              /* tiles granted to workers and not yet back */
    int workers_done;      /* workers told that the pass has no tiles left */
    /* worker */
    int *queue, qhead, qlen, qcap; /* granted tiles not yet claimed (ring) */
    bool asked;            /* a request is in flight */
    bool done;             /* rank 0 said no tiles are left */
#ifdef TB_HAVE_MPI
    int grant[2];          /* the answer to the request in flight */
    MPI_Request grant_req;
#endif
} tb__tiles;

#ifdef TB_HAVE_MPI

/* Rank 0: answers every message waiting (requests, tiles, skips). Lock held. */
static tb_status tb__tiles_serve(tb__tiles *t, bool block)
{
    for (;;) {
        int flag = 0;
        MPI_Status ms;
        if (block) {
            double t0 = tb__dist_now();
            MPI_Probe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &ms);
            t->wait += tb__dist_now() - t0;
            flag = 1;
            block = false; /* then drain whatever else is there */
        } else {
            MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &ms);
        }
        if (!flag)
            return TB_OK;
        int src = ms.MPI_SOURCE;
        if (ms.MPI_TAG == TB__TAG_REQUEST) {
            int want = 0;
            MPI_Recv(&want, 1, MPI_INT, src, TB__TAG_REQUEST, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
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
            MPI_Send(g, 2, MPI_INT, src, TB__TAG_GRANT, MPI_COMM_WORLD);
            t->bytes += sizeof g;
            t->msgs += 2;
        } else if (ms.MPI_TAG == TB__TAG_TILE) {
            int len = 0;
            MPI_Get_count(&ms, MPI_BYTE, &len);
            void *buf = malloc((size_t)len);
            if (!buf)
                return tb_error(TB_ERR_NOMEM, "out of memory for a tile of %d bytes from rank %d", len, src);
            MPI_Recv(buf, len, MPI_BYTE, src, TB__TAG_TILE, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
            t->msgs++;
            tb_film_tile *tile = tb_film_tile_unpack(t->film, buf, (size_t)len);
            free(buf);
            if (!tile)
                return tb_error_context(TB_ERR_FORMAT, "tile from rank %d", src);
            tb_tile_rect r = tb_film_tile_pixels(tile);
            tb_status st = tb_film_tile_submit(t->film, tile);
            if (st)
                return st;
            t->owed--;
            if (t->progress)
                tb_progress_add(t->progress, (int64_t)(r.x1 - r.x0) * (r.y1 - r.y0));
        } else if (ms.MPI_TAG == TB__TAG_SKIP) {
            int index = -1;
            MPI_Recv(&index, 1, MPI_INT, src, TB__TAG_SKIP, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
            t->msgs++;
            tb_status st = tb_film_tile_skip(t->film, index);
            if (st)
                return st;
            t->owed--;
        } else {
            return tb_error(TB_ERR_FORMAT, "tile exchange: unexpected message tag %d from rank %d", ms.MPI_TAG,
                            src);
        }
    }
}

/* A worker: takes the grant in flight into the queue (waiting for it if
 * `block`). Lock held. */
static void tb__tiles_take_grant(tb__tiles *t, bool block)
{
    if (!t->asked)
        return;
    int flag = 0;
    if (block) {
        double t0 = tb__dist_now();
        MPI_Wait(&t->grant_req, MPI_STATUS_IGNORE);
        t->wait += tb__dist_now() - t0;
        flag = 1;
    } else {
        MPI_Test(&t->grant_req, &flag, MPI_STATUS_IGNORE);
    }
    if (!flag)
        return;
    t->asked = false;
    if (t->grant[1] == 0)
        t->done = true;
    for (int k = 0; k < t->grant[1]; k++)
        t->queue[(t->qhead + t->qlen++) % t->qcap] = t->grant[0] + k;
}

/* A worker: asks rank 0 for more tiles unless a request is in flight, rank 0
 * said there are none, or the queue is full enough. Lock held. */
static void tb__tiles_ask(tb__tiles *t)
{
    if (t->asked || t->done || t->qlen >= t->ahead)
        return;
    int want = t->ahead;
    MPI_Send(&want, 1, MPI_INT, 0, TB__TAG_REQUEST, MPI_COMM_WORLD);
    MPI_Irecv(t->grant, 2, MPI_INT, 0, TB__TAG_GRANT, MPI_COMM_WORLD, &t->grant_req);
    t->asked = true;
    t->bytes += sizeof want;
    t->msgs += 2;
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
    t->qhead = t->qlen = 0;
    t->asked = t->done = false;
    t->wait = 0;
    t->bytes = t->msgs = t->units = 0;
    t->t_pass = tb__dist_now();
    return TB_OK;
}

static int tb__tiles_claim(void *ctx, int *index)
{
    tb__tiles *t = ctx;
    int got = 0;
    pthread_mutex_lock(&t->lock);
    if (t->ex.rank == 0) {
#ifdef TB_HAVE_MPI
        if (t->ex.ranks > 1 && tb__tiles_serve(t, false) != TB_OK) {
            /* a malformed tile: nothing sensible is left to do in any rank */
            fprintf(stderr, "testbed: rank 0: %s\n", tb_last_error());
            tb_dist_abort(1);
        }
#endif
        if (t->next < t->ntiles) {
            *index = t->next++;
            got = 1;
        }
    } else {
#ifdef TB_HAVE_MPI
        tb__tiles_take_grant(t, false);
        tb__tiles_ask(t);
        if (t->qlen == 0 && !t->done) {
            tb__tiles_take_grant(t, true);
            tb__tiles_ask(t);
        }
        if (t->qlen > 0) {
            *index = t->queue[t->qhead];
            t->qhead = (t->qhead + 1) % t->qcap;
            t->qlen--;
            got = 1;
            /* ask again now, so the answer comes while this tile renders */
            tb__tiles_ask(t);
        }
#endif
    }
    if (got)
        t->units++;
    pthread_mutex_unlock(&t->lock);
    return got;
}

static tb_status tb__tiles_finish(void *ctx, tb_film *film, int index, tb_film_tile *tile)
{
    tb__tiles *t = ctx;
    if (t->ex.rank == 0) {
        tb_status st = tile ? tb_film_tile_submit(film, tile) : tb_film_tile_skip(film, index);
#ifdef TB_HAVE_MPI
        if (!st && t->ex.ranks > 1) {
            pthread_mutex_lock(&t->lock);
            st = tb__tiles_serve(t, false);
            pthread_mutex_unlock(&t->lock);
        }
#endif
        return st;
    }
#ifdef TB_HAVE_MPI
    size_t len = tile ? tb_film_tile_packed_size(tile) : sizeof(int);
    void *buf = tile ? malloc(len) : NULL;
    if (tile && !buf) {
        tb_film_tile_free(tile);
        return tb_error(TB_ERR_NOMEM, "out of memory packing tile %d", index);
    }
    if (tile) {
        tb_film_tile_pack(tile, buf);
        tb_film_tile_free(tile);
    }
    pthread_mutex_lock(&t->lock);
    if (tile)
        MPI_Send(buf, (int)len, MPI_BYTE, 0, TB__TAG_TILE, MPI_COMM_WORLD);
    else
        MPI_Send(&index, 1, MPI_INT, 0, TB__TAG_SKIP, MPI_COMM_WORLD);
    t->bytes += len;
    t->msgs++;
    /* ask ahead while the lock is held anyway */
    tb__tiles_take_grant(t, false);
    tb__tiles_ask(t);
    pthread_mutex_unlock(&t->lock);
    free(buf);
    return TB_OK;
#else
    (void)film;
    tb_film_tile_free(tile);
    return tb_error(TB_ERR_UNSUPPORTED, "tile %d: a worker rank without MPI", index);
#endif
}

static tb_status tb__tiles_end(void *ctx, tb_film *film, tb_aa_stats *stats)
{
    tb__tiles *t = ctx;
    (void)film;
    tb_status st = TB_OK;
    if (t->ex.rank == 0) {
        /* rank 0's own claims are done: tiles never granted (a cancel) are skipped */
        while (!st && t->next < t->ntiles && ((t->cancel && atomic_load(t->cancel)) || t->ex.ranks == 1)) {
            st = tb_film_tile_skip(film, t->next++);
            stats->tiles_skipped++;
        }
#ifdef TB_HAVE_MPI
        /* then every worker's tiles, and every worker told it is done */
        pthread_mutex_lock(&t->lock);
        while (!st && t->ex.ranks > 1 && (t->owed > 0 || t->workers_done < t->ex.ranks - 1)) {
            st = tb__tiles_serve(t, true);
            while (!st && t->next < t->ntiles && t->cancel && atomic_load(t->cancel)) {
                st = tb_film_tile_skip(film, t->next++);
                stats->tiles_skipped++;
            }
        }
        pthread_mutex_unlock(&t->lock);
#endif
    }
#ifdef TB_HAVE_MPI
    if (!st && t->ex.ranks > 1) {
        double t0 = tb__dist_now();
        uint64_t sums[5] = {stats->samples, stats->ring_samples, stats->pixels, stats->pixels_refined,
                            (uint64_t)stats->tiles_skipped};
        int mx = stats->max_spp_used;
        MPI_Allreduce(MPI_IN_PLACE, sums, 5, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
        MPI_Allreduce(MPI_IN_PLACE, &mx, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
        t->wait += tb__dist_now() - t0;
        t->msgs += 2;
        stats->samples = sums[0], stats->ring_samples = sums[1], stats->pixels = sums[2];
        stats->pixels_refined = sums[3], stats->tiles_skipped = (int)sums[4];
        stats->max_spp_used = mx;
    }
#endif
    /* work: the pass less its waits (for grants, for the last tiles, the sums) */
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
    /* two tiles per thread: one rendering, one waiting, while rank 0 (which
     * answers between its own tiles) gets round to the next request */
    t->ahead = 2 * (threads > 0 ? threads : omp_get_max_threads());
    t->qcap = 2 * t->ahead + 2;
    t->queue = malloc(sizeof *t->queue * (size_t)t->qcap);
    if (!t->queue) {
        free(t);
        tb_error(TB_ERR_NOMEM, "out of memory for the tile exchange");
        return NULL;
    }
    pthread_mutex_init(&t->lock, NULL);
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
    free(t->queue);
    free(t);
}
