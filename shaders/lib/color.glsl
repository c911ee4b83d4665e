// sRGB transfer curve and linear sRGB <-> CIE XYZ: the GLSL twins of
// tb_srgb_encode/decode and tb_linear_srgb_to_xyz/tb_xyz_to_linear_srgb
// (util/color/srgb.c).
//
// The C functions compute in double and round once; the kernels compute in
// float. Tolerances (docs/gpu.md):
//  - encode/decode: same branches (the float knees below make `x <= knee`
//    decide exactly as C's double comparison does); pow() on a Vulkan device
//    is only as good as exp2(y log2 x), up to about 20 ulp, so the results
//    agree with C's to 4e-6 absolute (encode) and 2^-16 relative (decode):
//    both far below half a 16-bit code step (7.6e-6).
//  - matrices: the double matrices rounded to float (entries below), products
//    and sums in the order C uses, precise (no fused multiply-adds). Against
//    C's double result each component is within 5 * 2^-23 * sum_j |m_ij x_j|;
//    for a unit input vector it is exactly the float entry.
#ifndef TB_LIB_COLOR_GLSL
#define TB_LIB_COLOR_GLSL

// Largest floats <= 0.0031308 and <= 0.04045: for a float x, x <= knee here
// exactly when (double)x <= 0.0031308 (resp. 0.04045) in C.
// (Bits 0x3b4d2e1b and 0x3d25aee6; the literals are their exact decimal values.)
const float TB_SRGB_ENCODE_KNEE = 0.0031307998578995466;
const float TB_SRGB_DECODE_KNEE = 0.040449999272823334;

// Linear value -> sRGB-encoded value; inputs outside [0, 1] are clamped.
float tb_srgb_encode(float x)
{
    if (!(x > 0.0))
        return 0.0;
    if (x >= 1.0)
        return 1.0;
    if (x <= TB_SRGB_ENCODE_KNEE) {
        precise float y = 12.92 * x;
        return y;
    }
    precise float p = pow(x, 1.0 / 2.4);
    precise float y = 1.055 * p - 0.055;
    return y;
}

// sRGB-encoded value -> linear value; inputs outside [0, 1] are clamped.
float tb_srgb_decode(float v)
{
    if (!(v > 0.0))
        return 0.0;
    if (v >= 1.0)
        return 1.0;
    if (v <= TB_SRGB_DECODE_KNEE) {
        precise float y = v / 12.92;
        return y;
    }
    precise float base = (v + 0.055) / 1.055;
    return pow(base, 2.4);
}

// tb_srgb_to_xyz_matrix rounded to float, row by row.
const float TB_SRGB_TO_XYZ[9] = float[9](
    0.412390798, 0.357584327, 0.180480793,
    0.212639004, 0.715168655, 0.0721923187,
    0.0193308182, 0.119194783, 0.950532138);

// tb_xyz_to_srgb_matrix rounded to float, row by row.
const float TB_XYZ_TO_SRGB[9] = float[9](
    3.2409699, -1.5373832, -0.498610765,
    -0.969243646, 1.8759675, 0.0415550582,
    0.0556300804, -0.203976959, 1.05697155);

// m (row-major, 9 entries) times v, each row as m0 v.x + m1 v.y + m2 v.z in that order.
vec3 tb_mat3_apply(const float m[9], vec3 v)
{
    precise float x = m[0] * v.x + m[1] * v.y + m[2] * v.z;
    precise float y = m[3] * v.x + m[4] * v.y + m[5] * v.z;
    precise float z = m[6] * v.x + m[7] * v.y + m[8] * v.z;
    return vec3(x, y, z);
}

// Linear sRGB -> CIE XYZ (Y = 1 for white).
vec3 tb_linear_srgb_to_xyz(vec3 rgb) { return tb_mat3_apply(TB_SRGB_TO_XYZ, rgb); }

// CIE XYZ -> linear sRGB (no clamping).
vec3 tb_xyz_to_linear_srgb(vec3 xyz) { return tb_mat3_apply(TB_XYZ_TO_SRGB, xyz); }

#endif
