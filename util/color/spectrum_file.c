#include "util/color/spectrum_file.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>

#include "util/container/array.h"

/* Longest line accepted; a spectrum line is two numbers. */
#define TB__SPD_LINE_MAX 4096
/* More samples than any measured spectrum has; keeps hostile files bounded. */
#define TB__SPD_MAX_SAMPLES 1000000

static tb_status tb__spd_error(const char *name, int line, int col, const char *msg)
{
    return tb_error(TB_ERR_FORMAT, "%s:%d:%d: error: %s", name, line, col, msg);
}

/* Parses one number at *p (C locale rules, as strtod in the "C" locale would,
 * but without depending on the process locale: only [+-]digits[.digits][e..]). */
static int tb__spd_number(const char **p, double *out)
{
    const char *s = *p, *start = s;
    if (*s == '+' || *s == '-')
        s++;
    int digits = 0;
    while (isdigit((unsigned char)*s)) { s++; digits++; }
    if (*s == '.') {
        s++;
        while (isdigit((unsigned char)*s)) { s++; digits++; }
    }
    if (!digits)
        return 0;
    if (*s == 'e' || *s == 'E') {
        const char *e = s + 1;
        if (*e == '+' || *e == '-')
            e++;
        if (!isdigit((unsigned char)*e))
            return 0;
        while (isdigit((unsigned char)*e))
            e++;
        s = e;
    }
    char buf[128];
    size_t n = (size_t)(s - start);
    if (n >= sizeof buf)
        return 0;
    memcpy(buf, start, n);
    buf[n] = '\0';
    /* Our own digits only reach strtod, and '.' is the only radix we pass;
     * a comma-decimal locale would misread it, so swap in the locale's radix. */
    char *dot = strchr(buf, '.');
    if (dot) {
        char probe[8];
        snprintf(probe, sizeof probe, "%.1f", 0.5);
        *dot = probe[1];
    }
    errno = 0;
    *out = strtod(buf, NULL);
    if (errno == ERANGE && isinf(*out))
        return -1;
    *p = s;
    return 1;
}

static const char *tb__spd_skip_ws(const char *s)
{
    while (*s == ' ' || *s == '\t' || *s == '\r')
        s++;
    return s;
}

tb_status tb_spectrum_read_stream(FILE *f, const char *name, tb_spectrum *out)
{
    memset(out, 0, sizeof *out);
    tb_array lam, val;
    tb_array_init(&lam, sizeof(double));
    tb_array_init(&val, sizeof(double));
    char *line = NULL;
    size_t linecap = 0;
    ssize_t got;
    int lineno = 0;
    int seen_header = 0;
    tb_status st = TB_OK;
    while ((got = getline(&line, &linecap, f)) >= 0) {
        lineno++;
        if (got > TB__SPD_LINE_MAX) {
            st = tb__spd_error(name, lineno, TB__SPD_LINE_MAX, "line too long");
            goto done;
        }
        const char *nul = memchr(line, '\0', (size_t)got);
        if (nul) {
            st = tb__spd_error(name, lineno, (int)(nul - line) + 1, "NUL byte in text");
            goto done;
        }
        const char *p = tb__spd_skip_ws(line);
        if (*p == '#' || *p == '\n' || *p == '\0')
            continue;
        if (isalpha((unsigned char)*p)) {
            if (lam.len == 0 && !seen_header) {
                /* One header of column names, e.g. "lambda_nm,value": only before data. */
                seen_header = 1;
                continue;
            }
            st = tb__spd_error(name, lineno, (int)(p - line) + 1,
                               "expected a wavelength in nm (column names are allowed only before the first sample)");
            goto done;
        }
        double l, v;
        int r = tb__spd_number(&p, &l);
        if (r <= 0) {
            st = tb__spd_error(name, lineno, (int)(p - line) + 1,
                               r < 0 ? "wavelength out of range" : "expected a wavelength in nm");
            goto done;
        }
        p = tb__spd_skip_ws(p);
        if (*p == ',')
            p = tb__spd_skip_ws(p + 1);
        r = tb__spd_number(&p, &v);
        if (r <= 0) {
            st = tb__spd_error(name, lineno, (int)(p - line) + 1,
                               r < 0 ? "value out of range" : "expected a value after the wavelength");
            goto done;
        }
        p = tb__spd_skip_ws(p);
        if (*p == '#')
            p += strlen(p);
        if (*p != '\n' && *p != '\0') {
            st = tb__spd_error(name, lineno, (int)(p - line) + 1,
                               "unexpected text after the value (one sample per line: wavelength value)");
            goto done;
        }
        if (!(l > 0.0)) {
            st = tb__spd_error(name, lineno, 1, "wavelength must be > 0 nm");
            goto done;
        }
        if (lam.len > 0 && !(l > ((double *)lam.data)[lam.len - 1])) {
            st = tb__spd_error(name, lineno, 1, "wavelengths must be strictly increasing");
            goto done;
        }
        if (lam.len >= TB__SPD_MAX_SAMPLES) {
            st = tb__spd_error(name, lineno, 1, "too many samples");
            goto done;
        }
        if ((st = tb_array_push(&lam, &l)) || (st = tb_array_push(&val, &v)))
            goto done;
    }
    if (ferror(f)) {
        st = tb_error(TB_ERR_IO, "%s: read error", name);
        goto done;
    }
    if (lam.len < 2) {
        st = tb__spd_error(name, lineno + 1, 1, "a spectrum needs at least 2 samples");
        goto done;
    }
    st = tb_spectrum_init(out, (int)lam.len, lam.data, val.data);
    if (st)
        st = tb_error_context(st, "%s", name);
done:
    free(line);
    tb_array_free(&lam);
    tb_array_free(&val);
    return st;
}

tb_status tb_spectrum_read_file(const char *path, tb_spectrum *out)
{
    memset(out, 0, sizeof *out);
    FILE *f = fopen(path, "rb");
    if (!f)
        return tb_error(TB_ERR_IO, "%s: cannot open spectrum file: %s", path, strerror(errno));
    tb_status st = tb_spectrum_read_stream(f, path, out);
    fclose(f);
    return st;
}
