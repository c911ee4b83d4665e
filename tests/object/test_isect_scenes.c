/* The bundled MID scenes through the streaming reader and the object level:
 * every object is built while the reader moves on (so the deep copy is what
 * survives), then 64 x 64 camera rays find their closest hit over all
 * objects. Checks: everything builds; every hit gives its hit point back;
 * object indices are the MID order; in the Cornell box, whose walls face
 * into the box and whose blocks face out of themselves, the camera sees
 * front sides only (ng . d < 0) and over 90% of the rays hit. */
#include "test_isect_common.h"

#include "host/object/hit.h"
#include "host/object/intersect.h"
#include "host/mid/mid_reader.h"
#include "util/math/float.h"

typedef struct ti_scene_stats {
    long objects, rays, hits, front, points;
} ti_scene_stats;

static ti_scene_stats ti_run_scene(const char *name)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/scenes/%s", TB_SOURCE_DIR, name);
    tb_mid_reader *r = NULL;
    if (tb_mid_reader_open(&r, path))
        fail_msg("%s: %s", name, tb_last_error());
    tb_object **objs = NULL;
    long n = 0, cap = 0;
    tb_mid_item it;
    tb_status st;
    while (!(st = tb_mid_reader_next(r, &it)) && it.type != TB_MID_ITEM_END) {
        if (it.type != TB_MID_ITEM_OBJECT)
            continue;
        if (n == cap) {
            cap = cap ? 2 * cap : 16;
            objs = realloc(objs, sizeof *objs * (size_t)cap);
            assert_non_null(objs);
        }
        tb_object *o = NULL;
        if (tb_object_from_mid(it.object, (uint32_t)n, NULL, NULL, &o))
            fail_msg("%s: object %ld: %s", name, n, tb_last_error());
        objs[n++] = o;
    }
    assert_int_equal(st, TB_OK);
    const tb_mid_camera *cam = tb_mid_reader_camera(r);
    assert_non_null(cam);
    tb_transform c2w;
    assert_int_equal(tb_transform_look_at(cam->eye, cam->look_at, cam->up, &c2w), TB_OK);
    double th = tan(0.5 * cam->fov * TI_PI / 180.0), aspect = (double)cam->width / cam->height;
    ti_scene_stats S = {n, 0, 0, 0, 0};
    enum { RES = 64 };
    for (int j = 0; j < RES; j++)
        for (int i = 0; i < RES; i++) {
            double x = (2.0 * (i + 0.5) / RES - 1.0) * th * aspect, y = (1.0 - 2.0 * (j + 0.5) / RES) * th;
            tb_dvec3 d = tb_transform_dvector(&c2w, (tb_dvec3){x, y, -1.0});
            tb_ray ray = tb_ray_make((tb_vec3){(float)cam->eye.x, (float)cam->eye.y, (float)cam->eye.z},
                                     (tb_vec3){(float)d.x, (float)d.y, (float)d.z}, 0.0f, INFINITY);
            tb_hit h, best;
            long which = -1;
            for (long k = 0; k < n; k++)
                if (tb_object_intersect(objs[k], &ray, &h)) {
                    ray.tmax = h.t;
                    best = h;
                    which = k;
                }
            S.rays++;
            if (which < 0)
                continue;
            S.hits++;
            assert_int_equal(best.object, (uint32_t)which);
            if (best.ng.x * ray.d.x + best.ng.y * ray.d.y + best.ng.z * ray.d.z < 0.0f)
                S.front++;
            tb_vec3 p, perr;
            if (tb_object_hit_point(objs[which], &ray, &best, &p, &perr))
                S.points++;
        }
    for (long k = 0; k < n; k++)
        tb_object_free(objs[k]);
    free(objs);
    tb_mid_reader_close(r);
    print_message("[ %-19s ] %ld objects, %ld rays: %ld hits, %ld on front sides, %ld hit points recomputed\n", name,
                  S.objects, S.rays, S.hits, S.front, S.points);
    return S;
}

static void test_scenes(void **state)
{
    (void)state;
    ti_scene_stats s = ti_run_scene("cornell-box.mid");
    assert_true(s.objects >= 7);
    assert_true(s.hits > s.rays * 90 / 100); /* the image corners see past the open front */
    assert_int_equal(s.front, s.hits);
    assert_int_equal(s.points, s.hits);
    s = ti_run_scene("cornell-box-rgb.mid");
    assert_int_equal(s.front, s.hits);
    assert_int_equal(s.points, s.hits);
    /* The spheres variant: the mirror and glass spheres are closed, seen from outside. */
    s = ti_run_scene("cornell-box-spheres.mid");
    assert_true(s.objects >= 8);
    assert_int_equal(s.front, s.hits);
    assert_int_equal(s.points, s.hits);
    const char *others[] = {"radiosity-room.mid", "showcase.mid"};
    for (int i = 0; i < 2; i++) {
        s = ti_run_scene(others[i]);
        assert_true(s.objects > 0 && s.hits > 0);
        assert_int_equal(s.points, s.hits);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_scenes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
