/* The text form of FED (docs/fed.md, "Text form"): a line-oriented format,
 * read through a fixed buffer with every error located as
 * "name:line:col: error: message", like MID. */
#include "util/mesh/fed.h"

#include <errno.h>
#include <stdarg.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "util/container/array.h"
#include "util/mesh/fed_internal.h"

/* Longest token (numbers and keywords are short; this bounds the buffer). */
#define TB__TOKEN_MAX 128
#define TB__BUF_SIZE 65536

typedef enum tb__tok_kind {
    TB__TOK_WORD,    /* [A-Za-z_][A-Za-z0-9_]* */
    TB__TOK_NUMBER,  /* starts with a digit, sign or '.' */
    TB__TOK_NEWLINE, /* end of a line (comments end there too) */
    TB__TOK_EOF,
} tb__tok_kind;

typedef struct tb__lexer {
    FILE *f;
    const char *name;
    unsigned char buf[TB__BUF_SIZE];
    size_t pos, len;
    bool eof;
    long line, col;       /* position of the next byte */
    /* the current token */
    tb__tok_kind kind;
    char text[TB__TOKEN_MAX + 1];
    long tline, tcol;
    tb_status io;         /* a read error, reported when it is met */
} tb__lexer;

static int tb__peek(tb__lexer *lx)
{
    if (lx->pos == lx->len) {
        if (lx->eof)
            return EOF;
        lx->len = fread(lx->buf, 1, sizeof lx->buf, lx->f);
        lx->pos = 0;
        if (lx->len == 0) {
            lx->eof = true;
            if (ferror(lx->f) && !lx->io)
                lx->io = tb_error(TB_ERR_IO, "%s: read error: %s", lx->name, strerror(errno));
            return EOF;
        }
    }
    return lx->buf[lx->pos];
}

static void tb__advance(tb__lexer *lx)
{
    if (lx->buf[lx->pos++] == '\n') {
        lx->line++;
        lx->col = 1;
    } else {
        lx->col++;
    }
}

static tb_status tb__error_at(const tb__lexer *lx, long line, long col, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

static tb_status tb__error_at(const tb__lexer *lx, long line, long col, const char *fmt, ...)
{
    if (lx->io)
        return lx->io;
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return tb_error(TB_ERR_FORMAT, "%s:%ld:%ld: error: %s", lx->name, line, col, msg);
}

/* "'word'", "end of line" or "end of file": what the current token is, for messages. */
static const char *tb__describe(const tb__lexer *lx, char *buf, size_t n)
{
    switch (lx->kind) {
    case TB__TOK_NEWLINE:
        return "end of line";
    case TB__TOK_EOF:
        return "end of file";
    default:
        snprintf(buf, n, "'%s'", lx->text);
        return buf;
    }
}

static bool tb__is_word_start(int c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_'; }
static bool tb__is_digit(int c) { return c >= '0' && c <= '9'; }

/* Reads the next token. */
static tb_status tb__next(tb__lexer *lx)
{
    for (;;) {
        int c = tb__peek(lx);
        if (c == ' ' || c == '\t' || c == '\r') {
            tb__advance(lx);
        } else if (c == '#') {
            /* a comment: any bytes up to the end of the line */
            while ((c = tb__peek(lx)) != EOF && c != '\n')
                tb__advance(lx);
        } else {
            break;
        }
    }
    lx->tline = lx->line;
    lx->tcol = lx->col;
    lx->text[0] = 0;
    int c = tb__peek(lx);
    if (lx->io)
        return lx->io;
    if (c == EOF) {
        lx->kind = TB__TOK_EOF;
        return TB_OK;
    }
    if (c == '\n') {
        tb__advance(lx);
        lx->kind = TB__TOK_NEWLINE;
        return TB_OK;
    }
    bool word = tb__is_word_start(c);
    if (!word && !tb__is_digit(c) && c != '+' && c != '-' && c != '.') {
        if (c >= 0x20 && c < 0x7f)
            return tb__error_at(lx, lx->tline, lx->tcol, "unexpected character '%c'", c);
        return tb__error_at(lx, lx->tline, lx->tcol, "unexpected byte 0x%02x (outside comments only ASCII is allowed)",
                            c);
    }
    size_t n = 0;
    while ((c = tb__peek(lx)) != EOF && c != ' ' && c != '\t' && c != '\r' && c != '\n' && c != '#') {
        if (n == TB__TOKEN_MAX)
            return tb__error_at(lx, lx->tline, lx->tcol, "token too long (more than %d bytes)", TB__TOKEN_MAX);
        lx->text[n++] = (char)c;
        tb__advance(lx);
    }
    lx->text[n] = 0;
    if (lx->io)
        return lx->io;
    lx->kind = word ? TB__TOK_WORD : TB__TOK_NUMBER;
    if (word) {
        for (size_t k = 1; k < n; k++)
            if (!tb__is_word_start((unsigned char)lx->text[k]) && !tb__is_digit((unsigned char)lx->text[k]))
                return tb__error_at(lx, lx->tline, lx->tcol, "malformed word '%s'", lx->text);
    }
    return TB_OK;
}

/* Does `s` match [+-]? ( D+ ( "." D* )? | "." D+ ) ( [eE] [+-]? D+ )? (the MID number syntax)? */
static bool tb__number_syntax(const char *s)
{
    const char *p = s;
    if (*p == '+' || *p == '-')
        p++;
    size_t int_digits = 0, frac_digits = 0;
    while (tb__is_digit((unsigned char)*p))
        p++, int_digits++;
    if (*p == '.') {
        p++;
        while (tb__is_digit((unsigned char)*p))
            p++, frac_digits++;
    }
    if (int_digits + frac_digits == 0)
        return false;
    if (*p == 'e' || *p == 'E') {
        p++;
        if (*p == '+' || *p == '-')
            p++;
        if (!tb__is_digit((unsigned char)*p))
            return false;
        while (tb__is_digit((unsigned char)*p))
            p++;
    }
    return *p == 0;
}

/* The current token as a float (nearest, ties to even). */
static tb_status tb__float(tb__lexer *lx, float *out, const char *what)
{
    char buf[TB__TOKEN_MAX + 8];
    if (lx->kind != TB__TOK_NUMBER)
        return tb__error_at(lx, lx->tline, lx->tcol, "expected %s, found %s", what, tb__describe(lx, buf, sizeof buf));
    if (!tb__number_syntax(lx->text))
        return tb__error_at(lx, lx->tline, lx->tcol, "malformed number '%s'", lx->text);
    errno = 0;
    float v = strtof(lx->text, NULL);
    if (isinf(v))
        return tb__error_at(lx, lx->tline, lx->tcol, "number %s out of range for a float (largest %g)", lx->text,
                            (double)FLT_MAX);
    *out = v;
    return TB_OK;
}

/* The current token as an integer in [lo, hi]. */
static tb_status tb__integer(tb__lexer *lx, long long lo, long long hi, long long *out, const char *what)
{
    char buf[TB__TOKEN_MAX + 8];
    *out = 0; /* defined on error paths too (gcc -O3 cannot see they never return TB_OK) */
    if (lx->kind != TB__TOK_NUMBER)
        return tb__error_at(lx, lx->tline, lx->tcol, "expected %s, found %s", what, tb__describe(lx, buf, sizeof buf));
    const char *p = lx->text;
    bool neg = false;
    if (*p == '+' || *p == '-')
        neg = *p++ == '-';
    if (!*p)
        return tb__error_at(lx, lx->tline, lx->tcol, "expected %s, found '%s'", what, lx->text);
    unsigned long long v = 0;
    for (; *p; p++) {
        if (!tb__is_digit((unsigned char)*p))
            return tb__error_at(lx, lx->tline, lx->tcol, "expected %s (an integer), found '%s'", what, lx->text);
        if (v <= (1ull << 40))
            v = v * 10 + (unsigned)(*p - '0');
    }
    long long s = neg ? -(long long)v : (long long)v;
    if (s < lo || s > hi)
        return tb__error_at(lx, lx->tline, lx->tcol, "%s %s out of range (%lld to %lld)", what, lx->text, lo, hi);
    *out = s;
    return TB_OK;
}

/* Expects the end of the current line (or of the file). */
static tb_status tb__end_of_line(tb__lexer *lx, const char *after)
{
    char buf[TB__TOKEN_MAX + 8];
    if (lx->kind == TB__TOK_NEWLINE || lx->kind == TB__TOK_EOF)
        return TB_OK;
    return tb__error_at(lx, lx->tline, lx->tcol, "expected end of line after %s, found %s", after,
                        tb__describe(lx, buf, sizeof buf));
}

/* Skips blank and comment-only lines; leaves the first token of the next record current. */
static tb_status tb__skip_blank(tb__lexer *lx)
{
    tb_status st;
    while (lx->kind == TB__TOK_NEWLINE)
        if ((st = tb__next(lx)))
            return st;
    return TB_OK;
}

/* Reads "NAME COUNT" section headers' count; the current token is the count. */
static tb_status tb__count(tb__lexer *lx, const char *section, uint32_t *out)
{
    long long v;
    char what[64];
    snprintf(what, sizeof what, "a count of %s", section);
    tb_status st = tb__integer(lx, 0, TB_FED_MAX_COUNT, &v, what);
    if (st)
        return st;
    *out = (uint32_t)v;
    if ((st = tb__next(lx)))
        return st;
    snprintf(what, sizeof what, "'%s %u'", section, *out);
    if ((st = tb__end_of_line(lx, what)))
        return st;
    return tb__next(lx);
}

/* Reads `count` records of `dim` floats (vertices, normals or uvs) into arr. */
static tb_status tb__float_records(tb__lexer *lx, const char *section, uint32_t count, int dim, tb_array *arr)
{
    tb_status st = tb_array_reserve(arr, count < (1u << 16) ? count : (1u << 16)); /* grows with the input */
    char buf[TB__TOKEN_MAX + 8], what[96];
    for (uint32_t i = 0; i < count && !st; i++) {
        if ((st = tb__skip_blank(lx)))
            return st;
        float v[3];
        for (int k = 0; k < dim; k++) {
            if (lx->kind != TB__TOK_NUMBER) {
                if (k == 0)
                    return tb__error_at(lx, lx->tline, lx->tcol, "expected %s %u of %u (%d numbers), found %s",
                                        section, i, count, dim, tb__describe(lx, buf, sizeof buf));
                return tb__error_at(lx, lx->tline, lx->tcol, "%s %u: expected %d numbers, found %d", section, i,
                                    dim, k);
            }
            snprintf(what, sizeof what, "a number");
            if ((st = tb__float(lx, &v[k], what)) || (st = tb__next(lx)))
                return st;
        }
        snprintf(what, sizeof what, "%s %u (%d numbers per line)", section, i, dim);
        if ((st = tb__end_of_line(lx, what)))
            return st;
        st = tb_array_push(arr, v);
        if (!st)
            st = tb__next(lx);
    }
    return st;
}

/* Where a loop starts in the text, for messages found after parsing. */
typedef struct tb__loc {
    long line, col;
} tb__loc;

typedef struct tb__text_state {
    tb_array positions, normals, uvs; /* tb_vec3, tb_vec3, tb_vec2 */
    tb_array face_loops, loop_corners, corners, ids, materials, loop_loc;
    bool has_normals, has_uvs; /* the sections were present (even with 0 vertices) */
} tb__text_state;

static void tb__state_free(tb__text_state *s)
{
    tb_array_free(&s->positions);
    tb_array_free(&s->normals);
    tb_array_free(&s->uvs);
    tb_array_free(&s->face_loops);
    tb_array_free(&s->loop_corners);
    tb_array_free(&s->corners);
    tb_array_free(&s->ids);
    tb_array_free(&s->materials);
    tb_array_free(&s->loop_loc);
}

/* Reads one face line: loop, { "hole" loop }, [ "id" n ], [ "material" n ]. */
static tb_status tb__face(tb__lexer *lx, tb__text_state *s, uint32_t f, uint32_t nverts, bool *has_id,
                          bool *has_mat, int32_t *id, int32_t *mat)
{
    char buf[TB__TOKEN_MAX + 8];
    tb_status st;
    *has_id = *has_mat = false;
    uint32_t loops = 0;
    bool want_loop = true; /* at the start, or after "hole" */
    long hole_line = lx->tline, hole_col = lx->tcol;
    for (;;) {
        if (want_loop) {
            tb__loc loc = {lx->tline, lx->tcol};
            uint32_t n = 0;
            while (lx->kind == TB__TOK_NUMBER) {
                long long v;
                if ((st = tb__integer(lx, 0, TB_FED_MAX_COUNT, &v, "vertex index")))
                    return st;
                if ((uint64_t)v >= nverts)
                    return tb__error_at(lx, lx->tline, lx->tcol, "vertex index %lld out of range (%u vertices)", v,
                                        nverts);
                uint32_t idx = (uint32_t)v;
                if ((st = tb_array_push(&s->corners, &idx)) || (st = tb__next(lx)))
                    return st;
                n++;
            }
            if (n < 3) {
                if (n == 0 && loops == 0)
                    return tb__error_at(lx, lx->tline, lx->tcol, "face %u: expected vertex indices, found %s", f,
                                        tb__describe(lx, buf, sizeof buf));
                if (loops == 0)
                    return tb__error_at(lx, loc.line, loc.col, "face %u: a loop needs at least 3 vertices, found %u",
                                        f, n);
                return tb__error_at(lx, hole_line, hole_col, "face %u: a hole needs at least 3 vertices, found %u",
                                    f, n);
            }
            if (s->corners.len > TB_FED_MAX_COUNT)
                return tb__error_at(lx, loc.line, loc.col, "too many corners (at most %u)", TB_FED_MAX_COUNT);
            uint32_t end = (uint32_t)s->corners.len;
            if ((st = tb_array_push(&s->loop_corners, &end)) || (st = tb_array_push(&s->loop_loc, &loc)))
                return st;
            loops++;
            want_loop = false;
            continue;
        }
        if (lx->kind == TB__TOK_NEWLINE || lx->kind == TB__TOK_EOF)
            break;
        if (lx->kind == TB__TOK_WORD && strcmp(lx->text, "hole") == 0) {
            if (*has_id || *has_mat)
                return tb__error_at(lx, lx->tline, lx->tcol, "face %u: 'hole' after 'id' or 'material' (holes come first)", f);
            hole_line = lx->tline, hole_col = lx->tcol;
            if ((st = tb__next(lx)))
                return st;
            want_loop = true;
            continue;
        }
        bool is_id = lx->kind == TB__TOK_WORD && strcmp(lx->text, "id") == 0;
        bool is_mat = lx->kind == TB__TOK_WORD && strcmp(lx->text, "material") == 0;
        if (!is_id && !is_mat)
            return tb__error_at(lx, lx->tline, lx->tcol, "face %u: expected 'hole', 'id', 'material' or end of line, found %s",
                                f, tb__describe(lx, buf, sizeof buf));
        if ((is_id && *has_id) || (is_mat && *has_mat))
            return tb__error_at(lx, lx->tline, lx->tcol, "face %u: '%s' given twice", f, lx->text);
        const char *what = is_id ? "face id" : "material index";
        long long v;
        if ((st = tb__next(lx)) || (st = tb__integer(lx, INT32_MIN, INT32_MAX, &v, what)) || (st = tb__next(lx)))
            return st;
        if (is_id) {
            *has_id = true;
            *id = (int32_t)v;
        } else {
            *has_mat = true;
            *mat = (int32_t)v;
        }
    }
    if (s->loop_corners.len - 1 > TB_FED_MAX_COUNT)
        return tb__error_at(lx, lx->tline, lx->tcol, "too many loops (at most %u)", TB_FED_MAX_COUNT);
    uint32_t end = (uint32_t)(s->loop_corners.len - 1);
    return tb_array_push(&s->face_loops, &end);
}

/* Hands an array's storage over (it was allocated with malloc/realloc). */
static void *tb__take(tb_array *a)
{
    void *p = a->data;
    if (!p)
        p = malloc(1);
    a->data = NULL;
    a->len = a->cap = 0;
    return p;
}

static tb_status tb__parse(tb__lexer *lx, tb__text_state *s, tb_fed **out)
{
    char buf[TB__TOKEN_MAX + 8];
    tb_status st;
    /* Header: "fed 1" (or 1.0) on the first line. */
    if ((st = tb__next(lx)))
        return st;
    if (lx->kind != TB__TOK_WORD || strcmp(lx->text, "fed") != 0 || lx->tline != 1 || lx->tcol != 1)
        return tb__error_at(lx, lx->tline, lx->tcol, "expected the header 'fed 1' at the start of the file, found %s",
                            tb__describe(lx, buf, sizeof buf));
    if ((st = tb__next(lx)))
        return st;
    if (lx->kind != TB__TOK_NUMBER)
        return tb__error_at(lx, lx->tline, lx->tcol, "expected a version number after 'fed', found %s",
                            tb__describe(lx, buf, sizeof buf));
    if (strcmp(lx->text, "1") != 0 && strcmp(lx->text, "1.0") != 0)
        return tb__error_at(lx, lx->tline, lx->tcol, "unsupported FED version %s (this reader reads FED 1)", lx->text);
    if ((st = tb__next(lx)) || (st = tb__end_of_line(lx, "the header")) || (st = tb__next(lx)))
        return st;

    /* vertices N */
    if ((st = tb__skip_blank(lx)))
        return st;
    if (lx->kind != TB__TOK_WORD || strcmp(lx->text, "vertices") != 0)
        return tb__error_at(lx, lx->tline, lx->tcol, "expected 'vertices COUNT', found %s", tb__describe(lx, buf, sizeof buf));
    uint32_t nverts, nfaces = 0;
    if ((st = tb__next(lx)) || (st = tb__count(lx, "vertices", &nverts)) ||
        (st = tb__float_records(lx, "vertex", nverts, 3, &s->positions)))
        return st;
    /* optional sections, then faces */
    int stage = 0; /* 0: after vertices, 1: after normals, 2: after uvs */
    for (;;) {
        if ((st = tb__skip_blank(lx)))
            return st;
        if (lx->kind != TB__TOK_WORD)
            return tb__error_at(lx, lx->tline, lx->tcol, "expected 'normals', 'uvs' or 'faces', found %s",
                                tb__describe(lx, buf, sizeof buf));
        long sl = lx->tline, sc = lx->tcol;
        bool normals = strcmp(lx->text, "normals") == 0, uvs = strcmp(lx->text, "uvs") == 0;
        bool faces = strcmp(lx->text, "faces") == 0;
        if (!normals && !uvs && !faces)
            return tb__error_at(lx, sl, sc, "unknown section '%s' (expected 'normals', 'uvs' or 'faces')", lx->text);
        if ((normals && stage >= 1) || (uvs && stage >= 2))
            return tb__error_at(lx, sl, sc, "section '%s' out of order or repeated (order: vertices, normals, uvs, faces)",
                                lx->text);
        const char *name = normals ? "normals" : (uvs ? "uvs" : "faces");
        uint32_t n;
        if ((st = tb__next(lx)) || (st = tb__count(lx, name, &n)))
            return st;
        if (faces) {
            nfaces = n;
            break;
        }
        if (n != nverts)
            return tb__error_at(lx, sl, sc, "'%s %u' does not match the %u vertices", name, n, nverts);
        if ((st = tb__float_records(lx, normals ? "normal" : "uv", n, normals ? 3 : 2,
                                    normals ? &s->normals : &s->uvs)))
            return st;
        stage = normals ? 1 : 2;
        if (normals)
            s->has_normals = true;
        else
            s->has_uvs = true;
    }

    /* faces */
    uint32_t zero = 0;
    if ((st = tb_array_push(&s->face_loops, &zero)) || (st = tb_array_push(&s->loop_corners, &zero)))
        return st;
    bool any_id = false, any_mat = false;
    for (uint32_t f = 0; f < nfaces; f++) {
        if ((st = tb__skip_blank(lx)))
            return st;
        if (lx->kind == TB__TOK_EOF)
            return tb__error_at(lx, lx->tline, lx->tcol, "unexpected end of file: %u of %u faces read", f, nfaces);
        bool has_id, has_mat;
        int32_t id = 0, mat = 0;
        if ((st = tb__face(lx, s, f, nverts, &has_id, &has_mat, &id, &mat)))
            return st;
        /* Per-face arrays exist if any face sets the value; earlier faces get 0. */
        if (has_id && !any_id) {
            any_id = true;
            if ((st = tb_array_resize(&s->ids, f)))
                return st;
        }
        if (has_mat && !any_mat) {
            any_mat = true;
            if ((st = tb_array_resize(&s->materials, f)))
                return st;
        }
        if (any_id && (st = tb_array_push(&s->ids, &id)))
            return st;
        if (any_mat && (st = tb_array_push(&s->materials, &mat)))
            return st;
        if ((st = tb__next(lx)))
            return st;
    }
    if ((st = tb__skip_blank(lx)))
        return st;
    if (lx->kind != TB__TOK_EOF)
        return tb__error_at(lx, lx->tline, lx->tcol, "expected end of file after the %u faces, found %s", nfaces,
                            tb__describe(lx, buf, sizeof buf));

    tb_fed *m = calloc(1, sizeof *m);
    if (!m)
        return tb_error(TB_ERR_NOMEM, "%s: out of memory", lx->name);
    m->nverts = nverts;
    m->nfaces = nfaces;
    m->nloops = (uint32_t)(s->loop_corners.len - 1);
    m->ncorners = (uint32_t)s->corners.len;
    m->positions = tb__take(&s->positions);
    m->normals = s->has_normals ? tb__take(&s->normals) : NULL;
    m->uvs = s->has_uvs ? tb__take(&s->uvs) : NULL;
    m->face_ids = any_id ? tb__take(&s->ids) : NULL;
    m->face_materials = any_mat ? tb__take(&s->materials) : NULL;
    m->face_loops = tb__take(&s->face_loops);
    m->loop_corners = tb__take(&s->loop_corners);
    m->corner_vert = tb__take(&s->corners);
    if (!m->positions || !m->face_loops || !m->loop_corners || !m->corner_vert ||
        (s->has_normals && !m->normals) || (s->has_uvs && !m->uvs) || (any_id && !m->face_ids) ||
        (any_mat && !m->face_materials)) {
        tb_fed_free(m);
        return tb_error(TB_ERR_NOMEM, "%s: out of memory", lx->name);
    }
    tb_fed_issue issue;
    st = tb__fed_finish(m, &issue);
    if (st == TB_ERR_FORMAT) {
        tb__loc loc = {1, 1};
        if (issue.loop != TB_FED_NONE && issue.loop < s->loop_loc.len)
            loc = TB_ARRAY_AT(&s->loop_loc, tb__loc, issue.loop);
        st = tb_error(TB_ERR_FORMAT, "%s:%ld:%ld: error: %s", lx->name, loc.line, loc.col, issue.message);
    }
    if (st) {
        tb_fed_free(m);
        return st;
    }
    *out = m;
    return TB_OK;
}

tb_status tb_fed_read_text(FILE *f, const char *name, tb_fed **out)
{
    *out = NULL;
    tb__lexer *lx = calloc(1, sizeof *lx);
    if (!lx)
        return tb_error(TB_ERR_NOMEM, "%s: out of memory", name);
    lx->f = f;
    lx->name = name;
    lx->line = lx->col = 1;
    tb__text_state s = {0};
    tb_array_init(&s.positions, sizeof(tb_vec3));
    tb_array_init(&s.normals, sizeof(tb_vec3));
    tb_array_init(&s.uvs, sizeof(tb_vec2));
    tb_array_init(&s.face_loops, sizeof(uint32_t));
    tb_array_init(&s.loop_corners, sizeof(uint32_t));
    tb_array_init(&s.corners, sizeof(uint32_t));
    tb_array_init(&s.ids, sizeof(int32_t));
    tb_array_init(&s.materials, sizeof(int32_t));
    tb_array_init(&s.loop_loc, sizeof(tb__loc));
    tb_status st = tb__parse(lx, &s, out);
    tb__state_free(&s);
    free(lx);
    return st;
}

/* ------------------------------------------------------------------- writer */

/* Shortest %g form of v that reads back (strtof) to the same float. */
static void tb__format_float(char *buf, size_t n, float v)
{
    for (int prec = 6; prec <= 9; prec++) {
        snprintf(buf, n, "%.*g", prec, (double)v);
        if (strtof(buf, NULL) == v && (v != 0 || signbit(strtof(buf, NULL)) == signbit(v)))
            return;
    }
}

static void tb__write_floats(FILE *f, const float *v, int dim)
{
    char buf[32];
    for (int k = 0; k < dim; k++) {
        tb__format_float(buf, sizeof buf, v[k]);
        fputs(buf, f);
        fputc(k + 1 < dim ? ' ' : '\n', f);
    }
}

tb_status tb_fed_write_text(FILE *f, const tb_fed *m)
{
    fprintf(f, "fed 1\nvertices %u\n", m->nverts);
    for (uint32_t v = 0; v < m->nverts; v++)
        tb__write_floats(f, &m->positions[v].x, 3);
    if (m->normals) {
        fprintf(f, "normals %u\n", m->nverts);
        for (uint32_t v = 0; v < m->nverts; v++)
            tb__write_floats(f, &m->normals[v].x, 3);
    }
    if (m->uvs) {
        fprintf(f, "uvs %u\n", m->nverts);
        for (uint32_t v = 0; v < m->nverts; v++)
            tb__write_floats(f, &m->uvs[v].x, 2);
    }
    fprintf(f, "faces %u\n", m->nfaces);
    for (uint32_t fc = 0; fc < m->nfaces; fc++) {
        for (uint32_t l = m->face_loops[fc]; l < m->face_loops[fc + 1]; l++) {
            if (l > m->face_loops[fc])
                fputs(" hole", f);
            for (uint32_t c = m->loop_corners[l]; c < m->loop_corners[l + 1]; c++)
                fprintf(f, c == tb_fed_face_corner_begin(m, fc) ? "%u" : " %u", m->corner_vert[c]);
        }
        if (m->face_ids)
            fprintf(f, " id %d", m->face_ids[fc]);
        if (m->face_materials)
            fprintf(f, " material %d", m->face_materials[fc]);
        fputc('\n', f);
    }
    if (ferror(f))
        return tb_error(TB_ERR_IO, "FED: write error: %s", strerror(errno));
    return TB_OK;
}
