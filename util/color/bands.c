#include "util/color/bands.h"

#include <string.h>

#include "util/color/cie.h"
#include "util/color/srgb.h"

tb_status tb_bands_init(tb_bands *b, int n, const double *lambda)
{
    if (!b)
        return tb_error(TB_ERR_ARG, "bands: no output given");
    memset(b, 0, sizeof *b);
    if (n > TB_BANDS_MAX)
        return tb_error(TB_ERR_ARG, "bands: %d bands, at most %d", n, TB_BANDS_MAX);
    tb_status st = tb_spectrum_check(n, lambda, NULL);
    if (st)
        return tb_error_context(st, "bands");
    /* w_i = int hat_i * cmf, where hat_i is the spectrum that is 1 at band i and 0
     * at every other band: sum_i v_i hat_i is the band spectrum, so sum_i v_i w_i
     * is its exact XYZ integral. */
    const tb_spectrum *cmf[3] = {tb_cie_xbar(), tb_cie_ybar(), tb_cie_zbar()};
    for (int i = 0; i < n; i++) {
        double hl[3], hv[3];
        int m = 0;
        if (i > 0) {
            hl[m] = lambda[i - 1];
            hv[m++] = 0.0;
        }
        hl[m] = lambda[i];
        hv[m++] = 1.0;
        if (i + 1 < n) {
            hl[m] = lambda[i + 1];
            hv[m++] = 0.0;
        }
        const tb_spectrum hat = {m, hl, hv, NULL};
        for (int c = 0; c < 3; c++)
            b->xyz_weight[i][c] = tb_spectrum_product_integral(&hat, cmf[c], NULL);
    }
    for (int k = 0; k < TB_SMITS_BASIS_COUNT; k++) {
        st = tb_spectrum_resample_values(tb_smits_basis_spectrum((tb_smits_basis)k), n, lambda,
                                         b->smits[k]);
        if (st)
            return st;
    }
    b->n = n;
    memcpy(b->lambda, lambda, (size_t)n * sizeof *lambda);
    return TB_OK;
}

tb_status tb_bands_init_range(tb_bands *b, double lambda_min, double lambda_max, int n)
{
    if (!b)
        return tb_error(TB_ERR_ARG, "bands: no output given");
    if (n < 2 || n > TB_BANDS_MAX)
        return tb_error(TB_ERR_ARG, "bands: %d bands, need 2 to %d", n, TB_BANDS_MAX);
    double l[TB_BANDS_MAX];
    for (int i = 0; i < n; i++) /* interpolated so both ends are exact */
        l[i] = (lambda_min * (n - 1 - i) + lambda_max * i) / (n - 1);
    return tb_bands_init(b, n, l);
}

tb_status tb_bands_init_default(tb_bands *b)
{
    return tb_bands_init_range(b, TB_BANDS_DEFAULT_MIN, TB_BANDS_DEFAULT_MAX,
                               TB_BANDS_DEFAULT_COUNT);
}

tb_status tb_bands_from_spectrum(const tb_bands *b, const tb_spectrum *s, double *v)
{
    if (!b || !s || !v)
        return tb_error(TB_ERR_ARG, "bands: no bands, spectrum or output given");
    return tb_spectrum_resample_values(s, b->n, b->lambda, v);
}

tb_status tb_bands_from_rgb_reflectance(const tb_bands *b, const double rgb[3], double *v)
{
    if (!b || !v)
        return tb_error(TB_ERR_ARG, "bands: no bands or output given");
    double w[TB_SMITS_BASIS_COUNT];
    tb_status st = tb_smits_weights(rgb, w);
    if (st)
        return st;
    for (int i = 0; i < b->n; i++) {
        double s = 0.0;
        for (int k = 0; k < TB_SMITS_BASIS_COUNT; k++)
            s += w[k] * b->smits[k][i];
        v[i] = s;
    }
    return TB_OK;
}

void tb_bands_to_xyz(const tb_bands *b, const double *v, double xyz[3])
{
    double x = 0.0, y = 0.0, z = 0.0;
    for (int i = 0; i < b->n; i++) {
        x += v[i] * b->xyz_weight[i][0];
        y += v[i] * b->xyz_weight[i][1];
        z += v[i] * b->xyz_weight[i][2];
    }
    xyz[0] = x;
    xyz[1] = y;
    xyz[2] = z;
}

void tb_bands_to_linear_srgb(const tb_bands *b, const double *v, double scale, double rgb[3])
{
    double xyz[3];
    tb_bands_to_xyz(b, v, xyz);
    for (int c = 0; c < 3; c++)
        xyz[c] *= scale;
    tb_xyz_to_linear_srgb(xyz, rgb);
}
