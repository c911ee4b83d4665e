/* Scale (issue 19, docs/performance.md "Scale"): a FED file that many objects
 * refer to is read once and held once; the memory accounting of a loaded
 * scene. */
#define _XOPEN_SOURCE 700 /* realpath */
#include "tb_test.h"

#include <limits.h>
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
        assert_ptr_equal(s->objects[i]->fed, s->objects[0]->fed);
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fed_shared),
        cmocka_unit_test(test_fed_missing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
