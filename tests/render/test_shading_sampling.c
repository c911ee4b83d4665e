/* Sampling matches pdf: a chi-square goodness-of-fit test (Mitsuba 3's
 * method, test_shading_support.h) for every warping function of sampling.h
 * and every sampled shading model at several incident directions, plus the
 * integral of each pdf (1 where nothing is refused; else the fraction of
 * successful samples). Fixed seeds; rejection at TST_CHI2_ALPHA = 1e-3. */
#include "tb_test.h"

#include "host/render/sampling.h"
#include "host/render/shading.h"
#include "test_shading_support.h"

/* Samples per chi-square run: 200000, divided by $TB_SHADING_TEST_DIVISOR
 * (the unoptimised sanitizer build sets 4). */
static long nsamples(void)
{
    const char *e = getenv("TB_SHADING_TEST_DIVISOR");
    long d = e ? atol(e) : 1;
    return 200000L / (d > 0 ? d : 1);
}
#define NSAMPLES nsamples()
#define NPHI 48
#define NZ 24

/* -------------------------------------------------------------- warps */

typedef struct warp_ctx {
    int which;      /* 0 cosine, 1 uniform hemisphere, 2 sphere, 3 cone, 4 power cosine */
    double param;   /* cone: cos_max; power: n */
} warp_ctx;

static bool warp_sample(void *c_, float uc, float u1, float u2, tb_vec3 *w)
{
    (void)uc;
    warp_ctx *c = c_;
    switch (c->which) {
    case 0: *w = tb_sample_cosine_hemisphere(u1, u2); break;
    case 1: *w = tb_sample_uniform_hemisphere(u1, u2); break;
    case 2: *w = tb_sample_uniform_sphere(u1, u2); break;
    case 3: *w = tb_sample_uniform_cone(u1, u2, c->param); break;
    default: *w = tb_sample_power_cosine(u1, u2, c->param); break;
    }
    return true;
}

static double warp_pdf(void *c_, tb_vec3 w)
{
    warp_ctx *c = c_;
    switch (c->which) {
    case 0: return tb_cosine_hemisphere_pdf(w.z);
    case 1: return w.z >= 0.0f ? tb_uniform_hemisphere_pdf() : 0.0;
    case 2: return tb_uniform_sphere_pdf();
    case 3: return w.z >= c->param ? tb_uniform_cone_pdf(c->param) : 0.0;
    default: return tb_power_cosine_pdf(w.z, c->param);
    }
}

static void check(const tst_chi2 *r, bool normalised)
{
    assert_false(r->zero_bin_hit);
    if (!(r->p_value >= TST_CHI2_ALPHA))
        fail_msg("chi-square rejects: p = %g < %g", r->p_value, TST_CHI2_ALPHA);
    /* The density integrates to the fraction of samples produced. */
    double sd = sqrt(r->hist_sum * (1.0 - r->hist_sum) / NSAMPLES);
    tb_assert_near(r->pdf_sum, r->hist_sum, 5.0 * sd + 2e-4);
    if (normalised) {
        tb_assert_near(r->pdf_sum, 1.0, 2e-4);
        assert_true(r->hist_sum == 1.0);
    }
}

static void test_warps(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("warps", 31);
    struct {
        const char *name;
        warp_ctx c;
    } cases[] = {
        {"cosine hemisphere", {0, 0.0}},
        {"uniform hemisphere", {1, 0.0}},
        {"uniform sphere", {2, 0.0}},
        /* Cone edges on bin edges (z = -1 + k/12): the pdf jumps there. */
        {"cone cos_max 0.5", {3, 0.5}},
        {"cone cos_max -0.5", {3, -0.5}},
        {"cone cos_max 0.91666", {3, 11.0 / 12.0}},
        {"power cosine n 1", {4, 1.0}},
        {"power cosine n 30", {4, 30.0}},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        tst_chi2 r = tst_chi2_run(cases[k].name, warp_sample, warp_pdf, &cases[k].c, NSAMPLES,
                                  NPHI, NZ, seed + k);
        check(&r, true);
    }
}

/* Uniform disc and triangle: chi-square on a planar grid of 16 x 16 cells. */
static void test_disc_triangle(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("disc/triangle", 32);
    tb_rng rng;
    tb_rng_seed(&rng, seed, 0);
    enum { G = 16 };
    for (int shape = 0; shape < 2; shape++) {
        static double obs[G * G];
        memset(obs, 0, sizeof obs);
        long n = NSAMPLES;
        for (long k = 0; k < n; k++) {
            float u1 = tb_rng_float(&rng), u2 = tb_rng_float(&rng);
            double x, y;
            if (shape == 0) {
                tb_vec2 d = tb_sample_disk_concentric(u1, u2);
                x = 0.5 * (d.x + 1.0);
                y = 0.5 * (d.y + 1.0);
                assert_true(d.x * d.x + d.y * d.y <= 1.0f + 1e-6f);
            } else {
                /* Triangle (0,0) (1,0) (0,1): p = b0 v0 + b1 v1 + b2 v2. */
                tb_vec2 b = tb_sample_triangle(u1, u2);
                assert_true(b.x >= 0.0f && b.y >= 0.0f && b.x + b.y <= 1.0f + 1e-6f);
                x = b.y;
                y = 1.0 - b.x - b.y;
            }
            int i = (int)(x * G), j = (int)(y * G);
            i = i < 0 ? 0 : (i >= G ? G - 1 : i);
            j = j < 0 ? 0 : (j >= G ? G - 1 : j);
            obs[j * G + i] += 1.0;
        }
        /* Expected: area of the shape inside each cell (fine midpoint grid, 64^2 per cell). */
        double stat = 0.0;
        int dof = -1;
        double area = shape == 0 ? M_PI / 4.0 : 0.5; /* in the unit square's coordinates */
        for (int j = 0; j < G; j++)
            for (int i = 0; i < G; i++) {
                int inside = 0;
                for (int a = 0; a < 64; a++)
                    for (int b = 0; b < 64; b++) {
                        double x = (i + (a + 0.5) / 64) / G, y = (j + (b + 0.5) / 64) / G;
                        bool in = shape == 0 ? (2 * x - 1) * (2 * x - 1) + (2 * y - 1) * (2 * y - 1) <= 1.0
                                             : x + y <= 1.0;
                        inside += in;
                    }
                /* Cells cut by the boundary are left out (their area estimate is inexact). */
                if (inside != 64 * 64) {
                    if (inside == 0)
                        assert_true(obs[j * G + i] == 0.0);
                    continue;
                }
                double e = n * (1.0 / (G * G)) / area;
                stat += (obs[j * G + i] - e) * (obs[j * G + i] - e) / e;
                dof++;
            }
        /* Cells left out lower the count in the others only through the
         * constant expected value, so the statistic is still chi^2 with dof
         * degrees of freedom up to the (binomial) dependence; accept at 1e-3. */
        double p = tst_gamma_q(0.5 * dof, 0.5 * stat);
        printf("[ chi2     ] %-40s p = %.4g  chi2 = %.1f  dof = %d\n", shape ? "triangle" : "disc", p,
               stat, dof);
        assert_true(p >= TST_CHI2_ALPHA);
    }
}

/* ------------------------------------------------------------- models */

typedef struct bsdf_ctx {
    tb_bsdf b;
    tb_vec3 wo;
} bsdf_ctx;

static bool bsdf_sample(void *c_, float uc, float u1, float u2, tb_vec3 *w)
{
    bsdf_ctx *c = c_;
    tb_bsdf_sampled s;
    if (!tb_bsdf_sample(&c->b, c->wo, uc, u1, u2, &s))
        return false;
    *w = s.wi;
    return true;
}

static double bsdf_pdf(void *c_, tb_vec3 w)
{
    bsdf_ctx *c = c_;
    return tb_bsdf_pdf(&c->b, c->wo, w);
}

static tb_vec3 dir_at(double deg, bool below)
{
    double t = deg * M_PI / 180.0;
    return tb_vec3_make((float)(sin(t) * 0.8), (float)(sin(t) * 0.6), (float)(below ? -cos(t) : cos(t)));
}

static void run_model(const char *what, tb_bsdf b, const double *angles, int nangles, bool below,
                      bool normalised_at_normal, uint64_t seed)
{
    for (int a = 0; a < nangles; a++) {
        bsdf_ctx c = {b, dir_at(angles[a], below)};
        char name[96];
        snprintf(name, sizeof name, "%s, theta_o %g%s", what, angles[a], below ? " (inside)" : "");
        tst_chi2 r = tst_chi2_run(name, bsdf_sample, bsdf_pdf, &c, NSAMPLES, NPHI, NZ, seed + a);
        check(&r, normalised_at_normal && angles[a] == 0.0);
    }
}

static void test_lambert(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("lambert chi2", 33);
    const double ang[] = {0.0, 60.0};
    tb_bsdf b = tb_bsdf_lambert(tb_channels_splat(1, 0.8f));
    /* Lambert never refuses a sample: normalised at every angle. */
    for (int below = 0; below < 2; below++)
        for (int a = 0; a < 2; a++) {
            bsdf_ctx c = {b, dir_at(ang[a], below)};
            tst_chi2 r = tst_chi2_run(below ? "lambert (back side)" : "lambert", bsdf_sample, bsdf_pdf,
                                      &c, NSAMPLES, NPHI, NZ, seed + 2 * a + below);
            check(&r, true);
        }
}

static void test_phong_blinn(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("phong chi2", 34);
    tb_channels one = tb_channels_splat(1, 1.0f);
    const double ang[] = {0.0, 75.0, 40.0};
    run_model("phong n 4", tb_bsdf_phong(one, 4.0, true), ang, 3, false, true, seed);
    run_model("phong n 40", tb_bsdf_phong(one, 40.0, false), ang, 2, false, true, seed + 10);
    run_model("blinn n 6", tb_bsdf_blinn(one, 6.0, TB_BSDF_BLINN_NORMALIZED), ang, 3, false, false,
              seed + 20);
    run_model("blinn n 80", tb_bsdf_blinn(one, 80.0, TB_BSDF_BLINN), ang, 2, true, false, seed + 30);
}

static void test_ggx(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("ggx chi2", 35);
    tb_channels one = tb_channels_splat(1, 1.0f);
    const double ang[] = {0.0, 80.0, 45.0};
    run_model("ggx alpha 0.1", tb_bsdf_ggx(one, 0.1, TB_FRESNEL_NONE, 1.5), ang, 3, false, false, seed);
    run_model("ggx alpha 0.4", tb_bsdf_ggx(one, 0.4, TB_FRESNEL_SCHLICK, 1.5), ang + 2, 1, true, false,
              seed + 10);
    run_model("ggx alpha 1", tb_bsdf_ggx(one, 1.0, TB_FRESNEL_DIELECTRIC, 1.5), ang, 2, false, false,
              seed + 20);
}

static void test_ggx_dielectric(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("dielectric chi2", 36);
    tb_channels one = tb_channels_splat(1, 1.0f);
    const double ang[] = {0.0, 70.0, 30.0};
    run_model("rough glass alpha 0.2", tb_bsdf_ggx_dielectric(one, 0.2, 1.5), ang, 2, false, false, seed);
    /* From inside: below (30) and beyond (70) the critical angle (41.8 degrees). */
    run_model("rough glass alpha 0.2", tb_bsdf_ggx_dielectric(one, 0.2, 1.5), ang + 1, 2, true, false,
              seed + 10);
    run_model("rough glass alpha 0.7", tb_bsdf_ggx_dielectric(one, 0.7, 1.33), ang + 2, 1, false, false,
              seed + 20);
}

/* The visible normal distribution itself: samples m, density D_wo(m). */
typedef struct vndf_ctx {
    double alpha;
    tb_vec3 w;
} vndf_ctx;

static bool vndf_sample(void *c_, float uc, float u1, float u2, tb_vec3 *m)
{
    (void)uc;
    vndf_ctx *c = c_;
    *m = tb_ggx_sample_vndf(c->alpha, c->w, u1, u2);
    return true;
}

static double vndf_pdf(void *c_, tb_vec3 m)
{
    vndf_ctx *c = c_;
    return tb_ggx_vndf_pdf(c->alpha, c->w, m);
}

static void test_vndf(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("vndf chi2", 37);
    const double alphas[] = {0.15, 1.0};
    const double ang[] = {0.0, 85.0};
    for (int k = 0; k < 2; k++)
        for (int a = 0; a < 2; a++) {
            vndf_ctx c = {alphas[k], dir_at(ang[a], false)};
            char name[64];
            snprintf(name, sizeof name, "vndf alpha %g, theta %g", alphas[k], ang[a]);
            tst_chi2 r = tst_chi2_run(name, vndf_sample, vndf_pdf, &c, NSAMPLES, NPHI, NZ,
                                      seed + 3 * k + a);
            check(&r, true); /* the visible normals are a normalised density */
        }
}

/* The test can fail: a sampler checked against a slightly wrong density (the
 * power cosine lobe n = 30 against the pdf of n = 28, a 6 % narrower
 * exponent) is rejected, and so is a cosine sampler checked against the
 * uniform hemisphere. */
typedef struct mismatch_ctx {
    warp_ctx sample, pdf;
} mismatch_ctx;

static bool mismatch_sample(void *c_, float uc, float u1, float u2, tb_vec3 *w)
{
    return warp_sample(&((mismatch_ctx *)c_)->sample, uc, u1, u2, w);
}

static double mismatch_pdf(void *c_, tb_vec3 w) { return warp_pdf(&((mismatch_ctx *)c_)->pdf, w); }

static void test_chi2_rejects_wrong_pdf(void **state)
{
    (void)state;
    mismatch_ctx c = {{4, 30.0}, {4, 28.0}};
    tst_chi2 r = tst_chi2_run("power n 30 vs pdf of n 28 (must fail)", mismatch_sample, mismatch_pdf,
                              &c, NSAMPLES, NPHI, NZ, 99);
    assert_true(r.p_value < TST_CHI2_ALPHA);
    mismatch_ctx d = {{0, 0.0}, {1, 0.0}};
    r = tst_chi2_run("cosine vs uniform pdf (must fail)", mismatch_sample, mismatch_pdf, &d, NSAMPLES,
                     NPHI, NZ, 99);
    assert_true(r.p_value < TST_CHI2_ALPHA);
}

/* tb_sincos_2pi against cos and sin of 2 pi u in long double (u every
 * step of 2^-20 in [0, 1], and random doubles): within 2.5e-16 absolute (a
 * couple of units in the last place for values in [-1, 1]; libm's double
 * cos / sin of the rounded 2 pi u, printed for comparison, are off by up
 * to ~4.4e-16 near u = 1 from that rounding alone), and exactly 0 / +-1 at
 * the quarter turns. Fails when a polynomial term or a quadrant turn is
 * wrong. */
static double sincos_err(double u, double *libm_err)
{
    double c, s;
    tb_sincos_2pi(u, &c, &s);
    long double a = (long double)u * 6.283185307179586476925286766559005768L;
    long double rc = cosl(a), rs = sinl(a);
    *libm_err = fmax(*libm_err, fmax(fabs((double)(cos(2.0 * TB_PI * u) - rc)), fabs((double)(sin(2.0 * TB_PI * u) - rs))));
    return fmax(fabs((double)(c - rc)), fabs((double)(s - rs)));
}

static void test_sincos_2pi(void **state)
{
    (void)state;
    double worst = 0.0, libm = 0.0;
    for (int i = 0; i <= (1 << 20); i++)
        worst = fmax(worst, sincos_err((double)i * 0x1p-20, &libm));
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("sincos_2pi", 5), 1);
    for (int i = 0; i < 200000; i++)
        worst = fmax(worst, sincos_err(tb_rng_double(&r), &libm));
    print_message("tb_sincos_2pi: largest error %.3g (libm cos/sin of the rounded 2 pi u: %.3g)\n", worst, libm);
    assert_true(worst <= 2.5e-16);
    const double q[5][3] = {{0.0, 1.0, 0.0}, {0.25, 0.0, 1.0}, {0.5, -1.0, 0.0}, {0.75, 0.0, -1.0}, {1.0, 1.0, 0.0}};
    for (int i = 0; i < 5; i++) {
        double c, s;
        tb_sincos_2pi(q[i][0], &c, &s);
        assert_true(c == q[i][1] && s == q[i][2]);
    }
}

/* tb_distrib1d_sample_discrete (inline in sampling.h) on weights {1, 0, 3}
 * (cdf 0, 1/4, 1/4, 1): the item, its probability and the remapped u, at
 * slice ends, inside slices, for u = 1 and NaN; the weight-0 item is never
 * picked. A single item gives back u itself. Fails when the search, the
 * clamps or the remap change. */
static void test_distrib_discrete(void **state)
{
    (void)state;
    tb_distrib1d d;
    assert_int_equal(tb_distrib1d_init(&d, (const double[]){1.0, 0.0, 3.0}, 3), TB_OK);
    const double cases[][4] = {
        /* u, item, pmf, remapped u */
        {0.0, 0, 0.25, 0.0},   {0.125, 0, 0.25, 0.5}, {0.25, 2, 0.75, 0.0},
        {0.625, 2, 0.75, 0.5}, {-1.0, 0, 0.25, 0.0},  {NAN, 0, 0.25, 0.0},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        double pmf = -1.0, ur = -1.0;
        int i = tb_distrib1d_sample_discrete(&d, cases[k][0], &pmf, &ur);
        assert_int_equal(i, (int)cases[k][1]);
        assert_true(pmf == cases[k][2] && ur == cases[k][3]);
    }
    double pmf, ur;
    assert_int_equal(tb_distrib1d_sample_discrete(&d, 1.0, &pmf, &ur), 2);
    assert_true(ur < 1.0 && ur > 0.999999);
    assert_int_equal(tb_distrib1d_sample_discrete(&d, 0.9, NULL, NULL), 2);
    tb_distrib1d_release(&d);
    assert_int_equal(tb_distrib1d_init(&d, (const double[]){2.5}, 1), TB_OK);
    assert_int_equal(tb_distrib1d_sample_discrete(&d, 0.3f, &pmf, &ur), 0);
    assert_true(pmf == 1.0 && ur == (double)0.3f);
    tb_distrib1d_release(&d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_distrib_discrete),
        cmocka_unit_test(test_sincos_2pi),
        cmocka_unit_test(test_warps),
        cmocka_unit_test(test_disc_triangle),
        cmocka_unit_test(test_lambert),
        cmocka_unit_test(test_phong_blinn),
        cmocka_unit_test(test_ggx),
        cmocka_unit_test(test_ggx_dielectric),
        cmocka_unit_test(test_vndf),
        cmocka_unit_test(test_chi2_rejects_wrong_pdf),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
