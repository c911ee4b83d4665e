// Device self-test (tb_gpu_device_self_test, `testbed devices --check`):
// v[i] = v[i] * MUL + add for i < n, in 32-bit unsigned arithmetic, so the
// host knows every expected word exactly. Exercises what every kernel
// relies on: a storage buffer, push constants, a specialization constant and
// the host-chosen workgroup width.
#version 450

layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint MUL = 3u;

layout(std430, binding = 0) buffer Data { uint v[]; };
layout(push_constant) uniform Push {
    uint n;   // words to update
    uint add; // added to each
} pc;

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i < pc.n)
        v[i] = v[i] * MUL + pc.add;
}
