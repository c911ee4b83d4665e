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

int tb_quadratic(double a, double b, double c, double r[2])
{
    if (!(isfinite(a) && isfinite(b) && isfinite(c)))
        return 0;
    /* A power-of-two scale keeps b^2 and 4ac away from overflow and
     * underflow without changing the roots or rounding anything. */
    double m = fmax(fabs(a), fmax(fabs(b), fabs(c)));
    if (m == 0.0)
        return 0; /* 0 = 0: every x, reported as none */
    if (m > 0x1p480 || m < 0x1p-480) {
        int e;
        frexp(m, &e);
        a = ldexp(a, -e);
        b = ldexp(b, -e);
        c = ldexp(c, -e);
    }
    if (a == 0.0) {
        if (b == 0.0)
            return 0;
        r[0] = -c / b;
        return isfinite(r[0]) ? 1 : 0;
    }
    double disc = tb_diff_of_products(b, b, 4.0 * a, c);
    if (disc < 0.0)
        return 0;
    double q = -0.5 * (b + copysign(sqrt(disc), b));
    if (q == 0.0) { /* b == 0 and disc == 0, so c == 0: double root at 0 */
        r[0] = r[1] = 0.0;
        return 2;
    }
    double x0 = q / a, x1 = c / q;
    if (x0 > x1) {
        double t = x0;
        x0 = x1;
        x1 = t;
    }
    int n = 0;
    if (isfinite(x0))
        r[n++] = x0;
    if (isfinite(x1))
        r[n++] = x1;
    return n;
}

int tb_quadraticf(float a, float b, float c, float r[2])
{
    if (!(isfinite(a) && isfinite(b) && isfinite(c)))
        return 0;
    float m = fmaxf(fabsf(a), fmaxf(fabsf(b), fabsf(c)));
    if (m == 0.0f)
        return 0;
    if (m > 0x1p60f || m < 0x1p-60f) {
        int e;
        frexpf(m, &e);
        a = ldexpf(a, -e);
        b = ldexpf(b, -e);
        c = ldexpf(c, -e);
    }
    if (a == 0.0f) {
        if (b == 0.0f)
            return 0;
        r[0] = -c / b;
        return isfinite(r[0]) ? 1 : 0;
    }
    float disc = tb_diff_of_productsf(b, b, 4.0f * a, c);
    if (disc < 0.0f)
        return 0;
    float q = -0.5f * (b + copysignf(sqrtf(disc), b));
    if (q == 0.0f) {
        r[0] = r[1] = 0.0f;
        return 2;
    }
    float x0 = q / a, x1 = c / q;
    if (x0 > x1) {
        float t = x0;
        x0 = x1;
        x1 = t;
    }
    int n = 0;
    if (isfinite(x0))
        r[n++] = x0;
    if (isfinite(x1))
        r[n++] = x1;
    return n;
}
