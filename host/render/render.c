/* The render driver (render.h). */
#include "host/render/render.h"

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

/* The per-sample context: the tracer plus the time budget. */
typedef struct tb__render_ctx {
    const tb_raytracer *rt;
    int64_t deadline_ns;       /* 0: none */
    const atomic_int *external; /* the caller's cancel flag, or NULL */
    atomic_int stop;            /* what the tile loop checks: set on a cancel or when the deadline passes */
} tb__render_ctx;

static void tb__render_sample(void *ctx, double x, double y, tb_rng *rng, float *out)
{
    tb__render_ctx *c = ctx;
    if ((c->deadline_ns > 0 && tb__now_ns() > c->deadline_ns) || (c->external && atomic_load(c->external)))
        atomic_store(&c->stop, 1);
    tb_rt_sample((void *)c->rt, x, y, rng, out);
}

tb_status tb_render_raytrace(const tb_scene *s, const tb_render_options *o, tb_image **out, tb_render_stats *stats)
{
    *out = NULL;
    tb_render_stats st;
    memset(&st, 0, sizeof st);
    if (o->passes < 1)
        return tb_error(TB_ERR_ARG, "render: passes must be at least 1");
    tb_status err = tb_aa_check(&o->aa);
    if (err)
        return err;
    tb_raytracer rt;
    err = tb_rt_init(&rt, s, &o->rt);
    if (err)
        return err;
    tb_film_desc fd = {.width = s->camera.width, .height = s->camera.height, .channels = s->nchannels,
                       .filter = &o->filter};
    tb_film *film = tb_film_create(&fd);
    if (!film) {
        tb_rt_release(&rt);
        return TB_ERR_NOMEM;
    }
    tb__render_ctx ctx = {.rt = &rt, .external = o->cancel};
    atomic_init(&ctx.stop, o->cancel ? atomic_load(o->cancel) : 0);
    int64_t t0 = tb__now_ns();
    if (o->time_budget > 0.0)
        ctx.deadline_ns = t0 + (int64_t)(o->time_budget * 1e9);
    tb_progress prog;
    bool use_prog = o->progress &&
                    tb_progress_start(&prog, "render", (int64_t)fd.width * fd.height * o->passes, NULL, 0) == TB_OK;
    tb_aa_render_desc desc = {.sample = tb__render_sample, .ctx = &ctx, .threads = o->threads,
                              .progress = use_prog ? &prog : NULL, .cancel = &ctx.stop};
    tb_aa_options aa = o->aa;
    for (int pass = 0; pass < o->passes && !err; pass++) {
        aa.pass = o->aa.pass + (uint32_t)pass;
        tb_aa_stats as;
        err = tb_aa_render(film, &aa, &desc, &as);
        if (err)
            break;
        st.aa.samples += as.samples;
        st.aa.ring_samples += as.ring_samples;
        st.aa.pixels += as.pixels;
        st.aa.pixels_refined += as.pixels_refined;
        st.aa.tiles_skipped += as.tiles_skipped;
        if (as.max_spp_used > st.aa.max_spp_used)
            st.aa.max_spp_used = as.max_spp_used;
        if (as.tiles_skipped > 0 || atomic_load(&ctx.stop)) {
            st.interrupted = as.tiles_skipped > 0 || pass + 1 < o->passes;
            if (as.tiles_skipped == 0)
                st.passes_done++;
            break;
        }
        st.passes_done++;
        if (o->on_pass &&
            o->on_pass(o->on_pass_ctx, pass, aa.spp * (pass + 1), (double)(tb__now_ns() - t0) * 1e-9, film))
            break;
    }
    st.seconds = (double)(tb__now_ns() - t0) * 1e-9;
    if (use_prog)
        tb_progress_finish(&prog);
    if (!err) {
        *out = tb_render_resolve(s, film);
        if (!*out)
            err = TB_ERR_NOMEM;
    }
    if (!err && o->sample_counts)
        tb_render_sample_counts(film, o->sample_counts);
    tb_film_free(film);
    tb_rt_release(&rt);
    if (stats)
        *stats = st;
    return err;
}
