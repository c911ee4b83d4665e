// Layout round trip: reads rays in the shared C/GLSL layout and writes hits
// and rays whose every field is a known function of the input, so the host
// can check that both sides agree on every offset (shared/ray.h, shared/hit.h).
#version 450
#extension GL_GOOGLE_include_directive : require
#include "shared/ray.h"
#include "shared/hit.h"

layout(local_size_x_id = 0) in;
layout(std430, binding = 0) readonly buffer Rays { tb_gpu_ray rays[]; };
layout(std430, binding = 1) writeonly buffer Hits { tb_gpu_hit hits[]; };
layout(std430, binding = 2) writeonly buffer RaysOut { tb_gpu_ray rays_out[]; };
layout(push_constant) uniform Push { uint n; } pc;

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.n)
        return;
    tb_gpu_ray r = rays[i];
    tb_gpu_hit h;
    h.t = r.o.x;
    h.object = i;
    h.face = ~i;
    h.u = r.o.y;
    h.v = r.o.z;
    h.ng[0] = r.tmin;
    h.ng[1] = r.d.x;
    h.ng[2] = r.d.y;
    hits[2 * i] = h;
    h.t = r.d.z;
    h.object = TB_GPU_NO_HIT;
    h.face = 7u;
    h.u = r.tmax;
    h.v = 0.0;
    h.ng[0] = 0.0;
    h.ng[1] = 0.0;
    h.ng[2] = 0.0;
    hits[2 * i + 1] = h;
    // Swap the roles of the fields: o <- d, tmin <- tmax, d <- o, tmax <- tmin.
    rays_out[i] = tb_gpu_ray(r.d, r.tmax, r.o, r.tmin);
}
