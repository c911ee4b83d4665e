// The Vulkan path tracer's stages that traverse the scene: extend (closest
// hit) and shadow (any hit), specialisation constant 1. The code:
// lib/pathtrace.glsl with TB_PT_TRACE; the other stages: pathtrace.comp.
#version 450
#extension GL_GOOGLE_include_directive : require

#define TB_PT_TRACE 1
#include "lib/pathtrace.glsl"
