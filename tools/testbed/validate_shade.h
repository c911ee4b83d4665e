/* `testbed validate --kernel shade` (cmd_validate_shade.c; docs/gpu.md,
 * "Shade kernel and wavefront renderer"). */
#ifndef TB_TOOLS_TESTBED_VALIDATE_SHADE_H
#define TB_TOOLS_TESTBED_VALIDATE_SHADE_H

#include <stdbool.h>

#include "host/gpu/gpu.h"
#include "host/render/scene.h"

/* Image NMSE = sum (vulkan - cpu)^2 / sum cpu^2 (linear sRGB, every pixel and
 * channel) allowed by `testbed validate --kernel shade` (docs/accuracy.md,
 * "Shade kernel"). */
#define TB_VALIDATE_SHADE_TOL_NMSE 1e-4
/* Largest |sum (vulkan - cpu)| / sum cpu: a systematic shading error shows
 * here long before it shows in the NMSE. */
#define TB_VALIDATE_SHADE_TOL_BIAS 1e-3

/* Renders `s` at a small resolution (the file's aspect ratio, at most 96
 * pixels wide and `samples` camera samples, at least 8 pixels wide) with 4
 * samples per pixel and seed `seed` on the CPU path and with the
 * Vulkan wavefront renderer on the session's device, prints the image NMSE,
 * the mean bias, the largest pixel difference and the routing, and sets *ok
 * when the NMSE and the bias are within their tolerances. Returns nonzero (message printed)
 * when a render fails. */
int tb_validate_shade(const tb_scene *s, tb_gpu_session *sess, long samples, long seed, bool *ok);

#endif
