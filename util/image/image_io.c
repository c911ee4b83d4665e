/* Reading and writing image files: the format is chosen by the file name's
 * extension, and every write goes through a temporary file that is renamed
 * over the final name only when the whole image was written. */
#include "util/image/image.h"

#include <errno.h>
#include <math.h>
#include <string.h>

#include "util/base/outfile.h"

/* ASCII lower case, so the test does not depend on the locale. */
static int tb__lower(int c) { return c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c; }

/* Nonzero if `s` ends with `suffix` (which is lower case), ignoring ASCII case. */
static int tb__ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    if (n < m)
        return 0;
    for (size_t i = 0; i < m; i++)
        if (tb__lower((unsigned char)s[n - m + i]) != suffix[i])
            return 0;
    return 1;
}

tb_image_format tb_image_format_from_path(const char *path)
{
    if (!path)
        return TB_IMAGE_UNKNOWN;
    /* The extension must follow a file name: "dir/.png" names no PNG. */
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    if (strlen(base) < 5)
        return TB_IMAGE_UNKNOWN;
    if (tb__ends_with(base, ".rle"))
        return TB_IMAGE_RLE;
    if (tb__ends_with(base, ".png"))
        return TB_IMAGE_PNG;
    if (tb__ends_with(base, ".pfm"))
        return TB_IMAGE_PFM;
    if (tb__ends_with(base, ".exr"))
        return TB_IMAGE_EXR;
    return TB_IMAGE_UNKNOWN;
}

const char *tb_image_format_name(tb_image_format fmt)
{
    switch (fmt) {
    case TB_IMAGE_RLE: return "Utah RLE";
    case TB_IMAGE_PNG: return "PNG";
    case TB_IMAGE_PFM: return "PFM";
    case TB_IMAGE_EXR: return "OpenEXR";
    case TB_IMAGE_UNKNOWN: break;
    }
    return "unknown";
}

static tb_status tb__unknown_format(const char *path)
{
    return tb_error(TB_ERR_ARG, "%s: unknown image format (the name must end in .rle, .png, .pfm or .exr)",
                    path);
}

tb_status tb_image_read(const char *path, const tb_image_read_options *opts, tb_image **out)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "tb_image_read: NULL output pointer");
    *out = NULL;
    if (!path || !*path)
        return tb_error(TB_ERR_ARG, "tb_image_read: empty file name");
    static const tb_image_read_options defaults = {0};
    if (!opts)
        opts = &defaults;
    tb_image_format fmt = tb_image_format_from_path(path);
    if (fmt == TB_IMAGE_UNKNOWN)
        return tb__unknown_format(path);
    if (fmt == TB_IMAGE_EXR)
        return tb_exr_read(path, out);
    FILE *f = fopen(path, "rb");
    if (!f)
        return tb_error(errno == ENOENT ? TB_ERR_NOT_FOUND : TB_ERR_IO, "%s: cannot open: %s", path,
                        strerror(errno));
    tb_status st = TB_ERR_ARG;
    switch (fmt) {
    case TB_IMAGE_RLE: st = tb_rle_read(f, path, opts, out); break;
    case TB_IMAGE_PNG: st = tb_png_read(f, path, opts, out); break;
    case TB_IMAGE_PFM: st = tb_pfm_read(f, path, out); break;
    case TB_IMAGE_EXR:
    case TB_IMAGE_UNKNOWN: break;
    }
    fclose(f);
    if (st != TB_OK && *out) { /* a reader must not hand back half an image */
        tb_image_free(*out);
        *out = NULL;
    }
    return st;
}

tb_status tb_image_write(const char *path, const tb_image *img, const tb_image_write_options *opts)
{
    if (!img || !img->pixels || img->width < 1 || img->height < 1 || img->channels < 1)
        return tb_error(TB_ERR_ARG, "tb_image_write: no image to write");
    if (!path || !*path)
        return tb_error(TB_ERR_ARG, "tb_image_write: empty file name");
    static const tb_image_write_options defaults = {0};
    if (!opts)
        opts = &defaults;
    if (!isfinite(opts->exposure))
        return tb_error(TB_ERR_ARG, "%s: exposure must be a finite number of stops", path);
    tb_image_format fmt = tb_image_format_from_path(path);
    if (fmt == TB_IMAGE_UNKNOWN)
        return tb__unknown_format(path);
    if (fmt == TB_IMAGE_EXR) /* it has a temporary file of its own */
        return tb_exr_write(path, img, opts);
    tb_outfile of;
    tb_status st = tb_outfile_open(&of, path);
    if (st)
        return st;
    switch (fmt) {
    case TB_IMAGE_RLE: st = tb_rle_write(of.fp, path, img, opts); break;
    case TB_IMAGE_PNG: st = tb_png_write(of.fp, path, img, opts); break;
    case TB_IMAGE_PFM: st = tb_pfm_write(of.fp, path, img, opts); break;
    case TB_IMAGE_EXR:
    case TB_IMAGE_UNKNOWN: break;
    }
    if (st) {
        tb_outfile_abort(&of);
        return st;
    }
    return tb_outfile_commit(&of);
}

tb_status tb_image_write_exposed(const char *path, tb_image *img, double exposure)
{
    tb_image_format fmt = tb_image_format_from_path(path);
    tb_image_write_options wo = {0};
    if (img && img->pixels && img->channels >= 3 && (fmt == TB_IMAGE_PNG || fmt == TB_IMAGE_RLE)) {
        if (isnan(exposure)) {
            double sum = 0.0;
            size_t npix = (size_t)img->width * (size_t)img->height;
            for (size_t k = 0; k < npix; k++) {
                const float *px = img->pixels + k * (size_t)img->channels;
                sum += 0.2126 * px[0] + 0.7152 * px[1] + 0.0722 * px[2];
            }
            double mean = npix ? sum / (double)npix : 0.0;
            exposure = mean > 0.0 ? log2(0.18 / mean) : 0.0;
        }
        wo.exposure = (float)exposure;
        char ex[64];
        snprintf(ex, sizeof ex, "%.6g", exposure);
        tb_status st = tb_image_set_attr(img, "exposure", ex);
        if (st)
            return st;
    }
    return tb_image_write(path, img, &wo);
}
