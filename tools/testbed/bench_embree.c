/* Embree triangle geometries of a scene's meshes (bench_embree.h). */
#include "bench_embree.h"

#ifdef TB_HAVE_EMBREE
#include <stdio.h>
#include <string.h>

#include "util/math/transform.h"

bool tb_bench_embree_add_meshes(RTCDevice dev, RTCScene scene, const tb_scene *s, enum RTCBuildQuality quality,
                                const char *prog)
{
    for (uint32_t o = 0; o < s->nobjects; o++) {
        const tb_object *obj = s->objects[o];
        if (!obj->mesh || obj->mesh->ntris == 0)
            continue;
        const tb_object_mesh *m = obj->mesh;
        RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
        rtcSetGeometryBuildQuality(g, quality);
        float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                           m->nvertices);
        unsigned *ix = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                               m->ntris);
        if (!v || !ix) {
            fprintf(stderr, "%s: Embree buffer allocation failed\n", prog);
            rtcReleaseGeometry(g);
            return false;
        }
        for (uint32_t i = 0; i < m->nvertices; i++) {
            tb_vec3 w = tb_transform_point(&obj->to_world, m->vertices[i]);
            v[3 * i] = w.x, v[3 * i + 1] = w.y, v[3 * i + 2] = w.z;
        }
        memcpy(ix, m->tris, sizeof(unsigned) * 3 * (size_t)m->ntris);
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(scene, g, o);
        rtcReleaseGeometry(g);
    }
    return true;
}
#endif
