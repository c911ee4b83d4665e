/* libFuzzer target for the IES LM-63 parser. Any input must either parse or
 * fail with one located message ("fuzz.ies:LINE: error: ..."), without a
 * crash, leak, hang or sanitizer report. A parsed table must interpolate to
 * finite non-negative values no larger than its maximum, integrate to a
 * finite non-negative flux, and sample directions with positive, finite
 * densities that agree with tb_ies_pdf. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "host/render/ies.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size > 1 << 20)
        return 0;
    tb_ies *ies = NULL;
    tb_status st = tb_ies_parse((const char *)data, size, "fuzz.ies", &ies);
    if (st) {
        if (ies)
            abort();
        if ((st == TB_ERR_FORMAT || st == TB_ERR_UNSUPPORTED) && strncmp(tb_last_error(), "fuzz.ies:", 9) != 0)
            abort();
        return 0;
    }
    static const double vs[] = {0.0, 1e-9, 7.5, 45.0, 89.999, 90.0, 135.0, 180.0};
    static const double hs[] = {-30.0, 0.0, 45.0, 90.0, 180.0, 269.9, 359.999, 725.0};
    for (size_t i = 0; i < sizeof vs / sizeof vs[0]; i++)
        for (size_t j = 0; j < sizeof hs / sizeof hs[0]; j++) {
            double c = tb_ies_candela(ies, vs[i], hs[j]);
            if (!(c >= 0.0) || !(c <= ies->max_candela * (1.0 + 1e-12)))
                abort();
        }
    double flux = tb_ies_flux(ies);
    if (!(flux >= 0.0) || !isfinite(flux))
        abort();
    for (int k = 0; k < 16; k++) {
        double pdf;
        tb_vec3 w = tb_ies_sample(ies, (float)((k * 7 % 16) / 16.0), (float)(k / 16.0), &pdf);
        if (!(pdf > 0.0) || !isfinite(pdf) || !isfinite(w.x) || !isfinite(w.y) || !isfinite(w.z))
            abort();
        double q = tb_ies_pdf(ies, w);
        if (!(q >= 0.0) || !isfinite(q))
            abort();
    }
    tb_ies_free(ies);
    return 0;
}
