/* The MID 1.1 material attributes through the ray tracer (docs/raytrace.md,
 * "Materials"): every expected value comes from the shading module's own
 * functions, a quadrature written here, or geometry worked out by hand.
 *
 *  - a GGX sphere (F0 = 1) inside a closed box of inward emitters of
 *    radiance 1 (a white furnace) returns its directional albedo E(wo),
 *    integrated here from tb_bsdf_eval by quadrature (< 1: the
 *    single-scattering loss);
 *  - a GGX floor under a small area light, lit by light samples and glossy
 *    rays combined by multiple importance sampling, gives the quadrature of
 *    f L cos cos' / d^2 over the emitter;
 *  - under a point light, every model's radiance is rho/pi + its lobe times
 *    I cos / d^2 (GGX: tb_bsdf_eval; Blinn: the exact normalisation; Lambert:
 *    no specular term), so GGX and Lambert differ by the lobe where it is
 *    large and agree far from it;
 *  - a grazing floor with a checker pattern averages to grey without moire,
 *    a noise pattern far away fades to its mean (octaves limited by the
 *    footprint), and seen up close has the mean and spread of fBm;
 *  - an object-space checker follows the object's transform;
 *  - a bump map with a constant slope (an image ramp) tilts the normal by
 *    the analytic angle: cos = n' . l with n' = normalise(-H, 0, 2). */
#include "tb_test.h"
#include "test_scene_text.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "host/render/raytrace.h"
#include "host/render/shading.h"
#include "util/math/rng.h"

#define M_PI 3.14159265358979323846

static void rt_init(tb_raytracer *rt, const tb_scene *s, int glossy)
{
    tb_rt_options o = {0};
    o.glossy_samples = glossy;
    if (tb_rt_init(rt, s, &o))
        fail_msg("%s", tb_last_error());
}

static tb_channels radiance(const tb_raytracer *rt, tb_vec3 o, tb_vec3 target, uint64_t seed)
{
    tb_ray r = tb_ray_make(o, tb_vec3_normalize(tb_vec3_sub(target, o)), 0.0f, INFINITY);
    tb_rng rng;
    tb_rng_seed(&rng, seed, 7);
    return tb_rt_radiance(rt, &r, &rng);
}

/* ------------------------------------------------------------ white furnace */

/* E(wo) = integral of f cos over the hemisphere, midpoint rule in (cos theta,
 * phi) (dw = dmu dphi) on a grid refined toward the lobe's peak. */
static double albedo(const tb_bsdf *b, tb_vec3 wo)
{
    const int nm = 800, np = 800;
    double sum = 0.0;
    for (int i = 0; i < nm; i++) {
        /* mu = 1 - t^2 puts more points near the pole and the mirror direction */
        double t0 = (double)i / nm, t1 = (double)(i + 1) / nm, t = 0.5 * (t0 + t1);
        double mu = 1.0 - t * t, dmu = t1 * t1 - t0 * t0;
        double sn = sqrt(fmax(0.0, 1.0 - mu * mu));
        for (int j = 0; j < np; j++) {
            double phi = 2.0 * M_PI * (j + 0.5) / np;
            tb_vec3 wi = {(float)(sn * cos(phi)), (float)(sn * sin(phi)), (float)mu};
            sum += tb_bsdf_eval(b, wo, wi).v[0] * mu * dmu * (2.0 * M_PI / np);
        }
    }
    return sum;
}

/* The inside of the box [-10, 10]^3: every face turned so that its front
 * (counter-clockwise) side faces the centre, emitting M = pi (radiance 1)
 * into the box and reflecting nothing. */
static void furnace_box(char *buf, size_t n)
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
            /* (a1, a2, axis) is right-handed, so this loop's normal is +axis:
             * inward for the face at -10, reversed for the face at +10 */
            k += (size_t)snprintf(buf + k, n - k, "polygons { geometry = { vertices = [");
            for (int j = 0; j < 4; j++) {
                int q = sgn < 0 ? j : 3 - j;
                k += (size_t)snprintf(buf + k, n - k, "[%d %d %d] ", v[q][0], v[q][1], v[q][2]);
            }
            k += (size_t)snprintf(buf + k, n - k,
                                  "] faces = [[0 1 2 3]] } rendering = { diffuse = 0 emission = 3.14159265358979 } }\n");
        }
}

static void test_ggx_white_furnace(void **state)
{
    (void)state;
    static const double alphas[] = {0.2, 0.5, 1.0};
    static const double angles[] = {0.0, 45.0, 70.0};
    for (int ia = 0; ia < 3; ia++) {
        char text[8192];
        int k = snprintf(text, sizeof text,
                         "mid 1.1\nsphere { rendering = { diffuse = 0 specular = 1 model = ggx roughness = %g } }\n",
                         alphas[ia]);
        furnace_box(text + k, sizeof text - (size_t)k);
        tb_scene *s = tp_scene_text(text);
        tb_raytracer rt;
        rt_init(&rt, s, 64);
        tb_bsdf b = tb_bsdf_ggx(tb_channels_splat(1, 1.0f), alphas[ia], TB_FRESNEL_SCHLICK, 1.0);
        for (int it = 0; it < 3; it++) {
            double th = angles[it] * M_PI / 180.0;
            tb_vec3 wo = {(float)sin(th), 0.0f, (float)cos(th)};
            double E = albedo(&b, wo);
            /* the ray arrives at the sphere's pole (normal +z) from wo */
            tb_vec3 q = {0, 0, 1};
            const int calls = 300;
            double sum = 0.0, sum2 = 0.0;
            for (int c = 0; c < calls; c++) {
                tb_channels L = radiance(&rt, tb_vec3_add(q, tb_vec3_scale(wo, 4.0f)), q, (uint64_t)c);
                sum += L.v[1];
                sum2 += (double)L.v[1] * L.v[1];
            }
            double mean = sum / calls, sd = sqrt(fmax(0.0, sum2 / calls - mean * mean));
            double tol = 5.0 * sd / sqrt((double)calls) + 5e-4;
            print_message("GGX furnace: alpha %.1f theta %2.0f: rendered %.5f +- %.5f, albedo %.5f\n", alphas[ia],
                          angles[it], mean, sd / sqrt((double)calls), E);
            tb_assert_near(mean, E, tol);
            assert_true(E < 1.0);
        }
        tb_rt_release(&rt);
        tb_scene_free(s);
    }
}

/* A GGX floor (F0 = 1, alpha 0.3) under a 1 x 1 emitter of radiance 1 at
 * height 2, seen along the mirror direction of the emitter's centre: light
 * samples and glossy rays, combined by the power heuristic, must give the
 * integral of f L cos cos' / d^2 over the emitter (quadrature here). Weights
 * that did not sum to one for every direction would bias it. */
static void test_ggx_area_light_mis(void **state)
{
    (void)state;
    const double alpha = 0.3;
    tb_scene *s = tp_scene_text("mid 1.1\n"
                       "polygons { geometry = { vertices = [[0 -0.5 2] [0 0.5 2] [1 0.5 2] [1 -0.5 2]] faces = [[0 1 2 3]] }\n"
                       "  rendering = { diffuse = 0 emission = 3.14159265358979 } }\n"
                       "polygons { geometry = { vertices = [[-50 -50 0] [50 -50 0] [50 50 0] [-50 50 0]] faces = [[0 1 2 3]] }\n"
                       "  rendering = { diffuse = 0 specular = 1 model = ggx roughness = 0.3 } }\n");
    tb_bsdf b = tb_bsdf_ggx(tb_channels_splat(1, 1.0f), alpha, TB_FRESNEL_SCHLICK, 1.0);
    tb_vec3 wo = tb_vec3_normalize((tb_vec3){-0.5f, 0.0f, 2.0f});
    const int n = 400;
    double want = 0.0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double x = (i + 0.5) / n, y = -0.5 + (j + 0.5) / n, d2 = x * x + y * y + 4.0;
            tb_vec3 wi = {(float)(x / sqrt(d2)), (float)(y / sqrt(d2)), (float)(2.0 / sqrt(d2))};
            want += tb_bsdf_eval(&b, wo, wi).v[0] * wi.z * wi.z / d2 / ((double)n * n);
        }
    tb_raytracer rt;
    rt_init(&rt, s, 16);
    const int calls = 400;
    double sum = 0.0, sum2 = 0.0;
    for (int c = 0; c < calls; c++) {
        double L = radiance(&rt, tb_vec3_scale(wo, 3.0f), (tb_vec3){0, 0, 0}, (uint64_t)c).v[0];
        sum += L;
        sum2 += L * L;
    }
    double mean = sum / calls, se = sqrt(fmax(0.0, sum2 / calls - mean * mean) / calls);
    print_message("GGX under an area light (MIS): rendered %.5f +- %.5f, quadrature %.5f\n", mean, se, want);
    tb_assert_near(mean, want, 5.0 * se + 1e-3 * want);
    tb_rt_release(&rt);
    tb_scene_free(s);
}

/* ------------------------------------------------------- models, point light */

static void test_models_under_point_light(void **state)
{
    (void)state;
    const double I = 50.0, h = 4.0, rho = 0.3, ks = 0.04, alpha = 0.1, n = 30.0;
    static const char *const models[] = {"lambert", "phong", "blinn", "ggx"};
    const tb_vec3 light = {0, 0, (float)h};
    /* [0]: a floor point seen along the mirror direction of the light (the
     * highlight); [1]: the point under the light seen from 60 degrees off the
     * normal (the half vector 30 degrees off: far out in the lobes' tails) */
    const tb_vec3 P[2] = {{1.5f, 0.5f, 0.0f}, {0.0f, 0.0f, 0.0f}};
    const tb_vec3 eyes[2] = {{4.5f, 1.5f, 8.0f}, {3.4641016f, 0.0f, 2.0f}};
    double got[4][2], want[4][2];
    for (int im = 0; im < 4; im++) {
        char text[1024];
        snprintf(text, sizeof text,
                 "mid 1.1\npoint_light { position = [0 0 %g] intensity = %g }\n"
                 "polygons { geometry = { vertices = [[-50 -50 0] [50 -50 0] [50 50 0] [-50 50 0]] faces = [[0 1 2 3]] }\n"
                 "  rendering = { diffuse = %g specular = %g exponent = %g roughness = %g model = %s } }\n",
                 h, I, rho, ks, n, alpha, models[im]);
        tb_scene *s = tp_scene_text(text);
        tb_raytracer rt;
        rt_init(&rt, s, 1);
        for (int e = 0; e < 2; e++) {
            tb_vec3 wo = tb_vec3_normalize(tb_vec3_sub(eyes[e], P[e]));
            tb_vec3 d = tb_vec3_sub(light, P[e]);
            double d2 = tb_vec3_dot(d, d);
            tb_vec3 wi = tb_vec3_normalize(d);
            double E = I / d2 * wi.z;
            double f = rho / M_PI;
            if (im == 1) {
                double c = tb_vec3_dot(tb_reflect(wo, (tb_vec3){0, 0, 1}), wi);
                f += c > 0.0 ? ks * (n + 2.0) / (2.0 * M_PI) * pow(c, n) : 0.0;
            } else if (im == 2) {
                tb_vec3 hv = tb_vec3_normalize(tb_vec3_add(wo, wi));
                f += ks * tb_bsdf_lobe_norm(TB_BSDF_BLINN_NORMALIZED_EXACT, n) * pow(hv.z, n);
            } else if (im == 3) {
                tb_bsdf b = tb_bsdf_ggx(tb_channels_splat(1, (float)ks), alpha, TB_FRESNEL_SCHLICK, 1.0);
                f += tb_bsdf_eval(&b, wo, wi).v[0]; /* the plane's frame is the world's */
            }
            want[im][e] = f * E;
            got[im][e] = radiance(&rt, eyes[e], P[e], 1).v[0];
            tb_assert_near(got[im][e], want[im][e], 1e-5 * want[im][e] + 1e-7);
        }
        tb_rt_release(&rt);
        tb_scene_free(s);
    }
    print_message("point light, highlight: lambert %.5f phong %.5f blinn %.5f ggx %.5f\n", got[0][0], got[1][0],
                  got[2][0], got[3][0]);
    print_message("point light, off the lobe: lambert %.6f phong %.6f blinn %.6f ggx %.6f\n", got[0][1], got[1][1],
                  got[2][1], got[3][1]);
    /* GGX against Lambert: far more light in the highlight, little added off it */
    assert_true(got[3][0] > 3.0 * got[0][0]);
    assert_true(fabs(got[3][1] - got[0][1]) < 0.03 * got[0][1]);
}

/* ----------------------------------------------------- grazing patterns */

/* Renders the 64 x 48 grazing view of a floor with material `mat` under a
 * directional light of irradiance pi (so the value is the diffuse colour),
 * through tb_rt_sample (camera ray differentials), and returns the mean,
 * standard deviation, min and max of rows y0..y1. */
static void grazing_rows(const char *mat, int y0, int y1, double out[4])
{
    char text[1024];
    snprintf(text, sizeof text,
             "mid 1.1\ncamera { eye = [0 1 0] look_at = [0 0 20] up = [0 1 0] fov = 30 resolution = [64 48] }\n"
             "directional_light { direction = [0 -1 0] irradiance = 3.14159265358979 }\n"
             "polygons { geometry = { vertices = [[-100 0 0] [-100 0 100] [100 0 100] [100 0 0]] faces = [[0 1 2 3]] }\n"
             "  rendering = { %s } }\n",
             mat);
    tb_scene *s = tp_scene_text(text);
    tb_raytracer rt;
    rt_init(&rt, s, 1);
    double sum = 0.0, sum2 = 0.0, lo = INFINITY, hi = -INFINITY;
    int cnt = 0;
    for (int y = y0; y <= y1; y++)
        for (int x = 0; x < 64; x++) {
            tb_rng rng;
            tb_rng_seed(&rng, (uint64_t)(y * 64 + x), 1);
            float L[TB_CHANNELS_MAX];
            tb_rt_sample(&rt, x + 0.5, y + 0.5, &rng, L);
            sum += L[0];
            sum2 += (double)L[0] * L[0];
            lo = fmin(lo, L[0]);
            hi = fmax(hi, L[0]);
            cnt++;
        }
    out[0] = sum / cnt;
    out[1] = sqrt(fmax(0.0, sum2 / cnt - out[0] * out[0]));
    out[2] = lo;
    out[3] = hi;
    tb_rt_release(&rt);
    tb_scene_free(s);
}

static void test_grazing_checker_is_grey(void **state)
{
    (void)state;
    double far[4], near[4];
    /* 1024 checks across the floor's (u, v) range (checks of 0.2 x 0.1
     * units): rows 24..31 (3.5 to 8 degrees below the horizon) cover 5 to 28
     * checks along the view and a few tenths across; the closed-form box
     * filter over the footprint makes them grey (a point sample per pixel
     * would give 0 or 1: sd 0.5) */
    grazing_rows("diffuse = 1 diffuse_pattern = checker(1024, 0, 1)", 24, 31, far);
    grazing_rows("diffuse = 1 diffuse_pattern = checker(1024, 0, 1)", 44, 47, near);
    print_message("grazing checker: far rows mean %.4f sd %.4f; near rows sd %.4f\n", far[0], far[1], near[1]);
    tb_assert_near(far[0], 0.5, 0.01);
    assert_true(far[1] < 0.02);
    assert_true(near[1] > 0.2); /* up close the checks are resolved, so the test can tell */
}

static void test_noise_pattern_statistics(void **state)
{
    (void)state;
    double far[4], near[4];
    /* far away the octaves finer than the pixel drop out: the value tends to
     * the mean 0.5 (fBm of no octaves is 0) */
    grazing_rows("diffuse = 1 diffuse_pattern = noise(2000, 6, 0, 1)", 24, 27, far);
    print_message("grazing noise: far rows mean %.4f sd %.4f range [%.3f, %.3f]\n", far[0], far[1], far[2], far[3]);
    tb_assert_near(far[0], 0.5, 0.02);
    assert_true(far[1] < 0.03);
    /* seen up close (rows 40..47: about 2 to 8 units away, a few noise cells
     * per pixel row at most): the spread of fBm around 0.5, within [0, 1] */
    grazing_rows("diffuse = 1 diffuse_pattern = noise(20, 4, 0, 1)", 40, 47, near);
    print_message("near noise: mean %.4f sd %.4f range [%.3f, %.3f]\n", near[0], near[1], near[2], near[3]);
    tb_assert_near(near[0], 0.5, 0.06);
    assert_true(near[1] > 0.05 && near[1] < 0.3);
    assert_true(near[2] >= 0.0 && near[3] <= 1.0);
    assert_true(near[3] - near[2] > 0.3);
}

/* ------------------------------------------------- object-space checker */

static void test_object_space_checker(void **state)
{
    (void)state;
    /* a unit sphere scaled by 2 and moved to x = 5: object point (x, 0, 0.8)
     * of the 3D checker of scale 1 is odd for x = -0.6 (floor -1) and even
     * for x = 0.6; straight down light, cos = 0.8 */
    tb_scene *s = tp_scene_text("mid 1.1\ndirectional_light { direction = [0 0 -1] irradiance = 3.14159265358979 }\n"
                       "sphere { transform = [scale(2) translate([5 0 0])]\n"
                       "  rendering = { diffuse_pattern = checker(1, 0.2, 0.8, object) } }\n");
    tb_raytracer rt;
    rt_init(&rt, s, 1);
    double odd = radiance(&rt, (tb_vec3){5.0f - 1.2f, 0, 10}, (tb_vec3){5.0f - 1.2f, 0, 0}, 1).v[0];
    double even = radiance(&rt, (tb_vec3){5.0f + 1.2f, 0, 10}, (tb_vec3){5.0f + 1.2f, 0, 0}, 1).v[0];
    tb_assert_near(odd, 0.8 * 0.8, 1e-5);
    tb_assert_near(even, 0.2 * 0.8, 1e-5);
    tb_rt_release(&rt);
    tb_scene_free(s);
}

/* ----------------------------------------------------------------- bump */

static void test_bump_constant_slope(void **state)
{
    (void)state;
    /* heights h(u) = H u from a 256 x 1 ramp (texel x = (x + 1/2) / 256, so
     * bilinear lookups are exactly u between the texel centres) */
    char path[1024];
    snprintf(path, sizeof path, "%s/rt_bump_ramp.pfm", tb_test_tmpdir());
    FILE *fp = fopen(path, "wb");
    assert_non_null(fp);
    fprintf(fp, "PF\n256 1\n-1.0\n");
    for (int x = 0; x < 256; x++) {
        float v = (x + 0.5f) / 256.0f, px[3] = {v, v, v};
        fwrite(px, sizeof px, 1, fp);
    }
    fclose(fp);
    static const double Hs[] = {0.5, 3.0, -1.0};
    for (int i = 0; i < 3; i++) {
        const double H = Hs[i];
        /* the square [-1, 1]^2 at z = 0 with uvs: dp/du = (2, 0, 0), dp/dv = (0, 2, 0) */
        char text[1024];
        snprintf(text, sizeof text,
                 "mid 1.1\ndirectional_light { direction = [0 0 -1] irradiance = 3.14159265358979 }\n"
                 "directional_light { direction = [1 0 -1] irradiance = 3.14159265358979 }\n"
                 "polygons { geometry = { vertices = [[-1 -1 0] [1 -1 0] [1 1 0] [-1 1 0]] faces = [[0 1 2 3]]\n"
                 "                        uvs = [[0 0] [1 0] [1 1] [0 1]] }\n"
                 "  rendering = { diffuse = 1 bump = image(file(\"rt_bump_ramp.pfm\"), %.17g) } }\n",
                 H);
        tb_scene *s = tp_scene_text(text);
        tb_raytracer rt;
        rt_init(&rt, s, 1);
        /* dp'/du = (2, 0, H), dp'/dv = (0, 2, 0): n' = normalise(-H, 0, 2) */
        double len = sqrt(H * H + 4.0);
        double c1 = 2.0 / len;                               /* light from +z */
        double c2 = (H + 2.0) / (len * sqrt(2.0));           /* light from (-1, 0, 1) / sqrt 2 */
        /* irradiance pi on a plane facing each light; rho = 1: L = sum of cos */
        double want = fmax(0.0, c1) + fmax(0.0, c2);
        double flat = 1.0 + 1.0 / sqrt(2.0);
        for (int k = 0; k < 3; k++) {
            float x = -0.5f + 0.5f * (float)k;
            double got = radiance(&rt, (tb_vec3){x, 0.1f, 3.0f}, (tb_vec3){x, 0.1f, 0.0f}, 1).v[0];
            print_message("bump H = %4.1f at x = %4.1f: %.6f, analytic %.6f (flat %.6f)\n", H, x, got, want, flat);
            tb_assert_near(got, want, 2e-4);
        }
        tb_rt_release(&rt);
        tb_scene_free(s);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ggx_white_furnace),
        cmocka_unit_test(test_ggx_area_light_mis),
        cmocka_unit_test(test_models_under_point_light),
        cmocka_unit_test(test_grazing_checker_is_grey),
        cmocka_unit_test(test_noise_pattern_statistics),
        cmocka_unit_test(test_object_space_checker),
        cmocka_unit_test(test_bump_constant_slope),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
