// Real roots of a x^2 + b x + c: the GLSL twin of tb_quadraticf()
// (util/roots/quadratic.c), step for step: exact c == 0 case, power-of-two
// balancing of extreme coefficients, Kahan's discriminant, the stable
// q = -(b + sign(b) sqrt(D)) / 2 with roots q/a and c/q, ascending order.
//
// Differences a Vulkan device may introduce (docs/gpu.md, "Tolerances"):
//  - fma() need not be fused. Where it is (lavapipe, most desktop GPUs) the
//    discriminant is Kahan's, within 1.5 ulp as in C; where it is not, it is
//    the naive b*b - 4ac, which can lose digits (and flip the root count)
//    when the two products nearly cancel, i.e. for nearly tangent rays.
//  - division is within 2.5 ulp and sqrt within about 3.5 ulp instead of
//    0.5: with a fused fma the roots agree with C's to 16 ulp on
//    well-separated roots (the paired kernel test checks this).
//  - denormal coefficients or roots may be flushed to zero.
#ifndef TB_LIB_QUADRATIC_GLSL
#define TB_LIB_QUADRATIC_GLSL

#include "float.glsl"

// a*b - c*d by Kahan's algorithm (tb_diff_of_productsf).
float tb_diff_of_products(float a, float b, float c, float d)
{
    precise float cd = c * d;
    precise float err = fma(-c, d, cd); // cd - c*d exactly, if fma() is fused
    precise float dop = fma(a, b, -cd);
    precise float r = dop + err;
    return r;
}

// Writes the real roots in ascending order to r0, r1 and returns how many
// (0, 1 or 2); a double root is returned twice. Unused outputs are 0.
int tb_quadratic(float a, float b, float c, out float r0, out float r1)
{
    r0 = 0.0;
    r1 = 0.0;
    if (!(tb_isfinite(a) && tb_isfinite(b) && tb_isfinite(c)))
        return 0;
    if (a == 0.0) {
        if (b == 0.0)
            return 0;
        precise float x = -c / b;
        r0 = x;
        return tb_isfinite(x) ? 1 : 0;
    }
    if (c == 0.0) { // x (a x + b): exact whatever the magnitudes
        precise float x = -b / a;
        if (!tb_isfinite(x))
            return 1;
        r0 = x < 0.0 ? x : 0.0;
        r1 = x < 0.0 ? 0.0 : (x == 0.0 ? 0.0 : x); // +0, never -0
        return 2;
    }
    int k = 0;
    const float lo = 8.6736173798840355e-19; // 2^-60
    const float hi = 1152921504606846976.0;   // 2^60
    float fa = abs(a), fb = abs(b), fc = abs(c);
    if (!(fa >= lo && fa <= hi && fc >= lo && fc <= hi && (b == 0.0 || (fb >= lo && fb <= hi)))) {
        // x = 2^k y balances a and c; then one power-of-two scale: all exact.
        int ea = tb_ilogb(a), ec = tb_ilogb(c);
        k = (ec - ea) / 2;
        int m = ea + 2 * k > ec ? ea + 2 * k : ec;
        if (b != 0.0 && tb_ilogb(b) + k > m)
            m = tb_ilogb(b) + k;
        a = ldexp(a, 2 * k - m);
        b = ldexp(b, k - m);
        c = ldexp(c, -m);
    }
    precise float disc = tb_diff_of_products(b, b, 4.0 * a, c);
    if (disc < 0.0)
        return 0;
    precise float s = sqrt(disc);
    precise float q = -0.5 * (b + (tb_signbit(b) ? -s : s));
    precise float x0 = q / a;
    precise float x1 = c / q;
    if (x0 > x1) {
        float t = x0;
        x0 = x1;
        x1 = t;
    }
    if (k != 0) {
        x0 = ldexp(x0, k);
        x1 = ldexp(x1, k);
    }
    int n = 0;
    if (tb_isfinite(x0)) {
        r0 = x0;
        n = 1;
    }
    if (tb_isfinite(x1)) {
        if (n == 0)
            r0 = x1;
        else
            r1 = x1;
        n++;
    }
    return n;
}

#endif
