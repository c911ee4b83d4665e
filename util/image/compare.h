/* Image comparison: error metrics between a test image A and a reference B,
 * and a false-colour picture of where they differ.
 *
 * Channels. By default the colour channels both images share are compared:
 * R,G,B if both have all three, else Y if both have it, else every channel
 * name present in both (A's order), "A" (alpha) excluded unless asked for.
 * `channels` in the options names them explicitly instead; each must exist in
 * both images. No conversion between RGB and Y is attempted: an RGB image
 * and a Y image have nothing in common and comparing them is an error.
 *
 * Metrics, per compared channel c over the N comparable pixels:
 *   MSE_c    = mean (a - b)^2                 RMSE_c = sqrt(MSE_c)
 *   relMSE_c = mean (a - b)^2 / (b^2 + eps)   eps = 0.01, b = reference
 *              (the relative MSE of the rendering literature, e.g. Rousselle
 *              et al. 2011: it weights errors in dark regions up)
 *   PSNR_c   = 10 log10(peak^2 / MSE_c) dB    +inf when MSE_c = 0
 *   SSIM_c   = Wang, Bovik, Sheikh, Simoncelli 2004: 11x11 Gaussian window
 *              (sigma 1.5, normalised to sum 1), K1 = 0.01, K2 = 0.03,
 *              L = peak, C1 = (K1 L)^2, C2 = (K2 L)^2; the mean of the SSIM
 *              map over every window lying wholly inside the image (MATLAB
 *              "valid" filtering, no downsampling). NaN when the image is
 *              smaller than 11x11.
 *   max_c    = max |a - b|, with the pixel where it first occurs (row-major).
 * The "all" row: MSE and relMSE are the mean over channels (= over all
 * samples), RMSE and PSNR follow from that MSE, SSIM is the mean of the
 * per-channel SSIMs (channels are not mixed into a luminance), and max is the
 * largest over channels.
 *
 * Non-finite values. A pixel where any compared channel of A or B is NaN or
 * +-Inf is excluded from every metric (counted in nonfinite_a / nonfinite_b
 * and left out of valid_pixels); SSIM uses only windows without such pixels.
 * So one bad pixel cannot turn every number into NaN, and the counts say that
 * something was left out. If no pixel is comparable the metrics are NaN.
 *
 * Error image. Per pixel, e = sqrt(mean over compared channels of (a - b)^2)
 * (|a - b| for a single channel), mapped through viridis (matplotlib's
 * perceptually uniform map, 17 samples, linearly interpolated) with
 * t = min(e / scale, 1): 0 is dark purple, `scale` and above is yellow.
 * scale <= 0 means automatic: the largest e (1 if every e is 0). The map's
 * sRGB colours are stored as linear values (sRGB-decoded), so an 8-bit file
 * written with the default sRGB encoding shows exactly viridis. Pixels
 * excluded for NaN/Inf are magenta (1, 0, 1), which viridis never produces. */
#ifndef TB_UTIL_IMAGE_COMPARE_H
#define TB_UTIL_IMAGE_COMPARE_H

#include "util/image/image.h"

/* Most channels one comparison covers. */
#define TB_COMPARE_MAX_CHANNELS 16

/* eps in relMSE = mean (a-b)^2 / (b^2 + eps). */
#define TB_COMPARE_RELMSE_EPS 0.01

/* SSIM window: size (odd), Gaussian sigma and the constants K1, K2. */
#define TB_COMPARE_SSIM_WINDOW 11
#define TB_COMPARE_SSIM_SIGMA 1.5
#define TB_COMPARE_SSIM_K1 0.01
#define TB_COMPARE_SSIM_K2 0.03

/* Options for tb_image_compare(); a zeroed struct means the defaults. */
typedef struct tb_compare_options {
    double peak;          /* largest signal value, for PSNR and SSIM's L; 0 means 1.0 */
    const char *channels; /* comma-separated names to compare ("R,G,B"); NULL = automatic */
    int include_alpha;    /* nonzero: automatic selection also compares "A" when both have it */
} tb_compare_options;

/* The metrics of one channel, or of all compared channels together. */
typedef struct tb_compare_stats {
    double mse, rmse, relmse;
    double psnr;          /* dB; +INFINITY when mse is 0 */
    double ssim;          /* NaN when no 11x11 window fits or none is free of NaN/Inf */
    double max_abs;       /* largest |a - b| */
    int max_x, max_y;     /* where max_abs occurs (y = 0 at the top); -1 if no pixel was comparable */
} tb_compare_stats;

/* Everything tb_image_compare() measures. */
typedef struct tb_compare_result {
    int width, height;
    double peak;                  /* the peak used */
    int nchannels;                /* channels compared */
    char names[TB_COMPARE_MAX_CHANNELS][TB_IMAGE_CHANNEL_NAME_MAX]; /* their names */
    tb_compare_stats channel[TB_COMPARE_MAX_CHANNELS];              /* per channel */
    tb_compare_stats all;         /* over all compared channels (see the file comment) */
    int max_channel;              /* index into names of all.max_abs; -1 if none */
    long long pixels;             /* width * height */
    long long valid_pixels;       /* pixels entering the metrics */
    long long nonfinite_a;        /* pixels with a NaN/Inf compared channel in A */
    long long nonfinite_b;        /* same in B */
    long long ssim_windows;       /* SSIM windows used (per channel) */
} tb_compare_result;

/* Compares test image `a` with reference `b` (same size; see the file comment
 * for channels, metrics and the NaN rule). `opts` may be NULL. TB_ERR_ARG on
 * a size mismatch or when the channels cannot be matched. */
tb_status tb_image_compare(const tb_image *a, const tb_image *b, const tb_compare_options *opts,
                           tb_compare_result *res);

/* False-colour error image (R,G,B) of `a` against `b` over the same channels
 * as tb_image_compare(); `scale` <= 0 means automatic. The scale used is
 * stored in *scale_used (may be NULL) and in the attribute "compare.scale". */
tb_status tb_compare_error_image(const tb_image *a, const tb_image *b,
                                 const tb_compare_options *opts, double scale, tb_image **out,
                                 double *scale_used);

/* The error colour map at t in [0, 1] (clamped; NaN gives magenta), as linear RGB. */
void tb_compare_colormap(double t, float rgb[3]);

#endif
