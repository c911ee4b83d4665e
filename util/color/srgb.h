/* The sRGB transfer curve (IEC 61966-2-1), used for 8/16-bit image formats and display. */
#ifndef TB_UTIL_COLOR_SRGB_H
#define TB_UTIL_COLOR_SRGB_H

/* Linear value in [0,1] -> sRGB-encoded value in [0,1] (inputs outside are clamped). */
float tb_srgb_encode(float linear);

/* sRGB-encoded value in [0,1] -> linear value in [0,1] (inputs outside are clamped). */
float tb_srgb_decode(float encoded);

#endif
