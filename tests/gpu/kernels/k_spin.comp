// A kernel that runs for a while: a dependent chain of `iterations` integer
// hash steps per invocation (no closed form, so no compiler can shorten it).
// Used to test the submission timeout.
#version 450

layout(local_size_x_id = 0) in;
layout(std430, binding = 0) buffer Data { uint v[]; };
layout(push_constant) uniform Push { uint n; uint iterations; } pc;

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.n)
        return;
    uint x = v[i];
    for (uint k = 0u; k < pc.iterations; k++) {
        x ^= x >> 16;
        x *= 0x7feb352du;
        x ^= x >> 15;
        x += k;
    }
    v[i] = x;
}
