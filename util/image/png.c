/* PNG through libpng. Reading expands every colour type (grey, grey+alpha,
 * RGB, RGBA, palette, low bit depths, tRNS) to 8 or 16 bits per channel;
 * writing stores 1-4 channels at 8 or 16 bits. Colour channels go through the
 * sRGB curve unless the caller asks for linear values; alpha is always stored
 * linearly, as PNG requires. String attributes become tEXt chunks (iTXt when
 * the value is not plain ASCII).
 *
 * libpng reports errors by longjmp. Everything allocated while libpng runs is
 * owned by a state struct living in the caller's frame, and the function that
 * calls setjmp only reaches it through a pointer, so nothing is lost (or left
 * indeterminate) when libpng jumps back. */
#include "util/image/image.h"
#include "util/base/stream.h"

#include <errno.h>
#include <math.h>
#include <png.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>

/* Deflate cannot expand data more than 1032:1, so a PNG whose header promises
 * more than this many bytes of raw rows per file byte is lying; checking it
 * before allocating keeps a tiny malformed file from costing gigabytes. */
#define TB__PNG_MAX_INFLATE 1040

/* Everything libpng-related a read or write owns (see the comment above). */
typedef struct tb__png_state {
    png_structp png;
    png_infop info;
    const char *name;    /* file name for messages */
    char msg[256];       /* libpng's error message */
    unsigned char *data; /* raw rows (read) or one row (write) */
    png_bytep *rows;     /* row pointers into `data` (read) */
    png_textp text;      /* tEXt/iTXt records to write */
    char **strings;      /* converted keys/values owned by the state */
    int nstrings;
    tb_image *img;       /* image being read */
    size_t alloc_max;    /* largest block libpng may allocate while reading (0: no cap) */
} tb__png_state;

static void tb__png_error(png_structp png, png_const_charp msg)
{
    tb__png_state *s = png_get_error_ptr(png);
    snprintf(s->msg, sizeof s->msg, "%s", msg ? msg : "unknown libpng error");
    png_longjmp(png, 1);
}

static void tb__png_warning(png_structp png, png_const_charp msg)
{
    (void)png;
    (void)msg; /* warnings (bad ancillary chunk CRCs, ...) do not stop a read */
}

/* Copies `src` (Latin-1 when `latin1`, else already UTF-8) as a UTF-8 string
 * owned by the state; NULL when out of memory. */
static char *tb__png_string(tb__png_state *s, const char *src, size_t n, int latin1)
{
    char **list = realloc(s->strings, ((size_t)s->nstrings + 1) * sizeof *list);
    if (!list)
        return NULL;
    s->strings = list;
    char *d = malloc(2 * n + 1), *p = d;
    if (!d)
        return NULL;
    for (size_t i = 0; i < n; i++) {
        unsigned char c = (unsigned char)src[i];
        if (latin1 && c >= 0x80) {
            *p++ = (char)(0xc0 | c >> 6);
            *p++ = (char)(0x80 | (c & 0x3f));
        } else {
            *p++ = (char)c;
        }
    }
    *p = '\0';
    s->strings[s->nstrings++] = d;
    return d;
}

static void tb__png_state_free(tb__png_state *s, int writing)
{
    if (s->png) {
        if (writing)
            png_destroy_write_struct(&s->png, s->info ? &s->info : NULL);
        else
            png_destroy_read_struct(&s->png, s->info ? &s->info : NULL, NULL);
    }
    free(s->data);
    free(s->rows);
    free(s->text);
    for (int i = 0; i < s->nstrings; i++)
        free(s->strings[i]);
    free(s->strings);
    tb_image_free(s->img);
    s->img = NULL;
}

/* The part of a read that libpng may jump out of. */
/* Largest ancillary chunk we read (text, iCCP, ...): far above any real one. */
#define TB__PNG_CHUNK_MAX (16u << 20)

/* libpng's own blocks while reading are one row or one chunk. libpng 1.6
 * allocates a text chunk at whatever size its length field claims (up to
 * 2 GiB; png_set_chunk_malloc_max covers only compressed chunks), so a
 * damaged length is refused here instead (found by fuzz_png): no block may
 * exceed the bytes left in the file plus 1 MiB, and never less than 64 MiB
 * so that rows of very wide images still fit. */
static png_voidp tb__png_malloc(png_structp png, png_alloc_size_t size)
{
    const tb__png_state *s = png_get_mem_ptr(png);
    if (s && s->alloc_max && size > s->alloc_max)
        return NULL; /* libpng reports it: an error, or a warning and a skipped ancillary chunk */
    return malloc(size);
}

static void tb__png_free(png_structp png, png_voidp p)
{
    (void)png;
    free(p);
}

static tb_status tb__png_read_body(tb__png_state *s, FILE *f, const tb_image_read_options *opts,
                                   long long remaining)
{
    if (setjmp(png_jmpbuf(s->png))) {
        if (ferror(f))
            return tb_error(TB_ERR_IO, "%s: read failed: %s", s->name, strerror(errno));
        if (feof(f))
            return tb_error(TB_ERR_FORMAT, "%s: PNG file truncated (%s)", s->name, s->msg);
        return tb_error(TB_ERR_FORMAT, "%s: bad PNG file: %s", s->name, s->msg);
    }
    png_init_io(s->png, f);
    png_set_sig_bytes(s->png, 8);
    /* Ancillary chunks (text, ICC profiles) are read whole into memory, at
     * the size their length field claims: cap it, so a damaged length cannot
     * ask for gigabytes (found by fuzz_png). Pixel data is streamed and is
     * bounded separately below. */
    png_set_chunk_malloc_max(s->png, TB__PNG_CHUNK_MAX);
    png_read_info(s->png, s->info);

    png_uint_32 w, h;
    int depth, color, interlace;
    png_get_IHDR(s->png, s->info, &w, &h, &depth, &color, &interlace, NULL, NULL);
    /* Raw size as stored (one filter byte per row), before any expansion. */
    double raw = ((double)png_get_rowbytes(s->png, s->info) + 1.0) * (double)h;
    if (remaining >= 0 && raw > (double)TB__PNG_MAX_INFLATE * (double)remaining + 65536.0)
        return tb_error(TB_ERR_FORMAT, "%s: PNG header promises %u x %u pixels, far more than the "
                        "%lld bytes of the file can hold", s->name, (unsigned)w, (unsigned)h, remaining);

    if (color == PNG_COLOR_TYPE_PALETTE)
        png_set_palette_to_rgb(s->png);
    if (color == PNG_COLOR_TYPE_GRAY && depth < 8)
        png_set_expand_gray_1_2_4_to_8(s->png);
    if (png_get_valid(s->png, s->info, PNG_INFO_tRNS))
        png_set_tRNS_to_alpha(s->png);
    png_set_interlace_handling(s->png);
    png_read_update_info(s->png, s->info);

    int channels = png_get_channels(s->png, s->info);
    int bits = png_get_bit_depth(s->png, s->info);
    size_t rowbytes = png_get_rowbytes(s->png, s->info);
    if (channels < 1 || channels > 4 || (bits != 8 && bits != 16) ||
        rowbytes != (size_t)w * (size_t)channels * (size_t)(bits / 8))
        return tb_error(TB_ERR_FORMAT, "%s: unexpected PNG layout (%d channels, %d bits)", s->name,
                        channels, bits);
    if (w > INT32_MAX || h > INT32_MAX)
        return tb_error(TB_ERR_FORMAT, "%s: PNG image %u x %u is too large", s->name, (unsigned)w,
                        (unsigned)h);
    s->img = tb_image_create((int)w, (int)h, channels, NULL);
    if (!s->img)
        return tb_error_context(TB_ERR_NOMEM, "%s", s->name);
    s->data = malloc(rowbytes * h);
    s->rows = malloc(sizeof *s->rows * h);
    if (!s->data || !s->rows)
        return tb_error(TB_ERR_NOMEM, "%s: out of memory for a %u x %u PNG", s->name, (unsigned)w,
                        (unsigned)h);
    for (png_uint_32 y = 0; y < h; y++)
        s->rows[y] = s->data + (size_t)y * rowbytes;
    png_read_image(s->png, s->rows);
    png_read_end(s->png, s->info); /* text chunks may follow the pixels */

    png_textp text;
    int ntext = 0;
    png_get_text(s->png, s->info, &text, &ntext);
    for (int i = 0; i < ntext; i++) {
        int itxt = text[i].compression >= PNG_ITXT_COMPRESSION_NONE;
        size_t len = itxt ? text[i].itxt_length : text[i].text_length;
        const char *value = text[i].text ? text[i].text : "";
        char *k = tb__png_string(s, text[i].key, strlen(text[i].key), 1);
        char *v = k ? tb__png_string(s, value, strnlen(value, len), !itxt) : NULL;
        if (!v)
            return tb_error(TB_ERR_NOMEM, "%s: out of memory for text chunks", s->name);
        if (k[0] && tb_image_set_attr(s->img, k, v) != TB_OK)
            return tb_error_context(TB_ERR_NOMEM, "%s", s->name);
    }

    tb_image_encoding enc = opts ? opts->encoding : TB_ENCODING_SRGB;
    int has_alpha = channels == 2 || channels == 4;
    for (png_uint_32 y = 0; y < h; y++) {
        const unsigned char *src = s->rows[y];
        float *dst = tb_image_at(s->img, 0, (int)y);
        for (png_uint_32 x = 0; x < w; x++) {
            for (int c = 0; c < channels; c++, dst++) {
                /* Alpha is linear coverage in PNG, never sRGB-encoded. */
                tb_image_encoding e = has_alpha && c == channels - 1 ? TB_ENCODING_LINEAR : enc;
                if (bits == 8) {
                    *dst = tb_image_dequantize8(*src++, e);
                } else {
                    *dst = tb_image_dequantize16((unsigned short)(src[0] << 8 | src[1]), e);
                    src += 2;
                }
            }
        }
    }
    return TB_OK;
}

tb_status tb_png_read(FILE *f, const char *name, const tb_image_read_options *opts, tb_image **out)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "tb_png_read: NULL output pointer");
    *out = NULL;
    if (!name)
        name = "(stream)";
    if (!f)
        return tb_error(TB_ERR_ARG, "%s: no stream to read", name);
    unsigned char sig[8];
    size_t got = fread(sig, 1, sizeof sig, f);
    if (got == 0 && ferror(f))
        return tb_error(TB_ERR_IO, "%s: read failed: %s", name, strerror(errno));
    if (got < sizeof sig || png_sig_cmp(sig, 0, sizeof sig) != 0) {
        if (got > 0 && png_sig_cmp(sig, 0, got) == 0)
            return tb_error(TB_ERR_FORMAT, "%s: PNG file truncated in its signature", name);
        return tb_error(TB_ERR_FORMAT, "%s: not a PNG file (bad signature)", name);
    }
    long long remaining = tb_stream_remaining(f);

    tb__png_state s = {.name = name};
    size_t cap = (size_t)64 << 20;
    if (remaining >= 0 && (unsigned long long)remaining + (1u << 20) > cap)
        cap = (size_t)remaining + (1u << 20);
    s.alloc_max = remaining >= 0 ? cap : (size_t)256 << 20;
    s.png = png_create_read_struct_2(PNG_LIBPNG_VER_STRING, &s, tb__png_error, tb__png_warning, &s,
                                     tb__png_malloc, tb__png_free);
    if (s.png)
        s.info = png_create_info_struct(s.png);
    if (!s.png || !s.info) {
        tb__png_state_free(&s, 0);
        return tb_error(TB_ERR_NOMEM, "%s: out of memory for libpng", name);
    }
    tb_status st = tb__png_read_body(&s, f, opts, remaining);
    if (st == TB_OK) {
        *out = s.img;
        s.img = NULL;
    }
    tb__png_state_free(&s, 0);
    return st;
}

/* Nonzero if `key` is a valid PNG keyword in ASCII: 1-79 printable
 * characters, no leading, trailing or doubled spaces. */
static int tb__png_keyword_ok(const char *key)
{
    size_t n = strlen(key);
    if (n < 1 || n > 79 || key[0] == ' ' || key[n - 1] == ' ')
        return 0;
    for (size_t i = 0; i < n; i++) {
        if (key[i] < 32 || key[i] > 126)
            return 0;
        if (key[i] == ' ' && key[i + 1] == ' ')
            return 0;
    }
    return 1;
}

static int tb__png_ascii(const char *s)
{
    for (; *s; s++)
        if ((unsigned char)*s >= 0x80)
            return 0;
    return 1;
}

/* The part of a write that libpng may jump out of. */
static tb_status tb__png_write_body(tb__png_state *s, FILE *f, const tb_image *img, int bits,
                                    tb_image_encoding enc, float scale)
{
    if (setjmp(png_jmpbuf(s->png))) {
        if (ferror(f))
            return tb_error(TB_ERR_IO, "%s: write failed: %s", s->name, strerror(errno));
        return tb_error(TB_ERR_FORMAT, "%s: libpng cannot write this image: %s", s->name, s->msg);
    }
    static const int color_types[] = {PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                                      PNG_COLOR_TYPE_RGB_ALPHA};
    int channels = img->channels;
    png_init_io(s->png, f);
    png_set_IHDR(s->png, s->info, (png_uint_32)img->width, (png_uint_32)img->height, bits,
                 color_types[channels - 1], PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    /* Tell other readers how the integers are encoded. */
    if (enc == TB_ENCODING_SRGB)
        png_set_sRGB(s->png, s->info, PNG_sRGB_INTENT_PERCEPTUAL);
    else
        png_set_gAMA(s->png, s->info, 1.0);
    if (img->nattrs > 0)
        png_set_text(s->png, s->info, s->text, img->nattrs);
    png_write_info(s->png, s->info);

    int has_alpha = channels == 2 || channels == 4;
    for (int y = 0; y < img->height; y++) {
        const float *src = tb_image_at(img, 0, y);
        unsigned char *dst = s->data;
        for (int x = 0; x < img->width; x++) {
            for (int c = 0; c < channels; c++) {
                int alpha = has_alpha && c == channels - 1;
                float v = *src++;
                if (!alpha && scale != 1.0f)
                    v *= scale;
                tb_image_encoding e = alpha ? TB_ENCODING_LINEAR : enc;
                if (bits == 8) {
                    *dst++ = tb_image_quantize8(v, e);
                } else {
                    unsigned short q = tb_image_quantize16(v, e);
                    *dst++ = (unsigned char)(q >> 8);
                    *dst++ = (unsigned char)(q & 0xff);
                }
            }
        }
        png_write_row(s->png, s->data);
    }
    png_write_end(s->png, s->info);
    return TB_OK;
}

tb_status tb_png_write(FILE *f, const char *name, const tb_image *img, const tb_image_write_options *opts)
{
    if (!name)
        name = "(stream)";
    if (!f || !img || !img->pixels)
        return tb_error(TB_ERR_ARG, "%s: tb_png_write: NULL argument", name);
    if (img->channels < 1 || img->channels > 4)
        return tb_error(TB_ERR_UNSUPPORTED, "%s: PNG stores 1 to 4 channels; this image has %d", name,
                        img->channels);
    static const tb_image_write_options defaults = {0};
    if (!opts)
        opts = &defaults;
    int bits = opts->png_bits ? opts->png_bits : 8;
    if (bits != 8 && bits != 16)
        return tb_error(TB_ERR_ARG, "%s: PNG bit depth must be 8 or 16, not %d", name, opts->png_bits);
    if (opts->encoding != TB_ENCODING_SRGB && opts->encoding != TB_ENCODING_LINEAR)
        return tb_error(TB_ERR_ARG, "%s: unknown PNG encoding %d", name, (int)opts->encoding);
    if (!isfinite(opts->exposure))
        return tb_error(TB_ERR_ARG, "%s: exposure must be a finite number of stops", name);
    float scale = (float)exp2((double)opts->exposure);

    tb__png_state s = {.name = name};
    tb_status st = TB_OK;
    if (img->nattrs > 0) {
        s.text = calloc((size_t)img->nattrs, sizeof *s.text);
        if (!s.text) {
            tb__png_state_free(&s, 1);
            return tb_error(TB_ERR_NOMEM, "%s: out of memory", name);
        }
    }
    for (int i = 0; i < img->nattrs; i++) {
        const char *key = img->attrs[i].key, *value = img->attrs[i].value;
        if (!tb__png_keyword_ok(key)) {
            tb__png_state_free(&s, 1);
            return tb_error(TB_ERR_ARG,
                            "%s: attribute key '%s' cannot be a PNG text keyword (1-79 printable ASCII "
                            "characters, no leading, trailing or double spaces)", name, key);
        }
        s.text[i].key = (png_charp)key;
        s.text[i].text = (png_charp)value;
        if (tb__png_ascii(value)) {
            s.text[i].compression = PNG_TEXT_COMPRESSION_NONE;
            s.text[i].text_length = strlen(value);
        } else { /* UTF-8: tEXt would read it back as Latin-1 */
            s.text[i].compression = PNG_ITXT_COMPRESSION_NONE;
            s.text[i].itxt_length = strlen(value);
            s.text[i].lang = "";
            s.text[i].lang_key = "";
        }
    }
    s.data = malloc((size_t)img->width * (size_t)img->channels * (size_t)(bits / 8));
    s.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &s, tb__png_error, tb__png_warning);
    if (s.png)
        s.info = png_create_info_struct(s.png);
    if (!s.data || !s.png || !s.info)
        st = tb_error(TB_ERR_NOMEM, "%s: out of memory for libpng", name);
    else
        st = tb__png_write_body(&s, f, img, bits, opts->encoding, scale);
    tb__png_state_free(&s, 1);
    return st;
}
