// Float helpers for the kernels; the GLSL side of util/math/float.h.
//
// Vulkan's floating-point rules differ from C's (Vulkan spec, "Precision and
// Operation of SPIR-V Instructions"): add, subtract and multiply are correctly
// rounded, division is within 2.5 ulp, sqrt inherits 1/inversesqrt (2 ulp
// plus the division), fma() need not be fused, denormals may be flushed to
// zero, and NaN and signed zeros need not be preserved. So the routines here
// never rely on NaN, on the sign of a zero produced by arithmetic, or on
// infinities produced by overflow; they test bits instead. `precise` keeps the
// compiler from fusing a*b+c into an fma where the C code rounds twice
// (the C build uses -ffp-contract=off). docs/gpu.md lists each routine's
// tolerance against its C twin.
#ifndef TB_LIB_FLOAT_GLSL
#define TB_LIB_FLOAT_GLSL

// +infinity, made from its bits (a literal would be folded the same way, but
// this says what is meant).
float tb_inf() { return uintBitsToFloat(0x7f800000u); }

// True if x is neither infinite nor NaN, from its exponent bits (robust even
// where the compiler assumes no NaN).
bool tb_isfinite(float x) { return (floatBitsToUint(x) & 0x7f800000u) != 0x7f800000u; }

// The sign bit of x (true for -0.0), like C's signbit(); only meaningful for
// values read from memory, since arithmetic need not preserve -0.
bool tb_signbit(float x) { return (floatBitsToUint(x) & 0x80000000u) != 0u; }

// pbrt's gamma(n) = n u / (1 - n u), u = 2^-24, as tb_gamma() in C.
float tb_gamma(int n)
{
    precise float nu = float(n) * 5.9604644775390625e-8;
    precise float g = nu / (1.0 - nu);
    return g;
}

// ilogb(x) for normal x: the exponent e with 2^e <= |x| < 2^(e+1).
int tb_ilogb(float x)
{
    int e;
    frexp(x, e);
    return e - 1;
}

#endif
