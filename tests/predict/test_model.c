/* host/render/predict: the per-module fit recovers known costs from
 * synthetic runs (with a zero cost and collinear statistics), the
 * evaluation adds terms into modules, COSTS.json round-trips exactly, and
 * bad COSTS.json files get located errors. */
#include "tb_test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "host/render/predict.h"
#include "util/math/rng.h"

/* A term's index by name (the test fails if there is none). */
static int term(const char *name)
{
    int n;
    const tb_cost_term *t = tb_cost_terms(&n);
    for (int i = 0; i < n; i++)
        if (!strcmp(t[i].name, name))
            return i;
    fail_msg("no term %s", name);
    return -1;
}

/* Known costs: every term gets a positive cost but one per module stays 0. */
static void known_costs(tb_costs *c)
{
    memset(c, 0, sizeof *c);
    int n;
    const tb_cost_term *t = tb_cost_terms(&n);
    for (int i = 0; i < n; i++) {
        /* fixed costs as large as real ones (a tiny constant under large terms is ill-conditioned) */
        bool fixed = t[i].feature == TB_PF_ONE || t[i].feature == TB_PF_IS_RAYTRACE || t[i].feature == TB_PF_IS_PATH ||
                     t[i].feature == TB_PF_IS_RADIOSITY;
        double scale = t[i].module == TB_PM_MEMORY ? (fixed ? 1e7 : 1.0) : (fixed ? 0.05 : 1e-7);
        c->c[i] = scale * (1.0 + 0.37 * (i % 5));
    }
    c->c[term("load.csg_node")] = 0.0;
    c->c[term("raytrace.test_csg")] = 0.0;
    c->threads = 2;
}

/* Random runs of every method; the measured modules are exactly the model's. */
static void synthetic_runs(const tb_costs *truth, tb_predict_stats *f, tb_predict_measured *y, int n)
{
    tb_rng rng;
    tb_rng_seed(&rng, 5, 0);
    for (int r = 0; r < n; r++) {
        tb_predict_method m = (tb_predict_method)(r % 3);
        /* RGB and spectral runs, so the per-pixel and per-pixel-channel statistics differ */
        tb_predict_stats_init(&f[r], m, 1e5 * (1 + 20 * tb_rng_double(&rng)), 64 + r * 16, 48 + r * 8,
                              r % 4 == 1 ? 31 : 3, 2, 2);
        for (int k = 0; k < TB_PF_COUNT; k++) {
            bool fixed = k == TB_PF_ONE || k == TB_PF_IS_RAYTRACE || k == TB_PF_IS_PATH || k == TB_PF_IS_RADIOSITY ||
                         k == TB_PF_BYTES || k == TB_PF_PIXELS || k == TB_PF_FILM_BYTES || k == TB_PF_RAD_PIXEL_RAYS ||
                         k == TB_PF_PIXEL_CHANNELS;
            if (!fixed)
                f[r].f[k] = 1e3 * (0.05 + tb_rng_double(&rng)) * pow(10.0, 3.0 * tb_rng_double(&rng));
        }
        tb_prediction p;
        tb_predict_eval(truth, &f[r], &p);
        memset(&y[r], 0, sizeof y[r]);
        for (int k = 0; k < TB_PM_COUNT; k++)
            y[r].module[k] = p.module[k];
    }
}

static void test_fit_recovers_costs(void **state)
{
    (void)state;
    enum { N = 90 };
    tb_costs truth, got;
    known_costs(&truth);
    tb_predict_stats *f = calloc(N, sizeof *f);
    tb_predict_measured *y = calloc(N, sizeof *y);
    assert_non_null(f);
    assert_non_null(y);
    synthetic_runs(&truth, f, y, N);
    assert_int_equal(tb_costs_fit(f, y, N, 2, &got), TB_OK);
    int n;
    const tb_cost_term *t = tb_cost_terms(&n);
    for (int i = 0; i < n; i++) {
        /* render modules see only their method's runs: a third of N */
        if (truth.c[i] == 0.0)
            assert_true(got.c[i] < 1e-12);
        else if (fabs(got.c[i] / truth.c[i] - 1.0) > 1e-5)
            fail_msg("%s: fitted %g, true %g", t[i].name, got.c[i], truth.c[i]);
        assert_true(isfinite(got.c[i]) && got.c[i] >= 0.0);
    }
    for (int m = 0; m < TB_PM_COUNT; m++) {
        assert_true(got.fit[m].rows > 0);
        assert_true(got.fit[m].rel_rms < 1e-6);
    }
    assert_int_equal(got.threads, 2);
    /* collinear statistics (rays = 2 x samples in every run): no NaN, and
     * the predictions still match the measurements */
    for (int r = 0; r < N; r++) {
        f[r].f[TB_PF_RAYS] = 2.0 * f[r].f[TB_PF_SAMPLES];
        tb_prediction p;
        tb_predict_eval(&truth, &f[r], &p);
        for (int k = 0; k < TB_PM_COUNT; k++)
            y[r].module[k] = p.module[k];
    }
    assert_int_equal(tb_costs_fit(f, y, N, 2, &got), TB_OK);
    for (int i = 0; i < n; i++)
        assert_true(isfinite(got.c[i]) && got.c[i] >= 0.0);
    for (int r = 0; r < N; r++) {
        tb_prediction p;
        tb_predict_eval(&got, &f[r], &p);
        tb_assert_near(p.seconds / (y[r].module[0] + y[r].module[1] + y[r].module[2] + y[r].module[3] +
                                    y[r].module[4] + y[r].module[5]),
                       1.0, 1e-5);
    }
    free(f);
    free(y);
}

/* Runs shaped like the calibration's: the per-channel statistics are the
 * per-sample and per-hit ones times the channels (3 RGB, 31 spectral), and
 * hits per ray range from a sky-bound grid's to a closed room's. The fit
 * separates the per-sample, per-hit and per-channel costs when both
 * channel counts are present, and predicts a spectral run from them. */
static void test_fit_channels(void **state)
{
    (void)state;
    enum { N = 40 };
    tb_costs truth, got;
    memset(&truth, 0, sizeof truth);
    truth.threads = 1;
    truth.c[term("path.sample")] = 4e-7;
    truth.c[term("path.ray")] = 2e-7;
    truth.c[term("path.node")] = 3e-8;
    truth.c[term("path.hit")] = 5e-7;
    truth.c[term("path.sample_channel")] = 2e-8;
    truth.c[term("path.hit_channel")] = 6e-8;
    tb_predict_stats f[N];
    tb_predict_measured y[N];
    tb_rng rng;
    tb_rng_seed(&rng, 11, 0);
    for (int r = 0; r < N; r++) {
        int ch = r % 3 == 0 ? 31 : 3;
        tb_predict_stats_init(&f[r], TB_PREDICT_PATH, 1e4, 320, 240, ch, 0, 1);
        assert_true(f[r].channels == ch);
        assert_true(f[r].f[TB_PF_PIXEL_CHANNELS] == 320.0 * 240.0 * ch);
        double samples = 1e4 * (1 + 30 * tb_rng_double(&rng)), hit_frac = 0.05 + 0.95 * tb_rng_double(&rng);
        f[r].f[TB_PF_SAMPLES] = samples;
        f[r].f[TB_PF_RAYS] = samples * (1 + 6 * hit_frac * tb_rng_double(&rng));
        f[r].f[TB_PF_HITS] = f[r].f[TB_PF_RAYS] * hit_frac;
        f[r].f[TB_PF_NODES] = f[r].f[TB_PF_RAYS] * (5 + 40 * tb_rng_double(&rng));
        /* what add_work / sub_work derive */
        f[r].f[TB_PF_SAMPLE_CHANNELS] = samples * ch;
        f[r].f[TB_PF_HIT_CHANNELS] = f[r].f[TB_PF_HITS] * ch;
        tb_prediction p;
        tb_predict_eval(&truth, &f[r], &p);
        memset(&y[r], 0, sizeof y[r]);
        y[r].module[TB_PM_PATH] = p.module[TB_PM_PATH];
    }
    assert_int_equal(tb_costs_fit(f, y, N, 1, &got), TB_OK);
    static const char *const names[] = {"path.sample", "path.ray",         "path.node",
                                        "path.hit",    "path.sample_channel", "path.hit_channel"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (fabs(got.c[term(names[i])] / truth.c[term(names[i])] - 1.0) > 1e-4)
            fail_msg("%s: fitted %g, true %g", names[i], got.c[term(names[i])], truth.c[term(names[i])]);
    /* the per-channel terms carry the spectral run's extra cost */
    tb_prediction rgb, spec;
    tb_predict_stats g = f[1];
    tb_predict_eval(&got, &g, &rgb);
    g.f[TB_PF_SAMPLE_CHANNELS] = g.f[TB_PF_SAMPLES] * 31;
    g.f[TB_PF_HIT_CHANNELS] = g.f[TB_PF_HITS] * 31;
    tb_predict_eval(&got, &g, &spec);
    tb_assert_near(spec.module[TB_PM_PATH] - rgb.module[TB_PM_PATH],
                   28.0 * (2e-8 * g.f[TB_PF_SAMPLES] + 6e-8 * g.f[TB_PF_HITS]), 1e-6 * spec.module[TB_PM_PATH]);
}

/* Runs slowed by other jobs (a few measured 3 times their true time, as on
 * a shared machine) barely move the costs: the fit down-weights them. */
static void test_fit_outliers(void **state)
{
    (void)state;
    enum { N = 40 };
    tb_costs truth, got;
    memset(&truth, 0, sizeof truth);
    truth.threads = 1;
    truth.c[term("raytrace.sample")] = 3e-7;
    truth.c[term("raytrace.ray")] = 5e-7;
    truth.c[term("raytrace.node")] = 4e-8;
    truth.c[term("raytrace.hit")] = 8e-7;
    tb_predict_stats f[N];
    tb_predict_measured y[N];
    tb_rng rng;
    tb_rng_seed(&rng, 3, 0);
    for (int r = 0; r < N; r++) {
        tb_predict_stats_init(&f[r], TB_PREDICT_RAYTRACE, 1e4, 320, 240, 3, 0, 1);
        f[r].f[TB_PF_SAMPLES] = 1e4 * (1 + 30 * tb_rng_double(&rng));
        f[r].f[TB_PF_RAYS] = f[r].f[TB_PF_SAMPLES] * (1 + 4 * tb_rng_double(&rng));
        f[r].f[TB_PF_HITS] = f[r].f[TB_PF_RAYS] * (0.05 + 0.95 * tb_rng_double(&rng));
        f[r].f[TB_PF_NODES] = f[r].f[TB_PF_RAYS] * (5 + 40 * tb_rng_double(&rng));
        tb_prediction p;
        tb_predict_eval(&truth, &f[r], &p);
        memset(&y[r], 0, sizeof y[r]);
        /* 2% noise on every run; runs 5, 17 and 30 slowed three times */
        y[r].module[TB_PM_RAYTRACE] = p.module[TB_PM_RAYTRACE] * (0.98 + 0.04 * tb_rng_double(&rng)) *
                                      (r == 5 || r == 17 || r == 30 ? 3.0 : 1.0);
    }
    assert_int_equal(tb_costs_fit(f, y, N, 1, &got), TB_OK);
    static const char *const names[] = {"raytrace.sample", "raytrace.ray", "raytrace.node", "raytrace.hit"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (fabs(got.c[term(names[i])] / truth.c[term(names[i])] - 1.0) > 0.1)
            fail_msg("%s: fitted %g, true %g", names[i], got.c[term(names[i])], truth.c[term(names[i])]);
    /* the prediction of an unslowed run stays within 5% */
    for (int r = 0; r < N; r++) {
        if (r == 5 || r == 17 || r == 30)
            continue;
        tb_prediction p;
        tb_predict_eval(&got, &f[r], &p);
        if (fabs(p.module[TB_PM_RAYTRACE] / y[r].module[TB_PM_RAYTRACE] - 1.0) > 0.05)
            fail_msg("run %d: fitted %g, measured %g", r, p.module[TB_PM_RAYTRACE], y[r].module[TB_PM_RAYTRACE]);
    }
    /* the reported error counts the slowed runs too */
    assert_true(got.fit[TB_PM_RAYTRACE].rel_rms > 0.15);
}

/* Runs shaped like the calibration's: the ray tracer always probes the
 * Vulkan device (--backend auto) but for a few --backend cpu runs, the path
 * tracer only on some scenes (Lambert, area lights), radiosity never. The
 * probe's time and memory come back apart from each method's fixed cost,
 * and a probing path run is predicted that much dearer than its twin. */
static void test_fit_vulkan_probe(void **state)
{
    (void)state;
    enum { N = 36 };
    tb_costs truth, got;
    memset(&truth, 0, sizeof truth);
    truth.threads = 1;
    truth.c[term("process.raytrace")] = 0.04;
    truth.c[term("process.path")] = 0.05;
    truth.c[term("process.radiosity")] = 0.06;
    truth.c[term("process.vulkan_probe")] = 0.45;
    truth.c[term("process.pixel")] = 2e-8;
    truth.c[term("memory.raytrace")] = 3e7;
    truth.c[term("memory.path")] = 1.5e7;
    truth.c[term("memory.radiosity")] = 2e7;
    truth.c[term("memory.vulkan_probe")] = 5.2e7;
    truth.c[term("memory.film_byte")] = 1.2;
    tb_predict_stats f[N];
    tb_predict_measured y[N];
    for (int r = 0; r < N; r++) {
        tb_predict_method m = (tb_predict_method)(r % 3);
        tb_predict_stats_init(&f[r], m, 1e4, 160 + 40 * r, 120 + 30 * r, r % 2 ? 31 : 3, 4, 1);
        bool probe = m == TB_PREDICT_RAYTRACE ? r % 4 != 0 : m == TB_PREDICT_PATH ? r % 5 < 2 : false;
        f[r].f[TB_PF_VULKAN_PROBE] = probe;
        tb_prediction p;
        tb_predict_eval(&truth, &f[r], &p);
        memset(&y[r], 0, sizeof y[r]);
        y[r].module[TB_PM_PROCESS] = p.module[TB_PM_PROCESS];
        y[r].module[TB_PM_MEMORY] = p.module[TB_PM_MEMORY];
    }
    assert_int_equal(tb_costs_fit(f, y, N, 1, &got), TB_OK);
    static const char *const names[] = {"process.raytrace", "process.path", "process.vulkan_probe",
                                        "memory.raytrace",  "memory.path",  "memory.vulkan_probe"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (fabs(got.c[term(names[i])] / truth.c[term(names[i])] - 1.0) > 1e-6)
            fail_msg("%s: fitted %g, true %g", names[i], got.c[term(names[i])], truth.c[term(names[i])]);
    tb_predict_stats g = f[1]; /* a path run */
    tb_prediction with, without;
    g.f[TB_PF_VULKAN_PROBE] = 1.0;
    tb_predict_eval(&got, &g, &with);
    g.f[TB_PF_VULKAN_PROBE] = 0.0;
    tb_predict_eval(&got, &g, &without);
    tb_assert_near(with.peak_rss_bytes - without.peak_rss_bytes, 5.2e7, 1.0);
    tb_assert_near(with.seconds - without.seconds, 0.45, 1e-6);
}

/* The radiosity image traces ceil(sqrt(spp))^2 rays per pixel (a square
 * grid), so --spp 2 and 3 cost what --spp 4 does. */
static void test_radiosity_image_rays(void **state)
{
    (void)state;
    static const int spp[] = {1, 2, 3, 4, 5, 9};
    static const double rays[] = {1, 4, 4, 4, 9, 9};
    for (size_t i = 0; i < sizeof spp / sizeof spp[0]; i++) {
        tb_predict_stats f;
        tb_predict_stats_init(&f, TB_PREDICT_RADIOSITY, 1e4, 64, 32, 3, spp[i], 1);
        tb_assert_near(f.f[TB_PF_RAD_PIXEL_RAYS], 64.0 * 32.0 * rays[i], 0.0);
        tb_predict_stats_init(&f, TB_PREDICT_PATH, 1e4, 64, 32, 3, spp[i], 1);
        tb_assert_near(f.f[TB_PF_RAD_PIXEL_RAYS], 0.0, 0.0);
    }
}

/* A w x h RGB image: a grey of 0.5, or noise in [0, 1) where keep(x, y) is false. */
static tb_image *grey_or_noise(int w, int h, bool (*keep)(int x, int y), uint64_t seed)
{
    tb_image *img = tb_image_create(w, h, 3, NULL);
    assert_non_null(img);
    tb_rng rng;
    tb_rng_seed(&rng, seed, 0);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            for (int c = 0; c < 3; c++)
                img->pixels[((size_t)y * (size_t)w + (size_t)x) * 3 + (size_t)c] =
                    keep && keep(x, y) ? 0.5f : (float)tb_rng_double(&rng);
    return img;
}

static bool every_4th(int x, int y) { return x % 4 == 0 && y % 4 == 0; }
static bool everywhere(int x, int y) { (void)x, (void)y; return true; }

/* The PNG-bytes estimate: noise costs many more bytes than a flat grey, the
 * scale multiplies, and with a step only every step-th pixel each way is
 * read (noise between them changes nothing). */
static void test_image_bytes(void **state)
{
    (void)state;
    tb_image *grey = grey_or_noise(64, 48, everywhere, 1), *noise = grey_or_noise(64, 48, NULL, 2);
    tb_image *holes = grey_or_noise(64, 48, every_4th, 3);
    double g1, n1, g16, g4, h4;
    assert_int_equal(tb_predict_image_bytes(grey, 1, false, 1.0, &g1), TB_OK);
    assert_int_equal(tb_predict_image_bytes(noise, 1, false, 1.0, &n1), TB_OK);
    assert_true(g1 > 0.0 && n1 > 10.0 * g1);          /* 64 x 48 x 3 bytes of noise hardly compress */
    assert_true(n1 > 0.8 * 64 * 48 * 3);
    assert_int_equal(tb_predict_image_bytes(grey, 1, false, 16.0, &g16), TB_OK);
    tb_assert_near(g16, 16.0 * g1, 0.0);
    assert_int_equal(tb_predict_image_bytes(grey, 4, false, 1.0, &g4), TB_OK);
    assert_int_equal(tb_predict_image_bytes(holes, 4, false, 1.0, &h4), TB_OK);
    tb_assert_near(h4, g4, 0.0);                        /* the same 16 x 12 grey image */
    assert_true(g4 < g1);
    double b = 1.0;
    assert_int_equal(tb_predict_image_bytes(grey, 0, false, 1.0, &b), TB_ERR_ARG);
    assert_true(b == 0.0);
    tb_clear_error();
    tb_image_free(grey), tb_image_free(noise), tb_image_free(holes);
}

/* Process runs shaped like the calibration's: equal pixels, PNG bytes per
 * pixel from a sky's 0.02 to a noisy room's 1.3: the per-byte and per-pixel
 * costs come back apart, and a noisy image is predicted that much dearer. */
static void test_fit_image_bytes(void **state)
{
    (void)state;
    enum { N = 40 };
    tb_costs truth, got;
    memset(&truth, 0, sizeof truth);
    truth.threads = 2;
    truth.c[term("process.raytrace")] = 0.05;
    truth.c[term("process.pixel_channel")] = 2e-8;
    truth.c[term("process.image_byte")] = 1.5e-7;
    tb_predict_stats f[N];
    tb_predict_measured y[N];
    tb_rng rng;
    tb_rng_seed(&rng, 77, 0);
    for (int r = 0; r < N; r++) {
        int w = 160 * (1 + r % 5), h = 120 * (1 + r % 5);
        tb_predict_stats_init(&f[r], TB_PREDICT_RAYTRACE, 1e4, w, h, r % 3 ? 3 : 31, 0, 2);
        f[r].f[TB_PF_IMAGE_BYTES] = (double)w * h * (0.02 + 1.3 * tb_rng_double(&rng));
        tb_prediction p;
        tb_predict_eval(&truth, &f[r], &p);
        memset(&y[r], 0, sizeof y[r]);
        y[r].module[TB_PM_PROCESS] = p.module[TB_PM_PROCESS];
    }
    assert_int_equal(tb_costs_fit(f, y, N, 2, &got), TB_OK);
    tb_assert_near(got.c[term("process.image_byte")], 1.5e-7, 1e-4 * 1.5e-7);
    tb_assert_near(got.c[term("process.pixel_channel")], 2e-8, 1e-4 * 2e-8);
    tb_assert_near(got.c[term("process.raytrace")], 0.05, 1e-4 * 0.05);
    tb_predict_stats sky = f[0], room = f[0];
    sky.f[TB_PF_IMAGE_BYTES] = 0.02 * sky.f[TB_PF_PIXELS];
    room.f[TB_PF_IMAGE_BYTES] = 1.3 * room.f[TB_PF_PIXELS];
    tb_prediction ps, pr;
    tb_predict_eval(&got, &sky, &ps);
    tb_predict_eval(&got, &room, &pr);
    tb_assert_near(pr.seconds - ps.seconds, 1.5e-7 * 1.28 * sky.f[TB_PF_PIXELS], 1e-3 * pr.seconds);
}

static void test_eval_modules(void **state)
{
    (void)state;
    tb_costs c;
    memset(&c, 0, sizeof c);
    c.threads = 1;
    c.c[term("load.parse_byte")] = 1e-8;
    c.c[term("path.ray")] = 1e-6;
    c.c[term("memory.path")] = 1e7;
    c.c[term("memory.film_byte")] = 2.0;
    tb_predict_stats f;
    tb_predict_stats_init(&f, TB_PREDICT_PATH, 1e6, 100, 50, 3, 0, 1);
    f.f[TB_PF_RAYS] = 2e6;
    tb_prediction p;
    tb_predict_eval(&c, &f, &p);
    tb_assert_near(p.module[TB_PM_LOAD], 0.01, 1e-15);
    tb_assert_near(p.module[TB_PM_PATH], 2.0, 1e-12);
    tb_assert_near(p.seconds, 2.01, 1e-12);
    tb_assert_near(p.peak_rss_bytes, 1e7 + 2.0 * 100 * 50 * 3 * 4, 1e-6);
    tb_assert_near(p.term[term("path.ray")], 2.0, 1e-12);
    assert_string_equal(tb_pmodule_name(TB_PM_PATH), "path");
    assert_string_equal(tb_predict_method_name(TB_PREDICT_RADIOSITY), "radiosity");
    assert_string_equal(tb_pfeat_name(TB_PF_TRIANGLES), "triangles");
}

/* A temporary file holding `text`; its path in buf. */
static const char *write_tmp(char *buf, size_t n, const char *name, const char *text)
{
    const char *dir = getenv("TB_TEST_TMPDIR");
    snprintf(buf, n, "%s/predict-model-%s", dir && *dir ? dir : "/tmp", name);
    FILE *fp = fopen(buf, "w");
    assert_non_null(fp);
    fputs(text, fp);
    fclose(fp);
    return buf;
}

static void test_costs_round_trip(void **state)
{
    (void)state;
    tb_costs c, back;
    known_costs(&c);
    c.c[0] = 1.0 / 3.0; /* needs all 17 digits */
    c.c[1] = 5e-300;
    snprintf(c.cpu, sizeof c.cpu, "CPU \"quoted\" \\ name");
    snprintf(c.created, sizeof c.created, "2026-12-07T12:00:00Z");
    c.fit[TB_PM_LOAD].rows = 7;
    char path[512];
    write_tmp(path, sizeof path, "costs.json", "");
    assert_int_equal(tb_costs_write(path, &c), TB_OK);
    assert_int_equal(tb_costs_read(path, &back), TB_OK);
    int n;
    tb_cost_terms(&n);
    for (int i = 0; i < n; i++)
        assert_true(back.c[i] == c.c[i]);
    assert_int_equal(back.threads, 2);
    assert_string_equal(back.cpu, c.cpu);
    assert_string_equal(back.created, c.created);
    /* writing into a missing folder fails and leaves nothing */
    assert_int_equal(tb_costs_write("/nonexistent-dir/costs.json", &c), TB_ERR_IO);
}

/* Reads `text` as COSTS.json: expects failure with `want` in the message. */
static void expect_bad(const char *name, const char *text, tb_status st, const char *want)
{
    char path[512];
    write_tmp(path, sizeof path, name, text);
    tb_costs c;
    assert_int_equal(tb_costs_read(path, &c), st);
    if (!strstr(tb_last_error(), want))
        fail_msg("%s: message '%s' lacks '%s'", name, tb_last_error(), want);
}

static void test_costs_bad_files(void **state)
{
    (void)state;
    /* a valid file to edit */
    tb_costs c;
    known_costs(&c);
    char path[512];
    write_tmp(path, sizeof path, "good.json", "");
    assert_int_equal(tb_costs_write(path, &c), TB_OK);
    FILE *fp = fopen(path, "r");
    assert_non_null(fp);
    static char good[65536];
    size_t len = fread(good, 1, sizeof good - 1, fp);
    good[len] = 0;
    fclose(fp);
    static char bad[65536];

    expect_bad("empty.json", "", TB_ERR_FORMAT, "predict-model-empty.json:1:1: error: expected a JSON object");
    expect_bad("array.json", "[1, 2]", TB_ERR_FORMAT, ":1:1: error: expected a JSON object");
    expect_bad("trunc.json", "{\"schema\": \"testbed-costs-5\",\n  \"threads\": 2,\n  \"costs\": {\"load.fixed\": 1",
               TB_ERR_FORMAT, ":3:28: error: expected ',' or '}'");
    expect_bad("schema.json", "{\"schema\": \"other\", \"threads\": 2, \"costs\": {}}", TB_ERR_FORMAT,
               ":1:12: error: schema is not \"testbed-costs-5\"");
    /* a file of the previous model (other terms) is refused by its schema, with what to do */
    expect_bad("old.json", "{\"schema\": \"testbed-costs-4\", \"threads\": 2, \"costs\": {}}", TB_ERR_FORMAT,
               "schema is not \"testbed-costs-5\" (a COSTS.json of another version: re-run testbed calibrate)");
    expect_bad("noschema.json", "{\"threads\": 2, \"costs\": {}}", TB_ERR_FORMAT, "no \"schema\"");
    expect_bad("missing.json", "{\"schema\": \"testbed-costs-5\", \"threads\": 2, \"costs\": {}}", TB_ERR_FORMAT,
               "cost term \"load.parse_byte\" is missing");
    /* an unknown term, a negative and a non-number cost, a duplicate, text after */
    char *p = strstr(strcpy(bad, good), "\"load.primitive\"");
    memcpy(p, "\"load.primitiv_\"", 16);
    expect_bad("unknown.json", bad, TB_ERR_FORMAT, "unknown cost term \"load.primitiv_\"");
    p = strstr(strcpy(bad, good), "\"load.fixed\": ") + 14;
    memmove(p + 1, p, strlen(p) + 1); /* a minus sign before the cost */
    *p = '-';
    expect_bad("negative.json", bad, TB_ERR_FORMAT, "cost \"load.fixed\" must be a finite number >= 0");
    p = strstr(strcpy(bad, good), "\"load.fixed\": ") + 14;
    *p = 'x';
    expect_bad("nan.json", bad, TB_ERR_FORMAT, "error: expected a number");
    strcpy(bad, good);
    strcat(bad, "{}");
    expect_bad("after.json", bad, TB_ERR_FORMAT, "text after the JSON object");
    p = strstr(strcpy(bad, good), "\"threads\": 2") + 11;
    *p = '0';
    expect_bad("threads.json", bad, TB_ERR_FORMAT, "threads must be a whole number from 1 to 4096");
    char nopath[600];
    snprintf(nopath, sizeof nopath, "%s/predict-model-does-not-exist.json",
             getenv("TB_TEST_TMPDIR") ? getenv("TB_TEST_TMPDIR") : "/tmp");
    tb_costs c2;
    assert_int_equal(tb_costs_read(nopath, &c2), TB_ERR_IO);
    assert_non_null(strstr(tb_last_error(), "does-not-exist.json"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fit_recovers_costs),
        cmocka_unit_test(test_fit_channels),
        cmocka_unit_test(test_fit_outliers),
        cmocka_unit_test(test_fit_vulkan_probe),
        cmocka_unit_test(test_radiosity_image_rays),
        cmocka_unit_test(test_image_bytes),
        cmocka_unit_test(test_fit_image_bytes),
        cmocka_unit_test(test_eval_modules),
        cmocka_unit_test(test_costs_round_trip),
        cmocka_unit_test(test_costs_bad_files),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
