/* Rays with NaN or infinite components, a zero direction, a NaN range or
 * tmin > tmax are rejected cleanly by every kind and by CSG: no hit, no
 * occlusion, no hit point, no intervals, the hit record untouched, and each
 * rejected query counted once in "Intersect/invalid rays". A ray at the edge
 * of validity (tmax = +inf, denormal direction, tmin == tmax) is traced. */
#include "test_isect_common.h"

#include "host/object/csg.h"
#include "host/object/intersect.h"
#include "util/stats/stats.h"

static int64_t ti_invalid_count(void)
{
    tb_stat_total t;
    if (tb_stats_get("Intersect/invalid rays", TB_STAT_KIND_COUNTER, &t) != TB_OK)
        return 0;
    return t.v[0];
}

/* One object of every kind (and a CSG tree and a mesh). */
static int ti_all_objects(tb_object **objs, ti_mesh *mesh)
{
    int n = 0;
    for (int k = TB_PRIM_SPHERE; k <= TB_PRIM_ROUND_ARCH; k++) {
        tb_mid_geometry g = tb_mid_geometry_default((tb_prim_kind)k);
        if (k == TB_PRIM_POLYGONS)
            g = ti_mesh_geom(mesh);
        tb_mid_object m = ti_prim((tb_prim_kind)k, g, tb_transform_identity());
        objs[n] = ti_build(&m, (uint32_t)n);
        n++;
    }
    tb_transform id = tb_transform_identity();
    tb_mid_object kids[2] = {ti_prim(TB_PRIM_CUBE, tb_mid_geometry_default(TB_PRIM_CUBE), id),
                             ti_prim(TB_PRIM_SPHERE, tb_mid_geometry_default(TB_PRIM_SPHERE), id)};
    tb_mid_object d = ti_csg(TB_PRIM_DIFFERENCE, kids, 2, id);
    objs[n] = ti_build(&d, (uint32_t)n);
    n++;
    return n;
}

static void test_invalid_rays(void **state)
{
    (void)state;
    ti_mesh mesh = ti_cube_mesh(2);
    tb_object *objs[16];
    int nobj = ti_all_objects(objs, &mesh);
    const float nan = NAN, inf = INFINITY;
    /* A valid ray through every object, then one bad field at a time. */
    tb_ray good = tb_ray_make((tb_vec3){-5.0f, 0.1f, 0.05f}, (tb_vec3){1.0f, 0.0f, 0.0f}, 0.0f, inf);
    tb_ray bad[32];
    int nb = 0;
    for (int c = 0; c < 3; c++) {
        float vals[3] = {nan, inf, -inf};
        for (int v = 0; v < 3; v++) {
            tb_ray r = good;
            float *o = c == 0 ? &r.o.x : (c == 1 ? &r.o.y : &r.o.z);
            *o = vals[v];
            bad[nb++] = r;
            r = good;
            float *d = c == 0 ? &r.d.x : (c == 1 ? &r.d.y : &r.d.z);
            *d = vals[v];
            bad[nb++] = r;
        }
    }
    tb_ray r = good;
    r.d = (tb_vec3){0.0f, 0.0f, 0.0f};
    bad[nb++] = r;
    r.d = (tb_vec3){-0.0f, 0.0f, -0.0f};
    bad[nb++] = r;
    r = good;
    r.tmin = nan;
    bad[nb++] = r;
    r = good;
    r.tmax = nan;
    bad[nb++] = r;
    r = good;
    r.tmin = 2.0f;
    r.tmax = 1.0f;
    bad[nb++] = r;
    r = good;
    r.tmin = -inf;
    bad[nb++] = r;

    tb_stats_set_enabled(1);
    int64_t before = ti_invalid_count();
    int64_t calls = 0;
    for (int i = 0; i < nobj; i++) {
        tb_hit h0;
        assert_true(tb_object_intersect(objs[i], &good, &h0));
        for (int b = 0; b < nb; b++) {
            tb_hit h;
            memset(&h, 0xab, sizeof h);
            tb_hit copy = h;
            if (tb_object_intersect(objs[i], &bad[b], &h))
                fail_msg("object %d (%s): bad ray %d gave a hit", i, tb_prim_kind_name(objs[i]->kind), b);
            assert_memory_equal(&h, &copy, sizeof h);
            assert_false(tb_object_occluded(objs[i], &bad[b]));
            calls += 2;
            tb_vec3 p = {7, 7, 7}, e = {7, 7, 7};
            assert_false(tb_object_hit_point(objs[i], &bad[b], &h0, &p, &e));
            assert_true(p.x == 7.0f && e.x == 7.0f);
            float a[2], z[2];
            assert_int_equal(tb_object_intervals(objs[i], &bad[b], a, z, 2), 0);
        }
    }
    int64_t counted = ti_invalid_count() - before;
    print_message("%d objects x %d bad rays: %lld rejections counted\n", nobj, nb, (long long)counted);
    assert_int_equal(counted, calls);

    /* Borderline but valid. */
    for (int i = 0; i < nobj; i++) {
        tb_hit h;
        r = good;
        r.d = (tb_vec3){1e-37f, 0.0f, 0.0f}; /* a tiny direction: t is huge, but finite */
        assert_true(tb_object_intersect(objs[i], &r, &h));
        assert_true(isfinite(h.t) && h.t > 1e37f);
        r = good;
        assert_true(tb_object_intersect(objs[i], &good, &h));
        r.tmin = r.tmax = h.t; /* a one-point range */
        tb_hit h2;
        if (!tb_object_intersect(objs[i], &r, &h2))
            fail_msg("%s: no hit on the one-point range [%.9g, %.9g]", tb_prim_kind_name(objs[i]->kind), r.tmin, r.tmax);
        assert_true(h2.t == h.t);
    }
    for (int i = 0; i < nobj; i++)
        tb_object_free(objs[i]);
    ti_mesh_free(&mesh);
}

/* NULL arguments are refused without a crash. */
static void test_null_arguments(void **state)
{
    (void)state;
    tb_mid_object m = ti_prim(TB_PRIM_SPHERE, tb_mid_geometry_default(TB_PRIM_SPHERE), tb_transform_identity());
    tb_object *o = ti_build(&m, 0);
    tb_ray r = tb_ray_make((tb_vec3){0, 0, -5}, (tb_vec3){0, 0, 1}, 0.0f, INFINITY);
    tb_hit h;
    assert_false(tb_object_intersect(NULL, &r, &h));
    assert_false(tb_object_intersect(o, NULL, &h));
    assert_false(tb_object_occluded(NULL, &r));
    assert_false(tb_object_occluded(o, NULL));
    tb_object *o2 = o;
    assert_int_equal(tb_object_from_mid(NULL, 0, NULL, NULL, &o2), TB_ERR_ARG);
    assert_null(o2);
    tb_object_free(NULL);
    tb_object_free(o);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_invalid_rays),
        cmocka_unit_test(test_null_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
