/* sRGB (IEC 61966-2-1): the transfer curve, used for 8/16-bit image formats and
 * display, and the linear sRGB <-> CIE XYZ matrices (ITU-R BT.709 primaries,
 * D65 white), plus the general RGB <-> XYZ matrix from primaries and white. */
#ifndef TB_UTIL_COLOR_SRGB_H
#define TB_UTIL_COLOR_SRGB_H

#include "util/base/error.h"

/* Linear value in [0,1] -> sRGB-encoded value in [0,1] (inputs outside are clamped). */
float tb_srgb_encode(float linear);

/* sRGB-encoded value in [0,1] -> linear value in [0,1] (inputs outside are clamped). */
float tb_srgb_decode(float encoded);

/* Linear sRGB -> XYZ (Y = 1 for RGB white), row-major: xyz = M rgb. Derived in
 * full precision from the standard's primaries and white (x, y) = (0.3127, 0.3290);
 * rounds to the standard's published 4-digit matrix. */
extern const double tb_srgb_to_xyz_matrix[3][3];

/* XYZ -> linear sRGB, the exact inverse of tb_srgb_to_xyz_matrix (the standard's
 * 4-digit XYZ -> RGB table is the inverse of its rounded forward matrix and
 * differs from this one by up to 4e-4). */
extern const double tb_xyz_to_srgb_matrix[3][3];

/* Linear sRGB -> CIE XYZ. `xyz` may alias `rgb`. */
void tb_linear_srgb_to_xyz(const double rgb[3], double xyz[3]);

/* CIE XYZ -> linear sRGB (no clamping: out-of-gamut colours have components < 0 or > 1).
 * `rgb` may alias `xyz`. */
void tb_xyz_to_linear_srgb(const double xyz[3], double rgb[3]);

/* Relative luminance Y of a linear sRGB colour (the middle row of the matrix). */
double tb_linear_srgb_luminance(const double rgb[3]);

/* The RGB -> XYZ matrix of an RGB space with primaries (x, y) red, green, blue
 * and white point (x, y); RGB (1,1,1) maps to the white with Y = 1.
 * TB_ERR_ARG for a y <= 0, non-finite input or collinear primaries. The inverse
 * (XYZ -> RGB) is tb_mat3_inverse() of util/math/mat.h. */
tb_status tb_rgb_to_xyz_matrix(const double primaries_xy[3][2], const double white_xy[2],
                               double m[3][3]);

#endif
