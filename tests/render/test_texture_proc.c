/* Procedural textures, bump mapping, ray-differential footprints and the
 * texture cache: the checker's closed-form box average against brute-force
 * integration; improved noise is deterministic, zero on the lattice with
 * gradients of length sqrt(2) there, periodic and in range; fBm drops the
 * octaves the footprint cannot resolve; bump mapping on linear height fields
 * over a plane and a cylinder gives the analytic displaced normal; the
 * footprint solves dp = du dp/du + dv dp/dv for offset rays; the cache loads
 * each file once. */
#include "tb_test.h"

#include <string.h>
#include <unistd.h>
#include <sys/stat.h>

#include "host/render/texture.h"
#include "util/math/float.h"

/* ---------------------------------------------------------------- checker */

/* The point checker (1 where floor(s) + floor(t) is odd). */
static int point_checker(double s, double t)
{
    long k = (long)floor(s) + (long)floor(t);
    return (int)(k & 1);
}

static void test_checker_box(void **state)
{
    (void)state;
    /* by hand */
    tb_assert_near(tb_checker_box_average(0, 2, 0, 1), 0.5, 1e-15);
    tb_assert_near(tb_checker_box_average(0.5, 1.5, 0, 1), 0.5, 1e-15);
    tb_assert_near(tb_checker_box_average(0, 1, 0, 1), 0.0, 1e-15);
    tb_assert_near(tb_checker_box_average(1, 2, 0, 1), 1.0, 1e-15);
    tb_assert_near(tb_checker_box_average(0.25, 1.25, 0.5, 0.75), 0.25, 1e-15);
    tb_assert_near(tb_checker_box_average(-1.0, -0.5, 0.2, 0.3), 1.0, 1e-15);
    /* point samples */
    tb_assert_near(tb_checker_box_average(-0.5, -0.5, 0.5, 0.5), 1.0, 0.0);
    tb_assert_near(tb_checker_box_average(2.5, 2.5, 3.5, 3.5), 1.0, 0.0);
    tb_assert_near(tb_checker_box_average(2.5, 2.5, 2.5, 2.5), 0.0, 0.0);
    /* random boxes against a 400 x 400 midpoint grid of point samples: the
     * grid's error is at most the fraction of grid cells crossed by square
     * edges, about (edges crossed) / 400 per axis */
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("checker box", 12), 0);
    for (int k = 0; k < 200; k++) {
        double s0 = 20.0 * tb_rng_double(&rng) - 10.0, t0 = 20.0 * tb_rng_double(&rng) - 10.0;
        double ws = 4.0 * tb_rng_double(&rng), wt = 4.0 * tb_rng_double(&rng);
        int n = 400, hits = 0;
        for (int i = 0; i < n; i++)
            for (int j = 0; j < n; j++)
                hits += point_checker(s0 + (i + 0.5) * ws / n, t0 + (j + 0.5) * wt / n);
        double grid = (double)hits / (n * n);
        double tol = (ceil(ws) + ceil(wt) + 2.0) / n;
        tb_assert_near(tb_checker_box_average(s0, s0 + ws, t0, t0 + wt), grid, tol);
    }
    /* a wide box is grey: avg - 1/2 = -2 (fs - 1/2)(ft - 1/2), each factor
     * at most 1 / (2 width) */
    for (int k = 0; k < 1000; k++) {
        double s0 = 1000.0 * tb_rng_double(&rng), ws = 3.0 + 50.0 * tb_rng_double(&rng);
        double t0 = 1000.0 * tb_rng_double(&rng), wt = 0.01 + 5.0 * tb_rng_double(&rng);
        double avg = tb_checker_box_average(s0, s0 + ws, t0, t0 + wt);
        assert_true(fabs(avg - 0.5) <= 2.0 * (1.0 / (2.0 * ws)) * 0.5 + 1e-12);
    }
    /* through a texture: unfiltered = point sample; filtered with a zero
     * footprint = point sample; filtered wide = grey; mapping scales */
    const float black[3] = {0, 0, 0}, white[3] = {1, 1, 1};
    tb_texture pt = tb_texture_checker(3, black, white, false);
    tb_texture ft = tb_texture_checker(3, black, white, true);
    pt.su = pt.sv = ft.su = ft.sv = 8.0f;
    for (int k = 0; k < 1000; k++) {
        tb_tex_query q = {.u = tb_rng_float(&rng), .v = tb_rng_float(&rng)};
        float a[3], b[3];
        tb_texture_eval(&pt, &q, a);
        tb_texture_eval(&ft, &q, b);
        assert_true(a[0] == (float)point_checker(8.0 * q.u, 8.0 * q.v) && a[0] == b[0] && a[2] == b[2]);
        q.fp = (tb_tex_footprint){0.5f, 0.0f, 0.0f, 0.5f}; /* 4 squares per pixel */
        tb_texture_eval(&ft, &q, b);
        tb_assert_near(b[1], 0.5, 2.0 * (1.0 / 8.0) * (1.0 / 8.0) + 1e-6);
    }
}

/* ---------------------------------------------------------------- noise */

/* The 3D checker: by hand, against a brute-force grid for random boxes, and
 * through a solid texture (point sample, object-space scale, filtered box
 * from the point's change per pixel). */
static void test_checker3_box(void **state)
{
    (void)state;
    tb_assert_near(tb_checker3_box_average(0, 1, 0, 1, 0, 1), 0.0, 1e-15);
    tb_assert_near(tb_checker3_box_average(1, 2, 0, 1, 0, 1), 1.0, 1e-15);
    tb_assert_near(tb_checker3_box_average(1, 2, 1, 2, 1, 2), 1.0, 1e-15);
    tb_assert_near(tb_checker3_box_average(0, 2, 0, 1, 0, 1), 0.5, 1e-15);
    tb_assert_near(tb_checker3_box_average(-0.5, -0.5, 0.5, 0.5, 0.5, 0.5), 1.0, 0.0);
    tb_assert_near(tb_checker3_box_average(-0.5, -0.5, -0.5, -0.5, 0.5, 0.5), 0.0, 0.0);
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("checker3 box", 13), 0);
    for (int k = 0; k < 40; k++) {
        double o[3], w[3];
        for (int a = 0; a < 3; a++) {
            o[a] = 20.0 * tb_rng_double(&rng) - 10.0;
            w[a] = 3.0 * tb_rng_double(&rng);
        }
        int n = 60, hits = 0;
        for (int i = 0; i < n; i++)
            for (int j = 0; j < n; j++)
                for (int l = 0; l < n; l++) {
                    double x = o[0] + (i + 0.5) * w[0] / n, y = o[1] + (j + 0.5) * w[1] / n,
                           z = o[2] + (l + 0.5) * w[2] / n;
                    hits += ((long)floor(x) + (long)floor(y) + (long)floor(z)) & 1;
                }
        double grid = (double)hits / ((double)n * n * n);
        double tol = (ceil(w[0]) + ceil(w[1]) + ceil(w[2]) + 3.0) / n;
        tb_assert_near(tb_checker3_box_average(o[0], o[0] + w[0], o[1], o[1] + w[1], o[2], o[2] + w[2]), grid, tol);
    }
    const float zero = 0.0f, one = 1.0f;
    tb_texture t = tb_texture_checker(1, &zero, &one, true);
    t.solid = true;
    t.su = 2.0f;
    tb_tex_query q = {.p = {0.6f, 0.1f, 0.1f}}; /* cells (1, 0, 0): odd */
    tb_assert_near(tb_texture_eval1(&t, &q), 1.0, 0.0);
    q.p = (tb_vec3){0.6f, 0.6f, 0.1f}; /* (1, 1, 0): even */
    tb_assert_near(tb_texture_eval1(&t, &q), 0.0, 0.0);
    /* a pixel spanning 4 cells in x and 3 in z: the closed form of that box */
    q.p = (tb_vec3){0.3f, 0.2f, 0.7f};
    q.dpdx = (tb_vec3){1.0f, 0.0f, 0.0f};
    q.dpdy = (tb_vec3){0.5f, 0.0f, 1.5f};
    double want = tb_checker3_box_average(0.6 - 1.5, 0.6 + 1.5, 0.4, 0.4, 1.4 - 1.5, 1.4 + 1.5);
    tb_assert_near(tb_texture_eval1(&t, &q), want, 1e-6);
}

static void test_noise(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("noise", 4), 0);
    /* zero on the lattice, gradient there one of the 12 edge vectors */
    for (int k = 0; k < 500; k++) {
        double x = (double)((int)tb_rng_below(&rng, 1000) - 500);
        double y = (double)((int)tb_rng_below(&rng, 1000) - 500);
        double z = (double)((int)tb_rng_below(&rng, 1000) - 500);
        assert_true(tb_noise3(x, y, z) == 0.0);
        double h = 1e-5, g[3];
        g[0] = (tb_noise3(x + h, y, z) - tb_noise3(x - h, y, z)) / (2 * h);
        g[1] = (tb_noise3(x, y + h, z) - tb_noise3(x, y - h, z)) / (2 * h);
        g[2] = (tb_noise3(x, y, z + h) - tb_noise3(x, y, z - h)) / (2 * h);
        int nonzero = 0;
        for (int i = 0; i < 3; i++) {
            double r = round(g[i]);
            assert_true(r == 0.0 || r == 1.0 || r == -1.0);
            tb_assert_near(g[i], r, 1e-6);
            nonzero += r != 0.0;
        }
        assert_int_equal(nonzero, 2);
    }
    /* deterministic, periodic (256), bounded, zero mean */
    double lo = 0, hi = 0, sum = 0, sum2 = 0;
    int n = 100000;
    for (int k = 0; k < n; k++) {
        double x = 300.0 * tb_rng_double(&rng) - 150.0, y = 300.0 * tb_rng_double(&rng) - 150.0,
               z = 300.0 * tb_rng_double(&rng) - 150.0;
        double v = tb_noise3(x, y, z);
        assert_true(v == tb_noise3(x, y, z));
        tb_assert_near(tb_noise3(x + 256.0, y - 512.0, z + 256.0), v, 1e-9);
        assert_true(fabs(v) <= 2.0); /* each corner term |g . d| <= 2, weights sum to 1 */
        lo = fmin(lo, v);
        hi = fmax(hi, v);
        sum += v;
        sum2 += v * v;
    }
    double mean = sum / n, sd = sqrt(sum2 / n - mean * mean);
    print_message("[ noise    ] 1e5 points: range [%.4f, %.4f], mean %.4f, sd %.4f\n", lo, hi, mean, sd);
    assert_true(fabs(mean) < 0.01);
    assert_true(sd > 0.1 && hi > 0.6 && lo < -0.6);
    /* not constant along a line between lattice points */
    assert_true(tb_noise3(0.5, 0.5, 0.5) != tb_noise3(0.25, 0.5, 0.5));
    /* non-finite input */
    assert_true(tb_noise3(NAN, 0, 0) == 0.0);

    /* fBm: a footprint of a whole lattice cell (or more) leaves no octave */
    tb_dvec3 p = {0.3, 1.7, -2.2}, zero = {0, 0, 0};
    assert_true(tb_fbm3(p, (tb_dvec3){1.0, 0, 0}, zero, 0.5, 8) == 0.0);
    /* |dp| = 1/4: -1 - log2(1/4) = 1 octave exactly: the noise itself */
    tb_assert_near(tb_fbm3(p, (tb_dvec3){0.25, 0, 0}, zero, 0.5, 8), tb_noise3(p.x, p.y, p.z), 1e-15);
    /* no footprint: all octaves, by hand */
    double want = 0.0, f = 1.0, a = 1.0;
    for (int i = 0; i < 5; i++) {
        want += a * tb_noise3(p.x * f, p.y * f, p.z * f);
        f *= 1.99;
        a *= 0.5;
    }
    tb_assert_near(tb_fbm3(p, zero, zero, 0.5, 5), want, 1e-12);
    for (int k = 0; k < 2000; k++) {
        tb_dvec3 q = {10 * tb_rng_double(&rng), 10 * tb_rng_double(&rng), 10 * tb_rng_double(&rng)};
        double t = tb_turbulence3(q, zero, zero, 0.5, 6);
        assert_true(t >= 0.0 && t <= 2.0 * 2.0);
        assert_true(fabs(tb_fbm3(q, zero, zero, 0.5, 6)) <= 2.0 * 2.0);
    }
    /* the texture: in [lo, hi], deterministic */
    const float c0[3] = {0.1f, 0.2f, 0.3f}, c1[3] = {0.9f, 0.8f, 0.7f};
    tb_texture nt = tb_texture_noise(3, c0, c1, TB_NOISE_FBM, 6, 0.5f);
    tb_texture tt = tb_texture_noise(3, c0, c1, TB_NOISE_TURBULENCE, 6, 0.5f);
    nt.su = nt.sv = tt.su = tt.sv = 16.0f;
    for (int k = 0; k < 2000; k++) {
        tb_tex_query q = {.u = tb_rng_float(&rng), .v = tb_rng_float(&rng)};
        float o1[3], o2[3];
        tb_texture_eval(&nt, &q, o1);
        tb_texture_eval(&nt, &q, o2);
        assert_memory_equal(o1, o2, sizeof o1);
        assert_true(o1[0] >= 0.1f && o1[0] <= 0.9f && o1[2] >= 0.3f && o1[2] <= 0.7f);
        tb_texture_eval(&tt, &q, o1);
        assert_true(o1[0] >= 0.1f && o1[0] <= 0.9f);
    }
}

/* ---------------------------------------------------------------- bump mapping */

/* An image ramp h(u, v) = a u + b v at texel centres (bilinear reproduces it
 * exactly between them). */
static tb_mipmap *height_ramp(int w, int h, double a, double b)
{
    tb_image *img = tb_image_create(w, h, 1, NULL);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            tb_image_at(img, x, y)[0] = (float)(a * (x + 0.5) / w + b * (1.0 - (y + 0.5) / h));
    tb_mipmap *m = tb_mipmap_create(img);
    tb_image_free(img);
    return m;
}

static void test_bump_plane(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("bump plane", 6), 0);
    const double A = 0.3, B = -0.7;
    tb_mipmap *m = height_ramp(64, 64, A, B);
    for (int filt = 1; filt <= 2; filt++) {
        tb_texture ht = tb_texture_image(m, (tb_tex_filter)filt, TB_TEX_CLAMP);
        for (int k = 0; k < 500; k++) {
            /* plane z = 0 with tangents of lengths Lu, Lv along x, y */
            double Lu = 0.5 + 3 * tb_rng_double(&rng), Lv = 0.5 + 3 * tb_rng_double(&rng);
            double scale = 2.0 * tb_rng_double(&rng) - 1.0;
            tb_bump_geom g = {.p = {1, 2, 0}, .n = {0, 0, 1}, .dpdu = {(float)Lu, 0, 0}, .dpdv = {0, (float)Lv, 0},
                              .u = (float)(0.1 + 0.8 * tb_rng_double(&rng)),
                              .v = (float)(0.1 + 0.8 * tb_rng_double(&rng))};
            if (k % 2)
                g.fp = (tb_tex_footprint){(float)(0.002 + 0.008 * tb_rng_double(&rng)), 0.0f, 0.0f,
                                          (float)(0.002 + 0.008 * tb_rng_double(&rng))};
            tb_vec3 n, pu, pv;
            assert_true(tb_bump_map(&ht, (float)scale, &g, &n, &pu, &pv));
            /* heights come back as floats (|h| < 1, rounding 6e-8), so a
             * forward difference over a step du has an error up to about
             * 1.2e-7 / du: the tolerance follows the step the mapper takes */
            double step = fmin(k % 2 ? 0.5 * g.fp.dudx : 1.0 / 2048, k % 2 ? 0.5 * g.fp.dvdy : 1.0 / 2048);
            double tol = 1e-6 + 2.5e-7 / step;
            /* displaced surface (Lu u, Lv v, s (A u + B v)): tangents (Lu, 0, sA), (0, Lv, sB),
             * normal (-sA Lv, -sB Lu, Lu Lv) normalised */
            double nx = -scale * A * Lv, ny = -scale * B * Lu, nz = Lu * Lv, l = sqrt(nx * nx + ny * ny + nz * nz);
            tb_assert_near(n.x, nx / l, tol);
            tb_assert_near(n.y, ny / l, tol);
            tb_assert_near(n.z, nz / l, tol);
            tb_assert_near(pu.z, scale * A, tol);
            tb_assert_near(pv.z, scale * B, tol);
        }
    }
    /* zero scale: the normal is unchanged */
    tb_texture ht = tb_texture_image(m, TB_TEX_BILINEAR, TB_TEX_CLAMP);
    tb_bump_geom g = {.n = {0, 0, 1}, .dpdu = {1, 0, 0}, .dpdv = {0, 1, 0}, .u = 0.5f, .v = 0.5f};
    tb_vec3 n;
    assert_true(tb_bump_map(&ht, 0.0f, &g, &n, NULL, NULL));
    assert_true(n.x == 0.0f && n.y == 0.0f && n.z == 1.0f);
    /* a normal on the other side is followed */
    g.n = (tb_vec3){0, 0, -1};
    assert_true(tb_bump_map(&ht, 1.0f, &g, &n, NULL, NULL));
    assert_true(n.z < 0.0f);
    tb_mipmap_free(m);
}

static void test_bump_curved(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("bump curved", 7), 0);
    /* cylinder p = (cos 2 pi u, sin 2 pi u, L v), n = (cos, sin, 0),
     * dn/du = 2 pi (-sin, cos, 0), height h = alpha v: the displaced surface
     * has radius 1 + alpha v, tangents 2 pi (1 + alpha v)(-sin, cos, 0) and
     * (alpha cos, alpha sin, L), normal (L cos, L sin, -alpha) / sqrt(L^2 + alpha^2) */
    const double alpha = 0.4, L = 3.0;
    tb_mipmap *m = height_ramp(32, 32, 0.0, alpha);
    tb_texture ht = tb_texture_image(m, TB_TEX_BILINEAR, TB_TEX_CLAMP);
    for (int k = 0; k < 500; k++) {
        double u = 0.1 + 0.8 * tb_rng_double(&rng), v = 0.1 + 0.8 * tb_rng_double(&rng);
        double c = cos(2 * TB_PI * u), s = sin(2 * TB_PI * u);
        tb_bump_geom g = {.p = {(float)c, (float)s, (float)(L * v)},
                          .n = {(float)c, (float)s, 0},
                          .dpdu = {(float)(-2 * TB_PI * s), (float)(2 * TB_PI * c), 0},
                          .dpdv = {0, 0, (float)L},
                          .dndu = {(float)(-2 * TB_PI * s), (float)(2 * TB_PI * c), 0},
                          .u = (float)u,
                          .v = (float)v};
        tb_vec3 n, pu;
        assert_true(tb_bump_map(&ht, 1.0f, &g, &n, &pu, NULL));
        /* float heights over the default step 1/2048: slope error <= ~5e-4 */
        double l = sqrt(L * L + alpha * alpha);
        tb_assert_near(n.x, L * c / l, 5e-4);
        tb_assert_near(n.y, L * s / l, 5e-4);
        tb_assert_near(n.z, -alpha / l, 5e-4);
        double hv = alpha * (float)v; /* the lookup sees v rounded to float */
        tb_assert_near(pu.x, -2 * TB_PI * (1 + hv) * s, 1e-4);
        tb_assert_near(pu.y, 2 * TB_PI * (1 + hv) * c, 1e-4);
    }
    tb_mipmap_free(m);
    /* sphere with a constant height: an offset surface, same normal, tangents
     * scaled by 1 + h (unit sphere: dn/du = dp/du) */
    const float hval = 0.25f;
    tb_texture cst = tb_texture_constant(1, &hval);
    for (int k = 0; k < 200; k++) {
        double th = 0.2 + 2.7 * tb_rng_double(&rng), ph = 6.28 * tb_rng_double(&rng);
        tb_vec3 n0 = {(float)(sin(th) * cos(ph)), (float)(sin(th) * sin(ph)), (float)cos(th)};
        tb_vec3 du = {(float)(-2 * TB_PI * sin(th) * sin(ph)), (float)(2 * TB_PI * sin(th) * cos(ph)), 0};
        tb_vec3 dv = {(float)(-TB_PI * cos(th) * cos(ph)), (float)(-TB_PI * cos(th) * sin(ph)), (float)(TB_PI * sin(th))};
        /* (du x dv) points inward for this (u, v) order; the bump result
         * follows n anyway */
        tb_bump_geom g = {.p = n0, .n = n0, .dpdu = du, .dpdv = dv, .dndu = du, .dndv = dv, .u = 0.3f, .v = 0.6f};
        tb_vec3 n, pu;
        assert_true(tb_bump_map(&cst, 1.0f, &g, &n, &pu, NULL));
        tb_assert_near(n.x, n0.x, 2e-6);
        tb_assert_near(n.y, n0.y, 2e-6);
        tb_assert_near(n.z, n0.z, 2e-6);
        tb_assert_near(pu.x, 1.25 * du.x, 2e-5);
        tb_assert_near(pu.y, 1.25 * du.y, 2e-5);
    }
}

/* ---------------------------------------------------------------- footprints */

static tb_vec3 rvec(tb_rng *r, double s)
{
    return (tb_vec3){(float)(s * (2 * tb_rng_double(r) - 1)), (float)(s * (2 * tb_rng_double(r) - 1)),
                     (float)(s * (2 * tb_rng_double(r) - 1))};
}

static void test_footprint_from_rays(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("footprint", 10), 0);
    int solved = 0;
    for (int k = 0; k < 2000; k++) {
        /* a plane through p with arbitrary, non-orthogonal tangents */
        tb_vec3 p = rvec(&rng, 5), a = rvec(&rng, 2), b = rvec(&rng, 2);
        tb_dvec3 nd = tb_dvec3_normalize(tb_dvec3_cross(tb_vec3_to_d(a), tb_vec3_to_d(b)));
        if (tb_dvec3_length(tb_dvec3_cross(tb_vec3_to_d(a), tb_vec3_to_d(b))) < 0.1)
            continue;
        tb_vec3 n = tb_dvec3_to_f(nd);
        /* offset rays from a camera point in front of the plane towards
         * points q = p + du a + dv b */
        tb_vec3 cam = tb_vec3_add(p, tb_vec3_scale(n, (float)(1 + 5 * tb_rng_double(&rng))));
        cam = tb_vec3_add(cam, rvec(&rng, 1));
        double dux = 0.1 * (2 * tb_rng_double(&rng) - 1), dvx = 0.1 * (2 * tb_rng_double(&rng) - 1);
        double duy = 0.1 * (2 * tb_rng_double(&rng) - 1), dvy = 0.1 * (2 * tb_rng_double(&rng) - 1);
        tb_dvec3 qx = tb_dvec3_add(tb_vec3_to_d(p), tb_dvec3_add(tb_dvec3_scale(tb_vec3_to_d(a), dux), tb_dvec3_scale(tb_vec3_to_d(b), dvx)));
        tb_dvec3 qy = tb_dvec3_add(tb_vec3_to_d(p), tb_dvec3_add(tb_dvec3_scale(tb_vec3_to_d(a), duy), tb_dvec3_scale(tb_vec3_to_d(b), dvy)));
        tb_ray_differential rd = {cam, tb_dvec3_to_f(tb_dvec3_sub(qx, tb_vec3_to_d(cam))), cam,
                                  tb_dvec3_to_f(tb_dvec3_sub(qy, tb_vec3_to_d(cam)))};
        tb_tex_footprint fp;
        tb_vec3 dpdx, dpdy;
        if (!tb_tex_footprint_from_rays(p, n, a, b, &rd, &fp, &dpdx, &dpdy))
            fail_msg("footprint refused a regular configuration");
        solved++;
        /* float inputs: allow a few float roundings relative to the sizes */
        double tol = 2e-5 * (1.0 + 5.0 / tb_dvec3_length(tb_dvec3_cross(tb_vec3_to_d(a), tb_vec3_to_d(b))));
        tb_assert_near(fp.dudx, dux, tol);
        tb_assert_near(fp.dvdx, dvx, tol);
        tb_assert_near(fp.dudy, duy, tol);
        tb_assert_near(fp.dvdy, dvy, tol);
        tb_assert_near(dpdx.x, qx.x - p.x, 1e-4);
    }
    assert_true(solved > 1500);
    /* a ray parallel to the plane, or pointing away from it: no footprint */
    tb_ray_differential par = {{0, 0, 1}, {1, 0, 0}, {0, 0, 1}, {0, 1, -1}};
    tb_tex_footprint fp;
    assert_false(tb_tex_footprint_from_rays((tb_vec3){0, 0, 0}, (tb_vec3){0, 0, 1}, (tb_vec3){1, 0, 0},
                                            (tb_vec3){0, 1, 0}, &par, &fp, NULL, NULL));
    assert_true(fp.dudx == 0 && fp.dvdx == 0 && fp.dudy == 0 && fp.dvdy == 0);
    tb_ray_differential away = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0.1f, -1}};
    assert_false(tb_tex_footprint_from_rays((tb_vec3){0, 0, 0}, (tb_vec3){0, 0, 1}, (tb_vec3){1, 0, 0},
                                            (tb_vec3){0, 1, 0}, &away, &fp, NULL, NULL));
    /* degenerate tangents */
    tb_ray_differential ok = {{0, 0, 1}, {0.1f, 0, -1}, {0, 0, 1}, {0, 0.1f, -1}};
    assert_false(tb_tex_footprint_from_rays((tb_vec3){0, 0, 0}, (tb_vec3){0, 0, 1}, (tb_vec3){1, 0, 0},
                                            (tb_vec3){2, 0, 0}, &ok, &fp, NULL, NULL));
    /* the pinhole case of the grazing tests: camera at height 1 looking
     * along z at the plane y = 0, (u, v) = (x, z), pixel spacing 1/f: the
     * offset rays land exactly on the neighbouring pixels' hit points */
    double f = 128.0, a0 = 0.2, b0 = 0.05;
    tb_vec3 cam = {0, 1, 0};
    tb_vec3 hit = {(float)(a0 / b0), 0, (float)(1 / b0)};
    tb_ray_differential pin = {cam, {(float)(a0 + 1 / f), (float)-b0, 1}, cam, {(float)a0, (float)-(b0 + 1 / f), 1}};
    assert_true(tb_tex_footprint_from_rays(hit, (tb_vec3){0, 1, 0}, (tb_vec3){1, 0, 0}, (tb_vec3){0, 0, 1}, &pin, &fp, NULL, NULL));
    tb_assert_near(fp.dudx, (a0 + 1 / f) / b0 - a0 / b0, 1e-4);
    tb_assert_near(fp.dvdx, 0.0, 1e-4);
    tb_assert_near(fp.dudy, a0 / (b0 + 1 / f) - a0 / b0, 1e-4);
    tb_assert_near(fp.dvdy, 1 / (b0 + 1 / f) - 1 / b0, 1e-3);
}

/* ---------------------------------------------------------------- cache */

static void test_cache(void **state)
{
    (void)state;
    char dir[1024], sub[1100], png[1200], exr[1200], rel[1200], five[1200];
    snprintf(dir, sizeof dir, "%s/texture_cache", tb_test_tmpdir());
    mkdir(dir, 0777);
    snprintf(sub, sizeof sub, "%s/sub", dir);
    mkdir(sub, 0777);
    snprintf(png, sizeof png, "%s/sub/check.png", dir);
    snprintf(exr, sizeof exr, "%s/ramp.exr", dir);
    tb_image *img = tb_image_create(8, 4, 3, NULL);
    for (int i = 0; i < 8 * 4 * 3; i++)
        img->pixels[i] = (i % 7) / 6.0f;
    assert_int_equal(tb_image_write(png, img, NULL), TB_OK);
    assert_int_equal(tb_image_write(exr, img, NULL), TB_OK);
    tb_image *five_img = tb_image_create(2, 2, 5, NULL);
    snprintf(five, sizeof five, "%s/five.exr", dir);
    assert_int_equal(tb_image_write(five, five_img, NULL), TB_OK);

    tb_texture_cache *c = tb_texture_cache_create();
    const tb_mipmap *m1, *m2, *m3, *m4, *m5;
    assert_int_equal(tb_texture_cache_get(c, NULL, png, NULL, &m1), TB_OK);
    snprintf(rel, sizeof rel, "%s/sub/../sub/./check.png", dir);
    assert_int_equal(tb_texture_cache_get(c, NULL, rel, NULL, &m2), TB_OK);
    assert_int_equal(tb_texture_cache_get(c, sub, "check.png", NULL, &m3), TB_OK);
    assert_int_equal(tb_texture_cache_get(c, dir, "sub/check.png", NULL, &m4), TB_OK);
    assert_true(m1 == m2 && m2 == m3 && m3 == m4);
    assert_int_equal((int)tb_texture_cache_count(c), 1);
    /* level 0 holds what the image reader returns (linear values from sRGB codes) */
    tb_image *back = NULL;
    assert_int_equal(tb_image_read(png, NULL, &back), TB_OK);
    assert_memory_equal(m1->levels[0].texels, back->pixels, sizeof(float) * 8 * 4 * 3);
    tb_image_free(back);
    /* other read options are another entry; another file too */
    tb_image_read_options lin = {.encoding = TB_ENCODING_LINEAR};
    assert_int_equal(tb_texture_cache_get(c, NULL, png, &lin, &m5), TB_OK);
    assert_true(m5 != m1);
    assert_int_equal(tb_texture_cache_get(c, dir, "ramp.exr", NULL, &m5), TB_OK);
    assert_int_equal((int)tb_texture_cache_count(c), 3);
    assert_memory_equal(m5->levels[0].texels, img->pixels, sizeof(float) * 8 * 4 * 3);
    /* PFM (float, exact) and Utah RLE (8-bit, as its reader decodes it) */
    char pfm[1200], rle[1200];
    snprintf(pfm, sizeof pfm, "%s/ramp.pfm", dir);
    snprintf(rle, sizeof rle, "%s/ramp.rle", dir);
    assert_int_equal(tb_image_write(pfm, img, NULL), TB_OK);
    assert_int_equal(tb_image_write(rle, img, NULL), TB_OK);
    assert_int_equal(tb_texture_cache_get(c, NULL, pfm, NULL, &m5), TB_OK);
    assert_memory_equal(m5->levels[0].texels, img->pixels, sizeof(float) * 8 * 4 * 3);
    assert_int_equal(tb_texture_cache_get(c, NULL, rle, NULL, &m5), TB_OK);
    assert_int_equal(tb_image_read(rle, NULL, &back), TB_OK);
    assert_int_equal(back->channels, 3);
    assert_memory_equal(m5->levels[0].texels, back->pixels, sizeof(float) * 8 * 4 * 3);
    tb_image_free(back);
    assert_int_equal((int)tb_texture_cache_count(c), 5);
    /* errors */
    assert_int_equal(tb_texture_cache_get(c, dir, "missing.png", NULL, &m5), TB_ERR_NOT_FOUND);
    assert_null(m5);
    assert_non_null(strstr(tb_last_error(), "missing.png"));
    assert_int_equal(tb_texture_cache_get(c, NULL, five, NULL, &m5), TB_ERR_UNSUPPORTED);
    assert_int_equal((int)tb_texture_cache_count(c), 5);
    tb_texture_cache_free(c);
    tb_image_free(img);
    tb_image_free(five_img);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_checker_box),
        cmocka_unit_test(test_checker3_box),
        cmocka_unit_test(test_noise),
        cmocka_unit_test(test_bump_plane),
        cmocka_unit_test(test_bump_curved),
        cmocka_unit_test(test_footprint_from_rays),
        cmocka_unit_test(test_cache),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
