/* The composite BSDF of host/render/surface.h (docs/rendering.md,
 * "Surfaces, BSDFs and lights"), built from hand-made surface records:
 *
 *  - chi-square (test_shading_support.h, Mitsuba 3's method) of the
 *    directions tb_surface_bsdf_sample returns through its non-delta lobes
 *    against tb_surface_bsdf_pdf, for Lambert + normalised Phong, + exact
 *    Blinn, + GGX, GGX alone, a bumped shading normal (tilted from the
 *    geometric one: samples below the geometric surface are refused and the
 *    pdf is zero there), and Lambert beside a dielectric (whose delta
 *    samples are not counted: the pdf integrates to the fraction left);
 *  - white furnace: the mean sample weight (the directional albedo, delta
 *    lobes included) is <= 1 for every lobe combination whose colours sum to
 *    at most 1, and equals an independent estimate, the integral of
 *    tb_surface_bsdf_eval |cos| over the sphere by uniform sampling plus
 *    the dielectric's (R + T kt) times its share 1 - max(diffuse), each
 *    within 4 sigma;
 *  - eval is zero for directions on the other side of the geometric surface
 *    and pdf is zero where eval is. */
#include "tb_test.h"

#include "host/render/sampling.h"
#include "host/render/surface.h"
#include "test_shading_support.h"

/* Samples per run: 200000, divided by $TB_SHADING_TEST_DIVISOR (the
 * sanitizer build sets 4). */
static long nsamples(void)
{
    const char *e = getenv("TB_SHADING_TEST_DIVISOR");
    long d = e ? atol(e) : 1;
    return 200000L / (d > 0 ? d : 1);
}
#define NPHI 48
#define NZ 24

/* A material on the plane z = 0 (geometric normal +z, viewer above). */
typedef struct mat {
    const char *name;
    double kd, ks, kt;
    tb_mid_model model;
    double exponent, roughness, ior;
    double tilt;         /* degrees the shading normal leans from +z (a bump) */
    tb_surface_mode mode;
} mat;

static tb_surface make_surface(const mat *m, tb_vec3 wo)
{
    tb_surface sf;
    memset(&sf, 0, sizeof sf);
    sf.ng = sf.nv = tb_vec3_make(0, 0, 1);
    sf.front = true;
    double t = m->tilt * M_PI / 180.0;
    sf.n = tb_vec3_make((float)sin(t), 0.0f, (float)cos(t));
    sf.wo = wo;
    sf.model = m->model;
    sf.exponent = (float)m->exponent;
    sf.roughness = (float)m->roughness;
    sf.ior = (float)m->ior;
    sf.diffuse = tb_channels_splat(3, (float)m->kd);
    sf.specular = tb_channels_splat(3, (float)m->ks);
    sf.transmission = tb_channels_splat(3, (float)m->kt);
    sf.emission = tb_channels_splat(3, 0.0f);
    return sf;
}

static tb_vec3 dir_at(double deg)
{
    double t = deg * M_PI / 180.0;
    return tb_vec3_make((float)(sin(t) * 0.8), (float)(sin(t) * 0.6), (float)cos(t));
}

typedef struct ctx {
    tb_surface_bsdf b;
    tb_vec3 wo;
} ctx;

static bool sample_nondelta(void *c_, float uc, float u1, float u2, tb_vec3 *w)
{
    ctx *c = c_;
    tb_surface_sample s;
    if (!tb_surface_bsdf_sample(&c->b, c->wo, uc, u1, u2, &s) || s.delta)
        return false;
    *w = s.wi;
    return true;
}

static double pdf_fn(void *c_, tb_vec3 w)
{
    ctx *c = c_;
    return tb_surface_bsdf_pdf(&c->b, c->wo, w);
}

static const mat MATS[] = {
    {"lambert 1", 1.0, 0, 0, TB_MID_MODEL_LAMBERT, 0, 0, 1, 0, TB_SURFACE_PHYSICAL},
    {"lambert 0.5 + phong 0.5 n 20", 0.5, 0.5, 0, TB_MID_MODEL_PHONG, 20, 0, 1, 0, TB_SURFACE_PHYSICAL},
    {"lambert 0.3 + blinn 0.7 n 100", 0.3, 0.7, 0, TB_MID_MODEL_BLINN, 100, 0, 1, 0, TB_SURFACE_PHYSICAL},
    {"lambert 0.5 + ggx 0.5 a 0.3", 0.5, 0.5, 0, TB_MID_MODEL_GGX, 0, 0.3, 1, 0, TB_SURFACE_PHYSICAL},
    {"ggx 1 a 0.15", 0.0, 1.0, 0, TB_MID_MODEL_GGX, 0, 0.15, 1, 0, TB_SURFACE_PHYSICAL},
    {"bumped 25 deg: lambert 0.6 + ggx 0.4", 0.6, 0.4, 0, TB_MID_MODEL_GGX, 0, 0.4, 1, 25, TB_SURFACE_PHYSICAL},
    {"lambert 0.3 + dielectric 0.9 ior 1.33", 0.3, 0, 0.9, TB_MID_MODEL_PHONG, 20, 0, 1.33, 0, TB_SURFACE_PHYSICAL},
    {"glass: dielectric 1 ior 1.5 (+ ks 0.05)", 0.0, 0.05, 1.0, TB_MID_MODEL_PHONG, 1e4, 0, 1.5, 0,
     TB_SURFACE_PHYSICAL},
    {"whitted: lambert 0.5 + mirror 0.5", 0.5, 0.5, 0, TB_MID_MODEL_PHONG, 20, 0, 1, 0, TB_SURFACE_WHITTED},
};
#define NMATS ((int)(sizeof MATS / sizeof MATS[0]))

static void test_chi2(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("surface bsdf chi2", 171);
    static const double angles[] = {0.0, 50.0, 80.0};
    const long n = nsamples();
    for (int m = 0; m < NMATS; m++) {
        if (MATS[m].kd == 0.0 && MATS[m].kt > 0.0)
            continue; /* delta only: nothing to bin */
        for (int a = 0; a < 3; a++) {
            ctx c;
            c.wo = dir_at(angles[a]);
            tb_surface sf = make_surface(&MATS[m], c.wo);
            tb_surface_bsdf_init(&sf, MATS[m].mode, &c.b);
            char name[96];
            snprintf(name, sizeof name, "%s, theta_o %g", MATS[m].name, angles[a]);
            tst_chi2 r = tst_chi2_run(name, sample_nondelta, pdf_fn, &c, n, NPHI, NZ, seed + 10 * (uint64_t)m + a);
            assert_false(r.zero_bin_hit);
            if (!(r.p_value >= TST_CHI2_ALPHA))
                fail_msg("%s: chi-square rejects, p = %g", name, r.p_value);
            double sd = sqrt(r.hist_sum * (1.0 - r.hist_sum) / n);
            tb_assert_near(r.pdf_sum, r.hist_sum, 5.0 * sd + 2e-3);
        }
    }
}

static void test_white_furnace(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("surface bsdf furnace", 172);
    static const double angles[] = {0.0, 40.0, 75.0};
    const long n = nsamples();
    for (int m = 0; m < NMATS; m++)
        for (int a = 0; a < 3; a++) {
            tb_vec3 wo = dir_at(angles[a]);
            tb_surface sf = make_surface(&MATS[m], wo);
            tb_surface_bsdf b;
            tb_surface_bsdf_init(&sf, MATS[m].mode, &b);
            tb_rng rng;
            tb_rng_seed(&rng, seed + 10 * (uint64_t)m + a, 5);
            /* the sampler's estimate: mean weight */
            double s1 = 0.0, s2 = 0.0;
            for (long i = 0; i < n; i++) {
                tb_surface_sample s;
                float uc = tb_rng_float(&rng), u1 = tb_rng_float(&rng), u2 = tb_rng_float(&rng);
                double w = tb_surface_bsdf_sample(&b, wo, uc, u1, u2, &s) ? s.weight.v[1] : 0.0;
                s1 += w;
                s2 += w * w;
            }
            double E = s1 / n, seE = sqrt(fmax(0.0, s2 / n - E * E) / n);
            /* independent: eval |cos| over the sphere, uniformly, plus the delta lobes */
            double t1 = 0.0, t2 = 0.0;
            for (long i = 0; i < n; i++) {
                tb_vec3 wi = tb_sample_uniform_sphere(tb_rng_float(&rng), tb_rng_float(&rng));
                double v = tb_surface_bsdf_eval(&b, wo, wi).v[1] * fabs((double)tb_vec3_dot(wi, sf.n)) * 4.0 * M_PI;
                t1 += v;
                t2 += v * v;
            }
            double I = t1 / n, seI = sqrt(fmax(0.0, t2 / n - I * I) / n);
            if (b.lobes & TB_LOBE_DIELECTRIC) {
                double R = tb_fresnel_dielectric(wo.z, MATS[m].ior);
                I += b.dielectric * (R + (1.0 - R) * MATS[m].kt);
            }
            if (b.lobes & TB_LOBE_MIRROR)
                I += MATS[m].ks;
            double sd = sqrt(seE * seE + seI * seI);
            printf("[ furnace  ] %-42s theta %2g: albedo %.4f +- %.4f, by eval %.4f +- %.4f\n", MATS[m].name,
                   angles[a], E, seE, I, seI);
            if (!(E <= 1.0 + 4.0 * seE))
                fail_msg("%s: albedo %.4f > 1", MATS[m].name, E);
            if (!(fabs(E - I) <= 4.0 * sd + 1e-6))
                fail_msg("%s theta %g: sampled albedo %.4f vs eval %.4f: %.2f sigma", MATS[m].name, angles[a], E, I,
                         fabs(E - I) / sd);
        }
}

/* eval and pdf vanish below the geometric surface, even for a bumped normal. */
static void test_sides(void **state)
{
    (void)state;
    const mat *m = &MATS[5];
    tb_vec3 wo = dir_at(30.0);
    tb_surface sf = make_surface(m, wo);
    tb_surface_bsdf b;
    tb_surface_bsdf_init(&sf, m->mode, &b);
    tb_rng rng;
    tb_rng_seed(&rng, 3, 3);
    for (int i = 0; i < 10000; i++) {
        tb_vec3 wi = tb_sample_uniform_sphere(tb_rng_float(&rng), tb_rng_float(&rng));
        double f = tb_surface_bsdf_eval(&b, wo, wi).v[0], p = tb_surface_bsdf_pdf(&b, wo, wi);
        if (wi.z < 0.0f) {
            assert_true(f == 0.0 && p == 0.0);
        } else {
            assert_true(f >= 0.0 && p >= 0.0);
            assert_true((f > 0.0) == (p > 0.0) || f < 1e-30 || p < 1e-30);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sides),
        cmocka_unit_test(test_chi2),
        cmocka_unit_test(test_white_furnace),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
