/* The render driver (render.h, render_internal.h) and the CPU ray tracer
 * on it. */
#include "host/render/render.h"
#include "host/render/render_internal.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "util/base/progress.h"
#include "util/color/bands.h"

tb_render_options tb_render_defaults(void)
{
    tb_render_options o;
    memset(&o, 0, sizeof o);
    o.aa = tb_aa_defaults();
    tb_filter_init(&o.filter, TB_FILTER_BOX, 0.0, 0.0);
    o.passes = 1;
    return o;
}

static int64_t tb__now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

tb_image *tb_render_resolve(const tb_scene *s, const tb_film *film)
{
    tb_image *raw = tb_film_resolve(film, NULL);
    if (!raw || !s->spectral)
        return raw;
    tb_image *img = tb_image_create(raw->width, raw->height, 3, NULL);
    if (!img) {
        tb_image_free(raw);
        return NULL;
    }
    size_t npix = (size_t)raw->width * (size_t)raw->height;
    double v[TB_CHANNELS_MAX];
    for (size_t i = 0; i < npix; i++) {
        const float *src = raw->pixels + i * (size_t)raw->channels;
        for (int c = 0; c < raw->channels; c++)
            v[c] = src[c];
        double rgb[3];
        tb_bands_to_linear_srgb(&s->bands, v, 1.0, rgb);
        for (int c = 0; c < 3; c++)
            img->pixels[i * 3 + (size_t)c] = (float)rgb[c];
    }
    tb_image_free(raw);
    return img;
}

void tb_render_sample_counts(const tb_film *film, uint32_t *counts)
{
    int w = tb_film_width(film), h = tb_film_height(film);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            counts[(size_t)y * (size_t)w + (size_t)x] = tb_film_sample_count(film, x, y);
}

bool tb__render_should_stop(tb__render_run *run)
{
    const atomic_int *cancel = run->o->cancel;
    if ((run->deadline_ns > 0 && tb__now_ns() > run->deadline_ns) || (cancel && atomic_load(cancel)))
        atomic_store(&run->stop, 1);
    return atomic_load(&run->stop) != 0;
}

double tb__render_seconds(const tb__render_run *run) { return (double)(tb__now_ns() - run->t0_ns) * 1e-9; }

tb_status tb__render_check(const tb_render_options *o)
{
    if (o->passes < 1)
        return tb_error(TB_ERR_ARG, "render: passes must be at least 1");
    return tb_aa_check(&o->aa);
}

tb_status tb__render_drive(const tb_scene *s, const tb_render_options *o, const tb__render_engine *e,
                           tb_image **out, tb_render_stats *stats)
{
    *out = NULL;
    tb_render_stats st;
    memset(&st, 0, sizeof st);
    tb_film_desc fd = {.width = s->camera.width, .height = s->camera.height, .channels = s->nchannels,
                       .filter = &o->filter};
    tb_film *film = tb_film_create(&fd);
    if (!film)
        return TB_ERR_NOMEM;
    tb_status err = e->start ? e->start(e->ctx, film) : TB_OK;
    tb__render_run run = {.o = o};
    atomic_init(&run.stop, o->cancel ? atomic_load(o->cancel) : 0);
    run.t0_ns = tb__now_ns();
    if (o->time_budget > 0.0)
        run.deadline_ns = run.t0_ns + (int64_t)(o->time_budget * 1e9);
    tb_progress prog;
    if (o->progress && tb_progress_start(&prog, "render", (int64_t)fd.width * fd.height * o->passes, NULL, 0) == TB_OK)
        run.progress = &prog;
    const tb_tile_exchange *ex = o->exchange;
    bool root = !ex || ex->rank == 0;
    /* a checkpoint's passes: rank 0 restores the film, every rank starts
     * after them */
    if (!err && root && o->persist && o->persist->restore)
        err = o->persist->restore(o->persist->ctx, film, &st);
    int first = st.passes_done;
    if (ex)
        first = ex->agree(ex->ctx, err ? -1 : first);
    if (first < 0 && !err)
        err = tb_error(TB_ERR_IO, "render: rank 0 could not restore the checkpoint");
    if (!err && first > o->passes)
        err = tb_error(TB_ERR_ARG, "render: the checkpoint has %d passes, more than the %d asked for", first,
                       o->passes);
    if (run.progress && first > 0)
        tb_progress_add(run.progress, (int64_t)fd.width * fd.height * first);
    tb_aa_options aa = o->aa;
    for (int pass = first; pass < o->passes && !err; pass++) {
        aa.pass = o->aa.pass + (uint32_t)pass;
        tb_aa_stats as;
        memset(&as, 0, sizeof as);
        run.pass_index = pass;
        err = e->pass(e->ctx, &run, film, &aa, &as);
        if (err)
            break;
        st.aa.samples += as.samples;
        st.aa.ring_samples += as.ring_samples;
        st.aa.pixels += as.pixels;
        st.aa.pixels_refined += as.pixels_refined;
        st.aa.tiles_skipped += as.tiles_skipped;
        if (as.max_spp_used > st.aa.max_spp_used)
            st.aa.max_spp_used = as.max_spp_used;
        /* every process stops where rank 0 stops (its clock, its cancel flag) */
        int stop = as.tiles_skipped > 0 || atomic_load(&run.stop);
        if (ex)
            stop = ex->agree(ex->ctx, stop);
        if (stop) {
            st.interrupted = as.tiles_skipped > 0 || pass + 1 < o->passes;
            if (as.tiles_skipped == 0) {
                st.passes_done++;
                if (root && o->persist && o->persist->save)
                    err = o->persist->save(o->persist->ctx, film, &st, true);
            }
            break;
        }
        st.passes_done++;
        int quit = 0;
        if (root && o->persist && o->persist->save)
            err = o->persist->save(o->persist->ctx, film, &st, pass + 1 == o->passes);
        if (root && !err && o->on_pass)
            quit = o->on_pass(o->on_pass_ctx, pass, aa.spp * (pass + 1), tb__render_seconds(&run), film);
        if (ex)
            quit = ex->agree(ex->ctx, quit || err);
        if (quit)
            break;
    }
    st.seconds = tb__render_seconds(&run);
    if (run.progress)
        tb_progress_finish(run.progress);
    if (!err && root) {
        /* the other processes' films hold only what they did not send:
         * rank 0's is the image */
        *out = tb_render_resolve(s, film);
        if (!*out)
            err = TB_ERR_NOMEM;
    }
    if (!err && o->sample_counts)
        tb_render_sample_counts(film, o->sample_counts);
    tb_film_free(film);
    if (stats)
        *stats = st;
    return err;
}

/* A renderer's per-sample function with the run whose stop flag it
 * raises (tb_aa_render checks it at tile boundaries). */
typedef struct tb__render_ctx {
    tb_aa_sample_fn sample;
    void *ctx;
    tb__render_run *run;
} tb__render_ctx;

static void tb__render_sample(void *ctx, double x, double y, tb_rng *rng, float *out)
{
    tb__render_ctx *c = ctx;
    tb__render_should_stop(c->run);
    c->sample(c->ctx, x, y, rng, out);
}

/* One pass of a CPU renderer: tb_aa_render's tiles (OpenMP). ctx is the
 * renderer's tb__render_ctx with `run` still unset. */
static tb_status tb__render_cpu_pass(void *ctx, tb__render_run *run, tb_film *film, const tb_aa_options *aa,
                                     tb_aa_stats *as)
{
    tb__render_ctx c = *(const tb__render_ctx *)ctx;
    c.run = run;
    tb_aa_render_desc desc = {.sample = tb__render_sample, .ctx = &c, .threads = run->o->threads,
                              .progress = run->progress, .cancel = &run->stop, .exchange = run->o->exchange,
                              .pass_index = run->pass_index};
    return tb_aa_render(film, aa, &desc, as);
}

tb_status tb_render(const tb_scene *s, tb_aa_sample_fn sample, void *ctx, const tb_render_options *o,
                    tb_image **out, tb_render_stats *stats)
{
    *out = NULL;
    if (!s || !sample)
        return tb_error(TB_ERR_ARG, "render: no scene or no sample function");
    tb_status err = tb__render_check(o);
    if (err)
        return err;
    tb__render_ctx c = {.sample = sample, .ctx = ctx};
    tb__render_engine e = {.ctx = &c, .pass = tb__render_cpu_pass};
    return tb__render_drive(s, o, &e, out, stats);
}

tb_status tb_render_raytrace(const tb_scene *s, const tb_render_options *o, tb_image **out, tb_render_stats *stats)
{
    *out = NULL;
    tb_status err = tb__render_check(o);
    if (err)
        return err;
    tb_raytracer rt;
    if ((err = tb_rt_init(&rt, s, &o->rt)))
        return err;
    err = tb_render(s, tb_rt_sample, &rt, o, out, stats);
    tb_rt_release(&rt);
    return err;
}
