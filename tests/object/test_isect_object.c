/* Objects and hits by hand: tb_object_from_mid (deep copy, rejections, CSG
 * face numbering, materials) and one hand-computed hit per kind and face
 * family (t, face, normal), in object space and under a transform. */
#include "test_isect_common.h"

#include "host/object/csg.h"
#include "host/object/intersect.h"
#include "host/object/param.h"
#include "util/math/float.h"
#include "util/mesh/fed.h"

static tb_ray ti_ray(double ox, double oy, double oz, double dx, double dy, double dz)
{
    return tb_ray_make((tb_vec3){(float)ox, (float)oy, (float)oz}, (tb_vec3){(float)dx, (float)dy, (float)dz}, 0.0f,
                       INFINITY);
}

/* Asserts a hit at t with face and normal (tolerance 1e-6 relative). */
static void ti_expect(const tb_object *o, tb_ray r, double t, uint32_t face, double nx, double ny, double nz)
{
    tb_hit h;
    if (!tb_object_intersect(o, &r, &h))
        fail_msg("%s: no hit, expected t = %g", tb_prim_kind_name(o->kind), t);
    tb_assert_near(h.t, t, 1e-6 * fmax(1.0, fabs(t)));
    if (h.face != face)
        fail_msg("%s: face %u, expected %u", tb_prim_kind_name(o->kind), h.face, face);
    double l = sqrt(nx * nx + ny * ny + nz * nz);
    tb_assert_near(h.ng.x, nx / l, 1e-6);
    tb_assert_near(h.ng.y, ny / l, 1e-6);
    tb_assert_near(h.ng.z, nz / l, 1e-6);
    assert_true(h.u >= 0.0f && h.u <= 1.0f && h.v >= 0.0f && h.v <= 1.0f);
    assert_true(tb_object_occluded(o, &r));
}

static void ti_expect_miss(const tb_object *o, tb_ray r)
{
    tb_hit h;
    if (tb_object_intersect(o, &r, &h))
        fail_msg("%s: unexpected hit at t = %g face %u", tb_prim_kind_name(o->kind), h.t, h.face);
    assert_false(tb_object_occluded(o, &r));
}

static tb_object *ti_simple(tb_prim_kind k, tb_mid_geometry g)
{
    tb_mid_object m = ti_prim(k, g, tb_transform_identity());
    return ti_build(&m, 7);
}

static void test_hits_by_hand(void **state)
{
    (void)state;
    tb_object *o;
    o = ti_simple(TB_PRIM_SPHERE, tb_mid_geometry_default(TB_PRIM_SPHERE));
    ti_expect(o, ti_ray(0, 0, -5, 0, 0, 1), 4.0, TB_FACE_SPHERE, 0, 0, -1);
    ti_expect(o, ti_ray(0, 0, 0, 0, 0, 2), 0.5, TB_FACE_SPHERE, 0, 0, 1); /* from inside: the way out */
    ti_expect_miss(o, ti_ray(0, 1.01, -5, 0, 0, 1));
    tb_object_free(o);

    o = ti_simple(TB_PRIM_CUBE, tb_mid_geometry_default(TB_PRIM_CUBE));
    ti_expect(o, ti_ray(-5, 0.5, 0.25, 1, 0, 0), 4.0, TB_FACE_CUBE_NEG_X, -1, 0, 0);
    ti_expect(o, ti_ray(0.5, 0.25, 5, 0, 0, -1), 4.0, TB_FACE_CUBE_POS_Z, 0, 0, 1);
    ti_expect(o, ti_ray(0.5, -3, 0.25, 0, 1, 0), 2.0, TB_FACE_CUBE_NEG_Y, 0, -1, 0);
    tb_object_free(o);

    o = ti_simple(TB_PRIM_CYLINDER, tb_mid_geometry_default(TB_PRIM_CYLINDER));
    ti_expect(o, ti_ray(0.5, 0, 5, 0, 0, -1), 4.0, TB_FACE_CYLINDER_TOP, 0, 0, 1);
    ti_expect(o, ti_ray(0.5, 0, -5, 0, 0, 1), 4.0, TB_FACE_CYLINDER_BOTTOM, 0, 0, -1);
    ti_expect(o, ti_ray(5, 0, 0.3, -1, 0, 0), 4.0, TB_FACE_CYLINDER_SIDE, 1, 0, 0);
    tb_object_free(o);

    tb_mid_geometry g = tb_mid_geometry_default(TB_PRIM_CYLINDER);
    g.cylinder.caps = false; /* open: the ray down the axis passes through */
    o = ti_simple(TB_PRIM_CYLINDER, g);
    ti_expect_miss(o, ti_ray(0.5, 0, 5, 0, 0, -1));
    ti_expect(o, ti_ray(0, 0, 0, 1, 0, 0), 1.0, TB_FACE_CYLINDER_SIDE, 1, 0, 0); /* inside wall */
    assert_false(o->closed);
    tb_object_free(o);

    o = ti_simple(TB_PRIM_CONE, tb_mid_geometry_default(TB_PRIM_CONE));
    ti_expect(o, ti_ray(5, 0, 0, -1, 0, 0), 4.5, TB_FACE_CONE_SIDE, 1, 0, 0.5);
    ti_expect(o, ti_ray(0.2, 0.1, -4, 0, 0, 1), 3.0, TB_FACE_CONE_BOTTOM, 0, 0, -1);
    tb_object_free(o);

    g = tb_mid_geometry_default(TB_PRIM_CONE);
    g.cone.top_radius = 0.5;
    o = ti_simple(TB_PRIM_CONE, g);
    ti_expect(o, ti_ray(0.2, 0.1, 4, 0, 0, -1), 3.0, TB_FACE_CONE_TOP, 0, 0, 1);
    ti_expect(o, ti_ray(-5, 0, 0, 1, 0, 0), 4.25, TB_FACE_CONE_SIDE, -1, 0, 0.25);
    tb_object_free(o);

    o = ti_simple(TB_PRIM_PYRAMID, tb_mid_geometry_default(TB_PRIM_PYRAMID));
    ti_expect(o, ti_ray(5, 0.1, 0, -1, 0, 0), 4.5, TB_FACE_PYRAMID_POS_X, 1, 0, 0.5);
    ti_expect(o, ti_ray(0.1, -5, 0, 0, 1, 0), 4.5, TB_FACE_PYRAMID_NEG_Y, 0, -1, 0.5);
    ti_expect(o, ti_ray(0.1, 0.2, -3, 0, 0, 1), 2.0, TB_FACE_PYRAMID_BOTTOM, 0, 0, -1);
    tb_object_free(o);

    g = tb_mid_geometry_default(TB_PRIM_PRISM); /* triangle (1,0) (-1/2, .866) (-1/2, -.866) */
    o = ti_simple(TB_PRIM_PRISM, g);
    ti_expect(o, ti_ray(-5, 0.1, 0, 1, 0, 0), 4.5, TB_FACE_PRISM_SIDE0 + 1, -1, 0, 0);
    ti_expect(o, ti_ray(0, 0, 5, 0, 0, -1), 4.0, TB_FACE_PRISM_TOP, 0, 0, 1);
    tb_object_free(o);

    /* An L-shaped (non-convex) profile, clockwise. */
    static const tb_vec2 L[6] = {{0, 0}, {0, 1}, {1, 1}, {1, 0.5f}, {0.5f, 0.5f}, {0.5f, 0}};
    g = tb_mid_geometry_default(TB_PRIM_PRISM);
    g.prism.sides = 0;
    g.prism.nprofile = 6;
    g.prism.profile = L;
    o = ti_simple(TB_PRIM_PRISM, g);
    assert_false(o->profile_convex);
    ti_expect(o, ti_ray(5, 0.25, 0, -1, 0, 0), 4.5, TB_FACE_PRISM_SIDE0 + 4, 1, 0, 0);
    ti_expect(o, ti_ray(5, 0.75, 0, -1, 0, 0), 4.0, TB_FACE_PRISM_SIDE0 + 2, 1, 0, 0);
    ti_expect(o, ti_ray(0.25, 0.25, 5, 0, 0, -1), 4.0, TB_FACE_PRISM_TOP, 0, 0, 1);
    ti_expect_miss(o, ti_ray(0.75, 0.25, 5, 0, 0, -1)); /* the notch */
    tb_object_free(o);

    o = ti_simple(TB_PRIM_TORUS, tb_mid_geometry_default(TB_PRIM_TORUS));
    ti_expect(o, ti_ray(1, 0, 5, 0, 0, -1), 4.75, TB_FACE_TORUS, 0, 0, 1);
    ti_expect(o, ti_ray(-5, 0, 0, 1, 0, 0), 3.75, TB_FACE_TORUS, -1, 0, 0);
    ti_expect_miss(o, ti_ray(0, 0, 5, 0, 0, -1)); /* through the hole */
    tb_object_free(o);

    o = ti_simple(TB_PRIM_CONIC, tb_mid_geometry_default(TB_PRIM_CONIC));
    ti_expect(o, ti_ray(0, 0, -5, 0, 0, 1), 4.0, TB_FACE_CONIC_SIDE, 0, 0, -1);
    ti_expect(o, ti_ray(-3, 0, 0, 1, 0, 0), 2.0, TB_FACE_CONIC_SIDE, -1, 0, 0);
    tb_object_free(o);

    o = ti_simple(TB_PRIM_SQUARE_ARCH, tb_mid_geometry_default(TB_PRIM_SQUARE_ARCH));
    ti_expect_miss(o, ti_ray(0, -5, 0, 0, 1, 0)); /* through the opening */
    ti_expect(o, ti_ray(0, -5, 0.8, 0, 1, 0), 4.0, TB_FACE_ARCH_NEG_Y, 0, -1, 0);
    ti_expect(o, ti_ray(0, 0, -5, 0, 0, 1), 5.5, TB_FACE_ARCH_CEILING, 0, 0, -1);
    ti_expect(o, ti_ray(0, 0, 0, 1, 0, 0), 0.5, TB_FACE_ARCH_INNER_RIGHT, -1, 0, 0);
    ti_expect(o, ti_ray(0, 0, 0, -1, 0, 0), 0.5, TB_FACE_ARCH_INNER_LEFT, 1, 0, 0);
    ti_expect(o, ti_ray(-0.75, 0.5, -3, 0, 0, 1), 2.0, TB_FACE_ARCH_BOTTOM, 0, 0, -1);
    tb_object_free(o);

    o = ti_simple(TB_PRIM_ROUND_ARCH, tb_mid_geometry_default(TB_PRIM_ROUND_ARCH)); /* zs = 0 */
    ti_expect(o, ti_ray(0, 0, -5, 0, 0, 1), 5.5, TB_FACE_ARCH_CEILING, 0, 0, -1);
    ti_expect(o, ti_ray(0.4, 0.2, -5, 0, 0, 1), 5.3, TB_FACE_ARCH_CEILING, -0.8, 0, -0.6);
    ti_expect(o, ti_ray(0, 0, -0.5, 1, 0, 0), 0.5, TB_FACE_ARCH_INNER_RIGHT, -1, 0, 0);
    tb_object_free(o);

    /* One triangle: hit from both sides, the normal stays on the front. */
    static const tb_vec3 tv[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    static const int ts[2] = {0, 3}, ti[3] = {0, 1, 2};
    g = tb_mid_geometry_default(TB_PRIM_POLYGONS);
    g.polygons.nvertices = 3;
    g.polygons.vertices = tv;
    g.polygons.nfaces = 1;
    g.polygons.face_start = ts;
    g.polygons.indices = ti;
    o = ti_simple(TB_PRIM_POLYGONS, g);
    assert_false(o->closed);
    ti_expect(o, ti_ray(0.25, 0.25, 3, 0, 0, -1), 3.0, 0, 0, 0, 1);
    ti_expect(o, ti_ray(0.25, 0.25, -2, 0, 0, 1), 2.0, 0, 0, 0, 1);
    ti_expect_miss(o, ti_ray(0.75, 0.75, -2, 0, 0, 1));
    tb_object_free(o);
}

static void test_transformed(void **state)
{
    (void)state;
    /* scale([2 1 1]) then translate([10 0 0]): an ellipsoid at x = 10. */
    tb_transform S, T = tb_transform_translate((tb_dvec3){10, 0, 0});
    assert_int_equal(tb_transform_scale((tb_dvec3){2, 1, 1}, &S), TB_OK);
    tb_transform M = tb_transform_compose(&T, &S);
    tb_mid_object m = ti_prim(TB_PRIM_SPHERE, tb_mid_geometry_default(TB_PRIM_SPHERE), M);
    tb_object *o = ti_build(&m, 3);
    ti_expect(o, ti_ray(0, 0, 0, 1, 0, 0), 8.0, 0, -1, 0, 0);
    ti_expect(o, ti_ray(0, 0, 0, 2, 0, 0), 4.0, 0, -1, 0, 0); /* t in units of |d| */
    /* On the ellipse x^2/4 + y^2 = 1 at (sqrt 2, 1/sqrt 2) the normal is along (x/4, y). */
    double x = sqrt(2.0), y = 1.0 / sqrt(2.0);
    ti_expect(o, ti_ray(10 + x, 5, 0, 0, -1, 0), 5.0 - y, 0, x / 4.0, y, 0);
    tb_hit h;
    tb_ray r = ti_ray(0, 0, 0, 1, 0, 0);
    assert_true(tb_object_intersect(o, &r, &h));
    assert_int_equal(h.object, 3);
    tb_object_free(o);

    /* A mirror keeps the normal outward. */
    assert_int_equal(tb_transform_scale((tb_dvec3){-1, 1, 1}, &S), TB_OK);
    m = ti_prim(TB_PRIM_CUBE, tb_mid_geometry_default(TB_PRIM_CUBE), S);
    o = ti_build(&m, 0);
    ti_expect(o, ti_ray(-5, 0.5, 0.25, 1, 0, 0), 4.0, TB_FACE_CUBE_POS_X, -1, 0, 0);
    tb_object_free(o);
}

static void test_tmin_tmax(void **state)
{
    (void)state;
    tb_object *o = ti_simple(TB_PRIM_SPHERE, tb_mid_geometry_default(TB_PRIM_SPHERE));
    tb_ray r = ti_ray(0, 0, -5, 0, 0, 1);
    tb_hit h;
    r.tmax = 3.999f;
    assert_false(tb_object_intersect(o, &r, &h));
    assert_false(tb_object_occluded(o, &r));
    r.tmax = 4.0f;
    assert_true(tb_object_intersect(o, &r, &h)); /* closed range */
    r.tmin = 4.5f;
    r.tmax = INFINITY;
    assert_true(tb_object_intersect(o, &r, &h));
    tb_assert_near(h.t, 6.0, 1e-6);
    assert_true(h.ng.z > 0.99f);
    r.tmin = 6.0001f;
    assert_false(tb_object_intersect(o, &r, &h));
    tb_object_free(o);
}

/* The streamed object may die: the built object holds copies. */
static void test_deep_copy(void **state)
{
    (void)state;
    tb_vec2 *prof = malloc(sizeof(tb_vec2) * 4);
    prof[0] = (tb_vec2){-1, -1};
    prof[1] = (tb_vec2){1, -1};
    prof[2] = (tb_vec2){1, 1};
    prof[3] = (tb_vec2){-1, 1};
    tb_mid_geometry g = tb_mid_geometry_default(TB_PRIM_PRISM);
    g.prism.sides = 0;
    g.prism.nprofile = 4;
    g.prism.profile = prof;
    tb_mid_object *m = malloc(sizeof *m);
    *m = ti_prim(TB_PRIM_PRISM, g, tb_transform_identity());
    char *name = malloc(8);
    strcpy(name, "box");
    m->name = name;
    tb_object *o = ti_build(m, 1);
    memset(prof, 0x7f, sizeof(tb_vec2) * 4);
    free(prof);
    memset(m, 0xff, sizeof *m);
    free(m);
    free(name);
    assert_string_equal(o->name, "box");
    ti_expect(o, ti_ray(-5, 0.5, 0.25, 1, 0, 0), 4.0, TB_FACE_PRISM_SIDE0 + 3, -1, 0, 0);
    tb_object_free(o);

    ti_mesh mesh = ti_cube_mesh(2);
    tb_mid_object mm = ti_prim(TB_PRIM_POLYGONS, ti_mesh_geom(&mesh), tb_transform_identity());
    o = ti_build(&mm, 0);
    ti_mesh_free(&mesh);
    assert_true(o->closed);
    assert_int_equal(o->nfaces, 24);
    ti_expect(o, ti_ray(-5, 0.5, 0.25, 1, 0, 0), 4.0, 0 * 4 + 1 * 2 + 1, -1, 0, 0);
    tb_object_free(o);
}

static tb_status ti_material(void *user, const tb_mid_material *m, int *index)
{
    int *calls = user;
    (*calls)++;
    *index = m->diffuse.rgb[0] > 0.7f ? 2 : 1;
    return TB_OK;
}

static tb_status ti_material_fail(void *user, const tb_mid_material *m, int *index)
{
    (void)user, (void)m, (void)index;
    return tb_error(TB_ERR_NOT_FOUND, "no such material");
}

/* CSG faces are numbered leaf by leaf (pre-order); materials per node. */
static void test_csg_numbering(void **state)
{
    (void)state;
    tb_transform id = tb_transform_identity();
    tb_mid_object kids[3] = {
        ti_prim(TB_PRIM_CUBE, tb_mid_geometry_default(TB_PRIM_CUBE), id),
        ti_prim(TB_PRIM_CYLINDER, tb_mid_geometry_default(TB_PRIM_CYLINDER), id),
        ti_prim(TB_PRIM_SPHERE, tb_mid_geometry_default(TB_PRIM_SPHERE), id),
    };
    kids[1].material.diffuse = tb_mid_color_grey(0.9f);
    tb_mid_object inner = ti_csg(TB_PRIM_DIFFERENCE, kids, 2, id);
    tb_mid_object outer_kids[2] = {inner, kids[2]};
    tb_mid_object top = ti_csg(TB_PRIM_UNION, outer_kids, 2, id);
    int calls = 0;
    tb_object *o = NULL;
    assert_int_equal(tb_object_from_mid(&top, 5, ti_material, &calls, &o), TB_OK);
    assert_int_equal(calls, 5);
    assert_int_equal(o->nfaces, 6 + 3 + 1);
    assert_int_equal(o->children[0].children[1].material, 2);
    assert_int_equal(o->children[0].children[0].material, 1);
    uint32_t local;
    const tb_object *leaf = tb_object_leaf_for_face(o, 7, &local);
    assert_non_null(leaf);
    assert_int_equal(leaf->kind, TB_PRIM_CYLINDER);
    assert_int_equal(local, 1);
    assert_true(leaf->flip);
    assert_false(o->children[0].children[0].flip);
    leaf = tb_object_leaf_for_face(o, 9, &local);
    assert_int_equal(leaf->kind, TB_PRIM_SPHERE);
    assert_null(tb_object_leaf_for_face(o, 10, &local));
    assert_int_equal(tb_param_face_count(TB_PRIM_CUBE, &kids[0].geom), 6);
    tb_object_free(o);
    assert_int_equal(tb_object_from_mid(&top, 5, ti_material_fail, NULL, &o), TB_ERR_NOT_FOUND);
    assert_null(o);
}

static void ti_expect_reject(const tb_mid_object *m, tb_status want, const char *what)
{
    tb_object *o = (tb_object *)1;
    tb_status st = tb_object_from_mid(m, 0, NULL, NULL, &o);
    if (st != want)
        fail_msg("%s: status %d (%s), expected %d", what, (int)st, tb_last_error(), (int)want);
    assert_null(o);
    assert_true(strlen(tb_last_error()) > 0);
}

static void test_rejections(void **state)
{
    (void)state;
    tb_transform id = tb_transform_identity();
    tb_mid_object m = ti_prim(TB_PRIM_SPHERE, tb_mid_geometry_default(TB_PRIM_SPHERE), id);
    m.to_world.m.m[0][0] = 0.0; /* singular, with a stale inverse */
    m.to_world.inv = m.to_world.m;
    ti_expect_reject(&m, TB_ERR_ARG, "singular transform");
    m.to_world = id;
    m.to_world.m.m[1][1] = NAN;
    ti_expect_reject(&m, TB_ERR_ARG, "NaN transform");
    m.to_world = id;
    m.to_world.m.m[3][0] = 0.5;
    ti_expect_reject(&m, TB_ERR_ARG, "projective transform");
    m.to_world = id;
    m.to_world.m.m[0][0] = 2.0; /* inverse not updated */
    ti_expect_reject(&m, TB_ERR_ARG, "inconsistent inverse");

    tb_mid_geometry g = tb_mid_geometry_default(TB_PRIM_TORUS);
    g.torus.minor = 2.0;
    m = ti_prim(TB_PRIM_TORUS, g, id);
    ti_expect_reject(&m, TB_ERR_ARG, "torus minor > major");
    g = tb_mid_geometry_default(TB_PRIM_CONE);
    g.cone.top_radius = -1;
    m = ti_prim(TB_PRIM_CONE, g, id);
    ti_expect_reject(&m, TB_ERR_ARG, "negative top radius");
    g = tb_mid_geometry_default(TB_PRIM_PRISM);
    g.prism.sides = 2;
    m = ti_prim(TB_PRIM_PRISM, g, id);
    ti_expect_reject(&m, TB_ERR_ARG, "2-sided prism");
    static const tb_vec2 flat[3] = {{0, 0}, {1, 0}, {2, 0}};
    g.prism.sides = 0;
    g.prism.nprofile = 3;
    g.prism.profile = flat;
    m = ti_prim(TB_PRIM_PRISM, g, id);
    ti_expect_reject(&m, TB_ERR_ARG, "zero-area profile");
    g = tb_mid_geometry_default(TB_PRIM_CONIC);
    g.conic.c[0] = -1.0; /* r^2 < 0 at the ends */
    m = ti_prim(TB_PRIM_CONIC, g, id);
    ti_expect_reject(&m, TB_ERR_ARG, "imaginary conic");
    g = tb_mid_geometry_default(TB_PRIM_ROUND_ARCH);
    g.arch.height = 0.2;
    m = ti_prim(TB_PRIM_ROUND_ARCH, g, id);
    ti_expect_reject(&m, TB_ERR_ARG, "round arch lower than its half width");

    static const tb_vec3 tv[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    static const int ts[2] = {0, 3}, bad[3] = {0, 1, 3};
    g = tb_mid_geometry_default(TB_PRIM_POLYGONS);
    g.polygons.nvertices = 3;
    g.polygons.vertices = tv;
    g.polygons.nfaces = 1;
    g.polygons.face_start = ts;
    g.polygons.indices = bad;
    m = ti_prim(TB_PRIM_POLYGONS, g, id);
    ti_expect_reject(&m, TB_ERR_ARG, "index out of range");
    g.polygons.nfaces = 0;
    m = ti_prim(TB_PRIM_POLYGONS, g, id);
    ti_expect_reject(&m, TB_ERR_ARG, "no faces");

    /* CSG: too few children, open children. */
    tb_mid_object kids[2] = {ti_prim(TB_PRIM_CUBE, tb_mid_geometry_default(TB_PRIM_CUBE), id),
                             ti_prim(TB_PRIM_CYLINDER, tb_mid_geometry_default(TB_PRIM_CYLINDER), id)};
    m = ti_csg(TB_PRIM_DIFFERENCE, kids, 1, id);
    ti_expect_reject(&m, TB_ERR_ARG, "difference of one");
    kids[1].geom.cylinder.caps = false;
    m = ti_csg(TB_PRIM_UNION, kids, 2, id);
    ti_expect_reject(&m, TB_ERR_ARG, "open cylinder in CSG");
    g = tb_mid_geometry_default(TB_PRIM_POLYGONS);
    g.polygons.nvertices = 3;
    g.polygons.vertices = tv;
    g.polygons.nfaces = 1;
    g.polygons.face_start = ts;
    static const int ok[3] = {0, 1, 2};
    g.polygons.indices = ok;
    kids[1] = ti_prim(TB_PRIM_POLYGONS, g, id);
    m = ti_csg(TB_PRIM_INTERSECTION, kids, 2, id);
    ti_expect_reject(&m, TB_ERR_ARG, "open mesh in CSG");
    /* A conic closed by its poles needs no caps. */
    g = tb_mid_geometry_default(TB_PRIM_CONIC);
    g.conic.caps = false;
    kids[1] = ti_prim(TB_PRIM_CONIC, g, id);
    m = ti_csg(TB_PRIM_INTERSECTION, kids, 2, id);
    tb_object *o = ti_build(&m, 0);
    tb_object_free(o);
}


/* Polygons from FED files: a closed cube (usable in CSG) and an open square
 * face with a square hole (rays through the hole pass). */
static void test_fed_mesh(void **state)
{
    (void)state;
    static const tb_vec3 cv[8] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                  {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
    static const uint32_t quads[24] = {0, 3, 2, 1, 4, 5, 6, 7, 0, 1, 5, 4, 2, 3, 7, 6, 1, 2, 6, 5, 0, 4, 7, 3};
    static const uint32_t four[6] = {4, 4, 4, 4, 4, 4};
    tb_fed_desc d = {0};
    d.nverts = 8, d.positions = cv, d.nfaces = 6, d.nloops = 6, d.loop_sizes = four, d.corners = quads;
    tb_fed *fed = NULL;
    assert_int_equal(tb_fed_build(&d, &fed, NULL), TB_OK);
    char path[1024];
    snprintf(path, sizeof path, "%s/isect_cube.fed", tb_test_tmpdir());
    assert_int_equal(tb_fed_write_file(path, fed, TB_FED_FORMAT_TEXT), TB_OK);
    tb_fed_free(fed);

    tb_mid_geometry g = tb_mid_geometry_default(TB_PRIM_POLYGONS);
    g.polygons.mesh.text = "isect_cube.fed";
    g.polygons.mesh.path = path;
    tb_mid_object m = ti_prim(TB_PRIM_POLYGONS, g, tb_transform_identity());
    tb_object *o = ti_build(&m, 0);
    assert_true(o->closed);
    assert_non_null(o->fed);
    assert_null(o->geom.polygons.mesh.text); /* inline form for param and bounds */
    assert_non_null(o->fed->fed);
    assert_string_equal(o->fed->file.text, "isect_cube.fed");
    assert_int_equal(o->geom.polygons.nfaces, 6);
    ti_expect(o, ti_ray(-5, 0.5, 0.25, 1, 0, 0), 4.0, 5, -1, 0, 0);
    ti_expect(o, ti_ray(0.5, 0.25, 5, 0, 0, -1), 4.0, 1, 0, 0, 1);
    tb_object_free(o);
    tb_transform half;
    assert_int_equal(tb_transform_scale((tb_dvec3){0.5, 0.5, 0.5}, &half), TB_OK);
    tb_mid_object kids[2] = {m, ti_prim(TB_PRIM_SPHERE, tb_mid_geometry_default(TB_PRIM_SPHERE), half)};
    tb_mid_object diff = ti_csg(TB_PRIM_DIFFERENCE, kids, 2, tb_transform_identity());
    o = ti_build(&diff, 0);
    ti_expect(o, ti_ray(0, 0, 0, 1, 0, 0), 0.5, 6, -1, 0, 0); /* the sphere's wall, flipped */
    tb_object_free(o);

    /* A square [-1,1]^2 at z = 0 with the hole [-0.5,0.5]^2 (turning the other way). */
    static const tb_vec3 hv[8] = {{-1, -1, 0},     {1, -1, 0},     {1, 1, 0},     {-1, 1, 0},
                                  {-0.5f, -0.5f, 0}, {-0.5f, 0.5f, 0}, {0.5f, 0.5f, 0}, {0.5f, -0.5f, 0}};
    static const uint32_t hc[8] = {0, 1, 2, 3, 4, 5, 6, 7}, hl[2] = {4, 4}, hn[1] = {2};
    d = (tb_fed_desc){0};
    d.nverts = 8, d.positions = hv, d.nfaces = 1, d.face_nloops = hn, d.nloops = 2, d.loop_sizes = hl, d.corners = hc;
    assert_int_equal(tb_fed_build(&d, &fed, NULL), TB_OK);
    snprintf(path, sizeof path, "%s/isect_hole.fed", tb_test_tmpdir());
    assert_int_equal(tb_fed_write_file(path, fed, TB_FED_FORMAT_AUTO), TB_OK);
    tb_fed_free(fed);
    g.polygons.mesh.text = "isect_hole.fed";
    m = ti_prim(TB_PRIM_POLYGONS, g, tb_transform_identity());
    o = ti_build(&m, 0);
    assert_false(o->closed);
    ti_expect_miss(o, ti_ray(0.1, 0.2, 3, 0, 0, -1));
    ti_expect(o, ti_ray(0.75, 0.2, 3, 0, 0, -1), 3.0, 0, 0, 0, 1);
    tb_object_free(o);

    /* A missing file: the reader's error, with the file named. */
    g.polygons.mesh.text = "nowhere.fed";
    g.polygons.mesh.path = "/nonexistent/nowhere.fed";
    m = ti_prim(TB_PRIM_POLYGONS, g, tb_transform_identity());
    o = NULL;
    assert_int_not_equal(tb_object_from_mid(&m, 0, NULL, NULL, &o), TB_OK);
    assert_null(o);
    assert_non_null(strstr(tb_last_error(), "nowhere.fed"));
}

/* Clears inv_affine in o's tree (the world -> object mapping's general
 * path, tb_mat4_mul_point / mul_vec); returns how many nodes had it set. */
static int ti_clear_affine(tb_object *o)
{
    int n = o->inv_affine ? 1 : 0;
    o->inv_affine = false;
    for (int i = 0; i < o->nchildren; i++)
        n += ti_clear_affine(&o->children[i]);
    return n;
}

/* inv_affine is set on every built node, and its fast path maps rays as the
 * general path does: hits (t, face, u, v, normal) and occlusion of a
 * sphere, a cylinder and a CSG difference under random transforms (mirrors
 * included) are bit for bit the same with the flag cleared. Fails when the
 * fast path's arithmetic differs from tb_mat4_mul_point / mul_vec. */
static void test_affine_fast_path(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("affine_fast_path", 11), 1);
    const tb_prim_kind kinds[2] = {TB_PRIM_SPHERE, TB_PRIM_CYLINDER};
    long hits = 0;
    for (int i = 0; i < 30; i++) {
        tb_transform xf = ti_random_transform(&r, 0.2, 5.0, 10.0, true);
        tb_mid_object m = ti_prim(kinds[i % 2], tb_mid_geometry_default(kinds[i % 2]), xf);
        tb_mid_object kids[2] = {ti_prim(TB_PRIM_CUBE, tb_mid_geometry_default(TB_PRIM_CUBE),
                                         ti_random_transform(&r, 0.5, 2.0, 0.3, true)),
                                 ti_prim(TB_PRIM_SPHERE, tb_mid_geometry_default(TB_PRIM_SPHERE),
                                         ti_random_transform(&r, 0.5, 1.5, 0.5, false))};
        if (i % 3 == 2) { /* a difference of a cube and a sphere */
            m.kind = TB_PRIM_DIFFERENCE;
            m.children = kids;
            m.nchildren = 2;
        }
        tb_object *fast = ti_build(&m, 0), *slow = ti_build(&m, 0);
        assert_int_equal(ti_clear_affine(slow), 1 + slow->nchildren);
        for (int k = 0; k < 300; k++) {
            tb_dvec3 c = tb_transform_dpoint(&fast->to_world, (tb_dvec3){0, 0, 0});
            tb_dvec3 u = ti_sphere_dir(&r), v = ti_sphere_dir(&r);
            double dist = 3.0 * fast->scale;
            tb_vec3 o = {(float)(c.x + dist * u.x), (float)(c.y + dist * u.y), (float)(c.z + dist * u.z)};
            tb_vec3 d = {(float)(c.x + 0.5 * fast->scale * v.x - o.x), (float)(c.y + 0.5 * fast->scale * v.y - o.y),
                         (float)(c.z + 0.5 * fast->scale * v.z - o.z)};
            tb_ray ray = tb_ray_make(o, d, 0.0f, INFINITY);
            tb_hit h1, h2;
            bool b1 = tb_object_intersect(fast, &ray, &h1), b2 = tb_object_intersect(slow, &ray, &h2);
            assert_int_equal(b1, b2);
            if (b1) {
                hits++;
                assert_memory_equal(&h1, &h2, sizeof h1);
                ray.tmax = h1.t;
            }
            assert_int_equal(tb_object_occluded(fast, &ray), tb_object_occluded(slow, &ray));
        }
        tb_object_free(fast);
        tb_object_free(slow);
    }
    assert_true(hits > 3000);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hits_by_hand),  cmocka_unit_test(test_transformed),
        cmocka_unit_test(test_tmin_tmax),     cmocka_unit_test(test_deep_copy),
        cmocka_unit_test(test_csg_numbering), cmocka_unit_test(test_rejections),
        cmocka_unit_test(test_fed_mesh),
        cmocka_unit_test(test_affine_fast_path),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
