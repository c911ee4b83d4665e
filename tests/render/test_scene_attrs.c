/* Unknown MID attributes in the assembled scene (host/render/scene.h,
 * "unknown attributes"): values of every kind on object bodies, geometry
 * blocks, CSG nodes, materials (named, inherited, deduplicated), lights and
 * the camera; missing names; a scene without any. Expected values are the
 * ones written in the MID text below. */
#include "tb_test.h"

#include <stdlib.h>
#include <string.h>

#include "host/render/scene.h"

static const char *const text =
    "mid 1.1\n"
    "camera {\n"
    "    eye = [0 -20 0] look_at = [0 0 0] up = [0 0 1] fov = 40 resolution = [64 48]\n"
    "    my_exposure = 1.5\n"
    "    my_tonemap = \"filmic\"\n"
    "}\n"
    "material \"glass\" {\n"
    "    transmission = 1 ior = 1.5\n"
    "    my_dispersion = 0.02\n"
    "    my_medium = { absorption = [0.1 0.2 0.3] name = \"green glass\" }\n"
    "}\n"
    "material \"tinted\" { material = \"glass\" diffuse = 0.1 my_tint = [1 0 0] }\n"
    "point_light \"key\" { position = [0 0 5] my_shadow = soft my_samples = 16 }\n"
    "point_light \"fill\" { position = [1 0 5] }\n"
    /* 0: every value kind on the body, one in the geometry block, a material block with a nested block */
    "sphere \"a\" {\n"
    "    my_renderer_weight = 2.5\n"
    "    my_tags = [\"hero\" 3 [1 2]]\n"
    "    my_lut = file(\"data/cornell-box-reflectance.csv\")\n"
    "    my_curve = bezier([0 0] [1 1])\n"
    "    my_flags = []\n"
    "    geometry = { my_subdiv = 3 }\n"
    "    rendering = { diffuse = 0.5 my_sss = { radius = [1 0.5 0.25] enabled = true } }\n"
    "}\n"
    /* 1: the same known material, another unknown one: a material of its own */
    "sphere \"b\" { transform = [translate([3 0 0])]\n"
    "    rendering = { diffuse = 0.5 my_sss = { radius = [2 1 0.5] enabled = true } } }\n"
    /* 2: the same known material without unknown attributes */
    "sphere \"c\" { transform = [translate([-3 0 0])] rendering = { diffuse = 0.5 } }\n"
    /* 3: the same material block as a: a's entry */
    "sphere \"d\" { transform = [translate([0 3 0])]\n"
    "    rendering = { diffuse = 0.5 my_sss = { radius = [1 0.5 0.25] enabled = true } } }\n"
    /* 4, 5, 6: named materials, overridden, and a chain of names */
    "sphere \"e\" { transform = [translate([0 6 0])] rendering = { material = \"glass\" } }\n"
    "sphere \"f\" { transform = [translate([0 9 0])] rendering = { material = \"glass\" my_dispersion = 0.05 } }\n"
    "sphere \"g\" { transform = [translate([0 12 0])] rendering = { material = \"tinted\" } }\n"
    /* 7: a CSG tree: leaves with their own body attributes, inherited and overridden material ones */
    "union \"u\" {\n"
    "    transform = [translate([0 0 10])]\n"
    "    my_group = \"csg\"\n"
    "    rendering = { diffuse = 0.2 my_layer = 7 }\n"
    "    sphere \"u1\" { transform = [translate([-1.5 0 0])] my_leaf = 1 }\n"
    "    cube \"u2\" { transform = [translate([1.5 0 0])] rendering = { specular = 0.3 my_layer = 8 } }\n"
    "}\n";

static tb_scene *load_text(const char *mid)
{
    /* A heap copy overwritten after loading: nothing may point into it. */
    size_t n = strlen(mid);
    char *buf = malloc(n + 1);
    assert_non_null(buf);
    memcpy(buf, mid, n + 1);
    FILE *fp = fmemopen(buf, n, "r");
    assert_non_null(fp);
    tb_scene_options opt = {.no_accel = false};
    tb_scene *s = NULL;
    if (tb_scene_load_stream(fp, "attrs.mid", TB_SOURCE_DIR "/scenes", &opt, &s))
        fail_msg("%s", tb_last_error());
    fclose(fp);
    memset(buf, 'x', n);
    free(buf);
    return s;
}

static void test_object_attrs(void **state)
{
    (void)state;
    tb_scene *s = load_text(text);
    assert_int_equal(s->nobjects, 8);

    /* number, with the getters and their defaults */
    const tb_mid_value *w = tb_scene_object_attr(s, 0, "my_renderer_weight");
    assert_non_null(w);
    assert_int_equal(w->type, TB_MID_NUMBER);
    assert_true(tb_scene_attr_number(w, -1.0) == 2.5);
    assert_true(tb_scene_attr_number(tb_scene_object_attr(s, 1, "my_renderer_weight"), -1.0) == -1.0);
    assert_string_equal(tb_scene_attr_string(w, "def"), "def"); /* a number is not a string */
    /* list of a string, a number and a vector */
    const tb_mid_value *tags = tb_scene_object_attr(s, 0, "my_tags");
    assert_non_null(tags);
    assert_int_equal(tags->type, TB_MID_LIST);
    assert_int_equal(tags->count, 3);
    assert_string_equal(tb_scene_attr_string(&tags->items[0], NULL), "hero");
    assert_true(tb_scene_attr_number(&tags->items[1], 0.0) == 3.0);
    const double *v2 = tb_scene_attr_vector(&tags->items[2], 2, NULL);
    assert_non_null(v2);
    assert_true(v2[0] == 1.0 && v2[1] == 2.0);
    assert_null(tb_scene_attr_vector(&tags->items[2], 3, NULL)); /* wrong length: the default */
    /* file reference: as written and resolved against the scene's folder */
    const tb_mid_value *lut = tb_scene_object_attr(s, 0, "my_lut");
    assert_non_null(lut);
    assert_int_equal(lut->type, TB_MID_FILE);
    assert_string_equal(lut->ref.text, "data/cornell-box-reflectance.csv");
    assert_non_null(strstr(lut->ref.path, "scenes/data/cornell-box-reflectance.csv"));
    /* call with its arguments */
    const tb_mid_value *curve = tb_scene_object_attr(s, 0, "my_curve");
    assert_non_null(curve);
    assert_int_equal(curve->type, TB_MID_CALL);
    assert_string_equal(curve->name, "bezier");
    assert_int_equal(curve->count, 2);
    assert_int_equal(curve->items[1].type, TB_MID_VECTOR);
    assert_true(curve->items[1].numbers[0] == 1.0 && curve->items[1].numbers[1] == 1.0);
    /* the empty list */
    const tb_mid_value *flags = tb_scene_object_attr(s, 0, "my_flags");
    assert_non_null(flags);
    assert_int_equal(flags->count, 0);
    /* the geometry block's, found by the object lookup after the body's */
    assert_true(tb_scene_attr_number(tb_scene_object_attr(s, 0, "my_subdiv"), 0.0) == 3.0);
    tb_mid_attrs body = tb_scene_node_attrs(s, s->objects[0], false);
    tb_mid_attrs geom = tb_scene_node_attrs(s, s->objects[0], true);
    assert_int_equal(body.count, 5);
    assert_string_equal(body.items[0].name, "my_renderer_weight"); /* file order */
    assert_string_equal(body.items[4].name, "my_flags");
    assert_int_equal(geom.count, 1);
    assert_null(tb_scene_attr_find(body, "my_subdiv"));
    /* missing: names, objects, a NULL scene; material attributes are not the object's */
    assert_null(tb_scene_object_attr(s, 0, "my_renderer_weigh"));
    assert_null(tb_scene_object_attr(s, 0, "my_sss"));
    assert_null(tb_scene_object_attr(s, 0, "diffuse")); /* known attributes are not kept here */
    assert_null(tb_scene_object_attr(s, 8, "my_renderer_weight"));
    assert_null(tb_scene_object_attr(NULL, 0, "my_renderer_weight"));
    assert_int_equal(tb_scene_node_attrs(s, s->objects[2], false).count, 0);
    assert_null(tb_scene_node_attrs(s, s->objects[2], false).items);
    tb_scene_free(s);
}

static void test_material_attrs(void **state)
{
    (void)state;
    tb_scene *s = load_text(text);
    const int ma = s->objects[0]->material, mb = s->objects[1]->material, mc = s->objects[2]->material;
    const int md = s->objects[3]->material;
    /* a, b and c have the same known material but different unknown ones: three entries; d is a's */
    assert_int_not_equal(ma, mb);
    assert_int_not_equal(ma, mc);
    assert_int_not_equal(mb, mc);
    assert_int_equal(md, ma);
    assert_true(s->materials[ma].diffuse.v[0] == s->materials[mb].diffuse.v[0]);
    /* a's nested block */
    const tb_mid_value *sss = tb_scene_material_attr(s, ma, "my_sss");
    assert_non_null(sss);
    assert_int_equal(sss->type, TB_MID_BLOCK);
    assert_int_equal(sss->count, 2);
    static const double none[3] = {0, 0, 0};
    const double *ra = tb_scene_attr_vector(tb_scene_attr_field(sss, "radius"), 3, none);
    assert_true(ra[0] == 1.0 && ra[1] == 0.5 && ra[2] == 0.25);
    assert_string_equal(tb_scene_attr_string(tb_scene_attr_field(sss, "enabled"), "false"), "true");
    assert_null(tb_scene_attr_field(sss, "missing"));
    assert_null(tb_scene_attr_field(tb_scene_material_attr(s, ma, "my_sss_missing"), "radius"));
    const double *rb = tb_scene_attr_vector(tb_scene_attr_field(tb_scene_material_attr(s, mb, "my_sss"), "radius"),
                                            3, none);
    assert_true(rb[0] == 2.0);
    assert_int_equal(tb_scene_material_attrs(s, mc).count, 0);
    assert_null(tb_scene_material_attr(s, mc, "my_sss"));
    assert_null(tb_scene_material_attr(s, -1, "my_sss"));
    assert_null(tb_scene_material_attr(s, s->nmaterials, "my_sss"));

    /* named: the definition's own; overridden by the block; through a chain of names */
    const int me = s->objects[4]->material, mf = s->objects[5]->material, mg = s->objects[6]->material;
    assert_true(tb_scene_attr_number(tb_scene_material_attr(s, me, "my_dispersion"), 0.0) == 0.02);
    const tb_mid_value *medium = tb_scene_material_attr(s, me, "my_medium");
    assert_string_equal(tb_scene_attr_string(tb_scene_attr_field(medium, "name"), NULL), "green glass");
    assert_int_not_equal(me, mf);
    assert_true(tb_scene_attr_number(tb_scene_material_attr(s, mf, "my_dispersion"), 0.0) == 0.05);
    assert_non_null(tb_scene_material_attr(s, mf, "my_medium"));
    tb_mid_attrs fa = tb_scene_material_attrs(s, mf);
    assert_int_equal(fa.count, 2); /* the override replaces, not adds */
    assert_true(tb_scene_attr_number(tb_scene_material_attr(s, mg, "my_dispersion"), 0.0) == 0.02);
    const double *tint = tb_scene_attr_vector(tb_scene_material_attr(s, mg, "my_tint"), 3, none);
    assert_true(tint[0] == 1.0 && tint[1] == 0.0);
    assert_null(tb_scene_material_attr(s, me, "my_tint"));

    /* the CSG tree: the union's body; a leaf's body; materials inherited from and overriding the parent */
    const tb_object *u = s->objects[7];
    assert_int_equal(u->nchildren, 2);
    assert_string_equal(tb_scene_attr_string(tb_scene_object_attr(s, 7, "my_group"), NULL), "csg");
    assert_null(tb_scene_object_attr(s, 7, "my_leaf"));
    assert_true(tb_scene_attr_number(tb_scene_node_attr(s, &u->children[0], "my_leaf"), 0.0) == 1.0);
    assert_null(tb_scene_node_attr(s, &u->children[1], "my_leaf"));
    assert_true(tb_scene_attr_number(tb_scene_material_attr(s, u->children[0].material, "my_layer"), 0.0) == 7.0);
    assert_true(tb_scene_attr_number(tb_scene_material_attr(s, u->children[1].material, "my_layer"), 0.0) == 8.0);
    /* as a renderer finds it: the leaf a ray hits */
    tb_ray r = tb_ray_make(tb_vec3_make(-1.5f, -20.0f, 10.0f), tb_vec3_make(0, 1, 0), 0.0f, INFINITY);
    tb_hit h;
    assert_true(tb_scene_intersect(s, &r, &h));
    assert_int_equal(h.object, 7);
    const tb_object *leaf = tb_scene_hit_leaf(s, &h, NULL);
    assert_ptr_equal(leaf, &u->children[0]);
    assert_true(tb_scene_attr_number(tb_scene_node_attr(s, leaf, "my_leaf"), 0.0) == 1.0);
    assert_true(tb_scene_attr_number(tb_scene_material_attr(s, leaf->material, "my_layer"), 0.0) == 7.0);
    /* 8 entries: a=d, b, c, e, f, g, u1, u2 (the union's own material is unused) */
    assert_int_equal(s->nmaterials, 8);
    tb_scene_free(s);
}

static void test_light_camera_attrs(void **state)
{
    (void)state;
    tb_scene *s = load_text(text);
    assert_int_equal(s->nlights, 2);
    assert_string_equal(tb_scene_attr_string(tb_scene_light_attr(s, 0, "my_shadow"), NULL), "soft");
    assert_true(tb_scene_attr_number(tb_scene_light_attr(s, 0, "my_samples"), 1.0) == 16.0);
    assert_null(tb_scene_light_attr(s, 1, "my_shadow"));
    assert_int_equal(tb_scene_light_attrs(s, 1).count, 0);
    assert_null(tb_scene_light_attr(s, 2, "my_shadow"));
    assert_null(tb_scene_light_attr(s, -1, "my_shadow"));
    assert_true(tb_scene_attr_number(tb_scene_camera_attr(s, "my_exposure"), 1.0) == 1.5);
    assert_string_equal(tb_scene_attr_string(tb_scene_camera_attr(s, "my_tonemap"), "linear"), "filmic");
    assert_int_equal(tb_scene_camera_attrs(s).count, 2);
    assert_null(tb_scene_camera_attr(s, "my_fstop"));
    tb_scene_free(s);

    /* attributes on a light that is not the first; no camera at all */
    s = load_text("mid 1\n"
                  "point_light { position = [0 0 5] }\n"
                  "spot_light { position = [0 0 5] my_gobo = file(\"cornell-box.mid\") }\n"
                  "sphere {}\n");
    assert_null(tb_scene_light_attr(s, 0, "my_gobo"));
    assert_string_equal(tb_scene_light_attr(s, 1, "my_gobo")->ref.text, "cornell-box.mid");
    assert_int_equal(tb_scene_camera_attrs(s).count, 0);
    assert_null(tb_scene_camera_attr(s, "my_exposure"));
    tb_scene_free(s);
}

static void assert_node_has_none(const tb_scene *s, const tb_object *o)
{
    assert_int_equal(tb_scene_node_attrs(s, o, false).count, 0);
    assert_int_equal(tb_scene_node_attrs(s, o, true).count, 0);
    for (int i = 0; i < o->nchildren; i++)
        assert_node_has_none(s, &o->children[i]);
}

/* A scene without unknown attributes has none anywhere, and materials that
 * differ in nothing are still one entry. */
static void test_none(void **state)
{
    (void)state;
    static const char *const paths[] = {TB_SOURCE_DIR "/scenes/cornell-box.mid", TB_SOURCE_DIR "/scenes/materials.mid"};
    for (size_t k = 0; k < sizeof paths / sizeof *paths; k++) {
        tb_scene_options opt = {.no_accel = true};
        tb_scene *s;
        if (tb_scene_load(paths[k], &opt, &s))
            fail_msg("%s", tb_last_error());
        for (uint32_t i = 0; i < s->nobjects; i++)
            assert_node_has_none(s, s->objects[i]);
        for (int i = 0; i < s->nmaterials; i++)
            assert_int_equal(tb_scene_material_attrs(s, i).count, 0);
        for (int i = 0; i < s->nlights; i++)
            assert_int_equal(tb_scene_light_attrs(s, i).count, 0);
        assert_int_equal(tb_scene_camera_attrs(s).count, 0);
        tb_scene_free(s);
    }
    tb_scene *s = load_text("mid 1\n"
                            "sphere { rendering = { diffuse = 0.5 } }\n"
                            "sphere { transform = [translate([3 0 0])] rendering = { diffuse = 0.5 } }\n");
    assert_int_equal(s->nmaterials, 1);
    tb_scene_free(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_object_attrs),
        cmocka_unit_test(test_material_attrs),
        cmocka_unit_test(test_light_camera_attrs),
        cmocka_unit_test(test_none),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
