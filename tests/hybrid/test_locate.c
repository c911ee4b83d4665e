/* Hit -> radiosity element (host/radiosity/locate.h): a hand-made mesh with
 * known answers, a polygonized sphere, points that must not be found,
 * interpolated values at corners, and every pixel of the Cornell box. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "host/object/hit.h"
#include "host/object/intersect.h"
#include "host/radiosity/locate.h"
#include "host/radiosity/radiosity.h"
#include "host/render/scene.h"
#include "tb_test.h"
#include "util/math/float.h"

/* Two objects: object 0 a unit square quad in z = 0 facing +z (v0..v3),
 * object 1 a triangle in z = 0.5 facing +z (v4..v6), both rho 0.5. */
static void tb__two_objects(tb_rad_mesh *m)
{
    tb_rad_mesh_init(m);
    m->nchannels = 3;
    m->nverts = 7;
    m->verts = calloc(7, sizeof *m->verts);
    m->nelems = 2;
    m->elems = calloc(2, sizeof *m->elems);
    m->rho = calloc(6, sizeof(float));
    m->emission = calloc(6, sizeof(float));
    assert_non_null(m->verts);
    assert_non_null(m->elems);
    const float xy[7][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {2, 0, 0.5f}, {3, 0, 0.5f}, {2, 1, 0.5f}};
    for (int v = 0; v < 7; v++) {
        m->verts[v].p = tb_vec3_make(xy[v][0], xy[v][1], xy[v][2]);
        m->verts[v].n = tb_vec3_make(0, 0, 1);
    }
    m->elems[0] = (tb_rad_element){.v = {0, 1, 2, 3}, .object = 0, .parent = TB_RAD_NONE};
    m->elems[1] = (tb_rad_element){.v = {4, 5, 6, TB_RAD_NONE}, .object = 1, .parent = TB_RAD_NONE};
    for (int k = 0; k < 6; k++)
        m->rho[k] = 0.5f;
    assert_int_equal(tb_rad_mesh_update_geometry(m), TB_OK);
}

/* sum w[k] v[k] of a location. */
static tb_vec3 tb__weighted(const tb_rad_mesh *m, const tb_rad_location *at)
{
    double q[3] = {0, 0, 0};
    for (int k = 0; k < at->ncorners; k++) {
        tb_vec3 v = m->verts[at->v[k]].p;
        q[0] += at->w[k] * v.x, q[1] += at->w[k] * v.y, q[2] += at->w[k] * v.z;
    }
    return tb_vec3_make((float)q[0], (float)q[1], (float)q[2]);
}

/* Points on the known mesh: the right element, weights >= 0 summing to 1
 * that reproduce the point, and the display's triangles (v0 v1 v2) above
 * the diagonal x = y, (v0 v2 v3) below it. */
static void test_known_mesh(void **state)
{
    (void)state;
    tb_rad_mesh m;
    tb__two_objects(&m);
    tb_rad_locator *loc;
    assert_int_equal(tb_rad_locator_create(&m, &loc), TB_OK);
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("known_mesh", 7), 0);
    const tb_vec3 up = tb_vec3_make(0, 0, 1);
    for (int i = 0; i < 200; i++) {
        float x = tb_rng_float(&rng), y = tb_rng_float(&rng);
        tb_rad_location at;
        assert_true(tb_rad_locate(loc, 0, tb_vec3_make(x, y, 0), up, &at));
        assert_int_equal(at.element, 0);
        assert_int_equal(at.object, 0);
        assert_int_equal(at.ncorners, 4);
        double sum = 0;
        for (int k = 0; k < 4; k++) {
            assert_true(at.w[k] >= 0.0);
            sum += at.w[k];
        }
        tb_assert_near(sum, 1.0, 1e-12);
        tb_vec3 q = tb__weighted(&m, &at);
        tb_assert_near(q.x, x, 1e-6);
        tb_assert_near(q.y, y, 1e-6);
        tb_assert_near(at.distance, 0.0, 1e-6);
        /* bilinear would weight all four; the display's triangles use three */
        if (x > y + 1e-3)
            tb_assert_near(at.w[3], 0.0, 0.0);
        else if (y > x + 1e-3)
            tb_assert_near(at.w[1], 0.0, 0.0);
        /* above the plane by less than the tolerance (a quarter of the edge): found, at distance h */
        assert_true(tb_rad_locate(loc, 0, tb_vec3_make(x, y, 0.1f), up, &at));
        assert_int_equal(at.element, 0);
        tb_assert_near(at.distance, 0.1, 1e-6);
        /* the triangle of object 1 */
        float u = 0.5f * x, v = 0.5f * y; /* inside: u + v < 1 */
        assert_true(tb_rad_locate(loc, 1, tb_vec3_make(2 + u, v, 0.5f), up, &at));
        assert_int_equal(at.element, 1);
        assert_int_equal(at.ncorners, 3);
        tb_assert_near(at.w[0], 1.0 - u - v, 1e-6);
        tb_assert_near(at.w[1], u, 1e-6);
        tb_assert_near(at.w[2], v, 1e-6);
        tb_assert_near(at.w[3], 0.0, 0.0);
    }
    /* just outside an edge, within tolerance: the nearest point is on the edge */
    tb_rad_location at;
    assert_true(tb_rad_locate(loc, 0, tb_vec3_make(1.1f, 0.5f, 0), up, &at));
    tb_vec3 q = tb__weighted(&m, &at);
    tb_assert_near(q.x, 1.0, 1e-6);
    tb_assert_near(q.y, 0.5, 1e-6);
    tb_assert_near(at.distance, 0.1, 1e-6);
    /* a zero normal skips the side test */
    assert_true(tb_rad_locate(loc, 0, tb_vec3_make(0.5f, 0.5f, 0), tb_vec3_make(0, 0, 0), &at));
    tb_rad_locator_free(loc);
    tb_rad_mesh_free(&m);
}

/* Far points, the wrong object, an object without elements, the back side: false. */
static void test_not_found(void **state)
{
    (void)state;
    tb_rad_mesh m;
    tb__two_objects(&m);
    tb_rad_locator *loc;
    assert_int_equal(tb_rad_locator_create(&m, &loc), TB_OK);
    const tb_vec3 up = tb_vec3_make(0, 0, 1);
    tb_rad_location at;
    /* control: found */
    assert_true(tb_rad_locate(loc, 0, tb_vec3_make(0.5f, 0.5f, 0), up, &at));
    /* above the square by more than a quarter of its edge */
    assert_false(tb_rad_locate(loc, 0, tb_vec3_make(0.5f, 0.5f, 0.3f), up, &at));
    /* far away */
    assert_false(tb_rad_locate(loc, 0, tb_vec3_make(10, 10, 10), up, &at));
    assert_false(tb_rad_locate(loc, 0, tb_vec3_make(1.4f, 0.5f, 0), up, &at));
    /* on object 1's triangle, asked as object 0; on object 0 asked as 1 */
    assert_false(tb_rad_locate(loc, 0, tb_vec3_make(2.2f, 0.2f, 0.5f), up, &at));
    assert_false(tb_rad_locate(loc, 1, tb_vec3_make(0.5f, 0.5f, 0), up, &at));
    /* objects out of range */
    assert_false(tb_rad_locate(loc, 2, tb_vec3_make(0.5f, 0.5f, 0), up, &at));
    assert_false(tb_rad_locate(loc, UINT32_MAX, tb_vec3_make(0.5f, 0.5f, 0), up, &at));
    /* seen from behind: elements receive on their front only */
    assert_false(tb_rad_locate(loc, 0, tb_vec3_make(0.5f, 0.5f, 0), tb_vec3_make(0, 0, -1), &at));
    /* NaN */
    assert_false(tb_rad_locate(loc, 0, tb_vec3_make(NAN, 0.5f, 0), up, &at));
    tb_rad_locator_free(loc);
    /* an empty mesh is refused */
    tb_rad_mesh e;
    tb_rad_mesh_init(&e);
    assert_int_equal(tb_rad_locator_create(&e, &loc), TB_ERR_ARG);
    assert_null(loc);
    tb_rad_mesh_free(&m);
}

/* The element ray (o, d) crosses first (the display's two triangles), or
 * TB_RAD_NONE; *t its distance along d. */
static uint32_t tb__radial_element(const tb_rad_mesh *m, tb_vec3 o, tb_vec3 d, double *t)
{
    uint32_t best = TB_RAD_NONE;
    double bt = INFINITY;
    for (uint32_t i = 0; i < m->nelems; i++) {
        const tb_rad_element *e = &m->elems[i];
        int tris = e->v[3] == TB_RAD_NONE ? 1 : 2;
        for (int t = 0; t < tris; t++) {
            tb_vec3 a = m->verts[e->v[0]].p, b = m->verts[e->v[t ? 2 : 1]].p, c = m->verts[e->v[t ? 3 : 2]].p;
            tb_vec3 e1 = tb_vec3_sub(b, a), e2 = tb_vec3_sub(c, a), p = tb_vec3_cross(d, e2);
            double det = tb_vec3_dot(e1, p);
            if (fabs(det) < 1e-12)
                continue;
            tb_vec3 s = tb_vec3_sub(o, a), q = tb_vec3_cross(s, e1);
            double u = tb_vec3_dot(s, p) / det, v = tb_vec3_dot(d, q) / det, tt = tb_vec3_dot(e2, q) / det;
            if (u >= 0 && v >= 0 && u + v <= 1 && tt > 0 && tt < bt)
                bt = tt, best = i;
        }
    }
    *t = bt;
    return best;
}

/* Points of a true sphere (radius 2) find the element of its polygonization
 * under them: at most the chord height away, never farther than the
 * element the radial line crosses (which it is for most points), and for
 * most points with p projecting into its interior. */
static void test_sphere(void **state)
{
    (void)state;
    char path[1024];
    snprintf(path, sizeof path, "%s/locate_sphere.mid", tb_test_tmpdir());
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs("mid 1\nmaterial \"white\" { diffuse = 0.5 }\n"
          "cube \"floor\" { transform = [scale([10 10 0.1]) translate([0 0 -3])] rendering = { material = \"white\" } }\n"
          "sphere \"ball\" { transform = [scale(2) translate([1 2 3])] rendering = { material = \"white\" } }\n",
          f);
    fclose(f);
    tb_scene_options so = {.no_accel = true};
    tb_scene *s = NULL;
    if (tb_scene_load(path, &so, &s))
        fail_msg("%s", tb_last_error());
    tb_rad_mesh_options mo = tb_rad_default_mesh_options(s);
    tb_rad_mesh m;
    assert_int_equal(tb_rad_mesh_from_scene(s, &mo, &m), TB_OK);
    uint32_t ball = 1;
    size_t nball = 0;
    for (size_t i = 0; i < m.nelems; i++)
        nball += m.elems[i].object == ball;
    assert_true(nball > 50);
    tb_rad_locator *loc;
    assert_int_equal(tb_rad_locator_create(&m, &loc), TB_OK);
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("sphere", 11), 0);
    const tb_vec3 c = tb_vec3_make(1, 2, 3);
    int radial = 0, inside = 0;
    const int n = 500;
    for (int i = 0; i < n; i++) {
        /* a uniform direction */
        double z = 2.0 * tb_rng_double(&rng) - 1.0, ph = 2.0 * TB_PI * tb_rng_double(&rng), r = sqrt(1 - z * z);
        tb_vec3 d = tb_vec3_make((float)(r * cos(ph)), (float)(r * sin(ph)), (float)z);
        tb_vec3 p = tb_vec3_add(c, tb_vec3_scale(d, 2.0f));
        tb_rad_location at;
        assert_true(tb_rad_locate(loc, ball, p, d, &at));
        assert_int_equal(at.object, ball);
        /* the chord height at 15 degrees is 2 (1 - cos 7.5 deg) = 0.017 per edge; 0.05 bounds it */
        assert_true(at.distance < 0.05);
        double tu;
        uint32_t under = tb__radial_element(&m, c, d, &tu);
        assert_int_not_equal(under, TB_RAD_NONE);
        assert_int_equal(m.elems[under].object, ball);
        if (under == at.element)
            radial++;
        /* never farther than the element under p */
        tb_vec3 x = tb_vec3_add(c, tb_vec3_scale(d, (float)tu)); /* where the radial line crosses it */
        assert_true(at.distance <= tb_vec3_distance(p, x) + 1e-5);
        /* p projects into the element found: the offset to its nearest point is along the normal */
        tb_vec3 off = tb_vec3_sub(p, at.q);
        if (tb_vec3_length(tb_vec3_cross(off, m.elems[at.element].normal)) <= 1e-4)
            inside++;
        /* the weights reproduce the point the distance is measured to */
        tb_vec3 q = tb__weighted(&m, &at);
        tb_assert_near(tb_vec3_distance(q, at.q), 0.0, 1e-5);
        tb_assert_near(tb_vec3_distance(p, q), at.distance, 1e-5);
    }
    /* mostly the radial element itself, and p over its interior (at edges
     * between elements the nearest point is on the edge) */
    print_message("[ sphere   ] radial element %d of %d, projection inside %d\n", radial, n, inside);
    assert_true(radial > n * 8 / 10);
    assert_true(inside > n * 8 / 10);
    tb_rad_locator_free(loc);
    tb_rad_mesh_free(&m);
    tb_scene_free(s);
    remove(path);
}

/* Interpolated radiosity equals the corner values at the corners, and
 * tb_rad_location_interpolate of the vertex irradiances gives the same. */
static void test_corner_values(void **state)
{
    (void)state;
    char path[1024];
    snprintf(path, sizeof path, "%s/scenes/cornell-box-rgb.mid", TB_SOURCE_DIR);
    tb_scene_options so = {.no_accel = true};
    tb_scene *s = NULL;
    if (tb_scene_load(path, &so, &s))
        fail_msg("%s", tb_last_error());
    tb_rad_mesh_options mo = {.max_edge = 120.0};
    tb_rad_mesh m;
    assert_int_equal(tb_rad_mesh_from_scene(s, &mo, &m), TB_OK);
    tb_rad_options ro = {0};
    tb_rad_solver *sv;
    assert_int_equal(tb_rad_solver_create(&m, NULL, &ro, &sv), TB_OK);
    tb_rad_stop stop = {.threshold = 0.05};
    assert_int_equal(tb_rad_solver_run(sv, &stop, NULL, NULL, 0), TB_OK);
    const tb_rad_mesh *sm = tb_rad_solver_mesh(sv);
    tb_rad_locator *loc;
    assert_int_equal(tb_rad_locator_create(sm, &loc), TB_OK);
    double amb[TB_CHANNELS_MAX], b[TB_CHANNELS_MAX], want[TB_CHANNELS_MAX], h[TB_CHANNELS_MAX];
    tb_rad_ambient(sv, amb);
    double *hv = malloc(sm->nverts * 3 * sizeof *hv);
    assert_non_null(hv);
    for (size_t v = 0; v < sm->nverts; v++)
        tb_rad_vertex_irradiance(sv, v, hv + v * 3);
    size_t checked = 0, exact = 0;
    for (uint32_t i = 0; i < sm->nelems; i++) {
        const tb_rad_element *e = &sm->elems[i];
        int nk = e->v[3] == TB_RAD_NONE ? 3 : 4;
        for (int k = 0; k < nk; k++) {
            /* just inside the corner, towards the centroid: this element, the corner's value */
            tb_vec3 corner = sm->verts[e->v[k]].p;
            tb_vec3 p = tb_vec3_add(corner, tb_vec3_scale(tb_vec3_sub(e->centroid, corner), 1e-4f));
            tb_rad_location at;
            assert_true(tb_rad_locate(loc, e->object, p, e->normal, &at));
            assert_int_equal(at.element, i);
            assert_true(at.w[k] > 0.999);
            tb_rad_location_radiosity(sv, &at, amb, b);
            /* the corners' values weighted: what the display interpolates */
            for (int c = 0; c < 3; c++)
                want[c] = 0.0;
            for (int q = 0; q < nk; q++) {
                double cv[TB_CHANNELS_MAX];
                tb_rad_corner_radiosity(sv, i, q, true, cv);
                for (int c = 0; c < 3; c++)
                    want[c] += at.w[q] * cv[c];
            }
            for (int c = 0; c < 3; c++)
                tb_assert_near(b[c], want[c], 1e-9 * fabs(want[c]) + 1e-12);
            checked++;
            /* exactly at the corner: distance 0, and when the element found
             * has that vertex (not always: a corner can lie on another
             * element's edge, a T-junction, and ties go to the lower index)
             * weight 1 there and the corner value of the element found */
            assert_true(tb_rad_locate(loc, e->object, corner, e->normal, &at));
            tb_assert_near(at.distance, 0.0, 1e-4);
            int kk = -1;
            for (int q = 0; q < at.ncorners; q++)
                if (at.v[q] == e->v[k])
                    kk = q;
            if (kk < 0)
                continue;
            tb_assert_near(at.w[kk], 1.0, 1e-6);
            tb_rad_location_radiosity(sv, &at, amb, b);
            tb_rad_corner_radiosity(sv, at.element, kk, true, want);
            tb_rad_location_interpolate(&at, hv, 3, h);
            for (int c = 0; c < 3; c++) {
                tb_assert_near(b[c], want[c], 1e-6 * fabs(want[c]) + 1e-9);
                tb_assert_near(h[c], hv[e->v[k] * 3 + (size_t)c], 1e-6 * fabs(h[c]) + 1e-9);
            }
            exact++;
        }
    }
    print_message("[ corners  ] %zu corners, %zu with their vertex in the element found there\n", checked, exact);
    assert_true(checked > 100);
    assert_true(exact > checked / 2);
    free(hv);
    tb_rad_locator_free(loc);
    tb_rad_solver_free(sv);
    tb_rad_mesh_free(&m);
    tb_scene_free(s);
}

/* The whole Cornell box from its camera: every pixel's hit maps to an
 * element of the object hit, within a millimetre (the box is flat). */
static void test_cornell_camera(void **state)
{
    (void)state;
    char path[1024];
    snprintf(path, sizeof path, "%s/scenes/cornell-box-rgb.mid", TB_SOURCE_DIR);
    tb_scene *s = NULL;
    if (tb_scene_load(path, NULL, &s))
        fail_msg("%s", tb_last_error());
    tb_rad_mesh_options mo = tb_rad_default_mesh_options(s);
    tb_rad_mesh m;
    assert_int_equal(tb_rad_mesh_from_scene(s, &mo, &m), TB_OK);
    tb_rad_locator *loc;
    assert_int_equal(tb_rad_locator_create(&m, &loc), TB_OK);
    const int res = 128;
    size_t hits = 0;
    for (int y = 0; y < res; y++)
        for (int x = 0; x < res; x++) {
            double fx = (x + 0.5) * s->camera.width / res, fy = (y + 0.5) * s->camera.height / res;
            tb_ray ray = tb_camera_ray(&s->camera, fx, fy, 0.5f, 0.5f);
            tb_hit hit;
            if (!tb_scene_intersect(s, &ray, &hit))
                continue;
            tb_vec3 p, perr;
            assert_true(tb_object_hit_point(s->objects[hit.object], &ray, &hit, &p, &perr));
            tb_vec3 n = tb_vec3_dot(ray.d, hit.ng) < 0.0f ? hit.ng : tb_vec3_neg(hit.ng);
            tb_rad_location at;
            if (!tb_rad_locate(loc, hit.object, p, n, &at))
                fail_msg("pixel %d %d: object %u at (%g %g %g) has no element", x, y, hit.object, p.x, p.y, p.z);
            assert_int_equal(at.object, hit.object);
            assert_int_equal(m.elems[at.element].object, hit.object);
            assert_true(at.distance < 1.0);
            hits++;
        }
    /* the box fills the view but for its open front's rim */
    assert_true(hits > (size_t)res * res * 9 / 10);
    tb_rad_locator_free(loc);
    tb_rad_mesh_free(&m);
    tb_scene_free(s);
}

int main(int argc, char **argv)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_known_mesh),
        cmocka_unit_test(test_not_found),
        cmocka_unit_test(test_sphere),
        cmocka_unit_test(test_corner_values),
        cmocka_unit_test(test_cornell_camera),
    };
    if (argc > 1)
        cmocka_set_test_filter(argv[1]);
    return cmocka_run_group_tests(tests, NULL, NULL);
}
