/* Adaptive antialiasing on the wavefront (render.h): tb_aa_render's
 * decisions (antialias.c, tb__render_tile) in rounds: the first round of
 * every pixel of a batch's tiles and of each tile's one-pixel ring, the
 * criterion on the host from the wavefront's values, then a round for every
 * pixel that still needs one, and so on up to max_spp. Each tile evaluates
 * its own ring (as on the CPU path, so ring_samples agree), and every sample
 * keeps the CPU's position, stream and index. */
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "host/gpu/render_internal.h"
#include "host/render/antialias.h"

/* One camera sample to evaluate: its film position, pixel, index in the
 * pixel (its stream) and where its value goes. */
typedef struct tb__aa_req {
    double x, y;
    int px, py;
    uint32_t j;
    float *dst;
} tb__aa_req;

/* The adaptive state of one tile of a batch. */
typedef struct tb__aa_tile {
    tb_film_tile *tile;
    tb_tile_rect r, g;        /* its pixels; with the ring (clipped to the image) */
    float *ring_vals;         /* first-round values of every pixel of g (spp x nch each) */
    unsigned char *ring_flag; /* the first round fails the criterion */
    tb_pixel_sampler *ps;     /* per pixel of r: its sampler (rounds taken) */
    int *n, *cap, *rounds;    /* per pixel: samples so far, room, rounds */
    unsigned char *more;      /* per pixel: another round is due */
    float **vals, **xy;       /* per pixel: values (n x nch) and positions in the pixel (n x 2) */
} tb__aa_tile;

static void tb__aa_tile_free(tb__aa_tile *a)
{
    size_t np = (size_t)(a->r.x1 - a->r.x0) * (size_t)(a->r.y1 - a->r.y0);
    for (size_t i = 0; (a->vals || a->xy) && i < np; i++) {
        if (a->vals)
            free(a->vals[i]);
        if (a->xy)
            free(a->xy[i]);
    }
    tb_film_tile_free(a->tile);
    free(a->ring_vals), free(a->ring_flag), free(a->ps), free(a->n), free(a->cap), free(a->rounds), free(a->more),
        free(a->vals), free(a->xy);
    memset(a, 0, sizeof *a);
}

/* The shared state of an adaptive render. */
typedef struct tb__aa_ctx {
    tb_gpu_renderer *r;
    tb__paths *P;
    const tb_camera *cam;
    const tb_aa_options *aa;
    double *xy;         /* P's film positions (cap) */
    tb_rng *rng, *rng0; /* P's streams (cap) */
    size_t cap;         /* samples per wavefront call */
    int nth, nch, spp, max_spp;
    float lum[TB_FILM_MAX_CHANNELS];
} tb__aa_ctx;

/* Evaluates the samples reqs[0..n) with the wavefront, cap at a time. */
static tb_status tb__aa_eval(tb__aa_ctx *c, const tb__aa_req *reqs, size_t n)
{
    tb__paths *P = c->P;
    for (size_t b = 0; b < n; b += c->cap) {
        size_t m = n - b < c->cap ? n - b : c->cap;
        /* camera rays as tb_rt_sample makes them (the lens numbers first) */
#pragma omp parallel for schedule(static) num_threads(c->nth)
        for (size_t q = 0; q < m; q++) {
            const tb__aa_req *rq = &reqs[b + q];
            c->xy[2 * q] = rq->x;
            c->xy[2 * q + 1] = rq->y;
            tb_aa_sample_rng(c->aa, rq->px, rq->py, rq->j, &c->rng[q]);
            tb__gr_push_camera(P, q, c->cam, rq->x, rq->y, &c->rng[q], &c->rng0[q]);
        }
        P->n = m;
        memset(P->L, 0, m * (size_t)c->nch * sizeof *P->L);
        tb_status st = tb__gr_wavefront(c->r, P);
        if (st)
            return st;
#pragma omp parallel for schedule(static) num_threads(c->nth)
        for (size_t q = 0; q < m; q++)
            memcpy(reqs[b + q].dst, P->L + q * (size_t)c->nch, sizeof(float) * (size_t)c->nch);
    }
    return TB_OK;
}

/* Makes room for `need` samples of pixel i of tile a. */
static bool tb__aa_reserve(tb__aa_tile *a, size_t i, int need, int max_spp, int nch)
{
    if (need <= a->cap[i])
        return true;
    int nc = a->cap[i] * 2 > need ? a->cap[i] * 2 : need;
    if (nc > max_spp)
        nc = max_spp;
    float *v = realloc(a->vals[i], (size_t)nc * (size_t)nch * sizeof *v);
    if (!v)
        return false;
    a->vals[i] = v;
    float *xy = realloc(a->xy[i], (size_t)nc * 2 * sizeof *xy);
    if (!xy)
        return false;
    a->xy[i] = xy;
    a->cap[i] = nc;
    return true;
}

/* Renders tiles tl[0..nt) (created, in index order) adaptively and splats
 * them; stats into *as. */
static tb_status tb__aa_batch(tb__aa_ctx *c, const tb_film *film, tb__aa_tile *tl, int nt, tb_aa_stats *as)
{
    const int spp = c->spp, nch = c->nch, W = tb_film_width(film), H = tb_film_height(film);
    const tb_aa_options *aa = c->aa;
    size_t nreq = 0;
    for (int k = 0; k < nt; k++) {
        tb__aa_tile *a = &tl[k];
        a->r = tb_film_tile_pixels(a->tile);
        a->g = (tb_tile_rect){a->r.x0 > 0 ? a->r.x0 - 1 : 0, a->r.y0 > 0 ? a->r.y0 - 1 : 0,
                              a->r.x1 < W ? a->r.x1 + 1 : a->r.x1, a->r.y1 < H ? a->r.y1 + 1 : a->r.y1};
        size_t ng = (size_t)(a->g.x1 - a->g.x0) * (size_t)(a->g.y1 - a->g.y0);
        size_t np = (size_t)(a->r.x1 - a->r.x0) * (size_t)(a->r.y1 - a->r.y0);
        a->ring_vals = malloc(ng * (size_t)spp * (size_t)nch * sizeof *a->ring_vals);
        a->ring_flag = malloc(ng);
        a->ps = malloc(np * sizeof *a->ps);
        a->n = calloc(np, sizeof *a->n);
        a->cap = calloc(np, sizeof *a->cap);
        a->rounds = calloc(np, sizeof *a->rounds);
        a->more = calloc(np, 1);
        a->vals = calloc(np, sizeof *a->vals);
        a->xy = calloc(np, sizeof *a->xy);
        if (!a->ring_vals || !a->ring_flag || !a->ps || !a->n || !a->cap || !a->rounds || !a->more || !a->vals ||
            !a->xy)
            return tb_error(TB_ERR_NOMEM, "GPU render: out of memory for adaptive antialiasing");
        nreq += ng * (size_t)spp;
    }
    tb__aa_req *reqs = malloc((nreq ? nreq : 1) * sizeof *reqs);
    float *pxy = malloc((size_t)spp * 2 * sizeof *pxy);
    tb_status st = reqs && pxy ? TB_OK : tb_error(TB_ERR_NOMEM, "GPU render: out of memory for adaptive antialiasing");
    /* the first round of every pixel of each tile and its ring */
    size_t q = 0;
    for (int k = 0; k < nt && !st; k++) {
        tb__aa_tile *a = &tl[k];
        int gw = a->g.x1 - a->g.x0, rw = a->r.x1 - a->r.x0;
        for (int py = a->g.y0; py < a->g.y1 && !st; py++)
            for (int px = a->g.x0; px < a->g.x1; px++) {
                size_t gi = (size_t)(py - a->g.y0) * (size_t)gw + (size_t)(px - a->g.x0);
                bool own = px >= a->r.x0 && px < a->r.x1 && py >= a->r.y0 && py < a->r.y1;
                tb_pixel_sampler tmp, *ps = &tmp;
                float *xy = pxy;
                if (own) {
                    size_t i = (size_t)(py - a->r.y0) * (size_t)rw + (size_t)(px - a->r.x0);
                    if (!tb__aa_reserve(a, i, spp, c->max_spp, nch)) {
                        st = tb_error(TB_ERR_NOMEM, "GPU render: out of memory for adaptive antialiasing");
                        break;
                    }
                    ps = &a->ps[i];
                    xy = a->xy[i];
                } else {
                    as->ring_samples += (uint64_t)spp;
                }
                tb_pixel_sampler_init(ps, aa, px, py);
                tb_pixel_sampler_round(ps, xy);
                for (int j = 0; j < spp; j++)
                    reqs[q++] = (tb__aa_req){(double)px + (double)xy[2 * j], (double)py + (double)xy[2 * j + 1],
                                             px, py, (uint32_t)j,
                                             a->ring_vals + (gi * (size_t)spp + (size_t)j) * (size_t)nch};
            }
    }
    if (!st)
        st = tb__aa_eval(c, reqs, q);
    /* the criterion on the first rounds; a pixel refines if its own first
     * round or a neighbour's fails it */
    if (!st) {
#pragma omp parallel for schedule(dynamic, 1) num_threads(c->nth)
        for (int k = 0; k < nt; k++) {
            tb__aa_tile *a = &tl[k];
            int gw = a->g.x1 - a->g.x0, rw = a->r.x1 - a->r.x0;
            size_t ng = (size_t)gw * (size_t)(a->g.y1 - a->g.y0);
            for (size_t gi = 0; gi < ng; gi++)
                a->ring_flag[gi] =
                    tb_aa_needs_more(aa, nch, c->lum, a->ring_vals + gi * (size_t)spp * (size_t)nch, spp);
            for (int py = a->r.y0; py < a->r.y1; py++)
                for (int px = a->r.x0; px < a->r.x1; px++) {
                    size_t i = (size_t)(py - a->r.y0) * (size_t)rw + (size_t)(px - a->r.x0);
                    size_t gi = (size_t)(py - a->g.y0) * (size_t)gw + (size_t)(px - a->g.x0);
                    memcpy(a->vals[i], a->ring_vals + gi * (size_t)spp * (size_t)nch,
                           sizeof(float) * (size_t)spp * (size_t)nch);
                    a->n[i] = spp;
                    a->rounds[i] = 1;
                    bool more = false;
                    for (int dy = -1; dy <= 1 && !more; dy++)
                        for (int dx = -1; dx <= 1 && !more; dx++) {
                            int qx = px + dx, qy = py + dy;
                            if (qx >= a->g.x0 && qx < a->g.x1 && qy >= a->g.y0 && qy < a->g.y1)
                                more = a->ring_flag[(size_t)(qy - a->g.y0) * (size_t)gw + (size_t)(qx - a->g.x0)];
                        }
                    a->more[i] = more && spp + spp <= c->max_spp;
                }
        }
    }
    /* further rounds for the pixels that need them, until none does */
    while (!st) {
        q = 0;
        for (int k = 0; k < nt && !st; k++) {
            tb__aa_tile *a = &tl[k];
            int rw = a->r.x1 - a->r.x0;
            size_t np = (size_t)rw * (size_t)(a->r.y1 - a->r.y0);
            for (size_t i = 0; i < np; i++) {
                if (!a->more[i])
                    continue;
                int n = a->n[i], px = a->r.x0 + (int)(i % (size_t)rw), py = a->r.y0 + (int)(i / (size_t)rw);
                if (!tb__aa_reserve(a, i, n + spp, c->max_spp, nch)) {
                    st = tb_error(TB_ERR_NOMEM, "GPU render: out of memory for adaptive antialiasing");
                    break;
                }
                tb_pixel_sampler_round(&a->ps[i], a->xy[i] + 2 * (size_t)n);
                for (int j = n; j < n + spp; j++)
                    reqs[q++] = (tb__aa_req){(double)px + (double)a->xy[i][2 * j],
                                             (double)py + (double)a->xy[i][2 * j + 1], px, py, (uint32_t)j,
                                             a->vals[i] + (size_t)j * (size_t)nch};
            }
        }
        if (st || q == 0)
            break;
        if ((st = tb__aa_eval(c, reqs, q)))
            break;
#pragma omp parallel for schedule(dynamic, 1) num_threads(c->nth)
        for (int k = 0; k < nt; k++) {
            tb__aa_tile *a = &tl[k];
            size_t np = (size_t)(a->r.x1 - a->r.x0) * (size_t)(a->r.y1 - a->r.y0);
            for (size_t i = 0; i < np; i++) {
                if (!a->more[i])
                    continue;
                int n = a->n[i] += spp;
                a->rounds[i]++;
                a->more[i] = tb_aa_needs_more(aa, nch, c->lum, a->vals[i], n) && n + spp <= c->max_spp;
            }
        }
    }
    free(reqs), free(pxy);
    if (st)
        return st;
    /* splat in the CPU path's order: pixels in scanline order, each with
     * weight 1 / (its sample count) */
    uint64_t samples = 0, pixels = 0, refined = 0;
    int max_used = 0;
#pragma omp parallel for schedule(dynamic, 1) num_threads(c->nth) reduction(+ : samples, pixels, refined) \
    reduction(max : max_used)
    for (int k = 0; k < nt; k++) {
        tb__aa_tile *a = &tl[k];
        int rw = a->r.x1 - a->r.x0;
        size_t np = (size_t)rw * (size_t)(a->r.y1 - a->r.y0);
        for (size_t i = 0; i < np; i++) {
            int n = a->n[i], px = a->r.x0 + (int)(i % (size_t)rw), py = a->r.y0 + (int)(i / (size_t)rw);
            double wt = 1.0 / (double)n;
            for (int j = 0; j < n; j++)
                tb_film_tile_add(a->tile, (double)px + (double)a->xy[i][2 * j],
                                 (double)py + (double)a->xy[i][2 * j + 1], a->vals[i] + (size_t)j * (size_t)nch, wt);
            tb_film_tile_record_samples(a->tile, px, py, (uint32_t)n);
            samples += (uint64_t)n;
            pixels++;
            refined += a->rounds[i] > 1;
            max_used = n > max_used ? n : max_used;
        }
    }
    as->samples += samples;
    as->pixels += pixels;
    as->pixels_refined += refined;
    if (max_used > as->max_spp_used)
        as->max_spp_used = max_used;
    return TB_OK;
}

tb_status tb__gr_adaptive_pass(tb__gr_batch *b, tb__render_run *run, tb_film *film, const tb_aa_options *aa,
                               tb_aa_stats *as)
{
    tb_status err = tb_film_begin_pass(film);
    if (err)
        return err;
    const int ntiles = tb_film_tile_count(film), spp = aa->spp;
    tb__aa_ctx ac = {.r = b->r, .P = &b->P, .cam = &b->r->scene->camera, .aa = aa, .xy = b->xy, .rng = b->rng,
                     .rng0 = b->rng0, .cap = b->cap, .nth = b->nth, .nch = b->r->nch, .spp = spp,
                     .max_spp = tb_aa_max_spp(aa)};
    tb_aa_luminance_weights(ac.nch, ac.lum);
    tb__aa_tile *tl = calloc((size_t)(ntiles > 0 ? ntiles : 1), sizeof *tl);
    if (!tl)
        return tb_error(TB_ERR_NOMEM, "GPU render: out of memory");
    /* batches of whole tiles whose first rounds (with their rings) fit one
     * wavefront call (at least one tile) */
    int t = 0;
    while (t < ntiles && !err) {
        if (tb__render_should_stop(run)) {
            tb__gr_skip_tiles(film, t, as);
            break;
        }
        int nt = 0;
        size_t first = 0;
        while (t + nt < ntiles) {
            tb_tile_rect rc = tb_film_tile_rect(film, t + nt);
            size_t ring = (size_t)(rc.x1 - rc.x0 + 2) * (size_t)(rc.y1 - rc.y0 + 2) * (size_t)spp;
            if (nt > 0 && first + ring > b->cap)
                break;
            if (!(tl[nt].tile = tb_film_tile_create(film, t + nt))) {
                err = TB_ERR_NOMEM;
                break;
            }
            first += ring;
            nt++;
        }
        if (!err)
            err = tb__aa_batch(&ac, film, tl, nt, as);
        for (int k = 0; k < nt; k++) {
            if (!err) {
                tb_tile_rect rc = tl[k].r;
                if (run->progress)
                    tb_progress_add(run->progress, (int64_t)(rc.x1 - rc.x0) * (rc.y1 - rc.y0));
                err = tb_film_tile_submit(film, tl[k].tile);
                tl[k].tile = NULL;
            }
            tb__aa_tile_free(&tl[k]);
        }
        t += nt;
    }
    free(tl);
    return err;
}
