/* RGB -> spectrum upsampling with Smits (1999), "An RGB-to-Spectrum Conversion
 * for Reflectances", J. Graphics Tools 4(4): linear RGB with the sRGB primaries
 * becomes a smooth-ish reflectance built from seven published basis spectra
 * (white, cyan, magenta, yellow, red, green, blue). For reflectances only; see
 * docs/color.md for its round-trip error and the emission variant. */
#ifndef TB_UTIL_COLOR_SMITS_H
#define TB_UTIL_COLOR_SMITS_H

#include "util/base/error.h"
#include "util/color/spectrum.h"

/* The seven basis spectra, in the order of the published table. */
typedef enum tb_smits_basis {
    TB_SMITS_WHITE = 0,
    TB_SMITS_CYAN,
    TB_SMITS_MAGENTA,
    TB_SMITS_YELLOW,
    TB_SMITS_RED,
    TB_SMITS_GREEN,
    TB_SMITS_BLUE,
    TB_SMITS_BASIS_COUNT
} tb_smits_basis;

/* Number of samples of every Smits spectrum (see tb_smits_lambda()). */
#define TB_SMITS_SAMPLES 22

/* The wavelengths (nm) of every spectrum made here: the 10 published 34-nm bins
 * over 380-720 nm as steps, each step a 1-nm linear ramp centred on the bin edge
 * (so each bin keeps its area), and the end bins held flat out to 360 and 830 nm. */
const double *tb_smits_lambda(void);

/* Weights of the basis spectra for linear RGB `rgb` (Smits' algorithm: the smallest
 * component times white, then the two-colour and one-colour parts). */
tb_status tb_smits_weights(const double rgb[3], double w[TB_SMITS_BASIS_COUNT]);

/* One basis spectrum as a (shared, read-only) tb_spectrum. */
const tb_spectrum *tb_smits_basis_spectrum(tb_smits_basis which);

/* Reflectance spectrum for linear RGB `rgb` (components finite and >= 0; above 1
 * is accepted, the map is linear in scale). Free `*out` with tb_spectrum_release(). */
tb_status tb_smits_reflectance(const double rgb[3], tb_spectrum *out);

/* Emission spectrum for linear RGB `rgb`: the Smits reflectance times `illuminant`
 * (tb_illuminant_d65() or tb_illuminant_e()), divided by int illuminant * ybar,
 * so that RGB (1,1,1) emits the illuminant's spectrum with luminance Y = 1
 * (tb_emission_to_xyz radiometric units) and Y scales with the RGB. */
tb_status tb_smits_emission(const double rgb[3], const tb_spectrum *illuminant,
                            tb_spectrum *out);

#endif
