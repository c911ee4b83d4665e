/* MID lexer: a hand-written scanner over a fixed read buffer (docs/mid.md,
 * section 2). The buffer ends in a zero byte, so the inner loops test one
 * byte and go to the slow path (refill, end of file, or a real NUL in the
 * input) only when they meet a zero. */
#include "host/mid/mid_internal.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

static void tb__cls_build(void);
static pthread_once_t tb__cls_once;

tb_status tb__mid_lexer_init(tb__mid_lexer *lx, FILE *fp, const char *name)
{
    pthread_once(&tb__cls_once, tb__cls_build);
    memset(lx, 0, sizeof *lx);
    lx->fp = fp;
    lx->name = name;
    lx->buf = calloc(1, TB__MID_BUF + 1 + TB__MID_BUF_PAD);
    lx->str = malloc(TB_MID_MAX_TOKEN + 1);
    if (!lx->buf || !lx->str) {
        tb__mid_lexer_free(lx);
        return tb_error(TB_ERR_NOMEM, "%s: out of memory", name);
    }
    lx->buf[0] = '\0';
    lx->line = 1;
    return TB_OK;
}

void tb__mid_lexer_free(tb__mid_lexer *lx)
{
    free(lx->buf);
    free(lx->str);
    lx->buf = lx->str = NULL;
}

uint64_t tb__mid_lexer_offset(const tb__mid_lexer *lx) { return lx->base + lx->pos; }

tb_status tb__mid_errorf(const tb__mid_lexer *lx, tb_mid_loc loc, const char *fmt, ...)
{
    char msg[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return tb_error(TB_ERR_FORMAT, "%s:%ld:%ld: error: %s", lx->name, loc.line, loc.col, msg);
}

/* Location of buffer index i (on the current line). */
static tb_mid_loc tb__loc_at(const tb__mid_lexer *lx, size_t i)
{
    return (tb_mid_loc){lx->line, (long)(lx->base + i - lx->line_start) + 1};
}

/* Moves the bytes from `keep` to the front and reads more. False at end of
 * file or on a read error (io_status set). */
static bool tb__refill(tb__mid_lexer *lx)
{
    if (lx->eof)
        return false;
    size_t n = lx->end - lx->keep;
    /* Tokens are capped far below the buffer size, so there is always room;
     * a full buffer here would read nothing and look like the end of file. */
    if (n >= TB__MID_BUF) {
        lx->io_status = tb_error(TB_ERR_IO, "%s: token too long for the read buffer", lx->name);
        lx->eof = true;
        return false;
    }
    if (lx->keep > 0) {
        memmove(lx->buf, lx->buf + lx->keep, n);
        lx->base += lx->keep;
        lx->pos -= lx->keep;
        lx->keep = 0;
    }
    lx->end = n;
    size_t got = fread(lx->buf + n, 1, TB__MID_BUF - n, lx->fp);
    lx->end += got;
    lx->buf[lx->end] = '\0';
    if (got == 0) {
        if (ferror(lx->fp))
            lx->io_status = tb_error(TB_ERR_IO, "%s: read error: %s", lx->name, strerror(errno));
        lx->eof = true;
        return false;
    }
    return true;
}

/* The byte at pos after a zero was seen there: the refilled byte, 0 for a
 * real NUL in the input, -1 at end of file (or after a read error). */
__attribute__((noinline)) static int tb__more(tb__mid_lexer *lx)
{
    if (lx->pos < lx->end)
        return 0;
    if (!tb__refill(lx))
        return -1;
    return (unsigned char)lx->buf[lx->pos];
}

/* The byte at pos, or -1 at the end. */
static inline int tb__peek(tb__mid_lexer *lx)
{
    int c = (unsigned char)lx->buf[lx->pos];
    return c ? c : tb__more(lx);
}

/* Character classes, one table lookup per byte in the hot loops. */
enum {
    TB__C_SPACE = 1,  /* space, tab, carriage return (not newline: it counts lines) */
    TB__C_DIGIT = 2,  /* 0-9 */
    TB__C_IDENT = 4,  /* letters, digits, _ */
    TB__C_START = 8,  /* letters, _ */
    TB__C_ENDNUM = 16, /* may follow a number: white space, punctuation, # */
};
static unsigned char tb__cls[256];
static pthread_once_t tb__cls_once = PTHREAD_ONCE_INIT;

static void tb__cls_build(void)
{
    for (int c = 0; c < 256; c++) {
        unsigned char k = 0;
        if (c == ' ' || c == '\t' || c == '\r')
            k |= TB__C_SPACE;
        if (c >= '0' && c <= '9')
            k |= TB__C_DIGIT | TB__C_IDENT;
        if ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_')
            k |= TB__C_IDENT | TB__C_START;
        if (c && strchr(" \t\r\n#{}[]()=,", c))
            k |= TB__C_ENDNUM;
        tb__cls[c] = k;
    }
}

static inline bool tb__is_digit(int c) { return c >= 0 && (tb__cls[c & 255] & TB__C_DIGIT); }
static inline bool tb__is_ident_start(int c) { return c >= 0 && (tb__cls[c & 255] & TB__C_START); }
static inline bool tb__is_ident(int c) { return c >= 0 && (tb__cls[c & 255] & TB__C_IDENT); }

/* Error for a failed read, or the given end-of-input situation. */
static tb_status tb__eof_or_io(tb__mid_lexer *lx) { return lx->io_status; }

/* Validates one UTF-8 sequence whose lead byte c0 (>= 0x80) is at pos, and
 * moves pos past it, copying it to *out (advancing *out) if out is not NULL.
 * The caller has set keep so the bytes survive a refill. */
__attribute__((noinline)) static tb_status tb__utf8(tb__mid_lexer *lx, char **out)
{
    size_t start = lx->pos;
    tb_mid_loc loc = tb__loc_at(lx, start);
    int c0 = tb__peek(lx);
    int n;
    int lo = 0x80, hi = 0xBF; /* allowed range of the second byte */
    if (c0 >= 0xC2 && c0 <= 0xDF)
        n = 1;
    else if (c0 >= 0xE0 && c0 <= 0xEF) {
        n = 2;
        if (c0 == 0xE0)
            lo = 0xA0; /* overlong */
        if (c0 == 0xED)
            hi = 0x9F; /* surrogates */
    } else if (c0 >= 0xF0 && c0 <= 0xF4) {
        n = 3;
        if (c0 == 0xF0)
            lo = 0x90;
        if (c0 == 0xF4)
            hi = 0x8F; /* above U+10FFFF */
    } else
        return tb__mid_errorf(lx, loc, "invalid UTF-8 byte 0x%02x", (unsigned)c0);
    unsigned char seq[4] = {(unsigned char)c0};
    lx->pos++;
    for (int i = 1; i <= n; i++) {
        int c = tb__peek(lx);
        if (c < 0 && lx->io_status)
            return lx->io_status;
        int l = i == 1 ? lo : 0x80, h = i == 1 ? hi : 0xBF;
        if (c < l || c > h)
            return tb__mid_errorf(lx, loc, "invalid UTF-8 sequence starting with byte 0x%02x",
                                  (unsigned)c0);
        seq[i] = (unsigned char)c;
        lx->pos++;
    }
    if (out) {
        memcpy(*out, seq, (size_t)n + 1);
        *out += n + 1;
    }
    return TB_OK;
}

/* Skips a comment from '#' to the end of the line (the newline stays). */
__attribute__((noinline)) static tb_status tb__comment(tb__mid_lexer *lx)
{
    for (;;) {
        lx->keep = lx->pos;
        int c = (unsigned char)lx->buf[lx->pos];
        if (c == 0) {
            c = tb__more(lx);
            if (c < 0)
                return tb__eof_or_io(lx);
            if (c == 0)
                return tb__mid_errorf(lx, tb__loc_at(lx, lx->pos), "NUL byte in the input");
        }
        if (c == '\n')
            return TB_OK;
        if (c >= 0x80) {
            tb_status st = tb__utf8(lx, NULL);
            if (st)
                return st;
            continue;
        }
        lx->pos++;
    }
}

/* Appends the UTF-8 encoding of code point u to *out. */
static void tb__put_utf8(char **out, uint32_t u)
{
    unsigned char *o = (unsigned char *)*out;
    if (u < 0x80) {
        *o++ = (unsigned char)u;
    } else if (u < 0x800) {
        *o++ = (unsigned char)(0xC0 | (u >> 6));
        *o++ = (unsigned char)(0x80 | (u & 0x3F));
    } else if (u < 0x10000) {
        *o++ = (unsigned char)(0xE0 | (u >> 12));
        *o++ = (unsigned char)(0x80 | ((u >> 6) & 0x3F));
        *o++ = (unsigned char)(0x80 | (u & 0x3F));
    } else {
        *o++ = (unsigned char)(0xF0 | (u >> 18));
        *o++ = (unsigned char)(0x80 | ((u >> 12) & 0x3F));
        *o++ = (unsigned char)(0x80 | ((u >> 6) & 0x3F));
        *o++ = (unsigned char)(0x80 | (u & 0x3F));
    }
    *out = (char *)o;
}

static int tb__hex(int c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    if (c >= 'A' && c <= 'F')
        return c - 'A' + 10;
    return -1;
}

/* A string token; pos is at the opening quote. The unescaped text goes to
 * lx->str (raw bytes are not kept, so escapes may make the raw string
 * longer than the buffer). */
__attribute__((noinline)) static tb_status tb__string(tb__mid_lexer *lx)
{
    tb_mid_loc start = lx->loc;
    char *o = lx->str;
    char *limit = lx->str + TB_MID_MAX_TOKEN;
    /* Fast path: printable ASCII without escapes up to a closing quote in
     * the buffer is copied as it is. Anything else (escapes, UTF-8, control
     * bytes, the buffer end, an overlong string) takes the loop below from
     * the opening quote, which gives the messages. */
    {
        const char *b = lx->buf + lx->pos + 1, *q = b;
        while ((unsigned char)*q >= 0x20 && (unsigned char)*q < 0x7F && *q != '"' && *q != '\\')
            q++;
        size_t n = (size_t)(q - b);
        if (*q == '"' && n <= TB_MID_MAX_TOKEN) {
            memcpy(o, b, n);
            o[n] = '\0';
            lx->pos += n + 2;
            lx->type = TB__T_STRING;
            lx->text = lx->str;
            lx->len = n;
            return TB_OK;
        }
    }
    lx->pos++;
    for (;;) {
        lx->keep = lx->pos;
        int c = (unsigned char)lx->buf[lx->pos];
        if (c == 0) {
            c = tb__more(lx);
            if (c < 0) {
                if (lx->io_status)
                    return lx->io_status;
                return tb__mid_errorf(lx, start, "unterminated string (a string ends on the line it starts)");
            }
            if (c == 0)
                return tb__mid_errorf(lx, tb__loc_at(lx, lx->pos), "NUL byte in the input");
        }
        if (c == '"') {
            lx->pos++;
            break;
        }
        if (c == '\n')
            return tb__mid_errorf(lx, start, "unterminated string (a string ends on the line it starts)");
        if (c < 0x20 || c == 0x7F)
            return tb__mid_errorf(lx, tb__loc_at(lx, lx->pos),
                                  "control character 0x%02x in a string (write it as an escape such as \\n or \\u{%x})",
                                  (unsigned)c, (unsigned)c);
        if (c >= 0x80) {
            int n = c >= 0xF0 ? 4 : c >= 0xE0 ? 3 : 2; /* an invalid lead byte fails in tb__utf8 */
            if (o + n > limit)
                return tb__mid_errorf(lx, start, "string longer than %d bytes", TB_MID_MAX_TOKEN);
            tb_status st = tb__utf8(lx, &o);
            if (st)
                return st;
            continue;
        }
        if (c != '\\') {
            if (o >= limit)
                return tb__mid_errorf(lx, start, "string longer than %d bytes", TB_MID_MAX_TOKEN);
            *o++ = (char)c;
            lx->pos++;
            continue;
        }
        /* An escape. */
        tb_mid_loc esc = tb__loc_at(lx, lx->pos);
        lx->pos++;
        int e = tb__peek(lx);
        uint32_t u;
        switch (e) {
        case '"': u = '"'; lx->pos++; break;
        case '\\': u = '\\'; lx->pos++; break;
        case 'n': u = '\n'; lx->pos++; break;
        case 't': u = '\t'; lx->pos++; break;
        case 'r': u = '\r'; lx->pos++; break;
        case 'u': {
            lx->pos++;
            if (tb__peek(lx) != '{')
                return tb__mid_errorf(lx, esc, "malformed escape: expected \\u{HEX} with 1 to 6 hex digits");
            lx->pos++;
            u = 0;
            int nd = 0, h;
            while ((h = tb__hex(tb__peek(lx))) >= 0) {
                if (++nd > 6)
                    return tb__mid_errorf(lx, esc, "malformed escape: expected \\u{HEX} with 1 to 6 hex digits");
                u = u * 16 + (uint32_t)h;
                lx->pos++;
            }
            if (nd == 0 || tb__peek(lx) != '}')
                return tb__mid_errorf(lx, esc, "malformed escape: expected \\u{HEX} with 1 to 6 hex digits");
            lx->pos++;
            if (u == 0 || u > 0x10FFFF || (u >= 0xD800 && u <= 0xDFFF))
                return tb__mid_errorf(lx, esc,
                                      "\\u{%x} is not allowed (a Unicode scalar value from 1 to 10ffff, not a surrogate)",
                                      (unsigned)u);
            break;
        }
        default:
            if (e < 0 && lx->io_status)
                return lx->io_status;
            if (e < 0 || e == '\n')
                return tb__mid_errorf(lx, start, "unterminated string (a string ends on the line it starts)");
            if (e > 0x20 && e < 0x7F)
                return tb__mid_errorf(lx, esc, "unknown escape '\\%c' in a string (use \\\" \\\\ \\n \\t \\r or \\u{HEX})", e);
            return tb__mid_errorf(lx, esc, "unknown escape in a string (use \\\" \\\\ \\n \\t \\r or \\u{HEX})");
        }
        if (o + (u < 0x80 ? 1 : u < 0x800 ? 2 : u < 0x10000 ? 3 : 4) > limit)
            return tb__mid_errorf(lx, start, "string longer than %d bytes", TB_MID_MAX_TOKEN);
        tb__put_utf8(&o, u);
    }
    *o = '\0';
    lx->type = TB__T_STRING;
    lx->text = lx->str;
    lx->len = (size_t)(o - lx->str);
    return TB_OK;
}

/* Exact powers of ten (every one up to 1e22 is a double). */
static const double tb__p10[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                   1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                   1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

/* Characters that may end a number: white space, punctuation, a comment. */
static bool tb__ends_number(int c)
{
    switch (c) {
    case -1: case ' ': case '\t': case '\r': case '\n': case '#':
    case '{': case '}': case '[': case ']': case '(': case ')': case '=': case ',':
        return true;
    default:
        return false;
    }
}

/* Reports the run of number-like characters from the token start. */
__attribute__((noinline)) static tb_status tb__malformed_number(tb__mid_lexer *lx)
{
    int c;
    while ((c = tb__peek(lx)) >= 0 && (tb__is_ident(c) || c == '.' || c == '+' || c == '-') &&
           lx->pos - lx->keep < 40)
        lx->pos++;
    int n = (int)(lx->pos - lx->keep);
    return tb__mid_errorf(lx, lx->loc, "malformed number '%.*s'", n, lx->buf + lx->keep);
}

/* A number token; pos is at its first character ([+-.0-9]). Clinger's fast
 * path (an integer mantissa below 2^53 times an exact power of ten is
 * correctly rounded by one multiplication or division) covers the numbers
 * people and the writer produce; strtod does the rest. */
__attribute__((noinline)) static tb_status tb__number(tb__mid_lexer *lx)
{
    int c = tb__peek(lx);
    bool neg = false;
    if (c == '+' || c == '-') {
        neg = c == '-';
        lx->pos++;
        c = tb__peek(lx);
    }
    uint64_t m = 0;
    int nd = 0, exp10 = 0;
    bool exact = true, digits = false;
    while (tb__is_digit(c)) {
        digits = true;
        if (m || c != '0') {
            if (nd < 19) {
                m = m * 10 + (uint64_t)(c - '0');
                nd++;
            } else
                exact = false;
        }
        if (++lx->pos - lx->keep > TB_MID_MAX_TOKEN)
            return tb__mid_errorf(lx, lx->loc, "number longer than %d bytes", TB_MID_MAX_TOKEN);
        c = tb__peek(lx);
    }
    if (c == '.') {
        lx->pos++;
        c = tb__peek(lx);
        while (tb__is_digit(c)) {
            digits = true;
            if (m || c != '0') {
                if (nd < 19) {
                    m = m * 10 + (uint64_t)(c - '0');
                    nd++;
                    exp10--;
                } else
                    exact = false;
            } else
                exp10--;
            if (++lx->pos - lx->keep > TB_MID_MAX_TOKEN)
                return tb__mid_errorf(lx, lx->loc, "number longer than %d bytes", TB_MID_MAX_TOKEN);
            c = tb__peek(lx);
        }
    }
    if (!digits)
        return tb__malformed_number(lx);
    if (c == 'e' || c == 'E') {
        lx->pos++;
        c = tb__peek(lx);
        int esign = 1, e = 0;
        if (c == '+' || c == '-') {
            esign = c == '-' ? -1 : 1;
            lx->pos++;
            c = tb__peek(lx);
        }
        if (!tb__is_digit(c))
            return tb__malformed_number(lx);
        while (tb__is_digit(c)) {
            if (e < 100000)
                e = e * 10 + (c - '0');
            if (++lx->pos - lx->keep > TB_MID_MAX_TOKEN)
                return tb__mid_errorf(lx, lx->loc, "number longer than %d bytes", TB_MID_MAX_TOKEN);
            c = tb__peek(lx);
        }
        exp10 += esign * e;
    }
    if (!tb__ends_number(c)) {
        if (c < 0 && lx->io_status)
            return lx->io_status;
        return tb__malformed_number(lx);
    }
    lx->type = TB__T_NUMBER;
    lx->text = lx->buf + lx->keep;
    lx->len = lx->pos - lx->keep;
    double v;
    if (m == 0)
        v = 0.0;
    else if (exact && m <= ((uint64_t)1 << 53) && exp10 >= -22 && exp10 <= 22)
        v = exp10 >= 0 ? (double)m * tb__p10[exp10] : (double)m / tb__p10[-exp10];
    else {
        /* strtod needs a terminated copy, and the "C" locale so that '.' is
         * the decimal point whatever the program set with setlocale. */
        memcpy(lx->str, lx->text, lx->len);
        lx->str[lx->len] = '\0';
        locale_t c = tb__mid_c_locale(), old = c ? uselocale(c) : (locale_t)0;
        v = fabs(strtod(lx->str, NULL));
        if (c)
            uselocale(old);
    }
    if (!isfinite(v))
        return tb__mid_errorf(lx, lx->loc, "number out of range '%.*s' (beyond the largest double)",
                              (int)lx->len, lx->text);
    lx->number = neg ? -v : v;
    return TB_OK;
}

/* The common case of tb__number, scanned with a local pointer: a short
 * number inside the buffer that Clinger's fast path converts exactly. False
 * (nothing consumed) for anything else, which tb__number then handles with
 * refills, limits, strtod and error messages. */
static bool tb__number_fast(tb__mid_lexer *lx)
{
    const char *b = lx->buf + lx->pos, *p = b;
    bool neg = false;
    if (*p == '+' || *p == '-') {
        neg = *p == '-';
        p++;
    }
    /* Find the digit runs first, then accumulate them without checks: with
     * at most 19 digits in all the mantissa cannot overflow 64 bits. */
    const char *i0 = p;
    while (tb__cls[(unsigned char)*p] & TB__C_DIGIT)
        p++;
    const char *i1 = p, *f0 = p, *f1 = p;
    if (*p == '.') {
        f0 = ++p;
        while (tb__cls[(unsigned char)*p] & TB__C_DIGIT)
            p++;
        f1 = p;
    }
    if (i1 == i0 && f1 == f0)
        return false;
    if ((i1 - i0) + (f1 - f0) > 19)
        return false;
    uint64_t m = 0;
    for (const char *q = i0; q < i1; q++)
        m = m * 10 + (uint64_t)(*q - '0');
    for (const char *q = f0; q < f1; q++)
        m = m * 10 + (uint64_t)(*q - '0');
    int exp10 = -(int)(f1 - f0);
    if (*p == 'e' || *p == 'E') {
        p++;
        int esign = 1, e = 0;
        if (*p == '+' || *p == '-')
            esign = *p++ == '-' ? -1 : 1;
        if (!tb__is_digit(*p))
            return false;
        for (; tb__is_digit(*p); p++)
            if (e < 1000)
                e = e * 10 + (*p - '0');
        exp10 += esign * e;
    }
    /* A zero byte is the buffer end (or a NUL): let the careful path decide. */
    if (!(tb__cls[(unsigned char)*p] & TB__C_ENDNUM) || p - b > 64)
        return false;
    double v;
    if (m == 0)
        v = 0.0;
    else if (m <= ((uint64_t)1 << 53) && exp10 >= -22 && exp10 <= 22)
        v = exp10 >= 0 ? (double)m * tb__p10[exp10] : (double)m / tb__p10[-exp10];
    else
        return false;
    lx->type = TB__T_NUMBER;
    lx->text = b;
    lx->len = (size_t)(p - b);
    lx->number = neg ? -v : v;
    lx->pos += lx->len;
    return true;
}

tb_status tb__mid_lex(tb__mid_lexer *lx)
{
    for (;;) {
        /* White space, scanned with a local pointer (the sentinel stops it). */
        const char *p = lx->buf + lx->pos;
        for (;;) {
            unsigned char ch = (unsigned char)*p;
            if (ch == ' ' || ch == '\t' || ch == '\r') {
                p++;
                continue;
            }
            if (ch != '\n')
                break;
            p++;
            lx->line++;
            lx->line_start = lx->base + (uint64_t)(p - lx->buf);
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
            /* The indentation after a newline, 8 bytes at a time: the first
             * byte that is not a space ends the run. The zero sentinel is
             * not a space, and the buffer has TB__MID_BUF_PAD bytes after
             * it. (Between tokens a run is mostly one space, which the byte
             * loop above handles with less latency.) */
            for (;;) {
                uint64_t w;
                memcpy(&w, p, 8);
                w ^= 0x2020202020202020u;
                if (w) {
                    p += (unsigned)__builtin_ctzll(w) >> 3;
                    break;
                }
                p += 8;
            }
#endif
        }
        lx->pos = (size_t)(p - lx->buf);
        lx->keep = lx->pos;
        int c = (unsigned char)*p;
        if (c == 0) {
            c = tb__more(lx);
            lx->keep = lx->pos;
            if (c < 0) {
                if (lx->io_status)
                    return lx->io_status;
                lx->type = TB__T_EOF;
                lx->loc = tb__loc_at(lx, lx->pos);
                lx->text = "";
                lx->len = 0;
                return TB_OK;
            }
            if (c == 0)
                return tb__mid_errorf(lx, tb__loc_at(lx, lx->pos), "NUL byte in the input");
        }
        lx->loc = tb__loc_at(lx, lx->pos);
        tb__mid_tok punct;
        switch (c) {
        case ' ': case '\t': case '\r':
            lx->pos++;
            continue;
        case '\n':
            lx->pos++;
            lx->line++;
            lx->line_start = lx->base + lx->pos;
            continue;
        case '#': {
            tb_status st = tb__comment(lx);
            if (st)
                return st;
            continue;
        }
        case '"':
            return tb__string(lx);
        case '{': punct = TB__T_LBRACE; break;
        case '}': punct = TB__T_RBRACE; break;
        case '[': punct = TB__T_LBRACKET; break;
        case ']': punct = TB__T_RBRACKET; break;
        case '(': punct = TB__T_LPAREN; break;
        case ')': punct = TB__T_RPAREN; break;
        case '=': punct = TB__T_EQUAL; break;
        case ',': punct = TB__T_COMMA; break;
        case '+': case '-': case '.':
        case '0': case '1': case '2': case '3': case '4':
        case '5': case '6': case '7': case '8': case '9':
            if (tb__number_fast(lx))
                return TB_OK;
            return tb__number(lx);
        default:
            if (tb__is_ident_start(c)) {
                /* Fast path: the identifier ends inside the buffer. */
                const char *b = lx->buf + lx->pos, *q = b + 1;
                while (tb__is_ident(*q))
                    q++;
                if (q < lx->buf + lx->end && q - b <= TB_MID_MAX_TOKEN) {
                    lx->type = TB__T_IDENT;
                    lx->text = b;
                    lx->len = (size_t)(q - b);
                    lx->pos += lx->len;
                    return TB_OK;
                }
                lx->pos++;
                while (tb__is_ident(c = tb__peek(lx))) {
                    lx->pos++;
                    if (lx->pos - lx->keep > TB_MID_MAX_TOKEN)
                        return tb__mid_errorf(lx, lx->loc, "identifier longer than %d bytes",
                                              TB_MID_MAX_TOKEN);
                }
                if (c < 0 && lx->io_status)
                    return lx->io_status;
                lx->type = TB__T_IDENT;
                lx->text = lx->buf + lx->keep;
                lx->len = lx->pos - lx->keep;
                return TB_OK;
            }
            if (c > 0x20 && c < 0x7F)
                return tb__mid_errorf(lx, lx->loc, "unexpected character '%c'", c);
            if (c == 0xEF && lx->base + lx->pos == 0)
                return tb__mid_errorf(lx, lx->loc,
                                      "byte-order mark at the start of the file (MID files are UTF-8 without a BOM)");
            return tb__mid_errorf(lx, lx->loc, "unexpected byte 0x%02x outside a string or comment",
                                  (unsigned)c);
        }
        lx->pos++;
        lx->type = punct;
        lx->text = lx->buf + lx->keep;
        lx->len = 1;
        return TB_OK;
    }
}

void tb__mid_describe_token(const tb__mid_lexer *lx, char *out, size_t size)
{
    switch (lx->type) {
    case TB__T_EOF:
        snprintf(out, size, "end of file");
        return;
    case TB__T_IDENT:
        snprintf(out, size, "'%.*s'", lx->len > 40 ? 40 : (int)lx->len, lx->text);
        return;
    case TB__T_NUMBER:
        snprintf(out, size, "number %.*s", lx->len > 40 ? 40 : (int)lx->len, lx->text);
        return;
    case TB__T_STRING: {
        /* Up to 24 bytes, cut at a character boundary. */
        size_t n = lx->len;
        const char *dots = "";
        if (n > 24) {
            n = 24;
            while (n > 0 && ((unsigned char)lx->text[n] & 0xC0) == 0x80)
                n--;
            dots = "...";
        }
        char shown[32];
        for (size_t i = 0; i < n; i++)
            shown[i] = (unsigned char)lx->text[i] < 0x20 ? '?' : lx->text[i];
        snprintf(out, size, "string \"%.*s%s\"", (int)n, shown, dots);
        return;
    }
    default:
        snprintf(out, size, "'%c'", lx->text[0]);
        return;
    }
}
