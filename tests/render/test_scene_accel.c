/* The scene's acceleration references (host/render/scene.h): every triangle
 * of a polygons object is a reference of its own, tested by the structure
 * (tb_accel_tri) and completed by tb_scene_intersect; everything else is one
 * reference through tb_object_intersect. The scene's answer must be, bit for bit, what the
 * object level gives when every object is intersected whole (brute force,
 * ties to the lower object index), for the BVH, the grid and the list, on
 * the bundled scenes and on meshes under mirroring transforms, with rays
 * aimed at vertices and edges (where the watertight tie rule decides). */
#define _XOPEN_SOURCE 700 /* realpath */
#include "tb_test.h"

#include <limits.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>

#include "host/object/intersect.h"
#include "host/object/param.h"
#include "host/render/scene.h"
#include "util/math/rng.h"
#include "util/math/transform.h"
#include "util/mesh/fed.h"

/* 1/10 of the rays under AddressSanitizer. */
static long scaled(long n)
{
#if defined(__SANITIZE_ADDRESS__)
    return n / 10;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
    return n / 10;
#endif
#endif
    return n;
}

/* Closest hit over every object, each intersected whole by the object level. */
static bool brute(const tb_scene *s, const tb_ray *ray, tb_hit *out)
{
    bool found = false;
    for (uint32_t i = 0; i < s->nobjects; i++) {
        tb_hit h;
        if (!tb_object_intersect(s->objects[i], ray, &h))
            continue;
        if (!found || h.t < out->t) { /* equal t: the lower object, met first */
            *out = h;
            found = true;
        }
    }
    return found;
}

static float uni(tb_rng *r, float lo, float hi) { return lo + (hi - lo) * tb_rng_float(r); }

static tb_vec3 random_dir(tb_rng *r)
{
    for (;;) {
        tb_vec3 d = {uni(r, -1, 1), uni(r, -1, 1), uni(r, -1, 1)};
        float l = tb_vec3_length(d);
        if (l > 0.1f && l <= 1.0f)
            return d;
    }
}

/* True if (face, u, v) of hit h names the point o + t d of the ray (world
 * distance within 1e-5 of the scene's size) and the hit's normal is that
 * face's outward normal there: the record describes a real surface point
 * even where it differs from the object level's. */
static bool hit_point_ok(const tb_scene *s, const tb_ray *ray, const tb_hit *h)
{
    uint32_t local;
    const tb_object *leaf = tb_scene_hit_leaf(s, h, &local);
    if (!leaf)
        return false;
    tb_dvec3 p, n;
    if (tb_param_eval_world(leaf->kind, &leaf->geom, &leaf->to_world, (int)local, h->u, h->v, &p, &n, NULL, NULL))
        return false;
    if (!(tb_dvec3_dot(n, (tb_dvec3){h->ng.x, h->ng.y, h->ng.z}) > 0.99))
        return false;
    tb_dvec3 q = {ray->o.x + (double)h->t * ray->d.x, ray->o.y + (double)h->t * ray->d.y,
                  ray->o.z + (double)h->t * ray->d.z};
    tb_vec3 e = tb_aabb_extent(&s->bounds);
    return tb_dvec3_length(tb_dvec3_sub(p, q)) <= 1e-5 * (e.x + e.y + e.z);
}

/* Rays: camera rays, random rays from inside the bounds, and rays from
 * random points aimed exactly at mesh vertices and edge midpoints. */
static tb_ray *make_rays(const tb_scene *s, tb_rng *r, size_t n, size_t *count)
{
    tb_ray *rays = malloc(sizeof *rays * n);
    assert_non_null(rays);
    tb_vec3 lo = s->bounds.lo, hi = s->bounds.hi;
    size_t k = 0;
    for (; k < n / 3; k++)
        rays[k] = tb_camera_ray(&s->camera, uni(r, 0, (float)s->camera.width), uni(r, 0, (float)s->camera.height), 0.5f,
                                0.5f);
    for (; k < 2 * n / 3; k++) {
        tb_vec3 o = {uni(r, lo.x, hi.x), uni(r, lo.y, hi.y), uni(r, lo.z, hi.z)};
        rays[k] = tb_ray_make(o, random_dir(r), 0.0f, INFINITY);
    }
    /* Vertices and edges of the polygons objects, in world space. */
    uint32_t npoly = 0;
    for (uint32_t i = 0; i < s->nobjects; i++)
        npoly += s->objects[i]->kind == TB_PRIM_POLYGONS;
    for (; k < n && npoly; k++) {
        const tb_object *o;
        do
            o = s->objects[tb_rng_below(r, s->nobjects)];
        while (o->kind != TB_PRIM_POLYGONS);
        const tb_object_mesh *m = o->mesh;
        uint32_t t = tb_rng_below(r, m->ntris);
        int c = (int)tb_rng_below(r, 3);
        tb_vec3 a = m->vertices[m->tris[3 * t + c]], b = m->vertices[m->tris[3 * t + (c + 1) % 3]];
        tb_vec3 p = tb_rng_below(r, 2) ? a : tb_vec3_scale(tb_vec3_add(a, b), 0.5f);
        tb_vec3 pw = tb_transform_point(&o->to_world, p);
        tb_vec3 ow = {uni(r, lo.x, hi.x), uni(r, lo.y, hi.y), uni(r, lo.z, hi.z)};
        if (tb_rng_below(r, 2)) /* from outside the scene */
            ow = tb_vec3_add(pw, tb_vec3_scale(random_dir(r), 3.0f * tb_vec3_length(tb_vec3_sub(hi, lo))));
        rays[k] = tb_ray_make(ow, tb_vec3_sub(pw, ow), 0.0f, INFINITY);
    }
    *count = k;
    return rays;
}

/* The scene's answer against the brute force, for every structure. */
static void check_scene(const char *label, tb_scene *s, long nrays, uint64_t seed)
{
    tb_rng r;
    tb_rng_seed(&r, seed, 0);
    size_t n;
    tb_ray *rays = make_rays(s, &r, (size_t)scaled(nrays), &n);
    tb_hit *want = calloc(n, sizeof *want);
    bool *found = calloc(n, sizeof *found);
    assert_non_null(want);
    assert_non_null(found);
    size_t nhit = 0;
    for (size_t i = 0; i < n; i++)
        nhit += found[i] = brute(s, &rays[i], &want[i]);
    assert_true(nhit > n / 4);
    static const tb_accel_kind kinds[] = {TB_ACCEL_BVH, TB_ACCEL_GRID, TB_ACCEL_LIST};
    for (int k = 0; k < 3; k++) {
        assert_int_equal(tb_scene_rebuild_accel(s, kinds[k], NULL), TB_OK);
        long bad = 0, ties = 0;
        for (size_t i = 0; i < n; i++) {
            tb_hit h;
            memset(&h, 0xAB, sizeof h);
            bool f = tb_scene_intersect(s, &rays[i], &h);
            bool occ = tb_scene_occluded(s, &rays[i]);
            /* Without (u, v): the same record bit for bit, u = v = 0. */
            tb_hit hn;
            memset(&hn, 0xCD, sizeof hn);
            bool fn = tb_scene_intersect_no_uv(s, &rays[i], &hn);
            assert_int_equal(fn, f);
            if (f) {
                assert_memory_equal(&hn.t, &h.t, sizeof h.t);
                assert_memory_equal(&hn.ng, &h.ng, sizeof h.ng);
                assert_int_equal(hn.object, h.object);
                assert_int_equal(hn.face, h.face);
                assert_true(hn.u == 0.0f && hn.v == 0.0f);
            }
            /* Ties: a ray exactly through an edge or vertex where two faces
             * or triangles of one mesh are hit at the same float t (a
             * silhouette, a fold). Both levels keep the lowest face, then
             * triangle (docs/accel.md, "Tie rule"), so a tie that differs is
             * counted here (each side a real hit) and fails below. */
            if (f && found[i] && occ && memcmp(&h, &want[i], sizeof h) != 0 && h.t == want[i].t &&
                h.object == want[i].object &&
                (h.face < want[i].face ||
                 (h.face == want[i].face && tb_vec3_equal(h.ng, want[i].ng) && fabsf(h.u - want[i].u) <= 1e-5f &&
                  fabsf(h.v - want[i].v) <= 1e-5f)) &&
                hit_point_ok(s, &rays[i], &h) &&
                hit_point_ok(s, &rays[i], &want[i])) {
                ties++;
                continue;
            }
            if (f != found[i] || occ != found[i] || (f && memcmp(&h, &want[i], sizeof h) != 0)) {
                if (bad < 5)
                    print_message("%s %s ray %zu: scene %d (t %.9g obj %u face %u u %.9g) object level %d (t %.9g obj "
                                  "%u face %u u %.9g), occluded %d\n",
                                  label, tb_accel_kind_name(kinds[k]), i, f, h.t, h.object, h.face, h.u, found[i],
                                  want[i].t, want[i].object, want[i].face, want[i].u, occ);
                bad++;
            }
        }
        if (bad)
            fail_msg("%s: %ld of %zu rays differ from the object level (%s)", label, bad, n,
                     tb_accel_kind_name(kinds[k]));
        print_message("%s %s: %zu rays, %zu hits, %ld equal-t ties at edges and vertices\n", label,
                      tb_accel_kind_name(kinds[k]), n, nhit, ties);
        assert_int_equal(ties, 0);
    }
    free(rays);
    free(want);
    free(found);
}

static void check_file(const char *path, long nrays, uint64_t seed)
{
    tb_scene *s;
    if (tb_scene_load(path, NULL, &s))
        fail_msg("%s", tb_last_error());
    check_scene(path, s, nrays, seed);
    tb_scene_free(s);
}

static void test_cornell(void **state)
{
    (void)state;
    check_file(TB_SOURCE_DIR "/scenes/cornell-box.mid", 12000, tb_test_seed("cornell", 1));
    check_file(TB_SOURCE_DIR "/scenes/tests/cornell-box-coplanar-light.mid", 4000, tb_test_seed("coplanar", 2));
}

static void test_showcase(void **state)
{
    (void)state;
    check_file(TB_SOURCE_DIR "/scenes/showcase.mid", 3000, tb_test_seed("showcase", 3));
    check_file(TB_SOURCE_DIR "/scenes/radiosity-room.mid", 4000, tb_test_seed("room", 4));
}

/* A closed lat-long sphere mesh of quads and triangles and an open grid of
 * quads, under random affine transforms, half of them mirroring, next to a
 * CSG object and an analytic sphere. */
static void test_meshes(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("meshes", 5);
    tb_rng r;
    tb_rng_seed(&r, seed, 1);
    const int rings = 12, segs = 24, grid = 10;
    size_t cap = 1 << 20;
    char *text = malloc(cap);
    assert_non_null(text);
    for (int round = 0; round < 4; round++) {
        size_t len = 0;
#define EMIT(...) (len += (size_t)snprintf(text + len, cap - len, __VA_ARGS__), assert_true(len < cap))
        EMIT("mid 1\ncamera { eye = [0 -8 1] look_at = [0 0 0] up = [0 0 1] resolution = [64 64] }\n");
        for (int obj = 0; obj < 3; obj++) {
            bool mirror = (obj + round) % 2 == 1;
            EMIT("polygons { transform = [scale([%g %g %g]) rotate([%g %g %g], %g) translate([%g %g %g])]\n",
                 (mirror ? -1 : 1) * uni(&r, 0.5f, 1.5f), uni(&r, 0.5f, 1.5f), uni(&r, 0.5f, 1.5f), uni(&r, -1, 1),
                 uni(&r, -1, 1), uni(&r, 0.2f, 1), uni(&r, 0, 360), uni(&r, -2, 2), uni(&r, -2, 2), uni(&r, -1, 1));
            EMIT("  geometry = { vertices = [");
            if (obj < 2) { /* closed sphere: poles + rings-1 rings */
                EMIT("[0 0 1] ");
                for (int i = 1; i < rings; i++)
                    for (int j = 0; j < segs; j++) {
                        double t = TB_PI * i / rings, p = 2 * TB_PI * j / segs;
                        EMIT("[%.9g %.9g %.9g] ", sin(t) * cos(p), sin(t) * sin(p), cos(t));
                    }
                EMIT("[0 0 -1]]\n  faces = [");
                int south = 1 + (rings - 1) * segs;
                for (int j = 0; j < segs; j++)
                    EMIT("[0 %d %d] ", 1 + j, 1 + (j + 1) % segs);
                for (int i = 1; i < rings - 1; i++)
                    for (int j = 0; j < segs; j++) {
                        int a = 1 + (i - 1) * segs + j, b = 1 + (i - 1) * segs + (j + 1) % segs;
                        EMIT("[%d %d %d %d] ", a, a + segs, b + segs, b);
                    }
                for (int j = 0; j < segs; j++)
                    EMIT("[%d %d %d] ", 1 + (rings - 2) * segs + (j + 1) % segs, 1 + (rings - 2) * segs + j, south);
                EMIT("] }\n}\n");
            } else { /* an open height field of quads */
                for (int i = 0; i <= grid; i++)
                    for (int j = 0; j <= grid; j++)
                        EMIT("[%g %g %g] ", -1 + 2.0 * i / grid, -1 + 2.0 * j / grid, 0.1 * uni(&r, -1, 1));
                EMIT("]\n  faces = [");
                for (int i = 0; i < grid; i++)
                    for (int j = 0; j < grid; j++) {
                        int a = i * (grid + 1) + j;
                        EMIT("[%d %d %d] [%d %d %d] ", a, a + grid + 1, a + grid + 2, a, a + grid + 2, a + 1);
                    }
                EMIT("] }\n}\n");
            }
        }
        EMIT("difference { transform = [translate([0.5 0.5 0])] cube {} sphere { transform = [scale(1.2)] } }\n");
        EMIT("sphere { transform = [scale(0.7) translate([-0.5 1 0.3])] }\n");
#undef EMIT
        FILE *fp = fmemopen(text, len, "r");
        assert_non_null(fp);
        tb_scene *s;
        if (tb_scene_load_stream(fp, "meshes.mid", NULL, NULL, &s))
            fail_msg("%s", tb_last_error());
        fclose(fp);
        assert_int_equal(s->nobjects, 5);
        assert_int_equal(s->stats.triangles, 2 * (uint64_t)(2 * segs + 2 * segs * (rings - 2)) + 2 * grid * grid);
        assert_int_equal(s->nprims, s->stats.triangles + 2);
        char label[64];
        snprintf(label, sizeof label, "meshes round %d", round);
        check_scene(label, s, 3000, seed + (uint64_t)round);
        tb_scene_free(s);
    }
    free(text);
}

/* A FED mesh file: a thick square plate with a square hole through it (top
 * and bottom faces with a hole loop each, 4 outer and 4 inner sides), used
 * twice under different transforms (one mirroring), between analytic objects. */
static void test_fed_file(void **state)
{
    (void)state;
    tb_vec3 pos[16];
    const float o = 1.0f, in = 0.4f, h = 0.1f;
    const float sq[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (int k = 0; k < 4; k++) {
        pos[k] = (tb_vec3){o * sq[k][0], o * sq[k][1], h};        /* outer top */
        pos[4 + k] = (tb_vec3){o * sq[k][0], o * sq[k][1], -h};   /* outer bottom */
        pos[8 + k] = (tb_vec3){in * sq[k][0], in * sq[k][1], h};  /* inner top */
        pos[12 + k] = (tb_vec3){in * sq[k][0], in * sq[k][1], -h};/* inner bottom */
    }
    uint32_t corners[128], sizes[16], nloops_of[16];
    uint32_t nc = 0, nl = 0, nf = 0;
#define LOOP(a, b, c, d) (corners[nc++] = (a), corners[nc++] = (b), corners[nc++] = (c), corners[nc++] = (d), sizes[nl++] = 4)
    LOOP(0, 1, 2, 3), LOOP(8, 11, 10, 9), nloops_of[nf++] = 2;      /* top with its hole */
    LOOP(4, 7, 6, 5), LOOP(12, 13, 14, 15), nloops_of[nf++] = 2;    /* bottom with its hole */
    for (uint32_t k = 0; k < 4; k++) {
        uint32_t k1 = (k + 1) % 4;
        LOOP(4 + k, 4 + k1, k1, k), nloops_of[nf++] = 1;            /* outer side, facing out */
        LOOP(8 + k, 8 + k1, 12 + k1, 12 + k), nloops_of[nf++] = 1;  /* inner side, facing the hole */
    }
#undef LOOP
    tb_fed_desc d = {0};
    d.nverts = 16;
    d.positions = pos;
    d.nfaces = nf;
    d.face_nloops = nloops_of;
    d.nloops = nl;
    d.loop_sizes = sizes;
    d.corners = corners;
    tb_fed *fed;
    if (tb_fed_build(&d, &fed, NULL))
        fail_msg("%s", tb_last_error());
    assert_true(tb_fed_is_closed(fed));
    char dir[PATH_MAX], path[PATH_MAX + 32];
    assert_non_null(realpath(tb_test_tmpdir(), dir));
    snprintf(path, sizeof path, "%s/scene_plate.fed", dir);
    assert_int_equal(tb_fed_write_file(path, fed, TB_FED_FORMAT_TEXT), TB_OK);
    tb_fed_free(fed);
    char text[4 * PATH_MAX];
    snprintf(text, sizeof text,
             "mid 1\ncamera { eye = [0 -6 3] look_at = [0 0 0] up = [0 0 1] resolution = [64 64] }\n"
             "sphere { transform = [scale(0.3) translate([0 0 -1])] }\n"
             "polygons { transform = [rotate([1 0 0], 20) translate([0 0 0.5])] geometry = { mesh = file(\"%s\") } }\n"
             "polygons { transform = [scale([-1.5 1 1]) rotate([0 1 1], 50) translate([0.2 0 -0.5])]\n"
             "  geometry = { mesh = file(\"%s\") } }\n"
             "cube { transform = [scale(0.2) translate([1.5 0 0])] }\n",
             path, path);
    FILE *fp = fmemopen(text, strlen(text), "r");
    assert_non_null(fp);
    tb_scene *s;
    if (tb_scene_load_stream(fp, "fed.mid", NULL, NULL, &s))
        fail_msg("%s", tb_last_error());
    fclose(fp);
    assert_int_equal(s->nobjects, 4);
    /* Each plate: top and bottom (a square ring: 8 triangles each) and 8 quads (16). */
    assert_int_equal(s->stats.triangles, 2 * (8 + 8 + 16));
    assert_int_equal(s->nprims, s->stats.triangles + 2);
    check_scene("fed plates", s, 6000, tb_test_seed("fed", 6));
    /* Straight down the hole of the first plate: through it, onto the sphere. */
    tb_ray r = tb_ray_make((tb_vec3){0, 0, 3}, (tb_vec3){0, 0, -1}, 0, INFINITY);
    tb_hit hit;
    assert_true(tb_scene_intersect(s, &r, &hit));
    assert_int_equal(hit.object, 0);
    tb_scene_free(s);
    remove(path);
}

/* Polygons with per-vertex uvs: convex faces (triangle, quad, pentagon; the
 * scene's memo with tb_poly_fan_uv), a non-convex L (param's ear-clipped
 * path; its uvs are not affine, so the fan would give other (u, v)), two
 * objects with the same corners but other uvs, under a mirroring transform
 * too, and a non-planar quad (one corner lifted): rays aimed at its diagonal
 * cross both of its triangles at one float t but different double t, where
 * the object level used to keep the triangle its BVH met last (3 of 6000 rays
 * differed in u, v and the normal). (u, v) must be tb_object_intersect's bit
 * for bit. */
static void test_uv_polygons(void **state)
{
    (void)state;
    static const char text[] =
        "mid 1\ncamera { eye = [0 -6 3] look_at = [0 0 0] up = [0 0 1] resolution = [64 64] }\n"
        "polygons { transform = [rotate([1 0 0], 20) translate([0 0 0.5])]\n"
        "  geometry = { vertices = [[-1 -1 0] [1 -1 0] [1 1 0] [-1 1 0] [0 1.6 0.1] [2 -1 0] [2.5 1 0]]\n"
        "    faces = [[0 1 2 3] [3 2 4] [1 5 6 2]]\n"
        "    uvs = [[0 0] [1 0] [1 1] [0 1] [0.5 0.9] [0.2 0.3] [0.9 0.1]] } }\n"
        "polygons { transform = [rotate([1 0 0], 20) translate([0 0 0.5])]\n"
        "  geometry = { vertices = [[-1 -1 0] [1 -1 0] [1 1 0] [-1 1 0] [0 1.6 0.1] [2 -1 0] [2.5 1 0]]\n"
        "    faces = [[0 1 2 3] [3 2 4] [1 5 6 2]]\n"
        "    uvs = [[1 1] [0.3 0] [0 0.7] [0.5 0.5] [0 0] [1 0] [0.4 0.6]] } }\n"
        "polygons { transform = [scale([-1.5 1 1]) rotate([0 1 1], 50) translate([0.2 0 -0.8])]\n"
        "  geometry = { vertices = [[0 0 0] [2 0 0] [2 1 0] [1 1 0] [1 2 0] [0 2 0] [-1 0.5 0] [-0.5 -0.5 0]]\n"
        "    faces = [[0 1 2 3 4 5] [0 5 6 7]]\n"
        "    uvs = [[0 0] [1 0] [1 0.5] [0.8 0.3] [0.5 1] [0 1] [0.2 0.2] [0.7 0.1]] } }\n"
        "polygons { transform = [rotate([0 0 1], 30) translate([-0.6 0.3 -0.2])]\n"
        "  geometry = { vertices = [[0 0 0] [1.5 0 0.1] [1.5 1.2 0.7] [0 1.2 0] [-0.8 0.6 0.3]]\n"
        "    faces = [[0 1 2 3] [0 3 4]]\n"
        "    uvs = [[0 0] [1 0] [1 1] [0 1] [0.2 0.5]] } }\n"
        "sphere { transform = [scale(0.3) translate([0 0 -1.5])] }\n";
    FILE *fp = fmemopen((void *)text, strlen(text), "r");
    assert_non_null(fp);
    tb_scene *s;
    if (tb_scene_load_stream(fp, "uv.mid", NULL, NULL, &s))
        fail_msg("%s", tb_last_error());
    fclose(fp);
    assert_int_equal(s->nobjects, 5);
    check_scene("uv polygons", s, 6000, tb_test_seed("uv polygons", 7));
    tb_scene_free(s);
}

/* tb_object_hit_point after a scene query reuses the crossing the winner's
 * tb_object_intersect found, or, for a triangle reference, the one the
 * scene noted (tb_object_note_triangle_hit): a per-thread memo
 * (intersect.c); it must give bit for bit what a fresh sweep gives. Fresh:
 * the memo is first pointed at another object by intersecting the previous
 * ray's winner again. */
static void hit_point_memo(const char *scene, uint64_t seed, long *checked_mesh)
{
    tb_scene *s;
    if (tb_scene_load(scene, NULL, &s))
        fail_msg("%s", tb_last_error());
    tb_rng r;
    tb_rng_seed(&r, tb_test_seed("hit point memo", seed), 0);
    size_t n;
    tb_ray *rays = make_rays(s, &r, (size_t)scaled(6000), &n);
    long checked = 0, differ = 0;
    const tb_object *prev = NULL;
    tb_ray prev_ray = {0};
    for (size_t i = 0; i < n; i++) {
        tb_hit h;
        if (!tb_scene_intersect(s, &rays[i], &h))
            continue;
        const tb_object *o = s->objects[h.object];
        tb_vec3 p1 = {0}, e1 = {0}, p2 = {0}, e2 = {0};
        bool ok1 = tb_object_hit_point(o, &rays[i], &h, &p1, &e1);
        if (prev && prev != o) {
            tb_hit other;
            assert_true(tb_object_intersect(prev, &prev_ray, &other));
            bool ok2 = tb_object_hit_point(o, &rays[i], &h, &p2, &e2);
            checked++;
            *checked_mesh += o->kind == TB_PRIM_POLYGONS;
            if (ok1 != ok2 || memcmp(&p1, &p2, sizeof p1) != 0 || memcmp(&e1, &e2, sizeof e1) != 0)
                differ++;
        }
        if (tb_object_intersect(o, &rays[i], &(tb_hit){0}))
            prev = o, prev_ray = rays[i];
    }
    print_message("hit point memo (%s): %ld hits checked, %ld differ\n", scene, checked, differ);
    assert_true(checked > (long)n / 10);
    assert_int_equal(differ, 0);
    free(rays);
    tb_scene_free(s);
}

static void test_hit_point_memo(void **state)
{
    (void)state;
    long mesh = 0;
    hit_point_memo(TB_SOURCE_DIR "/scenes/showcase.mid", 8, &mesh);
    hit_point_memo(TB_SOURCE_DIR "/scenes/cornell-box.mid", 9, &mesh);
    assert_true(mesh > scaled(1000)); /* hits on triangle references, whose crossing the scene noted */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cornell),
        cmocka_unit_test(test_showcase),
        cmocka_unit_test(test_meshes),
        cmocka_unit_test(test_fed_file),
        cmocka_unit_test(test_uv_polygons),
        cmocka_unit_test(test_hit_point_memo),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
