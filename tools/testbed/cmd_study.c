/* `testbed study SCENE... --methods M,... --budgets B,... --seeds N -o DIR`:
 * every method at every budget and seed on every scene, error against a
 * reference, statistics over seeds, and a report (docs/study.md).
 *
 * Each cell is a normal `testbed render` run as a child process of this
 * binary (/proc/self/exe) with its image, stats JSON and log in its own
 * folder: a process per cell gives each cell its own peak memory (wait4's
 * ru_maxrss) and its own stats counters, which are process-wide, and a
 * failing or interrupted cell cannot take the study with it. A cell is
 * finished when its cell.json (written last, atomically) holds the same key
 * (scene SHA-256 + the render's arguments); a rerun reuses those. This file
 * plans and runs the cells and measures their errors; study_report.c writes
 * the outputs. */
#define _DEFAULT_SOURCE /* wait4 */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <spawn.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "commands.h"
#include "host/radiosity/radiosity.h"
#include "host/render/scene.h"
#include "options.h"
#include "study.h"
#include "util/base/outfile.h"
#include "util/base/progress.h"
#include "util/image/compare.h"
#include "util/stats/provenance.h"

extern char **environ;

const char *const tb_study_method_names[TB_STUDY_NMETHODS] = {"raytrace", "radiosity", "hybrid", "path"};

/* The seed of a rendered reference: far from the cells' seeds 0 .. N-1, so
 * its noise is independent of theirs. */
#define TB__STUDY_REFERENCE_SEED 1000003

/* Most render passes of a seconds budget (the time budget stops them first). */
#define TB__STUDY_SECONDS_PASSES 1048576

/* Set by SIGINT: the running render writes what it has and exits 130; the
 * study stops after it without recording it. */
static atomic_int tb__study_interrupt;

static void tb__study_on_sigint(int sig)
{
    (void)sig;
    atomic_store(&tb__study_interrupt, 1);
}

/* --methods raytrace,path,...: a TB_OPT_CUSTOM parser into a tb_study. */
static int tb__study_parse_methods(const char *val, void *dest, char *why, size_t len)
{
    tb_study *st = dest;
    st->nmethods = 0;
    const char *p = val;
    while (1) {
        size_t n = strcspn(p, ",");
        int found = -1;
        for (int m = 0; m < TB_STUDY_NMETHODS; m++)
            if (strlen(tb_study_method_names[m]) == n && !strncmp(p, tb_study_method_names[m], n))
                found = m;
        if (found < 0) {
            snprintf(why, len, "unknown method '%.*s' (raytrace, radiosity, hybrid, path)", (int)n, p);
            return 1;
        }
        for (int i = 0; i < st->nmethods; i++)
            if ((int)st->methods[i] == found) {
                snprintf(why, len, "method '%s' given twice", tb_study_method_names[found]);
                return 1;
            }
        st->methods[st->nmethods++] = (tb_study_method)found;
        if (!p[n])
            return 0;
        p += n + 1;
    }
}

/* --budgets 1,2,4,...: a TB_OPT_CUSTOM parser into a tb_study; positive,
 * increasing numbers (whether they must be whole depends on --budget-kind,
 * checked after parsing). */
static int tb__study_parse_budgets(const char *val, void *dest, char *why, size_t len)
{
    tb_study *st = dest;
    st->nbudgets = 0;
    const char *p = val;
    while (1) {
        char *end;
        errno = 0;
        double b = strtod(p, &end);
        if (end == p || (*end && *end != ',') || errno || !isfinite(b) || !(b > 0)) {
            snprintf(why, len, "expected positive numbers separated by commas, got '%s'", val);
            return 1;
        }
        if (st->nbudgets == TB_STUDY_MAX_BUDGETS) {
            snprintf(why, len, "at most %d budgets", TB_STUDY_MAX_BUDGETS);
            return 1;
        }
        if (st->nbudgets > 0 && !(b > st->budgets[st->nbudgets - 1])) {
            snprintf(why, len, "budgets must increase, got '%s'", val);
            return 1;
        }
        st->budgets[st->nbudgets++] = b;
        if (!*end)
            return 0;
        p = end + 1;
    }
}

/* A growable argument vector for one render. */
typedef struct tb__argv {
    char *v[256];
    int n;
    char store[8192]; /* the strings this vector made itself */
    size_t used;
} tb__argv;

/* Appends a formatted argument; false when the vector is full. */
static bool tb__arg(tb__argv *a, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static bool tb__arg(tb__argv *a, const char *fmt, ...)
{
    if (a->n + 2 > (int)(sizeof a->v / sizeof a->v[0]))
        return false;
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(a->store + a->used, sizeof a->store - a->used, fmt, ap);
    va_end(ap);
    if (k < 0 || (size_t)k >= sizeof a->store - a->used)
        return false;
    a->v[a->n++] = a->store + a->used;
    a->v[a->n] = NULL;
    a->used += (size_t)k + 1;
    return true;
}

/* Appends the whitespace-separated words of `s`. */
static bool tb__args_words(tb__argv *a, const char *s)
{
    while (s && *s) {
        s += strspn(s, " \t");
        size_t n = strcspn(s, " \t");
        if (n && !tb__arg(a, "%.*s", (int)n, s))
            return false;
        s += n;
    }
    return true;
}

/* A budget as the renders see it ("4", "0.5"). */
static void tb__budget_str(double b, char *buf, size_t n)
{
    snprintf(buf, n, "%.15g", b);
}

/* The options of a cell's render after `render SCENE` (the key is made of
 * these): the method, its budget (docs/study.md, "Budgets"), its seed and
 * the method's --args. */
static bool tb__cell_args(const tb_study *st, const tb_study_scene *sc, tb_study_method m, double budget, int seed,
                          tb__argv *a)
{
    char b[64];
    tb__budget_str(budget, b, sizeof b);
    bool ok = tb__arg(a, "--method") && tb__arg(a, "%s", tb_study_method_names[m]);
    if (m == TB_STUDY_RADIOSITY) {
        /* budget B: sqrt(B) times the base mesh's elements, so the solution's cost
         * (shots x elements, both proportional to the elements) grows about as B */
        double edge = st->radiosity_edge > 0 ? st->radiosity_edge : sc->diagonal / TB_RAD_DEFAULT_EDGE_DIVISIONS;
        if (st->kind == TB_STUDY_SPP)
            ok = ok && tb__arg(a, "--max-edge") && tb__arg(a, "%.9g", edge / pow(budget, 0.25));
        else
            ok = ok && tb__arg(a, "--max-edge") && tb__arg(a, "%.9g", edge) && tb__arg(a, "--time-budget") &&
                 tb__arg(a, "%s", b);
        ok = ok && tb__arg(a, "--seed") && tb__arg(a, "%d", seed);
    } else {
        if (st->kind == TB_STUDY_SPP)
            ok = ok && tb__arg(a, "--spp") && tb__arg(a, "%s", b);
        else
            ok = ok && tb__arg(a, "--spp") && tb__arg(a, "1") && tb__arg(a, "--passes") &&
                 tb__arg(a, "%d", TB__STUDY_SECONDS_PASSES) && tb__arg(a, "--time-budget") && tb__arg(a, "%s", b);
        ok = ok && tb__arg(a, "--seed") && tb__arg(a, "%d", seed);
        if (m == TB_STUDY_RAYTRACE) /* the CPU ray tracer, as the other methods (auto would probe Vulkan) */
            ok = ok && tb__arg(a, "--backend") && tb__arg(a, "cpu");
        if (m == TB_STUDY_HYBRID)
            ok = ok && tb__arg(a, "--rad-seed") && tb__arg(a, "%d", seed);
    }
    return ok && tb__args_words(a, st->method_args[m]);
}

/* mkdir -p for the folders of `path` up to and including the last one. */
static tb_status tb__mkdirs(const char *path)
{
    char buf[PATH_MAX];
    if (snprintf(buf, sizeof buf, "%s", path) >= (int)sizeof buf)
        return tb_error(TB_ERR_ARG, "%s: path too long", path);
    for (char *p = buf + 1; ; p++) {
        if (*p == '/' || !*p) {
            char c = *p;
            *p = 0;
            if (mkdir(buf, 0755) && errno != EEXIST)
                return tb_error(TB_ERR_IO, "cannot make folder %s: %s", buf, strerror(errno));
            struct stat sb;
            if (stat(buf, &sb) || !S_ISDIR(sb.st_mode))
                return tb_error(TB_ERR_IO, "%s is not a folder", buf);
            *p = c;
            if (!c)
                return TB_OK;
        }
    }
}

/* `s` as a JSON string body (quotes and backslashes escaped, controls as \u). */
static void tb__json_escape(const char *s, char *out, size_t n)
{
    size_t k = 0;
    for (; *s && k + 7 < n; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\')
            out[k++] = '\\', out[k++] = (char)c;
        else if (c < 0x20)
            k += (size_t)snprintf(out + k, n - k, "\\u%04x", c);
        else
            out[k++] = (char)c;
    }
    out[k] = 0;
}

/* What a finished cell's cell.json records. */
typedef struct tb__cell_record {
    double wall_seconds, cpu_seconds, peak_rss_bytes;
} tb__cell_record;

/* Reads DIR/<cell>/cell.json: true if it exists and holds exactly `key`. */
static bool tb__cell_finished(const char *path, const char *key, tb__cell_record *r)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return false;
    char want[8192], esc[8000], line[8192];
    tb__json_escape(key, esc, sizeof esc);
    snprintf(want, sizeof want, "  \"key\": \"%s\",\n", esc);
    bool key_ok = false;
    int found = 0;
    while (fgets(line, sizeof line, f)) {
        if (!strcmp(line, want))
            key_ok = true;
        found += sscanf(line, " \"wall_seconds\": %lf", &r->wall_seconds) == 1;
        found += sscanf(line, " \"cpu_seconds\": %lf", &r->cpu_seconds) == 1;
        found += sscanf(line, " \"peak_rss_bytes\": %lf", &r->peak_rss_bytes) == 1;
    }
    fclose(f);
    return key_ok && found == 3;
}

/* Writes cell.json (the completion mark) whole or not at all. */
static tb_status tb__cell_write_record(const char *path, const char *key, const tb__cell_record *r)
{
    tb_outfile of;
    tb_status e = tb_outfile_open(&of, path);
    if (e)
        return e;
    char esc[8000];
    tb__json_escape(key, esc, sizeof esc);
    fprintf(of.fp, "{\n  \"key\": \"%s\",\n  \"wall_seconds\": %.6f,\n  \"cpu_seconds\": %.6f,\n"
                   "  \"peak_rss_bytes\": %.0f\n}\n",
            esc, r->wall_seconds, r->cpu_seconds, r->peak_rss_bytes);
    return tb_outfile_commit(&of);
}

/* The environment of a render: ours with TB_NO_PROGRESS=1 (its bar would
 * fight the study's, and goes to its log). NULL when out of memory. */
static char **tb__child_env(void)
{
    size_t n = 0;
    while (environ[n])
        n++;
    char **env = malloc((n + 2) * sizeof *env);
    if (!env)
        return NULL;
    size_t k = 0;
    for (size_t i = 0; i < n; i++)
        if (strncmp(environ[i], "TB_NO_PROGRESS=", 15))
            env[k++] = environ[i];
    env[k++] = "TB_NO_PROGRESS=1";
    env[k] = NULL;
    return env;
}

static double tb__now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Runs `exe` with argv `a`, stdout and stderr to log_path, and waits: the
 * exit status in *status (128 + signal for a signal), its times and peak
 * memory in *r. */
static tb_status tb__run(const char *exe, tb__argv *a, const char *log_path, char **env, int *status,
                         tb__cell_record *r)
{
    posix_spawn_file_actions_t fa;
    if (posix_spawn_file_actions_init(&fa))
        return tb_error(TB_ERR_NOMEM, "out of memory");
    posix_spawn_file_actions_addopen(&fa, 1, log_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    pid_t pid;
    double t0 = tb__now();
    int e = posix_spawn(&pid, exe, &fa, NULL, a->v, env);
    posix_spawn_file_actions_destroy(&fa);
    if (e)
        return tb_error(TB_ERR_IO, "cannot run %s: %s", exe, strerror(e));
    int ws;
    struct rusage ru;
    while (wait4(pid, &ws, 0, &ru) < 0)
        if (errno != EINTR)
            return tb_error(TB_ERR_IO, "waiting for a render: %s", strerror(errno));
    r->wall_seconds = tb__now() - t0;
    r->cpu_seconds = (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
                     1e-6 * (double)ru.ru_stime.tv_usec;
    r->peak_rss_bytes = 1024.0 * (double)ru.ru_maxrss; /* Linux: KiB */
    *status = WIFEXITED(ws) ? WEXITSTATUS(ws) : 128 + WTERMSIG(ws);
    return TB_OK;
}

/* Prints the last lines of a failed render's log. */
static void tb__print_log_tail(const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return;
    char lines[8][512];
    int n = 0;
    while (fgets(lines[n % 8], sizeof lines[0], f))
        n++;
    fclose(f);
    for (int i = n > 8 ? n - 8 : 0; i < n; i++)
        fprintf(stderr, "  | %s%s", lines[i % 8], strchr(lines[i % 8], '\n') ? "" : "\n");
}

/* One render of the plan: a cell or a scene's reference. */
typedef struct tb__job {
    tb_study_cell *cell;   /* NULL for a reference */
    int scene;
    char dir[PATH_MAX - 64]; /* absolute or relative to the working folder */
    char key[8192];
    tb__argv args;         /* after `testbed render SCENE -o IMAGE --stats JSON` */
    double units;          /* of the progress bar: its budget in samples or seconds */
    bool finished;
    tb__cell_record rec;
} tb__job;

/* Renders one job into its folder: image.exr, stats.json, log.txt, then
 * cell.json. Returns the render's exit status through *status. */
static tb_status tb__job_run(const tb_study *st, const char *exe, tb__job *j, char **env, int threads,
                             int *status)
{
    tb_status e = tb__mkdirs(j->dir);
    if (e)
        return e;
    char image[PATH_MAX + 16], stats[PATH_MAX + 16], log[PATH_MAX + 16], rec[PATH_MAX + 16];
    snprintf(image, sizeof image, "%s/image.exr", j->dir);
    snprintf(stats, sizeof stats, "%s/stats.json", j->dir);
    snprintf(log, sizeof log, "%s/log.txt", j->dir);
    snprintf(rec, sizeof rec, "%s/cell.json", j->dir);
    remove(rec); /* a stale mark must not outlive a failed render */
    tb__argv a = {.n = 0};
    bool ok = tb__arg(&a, "testbed") && tb__arg(&a, "render") && tb__arg(&a, "%s", st->scenes[j->scene].path) &&
              tb__arg(&a, "-o") && tb__arg(&a, "%s", image) && tb__arg(&a, "--stats") && tb__arg(&a, "%s", stats);
    for (int i = 0; ok && i < j->args.n; i++)
        ok = tb__arg(&a, "%s", j->args.v[i]);
    if (ok && threads > 0)
        ok = tb__arg(&a, "--threads") && tb__arg(&a, "%d", threads);
    if (!ok)
        return tb_error(TB_ERR_ARG, "a render's command line is too long");
    e = tb__run(exe, &a, log, env, status, &j->rec);
    if (e || *status)
        return e;
    j->finished = true;
    return tb__cell_write_record(rec, j->key, &j->rec);
}

/* Removes an unfinished job's image and stats (its log stays, to read why). */
static void tb__job_clean(const tb__job *j)
{
    char path[PATH_MAX + 16];
    snprintf(path, sizeof path, "%s/image.exr", j->dir);
    remove(path);
    snprintf(path, sizeof path, "%s/stats.json", j->dir);
    remove(path);
}

/* The file stem of `path`, made unique among the scenes before index i. */
static void tb__scene_name(tb_study *st, int i)
{
    const char *base = strrchr(st->scenes[i].path, '/');
    base = base ? base + 1 : st->scenes[i].path;
    char stem[48];
    snprintf(stem, sizeof stem, "%.*s", (int)strcspn(base, "."), base);
    for (char *p = stem; *p; p++)
        if (!((*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z') || (*p >= '0' && *p <= '9') || *p == '-' ||
              *p == '_'))
            *p = '_';
    if (!stem[0])
        snprintf(stem, sizeof stem, "scene");
    snprintf(st->scenes[i].name, sizeof st->scenes[i].name, "%s", stem);
    for (int k = 2; ; k++) {
        bool clash = false;
        for (int j = 0; j < i; j++)
            clash = clash || !strcmp(st->scenes[j].name, st->scenes[i].name);
        if (!clash)
            return;
        snprintf(st->scenes[i].name, sizeof st->scenes[i].name, "%s-%d", stem, k);
    }
}

/* Reads a finished cell's image and measures it against the scene's reference. */
static tb_status tb__measure(const tb_study *st, tb_study_cell *c)
{
    char path[PATH_MAX + 600];
    snprintf(path, sizeof path, "%s/%s/image.exr", st->out, c->dir);
    tb_image *img;
    tb_status e = tb_image_read(path, NULL, &img);
    if (e)
        return e;
    tb_compare_result r;
    e = tb_image_compare(img, st->scenes[c->scene].ref, NULL, &r);
    tb_image_free(img);
    if (e)
        return tb_error_context(e, "%s against the reference %s", path, st->scenes[c->scene].reference);
    c->relmse = r.all.relmse, c->rmse = r.all.rmse, c->ssim = r.all.ssim;
    c->nonfinite = r.nonfinite_a;
    return TB_OK;
}

int tb_cmd_study(int argc, char **argv)
{
    static tb_study st; /* large (scene list with paths): not on the stack */
    memset(&st, 0, sizeof st);
    const char *scene_paths[TB_STUDY_MAX_SCENES] = {0};
    tb_opt_strings refs = {.n = 0}, margs = {.n = 0};
    int kind = TB_STUDY_SPP, threads = 0;
    st.reference_method = "path";
    st.reference_spp = 1024;
    st.nseeds = 5;
    bool ref_spp_seen = false;
    char why[256];
    tb__study_parse_methods("raytrace,radiosity,hybrid,path", &st, why, sizeof why);
    tb__study_parse_budgets("1,2,4,8,16", &st, why, sizeof why);
    static const tb_opt_choice kinds[] = {{"spp", TB_STUDY_SPP}, {"seconds", TB_STUDY_SECONDS}, {NULL, 0}};
    static const tb_opt_choice ref_methods[] = {{"path", 0}, {"raytrace", 1}, {"hybrid", 2}, {NULL, 0}};
    int ref_method = 0;
    static const tb_opt_choice time_axes[] = {{"wall", 0}, {"cpu", 1}, {NULL, 0}};
    int time_axis = 0;
    const tb_opt opts[] = {
        {.short_name = 'o', .type = TB_OPT_STRING, .dest = &st.out, .metavar = "DIR",
         .help = "the output folder (made if missing; a rerun with the same DIR resumes)"},
        {"methods", .type = TB_OPT_CUSTOM, .dest = &st, .metavar = "M,...", .parse = tb__study_parse_methods,
         .help = "renderers to compare: raytrace, radiosity, hybrid, path\n(default raytrace,radiosity,hybrid,path)"},
        {"budgets", .type = TB_OPT_CUSTOM, .dest = &st, .metavar = "B,...", .parse = tb__study_parse_budgets,
         .help = "increasing budgets (default 1,2,4,8,16); what one means per method:\ndocs/study.md, \"Budgets\""},
        {"budget-kind", .type = TB_OPT_CHOICE, .dest = &kind, .choices = kinds,
         .help = "spp (default: samples per pixel; radiosity: about sqrt(B) times the elements\n"
                 "of budget 1, see --radiosity-edge) or seconds (each renderer's --time-budget)"},
        {"seeds", .type = TB_OPT_INT, .dest = &st.nseeds, .min = 1, .max = TB_STUDY_MAX_SEEDS, .metavar = "N",
         .help = "renders per method and budget, with seeds 0 .. N-1 (default %D)"},
        {"reference", .type = TB_OPT_REPEAT, .dest = &refs, .metavar = "REF.exr",
         .help = "the reference image, once per SCENE in the same order (default: render one)"},
        {"reference-spp", .type = TB_OPT_INT, .dest = &st.reference_spp, .min = 1, .max = 1 << 24, .metavar = "N",
         .seen = &ref_spp_seen,
         .help = "samples per pixel of a rendered reference (default %D), cached in DIR/reference"},
        {"reference-method", .type = TB_OPT_CHOICE, .dest = &ref_method, .choices = ref_methods, .metavar = "M",
         .help = "the renderer of a rendered reference (default path; raytrace and hybrid are\n"
                 "biased for most scenes: for tests and scenes they solve exactly)"},
        {"args", .type = TB_OPT_REPEAT, .dest = &margs, .metavar = "M=OPTS",
         .help = "more `testbed render --method M` options for method M's renders, as words\n"
                 "(\"hybrid=--hybrid-mode gather\"); part of the cells' keys"},
        {"radiosity-edge", .type = TB_OPT_DOUBLE, .dest = &st.radiosity_edge, .min = 0, .max = 1e30, .metavar = "L",
         .flags = TB_OPTF_OPEN_MIN,
         .help = "radiosity: the longest element edge at budget 1, scene units (default: the\n"
                 "scene's bounding-box diagonal / 24, the radiosity renderer's default); budget B\n"
                 "uses L / B^(1/4), so about sqrt(B) times the elements"},
        {"time", .type = TB_OPT_CHOICE, .dest = &time_axis, .choices = time_axes,
         .help = "the time of the plots, time slopes and equal-time/error tables: wall (default:\n"
                 "each render process start to exit) or cpu (its user + system seconds: steadier\n"
                 "on a loaded machine, but the sum over threads)"},
        {"threads", .type = TB_OPT_INT, .dest = &threads, .min = 0, .max = 4096, .metavar = "N",
         .help = "OpenMP threads per render (default: OpenMP's; not part of the keys)"},
        {0},
    };
    const tb_cli cli = {
        .prog = "testbed study",
        .err = "testbed study: ",
        .usage = "SCENE.mid... -o DIR [--methods M,...] [--budgets B,...] [--budget-kind spp|seconds]\n"
                 "                     [--seeds N] [--reference REF.exr... | --reference-spp N] [options]",
        .intro = "Renders every SCENE with every method at every budget and seed (each cell a `testbed render`\n"
                 "with its stats JSON), measures relMSE, RMSE and SSIM against a reference, and writes\n"
                 "DIR/index.html, DIR/report.md, DIR/cells.csv, DIR/study.json and gnuplot plots: means with\n"
                 "95% confidence intervals over seeds, time and peak memory per cell, convergence slopes,\n"
                 "equal-time and equal-error tables (docs/study.md). Finished cells are reused by a rerun.",
        .outro = "Ctrl-C stops after the running render; finished cells are kept (run again to resume); exit 130.",
        .opts = opts,
        .pos = scene_paths,
        .max_pos = TB_STUDY_MAX_SCENES,
        .min_pos = 1,
        .missing = "no SCENE.mid given",
    };
    int npos, prc = tb_cli_parse(&cli, argc, argv, &npos);
    if (prc != TB_CLI_OK)
        return prc;
    st.kind = (tb_study_budget_kind)kind;
    st.time_cpu = time_axis == 1;
    st.reference_method = ref_methods[ref_method].name;
    if (!st.out)
        return tb_cli_usage_error(&cli, "no output folder given (-o DIR)");
    if (refs.n && refs.n != npos)
        return tb_cli_usage_error(&cli, "%d --reference image(s) for %d scene(s): give one per scene, in order",
                                  refs.n, npos);
    if (refs.n && ref_spp_seen)
        return tb_cli_usage_error(&cli, "--reference-spp renders a reference: not with --reference");
    int ref_pass_spp = st.reference_spp, ref_passes = 1;
    while (ref_pass_spp > 256 && ref_pass_spp % 2 == 0) /* passes of at most 256 samples where N allows */
        ref_pass_spp /= 2, ref_passes *= 2;
    if (ref_pass_spp > 65536)
        return tb_cli_usage_error(&cli, "--reference-spp %d: more than 65536 needs a multiple of a power of two "
                                        "(passes of at most 65536 samples)", st.reference_spp);
    if (st.kind == TB_STUDY_SPP)
        for (int b = 0; b < st.nbudgets; b++)
            if (st.budgets[b] != floor(st.budgets[b]) || st.budgets[b] > 65536)
                return tb_cli_usage_error(&cli, "--budgets: %g is not a whole number of samples in [1, 65536]",
                                          st.budgets[b]);
    for (int i = 0; i < margs.n; i++) {
        const char *eq = strchr(margs.v[i], '=');
        int m = -1;
        for (int k = 0; eq && k < TB_STUDY_NMETHODS; k++)
            if ((size_t)(eq - margs.v[i]) == strlen(tb_study_method_names[k]) &&
                !strncmp(margs.v[i], tb_study_method_names[k], (size_t)(eq - margs.v[i])))
                m = k;
        if (m < 0)
            return tb_cli_usage_error(&cli, "--args '%s': expected METHOD=OPTIONS with METHOD one of raytrace, "
                                            "radiosity, hybrid, path", margs.v[i]);
        if (st.method_args[m])
            return tb_cli_usage_error(&cli, "--args for %s given twice", tb_study_method_names[m]);
        static const char *const owned[] = {"-o", "--stats", "--method", "--spp", "--seed", "--rad-seed", "--passes",
                                            "--time-budget", "--threads", "--report", "--reference", "--sample-map",
                                            "--checkpoint", "--resume",
                                            "--max-edge", "--max-area", NULL};
        for (int k = 0; owned[k]; k++) {
            if (m != TB_STUDY_RADIOSITY && (!strcmp(owned[k], "--max-edge") || !strcmp(owned[k], "--max-area")))
                continue; /* the hybrid's radiosity pass: its own mesh, the same for every budget */
            const char *w = eq + 1;
            size_t n = strlen(owned[k]);
            while ((w = strstr(w, owned[k]))) {
                bool starts = w == eq + 1 || w[-1] == ' ' || w[-1] == '\t';
                bool ends = !w[n] || w[n] == ' ' || w[n] == '\t' || w[n] == '=';
                if (starts && ends)
                    return tb_cli_usage_error(&cli, "--args %s: %s is set by the study (its budget, seed or "
                                                    "outputs)", tb_study_method_names[m], owned[k]);
                w += n;
            }
        }
        st.method_args[m] = (char *)(eq + 1);
    }

    /* the scenes: readable, loadable (their errors before any render), hashed */
    for (int i = 0; i < npos; i++)
        if (!strcmp(scene_paths[i], "-"))
            return tb_cli_usage_error(&cli, "a study renders each scene many times: give files, not '-'");
    st.nscenes = npos;
    for (int i = 0; i < npos; i++) {
        tb_study_scene *sc = &st.scenes[i];
        sc->path = scene_paths[i];
        if (tb_sha256_file(sc->path, sc->sha256)) {
            fprintf(stderr, "testbed study: %s\n", tb_last_error());
            goto fail_scenes;
        }
        tb_scene *s;
        if (tb_scene_load(sc->path, NULL, &s)) {
            fprintf(stderr, "testbed study: %s\n", tb_last_error());
            goto fail_scenes;
        }
        tb_vec3 ext = tb_vec3_sub(s->bounds.hi, s->bounds.lo);
        sc->diagonal = tb_vec3_length(ext);
        int w = s->camera.width, h = s->camera.height;
        tb_scene_free(s);
        if (!(sc->diagonal > 0) || !isfinite(sc->diagonal)) {
            fprintf(stderr, "testbed study: %s: the scene has no extent\n", sc->path);
            goto fail_scenes;
        }
        tb__scene_name(&st, i);
        if (refs.n) {
            sc->reference_given = true;
            snprintf(sc->reference, sizeof sc->reference, "%s", refs.v[i]);
            /* read now: a bad reference fails before hours of rendering */
            if (tb_image_read(sc->reference, NULL, &sc->ref)) {
                fprintf(stderr, "testbed study: --reference %s: %s\n", sc->reference, tb_last_error());
                goto fail_scenes;
            }
            if (sc->ref->width != w || sc->ref->height != h) {
                fprintf(stderr, "testbed study: --reference %s is %dx%d, the renders of %s are %dx%d\n",
                        sc->reference, sc->ref->width, sc->ref->height, sc->path, w, h);
                goto fail_scenes;
            }
        }
    }
    if (tb__mkdirs(st.out)) {
        fprintf(stderr, "testbed study: %s\n", tb_last_error());
    fail_scenes:
        for (int i = 0; i < st.nscenes; i++)
            tb_image_free(st.scenes[i].ref);
        return TB_EXIT_FAIL;
    }
    /* the renders run this very binary: /proc/self/exe in the spawned child is
     * the parent's image, even if the file was rebuilt since the study began */
    const char *exe = "/proc/self/exe";
    if (access(exe, X_OK)) {
        fprintf(stderr, "testbed study: cannot run this program again (%s): %s\n", exe, strerror(errno));
        goto fail_scenes;
    }

    /* the plan: references first (their failures show early), then the cells */
    st.ncells = (size_t)st.nscenes * (size_t)st.nmethods * (size_t)st.nbudgets * (size_t)st.nseeds;
    st.cells = calloc(st.ncells, sizeof *st.cells);
    size_t njobs = st.ncells + (size_t)st.nscenes;
    tb__job *jobs = calloc(njobs, sizeof *jobs);
    char **env = tb__child_env();
    int rc = TB_EXIT_FAIL;
    if (!st.cells || !jobs || !env) {
        fprintf(stderr, "testbed study: out of memory\n");
        goto done;
    }
    size_t nj = 0;
    for (int s = 0; s < st.nscenes; s++) {
        tb_study_scene *sc = &st.scenes[s];
        if (sc->reference_given)
            continue;
        tb__job *j = &jobs[nj++];
        j->scene = s;
        snprintf(j->dir, sizeof j->dir, "%s/reference/%s", st.out, sc->name);
        int spp = ref_pass_spp, passes = ref_passes;
        sc->reference_spp = (double)spp * passes;
        bool ok = tb__arg(&j->args, "--method") && tb__arg(&j->args, "%s", st.reference_method) &&
                  tb__arg(&j->args, "--spp") && tb__arg(&j->args, "%d", spp) && tb__arg(&j->args, "--passes") &&
                  tb__arg(&j->args, "%d", passes) && tb__arg(&j->args, "--seed") &&
                  tb__arg(&j->args, "%d", TB__STUDY_REFERENCE_SEED);
        if (ok && !strcmp(st.reference_method, "raytrace"))
            ok = tb__arg(&j->args, "--backend") && tb__arg(&j->args, "cpu");
        if (!ok) {
            fprintf(stderr, "testbed study: a render's command line is too long\n");
            goto done;
        }
        j->units = st.kind == TB_STUDY_SPP ? sc->reference_spp : 1;
        snprintf(sc->reference, sizeof sc->reference, "%s/image.exr", j->dir);
    }
    for (int s = 0; s < st.nscenes; s++)
        for (int m = 0; m < st.nmethods; m++)
            for (int b = 0; b < st.nbudgets; b++)
                for (int k = 0; k < st.nseeds; k++) {
                    tb_study_cell *c = tb_study_cell_at(&st, s, m, b, k);
                    *c = (tb_study_cell){.scene = s, .method = m, .budget = b, .seed = k,
                                         .relmse = NAN, .rmse = NAN, .ssim = NAN};
                    char bs[64];
                    tb__budget_str(st.budgets[b], bs, sizeof bs);
                    snprintf(c->dir, sizeof c->dir, "cells/%s/%s/%s%s-seed%d", st.scenes[s].name,
                             tb_study_method_names[st.methods[m]], st.kind == TB_STUDY_SPP ? "spp" : "sec", bs, k);
                    tb__job *j = &jobs[nj++];
                    j->cell = c;
                    j->scene = s;
                    snprintf(j->dir, sizeof j->dir, "%s/%s", st.out, c->dir);
                    if (!tb__cell_args(&st, &st.scenes[s], st.methods[m], st.budgets[b], k, &j->args)) {
                        fprintf(stderr, "testbed study: a render's command line is too long\n");
                        goto done;
                    }
                    j->units = st.budgets[b];
                }
    /* keys: the scene's bytes and the render's options; finished jobs are reused */
    double todo_units = 0;
    int todo = 0;
    for (size_t i = 0; i < nj; i++) {
        tb__job *j = &jobs[i];
        int k = snprintf(j->key, sizeof j->key, "scene_sha256=%s", st.scenes[j->scene].sha256);
        for (int a = 0; a < j->args.n && k < (int)sizeof j->key; a++)
            k += snprintf(j->key + k, sizeof j->key - (size_t)k, " %s", j->args.v[a]);
        char rec[PATH_MAX + 16];
        snprintf(rec, sizeof rec, "%s/cell.json", j->dir);
        char img[PATH_MAX + 16];
        snprintf(img, sizeof img, "%s/image.exr", j->dir);
        j->finished = tb__cell_finished(rec, j->key, &j->rec) && access(img, R_OK) == 0; /* image deleted: again */
        if (!j->finished)
            todo_units += j->units, todo++;
    }
    fprintf(stderr, "testbed study: %zu cells (%d scene(s) x %d method(s) x %d budget(s) x %d seed(s)); %d render(s) "
                    "to run, the rest finished before\n",
            st.ncells, st.nscenes, st.nmethods, st.nbudgets, st.nseeds, todo);

    /* run */
    struct sigaction sa, old_sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = tb__study_on_sigint;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old_sa);
    tb_progress prog;
    bool bar = tb_progress_start(&prog, "study", (int64_t)ceil(todo_units), NULL, 0) == TB_OK;
    bool failed = false;
    for (size_t i = 0; i < nj && !failed && !atomic_load(&tb__study_interrupt); i++) {
        tb__job *j = &jobs[i];
        if (j->finished) {
            if (j->cell)
                j->cell->reused = true, st.reused++;
            continue;
        }
        int status = 0;
        tb_status e = tb__job_run(&st, exe, j, env, threads, &status);
        if (bar)
            tb_progress_add(&prog, (int64_t)ceil(j->units));
        if (!j->finished)
            tb__job_clean(j); /* an interrupted or failed render's partial image is no result */
        if (atomic_load(&tb__study_interrupt))
            break;
        if (e || status) {
            if (bar)
                tb_progress_finish(&prog), bar = false;
            if (e)
                fprintf(stderr, "testbed study: %s: %s\n", j->dir, tb_last_error());
            else {
                fprintf(stderr, "testbed study: the render in %s failed (exit status %d); its log, %s/log.txt, "
                                "ends:\n", j->dir, status, j->dir);
                char log[PATH_MAX + 16];
                snprintf(log, sizeof log, "%s/log.txt", j->dir);
                tb__print_log_tail(log);
            }
            failed = true;
            break;
        }
        if (j->cell)
            st.rendered++;
        if (!tb_progress_active(&prog))
            fprintf(stderr, "testbed study: rendered %s (%.2f s, %.1f MiB)\n", j->dir, j->rec.wall_seconds,
                    j->rec.peak_rss_bytes / 1048576.0);
    }
    if (bar)
        tb_progress_finish(&prog);
    sigaction(SIGINT, &old_sa, NULL);
    if (atomic_load(&tb__study_interrupt)) {
        int finished = 0;
        for (size_t i = 0; i < nj; i++)
            finished += jobs[i].finished && jobs[i].cell;
        fprintf(stderr, "testbed study: interrupted; %d of %zu cells are finished and kept in %s/cells: run the same "
                        "command again to resume\n", finished, st.ncells, st.out);
        rc = 130;
        goto done;
    }
    if (failed)
        goto done;
    for (size_t i = 0; i < nj; i++)
        if (jobs[i].cell) {
            jobs[i].cell->wall_seconds = jobs[i].rec.wall_seconds;
            jobs[i].cell->cpu_seconds = jobs[i].rec.cpu_seconds;
            jobs[i].cell->peak_rss_bytes = jobs[i].rec.peak_rss_bytes;
        }

    /* errors against the references */
    for (int s = 0; s < st.nscenes; s++)
        if (!st.scenes[s].ref && tb_image_read(st.scenes[s].reference, NULL, &st.scenes[s].ref)) {
            fprintf(stderr, "testbed study: reference of %s: %s\n", st.scenes[s].path, tb_last_error());
            goto done;
        }
    for (size_t i = 0; i < st.ncells; i++) {
        if (tb__measure(&st, &st.cells[i])) {
            fprintf(stderr, "testbed study: %s\n", tb_last_error());
            goto done;
        }
        if (st.cells[i].nonfinite) /* a broken render: its errors leave those pixels out */
            fprintf(stderr, "testbed study: warning: %s/%s/image.exr has %lld NaN or infinite pixel(s)\n", st.out,
                    st.cells[i].dir, st.cells[i].nonfinite);
    }
    if (tb_study_write_outputs(&st)) {
        fprintf(stderr, "testbed study: %s\n", tb_last_error());
        goto done;
    }
    printf("testbed study: %zu cells: %d rendered, %d reused; wrote %s/index.html, report.md, cells.csv, "
           "study.json\n", st.ncells, st.rendered, st.reused, st.out);
    rc = TB_EXIT_OK;
done:
    for (int s = 0; s < st.nscenes; s++)
        tb_image_free(st.scenes[s].ref);
    free(env);
    free(jobs);
    free(st.cells);
    return rc;
}
