/* `testbed compare A B`: error metrics of image A against reference B, as a
 * table or JSON, and optionally a false-colour error image. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "util/image/compare.h"

/* A JSON number; NaN and +-Inf are not JSON, so they become null. */
static void tb__json_num(FILE *out, double v)
{
    if (isfinite(v))
        fprintf(out, "%.17g", v);
    else
        fputs("null", out);
}

static void tb__json_str(FILE *out, const char *s)
{
    putc('"', out);
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if (*p == '"' || *p == '\\')
            fprintf(out, "\\%c", *p);
        else if (*p < 0x20)
            fprintf(out, "\\u%04x", *p);
        else
            putc(*p, out);
    }
    putc('"', out);
}

static void tb__json_stats(FILE *out, const tb_compare_stats *s)
{
    fputs("\"mse\": ", out);
    tb__json_num(out, s->mse);
    fputs(", \"rmse\": ", out);
    tb__json_num(out, s->rmse);
    fputs(", \"relmse\": ", out);
    tb__json_num(out, s->relmse);
    fputs(", \"psnr\": ", out);
    tb__json_num(out, s->psnr);
    fputs(", \"ssim\": ", out);
    tb__json_num(out, s->ssim);
    fputs(", \"max_abs\": ", out);
    tb__json_num(out, s->max_abs);
    fprintf(out, ", \"max_x\": %d, \"max_y\": %d", s->max_x, s->max_y);
}

static void tb__print_json(FILE *out, const char *pa, const char *pb, const tb_compare_result *r,
                           const char *err_path, double err_scale)
{
    fputs("{\n  \"a\": ", out);
    tb__json_str(out, pa);
    fputs(",\n  \"b\": ", out);
    tb__json_str(out, pb);
    fprintf(out, ",\n  \"width\": %d,\n  \"height\": %d,\n  \"peak\": ", r->width, r->height);
    tb__json_num(out, r->peak);
    fputs(",\n  \"relmse_eps\": ", out);
    tb__json_num(out, TB_COMPARE_RELMSE_EPS);
    fputs(",\n  \"channels\": [\n", out);
    for (int c = 0; c < r->nchannels; c++) {
        fputs("    {\"name\": ", out);
        tb__json_str(out, r->names[c]);
        fputs(", ", out);
        tb__json_stats(out, &r->channel[c]);
        fprintf(out, "}%s\n", c + 1 < r->nchannels ? "," : "");
    }
    fputs("  ],\n  \"all\": {", out);
    tb__json_stats(out, &r->all);
    fputs(", \"max_channel\": ", out);
    if (r->max_channel >= 0)
        tb__json_str(out, r->names[r->max_channel]);
    else
        fputs("null", out);
    fprintf(out,
            "},\n  \"pixels\": %lld,\n  \"valid_pixels\": %lld,\n  \"nonfinite_a\": %lld,\n"
            "  \"nonfinite_b\": %lld,\n  \"ssim_windows\": %lld,\n  \"error_image\": ",
            r->pixels, r->valid_pixels, r->nonfinite_a, r->nonfinite_b, r->ssim_windows);
    if (err_path) {
        fputs("{\"path\": ", out);
        tb__json_str(out, err_path);
        fputs(", \"scale\": ", out);
        tb__json_num(out, err_scale);
        fputs("}", out);
    } else {
        fputs("null", out);
    }
    fputs("\n}\n", out);
}

/* A table cell: %12.6g, or inf / n/a. */
static void tb__cell(FILE *out, double v)
{
    if (isnan(v))
        fprintf(out, " %12s", "n/a");
    else
        fprintf(out, " %12.6g", v);
}

static void tb__row(FILE *out, const char *name, const tb_compare_stats *s)
{
    fprintf(out, "%-8s", name);
    tb__cell(out, s->mse);
    tb__cell(out, s->rmse);
    tb__cell(out, s->relmse);
    tb__cell(out, s->psnr);
    tb__cell(out, s->ssim);
    tb__cell(out, s->max_abs);
    if (s->max_x >= 0)
        fprintf(out, "  (%d, %d)\n", s->max_x, s->max_y);
    else
        fprintf(out, "  -\n");
}

static void tb__print_table(FILE *out, const char *pa, const char *pb, const tb_compare_result *r,
                            const char *err_path, double err_scale)
{
    fprintf(out, "A: %s\nB: %s (reference)\n%dx%d, peak %g, channels ", pa, pb, r->width,
            r->height, r->peak);
    for (int c = 0; c < r->nchannels; c++)
        fprintf(out, "%s%s", c ? "," : "", r->names[c]);
    fprintf(out, "\n\n%-8s %12s %12s %12s %12s %12s %12s  %s\n", "channel", "MSE", "RMSE",
            "relMSE", "PSNR [dB]", "SSIM", "max|A-B|", "at (x, y)");
    for (int c = 0; c < r->nchannels; c++)
        tb__row(out, r->names[c], &r->channel[c]);
    if (r->nchannels > 1)
        tb__row(out, "all", &r->all);
    fprintf(out, "\npixels compared: %lld of %lld (NaN/Inf pixels left out: %lld in A, %lld in B)\n",
            r->valid_pixels, r->pixels, r->nonfinite_a, r->nonfinite_b);
    if (r->ssim_windows == 0)
        fprintf(out, "SSIM: n/a (needs an 11x11 window free of NaN/Inf)\n");
    if (err_path)
        fprintf(out, "error image: %s (scale %g)\n", err_path, err_scale);
}

int tb_cmd_compare(int argc, char **argv)
{
    const char *paths[2] = {NULL, NULL};
    bool json = false, alpha = false, linear = false;
    const char *err_path = NULL;
    double err_scale = 0.0;
    tb_compare_options co = {0};
    tb_image_read_options ro = {0};
    const tb_opt opts[] = {
        {"json", .type = TB_OPT_FLAG, .dest = &json,
         .help = "print JSON instead of a table (non-finite numbers are null:\n"
                 "PSNR is null when MSE is 0, i.e. +inf)"},
        {"error-image", .type = TB_OPT_STRING, .dest = &err_path, .metavar = "OUT",
         .help = "write a false-colour error image (viridis; format by\n"
                 "extension; pixels with NaN/Inf are magenta)"},
        {"error-scale", .type = TB_OPT_DOUBLE, .dest = &err_scale, .min = 0, .max = INFINITY, .metavar = "S",
         .flags = TB_OPTF_OPEN_MIN,
         .help = "error shown at the top of the colour map (default: the\n"
                 "largest per-pixel error)"},
        {"peak", .type = TB_OPT_DOUBLE, .dest = &co.peak, .min = 0, .max = INFINITY, .metavar = "P",
         .flags = TB_OPTF_OPEN_MIN, .help = "signal peak for PSNR and SSIM (default 1)"},
        {"channels", .type = TB_OPT_STRING, .dest = &co.channels, .metavar = "LIST",
         .help = "comma-separated channel names to compare (default: R,G,B\n"
                 "if both have them, else Y, else the names both share)"},
        {"alpha", .type = TB_OPT_FLAG, .dest = &alpha, .help = "also compare the A channel when both images have one"},
        {"linear", .type = TB_OPT_FLAG, .dest = &linear,
         .help = "read 8-bit formats (PNG, RLE) as code/255, not sRGB"},
        {0},
    };
    const tb_cli cli = {
        .prog = "testbed compare",
        .err = "testbed compare: error: ",
        .usage = "A B [options]",
        .intro = "\n"
                 "Compares test image A with reference image B (same size, any format testbed\n"
                 "reads) and prints MSE, RMSE, relMSE, PSNR, SSIM and the largest absolute error,\n"
                 "per channel and over all compared channels.\n",
        .opts = opts,
        .outro = "\n"
                 "Definitions: relMSE = mean (a-b)^2 / (b^2 + 0.01) with B the reference; SSIM is\n"
                 "Wang et al. 2004 (11x11 Gaussian, sigma 1.5, K1 0.01, K2 0.03, L = peak), per\n"
                 "channel, averaged. Pixels with NaN/Inf in a compared channel are left out of\n"
                 "every metric and counted. See util/image/compare.h.\n"
                 "\n"
                 "Exit status: 0 compared, 1 an image could not be read/written or compared\n"
                 "(size or channel mismatch), 2 usage error.",
        .pos = paths,
        .max_pos = 2,
        .min_pos = 2,
        .missing = "need two images, A and B",
    };
    int npaths, prc = tb_cli_parse(&cli, argc, argv, &npaths);
    if (prc != TB_CLI_OK)
        return prc;
    co.include_alpha = alpha;
    if (linear)
        ro.encoding = TB_ENCODING_LINEAR;

    tb_image *img[2] = {NULL, NULL};
    tb_image *err = NULL;
    int rc = TB_EXIT_FAIL;
    for (int k = 0; k < 2; k++) {
        if (tb_image_read(paths[k], &ro, &img[k])) {
            fprintf(stderr, "testbed compare: error: %s\n", tb_last_error());
            goto done;
        }
    }
    tb_compare_result r;
    if (tb_image_compare(img[0], img[1], &co, &r)) {
        fprintf(stderr, "testbed compare: error: %s\n", tb_last_error());
        goto done;
    }
    double scale_used = 0.0;
    if (err_path) {
        if (tb_compare_error_image(img[0], img[1], &co, err_scale, &err, &scale_used) ||
            tb_image_set_attr(err, "compare.a", paths[0]) ||
            tb_image_set_attr(err, "compare.b", paths[1]) ||
            tb_image_write(err_path, err, NULL)) {
            fprintf(stderr, "testbed compare: error: %s\n", tb_last_error());
            goto done;
        }
    }
    if (json)
        tb__print_json(stdout, paths[0], paths[1], &r, err_path, scale_used);
    else
        tb__print_table(stdout, paths[0], paths[1], &r, err_path, scale_used);
    rc = fflush(stdout) == 0 ? TB_EXIT_OK : TB_EXIT_FAIL;

done:
    tb_image_free(err);
    tb_image_free(img[0]);
    tb_image_free(img[1]);
    return rc;
}
