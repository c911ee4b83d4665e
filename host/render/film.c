/* Reconstruction filters and the film: splatting, tile buffers merged in a
 * fixed order, resolution into an image (film.h, docs/antialiasing.md). */
#include "host/render/film.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "util/math/float.h"
#include "util/stats/stats.h"

TB_STAT_COUNTER(tb__stat_splats, "Film/samples splatted");
TB_STAT_COUNTER(tb__stat_tiles_merged, "Film/tiles merged");

/* Largest radius accepted: a wider filter is almost certainly a mistake and
 * would make tile aprons larger than the tiles. */
#define TB__FILTER_MAX_RADIUS 16.0

/* ---------------------------------------------------------------- filters */

static const char *const tb__filter_names[TB_FILTER_KIND_COUNT] = {"box", "tent", "gaussian",
                                                                    "mitchell"};

const char *tb_filter_kind_name(tb_filter_kind kind)
{
    return (unsigned)kind < TB_FILTER_KIND_COUNT ? tb__filter_names[kind] : "unknown";
}

double tb_filter_default_radius(tb_filter_kind kind)
{
    switch (kind) {
    case TB_FILTER_BOX: return 0.5;
    case TB_FILTER_TENT: return 1.0;
    case TB_FILTER_GAUSSIAN: return 1.5;
    case TB_FILTER_MITCHELL: return 2.0;
    }
    return 0.0;
}

/* Mitchell-Netravali cubic k(x) with support |x| < 2 (Mitchell and Netravali
 * 1988, eq. 8); integrates to 1 for every B, C. */
static double tb__mitchell(double x, double b, double c)
{
    x = fabs(x);
    if (x < 1.0)
        return ((12.0 - 9.0 * b - 6.0 * c) * x * x * x + (-18.0 + 12.0 * b + 6.0 * c) * x * x +
                (6.0 - 2.0 * b)) / 6.0;
    if (x < 2.0)
        return ((-b - 6.0 * c) * x * x * x + (6.0 * b + 30.0 * c) * x * x +
                (-12.0 * b - 48.0 * c) * x + (8.0 * b + 24.0 * c)) / 6.0;
    return 0.0;
}

/* The unnormalised 1D profile. */
static inline double tb__filter_raw(const tb_filter *f, double x)
{
    double r = f->radius;
    switch (f->kind) {
    case TB_FILTER_BOX:
        return (x >= -r && x < r) ? 1.0 : 0.0;
    case TB_FILTER_TENT: {
        double a = fabs(x);
        return a < r ? 1.0 - a / r : 0.0;
    }
    case TB_FILTER_GAUSSIAN: {
        double a = fabs(x);
        if (a >= r)
            return 0.0;
        double s2 = 2.0 * f->sigma * f->sigma;
        return exp(-a * a / s2) - exp(-r * r / s2);
    }
    case TB_FILTER_MITCHELL:
        return tb__mitchell(2.0 * x / r, f->b, f->c);
    }
    return 0.0;
}

tb_status tb_filter_init(tb_filter *f, tb_filter_kind kind, double radius, double sigma)
{
    if (!f)
        return tb_error(TB_ERR_ARG, "filter: NULL filter");
    if ((unsigned)kind >= TB_FILTER_KIND_COUNT)
        return tb_error(TB_ERR_ARG, "filter: unknown kind %d", (int)kind);
    if (!isfinite(radius) || !isfinite(sigma))
        return tb_error(TB_ERR_ARG, "filter %s: radius and sigma must be finite",
                        tb_filter_kind_name(kind));
    if (radius <= 0.0)
        radius = tb_filter_default_radius(kind);
    if (radius > TB__FILTER_MAX_RADIUS)
        return tb_error(TB_ERR_ARG, "filter %s: radius %g exceeds %g pixels",
                        tb_filter_kind_name(kind), radius, TB__FILTER_MAX_RADIUS);
    memset(f, 0, sizeof *f);
    f->kind = kind;
    f->radius = radius;
    double integral = 1.0;
    switch (kind) {
    case TB_FILTER_BOX:
        integral = 2.0 * radius;
        break;
    case TB_FILTER_TENT:
        integral = radius;
        break;
    case TB_FILTER_GAUSSIAN: {
        f->sigma = sigma > 0.0 ? sigma : radius / 3.0;
        double s = f->sigma;
        /* integral of exp(-x^2/2s^2) - exp(-r^2/2s^2) over [-r, r] */
        integral = s * sqrt(2.0 * TB_PI) * erf(radius / (s * sqrt(2.0))) -
                   2.0 * radius * exp(-radius * radius / (2.0 * s * s));
        if (!(integral > 0.0))
            return tb_error(TB_ERR_ARG, "filter gaussian: sigma %g too large for radius %g", s,
                            radius);
        break;
    }
    case TB_FILTER_MITCHELL:
        f->b = 1.0 / 3.0;
        f->c = 1.0 / 3.0;
        /* k integrates to 1 over |x| < 2; scaling x by 2/r stretches it by r/2 */
        integral = radius / 2.0;
        break;
    }
    f->norm = 1.0 / integral;
    return TB_OK;
}

tb_status tb_filter_parse(const char *spec, tb_filter *f)
{
    if (!spec || !f)
        return tb_error(TB_ERR_ARG, "filter: NULL argument");
    const char *colon = strchr(spec, ':');
    size_t len = colon ? (size_t)(colon - spec) : strlen(spec);
    int kind = -1;
    for (int k = 0; k < TB_FILTER_KIND_COUNT; k++)
        if (strlen(tb__filter_names[k]) == len && strncmp(spec, tb__filter_names[k], len) == 0)
            kind = k;
    if (kind < 0)
        return tb_error(TB_ERR_ARG,
                        "filter '%s': unknown kind (expected box, tent, gaussian or mitchell)", spec);
    double vals[2] = {0.0, 0.0};
    int nvals = 0;
    const char *p = colon;
    while (p) {
        if (nvals == 2 || (nvals == 1 && kind != TB_FILTER_GAUSSIAN))
            return tb_error(TB_ERR_ARG, "filter '%s': too many parameters", spec);
        char *end = NULL;
        errno = 0;
        double v = strtod(p + 1, &end);
        if (end == p + 1 || (*end != '\0' && *end != ':') || errno || !isfinite(v) || v <= 0.0)
            return tb_error(TB_ERR_ARG, "filter '%s': bad number '%s' (expected a positive value)",
                            spec, p + 1);
        vals[nvals++] = v;
        p = *end == ':' ? end : NULL;
    }
    return tb_filter_init(f, (tb_filter_kind)kind, vals[0], vals[1]);
}

double tb_filter_eval1(const tb_filter *f, double x)
{
    return tb__filter_raw(f, x) * f->norm;
}

double tb_filter_eval(const tb_filter *f, double x, double y)
{
    return tb_filter_eval1(f, x) * tb_filter_eval1(f, y);
}

/* ---------------------------------------------------------------- film */

/* Tile states within a pass. */
enum { TB__TILE_WAITING = 0, TB__TILE_PENDING = 1, TB__TILE_MERGED = 2 };

struct tb_film {
    int width, height, channels;
    int tile_size, tiles_x, tiles_y, ntiles;
    int apron;             /* pixels a splat reaches beyond the sample's own pixel */
    tb_filter filter;
    double *sum;           /* per pixel: channels weighted sums, then the weight sum */
    uint32_t *count;       /* per pixel: camera samples recorded */
    pthread_mutex_t lock;  /* guards pending, state, cursor and the merge */
    tb_film_tile **pending;/* submitted tiles waiting for their turn (NULL for skipped) */
    unsigned char *state;  /* TB__TILE_* per tile, this pass */
    int cursor;            /* next tile index to merge */
    uint64_t dropped;      /* non-finite samples dropped (merged from tiles; under lock) */
};

struct tb_film_tile {
    int index;
    int channels;
    const tb_filter *filter; /* the film's */
    tb_tile_rect own;        /* the tile's pixels */
    tb_tile_rect buf;        /* own + apron, clipped to the image */
    double *sum;             /* (channels + 1) per buf pixel */
    uint32_t *count;         /* per own pixel */
    uint64_t dropped;
};

tb_film *tb_film_create(const tb_film_desc *desc)
{
    if (!desc) {
        tb_error(TB_ERR_ARG, "film: NULL description");
        return NULL;
    }
    if (desc->width < 1 || desc->height < 1 || desc->width > (1 << 20) || desc->height > (1 << 20)) {
        tb_error(TB_ERR_ARG, "film: bad size %d x %d", desc->width, desc->height);
        return NULL;
    }
    if (desc->channels < 1 || desc->channels > TB_FILM_MAX_CHANNELS) {
        tb_error(TB_ERR_ARG, "film: %d channels (expected 1 to %d)", desc->channels,
                 TB_FILM_MAX_CHANNELS);
        return NULL;
    }
    if (desc->tile_size < 0 || desc->tile_size > 4096) {
        tb_error(TB_ERR_ARG, "film: bad tile size %d", desc->tile_size);
        return NULL;
    }
    size_t npix = (size_t)desc->width * (size_t)desc->height;
    size_t nsum = npix * (size_t)(desc->channels + 1);
    if (nsum / (size_t)(desc->channels + 1) != npix || nsum > ((size_t)1 << 32)) {
        tb_error(TB_ERR_ARG, "film: %d x %d x %d is too large", desc->width, desc->height,
                 desc->channels);
        return NULL;
    }
    tb_film *film = calloc(1, sizeof *film);
    if (!film) {
        tb_error(TB_ERR_NOMEM, "film: out of memory");
        return NULL;
    }
    film->width = desc->width;
    film->height = desc->height;
    film->channels = desc->channels;
    film->tile_size = desc->tile_size ? desc->tile_size : 16;
    film->tiles_x = (film->width + film->tile_size - 1) / film->tile_size;
    film->tiles_y = (film->height + film->tile_size - 1) / film->tile_size;
    film->ntiles = film->tiles_x * film->tiles_y;
    if (desc->filter) {
        film->filter = *desc->filter;
        if ((unsigned)film->filter.kind >= TB_FILTER_KIND_COUNT || !(film->filter.radius > 0.0) ||
            !(film->filter.radius <= TB__FILTER_MAX_RADIUS) || !(film->filter.norm > 0.0)) {
            free(film);
            tb_error(TB_ERR_ARG, "film: filter not set up by tb_filter_init");
            return NULL;
        }
    } else {
        tb_filter_init(&film->filter, TB_FILTER_BOX, 0.0, 0.0);
    }
    film->apron = (int)ceil(film->filter.radius + 0.5);
    film->sum = calloc(nsum, sizeof *film->sum);
    film->count = calloc(npix, sizeof *film->count);
    film->pending = calloc((size_t)film->ntiles, sizeof *film->pending);
    film->state = calloc((size_t)film->ntiles, 1);
    if (!film->sum || !film->count || !film->pending || !film->state ||
        pthread_mutex_init(&film->lock, NULL) != 0) {
        free(film->sum);
        free(film->count);
        free(film->pending);
        free(film->state);
        free(film);
        tb_error(TB_ERR_NOMEM, "film: out of memory for %d x %d pixels", desc->width, desc->height);
        return NULL;
    }
    return film;
}

void tb_film_free(tb_film *film)
{
    if (!film)
        return;
    for (int i = 0; i < film->ntiles; i++)
        tb_film_tile_free(film->pending[i]);
    pthread_mutex_destroy(&film->lock);
    free(film->sum);
    free(film->count);
    free(film->pending);
    free(film->state);
    free(film);
}

int tb_film_width(const tb_film *film) { return film->width; }
int tb_film_height(const tb_film *film) { return film->height; }
int tb_film_channels(const tb_film *film) { return film->channels; }
const tb_filter *tb_film_filter(const tb_film *film) { return &film->filter; }
int tb_film_tile_count(const tb_film *film) { return film->ntiles; }

tb_tile_rect tb_film_tile_rect(const tb_film *film, int index)
{
    tb_tile_rect r = {0, 0, 0, 0};
    if (index < 0 || index >= film->ntiles)
        return r;
    int tx = index % film->tiles_x, ty = index / film->tiles_x;
    r.x0 = tx * film->tile_size;
    r.y0 = ty * film->tile_size;
    r.x1 = r.x0 + film->tile_size < film->width ? r.x0 + film->tile_size : film->width;
    r.y1 = r.y0 + film->tile_size < film->height ? r.y0 + film->tile_size : film->height;
    return r;
}

tb_status tb_film_begin_pass(tb_film *film)
{
    pthread_mutex_lock(&film->lock);
    bool started = false;
    for (int i = 0; i < film->ntiles && !started; i++)
        started = film->state[i] != TB__TILE_WAITING;
    if (started && film->cursor < film->ntiles) {
        pthread_mutex_unlock(&film->lock);
        return tb_error(TB_ERR_ARG, "film: the previous pass has %d of %d tiles unmerged",
                        film->ntiles - film->cursor, film->ntiles);
    }
    memset(film->state, TB__TILE_WAITING, (size_t)film->ntiles);
    film->cursor = 0;
    pthread_mutex_unlock(&film->lock);
    return TB_OK;
}

bool tb_film_pass_complete(const tb_film *film)
{
    /* cursor is only written under the lock; reading it here is for a caller
     * that has joined its workers */
    return film->cursor == film->ntiles;
}

tb_film_tile *tb_film_tile_create(const tb_film *film, int index)
{
    if (index < 0 || index >= film->ntiles) {
        tb_error(TB_ERR_ARG, "film: tile index %d out of range (0..%d)", index, film->ntiles - 1);
        return NULL;
    }
    tb_film_tile *t = calloc(1, sizeof *t);
    if (!t) {
        tb_error(TB_ERR_NOMEM, "film: out of memory for a tile");
        return NULL;
    }
    t->index = index;
    t->channels = film->channels;
    t->filter = &film->filter;
    t->own = tb_film_tile_rect(film, index);
    int a = film->apron;
    t->buf.x0 = t->own.x0 - a > 0 ? t->own.x0 - a : 0;
    t->buf.y0 = t->own.y0 - a > 0 ? t->own.y0 - a : 0;
    t->buf.x1 = t->own.x1 + a < film->width ? t->own.x1 + a : film->width;
    t->buf.y1 = t->own.y1 + a < film->height ? t->own.y1 + a : film->height;
    size_t nbuf = (size_t)(t->buf.x1 - t->buf.x0) * (size_t)(t->buf.y1 - t->buf.y0);
    size_t nown = (size_t)(t->own.x1 - t->own.x0) * (size_t)(t->own.y1 - t->own.y0);
    t->sum = calloc(nbuf * (size_t)(film->channels + 1), sizeof *t->sum);
    t->count = calloc(nown, sizeof *t->count);
    if (!t->sum || !t->count) {
        tb_film_tile_free(t);
        tb_error(TB_ERR_NOMEM, "film: out of memory for a tile");
        return NULL;
    }
    return t;
}

tb_tile_rect tb_film_tile_pixels(const tb_film_tile *tile) { return tile->own; }

void tb_film_tile_free(tb_film_tile *tile)
{
    if (!tile)
        return;
    free(tile->sum);
    free(tile->count);
    free(tile);
}

/* floor(v) and ceil(v) as far as comparisons and int conversions see them
 * (a -0 may come back +0), by a conversion to int64 where |v| < 2^52: the
 * baseline x86-64 build has no rounding instruction and calls libm. */
static inline double tb__floor(double v)
{
    if (!(fabs(v) < 0x1p52))
        return floor(v);
    double t = (double)(long long)v;
    return t > v ? t - 1.0 : t;
}

static inline double tb__ceil(double v)
{
    if (!(fabs(v) < 0x1p52))
        return ceil(v);
    double t = (double)(long long)v;
    return t < v ? t + 1.0 : t;
}

/* Splats one sample into `sum`, the accumulator of the pixel rectangle `rect`
 * (row-major, channels + 1 doubles per pixel). Pixels outside rect get
 * nothing. Returns false if the sample was dropped as non-finite. */
static bool tb__splat(const tb_filter *f, int channels, double *sum, tb_tile_rect rect, double x,
                      double y, const float *value, double weight)
{
    if (!isfinite(x) || !isfinite(y) || !isfinite(weight))
        return false;
    for (int c = 0; c < channels; c++)
        if (!isfinite(value[c]))
            return false;
    double r = f->radius;
    /* pixels i with |x - (i + 1/2)| <= r; the filter decides the boundary */
    double lo_x = tb__ceil(x - 0.5 - r), hi_x = tb__floor(x - 0.5 + r);
    double lo_y = tb__ceil(y - 0.5 - r), hi_y = tb__floor(y - 0.5 + r);
    int ix0 = lo_x > rect.x0 ? (int)lo_x : rect.x0;
    int ix1 = hi_x < rect.x1 - 1 ? (int)hi_x : rect.x1 - 1;
    int iy0 = lo_y > rect.y0 ? (int)lo_y : rect.y0;
    int iy1 = hi_y < rect.y1 - 1 ? (int)hi_y : rect.y1 - 1;
    if (ix0 > ix1 || iy0 > iy1)
        return true;
    /* the support spans at most 2 r + 1 pixels per axis */
    double wx[2 * (int)TB__FILTER_MAX_RADIUS + 2];
    int nx = ix1 - ix0 + 1;
    /* tb_filter_eval1, inline (a call per pixel and axis cost more than the sum) */
    for (int i = 0; i < nx; i++)
        wx[i] = tb__filter_raw(f, x - ((double)(ix0 + i) + 0.5)) * f->norm;
    int stride = channels + 1;
    int rw = rect.x1 - rect.x0;
    for (int iy = iy0; iy <= iy1; iy++) {
        double wy = tb__filter_raw(f, y - ((double)iy + 0.5)) * f->norm * weight;
        if (wy == 0.0)
            continue;
        double *row = sum + ((size_t)(iy - rect.y0) * (size_t)rw + (size_t)(ix0 - rect.x0)) * (size_t)stride;
        for (int i = 0; i < nx; i++) {
            double w = wx[i] * wy;
            if (w == 0.0)
                continue;
            double *px = row + (size_t)i * (size_t)stride;
            for (int c = 0; c < channels; c++)
                px[c] += w * (double)value[c];
            px[channels] += w;
        }
    }
    return true;
}

void tb_film_tile_add(tb_film_tile *tile, double x, double y, const float *value, double weight)
{
    if (!(x >= tile->own.x0 && x < tile->own.x1 && y >= tile->own.y0 && y < tile->own.y1)) {
        if (!(isfinite(x) && isfinite(y)))
            tile->dropped++;
        return;
    }
    if (!tb__splat(tile->filter, tile->channels, tile->sum, tile->buf, x, y, value, weight))
        tile->dropped++;
    else
        TB_STAT_INC(tb__stat_splats);
}

void tb_film_tile_record_samples(tb_film_tile *tile, int px, int py, uint32_t n)
{
    if (px < tile->own.x0 || px >= tile->own.x1 || py < tile->own.y0 || py >= tile->own.y1)
        return;
    size_t w = (size_t)(tile->own.x1 - tile->own.x0);
    tile->count[(size_t)(py - tile->own.y0) * w + (size_t)(px - tile->own.x0)] += n;
}

/* Adds a tile's buffer into the film (caller holds the lock). */
static void tb__merge(tb_film *film, const tb_film_tile *t)
{
    int stride = film->channels + 1;
    int bw = t->buf.x1 - t->buf.x0;
    for (int y = t->buf.y0; y < t->buf.y1; y++) {
        const double *src = t->sum + (size_t)(y - t->buf.y0) * (size_t)bw * (size_t)stride;
        double *dst = film->sum + ((size_t)y * (size_t)film->width + (size_t)t->buf.x0) * (size_t)stride;
        size_t n = (size_t)bw * (size_t)stride;
        for (size_t i = 0; i < n; i++)
            dst[i] += src[i];
    }
    int ow = t->own.x1 - t->own.x0;
    for (int y = t->own.y0; y < t->own.y1; y++)
        for (int x = t->own.x0; x < t->own.x1; x++)
            film->count[(size_t)y * (size_t)film->width + (size_t)x] +=
                t->count[(size_t)(y - t->own.y0) * (size_t)ow + (size_t)(x - t->own.x0)];
    film->dropped += t->dropped;
    TB_STAT_INC(tb__stat_tiles_merged);
}

/* Records tile `index` as done (tile may be NULL for a skip) and merges every
 * tile whose turn has come. */
static tb_status tb__finish_tile(tb_film *film, int index, tb_film_tile *tile)
{
    if (index < 0 || index >= film->ntiles) {
        tb_film_tile_free(tile);
        return tb_error(TB_ERR_ARG, "film: tile index %d out of range", index);
    }
    pthread_mutex_lock(&film->lock);
    if (film->state[index] != TB__TILE_WAITING) {
        pthread_mutex_unlock(&film->lock);
        tb_film_tile_free(tile);
        return tb_error(TB_ERR_ARG, "film: tile %d finished twice in one pass", index);
    }
    film->state[index] = TB__TILE_PENDING;
    film->pending[index] = tile;
    while (film->cursor < film->ntiles && film->state[film->cursor] == TB__TILE_PENDING) {
        tb_film_tile *t = film->pending[film->cursor];
        if (t)
            tb__merge(film, t);
        tb_film_tile_free(t);
        film->pending[film->cursor] = NULL;
        film->state[film->cursor] = TB__TILE_MERGED;
        film->cursor++;
    }
    pthread_mutex_unlock(&film->lock);
    return TB_OK;
}

tb_status tb_film_tile_submit(tb_film *film, tb_film_tile *tile)
{
    if (!tile)
        return tb_error(TB_ERR_ARG, "film: NULL tile");
    return tb__finish_tile(film, tile->index, tile);
}

tb_status tb_film_tile_skip(tb_film *film, int index)
{
    return tb__finish_tile(film, index, NULL);
}

void tb_film_add(tb_film *film, double x, double y, const float *value, double weight)
{
    tb_tile_rect all = {0, 0, film->width, film->height};
    if (!tb__splat(&film->filter, film->channels, film->sum, all, x, y, value, weight))
        film->dropped++;
    else
        TB_STAT_INC(tb__stat_splats);
}

tb_image *tb_film_resolve(const tb_film *film, const char *const *names)
{
    tb_image *img = tb_image_create(film->width, film->height, film->channels, names);
    if (!img)
        return NULL;
    int stride = film->channels + 1;
    size_t npix = (size_t)film->width * (size_t)film->height;
    for (size_t i = 0; i < npix; i++) {
        const double *s = film->sum + i * (size_t)stride;
        double w = s[film->channels];
        float *out = img->pixels + i * (size_t)film->channels;
        for (int c = 0; c < film->channels; c++)
            out[c] = w > 0.0 ? (float)(s[c] / w) : 0.0f;
    }
    return img;
}

uint32_t tb_film_sample_count(const tb_film *film, int x, int y)
{
    if (x < 0 || y < 0 || x >= film->width || y >= film->height)
        return 0;
    return film->count[(size_t)y * (size_t)film->width + (size_t)x];
}

double tb_film_weight_sum(const tb_film *film, int x, int y)
{
    if (x < 0 || y < 0 || x >= film->width || y >= film->height)
        return 0.0;
    int stride = film->channels + 1;
    return film->sum[((size_t)y * (size_t)film->width + (size_t)x) * (size_t)stride + (size_t)film->channels];
}

uint64_t tb_film_dropped(const tb_film *film) { return film->dropped; }

/* ---------------------------------------------------------------- packing */

/* Tile bytes: a header of 6 int32 (index, channels, buf x0 y0 x1 y1), the
 * dropped count (uint64), then the sums (doubles) and the own pixels'
 * counts (uint32). The own rectangle follows from the index. */
#define TB__TILE_HEADER (6 * sizeof(int32_t) + sizeof(uint64_t))

static size_t tb__tile_nbuf(const tb_film_tile *t)
{
    return (size_t)(t->buf.x1 - t->buf.x0) * (size_t)(t->buf.y1 - t->buf.y0);
}

static size_t tb__tile_nown(const tb_film_tile *t)
{
    return (size_t)(t->own.x1 - t->own.x0) * (size_t)(t->own.y1 - t->own.y0);
}

size_t tb_film_tile_packed_size(const tb_film_tile *tile)
{
    return TB__TILE_HEADER + tb__tile_nbuf(tile) * (size_t)(tile->channels + 1) * sizeof(double) +
           tb__tile_nown(tile) * sizeof(uint32_t);
}

void tb_film_tile_pack(const tb_film_tile *tile, void *buf)
{
    unsigned char *p = buf;
    int32_t h[6] = {tile->index, tile->channels, tile->buf.x0, tile->buf.y0, tile->buf.x1, tile->buf.y1};
    memcpy(p, h, sizeof h);
    p += sizeof h;
    memcpy(p, &tile->dropped, sizeof tile->dropped);
    p += sizeof tile->dropped;
    size_t ns = tb__tile_nbuf(tile) * (size_t)(tile->channels + 1) * sizeof(double);
    memcpy(p, tile->sum, ns);
    p += ns;
    memcpy(p, tile->count, tb__tile_nown(tile) * sizeof(uint32_t));
}

tb_film_tile *tb_film_tile_unpack(const tb_film *film, const void *buf, size_t len)
{
    int32_t h[6];
    if (len < TB__TILE_HEADER) {
        tb_error(TB_ERR_FORMAT, "film: a packed tile of %zu bytes is shorter than its header", len);
        return NULL;
    }
    memcpy(h, buf, sizeof h);
    if (h[0] < 0 || h[0] >= film->ntiles || h[1] != film->channels) {
        tb_error(TB_ERR_FORMAT, "film: packed tile %d with %d channels does not fit this film (%d tiles, %d channels)",
                 (int)h[0], (int)h[1], film->ntiles, film->channels);
        return NULL;
    }
    tb_film_tile *t = tb_film_tile_create(film, h[0]);
    if (!t)
        return NULL;
    if (h[2] != t->buf.x0 || h[3] != t->buf.y0 || h[4] != t->buf.x1 || h[5] != t->buf.y1 ||
        len != tb_film_tile_packed_size(t)) {
        tb_film_tile_free(t);
        tb_error(TB_ERR_FORMAT, "film: packed tile %d (%zu bytes) has another apron or size than this film's",
                 (int)h[0], len);
        return NULL;
    }
    const unsigned char *p = (const unsigned char *)buf + sizeof h;
    memcpy(&t->dropped, p, sizeof t->dropped);
    p += sizeof t->dropped;
    size_t ns = tb__tile_nbuf(t) * (size_t)(t->channels + 1) * sizeof(double);
    memcpy(t->sum, p, ns);
    p += ns;
    memcpy(t->count, p, tb__tile_nown(t) * sizeof(uint32_t));
    return t;
}

/* Film bytes: width, height, channels (int32 each), pad, dropped (uint64),
 * the sums, the counts. */
#define TB__FILM_HEADER (4 * sizeof(int32_t) + sizeof(uint64_t))

size_t tb_film_packed_size(const tb_film *film)
{
    size_t npix = (size_t)film->width * (size_t)film->height;
    return TB__FILM_HEADER + npix * (size_t)(film->channels + 1) * sizeof(double) + npix * sizeof(uint32_t);
}

void tb_film_pack(const tb_film *film, void *buf)
{
    unsigned char *p = buf;
    int32_t h[4] = {film->width, film->height, film->channels, 0};
    memcpy(p, h, sizeof h);
    p += sizeof h;
    memcpy(p, &film->dropped, sizeof film->dropped);
    p += sizeof film->dropped;
    size_t npix = (size_t)film->width * (size_t)film->height;
    size_t ns = npix * (size_t)(film->channels + 1) * sizeof(double);
    memcpy(p, film->sum, ns);
    p += ns;
    memcpy(p, film->count, npix * sizeof(uint32_t));
}

tb_status tb_film_unpack(tb_film *film, const void *buf, size_t len)
{
    int32_t h[4];
    if (len < TB__FILM_HEADER)
        return tb_error(TB_ERR_FORMAT, "film: packed film of %zu bytes is shorter than its header", len);
    memcpy(h, buf, sizeof h);
    if (h[0] != film->width || h[1] != film->height || h[2] != film->channels)
        return tb_error(TB_ERR_FORMAT, "film: packed film is %d x %d with %d channels, this one %d x %d with %d",
                        (int)h[0], (int)h[1], (int)h[2], film->width, film->height, film->channels);
    if (len != tb_film_packed_size(film))
        return tb_error(TB_ERR_FORMAT, "film: packed film has %zu bytes, expected %zu", len,
                        tb_film_packed_size(film));
    const unsigned char *p = (const unsigned char *)buf + sizeof h;
    memcpy(&film->dropped, p, sizeof film->dropped);
    p += sizeof film->dropped;
    size_t npix = (size_t)film->width * (size_t)film->height;
    size_t ns = npix * (size_t)(film->channels + 1) * sizeof(double);
    memcpy(film->sum, p, ns);
    p += ns;
    memcpy(film->count, p, npix * sizeof(uint32_t));
    return TB_OK;
}
