/* `testbed bench scale`: scenes of growing size (testbed generate) loaded and
 * rendered up to the first pixel, each in a child process of its own, so
 * that its peak resident memory is its own (issue 19; docs/performance.md,
 * "Scale"). Per count: the MID file's size, parse (a streaming pass over the
 * file, as `testbed check` reads it), prepare (the rest of the scene load:
 * objects, materials, lights, emitters, references), build (the BVH), first
 * pixel (from the start of the load to the first pixel's radiance, the ray
 * tracer's set-up included), peak resident memory, and the scene's own
 * accounting (tb_scene_memory): bytes per object and per triangle. */
#define _GNU_SOURCE /* wait4 */
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cli_util.h"
#include "commands.h"
#include "host/mid/generate.h"
#include "host/mid/mid_reader.h"
#include "host/render/raytrace.h"
#include "host/render/scene.h"
#include "util/math/rng.h"
#include "util/stats/stats.h"

#define TB__SCALE_MAX_COUNTS 32

/* What a child reports for one count (written through a pipe). */
typedef struct tb__scale_row {
    int ok;                 /* 1: measured; 0: failed (msg says why) */
    double parse, prepare, build, first_pixel;
    uint64_t objects, triangles;
    double per_object, per_triangle, scene_mib;
    char msg[512];
} tb__scale_row;

static double tb__wall(void) { return 1e-9 * (double)tb_stats_now_ns(); }

/* The measurement, in the child: parse, load, build, first pixel. */
static void tb__scale_child(const char *path, int threads, tb__scale_row *row)
{
    memset(row, 0, sizeof *row);
    double t0 = tb__wall();
    tb_mid_reader *r;
    tb_status st = tb_mid_reader_open(&r, path);
    tb_mid_item it;
    while (!st && !(st = tb_mid_reader_next(r, &it)) && it.type != TB_MID_ITEM_END)
        ;
    if (r)
        tb_mid_reader_close(r);
    double t1 = tb__wall();
    tb_scene *s = NULL;
    tb_scene_options so = {.no_accel = true, .threads = threads};
    if (!st)
        st = tb_scene_load(path, &so, &s);
    double t2 = tb__wall();
    if (!st)
        st = tb_scene_rebuild_accel(s, TB_ACCEL_BVH, &(tb_accel_options){.threads = threads});
    double t3 = tb__wall();
    tb_raytracer rt;
    memset(&rt, 0, sizeof rt);
    if (!st)
        st = tb_rt_init(&rt, s, NULL);
    if (!st) {
        tb_rng rng;
        tb_rng_seed(&rng, 1, 0);
        tb_ray ray = tb_camera_ray(&s->camera, 0.5 * s->camera.width, 0.5 * s->camera.height, 0.5f, 0.5f);
        tb_channels L = tb_rt_radiance(&rt, &ray, &rng);
        (void)L;
    }
    double t4 = tb__wall();
    if (st) {
        snprintf(row->msg, sizeof row->msg, "%s", tb_last_error());
    } else {
        tb_scene_memory_use mu;
        tb_scene_memory(s, &mu);
        row->ok = 1;
        row->parse = t1 - t0;
        row->prepare = (t2 - t1) - row->parse; /* the load parses again */
        if (row->prepare < 0.0)
            row->prepare = 0.0;
        row->build = t3 - t2;
        row->first_pixel = t4 - t1;
        row->objects = s->nobjects;
        row->triangles = mu.triangles;
        row->per_object = mu.per_object;
        row->per_triangle = mu.per_triangle;
        row->scene_mib = (double)mu.total / 1048576.0;
    }
    tb_rt_release(&rt);
    tb_scene_free(s);
}

/* Runs the child for `path`; fills row and *peak_kib (its peak RSS). */
static int tb__scale_run(const char *path, int threads, tb__scale_row *row, long *peak_kib)
{
    int fd[2];
    if (pipe(fd)) {
        snprintf(row->msg, sizeof row->msg, "pipe: %s", strerror(errno));
        return 0;
    }
    fflush(NULL);
    pid_t pid = fork();
    if (pid < 0) {
        snprintf(row->msg, sizeof row->msg, "fork: %s", strerror(errno));
        return 0;
    }
    if (pid == 0) {
        close(fd[0]);
        tb__scale_row r;
        tb__scale_child(path, threads, &r);
        ssize_t w = write(fd[1], &r, sizeof r);
        _exit(w == (ssize_t)sizeof r ? 0 : 1);
    }
    close(fd[1]);
    ssize_t got = 0, n;
    while (got < (ssize_t)sizeof *row && (n = read(fd[0], (char *)row + got, sizeof *row - (size_t)got)) > 0)
        got += n;
    close(fd[0]);
    int status = 0;
    struct rusage ru;
    memset(&ru, 0, sizeof ru);
    if (wait4(pid, &status, 0, &ru) < 0) {
        snprintf(row->msg, sizeof row->msg, "wait: %s", strerror(errno));
        return 0;
    }
    *peak_kib = ru.ru_maxrss;
    if (got != (ssize_t)sizeof *row) {
        memset(row, 0, sizeof *row);
        snprintf(row->msg, sizeof row->msg, "the measuring process died (%s %d)",
                 WIFSIGNALED(status) ? "signal" : "status",
                 WIFSIGNALED(status) ? WTERMSIG(status) : WEXITSTATUS(status));
        return 0;
    }
    return row->ok;
}

/* "1e4,1e5,250000" -> counts (each a whole number in [1, 1e9]); the number
 * of counts, or -1 with a message in why. */
static int tb__scale_counts(const char *s, int64_t *out, int cap, char *why, size_t len)
{
    int n = 0;
    const char *p = s;
    while (*p) {
        char *end;
        errno = 0;
        double v = strtod(p, &end);
        if (end == p || errno || !(v >= 1.0 && v <= 1e9) || v != floor(v) || (*end && *end != ',')) {
            snprintf(why, len, "--counts: '%s' is not a list of whole numbers in [1, 1e9] (e.g. 1e4,1e5)", s);
            return -1;
        }
        if (n == cap) {
            snprintf(why, len, "--counts: more than %d counts", cap);
            return -1;
        }
        out[n++] = (int64_t)v;
        p = *end ? end + 1 : end;
        if (*end == ',' && !*p) {
            snprintf(why, len, "--counts: '%s' ends with a comma", s);
            return -1;
        }
    }
    if (n == 0)
        snprintf(why, len, "--counts: no count given");
    return n ? n : -1;
}

int tb_cmd_bench_scale(int argc, char **argv)
{
    const char *kind_name = "grid", *counts_s = "1e3,1e4,1e5", *dir = NULL, *csv = NULL;
    int threads = 2;
    uint64_t seed = 1;
    bool keep = false;
    const tb_opt opts[] = {
        {"kind", .type = TB_OPT_STRING, .dest = &kind_name, .metavar = "K",
         .help = "grid (default), csg or mesh: the scene testbed generate makes"},
        {"counts", .type = TB_OPT_STRING, .dest = &counts_s, .metavar = "N,...",
         .help = "object counts, ascending or not (default 1e3,1e4,1e5)"},
        {"threads", .type = TB_OPT_INT, .dest = &threads, .min = 1, .max = 4096, .metavar = "T",
         .help = "threads of the load and the build (default 2)"},
        {"seed", .type = TB_OPT_UINT64, .dest = &seed, .metavar = "S", .help = "generator seed (default 1)"},
        {"dir", .type = TB_OPT_STRING, .dest = &dir, .metavar = "DIR",
         .help = "where the scenes are written (default $TMPDIR or /tmp)"},
        {"keep", .type = TB_OPT_FLAG, .dest = &keep, .help = "keep the generated scenes"},
        {"csv", .type = TB_OPT_STRING, .dest = &csv, .metavar = "FILE",
         .help = "also write the rows to FILE (for tools/plot-scale.gp)"},
        {0},
    };
    const tb_cli cli = {
        .prog = "testbed bench scale",
        .err = "testbed bench scale: ",
        .usage = "[--kind grid|csg|mesh] [--counts N,...] [--threads T] [options]",
        .intro = "Generates scenes of growing size (testbed generate KIND --count N), then, each in a\n"
                 "child process, parses, loads and builds them and renders the first pixel; prints\n"
                 "the times, the child's peak resident memory and the scene's own accounting\n"
                 "(docs/performance.md, \"Scale\"). A scene that does not fit fails cleanly (the\n"
                 "load's memory check) and is reported as such.",
        .opts = opts,
        .outro = "Exit status: 0 every count measured, 1 some count failed, 2 usage error.",
    };
    int npos, prc = tb_cli_parse(&cli, argc, argv, &npos);
    if (prc != TB_CLI_OK)
        return prc;
    tb_gen_kind kind;
    if (tb_gen_kind_parse(kind_name, &kind))
        return tb_cli_usage_error(&cli, "--kind: '%s' is not grid, csg or mesh", kind_name);
    int64_t counts[TB__SCALE_MAX_COUNTS];
    char why[256];
    int nc = tb__scale_counts(counts_s, counts, TB__SCALE_MAX_COUNTS, why, sizeof why);
    if (nc < 0)
        return tb_cli_usage_error(&cli, "%s", why);
    if (!dir)
        dir = getenv("TMPDIR") && *getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp";
    FILE *cf = NULL;
    if (csv && !(cf = fopen(csv, "w"))) {
        fprintf(stderr, "testbed bench scale: %s: %s\n", csv, strerror(errno));
        return TB_EXIT_FAIL;
    }
    if (cf)
        fprintf(cf, "kind,count,file_mb,parse_s,prepare_s,build_s,first_pixel_s,peak_mib,"
                    "peak_bytes_per_object,scene_bytes_per_object,scene_bytes_per_triangle,triangles\n");
    double load[3];
    tb_cli_load_average(load);
    printf("testbed bench scale: --kind %s, %d threads, load average %.2f %.2f %.2f at the start\n\n",
           tb_gen_kind_name(kind), threads, load[0], load[1], load[2]);
    printf("%10s %9s %8s %9s %8s %11s %9s %11s %11s %11s\n", "objects", "MID MB", "parse s", "prepare s",
           "build s", "1st pixel s", "peak MiB", "peak B/obj", "scene B/obj", "scene B/tri");
    int failed = 0;
    for (int i = 0; i < nc; i++) {
        char path[4096];
        snprintf(path, sizeof path, "%s/testbed-bench-scale-%s-%" PRId64 "-%d.mid", dir, tb_gen_kind_name(kind),
                 counts[i], (int)getpid());
        FILE *f = fopen(path, "w");
        tb_gen_options go = {.kind = kind, .count = counts[i], .seed = seed};
        tb_status gst = f ? tb_generate_write(f, &go) : tb_error(TB_ERR_IO, "%s: %s", path, strerror(errno));
        if (f && fclose(f) && !gst)
            gst = tb_error(TB_ERR_IO, "%s: write error", path);
        if (gst) {
            fprintf(stderr, "testbed bench scale: %s\n", tb_last_error());
            remove(path);
            return TB_EXIT_FAIL;
        }
        struct stat sb;
        double mb = stat(path, &sb) == 0 ? (double)sb.st_size / 1e6 : 0.0;
        tb__scale_row row;
        long peak = 0;
        int ok = tb__scale_run(path, threads, &row, &peak);
        double peak_mib = (double)peak / 1024.0;
        if (ok) {
            double per = (double)peak * 1024.0 / (double)counts[i];
            printf("%10" PRId64 " %9.1f %8.3f %9.3f %8.3f %11.3f %9.1f %11.0f %11.0f %11.0f\n", counts[i], mb,
                   row.parse, row.prepare, row.build, row.first_pixel, peak_mib, per, row.per_object,
                   row.per_triangle);
            if (cf)
                fprintf(cf, "%s,%" PRId64 ",%.3f,%.4f,%.4f,%.4f,%.4f,%.1f,%.0f,%.0f,%.0f,%" PRIu64 "\n",
                        tb_gen_kind_name(kind), counts[i], mb, row.parse, row.prepare, row.build, row.first_pixel,
                        peak_mib, per, row.per_object, row.per_triangle, row.triangles);
        } else {
            printf("%10" PRId64 " %9.1f   failed after a peak of %.1f MiB: %s\n", counts[i], mb, peak_mib, row.msg);
            failed = 1;
        }
        fflush(stdout);
        if (!keep)
            remove(path);
    }
    if (cf && fclose(cf)) {
        fprintf(stderr, "testbed bench scale: %s: write error\n", csv);
        return TB_EXIT_FAIL;
    }
    return failed ? TB_EXIT_FAIL : TB_EXIT_OK;
}
