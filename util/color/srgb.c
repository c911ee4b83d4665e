#include "util/color/srgb.h"

#include <math.h>

#include "util/math/mat.h"

/* Computed in double so that decode(encode(x)) round-trips every 8- and 16-bit
 * code exactly after rounding; the curve itself is the standard's. */
float tb_srgb_encode(float linear)
{
    double x = linear;
    if (!(x > 0.0))
        return 0.0f; /* also maps NaN to 0 */
    if (x >= 1.0)
        return 1.0f;
    return (float)(x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055);
}

float tb_srgb_decode(float encoded)
{
    double v = encoded;
    if (!(v > 0.0))
        return 0.0f;
    if (v >= 1.0)
        return 1.0f;
    return (float)(v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4));
}

/* Printed to 17 digits from an exact rational evaluation of the derivation in
 * tb_rgb_to_xyz_matrix() with the IEC 61966-2-1 primaries and white; the tests
 * recompute both from the primaries and compare with the standard's table. */
const double tb_srgb_to_xyz_matrix[3][3] = {
    {0.41239079926595951, 0.35758433938387796, 0.18048078840183429},
    {0.21263900587151036, 0.71516867876775592, 0.072192315360733714},
    {0.019330818715591849, 0.11919477979462599, 0.95053215224966059},
};

const double tb_xyz_to_srgb_matrix[3][3] = {
    {3.2409699419045213, -1.5373831775700935, -0.49861076029300327},
    {-0.96924363628087984, 1.8759675015077206, 0.041555057407175612},
    {0.055630079696993608, -0.20397695888897657, 1.0569715142428786},
};

static void tb__mat3_apply(const double m[3][3], const double in[3], double out[3])
{
    double a = in[0], b = in[1], c = in[2];
    out[0] = m[0][0] * a + m[0][1] * b + m[0][2] * c;
    out[1] = m[1][0] * a + m[1][1] * b + m[1][2] * c;
    out[2] = m[2][0] * a + m[2][1] * b + m[2][2] * c;
}

void tb_linear_srgb_to_xyz(const double rgb[3], double xyz[3])
{
    tb__mat3_apply(tb_srgb_to_xyz_matrix, rgb, xyz);
}

void tb_xyz_to_linear_srgb(const double xyz[3], double rgb[3])
{
    tb__mat3_apply(tb_xyz_to_srgb_matrix, xyz, rgb);
}

double tb_linear_srgb_luminance(const double rgb[3])
{
    const double *y = tb_srgb_to_xyz_matrix[1];
    return y[0] * rgb[0] + y[1] * rgb[1] + y[2] * rgb[2];
}

tb_status tb_rgb_to_xyz_matrix(const double primaries_xy[3][2], const double white_xy[2],
                               double m[3][3])
{
    const double *xy[4] = {primaries_xy[0], primaries_xy[1], primaries_xy[2], white_xy};
    for (int k = 0; k < 4; k++)
        if (!isfinite(xy[k][0]) || !isfinite(xy[k][1]) || !(xy[k][1] > 0.0))
            return tb_error(TB_ERR_ARG, "RGB matrix: chromaticity (%g, %g) needs finite x, y > 0",
                            xy[k][0], xy[k][1]);
    /* Columns: XYZ of each primary at Y = 1; then scale them so they sum to the white. */
    tb_mat3 p, pinv;
    for (int k = 0; k < 3; k++) {
        p.m[0][k] = xy[k][0] / xy[k][1];
        p.m[1][k] = 1.0;
        p.m[2][k] = (1.0 - xy[k][0] - xy[k][1]) / xy[k][1];
    }
    if (tb_mat3_inverse(&p, &pinv))
        return tb_error_context(TB_ERR_ARG, "RGB matrix: primaries are collinear");
    double w[3] = {white_xy[0] / white_xy[1], 1.0, (1.0 - white_xy[0] - white_xy[1]) / white_xy[1]};
    double s[3];
    tb__mat3_apply(pinv.m, w, s);
    for (int r = 0; r < 3; r++)
        for (int k = 0; k < 3; k++)
            m[r][k] = p.m[r][k] * s[k];
    return TB_OK;
}
