#include "util/color/cie.h"

#include <math.h>

#include "color/color_tables.h" /* generated from the CSV files by module.cmake */

/* The built-in spectra point straight at the compiled tables: nothing to set up,
 * safe to share between threads. */
static const tb_spectrum tb__xbar = {TB__CIE1931_COUNT, tb__cie1931_lambda_nm, tb__cie1931_xbar, NULL};
static const tb_spectrum tb__ybar = {TB__CIE1931_COUNT, tb__cie1931_lambda_nm, tb__cie1931_ybar, NULL};
static const tb_spectrum tb__zbar = {TB__CIE1931_COUNT, tb__cie1931_lambda_nm, tb__cie1931_zbar, NULL};
static const tb_spectrum tb__d65 = {TB__D65_COUNT, tb__d65_lambda_nm, tb__d65_s, NULL};

/* Equal energy over the same range as the D65 table, at D65's level at 560 nm. */
static const double tb__e_lambda[2] = {300.0, 830.0};
static const double tb__e_value[2] = {100.0, 100.0};
static const tb_spectrum tb__e = {2, tb__e_lambda, tb__e_value, NULL};

const tb_spectrum *tb_cie_xbar(void) { return &tb__xbar; }
const tb_spectrum *tb_cie_ybar(void) { return &tb__ybar; }
const tb_spectrum *tb_cie_zbar(void) { return &tb__zbar; }
const tb_spectrum *tb_illuminant_d65(void) { return &tb__d65; }
const tb_spectrum *tb_illuminant_e(void) { return &tb__e; }

tb_status tb_emission_to_xyz(const tb_spectrum *emission, tb_emission_units units, double xyz[3])
{
    if (!emission || !xyz)
        return tb_error(TB_ERR_ARG, "emission to XYZ: no spectrum or output given");
    double k;
    switch (units) {
    case TB_EMISSION_RADIOMETRIC: k = 1.0; break;
    case TB_EMISSION_PHOTOMETRIC: k = TB_CIE_KM; break;
    default: return tb_error(TB_ERR_ARG, "emission to XYZ: unknown units %d", (int)units);
    }
    xyz[0] = k * tb_spectrum_product_integral(emission, &tb__xbar, NULL);
    xyz[1] = k * tb_spectrum_product_integral(emission, &tb__ybar, NULL);
    xyz[2] = k * tb_spectrum_product_integral(emission, &tb__zbar, NULL);
    return TB_OK;
}

/* int S ybar, checked to be usable as a normalisation. */
static tb_status tb__illuminant_y(const tb_spectrum *illuminant, double white_y, double *y)
{
    *y = 0.0; /* defined on error paths too (gcc -O3 cannot see they never return TB_OK) */
    if (!isfinite(white_y) || !(white_y > 0.0))
        return tb_error(TB_ERR_ARG, "reflectance to XYZ: white Y %g must be finite and > 0", white_y);
    *y = tb_spectrum_product_integral(illuminant, &tb__ybar, NULL);
    if (!(*y > 0.0))
        return tb_error(TB_ERR_ARG,
                        "reflectance to XYZ: the illuminant has no luminance (int S ybar = %g)", *y);
    return TB_OK;
}

tb_status tb_reflectance_to_xyz(const tb_spectrum *reflectance, const tb_spectrum *illuminant,
                                double white_y, double xyz[3])
{
    if (!reflectance || !illuminant || !xyz)
        return tb_error(TB_ERR_ARG, "reflectance to XYZ: no spectrum, illuminant or output given");
    double ys;
    tb_status st = tb__illuminant_y(illuminant, white_y, &ys);
    if (st)
        return st;
    double k = white_y / ys;
    xyz[0] = k * tb_spectrum_product_integral(reflectance, illuminant, &tb__xbar);
    xyz[1] = k * tb_spectrum_product_integral(reflectance, illuminant, &tb__ybar);
    xyz[2] = k * tb_spectrum_product_integral(reflectance, illuminant, &tb__zbar);
    return TB_OK;
}

tb_status tb_illuminant_white_xyz(const tb_spectrum *illuminant, double white_y, double xyz[3])
{
    if (!illuminant || !xyz)
        return tb_error(TB_ERR_ARG, "illuminant white: no illuminant or output given");
    double ys;
    tb_status st = tb__illuminant_y(illuminant, white_y, &ys);
    if (st)
        return st;
    double k = white_y / ys;
    xyz[0] = k * tb_spectrum_product_integral(illuminant, &tb__xbar, NULL);
    xyz[1] = white_y;
    xyz[2] = k * tb_spectrum_product_integral(illuminant, &tb__zbar, NULL);
    return TB_OK;
}

tb_status tb_xyz_to_xy(const double xyz[3], double xy[2])
{
    if (!isfinite(xyz[0]) || !isfinite(xyz[1]) || !isfinite(xyz[2]))
        return tb_error(TB_ERR_ARG, "XYZ to xy: XYZ (%g, %g, %g) is not finite", xyz[0], xyz[1],
                        xyz[2]);
    double sum = xyz[0] + xyz[1] + xyz[2];
    if (!(sum > 0.0))
        return tb_error(TB_ERR_ARG, "XYZ to xy: X+Y+Z = %g has no chromaticity", sum);
    xy[0] = xyz[0] / sum;
    xy[1] = xyz[1] / sum;
    return TB_OK;
}

tb_status tb_xyY_to_xyz(const double xy[2], double Y, double xyz[3])
{
    if (!isfinite(xy[0]) || !isfinite(xy[1]) || !isfinite(Y) || !(xy[1] > 0.0))
        return tb_error(TB_ERR_ARG, "xyY to XYZ: (x, y, Y) = (%g, %g, %g) needs finite values, y > 0",
                        xy[0], xy[1], Y);
    xyz[0] = xy[0] * Y / xy[1];
    xyz[1] = Y;
    xyz[2] = (1.0 - xy[0] - xy[1]) * Y / xy[1];
    return TB_OK;
}
