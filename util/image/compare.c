/* Image comparison metrics and the false-colour error image (see compare.h
 * for the definitions and the rules on channels and NaN/Inf). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util/color/srgb.h"
#include "util/image/compare.h"

/* The channels being compared: indices into A and B, and their names. */
typedef struct tb__cmp_sel {
    int n;
    int ia[TB_COMPARE_MAX_CHANNELS];
    int ib[TB_COMPARE_MAX_CHANNELS];
    char names[TB_COMPARE_MAX_CHANNELS][TB_IMAGE_CHANNEL_NAME_MAX];
} tb__cmp_sel;

static tb_status tb__cmp_add(tb__cmp_sel *s, const tb_image *a, const tb_image *b, const char *name)
{
    int ia = tb_image_channel(a, name), ib = tb_image_channel(b, name);
    if (ia < 0 || ib < 0)
        return tb_error(TB_ERR_ARG, "channel \"%s\" is missing from image %s", name,
                        ia < 0 ? "A" : "B");
    for (int i = 0; i < s->n; i++)
        if (s->ia[i] == ia)
            return tb_error(TB_ERR_ARG, "channel \"%s\" named twice", name);
    if (s->n == TB_COMPARE_MAX_CHANNELS)
        return tb_error(TB_ERR_ARG, "more than %d channels", TB_COMPARE_MAX_CHANNELS);
    s->ia[s->n] = ia;
    s->ib[s->n] = ib;
    snprintf(s->names[s->n], sizeof s->names[s->n], "%s", name);
    s->n++;
    return TB_OK;
}

static int tb__cmp_has(const tb_image *img, const char *name)
{
    return tb_image_channel(img, name) >= 0;
}

/* Picks the channels to compare (rules in compare.h). */
static tb_status tb__cmp_select(const tb_image *a, const tb_image *b, const tb_compare_options *o,
                                tb__cmp_sel *s)
{
    memset(s, 0, sizeof *s);
    tb_status st;
    if (o && o->channels) {
        const char *p = o->channels;
        for (;;) {
            while (*p == ' ')
                p++;
            size_t n = strcspn(p, ",");
            while (n > 0 && p[n - 1] == ' ')
                n--;
            if (n == 0 || n >= TB_IMAGE_CHANNEL_NAME_MAX)
                return tb_error(TB_ERR_ARG, "bad channel list \"%s\"", o->channels);
            char name[TB_IMAGE_CHANNEL_NAME_MAX];
            memcpy(name, p, n);
            name[n] = '\0';
            if ((st = tb__cmp_add(s, a, b, name)))
                return st;
            p = strchr(p, ',');
            if (!p)
                break;
            p++;
        }
        return TB_OK;
    }
    static const char *const rgb[] = {"R", "G", "B"};
    if (tb__cmp_has(a, "R") && tb__cmp_has(a, "G") && tb__cmp_has(a, "B") && tb__cmp_has(b, "R") &&
        tb__cmp_has(b, "G") && tb__cmp_has(b, "B")) {
        for (int i = 0; i < 3; i++)
            if ((st = tb__cmp_add(s, a, b, rgb[i])))
                return st;
    } else if (tb__cmp_has(a, "Y") && tb__cmp_has(b, "Y")) {
        if ((st = tb__cmp_add(s, a, b, "Y")))
            return st;
    } else {
        for (int c = 0; c < a->channels; c++)
            if (strcmp(a->names[c], "A") != 0 && tb__cmp_has(b, a->names[c]))
                if ((st = tb__cmp_add(s, a, b, a->names[c])))
                    return st;
    }
    int include_alpha = o && o->include_alpha;
    if (include_alpha && tb__cmp_has(a, "A") && tb__cmp_has(b, "A"))
        if ((st = tb__cmp_add(s, a, b, "A")))
            return st;
    if (s->n == 0)
        return tb_error(TB_ERR_ARG,
                        "the images have no colour channel in common (A has %d "
                        "channels starting \"%s\", B has %d starting \"%s\"); name them with "
                        "the channels option",
                        a->channels, a->names[0], b->channels, b->names[0]);
    return TB_OK;
}

static tb_status tb__cmp_check(const tb_image *a, const tb_image *b)
{
    if (!a || !b || !a->pixels || !b->pixels)
        return tb_error(TB_ERR_ARG, "tb_image_compare: NULL image");
    if (a->width != b->width || a->height != b->height)
        return tb_error(TB_ERR_ARG, "size mismatch: A is %dx%d, B is %dx%d", a->width,
                        a->height, b->width, b->height);
    return TB_OK;
}

/* valid[i] = 1 when every selected channel of pixel i is finite in A and B. */
static unsigned char *tb__cmp_valid(const tb_image *a, const tb_image *b, const tb__cmp_sel *s,
                                    long long *bad_a, long long *bad_b)
{
    size_t n = (size_t)a->width * (size_t)a->height;
    unsigned char *valid = malloc(n ? n : 1);
    if (!valid)
        return NULL;
    *bad_a = *bad_b = 0;
    for (size_t i = 0; i < n; i++) {
        const float *pa = a->pixels + i * (size_t)a->channels;
        const float *pb = b->pixels + i * (size_t)b->channels;
        int fa = 1, fb = 1;
        for (int c = 0; c < s->n; c++) {
            fa &= isfinite(pa[s->ia[c]]) != 0;
            fb &= isfinite(pb[s->ib[c]]) != 0;
        }
        *bad_a += !fa;
        *bad_b += !fb;
        valid[i] = (unsigned char)(fa && fb);
    }
    return valid;
}

/* ------------------------------------------------------------------ SSIM */

/* The normalised 1-D Gaussian; the 2-D window is its outer product. */
static void tb__ssim_kernel(double g[TB_COMPARE_SSIM_WINDOW])
{
    const int r = TB_COMPARE_SSIM_WINDOW / 2;
    double sum = 0.0;
    for (int i = 0; i < TB_COMPARE_SSIM_WINDOW; i++) {
        double d = (double)(i - r);
        g[i] = exp(-d * d / (2.0 * TB_COMPARE_SSIM_SIGMA * TB_COMPARE_SSIM_SIGMA));
        sum += g[i];
    }
    for (int i = 0; i < TB_COMPARE_SSIM_WINDOW; i++)
        g[i] /= sum;
}

/* Mean SSIM of one channel over the windows that hold no excluded pixel.
 * The Gaussian filter is separable: each input row is filtered horizontally
 * (x, y, x^2, y^2, xy, and a count of excluded pixels) into a ring of
 * 11 rows, and each output row sums 11 of those vertically, so memory grows
 * with the width only. Excluded pixels read as 0; the windows holding them
 * are skipped. */
static tb_status tb__ssim_channel(const tb_image *a, int ca, const tb_image *b, int cb,
                                  const unsigned char *valid, double peak, double *ssim,
                                  long long *nwin)
{
    enum { W = TB_COMPARE_SSIM_WINDOW, NQ = 5 };
    int w = a->width, h = a->height;
    int ow = w - W + 1;
    double g[TB_COMPARE_SSIM_WINDOW];
    tb__ssim_kernel(g);
    size_t ring = (size_t)W * (size_t)ow; /* per quantity: W filtered rows */
    double *hq = malloc(NQ * ring * sizeof *hq);
    int *hbad = malloc(ring * sizeof *hbad);
    double *row = malloc(2 * (size_t)w * sizeof *row);
    if (!hq || !hbad || !row) {
        free(hq);
        free(hbad);
        free(row);
        return tb_error(TB_ERR_NOMEM, "no memory for SSIM of a %dx%d image", w, h);
    }
    const double c1 = (TB_COMPARE_SSIM_K1 * peak) * (TB_COMPARE_SSIM_K1 * peak);
    const double c2 = (TB_COMPARE_SSIM_K2 * peak) * (TB_COMPARE_SSIM_K2 * peak);
    double *rx = row, *ry = row + w;
    double sum = 0.0;
    long long count = 0;
    for (int y = 0; y < h; y++) {
        /* horizontal pass of input row y into ring slot y % W */
        size_t slot = (size_t)(y % W) * (size_t)ow;
        const unsigned char *vrow = valid + (size_t)y * (size_t)w;
        for (int x = 0; x < w; x++) {
            size_t i = (size_t)y * (size_t)w + (size_t)x;
            rx[x] = vrow[x] ? (double)a->pixels[i * (size_t)a->channels + (size_t)ca] : 0.0;
            ry[x] = vrow[x] ? (double)b->pixels[i * (size_t)b->channels + (size_t)cb] : 0.0;
        }
        for (int x = 0; x < ow; x++) {
            double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
            int bad = 0;
            for (int k = 0; k < W; k++) {
                double vx = rx[x + k], vy = ry[x + k];
                sx += g[k] * vx;
                sy += g[k] * vy;
                sxx += g[k] * vx * vx;
                syy += g[k] * vy * vy;
                sxy += g[k] * vx * vy;
                bad += !vrow[x + k];
            }
            size_t o = slot + (size_t)x;
            hq[o] = sx, hq[ring + o] = sy, hq[2 * ring + o] = sxx;
            hq[3 * ring + o] = syy, hq[4 * ring + o] = sxy;
            hbad[o] = bad;
        }
        /* vertical pass: output row oy = y - W + 1 uses input rows oy..y */
        int oy = y - W + 1;
        if (oy < 0)
            continue;
        for (int x = 0; x < ow; x++) {
            double mx = 0, my = 0, exx = 0, eyy = 0, exy = 0;
            int bad = 0;
            for (int k = 0; k < W; k++) {
                size_t o = (size_t)((oy + k) % W) * (size_t)ow + (size_t)x;
                mx += g[k] * hq[o];
                my += g[k] * hq[ring + o];
                exx += g[k] * hq[2 * ring + o];
                eyy += g[k] * hq[3 * ring + o];
                exy += g[k] * hq[4 * ring + o];
                bad += hbad[o];
            }
            if (bad)
                continue;
            double vx = exx - mx * mx, vy = eyy - my * my, cxy = exy - mx * my;
            sum += ((2.0 * mx * my + c1) * (2.0 * cxy + c2)) /
                   ((mx * mx + my * my + c1) * (vx + vy + c2));
            count++;
        }
    }
    free(hq);
    free(hbad);
    free(row);
    *ssim = count > 0 ? sum / (double)count : NAN;
    *nwin = count;
    return TB_OK;
}

/* ------------------------------------------------------------------ metrics */

static double tb__psnr(double mse, double peak)
{
    if (isnan(mse))
        return NAN;
    if (mse == 0.0)
        return INFINITY;
    return 10.0 * log10(peak * peak / mse);
}

tb_status tb_image_compare(const tb_image *a, const tb_image *b, const tb_compare_options *opts,
                           tb_compare_result *res)
{
    if (!res)
        return tb_error(TB_ERR_ARG, "tb_image_compare: result is NULL");
    memset(res, 0, sizeof *res);
    tb_status st = tb__cmp_check(a, b);
    if (st)
        return st;
    double peak = opts && opts->peak != 0.0 ? opts->peak : 1.0;
    if (!(peak > 0.0) || !isfinite(peak))
        return tb_error(TB_ERR_ARG, "peak must be positive and finite, not %g", peak);
    tb__cmp_sel s;
    if ((st = tb__cmp_select(a, b, opts, &s)))
        return st;

    int w = a->width, h = a->height;
    res->width = w;
    res->height = h;
    res->peak = peak;
    res->nchannels = s.n;
    memcpy(res->names, s.names, sizeof s.names);
    res->pixels = (long long)w * h;
    unsigned char *valid = tb__cmp_valid(a, b, &s, &res->nonfinite_a, &res->nonfinite_b);
    if (!valid)
        return tb_error(TB_ERR_NOMEM, "no memory for a %dx%d mask", w, h);

    long long nvalid = 0;
    size_t npix = (size_t)w * (size_t)h;
    for (size_t i = 0; i < npix; i++)
        nvalid += valid[i];
    res->valid_pixels = nvalid;

    int ssim_fits = w >= TB_COMPARE_SSIM_WINDOW && h >= TB_COMPARE_SSIM_WINDOW;

    double sum_mse = 0, sum_rel = 0, sum_ssim = 0;
    res->all.max_abs = nvalid > 0 ? 0.0 : NAN;
    res->all.max_x = res->all.max_y = -1;
    res->max_channel = -1;
    for (int c = 0; c < s.n; c++) {
        tb_compare_stats *cs = &res->channel[c];
        double se = 0, rel = 0, mx = -1;
        int mxx = -1, mxy = -1;
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                size_t i = (size_t)y * (size_t)w + (size_t)x;
                if (!valid[i])
                    continue;
                double va = a->pixels[i * (size_t)a->channels + (size_t)s.ia[c]];
                double vb = b->pixels[i * (size_t)b->channels + (size_t)s.ib[c]];
                double d = va - vb;
                se += d * d;
                rel += d * d / (vb * vb + TB_COMPARE_RELMSE_EPS);
                if (fabs(d) > mx) {
                    mx = fabs(d);
                    mxx = x;
                    mxy = y;
                }
            }
        cs->mse = nvalid > 0 ? se / (double)nvalid : NAN;
        cs->rmse = sqrt(cs->mse);
        cs->relmse = nvalid > 0 ? rel / (double)nvalid : NAN;
        cs->psnr = tb__psnr(cs->mse, peak);
        cs->max_abs = nvalid > 0 ? mx : NAN;
        cs->max_x = mxx;
        cs->max_y = mxy;
        cs->ssim = NAN;
        if (ssim_fits && (st = tb__ssim_channel(a, s.ia[c], b, s.ib[c], valid, peak, &cs->ssim,
                                                &res->ssim_windows))) {
            free(valid);
            return st;
        }
        sum_mse += cs->mse;
        sum_rel += cs->relmse;
        sum_ssim += cs->ssim;
        if (nvalid > 0 && (res->max_channel < 0 || cs->max_abs > res->all.max_abs)) {
            res->all.max_abs = cs->max_abs;
            res->all.max_x = mxx;
            res->all.max_y = mxy;
            res->max_channel = c;
        }
    }
    res->all.mse = sum_mse / s.n;
    res->all.rmse = sqrt(res->all.mse);
    res->all.relmse = sum_rel / s.n;
    res->all.psnr = tb__psnr(res->all.mse, peak);
    res->all.ssim = sum_ssim / s.n;
    free(valid);
    return TB_OK;
}

/* ------------------------------------------------------------------ error image */

/* viridis (van der Walt and Smith, matplotlib, CC0): entries
 * round(k * 255 / 16) of its 256-entry table, sRGB-encoded. */
#define TB__VIRIDIS_N 17
static const unsigned char tb__viridis_index[TB__VIRIDIS_N] = {
    0, 16, 32, 48, 64, 80, 96, 112, 128, 143, 159, 175, 191, 207, 223, 239, 255};
static const float tb__viridis[TB__VIRIDIS_N][3] = {
    {0.267004f, 0.004874f, 0.329415f}, {0.282327f, 0.094955f, 0.417331f},
    {0.278826f, 0.175490f, 0.483397f}, {0.258965f, 0.251537f, 0.524736f},
    {0.229739f, 0.322361f, 0.545706f}, {0.199430f, 0.387607f, 0.554642f},
    {0.172719f, 0.448791f, 0.557885f}, {0.149039f, 0.508051f, 0.557250f},
    {0.127568f, 0.566949f, 0.550556f}, {0.120081f, 0.622161f, 0.534946f},
    {0.153894f, 0.680203f, 0.504172f}, {0.239374f, 0.735588f, 0.455688f},
    {0.360741f, 0.785964f, 0.387814f}, {0.506271f, 0.828786f, 0.300362f},
    {0.668054f, 0.861999f, 0.196293f}, {0.835270f, 0.886029f, 0.102646f},
    {0.993248f, 0.906157f, 0.143936f},
};

void tb_compare_colormap(double t, float rgb[3])
{
    if (isnan(t)) {
        rgb[0] = 1.0f, rgb[1] = 0.0f, rgb[2] = 1.0f;
        return;
    }
    double u = (t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t) * 255.0; /* position in the 256-entry table */
    int k = 0;
    while (k < TB__VIRIDIS_N - 2 && u > tb__viridis_index[k + 1])
        k++;
    double u0 = tb__viridis_index[k], u1 = tb__viridis_index[k + 1];
    double f = (u - u0) / (u1 - u0);
    for (int c = 0; c < 3; c++) {
        double e = tb__viridis[k][c] + f * (tb__viridis[k + 1][c] - tb__viridis[k][c]);
        rgb[c] = tb_srgb_decode((float)e);
    }
}

tb_status tb_compare_error_image(const tb_image *a, const tb_image *b,
                                 const tb_compare_options *opts, double scale, tb_image **out,
                                 double *scale_used)
{
    if (!out)
        return tb_error(TB_ERR_ARG, "tb_compare_error_image: out is NULL");
    *out = NULL;
    tb_status st = tb__cmp_check(a, b);
    if (st)
        return st;
    if (isnan(scale) || isinf(scale))
        return tb_error(TB_ERR_ARG, "error scale must be finite");
    tb__cmp_sel s;
    if ((st = tb__cmp_select(a, b, opts, &s)))
        return st;
    int w = a->width, h = a->height;
    size_t npix = (size_t)w * (size_t)h;
    double *err = malloc(npix * sizeof *err);
    if (!err)
        return tb_error(TB_ERR_NOMEM, "no memory for a %dx%d error map", w, h);
    double emax = 0.0;
    for (size_t i = 0; i < npix; i++) {
        double se = 0.0;
        int finite = 1;
        for (int c = 0; c < s.n; c++) {
            float va = a->pixels[i * (size_t)a->channels + (size_t)s.ia[c]];
            float vb = b->pixels[i * (size_t)b->channels + (size_t)s.ib[c]];
            finite &= isfinite(va) && isfinite(vb);
            double d = (double)va - (double)vb;
            se += d * d;
        }
        err[i] = finite ? sqrt(se / s.n) : NAN;
        if (finite && err[i] > emax)
            emax = err[i];
    }
    if (scale <= 0.0)
        scale = emax > 0.0 ? emax : 1.0;

    tb_image *img = tb_image_create(w, h, 3, NULL);
    if (!img) {
        free(err);
        return tb_error_context(TB_ERR_NOMEM, "error image");
    }
    for (size_t i = 0; i < npix; i++)
        tb_compare_colormap(isnan(err[i]) ? NAN : err[i] / scale, img->pixels + 3 * i);
    free(err);

    char text[64];
    snprintf(text, sizeof text, "%.9g", scale);
    if ((st = tb_image_set_attr(img, "compare.scale", text)) ||
        (st = tb_image_set_attr(img, "compare.colormap", "viridis"))) {
        tb_image_free(img);
        return st;
    }
    if (scale_used)
        *scale_used = scale;
    *out = img;
    return TB_OK;
}
