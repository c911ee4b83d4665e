/* Importer: correctly rounded coordinates for text formats (docs/import.md,
 * "Coordinates").
 *
 * Assimp 5.2 reads the numbers of OBJ, ASCII PLY and ASCII STL files with
 * fast_atoreal_move, which is not correctly rounded: a coordinate can come
 * out one ulp from the float nearest to the decimal in the file. Here the
 * file's vertex coordinates are read again with strtof (correctly rounded)
 * into a sorted set C, and each coordinate a Assimp gives is settled:
 *   - a in C: kept (it is some number of the file, correctly rounded);
 *   - a not in C: a was misrounded, so its true value is a neighbour of a;
 *     if exactly one neighbour is in C it is taken, otherwise a is kept and
 *     counted as undecided.
 * A replacement is always one ulp and always onto a number of the file. */
#include "host/mid/import_internal.h"

#include <locale.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static tb_status tb__add(tb__import_reround *r, size_t *cap, float v)
{
    if (!isfinite(v))
        return TB_OK;
    if (r->n == *cap) {
        size_t nc = *cap ? 2 * *cap : 4096;
        float *g = realloc(r->vals, nc * sizeof *g);
        if (!g)
            return tb_error(TB_ERR_NOMEM, "out of memory reading coordinates");
        r->vals = g;
        *cap = nc;
    }
    r->vals[r->n++] = v;
    return TB_OK;
}

/* Adds up to `count` numbers from s (or the numbers in the columns
 * cols[0..2] when cols is not NULL). */
static tb_status tb__numbers(tb__import_reround *r, size_t *cap, const char *s, int count, const int *cols)
{
    for (int col = 0, taken = 0; taken < count; col++) {
        char *end;
        float v = strtof(s, &end);
        if (end == s)
            return TB_OK;
        s = end;
        if (!cols || col == cols[0] || col == cols[1] || col == cols[2]) {
            tb_status st = tb__add(r, cap, v);
            if (st)
                return st;
            taken++;
        }
    }
    return TB_OK;
}

static int tb__float_cmp(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return x < y ? -1 : x > y;
}

/* True if `line` starts (after blanks) with the word `w`; *rest after it. */
static bool tb__word(const char *line, const char *w, const char **rest)
{
    while (*line == ' ' || *line == '\t')
        line++;
    size_t n = strlen(w);
    if (strncmp(line, w, n) != 0 || (line[n] != ' ' && line[n] != '\t'))
        return false;
    *rest = line + n;
    return true;
}

static tb_status tb__scan(FILE *f, tb__import_text_kind kind, tb__import_reround *r)
{
    size_t cap = 0;
    char *line = NULL;
    size_t linecap = 0;
    tb_status st = TB_OK;
    /* PLY: the vertex element's count and the columns of x, y, z. */
    long ply_vertices = -1, ply_left = 0;
    int cols[3] = {-1, -1, -1}, nprops = 0;
    bool in_vertex = false, header = kind == TB__TEXT_PLY, list_prop = false;
    while (!st && getline(&line, &linecap, f) > 0) {
        const char *rest;
        switch (kind) {
        case TB__TEXT_OBJ:
            if (tb__word(line, "v", &rest))
                st = tb__numbers(r, &cap, rest, 3, NULL);
            break;
        case TB__TEXT_STL:
            if (tb__word(line, "vertex", &rest))
                st = tb__numbers(r, &cap, rest, 3, NULL);
            break;
        case TB__TEXT_PLY:
            if (header) {
                if (tb__word(line, "element", &rest)) {
                    in_vertex = false;
                    const char *p = rest;
                    while (*p == ' ' || *p == '\t')
                        p++;
                    if (ply_vertices < 0 && tb__word(p, "vertex", &rest)) {
                        in_vertex = true;
                        ply_vertices = strtol(rest, NULL, 10);
                    } else if (ply_vertices < 0)
                        goto done; /* vertices not first: their lines are hard to find */
                } else if (in_vertex && tb__word(line, "property", &rest)) {
                    char type[32], name[64];
                    if (sscanf(rest, "%31s %63s", type, name) == 2) {
                        if (!strcmp(type, "list"))
                            list_prop = true;
                        for (int k = 0; k < 3; k++)
                            if (!strcmp(name, (const char *[]){"x", "y", "z"}[k]))
                                cols[k] = nprops;
                    }
                    nprops++;
                } else if (!strncmp(line, "end_header", 10)) {
                    header = false;
                    ply_left = ply_vertices;
                    if (ply_vertices <= 0 || list_prop || cols[0] < 0 || cols[1] < 0 || cols[2] < 0)
                        goto done;
                }
            } else if (ply_left-- > 0)
                st = tb__numbers(r, &cap, line, 3, cols);
            else
                goto done;
            break;
        }
    }
done:
    free(line);
    return st;
}

tb_status tb__import_reround_load(const char *path, tb__import_text_kind kind, tb__import_reround *r)
{
    memset(r, 0, sizeof *r);
    FILE *f = fopen(path, "rb");
    if (!f)
        return TB_OK; /* Assimp read it a moment ago; without the text nothing is settled */
    /* strtof in the "C" locale: '.' is the decimal point whatever the program set. */
    locale_t c = newlocale(LC_ALL_MASK, "C", (locale_t)0), old = c ? uselocale(c) : (locale_t)0;
    tb_status st = tb__scan(f, kind, r);
    if (c) {
        uselocale(old);
        freelocale(c);
    }
    fclose(f);
    if (st) {
        tb__import_reround_free(r);
        return st;
    }
    if (r->n) {
        qsort(r->vals, r->n, sizeof *r->vals, tb__float_cmp);
        size_t k = 1; /* distinct values; +0 and -0 compare equal and are both kept */
        for (size_t i = 1; i < r->n; i++)
            if (memcmp(&r->vals[i], &r->vals[k - 1], sizeof(float)) != 0)
                r->vals[k++] = r->vals[i];
        r->n = k;
    }
    r->active = r->n > 0;
    return TB_OK;
}

/* True if v (bit for bit) is in the sorted set. */
static bool tb__has(const tb__import_reround *r, float v)
{
    size_t lo = 0, hi = r->n;
    while (lo < hi) { /* first element >= v */
        size_t mid = lo + (hi - lo) / 2;
        if (r->vals[mid] < v)
            lo = mid + 1;
        else
            hi = mid;
    }
    for (size_t i = lo; i < r->n && r->vals[i] == v; i++)
        if (memcmp(&r->vals[i], &v, sizeof v) == 0)
            return true;
    return false;
}

float tb__import_reround_value(tb__import_reround *r, float a)
{
    if (!r || !r->active || !isfinite(a) || tb__has(r, a))
        return a;
    float lo = nextafterf(a, -INFINITY), hi = nextafterf(a, INFINITY);
    bool in_lo = tb__has(r, lo), in_hi = tb__has(r, hi);
    if (in_lo != in_hi) {
        r->changed++;
        return in_lo ? lo : hi;
    }
    r->undecided++;
    return a;
}

void tb__import_reround_free(tb__import_reround *r)
{
    free(r->vals);
    memset(r, 0, sizeof *r);
}
