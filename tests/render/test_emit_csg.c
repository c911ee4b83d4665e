/* Lazily tessellated CSG emitters (host/render/emit_csg.h, docs/lights.md
 * "CSG emitters"):
 *
 *  - loading a scene tessellates nothing (the stats counters of built CSG
 *    emitter tessellations and of CSG probe rays stay 0, also for a
 *    non-emitting CSG object); the first sample builds it, once;
 *  - its area against closed forms: the union of two unit spheres whose
 *    centres are 1 apart (6 pi) and a cube minus a sphere (24 + pi), within
 *    the tessellation's documented error, at most TB_CSG_EMIT_MAX_TRIS
 *    triangles;
 *  - the samples: uniform by area (Archimedes: the height of a uniform point
 *    on the two-sphere union is uniform on [-1, 2]; chi-square over 24
 *    bins), on the exact surface within the tessellation's tolerance; seen
 *    from inside (two-sided) the line query's density integrates to 1 over
 *    the directions and agrees with what samples report;
 *  - the path tracer lit by emitting CSG objects gives the same radiance as
 *    with the eager tessellation (tb_scene_options.tessellated_emitters)
 *    within 4 standard errors, and byte-identical images with 1 and 2
 *    threads, each from a freshly loaded scene (the tessellations built
 *    during the render). */
#include "tb_test.h"
#include "test_scene_text.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "host/render/emit_csg.h"
#include "host/render/pathtrace.h"
#include "host/render/scene.h"
#include "test_pt_agree.h"
#include "host/render/sampling.h"
#include "util/math/rng.h"
#include "util/stats/stats.h"

/* Two unit spheres, centres (0 0 0) and (0 0 1): area 2 (4 pi - 2 pi / 2) = 6 pi. */
#define TWO_SPHERES "union { rendering = { emission = 1 } sphere {} sphere { transform = [translate([0 0 1])] } }\n"
/* The cube [-1, 1]^3 minus a sphere of radius 0.5: 24 + pi. */
#define CUBE_HOLE                                                                                                  \
    "difference { transform = [translate([5 0 0])] rendering = { emission = 2 } cube {} sphere { transform = "     \
    "[scale(0.5)] } }\n"

static tb_csg_emitter *csg_of(const tb_scene *s, int emissive)
{
    const tb_emitter *e = &s->emitters[s->emissive[emissive].first_emitter];
    assert_int_equal(s->emissive[emissive].nemitters, 1);
    assert_true(tb_emitter_is_csg(e));
    return e->ctx;
}

static void test_lazy(void **state)
{
    (void)state;
    tb_stats_set_enabled(1);
    tb_stats_reset();
    tb_scene *s = tp_scene_text("mid 1\n" TWO_SPHERES CUBE_HOLE
                       "intersection { transform = [translate([0 6 0])] sphere {} cube { transform = [scale(0.8)] } }\n");
    assert_int_equal(s->nemissive, 2);
    assert_int_equal(s->nemitters, 2);
    /* nothing tessellated by the load, neither emitting nor other CSG objects */
    assert_int_equal(tb_stats_counter("Emitters/CSG tessellations built"), 0);
    assert_int_equal(tb_stats_counter("Polygonize/CSG probes"), 0);
    assert_int_equal(tb_stats_counter("Polygonize/faces made"), 0);
    tb_csg_emitter *a = csg_of(s, 0), *b = csg_of(s, 1);
    assert_false(tb_csg_emitter_built(a));
    assert_false(tb_csg_emitter_built(b));
    /* the proxy: pi/6 of the world box's area (2 x 2 x 3: 32) */
    tb_assert_near(s->emitters[0].area, TB_PI / 6.0 * 32.0, 1e-5);
    assert_true(tb_csg_emitter_bytes(a) == tb_csg_emitter_unbuilt_bytes());
    /* a sample of the first builds it alone; more samples do not rebuild */
    tb_area_light al;
    assert_int_equal(tb_area_light_init(&al, &s->emitters[0], 1), TB_OK);
    tb_light_sample ls;
    assert_true(tb_area_light_sample(&al, tb_vec3_make(0, -5, 0.5f), 0.3f, 0.6f, &ls));
    assert_true(tb_csg_emitter_built(a));
    assert_false(tb_csg_emitter_built(b));
    assert_int_equal(tb_stats_counter("Emitters/CSG tessellations built"), 1);
    for (int k = 0; k < 100; k++)
        (void)tb_area_light_sample(&al, tb_vec3_make(0, -5, 0.5f), k / 100.0f, 0.5f, &ls);
    assert_int_equal(tb_stats_counter("Emitters/CSG tessellations built"), 1);
    assert_true(tb_stats_counter("Polygonize/CSG probes") > 0);
    assert_true(tb_csg_emitter_bytes(a) > tb_csg_emitter_unbuilt_bytes());
    tb_area_light_release(&al);
    tb_scene_free(s);
    tb_stats_set_enabled(0);
}

static void test_area(void **state)
{
    (void)state;
    tb_scene *s = tp_scene_text("mid 1\n" TWO_SPHERES CUBE_HOLE);
    const double want[2] = {6.0 * TB_PI, 24.0 + TB_PI};
    for (int i = 0; i < 2; i++) {
        tb_csg_emitter *ce = csg_of(s, i);
        double a = tb_csg_emitter_area(ce), rel = a / want[i] - 1.0;
        int n = tb_csg_emitter_triangles(ce);
        printf("[ area     ] %s: tessellated %.6f, exact %.6f (rel %+.4f), %d triangles, level %d\n",
               i ? "cube - sphere" : "two spheres", a, want[i], rel, n, tb_csg_emitter_level(ce));
        assert_true(n > 0 && n <= TB_CSG_EMIT_MAX_TRIS);
        /* inscribed facets, lifted by the sagitta bound, and the seams'
         * overshoots and gaps (docs/lights.md, "CSG emitters") */
        if (!(fabs(rel) <= 0.02))
            fail_msg("area %.9g, exact %.9g: relative error %.4f above 2%%", a, want[i], rel);
    }
    tb_scene_free(s);
}

/* Heights of uniform samples on the two-sphere union: uniform on [-1, 2];
 * every point on the union's exact surface within the tolerance. */
static void test_uniform(void **state)
{
    (void)state;
    tb_scene *s = tp_scene_text("mid 1\n" TWO_SPHERES);
    tb_area_light al;
    assert_int_equal(tb_area_light_init(&al, s->emitters, 1), TB_OK);
    enum { BINS = 24 };
    long n = 48000 / tp_pt_divisor(), count[BINS] = {0}, got = 0;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("csg emitter uniform", 3), 1);
    const tb_emitter *e = &s->emitters[0];
    double maxdev = 0.0;
    for (long k = 0; k < n; k++) {
        tb_vec3 q, nq;
        double pdf;
        if (!e->sample(e->ctx, tb_rng_float(&rng), tb_rng_float(&rng), &q, &nq, &pdf))
            continue;
        got++;
        double r0 = sqrt((double)q.x * q.x + (double)q.y * q.y + (double)q.z * q.z);
        double r1 = sqrt((double)q.x * q.x + (double)q.y * q.y + ((double)q.z - 1.0) * (q.z - 1.0));
        /* on one sphere (facets inscribed then lifted: within 1%), and not
         * deep inside the other (seams: within the refinement edge, 0.03 of
         * the box diagonal) */
        double dev = fmin(fabs(r0 - 1.0), fabs(r1 - 1.0));
        maxdev = fmax(maxdev, dev);
        if (!(dev <= 0.01) || !(fmin(r0, r1) >= 1.0 - 0.11))
            fail_msg("sample (%g %g %g) off the union: radii %g %g", q.x, q.y, q.z, r0, r1);
        tb_assert_near(pdf, 1.0 / tb_csg_emitter_area(e->ctx), 1e-12);
        /* a unit normal pointing out of a sphere it is on (either, at the seam) */
        float c0 = tb_vec3_dot(nq, q), c1 = tb_vec3_dot(nq, tb_vec3_sub(q, tb_vec3_make(0, 0, 1)));
        tb_assert_near(tb_vec3_length(nq), 1.0, 1e-6);
        if (!((fabs(r0 - 1.0) <= 0.01 && c0 > 0.95f) || (fabs(r1 - 1.0) <= 0.01 && c1 > 0.95f)))
            fail_msg("sample (%g %g %g): normal (%g %g %g) not outward", q.x, q.y, q.z, nq.x, nq.y, nq.z);
        int b = (int)((q.z + 1.0) / 3.0 * BINS);
        count[b < 0 ? 0 : (b >= BINS ? BINS - 1 : b)]++;
    }
    assert_int_equal(got, n);
    double chi2 = 0.0, expect = (double)n / BINS;
    for (int b = 0; b < BINS; b++)
        chi2 += (count[b] - expect) * (count[b] - expect) / expect;
    /* 23 degrees of freedom: P(chi2 > 49.7) = 0.001 */
    printf("[ uniform  ] %ld samples, chi-square %.2f (23 dof, 0.1%% bound 49.7), largest radial deviation %.4f\n",
           n, chi2, maxdev);
    assert_true(chi2 < 49.7);
    tb_area_light_release(&al);
    tb_scene_free(s);
}

/* Seen from inside the solid (two-sided): every direction meets the
 * surface, and the line query's density (tb_area_light_pdf_line, summed
 * over the line's crossings) integrates to 1 over the sphere of directions
 * (Monte Carlo with uniform directions; an adaptive quadrature would chase
 * every facet edge); the density a sample reports is tb_area_light_pdf at
 * its point, and the line query finds that point. */
static void test_line_pdf(void **state)
{
    (void)state;
    const char *cases[2] = {"mid 1\n" TWO_SPHERES, "mid 1\n" CUBE_HOLE};
    const tb_vec3 p[2] = {{0.1f, -0.2f, 0.4f}, {5.7f, 0.1f, 0.2f}};
    uint64_t seed = tb_test_seed("csg emitter line pdf", 17);
    for (int i = 0; i < 2; i++) {
        tb_scene *s = tp_scene_text(cases[i]);
        tb_emitter e = s->emitters[0];
        e.two_sided = true;
        tb_area_light a;
        assert_int_equal(tb_area_light_init(&a, &e, 1), TB_OK);
        tb_rng rng;
        tb_rng_seed(&rng, seed + (uint64_t)i, 3);
        long n = 4000 / tp_pt_divisor();
        double s1 = 0.0, s2 = 0.0;
        for (long k = 0; k < n; k++) {
            tb_vec3 w = tb_sample_uniform_sphere(tb_rng_float(&rng), tb_rng_float(&rng));
            double f = 4.0 * TB_PI * tb_area_light_pdf_line(&a, 0, p[i], w);
            s1 += f;
            s2 += f * f;
        }
        double mean = s1 / n, se = sqrt(fmax(0.0, s2 / n - mean * mean) / n);
        printf("[ line pdf ] %s: integral %.4f +- %.4f\n", i ? "cube - sphere" : "two spheres", mean, se);
        if (!(fabs(mean - 1.0) <= 4.0 * se + 1e-3))
            fail_msg("integral of the line density %.5f +- %.5f, not 1", mean, se);
        for (int k = 0; k < 500 / tp_pt_divisor(); k++) {
            tb_light_sample ls;
            if (!tb_area_light_sample(&a, p[i], tb_rng_float(&rng), tb_rng_float(&rng), &ls))
                continue;
            double q = tb_area_light_pdf(&a, 0, p[i], ls.point, ls.normal);
            if (!(fabs(q - ls.pdf) <= 1e-4 * ls.pdf))
                fail_msg("sample density %.9g, tb_area_light_pdf %.9g", ls.pdf, q);
            double line = tb_area_light_pdf_line(&a, 0, p[i], ls.wi);
            if (!(line >= ls.pdf * (1.0 - 1e-3)))
                fail_msg("line density %.9g below the sample's %.9g", line, ls.pdf);
        }
        tb_area_light_release(&a);
        tb_scene_free(s);
    }
}

/* ------------------------------------------------------------- path tracer */

#define PT_SCENE                                                                                                   \
    "mid 1\n"                                                                                                      \
    "camera { eye = [0.5 -7 4] look_at = [0 0 0.8] up = [0 0 1] fov = 50 resolution = [40 30] }\n"               \
    "polygons { geometry = { vertices = [[-8 -8 0] [8 -8 0] [8 8 0] [-8 8 0]] faces = [[0 1 2 3]] }\n"             \
    "  rendering = { diffuse = 0.6 specular = 0.3 roughness = 0.3 model = ggx } }\n"                              \
    "union { transform = [scale(0.6) translate([-1.5 0 2.2])] rendering = { emission = 3 } sphere {} "            \
    "sphere { transform = [translate([0 0 1])] } }\n"                                                               \
    "difference { transform = [scale(0.5) rotate([1 1 0], 30) translate([1.8 0.5 1.5])] rendering = { emission = " \
    "5 } cube {} sphere { transform = [scale(0.7)] } }\n"

static void test_pathtracer(void **state)
{
    (void)state;
    long n = 4000 / tp_pt_divisor();
    tb_scene *sa = tp_scene_text(PT_SCENE);
    tb_scene_options o = {.tessellated_emitters = true};
    tb_scene *st = tp_scene_text_opt(PT_SCENE, &o);
    assert_int_equal(sa->nemitters, 2);
    assert_true(st->nemitters > 100); /* the eager triangles */
    const tb_vec3 eye = tb_vec3_make(0.5f, -6.0f, 4.0f);
    const tb_vec3 pts[4] = {{0, 0, 0}, {-1.5f, 0.3f, 0}, {2, 1, 0}, {-3, -2, 0}};
    uint64_t seed = tb_test_seed("csg emitter path tracer", 5);
    tp_pt_agree(sa, "lazy", st, "eager", eye, pts, 4, n, seed);
    tb_scene_free(sa);
    tb_scene_free(st);
}

/* 1 and 2 threads from fresh scenes (the tessellations built while rendering). */
static void test_threads(void **state)
{
    (void)state;
    tb_image *img[2] = {NULL, NULL};
    for (int k = 0; k < 2; k++) {
        tb_scene *s = tp_scene_text(PT_SCENE);
        tb_render_options o = tb_render_defaults();
        o.aa.spp = 4;
        o.threads = k + 1;
        o.aa.seed = 7;
        if (tb_render_path(s, NULL, &o, &img[k], NULL))
            fail_msg("%s", tb_last_error());
        assert_true(tb_csg_emitter_built(csg_of(s, 0)) && tb_csg_emitter_built(csg_of(s, 1)));
        tb_scene_free(s);
    }
    size_t bytes = (size_t)img[0]->width * img[0]->height * img[0]->channels * sizeof(float);
    assert_memory_equal(img[0]->pixels, img[1]->pixels, bytes);
    double sum = 0.0;
    for (size_t i = 0; i < bytes / sizeof(float); i++)
        sum += img[0]->pixels[i];
    assert_true(sum > 0.0);
    for (int k = 0; k < 2; k++)
        tb_image_free(img[k]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lazy),     cmocka_unit_test(test_area),       cmocka_unit_test(test_uniform),
        cmocka_unit_test(test_line_pdf),     cmocka_unit_test(test_pathtracer), cmocka_unit_test(test_threads),
    };
    const char *only = getenv("TB_TEST_FILTER");
    if (only && *only)
        cmocka_set_test_filter(only);
    return cmocka_run_group_tests(tests, NULL, NULL);
}
