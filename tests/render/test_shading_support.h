/* Numerical tools shared by the shading, light and IES tests: Gauss-Legendre
 * quadrature over the sphere, and Pearson's chi-square goodness-of-fit test of
 * a direction sampler against its density, following Mitsuba 3's
 * src/python/python/chi2.py (Jakob et al.): directions are binned over
 * (phi, cos theta), an equal-area parameterisation of the sphere, the
 * expected count of every bin is the integral of the pdf over it (here by
 * adaptive Gauss-Legendre cubature instead of a fixed trapezoid rule, so narrow
 * lobes are integrated accurately), bins with an expected count below 5 are
 * pooled, and the hypothesis "the samples follow the pdf" is rejected when
 * the p-value of the statistic (regularised upper incomplete gamma function)
 * falls below the significance level. Everything is deterministic for a
 * fixed seed. */
#ifndef TB_TESTS_RENDER_TEST_SHADING_SUPPORT_H
#define TB_TESTS_RENDER_TEST_SHADING_SUPPORT_H

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util/math/rng.h"
#include "util/math/vec.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* ------------------------------------------------------- Gauss-Legendre */

/* Most nodes of one rule. */
#define TST_GL_MAX 64

/* Nodes x[k] and weights w[k] of the n-point Gauss-Legendre rule on [-1, 1]
 * (Newton's iteration on P_n from Chebyshev starting points). */
static inline void tst_gauss_legendre(int n, double *x, double *w)
{
    for (int i = 0; i < (n + 1) / 2; i++) {
        double z = cos(M_PI * (i + 0.75) / (n + 0.5)), pp = 0.0;
        for (int it = 0; it < 100; it++) {
            double p0 = 1.0, p1 = 0.0;
            for (int j = 1; j <= n; j++) {
                double p2 = p1;
                p1 = p0;
                p0 = ((2.0 * j - 1.0) * z * p1 - (j - 1.0) * p2) / j;
            }
            pp = n * (z * p0 - p1) / (z * z - 1.0);
            double dz = p0 / pp;
            z -= dz;
            if (fabs(dz) < 1e-16)
                break;
        }
        x[i] = -z;
        x[n - 1 - i] = z;
        w[i] = w[n - 1 - i] = 2.0 / ((1.0 - z * z) * pp * pp);
    }
}

/* A scalar function of a unit direction. */
typedef double (*tst_dir_fn)(void *ctx, tb_vec3 w);

/* Direction of (phi, z = cos theta). */
static inline tb_vec3 tst_dir(double phi, double z)
{
    double s = sqrt(fmax(0.0, 1.0 - z * z));
    return tb_vec3_make((float)(s * cos(phi)), (float)(s * sin(phi)), (float)z);
}

/* Integral of fn over the directions within tmax of `pole` (tmax = pi: the
 * whole sphere; pi/2: the hemisphere about the pole), by composite
 * Gauss-Legendre in spherical coordinates about the pole (unit): theta in
 * [0, tmax] split into nt panels graded quadratically (edges tmax (k/nt)^2, so a lobe
 * centred on the pole gets small panels), phi in np equal panels, `order`
 * points per panel and direction. Put the pole at the centre of a narrow lobe:
 * the grid then resolves lobes far narrower than a uniform one could. The
 * integrand should be smooth inside the region: f |cos theta| is continuous
 * for every model here but has a kink at the horizon, which costs digits
 * unless the horizon is the region's edge (pole = normal, tmax = pi/2). */
static inline double tst_integrate_sphere(tst_dir_fn fn, void *ctx, tb_vec3 pole, double tmax,
                                          int nt, int np, int order)
{
    double x[TST_GL_MAX], w[TST_GL_MAX];
    tst_gauss_legendre(order, x, w);
    tb_vec3 b1, b2;
    tb_vec3_basis(pole, &b1, &b2);
    double sum = 0.0, hp = 2.0 * M_PI / np;
    for (int a = 0; a < nt; a++) {
        double ta = tmax * ((double)a / nt) * ((double)a / nt);
        double tb = tmax * ((double)(a + 1) / nt) * ((double)(a + 1) / nt);
        double ht = tb - ta, panel = 0.0;
        for (int i = 0; i < order; i++) {
            double t = ta + ht * 0.5 * (x[i] + 1.0);
            double st = sin(t), ct = cos(t);
            double row = 0.0;
            for (int b = 0; b < np; b++)
                for (int j = 0; j < order; j++) {
                    double p = hp * (b + 0.5 * (x[j] + 1.0));
                    double lx = st * cos(p), ly = st * sin(p);
                    tb_vec3 d = tb_vec3_make((float)(lx * b1.x + ly * b2.x + ct * pole.x),
                                             (float)(lx * b1.y + ly * b2.y + ct * pole.y),
                                             (float)(lx * b1.z + ly * b2.z + ct * pole.z));
                    row += w[j] * fn(ctx, d);
                }
            panel += w[i] * st * row;
        }
        sum += panel * 0.5 * ht;
    }
    return sum * 0.5 * hp;
}

/* ------------------------------------------------ incomplete gamma, p-value */

/* Regularised upper incomplete gamma Q(a, x) = Gamma(a, x) / Gamma(a):
 * series for x < a + 1, Lentz's continued fraction otherwise. */
static inline double tst_gamma_q(double a, double x)
{
    if (x <= 0.0)
        return 1.0;
    double gln = lgamma(a);
    if (x < a + 1.0) {
        double ap = a, sum = 1.0 / a, del = sum;
        for (int n = 0; n < 100000; n++) {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if (fabs(del) < fabs(sum) * 1e-15)
                break;
        }
        return 1.0 - sum * exp(-x + a * log(x) - gln);
    }
    double b = x + 1.0 - a, c = 1.0 / 1e-300, d = 1.0 / b, h = d;
    for (int i = 1; i < 100000; i++) {
        double an = -i * (i - a);
        b += 2.0;
        d = an * d + b;
        if (fabs(d) < 1e-300)
            d = 1e-300;
        c = b + an / c;
        if (fabs(c) < 1e-300)
            c = 1e-300;
        d = 1.0 / d;
        double del = d * c;
        h *= del;
        if (fabs(del - 1.0) < 1e-15)
            break;
    }
    return exp(-x + a * log(x) - gln) * h;
}

/* ------------------------------------------------------------ chi-square */

/* Draws one direction from uniform numbers (uc, u1, u2); false if the
 * sampler produced none (the sample then counts in no bin). */
typedef bool (*tst_sample_fn)(void *ctx, float uc, float u1, float u2, tb_vec3 *w);

/* Result of one chi-square run. */
typedef struct tst_chi2 {
    double p_value;      /* probability of a statistic at least this large under the hypothesis */
    double statistic;    /* Pearson's chi^2 after pooling */
    int dof;             /* degrees of freedom */
    double hist_sum;     /* fraction of samples that produced a direction */
    double pdf_sum;      /* integral of the pdf over the sphere */
    bool zero_bin_hit;   /* a sample fell in a bin whose expected count is 0 */
} tst_chi2;

/* Integral of pdf over the cell [p0,p1] x [z0,z1] of (phi, cos theta),
 * adaptively: a 6x6 Gauss-Legendre rule compared with the same rule on the
 * four quarters, refining until they agree to within a hundredth of the
 * statistical noise of the bin's count (n samples: 1e-2 sqrt(n I) / n for an
 * integral I), or depth 5. */
static inline double tst__cell(tst_dir_fn pdf, void *ctx, double p0, double p1, double z0,
                               double z1, const double *x, const double *w, int depth,
                               double whole, double n)
{
    double q[4], total = 0.0;
    double pm = 0.5 * (p0 + p1), zm = 0.5 * (z0 + z1);
    double cp[4][4] = {{p0, pm, z0, zm}, {pm, p1, z0, zm}, {p0, pm, zm, z1}, {pm, p1, zm, z1}};
    for (int c = 0; c < 4; c++) {
        double a0 = cp[c][0], a1 = cp[c][1], b0 = cp[c][2], b1 = cp[c][3];
        double s = 0.0;
        for (int i = 0; i < 6; i++) {
            double z = b0 + (b1 - b0) * 0.5 * (x[i] + 1.0);
            for (int j = 0; j < 6; j++) {
                double p = a0 + (a1 - a0) * 0.5 * (x[j] + 1.0);
                s += w[i] * w[j] * pdf(ctx, tst_dir(p, z));
            }
        }
        q[c] = s * 0.25 * (a1 - a0) * (b1 - b0);
        total += q[c];
    }
    if (depth >= 5 || fabs(total - whole) * n <= 1e-2 * sqrt(fmax(1.0, fabs(total) * n)))
        return total;
    double r = 0.0;
    for (int c = 0; c < 4; c++)
        r += tst__cell(pdf, ctx, cp[c][0], cp[c][1], cp[c][2], cp[c][3], x, w, depth + 1, q[c], n);
    return r;
}

static inline int tst__cmp_double(const void *a, const void *b)
{
    double x = ((const double *)a)[0], y = ((const double *)b)[0];
    return (x > y) - (x < y);
}

/* Runs the test: n samples from `sample` with numbers from a PCG32 stream
 * seeded with `seed`, binned on an nphi x nz grid over phi in [-pi, pi) and
 * z in [-1, 1]; expected counts from `pdf`. Prints a one-line summary. */
static inline tst_chi2 tst_chi2_run(const char *name, tst_sample_fn sample, tst_dir_fn pdf,
                                    void *ctx, long n, int nphi, int nz, uint64_t seed)
{
    tst_chi2 r = {0};
    int cells = nphi * nz;
    double *obs = calloc((size_t)cells, sizeof(double));
    double *expd = calloc((size_t)cells, sizeof(double));
    double (*pair)[2] = calloc((size_t)cells, sizeof(*pair));
    tb_rng rng;
    tb_rng_seed(&rng, seed, 7);
    long got = 0;
    for (long k = 0; k < n; k++) {
        float uc = tb_rng_float(&rng), u1 = tb_rng_float(&rng), u2 = tb_rng_float(&rng);
        tb_vec3 w;
        if (!sample(ctx, uc, u1, u2, &w))
            continue;
        got++;
        double phi = atan2(w.y, w.x);
        int i = (int)floor((phi + M_PI) / (2.0 * M_PI) * nphi);
        int j = (int)floor((w.z + 1.0) * 0.5 * nz);
        i = i < 0 ? 0 : (i >= nphi ? nphi - 1 : i);
        j = j < 0 ? 0 : (j >= nz ? nz - 1 : j);
        obs[j * nphi + i] += 1.0;
    }
    r.hist_sum = (double)got / n;
    double x[6], w[6];
    tst_gauss_legendre(6, x, w);
    double psum = 0.0;
    for (int j = 0; j < nz; j++)
        for (int i = 0; i < nphi; i++) {
            double p0 = -M_PI + 2.0 * M_PI * i / nphi, p1 = -M_PI + 2.0 * M_PI * (i + 1) / nphi;
            double z0 = -1.0 + 2.0 * j / nz, z1 = -1.0 + 2.0 * (j + 1) / nz;
            double v = tst__cell(pdf, ctx, p0, p1, z0, z1, x, w, 0, -1.0, (double)n);
            psum += v;
            expd[j * nphi + i] = v * n;
        }
    r.pdf_sum = psum;
    for (int c = 0; c < cells; c++) {
        pair[c][0] = expd[c];
        pair[c][1] = obs[c];
        if (expd[c] == 0.0 && obs[c] > 0.0)
            r.zero_bin_hit = true;
    }
    /* Pool bins with expected counts below 5, smallest first (Mitsuba's chi2). */
    qsort(pair, (size_t)cells, sizeof(*pair), tst__cmp_double);
    double stat = 0.0, pe = 0.0, po = 0.0;
    int dof = 0;
    for (int c = 0; c < cells; c++) {
        double e = pair[c][0], o = pair[c][1];
        if (e == 0.0)
            continue;
        if (e < 5.0) {
            pe += e;
            po += o;
            if (pe > 5.0) {
                stat += (po - pe) * (po - pe) / pe;
                dof++;
                pe = po = 0.0;
            }
        } else {
            stat += (o - e) * (o - e) / e;
            dof++;
        }
    }
    if (pe > 0.0) { /* leftover pooled mass */
        stat += (po - pe) * (po - pe) / pe;
        dof++;
    }
    dof -= 1;
    r.statistic = stat;
    r.dof = dof;
    r.p_value = dof > 0 ? tst_gamma_q(0.5 * dof, 0.5 * stat) : 0.0;
    printf("[ chi2     ] %-40s p = %.4g  chi2 = %.1f  dof = %d  samples %.4f  pdf %.4f\n", name,
           r.p_value, r.statistic, r.dof, r.hist_sum, r.pdf_sum);
    free(obs);
    free(expd);
    free(pair);
    return r;
}

/* Significance level at which the chi-square tests reject. */
#define TST_CHI2_ALPHA 1e-3

#endif
