/* Virtual instruments (measure.h, docs/measure.md). */
#include "host/hybrid/measure.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "host/render/pathtrace.h"
#include "host/render/sampling.h"
#include "host/render/shading.h"
#include "host/render/surface.h"
#include "util/base/progress.h"
#include "util/base/str.h"
#include "util/color/bands.h"
#include "util/color/cie.h"
#include "util/color/spectrum_file.h"
#include "util/color/srgb.h"
#include "util/math/rng.h"

#define TB__PI 3.14159265358979323846

/* ------------------------------------------------------------- CSV lines */

/* The most fields a row of either file has. */
#define TB__CSV_MAX_FIELDS 16

/* One line of a CSV file split into trimmed fields (pointers into `buf`). */
typedef struct tb__csv_row {
    char *buf;
    size_t cap;
    int n;
    char *f[TB__CSV_MAX_FIELDS + 1];
    long line;
} tb__csv_row;

static char *tb__trim(char *s)
{
    while (*s && isspace((unsigned char)*s))
        s++;
    char *e = s + strlen(s);
    while (e > s && isspace((unsigned char)e[-1]))
        *--e = '\0';
    return s;
}

/* Reads the next row that is neither blank nor a `#` comment. 1: a row; 0:
 * end of file; -1: a read error (message set). */
static int tb__csv_next(FILE *fp, const char *name, tb__csv_row *r)
{
    for (;;) {
        errno = 0;
        ssize_t len = getline(&r->buf, &r->cap, fp);
        if (len < 0) {
            if (ferror(fp)) {
                tb_error(TB_ERR_IO, "%s: read error: %s", name, strerror(errno ? errno : EIO));
                return -1;
            }
            return 0;
        }
        r->line++;
        if (memchr(r->buf, '\0', (size_t)len)) {
            tb_error(TB_ERR_FORMAT, "%s:%ld: error: NUL byte in the line", name, r->line);
            return -1;
        }
        char *s = tb__trim(r->buf);
        if (*s == '\0' || *s == '#')
            continue;
        r->n = 0;
        for (char *p = s;;) {
            char *c = strchr(p, ',');
            if (c)
                *c = '\0';
            if (r->n == TB__CSV_MAX_FIELDS) {
                tb_error(TB_ERR_FORMAT, "%s:%ld: error: more than %d columns", name, r->line, TB__CSV_MAX_FIELDS);
                return -1;
            }
            r->f[r->n++] = tb__trim(p);
            if (!c)
                break;
            p = c + 1;
        }
        return 1;
    }
}

/* A finite number filling the whole field. */
static bool tb__number(const char *s, double *out)
{
    if (!*s)
        return false;
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (*end || !isfinite(v))
        return false;
    *out = v;
    return true;
}

/* Checks a header against the expected column names: the first `required`
 * must be there in order, the rest of `cols` may follow in order. */
static tb_status tb__header(const char *name, const tb__csv_row *r, const char *const *cols, int ncols, int required)
{
    for (int i = 0; i < r->n; i++) {
        if (i >= ncols)
            return tb_error(TB_ERR_FORMAT, "%s:%ld: error: header: unexpected column '%s' (expected %d at most)",
                            name, r->line, r->f[i], ncols);
        if (strcmp(r->f[i], cols[i]) != 0)
            return tb_error(TB_ERR_FORMAT, "%s:%ld: error: header: column %d is '%s', expected '%s'", name, r->line,
                            i + 1, r->f[i], cols[i]);
    }
    if (r->n < required)
        return tb_error(TB_ERR_FORMAT, "%s:%ld: error: header: missing column '%s'", name, r->line, cols[r->n]);
    return TB_OK;
}

/* ---------------------------------------------------------- sensors file */

static const char *const tb__sensor_cols[] = {"name", "kind", "x", "y", "z", "dx", "dy", "dz", "half_angle_deg",
                                              "filter"};

void tb_sensors_free(tb_sensor_set *set)
{
    if (!set)
        return;
    for (int i = 0; i < set->n; i++) {
        free(set->s[i].filter_path);
        tb_spectrum_release(&set->s[i].filter);
    }
    free(set->s);
    memset(set, 0, sizeof *set);
}

/* `rel` resolved against `base_dir` (absolute paths and a NULL base as given). */
static char *tb__resolve(const char *base_dir, const char *rel)
{
    if (rel[0] == '/' || !base_dir || !*base_dir)
        return tb_strdup(rel);
    size_t nb = strlen(base_dir), nr = strlen(rel);
    char *p = malloc(nb + nr + 2);
    if (p) {
        memcpy(p, base_dir, nb);
        p[nb] = '/';
        memcpy(p + nb + 1, rel, nr + 1);
    }
    return p;
}

/* Parses one sensor row into *s. */
static tb_status tb__sensor_row(const char *name, const char *base_dir, const tb__csv_row *r, int ncols,
                                tb_sensor *s)
{
    const long ln = r->line;
    memset(s, 0, sizeof *s); /* the caller frees it whatever happens below */
    if (r->n > ncols)
        return tb_error(TB_ERR_FORMAT, "%s:%ld: error: %d columns, the header has %d", name, ln, r->n, ncols);
    if (r->n < 8)
        return tb_error(TB_ERR_FORMAT, "%s:%ld: error: missing column '%s'", name, ln, tb__sensor_cols[r->n]);
    s->line = ln;
    if (!*r->f[0])
        return tb_error(TB_ERR_FORMAT, "%s:%ld: error: empty sensor name", name, ln);
    if (strlen(r->f[0]) > TB_SENSOR_NAME_MAX)
        return tb_error(TB_ERR_FORMAT, "%s:%ld: error: sensor name longer than %d characters", name, ln,
                        TB_SENSOR_NAME_MAX);
    strcpy(s->name, r->f[0]);
    if (strcmp(r->f[1], "irradiance") == 0)
        s->kind = TB_SENSOR_IRRADIANCE;
    else if (strcmp(r->f[1], "radiance") == 0)
        s->kind = TB_SENSOR_RADIANCE;
    else
        return tb_error(TB_ERR_FORMAT, "%s:%ld: error: unknown kind '%s' (irradiance or radiance)", name, ln,
                        r->f[1]);
    double v[6];
    for (int i = 0; i < 6; i++)
        if (!tb__number(r->f[2 + i], &v[i]))
            return tb_error(TB_ERR_FORMAT, "%s:%ld: error: %s: expected a finite number, got '%s'", name, ln,
                            tb__sensor_cols[2 + i], r->f[2 + i]);
    for (int i = 0; i < 6; i++)
        if (fabs(v[i]) > 1e30)
            return tb_error(TB_ERR_FORMAT, "%s:%ld: error: %s: %g is out of range", name, ln, tb__sensor_cols[2 + i],
                            v[i]);
    const double dl = sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5]);
    if (!(dl > 1e-30) || !isfinite(dl))
        return tb_error(TB_ERR_FORMAT, "%s:%ld: error: zero direction (dx, dy, dz)", name, ln);
    s->p = (tb_vec3){(float)v[0], (float)v[1], (float)v[2]};
    s->d = (tb_vec3){(float)(v[3] / dl), (float)(v[4] / dl), (float)(v[5] / dl)};
    const char *ha = r->n > 8 ? r->f[8] : "";
    if (s->kind == TB_SENSOR_RADIANCE) {
        double a;
        if (!*ha)
            return tb_error(TB_ERR_FORMAT, "%s:%ld: error: a radiance sensor needs half_angle_deg", name, ln);
        if (!tb__number(ha, &a))
            return tb_error(TB_ERR_FORMAT, "%s:%ld: error: half_angle_deg: expected a finite number, got '%s'", name,
                            ln, ha);
        if (!(a > 0.0 && a <= 90.0))
            return tb_error(TB_ERR_FORMAT, "%s:%ld: error: half_angle_deg %g is not in (0, 90]", name, ln, a);
        s->half_angle_deg = a;
    } else if (*ha) {
        return tb_error(TB_ERR_FORMAT,
                        "%s:%ld: error: half_angle_deg is for radiance sensors (an irradiance meter sees the "
                        "whole hemisphere): leave it empty",
                        name, ln);
    }
    const char *fl = r->n > 9 ? r->f[9] : "";
    if (*fl) {
        s->filter_path = tb__resolve(base_dir, fl);
        if (!s->filter_path)
            return tb_error(TB_ERR_NOMEM, "%s:%ld: error: out of memory", name, ln);
        tb_status st = tb_spectrum_read_file(s->filter_path, &s->filter);
        if (st)
            return tb_error(st, "%s:%ld: error: filter '%s': %s", name, ln, s->filter_path, tb_last_error());
        for (int i = 0; i < s->filter.n; i++)
            if (s->filter.value[i] < 0.0)
                return tb_error(TB_ERR_FORMAT, "%s:%ld: error: filter '%s': transmission %g < 0 at %g nm", name, ln,
                                s->filter_path, s->filter.value[i], s->filter.lambda[i]);
    }
    return TB_OK;
}

tb_status tb_sensors_read_stream(FILE *fp, const char *name, const char *base_dir, tb_sensor_set *out)
{
    memset(out, 0, sizeof *out);
    tb__csv_row r = {0};
    tb_sensor_set set = {0};
    int cap = 0, ncols = 0;
    tb_status st = TB_OK;
    int k = tb__csv_next(fp, name, &r);
    if (k < 0)
        st = TB_ERR_IO;
    else if (k == 0)
        st = tb_error(TB_ERR_FORMAT, "%s:%ld: error: no header (name,kind,x,y,z,dx,dy,dz,half_angle_deg,filter)",
                      name, r.line + 1);
    else {
        st = tb__header(name, &r, tb__sensor_cols, 10, 8);
        ncols = r.n;
    }
    while (!st && (k = tb__csv_next(fp, name, &r)) > 0) {
        if (set.n == cap) {
            int nc = cap ? 2 * cap : 16;
            tb_sensor *ns = realloc(set.s, (size_t)nc * sizeof *ns);
            if (!ns) {
                st = tb_error(TB_ERR_NOMEM, "%s: out of memory", name);
                break;
            }
            set.s = ns;
            cap = nc;
        }
        tb_sensor *s = &set.s[set.n];
        st = tb__sensor_row(name, base_dir, &r, ncols, s);
        set.n++; /* owned now, freed with the set even when the row failed */
        if (st)
            break;
        for (int i = 0; i < set.n - 1; i++)
            if (strcmp(set.s[i].name, s->name) == 0) {
                st = tb_error(TB_ERR_FORMAT, "%s:%ld: error: duplicate sensor name '%s' (first on line %ld)", name,
                              r.line, s->name, set.s[i].line);
                break;
            }
        if (s->filter.n)
            set.filtered = true;
    }
    if (!st && k < 0)
        st = TB_ERR_IO;
    if (!st && set.n == 0)
        st = tb_error(TB_ERR_FORMAT, "%s:%ld: error: no sensors", name, r.line);
    free(r.buf);
    if (st) {
        tb_sensors_free(&set);
        return st;
    }
    *out = set;
    return TB_OK;
}

tb_status tb_sensors_read_file(const char *path, tb_sensor_set *out)
{
    memset(out, 0, sizeof *out);
    FILE *fp = fopen(path, "r");
    if (!fp)
        return tb_error(TB_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    char *dir = tb_strdup(path);
    if (!dir) {
        fclose(fp);
        return tb_error(TB_ERR_NOMEM, "%s: out of memory", path);
    }
    char *slash = strrchr(dir, '/');
    if (slash)
        slash[slash == dir ? 1 : 0] = '\0';
    tb_status st = tb_sensors_read_stream(fp, path, slash ? dir : NULL, out);
    free(dir);
    fclose(fp);
    return st;
}

/* ---------------------------------------------------------- measured file */

static const char *const tb__measured_cols[] = {"name", "value", "uncertainty"};

void tb_measured_free(tb_measured_set *set)
{
    if (!set)
        return;
    free(set->m);
    memset(set, 0, sizeof *set);
}

tb_status tb_measured_read_stream(FILE *fp, const char *name, const tb_sensor_set *sensors, tb_measured_set *out)
{
    memset(out, 0, sizeof *out);
    tb__csv_row r = {0};
    tb_measured_set set = {0};
    int ncols = 0;
    tb_status st = TB_OK;
    int *seen = calloc((size_t)sensors->n + 1, sizeof *seen); /* line of each sensor's row, 0: none */
    set.m = malloc(((size_t)sensors->n + 1) * sizeof *set.m);
    if (!seen || !set.m)
        st = tb_error(TB_ERR_NOMEM, "%s: out of memory", name);
    int k = st ? -1 : tb__csv_next(fp, name, &r);
    if (!st && k < 0)
        st = TB_ERR_IO;
    else if (!st && k == 0)
        st = tb_error(TB_ERR_FORMAT, "%s:%ld: error: no header (name,value[,uncertainty])", name, r.line + 1);
    else if (!st) {
        st = tb__header(name, &r, tb__measured_cols, 3, 2);
        ncols = r.n;
    }
    while (!st && (k = tb__csv_next(fp, name, &r)) > 0) {
        if (r.n > ncols) {
            st = tb_error(TB_ERR_FORMAT, "%s:%ld: error: %d columns, the header has %d", name, r.line, r.n, ncols);
            break;
        }
        if (r.n < 2) {
            st = tb_error(TB_ERR_FORMAT, "%s:%ld: error: missing column 'value'", name, r.line);
            break;
        }
        int idx = -1;
        for (int i = 0; i < sensors->n; i++)
            if (strcmp(sensors->s[i].name, r.f[0]) == 0)
                idx = i;
        if (idx < 0) {
            st = tb_error(TB_ERR_FORMAT, "%s:%ld: error: no sensor named '%s' in the sensors file", name, r.line,
                          r.f[0]);
            break;
        }
        if (seen[idx]) {
            st = tb_error(TB_ERR_FORMAT, "%s:%ld: error: duplicate measurement of '%s' (first on line %d)", name,
                          r.line, r.f[0], seen[idx]);
            break;
        }
        tb_measured m = {.sensor = idx, .line = r.line};
        if (!tb__number(r.f[1], &m.value)) {
            st = tb_error(TB_ERR_FORMAT, "%s:%ld: error: value: expected a finite number, got '%s'", name, r.line,
                          r.f[1]);
            break;
        }
        if (r.n > 2 && *r.f[2]) {
            if (!tb__number(r.f[2], &m.uncertainty) || m.uncertainty < 0.0) {
                st = tb_error(TB_ERR_FORMAT, "%s:%ld: error: uncertainty: expected a finite number >= 0, got '%s'",
                              name, r.line, r.f[2]);
                break;
            }
        }
        seen[idx] = (int)r.line;
        set.m[set.n++] = m;
    }
    if (!st && k < 0)
        st = TB_ERR_IO;
    if (!st && set.n == 0)
        st = tb_error(TB_ERR_FORMAT, "%s:%ld: error: no measured values", name, r.line);
    free(r.buf);
    free(seen);
    if (st) {
        tb_measured_free(&set);
        return st;
    }
    *out = set;
    return TB_OK;
}

tb_status tb_measured_read_file(const char *path, const tb_sensor_set *sensors, tb_measured_set *out)
{
    memset(out, 0, sizeof *out);
    FILE *fp = fopen(path, "r");
    if (!fp)
        return tb_error(TB_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    tb_status st = tb_measured_read_stream(fp, path, sensors, out);
    fclose(fp);
    return st;
}

/* -------------------------------------------------------------- estimates */

tb_measure_options tb_measure_defaults(void)
{
    tb_measure_options o;
    memset(&o, 0, sizeof o);
    o.method = TB_MEASURE_PATH;
    o.samples = TB_MEASURE_DEFAULT_SAMPLES;
    o.seed = 1;
    o.rad = tb_hybrid_defaults();
    return o;
}

/* Samples per set of jittered strata (8 x 8). */
#define TB__STRATA 64

/* What every sample reads. */
typedef struct tb__mctx {
    const tb_scene *s;
    tb_measure_method method;
    tb_pathtracer *pt;      /* surfaces and lights (both methods), paths (path method) */
    const tb_hybrid *h;     /* radiosity method */
    float eps;              /* the meter sits this far along its direction from its point */
} tb__mctx;

/* acc += k * c, channel by channel. */
static void tb__acc(double *acc, const tb_channels *c, double k)
{
    for (int i = 0; i < c->n; i++)
        acc[i] += k * (double)c->v[i];
}

/* The emission a ray from the sensor meets first (front side of an emitter),
 * MIS-weighted against the area light's sampling from p when pdf_dir > 0;
 * acc += k * Le * w. */
static void tb__hit_emission(const tb__mctx *c, const tb_ray *ray, tb_vec3 p, double pdf_dir, double k, double *acc)
{
    tb_hit hit;
    tb_surface hs;
    if (!tb_scene_intersect(c->s, ray, &hit) || !tb_surface_at(tb_pt_surfaces(c->pt), ray, &hit, NULL, &hs))
        return;
    if (!(hs.emits && hs.front))
        return;
    const tb_channels Le = tb_surface_emitted(&hs);
    double w = 1.0;
    if (pdf_dir > 0.0)
        w = tb_power_heuristic(pdf_dir, tb_light_set_emitter_pdf(tb_pt_lights(c->pt), p, &hs));
    tb__acc(acc, &Le, k * w);
}

/* One irradiance sample: every delta light, one area-light sample and one
 * cosine-distributed direction, the two combined by the power heuristic;
 * acc[0..nc) += the estimate of E. */
static void tb__irradiance_sample(const tb__mctx *c, const tb_sensor *sn, const float *ul, const float *ud,
                                  tb_rng *rng, double *acc)
{
    const tb_light_set *ls = tb_pt_lights(c->pt);
    const tb_vec3 d = sn->d, p = sn->p;
    /* the meter as a surface record: the light set's shadow and emitter tests read p, ng and the origins */
    tb_surface sf;
    memset(&sf, 0, sizeof sf);
    sf.p = p;
    sf.ng = sf.nv = sf.n = d;
    sf.front = true;
    sf.org[0] = tb_vec3_add(p, tb_vec3_scale(d, c->eps));
    sf.org[1] = tb_vec3_sub(p, tb_vec3_scale(d, c->eps));
    sf.object = UINT32_MAX;
    sf.material = -1;
    for (int i = 0; i < ls->nlights; i++) {
        tb_light_sample l;
        if (!tb_light_set_sample(ls, i, p, 0.0f, 0.0f, &l) || tb_channels_is_black(l.L))
            continue;
        const double cs = tb_vec3_dot(l.wi, d);
        if (!(cs > 0.0) || tb_light_set_occluded(ls, &sf, &l))
            continue;
        tb__acc(acc, &l.L, cs);
    }
    if (ls->has_area) {
        const float u1 = ul[0], u2 = ul[1];
        tb_light_sample l;
        tb_channels Le;
        double pl;
        if (tb_light_set_sample(ls, ls->nlights, p, u1, u2, &l)) {
            const double cs = tb_vec3_dot(l.wi, d);
            if (cs > 0.0 && tb_light_set_visible_emitter(ls, tb_pt_surfaces(c->pt), &sf, &l, &Le, &pl))
                tb__acc(acc, &Le, cs * tb_power_heuristic(pl, cs / TB__PI) / pl);
        }
    }
    const tb_vec3 loc = tb_sample_cosine_hemisphere(ud[0], ud[1]);
    if (!(loc.z > 0.0f))
        return;
    const tb_frame fr = tb_frame_from_normal(d);
    const tb_vec3 w = tb_vec3_normalize(tb_frame_to_world(&fr, loc));
    const double pc = (double)loc.z / TB__PI; /* E = pi * mean radiance under this density */
    const tb_ray ray = tb_ray_make(sf.org[0], w, 0.0f, INFINITY);
    if (c->method == TB_MEASURE_PATH) {
        /* the path leaves the meter as from a diffuse vertex: its first hit's
         * emission is weighted against the area-light sample above */
        tb_pt_path path = tb_pt_path_start(c->pt, &ray);
        path.prev_delta = 0;
        path.prev_pdf = pc;
        path.prev_p = p;
        while (!path.done)
            tb_pt_path_step(c->pt, &path, NULL, rng);
        tb__acc(acc, &path.L, TB__PI);
    } else {
        tb__hit_emission(c, &ray, p, ls->has_area ? pc : 0.0, TB__PI, acc);
        double b[TB_CHANNELS_MAX];
        tb_hybrid_gather_ray(c->h, &ray, b); /* pi times the reflected radiance (B - E) / pi */
        for (int i = 0; i < c->s->nchannels; i++)
            acc[i] += b[i];
    }
}

/* One radiance sample: a uniform direction in the cone; acc += its radiance. */
static void tb__radiance_sample(const tb__mctx *c, const tb_sensor *sn, const float *ud, tb_rng *rng, double *acc)
{
    const double cos_max = cos(sn->half_angle_deg * (TB__PI / 180.0));
    const tb_frame fr = tb_frame_from_normal(sn->d);
    const tb_vec3 w = tb_vec3_normalize(tb_frame_to_world(&fr, tb_sample_uniform_cone(ud[0], ud[1], cos_max)));
    const tb_ray ray = tb_ray_make(tb_vec3_add(sn->p, tb_vec3_scale(sn->d, c->eps)), w, 0.0f, INFINITY);
    if (c->method == TB_MEASURE_PATH) {
        const tb_channels L = tb_pt_radiance(c->pt, &ray, rng);
        tb__acc(acc, &L, 1.0);
    } else {
        tb__hit_emission(c, &ray, sn->p, 0.0, 1.0, acc);
        double b[TB_CHANNELS_MAX];
        tb_hybrid_gather_ray(c->h, &ray, b);
        for (int i = 0; i < c->s->nchannels; i++)
            acc[i] += b[i] / TB__PI;
    }
}

/* The reading and photometric value of channel values v (filter applied). */
static void tb__functionals(const tb_scene *s, const double *v, double *reading, double *photometric)
{
    if (s->spectral) {
        const tb_bands *b = &s->bands;
        double r = 0.0, y = 0.0;
        for (int i = 0; i < b->n; i++) {
            /* trapezoid weight of band i: the integral of its hat function */
            const double lo = i > 0 ? b->lambda[i - 1] : b->lambda[i];
            const double hi = i + 1 < b->n ? b->lambda[i + 1] : b->lambda[i];
            r += v[i] * 0.5 * (hi - lo);
            y += v[i] * b->xyz_weight[i][1];
        }
        *reading = r;
        *photometric = TB_CIE_KM * y;
    } else {
        const double rgb[3] = {v[0], v[1], v[2]};
        *reading = tb_linear_srgb_luminance(rgb);
        *photometric = TB_CIE_KM * *reading;
    }
}

/* Mean and standard error of the mean of n values. */
static void tb__mean_se(const double *x, int n, double *mean, double *se)
{
    double m = 0.0;
    for (int i = 0; i < n; i++)
        m += x[i];
    m /= n;
    double ss = 0.0;
    for (int i = 0; i < n; i++)
        ss += (x[i] - m) * (x[i] - m);
    *mean = m;
    *se = n > 1 ? sqrt(ss / ((double)n * (n - 1))) : 0.0;
}

tb_status tb_measure(const tb_scene *s, const tb_sensor_set *set, const tb_measure_options *opt,
                     tb_measure_result *out)
{
    tb_measure_options o = opt ? *opt : tb_measure_defaults();
    if (!s || !s->accel)
        return tb_error(TB_ERR_ARG, "measure: the scene has no acceleration structure");
    if (o.samples < 1)
        return tb_error(TB_ERR_ARG, "measure: samples %d < 1", o.samples);
    if (o.threads < 0)
        return tb_error(TB_ERR_ARG, "measure: threads %d < 0", o.threads);
    if (o.method != TB_MEASURE_PATH && o.method != TB_MEASURE_RADIOSITY)
        return tb_error(TB_ERR_ARG, "measure: unknown method %d", (int)o.method);
    if (set->n == 0)
        return TB_OK;
    if (set->filtered && !s->spectral)
        return tb_error(TB_ERR_ARG, "measure: filters need a spectral scene (load it with spectral colours)");
    const int nc = s->nchannels, B = TB_MEASURE_BATCHES;
    const int per_batch = (int)(((int64_t)o.samples + B - 1) / B);
    /* per sensor: the filter on the bands (1 without one) */
    double *T = malloc((size_t)set->n * (size_t)nc * sizeof *T);
    double *bm = calloc((size_t)set->n * (size_t)B * (size_t)nc, sizeof *bm); /* batch means */
    if (!T || !bm) {
        free(T);
        free(bm);
        return tb_error(TB_ERR_NOMEM, "measure: out of memory");
    }
    tb_status st = TB_OK;
    for (int i = 0; i < set->n && !st; i++) {
        double *t = T + (size_t)i * (size_t)nc;
        if (set->s[i].filter.n)
            st = tb_bands_from_spectrum(&s->bands, &set->s[i].filter, t);
        else
            for (int k = 0; k < nc; k++)
                t[k] = 1.0;
        if (st)
            st = tb_error(st, "measure: sensor '%s': filter: %s", set->s[i].name, tb_last_error());
    }
    tb__mctx c = {.s = s, .method = o.method};
    tb_hybrid *h = NULL;
    if (!st)
        st = tb_pt_create(s, NULL, &c.pt);
    if (!st && o.method == TB_MEASURE_RADIOSITY) {
        tb_hybrid_options ho = o.rad;
        ho.mode = TB_HYBRID_GATHER;
        ho.gather_rays = 1;
        ho.log = o.log;
        ho.log_prefix = "measure: ";
        st = tb_hybrid_create(s, &ho, &h);
        c.h = h;
    }
    if (st) {
        tb_pt_free(c.pt);
        free(T);
        free(bm);
        return tb_error_context(st, "measure");
    }
    const tb_vec3 ext = tb_vec3_sub(s->bounds.hi, s->bounds.lo);
    const double diag = tb_vec3_length(ext);
    c.eps = (float)(1e-5 * (isfinite(diag) && diag > 0.0 ? diag : 1.0));
    const int64_t ntasks = (int64_t)set->n * B;
    tb_progress prog;
    const bool bar = o.progress && tb_progress_start(&prog, "measure", ntasks, NULL, 0) == TB_OK;
    const int nthreads = o.threads > 0 ? o.threads : omp_get_max_threads();
#pragma omp parallel for schedule(dynamic, 1) num_threads(nthreads)
    for (int64_t t = 0; t < ntasks; t++) {
        const int i = (int)(t / B);
        const tb_sensor *sn = &set->s[i];
        tb_rng rng;
        tb_rng_seed(&rng, o.seed, (uint64_t)t);
        double acc[TB_CHANNELS_MAX] = {0};
        /* the light sample's and the direction's numbers are jittered over
         * strata of TB__STRATA samples (a batch stays an independent mean) */
        float ul[2 * TB__STRATA], ud[2 * TB__STRATA];
        for (int k = 0; k < per_batch; k++) {
            const int j = k % TB__STRATA;
            if (j == 0) {
                int nx, ny;
                tb_stratified_dims(per_batch - k < TB__STRATA ? per_batch - k : TB__STRATA, &nx, &ny);
                tb_stratified_2d(&rng, nx, ny, ud);
                if (sn->kind == TB_SENSOR_IRRADIANCE)
                    tb_stratified_2d(&rng, nx, ny, ul);
            }
            if (sn->kind == TB_SENSOR_IRRADIANCE)
                tb__irradiance_sample(&c, sn, ul + 2 * j, ud + 2 * j, &rng, acc);
            else
                tb__radiance_sample(&c, sn, ud + 2 * j, &rng, acc);
        }
        double *m = bm + (size_t)t * (size_t)nc;
        const double *ti = T + (size_t)i * (size_t)nc;
        for (int k = 0; k < nc; k++)
            m[k] = acc[k] / per_batch * ti[k];
        if (bar)
            tb_progress_add(&prog, 1);
    }
    if (bar)
        tb_progress_finish(&prog);
    for (int i = 0; i < set->n; i++) {
        tb_measure_result *r = &out[i];
        memset(r, 0, sizeof *r);
        r->nc = nc;
        r->samples = per_batch * B;
        double x[TB_MEASURE_BATCHES], rd[TB_MEASURE_BATCHES], ph[TB_MEASURE_BATCHES];
        for (int k = 0; k < nc; k++) {
            for (int b = 0; b < B; b++)
                x[b] = bm[((size_t)i * B + (size_t)b) * (size_t)nc + (size_t)k];
            tb__mean_se(x, B, &r->value[k], &r->value_se[k]);
        }
        for (int b = 0; b < B; b++)
            tb__functionals(s, bm + ((size_t)i * B + (size_t)b) * (size_t)nc, &rd[b], &ph[b]);
        tb__mean_se(rd, B, &r->reading, &r->reading_se);
        tb__mean_se(ph, B, &r->photometric, &r->photometric_se);
    }
    tb_hybrid_free(h);
    tb_pt_free(c.pt);
    free(T);
    free(bm);
    return TB_OK;
}

/* ----------------------------------------------------------------- output */

static const char *tb__kind_name(tb_sensor_kind k) { return k == TB_SENSOR_IRRADIANCE ? "irradiance" : "radiance"; }
static const char *tb__reading_unit(tb_sensor_kind k) { return k == TB_SENSOR_IRRADIANCE ? "W/m^2" : "W/m^2/sr"; }
static const char *tb__photo_unit(tb_sensor_kind k) { return k == TB_SENSOR_IRRADIANCE ? "lx" : "cd/m^2"; }

/* The label of channel k: R, G, B or the band's wavelength. */
static void tb__channel_label(const tb_scene *s, int k, char *buf, size_t n)
{
    if (s->spectral)
        snprintf(buf, n, "%gnm", s->bands.lambda[k]);
    else
        snprintf(buf, n, "%c", "RGB"[k]);
}

tb_status tb_measure_write_csv(FILE *f, const tb_scene *s, const tb_sensor_set *set, const tb_measure_result *r)
{
    char lab[32];
    fprintf(f, "name,kind,samples,reading,reading_se,reading_unit,photometric,photometric_se,photometric_unit");
    for (int k = 0; k < s->nchannels; k++) {
        tb__channel_label(s, k, lab, sizeof lab);
        fprintf(f, ",%s", lab);
    }
    for (int k = 0; k < s->nchannels; k++) {
        tb__channel_label(s, k, lab, sizeof lab);
        fprintf(f, ",%s_se", lab);
    }
    fputc('\n', f);
    for (int i = 0; i < set->n; i++) {
        const tb_sensor *sn = &set->s[i];
        fprintf(f, "%s,%s,%d,%.9g,%.3g,%s,%.9g,%.3g,%s", sn->name, tb__kind_name(sn->kind), r[i].samples, r[i].reading,
                r[i].reading_se, tb__reading_unit(sn->kind), r[i].photometric, r[i].photometric_se,
                tb__photo_unit(sn->kind));
        for (int k = 0; k < r[i].nc; k++)
            fprintf(f, ",%.9g", r[i].value[k]);
        for (int k = 0; k < r[i].nc; k++)
            fprintf(f, ",%.3g", r[i].value_se[k]);
        fputc('\n', f);
    }
    if (fflush(f) || ferror(f))
        return tb_error(TB_ERR_IO, "measure: write error: %s", strerror(errno));
    return TB_OK;
}

void tb_measure_print_table(FILE *f, const tb_sensor_set *set, const tb_measure_result *r)
{
    int w = 6;
    for (int i = 0; i < set->n; i++)
        if ((int)strlen(set->s[i].name) > w)
            w = (int)strlen(set->s[i].name);
    fprintf(f, "%-*s  %-10s  %14s  %10s  %-8s  %14s  %10s  %s\n", w, "sensor", "kind", "reading", "s.e.", "unit",
            "photometric", "s.e.", "unit");
    for (int i = 0; i < set->n; i++) {
        const tb_sensor *sn = &set->s[i];
        fprintf(f, "%-*s  %-10s  %14.6g  %10.3g  %-8s  %14.6g  %10.3g  %s\n", w, sn->name, tb__kind_name(sn->kind),
                r[i].reading, r[i].reading_se, tb__reading_unit(sn->kind), r[i].photometric, r[i].photometric_se,
                tb__photo_unit(sn->kind));
    }
}

void tb_measure_compare(FILE *f, const tb_sensor_set *set, const tb_measure_result *r, const tb_measured_set *m,
                        tb_compare_quantity q, double k, tb_compare_summary *sum)
{
    memset(sum, 0, sizeof *sum);
    int w = 6;
    for (int i = 0; i < m->n; i++)
        if ((int)strlen(set->s[m->m[i].sensor].name) > w)
            w = (int)strlen(set->s[m->m[i].sensor].name);
    if (f)
        fprintf(f, "%-*s  %14s  %14s  %12s  %10s  %12s  %s\n", w, "sensor", "simulated", "measured", "residual",
                "relative", "combined u", "agrees");
    double ss_rel = 0.0, ss_res = 0.0;
    int nrel = 0;
    for (int i = 0; i < m->n; i++) {
        const tb_measured *mm = &m->m[i];
        const tb_measure_result *ri = &r[mm->sensor];
        const double sim = q == TB_COMPARE_PHOTOMETRIC ? ri->photometric : ri->reading;
        const double se = q == TB_COMPARE_PHOTOMETRIC ? ri->photometric_se : ri->reading_se;
        const double res = sim - mm->value;
        const double u = sqrt(mm->uncertainty * mm->uncertainty + se * se);
        const bool bad = fabs(res) > k * u;
        double rel = NAN;
        if (mm->value != 0.0) {
            rel = res / mm->value;
            ss_rel += rel * rel;
            nrel++;
            if (fabs(rel) > sum->max_rel)
                sum->max_rel = fabs(rel);
        }
        ss_res += res * res;
        if (fabs(res) > sum->max_resid)
            sum->max_resid = fabs(res);
        sum->compared++;
        sum->disagree += bad;
        if (f)
            fprintf(f, "%-*s  %14.6g  %14.6g  %12.4g  %9.3f%%  %12.4g  %s\n", w, set->s[mm->sensor].name, sim,
                    mm->value, res, 100.0 * rel, u, bad ? "NO" : "yes");
    }
    sum->rms_rel = nrel ? sqrt(ss_rel / nrel) : NAN;
    sum->rms_resid = sum->compared ? sqrt(ss_res / sum->compared) : NAN;
    if (!f)
        return;
    fprintf(f, "compared %d of %d sensors (%s): RMS relative error %.3f%%, max %.3f%%; RMS residual %.4g, max %.4g\n",
            sum->compared, set->n, q == TB_COMPARE_PHOTOMETRIC ? "photometric" : "reading", 100.0 * sum->rms_rel,
            100.0 * sum->max_rel, sum->rms_resid, sum->max_resid);
    if (sum->disagree) {
        fprintf(f, "DISAGREE: %d sensor%s beyond %g x the combined uncertainty:", sum->disagree,
                sum->disagree == 1 ? "" : "s", k);
        for (int i = 0; i < m->n; i++) {
            const tb_measured *mm = &m->m[i];
            const tb_measure_result *ri = &r[mm->sensor];
            const double sim = q == TB_COMPARE_PHOTOMETRIC ? ri->photometric : ri->reading;
            const double se = q == TB_COMPARE_PHOTOMETRIC ? ri->photometric_se : ri->reading_se;
            if (fabs(sim - mm->value) > k * sqrt(mm->uncertainty * mm->uncertainty + se * se))
                fprintf(f, " %s", set->s[mm->sensor].name);
        }
        fputc('\n', f);
    } else {
        fprintf(f, "all %d agree within %g x the combined uncertainty\n", sum->compared, k);
    }
}
