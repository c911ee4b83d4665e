/* IES LM-63 parser, interpolation, flux and sampling (ies.h, docs/lights.md). */
#include "host/render/ies.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util/math/float.h"

/* Largest number of vertical or horizontal angles accepted. */
#define TB__IES_MAX_ANGLES 100000
/* Largest candela value (times the multiplier) accepted. */
#define TB__IES_MAX_CANDELA 1e30
/* Most cells of the sampling grid. */
#define TB__IES_MAX_CELLS ((size_t)1 << 22)
/* Largest file tb_ies_read reads. */
#define TB__IES_MAX_FILE (64L << 20)
/* Largest step (degrees) of the sampling grid in gamma and in C. */
#define TB__IES_STEP_V 1.0
#define TB__IES_STEP_H 5.0

/* ------------------------------------------------------------------ lexing */

typedef struct tb__lex {
    const char *s;    /* text */
    size_t len, pos;  /* length, read position */
    long line;        /* line of pos, from 1 */
    const char *name; /* for messages */
} tb__lex;

static tb_status tb__err(const tb__lex *lx, long line, tb_status st, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

static tb_status tb__err(const tb__lex *lx, long line, tb_status st, const char *fmt, ...)
{
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return tb_error(st, "%s:%ld: error: %s", lx->name, line, msg);
}

static bool tb__is_sep(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v' || c == ',';
}

/* Skips separators (counting lines); true if a token follows. */
static bool tb__skip(tb__lex *lx)
{
    while (lx->pos < lx->len && tb__is_sep(lx->s[lx->pos])) {
        if (lx->s[lx->pos] == '\n')
            lx->line++;
        lx->pos++;
    }
    return lx->pos < lx->len;
}

/* A printable copy of the token at [b, e) for messages (at most 24 bytes). */
static void tb__show(const char *b, const char *e, char *out, size_t cap)
{
    size_t n = 0;
    for (const char *p = b; p < e && n + 4 < cap && n < 24; p++)
        out[n++] = (*p >= 32 && *p < 127) ? *p : '?';
    if (e - b > 24 && n + 4 < cap) {
        memcpy(out + n, "...", 3);
        n += 3;
    }
    out[n] = '\0';
}

/* True if [b, e) is a decimal number: [+-] digits [. digits] [eE [+-] digits],
 * with at least one digit before or after the point (no nan, inf, hex). */
static bool tb__decimal(const char *b, const char *e)
{
    const char *p = b;
    if (p < e && (*p == '+' || *p == '-'))
        p++;
    int digits = 0;
    while (p < e && *p >= '0' && *p <= '9') {
        p++;
        digits++;
    }
    if (p < e && *p == '.') {
        p++;
        while (p < e && *p >= '0' && *p <= '9') {
            p++;
            digits++;
        }
    }
    if (digits == 0)
        return false;
    if (p < e && (*p == 'e' || *p == 'E')) {
        p++;
        if (p < e && (*p == '+' || *p == '-'))
            p++;
        int ed = 0;
        while (p < e && *p >= '0' && *p <= '9') {
            p++;
            ed++;
        }
        if (ed == 0)
            return false;
    }
    return p == e;
}

/* Reads the next number, naming it `what` in messages; *line gets its line. */
static tb_status tb__number(tb__lex *lx, const char *what, double *v, long *line)
{
    if (!tb__skip(lx))
        return tb__err(lx, lx->line, TB_ERR_FORMAT, "expected %s, found end of file", what);
    const char *b = lx->s + lx->pos, *e = b;
    while (e < lx->s + lx->len && !tb__is_sep(*e))
        e++;
    *line = lx->line;
    char shown[40];
    if (!tb__decimal(b, e) || e - b > 64) {
        tb__show(b, e, shown, sizeof shown);
        return tb__err(lx, lx->line, TB_ERR_FORMAT, "expected %s, found '%s'", what, shown);
    }
    char buf[72];
    memcpy(buf, b, (size_t)(e - b));
    buf[e - b] = '\0';
    errno = 0;
    double x = strtod(buf, NULL);
    if (!isfinite(x)) {
        tb__show(b, e, shown, sizeof shown);
        return tb__err(lx, lx->line, TB_ERR_FORMAT, "%s '%s' is out of range", what, shown);
    }
    lx->pos = (size_t)(e - lx->s);
    *v = x;
    return TB_OK;
}

/* A number that must be an integer in [lo, hi]. */
static tb_status tb__integer(tb__lex *lx, const char *what, long lo, long hi, int *out)
{
    double v;
    long line;
    tb_status st = tb__number(lx, what, &v, &line);
    if (st)
        return st;
    if (v != floor(v) || v < (double)lo || v > (double)hi)
        return tb__err(lx, line, TB_ERR_FORMAT, "%s must be an integer from %ld to %ld, found %.17g",
                       what, lo, hi, v);
    *out = (int)v;
    return TB_OK;
}

/* ------------------------------------------------------------- the header */

/* Copy of [b, e) with spaces trimmed. */
static char *tb__strndup_trim(const char *b, const char *e)
{
    while (b < e && (*b == ' ' || *b == '\t' || *b == '\r'))
        b++;
    while (e > b && (e[-1] == ' ' || e[-1] == '\t' || e[-1] == '\r'))
        e--;
    char *s = malloc((size_t)(e - b) + 1);
    if (s) {
        memcpy(s, b, (size_t)(e - b));
        s[e - b] = '\0';
    }
    return s;
}

static bool tb__starts(const char *b, const char *e, const char *prefix)
{
    size_t n = strlen(prefix);
    return (size_t)(e - b) >= n && memcmp(b, prefix, n) == 0;
}

/* Adds a keyword line "[KEY] value" (already known to start with '['). */
static tb_status tb__add_keyword(tb_ies *ies, const tb__lex *lx, const char *b, const char *e)
{
    const char *close = memchr(b, ']', (size_t)(e - b));
    if (!close)
        return tb__err(lx, lx->line, TB_ERR_FORMAT, "keyword line without ']'");
    tb_ies_keyword *k = realloc(ies->keywords, sizeof *k * (size_t)(ies->nkeywords + 1));
    if (!k)
        return tb_error(TB_ERR_NOMEM, "%s: out of memory for keywords", lx->name);
    ies->keywords = k;
    k += ies->nkeywords;
    k->key = tb__strndup_trim(b + 1, close);
    k->value = tb__strndup_trim(close + 1, e);
    ies->nkeywords++;
    if (!k->key || !k->value)
        return tb_error(TB_ERR_NOMEM, "%s: out of memory for keywords", lx->name);
    return TB_OK;
}

/* Reads the lines up to and including TILT=; leaves lx after that line. */
static tb_status tb__header(tb_ies *ies, tb__lex *lx)
{
    bool first = true;
    while (lx->pos < lx->len) {
        const char *b = lx->s + lx->pos, *end = lx->s + lx->len;
        const char *nl = memchr(b, '\n', (size_t)(end - b));
        const char *e = nl ? nl : end;
        /* Leading spaces do not matter. */
        const char *t = b;
        while (t < e && (*t == ' ' || *t == '\t'))
            t++;
        if (first) {
            first = false;
            if (tb__starts(t, e, "IESNA:LM-63-2002"))
                strcpy(ies->version, "LM-63-2002");
            else if (tb__starts(t, e, "IESNA:LM-63-1995"))
                strcpy(ies->version, "LM-63-1995");
            else if (tb__starts(t, e, "IESNA91"))
                strcpy(ies->version, "LM-63-1991");
            else
                strcpy(ies->version, "LM-63-1986"); /* no version line: free text labels */
            if (strcmp(ies->version, "LM-63-1986") != 0)
                goto next;
        }
        if (tb__starts(t, e, "TILT")) {
            const char *p = t + 4;
            while (p < e && (*p == ' ' || *p == '\t'))
                p++;
            if (p >= e || *p != '=')
                return tb__err(lx, lx->line, TB_ERR_FORMAT, "expected '=' after TILT");
            p++;
            char *v = tb__strndup_trim(p, e);
            if (!v)
                return tb_error(TB_ERR_NOMEM, "%s: out of memory", lx->name);
            bool none = strcmp(v, "NONE") == 0, include = strcmp(v, "INCLUDE") == 0;
            free(v);
            if (include)
                return tb__err(lx, lx->line, TB_ERR_UNSUPPORTED,
                               "TILT=INCLUDE (lamp tilt factors) is not supported; only TILT=NONE");
            if (!none)
                return tb__err(lx, lx->line, TB_ERR_UNSUPPORTED,
                               "TILT=<file> (tilt factors in another file) is not supported; only TILT=NONE");
            lx->pos = (size_t)(e - lx->s);
            return TB_OK; /* the newline (if any) is counted by the number lexer */
        }
        if (t < e && *t == '[') {
            tb_status st = tb__add_keyword(ies, lx, t, e);
            if (st)
                return st;
        }
        /* Other lines before TILT (LM-63-1986 labels) are free text. */
    next:
        if (!nl) {
            lx->pos = lx->len;
            break;
        }
        lx->pos = (size_t)(nl + 1 - lx->s);
        lx->line++;
    }
    return tb__err(lx, lx->line, TB_ERR_FORMAT, "no TILT= line before the end of the file");
}

/* ------------------------------------------------------------ interpolation */

/* Index i of the interval [a[i], a[i+1]] holding x (a strictly increasing, n >= 2, a[0] <= x <= a[n-1]). */
static int tb__interval(const double *a, int n, double x)
{
    int lo = 0, hi = n - 2;
    while (lo < hi) {
        int mid = lo + (hi - lo + 1) / 2;
        if (a[mid] <= x)
            lo = mid;
        else
            hi = mid - 1;
    }
    return lo;
}

/* Horizontal angle reduced into the table's range by its symmetry. */
static double tb__reduce_h(const tb_ies *ies, double h)
{
    h = fmod(h, 360.0);
    if (h < 0.0)
        h += 360.0;
    if (h >= 360.0)
        h = 0.0;
    switch (ies->symmetry) {
    case TB_IES_SYM_QUADRANT:
        if (h > 180.0)
            h = 360.0 - h;
        if (h > 90.0)
            h = 180.0 - h;
        break;
    case TB_IES_SYM_BILATERAL:
        if (h > 180.0)
            h = 360.0 - h;
        break;
    case TB_IES_SYM_BILATERAL_90:
        if (h < 90.0)
            h = 180.0 - h;
        else if (h > 270.0)
            h = 540.0 - h;
        break;
    default:
        break;
    }
    return h;
}

double tb_ies_candela(const tb_ies *ies, double vertical, double horizontal)
{
    if (!(vertical >= ies->v_angles[0] && vertical <= ies->v_angles[ies->nv - 1]) || isnan(horizontal))
        return 0.0;
    int i = tb__interval(ies->v_angles, ies->nv, vertical);
    double t = (vertical - ies->v_angles[i]) / (ies->v_angles[i + 1] - ies->v_angles[i]);
    const double *c = ies->candela;
    int nv = ies->nv;
    if (ies->nh == 1 || ies->symmetry == TB_IES_SYM_ROTATIONAL)
        return (1.0 - t) * c[i] + t * c[i + 1];
    double h = tb__reduce_h(ies, horizontal);
    h = tb_clamp(h, ies->h_angles[0], ies->h_angles[ies->nh - 1]);
    int j = tb__interval(ies->h_angles, ies->nh, h);
    double s = (h - ies->h_angles[j]) / (ies->h_angles[j + 1] - ies->h_angles[j]);
    /* (1 - t) a + t b is exactly a at t = 0 and exactly b at t = 1, so
     * tabulated angles give tabulated values. */
    double lo = (1.0 - t) * c[j * nv + i] + t * c[j * nv + i + 1];
    double hi = (1.0 - t) * c[(j + 1) * nv + i] + t * c[(j + 1) * nv + i + 1];
    return (1.0 - s) * lo + s * hi;
}

void tb_ies_angles(tb_vec3 w, double *vertical, double *horizontal)
{
    double x = w.x, y = w.y, z = w.z;
    *vertical = atan2(sqrt(x * x + y * y), -z) * (180.0 / TB_PI);
    double h = atan2(y, x) * (180.0 / TB_PI);
    if (h < 0.0)
        h += 360.0;
    if (h >= 360.0)
        h = 0.0;
    *horizontal = h;
}

tb_vec3 tb_ies_direction(double vertical, double horizontal)
{
    double g = tb_radians(vertical), c = tb_radians(horizontal);
    return tb_vec3_make((float)(sin(g) * cos(c)), (float)(sin(g) * sin(c)), (float)-cos(g));
}

double tb_ies_candela_dir(const tb_ies *ies, tb_vec3 w)
{
    double v, h;
    tb_ies_angles(w, &v, &h);
    return tb_ies_candela(ies, v, h);
}

double tb_ies_normalized(const tb_ies *ies, tb_vec3 w)
{
    return tb_ies_candela_dir(ies, w) / ies->max_candela;
}

/* ------------------------------------------------------- the full circle */

static int tb__cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The table's horizontal nodes mapped onto [0, 360] by the symmetry, sorted
 * and unique: between two consecutive ones the reduced angle is linear in C
 * and stays within one table interval. Returns the count (*out malloc'ed). */
static int tb__full_circle(const tb_ies *ies, double **out)
{
    int nh = ies->nh;
    double *e = malloc(sizeof(double) * (4 * (size_t)nh + 2));
    if (!e)
        return -1;
    int n = 0;
    e[n++] = 0.0;
    e[n++] = 360.0;
    if (ies->symmetry != TB_IES_SYM_ROTATIONAL)
        for (int j = 0; j < nh; j++) {
            double a = ies->h_angles[j];
            switch (ies->symmetry) {
            case TB_IES_SYM_QUADRANT:
                e[n++] = a;
                e[n++] = 180.0 - a;
                e[n++] = 180.0 + a;
                e[n++] = 360.0 - a;
                break;
            case TB_IES_SYM_BILATERAL:
                e[n++] = a;
                e[n++] = 360.0 - a;
                break;
            case TB_IES_SYM_BILATERAL_90:
                e[n++] = a;
                e[n++] = fmod(540.0 - a, 360.0);
                break;
            default:
                e[n++] = a;
                break;
            }
        }
    qsort(e, (size_t)n, sizeof(double), tb__cmp_double);
    int m = 0;
    for (int k = 0; k < n; k++)
        if (e[k] >= 0.0 && e[k] <= 360.0 && (m == 0 || e[k] > e[m - 1]))
            e[m++] = e[k];
    *out = e;
    return m;
}

/* Weights of the two ends of a linear function of gamma over [g0, g1]
 * (radians) in the integral against sin gamma: int (g1 - g)/h sin g dg and
 * int (g - g0)/h sin g dg. */
static void tb__sin_weights(double g0, double g1, double *w0, double *w1)
{
    double h = g1 - g0, ds = (sin(g1) - sin(g0)) / h;
    *w0 = cos(g0) - ds;
    *w1 = ds - cos(g1);
}

double tb_ies_flux(const tb_ies *ies)
{
    double *e;
    int ne = tb__full_circle(ies, &e);
    if (ne < 2)
        return NAN;
    double sum = 0.0;
    for (int i = 0; i + 1 < ies->nv; i++) {
        double ga = ies->v_angles[i], gb = ies->v_angles[i + 1];
        double w0, w1;
        tb__sin_weights(tb_radians(ga), tb_radians(gb), &w0, &w1);
        for (int k = 0; k + 1 < ne; k++) {
            double ca = e[k], cb = e[k + 1];
            /* Bilinear over the patch: each corner times its gamma weight times
             * half the patch's width in C (the integral of a linear hat). */
            double half = 0.5 * tb_radians(cb - ca);
            sum += half * (w0 * (tb_ies_candela(ies, ga, ca) + tb_ies_candela(ies, ga, cb)) +
                           w1 * (tb_ies_candela(ies, gb, ca) + tb_ies_candela(ies, gb, cb)));
        }
    }
    free(e);
    return sum;
}

/* ---------------------------------------------------------------- sampling */

/* Breakpoints of [a[0], a[n-1]] with every step of a split into pieces of at most `step`. */
static double *tb__refine(const double *a, int n, double step, int *count)
{
    size_t total = 1;
    for (int k = 0; k + 1 < n; k++)
        total += (size_t)ceil((a[k + 1] - a[k]) / step);
    double *r = malloc(sizeof(double) * total);
    if (!r)
        return NULL;
    int m = 0;
    for (int k = 0; k + 1 < n; k++) {
        int pieces = (int)ceil((a[k + 1] - a[k]) / step);
        if (pieces < 1)
            pieces = 1;
        for (int p = 0; p < pieces; p++)
            r[m++] = a[k] + (a[k + 1] - a[k]) * p / pieces;
    }
    r[m++] = a[n - 1];
    *count = m;
    return r;
}

static tb_status tb__build_sampling(tb_ies *ies, const char *name)
{
    double *e = NULL;
    int ne = tb__full_circle(ies, &e);
    if (ne < 2)
        return tb_error(TB_ERR_NOMEM, "%s: out of memory", name);
    ies->s_gamma = tb__refine(ies->v_angles, ies->nv, TB__IES_STEP_V, &ies->sv);
    ies->s_c = ies->symmetry == TB_IES_SYM_ROTATIONAL ? tb__refine(e, 2, 360.0, &ies->sh)
                                                      : tb__refine(e, ne, TB__IES_STEP_H, &ies->sh);
    free(e);
    if (!ies->s_gamma || !ies->s_c)
        return tb_error(TB_ERR_NOMEM, "%s: out of memory", name);
    int rows = ies->sv - 1, cols = ies->sh - 1;
    size_t cells = (size_t)rows * (size_t)cols;
    if (cells > TB__IES_MAX_CELLS)
        return tb_error(TB_ERR_UNSUPPORTED, "%s: error: the table is too large to sample (%zu grid cells, at most %zu)",
                        name, cells, TB__IES_MAX_CELLS);
    ies->s_mean = malloc(sizeof(double) * cells);
    double *w = malloc(sizeof(double) * cells);
    if (!ies->s_mean || !w) {
        free(w);
        return tb_error(TB_ERR_NOMEM, "%s: out of memory", name);
    }
    for (int r = 0; r < rows; r++) {
        double g0 = ies->s_gamma[r], g1 = ies->s_gamma[r + 1];
        double dcos = cos(tb_radians(g0)) - cos(tb_radians(g1));
        for (int c = 0; c < cols; c++) {
            double c0 = ies->s_c[c], c1 = ies->s_c[c + 1];
            double mean = 0.25 * (tb_ies_candela(ies, g0, c0) + tb_ies_candela(ies, g0, c1) +
                                  tb_ies_candela(ies, g1, c0) + tb_ies_candela(ies, g1, c1)) /
                          ies->max_candela;
            ies->s_mean[(size_t)r * cols + c] = mean;
            w[(size_t)r * cols + c] = mean * dcos * tb_radians(c1 - c0);
        }
    }
    tb_status st = tb_distrib1d_init(&ies->s_cells, w, (int)cells);
    free(w);
    if (st)
        return tb_error_context(st, "%s", name);
    return TB_OK;
}

tb_vec3 tb_ies_sample(const tb_ies *ies, float u1, float u2, double *pdf)
{
    double pmf, ur;
    int cell = tb_distrib1d_sample_discrete(&ies->s_cells, u1, &pmf, &ur);
    int cols = ies->sh - 1;
    int r = cell / cols, c = cell % cols;
    double z0 = cos(tb_radians(ies->s_gamma[r])), z1 = cos(tb_radians(ies->s_gamma[r + 1]));
    /* Uniform in solid angle inside the cell: cos gamma uniform, C uniform. */
    double cg = z0 + ur * (z1 - z0);
    double cc = tb_radians(ies->s_c[c] + u2 * (ies->s_c[c + 1] - ies->s_c[c]));
    double sg = sqrt(fmax(0.0, 1.0 - cg * cg));
    if (pdf)
        *pdf = ies->s_mean[cell] / ies->s_cells.total;
    return tb_vec3_make((float)(sg * cos(cc)), (float)(sg * sin(cc)), (float)-cg);
}

double tb_ies_pdf(const tb_ies *ies, tb_vec3 w)
{
    double v, h;
    tb_ies_angles(w, &v, &h);
    if (!(v >= ies->s_gamma[0] && v <= ies->s_gamma[ies->sv - 1]))
        return 0.0;
    int r = tb__interval(ies->s_gamma, ies->sv, v);
    int c = tb__interval(ies->s_c, ies->sh, h);
    return ies->s_mean[(size_t)r * (ies->sh - 1) + c] / ies->s_cells.total;
}

/* ------------------------------------------------------------------- parse */

void tb_ies_free(tb_ies *ies)
{
    if (!ies)
        return;
    for (int k = 0; k < ies->nkeywords; k++) {
        free(ies->keywords[k].key);
        free(ies->keywords[k].value);
    }
    free(ies->keywords);
    free(ies->v_angles);
    free(ies->h_angles);
    free(ies->candela);
    free(ies->s_gamma);
    free(ies->s_c);
    free(ies->s_mean);
    tb_distrib1d_release(&ies->s_cells);
    free(ies);
}

/* Reads n angles into a (fresh) array, checking that they are finite,
 * strictly increasing and within [lo, hi]. */
static tb_status tb__angles(tb__lex *lx, int n, const char *what, double lo, double hi, double **out)
{
    double *a = malloc(sizeof(double) * (size_t)n);
    if (!a)
        return tb_error(TB_ERR_NOMEM, "%s: out of memory for %d angles", lx->name, n);
    *out = a;
    char label[64];
    for (int k = 0; k < n; k++) {
        long line;
        snprintf(label, sizeof label, "%s angle %d of %d", what, k + 1, n);
        tb_status st = tb__number(lx, label, &a[k], &line);
        if (st)
            return st;
        if (a[k] < lo || a[k] > hi)
            return tb__err(lx, line, TB_ERR_FORMAT, "%s angle %.17g is outside [%g, %g]", what, a[k], lo, hi);
        if (k > 0 && !(a[k] > a[k - 1]))
            return tb__err(lx, line, TB_ERR_FORMAT,
                           "%s angles must increase: %.17g follows %.17g", what, a[k], a[k - 1]);
    }
    return TB_OK;
}

static tb_status tb__parse(tb_ies *ies, tb__lex *lx)
{
    tb_status st = tb__header(ies, lx);
    if (st)
        return st;
    long line;
    double v;
    if ((st = tb__integer(lx, "the number of lamps", 1, 1000000, &ies->lamps)))
        return st;
    if ((st = tb__number(lx, "the lumens per lamp", &ies->lumens_per_lamp, &line)))
        return st;
    if (!(ies->lumens_per_lamp > 0.0 || ies->lumens_per_lamp == -1.0))
        return tb__err(lx, line, TB_ERR_FORMAT, "lumens per lamp must be > 0 or -1 (absolute photometry), found %.17g",
                       ies->lumens_per_lamp);
    if ((st = tb__number(lx, "the candela multiplier", &ies->multiplier, &line)))
        return st;
    if (!(ies->multiplier > 0.0))
        return tb__err(lx, line, TB_ERR_FORMAT, "the candela multiplier must be > 0, found %.17g", ies->multiplier);
    if ((st = tb__integer(lx, "the number of vertical angles", 2, TB__IES_MAX_ANGLES, &ies->nv)))
        return st;
    if ((st = tb__integer(lx, "the number of horizontal angles", 1, TB__IES_MAX_ANGLES, &ies->nh)))
        return st;
    long type_line = lx->line;
    if ((st = tb__integer(lx, "the photometric type", 1, 3, &ies->photometric_type)))
        return st;
    if (ies->photometric_type != 1)
        return tb__err(lx, type_line, TB_ERR_UNSUPPORTED,
                       "photometric type %d (%s) is not supported; only type 1 (C)", ies->photometric_type,
                       ies->photometric_type == 2 ? "B" : "A");
    if ((st = tb__integer(lx, "the units type", 1, 2, &ies->units)))
        return st;
    if ((st = tb__number(lx, "the luminous width", &ies->width, &line)) ||
        (st = tb__number(lx, "the luminous length", &ies->length, &line)) ||
        (st = tb__number(lx, "the luminous height", &ies->height, &line)) ||
        (st = tb__number(lx, "the ballast factor", &ies->ballast_factor, &line)) ||
        (st = tb__number(lx, "the ballast-lamp photometric factor", &ies->ballast_lamp_factor, &line)) ||
        (st = tb__number(lx, "the input watts", &ies->input_watts, &line)))
        return st;

    /* Every value needs a byte and a separator: refuse counts the rest of the
     * file cannot hold before allocating for them. */
    size_t need = (size_t)ies->nv + (size_t)ies->nh + (size_t)ies->nv * (size_t)ies->nh;
    size_t left = lx->len - lx->pos;
    if (need > left / 2 + 1) {
        long eof_line = lx->line;
        for (size_t p = lx->pos; p < lx->len; p++)
            eof_line += lx->s[p] == '\n';
        return tb__err(lx, eof_line, TB_ERR_FORMAT,
                       "file truncated: %d vertical x %d horizontal angles need %zu more numbers, but only %zu bytes remain",
                       ies->nv, ies->nh, need, left);
    }
    if ((st = tb__angles(lx, ies->nv, "vertical", 0.0, 180.0, &ies->v_angles)))
        return st;
    tb__skip(lx);
    long h_line = lx->line; /* where the horizontal angles start */
    if ((st = tb__angles(lx, ies->nh, "horizontal", 0.0, 360.0, &ies->h_angles)))
        return st;
    double h0 = ies->h_angles[0], h1 = ies->h_angles[ies->nh - 1];
    if (ies->nh == 1)
        ies->symmetry = TB_IES_SYM_ROTATIONAL;
    else if (h0 == 0.0 && h1 == 90.0)
        ies->symmetry = TB_IES_SYM_QUADRANT;
    else if (h0 == 0.0 && h1 == 180.0)
        ies->symmetry = TB_IES_SYM_BILATERAL;
    else if (h0 == 90.0 && h1 == 270.0)
        ies->symmetry = TB_IES_SYM_BILATERAL_90;
    else if (h0 == 0.0 && h1 == 360.0)
        ies->symmetry = TB_IES_SYM_FULL;
    else
        return tb__err(lx, h_line, TB_ERR_FORMAT,
                       "horizontal angles must run 0..90, 0..180, 0..360 or 90..270 (or be the single angle 0), found %g..%g",
                       h0, h1);

    size_t nc = (size_t)ies->nv * (size_t)ies->nh;
    ies->candela = malloc(sizeof(double) * nc);
    if (!ies->candela)
        return tb_error(TB_ERR_NOMEM, "%s: out of memory for %zu candela values", lx->name, nc);
    char label[96];
    long last_line = lx->line;
    for (int j = 0; j < ies->nh; j++)
        for (int i = 0; i < ies->nv; i++) {
            snprintf(label, sizeof label, "candela value %d of %zu (horizontal angle %g, vertical angle %g)",
                     j * ies->nv + i + 1, nc, ies->h_angles[j], ies->v_angles[i]);
            if ((st = tb__number(lx, label, &v, &line)))
                return st;
            if (v < 0.0)
                return tb__err(lx, line, TB_ERR_FORMAT, "negative candela value %.17g (horizontal %g, vertical %g)",
                               v, ies->h_angles[j], ies->v_angles[i]);
            double c = v * ies->multiplier;
            /* Far beyond any luminaire (~1e6 cd), and low enough that sums
             * over the table (flux, sampling weights) stay finite. */
            if (!(c <= TB__IES_MAX_CANDELA))
                return tb__err(lx, line, TB_ERR_FORMAT, "candela value %.17g times the multiplier exceeds %g", v,
                               TB__IES_MAX_CANDELA);
            ies->candela[(size_t)j * ies->nv + i] = c;
            last_line = line;
            if (c > ies->max_candela)
                ies->max_candela = c;
        }
    /* Only white space (and a DOS end-of-file mark) may follow. */
    while (tb__skip(lx)) {
        if (lx->s[lx->pos] == '\x1a' && lx->pos + 1 == lx->len)
            break;
        const char *b = lx->s + lx->pos, *e = b;
        while (e < lx->s + lx->len && !tb__is_sep(*e))
            e++;
        char shown[40];
        tb__show(b, e, shown, sizeof shown);
        return tb__err(lx, lx->line, TB_ERR_FORMAT, "unexpected '%s' after the %zu candela values", shown, nc);
    }
    if (!(ies->max_candela > 0.0))
        return tb__err(lx, last_line, TB_ERR_FORMAT, "every candela value is 0");
    return tb__build_sampling(ies, lx->name);
}

tb_status tb_ies_parse(const char *text, size_t len, const char *name, tb_ies **out)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "tb_ies_parse: no output given");
    *out = NULL;
    if (!text && len > 0)
        return tb_error(TB_ERR_ARG, "tb_ies_parse: no text given");
    tb__lex lx = {text ? text : "", len, 0, 1, name ? name : "<ies>"};
    tb_ies *ies = calloc(1, sizeof *ies);
    if (!ies)
        return tb_error(TB_ERR_NOMEM, "%s: out of memory", lx.name);
    tb_status st = tb__parse(ies, &lx);
    if (st) {
        tb_ies_free(ies);
        return st;
    }
    *out = ies;
    return TB_OK;
}

tb_status tb_ies_read(const char *path, tb_ies **out)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "tb_ies_read: no output given");
    *out = NULL;
    FILE *f = fopen(path, "rb");
    if (!f)
        return tb_error(TB_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    char *buf = NULL;
    size_t len = 0, cap = 0;
    for (;;) {
        if (len == cap) {
            if (cap >= (size_t)TB__IES_MAX_FILE) {
                free(buf);
                fclose(f);
                return tb_error(TB_ERR_FORMAT, "%s: larger than %ld bytes: not an IES file", path,
                                TB__IES_MAX_FILE);
            }
            cap = cap ? 2 * cap : 65536;
            char *nb = realloc(buf, cap);
            if (!nb) {
                free(buf);
                fclose(f);
                return tb_error(TB_ERR_NOMEM, "%s: out of memory", path);
            }
            buf = nb;
        }
        size_t got = fread(buf + len, 1, cap - len, f);
        len += got;
        if (got == 0)
            break;
    }
    bool bad = ferror(f);
    fclose(f);
    if (bad) {
        free(buf);
        return tb_error(TB_ERR_IO, "%s: read error", path);
    }
    tb_status st = tb_ies_parse(buf, len, path, out);
    free(buf);
    return st;
}
