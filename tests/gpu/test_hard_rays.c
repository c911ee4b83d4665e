/* Paired GLSL-vs-C tests of every intersection routine of the intersect
 * kernel (shaders/lib: sphere, cube, revolved (cylinder, cone, conic),
 * torus, planar (pyramid, prism, arches), xings and csg) on hard ray sets:
 * rays from nearby, from 10^4 and 10^6 units away, grazing rays, rays
 * starting on the surface, and non-finite rays (NaN, inf, zero direction),
 * at unit scale, at 10^-4 scale, on thin tori (minor/major 10^-3), on CSG
 * trees with coincident faces, and under 10:1 and 100:1 scaling. The C
 * reference is the CPU path (tb_scene_intersect, double). Tolerances: those
 * of docs/accuracy.md ("Intersect kernel"), plus the conditioning bound on
 * normals stated there ("Hard cases"), which this test checks per ray.
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
#include "util/math/float.h"
#include "util/math/rng.h"

/* The objects, one per kind (CSG trees with coincident faces included), each
 * placed by `translate(x) TR` where TR is the placement's transform. Every
 * object fits in [-1, 1]^3 before TR. */
static const char *const tb__kinds[] = {
    "sphere \"sphere\" { transform = [translate([%g 0 0]) %s] }",
    "cube \"cube\" { transform = [translate([%g 0 0]) %s] }",
    "cylinder \"cylinder\" { transform = [translate([%g 0 0]) %s] }",
    "cone \"cone\" { transform = [translate([%g 0 0]) %s] }",
    "cone \"frustum\" { transform = [translate([%g 0 0]) %s] geometry = { top_radius = 0.3 caps = false } }",
    "conic \"hyperboloid\" { transform = [translate([%g 0 0]) %s] "
    "geometry = { coefficients = [0.3 0 0.6] z_range = [-1 1] } }",
    "torus \"torus\" { transform = [translate([%g 0 0]) %s] geometry = { major = 0.75 minor = 0.25 } }",
    "torus \"thin\" { transform = [translate([%g 0 0]) %s] geometry = { major = 1 minor = 0.001 } }",
    "pyramid \"pyramid\" { transform = [translate([%g 0 0]) %s] }",
    "prism \"hex\" { transform = [translate([%g 0 0]) %s] geometry = { sides = 6 } }",
    "prism \"ell\" { transform = [translate([%g 0 0]) %s] "
    "geometry = { profile = [[-1 -1] [1 -1] [1 -0.4] [-0.4 -0.4] [-0.4 1] [-1 1]] } }",
    "square_arch \"sarch\" { transform = [translate([%g 0 0]) %s] geometry = { width = 1 height = 1.5 } }",
    "round_arch \"rarch\" { transform = [translate([%g 0 0]) %s] geometry = { width = 1 height = 1.5 } }",
    "difference \"same\" { transform = [translate([%g 0 0]) %s] cube { } cube { } }",
    "union \"twins\" { transform = [translate([%g 0 0]) %s] cube { } cube { } }",
    "difference \"shared\" { transform = [translate([%g 0 0]) %s] cube { } "
    "cube { transform = [scale(0.5) translate([0 0 0.5])] } }",
    "intersection \"lens\" { transform = [translate([%g 0 0]) %s] sphere { } "
    "cylinder { transform = [scale([0.6 0.6 2])] } }",
};
enum { TB__NKINDS = sizeof tb__kinds / sizeof tb__kinds[0] };

/* A placement: the transform after each object's translate([3k 0 0]) (so
 * object k's centre is TR(3k, 0, 0)), its scale (the objects' size in world
 * units: the length of the map's largest axis), and the far distances. */
typedef struct tb__placement {
    const char *name, *tr;
    double size;       /* the objects' world size (largest axis) */
    double x0, y0, z0; /* TR's translation */
    double far1, far2; /* distances of the far ray sets, in world units */
    double sc[3];      /* TR's scale per axis */
    uint64_t seed;     /* default seed (TB_TEST_SEED overrides) */
} tb__placement;

static const tb__placement tb__placements[] = {
    {"unit", "scale(1)", 1.0, 0.0, 0.0, 0.0, 1e4, 1e6, {1.0, 1.0, 1.0}, 11},
    /* 10^-4 scale; "far" is 10^4 and 10^6 sizes away (1 and 100 units). */
    {"tiny", "scale(0.0001) translate([0.5 -0.25 0.125])", 1e-4, 0.5, -0.25, 0.125, 1.0, 100.0, {1e-4, 1e-4, 1e-4}, 12},
    /* Unit objects 10^4 from the origin, rays from 10^4 and 10^5 away. */
    {"far", "translate([10000 10000 0])", 1.0, 1e4, 1e4, 0.0, 1e4, 1e5, {1.0, 1.0, 1.0}, 13},
    {"flat 10:1", "scale([1 1 0.1])", 1.0, 0.0, 0.0, 0.0, 1e4, 1e6, {1.0, 1.0, 0.1}, 14},
    {"flat 100:1", "scale([1 1 0.01])", 1.0, 0.0, 0.0, 0.0, 1e4, 1e6, {1.0, 1.0, 0.01}, 15},
};

/* The ray sets. */
enum { TB__NEAR, TB__FAR1, TB__FAR2, TB__GRAZING, TB__SURFACE, TB__NSETS };
static const char *const tb__set_names[TB__NSETS] = {"near", "far 1", "far 2", "grazing", "on surface"};

enum { TB__PER_OBJECT = 60 }; /* rays per object and set */

typedef struct tb__figures {
    int rays, hits, hit_differ, occ_differ;
    int face_differ; /* object, face or crossing (t beyond its bound, or normals > 90 degrees apart) */
    double dt, dt_over_bound, angle, angle_over_bound;
    double delta; /* the set's float resolution at its ray distance (tb__delta) */
} tb__figures;

static tb_hit tb__cpu(const tb_scene *s, const tb_ray *r)
{
    tb_hit h = {INFINITY, UINT32_MAX, UINT32_MAX, 0.0f, 0.0f, {0.0f, 0.0f, 0.0f}};
    tb_scene_intersect(s, r, &h);
    return h;
}

static double tb__angle(tb_vec3 a, tb_vec3 b)
{
    double d = ((double)a.x * b.x + (double)a.y * b.y + (double)a.z * b.z) /
               (sqrt((double)a.x * a.x + (double)a.y * a.y + (double)a.z * a.z) *
                sqrt((double)b.x * b.x + (double)b.y * b.y + (double)b.z * b.z));
    return acos(fmin(1.0, fmax(-1.0, d)));
}

/* A random point of object k's box (TR applied to [3k-1, 3k+1] x [-1,1]^2),
 * computed in double from the placement's axis-aligned scale. */
static void tb__box_point(const tb__placement *pl, const double sc[3], int k, tb_rng *rng, double p[3])
{
    p[0] = pl->x0 + sc[0] * (3.0 * k + 2.0 * tb_rng_double(rng) - 1.0);
    p[1] = pl->y0 + sc[1] * (2.0 * tb_rng_double(rng) - 1.0);
    p[2] = pl->z0 + sc[2] * (2.0 * tb_rng_double(rng) - 1.0);
}

/* A unit vector uniform on the sphere. */
static void tb__unit(tb_rng *rng, double w[3])
{
    double z = 2.0 * tb_rng_double(rng) - 1.0, a = 2.0 * TB_PI * tb_rng_double(rng), r = sqrt(1.0 - z * z);
    w[0] = r * cos(a), w[1] = r * sin(a), w[2] = z;
}

/* A ray from p - dist * w toward p (w unit), in float. */
static tb_ray tb__ray_toward(const double p[3], const double w[3], double dist)
{
    tb_vec3 o = {(float)(p[0] - dist * w[0]), (float)(p[1] - dist * w[1]), (float)(p[2] - dist * w[2])};
    return (tb_ray){o, 0.0f, {(float)(p[0] - o.x), (float)(p[1] - o.y), (float)(p[2] - o.z)}, INFINITY};
}

/* Makes set `set` for object k: TB__PER_OBJECT rays (fewer for grazing and
 * surface rays when the aimed rays miss). Returns the count written. */
static int tb__make_set(const tb_scene *s, const tb__placement *pl, const double sc[3], int set, int k, tb_rng *rng,
                        tb_ray *out)
{
    int n = 0;
    for (int tries = 0; n < TB__PER_OBJECT && tries < 20 * TB__PER_OBJECT; ++tries) {
        double p[3], w[3];
        tb__box_point(pl, sc, k, rng, p);
        tb__unit(rng, w);
        double dist = set == TB__FAR1 ? pl->far1 : set == TB__FAR2 ? pl->far2 : 4.0 * pl->size;
        tb_ray r = tb__ray_toward(p, w, dist);
        if (set <= TB__FAR2) {
            out[n++] = r;
            continue;
        }
        tb_hit h = tb__cpu(s, &r);
        tb_vec3 hp, perr;
        if (h.object != (uint32_t)k || !tb_object_hit_point(s->objects[h.object], &r, &h, &hp, &perr))
            continue;
        double ng[3] = {h.ng.x, h.ng.y, h.ng.z}, ln = sqrt(ng[0] * ng[0] + ng[1] * ng[1] + ng[2] * ng[2]);
        for (int c = 0; c < 3; ++c)
            ng[c] /= ln;
        double q[3] = {hp.x, hp.y, hp.z}, v[3];
        tb__unit(rng, v);
        double vn = v[0] * ng[0] + v[1] * ng[1] + v[2] * ng[2];
        if (set == TB__GRAZING) {
            /* Along the tangent plane, tilted into the surface by 10^-5 to 10^-2 rad. */
            double tl = 0.0;
            for (int c = 0; c < 3; ++c)
                v[c] -= vn * ng[c], tl += v[c] * v[c];
            if (tl < 1e-6)
                continue;
            double a = pow(10.0, -5.0 + 3.0 * tb_rng_double(rng)), ca = cos(a) / sqrt(tl), sa = sin(a);
            double d[3];
            for (int c = 0; c < 3; ++c)
                d[c] = v[c] * ca - ng[c] * sa;
            out[n++] = tb__ray_toward(q, d, 4.0 * pl->size);
        } else {
            /* From the float hit point, tmin 0: half outward, half into the solid. */
            double side = n % 2 ? -1.0 : 1.0;
            if (vn * side < 0.0)
                for (int c = 0; c < 3; ++c)
                    v[c] -= 2.0 * vn * ng[c];
            if (fabs(vn) < 0.05)
                continue;
            /* tmin: crossings nearer than 2^-14 (|o| + size) are not resolvable
             * in float (docs/accuracy.md, "Rays starting on a surface"). */
            double eps = ldexp(1.0, -14) * (fabs((double)hp.x) + fabs((double)hp.y) + fabs((double)hp.z) + pl->size);
            out[n++] = (tb_ray){hp, (float)eps, {(float)v[0], (float)v[1], (float)v[2]}, INFINITY};
        }
    }
    return n;
}

/* The kernel's float resolution for a ray from o at an object centred at c
 * (docs/accuracy.md, "Hard cases"), in the object's units: the float steps
 * o - c, the map and the move to the point nearest the centre each round at
 * the magnitude of |o - c| (and c itself at |c|), and the map divides by the
 * smallest axis sigma_min: delta = u (|o - c| + |c|) / sigma_min + u. */
static double tb__delta(const tb_ray *r, const double c[3], double smin)
{
    const double u = ldexp(1.0, -24);
    double oc = sqrt(pow(r->o.x - c[0], 2) + pow(r->o.y - c[1], 2) + pow(r->o.z - c[2], 2));
    return u * (oc + sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2])) / smin + u;
}

/* Smallest radius of curvature of object kind k in object units (0: only flat faces). */
static double tb__rho_unit(int k)
{
    static const double rho[TB__NKINDS] = {1.0, 0.0, 1.0, 0.3, 0.3, 0.5, 0.25, 0.001, 0.0,
                                           0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0,  0.6};
    return rho[k];
}

/* The per-hit bounds (K = 16 rounding steps of margin): with s = sin of the
 * angle between the ray and the surface, the hit moves along the ray by at
 * most K delta / s object units, so |dt| |d| <= max(1e-4 t |d|, K delta
 * sigma_max / s); a curved surface's normal turns by that distance over its
 * radius of curvature rho, and the inverse-transpose map amplifies an
 * object-space angle by at most kappa = sigma_max / sigma_min: angle <=
 * max(1e-3, K kappa delta / (rho s)). Flat faces: 1e-3 (their normal is a
 * row of the map). */
enum { TB__K = 16 };

/* Compares the GPU's records with the CPU's on n rays aimed at object k;
 * accumulates into f (hit/miss and face counts; the worst |dt|/t, normal
 * angle, and each as a fraction of its per-hit bound). */
static void tb__compare(const tb_scene *s, const tb__placement *pl, const double sc[3], const tb_ray *rays,
                        const tb_hit *gh, const uint8_t *go, int n, tb__figures *f)
{
    double smin = fmin(sc[0], fmin(sc[1], sc[2])), smax = fmax(sc[0], fmax(sc[1], sc[2]));
    for (int i = 0; i < n; ++i) {
        tb_hit c = tb__cpu(s, &rays[i]);
        f->rays++;
        f->occ_differ += go[i] != tb_scene_occluded(s, &rays[i]);
        bool ch = c.object != UINT32_MAX, gh_ = gh[i].object != UINT32_MAX;
        if (ch != gh_) {
            f->hit_differ++;
            continue;
        }
        if (!ch)
            continue;
        f->hits++;
        if (c.object != gh[i].object || c.face != gh[i].face) {
            f->face_differ++;
            continue;
        }
        double centre[3] = {pl->x0 + sc[0] * 3.0 * c.object, pl->y0, pl->z0};
        double delta = tb__delta(&rays[i], centre, smin);
        double dl = sqrt((double)rays[i].d.x * rays[i].d.x + (double)rays[i].d.y * rays[i].d.y +
                         (double)rays[i].d.z * rays[i].d.z);
        double sn = fmax(1e-6, fabs(cos(tb__angle(rays[i].d, c.ng))));
        double dt = fabs((double)gh[i].t - c.t) * dl, tbound = fmax(1e-4 * c.t * dl, TB__K * delta * smax / sn);
        double a = tb__angle(gh[i].ng, c.ng), rho = tb__rho_unit((int)c.object);
        if (dt > tbound || a > 0.5 * TB_PI) {
            /* Another crossing of the same surface (a tangent crossing one
             * path finds, the inside of an open surface near its rim): a
             * disagreement like a hit/miss one, counted with object/face. */
            f->face_differ++;
            continue;
        }
        f->dt = fmax(f->dt, dt / (c.t * dl));
        f->dt_over_bound = fmax(f->dt_over_bound, dt / tbound);
        double abound = rho > 0.0 ? fmax(1e-3, TB__K * (smax / smin) * delta / (rho * sn)) : 1e-3;
        f->angle = fmax(f->angle, a);
        f->angle_over_bound = fmax(f->angle_over_bound, a / abound);
        if (a > abound)
            print_message("[ beyond   ] object %u face %u: o (%.9g %.9g %.9g) d (%.9g %.9g %.9g) tmin %g: "
                          "cpu t %.9g n (%.4g %.4g %.4g), gpu t %.9g n (%.4g %.4g %.4g); s %.3g delta %.3g\n",
                          c.object, c.face, (double)rays[i].o.x, (double)rays[i].o.y, (double)rays[i].o.z,
                          (double)rays[i].d.x, (double)rays[i].d.y, (double)rays[i].d.z, (double)rays[i].tmin,
                          (double)c.t, (double)c.ng.x, (double)c.ng.y, (double)c.ng.z, (double)gh[i].t,
                          (double)gh[i].ng.x, (double)gh[i].ng.y, (double)gh[i].ng.z, sn, delta);
    }
}

static gpu_test_env tb__env; /* one device for every test: the pipeline is compiled once */

/* Loads the placement's scene, makes and traces every set, compares. */
static void tb__run_placement(const tb__placement *pl, const double sc[3], uint64_t seed, tb__figures out[TB__NSETS])
{
    char text[16384];
    size_t len = (size_t)snprintf(text, sizeof text, "mid 1\n");
    for (int k = 0; k < TB__NKINDS; ++k) {
        len += (size_t)snprintf(text + len, sizeof text - len, tb__kinds[k], 3.0 * k, pl->tr);
        len += (size_t)snprintf(text + len, sizeof text - len, "\n");
    }
    assert_true(len < sizeof text);
    tb_scene *s = gpu_test_load(text, "hard.mid", NULL);
    assert_int_equal(s->nobjects, TB__NKINDS);
    tb_gpu_scene *g = tb_gpu_scene_create(tb__env.dev, s);
    assert_non_null(g);
    tb_gpu_scene_info info;
    tb_gpu_scene_get_info(g, &info);
    assert_int_equal(info.cpu_objects, 0);
    enum { CAP = TB__NKINDS * TB__PER_OBJECT };
    tb_ray *rays = malloc(CAP * sizeof *rays);
    tb_hit *hits = malloc(CAP * sizeof *hits);
    uint8_t *occ = malloc(CAP);
    assert_true(rays && hits && occ);
    double smin = fmin(sc[0], fmin(sc[1], sc[2]));
    tb_rng rng;
    for (int set = 0; set < TB__NSETS; ++set) {
        tb_rng_seed(&rng, seed, (uint64_t)set);
        int n = 0;
        for (int k = 0; k < TB__NKINDS; ++k)
            n += tb__make_set(s, pl, sc, set, k, &rng, rays + n);
        assert_int_equal(tb_gpu_intersect(g, rays, (size_t)n, hits, NULL), TB_OK);
        assert_int_equal(tb_gpu_occluded(g, rays, (size_t)n, occ, NULL), TB_OK);
        tb__figures f = {0};
        tb__compare(s, pl, sc, rays, hits, occ, n, &f);
        double dist = set == TB__FAR1 ? pl->far1 : set == TB__FAR2 ? pl->far2 : 4.0 * pl->size;
        double c[3] = {pl->x0, pl->y0, pl->z0};
        tb_ray probe = {{(float)(pl->x0 + dist), (float)pl->y0, (float)pl->z0}, 0.0f, {1, 0, 0}, INFINITY};
        f.delta = tb__delta(&probe, c, smin);
        out[set] = f;
        print_message("[ info     ] %-10s %-10s %4d rays %4d hits: hit/miss %d, object/face %d, occlusion %d "
                      "(delta %.1e); |dt|/t %.1e (%.2f of bound), normal %.1e rad (%.2f of bound)\n",
                      pl->name, tb__set_names[set], f.rays, f.hits, f.hit_differ, f.face_differ, f.occ_differ, f.delta,
                      f.dt, f.dt_over_bound, f.angle, f.angle_over_bound);
    }
    free(rays), free(hits), free(occ);
    tb_gpu_scene_destroy(g);
    tb_scene_free(s);
}

/* The tolerances (docs/accuracy.md, "Hard cases"): per hit, t and the normal
 * within the bounds of tb__compare; hit/miss, object/face and occlusion
 * disagreements at most 10^-3 of the rays plus the band of width 4 delta
 * about silhouettes and edges that the float resolution leaves undecided
 * (vacuous for the sets where delta is large: 10^6 sizes away, which the
 * test prints for information), plus 5 % of grazing rays (tilted down to
 * 10^-5 rad: undecided by construction). */
static void tb__check(const tb__figures f[TB__NSETS])
{
    for (int set = 0; set < TB__NSETS; ++set) {
        const tb__figures *x = &f[set];
        assert_true(x->rays > 0 && x->hits > x->rays / 8);
        double frac = 1e-3 + 4.0 * x->delta + (set == TB__GRAZING ? 0.05 : 0.0);
        int hit_tol = (int)(frac * x->rays), face_tol = (int)(frac * x->hits) + 1;
        if (x->hit_differ > hit_tol || x->occ_differ > hit_tol)
            fail_msg("%s: hit/miss %d, occlusion %d of %d rays (at most %d)", tb__set_names[set], x->hit_differ,
                     x->occ_differ, x->rays, hit_tol);
        if (x->face_differ > face_tol)
            fail_msg("%s: object/face %d of %d hits (at most %d)", tb__set_names[set], x->face_differ, x->hits,
                     face_tol);
        if (!(x->dt_over_bound <= 1.0))
            fail_msg("%s: |dt|/t %g, %g of the bound", tb__set_names[set], x->dt, x->dt_over_bound);
        if (!(x->angle_over_bound <= 1.0))
            fail_msg("%s: normal %g rad, %g of the bound", tb__set_names[set], x->angle, x->angle_over_bound);
    }
}

/* One placement (its tb__placements entry is the test's state). */
static void test_placement(void **state)
{
    const tb__placement *pl = *state;
    char name[64];
    snprintf(name, sizeof name, "test_placement %s", pl->name);
    tb__figures f[TB__NSETS];
    tb__run_placement(pl, pl->sc, tb_test_seed(name, pl->seed), f);
    tb__check(f);
}

/* Non-finite and degenerate rays: a miss and no occlusion on the GPU, as on
 * the CPU, at every kind in the scene; the device keeps working. */
static void test_non_finite(void **state)
{
    (void)state;
    char text[16384];
    size_t len = (size_t)snprintf(text, sizeof text, "mid 1\n");
    for (int k = 0; k < TB__NKINDS; ++k) {
        len += (size_t)snprintf(text + len, sizeof text - len, tb__kinds[k], 3.0 * k, "scale(1)");
        len += (size_t)snprintf(text + len, sizeof text - len, "\n");
    }
    tb_scene *s = gpu_test_load(text, "bad.mid", NULL);
    tb_gpu_scene *g = tb_gpu_scene_create(tb__env.dev, s);
    assert_non_null(g);
    const float nan = NAN, inf = INFINITY;
    enum { NB = 12 };
    tb_ray base[NB] = {
        {{nan, 0, 5}, 0, {0, 0, -1}, inf},    {{0, 0, 5}, 0, {nan, 0, -1}, inf},
        {{0, 0, 5}, 0, {0, 0, nan}, inf},     {{inf, 0, 5}, 0, {-1, 0, -1}, inf},
        {{0, 0, -inf}, 0, {0, 0, 1}, inf},    {{0, 0, 5}, 0, {inf, 0, -1}, inf},
        {{0, 0, 5}, 0, {0, -inf, -inf}, inf}, {{0, 0, 5}, 0, {0, 0, 0}, inf},
        {{0, 0, 5}, nan, {0, 0, -1}, inf},    {{0, 0, 5}, 0, {0, 0, -1}, nan},
        {{0, 0, 5}, inf, {0, 0, -1}, inf},    {{nan, nan, nan}, nan, {nan, nan, nan}, nan},
    };
    /* Each bad ray at each object (x moved to its centre where finite). */
    enum { N = NB * TB__NKINDS };
    tb_ray rays[N];
    tb_hit hits[N];
    uint8_t occ[N];
    for (int k = 0; k < TB__NKINDS; ++k)
        for (int i = 0; i < NB; ++i) {
            tb_ray r = base[i];
            r.o.x += 3.0f * (float)k;
            rays[k * NB + i] = r;
        }
    assert_int_equal(tb_gpu_intersect(g, rays, N, hits, NULL), TB_OK);
    assert_int_equal(tb_gpu_occluded(g, rays, N, occ, NULL), TB_OK);
    for (int i = 0; i < N; ++i) {
        tb_hit c = tb__cpu(s, &rays[i]);
        if (hits[i].object != UINT32_MAX || occ[i] || c.object != UINT32_MAX)
            fail_msg("bad ray %d at object %d: GPU object %u t %g occluded %d, CPU object %u", i % NB, i / NB,
                     hits[i].object, (double)hits[i].t, occ[i], c.object);
    }
    /* The device still works: a plain ray after them hits the sphere at t = 4. */
    tb_ray ok = {{0, 0, 5}, 0, {0, 0, -1}, inf};
    tb_hit h;
    assert_int_equal(tb_gpu_intersect(g, &ok, 1, &h, NULL), TB_OK);
    assert_int_equal(h.object, 0);
    tb_assert_near(h.t, 4.0, 1e-6);
    tb_gpu_scene_destroy(g);
    tb_scene_free(s);
}

static int setup(void **state)
{
    (void)state;
    gpu_test_open(&tb__env, NULL);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    gpu_test_close(&tb__env);
    return 0;
}

int main(void)
{
    struct CMUnitTest tests[1 + sizeof tb__placements / sizeof tb__placements[0]] = {
        cmocka_unit_test(test_non_finite)};
    static char names[sizeof tb__placements / sizeof tb__placements[0]][48];
    for (size_t i = 0; i < sizeof tb__placements / sizeof tb__placements[0]; ++i) {
        snprintf(names[i], sizeof names[i], "test_placement %s", tb__placements[i].name);
        tests[i + 1] = (struct CMUnitTest){names[i], test_placement, NULL, NULL, (void *)&tb__placements[i]};
    }
    return cmocka_run_group_tests(tests, setup, teardown);
}
