// A kernel that runs until the host lets it go: each invocation hashes in a
// loop until word v[n] of its buffer (coherent, written by the host through
// a mapped buffer) is non-zero, or `iterations` steps have passed (a safety
// bound for devices whose buffers the host cannot write while the kernel
// runs). Used to test the submission timeout: the kernel cannot finish
// before the host releases it, however the host thread is scheduled.
#version 450

layout(local_size_x_id = 0) in;
layout(std430, binding = 0) coherent volatile buffer Data { uint v[]; };
layout(push_constant) uniform Push { uint n; uint iterations; } pc;

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.n)
        return;
    uint x = v[i];
    for (uint k = 0u; k < pc.iterations && v[pc.n] == 0u; k++) {
        x ^= x >> 16;
        x *= 0x7feb352du;
        x ^= x >> 15;
        x += k;
    }
    v[i] = x;
}
