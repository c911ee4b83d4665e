/* tb_gpu_render_raytrace (render.h): host/render's pass driver
 * (render_internal.h) with the wavefront as its renderer. A pass takes the
 * film's tiles in batches of whole rows, in the CPU path's order, traces a
 * batch's camera samples in one wavefront call and merges the tiles in
 * index order; adaptive passes run in render_adaptive.c. */
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "host/gpu/render_internal.h"
#include "host/render/antialias.h"

/* Host memory for the paths of one wavefront batch (stacks, streams,
 * radiance, the wave's arrays): the batch takes rows of tiles, in the CPU
 * path's order, until its samples would need more (at least one row). */
#define TB__GR_BATCH_BYTES ((size_t)256 << 20)
/* ... and at most this many samples (enough to keep a device busy). */
#define TB__GR_BATCH_MAX 65536

/* A run of rows of one film tile within a batch. */
typedef struct tb__seg {
    int slot;      /* its tile buffer in tiles[] */
    int y0, y1;    /* rows */
    size_t base;   /* its first sample in the batch */
    bool last;     /* the tile's last rows: submit it after this batch */
} tb__seg;

/* The renderer as tb__render_drive runs it: the batch buffers, and the
 * tiles a batch is filling. */
typedef struct tb__gr_engine {
    tb__gr_batch b;
    const tb_render_options *o;
    size_t row_samples;     /* samples of one row of a full tile */
    int max_slots;          /* tiles a batch can touch */
    tb_film_tile **tiles;   /* their buffers; tiles[0]: a tile begun in the previous batch */
    tb__seg *segs;
    float *pxys;            /* per thread: a pixel's sample positions */
} tb__gr_engine;

void tb__gr_skip_tiles(tb_film *film, int t, tb_aa_stats *as)
{
    int ntiles = tb_film_tile_count(film);
    for (int k = t; k < ntiles; k++)
        tb_film_tile_skip(film, k);
    as->tiles_skipped += ntiles - t;
}

/* tb__render_engine.start: sizes the batches from the film's tiles and
 * allocates them. */
static tb_status tb__gr_start(void *ctx, const tb_film *film)
{
    tb__gr_engine *e = ctx;
    tb_gpu_renderer *r = e->b.r;
    const tb_render_options *o = e->o;
    const int nch = r->nch, spp = o->aa.spp;
    tb_tile_rect t0r = tb_film_tile_rect(film, 0);
    const size_t tw = (size_t)(t0r.x1 - t0r.x0), th = (size_t)(t0r.y1 - t0r.y0);
    /* bytes per path: stack entries (ray, depth, MIS context, throughput),
     * streams, film position, radiance, and the wave's copies and surface
     * records */
    size_t per_path =
        (size_t)r->cap_stack * (sizeof(tb_ray) + sizeof(int) + sizeof(tb_rt_mis) + (size_t)nch * sizeof(float)) +
        2 * sizeof(tb_rng) + 2 * sizeof(double) + 2 * (size_t)nch * sizeof(float) + sizeof(tb_ray) + sizeof(tb_hit) +
        sizeof(tb_rt_mis) + 4 * sizeof(size_t) + 2 * sizeof(int) + (r->any_surface ? sizeof(tb_gpu_surface) + 1 : 0);
    size_t budget = TB__GR_BATCH_BYTES / per_path;
    if (budget > TB__GR_BATCH_MAX)
        budget = TB__GR_BATCH_MAX;
    e->row_samples = tw * (size_t)spp;
    size_t cap = budget > e->row_samples ? budget - budget % e->row_samples : e->row_samples; /* whole rows */
    if (o->aa.adaptive)
        cap = budget; /* adaptive rounds go through the wavefront in pieces of any size */
    e->b.cap = cap;
    e->max_slots = (int)(cap / e->row_samples / (th ? th : 1)) + 2;
    size_t max_segs = cap / e->row_samples + 2;
    e->tiles = calloc((size_t)e->max_slots, sizeof *e->tiles);
    e->segs = malloc(max_segs * sizeof *e->segs);
    e->b.xy = malloc(cap * 2 * sizeof *e->b.xy);
    e->b.rng = malloc(cap * sizeof *e->b.rng);
    e->b.rng0 = malloc(cap * sizeof *e->b.rng0);
    int maxth = omp_get_max_threads() > o->threads ? omp_get_max_threads() : o->threads;
    e->b.L = malloc(cap * (size_t)nch * sizeof *e->b.L);
    e->pxys = malloc((size_t)maxth * (size_t)spp * 2 * sizeof *e->pxys);
    if (!e->tiles || !e->segs || !e->b.xy || !e->b.rng || !e->b.rng0 || !e->b.L || !e->pxys)
        return tb_error(TB_ERR_NOMEM, "GPU render: out of memory");
    tb_status err = tb__gr_paths_alloc(&e->b.P, cap, r->cap_stack, nch);
    e->b.P.rng = e->b.rng;
    e->b.P.rng0 = e->b.rng0;
    e->b.P.xy = e->b.xy;
    e->b.P.L = e->b.L;
    return err;
}

/* The next batch: rows of tiles from tile *t, row *row on, whole rows, at
 * most cap samples (a tile begun in the previous batch is in tiles[0]).
 * Its segments into e->segs; *nseg, *np: their count and samples. */
static tb_status tb__gr_fill_batch(tb__gr_engine *e, tb_film *film, const tb_aa_options *aa, int *t, int *row,
                                   int *nseg, size_t *np)
{
    const int ntiles = tb_film_tile_count(film);
    const size_t cap = e->b.cap;
    int nslot = e->tiles[0] ? 1 : 0;
    *nseg = 0;
    *np = 0;
    while (*t < ntiles && *np + e->row_samples <= cap) {
        tb_tile_rect rc = tb_film_tile_rect(film, *t);
        int slot = 0;
        if (*row == rc.y0) {
            if (nslot == e->max_slots)
                break;
            if (!(e->tiles[nslot] = tb_film_tile_create(film, *t)))
                return TB_ERR_NOMEM;
            slot = nslot++;
        }
        size_t rs_ = (size_t)(rc.x1 - rc.x0) * (size_t)aa->spp;
        size_t fit = (cap - *np) / rs_;
        int y1 = fit >= (size_t)(rc.y1 - *row) ? rc.y1 : *row + (int)fit;
        e->segs[(*nseg)++] = (tb__seg){slot, *row, y1, *np, y1 == rc.y1};
        *np += (size_t)(y1 - *row) * rs_;
        if (y1 < rc.y1) {
            *row = y1;
            break; /* the batch is full in this tile's middle */
        }
        (*t)++;
        *row = *t < ntiles ? tb_film_tile_rect(film, *t).y0 : 0;
    }
    return TB_OK;
}

/* The batch's camera rays, in the CPU path's order. */
static void tb__gr_camera_rays(tb__gr_engine *e, const tb_aa_options *aa, int nseg)
{
    const tb_camera *cam = &e->b.r->scene->camera;
    tb__gr_batch *b = &e->b;
    const int spp = aa->spp;
#pragma omp parallel for schedule(dynamic, 1) num_threads(b->nth)
    for (int g = 0; g < nseg; g++) {
        const tb__seg *sg = &e->segs[g];
        tb_tile_rect rc = tb_film_tile_pixels(e->tiles[sg->slot]);
        size_t q = sg->base;
        float *pxy = e->pxys + (size_t)omp_get_thread_num() * 2 * (size_t)spp;
        for (int py = sg->y0; py < sg->y1; py++)
            for (int px = rc.x0; px < rc.x1; px++) {
                tb_pixel_sampler ps;
                tb_pixel_sampler_init(&ps, aa, px, py);
                int ns = tb_pixel_sampler_round(&ps, pxy);
                for (int j = 0; j < ns; j++, q++) {
                    double x = (double)px + (double)pxy[2 * j], y = (double)py + (double)pxy[2 * j + 1];
                    b->xy[2 * q] = x;
                    b->xy[2 * q + 1] = y;
                    tb_aa_sample_rng(aa, px, py, (uint32_t)j, &b->rng[q]);
                    tb__gr_push_camera(&b->P, q, cam, x, y, &b->rng[q], &b->rng0[q]);
                }
            }
    }
}

/* Splats the batch in the CPU path's order (each tile its own buffer: the
 * segments of a batch are in distinct tiles) and merges its finished tiles
 * in index order; an unfinished one moves to slot 0 for the next batch. */
static tb_status tb__gr_splat(tb__gr_engine *e, tb__render_run *run, tb_film *film, int spp, int nseg,
                              tb_aa_stats *as)
{
    const tb__gr_batch *b = &e->b;
    const size_t nch = (size_t)b->r->nch;
#pragma omp parallel for schedule(dynamic, 1) num_threads(b->nth)
    for (int g = 0; g < nseg; g++) {
        const tb__seg *sg = &e->segs[g];
        tb_tile_rect rc = tb_film_tile_pixels(e->tiles[sg->slot]);
        size_t q = sg->base;
        double wt = 1.0 / (double)spp;
        for (int py = sg->y0; py < sg->y1; py++)
            for (int px = rc.x0; px < rc.x1; px++) {
                for (int j = 0; j < spp; j++, q++)
                    tb_film_tile_add(e->tiles[sg->slot], b->xy[2 * q], b->xy[2 * q + 1], b->L + q * nch, wt);
                tb_film_tile_record_samples(e->tiles[sg->slot], px, py, (uint32_t)spp);
            }
    }
    tb_status err = TB_OK;
    int keep = -1;
    for (int g = 0; g < nseg; g++) {
        tb__seg *sg = &e->segs[g];
        tb_tile_rect rc = tb_film_tile_pixels(e->tiles[sg->slot]);
        as->pixels += (uint64_t)(rc.x1 - rc.x0) * (uint64_t)(sg->y1 - sg->y0);
        if (run->progress)
            tb_progress_add(run->progress, (int64_t)(rc.x1 - rc.x0) * (sg->y1 - sg->y0));
        if (!sg->last) {
            keep = sg->slot;
            continue;
        }
        tb_status e2 = tb_film_tile_submit(film, e->tiles[sg->slot]);
        e->tiles[sg->slot] = NULL;
        if (e2 && !err)
            err = e2;
    }
    if (keep > 0) {
        e->tiles[0] = e->tiles[keep];
        e->tiles[keep] = NULL;
    }
    return err;
}

/* tb__render_engine.pass: one pass in row batches (adaptive:
 * tb__gr_adaptive_pass). */
static tb_status tb__gr_pass(void *ctx, tb__render_run *run, tb_film *film, const tb_aa_options *aa,
                             tb_aa_stats *as)
{
    tb__gr_engine *e = ctx;
    if (aa->adaptive)
        return tb__gr_adaptive_pass(&e->b, run, film, aa, as);
    as->max_spp_used = aa->spp;
    tb_status err = tb_film_begin_pass(film);
    const int ntiles = tb_film_tile_count(film);
    /* t: the tile being filled, row: its next row (tiles[0] is its buffer
     * when a batch starts in its middle) */
    int t = 0, row = ntiles > 0 ? tb_film_tile_rect(film, 0).y0 : 0;
    while (t < ntiles && !err) {
        if (tb__render_should_stop(run)) {
            /* a tile cut short is skipped whole, as the CPU path skips tiles */
            tb_film_tile_free(e->tiles[0]);
            e->tiles[0] = NULL;
            tb__gr_skip_tiles(film, t, as);
            break;
        }
        int nseg;
        size_t np;
        if ((err = tb__gr_fill_batch(e, film, aa, &t, &row, &nseg, &np)))
            break;
        tb__gr_camera_rays(e, aa, nseg);
        e->b.P.n = np;
        memset(e->b.L, 0, np * (size_t)e->b.r->nch * sizeof *e->b.L);
        if ((err = tb__gr_wavefront(e->b.r, &e->b.P)))
            break;
        err = tb__gr_splat(e, run, film, aa->spp, nseg, as);
        as->samples += np;
    }
    return err;
}

tb_status tb_gpu_render_raytrace(tb_gpu_device *dev, const tb_scene *s, const tb_render_options *o,
                                 tb_image **out, tb_render_stats *stats, tb_gpu_render_stats *gstats)
{
    *out = NULL;
    tb_status err = tb__render_check(o);
    if (err)
        return err;
    tb__gr_engine e = {.o = o, .b.nth = o->threads > 0 ? o->threads : omp_get_max_threads()};
    if ((err = tb_gpu_renderer_create(dev, s, &o->rt, &e.b.r)))
        return err;
    e.b.r->threads = o->threads;
    tb_render_stats rs;
    memset(&rs, 0, sizeof rs);
    err = tb__render_drive(s, o, &(tb__render_engine){.ctx = &e, .start = tb__gr_start, .pass = tb__gr_pass}, out,
                           &rs);
    e.b.r->st.samples += rs.aa.samples;
    if (gstats)
        *gstats = e.b.r->st;
    if (stats)
        *stats = rs;
    for (int k = 0; k < e.max_slots && e.tiles; k++)
        tb_film_tile_free(e.tiles[k]);
    tb__gr_paths_free(&e.b.P);
    free(e.tiles), free(e.segs), free(e.b.xy), free(e.b.rng), free(e.b.rng0), free(e.b.L), free(e.pxys);
    tb_gpu_renderer_destroy(e.b.r);
    return err;
}
