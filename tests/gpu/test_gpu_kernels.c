/* Paired kernel tests (after Falcor's AABBTests.cpp + AABBTests.cs.slang):
 * a tiny kernel per GLSL routine of shaders/lib writes its results to a
 * buffer and the host compares them with the C function they mirror, first
 * on exactly representable inputs, then on seeded random inputs with the
 * tolerances docs/gpu.md states (and derives from Vulkan's precision rules).
 * Also: the C/GLSL layouts of shaders/shared agree field by field, and
 * `precise` really stops the compiler from fusing a*b+c. The instance runs
 * with the validation layer and every test fails on any message. Pipelines
 * are created once, in the group setup (lavapipe compiles them just in time). */
#include "gpu_test.h"

#include <float.h>

#include "host/object/hit.h"
#include "host/object/intersect.h"
#include "host/object/object.h"
#include "host/mid/mid.h"
#include "kernels/cases.h"
#include "shared/hit.h"
#include "shared/ray.h"
#include "util/color/srgb.h"
#include "util/math/aabb.h"
#include "util/math/float.h"
#include "util/roots/roots.h"

#define U 0x1p-24 /* unit roundoff of float */

/* The GPU hit record is the CPU's (host/object/hit.h), byte for byte, so hit
 * buffers and HITS files are interchangeable. */
_Static_assert(sizeof(tb_gpu_hit) == sizeof(tb_hit) && offsetof(tb_gpu_hit, object) == offsetof(tb_hit, object) &&
                   offsetof(tb_gpu_hit, face) == offsetof(tb_hit, face) &&
                   offsetof(tb_gpu_hit, u) == offsetof(tb_hit, u) && offsetof(tb_gpu_hit, v) == offsetof(tb_hit, v) &&
                   offsetof(tb_gpu_hit, ng) == offsetof(tb_hit, ng),
               "tb_gpu_hit has the layout of host/object's tb_hit");

static tb_gpu_instance *g_inst;
static tb_gpu_device *g_dev;
static tb_gpu_kernel *k_aabb, *k_sphere, *k_quadratic, *k_contract, *k_layout, *k_color[4];
static bool g_fma_fused; /* measured by test_contraction, which runs first */
/* host/object's unit sphere (identity transform): the CPU path's own
 * intersection, in double, that lib/sphere.glsl is checked against. */
static tb_object *g_unit_sphere;

static tb_gpu_kernel *make(const char *name, int buffers, int op)
{
    tb_gpu_spec_constant spec = {1, (uint32_t)op};
    tb_gpu_kernel *k = tb_gpu_kernel_get(g_dev, &(tb_gpu_kernel_desc){.spirv = gpu_test_kernel(name),
                                                                      .buffers = buffers,
                                                                      .push_size = 4,
                                                                      .spec = op >= 0 ? &spec : NULL,
                                                                      .spec_count = op >= 0 ? 1 : 0});
    if (!k)
        fail_msg("kernel %s: %s", name, tb_last_error());
    return k;
}

static int setup(void **state)
{
    (void)state;
    g_inst = gpu_test_instance();
    int index;
    if (tb_gpu_pick_device(tb_gpu_device_info_at(g_inst, 0), tb_gpu_device_count(g_inst), TB_GPU_MODE_VULKAN, -1,
                           &index, NULL, 0) ||
        !(g_dev = tb_gpu_device_create(g_inst, index, NULL))) {
        print_error("no Vulkan device: %s\n", tb_last_error());
        return -1;
    }
    print_message("[ device   ] %s\n", tb_gpu_device_info_of(g_dev)->name);
    tb_mid_object m;
    memset(&m, 0, sizeof m);
    m.kind = TB_PRIM_SPHERE;
    m.geom = tb_mid_geometry_default(TB_PRIM_SPHERE);
    m.to_world = tb_transform_identity();
    m.material = tb_mid_material_default();
    if (tb_object_from_mid(&m, 0, NULL, NULL, &g_unit_sphere)) {
        print_error("unit sphere: %s\n", tb_last_error());
        return -1;
    }
    k_aabb = make("k_aabb", 2, -1);
    k_sphere = make("k_sphere", 2, -1);
    k_quadratic = make("k_quadratic", 2, -1);
    k_contract = make("k_contract", 2, -1);
    k_layout = make("k_layout", 3, -1);
    for (int op = 0; op < 4; op++)
        k_color[op] = make("k_color", 2, op); /* one pipeline per specialization */
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    tb_object_free(g_unit_sphere);
    tb_gpu_device_destroy(g_dev);
    int dirty = tb_gpu_validation_errors(g_inst) + tb_gpu_validation_warnings(g_inst);
    tb_gpu_instance_destroy(g_inst);
    return dirty ? -1 : 0;
}

/* Runs kernel k over n records: in (n * in_size bytes) -> out (n * out_size). */
static void run(tb_gpu_kernel *k, const void *in, size_t in_size, void *out, size_t out_size, uint32_t n)
{
    tb_gpu_buffer *bi = tb_gpu_buffer_create(g_dev, (size_t)n * in_size);
    tb_gpu_buffer *bo = tb_gpu_buffer_create(g_dev, (size_t)n * out_size);
    if (!bi || !bo)
        fail_msg("buffers: %s", tb_last_error());
    uint32_t push = n;
    tb_gpu_dispatch d = {.kernel = k, .buffers = {bi, bo}, .push = &push, .items = n};
    if (tb_gpu_buffer_upload(bi, 0, in, (size_t)n * in_size) || tb_gpu_run(g_dev, &d, 1) ||
        tb_gpu_buffer_download(bo, 0, out, (size_t)n * out_size))
        fail_msg("kernel %s: %s", tb_gpu_kernel_name(k), tb_last_error());
    tb_gpu_buffer_destroy(bi);
    tb_gpu_buffer_destroy(bo);
    gpu_assert_clean(g_inst);
}

static uint32_t ulps(float a, float b) { return tb_ulp_distance(a, b); }

static float rnd(tb_rng *r, float lo, float hi) { return lo + (hi - lo) * tb_rng_float(r); }

/* ---------------------------------------------------------------- layouts */

static void test_layout_roundtrip(void **state)
{
    (void)state;
    enum { N = 37 };
    tb_ray rays[N];
    for (int i = 0; i < N; i++) {
        float b = (float)(i * 8);
        rays[i] = tb_ray_make((tb_vec3){b + 1, b + 2, b + 3}, (tb_vec3){b + 5, b + 6, b + 7}, b + 4, b + 8);
    }
    rays[3].tmax = INFINITY;
    tb_gpu_buffer *bin = tb_gpu_buffer_create(g_dev, sizeof rays);
    tb_gpu_buffer *bhits = tb_gpu_buffer_create(g_dev, 2 * N * sizeof(tb_gpu_hit));
    tb_gpu_buffer *bout = tb_gpu_buffer_create(g_dev, N * sizeof(tb_gpu_ray));
    assert_true(bin && bhits && bout);
    uint32_t n = N;
    tb_gpu_dispatch d = {.kernel = k_layout, .buffers = {bin, bhits, bout}, .push = &n, .items = N};
    assert_int_equal(tb_gpu_buffer_upload(bin, 0, rays, sizeof rays), TB_OK); /* tb_ray uploaded as is */
    assert_int_equal(tb_gpu_run(g_dev, &d, 1), TB_OK);
    tb_gpu_hit hits[2 * N];
    tb_ray back[N];
    assert_int_equal(tb_gpu_buffer_download(bhits, 0, hits, sizeof hits), TB_OK);
    assert_int_equal(tb_gpu_buffer_download(bout, 0, back, sizeof back), TB_OK);
    for (int i = 0; i < N; i++) {
        const tb_ray *r = &rays[i];
        const tb_gpu_hit *h = &hits[2 * i], *m = &hits[2 * i + 1];
        assert_true(h->t == r->o.x && h->u == r->o.y && h->v == r->o.z);
        assert_true(h->object == (uint32_t)i && h->face == ~(uint32_t)i);
        assert_true(h->ng[0] == r->tmin && h->ng[1] == r->d.x && h->ng[2] == r->d.y);
        assert_true(m->t == r->d.z && m->object == TB_GPU_NO_HIT && m->face == 7u && m->u == r->tmax);
        assert_true(m->v == 0.0f && m->ng[0] == 0.0f && m->ng[1] == 0.0f && m->ng[2] == 0.0f);
        const tb_ray *b = &back[i];
        assert_true(b->o.x == r->d.x && b->o.y == r->d.y && b->o.z == r->d.z && b->tmin == r->tmax);
        assert_true(b->d.x == r->o.x && b->d.y == r->o.y && b->d.z == r->o.z && b->tmax == r->tmin);
    }
    tb_gpu_buffer_destroy(bin);
    tb_gpu_buffer_destroy(bhits);
    tb_gpu_buffer_destroy(bout);
    gpu_assert_clean(g_inst);
}

/* ---------------------------------------------------------------- contraction */

/* x*y + z where the exact product 1 + (i+j)2^-12 + ij 2^-24 (ij = 1 mod 4)
 * lies halfway between two floats and rounds (to nearest even, or toward
 * zero: the same float T here) down by 2^-24; with z = -T the unfused result
 * is exactly 0 and the fused one 2^-24 (all scaled by 2^e, sign s). */
static void test_contraction(void **state)
{
    (void)state;
    enum { N = 64 };
    tb_case_f4 in[N], out[N];
    float fused_want[N];
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("contraction", 11), 0);
    for (int k = 0; k < N; k++) {
        int i, j;
        do {
            i = 2 * (int)tb_rng_below(&rng, 200) + 1;
            j = 2 * (int)tb_rng_below(&rng, 200) + 1;
        } while ((i * j) % 4 != 1);
        int e = (int)tb_rng_below(&rng, 41) - 20;
        float s = tb_rng_below(&rng, 2) ? -1.0f : 1.0f;
        double x = 1.0 + i * 0x1p-12, y = 1.0 + j * 0x1p-12;
        double t = x * y - 0x1p-24; /* exact in double: T */
        in[k] = (tb_case_f4){(float)ldexp(s * x, e), (float)y, (float)ldexp(-s * t, e), 0.0f};
        fused_want[k] = (float)ldexp(s * 0x1p-24, e);
        /* the C reference (-ffp-contract=off) is the unfused value */
        assert_true(in[k].x * in[k].y + in[k].z == 0.0f);
        assert_true(fmaf(in[k].x, in[k].y, in[k].z) == fused_want[k]);
    }
    run(k_contract, in, sizeof in[0], out, sizeof out[0], N);
    int plain_fused = 0, fma_fused = 0;
    for (int k = 0; k < N; k++) {
        if (out[k].x != 0.0f)
            fail_msg("case %d: precise x*y+z = %a, want 0 (the product was fused)", k, out[k].x);
        if (!(out[k].y == 0.0f || out[k].y == fused_want[k]))
            fail_msg("case %d: x*y+z = %a is neither the fused nor the unfused value", k, out[k].y);
        if (!(out[k].z == 0.0f || out[k].z == fused_want[k]))
            fail_msg("case %d: fma = %a is neither the fused nor the unfused value", k, out[k].z);
        plain_fused += out[k].y != 0.0f;
        fma_fused += out[k].z != 0.0f;
    }
    /* A device either fuses fma() or not; a mix would be a driver bug. */
    assert_true(fma_fused == 0 || fma_fused == N);
    g_fma_fused = fma_fused == N;
    print_message("[ info     ] precise: unfused in %d/%d; plain a*b+c fused in %d/%d; fma() fused: %s\n", N, N,
                  plain_fused, N, g_fma_fused ? "yes" : "no");
}

/* ---------------------------------------------------------------- ray/box */

/* The exact slab interval in double (inputs are floats, so plane - o is
 * exact in double and each t has one double rounding): [*t0, *t1], which
 * may be empty (t0 > t1). False for an empty box or a ray parallel to a slab
 * and outside it: misses that involve no rounding at all. */
static bool slab_interval(const tb_case_box *c, double *t0, double *t1)
{
    float o[3] = {c->ray.o.x, c->ray.o.y, c->ray.o.z}, d[3] = {c->ray.d.x, c->ray.d.y, c->ray.d.z};
    float lo[3] = {c->lo.x, c->lo.y, c->lo.z}, hi[3] = {c->hi.x, c->hi.y, c->hi.z};
    if (!(lo[0] <= hi[0] && lo[1] <= hi[1] && lo[2] <= hi[2]))
        return false;
    double a = c->ray.tmin, z = c->ray.tmax;
    for (int k = 0; k < 3; k++) {
        if (d[k] == 0.0f) {
            if (o[k] < lo[k] || o[k] > hi[k])
                return false;
            continue;
        }
        double tn = ((double)lo[k] - o[k]) / d[k], tf = ((double)hi[k] - o[k]) / d[k];
        a = fmax(a, fmin(tn, tf));
        z = fmin(z, fmax(tn, tf));
    }
    *t0 = a;
    *t1 = z;
    return true;
}

/* True if the exact ray meets the box (then [*t0, *t1] is where). */
static bool slab_ref(const tb_case_box *c, double *t0, double *t1)
{
    return slab_interval(c, t0, t1) && *t0 <= *t1;
}

/* GPU and C disagree only where the GPU's wider widening (18u instead of 6u)
 * turns a near miss into a hit: a gap below 40u relative to |t|. */
static bool near_miss(const tb_case_box *c)
{
    double a, z;
    if (!slab_interval(c, &a, &z))
        return false; /* exact on both sides */
    return a > z && a - z <= 40 * U * fmax(fabs(a), fabs(z));
}

static void c_slab(const tb_case_box *c, tb_case_box_out *o)
{
    tb_aabb b = {c->lo, c->hi};
    tb_ray r;
    memcpy(&r, &c->ray, sizeof r); /* same layout (shared/ray.h asserts it) */
    float t0 = 0.0f, t1 = 0.0f;
    o->hit = tb_aabb_intersect_ray(&b, &r, &t0, &t1);
    o->t0 = o->hit ? t0 : 0.0f;
    o->t1 = o->hit ? t1 : 0.0f;
}

/* Checks one case; returns 1 for an allowed near-miss disagreement. */
static int check_box(const tb_case_box *c, const tb_case_box_out *g, int i, bool exact_inputs)
{
    tb_case_box_out cc;
    c_slab(c, &cc);
    double r0, r1;
    bool ref = slab_ref(c, &r0, &r1);
    if (ref && !g->hit)
        fail_msg("case %d: the GPU misses a box the exact ray meets in [%.9g, %.9g]", i, r0, r1);
    if (g->hit != cc.hit) {
        if (exact_inputs || !near_miss(c))
            fail_msg("case %d: GPU %s, C %s (o %a %a %a d %a %a %a t [%a, %a])", i, g->hit ? "hit" : "miss",
                     cc.hit ? "hit" : "miss", c->ray.o.x, c->ray.o.y, c->ray.o.z, c->ray.d.x, c->ray.d.y,
                     c->ray.d.z, c->ray.tmin, c->ray.tmax);
        return 1;
    }
    if (!g->hit)
        return 0;
    if (ref && !(g->t0 <= r0 && g->t1 >= r1))
        fail_msg("case %d: GPU [%.9g, %.9g] does not contain the exact [%.9g, %.9g]", i, g->t0, g->t1, r0, r1);
    float gt[2] = {g->t0, g->t1}, ct[2] = {cc.t0, cc.t1};
    for (int k = 0; k < 2; k++) {
        double tol = 40 * U * fmax(fabs(gt[k]), fabs(ct[k]));
        if (!(fabs((double)gt[k] - ct[k]) <= tol) && !(isinf(gt[k]) && gt[k] == ct[k]))
            fail_msg("case %d: t%d GPU %.9g, C %.9g: more than 40u apart", i, k, gt[k], ct[k]);
    }
    return 0;
}

static void test_aabb_exact(void **state)
{
    (void)state;
    /* Boxes, origins at fractions -1, 0, 1/2, 1, 2 of each axis (on, inside,
     * outside the slabs), directions from {-3, -1, -0, +0, 1/2} per axis,
     * two ranges: every input exactly representable. */
    const float boxes[][6] = {
        {0, 0, 0, 1, 1, 1},          {-1, 0, -3, 2, 1, -1}, {0, 0, 0, 0, 1, 1}, /* flat */
        {1, 1, 1, 1, 1, 1},          /* a point */
        {-1e30f, -1e30f, -1e30f, 1e30f, 1e30f, 1e30f}, {0, 0, 0, 0x1p-20f, 0x1p-20f, 0x1p-20f},
        {1, 0, 0, 0, 1, 1},          /* empty: lo.x > hi.x */
    };
    const float frac[5] = {-1.0f, 0.0f, 0.5f, 1.0f, 2.0f};
    const float dirs[5] = {-3.0f, -1.0f, -0.0f, 0.0f, 0.5f};
    const float ranges[2][2] = {{0.0f, INFINITY}, {-0.25f, 0.75f}};
    size_t nb = sizeof boxes / sizeof boxes[0], cap = nb * 125 * 125 * 2;
    tb_case_box *in = calloc(cap, sizeof *in);
    tb_case_box_out *out = calloc(cap, sizeof *out);
    assert_true(in && out);
    uint32_t n = 0;
    for (size_t b = 0; b < nb; b++)
        for (int oi = 0; oi < 125; oi++)
            for (int di = 0; di < 125; di++)
                for (int ri = 0; ri < 2; ri++) {
                    const float *bx = boxes[b];
                    float d[3] = {dirs[di % 5], dirs[di / 5 % 5], dirs[di / 25]};
                    if (d[0] == 0.0f && d[1] == 0.0f && d[2] == 0.0f)
                        continue; /* not a ray */
                    float f[3] = {frac[oi % 5], frac[oi / 5 % 5], frac[oi / 25]};
                    float o[3];
                    for (int k = 0; k < 3; k++) {
                        float lo = bx[k], hi = bx[k + 3];
                        /* lo + f (hi - lo), exact for these boxes (huge one: f * 1e30 stays exact) */
                        o[k] = lo + f[k] * (hi - lo);
                        if (hi - lo > 1e29f)
                            o[k] = f[k] == 0.5f ? 0.0f : f[k] * 1e30f;
                    }
                    tb_case_box *c = &in[n++];
                    c->ray = (tb_gpu_ray){{o[0], o[1], o[2]}, ranges[ri][0], {d[0], d[1], d[2]}, ranges[ri][1]};
                    c->lo = (tb_vec3){bx[0], bx[1], bx[2]};
                    c->hi = (tb_vec3){bx[3], bx[4], bx[5]};
                }
    run(k_aabb, in, sizeof *in, out, sizeof *out, n);
    int hits = 0;
    for (uint32_t i = 0; i < n; i++) {
        check_box(&in[i], &out[i], (int)i, true);
        hits += (int)out[i].hit;
    }
    print_message("[ info     ] %u exactly representable ray/box cases, %d hits: same hit/miss as C\n", n, hits);
    assert_true(hits > 1000 && hits < (int)n - 1000); /* both outcomes well represented */
    free(in);
    free(out);
}

static void test_aabb_random(void **state)
{
    (void)state;
    enum { N = 20000 };
    tb_case_box *in = calloc(N, sizeof *in);
    tb_case_box_out *out = calloc(N, sizeof *out);
    assert_true(in && out);
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("aabb_random", 1234), 0);
    for (int i = 0; i < N; i++) {
        float lo[3], hi[3], o[3], t[3], d[3];
        for (int k = 0; k < 3; k++) {
            float a = rnd(&rng, -10, 10), b = rnd(&rng, -10, 10);
            lo[k] = fminf(a, b);
            hi[k] = fmaxf(a, b);
            o[k] = rnd(&rng, -20, 20);
        }
        /* aim at a corner, an edge or a face point, slightly jittered */
        uint32_t kind = tb_rng_below(&rng, 3);
        for (int k = 0; k < 3; k++) {
            bool snap = kind == 0 || (kind == 1 && k != 0);
            t[k] = snap ? (tb_rng_below(&rng, 2) ? hi[k] : lo[k]) : rnd(&rng, lo[k], hi[k]);
            t[k] += rnd(&rng, -1e-5f, 1e-5f) * (1.0f + fabsf(t[k]));
            if (tb_rng_below(&rng, 20) == 0)
                o[k] = tb_rng_below(&rng, 2) ? lo[k] : hi[k]; /* origin on a slab plane */
            d[k] = t[k] - o[k];
            if (tb_rng_below(&rng, 10) == 0)
                d[k] = tb_rng_below(&rng, 2) ? -0.0f : 0.0f; /* parallel to a slab */
        }
        if (d[0] == 0.0f && d[1] == 0.0f && d[2] == 0.0f)
            d[2] = 1.0f;
        float tmin = tb_rng_below(&rng, 2) ? 0.0f : -rnd(&rng, 0, 2);
        float tmax = tb_rng_below(&rng, 2) ? INFINITY : rnd(&rng, 0.5f, 2.0f);
        in[i].ray = (tb_gpu_ray){{o[0], o[1], o[2]}, tmin, {d[0], d[1], d[2]}, tmax};
        in[i].lo = (tb_vec3){lo[0], lo[1], lo[2]};
        in[i].hi = (tb_vec3){hi[0], hi[1], hi[2]};
    }
    run(k_aabb, in, sizeof *in, out, sizeof *out, N);
    int differ = 0, hits = 0;
    for (int i = 0; i < N; i++) {
        differ += check_box(&in[i], &out[i], i, false);
        hits += (int)out[i].hit;
    }
    print_message("[ info     ] %d random ray/box cases, %d hits, %d near misses hit only on the GPU\n", N, hits,
                  differ);
    free(in);
    free(out);
}

/* ---------------------------------------------------------------- quadratic */

/* Allowed ulp distance between GPU and C roots: 16 with a fused fma();
 * without one the GPU discriminant is b*b - 4ac with two roundings, whose
 * relative error (b^2 + |4ac|) u / |D| the root inherits halved, plus 16. */
static double root_tol(float a, float b, float c)
{
    double disc = (double)b * b - 4.0 * a * c;
    if (g_fma_fused || disc == 0.0)
        return 16.0;
    return 16.0 + 2.0 * ((double)b * b + fabs(4.0 * a * c)) / fabs(disc);
}

static void check_quadratic(const tb_case_f4 *in, const tb_case_f4 *g, int i, bool exact)
{
    float r[2] = {0, 0};
    int n = tb_quadraticf(in->x, in->y, in->z, r);
    if ((int)g->x != n)
        fail_msg("case %d (%a, %a, %a): GPU %d roots, C %d", i, in->x, in->y, in->z, (int)g->x, n);
    double tol = exact ? 16.0 : root_tol(in->x, in->y, in->z);
    float gr[2] = {g->y, g->z};
    for (int k = 0; k < n; k++)
        if (ulps(gr[k], r[k]) > tol)
            fail_msg("case %d (%a, %a, %a): root %d GPU %.9g, C %.9g: %u ulps > %.0f", i, in->x, in->y, in->z, k,
                     gr[k], r[k], ulps(gr[k], r[k]), tol);
}

static void test_quadratic_exact(void **state)
{
    (void)state;
    tb_case_f4 in[600], out[600];
    int n = 0;
    /* (x - p)(x - q) with small dyadic roots: coefficients and discriminant
     * exact, so the root count must agree exactly */
    for (int p = -6; p <= 6; p++)
        for (int q = p; q <= 6; q++) {
            float s = (float)(p + q) * 0.5f, t = (float)(p * q) * 0.25f; /* roots p/2, q/2 */
            in[n++] = (tb_case_f4){1.0f, -s, t, 0};
            in[n++] = (tb_case_f4){-4.0f, 4.0f * s, -4.0f * t, 0}; /* scaled by -4 */
            in[n++] = (tb_case_f4){1.0f, -s, t + 1.0f, 0};          /* pushed up: fewer roots */
        }
    const tb_case_f4 special[] = {
        {0, 2, -3, 0},          /* linear: 1.5 */
        {0, 0, 1, 0},           /* no equation */
        {0, 0, 0, 0},           /* 0 = 0 */
        {1, 0, 0, 0},           /* double root at 0 (c == 0 path) */
        {2, -6, 0, 0},          /* roots 0, 3 */
        {1, 2, 1, 0},           /* double root -1 */
        {1, 0, 1, 0},           /* none */
        {1, 0, -4, 0},          /* +-2, b == 0 */
        {1, -0.0f, -4, 0},      /* b == -0 */
        {1e30f, -3e30f, 2e30f, 0}, /* roots 1, 2 through the range scaling */
        {1e-30f, -3e-30f, 2e-30f, 0},
        {0x1p-70f, -0x1p-69f, 0x1p-72f, 0}, /* tiny a: x = 2^k y balancing */
        {INFINITY, 1, 1, 0},     /* non-finite coefficient: no roots */
        {1, -INFINITY, 1, 0},
        {1, 1, NAN, 0},
    };
    for (size_t i = 0; i < sizeof special / sizeof special[0]; i++)
        in[n++] = special[i];
    assert_true(n <= 600);
    run(k_quadratic, in, sizeof in[0], out, sizeof out[0], (uint32_t)n);
    int exact_roots = 0, roots = 0;
    for (int i = 0; i < n; i++) {
        check_quadratic(&in[i], &out[i], i, true);
        float r[2];
        int m = tb_quadraticf(in[i].x, in[i].y, in[i].z, r);
        exact_roots += (m > 0 && out[i].y == r[0]) + (m > 1 && out[i].z == r[1]);
        roots += m;
    }
    print_message("[ info     ] %d exactly representable quadratics: root counts equal; %d of %d roots bit-equal\n",
                  n, exact_roots, roots);
}

static void test_quadratic_random(void **state)
{
    (void)state;
    enum { N = 20000 };
    tb_case_f4 *in = calloc(N, sizeof *in), *out = calloc(N, sizeof *out);
    assert_true(in && out);
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("quadratic_random", 77), 0);
    for (int i = 0; i < N; i++) {
        /* well-separated roots of float coefficients (both sides solve the same floats) */
        float p = rnd(&rng, -100, 100), q;
        do
            q = rnd(&rng, -100, 100);
        while (fabsf(p - q) < 0.05f * fmaxf(fabsf(p), fabsf(q)));
        float a = rnd(&rng, 0.5f, 2.0f) * (tb_rng_below(&rng, 2) ? 1.0f : -1.0f);
        in[i] = (tb_case_f4){a, -a * (p + q), a * p * q, 0};
    }
    run(k_quadratic, in, sizeof *in, out, sizeof *out, N);
    uint32_t worst = 0;
    for (int i = 0; i < N; i++) {
        check_quadratic(&in[i], &out[i], i, false);
        float r[2];
        int m = tb_quadraticf(in[i].x, in[i].y, in[i].z, r);
        for (int k = 0; k < m; k++) {
            uint32_t e = ulps(k ? out[i].z : out[i].y, r[k]);
            worst = e > worst ? e : worst;
        }
    }
    print_message("[ info     ] %d random quadratics: worst root %u ulps from C (fma fused: %s)\n", N, worst,
                  g_fma_fused ? "yes" : "no");
    free(in);
    free(out);
}

/* ---------------------------------------------------------------- sphere */

/* The float C twin of lib/sphere.glsl (same steps, tb_vec3_dot and
 * tb_quadraticf); *scale gets |t0| + |s|, the size the error of t is relative to. */
static bool c_sphere(const tb_case_sphere *c, float *t, double *scale)
{
    tb_vec3 o = c->ray.o, d = c->ray.d;
    float dd = tb_vec3_dot(d, d), t0 = -tb_vec3_dot(o, d) / dd;
    tb_vec3 p0 = {o.x + t0 * d.x, o.y + t0 * d.y, o.z + t0 * d.z};
    float s[2];
    int n = tb_quadraticf(dd, 2.0f * tb_vec3_dot(p0, d), tb_vec3_dot(p0, p0) - c->radius * c->radius, s);
    *scale = fabs(t0);
    if (n == 1)
        s[1] = s[0];
    for (int k = 0; k < 2 && n > 0; k++) {
        float tk = t0 + s[k];
        if (tk >= c->ray.tmin && tk <= c->ray.tmax) {
            *t = tk;
            *scale = fabs(t0) + fabs(s[k]);
            return true;
        }
    }
    return false;
}

static bool cpu_sphere(const tb_case_sphere *c, float *t)
{
    tb_ray r;
    memcpy(&r, &c->ray, sizeof r);
    tb_hit h;
    if (!tb_object_intersect(g_unit_sphere, &r, &h))
        return false;
    *t = h.t;
    return true;
}

/* A grazing ray: the line passes the centre at a distance within 2^-10 of the
 * radius (the two roots nearly merge, and rounding may decide hit or miss). */
static bool grazing(const tb_case_sphere *c)
{
    tb_dvec3 o = {c->ray.o.x, c->ray.o.y, c->ray.o.z}, d = {c->ray.d.x, c->ray.d.y, c->ray.d.z};
    double t0 = -tb_dvec3_dot(o, d) / tb_dvec3_dot(d, d);
    tb_dvec3 p = {o.x + t0 * d.x, o.y + t0 * d.y, o.z + t0 * d.z};
    return fabs(sqrt(tb_dvec3_dot(p, p)) - c->radius) <= 0x1p-10 * c->radius;
}

/* GPU against the float twin: same decision, t within 32u (|t0| + |s|)
 * (division 2.5 ulp, sqrt ~3.5 ulp on a Vulkan device; p0.d ~ 0 keeps the
 * discriminant free of cancellation, fused fma or not). Against host/object
 * (double): same decision unless grazing, t within 2^-16 (|t0| + |s|) + 2^-16
 * (the float formulation's own error). Returns 1 for a grazing disagreement. */
static int check_sphere(const tb_case_sphere *c, const tb_case_box_out *g, int i, bool exact)
{
    float t = 0.0f;
    double scale;
    bool hit = c_sphere(c, &t, &scale);
    bool graze = !exact && grazing(c);
    if ((bool)g->hit != hit && !graze)
        fail_msg("case %d: GPU %s, C twin %s (o %a %a %a d %a %a %a r %a)", i, g->hit ? "hit" : "miss",
                 hit ? "hit" : "miss", c->ray.o.x, c->ray.o.y, c->ray.o.z, c->ray.d.x, c->ray.d.y, c->ray.d.z,
                 c->radius);
    if (g->hit && hit && !(fabs((double)g->t0 - t) <= 32 * U * scale))
        fail_msg("case %d: t GPU %.9g, C twin %.9g: more than 32u * %.3g apart", i, g->t0, t, scale);
    if (c->radius == 1.0f) {
        float tc = 0.0f;
        bool hc = cpu_sphere(c, &tc);
        if ((bool)g->hit != hc && !graze)
            fail_msg("case %d: GPU %s, host/object %s", i, g->hit ? "hit" : "miss", hc ? "hit" : "miss");
        if (g->hit && hc && !(fabs((double)g->t0 - tc) <= 0x1p-16 * (scale + 1.0)))
            fail_msg("case %d: t GPU %.9g, host/object %.9g", i, g->t0, tc);
    }
    return (bool)g->hit != hit;
}

static void test_sphere_exact(void **state)
{
    (void)state;
    const tb_case_sphere cases[] = {
        {{{-3, 0, 0}, 0, {1, 0, 0}, INFINITY}, 1, 0, 0, 0},    /* t = 2 */
        {{{0, -3, 0}, 0, {0, 2, 0}, INFINITY}, 1, 0, 0, 0},    /* t = 1 */
        {{{0, 0, 5}, 0, {0, 0, -1}, INFINITY}, 2, 0, 0, 0},    /* t = 3 */
        {{{0, 0, 0}, 0, {1, 0, 0}, INFINITY}, 1, 0, 0, 0},     /* inside: t = 1 */
        {{{0, 0, 0}, -5, {1, 0, 0}, INFINITY}, 1, 0, 0, 0},    /* tmin < 0: t = -1 */
        {{{-3, 1, 0}, 0, {1, 0, 0}, INFINITY}, 1, 0, 0, 0},    /* tangent: double root 3 */
        {{{-3, 1.5f, 0}, 0, {1, 0, 0}, INFINITY}, 1, 0, 0, 0}, /* miss */
        {{{1, 0, 0}, 0, {1, 0, 0}, INFINITY}, 1, 0, 0, 0},     /* on the surface, leaving: t = 0 */
        {{{1, 0, 0}, 0, {-1, 0, 0}, INFINITY}, 1, 0, 0, 0},    /* on the surface, entering: t = 0 */
        {{{-3, 0, 0}, 0, {1, 0, 0}, 1.5f}, 1, 0, 0, 0},        /* tmax before the sphere: miss */
        {{{-3, 0, 0}, 3, {1, 0, 0}, INFINITY}, 1, 0, 0, 0},    /* tmin inside: exit at 4 */
        {{{3, 0, 0}, 0, {1, 0, 0}, INFINITY}, 1, 0, 0, 0},     /* behind: miss */
        {{{-2, -2, -1}, 0, {2, 2, 1}, INFINITY}, 1, 0, 0, 0},  /* |p| = 3|t - 1|: t = 2/3 */
        {{{-96, 0, 0}, 0, {32, 0, 0}, INFINITY}, 0.5f, 0, 0, 0},
        {{{0, 0, -1e4f}, 0, {0, 0, 1}, INFINITY}, 1, 0, 0, 0}, /* far: |o|^2 - 1 would round to 10^8 */
        {{{0, 0.6f, -1e6f}, 0, {0, 0, 1}, INFINITY}, 1, 0, 0, 0}, /* farther, off axis: t = 10^6 - 0.8 */
    };
    const float want[] = {2, 1, 3, 1, -1, 3, NAN, 0, 0, NAN, 4, NAN, 2.0f / 3.0f, 2.984375f, 9999, 999999.2f};
    enum { N = sizeof cases / sizeof cases[0] };
    tb_case_box_out out[N];
    run(k_sphere, cases, sizeof cases[0], out, sizeof out[0], N);
    for (int i = 0; i < N; i++) {
        check_sphere(&cases[i], &out[i], i, true);
        /* and against the analytic answer */
        if (isnan(want[i]))
            assert_int_equal(out[i].hit, 0);
        else if (!out[i].hit || ulps(out[i].t0, want[i]) > 16)
            fail_msg("case %d: GPU t %.9g (hit %u), exact %.9g", i, out[i].t0, out[i].hit, want[i]);
    }
}

static void test_sphere_random(void **state)
{
    (void)state;
    enum { N = 20000 };
    tb_case_sphere *in = calloc(N, sizeof *in);
    tb_case_box_out *out = calloc(N, sizeof *out);
    assert_true(in && out);
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("sphere_random", 99), 0);
    for (int i = 0; i < N; i++) {
        /* half the cases on the unit sphere (checked against host/object too) */
        float radius = tb_rng_below(&rng, 2) ? 1.0f : rnd(&rng, 0.1f, 3.0f);
        float dist = tb_rng_below(&rng, 4) ? rnd(&rng, 0.0f, 20.0f) : rnd(&rng, 100.0f, 1e4f);
        tb_vec3 o = {rnd(&rng, -1, 1), rnd(&rng, -1, 1), rnd(&rng, -1, 1)};
        float len = tb_vec3_length(o);
        if (len < 1e-3f)
            o = (tb_vec3){1, 0, 0}, len = 1;
        o = tb_vec3_scale(o, dist / len); /* inside for dist < radius */
        tb_vec3 aim = {rnd(&rng, -1.3f, 1.3f) * radius, rnd(&rng, -1.3f, 1.3f) * radius, rnd(&rng, -1.3f, 1.3f) * radius};
        tb_vec3 d = tb_vec3_scale(tb_vec3_sub(aim, o), rnd(&rng, 0.25f, 4.0f) / fmaxf(dist, 1.0f));
        if (d.x == 0.0f && d.y == 0.0f && d.z == 0.0f)
            d.z = 1.0f;
        in[i] = (tb_case_sphere){{o, 0.0f, d, INFINITY}, radius, 0, 0, 0};
    }
    run(k_sphere, in, sizeof *in, out, sizeof *out, N);
    int hits = 0, differ = 0;
    for (int i = 0; i < N; i++) {
        differ += check_sphere(&in[i], &out[i], i, false);
        hits += (int)out[i].hit;
    }
    print_message("[ info     ] %d random rays at spheres (near and up to 10^4 radii away): %d hits, "
                  "%d grazing rays decided differently\n", N, hits, differ);
    assert_true(hits > N / 4 && hits < N - N / 10);
    free(in);
    free(out);
}

/* ---------------------------------------------------------------- colour */

static void test_srgb(void **state)
{
    (void)state;
    enum { R = 20000, N = R + 512 + 16 };
    tb_case_f4 *in = calloc(N, sizeof *in), *enc = calloc(N, sizeof *enc), *dec = calloc(N, sizeof *dec);
    assert_true(in && enc && dec);
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("srgb", 5), 0);
    int n = 0;
    /* every 8-bit code, as an encoded value (x) and as its linear value (y) */
    for (int k = 0; k < 256; k++, n++)
        in[n] = (tb_case_f4){(float)k / 255.0f, tb_srgb_decode((float)k / 255.0f), (float)k / 255.0f, 0};
    /* the knees and the clamps: exactly representable edge inputs */
    const float edge[] = {0.0f, -0.0f, -1.0f, 1.0f, 2.0f, INFINITY, 0x1.9a5c36p-9f /* 0.0031308 knee */,
                          0x1.9a5c38p-9f, 0x1.4b5dccp-5f /* 0.04045 knee */, 0x1.4b5dcep-5f, 0x1p-126f,
                          0.5f, 0.25f, 0.75f, 0x1p-9f, 0x1p-4f};
    for (size_t k = 0; k < sizeof edge / sizeof edge[0]; k++, n++)
        in[n] = (tb_case_f4){edge[k], edge[k], edge[k], 0};
    while (n < N) {
        float v = tb_rng_float(&rng);
        if (tb_rng_below(&rng, 4) == 0)
            v *= 0.05f; /* the linear segments */
        in[n++] = (tb_case_f4){v, tb_rng_float(&rng), v, 0};
    }
    run(k_color[0], in, sizeof *in, enc, sizeof *enc, N);
    run(k_color[1], in, sizeof *in, dec, sizeof *dec, N);
    double worst_enc = 0, worst_dec = 0;
    for (int i = 0; i < N; i++) {
        const float *x = &in[i].x, *e = &enc[i].x, *d = &dec[i].x;
        for (int k = 0; k < 3; k++) {
            float ce = tb_srgb_encode(x[k]), cd = tb_srgb_decode(x[k]);
            double de = fabs((double)e[k] - ce), dd = fabs((double)d[k] - cd);
            if (!(de <= 4e-6))
                fail_msg("encode(%a): GPU %.9g, C %.9g (|diff| %.3g > 4e-6)", x[k], e[k], ce, de);
            if (!(dd <= 0x1p-16 * cd))
                fail_msg("decode(%a): GPU %.9g, C %.9g (relative %.3g > 2^-16)", x[k], d[k], cd, dd / cd);
            worst_enc = fmax(worst_enc, de);
            worst_dec = fmax(worst_dec, cd > 0 ? dd / cd : 0);
        }
    }
    /* exact where the curve is: 0 and 1 and the clamps */
    for (int i = 256; i < 256 + 6; i++) {
        float want = in[i].x >= 1.0f ? 1.0f : 0.0f;
        assert_true(enc[i].x == want && dec[i].x == want);
    }
    /* 8-bit codes survive decode on the CPU and encode on the GPU */
    for (int k = 0; k < 256; k++)
        if ((int)lrintf(enc[k].y * 255.0f) != k)
            fail_msg("8-bit code %d: GPU encode of its linear value gives %.9g", k, enc[k].y);
    print_message("[ info     ] sRGB: worst encode |diff| %.3g (bound 4e-6), worst decode relative %.3g "
                  "(bound 2^-16 = %.3g)\n", worst_enc, worst_dec, 0x1p-16);
    free(in);
    free(enc);
    free(dec);
}

static void test_xyz(void **state)
{
    (void)state;
    enum { N = 20000 };
    tb_case_f4 *in = calloc(N, sizeof *in), *to_xyz = calloc(N, sizeof *in), *to_rgb = calloc(N, sizeof *in);
    assert_true(in && to_xyz && to_rgb);
    /* unit vectors and zero first: the result is exactly a float matrix column */
    in[0] = (tb_case_f4){1, 0, 0, 0};
    in[1] = (tb_case_f4){0, 1, 0, 0};
    in[2] = (tb_case_f4){0, 0, 1, 0};
    in[3] = (tb_case_f4){0, 0, 0, 0};
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("xyz", 8), 0);
    for (int i = 4; i < N; i++)
        in[i] = (tb_case_f4){rnd(&rng, -0.5f, 1.5f), rnd(&rng, -0.5f, 1.5f), rnd(&rng, -0.5f, 1.5f), 0};
    run(k_color[2], in, sizeof *in, to_xyz, sizeof *to_xyz, N);
    run(k_color[3], in, sizeof *in, to_rgb, sizeof *to_rgb, N);
    for (int j = 0; j < 3; j++)
        for (int r = 0; r < 3; r++) {
            const float *gx = &to_xyz[j].x, *gr = &to_rgb[j].x;
            assert_true(gx[r] == (float)tb_srgb_to_xyz_matrix[r][j]);
            assert_true(gr[r] == (float)tb_xyz_to_srgb_matrix[r][j]);
        }
    assert_true(to_xyz[3].x == 0 && to_xyz[3].y == 0 && to_xyz[3].z == 0);
    double worst = 0;
    for (int i = 0; i < N; i++) {
        double v[3] = {in[i].x, in[i].y, in[i].z}, cx[3], cr[3];
        tb_linear_srgb_to_xyz(v, cx);
        tb_xyz_to_linear_srgb(v, cr);
        const float *gx = &to_xyz[i].x, *gr = &to_rgb[i].x;
        for (int r = 0; r < 3; r++) {
            /* entry rounding, 3 products, 2 sums: within 5 * 2^-23 of sum |m x| */
            double sx = 0, sr = 0;
            for (int k = 0; k < 3; k++) {
                sx += fabs(tb_srgb_to_xyz_matrix[r][k] * v[k]);
                sr += fabs(tb_xyz_to_srgb_matrix[r][k] * v[k]);
            }
            if (!(fabs(gx[r] - cx[r]) <= 10 * U * sx) || !(fabs(gr[r] - cr[r]) <= 10 * U * sr))
                fail_msg("case %d row %d: to XYZ GPU %.9g C %.17g; to RGB GPU %.9g C %.17g", i, r, gx[r], cx[r],
                         gr[r], cr[r]);
            worst = fmax(worst, fmax(fabs(gx[r] - cx[r]) / (sx * U + DBL_MIN), fabs(gr[r] - cr[r]) / (sr * U + DBL_MIN)));
        }
    }
    print_message("[ info     ] XYZ <-> sRGB: worst error %.2f u * sum|m x| (bound 10)\n", worst);
    free(in);
    free(to_xyz);
    free(to_rgb);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_layout_roundtrip),
        cmocka_unit_test(test_contraction), /* first of the numeric tests: measures fma fusion */
        cmocka_unit_test(test_aabb_exact),
        cmocka_unit_test(test_aabb_random),
        cmocka_unit_test(test_quadratic_exact),
        cmocka_unit_test(test_quadratic_random),
        cmocka_unit_test(test_sphere_exact),
        cmocka_unit_test(test_sphere_random),
        cmocka_unit_test(test_srgb),
        cmocka_unit_test(test_xyz),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
