/* Type spellings for data layouts shared by C and GLSL (after Falcor's
 * HostDeviceShared.slangh): each shaders/shared/<name>.h is compiled by both the C
 * compiler and glslang, which defines VULKAN when compiling for Vulkan
 * (GL_core_profile covers an OpenGL compile).
 *
 * Layout rules (std430 on the GLSL side, checked by _Static_assert on the C side):
 *  - only 4-byte scalars (float, uint/uint32_t, int/int32_t) and vec3; never
 *    bool (4 bytes in GLSL, 1 in C) and no double;
 *  - a vec3 has 16-byte alignment in std430 but 4 in C (tb_vec3): it must sit
 *    at an offset that is a multiple of 16 and be followed by a 4-byte scalar,
 *    so both sides put the next member 12 bytes later;
 *  - a struct holding a vec3 is 16-byte aligned in std430: its size must be a
 *    multiple of 16 so that array strides agree;
 *  - arrays of scalars inside a struct have stride 4 in std430 (not 16 as in
 *    std140): use std430 buffers only;
 *  - explicit padding members (pad0, pad1...) instead of implicit holes.
 * The C side of every header asserts each struct's size and member offsets. */
#ifndef TB_SHADERS_SHARED_TYPES_H
#define TB_SHADERS_SHARED_TYPES_H

#if defined(VULKAN) || defined(GL_core_profile)
#define TB_GPU_GLSL 1
#define TB_GPU_UINT uint
#define TB_GPU_INT int
#define TB_GPU_VEC3 vec3
#else
#include <stddef.h>
#include <stdint.h>

#include "util/math/vec.h"

#define TB_GPU_UINT uint32_t
#define TB_GPU_INT int32_t
#define TB_GPU_VEC3 tb_vec3
_Static_assert(sizeof(tb_vec3) == 12, "tb_vec3 must be three packed floats to match a GLSL vec3");
#endif

#endif
