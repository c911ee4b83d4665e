/* Paired kernel tests of the shade kernel's GLSL routines (shaders/lib/ggx.glsl,
 * shaders/lib/pattern.glsl) against the C functions they mirror
 * (host/render/shading.c, texture_proc.c): the GGX D, Smith Lambda, visible
 * normal sampling and its density, the Schlick lobe's value, Perlin noise,
 * fBm, and the box-filtered checkerboards, on exactly representable edge
 * inputs and on seeded random ones. The C code works in double, the GLSL in
 * float: the bounds are those docs/gpu.md states ("GLSL routine library");
 * the worst differences are printed. Validation layer on; any message fails. */
#include "gpu_test.h"

#include <math.h>

#include "host/render/shading.h"
#include "host/render/sampling.h"
#include "host/render/texture.h"
#include "kernels/cases.h"
#include "util/image/image.h"
#include "util/math/rng.h"

enum { OP_D, OP_LAMBDA, OP_SAMPLE, OP_PDF, OP_EVAL, OP_NOISE, OP_FBM, OP_CHECKER, OP_CHECKER3, OP_TEX, OP_COUNT };

static gpu_test_env g_env;
static tb_gpu_kernel *g_k[OP_COUNT];
static tb_gpu_buffer *g_perm;
static tb_gpu_buffer *g_texinfo, *g_texels; /* the texture of test_texture (a placeholder before) */

static int setup(void **state)
{
    (void)state;
    gpu_test_open(&g_env, NULL);
    for (int op = 0; op < OP_COUNT; op++) {
        tb_gpu_spec_constant spec = {1, (uint32_t)op};
        g_k[op] = tb_gpu_kernel_get(g_env.dev, &(tb_gpu_kernel_desc){.spirv = gpu_test_kernel("k_shading"),
                                                                      .buffers = 5,
                                                                      .push_size = 4,
                                                                      .spec = &spec,
                                                                      .spec_count = 1});
        if (!g_k[op]) {
            print_error("k_shading %d: %s\n", op, tb_last_error());
            return -1;
        }
    }
    float perm[256];
    for (int i = 0; i < 256; i++)
        perm[i] = (float)tb_noise_permutation()[i];
    g_perm = tb_gpu_buffer_create(g_env.dev, sizeof perm);
    if (!g_perm || tb_gpu_buffer_upload(g_perm, 0, perm, sizeof perm))
        return -1;
    g_texinfo = tb_gpu_buffer_create(g_env.dev, 16);
    g_texels = tb_gpu_buffer_create(g_env.dev, 16);
    return g_texinfo && g_texels ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    tb_gpu_buffer_destroy(g_perm);
    tb_gpu_buffer_destroy(g_texinfo);
    tb_gpu_buffer_destroy(g_texels);
    gpu_test_close(&g_env);
    return 0;
}

/* Runs routine op on n cases. */
static void run(int op, const tb_case_f8 *in, tb_case_f4 *out, uint32_t n)
{
    tb_gpu_buffer *bi = tb_gpu_buffer_create(g_env.dev, n * sizeof *in);
    tb_gpu_buffer *bo = tb_gpu_buffer_create(g_env.dev, n * sizeof *out);
    assert_true(bi && bo);
    tb_gpu_dispatch d = {.kernel = g_k[op], .buffers = {bi, bo, g_perm, g_texinfo, g_texels}, .push = &n, .items = n};
    if (tb_gpu_buffer_upload(bi, 0, in, n * sizeof *in) || tb_gpu_run(g_env.dev, &d, 1) ||
        tb_gpu_buffer_download(bo, 0, out, n * sizeof *out))
        fail_msg("k_shading %d: %s", op, tb_last_error());
    tb_gpu_buffer_destroy(bi);
    tb_gpu_buffer_destroy(bo);
    gpu_assert_clean(g_env.inst);
}

static float rnd(tb_rng *r, float lo, float hi) { return lo + (hi - lo) * tb_rng_float(r); }

/* A random unit vector (z >= 0 when `upper`), rounded to float. */
static tb_vec3 rnd_dir(tb_rng *r, bool upper)
{
    tb_vec3 w = tb_sample_uniform_sphere(tb_rng_float(r), tb_rng_float(r));
    if (upper && w.z < 0.0f)
        w.z = -w.z;
    return w;
}

/* A GGX width: a few exact ones, then random over [1e-3, 1]. */
static float rnd_alpha(tb_rng *r, int i)
{
    static const float exact[] = {1.0f, 0.5f, 0.25f, 0.125f, 0x1p-7f, 1e-3f};
    return i < 6 ? exact[i] : (float)exp2(rnd(r, -9.9f, 0.0f));
}

#define N 4096

static void test_ggx(void **state)
{
    (void)state;
    tb_case_f8 *in = calloc(N, sizeof *in);
    tb_case_f4 *out = calloc(N, sizeof *out);
    assert_true(in && out);
    tb_rng rng;
    tb_rng_seed(&rng, 61, 3);
    for (int i = 0; i < N; i++) {
        float a = rnd_alpha(&rng, i % 16);
        tb_vec3 v1 = rnd_dir(&rng, true), v2 = rnd_dir(&rng, true);
        if (i < 8) /* the poles and grazing: exact inputs */
            v1 = (tb_vec3){0.0f, 0.0f, 1.0f}, v2 = i < 4 ? (tb_vec3){0.6f, 0.0f, 0.8f} : (tb_vec3){0.0f, 0.6f, 0.8f};
        in[i] = (tb_case_f8){a, v1.x, v1.y, v1.z, v2.x, v2.y, v2.z, 0};
    }
    double wD = 0, wL = 0, wS = 0, wP = 0, wE = 0, wF = 0, wEP = 0;
    /* D and Lambda: relative 2e-6 */
    run(OP_D, in, out, N);
    for (int i = 0; i < N; i++) {
        double c = tb_ggx_D(in[i].a, (tb_vec3){in[i].b, in[i].c, in[i].d});
        double rel = fabs(out[i].x - c) / c;
        if (!(rel <= 2e-6))
            fail_msg("D(%a, %a %a %a): GPU %.9g, C %.9g", in[i].a, in[i].b, in[i].c, in[i].d, out[i].x, c);
        wD = fmax(wD, rel);
    }
    run(OP_LAMBDA, in, out, N);
    for (int i = 0; i < N; i++) {
        double c = tb_ggx_lambda(in[i].a, (tb_vec3){in[i].b, in[i].c, in[i].d});
        double rel = fabs(out[i].x - c) / fmax(c, 1e-30);
        if (!(rel <= 2e-6) && !(c == 0.0 && out[i].x == 0.0f))
            fail_msg("Lambda(%a, %a %a %a): GPU %.9g, C %.9g", in[i].a, in[i].b, in[i].c, in[i].d, out[i].x, c);
        wL = fmax(wL, c > 0 ? rel : 0);
    }
    /* VNDF samples (u1 up to 0.99: nearer the visible disc's rim a float
     * sqrt(1 - p1^2 - p2^2) loses digits), their density, and the lobe */
    for (int i = 0; i < N; i++) {
        in[i].e = i < 8 ? (float)(i % 4) * 0.25f : rnd(&rng, 0.0f, 0.99f);
        in[i].f = i < 8 ? 0.5f : tb_rng_float(&rng);
    }
    run(OP_SAMPLE, in, out, N);
    for (int i = 0; i < N; i++) {
        tb_vec3 c = tb_ggx_sample_vndf(in[i].a, (tb_vec3){in[i].b, in[i].c, in[i].d}, in[i].e, in[i].f);
        double d = fmax(fabs(out[i].x - c.x), fmax(fabs(out[i].y - c.y), fabs(out[i].z - c.z)));
        if (!(d <= 2e-5))
            fail_msg("sample_vndf(%a, %a %a %a, %a %a): GPU %.9g %.9g %.9g, C %.9g %.9g %.9g", in[i].a, in[i].b,
                     in[i].c, in[i].d, in[i].e, in[i].f, out[i].x, out[i].y, out[i].z, c.x, c.y, c.z);
        wS = fmax(wS, d);
    }
    /* density and lobe at m = the sampled normal's neighbour v2 */
    run(OP_PDF, in, out, N);
    for (int i = 0; i < N; i++) {
        double c = tb_ggx_vndf_pdf(in[i].a, (tb_vec3){in[i].b, in[i].c, in[i].d}, (tb_vec3){in[i].e, in[i].f, in[i].g});
        double rel = fabs(out[i].x - c) / fmax(c, 1e-30);
        if (!(rel <= 1e-4) && !(c == 0.0 && out[i].x == 0.0f))
            fail_msg("vndf_pdf(%a, %a %a %a, %a %a %a): GPU %.9g, C %.9g", in[i].a, in[i].b, in[i].c, in[i].d,
                     in[i].e, in[i].f, in[i].g, out[i].x, c);
        wP = fmax(wP, c > 0 ? rel : 0);
    }
    for (int i = 0; i < N; i++) { /* wi anywhere: the other side gives 0 */
        tb_vec3 v2 = rnd_dir(&rng, i % 8 != 0);
        in[i].e = v2.x, in[i].f = v2.y, in[i].g = v2.z;
    }
    run(OP_EVAL, in, out, N);
    const tb_channels one = tb_channels_splat(1, 1.0f), zero = tb_channels_splat(1, 0.0f);
    for (int i = 0; i < N; i++) {
        tb_vec3 wo = {in[i].b, in[i].c, in[i].d}, wi = {in[i].e, in[i].f, in[i].g};
        /* Schlick with F0 = 1 is 1 (the scalar alone), with F0 = 0 it is m^5 */
        tb_bsdf b1 = tb_bsdf_ggx(one, in[i].a, TB_FRESNEL_SCHLICK, 1.0),
                b0 = tb_bsdf_ggx(zero, in[i].a, TB_FRESNEL_SCHLICK, 1.0);
        double f1 = tb_bsdf_eval(&b1, wo, wi).v[0], f0 = tb_bsdf_eval(&b0, wo, wi).v[0], pdf = tb_bsdf_pdf(&b1, wo, wi);
        double g = out[i].x, gm = out[i].y, gp = out[i].z;
        double rel = fabs(g - f1) / fmax(f1, 1e-30), drel = fabs(gp - pdf) / fmax(pdf, 1e-30);
        double dm = f1 > 0 ? fabs(gm - f0 / f1) : 0.0;
        if (!((rel <= 1e-4 || (f1 == 0.0 && g == 0.0)) && dm <= 1e-5 && (drel <= 1e-4 || (pdf == 0.0 && gp == 0.0))))
            fail_msg("eval(%a, %a %a %a, %a %a %a): GPU %.9g %.9g %.9g, C %.9g %.9g %.9g", in[i].a, in[i].b, in[i].c,
                     in[i].d, in[i].e, in[i].f, in[i].g, g, gm, gp, f1, f1 > 0 ? f0 / f1 : 0.0, pdf);
        wE = fmax(wE, f1 > 0 ? rel : 0);
        wF = fmax(wF, dm);
        wEP = fmax(wEP, pdf > 0 ? drel : 0);
    }
    print_message("[ info     ] GGX worst: D %.2g, Lambda %.2g relative (bound 2e-6); sample %.2g absolute (2e-5); "
                  "vndf pdf %.2g, lobe %.2g, lobe pdf %.2g relative (1e-4); Schlick m^5 %.2g absolute (1e-5)\n",
                  wD, wL, wS, wP, wE, wEP, wF);
    free(in);
    free(out);
}

static void test_noise(void **state)
{
    (void)state;
    tb_case_f8 *in = calloc(N, sizeof *in);
    tb_case_f4 *out = calloc(N, sizeof *out);
    assert_true(in && out);
    tb_rng rng;
    tb_rng_seed(&rng, 62, 3);
    for (int i = 0; i < N; i++) {
        if (i < 27) /* lattice points (noise 0) and half-cells: exact */
            in[i] = (tb_case_f8){(float)(i % 3) * 0.5f - 1.0f, (float)(i / 3 % 3) * 0.5f, (float)(i / 9) * 0.5f + 3.0f,
                                 0, 0, 0, 0, 0};
        else
            in[i] = (tb_case_f8){rnd(&rng, -60, 60), rnd(&rng, -60, 60), rnd(&rng, -60, 60), 0, 0, 0, 0, 0};
    }
    run(OP_NOISE, in, out, N);
    double wn = 0;
    for (int i = 0; i < N; i++) {
        double c = tb_noise3(in[i].a, in[i].b, in[i].c), d = fabs(out[i].x - c);
        if (!(d <= 4e-6))
            fail_msg("noise3(%a, %a, %a): GPU %.9g, C %.9g", in[i].a, in[i].b, in[i].c, out[i].x, c);
        if (i < 27 && fmodf(in[i].a, 1.0f) == 0.0f && fmodf(in[i].b, 1.0f) == 0.0f && fmodf(in[i].c, 1.0f) == 0.0f)
            assert_true(out[i].x == 0.0f);
        wn = fmax(wn, d);
    }
    /* fBm over |p| < 8 with footprints from none (all octaves) to a cell
     * (none): every partial-octave fade */
    for (int i = 0; i < N; i++) {
        float fx = i % 4 == 0 ? 0.0f : (float)exp2(rnd(&rng, -10.0f, 1.0f));
        in[i] = (tb_case_f8){rnd(&rng, -8, 8), rnd(&rng, -8, 8), rnd(&rng, -8, 8), fx, 0.5f * fx, 0.0f,
                             (float)(1 + (int)tb_rng_below(&rng, 8)), 0};
    }
    run(OP_FBM, in, out, N);
    double wf = 0;
    for (int i = 0; i < N; i++) {
        tb_dvec3 p = {in[i].a, in[i].b, in[i].c}, dx = {in[i].d, in[i].e, in[i].f}, dy = {0, 0, 0};
        double c = tb_fbm3(p, dx, dy, 0.5, (int)in[i].g), d = fabs(out[i].x - c);
        if (!(d <= 1e-5))
            fail_msg("fbm3(%a %a %a, %a %a, %d): GPU %.9g, C %.9g", in[i].a, in[i].b, in[i].c, in[i].d, in[i].e,
                     (int)in[i].g, out[i].x, c);
        wf = fmax(wf, d);
    }
    print_message("[ info     ] noise worst |diff| %.2g (bound 4e-6), fBm %.2g (bound 1e-5)\n", wn, wf);
    free(in);
    free(out);
}

static void test_checker(void **state)
{
    (void)state;
    tb_case_f8 *in = calloc(N, sizeof *in);
    tb_case_f4 *out = calloc(N, sizeof *out);
    assert_true(in && out);
    tb_rng rng;
    tb_rng_seed(&rng, 63, 3);
    for (int i = 0; i < N; i++) {
        float s = rnd(&rng, -100, 100), t = rnd(&rng, -100, 100), z = rnd(&rng, -100, 100);
        /* a quarter point-sampled, the rest boxes from 1e-3 to 4 cells */
        float hs = i % 4 == 0 ? 0.0f : (float)exp2(rnd(&rng, -10, 2)),
              ht = i % 4 == 0 ? 0.0f : (float)exp2(rnd(&rng, -10, 2));
        float hz = i % 4 == 0 ? 0.0f : (float)exp2(rnd(&rng, -10, 2));
        if (i < 16) /* whole cells: exact halves and quarters */
            s = (float)(i % 4) - 1.5f, t = (float)(i / 4) + 0.5f, hs = 1.0f, ht = 0.5f, z = 0.25f, hz = 0.0f;
        in[i] = (tb_case_f8){s - hs, s + hs, t - ht, t + ht, z - hz, z + hz, 0, 0};
    }
    run(OP_CHECKER, in, out, N);
    double w2 = 0, w3 = 0;
    for (int i = 0; i < N; i++) {
        double c = tb_checker_box_average(in[i].a, in[i].b, in[i].c, in[i].d), d = fabs(out[i].x - c);
        if (!(d <= 1e-6))
            fail_msg("checker(%a %a %a %a): GPU %.9g, C %.9g", in[i].a, in[i].b, in[i].c, in[i].d, out[i].x, c);
        if (i < 16)
            assert_true(out[i].x == (float)c);
        w2 = fmax(w2, d);
    }
    /* checker3 takes (x0, y0, z0), (x1, y1, z1) */
    tb_case_f8 *in3 = calloc(N, sizeof *in3);
    assert_true(in3);
    for (int i = 0; i < N; i++)
        in3[i] = (tb_case_f8){in[i].a, in[i].c, in[i].e, in[i].b, in[i].d, in[i].f, 0, 0};
    run(OP_CHECKER3, in3, out, N);
    for (int i = 0; i < N; i++) {
        double c = tb_checker3_box_average(in[i].a, in[i].b, in[i].c, in[i].d, in[i].e, in[i].f);
        double d = fabs(out[i].x - c);
        if (!(d <= 1e-6))
            fail_msg("checker3(%a %a, %a %a, %a %a): GPU %.9g, C %.9g", in[i].a, in[i].b, in[i].c, in[i].d, in[i].e,
                     in[i].f, out[i].x, c);
        w3 = fmax(w3, d);
    }
    print_message("[ info     ] checker worst |diff| %.2g, checker3 %.2g (bound 1e-6)\n", w2, w3);
    free(in);
    free(in3);
    free(out);
}

/* MIP-map lookups of a 37 x 23 RGB image (odd sizes: 3-tap reductions,
 * non-square levels) with every filter, at random (u, v) (outside [0, 1]
 * too: the repeat wrap) and footprints from none to many texels, long
 * ones (the anisotropy clamp) and degenerate ones, against tb_mipmap_lookup. */
static void test_texture(void **state)
{
    (void)state;
    tb_image *img = tb_image_create(37, 23, 3, NULL);
    assert_non_null(img);
    tb_rng rng;
    tb_rng_seed(&rng, 64, 3);
    for (int i = 0; i < 37 * 23 * 3; i++)
        img->pixels[i] = tb_rng_float(&rng);
    tb_mipmap *m = tb_mipmap_create(img);
    assert_non_null(m);
    /* the record and the texels, as host/gpu/render.c lays them out */
    uint32_t info[4 + 3 * 16];
    size_t nt = 0;
    for (int l = 0; l < m->nlevels; l++)
        nt += (size_t)m->levels[l].width * (size_t)m->levels[l].height * 3;
    float *tx = malloc(nt * sizeof *tx);
    assert_true(tx && m->nlevels <= 16);
    info[0] = 3, info[1] = (uint32_t)m->nlevels, info[2] = 37, info[3] = 23;
    nt = 0;
    for (int l = 0; l < m->nlevels; l++) {
        size_t n = (size_t)m->levels[l].width * (size_t)m->levels[l].height * 3;
        info[4 + 3 * l] = (uint32_t)m->levels[l].width;
        info[5 + 3 * l] = (uint32_t)m->levels[l].height;
        info[6 + 3 * l] = (uint32_t)nt;
        memcpy(tx + nt, m->levels[l].texels, n * sizeof *tx);
        nt += n;
    }
    tb_gpu_buffer_destroy(g_texinfo);
    tb_gpu_buffer_destroy(g_texels);
    g_texinfo = tb_gpu_buffer_create(g_env.dev, sizeof info);
    g_texels = tb_gpu_buffer_create(g_env.dev, nt * sizeof *tx);
    assert_true(g_texinfo && g_texels);
    assert_int_equal(tb_gpu_buffer_upload(g_texinfo, 0, info, sizeof info), TB_OK);
    assert_int_equal(tb_gpu_buffer_upload(g_texels, 0, tx, nt * sizeof *tx), TB_OK);
    tb_case_f8 *in = calloc(N, sizeof *in);
    tb_case_f4 *out = calloc(N, sizeof *out);
    assert_true(in && out);
    for (int i = 0; i < N; i++) {
        float u = rnd(&rng, -0.5f, 1.5f), v = rnd(&rng, -0.5f, 1.5f);
        /* footprint: none, isotropic, or long (up to 64 texels one way) */
        float s = i % 5 == 0 ? 0.0f : (float)exp2(rnd(&rng, -10.0f, 1.0f));
        float ang = rnd(&rng, 0.0f, 6.2831853f), e = i % 3 == 0 ? rnd(&rng, 0.0f, 0.1f) : rnd(&rng, 0.2f, 1.0f);
        in[i] = (tb_case_f8){u, v, s * cosf(ang), s * sinf(ang), -e * s * sinf(ang), e * s * cosf(ang), 0.0f,
                             (float)(i % 4)};
    }
    run(OP_TEX, in, out, N);
    double worst[4] = {0};
    for (int i = 0; i < N; i++) {
        float c[4];
        tb_tex_footprint fp = {in[i].c, in[i].d, in[i].e, in[i].f};
        tb_mipmap_lookup(m, (tb_tex_filter)(int)in[i].h, in[i].a, in[i].b, &fp, TB_TEX_REPEAT, TB_TEX_MAX_ANISO_DEFAULT,
                         c);
        const float *g = &out[i].x;
        double d = 0;
        for (int k = 0; k < 3; k++)
            d = fmax(d, fabs((double)g[k] - c[k]));
        /* nearest: the same texel (exact) but where u w or (1 - v) h rounds
         * across a texel edge in float; the filters within 1e-5 */
        int f = (int)in[i].h;
        if (!(d <= (f == 0 ? 0.0 : 1e-5)))
            fail_msg("lookup filter %d at (%a, %a), fp %a %a %a %a: GPU %.9g %.9g %.9g, C %.9g %.9g %.9g", f, in[i].a,
                     in[i].b, in[i].c, in[i].d, in[i].e, in[i].f, g[0], g[1], g[2], c[0], c[1], c[2]);
        worst[f] = fmax(worst[f], d);
    }
    print_message("[ info     ] texture lookups worst |diff|: nearest %.2g (bound 0), bilinear %.2g, trilinear %.2g, "
                  "EWA %.2g (bound 1e-5)\n",
                  worst[0], worst[1], worst[2], worst[3]);
    free(in);
    free(out);
    free(tx);
    tb_mipmap_free(m);
    tb_image_free(img);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ggx),
        cmocka_unit_test(test_noise),
        cmocka_unit_test(test_checker),
        cmocka_unit_test(test_texture),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
