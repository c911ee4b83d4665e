// The Vulkan path tracer's stages without ray traversal: init, shade,
// accumulate (specialisation constant 1). The code: lib/pathtrace.glsl;
// the traversing stages: pathtrace_trace.comp.
#version 450
#extension GL_GOOGLE_include_directive : require

#include "lib/pathtrace.glsl"
