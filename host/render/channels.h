/* The colour value the renderer carries through shading and lights: N float
 * channels with a run-time count, so RGB (N = 3) and spectral render bands
 * (util/color/bands.h, e.g. N = 31 for 400-700 nm at 10 nm) share every
 * shading and light function. Channels are independent: every operation here
 * works channel by channel, which is exactly right for band values (samples of
 * a piecewise-linear spectrum, multiplied and added pointwise) and for linear
 * RGB. A renderer with more than TB_CHANNELS_MAX bands shades them in batches.
 *
 * Plain struct passed by value (132 bytes); operations on two values use the
 * channel count of the first. */
#ifndef TB_HOST_RENDER_CHANNELS_H
#define TB_HOST_RENDER_CHANNELS_H

#include <math.h>
#include <stdbool.h>

#include "host/mid/mid.h"
#include "util/base/error.h"
#include "util/color/bands.h"

/* Most channels one value holds: the 31 default render bands fit. */
#define TB_CHANNELS_MAX 32

/* N channel values. Channels n .. TB_CHANNELS_MAX-1 are kept at zero by the
 * constructors below, so whole-struct comparisons are meaningful. */
typedef struct tb_channels {
    int n;                    /* channels in use, 1..TB_CHANNELS_MAX */
    float v[TB_CHANNELS_MAX]; /* channel values (linear RGB, or band values) */
} tb_channels;

/* n channels, all equal to s (n is clamped to 1..TB_CHANNELS_MAX). */
static inline tb_channels tb_channels_splat(int n, float s)
{
    tb_channels c = {0};
    c.n = n < 1 ? 1 : (n > TB_CHANNELS_MAX ? TB_CHANNELS_MAX : n);
    for (int i = 0; i < c.n; i++)
        c.v[i] = s;
    return c;
}

/* Three channels (r, g, b). */
static inline tb_channels tb_channels_rgb(float r, float g, float b)
{
    tb_channels c = {0};
    c.n = 3;
    c.v[0] = r;
    c.v[1] = g;
    c.v[2] = b;
    return c;
}

/* n channels copied from v[0..n) (n clamped as in tb_channels_splat). */
static inline tb_channels tb_channels_from_array(int n, const float *v)
{
    tb_channels c = tb_channels_splat(n, 0.0f);
    for (int i = 0; i < c.n; i++)
        c.v[i] = v[i];
    return c;
}

/* a + b. */
static inline tb_channels tb_channels_add(tb_channels a, tb_channels b)
{
    for (int i = 0; i < a.n; i++)
        a.v[i] += b.v[i];
    return a;
}

/* a - b. */
static inline tb_channels tb_channels_sub(tb_channels a, tb_channels b)
{
    for (int i = 0; i < a.n; i++)
        a.v[i] -= b.v[i];
    return a;
}

/* Channel-wise a * b. */
static inline tb_channels tb_channels_mul(tb_channels a, tb_channels b)
{
    for (int i = 0; i < a.n; i++)
        a.v[i] *= b.v[i];
    return a;
}

/* a * s. */
static inline tb_channels tb_channels_scale(tb_channels a, float s)
{
    for (int i = 0; i < a.n; i++)
        a.v[i] *= s;
    return a;
}

/* a + b * s (two roundings per channel: no FMA). */
static inline tb_channels tb_channels_add_scaled(tb_channels a, tb_channels b, float s)
{
    for (int i = 0; i < a.n; i++)
        a.v[i] += b.v[i] * s;
    return a;
}

/* Largest channel. */
static inline float tb_channels_max(tb_channels a)
{
    float m = a.v[0];
    for (int i = 1; i < a.n; i++)
        m = fmaxf(m, a.v[i]);
    return m;
}

/* Mean of the channels (a scalar weight for lobe selection and Russian roulette). */
static inline float tb_channels_average(tb_channels a)
{
    double s = 0.0;
    for (int i = 0; i < a.n; i++)
        s += a.v[i];
    return (float)(s / a.n);
}

/* True if every channel is exactly zero. */
static inline bool tb_channels_is_black(tb_channels a)
{
    for (int i = 0; i < a.n; i++)
        if (a.v[i] != 0.0f)
            return false;
    return true;
}

/* True if every channel is finite. */
static inline bool tb_channels_is_finite(tb_channels a)
{
    for (int i = 0; i < a.n; i++)
        if (!isfinite(a.v[i]))
            return false;
    return true;
}

/* What a MID colour means, which decides how RGB is turned into bands. */
typedef enum tb_color_use {
    TB_COLOR_REFLECTANCE = 0, /* reflectance or transmittance in [0, 1] */
    TB_COLOR_EMISSION,        /* an emitted quantity (exitance, intensity, irradiance) */
} tb_color_use;

/* Channels of a MID colour (docs/mid.md, 7.1; docs/shading.md, "Colour
 * values"). With bands == NULL the result is linear RGB (3 channels): RGB
 * colours as given; an inline spectrum by its XYZ, then the sRGB matrix: for
 * TB_COLOR_REFLECTANCE as a reflectance under D65 (the sRGB white, so a perfect
 * reflector gives (1, 1, 1)), for TB_COLOR_EMISSION radiometrically
 * (X = int L xbar dl), so RGB (1, 1, 1) stands for the D65-shaped emission of
 * Y = 1 that tb_smits_emission makes. With bands: an inline spectrum resampled
 * onto the bands (tb_bands_from_spectrum); an RGB reflectance by Smits
 * upsampling (tb_bands_from_rgb_reflectance); an RGB emission as
 * tb_smits_emission(rgb, D65) resampled onto the bands (the inverse of the RGB
 * rule above). TB_ERR_UNSUPPORTED for a spectrum file (util/color has no reader
 * for them) and for more than TB_CHANNELS_MAX bands; TB_ERR_ARG for NULL
 * arguments or values util/color refuses. */
tb_status tb_channels_from_mid_color(const tb_mid_color *c, const tb_bands *bands, tb_color_use use,
                                     tb_channels *out);

#endif
