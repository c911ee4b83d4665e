/* The outputs of `testbed study` (docs/study.md, "Outputs"): statistics over
 * seeds (util/stats/summary.h), cells.csv, study.json, report.md,
 * index.html, the display images (PNG renders, error maps and crops of the
 * first seed) and the gnuplot plots. Every file goes through a temporary
 * name (util/base/outfile.h; gnuplot writes *.part files renamed here). */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "study.h"
#include "util/base/outfile.h"
#include "util/image/compare.h"
#include "util/stats/summary.h"

extern char **environ;

/* Statistics over the seeds of one scene, method and budget. */
typedef struct tb__point {
    tb_summary relmse, rmse, ssim, wall, cpu, rss;
} tb__point;

/* What the report says per scene, besides the cells. */
typedef struct tb__scene_report {
    tb__point *pts;              /* [method][budget] */
    tb_line_fit fit_budget[TB_STUDY_NMETHODS]; /* log relMSE on log budget, every cell */
    tb_line_fit fit_time[TB_STUDY_NMETHODS];   /* log mean relMSE on log mean wall time */
    bool has_fit_budget[TB_STUDY_NMETHODS], has_fit_time[TB_STUDY_NMETHODS];
    double exposure;             /* stops of the display PNGs (the reference's automatic exposure) */
    double err_scale;            /* error maps: this RMS difference is yellow */
    int crop_size;               /* side of the crops in pixels */
    int crop_x[2], crop_y[2];    /* top-left corners: worst at the largest budget, worst at the smallest */
    bool images;                 /* display images written */
    bool plot_time, plot_budget; /* plots written */
} tb__scene_report;

/* ------------------------------------------------------------------ helpers */

static tb__point *tb__pt(const tb_study *st, tb__scene_report *r, int m, int b)
{
    return &r->pts[(size_t)m * (size_t)st->nbudgets + (size_t)b];
}

static const char *tb__mname(const tb_study *st, int m)
{
    return tb_study_method_names[st->methods[m]];
}

/* A JSON number, or null when not finite. */
static void tb__jnum(FILE *f, double v)
{
    if (isfinite(v))
        fprintf(f, "%.9g", v);
    else
        fputs("null", f);
}

/* A JSON string. */
static void tb__jstr(FILE *f, const char *s)
{
    fputc('"', f);
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\')
            fprintf(f, "\\%c", c);
        else if (c < 0x20)
            fprintf(f, "\\u%04x", c);
        else
            fputc(c, f);
    }
    fputc('"', f);
}

/* Text with &, <, >, " escaped for HTML. */
static void tb__html(FILE *f, const char *s)
{
    for (; *s; s++)
        switch (*s) {
        case '&': fputs("&amp;", f); break;
        case '<': fputs("&lt;", f); break;
        case '>': fputs("&gt;", f); break;
        case '"': fputs("&quot;", f); break;
        default: fputc(*s, f);
        }
}

/* A CSV field: quoted when it holds a comma, quote or newline. */
static void tb__csv(FILE *f, const char *s)
{
    if (!strpbrk(s, ",\"\n")) {
        fputs(s, f);
        return;
    }
    fputc('"', f);
    for (; *s; s++) {
        if (*s == '"')
            fputc('"', f);
        fputc(*s, f);
    }
    fputc('"', f);
}

/* A number for tables: 4 significant digits, "–" when not finite. */
static const char *tb__fmt(double v, char *buf, size_t n)
{
    if (!isfinite(v))
        snprintf(buf, n, "–");
    else
        snprintf(buf, n, "%.4g", v);
    return buf;
}

/* "mean ± ci" (or the mean alone with one seed). */
static const char *tb__pm(const tb_summary *s, double scale, char *buf, size_t n)
{
    char a[24], b[24];
    if (isfinite(s->ci95))
        snprintf(buf, n, "%s ± %s", tb__fmt(s->mean * scale, a, sizeof a), tb__fmt(s->ci95 * scale, b, sizeof b));
    else
        snprintf(buf, n, "%s", tb__fmt(s->mean * scale, a, sizeof a));
    return buf;
}

static const char *tb__kind_unit(const tb_study *st)
{
    return st->kind == TB_STUDY_SPP ? "spp" : "s";
}

/* The display name of budget b ("4 spp", "0.5 s"). */
static const char *tb__budget_label(const tb_study *st, int b, char *buf, size_t n)
{
    snprintf(buf, n, "%g %s", st->budgets[b], tb__kind_unit(st));
    return buf;
}

/* Budget b as method m spends it ("4 spp"; radiosity: "4 (mesh)"). */
static const char *tb__method_budget(const tb_study *st, int m, int b, char *buf, size_t n)
{
    if (st->kind == TB_STUDY_SPP && st->methods[m] == TB_STUDY_RADIOSITY)
        snprintf(buf, n, "%g (mesh)", st->budgets[b]);
    else
        tb__budget_label(st, b, buf, n);
    return buf;
}

/* The time of the equal-time axis: mean wall or CPU seconds. */
static const tb_summary *tb__time(const tb_study *st, const tb__point *p)
{
    return st->time_cpu ? &p->cpu : &p->wall;
}

/* The name of that time. */
static const char *tb__time_name(const tb_study *st)
{
    return st->time_cpu ? "CPU seconds" : "wall seconds";
}

/* A display file name's stem for (method m, budget b) ("path-spp4"). */
static void tb__img_stem(const tb_study *st, int m, int b, char *buf, size_t n)
{
    snprintf(buf, n, "%s-%s%g", tb__mname(st, m), st->kind == TB_STUDY_SPP ? "spp" : "sec", st->budgets[b]);
}

static bool tb__exists(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0 && S_ISREG(sb.st_mode);
}

/* mkdir for one folder level. */
static tb_status tb__mkdir(const char *path)
{
    if (mkdir(path, 0755) && errno != EEXIST)
        return tb_error(TB_ERR_IO, "cannot make folder %s: %s", path, strerror(errno));
    return TB_OK;
}

/* ------------------------------------------------------------- statistics */

static tb_status tb__summarise(const tb_study *st, int s, tb__scene_report *r)
{
    int k = st->nseeds;
    double *v[6];
    bool ok = true;
    for (int i = 0; i < 6; i++)
        ok = (v[i] = malloc(sizeof(double) * (size_t)k)) && ok;
    double *allx = malloc(sizeof(double) * (size_t)(st->nbudgets * k));
    double *ally = malloc(sizeof(double) * (size_t)(st->nbudgets * k));
    ok = ok && allx && ally;
    for (int m = 0; ok && m < st->nmethods; m++) {
        double tx[TB_STUDY_MAX_BUDGETS], ty[TB_STUDY_MAX_BUDGETS];
        int n = 0;
        for (int b = 0; b < st->nbudgets; b++) {
            for (int i = 0; i < k; i++) {
                const tb_study_cell *c = tb_study_cell_at(st, s, m, b, i);
                v[0][i] = c->relmse, v[1][i] = c->rmse, v[2][i] = c->ssim;
                v[3][i] = c->wall_seconds, v[4][i] = c->cpu_seconds, v[5][i] = c->peak_rss_bytes;
                allx[n] = st->budgets[b], ally[n] = c->relmse, n++;
            }
            tb__point *p = tb__pt(st, r, m, b);
            p->relmse = tb_summarize(v[0], k), p->rmse = tb_summarize(v[1], k), p->ssim = tb_summarize(v[2], k);
            p->wall = tb_summarize(v[3], k), p->cpu = tb_summarize(v[4], k), p->rss = tb_summarize(v[5], k);
            tx[b] = tb__time(st, p)->mean, ty[b] = p->relmse.mean;
        }
        r->has_fit_budget[m] = tb_fit_loglog(allx, ally, n, &r->fit_budget[m]) == TB_OK;
        r->has_fit_time[m] = tb_fit_loglog(tx, ty, st->nbudgets, &r->fit_time[m]) == TB_OK;
    }
    for (int i = 0; i < 6; i++)
        free(v[i]);
    free(allx);
    free(ally);
    return ok ? TB_OK : tb_error(TB_ERR_NOMEM, "out of memory");
}

/* The mean curves of method m: x = mean wall seconds, y = mean relMSE, by budget. */
static void tb__curve(const tb_study *st, tb__scene_report *r, int m, double *t, double *e)
{
    for (int b = 0; b < st->nbudgets; b++) {
        t[b] = tb__time(st, tb__pt(st, r, m, b))->mean;
        e[b] = tb__pt(st, r, m, b)->relmse.mean;
    }
}

/* ------------------------------------------------------- display images */

/* The cell image of method m, budget b, seed 0; NULL (message set) on failure. */
static tb_image *tb__cell_image(const tb_study *st, int s, int m, int b)
{
    char path[PATH_MAX + 600];
    snprintf(path, sizeof path, "%s/%s/image.exr", st->out, tb_study_cell_at(st, s, m, b, 0)->dir);
    tb_image *img = NULL;
    return tb_image_read(path, NULL, &img) ? NULL : img;
}

/* Per-pixel relative squared error (mean over channels), added into acc. */
static void tb__add_error(const tb_image *a, const tb_image *ref, double *acc)
{
    int nc = a->channels < ref->channels ? a->channels : ref->channels;
    for (size_t p = 0; p < (size_t)a->width * (size_t)a->height; p++) {
        double e = 0;
        for (int c = 0; c < nc; c++) {
            double x = a->pixels[p * (size_t)a->channels + (size_t)c], y = ref->pixels[p * (size_t)ref->channels + (size_t)c];
            double d = (x - y) * (x - y) / (y * y + TB_COMPARE_RELMSE_EPS);
            if (isfinite(d))
                e += d;
        }
        acc[p] += e / nc;
    }
}

/* The top-left corner of the size x size window with the largest sum of acc. */
static void tb__worst_window(const double *acc, int w, int h, int size, int *bx, int *by)
{
    double *sat = calloc((size_t)(w + 1) * (size_t)(h + 1), sizeof *sat);
    *bx = (w - size) / 2, *by = (h - size) / 2;
    if (!sat)
        return;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            sat[(size_t)(y + 1) * (size_t)(w + 1) + (size_t)(x + 1)] =
                acc[(size_t)y * (size_t)w + (size_t)x] + sat[(size_t)y * (size_t)(w + 1) + (size_t)(x + 1)] +
                sat[(size_t)(y + 1) * (size_t)(w + 1) + (size_t)x] - sat[(size_t)y * (size_t)(w + 1) + (size_t)x];
    double best = -1;
    for (int y = 0; y + size <= h; y++)
        for (int x = 0; x + size <= w; x++) {
            size_t W = (size_t)(w + 1);
            double v = sat[(size_t)(y + size) * W + (size_t)(x + size)] - sat[(size_t)y * W + (size_t)(x + size)] -
                       sat[(size_t)(y + size) * W + (size_t)x] + sat[(size_t)y * W + (size_t)x];
            if (v > best)
                best = v, *bx = x, *by = y;
        }
    free(sat);
}

/* A size x size crop of img at (x0, y0). */
static tb_image *tb__crop(const tb_image *img, int x0, int y0, int size)
{
    const char *names[TB_COMPARE_MAX_CHANNELS];
    int nc = img->channels > TB_COMPARE_MAX_CHANNELS ? TB_COMPARE_MAX_CHANNELS : img->channels;
    for (int c = 0; c < nc; c++)
        names[c] = img->names[c];
    tb_image *out = tb_image_create(size, size, nc, names);
    if (!out)
        return NULL;
    for (int y = 0; y < size; y++)
        for (int x = 0; x < size; x++)
            for (int c = 0; c < nc; c++)
                tb_image_at(out, x, y)[c] = tb_image_at(img, x0 + x, y0 + y)[c];
    return out;
}

/* Writes PREFIX.png (exposed) and PREFIX-crop0.png, PREFIX-crop1.png. */
static tb_status tb__write_display(const tb__scene_report *r, tb_image *img, const char *prefix)
{
    char path[PATH_MAX + 700];
    snprintf(path, sizeof path, "%s.png", prefix);
    tb_status e = tb_image_write_exposed(path, img, r->exposure);
    for (int i = 0; i < 2 && !e; i++) {
        tb_image *c = tb__crop(img, r->crop_x[i], r->crop_y[i], r->crop_size);
        if (!c)
            return TB_ERR_NOMEM;
        snprintf(path, sizeof path, "%s-crop%d.png", prefix, i);
        e = tb_image_write_exposed(path, c, r->exposure);
        tb_image_free(c);
    }
    return e;
}

/* DIR/images/SCENE/: reference.png, and per method and budget (seed 0) the
 * render, its error map and both crops of each. */
static tb_status tb__display_images(const tb_study *st, int s, tb__scene_report *r)
{
    const tb_study_scene *sc = &st->scenes[s];
    tb_image *ref = sc->ref;
    int w = ref->width, h = ref->height;
    char dir[PATH_MAX + 200], prefix[PATH_MAX + 400];
    snprintf(dir, sizeof dir, "%s/images", st->out);
    tb_status e = tb__mkdir(dir);
    snprintf(dir, sizeof dir, "%s/images/%s", st->out, sc->name);
    if (!e)
        e = tb__mkdir(dir);
    if (e)
        return e;
    /* the reference's exposure for every PNG, so brightness compares */
    tb_image *rc = tb_image_clone(ref);
    if (!rc)
        return TB_ERR_NOMEM;
    snprintf(prefix, sizeof prefix, "%s/reference.png", dir);
    e = tb_image_write_exposed(prefix, rc, NAN);
    const char *ex = tb_image_get_attr(rc, "exposure");
    r->exposure = ex ? atof(ex) : 0;
    tb_image_free(rc);
    if (e)
        return e;
    /* error maps: an RMS difference equal to the reference's mean value is yellow */
    double sum = 0;
    size_t n = (size_t)w * (size_t)h * (size_t)ref->channels;
    for (size_t i = 0; i < n; i++)
        sum += isfinite(ref->pixels[i]) ? ref->pixels[i] : 0;
    r->err_scale = sum > 0 ? sum / (double)n : 1;
    /* crops: where the methods' relative error is largest at the largest and at the smallest budget */
    r->crop_size = (w < h ? w : h) / 4;
    if (r->crop_size < 4)
        r->crop_size = w < h ? w : h;
    double *acc = calloc((size_t)w * (size_t)h, sizeof *acc);
    if (!acc)
        return TB_ERR_NOMEM;
    for (int i = 0; i < 2 && !e; i++) {
        int b = i == 0 ? st->nbudgets - 1 : 0;
        memset(acc, 0, sizeof *acc * (size_t)w * (size_t)h);
        for (int m = 0; m < st->nmethods && !e; m++) {
            tb_image *img = tb__cell_image(st, s, m, b);
            if (!img)
                e = TB_ERR_IO;
            else if (img->width != w || img->height != h)
                e = tb_error(TB_ERR_ARG, "%s: %dx%d image, the reference is %dx%d", sc->path, img->width,
                             img->height, w, h);
            else
                tb__add_error(img, ref, acc);
            tb_image_free(img);
        }
        tb__worst_window(acc, w, h, r->crop_size, &r->crop_x[i], &r->crop_y[i]);
    }
    free(acc);
    if (e)
        return e;
    snprintf(prefix, sizeof prefix, "%s/reference", dir);
    rc = tb_image_clone(ref);
    if (!rc)
        return TB_ERR_NOMEM;
    e = tb__write_display(r, rc, prefix);
    tb_image_free(rc);
    for (int m = 0; m < st->nmethods && !e; m++)
        for (int b = 0; b < st->nbudgets && !e; b++) {
            tb_image *img = tb__cell_image(st, s, m, b);
            if (!img)
                return TB_ERR_IO;
            char stem[128];
            tb__img_stem(st, m, b, stem, sizeof stem);
            snprintf(prefix, sizeof prefix, "%s/%s", dir, stem);
            e = tb__write_display(r, img, prefix);
            tb_image *err = NULL;
            if (!e)
                e = tb_compare_error_image(img, ref, NULL, r->err_scale, &err, NULL);
            if (!e) {
                snprintf(prefix, sizeof prefix, "%s/%s-error", dir, stem);
                tb__scene_report er = *r;
                er.exposure = 0; /* the colour map as it is */
                e = tb__write_display(&er, err, prefix);
            }
            tb_image_free(err);
            tb_image_free(img);
        }
    r->images = !e;
    return e;
}

/* ------------------------------------------------------------------ plots */

/* Writes a gnuplot string literal (single quotes, '' for a quote). */
static void tb__gpstr(FILE *f, const char *s)
{
    fputc('\'', f);
    for (; *s; s++) {
        if (*s == '\'')
            fputc('\'', f);
        fputc(*s, f);
    }
    fputc('\'', f);
}

/* Runs `gnuplot SCRIPT`; true on exit status 0. */
static bool tb__gnuplot(const char *script, const char *log)
{
    posix_spawn_file_actions_t fa;
    if (posix_spawn_file_actions_init(&fa))
        return false;
    posix_spawn_file_actions_addopen(&fa, 1, log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    char *argv[] = {"gnuplot", (char *)script, NULL};
    pid_t pid;
    int e = posix_spawnp(&pid, "gnuplot", &fa, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    if (e)
        return false;
    int ws;
    while (waitpid(pid, &ws, 0) < 0)
        if (errno != EINTR)
            return false;
    return WIFEXITED(ws) && WEXITSTATUS(ws) == 0;
}

/* The lower end of a confidence band on a log axis: mean - ci, or a tenth
 * of the mean when that is not positive. */
static double tb__band_lo(const tb_summary *s)
{
    double lo = s->mean - (isfinite(s->ci95) ? s->ci95 : 0);
    return lo > 0 ? lo : s->mean / 10;
}

/* DIR/plots/SCENE.dat and .gp, then the plots error-time and error-budget
 * (PNG and SVG). A missing or failing gnuplot leaves the plots out (said on
 * stderr), not the study. */
static tb_status tb__plots(const tb_study *st, int s, tb__scene_report *r)
{
    const char *name = st->scenes[s].name;
    char dir[PATH_MAX + 100], dat[PATH_MAX + 200], gp[PATH_MAX + 200], log[PATH_MAX + 200];
    snprintf(dir, sizeof dir, "%s/plots", st->out);
    tb_status e = tb__mkdir(dir);
    if (e)
        return e;
    snprintf(dat, sizeof dat, "%s/%s.dat", dir, name);
    snprintf(gp, sizeof gp, "%s/%s.gp", dir, name);
    snprintf(log, sizeof log, "%s/%s.log", dir, name);
    tb_outfile of;
    if ((e = tb_outfile_open(&of, dat)))
        return e;
    fprintf(of.fp, "# testbed study: %s; one block per method (gnuplot index = method order)\n", name);
    for (int m = 0; m < st->nmethods; m++) {
        fprintf(of.fp, "%s# %s: budget %s_mean %s_ci95 relmse_mean relmse_lo relmse_hi seeds\n", m ? "\n\n" : "",
                tb__mname(st, m), st->time_cpu ? "cpu" : "wall", st->time_cpu ? "cpu" : "wall");
        for (int b = 0; b < st->nbudgets; b++) {
            const tb__point *p = tb__pt(st, r, m, b);
            double hi = p->relmse.mean + (isfinite(p->relmse.ci95) ? p->relmse.ci95 : 0);
            const tb_summary *t = tb__time(st, p);
            fprintf(of.fp, "%.9g %.9g %.9g %.9g %.9g %.9g %d\n", st->budgets[b], t->mean, isfinite(t->ci95) ? t->ci95 : 0, p->relmse.mean, tb__band_lo(&p->relmse), hi,
                    p->relmse.n);
        }
    }
    if ((e = tb_outfile_commit(&of)))
        return e;
    if ((e = tb_outfile_open(&of, gp)))
        return e;
    FILE *f = of.fp;
    fprintf(f, "# testbed study: the plots of %s (run: gnuplot %s.gp, from the folder of the study's -o)\n", name,
            name);
    fprintf(f, "set logscale xy\nset grid\nset key outside right top\nset ylabel 'relMSE (mean over seeds, 95%% CI band)'\n");
    static const char *const colours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd"};
    for (int plot = 0; plot < 2; plot++) {
        const char *what = plot == 0 ? "error-time" : "error-budget";
        if (plot == 0)
            fprintf(f, "set xlabel '%s per render (mean over seeds)'\n", tb__time_name(st));
        else
        {
            bool rad = false;
            for (int m = 0; m < st->nmethods; m++)
                rad = rad || st->methods[m] == TB_STUDY_RADIOSITY;
            fprintf(f, "set xlabel 'budget (%s)'\n",
                    st->kind == TB_STUDY_SECONDS ? "seconds"
                    : rad                        ? "samples per pixel; radiosity: mesh refinement"
                                                 : "samples per pixel");
        }
        fprintf(f, "set title ");
        char title[200];
        snprintf(title, sizeof title, "%s: relMSE against %s", name, plot == 0 ? "time" : "budget");
        tb__gpstr(f, title);
        fputc('\n', f);
        for (int m = 0; plot == 1 && m < st->nmethods; m++)
            if (r->has_fit_budget[m])
                fprintf(f, "f%d(x) = 10**(%.9g) * x**(%.9g)\n", m, r->fit_budget[m].intercept,
                        r->fit_budget[m].slope);
        for (int t = 0; t < 2; t++) {
            char out[PATH_MAX + 300];
            snprintf(out, sizeof out, "%s/%s-%s.%s.part", dir, name, what, t == 0 ? "png" : "svg");
            fprintf(f, "set terminal %s\nset output ", t == 0 ? "pngcairo size 800,560" : "svg size 800,560 dynamic");
            tb__gpstr(f, out);
            fprintf(f, "\nplot ");
            int xcol = plot == 0 ? 2 : 1;
            for (int m = 0; m < st->nmethods; m++) {
                fprintf(f, "%s", m ? ", \\\n     " : "");
                tb__gpstr(f, dat);
                fprintf(f, " index %d using %d:5:6 with filledcurves fillstyle transparent solid 0.2 noborder "
                           "lc rgb '%s' notitle, \\\n     ", m, xcol, colours[st->methods[m]]);
                tb__gpstr(f, dat);
                fprintf(f, " index %d using %d:4 with linespoints pt 7 lw 2 lc rgb '%s' title '%s'", m, xcol,
                        colours[st->methods[m]], tb__mname(st, m));
                if (plot == 1 && r->has_fit_budget[m])
                    fprintf(f, ", \\\n     f%d(x) with lines dt 2 lc rgb '%s' title 'fit: slope %.3f'", m,
                            colours[st->methods[m]], r->fit_budget[m].slope);
            }
            fprintf(f, "\nunset output\n");
        }
    }
    if ((e = tb_outfile_commit(&of)))
        return e;
    bool ok = tb__gnuplot(gp, log);
    for (int plot = 0; plot < 2; plot++)
        for (int t = 0; t < 2; t++) {
            char final[PATH_MAX + 300], part[PATH_MAX + 310];
            snprintf(final, sizeof final, "%s/%s-%s.%s", dir, name, plot == 0 ? "error-time" : "error-budget",
                     t == 0 ? "png" : "svg");
            snprintf(part, sizeof part, "%s.part", final);
            if (ok && tb__exists(part) && rename(part, final) == 0)
                continue;
            remove(part);
            ok = false;
        }
    if (!ok) {
        fprintf(stderr, "testbed study: gnuplot failed or is missing (see %s): no plots for %s\n", log, name);
        return TB_OK;
    }
    remove(log);
    r->plot_time = r->plot_budget = true;
    return TB_OK;
}

/* ------------------------------------------------------------- the files */

static tb_status tb__write_csv(const tb_study *st)
{
    char path[PATH_MAX + 32];
    snprintf(path, sizeof path, "%s/cells.csv", st->out);
    tb_outfile of;
    tb_status e = tb_outfile_open(&of, path);
    if (e)
        return e;
    fprintf(of.fp, "scene,method,budget_kind,budget,seed,wall_seconds,cpu_seconds,peak_rss_bytes,relmse,rmse,ssim,"
                   "nonfinite_pixels,reused,dir\n");
    for (size_t i = 0; i < st->ncells; i++) {
        const tb_study_cell *c = &st->cells[i];
        tb__csv(of.fp, st->scenes[c->scene].name);
        fprintf(of.fp, ",%s,%s,%.15g,%d,%.6f,%.6f,%.0f,%.9g,%.9g,%.9g,%lld,%d,", tb__mname(st, c->method),
                st->kind == TB_STUDY_SPP ? "spp" : "seconds", st->budgets[c->budget], c->seed, c->wall_seconds,
                c->cpu_seconds, c->peak_rss_bytes, c->relmse, c->rmse, c->ssim, c->nonfinite, c->reused);
        tb__csv(of.fp, c->dir);
        fputc('\n', of.fp);
    }
    return tb_outfile_commit(&of);
}

static void tb__jsummary(FILE *f, const char *key, const tb_summary *s)
{
    fprintf(f, "\"%s\": {\"mean\": ", key);
    tb__jnum(f, s->mean);
    fprintf(f, ", \"ci95\": ");
    tb__jnum(f, s->ci95);
    fprintf(f, ", \"sd\": ");
    tb__jnum(f, s->sd);
    fprintf(f, ", \"min\": ");
    tb__jnum(f, s->min);
    fprintf(f, ", \"max\": ");
    tb__jnum(f, s->max);
    fprintf(f, ", \"n\": %d}", s->n);
}

static void tb__jfit(FILE *f, const char *key, bool ok, const tb_line_fit *fit)
{
    fprintf(f, "\"%s\": ", key);
    if (!ok) {
        fputs("null", f);
        return;
    }
    fprintf(f, "{\"slope\": ");
    tb__jnum(f, fit->slope);
    fprintf(f, ", \"slope_se\": ");
    tb__jnum(f, fit->slope_se);
    fprintf(f, ", \"intercept\": ");
    tb__jnum(f, fit->intercept);
    fprintf(f, ", \"r2\": ");
    tb__jnum(f, fit->r2);
    fprintf(f, ", \"points\": %d}", fit->n);
}

static tb_status tb__write_json(const tb_study *st, tb__scene_report *reps)
{
    char path[PATH_MAX + 32];
    snprintf(path, sizeof path, "%s/study.json", st->out);
    tb_outfile of;
    tb_status e = tb_outfile_open(&of, path);
    if (e)
        return e;
    FILE *f = of.fp;
    fprintf(f, "{\n  \"budget_kind\": \"%s\",\n  \"methods\": [", st->kind == TB_STUDY_SPP ? "spp" : "seconds");
    for (int m = 0; m < st->nmethods; m++)
        fprintf(f, "%s\"%s\"", m ? ", " : "", tb__mname(st, m));
    fprintf(f, "],\n  \"budgets\": [");
    for (int b = 0; b < st->nbudgets; b++)
        fprintf(f, "%s%.17g", b ? ", " : "", st->budgets[b]);
    fprintf(f, "],\n  \"time_axis\": \"%s\",\n  \"seeds\": %d,\n  \"cells_total\": %zu,\n  \"cells_rendered\": %d,\n  \"cells_reused\": %d,\n",
            st->time_cpu ? "cpu" : "wall", st->nseeds, st->ncells, st->rendered, st->reused);
    fprintf(f, "  \"scenes\": [\n");
    for (int s = 0; s < st->nscenes; s++) {
        const tb_study_scene *sc = &st->scenes[s];
        tb__scene_report *r = &reps[s];
        fprintf(f, "    {\"name\": ");
        tb__jstr(f, sc->name);
        fprintf(f, ", \"path\": ");
        tb__jstr(f, sc->path);
        fprintf(f, ", \"sha256\": \"%s\",\n     \"reference\": {\"path\": ", sc->sha256);
        tb__jstr(f, sc->reference);
        fprintf(f, ", \"given\": %s", sc->reference_given ? "true" : "false");
        if (!sc->reference_given)
            fprintf(f, ", \"method\": \"%s\", \"spp\": %.0f", st->reference_method, sc->reference_spp);
        fprintf(f, "},\n     \"summary\": [\n");
        for (int m = 0; m < st->nmethods; m++)
            for (int b = 0; b < st->nbudgets; b++) {
                const tb__point *p = tb__pt(st, r, m, b);
                fprintf(f, "       {\"method\": \"%s\", \"budget\": %.17g, ", tb__mname(st, m), st->budgets[b]);
                tb__jsummary(f, "relmse", &p->relmse);
                fputs(", ", f);
                tb__jsummary(f, "rmse", &p->rmse);
                fputs(", ", f);
                tb__jsummary(f, "ssim", &p->ssim);
                fputs(", ", f);
                tb__jsummary(f, "wall_seconds", &p->wall);
                fputs(", ", f);
                tb__jsummary(f, "cpu_seconds", &p->cpu);
                fputs(", ", f);
                tb__jsummary(f, "peak_rss_bytes", &p->rss);
                fprintf(f, "}%s\n", m + 1 == st->nmethods && b + 1 == st->nbudgets ? "" : ",");
            }
        fprintf(f, "     ],\n     \"convergence\": [\n");
        for (int m = 0; m < st->nmethods; m++) {
            fprintf(f, "       {\"method\": \"%s\", ", tb__mname(st, m));
            tb__jfit(f, "relmse_vs_budget", r->has_fit_budget[m], &r->fit_budget[m]);
            fputs(", ", f);
            tb__jfit(f, "relmse_vs_time", r->has_fit_time[m], &r->fit_time[m]);
            fprintf(f, "}%s\n", m + 1 == st->nmethods ? "" : ",");
        }
        /* the tables, against the first method's budgets */
        fprintf(f, "     ],\n     \"equal_time\": [\n");
        double t0[TB_STUDY_MAX_BUDGETS], e0[TB_STUDY_MAX_BUDGETS], t[TB_STUDY_MAX_BUDGETS], er[TB_STUDY_MAX_BUDGETS];
        tb__curve(st, r, 0, t0, e0);
        for (int b = 0; b < st->nbudgets; b++) {
            fprintf(f, "       {\"seconds\": ");
            tb__jnum(f, t0[b]);
            fprintf(f, ", \"relmse\": {");
            for (int m = 0; m < st->nmethods; m++) {
                tb__curve(st, r, m, t, er);
                fprintf(f, "%s\"%s\": ", m ? ", " : "", tb__mname(st, m));
                tb__jnum(f, tb_loglog_y_at(t, er, st->nbudgets, t0[b]));
            }
            fprintf(f, "}}%s\n", b + 1 == st->nbudgets ? "" : ",");
        }
        fprintf(f, "     ],\n     \"equal_error\": [\n");
        for (int b = 0; b < st->nbudgets; b++) {
            fprintf(f, "       {\"relmse\": ");
            tb__jnum(f, e0[b]);
            fprintf(f, ", \"seconds\": {");
            for (int m = 0; m < st->nmethods; m++) {
                tb__curve(st, r, m, t, er);
                fprintf(f, "%s\"%s\": ", m ? ", " : "", tb__mname(st, m));
                tb__jnum(f, tb_loglog_x_at(t, er, st->nbudgets, e0[b]));
            }
            fprintf(f, "}}%s\n", b + 1 == st->nbudgets ? "" : ",");
        }
        fprintf(f, "     ]}%s\n", s + 1 == st->nscenes ? "" : ",");
    }
    fprintf(f, "  ],\n  \"cells\": [\n");
    for (size_t i = 0; i < st->ncells; i++) {
        const tb_study_cell *c = &st->cells[i];
        fprintf(f, "    {\"scene\": ");
        tb__jstr(f, st->scenes[c->scene].name);
        fprintf(f, ", \"method\": \"%s\", \"budget\": %.17g, \"seed\": %d, \"dir\": ", tb__mname(st, c->method),
                st->budgets[c->budget], c->seed);
        tb__jstr(f, c->dir);
        fprintf(f, ", \"reused\": %s, \"wall_seconds\": ", c->reused ? "true" : "false");
        tb__jnum(f, c->wall_seconds);
        fprintf(f, ", \"cpu_seconds\": ");
        tb__jnum(f, c->cpu_seconds);
        fprintf(f, ", \"peak_rss_bytes\": ");
        tb__jnum(f, c->peak_rss_bytes);
        fprintf(f, ", \"relmse\": ");
        tb__jnum(f, c->relmse);
        fprintf(f, ", \"rmse\": ");
        tb__jnum(f, c->rmse);
        fprintf(f, ", \"ssim\": ");
        tb__jnum(f, c->ssim);
        fprintf(f, ", \"nonfinite_pixels\": %lld}%s\n", c->nonfinite, i + 1 == st->ncells ? "" : ",");
    }
    fprintf(f, "  ]\n}\n");
    return tb_outfile_commit(&of);
}

/* The tables of one scene, in Markdown (md) or HTML. */
static void tb__tables(FILE *f, const tb_study *st, tb__scene_report *r, bool md)
{
    char a[64], b1[64], c1[64], d1[64], e1[64], g1[64], h1[64];
    const char *m0 = tb__mname(st, 0);
    /* summary */
    if (md)
        fprintf(f, "\n#### Summary (mean ± 95%% CI over %d seed(s))\n\n"
                   "| method | budget | wall s | CPU s | peak RSS MiB | relMSE | RMSE | SSIM |\n"
                   "|---|---|---|---|---|---|---|---|\n", st->nseeds);
    else
        fprintf(f, "<h4>Summary (mean ± 95%% CI over %d seed(s))</h4>\n<table>\n<tr><th>method</th><th>budget</th>"
                   "<th>wall s</th><th>CPU s</th><th>peak RSS MiB</th><th>relMSE</th><th>RMSE</th><th>SSIM</th>"
                   "</tr>\n", st->nseeds);
    for (int m = 0; m < st->nmethods; m++)
        for (int b = 0; b < st->nbudgets; b++) {
            const tb__point *p = tb__pt(st, r, m, b);
            const char *sep = md ? " | " : "</td><td>";
            fprintf(f, "%s%s%s%s%s%s%s%s%s%s%s%s%s%s%s%s%s", md ? "| " : "<tr><td>", tb__mname(st, m), sep,
                    tb__method_budget(st, m, b, a, sizeof a), sep, tb__pm(&p->wall, 1, b1, sizeof b1), sep,
                    tb__pm(&p->cpu, 1, c1, sizeof c1), sep, tb__fmt(p->rss.max / 1048576.0, d1, sizeof d1), sep,
                    tb__pm(&p->relmse, 1, e1, sizeof e1), sep, tb__pm(&p->rmse, 1, g1, sizeof g1), sep,
                    tb__pm(&p->ssim, 1, h1, sizeof h1), md ? " |\n" : "</td></tr>\n");
        }
    if (!md)
        fputs("</table>\n", f);
    /* convergence */
    if (md)
        fprintf(f, "\n#### Convergence (least-squares slopes on log-log axes)\n\n"
                   "| method | relMSE vs budget (every cell) | r² | relMSE vs time (means) |\n|---|---|---|---|\n");
    else
        fprintf(f, "<h4>Convergence (least-squares slopes on log-log axes)</h4>\n<table>\n<tr><th>method</th>"
                   "<th>relMSE vs budget (every cell)</th><th>r²</th><th>relMSE vs time (means)</th></tr>\n");
    for (int m = 0; m < st->nmethods; m++) {
        const char *sep = md ? " | " : "</td><td>";
        char slope[64];
        if (r->has_fit_budget[m] && isfinite(r->fit_budget[m].slope_se))
            snprintf(slope, sizeof slope, "%.3f ± %.3f", r->fit_budget[m].slope, 1.96 * r->fit_budget[m].slope_se);
        else
            tb__fmt(r->has_fit_budget[m] ? r->fit_budget[m].slope : NAN, slope, sizeof slope);
        fprintf(f, "%s%s%s%s%s%s%s%s%s", md ? "| " : "<tr><td>", tb__mname(st, m), sep, slope, sep,
                tb__fmt(r->has_fit_budget[m] ? r->fit_budget[m].r2 : NAN, a, sizeof a), sep,
                tb__fmt(r->has_fit_time[m] ? r->fit_time[m].slope : NAN, b1, sizeof b1),
                md ? " |\n" : "</td></tr>\n");
    }
    if (!md)
        fputs("</table>\n", f);
    /* equal time and equal error, at the first method's points */
    double t0[TB_STUDY_MAX_BUDGETS], e0[TB_STUDY_MAX_BUDGETS], t[TB_STUDY_MAX_BUDGETS], er[TB_STUDY_MAX_BUDGETS];
    tb__curve(st, r, 0, t0, e0);
    for (int table = 0; table < 2; table++) {
        if (md) {
            fprintf(f, table == 0 ? "\n#### Equal time: relMSE each method reaches in the time %s takes\n\n| %s |"
                                  : "\n#### Equal error: %s each method needs to reach the relMSE %s reaches\n\n"
                                    "| relMSE |",
                    table == 0 ? m0 : tb__time_name(st), table == 0 ? tb__time_name(st) : m0);
            for (int m = 0; m < st->nmethods; m++)
                fprintf(f, " %s |", tb__mname(st, m));
            fputs("\n|---|", f);
            for (int m = 0; m < st->nmethods; m++)
                fputs("---|", f);
            fputc('\n', f);
        } else {
            fprintf(f, table == 0 ? "<h4>Equal time: relMSE each method reaches in the time %s takes</h4>\n"
                                    "<table>\n<tr><th>%s</th>"
                                  : "<h4>Equal error: %s each method needs to reach the relMSE %s reaches</h4>\n"
                                    "<table>\n<tr><th>relMSE</th>",
                    table == 0 ? m0 : tb__time_name(st), table == 0 ? tb__time_name(st) : m0);
            for (int m = 0; m < st->nmethods; m++)
                fprintf(f, "<th>%s</th>", tb__mname(st, m));
            fputs("</tr>\n", f);
        }
        for (int b = 0; b < st->nbudgets; b++) {
            fprintf(f, md ? "| %s |" : "<tr><td>%s</td>", tb__fmt(table == 0 ? t0[b] : e0[b], a, sizeof a));
            for (int m = 0; m < st->nmethods; m++) {
                tb__curve(st, r, m, t, er);
                double v = table == 0 ? tb_loglog_y_at(t, er, st->nbudgets, t0[b])
                                      : tb_loglog_x_at(t, er, st->nbudgets, e0[b]);
                fprintf(f, md ? " %s |" : "<td>%s</td>", tb__fmt(v, a, sizeof a));
            }
            fputs(md ? "\n" : "</tr>\n", f);
        }
        if (!md)
            fputs("</table>\n", f);
    }
    if (md)
        fprintf(f, "\n(–: outside the range the method was measured over; log-log interpolation between budgets.)\n");
    else
        fprintf(f, "<p class=\"note\">–: outside the range the method was measured over; log-log interpolation "
                   "between budgets.</p>\n");
}

/* The cells of scene s with NaN or infinite pixels (a broken render: the
 * errors leave those pixels out, the means may be absurd), if any. */
static void tb__warnings(FILE *f, const tb_study *st, int s, bool md)
{
    int n = 0;
    for (size_t i = 0; i < st->ncells; i++) {
        const tb_study_cell *c = &st->cells[i];
        if (c->scene != s || !c->nonfinite)
            continue;
        if (n++ == 0)
            fputs(md ? "\n#### Warnings: renders with NaN or infinite pixels (left out of their errors)\n\n"
                     : "<h4>Warnings: renders with NaN or infinite pixels (left out of their errors)</h4>\n<ul>\n",
                  f);
        if (md)
            fprintf(f, "- `%s/image.exr`: %lld pixel(s)\n", c->dir, c->nonfinite);
        else {
            fprintf(f, "<li><a href=\"");
            tb__html(f, c->dir);
            fprintf(f, "/image.exr\">");
            tb__html(f, c->dir);
            fprintf(f, "/image.exr</a>: %lld pixel(s)</li>\n", c->nonfinite);
        }
    }
    if (n && !md)
        fputs("</ul>\n", f);
}

static tb_status tb__write_md(const tb_study *st, tb__scene_report *reps)
{
    char path[PATH_MAX + 32];
    snprintf(path, sizeof path, "%s/report.md", st->out);
    tb_outfile of;
    tb_status e = tb_outfile_open(&of, path);
    if (e)
        return e;
    FILE *f = of.fp;
    fprintf(f, "# Testbed study\n\nMethods:");
    for (int m = 0; m < st->nmethods; m++)
        fprintf(f, " %s", tb__mname(st, m));
    fprintf(f, "; budgets (%s):", st->kind == TB_STUDY_SPP ? "samples per pixel" : "seconds");
    for (int b = 0; b < st->nbudgets; b++)
        fprintf(f, " %g", st->budgets[b]);
    fprintf(f, "; %d seed(s) per cell; %zu cells (%d rendered by this run, %d reused).\n"
               "Definitions: docs/study.md. Every cell: cells.csv; everything: study.json; pictures: index.html.\n",
            st->nseeds, st->ncells, st->rendered, st->reused);
    for (int s = 0; s < st->nscenes; s++) {
        const tb_study_scene *sc = &st->scenes[s];
        fprintf(f, "\n## %s\n\nScene `%s` (SHA-256 %.16s…); reference `%s`", sc->name, sc->path, sc->sha256,
                sc->reference);
        if (sc->reference_given)
            fprintf(f, " (given).\n");
        else
            fprintf(f, " (%s, %.0f spp).\n", st->reference_method, sc->reference_spp);
        if (reps[s].plot_time)
            fprintf(f, "\n![relMSE against time](plots/%s-error-time.png)\n"
                       "![relMSE against budget](plots/%s-error-budget.png)\n", sc->name, sc->name);
        tb__tables(f, st, &reps[s], true);
        tb__warnings(f, st, s, true);
    }
    return tb_outfile_commit(&of);
}

/* An <img> with a pixel-exact upscale to about `px` wide. */
static void tb__img(FILE *f, const char *src, int w, int px, const char *alt)
{
    int k = w > 0 && w < px ? px / w : 1;
    fprintf(f, "<img src=\"");
    tb__html(f, src);
    fprintf(f, "\" width=\"%d\" alt=\"", w * k);
    tb__html(f, alt);
    fprintf(f, "\">");
}

static tb_status tb__write_html(const tb_study *st, tb__scene_report *reps)
{
    char path[PATH_MAX + 32];
    snprintf(path, sizeof path, "%s/index.html", st->out);
    tb_outfile of;
    tb_status e = tb_outfile_open(&of, path);
    if (e)
        return e;
    FILE *f = of.fp;
    fprintf(f, "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>Testbed study</title>\n"
               "<style>\nbody { font-family: sans-serif; margin: 1.5em; }\n"
               "table { border-collapse: collapse; margin: 0.5em 0 1em 0; }\n"
               "td, th { border: 1px solid #bbb; padding: 2px 6px; text-align: right; }\n"
               "th { background: #eee; }\ntable.images td { text-align: center; vertical-align: top; }\n"
               "img { image-rendering: pixelated; margin: 1px; }\n.note { color: #555; font-size: 90%%; }\n"
               "</style>\n</head>\n<body>\n<h1>Testbed study</h1>\n<p>Methods:");
    for (int m = 0; m < st->nmethods; m++)
        fprintf(f, " %s", tb__mname(st, m));
    fprintf(f, "; budgets (%s):", st->kind == TB_STUDY_SPP ? "samples per pixel" : "seconds");
    for (int b = 0; b < st->nbudgets; b++)
        fprintf(f, " %g", st->budgets[b]);
    fprintf(f, "; %d seed(s) per cell; %zu cells (%d rendered by this run, %d reused). Files: "
               "<a href=\"report.md\">report.md</a>, <a href=\"cells.csv\">cells.csv</a>, "
               "<a href=\"study.json\">study.json</a>. Definitions: docs/study.md.</p>\n",
            st->nseeds, st->ncells, st->rendered, st->reused);
    for (int s = 0; s < st->nscenes; s++) {
        const tb_study_scene *sc = &st->scenes[s];
        tb__scene_report *r = &reps[s];
        fprintf(f, "<h2 id=\"scene-%s\">", sc->name);
        tb__html(f, sc->name);
        fprintf(f, "</h2>\n<p>Scene <code>");
        tb__html(f, sc->path);
        fprintf(f, "</code> (SHA-256 %.16s…); reference <code>", sc->sha256);
        tb__html(f, sc->reference);
        if (sc->reference_given)
            fprintf(f, "</code> (given).</p>\n");
        else
            fprintf(f, "</code> (%s, %.0f spp).</p>\n", st->reference_method, sc->reference_spp);
        if (r->plot_time) {
            fprintf(f, "<p>");
            for (int p = 0; p < 2; p++) {
                const char *what = p == 0 ? "error-time" : "error-budget";
                fprintf(f, "<a href=\"plots/%s-%s.svg\"><img src=\"plots/%s-%s.png\" width=\"560\" alt=\"%s\"></a>",
                        sc->name, what, sc->name, what, what);
            }
            fprintf(f, "</p>\n");
        }
        tb__tables(f, st, r, false);
        tb__warnings(f, st, s, false);
        if (!r->images)
            continue;
        fprintf(f, "<h4>Images (seed 0; PNGs at the reference's exposure, %+.2f stops; error maps: RMS difference "
                   "over channels, yellow at %.4g and above; crops %dx%d: where the methods' error is largest at "
                   "the largest (1) and the smallest (2) budget)</h4>\n",
                r->exposure, r->err_scale, r->crop_size, r->crop_size);
        int w = sc->ref->width;
        char src[700], alt[200];
        fprintf(f, "<table class=\"images\">\n<tr><th>reference</th><td colspan=\"%d\">", st->nbudgets);
        snprintf(src, sizeof src, "images/%s/reference.png", sc->name);
        tb__img(f, src, w, 192, "reference");
        for (int i = 0; i < 2; i++) {
            snprintf(src, sizeof src, "images/%s/reference-crop%d.png", sc->name, i);
            snprintf(alt, sizeof alt, "reference, crop %d", i + 1);
            tb__img(f, src, r->crop_size, 96, alt);
        }
        fprintf(f, "</td></tr>\n<tr><th>method</th>");
        for (int b = 0; b < st->nbudgets; b++)
            fprintf(f, "<th>budget %s</th>", tb__budget_label(st, b, alt, sizeof alt));
        fprintf(f, "</tr>\n");
        for (int m = 0; m < st->nmethods; m++) {
            fprintf(f, "<tr><th>%s</th>", tb__mname(st, m));
            for (int b = 0; b < st->nbudgets; b++) {
                char stem[128];
                tb__img_stem(st, m, b, stem, sizeof stem);
                fprintf(f, "<td>");
                for (int k = 0; k < 2; k++) {
                    snprintf(src, sizeof src, "images/%s/%s%s.png", sc->name, stem, k ? "-error" : "");
                    snprintf(alt, sizeof alt, "%s%s", stem, k ? " error" : "");
                    tb__img(f, src, w, 96, alt);
                }
                fprintf(f, "<br>");
                for (int k = 0; k < 2; k++)
                    for (int i = 0; i < 2; i++) {
                        snprintf(src, sizeof src, "images/%s/%s%s-crop%d.png", sc->name, stem, k ? "-error" : "", i);
                        snprintf(alt, sizeof alt, "%s%s crop %d", stem, k ? " error" : "", i + 1);
                        tb__img(f, src, r->crop_size, 44, alt);
                    }
                const tb_study_cell *c = tb_study_cell_at(st, s, m, b, 0);
                char v[32];
                fprintf(f, "<br>relMSE %s<br><a href=\"", tb__fmt(c->relmse, v, sizeof v));
                tb__html(f, c->dir);
                fprintf(f, "/image.exr\">exr</a> <a href=\"");
                tb__html(f, c->dir);
                fprintf(f, "/stats.json\">stats</a> <a href=\"");
                tb__html(f, c->dir);
                fprintf(f, "/log.txt\">log</a></td>");
            }
            fprintf(f, "</tr>\n");
        }
        fprintf(f, "</table>\n");
    }
    fprintf(f, "</body>\n</html>\n");
    return tb_outfile_commit(&of);
}

tb_status tb_study_write_outputs(tb_study *st)
{
    tb__scene_report *reps = calloc((size_t)st->nscenes, sizeof *reps);
    if (!reps)
        return tb_error(TB_ERR_NOMEM, "out of memory");
    tb_status e = TB_OK;
    for (int s = 0; s < st->nscenes && !e; s++) {
        reps[s].pts = calloc((size_t)st->nmethods * (size_t)st->nbudgets, sizeof *reps[s].pts);
        if (!reps[s].pts) {
            e = tb_error(TB_ERR_NOMEM, "out of memory");
            break;
        }
        e = tb__summarise(st, s, &reps[s]);
        if (!e)
            e = tb__display_images(st, s, &reps[s]);
        if (!e)
            e = tb__plots(st, s, &reps[s]);
    }
    if (!e)
        e = tb__write_csv(st);
    if (!e)
        e = tb__write_json(st, reps);
    if (!e)
        e = tb__write_md(st, reps);
    if (!e)
        e = tb__write_html(st, reps);
    for (int s = 0; s < st->nscenes; s++)
        free(reps[s].pts);
    free(reps);
    return e;
}
