/* CSG by interval lists.
 *
 * Property test: random trees (depth <= 3, union / intersection / difference)
 * of random closed primitives of every kind under random transforms; along
 * random rays, points sampled inside every reported interval must be inside
 * the CSG expression and points in the gaps outside it, by brute-force
 * point membership (test_isect_common.h, written from docs/mid.md); the
 * closest hit must be the first interval end at t >= 0, with a normal facing
 * against the ray when entering and along it when leaving.
 *
 * Coincident surfaces, by the rules of csg.h: A u A = A, A n A = A, A - A is
 * empty, touching solids have no inner face, a pocket cut flush with a face
 * is open, a shared face of an intersection belongs to the first child, and
 * subtracted surfaces have flipped normals. */
#include "test_isect_common.h"

#include "host/object/csg.h"
#include "host/object/intersect.h"
#include "host/object/param.h"

/* ------------------------------------------------------------------ random trees */

typedef struct ti_pool {
    tb_mid_object objs[64];
    int n;
    ti_mesh mesh;
    tb_vec2 L[6];
} ti_pool;

static tb_mid_object *ti_alloc(ti_pool *p)
{
    assert_true(p->n < 64);
    return &p->objs[p->n++];
}

static tb_transform ti_local(tb_rng *r)
{
    tb_transform t = ti_random_transform(r, 0.3, 1.3, 0.8, true);
    return t;
}

/* A random closed primitive placed by world transform xf. */
static tb_mid_object ti_random_leaf(tb_rng *r, ti_pool *p, tb_transform xf)
{
    static const tb_prim_kind kinds[] = {TB_PRIM_SPHERE,  TB_PRIM_CUBE,        TB_PRIM_CYLINDER,   TB_PRIM_CONE,
                                         TB_PRIM_PYRAMID, TB_PRIM_PRISM,       TB_PRIM_TORUS,      TB_PRIM_POLYGONS,
                                         TB_PRIM_CONIC,   TB_PRIM_SQUARE_ARCH, TB_PRIM_ROUND_ARCH};
    tb_prim_kind k = kinds[tb_rng_below(r, sizeof kinds / sizeof kinds[0])];
    tb_mid_geometry g = tb_mid_geometry_default(k);
    switch (k) {
    case TB_PRIM_CONE: g.cone.top_radius = tb_rng_below(r, 2) ? 0.0 : ti_uniform(r, 0.2, 1.5); break;
    case TB_PRIM_PYRAMID: g.pyramid.top = tb_rng_below(r, 2) ? 0.0 : ti_uniform(r, 0.2, 1.5); break;
    case TB_PRIM_PRISM:
        if (tb_rng_below(r, 3) == 0) {
            g.prism.sides = 0;
            g.prism.nprofile = 6;
            g.prism.profile = p->L;
        } else {
            g.prism.sides = 3 + (int)tb_rng_below(r, 6);
        }
        break;
    case TB_PRIM_TORUS: g.torus.minor = ti_uniform(r, 0.1, 0.6); break;
    case TB_PRIM_POLYGONS: g = ti_mesh_geom(&p->mesh); break;
    case TB_PRIM_CONIC: {
        int f = (int)tb_rng_below(r, 3);
        if (f == 1) { /* paraboloid */
            g.conic.c[0] = 0.5, g.conic.c[1] = -0.5, g.conic.c[2] = 0.0;
        } else if (f == 2) { /* hyperboloid of one sheet */
            g.conic.c[0] = 0.3, g.conic.c[1] = 0.1, g.conic.c[2] = 0.6;
        }
        break;
    }
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH:
        g.arch.width = ti_uniform(r, 0.3, 1.6);
        g.arch.height = ti_uniform(r, 0.5 * g.arch.width + 0.05, 1.9);
        break;
    default: break;
    }
    return ti_prim(k, g, xf);
}

static tb_mid_object ti_random_tree(tb_rng *r, ti_pool *p, tb_transform parent, int depth)
{
    tb_transform loc = ti_local(r);
    tb_transform xf = tb_transform_compose(&parent, &loc);
    if (depth == 0 || tb_rng_below(r, 3) == 0)
        return ti_random_leaf(r, p, xf);
    static const tb_prim_kind ops[] = {TB_PRIM_UNION, TB_PRIM_INTERSECTION, TB_PRIM_DIFFERENCE};
    tb_prim_kind k = ops[tb_rng_below(r, 3)];
    int n = 2 + (int)tb_rng_below(r, 2);
    tb_mid_object *kids = &p->objs[p->n];
    assert_true(p->n + n <= 64);
    p->n += n;
    for (int i = 0; i < n; i++)
        kids[i] = ti_random_tree(r, p, xf, depth - 1);
    /* An intersection of unrelated solids is often empty: pull the second
     * child onto the first now and then by giving it the same placement. */
    return ti_csg(k, kids, n, xf);
}

/* ------------------------------------------------------------------ the property */

typedef struct ti_cstats {
    long rays, intervals, samples, wrong_inside, wrong_outside, bad_hit, bad_normal, bad_order;
} ti_cstats;

static bool ti_near_end(double t, const float *a, const float *b, int n, double tol)
{
    for (int i = 0; i < n; i++)
        if (fabs(t - a[i]) <= tol || fabs(t - b[i]) <= tol)
            return true;
    return false;
}

static void ti_check_sample(const tb_object *o, const tb_ray *ray, double t, bool expect_in, ti_cstats *S)
{
    tb_dvec3 p = {ray->o.x + t * ray->d.x, ray->o.y + t * ray->d.y, ray->o.z + t * ray->d.z};
    bool in = ti_inside_object(o, p);
    S->samples++;
    if (in != expect_in) {
        if (expect_in)
            S->wrong_inside++;
        else
            S->wrong_outside++;
        if (S->wrong_inside + S->wrong_outside <= 3)
            print_message("t = %.9g: reference says %s, intervals say %s (o = %.9g %.9g %.9g, d = %.9g %.9g "
                          "%.9g)\n",
                          t, in ? "inside" : "outside", expect_in ? "inside" : "outside", ray->o.x, ray->o.y,
                          ray->o.z, ray->d.x, ray->d.y, ray->d.z);
    }
}

static void ti_check_ray(const tb_object *o, tb_rng *r, const tb_ray *ray, ti_cstats *S)
{
    float a[64], b[64];
    int n = tb_object_intervals(o, ray, a, b, 64);
    assert_true(n <= 64);
    S->rays++;
    S->intervals += n;
    for (int i = 0; i < n; i++)
        if (!(a[i] <= b[i]) || (i > 0 && !(b[i - 1] <= a[i])))
            S->bad_order++;
    /* Samples: interval and gap midpoints and random points, on t in [-1, 3]
     * (the ray passes the objects' region around t = 1), away from the ends. */
    double tol = 1e-5;
    for (int i = 0; i <= n; i++) {
        double lo = i == 0 ? -1.0 : b[i - 1], hi = i == n ? 3.0 : a[i];
        if (hi > lo) /* a gap */
            for (int s = 0; s < 3; s++) {
                double t = s == 0 ? 0.5 * (lo + hi) : lo + (hi - lo) * tb_rng_double(r);
                if (!ti_near_end(t, a, b, n, tol))
                    ti_check_sample(o, ray, t, false, S);
            }
        if (i < n)
            for (int s = 0; s < 3; s++) {
                double t = s == 0 ? 0.5 * ((double)a[i] + b[i]) : a[i] + (b[i] - a[i]) * tb_rng_double(r);
                if (!ti_near_end(t, a, b, n, tol))
                    ti_check_sample(o, ray, t, true, S);
            }
    }
    /* The closest hit is the first end at t >= tmin = 0. */
    float first = INFINITY;
    bool entering = false;
    for (int i = 0; i < n && first == INFINITY; i++) {
        if (a[i] >= 0.0f) {
            first = a[i];
            entering = true;
        } else if (b[i] >= 0.0f) {
            first = b[i];
        }
    }
    tb_hit h;
    bool hit = tb_object_intersect(o, ray, &h);
    if (hit != (first < INFINITY) || (hit && h.t != first) || hit != tb_object_occluded(o, ray)) {
        if (S->bad_hit++ < 3)
            print_message("closest hit %s t = %.9g, first interval end %.9g\n", hit ? "at" : "none", hit ? h.t : 0.0,
                          first);
        return;
    }
    if (hit) {
        double dl = sqrt((double)ray->d.x * ray->d.x + (double)ray->d.y * ray->d.y + (double)ray->d.z * ray->d.z);
        double c = ((double)h.ng.x * ray->d.x + (double)h.ng.y * ray->d.y + (double)h.ng.z * ray->d.z) / dl;
        double len = sqrt((double)h.ng.x * h.ng.x + (double)h.ng.y * h.ng.y + (double)h.ng.z * h.ng.z);
        /* Entering: the normal faces the ray; leaving: along it (grazing hits excepted). */
        if (fabs(len - 1.0) > 1e-6 || (fabs(c) > 1e-3 && (c < 0) != entering))
            if (S->bad_normal++ < 3)
                print_message("normal (%g %g %g) . d = %g when %s\n", h.ng.x, h.ng.y, h.ng.z, c,
                              entering ? "entering" : "leaving");
        uint32_t local;
        assert_non_null(tb_object_leaf_for_face(o, h.face, &local));
    }
}

static void test_csg_property(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("csg_property", 555), 3);
    ti_pool *pool = calloc(1, sizeof *pool);
    pool->mesh = ti_cube_mesh(2);
    const tb_vec2 L[6] = {{-1, -1}, {-1, 1}, {1, 1}, {1, 0}, {0, 0}, {0, -1}};
    memcpy(pool->L, L, sizeof L);
    ti_cstats S = {0};
    long ntrees = ti_count(400, 40), nrays = 150;
    for (long ti = 0; ti < ntrees; ti++) {
        pool->n = 0;
        tb_mid_object *top = ti_alloc(pool);
        *top = ti_random_tree(&r, pool, tb_transform_identity(), 3);
        tb_object *o = ti_build(top, (uint32_t)ti);
        for (long k = 0; k < nrays; k++) {
            tb_dvec3 u = ti_sphere_dir(&r);
            /* Through a point inside the solid when one is found quickly. */
            tb_dvec3 target = {0, 0, 0};
            for (int tries = 0; tries < 30; tries++) {
                target = (tb_dvec3){ti_uniform(&r, -1.5, 1.5), ti_uniform(&r, -1.5, 1.5), ti_uniform(&r, -1.5, 1.5)};
                if (ti_inside_object(o, target))
                    break;
            }
            tb_vec3 orig = {(float)(target.x + 4 * u.x), (float)(target.y + 4 * u.y), (float)(target.z + 4 * u.z)};
            tb_vec3 d = {(float)target.x - orig.x, (float)target.y - orig.y, (float)target.z - orig.z};
            tb_ray ray = tb_ray_make(orig, d, 0.0f, INFINITY);
            if (k % 4 == 3) /* some rays start inside the region */
                ray.o = (tb_vec3){(float)target.x, (float)target.y, (float)target.z};
            ti_check_ray(o, &r, &ray, &S);
        }
        tb_object_free(o);
    }
    print_message("%ld trees, %ld rays, %ld intervals, %ld samples: %ld wrongly inside, %ld wrongly outside, %ld "
                  "closest-hit errors, %ld normal errors, %ld order errors\n",
                  ntrees, S.rays, S.intervals, S.samples, S.wrong_inside, S.wrong_outside, S.bad_hit, S.bad_normal,
                  S.bad_order);
    ti_mesh_free(&pool->mesh);
    free(pool);
    assert_true(S.intervals > S.rays / 3);
    assert_int_equal(S.wrong_inside + S.wrong_outside, 0);
    assert_int_equal(S.bad_hit, 0);
    assert_int_equal(S.bad_normal, 0);
    assert_int_equal(S.bad_order, 0);
}

/* ------------------------------------------------------------------ coincident surfaces */

static tb_ray ti_ray(double ox, double oy, double oz, double dx, double dy, double dz)
{
    return tb_ray_make((tb_vec3){(float)ox, (float)oy, (float)oz}, (tb_vec3){(float)dx, (float)dy, (float)dz}, 0.0f,
                       INFINITY);
}

static int ti_intervals(const tb_object *o, tb_ray r, float *a, float *b) { return tb_object_intervals(o, &r, a, b, 8); }

static void test_csg_coincident(void **state)
{
    (void)state;
    tb_transform id = tb_transform_identity();
    tb_mid_geometry gs = tb_mid_geometry_default(TB_PRIM_SPHERE), gc = tb_mid_geometry_default(TB_PRIM_CUBE);
    float a[8], b[8];
    tb_hit h;
    tb_ray r = ti_ray(-5, 0.3, 0.2, 1, 0, 0);

    /* A u A, A n A: as A; A - A: nothing. The twin is rotated by 90 degrees
     * (exact), so its crossings are computed from different numbers. */
    tb_transform rot;
    assert_int_equal(tb_transform_rotate_deg(90.0, (tb_dvec3){0, 0, 1}, &rot), TB_OK);
    tb_mid_object twins[2] = {ti_prim(TB_PRIM_CUBE, gc, id), ti_prim(TB_PRIM_CUBE, gc, rot)};
    tb_prim_kind ops[3] = {TB_PRIM_UNION, TB_PRIM_INTERSECTION, TB_PRIM_DIFFERENCE};
    for (int i = 0; i < 3; i++) {
        tb_mid_object m = ti_csg(ops[i], twins, 2, id);
        tb_object *o = ti_build(&m, 0);
        int n = ti_intervals(o, r, a, b);
        if (ops[i] == TB_PRIM_DIFFERENCE) {
            assert_int_equal(n, 0);
            assert_false(tb_object_intersect(o, &r, &h));
            assert_false(tb_object_occluded(o, &r));
        } else {
            assert_int_equal(n, 1);
            tb_assert_near(a[0], 4.0, 1e-6);
            tb_assert_near(b[0], 6.0, 1e-6);
            assert_true(tb_object_intersect(o, &r, &h));
            assert_int_equal(h.face, TB_FACE_CUBE_NEG_X); /* the first child's face */
        }
        tb_object_free(o);
    }

    /* Two cubes sharing the face x = 1: one solid, no inner face. */
    tb_transform t2 = tb_transform_translate((tb_dvec3){2, 0, 0});
    tb_mid_object pair[2] = {ti_prim(TB_PRIM_CUBE, gc, id), ti_prim(TB_PRIM_CUBE, gc, t2)};
    tb_mid_object u = ti_csg(TB_PRIM_UNION, pair, 2, id);
    tb_object *o = ti_build(&u, 0);
    assert_int_equal(ti_intervals(o, r, a, b), 1);
    tb_assert_near(a[0], 4.0, 1e-6);
    tb_assert_near(b[0], 8.0, 1e-6);
    tb_ray inside = ti_ray(0.5, 0.3, 0.2, 1, 0, 0);
    assert_true(tb_object_intersect(o, &inside, &h));
    tb_assert_near(h.t, 2.5, 1e-6);
    assert_int_equal(h.face, 6 + TB_FACE_CUBE_POS_X);
    tb_object_free(o);

    /* A pocket cut flush with the top face (the cutter's top is 1 up to
     * rounding: 1/3 + 2/3): open at the top, its floor faces up. */
    tb_transform s3, t3;
    assert_int_equal(tb_transform_scale((tb_dvec3){0.5, 0.5, 1.0 / 3.0}, &s3), TB_OK);
    t3 = tb_transform_translate((tb_dvec3){0, 0, 2.0 / 3.0});
    tb_transform cut = tb_transform_compose(&t3, &s3);
    tb_mid_object pk[2] = {ti_prim(TB_PRIM_CUBE, gc, id), ti_prim(TB_PRIM_CUBE, gc, cut)};
    tb_mid_object d = ti_csg(TB_PRIM_DIFFERENCE, pk, 2, id);
    o = ti_build(&d, 0);
    tb_ray down = ti_ray(0.1, 0.2, 5, 0, 0, -1);
    assert_true(tb_object_intersect(o, &down, &h));
    tb_assert_near(h.t, 5.0 - 1.0 / 3.0, 1e-6); /* the floor at z = 1/3 */
    assert_int_equal(h.face, 6 + TB_FACE_CUBE_NEG_Z);
    tb_assert_near(h.ng.z, 1.0, 1e-6); /* flipped: out of the result, up into the pocket */
    tb_ray beside = ti_ray(0.8, 0.2, 5, 0, 0, -1);
    assert_true(tb_object_intersect(o, &beside, &h));
    tb_assert_near(h.t, 4.0, 1e-6);
    assert_int_equal(h.face, TB_FACE_CUBE_POS_Z);
    tb_object_free(o);

    /* Intersection sharing a face: the first child's surface. */
    tb_transform sq, sh;
    assert_int_equal(tb_transform_scale((tb_dvec3){1, 1, 0.5}, &sq), TB_OK);
    sh = tb_transform_translate((tb_dvec3){0, 0, 0.5});
    tb_transform slab = tb_transform_compose(&sh, &sq); /* z in [0, 1] */
    tb_mid_object ik[2] = {ti_prim(TB_PRIM_CUBE, gc, id), ti_prim(TB_PRIM_CUBE, gc, slab)};
    tb_mid_object in = ti_csg(TB_PRIM_INTERSECTION, ik, 2, id);
    o = ti_build(&in, 0);
    assert_true(tb_object_intersect(o, &down, &h));
    tb_assert_near(h.t, 4.0, 1e-6);
    assert_int_equal(h.face, TB_FACE_CUBE_POS_Z); /* both tops at z = 1; child 0 wins */
    tb_ray upward = ti_ray(0.1, 0.2, -5, 0, 0, 1);
    assert_true(tb_object_intersect(o, &upward, &h));
    tb_assert_near(h.t, 5.0, 1e-6); /* z = 0: child 1's bottom */
    assert_int_equal(h.face, 6 + TB_FACE_CUBE_NEG_Z);
    tb_object_free(o);

    /* A cavity: cube minus sphere of radius 1/2; from inside the cavity the
     * wall's normal points into the cavity (out of the result). */
    tb_transform half;
    assert_int_equal(tb_transform_scale((tb_dvec3){0.5, 0.5, 0.5}, &half), TB_OK);
    tb_mid_object cv[2] = {ti_prim(TB_PRIM_CUBE, gc, id), ti_prim(TB_PRIM_SPHERE, gs, half)};
    tb_mid_object cav = ti_csg(TB_PRIM_DIFFERENCE, cv, 2, id);
    o = ti_build(&cav, 0);
    assert_int_equal(ti_intervals(o, ti_ray(-5, 0, 0, 1, 0, 0), a, b), 2);
    tb_assert_near(b[0], 4.5, 1e-6);
    tb_assert_near(a[1], 5.5, 1e-6);
    tb_ray mid = ti_ray(0, 0, 0, 1, 0, 0);
    assert_true(tb_object_intersect(o, &mid, &h));
    tb_assert_near(h.t, 0.5, 1e-6);
    assert_int_equal(h.face, 6 + TB_FACE_SPHERE);
    tb_assert_near(h.ng.x, -1.0, 1e-6);
    tb_object_free(o);

    /* Order of children changes surfaces only by the stated rule, never the intervals. */
    tb_mid_object ab[2] = {ti_prim(TB_PRIM_SPHERE, gs, id), ti_prim(TB_PRIM_CUBE, gc, half)};
    tb_mid_object ba[2] = {ab[1], ab[0]};
    tb_mid_object m1 = ti_csg(TB_PRIM_UNION, ab, 2, id), m2 = ti_csg(TB_PRIM_UNION, ba, 2, id);
    tb_object *o1 = ti_build(&m1, 0), *o2 = ti_build(&m2, 0);
    float a2[8], b2[8];
    tb_ray diag = ti_ray(-3, -2.9, -3.1, 1, 1, 1);
    int n1 = ti_intervals(o1, diag, a, b), n2 = ti_intervals(o2, diag, a2, b2);
    assert_int_equal(n1, n2);
    for (int i = 0; i < n1; i++)
        assert_true(a[i] == a2[i] && b[i] == b2[i]);
    tb_object_free(o1);
    tb_object_free(o2);
}

/* More than 32 ends in one node: the sweep sorts them with qsort instead of
 * insertion sort (csg.c; it once called itself there, without end). A union
 * of 20 unit spheres 3 apart along x, children in scrambled order, crossed
 * along x: 40 ends, 20 intervals [3i - 1, 3i + 1] + 5 from o.x = -5. */
static void test_csg_many_ends(void **state)
{
    (void)state;
    enum { N = 20 };
    tb_transform id = tb_transform_identity();
    tb_mid_geometry gs = tb_mid_geometry_default(TB_PRIM_SPHERE);
    tb_mid_object kids[N];
    for (int i = 0; i < N; i++) {
        int at = (7 * i) % N; /* a permutation: the lists arrive out of order */
        kids[i] = ti_prim(TB_PRIM_SPHERE, gs, tb_transform_translate((tb_dvec3){3.0 * at, 0, 0}));
    }
    tb_mid_object m = ti_csg(TB_PRIM_UNION, kids, N, id);
    tb_object *o = ti_build(&m, 0);
    tb_ray r = ti_ray(-5, 0, 0, 1, 0, 0);
    float a[N + 2], b[N + 2];
    assert_int_equal(tb_object_intervals(o, &r, a, b, N + 2), N);
    for (int i = 0; i < N; i++) {
        tb_assert_near(a[i], 3.0 * i - 1.0 + 5.0, 1e-5);
        tb_assert_near(b[i], 3.0 * i + 1.0 + 5.0, 1e-5);
    }
    tb_hit h;
    tb_ray far = ti_ray(30.5, 0, 0, 1, 0, 0); /* from inside the sphere at x = 30 */
    assert_true(tb_object_intersect(o, &far, &h));
    tb_assert_near(h.t, 0.5, 1e-6);
    far.tmax = 0.25f;
    assert_false(tb_object_occluded(o, &far));
    tb_object_free(o);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_csg_property),
        cmocka_unit_test(test_csg_coincident),
        cmocka_unit_test(test_csg_many_ends),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
