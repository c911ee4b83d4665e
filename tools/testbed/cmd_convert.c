/* `testbed convert IN OUT`: converts an image between Utah RLE, PNG, PFM and
 * OpenEXR (formats chosen by extension), carrying the attributes across. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "util/image/image.h"

static void tb__convert_usage(FILE *out)
{
    fprintf(out,
            "usage: testbed convert IN OUT [options]\n"
            "\n"
            "Converts image IN to OUT; each file's format follows its extension: .rle (Utah\n"
            "Raster Toolkit), .png, .pfm (Portable Float Map) or .exr (OpenEXR). Pixels pass\n"
            "through as linear floats; 8- and 16-bit formats are decoded from and encoded to\n"
            "the sRGB curve (alpha stays linear). String attributes (provenance) are copied\n"
            "to formats that hold them: PNG text chunks, EXR string attributes, RLE comments.\n"
            "\n"
            "  --exposure STOPS   multiply colour values by 2^STOPS before writing (alpha and\n"
            "                     EXR data channels such as Z are not scaled)\n"
            "  --linear           8/16-bit files (PNG, RLE) hold linear values, code/max, with\n"
            "                     no sRGB curve; applies to reading IN and to writing OUT\n"
            "  --bits 8|16        bits per channel of a PNG OUT (default 8)\n"
            "  --half             store an EXR OUT as 16-bit half floats (default 32-bit float)\n"
            "  -h, --help         show this help\n"
            "\n"
            "The output appears whole or not at all: it is written to a temporary file that\n"
            "replaces OUT only on success.\n"
            "\n"
            "Exit status: 0 converted, 1 IN could not be read or OUT written, 2 usage error.\n");
}

/* A finite number, the whole of `s`. */
static int tb__convert_number(const char *s, double *out)
{
    char *end;
    double v = strtod(s, &end);
    if (end == s || *end || !isfinite(v))
        return -1;
    *out = v;
    return 0;
}

/* The value of option `name` in argv[*i]: "--name=VALUE" or "--name VALUE".
 * NULL if argv[*i] is not that option; *missing set if it lacks its value. */
static const char *tb__convert_value(int argc, char **argv, int *i, const char *name, int *missing)
{
    size_t n = strlen(name);
    const char *arg = argv[*i];
    if (strncmp(arg, name, n) != 0)
        return NULL;
    if (arg[n] == '=')
        return arg + n + 1;
    if (arg[n] != '\0')
        return NULL;
    if (*i + 1 >= argc) {
        *missing = 1;
        return NULL;
    }
    return argv[++*i];
}

static int tb__convert_usage_error(const char *msg, const char *detail)
{
    fprintf(stderr, "testbed convert: error: %s%s%s%s (see `testbed convert --help`)\n", msg,
            detail ? " '" : "", detail ? detail : "", detail ? "'" : "");
    return TB_EXIT_USAGE;
}

int tb_cmd_convert(int argc, char **argv)
{
    if (tb_wants_help(argc, argv)) {
        tb__convert_usage(stdout);
        return TB_EXIT_OK;
    }
    const char *paths[2] = {NULL, NULL};
    int npaths = 0, opts_done = 0, bits = 0, half = 0, linear = 0;
    double exposure = 0.0;
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i], *v;
        int missing = 0;
        if (opts_done || arg[0] != '-' || arg[1] == '\0') {
            if (npaths == 2)
                return tb__convert_usage_error("more than two files given:", arg);
            paths[npaths++] = arg;
        } else if (strcmp(arg, "--") == 0) {
            opts_done = 1;
        } else if (strcmp(arg, "--linear") == 0) {
            linear = 1;
        } else if (strcmp(arg, "--half") == 0) {
            half = 1;
        } else if ((v = tb__convert_value(argc, argv, &i, "--exposure", &missing))) {
            if (tb__convert_number(v, &exposure) || fabs(exposure) > 100.0)
                return tb__convert_usage_error("--exposure needs a number of stops in [-100, 100], not", v);
        } else if ((v = tb__convert_value(argc, argv, &i, "--bits", &missing))) {
            if (strcmp(v, "8") != 0 && strcmp(v, "16") != 0)
                return tb__convert_usage_error("--bits must be 8 or 16, not", v);
            bits = atoi(v);
        } else if (missing) {
            return tb__convert_usage_error("option needs a value:", arg);
        } else {
            return tb__convert_usage_error("unknown option", arg);
        }
    }
    if (npaths != 2) {
        fprintf(stderr, "testbed convert: error: need an input and an output file\n");
        tb__convert_usage(stderr);
        return TB_EXIT_USAGE;
    }
    tb_image_format in_fmt = tb_image_format_from_path(paths[0]);
    tb_image_format out_fmt = tb_image_format_from_path(paths[1]);
    for (int k = 0; k < 2; k++)
        if ((k ? out_fmt : in_fmt) == TB_IMAGE_UNKNOWN)
            return tb__convert_usage_error("cannot tell the format from the extension (use .rle, .png, "
                                           ".pfm or .exr):", paths[k]);
    if (bits && out_fmt != TB_IMAGE_PNG)
        return tb__convert_usage_error("--bits applies to PNG output only, not", paths[1]);
    if (half && out_fmt != TB_IMAGE_EXR)
        return tb__convert_usage_error("--half applies to OpenEXR output only, not", paths[1]);

    tb_image_read_options ro = {.encoding = linear ? TB_ENCODING_LINEAR : TB_ENCODING_SRGB};
    tb_image *img = NULL;
    if (tb_image_read(paths[0], &ro, &img) != TB_OK) {
        fprintf(stderr, "testbed convert: error: %s\n", tb_last_error());
        return TB_EXIT_FAIL;
    }
    tb_image_write_options wo = {
        .exposure = (float)exposure,
        .encoding = ro.encoding,
        .png_bits = bits,
        .exr_half = half,
    };
    if (out_fmt == TB_IMAGE_PFM && img->nattrs > 0)
        fprintf(stderr, "testbed convert: note: PFM files hold no attributes; %d not copied\n", img->nattrs);
    int rc = TB_EXIT_OK;
    if (tb_image_write(paths[1], img, &wo) != TB_OK) {
        fprintf(stderr, "testbed convert: error: %s\n", tb_last_error());
        rc = TB_EXIT_FAIL;
    }
    tb_image_free(img);
    return rc;
}
