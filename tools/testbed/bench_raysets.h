/* The first bounce of a render as ray sets for `testbed bench rays` and
 * `testbed bench gpu`: from the first hits of a set of primary rays, one
 * shadow ray toward a light and one cosine-distributed diffuse ray each, spawned
 * as the renderer spawns them (tb_object_hit_point, tb_spawn_ray_origin). */
#ifndef TB_TOOLS_TESTBED_BENCH_RAYSETS_H
#define TB_TOOLS_TESTBED_BENCH_RAYSETS_H

#include <stddef.h>

#include "host/render/lights.h"
#include "host/render/scene.h"
#include "util/math/rng.h"

/* Appends to shadow[*nshadow] and diffuse[*ndiffuse] (room for np each) the
 * secondary rays of primary[0..np), drawing 4 numbers from rng per hit: shadow
 * rays toward `area` when not NULL, else toward one of the scene's lights.
 * Returns how many hits gave no shadow ray (behind a one-sided emitter, outside
 * a spot cone, no light). */
size_t tb_bench_secondary_rays(const tb_scene *s, const tb_area_light *area, const tb_ray *primary, size_t np,
                               tb_rng *rng, tb_ray *shadow, size_t *nshadow, tb_ray *diffuse, size_t *ndiffuse);

#endif
