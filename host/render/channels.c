/* MID colours to shading channels (channels.h). */
#include "host/render/channels.h"

#include <stdlib.h>

#include "util/color/cie.h"
#include "util/color/smits.h"
#include "util/color/spectrum_file.h"
#include "util/color/srgb.h"

/* The spectrum of a MID colour as a tb_spectrum: inline samples (floats
 * widened) or the samples of its spectrum file. */
static tb_status tb__mid_spectrum(const tb_mid_color *c, tb_spectrum *out)
{
    if (c->type == TB_MID_COLOR_SPECTRUM_FILE)
        return tb_spectrum_read_file(c->file.path, out);
    double lambda[64], value[64];
    double *l = lambda, *v = value;
    double *heap = NULL;
    if (c->nsamples > 64) {
        heap = malloc(sizeof(double) * 2 * (size_t)c->nsamples);
        if (!heap)
            return tb_error(TB_ERR_NOMEM, "colour: out of memory for %d spectrum samples", c->nsamples);
        l = heap;
        v = heap + c->nsamples;
    }
    for (int i = 0; i < c->nsamples; i++) {
        l[i] = c->nm[i];
        v[i] = c->values[i];
    }
    tb_status st = tb_spectrum_init(out, c->nsamples, l, v);
    free(heap);
    return st;
}

tb_status tb_channels_from_mid_color(const tb_mid_color *c, const tb_bands *bands, tb_color_use use,
                                     tb_channels *out)
{
    if (!c || !out)
        return tb_error(TB_ERR_ARG, "colour: NULL argument");
    if (bands && bands->n > TB_CHANNELS_MAX)
        return tb_error(TB_ERR_UNSUPPORTED, "colour: %d render bands, at most %d per shading value",
                        bands->n, TB_CHANNELS_MAX);
    bool spectrum = c->type == TB_MID_COLOR_SPECTRUM || c->type == TB_MID_COLOR_SPECTRUM_FILE;
    if (c->type != TB_MID_COLOR_RGB && !spectrum)
        return tb_error(TB_ERR_ARG, "colour: unknown colour type %d", (int)c->type);

    double rgb[3] = {c->rgb[0], c->rgb[1], c->rgb[2]};
    double v[TB_CHANNELS_MAX];
    tb_status st = TB_OK;

    if (!bands) {
        if (spectrum) {
            tb_spectrum s;
            if ((st = tb__mid_spectrum(c, &s)))
                return st;
            double xyz[3];
            if (use == TB_COLOR_EMISSION)
                st = tb_emission_to_xyz(&s, TB_EMISSION_RADIOMETRIC, xyz);
            else
                st = tb_reflectance_to_xyz(&s, tb_illuminant_d65(), 1.0, xyz);
            tb_spectrum_release(&s);
            if (st)
                return st;
            tb_xyz_to_linear_srgb(xyz, rgb);
        }
        *out = tb_channels_rgb((float)rgb[0], (float)rgb[1], (float)rgb[2]);
        return TB_OK;
    }

    if (spectrum) {
        tb_spectrum s;
        if ((st = tb__mid_spectrum(c, &s)))
            return st;
        st = tb_bands_from_spectrum(bands, &s, v);
        tb_spectrum_release(&s);
    } else if (use == TB_COLOR_REFLECTANCE) {
        st = tb_bands_from_rgb_reflectance(bands, rgb, v);
    } else {
        tb_spectrum s;
        if ((st = tb_smits_emission(rgb, tb_illuminant_d65(), &s)))
            return st;
        st = tb_bands_from_spectrum(bands, &s, v);
        tb_spectrum_release(&s);
    }
    if (st)
        return st;
    *out = tb_channels_splat(bands->n, 0.0f);
    for (int i = 0; i < bands->n; i++)
        out->v[i] = (float)v[i];
    return TB_OK;
}
