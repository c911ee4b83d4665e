/* The distributed and checkpoint side of `testbed render` (all methods):
 * the job key of a checkpoint, the per-rank summary lines, and the set-up
 * every render method shares (docs/distributed.md). */
#ifndef TB_TOOLS_TESTBED_DIST_CLI_H
#define TB_TOOLS_TESTBED_DIST_CLI_H

#include <stdbool.h>
#include <stdint.h>

#include "host/dist/checkpoint.h"
#include "host/dist/dist.h"
#include "host/dist/tiles.h"
#include "host/render/render.h"

/* The job key of a checkpoint: the scene file's bytes and the command line
 * without the options that may change between a run and its resume (those
 * in `free_opts`, NULL-terminated long names with their values: outputs,
 * threads, passes, time budget, checkpoint options). 0 with tb_error set if
 * the scene cannot be read. */
uint64_t tb_cli_job_key(const char *scene_path, int argc, char **argv, const char *const *free_opts);

/* The options any render method leaves out of its job key. */
extern const char *const tb_cli_free_opts[];

/* False (rank 0 says why) when a job of several ranks is given the scene
 * on standard input, which mpirun passes to rank 0 alone. */
bool tb_cli_dist_scene_ok(const char *prog, const char *scene_path);

/* A progressive render's tiles over ranks and checkpoints: sets *ex to the
 * tile exchange when the job has several ranks (else NULL; free it with
 * tb_dist_tiles_free), fills `ck` and *persist when a checkpoint is written
 * or resumed, and wires both into `ro`; rank 0 of a job learns to name its
 * last checkpoint when the launcher stops it. `ckpt`, `every`, `resume` are the
 * command's options. Prints its own error (with `prog`) and returns false
 * on failure. */
bool tb_cli_dist_render_setup(const char *prog, const char *scene_path, int argc, char **argv,
                              tb_render_options *ro, const char *ckpt, double every, const char *resume,
                              tb_tile_exchange **ex, tb_ckpt_render *ck, tb_render_persist *persist);

/* Turns the statistics counters on only where they are written: on rank 0
 * when `stats_path` (--stats) is given. They cost a few per cent of a
 * renderer's time (a thread-local add per ray, node and test) and the other
 * ranks' are never reported. Returns the previous state, for
 * tb_stats_set_enabled after the render. */
int tb_cli_stats_where_written(const char *stats_path);

/* Rank 0 prints a line per rank (work, wait, bytes sent, units) after a
 * distributed job if `print` (rank 0's say); collective, so every rank calls
 * it, failed or not. Nothing in a job of one rank. */
void tb_cli_dist_summary(const char *prog, const char *unit, bool print);

#endif
