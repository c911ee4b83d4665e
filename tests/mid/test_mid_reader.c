/* MID reader on valid input: numbers against strtod, strings and escapes,
 * positions, transforms against hand-computed matrices, defaults, material
 * resolution and inheritance, unknown attributes, lights, camera, the example
 * scene, and flat memory while streaming. */
#include "tb_test.h"

#include <string.h>

#include "host/mid/mid_reader.h"

#define DATA TB_TESTS_DIR "/mid/data"
#define PI 3.14159265358979323846

/* A reader over a copy of `text` (kept alive with the reader). */
typedef struct src {
    FILE *fp;
    tb_mid_reader *r;
} src;

static src open_text(const char *text)
{
    src s;
    s.fp = fmemopen((void *)text, strlen(text), "rb");
    assert_non_null(s.fp);
    assert_int_equal(tb_mid_reader_open_stream(&s.r, s.fp, "t.mid", DATA), TB_OK);
    return s;
}

static void close_text(src *s)
{
    tb_mid_reader_close(s->r);
    fclose(s->fp);
}

/* The next item, which must exist. */
static tb_mid_item next(src *s)
{
    tb_mid_item it;
    tb_status st = tb_mid_reader_next(s->r, &it);
    if (st)
        fail_msg("%s", tb_last_error());
    assert_int_not_equal(it.type, TB_MID_ITEM_END);
    return it;
}

static void expect_end(src *s)
{
    tb_mid_item it;
    assert_int_equal(tb_mid_reader_next(s->r, &it), TB_OK);
    assert_int_equal(it.type, TB_MID_ITEM_END);
}

static bool bits_equal(double a, double b) { return memcmp(&a, &b, sizeof a) == 0; }

/* Numbers: each text reads as exactly what strtod gives (fast and slow paths). */
static void test_numbers_match_strtod(void **state)
{
    (void)state;
    static const char *const fixed[] = {
        "0", "-0", "+3", ".5", "5.", "0.1", "1e-5", "1E+2", "-2.5e-3", "123456789012345678901234",
        "9007199254740992", "9007199254740993", "4.9406564584124654e-324", "2.2250738585072014e-308",
        "1.7976931348623157e308", "1e-400", "0.000000000000000000000000000001", "3.141592653589793238462643",
        "1e22", "1e23", "8.98846567431158e307", "0.30000000000000004"};
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("mid numbers", 20261121), 1);
    char text[256 * 64];
    char nums[256][40];
    int n = 0;
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++)
        snprintf(nums[n++], sizeof nums[0], "%s", fixed[i]);
    while (n < 256) {
        double x = ldexp(tb_rng_double(&rng), (int)tb_rng_below(&rng, 200) - 100);
        if (tb_rng_below(&rng, 2))
            x = -x;
        static const char *const fmts[] = {"%.17g", "%.9g", "%.3f", "%.20e", "%g", "%.15g"};
        snprintf(nums[n++], sizeof nums[0], fmts[tb_rng_below(&rng, 6)], x);
    }
    size_t k = (size_t)snprintf(text, sizeof text, "mid 1\nsphere { x = [");
    for (int i = 0; i < n; i++)
        k += (size_t)snprintf(text + k, sizeof text - k, " %s", nums[i]);
    snprintf(text + k, sizeof text - k, " ] }\n");
    src s = open_text(text);
    tb_mid_item it = next(&s);
    const tb_mid_object *o = it.object;
    assert_int_equal(o->extra.count, 1);
    const tb_mid_value *v = &o->extra.items[0].value;
    assert_int_equal(v->type, TB_MID_VECTOR);
    assert_int_equal(v->count, n);
    for (int i = 0; i < n; i++)
        if (!bits_equal(v->numbers[i], strtod(nums[i], NULL)))
            fail_msg("'%s' read as %.17g, strtod gives %.17g", nums[i], v->numbers[i], strtod(nums[i], NULL));
    close_text(&s);
}

/* Strings: escapes decode to the bytes they name; UTF-8 passes through. */
static void test_strings_and_positions(void **state)
{
    (void)state;
    const char *text = "mid 1 # header comment\r\n"
                       "\r\n"
                       "sphere \"a\\\"b\\\\c\\n\\t\\r\\u{e9}\\u{1F600}\xE4\xB8\xAD\" {\n"
                       "  # a comment with UTF-8: \xC3\xA9\n"
                       "  s = \"\" t = sym u = f(1, [2 3] \"x\") }\n";
    src s = open_text(text);
    tb_mid_item it = next(&s);
    const tb_mid_object *o = it.object;
    assert_string_equal(o->name, "a\"b\\c\n\t\r\xC3\xA9\xF0\x9F\x98\x80\xE4\xB8\xAD");
    assert_int_equal(o->loc.line, 3);
    assert_int_equal(o->loc.col, 1);
    assert_int_equal(o->extra.count, 3);
    const tb_mid_attr *a = o->extra.items;
    assert_string_equal(a[0].name, "s");
    assert_int_equal(a[0].value.type, TB_MID_STRING);
    assert_string_equal(a[0].value.text, "");
    assert_int_equal(a[0].loc.line, 5);
    assert_int_equal(a[0].loc.col, 3);
    assert_int_equal(a[1].value.type, TB_MID_SYMBOL);
    assert_string_equal(a[1].value.text, "sym");
    assert_int_equal(a[1].loc.col, 10);
    const tb_mid_value *u = &a[2].value;
    assert_int_equal(u->type, TB_MID_CALL);
    assert_string_equal(u->name, "f");
    assert_int_equal(u->count, 3);
    assert_int_equal(u->items[0].type, TB_MID_NUMBER);
    assert_int_equal(u->items[1].type, TB_MID_VECTOR);
    assert_int_equal(u->items[1].count, 2);
    assert_true(u->items[1].numbers[1] == 3.0);
    assert_int_equal(u->items[2].type, TB_MID_STRING);
    assert_int_equal(u->loc.col, 22);
    expect_end(&s);
    int major, minor;
    tb_mid_reader_version(s.r, &major, &minor);
    assert_int_equal(major, 1);
    assert_int_equal(minor, 0);
    close_text(&s);

    /* A newer minor version reads as long as everything in it is known. */
    s = open_text("mid 1.7\ncube { new_attribute = 1 }");
    it = next(&s);
    assert_int_equal(it.object->kind, TB_PRIM_CUBE);
    tb_mid_reader_version(s.r, &major, &minor);
    assert_int_equal(minor, 7);
    close_text(&s);
}

/* p' = M p with the reader's composed transform. */
static tb_dvec3 apply(const tb_mid_object *o, double x, double y, double z)
{
    return tb_mat4_mul_point(&o->to_world.m, (tb_dvec3){x, y, z});
}

static void assert_point(tb_dvec3 p, double x, double y, double z, double tol)
{
    tb_assert_near(p.x, x, tol);
    tb_assert_near(p.y, y, tol);
    tb_assert_near(p.z, z, tol);
}

/* Operations apply in the order written; a CSG node's transform applies to its children. */
static void test_transform_order(void **state)
{
    (void)state;
    src s = open_text("mid 1\n"
                      "sphere { transform = [scale(2) translate([0 0 1])] }\n"
                      "sphere { transform = [translate([0 0 1]) scale(2)] }\n"
                      "sphere { transform = [rotate([0 0 1], 90) translate([1 0 0])] }\n"
                      "sphere { transform = [matrix([1 0 0 5  0 2 0 6  0 0 3 7  0 0 0 1])] }\n"
                      "union { transform = [translate([10 0 0])] sphere { transform = [scale(2)] } }\n"
                      "sphere { transform = [scale([1 -1 1])] }\n"
                      "sphere { transform = [] }\n");
    tb_mid_item it = next(&s);
    assert_point(apply(it.object, 1, 0, 0), 2, 0, 1, 0); /* scaled, then lifted: exact */
    assert_int_equal(it.object->nops, 2);
    assert_int_equal(it.object->ops[0].kind, TB_MID_SCALE);
    it = next(&s);
    assert_point(apply(it.object, 1, 0, 0), 2, 0, 2, 0); /* lifted, then scaled */
    it = next(&s);
    assert_point(apply(it.object, 1, 0, 0), 1, 1, 0, 0); /* x -> y exactly, then moved */
    it = next(&s);
    assert_point(apply(it.object, 1, 1, 1), 6, 8, 10, 0); /* rows in reading order, translation last column */
    tb_dvec3 back = tb_mat4_mul_point(&it.object->to_world.inv, (tb_dvec3){6, 8, 10});
    assert_point(back, 1, 1, 1, 1e-15);
    it = next(&s);
    assert_point(apply(it.object, 0, 0, 0), 10, 0, 0, 0);
    assert_point(apply(&it.object->children[0], 1, 0, 0), 12, 0, 0, 0);
    it = next(&s);
    assert_true(tb_transform_swaps_handedness(&it.object->to_world));
    it = next(&s);
    assert_true(tb_transform_is_identity(&it.object->to_world));
    assert_int_equal(it.object->nops, 0);
    expect_end(&s);
    close_text(&s);
}

/* Geometry defaults (docs/mid.md 6.3) and explicit parameters. */
static void test_geometry(void **state)
{
    (void)state;
    src s = open_text("mid 1\n"
                      "cylinder {} cone {} pyramid {} prism {} torus {} conic {} square_arch {} round_arch {}\n"
                      "cone { geometry = { top_radius = 0.5 caps = false } }\n"
                      "prism { geometry = { profile = [[0 0] [1 0] [0 1]] } }\n"
                      "torus { geometry = { major = 3 minor = 1 extra = 7 } }\n"
                      "conic { geometry = { coefficients = [0.5 0 0.5] z_range = [-2 1] caps = false } }\n"
                      "round_arch { geometry = { width = 1 height = 0.5 } }\n"
                      "polygons { geometry = { vertices = [[0 0 0] [1 0 0] [1 1 0] [0 1 0] [2 0 0]]\n"
                      "                        faces = [[0 1 2 3] [1 4 2]] normals = [[0 0 1] [0 0 1] [0 0 1] [0 0 1] [0 0 1]] } }\n"
                      "polygons { geometry = { mesh = file(\"checker.png\") } }\n");
    tb_mid_item it = next(&s);
    assert_true(it.object->geom.cylinder.caps);
    it = next(&s);
    assert_true(it.object->geom.cone.top_radius == 0.0 && it.object->geom.cone.caps);
    it = next(&s);
    assert_true(it.object->geom.pyramid.top == 0.0 && it.object->geom.pyramid.caps);
    it = next(&s);
    assert_int_equal(it.object->geom.prism.sides, 3);
    assert_int_equal(it.object->geom.prism.nprofile, 0);
    it = next(&s);
    assert_true(it.object->geom.torus.major == 1.0 && it.object->geom.torus.minor == 0.25);
    it = next(&s);
    const tb_geom_conic *c = &it.object->geom.conic;
    assert_true(c->c[0] == 1.0 && c->c[1] == 0.0 && c->c[2] == -1.0 && c->z0 == -1.0 && c->z1 == 1.0 && c->caps);
    it = next(&s);
    assert_true(it.object->geom.arch.width == 1.0 && it.object->geom.arch.height == 1.5);
    it = next(&s);
    assert_int_equal(it.object->kind, TB_PRIM_ROUND_ARCH);
    it = next(&s);
    assert_true(it.object->geom.cone.top_radius == 0.5 && !it.object->geom.cone.caps);
    it = next(&s);
    assert_int_equal(it.object->geom.prism.sides, 0);
    assert_int_equal(it.object->geom.prism.nprofile, 3);
    assert_true(it.object->geom.prism.profile[2].y == 1.0f);
    it = next(&s);
    assert_true(it.object->geom.torus.major == 3.0 && it.object->geom.torus.minor == 1.0);
    assert_int_equal(it.object->geometry_extra.count, 1);
    assert_string_equal(it.object->geometry_extra.items[0].name, "extra");
    it = next(&s);
    c = &it.object->geom.conic;
    assert_true(c->c[0] == 0.5 && c->c[2] == 0.5 && c->z0 == -2.0 && c->z1 == 1.0 && !c->caps);
    it = next(&s);
    assert_true(it.object->geom.arch.height == 0.5); /* exactly half the width is allowed */
    it = next(&s);
    const tb_geom_polygons *p = &it.object->geom.polygons;
    assert_int_equal(p->nvertices, 5);
    assert_int_equal(p->nfaces, 2);
    assert_int_equal(p->face_start[0], 0);
    assert_int_equal(p->face_start[1], 4);
    assert_int_equal(p->face_start[2], 7);
    assert_int_equal(p->indices[5], 4);
    assert_true(p->vertices[4].x == 2.0f);
    assert_non_null(p->normals);
    assert_null(p->uvs);
    assert_null(p->mesh.text);
    it = next(&s);
    p = &it.object->geom.polygons;
    assert_string_equal(p->mesh.text, "checker.png");
    assert_string_equal(p->mesh.path, DATA "/checker.png");
    assert_int_equal(it.object->nrefs, 1);
    expect_end(&s);
    close_text(&s);
}

static void assert_rgb(const tb_mid_color *c, float r, float g, float b)
{
    assert_int_equal(c->type, TB_MID_COLOR_RGB);
    assert_true(c->rgb[0] == r && c->rgb[1] == g && c->rgb[2] == b);
}

/* Named materials, overrides, CSG inheritance, spectra. */
static void test_materials(void **state)
{
    (void)state;
    src s = open_text("mid 1\n"
                      "material \"red\" { diffuse = [0.5 0.25 0.125] specular = 0.5 }\n"
                      "material \"shiny\" { material = \"red\" exponent = 100 x = 1 }\n"
                      "sphere {}\n"
                      "sphere { rendering = { material = \"shiny\" ior = 1.5 } }\n"
                      "union { rendering = { material = \"red\" }\n"
                      "  sphere {}\n"
                      "  sphere { rendering = { emission = spectrum([400 700], [1 2]) } }\n"
                      "  sphere { rendering = { material = \"shiny\" } } }\n");
    tb_mid_item it = next(&s);
    assert_int_equal(it.type, TB_MID_ITEM_MATERIAL);
    assert_string_equal(it.material->name, "red");
    assert_int_equal(it.material->set, TB_MID_SET_DIFFUSE | TB_MID_SET_SPECULAR);
    it = next(&s);
    const tb_mid_material *shiny = it.material;
    assert_string_equal(shiny->base, "red");
    assert_rgb(&shiny->diffuse, 0.5f, 0.25f, 0.125f);
    assert_rgb(&shiny->specular, 0.5f, 0.5f, 0.5f);
    assert_true(shiny->exponent == 100.0f);
    assert_int_equal(shiny->extra.count, 1);
    assert_ptr_equal(tb_mid_reader_material(s.r, "shiny"), shiny);
    assert_null(tb_mid_reader_material(s.r, "blue"));

    it = next(&s); /* defaults */
    const tb_mid_material *m = &it.object->material;
    assert_rgb(&m->diffuse, 0.5f, 0.5f, 0.5f);
    assert_rgb(&m->specular, 0, 0, 0);
    assert_rgb(&m->transmission, 0, 0, 0);
    assert_rgb(&m->emission, 0, 0, 0);
    assert_true(m->exponent == 20.0f && m->ior == 1.0f);
    assert_false(tb_mid_material_emits(m));
    assert_null(m->base);
    assert_int_equal(m->set, 0);

    it = next(&s);
    m = &it.object->material;
    assert_string_equal(m->base, "shiny");
    assert_int_equal(m->set, TB_MID_SET_IOR);
    assert_true(m->ior == 1.5f && m->exponent == 100.0f);
    assert_rgb(&m->diffuse, 0.5f, 0.25f, 0.125f);
    assert_int_equal(m->extra.count, 0); /* the base's unknown attributes stay with the base */

    it = next(&s);
    const tb_mid_object *u = it.object;
    assert_int_equal(u->nchildren, 3);
    assert_rgb(&u->children[0].material.diffuse, 0.5f, 0.25f, 0.125f); /* inherited */
    assert_null(u->children[0].material.base);
    assert_int_equal(u->children[0].material.set, 0);
    const tb_mid_material *e = &u->children[1].material;
    assert_rgb(&e->diffuse, 0.5f, 0.25f, 0.125f); /* inherited, plus its own emission */
    assert_int_equal(e->emission.type, TB_MID_COLOR_SPECTRUM);
    assert_int_equal(e->emission.nsamples, 2);
    assert_true(e->emission.nm[1] == 700.0f && e->emission.values[1] == 2.0f);
    assert_true(tb_mid_material_emits(e));
    assert_true(u->children[2].material.exponent == 100.0f);
    expect_end(&s);
    close_text(&s);
}

/* Unknown attributes keep their whole value tree and location; file references resolve. */
static void test_unknown_attributes_and_refs(void **state)
{
    (void)state;
    src s = open_text("mid 1\n"
                      "sphere { geometry = { g = 1 } rendering = { r = 2 diffuse_texture = file(\"checker.png\") }\n"
                      "  z = { a = [x [1 2] \"s\" {}] b = file(\"./checker.png\") } }\n");
    tb_mid_item it = next(&s);
    const tb_mid_object *o = it.object;
    assert_int_equal(o->geometry_extra.count, 1);
    assert_int_equal(o->material.extra.count, 1);
    assert_string_equal(o->material.extra.items[0].name, "r");
    assert_int_equal(o->extra.count, 1);
    const tb_mid_attr *z = &o->extra.items[0];
    assert_string_equal(z->name, "z");
    assert_int_equal(z->loc.line, 3);
    assert_int_equal(z->loc.col, 3);
    assert_int_equal(z->value.type, TB_MID_BLOCK);
    assert_int_equal(z->value.count, 2);
    const tb_mid_value *a = &z->value.attrs[0].value;
    assert_int_equal(a->type, TB_MID_LIST);
    assert_int_equal(a->count, 4);
    assert_int_equal(a->items[0].type, TB_MID_SYMBOL);
    assert_int_equal(a->items[1].type, TB_MID_VECTOR);
    assert_int_equal(a->items[2].type, TB_MID_STRING);
    assert_int_equal(a->items[3].type, TB_MID_BLOCK);
    assert_int_equal(a->items[3].count, 0);
    const tb_mid_value *b = &z->value.attrs[1].value;
    assert_int_equal(b->type, TB_MID_FILE);
    assert_string_equal(b->ref.text, "./checker.png");
    assert_string_equal(b->ref.path, DATA "/./checker.png");
    /* References in the writer's order: rendering, then unknown attributes. */
    assert_int_equal(o->nrefs, 2);
    assert_string_equal(o->refs[0].text, "checker.png");
    assert_string_equal(o->refs[1].text, "./checker.png");
    assert_int_equal(o->material.nrefs, 1);
    assert_string_equal(o->material.diffuse_texture.path, DATA "/checker.png");
    close_text(&s);
}

static void test_lights_and_camera(void **state)
{
    (void)state;
    src s = open_text("mid 1\n"
                      "point_light {}\n"
                      "spot_light \"s\" { transform = [translate([0 0 2])] direction = [0 1 0] cone_angle = 20 cone_delta = 0 }\n"
                      "directional_light { irradiance = [1 2 3] position = [1 1 1] }\n"
                      "camera { }\n");
    tb_mid_item it = next(&s);
    const tb_mid_light *l = it.light;
    assert_int_equal(l->kind, TB_LIGHT_POINT);
    assert_true(l->position.x == 0 && l->position.y == 0 && l->position.z == 0);
    assert_rgb(&l->intensity, 1, 1, 1);
    assert_null(l->ies.text);
    it = next(&s);
    l = it.light;
    assert_int_equal(l->kind, TB_LIGHT_SPOT);
    assert_string_equal(l->name, "s");
    assert_true(l->direction.y == 1.0 && l->cone_angle == 20.0 && l->cone_delta == 0.0);
    assert_point(tb_mat4_mul_point(&l->to_world.m, l->position), 0, 0, 2, 0);
    it = next(&s);
    l = it.light;
    assert_int_equal(l->kind, TB_LIGHT_DIRECTIONAL);
    assert_rgb(&l->intensity, 1, 2, 3);
    assert_int_equal(l->extra.count, 1); /* position means nothing for a directional light */
    assert_true(l->direction.z == -1.0);
    it = next(&s);
    const tb_mid_camera *c = it.camera;
    assert_true(c->eye.x == 0 && c->eye.y == 0 && c->eye.z == 0);
    assert_true(c->look_at.z == -1.0 && c->up.y == 1.0);
    assert_true(c->fov == 45.0 && c->focal_length == 0.0);
    assert_int_equal(c->width, 512);
    assert_int_equal(c->height, 512);
    assert_true(c->aperture == 0.0 && c->focus_distance == 1.0);
    assert_ptr_equal(tb_mid_reader_camera(s.r), c);
    close_text(&s);

    /* Focal length on a 36x24 film: a 4:3 image uses the full 24 mm height;
     * a 2:1 image uses 36 mm x 18 mm. */
    s = open_text("mid 1\ncamera { focal_length = 50 resolution = [640 480] eye = [0 0 3] look_at = [0 4 0] }\n");
    it = next(&s);
    tb_assert_near(it.camera->fov, 2.0 * atan(24.0 / 100.0) * 180.0 / PI, 1e-12);
    tb_assert_near(it.camera->focus_distance, 5.0, 0);
    close_text(&s);
    s = open_text("mid 1\ncamera { focal_length = 50 resolution = [1000 500] }\n");
    it = next(&s);
    tb_assert_near(it.camera->fov, 2.0 * atan(18.0 / 100.0) * 180.0 / PI, 1e-12);
    close_text(&s);
}

/* The example scene in tests/mid/data reads whole, with the values it states. */
static void test_example_scene(void **state)
{
    (void)state;
    tb_mid_reader *r;
    assert_int_equal(tb_mid_reader_open(&r, DATA "/example.mid"), TB_OK);
    tb_mid_item it;
    tb_status st;
    int counts[5] = {0}, kinds[TB_PRIM_COUNT] = {0};
    while (!(st = tb_mid_reader_next(r, &it)) && it.type != TB_MID_ITEM_END) {
        counts[it.type]++;
        if (it.type == TB_MID_ITEM_OBJECT) {
            kinds[it.object->kind]++;
            if (it.object->name && strcmp(it.object->name, "ball") == 0) {
                assert_point(apply(it.object, 0, 0, 1), -2, 0, 1, 0);
                assert_true(it.object->material.specular.rgb[0] == 0.2f);
                assert_rgb(&it.object->material.diffuse, 0.63f, 0.065f, 0.05f);
            }
            if (it.object->kind == TB_PRIM_DIFFERENCE) {
                const tb_mid_object *u = &it.object->children[1];
                assert_int_equal(u->kind, TB_PRIM_UNION);
                assert_true(u->children[0].material.transmission.rgb[0] == 0.9f); /* glass, twice inherited */
                assert_true(u->children[1].material.diffuse.rgb[0] == 0.63f);      /* red */
                assert_point(apply(&u->children[0], 0, 0, 1), 0, 0, 2.2, 1e-15);
            }
        }
    }
    if (st)
        fail_msg("%s", tb_last_error());
    assert_int_equal(counts[TB_MID_ITEM_CAMERA], 1);
    assert_int_equal(counts[TB_MID_ITEM_MATERIAL], 5);
    assert_int_equal(counts[TB_MID_ITEM_LIGHT], 3);
    assert_int_equal(counts[TB_MID_ITEM_OBJECT], 15);
    assert_int_equal(kinds[TB_PRIM_SPHERE], 2);
    assert_int_equal(kinds[TB_PRIM_POLYGONS], 2);
    assert_int_equal(kinds[TB_PRIM_PRISM], 2);
    const tb_mid_camera *c = tb_mid_reader_camera(r);
    assert_string_equal(c->name, "main");
    tb_assert_near(c->fov, 2.0 * atan(24.0 / 100.0) * 180.0 / PI, 1e-12);
    tb_mid_reader_close(r);
}

/* Streaming: memory after 20000 objects is what it was after 100. */
static void test_memory_is_flat(void **state)
{
    (void)state;
    FILE *fp = tmpfile();
    assert_non_null(fp);
    fprintf(fp, "mid 1\nmaterial \"m\" { diffuse = 0.25 }\n");
    for (int i = 0; i < 20000; i++)
        fprintf(fp,
                "%s { transform = [scale(%d.5) translate([%d 2.25 -3.125])] rendering = { material = \"m\" } "
                "note = \"object %d\" }\n",
                i % 3 ? "sphere" : "cube", i % 7 + 1, i, i);
    rewind(fp);
    tb_mid_reader *r;
    assert_int_equal(tb_mid_reader_open_stream(&r, fp, "big.mid", NULL), TB_OK);
    tb_mid_item it;
    size_t early = 0;
    int n = 0;
    tb_status st;
    while (!(st = tb_mid_reader_next(r, &it)) && it.type != TB_MID_ITEM_END) {
        if (++n == 101)
            early = tb_mid_reader_memory(r);
    }
    assert_int_equal(st, TB_OK);
    assert_int_equal(n, 20001);
    assert_int_equal(tb_mid_reader_memory(r), early);
    assert_true(tb_mid_reader_offset(r) > 20000 * 80);
    tb_mid_reader_close(r);
    fclose(fp);
}

/* MID 1.1 material attributes: defaults, every form of model, roughness,
 * patterns and bump maps, inheritance through a named material, and the
 * file references they bring. */
static void test_materials_11(void **state)
{
    (void)state;
    src s = open_text("mid 1.1\n"
                      "material \"d\" {}\n"
                      "material \"metal\" { model = ggx roughness = 0.35 specular = [0.9 0.6 0.3]\n"
                      "    diffuse_pattern = checker(8, 0.1, [1 0.5 0.25])\n"
                      "    specular_pattern = noise(2.5, 4, 0, 1, object)\n"
                      "    bump = noise(16, 3, -0.01, uv) }\n"
                      "sphere { rendering = { material = \"metal\" model = blinn\n"
                      "    bump = image(file(\"checker.png\"), 0.002) } }\n"
                      "cube { rendering = { model = lambert diffuse_pattern = checker(1.5, 0, 1, object) } }\n"
                      "cube { rendering = { model = phong } }\n"
                      "cube { rendering = { diffuse_pattern = checker([24 8], 0, 1) bump = noise([6 2], 2, 0.1) } }\n");
    tb_mid_item it = next(&s);
    const tb_mid_material *d = it.material;
    assert_int_equal(d->model, TB_MID_MODEL_PHONG);
    assert_true(d->roughness == 0.2f);
    assert_int_equal(d->diffuse_pattern.kind, TB_MID_PATTERN_NONE);
    assert_int_equal(d->specular_pattern.kind, TB_MID_PATTERN_NONE);
    assert_int_equal(d->bump.kind, TB_MID_PATTERN_NONE);
    it = next(&s);
    const tb_mid_material *m = it.material;
    assert_int_equal(m->model, TB_MID_MODEL_GGX);
    assert_true(m->roughness == 0.35f);
    assert_int_equal(m->set & (TB_MID_SET_MODEL | TB_MID_SET_ROUGHNESS | TB_MID_SET_DIFFUSE_PATTERN |
                               TB_MID_SET_SPECULAR_PATTERN | TB_MID_SET_BUMP),
                     TB_MID_SET_MODEL | TB_MID_SET_ROUGHNESS | TB_MID_SET_DIFFUSE_PATTERN |
                         TB_MID_SET_SPECULAR_PATTERN | TB_MID_SET_BUMP);
    assert_int_equal(m->diffuse_pattern.kind, TB_MID_PATTERN_CHECKER);
    assert_true(m->diffuse_pattern.scale == 8.0 && m->diffuse_pattern.scale_v == 8.0 &&
                !m->diffuse_pattern.object_space);
    assert_rgb(&m->diffuse_pattern.a, 0.1f, 0.1f, 0.1f);
    assert_rgb(&m->diffuse_pattern.b, 1.0f, 0.5f, 0.25f);
    assert_int_equal(m->specular_pattern.kind, TB_MID_PATTERN_NOISE);
    assert_true(m->specular_pattern.scale == 2.5 && m->specular_pattern.octaves == 4 &&
                m->specular_pattern.object_space);
    assert_rgb(&m->specular_pattern.a, 0.0f, 0.0f, 0.0f);
    assert_rgb(&m->specular_pattern.b, 1.0f, 1.0f, 1.0f);
    assert_int_equal(m->bump.kind, TB_MID_PATTERN_NOISE);
    assert_true(m->bump.scale == 16.0 && m->bump.octaves == 3 && m->bump.height == -0.01 && !m->bump.object_space);
    /* an object starting from "metal" overrides the model and the bump, keeps the rest */
    it = next(&s);
    const tb_mid_material *o = &it.object->material;
    assert_int_equal(o->model, TB_MID_MODEL_BLINN);
    assert_true(o->roughness == 0.35f);
    assert_int_equal(o->set, TB_MID_SET_MODEL | TB_MID_SET_BUMP);
    assert_int_equal(o->diffuse_pattern.kind, TB_MID_PATTERN_CHECKER);
    assert_int_equal(o->bump.kind, TB_MID_PATTERN_IMAGE);
    assert_true(o->bump.height == 0.002);
    assert_string_equal(o->bump.image.text, "checker.png");
    assert_string_equal(o->bump.image.path, DATA "/checker.png");
    assert_int_equal(it.object->nrefs, 1);
    it = next(&s);
    o = &it.object->material;
    assert_int_equal(o->model, TB_MID_MODEL_LAMBERT);
    assert_true(o->diffuse_pattern.object_space && o->diffuse_pattern.scale == 1.5);
    it = next(&s);
    assert_int_equal(it.object->material.model, TB_MID_MODEL_PHONG);
    assert_int_equal(it.object->material.set, TB_MID_SET_MODEL);
    it = next(&s);
    o = &it.object->material;
    assert_true(o->diffuse_pattern.scale == 24.0 && o->diffuse_pattern.scale_v == 8.0);
    assert_true(o->bump.scale == 6.0 && o->bump.scale_v == 2.0 && o->bump.height == 0.1);
    expect_end(&s);
    close_text(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_numbers_match_strtod),
        cmocka_unit_test(test_strings_and_positions),
        cmocka_unit_test(test_transform_order),
        cmocka_unit_test(test_geometry),
        cmocka_unit_test(test_materials),
        cmocka_unit_test(test_materials_11),
        cmocka_unit_test(test_unknown_attributes_and_refs),
        cmocka_unit_test(test_lights_and_camera),
        cmocka_unit_test(test_example_scene),
        cmocka_unit_test(test_memory_is_flat),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
