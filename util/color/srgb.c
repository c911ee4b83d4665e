#include "util/color/srgb.h"

#include <math.h>

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
