/* The acceleration structures over real scene objects (host/object): every
 * top-level MID object (primitive or CSG tree) is one reference with its
 * world box from host/object/bounds.h, intersected by tb_object_intersect.
 * BVH, grid and list must give the brute-force answer (every object tested,
 * ties by object index) bit for bit, on the bundled scenes and on random
 * scenes of every primitive kind with exact duplicates. */
#include "tb_test.h"

#include <stdio.h>
#include <string.h>

#include "host/object/bounds.h"
#include "host/object/intersect.h"
#include "host/object/object.h"
#include "host/render/accel.h"
#include "host/mid/mid_reader.h"
#include "util/math/aabb.h"
#include "util/math/rng.h"

static const tb_accel_kind kinds[] = {TB_ACCEL_BVH, TB_ACCEL_GRID, TB_ACCEL_LIST};
#define NKINDS 3

/* Work factor: 1/10 of the rays under AddressSanitizer. */
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

typedef struct objscene {
    tb_object **objs;
    tb_accel_prim *refs;
    size_t n, cap;
    tb_aabb bounds;
    tb_vec3 eye, look;
    bool has_camera;
} objscene;

/* World box of an object: the primitive's exact box, or the CSG combination
 * of its children's. */
static tb_aabb object_box(const tb_object *o)
{
    tb_aabb b = tb_aabb_empty();
    if (tb_prim_is_csg(o->kind)) {
        tb_aabb *cb = calloc((size_t)o->nchildren + 1, sizeof *cb);
        assert_non_null(cb);
        for (int i = 0; i < o->nchildren; i++)
            cb[i] = object_box(&o->children[i]);
        b = tb_bounds_csg(o->kind, cb, o->nchildren);
        free(cb);
    } else if (o->kind == TB_PRIM_POLYGONS && o->mesh) {
        assert_int_equal(tb_bounds_points(o->mesh->vertices, o->mesh->nvertices, &o->to_world, &b), TB_OK);
    } else {
        if (tb_bounds_world(o->kind, &o->geom, &o->to_world, &b) != TB_OK)
            fail_msg("bounds of object %u: %s", o->index, tb_last_error());
    }
    return b;
}

/* Reads every object of MID text `text` (or of file `path` when text is NULL). */
static void load(objscene *s, const char *path, const char *text)
{
    memset(s, 0, sizeof *s);
    s->bounds = tb_aabb_empty();
    tb_mid_reader *r;
    FILE *fp = NULL;
    if (text) {
        fp = fmemopen((void *)text, strlen(text), "r");
        assert_non_null(fp);
        assert_int_equal(tb_mid_reader_open_stream(&r, fp, "random.mid", NULL), TB_OK);
    } else if (tb_mid_reader_open(&r, path) != TB_OK) {
        fail_msg("%s", tb_last_error());
    }
    tb_mid_item it;
    tb_status st;
    while (!(st = tb_mid_reader_next(r, &it)) && it.type != TB_MID_ITEM_END) {
        if (it.type != TB_MID_ITEM_OBJECT)
            continue;
        if (s->n == s->cap) {
            s->cap = s->cap ? 2 * s->cap : 32;
            s->objs = realloc(s->objs, s->cap * sizeof *s->objs);
            s->refs = realloc(s->refs, s->cap * sizeof *s->refs);
            assert_non_null(s->objs);
            assert_non_null(s->refs);
        }
        tb_object *o;
        if (tb_object_from_mid(it.object, (uint32_t)s->n, NULL, NULL, &o) != TB_OK)
            fail_msg("object %zu: %s", s->n, tb_last_error());
        s->objs[s->n] = o;
        s->refs[s->n] = (tb_accel_prim){object_box(o), (uint32_t)s->n, 0};
        s->bounds = tb_aabb_union(s->bounds, s->refs[s->n].bounds);
        s->n++;
    }
    if (st)
        fail_msg("%s", tb_last_error());
    const tb_mid_camera *cam = tb_mid_reader_camera(r);
    if (cam) {
        s->has_camera = true;
        s->eye = (tb_vec3){(float)cam->eye.x, (float)cam->eye.y, (float)cam->eye.z};
        s->look = (tb_vec3){(float)cam->look_at.x, (float)cam->look_at.y, (float)cam->look_at.z};
    }
    tb_mid_reader_close(r);
    if (fp)
        fclose(fp);
}

static void unload(objscene *s)
{
    for (size_t i = 0; i < s->n; i++)
        tb_object_free(s->objs[i]);
    free(s->objs);
    free(s->refs);
}

static bool obj_intersect(void *ctx, const tb_accel_prim *prim, uint32_t index, const tb_ray *ray, tb_hit *hit)
{
    (void)index;
    return tb_object_intersect(((objscene *)ctx)->objs[prim->object], ray, hit);
}

static bool obj_occluded(void *ctx, const tb_accel_prim *prim, uint32_t index, const tb_ray *ray)
{
    (void)index;
    return tb_object_occluded(((objscene *)ctx)->objs[prim->object], ray);
}

/* Brute force: the closest hit of every object over the full range; ties by
 * object index (one reference per object, so that is the whole rule). */
static bool brute(const objscene *s, const tb_ray *ray, tb_hit *out)
{
    bool found = false;
    for (size_t i = 0; i < s->n; i++) {
        tb_hit h;
        if (!tb_object_intersect(s->objs[i], ray, &h))
            continue;
        if (!found || h.t < out->t || (h.t == out->t && h.object < out->object)) {
            *out = h;
            found = true;
        }
    }
    return found;
}

static float uni(tb_rng *r, float a, float b) { return a + (b - a) * tb_rng_float(r); }

static tb_vec3 random_dir(tb_rng *r)
{
    for (;;) {
        tb_vec3 v = {uni(r, -1, 1), uni(r, -1, 1), uni(r, -1, 1)};
        float l = tb_vec3_length(v);
        if (l > 0.1f && l <= 1.0f)
            return tb_vec3_scale(v, 1.0f / l);
    }
}

/* Compares every kind with brute force on `nrays` rays: camera rays towards
 * random points of the scene box, random rays from inside it, and rays aimed
 * at the objects' box centres. Returns the number of hits. */
static long compare(objscene *s, uint64_t seed, long nrays)
{
    tb_accel_callbacks cb = {obj_intersect, obj_occluded, s, NULL};
    tb_accel *acc[NKINDS];
    for (int k = 0; k < NKINDS; k++)
        if (tb_accel_build(kinds[k], s->refs, s->n, &cb, NULL, &acc[k]) != TB_OK)
            fail_msg("build: %s", tb_last_error());
    tb_rng r;
    tb_rng_seed(&r, seed, 7);
    tb_vec3 lo = s->bounds.lo, hi = s->bounds.hi;
    long hits = 0;
    for (long i = 0; i < nrays; i++) {
        tb_vec3 p = {uni(&r, lo.x, hi.x), uni(&r, lo.y, hi.y), uni(&r, lo.z, hi.z)};
        tb_ray ray;
        switch (i % 3) {
        case 0:
            if (s->has_camera) {
                ray = tb_ray_make(s->eye, tb_vec3_sub(p, s->eye), 0, INFINITY);
                break;
            }
            /* fall through */
        case 1:
            ray = tb_ray_make(p, random_dir(&r), 0, INFINITY);
            break;
        default: {
            tb_aabb b = s->refs[tb_rng_below(&r, (uint32_t)s->n)].bounds;
            tb_vec3 c = tb_aabb_centroid(&b);
            ray = tb_ray_make(p, tb_vec3_sub(c, p), 0, INFINITY);
            if (tb_vec3_length(ray.d) == 0.0f)
                ray.d = (tb_vec3){0, 0, 1};
            break;
        }
        }
        if (tb_rng_below(&r, 4) == 0)
            ray.tmax = uni(&r, 0.0f, 2.0f);
        tb_hit want, got;
        bool wf = brute(s, &ray, &want);
        hits += wf;
        for (int k = 0; k < NKINDS; k++) {
            bool f = tb_accel_intersect(acc[k], &ray, &got);
            bool o = tb_accel_occluded(acc[k], &ray);
            if (f != wf || o != wf || (f && memcmp(&got, &want, sizeof got) != 0))
                fail_msg("ray %ld (o %a %a %a d %a %a %a tmax %a): %s found %d (object %u t %a), occluded %d; "
                         "brute force %d (object %u t %a)",
                         i, (double)ray.o.x, (double)ray.o.y, (double)ray.o.z, (double)ray.d.x, (double)ray.d.y,
                         (double)ray.d.z, (double)ray.tmax, tb_accel_kind_name(kinds[k]), f, f ? got.object : 0,
                         f ? (double)got.t : 0.0, o, wf, wf ? want.object : 0, wf ? (double)want.t : 0.0);
        }
    }
    for (int k = 0; k < NKINDS; k++)
        tb_accel_free(acc[k]);
    return hits;
}

static void test_bundled_scenes(void **state)
{
    (void)state;
    const char *names[] = {"showcase.mid", "cornell-box.mid"};
    for (int i = 0; i < 2; i++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/scenes/%s", TB_SOURCE_DIR, names[i]);
        objscene s;
        load(&s, path, NULL);
        assert_true(s.n > 3);
        long n = scaled(3000);
        long hits = compare(&s, tb_test_seed(names[i], 31) + (uint64_t)i, n);
        assert_true(hits > n / 4);
        unload(&s);
    }
}

/* Appends printf-style text to a growing buffer. */
typedef struct strbuf {
    char *p;
    size_t len, cap;
} strbuf;

static void sb_printf(strbuf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void sb_printf(strbuf *b, const char *fmt, ...)
{
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        int n = vsnprintf(b->p ? b->p + b->len : NULL, b->p ? b->cap - b->len : 0, fmt, ap);
        va_end(ap);
        assert_true(n >= 0);
        if (b->p && b->len + (size_t)n < b->cap) {
            b->len += (size_t)n;
            return;
        }
        b->cap = (b->cap + (size_t)n + 1) * 2;
        b->p = realloc(b->p, b->cap);
        assert_non_null(b->p);
    }
}

/* A random MID scene: primitives of every closed kind and CSG differences
 * under random scale, rotation and translation, some written twice (exact
 * duplicates: equal hits, the lower object index must win). */
static char *random_mid(tb_rng *r, int n)
{
    static const char *const shapes[] = {
        "sphere {", "cube {", "cylinder {", "cone {", "pyramid {",
        "torus { geometry = { major = 1 minor = 0.35 }",
        "prism { geometry = { sides = 6 }",
        "conic { geometry = { coefficients = [1 0 -1] z_range = [-1 1] }",
        "difference { cube {} sphere { transform = [scale(1.3)] }",
        "union { sphere {} cube { transform = [translate([1 0 0])] }",
    };
    const int nshapes = (int)(sizeof shapes / sizeof shapes[0]);
    strbuf b = {0};
    sb_printf(&b, "mid 1\n");
    char last[512] = "";
    for (int i = 0; i < n; i++) {
        if (i > 0 && tb_rng_below(r, 8) == 0) {
            sb_printf(&b, "%s", last); /* an exact duplicate of the previous object */
            continue;
        }
        float s = 0.05f * powf(8.0f, tb_rng_float(r));
        snprintf(last, sizeof last,
                 "%s transform = [scale([%.6g %.6g %.6g]) rotate([%.4g %.4g %.4g] %.5g) translate([%.6g %.6g %.6g])] }\n",
                 shapes[tb_rng_below(r, (uint32_t)nshapes)], s * uni(r, 0.5f, 2), s * uni(r, 0.5f, 2),
                 s * uni(r, 0.5f, 2), uni(r, 0.1f, 1), uni(r, -1, 1), uni(r, -1, 1), uni(r, 0, 360),
                 uni(r, -3, 3), uni(r, -3, 3), uni(r, -3, 3));
        sb_printf(&b, "%s", last);
    }
    return b.p;
}

static void test_random_objects(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("random_objects", 32);
    tb_rng r;
    tb_rng_seed(&r, seed, 8);
    for (int round = 0; round < 2; round++) {
        char *text = random_mid(&r, round == 0 ? 60 : 400);
        objscene s;
        load(&s, NULL, text);
        long n = scaled(2500);
        long hits = compare(&s, seed + 100 + (uint64_t)round, n);
        assert_true(hits > n / 5);
        unload(&s);
        free(text);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bundled_scenes),
        cmocka_unit_test(test_random_objects),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
