/* `testbed convert IN OUT`: converts an image between Utah RLE, PNG, PFM and
 * OpenEXR (formats chosen by extension), carrying the attributes across. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "util/image/image.h"

static int tb__convert_usage_error(const tb_cli *cli, const char *msg, const char *detail)
{
    return tb_cli_usage_error(cli, "%s '%s'", msg, detail);
}

int tb_cmd_convert(int argc, char **argv)
{
    const char *paths[2] = {NULL, NULL};
    bool half = false, linear = false;
    int bits = 0;
    double exposure = 0.0;
    static const tb_opt_choice bit_depths[] = {{"8", 8}, {"16", 16}, {NULL, 0}};
    const tb_opt opts[] = {
        {"exposure", .type = TB_OPT_DOUBLE, .dest = &exposure, .min = -100, .max = 100, .metavar = "STOPS",
         .help = "multiply colour values by 2^STOPS before writing (alpha and\n"
                 "EXR data channels such as Z are not scaled)"},
        {"linear", .type = TB_OPT_FLAG, .dest = &linear,
         .help = "8/16-bit files (PNG, RLE) hold linear values, code/max, with\n"
                 "no sRGB curve; applies to reading IN and to writing OUT"},
        {"bits", .type = TB_OPT_CHOICE, .dest = &bits, .choices = bit_depths,
         .help = "bits per channel of a PNG OUT (default 8)"},
        {"half", .type = TB_OPT_FLAG, .dest = &half,
         .help = "store an EXR OUT as 16-bit half floats (default 32-bit float)"},
        {0},
    };
    const tb_cli cli = {
        .prog = "testbed convert",
        .err = "testbed convert: error: ",
        .usage = "IN OUT [options]",
        .intro = "\n"
                 "Converts image IN to OUT; each file's format follows its extension: .rle (Utah\n"
                 "Raster Toolkit), .png, .pfm (Portable Float Map) or .exr (OpenEXR). Pixels pass\n"
                 "through as linear floats; 8- and 16-bit formats are decoded from and encoded to\n"
                 "the sRGB curve (alpha stays linear). String attributes (provenance) are copied\n"
                 "to formats that hold them: PNG text chunks, EXR string attributes, RLE comments.\n",
        .opts = opts,
        .outro = "\n"
                 "The output appears whole or not at all: it is written to a temporary file that\n"
                 "replaces OUT only on success.\n"
                 "\n"
                 "Exit status: 0 converted, 1 IN could not be read or OUT written, 2 usage error.",
        .pos = paths,
        .max_pos = 2,
        .min_pos = 2,
        .missing = "need an input and an output file",
    };
    int npaths, prc = tb_cli_parse(&cli, argc, argv, &npaths);
    if (prc != TB_CLI_OK)
        return prc;
    tb_image_format in_fmt = tb_image_format_from_path(paths[0]);
    tb_image_format out_fmt = tb_image_format_from_path(paths[1]);
    for (int k = 0; k < 2; k++)
        if ((k ? out_fmt : in_fmt) == TB_IMAGE_UNKNOWN)
            return tb__convert_usage_error(&cli, "cannot tell the format from the extension (use .rle, .png, "
                                                 ".pfm or .exr):", paths[k]);
    if (bits && out_fmt != TB_IMAGE_PNG)
        return tb__convert_usage_error(&cli, "--bits applies to PNG output only, not", paths[1]);
    if (half && out_fmt != TB_IMAGE_EXR)
        return tb__convert_usage_error(&cli, "--half applies to OpenEXR output only, not", paths[1]);

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
