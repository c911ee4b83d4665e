/* Render bands: a fixed set of wavelengths a renderer carries per ray or patch
 * (e.g. 400-700 nm at 10 nm). Band values are samples of a piecewise-linear
 * spectrum (zero outside the first and last band, as every tb_spectrum), so a
 * renderer multiplies and adds band values and converts to XYZ / sRGB once at the
 * end with precomputed weights, exactly as tb_emission_to_xyz() would. */
#ifndef TB_UTIL_COLOR_BANDS_H
#define TB_UTIL_COLOR_BANDS_H

#include "util/base/error.h"
#include "util/color/smits.h"
#include "util/color/spectrum.h"

/* Most bands a tb_bands can hold. */
#define TB_BANDS_MAX 128

/* The default band set: 400-700 nm at 10 nm (31 bands), the range of the Cornell
 * Box measurements. */
#define TB_BANDS_DEFAULT_MIN 400.0
#define TB_BANDS_DEFAULT_MAX 700.0
#define TB_BANDS_DEFAULT_COUNT 31

/* A band set with its precomputed conversion weights (plain data: copy freely). */
typedef struct tb_bands {
    int n;                              /* number of bands, 2..TB_BANDS_MAX */
    double lambda[TB_BANDS_MAX];        /* band wavelengths, nm, strictly increasing */
    double xyz_weight[TB_BANDS_MAX][3]; /* int hat_i(l) {xbar, ybar, zbar}(l) dl: XYZ = sum_i v_i w_i */
    double smits[TB_SMITS_BASIS_COUNT][TB_BANDS_MAX]; /* Smits basis spectra resampled onto the bands */
} tb_bands;

/* Bands at the n wavelengths `lambda` (checked as tb_spectrum_check, n <= TB_BANDS_MAX). */
tb_status tb_bands_init(tb_bands *b, int n, const double *lambda);

/* n bands evenly spaced from lambda_min to lambda_max inclusive. */
tb_status tb_bands_init_range(tb_bands *b, double lambda_min, double lambda_max, int n);

/* The default bands (TB_BANDS_DEFAULT_*). */
tb_status tb_bands_init_default(tb_bands *b);

/* Band values of a spectrum (tb_spectrum_resample_values: averaging where the
 * spectrum has finer detail than the bands). `v` holds b->n values. */
tb_status tb_bands_from_spectrum(const tb_bands *b, const tb_spectrum *s, double *v);

/* Band values of the Smits reflectance of linear RGB `rgb` (a combination of the
 * resampled basis, so no allocation: usable per shading point). */
tb_status tb_bands_from_rgb_reflectance(const tb_bands *b, const double rgb[3], double *v);

/* XYZ of band values, as the emission of their piecewise-linear spectrum
 * (radiometric: the units of v times nm). Divide by the Y of the light's bands
 * for reflectance-style normalisation. */
void tb_bands_to_xyz(const tb_bands *b, const double *v, double xyz[3]);

/* Linear sRGB of band values: tb_bands_to_xyz() times `scale`, then the sRGB matrix. */
void tb_bands_to_linear_srgb(const tb_bands *b, const double *v, double scale, double rgb[3]);

#endif
