/* The path tracer (host/render/pathtrace.h, docs/pathtrace.md) against
 * analytic answers; every statistical check states its bound from the
 * sample variance (4 sigma) and, where the issue fixes one, a tolerance:
 *
 *  - furnace: inside a closed box of inward-facing Lambert walls of
 *    reflectance rho and exitance E the radiance is E / (pi (1 - rho))
 *    everywhere: to 0.5% for rho 0.5 and 0.8 (RGB) and per band with a
 *    reflectance and an emission that vary over the spectrum; rho 0.9 with
 *    Russian roulette from the first bounce (the estimate rests on the
 *    roulette alone) stays unbiased;
 *  - direct light on a Lambert floor (rho / pi times the irradiance): from
 *    a sphere emitter, E = pi L (R / D)^2 cos(beta), and from a rectangle
 *    above a corner of the receiving point, E = pi L F with the corner form
 *    factor, at several points;
 *  - point, spot (inside the full-intensity cone and in the smoothstep
 *    falloff) and directional lights: rho / pi I cos / d^2 and rho / pi E
 *    cos, exact up to rounding (delta lights are not sampled at random);
 *  - MIS: a GGX floor under a small and a large emitter: the path
 *    tracer's direct light (max_depth 1: light samples and BSDF rays
 *    weighted by the power heuristic) equals a light-sampling-only and a
 *    BSDF-sampling-only estimate written here from the public surface API,
 *    so the weights sum to one; a Lambert + GGX floor under a sphere, an
 *    ellipsoid, a cylinder and a CSG union (exact and tessellated emitters):
 *    the path tracer equals BSDF sampling alone, i.e. the exact surfaces'
 *    light (light sampling alone would see the facets);
 *  - determinism: a rendered image is byte-identical for 1 and 2 threads and
 *    the same seed, and differs for another seed. */
#include "tb_test.h"
#include "test_scene_text.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "host/render/pathtrace.h"
#include "host/render/surface.h"
#include "util/math/rng.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Path counts are divided by $TB_PT_TEST_DIVISOR (the sanitizer build sets 4);
 * the bounds follow from the sample variance, so they widen accordingly. */
static long scaled(long n) { return n / tp_pt_divisor(); }

/* A standard error allowed to grow as the counts shrink: sqrt(divisor) times base. */
static double se_bound(double base) { return base * sqrt((double)tp_pt_divisor()); }

static tb_pathtracer *pt_make(const tb_scene *s, int max_depth, int rr_depth)
{
    tb_pt_options o = {0};
    o.max_depth = max_depth;
    o.rr_depth = rr_depth;
    tb_pathtracer *pt = NULL;
    if (tb_pt_create(s, &o, &pt))
        fail_msg("%s", tb_last_error());
    return pt;
}

/* Mean and standard error of channel c over n paths. */
typedef struct est {
    double mean[TB_CHANNELS_MAX], se[TB_CHANNELS_MAX];
} est;

/* n paths from o toward `target` (or, with random_dir, in uniformly random
 * directions), numbers from stream `seed`. */
static est estimate(const tb_pathtracer *pt, int nc, tb_vec3 o, tb_vec3 target, bool random_dir, long n,
                    uint64_t seed)
{
    double s1[TB_CHANNELS_MAX] = {0}, s2[TB_CHANNELS_MAX] = {0};
    tb_rng rng;
    tb_rng_seed(&rng, seed, 11);
    for (long i = 0; i < n; i++) {
        tb_vec3 d;
        if (random_dir) {
            double z = 1.0 - 2.0 * tb_rng_double(&rng), ph = 2.0 * M_PI * tb_rng_double(&rng);
            double r = sqrt(fmax(0.0, 1.0 - z * z));
            d = tb_vec3_make((float)(r * cos(ph)), (float)(r * sin(ph)), (float)z);
        } else {
            d = tb_vec3_normalize(tb_vec3_sub(target, o));
        }
        tb_ray ray = tb_ray_make(o, d, 0.0f, INFINITY);
        tb_channels L = tb_pt_radiance(pt, &ray, &rng);
        for (int c = 0; c < nc; c++) {
            s1[c] += L.v[c];
            s2[c] += (double)L.v[c] * L.v[c];
        }
    }
    est e;
    for (int c = 0; c < nc; c++) {
        e.mean[c] = s1[c] / n;
        double var = fmax(0.0, s2[c] / n - e.mean[c] * e.mean[c]);
        e.se[c] = sqrt(var / n);
    }
    return e;
}

/* ------------------------------------------------------------------ furnace */

/* The inside of the box [-10, 10]^3, every face turned so that its front
 * (counter-clockwise) side faces the centre, with the material `mat`. */
static void furnace_box(char *buf, size_t n, const char *mat)
{
    size_t k = 0;
    for (int axis = 0; axis < 3; axis++)
        for (int sgn = -1; sgn <= 1; sgn += 2) {
            int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
            static const int sq[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
            int v[4][3];
            for (int j = 0; j < 4; j++) {
                v[j][axis] = 10 * sgn;
                v[j][a1] = 10 * sq[j][0];
                v[j][a2] = 10 * sq[j][1];
            }
            /* (a1, a2, axis) is right-handed: this loop's normal is +axis,
             * inward for the face at -10, reversed for the face at +10 */
            k += (size_t)snprintf(buf + k, n - k, "polygons { geometry = { vertices = [");
            for (int j = 0; j < 4; j++) {
                int q = sgn < 0 ? j : 3 - j;
                k += (size_t)snprintf(buf + k, n - k, "[%d %d %d] ", v[q][0], v[q][1], v[q][2]);
            }
            k += (size_t)snprintf(buf + k, n - k, "] faces = [[0 1 2 3]] } rendering = { %s } }\n", mat);
        }
}

/* Radiance everywhere in the box against E / (pi (1 - rho)) per channel,
 * read from the loaded material (band values in a spectral scene). */
static void furnace_check(const char *what, const char *mat, long n, int rr_depth, double tol, uint64_t seed)
{
    char text[8192];
    int k = snprintf(text, sizeof text, "mid 1.1\n");
    furnace_box(text + k, sizeof text - (size_t)k, mat);
    tb_scene *s = tp_scene_text(text);
    tb_pathtracer *pt = pt_make(s, 0, rr_depth);
    const tb_material *m = &s->materials[0];
    est e = estimate(pt, s->nchannels, tb_vec3_make(1.0f, -2.0f, 3.0f), tb_vec3_make(0, 0, 0), true, n, seed);
    double worst = 0.0, sig = 0.0;
    for (int c = 0; c < s->nchannels; c++) {
        double want = m->emission.v[c] / (M_PI * (1.0 - m->diffuse.v[c]));
        double err = fabs(e.mean[c] - want);
        worst = fmax(worst, err / want);
        sig = fmax(sig, 4.0 * e.se[c] / want);
        if (!(err <= 4.0 * e.se[c] + 1e-6 * want))
            fail_msg("%s channel %d: %.6f, exact %.6f: off by %.2f sigma", what, c, e.mean[c], want, err / e.se[c]);
        if (!(4.0 * e.se[c] <= tol * want) || !(err <= tol * want))
            fail_msg("%s channel %d: %.6f +- %.6f, exact %.6f: not within %g", what, c, e.mean[c], e.se[c], want,
                     tol);
    }
    printf("[ furnace  ] %-34s %d channels, %ld paths: worst rel. error %.2e, 4 sigma %.2e (bound %g)\n", what,
           s->nchannels, n, worst, sig, tol);
    tb_pt_free(pt);
    tb_scene_free(s);
}

/* The 0.5% bound needs 4 sigma below it: sigma / mean of one path is about
 * 0.37 at rho 0.5 and 0.77 at rho 0.8 (measured: 4 sigma 3.3e-3 at 2e5
 * paths, 4.9e-3 at 4e5), so 2e5 and 6e5 paths. */
static double furnace_tol(void) { return getenv("TB_PT_TEST_DIVISOR") ? 0.01 : 0.005; }

static void test_furnace_rgb(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("pt furnace rgb", 161);
    furnace_check("rgb rho 0.5", "diffuse = 0.5 emission = [1 2 0.5]", scaled(200000), 0, furnace_tol(), seed);
    furnace_check("rgb rho 0.8", "diffuse = [0.8 0.8 0.8] emission = 1", scaled(600000), 0, furnace_tol(), seed + 1);
}

static void test_furnace_spectral(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("pt furnace spectral", 165);
    furnace_check("spectral rho 0.5..0.8",
                  "diffuse = spectrum([400 550 700], [0.5 0.8 0.6]) emission = spectrum([400 700], [1 3])",
                  scaled(600000), 0, furnace_tol(), seed);
    /* Roulette from the first bounce at rho 0.9: long paths, the estimate
     * unbiased only if the roulette is (bound from the variance, 1%). */
    furnace_check("rgb rho 0.9, roulette from bounce 1", "diffuse = 0.9 emission = 1", scaled(300000), 1,
                  2.0 * furnace_tol(), seed + 3);
}

/* ---------------------------------------------------------- direct light */

/* The floor: z = 0 over [-40, 40]^2, front side up, Lambert rho. */
#define FLOOR                                                                              \
    "polygons { geometry = { vertices = [[-40 -40 0] [40 -40 0] [40 40 0] [-40 40 0]] "    \
    "faces = [[0 1 2 3]] } rendering = { diffuse = 0.5 } }\n"

/* Floor radiance at (x, y) seen from low on the -x side (below the emitters), channel 0. */
static est floor_radiance(const tb_pathtracer *pt, double x, double y, long n, uint64_t seed)
{
    tb_vec3 q = tb_vec3_make((float)x, (float)y, 0.0f);
    return estimate(pt, 3, tb_vec3_add(q, tb_vec3_make(-6.0f, -1.0f, 1.0f)), q, false, n, seed);
}

static void check_direct(const char *what, const est *e, double want)
{
    double err = fabs(e->mean[0] - want);
    printf("[ direct   ] %-40s %.6f exact %.6f (%.2f sigma)\n", what, e->mean[0], want, err / e->se[0]);
    if (!(err <= 4.0 * e->se[0] + 1e-5 * want))
        fail_msg("%s: %.6f, exact %.6f, %.2f sigma", what, e->mean[0], want, err / e->se[0]);
    if (!(e->se[0] <= se_bound(0.01) * want))
        fail_msg("%s: standard error %.3g too large for a check", what, e->se[0]);
}

/* A sphere emitter (radius 1, centre (0, 0, 6), M = pi: L = 1, reflecting
 * nothing) over the floor. */
static void test_direct_sphere(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("pt direct sphere", 162);
    tb_scene *s = tp_scene_text("mid 1.1\n" FLOOR
                       "sphere { transform = [translate([0 0 6])] "
                       "rendering = { diffuse = 0 emission = 3.14159265358979 } }\n");
    tb_pathtracer *pt = pt_make(s, 0, 0);
    const double pts[][2] = {{0, 0}, {3, 1}, {-4, -2}};
    for (int k = 0; k < 3; k++) {
        double x = pts[k][0], y = pts[k][1];
        double D2 = x * x + y * y + 36.0, cosb = 6.0 / sqrt(D2);
        double want = 0.5 / M_PI * M_PI * 1.0 * (1.0 / D2) * cosb;
        char name[64];
        snprintf(name, sizeof name, "sphere emitter, point (%g, %g)", x, y);
        est e = floor_radiance(pt, x, y, scaled(40000), seed + (uint64_t)k);
        check_direct(name, &e, want);
    }
    tb_pt_free(pt);
    tb_scene_free(s);
}

/* Form factor from a point to a rectangle a x b parallel to it at height h,
 * above one corner. */
static double corner_ff(double a, double b, double h)
{
    double A = a / h, B = b / h, sa = sqrt(1.0 + A * A), sb = sqrt(1.0 + B * B);
    return (A / sa * atan(B / sa) + B / sb * atan(A / sb)) / (2.0 * M_PI);
}

/* A rectangle emitter [0, 2] x [0, 3] at z = 4 facing down (L = 2). */
static void test_direct_rectangle(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("pt direct rectangle", 163);
    tb_scene *s = tp_scene_text("mid 1.1\n" FLOOR
                       "polygons { geometry = { vertices = [[0 0 4] [0 3 4] [2 3 4] [2 0 4]] faces = [[0 1 2 3]] } "
                       "rendering = { diffuse = 0 emission = 6.28318530717959 } }\n");
    tb_pathtracer *pt = pt_make(s, 0, 0);
    /* at (0, 0): one corner; at (1, 1): four rectangles meeting there */
    double f0 = corner_ff(2, 3, 4);
    double f1 = corner_ff(1, 1, 4) + corner_ff(1, 2, 4) + corner_ff(1, 1, 4) + corner_ff(1, 2, 4);
    est e0 = floor_radiance(pt, 0, 0, scaled(40000), seed);
    check_direct("rectangle emitter, corner", &e0, 0.5 / M_PI * M_PI * 2.0 * f0);
    est e1 = floor_radiance(pt, 1, 1, scaled(40000), seed + 1);
    check_direct("rectangle emitter, inside", &e1, 0.5 / M_PI * M_PI * 2.0 * f1);
    tb_pt_free(pt);
    tb_scene_free(s);
}

/* ------------------------------------------------------------ delta lights */

static void test_delta_lights(void **state)
{
    (void)state;
    tb_scene *s = tp_scene_text("mid 1.1\n" FLOOR
                       "point_light { position = [1 2 5] intensity = 40 }\n"
                       "spot_light { position = [-20 0 8] direction = [0 0 -1] intensity = 90 cone_angle = 30 "
                       "cone_delta = 10 }\n"
                       "directional_light { direction = [0.6 0 -0.8] irradiance = 2 }\n");
    tb_pathtracer *pt = pt_make(s, 0, 0);
    const double pts[][2] = {{0, 0}, {2, -3}, {-20, 0}, {-20, 3.5}, {-20, 4.2}};
    for (int k = 0; k < 5; k++) {
        double x = pts[k][0], y = pts[k][1];
        /* point light: I cos / d^2 */
        double dx = 1 - x, dy = 2 - y, dz = 5, d2 = dx * dx + dy * dy + dz * dz;
        double E = 40.0 * dz / sqrt(d2) / d2;
        /* spot light: inside 20 degrees full, smoothstep to 30 */
        double sx = -20 - x, sy = -y, sz = 8, s2 = sx * sx + sy * sy + sz * sz, cs = sz / sqrt(s2);
        double ct = cos(30.0 * M_PI / 180.0), cf = cos(20.0 * M_PI / 180.0);
        double t = fmin(1.0, fmax(0.0, (cs - ct) / (cf - ct)));
        E += 90.0 * t * t * (3.0 - 2.0 * t) * cs / s2;
        /* directional: E cos */
        E += 2.0 * 0.8;
        double want = 0.5 / M_PI * E;
        tb_vec3 q = tb_vec3_make((float)x, (float)y, 0.0f);
        tb_rng rng;
        tb_rng_seed(&rng, 1, (uint64_t)k);
        /* straight down: the paths that bounce off the floor find nothing */
        tb_ray ray = tb_ray_make(tb_vec3_add(q, tb_vec3_make(0, 0, 3)), tb_vec3_make(0, 0, -1), 0.0f, INFINITY);
        double L = tb_pt_radiance(pt, &ray, &rng).v[0];
        printf("[ delta    ] point (%g, %g): %.7f exact %.7f (spot factor %.3f)\n", x, y, L, want, t);
        tb_assert_near(L, want, 1e-5 * want);
    }
    tb_pt_free(pt);
    tb_scene_free(s);
}

/* -------------------------------------------------------------------- MIS */

typedef struct mis_ctx {
    const tb_scene *s;
    tb_surfaces *ss;
    tb_light_set ls;
} mis_ctx;

/* Direct light at the floor point seen along `ray` by one strategy alone:
 * light samples (f L cos / pdf) or BSDF samples (weight times the emission
 * the ray meets). */
static double one_strategy(const mis_ctx *c, const tb_ray *ray, bool light, tb_rng *rng)
{
    tb_hit hit;
    tb_surface sf;
    if (!tb_scene_intersect(c->s, ray, &hit) || !tb_surface_at(c->ss, ray, &hit, NULL, &sf))
        return 0.0;
    tb_surface_bsdf b;
    tb_surface_bsdf_init(&sf, TB_SURFACE_PHYSICAL, &b);
    if (light) {
        tb_light_sample l;
        float u1 = tb_rng_float(rng), u2 = tb_rng_float(rng);
        if (!tb_light_set_sample(&c->ls, c->ls.nlights, sf.p, u1, u2, &l) || tb_light_set_occluded(&c->ls, &sf, &l))
            return 0.0; /* the facet sampled, as the ray tracer sees it */
        return tb_surface_bsdf_eval(&b, sf.wo, l.wi).v[0] * l.L.v[0] * fabs(tb_vec3_dot(l.wi, sf.n)) / l.pdf;
    }
    tb_surface_sample bs;
    float uc = tb_rng_float(rng), u1 = tb_rng_float(rng), u2 = tb_rng_float(rng);
    if (!tb_surface_bsdf_sample(&b, sf.wo, uc, u1, u2, &bs))
        return 0.0;
    tb_ray r = tb_surface_spawn(&sf, bs.wi);
    tb_surface e;
    if (!tb_scene_intersect(c->s, &r, &hit) || !tb_surface_at(c->ss, &r, &hit, NULL, &e))
        return 0.0;
    return bs.weight.v[0] * tb_surface_emitted(&e).v[0];
}

/* The path tracer's direct light at floor point q seen from `eye` against
 * the two single-strategy estimates, n paths each. */
static void mis_case(const char *what, const char *text, tb_vec3 eye, tb_vec3 q, long n, bool exact, uint64_t seed)
{
    tb_scene *s = tp_scene_text(text);
    mis_ctx c = {.s = s};
    assert_int_equal(tb_surfaces_create(s, NULL, &c.ss), TB_OK);
    assert_int_equal(tb_light_set_init(&c.ls, s), TB_OK);
    tb_pathtracer *pt = pt_make(s, 1, 0);
    est mis = estimate(pt, 3, eye, q, false, n, seed);
    double m[2], se[2];
    for (int k = 0; k < 2; k++) {
        tb_rng rng;
        tb_rng_seed(&rng, seed + 10 + (uint64_t)k, 3);
        tb_ray ray = tb_ray_make(eye, tb_vec3_normalize(tb_vec3_sub(q, eye)), 0.0f, INFINITY);
        double s1 = 0.0, s2 = 0.0;
        for (long i = 0; i < n; i++) {
            double v = one_strategy(&c, &ray, k == 0, &rng);
            s1 += v;
            s2 += v * v;
        }
        m[k] = s1 / n;
        se[k] = sqrt(fmax(0.0, s2 / n - m[k] * m[k]) / n);
    }
    printf("[ mis      ] %s: MIS %.5f +- %.5f, light only %.5f +- %.5f, BSDF only %.5f +- %.5f\n", what,
           mis.mean[0], mis.se[0], m[0], se[0], m[1], se[1]);
    /* light sampling alone sees tessellated emitters as their facets: it is
     * compared only where the emitters are exact */
    for (int k = exact ? 0 : 1; k < 2; k++) {
        double sd = sqrt(mis.se[0] * mis.se[0] + se[k] * se[k]);
        if (!(fabs(mis.mean[0] - m[k]) <= 4.0 * sd))
            fail_msg("%s: MIS %.5f vs %s %.5f: %.2f sigma", what, mis.mean[0], k ? "BSDF only" : "light only", m[k],
                     fabs(mis.mean[0] - m[k]) / sd);
        assert_true(sd < se_bound(0.02) * m[k]); /* a meaningful comparison */
    }
    /* MIS has the smaller error of the two at the same count */
    assert_true(mis.se[0] < fmax(se[0], se[1]));
    tb_pt_free(pt);
    tb_light_set_release(&c.ls);
    tb_surfaces_free(c.ss);
    tb_scene_free(s);
}

static void test_mis_weights(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("pt mis", 164);
    /* a glossy GGX floor; a small bright square and a large dim panel, viewed
     * from the side where the small square's reflection lies */
    mis_case("GGX floor, two rectangles",
             "mid 1.1\n"
             "polygons { geometry = { vertices = [[-40 -40 0] [40 -40 0] [40 40 0] [-40 40 0]] "
             "faces = [[0 1 2 3]] } rendering = { diffuse = 0.2 specular = 0.8 model = ggx roughness = 0.15 } }\n"
             "polygons { geometry = { vertices = [[-3.2 -0.2 3] [-3.2 0.2 3] [-2.8 0.2 3] [-2.8 -0.2 3]] "
             "faces = [[0 1 2 3]] } rendering = { diffuse = 0 emission = 300 } }\n"
             "polygons { geometry = { vertices = [[1 -6 5] [1 6 5] [9 6 5] [9 -6 5]] "
             "faces = [[0 1 2 3]] } rendering = { diffuse = 0 emission = 3 } }\n",
             tb_vec3_make(3.0f, 0.0f, 3.0f), tb_vec3_make(0.0f, 0.0f, 0.0f), scaled(200000), true, seed);
    /* every kind of emitter: an exact sphere, an ellipsoid and a cylinder
     * (tessellated: facets pushed out, with gaps), a CSG union of two cubes
     * (its clipped faces) over a Lambert + GGX floor */
    mis_case("Lambert + GGX floor, sphere, ellipsoid, cylinder, CSG emitters",
             "mid 1.1\n"
             "polygons { geometry = { vertices = [[-40 -40 0] [40 -40 0] [40 40 0] [-40 40 0]] "
             "faces = [[0 1 2 3]] } rendering = { diffuse = 0.5 specular = 0.4 model = ggx roughness = 0.3 } }\n"
             "sphere { transform = [scale(0.4) translate([-1.5 1 2.5])] rendering = { diffuse = 0 emission = 20 } }\n"
             "cylinder { transform = [scale([0.3 0.3 0.6]) translate([-1 -2 2])] "
             "rendering = { diffuse = 0 emission = 10 } }\n"
             "sphere { transform = [scale([0.8 0.5 0.3]) translate([1.5 -1 2])] "
             "rendering = { diffuse = 0 emission = 10 } }\n"
             "union { transform = [translate([1.5 1 2.5])] rendering = { diffuse = 0 emission = 8 } "
             "cube { transform = [scale(0.4)] } cube { transform = [scale(0.4) rotate([0 0 1] 45) "
             "translate([0.3 0 0.2])] } }\n",
             tb_vec3_make(-3.0f, 0.5f, 2.0f), tb_vec3_make(0.2f, 0.1f, 0.0f), scaled(100000), false, seed + 100);
}

/* ------------------------------------------------------------ determinism */

static void test_threads_identical(void **state)
{
    (void)state;
    /* the bundled spheres scene (mirror, glass, spectral) on a 48 x 48 film */
    FILE *fp = fopen(TB_SOURCE_DIR "/scenes/cornell-box-spheres.mid", "r");
    assert_non_null(fp);
    static char text[1 << 16];
    size_t len = fread(text, 1, sizeof text - 1, fp);
    fclose(fp);
    text[len] = 0;
    char *res = strstr(text, "resolution = [512 512]");
    assert_non_null(res);
    memcpy(res, "resolution = [48 48]  ", 22);
    FILE *mf = fmemopen(text, len, "r");
    tb_scene *s = NULL;
    if (tb_scene_load_stream(mf, "cornell-box-spheres.mid", TB_SOURCE_DIR "/scenes", NULL, &s))
        fail_msg("%s", tb_last_error());
    fclose(mf);
    assert_int_equal(s->camera.width, 48);
    tb_image *img[3] = {NULL, NULL, NULL};
    for (int k = 0; k < 3; k++) {
        tb_render_options o = tb_render_defaults();
        o.aa.spp = 4;
        o.threads = k == 0 ? 1 : 2;
        o.aa.seed = k == 2 ? 99 : 7;
        if (tb_render_path(s, NULL, &o, &img[k], NULL))
            fail_msg("%s", tb_last_error());
    }
    size_t bytes = (size_t)img[0]->width * img[0]->height * img[0]->channels * sizeof(float);
    assert_memory_equal(img[0]->pixels, img[1]->pixels, bytes);
    assert_true(memcmp(img[0]->pixels, img[2]->pixels, bytes) != 0);
    printf("[ threads  ] 48x48 at 4 spp: 1 and 2 threads byte-identical; another seed differs\n");
    for (int k = 0; k < 3; k++)
        tb_image_free(img[k]);
    tb_scene_free(s);
}

/* Bad options are refused with a message. */
static void test_bad_options(void **state)
{
    (void)state;
    tb_scene *s = tp_scene_text("mid 1.1\n" FLOOR);
    tb_pathtracer *pt = NULL;
    tb_pt_options o = {.max_depth = -1};
    assert_int_equal(tb_pt_create(s, &o, &pt), TB_ERR_ARG);
    assert_null(pt);
    o = (tb_pt_options){.rr_depth = TB_PT_MAX_BOUNCES + 1};
    assert_int_equal(tb_pt_create(s, &o, &pt), TB_ERR_ARG);
    o = (tb_pt_options){.texture_filter = 9};
    assert_int_equal(tb_pt_create(s, &o, &pt), TB_ERR_ARG);
    printf("[ options  ] %s\n", tb_last_error());
    tb_scene_free(s);
}

/* `render_pt_render furnace-rgb` or `furnace-spectral` runs that furnace alone (a ctest of
 * its own: each takes about ten seconds), no argument the rest. */
int main(int argc, char **argv)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bad_options),   cmocka_unit_test(test_delta_lights),
        cmocka_unit_test(test_direct_sphere), cmocka_unit_test(test_direct_rectangle),
        cmocka_unit_test(test_mis_weights),   cmocka_unit_test(test_threads_identical),
    };
    const struct CMUnitTest furnace_rgb[] = {cmocka_unit_test(test_furnace_rgb)};
    const struct CMUnitTest furnace_spectral[] = {cmocka_unit_test(test_furnace_spectral)};
    if (argc > 1 && !strcmp(argv[1], "furnace-rgb"))
        return cmocka_run_group_tests(furnace_rgb, NULL, NULL);
    if (argc > 1 && !strcmp(argv[1], "furnace-spectral"))
        return cmocka_run_group_tests(furnace_spectral, NULL, NULL);
    return cmocka_run_group_tests(tests, NULL, NULL);
}
