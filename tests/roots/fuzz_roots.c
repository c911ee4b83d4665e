/* libFuzzer target for util/roots: arbitrary coefficients (NaN, Inf,
 * subnormal, huge, zero) must give a count within the degree, finite sorted
 * roots, and, where nothing over- or underflows, roots with a small backward
 * error (|p(x)| against sum |c_i||x|^(n-i), long double reference). */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "roots_ref.h"
#include "util/roots/roots.h"

#define CHECK(cond)                                                                                          \
    do {                                                                                                     \
        if (!(cond))                                                                                         \
            __builtin_trap();                                                                                \
    } while (0)

/* True when backward errors are meaningful: nonzero coefficients and the
 * roots stay well inside the exponent range (no over/underflow in p). */
static int tame(const double *c, int n, const double *r, int k)
{
    for (int i = 0; i <= n; ++i)
        if (c[i] != 0.0 && !(fabs(c[i]) >= 0x1p-300 && fabs(c[i]) <= 0x1p300))
            return 0;
    for (int i = 0; i < k; ++i)
        if (r[i] != 0.0 && !(fabs(r[i]) >= 0x1p-60 && fabs(r[i]) <= 0x1p60))
            return 0;
    return 1;
}

static void check_roots(const double *c, int n, const double *r, int k, double max_backward)
{
    CHECK(k >= 0 && k <= n);
    for (int i = 0; i < k; ++i) {
        CHECK(isfinite(r[i]));
        CHECK(i == 0 || r[i - 1] <= r[i]);
    }
    if (tame(c, n, r, k))
        for (int i = 0; i < k; ++i)
            CHECK(ref_backward(c, n, r[i]) <= max_backward);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1 + sizeof(double))
        return 0;
    uint8_t op = data[0];
    double c[6] = {0};
    size_t nc = (size - 1) / sizeof(double);
    if (nc > 6)
        nc = 6;
    memcpy(c, data + 1, nc * sizeof(double));

    double r[4];
    int n = 2 + op % 3; /* 2, 3 or 4 */
    int k = tb_poly_roots(c, n, r);
    /* a root within k ulps has backward error <= 2 k n u: k = 4 for the
     * quadratic, k <= 2 elsewhere (1 ulp, or the degree-drop huge root) */
    check_roots(c, n, r, k, n == 2 ? 8.0 * n + 1.0 : 4.0 * n);
    if (n == 2) {
        double rq[2];
        int kq = tb_quadratic(c[0], c[1], c[2], rq);
        CHECK(kq == k && (kq < 1 || rq[0] == r[0]) && (kq < 2 || rq[1] == r[1]));
        float rf[2];
        int kf = tb_quadraticf((float)c[0], (float)c[1], (float)c[2], rf);
        CHECK(kf >= 0 && kf <= 2);
        for (int i = 0; i < kf; ++i)
            CHECK(isfinite(rf[i]) && (i == 0 || rf[0] <= rf[1]));
    }

    /* Polishing never raises |p| (by its own evaluation) and respects the bracket. */
    if (nc == 6 && isfinite(c[5])) {
        double lo = (op & 8) ? c[5] - 1.0 : -INFINITY, hi = (op & 8) ? c[5] + 1.0 : INFINITY;
        double x = tb_poly_polish(c, n, c[5], lo, hi);
        CHECK(!isnan(x));
        if (op & 8)
            CHECK(x >= lo && x <= hi);
        double p0 = tb_poly_eval(c, n, c[5], NULL), p1 = tb_poly_eval(c, n, x, NULL);
        if (isfinite(p0) && isfinite(p1))
            CHECK(fabs(p1) <= fabs(p0));
    }
    return 0;
}
