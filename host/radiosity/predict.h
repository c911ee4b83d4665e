/* The statistics of a radiosity render for the cost model of
 * host/render/predict.h (docs/predict.md, "Gathering the statistics"): the
 * mesh is made exactly as the render makes it, and a pilot solve on a
 * coarser mesh with one sample point per shooter counts the shots to
 * convergence. */
#ifndef TB_HOST_RADIOSITY_PREDICT_H
#define TB_HOST_RADIOSITY_PREDICT_H

#include "host/radiosity/render.h"
#include "host/render/predict.h"

/* Loads the scene at `path` as tb_rad_render would with `o`, meshes it
 * (the render's elements and vertices) and runs the pilot: the solver on a
 * mesh with elements and patches 4 times longer (when the mesh has more
 * than 256 shooters), ray-cast sample points cut to one per shooter
 * (hemicube: resolution / 4), to the render's threshold, for at most
 * `pilot_seconds` of shooting (> 0). The pilot's shots per shooter times
 * the render's shooters is the shot count (capped by --max-shots); if the
 * pilot runs out of time first, its count is extrapolated along an
 * exponential fitted to the unshot fraction over its second half
 * (f->rad_extrapolated). Rays and form factors per shot scale with the
 * vertices and the sample points; when the pilot's mesh is coarser, the
 * visibility work per ray (BVH rays, their nodes, shaft occluders) comes
 * from the form factors of up to 32 of the render's own shooters (ray
 * cast; at most 2 s). The image's PNG bytes come from a pilot image.
 * TB_ERR_UNSUPPORTED for adaptive
 * subdivision (o->adapt), which the model leaves out; the loader's and
 * solver's errors. */
tb_status tb_rad_predict_scene(const char *path, const tb_rad_render_options *o, double pilot_seconds,
                               tb_predict_stats *f);

#endif
