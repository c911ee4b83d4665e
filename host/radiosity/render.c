/* The radiosity workflow in one call (render.h): scene -> mesh -> solve ->
 * outputs, with the log lines and provenance `testbed render --method
 * radiosity` has always written. */
#include "host/radiosity/render.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <omp.h>

#include "host/render/scene.h"
#include "util/base/outfile.h"
#include "util/image/image.h"
#include "util/stats/provenance.h"
#include "util/stats/stats.h"
#include "host/render/predict.h"

#define TB__RAD_STR2(x) #x
#define TB__RAD_STR(x) TB__RAD_STR2(x)

tb_rad_render_options tb_rad_render_defaults(void)
{
    return (tb_rad_render_options){
        .stop = {.threshold = TB_RAD_DEFAULT_THRESHOLD},
        .spp = 4,
        .exposure = NAN,
        .log_prefix = "",
    };
}

/* The --report rows, kept in memory and written at the end (all or nothing). */
typedef struct tb__rad_report {
    const double *ref; /* nelems * nc */
    size_t n;
    int nc;
    char *buf;
    size_t len, cap;
    double b[TB_CHANNELS_MAX];
} tb__rad_report;

/* BVH nodes visited so far (0 with statistics off): the image rays' share
 * is told apart from the form factors' for testbed calibrate. */
static double tb__rad_nodes_visited(void)
{
    return tb_stats_enabled() ? (double)tb_stats_counter("BVH/nodes visited") : 0.0;
}

/* The same for the elements tested at BVH leaves. */
static double tb__rad_leaf_tests(void)
{
    return tb_stats_enabled() ? (double)tb_stats_counter("BVH/primitives tested") : 0.0;
}

static tb_status tb__rad_report_row(void *user, const tb_rad_solver *s)
{
    tb__rad_report *r = user;
    double num = 0.0, num_a = 0.0, den = 0.0;
    double amb[TB_CHANNELS_MAX];
    tb_rad_ambient(s, amb);
    const tb_rad_mesh *m = tb_rad_solver_mesh(s);
    for (size_t i = 0; i < r->n; i++) {
        tb_rad_element_radiosity(s, i, false, r->b);
        for (int c = 0; c < r->nc; c++) {
            double ref = r->ref[i * (size_t)r->nc + (size_t)c];
            double d = r->b[c] - ref;
            double da = d + m->rho[i * (size_t)r->nc + (size_t)c] * amb[c];
            /* relative to the reflected radiosity: the emitters' own E is
             * exact in every solution and would swamp the error */
            double refl = ref - m->emission[i * (size_t)r->nc + (size_t)c];
            num += d * d, num_a += da * da, den += refl * refl;
        }
    }
    double nrmse = den > 0 ? sqrt(num / den) : 0.0, nrmse_a = den > 0 ? sqrt(num_a / den) : 0.0;
    char line[256];
    int k = snprintf(line, sizeof line, "%.6f,%llu,%.6f,%.9g,%.9g,%.9g\n", tb_rad_solver_seconds(s),
                     (unsigned long long)tb_rad_solver_shots(s), (double)tb_rad_solver_shots(s) / (double)r->n,
                     tb_rad_unshot_fraction(s), nrmse, nrmse_a);
    if (r->len + (size_t)k + 1 > r->cap) {
        size_t cap = r->cap ? 2 * r->cap : 4096;
        while (cap < r->len + (size_t)k + 1)
            cap *= 2;
        char *p = realloc(r->buf, cap);
        if (!p)
            return tb_error(TB_ERR_NOMEM, "report: out of memory");
        r->buf = p, r->cap = cap;
    }
    memcpy(r->buf + r->len, line, (size_t)k + 1);
    r->len += (size_t)k;
    return TB_OK;
}

static tb_status tb__write_text(const char *path, const char *header, const char *body, size_t len)
{
    tb_outfile of;
    tb_status st = tb_outfile_open(&of, path);
    if (st)
        return st;
    fputs(header, of.fp);
    if (len)
        fwrite(body, 1, len, of.fp);
    if (ferror(of.fp)) {
        tb_outfile_abort(&of);
        return tb_error(TB_ERR_IO, "%s: write failed", path);
    }
    return tb_outfile_commit(&of);
}

/* Checks that need no scene: what the command reports as usage errors. */
static tb_status tb__rad_check(const tb_rad_render_options *o)
{
    if (!o->image_path && !o->patches_path && !o->mesh_path)
        return tb_error(TB_ERR_ARG, "nothing to write: give -o IMAGE, --patches FILE.csv or --mesh-out "
                                    "FILE.ply|.gltf|.glb");
    if (o->image_path && tb_image_format_from_path(o->image_path) == TB_IMAGE_UNKNOWN)
        return tb_error(TB_ERR_ARG, "unknown image format of '%s' (.png, .exr, .pfm, .rle)", o->image_path);
    if (o->mesh_path && tb_rad_mesh_format_from_path(o->mesh_path) == TB_RAD_MESH_UNKNOWN)
        return tb_error(TB_ERR_ARG, "--mesh-out '%s': unknown mesh format (.ply, .gltf, .glb)", o->mesh_path);
    if (!o->report_path != !o->reference_path)
        return tb_error(TB_ERR_ARG, "--report and --reference go together");
    if (o->adapt.threshold > 0 && o->report_path)
        return tb_error(TB_ERR_ARG, "--report compares with a reference of the same mesh: not with --adapt");
    return TB_OK;
}

/* The solved mesh with vertex colours: mean non-emitting radiance (luminance) to 0.18. */
static tb_status tb__rad_write_mesh(const tb_rad_solver *solver, const char *path, const tb_provenance *prov)
{
    double scale = tb_rad_display_scale(solver);
    tb_rad_mesh_format f = tb_rad_mesh_format_from_path(path);
    switch (f) {
    case TB_RAD_MESH_PLY:
        return tb_rad_write_ply(solver, path, scale, prov);
    case TB_RAD_MESH_GLTF:
    case TB_RAD_MESH_GLB:
        return tb_rad_write_gltf(solver, path, scale, f == TB_RAD_MESH_GLB, prov);
    case TB_RAD_MESH_UNKNOWN:
        break;
    }
    return tb_error(TB_ERR_ARG, "%s: unknown mesh format", path);
}

/* The element-size phrase of the log line. */
static void tb__rad_size_text(const tb_rad_mesh_options *mo, bool given, char *size, size_t len)
{
    if (mo->max_edge > 0 && mo->max_area > 0)
        snprintf(size, len, "max edge %g, max area %g", mo->max_edge, mo->max_area);
    else if (mo->max_area > 0)
        snprintf(size, len, "max area %g", mo->max_area);
    else if (mo->max_edge > 0)
        snprintf(size, len, "max edge %g%s", mo->max_edge,
                 given ? "" : " (default: bounding-box diagonal / " TB__RAD_STR(TB_RAD_DEFAULT_EDGE_DIVISIONS) ")");
    else
        snprintf(size, len, "faces whole");
}

/* The solver's per-shot callback when a checkpoint is kept: the report
 * rows every `every` shots, as tb_rad_solver_run would write them, and the
 * persist's save after every shot (it keeps its own schedule). */
typedef struct tb__rad_shot_hook {
    tb__rad_report *rep; /* NULL: no report */
    uint64_t every, n;   /* rows every `every` shots; shots so far */
    const tb_rad_persist *persist;
} tb__rad_shot_hook;

static tb_status tb__rad_on_shot(void *user, const tb_rad_solver *s)
{
    tb__rad_shot_hook *h = user;
    tb_status st = TB_OK;
    h->n++;
    if (h->rep && h->n % h->every == 0)
        st = tb__rad_report_row(h->rep, s);
    if (!st && h->persist->save)
        st = h->persist->save(h->persist->ctx, s, NULL, 0, tb_rad_solver_shots(s), false);
    return st;
}

/* The saved state of a solve without adaptive subdivision into s, if
 * there is one. */
static tb_status tb__rad_restore(const tb_rad_persist *pe, tb_rad_solver *s)
{
    bool found = false;
    void *extra = NULL, *state = NULL;
    size_t extra_len = 0, state_len = 0;
    tb_status st = pe->load(pe->ctx, &found, &extra, &extra_len, &state, &state_len);
    if (!st && found && extra_len)
        st = tb_error(TB_ERR_FORMAT, "the checkpoint is of a solve with adaptive subdivision (--adapt)");
    if (!st && found)
        st = tb_rad_solver_unpack(s, state, state_len);
    free(extra);
    free(state);
    return st;
}

/* Everything tb_rad_render holds, freed in one place. */
typedef struct tb__rad_run {
    tb_scene *scene;
    tb_rad_mesh mesh;
    tb_rad_solver *solver;
    tb_image *img;
    tb__rad_report rep;
    double *ref;
    bool has_prov;
    tb_provenance prov;
} tb__rad_run;

static void tb__rad_run_free(tb__rad_run *r)
{
    if (r->has_prov)
        tb_provenance_free(&r->prov);
    free(r->rep.buf);
    free(r->ref);
    tb_image_free(r->img);
    tb_rad_solver_free(r->solver);
    tb_rad_mesh_free(&r->mesh);
    tb_scene_free(r->scene);
}

/* Reads the reference of --report; it must match the mesh. */
static tb_status tb__rad_reference(tb__rad_run *r, const char *path)
{
    size_t nrows;
    int ncols;
    tb_status st = tb_rad_read_patches(path, &nrows, &ncols, &r->ref);
    if (st)
        return st;
    if (nrows != r->mesh.nelems || ncols != r->mesh.nchannels)
        return tb_error(TB_ERR_ARG,
                        "--reference %s has %zu elements x %d channels, this mesh %zu x %d "
                        "(use the same scene and meshing options)",
                        path, nrows, ncols, r->mesh.nelems, r->mesh.nchannels);
    r->rep.ref = r->ref, r->rep.n = r->mesh.nelems, r->rep.nc = r->mesh.nchannels;
    return TB_OK;
}

/* The provenance of the image, the mesh files and the stats. */
static tb_status tb__rad_provenance(tb__rad_run *r, const char *scene_path, const tb_rad_options *ro,
                                    const tb_rad_mesh_options *mo, const tb_rad_render_options *o, int nthreads)
{
    char *empty[] = {"", NULL};
    tb_status st = o->argv ? tb_provenance_init(&r->prov, o->argc, o->argv) : tb_provenance_init(&r->prov, 1, empty);
    if (st)
        return st;
    r->has_prov = true;
    const tb_rad_adapt_options *ao = &o->adapt;
    char opts[512];
    snprintf(opts, sizeof opts,
             "method=radiosity formfactor=%s samples=%d hemicube_res=%d threshold=%g time_budget=%g max_edge=%g "
             "max_area=%g max_angle=%g patch_edge=%g patch_area=%g spp=%d threads=%d colour=%s backend=%s adapt=%g "
             "adapt_levels=%d min_area=%g",
             ro->ff == TB_RAD_FF_HEMICUBE ? "hemicube" : "raycast", ro->samples ? ro->samples : TB_RAD_DEFAULT_SAMPLES,
             ro->hemicube_res ? ro->hemicube_res : TB_RAD_DEFAULT_HEMICUBE_RES, o->stop.threshold, o->stop.time_budget,
             mo->max_edge, mo->max_area, mo->max_angle, mo->patch_edge, mo->patch_area, o->spp, nthreads,
             r->mesh.spectral ? "spectral" : "rgb",
             ro->batch ? (o->backend_name ? o->backend_name : "batch") : "cpu", ao->threshold,
             ao->threshold > 0 ? (ao->max_levels ? ao->max_levels : TB_RAD_ADAPT_DEFAULT_LEVELS) : 0, ao->min_area);
    tb_provenance_set_seed(&r->prov, ro->seed);
    if (strcmp(scene_path, "-") != 0 && (st = tb_provenance_hash_file(&r->prov, scene_path)))
        return st;
    return tb_provenance_set_options(&r->prov, opts);
}

/* Where each step of the solve runs: a form-factor backend (opt->backend)
 * replaces the sampled form factors and their visibility only; the other
 * steps are CPU code on every backend. Reported in the log and in --stats so
 * that no step runs elsewhere unsaid (docs/radiosity.md, "Where each step runs"). */
typedef struct tb__rad_where {
    const char *formfactors; /* sampled shooter-to-vertex form factors with visibility (the batch) */
    const char *near_field;  /* exact point-to-polygon form factors near the shooter */
    const char *light_shots; /* point, spot and directional lights: irradiance and shadow segments */
    const char *image;       /* the Gouraud display (-o) */
} tb__rad_where;

static tb__rad_where tb__rad_where_of(const tb_rad_render_options *o, const tb_rad_options *ro, int nlights)
{
    bool hemi = ro->ff == TB_RAD_FF_HEMICUBE;
    const char *batch = ro->batch ? (o->backend_name ? o->backend_name : "batch") : "cpu";
    return (tb__rad_where){
        .formfactors = hemi ? "cpu (hemicube)" : batch,
        .near_field = hemi ? "cpu (hemicube)" : "cpu",
        .light_shots = nlights > 0 ? "cpu" : "none",
        .image = o->image_path ? "cpu" : "none",
    };
}

static tb_status tb__rad_stats(const tb__rad_run *r, const char *path, double t_mesh, int nthreads,
                               const tb_rad_adapt_stats *as, const tb__rad_where *w)
{
    const tb_rad_solver *s = r->solver;
    tb_rad_energy en = tb_rad_solver_energy(s);
    struct {
        const char *k;
        double v;
    } kv[] = {{"seconds", tb_rad_solver_seconds(s)},
              {"mesh_seconds", t_mesh},
              {"elements", (double)r->mesh.nelems},
              {"vertices", (double)r->mesh.nverts},
              {"patches", (double)tb_rad_solver_npatches(s)},
              {"shots", (double)tb_rad_solver_shots(s)},
              {"shots_per_element", (double)tb_rad_solver_shots(s) / (double)r->mesh.nelems},
              {"unshot_fraction", tb_rad_unshot_fraction(s)},
              {"power_emitted", en.emitted},
              {"power_absorbed", en.absorbed},
              {"power_unshot", en.unshot},
              {"power_escaped", en.escaped},
              {"threads", (double)nthreads},
              {"adapt_rounds", (double)as->rounds},
              {"adapt_shots", (double)as->shots}};
    tb_status st = TB_OK;
    for (size_t k = 0; k < sizeof kv / sizeof kv[0] && !st; k++)
        st = tb_stats_set_value(kv[k].k, kv[k].v);
    const char *steps[][2] = {{"backend_formfactors", w->formfactors},
                              {"backend_near_field", w->near_field},
                              {"backend_light_shots", w->light_shots},
                              {"backend_image", w->image}};
    for (size_t k = 0; k < sizeof steps / sizeof steps[0] && !st; k++)
        st = tb_stats_set_string(steps[k][0], steps[k][1]);
    return st ? st : tb_stats_write_json_file(path, &r->prov);
}

/* The log lines before the solve: mesh size, patches, emitters, lights. */
static void tb__rad_log_mesh(const tb_rad_render_options *o, const char *scene_path, const tb__rad_run *r,
                             const tb_rad_mesh_options *mo, const tb_rad_options *ro)
{
    FILE *log = o->log;
    const char *p = o->log_prefix ? o->log_prefix : "";
    const tb_rad_mesh *m = &r->mesh;
    char size[96];
    tb__rad_size_text(mo, o->mesh_given, size, sizeof size);
    fprintf(log, "%sradiosity on %s: %zu elements (%s), %zu vertices, %d channels (%s), %s\n", p, scene_path,
            m->nelems, size, m->nverts, m->nchannels, m->spectral ? "spectral" : "rgb",
            ro->ff == TB_RAD_FF_HEMICUBE ? "hemicube" : "ray cast");
    if (m->npatches > 0)
        fprintf(log, "%s%zu patches (patch edge %g, area %g) shoot; the elements receive\n", p, m->npatches,
                mo->patch_edge, mo->patch_area);
    bool emits = false;
    for (size_t k = 0; k < m->nelems * (size_t)m->nchannels && !emits; k++)
        emits = m->emission[k] > 0.0f;
    if (!emits && r->scene->nlights == 0)
        fprintf(log, "%snote: no surface or light of %s emits: the solution is black\n", p, scene_path);
    if (r->scene->nlights > 0)
        fprintf(log, "%s%d point, spot or directional light%s shot directly (docs/radiosity.md)\n", p,
                r->scene->nlights, r->scene->nlights == 1 ? "" : "s");
    tb__rad_where w = tb__rad_where_of(o, ro, r->scene->nlights);
    fprintf(log, "%ssteps: form factors %s, near-shooter form factors %s, light shots %s, image %s\n", p,
            w.formfactors, w.near_field, w.light_shots, w.image);
}

tb_status tb_rad_render(const char *scene_path, const tb_rad_render_options *opt, tb_rad_render_result *out)
{
    tb_status st = tb__rad_check(opt);
    if (st)
        return st;
    if (opt->threads > 0)
        omp_set_num_threads(opt->threads);
    tb__rad_run r = {0};
    tb_rad_mesh_init(&r.mesh);
    tb_rad_options ro = opt->solver;
    tb_rad_adapt_stats as = {0};
    tb_scene_options so = {.no_accel = true, .no_emitters = true, .threads = opt->threads};
    const tb_rad_exchange *ex = ro.exchange && ro.exchange->ranks > 1 ? ro.exchange : NULL;
    bool root = !ex || ex->rank == 0;
    st = tb_scene_load(scene_path, &so, &r.scene);
    if (!st && opt->image_path && !r.scene->has_camera)
        st = tb_error(TB_ERR_ARG, "%s: the scene has no camera: use --patches or --mesh-out instead of -o",
                      scene_path);
    /* every process reads the scene itself; one that cannot stops them all
     * with its own file:line:col message */
    if (ex)
        st = ex->agree_status(ex->ctx, st);
    if (st)
        goto done;
    tb_rad_mesh_options mo = opt->mesh;
    if (!opt->mesh_given) {
        mo = tb_rad_default_mesh_options(r.scene);
        mo.patch_edge = opt->mesh.patch_edge, mo.patch_area = opt->mesh.patch_area;
    }
    double t_mesh = 1e-9 * (double)tb_stats_now_ns();
    if ((st = tb_rad_mesh_from_scene(r.scene, &mo, &r.mesh)))
        goto done;
    t_mesh = 1e-9 * (double)tb_stats_now_ns() - t_mesh;
    if (opt->reference_path)
        st = tb__rad_reference(&r, opt->reference_path);
    if (ex)
        st = ex->agree_status(ex->ctx, st);
    if (st)
        goto done;
    if (opt->backend && (st = opt->backend(opt->backend_user, &r.mesh, &ro)))
        goto done;
    if (opt->log && root)
        tb__rad_log_mesh(opt, scene_path, &r, &mo, &ro);
    ro.lights = r.scene->lights; /* the scene outlives the solver (IES tables) */
    ro.nlights = r.scene->nlights;
    bool adaptive = opt->adapt.threshold > 0;
    if (adaptive) {
        /* host/radiosity/adaptive.h: the mesh becomes the refined mesh */
        if ((st = tb_rad_adapt_solve_persist(&r.mesh, &ro, &opt->stop, &opt->adapt, opt->persist, &r.solver, &as)))
            goto done;
        if (opt->log && root)
            fprintf(opt->log, "%sadaptive subdivision: %d rounds, %zu -> %zu elements, %llu shots in all\n",
                    opt->log_prefix ? opt->log_prefix : "", as.rounds, as.elems_in, as.elems_out,
                    (unsigned long long)as.shots);
    } else {
        st = tb_rad_solver_create(&r.mesh, NULL, &ro, &r.solver);
        if (ex) /* one process short of memory stops them all */
            st = ex->agree_status(ex->ctx, st);
        if (st)
            goto done;
        const tb_rad_persist *pe = opt->persist;
        if (pe && pe->load && (st = tb__rad_restore(pe, r.solver)))
            goto done;
        uint64_t every = r.mesh.nelems / 20 ? r.mesh.nelems / 20 : 1;
        if (r.rep.ref && (st = tb__rad_report_row(&r.rep, r.solver)))
            goto done;
        if (pe) {
            /* after every shot: the persist decides when to save */
            tb__rad_shot_hook hook = {.rep = r.rep.ref ? &r.rep : NULL, .every = every, .persist = pe};
            if ((st = tb_rad_solver_run(r.solver, &opt->stop, tb__rad_on_shot, &hook, 1)))
                goto done;
            if (hook.rep && hook.n % every != 0 && (st = tb__rad_report_row(&r.rep, r.solver)))
                goto done;
            if (pe->save && (st = pe->save(pe->ctx, r.solver, NULL, 0, tb_rad_solver_shots(r.solver), true)))
                goto done;
        } else if ((st = tb_rad_solver_run(r.solver, &opt->stop, r.rep.ref ? tb__rad_report_row : NULL, &r.rep,
                                           every)))
            goto done;
    }
    int nthreads = opt->threads > 0 ? opt->threads : omp_get_max_threads();
    /* every process's share of the work in the stats (collective); then
     * rank 0 alone writes */
    if (ex && ex->report && (st = ex->report(ex->ctx)))
        goto done;
    if (!root)
        goto result;
    if ((st = tb__rad_provenance(&r, scene_path, &ro, &mo, opt, nthreads)))
        goto done;
    if (opt->image_path) {
        double nodes0 = tb__rad_nodes_visited(), leaves0 = tb__rad_leaf_tests();
        if ((st = tb_rad_render_image(r.solver, r.scene, opt->spp, &r.img)) ||
            (st = tb_provenance_to_attrs(&r.prov, r.img)))
            goto done;
        if (tb_stats_enabled()) {
            tb_stats_set_value(TB_RAD_IMAGE_NODES_KEY, tb__rad_nodes_visited() - nodes0);
            tb_stats_set_value(TB_RAD_IMAGE_LEAF_KEY, tb__rad_leaf_tests() - leaves0);
        }
    }
    tb__rad_where where = tb__rad_where_of(opt, &ro, r.scene->nlights);
    if (opt->stats_path && (st = tb__rad_stats(&r, opt->stats_path, t_mesh, nthreads, &as, &where)))
        goto done;

    /* outputs, each all-or-nothing */
    if (opt->patches_path && (st = tb_rad_write_patches(r.solver, opt->patches_path)))
        goto done;
    if (opt->mesh_path && (st = tb__rad_write_mesh(r.solver, opt->mesh_path, &r.prov)))
        goto done;
    if (opt->report_path &&
        (st = tb__write_text(opt->report_path, "seconds,shots,shots_per_n,unshot_fraction,nrmse,nrmse_ambient\n",
                             r.rep.buf, r.rep.len)))
        goto done;
    if (opt->image_path && (st = tb_image_write_exposed(opt->image_path, r.img, opt->exposure)))
        goto done;
result:
    if (out) {
        *out = (tb_rad_render_result){
            .elements = r.mesh.nelems,
            .vertices = r.mesh.nverts,
            .shots = adaptive ? as.shots : tb_rad_solver_shots(r.solver),
            .seconds = adaptive ? as.seconds : tb_rad_solver_seconds(r.solver),
            .unshot_fraction = tb_rad_unshot_fraction(r.solver),
            .threads = nthreads,
            .spectral = r.mesh.spectral,
            .batch = ro.batch != NULL,
        };
    }
done:
    tb__rad_run_free(&r);
    return st;
}
