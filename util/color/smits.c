#include "util/color/smits.h"

#include <math.h>
#include <pthread.h>

#include "color/color_tables.h" /* generated from smits1999-basis.csv by module.cmake */
#include "util/color/cie.h"

#define TB__SMITS_BINS TB__SMITS1999_COUNT
#define TB__SMITS_RAMP 0.5 /* nm each side of a bin edge: a 1-nm ramp between steps */
#define TB__SMITS_LO 360.0 /* nm: the end bins are held flat to the CIE's visible range */
#define TB__SMITS_HI 830.0

_Static_assert(TB_SMITS_SAMPLES == 2 * TB__SMITS_BINS + 2, "TB_SMITS_SAMPLES follows the table");

static double tb__lambda[TB_SMITS_SAMPLES];
static double tb__value[TB_SMITS_BASIS_COUNT][TB_SMITS_SAMPLES];
static tb_spectrum tb__basis[TB_SMITS_BASIS_COUNT];
static pthread_once_t tb__once = PTHREAD_ONCE_INIT;

/* Lays the published bins out as steps on the wavelengths described in smits.h. */
static void tb__smits_setup(void)
{
    const double *column[TB_SMITS_BASIS_COUNT] = {
        tb__smits1999_white, tb__smits1999_cyan,  tb__smits1999_magenta, tb__smits1999_yellow,
        tb__smits1999_red,   tb__smits1999_green, tb__smits1999_blue};
    int m = 0;
    tb__lambda[m++] = TB__SMITS_LO;
    tb__lambda[m++] = tb__smits1999_bin_lo_nm[0];
    for (int i = 1; i < TB__SMITS_BINS; i++) {
        tb__lambda[m++] = tb__smits1999_bin_lo_nm[i] - TB__SMITS_RAMP;
        tb__lambda[m++] = tb__smits1999_bin_lo_nm[i] + TB__SMITS_RAMP;
    }
    tb__lambda[m++] = tb__smits1999_bin_hi_nm[TB__SMITS_BINS - 1];
    tb__lambda[m++] = TB__SMITS_HI;
    for (int k = 0; k < TB_SMITS_BASIS_COUNT; k++) {
        const double *v = column[k];
        double *out = tb__value[k];
        out[0] = out[1] = v[0];
        for (int i = 1; i < TB__SMITS_BINS; i++) {
            out[2 * i] = v[i - 1];
            out[2 * i + 1] = v[i];
        }
        out[TB_SMITS_SAMPLES - 2] = out[TB_SMITS_SAMPLES - 1] = v[TB__SMITS_BINS - 1];
        tb__basis[k] = (tb_spectrum){TB_SMITS_SAMPLES, tb__lambda, tb__value[k], NULL};
    }
}

const double *tb_smits_lambda(void)
{
    pthread_once(&tb__once, tb__smits_setup);
    return tb__lambda;
}

const tb_spectrum *tb_smits_basis_spectrum(tb_smits_basis which)
{
    if ((int)which < 0 || which >= TB_SMITS_BASIS_COUNT)
        return NULL;
    pthread_once(&tb__once, tb__smits_setup);
    return &tb__basis[which];
}

tb_status tb_smits_weights(const double rgb[3], double w[TB_SMITS_BASIS_COUNT])
{
    if (!rgb || !w)
        return tb_error(TB_ERR_ARG, "Smits: no RGB or output given");
    double r = rgb[0], g = rgb[1], b = rgb[2];
    if (!isfinite(r) || !isfinite(g) || !isfinite(b) || r < 0.0 || g < 0.0 || b < 0.0)
        return tb_error(TB_ERR_ARG,
                        "Smits: RGB (%g, %g, %g) must be finite and >= 0 (a reflectance or emission)",
                        r, g, b);
    for (int k = 0; k < TB_SMITS_BASIS_COUNT; k++)
        w[k] = 0.0;
    /* Smits (1999), section 3: white for the common part, then the secondary
     * colour for the two larger components, then the primary for the largest. */
    if (r <= g && r <= b) {
        w[TB_SMITS_WHITE] = r;
        if (g <= b) {
            w[TB_SMITS_CYAN] = g - r;
            w[TB_SMITS_BLUE] = b - g;
        } else {
            w[TB_SMITS_CYAN] = b - r;
            w[TB_SMITS_GREEN] = g - b;
        }
    } else if (g <= r && g <= b) {
        w[TB_SMITS_WHITE] = g;
        if (r <= b) {
            w[TB_SMITS_MAGENTA] = r - g;
            w[TB_SMITS_BLUE] = b - r;
        } else {
            w[TB_SMITS_MAGENTA] = b - g;
            w[TB_SMITS_RED] = r - b;
        }
    } else {
        w[TB_SMITS_WHITE] = b;
        if (r <= g) {
            w[TB_SMITS_YELLOW] = r - b;
            w[TB_SMITS_GREEN] = g - r;
        } else {
            w[TB_SMITS_YELLOW] = g - b;
            w[TB_SMITS_RED] = r - g;
        }
    }
    return TB_OK;
}

tb_status tb_smits_reflectance(const double rgb[3], tb_spectrum *out)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "Smits: no output given");
    double w[TB_SMITS_BASIS_COUNT], v[TB_SMITS_SAMPLES];
    tb_status st = tb_smits_weights(rgb, w);
    if (st) {
        *out = (tb_spectrum){0};
        return st;
    }
    pthread_once(&tb__once, tb__smits_setup);
    for (int i = 0; i < TB_SMITS_SAMPLES; i++) {
        double s = 0.0;
        for (int k = 0; k < TB_SMITS_BASIS_COUNT; k++)
            s += w[k] * tb__value[k][i];
        v[i] = s;
    }
    return tb_spectrum_init(out, TB_SMITS_SAMPLES, tb__lambda, v);
}

tb_status tb_smits_emission(const double rgb[3], const tb_spectrum *illuminant, tb_spectrum *out)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "Smits emission: no output given");
    *out = (tb_spectrum){0};
    if (!illuminant)
        return tb_error(TB_ERR_ARG, "Smits emission: no illuminant given");
    double y = tb_spectrum_product_integral(illuminant, tb_cie_ybar(), NULL);
    if (!(y > 0.0))
        return tb_error(TB_ERR_ARG, "Smits emission: the illuminant has no luminance (int S ybar = %g)", y);
    tb_spectrum refl, lit;
    tb_status st = tb_smits_reflectance(rgb, &refl);
    if (st)
        return st;
    st = tb_spectrum_multiply(&refl, illuminant, &lit);
    tb_spectrum_release(&refl);
    if (st)
        return st;
    st = tb_spectrum_scale(&lit, 1.0 / y, out);
    tb_spectrum_release(&lit);
    return st;
}
