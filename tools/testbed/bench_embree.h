/* Embree 3 scenes for the benchmarks that compare with it (`testbed bench
 * rays --embree`, `testbed bench accel --scene ... --embree`): the scene's
 * meshes as Embree triangle geometries. Only with TB_HAVE_EMBREE. */
#ifndef TB_TOOLS_TESTBED_BENCH_EMBREE_H
#define TB_TOOLS_TESTBED_BENCH_EMBREE_H

#ifdef TB_HAVE_EMBREE
#include <embree3/rtcore.h>
#include <stdbool.h>

#include "host/render/scene.h"

/* Attaches every polygons object of `s` with triangles to `scene` as one
 * RTC_GEOMETRY_TYPE_TRIANGLE geometry (world-space float vertices, geometry
 * ID = object index, primitive ID = triangle of obj->mesh) of build quality
 * `quality`. False on failure, with a message prefixed by `prog` on stderr. */
bool tb_bench_embree_add_meshes(RTCDevice dev, RTCScene scene, const tb_scene *s, enum RTCBuildQuality quality,
                                const char *prog);
#endif

#endif
