/* Radiosity over the ranks of a job (docs/distributed.md, "Radiosity"):
 * the tb_rad_exchange of host/radiosity/radiosity.h. Every rank runs the
 * same progressive solver; each shot's ray-cast form factors are computed
 * for a share of the receiver clusters on each rank and gathered
 * (MPI_Allgatherv), so every rank shoots the same patches in the same
 * order and the `--patches` CSV is byte-identical to one process.
 *
 *     tb_rad_exchange *ex = tb_dist_rad_exchange_create();
 *     ro.solver.exchange = ex;          (every rank calls tb_rad_render)
 *     ...
 *     tb_dist_rad_exchange_free(ex);
 */
#ifndef TB_HOST_DIST_RADIOSITY_H
#define TB_HOST_DIST_RADIOSITY_H

#include "host/radiosity/radiosity.h"

/* The exchange of this job; NULL on no memory, or TB_ERR_ARG when
 * TB_DIST_SPIN_US (microseconds an exchange is polled, yielding the core
 * between polls, before the rank sleeps; default 1000) is not a number in
 * 0..1e7. */
tb_rad_exchange *tb_dist_rad_exchange_create(void);

/* Frees it; NULL is allowed. */
void tb_dist_rad_exchange_free(tb_rad_exchange *ex);

#endif
