/* `testbed render SCENE.mid --method radiosity`: progressive-refinement
 * radiosity (docs/radiosity.md). Options -> tb_rad_render_options -> one
 * library call (host/radiosity/render.h) -> one line of summary. Called by
 * tb_cmd_render (cmd_render.c) when --method radiosity is given. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli_util.h"
#include "commands.h"
#include "dist_cli.h"
#include "host/dist/radiosity.h"
#include "host/gpu/formfactor.h"
#include "host/gpu/gpu.h"
#include "host/radiosity/render.h"
#include "options.h"
#include "util/image/image.h"
#include "util/stats/stats.h"

#define TB__RAD_STR2(x) #x
#define TB__RAD_STR(x) TB__RAD_STR2(x)

/* The Vulkan form-factor kernel as the solver's batch backend (the
 * tb_rad_backend_fn of tb_rad_render). */
typedef struct tb__rad_gpu {
    tb_gpu_mode mode;
    int device;
    tb_gpu_session sess;
    tb_gpu_ff_scene *scene;
    tb_ff_polygon *polys;
} tb__rad_gpu;

static tb_status tb__rad_gpu_setup(void *user, const tb_rad_mesh *mesh, tb_rad_options *ro)
{
    tb__rad_gpu *g = user;
    tb_status st = tb_gpu_backend_choose(g->mode, g->device, false, &g->sess);
    if (st)
        return st;
    fprintf(stderr, "testbed render: backend %s: %s\n", tb_gpu_backend_name(g->sess.backend), g->sess.reason);
    if (g->sess.backend != TB_GPU_BACKEND_VULKAN)
        return TB_OK;
    g->polys = malloc(mesh->nelems * sizeof *g->polys);
    if (!g->polys)
        return tb_error(TB_ERR_NOMEM, "out of memory");
    /* the same occluders as the CPU path: the room's walls cannot occlude */
    size_t nocc = tb_rad_mesh_occluders(mesh, g->polys);
    g->scene = tb_gpu_ff_scene_create(g->sess.device, g->polys, nocc);
    if (!g->scene)
        return TB_ERR_DEVICE;
    ro->batch = tb_gpu_ff_batch;
    ro->batch_ctx = g->scene;
    return TB_OK;
}

static void tb__rad_gpu_close(tb__rad_gpu *g)
{
    tb_gpu_ff_scene_destroy(g->scene);
    free(g->polys);
    if (g->sess.backend == TB_GPU_BACKEND_VULKAN)
        tb_gpu_session_close(&g->sess);
}

int tb_cmd_render_radiosity(int argc, char **argv)
{
    tb_rad_render_options o = tb_rad_render_defaults();
    o.solver.samples = TB_RAD_DEFAULT_SAMPLES;
    o.solver.hemicube_res = TB_RAD_DEFAULT_HEMICUBE_RES;
    o.adapt.max_levels = TB_RAD_ADAPT_DEFAULT_LEVELS;
    o.stop.progress = true;
    int method = 0, ff = TB_RAD_FF_RAYCAST, backend = TB_GPU_MODE_CPU, device = -1, max_shots = 0;
    bool edge_given = false, area_given = false, samples_given = false, res_given = false, levels_given = false;
    bool device_given = false;
    uint64_t seed = 0;
    const char *ckpt_path = NULL, *resume_path = NULL;
    double ckpt_every = 5.0;
    bool several = false;
    static const tb_opt_choice methods[] = {{"radiosity", 0}, {NULL, 0}};
    static const tb_opt_choice ffs[] = {{"raycast", TB_RAD_FF_RAYCAST}, {"hemicube", TB_RAD_FF_HEMICUBE}, {NULL, 0}};
    const tb_opt opts[] = {
        {.short_name = 'o', .type = TB_OPT_STRING, .dest = &o.image_path, .metavar = "IMAGE",
         .help = "the solution from the scene camera (.png, .exr, .pfm, .rle), Gouraud-shaded"},
        {"method", .type = TB_OPT_CHOICE, .dest = &method, .choices = methods, .metavar = "radiosity",
         .help = "this renderer (testbed render --help: the ray tracer)"},
        {"patches", .type = TB_OPT_STRING, .dest = &o.patches_path, .metavar = "FILE.csv",
         .help = "one row per element: element,object,area,cx,cy,cz,nx,ny,nz, the radiosity\n"
                 "per channel (b_r,b_g,b_b or b_<nm>), then the unshot radiosity (u_...); W/m^2;\n"
                 "with --patch-edge/--patch-area a last column `patch` (the element's patch)"},
        {"mesh-out", .type = TB_OPT_STRING, .dest = &o.mesh_path, .metavar = "FILE",
         .help = "the solved mesh with vertex colours, by extension: .ply (binary PLY), .gltf\n"
                 "(glTF 2.0, buffer embedded as base64) or .glb (binary glTF); colours are\n"
                 "radiance B/pi scaled so the mean non-emitting luminance is 0.18, clamped"},
        {"formfactor", .type = TB_OPT_CHOICE, .dest = &ff, .choices = ffs, .metavar = "M",
         .help = "raycast (default; Wallace et al. 1989, receivers at vertices) | hemicube"},
        {"backend", .type = TB_OPT_CHOICE, .dest = &backend, .choices = tb_cli_backends, .metavar = "B",
         .help = "ray-cast form factors on cpu (default), vulkan (the form-factor kernel,\n"
                 "lavapipe included; fails if there is no device) or auto (Vulkan on a real GPU)"},
        {"device", .type = TB_OPT_INT, .dest = &device, .min = 0, .max = 1024, .metavar = "N", .seen = &device_given,
         .help = "Vulkan device N (testbed devices lists them)"},
        {"samples", .type = TB_OPT_INT, .dest = &o.solver.samples, .min = 1, .max = 65536, .metavar = "N",
         .seen = &samples_given, .help = "ray cast: sample points per shooter (default %D)"},
        {"hemicube-res", .type = TB_OPT_INT, .dest = &o.solver.hemicube_res, .min = 2, .max = 8192, .metavar = "N",
         .seen = &res_given, .help = "hemicube: top-face resolution (default %D)"},
        {"threshold", .type = TB_OPT_DOUBLE, .dest = &o.stop.threshold, .min = 0, .max = 1, .metavar = "X",
         .flags = TB_OPTF_OPEN_MIN | TB_OPTF_OPEN_MAX,
         .help = "stop when the unshot fraction of emitted power is below X (default %D)"},
        {"time-budget", .type = TB_OPT_DOUBLE, .dest = &o.stop.time_budget, .min = 0, .max = 1e9, .metavar = "S",
         .flags = TB_OPTF_OPEN_MIN, .help = "stop after S seconds of shooting"},
        {"max-shots", .type = TB_OPT_INT, .dest = &max_shots, .min = 1, .max = 0x7fffffff, .metavar = "N",
         .help = "stop after N shots"},
        {"max-edge", .type = TB_OPT_DOUBLE, .dest = &o.mesh.max_edge, .min = 0, .max = 1e30, .metavar = "L",
         .seen = &edge_given,
         .help = "longest element edge, scene units (default, when neither --max-edge nor\n"
                 "--max-area is given: the scene's bounding-box diagonal / " TB__RAD_STR(
                     TB_RAD_DEFAULT_EDGE_DIVISIONS) "; 0: faces whole)"},
        {"max-area", .type = TB_OPT_DOUBLE, .dest = &o.mesh.max_area, .min = 0, .max = 1e30, .metavar = "A",
         .flags = TB_OPTF_OPEN_MIN, .seen = &area_given,
         .help = "largest element area, scene units^2 (alone: no edge limit besides sqrt(A))"},
        {"patch-edge", .type = TB_OPT_DOUBLE, .dest = &o.mesh.patch_edge, .min = 0, .max = 1e30, .metavar = "L",
         .flags = TB_OPTF_OPEN_MIN,
         .help = "two levels (Cohen et al. 1986): cut faces into patches with edges up to L,\n"
                 "then each patch into elements (--max-edge/--max-area, which L must not be\n"
                 "below); patches shoot (sample points over the whole patch, or the hemicube at\n"
                 "its centroid), elements receive and are displayed and written (default: one\n"
                 "level, every element shoots)"},
        {"patch-area", .type = TB_OPT_DOUBLE, .dest = &o.mesh.patch_area, .min = 0, .max = 1e30, .metavar = "A",
         .flags = TB_OPTF_OPEN_MIN,
         .help = "two levels: largest patch area, scene units^2 (like --patch-edge sqrt(A))"},
        {"adapt", .type = TB_OPT_DOUBLE, .dest = &o.adapt.threshold, .min = 0, .max = 1e30, .metavar = "X",
         .flags = TB_OPTF_OPEN_MIN,
         .help = "adaptive subdivision (Cohen et al. 1986): after solving, split elements whose\n"
                 "corners' reflected luminance differs by more than X times the brightest\n"
                 "element's, keep the mesh conforming, gather for the new vertices, continue"},
        {"adapt-levels", .type = TB_OPT_INT, .dest = &o.adapt.max_levels, .min = 1, .max = TB_RAD_ADAPT_MAX_LEVELS,
         .metavar = "N", .seen = &levels_given,
         .help = "--adapt: at most N splits below an initial element, one per round (default %D)"},
        {"min-area", .type = TB_OPT_DOUBLE, .dest = &o.adapt.min_area, .min = 0, .max = 1e30, .metavar = "A",
         .help = "--adapt: never split an element of area A or less (scene units^2)"},
        {"threads", .type = TB_OPT_INT, .dest = &o.threads, .min = 0, .max = 4096, .metavar = "N",
         .help = "OpenMP threads (the solution does not depend on it)"},
        {"seed", .type = TB_OPT_UINT64, .dest = &seed, .metavar = "N",
         .help = "seed of the shooters' sample points (default %D)"},
        {"spp", .type = TB_OPT_INT, .dest = &o.spp, .min = 1, .max = 1024, .metavar = "N",
         .help = "image: rays per pixel on a regular sub-grid (default %D)"},
        {"exposure", .type = TB_OPT_DOUBLE, .dest = &o.exposure, .min = -1e3, .max = 1e3, .metavar = "STOPS",
         .help = "PNG/RLE only: scale by 2^STOPS (default: mean luminance to 0.18)"},
        {"report", .type = TB_OPT_STRING, .dest = &o.report_path, .metavar = "FILE.csv",
         .help = "with --reference REF.csv (a --patches file of the same mesh): rows of\n"
                 "seconds,shots,shots_per_n,unshot_fraction,nrmse,nrmse_ambient (the RMS\n"
                 "error over the reference's RMS reflected radiosity B - E)"},
        {"reference", .type = TB_OPT_STRING, .dest = &o.reference_path, .metavar = "REF.csv",
         .help = "the reference of --report"},
        {"several-shooters", .type = TB_OPT_FLAG, .dest = &several,
         .help = "under mpirun: one shooter per rank in flight (Recker et al. 1990):\n"
                 "faster, but another shooting order than one process (the result\n"
                 "depends on the rank count; docs/distributed.md); default: each\n"
                 "shot's receivers shared, the one-process result bit for bit"},
        {"checkpoint", .type = TB_OPT_STRING, .dest = &ckpt_path, .metavar = "FILE",
         .help = "save the solver's state (gathered and unshot radiosity, shots; with\n"
                 "--adapt also the refinement rounds) to FILE, atomically, every\n"
                 "--checkpoint-every seconds and after the last shot"},
        {"checkpoint-every", .type = TB_OPT_DOUBLE, .dest = &ckpt_every, .min = 0, .max = INFINITY,
         .metavar = "S", .help = "seconds between checkpoints (default %D; 0: after every shot)"},
        {"resume", .type = TB_OPT_STRING, .dest = &resume_path, .metavar = "FILE",
         .help = "continue the solve saved in FILE (same scene and options; --threshold\n"
                 "may drop, except with --adapt): the outputs equal an uninterrupted\n"
                 "run's bit for bit"},
        {"stats", .type = TB_OPT_STRING, .dest = &o.stats_path, .metavar = "FILE.json",
         .help = "counters, times and provenance"},
        {0},
    };
    const char *scene_path = NULL;
    const tb_cli cli = {
        .prog = "testbed render",
        .err = "testbed render: ",
        .usage = "SCENE.mid --method radiosity [-o IMAGE] [--patches FILE.csv]\n"
                 "                      [--mesh-out FILE.ply|.gltf|.glb] [options]",
        .intro = "Progressive-refinement radiosity (docs/radiosity.md). -o is optional when --patches or\n"
                 "--mesh-out is given (scenes without a camera). Light comes from emitting surfaces and from the\n"
                 "scene's point, spot and directional lights (IES included), each shot once, directly, with shadows.",
        .opts = opts,
        .pos = &scene_path,
        .max_pos = 1,
        .min_pos = 1,
        .missing = "no SCENE.mid given",
    };
    int npos, rc = tb_cli_parse(&cli, argc, argv, &npos);
    if (rc != TB_CLI_OK)
        return rc;
    o.solver.ff = (tb_rad_ff_method)ff;
    o.solver.seed = seed;
    o.stop.max_shots = (uint64_t)max_shots;
    o.mesh_given = edge_given || area_given;
    /* what the library would refuse with TB_ERR_ARG is a usage error here */
    if (!o.image_path && !o.patches_path && !o.mesh_path)
        return tb_cli_usage_error(&cli, "nothing to write: give -o IMAGE, --patches FILE.csv or --mesh-out "
                                        "FILE.ply|.gltf|.glb");
    if (o.image_path && tb_image_format_from_path(o.image_path) == TB_IMAGE_UNKNOWN)
        return tb_cli_usage_error(&cli, "unknown image format of '%s' (.png, .exr, .pfm, .rle)", o.image_path);
    if (o.mesh_path && tb_rad_mesh_format_from_path(o.mesh_path) == TB_RAD_MESH_UNKNOWN)
        return tb_cli_usage_error(&cli, "--mesh-out '%s': unknown mesh format (.ply, .gltf, .glb)", o.mesh_path);
    if (!o.report_path != !o.reference_path)
        return tb_cli_usage_error(&cli, "--report and --reference go together");
    if (!(o.adapt.threshold > 0) && (levels_given || o.adapt.min_area > 0))
        return tb_cli_usage_error(&cli, "--adapt-levels and --min-area go with --adapt");
    if (o.adapt.threshold > 0 && o.report_path)
        return tb_cli_usage_error(&cli, "--report compares with a reference of the same mesh: not with --adapt");
    if (ff == TB_RAD_FF_HEMICUBE && samples_given)
        return tb_cli_usage_error(&cli, "--samples is for --formfactor raycast");
    if (ff == TB_RAD_FF_RAYCAST && res_given)
        return tb_cli_usage_error(&cli, "--hemicube-res is for --formfactor hemicube");
    tb__rad_gpu gpu = {.mode = (tb_gpu_mode)backend, .device = device};
    if (gpu.mode == TB_GPU_MODE_CPU && device_given)
        gpu.mode = TB_GPU_MODE_VULKAN; /* --device implies Vulkan, as for the ray tracer */
    if (gpu.mode != TB_GPU_MODE_CPU && ff == TB_RAD_FF_HEMICUBE)
        return tb_cli_usage_error(&cli, "--backend vulkan runs ray-cast form factors: not with --formfactor hemicube");
    if (gpu.mode != TB_GPU_MODE_CPU) {
        o.backend = tb__rad_gpu_setup;
        o.backend_user = &gpu;
        o.backend_name = "vulkan";
    }
    /* under mpirun: every rank solves, each shot's receivers are shared */
    bool root = tb_dist_rank() == 0;
    tb_rad_exchange *ex = NULL;
    if (!tb_cli_dist_scene_ok("testbed render", scene_path))
        return TB_EXIT_FAIL;
    if (tb_dist_size() > 1) {
        if (gpu.mode != TB_GPU_MODE_CPU)
            return tb_cli_usage_error(&cli, "--backend vulkan solves in one process, not over %d ranks",
                                      tb_dist_size());
        if (ff == TB_RAD_FF_HEMICUBE && root)
            fprintf(stderr, "testbed render: note: hemicube form factors are not shared over ranks: every rank "
                            "computes all of them (use --formfactor raycast to divide the work)\n");
        if (!(ex = tb_dist_rad_exchange_create())) {
            fprintf(stderr, "testbed render: %s\n", tb_last_error());
            return TB_EXIT_FAIL;
        }
        ex->several = several;
        o.solver.exchange = ex;
    }
    tb_ckpt_rad ck = {.path = ckpt_path, .every = ckpt_every, .resume_path = resume_path};
    tb_rad_persist persist;
    if (ckpt_path || resume_path) {
        /* with --adapt the rounds depend on where each round stops: the
         * threshold and the shot limit are part of the job */
        static const char *const adapt_free[] = {"-o", "--threads", "--time-budget", "--checkpoint",
                                                 "--checkpoint-every", "--resume", "--stats", "--report",
                                                 "--reference", "--exposure", "--backend", "--device", "--patches",
                                                 "--mesh-out", NULL};
        const char *const *free_opts = o.adapt.threshold > 0 ? adapt_free : tb_cli_free_opts;
        if (!(ck.key = tb_cli_job_key(scene_path, argc, argv, free_opts))) {
            fprintf(stderr, "testbed render: %s\n", tb_last_error());
            tb_dist_rad_exchange_free(ex);
            return TB_EXIT_FAIL;
        }
        persist = tb_ckpt_rad_persist(&ck);
        o.persist = &persist;
    }
    if (root && tb_dist_size() > 1)
        tb_ckpt_on_term("testbed render");
    o.log = root ? stderr : NULL;
    o.log_prefix = "testbed render: ";
    o.stop.progress = o.stop.progress && root;

    /* the provenance records the whole command line */
    char **full = tb_cli_full_argv(argc, argv);
    if (!full) {
        fprintf(stderr, "testbed render: out of memory\n");
        tb_dist_rad_exchange_free(ex);
        return TB_EXIT_FAIL;
    }
    o.argc = argc + 1, o.argv = full;
    tb_rad_render_result res;
    const int stats_were = tb_cli_stats_where_written(o.stats_path);
    tb_status st = tb_rad_render(scene_path, &o, &res);
    tb_stats_set_enabled(stats_were);
    free(full);
    tb__rad_gpu_close(&gpu);
    tb_dist_rad_exchange_free(ex);
    tb_cli_dist_summary("testbed render", "receivers", st == TB_OK);
    if (st) {
        if (root)
            fprintf(stderr, "testbed render: %s\n", tb_last_error());
        return TB_EXIT_FAIL;
    }
    if (!root)
        return TB_EXIT_OK;
    printf("testbed render: %s: radiosity, %zu elements, %llu shots (%.2f N), unshot %.3g, %.3f s (%d threads, %s, "
           "%s)\n",
           scene_path, res.elements, (unsigned long long)res.shots, (double)res.shots / (double)res.elements,
           res.unshot_fraction, res.seconds, res.threads, res.spectral ? "spectral" : "rgb",
           res.batch ? "vulkan" : "cpu");
    return TB_EXIT_OK;
}
