/* OpenEXR through the library's C API (OpenEXRCore). We write one scanline
 * part, ZIP-compressed, HALF or FLOAT channels with any names, and the image's
 * attributes as EXR string attributes. We read the first part of scanline or
 * tiled files (the full-resolution level), HALF, FLOAT or UINT channels, into
 * floats, and every string attribute into the image's attributes.
 *
 * All I/O goes through our own read/write callbacks on a stdio stream, so a
 * write lands in tb_outfile's temporary file and memory (fmemopen) can be
 * read like a file. */
#include "util/image/image.h"

#include <errno.h>
#include <math.h>
#include <openexr.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>

#include "util/base/outfile.h"

/* The library reports details through a callback, not a return value; the
 * last message of this thread's current call is kept here. */
static _Thread_local char tb__exr_msg[512];

static void tb__exr_error_cb(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    (void)ctxt;
    snprintf(tb__exr_msg, sizeof tb__exr_msg, "%s", msg ? msg : exr_get_default_error_message(code));
}

static tb_status tb__exr_status(exr_result_t rv)
{
    switch (rv) {
    case EXR_ERR_OUT_OF_MEMORY: return TB_ERR_NOMEM;
    case EXR_ERR_FILE_ACCESS:
    case EXR_ERR_WRITE_IO: return TB_ERR_IO;
    case EXR_ERR_FEATURE_NOT_IMPLEMENTED: return TB_ERR_UNSUPPORTED;
    case EXR_ERR_INVALID_ARGUMENT:
    case EXR_ERR_ARGUMENT_OUT_OF_RANGE:
    case EXR_ERR_NAME_TOO_LONG: return TB_ERR_ARG;
    default: return TB_ERR_FORMAT;
    }
}

/* Error for a failed library call: "name: what: library message". */
static tb_status tb__exr_fail(exr_result_t rv, const char *name, const char *what)
{
    const char *detail = tb__exr_msg[0] ? tb__exr_msg : exr_get_default_error_message(rv);
    return tb_error(tb__exr_status(rv), "%s: %s: %s", name, what, detail);
}

/* ------------------------------------------------------------------ streams */

/* A stdio stream as seen by the library: offsets are relative to `base`. */
typedef struct tb__exr_stream {
    FILE *f;
    off_t base;      /* stream position where the EXR data starts */
    int64_t size;    /* readable bytes from `base`, -1 if unknown */
    uint64_t end;    /* one past the last byte written */
    int err;         /* errno of the first failed read/write/seek, or 0 */
} tb__exr_stream;

static int64_t tb__exr_read_fn(exr_const_context_t ctxt, void *user, void *buffer, uint64_t sz,
                               uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    tb__exr_stream *s = user;
    if (offset > (uint64_t)INT64_MAX - (uint64_t)s->base ||
        fseeko(s->f, s->base + (off_t)offset, SEEK_SET) != 0) {
        if (!s->err)
            s->err = errno ? errno : EINVAL;
        error_cb(ctxt, EXR_ERR_READ_IO, "cannot seek to byte %llu", (unsigned long long)offset);
        return -1;
    }
    size_t got = fread(buffer, 1, (size_t)sz, s->f);
    if (got < sz && ferror(s->f)) {
        if (!s->err)
            s->err = errno ? errno : EIO;
        error_cb(ctxt, EXR_ERR_READ_IO, "read failed: %s", strerror(s->err));
        return -1;
    }
    return (int64_t)got;
}

static int64_t tb__exr_size_fn(exr_const_context_t ctxt, void *user)
{
    (void)ctxt;
    return ((tb__exr_stream *)user)->size;
}

static int64_t tb__exr_write_fn(exr_const_context_t ctxt, void *user, const void *buffer, uint64_t sz,
                                uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    tb__exr_stream *s = user;
    errno = 0;
    if (offset > (uint64_t)INT64_MAX - (uint64_t)s->base - sz ||
        fseeko(s->f, s->base + (off_t)offset, SEEK_SET) != 0 || fwrite(buffer, 1, (size_t)sz, s->f) != sz) {
        if (!s->err)
            s->err = errno ? errno : EIO;
        error_cb(ctxt, EXR_ERR_WRITE_IO, "write failed: %s", strerror(s->err));
        return -1;
    }
    if (offset + sz > s->end)
        s->end = offset + sz;
    return (int64_t)sz;
}

/* ------------------------------------------------------------------ reading */

/* Exact conversion of an IEEE half (binary16) to float. */
static float tb__half_to_float(uint16_t h)
{
    uint32_t sign = (uint32_t)(h & 0x8000u) << 16, exp = (uint32_t)(h >> 10 & 0x1f), man = h & 0x3ffu;
    uint32_t u;
    if (exp == 0) {
        float f = (float)man * 0x1p-24f; /* zero or subnormal: man * 2^-24, exact */
        return sign ? -f : f;
    }
    if (exp == 31)
        u = sign | 0x7f800000u | man << 13; /* infinity or NaN (payload kept) */
    else
        u = sign | (exp + 112) << 23 | man << 13;
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* Order of channels in our image: R, G, B, Y, A first when present (EXR sorts
 * channels by name, which would put A first), then the rest in file order. */
static int tb__exr_rank(const char *name)
{
    static const char *const first[] = {"R", "G", "B", "Y", "A"};
    for (int i = 0; i < 5; i++)
        if (strcmp(name, first[i]) == 0)
            return i;
    return 5;
}

/* Converts one decoded chunk (planar, native type, one block per channel)
 * into the image at (x0, y0). */
static void tb__exr_store(tb_image *img, const exr_decode_pipeline_t *dec, const int *map, int x0, int y0)
{
    for (int c = 0; c < dec->channel_count; c++) {
        const exr_coding_channel_info_t *ch = &dec->channels[c];
        const uint8_t *src = ch->decode_to_ptr;
        for (int y = 0; y < ch->height; y++) {
            float *dst = tb_image_at(img, x0, y0 + y) + map[c];
            for (int x = 0; x < ch->width; x++, dst += img->channels) {
                if (ch->data_type == EXR_PIXEL_HALF) {
                    uint16_t h;
                    memcpy(&h, src, 2);
                    *dst = tb__half_to_float(h);
                    src += 2;
                } else if (ch->data_type == EXR_PIXEL_FLOAT) {
                    memcpy(dst, src, 4);
                    src += 4;
                } else {
                    uint32_t u;
                    memcpy(&u, src, 4);
                    *dst = (float)u;
                    src += 4;
                }
            }
        }
    }
}

/* Decodes the chunk described by `cinfo` into the image at (x0, y0). */
static tb_status tb__exr_decode_chunk(exr_context_t ctxt, const char *name, exr_decode_pipeline_t *dec,
                                      const exr_chunk_info_t *cinfo, tb_image *img, const int *map,
                                      int x0, int y0, uint8_t **buf, size_t *bufsize)
{
    exr_result_t rv = dec->channels ? exr_decoding_update(ctxt, 0, cinfo, dec)
                                    : exr_decoding_initialize(ctxt, 0, cinfo, dec);
    if (rv)
        return tb__exr_fail(rv, name, "cannot decode pixel data");
    if (dec->channel_count != img->channels)
        return tb_error(TB_ERR_FORMAT, "%s: chunk has %d channels, header %d", name, dec->channel_count,
                        img->channels);
    size_t need = 0;
    for (int c = 0; c < dec->channel_count; c++) {
        const exr_coding_channel_info_t *ch = &dec->channels[c];
        if (ch->width < 0 || ch->height < 0 || x0 + ch->width > img->width ||
            y0 + ch->height > img->height || (ch->bytes_per_element != 2 && ch->bytes_per_element != 4))
            return tb_error(TB_ERR_FORMAT, "%s: pixel chunk at (%d, %d) lies outside the data window",
                            name, x0, y0);
        need += (size_t)ch->width * (size_t)ch->height * (size_t)ch->bytes_per_element;
    }
    if (need > *bufsize) {
        uint8_t *nb = realloc(*buf, need);
        if (!nb)
            return tb_error(TB_ERR_NOMEM, "%s: out of memory decoding a chunk", name);
        *buf = nb;
        *bufsize = need;
    }
    uint8_t *p = *buf;
    for (int c = 0; c < dec->channel_count; c++) {
        exr_coding_channel_info_t *ch = &dec->channels[c];
        /* Native type, planar: the simplest unpacking path; we convert. */
        ch->user_data_type = ch->data_type;
        ch->user_bytes_per_element = ch->bytes_per_element;
        ch->user_pixel_stride = ch->bytes_per_element;
        ch->user_line_stride = ch->width * ch->bytes_per_element;
        ch->decode_to_ptr = p;
        p += (size_t)ch->width * (size_t)ch->height * (size_t)ch->bytes_per_element;
    }
    if (!dec->unpack_and_convert_fn && (rv = exr_decoding_choose_default_routines(ctxt, 0, dec)))
        return tb__exr_fail(rv, name, "cannot decode pixel data");
    if ((rv = exr_decoding_run(ctxt, 0, dec)))
        return tb__exr_fail(rv, name, "cannot decode pixel data");
    tb__exr_store(img, dec, map, x0, y0);
    return TB_OK;
}

/* No EXR compression packs pixels more than about 4000:1 (zlib's limit is
 * 1032:1; PIZ's Huffman run codes and DWA's zlib stages stay in the
 * thousands), so a header promising more raw bytes than this many times the
 * file's size comes from a damaged file, and is refused before a damaged
 * header can make us allocate gigabytes. */
#define TB__EXR_MAX_RATIO 65536.0

/* Reads part 0 of an open file into a new image (the body of tb_exr_read_stream). */
static tb_status tb__exr_read_part(exr_context_t ctxt, const char *name, int64_t file_size, tb_image **out)
{
    exr_result_t rv;
    exr_storage_t storage;
    if ((rv = exr_get_storage(ctxt, 0, &storage)))
        return tb__exr_fail(rv, name, "cannot read OpenEXR header");
    if (storage != EXR_STORAGE_SCANLINE && storage != EXR_STORAGE_TILED)
        return tb_error(TB_ERR_UNSUPPORTED, "%s: deep OpenEXR images are not supported", name);
    exr_attr_box2i_t dw;
    if ((rv = exr_get_data_window(ctxt, 0, &dw)))
        return tb__exr_fail(rv, name, "cannot read OpenEXR header");
    int64_t w = (int64_t)dw.max.x - dw.min.x + 1, h = (int64_t)dw.max.y - dw.min.y + 1;
    const exr_attr_chlist_t *chl;
    if ((rv = exr_get_channels(ctxt, 0, &chl)))
        return tb__exr_fail(rv, name, "cannot read OpenEXR channel list");
    int nch = chl->num_channels;
    if (w < 1 || h < 1 || w > INT32_MAX || h > INT32_MAX)
        return tb_error(TB_ERR_FORMAT, "%s: bad OpenEXR data window (%d, %d) - (%d, %d)", name, dw.min.x,
                        dw.min.y, dw.max.x, dw.max.y);
    if (nch < 1 || nch > TB_IMAGE_MAX_CHANNELS)
        return tb_error(TB_ERR_FORMAT, "%s: OpenEXR image with %d channels", name, nch);
    if (w > INT32_MAX / 4) /* the decoder's line stride is a 32-bit byte count */
        return tb_error(TB_ERR_UNSUPPORTED, "%s: OpenEXR image %lld pixels wide is too wide", name,
                        (long long)w);
    if ((size_t)w * (size_t)h > TB_IMAGE_MAX_SAMPLES / (size_t)nch)
        return tb_error(TB_ERR_FORMAT, "%s: OpenEXR image %lld x %lld x %d is too large", name,
                        (long long)w, (long long)h, nch);
    double raw = 0.0; /* bytes of pixel data the header promises */
    for (int c = 0; c < nch; c++)
        raw += (double)w * (double)h * (chl->entries[c].pixel_type == EXR_PIXEL_HALF ? 2.0 : 4.0);
    if (file_size > 0 && raw > TB__EXR_MAX_RATIO * (double)file_size)
        return tb_error(TB_ERR_FORMAT, "%s: OpenEXR header promises %lld x %lld pixels, far more than the "
                        "%lld bytes of the file can hold (damaged file?)", name, (long long)w,
                        (long long)h, (long long)file_size);

    /* map[file channel] = our channel: a stable sort by rank. */
    int *map = calloc((size_t)nch, sizeof *map);
    const char **names = calloc((size_t)nch, sizeof *names);
    if (!map || !names) {
        free(map);
        free(names);
        return tb_error(TB_ERR_NOMEM, "%s: out of memory", name);
    }
    tb_status st = TB_OK;
    int k = 0;
    for (int rank = 0; rank <= 5; rank++) {
        for (int c = 0; c < nch; c++) {
            const exr_attr_chlist_entry_t *e = &chl->entries[c];
            const char *cn = e->name.str ? e->name.str : "";
            if (tb__exr_rank(cn) != rank)
                continue;
            if (e->x_sampling != 1 || e->y_sampling != 1) {
                st = tb_error(TB_ERR_UNSUPPORTED, "%s: channel '%s' is subsampled (%d x %d), which is "
                              "not supported", name, cn, e->x_sampling, e->y_sampling);
            } else if (strlen(cn) >= TB_IMAGE_CHANNEL_NAME_MAX || !cn[0]) {
                st = tb_error(TB_ERR_UNSUPPORTED, "%s: channel name '%.40s' is empty or longer than %d "
                              "bytes", name, cn, TB_IMAGE_CHANNEL_NAME_MAX - 1);
            } else if (e->pixel_type != EXR_PIXEL_HALF && e->pixel_type != EXR_PIXEL_FLOAT &&
                       e->pixel_type != EXR_PIXEL_UINT) {
                st = tb_error(TB_ERR_FORMAT, "%s: channel '%s' has unknown pixel type %d", name, cn,
                              (int)e->pixel_type);
            }
            map[c] = k;
            names[k++] = cn;
        }
    }
    tb_image *img = NULL;
    if (!st && !(img = tb_image_create((int)w, (int)h, nch, names)))
        st = tb_error_context(TB_ERR_NOMEM, "%s", name);
    free(names);

    /* String attributes (the part's structural "name" and "type" are not ours). */
    int32_t nattr = 0;
    if (!st && (rv = exr_get_attribute_count(ctxt, 0, &nattr)))
        st = tb__exr_fail(rv, name, "cannot read OpenEXR attributes");
    for (int32_t i = 0; !st && i < nattr; i++) {
        const exr_attribute_t *a;
        if ((rv = exr_get_attribute_by_index(ctxt, 0, EXR_ATTR_LIST_FILE_ORDER, i, &a))) {
            st = tb__exr_fail(rv, name, "cannot read OpenEXR attributes");
            break;
        }
        if (a->type != EXR_ATTR_STRING || !a->string || strcmp(a->name, "name") == 0 ||
            strcmp(a->name, "type") == 0 || !a->name[0])
            continue;
        size_t len = a->string->length > 0 ? (size_t)a->string->length : 0;
        char *v = malloc(len + 1);
        if (!v) {
            st = tb_error(TB_ERR_NOMEM, "%s: out of memory", name);
            break;
        }
        if (len)
            memcpy(v, a->string->str, len);
        v[len] = '\0'; /* an embedded zero ends the value early; C strings cannot hold it */
        st = tb_image_set_attr(img, a->name, v);
        free(v);
    }

    exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
    uint8_t *buf = NULL;
    size_t bufsize = 0;
    if (!st && storage == EXR_STORAGE_SCANLINE) {
        int32_t lpc = 0;
        if ((rv = exr_get_scanlines_per_chunk(ctxt, 0, &lpc)) || lpc < 1)
            st = rv ? tb__exr_fail(rv, name, "cannot read OpenEXR header")
                    : tb_error(TB_ERR_FORMAT, "%s: bad scanlines per chunk", name);
        for (int64_t y = dw.min.y; !st && y <= dw.max.y; y += lpc) {
            exr_chunk_info_t cinfo;
            if ((rv = exr_read_scanline_chunk_info(ctxt, 0, (int)y, &cinfo))) {
                st = tb__exr_fail(rv, name, "cannot read pixel data");
                break;
            }
            int64_t y0 = (int64_t)cinfo.start_y - dw.min.y;
            if (y0 < 0 || y0 >= h) {
                st = tb_error(TB_ERR_FORMAT, "%s: scanline chunk for y = %d is out of range", name,
                              cinfo.start_y);
                break;
            }
            st = tb__exr_decode_chunk(ctxt, name, &dec, &cinfo, img, map, 0, (int)y0, &buf, &bufsize);
        }
    } else if (!st) {
        uint32_t tw, th;
        exr_tile_level_mode_t level;
        exr_tile_round_mode_t round;
        if ((rv = exr_get_tile_descriptor(ctxt, 0, &tw, &th, &level, &round)))
            st = tb__exr_fail(rv, name, "cannot read OpenEXR tile description");
        else if (tw < 1 || th < 1)
            st = tb_error(TB_ERR_FORMAT, "%s: bad tile size %u x %u", name, tw, th);
        /* Level (0, 0) is the full-resolution image in every level mode. */
        for (int64_t ty = 0; !st && ty * th < h; ty++) {
            for (int64_t tx = 0; !st && tx * tw < w; tx++) {
                exr_chunk_info_t cinfo;
                if ((rv = exr_read_tile_chunk_info(ctxt, 0, (int)tx, (int)ty, 0, 0, &cinfo)))
                    st = tb__exr_fail(rv, name, "cannot read pixel data");
                else
                    st = tb__exr_decode_chunk(ctxt, name, &dec, &cinfo, img, map, (int)(tx * tw),
                                              (int)(ty * th), &buf, &bufsize);
            }
        }
    }
    if (dec.channels)
        exr_decoding_destroy(ctxt, &dec);
    free(buf);
    free(map);
    if (st) {
        tb_image_free(img);
        return st;
    }
    *out = img;
    return TB_OK;
}

tb_status tb_exr_read_stream(FILE *f, const char *name, tb_image **out)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "tb_exr_read_stream: NULL output pointer");
    *out = NULL;
    if (!name)
        name = "(stream)";
    if (!f)
        return tb_error(TB_ERR_ARG, "%s: no stream to read", name);
    tb__exr_stream s = {.f = f, .base = ftello(f), .size = -1};
    if (s.base < 0)
        return tb_error(TB_ERR_ARG, "%s: OpenEXR needs a seekable stream", name);
    if (fseeko(f, 0, SEEK_END) == 0) {
        off_t end = ftello(f);
        if (end >= s.base)
            s.size = (int64_t)(end - s.base);
    }
    clearerr(f);
    if (s.size == 0)
        return tb_error(TB_ERR_FORMAT, "%s: empty file, not an OpenEXR image", name);

    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = tb__exr_error_cb;
    init.user_data = &s;
    init.read_fn = tb__exr_read_fn;
    init.size_fn = tb__exr_size_fn;
    /* A damaged chunk table is an error, not something to search around. */
    init.flags = EXR_CONTEXT_FLAG_DISABLE_CHUNK_RECONSTRUCTION;
    tb__exr_msg[0] = '\0';
    exr_context_t ctxt = NULL;
    exr_result_t rv = exr_start_read(&ctxt, name, &init);
    if (rv) {
        if (s.err)
            return tb_error(TB_ERR_IO, "%s: read failed: %s", name, strerror(s.err));
        return tb__exr_fail(rv == EXR_ERR_FILE_ACCESS ? EXR_ERR_FILE_BAD_HEADER : rv, name,
                            "not a readable OpenEXR file");
    }
    tb_status st = tb__exr_read_part(ctxt, name, s.size, out);
    if (st && s.err)
        st = tb_error(TB_ERR_IO, "%s: read failed: %s", name, strerror(s.err));
    exr_finish(&ctxt);
    return st;
}

tb_status tb_exr_read(const char *path, tb_image **out)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "tb_exr_read: NULL output pointer");
    *out = NULL;
    if (!path || !*path)
        return tb_error(TB_ERR_ARG, "tb_exr_read: empty file name");
    FILE *f = fopen(path, "rb");
    if (!f)
        return tb_error(errno == ENOENT ? TB_ERR_NOT_FOUND : TB_ERR_IO, "%s: cannot open: %s", path,
                        strerror(errno));
    tb_status st = tb_exr_read_stream(f, path, out);
    fclose(f);
    return st;
}

/* ------------------------------------------------------------------ writing */

/* Attributes the library manages itself (required ones) or that other EXR
 * readers expect with a non-string type: a string under these names would be
 * rejected or misread. */
static const char *const tb__exr_reserved[] = {
    "channels", "compression", "dataWindow", "displayWindow", "lineOrder", "pixelAspectRatio",
    "screenWindowCenter", "screenWindowWidth", "tiles", "name", "type", "version", "chunkCount",
    "maxSamplesPerPixel", "chromaticities", "whiteLuminance", "adoptedNeutral", "xDensity",
    "utcOffset", "longitude", "latitude", "altitude", "focus", "expTime", "aperture", "isoSpeed",
    "envmap", "keyCode", "timeCode", "framesPerSecond", "multiView", "worldToCamera", "worldToNDC",
    "deepImageState", "originalDataWindow", "dwaCompressionLevel", "preview",
};

/* Nonzero for colour channels, which exposure scales: R, G, B, Y, also as the
 * last component of a layered name ("diffuse.R"). Alpha, depth and other
 * data channels are left alone. */
static int tb__exr_is_color(const char *name)
{
    const char *dot = strrchr(name, '.');
    const char *last = dot ? dot + 1 : name;
    return strcmp(last, "R") == 0 || strcmp(last, "G") == 0 || strcmp(last, "B") == 0 ||
           strcmp(last, "Y") == 0;
}

/* Checks what the library would otherwise reject halfway through. */
static tb_status tb__exr_check(const char *name, const tb_image *img)
{
    if ((size_t)img->width * (size_t)img->channels > INT32_MAX / sizeof(float))
        return tb_error(TB_ERR_UNSUPPORTED, "%s: rows of %d x %d floats are too long for the OpenEXR "
                        "encoder", name, img->width, img->channels);
    for (int c = 0; c < img->channels; c++) {
        if (!img->names[c][0] || strnlen(img->names[c], TB_IMAGE_CHANNEL_NAME_MAX) >= TB_IMAGE_CHANNEL_NAME_MAX)
            return tb_error(TB_ERR_ARG, "%s: channel %d has an empty or unterminated name", name, c);
        for (int d = 0; d < c; d++)
            if (strcmp(img->names[c], img->names[d]) == 0)
                return tb_error(TB_ERR_ARG, "%s: two channels are called '%s'; OpenEXR channel names "
                                "must be unique", name, img->names[c]);
    }
    for (int i = 0; i < img->nattrs; i++) {
        const char *key = img->attrs[i].key;
        size_t n = strlen(key);
        if (n < 1 || n > 255)
            return tb_error(TB_ERR_ARG, "%s: attribute name '%.40s...' must have 1 to 255 bytes for "
                            "OpenEXR", name, key);
        if (strlen(img->attrs[i].value) > INT32_MAX / 2)
            return tb_error(TB_ERR_ARG, "%s: attribute '%s' is too long", name, key);
        for (size_t r = 0; r < sizeof tb__exr_reserved / sizeof *tb__exr_reserved; r++)
            if (strcmp(key, tb__exr_reserved[r]) == 0)
                return tb_error(TB_ERR_ARG, "%s: attribute '%s' is a standard OpenEXR attribute and "
                                "cannot be stored as a string", name, key);
    }
    return TB_OK;
}

/* The library's compressor of this part, wrapped by tb__exr_compress. */
typedef struct tb__exr_codec {
    exr_result_t (*compress)(exr_encode_pipeline_t *p);
} tb__exr_codec;

/* Compresses a chunk and stores it raw when compression saved nothing.
 * Readers take a chunk of exactly the raw size as stored uncompressed, but
 * OpenEXR 3.1's encoder keeps the compressed bytes when they are EQUAL in
 * size to the raw ones (it falls back only when they are larger), and such a
 * chunk reads back as garbage (tests/image/test_exr.c,
 * test_zip_chunk_as_long_as_raw). */
static exr_result_t tb__exr_compress(exr_encode_pipeline_t *p)
{
    const tb__exr_codec *codec = p->encoding_user_data;
    exr_result_t rv = codec->compress(p);
    if (rv != EXR_ERR_SUCCESS || p->compressed_buffer == p->packed_buffer || p->compressed_bytes < p->packed_bytes)
        return rv;
    if (!p->compressed_buffer || p->compressed_alloc_size < p->packed_bytes)
        return EXR_ERR_OUT_OF_MEMORY; /* the library sizes it for at least the raw bytes; never seen */
    memcpy(p->compressed_buffer, p->packed_buffer, p->packed_bytes);
    p->compressed_bytes = p->packed_bytes;
    return rv;
}

/* The body of tb_exr_write_stream once the context exists. */
static tb_status tb__exr_write_part(exr_context_t ctxt, const char *name, const tb_image *img, int half)
{
    exr_result_t rv;
    int part = 0;
    if ((rv = exr_add_part(ctxt, NULL, EXR_STORAGE_SCANLINE, &part)) ||
        (rv = exr_initialize_required_attr_simple(ctxt, part, img->width, img->height,
                                                  EXR_COMPRESSION_ZIP)))
        return tb__exr_fail(rv, name, "cannot set up the OpenEXR header");
    for (int c = 0; c < img->channels; c++) {
        exr_perceptual_treatment_t p =
            tb__exr_is_color(img->names[c]) ? EXR_PERCEPTUALLY_LOGARITHMIC : EXR_PERCEPTUALLY_LINEAR;
        if ((rv = exr_add_channel(ctxt, part, img->names[c], half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT, p,
                                  1, 1)))
            return tb__exr_fail(rv, name, "cannot add a channel");
    }
    for (int i = 0; i < img->nattrs; i++) {
        if (strlen(img->attrs[i].key) > 31 && (rv = exr_set_longname_support(ctxt, 1)))
            return tb__exr_fail(rv, name, "cannot enable long attribute names");
        if ((rv = exr_attr_set_string(ctxt, part, img->attrs[i].key, img->attrs[i].value)))
            return tb__exr_fail(rv, name, "cannot store an attribute");
    }
    if ((rv = exr_write_header(ctxt)))
        return tb__exr_fail(rv, name, "cannot write the OpenEXR header");

    int32_t lpc = 0;
    if ((rv = exr_get_scanlines_per_chunk(ctxt, part, &lpc)) || lpc < 1)
        return rv ? tb__exr_fail(rv, name, "cannot write pixel data")
                  : tb_error(TB_ERR_FORMAT, "%s: bad scanlines per chunk", name);
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    tb__exr_codec codec = {NULL};
    int initialized = 0;
    tb_status st = TB_OK;
    int32_t pixel_stride = img->channels * (int32_t)sizeof(float);
    for (int y = 0; !st && y < img->height; y += lpc) {
        exr_chunk_info_t cinfo;
        if ((rv = exr_write_scanline_chunk_info(ctxt, part, y, &cinfo))) {
            st = tb__exr_fail(rv, name, "cannot write pixel data");
            break;
        }
        rv = initialized ? exr_encoding_update(ctxt, part, &cinfo, &enc)
                         : exr_encoding_initialize(ctxt, part, &cinfo, &enc);
        if (rv) {
            st = tb__exr_fail(rv, name, "cannot encode pixel data");
            break;
        }
        initialized = 1;
        for (int c = 0; c < enc.channel_count; c++) {
            exr_coding_channel_info_t *ch = &enc.channels[c];
            int k = tb_image_channel(img, ch->channel_name);
            if (k < 0) {
                st = tb_error(TB_ERR_FORMAT, "%s: OpenEXR reported an unknown channel '%s'", name,
                              ch->channel_name);
                break;
            }
            /* The library converts our interleaved floats to the file's type. */
            ch->user_data_type = EXR_PIXEL_FLOAT;
            ch->user_bytes_per_element = (int16_t)sizeof(float);
            ch->user_pixel_stride = pixel_stride;
            ch->user_line_stride = pixel_stride * img->width;
            ch->encode_from_ptr = (const uint8_t *)(tb_image_at(img, 0, cinfo.start_y) + k);
        }
        if (st)
            break;
        if (!enc.convert_and_pack_fn && (rv = exr_encoding_choose_default_routines(ctxt, part, &enc))) {
            st = tb__exr_fail(rv, name, "cannot encode pixel data");
            break;
        }
        if (enc.compress_fn && enc.compress_fn != tb__exr_compress) {
            codec.compress = enc.compress_fn;
            enc.compress_fn = tb__exr_compress;
            enc.encoding_user_data = &codec;
        }
        if ((rv = exr_encoding_run(ctxt, part, &enc)))
            st = tb__exr_fail(rv, name, "cannot write pixel data");
    }
    if (initialized)
        exr_encoding_destroy(ctxt, &enc);
    return st;
}

tb_status tb_exr_write_stream(FILE *f, const char *name, const tb_image *img,
                              const tb_image_write_options *opts)
{
    if (!name)
        name = "(stream)";
    if (!f || !img || !img->pixels || img->width < 1 || img->height < 1 || img->channels < 1)
        return tb_error(TB_ERR_ARG, "%s: tb_exr_write_stream: no image or stream", name);
    static const tb_image_write_options defaults = {0};
    if (!opts)
        opts = &defaults;
    if (!isfinite(opts->exposure))
        return tb_error(TB_ERR_ARG, "%s: exposure must be a finite number of stops", name);
    tb_status st = tb__exr_check(name, img);
    if (st)
        return st;
    tb__exr_stream s = {.f = f, .base = ftello(f), .size = -1};
    if (s.base < 0)
        return tb_error(TB_ERR_ARG, "%s: OpenEXR needs a seekable stream", name);

    /* Exposure scales a copy, so the caller's image is never touched. */
    tb_image *scaled = NULL;
    if (opts->exposure != 0.0f) {
        if (!(scaled = tb_image_clone(img)))
            return tb_error_context(TB_ERR_NOMEM, "%s", name);
        float k = (float)exp2((double)opts->exposure);
        size_t npix = (size_t)img->width * (size_t)img->height;
        for (int c = 0; c < img->channels; c++)
            if (tb__exr_is_color(img->names[c]))
                for (size_t i = 0; i < npix; i++)
                    scaled->pixels[i * (size_t)img->channels + (size_t)c] *= k;
        img = scaled;
    }

    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = tb__exr_error_cb;
    init.user_data = &s;
    init.write_fn = tb__exr_write_fn;
    tb__exr_msg[0] = '\0';
    exr_context_t ctxt = NULL;
    exr_result_t rv = exr_start_write(&ctxt, name, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv) {
        st = tb__exr_fail(rv, name, "cannot start writing OpenEXR");
    } else {
        st = tb__exr_write_part(ctxt, name, img, opts->exr_half != 0);
        /* Finishing writes the chunk offset table; it must succeed too. */
        rv = exr_finish(&ctxt);
        if (!st && rv)
            st = tb__exr_fail(rv, name, "cannot finish the OpenEXR file");
    }
    if (s.err)
        st = tb_error(TB_ERR_IO, "%s: write failed: %s", name, strerror(s.err));
    if (!st && fseeko(f, s.base + (off_t)s.end, SEEK_SET) != 0)
        st = tb_error(TB_ERR_IO, "%s: seek failed: %s", name, strerror(errno));
    tb_image_free(scaled);
    return st;
}

tb_status tb_exr_write(const char *path, const tb_image *img, const tb_image_write_options *opts)
{
    tb_outfile of;
    tb_status st = tb_outfile_open(&of, path);
    if (st)
        return st;
    st = tb_exr_write_stream(of.fp, path, img, opts);
    if (st) {
        tb_outfile_abort(&of);
        return st;
    }
    return tb_outfile_commit(&of);
}
