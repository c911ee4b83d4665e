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
#include "util/image/image.h"
#include "util/stats/stats.h"
#include "util/stats/summary.h"

/* How much longer the pilot's elements are than the render's. */
#define TB__RAD_PILOT_COARSEN 4.0

/* What the pilot records after every shot: the unshot fraction (a tb_array
 * of double) and, for the shot-count scaling, the shots by object. */
typedef struct tb__rad_pilot {
    tb_array decay;      /* unshot fraction after each shot */
    double *prev;        /* npatches: each shooter's unshot power at the last report */
    const uint32_t *obj; /* npatches: the shooter's top-level object */
    double *shots;       /* nobj: pilot shots from each object's shooters */
    size_t npatches;
} tb__rad_pilot;

static tb_status tb__rad_record(void *user, const tb_rad_solver *s)
{
    tb__rad_pilot *p = user;
    double u = tb_rad_unshot_fraction(s);
    /* the shooter is the patch whose unshot power dropped to 0 (others only gain; a light shot has none) */
    for (size_t i = 0; i < p->npatches; i++) {
        double now = tb_rad_patch_unshot_power(s, i);
        if (p->prev[i] > 0.0 && now == 0.0)
            p->shots[p->obj[i]] += 1.0;
        p->prev[i] = now;
    }
    return tb_array_push(&p->decay, &u);
}

/* The top-level object of every shooter (patches, else elements) into
 * obj[0 .. shooters); counts them per object into count[0 .. nobj) when
 * count is not NULL. */
static void tb__rad_shooter_objects(const tb_rad_mesh *m, uint32_t *obj, double *count)
{
    for (size_t e = 0; e < m->nelems; e++) {
        size_t p = m->npatches ? m->patch[e] : e;
        obj[p] = m->elems[e].object;
    }
    size_t n = m->npatches ? m->npatches : m->nelems;
    if (count)
        for (size_t p = 0; p < n; p++)
            count[obj[p]] += 1.0;
}

/* One more than the largest object index of m's elements. */
static size_t tb__rad_nobj(const tb_rad_mesh *m)
{
    size_t n = 0;
    for (size_t e = 0; e < m->nelems; e++)
        if ((size_t)m->elems[e].object + 1 > n)
            n = (size_t)m->elems[e].object + 1;
    return n;
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

/* How many of the full mesh's shooters tb__rad_full_sample casts form factors from, and for how long at most. */
#define TB__RAD_SAMPLE_SHOOTERS 32
#define TB__RAD_SAMPLE_SECONDS 2.0

/* The visibility work per form-factor ray on the full mesh: from up to
 * TB__RAD_SAMPLE_SHOOTERS shooters spread evenly over the mesh's, the
 * form-factor rays traced through the BVH, the BVH nodes they visit and the
 * occluders listed per shaft, each per form-factor ray. The coarse pilot
 * gets these wrong (its larger elements make larger shafts, more of them
 * too full for a list: radiosity-room's BVH rays came out 3.2 times the
 * render's), so they come from the render's own mesh. False when nothing
 * was sampled (hemicube form factors: no rays). */
static bool tb__rad_full_sample(const tb_rad_mesh *mesh, const tb_rad_options *ro, double ratio[3])
{
    if (ro->ff != TB_RAD_FF_RAYCAST)
        return false;
    tb_rad_solver *s = NULL;
    if (tb_rad_solver_create(mesh, NULL, ro, &s)) {
        tb_clear_error();
        return false;
    }
    size_t n = tb_rad_solver_npatches(s), k = n < TB__RAD_SAMPLE_SHOOTERS ? n : TB__RAD_SAMPLE_SHOOTERS;
    tb_stats_reset();
    int64_t t0 = tb_stats_now_ns();
    size_t done = 0;
    for (size_t j = 0; j < k && 1e-9 * (double)(tb_stats_now_ns() - t0) < TB__RAD_SAMPLE_SECONDS; j++) {
        double f;
        if (tb_rad_formfactor(s, (j * n + n / 2) / k, 0, &f)) {
            tb_clear_error();
            break;
        }
        done++;
    }
    double rays = (double)tb_stats_counter("Radiosity/rays (receivers x samples)");
    double shafts = (double)tb_stats_counter("Form factors/shafts");
    bool ok = done > 0 && rays > 0;
    if (ok) {
        ratio[0] = (double)tb_stats_counter("BVH/occlusion rays") / rays;
        ratio[1] = (double)tb_stats_counter("BVH/nodes visited") / rays;
        ratio[2] = shafts > 0 ? (double)tb_stats_counter("Form factors/occluders listed in shafts") / shafts : 0.0;
    }
    tb_rad_solver_free(s);
    tb_stats_reset();
    return ok;
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
    tb__rad_pilot pilot = {0};
    tb_array_init(&pilot.decay, sizeof(double));
    double *full_count = NULL, *pilot_count = NULL;
    uint32_t *full_obj = NULL, *pobj = NULL;
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
     * elements; with spheres, 1.6 to 2.5 from 1772 to 97), but the
     * coarsening is not uniform: flat faces get 16 times fewer elements,
     * curved surfaces (meshed by angle) about as many. So each pilot shot
     * counts for the ratio of the render's shooters to the pilot's on the
     * object it was shot from. */
    double full_shooters = (double)(mesh.npatches ? mesh.npatches : mesh.nelems);
    double full_verts = (double)mesh.nverts, full_elems = (double)mesh.nelems;
    size_t full_nobj = tb__rad_nobj(&mesh);
    full_count = calloc(full_nobj + 1, sizeof *full_count);
    full_obj = malloc(((size_t)full_shooters + 1) * sizeof *full_obj);
    if (!full_count || !full_obj) {
        st = tb_error(TB_ERR_NOMEM, "predict: out of memory");
        goto done;
    }
    tb__rad_shooter_objects(&mesh, full_obj, full_count);
    double full_ratio[3] = {0};
    bool coarsen = full_shooters > 256 && (mo.max_edge > 0 || mo.max_area > 0);
    bool sampled = false;
    if (coarsen) {
        tb_rad_options fo = ro; /* the render's sample points: the rays as it traces them */
        fo.samples = o->solver.samples;
        sampled = tb__rad_full_sample(&mesh, &fo, full_ratio);
    }
    if (coarsen) {
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
    size_t nobj = tb__rad_nobj(&mesh) > full_nobj ? tb__rad_nobj(&mesh) : full_nobj;
    pilot.npatches = (size_t)shooters;
    pilot.prev = calloc(pilot.npatches + 1, sizeof *pilot.prev);
    pilot.shots = calloc(nobj + 1, sizeof *pilot.shots);
    pilot_count = calloc(nobj + 1, sizeof *pilot_count);
    pobj = malloc((pilot.npatches + 1) * sizeof *pobj);
    pilot.obj = pobj;
    if (!pilot.prev || !pilot.shots || !pilot_count || !pobj) {
        st = tb_error(TB_ERR_NOMEM, "predict: out of memory");
        goto done;
    }
    tb__rad_shooter_objects(&mesh, pobj, pilot_count);
    int64_t t0 = tb_stats_now_ns();
    tb_stats_reset();
    if ((st = tb_rad_solver_create(&mesh, NULL, &ro, &solver)))
        goto done;
    for (size_t i = 0; i < pilot.npatches; i++)
        pilot.prev[i] = tb_rad_patch_unshot_power(solver, i);
    tb_rad_stop stop = o->stop;
    stop.progress = false;
    stop.time_budget = pilot_seconds;
    stop.max_shots = 0;
    if ((st = tb_rad_solver_run(solver, &stop, tb__rad_record, &pilot, 1)))
        goto done;
    f->pilot_seconds = 1e-9 * (double)(tb_stats_now_ns() - t0);
    double threshold = o->stop.threshold > 0 ? o->stop.threshold : TB_RAD_DEFAULT_THRESHOLD;
    double pilot_shots = (double)tb_rad_solver_shots(solver), shots = pilot_shots;
    if (tb_rad_unshot_fraction(solver) > threshold && pilot_shots > 0) {
        /* out of pilot time: extrapolate (an underestimate when the decay slows) */
        double e = tb__rad_extrapolate(&pilot.decay, threshold);
        if (isfinite(e) && e > pilot_shots)
            shots = e;
        f->rad_extrapolated = true;
    }
    /* each pilot shot from an object stands for (render's shooters / pilot's) on that object; shots from
     * point lights and objects missing in one mesh count once, and an extrapolated tail at the mean scale */
    double scaled = 0.0, counted = 0.0;
    for (size_t k = 0; k < nobj; k++) {
        double fc = k < full_nobj ? full_count[k] : 0.0;
        if (pilot.shots[k] > 0.0) {
            scaled += pilot.shots[k] * (pilot_count[k] > 0.0 && fc > 0.0 ? fc / pilot_count[k] : 1.0);
            counted += pilot.shots[k];
        }
    }
    scaled += fmax(0.0, pilot_shots - counted);
    double mean_scale = pilot_shots > 0 ? scaled / pilot_shots : full_shooters / (shooters > 0 ? shooters : 1.0);
    shots = scaled + (shots - pilot_shots) * mean_scale;
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
    f->f[TB_PF_RAD_NODES] *= ray_scale;
    f->f[TB_PF_RAD_SHAFT_TESTS] *= ray_scale;
    if (sampled) { /* the full mesh's visibility work per ray, not the coarse pilot's */
        f->f[TB_PF_RAD_OCC_RAYS] = f->f[TB_PF_RAD_RAYS] * full_ratio[0];
        f->f[TB_PF_RAD_NODES] = f->f[TB_PF_RAD_RAYS] * full_ratio[1];
        f->f[TB_PF_RAD_SHAFT_TESTS] = f->f[TB_PF_RAD_RAYS] * full_ratio[2];
    }
    if (image) {
        /* A pilot image, 1/TB__RAD_PILOT_COARSEN of the resolution each way, of
         * the pilot's solution: the BVH nodes its rays visit (a view of mostly
         * sky costs little per ray, a closed room a walk to a leaf), times the
         * pixel ratio and the full mesh's tree depth over the pilot's. */
        int W = scene->camera.width, H = scene->camera.height;
        int pw = (int)(W / TB__RAD_PILOT_COARSEN), ph = (int)(H / TB__RAD_PILOT_COARSEN);
        pw = pw < 1 ? 1 : pw, ph = ph < 1 ? 1 : ph;
        tb_camera full = scene->camera;
        tb_image *img = NULL;
        tb_stats_reset();
        if (!(st = tb_camera_from_mid(&scene->mid_camera, pw, ph, &scene->camera)))
            st = tb_rad_render_image(solver, scene, o->spp, &img);
        scene->camera = full;
        double px_ratio = ((double)W * H) / ((double)pw * ph);
        if (!st) /* the pilot image's PNG bytes stand for the image's (docs/predict.md) */
            st = tb_predict_image_bytes(img, 1, true, px_ratio, &f->f[TB_PF_IMAGE_BYTES]);
        tb_image_free(img);
        if (st)
            goto done;
        double nodes = (double)tb_stats_counter("BVH/nodes visited");
        double depth = log2(full_elems + 2.0) / log2((double)mesh.nelems + 2.0);
        f->f[TB_PF_RAD_PIXEL_NODES] = nodes * px_ratio * depth;
        /* a leaf holds a few elements however fine the mesh: the tests per ray follow what the rays hit */
        f->f[TB_PF_RAD_PIXEL_LEAF_TESTS] = (double)tb_stats_counter("BVH/primitives tested") * px_ratio;
    }
    f->rad_shots = shots;
    f->f[TB_PF_RAD_SHOT_ELEMS] = shots * full_elems;
    f->f[TB_PF_RAD_CACHE_BYTES] =
        fmin((double)(512u << 20), f->f[TB_PF_RAD_CACHE_BYTES] / (pilot_shots > 0 ? pilot_shots : 1.0) * shots);
done:
    tb_array_free(&pilot.decay);
    free(pilot.prev), free(pilot.shots), free(pobj), free(pilot_count), free(full_count), free(full_obj);
    tb_rad_solver_free(solver);
    tb_rad_mesh_free(&mesh);
    tb_scene_free(scene);
    tb_stats_reset();
    tb_stats_set_enabled(saved);
    return st;
}
