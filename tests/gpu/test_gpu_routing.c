/* Routing by feature mask (host/render/features.h, host/gpu/render.h): the
 * shading features of the materials of a small MID scene, which of them the
 * shade kernel's mask TB_GPU_SHADE_FEATURES routes to the CPU path (a colour
 * black in some places only) and which it keeps (a checker pattern), that a
 * feature taken off the mask routes its materials, and that the Vulkan
 * renderer routes exactly the materials the mask says. */
#include "tb_test.h"

#include <stdlib.h>
#include <string.h>

#include "gpu_test.h"
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_material_features),
        cmocka_unit_test(test_route_by_mask),
        cmocka_unit_test(test_renderer_routes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
