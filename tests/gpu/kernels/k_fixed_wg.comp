// A kernel with a fixed workgroup size instead of local_size_x_id = 0: host/gpu
// must refuse it (it cannot know how many groups to launch).
#version 450

layout(local_size_x = 64) in;
layout(std430, binding = 0) buffer Data { uint v[]; };

void main() { v[gl_GlobalInvocationID.x] = 1u; }
