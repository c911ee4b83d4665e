/* Float image buffer and the readers/writers of every image format Testbed
 * speaks: Utah RLE, PNG, PFM and OpenEXR. Pixels are stored as linear values;
 * 8- and 16-bit formats are decoded from / encoded to the sRGB transfer curve
 * unless the caller asks for raw values. */
#ifndef TB_UTIL_IMAGE_IMAGE_H
#define TB_UTIL_IMAGE_IMAGE_H

#include <stddef.h>
#include <stdio.h>
#include "util/base/error.h"

/* Longest channel name, including the terminating zero. */
#define TB_IMAGE_CHANNEL_NAME_MAX 32

/* Most channels an image may have (a guard against absurd file headers). */
#define TB_IMAGE_MAX_CHANNELS 1024

/* Most floats (width * height * channels) an image may hold: 8 GiB of pixels.
 * Readers reject larger headers before allocating anything. */
#define TB_IMAGE_MAX_SAMPLES ((size_t)1 << 31)

/* One string attribute (provenance, comments, format-specific keys). */
typedef struct tb_image_attr {
    char *key;
    char *value;
} tb_image_attr;

/* A width x height image with `channels` interleaved float channels. */
typedef struct tb_image {
    int width, height;
    int channels;      /* number of interleaved channels per pixel (>= 1) */
    char (*names)[TB_IMAGE_CHANNEL_NAME_MAX]; /* channel names: "R","G","B","A","Y" or any other */
    float *pixels;     /* width*height*channels floats, row 0 at the TOP, then left to right */
    tb_image_attr *attrs; /* string attributes, in insertion order */
    int nattrs;
} tb_image;

/* File formats, chosen by file name extension. */
typedef enum tb_image_format {
    TB_IMAGE_UNKNOWN = 0,
    TB_IMAGE_RLE,  /* Utah Raster Toolkit RLE (.rle) */
    TB_IMAGE_PNG,  /* PNG (.png) */
    TB_IMAGE_PFM,  /* Portable Float Map (.pfm) */
    TB_IMAGE_EXR,  /* OpenEXR (.exr) */
} tb_image_format;

/* How pixel values map to and from integer formats (PNG, RLE). */
typedef enum tb_image_encoding {
    TB_ENCODING_SRGB = 0, /* default: integers hold sRGB-encoded values, floats are linear */
    TB_ENCODING_LINEAR,   /* integers hold linear values scaled to [0, max] */
} tb_image_encoding;

/* Options for tb_image_write(); a zeroed struct means the defaults. */
typedef struct tb_image_write_options {
    float exposure;              /* stops: values are multiplied by 2^exposure before writing */
    tb_image_encoding encoding;  /* for PNG and RLE */
    int png_bits;                /* 8 (default) or 16 */
    int exr_half;                /* nonzero: EXR channels as half floats (default float) */
} tb_image_write_options;

/* Options for tb_image_read(); a zeroed struct means the defaults. */
typedef struct tb_image_read_options {
    tb_image_encoding encoding;  /* for PNG and RLE */
} tb_image_read_options;

/* A zero-filled image; `names` may be NULL for the defaults by channel count
 * (1: Y; 2: Y,A; 3: R,G,B; 4: R,G,B,A; more: R,G,B,A,C4,C5...). NULL on failure
 * (see tb_last_error()). */
tb_image *tb_image_create(int width, int height, int channels, const char *const *names);

/* A deep copy of `img`, or NULL when out of memory. */
tb_image *tb_image_clone(const tb_image *img);

/* Frees `img` and everything it owns; NULL is allowed. */
void tb_image_free(tb_image *img);

/* Pointer to the first channel of pixel (x, y), y = 0 at the top. */
static inline float *tb_image_at(const tb_image *img, int x, int y)
{
    return img->pixels + ((size_t)y * (size_t)img->width + (size_t)x) * (size_t)img->channels;
}

/* Index of the channel called `name`, or -1. */
int tb_image_channel(const tb_image *img, const char *name);

/* Sets (or replaces) string attribute `key`. */
tb_status tb_image_set_attr(tb_image *img, const char *key, const char *value);

/* Value of attribute `key`, or NULL. */
const char *tb_image_get_attr(const tb_image *img, const char *key);

/* Format implied by the extension of `path` (case-insensitive), or TB_IMAGE_UNKNOWN. */
tb_image_format tb_image_format_from_path(const char *path);

/* Short display name of a format ("PNG", "OpenEXR", ...; "unknown"). */
const char *tb_image_format_name(tb_image_format fmt);

/* Reads `path` in the format its extension names; `opts` may be NULL. */
tb_status tb_image_read(const char *path, const tb_image_read_options *opts, tb_image **out);

/* Writes `img` to `path` in the format its extension names, through a temporary
 * file renamed on success (a failed write leaves no file behind); `opts` may be NULL. */
tb_status tb_image_write(const char *path, const tb_image *img, const tb_image_write_options *opts);

/* Writes a rendered image as tb_image_write does; for the display formats
 * (PNG, RLE) it first scales by 2^exposure stops, NAN meaning automatic (the
 * mean Rec. 709 luminance to 0.18), and records the stops used as the
 * attribute "exposure". HDR formats (PFM, EXR) are written as they are. */
tb_status tb_image_write_exposed(const char *path, tb_image *img, double exposure);

/* Per-format readers from an open stream; `name` is used in error messages.
 * Every malformed or truncated input returns TB_ERR_FORMAT with a message. */
tb_status tb_rle_read(FILE *f, const char *name, const tb_image_read_options *opts, tb_image **out);
tb_status tb_png_read(FILE *f, const char *name, const tb_image_read_options *opts, tb_image **out);
tb_status tb_pfm_read(FILE *f, const char *name, tb_image **out);
/* OpenEXR from a file (by path; the stream form follows). */
tb_status tb_exr_read(const char *path, tb_image **out);
/* OpenEXR from a seekable stream (a file, or fmemopen() memory), starting at
 * its current position. */
tb_status tb_exr_read_stream(FILE *f, const char *name, tb_image **out);

/* Per-format writers to an open stream (tb_image_write adds the temporary-file step). */
tb_status tb_rle_write(FILE *f, const char *name, const tb_image *img, const tb_image_write_options *opts);
tb_status tb_png_write(FILE *f, const char *name, const tb_image *img, const tb_image_write_options *opts);
tb_status tb_pfm_write(FILE *f, const char *name, const tb_image *img, const tb_image_write_options *opts);
/* OpenEXR to `path`, through a temporary file of its own (all or nothing). */
tb_status tb_exr_write(const char *path, const tb_image *img, const tb_image_write_options *opts);
/* OpenEXR to a seekable stream at its current position (the chunk offset table
 * is filled in last); tb_exr_write() wraps this in a temporary file. */
tb_status tb_exr_write_stream(FILE *f, const char *name, const tb_image *img,
                              const tb_image_write_options *opts);

/* Linear float -> 8-bit integer through `enc`, clamped and rounded to nearest. */
unsigned char tb_image_quantize8(float v, tb_image_encoding enc);

/* 8-bit integer -> linear float through `enc` (exact inverse of tb_image_quantize8 on integers). */
float tb_image_dequantize8(unsigned char v, tb_image_encoding enc);

/* Linear float -> 16-bit integer through `enc`, clamped and rounded to nearest. */
unsigned short tb_image_quantize16(float v, tb_image_encoding enc);

/* 16-bit integer -> linear float through `enc` (exact inverse of tb_image_quantize16 on integers). */
float tb_image_dequantize16(unsigned short v, tb_image_encoding enc);

#endif
