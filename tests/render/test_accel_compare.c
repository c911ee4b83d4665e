/* BVH, grid and list against an independent brute force: the same closest
 * hit, bit for bit (t, object, face, u, v, normal), and the same occlusion
 * answer, on random scenes and rays, including ties, rays along voxel
 * planes, huge and tiny scales; BVH structure, SAH cost and determinism
 * across thread counts; statistics counters. */
#include "tb_test.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "host/render/accel.h"
#include "test_accel_prims.h"
#include "util/stats/stats.h"

static const tb_accel_kind kinds[] = {TB_ACCEL_BVH, TB_ACCEL_GRID, TB_ACCEL_LIST};
#define NKINDS 3

/* The number of rays is divided by $TB_ACCEL_TEST_DIVISOR (the unoptimised
 * sanitizer build uses 4). */
static int divisor(void)
{
    const char *e = getenv("TB_ACCEL_TEST_DIVISOR");
    int d = e ? atoi(e) : 1;
    return d > 0 ? d : 1;
}

static void build_all(tp_scene *s, tb_accel *acc[NKINDS], const tb_accel_options *opt)
{
    tb_accel_callbacks cb = {tp_cb_intersect, tp_cb_occluded, s, NULL};
    for (int k = 0; k < NKINDS; k++) {
        tb_status st = tb_accel_build(kinds[k], s->refs, s->n, &cb, opt, &acc[k]);
        if (st)
            fail_msg("build %s: %s", tb_accel_kind_name(kinds[k]), tb_last_error());
    }
}

static void free_all(tb_accel *acc[NKINDS])
{
    for (int k = 0; k < NKINDS; k++)
        tb_accel_free(acc[k]);
}

static void print_hit(const char *what, bool found, const tb_hit *h)
{
    if (!found)
        print_message("  %s: miss\n", what);
    else
        print_message("  %s: t %.9g (%a) object %u face %u uv %.9g %.9g n %.9g %.9g %.9g\n", what,
                      (double)h->t, (double)h->t, h->object, h->face, (double)h->u, (double)h->v,
                      (double)h->ng.x, (double)h->ng.y, (double)h->ng.z);
}

/* Checks one ray against every structure; returns true if the brute force hit. */
static bool check_ray(tp_scene *s, tb_accel *acc[NKINDS], const tb_ray *ray, long ray_no)
{
    tb_hit ref, got;
    bool want = tp_brute(s, ray, &ref);
    for (int k = 0; k < NKINDS; k++) {
        memset(&got, 0xab, sizeof got);
        bool found = tb_accel_intersect(acc[k], ray, &got);
        bool occl = tb_accel_occluded(acc[k], ray);
        if (found != want || (want && memcmp(&got, &ref, sizeof got) != 0) || occl != want) {
            print_message("ray %ld: o %a %a %a d %a %a %a tmin %a tmax %a\n", ray_no, (double)ray->o.x,
                          (double)ray->o.y, (double)ray->o.z, (double)ray->d.x, (double)ray->d.y,
                          (double)ray->d.z, (double)ray->tmin, (double)ray->tmax);
            print_hit("brute force", want, &ref);
            print_hit(tb_accel_kind_name(kinds[k]), found, &got);
            fail_msg("%s differs from brute force (occluded %d)", tb_accel_kind_name(kinds[k]), occl);
        }
    }
    return want;
}

static void compare_random(uint64_t seed, size_t nprims, long nrays, float scale, float offset)
{
    tb_rng r;
    tb_rng_seed(&r, seed, 1);
    tp_scene s = {0};
    tp_random_scene(&s, &r, nprims, scale, offset);
    tb_accel *acc[NKINDS];
    build_all(&s, acc, NULL);
    long hits = 0;
    nrays /= divisor();
    for (long i = 0; i < nrays; i++) {
        tb_ray ray = tp_random_ray(&r, &s, scale, offset);
        hits += check_ray(&s, acc, &ray, i);
    }
    /* The ray mix must actually hit things, or the comparison proves little. */
    assert_true(hits > nrays / 5);
    assert_true(hits < nrays);
    free_all(acc);
    tp_free(&s);
}

static void test_random_small(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("random_small", 11);
    for (int i = 0; i < 4; i++)
        compare_random(seed + i, 60 + 80 * i, 3000, 1.0f, 0.0f);
}

static void test_random_large(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("random_large", 12);
    compare_random(seed, 2000, 1500, 1.0f, 0.0f);
}

/* Huge (1e6) and tiny (1e-6) scenes, and a unit scene far from the origin. */
static void test_scales(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("scales", 13);
    compare_random(seed, 400, 1500, 1e6f, 0.0f);
    compare_random(seed + 1, 400, 1500, 1e-6f, 0.0f);
    compare_random(seed + 2, 400, 1500, 1.0f, 1000.0f);
    compare_random(seed + 3, 400, 1500, 1e-6f, 1e-3f);
}

/* Exact ties: every sphere is present several times under different object
 * and face numbers. The winner must be the lowest object, then the lowest
 * face, then the first reference, by construction of the scene. */
static void test_ties(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("ties", 14);
    tb_rng r;
    tb_rng_seed(&r, seed, 2);
    tp_scene s = {0};
    for (uint32_t i = 0; i < 80; i++) {
        float c[3] = {tp_uniform(&r, -1, 1), tp_uniform(&r, -1, 1), tp_uniform(&r, -1, 1)};
        float rad = tp_uniform(&r, 0.02f, 0.2f);
        /* Copies in scrambled order: (object 3i+2, face 0), (3i, face 5), (3i, face 2), (3i+1, face 0). */
        tp_add_sphere(&s, c[0], c[1], c[2], rad, 3 * i + 2, 0);
        tp_add_sphere(&s, c[0], c[1], c[2], rad, 3 * i, 5);
        tp_add_sphere(&s, c[0], c[1], c[2], rad, 3 * i, 2);
        tp_add_sphere(&s, c[0], c[1], c[2], rad, 3 * i + 1, 0);
        tp_add_sphere(&s, c[0], c[1], c[2], rad, 3 * i, 2); /* same t, object and face as the third, */
        s.prims[s.n - 1].tag = 1.0f;                         /* but another v: the earlier reference wins */
    }
    tb_accel *acc[NKINDS];
    build_all(&s, acc, NULL);
    long hits = 0, n = 4000 / divisor();
    for (long i = 0; i < n; i++) {
        tb_ray ray = tp_random_ray(&r, &s, 1.0f, 0.0f);
        if (check_ray(&s, acc, &ray, i)) {
            tb_hit h;
            assert_true(tb_accel_intersect(acc[0], &ray, &h));
            assert_int_equal(h.object % 3, 0);
            assert_int_equal(h.face, 2);
            assert_true(h.v < 1.0f);
            hits++;
        }
    }
    assert_true(hits > n / 10);
    free_all(acc);
    tp_free(&s);
}

/* Rays running along voxel planes, through voxel edges and corners, and
 * grazing flat boxes that lie in voxel planes. */
static void test_voxel_planes(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("voxel_planes", 15);
    tb_rng r;
    tb_rng_seed(&r, seed, 3);
    tp_scene s = {0};
    /* Unit-sized content on integer coordinates 0..8: with 512 primitives the
     * grid has 3 * 8 = 24 voxels per axis, so many planes fall on voxel planes. */
    for (int i = 0; i < 512; i++) {
        float x = (float)tb_rng_below(&r, 9), y = (float)tb_rng_below(&r, 9), z = (float)tb_rng_below(&r, 9);
        if (i % 3 == 0) {
            tp_add_sphere(&s, x, y, z, 0.5f * (1 + tb_rng_below(&r, 3)), (uint32_t)i, 0);
        } else {
            /* Axis-aligned right triangles with corners on the integer lattice. */
            int ax = i % 3, b1 = (ax + 1) % 3, b2 = (ax + 2) % 3;
            float v[3][3];
            float p[3] = {x, y, z};
            for (int j = 0; j < 3; j++)
                memcpy(v[j], p, sizeof p);
            v[1][b1] += 1.0f;
            v[2][b2] += 1.0f;
            tp_add_triangle(&s, (const float(*)[3])v, (uint32_t)i, 1);
        }
    }
    tb_accel *acc[NKINDS];
    build_all(&s, acc, NULL);
    tb_accel_stats gs;
    tb_accel_get_stats(acc[1], &gs);
    float lo[3] = {gs.grid_bounds.lo.x, gs.grid_bounds.lo.y, gs.grid_bounds.lo.z};
    float hi[3] = {gs.grid_bounds.hi.x, gs.grid_bounds.hi.y, gs.grid_bounds.hi.z};
    long n = 6000 / divisor(), hits = 0;
    for (long i = 0; i < n; i++) {
        float o[3], d[3] = {0, 0, 0};
        for (int k = 0; k < 3; k++) {
            int m = (int)tb_rng_below(&r, 3);
            if (m == 0) /* on a voxel plane (as the grid computes them, up to float rounding) */
                o[k] = lo[k] + (hi[k] - lo[k]) * (float)tb_rng_below(&r, (uint32_t)gs.grid_res[k] + 1) /
                                   (float)gs.grid_res[k];
            else if (m == 1) /* on an integer plane: an edge or face of the content */
                o[k] = (float)tb_rng_below(&r, 10) - 0.5f * (float)tb_rng_below(&r, 2);
            else
                o[k] = tp_uniform(&r, -2, 10);
        }
        int ax = (int)tb_rng_below(&r, 3);
        switch (tb_rng_below(&r, 3)) {
        case 0: /* along an axis, in the plane of the other two coordinates */
            d[ax] = tb_rng_below(&r, 2) ? 1.0f : -1.0f;
            o[ax] = tb_rng_below(&r, 2) ? -5.0f : 13.0f;
            break;
        case 1: /* in an axis plane, diagonal across voxel corners */
            d[(ax + 1) % 3] = tb_rng_below(&r, 2) ? 1.0f : -1.0f;
            d[(ax + 2) % 3] = tb_rng_below(&r, 2) ? 1.0f : -1.0f;
            break;
        default: /* through voxel corners in 3D */
            for (int k = 0; k < 3; k++)
                d[k] = tb_rng_below(&r, 2) ? 1.0f : -1.0f;
            break;
        }
        tb_ray ray = tb_ray_make((tb_vec3){o[0], o[1], o[2]}, (tb_vec3){d[0], d[1], d[2]}, 0.0f, INFINITY);
        if (tb_rng_below(&r, 4) == 0)
            ray.tmin = -3.0f;
        hits += check_ray(&s, acc, &ray, i);
    }
    assert_true(hits > n / 10);
    free_all(acc);
    tp_free(&s);
}

/* Grazing rays: tangent to spheres (at exactly the radius from the centre,
 * and one float either side), and along the faces and edges of the boxes
 * of spheres lying on a lattice, so that hits sit on box boundaries. */
static void test_grazing(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("grazing", 19);
    tb_rng r;
    tb_rng_seed(&r, seed, 9);
    tp_scene s = {0};
    for (int x = 0; x < 6; x++)
        for (int y = 0; y < 6; y++)
            for (int z = 0; z < 6; z++)
                if (tb_rng_below(&r, 3) == 0)
                    tp_add_sphere(&s, (float)x, (float)y, (float)z, tb_rng_below(&r, 2) ? 0.5f : 0.25f,
                                  (uint32_t)(x + 6 * y + 36 * z), 0);
    tb_accel *acc[NKINDS];
    build_all(&s, acc, NULL);
    long n = 4000 / divisor(), hits = 0;
    for (long i = 0; i < n; i++) {
        /* Offsets of 0.5 or 0.25 from a lattice line: tangent to spheres of that radius. */
        float off[2];
        for (int k = 0; k < 2; k++) {
            off[k] = (float)tb_rng_below(&r, 6) + (tb_rng_below(&r, 2) ? 0.5f : 0.25f) * (tb_rng_below(&r, 2) ? 1 : -1);
            if (tb_rng_below(&r, 4) == 0)
                off[k] = tb_rng_below(&r, 2) ? tb_next_float_up(off[k]) : tb_next_float_down(off[k]);
            if (tb_rng_below(&r, 4) == 0)
                off[k] = (float)tb_rng_below(&r, 6); /* through the centres */
        }
        int ax = (int)tb_rng_below(&r, 3);
        float o[3], d[3] = {0, 0, 0};
        o[ax] = tb_rng_below(&r, 2) ? -3.0f : 9.0f;
        d[ax] = o[ax] < 0 ? 1.0f : -1.0f;
        o[(ax + 1) % 3] = off[0];
        o[(ax + 2) % 3] = off[1];
        tb_ray ray = tb_ray_make((tb_vec3){o[0], o[1], o[2]}, (tb_vec3){d[0], d[1], d[2]}, 0.0f, INFINITY);
        hits += check_ray(&s, acc, &ray, i);
    }
    assert_true(hits > n / 10);
    free_all(acc);
    tp_free(&s);
}

/* Checks the flattened BVH: depth-first layout, every reference in exactly
 * one leaf, boxes nested, leaf sizes within the limit, and the reported SAH
 * cost and depth recomputed from the nodes. */
static void check_bvh(const tb_accel *acc, const tp_scene *s, int max_leaf)
{
    size_t nn, nr;
    const tb_bvh_node *nodes = tb_accel_bvh_nodes(acc, &nn);
    const uint32_t *refs = tb_accel_bvh_refs(acc, &nr);
    tb_accel_stats st;
    tb_accel_get_stats(acc, &st);
    assert_int_equal(nn, st.bvh_nodes);
    assert_int_equal(nr, st.nprims);
    char *seen = calloc(s->n, 1);
    size_t *stack = malloc(nn * sizeof *stack);
    int *depth = malloc(nn * sizeof *depth);
    assert_non_null(seen);
    /* Independent SAH: surface areas in double, as the docs define the cost. */
    const tb_aabb *rb = &nodes[0].bounds;
    double ex = (double)rb->hi.x - rb->lo.x, ey = (double)rb->hi.y - rb->lo.y, ez = (double)rb->hi.z - rb->lo.z;
    double root_area = ex * ey + ey * ez + ez * ex;
    assert_true(root_area > 0.0);
    double sah = 0.0;
    size_t sp = 0, leaves = 0, visited = 0;
    int maxdepth = 0;
    stack[sp] = 0;
    depth[0] = 0;
    sp++;
    while (sp) {
        size_t i = stack[--sp];
        visited++;
        const tb_bvh_node *nd = &nodes[i];
        const tb_aabb *b = &nd->bounds;
        double bx = (double)b->hi.x - b->lo.x, by = (double)b->hi.y - b->lo.y, bz = (double)b->hi.z - b->lo.z;
        double p = (bx * by + by * bz + bz * bx) / root_area;
        assert_int_equal(nd->pad, 0);
        if (nd->count == 0) {
            sah += 1.0 * p;
            assert_true(nd->axis < 3);
            assert_true(i + 1 < nn && nd->offset > i + 1 && nd->offset < nn);
            const tb_aabb *c0 = &nodes[i + 1].bounds, *c1 = &nodes[nd->offset].bounds;
            assert_true(tb_aabb_contains_box(b, c0) && tb_aabb_contains_box(b, c1));
            /* The node box is exactly the union of its children's. */
            tb_aabb u = tb_aabb_union(*c0, *c1);
            assert_true(tb_vec3_equal(u.lo, b->lo) && tb_vec3_equal(u.hi, b->hi));
            depth[i + 1] = depth[nd->offset] = depth[i] + 1;
            stack[sp++] = nd->offset;
            stack[sp++] = i + 1;
        } else {
            leaves++;
            sah += 1.0 * nd->count * p;
            if (depth[i] > maxdepth)
                maxdepth = depth[i];
            assert_true(nd->count <= max_leaf);
            assert_true(nd->offset + nd->count <= nr);
            tb_aabb u = tb_aabb_empty();
            for (uint32_t k = nd->offset; k < nd->offset + nd->count; k++) {
                assert_true(refs[k] < s->n);
                assert_int_equal(seen[refs[k]], 0);
                seen[refs[k]] = 1;
                u = tb_aabb_union(u, s->refs[refs[k]].bounds);
            }
            assert_true(tb_vec3_equal(u.lo, b->lo) && tb_vec3_equal(u.hi, b->hi));
        }
    }
    assert_int_equal(visited, nn); /* every node reachable exactly once */
    size_t kept = 0;
    for (size_t i = 0; i < s->n; i++) {
        bool empty = tb_aabb_is_empty(&s->refs[i].bounds);
        assert_int_equal(seen[i], empty ? 0 : 1);
        kept += !empty;
    }
    assert_int_equal(kept, nr);
    assert_int_equal(leaves, st.bvh_leaves);
    assert_int_equal(maxdepth, st.bvh_depth);
    tb_assert_near(st.bvh_sah_cost, sah, 1e-9 * sah);
    free(seen);
    free(stack);
    free(depth);
}

static void test_bvh_structure(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("bvh_structure", 16);
    tb_rng r;
    tb_rng_seed(&r, seed, 4);
    tp_scene s = {0};
    tp_random_scene(&s, &r, 5000, 1.0f, 0.0f);
    tb_accel_callbacks cb = {tp_cb_intersect, NULL, &s, NULL};
    for (int leaf = 1; leaf <= 16; leaf *= 4) {
        tb_accel_options opt = {.bvh_max_leaf = leaf, .bvh_keep_binary = 1};
        tb_accel *acc;
        assert_int_equal(tb_accel_build(TB_ACCEL_BVH, s.refs, s.n, &cb, &opt, &acc), TB_OK);
        check_bvh(acc, &s, leaf);
        tb_accel_stats st;
        tb_accel_get_stats(acc, &st);
        /* SAH splits keep random scenes shallow; the bound is the build's hard limit. */
        assert_true(st.bvh_depth < 64 + 32);
        assert_true(st.bvh_sah_cost > 0.0);
        /* The tree must beat testing every reference (the cost of one big leaf). */
        assert_true(st.bvh_sah_cost < (double)s.n);
        tb_accel_free(acc);
    }
    tp_free(&s);
}

/* The tree is the same, byte for byte, for 1, 2 and 3 build threads (the
 * scene is large enough for the build to use tasks: subtrees of 4096
 * references and more, also with the sanitizer build's smaller scene). */
static void test_bvh_deterministic(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("bvh_deterministic", 17);
    tb_rng r;
    tb_rng_seed(&r, seed, 5);
    tp_scene s = {0};
    tp_random_scene(&s, &r, (size_t)(30000 / divisor()), 1.0f, 0.0f);
    tb_accel_callbacks cb = {tp_cb_intersect, NULL, &s, NULL};
    tb_accel *a[3];
    for (int t = 0; t < 3; t++) {
        tb_accel_options opt = {.threads = t + 1, .bvh_keep_binary = 1};
        assert_int_equal(tb_accel_build(TB_ACCEL_BVH, s.refs, s.n, &cb, &opt, &a[t]), TB_OK);
    }
    size_t n0, r0;
    const tb_bvh_node *nodes0 = tb_accel_bvh_nodes(a[0], &n0);
    const uint32_t *refs0 = tb_accel_bvh_refs(a[0], &r0);
    assert_true(n0 > 2000);
    for (int t = 1; t < 3; t++) {
        size_t n1, r1;
        const tb_bvh_node *nodes1 = tb_accel_bvh_nodes(a[t], &n1);
        const uint32_t *refs1 = tb_accel_bvh_refs(a[t], &r1);
        assert_int_equal(n0, n1);
        assert_int_equal(r0, r1);
        assert_memory_equal(nodes0, nodes1, n0 * sizeof *nodes0);
        assert_memory_equal(refs0, refs1, r0 * sizeof *refs0);
    }
    check_bvh(a[1], &s, 8);
    for (int t = 0; t < 3; t++)
        tb_accel_free(a[t]);
    tp_free(&s);
}

/* By default the binary nodes are freed once collapsed into the wide tree:
 * tb_accel_bvh_nodes gives none, the stats still count them, the structure
 * holds 32 bytes per node less, and every query gives the same answer as
 * with the nodes kept (the CPU traverses the wide tree alone). */
static void test_bvh_drop_binary(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("bvh_drop_binary", 23);
    tb_rng r;
    tb_rng_seed(&r, seed, 7);
    tp_scene s = {0};
    tp_random_scene(&s, &r, (size_t)(5000 / divisor()), 1.0f, 0.0f);
    tb_accel_callbacks cb = {tp_cb_intersect, tp_cb_occluded, &s, NULL};
    tb_accel *keep, *drop;
    assert_int_equal(tb_accel_build(TB_ACCEL_BVH, s.refs, s.n, &cb, &(tb_accel_options){.bvh_keep_binary = 1}, &keep),
                     TB_OK);
    assert_int_equal(tb_accel_build(TB_ACCEL_BVH, s.refs, s.n, &cb, NULL, &drop), TB_OK);
    size_t nk = 0, nd = 1;
    assert_non_null(tb_accel_bvh_nodes(keep, &nk));
    assert_null(tb_accel_bvh_nodes(drop, &nd));
    assert_int_equal(nd, 0);
    tb_accel_stats sk, sd;
    tb_accel_get_stats(keep, &sk);
    tb_accel_get_stats(drop, &sd);
    assert_true(nk > 100);
    assert_int_equal(sk.bvh_nodes, nk);
    assert_int_equal(sd.bvh_nodes, nk);
    assert_int_equal(sk.memory_bytes - sd.memory_bytes, nk * sizeof(tb_bvh_node));
    for (int i = 0; i < 2000; i++) {
        tb_ray ray = tp_random_ray(&r, &s, 1.0f, 0.0f);
        tb_hit hk, hd;
        bool ak = tb_accel_intersect(keep, &ray, &hk), ad = tb_accel_intersect(drop, &ray, &hd);
        assert_int_equal(ak, ad);
        if (ak) {
            assert_int_equal(hk.object, hd.object);
            assert_int_equal(hk.face, hd.face);
            assert_true(hk.t == hd.t);
        }
        assert_int_equal(tb_accel_occluded(keep, &ray), tb_accel_occluded(drop, &ray));
    }
    tb_accel_free(keep);
    tb_accel_free(drop);
    tp_free(&s);
}

/* ---- SAH quality against an exact sweep ----
 * A slow reference builder, independent of bvh.c: top-down, every node
 * sorts its references by centroid on each axis (ties by index) and
 * evaluates every split between two of them (not bins) with the same cost
 * and leaf rule (C_split = 1 + (A(L) n_L + A(R) n_R) / A(node), leaf when
 * n <= 8 and n <= C_split, or n == 1); its tree's SAH cost is the
 * reference value the binned build must stay within 5 % of. */
typedef struct xs_ref {
    tb_aabb b;
    float c[3];
    uint32_t id;
} xs_ref;

static int xs_axis;
static int xs_cmp(const void *pa, const void *pb)
{
    const xs_ref *a = pa, *b = pb;
    if (a->c[xs_axis] != b->c[xs_axis])
        return a->c[xs_axis] < b->c[xs_axis] ? -1 : 1;
    return a->id < b->id ? -1 : (a->id > b->id);
}

static double xs_area(const tb_aabb *b)
{
    double ex = (double)b->hi.x - b->lo.x, ey = (double)b->hi.y - b->lo.y, ez = (double)b->hi.z - b->lo.z;
    return ex * ey + ey * ez + ez * ex;
}

/* SAH sum (unnormalised) of the exact-sweep subtree over r[0, n). */
static double xs_build(xs_ref *r, size_t n, double *right)
{
    tb_aabb box = tb_aabb_empty();
    for (size_t i = 0; i < n; i++)
        box = tb_aabb_union(box, r[i].b);
    double area = xs_area(&box);
    if (n == 1)
        return area;
    double best = INFINITY;
    int best_axis = -1;
    size_t best_k = 0;
    for (int a = 0; a < 3; a++) {
        xs_axis = a;
        qsort(r, n, sizeof *r, xs_cmp);
        tb_aabb acc = tb_aabb_empty();
        for (size_t k = n; k-- > 1;) { /* right[k]: area of r[k, n) */
            acc = tb_aabb_union(acc, r[k].b);
            right[k] = xs_area(&acc);
        }
        acc = tb_aabb_empty();
        for (size_t k = 1; k < n; k++) {
            acc = tb_aabb_union(acc, r[k - 1].b);
            double x = xs_area(&acc) * (double)k + right[k] * (double)(n - k);
            if (x < best)
                best = x, best_axis = a, best_k = k;
        }
    }
    double split = 1.0 + best / area;
    if (n <= 8 && (double)n <= split)
        return (double)n * area;
    xs_axis = best_axis;
    qsort(r, n, sizeof *r, xs_cmp);
    return area + xs_build(r, best_k, right) + xs_build(r + best_k, n - best_k, right);
}

static double xs_sah(const tp_scene *s)
{
    xs_ref *r = malloc(s->n * sizeof *r);
    double *right = malloc(s->n * sizeof *right);
    assert_non_null(r);
    assert_non_null(right);
    tb_aabb root = tb_aabb_empty();
    for (size_t i = 0; i < s->n; i++) {
        const tb_aabb *b = &s->refs[i].bounds;
        r[i] = (xs_ref){*b, {0.5f * b->lo.x + 0.5f * b->hi.x, 0.5f * b->lo.y + 0.5f * b->hi.y,
                             0.5f * b->lo.z + 0.5f * b->hi.z}, (uint32_t)i};
        root = tb_aabb_union(root, *b);
    }
    double sum = xs_build(r, s->n, right);
    free(r);
    free(right);
    return sum / xs_area(&root);
}

/* A displaced sphere (lat/long grid) on a ground quad, and long thin
 * triangles in random directions (boxes that bound badly). */
static void sah_mesh(tp_scene *s, tb_rng *r, int kind)
{
    if (kind == 0) {
        const int nu = 96, nv = 48;
        float amp[4], fr[4][3];
        for (int k = 0; k < 4; k++) {
            amp[k] = tp_uniform(r, 0.01f, 0.05f);
            for (int a = 0; a < 3; a++)
                fr[k][a] = tp_uniform(r, -12.0f, 12.0f);
        }
        float (*p)[3] = malloc(sizeof *p * (size_t)(nu + 1) * (nv + 1));
        assert_non_null(p);
        for (int j = 0; j <= nv; j++)
            for (int i = 0; i <= nu; i++) {
                double th = 3.14159265358979 * j / nv, ph = 2 * 3.14159265358979 * i / nu;
                double d[3] = {sin(th) * cos(ph), sin(th) * sin(ph), cos(th)}, rad = 0.9;
                for (int k = 0; k < 4; k++)
                    rad += amp[k] * sin(fr[k][0] * d[0] + fr[k][1] * d[1] + fr[k][2] * d[2]);
                for (int a = 0; a < 3; a++)
                    p[j * (nu + 1) + i][a] = (float)(rad * d[a]) + (a == 2 ? 1.0f : 0.0f);
            }
        for (int j = 0; j < nv; j++)
            for (int i = 0; i < nu; i++) {
                const float *q00 = p[j * (nu + 1) + i], *q10 = p[j * (nu + 1) + i + 1];
                const float *q01 = p[(j + 1) * (nu + 1) + i], *q11 = p[(j + 1) * (nu + 1) + i + 1];
                float t0[3][3], t1[3][3];
                memcpy(t0[0], q00, 12), memcpy(t0[1], q10, 12), memcpy(t0[2], q11, 12);
                memcpy(t1[0], q00, 12), memcpy(t1[1], q11, 12), memcpy(t1[2], q01, 12);
                tp_add_triangle(s, t0, 0, 0);
                tp_add_triangle(s, t1, 0, 0);
            }
        free(p);
        const float g0[3][3] = {{-3, -3, 0}, {3, -3, 0}, {3, 3, 0}}, g1[3][3] = {{-3, -3, 0}, {3, 3, 0}, {-3, 3, 0}};
        tp_add_triangle(s, g0, 1, 0);
        tp_add_triangle(s, g1, 1, 0);
        return;
    }
    for (int k = 0; k < 6000; k++) {
        tb_vec3 d = tp_random_dir(r), e = tp_random_dir(r);
        float len = tp_uniform(r, 0.3f, 1.5f), w = tp_uniform(r, 0.001f, 0.01f);
        float c[3] = {tp_uniform(r, -2, 2), tp_uniform(r, -2, 2), tp_uniform(r, -2, 2)};
        float v[3][3];
        for (int a = 0; a < 3; a++) {
            float da = tb_vec3_get(d, a), ea = tb_vec3_get(e, a);
            v[0][a] = c[a] - 0.5f * len * da;
            v[1][a] = c[a] + 0.5f * len * da;
            v[2][a] = c[a] + w * ea;
        }
        tp_add_triangle(s, v, 0, (uint32_t)k);
    }
}

static void test_bvh_sah_quality(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("bvh_sah_quality", 23);
    for (int kind = 0; kind < 2; kind++) {
        tb_rng r;
        tb_rng_seed(&r, seed, 7 + (uint64_t)kind);
        tp_scene s = {0};
        sah_mesh(&s, &r, kind);
        double exact = xs_sah(&s);
        tb_accel_callbacks cb = {tp_cb_intersect, NULL, &s, NULL};
        tb_accel *first = NULL;
        for (int threads = 1; threads <= 2; threads++) {
            tb_accel_options opt = {.threads = threads, .bvh_keep_binary = 1};
            tb_accel *acc;
            assert_int_equal(tb_accel_build(TB_ACCEL_BVH, s.refs, s.n, &cb, &opt, &acc), TB_OK);
            if (!first) {
                first = acc;
            } else { /* the same tree at 2 threads, byte for byte */
                size_t n0, n1, r0, r1;
                const tb_bvh_node *a0 = tb_accel_bvh_nodes(first, &n0), *a1 = tb_accel_bvh_nodes(acc, &n1);
                const uint32_t *i0 = tb_accel_bvh_refs(first, &r0), *i1 = tb_accel_bvh_refs(acc, &r1);
                assert_int_equal(n0, n1);
                assert_int_equal(r0, r1);
                assert_memory_equal(a0, a1, n0 * sizeof *a0);
                assert_memory_equal(i0, i1, r0 * sizeof *i0);
            }
            tb_accel_stats st;
            tb_accel_get_stats(acc, &st);
            print_message("  %s, %zu references, %d threads: SAH binned %.4f, exact sweep %.4f, ratio %.4f\n",
                          kind ? "slivers" : "bumpy sphere", s.n, threads, st.bvh_sah_cost, exact,
                          st.bvh_sah_cost / exact);
            assert_true(st.bvh_sah_cost <= 1.05 * exact);
            /* A plane between bins is one of the exact sweep's candidates, so
             * a much lower cost would mean a wrong cost, not a better tree. */
            assert_true(st.bvh_sah_cost >= 0.9 * exact);
            if (acc != first)
                tb_accel_free(acc);
        }
        tb_accel_free(first);
        tp_free(&s);
    }
}

static int64_t counter(const char *name)
{
    tb_stat_total t;
    if (tb_stats_get(name, TB_STAT_KIND_COUNTER, &t) != TB_OK)
        return -1;
    return t.v[0];
}

/* The counters move by what one query did: a ray at a lone sphere visits the
 * BVH's single node and tests it once; the grid visits voxels along the ray. */
static void test_counters(void **state)
{
    (void)state;
    tp_scene s = {0};
    tp_add_sphere(&s, 0, 0, 0, 1, 0, 0);
    tb_accel *acc[NKINDS];
    build_all(&s, acc, NULL);
    tb_ray ray = tb_ray_make((tb_vec3){-5, 0.25f, 0}, (tb_vec3){1, 0, 0}, 0, INFINITY);
    tb_hit h;
    int64_t nv = counter("BVH/nodes visited"), pt = counter("BVH/primitives tested");
    int64_t br = counter("BVH/rays"), bo = counter("BVH/occlusion rays");
    assert_true(tb_accel_intersect(acc[0], &ray, &h));
    assert_int_equal(counter("BVH/nodes visited") - nv, 1);
    assert_int_equal(counter("BVH/primitives tested") - pt, 1);
    assert_int_equal(counter("BVH/rays") - br, 1);
    assert_true(tb_accel_occluded(acc[0], &ray));
    assert_int_equal(counter("BVH/occlusion rays") - bo, 1);

    int64_t vv = counter("Grid/voxels visited"), gt = counter("Grid/primitives tested");
    int64_t gr = counter("Grid/rays");
    assert_true(tb_accel_intersect(acc[1], &ray, &h));
    tb_accel_stats st;
    tb_accel_get_stats(acc[1], &st);
    /* One reference: a 3 * cbrt(1) = 3 voxel grid along x; the ray enters at
     * the first voxel, and the hit (x = -0.968) lies in it, so the walk ends there. */
    assert_int_equal(st.grid_res[0], 3);
    assert_int_equal(counter("Grid/voxels visited") - vv, 1);
    assert_int_equal(counter("Grid/primitives tested") - gt, 1);
    assert_int_equal(counter("Grid/rays") - gr, 1);
    /* A miss walks the whole row of 3 voxels. */
    vv = counter("Grid/voxels visited");
    tb_ray miss = tb_ray_make((tb_vec3){-5, 0.99f, 0.99f}, (tb_vec3){1, 0, 0}, 0, INFINITY);
    assert_false(tb_accel_intersect(acc[1], &miss, &h));
    assert_int_equal(counter("Grid/voxels visited") - vv, 3);

    int64_t lt = counter("List/primitives tested");
    assert_true(tb_accel_intersect(acc[2], &ray, &h));
    assert_int_equal(counter("List/primitives tested") - lt, 1);
    free_all(acc);
    tp_free(&s);
}

/* Near child first: along a row of 1024 spheres, a ray from either end
 * descends straight to the first sphere and then only tests the boxes it
 * pushed on the way (each then pruned by the hit), about 2 x depth nodes;
 * a far-first order would find the far spheres first and visit most nodes. */
static void test_bvh_near_first(void **state)
{
    (void)state;
    tp_scene s = {0};
    for (int i = 0; i < 1024; i++)
        tp_add_sphere(&s, (float)i, 0, 0, 0.4f, (uint32_t)i, 0);
    tb_accel_callbacks cb = {tp_cb_intersect, NULL, &s, NULL};
    tb_accel *acc;
    assert_int_equal(tb_accel_build(TB_ACCEL_BVH, s.refs, s.n, &cb, NULL, &acc), TB_OK);
    tb_accel_stats st;
    tb_accel_get_stats(acc, &st);
    tb_ray rays[2] = {tb_ray_make((tb_vec3){-10, 0.1f, 0}, (tb_vec3){1, 0, 0}, 0, INFINITY),
                      tb_ray_make((tb_vec3){1034, 0.1f, 0}, (tb_vec3){-1, 0, 0}, 0, INFINITY)};
    uint32_t want[2] = {0, 1023};
    for (int i = 0; i < 2; i++) {
        tb_hit h;
        int64_t nv = counter("BVH/nodes visited");
        assert_true(tb_accel_intersect(acc, &rays[i], &h));
        assert_int_equal(h.object, want[i]);
        int64_t visited = counter("BVH/nodes visited") - nv;
        if (visited > 2 * st.bvh_depth + 2)
            fail_msg("ray %d visited %lld nodes (depth %d)", i, (long long)visited, st.bvh_depth);
    }
    tb_accel_free(acc);
    tp_free(&s);
}

/* Concurrent queries from several threads give the single-threaded answers. */
static void test_concurrent_queries(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("concurrent", 18);
    tb_rng r;
    tb_rng_seed(&r, seed, 6);
    tp_scene s = {0};
    tp_random_scene(&s, &r, 1000, 1.0f, 0.0f);
    tb_accel_callbacks cb = {tp_cb_intersect, NULL, &s, NULL};
    int n = 2000 / divisor();
    tb_ray *rays = malloc((size_t)n * sizeof *rays);
    tb_hit *want = malloc((size_t)n * sizeof *want);
    bool *wfound = malloc((size_t)n);
    assert_non_null(rays);
    for (int i = 0; i < n; i++) {
        rays[i] = tp_random_ray(&r, &s, 1.0f, 0.0f);
        wfound[i] = tp_brute(&s, &rays[i], &want[i]);
    }
    for (int k = 0; k < 2; k++) {
        tb_accel *acc;
        assert_int_equal(tb_accel_build(kinds[k], s.refs, s.n, &cb, NULL, &acc), TB_OK);
        int bad = 0;
#pragma omp parallel for num_threads(2) schedule(dynamic, 16) reduction(+ : bad)
        for (int i = 0; i < n; i++) {
            tb_hit h;
            bool f = tb_accel_intersect(acc, &rays[i], &h);
            if (f != wfound[i] || (f && memcmp(&h, &want[i], sizeof h) != 0))
                bad++;
        }
        assert_int_equal(bad, 0);
        tb_accel_free(acc);
    }
    free(rays);
    free(want);
    free(wfound);
    tp_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_random_small),
        cmocka_unit_test(test_random_large),
        cmocka_unit_test(test_scales),
        cmocka_unit_test(test_ties),
        cmocka_unit_test(test_voxel_planes),
        cmocka_unit_test(test_grazing),
        cmocka_unit_test(test_bvh_structure),
        cmocka_unit_test(test_bvh_deterministic),
        cmocka_unit_test(test_bvh_drop_binary),
        cmocka_unit_test(test_bvh_sah_quality),
        cmocka_unit_test(test_counters),
        cmocka_unit_test(test_bvh_near_first),
        cmocka_unit_test(test_concurrent_queries),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
