/* The Vulkan path tracer (host/gpu/pathtrace.h) is statistically equal to the
 * CPU path tracer (tb_render_path) on every bundled scene it takes, and
 * refuses, with the reason, every bundled scene it does not take.
 *
 * Each scene at TB__W x TB__H pixels, TB__SPP samples per pixel, rendered K
 * times with independent seeds on each backend (linear sRGB). Then, as
 * Mitsuba's Z-tests (Jakob et al., mitsuba3 src/python/python/test/...), per
 * pixel and channel Welch's t-test of the two sets of K values, the p-values
 * held against the Sidak-corrected level 1 - (1 - alpha)^(1 / tests) for an
 * overall alpha = 0.01; and a bound on the mean image difference: per
 * channel, the image means of the two backends within 4 standard errors
 * (from the spread of the K renders' means) and that standard error below 2%
 * of the mean, so the bound is tight enough to see a small bias.
 *
 * Negative controls (the test must be able to fail): the same procedure
 * rejects the CPU path tracer capped at one bounce (direct light only)
 * against the GPU's uncapped render, per pixel and in the mean; and the
 * capped renders of both backends agree (the --max-depth path of the kernel);
 * and the CPU's materials scene without its patterns and bump maps is
 * rejected against the GPU's with them.
 *
 * Patterns without statistics: tb_gpu_pt_surfaces (the kernel's surface at
 * the first hit: (u, v), bumped normal, patterned colours) against the CPU
 * path tracer's tb_surface_at on a grid of camera rays of the materials
 * scene, with and without the camera rays' footprints: equal to float
 * rounding.
 * Validation layer on; any message fails. */
#include "gpu_test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "host/gpu/pathtrace.h"
#include "host/render/camera.h"
#include "host/render/pathtrace.h"
#include "host/render/render.h"
#include "host/render/scene.h"
#include "host/render/surface.h"

#define TB__W 32
#define TB__H 24
#define TB__SPP 4
#define TB__K 16
#define TB__ALPHA 0.01

/* ln Gamma(x), x > 0 (Lanczos, g = 7, 9 terms: |error| < 1e-13). */
static double tb__lgamma(double x)
{
    static const double c[9] = {0.99999999999980993,  676.5203681218851,     -1259.1392167224028,
                                771.32342877765313,   -176.61502916214059,   12.507343278686905,
                                -0.13857109526572012, 9.9843695780195716e-6, 1.5056327351493116e-7};
    x -= 1.0;
    double a = c[0], t = x + 7.5;
    for (int i = 1; i < 9; i++)
        a += c[i] / (x + (double)i);
    return 0.91893853320467274178 /* ln sqrt(2 pi) */ + (x + 0.5) * log(t) - t + log(a);
}

/* The continued fraction of the incomplete beta function (Lentz's method). */
static double tb__betacf(double a, double b, double x)
{
    const double tiny = 1e-300;
    double qab = a + b, qap = a + 1.0, qam = a - 1.0, c = 1.0, d = 1.0 - qab * x / qap;
    d = fabs(d) < tiny ? tiny : d;
    d = 1.0 / d;
    double h = d;
    for (int m = 1; m <= 300; m++) {
        double m2 = 2.0 * m, aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 + aa * d;
        d = fabs(d) < tiny ? tiny : d;
        c = 1.0 + aa / c;
        c = fabs(c) < tiny ? tiny : c;
        d = 1.0 / d;
        h *= d * c;
        aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 + aa * d;
        d = fabs(d) < tiny ? tiny : d;
        c = 1.0 + aa / c;
        c = fabs(c) < tiny ? tiny : c;
        d = 1.0 / d;
        double del = d * c;
        h *= del;
        if (fabs(del - 1.0) < 1e-15)
            break;
    }
    return h;
}

/* The regularised incomplete beta function I_x(a, b). */
static double tb__betai(double a, double b, double x)
{
    if (x <= 0.0)
        return 0.0;
    if (x >= 1.0)
        return 1.0;
    double bt = exp(tb__lgamma(a + b) - tb__lgamma(a) - tb__lgamma(b) + a * log(x) + b * log1p(-x));
    if (x < (a + 1.0) / (a + b + 2.0))
        return bt * tb__betacf(a, b, x) / a;
    return 1.0 - bt * tb__betacf(b, a, 1.0 - x) / b;
}

/* Two-sided p-value of Student's t with df degrees of freedom. */
static double tb__t_pvalue(double t, double df) { return tb__betai(0.5 * df, 0.5, df / (df + t * t)); }

/* The p-value routine against known values (scipy.stats.t.sf(t, df) * 2). */
static void test_t_pvalue(void **state)
{
    (void)state;
    assert_true(fabs(tb__t_pvalue(0.0, 10.0) - 1.0) < 1e-12);
    assert_true(fabs(tb__t_pvalue(2.228138851986273, 10.0) - 0.05) < 1e-9);   /* t_0.975, 10 dof */
    assert_true(fabs(tb__t_pvalue(2.042272456301238, 30.0) - 0.05) < 1e-9);   /* t_0.975, 30 dof */
    assert_true(fabs(tb__t_pvalue(4.604094871415897, 4.0) - 0.01) < 1e-9);    /* t_0.995, 4 dof */
    assert_true(fabs(tb__t_pvalue(1.959963984540054, 1e7) - 0.05) < 1e-6);    /* the normal limit */
    assert_true(tb__t_pvalue(40.0, 20.0) < 1e-19 && tb__t_pvalue(40.0, 20.0) > 0.0);
}

/* Bundled scene `name` at TB__W x TB__H. */
static tb_scene *tb__scene(const char *name)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/scenes/%s", TB_SOURCE_DIR, name);
    FILE *fp = fopen(path, "rb");
    if (!fp)
        fail_msg("cannot read %s", path);
    fseek(fp, 0, SEEK_END);
    long n = ftell(fp);
    fseek(fp, 0, SEEK_SET);
    char *text = malloc((size_t)n + 64);
    assert_non_null(text);
    assert_true(fread(text, 1, (size_t)n, fp) == (size_t)n);
    text[n] = 0;
    fclose(fp);
    /* resolution = [W H] -> [TB__W TB__H] (same length or shorter, padded) */
    char *r = strstr(text, "resolution = [");
    assert_non_null(r);
    char *e = strchr(r, ']');
    char repl[64];
    int k = snprintf(repl, sizeof repl, "resolution = [%d %d", TB__W, TB__H);
    assert_true(k <= (int)(e - r));
    memcpy(r, repl, (size_t)k);
    memset(r + k, ' ', (size_t)(e - r - k));
    char dir[1024];
    snprintf(dir, sizeof dir, "%s/scenes", TB_SOURCE_DIR);
    tb_scene *s = gpu_test_load(text, name, dir);
    free(text);
    return s;
}

/* K renders of spp samples per pixel (seeds base .. base + K - 1) into
 * v[k][pixel * 3 + c]. */
static void tb__renders(gpu_test_env *env, const tb_scene *s, bool gpu, int max_depth, int spp, uint64_t base,
                        float **v)
{
    tb_render_options ro = tb_render_defaults();
    ro.aa.spp = spp;
    ro.threads = 2;
    ro.progress = false;
    tb_pt_options po = {.max_depth = max_depth};
    for (int k = 0; k < TB__K; k++) {
        ro.aa.seed = base + (uint64_t)k;
        tb_image *img = NULL;
        tb_status st = gpu ? tb_gpu_render_path(env->dev, s, &po, &ro, &img, NULL, NULL)
                           : tb_render_path(s, &po, &ro, &img, NULL);
        if (st)
            fail_msg("%s render: %s", gpu ? "GPU" : "CPU", tb_last_error());
        assert_int_equal(img->width, TB__W);
        assert_int_equal(img->height, TB__H);
        assert_int_equal(img->channels, 3);
        v[k] = malloc((size_t)TB__W * TB__H * 3 * sizeof *v[k]);
        assert_non_null(v[k]);
        memcpy(v[k], img->pixels, (size_t)TB__W * TB__H * 3 * sizeof *v[k]);
        tb_image_free(img);
    }
}

/* What the comparison of two sets of K renders found. */
typedef struct tb__verdict {
    int tests;          /* pixel channels tested */
    int rejected;       /* below the Sidak level */
    double min_p;       /* smallest p-value */
    int worst;          /* its pixel channel */
    double mean_z[3];   /* per channel: (mean a - mean b) / its standard error */
    double rel_se[3];   /* that standard error / the mean */
    double rel_diff[3]; /* (mean a - mean b) / mean b */
} tb__verdict;

static tb__verdict tb__compare(float **a, float **b)
{
    tb__verdict r = {.min_p = 1.0, .worst = -1};
    const int n = TB__W * TB__H * 3;
    double *p = malloc((size_t)n * sizeof *p);
    assert_non_null(p);
    const double K = TB__K;
    for (int i = 0; i < n; i++) {
        double ma = 0, mb = 0, va = 0, vb = 0;
        for (int k = 0; k < TB__K; k++)
            ma += a[k][i], mb += b[k][i];
        ma /= K, mb /= K;
        for (int k = 0; k < TB__K; k++)
            va += (a[k][i] - ma) * (a[k][i] - ma), vb += (b[k][i] - mb) * (b[k][i] - mb);
        va /= K - 1.0, vb /= K - 1.0;
        p[i] = -1.0;
        if (va == 0.0 && vb == 0.0) {
            /* a constant pixel (a black one, or one that sees only the light):
             * the two values must agree to float rounding */
            if (fabs(ma - mb) > 1e-5 * fmax(fabs(ma), fabs(mb)) + 1e-30)
                p[i] = 0.0;
            else
                continue;
        } else {
            double sa = va / K, sb = vb / K, se2 = sa + sb;
            double df = se2 * se2 / (sa * sa / (K - 1.0) + sb * sb / (K - 1.0));
            p[i] = tb__t_pvalue((ma - mb) / sqrt(se2), df);
        }
        r.tests++;
    }
    const double level = 1.0 - pow(1.0 - TB__ALPHA, 1.0 / (r.tests > 0 ? r.tests : 1));
    for (int i = 0; i < n; i++) {
        if (p[i] < 0.0)
            continue;
        if (p[i] < level)
            r.rejected++;
        if (p[i] < r.min_p)
            r.min_p = p[i], r.worst = i;
    }
    free(p);
    for (int c = 0; c < 3; c++) {
        double ia[TB__K], ib[TB__K], ma = 0, mb = 0, va = 0, vb = 0;
        for (int k = 0; k < TB__K; k++) {
            double sa = 0, sb = 0;
            for (int q = c; q < n; q += 3)
                sa += a[k][q], sb += b[k][q];
            ia[k] = sa / (TB__W * TB__H), ib[k] = sb / (TB__W * TB__H);
            ma += ia[k], mb += ib[k];
        }
        ma /= K, mb /= K;
        for (int k = 0; k < TB__K; k++)
            va += (ia[k] - ma) * (ia[k] - ma), vb += (ib[k] - mb) * (ib[k] - mb);
        double se = sqrt(va / (K - 1.0) / K + vb / (K - 1.0) / K);
        r.mean_z[c] = se > 0.0 ? (ma - mb) / se : (ma == mb ? 0.0 : INFINITY);
        r.rel_se[c] = mb > 0.0 ? se / mb : INFINITY;
        r.rel_diff[c] = mb > 0.0 ? (ma - mb) / mb : INFINITY;
    }
    return r;
}

static void tb__print(const char *what, const tb__verdict *v)
{
    printf("[ pt-equiv ] %-44s %4d tests, %d below the Sidak level %.3g, min p %.3g (pixel %d, %d ch %d); "
           "mean diff %+.2f%% %+.2f%% %+.2f%% (z %+.2f %+.2f %+.2f, se %.2f%%)\n",
           what, v->tests, v->rejected, 1.0 - pow(1.0 - TB__ALPHA, 1.0 / (v->tests > 0 ? v->tests : 1)), v->min_p,
           v->worst >= 0 ? v->worst / 3 % TB__W : -1, v->worst >= 0 ? v->worst / 3 / TB__W : -1,
           v->worst >= 0 ? v->worst % 3 : -1, 100 * v->rel_diff[0], 100 * v->rel_diff[1], 100 * v->rel_diff[2],
           v->mean_z[0], v->mean_z[1], v->mean_z[2],
           100 * fmax(v->rel_se[0], fmax(v->rel_se[1], v->rel_se[2])));
}

static void tb__free(float **v)
{
    for (int k = 0; k < TB__K; k++)
        free(v[k]);
}

/* Equal: nothing below the Sidak level, the means within 4 standard errors
 * and the standard error small enough for the bound to mean something. */
static void tb__assert_equal(const char *what, const tb__verdict *v)
{
    tb__print(what, v);
    assert_true(v->tests > TB__W * TB__H); /* most pixels are lit: the test tested something */
    if (v->rejected > 0)
        fail_msg("%s: %d pixel channels differ (min p %.3g)", what, v->rejected, v->min_p);
    for (int c = 0; c < 3; c++) {
        if (!(fabs(v->mean_z[c]) < 4.0))
            fail_msg("%s: channel %d: image means differ by %.2f standard errors", what, c, v->mean_z[c]);
        if (!(v->rel_se[c] < 0.02))
            fail_msg("%s: channel %d: standard error %.3g of the mean: too noisy to bound", what, c, v->rel_se[c]);
    }
}

/* Scene s on both backends at spp samples per pixel: equal. */
static void tb__equivalent_scene(gpu_test_env *env, tb_scene *s, const char *name, int spp)
{
    const char *why = tb_gpu_pt_unsupported(s);
    if (why)
        fail_msg("%s: the kernel should take it but says: %s", name, why);
    float *cpu[TB__K], *gpu[TB__K];
    tb__renders(env, s, false, 0, spp, 1000, cpu);
    tb__renders(env, s, true, 0, spp, 2000, gpu);
    tb__verdict v = tb__compare(gpu, cpu);
    tb__assert_equal(name, &v);
    tb__free(cpu);
    tb__free(gpu);
    tb_scene_free(s);
}

/* Bundled scene `name` on both backends: equal. */
static void tb__equivalent(gpu_test_env *env, const char *name, int spp)
{
    tb__equivalent_scene(env, tb__scene(name), name, spp);
}

static void test_cornell_box(void **state) { tb__equivalent(*state, "cornell-box.mid", TB__SPP); }
static void test_cornell_box_rgb(void **state) { tb__equivalent(*state, "cornell-box-rgb.mid", TB__SPP); }
static void test_radiosity_room(void **state) { tb__equivalent(*state, "radiosity-room.mid", TB__SPP); }
/* Mirror (normalised Phong, exponent 10000) and glass (smooth dielectric):
 * MIS of light samples and BSDF-sampled emission, delta lobes; twice the
 * samples, as the caustics make the image mean noisier (4 spp: standard
 * error 1.97%, at the bound). */
static void test_cornell_box_spheres(void **state)
{
    tb__equivalent(*state, "cornell-box-spheres.mid", 2 * TB__SPP);
}

/* Point, spot and directional lights, Phong and glass, and CSG trees with a
 * material per leaf among every primitive kind (tori, prisms, pyramids,
 * arches, conics). */
static void test_showcase(void **state) { tb__equivalent(*state, "showcase.mid", TB__SPP); }

/* Every lobe and emitter kind the kernel takes, where MIS matters: a
 * Lambert + Blinn floor (exponent 20), a Lambert + GGX wall (alpha 0.3), a
 * GGX metal sphere (alpha 0.2) and a Lambert + Phong sphere under a
 * quad and a small sphere emitter (the cone density in the emission
 * weight), a glass sphere with a diffuse part (Lambert beside a smooth
 * dielectric: lobe choice by weight). */
static void test_lobes(void **state)
{
    static const char text[] =
        "mid 1\n"
        "camera \"c\" { eye = [0 -6 3] look_at = [0 0 0.6] up = [0 0 1] fov = 45 resolution = [32 24] }\n"
        "polygons \"floor\" { geometry = { vertices = [[-4 -4 0] [4 -4 0] [4 4 0] [-4 4 0]] faces = [[0 1 2 3]] }\n"
        "  rendering = { diffuse = [0.4 0.35 0.3] specular = 0.3 exponent = 20 model = blinn } }\n"
        "polygons \"wall\" { geometry = { vertices = [[-4 3 0] [4 3 0] [4 3 5] [-4 3 5]] faces = [[0 1 2 3]] }\n"
        "  rendering = { diffuse = [0.3 0.5 0.3] specular = 0.1 model = ggx roughness = 0.3 } }\n"
        "polygons \"lamp\" { geometry = { vertices = [[-1 -1 4] [-1 1 4] [1 1 4] [1 -1 4]] faces = [[0 1 2 3]] }\n"
        "  rendering = { diffuse = 0 emission = [6 6 5] } }\n"
        "sphere \"bulb\" { transform = [scale(0.2) translate([0 1.5 1.8])] rendering = { diffuse = 0 emission = [20 15 10] } }\n"
        "sphere \"phong\" { transform = [scale(0.7) translate([-1.2 0.5 0.7])]\n"
        "  rendering = { diffuse = 0.15 specular = 0.7 exponent = 60 model = phong } }\n"
        "sphere \"glass\" { transform = [scale(0.6) translate([1.2 -0.3 0.6])]\n"
        "  rendering = { diffuse = 0.1 specular = 0.04 exponent = 1000 transmission = [0.9 0.95 1] ior = 1.5 } }\n"
        "sphere \"metal\" { transform = [scale(0.5) translate([0 -1.5 0.5])]\n"
        "  rendering = { diffuse = 0 specular = [0.95 0.64 0.54] model = ggx roughness = 0.2 } }\n";
    tb_scene *s = gpu_test_load(text, "lobes", NULL);
    tb__equivalent_scene(*state, s, "lobes (Blinn, Phong, GGX, glass, sphere lamp)", 2 * TB__SPP);
}

/* Point, spot (inside and across its smoothstep falloff) and directional
 * lights beside a quad lamp, on Lambert, Lambert + Phong and Lambert +
 * Blinn surfaces, a wall blocking part of the sun (shadow rays to infinity)
 * and a glass sphere (no light samples at its delta lobe). */
static void test_delta_lights(void **state)
{
    static const char text[] =
        "mid 1\n"
        "camera \"c\" { eye = [0 -6 3] look_at = [0 0 0.6] up = [0 0 1] fov = 45 resolution = [32 24] }\n"
        "directional_light \"sun\" { direction = [-0.4 0.6 -1] irradiance = [1 0.9 0.8] }\n"
        "point_light \"fill\" { position = [-3 -2 3] intensity = 6 }\n"
        "spot_light \"spot\" { position = [1 -1 4] direction = [0 0.3 -1] intensity = [30 25 20]\n"
        "  cone_angle = 25 cone_delta = 10 }\n"
        "polygons \"floor\" { geometry = { vertices = [[-4 -4 0] [4 -4 0] [4 4 0] [-4 4 0]] faces = [[0 1 2 3]] }\n"
        "  rendering = { diffuse = [0.5 0.45 0.4] specular = 0.2 exponent = 15 model = blinn } }\n"
        "polygons \"wall\" { geometry = { vertices = [[-4 3 0] [4 3 0] [4 3 5] [-4 3 5]] faces = [[0 1 2 3]] }\n"
        "  rendering = { diffuse = [0.3 0.5 0.3] } }\n"
        "polygons \"lamp\" { geometry = { vertices = [[-3 -1 3] [-3 0 3] [-2 0 3] [-2 -1 3]] faces = [[0 1 2 3]] }\n"
        "  rendering = { diffuse = 0 emission = [4 4 4] } }\n"
        "sphere \"phong\" { transform = [scale(0.7) translate([-1.2 0.5 0.7])]\n"
        "  rendering = { diffuse = 0.3 specular = 0.5 exponent = 40 model = phong } }\n"
        "sphere \"glass\" { transform = [scale(0.6) translate([1.2 -0.3 0.6])]\n"
        "  rendering = { diffuse = 0 specular = 0.04 exponent = 1000 transmission = 1 ior = 1.5 } }\n";
    tb_scene *s = gpu_test_load(text, "delta-lights", NULL);
    tb__equivalent_scene(*state, s, "delta lights (point, spot, directional)", TB__SPP);
}

/* Checker and noise patterns in (u, v) on polygons and spheres and in
 * object space on a sphere and a cube, noise bump maps in (u, v) on a
 * polygon and a sphere, GGX metals, the four models (the bundled scene
 * scenes/materials.mid). */
static void test_materials(void **state) { tb__equivalent(*state, "materials.mid", TB__SPP); }

/* The control for the patterns: the CPU's materials scene without its
 * patterns and bump maps (the materials' plain colours, as a kernel that
 * ignored them would render) is rejected against the GPU's with them, per
 * pixel and in the mean. */
static void test_materials_control(void **state)
{
    gpu_test_env *env = *state;
    tb_scene *s = tb__scene("materials.mid"), *plain = tb__scene("materials.mid");
    int patterned = 0;
    static const tb_material_pattern none = {.kind = TB_MID_PATTERN_NONE}; /* as the scene's own */
    for (int i = 0; i < plain->nmaterials; i++) {
        tb_material *m = &plain->materials[i];
        patterned += m->diffuse_pattern->kind != TB_MID_PATTERN_NONE || m->bump->kind != TB_MID_PATTERN_NONE;
        m->diffuse_pattern = m->specular_pattern = m->bump = &none;
    }
    assert_int_equal(patterned, 5); /* ground, wall, marble, solid checker, hammered */
    float *cpu[TB__K], *gpu[TB__K];
    tb__renders(env, plain, false, 0, TB__SPP, 6000, cpu);
    tb__renders(env, s, true, 0, TB__SPP, 7000, gpu);
    tb__verdict v = tb__compare(gpu, cpu);
    tb__print("control: GPU patterns vs CPU without", &v);
    assert_true(v.rejected > 0);
    assert_true(fabs(v.mean_z[0]) > 4.0 || fabs(v.mean_z[1]) > 4.0 || fabs(v.mean_z[2]) > 4.0);
    tb__free(cpu);
    tb__free(gpu);
    tb_scene_free(plain);
    tb_scene_free(s);
}

/* Largest differences of the kernel's surfaces from the CPU's. */
typedef struct tb__surf_err {
    double uv, n, colour; /* (u, v), shading normal, colours (absolute) */
    int hits, patterned, bumped, outliers;
} tb__surf_err;

/* The kernel's first-hit surfaces against tb_surface_at on a grid of nx x ny
 * camera rays of s (with their offset rays when `diffs`); a ray is an
 * outlier when (u, v) differ by more than 5e-5, the normal or a colour by
 * more than 5e-4 (float against double: measured at most 2.6e-6, 4.6e-5
 * and 2.7e-5). */
static tb__surf_err tb__surfaces(gpu_test_env *env, const tb_scene *s, int nx, int ny, bool diffs)
{
    tb_pt_options po = {.spp = TB__SPP};
    tb_gpu_pathtracer *gpt = NULL;
    tb_pathtracer *cpt = NULL;
    if (tb_gpu_pt_create(env->dev, s, &po, &gpt) || tb_pt_create(s, &po, &cpt))
        fail_msg("path tracer: %s", tb_last_error());
    const size_t n = (size_t)nx * (size_t)ny, nch = (size_t)s->nchannels, stride = 5 + 2 * nch;
    tb_ray *rays = malloc(3 * n * sizeof *rays);
    tb_vec3 *rd = malloc(4 * n * sizeof *rd);
    float *out = malloc(n * stride * sizeof *out);
    assert_true(rays && rd && out);
    for (size_t i = 0; i < n; i++) {
        /* film points off the pixel centres by an irrational step */
        const double x = ((double)(i % (size_t)nx) + 0.5 + 0.1234 * (double)(i % 7)) * s->camera.width / nx;
        const double y = ((double)(i / (size_t)nx) + 0.5 + 0.0617 * (double)(i % 5)) * s->camera.height / ny;
        tb_camera_ray_diff cd;
        tb_camera_ray_differential(&s->camera, x, y, 0.5f, 0.5f, &cd);
        rays[i] = cd.ray;
        rays[n + i] = (tb_ray){cd.rx_o, 0.0f, cd.rx_d, INFINITY};
        rays[2 * n + i] = (tb_ray){cd.ry_o, 0.0f, cd.ry_d, INFINITY};
        const tb_vec3 r4[4] = {cd.rx_o, cd.rx_d, cd.ry_o, cd.ry_d};
        memcpy(rd + 4 * i, r4, sizeof r4);
    }
    if (tb_gpu_pt_surfaces(gpt, rays, diffs ? rays + n : NULL, diffs ? rays + 2 * n : NULL, n, out))
        fail_msg("tb_gpu_pt_surfaces: %s", tb_last_error());
    gpu_assert_clean(env->inst);
    tb__surf_err e = {0};
    for (size_t i = 0; i < n; i++) {
        const float *o = out + i * stride;
        tb_hit hit;
        tb_surface sf;
        const bool hc = tb_scene_intersect(s, &rays[i], &hit) &&
                        tb_surface_at(tb_pt_surfaces(cpt), &rays[i], &hit, diffs ? rd + 4 * i : NULL, &sf);
        if (hc != !isnan(o[0])) {
            e.outliers++; /* a silhouette: one backend hit, the other missed */
            continue;
        }
        if (!hc)
            continue;
        e.hits++;
        const tb_material *m = &s->materials[sf.material];
        e.patterned += m->diffuse_pattern->kind != TB_MID_PATTERN_NONE;
        e.bumped += m->bump->kind != TB_MID_PATTERN_NONE;
        /* (u, v) on the device only where a pattern needs them */
        double duv = sf.has_tangents ? fmax(fabs(o[0] - sf.u), fabs(o[1] - sf.v)) : 0.0, dn = 0.0, dc = 0.0;
        const float nc[3] = {sf.n.x, sf.n.y, sf.n.z};
        for (int c = 0; c < 3; c++)
            dn = fmax(dn, fabs(o[2 + c] - nc[c]));
        for (size_t c = 0; c < nch; c++)
            dc = fmax(dc, fmax(fabs(o[5 + c] - sf.diffuse.v[c]), fabs(o[5 + nch + c] - sf.specular.v[c])));
        if (!(duv <= 5e-5 && dn <= 5e-4 && dc <= 5e-4)) {
            e.outliers++;
            continue;
        }
        e.uv = fmax(e.uv, duv), e.n = fmax(e.n, dn), e.colour = fmax(e.colour, dc);
    }
    printf("[ pt-equiv ] surfaces %s: %d hits (%d patterned, %d bumped), %d outliers; largest differences: "
           "(u, v) %.2g, normal %.2g, colour %.2g\n",
           diffs ? "with footprints" : "point sampled", e.hits, e.patterned, e.bumped, e.outliers, e.uv, e.n, e.colour);
    free(rays), free(rd), free(out);
    tb_gpu_pt_destroy(gpt);
    tb_pt_free(cpt);
    return e;
}

/* The kernel's patterns, bump maps, (u, v) and tangents against the CPU's
 * at 96 x 54 camera rays of the materials scene (at the test's 32 x 24
 * pixels, so that the footprints span several checker cells): every hit
 * within the tolerances of tb__surfaces but at most 1 % (edges of objects
 * and, point sampled, of checker cells, where float and double may round
 * to different sides; none measured). */
static void test_surfaces(void **state)
{
    gpu_test_env *env = *state;
    tb_scene *s = tb__scene("materials.mid");
    for (int d = 1; d >= 0; d--) {
        tb__surf_err e = tb__surfaces(env, s, 96, 54, d != 0);
        assert_true(e.hits > 3000 && e.patterned > 1500 && e.bumped > 300); /* the test sees the patterns */
        assert_true(e.outliers <= e.hits / 100);
    }
    tb_scene_free(s);
}

/* The controls on the RGB Cornell box: direct light only on both backends
 * agrees; the CPU's direct light against the GPU's full render is rejected
 * per pixel and in the mean. */
static void test_controls(void **state)
{
    gpu_test_env *env = *state;
    tb_scene *s = tb__scene("cornell-box-rgb.mid");
    float *cpu1[TB__K], *gpu1[TB__K], *gpu[TB__K];
    tb__renders(env, s, false, 1, TB__SPP, 3000, cpu1);
    tb__renders(env, s, true, 1, TB__SPP, 4000, gpu1);
    tb__renders(env, s, true, 0, TB__SPP, 5000, gpu);
    tb__verdict v = tb__compare(gpu1, cpu1);
    tb__assert_equal("cornell-box-rgb.mid, max depth 1", &v);
    v = tb__compare(gpu, cpu1);
    tb__print("control: GPU full vs CPU direct only", &v);
    assert_true(v.rejected > 0);
    assert_true(fabs(v.mean_z[0]) > 4.0 && fabs(v.mean_z[1]) > 4.0 && fabs(v.mean_z[2]) > 4.0);
    tb__free(cpu1);
    tb__free(gpu1);
    tb__free(gpu);
    tb_scene_free(s);
}

/* The scenes with features outside the kernel are refused with the reason. */
static void test_refused(void **state)
{
    gpu_test_env *env = *state;
    static const struct {
        const char *scene, *why;
    } cases[] = {
        {"torus", "patterns or bump maps on objects other than spheres, cubes and polygons"},
        {"image bump", "bump maps from images"},
    };
    static const char *const texts[] = {
        "mid 1.1\ncamera \"c\" { eye = [0 -6 3] look_at = [0 0 0] up = [0 0 1] fov = 45 resolution = [8 8] }\n"
        "point_light \"l\" { position = [0 -3 4] intensity = 10 }\n"
        "torus \"t\" { geometry = { major = 1 minor = 0.3 }\n"
        "  rendering = { diffuse = 0.5 diffuse_pattern = checker(8, 0.2, 0.8) } }\n",
        "mid 1.1\ncamera \"c\" { eye = [0 -6 3] look_at = [0 0 0] up = [0 0 1] fov = 45 resolution = [8 8] }\n"
        "point_light \"l\" { position = [0 -3 4] intensity = 10 }\n"
        "sphere \"s\" { rendering = { diffuse = 0.5 bump = image(file(\"grey.pgm\"), 0.01) } }\n",
    };
    /* the bump image, in a directory of its own */
    char dir[] = "/tmp/tb_pt_equiv_XXXXXX", img_path[64];
    assert_non_null(mkdtemp(dir));
    snprintf(img_path, sizeof img_path, "%s/grey.pgm", dir);
    FILE *fp = fopen(img_path, "w");
    assert_non_null(fp);
    fputs("P2\n2 2\n255\n0 255\n255 0\n", fp);
    fclose(fp);
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        tb_scene *s = gpu_test_load(texts[i], cases[i].scene, dir);
        const char *why = tb_gpu_pt_unsupported(s);
        printf("[ pt-equiv ] %-44s refused: %s\n", cases[i].scene, why ? why : "(not refused)");
        assert_non_null(why);
        tb_render_options ro = tb_render_defaults();
        ro.aa.spp = 1;
        ro.progress = false;
        tb_image *img = NULL;
        gpu_assert_error(tb_gpu_render_path(env->dev, s, NULL, &ro, &img, NULL, NULL), TB_ERR_UNSUPPORTED,
                         cases[i].why);
        assert_null(img);
        tb_scene_free(s);
    }
    remove(img_path);
    remove(dir);
}

/* A patterned polygon whose (u, v) the kernel cannot reproduce (texture
 * coordinates past 1, which the CPU clamps: not affine over the face) is
 * refused when the tables are built, naming the object and face. */
static void test_refused_uv(void **state)
{
    gpu_test_env *env = *state;
    static const char text[] =
        "mid 1.1\ncamera \"c\" { eye = [0 -6 3] look_at = [0 0 0] up = [0 0 1] fov = 45 resolution = [8 8] }\n"
        "point_light \"l\" { position = [0 -3 4] intensity = 10 }\n"
        "polygons \"p\" { geometry = { vertices = [[-2 -2 0] [2 -2 0] [2 2 0] [-2 2 0]] faces = [[0 1 2 3]]\n"
        "  uvs = [[0 0] [2 0] [2 2] [0 2]] } rendering = { diffuse = 0.5 diffuse_pattern = checker(4, 0.2, 0.8) } }\n";
    tb_scene *s = gpu_test_load(text, "uv past 1", NULL);
    assert_null(tb_gpu_pt_unsupported(s));
    tb_render_options ro = tb_render_defaults();
    ro.aa.spp = 1;
    ro.progress = false;
    tb_image *img = NULL;
    gpu_assert_error(tb_gpu_render_path(env->dev, s, NULL, &ro, &img, NULL, NULL), TB_ERR_UNSUPPORTED,
                     "object 0, face 0: its (u, v) is not an affine map over the face");
    assert_null(img);
    tb_scene_free(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_t_pvalue),       cmocka_unit_test(test_cornell_box),
        cmocka_unit_test(test_cornell_box_rgb), cmocka_unit_test(test_radiosity_room),
        cmocka_unit_test(test_cornell_box_spheres), cmocka_unit_test(test_showcase), cmocka_unit_test(test_lobes),
        cmocka_unit_test(test_delta_lights),
        cmocka_unit_test(test_materials),      cmocka_unit_test(test_materials_control),
        cmocka_unit_test(test_surfaces),
        cmocka_unit_test(test_controls),       cmocka_unit_test(test_refused),
        cmocka_unit_test(test_refused_uv),
    };
    return cmocka_run_group_tests(tests, gpu_test_setup, gpu_test_teardown);
}
