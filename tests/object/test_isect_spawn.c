/* Self-intersection: a ray leaving a convex surface from a hit point, with its
 * origin moved off the surface by tb_spawn_ray_origin (pbrt-v4's error-bound
 * offset, hit.h) using the point and error bound of tb_object_hit_point, must
 * never hit that surface again, for 10^6 trials per convex primitive (after
 * pbrt-v4's shapes_test "reintersect"). A trial is one spawned ray: random
 * rays from outside toward random points near the object (under one of 9
 * transforms, mirrors and 25:1 scale ratios included) give hit points, and
 * each hit point spawns 4 rays in random directions of the hemisphere of the
 * geometric normal. The offsets stay small: at most 2^-14 of the
 * point's size (checked), so the test cannot pass by pushing origins away. */
#include "test_isect_common.h"

#include <string.h>

#include "host/object/hit.h"
#include "host/object/intersect.h"

typedef struct ti_case {
    const char *name;
    tb_prim_kind kind;
    tb_mid_geometry g;
} ti_case;

static void ti_spawn_case(const ti_case *c, uint64_t seed, long trials)
{
    tb_rng r;
    tb_rng_seed(&r, seed, (uint64_t)c->kind);
    enum { NOBJ = 9 };
    tb_object *objs[NOBJ];
    for (int i = 0; i < NOBJ; i++) {
        tb_transform xf = i == 0 ? tb_transform_identity() : ti_random_transform(&r, 0.2, 5.0, 10.0, true);
        tb_mid_object m = ti_prim(c->kind, c->g, xf);
        objs[i] = ti_build(&m, 0);
    }
    long hits = 0, rehits = 0, lost = 0, spawned = 0, shot = 0;
    double worst_offset = 0.0;
    /* A trial is one spawned ray; each hit point spawns NDIR of them. */
    enum { NDIR = 4 };
    for (long i = 0; spawned < trials; i++) {
        const tb_object *o = objs[i % NOBJ];
        tb_dvec3 q = {ti_uniform(&r, -1.1, 1.1), ti_uniform(&r, -1.1, 1.1), ti_uniform(&r, -1.1, 1.1)};
        tb_dvec3 target = tb_transform_dpoint(&o->to_world, q);
        tb_dvec3 u = ti_sphere_dir(&r);
        double dist = o->scale * ti_uniform(&r, 2.0, 20.0);
        tb_vec3 orig = {(float)(target.x + dist * u.x), (float)(target.y + dist * u.y),
                        (float)(target.z + dist * u.z)};
        tb_vec3 d = {(float)(target.x - orig.x), (float)(target.y - orig.y), (float)(target.z - orig.z)};
        tb_ray ray = tb_ray_make(orig, d, 0.0f, INFINITY);
        tb_hit h;
        shot++;
        if (!tb_object_intersect(o, &ray, &h))
            continue;
        hits++;
        tb_vec3 p, perr;
        if (!tb_object_hit_point(o, &ray, &h, &p, &perr)) {
            lost++;
            continue;
        }
        for (int k = 0; k < NDIR; k++) {
            tb_dvec3 w = ti_sphere_dir(&r);
            double wn = w.x * h.ng.x + w.y * h.ng.y + w.z * h.ng.z;
            if (wn == 0.0)
                continue;
            if (wn < 0.0)
                w = tb_dvec3_neg(w);
            tb_vec3 wf = {(float)w.x, (float)w.y, (float)w.z};
            tb_vec3 o2 = tb_spawn_ray_origin(p, perr, h.ng, wf);
            double off = fmax(fabs(o2.x - p.x), fmax(fabs(o2.y - p.y), fabs(o2.z - p.z)));
            double size = fmax(fabs(p.x), fmax(fabs(p.y), fabs(p.z))) + o->scale;
            worst_offset = fmax(worst_offset, off / size);
            tb_ray out = tb_ray_make(o2, wf, 0.0f, INFINITY);
            spawned++;
            if (tb_object_occluded(o, &out)) {
                tb_hit h2;
                if (rehits++ < 3 && tb_object_intersect(o, &out, &h2))
                    print_message("%s: re-hit at t = %g (face %u) from p = (%.9g %.9g %.9g) +- (%g %g %g), ng = (%g "
                                  "%g %g), w.ng = %g\n",
                                  c->name, h2.t, h2.face, p.x, p.y, p.z, perr.x, perr.y, perr.z, h.ng.x, h.ng.y,
                                  h.ng.z, fabs(wn));
            }
        }
    }
    print_message("[ %-9s ] %ld spawned rays from %ld hits: %ld re-hits, %ld hit points not recomputed, largest "
                  "offset %.2g of the point's size\n",
                  c->name, spawned, hits, rehits, lost, worst_offset);
    for (int i = 0; i < NOBJ; i++)
        tb_object_free(objs[i]);
    assert_true(hits > shot / 4); /* the rays do find the object */
    assert_int_equal(lost, 0);
    assert_int_equal(rehits, 0);
    assert_true(worst_offset < 0x1p-14);
}

static long ti_trials(void) { return ti_count(1000000, 2000); }

#define TI_GEOM(k) tb_mid_geometry_default(k)

static void test_spawn_quadrics(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("spawn_quadrics", 7001);
    ti_case c;
    c = (ti_case){"sphere", TB_PRIM_SPHERE, TI_GEOM(TB_PRIM_SPHERE)};
    ti_spawn_case(&c, seed, ti_trials());
    c = (ti_case){"cylinder", TB_PRIM_CYLINDER, TI_GEOM(TB_PRIM_CYLINDER)};
    ti_spawn_case(&c, seed, ti_trials());
    c = (ti_case){"cone", TB_PRIM_CONE, TI_GEOM(TB_PRIM_CONE)};
    ti_spawn_case(&c, seed, ti_trials());
    c = (ti_case){"frustum", TB_PRIM_CONE, TI_GEOM(TB_PRIM_CONE)};
    c.g.cone.top_radius = 1.5;
    ti_spawn_case(&c, seed, ti_trials());
    c = (ti_case){"paraboloid", TB_PRIM_CONIC, TI_GEOM(TB_PRIM_CONIC)};
    c.g.conic.c[0] = 0.5, c.g.conic.c[1] = -0.5, c.g.conic.c[2] = 0.0;
    ti_spawn_case(&c, seed, ti_trials());
    c = (ti_case){"ellipsoid", TB_PRIM_CONIC, TI_GEOM(TB_PRIM_CONIC)};
    c.g.conic.c[0] = 1.0, c.g.conic.c[1] = 0.0, c.g.conic.c[2] = -4.0; /* poles at z = +-1/2 */
    c.g.conic.z0 = -0.5, c.g.conic.z1 = 0.5;
    ti_spawn_case(&c, seed, ti_trials());
}

static void test_spawn_polyhedra(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("spawn_polyhedra", 7002);
    ti_case c;
    c = (ti_case){"cube", TB_PRIM_CUBE, TI_GEOM(TB_PRIM_CUBE)};
    ti_spawn_case(&c, seed, ti_trials());
    c = (ti_case){"pyramid", TB_PRIM_PYRAMID, TI_GEOM(TB_PRIM_PYRAMID)};
    ti_spawn_case(&c, seed, ti_trials());
    c = (ti_case){"pyr-frust", TB_PRIM_PYRAMID, TI_GEOM(TB_PRIM_PYRAMID)};
    c.g.pyramid.top = 0.4;
    ti_spawn_case(&c, seed, ti_trials());
    c = (ti_case){"prism-5", TB_PRIM_PRISM, TI_GEOM(TB_PRIM_PRISM)};
    c.g.prism.sides = 5;
    ti_spawn_case(&c, seed, ti_trials());
    c = (ti_case){"prism-1000", TB_PRIM_PRISM, TI_GEOM(TB_PRIM_PRISM)};
    c.g.prism.sides = 1000; /* the sector test */
    ti_spawn_case(&c, seed, ti_trials());
}

static void test_spawn_meshes(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("spawn_meshes", 7003);
    ti_mesh s = ti_icosphere(3), b = ti_cube_mesh(4);
    ti_case c = {"icosphere", TB_PRIM_POLYGONS, ti_mesh_geom(&s)};
    ti_spawn_case(&c, seed, ti_trials());
    c = (ti_case){"cube mesh", TB_PRIM_POLYGONS, ti_mesh_geom(&b)};
    ti_spawn_case(&c, seed, ti_trials());
    ti_mesh_free(&s);
    ti_mesh_free(&b);
}

/* tb_spawn_ray_origins + tb_spawn_front (the two origins of a point, picked
 * by side) against tb_spawn_ray_origin for each direction, bit for bit:
 * random points, error bounds and directions, unit and axis normals, a zero
 * normal, and directions exactly in the tangent plane (w . ng = 0, which
 * take the front origin). Fails when a side is swapped or the tie goes to
 * the back. */
static void test_spawn_origins_pair(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("spawn_origins_pair", 7003), 1);
    long ties = 0, backs = 0;
    for (int i = 0; i < 20000; i++) {
        tb_dvec3 nd = ti_sphere_dir(&r);
        tb_vec3 ng = {(float)nd.x, (float)nd.y, (float)nd.z};
        if (i % 5 == 1)
            ng = (tb_vec3){0.0f, 0.0f, i % 2 ? 1.0f : -1.0f};
        if (i % 97 == 0)
            ng = (tb_vec3){0.0f, 0.0f, 0.0f};
        double sc = exp(ti_uniform(&r, log(1e-3), log(1e3)));
        tb_vec3 p = {(float)ti_uniform(&r, -sc, sc), (float)ti_uniform(&r, -sc, sc), (float)ti_uniform(&r, -sc, sc)};
        tb_vec3 perr = {(float)(sc * 1e-6 * tb_rng_double(&r)), (float)(sc * 1e-6 * tb_rng_double(&r)),
                        (float)(sc * 1e-6 * tb_rng_double(&r))};
        tb_vec3 front, back;
        tb_spawn_ray_origins(p, perr, ng, &front, &back);
        for (int k = 0; k < 8; k++) {
            tb_dvec3 wd = ti_sphere_dir(&r);
            tb_vec3 w = {(float)wd.x, (float)wd.y, (float)wd.z};
            if (k == 0 && i % 5 == 1)
                w.z = 0.0f; /* in the tangent plane of an axis normal: w . ng = 0 */
            tb_vec3 want = tb_spawn_ray_origin(p, perr, ng, w);
            bool f = tb_spawn_front(ng, w);
            tb_vec3 got = f ? front : back;
            if (memcmp(&want, &got, sizeof want) != 0)
                fail_msg("point %d dir %d: the %s origin differs from tb_spawn_ray_origin", i, k, f ? "front" : "back");
            ties += (double)w.x * ng.x + (double)w.y * ng.y + (double)w.z * ng.z == 0.0;
            backs += !f;
        }
    }
    assert_true(ties > 1000 && backs > 50000);
}

/* tb_spawn_ray_origin's branch-free steps against the rule they replace,
 * bit for bit: each coordinate of p + s ng moves one float up where its
 * offset is > 0 and down where it is < 0 (tb_next_float_up/down), on points
 * of every sign and size, zeros, denormals, FLT_MAX, infinities and NaN, and
 * normals with zero, negative and NaN components. */
static tb_vec3 ti_spawn_reference(tb_vec3 p, tb_vec3 perr, tb_vec3 ng, tb_vec3 w)
{
    double dd = fabs((double)ng.x) * perr.x + fabs((double)ng.y) * perr.y + fabs((double)ng.z) * perr.z;
    float d = (float)dd;
    if ((double)d < dd)
        d = tb_next_float_up(d);
    double side = (double)w.x * ng.x + (double)w.y * ng.y + (double)w.z * ng.z;
    float s = side < 0.0 ? -d : d;
    float off[3] = {s * ng.x, s * ng.y, s * ng.z};
    float po[3] = {p.x + off[0], p.y + off[1], p.z + off[2]};
    for (int i = 0; i < 3; i++) {
        if (off[i] > 0.0f)
            po[i] = tb_next_float_up(po[i]);
        else if (off[i] < 0.0f)
            po[i] = tb_next_float_down(po[i]);
    }
    return (tb_vec3){po[0], po[1], po[2]};
}

static void test_spawn_origin_steps(void **state)
{
    (void)state;
    static const float special[] = {0.0f,     -0.0f,    0x1p-149f, -0x1p-149f, 1.0f,      -1.0f,    FLT_MAX,
                                    -FLT_MAX, INFINITY, -INFINITY, NAN,        0x1p-126f, 3.5e-20f, -7e30f};
    const int ns = (int)(sizeof special / sizeof special[0]);
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("spawn_origin_steps", 7004), 1);
    for (int i = 0; i < 200000; i++) {
        float c[9];
        for (int k = 0; k < 9; k++) {
            uint32_t u = tb_rng_u32(&r);
            if (u % 5 == 0)
                c[k] = special[(u >> 8) % (uint32_t)ns];
            else
                c[k] = (float)(ldexp(tb_rng_double(&r), (int)(u >> 8) % 80 - 60) * (u & 0x80 ? -1.0 : 1.0));
        }
        tb_vec3 p = {c[0], c[1], c[2]}, perr = {fabsf(c[3]), fabsf(c[4]), fabsf(c[5])};
        tb_vec3 ng = {c[6], c[7], c[8]}, w = {c[8], c[6], -c[7]};
        if (i % 3 == 0) { /* unit normals, the common case */
            tb_dvec3 nd = ti_sphere_dir(&r);
            ng = (tb_vec3){(float)nd.x, (float)nd.y, (float)nd.z};
        }
        tb_vec3 want = ti_spawn_reference(p, perr, ng, w), got = tb_spawn_ray_origin(p, perr, ng, w);
        const float wv[3] = {want.x, want.y, want.z}, gv[3] = {got.x, got.y, got.z};
        bool same = true; /* bit for bit, but any NaN for a NaN (its payload is the compiler's choice) */
        for (int k = 0; k < 3; k++)
            same = same && (isnan(wv[k]) ? isnan(gv[k]) : memcmp(&wv[k], &gv[k], sizeof wv[k]) == 0);
        if (!same)
            fail_msg("case %d: want (%a %a %a) got (%a %a %a) p (%a %a %a) perr (%a %a %a) ng (%a %a %a): origin differs from the rule", i,
                     (double)wv[0], (double)wv[1], (double)wv[2], (double)gv[0], (double)gv[1], (double)gv[2], (double)p.x, (double)p.y, (double)p.z, (double)perr.x, (double)perr.y, (double)perr.z,
                     (double)ng.x, (double)ng.y, (double)ng.z);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_spawn_quadrics),
        cmocka_unit_test(test_spawn_polyhedra),
        cmocka_unit_test(test_spawn_meshes),
        cmocka_unit_test(test_spawn_origins_pair),
        cmocka_unit_test(test_spawn_origin_steps),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
