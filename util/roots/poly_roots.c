/* Real roots of cubics and quartics by isolation between critical points.
 *
 * The real roots of p are separated by the real roots of p' (Rolle): between
 * two consecutive critical points p is monotone, so it has a root there
 * exactly when its values at the ends differ in sign. The critical points
 * come from the same solver one degree down (down to the quadratic formula),
 * the outermost intervals end at Fujiwara's root bound, and every root is
 * found by safeguarded Laguerre/Newton iteration on the original polynomial
 * with compensated evaluation (polish.c), so the sign tests and the roots
 * are accurate to the last bit even
 * when the closed-form (Cardano, Ferrari) formulas would lose digits or miss
 * a pair of close roots. This is the approach of C. Yuksel, "High-Performance
 * Polynomial Root Finding for Graphics" (HPG 2022), made exact-sign with
 * compensated Horner. A critical point where p is zero to within its rounding
 * error is a multiple root (tangent ray) and is reported with multiplicity. */
#include "util/roots/roots.h"

#include <limits.h>
#include <math.h>

#include "util/roots/roots_internal.h"

static int tb__roots_core(const double *a, int n, double *r);

/* A power of two at least Fujiwara's root bound 2 max_i |a_i/a_0|^(1/i)
 * (the last term with a_n/2) and at most 8 times it, from the exponents
 * alone (no roots taken, no rounding); 0 if a_1..a_n are all 0. */
static double tb__fujiwara(const double *a, int n)
{
    int e0 = tb__ilogb(a[0]), best = INT_MIN;
    for (int i = 1; i <= n; ++i) {
        if (a[i] == 0.0)
            continue;
        /* |a_i/a_0| < 2^e, e = ilogb(a_i) + 1 - ilogb(a_0), so its i-th root < 2^ceil(e/i) */
        int e = tb__ilogb(a[i]) + 1 - e0 - (i == n);
        int c = e >= 0 ? (e + i - 1) / i : -((-e) / i);
        if (c > best)
            best = c;
    }
    return best == INT_MIN ? 0.0 : tb__pow2(best + 1);
}

static int tb__sign(double v) { return v > 0.0 ? 1 : (v < 0.0 ? -1 : 0); }

/* Isolation for n >= 3 with a[0] != 0 and a[n] != 0, coefficients below 2^100. */
static int tb__isolate(const double *a, int n, double *r)
{
    double d[TB_POLY_MAX_DEGREE] = {0};
    for (int i = 0; i < n; ++i)
        d[i] = a[i] * (double)(n - i);
    double crit[TB_POLY_MAX_DEGREE];
    int nc = tb_poly_roots(d, n - 1, crit);

    /* Beyond 2^(890/n) a term of p could overflow (coefficients are below
     * 2^100), so the bound is capped there and the end values are then
     * evaluated. Unbalanced coefficients within 2^+-100 never reach the cap
     * (Fujiwara <= 2^201); balanced ones only with a tiny leading coefficient
     * that still fails the negligibility test, and roots beyond the cap are
     * then not reported. */
    double cap = tb__pow2(890 / n);
    double bound = tb__fujiwara(a, n);
    int capped = !(bound < cap);
    if (capped)
        bound = cap;
    /* No root is smaller in magnitude than 1 / (Fujiwara bound of the
     * reversed polynomial): [-low, low] holds none, so p has the sign of
     * a[n] there, and no bracket needs to reach 0 (brackets stay on one side
     * of 0, where bisection can work by binades). */
    double rev[TB_POLY_MAX_DEGREE + 1];
    for (int i = 0; i <= n; ++i)
        rev[i] = a[n - i];
    double low = 1.0 / tb__fujiwara(rev, n);
    if (!(low > 0.0) || !(low < bound))
        low = 0.0;

    double x[TB_POLY_MAX_DEGREE + 4], ap[TB_POLY_MAX_DEGREE + 4];
    int sg[TB_POLY_MAX_DEGREE + 4];
    int lead = a[0] > 0.0 ? 1 : -1, trail = a[n] > 0.0 ? 1 : -1;
    int m = 0;
    x[m] = -bound;
    sg[m] = (n & 1) ? -lead : lead;
    ap[m++] = INFINITY;
    for (int i = 0, side = -1; i <= nc; ++i) {
        /* the points -low, +low go in before the first critical point >= 0 */
        if (side < 0 && low > 0.0 && (i == nc || crit[i] >= 0.0)) {
            for (int k = -1; k <= 1; k += 2) {
                x[m] = k * low;
                sg[m] = trail;
                ap[m++] = INFINITY;
            }
            side = 1;
        }
        if (i == nc)
            break;
        if (!(crit[i] > -bound && crit[i] < bound) || fabs(crit[i]) < low)
            continue;
        tb__peval e = tb__poly_eval_quick(a, n, crit[i]);
        x[m] = crit[i];
        ap[m] = fabs(e.p);
        sg[m] = ap[m] <= tb__poly_band(n, e.abs) ? 0 : tb__sign(e.p);
        ++m;
    }
    x[m] = bound;
    sg[m] = lead;
    ap[m] = INFINITY;
    if (capped) {
        for (int j = 0; j <= m; j += m) {
            int s = tb__sign(tb__poly_eval(a, n, x[j]).p);
            if (s != 0)
                sg[j] = s;
        }
    }

    /* Walk the points: a sign change between neighbours is one simple root;
     * a run of critical points where p is 0 (to rounding) is one multiple
     * root, of multiplicity 1 + run length, made to agree in parity with the
     * signs on either side of the run. */
    int k = 0, i = 0;
    while (i < m && k < n) {
        int j = i + 1;
        if (sg[j] != 0) {
            if (sg[j] != sg[i]) {
                /* Start at the secant point when both values are known. */
                double t = ap[i] / (ap[i] + ap[j]), guess = x[i] + t * (x[j] - x[i]);
                r[k++] = tb__poly_bracketed(a, n, x[i], x[j], sg[i], isfinite(guess) ? guess : NAN);
            }
            i = j;
            continue;
        }
        int best = j, end = j;
        while (sg[end] == 0) {
            if (ap[end] < ap[best])
                best = end;
            ++end;
        }
        int mult = end - j + 1;
        if ((mult & 1) != (sg[i] != sg[end]))
            --mult;
        for (int q = 0; q < mult && k < n; ++q)
            r[k++] = x[best];
        i = end;
    }
    return k;
}

static int tb__roots_core(const double *a, int n, double *r)
{
    if (n <= 0)
        return 0;
    if (n == 1) {
        r[0] = -a[1] / a[0];
        return isfinite(r[0]) ? 1 : 0;
    }
    if (n == 2)
        return tb_quadratic(a[0], a[1], a[2], r);

    /* Negligible leading coefficient. With q(x) = p(x) - a0 x^n and R a
     * bound on the roots of q, |a0| R^n <= u/2 * sum_{i>=1} |a_i| R^(n-i)
     * says the dropped term is below half an ulp of q's own terms at every
     * root of q, so q's roots are roots of p to within p's rounding (a
     * backward-stable answer); they are then polished on p itself. The
     * remaining root of p is huge, -a1/a0 + a2/a1 to within ~u^2 relative. */
    if (a[1] != 0.0) {
        double R = tb__fujiwara(a + 1, n - 1);
        double s = 0.0, rp = 1.0;
        for (int i = 1; i <= n; ++i, rp *= R)
            if (a[i] != 0.0)
                s += fabs(a[i]) / rp;
        if (fabs(a[0]) * R <= 0x1p-54 * s) {
            int k = tb__roots_core(a + 1, n - 1, r);
            for (int i = 0; i < k; ++i)
                r[i] = tb_poly_polish(a, n, r[i], -INFINITY, INFINITY);
            double big = -a[1] / a[0] + a[2] / a[1];
            if (isfinite(big))
                r[k++] = big;
            return k;
        }
    }
    return tb__isolate(a, n, r);
}

int tb_poly_roots(const double *coef, int degree, double *r)
{
    if (!coef || !r || degree < 0 || degree > TB_POLY_MAX_DEGREE)
        return 0;
    int in_range = 1, off = -1;
    for (int i = 0; i <= degree; ++i) {
        if (!isfinite(coef[i]))
            return 0;
        double m = fabs(coef[i]);
        if (m != 0.0 && off < 0)
            off = i;
        in_range &= m == 0.0 || (m >= 0x1p-100 && m <= 0x1p100);
    }
    if (off < 0)
        return 0; /* 0 = 0 holds for every x: reported as no roots */
    int n = degree - off;
    if (n <= 2) { /* the closed forms handle any scale themselves */
        if (n == 2)
            return tb_quadratic(coef[off], coef[off + 1], coef[off + 2], r);
        if (n == 0)
            return 0; /* a nonzero constant */
        r[0] = -coef[off + 1] / coef[off];
        return isfinite(r[0]) ? 1 : 0;
    }
    double a[TB_POLY_MAX_DEGREE + 1];
    for (int i = 0; i <= n; ++i)
        a[i] = coef[off + i];

    /* Zero constant terms are exact roots at 0; divide them out. */
    int k = 0;
    while (a[n] == 0.0) {
        r[k++] = 0.0;
        --n;
    }

    /* Coefficients beyond 2^+-100: substitute x = 2^shift y, with shift
     * making the first and last coefficients about equal, and scale by one
     * power of two so the largest is in [1, 2); all exact, and no product of
     * a coefficient and a power of a root then over- or underflows before the
     * root itself does. A coefficient that still underflows (the set spans
     * more than ~2^1000 after balancing) becomes 0. */
    int shift = 0;
    if (!in_range && n > 0) {
        shift = (ilogb(a[n]) - ilogb(a[0])) / n;
        int top = INT_MIN;
        for (int i = 0; i <= n; ++i)
            if (a[i] != 0.0 && ilogb(a[i]) + (n - i) * shift > top)
                top = ilogb(a[i]) + (n - i) * shift;
        for (int i = 0; i <= n; ++i)
            a[i] = ldexp(a[i], (n - i) * shift - top);
        int lead = 0;
        while (a[lead] == 0.0)
            ++lead;
        for (int i = 0; lead > 0 && i + lead <= n; ++i)
            a[i] = a[i + lead];
        n -= lead;
        while (n > 0 && a[n] == 0.0) {
            r[k++] = 0.0;
            --n;
        }
    }
    int z = k;
    k += tb__roots_core(a, n, r + k);
    if (shift != 0) { /* back to x, dropping roots that overflow */
        int kept = z;
        for (int i = z; i < k; ++i) {
            double x = ldexp(r[i], shift);
            if (isfinite(x))
                r[kept++] = x;
        }
        k = kept;
    }

    for (int i = 1; i < k; ++i) /* insertion sort: k <= 4 */
        for (int j = i; j > 0 && r[j - 1] > r[j]; --j) {
            double t = r[j];
            r[j] = r[j - 1];
            r[j - 1] = t;
        }
    return k;
}

int tb_cubic(double a, double b, double c, double d, double r[3])
{
    const double coef[4] = {a, b, c, d};
    return tb_poly_roots(coef, 3, r);
}

int tb_quartic(double a, double b, double c, double d, double e, double r[4])
{
    const double coef[5] = {a, b, c, d, e};
    return tb_poly_roots(coef, 4, r);
}
