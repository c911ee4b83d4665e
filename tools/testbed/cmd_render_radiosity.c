/* `testbed render SCENE.mid --method radiosity`: progressive-refinement
 * radiosity (host/radiosity/radiosity.h; docs/radiosity.md). Called by
 * tb_cmd_render (cmd_render.c) when --method radiosity is given. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <omp.h>

#include "commands.h"
#include "host/gpu/formfactor.h"
#include "host/gpu/gpu.h"
#include "host/radiosity/adaptive.h"
#include "host/radiosity/radiosity.h"
#include "host/render/scene.h"
#include "util/base/outfile.h"
#include "util/image/image.h"
#include "util/stats/provenance.h"
#include "util/stats/stats.h"

#define TB__RAD_STR2(x) #x
#define TB__RAD_STR(x) TB__RAD_STR2(x)

static void tb__rad_usage(FILE *out)
{
    fprintf(out,
            "usage: testbed render SCENE.mid --method radiosity [-o IMAGE] [--patches FILE.csv]\n"
            "                      [--mesh-out FILE.ply|.gltf|.glb] [options]\n"
            "Progressive-refinement radiosity (docs/radiosity.md). -o is optional when --patches or\n"
            "--mesh-out is given (scenes without a camera). Light comes from emitting surfaces and from the\n"
            "scene's point, spot and directional lights (IES included), each shot once, directly, with shadows.\n"
            "  -o IMAGE              the solution from the scene camera (.png, .exr, .pfm, .rle), Gouraud-shaded\n"
            "  --patches FILE.csv    one row per element: element,object,area,cx,cy,cz,nx,ny,nz, the radiosity\n"
            "                        per channel (b_r,b_g,b_b or b_<nm>), then the unshot radiosity (u_...); W/m^2;\n"
            "                        with --patch-edge/--patch-area a last column `patch` (the element's patch)\n"
            "  --mesh-out FILE       the solved mesh with vertex colours, by extension: .ply (binary PLY), .gltf\n"
            "                        (glTF 2.0, buffer embedded as base64) or .glb (binary glTF); colours are\n"
            "                        radiance B/pi scaled so the mean non-emitting luminance is 0.18, clamped\n"
            "  --formfactor M        raycast (default; Wallace et al. 1989, receivers at vertices) | hemicube\n"
            "  --backend B           ray-cast form factors on cpu (default), vulkan (the form-factor kernel,\n"
            "                        lavapipe included; fails if there is no device) or auto (Vulkan on a real GPU)\n"
            "  --device N            Vulkan device N (testbed devices lists them)\n"
            "  --samples N           ray cast: sample points per shooter (default %d)\n"
            "  --hemicube-res N      hemicube: top-face resolution (default %d)\n"
            "  --threshold X         stop when the unshot fraction of emitted power is below X (default %g)\n"
            "  --time-budget S       stop after S seconds of shooting\n"
            "  --max-shots N         stop after N shots\n"
            "  --max-edge L          longest element edge, scene units (default, when neither --max-edge nor\n"
            "                        --max-area is given: the scene's bounding-box diagonal / %d; 0: faces whole)\n"
            "  --max-area A          largest element area, scene units^2 (alone: no edge limit besides sqrt(A))\n"
            "  --patch-edge L        two levels (Cohen et al. 1986): cut faces into patches with edges up to L,\n"
            "                        then each patch into elements (--max-edge/--max-area, which L must not be\n"
            "                        below); patches shoot (sample points over the whole patch, or the hemicube at\n"
            "                        its centroid), elements receive and are displayed and written (default: one\n"
            "                        level, every element shoots)\n"
            "  --patch-area A        two levels: largest patch area, scene units^2 (like --patch-edge sqrt(A))\n"
            "  --adapt X             adaptive subdivision (Cohen et al. 1986): after solving, split elements whose\n"
            "                        corners' reflected luminance differs by more than X times the brightest\n"
            "                        element's, keep the mesh conforming, gather for the new vertices, continue\n"
            "  --adapt-levels N      --adapt: at most N splits below an initial element, one per round (default %d)\n"
            "  --min-area A          --adapt: never split an element of area A or less (scene units^2)\n"
            "  --threads N           OpenMP threads (the solution does not depend on it)\n"
            "  --seed N              seed of the shooters' sample points (default 0)\n"
            "  --spp N               image: rays per pixel on a regular sub-grid (default 4)\n"
            "  --exposure STOPS      PNG/RLE only: scale by 2^STOPS (default: mean luminance to 0.18)\n"
            "  --report FILE.csv     with --reference REF.csv (a --patches file of the same mesh): rows of\n"
            "                        seconds,shots,shots_per_n,unshot_fraction,nrmse,nrmse_ambient (the RMS\n"
            "                        error over the reference's RMS reflected radiosity B - E)\n"
            "  --stats FILE.json     counters, times and provenance\n",
            TB_RAD_DEFAULT_SAMPLES, TB_RAD_DEFAULT_HEMICUBE_RES, TB_RAD_DEFAULT_THRESHOLD, TB_RAD_DEFAULT_EDGE_DIVISIONS,
            TB_RAD_ADAPT_DEFAULT_LEVELS);
}

static int tb__rad_fail(const char *fmt, const char *arg)
{
    fprintf(stderr, "testbed render: ");
    fprintf(stderr, fmt, arg);
    fprintf(stderr, "\n");
    return TB_EXIT_FAIL;
}

static bool tb__rad_long(const char *s, long lo, long hi, long *out)
{
    char *end;
    long v = strtol(s, &end, 10);
    if (end == s || *end || v < lo || v > hi)
        return false;
    *out = v;
    return true;
}

static bool tb__rad_double(const char *s, double lo, double hi, double *out)
{
    char *end;
    double v = strtod(s, &end);
    if (end == s || *end || !(v >= lo && v <= hi))
        return false;
    *out = v;
    return true;
}

/* The --report rows, kept in memory and written at the end (all or nothing). */
typedef struct tb__rad_report {
    const double *ref; /* nelems * nc */
    size_t n;
    int nc;
    char *buf;
    size_t len, cap;
    double *b;
} tb__rad_report;

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

int tb_cmd_render_radiosity(int argc, char **argv)
{
    if (tb_wants_help(argc, argv)) {
        tb__rad_usage(stdout);
        return TB_EXIT_OK;
    }
    const char *scene_path = NULL, *out_path = NULL, *patches_path = NULL, *mesh_path = NULL, *stats_path = NULL,
               *report_path = NULL, *ref_path = NULL;
    tb_rad_options ro = {0};
    tb_rad_mesh_options mo = {0};
    tb_rad_stop stop = {.threshold = TB_RAD_DEFAULT_THRESHOLD, .progress = true};
    tb_rad_adapt_options ao = {0};
    tb_rad_adapt_stats as = {0};
    int threads = 0, spp = 4, gdevice = -1;
    const char *backend = "cpu";
    double exposure = NAN;
    bool size_given = false; /* --max-edge or --max-area: else the default element size */
    double patch_edge = 0.0, patch_area = 0.0;
    long v;
    double d;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        bool has = i + 1 < argc;
        const char *nx = has ? argv[i + 1] : "";
        if (!strcmp(a, "-o") && has)
            out_path = argv[++i];
        else if (!strcmp(a, "--method") && has) {
            if (strcmp(argv[++i], "radiosity") != 0)
                return tb__rad_fail("unknown --method '%s' here", argv[i]), TB_EXIT_USAGE;
        } else if (!strcmp(a, "--patches") && has)
            patches_path = argv[++i];
        else if (!strcmp(a, "--mesh-out") && has)
            mesh_path = argv[++i];
        else if (!strcmp(a, "--formfactor") && has) {
            const char *m = argv[++i];
            if (!strcmp(m, "raycast"))
                ro.ff = TB_RAD_FF_RAYCAST;
            else if (!strcmp(m, "hemicube"))
                ro.ff = TB_RAD_FF_HEMICUBE;
            else
                return tb__rad_fail("unknown --formfactor '%s' (raycast, hemicube)", m), TB_EXIT_USAGE;
        } else if (!strcmp(a, "--samples") && has) {
            if (!tb__rad_long(nx, 1, 65536, &v))
                return tb__rad_fail("bad --samples '%s' (1..65536)", nx), TB_EXIT_USAGE;
            ro.samples = (int)v, i++;
        } else if (!strcmp(a, "--hemicube-res") && has) {
            if (!tb__rad_long(nx, 2, 8192, &v))
                return tb__rad_fail("bad --hemicube-res '%s' (2..8192)", nx), TB_EXIT_USAGE;
            ro.hemicube_res = (int)v, i++;
        } else if (!strcmp(a, "--threshold") && has) {
            if (!tb__rad_double(nx, 1e-300, 1.0, &d) || !(d < 1.0))
                return tb__rad_fail("bad --threshold '%s' (0 < X < 1)", nx), TB_EXIT_USAGE;
            stop.threshold = d, i++;
        } else if (!strcmp(a, "--time-budget") && has) {
            if (!tb__rad_double(nx, 1e-300, 1e9, &d))
                return tb__rad_fail("bad --time-budget '%s' (seconds > 0)", nx), TB_EXIT_USAGE;
            stop.time_budget = d, i++;
        } else if (!strcmp(a, "--max-shots") && has) {
            if (!tb__rad_long(nx, 1, 0x7fffffffL, &v))
                return tb__rad_fail("bad --max-shots '%s'", nx), TB_EXIT_USAGE;
            stop.max_shots = (uint64_t)v, i++;
        } else if (!strcmp(a, "--max-edge") && has) {
            if (!tb__rad_double(nx, 0, 1e30, &d))
                return tb__rad_fail("bad --max-edge '%s' (>= 0; 0: faces whole)", nx), TB_EXIT_USAGE;
            mo.max_edge = d, size_given = true, i++;
        } else if (!strcmp(a, "--max-area") && has) {
            if (!tb__rad_double(nx, 1e-300, 1e30, &d))
                return tb__rad_fail("bad --max-area '%s' (> 0)", nx), TB_EXIT_USAGE;
            mo.max_area = d, size_given = true, i++;
        } else if (!strcmp(a, "--patch-edge") && has) {
            if (!tb__rad_double(nx, 1e-300, 1e30, &d))
                return tb__rad_fail("bad --patch-edge '%s' (> 0)", nx), TB_EXIT_USAGE;
            patch_edge = d, i++;
        } else if (!strcmp(a, "--patch-area") && has) {
            if (!tb__rad_double(nx, 1e-300, 1e30, &d))
                return tb__rad_fail("bad --patch-area '%s' (> 0)", nx), TB_EXIT_USAGE;
            patch_area = d, i++;
        } else if (!strcmp(a, "--threads") && has) {
            if (!tb__rad_long(nx, 0, 4096, &v))
                return tb__rad_fail("bad --threads '%s' (0..4096)", nx), TB_EXIT_USAGE;
            threads = (int)v, i++;
        } else if (!strcmp(a, "--adapt") && has) {
            if (!tb__rad_double(nx, 1e-300, 1e30, &d))
                return tb__rad_fail("bad --adapt '%s' (> 0)", nx), TB_EXIT_USAGE;
            ao.threshold = d, i++;
        } else if (!strcmp(a, "--adapt-levels") && has) {
            if (!tb__rad_long(nx, 1, TB_RAD_ADAPT_MAX_LEVELS, &v))
                return tb__rad_fail("bad --adapt-levels '%s' (1..60)", nx), TB_EXIT_USAGE;
            ao.max_levels = (int)v, i++;
        } else if (!strcmp(a, "--min-area") && has) {
            if (!tb__rad_double(nx, 0, 1e30, &d))
                return tb__rad_fail("bad --min-area '%s' (>= 0)", nx), TB_EXIT_USAGE;
            ao.min_area = d, i++;
        } else if (!strcmp(a, "--seed") && has) {
            char *end;
            unsigned long long s = strtoull(argv[++i], &end, 10);
            if (*end || end == argv[i] || argv[i][0] == '-')
                return tb__rad_fail("bad --seed '%s'", argv[i]), TB_EXIT_USAGE;
            ro.seed = s;
        } else if (!strcmp(a, "--spp") && has) {
            if (!tb__rad_long(nx, 1, 1024, &v))
                return tb__rad_fail("bad --spp '%s' (1..1024)", nx), TB_EXIT_USAGE;
            spp = (int)v, i++;
        } else if (!strcmp(a, "--exposure") && has) {
            if (!tb__rad_double(nx, -1e3, 1e3, &d))
                return tb__rad_fail("bad --exposure '%s'", nx), TB_EXIT_USAGE;
            exposure = d, i++;
        } else if (!strcmp(a, "--backend") && has)
            backend = argv[++i];
        else if (!strcmp(a, "--device") && has) {
            if (!tb__rad_long(nx, 0, 1024, &v))
                return tb__rad_fail("bad --device '%s'", nx), TB_EXIT_USAGE;
            gdevice = (int)v, i++;
        } else if (!strcmp(a, "--stats") && has)
            stats_path = argv[++i];
        else if (!strcmp(a, "--report") && has)
            report_path = argv[++i];
        else if (!strcmp(a, "--reference") && has)
            ref_path = argv[++i];
        else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "testbed render: bad or incomplete option '%s'\n", a);
            tb__rad_usage(stderr);
            return TB_EXIT_USAGE;
        } else if (!scene_path)
            scene_path = a;
        else
            return tb__rad_fail("unexpected argument '%s'", a), TB_EXIT_USAGE;
    }
    if (!scene_path) {
        tb__rad_usage(stderr);
        return TB_EXIT_USAGE;
    }
    if (!out_path && !patches_path && !mesh_path)
        return tb__rad_fail("%s", "nothing to write: give -o IMAGE, --patches FILE.csv or --mesh-out FILE.ply|.gltf|.glb"),
               TB_EXIT_USAGE;
    tb_image_format fmt = TB_IMAGE_UNKNOWN;
    if (out_path && (fmt = tb_image_format_from_path(out_path)) == TB_IMAGE_UNKNOWN)
        return tb__rad_fail("unknown image format of '%s' (.png, .exr, .pfm, .rle)", out_path), TB_EXIT_USAGE;
    tb_rad_mesh_format mesh_fmt = mesh_path ? tb_rad_mesh_format_from_path(mesh_path) : TB_RAD_MESH_UNKNOWN;
    if (mesh_path && mesh_fmt == TB_RAD_MESH_UNKNOWN)
        return tb__rad_fail("--mesh-out '%s': unknown mesh format (.ply, .gltf, .glb)", mesh_path), TB_EXIT_USAGE;
    if (!report_path != !ref_path)
        return tb__rad_fail("%s", "--report and --reference go together"), TB_EXIT_USAGE;
    if (!(ao.threshold > 0) && (ao.max_levels || ao.min_area > 0))
        return tb__rad_fail("%s", "--adapt-levels and --min-area go with --adapt"), TB_EXIT_USAGE;
    if (ao.threshold > 0 && report_path)
        return tb__rad_fail("%s", "--report compares with a reference of the same mesh: not with --adapt"),
               TB_EXIT_USAGE;
    if (ro.ff == TB_RAD_FF_HEMICUBE && ro.samples)
        return tb__rad_fail("%s", "--samples is for --formfactor raycast"), TB_EXIT_USAGE;
    if (ro.ff == TB_RAD_FF_RAYCAST && ro.hemicube_res)
        return tb__rad_fail("%s", "--hemicube-res is for --formfactor hemicube"), TB_EXIT_USAGE;
    tb_gpu_mode gmode;
    if (tb_gpu_mode_parse(backend, &gmode))
        return tb__rad_fail("--backend must be cpu, vulkan or auto, not '%s'", backend), TB_EXIT_USAGE;
    if (gmode == TB_GPU_MODE_CPU && gdevice >= 0)
        gmode = TB_GPU_MODE_VULKAN; /* --device implies Vulkan, as for the ray tracer */
    if (gmode != TB_GPU_MODE_CPU && ro.ff == TB_RAD_FF_HEMICUBE)
        return tb__rad_fail("%s", "--backend vulkan runs ray-cast form factors: not with --formfactor hemicube"),
               TB_EXIT_USAGE;
    if (threads > 0)
        omp_set_num_threads(threads);

    int rc = TB_EXIT_FAIL;
    tb_scene *scene = NULL;
    tb_rad_mesh mesh;
    tb_rad_mesh_init(&mesh);
    tb_rad_solver *solver = NULL;
    tb_image *img = NULL;
    tb_gpu_session gsess = {0};
    tb_gpu_ff_scene *gscene = NULL;
    tb_ff_polygon *gpolys = NULL;
    tb__rad_report rep = {0};
    double *ref = NULL;
    tb_status st;
    tb_scene_options so = {.no_accel = true, .threads = threads};
    if ((st = tb_scene_load(scene_path, &so, &scene)))
        goto fail;
    if (out_path && !scene->has_camera) {
        tb__rad_fail("%s: the scene has no camera: use --patches or --mesh-out instead of -o", scene_path);
        goto done;
    }
    if (!size_given)
        mo = tb_rad_default_mesh_options(scene);
    mo.patch_edge = patch_edge, mo.patch_area = patch_area;
    double t_mesh = 1e-9 * (double)tb_stats_now_ns();
    if ((st = tb_rad_mesh_from_scene(scene, &mo, &mesh)))
        goto fail;
    t_mesh = 1e-9 * (double)tb_stats_now_ns() - t_mesh;
    if (ref_path) {
        size_t nrows;
        int ncols;
        if ((st = tb_rad_read_patches(ref_path, &nrows, &ncols, &ref)))
            goto fail;
        if (nrows != mesh.nelems || ncols != mesh.nchannels) {
            fprintf(stderr,
                    "testbed render: --reference %s has %zu elements x %d channels, this mesh %zu x %d "
                    "(use the same scene and meshing options)\n",
                    ref_path, nrows, ncols, mesh.nelems, mesh.nchannels);
            goto done;
        }
        rep.ref = ref, rep.n = mesh.nelems, rep.nc = mesh.nchannels;
        rep.b = malloc(sizeof(double) * TB_CHANNELS_MAX);
        if (!rep.b) {
            st = tb_error(TB_ERR_NOMEM, "out of memory");
            goto fail;
        }
    }
    if (gmode != TB_GPU_MODE_CPU) {
        if ((st = tb_gpu_backend_choose(gmode, gdevice, false, &gsess)))
            goto fail;
        fprintf(stderr, "testbed render: backend %s: %s\n", tb_gpu_backend_name(gsess.backend), gsess.reason);
        if (gsess.backend == TB_GPU_BACKEND_VULKAN) {
            gpolys = malloc(mesh.nelems * sizeof *gpolys);
            if (!gpolys) {
                st = tb_error(TB_ERR_NOMEM, "out of memory");
                goto fail;
            }
            /* the same occluders as the CPU path: the room's walls cannot occlude */
            size_t nocc = tb_rad_mesh_occluders(&mesh, gpolys);
            gscene = tb_gpu_ff_scene_create(gsess.device, gpolys, nocc);
            if (!gscene) {
                st = TB_ERR_DEVICE;
                goto fail;
            }
            ro.batch = tb_gpu_ff_batch;
            ro.batch_ctx = gscene;
        }
    }
    char size[96];
    if (mo.max_edge > 0 && mo.max_area > 0)
        snprintf(size, sizeof size, "max edge %g, max area %g", mo.max_edge, mo.max_area);
    else if (mo.max_area > 0)
        snprintf(size, sizeof size, "max area %g", mo.max_area);
    else if (mo.max_edge > 0)
        snprintf(size, sizeof size, "max edge %g%s", mo.max_edge,
                 size_given ? "" : " (default: bounding-box diagonal / " TB__RAD_STR(TB_RAD_DEFAULT_EDGE_DIVISIONS) ")");
    else
        snprintf(size, sizeof size, "faces whole");
    fprintf(stderr, "testbed render: radiosity on %s: %zu elements (%s), %zu vertices, %d channels (%s), %s\n",
            scene_path, mesh.nelems, size, mesh.nverts, mesh.nchannels, mesh.spectral ? "spectral" : "rgb",
            ro.ff == TB_RAD_FF_HEMICUBE ? "hemicube" : "ray cast");
    if (mesh.npatches > 0)
        fprintf(stderr, "testbed render: %zu patches (patch edge %g, area %g) shoot; the elements receive\n",
                mesh.npatches, mo.patch_edge, mo.patch_area);
    bool emits = false;
    for (size_t k = 0; k < mesh.nelems * (size_t)mesh.nchannels && !emits; k++)
        emits = mesh.emission[k] > 0.0f;
    if (!emits && scene->nlights == 0)
        fprintf(stderr, "testbed render: note: no surface or light of %s emits: the solution is black\n", scene_path);
    ro.lights = scene->lights; /* the scene outlives the solver (IES tables) */
    ro.nlights = scene->nlights;
    if (scene->nlights > 0)
        fprintf(stderr, "testbed render: %d point, spot or directional light%s shot directly (docs/radiosity.md)\n",
                scene->nlights, scene->nlights == 1 ? "" : "s");
    if (ao.threshold > 0) {
        /* host/radiosity/adaptive.h: mesh becomes the refined mesh */
        if ((st = tb_rad_adapt_solve(&mesh, &ro, &stop, &ao, &solver, &as)))
            goto fail;
        fprintf(stderr, "testbed render: adaptive subdivision: %d rounds, %zu -> %zu elements, %llu shots in all\n",
                as.rounds, as.elems_in, as.elems_out, (unsigned long long)as.shots);
    } else {
        if ((st = tb_rad_solver_create(&mesh, NULL, &ro, &solver)))
            goto fail;
        uint64_t every = mesh.nelems / 20 ? mesh.nelems / 20 : 1;
        if (rep.ref && (st = tb__rad_report_row(&rep, solver)))
            goto fail;
        if ((st = tb_rad_solver_run(solver, &stop, rep.ref ? tb__rad_report_row : NULL, &rep, every)))
            goto fail;
    }
    double frac = tb_rad_unshot_fraction(solver);
    tb_rad_energy en = tb_rad_solver_energy(solver);
    int nthreads = threads > 0 ? threads : omp_get_max_threads();

    /* provenance for the image and the stats */
    tb_provenance prov;
    char **full = malloc(sizeof *full * ((size_t)argc + 2));
    if (!full) {
        st = tb_error(TB_ERR_NOMEM, "out of memory");
        goto fail;
    }
    full[0] = "testbed";
    memcpy(full + 1, argv, sizeof *full * (size_t)argc);
    full[argc + 1] = NULL;
    st = tb_provenance_init(&prov, argc + 1, full);
    free(full);
    if (st)
        goto fail;
    char opts[512];
    snprintf(opts, sizeof opts,
             "method=radiosity formfactor=%s samples=%d hemicube_res=%d threshold=%g time_budget=%g max_edge=%g "
             "max_area=%g max_angle=%g patch_edge=%g patch_area=%g spp=%d threads=%d colour=%s backend=%s adapt=%g "
             "adapt_levels=%d min_area=%g",
             ro.ff == TB_RAD_FF_HEMICUBE ? "hemicube" : "raycast", ro.samples ? ro.samples : TB_RAD_DEFAULT_SAMPLES,
             ro.hemicube_res ? ro.hemicube_res : TB_RAD_DEFAULT_HEMICUBE_RES, stop.threshold, stop.time_budget,
             mo.max_edge, mo.max_area, mo.max_angle, mo.patch_edge, mo.patch_area, spp, nthreads, mesh.spectral ? "spectral" : "rgb",
             ro.batch ? "vulkan" : "cpu", ao.threshold,
             ao.threshold > 0 ? (ao.max_levels ? ao.max_levels : TB_RAD_ADAPT_DEFAULT_LEVELS) : 0, ao.min_area);
    tb_provenance_set_seed(&prov, ro.seed);
    if (strcmp(scene_path, "-") != 0)
        st = tb_provenance_hash_file(&prov, scene_path);
    if (!st)
        st = tb_provenance_set_options(&prov, opts);
    if (!st && out_path) {
        st = tb_rad_render_image(solver, scene, spp, &img);
        if (!st)
            st = tb_provenance_to_attrs(&prov, img);
    }
    if (!st && stats_path) {
        struct {
            const char *k;
            double v;
        } kv[] = {{"seconds", tb_rad_solver_seconds(solver)},
                  {"mesh_seconds", t_mesh},
                  {"elements", (double)mesh.nelems},
                  {"vertices", (double)mesh.nverts},
                  {"patches", (double)tb_rad_solver_npatches(solver)},
                  {"shots", (double)tb_rad_solver_shots(solver)},
                  {"shots_per_element", (double)tb_rad_solver_shots(solver) / (double)mesh.nelems},
                  {"unshot_fraction", frac},
                  {"power_emitted", en.emitted},
                  {"power_absorbed", en.absorbed},
                  {"power_unshot", en.unshot},
                  {"power_escaped", en.escaped},
                  {"threads", (double)nthreads},
                  {"adapt_rounds", (double)as.rounds},
                  {"adapt_shots", (double)as.shots}};
        for (size_t k = 0; k < sizeof kv / sizeof kv[0] && !st; k++)
            st = tb_stats_set_value(kv[k].k, kv[k].v);
        if (!st)
            st = tb_stats_write_json_file(stats_path, &prov);
    }
    if (st)
        goto fail_prov;

    /* outputs, each all-or-nothing */
    if (patches_path && (st = tb_rad_write_patches(solver, patches_path)))
        goto fail_prov;
    if (mesh_path) {
        /* colours: mean non-emitting radiance (luminance) to 0.18 */
        double scale = tb_rad_display_scale(solver);
        switch (mesh_fmt) {
        case TB_RAD_MESH_PLY:
            st = tb_rad_write_ply(solver, mesh_path, scale, &prov);
            break;
        case TB_RAD_MESH_GLTF:
        case TB_RAD_MESH_GLB:
            st = tb_rad_write_gltf(solver, mesh_path, scale, mesh_fmt == TB_RAD_MESH_GLB, &prov);
            break;
        case TB_RAD_MESH_UNKNOWN:
            st = tb_error(TB_ERR_ARG, "%s: unknown mesh format", mesh_path);
            break;
        }
        if (st)
            goto fail_prov;
    }
    tb_provenance_free(&prov);
    if (report_path &&
        (st = tb__write_text(report_path, "seconds,shots,shots_per_n,unshot_fraction,nrmse,nrmse_ambient\n", rep.buf,
                             rep.len)))
        goto fail;
    if (out_path) {
        tb_image_write_options wo = {0};
        if (fmt == TB_IMAGE_PNG || fmt == TB_IMAGE_RLE) {
            if (isnan(exposure)) {
                double sum = 0.0;
                size_t npix = (size_t)img->width * (size_t)img->height;
                for (size_t k = 0; k < npix; k++) {
                    const float *px = img->pixels + k * 3;
                    sum += 0.2126 * px[0] + 0.7152 * px[1] + 0.0722 * px[2];
                }
                double mean = sum / (double)npix;
                exposure = mean > 0.0 ? log2(0.18 / mean) : 0.0;
            }
            wo.exposure = (float)exposure;
            char ex[64];
            snprintf(ex, sizeof ex, "%.6g", exposure);
            if ((st = tb_image_set_attr(img, "exposure", ex)))
                goto fail;
        }
        if ((st = tb_image_write(out_path, img, &wo)))
            goto fail;
    }
    printf("testbed render: %s: radiosity, %zu elements, %llu shots (%.2f N), unshot %.3g, %.3f s (%d threads, %s, "
           "%s)\n",
           scene_path, mesh.nelems, (unsigned long long)(ao.threshold > 0 ? as.shots : tb_rad_solver_shots(solver)),
           (double)(ao.threshold > 0 ? as.shots : tb_rad_solver_shots(solver)) / (double)mesh.nelems, frac,
           ao.threshold > 0 ? as.seconds : tb_rad_solver_seconds(solver), nthreads,
           mesh.spectral ? "spectral" : "rgb", ro.batch ? "vulkan" : "cpu");
    rc = TB_EXIT_OK;
    goto done;
fail_prov:
    tb_provenance_free(&prov);
fail:
    fprintf(stderr, "testbed render: %s\n", tb_last_error());
done:
    free(rep.buf);
    free(rep.b);
    free(ref);
    tb_image_free(img);
    tb_rad_solver_free(solver);
    tb_gpu_ff_scene_destroy(gscene);
    free(gpolys);
    if (gsess.backend == TB_GPU_BACKEND_VULKAN)
        tb_gpu_session_close(&gsess);
    tb_rad_mesh_free(&mesh);
    tb_scene_free(scene);
    return rc;
}
