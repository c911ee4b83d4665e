/* Ground truth on the purely diffuse Cornell box (scenes/cornell-box.mid,
 * spectral): per surface, the mean radiance of a renderer against the
 * radiosity solution's, at the same points (docs/accuracy.md, "Ground
 * truth").
 *
 * For each surface (the five walls and the two blocks), N points uniformly
 * distributed by area over its radiosity elements (an element chosen with
 * probability proportional to its area, then a uniform point in one of its
 * display triangles (v0 v1 v2), (v0 v2 v3), chosen by area). At each point a
 * ray from 0.01 mm off the surface along -n finds the surface there, and
 * the renderer's radiance along it (K samples, channels summed) is averaged:
 * the radiance leaving the surface toward n, which for a Lambertian surface
 * is its radiance in every direction. The same points give the radiosity
 * solution's radiance B / pi there (with its ambient term; Gouraud-
 * interpolated from the element's corners as the display and the hybrid
 * read it). Both means are over the same points, so the point set's own
 * sampling error cancels: what remains is the renderer's noise (its standard
 * error is estimated from the per-point differences and printed) and the
 * two methods' disagreement.
 *
 * Tolerances. The radiosity solution has discretization error (vertex
 * irradiance interpolated linearly over elements of at most 40 mm, the
 * command's default; the walls' radiance varies smoothly, so the mean of
 * the interpolant differs from the true mean by O(h^2)), form-factor error
 * (the ray-cast disk approximation, docs/accuracy.md) and leaves 0.3% of
 * the power unshot (the ambient term stands for it). Those are each a
 * fraction of a percent on these surfaces; the issue asks for 1-2% when
 * both are converged. Renderer A agrees with B on a surface when
 *     |A / B - 1| <= 2% + 3 standard errors
 * (the standard error of A / B from both renderers' noise, estimated from
 * the spread of each point's samples; the solution has none. About
 * 0.1-0.4% at the default sample counts; $TB_TRUTH_TEST_DIVISOR, set to 4 in the
 * sanitizer build, divides the sample counts there and so widens this
 * allowance, not the 2%). The floor under the blocks and the ceiling above
 * the light are in the means of both (a ray there finds its own surface;
 * both renderers see it dark). */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "host/hybrid/hybrid.h"
#include "host/radiosity/locate.h"
#include "host/radiosity/radiosity.h"
#include "host/render/pathtrace.h"
#include "host/render/raytrace.h"
#include "host/render/scene.h"
#include "tb_test.h"
#include "util/math/float.h"
#include "util/math/rng.h"

/* Points per surface and samples per point (before the divisor). */
#define TB__POINTS 256
#define TB__HYBRID_SAMPLES 16
#define TB__PATH_SAMPLES 512
/* The ray starts this far off the surface (mm): below the 0.1 mm between the
 * light and the ceiling; or, where that misses the surface, TB__OFFSET_FAR. */
#define TB__OFFSET 0.01f
#define TB__OFFSET_FAR 5.0f

/* n divided by $TB_TRUTH_TEST_DIVISOR (the sanitizer build sets 4), at least 1. */
static int tb__scaled(int n)
{
    const char *e = getenv("TB_TRUTH_TEST_DIVISOR");
    int d = e ? atoi(e) : 1;
    n /= d > 0 ? d : 1;
    return n > 0 ? n : 1;
}

/* A radiance estimator along a ray (scene channels); called from several threads. */
typedef tb_channels (*tb__radiance_fn)(const void *ctx, const tb_ray *ray, tb_rng *rng);

/* The sample points of one surface. */
typedef struct tb__surface {
    uint32_t object;
    const char *name;
    size_t n;      /* points kept */
    tb_ray *rays;  /* each finds its point on the surface */
    double *rad;   /* the radiosity solution's radiance at each point, channels summed */
} tb__surface;

/* A renderer's mean over a surface's points against the solution's there. */
typedef struct tb__agreement {
    double mean, rad_mean, se; /* se: standard error of mean (the renderer's noise) */
} tb__agreement;

static double tb__sum(const double *v, int n)
{
    double s = 0.0;
    for (int i = 0; i < n; i++)
        s += v[i];
    return s;
}

static double tb__tri_area(tb_vec3 a, tb_vec3 b, tb_vec3 c)
{
    return 0.5 * (double)tb_vec3_length(tb_vec3_cross(tb_vec3_sub(b, a), tb_vec3_sub(c, a)));
}

/* The points of `object`: N candidates on its elements, kept when the ray
 * from off the surface finds this object's front there and the locator
 * finds its element. */
static void tb__surface_points(const tb_scene *s, const tb_rad_solver *sol, const tb_rad_locator *loc,
                               uint32_t object, int npoints, uint64_t seed, tb__surface *out)
{
    const tb_rad_mesh *m = tb_rad_solver_mesh(sol);
    memset(out, 0, sizeof *out);
    out->object = object;
    out->name = s->objects[object]->name;
    /* the object's elements and their cumulative areas */
    double *cum = malloc(m->nelems * sizeof *cum);
    size_t *idx = malloc(m->nelems * sizeof *idx), ne = 0;
    assert_true(cum && idx);
    double total = 0.0;
    for (size_t i = 0; i < m->nelems; i++)
        if (m->elems[i].object == object) {
            total += m->elems[i].area;
            cum[ne] = total;
            idx[ne++] = i;
        }
    assert_true(ne > 0);
    out->rays = malloc((size_t)npoints * sizeof *out->rays);
    out->rad = malloc((size_t)npoints * sizeof *out->rad);
    assert_true(out->rays && out->rad);
    double amb[TB_CHANNELS_MAX];
    tb_rad_ambient(sol, amb);
    tb_rng rng;
    tb_rng_seed(&rng, seed, object);
    for (int k = 0; k < npoints; k++) {
        double u = tb_rng_double(&rng) * total;
        size_t lo = 0, hi = ne - 1;
        while (lo < hi) {
            size_t mid = (lo + hi) / 2;
            if (cum[mid] < u)
                lo = mid + 1;
            else
                hi = mid;
        }
        const tb_rad_element *e = &m->elems[idx[lo]];
        tb_vec3 v0 = m->verts[e->v[0]].p, v1 = m->verts[e->v[1]].p, v2 = m->verts[e->v[2]].p, a = v1, b = v2;
        if (e->v[3] != TB_RAD_NONE) {
            tb_vec3 v3 = m->verts[e->v[3]].p;
            double a1 = tb__tri_area(v0, v1, v2), a2 = tb__tri_area(v0, v2, v3);
            if (tb_rng_double(&rng) * (a1 + a2) >= a1)
                a = v2, b = v3;
        }
        double r1 = tb_rng_double(&rng), r2 = tb_rng_double(&rng), sq = sqrt(r1);
        float w0 = (float)(1.0 - sq), w1 = (float)(sq * (1.0 - r2)), w2 = (float)(sq * r2);
        tb_vec3 p = tb_vec3_add(tb_vec3_add(tb_vec3_scale(v0, w0), tb_vec3_scale(a, w1)), tb_vec3_scale(b, w2));
        /* 0.01 mm off, or 5 mm where the element's plane is not the
         * tracer's surface (the left wall is not planar: its two triangles
         * lie up to 3.2 mm off the mesh's elements) */
        tb_vec3 n = e->normal;
        tb_ray ray;
        tb_hit hit;
        bool found = false;
        for (int t = 0; t < 2 && !found; t++) {
            float off = t == 0 ? TB__OFFSET : TB__OFFSET_FAR;
            ray = tb_ray_make(tb_vec3_add(p, tb_vec3_scale(n, off)), tb_vec3_scale(n, -1.0f), 0.0f, 2.0f * off);
            found = tb_scene_intersect(s, &ray, &hit) && hit.object == object && tb_vec3_dot(hit.ng, n) > 0.0f;
        }
        if (!found)
            continue;
        tb_rad_location at;
        if (!tb_rad_locate(loc, object, tb_ray_at(&ray, hit.t), hit.ng, &at))
            continue;
        double bv[TB_CHANNELS_MAX];
        tb_rad_location_radiosity(sol, &at, amb, bv);
        out->rays[out->n] = ray;
        out->rad[out->n++] = tb__sum(bv, m->nchannels) / TB_PI;
    }
    free(cum);
    free(idx);
    /* every point of a wall or block of the Cornell box finds its surface */
    assert_true(out->n >= (size_t)npoints * 9 / 10);
}

static void tb__surface_free(tb__surface *s)
{
    free(s->rays);
    free(s->rad);
}

/* The renderer's mean over the surface's points (`samples` estimates per
 * point, each point from its own stream), against the solution's; the
 * standard error from the samples' spread within each point (the noise). */
static tb__agreement tb__agree(const tb__surface *sf, tb__radiance_fn fn, const void *ctx, int samples,
                               uint64_t seed)
{
    assert_true(samples >= 2);
    double *est = malloc(sf->n * sizeof *est), *var = malloc(sf->n * sizeof *var);
    assert_true(est && var);
#pragma omp parallel for schedule(dynamic, 4)
    for (size_t i = 0; i < sf->n; i++) {
        tb_rng rng;
        tb_rng_seed(&rng, seed, ((uint64_t)sf->object << 32) | i);
        double s1 = 0.0, s2 = 0.0;
        for (int k = 0; k < samples; k++) {
            tb_channels c = fn(ctx, &sf->rays[i], &rng);
            double x = 0.0;
            for (int j = 0; j < c.n; j++)
                x += c.v[j];
            s1 += x;
            s2 += x * x;
        }
        est[i] = s1 / samples;
        /* the variance of this point's mean */
        var[i] = fmax(0.0, (s2 - s1 * est[i]) / (samples - 1)) / samples;
    }
    tb__agreement a = {0};
    double v = 0.0;
    for (size_t i = 0; i < sf->n; i++) {
        a.mean += est[i];
        a.rad_mean += sf->rad[i];
        v += var[i];
    }
    double n = (double)sf->n;
    a.mean /= n;
    a.rad_mean /= n;
    a.se = sqrt(v) / n;
    free(est);
    free(var);
    return a;
}

/* The radiosity solution's mean over the surface's points (no noise). */
static tb__agreement tb__agree_radiosity(const tb__surface *sf)
{
    tb__agreement a = {0};
    for (size_t i = 0; i < sf->n; i++)
        a.mean += sf->rad[i];
    a.mean /= (double)sf->n;
    a.rad_mean = a.mean;
    return a;
}

/* The Cornell box with the hybrid's radiosity pass (elements of at most
 * `edge` mm, 16 samples per shooter, 0.3% unshot, the ambient term). */
typedef struct tb__box {
    tb_scene *scene;
    tb_hybrid *hybrid;
    tb__surface surf[8];
    int nsurf;
} tb__box;

static void tb__box_open(tb__box *b, double edge, int points)
{
    memset(b, 0, sizeof *b);
    char path[1024];
    snprintf(path, sizeof path, "%s/scenes/cornell-box.mid", TB_SOURCE_DIR);
    if (tb_scene_load(path, NULL, &b->scene))
        fail_msg("%s", tb_last_error());
    /* purely diffuse: no specular, transmission or glossy part anywhere */
    for (int i = 0; i < b->scene->nmaterials; i++) {
        const tb_material *mt = &b->scene->materials[i];
        for (int c = 0; c < b->scene->nchannels; c++)
            assert_true(mt->specular.v[c] == 0.0f && mt->transmission.v[c] == 0.0f);
    }
    tb_hybrid_options ho = tb_hybrid_defaults();
    ho.mesh_given = true;
    ho.mesh.max_edge = edge;
    const char *e = getenv("TB_TRUTH_EDGE"); /* to try other element sizes */
    if (e)
        ho.mesh.max_edge = atof(e);
    if (tb_hybrid_create(b->scene, &ho, &b->hybrid))
        fail_msg("%s", tb_last_error());
    tb_hybrid_stats st = tb_hybrid_get_stats(b->hybrid);
    print_message("[ radiosity] %zu elements, %llu shots, %.1f s, unshot %.4f\n", st.elements,
                  (unsigned long long)st.shots, st.solve_seconds, st.unshot_fraction);
    const tb_rad_solver *sol = tb_hybrid_solver(b->hybrid);
    for (uint32_t o = 0; o < b->scene->nobjects; o++) {
        const char *nm = b->scene->objects[o]->name;
        if (nm && strcmp(nm, "light") == 0)
            continue;
        assert_true(b->nsurf < 8);
        tb__surface_points(b->scene, sol, tb_hybrid_locator(b->hybrid), o, points, 17, &b->surf[b->nsurf++]);
    }
    assert_int_equal(b->nsurf, 7);
}

static void tb__box_close(tb__box *b)
{
    for (int i = 0; i < b->nsurf; i++)
        tb__surface_free(&b->surf[i]);
    tb_hybrid_free(b->hybrid);
    tb_scene_free(b->scene);
}

/* A renderer: its radiance estimator and samples per point. */
typedef struct tb__renderer {
    const char *name;
    tb__radiance_fn fn; /* NULL: the radiosity solution itself (no noise) */
    const void *ctx;
    int samples;
} tb__renderer;

/* Checks renderer `a` against `b` on every surface: |a / b - 1| <= 2% + 3
 * standard errors of the difference (both renderers' noise); prints the
 * table. */
static void tb__check_surfaces(const tb__box *bx, const tb__renderer *a, const tb__renderer *b, double tol)
{
    int bad = 0;
    print_message("[ truth    ] %s against %s (tolerance %.1f%% + 3 standard errors): surface, points, means, "
                  "ratio - 1, standard error\n", a->name, b->name, 100 * tol);
    for (int i = 0; i < bx->nsurf; i++) {
        const tb__surface *sf = &bx->surf[i];
        tb__agreement ea = {0}, eb = {0};
        const tb__renderer *r[2] = {a, b};
        tb__agreement *e[2] = {&ea, &eb};
        for (int k = 0; k < 2; k++) {
            if (r[k]->fn)
                *e[k] = tb__agree(sf, r[k]->fn, r[k]->ctx, r[k]->samples, 1234567 + 7919 * (uint64_t)k);
            else
                *e[k] = tb__agree_radiosity(sf);
        }
        if (ea.mean == 0.0 && eb.mean == 0.0) { /* no light at all (the ceiling, direct light only) */
            print_message("[ truth    ] %-12s %4zu  both 0\n", sf->name ? sf->name : "?", sf->n);
            continue;
        }
        assert_true(eb.mean > 0.0);
        double ratio = ea.mean / eb.mean - 1.0;
        /* standard error of the ratio, to first order */
        double se = (1.0 + ratio) * sqrt(ea.se * ea.se / (ea.mean * ea.mean + 1e-300) + eb.se * eb.se / (eb.mean * eb.mean));
        bool ok = fabs(ratio) <= tol + 3.0 * se;
        print_message("[ truth    ] %-12s %4zu  %-9s %9.5g  %-9s %9.5g  %+7.4f  %6.4f%s\n", sf->name ? sf->name : "?",
                      sf->n, a->name, ea.mean, b->name, eb.mean, ratio, se, ok ? "" : "  FAILED");
        bad += !ok;
    }
    if (bad)
        fail_msg("%s against %s: %d surfaces disagree beyond %.1f%% + 3 standard errors", a->name, b->name, bad,
                 100 * tol);
}

static tb_channels tb__rt_fn(const void *ctx, const tb_ray *ray, tb_rng *rng)
{
    return tb_rt_radiance((const tb_raytracer *)ctx, ray, rng);
}

static tb_channels tb__pt_fn(const void *ctx, const tb_ray *ray, tb_rng *rng)
{
    return tb_pt_radiance((const tb_pathtracer *)ctx, ray, rng);
}

/* The element size and tolerance of the cases against the path tracer:
 * 20 mm elements, within 2% (measured at most 1.5%, the blocks); in the
 * sanitizer build (TB_TRUTH_TEST_DIVISOR > 1) the command's default 40 mm,
 * a quarter of the solve's time, within 4% (measured at most 3.2%: the
 * coarser solution loses more of the interreflected light, the ceiling and
 * the short block most; docs/accuracy.md, "Ground truth"). */
static double tb__fine_edge(void)
{
    return tb__scaled(4) == 4 ? 20.0 : 40.0;
}

static double tb__fine_tol(void)
{
    return tb__scaled(4) == 4 ? 0.02 : 0.04;
}

/* The hybrid (interpolated) against its own radiosity solution (the
 * command's default 40 mm elements): its direct light by shadow rays (4
 * light samples) replaces the solution's discretized first bounce, its
 * indirect part is the solution's. Within 2% (measured at most 1.2%, the
 * floor: the solution blurs the blocks' shadows). */
static void test_hybrid_radiosity(void **state)
{
    (void)state;
    tb__box b;
    tb__box_open(&b, 40.0, tb__scaled(TB__POINTS));
    tb_raytracer rt;
    assert_int_equal(tb_hybrid_tracer_init(b.hybrid, NULL, &rt), TB_OK);
    tb__renderer hy = {"hybrid", tb__rt_fn, &rt, tb__scaled(TB__HYBRID_SAMPLES)}, rad = {"radiosity", NULL, NULL, 0};
    tb__check_surfaces(&b, &hy, &rad, 0.02);
    tb_rt_release(&rt);
    tb__box_close(&b);
}

/* Direct light alone: the path tracer capped at one bounce against the
 * Whitted ray tracer (no indirect callback). Both estimate the same
 * integral without bias (the tracer: 4 stratified area-light samples; the
 * path tracer: one light sample and one BSDF ray, power heuristic), so
 * within 1% + 3 standard errors. (The radiosity solve only places the
 * points: 80 mm elements.) */
static void test_path_direct(void **state)
{
    (void)state;
    tb__box b;
    tb__box_open(&b, 80.0, tb__scaled(TB__POINTS));
    tb_pt_options po = {.max_depth = 1};
    tb_pathtracer *pt;
    if (tb_pt_create(b.scene, &po, &pt))
        fail_msg("%s", tb_last_error());
    tb_raytracer rt;
    assert_int_equal(tb_rt_init(&rt, b.scene, NULL), TB_OK);
    tb__renderer pa = {"path 1", tb__pt_fn, pt, tb__scaled(TB__PATH_SAMPLES)},
                 wh = {"Whitted", tb__rt_fn, &rt, tb__scaled(TB__HYBRID_SAMPLES)};
    tb__check_surfaces(&b, &pa, &wh, 0.01);
    tb_rt_release(&rt);
    tb_pt_free(pt);
    tb__box_close(&b);
}

/* The path tracer (its defaults: Russian roulette, no depth cap) against a
 * converged radiosity solution: the "agreement with the radiosity
 * renderer on purely diffuse scenes (mean radiance per surface within 1-2%
 * when both are converged)"; then the hybrid over the same solution against
 * the path tracer on the same points (its direct light is exact, its
 * indirect light the solution's). One case: the 20 mm solve is most of the
 * time, and both comparisons read it. */
static void test_path_agreement(void **state)
{
    (void)state;
    tb__box b;
    tb__box_open(&b, tb__fine_edge(), tb__scaled(TB__POINTS));
    tb_pathtracer *pt;
    if (tb_pt_create(b.scene, NULL, &pt))
        fail_msg("%s", tb_last_error());
    tb_raytracer rt;
    assert_int_equal(tb_hybrid_tracer_init(b.hybrid, NULL, &rt), TB_OK);
    tb__renderer pa = {"path", tb__pt_fn, pt, tb__scaled(TB__PATH_SAMPLES)}, rad = {"radiosity", NULL, NULL, 0},
                 hy = {"hybrid", tb__rt_fn, &rt, tb__scaled(TB__HYBRID_SAMPLES)};
    tb__check_surfaces(&b, &pa, &rad, tb__fine_tol());
    tb__check_surfaces(&b, &hy, &pa, tb__fine_tol());
    tb_rt_release(&rt);
    tb_pt_free(pt);
    tb__box_close(&b);
}

int main(int argc, char **argv)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hybrid_radiosity),
        cmocka_unit_test(test_path_direct),
        cmocka_unit_test(test_path_agreement),
    };
    if (argc > 1)
        cmocka_set_test_filter(argv[1]);
    return cmocka_run_group_tests(tests, NULL, NULL);
}
