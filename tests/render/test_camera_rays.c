/* The camera (host/render/camera.h) against values computed here from the
 * camera's definition: the published Cornell box camera (35 mm lens on a
 * 25 mm x 25 mm film: fov 2 atan(12.5 / 35) = 39.3076481 degrees on both
 * axes) maps the image corners and centre to the right world directions;
 * random cameras span exactly their fields of view with the image's right
 * and up where `up` and the view direction say; pinhole rays start at the
 * eye; thin-lens rays through one film point start on the lens and meet at
 * the point where the pinhole ray crosses the plane in focus; differentials
 * are the neighbours' rays; projection inverts ray generation. */
#include "tb_test.h"

#include <string.h>

#include "host/render/camera.h"
#include "host/mid/mid_reader.h"
#include "util/math/float.h"
#include "util/math/rng.h"

static tb_dvec3 dv(tb_vec3 v) { return (tb_dvec3){v.x, v.y, v.z}; }

/* Angle in degrees between two directions. */
static double angle_deg(tb_dvec3 a, tb_dvec3 b)
{
    double c = tb_dvec3_dot(a, b) / (tb_dvec3_length(a) * tb_dvec3_length(b));
    return acos(fmax(-1.0, fmin(1.0, c))) * 180.0 / TB_PI;
}

static void assert_dir(tb_vec3 got, tb_dvec3 want, double tol)
{
    tb_dvec3 w = tb_dvec3_normalize(want);
    tb_assert_near(got.x, w.x, tol);
    tb_assert_near(got.y, w.y, tol);
    tb_assert_near(got.z, w.z, tol);
}

static tb_mid_camera read_camera(const char *path)
{
    tb_mid_reader *r;
    if (tb_mid_reader_open(&r, path))
        fail_msg("%s", tb_last_error());
    tb_mid_item it;
    tb_status st;
    while (!(st = tb_mid_reader_next(r, &it)) && it.type != TB_MID_ITEM_END) {
    }
    assert_int_equal(st, TB_OK);
    const tb_mid_camera *c = tb_mid_reader_camera(r);
    assert_non_null(c);
    tb_mid_camera copy = *c;
    tb_mid_reader_close(r);
    copy.name = NULL;
    copy.extra = (tb_mid_attrs){NULL, 0};
    copy.refs = NULL;
    copy.nrefs = 0;
    return copy;
}

/* The Cornell box camera: eye (278, 273, -800) looking along +z with +y up,
 * so the image's right is world -x (the green wall at x = 0 is on the right). */
static void test_cornell_corners(void **state)
{
    (void)state;
    tb_mid_camera mc = read_camera(TB_SOURCE_DIR "/scenes/cornell-box.mid");
    tb_camera cam;
    assert_int_equal(tb_camera_from_mid(&mc, 0, 0, &cam), TB_OK);
    assert_int_equal(cam.width, 512);
    assert_int_equal(cam.height, 512);
    double fov = 2.0 * atan(12.5 / 35.0) * 180.0 / TB_PI;
    tb_assert_near(fov, 39.3076481, 5e-8); /* the published value, to its digits */
    tb_assert_near(cam.fov_y, fov, 1e-12);
    tb_assert_near(cam.fov_x, fov, 1e-12);
    double t = 12.5 / 35.0; /* tan of half the field of view */
    struct {
        double x, y;
        tb_dvec3 dir;
    } cases[] = {
        {0, 0, {t, t, 1}},      /* top left: +x is left, +y up */
        {512, 0, {-t, t, 1}},   /* top right */
        {0, 512, {t, -t, 1}},   /* bottom left */
        {512, 512, {-t, -t, 1}},/* bottom right */
        {256, 256, {0, 0, 1}},  /* centre: the view direction */
        {256, 0, {0, t, 1}},    /* middle of the top edge */
        {0, 256, {t, 0, 1}},    /* middle of the left edge */
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        tb_ray r = tb_camera_ray(&cam, cases[i].x, cases[i].y, 0.5f, 0.5f);
        assert_true(r.o.x == 278.0f && r.o.y == 273.0f && r.o.z == -800.0f);
        assert_true(r.tmin == 0.0f && isinf(r.tmax));
        assert_dir(r.d, cases[i].dir, 2e-7);
    }
    /* The centre ray is exactly the view direction. */
    tb_ray c = tb_camera_ray(&cam, 256, 256, 0.5f, 0.5f);
    assert_true(c.d.x == 0.0f && c.d.y == 0.0f && c.d.z == 1.0f);
    /* The opposite corners are the diagonal field of view apart. */
    tb_ray a = tb_camera_ray(&cam, 0, 0, 0, 0), b = tb_camera_ray(&cam, 512, 512, 0, 0);
    tb_assert_near(angle_deg(dv(a.d), dv(b.d)), 2.0 * atan(t * sqrt(2.0)) * 180.0 / TB_PI, 2e-5);

    /* A non-square resolution: the largest centred region of the film with
     * the image's aspect ratio, 25 mm x 12.5 mm for 512 x 256. */
    assert_int_equal(tb_camera_from_mid(&mc, 512, 256, &cam), TB_OK);
    tb_assert_near(cam.fov_y, 2.0 * atan(6.25 / 35.0) * 180.0 / TB_PI, 1e-12);
    tb_assert_near(cam.fov_x, fov, 1e-12);
    tb_ray tr = tb_camera_ray(&cam, 512, 0, 0, 0);
    assert_dir(tr.d, (tb_dvec3){-t, 6.25 / 35.0, 1}, 2e-7);
}

/* A random camera with its frame from `up` and the view direction. */
static void random_camera(tb_rng *rng, tb_camera *cam, tb_dvec3 *eye, tb_dvec3 *look, tb_dvec3 *up, double *fov,
                          int *w, int *h, double aperture, double focus)
{
    for (;;) {
        *eye = (tb_dvec3){100 * tb_rng_double(rng) - 50, 100 * tb_rng_double(rng) - 50, 100 * tb_rng_double(rng) - 50};
        *look = (tb_dvec3){eye->x + 2 * tb_rng_double(rng) - 1, eye->y + 2 * tb_rng_double(rng) - 1,
                           eye->z + 2 * tb_rng_double(rng) - 1};
        *up = (tb_dvec3){2 * tb_rng_double(rng) - 1, 2 * tb_rng_double(rng) - 1, 2 * tb_rng_double(rng) - 1};
        tb_dvec3 v = tb_dvec3_sub(*look, *eye);
        double lv = tb_dvec3_length(v), lu = tb_dvec3_length(*up);
        if (lv < 0.1 || lu < 0.1 || tb_dvec3_length(tb_dvec3_cross(v, *up)) < 0.3 * lv * lu)
            continue;
        break;
    }
    *fov = 10.0 + 150.0 * tb_rng_double(rng);
    *w = 1 + (int)(tb_rng_below(rng, 999));
    *h = 1 + (int)(tb_rng_below(rng, 999));
    assert_int_equal(tb_camera_init(cam, *eye, *look, *up, *fov, *w, *h, aperture, focus), TB_OK);
}

static void test_random_cameras(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("random_cameras", 7), 0);
    for (int k = 0; k < 500; k++) {
        tb_camera cam;
        tb_dvec3 eye, look, up;
        double fov;
        int w, h;
        random_camera(&rng, &cam, &eye, &look, &up, &fov, &w, &h, 0.0, 0.0);
        tb_dvec3 view = tb_dvec3_sub(look, eye);
        /* Centre: the view direction. */
        tb_ray c = tb_camera_ray(&cam, 0.5 * w, 0.5 * h, 0.3f, 0.7f);
        assert_dir(c.d, view, 3e-7);
        /* Edge midpoints span the fields of view: vertical fov as given,
         * horizontal from square pixels. */
        tb_ray l = tb_camera_ray(&cam, 0, 0.5 * h, 0, 0), r = tb_camera_ray(&cam, w, 0.5 * h, 0, 0);
        tb_ray t = tb_camera_ray(&cam, 0.5 * w, 0, 0, 0), b = tb_camera_ray(&cam, 0.5 * w, h, 0, 0);
        double fov_x = 2.0 * atan(tan(fov * TB_PI / 360.0) * w / h) * 180.0 / TB_PI;
        tb_assert_near(angle_deg(dv(t.d), dv(b.d)), fov, 1e-4);
        tb_assert_near(angle_deg(dv(l.d), dv(r.d)), fov_x, 1e-4);
        /* The top of the image is toward `up`, the right toward view x up. */
        tb_dvec3 right = tb_dvec3_cross(view, up);
        assert_true(tb_dvec3_dot(tb_dvec3_sub(dv(t.d), dv(b.d)), up) > 0.0);
        assert_true(tb_dvec3_dot(tb_dvec3_sub(dv(r.d), dv(l.d)), right) > 0.0);
        /* The vertical edge midpoints lie in the plane of view and up; the
         * horizontal ones in the plane perpendicular to it through the view. */
        tb_dvec3 nvu = tb_dvec3_normalize(right);
        tb_assert_near(tb_dvec3_dot(dv(t.d), nvu), 0.0, 3e-7);
        tb_assert_near(tb_dvec3_dot(dv(b.d), nvu), 0.0, 3e-7);
        /* Pinhole rays start at the eye; unit directions; projection is the inverse. */
        for (int i = 0; i < 8; i++) {
            double x = (1.4 * tb_rng_double(&rng) - 0.2) * w, y = (1.4 * tb_rng_double(&rng) - 0.2) * h;
            tb_camera_ray_diff rd;
            tb_camera_ray_differential(&cam, x, y, tb_rng_float(&rng), tb_rng_float(&rng), &rd);
            assert_true(rd.ray.o.x == (float)eye.x && rd.ray.o.y == (float)eye.y && rd.ray.o.z == (float)eye.z);
            assert_true(tb_vec3_equal(rd.rx_o, rd.ray.o) && tb_vec3_equal(rd.ry_o, rd.ray.o));
            tb_assert_near(tb_dvec3_length(dv(rd.ray.d)), 1.0, 2e-7);
            tb_ray nx = tb_camera_ray(&cam, x + 1, y, 0, 0), ny = tb_camera_ray(&cam, x, y + 1, 0, 0);
            assert_true(tb_vec3_equal(rd.rx_d, nx.d) && tb_vec3_equal(rd.ry_d, ny.d));
            double px, py;
            tb_dvec3 p = tb_dvec3_add(eye, tb_dvec3_scale(dv(rd.ray.d), 10.0));
            assert_true(tb_camera_project(&cam, p, &px, &py));
            double tol = 1e-5 * (w + h) * (1.0 + fabs(x) / w + fabs(y) / h);
            tb_assert_near(px, x, tol);
            tb_assert_near(py, y, tol);
        }
        /* Points behind the eye do not project. */
        double px, py;
        assert_false(tb_camera_project(&cam, tb_dvec3_sub(eye, view), &px, &py));
    }
}

/* Thin lens: every ray of one film point starts on the lens disc (in the
 * plane through the eye perpendicular to the view) and passes through the
 * point where the pinhole ray of that film point meets the plane in focus. */
static void test_thin_lens(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("thin_lens", 11), 0);
    for (int k = 0; k < 200; k++) {
        double aperture = 0.05 + 2.0 * tb_rng_double(&rng), focus = 0.5 + 20.0 * tb_rng_double(&rng);
        tb_camera cam, pin;
        tb_dvec3 eye, look, up;
        double fov;
        int w, h;
        random_camera(&rng, &cam, &eye, &look, &up, &fov, &w, &h, aperture, focus);
        assert_int_equal(tb_camera_init(&pin, eye, look, up, fov, w, h, 0.0, 0.0), TB_OK);
        tb_assert_near(cam.lens_radius, aperture / 2, 1e-15);
        tb_dvec3 fwd = tb_dvec3_normalize(tb_dvec3_sub(look, eye));
        double x = tb_rng_double(&rng) * w, y = tb_rng_double(&rng) * h;
        tb_ray pr = tb_camera_ray(&pin, x, y, 0, 0);
        tb_dvec3 d0 = dv(pr.d);
        tb_dvec3 focus_pt = tb_dvec3_add(eye, tb_dvec3_scale(d0, focus / tb_dvec3_dot(d0, fwd)));
        double scale = tb_dvec3_length(eye) + tb_dvec3_length(focus_pt) + focus;
        int distinct = 0;
        tb_vec3 first = {0};
        for (int i = 0; i < 64; i++) {
            float u = tb_rng_float(&rng), v = tb_rng_float(&rng);
            tb_camera_ray_diff rd;
            tb_camera_ray_differential(&cam, x, y, u, v, &rd);
            tb_ray r = rd.ray;
            assert_true(tb_vec3_equal(r.o, tb_camera_ray(&cam, x, y, u, v).o));
            tb_dvec3 off = tb_dvec3_sub(dv(r.o), eye);
            tb_assert_near(tb_dvec3_dot(off, fwd), 0.0, 1e-6 * scale);
            assert_true(tb_dvec3_length(off) <= cam.lens_radius * (1 + 1e-6) + 1e-6 * scale);
            /* Distance from the focus point to the ray's line. */
            tb_dvec3 q = tb_dvec3_sub(focus_pt, dv(r.o));
            double along = tb_dvec3_dot(q, dv(r.d));
            assert_true(along > 0.0);
            double miss = tb_dvec3_length(tb_dvec3_sub(q, tb_dvec3_scale(dv(r.d), along)));
            assert_true(miss <= 2e-6 * scale);
            /* The neighbours share the lens point. */
            assert_true(tb_vec3_equal(rd.rx_o, r.o) && tb_vec3_equal(rd.ry_o, r.o));
            if (i == 0)
                first = r.o;
            else if (!tb_vec3_equal(first, r.o))
                distinct++;
        }
        assert_true(distinct > 50);
    }
}

static void test_init_errors(void **state)
{
    (void)state;
    tb_camera c;
    tb_dvec3 e = {0, 0, 0}, l = {0, 0, -1}, u = {0, 1, 0};
    assert_int_equal(tb_camera_init(&c, e, l, u, 45, 64, 64, 0, 0), TB_OK);
    assert_int_equal(tb_camera_init(&c, e, l, u, 0, 64, 64, 0, 0), TB_ERR_ARG);
    assert_int_equal(tb_camera_init(&c, e, l, u, 180, 64, 64, 0, 0), TB_ERR_ARG);
    assert_int_equal(tb_camera_init(&c, e, l, u, NAN, 64, 64, 0, 0), TB_ERR_ARG);
    assert_int_equal(tb_camera_init(&c, e, l, u, 45, 0, 64, 0, 0), TB_ERR_ARG);
    assert_int_equal(tb_camera_init(&c, e, l, u, 45, 64, 65537, 0, 0), TB_ERR_ARG);
    assert_int_equal(tb_camera_init(&c, e, l, u, 45, 64, 64, -1, 1), TB_ERR_ARG);
    assert_int_equal(tb_camera_init(&c, e, l, u, 45, 64, 64, 1, 0), TB_ERR_ARG);
    assert_int_equal(tb_camera_init(&c, e, e, u, 45, 64, 64, 0, 0), TB_ERR_ARG);  /* eye == look_at */
    assert_int_equal(tb_camera_init(&c, e, l, l, 45, 64, 64, 0, 0), TB_ERR_ARG);  /* up parallel */
    assert_non_null(strstr(tb_last_error(), "camera"));
    /* A thin lens with no explicit focus distance focuses at look_at. */
    assert_int_equal(tb_camera_init(&c, e, (tb_dvec3){0, 0, -5}, u, 45, 64, 64, 0, 0), TB_OK);
    tb_assert_near(c.focus_distance, 5.0, 0.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cornell_corners),
        cmocka_unit_test(test_random_cameras),
        cmocka_unit_test(test_thin_lens),
        cmocka_unit_test(test_init_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
