/* Texture antialiasing on analytic patterns.
 *
 * Grazing checkerboard: a pinhole camera at height 1 looks along the plane
 * y = 0 towards the horizon; (u, v) = (x, z) on the plane carries 64 x 64
 * checks per unit. Each pixel's footprint (du/dx, dv/dx, du/dy, dv/dy) is
 * computed analytically from the camera. Far from the camera a pixel covers
 * many checks, so its correct value is grey: every far pixel must be within a
 * tolerance of 0.5, and the spread over the far pixels must be small (no
 * moire). Checked for an image checker through trilinear and EWA filtering
 * and for the procedural checker with its closed-form box filter; plain
 * bilinear lookups (no prefiltering) serve as the control that shows the
 * test catches aliasing. Near rows are compared with supersampled box and
 * Gaussian pixel filters.
 *
 * EWA against trilinear: a cosine grating seen through an 8:1 footprint whose
 * short axis runs across the stripes. Trilinear picks its level by the long
 * axis and blurs the stripes away; EWA picks it by the short axis and keeps
 * them, while still removing stripes that run along the long axis. */
#include "tb_test.h"

#include <string.h>

#include "host/render/texture.h"
#include "util/math/float.h"

enum { W = 128, R = 128 }; /* image columns, rows below the horizon */
static const double F = 128.0; /* focal length in pixels */
static const double CHECKS = 64.0; /* checks per unit of u and v */

/* Ray direction (a, -b, 1) of pixel (i, j); j = 0 is the row just below the horizon. */
static void pixel_ab(double px, double py, double *a, double *b)
{
    *a = (px - W / 2.0) / F;
    *b = py / F;
}

/* (u, v) seen at continuous pixel position (px, py). */
static void pixel_uv(double px, double py, double *u, double *v)
{
    double a, b;
    pixel_ab(px, py, &a, &b);
    *u = a / b;
    *v = 1.0 / b;
}

/* The analytic footprint at the centre of pixel (i, j): derivatives of
 * u = a / b and v = 1 / b with a = (x - W/2)/F, b = y / F. */
static tb_tex_footprint footprint(int i, int j, double *u, double *v)
{
    double a, b;
    pixel_ab(i + 0.5, j + 0.5, &a, &b);
    *u = a / b;
    *v = 1.0 / b;
    tb_tex_footprint fp = {(float)(1.0 / (b * F)), 0.0f, (float)(-a / (b * b * F)), (float)(-1.0 / (b * b * F))};
    return fp;
}

static double point_checker(double px, double py)
{
    double u, v;
    pixel_uv(px, py, &u, &v);
    long k = (long)floor(u * CHECKS) + (long)floor(v * CHECKS);
    return (double)(k & 1);
}

/* References through the exact mapping: the point checker averaged over the
 * pixel (box filter, 16 x 16 grid), and weighted by a Gaussian of standard
 * deviation 1/2 pixel (the filter EWA approximates; 24 x 24 grid over +-1.5
 * pixels). */
static void reference(int i, int j, double *box, double *gauss)
{
    double b = 0.0, g = 0.0, gw = 0.0;
    for (int sy = 0; sy < 16; sy++)
        for (int sx = 0; sx < 16; sx++)
            b += point_checker(i + (sx + 0.5) / 16.0, j + (sy + 0.5) / 16.0);
    for (int sy = 0; sy < 24; sy++)
        for (int sx = 0; sx < 24; sx++) {
            double ox = -1.5 + (sx + 0.5) / 8.0, oy = -1.5 + (sy + 0.5) / 8.0;
            double w = exp(-(ox * ox + oy * oy) / (2.0 * 0.25));
            g += w * point_checker(i + 0.5 + ox, j + 0.5 + oy);
            gw += w;
        }
    *box = b / 256.0;
    *gauss = g / gw;
}

/* A 192 x 192 checker image with 3-texel checks: 64 x 64 checks per period.
 * A size that is not a power of two, so the pyramid is not simply grey from
 * some level on: levels 1-3 hold checks 1.5, 0.75 and 0.375 texels wide.
 * Texel rows run down the image and v up, so the check parity of texel
 * (x, y) is that of (x/3) + (191 - y)/3, the same checker as the procedural
 * one at (u, v) = texel centre. */
static tb_mipmap *checker_image(void)
{
    tb_image *img = tb_image_create(192, 192, 1, NULL);
    for (int y = 0; y < 192; y++)
        for (int x = 0; x < 192; x++)
            tb_image_at(img, x, y)[0] = (float)(((x / 3) + ((191 - y) / 3)) & 1);
    tb_mipmap *m = tb_mipmap_create(img);
    tb_image_free(img);
    return m;
}

typedef struct result {
    double far_mean, far_maxdev, far_sd; /* far rows: against grey */
    double near_box, near_gauss;         /* near rows: RMS against the references */
} result;

/* Evaluates `t` for every pixel; "far" = rows where a pixel is at least two
 * checks wide (b <= 1/4: j < 32), "near" = every other pixel of rows 64 and
 * below (checks at least 1 pixel wide), against the references. */
static result render(const tb_texture *t)
{
    result r = {0};
    double s = 0, s2 = 0, nb = 0, ng = 0;
    int nfar = 0, nnear = 0;
    for (int j = 0; j < R; j++)
        for (int i = 0; i < W; i++) {
            double u, v;
            tb_tex_query q = {0};
            q.fp = footprint(i, j, &u, &v);
            q.u = (float)u;
            q.v = (float)v;
            float val = tb_texture_eval1(t, &q);
            if (j < 32) {
                s += val;
                s2 += val * val;
                r.far_maxdev = fmax(r.far_maxdev, fabs(val - 0.5));
                nfar++;
            } else if (j >= 64 && ((i + j) & 1) == 0) {
                double box, gauss;
                reference(i, j, &box, &gauss);
                nb += (val - box) * (val - box);
                ng += (val - gauss) * (val - gauss);
                nnear++;
            }
        }
    r.far_mean = s / nfar;
    r.far_sd = sqrt(fmax(0.0, s2 / nfar - r.far_mean * r.far_mean));
    r.near_box = sqrt(nb / nnear);
    r.near_gauss = sqrt(ng / nnear);
    return r;
}

static void test_grazing_checker(void **state)
{
    (void)state;
    /* the geometry: far rows span at least 2 checks across and 8 along */
    double u, v;
    tb_tex_footprint fp = footprint(0, 31, &u, &v);
    assert_true(fp.dudx * CHECKS >= 2.0 && fabs(fp.dvdy) * CHECKS >= 8.0);
    fp = footprint(64, 127, &u, &v);
    assert_true(fp.dudx * CHECKS < 1.0); /* near rows: checks wider than a pixel */

    tb_mipmap *m = checker_image();
    /* the image and the procedural checker agree at texel centres */
    for (int y = 0; y < 192; y += 2)
        for (int x = 0; x < 192; x += 5) {
            double cu = (x + 0.5) / 192.0, cv = 1.0 - (y + 0.5) / 192.0;
            long k = (long)floor(cu * CHECKS) + (long)floor(cv * CHECKS);
            assert_true(m->levels[0].texels[y * 192 + x] == (float)(k & 1));
        }
    const float zero = 0.0f, one = 1.0f;
    tb_texture tex[4];
    const char *names[4] = {"EWA", "trilinear", "procedural box", "bilinear (control)"};
    tex[0] = tb_texture_image(m, TB_TEX_EWA, TB_TEX_REPEAT);
    tex[1] = tb_texture_image(m, TB_TEX_TRILINEAR, TB_TEX_REPEAT);
    tex[2] = tb_texture_checker(1, &zero, &one, true);
    tex[2].su = tex[2].sv = (float)CHECKS;
    tex[3] = tb_texture_image(m, TB_TEX_BILINEAR, TB_TEX_REPEAT);
    result res[4];
    for (int k = 0; k < 4; k++) {
        res[k] = render(&tex[k]);
        print_message("[ grazing  ] %-19s far pixels: mean %.4f, max |v - 0.5| %.4f, sd %.4f; "
                      "near pixels RMS vs box %.4f, vs Gaussian %.4f\n", names[k], res[k].far_mean,
                      res[k].far_maxdev, res[k].far_sd, res[k].near_box, res[k].near_gauss);
    }
    /* filtered lookups: grey, no pattern */
    for (int k = 0; k < 3; k++) {
        tb_assert_near(res[k].far_mean, 0.5, 0.01);
        assert_true(res[k].far_maxdev <= 0.06);
        assert_true(res[k].far_sd <= 0.02);
    }
    /* near rows: EWA is the Gaussian pixel filter it approximates; the
     * procedural checker's box follows the box reference; trilinear (a
     * bilinear tent over texels as large as the long axis) blurs more than a
     * box, so it is held to the Gaussian reference with a wider margin */
    assert_true(res[0].near_gauss < 0.05);
    assert_true(res[2].near_box < 0.1);
    assert_true(res[1].near_gauss < 0.1);
    /* the control aliases: far pixels are black or white in a pattern */
    assert_true(res[3].far_sd > 0.3 && res[3].far_maxdev > 0.45);
    tb_mipmap_free(m);
}

/* ------------------------------------------------------------- EWA vs trilinear */

/* Modulation kept by a lookup: (max - min) / (2 * 0.5) of a grating
 * 0.5 + 0.5 cos(2 pi x / period) sampled across a whole period. */
static double modulation(const tb_mipmap *m, tb_tex_filter f, const tb_tex_footprint *fp, bool across_u)
{
    double lo = INFINITY, hi = -INFINITY;
    for (int k = 0; k < 64; k++) {
        double c = (k + 0.5) / 256.0 * 0.25; /* one period (16 texels) in 64 steps */
        float u = across_u ? (float)(0.5 + c) : 0.5f, v = across_u ? 0.5f : (float)(0.5 + c);
        float out;
        tb_mipmap_lookup(m, f, u, v, fp, TB_TEX_REPEAT, 8.0f, &out);
        lo = fmin(lo, out);
        hi = fmax(hi, out);
    }
    return hi - lo;
}

static void test_ewa_sharper(void **state)
{
    (void)state;
    const double period = 16.0;
    /* stripes across u (vary with x) and stripes across v (vary with y) */
    tb_image *gu = tb_image_create(256, 256, 1, NULL), *gv = tb_image_create(256, 256, 1, NULL);
    for (int y = 0; y < 256; y++)
        for (int x = 0; x < 256; x++) {
            tb_image_at(gu, x, y)[0] = (float)(0.5 + 0.5 * cos(2 * TB_PI * (x + 0.5) / period));
            tb_image_at(gv, x, y)[0] = (float)(0.5 + 0.5 * cos(2 * TB_PI * (y + 0.5) / period));
        }
    tb_mipmap *mu = tb_mipmap_create(gu), *mv = tb_mipmap_create(gv);
    for (double minor = 1.0; minor <= 4.0; minor *= 2.0) {
        /* short axis along u (minor texels), long axis along v (8 x minor) */
        tb_tex_footprint fp = {(float)(minor / 256.0), 0.0f, 0.0f, (float)(8.0 * minor / 256.0)};
        double ewa = modulation(mu, TB_TEX_EWA, &fp, true);
        double tri = modulation(mu, TB_TEX_TRILINEAR, &fp, true);
        /* an ideal one-pixel box across the stripes keeps sinc(minor / period) */
        double x = TB_PI * minor / period, ideal = sin(x) / x;
        /* stripes along the long axis: the ideal box of 8 x minor texels keeps |sinc(8 minor / period)| */
        double ewa_long = modulation(mv, TB_TEX_EWA, &fp, false);
        double x8 = TB_PI * 8.0 * minor / period, ideal_long = fabs(sin(x8) / x8);
        print_message("[ sharp    ] footprint %gx%g texels: stripes across the short axis keep %.3f (EWA) vs "
                      "%.3f (trilinear), ideal box %.3f; along the long axis EWA keeps %.3f, ideal %.3f\n",
                      minor, 8 * minor, ewa, tri, ideal, ewa_long, ideal_long);
        assert_true(ewa > tri + 0.3);
        assert_true(ewa > 0.5 * ideal);
        /* not sharp by aliasing: stripes along the long axis are blurred away */
        assert_true(ewa_long < ideal_long + 0.15);
    }
    tb_mipmap_free(mu);
    tb_mipmap_free(mv);
    tb_image_free(gu);
    tb_image_free(gv);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_grazing_checker),
        cmocka_unit_test(test_ewa_sharper),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
