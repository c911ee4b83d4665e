/* Utah Raster Toolkit RLE (Spencer W. Thomas, 1983-87): reader and writer.
 * Layout, opcodes and what is accepted or rejected are described in
 * docs/rle.md; the short version:
 *
 *   15-byte header (little-endian 16-bit words), background colour or a
 *   filler byte, optional colour maps, optional comments, then a stream of
 *   2-byte instructions (opcode, operand; bit 0x40 of the opcode = "long":
 *   a 16-bit operand follows) that paint scanlines from the BOTTOM row up.
 *
 * The reader never trusts a count from the file: every write into the image
 * is bounds-checked, the image size is capped before anything is allocated,
 * and every error names the byte offset where the input went wrong. */
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "util/image/image.h"

/* Header flags (byte 10). */
#define TB__RLE_CLEARFIRST    0x01 /* clear the frame buffer to the background first */
#define TB__RLE_NO_BACKGROUND 0x02 /* no background colour in the header */
#define TB__RLE_ALPHA         0x04 /* an alpha channel (number 255, i.e. -1) is present */
#define TB__RLE_COMMENT       0x08 /* comments follow the colour map */

/* Opcodes; TB__RLE_LONG marks the form with a 16-bit operand after the instruction. */
#define TB__RLE_LONG        0x40
#define TB__RLE_SKIP_LINES  1
#define TB__RLE_SET_COLOR   2
#define TB__RLE_SKIP_PIXELS 3
#define TB__RLE_BYTE_DATA   5
#define TB__RLE_RUN_DATA    6
#define TB__RLE_EOF         7

/* SetColor operand naming the alpha channel. */
#define TB__RLE_ALPHA_CHANNEL 255

/* Largest image the reader allocates (8192 x 8192): the header alone can claim
 * 65535 x 65535, and a few bytes of SkipLines can legally describe it, so the
 * size cannot be checked against the file length. */
#define TB__RLE_MAX_PIXELS ((int64_t)1 << 26)

/* Largest width/height the writer emits: some RLE readers (netpbm's among
 * them) hold these sizes in signed 16-bit variables. */
#define TB__RLE_WRITE_MAX_SIZE 32767

/* A run of at least this many equal bytes is written as RunData (4 bytes)
 * rather than inside ByteData (1 byte per pixel). */
#define TB__RLE_MIN_RUN 4

/* ------------------------------------------------------------------ reading */

/* The input stream and how far into it we are, for error messages. */
typedef struct tb__rle_in {
    FILE *f;
    const char *name;
    long pos; /* bytes consumed so far */
} tb__rle_in;

/* Reads exactly `n` bytes; a short read is a truncated file (or an I/O error). */
static tb_status tb__rle_read(tb__rle_in *in, void *buf, size_t n, const char *what)
{
    size_t got = fread(buf, 1, n, in->f);
    if (got != n) {
        if (ferror(in->f))
            return tb_error(TB_ERR_IO, "%s: read error at byte %ld (%s)", in->name,
                            in->pos + (long)got, what);
        return tb_error(TB_ERR_FORMAT, "%s: truncated at byte %ld: %s needs %zu bytes, %zu left",
                        in->name, in->pos + (long)got, what, n, got);
    }
    in->pos += (long)n;
    return TB_OK;
}

static unsigned tb__rle_u16(const unsigned char *p)
{
    return (unsigned)p[0] | ((unsigned)p[1] << 8);
}

/* Everything the header says, after validation. */
typedef struct tb__rle_header {
    int xpos, ypos;       /* lower-left corner on the original frame buffer (dropped) */
    int width, height;    /* xlen, ylen */
    int flags;
    int ncolors;          /* colour channels in the file (1..3) */
    int alpha;            /* nonzero: channel 255 carries alpha */
    int has_bg;           /* nonzero: bg[] holds the background colour */
    unsigned char bg[3];
    int ncmap;            /* channels in the colour map (0: none) */
    int maplen;           /* entries per colour-map channel (1 << cmaplen) */
    uint16_t *cmap;       /* ncmap * maplen entries, channel-major, 16-bit left-justified */
} tb__rle_header;

static tb_status tb__rle_read_header(tb__rle_in *in, tb__rle_header *h)
{
    unsigned char b[15];
    tb_status st = tb__rle_read(in, b, sizeof b, "the 15-byte header");
    if (st)
        return st;
    if (b[0] != 0x52 || b[1] != 0xCC)
        return tb_error(TB_ERR_FORMAT,
                        "%s: not a Utah RLE file: bytes 0-1 are %02x %02x, expected 52 cc",
                        in->name, b[0], b[1]);
    h->xpos = (int16_t)tb__rle_u16(b + 2);
    h->ypos = (int16_t)tb__rle_u16(b + 4);
    h->width = (int)tb__rle_u16(b + 6);
    h->height = (int)tb__rle_u16(b + 8);
    h->flags = b[10];
    h->ncolors = b[11];
    int pixelbits = b[12];
    h->ncmap = b[13];
    int cmaplen = b[14];

    if (h->width == 0 || h->height == 0)
        return tb_error(TB_ERR_FORMAT, "%s: empty image (%dx%d) in bytes 6-9", in->name,
                        h->width, h->height);
    if ((int64_t)h->width * h->height > TB__RLE_MAX_PIXELS)
        return tb_error(TB_ERR_UNSUPPORTED,
                        "%s: %dx%d image (bytes 6-9) exceeds the reader's limit of %lld pixels",
                        in->name, h->width, h->height, (long long)TB__RLE_MAX_PIXELS);
    if (h->ncolors < 1 || h->ncolors > 3)
        return tb_error(TB_ERR_UNSUPPORTED,
                        "%s: %d colour channels (byte 11); only 1 to 3 are supported",
                        in->name, h->ncolors);
    if (pixelbits != 8)
        return tb_error(TB_ERR_UNSUPPORTED, "%s: %d bits per pixel (byte 12); only 8 is supported",
                        in->name, pixelbits);
    h->alpha = (h->flags & TB__RLE_ALPHA) != 0;
    if (h->ncmap > 0) {
        if (cmaplen > 8)
            return tb_error(TB_ERR_UNSUPPORTED,
                            "%s: colour map of 2^%d entries (byte 14); at most 256 are supported",
                            in->name, cmaplen);
        /* URT's two conventions: one map per channel, or one 8-bit channel
         * indexing an RGB map (pseudocolour). */
        if (h->ncmap != h->ncolors && !(h->ncolors == 1 && h->ncmap == 3))
            return tb_error(TB_ERR_UNSUPPORTED,
                            "%s: %d colour-map channels (byte 13) for %d colour channels; "
                            "supported are one map per channel, or 3 maps for 1 channel",
                            in->name, h->ncmap, h->ncolors);
        h->maplen = 1 << cmaplen;
    }

    /* Background colour padded to an odd length, or one filler byte: either
     * way the header plus this part has an even length. */
    if (!(h->flags & TB__RLE_NO_BACKGROUND)) {
        unsigned char bg[3];
        size_t n = 1 + (size_t)(h->ncolors / 2) * 2;
        if ((st = tb__rle_read(in, bg, n, "the background colour")))
            return st;
        h->has_bg = 1;
        for (int c = 0; c < h->ncolors; c++) {
            h->bg[c] = bg[c];
            if (h->ncmap > 0 && bg[c] >= h->maplen)
                return tb_error(TB_ERR_FORMAT,
                                "%s: background value %d at byte %ld is beyond the colour map "
                                "of %d entries",
                                in->name, bg[c], in->pos - (long)n + c, h->maplen);
        }
    } else {
        unsigned char filler;
        if ((st = tb__rle_read(in, &filler, 1, "the filler byte after the header")))
            return st;
    }

    if (h->ncmap > 0) {
        size_t n = (size_t)h->ncmap * (size_t)h->maplen;
        unsigned char *raw = malloc(2 * n);
        h->cmap = malloc(n * sizeof *h->cmap);
        if (!raw || !h->cmap) {
            free(raw);
            return tb_error(TB_ERR_NOMEM, "%s: no memory for the colour map", in->name);
        }
        st = tb__rle_read(in, raw, 2 * n, "the colour map");
        for (size_t i = 0; !st && i < n; i++)
            h->cmap[i] = (uint16_t)tb__rle_u16(raw + 2 * i);
        free(raw);
        if (st)
            return st;
    }
    return TB_OK;
}

/* Reads the comment block (flags & TB__RLE_COMMENT): a 16-bit length, then
 * that many bytes of NUL-terminated strings, padded to an even length. */
static tb_status tb__rle_read_comments(tb__rle_in *in, char **block, size_t *len)
{
    unsigned char b[2];
    tb_status st = tb__rle_read(in, b, 2, "the comment length");
    if (st)
        return st;
    size_t n = tb__rle_u16(b);
    size_t padded = (n + 1) & ~(size_t)1; /* the block keeps the stream 16-bit aligned */
    char *buf = malloc(padded + 1);
    if (!buf)
        return tb_error(TB_ERR_NOMEM, "%s: no memory for %zu bytes of comments", in->name, n);
    if ((st = tb__rle_read(in, buf, padded, "the comments"))) {
        free(buf);
        return st;
    }
    buf[n] = '\0'; /* the last comment's terminator may be missing */
    *block = buf;
    *len = n;
    return TB_OK;
}

/* Comments become attributes: "key=value" -> (key, value), a bare "key" ->
 * (key, ""), the URT convention; a repeated key keeps its last value. */
static tb_status tb__rle_apply_comments(tb_image *img, const char *name, char *block, size_t len)
{
    for (size_t i = 0; i < len;) {
        char *s = block + i;
        size_t n = strlen(s);
        i += n + 1;
        if (n == 0)
            continue;
        char *eq = strchr(s, '=');
        const char *value = "";
        if (eq) {
            *eq = '\0';
            value = eq + 1;
        }
        if (s[0] == '\0')
            continue; /* "=value" names nothing */
        tb_status st = tb_image_set_attr(img, s, value);
        if (st)
            return tb_error_context(st, "%s: comment \"%s\"", name, s);
    }
    return TB_OK;
}

/* Decoder state for the instruction stream. */
typedef struct tb__rle_decode {
    tb__rle_in *in;
    const tb__rle_header *h;
    unsigned char *planes[4]; /* colour channels 0..ncolors-1, then alpha; row 0 at the BOTTOM */
    int limit[4];             /* pixel values must be below this (colour-map length) */
} tb__rle_decode;

/* Checks that `n` pixels starting at (x, y) lie inside the image. */
static tb_status tb__rle_check_span(const tb__rle_decode *d, long op_pos, const char *op,
                                    int64_t x, int64_t y, int64_t n)
{
    if (y >= d->h->height)
        return tb_error(TB_ERR_FORMAT,
                        "%s: %s at byte %ld writes scanline %lld, above the image's %d lines",
                        d->in->name, op, op_pos, (long long)y, d->h->height);
    if (x + n > d->h->width)
        return tb_error(TB_ERR_FORMAT,
                        "%s: %s at byte %ld writes pixels %lld..%lld of a %d-pixel scanline",
                        d->in->name, op, op_pos, (long long)x, (long long)(x + n - 1),
                        d->h->width);
    return TB_OK;
}

static tb_status tb__rle_check_values(const tb__rle_decode *d, long op_pos, int ch,
                                      const unsigned char *v, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (v[i] >= d->limit[ch])
            return tb_error(TB_ERR_FORMAT,
                            "%s: pixel value %d (instruction at byte %ld) is beyond the "
                            "colour map of %d entries",
                            d->in->name, v[i], op_pos, d->limit[ch]);
    return TB_OK;
}

/* Runs the instruction stream up to the EOF opcode. */
static tb_status tb__rle_decode_ops(tb__rle_decode *d)
{
    const tb__rle_header *h = d->h;
    tb__rle_in *in = d->in;
    int64_t x = 0, y = 0; /* x from the left, y from the bottom */
    int ch = 0;           /* URT starts on channel 0 until a SetColor */
    tb_status st;
    for (;;) {
        long op_pos = in->pos;
        unsigned char inst[2], b[2];
        size_t got = fread(inst, 1, 2, in->f);
        if (got != 2) {
            if (ferror(in->f))
                return tb_error(TB_ERR_IO, "%s: read error at byte %ld", in->name, op_pos);
            return tb_error(TB_ERR_FORMAT,
                            "%s: truncated at byte %ld: the data ends without an EOF opcode",
                            in->name, op_pos + (long)got);
        }
        in->pos += 2;
        int op = inst[0] & ~TB__RLE_LONG;
        unsigned operand = inst[1];
        if (inst[0] & TB__RLE_LONG) {
            if ((st = tb__rle_read(in, b, 2, "a long operand")))
                return st;
            operand = tb__rle_u16(b);
        }
        switch (op) {
        case TB__RLE_SKIP_LINES:
            /* Saturate: skipping past the top is harmless until data is written there. */
            y = y + operand > h->height ? h->height : y + operand;
            x = 0;
            break;
        case TB__RLE_SET_COLOR:
            if (operand == TB__RLE_ALPHA_CHANNEL) {
                if (!h->alpha)
                    return tb_error(TB_ERR_FORMAT,
                                    "%s: SetColor at byte %ld selects alpha, but the header's "
                                    "alpha flag is clear",
                                    in->name, op_pos);
                ch = h->ncolors;
            } else if (operand < (unsigned)h->ncolors) {
                ch = (int)operand;
            } else {
                return tb_error(TB_ERR_FORMAT,
                                "%s: SetColor at byte %ld selects channel %u of %d", in->name,
                                op_pos, operand, h->ncolors);
            }
            x = 0;
            break;
        case TB__RLE_SKIP_PIXELS:
            x = x + operand > h->width ? h->width : x + operand;
            break;
        case TB__RLE_BYTE_DATA: {
            int64_t n = (int64_t)operand + 1;
            if ((st = tb__rle_check_span(d, op_pos, "ByteData", x, y, n)))
                return st;
            unsigned char *dst = d->planes[ch] + (size_t)y * (size_t)h->width + (size_t)x;
            if ((st = tb__rle_read(in, dst, (size_t)n, "ByteData pixels")))
                return st;
            if ((n & 1) && (st = tb__rle_read(in, b, 1, "the ByteData pad byte")))
                return st;
            if ((st = tb__rle_check_values(d, op_pos, ch, dst, (size_t)n)))
                return st;
            x += n;
            break;
        }
        case TB__RLE_RUN_DATA: {
            int64_t n = (int64_t)operand + 1;
            if ((st = tb__rle_check_span(d, op_pos, "RunData", x, y, n)))
                return st;
            if ((st = tb__rle_read(in, b, 2, "the RunData value")))
                return st;
            if ((st = tb__rle_check_values(d, op_pos, ch, b, 1)))
                return st;
            memset(d->planes[ch] + (size_t)y * (size_t)h->width + (size_t)x, b[0], (size_t)n);
            x += n;
            break;
        }
        case TB__RLE_EOF:
            return TB_OK;
        default:
            return tb_error(TB_ERR_FORMAT, "%s: unknown opcode 0x%02x at byte %ld", in->name,
                            inst[0], op_pos);
        }
    }
}

/* Builds the float image from the decoded byte planes. */
static tb_status tb__rle_to_image(const tb__rle_decode *d, const tb_image_read_options *opts,
                                  const char *name, tb_image **out)
{
    const tb__rle_header *h = d->h;
    tb_image_encoding enc = opts ? opts->encoding : TB_ENCODING_SRGB;
    int pseudo = h->ncmap == 3 && h->ncolors == 1;
    int ncol = pseudo ? 3 : h->ncolors;
    const char *rgb_names[] = {"R", "G", "B", "A"};
    const char *y_names[] = {"Y", "A"};
    const char *names[4];
    int nch = 0;
    for (int c = 0; c < ncol; c++)
        names[nch++] = ncol == 1 ? y_names[0] : rgb_names[c];
    if (h->alpha)
        names[nch++] = "A";

    tb_image *img = tb_image_create(h->width, h->height, nch, names);
    if (!img)
        return tb_error_context(TB_ERR_NOMEM, "%s", name);

    /* Lookup tables: code -> float, per output channel (colour maps applied). */
    float lut[4][256];
    for (int c = 0; c < ncol; c++) {
        for (int v = 0; v < 256; v++) {
            int code = v;
            if (h->ncmap > 0) {
                int entry = v < h->maplen ? v : 0; /* values were checked against maplen */
                code = h->cmap[(size_t)c * (size_t)h->maplen + (size_t)entry] >> 8;
            }
            lut[c][v] = tb_image_dequantize8((unsigned char)code, enc);
        }
    }
    if (h->alpha) /* alpha is coverage, never gamma-encoded */
        for (int v = 0; v < 256; v++)
            lut[ncol][v] = tb_image_dequantize8((unsigned char)v, TB_ENCODING_LINEAR);

    for (int r = 0; r < h->height; r++) {
        float *dst = tb_image_at(img, 0, h->height - 1 - r); /* file rows go bottom-up */
        size_t row = (size_t)r * (size_t)h->width;
        for (int x = 0; x < h->width; x++, dst += nch) {
            for (int c = 0; c < ncol; c++)
                dst[c] = lut[c][d->planes[pseudo ? 0 : c][row + (size_t)x]];
            if (h->alpha)
                dst[ncol] = lut[ncol][d->planes[h->ncolors][row + (size_t)x]];
        }
    }
    *out = img;
    return TB_OK;
}

tb_status tb_rle_read(FILE *f, const char *name, const tb_image_read_options *opts, tb_image **out)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "tb_rle_read: out is NULL");
    *out = NULL;
    if (!f)
        return tb_error(TB_ERR_ARG, "tb_rle_read: stream is NULL");
    if (!name)
        name = "(rle stream)";

    tb__rle_in in = {f, name, 0};
    tb__rle_header h;
    memset(&h, 0, sizeof h);
    char *comments = NULL;
    size_t ncomment = 0;
    tb__rle_decode d;
    memset(&d, 0, sizeof d);
    tb_image *img = NULL;

    tb_status st = tb__rle_read_header(&in, &h);
    if (!st && (h.flags & TB__RLE_COMMENT))
        st = tb__rle_read_comments(&in, &comments, &ncomment);
    if (st)
        goto done;

    /* Unwritten pixels: the background colour if the header gives one, else 0;
     * alpha 0 (transparent), as URT's rle_getrow clears them. */
    d.in = &in;
    d.h = &h;
    size_t npix = (size_t)h.width * (size_t)h.height;
    int nplanes = h.ncolors + (h.alpha ? 1 : 0);
    for (int c = 0; c < nplanes; c++) {
        int is_alpha = c == h.ncolors;
        d.planes[c] = malloc(npix);
        if (!d.planes[c]) {
            st = tb_error(TB_ERR_NOMEM, "%s: no memory for a %dx%d image", name, h.width,
                          h.height);
            goto done;
        }
        memset(d.planes[c], (!is_alpha && h.has_bg) ? h.bg[c] : 0, npix);
        d.limit[c] = (!is_alpha && h.ncmap > 0) ? h.maplen : 256;
    }
    if ((st = tb__rle_decode_ops(&d)))
        goto done;
    if ((st = tb__rle_to_image(&d, opts, name, &img)))
        goto done;
    if ((st = tb__rle_apply_comments(img, name, comments, ncomment)))
        goto done;
    *out = img;
    img = NULL;

done:
    tb_image_free(img);
    for (int c = 0; c < 4; c++)
        free(d.planes[c]);
    free(h.cmap);
    free(comments);
    return st;
}

/* ------------------------------------------------------------------ writing */

/* Output stream with a sticky error flag (checked once at the end). */
typedef struct tb__rle_out {
    FILE *f;
    int failed;
} tb__rle_out;

static void tb__rle_put(tb__rle_out *o, const void *p, size_t n)
{
    if (!o->failed && fwrite(p, 1, n, o->f) != n)
        o->failed = 1;
}

/* One instruction; the long form when the operand does not fit a byte. */
static void tb__rle_put_op(tb__rle_out *o, int op, unsigned operand)
{
    if (operand <= 255) {
        unsigned char b[2] = {(unsigned char)op, (unsigned char)operand};
        tb__rle_put(o, b, 2);
    } else {
        unsigned char b[4] = {(unsigned char)(op | TB__RLE_LONG), 0, (unsigned char)(operand & 0xff),
                              (unsigned char)(operand >> 8)};
        tb__rle_put(o, b, 4);
    }
}

static void tb__rle_put_literal(tb__rle_out *o, const unsigned char *v, int n)
{
    static const unsigned char pad = 0;
    if (n <= 0)
        return;
    tb__rle_put_op(o, TB__RLE_BYTE_DATA, (unsigned)(n - 1));
    tb__rle_put(o, v, (size_t)n);
    if (n & 1)
        tb__rle_put(o, &pad, 1);
}

/* One channel of one scanline: long runs as RunData, the rest as ByteData. */
static void tb__rle_put_row(tb__rle_out *o, const unsigned char *v, int w)
{
    int lit = 0; /* start of the pending literal */
    int i = 0;
    while (i < w) {
        int run = 1;
        while (i + run < w && v[i + run] == v[i])
            run++;
        if (run >= TB__RLE_MIN_RUN) {
            tb__rle_put_literal(o, v + lit, i - lit);
            tb__rle_put_op(o, TB__RLE_RUN_DATA, (unsigned)(run - 1));
            unsigned char word[2] = {v[i], 0};
            tb__rle_put(o, word, 2);
            lit = i + run;
        }
        i += run;
    }
    tb__rle_put_literal(o, v + lit, w - lit);
}

/* Chooses what to write: R,G,B if all present, else Y, else the (1..3)
 * channels that are not "A". Returns the count, or 0 if none fits. */
static int tb__rle_pick_channels(const tb_image *img, int idx[3])
{
    int r = tb_image_channel(img, "R"), g = tb_image_channel(img, "G"),
        b = tb_image_channel(img, "B");
    if (r >= 0 && g >= 0 && b >= 0) {
        idx[0] = r, idx[1] = g, idx[2] = b;
        return 3;
    }
    int y = tb_image_channel(img, "Y");
    if (y >= 0) {
        idx[0] = y;
        return 1;
    }
    int n = 0;
    for (int c = 0; c < img->channels; c++) {
        if (strcmp(img->names[c], "A") == 0)
            continue;
        if (n == 3)
            return 0;
        idx[n++] = c;
    }
    return n;
}

tb_status tb_rle_write(FILE *f, const char *name, const tb_image *img, const tb_image_write_options *opts)
{
    if (!name)
        name = "(rle stream)";
    if (!f || !img || !img->pixels || img->width <= 0 || img->height <= 0 || img->channels <= 0)
        return tb_error(TB_ERR_ARG, "%s: tb_rle_write needs a stream and a non-empty image", name);
    if (img->width > TB__RLE_WRITE_MAX_SIZE || img->height > TB__RLE_WRITE_MAX_SIZE)
        return tb_error(TB_ERR_UNSUPPORTED, "%s: %dx%d image; RLE holds at most %dx%d", name,
                        img->width, img->height, TB__RLE_WRITE_MAX_SIZE, TB__RLE_WRITE_MAX_SIZE);
    int idx[3];
    int ncolors = tb__rle_pick_channels(img, idx);
    if (ncolors == 0)
        return tb_error(TB_ERR_UNSUPPORTED,
                        "%s: RLE stores R,G,B or Y (or 1 to 3 unnamed channels) plus A; "
                        "this image has %d other channels",
                        name, img->channels);
    int alpha = tb_image_channel(img, "A");
    tb_image_encoding enc = opts ? opts->encoding : TB_ENCODING_SRGB;
    float scale = opts ? exp2f(opts->exposure) : 1.0f;

    /* Comments: one "key=value" (or bare "key" for an empty value) per attribute. */
    size_t clen = 0;
    for (int i = 0; i < img->nattrs; i++) {
        const char *k = img->attrs[i].key, *v = img->attrs[i].value;
        if (!k[0] || strchr(k, '='))
            return tb_error(TB_ERR_ARG,
                            "%s: attribute \"%s\" cannot be an RLE comment (empty or contains '=')",
                            name, k);
        clen += strlen(k) + (v[0] ? 1 + strlen(v) : 0) + 1;
        if (clen > 65535)
            return tb_error(TB_ERR_UNSUPPORTED,
                            "%s: attributes need more than the 65535 bytes RLE allows for comments",
                            name);
    }

    int w = img->width, h = img->height;
    unsigned char *row = malloc((size_t)w);
    if (!row)
        return tb_error(TB_ERR_NOMEM, "%s: no memory for a %d-pixel row", name, w);

    tb__rle_out o = {f, 0};
    unsigned char hdr[16] = {0x52, 0xCC, 0, 0, 0, 0, (unsigned char)(w & 0xff),
                             (unsigned char)(w >> 8), (unsigned char)(h & 0xff),
                             (unsigned char)(h >> 8),
                             (unsigned char)(TB__RLE_NO_BACKGROUND | (alpha >= 0 ? TB__RLE_ALPHA : 0) |
                                             (img->nattrs > 0 ? TB__RLE_COMMENT : 0)),
                             (unsigned char)ncolors, 8, 0, 0, 0 /* filler byte */};
    tb__rle_put(&o, hdr, sizeof hdr);

    if (img->nattrs > 0) {
        unsigned char len[2] = {(unsigned char)(clen & 0xff), (unsigned char)(clen >> 8)};
        tb__rle_put(&o, len, 2);
        for (int i = 0; i < img->nattrs; i++) {
            const char *k = img->attrs[i].key, *v = img->attrs[i].value;
            tb__rle_put(&o, k, strlen(k));
            if (v[0]) {
                tb__rle_put(&o, "=", 1);
                tb__rle_put(&o, v, strlen(v));
            }
            tb__rle_put(&o, "", 1);
        }
        if (clen & 1)
            tb__rle_put(&o, "", 1);
    }

    for (int r = 0; r < h && !o.failed; r++) {
        int y = h - 1 - r; /* the first scanline in the file is the bottom row */
        if (r > 0)
            tb__rle_put_op(&o, TB__RLE_SKIP_LINES, 1);
        if (alpha >= 0) { /* URT writes alpha first; any order is legal */
            for (int x = 0; x < w; x++)
                row[x] = tb_image_quantize8(tb_image_at(img, x, y)[alpha], TB_ENCODING_LINEAR);
            tb__rle_put_op(&o, TB__RLE_SET_COLOR, TB__RLE_ALPHA_CHANNEL);
            tb__rle_put_row(&o, row, w);
        }
        for (int c = 0; c < ncolors; c++) {
            for (int x = 0; x < w; x++)
                row[x] = tb_image_quantize8(tb_image_at(img, x, y)[idx[c]] * scale, enc);
            tb__rle_put_op(&o, TB__RLE_SET_COLOR, (unsigned)c);
            tb__rle_put_row(&o, row, w);
        }
    }
    tb__rle_put_op(&o, TB__RLE_EOF, 0);
    free(row);
    if (o.failed || fflush(f) != 0 || ferror(f))
        return tb_error(TB_ERR_IO, "%s: write failed", name);
    return TB_OK;
}
