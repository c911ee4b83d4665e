/* Warping functions, stratified samples and 1D tables (sampling.h). */
#include "host/render/sampling.h"

#include <math.h>
#include <stdlib.h>

#include "util/math/float.h"

/* Unit direction from cos theta (with 1 - cos theta given separately, for
 * accuracy near the pole) and phi. */
static tb_vec3 tb__dir(double cos_theta, double one_minus_cos, double phi)
{
    /* sin^2 = (1 - c)(1 + c) = a (2 - a): no cancellation near c = 1. */
    double s = sqrt(fmax(0.0, one_minus_cos * (2.0 - one_minus_cos)));
    return tb_vec3_make((float)(s * cos(phi)), (float)(s * sin(phi)), (float)cos_theta);
}

tb_vec2 tb_sample_disk_concentric(float u1, float u2)
{
    double ox = 2.0 * u1 - 1.0, oy = 2.0 * u2 - 1.0;
    if (ox == 0.0 && oy == 0.0)
        return tb_vec2_make(0.0f, 0.0f);
    double r, theta;
    if (fabs(ox) > fabs(oy)) {
        r = ox;
        theta = TB_PI_4 * (oy / ox);
    } else {
        r = oy;
        theta = TB_PI_2 - TB_PI_4 * (ox / oy);
    }
    return tb_vec2_make((float)(r * cos(theta)), (float)(r * sin(theta)));
}

tb_vec3 tb_sample_cosine_hemisphere(float u1, float u2)
{
    double ox = 2.0 * u1 - 1.0, oy = 2.0 * u2 - 1.0;
    if (ox == 0.0 && oy == 0.0)
        return tb_vec3_make(0.0f, 0.0f, 1.0f);
    double r, theta;
    if (fabs(ox) > fabs(oy)) {
        r = ox;
        theta = TB_PI_4 * (oy / ox);
    } else {
        r = oy;
        theta = TB_PI_2 - TB_PI_4 * (ox / oy);
    }
    /* Malley: lift the disc point; z = sqrt(1 - r^2) = sqrt((1 - r)(1 + r)). */
    double ar = fabs(r);
    double z = sqrt(fmax(0.0, (1.0 - ar) * (1.0 + ar)));
    return tb_vec3_make((float)(r * cos(theta)), (float)(r * sin(theta)), (float)z);
}

float tb_cosine_hemisphere_pdf(float cos_theta)
{
    return cos_theta > 0.0f ? (float)(cos_theta * TB_INV_PI) : 0.0f;
}

tb_vec3 tb_sample_uniform_hemisphere(float u1, float u2)
{
    double z = u1;
    return tb__dir(z, 1.0 - z, TB_2PI * u2);
}

float tb_uniform_hemisphere_pdf(void) { return (float)TB_INV_2PI; }

tb_vec3 tb_sample_uniform_sphere(float u1, float u2)
{
    double a = 2.0 * u1; /* 1 - z */
    return tb__dir(1.0 - a, a, TB_2PI * u2);
}

float tb_uniform_sphere_pdf(void) { return (float)TB_INV_4PI; }

tb_vec3 tb_sample_uniform_cone(float u1, float u2, double cos_max)
{
    double a = u1 * (1.0 - cos_max); /* 1 - cos theta, uniform in [0, 1 - cos_max) */
    return tb__dir(1.0 - a, a, TB_2PI * u2);
}

double tb_uniform_cone_pdf(double cos_max) { return 1.0 / (TB_2PI * (1.0 - cos_max)); }

tb_vec3 tb_sample_power_cosine(float u1, float u2, double n)
{
    /* cos = u1^(1/(n+1)); 1 - cos = -expm1(log(u1)/(n+1)) keeps the digits of
     * narrow lobes (large n), where cos rounds to 1. */
    if (u1 <= 0.0f)
        return tb__dir(0.0, 1.0, TB_2PI * u2);
    double lg = log((double)u1) / (n + 1.0);
    double a = -expm1(lg);
    return tb__dir(exp(lg), a, TB_2PI * u2);
}

double tb_power_cosine_pdf(double cos_theta, double n)
{
    if (!(cos_theta > 0.0))
        return 0.0;
    return (n + 1.0) * TB_INV_2PI * pow(cos_theta, n);
}

tb_vec2 tb_sample_triangle(float u1, float u2)
{
    double su = sqrt((double)u1);
    return tb_vec2_make((float)(1.0 - su), (float)(u2 * su));
}

void tb_stratified_dims(int n, int *nx, int *ny)
{
    if (n < 1)
        n = 1;
    int best = 1;
    for (int d = 1; (long)d * d <= n; d++)
        if (n % d == 0)
            best = d;
    *ny = best;
    *nx = n / best;
}

void tb_stratified_point(int nx, int ny, int index, float j1, float j2, float *u1, float *u2)
{
    int ix = index % nx, iy = index / nx;
    double x = (ix + (double)j1) / nx, y = (iy + (double)j2) / ny;
    /* Rounding to float may reach 1 in the last cell: keep [0, 1). */
    float fx = (float)x, fy = (float)y;
    *u1 = fx < 1.0f ? fx : 0x1.fffffep-1f;
    *u2 = fy < 1.0f ? fy : 0x1.fffffep-1f;
}

void tb_stratified_2d(tb_rng *rng, int nx, int ny, float *u)
{
    for (int k = 0; k < nx * ny; k++) {
        float j1 = tb_rng_float(rng);
        float j2 = tb_rng_float(rng);
        tb_stratified_point(nx, ny, k, j1, j2, &u[2 * k], &u[2 * k + 1]);
    }
}

/* ---------------------------------------------------------------- 1D tables */

tb_status tb_distrib1d_init(tb_distrib1d *d, const double *f, int n)
{
    *d = (tb_distrib1d){0};
    if (n < 1 || !f)
        return tb_error(TB_ERR_ARG, "distribution: needs at least one weight (got %d)", n);
    double total = 0.0;
    for (int i = 0; i < n; i++) {
        if (!(f[i] >= 0.0) || !isfinite(f[i]))
            return tb_error(TB_ERR_ARG, "distribution: weight %d is %g (must be finite and >= 0)", i,
                            f[i]);
        total += f[i];
    }
    if (!(total > 0.0) || !isfinite(total))
        return tb_error(TB_ERR_ARG, "distribution: the weights sum to %g (must be finite and > 0)",
                        total);
    double *mem = malloc(sizeof(double) * (2 * (size_t)n + 1));
    if (!mem)
        return tb_error(TB_ERR_NOMEM, "distribution: out of memory for %d weights", n);
    d->n = n;
    d->f = mem;
    d->cdf = mem + n;
    d->total = total;
    double run = 0.0;
    d->cdf[0] = 0.0;
    for (int i = 0; i < n; i++) {
        d->f[i] = f[i];
        run += f[i];
        d->cdf[i + 1] = run / total;
    }
    d->cdf[n] = 1.0;
    return TB_OK;
}

void tb_distrib1d_release(tb_distrib1d *d)
{
    if (!d)
        return;
    free(d->f);
    *d = (tb_distrib1d){0};
}

/* tb_distrib1d_sample_discrete is inline in sampling.h. */

double tb_distrib1d_pmf(const tb_distrib1d *d, int i)
{
    if (i < 0 || i >= d->n)
        return 0.0;
    return d->f[i] / d->total;
}
