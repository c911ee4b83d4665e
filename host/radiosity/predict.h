/* The statistics of a radiosity render for the cost model of
 * host/render/predict.h (docs/predict.md, "Radiosity"): the mesh is made
 * exactly as the render makes it, and a pilot solve with one sample point
 * per shooter counts the shots to convergence. */
#ifndef TB_HOST_RADIOSITY_PREDICT_H
#define TB_HOST_RADIOSITY_PREDICT_H

#include "host/radiosity/render.h"
#include "host/render/predict.h"

/* Loads the scene at `path` as tb_rad_render would with `o`, meshes it and
 * runs the pilot: the solver with ray-cast sample points cut to one per
 * shooter (hemicube: resolution / 4), to the render's threshold and
 * --max-shots, for at most `pilot_seconds` of shooting (> 0). If the pilot
 * stops first, the shot count is extrapolated along a power law fitted to
 * the unshot fraction over the pilot's second half (f->rad_extrapolated).
 * Rays and form factors are scaled to the render's sample count and shots.
 * TB_ERR_UNSUPPORTED for adaptive subdivision (o->adapt), which the model
 * leaves out; the loader's and solver's errors. */
tb_status tb_rad_predict_scene(const char *path, const tb_rad_render_options *o, double pilot_seconds,
                               tb_predict_stats *f);

#endif
