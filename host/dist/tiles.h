/* A render's tiles shared over the ranks of a job (docs/distributed.md):
 * the tb_tile_exchange that tb_render (host/render/render.h) takes in
 * tb_render_options.exchange. Rank 0 hands out tiles on request, in index
 * order, a few at a time; each rank renders its tiles with its OpenMP
 * threads and sends them, packed (film.h), to rank 0, which merges every
 * tile into its film in tile order as the one-process render does: the
 * image is bit-identical for any number of ranks and threads. The render
 * threads make the MPI calls (requests ahead, grants, tiles) between their
 * tiles, one thread at a time; rank 0 also has a communication thread,
 * mostly asleep, that answers requests while its render threads are busy.
 *
 *     tb_tile_exchange *ex = tb_dist_tiles_create(threads);
 *     ro.exchange = ex;                 (every rank calls tb_render)
 *     ... tb_render(...) ...            (rank 0's image is the image)
 *     tb_dist_tiles_free(ex);
 */
#ifndef TB_HOST_DIST_TILES_H
#define TB_HOST_DIST_TILES_H

#include "host/render/antialias.h"

/* The exchange of this job for renders with `threads` OpenMP threads per
 * rank (0: OpenMP's default; sets how far ahead a worker asks). In a job of
 * one rank it still works (every tile here). NULL on no memory. */
tb_tile_exchange *tb_dist_tiles_create(int threads);

/* Frees the exchange; NULL is allowed. */
void tb_dist_tiles_free(tb_tile_exchange *ex);

#endif
