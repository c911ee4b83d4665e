/* Virtual instruments (host/hybrid/measure.h) against independent analytic
 * answers, in the manner of the CIE 171:2006 test cases for lighting
 * programs: a point light over a plane (E = I cos / r^2), a diffuse disc
 * seen from its axis (E = M R^2 / (R^2 + h^2)), a rectangle emitter seen
 * from points of a parallel plane (Howell's B-3), the inside of a furnace
 * (E = M / (1 - rho), L = E / pi), a radiance meter inside and around a
 * uniform Lambertian emitter; both methods, and the two against each other
 * on the Cornell box. Plus filters, thread-count independence and the
 * sensors file's errors. Statistical bounds are 4 standard errors (the
 * tests' seeds are fixed: TB_TEST_SEED overrides them). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../formfactor/ff_cases.h"
#include "host/hybrid/measure.h"
#include "host/render/scene.h"
#include "tb_test.h"

#define PI 3.14159265358979323846

static tb_scene *load(const char *rel, tb_scene_color color)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", TB_SOURCE_DIR, rel);
    tb_scene_options so = {0};
    so.color = color;
    tb_scene *s = NULL;
    if (tb_scene_load(path, &so, &s))
        fail_msg("%s", tb_last_error());
    return s;
}

/* A sensor set from CSV text (filters resolve against tests/measure). */
static tb_sensor_set sensors(const char *text)
{
    FILE *f = fmemopen((void *)text, strlen(text), "r");
    assert_non_null(f);
    tb_sensor_set ss;
    tb_status st = tb_sensors_read_stream(f, "text.csv", TB_TESTS_DIR "/measure", &ss);
    fclose(f);
    if (st)
        fail_msg("%s", tb_last_error());
    return ss;
}

/* $TB_MEASURE_TEST_DIVISOR (the sanitizer build sets 4; default 1). */
static int divisor(void)
{
    const char *e = getenv("TB_MEASURE_TEST_DIVISOR");
    int d = e ? atoi(e) : 1;
    return d > 1 ? d : 1;
}

/* Measures with `method` (radiosity: elements of at most `edge`; 0: faces whole). */
static tb_measure_result *run(const tb_scene *s, const tb_sensor_set *ss, tb_measure_method method, int samples,
                              double edge, int threads)
{
    tb_measure_options o = tb_measure_defaults();
    o.method = method;
    o.samples = samples / divisor() > 16 ? samples / divisor() : 16;
    o.seed = tb_test_seed("measure", 11);
    o.threads = threads;
    o.rad.mesh_given = true;
    o.rad.mesh = tb_rad_default_mesh_options(s);
    o.rad.mesh.max_edge = edge;
    tb_measure_result *r = calloc((size_t)ss->n, sizeof *r);
    assert_non_null(r);
    if (tb_measure(s, ss, &o, r))
        fail_msg("%s", tb_last_error());
    return r;
}

/* |got - exact| <= 4 se + bias * |exact| (+ a float rounding floor). */
static void near(const char *what, double got, double se, double exact, double bias)
{
    const double tol = 4.0 * se + bias * fabs(exact) + 2e-6 * fabs(exact) + 1e-12;
    printf("  %-34s %.7g (se %.2g) exact %.7g: %+.3f %% (%.2f se)\n", what, got, se, exact,
           100.0 * (got / exact - 1.0), se > 0 ? (got - exact) / se : 0.0);
    if (!(fabs(got - exact) <= tol))
        fail_msg("%s: %.9g, exact %.9g, tolerance %.3g", what, got, exact, tol);
}

static const char *method_name(tb_measure_method m) { return m == TB_MEASURE_PATH ? "path" : "radiosity"; }

/* Every sensor's reading by both methods against exact[i], bias[method] allowed. */
static void check_readings(const char *label, const tb_scene *s, const tb_sensor_set *ss, int samples, double edge,
                           const double *exact, const double *bias)
{
    for (int m = 0; m < 2; m++) {
        tb_measure_result *r = run(s, ss, (tb_measure_method)m, samples, edge, 0);
        for (int i = 0; i < ss->n; i++) {
            char what[256];
            snprintf(what, sizeof what, "%s %s %s", method_name((tb_measure_method)m), label, ss->s[i].name);
            near(what, r[i].reading, r[i].reading_se, exact[i], bias[m]);
        }
        free(r);
    }
}

/* Point light I = (4, 2, 1) W/sr at (0, 0, 2) over a black plane. */
static void test_point_light(void **state)
{
    (void)state;
    tb_scene *s = load("tests/measure/point.mid", TB_SCENE_COLOR_RGB);
    tb_sensor_set ss = sensors("name,kind,x,y,z,dx,dy,dz,half_angle_deg,filter\n"
                               "below,irradiance,0,0,0,0,0,1,,\n"
                               "side,irradiance,1.5,0,0,0,0,1,,\n"
                               "far,irradiance,-30,40,0,0,0,1,,\n"
                               "tilted,irradiance,1,1,0.5,0.3,-0.2,1,,\n"
                               "away,irradiance,0,0,1,0,0,-1,,\n");
    const double I[3] = {4, 2, 1};
    const double lp[3] = {0, 0, 2};
    for (int m = 0; m < 2; m++) {
        tb_measure_result *r = run(s, &ss, (tb_measure_method)m, 64, 0.0, 0);
        for (int i = 0; i < ss.n; i++) {
            const tb_sensor *sn = &ss.s[i];
            const double v[3] = {lp[0] - sn->p.x, lp[1] - sn->p.y, lp[2] - sn->p.z};
            const double r2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2], rr = sqrt(r2);
            const double cs = fmax(0.0, (v[0] * sn->d.x + v[1] * sn->d.y + v[2] * sn->d.z) / rr);
            for (int c = 0; c < 3; c++) {
                char what[256];
                snprintf(what, sizeof what, "%s %s channel %d", method_name((tb_measure_method)m), sn->name, c);
                if (cs == 0.0)
                    assert_true(r[i].value[c] == 0.0);
                else
                    near(what, r[i].value[c], r[i].value_se[c], I[c] * cs / r2, 1e-6);
            }
            assert_true(r[i].value_se[0] == 0.0); /* a delta light has no variance */
            const double Y = 0.2126 * I[0] + 0.7152 * I[1] + 0.0722 * I[2];
            if (cs > 0)
                near("photometric: 683 Y", r[i].photometric, 0.0, 683.0 * Y * cs / r2, 1e-4);
        }
        free(r);
    }
    tb_sensors_free(&ss);
    tb_scene_free(s);
}

/* Disc of radius 1 at height 2, radiance 1: E = pi R^2 / (R^2 + h^2). */
static void test_disc(void **state)
{
    (void)state;
    tb_scene *s = load("tests/measure/disc.mid", TB_SCENE_COLOR_RGB);
    tb_sensor_set ss = sensors("name,kind,x,y,z,dx,dy,dz,half_angle_deg,filter\n"
                               "h2,irradiance,0,0,0,0,0,1,,\n"
                               "h1,irradiance,0,0,1,0,0,1,,\n"
                               "h0.25,irradiance,0,0,1.75,0,0,1,,\n"
                               "inside,radiance,0,0,0,0,0,1,20,\n"
                               "around,radiance,0,0,1,0,0,1,60,\n"
                               "hemisphere,radiance,0,0,1.5,0,0,1,90,\n");
    const double h[3] = {2, 1, 0.25};
    for (int m = 0; m < 2; m++) {
        tb_measure_result *r = run(s, &ss, (tb_measure_method)m, 8192, 0.0, 0);
        char what[256];
        for (int i = 0; i < 3; i++) {
            snprintf(what, sizeof what, "%s disc E at h = %g", method_name((tb_measure_method)m), h[i]);
            near(what, r[i].value[1], r[i].value_se[1], PI / (1.0 + h[i] * h[i]), 0.0);
        }
        /* a cone inside the disc (half-angle 20 < atan(1/2)) sees L = 1 only */
        near("radiance, cone inside the emitter", r[3].value[0], r[3].value_se[0], 1.0, 0.0);
        assert_true(r[3].value_se[0] == 0.0);
        /* cones around it: the disc's share of the cone's solid angle */
        const double ca = 1.0 / sqrt(2.0), cb = cos(60.0 * PI / 180.0);
        near("radiance, 60 degree cone around", r[4].value[2], r[4].value_se[2], (1.0 - ca) / (1.0 - cb), 0.0);
        const double ch = 0.5 / sqrt(1.25);
        near("radiance, hemisphere", r[5].value[0], r[5].value_se[0], 1.0 - ch, 0.0);
        free(r);
    }
    tb_sensors_free(&ss);
    tb_scene_free(s);
}

/* Rectangle 2 x 1 at height 1, exitance 1: Howell B-3 at a corner, four B-3 at the middle. */
static void test_rectangle(void **state)
{
    (void)state;
    tb_scene *s = load("tests/measure/rect.mid", TB_SCENE_COLOR_RGB);
    tb_sensor_set ss = sensors("name,kind,x,y,z,dx,dy,dz,half_angle_deg,filter\n"
                               "corner,irradiance,0,0,0,0,0,1,,\n"
                               "middle,irradiance,1,0.5,0,0,0,1,,\n"
                               "quarter,irradiance,0.5,0.5,0.5,0,0,1,,\n");
    const double exact[3] = {ff_howell_b3(2, 1, 1), 4.0 * ff_howell_b3(1, 0.5, 1),
                             2.0 * ff_howell_b3(0.5, 0.5, 0.5) + 2.0 * ff_howell_b3(1.5, 0.5, 0.5)};
    check_readings("rectangle", s, &ss, 8192, 0.0, exact, (const double[2]){0.0, 0.0});
    tb_sensors_free(&ss);
    tb_scene_free(s);
}

/* Closed unit cube, rho 0.5, exitance 1 on every face: E = 2, L = 2 / pi everywhere inside. */
static void test_furnace(void **state)
{
    (void)state;
    tb_scene *s = load("tests/radiosity/furnace.mid", TB_SCENE_COLOR_RGB);
    tb_sensor_set ss = sensors("name,kind,x,y,z,dx,dy,dz,half_angle_deg,filter\n"
                               "centre,irradiance,0.5,0.5,0.5,0,0,1,,\n"
                               "corner,irradiance,0.1,0.2,0.15,1,1,-1,,\n"
                               "floor,irradiance,0.5,0.5,0,0,0,1,,\n"
                               "look,radiance,0.5,0.5,0.5,1,0,0,30,\n"
                               "wide,radiance,0.3,0.6,0.2,0,-1,0,90,\n");
    double exact[5];
    for (int i = 0; i < ss.n; i++)
        exact[i] = ss.s[i].kind == TB_SENSOR_IRRADIANCE ? 2.0 : 2.0 / PI;
    /* radiosity: 4 x 4 elements per face lose up to 0.5 % of the
     * interreflected power (measured 0.4 %; docs/measure.md) */
    check_readings("furnace", s, &ss, 8192, 0.25, exact, (const double[2]){0.0, 0.01});
    tb_sensors_free(&ss);
    tb_scene_free(s);
}

/* Path and radiosity on the diffuse Cornell box (40 mm elements: the
 * solution is up to 3.2 % low in interreflected light, docs/accuracy.md;
 * the sanitizer build's 80 mm elements up to 9.3 % low). */
static void test_methods_agree(void **state)
{
    (void)state;
    tb_scene *s = load("scenes/cornell-box-rgb.mid", TB_SCENE_COLOR_AUTO);
    tb_sensor_set ss = sensors("name,kind,x,y,z,dx,dy,dz,half_angle_deg,filter\n"
                               "floor,irradiance,420,0,120,0,1,0,,\n"
                               "ceiling,irradiance,278,548.7,100,0,-1,0,,\n"
                               "red,radiance,278,450,200,1,0,0,5,\n"
                               "green,radiance,278,450,200,-1,0,0,5,\n"
                               "back,radiance,278,400,0,0,0,1,3,\n");
    tb_measure_result *p = run(s, &ss, TB_MEASURE_PATH, 16384, 0.0, 0);
    const bool quick = divisor() > 1;
    tb_measure_result *r = run(s, &ss, TB_MEASURE_RADIOSITY, 16384, quick ? 80.0 : 40.0, 0);
    for (int i = 0; i < ss.n; i++) {
        char what[256];
        snprintf(what, sizeof what, "radiosity vs path, %s", ss.s[i].name);
        const double se = sqrt(p[i].reading_se * p[i].reading_se + r[i].reading_se * r[i].reading_se);
        near(what, r[i].reading, se, p[i].reading, quick ? 0.10 : 0.04);
    }
    free(p);
    free(r);
    tb_sensors_free(&ss);
    tb_scene_free(s);
}

/* A band filter reads the band; a clear filter changes nothing (same streams: bit for bit). */
static void test_filters(void **state)
{
    (void)state;
    tb_scene *s = load("tests/measure/disc.mid", TB_SCENE_COLOR_SPECTRAL);
    assert_true(s->spectral);
    const char *rows = "e,irradiance,0,0,1,0,0,1,,%s\nl,radiance,0,0,1,0.2,0,1,60,%s\n";
    char text[512];
    const char *head = "name,kind,x,y,z,dx,dy,dz,half_angle_deg,filter\n";
    snprintf(text, sizeof text, "%s", head);
    snprintf(text + strlen(text), sizeof text - strlen(text), rows, "", "");
    tb_sensor_set none = sensors(text);
    snprintf(text, sizeof text, "%s", head);
    snprintf(text + strlen(text), sizeof text - strlen(text), rows, "filter-550.csv", "filter-550.csv");
    tb_sensor_set band = sensors(text);
    snprintf(text, sizeof text, "%s", head);
    snprintf(text + strlen(text), sizeof text - strlen(text), rows, "filter-clear.csv", "filter-clear.csv");
    tb_sensor_set clear = sensors(text);
    assert_true(band.filtered && clear.filtered && !none.filtered);
    tb_measure_result *a = run(s, &none, TB_MEASURE_PATH, 256, 0.0, 0);
    tb_measure_result *b = run(s, &band, TB_MEASURE_PATH, 256, 0.0, 0);
    tb_measure_result *c = run(s, &clear, TB_MEASURE_PATH, 256, 0.0, 0);
    int k550 = -1;
    for (int k = 0; k < s->nchannels; k++)
        if (s->bands.lambda[k] == 550.0)
            k550 = k;
    assert_true(k550 >= 0);
    for (int i = 0; i < 2; i++) {
        assert_true(a[i].value[k550] > 0.0);
        for (int k = 0; k < s->nchannels; k++)
            assert_true(b[i].value[k] == (k == k550 ? a[i].value[k] : 0.0));
        /* the reading integrates the band's hat: 10 nm wide */
        assert_true(fabs(b[i].reading - 10.0 * a[i].value[k550]) <= 1e-12 * b[i].reading);
        assert_memory_equal(&a[i], &c[i], sizeof a[i]);
    }
    /* an RGB scene refuses filters */
    tb_scene *rgb = load("tests/measure/disc.mid", TB_SCENE_COLOR_RGB);
    tb_measure_result r[2];
    tb_measure_options o = tb_measure_defaults();
    assert_int_equal(tb_measure(rgb, &band, &o, r), TB_ERR_ARG);
    tb_scene_free(rgb);
    free(a);
    free(b);
    free(c);
    tb_sensors_free(&none);
    tb_sensors_free(&band);
    tb_sensors_free(&clear);
    tb_scene_free(s);
}

/* The same bits for 1 and 2 threads, both methods. */
static void test_threads(void **state)
{
    (void)state;
    tb_scene *s = load("tests/radiosity/furnace.mid", TB_SCENE_COLOR_RGB);
    tb_sensor_set ss = sensors("name,kind,x,y,z,dx,dy,dz,half_angle_deg,filter\n"
                               "a,irradiance,0.5,0.5,0.5,0,0,1,,\n"
                               "b,radiance,0.2,0.5,0.5,1,0.1,0,10,\n"
                               "c,irradiance,0.9,0.1,0.5,-1,0,0,,\n");
    for (int m = 0; m < 2; m++) {
        tb_measure_result *r1 = run(s, &ss, (tb_measure_method)m, 512, 0.5, 1);
        tb_measure_result *r2 = run(s, &ss, (tb_measure_method)m, 512, 0.5, 2);
        assert_memory_equal(r1, r2, (size_t)ss.n * sizeof *r1);
        free(r1);
        free(r2);
    }
    tb_sensors_free(&ss);
    tb_scene_free(s);
}

/* Every bad row gives "text.csv:LINE: error: ..." naming what is wrong. */
static void test_errors(void **state)
{
    (void)state;
    static const struct {
        const char *text, *want;
    } cases[] = {
        {"", "text.csv:1: error: no header"},
        {"name,kind,x,y,z,dx,dy\n", "text.csv:1: error: header: missing column 'dz'"},
        {"name,kind,x,y,z,dx,dy,dz,half,filter\n", "text.csv:1: error: header: column 9 is 'half'"},
        {"name,kind,x,y,z,dx,dy,dz\n", "text.csv:1: error: no sensors"},
        {"name,kind,x,y,z,dx,dy,dz\n\n# c\nlux,photometer,0,0,0,0,0,1\n", "text.csv:4: error: unknown kind 'photometer'"},
        {"name,kind,x,y,z,dx,dy,dz\na,irradiance,0,0,0,0,0\n", "text.csv:2: error: missing column 'dz'"},
        {"name,kind,x,y,z,dx,dy,dz\na,irradiance,0,0,0,0,0,1,2\n", "text.csv:2: error: 9 columns, the header has 8"},
        {"name,kind,x,y,z,dx,dy,dz\na,irradiance,0,zero,0,0,0,1\n", "text.csv:2: error: y: expected a finite number"},
        {"name,kind,x,y,z,dx,dy,dz\na,irradiance,0,0,nan,0,0,1\n", "text.csv:2: error: z: expected a finite number"},
        {"name,kind,x,y,z,dx,dy,dz\na,irradiance,0,0,0,1e300,0,1\n", "text.csv:2: error: dx: 1e+300 is out of range"},
        {"name,kind,x,y,z,dx,dy,dz\na,irradiance,0,0,0,0,0,0\n", "text.csv:2: error: zero direction"},
        {"name,kind,x,y,z,dx,dy,dz,half_angle_deg\na,radiance,0,0,0,0,0,1,\n", "text.csv:2: error: a radiance sensor needs"},
        {"name,kind,x,y,z,dx,dy,dz,half_angle_deg\na,radiance,0,0,0,0,0,1,0\n", "text.csv:2: error: half_angle_deg 0 is not in (0, 90]"},
        {"name,kind,x,y,z,dx,dy,dz,half_angle_deg\na,radiance,0,0,0,0,0,1,90.5\n", "half_angle_deg 90.5 is not in (0, 90]"},
        {"name,kind,x,y,z,dx,dy,dz,half_angle_deg\na,irradiance,0,0,0,0,0,1,5\n", "text.csv:2: error: half_angle_deg is for radiance"},
        {"name,kind,x,y,z,dx,dy,dz,half_angle_deg,filter\na,irradiance,0,0,0,0,0,1,,missing.csv\n", "text.csv:2: error: filter '"},
        {"name,kind,x,y,z,dx,dy,dz,half_angle_deg,filter\na,irradiance,0,0,0,0,0,1,,point.mid\n", "text.csv:2: error: filter '"},
        {"name,kind,x,y,z,dx,dy,dz\na,irradiance,0,0,0,0,0,1\nb,irradiance,0,0,0,0,0,1\na,irradiance,0,0,0,0,0,1\n",
         "text.csv:4: error: duplicate sensor name 'a' (first on line 2)"},
        {"name,kind,x,y,z,dx,dy,dz\n,irradiance,0,0,0,0,0,1\n", "text.csv:2: error: empty sensor name"},
        {"name,kind,x,y,z,dx,dy,dz\na,irradiance,0,0\0,0,0,0,1\n", "text.csv:2: error: NUL byte"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        size_t n = strlen(cases[i].text);
        if (strstr(cases[i].want, "NUL"))
            n = sizeof "name,kind,x,y,z,dx,dy,dz\na,irradiance,0,0\0,0,0,0,1\n" - 1;
        FILE *f = n ? fmemopen((void *)cases[i].text, n, "r") : fopen("/dev/null", "r");
        assert_non_null(f);
        tb_sensor_set ss;
        tb_status st = tb_sensors_read_stream(f, "text.csv", TB_TESTS_DIR "/measure", &ss);
        fclose(f);
        if (st == TB_OK || !strstr(tb_last_error(), cases[i].want))
            fail_msg("case %zu: status %d, message '%s', want '%s'", i, (int)st, st ? tb_last_error() : "",
                     cases[i].want);
        assert_int_equal(ss.n, 0);
        assert_null(ss.s);
    }
    /* MEASURED files */
    tb_sensor_set ss = sensors("name,kind,x,y,z,dx,dy,dz\na,irradiance,0,0,0,0,0,1\nb,irradiance,0,0,0,0,0,1\n");
    static const struct {
        const char *text, *want;
    } mcases[] = {
        {"name,value\nc,1\n", "m.csv:2: error: no sensor named 'c'"},
        {"name,value\na,1\na,2\n", "m.csv:3: error: duplicate measurement of 'a' (first on line 2)"},
        {"name,value\na,x\n", "m.csv:2: error: value: expected a finite number, got 'x'"},
        {"name,value,uncertainty\na,1,-1\n", "m.csv:2: error: uncertainty"},
        {"name,value\na\n", "m.csv:2: error: missing column 'value'"},
        {"name,value\na,1,2\n", "m.csv:2: error: 3 columns, the header has 2"},
        {"name,val\n", "m.csv:1: error: header: column 2 is 'val'"},
        {"name,value\n", "m.csv:1: error: no measured values"},
    };
    for (size_t i = 0; i < sizeof mcases / sizeof mcases[0]; i++) {
        FILE *f = fmemopen((void *)mcases[i].text, strlen(mcases[i].text), "r");
        tb_measured_set ms;
        tb_status st = tb_measured_read_stream(f, "m.csv", &ss, &ms);
        fclose(f);
        if (st == TB_OK || !strstr(tb_last_error(), mcases[i].want))
            fail_msg("measured case %zu: message '%s', want '%s'", i, st ? tb_last_error() : "", mcases[i].want);
        assert_int_equal(ms.n, 0);
    }
    tb_sensors_free(&ss);
}

/* The comparison's residuals, relative errors and disagreement. */
static void test_compare(void **state)
{
    (void)state;
    tb_sensor_set ss = sensors("name,kind,x,y,z,dx,dy,dz\na,irradiance,0,0,0,0,0,1\nb,irradiance,0,0,0,0,0,1\n"
                               "c,irradiance,0,0,0,0,0,1\n");
    tb_measure_result r[3];
    memset(r, 0, sizeof r);
    r[0].reading = 10.0, r[0].reading_se = 0.1;
    r[1].reading = 20.0, r[1].reading_se = 0.3;
    r[2].reading = 5.0, r[2].reading_se = 0.0;
    const char *text = "name,value,uncertainty\na,10.5,0.2\nb,19,0.4\n";
    FILE *f = fmemopen((void *)text, strlen(text), "r");
    tb_measured_set ms;
    assert_int_equal(tb_measured_read_stream(f, "m.csv", &ss, &ms), TB_OK);
    fclose(f);
    tb_compare_summary sum;
    tb_measure_compare(NULL, &ss, r, &ms, TB_COMPARE_READING, 2.0, &sum);
    assert_int_equal(sum.compared, 2);
    /* a: -0.5 against 2 sqrt(0.04 + 0.01) = 0.447: disagrees; b: +1 against 2 * 0.5 = 1: agrees (not beyond) */
    assert_int_equal(sum.disagree, 1);
    const double ra = -0.5 / 10.5, rb = 1.0 / 19.0;
    tb_assert_near(sum.max_rel, fabs(rb), 1e-15);
    tb_assert_near(sum.rms_rel, sqrt(0.5 * (ra * ra + rb * rb)), 1e-15);
    tb_assert_near(sum.max_resid, 1.0, 0.0);
    tb_assert_near(sum.rms_resid, sqrt(0.5 * (0.25 + 1.0)), 1e-15);
    tb_measured_free(&ms);
    tb_sensors_free(&ss);
}

int main(int argc, char **argv)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_point_light), cmocka_unit_test(test_disc),    cmocka_unit_test(test_rectangle),
        cmocka_unit_test(test_furnace),     cmocka_unit_test(test_methods_agree), cmocka_unit_test(test_filters),
        cmocka_unit_test(test_threads),     cmocka_unit_test(test_errors),  cmocka_unit_test(test_compare),
    };
    if (argc > 1)
        cmocka_set_test_filter(argv[1]);
    return cmocka_run_group_tests(tests, NULL, NULL);
}
