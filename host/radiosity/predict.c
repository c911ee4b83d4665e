/* The radiosity pilot of the cost model (host/radiosity/predict.h). */
#include "host/radiosity/predict.h"

#include <errno.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "host/render/camera.h"
#include "util/container/array.h"
#include "util/stats/stats.h"
#include "util/stats/summary.h"

/* How much longer the pilot's elements are than the render's. */
#define TB__RAD_PILOT_COARSEN 4.0

/* Records the unshot fraction after every pilot shot (a tb_array of double). */
static tb_status tb__rad_record(void *user, const tb_rad_solver *s)
{
    double u = tb_rad_unshot_fraction(s);
    return tb_array_push(user, &u);
}

/* Shots until the unshot fraction reaches `threshold`, along the
 * exponential decay log u = a + b k fitted over the second half of the
 * recorded decay (progressive refinement's unshot energy falls roughly
 * geometrically once the light sources have shot); NaN if it does not fall. */
static double tb__rad_extrapolate(const tb_array *d, double threshold)
{
    const double *u = d->data;
    size_t from = d->len / 2, m = d->len - from;
    if (m < 2)
        return NAN;
    double *k = malloc(2 * m * sizeof *k);
    if (!k)
        return NAN;
    double *lu = k + m;
    size_t used = 0;
    for (size_t i = 0; i < m; i++)
        if (u[from + i] > 0.0) {
            k[used] = (double)(from + i + 1);
            lu[used++] = log10(u[from + i]);
        }
    tb_line_fit lf;
    double shots = NAN;
    if (used >= 2 && tb_fit_line(k, lu, (int)used, &lf) == TB_OK && lf.slope < 0.0)
        shots = (log10(threshold) - lf.intercept) / lf.slope;
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
    tb_array decay;
    tb_array_init(&decay, sizeof(double));
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
    /* The pilot's mesh: elements (and patches) TB__RAD_PILOT_COARSEN times
     * longer, about 1/16 of the shooters, unless the mesh is small already.
     * Shots to convergence per shooter change little with the element size
     * (the Cornell box: 3.7 to 4.2 shots per element from 31 to 1322
     * elements), so the pilot's shots per shooter times the render's
     * shooters is the render's shot count. */
    double full_shooters = (double)(mesh.npatches ? mesh.npatches : mesh.nelems);
    double full_verts = (double)mesh.nverts, full_elems = (double)mesh.nelems;
    if (full_shooters > 256 && (mo.max_edge > 0 || mo.max_area > 0)) {
        tb_rad_mesh_options co = mo;
        co.max_edge *= TB__RAD_PILOT_COARSEN;
        co.max_area *= TB__RAD_PILOT_COARSEN * TB__RAD_PILOT_COARSEN;
        co.patch_edge *= TB__RAD_PILOT_COARSEN;
        co.patch_area *= TB__RAD_PILOT_COARSEN * TB__RAD_PILOT_COARSEN;
        tb_rad_mesh_free(&mesh);
        tb_rad_mesh_init(&mesh);
        if ((st = tb_rad_mesh_from_scene(scene, &co, &mesh)))
            goto done;
    }
    double shooters = (double)(mesh.npatches ? mesh.npatches : mesh.nelems);
    int64_t t0 = tb_stats_now_ns();
    tb_stats_reset();
    if ((st = tb_rad_solver_create(&mesh, NULL, &ro, &solver)))
        goto done;
    tb_rad_stop stop = o->stop;
    stop.progress = false;
    stop.time_budget = pilot_seconds;
    stop.max_shots = 0;
    if ((st = tb_rad_solver_run(solver, &stop, tb__rad_record, &decay, 1)))
        goto done;
    f->pilot_seconds = 1e-9 * (double)(tb_stats_now_ns() - t0);
    double threshold = o->stop.threshold > 0 ? o->stop.threshold : TB_RAD_DEFAULT_THRESHOLD;
    double pilot_shots = (double)tb_rad_solver_shots(solver), shots = pilot_shots;
    if (tb_rad_unshot_fraction(solver) > threshold && pilot_shots > 0) {
        /* out of pilot time: extrapolate (an underestimate when the decay slows) */
        double e = tb__rad_extrapolate(&decay, threshold);
        if (isfinite(e) && e > pilot_shots)
            shots = e;
        f->rad_extrapolated = true;
    }
    shots *= full_shooters / (shooters > 0 ? shooters : 1.0);
    if (o->stop.max_shots > 0 && shots > (double)o->stop.max_shots)
        shots = (double)o->stop.max_shots;
    /* per shot, the pilot's rays and form factors grow with the receivers (vertices) */
    double per_shot = pilot_shots > 0 ? shots / pilot_shots : 0.0;
    double vscale = mesh.nverts ? full_verts / (double)mesh.nverts : 1.0;
    tb_stats_set_value("shots", pilot_shots);
    tb_stats_set_value("elements", full_elems);
    tb_stats_set_value("vertices", full_verts);
    tb_predict_stats_add_work(f, per_shot * vscale);
    f->f[TB_PF_RAD_RAYS] *= ray_scale;
    f->f[TB_PF_RAD_OCC_RAYS] *= ray_scale;
    f->f[TB_PF_RAD_SHAFT_TESTS] *= ray_scale;
    f->rad_shots = shots;
    f->f[TB_PF_RAD_SHOT_ELEMS] = shots * full_elems;
    f->f[TB_PF_RAD_CACHE_BYTES] =
        fmin((double)(512u << 20), f->f[TB_PF_RAD_CACHE_BYTES] / (pilot_shots > 0 ? pilot_shots : 1.0) * shots);
done:
    tb_array_free(&decay);
    tb_rad_solver_free(solver);
    tb_rad_mesh_free(&mesh);
    tb_scene_free(scene);
    tb_stats_reset();
    tb_stats_set_enabled(saved);
    return st;
}
