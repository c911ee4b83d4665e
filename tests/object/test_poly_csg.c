/* host/object/polygonize_csg: polygonal approximation of CSG trees against
 * analytic areas and volumes (spheres and a cube, written here), the
 * orientation rule for subtracted surfaces, the coincident-surface rule
 * (A u A = A) and the distance of every output vertex from the true CSG
 * surface. */
#include "tb_test.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "host/object/object.h"
#include "host/object/polygonize.h"
#include "util/mesh/fed.h"

#define TP_PI 3.14159265358979323846

static tb_mid_object tp_mid(tb_prim_kind k, tb_transform xf)
{
    tb_mid_object m;
    memset(&m, 0, sizeof m);
    m.kind = k;
    m.to_world = xf;
    m.geom = tb_mid_geometry_default(k);
    m.material = tb_mid_material_default();
    return m;
}

/* A sphere of radius r at c. */
static tb_mid_object tp_sphere(tb_dvec3 c, double r)
{
    tb_transform s;
    assert_int_equal(tb_transform_scale((tb_dvec3){r, r, r}, &s), TB_OK);
    tb_transform t = tb_transform_translate(c);
    return tp_mid(TB_PRIM_SPHERE, tb_transform_compose(&t, &s));
}

static tb_object *tp_csg(tb_prim_kind op, const tb_mid_object *ch, int n)
{
    tb_mid_object m = tp_mid(op, tb_transform_identity());
    m.children = ch;
    m.nchildren = n;
    tb_object *o = NULL;
    if (tb_object_from_mid(&m, 0, NULL, NULL, &o))
        fail_msg("tb_object_from_mid: %s", tb_last_error());
    return o;
}

static tb_fed *tp_poly(const tb_object *o, double angle, double edge)
{
    tb_poly_options opt = {.max_angle = angle};
    tb_fed *fed = NULL;
    if (tb_polygonize_object(o, &opt, edge, &fed))
        fail_msg("tb_polygonize_object: %s", tb_last_error());
    return fed;
}

static tb_dvec3 tp_v(const tb_fed *f, uint32_t c) { tb_vec3 p = f->positions[f->corner_vert[c]]; return (tb_dvec3){p.x, p.y, p.z}; }

/* Area and signed volume (divergence theorem: positive when the normals
 * point out of the enclosed solid) of a triangle mesh. */
static void tp_measure(const tb_fed *f, double *area, double *volume)
{
    double a = 0, v = 0;
    for (uint32_t i = 0; i < f->nfaces; i++) {
        uint32_t c = f->loop_corners[f->face_loops[i]];
        assert_int_equal(f->loop_corners[f->face_loops[i] + 1] - c, 3);
        tb_dvec3 p0 = tp_v(f, c), p1 = tp_v(f, c + 1), p2 = tp_v(f, c + 2);
        tb_dvec3 n = tb_dvec3_cross(tb_dvec3_sub(p1, p0), tb_dvec3_sub(p2, p0));
        a += 0.5 * tb_dvec3_length(n);
        v += tb_dvec3_dot(p0, tb_dvec3_cross(p1, p2)) / 6.0;
    }
    *area = a, *volume = v;
}

static void test_poly_csg_union_disjoint(void **state)
{
    (void)state;
    tb_mid_object ch[2] = {tp_sphere((tb_dvec3){-3, 0, 0}, 1), tp_sphere((tb_dvec3){3, 0.5, 0}, 0.5)};
    tb_object *u = tp_csg(TB_PRIM_UNION, ch, 2);
    tb_fed *f = tp_poly(u, 0.05, 0.02);
    double a, v;
    tp_measure(f, &a, &v);
    double ea = 4 * TP_PI * 1.25, ev = 4.0 / 3 * TP_PI * 1.125;
    print_message("union of disjoint spheres: area %.5f (exact %.5f), volume %.5f (exact %.5f)\n", a, ea, v, ev);
    /* Chords at 0.05 rad fall short by about a^2 / 8 of the area. */
    assert_true(fabs(a - ea) < 2e-3 * ea);
    assert_true(fabs(v - ev) < 3e-3 * ev);
    tb_fed_free(f);
    tb_object_free(u);
}

static void test_poly_csg_cavity_flipped(void **state)
{
    (void)state;
    /* Cube [-1, 1]^3 minus a sphere of radius 0.5 at (0.1, 0, -0.2). */
    tb_dvec3 sc = {0.1, 0, -0.2};
    tb_mid_object ch[2] = {tp_mid(TB_PRIM_CUBE, tb_transform_identity()), tp_sphere(sc, 0.5)};
    tb_object *d = tp_csg(TB_PRIM_DIFFERENCE, ch, 2);
    tb_fed *f = tp_poly(d, 0.05, 0.02);
    double a, v;
    tp_measure(f, &a, &v);
    double ea = 24 + 4 * TP_PI * 0.25, ev = 8 - 4.0 / 3 * TP_PI * 0.125;
    print_message("cube - inner sphere: area %.5f (exact %.5f), volume %.5f (exact %.5f)\n", a, ea, v, ev);
    assert_true(fabs(a - ea) < 1e-3 * ea);
    /* A cavity with outward normals would add its volume instead. */
    assert_true(fabs(v - ev) < 2e-3 * ev);
    /* Every sphere triangle faces the sphere's centre (into the cavity, out
     * of the solid); every cube triangle faces away from the origin. */
    uint32_t cube_faces = d->children[0].nfaces, nsphere = 0;
    for (uint32_t i = 0; i < f->nfaces; i++) {
        uint32_t c = f->loop_corners[f->face_loops[i]];
        tb_dvec3 p0 = tp_v(f, c), p1 = tp_v(f, c + 1), p2 = tp_v(f, c + 2);
        tb_dvec3 n = tb_dvec3_cross(tb_dvec3_sub(p1, p0), tb_dvec3_sub(p2, p0));
        tb_dvec3 g = tb_dvec3_scale(tb_dvec3_add(tb_dvec3_add(p0, p1), p2), 1.0 / 3);
        if ((uint32_t)f->face_ids[i] >= cube_faces) {
            nsphere++;
            assert_true(tb_dvec3_dot(n, tb_dvec3_sub(sc, g)) > 0);
        } else {
            assert_true(tb_dvec3_dot(n, g) > 0);
        }
    }
    assert_true(nsphere > 100);
    tb_fed_free(f);
    tb_object_free(d);
}

/* Distance from p to the surface of the lens: unit spheres at A = 0 and
 * B = (1, 0, 0); the rim is the circle x = 1/2, radius sqrt(3)/2. */
static double tp_lens_distance(tb_dvec3 p)
{
    double best = INFINITY;
    for (int s = 0; s < 2; s++) {
        tb_dvec3 c = {s ? 1.0 : 0.0, 0, 0}, o = {s ? 0.0 : 1.0, 0, 0};
        tb_dvec3 q = tb_dvec3_add(c, tb_dvec3_normalize(tb_dvec3_sub(p, c))); /* nearest point of sphere s */
        if (tb_dvec3_length(tb_dvec3_sub(q, o)) <= 1.0)                       /* on the lens part of it */
            best = fmin(best, fabs(tb_dvec3_length(tb_dvec3_sub(p, c)) - 1.0));
    }
    double rr = hypot(p.y, p.z), rim = sqrt(3.0) / 2;
    best = fmin(best, hypot(p.x - 0.5, rr - rim));
    return best;
}

static void test_poly_csg_lens_converges(void **state)
{
    (void)state;
    tb_mid_object ch[2] = {tp_sphere((tb_dvec3){0, 0, 0}, 1), tp_sphere((tb_dvec3){1, 0, 0}, 1)};
    tb_object *x = tp_csg(TB_PRIM_INTERSECTION, ch, 2);
    /* Two caps of height 1/2 on unit spheres: 2 (2 pi r h) = 2 pi. */
    double ea = 2 * TP_PI, prev = INFINITY;
    const double res[3] = {0.2, 0.1, 0.05};
    for (int k = 0; k < 3; k++) {
        double tol = res[k];
        tb_fed *f = tp_poly(x, tol, tol);
        double a, v;
        tp_measure(f, &a, &v);
        double err = fabs(a - ea), worst = 0;
        for (uint32_t i = 0; i < f->nverts; i++) {
            tb_vec3 p = f->positions[i];
            worst = fmax(worst, tp_lens_distance((tb_dvec3){p.x, p.y, p.z}));
        }
        print_message("lens at %.3f: area %.5f (exact %.5f, error %.2e), volume %.5f, worst vertex distance %.2e\n",
                      tol, a, ea, err, v, worst);
        /* Every vertex is on a sphere; off the lens at most one csg_edge. */
        assert_true(worst <= tol);
        assert_true(err < prev);
        assert_true(v > 0);
        prev = err;
        tb_fed_free(f);
    }
    assert_true(prev < 0.01 * ea);
    /* And the volume: two caps of height 1/2, pi h^2 (3 r - h) / 3 each. */
    tb_fed *f = tp_poly(x, res[2], res[2]);
    double a, v, ev = 2 * TP_PI * 0.25 * 2.5 / 3;
    tp_measure(f, &a, &v);
    assert_true(fabs(v - ev) < 0.01 * ev);
    tb_fed_free(f);
    tb_object_free(x);
}

static void test_poly_csg_self_union(void **state)
{
    (void)state;
    tb_mid_object s = tp_sphere((tb_dvec3){0.3, -0.2, 0.1}, 0.8);
    tb_mid_object ch[2] = {s, s};
    tb_object *u = tp_csg(TB_PRIM_UNION, ch, 2);
    tb_object *lone = NULL;
    assert_int_equal(tb_object_from_mid(&s, 0, NULL, NULL, &lone), TB_OK);
    tb_fed *fu = tp_poly(u, 0.1, 0.05), *fl = tp_poly(lone, 0.1, 0.05);
    double au, vu, al, vl;
    tp_measure(fu, &au, &vu);
    tp_measure(fl, &al, &vl);
    print_message("A u A: area %.6f, A alone %.6f (exact %.6f)\n", au, al, 4 * TP_PI * 0.64);
    /* One copy, not two: the coincident surface goes to the first child. */
    assert_true(fabs(au - al) < 1e-6 * al);
    assert_true(fabs(al - 4 * TP_PI * 0.64) < 0.01 * al);
    for (uint32_t i = 0; i < fu->nfaces; i++)
        assert_true((uint32_t)fu->face_ids[i] < u->children[0].nfaces);
    tb_fed_free(fu);
    tb_fed_free(fl);
    tb_object_free(u);
    tb_object_free(lone);
}

/* A polygons object from a FED file whose face has a hole: the 4 x 4 square
 * minus the 2 x 2 one, under a scale (2, 3, 1): area (16 - 4) * 6 = 72. The
 * inline form the object keeps for param (outer loops only) would give 96. */
static void test_poly_fed_hole(void **state)
{
    (void)state;
    char path[4096];
    snprintf(path, sizeof path, "%s/objgap_hole.fed", tb_test_tmpdir());
    FILE *fp = fopen(path, "w");
    assert_non_null(fp);
    fputs("fed 1.0\nvertices 8\n0 0 0\n4 0 0\n4 4 0\n0 4 0\n1 1 0\n1 3 0\n3 3 0\n3 1 0\n"
          "faces 1\n0 1 2 3 hole 4 5 6 7\n",
          fp);
    fclose(fp);
    tb_transform s;
    assert_int_equal(tb_transform_scale((tb_dvec3){2, 3, 1}, &s), TB_OK);
    tb_mid_object m = tp_mid(TB_PRIM_POLYGONS, s);
    m.geom.polygons.mesh.text = path;
    m.geom.polygons.mesh.path = path;
    tb_object *o = NULL;
    if (tb_object_from_mid(&m, 0, NULL, NULL, &o))
        fail_msg("tb_object_from_mid: %s", tb_last_error());
    assert_non_null(o->fed);
    tb_fed *f = tp_poly(o, 0.1, 0.5);
    double a, v;
    tp_measure(f, &a, &v);
    print_message("FED face with a hole: area %.6f (exact 72)\n", a);
    assert_true(fabs(a - 72.0) < 1e-5);
    /* No triangle covers the hole (x in (2, 6), y in (3, 9) after scaling). */
    for (uint32_t i = 0; i < f->nfaces; i++) {
        uint32_t c = f->loop_corners[f->face_loops[i]];
        tb_dvec3 g = tb_dvec3_scale(tb_dvec3_add(tb_dvec3_add(tp_v(f, c), tp_v(f, c + 1)), tp_v(f, c + 2)), 1.0 / 3);
        assert_false(g.x > 2 && g.x < 6 && g.y > 3 && g.y < 9);
        assert_int_equal(f->face_ids[i], 0);
    }
    tb_fed_free(f);
    tb_object_free(o);
    remove(path);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_poly_csg_union_disjoint),
        cmocka_unit_test(test_poly_csg_cavity_flipped),
        cmocka_unit_test(test_poly_csg_lens_converges),
        cmocka_unit_test(test_poly_csg_self_union),
        cmocka_unit_test(test_poly_fed_hole),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
