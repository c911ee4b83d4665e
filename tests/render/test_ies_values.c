/* IES tables: interpolation returns the table values (times the multiplier)
 * at the tabulated angles and bilinear values between them, read back by an
 * independent tokenizer; symmetry expansions; the flux of the cosine
 * distribution against pi I0 and the lumens of its file; the exact flux
 * integral; sampling against its pdf (chi-square) and the flux; IES lights:
 * the MID normalisation (maximum 1 times intensity) and orientation. */
#include "tb_test.h"

#include <string.h>

#include "host/render/ies.h"
#include "host/render/lights.h"
#include "test_shading_support.h"

static const char *const FILES[] = {"lambertian.ies", "quadrant.ies", "bilateral.ies", "full.ies",
                                    "bilateral90.ies"};
#define NFILES 5

static void path_of(const char *name, char *path, size_t cap)
{
    snprintf(path, cap, "%s/render/data/%s", TB_TESTS_DIR, name);
}

static tb_ies *load(const char *name)
{
    char path[1024];
    path_of(name, path, sizeof path);
    tb_ies *ies = NULL;
    if (tb_ies_read(path, &ies))
        fail_msg("%s: %s", name, tb_last_error());
    return ies;
}

/* The numbers after the TILT= line, read with strtod (independent of ies.c). */
typedef struct raw {
    int nv, nh;
    double mult, lumens;
    int lamps;
    double v[64], h[64], c[64 * 64]; /* c[h * nv + v] as in the file */
} raw;

static void read_raw(const char *name, raw *r)
{
    char path[1024];
    path_of(name, path, sizeof path);
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    static char text[1 << 16];
    size_t n = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[n] = '\0';
    char *p = strstr(text, "TILT=");
    assert_non_null(p);
    p = strchr(p, '\n');
    double num[8192];
    int k = 0;
    while (*p && k < 8192) {
        char *end;
        double x = strtod(p, &end);
        if (end == p) {
            p++;
            continue;
        }
        num[k++] = x;
        p = end;
    }
    r->lamps = (int)num[0];
    r->lumens = num[1];
    r->mult = num[2];
    r->nv = (int)num[3];
    r->nh = (int)num[4];
    assert_true(k == 13 + r->nv + r->nh + r->nv * r->nh);
    for (int i = 0; i < r->nv; i++)
        r->v[i] = num[13 + i];
    for (int j = 0; j < r->nh; j++)
        r->h[j] = num[13 + r->nv + j];
    for (int i = 0; i < r->nv * r->nh; i++)
        r->c[i] = num[13 + r->nv + r->nh + i];
}

/* Independent bilinear interpolation of the raw table at angles inside it. */
static double raw_bilinear(const raw *r, double v, double h)
{
    int i = 0, j = 0;
    while (i + 2 < r->nv && r->v[i + 1] <= v)
        i++;
    double t = (v - r->v[i]) / (r->v[i + 1] - r->v[i]);
    if (r->nh == 1)
        return r->mult * (r->c[i] + t * (r->c[i + 1] - r->c[i]));
    while (j + 2 < r->nh && r->h[j + 1] <= h)
        j++;
    double s = (h - r->h[j]) / (r->h[j + 1] - r->h[j]);
    const double *c0 = r->c + j * r->nv, *c1 = r->c + (j + 1) * r->nv;
    double a = c0[i] + t * (c0[i + 1] - c0[i]), b = c1[i] + t * (c1[i + 1] - c1[i]);
    return r->mult * (a + s * (b - a));
}

static void test_table_values(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("ies table", 61), 0);
    for (int f = 0; f < NFILES; f++) {
        tb_ies *ies = load(FILES[f]);
        raw r;
        read_raw(FILES[f], &r);
        assert_int_equal(ies->nv, r.nv);
        assert_int_equal(ies->nh, r.nh);
        /* Exactly the table value times the multiplier at every tabulated pair. */
        double max = 0.0;
        for (int j = 0; j < r.nh; j++)
            for (int i = 0; i < r.nv; i++) {
                double want = r.c[j * r.nv + i] * r.mult;
                double got = tb_ies_candela(ies, r.v[i], r.h[j]);
                if (got != want)
                    fail_msg("%s: (%g, %g): %.17g, table %.17g", FILES[f], r.v[i], r.h[j], got, want);
                max = fmax(max, want);
            }
        assert_true(ies->max_candela == max);
        /* Bilinear in between. */
        for (int k = 0; k < 2000; k++) {
            double v = r.v[0] + (r.v[r.nv - 1] - r.v[0]) * tb_rng_double(&rng);
            double h = r.h[0] + (r.h[r.nh - 1] - r.h[0]) * tb_rng_double(&rng);
            double want = raw_bilinear(&r, v, h);
            tb_assert_near(tb_ies_candela(ies, v, h), want, 1e-12 * max);
        }
        /* Directions give the same values as angles. */
        for (int k = 0; k < 500; k++) {
            double v = r.v[0] + (r.v[r.nv - 1] - r.v[0]) * tb_rng_double(&rng);
            double h = 360.0 * tb_rng_double(&rng);
            tb_vec3 w = tb_ies_direction(v, h);
            tb_assert_near(tb_ies_candela_dir(ies, w), tb_ies_candela(ies, v, h), 1e-4 * max);
            tb_assert_near(tb_ies_normalized(ies, w), tb_ies_candela(ies, v, h) / max, 1e-4);
        }
        tb_ies_free(ies);
    }
}

static void test_angles_and_frame(void **state)
{
    (void)state;
    double v, h;
    tb_ies_angles(tb_vec3_make(0, 0, -1), &v, &h);
    assert_true(v == 0.0);
    tb_ies_angles(tb_vec3_make(0, 0, 1), &v, &h);
    assert_true(v == 180.0);
    tb_ies_angles(tb_vec3_make(1, 0, 0), &v, &h);
    assert_true(v == 90.0 && h == 0.0);
    tb_ies_angles(tb_vec3_make(0, 2, 0), &v, &h);
    assert_true(v == 90.0 && h == 90.0);
    tb_ies_angles(tb_vec3_make(0, -1, -1), &v, &h);
    tb_assert_near(v, 45.0, 1e-12);
    tb_assert_near(h, 270.0, 1e-12);
    tb_ies_angles(tb_vec3_make(1, -1e-30f, 0), &v, &h);
    assert_true(h >= 0.0 && h < 360.0);
    tb_vec3 w = tb_ies_direction(60.0, 90.0);
    tb_assert_near(w.y, sin(M_PI / 3), 1e-7);
    tb_assert_near(w.z, -0.5, 1e-7);
}

static void test_symmetry(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("ies symmetry", 62), 0);
    tb_ies *ies[NFILES];
    for (int f = 0; f < NFILES; f++)
        ies[f] = load(FILES[f]);
    for (int k = 0; k < 2000; k++) {
        double v = 90.0 * tb_rng_double(&rng), c = 360.0 * tb_rng_double(&rng);
        double tol = 1e-9;
        /* Rotational: the same in every plane. */
        tb_assert_near(tb_ies_candela(ies[0], v, c), tb_ies_candela(ies[0], v, 0.0), tol);
        /* Quadrant: mirror about the 0-180 and the 90-270 planes. */
        double q = tb_ies_candela(ies[1], v, c);
        tb_assert_near(q, tb_ies_candela(ies[1], v, 180.0 - c), tol);
        tb_assert_near(q, tb_ies_candela(ies[1], v, 180.0 + c), tol);
        tb_assert_near(q, tb_ies_candela(ies[1], v, 360.0 - c), tol);
        tb_assert_near(q, tb_ies_candela(ies[1], v, -c), tol);
        tb_assert_near(q, tb_ies_candela(ies[1], v, c + 720.0), tol);
        /* Bilateral: mirror about the 0-180 plane only. */
        double b = tb_ies_candela(ies[2], 2 * v, c);
        tb_assert_near(b, tb_ies_candela(ies[2], 2 * v, 360.0 - c), tol);
        /* About the 90-270 plane. */
        double n = tb_ies_candela(ies[4], 2 * v, c);
        tb_assert_near(n, tb_ies_candela(ies[4], 2 * v, 180.0 - c), tol);
        /* Full: periodic. */
        tb_assert_near(tb_ies_candela(ies[3], v, c), tb_ies_candela(ies[3], v, c - 360.0), tol);
    }
    /* The mirrored halves carry the table's own values: quadrant C = 270 is table C = 90. */
    raw r;
    read_raw("quadrant.ies", &r);
    assert_true(tb_ies_candela(ies[1], 45.0, 270.0) == r.c[3 * r.nv + 3] * r.mult);
    assert_true(tb_ies_candela(ies[1], 45.0, 150.0) == r.c[1 * r.nv + 3] * r.mult);
    /* The bilateral table is not symmetric about 90-270 (so the test above can fail). */
    assert_true(fabs(tb_ies_candela(ies[2], 60.0, 30.0) - tb_ies_candela(ies[2], 60.0, 150.0)) > 1.0);
    /* Full: C = 90 and C = 270 differ (25 vs 45 at gamma = 45). */
    assert_true(tb_ies_candela(ies[3], 45.0, 90.0) == 25.0 && tb_ies_candela(ies[3], 45.0, 270.0) == 45.0);
    /* Outside the vertical range: nothing. */
    assert_true(tb_ies_candela(ies[1], 90.0, 0.0) > 0.0);
    assert_true(tb_ies_candela(ies[1], 90.5, 0.0) == 0.0);
    assert_true(tb_ies_candela(ies[1], NAN, 0.0) == 0.0);
    assert_true(tb_ies_candela(ies[1], 10.0, NAN) == 0.0);
    for (int f = 0; f < NFILES; f++)
        tb_ies_free(ies[f]);
}

/* int over [a, b] of (ya + (yb - ya)(g - a)/(b - a)) sin g dg by 16-point
 * Gauss-Legendre (angles in radians). */
static double lin_sin(double a, double b, double ya, double yb)
{
    double x[16], w[16], s = 0.0;
    tst_gauss_legendre(16, x, w);
    for (int k = 0; k < 16; k++) {
        double t = 0.5 * (x[k] + 1.0), g = a + (b - a) * t;
        s += w[k] * (ya + (yb - ya) * t) * sin(g);
    }
    return 0.5 * (b - a) * s;
}

static void test_flux(void **state)
{
    (void)state;
    tb_ies *l = load("lambertian.ies");
    raw r;
    read_raw("lambertian.ies", &r);
    double flux = tb_ies_flux(l);
    /* The exact integral of the piecewise-linear interpolant. */
    double exact = 0.0;
    for (int i = 0; i + 1 < r.nv; i++)
        exact += lin_sin(r.v[i] * M_PI / 180, r.v[i + 1] * M_PI / 180, r.c[i], r.c[i + 1]);
    exact *= 2.0 * M_PI * r.mult;
    tb_assert_near(flux, exact, 1e-11 * exact);
    /* The cosine distribution I0 cos(gamma) emits pi I0; the table in 5-degree
     * steps is within its interpolation error of that, and of the file's lumens. */
    double want = M_PI * 1000.0;
    printf("[ ies      ] lambertian.ies: flux %.6f lm, pi I0 = %.6f, lumens in file %.6f, rel. diff %.2e\n", flux,
           want, r.lumens * r.lamps, (flux - want) / want);
    tb_assert_near(flux, want, 1e-3 * want);
    tb_assert_near(flux, l->lamps * l->lumens_per_lamp, 1e-3 * want);
    tb_ies_free(l);

    /* Other symmetries: tb_ies_flux against 2 x 2-point Gauss-Legendre over 1 x 1 degree
     * cells of the interpolated table (exact in C, where it is linear; error
     * ~1e-11 in gamma; the table's kinks lie on cell edges: all table angles
     * are integers). */
    for (int f = 1; f < NFILES; f++) {
        tb_ies *ies = load(FILES[f]);
        double x[2], w[2], s = 0.0;
        tst_gauss_legendre(2, x, w);
        for (int a = 0; a < 180; a++)
            for (int b = 0; b < 360; b++)
                for (int i = 0; i < 2; i++) {
                    double g = a + 0.5 * (x[i] + 1.0);
                    for (int j = 0; j < 2; j++) {
                        double c = b + 0.5 * (x[j] + 1.0);
                        s += w[i] * w[j] * tb_ies_candela(ies, g, c) * sin(g * M_PI / 180.0);
                    }
                }
        s *= 0.25 * (M_PI / 180.0) * (M_PI / 180.0);
        double fl = tb_ies_flux(ies);
        printf("[ ies      ] %s: flux %.6f, quadrature %.6f\n", FILES[f], fl, s);
        tb_assert_near(fl, s, 1e-8 * s);
        tb_ies_free(ies);
    }
}

/* ---------------------------------------------------------------- sampling */

static bool ies_sample(void *c, float uc, float u1, float u2, tb_vec3 *w)
{
    (void)uc;
    double pdf;
    *w = tb_ies_sample((const tb_ies *)c, u1, u2, &pdf);
    return true;
}

static double ies_pdf(void *c, tb_vec3 w) { return tb_ies_pdf((const tb_ies *)c, w); }

static void test_sampling(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("ies sampling", 63);
    for (int f = 0; f < NFILES; f++) {
        tb_ies *ies = load(FILES[f]);
        tst_chi2 r = tst_chi2_run(FILES[f], ies_sample, ies_pdf, ies, 200000, 48, 24, seed + f);
        assert_false(r.zero_bin_hit);
        assert_true(r.p_value >= TST_CHI2_ALPHA);
        tb_assert_near(r.pdf_sum, 1.0, 2e-3);
        /* The sampled pdf is the pdf of the sample; candela / pdf estimates the flux. */
        tb_rng rng;
        tb_rng_seed(&rng, seed + 10 + f, 0);
        double s = 0.0, s2 = 0.0;
        int n = 50000, differ = 0;
        for (int k = 0; k < n; k++) {
            double pdf;
            tb_vec3 w = tb_ies_sample(ies, tb_rng_float(&rng), tb_rng_float(&rng), &pdf);
            assert_true(pdf > 0.0);
            /* The same cell's density, unless rounding the direction to float
             * moved it across a cell edge. */
            differ += tb_ies_pdf(ies, w) != pdf;
            double v = tb_ies_candela_dir(ies, w) / pdf;
            s += v;
            s2 += v * v;
        }
        assert_true(differ < n / 1000);
        double mean = s / n, sd = sqrt(fmax(0.0, s2 / n - mean * mean) / n);
        double flux = tb_ies_flux(ies);
        tb_assert_near(mean, flux, 5.0 * sd + 1e-6 * flux);
        /* Never a zero density where there is light. */
        for (int k = 0; k < 5000; k++) {
            double z = 1.0 - 2.0 * tb_rng_double(&rng), p = 2.0 * M_PI * tb_rng_double(&rng);
            tb_vec3 w = tst_dir(p, z);
            if (tb_ies_candela_dir(ies, w) > 0.0)
                assert_true(tb_ies_pdf(ies, w) > 0.0);
        }
        tb_ies_free(ies);
    }
}

/* -------------------------------------------------------------- IES lights */

static void test_ies_lights(void **state)
{
    (void)state;
    tb_ies *full = load("full.ies");
    tb_ies *lam = load("lambertian.ies");
    /* Point light, identity transform: nadir -z, C = 0 along +x, C = 90 along +y. */
    tb_mid_light m = tb_mid_light_default(TB_LIGHT_POINT);
    m.intensity = tb_mid_color_grey(5.0f);
    tb_light l;
    assert_int_equal(tb_light_from_mid(&m, NULL, full, &l), TB_OK);
    const double C[] = {0.0, 45.0, 90.0, 180.0, 270.0, 300.0};
    const double G[] = {0.0, 30.0, 60.0, 90.0};
    for (int a = 0; a < 6; a++)
        for (int b = 0; b < 4; b++) {
            double g = G[b] * M_PI / 180.0, c = C[a] * M_PI / 180.0;
            tb_vec3 w = tb_vec3_make((float)(sin(g) * cos(c)), (float)(sin(g) * sin(c)), (float)-cos(g));
            /* The MID normalisation: the table over its maximum (41 here), times intensity. */
            double want = 5.0 * tb_ies_candela(full, G[b], C[a]) / full->max_candela;
            tb_assert_near(tb_light_intensity(&l, w).v[0], want, 2e-5 * 5.0);
        }
    tb_assert_near(full->max_candela, 50.0, 0.0); /* C = 270, gamma = 90: 40 + 10 */
    /* Power of an IES point light: intensity x flux / max. */
    tb_assert_near(tb_light_power(&l, 0.0).v[0], 5.0 * tb_ies_flux(full) / 50.0, 1e-5);

    /* Spot light along light-space +x with a 90-degree hard cone: the
     * photometric +x is world +z, so C = 0 lies toward +z and C = 90 toward +y. */
    m = tb_mid_light_default(TB_LIGHT_SPOT);
    m.direction = tb_dvec3_make(1, 0, 0);
    m.cone_angle = 90.0;
    m.cone_delta = 0.0;
    m.intensity = tb_mid_color_grey(2.0f);
    assert_int_equal(tb_light_from_mid(&m, NULL, full, &l), TB_OK);
    double g = 45.0 * M_PI / 180.0;
    tb_vec3 toward_z = tb_vec3_make((float)cos(g), 0.0f, (float)sin(g));
    tb_vec3 toward_y = tb_vec3_make((float)cos(g), (float)sin(g), 0.0f);
    tb_vec3 toward_my = tb_vec3_make((float)cos(g), (float)-sin(g), 0.0f);
    tb_assert_near(tb_light_intensity(&l, toward_z).v[0], 2.0 * tb_ies_candela(full, 45.0, 0.0) / 50.0, 1e-5);
    tb_assert_near(tb_light_intensity(&l, toward_y).v[0], 2.0 * tb_ies_candela(full, 45.0, 90.0) / 50.0, 1e-5);
    tb_assert_near(tb_light_intensity(&l, toward_my).v[0], 2.0 * tb_ies_candela(full, 45.0, 270.0) / 50.0, 1e-5);
    /* Behind the spot: nothing (the cone applies on top of the table). */
    assert_true(tb_light_intensity(&l, tb_vec3_make(-1, 0, 0)).v[0] == 0.0f);

    /* A cosine IES point light: irradiance straight below at distance d is I/d^2. */
    m = tb_mid_light_default(TB_LIGHT_POINT);
    m.intensity = tb_mid_color_grey(3.0f);
    assert_int_equal(tb_light_from_mid(&m, NULL, lam, &l), TB_OK);
    tb_light_sample s;
    assert_true(tb_light_sample_li(&l, tb_vec3_make(0, 0, -2), &s));
    tb_assert_near(s.L.v[0], 3.0 / 4.0, 1e-6);
    /* 60 degrees off the nadir: I cos(60) / d^2. */
    tb_vec3 p = tb_vec3_make((float)(2.0 * sin(M_PI / 3)), 0.0f, (float)(-2.0 * cos(M_PI / 3)));
    assert_true(tb_light_sample_li(&l, p, &s));
    tb_assert_near(s.L.v[0], 3.0 * 0.5 / 4.0, 1e-5);
    /* Emission sampling through the table: E[I / pdf] = power. */
    tb_rng rng;
    tb_rng_seed(&rng, 5, 0);
    double sum = 0.0;
    int n = 20000;
    for (int k = 0; k < n; k++) {
        tb_vec3 w;
        double pdf;
        tb_channels I;
        assert_true(tb_light_sample_emission(&l, tb_rng_float(&rng), tb_rng_float(&rng), &w, &pdf, &I));
        sum += I.v[0] / pdf;
    }
    double P = tb_light_power(&l, 0.0).v[0];
    tb_assert_near(sum / n, P, 0.01 * P);
    tb_ies_free(full);
    tb_ies_free(lam);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_table_values),
        cmocka_unit_test(test_angles_and_frame),
        cmocka_unit_test(test_symmetry),
        cmocka_unit_test(test_flux),
        cmocka_unit_test(test_sampling),
        cmocka_unit_test(test_ies_lights),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
