/* Adaptive exact orientation test (Shewchuk 1997), written for this project.
 * The exact stage expands the determinant into six products of input
 * coordinates, each split exactly into a head and a tail (Dekker's product),
 * and sums the twelve doubles into a non-overlapping expansion whose most
 * significant component carries the exact sign. That is slower than
 * Shewchuk's staged B/C/D refinements but far simpler, and it only runs when
 * the first, cheap test is inconclusive. */
#include "util/mesh/predicates.h"

/* Half the machine epsilon, 2^-53. */
#define TB__EPS 0x1p-53
/* Shewchuk's ccwerrboundA: |det - computed| <= bound * (|detleft| + |detright|). */
#define TB__CCW_BOUND_A ((3.0 + 16.0 * TB__EPS) * TB__EPS)
/* 2^27 + 1: splits a double into two 26-bit halves (Veltkamp/Dekker). */
#define TB__SPLITTER 134217729.0

/* x + y == a + b exactly, x = fl(a + b) (Knuth's TwoSum, no ordering needed). */
static inline void tb__two_sum(double a, double b, double *x, double *y)
{
    double s = a + b;
    double bv = s - a;
    double av = s - bv;
    *x = s;
    *y = (a - av) + (b - bv);
}

/* hi + lo == a, each with at most 26 significant bits. */
static inline void tb__split(double a, double *hi, double *lo)
{
    double c = TB__SPLITTER * a;
    double big = c - a;
    *hi = c - big;
    *lo = a - *hi;
}

/* x + y == a * b exactly, x = fl(a * b) (Dekker's product; no FMA needed). */
static inline void tb__two_product(double a, double b, double *x, double *y)
{
    double p = a * b, ahi, alo, bhi, blo;
    tb__split(a, &ahi, &alo);
    tb__split(b, &bhi, &blo);
    double err1 = p - ahi * bhi;
    double err2 = err1 - alo * bhi;
    double err3 = err2 - ahi * blo;
    *x = p;
    *y = alo * blo - err3;
}

/* Adds b to the non-overlapping expansion e[0..n-1] (increasing magnitude),
 * in place, dropping zero components; returns the new length (<= n + 1). */
static int tb__grow_expansion(double *e, int n, double b)
{
    double q = b;
    int m = 0;
    for (int i = 0; i < n; i++) {
        double h;
        tb__two_sum(q, e[i], &q, &h);
        if (h != 0.0)
            e[m++] = h;
    }
    if (q != 0.0 || m == 0)
        e[m++] = q;
    return m;
}

double tb_orient2d_fast(double ax, double ay, double bx, double by, double cx, double cy)
{
    return (ax - cx) * (by - cy) - (ay - cy) * (bx - cx);
}

/* The determinant expanded over the input coordinates:
 * ax by - ax cy - cx by - ay bx + ay cx + cy bx (the cx cy terms cancel). */
static double tb__orient2d_exact(double ax, double ay, double bx, double by, double cx, double cy)
{
    const double f[6][2] = {{ax, by}, {-ax, cy}, {-cx, by}, {-ay, bx}, {ay, cx}, {cy, bx}};
    double e[13];
    int n = 0;
    for (int i = 0; i < 6; i++) {
        double hi, lo;
        tb__two_product(f[i][0], f[i][1], &hi, &lo);
        n = tb__grow_expansion(e, n, lo);
        n = tb__grow_expansion(e, n, hi);
    }
    return e[n - 1]; /* the largest component has the sign of the sum */
}

double tb_orient2d(double ax, double ay, double bx, double by, double cx, double cy)
{
    double detleft = (ax - cx) * (by - cy);
    double detright = (ay - cy) * (bx - cx);
    double det = detleft - detright, detsum;
    if (detleft > 0.0) {
        if (detright <= 0.0)
            return det; /* no cancellation: the sign is right */
        detsum = detleft + detright;
    } else if (detleft < 0.0) {
        if (detright >= 0.0)
            return det;
        detsum = -detleft - detright;
    } else {
        /* detleft is exactly zero only if a factor is (differences of doubles
         * are zero only for equal inputs), so det == -detright exactly,
         * unless the product underflowed, which the input range excludes. */
        return det;
    }
    double bound = TB__CCW_BOUND_A * detsum;
    if (det >= bound || -det >= bound)
        return det;
    return tb__orient2d_exact(ax, ay, bx, by, cx, cy);
}
