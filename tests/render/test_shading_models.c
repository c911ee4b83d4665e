/* Shading models: Fresnel against the textbook angle forms, Snell's law,
 * reflection, the Whitted split, reciprocity of every model, and the
 * analytic values of the Phong/Blinn lobes and GGX terms. */
#include "tb_test.h"

#include "host/render/shading.h"
#include "test_shading_support.h"

/* Fresnel reflectance from the angle forms (Born & Wolf):
 * Rs = sin^2(ti - tt) / sin^2(ti + tt), Rp = tan^2(ti - tt) / tan^2(ti + tt),
 * with tt from Snell's law; n1 on the incident side. Independent of the
 * cosine form in shading.c. */
static double ref_fresnel(double theta_i, double n1, double n2)
{
    double st = n1 / n2 * sin(theta_i);
    if (st >= 1.0)
        return 1.0;
    double tt = asin(st);
    if (theta_i == 0.0) {
        double r = (n1 - n2) / (n1 + n2);
        return r * r;
    }
    double rs = sin(theta_i - tt) / sin(theta_i + tt);
    double rp = tan(theta_i - tt) / tan(theta_i + tt);
    return 0.5 * (rs * rs + rp * rp);
}

static void test_fresnel_normal_incidence(void **state)
{
    (void)state;
    const double etas[] = {1.0001, 1.1, 1.333, 1.5, 2.42, 1.0 / 1.5, 0.5};
    for (size_t k = 0; k < sizeof etas / sizeof etas[0]; k++) {
        double eta = etas[k];
        double want = ((eta - 1.0) / (eta + 1.0)) * ((eta - 1.0) / (eta + 1.0));
        tb_assert_near(tb_fresnel_dielectric(1.0, eta), want, 1e-15);
        /* From the inside at normal incidence: the same reflectance. */
        tb_assert_near(tb_fresnel_dielectric(-1.0, eta), want, 1e-15);
        tb_assert_near(tb_fresnel_f0(eta), want, 1e-15);
        tb_assert_near(tb_fresnel_schlick(1.0, want), want, 1e-15);
    }
    assert_true(tb_fresnel_dielectric(0.3, 1.0) == 0.0);
}

static void test_fresnel_matches_angle_form(void **state)
{
    (void)state;
    const double etas[] = {1.2, 1.5, 2.0};
    for (size_t k = 0; k < 3; k++)
        for (int a = 0; a <= 89; a++) {
            double th = a * M_PI / 180.0;
            double eta = etas[k];
            /* Outside (n1 = 1, n2 = eta) and inside (n1 = eta, n2 = 1). */
            /* Both forms lose digits next to the critical angle (cos theta_t -> 0). */
            double tol = fabs(th - asin(1.0 / eta)) > 0.01 ? 1e-12 : 1e-6;
            tb_assert_near(tb_fresnel_dielectric(cos(th), eta), ref_fresnel(th, 1.0, eta), 1e-12);
            tb_assert_near(tb_fresnel_dielectric(-cos(th), eta), ref_fresnel(th, eta, 1.0), tol);
        }
}

static void test_fresnel_grazing_and_tir(void **state)
{
    (void)state;
    double eta = 1.5;
    assert_true(tb_fresnel_dielectric(0.0, eta) == 1.0);
    assert_true(tb_fresnel_dielectric(1e-9, eta) > 1.0 - 1e-8);
    assert_true(tb_fresnel_schlick(0.0, 0.04) == 1.0);
    /* Total internal reflection beyond the critical angle asin(1 / eta). */
    double tc = asin(1.0 / eta);
    for (int k = 1; k <= 50; k++) {
        double th = tc + (M_PI / 2.0 - tc) * k / 51.0;
        assert_true(tb_fresnel_dielectric(-cos(th), eta) == 1.0);
    }
    assert_true(tb_fresnel_dielectric(-cos(tc + 1e-6), eta) == 1.0);
    assert_true(tb_fresnel_dielectric(-cos(tc - 1e-3), eta) < 1.0);
    assert_true(tb_fresnel_dielectric(-cos(tc - 1e-3), eta) > 0.5); /* steep just below */
}

/* Random unit vector (uniform on the sphere). */
static tb_vec3 rand_dir(tb_rng *r)
{
    double z = 1.0 - 2.0 * tb_rng_double(r), p = 2.0 * M_PI * tb_rng_double(r);
    double s = sqrt(fmax(0.0, 1.0 - z * z));
    return tb_vec3_make((float)(s * cos(p)), (float)(s * sin(p)), (float)z);
}

static void test_snell(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("snell", 11), 0);
    int refracted = 0, tir = 0;
    for (int k = 0; k < 20000; k++) {
        tb_vec3 n = rand_dir(&rng), wi = rand_dir(&rng);
        double eta = 0.4 + 2.2 * tb_rng_double(&rng);
        double ci = (double)n.x * wi.x + (double)n.y * wi.y + (double)n.z * wi.z;
        double n1 = ci >= 0.0 ? 1.0 : eta, n2 = ci >= 0.0 ? eta : 1.0; /* n points outside (index 1) */
        double si = sqrt(fmax(0.0, 1.0 - ci * ci));
        tb_vec3 wt;
        double etap = 0.0;
        bool ok = tb_refract(wi, n, eta, &wt, &etap);
        double st_want = n1 / n2 * si;
        if (st_want > 1.0 + 1e-6) {
            assert_false(ok);
            tir++;
            continue;
        }
        if (st_want < 1.0 - 1e-6)
            assert_true(ok);
        if (!ok)
            continue;
        refracted++;
        tb_assert_near(etap, n2 / n1, 1e-12);
        double ct = (double)n.x * wt.x + (double)n.y * wt.y + (double)n.z * wt.z;
        /* Opposite side, unit length, Snell's law n1 sin ti = n2 sin tt. */
        assert_true(ci * ct <= 0.0);
        tb_assert_near(tb_vec3_length(wt), 1.0, 1e-6);
        double st = sqrt(fmax(0.0, 1.0 - ct * ct));
        tb_assert_near(n1 * si, n2 * st, 1e-5);
        /* Coplanar: wt lies in the plane of wi and n. */
        tb_vec3 c = tb_vec3_cross(wi, n);
        tb_assert_near(tb_vec3_dot(c, wt), 0.0, 1e-5);
        /* And on the far side of n from wi's tangent part (no reversal). */
        tb_vec3 ti = tb_vec3_sub(wi, tb_vec3_scale(n, (float)ci));
        tb_vec3 tt = tb_vec3_sub(wt, tb_vec3_scale(n, (float)ct));
        assert_true(tb_vec3_dot(ti, tt) <= 1e-6f);
    }
    assert_true(refracted > 10000 && tir > 500);
}

static void test_reflect_and_split(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("reflect", 12), 0);
    for (int k = 0; k < 5000; k++) {
        tb_vec3 n = rand_dir(&rng), w = rand_dir(&rng);
        tb_vec3 r = tb_reflect(w, n);
        tb_assert_near(tb_vec3_dot(r, n), tb_vec3_dot(w, n), 5e-7);
        tb_assert_near(tb_vec3_length(r), 1.0, 1e-6);
        /* r + w is along n. */
        tb_vec3 s = tb_vec3_add(r, w);
        tb_assert_near(tb_vec3_length(tb_vec3_cross(s, n)), 0.0, 1e-6);
    }
    for (int k = 0; k < 5000; k++) {
        tb_vec3 wo = rand_dir(&rng);
        double eta = 1.5;
        tb_specular_split sp;
        tb_specular_dielectric(wo, eta, &sp);
        assert_true(sp.wr.x == -wo.x && sp.wr.y == -wo.y && sp.wr.z == wo.z);
        tb_assert_near(sp.R + sp.T, 1.0, 0.0);
        if (sp.refracts) {
            tb_assert_near(sp.R, tb_fresnel_dielectric(wo.z, eta), 0.0);
            assert_true(sp.wt.z * wo.z <= 0.0f);
        } else {
            assert_true(wo.z < 0.0f); /* TIR only from inside */
            assert_true(sp.R == 1.0 && sp.T == 0.0);
            double s = sqrt(1.0 - (double)wo.z * wo.z);
            assert_true(s * eta >= 1.0 - 1e-6);
        }
    }
}

/* ---------------------------------------------------------- reciprocity */

static tb_bsdf make_model(int which)
{
    tb_channels c = tb_channels_rgb(0.9f, 0.5f, 0.25f);
    switch (which) {
    case 0: return tb_bsdf_lambert(c);
    case 1: return tb_bsdf_phong(c, 12.0, false);
    case 2: return tb_bsdf_phong(c, 37.5, true);
    case 3: return tb_bsdf_blinn(c, 8.0, TB_BSDF_BLINN);
    case 4: return tb_bsdf_blinn(c, 60.0, TB_BSDF_BLINN_NORMALIZED);
    case 5: return tb_bsdf_blinn(c, 3.0, TB_BSDF_BLINN_NORMALIZED_EXACT);
    case 6: return tb_bsdf_ggx(c, 0.3, TB_FRESNEL_NONE, 1.5);
    case 7: return tb_bsdf_ggx(c, 0.6, TB_FRESNEL_SCHLICK, 1.5);
    case 8: return tb_bsdf_ggx(c, 0.15, TB_FRESNEL_DIELECTRIC, 1.7);
    case 9: return tb_bsdf_ggx_dielectric(c, 0.35, 1.5);
    default: return tb_bsdf_ggx_dielectric(c, 0.8, 1.0 / 1.33);
    }
}
#define NMODELS 11

static void test_reciprocity(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("reciprocity", 13), 0);
    for (int m = 0; m < NMODELS; m++) {
        tb_bsdf b = make_model(m);
        int nonzero = 0;
        for (int k = 0; k < 20000; k++) {
            tb_vec3 wo = rand_dir(&rng), wi = rand_dir(&rng);
            if (fabsf(wo.z) < 1e-3f || fabsf(wi.z) < 1e-3f)
                continue;
            tb_channels a = tb_bsdf_eval(&b, wo, wi), c = tb_bsdf_eval(&b, wi, wo);
            /* Transmission: f(wo, wi) n_i^2 = f(wi, wo) n_o^2 (n_x: index on x's side). */
            double sa = 1.0, sc = 1.0;
            if (b.kind == TB_BSDF_GGX_DIELECTRIC && wo.z * wi.z < 0.0f) {
                double ni = wi.z > 0.0f ? 1.0 : b.eta, no = wo.z > 0.0f ? 1.0 : b.eta;
                sa = ni * ni;
                sc = no * no;
            }
            for (int i = 0; i < a.n; i++) {
                double x = a.v[i] * sa, y = c.v[i] * sc;
                assert_true(x >= 0.0 && isfinite(x));
                if (!(fabs(x - y) <= 2e-5 * fmax(fabs(x), fabs(y)) + 1e-30))
                    fail_msg("model %d: f(wo,wi) = %.9g, f(wi,wo) = %.9g (channel %d, wo %g %g %g, wi %g %g %g)",
                             m, x, y, i, wo.x, wo.y, wo.z, wi.x, wi.y, wi.z);
            }
            nonzero += a.v[0] > 0.0f;
        }
        assert_true(nonzero > 100); /* the test saw the lobe */
    }
}

/* Reflection models are zero across the surface, and two-sided. */
static void test_sidedness(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("sides", 14), 0);
    for (int m = 0; m < 9; m++) {
        tb_bsdf b = make_model(m);
        for (int k = 0; k < 2000; k++) {
            tb_vec3 wo = rand_dir(&rng), wi = rand_dir(&rng);
            tb_channels f = tb_bsdf_eval(&b, wo, wi);
            if (wo.z * wi.z <= 0.0f)
                assert_true(tb_channels_is_black(f) && tb_bsdf_pdf(&b, wo, wi) == 0.0);
            tb_vec3 wo2 = tb_vec3_make(wo.x, wo.y, -wo.z), wi2 = tb_vec3_make(wi.x, wi.y, -wi.z);
            tb_channels g = tb_bsdf_eval(&b, wo2, wi2);
            for (int i = 0; i < f.n; i++)
                tb_assert_near(f.v[i], g.v[i], 1e-6 * fabs(f.v[i]));
        }
    }
}

/* ------------------------------------------------------ analytic values */

static void test_lobe_values(void **state)
{
    (void)state;
    tb_channels one = tb_channels_splat(1, 1.0f);
    /* Lambert: 1/pi everywhere on the same side. */
    tb_bsdf l = tb_bsdf_lambert(tb_channels_splat(1, 0.7f));
    tb_assert_near(tb_bsdf_eval(&l, tb_vec3_make(0.6f, 0, 0.8f), tb_vec3_make(0, -0.28f, 0.96f)).v[0],
                   0.7 / M_PI, 1e-7);
    /* Phong at the mirror direction = k; at angle a from it, k cos^n a. */
    double n = 20.0;
    tb_bsdf p = tb_bsdf_phong(one, n, true);
    tb_vec3 wo = tb_vec3_make(0.6f, 0.0f, 0.8f), r = tb_vec3_make(-0.6f, 0.0f, 0.8f);
    tb_assert_near(tb_bsdf_eval(&p, wo, r).v[0], (n + 2) / (2 * M_PI), 1e-5);
    double a = 0.1, th = acos(0.8);
    tb_vec3 wi = tb_vec3_make((float)-sin(th + a), 0.0f, (float)cos(th + a));
    tb_assert_near(tb_bsdf_eval(&p, wo, wi).v[0], (n + 2) / (2 * M_PI) * pow(cos(a), n), 1e-5);
    /* Blinn at theta_h: wo, wi symmetric about a tilted h. */
    tb_bsdf bl = tb_bsdf_blinn(one, n, TB_BSDF_BLINN);
    double th_h = 0.2;
    tb_vec3 h = tb_vec3_make((float)sin(th_h), 0.0f, (float)cos(th_h));
    tb_vec3 wo2 = tb_vec3_make(0.0f, 0.0f, 1.0f);
    tb_vec3 wi2 = tb_reflect(wo2, h);
    tb_assert_near(tb_bsdf_eval(&bl, wo2, wi2).v[0], pow(cos(th_h), n), 1e-5);
    /* Normalisations (docs/shading.md). */
    tb_assert_near(tb_bsdf_lobe_norm(TB_BSDF_PHONG, n), 1.0, 0.0);
    tb_assert_near(tb_bsdf_lobe_norm(TB_BSDF_PHONG_NORMALIZED, n), (n + 2) / (2 * M_PI), 1e-15);
    tb_assert_near(tb_bsdf_lobe_norm(TB_BSDF_BLINN_NORMALIZED, n), (n + 8) / (8 * M_PI), 1e-15);
    tb_assert_near(tb_bsdf_lobe_norm(TB_BSDF_BLINN_NORMALIZED_EXACT, n),
                   (n + 2) * (n + 4) / (8 * M_PI * (pow(2.0, -n / 2) + n)), 1e-15);
}

static void test_ggx_terms(void **state)
{
    (void)state;
    /* D at the pole = 1 / (pi alpha^2); alpha = 1 is uniform 1/pi. */
    tb_assert_near(tb_ggx_D(0.25, tb_vec3_make(0, 0, 1)), 1.0 / (M_PI * 0.0625), 1e-9);
    tb_assert_near(tb_ggx_D(1.0, tb_vec3_make(0.6f, 0, 0.8f)), 1.0 / M_PI, 1e-7);
    assert_true(tb_ggx_D(0.5, tb_vec3_make(0.6f, 0, -0.8f)) == 0.0);
    /* Lambda at normal incidence is 0; at theta with alpha = 1: (1/cos - 1)/2. */
    tb_assert_near(tb_ggx_lambda(0.3, tb_vec3_make(0, 0, 1)), 0.0, 0.0);
    tb_assert_near(tb_ggx_lambda(1.0, tb_vec3_make(0.6f, 0, 0.8f)), (1.0 / 0.8 - 1.0) / 2.0, 1e-7);
    /* D is normalised: int D(m) m.z dm = 1. Midpoint rule in x with
     * cos theta = 1 - x^2, which puts many nodes in narrow lobes. */
    const double alphas[] = {0.05, 0.3, 1.0};
    for (int k = 0; k < 3; k++) {
        double s = 0.0;
        int N = 200000;
        for (int i = 0; i < N; i++) {
            double x = (i + 0.5) / N, z = 1.0 - x * x;
            double sz = sqrt(1 - z * z);
            s += tb_ggx_D(alphas[k], tb_vec3_make((float)sz, 0, (float)z)) * z * 2.0 * x;
        }
        s *= 2.0 * M_PI / N;
        tb_assert_near(s, 1.0, 1e-5);
    }
    /* Height-correlated G2 lies between the uncorrelated product and the smaller G1. */
    tb_vec3 wo = tb_vec3_make(0.6f, 0, 0.8f), wi = tb_vec3_make(-0.8f, 0, 0.6f);
    double g2 = tb_ggx_G2(0.5, wo, wi), g1o = tb_ggx_G1(0.5, wo), g1i = tb_ggx_G1(0.5, wi);
    assert_true(g2 >= g1o * g1i - 1e-12 && g2 <= fmin(g1o, g1i) + 1e-12);
}

static void test_sample_consistency(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("sample", 15), 0);
    for (int m = 0; m < NMODELS; m++) {
        tb_bsdf b = make_model(m);
        int ok = 0;
        for (int k = 0; k < 5000; k++) {
            tb_vec3 wo = rand_dir(&rng);
            tb_bsdf_sampled s;
            if (!tb_bsdf_sample(&b, wo, tb_rng_float(&rng), tb_rng_float(&rng), tb_rng_float(&rng), &s)) {
                assert_true(s.pdf == 0.0);
                continue;
            }
            ok++;
            tb_assert_near(tb_vec3_length(s.wi), 1.0, 1e-6);
            double pdf = tb_bsdf_pdf(&b, wo, s.wi);
            /* Equal up to the rounding of wi to float (which matters more
             * where the density is tiny and steep). */
            double rel = pdf > 1e-3 ? 1e-5 : 1e-2;
            if (!(fabs(s.pdf - pdf) <= rel * pdf))
                fail_msg("model %d: sampled pdf %.17g, tb_bsdf_pdf %.17g", m, s.pdf, pdf);
            tb_channels f = tb_bsdf_eval(&b, wo, s.wi);
            for (int i = 0; i < f.n; i++) {
                tb_assert_near(s.f.v[i], f.v[i], rel * f.v[i]);
                tb_assert_near(s.weight.v[i], f.v[i] * fabs(s.wi.z) / pdf, 3.0 * rel * s.weight.v[i]);
            }
            assert_true(s.transmitted == (s.wi.z * wo.z < 0.0f));
            if (b.kind != TB_BSDF_GGX_DIELECTRIC)
                assert_false(s.transmitted);
        }
        assert_true(ok > 1000);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fresnel_normal_incidence),
        cmocka_unit_test(test_fresnel_matches_angle_form),
        cmocka_unit_test(test_fresnel_grazing_and_tir),
        cmocka_unit_test(test_snell),
        cmocka_unit_test(test_reflect_and_split),
        cmocka_unit_test(test_reciprocity),
        cmocka_unit_test(test_sidedness),
        cmocka_unit_test(test_lobe_values),
        cmocka_unit_test(test_ggx_terms),
        cmocka_unit_test(test_sample_consistency),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
