/* The Vulkan intersect kernel (host/gpu/intersect.h) against the CPU path
 * (tb_scene_intersect / tb_scene_occluded) on scenes mixing triangles and a
 * sphere, a cube, a torus and a prism (placed objects on the GPU),
 * cylinders, cones and conics, a lone cube (the BVH's root a leaf) and a deep BVH with
 * kinds mixed in its leaves.
 * Runs with the validation layer and fails on any message. */
#include "gpu_test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "host/gpu/intersect.h"
#include "host/object/hit.h"
#include "host/object/intersect.h"
#include "host/render/scene.h"
#include "util/math/rng.h"

/* A quad at z = 0 (two triangles, one face), a triangle at z = 1, a torus
 * about z at height 2 and a sphere off to the side. */
static const char *tb__mixed =
    "mid 1\n"
    "polygons \"quad\" { geometry = { vertices = [[-2 -2 0] [2 -2 0] [2 2 0] [-2 2 0]] faces = [[0 1 2 3]] } }\n"
    "polygons \"tri\" { geometry = { vertices = [[-1 -1 1] [1 -1 1] [0 1 1]] faces = [[0 1 2]] } }\n"
    "torus \"ring\" { transform = [translate([0 0 2])] geometry = { major = 1 minor = 0.25 } }\n"
    "sphere \"ball\" { transform = [scale(0.5) translate([3 3 0.5])] }\n"
    "cube \"box\" { transform = [scale([0.25 0.5 0.25]) translate([-3 3 0.25])] }\n";

/* Only a torus and a prism: no triangles. */
static const char *tb__analytic =
    "mid 1\n"
    "torus \"ring\" { transform = [translate([0 0 2])] geometry = { major = 1 minor = 0.25 } }\n"
    "prism \"bar\" { transform = [scale(0.5) translate([0.5 0.5 0.5])] }\n";

static tb_scene *tb__load(const char *text)
{
    return gpu_test_load(text, "t.mid", NULL);
}

/* Ends a test: the GPU scene, the scene, then the device (validation checked). */
static void tb__finish(gpu_test_env *e, tb_gpu_scene *g, tb_scene *s)
{
    tb_gpu_scene_destroy(g);
    tb_scene_free(s);
    gpu_test_close(e);
}

/* A random test's rays with their GPU closest hits and any-hit flags. */
typedef struct tb__batch {
    int n;
    tb_ray *rays;
    tb_hit *hits;
    uint8_t *occ;
} tb__batch;

static tb__batch tb__batch_new(int n)
{
    tb__batch b = {n, malloc((size_t)n * sizeof *b.rays), malloc((size_t)n * sizeof *b.hits), malloc((size_t)n)};
    assert_true(b.rays && b.hits && b.occ);
    return b;
}

/* Both kernels on the batch's rays. */
static void tb__batch_trace(tb_gpu_scene *g, tb__batch *b)
{
    assert_int_equal(tb_gpu_intersect(g, b->rays, b->n, b->hits, NULL), TB_OK);
    assert_int_equal(tb_gpu_occluded(g, b->rays, b->n, b->occ, NULL), TB_OK);
}

/* How many of the batch's any-hit flags differ from the CPU's. */
static int tb__occ_differ(const tb_scene *s, const tb__batch *b)
{
    int n = 0;
    for (int i = 0; i < b->n; ++i)
        n += b->occ[i] != tb_scene_occluded(s, &b->rays[i]);
    return n;
}

static void tb__batch_free(tb__batch *b)
{
    free(b->rays), free(b->hits), free(b->occ);
}

/* Ends a random test: at most 1 ray in 1000 may differ from the CPU in object
 * or face (`differ`) or in the any-hit answer (rays within float error of an
 * edge, silhouette or rim); then frees the batch and closes as tb__finish. */
static void tb__finish_batch(gpu_test_env *e, tb_gpu_scene *g, tb_scene *s, tb__batch *b, int differ, int occ_differ)
{
    assert_true(differ <= b->n / 1000);
    assert_true(occ_differ <= b->n / 1000);
    tb__batch_free(b);
    tb__finish(e, g, s);
}

static tb_hit tb__cpu(const tb_scene *s, const tb_ray *r)
{
    tb_hit h = {INFINITY, UINT32_MAX, UINT32_MAX, 0.0f, 0.0f, {0.0f, 0.0f, 0.0f}};
    tb_scene_intersect(s, r, &h);
    return h;
}

static bool tb__same(const tb_hit *a, const tb_hit *b, double uv_tol)
{
    return a->t == b->t && a->object == b->object && a->face == b->face && a->ng.x == b->ng.x &&
           a->ng.y == b->ng.y && a->ng.z == b->ng.z && fabs((double)a->u - b->u) <= uv_tol &&
           fabs((double)a->v - b->v) <= uv_tol;
}

/* Vertical rays through a grid of odd multiples of 1/8: every GPU operation
 * is exact (shear 0, z differences of small dyadics), no ray meets an edge of
 * the triangle or the torus's silhouette, so the mixed path's records equal
 * the CPU's bit for bit (u, v: the host computes them from the float t, the
 * CPU from the double t: equal here since t is exact). */
static void test_exact_grid(void **state)
{
    (void)state;
    gpu_test_env e;
    gpu_test_open(&e, NULL);
    tb_scene *s = tb__load(tb__mixed);
    tb_gpu_scene *g = tb_gpu_scene_create(e.dev, s);
    assert_non_null(g);
    tb_gpu_scene_info info;
    tb_gpu_scene_get_info(g, &info);
    assert_int_equal(info.gpu_objects, 5);
    assert_int_equal(info.cpu_objects, 0);
    assert_int_equal(info.gpu_triangles, 3);
    assert_int_equal(info.gpu_spheres, 1);
    assert_int_equal(info.gpu_cubes, 1);
    for (uint32_t i = 0; i < 5; ++i)
        assert_true(tb_gpu_scene_object_on_gpu(g, i));

    enum { N = 32 * 32 };
    tb_ray rays[N];
    tb_hit hits[N];
    for (int i = 0; i < N; ++i) {
        float x = -3.875f + 0.25f * (float)(i % 32), y = -3.875f + 0.25f * (float)(i / 32);
        rays[i] = (tb_ray){{x, y, 5.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, INFINITY};
    }
    assert_int_equal(tb_gpu_intersect(g, rays, N, hits, NULL), TB_OK);
    int on[5] = {0};
    for (int i = 0; i < N; ++i) {
        tb_hit c = tb__cpu(s, &rays[i]);
        /* the sphere off its centre (sqrt) and the torus (bisection): not exact */
        if ((c.object == 3 || c.object == 2) && hits[i].object == c.object) {
            assert_int_equal(hits[i].face, c.face);
            tb_assert_near(hits[i].t, c.t, 1e-5 * c.t);
            tb_assert_near(hits[i].ng.x, c.ng.x, 1e-4);
            tb_assert_near(hits[i].ng.y, c.ng.y, 1e-4);
            tb_assert_near(hits[i].ng.z, c.ng.z, 1e-4);
            on[c.object]++;
            continue;
        }
        if (!tb__same(&c, &hits[i], 0.0))
            fail_msg("ray %d (%g, %g): cpu t %.9g object %u face %u, gpu t %.9g object %u face %u", i,
                     rays[i].o.x, rays[i].o.y, c.t, c.object, c.face, hits[i].t, hits[i].object, hits[i].face);
        if (c.object < 5)
            on[c.object]++;
    }
    /* Exact t on the planes, and every object was hit (the test covers both paths). */
    for (int i = 0; i < N; ++i)
        if (hits[i].object == 0)
            assert_true(hits[i].t == 5.0f);
        else if (hits[i].object == 1)
            assert_true(hits[i].t == 4.0f);
    for (int k = 0; k < 5; ++k)
        assert_true(on[k] > 0);

    /* Rays through the sphere's centre: every step of the GPU sphere is exact
     * (object-space origin and direction, p0 = 0, discriminant 16), so t and
     * the normal are exact: down from above (t 4, normal +z) and along +x (t 2.5, normal -x). */
    tb_ray cr[2] = {{{3.0f, 3.0f, 5.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, INFINITY},
                    {{0.0f, 3.0f, 0.5f}, 0.0f, {1.0f, 0.0f, 0.0f}, INFINITY}};
    tb_hit ch[2];
    assert_int_equal(tb_gpu_intersect(g, cr, 2, ch, NULL), TB_OK);
    for (int i = 0; i < 2; ++i) {
        tb_hit c = tb__cpu(s, &cr[i]);
        assert_int_equal(c.object, 3);
        assert_true(tb__same(&c, &ch[i], 1e-6));
    }
    assert_true(ch[0].t == 4.0f && ch[0].ng.z == 1.0f);
    assert_true(ch[1].t == 2.5f && ch[1].ng.x == -1.0f);

    /* Any hit on the same rays, and shortened so the planes are out of reach. */
    uint8_t occ[N];
    assert_int_equal(tb_gpu_occluded(g, rays, N, occ, NULL), TB_OK);
    for (int i = 0; i < N; ++i)
        assert_int_equal(occ[i], tb_scene_occluded(s, &rays[i]));
    for (int i = 0; i < N; ++i)
        rays[i].tmax = 3.5f;
    assert_int_equal(tb_gpu_occluded(g, rays, N, occ, NULL), TB_OK);
    for (int i = 0; i < N; ++i)
        assert_int_equal(occ[i], tb_scene_occluded(s, &rays[i]));
    tb__finish(&e, g, s);
}

/* Random rays through the mixed scene: torus, triangle, sphere and cube hits
 * agree within float tolerance; hit/miss and
 * object may differ only for rays within float error of an edge (none
 * expected among a few thousand random rays; allowed: 1 in 1000). */
static void test_random_mixed(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("test_random_mixed", 6);
    tb_rng rng;
    tb_rng_seed(&rng, seed, 1);
    gpu_test_env e;
    gpu_test_open(&e, NULL);
    tb_scene *s = tb__load(tb__mixed);
    tb_gpu_scene *g = tb_gpu_scene_create(e.dev, s);
    assert_non_null(g);
    enum { N = 4000 };
    tb__batch b = tb__batch_new(N);
    tb_ray *rays = b.rays;
    const tb_hit *hits = b.hits;
    for (int i = 0; i < N; ++i) {
        float o[3], p[3];
        for (int k = 0; k < 3; ++k) {
            o[k] = (float)(tb_rng_double(&rng) * 12.0 - 6.0);
            p[k] = (float)(tb_rng_double(&rng) * 6.0 - 3.0);
        }
        p[2] = (float)(tb_rng_double(&rng) * 3.0);
        float tmax = tb_rng_double(&rng) < 0.25 ? (float)tb_rng_double(&rng) : INFINITY;
        rays[i] = (tb_ray){{o[0], o[1], o[2]}, 0.0f, {p[0] - o[0], p[1] - o[1], p[2] - o[2]}, tmax};
    }
    tb__batch_trace(g, &b);
    int occ_differ = tb__occ_differ(s, &b), differ = 0, routed = 0, tri = 0;
    for (int i = 0; i < N; ++i) {
        tb_hit c = tb__cpu(s, &rays[i]);
        if (c.object != hits[i].object || c.face != hits[i].face) {
            ++differ;
            continue;
        }
        if (c.object == UINT32_MAX)
            continue;
        if (c.object >= 2) { /* the torus, the sphere and the cube, placed objects in float */
            ++tri;
            tb_assert_near(hits[i].t, c.t, 1e-5 * fabs(c.t));
            assert_true(fabs((double)hits[i].ng.x - c.ng.x) + fabs((double)hits[i].ng.y - c.ng.y) +
                            fabs((double)hits[i].ng.z - c.ng.z) <= 1e-3);
            routed += c.object == 2;
        } else {
            ++tri;
            tb_assert_near(hits[i].t, c.t, 1e-5 * fabs(c.t));
            assert_true(c.ng.x == hits[i].ng.x && c.ng.y == hits[i].ng.y && c.ng.z == hits[i].ng.z);
            tb_assert_near(hits[i].u, c.u, 1e-4);
            tb_assert_near(hits[i].v, c.v, 1e-4);
        }
    }
    print_message("[ info     ] %d torus hits, %d triangle, sphere and cube hits, %d differ, %d occlusion differ\n", routed,
                  tri, differ, occ_differ);
    assert_true(routed > 20 && tri > 50);
    tb__finish_batch(&e, g, s, &b, differ, occ_differ);
}

/* A scene with no triangles, only a torus and a prism: both in the kernel,
 * within float tolerance of the CPU's records. */
static void test_no_triangles(void **state)
{
    (void)state;
    gpu_test_env e;
    gpu_test_open(&e, NULL);
    tb_scene *s = tb__load(tb__analytic);
    tb_gpu_scene *g = tb_gpu_scene_create(e.dev, s);
    assert_non_null(g);
    tb_gpu_scene_info info;
    tb_gpu_scene_get_info(g, &info);
    assert_int_equal(info.gpu_objects, 2);
    assert_int_equal(info.cpu_objects, 0);
    assert_int_equal(info.gpu_tori, 1);
    assert_int_equal(info.gpu_planar, 1);
    enum { N = 64 };
    tb_ray rays[N];
    tb_hit hits[N];
    for (int i = 0; i < N; ++i)
        rays[i] = (tb_ray){{-1.5f + 0.05f * (float)i, 0.5f, 5.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, INFINITY};
    assert_int_equal(tb_gpu_intersect(g, rays, N, hits, NULL), TB_OK);
    int hit = 0;
    for (int i = 0; i < N; ++i) {
        tb_hit c = tb__cpu(s, &rays[i]);
        assert_int_equal(c.object, hits[i].object);
        assert_int_equal(c.face, hits[i].face);
        if (c.object == UINT32_MAX)
            continue;
        tb_assert_near(hits[i].t, c.t, 1e-5 * c.t);
        tb_assert_near(hits[i].ng.x, c.ng.x, 1e-4);
        tb_assert_near(hits[i].ng.y, c.ng.y, 1e-4);
        tb_assert_near(hits[i].ng.z, c.ng.z, 1e-4);
        tb_assert_near(hits[i].u, c.u, 1e-4);
        tb_assert_near(hits[i].v, c.v, 1e-4);
        ++hit;
    }
    assert_true(hit > 0);
    tb__finish(&e, g, s);
}

/* A lone cube: the BVH's root is a leaf (the GPU BVH then has one node of
 * its own, the root and an empty box), and a scene with cubes but no
 * triangles or spheres must still be traversed. Exact rays: axis-aligned,
 * through dyadic points, so t and the normal equal the CPU's bit for bit. */
static void test_lone_cube(void **state)
{
    (void)state;
    gpu_test_env e;
    gpu_test_open(&e, NULL);
    tb_scene *s = tb__load("mid 1\ncube \"box\" { transform = [scale(0.5) translate([1 2 3])] }\n");
    tb_gpu_scene *g = tb_gpu_scene_create(e.dev, s);
    assert_non_null(g);
    tb_gpu_scene_info info;
    tb_gpu_scene_get_info(g, &info);
    assert_int_equal(info.gpu_cubes, 1);
    assert_int_equal(info.cpu_objects, 0);
    enum { N = 16 * 16 };
    tb_ray rays[N];
    tb_hit hits[N];
    uint8_t occ[N];
    for (int i = 0; i < N; ++i) { /* down onto the top face z = 3.5, half of them missing the cube */
        float x = 0.0625f + 0.125f * (float)(i % 16), y = 1.0625f + 0.125f * (float)(i / 16);
        rays[i] = (tb_ray){{x, y, 10.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, INFINITY};
    }
    assert_int_equal(tb_gpu_intersect(g, rays, N, hits, NULL), TB_OK);
    assert_int_equal(tb_gpu_occluded(g, rays, N, occ, NULL), TB_OK);
    int hit = 0;
    for (int i = 0; i < N; ++i) {
        tb_hit c = tb__cpu(s, &rays[i]);
        if (!tb__same(&c, &hits[i], 1e-6))
            fail_msg("ray %d: cpu t %.9g object %u face %u, gpu t %.9g object %u face %u", i, c.t, c.object,
                     c.face, hits[i].t, hits[i].object, hits[i].face);
        assert_int_equal(occ[i], c.object != UINT32_MAX);
        if (c.object == 0) {
            assert_true(hits[i].t == 6.5f && hits[i].ng.z == 1.0f);
            ++hit;
        }
    }
    assert_true(hit == 8 * 8); /* x in [0.5, 1.5], y in [1.5, 2.5]: columns and rows 4..11 of 16 */
    tb__finish(&e, g, s);
}

/* A deep BVH mixing kinds in its leaves: a 48 x 48 height field of
 * triangles with spheres and cubes standing in it, random rays (closest and
 * any hit) against the CPU path. Covers the two-children-per-step traversal
 * with its stack (tens of levels), the while-while order and the leaves'
 * triangles-then-placed loops. Tolerance as test_random_mixed. */
static void test_deep_mixed(void **state)
{
    (void)state;
    enum { G = 48 };
    size_t cap = 1u << 20;
    char *text = malloc(cap);
    assert_non_null(text);
    size_t at = (size_t)snprintf(text, cap, "mid 1\npolygons \"field\" { geometry = { vertices = [");
    for (int j = 0; j <= G; ++j)
        for (int i = 0; i <= G; ++i) {
            double x = -4.0 + 8.0 * i / G, y = -4.0 + 8.0 * j / G, z = 0.3 * sin(1.7 * x) * cos(1.3 * y);
            at += (size_t)snprintf(text + at, cap - at, "[%.6f %.6f %.6f] ", x, y, z);
        }
    at += (size_t)snprintf(text + at, cap - at, "] faces = [");
    for (int j = 0; j < G; ++j)
        for (int i = 0; i < G; ++i) {
            int a = j * (G + 1) + i;
            at += (size_t)snprintf(text + at, cap - at, "[%d %d %d] [%d %d %d] ", a, a + 1, a + G + 2, a, a + G + 2,
                                   a + G + 1);
        }
    at += (size_t)snprintf(text + at, cap - at, "] } }\n");
    for (int k = 0; k < 12; ++k) {
        double x = -3.5 + 0.6 * k, y = 3.0 * sin(1.1 * k);
        at += (size_t)snprintf(text + at, cap - at, "%s \"p%d\" { transform = [scale(0.2) translate([%.3f %.3f 0.1])] }\n",
                               k % 2 ? "cube" : "sphere", k, x, y);
    }
    assert_true(at < cap);
    gpu_test_env e;
    gpu_test_open(&e, NULL);
    tb_scene *s = tb__load(text);
    free(text);
    tb_gpu_scene *g = tb_gpu_scene_create(e.dev, s);
    assert_non_null(g);
    tb_gpu_scene_info info;
    tb_gpu_scene_get_info(g, &info);
    assert_int_equal(info.gpu_triangles, 2 * G * G);
    assert_int_equal(info.gpu_spheres + info.gpu_cubes, 12);
    uint64_t seed = tb_test_seed("test_deep_mixed", 3);
    tb_rng rng;
    tb_rng_seed(&rng, seed, 2);
    enum { N = 20000 };
    tb__batch b = tb__batch_new(N);
    tb_ray *rays = b.rays;
    const tb_hit *hits = b.hits;
    for (int i = 0; i < N; ++i) {
        float o[3], p[3];
        for (int k = 0; k < 3; ++k) {
            o[k] = (float)(tb_rng_double(&rng) * 10.0 - 5.0);
            p[k] = (float)(tb_rng_double(&rng) * 8.0 - 4.0);
        }
        o[2] = (float)(tb_rng_double(&rng) * 3.0 + 0.5);
        p[2] = (float)(tb_rng_double(&rng) * 0.8 - 0.4);
        float tmax = i % 3 == 0 ? (float)tb_rng_double(&rng) : INFINITY;
        rays[i] = (tb_ray){{o[0], o[1], o[2]}, 0.0f, {p[0] - o[0], p[1] - o[1], p[2] - o[2]}, tmax};
    }
    tb__batch_trace(g, &b);
    int occ_differ = tb__occ_differ(s, &b), differ = 0, field = 0, placed = 0;
    for (int i = 0; i < N; ++i) {
        tb_hit c = tb__cpu(s, &rays[i]);
        if (c.object != hits[i].object || c.face != hits[i].face) {
            ++differ;
            continue;
        }
        if (c.object == UINT32_MAX)
            continue;
        tb_assert_near(hits[i].t, c.t, 1e-5 * fabs(c.t));
        if (c.object == 0)
            ++field;
        else
            ++placed;
    }
    print_message("[ info     ] %d field hits, %d sphere and cube hits, %d differ, %d occlusion differ\n", field, placed,
                  differ, occ_differ);
    assert_true(field > N / 4 && placed > 50);
    tb__finish_batch(&e, g, s, &b, differ, occ_differ);
}

/* Cylinders, cones and conics (lib/revolved.glsl) against host/object's
 * tb_object_intersect: capped and open cylinders, a cone (closed apex), an
 * open frustum, a hyperboloid (two-sided interval, open ends), an ellipsoid
 * and a paraboloid (closed apex), placed by scales, rotations and
 * translations. Exact rays (axis-aligned, through dyadic points of a unit
 * cylinder and a cone with exact slopes) must give the CPU's t and face
 * exactly; random rays agree within float tolerance, at most 1 in 1000 may
 * differ in object or face (rays within float error of a silhouette or rim). */
static void test_revolved(void **state)
{
    (void)state;
    static const char *text =
        "mid 1\n"
        "cylinder \"can\" { }\n"
        "cylinder \"pipe\" { transform = [scale([0.3 0.3 0.8]) rotate([0 1 0] 90) translate([4 0 0.5])] "
        "geometry = { caps = false } }\n"
        "cone \"cone\" { transform = [translate([-4 0 0])] }\n"
        "cone \"pot\" { transform = [scale([0.6 0.6 0.5]) rotate([1 0 0] 30) translate([0 4 0.5])] "
        "geometry = { top_radius = 0.45 caps = false } }\n"
        "conic \"tower\" { transform = [scale([0.6 0.6 1.2]) translate([0 -4 1.2])] "
        "geometry = { coefficients = [0.5 0 0.5] z_range = [-1 1] caps = false } }\n"
        "conic \"egg\" { transform = [scale([0.45 0.45 0.6]) translate([4 4 0.6])] "
        "geometry = { coefficients = [1 0 -1] z_range = [-1 1] } }\n"
        "conic \"dome\" { transform = [scale([0.7 0.7 0.6]) translate([-4 -4 0.6])] "
        "geometry = { coefficients = [0.5 -0.5 0] z_range = [-1 1] } }\n";
    gpu_test_env e;
    gpu_test_open(&e, NULL);
    tb_scene *s = tb__load(text);
    /* By default every device runs them in the kernel. */
    tb_gpu_scene *g = tb_gpu_scene_create(e.dev, s);
    assert_non_null(g);
    tb_gpu_scene_info info;
    tb_gpu_scene_get_info(g, &info);
    assert_int_equal(info.gpu_quadrics, 7);
    assert_int_equal(info.cpu_objects, 0);
    tb_gpu_scene_destroy(g);
    /* The kernel's path, forced. */
    g = tb_gpu_scene_create_ex(e.dev, s, &(tb_gpu_scene_desc){TB_GPU_QUADRICS_GPU});
    assert_non_null(g);
    tb_gpu_scene_get_info(g, &info);
    assert_int_equal(info.gpu_quadrics, 7);
    assert_int_equal(info.cpu_objects, 0);

    /* Exact rays: down onto the can's top cap (z = 1) and the cone (apex at
     * z = 1, radius (1 - z) / 2, so t is a dyadic), along x through the can. */
    enum { NE = 3 * 16 };
    tb_ray er[NE];
    tb_hit eh[NE];
    for (int i = 0; i < 16; ++i) {
        float a = -0.9375f + 0.125f * (float)i;
        er[i] = (tb_ray){{a, 0.0625f, 4.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, INFINITY};
        er[16 + i] = (tb_ray){{-4.0f + 0.5f * a, 0.0f, 4.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, INFINITY};
        er[32 + i] = (tb_ray){{-2.0f, 0.0f, a}, 0.0f, {1.0f, 0.0f, 0.0f}, INFINITY};
    }
    assert_int_equal(tb_gpu_intersect(g, er, NE, eh, NULL), TB_OK);
    int exact = 0;
    for (int i = 0; i < NE; ++i) {
        tb_hit c = tb__cpu(s, &er[i]);
        if (c.object != eh[i].object || c.face != eh[i].face || c.t != eh[i].t)
            fail_msg("exact ray %d: cpu t %.9g object %u face %u, gpu t %.9g object %u face %u", i, c.t, c.object,
                     c.face, eh[i].t, eh[i].object, eh[i].face);
        if (c.object != UINT32_MAX) {
            ++exact;
            assert_true(fabs((double)c.ng.x - eh[i].ng.x) + fabs((double)c.ng.y - eh[i].ng.y) +
                            fabs((double)c.ng.z - eh[i].ng.z) <= 1e-5);
        }
    }
    assert_true(exact == NE);

    uint64_t seed = tb_test_seed("test_revolved", 5);
    tb_rng rng;
    tb_rng_seed(&rng, seed, 3);
    enum { N = 20000 };
    tb__batch b = tb__batch_new(N);
    tb_ray *rays = b.rays;
    const tb_hit *hits = b.hits;
    for (int i = 0; i < N; ++i) {
        float o[3], p[3];
        for (int k = 0; k < 3; ++k) {
            o[k] = (float)(tb_rng_double(&rng) * 14.0 - 7.0);
            p[k] = (float)(tb_rng_double(&rng) * 10.0 - 5.0);
        }
        p[2] = (float)(tb_rng_double(&rng) * 3.0 - 1.0);
        /* Some rays start inside the solids (the can and the cone are at the origin's columns). */
        if (i % 5 == 0)
            o[0] = p[0] + 0.1f, o[1] = p[1] - 0.1f, o[2] = (float)(tb_rng_double(&rng) * 2.0 - 1.0);
        float tmax = i % 4 == 0 ? (float)tb_rng_double(&rng) : INFINITY;
        rays[i] = (tb_ray){{o[0], o[1], o[2]}, 0.0f, {p[0] - o[0], p[1] - o[1], p[2] - o[2]}, tmax};
    }
    tb__batch_trace(g, &b);
    int occ_differ = tb__occ_differ(s, &b), differ = 0, on[7] = {0}, caps = 0;
    for (int i = 0; i < N; ++i) {
        tb_hit c = tb__cpu(s, &rays[i]);
        if (c.object != hits[i].object || c.face != hits[i].face) {
            ++differ;
            continue;
        }
        if (c.object == UINT32_MAX)
            continue;
        on[c.object]++;
        caps += c.face != s->objects[c.object]->face_base;
        tb_assert_near(hits[i].t, c.t, 1e-5 * fabs(c.t) + 1e-6);
        assert_true(fabs((double)hits[i].ng.x - c.ng.x) + fabs((double)hits[i].ng.y - c.ng.y) +
                        fabs((double)hits[i].ng.z - c.ng.z) <= 1e-3);
    }
    print_message("[ info     ] hits per object %d %d %d %d %d %d %d (%d on caps), %d differ, %d occlusion differ\n",
                  on[0], on[1], on[2], on[3], on[4], on[5], on[6], caps, differ, occ_differ);
    for (int k = 0; k < 7; ++k)
        assert_true(on[k] > 20);
    assert_true(caps > 50);
    tb__finish_batch(&e, g, s, &b, differ, occ_differ);
}

/* Rays spawned off the GPU's analytic surfaces the way a renderer spawns
 * secondary rays (tb_object_hit_point, tb_spawn_ray_origin: offsets sized
 * for the CPU's double arithmetic, tmin = 0): the kernel must not find the
 * surface it starts on again in float (it did on 1 % of diffuse rays off a
 * sphere before lib/bvh_traverse.glsl raised tmin by its float error bound).
 * Spheres, cubes, a cylinder, a cone and a conic, forced into the kernel. */
static void test_spawned(void **state)
{
    (void)state;
    static const char *text =
        "mid 1\n"
        "sphere \"ball\" { transform = [scale(0.5) translate([3 3 0.5])] }\n"
        "sphere \"egg\" { transform = [scale([0.3 0.4 0.6]) rotate([1 1 0] 40) translate([-2 2.5 0.6])] }\n"
        "cube \"box\" { transform = [scale([0.25 0.5 0.25]) rotate([0 0 1] 30) translate([-3 -3 0.25])] }\n"
        "cylinder \"can\" { transform = [scale(0.5) translate([3 -3 0.5])] }\n"
        "cone \"cone\" { transform = [scale(0.7) translate([0 0 0.7])] }\n"
        "conic \"tower\" { transform = [scale([0.6 0.6 1.2]) translate([0 3.5 1.2])] "
        "geometry = { coefficients = [0.5 0 0.5] z_range = [-1 1] caps = false } }\n";
    gpu_test_env e;
    gpu_test_open(&e, NULL);
    tb_scene *s = tb__load(text);
    tb_gpu_scene *g = tb_gpu_scene_create_ex(e.dev, s, &(tb_gpu_scene_desc){TB_GPU_QUADRICS_GPU});
    assert_non_null(g);
    uint64_t seed = tb_test_seed("test_spawned", 7);
    tb_rng rng;
    tb_rng_seed(&rng, seed, 4);
    enum { N = 20000 };
    tb__batch b = tb__batch_new(N);
    tb_ray *rays = b.rays;
    const tb_hit *hits = b.hits;
    int n = 0;
    while (n < N) {
        /* A ray from above toward a random point of the objects' region. */
        tb_vec3 o = {(float)(tb_rng_double(&rng) * 10.0 - 5.0), (float)(tb_rng_double(&rng) * 10.0 - 5.0), 6.0f};
        tb_vec3 q = {(float)(tb_rng_double(&rng) * 8.0 - 4.0), (float)(tb_rng_double(&rng) * 8.0 - 4.0),
                     (float)(tb_rng_double(&rng) * 1.5)};
        tb_ray r = {o, 0.0f, {q.x - o.x, q.y - o.y, q.z - o.z}, INFINITY};
        tb_hit h;
        tb_vec3 p, perr;
        if (!tb_scene_intersect(s, &r, &h))
            continue;
        r.tmax = h.t;
        if (!tb_object_hit_point(s->objects[h.object], &r, &h, &p, &perr))
            continue;
        /* Half reflected-ish (away from the surface), half into the solid (through it). */
        tb_vec3 nrm = tb_vec3_dot(h.ng, r.d) > 0.0f ? tb_vec3_neg(h.ng) : h.ng;
        tb_vec3 w = {(float)(tb_rng_double(&rng) - 0.5), (float)(tb_rng_double(&rng) - 0.5),
                     (float)(tb_rng_double(&rng) - 0.5)};
        float side = n % 2 ? -1.0f : 1.0f, dn = tb_vec3_dot(w, nrm);
        if (dn * side < 0.0f)
            w = (tb_vec3){w.x - 2.0f * dn * nrm.x, w.y - 2.0f * dn * nrm.y, w.z - 2.0f * dn * nrm.z};
        if (fabsf(tb_vec3_dot(w, nrm)) < 0.05f)
            continue;
        float tmax = n % 3 == 0 ? 2.0f : INFINITY;
        rays[n++] = (tb_ray){tb_spawn_ray_origin(p, perr, h.ng, w), 0.0f, w, tmax};
    }
    tb__batch_trace(g, &b);
    int occ_differ = tb__occ_differ(s, &b), differ = 0, hit = 0;
    for (int i = 0; i < N; ++i) {
        tb_hit c = tb__cpu(s, &rays[i]);
        differ += c.object != hits[i].object || c.face != hits[i].face;
        hit += c.object != UINT32_MAX;
    }
    print_message("[ info     ] %d spawned rays, %d hit on the CPU, %d differ, %d occlusion differ\n", N, hit, differ,
                  occ_differ);
    assert_true(hit > N / 4);
    tb__finish_batch(&e, g, s, &b, differ, occ_differ);
}

/* Writes `head`, then n unions of 12 tori (rows `dy` apart), then the closing brace. */
static void tb__tori_unions(char *text, size_t size, const char *head, int n, int dy)
{
    int len = snprintf(text, size, "%s", head);
    for (int u = 0; u < n; ++u) {
        len += snprintf(text + len, size - (size_t)len, " union {");
        for (int i = 0; i < 12; ++i)
            len += snprintf(text + len, size - (size_t)len,
                            " torus { transform = [translate([%d %d 0])] geometry = { major = 1 minor = 0.2 } }", i,
                            dy * u);
        len += snprintf(text + len, size - (size_t)len, " }");
    }
    snprintf(text + len, size - (size_t)len, " }\n");
}

/* The scene `text` is refused by tb_gpu_scene_create with a message holding both phrases. */
static void tb__refused(gpu_test_env *e, const char *text, const char *phrase1, const char *phrase2)
{
    tb_scene *s = tb__load(text);
    assert_null(tb_gpu_scene_create(e->dev, s));
    if (!strstr(tb_last_error(), phrase1) || !strstr(tb_last_error(), phrase2))
        fail_msg("refusal message: %s", tb_last_error());
    tb_scene_free(s);
}

/* CSG trees beyond the kernel's per-ray bounds are refused when the GPU
 * scene is made, with a message naming the object and the bound; a tree
 * within them is taken. */
static void test_csg_bounds(void **state)
{
    (void)state;
    gpu_test_env e;
    gpu_test_open(&e, NULL);
    char text[8192];
    /* 33 children: beyond TB_GPU_CSG_CHILDREN */
    int len = snprintf(text, sizeof text, "mid 1\nunion \"wide\" {");
    for (int i = 0; i < 33; ++i)
        len += snprintf(text + len, sizeof text - (size_t)len, " sphere { transform = [translate([%d 0 0])] }", i);
    snprintf(text + len, sizeof text - (size_t)len, " }\n");
    tb__refused(&e, text, "object 0 (\"wide\"): CSG tree beyond the Vulkan intersect kernel", "33 children");
    /* three unions of 12 tori: 144 crossings pending, beyond TB_GPU_CSG_POOL */
    tb__tori_unions(text, sizeof text, "mid 1\nsphere { }\nunion \"many\" {", 3, 1);
    tb__refused(&e, text, "object 1 (\"many\")", "up to 144 crossings");
    /* two unions of 12: 96, taken */
    tb__tori_unions(text, sizeof text, "mid 1\nunion \"fits\" {", 2, 3);
    tb_scene *s = tb__load(text);
    tb_gpu_scene *g = tb_gpu_scene_create(e.dev, s);
    assert_non_null(g);
    tb_gpu_scene_info info;
    tb_gpu_scene_get_info(g, &info);
    assert_int_equal(info.gpu_csg, 1);
    assert_int_equal(info.cpu_objects, 0);
    /* rays down onto the tori agree with the CPU */
    enum { N = 256 };
    tb_ray rays[N];
    tb_hit hits[N];
    int hit = 0;
    for (int i = 0; i < N; ++i)
        rays[i] = (tb_ray){{-1.0f + 0.05f * (float)(i % 64), -0.6f + 1.05f * (float)(i / 64), 5.0f}, 0.0f,
                           {0.01f, 0.0f, -1.0f}, INFINITY};
    assert_int_equal(tb_gpu_intersect(g, rays, N, hits, NULL), TB_OK);
    for (int i = 0; i < N; ++i) {
        tb_hit c = tb__cpu(s, &rays[i]);
        assert_int_equal(c.object, hits[i].object);
        if (c.object == UINT32_MAX)
            continue;
        assert_int_equal(c.face, hits[i].face);
        tb_assert_near(hits[i].t, c.t, 1e-5 * c.t);
        ++hit;
    }
    assert_true(hit > 20);
    tb__finish(&e, g, s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_exact_grid),
        cmocka_unit_test(test_random_mixed),
        cmocka_unit_test(test_no_triangles),
        cmocka_unit_test(test_csg_bounds),
        cmocka_unit_test(test_lone_cube),
        cmocka_unit_test(test_deep_mixed),
        cmocka_unit_test(test_revolved),
        cmocka_unit_test(test_spawned),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
