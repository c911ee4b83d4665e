/* Warping functions: uniform numbers (u1, u2) in [0,1)^2 to points on the
 * disc, hemisphere, sphere, cone and triangle with known densities, the
 * stratified (jittered) sample sets that soft shadows and antialiasing use,
 * and a tabulated 1D distribution (discrete choice among weighted items, or a
 * piecewise-constant density) for light selection and IES sampling.
 *
 * Directions are in a local frame whose z axis is the pole (the shading
 * normal, or the cone axis). Every sampler is paired with its density, in the
 * measure stated (solid angle for directions, area for points); the chi-square
 * tests in tests/render check each pair. Arithmetic is in double and results
 * are rounded to float once (docs/shading.md, "Sampling"). */
#ifndef TB_HOST_RENDER_SAMPLING_H
#define TB_HOST_RENDER_SAMPLING_H

#include <stddef.h>

#include "util/base/error.h"
#include "util/math/rng.h"
#include "util/math/vec.h"

/* cos(2 pi u) and sin(2 pi u) for u in [0, 1] (a uniform angle from a
 * sample), without libm: 4u is split into the nearest quadrant k and a rest
 * f in [-1/2, 1/2] (both exact), the angle f pi/2 in [-pi/4, pi/4] goes
 * through Taylor polynomials of sin (to x^15) and cos (to x^16), whose
 * truncation is below 1e-16 there, and the quadrant turns the pair. Within
 * a few units in the last place of libm's cos / sin of the rounded 2 pi u
 * (tests/render/test_shading_sampling.c), at a third of the cost; exact
 * (up to the sign of a zero) at u = 0, 1/4, 1/2, 3/4, 1. */
static inline void tb_sincos_2pi(double u, double *c, double *s)
{
    double t = 4.0 * u;
    double k = (double)(long)(t + 0.5); /* nearest quadrant (t >= 0) */
    double f = t - k;
    double a = f * 1.5707963267948966; /* pi / 2 */
    double a2 = a * a;
    double sp = a + a * a2 *
                        (-1.0 / 6.0 +
                         a2 * (1.0 / 120.0 +
                               a2 * (-1.0 / 5040.0 +
                                     a2 * (1.0 / 362880.0 +
                                           a2 * (-1.0 / 39916800.0 +
                                                 a2 * (1.0 / 6227020800.0 + a2 * (-1.0 / 1307674368000.0)))))));
    double cp = 1.0 + a2 * (-0.5 +
                            a2 * (1.0 / 24.0 +
                                  a2 * (-1.0 / 720.0 +
                                        a2 * (1.0 / 40320.0 +
                                              a2 * (-1.0 / 3628800.0 +
                                                    a2 * (1.0 / 479001600.0 +
                                                          a2 * (-1.0 / 87178291200.0 +
                                                                a2 * (1.0 / 20922789888000.0))))))));
    switch ((long)k & 3) {
    case 0: *c = cp, *s = sp; break;
    case 1: *c = -sp, *s = cp; break;
    case 2: *c = -cp, *s = -sp; break;
    default: *c = sp, *s = -cp; break;
    }
}

/* Shirley-Chiu concentric map of the square onto the unit disc (area
 * preserving, low distortion, continuous); density 1/pi per unit area. */
tb_vec2 tb_sample_disk_concentric(float u1, float u2);

/* Cosine-weighted direction on the hemisphere z >= 0 (Malley's method: the
 * concentric disc lifted to the hemisphere). */
tb_vec3 tb_sample_cosine_hemisphere(float u1, float u2);

/* Density of tb_sample_cosine_hemisphere: cos_theta / pi for cos_theta > 0, else 0. */
float tb_cosine_hemisphere_pdf(float cos_theta);

/* Uniform direction on the hemisphere z >= 0. */
tb_vec3 tb_sample_uniform_hemisphere(float u1, float u2);

/* Density of tb_sample_uniform_hemisphere: 1 / (2 pi). */
float tb_uniform_hemisphere_pdf(void);

/* Uniform direction on the unit sphere. */
tb_vec3 tb_sample_uniform_sphere(float u1, float u2);

/* Density of tb_sample_uniform_sphere: 1 / (4 pi). */
float tb_uniform_sphere_pdf(void);

/* Uniform direction in the cone of directions within angle theta_max of +z,
 * given cos_max = cos(theta_max) in [-1, 1]. Accurate for tiny cones: sin^2
 * theta is formed from 1 - cos_theta, never from a difference of squares. */
tb_vec3 tb_sample_uniform_cone(float u1, float u2, double cos_max);

/* Density of tb_sample_uniform_cone: 1 / (2 pi (1 - cos_max)). */
double tb_uniform_cone_pdf(double cos_max);

/* Direction about +z with density (n + 1) / (2 pi) cos^n theta on the
 * hemisphere (n >= 0): cos theta = u1^(1/(n+1)). The Phong lobe sampler. */
tb_vec3 tb_sample_power_cosine(float u1, float u2, double n);

/* Density of tb_sample_power_cosine for a direction with this cos theta (0 below the horizon). */
double tb_power_cosine_pdf(double cos_theta, double n);

/* Uniform point on a triangle as barycentric weights (b0, b1) of its first
 * two vertices (b2 = 1 - b0 - b1); density 1 / area. The square-root map,
 * which keeps stratification of (u1, u2). */
tb_vec2 tb_sample_triangle(float u1, float u2);

/* Splits n samples into an nx * ny grid as close to square as possible with
 * nx * ny == n (nx >= ny; a prime n gives n x 1). n >= 1. */
void tb_stratified_dims(int n, int *nx, int *ny);

/* Jittered stratified samples: writes nx * ny points (u[2k], u[2k+1]) in
 * [0,1)^2, one uniformly placed in each cell of the nx x ny grid, row by row.
 * The stream of `rng` advances by exactly 2 nx ny floats. */
void tb_stratified_2d(tb_rng *rng, int nx, int ny, float *u);

/* One jittered sample: the point of cell `index` (0 .. nx*ny - 1, row by row)
 * of the nx x ny grid, jittered by (j1, j2) in [0,1)^2. */
void tb_stratified_point(int nx, int ny, int index, float j1, float j2, float *u1, float *u2);

/* ---------------------------------------------------------------- 1D tables */

/* A tabulated distribution over n items (or n equal bins of [0, 1)) with
 * weights f[i] >= 0. */
typedef struct tb_distrib1d {
    int n;         /* items */
    double *f;     /* weights as given */
    double *cdf;   /* n + 1 entries: cdf[0] = 0, cdf[n] = 1, non-decreasing */
    double total;  /* sum of the weights */
} tb_distrib1d;

/* Builds the table over f[0..n) (copied). TB_ERR_ARG for n < 1, a negative or
 * non-finite weight, or a zero or overflowing sum; TB_ERR_NOMEM. */
tb_status tb_distrib1d_init(tb_distrib1d *d, const double *f, int n);

/* Frees the table and zeroes *d (harmless on a zeroed struct). */
void tb_distrib1d_release(tb_distrib1d *d);

/* The item of u in [0, 1) under a cumulative table of n + 1 entries (cdf[0] =
 * 0, cdf[n] = 1, non-decreasing): the i with cdf[i] <= u < cdf[i + 1], so an
 * item of width 0 is never returned. */
static inline int tb_cdf_search(const double *cdf, int n, double u)
{
    int lo = 1, hi = n; /* first j with cdf[j] > u; cdf[n] = 1 > u always */
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (cdf[mid] > u)
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo - 1;
}

/* Picks item i with probability f[i] / total (never an item of weight 0).
 * *pmf (if not NULL) gets that probability and *u_remap (if not NULL) the
 * position of u within the item's slice of [0,1), rescaled to [0,1), so the
 * same number can drive a further choice without losing stratification. */
static inline int tb_distrib1d_sample_discrete(const tb_distrib1d *d, double u, double *pmf, double *u_remap)
{
    /* Inline: once per light sample. 0x1.fffffffffffffp-1 is the largest double below 1. */
    if (!(u >= 0.0))
        u = 0.0;
    if (u >= 1.0)
        u = 0x1.fffffffffffffp-1;
    int i = tb_cdf_search(d->cdf, d->n, u);
    /* cdf[n] = 1 > u always, so i is in 0..n-1 with cdf[i] <= u < cdf[i+1]. */
    double w = d->cdf[i + 1] - d->cdf[i];
    if (pmf)
        *pmf = d->f[i] / d->total;
    if (u_remap) {
        double r = (u - d->cdf[i]) / w;
        *u_remap = r < 1.0 ? (r > 0.0 ? r : 0.0) : 0x1.fffffffffffffp-1;
    }
    return i;
}

/* Probability of item i (0 outside 0 .. n-1). */
double tb_distrib1d_pmf(const tb_distrib1d *d, int i);

#endif
