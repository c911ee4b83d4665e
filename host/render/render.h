/* The render driver (docs/raytrace.md): runs a renderer's per-sample function
 * over the film in passes (antialias.h: tiles, dynamic OpenMP schedule, merge
 * in tile order, so the image is bit-identical for any thread count), with a
 * progress bar, a cancel flag checked at tile boundaries (Ctrl-C), a time
 * budget, and the conversion of the film to a linear sRGB image (spectral
 * render bands through CIE XYZ).
 *
 *     tb_render_options o = tb_render_defaults();
 *     o.aa.spp = 16;
 *     tb_image *img;
 *     if (tb_render_raytrace(scene, &o, &img, NULL)) die(tb_last_error());
 */
#ifndef TB_HOST_RENDER_RENDER_H
#define TB_HOST_RENDER_RENDER_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "host/render/antialias.h"
#include "host/render/film.h"
#include "host/render/raytrace.h"
#include "host/render/scene.h"
#include "util/base/error.h"
#include "util/image/image.h"

/* Called after each finished pass with the film so far (resolve it with
 * tb_render_resolve); a nonzero return stops the render. */
typedef int (*tb_render_pass_fn)(void *ctx, int pass, int spp_total, double seconds, const tb_film *film);

typedef struct tb_render_stats tb_render_stats;

/* Saving and restoring a progressive render (checkpoints): the film's
 * accumulators and the passes done. Only rank 0 of an exchange calls them. */
typedef struct tb_render_persist {
    void *ctx; /* passed to both */
    /* Before the first pass: fills `film` and *done (passes_done and aa
     * counts of the passes in it) from a checkpoint, or leaves both as they
     * are (a new render). NULL: a new render. */
    tb_status (*restore)(void *ctx, tb_film *film, tb_render_stats *done);
    /* After each complete pass: may save `film` and *done (its own
     * schedule, e.g. every N seconds, and always after the last pass when
     * `last`). NULL: never. An error stops the render. */
    tb_status (*save)(void *ctx, const tb_film *film, const tb_render_stats *done, bool last);
} tb_render_persist;

/* Render options; start from tb_render_defaults(). */
typedef struct tb_render_options {
    tb_aa_options aa;       /* samples per pixel (per pass), pattern, adaptive, seed */
    tb_filter filter;       /* reconstruction filter */
    int passes;             /* passes of aa.spp samples each (>= 1); pass k uses aa.pass = k */
    int threads;            /* OpenMP threads; 0: OpenMP's default */
    tb_rt_options rt;       /* ray tracer options */
    double time_budget;     /* seconds; > 0: tiles not started by then are skipped (0: none) */
    atomic_int *cancel;     /* nonzero stops the render at the next tile (e.g. set by SIGINT); may be NULL */
    bool progress;          /* draw a progress bar on a terminal (util/base/progress.h) */
    tb_render_pass_fn on_pass; /* NULL: none */
    void *on_pass_ctx;
    uint32_t *sample_counts; /* NULL, or width x height (row by row): set to each pixel's camera samples, all passes */
    const tb_tile_exchange *exchange; /* NULL: every tile in this process; else tiles shared over processes
                                       * (host/dist); rank 0 alone gets the image (*out NULL elsewhere) and
                                       * calls on_pass and persist */
    const tb_render_persist *persist; /* NULL: no checkpoints */
} tb_render_options;

/* What a render did. */
struct tb_render_stats {
    tb_aa_stats aa;        /* summed over passes (max_spp_used: the largest of one pass) */
    int passes_done;       /* complete passes */
    bool interrupted;      /* cancelled or out of time: some tiles were skipped */
    double seconds;        /* wall time of the passes (of this run, not of passes restored) */
};

/* 1 sample per pixel, box filter of radius 0.5, one pass, defaults elsewhere. */
tb_render_options tb_render_defaults(void);

/* The film as a linear sRGB image (channels R, G, B): RGB scenes as they
 * are, spectral scenes through tb_bands_to_linear_srgb (radiometric XYZ, no
 * scale: a band value of 1 W/(m^2 sr nm) over the visible gives Y of about
 * 107). NULL on failure. */
tb_image *tb_render_resolve(const tb_scene *s, const tb_film *film);

/* Copies the film's per-pixel camera sample counts into counts[y * width + x]. */
void tb_render_sample_counts(const tb_film *film, uint32_t *counts);

/* Renders `s` with any renderer given as a per-sample function (a
 * tb_aa_sample_fn of antialias.h: the radiance of one camera sample at film
 * point (x, y), numbers from its own deterministic stream) into *out (linear
 * sRGB, see tb_render_resolve): tiles, OpenMP threads, passes, time budget,
 * cancel flag and progress bar as `o` says. The ray tracer, the path tracer
 * and the hybrid renderer are thin users. `sample` is called from several
 * threads at once with the same ctx. An interrupted render returns TB_OK
 * with what was rendered; `stats` (may be NULL) says so. */
tb_status tb_render(const tb_scene *s, tb_aa_sample_fn sample, void *ctx, const tb_render_options *o,
                    tb_image **out, tb_render_stats *stats);

/* Renders `s` with the Whitted ray tracer (raytrace.h) into *out (linear
 * sRGB, see tb_render_resolve). An interrupted render still returns TB_OK
 * and the image of what was rendered (skipped tiles black); `stats` (may be
 * NULL) says so. */
tb_status tb_render_raytrace(const tb_scene *s, const tb_render_options *o, tb_image **out, tb_render_stats *stats);

#endif
