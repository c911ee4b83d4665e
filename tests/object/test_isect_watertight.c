/* Watertight ray/triangle intersection (Woop, Benthin, Wald 2013): 10^6 rays
 * from inside a closed tessellated sphere and 10^6 from inside a closed
 * subdivided cube mesh, aimed at vertices, at points on edges and at face
 * interiors, must all hit (zero leaks). Rays from the centre aimed at the
 * cube mesh's lattice points pass exactly through edges and vertices, where
 * the exact tie rule decides. Every 8th ray also checks that the whole line
 * crosses the (convex) mesh exactly once each way: one interval, containing
 * the origin (no crossing counted twice). The meshes are placed by random
 * transforms (mirrors included) half of the time. */
#include "test_isect_common.h"

#include "host/object/csg.h"
#include "host/object/intersect.h"
#include "host/object/param.h"
#include "host/object/watertight.h"

typedef struct ti_leaks {
    long rays, leaks, double_counted, wrong_side;
} ti_leaks;

/* A target point on the mesh surface in object space: a vertex, a point on
 * an edge (midpoint or random), or a random point inside a triangle. */
static tb_dvec3 ti_target(const ti_mesh *m, tb_rng *r, int kind)
{
    int f = (int)tb_rng_below(r, (uint32_t)m->nf);
    int s = m->start[f], n = m->start[f + 1] - s;
    int k = (int)tb_rng_below(r, (uint32_t)n);
    tb_vec3 a = m->v[m->idx[s + k]], b = m->v[m->idx[s + (k + 1) % n]], c = m->v[m->idx[s + (k + 2) % n]];
    if (kind == 0)
        return (tb_dvec3){a.x, a.y, a.z};
    if (kind == 1 || kind == 2) {
        double l = kind == 1 ? 0.5 : tb_rng_double(r);
        return (tb_dvec3){a.x + l * (b.x - a.x), a.y + l * (b.y - a.y), a.z + l * (b.z - a.z)};
    }
    double u = tb_rng_double(r), v = tb_rng_double(r);
    if (u + v > 1.0)
        u = 1.0 - u, v = 1.0 - v;
    return (tb_dvec3){a.x + u * (b.x - a.x) + v * (c.x - a.x), a.y + u * (b.y - a.y) + v * (c.y - a.y),
                      a.z + u * (b.z - a.z) + v * (c.z - a.z)};
}

static void ti_shoot(const tb_object *o, tb_dvec3 ow, tb_dvec3 tw, bool check_line, ti_leaks *L)
{
    tb_vec3 orig = {(float)ow.x, (float)ow.y, (float)ow.z};
    tb_vec3 d = {(float)(tw.x - orig.x), (float)(tw.y - orig.y), (float)(tw.z - orig.z)};
    if (d.x == 0.0f && d.y == 0.0f && d.z == 0.0f)
        return;
    tb_ray ray = tb_ray_make(orig, d, 0.0f, INFINITY);
    L->rays++;
    tb_hit h;
    if (!tb_object_intersect(o, &ray, &h)) {
        if (L->leaks++ < 5)
            print_message("leak: o = (%.9g %.9g %.9g) d = (%.9g %.9g %.9g)\n", orig.x, orig.y, orig.z, d.x, d.y,
                          d.z);
        return;
    }
    /* From inside, the way out is through the back of a front-facing polygon. */
    if (h.ng.x * d.x + h.ng.y * d.y + h.ng.z * d.z < 0.0f)
        L->wrong_side++;
    if (check_line) {
        float a[4], b[4];
        int n = tb_object_intervals(o, &ray, a, b, 4);
        if (n != 1 || !(a[0] <= 0.0f && b[0] >= 0.0f)) {
            if (L->double_counted++ < 5)
                print_message("line: %d intervals, first [%g %g]\n", n, n ? a[0] : 0.0, n ? b[0] : 0.0);
        }
    }
}

static void ti_run(const ti_mesh *mesh, bool lattice, uint64_t seed, long nrays, const char *what)
{
    tb_rng r;
    tb_rng_seed(&r, seed, 1);
    tb_object *objs[4];
    for (int i = 0; i < 4; i++) {
        tb_transform xf = i < 2 ? tb_transform_identity() : ti_random_transform(&r, 0.5, 3.0, 5.0, true);
        if (i == 1) { /* exact: a power-of-two scale and an integer shift keep the lattice */
            tb_transform s;
            assert_int_equal(tb_transform_scale((tb_dvec3){2, 0.5, 4}, &s), TB_OK);
            tb_transform t = tb_transform_translate((tb_dvec3){3, -1, 8});
            xf = tb_transform_compose(&t, &s);
        }
        tb_mid_object m = ti_prim(TB_PRIM_POLYGONS, ti_mesh_geom(mesh), xf);
        objs[i] = ti_build(&m, 0);
        assert_true(objs[i]->closed);
    }
    ti_leaks L = {0};
    for (long i = 0; i < nrays; i++) {
        const tb_object *o = objs[i % 4];
        int kind = (int)tb_rng_below(&r, 4);
        tb_dvec3 target = ti_target(mesh, &r, kind);
        tb_dvec3 orig;
        int mode = (int)tb_rng_below(&r, 4);
        if (mode == 0) {
            orig = (tb_dvec3){0, 0, 0};
        } else if (lattice && mode == 1) {
            /* A grid point of a face, strictly inside it (a vertex, or the
             * middle of a grid edge or of a quad, where the split diagonal
             * runs), shot at along the face's axis from the centre plane:
             * the ray passes exactly through the vertex or edge. */
            int ax = (int)tb_rng_below(&r, 3), n = 8;
            double c[3];
            for (int q = 0; q < 3; q++)
                c[q] = -1.0 + (double)(1 + (int)tb_rng_below(&r, (uint32_t)(2 * n - 1))) / n;
            c[ax] = tb_rng_below(&r, 2) ? 1.0 : -1.0;
            target = (tb_dvec3){c[0], c[1], c[2]};
            c[ax] = 0.0;
            orig = (tb_dvec3){c[0], c[1], c[2]};
        } else {
            tb_dvec3 u = ti_sphere_dir(&r);
            double rad = 0.85 * cbrt(tb_rng_double(&r));
            orig = (tb_dvec3){rad * u.x, rad * u.y, rad * u.z};
        }
        tb_dvec3 ow = tb_transform_dpoint(&o->to_world, orig);
        tb_dvec3 tw = tb_transform_dpoint(&o->to_world, target);
        ti_shoot(o, ow, tw, i % 8 == 0, &L);
    }
    print_message("[ %-8s ] %ld rays, %ld leaks, %ld lines not crossed exactly once each way, %ld exits on the "
                  "wrong side\n",
                  what, L.rays, L.leaks, L.double_counted, L.wrong_side);
    for (int i = 0; i < 4; i++)
        tb_object_free(objs[i]);
    assert_true(L.rays > nrays * 9 / 10);
    assert_int_equal(L.leaks, 0);
    assert_int_equal(L.double_counted, 0);
    assert_int_equal(L.wrong_side, 0);
}

static void test_watertight_sphere(void **state)
{
    (void)state;
    ti_mesh m = ti_icosphere(4); /* 5120 triangles */
    ti_run(&m, false, tb_test_seed("watertight_sphere", 20240601), ti_count(1000000, 2000), "sphere");
    ti_mesh_free(&m);
}

static void test_watertight_cube(void **state)
{
    (void)state;
    ti_mesh m = ti_cube_mesh(8); /* 384 quads, 768 triangles */
    ti_run(&m, true, tb_test_seed("watertight_cube", 20240602), ti_count(1000000, 2000), "cube");
    ti_mesh_free(&m);
}

/* The one-triangle tests the scene and the form factors use
 * (tb_object_triangle_crossing, and host/object/watertight.h's test on the
 * corners copied out of the mesh, as the scene's triangle records hold them)
 * against the whole-mesh query:
 * on meshes under random transforms (mirrors included), for rays from
 * outside aimed at the mesh, the least crossing over all triangles (float t
 * in range, then face, then triangle: the scene's order) must be
 * tb_object_intersect's hit bit for bit (t, face, normal), the two
 * one-triangle calls must agree on every triangle, the world vertices must
 * be the transformed object vertices, and a front hit's normal must face the
 * ray (the mirror's orientation flip). */
static void test_triangle_calls(void **state)
{
    (void)state;
    ti_mesh mesh = ti_icosphere(2); /* 320 triangles */
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("triangle_calls", 20261204), 1);
    long nrays = ti_count(20000, 400), hits = 0, mismatches = 0, entries = 0, back = 0;
    for (int i = 0; i < 4; i++) {
        tb_transform xf = i == 0 ? tb_transform_identity() : ti_random_transform(&r, 0.5, 3.0, 5.0, i >= 2);
        tb_mid_object mo = ti_prim(TB_PRIM_POLYGONS, ti_mesh_geom(&mesh), xf);
        tb_object *o = ti_build(&mo, 0);
        const tb_object_mesh *m = o->mesh;
        for (uint32_t v = 0; v < m->nvertices; v++) {
            tb_dvec3 w = tb_transform_dpoint(&o->to_world, tb_vec3_to_d(m->vertices[v]));
            assert_true(w.x == m->wvertices[3 * v] && w.y == m->wvertices[3 * v + 1] && w.z == m->wvertices[3 * v + 2]);
        }
        for (long k = 0; k < nrays / 4; k++) {
            tb_dvec3 u = ti_sphere_dir(&r), target = ti_target(&mesh, &r, (int)tb_rng_below(&r, 4));
            tb_dvec3 orig = {3.0 * u.x, 3.0 * u.y, 3.0 * u.z};
            tb_dvec3 ow = tb_transform_dpoint(&o->to_world, orig), tw = tb_transform_dpoint(&o->to_world, target);
            tb_vec3 of = {(float)ow.x, (float)ow.y, (float)ow.z};
            tb_ray ray = tb_ray_make(of, (tb_vec3){(float)(tw.x - of.x), (float)(tw.y - of.y), (float)(tw.z - of.z)},
                                     0.0f, INFINITY);
            bool found = false;
            float best_t = 0.0f;
            uint32_t best_face = 0, best_tri = 0;
            for (uint32_t t = 0; t < m->ntris; t++) {
                double ta = 0.0, tb = 0.0;
                const uint32_t *tv = &m->tris[3 * t];
                double c[9];
                for (int q = 0; q < 3; q++)
                    memcpy(&c[3 * q], &m->wvertices[3 * (size_t)tv[q]], sizeof(double) * 3);
                bool a = tb_object_triangle_crossing(o, t, &ray, &ta);
                tb_wt_ray w;
                tb_wt_ray_init(&w, &ray);
                int dir;
                bool b = tb_wt_triangle(&w, &c[0], &c[3], &c[6], &tb, &dir, NULL);
                if (a != b || (a && memcmp(&ta, &tb, sizeof ta) != 0))
                    mismatches++;
                float tf = (float)ta;
                if (!a || !(tf >= ray.tmin && tf <= ray.tmax))
                    continue;
                uint32_t f = m->tri_face[t];
                if (!found || tf < best_t || (tf == best_t && (f < best_face || (f == best_face && t < best_tri))))
                    found = true, best_t = tf, best_face = f, best_tri = t;
            }
            tb_hit h;
            bool hit = tb_object_intersect(o, &ray, &h);
            assert_int_equal(hit, found);
            if (!hit)
                continue;
            hits++;
            assert_true(h.t == best_t);
            assert_int_equal(h.face, best_face);
            tb_vec3 n = tb_object_triangle_normal(o, best_tri);
            assert_memory_equal(&h.ng, &n, sizeof n);
            /* Where the ray enters the solid (not a tangent touch at a
             * silhouette vertex, which the tie rule may give to a triangle
             * facing away), the front: the mirror's flip is accounted for. */
            float a[4], b[4];
            int nn = tb_object_intervals(o, &ray, a, b, 4);
            if (nn >= 1 && a[0] == h.t && b[0] > a[0]) {
                entries++;
                if (!(n.x * ray.d.x + n.y * ray.d.y + n.z * ray.d.z < 0.0f))
                    back++;
            }
        }
        tb_object_free(o);
    }
    print_message("[ triangles ] %ld rays, %ld hits, %ld one-triangle disagreements, %ld of %ld entries on a back "
                  "face\n",
                  nrays, hits, mismatches, back, entries);
    assert_int_equal(mismatches, 0);
    assert_int_equal(back, 0);
    assert_true(entries > nrays / 3);
    assert_true(hits > nrays / 2);
    ti_mesh_free(&mesh);
}

/* A triangle hit's (u, v) is the mix of the triangle's corner (u, v) by the
 * test's edge functions (tb_object_triangle_uv): it must be
 * tb_param_from_point's (u, v) of the hit point (the double t, mapped to
 * object space as tb_object_intersect does) within a few float ulps on faces
 * where (u, v) is affine over the triangles (without uvs: a trapezoid, a
 * non-convex L, a slightly non-planar quad, a triangle; with uvs: a
 * triangle), and exactly the point's on faces of more than 3 corners with
 * uvs (a trapezoid with a square's uvs, a non-convex pentagon), which keep
 * that path. Meshes placed by the identity, a random and a mirroring
 * transform; rays from random points aimed at random points of the faces. */
static void test_triangle_uv(void **state)
{
    (void)state;
    static const tb_vec3 va[] = {
        {0, 0, 0}, {2, 0, 0}, {1.5f, 1, 0}, {0.25f, 1, 0},                            /* trapezoid (z = 0) */
        {0, 0, 1}, {2, 0, 1}, {2, 1, 1}, {1, 1, 1}, {1, 2, 1}, {0, 2, 1},              /* L (z = 1) */
        {0, 0, 2}, {1, 0, 2.05f}, {1, 1, 2}, {0, 1, 1.95f},                            /* non-planar quad */
        {0, 0, 3}, {1, 0.2f, 3}, {0.3f, 1, 3.1f},                                      /* triangle */
    };
    static const int sa[] = {0, 4, 10, 14, 17};
    static const int ia[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16};
    static const tb_vec3 vb[] = {
        {0, 0, 0}, {1, 0.1f, 0}, {0.2f, 1, 0.1f},                                     /* triangle */
        {0, 0, 1}, {2, 0, 1}, {1.5f, 1, 1}, {0.5f, 1, 1},                              /* trapezoid */
        {0, 0, 2}, {2, 0, 2}, {2, 2, 2}, {1, 0.8f, 2}, {0, 2, 2},                      /* non-convex pentagon */
    };
    static const tb_vec2 uvb[] = {
        {0.1f, 0.2f}, {0.9f, 0.3f}, {0.4f, 0.95f},
        {0, 0}, {1, 0}, {1, 1}, {0, 1},
        {0, 0}, {1, 0}, {1, 1}, {0.5f, 0.3f}, {0, 1},
    };
    static const int sb[] = {0, 3, 7, 12};
    static const int ib[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("triangle_uv", 20261205), 1);
    long nrays = ti_count(20000, 600), hits = 0, affine = 0, from_point = 0, far = 0, differ = 0;
    double worst = 0.0;
    for (int g = 0; g < 2; g++) {
        tb_mid_geometry geom;
        memset(&geom, 0, sizeof geom);
        geom.polygons.nvertices = g ? 12 : 17;
        geom.polygons.vertices = g ? vb : va;
        geom.polygons.uvs = g ? uvb : NULL;
        geom.polygons.nfaces = g ? 3 : 4;
        geom.polygons.face_start = g ? sb : sa;
        geom.polygons.indices = g ? ib : ia;
        for (int x = 0; x < 3; x++) {
            tb_transform xf = x == 0 ? tb_transform_identity() : ti_random_transform(&r, 0.5, 3.0, 5.0, x == 2);
            tb_mid_object mo = ti_prim(TB_PRIM_POLYGONS, geom, xf);
            tb_object *o = ti_build(&mo, 0);
            const tb_object_mesh *m = o->mesh;
            for (long k = 0; k < nrays / 6; k++) {
                /* A random point of a random triangle, shot at from a random point around the mesh. */
                uint32_t tri = tb_rng_below(&r, m->ntris);
                const uint32_t *tv = &m->tris[3 * tri];
                double a = tb_rng_double(&r), b = tb_rng_double(&r);
                if (a + b > 1.0)
                    a = 1.0 - a, b = 1.0 - b;
                tb_vec3 p0 = m->vertices[tv[0]], p1 = m->vertices[tv[1]], p2 = m->vertices[tv[2]];
                tb_dvec3 target = {p0.x + a * (p1.x - p0.x) + b * (p2.x - p0.x),
                                   p0.y + a * (p1.y - p0.y) + b * (p2.y - p0.y),
                                   p0.z + a * (p1.z - p0.z) + b * (p2.z - p0.z)};
                tb_dvec3 u = ti_sphere_dir(&r), orig = {target.x + 4.0 * u.x, target.y + 4.0 * u.y, target.z + 4.0 * u.z};
                tb_dvec3 ow = tb_transform_dpoint(&o->to_world, orig), tw = tb_transform_dpoint(&o->to_world, target);
                tb_vec3 of = {(float)ow.x, (float)ow.y, (float)ow.z};
                tb_ray ray = tb_ray_make(
                    of, (tb_vec3){(float)(tw.x - of.x), (float)(tw.y - of.y), (float)(tw.z - of.z)}, 0.0f, INFINITY);
                tb_hit h;
                if (!tb_object_intersect(o, &ray, &h))
                    continue;
                /* The winning triangle (the least in float t, face, triangle) and its double t. */
                bool found = false;
                double best_t = 0.0;
                for (uint32_t t = 0; t < m->ntris; t++) {
                    double tt;
                    if (tb_object_triangle_crossing(o, t, &ray, &tt) && (float)tt == h.t &&
                        m->tri_face[t] == h.face && !found) {
                        found = true;
                        best_t = tt;
                    }
                }
                assert_true(found);
                hits++;
                tb_dvec3 p = tb_object_ray_point(o, &ray, best_t);
                int pf;
                double pu, pv;
                if (tb_param_from_point(TB_PRIM_POLYGONS, &o->geom, p, (int)h.face, &pf, &pu, &pv) != TB_OK)
                    pu = pv = 0.0;
                int nv = o->geom.polygons.face_start[h.face + 1] - o->geom.polygons.face_start[h.face];
                if (g && nv > 3) {
                    from_point++;
                    if (h.u != (float)pu || h.v != (float)pv)
                        differ++;
                } else {
                    affine++;
                    double e = fmax(fabs(h.u - pu), fabs(h.v - pv));
                    worst = fmax(worst, e);
                    if (!(e <= 4.0 * 0x1p-24)) /* corners and result rounded to float */
                        if (far++ < 3)
                            print_message("face %u: (u, v) = (%.9g, %.9g), param (%.9g, %.9g)\n", h.face, h.u, h.v,
                                          pu, pv);
                }
            }
            tb_object_free(o);
        }
    }
    print_message("[ triangle uv ] %ld hits: %ld by the corners' mix (largest difference from param %.3g), %ld "
                  "from the point (%ld differ)\n",
                  hits, affine, worst, from_point, differ);
    assert_true(affine > nrays / 4);
    assert_true(from_point > nrays / 20);
    assert_int_equal(far, 0);
    assert_int_equal(differ, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_watertight_sphere),
        cmocka_unit_test(test_watertight_cube),
        cmocka_unit_test(test_triangle_calls),
        cmocka_unit_test(test_triangle_uv),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
