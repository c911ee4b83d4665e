#define _XOPEN_SOURCE 700 /* realpath */
/* Scene assembly (host/render/scene.h): objects in MID order, the
 * deduplicated material table and the colour representation the scene
 * needs, lights, emissive objects with their areas and emitters, the camera,
 * located error messages and the load statistics. Expected values come from
 * the MID text itself (read back with the reader), from util/color, or from
 * geometry worked out here (areas by formula or by quadrature). */
#include "tb_test.h"

#include <limits.h>
#include <stdlib.h>
#include <string.h>

#include "host/object/intersect.h"
#include "host/render/scene.h"
#include "host/mid/mid_reader.h"
#include "util/color/bands.h"
#include "util/math/float.h"
#include "util/stats/stats.h"

#define CORNELL TB_SOURCE_DIR "/scenes/cornell-box.mid"
#define CORNELL_RGB TB_SOURCE_DIR "/scenes/cornell-box-rgb.mid"

/* Loads MID text; st receives the status (the scene is NULL on failure). */
static tb_scene *load_text(const char *text, const tb_scene_options *opt, tb_status *st)
{
    FILE *fp = fmemopen((void *)text, strlen(text), "r");
    assert_non_null(fp);
    tb_scene *s = (tb_scene *)0x1;
    *st = tb_scene_load_stream(fp, "t.mid", TB_SOURCE_DIR "/scenes", opt, &s);
    fclose(fp);
    if (*st)
        assert_null(s);
    return s;
}

static tb_scene *load_ok(const char *text, const tb_scene_options *opt)
{
    tb_status st;
    tb_scene *s = load_text(text, opt, &st);
    if (st)
        fail_msg("%s", tb_last_error());
    return s;
}

static tb_hit trace(const tb_scene *s, tb_vec3 o, tb_vec3 d)
{
    tb_ray r = tb_ray_make(o, d, 0.0f, INFINITY);
    tb_hit h;
    if (!tb_scene_intersect(s, &r, &h))
        fail_msg("ray (%g %g %g) -> (%g %g %g) missed", o.x, o.y, o.z, d.x, d.y, d.z);
    return h;
}

/* ------------------------------------------------------------------ Cornell box */

static void test_cornell_spectral(void **state)
{
    (void)state;
    tb_scene *s;
    if (tb_scene_load(CORNELL, NULL, &s))
        fail_msg("%s", tb_last_error());
    /* 8 polygons objects in file order: floor, ceiling, back, right, left, light, short, tall. */
    assert_int_equal(s->nobjects, 8);
    assert_int_equal(s->stats.objects_by_kind[TB_PRIM_POLYGONS], 8);
    for (uint32_t i = 0; i < 8; i++)
        assert_int_equal(s->objects[i]->index, i);
    assert_string_equal(s->objects[0]->name, "floor");
    assert_string_equal(s->objects[5]->name, "light");
    assert_string_equal(s->objects[7]->name, "tall block");
    /* 6 quads and two blocks of 5 quads: 32 triangles, one reference each. */
    assert_int_equal(s->stats.triangles, 32);
    assert_int_equal(s->nprims, 32);
    /* Spectral data: spectral with util/color's default bands. */
    assert_true(s->spectral);
    assert_int_equal(s->nchannels, 31);
    assert_int_equal(s->bands.n, 31);
    tb_assert_near(s->bands.lambda[0], 400.0, 0.0);
    tb_assert_near(s->bands.lambda[30], 700.0, 0.0);
    /* white, green, red, light: four materials shared by the objects. */
    assert_int_equal(s->nmaterials, 4);
    int white = s->objects[0]->material;
    for (int i = 1; i < 8; i++) {
        bool is_white = i == 1 || i == 2 || i == 6 || i == 7;
        assert_int_equal(s->objects[i]->material == white, is_white);
    }
    assert_true(s->objects[3]->material != s->objects[4]->material);
    assert_true(s->objects[5]->material != s->objects[3]->material && s->objects[5]->material != s->objects[4]->material);
    /* The light's emission: samples 0, 25.13274, 49.00885, 57.8053 at 400,
     * 500, 600, 700 nm, linear between; band k is at 400 + 10 k nm. */
    const tb_material *lm = &s->materials[s->objects[5]->material];
    assert_true(lm->emits);
    assert_int_equal(lm->emission.n, 31);
    tb_assert_near(lm->emission.v[0], 0.0, 1e-6);
    tb_assert_near(lm->emission.v[5], 25.13274 / 2, 1e-4);
    tb_assert_near(lm->emission.v[10], 25.13274, 1e-4);
    tb_assert_near(lm->emission.v[23], 49.00885 + 0.3 * (57.8053 - 49.00885), 1e-4);
    tb_assert_near(lm->emission.v[30], 57.8053, 1e-4);
    {
        /* The grey 0.78 diffuse: Smits' (nearly flat) white spectrum. */
        double rgb[3] = {0.78f, 0.78f, 0.78f}, want[TB_BANDS_MAX];
        assert_int_equal(tb_bands_from_rgb_reflectance(&s->bands, rgb, want), TB_OK);
        for (int k = 0; k < 31; k++) {
            tb_assert_near(lm->diffuse.v[k], want[k], 1e-6);
            tb_assert_near(lm->diffuse.v[k], 0.78, 1e-2);
        }
    }
    assert_false(s->materials[white].emits);
    /* The white reflectance: the MID spectrum resampled onto the bands (util/color). */
    {
        tb_mid_reader *r;
        assert_int_equal(tb_mid_reader_open(&r, CORNELL), TB_OK);
        tb_mid_item it;
        while (!tb_mid_reader_next(r, &it) && it.type != TB_MID_ITEM_END) {
        }
        const tb_mid_material *mw = tb_mid_reader_material(r, "white");
        assert_non_null(mw);
        assert_int_equal(mw->diffuse.type, TB_MID_COLOR_SPECTRUM);
        double nm[128], val[128], want[TB_BANDS_MAX];
        for (int i = 0; i < mw->diffuse.nsamples; i++) {
            nm[i] = mw->diffuse.nm[i];
            val[i] = mw->diffuse.values[i];
        }
        tb_spectrum sp;
        assert_int_equal(tb_spectrum_init(&sp, mw->diffuse.nsamples, nm, val), TB_OK);
        assert_int_equal(tb_bands_from_spectrum(&s->bands, &sp, want), TB_OK);
        for (int k = 0; k < 31; k++)
            tb_assert_near(s->materials[white].diffuse.v[k], want[k], 1e-6);
        tb_spectrum_release(&sp);
        tb_mid_reader_close(r);
    }
    /* The light is the one emissive object: 130 mm x 105 mm, two triangles
     * facing down into the box, radiance M / pi. */
    assert_int_equal(s->nemissive, 1);
    assert_int_equal(s->emissive[0].object, 5);
    assert_int_equal(s->emissive[0].material, s->objects[5]->material);
    tb_assert_near(s->emissive[0].area, 130.0 * 105.0, 1e-9 * 13650.0);
    assert_int_equal(s->emissive[0].nemitters, 2);
    assert_int_equal(s->nemitters, 2);
    double sum = 0.0;
    for (int i = 0; i < 2; i++) {
        const tb_emitter *e = &s->emitters[i];
        assert_int_equal(e->kind, TB_EMITTER_TRIANGLE);
        assert_int_equal(e->object, 5);
        sum += tb_emitter_area(e);
        tb_vec3 n = tb_vec3_cross(tb_vec3_sub(e->v[1], e->v[0]), tb_vec3_sub(e->v[2], e->v[0]));
        assert_true(n.y < 0.0f && n.x == 0.0f && n.z == 0.0f);
        tb_assert_near(e->radiance.v[10], 25.13274 / TB_PI, 1e-4);
    }
    tb_assert_near(sum, 13650.0, 1e-2);
    /* No light items; the camera of the file. */
    assert_int_equal(s->nlights, 0);
    assert_true(s->has_camera);
    tb_assert_near(s->camera.fov_y, 2.0 * atan(12.5 / 35.0) * 180.0 / TB_PI, 1e-12);
    /* Bounds: the box is 556 x 548.8 x 559.2 mm. */
    tb_assert_near(s->bounds.lo.x, 0.0, 1e-9);
    tb_assert_near(s->bounds.lo.y, 0.0, 1e-9);
    tb_assert_near(s->bounds.hi.x, 556.0, 1e-3);
    tb_assert_near(s->bounds.hi.y, 548.8, 1e-3);
    tb_assert_near(s->bounds.hi.z, 559.2, 1e-3);
    /* Materials through hits: the floor from above is white, the light from below emits. */
    tb_hit h = trace(s, (tb_vec3){100, 300, 100}, (tb_vec3){0, -1, 0});
    assert_int_equal(h.object, 0);
    assert_ptr_equal(tb_scene_hit_material(s, &h), &s->materials[white]);
    h = trace(s, (tb_vec3){278, 300, 280}, (tb_vec3){0, 1, 0});
    assert_int_equal(h.object, 5);
    assert_true(tb_scene_hit_material(s, &h)->emits);
    uint32_t local = 99;
    assert_ptr_equal(tb_scene_hit_leaf(s, &h, &local), s->objects[5]);
    assert_int_equal(local, h.face);
    tb_hit bogus = h;
    bogus.object = 8;
    assert_null(tb_scene_hit_material(s, &bogus));
    tb_scene_free(s);
}

/* The RGB Cornell box stays RGB: the material table holds the file's values. */
static void test_cornell_rgb(void **state)
{
    (void)state;
    tb_scene *s;
    if (tb_scene_load(CORNELL_RGB, NULL, &s))
        fail_msg("%s", tb_last_error());
    assert_false(s->spectral);
    assert_int_equal(s->nchannels, 3);
    assert_int_equal(s->nmaterials, 4);
    tb_mid_reader *r;
    assert_int_equal(tb_mid_reader_open(&r, CORNELL_RGB), TB_OK);
    tb_mid_item it;
    while (!tb_mid_reader_next(r, &it) && it.type != TB_MID_ITEM_END) {
    }
    const char *names[4] = {"white", "green", "red", "light"};
    int objs[4] = {0, 3, 4, 5};
    for (int k = 0; k < 4; k++) {
        const tb_mid_material *mm = tb_mid_reader_material(r, names[k]);
        assert_non_null(mm);
        const tb_material *m = &s->materials[s->objects[objs[k]]->material];
        assert_int_equal(m->diffuse.n, 3);
        for (int c = 0; c < 3; c++) {
            assert_true(m->diffuse.v[c] == mm->diffuse.rgb[c]);
            assert_true(m->emission.v[c] == mm->emission.rgb[c]);
        }
        assert_string_equal(m->name, names[k]);
    }
    /* Forced spectral: RGB reflectances become Smits spectra on the bands. */
    tb_scene_options opt = {0};
    opt.color = TB_SCENE_COLOR_SPECTRAL;
    tb_scene *sp;
    if (tb_scene_load(CORNELL_RGB, &opt, &sp))
        fail_msg("%s", tb_last_error());
    assert_true(sp->spectral);
    assert_int_equal(sp->nchannels, 31);
    const tb_mid_material *mw = tb_mid_reader_material(r, "white");
    double rgb[3] = {mw->diffuse.rgb[0], mw->diffuse.rgb[1], mw->diffuse.rgb[2]}, want[TB_BANDS_MAX];
    assert_int_equal(tb_bands_from_rgb_reflectance(&sp->bands, rgb, want), TB_OK);
    for (int k = 0; k < 31; k++)
        tb_assert_near(sp->materials[sp->objects[0]->material].diffuse.v[k], want[k], 1e-6);
    tb_scene_free(sp);
    tb_mid_reader_close(r);
    tb_scene_free(s);

    /* Forced RGB on the spectral box: 3 channels, the red wall reddest. */
    opt.color = TB_SCENE_COLOR_RGB;
    if (tb_scene_load(CORNELL, &opt, &s))
        fail_msg("%s", tb_last_error());
    assert_false(s->spectral);
    assert_int_equal(s->nchannels, 3);
    const tb_material *red = &s->materials[s->objects[4]->material];
    assert_true(red->diffuse.v[0] > 2 * red->diffuse.v[1] && red->diffuse.v[0] > 2 * red->diffuse.v[2]);
    assert_true(s->materials[s->objects[5]->material].emission.v[1] > 0.0f);
    tb_scene_free(s);
}

/* ------------------------------------------------------------------ materials */

static void test_material_dedup(void **state)
{
    (void)state;
    const char *text =
        "mid 1\n"
        "material \"a\" { diffuse = [0.2 0.3 0.4] }\n"
        "material \"b\" { diffuse = [0.2 0.3 0.4] }\n"
        "material \"unused\" { diffuse = 0.9 }\n"
        "sphere { rendering = { material = \"a\" } }\n"                         /* 0 */
        "sphere { rendering = { material = \"b\" } }\n"                         /* 1: equal to a */
        "sphere { rendering = { diffuse = [0.2 0.3 0.4] } }\n"                  /* 2: equal to a */
        "sphere { rendering = { material = \"a\" specular = 0.5 } }\n"          /* 3: differs */
        "union { rendering = { diffuse = 0.1 }\n"                               /* 4: 0.1 only inherited... */
        "  sphere { rendering = { diffuse = 0.7 } }\n"
        "  cube { rendering = { diffuse = 0.7 } } }\n"                          /* ...by no one */
        "sphere {}\n"                                                           /* 5: the default */
        "sphere { rendering = { diffuse_texture = file(\"data/cornell-box-reflectance.csv\") } }\n" /* 6 */
        "sphere { rendering = { diffuse_texture = file(\"data/cornell-box-reflectance.csv\") } }\n" /* 7 = 6 */
        "sphere { rendering = { diffuse = 0.5 exponent = 20 } }\n";            /* 8: the default written out */
    tb_scene_options opt = {0};
    opt.no_accel = true;
    tb_scene *s = load_ok(text, &opt);
    assert_null(s->accel);
    assert_int_equal(s->nobjects, 9);
    assert_false(s->spectral);
    /* {a}, {a + specular}, {0.7}, {default}, {default + texture}: five; 0.1 and "unused" dropped. */
    assert_int_equal(s->nmaterials, 5);
    int a = s->objects[0]->material;
    assert_int_equal(s->objects[1]->material, a);
    assert_int_equal(s->objects[2]->material, a);
    assert_true(s->objects[3]->material != a);
    const tb_object *u = s->objects[4];
    assert_int_equal(u->material, -1); /* the union's own material is used by no primitive */
    assert_int_equal(u->children[0].material, u->children[1].material);
    assert_int_equal(s->objects[8]->material, s->objects[5]->material);
    assert_int_equal(s->objects[7]->material, s->objects[6]->material);
    assert_true(s->objects[6]->material != s->objects[5]->material);
    for (int i = 0; i < s->nmaterials; i++)
        assert_true(s->materials[i].diffuse.v[0] != 0.1f && s->materials[i].diffuse.v[0] != 0.9f);
    const tb_material *ma = &s->materials[a];
    assert_true(ma->diffuse.v[0] == 0.2f && ma->diffuse.v[1] == 0.3f && ma->diffuse.v[2] == 0.4f);
    assert_string_equal(ma->name, "a");
    assert_true(s->materials[s->objects[3]->material].specular.v[2] == 0.5f);
    const tb_material *tex = &s->materials[s->objects[6]->material];
    assert_non_null(tex->diffuse_texture);
    assert_non_null(strstr(tex->diffuse_texture, "scenes/data/cornell-box-reflectance.csv"));
    assert_null(tex->specular_texture);
    assert_null(s->materials[a].diffuse_texture);
    /* No accel: rays miss. */
    tb_ray r = tb_ray_make((tb_vec3){0, 0, 5}, (tb_vec3){0, 0, -1}, 0, INFINITY);
    tb_hit h;
    assert_false(tb_scene_intersect(s, &r, &h));
    tb_scene_free(s);
}

/* Patterns are kept out of line: a material without one points to the
 * scene's one pattern of kind NONE (zero colours of the scene's channels),
 * a material with one to its own, converted like the colours. */
static void test_material_patterns(void **state)
{
    (void)state;
    const char *text = "mid 1.1\n"
                       "sphere { rendering = { diffuse = 0.5 } }\n"
                       "sphere { rendering = { diffuse = 1 diffuse_pattern = checker([3 2], 0.2, [0.9 0.7 0.5]) } }\n"
                       "sphere { rendering = { diffuse = 0.3 specular = 1 exponent = 40 "
                       "specular_pattern = noise(3, 4, [0.9 0.6 0.3], 0.2) } }\n"
                       "sphere { rendering = { diffuse = 0.7 } }\n";
    tb_scene_options opt = {0};
    opt.no_accel = true;
    tb_scene *s = load_ok(text, &opt);
    assert_int_equal(s->nmaterials, 4);
    const tb_material *plain = &s->materials[s->objects[0]->material];
    const tb_material *check = &s->materials[s->objects[1]->material];
    const tb_material *noise = &s->materials[s->objects[2]->material];
    const tb_material *other = &s->materials[s->objects[3]->material];
    const tb_material_pattern *none = plain->diffuse_pattern;
    assert_non_null(none);
    assert_int_equal(none->kind, TB_MID_PATTERN_NONE);
    assert_int_equal(none->a.n, s->nchannels);
    for (int c = 0; c < TB_CHANNELS_MAX; c++)
        assert_true(none->a.v[c] == 0.0f && none->b.v[c] == 0.0f);
    /* Shared by every material without a pattern, in every slot. */
    assert_ptr_equal(plain->specular_pattern, none);
    assert_ptr_equal(plain->bump, none);
    assert_ptr_equal(other->diffuse_pattern, none);
    assert_ptr_equal(check->specular_pattern, none);
    assert_ptr_equal(noise->diffuse_pattern, none);
    assert_ptr_equal(noise->bump, none);
    assert_int_equal(check->diffuse_pattern->kind, TB_MID_PATTERN_CHECKER);
    assert_true(check->diffuse_pattern->scale == 3.0f && check->diffuse_pattern->scale_v == 2.0f);
    assert_true(check->diffuse_pattern->a.v[0] == 0.2f && check->diffuse_pattern->a.v[2] == 0.2f);
    assert_true(check->diffuse_pattern->b.v[0] == 0.9f && check->diffuse_pattern->b.v[2] == 0.5f);
    assert_int_equal(noise->specular_pattern->kind, TB_MID_PATTERN_NOISE);
    assert_int_equal(noise->specular_pattern->octaves, 4);
    assert_true(noise->specular_pattern->a.v[1] == 0.6f && noise->specular_pattern->b.v[1] == 0.2f);
    assert_true(noise->specular_pattern != check->diffuse_pattern);
    /* The accounting counts the table and the three patterns (NONE, checker, noise). */
    tb_scene_memory_use mu;
    tb_scene_memory(s, &mu);
    assert_int_equal(mu.materials, 4 * sizeof(tb_material) + 3 * sizeof(tb_material_pattern) +
                                       2 * TB_SCENE_MALLOC_OVERHEAD);
    tb_scene_free(s);
}

/* ------------------------------------------------------------------ lights */

static void test_lights(void **state)
{
    (void)state;
    const char *text = "mid 1\n"
                       "point_light { transform = [translate([1 2 3])] position = [0 0 1] intensity = 5 }\n"
                       "spot_light { position = [0 0 4] direction = [0 0 -2] intensity = [1 2 3] cone_angle = 20 cone_delta = 5 }\n"
                       "directional_light { direction = [1 0 -1] irradiance = spectrum([400 700], [1 3]) }\n"
                       "sphere { rendering = { diffuse = [0.2 0.3 0.4] } }\n";
    tb_scene *s = load_ok(text, NULL);
    assert_int_equal(s->nlights, 3);
    /* A spectral light makes the whole scene spectral. */
    assert_true(s->spectral);
    assert_int_equal(s->nchannels, 31);
    assert_int_equal(s->lights[0].kind, TB_LIGHT_POINT);
    assert_true(s->lights[0].position.x == 1.0f && s->lights[0].position.y == 2.0f && s->lights[0].position.z == 4.0f);
    assert_int_equal(s->lights[0].intensity.n, 31);
    /* Grey RGB emission 5 is the D65-shaped spectrum of luminance Y = 5
     * (docs/color.md); the bands cover 400-700 nm, nearly all of Y. */
    {
        double v[TB_BANDS_MAX], xyz[3];
        for (int k = 0; k < 31; k++)
            v[k] = s->lights[0].intensity.v[k];
        tb_bands_to_xyz(&s->bands, v, xyz);
        tb_assert_near(xyz[1], 5.0, 0.05);
        assert_true(s->lights[0].intensity.v[0] != s->lights[0].intensity.v[30]); /* not flat: D65 */
    }
    assert_int_equal(s->lights[1].kind, TB_LIGHT_SPOT);
    tb_assert_near(s->lights[1].axis.z, -1.0, 1e-7);
    tb_assert_near(s->lights[1].cos_total, cos(20.0 * TB_PI / 180.0), 1e-12);
    assert_int_equal(s->lights[2].kind, TB_LIGHT_DIRECTIONAL);
    tb_assert_near(s->lights[2].axis.x, sqrt(0.5), 1e-7);
    tb_assert_near(s->lights[2].intensity.v[0], 1.0, 1e-6);
    tb_assert_near(s->lights[2].intensity.v[15], 2.0, 1e-6);
    tb_assert_near(s->lights[2].intensity.v[30], 3.0, 1e-6);
    /* The RGB reflectance is upsampled (Smits) onto the same bands. */
    double rgb[3] = {0.2f, 0.3f, 0.4f}, want[TB_BANDS_MAX];
    assert_int_equal(tb_bands_from_rgb_reflectance(&s->bands, rgb, want), TB_OK);
    for (int k = 0; k < 31; k++)
        tb_assert_near(s->materials[0].diffuse.v[k], want[k], 1e-6);
    assert_int_equal(s->nemissive, 0);
    assert_false(s->has_camera);
    /* MID's default camera. */
    assert_int_equal(s->camera.width, 512);
    tb_assert_near(s->camera.fov_y, 45.0, 1e-12);
    tb_scene_free(s);
}

/* ------------------------------------------------------------------ emissive objects */

/* Area of the ellipsoid with semi-axes a, b, c by quadrature: midpoint rule
 * in theta, trapezoid (spectrally accurate for periodic functions) in phi. */
static double ellipsoid_area(double a, double b, double c)
{
    const int nt = 1000, np = 1000;
    double sum = 0.0;
    for (int i = 0; i < nt; i++) {
        double t = (i + 0.5) * TB_PI / nt, st = sin(t), ct = cos(t);
        for (int j = 0; j < np; j++) {
            double p = j * 2.0 * TB_PI / np, sp = sin(p), cp = cos(p);
            tb_dvec3 dt = {a * ct * cp, b * ct * sp, -c * st};
            tb_dvec3 dp = {-a * st * sp, b * st * cp, 0.0};
            sum += tb_dvec3_length(tb_dvec3_cross(dt, dp));
        }
    }
    return sum * (TB_PI / nt) * (2.0 * TB_PI / np);
}

static void test_emissive(void **state)
{
    (void)state;
    const char *text =
        "mid 1\n"
        "sphere { transform = [scale(2) rotate([1 1 0], 30) translate([1 2 3])] rendering = { emission = 1 } }\n" /* 0 */
        "sphere { transform = [scale([1 2 3]) translate([10 0 0])] rendering = { emission = 1 } }\n"             /* 1 */
        "cube { transform = [scale([1 2 3]) rotate([0 0 1], 17) translate([20 0 0])] rendering = { emission = 1 } }\n" /* 2 */
        "torus { geometry = { major = 2 minor = 0.5 } transform = [translate([30 0 0])] rendering = { emission = 1 } }\n" /* 3 */
        "cylinder { transform = [translate([40 0 0])] rendering = { emission = 1 } }\n"                            /* 4 */
        "cone { transform = [translate([50 0 0])] rendering = { emission = 1 } }\n"                                /* 5 */
        "difference { transform = [translate([60 0 0])] rendering = { emission = 1 } cube {} sphere { transform = [scale(0.5)] } }\n" /* 6 */
        "polygons { transform = [scale([-1 1 1]) translate([0 0 100])]\n"                                          /* 7 */
        "  geometry = { vertices = [[0 0 0] [1 0 0] [1 1 0] [0 1 0]] faces = [[0 1 2 3]] }\n"
        "  rendering = { emission = [1 2 3] } }\n"
        "sphere { transform = [translate([70 0 0])] }\n"                                                           /* 8 */
        "union { transform = [translate([80 0 0])] sphere {} sphere { transform = [translate([0 0 1])] rendering = { emission = 2 } } }\n"; /* 9 */
    tb_scene *s = load_ok(text, NULL);
    assert_false(s->spectral);
    assert_int_equal(s->nemissive, 9);
    double want[9] = {
        16.0 * TB_PI,                      /* sphere of radius 2 */
        ellipsoid_area(1, 2, 3),           /* ellipsoid */
        8.0 * (1 * 2 + 2 * 3 + 1 * 3),     /* box 2 x 4 x 6 */
        4.0 * TB_PI * TB_PI * 2.0 * 0.5,   /* torus */
        2.0 * TB_PI * 2.0 + 2.0 * TB_PI,   /* capped cylinder: side 2 pi r h, two discs */
        TB_PI * sqrt(5.0) + TB_PI,         /* cone: slant side pi r l, base */
        NAN,                               /* CSG: not computed */
        1.0,                               /* unit square (mirrored) */
        NAN,                               /* CSG union */
    };
    uint32_t objs[9] = {0, 1, 2, 3, 4, 5, 6, 7, 9};
    for (int i = 0; i < 9; i++) {
        const tb_scene_emissive *e = &s->emissive[i];
        assert_int_equal(e->object, objs[i]);
        /* Stored at load only where no tessellation is needed. */
        assert_true(isnan(e->area) == !(i == 0 || i == 7));
        double area = NAN;
        if (isnan(want[i])) {
            assert_int_equal(tb_scene_emissive_area(s, i, &area), TB_ERR_UNSUPPORTED);
            assert_int_equal(e->nemitters, 1); /* the lazily tessellated CSG emitter */
        } else {
            /* Flat shapes and the similarity-transformed sphere exactly;
             * other curved ones by their analytic emitter's integral. */
            assert_int_equal(tb_scene_emissive_area(s, i, &area), TB_OK);
            double tol = (i == 0 || i == 2 || i == 7) ? 1e-12 : 1e-6;
            if (fabs(area - want[i]) > tol * want[i])
                fail_msg("emissive %d: area %.12g, want %.12g (rel %.3g)", i, area, want[i],
                         fabs(area - want[i]) / want[i]);
        }
    }
    double bad;
    assert_int_equal(tb_scene_emissive_area(s, 9, &bad), TB_ERR_ARG);
    assert_int_equal(tb_scene_emissive_area(s, -1, &bad), TB_ERR_ARG);
    /* The union emits through its second child only. */
    const tb_object *u = s->objects[9];
    assert_int_equal(s->emissive[8].material, u->children[1].material);
    assert_true(s->materials[s->emissive[8].material].emission.v[0] == 2.0f);
    /* Emitters: a sphere for the similarity-transformed sphere, one analytic
     * surface emitter for the ellipsoid, the box and the other curved
     * primitives (their areas those of the surfaces), one lazily
     * tessellated emitter per CSG object, two triangles for the square. */
    assert_int_equal(s->emissive[0].nemitters, 1);
    const tb_emitter *es = &s->emitters[s->emissive[0].first_emitter];
    assert_int_equal(es->kind, TB_EMITTER_SPHERE);
    tb_assert_near(es->radius, 2.0, 1e-6);
    tb_assert_near(es->v[0].x, 1.0, 1e-6);
    tb_assert_near(es->v[0].z, 3.0, 1e-6);
    tb_assert_near(es->radiance.v[1], 1.0 / TB_PI, 1e-7);
    int total = 0;
    for (int i = 0; i < 9; i++)
        total += s->emissive[i].nemitters;
    for (int i = 1; i < 6; i++) {
        const tb_scene_emissive *e = &s->emissive[i];
        assert_int_equal(e->nemitters, 1);
        const tb_emitter *x = &s->emitters[e->first_emitter];
        assert_int_equal(x->kind, TB_EMITTER_CUSTOM);
        assert_int_equal(x->object, e->object);
        double a = tb_emitter_area(x);
        if (fabs(a - want[i]) > 1e-6 * want[i])
            fail_msg("emissive %d: surface emitter area %.9g, want %.9g", i, a, want[i]);
    }
    assert_true(s->emissive[6].nemitters == 1 && s->emissive[8].nemitters == 1); /* CSG: lazy emitters */
    assert_int_equal(s->emissive[7].nemitters, 2);
    assert_int_equal(s->nemitters, total);
    /* The mirrored square: its emitters face where the surface's hit normal
     * says its front is, and their radiance is M / pi. */
    tb_hit h = trace(s, (tb_vec3){-0.3f, 0.6f, 105}, (tb_vec3){0, 0, -1});
    assert_int_equal(h.object, 7);
    for (int k = 0; k < 2; k++) {
        const tb_emitter *e = &s->emitters[s->emissive[7].first_emitter + k];
        assert_int_equal(e->kind, TB_EMITTER_TRIANGLE);
        tb_vec3 n = tb_vec3_cross(tb_vec3_sub(e->v[1], e->v[0]), tb_vec3_sub(e->v[2], e->v[0]));
        assert_true(tb_vec3_dot(n, h.ng) > 0.0f);
        tb_assert_near(e->radiance.v[2], 3.0 / TB_PI, 1e-6);
        assert_int_equal(e->object, 7);
    }
    tb_scene_free(s);
}

/* ------------------------------------------------------------------ errors */

static void expect_error(const char *text, tb_status want, const char *prefix, const char *contains)
{
    tb_status st;
    tb_scene *s = load_text(text, NULL, &st);
    assert_null(s);
    if (st != want)
        fail_msg("status %d (%s), want %d: %s", st, tb_status_name(st), want, tb_last_error());
    const char *msg = tb_last_error();
    if (strncmp(msg, prefix, strlen(prefix)) != 0 || (contains && !strstr(msg, contains)))
        fail_msg("message '%s' does not start with '%s' or lacks '%s'", msg, prefix, contains ? contains : "");
}

static void test_errors(void **state)
{
    (void)state;
    /* The reader's own messages pass through. */
    expect_error("mid 1\nsphere {\n", TB_ERR_FORMAT, "t.mid:", "error: expected '}'");
    expect_error("mid 1\nsphere { rendering = { material = \"nope\" } }\n", TB_ERR_FORMAT, "t.mid:2:", "error:");
    /* The object level's refusals, located at the object. */
    expect_error("mid 1\nsphere {}\n  union \"u\" {\n  cylinder { geometry = { caps = false } }\n}\n", TB_ERR_ARG,
                 "t.mid:3:3: error: union 'u': ", "closed");
    /* A colour util/color cannot read (a four-column CSV is not a spectrum
     * file), located at the rendering block and at the file's own line. */
    expect_error("mid 1\nmaterial \"m\" { diffuse = spectrum(file(\"data/cornell-box-reflectance.csv\")) }\n"
                 "sphere { rendering = { material = \"m\" } }\n",
                 TB_ERR_FORMAT, "t.mid:3:10: error: material 'm', diffuse: ",
                 "cornell-box-reflectance.csv:3:10: error: unexpected text after the value");
    /* An IES file that does not parse, located at the light. */
    char ies[PATH_MAX + 32], dir[PATH_MAX];
    assert_non_null(realpath(tb_test_tmpdir(), dir)); /* file references resolve against the scenes folder */
    snprintf(ies, sizeof ies, "%s/scene_bad.ies", dir);
    FILE *f = fopen(ies, "w");
    assert_non_null(f);
    fputs("this is not an IES file\n", f);
    fclose(f);
    char text[PATH_MAX + 128];
    snprintf(text, sizeof text, "mid 1\nsphere {}\npoint_light { ies = file(\"%s\") }\n", ies);
    expect_error(text, TB_ERR_FORMAT, "t.mid:3:1: error: point_light: ", NULL);
    remove(ies);
    /* A missing file. */
    tb_scene *s = (tb_scene *)0x1;
    assert_int_equal(tb_scene_load(TB_SOURCE_DIR "/no/such/scene.mid", NULL, &s), TB_ERR_IO);
    assert_null(s);
    assert_int_equal(tb_scene_load(NULL, NULL, &s), TB_ERR_ARG);
    /* A bad accel kind. */
    tb_scene_options opt = {0};
    opt.accel = (tb_accel_kind)7;
    tb_status st;
    s = load_text("mid 1\nsphere {}\n", &opt, &st);
    assert_int_equal(st, TB_ERR_ARG);
}

/* ------------------------------------------------------------------ statistics */

static void test_stats(void **state)
{
    (void)state;
    tb_stat_total before, after, tris, load;
    assert_int_equal(tb_stats_get("Scene/polygons objects", TB_STAT_KIND_COUNTER, &before), TB_OK);
    tb_scene *s;
    if (tb_scene_load(CORNELL, NULL, &s))
        fail_msg("%s", tb_last_error());
    assert_int_equal(tb_stats_get("Scene/polygons objects", TB_STAT_KIND_COUNTER, &after), TB_OK);
    assert_int_equal(after.v[0] - before.v[0], 8);
    assert_int_equal(tb_stats_get("Scene/triangle references", TB_STAT_KIND_COUNTER, &tris), TB_OK);
    assert_true(tris.v[0] >= 32);
    assert_int_equal(tb_stats_get("Scene/load", TB_STAT_KIND_TIMER, &load), TB_OK);
    assert_true(load.v[0] >= 1);
    assert_true(s->stats.load_seconds > 0.0 && s->stats.accel_seconds > 0.0);
    /* The summary names what was loaded. */
    char buf[4096] = {0};
    FILE *m = fmemopen(buf, sizeof buf - 1, "w");
    assert_non_null(m);
    tb_scene_print_summary(s, m);
    fclose(m);
    assert_non_null(strstr(buf, "8 objects (8 polygons)"));
    assert_non_null(strstr(buf, "32 triangles"));
    assert_non_null(strstr(buf, "spectral colours (31 channels)"));
    assert_non_null(strstr(buf, "accel: bvh over 32 references"));
    tb_scene_free(s);
}

/* tb_scene_occluded_except: two spheres on the x axis (0 at x = 5, 1 at
 * x = 10); a shadow segment across both is blocked whichever is left out,
 * one across the first only is free when that one is left out. Also the
 * emitter record the ray tracer reads to choose what to leave out: a
 * top-level emissive sphere's emitter names that sphere, an emissive sphere
 * inside a union names an object that is not a plain sphere (so the ray
 * tracer never leaves out a non-convex object). */
static void test_occluded_except(void **state)
{
    (void)state;
    tb_scene *s = load_ok("mid 1\n"
                          "sphere { transform = [translate([5 0 0])] rendering = { emission = 1 } }\n"
                          "sphere { transform = [translate([10 0 0])] }\n"
                          "union { transform = [translate([0 10 0])] sphere {} sphere { transform = [translate([0 0 1])]"
                          " rendering = { emission = 2 } } }\n",
                          NULL);
    tb_ray both = tb_ray_make(tb_vec3_make(0, 0, 0), tb_vec3_make(20, 0, 0), 0.0f, 1.0f);
    tb_ray first = tb_ray_make(tb_vec3_make(0, 0, 0), tb_vec3_make(7, 0, 0), 0.0f, 1.0f);
    assert_true(tb_scene_occluded(s, &both));
    assert_true(tb_scene_occluded_except(s, &both, UINT32_MAX));
    assert_true(tb_scene_occluded_except(s, &both, 0));
    assert_true(tb_scene_occluded_except(s, &both, 1));
    assert_true(tb_scene_occluded_except(s, &first, UINT32_MAX));
    assert_true(tb_scene_occluded_except(s, &first, 1));
    assert_false(tb_scene_occluded_except(s, &first, 0));
    assert_true(tb_scene_occluded(s, &first)); /* the left-out object is back for the next query */
    assert_int_equal(s->nemissive, 2);
    const tb_emitter *e0 = &s->emitters[s->emissive[0].first_emitter];
    assert_int_equal(e0->kind, TB_EMITTER_SPHERE);
    assert_int_equal(e0->object, 0);
    const tb_emitter *e2 = &s->emitters[s->emissive[1].first_emitter];
    assert_true(e2->object >= s->nobjects || s->objects[e2->object]->kind != TB_PRIM_SPHERE);
    tb_scene_free(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cornell_spectral), cmocka_unit_test(test_cornell_rgb),
        cmocka_unit_test(test_material_dedup),   cmocka_unit_test(test_material_patterns),
        cmocka_unit_test(test_lights),
        cmocka_unit_test(test_emissive),         cmocka_unit_test(test_errors),
        cmocka_unit_test(test_stats),
        cmocka_unit_test(test_occluded_except),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
