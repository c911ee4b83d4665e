/* The float image buffer: construction, channel names, string attributes and
 * the integer quantisation shared by the 8- and 16-bit formats. Reading and
 * writing files by extension lives in image_io.c. */
#include "util/image/image.h"
#include "util/base/str.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "util/color/srgb.h"

/* Default name of channel `i` of an image with `n` channels (see image.h). */
static void tb__default_name(char *dst, int i, int n)
{
    static const char *const rgba[] = {"R", "G", "B", "A"};
    if (n == 1)
        snprintf(dst, TB_IMAGE_CHANNEL_NAME_MAX, "Y");
    else if (n == 2)
        snprintf(dst, TB_IMAGE_CHANNEL_NAME_MAX, "%s", i == 0 ? "Y" : "A");
    else if (i < 4)
        snprintf(dst, TB_IMAGE_CHANNEL_NAME_MAX, "%s", rgba[i]);
    else
        snprintf(dst, TB_IMAGE_CHANNEL_NAME_MAX, "C%d", i);
}

tb_image *tb_image_create(int width, int height, int channels, const char *const *names)
{
    if (width < 1 || height < 1)
        return tb_error(TB_ERR_ARG, "image size %d x %d: both must be at least 1", width, height), NULL;
    if (channels < 1 || channels > TB_IMAGE_MAX_CHANNELS)
        return tb_error(TB_ERR_ARG, "image with %d channels: must be 1 to %d", channels,
                        TB_IMAGE_MAX_CHANNELS), NULL;
    /* width, height <= INT_MAX and channels <= 1024, so the product fits in
     * 64 bits; compare it with the limit before multiplying by sizeof(float). */
    size_t samples = (size_t)width * (size_t)height;
    if (samples > TB_IMAGE_MAX_SAMPLES / (size_t)channels)
        return tb_error(TB_ERR_ARG, "image %d x %d x %d is too large (more than %zu values)", width,
                        height, channels, TB_IMAGE_MAX_SAMPLES), NULL;
    samples *= (size_t)channels;
    if (names) {
        for (int i = 0; i < channels; i++) {
            if (!names[i] || !names[i][0])
                return tb_error(TB_ERR_ARG, "channel %d has no name", i), NULL;
            if (strlen(names[i]) >= TB_IMAGE_CHANNEL_NAME_MAX)
                return tb_error(TB_ERR_ARG, "channel name '%.40s...' is longer than %d bytes", names[i],
                                TB_IMAGE_CHANNEL_NAME_MAX - 1), NULL;
        }
    }
    tb_image *img = calloc(1, sizeof *img);
    if (!img)
        return tb_error(TB_ERR_NOMEM, "out of memory for an image"), NULL;
    img->width = width;
    img->height = height;
    img->channels = channels;
    img->names = calloc((size_t)channels, sizeof *img->names);
    img->pixels = calloc(samples, sizeof(float));
    if (!img->names || !img->pixels) {
        tb_image_free(img);
        return tb_error(TB_ERR_NOMEM, "out of memory for a %d x %d x %d image", width, height, channels),
               NULL;
    }
    for (int i = 0; i < channels; i++) {
        if (names)
            memcpy(img->names[i], names[i], strlen(names[i]) + 1);
        else
            tb__default_name(img->names[i], i, channels);
    }
    return img;
}

tb_image *tb_image_clone(const tb_image *img)
{
    if (!img)
        return tb_error(TB_ERR_ARG, "tb_image_clone: NULL image"), NULL;
    tb_image *c = tb_image_create(img->width, img->height, img->channels, NULL);
    if (!c)
        return NULL;
    memcpy(c->names, img->names, (size_t)img->channels * sizeof *img->names);
    memcpy(c->pixels, img->pixels,
           (size_t)img->width * (size_t)img->height * (size_t)img->channels * sizeof(float));
    for (int i = 0; i < img->nattrs; i++) {
        if (tb_image_set_attr(c, img->attrs[i].key, img->attrs[i].value) != TB_OK) {
            tb_image_free(c);
            return NULL;
        }
    }
    return c;
}

void tb_image_free(tb_image *img)
{
    if (!img)
        return;
    for (int i = 0; i < img->nattrs; i++) {
        free(img->attrs[i].key);
        free(img->attrs[i].value);
    }
    free(img->attrs);
    free(img->names);
    free(img->pixels);
    free(img);
}

int tb_image_channel(const tb_image *img, const char *name)
{
    if (!img || !name)
        return -1;
    for (int i = 0; i < img->channels; i++)
        if (strcmp(img->names[i], name) == 0)
            return i;
    return -1;
}

tb_status tb_image_set_attr(tb_image *img, const char *key, const char *value)
{
    if (!img || !key || !value)
        return tb_error(TB_ERR_ARG, "tb_image_set_attr: NULL argument");
    if (!key[0])
        return tb_error(TB_ERR_ARG, "image attribute with an empty key");
    char *v = tb_strdup(value);
    if (!v)
        return tb_error(TB_ERR_NOMEM, "out of memory for attribute '%s'", key);
    for (int i = 0; i < img->nattrs; i++) {
        if (strcmp(img->attrs[i].key, key) == 0) {
            free(img->attrs[i].value);
            img->attrs[i].value = v;
            return TB_OK;
        }
    }
    char *k = tb_strdup(key);
    tb_image_attr *a = realloc(img->attrs, ((size_t)img->nattrs + 1) * sizeof *a);
    if (!k || !a) {
        free(k);
        free(v);
        if (a)
            img->attrs = a;
        return tb_error(TB_ERR_NOMEM, "out of memory for attribute '%s'", key);
    }
    img->attrs = a;
    img->attrs[img->nattrs].key = k;
    img->attrs[img->nattrs].value = v;
    img->nattrs++;
    return TB_OK;
}

const char *tb_image_get_attr(const tb_image *img, const char *key)
{
    if (!img || !key)
        return NULL;
    for (int i = 0; i < img->nattrs; i++)
        if (strcmp(img->attrs[i].key, key) == 0)
            return img->attrs[i].value;
    return NULL;
}

/* Encoded value in [0, 1] of linear `v` (NaN and negatives -> 0, above 1 -> 1). */
static double tb__encode(float v, tb_image_encoding enc)
{
    if (enc == TB_ENCODING_SRGB)
        return tb_srgb_encode(v);
    if (!(v > 0.0f))
        return 0.0;
    return v >= 1.0f ? 1.0 : (double)v;
}

unsigned char tb_image_quantize8(float v, tb_image_encoding enc)
{
    return (unsigned char)floor(tb__encode(v, enc) * 255.0 + 0.5);
}

float tb_image_dequantize8(unsigned char v, tb_image_encoding enc)
{
    float e = (float)v / 255.0f;
    return enc == TB_ENCODING_SRGB ? tb_srgb_decode(e) : e;
}

unsigned short tb_image_quantize16(float v, tb_image_encoding enc)
{
    return (unsigned short)floor(tb__encode(v, enc) * 65535.0 + 0.5);
}

float tb_image_dequantize16(unsigned short v, tb_image_encoding enc)
{
    float e = (float)v / 65535.0f;
    return enc == TB_ENCODING_SRGB ? tb_srgb_decode(e) : e;
}
