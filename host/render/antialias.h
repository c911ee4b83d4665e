/* Antialiasing: where the camera samples of a pixel go, how many a pixel
 * gets, and the tiled, deterministic, OpenMP loop that feeds them to a film
 * (docs/antialiasing.md).
 *
 *  - Sample positions: n x n jittered strata (any count: nx x ny as square as
 *    possible), or a (0,2)-sequence (Sobol' dimensions 1 and 2, randomised per
 *    pixel by a digit scramble). Every pixel has its own random key, hashed
 *    from (seed, pass, pixel x, pixel y), so the samples do not depend on the
 *    thread count, the tile order or the order pixels are visited in.
 *  - Adaptive refinement: after each round of spp samples, a pixel whose
 *    samples fail the criterion (standard error of the luminance mean, or
 *    Mitchell's contrast) gets another round, up to max_spp.
 *  - tb_aa_render: tiles handed out dynamically to threads, each rendered into
 *    its own film tile buffer and merged in tile order (film.h): the image is
 *    bit-identical for any thread count.
 *
 * Command-line spelling (tb_aa_parse_arg): --spp N, --adaptive [T],
 * --max-spp N, --aa-criterion stderr|contrast, --aa-pattern stratified|sobol,
 * --filter KIND[:RADIUS[:SIGMA]]. The seed (--seed) belongs to the renderer,
 * which copies it into tb_aa_options.seed. */
#ifndef TB_HOST_RENDER_ANTIALIAS_H
#define TB_HOST_RENDER_ANTIALIAS_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "host/render/film.h"
#include "util/base/error.h"
#include "util/base/progress.h"
#include "util/math/rng.h"

/* Where the samples of one round lie in the pixel. */
typedef enum tb_aa_pattern {
    TB_AA_STRATIFIED = 0, /* jittered nx x ny strata, fresh jitter each round */
    TB_AA_SOBOL = 1,      /* (0,2)-sequence with a per-pixel random digit scramble */
} tb_aa_pattern;

/* When a pixel gets another round. */
typedef enum tb_aa_criterion {
    TB_AA_STDERR = 0,   /* standard error of the luminance mean > T * (mean + 1/256) */
    TB_AA_CONTRAST = 1, /* Mitchell 1987: some channel's (max-min)/(max+min) > T * (1, 0.75, 1.5)[c] */
} tb_aa_criterion;

/* Default thresholds of the two criteria. */
#define TB_AA_STDERR_DEFAULT 0.03
#define TB_AA_CONTRAST_DEFAULT 0.4

/* Largest sample count a pixel may reach. */
#define TB_AA_MAX_SPP 65536

/* Antialiasing options; start from tb_aa_defaults(). */
typedef struct tb_aa_options {
    int spp;                   /* samples per pixel, and per round when adaptive (>= 1) */
    tb_aa_pattern pattern;
    bool adaptive;             /* refine pixels in rounds until the criterion passes */
    tb_aa_criterion criterion;
    double threshold;          /* T of the criterion; <= 0: the criterion's default */
    int max_spp;               /* adaptive cap per pixel; <= 0: 16 spp (at most TB_AA_MAX_SPP) */
    uint64_t seed;             /* global seed (--seed) */
    uint32_t pass;             /* progressive pass number: each pass draws new samples */
} tb_aa_options;

/* The defaults: 1 stratified sample per pixel, not adaptive, seed 0. */
tb_aa_options tb_aa_defaults(void);

/* TB_OK if the options are usable, else TB_ERR_ARG with a message. */
tb_status tb_aa_check(const tb_aa_options *o);

/* The threshold in effect (the default when o->threshold <= 0). */
double tb_aa_threshold(const tb_aa_options *o);

/* The per-pixel cap in effect: spp when not adaptive, else max_spp or 16 spp,
 * never below spp, at most TB_AA_MAX_SPP. */
int tb_aa_max_spp(const tb_aa_options *o);

/* Parses the antialiasing option at argv[*i] (see the header comment), if it
 * is one: fills `aa` / `filter` (either may be NULL to refuse those options),
 * advances *i past the option's last argument and returns 1. Returns 0 if
 * argv[*i] is not an antialiasing option, -1 with tb_error set on a bad value.
 * --adaptive takes the next argument as T only if it is a number. */
int tb_aa_parse_arg(int argc, char **argv, int *i, tb_aa_options *aa, tb_filter *filter);

/* ------------------------------------------------------------- per pixel */

/* The sample generator of one pixel. Plain struct; no allocation. */
typedef struct tb_pixel_sampler {
    tb_aa_pattern pattern;
    int nx, ny;   /* strata per round (nx * ny = spp) */
    int spp;      /* samples per round */
    int taken;    /* samples generated so far */
    uint64_t key; /* the pixel's random key, from (seed, pass, x, y) */
} tb_pixel_sampler;

/* Starts the sampler of pixel (px, py) for options `o` (seed, pass, spp, pattern). */
void tb_pixel_sampler_init(tb_pixel_sampler *s, const tb_aa_options *o, int px, int py);

/* The next round: writes spp positions (xy[2k], xy[2k+1]) in [0,1)^2 within
 * the pixel and returns spp.
 * Stratified: one point in each of the nx x ny cells, row by row; round r
 * places in each cell point r of a (0,2)-sequence with the cell's own random
 * digit scramble, so each point is uniform in its cell (jittered) and the
 * rounds of a cell together are a (0,m,2)-net in it after 2^m rounds.
 * Sobol': points taken .. taken + spp - 1 of the pixel's scrambled
 * (0,2)-sequence (every aligned block of 2^m points is a (0,m,2)-net). */
int tb_pixel_sampler_round(tb_pixel_sampler *s, float *xy);

/* A random stream for everything else sample `index` of pixel (px, py) needs
 * (lens, time, light and BSDF choices): independent of the position stream
 * and of the other samples, so a renderer that draws a variable number of
 * numbers per sample cannot shift the next sample. */
void tb_aa_sample_rng(const tb_aa_options *o, int px, int py, uint32_t index, tb_rng *out);

/* Splits n into nx * ny = n with nx >= ny as close as possible (n >= 1). */
void tb_aa_strata(int n, int *nx, int *ny);

/* Luminance weights for `channels` channels: Rec. 709 Y for 3 (linear RGB),
 * 1 for 1, otherwise 1/channels each. `w` has room for TB_FILM_MAX_CHANNELS. */
void tb_aa_luminance_weights(int channels, float *w);

/* True if the n samples `values` (n x channels, row by row) of one pixel
 * call for another round under `o`'s criterion. lum_w: weights from
 * tb_aa_luminance_weights (stderr criterion). n < 2 always refines. */
bool tb_aa_needs_more(const tb_aa_options *o, int channels, const float *lum_w, const float *values,
                      int n);

/* ----------------------------------------------------------- the render loop */

/* The radiance along the camera ray through film position (x, y) (film.h
 * coordinates), written to out[0 .. channels). `rng` is the sample's own
 * stream (tb_aa_sample_rng). Called from many threads at once. */
typedef void (*tb_aa_sample_fn)(void *ctx, double x, double y, tb_rng *rng, float *out);

typedef struct tb_aa_stats tb_aa_stats;

/* Where a pass's tiles come from and where finished ones go, when they are
 * not all rendered and merged in this process (host/dist shares them over
 * MPI ranks; host/render does not know MPI). A tile's buffer depends only on
 * its index and the options, so it may be rendered in any process. */
typedef struct tb_tile_exchange {
    void *ctx;  /* passed to every function */
    int rank;   /* this process (0: the one whose film is the image) */
    int ranks;  /* processes sharing the tiles */
    /* Starts pass `pass` on `film` (already begun); progress (may be NULL)
     * counts pixels of tiles merged from elsewhere; once `cancel` (may be
     * NULL) is set on rank 0, no more tiles go out. */
    tb_status (*begin_pass)(void *ctx, tb_film *film, int pass, tb_progress *progress, const atomic_int *cancel);
    /* Claims the next tile for this process into *index: 1, or 0 when none
     * is left in this pass. Called from any thread. */
    int (*claim)(void *ctx, int *index);
    /* Hands over the finished tile `index` (ownership; NULL: skipped after a
     * cancel). Called from any thread. */
    tb_status (*finish)(void *ctx, tb_film *film, int index, tb_film_tile *tile);
    /* Ends the pass once this process's claims are finished (`st`: this
     * process's outcome, its message in tb_last_error()): rank 0 returns
     * when every tile of the pass is merged into its film; tiles not claimed
     * are skipped. Returns the lowest-ranked failure of any process, with
     * its message, on every process (so all stop together), else TB_OK with
     * *stats (this process's) become the sum over processes. */
    tb_status (*end_pass)(void *ctx, tb_film *film, tb_aa_stats *stats, tb_status st);
    /* Rank 0's `flag` on every process (a decision all must share). */
    int (*agree)(void *ctx, int flag);
    /* The lowest-ranked failure among every process's `st` (its message as
     * this process's last error), or TB_OK on all: a step all must pass. */
    tb_status (*agree_status)(void *ctx, tb_status st);
    /* After the render, on every process: puts each process's share of the
     * work into the stats values (tb_stats_set_value). NULL: nothing. */
    tb_status (*report)(void *ctx);
} tb_tile_exchange;

/* How tb_aa_render runs; zero fields take the defaults. */
typedef struct tb_aa_render_desc {
    tb_aa_sample_fn sample; /* required */
    void *ctx;              /* passed to sample */
    int threads;            /* OpenMP threads; 0: OpenMP's default */
    const float *lum_weights; /* per channel luminance weights; NULL: tb_aa_luminance_weights */
    tb_progress *progress;  /* NULL: none; counts pixels */
    const atomic_int *cancel; /* NULL: never; when nonzero, tiles not yet started are skipped */
    const tb_tile_exchange *exchange; /* NULL: every tile here, merged here */
    int pass_index;         /* exchange only: the driver's pass number (begin_pass) */
} tb_aa_render_desc;

/* What a render did. */
struct tb_aa_stats {
    uint64_t samples;        /* camera samples in the image */
    uint64_t ring_samples;   /* adaptive: extra first-round samples of neighbouring tiles' pixels */
    uint64_t pixels;         /* pixels rendered */
    uint64_t pixels_refined; /* pixels that took more than one round */
    int max_spp_used;        /* largest sample count of a pixel */
    int tiles_skipped;       /* tiles skipped because of a cancel */
};

/* Renders one pass of `aa` into `film`: every tile (dynamic OpenMP schedule,
 * any order) renders its pixels in scanline order, each pixel its rounds of
 * samples, splatted with weight 1 / (the pixel's final sample count) so that
 * pixels with more samples do not outweigh their neighbours under wide
 * filters; tiles merge in index order. Adaptive: a pixel gets more rounds if
 * its first round or that of one of its 8 neighbours fails the criterion, then
 * while its own samples fail it (a tile evaluates the first rounds of the
 * pixels around it itself: ring_samples). Calls tb_film_begin_pass. `stats`
 * may be NULL. The first error of any thread is returned. */
tb_status tb_aa_render(tb_film *film, const tb_aa_options *aa, const tb_aa_render_desc *desc,
                       tb_aa_stats *stats);

#endif
