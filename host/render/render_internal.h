/* The render driver's renderer interface (render.h): what the CPU ray tracer
 * (tb_render_raytrace) and the Vulkan renderer (host/gpu/render.c) plug
 * into, so both share one pass loop: option checks, the film, the progress
 * bar, the cancel flag and time budget, the pass bookkeeping and on_pass,
 * and the resolved image. A renderer supplies how one pass fills the film's
 * tiles. Not installed (an _internal.h header). */
#ifndef TB_HOST_RENDER_RENDER_INTERNAL_H
#define TB_HOST_RENDER_RENDER_INTERNAL_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "host/render/antialias.h"
#include "host/render/film.h"
#include "host/render/render.h"
#include "host/render/scene.h"
#include "util/base/error.h"
#include "util/base/progress.h"
#include "util/image/image.h"

/* The state of one render that a renderer's pass reads and updates. */
typedef struct tb__render_run {
    const tb_render_options *o; /* the caller's options */
    tb_progress *progress;      /* NULL: none; counts finished pixels */
    int64_t t0_ns;              /* monotonic clock at the start of the passes */
    int64_t deadline_ns;        /* end of the time budget (0: none) */
    atomic_int stop;            /* latched by tb__render_should_stop: tiles not started are skipped */
    int pass_index;             /* the pass being rendered (0-based, counting restored passes) */
} tb__render_run;

/* True once the render must stop: the caller's cancel flag is set or the
 * time budget is spent (latched into run->stop). Thread-safe. */
bool tb__render_should_stop(tb__render_run *run);

/* Seconds since the passes began. */
double tb__render_seconds(const tb__render_run *run);

/* A renderer as the driver runs it. */
typedef struct tb__render_engine {
    void *ctx; /* passed to both functions */
    /* Called once the film exists, before the first pass (NULL: nothing to prepare). */
    tb_status (*start)(void *ctx, const tb_film *film);
    /* Renders pass aa->pass into `film`: begins the pass (tb_film_begin_pass),
     * merges finished tiles and marks those not started once the run must
     * stop as skipped (tb_film_tile_skip), adds finished pixels to
     * run->progress and fills *as (zeroed by the driver). */
    tb_status (*pass)(void *ctx, tb__render_run *run, tb_film *film, const tb_aa_options *aa, tb_aa_stats *as);
} tb__render_engine;

/* TB_OK if `o` can be rendered (passes, antialiasing options); a renderer
 * checks this before it prepares itself for tb__render_drive. */
tb_status tb__render_check(const tb_render_options *o);

/* Runs `e` over scene `s` with options `o` as tb_render_raytrace does
 * (render.h): film, passes, stop rules, on_pass, *out resolved to linear
 * sRGB, o->sample_counts, and `stats` (may be NULL). */
tb_status tb__render_drive(const tb_scene *s, const tb_render_options *o, const tb__render_engine *e,
                           tb_image **out, tb_render_stats *stats);

#endif
