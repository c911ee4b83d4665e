/* Scale (issue 19, docs/performance.md "Scale"): a FED file that many objects
 * refer to is read once and held once; the memory accounting of a loaded
 * scene. */
#define _XOPEN_SOURCE 700 /* realpath */
#include "tb_test.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "host/object/intersect.h"
#include "host/render/scene.h"
#include "util/mesh/fed.h"
#include "util/stats/stats.h"

/* Writes a unit cube (6 quads, closed) as a text FED file in the test's
 * temporary directory; returns its absolute path in `path`. */
static void write_cube_fed(char *path, size_t n)
{
    static const tb_vec3 pos[8] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                   {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    static const uint32_t corners[24] = {0, 3, 2, 1, 4, 5, 6, 7, 0, 1, 5, 4,
                                         1, 2, 6, 5, 2, 3, 7, 6, 3, 0, 4, 7};
    static const uint32_t sizes[6] = {4, 4, 4, 4, 4, 4};
    tb_fed_desc d = {0};
    d.nverts = 8;
    d.positions = pos;
    d.nfaces = 6;
    d.nloops = 6;
    d.loop_sizes = sizes;
    d.corners = corners;
    tb_fed *fed;
    if (tb_fed_build(&d, &fed, NULL))
        fail_msg("%s", tb_last_error());
    assert_true(tb_fed_is_closed(fed));
    char dir[PATH_MAX];
    assert_non_null(realpath(tb_test_tmpdir(), dir));
    snprintf(path, n, "%s/scale_cube.fed", dir);
    assert_int_equal(tb_fed_write_file(path, fed, TB_FED_FORMAT_TEXT), TB_OK);
    tb_fed_free(fed);
}

/* MID text of `count` polygons objects on a row, each referring to `path`
 * (caller frees). */
static char *fed_scene_text(const char *path, int count)
{
    size_t cap = 256 + (size_t)count * (strlen(path) + 128);
    char *t = malloc(cap);
    assert_non_null(t);
    size_t n = (size_t)snprintf(t, cap, "mid 1\n");
    for (int i = 0; i < count; i++)
        n += (size_t)snprintf(t + n, cap - n,
                              "polygons { transform = [translate([-0.5 -0.5 0]) rotate([0 0 1], %d) translate([%d 0 0])] "
                              "geometry = { mesh = file(\"%s\") } }\n",
                              i % 90, 2 * i, path);
    return t;
}

static tb_scene *load_text(const char *text)
{
    FILE *fp = fmemopen((void *)text, strlen(text), "r");
    assert_non_null(fp);
    tb_scene *s;
    if (tb_scene_load_stream(fp, "scale.mid", NULL, NULL, &s))
        fail_msg("%s", tb_last_error());
    fclose(fp);
    return s;
}

static int64_t counter(const char *name)
{
    tb_stat_total t;
    assert_int_equal(tb_stats_get(name, TB_STAT_KIND_COUNTER, &t), TB_OK);
    return t.v[0];
}

/* One FED file referred to by 1000 objects: read once, one copy of its data
 * (the same bytes as for a single object), every object borrowing it, and
 * every object still hit exactly where an object built on its own is. */
static void test_fed_shared(void **state)
{
    (void)state;
    char path[PATH_MAX + 32];
    write_cube_fed(path, sizeof path);

    char *one_text = fed_scene_text(path, 1);
    int64_t reads0 = counter("Object/FED files read");
    tb_scene *one = load_text(one_text);
    free(one_text);
    assert_int_equal(counter("Object/FED files read") - reads0, 1);
    assert_int_equal(one->stats.fed_files, 1);
    size_t one_bytes = one->stats.fed_bytes;
    assert_true(one_bytes > 8 * sizeof(tb_vec3));

    char *text = fed_scene_text(path, 1000);
    int64_t reads1 = counter("Object/FED files read"), shared1 = counter("Object/FED references shared");
    tb_scene *s = load_text(text);
    free(text);
    assert_int_equal(s->nobjects, 1000);
    assert_int_equal(counter("Object/FED files read") - reads1, 1);
    assert_int_equal(counter("Object/FED references shared") - shared1, 999);
    assert_int_equal(s->stats.fed_files, 1);
    assert_int_equal(s->stats.fed_bytes, one_bytes); /* one copy, not 1000 */
    assert_int_equal(s->stats.triangles, 1000 * 12);
    for (uint32_t i = 1; i < s->nobjects; i++) {
        assert_ptr_equal(s->objects[i]->fed->fed, s->objects[0]->fed->fed);
        assert_ptr_equal(s->objects[i]->geom.polygons.vertices, s->objects[0]->geom.polygons.vertices);
    }
    /* Each object where its transform puts it, hit as an unshared copy is. */
    for (uint32_t i = 0; i < s->nobjects; i += 97) {
        tb_ray r = tb_ray_make((tb_vec3){2.0f * (float)i + 0.01f, 0.013f, 5.0f}, (tb_vec3){0, 0, -1}, 0, INFINITY);
        tb_hit h, ho;
        assert_true(tb_scene_intersect(s, &r, &h));
        assert_int_equal(h.object, i);
        assert_true(tb_object_intersect(one->objects[0], &r, &ho) ==
                    (i == 0));
        if (i == 0) {
            assert_true(h.t == ho.t);
            assert_int_equal(h.face, ho.face);
        }
    }
    /* The objects own their references: freeing the scenes in either order is clean (ASan/LSan). */
    tb_scene_free(one);
    tb_scene_free(s);
}

/* A missing FED file is an error naming it, also when shared. */
static void test_fed_missing(void **state)
{
    (void)state;
    const char *text = "mid 1\npolygons { geometry = { mesh = file(\"/nonexistent/scale.fed\") } }\n"
                       "polygons { geometry = { mesh = file(\"/nonexistent/scale.fed\") } }\n";
    FILE *fp = fmemopen((void *)text, strlen(text), "r");
    assert_non_null(fp);
    tb_scene *s = (tb_scene *)0x1;
    assert_int_not_equal(tb_scene_load_stream(fp, "missing.mid", NULL, NULL, &s), TB_OK);
    fclose(fp);
    assert_null(s);
    assert_non_null(strstr(tb_last_error(), "missing.mid:2:"));
    assert_non_null(strstr(tb_last_error(), "scale.fed"));
}

/* Writes `count` spheres (one in ten emitting, a cylinder in every fifth
 * place) as a MID file in the temporary directory; returns its path. */
static void write_spheres(char *path, size_t n, int count)
{
    char dir[PATH_MAX];
    assert_non_null(realpath(tb_test_tmpdir(), dir));
    snprintf(path, n, "%s/scale_spheres_%d.mid", dir, count);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "mid 1\ncamera { eye = [0 -10 3] look_at = [0 0 0] up = [0 0 1] resolution = [32 24] }\n");
    for (int i = 0; i < count; i++)
        fprintf(f, "%s { transform = [scale(0.4) translate([%d %d 0])] rendering = { diffuse = %.3f%s } }\n",
                i % 5 == 4 ? "cylinder" : "sphere", i % 100, i / 100, 0.1 + 0.001 * (i % 7),
                i % 10 == 0 ? " emission = 2" : "");
    assert_int_equal(fclose(f), 0);
}

/* --memory-budget: a scene predicted over the budget is refused before any
 * object is built, the message saying what takes the memory; under it, the
 * scene loads and takes no more than was predicted. */
static void test_budget(void **state)
{
    (void)state;
    char path[PATH_MAX + 64];
    write_spheres(path, sizeof path, 2000);
    tb_scene_memory_use pred;
    assert_int_equal(tb_scene_predict_memory(path, &pred), TB_OK);
    assert_int_equal(pred.nobjects, 2000);
    assert_true(pred.objects > 2000 * sizeof(tb_object));
    assert_true(pred.emitters > 0); /* 200 emitting objects, the cylinders tessellated */

    tb_scene_options opt = {.memory_budget = pred.total / 2};
    int64_t built = counter("Scene/sphere objects");
    tb_scene *s = (tb_scene *)0x1;
    assert_int_equal(tb_scene_load(path, &opt, &s), TB_ERR_NOMEM);
    assert_null(s);
    const char *msg = tb_last_error();
    assert_non_null(strstr(msg, "more than the memory budget"));
    assert_non_null(strstr(msg, "objects"));
    assert_non_null(strstr(msg, "2000 objects"));
    assert_non_null(strstr(msg, "emitters"));
    assert_non_null(strstr(msg, "nothing was loaded"));
    assert_int_equal(counter("Scene/sphere objects"), built); /* refused before building any */

    opt.memory_budget = pred.total + 1;
    assert_int_equal(tb_scene_load(path, &opt, &s), TB_OK);
    tb_scene_memory_use got;
    tb_scene_memory(s, &got);
    assert_int_equal(got.nobjects, 2000);
    /* The prediction holds the loaded parts (the acceleration at its build peak). */
    assert_true(got.objects <= pred.objects && got.objects * 2 > pred.objects);
    assert_true(got.prims + got.accel <= pred.prims + pred.accel);
    assert_true(got.emitters <= pred.emitters);
    assert_true(got.total <= pred.total);
    assert_true(got.per_object > 0.0 && got.per_object < 2000.0);
    tb_scene_free(s);
}

/* Without a pass to predict from (a stream), the load stops cleanly once it
 * has taken more than the budget, at the object that crossed it. */
static void test_budget_stream(void **state)
{
    (void)state;
    char *text = malloc(64 * 1000 + 64);
    assert_non_null(text);
    size_t n = (size_t)sprintf(text, "mid 1\n");
    for (int i = 0; i < 1000; i++)
        n += (size_t)sprintf(text + n, "sphere { transform = [translate([%d 0 0])] }\n", 3 * i);
    FILE *fp = fmemopen(text, n, "r");
    assert_non_null(fp);
    tb_scene_options opt = {.memory_budget = 100 * 1000};
    tb_scene *s = (tb_scene *)0x1;
    assert_int_equal(tb_scene_load_stream(fp, "budget.mid", NULL, &opt, &s), TB_ERR_NOMEM);
    fclose(fp);
    free(text);
    assert_null(s);
    const char *msg = tb_last_error();
    assert_non_null(strstr(msg, "budget.mid:"));
    assert_non_null(strstr(msg, "more than the memory budget"));
    assert_non_null(strstr(msg, "nothing was rendered"));
}

/* The accounting: bytes per object and per triangle of a loaded scene. */
static void test_memory_accounting(void **state)
{
    (void)state;
    char path[PATH_MAX + 32];
    write_cube_fed(path, sizeof path);
    char text[PATH_MAX + 512];
    snprintf(text, sizeof text,
             "mid 1\nsphere {}\ncube { transform = [translate([3 0 0])] }\n"
             "polygons { transform = [translate([6 0 0])] geometry = { mesh = file(\"%s\") } }\n"
             "polygons { geometry = { vertices = [[0 0 5] [1 0 5] [1 1 5]] faces = [[0 1 2]] } }\n",
             path);
    tb_scene *s = load_text(text);
    tb_scene_memory_use m;
    tb_scene_memory(s, &m);
    assert_int_equal(m.nobjects, 2);
    assert_int_equal(m.triangles, 13);
    assert_true(m.objects >= 2 * sizeof(tb_object));
    assert_true(m.meshes > 13 * (3 * sizeof(uint32_t) + sizeof(tb_vec3)));
    assert_int_equal(m.fed, s->stats.fed_bytes);
    /* The scene's reference array is dropped once the structure holds its copy. */
    assert_true(m.accel > 15 * sizeof(tb_accel_prim) && m.prims == 0 && s->prims == NULL && s->nprims == 15);
    assert_int_equal(m.total, m.objects + m.meshes + m.fed + m.materials + m.emitters + m.lights + m.prims + m.accel);
    assert_true(m.per_object > (double)sizeof(tb_object) && m.per_object < 4096.0);
    assert_true(m.per_triangle > 0.0);
    /* The two shares divide the objects, meshes and structure between them, nothing left out or counted twice. */
    double shared = m.per_object * (double)m.nobjects + m.per_triangle * (double)m.triangles;
    assert_true(fabs(shared - (double)(m.objects + m.meshes + m.prims + m.accel)) < 1e-6 * shared);
    /* The references are made again, bit for bit, from the objects: as a
     * load without a structure keeps them, and a rebuild finds them. */
    tb_accel_prim *again;
    assert_int_equal(tb_scene_refs(s, &again), TB_OK);
    FILE *fp = fmemopen((void *)text, strlen(text), "r");
    assert_non_null(fp);
    tb_scene_options o = {.no_accel = true};
    tb_scene *kept;
    assert_int_equal(tb_scene_load_stream(fp, "scale.mid", NULL, &o, &kept), TB_OK);
    fclose(fp);
    assert_int_equal(kept->nprims, 15);
    assert_non_null(kept->prims);
    assert_memory_equal(again, kept->prims, 15 * sizeof *again);
    tb_scene_free(kept);
    free(again);
    assert_int_equal(tb_scene_rebuild_accel(s, TB_ACCEL_GRID, NULL), TB_OK);
    assert_null(s->prims);
    tb_scene_memory_use z;
    tb_scene_memory(NULL, &z);
    assert_int_equal(z.total, 0);
    tb_scene_free(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fed_shared),
        cmocka_unit_test(test_fed_missing),
        cmocka_unit_test(test_budget),
        cmocka_unit_test(test_budget_stream),
        cmocka_unit_test(test_memory_accounting),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
