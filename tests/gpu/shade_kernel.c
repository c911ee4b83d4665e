/* The shade kernel and the wavefront (host/gpu/render.h) against the CPU ray
 * tracer (tb_rt_radiance), ray by ray: a floor lit by a point light and a
 * quad emitter with a sphere casting shadows, seen by 1024 rays, once per
 * material or light feature (Lambert, Phong highlight + mirror, spot,
 * directional, smooth glass, spectral bands, a sphere emitter, IES tables,
 * GGX lobes with glossy rays, checker and noise patterns, noise bumps,
 * image textures), and the cases the kernel routes to the CPU path
 * (counted, with the reason, and equal to the CPU's values bit for bit).
 * Each ray's stream is seeded alike on both paths: the radiance must agree
 * within float tolerance and the stream must end in the same state (the
 * wavefront drew exactly the CPU path's numbers). Validation layer on; any
 * message fails. */
#include "gpu_test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "host/gpu/render.h"
#include "host/render/raytrace.h"
#include "host/render/scene.h"
#include "util/math/rng.h"

#define TB__N 1024

/* The scene: MAT on the floor, EXTRA appended (lights, objects). */
static tb_scene *tb__load(const char *mat, const char *extra, bool lamp, const char *dir)
{
    char text[4096];
    snprintf(text, sizeof text,
             "mid %s\n"
             "material \"m\" { %s }\n"
             "polygons \"floor\" { geometry = { vertices = [[-4 -4 0] [4 -4 0] [4 4 0] [-4 4 0]] faces = [[0 1 2 3]] }"
             " rendering = { material = \"m\" } }\n"
             "sphere \"blocker\" { transform = [scale(0.3) translate([0.5 0 1])] }\n"
             "%s%s",
             /* models, patterns and bump maps are MID 1.1 */
             strstr(mat, "model") || strstr(mat, "pattern") || strstr(mat, "bump") || strstr(extra, "model") ||
                     strstr(extra, "pattern") || strstr(extra, "bump")
                 ? "1.1"
                 : "1",
             mat,
             lamp ? "polygons \"lamp\" { geometry = { vertices = [[-0.5 -0.5 3] [-0.5 0.5 3] [0.5 0.5 3] [0.5 -0.5 3]]"
                    " faces = [[0 1 2 3]] } rendering = { diffuse = 0 emission = [10 8 6] } }\n"
                  : "",
             extra);
    return gpu_test_load(text, "shade.mid", dir);
}

/* Rays from (0, -6, 3) to a 32 x 32 grid of floor points. */
static void tb__rays(tb_ray *rays)
{
    for (int i = 0; i < TB__N; i++) {
        double x = -3.0 + 6.0 * ((i % 32) + 0.5) / 32.0, y = -3.0 + 6.0 * ((i / 32) + 0.5) / 32.0;
        tb_vec3 o = {0.0f, -6.0f, 3.0f}, p = {(float)x, (float)y, 0.0f};
        rays[i] = tb_ray_make(o, tb_vec3_normalize(tb_vec3_sub(p, o)), 0.0f, INFINITY);
    }
}

/* What a case expects of the run. */
typedef struct tb__want {
    const char *routed; /* floor hits are routed to the CPU, for this reason (NULL: shaded by the kernel) */
    bool no_secondary;  /* no mirror or refracted ray may occur */
    bool secondary;     /* mirror or refracted rays must occur */
    int channels;       /* scene channels */
    double tol;         /* relative difference beyond which a ray counts as differing (0: 1e-4) */
} tb__want;

/* Renders the 1024 rays on both paths and compares. */
static void tb__compare(gpu_test_env *e, tb_scene *s, const char *name, tb__want want)
{
    assert_int_equal(s->nchannels, want.channels);
    tb_rt_options opt = {.max_depth = 5, .light_samples = 4};
    tb_raytracer rt;
    assert_int_equal(tb_rt_init(&rt, s, &opt), TB_OK);
    tb_gpu_renderer *r;
    if (tb_gpu_renderer_create(e->dev, s, &opt, &r))
        fail_msg("%s: renderer: %s", name, tb_last_error());
    tb_ray *rays = malloc(TB__N * sizeof *rays);
    tb_rng *rg = malloc(TB__N * sizeof *rg), *rc = malloc(TB__N * sizeof *rc);
    float *lg = malloc((size_t)TB__N * (size_t)s->nchannels * sizeof *lg);
    assert_true(rays && rg && rc && lg);
    tb__rays(rays);
    for (int i = 0; i < TB__N; i++) {
        tb_rng_seed(&rg[i], (uint64_t)i, 7);
        rc[i] = rg[i];
    }
    if (tb_gpu_radiance(r, rays, rg, TB__N, lg))
        fail_msg("%s: tb_gpu_radiance: %s", name, tb_last_error());
    int bad = 0, same_rng = 0, routed_rays = 0;
    double worst = 0.0, sum = 0.0;
    for (int i = 0; i < TB__N; i++) {
        tb_channels lc = tb_rt_radiance(&rt, &rays[i], &rc[i]);
        double peak = 0.0, d = 0.0;
        for (int c = 0; c < s->nchannels; c++) {
            double a = lg[(size_t)i * (size_t)s->nchannels + (size_t)c], b = lc.v[c];
            peak = fmax(peak, fabs(b));
            d = fmax(d, fabs(a - b));
            sum += b;
        }
        double rel = d / (peak + 1e-6);
        worst = fmax(worst, rel);
        if (rel > (want.tol > 0.0 ? want.tol : 1e-4))
            bad++;
        same_rng += memcmp(&rg[i], &rc[i], sizeof rg[i]) == 0;
        /* a routed hit is the CPU path itself: equal bit for bit */
        tb_hit h;
        if (tb_scene_intersect(s, &rays[i], &h) &&
            tb_gpu_renderer_material_route(r, (int)(tb_scene_hit_material(s, &h) - s->materials))) {
            routed_rays++;
            for (int c = 0; c < s->nchannels; c++)
                assert_true(lg[(size_t)i * (size_t)s->nchannels + (size_t)c] == lc.v[c]);
        }
    }
    tb_gpu_render_stats gs;
    tb_gpu_renderer_stats(r, &gs);
    print_message("%-12s %4d rays: %d beyond %.0e relative (worst %.2g), %d streams equal; %llu kernel hits, "
                  "%llu routed, %llu rays, %llu shadow rays, mean %.4g\n",
                  name, TB__N, bad, want.tol > 0.0 ? want.tol : 1e-4, worst, same_rng,
                  (unsigned long long)gs.gpu_shaded, (unsigned long long)gs.cpu_shaded, (unsigned long long)gs.rays,
                  (unsigned long long)gs.shadow_rays, sum / TB__N / s->nchannels);
    /* Float against double: a ray may meet an edge or a shadow boundary on
     * one path only; at most 1 % of rays, every stream the same otherwise.
     * Behind glass the float refraction and the kernel's wider spawn offset
     * (2^-17 of the coordinates, docs/accuracy.md) move the floor point
     * seen by a few 1e-5: differences up to 1e-2 relative there. */
    assert_true(sum > 0.0);
    assert_true(bad <= TB__N / 100);
    assert_true(same_rng >= TB__N - TB__N / 100);
    if (want.routed) {
        assert_true(gs.cpu_shaded > 0 && routed_rays > TB__N / 2);
        assert_true(gs.routed_materials > 0);
        if (!strstr(gs.routed_reason, want.routed))
            fail_msg("%s: routed because \"%s\", expected \"%s\"", name, gs.routed_reason, want.routed);
    } else {
        assert_int_equal(gs.cpu_shaded, 0);
        assert_true(gs.gpu_shaded >= TB__N);
        assert_true(gs.shadow_rays > 0);
    }
    if (want.secondary)
        assert_true(gs.rays > TB__N);
    if (want.no_secondary)
        assert_int_equal(gs.rays, TB__N);
    tb_gpu_renderer_destroy(r);
    tb_rt_release(&rt);
    free(rays), free(rg), free(rc), free(lg);
    tb_scene_free(s);
}

static const char *tb__point = "point_light { position = [1 1 2] intensity = [5 4 3] }\n";

static void test_lambert(void **state)
{
    tb__compare(*state, tb__load("diffuse = [0.6 0.5 0.4]", tb__point, true, NULL), "lambert",
                (tb__want){.channels = 3});
}

static void test_phong_mirror(void **state)
{
    tb__compare(*state, tb__load("diffuse = 0.3 specular = [0.4 0.3 0.2] exponent = 30", tb__point, true, NULL),
                "phong+mirror", (tb__want){.channels = 3, .secondary = true});
}

static void test_blinn(void **state)
{
    tb__compare(*state,
                tb__load("diffuse = 0.3 specular = [0.4 0.3 0.2] exponent = 30 model = blinn", tb__point, true, NULL),
                "blinn+mirror", (tb__want){.channels = 3, .secondary = true});
}

/* model lambert ignores the specular colour: no highlight, no mirror ray */
static void test_lambert_model(void **state)
{
    tb__compare(*state, tb__load("diffuse = 0.5 specular = 0.5 model = lambert", tb__point, true, NULL),
                "model lamb.", (tb__want){.channels = 3, .no_secondary = true});
}

/* The GGX lobe: its value for the point light and the light samples (the
 * samples weighted against the glossy rays by the power heuristic), and the
 * glossy rays (4 at the camera ray's hit, one deeper), whose emission found
 * on the lamp is weighted against the light samples; plastic, a rough and a
 * nearly smooth metal (no diffuse part: the light samples are taken for the
 * lobe alone), spectral bands, and a GGX sphere whose glossy rays find the
 * floor and the lamp. */
static void test_ggx(void **state)
{
    tb__compare(*state, tb__load("diffuse = 0.2 specular = 0.6 model = ggx roughness = 0.3", tb__point, true, NULL),
                "ggx", (tb__want){.channels = 3, .secondary = true});
    tb__compare(*state,
                tb__load("diffuse = 0 specular = [1 0.78 0.34] model = ggx roughness = 0.45", tb__point, true, NULL),
                "ggx metal", (tb__want){.channels = 3, .secondary = true});
    tb__compare(*state,
                tb__load("diffuse = 0 specular = [0.9 0.9 0.8] model = ggx roughness = 0.02", tb__point, true, NULL),
                "ggx mirror", (tb__want){.channels = 3, .secondary = true});
    tb_scene *sp = tb__load("diffuse = 0.3 specular = spectrum([400 550 700], [0.3 0.9 0.5]) model = ggx "
                            "roughness = 0.2",
                            "point_light { position = [1 1 2] intensity = spectrum([400 700], [1 5]) }\n", true, NULL);
    assert_true(sp->spectral);
    tb__compare(*state, sp, "ggx spectral", (tb__want){.channels = sp->nchannels, .secondary = true});
    tb__compare(*state,
                tb__load("diffuse = 0.5",
                         "material \"gold\" { diffuse = 0 specular = [1 0.78 0.34] model = ggx roughness = 0.15 }\n"
                         "sphere \"ball\" { transform = [scale(0.6) translate([-0.8 -1.5 0.6])] "
                         "rendering = { material = \"gold\" } }\n",
                         true, NULL),
                "ggx sphere", (tb__want){.channels = 3, .secondary = true});
}

/* Procedural patterns and noise bump maps: checker and fBm noise for the
 * diffuse and the specular colour, over (u, v) and in object space, and
 * noise bumps under Lambert, Phong and GGX (the rays are not camera rays
 * of a film: no footprint, point-sampled as tb_rt_radiance does). */
static void test_patterns(void **state)
{
    static const struct {
        const char *name, *on, *mat; /* on: "sphere" for a sphere in front of a Lambert floor */
        double tol;
    } cases[] = {
        {"checker uv", NULL, "diffuse = 1 diffuse_pattern = checker([3 2], 0.2, [0.9 0.7 0.5])", 0},
        /* object space on a sphere: the floor's z = 0 is a cell boundary,
         * where float and double may disagree about the hit's side */
        {"checker obj", "sphere", "diffuse = 1 diffuse_pattern = checker(1.7, [0.1 0.2 0.5], 0.8, object)", 0},
        {"noise uv", NULL, "diffuse = 1 diffuse_pattern = noise(6, 5, [0.35 0.3 0.28], [0.95 0.93 0.9])", 0},
        {"noise obj", NULL, "diffuse = 1 diffuse_pattern = noise(2.5, 6, 0.1, [0.9 0.8 0.7], object)", 0},
        {"spec checker", NULL,
         "diffuse = 0.3 specular = 1 exponent = 40 specular_pattern = checker(4, 0.1, [0.5 0.4 0.3])", 0},
        {"ggx noise", NULL,
         "diffuse = 0.1 specular = 1 model = ggx roughness = 0.25 "
         "specular_pattern = noise(3, 4, [0.9 0.6 0.3], 0.2) diffuse_pattern = checker(2, 0.1, 0.6)",
         0},
        {"bump uv", NULL, "diffuse = 0.7 bump = noise(3, 2, 0.05)", 0},
        {"bump obj", NULL, "diffuse = 0.6 specular = 0.3 exponent = 20 bump = noise(1.5, 4, 0.08, object)", 0},
        {"bump ggx", NULL,
         "diffuse = 0 specular = [0.95 0.64 0.54] model = ggx roughness = 0.1 bump = noise(4, 3, 0.02)", 0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char extra[1024];
        snprintf(extra, sizeof extra,
                 "%smaterial \"p\" { %s }\n"
                 "sphere \"ball\" { transform = [scale(1.2) translate([-0.6 -1.2 1.2])] rendering = { material = \"p\" "
                 "} }\n",
                 tb__point, cases[i].mat);
        tb__compare(*state,
                    cases[i].on ? tb__load("diffuse = 0.5", extra, true, NULL)
                                : tb__load(cases[i].mat, tb__point, true, NULL),
                    cases[i].name, (tb__want){.channels = 3, .tol = cases[i].tol});
    }
}

/* A colour pattern that is black in places decides per hit whether the
 * point takes light samples (the CPU draws them only for a non-black
 * diffuse colour): routed to the CPU path, counted, with the reason. */
static void test_routed_models(void **state)
{
    tb__compare(*state, tb__load("diffuse = 1 diffuse_pattern = checker(1, 0, 0.8)", tb__point, true, NULL),
                "black check", (tb__want){.channels = 3, .routed = "black in some places"});
}

/* IES distributions (tests/render/data: every symmetry) on a point light
 * and a spot light: the kernel's float table lookup against tb_ies_normalized. */
static void test_ies(void **state)
{
    static const char *const files[] = {"full", "quadrant", "bilateral", "bilateral90", "lambertian"};
    for (int i = 0; i < 5; i++) {
        char extra[1024], name[32];
        snprintf(extra, sizeof extra,
                 "point_light { position = [0.3 0.2 2] intensity = [40 30 20] ies = file(\"%s/render/data/%s.ies\") }\n"
                 "spot_light { position = [-1 -1 2.5] direction = [0.3 0.5 -1] cone_angle = 50 cone_delta = 10 "
                 "intensity = 30 ies = file(\"%s/render/data/%s.ies\") }\n",
                 TB_TEST_SOURCE_DIR, files[i], TB_TEST_SOURCE_DIR, files[i]);
        snprintf(name, sizeof name, "ies %s", files[i]);
        tb__compare(*state, tb__load("diffuse = 0.6 specular = 0.2 exponent = 10", extra, false, NULL), name,
                    (tb__want){.channels = 3, .secondary = true});
    }
}

static void test_spot(void **state)
{
    tb__compare(*state,
                tb__load("diffuse = 0.7",
                         "spot_light { position = [0 0 2.5] direction = [0.2 0 -1] cone_angle = 40 cone_delta = 15 "
                         "intensity = 20 }\n",
                         false, NULL),
                "spot", (tb__want){.channels = 3});
}

static void test_directional(void **state)
{
    tb__compare(*state,
                tb__load("diffuse = [0.2 0.9 0.5]", "directional_light { direction = [0.3 0.2 -1] irradiance = 2 }\n",
                         true, NULL),
                "directional", (tb__want){.channels = 3});
}

static void test_glass(void **state)
{
    tb__compare(*state,
                tb__load("diffuse = 0.6",
                         "sphere \"glass\" { transform = [scale(0.9) translate([-0.8 -1.5 0.9])] rendering = { "
                         "diffuse = 0 transmission = [1 0.9 0.8] ior = 1.5 } }\n",
                         true, NULL),
                "glass", (tb__want){.channels = 3, .secondary = true, .tol = 1e-2});
}

static void test_spectral(void **state)
{
    tb_scene *s = tb__load("diffuse = spectrum([400 550 700], [0.2 0.8 0.4])",
                           "point_light { position = [1 1 2] intensity = spectrum([400 700], [1 5]) }\n", true, NULL);
    assert_true(s->spectral);
    tb__compare(*state, s, "spectral", (tb__want){.channels = s->nchannels});
}

static void test_sphere_emitter(void **state)
{
    tb__compare(*state,
                tb__load("diffuse = 0.8",
                         "sphere \"bulb\" { transform = [scale(0.25) translate([-1 1 1.5])] rendering = { diffuse = 0 "
                         "emission = [30 20 10] } }\n",
                         false, NULL),
                "sphere lamp", (tb__want){.channels = 3});
}

/* Writes a w x h PFM texture (bottom-to-top rows) of RGB pixels px into
 * TB_TEST_TMPDIR; returns the directory. */
static const char *tb__texture(const char *name, int w, int h, const float *px)
{
    const char *dir = getenv("TB_TEST_TMPDIR");
    if (!dir)
        dir = "/tmp";
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *fp = fopen(path, "wb");
    assert_non_null(fp);
    fprintf(fp, "PF\n%d %d\n-1.0\n", w, h);
    assert_int_equal(fwrite(px, sizeof(float) * 3 * (size_t)w * (size_t)h, 1, fp), 1);
    fclose(fp);
    return dir;
}

/* Image textures on the diffuse, specular and emission colours (point
 * sampled: these rays have no footprint, so every filter is the bilinear
 * lookup of level 0; the renderer's footprints and filters are checked by
 * gpu_shade_cli). A texture with a black texel where the colour is not
 * black elsewhere, and a texture in a spectral scene, are routed. */
static void test_textures(void **state)
{
    float px[12] = {0.9f, 0.2f, 0.2f, 0.2f, 0.9f, 0.2f, 0.2f, 0.2f, 0.9f, 0.8f, 0.8f, 0.8f};
    const char *dir = tb__texture("shade_kernel_tex.pfm", 2, 2, px);
    float big[3 * 16 * 8];
    for (int i = 0; i < 3 * 16 * 8; i++)
        big[i] = 0.1f + 0.8f * (float)((i * 37) % 101) / 101.0f;
    tb__texture("shade_kernel_tex16.pfm", 16, 8, big);
    tb__compare(*state, tb__load("diffuse = 1 diffuse_texture = file(\"shade_kernel_tex.pfm\")", tb__point, true, dir),
                "texture", (tb__want){.channels = 3});
    tb__compare(
        *state,
        tb__load("diffuse = 0.5 specular = 0.4 exponent = 30 diffuse_texture = file(\"shade_kernel_tex16.pfm\") "
                 "specular_texture = file(\"shade_kernel_tex.pfm\")",
                 tb__point, true, dir),
        "tex spec", (tb__want){.channels = 3, .secondary = true});
    tb__compare(*state,
                tb__load("diffuse = [0.6 0.5 0.4]",
                         "point_light { position = [1 1 2] intensity = [5 4 3] }\n"
                         "polygons \"panel\" { geometry = { vertices = [[-3 1 0] [-1 1 0] [-1 1 2] [-3 1 2]] "
                         "faces = [[0 1 2 3]] uvs = [[0 0] [1 0] [1 1] [0 1]] } rendering = { diffuse = 0 "
                         "emission = [2 2 2] emission_texture = file(\"shade_kernel_tex16.pfm\") } }\n",
                         true, dir),
                "tex emitter", (tb__want){.channels = 3});
    px[3] = px[4] = px[5] = 0.0f; /* a black texel */
    tb__texture("shade_kernel_black.pfm", 2, 2, px);
    tb__compare(*state,
                tb__load("diffuse = 1 diffuse_texture = file(\"shade_kernel_black.pfm\")", tb__point, true, dir),
                "black texel", (tb__want){.channels = 3, .routed = "black in some places"});
    tb_scene *sp = tb__load("diffuse = spectrum([400 700], [0.5 0.7]) diffuse_texture = file(\"shade_kernel_tex.pfm\")",
                            tb__point, true, dir);
    assert_true(sp->spectral);
    tb__compare(*state, sp, "tex spectral", (tb__want){.channels = sp->nchannels, .routed = "spectral"});
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lambert),        cmocka_unit_test(test_phong_mirror),  cmocka_unit_test(test_spot),
        cmocka_unit_test(test_directional),    cmocka_unit_test(test_glass),         cmocka_unit_test(test_spectral),
        cmocka_unit_test(test_sphere_emitter), cmocka_unit_test(test_textures),      cmocka_unit_test(test_blinn),
        cmocka_unit_test(test_lambert_model),  cmocka_unit_test(test_routed_models), cmocka_unit_test(test_ggx),
        cmocka_unit_test(test_patterns),       cmocka_unit_test(test_ies),
    };
    return cmocka_run_group_tests(tests, gpu_test_setup, gpu_test_teardown);
}
