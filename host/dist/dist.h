/* The distributed layer (docs/distributed.md): a job of several processes
 * (MPI ranks) started by `mpirun`, on Open MPI. host/dist sits above the
 * renderers: it hands them callbacks (tb_tile_exchange of
 * host/render/antialias.h, tb_rad_exchange of host/radiosity/radiosity.h),
 * so host/render and host/radiosity never see MPI.
 *
 * A process not started by mpirun (or a build without MPI) is a job of one
 * rank and never calls MPI at all (Open MPI's singleton start costs half a
 * second). A build without MPI started by mpirun with several ranks refuses
 * to run: tb_dist_init says so.
 *
 *     if (tb_dist_init(&argc, &argv)) die(tb_last_error());
 *     ... tb_dist_rank(), tb_dist_size(), tb_dist_tiles_create(...) ...
 *     tb_dist_finalize();
 */
#ifndef TB_HOST_DIST_DIST_H
#define TB_HOST_DIST_DIST_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "util/base/error.h"

/* What one rank did in a distributed job (its own figures). */
typedef struct tb_dist_stats {
    double work_seconds;  /* wall time spent on its share of the work (rendering tiles, shooting) */
    double wait_seconds;  /* wall time blocked on other ranks (tile grants, gathers, the end of a pass) */
    uint64_t bytes_sent;  /* payload bytes this rank sent (tiles, results, grants) */
    uint64_t messages;    /* point-to-point messages and collective calls it took part in */
    uint64_t units;       /* work units done here: tiles, or receivers of shots */
    double init_seconds;  /* wall time of this rank's MPI start (MPI_Init_thread) */
    double cpu_seconds;   /* CPU time (user + system) of this process so far, when gathered */
} tb_dist_stats;

/* True if this build has MPI (CMake found it and TB_MPI was on). */
bool tb_dist_built_with_mpi(void);

/* Starts the job: MPI (threads serialized) if mpirun started this process,
 * else a job of one rank. TB_ERR_UNSUPPORTED when a build without MPI is run
 * as one of several ranks (it would render the whole job N times). Call once,
 * before any other tb_dist_ function. */
tb_status tb_dist_init(int *argc, char ***argv);

/* Ends the job (MPI_Finalize when MPI was started); safe without init. */
void tb_dist_finalize(void);

/* This process's rank (0 .. size-1) and the number of ranks (1 without MPI). */
int tb_dist_rank(void);
int tb_dist_size(void);

/* Stops every rank of the job at once (MPI_Abort) with exit status `code`;
 * a plain exit(code) in a job of one rank. */
_Noreturn void tb_dist_abort(int code);

/* The lowest-ranked failure of a step every rank took: each rank passes its
 * status (its message in tb_last_error()); every rank gets back TB_OK if all
 * succeeded, else that rank's status, with that rank's message as its own
 * last error, and *rank (may be NULL) set to the failing rank (-1: none).
 * Collective. */
tb_status tb_dist_agree_status(tb_status st, int *rank);

/* Rank 0's value of `v` on every rank. Collective. */
int tb_dist_bcast_int(int v);

/* Rank 0's `len` bytes of `buf` on every rank (len equal everywhere). Collective. */
tb_status tb_dist_bcast_bytes(void *buf, size_t len);

/* This rank's running totals (all exchanges and solves so far). */
tb_dist_stats tb_dist_my_stats(void);

/* Every rank's totals gathered on rank 0 into all[0 .. size) (`all` may be
 * NULL on other ranks). Collective. */
tb_status tb_dist_gather_stats(tb_dist_stats *all);

/* Every rank's totals as stats values on rank 0 (tb_stats_set_value of
 * util/stats: ranks, rank<R>_work_seconds, rank<R>_wait_seconds,
 * rank<R>_bytes_sent, rank<R>_messages, rank<R>_<unit>s,
 * rank<R>_init_seconds, rank<R>_cpu_seconds). Collective. */
tb_status tb_dist_report_stats(const char *unit);

#endif
