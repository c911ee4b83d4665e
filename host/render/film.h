/* The film: camera samples splatted through a reconstruction filter into
 * per-pixel weighted sums, resolved into a tb_image (docs/antialiasing.md).
 *
 * Coordinates are continuous film (raster) coordinates: x to the right, y
 * down, pixel (i, j) covers [i, i+1) x [j, j+1) and its centre is
 * (i + 1/2, j + 1/2); row 0 is the top row, as in tb_image.
 *
 * A sample at (x, y) contributes to every pixel whose centre lies within the
 * filter's support, with weight f(x - cx) f(y - cy) (filters are separable).
 * So a sample near a border between pixels is used by the pixels on both
 * sides: the "reuse of samples on shared pixel borders". A pixel's value is
 * sum(w v) / sum(w) (a ratio estimator), which reproduces a constant exactly,
 * also at the image border where part of the support has no samples.
 *
 * Determinism: the film is split into a grid of tiles. A renderer fills a
 * tile buffer (the tile's pixels plus an apron as wide as the filter reaches)
 * for each tile, in any order and on any thread, and submits it; the film
 * merges submitted tiles strictly in tile-index order. Every addition into the
 * film's sums therefore happens in the same order whatever the thread count
 * or schedule, and the result is bit-identical. */
#ifndef TB_HOST_RENDER_FILM_H
#define TB_HOST_RENDER_FILM_H

#include <stdbool.h>
#include <stdint.h>

#include "util/base/error.h"
#include "util/image/image.h"

/* Reconstruction filter kinds. */
typedef enum tb_filter_kind {
    TB_FILTER_BOX = 0,  /* 1 on [-r, r) (half-open: a sample on a pixel border goes to one pixel) */
    TB_FILTER_TENT,     /* triangle 1 - |x|/r */
    TB_FILTER_GAUSSIAN, /* exp(-x^2 / 2 sigma^2) minus its value at r, clipped at r */
    TB_FILTER_MITCHELL, /* Mitchell-Netravali cubic, B = C = 1/3, scaled to radius r */
} tb_filter_kind;

/* Number of filter kinds. */
#define TB_FILTER_KIND_COUNT 4

/* A separable filter f(x, y) = f1(x) f1(y), normalised so that its integral
 * over the plane is 1. Build with tb_filter_init; fields are read-only after. */
typedef struct tb_filter {
    tb_filter_kind kind;
    double radius; /* support is |x| <= radius (box: -radius <= x < radius) in pixels */
    double sigma;  /* Gaussian standard deviation in pixels (Gaussian only) */
    double b, c;   /* Mitchell-Netravali parameters (Mitchell only) */
    double norm;   /* 1 / (integral of the unnormalised 1D profile) */
} tb_filter;

/* Default radius of each kind: box 0.5, tent 1, Gaussian 1.5, Mitchell 2. */
double tb_filter_default_radius(tb_filter_kind kind);

/* Sets up `f`. radius <= 0 picks the kind's default; sigma <= 0 picks radius / 3
 * (Gaussian only; 0.5 at the default radius). TB_ERR_ARG for an unknown kind,
 * a non-finite value, or a radius above 16 pixels. */
tb_status tb_filter_init(tb_filter *f, tb_filter_kind kind, double radius, double sigma);

/* Parses "KIND[:RADIUS[:SIGMA]]" (KIND = box, tent, gaussian, mitchell; e.g.
 * "gaussian:1.5:0.5", "mitchell:2") into `f`. TB_ERR_ARG with a message on
 * anything else. */
tb_status tb_filter_parse(const char *spec, tb_filter *f);

/* Name of a kind ("box", "tent", "gaussian", "mitchell"). */
const char *tb_filter_kind_name(tb_filter_kind kind);

/* The normalised 1D profile f1(x) (integrates to 1 over the real line). */
double tb_filter_eval1(const tb_filter *f, double x);

/* The normalised 2D filter f1(x) f1(y). */
double tb_filter_eval(const tb_filter *f, double x, double y);

/* ------------------------------------------------------------------ film */

/* What a film is made of; zero fields take the defaults noted. */
typedef struct tb_film_desc {
    int width, height;       /* pixels, >= 1 */
    int channels;            /* values per sample, 1 .. TB_FILM_MAX_CHANNELS */
    const tb_filter *filter; /* NULL: box of radius 0.5 */
    int tile_size;           /* tile edge in pixels; 0: 16 */
} tb_film_desc;

/* Most channels a film holds (RGB, XYZ, or a renderer's spectral bands). */
#define TB_FILM_MAX_CHANNELS 64

/* A film (opaque). */
typedef struct tb_film tb_film;

/* A tile's private buffer (opaque). */
typedef struct tb_film_tile tb_film_tile;

/* Pixel rectangle [x0, x1) x [y0, y1) of one tile. */
typedef struct tb_tile_rect {
    int x0, y0, x1, y1;
} tb_tile_rect;

/* A new, empty film; NULL on failure (see tb_last_error()). */
tb_film *tb_film_create(const tb_film_desc *desc);

/* Frees the film and any tiles still pending; NULL is allowed. */
void tb_film_free(tb_film *film);

/* Width, height and channel count. */
int tb_film_width(const tb_film *film);
int tb_film_height(const tb_film *film);
int tb_film_channels(const tb_film *film);

/* The film's filter. */
const tb_filter *tb_film_filter(const tb_film *film);

/* Number of tiles (row-major grid of tile_size squares, clipped at the edges). */
int tb_film_tile_count(const tb_film *film);

/* Pixel rectangle of tile `index` (0 .. tb_film_tile_count - 1). */
tb_tile_rect tb_film_tile_rect(const tb_film *film, int index);

/* Starts a pass: every tile of the pass is to be submitted (or skipped) once,
 * and merging restarts at tile 0. TB_ERR_ARG if the previous pass has tiles
 * still unmerged. A new film is already in its first pass. */
tb_status tb_film_begin_pass(tb_film *film);

/* A zeroed buffer for tile `index`: its pixels plus the apron the filter
 * reaches. NULL on failure. Any thread may own one tile buffer at a time. */
tb_film_tile *tb_film_tile_create(const tb_film *film, int index);

/* The rectangle of the tile's own pixels (where its samples must lie). */
tb_tile_rect tb_film_tile_pixels(const tb_film_tile *tile);

/* Splats `value` (the film's channel count) at film position (x, y) with an
 * extra weight `weight` (1 for plain samples; see docs/antialiasing.md for the
 * density compensation of adaptive sampling). (x, y) must lie in the tile's
 * own pixels; others are ignored. Non-finite values are dropped and counted. */
void tb_film_tile_add(tb_film_tile *tile, double x, double y, const float *value, double weight);

/* Records that pixel (px, py) of the tile was given `n` camera samples (the
 * film keeps a per-pixel sample count for statistics and heat maps). */
void tb_film_tile_record_samples(tb_film_tile *tile, int px, int py, uint32_t n);

/* Hands the tile to the film, which takes ownership and merges it when all
 * tiles of lower index in this pass have been merged (thread-safe). A tile
 * submitted twice in one pass is TB_ERR_ARG (and freed). */
tb_status tb_film_tile_submit(tb_film *film, tb_film_tile *tile);

/* Marks tile `index` as done without content (a cancelled render), so the
 * tiles after it still merge (thread-safe). */
tb_status tb_film_tile_skip(tb_film *film, int index);

/* ------------------------------------------------ packing (host/dist, checkpoints)
 *
 * A tile buffer or a whole film as plain bytes in this machine's byte order,
 * so another process with the same film (size, channels, filter, tile size)
 * can merge the tile or continue the film. The bytes carry the exact doubles,
 * so a tile merged from its packed copy adds what the original would have:
 * the image stays bit-identical however tiles travel. */

/* Bytes tb_film_tile_pack writes for `tile`. */
size_t tb_film_tile_packed_size(const tb_film_tile *tile);

/* Writes the tile (index, rectangles, sums, sample counts, dropped count)
 * into buf[0 .. tb_film_tile_packed_size). */
void tb_film_tile_pack(const tb_film_tile *tile, void *buf);

/* A tile of `film` rebuilt from tb_film_tile_pack's bytes; NULL with
 * TB_ERR_FORMAT (tb_last_error) if they do not describe a tile of this film
 * (index, rectangles or length), TB_ERR_NOMEM on no memory. */
tb_film_tile *tb_film_tile_unpack(const tb_film *film, const void *buf, size_t len);

/* Bytes tb_film_pack writes for `film`. */
size_t tb_film_packed_size(const tb_film *film);

/* Writes the film's accumulators (size, channels, per-pixel weighted sums
 * and weights, sample counts, dropped count) into buf[0 ..
 * tb_film_packed_size). Only between passes (every tile merged). */
void tb_film_pack(const tb_film *film, void *buf);

/* Replaces the accumulators of `film` by packed ones: TB_ERR_FORMAT if the
 * bytes are short or were packed from a film of another size or channel
 * count; the film is unchanged then. */
tb_status tb_film_unpack(tb_film *film, const void *buf, size_t len);

/* Frees a tile buffer that is not going to be submitted; NULL is allowed. */
void tb_film_tile_free(tb_film_tile *tile);

/* True if every tile of the current pass has been merged. */
bool tb_film_pass_complete(const tb_film *film);

/* Splats directly into the film (single-threaded use, no tiles; deterministic
 * in call order). */
void tb_film_add(tb_film *film, double x, double y, const float *value, double weight);

/* The resolved image: per pixel sum(w v) / sum(w), 0 where sum(w) <= 0 (no
 * sample reached the pixel, or a negative-lobe filter cancelled). `names` as
 * for tb_image_create (NULL: defaults). NULL on failure. */
tb_image *tb_film_resolve(const tb_film *film, const char *const *names);

/* Camera samples recorded for pixel (x, y) with tb_film_tile_record_samples. */
uint32_t tb_film_sample_count(const tb_film *film, int x, int y);

/* Sum of filter weights at pixel (x, y) (for tests and diagnostics). */
double tb_film_weight_sum(const tb_film *film, int x, int y);

/* Samples dropped because a value was not finite. */
uint64_t tb_film_dropped(const tb_film *film);

#endif
