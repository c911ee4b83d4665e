/* Analytic surface emitters (host/render/emit_surface.h, docs/lights.md
 * "Analytic surface emitters"):
 *
 *  - areas (hence powers, pi x area x L) against closed forms: sphere,
 *    prolate and oblate spheroids, capped and open cylinders, an elliptic
 *    cylinder (perimeter by the trapezoid rule, spectrally exact for the
 *    periodic integrand), cone and frustum, torus (also scaled), a
 *    one-sheet hyperboloid conic, a scaled rotated box; a general ellipsoid
 *    (also scaled by 1e-6 and 1e6) and a non-uniformly scaled torus against
 *    quadratures of their own parametrisations written here; prisms
 *    (caps exactly); arches through the scene;
 *  - the sampled directions (two-sided emitters seen from inside the solid,
 *    so that every direction meets the surface and its density is the sum
 *    over the line's crossings: an ellipsoid, an elliptic cylinder, a scaled
 *    torus (from inside its tube: up to four crossings), a hexagonal prism,
 *    a round arch (from inside a pillar, through the opening)) pass the chi-square test of test_shading_support.h against
 *    tb_area_light_pdf_line, whose integral over the sphere is 1 (or the
 *    fraction of samples kept, for faces that reject points off the face);
 *  - the density a sample reports is the one tb_area_light_pdf gives at its
 *    point (what MIS reads);
 *  - the path tracer lit by an emitting torus and an elliptic cylinder gives
 *    the same radiance with analytic emitters as with the tessellated ones
 *    (tb_scene_options.tessellated_emitters) within 4 standard errors;
 *  - the scene: one emitter per curved primitive, its area for
 *    tb_scene_emissive_area, its table in tb_scene_memory. */
#include "tb_test.h"
#include "test_scene_text.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "host/render/emit_surface.h"
#include "host/render/pathtrace.h"
#include "host/render/scene.h"
#include "test_pt_agree.h"
#include "test_shading_support.h"
#include "util/math/rng.h"

/* Area of the surface of object i of a one-object scene `text`, by its
 * surface emitter; prints its table's size. */
static double surf_area(const char *text)
{
    tb_scene *s = tp_scene_text(text);
    tb_surface_emitter *se;
    if (tb_surface_emitter_make(s->objects[0], &se))
        fail_msg("%s", tb_last_error());
    double a = tb_surface_emitter_area(se);
    printf("[ table    ] %d cells, %zu bytes\n", tb_surface_emitter_cells(se), tb_surface_emitter_bytes(se, 16));
    tb_surface_emitter_free(se);
    tb_scene_free(s);
    return a;
}

static void check_area(const char *what, const char *text, double want, double tol)
{
    double a = surf_area(text);
    printf("[ area     ] %-34s %.15g want %.15g rel %.2e\n", what, a, want, fabs(a - want) / want);
    if (!(fabs(a - want) <= tol * want))
        fail_msg("%s: area %.15g, want %.15g (rel %.3g > %.3g)", what, a, want, fabs(a - want) / want, tol);
}

/* Perimeter of the ellipse of semi-axes a, b: trapezoid rule on the periodic
 * integrand (exact to rounding with 4096 points). */
static double ellipse_perimeter(double a, double b)
{
    const int n = 4096;
    double s = 0.0;
    for (int i = 0; i < n; i++) {
        double t = 2.0 * M_PI * i / n;
        s += sqrt(a * a * sin(t) * sin(t) + b * b * cos(t) * cos(t));
    }
    return s * 2.0 * M_PI / n;
}

/* Ellipsoid of semi-axes a, b, c: Gauss-Legendre in theta (64 panels of 6
 * points), trapezoid in phi. */
static double ellipsoid_area(double a, double b, double c)
{
    double x[6], w[6];
    tst_gauss_legendre(6, x, w);
    const int nt = 64, np = 512;
    double sum = 0.0;
    for (int i = 0; i < nt; i++)
        for (int k = 0; k < 6; k++) {
            double h = M_PI / nt, t = h * (i + 0.5 * (x[k] + 1.0)), st = sin(t), ct = cos(t);
            double row = 0.0;
            for (int j = 0; j < np; j++) {
                double p = j * 2.0 * M_PI / np, sp = sin(p), cp = cos(p);
                tb_dvec3 dt = {a * ct * cp, b * ct * sp, -c * st};
                tb_dvec3 dp = {-a * st * sp, b * st * cp, 0.0};
                row += tb_dvec3_length(tb_dvec3_cross(dt, dp));
            }
            sum += 0.5 * h * w[k] * row * (2.0 * M_PI / np);
        }
    return sum;
}

/* Torus (major R, minor r) scaled by (sx, sy, sz): trapezoid in both angles. */
static double torus_area(double R, double r, double sx, double sy, double sz)
{
    const int n = 1024;
    double sum = 0.0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double p = 2.0 * M_PI * i / n, t = 2.0 * M_PI * j / n;
            double cp = cos(p), sp = sin(p), ct = cos(t), st = sin(t), rr = R + r * ct;
            tb_dvec3 dp = {-sx * rr * sp, sy * rr * cp, 0.0};
            tb_dvec3 dt = {-sx * r * st * cp, -sy * r * st * sp, sz * r * ct};
            sum += tb_dvec3_length(tb_dvec3_cross(dp, dt));
        }
    return sum * (2.0 * M_PI / n) * (2.0 * M_PI / n);
}

static void test_areas(void **state)
{
    (void)state;
    check_area("sphere r 2", "mid 1 sphere { transform = [scale(2)] }", 16.0 * M_PI, 1e-12);
    {
        double a = 1.0, c = 2.0, e = sqrt(1.0 - a * a / (c * c));
        check_area("prolate spheroid 1 1 2", "mid 1 sphere { transform = [scale([1 1 2])] }",
                   2.0 * M_PI * a * a * (1.0 + c / (a * e) * asin(e)), 1e-10);
    }
    {
        double a = 2.0, c = 1.0, e = sqrt(1.0 - c * c / (a * a));
        check_area("oblate spheroid 2 2 1", "mid 1 sphere { transform = [scale([2 2 1]) rotate([1 2 3], 40)] }",
                   2.0 * M_PI * a * a * (1.0 + (1.0 - e * e) / e * atanh(e)), 1e-10);
    }
    check_area("ellipsoid 1 2 3", "mid 1 sphere { transform = [scale([1 2 3]) translate([10 0 0])] }",
               ellipsoid_area(1, 2, 3), 1e-8);
    /* tiny and huge scales: the same relative accuracy */
    check_area("ellipsoid 1 2 3 x 1e-6", "mid 1 sphere { transform = [scale([1e-6 2e-6 3e-6]) translate([5 5 5])] }",
               ellipsoid_area(1, 2, 3) * 1e-12, 1e-8);
    check_area("ellipsoid 1 2 3 x 1e6", "mid 1 sphere { transform = [scale([1e6 2e6 3e6])] }",
               ellipsoid_area(1, 2, 3) * 1e12, 1e-8);
    check_area("cylinder", "mid 1 cylinder { }", 4.0 * M_PI + 2.0 * M_PI, 1e-12);
    check_area("open cylinder", "mid 1 cylinder { geometry = { caps = false } }", 4.0 * M_PI, 1e-12);
    check_area("elliptic cylinder 1 3 h 2", "mid 1 cylinder { transform = [scale([1 3 2]) rotate([0 1 1], 25)] }",
               2.0 * 2.0 * ellipse_perimeter(1, 3) + 2.0 * M_PI * 3.0, 1e-10);
    check_area("cone", "mid 1 cone { }", M_PI * sqrt(5.0) + M_PI, 1e-12);
    check_area("frustum", "mid 1 cone { geometry = { top_radius = 0.5 } }",
               M_PI * 1.5 * sqrt(0.25 + 4.0) + M_PI * 1.25, 1e-12);
    check_area("torus 2 0.5", "mid 1 torus { geometry = { major = 2 minor = 0.5 } }", 4.0 * M_PI * M_PI, 1e-10);
    check_area("torus scaled 3", "mid 1 torus { geometry = { major = 2 minor = 0.5 } transform = [scale(3)] }",
               36.0 * M_PI * M_PI, 1e-10);
    check_area("torus scaled 1 1.5 0.5",
               "mid 1 torus { geometry = { major = 2 minor = 0.5 } transform = [scale([1 1.5 0.5])] }",
               torus_area(2, 0.5, 1, 1.5, 0.5), 1e-9);
    /* r^2 = 1 + z^2: side 2 pi int sqrt(1 + 2 z^2) dz over [-1, 1], caps of r^2 = 2 */
    double hyp = 2.0 * M_PI * (sqrt(3.0) + asinh(sqrt(2.0)) / sqrt(2.0)) + 2.0 * M_PI * 2.0;
    check_area("hyperboloid conic", "mid 1 conic { geometry = { coefficients = [1 0 1] } }", hyp, 1e-9);
    check_area("sphere as conic", "mid 1 conic { }", 4.0 * M_PI, 1e-9);
    check_area("box 2 4 6", "mid 1 cube { transform = [scale([1 2 3]) rotate([0 0 1], 17)] }",
               8.0 * (1 * 2 + 2 * 3 + 1 * 3), 1e-12);
    check_area("pyramid", "mid 1 pyramid { }", 4.0 + 4.0 * sqrt(5.0), 1e-12);
    /* prisms: sides by the table, caps (partly covering their square) exactly */
    check_area("hexagonal prism", "mid 1 prism { geometry = { sides = 6 } }", 12.0 + 3.0 * sqrt(3.0), 1e-12);
    check_area("L prism scaled", "mid 1 prism { geometry = { profile = [[0 0] [2 0] [2 1] [1 1] [1 2] [0 2]] } "
               "transform = [scale([1 1 0.5])] }", 8.0 + 6.0, 1e-12);
}

/* ------------------------------------------------------------- chi-square */

typedef struct light_ctx {
    const tb_area_light *a;
    tb_vec3 p;
} light_ctx;

static bool light_sample(void *c_, float uc, float u1, float u2, tb_vec3 *w)
{
    (void)uc;
    light_ctx *c = c_;
    tb_light_sample s;
    if (!tb_area_light_sample(c->a, c->p, u1, u2, &s))
        return false;
    *w = s.wi;
    return true;
}

static double light_pdf(void *c_, tb_vec3 w)
{
    light_ctx *c = c_;
    double sum = 0.0;
    for (int i = 0; i < c->a->n; i++)
        sum += tb_area_light_pdf_line(c->a, i, c->p, w);
    return sum;
}

/* Chi-square of object 0 of `text` as a two-sided emitter seen from p, n
 * samples; `partial`: faces reject points off them (the density then
 * integrates to the share kept). Seen from inside the solid there are no
 * silhouettes, which the expected counts' quadrature could miss. */
static void chi2_case(const char *name, const char *text, tb_vec3 p, uint64_t seed, bool partial, long n)
{
    tb_scene *s = tp_scene_text(text);
    assert_int_equal(s->nemitters, 1);
    tb_emitter e = s->emitters[0];
    assert_true(tb_emitter_is_surface(&e));
    e.two_sided = true;
    tb_area_light a;
    assert_int_equal(tb_area_light_init(&a, &e, 1), TB_OK);
    light_ctx c = {&a, p};
    n /= tp_pt_divisor();
    tst_chi2 r = tst_chi2_run(name, light_sample, light_pdf, &c, n, 24, 12, seed);
    assert_false(r.zero_bin_hit);
    assert_true(r.p_value >= TST_CHI2_ALPHA);
    if (partial) /* the density integrates to the share of points kept */
        tb_assert_near(r.pdf_sum, r.hist_sum, 5e-3);
    else
        tb_assert_near(r.pdf_sum, 1.0, 2e-3);
    /* The density a sample reports is tb_area_light_pdf at its point. */
    tb_rng rng;
    tb_rng_seed(&rng, seed, 3);
    for (int k = 0; k < 2000 / tp_pt_divisor(); k++) {
        tb_light_sample ls;
        if (!tb_area_light_sample(&a, p, tb_rng_float(&rng), tb_rng_float(&rng), &ls))
            continue;
        double q = tb_area_light_pdf(&a, 0, p, ls.point, ls.normal);
        if (!(fabs(q - ls.pdf) <= 1e-4 * ls.pdf))
            fail_msg("%s: sample density %.9g, tb_area_light_pdf %.9g", name, ls.pdf, q);
    }
    tb_area_light_release(&a);
    tb_scene_free(s);
}

static void test_chi2(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("surface emitter chi2", 91);
    const char *em = " rendering = { emission = 1 } ";
    char buf[512];
#define CASE(name, obj, px, py, pz, partial, n)                                                                   \
    do {                                                                                                         \
        snprintf(buf, sizeof buf, "mid 1 " obj, em);                                                             \
        chi2_case(name, buf, tb_vec3_make(px, py, pz), seed++, partial, n);                                         \
    } while (0)
    CASE("ellipsoid 1 2 3 from inside", "sphere { transform = [scale([1 2 3]) rotate([1 1 0], 20)] %s }", 0.2f,
         0.3f, -0.5f, false, 40000);
    CASE("elliptic cylinder from inside", "cylinder { transform = [scale([1 2 1.5])] %s }", 0.3f, -0.4f, 0.2f,
         false, 40000);
    CASE("torus 1 1.5 0.7 from inside its tube",
         "torus { geometry = { major = 2 minor = 0.6 } transform = [scale([1 1.5 0.7]) rotate([1 0 0], 30)] %s }",
         2.0f, 0.1f, 0.05f, false, 40000);
    CASE("hexagonal prism from inside", "prism { geometry = { sides = 6 } transform = [scale([1 1 2])] %s }", 0.1f,
         0.2f, 0.3f, true, 40000);
    CASE("round arch from inside a pillar", "round_arch { transform = [scale([1 0.5 1])] %s }", -0.75f, 0.1f, -0.5f,
         true, 40000);
#undef CASE
}

/* ------------------------------------------------------------- the scene */

static void test_scene(void **state)
{
    (void)state;
    const char *text = "mid 1\n"
                       "sphere { transform = [scale([1 2 3])] rendering = { emission = 2 } }\n"
                       "torus { geometry = { major = 2 minor = 0.5 } transform = [translate([10 0 0])] "
                       "rendering = { emission = 1 } }\n"
                       "prism { geometry = { sides = 6 } transform = [translate([20 0 0])] rendering = { emission = 1 } }\n"
                       "square_arch { transform = [translate([30 0 0])] rendering = { emission = 1 } }\n"
                       "sphere { transform = [scale(2)] rendering = { emission = 1 } }\n";
    tb_scene *s = tp_scene_text(text);
    assert_int_equal(s->nemissive, 5);
    assert_int_equal(s->nemitters, 5);
    double want[4] = {ellipsoid_area(1, 2, 3), 4.0 * M_PI * M_PI * 2.0 * 0.5, 12.0 + 2.0 * 1.5 * sqrt(3.0), 0.0};
    /* square arch (default: w = 1, h = 1.5 in the 2 x 2 x 2 block, docs/mid.md):
     * exact area by the tessellation of flat faces, checked against the emitter */
    double arch;
    assert_int_equal(tb_scene_emissive_area(s, 3, &arch), TB_OK);
    want[3] = arch;
    for (int i = 0; i < 4; i++) {
        const tb_emitter *e = &s->emitters[s->emissive[i].first_emitter];
        assert_int_equal(s->emissive[i].nemitters, 1);
        assert_true(tb_emitter_is_surface(e));
        assert_int_equal(e->object, (uint32_t)i);
        double a;
        assert_int_equal(tb_scene_emissive_area(s, i, &a), TB_OK);
        if (!(fabs(a - want[i]) <= 1e-8 * want[i]) || a != e->area)
            fail_msg("emissive %d: area %.12g (emitter %.12g), want %.12g", i, a, e->area, want[i]);
        /* its power: pi x area x L */
        tb_area_light al;
        assert_int_equal(tb_area_light_init(&al, e, 1), TB_OK);
        double L = e->radiance.v[0];
        if (!(fabs(al.power - M_PI * want[i] * L) <= 1e-6 * al.power))
            fail_msg("emissive %d: power %.9g, want %.9g", i, al.power, M_PI * want[i] * L);
        tb_area_light_release(&al);
    }
    /* the similarity sphere stays the exact sphere emitter */
    assert_int_equal(s->emitters[4].kind, TB_EMITTER_SPHERE);
    /* memory: the tables are counted with the emitters */
    tb_scene_memory_use m;
    tb_scene_memory(s, &m);
    size_t tables = 0;
    for (int i = 0; i < 4; i++)
        tables += tb_surface_emitter_bytes(s->emitters[i].ctx, TB_SCENE_MALLOC_OVERHEAD);
    assert_true(m.emitters >= tables + 5 * sizeof(tb_emitter));
    assert_true(m.emitters < 64 * 1024); /* the tessellation was 16200 triangles of 224 bytes for the torus alone */
    tb_scene_free(s);
    /* tessellated on request: many triangles */
    tb_scene_options o = {.tessellated_emitters = true};
    s = tp_scene_text_opt(text, &o);
    assert_true(s->nemitters > 1000);
    for (int i = 0; i < s->nemitters; i++)
        assert_false(tb_emitter_is_surface(&s->emitters[i]));
    tb_scene_free(s);
}

/* ------------------------------------------------------------- path tracer */

static void test_pathtracer(void **state)
{
    (void)state;
    /* A Lambert + GGX floor under an emitting non-uniformly scaled torus and
     * an elliptic cylinder; radiance toward points of the floor. */
    const char *text =
        "mid 1\n"
        "polygons { geometry = { vertices = [[-8 -8 0] [8 -8 0] [8 8 0] [-8 8 0]] faces = [[0 1 2 3]] }\n"
        "  rendering = { diffuse = 0.6 specular = 0.3 roughness = 0.3 model = ggx } }\n"
        "torus { geometry = { major = 1.2 minor = 0.35 } transform = [scale([1 1.4 0.8]) rotate([1 0 0], 40) "
        "translate([-1 0 2.2])] rendering = { emission = 3 } }\n"
        "cylinder { transform = [scale([0.3 0.6 0.5]) rotate([0 1 0], 70) translate([2 1 1.5])] "
        "rendering = { emission = 5 } }\n";
    long n = 16000 / tp_pt_divisor();
    tb_scene *sa = tp_scene_text(text);
    tb_scene_options o = {.tessellated_emitters = true};
    tb_scene *st = tp_scene_text_opt(text, &o);
    const tb_vec3 eye = tb_vec3_make(0.5f, -6.0f, 4.0f);
    const tb_vec3 pts[5] = {{0, 0, 0}, {-1, 0.3f, 0}, {2, 1, 0}, {-3, -2, 0}, {3, -1.5f, 0}};
    uint64_t seed = tb_test_seed("surface emitter path tracer", 5);
    tp_pt_agree(sa, "analytic", st, "tessellated", eye, pts, 5, n, seed);
    tb_scene_free(sa);
    tb_scene_free(st);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_areas),
        cmocka_unit_test(test_chi2),
        cmocka_unit_test(test_scene),
        cmocka_unit_test(test_pathtracer),
    };
    const char *only = getenv("TB_TEST_FILTER");
    if (only && *only)
        cmocka_set_test_filter(only);
    return cmocka_run_group_tests(tests, NULL, NULL);
}
