/* Internals shared by the files of util/roots (not installed). */
#ifndef TB_UTIL_ROOTS_ROOTS_INTERNAL_H
#define TB_UTIL_ROOTS_ROOTS_INTERNAL_H

#include <math.h>
#include <stdint.h>
#include <string.h>

/* ilogb(x) without the libm call for normal x (the exponent field), the
 * call itself for 0, subnormals, Inf and NaN: the same value in every case. */
static inline int tb__ilogb(double x)
{
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    int e = (int)((u >> 52) & 0x7ff);
    return e != 0 && e != 0x7ff ? e - 1023 : ilogb(x);
}

/* 2^k, exactly ldexp(1.0, k), built from the bits when it is a normal double. */
static inline double tb__pow2(int k)
{
    if (k < -1022 || k > 1023)
        return ldexp(1.0, k);
    uint64_t u = (uint64_t)(k + 1023) << 52;
    double x;
    memcpy(&x, &u, sizeof x);
    return x;
}

/* Unit roundoff of double, 2^-53. */
#define TB__ROOTS_U 0x1p-53

/* One polynomial evaluation with what the root finders need beside the value. */
typedef struct tb__peval {
    double p;   /* p(x) by compensated Horner */
    double dp;  /* p'(x) by plain Horner (only steers the iteration) */
    double ddp; /* p''(x) by plain Horner */
    double abs; /* sum |a_i| |x|^(n-i): scale of the rounding errors at x */
} tb__peval;

/* Evaluates a[0..n] (highest power first) at x. */
tb__peval tb__poly_eval(const double *a, int n, double x);

/* Like tb__poly_eval, but plain Horner when its sign is already certain
 * (|p| well above its error bound); compensated only near a root. */
tb__peval tb__poly_eval_quick(const double *a, int n, double x);

/* Half-width of the band around 0 inside which the sign of a compensated
 * value is not certain: |p_computed - p| <= u |p| + gamma(2n)^2 * abs
 * (Graillat, Langlois, Louvet 2009), with a factor 2 of margin. */
static inline double tb__poly_band(int n, double abs)
{
    double g = 2.0 * n * TB__ROOTS_U;
    return 2.0 * g * g * abs + 0x1p-1070;
}

/* The root of a[0..n] in [lo, hi], where p(lo) has sign slo (+1 or -1) and
 * p(hi) the other sign; x is the first guess (ignored unless inside). Hybrid
 * Newton/bisection on compensated values: within about 1 ulp of the root. */
double tb__poly_bracketed(const double *a, int n, double lo, double hi, int slo, double x);

#endif
