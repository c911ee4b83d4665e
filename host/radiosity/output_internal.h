/* Shared by the radiosity mesh writers (output.c: PLY, output_gltf.c: glTF),
 * so both files carry exactly the same colours. */
#ifndef TB_HOST_RADIOSITY_OUTPUT_INTERNAL_H
#define TB_HOST_RADIOSITY_OUTPUT_INTERNAL_H

#include <stddef.h>

#include "host/radiosity/radiosity.h"

/* Colours of corner k of element i, the ambient term `amb` included
 * (tb_rad_ambient, summed once by the caller: per corner it would be
 * quadratic in the elements): `radiance` the linear sRGB radiance B / pi;
 * `display` that times `scale`, clamped to [0, 1] (linear); `u8` display
 * sRGB-encoded to 8 bits. */
void tb__rad_corner_colour(const tb_rad_solver *s, const double *amb, size_t i, int k, double scale, float radiance[3],
                           float display[3], unsigned char u8[3]);

/* The provenance as a one-line JSON object (malloc'd), NULL if p is NULL
 * or out of memory. */
char *tb__rad_provenance_json(const struct tb_provenance *p, int indent, size_t *len);

#endif
