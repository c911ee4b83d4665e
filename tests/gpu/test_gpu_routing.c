/* Routing by feature mask (host/render/features.h, host/gpu/render.h,
 * host/gpu/intersect.h). Materials: the shading features of the materials of
 * a small MID scene, which of them the shade kernel's mask
 * TB_GPU_SHADE_FEATURES routes to the CPU path (a colour black in some places
 * only) and which it keeps (a checker pattern), that a feature taken off the
 * mask routes its materials, and that the Vulkan renderer routes exactly the
 * materials the mask says. Objects: the object features of one object of
 * every primitive kind and of CSG trees, and that the intersect kernel's
 * scene routes exactly the objects with a feature outside its mask (quadrics
 * under each tb_gpu_quadrics mode), with hits equal to the CPU path's. */
#include "tb_test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gpu_test.h"
#include "host/gpu/intersect.h"
#include "host/gpu/render.h"
#include "host/render/features.h"
#include "host/render/raytrace.h"

/* Materials 0 .. 5 in this order (each used by one object, so none is merged). */
static const char *const tb__scene =
    "mid 1.1\n"
    "polygons \"plain\" { geometry = { vertices = [[-4 -4 0] [0 -4 0] [0 0 0] [-4 0 0]] faces = [[0 1 2 3]] }"
    " rendering = { diffuse = 0.5 } }\n"
    "polygons \"blinn\" { geometry = { vertices = [[0 -4 0] [4 -4 0] [4 0 0] [0 0 0]] faces = [[0 1 2 3]] }"
    " rendering = { diffuse = 0.3 specular = 0.4 exponent = 30 model = blinn } }\n"
    "polygons \"ggx\" { geometry = { vertices = [[-4 0 0] [0 0 0] [0 4 0] [-4 4 0]] faces = [[0 1 2 3]] }"
    " rendering = { diffuse = 0 specular = [1 0.78 0.34] model = ggx roughness = 0.3 } }\n"
    "polygons \"checker\" { geometry = { vertices = [[0 0 0] [4 0 0] [4 4 0] [0 4 0]] faces = [[0 1 2 3]] }"
    " rendering = { diffuse = 1 diffuse_pattern = checker(3, 0.2, [0.9 0.7 0.5]) } }\n"
    "polygons \"black check\" { geometry = { vertices = [[0 0 1] [4 0 1] [4 4 1] [0 4 1]] faces = [[0 1 2 3]] }"
    " rendering = { diffuse = 1 diffuse_pattern = checker(3, 0, 0.9) } }\n"
    "polygons \"lamp\" { geometry = { vertices = [[-0.5 -0.5 3] [-0.5 0.5 3] [0.5 0.5 3] [0.5 -0.5 3]]"
    " faces = [[0 1 2 3]] } rendering = { diffuse = 0 emission = [10 8 6] } }\n";

enum { TB__PLAIN, TB__BLINN, TB__GGX, TB__CHECKER, TB__BLACK_CHECK, TB__LAMP, TB__NMAT };

/* The lamp's kind of emitter, as every lit material sees it. */
#define TB__LIT (TB_FEAT_LIT_TRIANGLE | TB_FEAT_LIT_PARALLELOGRAM)

static tb_scene *tb__load(void)
{
    tb_scene *s = gpu_test_load(tb__scene, "routing.mid", NULL);
    assert_int_equal(s->nmaterials, TB__NMAT);
    return s;
}

static void tb__features(const tb_scene *s, uint32_t f[TB__NMAT])
{
    tb_raytracer rt;
    if (tb_rt_init(&rt, s, NULL))
        fail_msg("tracer: %s", tb_last_error());
    tb_material_features(&rt, f);
    tb_rt_release(&rt);
}

/* The masks: colours, models, patterns, emission and the emitter kind the
 * lit materials sample, nothing more. */
static void test_material_features(void **state)
{
    (void)state;
    tb_scene *s = tb__load();
    uint32_t f[TB__NMAT];
    tb__features(s, f);
    uint32_t lit = f[TB__PLAIN] & TB__LIT;
    assert_true(lit != 0 && (lit & (lit - 1)) == 0); /* one emitter kind */
    assert_int_equal(f[TB__PLAIN], TB_FEAT_DIFFUSE | lit);
    assert_int_equal(f[TB__BLINN], TB_FEAT_DIFFUSE | TB_FEAT_SPECULAR | TB_FEAT_BLINN | lit);
    assert_int_equal(f[TB__GGX], TB_FEAT_SPECULAR | TB_FEAT_GGX | lit);
    assert_int_equal(f[TB__CHECKER], TB_FEAT_DIFFUSE | TB_FEAT_PATTERN_CHECKER | lit);
    /* a checker with a black square: black in some places only, not lit as a whole */
    assert_int_equal(f[TB__BLACK_CHECK], TB_FEAT_VARYING_BLACK | TB_FEAT_PATTERN_CHECKER);
    assert_int_equal(f[TB__LAMP], TB_FEAT_EMISSION);
    for (int i = 0; i < TB__NMAT; i++)
        for (uint32_t b = f[i]; b; b &= b - 1)
            assert_non_null(tb_feature_name(tb_feature_first(b)));
    tb_scene_free(s);
}

/* A feature outside the mask routes, one inside does not; taking a feature
 * off the mask routes the materials that use it, and only those. */
static void test_route_by_mask(void **state)
{
    (void)state;
    tb_scene *s = tb__load();
    uint32_t f[TB__NMAT];
    tb__features(s, f);
    const uint32_t gpu = TB_GPU_SHADE_FEATURES;
    assert_false(gpu & TB_FEAT_VARYING_BLACK);
    assert_true(gpu & TB_FEAT_PATTERN_CHECKER);
    for (int i = 0; i < TB__NMAT; i++) {
        const char *why = tb_gpu_route_reason(f[i], gpu);
        if (i == TB__BLACK_CHECK) {
            assert_non_null(why);
            assert_non_null(strstr(why, "black in some places"));
        } else if (why) {
            fail_msg("material %d (features 0x%x) routed: %s", i, (unsigned)f[i], why);
        }
    }
    const uint32_t no_checker = gpu & ~(uint32_t)TB_FEAT_PATTERN_CHECKER;
    const char *why = tb_gpu_route_reason(f[TB__CHECKER], no_checker);
    assert_non_null(why);
    assert_string_equal(why, tb_feature_name(TB_FEAT_PATTERN_CHECKER));
    assert_null(tb_gpu_route_reason(f[TB__PLAIN], no_checker));
    assert_null(tb_gpu_route_reason(f[TB__GGX], no_checker));
    /* the first unsupported feature in TB_FEATURES order names the reason */
    assert_non_null(strstr(tb_gpu_route_reason(f[TB__BLACK_CHECK], no_checker), "black in some places"));
    tb_scene_free(s);
}

/* The renderer routes what the mask routes. */
static void test_renderer_routes(void **state)
{
    (void)state;
    gpu_test_env e;
    gpu_test_open(&e, NULL);
    tb_scene *s = tb__load();
    uint32_t f[TB__NMAT];
    tb__features(s, f);
    tb_gpu_renderer *r;
    if (tb_gpu_renderer_create(e.dev, s, NULL, &r))
        fail_msg("renderer: %s", tb_last_error());
    for (int i = 0; i < TB__NMAT; i++) {
        const char *want = tb_gpu_route_reason(f[i], TB_GPU_SHADE_FEATURES);
        const char *got = tb_gpu_renderer_material_route(r, i);
        assert_int_equal(want != NULL, got != NULL);
        if (want)
            assert_non_null(strstr(got, want));
    }
    tb_gpu_render_stats gs;
    tb_gpu_renderer_stats(r, &gs);
    assert_int_equal(gs.routed_materials, 1);
    assert_non_null(strstr(gs.routed_reason, "material 4"));
    tb_gpu_renderer_destroy(r);
    tb_scene_free(s);
    gpu_test_close(&e);
}

/* Objects 0 .. 13 in this order along x (3 apart), each under a downward
 * ray at (x + dx, 0): every primitive kind, then CSG trees (the difference's
 * hollow and the torus's hole are off the rays). */
static const char *const tb__objects =
    "mid 1.1\n"
    "polygons \"quad\" { geometry = { vertices = [[-1 -1 0] [1 -1 0] [1 1 0] [-1 1 0]] faces = [[0 1 2 3]] } }\n"
    "sphere \"ball\" { transform = [translate([3 0 0])] }\n"
    "cube \"box\" { transform = [translate([6 0 0])] }\n"
    "cylinder \"can\" { transform = [translate([9 0 0])] }\n"
    "cone \"cone\" { transform = [translate([12 0 0])] geometry = { top_radius = 0.5 } }\n"
    "conic \"egg\" { transform = [translate([15 0 0])] geometry = { coefficients = [1 0 -1] z_range = [-1 1] } }\n"
    "pyramid \"pyramid\" { transform = [translate([18 0 0])] geometry = { top = 0.5 } }\n"
    "prism \"hex\" { transform = [translate([21 0 0])] geometry = { sides = 6 } }\n"
    "torus \"ring\" { transform = [translate([24 0 0])] geometry = { major = 1 minor = 0.25 } }\n"
    "square_arch \"gate\" { transform = [translate([27 0 0])] geometry = { width = 1.2 height = 1.5 } }\n"
    "round_arch \"arch\" { transform = [translate([30 0 0])] geometry = { width = 1 height = 1.5 } }\n"
    "union \"snowman\" { transform = [translate([33 0 0])] sphere { } sphere { transform = [translate([0 0 1])] } }\n"
    "difference \"cup\" { transform = [translate([36 0 0])] cube { } sphere { transform = [scale(0.5)] } }\n"
    "intersection \"die\" { transform = [translate([39 0 0])] cube { }"
    " union { cylinder { transform = [scale([1 1 2])] } torus { geometry = { major = 1 minor = 0.5 } } } }\n";

enum { TB__NOBJ = 14 };

/* Each object's features, in MID order. */
static const uint32_t tb__object_want[TB__NOBJ] = {
    TB_OBJ_FEAT_TRIANGLES,
    TB_OBJ_FEAT_SPHERE,
    TB_OBJ_FEAT_CUBE,
    TB_OBJ_FEAT_CYLINDER,
    TB_OBJ_FEAT_CONE,
    TB_OBJ_FEAT_CONIC,
    TB_OBJ_FEAT_PYRAMID,
    TB_OBJ_FEAT_PRISM,
    TB_OBJ_FEAT_TORUS,
    TB_OBJ_FEAT_SQUARE_ARCH,
    TB_OBJ_FEAT_ROUND_ARCH,
    TB_OBJ_FEAT_CSG_UNION | TB_OBJ_FEAT_SPHERE,
    TB_OBJ_FEAT_CSG_DIFFERENCE | TB_OBJ_FEAT_CUBE | TB_OBJ_FEAT_SPHERE,
    TB_OBJ_FEAT_CSG_INTERSECTION | TB_OBJ_FEAT_CSG_UNION | TB_OBJ_FEAT_CUBE | TB_OBJ_FEAT_CYLINDER |
        TB_OBJ_FEAT_TORUS,
};

/* The masks: one kind's bit per primitive, a CSG tree's operations and
 * leaves; every bit named; the reasons name the first unsupported feature. */
static void test_object_features(void **state)
{
    (void)state;
    tb_scene *s = gpu_test_load(tb__objects, "objects.mid", NULL);
    assert_int_equal(s->nobjects, TB__NOBJ);
    uint32_t f[TB__NOBJ];
    tb_object_features(s, f);
    uint32_t seen = 0;
    for (int i = 0; i < TB__NOBJ; i++) {
        if (f[i] != tb__object_want[i])
            fail_msg("object %d: features 0x%x, want 0x%x", i, (unsigned)f[i], (unsigned)tb__object_want[i]);
        seen |= f[i];
        for (uint32_t b = f[i]; b; b &= b - 1)
            assert_non_null(tb_object_feature_name(tb_feature_first(b)));
    }
    /* every kind of the scene, i.e. every bit but the unmeshed polygons' */
    assert_int_equal(seen, TB_OBJ_FEAT_ALL & ~(uint32_t)TB_OBJ_FEAT_POLYGONS_UNMESHED);
    assert_null(tb_object_feature_name(0));
    assert_null(tb_object_feature_name(TB_OBJ_FEAT_SPHERE | TB_OBJ_FEAT_CUBE));
    /* the kernel's mask: every primitive kind and CSG tree */
    const uint32_t gpu = TB_GPU_INTERSECT_FEATURES, cpu_quadrics = gpu & ~TB_GPU_QUADRIC_FEATURES;
    for (int i = 0; i < TB__NOBJ; i++)
        assert_null(tb_gpu_object_route_reason(f[i], gpu));
    /* unmeshed polygons stay outside the mask, named */
    assert_string_equal(tb_gpu_object_route_reason(TB_OBJ_FEAT_POLYGONS_UNMESHED, gpu),
                        "polygons without a triangle mesh");
    /* quadrics off the mask: routed, saying why */
    assert_non_null(strstr(tb_gpu_object_route_reason(f[3], cpu_quadrics), "quadrics on the CPU path"));
    assert_non_null(strstr(tb_gpu_object_route_reason(f[5], cpu_quadrics), "conic"));
    assert_null(tb_gpu_object_route_reason(f[2], cpu_quadrics));
    tb_scene_free(s);
}

/* The GPU scene under one quadrics mode: routed exactly where the mask says,
 * the counts, and each object's ray hitting what the CPU path hits. */
static void tb__check_scene(gpu_test_env *e, const tb_scene *s, tb_gpu_quadrics mode, uint32_t want_supported)
{
    static const float dx[TB__NOBJ] = {0.25f, 0.25f, 0.25f, 0.25f, 0.25f, 0.25f, 0.25f,
                                       0.25f, 1.0f,  0.25f, 0.25f, 0.25f, 0.75f, 0.25f};
    uint32_t supported = tb_gpu_intersect_supported(e->dev, mode);
    assert_int_equal(supported, want_supported);
    tb_gpu_scene *g = tb_gpu_scene_create_ex(e->dev, s, &(tb_gpu_scene_desc){mode});
    if (!g)
        fail_msg("GPU scene: %s", tb_last_error());
    uint32_t f[TB__NOBJ], ngpu = 0;
    tb_object_features(s, f);
    for (uint32_t i = 0; i < TB__NOBJ; i++) {
        bool on_gpu = !(f[i] & ~supported);
        ngpu += on_gpu;
        if (tb_gpu_scene_object_on_gpu(g, i) != on_gpu)
            fail_msg("mode %d: object %u (features 0x%x) on the %s", (int)mode, i, (unsigned)f[i],
                     on_gpu ? "CPU" : "GPU");
        const char *why = tb_gpu_scene_object_route(g, i);
        assert_int_equal(why == NULL, on_gpu);
        if (why)
            assert_string_equal(why, tb_gpu_object_route_reason(f[i], supported));
    }
    assert_false(tb_gpu_scene_object_on_gpu(g, TB__NOBJ));
    assert_null(tb_gpu_scene_object_route(g, TB__NOBJ));
    bool quadrics = (supported & TB_GPU_QUADRIC_FEATURES) != 0;
    tb_gpu_scene_info info;
    tb_gpu_scene_get_info(g, &info);
    assert_int_equal(info.gpu_objects, ngpu);
    assert_int_equal(info.gpu_objects, quadrics ? 14 : 10); /* the die's cylinder routes it with the quadrics */
    assert_int_equal(info.cpu_objects, TB__NOBJ - ngpu);
    assert_int_equal(info.gpu_triangles, 2);
    assert_int_equal(info.gpu_spheres, 1);
    assert_int_equal(info.gpu_cubes, 1);
    assert_int_equal(info.gpu_quadrics, quadrics ? 3 : 0);
    assert_int_equal(info.gpu_planar, 4);
    assert_int_equal(info.gpu_tori, 1);
    assert_int_equal(info.gpu_csg, quadrics ? 3 : 2);
    tb_ray rays[TB__NOBJ];
    tb_hit hits[TB__NOBJ];
    for (int i = 0; i < TB__NOBJ; i++)
        rays[i] = (tb_ray){{3.0f * (float)i + dx[i], 0.0f, 5.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, INFINITY};
    if (tb_gpu_intersect(g, rays, TB__NOBJ, hits, NULL))
        fail_msg("intersect: %s", tb_last_error());
    for (uint32_t i = 0; i < TB__NOBJ; i++) {
        tb_hit want;
        assert_true(tb_scene_intersect(s, &rays[i], &want));
        assert_int_equal(want.object, i);
        if (hits[i].object != i || hits[i].face != want.face || fabsf(hits[i].t - want.t) > 1e-5f * want.t)
            fail_msg("mode %d: ray %u hit object %u face %u t %g, the CPU object %u face %u t %g", (int)mode, i,
                     hits[i].object, hits[i].face, (double)hits[i].t, want.object, want.face, (double)want.t);
    }
    tb_gpu_scene_destroy(g);
}

/* tb_gpu_scene_create_ex routes what the mask routes: quadrics into the
 * kernel under AUTO on every device (lavapipe included) and when forced, to
 * the CPU under CPU. */
static void test_objects_route(void **state)
{
    (void)state;
    gpu_test_env e;
    gpu_test_open(&e, NULL);
    tb_scene *s = gpu_test_load(tb__objects, "objects.mid", NULL);
    const uint32_t all = TB_GPU_INTERSECT_FEATURES, no_quadrics = all & ~TB_GPU_QUADRIC_FEATURES;
    tb__check_scene(&e, s, TB_GPU_QUADRICS_AUTO, all);
    tb__check_scene(&e, s, TB_GPU_QUADRICS_GPU, all);
    tb__check_scene(&e, s, TB_GPU_QUADRICS_CPU, no_quadrics);
    tb_scene_free(s);
    gpu_test_close(&e);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_material_features),
        cmocka_unit_test(test_route_by_mask),
        cmocka_unit_test(test_renderer_routes),
        cmocka_unit_test(test_object_features),
        cmocka_unit_test(test_objects_route),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
