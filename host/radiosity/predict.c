/* The radiosity pilot of the cost model (host/radiosity/predict.h). */
#include "host/radiosity/predict.h"

#include <errno.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "host/render/camera.h"
#include "util/stats/stats.h"
#include "util/stats/summary.h"

/* The unshot fraction after every pilot shot. */
typedef struct tb__rad_decay {
    double *u;
    size_t n, cap;
} tb__rad_decay;

static tb_status tb__rad_record(void *user, const tb_rad_solver *s)
{
    tb__rad_decay *d = user;
    if (d->n == d->cap) {
        size_t cap = d->cap ? 2 * d->cap : 256;
        double *u = realloc(d->u, cap * sizeof *u);
        if (!u)
            return tb_error(TB_ERR_NOMEM, "predict: out of memory for the pilot's decay");
        d->u = u, d->cap = cap;
    }
    d->u[d->n++] = tb_rad_unshot_fraction(s);
    return TB_OK;
}

/* Shots until the unshot fraction reaches `threshold`, along the power law
 * u = a k^b fitted over the second half of the recorded decay; NaN if the
 * decay does not fall. */
static double tb__rad_extrapolate(const tb__rad_decay *d, double threshold)
{
    size_t from = d->n / 2, m = d->n - from;
    if (m < 2)
        return NAN;
    double *k = malloc(m * sizeof *k);
    if (!k)
        return NAN;
    for (size_t i = 0; i < m; i++)
        k[i] = (double)(from + i + 1);
    tb_line_fit lf;
    double shots = NAN;
    if (tb_fit_loglog(k, d->u + from, (int)m, &lf) == TB_OK && lf.slope < -1e-3)
        shots = pow(10.0, (log10(threshold) - lf.intercept) / lf.slope);
    free(k);
    return shots;
}

tb_status tb_rad_predict_scene(const char *path, const tb_rad_render_options *o, double pilot_seconds,
                               tb_predict_stats *f)
{
    if (o->adapt.threshold > 0)
        return tb_error(TB_ERR_UNSUPPORTED, "predict: adaptive subdivision (--adapt) is not in the cost model");
    if (!(pilot_seconds > 0))
        return tb_error(TB_ERR_ARG, "predict: the pilot's time must be > 0 seconds");
    struct stat sb;
    if (stat(path, &sb) != 0)
        return tb_error(TB_ERR_IO, "%s: %s", path, strerror(errno));
    if (o->threads > 0)
        omp_set_num_threads(o->threads);
    int saved = tb_stats_enabled();
    tb_stats_set_enabled(1);
    tb_stats_reset();
    tb_scene_options so = {.no_accel = true, .no_emitters = true, .threads = o->threads};
    tb_scene *scene = NULL;
    tb_rad_mesh mesh;
    tb_rad_mesh_init(&mesh);
    tb_rad_solver *solver = NULL;
    tb__rad_decay decay = {0};
    tb_status st = tb_scene_load(path, &so, &scene);
    if (st)
        goto done;
    bool image = o->image_path != NULL;
    tb_predict_stats_init(f, TB_PREDICT_RADIOSITY, (double)sb.st_size, image ? scene->camera.width : 0,
                          image ? scene->camera.height : 0, scene->nchannels, o->spp, o->threads);
    tb_rad_mesh_options mo = o->mesh;
    if (!o->mesh_given) {
        mo = tb_rad_default_mesh_options(scene);
        mo.patch_edge = o->mesh.patch_edge, mo.patch_area = o->mesh.patch_area;
    }
    if ((st = tb_rad_mesh_from_scene(scene, &mo, &mesh)))
        goto done;
    tb_predict_stats_add_scene(f); /* after meshing: its CSG probes count too */
    tb_rad_options ro = o->solver;
    ro.lights = scene->lights;
    ro.nlights = scene->nlights;
    ro.batch = NULL, ro.batch_ctx = NULL, ro.exchange = NULL;
    double ray_scale = 1.0;
    if (ro.ff == TB_RAD_FF_RAYCAST) {
        int samples = ro.samples > 0 ? ro.samples : TB_RAD_DEFAULT_SAMPLES;
        ray_scale = samples; /* the pilot's rays per receiver are 1 */
        ro.samples = 1;
    } else {
        int res = ro.hemicube_res > 0 ? ro.hemicube_res : TB_RAD_DEFAULT_HEMICUBE_RES;
        ro.hemicube_res = res / 4 > 8 ? res / 4 : 8;
        ray_scale = (double)res * res / ((double)ro.hemicube_res * ro.hemicube_res);
    }
    int64_t t0 = tb_stats_now_ns();
    tb_stats_reset();
    if ((st = tb_rad_solver_create(&mesh, NULL, &ro, &solver)))
        goto done;
    tb_rad_stop stop = o->stop;
    stop.progress = false;
    stop.time_budget = pilot_seconds;
    if ((st = tb_rad_solver_run(solver, &stop, tb__rad_record, &decay, 1)))
        goto done;
    f->pilot_seconds = 1e-9 * (double)(tb_stats_now_ns() - t0);
    double threshold = o->stop.threshold > 0 ? o->stop.threshold : TB_RAD_DEFAULT_THRESHOLD;
    double pilot_shots = (double)tb_rad_solver_shots(solver), shots = pilot_shots;
    bool capped = o->stop.max_shots > 0 && pilot_shots >= (double)o->stop.max_shots;
    if (tb_rad_unshot_fraction(solver) > threshold && !capped && pilot_shots > 0) {
        double e = tb__rad_extrapolate(&decay, threshold);
        if (isfinite(e) && e > pilot_shots) {
            shots = e;
            f->rad_extrapolated = true;
        }
        if (o->stop.max_shots > 0 && shots > (double)o->stop.max_shots)
            shots = (double)o->stop.max_shots;
    }
    /* the pilot's counters, per shot, times the render's shots */
    double per_shot = pilot_shots > 0 ? shots / pilot_shots : 0.0;
    tb_stats_set_value("shots", pilot_shots);
    tb_stats_set_value("elements", (double)mesh.nelems);
    tb_stats_set_value("vertices", (double)mesh.nverts);
    tb_predict_stats_add_work(f, per_shot);
    f->f[TB_PF_RAD_RAYS] *= ray_scale;
    /* shot-proportional figures that add_work took from the run values */
    f->rad_shots = shots;
    f->f[TB_PF_RAD_SHOT_ELEMS] = shots * (double)mesh.nelems;
    f->f[TB_PF_RAD_CACHE_BYTES] = fmin((double)(512u << 20), f->f[TB_PF_RAD_CACHE_BYTES] * per_shot);
done:
    free(decay.u);
    tb_rad_solver_free(solver);
    tb_rad_mesh_free(&mesh);
    tb_scene_free(scene);
    tb_stats_reset();
    tb_stats_set_enabled(saved);
    return st;
}
