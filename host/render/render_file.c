/* The ray-tracer workflow in one call (render_file.h): scene -> render ->
 * image, sample map, stats, with the report rows and the provenance
 * `testbed render` has always written. */
#include "host/render/render_file.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <omp.h>

#include "host/render/accel.h"
#include "util/image/compare.h"
#include "util/stats/provenance.h"
#include "util/stats/stats.h"

tb_render_file_options tb_render_file_defaults(void)
{
    return (tb_render_file_options){
        .render = tb_render_defaults(),
        .scene = {.accel = TB_ACCEL_BVH},
        .exposure = NAN,
    };
}

/* The report's state: the open CSV, the reference, and the first failure. */
typedef struct tb__rf_report {
    FILE *fp;
    const tb_image *reference;
    const tb_scene *scene;
    tb_status failed;   /* TB_OK until a pass could not be compared */
    char why[512];      /* that pass's error message */
} tb__rf_report;

/* A tb_render_pass_fn: resolves the film so far and writes its relMSE row. */
static int tb__rf_report_pass(void *ctx, int pass, int spp_total, double seconds, const tb_film *film)
{
    tb__rf_report *r = ctx;
    (void)pass;
    tb_image *img = tb_render_resolve(r->scene, film);
    tb_compare_result res;
    tb_status st = img ? tb_image_compare(img, r->reference, NULL, &res) : TB_ERR_NOMEM;
    tb_image_free(img);
    if (st) {
        snprintf(r->why, sizeof r->why, "%s", tb_last_error());
        r->failed = st;
        return 1;
    }
    fprintf(r->fp, "%.6f,%d,%.9g\n", seconds, spp_total, res.all.relmse);
    fflush(r->fp);
    return 0;
}

/* Checks that need no scene: what the command reports as usage errors. */
static tb_status tb__rf_check(const tb_render_file_options *o)
{
    if (!o->image_path)
        return tb_error(TB_ERR_ARG, "no output given (-o OUT)");
    if (tb_image_format_from_path(o->image_path) == TB_IMAGE_UNKNOWN)
        return tb_error(TB_ERR_ARG, "unknown image format of '%s' (.png, .exr, .pfm, .rle)", o->image_path);
    if (o->sample_map_path && tb_image_format_from_path(o->sample_map_path) != TB_IMAGE_PFM)
        return tb_error(TB_ERR_ARG, "--sample-map writes a .pfm file, not '%s'", o->sample_map_path);
    if (!o->report_path != !o->reference_path)
        return tb_error(TB_ERR_ARG, "--report and --reference go together");
    if (o->method && (!o->method->init || !o->method->name))
        return tb_error(TB_ERR_ARG, "render method without a name or an init function");
    if (o->backend && o->render.exchange && o->render.exchange->ranks > 1)
        return tb_error(TB_ERR_ARG, "the Vulkan backend renders in one process, not over %d ranks",
                        o->render.exchange->ranks);
    return TB_OK;
}

/* Everything tb_render_file holds, freed in one place. */
typedef struct tb__rf_run {
    tb_scene *scene;
    tb_image *img, *ref, *map;
    uint32_t *counts;
    tb__rf_report rep;
    bool has_prov;
    tb_provenance prov;
    const tb_render_method *method; /* NULL: the ray tracer */
    bool method_ready;              /* method->init succeeded: release owed */
    void *method_ctx;
    tb_aa_sample_fn method_sample;
    char method_desc[384];          /* the method's options for the provenance */
} tb__rf_run;

static void tb__rf_run_free(tb__rf_run *r)
{
    if (r->method_ready && r->method->release)
        r->method->release(r->method->user, r->method_ctx);
    if (r->has_prov)
        tb_provenance_free(&r->prov);
    if (r->rep.fp)
        fclose(r->rep.fp);
    tb_image_free(r->ref);
    tb_image_free(r->img);
    tb_image_free(r->map);
    free(r->counts);
    tb_scene_free(r->scene);
}

/* Reads the reference and starts the report file with its header. */
static tb_status tb__rf_report_open(tb__rf_run *r, const tb_render_file_options *o)
{
    tb_status st = tb_image_read(o->reference_path, NULL, &r->ref);
    if (st)
        return st;
    r->rep.fp = fopen(o->report_path, "w");
    if (!r->rep.fp)
        return tb_error(TB_ERR_IO, "cannot write '%s'", o->report_path);
    fprintf(r->rep.fp, "seconds,spp,relmse\n");
    r->rep.reference = r->ref;
    r->rep.scene = r->scene;
    return TB_OK;
}

/* The backend if there is one and it renders (the command's backend knows
 * the method: with a method, the backend renders that method); else the
 * method if there is one, else the CPU ray tracer. A method is initialised
 * first in any case: its options go into the provenance. */
static tb_status tb__rf_render(tb__rf_run *r, const tb_render_file_options *o, const tb_render_options *ro,
                               tb_render_stats *rs, bool *on_backend)
{
    *on_backend = false;
    if (r->method) {
        tb_status st = r->method->init(r->method->user, r->scene, ro, &r->method_sample, &r->method_ctx,
                                       r->method_desc, sizeof r->method_desc);
        if (st)
            return st;
        r->method_ready = true;
    }
    if (o->backend) {
        tb_status st = o->backend(o->backend_user, r->scene, ro, &r->img, rs);
        if (st) {
            tb_image_free(r->img);
            r->img = NULL;
            return st;
        }
        *on_backend = r->img != NULL;
    }
    if (*on_backend)
        return TB_OK;
    if (r->method)
        return tb_render(r->scene, r->method_sample, r->method_ctx, ro, &r->img, rs);
    return tb_render_raytrace(r->scene, ro, &r->img, rs);
}

/* The provenance of the image and the stats. */
static tb_status tb__rf_provenance(tb__rf_run *r, const char *scene_path, const tb_render_file_options *o,
                                   const tb_render_options *ro, int nthreads, bool on_backend)
{
    char *empty[] = {"", NULL};
    tb_status st = o->argv ? tb_provenance_init(&r->prov, o->argc, o->argv) : tb_provenance_init(&r->prov, 1, empty);
    if (st)
        return st;
    r->has_prov = true;
    char popts[1024];
    if (r->method)
        snprintf(popts, sizeof popts, "method=%s spp=%d passes=%d adaptive=%d filter=%s:%g accel=%s %s threads=%d colour=%s backend=%s",
                 r->method->name, ro->aa.spp, ro->passes, (int)ro->aa.adaptive, tb_filter_kind_name(ro->filter.kind),
                 ro->filter.radius, tb_accel_kind_name(o->scene.accel), r->method_desc, nthreads,
                 r->scene->spectral ? "spectral" : "rgb",
                 on_backend ? (o->backend_name ? o->backend_name : "backend") : "cpu");
    else
        snprintf(popts, sizeof popts,
             "method=raytrace spp=%d passes=%d adaptive=%d filter=%s:%g accel=%s max_depth=%d "
             "light_samples=%d glossy_samples=%d threads=%d colour=%s backend=%s",
             ro->aa.spp, ro->passes, (int)ro->aa.adaptive, tb_filter_kind_name(ro->filter.kind), ro->filter.radius,
             tb_accel_kind_name(o->scene.accel),
             ro->rt.max_depth == 0 ? TB_RT_DEFAULT_MAX_DEPTH : (ro->rt.max_depth < 0 ? 0 : ro->rt.max_depth),
             ro->rt.light_samples ? ro->rt.light_samples : TB_RT_DEFAULT_LIGHT_SAMPLES,
             ro->rt.glossy_samples ? ro->rt.glossy_samples : TB_RT_DEFAULT_GLOSSY_SAMPLES, nthreads,
             r->scene->spectral ? "spectral" : "rgb",
             on_backend ? (o->backend_name ? o->backend_name : "backend") : "cpu");
    if (!r->method && ro->rt.min_weight > 0.0) {
        size_t n = strlen(popts);
        snprintf(popts + n, sizeof popts - n, " adc_bailout=%.17g", ro->rt.min_weight);
    }
    if (ro->exchange && ro->exchange->ranks > 1) {
        size_t n = strlen(popts);
        snprintf(popts + n, sizeof popts - n, " ranks=%d", ro->exchange->ranks);
    }
    tb_provenance_set_seed(&r->prov, ro->aa.seed);
    if (strcmp(scene_path, "-") != 0 && (st = tb_provenance_hash_file(&r->prov, scene_path)))
        return st;
    if ((st = tb_provenance_set_options(&r->prov, popts)))
        return st;
    return tb_provenance_to_attrs(&r->prov, r->img);
}

/* The stats JSON: the render's values, then the backend's. */
static tb_status tb__rf_stats(const tb__rf_run *r, const tb_render_file_options *o, const tb_render_options *ro,
                              const tb_render_stats *rs, bool on_backend)
{
    struct {
        const char *k;
        double v;
        bool on;
    } kv[] = {{"seconds", rs->seconds, true},
              {"samples", (double)rs->aa.samples, true},
              {"pixels_refined", (double)rs->aa.pixels_refined, ro->aa.adaptive},
              {"ring_samples", (double)rs->aa.ring_samples, ro->aa.adaptive},
              {"max_spp_used", (double)rs->aa.max_spp_used, ro->aa.adaptive},
              {"passes", (double)rs->passes_done, true},
              {"interrupted", rs->interrupted ? 1.0 : 0.0, true},
              {"samples_per_second", rs->seconds > 0 ? (double)rs->aa.samples / rs->seconds : 0.0, true}};
    tb_status st = TB_OK;
    for (size_t k = 0; k < sizeof kv / sizeof kv[0] && !st; k++)
        if (kv[k].on)
            st = tb_stats_set_value(kv[k].k, kv[k].v);
    if (!st && on_backend && o->backend_stats)
        st = o->backend_stats(o->backend_user);
    if (!st && r->method_ready && r->method->stats)
        st = r->method->stats(r->method->user, r->method_ctx);
    return st ? st : tb_stats_write_json_file(o->stats_path, &r->prov);
}

/* The sample map: the counts as a grey PFM. */
static tb_status tb__rf_write_map(const tb__rf_run *r, const char *path)
{
    for (size_t k = 0; k < (size_t)r->map->width * (size_t)r->map->height; k++)
        r->map->pixels[k] = (float)r->counts[k];
    return tb_image_write(path, r->map, NULL);
}

tb_status tb_render_file(const char *scene_path, const tb_render_file_options *opt, tb_render_file_result *out)
{
    if (!scene_path || !opt)
        return tb_error(TB_ERR_ARG, "tb_render_file: no scene or no options");
    tb_status st = tb__rf_check(opt);
    if (st)
        return st;
    tb__rf_run r = {.method = opt->method};
    tb_render_options ro = opt->render;
    tb_scene_options so = opt->scene;
    if (so.threads == 0)
        so.threads = ro.threads;
    const tb_tile_exchange *ex = ro.exchange;
    bool root = !ex || ex->rank == 0;
    st = tb_scene_load(scene_path, &so, &r.scene);
    if (!st && root && opt->report_path && !(st = tb__rf_report_open(&r, opt))) {
        ro.on_pass = tb__rf_report_pass;
        ro.on_pass_ctx = &r.rep;
    }
    /* every process reads the scene itself; one that cannot stops them all
     * with its own file:line:col message */
    if (ex)
        st = ex->agree_status(ex->ctx, st);
    if (st)
        goto done;
    if (!root) {
        /* rank 0 reports, writes and counts samples; the others only render */
        ro.sample_counts = NULL;
        ro.progress = false;
    }

    /* The render, between the caller's hooks. */
    if (opt->on_render)
        opt->on_render(opt->on_render_user, true);
    tb_render_stats rs;
    bool on_backend = false;
    if (root && opt->sample_map_path) {
        r.map = tb_image_create(r.scene->camera.width, r.scene->camera.height, 1, NULL);
        r.counts = r.map ? calloc((size_t)r.map->width * (size_t)r.map->height, sizeof *r.counts) : NULL;
        if (!r.counts)
            st = tb_error(TB_ERR_NOMEM, "out of memory for --sample-map");
        ro.sample_counts = r.counts;
    }
    ro.rt.spp = ro.aa.spp; /* scales the texture footprints (docs/raytrace.md) */
    if (!st)
        st = tb__rf_render(&r, opt, &ro, &rs, &on_backend);
    if (opt->on_render)
        opt->on_render(opt->on_render_user, false);
    /* every process's share of the work in the stats (collective) */
    if (ex && ex->report) {
        tb_status rst = ex->report(ex->ctx);
        st = st ? st : rst;
    }
    if (st)
        goto done;
    if (!root) {
        if (out)
            *out = (tb_render_file_result){.stats = rs, .width = r.scene->camera.width,
                                           .height = r.scene->camera.height,
                                           .threads = ro.threads > 0 ? ro.threads : omp_get_max_threads(),
                                           .spectral = r.scene->spectral};
        goto done;
    }
    if (r.rep.failed) {
        st = tb_error(r.rep.failed, "report: %s", r.rep.why);
        goto done;
    }

    /* Provenance in the image and the stats file, then the image and the
     * sample map (the image is removed if the map cannot be written). */
    int nthreads = ro.threads > 0 ? ro.threads : omp_get_max_threads();
    if ((st = tb__rf_provenance(&r, scene_path, opt, &ro, nthreads, on_backend)))
        goto done;
    if (opt->stats_path && (st = tb__rf_stats(&r, opt, &ro, &rs, on_backend)))
        goto done;
    if ((st = tb_image_write_exposed(opt->image_path, r.img, opt->exposure)))
        goto done;
    if (r.map && (st = tb__rf_write_map(&r, opt->sample_map_path))) {
        remove(opt->image_path);
        goto done;
    }
    if (out) {
        *out = (tb_render_file_result){
            .stats = rs,
            .width = r.img->width,
            .height = r.img->height,
            .threads = nthreads,
            .spectral = r.scene->spectral,
            .backend = on_backend,
        };
    }
done:
    tb__rf_run_free(&r);
    return st;
}
