/* Pixel sample patterns, adaptive refinement and the deterministic tiled
 * render loop (antialias.h, docs/antialiasing.md). */
#include "host/render/antialias.h"

#include <errno.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util/container/hash_table.h"
#include "util/stats/stats.h"

TB_STAT_COUNTER(tb__stat_aa_samples, "Antialias/camera samples");
TB_STAT_COUNTER(tb__stat_aa_rounds, "Antialias/adaptive rounds after the first");
TB_STAT_DISTRIBUTION(tb__stat_aa_spp, "Antialias/samples per pixel");

tb_aa_options tb_aa_defaults(void)
{
    tb_aa_options o;
    memset(&o, 0, sizeof o);
    o.spp = 1;
    o.pattern = TB_AA_STRATIFIED;
    o.criterion = TB_AA_STDERR;
    return o;
}

tb_status tb_aa_check(const tb_aa_options *o)
{
    if (!o)
        return tb_error(TB_ERR_ARG, "antialias: NULL options");
    if (o->spp < 1 || o->spp > TB_AA_MAX_SPP)
        return tb_error(TB_ERR_ARG, "antialias: spp %d out of range (1..%d)", o->spp, TB_AA_MAX_SPP);
    if (o->pattern != TB_AA_STRATIFIED && o->pattern != TB_AA_SOBOL)
        return tb_error(TB_ERR_ARG, "antialias: unknown sample pattern %d", (int)o->pattern);
    if (o->criterion != TB_AA_STDERR && o->criterion != TB_AA_CONTRAST)
        return tb_error(TB_ERR_ARG, "antialias: unknown criterion %d", (int)o->criterion);
    if (isnan(o->threshold) || isinf(o->threshold))
        return tb_error(TB_ERR_ARG, "antialias: threshold must be finite");
    if (o->max_spp > TB_AA_MAX_SPP)
        return tb_error(TB_ERR_ARG, "antialias: max spp %d exceeds %d", o->max_spp, TB_AA_MAX_SPP);
    return TB_OK;
}

double tb_aa_threshold(const tb_aa_options *o)
{
    if (o->threshold > 0.0)
        return o->threshold;
    return o->criterion == TB_AA_CONTRAST ? TB_AA_CONTRAST_DEFAULT : TB_AA_STDERR_DEFAULT;
}

int tb_aa_max_spp(const tb_aa_options *o)
{
    if (!o->adaptive)
        return o->spp;
    long m = o->max_spp > 0 ? o->max_spp : 16L * o->spp;
    if (m > TB_AA_MAX_SPP)
        m = TB_AA_MAX_SPP;
    if (m < o->spp)
        m = o->spp;
    return (int)m;
}

/* ------------------------------------------------------------ option parsing */

/* Parses a whole decimal integer in [lo, hi]. */
static bool tb__parse_int(const char *s, long lo, long hi, long *out)
{
    char *end = NULL;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (end == s || *end != '\0' || errno || v < lo || v > hi)
        return false;
    *out = v;
    return true;
}

/* Parses a whole finite number. */
static bool tb__parse_double(const char *s, double *out)
{
    char *end = NULL;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || *end != '\0' || errno || !isfinite(v))
        return false;
    *out = v;
    return true;
}

int tb_aa_parse_arg(int argc, char **argv, int *i, tb_aa_options *aa, tb_filter *filter)
{
    const char *opt = argv[*i];
    const char *val = *i + 1 < argc ? argv[*i + 1] : NULL;
    long n;
    if (aa && strcmp(opt, "--spp") == 0) {
        if (!val || !tb__parse_int(val, 1, TB_AA_MAX_SPP, &n)) {
            tb_error(TB_ERR_ARG, "--spp expects a whole number from 1 to %d", TB_AA_MAX_SPP);
            return -1;
        }
        aa->spp = (int)n;
        *i += 1;
        return 1;
    }
    if (aa && strcmp(opt, "--max-spp") == 0) {
        if (!val || !tb__parse_int(val, 1, TB_AA_MAX_SPP, &n)) {
            tb_error(TB_ERR_ARG, "--max-spp expects a whole number from 1 to %d", TB_AA_MAX_SPP);
            return -1;
        }
        aa->max_spp = (int)n;
        *i += 1;
        return 1;
    }
    if (aa && strcmp(opt, "--adaptive") == 0) {
        aa->adaptive = true;
        double t;
        if (val && tb__parse_double(val, &t)) {
            if (!(t > 0.0)) {
                tb_error(TB_ERR_ARG, "--adaptive threshold must be positive (got %s)", val);
                return -1;
            }
            aa->threshold = t;
            *i += 1;
        }
        return 1;
    }
    if (aa && strcmp(opt, "--aa-criterion") == 0) {
        if (val && strcmp(val, "stderr") == 0)
            aa->criterion = TB_AA_STDERR;
        else if (val && strcmp(val, "contrast") == 0)
            aa->criterion = TB_AA_CONTRAST;
        else {
            tb_error(TB_ERR_ARG, "--aa-criterion expects stderr or contrast");
            return -1;
        }
        *i += 1;
        return 1;
    }
    if (aa && strcmp(opt, "--aa-pattern") == 0) {
        if (val && strcmp(val, "stratified") == 0)
            aa->pattern = TB_AA_STRATIFIED;
        else if (val && strcmp(val, "sobol") == 0)
            aa->pattern = TB_AA_SOBOL;
        else {
            tb_error(TB_ERR_ARG, "--aa-pattern expects stratified or sobol");
            return -1;
        }
        *i += 1;
        return 1;
    }
    if (filter && strcmp(opt, "--filter") == 0) {
        if (!val) {
            tb_error(TB_ERR_ARG, "--filter expects KIND[:RADIUS[:SIGMA]]");
            return -1;
        }
        if (tb_filter_parse(val, filter) != TB_OK)
            return -1;
        *i += 1;
        return 1;
    }
    return 0;
}

/* ------------------------------------------------------------- per pixel */

void tb_aa_strata(int n, int *nx, int *ny)
{
    if (n < 1)
        n = 1;
    int y = (int)floor(sqrt((double)n));
    while (y > 1 && n % y != 0)
        y--;
    *ny = y;
    *nx = n / y;
}

/* The key of pixel (px, py) in pass `pass` of a render seeded `seed`: a chain
 * of bijective 64-bit mixes, so neighbouring pixels get unrelated streams. */
static uint64_t tb__pixel_key(const tb_aa_options *o, int px, int py)
{
    uint64_t h = tb_hash_u64(o->seed ^ 0x9e3779b97f4a7c15ull);
    h = tb_hash_u64(h ^ (uint64_t)o->pass);
    h = tb_hash_u64(h ^ (uint64_t)(uint32_t)px);
    h = tb_hash_u64(h ^ ((uint64_t)(uint32_t)py << 32));
    return h;
}

void tb_pixel_sampler_init(tb_pixel_sampler *s, const tb_aa_options *o, int px, int py)
{
    memset(s, 0, sizeof *s);
    s->pattern = o->pattern;
    s->spp = o->spp < 1 ? 1 : o->spp;
    tb_aa_strata(s->spp, &s->nx, &s->ny);
    s->key = tb__pixel_key(o, px, py);
}

/* The two 32-bit digit scrambles of stratum `cell` (-1: the whole pixel, for
 * the Sobol' pattern), fixed for the pixel so every round uses the same ones. */
static void tb__scrambles(uint64_t key, int cell, uint32_t *sx, uint32_t *sy)
{
    uint64_t h = tb_hash_u64(key ^ ((uint64_t)(uint32_t)(cell + 1) * 0xd1b54a32d192ed03ull));
    *sx = (uint32_t)h;
    *sy = (uint32_t)(h >> 32);
}

/* Radical inverse in base 2 of i as 32 bits (van der Corput; Sobol's first dimension). */
static uint32_t tb__reverse_bits(uint32_t i)
{
    i = (i << 16) | (i >> 16);
    i = ((i & 0x00ff00ffu) << 8) | ((i & 0xff00ff00u) >> 8);
    i = ((i & 0x0f0f0f0fu) << 4) | ((i & 0xf0f0f0f0u) >> 4);
    i = ((i & 0x33333333u) << 2) | ((i & 0xccccccccu) >> 2);
    i = ((i & 0x55555555u) << 1) | ((i & 0xaaaaaaaau) >> 1);
    return i;
}

/* Sobol's second dimension as 32 bits: its generator matrix has the columns
 * v_k (v_0 = 2^31, v_{k+1} = v_k ^ (v_k >> 1)), i.e. Pascal's triangle mod 2
 * (Kollig and Keller 2002). Together with the first dimension this is the
 * (0,2)-sequence in base 2. */
static uint32_t tb__sobol2(uint32_t i)
{
    uint32_t r = 0;
    for (uint32_t v = 1u << 31; i; i >>= 1, v ^= v >> 1)
        if (i & 1u)
            r ^= v;
    return r;
}

/* The top 24 bits of a 32-bit fraction as a float in [0, 1). */
static float tb__u32_to_unit(uint32_t b)
{
    return (float)(b >> 8) * 0x1p-24f;
}

/* (c + j) / n rounded to float and kept inside the cell [c/n, (c+1)/n) of
 * the real line: rounding may land on an edge, which would put the sample in
 * the neighbouring stratum (the products below are exact in double). */
static float tb__in_cell(int c, int n, double j)
{
    float x = (float)(((double)c + j) / (double)n);
    if ((double)x * (double)n >= (double)(c + 1))
        x = nextafterf(x, 0.0f);
    if ((double)x * (double)n < (double)c)
        x = nextafterf(x, 1.0f);
    return x;
}

int tb_pixel_sampler_round(tb_pixel_sampler *s, float *xy)
{
    int n = s->spp;
    if (s->pattern == TB_AA_SOBOL) {
        uint32_t sx, sy;
        tb__scrambles(s->key, -1, &sx, &sy);
        for (int k = 0; k < n; k++) {
            uint32_t i = (uint32_t)s->taken + (uint32_t)k;
            xy[2 * k] = tb__u32_to_unit(tb__reverse_bits(i) ^ sx);
            xy[2 * k + 1] = tb__u32_to_unit(tb__sobol2(i) ^ sy);
        }
    } else {
        /* round r puts point r of its stratum's own scrambled (0,2)-sequence
         * in each stratum: one uniformly distributed point per stratum in
         * every round, and rounds that fill each stratum evenly together */
        uint32_t r = (uint32_t)(s->taken / n);
        uint32_t bx = tb__reverse_bits(r), by = tb__sobol2(r);
        for (int k = 0; k < n; k++) {
            uint32_t sx, sy;
            tb__scrambles(s->key, k, &sx, &sy);
            xy[2 * k] = tb__in_cell(k % s->nx, s->nx, (double)tb__u32_to_unit(bx ^ sx));
            xy[2 * k + 1] = tb__in_cell(k / s->nx, s->ny, (double)tb__u32_to_unit(by ^ sy));
        }
    }
    s->taken += n;
    return n;
}

/* The stream of sample `index` of the pixel with key `key`. */
static void tb__sample_rng(uint64_t key, uint32_t index, tb_rng *out)
{
    tb_rng_seed(out, tb_hash_u64(key ^ (uint64_t)index), 1);
}

void tb_aa_sample_rng(const tb_aa_options *o, int px, int py, uint32_t index, tb_rng *out)
{
    tb__sample_rng(tb__pixel_key(o, px, py), index, out);
}

void tb_aa_luminance_weights(int channels, float *w)
{
    if (channels == 3) {
        w[0] = 0.2126f;
        w[1] = 0.7152f;
        w[2] = 0.0722f;
        return;
    }
    for (int c = 0; c < channels; c++)
        w[c] = 1.0f / (float)channels;
}

bool tb_aa_needs_more(const tb_aa_options *o, int channels, const float *lum_w, const float *values,
                      int n)
{
    if (n < 2)
        return true;
    double t = tb_aa_threshold(o);
    if (o->criterion == TB_AA_CONTRAST) {
        /* Mitchell 1987: contrast per channel against 0.4, 0.3, 0.6 for R, G, B
         * (the eye is most sensitive to green contrast), scaled with T */
        static const double rgb_scale[3] = {1.0, 0.75, 1.5};
        for (int c = 0; c < channels; c++) {
            double lo = values[c], hi = values[c];
            for (int k = 1; k < n; k++) {
                double v = values[(size_t)k * (size_t)channels + (size_t)c];
                lo = v < lo ? v : lo;
                hi = v > hi ? v : hi;
            }
            double sum = hi + lo;
            double contrast = sum > 0.0 ? (hi - lo) / sum : 0.0;
            double tc = channels == 3 ? t * rgb_scale[c] : t;
            if (contrast > tc)
                return true;
        }
        return false;
    }
    /* standard error of the mean luminance, two passes in double */
    double mean = 0.0;
    for (int k = 0; k < n; k++) {
        double y = 0.0;
        for (int c = 0; c < channels; c++)
            y += (double)lum_w[c] * (double)values[(size_t)k * (size_t)channels + (size_t)c];
        mean += y;
    }
    mean /= n;
    double ss = 0.0;
    for (int k = 0; k < n; k++) {
        double y = 0.0;
        for (int c = 0; c < channels; c++)
            y += (double)lum_w[c] * (double)values[(size_t)k * (size_t)channels + (size_t)c];
        ss += (y - mean) * (y - mean);
    }
    double se = sqrt(ss / ((double)(n - 1) * (double)n));
    return se > t * (fabs(mean) + 1.0 / 256.0);
}

/* ----------------------------------------------------------- the render loop */

/* One thread's scratch memory and counters. */
typedef struct tb__aa_worker {
    const tb_aa_options *aa;
    const tb_aa_render_desc *desc;
    int channels, spp, max_spp, width, height;
    const float *lum;
    float *xy;          /* max_spp positions of the current pixel */
    float *vals;        /* max_spp values of the current pixel */
    float *ring_vals;   /* adaptive: first-round values of the tile and its 1-pixel ring */
    unsigned char *ring_flag; /* adaptive: first round failed the criterion */
    uint64_t samples, ring_samples, pixels, refined;
    int max_used;
} tb__aa_worker;

/* Evaluates the samples k0 .. k1-1 of pixel (px, py) at positions xy. */
static void tb__eval(tb__aa_worker *w, int px, int py, const float *xy, int k0, int k1, float *out)
{
    uint64_t key = tb__pixel_key(w->aa, px, py);
    for (int j = k0; j < k1; j++) {
        tb_rng srng;
        tb__sample_rng(key, (uint32_t)j, &srng);
        w->desc->sample(w->desc->ctx, (double)px + (double)xy[2 * j], (double)py + (double)xy[2 * j + 1],
                        &srng, out + (size_t)(j - k0) * (size_t)w->channels);
    }
}

/* Renders the pixels of `tile`. Adaptive: first the first round of every
 * pixel of the tile and of the ring of pixels around it (the neighbours'
 * first rounds are a function of their own streams, so a tile computes them
 * itself and stays independent of the others); a pixel gets more rounds if
 * its own first round or a neighbour's fails the criterion (an edge that
 * slips between a pixel's first samples is usually caught by a neighbour),
 * and then as long as its own samples fail it, up to max_spp. */
static void tb__render_tile(tb__aa_worker *w, tb_film_tile *tile)
{
    const tb_aa_options *aa = w->aa;
    int ch = w->channels, spp = w->spp;
    tb_tile_rect r = tb_film_tile_pixels(tile);
    tb_tile_rect g = r; /* ring rectangle */
    int gw = 0;
    if (aa->adaptive) {
        g.x0 = r.x0 > 0 ? r.x0 - 1 : 0;
        g.y0 = r.y0 > 0 ? r.y0 - 1 : 0;
        g.x1 = r.x1 < w->width ? r.x1 + 1 : r.x1;
        g.y1 = r.y1 < w->height ? r.y1 + 1 : r.y1;
        gw = g.x1 - g.x0;
        for (int py = g.y0; py < g.y1; py++)
            for (int px = g.x0; px < g.x1; px++) {
                size_t gi = (size_t)(py - g.y0) * (size_t)gw + (size_t)(px - g.x0);
                float *v = w->ring_vals + gi * (size_t)spp * (size_t)ch;
                tb_pixel_sampler ps;
                tb_pixel_sampler_init(&ps, aa, px, py);
                tb_pixel_sampler_round(&ps, w->xy);
                tb__eval(w, px, py, w->xy, 0, spp, v);
                w->ring_flag[gi] = tb_aa_needs_more(aa, ch, w->lum, v, spp);
                if (px < r.x0 || px >= r.x1 || py < r.y0 || py >= r.y1)
                    w->ring_samples += (uint64_t)spp;
            }
    }
    for (int py = r.y0; py < r.y1; py++) {
        for (int px = r.x0; px < r.x1; px++) {
            tb_pixel_sampler ps;
            tb_pixel_sampler_init(&ps, aa, px, py);
            int n = tb_pixel_sampler_round(&ps, w->xy), rounds = 1;
            if (aa->adaptive) {
                size_t gi = (size_t)(py - g.y0) * (size_t)gw + (size_t)(px - g.x0);
                memcpy(w->vals, w->ring_vals + gi * (size_t)spp * (size_t)ch,
                       sizeof(float) * (size_t)spp * (size_t)ch);
                bool more = false;
                for (int dy = -1; dy <= 1 && !more; dy++)
                    for (int dx = -1; dx <= 1 && !more; dx++) {
                        int qx = px + dx, qy = py + dy;
                        if (qx >= g.x0 && qx < g.x1 && qy >= g.y0 && qy < g.y1)
                            more = w->ring_flag[(size_t)(qy - g.y0) * (size_t)gw + (size_t)(qx - g.x0)];
                    }
                while (more && n + spp <= w->max_spp) {
                    int k = tb_pixel_sampler_round(&ps, w->xy + 2 * (size_t)n);
                    tb__eval(w, px, py, w->xy, n, n + k, w->vals + (size_t)n * (size_t)ch);
                    n += k;
                    rounds++;
                    more = tb_aa_needs_more(aa, ch, w->lum, w->vals, n);
                }
            } else {
                tb__eval(w, px, py, w->xy, 0, n, w->vals);
            }
            /* density compensation: each pixel's samples carry a total
             * weight of 1 whatever their number */
            double wt = 1.0 / (double)n;
            for (int j = 0; j < n; j++)
                tb_film_tile_add(tile, (double)px + (double)w->xy[2 * j], (double)py + (double)w->xy[2 * j + 1],
                                 w->vals + (size_t)j * (size_t)ch, wt);
            tb_film_tile_record_samples(tile, px, py, (uint32_t)n);
            w->samples += (uint64_t)n;
            w->pixels++;
            if (rounds > 1) {
                w->refined++;
                tb_stat_add(&tb__stat_aa_rounds, rounds - 1);
            }
            if (n > w->max_used)
                w->max_used = n;
            tb_stat_add(&tb__stat_aa_samples, n);
            tb_stat_sample(&tb__stat_aa_spp, n);
        }
    }
}

tb_status tb_aa_render(tb_film *film, const tb_aa_options *aa, const tb_aa_render_desc *desc,
                       tb_aa_stats *stats)
{
    if (!film || !aa || !desc || !desc->sample)
        return tb_error(TB_ERR_ARG, "antialias render: NULL film, options or sample function");
    tb_status st = tb_aa_check(aa);
    if (st)
        return st;
    if (desc->threads < 0)
        return tb_error(TB_ERR_ARG, "antialias render: negative thread count %d", desc->threads);
    st = tb_film_begin_pass(film);
    if (!st && desc->exchange)
        st = desc->exchange->begin_pass(desc->exchange->ctx, film, desc->pass_index, desc->progress,
                                         desc->cancel);
    if (st)
        return st;
    int channels = tb_film_channels(film);
    float lum_default[TB_FILM_MAX_CHANNELS];
    tb_aa_luminance_weights(channels, lum_default);
    int ntiles = tb_film_tile_count(film);
    int nthreads = desc->threads > 0 ? desc->threads : omp_get_max_threads();
    /* the largest tile plus its ring */
    tb_tile_rect t0 = tb_film_tile_rect(film, 0);
    size_t ring_pixels = (size_t)(t0.x1 - t0.x0 + 2) * (size_t)(t0.y1 - t0.y0 + 2);

    /* the first error of any thread: status and message, copied under a lock
     * because the message buffer is thread-local */
    tb_status first_err = TB_OK;
    char err_msg[512] = "";
    atomic_int failed = 0;
    uint64_t total_samples = 0, total_ring = 0, total_pixels = 0, total_refined = 0;
    int max_used = 0, skipped = 0;

#pragma omp parallel num_threads(nthreads) reduction(+ : total_samples, total_ring, total_pixels, total_refined, skipped) reduction(max : max_used)
    {
        tb__aa_worker w;
        memset(&w, 0, sizeof w);
        w.aa = aa;
        w.desc = desc;
        w.channels = channels;
        w.spp = aa->spp;
        w.max_spp = tb_aa_max_spp(aa);
        w.width = tb_film_width(film);
        w.height = tb_film_height(film);
        w.lum = desc->lum_weights ? desc->lum_weights : lum_default;
        w.xy = malloc((size_t)w.max_spp * 2 * sizeof *w.xy);
        w.vals = malloc((size_t)w.max_spp * (size_t)channels * sizeof *w.vals);
        if (aa->adaptive) {
            w.ring_vals = malloc(ring_pixels * (size_t)w.spp * (size_t)channels * sizeof *w.ring_vals);
            w.ring_flag = malloc(ring_pixels);
        }
        if (!w.xy || !w.vals || (aa->adaptive && (!w.ring_vals || !w.ring_flag))) {
#pragma omp critical(tb__aa_error)
            if (!first_err) {
                first_err = TB_ERR_NOMEM;
                snprintf(err_msg, sizeof err_msg, "antialias render: out of memory for %d samples",
                         w.max_spp);
            }
            atomic_store(&failed, 1);
        }
        const tb_tile_exchange *ex = desc->exchange;
        /* the tiles: all of them over this process's threads, or those the
         * exchange hands this process */
#pragma omp for schedule(dynamic, 1)
        for (int k = 0; k < (ex ? nthreads : ntiles); k++) {
            int t = k;
            while (ex ? ex->claim(ex->ctx, &t) : t == k) {
                bool cancel = desc->cancel && atomic_load(desc->cancel);
                tb_film_tile *tile = NULL;
                if (!atomic_load(&failed) && !cancel) {
                    tile = tb_film_tile_create(film, t);
                    if (!tile) {
#pragma omp critical(tb__aa_error)
                        if (!first_err) {
                            first_err = TB_ERR_NOMEM;
                            snprintf(err_msg, sizeof err_msg, "%s", tb_last_error());
                        }
                        atomic_store(&failed, 1);
                    }
                }
                tb_tile_rect r = tile ? tb_film_tile_pixels(tile) : (tb_tile_rect){0, 0, 0, 0};
                if (tile)
                    tb__render_tile(&w, tile);
                else
                    skipped++;
                tb_status fst = ex ? ex->finish(ex->ctx, film, t, tile)
                                   : (tile ? tb_film_tile_submit(film, tile) : tb_film_tile_skip(film, t));
                if (fst != TB_OK) {
#pragma omp critical(tb__aa_error)
                    if (!first_err) {
                        first_err = fst;
                        snprintf(err_msg, sizeof err_msg, "%s", tb_last_error());
                    }
                    atomic_store(&failed, 1);
                }
                if (tile && desc->progress)
                    tb_progress_add(desc->progress, (int64_t)(r.x1 - r.x0) * (r.y1 - r.y0));
                if (!ex)
                    t = -1; /* one tile per iteration without an exchange */
            }
        }
        total_samples += w.samples;
        total_ring += w.ring_samples;
        total_pixels += w.pixels;
        total_refined += w.refined;
        if (w.max_used > max_used)
            max_used = w.max_used;
        free(w.xy);
        free(w.vals);
        free(w.ring_vals);
        free(w.ring_flag);
    }
    tb_aa_stats all;
    all.samples = total_samples;
    all.ring_samples = total_ring;
    all.pixels = total_pixels;
    all.pixels_refined = total_refined;
    all.max_spp_used = max_used;
    all.tiles_skipped = skipped;
    /* the other processes' tiles: rank 0 waits for them, everyone sums */
    if (desc->exchange) {
        /* always: the others wait for this process's tiles (a failed one
         * sent skips), and all must learn of a failure anywhere */
        tb_status mine = first_err ? tb_error(first_err, "%s", err_msg) : TB_OK;
        tb_status est = desc->exchange->end_pass(desc->exchange->ctx, film, &all, mine);
        if (est)
            return est;
        total_samples = all.samples, total_ring = all.ring_samples, total_pixels = all.pixels;
        total_refined = all.pixels_refined, max_used = all.max_spp_used, skipped = all.tiles_skipped;
    }
    if (stats) {
        stats->samples = total_samples;
        stats->ring_samples = total_ring;
        stats->pixels = total_pixels;
        stats->pixels_refined = total_refined;
        stats->max_spp_used = max_used;
        stats->tiles_skipped = skipped;
    }
    if (first_err)
        return tb_error(first_err, "%s", err_msg);
    return TB_OK;
}
