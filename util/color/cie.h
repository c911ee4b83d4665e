/* CIE colorimetry: the 1931 2-degree colour matching functions, the standard
 * illuminants D65 and E, spectrum -> XYZ and chromaticity. The tables are the
 * CSV files in util/color/, compiled in at build time (docs/color.md). */
#ifndef TB_UTIL_COLOR_CIE_H
#define TB_UTIL_COLOR_CIE_H

#include "util/base/error.h"
#include "util/color/spectrum.h"

/* Maximum luminous efficacy K_m (lm/W) of the CIE photometric system. */
#define TB_CIE_KM 683.0

/* CIE 1931 2-degree colour matching function x-bar, 380-780 nm at 5 nm (CIE 15:2004). */
const tb_spectrum *tb_cie_xbar(void);
/* CIE 1931 2-degree y-bar (= the photopic luminous efficiency V(lambda)). */
const tb_spectrum *tb_cie_ybar(void);
/* CIE 1931 2-degree z-bar. */
const tb_spectrum *tb_cie_zbar(void);

/* CIE standard illuminant D65, relative SPD 300-830 nm at 5 nm, S(560 nm) = 100. */
const tb_spectrum *tb_illuminant_d65(void);
/* CIE illuminant E (equal energy): 100 from 300 to 830 nm. */
const tb_spectrum *tb_illuminant_e(void);

/* How tb_emission_to_xyz() scales the integrals. */
typedef enum tb_emission_units {
    TB_EMISSION_RADIOMETRIC = 0, /* X = int L(l) xbar(l) dl, l in nm: the units of L times nm */
    TB_EMISSION_PHOTOMETRIC,     /* X = 683 lm/W * int L xbar dl: L in W/(sr m^2 nm) gives cd/m^2 */
} tb_emission_units;

/* XYZ of an emission spectrum (radiance, irradiance, ...) with absolute scale. */
tb_status tb_emission_to_xyz(const tb_spectrum *emission, tb_emission_units units,
                             double xyz[3]);

/* XYZ of a reflectance (or transmittance) lit by `illuminant`, normalised so a
 * perfect white reflector (1 everywhere) has Y = white_y (use 1 or 100):
 * X = white_y * int R S xbar / int S ybar. */
tb_status tb_reflectance_to_xyz(const tb_spectrum *reflectance, const tb_spectrum *illuminant,
                                double white_y, double xyz[3]);

/* XYZ of the illuminant itself normalised to Y = white_y (its white point). */
tb_status tb_illuminant_white_xyz(const tb_spectrum *illuminant, double white_y, double xyz[3]);

/* Chromaticity x = X/(X+Y+Z), y = Y/(X+Y+Z). TB_ERR_ARG if X+Y+Z is not > 0 or
 * a component is not finite. */
tb_status tb_xyz_to_xy(const double xyz[3], double xy[2]);

/* XYZ from chromaticity (x, y) and luminance Y; y must be > 0 (else TB_ERR_ARG). */
tb_status tb_xyY_to_xyz(const double xy[2], double Y, double xyz[3]);

#endif
