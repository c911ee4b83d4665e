/* `testbed trace SCENE.mid --rays RAYS --hits HITS`: a ray server for scripts
 * and for comparisons with other tools (docs/trace.md). Reads N rays of 32
 * bytes, writes N hits of 32 bytes, all little-endian:
 *
 *   RAYS record: float32 ox oy oz tmin dx dy dz tmax
 *   HITS record: float32 t, uint32 object, uint32 face, float32 u v, float32 nx ny nz
 *
 * The closest hit of every ray through the scene's acceleration structure
 * (host/render/scene.h), rays spread over OpenMP threads; each ray is
 * independent, so the HITS file is the same for any thread count. Only the
 * traversal is timed for the stats JSON (not reading, loading or building). */
#include <errno.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "cli_util.h"
#include "commands.h"
#include "host/gpu/intersect.h"
#include "host/render/scene.h"
#include "util/base/outfile.h"
#include "util/stats/provenance.h"
#include "util/stats/stats.h"

TB_STAT_COUNTER(tb__n_trace_rays, "Trace/rays");
TB_STAT_COUNTER(tb__n_trace_hits, "Trace/hits");
TB_STAT_COUNTER(tb__n_trace_invalid, "Trace/invalid rays");

/* Bytes per RAYS and HITS record. */
#define TB__RECORD 32

/* Rays read, traced and written per round (32 MiB of rays, 32 MiB of hits). */
#define TB__CHUNK ((size_t)1 << 20)

/* The object and face of a miss. */
#define TB__MISS UINT32_MAX

/* Little-endian 32-bit words to native and back (a no-op on little-endian hosts). */
static void tb__le32_words(void *p, size_t nwords)
{
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
    uint32_t *w = p;
    for (size_t i = 0; i < nwords; i++)
        w[i] = __builtin_bswap32(w[i]);
#else
    (void)p;
    (void)nwords;
#endif
}

static int tb__fail(const char *fmt, const char *arg)
{
    fprintf(stderr, "testbed trace: error: ");
    fprintf(stderr, fmt, arg);
    fprintf(stderr, "\n");
    return TB_EXIT_FAIL;
}

/* Process CPU time in seconds (all threads). */
static double tb__cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Traces rays[0..n) into hits[0..n); returns the traversal's wall seconds,
 * adds its process CPU seconds to *cpu and the hits and invalid rays found. */
static double tb__trace_chunk(const tb_scene *s, const tb_ray *rays, tb_hit *hits, size_t n, int threads,
                              uint64_t *nhits, uint64_t *ninvalid, double *cpu)
{
    uint64_t h = 0, bad = 0;
    /* Start the thread team outside the timed region (the first parallel
     * region creates the threads, a few milliseconds). */
#pragma omp parallel num_threads(threads)
    {
        (void)0;
    }
    double c0 = tb__cpu_seconds();
    int64_t t0 = tb_stats_now_ns();
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1024) reduction(+ : h, bad)
    for (size_t i = 0; i < n; i++) {
        tb_hit hit = {INFINITY, TB__MISS, TB__MISS, 0.0f, 0.0f, {0.0f, 0.0f, 0.0f}};
        if (!tb_ray_is_valid(&rays[i]))
            bad++;
        else if (tb_scene_intersect(s, &rays[i], &hit))
            h++;
        hits[i] = hit;
    }
    double sec = (double)(tb_stats_now_ns() - t0) * 1e-9;
    *cpu += tb__cpu_seconds() - c0;
    *nhits += h;
    *ninvalid += bad;
    return sec;
}

int tb_cmd_trace(int argc, char **argv)
{
    const char *scene_path = NULL, *rays_path = NULL, *hits_path = NULL, *stats_path = NULL;
    int backend = TB_GPU_MODE_AUTO, accel = TB_ACCEL_BVH, threads = 0;
    bool verbose = false;
    const tb_opt opts[] = {
        {"rays", .type = TB_OPT_STRING, .dest = &rays_path, .metavar = "RAYS", .help = "input rays (required)"},
        {"hits", .type = TB_OPT_STRING, .dest = &hits_path, .metavar = "HITS", .help = "output hits (required)"},
        {"backend", .type = TB_OPT_CHOICE, .dest = &backend, .choices = tb_cli_backends, .metavar = "B",
         .help = "cpu (the reference path), vulkan or auto (default: %D).\n"
                 "vulkan runs the Vulkan intersect kernel (host/gpu/intersect.h) on any\n"
                 "device, lavapipe included (fails if there is none); auto uses it only on\n"
                 "a real GPU. Every primitive kind and CSG tree runs on the device (-v and\n"
                 "--stats report the objects on the GPU and any routed to the CPU path; a\n"
                 "CSG tree beyond the kernel's bounds is refused). Hits agree with cpu within\n"
                 "docs/accuracy.md's float tolerances, not byte for byte."},
        {"accel", .type = TB_OPT_CHOICE, .dest = &accel, .choices = tb_cli_accels, .metavar = "A",
         .help = "bvh (default), grid, or list (every reference tested: slow, for checks);\n"
                 "every structure gives byte-identical hits"},
        {"threads", .type = TB_OPT_INT, .dest = &threads, .min = 1, .max = 1024, .metavar = "N",
         .help = "OpenMP threads for the build and the traversal (default: OpenMP's)"},
        {"stats", .type = TB_OPT_STRING, .dest = &stats_path, .metavar = "FILE.json",
         .help = "write the run's statistics: \"rays\", \"seconds\" (wall clock) and\n"
                 "\"rays_per_second\" of the traversal alone (not reading, loading or\n"
                 "building), \"cpu_seconds\" (process CPU time of the traversal), \"hits\",\n"
                 "\"invalid_rays\", the provenance and the counters (util/stats)"},
        {"verbose", 'v', TB_OPT_FLAG, &verbose, .help = "print a summary of the scene on stderr"},
        {0},
    };
    const tb_cli cli = {
        .prog = "testbed trace",
        .err = "testbed trace: error: ",
        .usage = "SCENE.mid --rays RAYS --hits HITS [--backend cpu|vulkan|auto]\n"
                 "                     [--accel bvh|grid|list] [--threads N] [--stats FILE.json] [--verbose]",
        .intro = "\n"
                 "Traces every ray of the file RAYS through the scene and writes its closest hit to HITS\n"
                 "(docs/trace.md). All numbers are little-endian.\n"
                 "\n"
                 "  RAYS  N records of 32 bytes: float32 ox oy oz tmin dx dy dz tmax. The ray is o + t d\n"
                 "        for tmin <= t <= tmax; d need not be unit length (t is in units of |d|);\n"
                 "        tmax may be +inf. The file size must be a multiple of 32.\n"
                 "  HITS  N records of 32 bytes, in ray order: float32 t, uint32 object (0-based index of\n"
                 "        the top-level object in MID file order), uint32 face ID, float32 u, float32 v,\n"
                 "        float32 nx ny nz (unit geometric normal, world space, pointing out of the solid or\n"
                 "        to the front side of a polygon; never flipped toward the ray).\n"
                 "        A miss is t = +inf, object = face = 0xFFFFFFFF, u = v = 0, normal (0, 0, 0).\n"
                 "        Invalid rays (a NaN or infinite origin or direction, a zero direction, a NaN or\n"
                 "        infinite tmin, a NaN tmax, tmin > tmax) are written as misses and counted.\n"
                 "        HITS is written whole or not at all.\n"
                 "\n"
                 "options:",
        .opts = opts,
        .outro = "\n"
                 "Exit status: 0 on success, 1 for bad input (scene, ray file) or a failed write, 2 for a bad\n"
                 "command line.",
        .pos = &scene_path,
        .max_pos = 1,
    };
    int npos, prc = tb_cli_parse(&cli, argc, argv, &npos);
    if (prc != TB_CLI_OK)
        return prc;
    if (!scene_path || !rays_path || !hits_path)
        return tb_cli_usage_error(&cli, "needs SCENE.mid, --rays RAYS and --hits HITS");
    tb_accel_kind kind = (tb_accel_kind)accel;
    tb_gpu_mode gmode = (tb_gpu_mode)backend;
    if (threads > 0)
        omp_set_num_threads(threads);

    /* The ray file first: a malformed one fails before any work. */
    FILE *rf = fopen(rays_path, "rb");
    if (!rf) {
        fprintf(stderr, "testbed trace: error: cannot open rays file '%s': %s\n", rays_path, strerror(errno));
        return TB_EXIT_FAIL;
    }
    struct stat stt;
    if (fstat(fileno(rf), &stt) != 0 || !S_ISREG(stt.st_mode)) {
        fclose(rf);
        return tb__fail("rays file '%s' is not a regular file", rays_path);
    }
    uint64_t size = (uint64_t)stt.st_size;
    if (size % TB__RECORD != 0) {
        fclose(rf);
        fprintf(stderr,
                "testbed trace: error: rays file '%s' is %llu bytes, not a multiple of the 32-byte record "
                "(8 float32: ox oy oz tmin dx dy dz tmax)\n",
                rays_path, (unsigned long long)size);
        return TB_EXIT_FAIL;
    }
    uint64_t nrays = size / TB__RECORD;

    tb_scene_options so = {0};
    so.accel = kind;
    so.threads = (int)threads;
    tb_scene *scene;
    if (tb_scene_load(scene_path, &so, &scene)) {
        fclose(rf);
        fprintf(stderr, "%s\n", tb_last_error());
        return TB_EXIT_FAIL;
    }
    if (verbose)
        tb_scene_print_summary(scene, stderr);
    /* The Vulkan path (docs/gpu.md, "Intersect kernel"): kinds the kernel lacks are routed to the CPU. */
    tb_gpu_session gsess;
    tb_gpu_scene *gscene = NULL;
    char routed[512] = "";
    if (tb_gpu_backend_choose(gmode, -1, false, &gsess)) {
        fclose(rf);
        tb_scene_free(scene);
        return tb__fail("%s", tb_last_error());
    }
    if (verbose)
        fprintf(stderr, "backend: %s: %s\n", tb_gpu_backend_name(gsess.backend), gsess.reason);
    if (gsess.backend == TB_GPU_BACKEND_VULKAN) {
        gscene = tb_gpu_scene_create(gsess.device, scene);
        if (!gscene) {
            fclose(rf);
            tb_scene_free(scene);
            tb_gpu_session_close(&gsess);
            return tb__fail("--backend vulkan: %s", tb_last_error());
        }
        for (uint32_t i = 0, len = 0; i < scene->nobjects && len + 12 < sizeof routed; ++i)
            if (!tb_gpu_scene_object_on_gpu(gscene, i))
                len += (uint32_t)snprintf(routed + len, sizeof routed - len, "%s%u", len ? "," : "", i);
        tb_gpu_scene_info gi;
        tb_gpu_scene_get_info(gscene, &gi);
        if (verbose) {
            char lim[512];
            tb_gpu_limits_describe(tb_gpu_device_info_of(gsess.device), lim, sizeof lim);
            fprintf(stderr, "vulkan: device %s\n", lim);
        }
        if (verbose)
            fprintf(stderr,
                    "vulkan: %u objects on the GPU, %u routed (%llu triangles, %u spheres, %u cubes, %u "
                    "cylinders/cones/conics, %u pyramids/prisms/arches, %u tori)%s%s%s\n",
                    gi.gpu_objects, gi.cpu_objects, (unsigned long long)gi.gpu_triangles, gi.gpu_spheres,
                    gi.gpu_cubes, gi.gpu_quadrics, gi.gpu_planar, gi.gpu_tori, gi.cpu_objects ? ": [" : "", routed,
                    gi.cpu_objects ? "]" : "");
        /* Why, per routed object (the first feature the kernel lacks); a
         * few are enough to see what a scene needs. */
        for (uint32_t i = 0, shown = 0; verbose && i < scene->nobjects; ++i) {
            const char *why = tb_gpu_scene_object_route(gscene, i);
            if (!why)
                continue;
            if (shown < 20)
                fprintf(stderr, "vulkan: object %u on the CPU path: %s\n", i, why);
            else if (shown == 20)
                fprintf(stderr, "vulkan: (more routed objects not listed)\n");
            ++shown;
        }
    }

    size_t cap = nrays < TB__CHUNK ? (size_t)nrays : TB__CHUNK;
    tb_ray *rays = malloc(sizeof *rays * (cap ? cap : 1));
    tb_hit *hits = malloc(sizeof *hits * (cap ? cap : 1));
    tb_outfile of = {0};
    int rc = TB_EXIT_OK;
    if (!rays || !hits) {
        rc = tb__fail("out of memory for %s rays", "2^20");
        goto done;
    }
    if (tb_outfile_open(&of, hits_path)) {
        rc = tb__fail("%s", tb_last_error());
        goto done;
    }
    uint64_t done_rays = 0, nhits = 0, ninvalid = 0;
    double seconds = 0.0, cpu_seconds = 0.0;
    while (done_rays < nrays) {
        size_t n = nrays - done_rays < cap ? (size_t)(nrays - done_rays) : cap;
        if (fread(rays, TB__RECORD, n, rf) != n) {
            rc = tb__fail("rays file '%s' ended early (was it changed while being read?)", rays_path);
            break;
        }
        tb__le32_words(rays, n * 8);
        if (gscene) {
            double c0 = tb__cpu_seconds();
            int64_t t0 = tb_stats_now_ns();
            if (tb_gpu_intersect(gscene, rays, n, hits, NULL)) {
                rc = tb__fail("--backend vulkan: %s", tb_last_error());
                break;
            }
            seconds += (double)(tb_stats_now_ns() - t0) * 1e-9;
            cpu_seconds += tb__cpu_seconds() - c0;
            for (size_t i = 0; i < n; i++) {
                ninvalid += !tb_ray_is_valid(&rays[i]);
                nhits += hits[i].object != TB__MISS;
            }
        } else {
            seconds += tb__trace_chunk(scene, rays, hits, n, (int)(threads > 0 ? threads : omp_get_max_threads()),
                                       &nhits, &ninvalid, &cpu_seconds);
        }
        tb__le32_words(hits, n * 8);
        if (fwrite(hits, TB__RECORD, n, of.fp) != n) {
            rc = tb__fail("cannot write hits file '%s'", hits_path);
            break;
        }
        done_rays += n;
    }
    if (rc != TB_EXIT_OK)
        goto done;
    tb_stat_add(&tb__n_trace_rays, (int64_t)nrays);
    tb_stat_add(&tb__n_trace_hits, (int64_t)nhits);
    tb_stat_add(&tb__n_trace_invalid, (int64_t)ninvalid);
    double rps = nrays == 0 ? 0.0 : (seconds > 0.0 ? (double)nrays / seconds : NAN);
    int nthreads = threads > 0 ? (int)threads : omp_get_max_threads();
    /* The stats before the hits: a run whose report cannot be written leaves
     * no HITS file either. */
    if (stats_path) {
        tb_provenance prov;
        /* The command line as typed: "testbed" and the subcommand's arguments. */
        char **full = tb_cli_full_argv(argc, argv);
        tb_status st = full ? TB_OK : tb_error(TB_ERR_NOMEM, "out of memory");
        if (!st) {
            st = tb_provenance_init(&prov, argc + 1, full);
            free(full);
        }
        if (!st) {
            char opts[256];
            snprintf(opts, sizeof opts, "backend=%s accel=%s threads=%d", tb_gpu_backend_name(gsess.backend),
                     tb_accel_kind_name(kind), nthreads);
            if (strcmp(scene_path, "-") != 0)
                st = tb_provenance_hash_file(&prov, scene_path);
            if (!st)
                st = tb_provenance_set_options(&prov, opts);
            if (!st)
                st = tb_stats_set_value("rays", (double)nrays);
            if (!st)
                st = tb_stats_set_value("seconds", seconds);
            if (!st)
                st = tb_stats_set_value("rays_per_second", rps);
            if (!st)
                st = tb_stats_set_value("cpu_seconds", cpu_seconds);
            if (!st)
                st = tb_stats_set_value("hits", (double)nhits);
            if (!st)
                st = tb_stats_set_value("invalid_rays", (double)ninvalid);
            if (!st)
                st = tb_stats_set_string("backend", tb_gpu_backend_name(gsess.backend));
            if (!st && gscene) /* which objects the kernel did not run (routed to the CPU path) */
                st = tb_stats_set_string("routed_objects", routed);
            if (!st && gscene) {
                tb_gpu_scene_info gi;
                tb_gpu_scene_get_info(gscene, &gi);
                st = tb_stats_set_value("gpu_objects", (double)gi.gpu_objects);
                if (!st)
                    st = tb_stats_set_value("routed_object_count", (double)gi.cpu_objects);
                if (!st)
                    st = tb_gpu_limits_to_stats(tb_gpu_device_info_of(gsess.device));
            }
            if (!st)
                st = tb_stats_set_string("accel", tb_accel_kind_name(kind));
            if (!st)
                st = tb_stats_write_json_file(stats_path, &prov);
            tb_provenance_free(&prov);
        }
        if (st) {
            rc = tb__fail("stats: %s", tb_last_error());
            goto done;
        }
    }
    if (tb_outfile_commit(&of)) {
        rc = tb__fail("%s", tb_last_error());
        goto done;
    }
    printf("testbed trace: %llu rays, %llu hits, %llu invalid; traversal %.6f s, %.3f Mrays/s, %.3f Mrays per CPU "
           "second (%s, %s, %d threads)\n",
           (unsigned long long)nrays, (unsigned long long)nhits, (unsigned long long)ninvalid, seconds, rps * 1e-6,
           cpu_seconds > 0.0 ? (double)nrays / cpu_seconds * 1e-6 : 0.0, tb_gpu_backend_name(gsess.backend),
           tb_accel_kind_name(kind), nthreads);
done:
    if (of.fp)
        tb_outfile_abort(&of);
    free(rays);
    free(hits);
    fclose(rf);
    tb_gpu_scene_destroy(gscene);
    tb_gpu_session_close(&gsess);
    tb_scene_free(scene);
    return rc;
}
