/* Quadratic equations in double and float.
 *
 * The stable form q = -(b + sign(b) sqrt(D)) / 2, roots q/a and c/q, never
 * subtracts nearly equal numbers, and Kahan's difference of products (with
 * explicit fma) gives the discriminant D = b^2 - 4ac with relative error at
 * most 2u (Jeannerod, Louvet, Muller 2013). Together every root is within
 * about 4 ulps of the exact root of the given coefficients, even for nearly
 * tangent rays, and the root count is exact: the sign of D is never wrong. */
#include "util/roots/roots.h"

#include <math.h>

#include "util/math/float.h"

/* Both solvers follow the same steps; the double one is commented. (The
 * double one's common case, no early exit and no rescaling, is also inline
 * in roots.h as tb_quadratic; this is its general path.)
 *
 * Overflow and underflow: when every nonzero coefficient lies within
 * 2^+-480 (2^+-60 for float) no product in the discriminant can overflow or
 * lose digits to underflow. Otherwise x = 2^k y is substituted with k chosen
 * so that the y^2 and constant coefficients have about the same exponent,
 * then all three are scaled by one power of two to a largest in [1, 2): all
 * exact, and it leaves b^2 or 4ac negligible whenever either underflows. */
int tb__quadratic_general(double a, double b, double c, double r[2])
{
    if (!(isfinite(a) && isfinite(b) && isfinite(c)))
        return 0;
    if (a == 0.0) {
        if (b == 0.0)
            return 0; /* c = 0: none, or every x when c == 0 (reported as none) */
        r[0] = -c / b;
        return isfinite(r[0]) ? 1 : 0;
    }
    if (c == 0.0) { /* x (a x + b): exact, whatever the magnitudes */
        double x = -b / a + 0.0; /* + 0.0 turns -0 into +0 */
        r[0] = 0.0;
        if (!isfinite(x))
            return 1;
        r[0] = x < 0.0 ? x : 0.0;
        r[1] = x < 0.0 ? 0.0 : x;
        return 2;
    }
    int k = 0;
    const double lo = 0x1p-480, hi = 0x1p480;
    double fa = fabs(a), fb = fabs(b), fc = fabs(c);
    if (!(fa >= lo && fa <= hi && fc >= lo && fc <= hi && (b == 0.0 || (fb >= lo && fb <= hi)))) {
        int ea = ilogb(a), ec = ilogb(c);
        k = (ec - ea) / 2;
        int m = ea + 2 * k > ec ? ea + 2 * k : ec;
        if (b != 0.0 && ilogb(b) + k > m)
            m = ilogb(b) + k;
        a = ldexp(a, 2 * k - m);
        b = ldexp(b, k - m);
        c = ldexp(c, -m);
    }
    return tb__quadratic_solve(a, b, c, k, r);
}

int tb_quadraticf(float a, float b, float c, float r[2])
{
    if (!(isfinite(a) && isfinite(b) && isfinite(c)))
        return 0;
    if (a == 0.0f) {
        if (b == 0.0f)
            return 0;
        r[0] = -c / b;
        return isfinite(r[0]) ? 1 : 0;
    }
    if (c == 0.0f) {
        float x = -b / a + 0.0f;
        r[0] = 0.0f;
        if (!isfinite(x))
            return 1;
        r[0] = x < 0.0f ? x : 0.0f;
        r[1] = x < 0.0f ? 0.0f : x;
        return 2;
    }
    int k = 0;
    const float lo = 0x1p-60f, hi = 0x1p60f;
    float fa = fabsf(a), fb = fabsf(b), fc = fabsf(c);
    if (!(fa >= lo && fa <= hi && fc >= lo && fc <= hi && (b == 0.0f || (fb >= lo && fb <= hi)))) {
        int ea = ilogbf(a), ec = ilogbf(c);
        k = (ec - ea) / 2;
        int m = ea + 2 * k > ec ? ea + 2 * k : ec;
        if (b != 0.0f && ilogbf(b) + k > m)
            m = ilogbf(b) + k;
        a = ldexpf(a, 2 * k - m);
        b = ldexpf(b, k - m);
        c = ldexpf(c, -m);
    }
    float disc = tb_diff_of_productsf(b, b, 4.0f * a, c);
    if (disc < 0.0f)
        return 0;
    float q = -0.5f * (b + copysignf(sqrtf(disc), b));
    float x0 = q / a, x1 = c / q;
    if (x0 > x1) {
        float t = x0;
        x0 = x1;
        x1 = t;
    }
    if (k != 0) {
        x0 = ldexpf(x0, k);
        x1 = ldexpf(x1, k);
    }
    int n = 0;
    if (isfinite(x0))
        r[n++] = x0;
    if (isfinite(x1))
        r[n++] = x1;
    return n;
}
