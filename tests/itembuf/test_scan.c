/* util/itembuf/scan: analytic pixel coverage of known shapes, the top-left
 * rule, shared edges drawn exactly once (property tests), clipping of huge
 * coordinates, and degenerate input. */
#include "itembuf_test.h"

#include <math.h>

/* Pixels i with x0 <= i + 0.5 < x1, clamped to [0, n): the top-left rule
 * includes a left/top edge through a centre and excludes a right/bottom one. */
static void centre_range(double x0, double x1, int n, int *lo, int *hi)
{
    double a = ceil(x0 - 0.5), b = ceil(x1 - 0.5);
    *lo = a < 0 ? 0 : a > n ? n : (int)a;
    *hi = b < 0 ? 0 : b > n ? n : (int)b;
    if (*hi < *lo)
        *hi = *lo;
}

/* Random rectangles (on the 1/256 grid, often on half-pixels so that edges
 * run through centres), both orientations, every starting vertex, partly
 * outside the buffer: exactly the analytic pixel set. */
static void test_scan_rectangles(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("scan_rectangles", 101), 1);
    const int W = 37, H = 23;
    cover c;
    cover_init(&c, W, H);
    for (int trial = 0; trial < 400; trial++) {
        int bits = trial % 2 ? 8 : 1;
        float x0 = grid_rand(&rng, -5, W + 5, bits), x1 = grid_rand(&rng, -5, W + 5, bits);
        float y0 = grid_rand(&rng, -5, H + 5, bits), y1 = grid_rand(&rng, -5, H + 5, bits);
        if (x0 > x1) { float t = x0; x0 = x1; x1 = t; }
        if (y0 > y1) { float t = y0; y0 = y1; y1 = t; }
        int ilo, ihi, jlo, jhi;
        centre_range(x0, x1, W, &ilo, &ihi);
        centre_range(y0, y1, H, &jlo, &jhi);
        const float ccw[4][2] = {{x0, y0}, {x0, y1}, {x1, y1}, {x1, y0}};
        for (int orient = 0; orient < 2; orient++) {
            for (int s = 0; s < 4; s++) {
                float p[4][2];
                for (int k = 0; k < 4; k++) {
                    int idx = orient ? (s + k) % 4 : (s + 4 - k) % 4;
                    p[k][0] = ccw[idx][0];
                    p[k][1] = ccw[idx][1];
                }
                memset(c.count, 0, (size_t)W * H);
                assert_int_equal(cover_polygon(&c, p, 4), TB_OK);
                for (int j = 0; j < H; j++)
                    for (int i = 0; i < W; i++) {
                        int expect = i >= ilo && i < ihi && j >= jlo && j < jhi;
                        if (c.count[j * W + i] != expect)
                            fail_msg("rect [%g,%g]x[%g,%g] pixel (%d,%d): %d, expected %d", x0, x1,
                                     y0, y1, i, j, c.count[j * W + i], expect);
                    }
            }
        }
    }
    cover_free(&c);
}

/* Right triangle with legs N on pixel corners: centres (i+.5, j+.5) with
 * i + j + 1 < N are inside, those on the hypotenuse (a right/bottom edge) are
 * not: N(N-1)/2 pixels. The other half of the square gets the rest. */
static void test_scan_right_triangle(void **state)
{
    (void)state;
    for (int N = 1; N <= 64; N *= 4) {
        cover c;
        cover_init(&c, N, N);
        const float t1[3][2] = {{0, 0}, {(float)N, 0}, {0, (float)N}};
        const float t1r[3][2] = {{0, 0}, {0, (float)N}, {(float)N, 0}};
        const float t2[3][2] = {{(float)N, 0}, {(float)N, (float)N}, {0, (float)N}};
        assert_int_equal(cover_polygon(&c, t1, 3), TB_OK);
        assert_int_equal(cover_total(&c), N * (N - 1) / 2);
        for (int j = 0; j < N; j++)
            for (int i = 0; i < N; i++)
                assert_int_equal(c.count[j * N + i], i + j + 1 < N);
        memset(c.count, 0, (size_t)N * N);
        assert_int_equal(cover_polygon(&c, t1r, 3), TB_OK); /* orientation does not matter */
        assert_int_equal(cover_total(&c), N * (N - 1) / 2);
        assert_int_equal(cover_polygon(&c, t2, 3), TB_OK);
        for (int k = 0; k < N * N; k++)
            assert_int_equal(c.count[k], 1); /* the two halves tile the square */
        cover_free(&c);
    }
}

/* A circle as a 1000-gon: pixels well inside the inscribed circle are
 * covered, pixels outside the circumscribed one are not, and the count tends
 * to pi r^2 with an error below half the perimeter (a bound that shrinks
 * relative to the area as 1/r). */
static void test_scan_circle(void **state)
{
    (void)state;
    const int n = 1000;
    static float p[1000][2];
    const double radii[] = {3.3, 10.0, 47.25, 200.0, 500.0};
    for (int t = 0; t < 5; t++) {
        double r = radii[t];
        int W = (int)(2 * r) + 4;
        double cx = W / 2.0 + 0.123, cy = W / 2.0 - 0.377;
        for (int k = 0; k < n; k++) {
            p[k][0] = (float)(cx + r * cos(2 * TEST_PI * k / n));
            p[k][1] = (float)(cy + r * sin(2 * TEST_PI * k / n));
        }
        cover c;
        cover_init(&c, W, W);
        assert_int_equal(cover_polygon(&c, p, n), TB_OK);
        /* Vertices move by <= 1/512 px when snapped, and by float rounding. */
        double margin = 0.003, rin = r * cos(TEST_PI / n) - margin, rout = r + margin;
        for (int j = 0; j < W; j++)
            for (int i = 0; i < W; i++) {
                double d = hypot(i + 0.5 - cx, j + 0.5 - cy);
                int got = c.count[j * W + i];
                if ((d < rin && got != 1) || (d > rout && got != 0))
                    fail_msg("r=%g pixel (%d,%d) at distance %.6f: count %d", r, i, j, d, got);
            }
        long count = cover_total(&c);
        double area = TEST_PI * r * r, poly = 0.5 * n * r * r * sin(2 * TEST_PI / n);
        double bound = TEST_PI * r + 1 + (area - poly);
        print_message("circle r=%g: %ld pixels, pi r^2 = %.1f, relative error %.2e (bound %.2e)\n",
                      r, count, area, fabs(count - area) / area, bound / area);
        assert_true(fabs((double)count - area) <= bound);
        cover_free(&c);
    }
}

/* L-shape on integer corners (no centre on an edge) and on half-integer
 * corners (many centres on edges): per-pixel analytic membership. */
static void test_scan_l_shape(void **state)
{
    (void)state;
    const int W = 14, H = 12;
    for (int half = 0; half < 2; half++) {
        float o = half ? 0.5f : 0.0f;
        const float L[6][2] = {{2 + o, 1 + o}, {10 + o, 1 + o}, {10 + o, 4 + o},
                               {5 + o, 4 + o}, {5 + o, 9 + o},  {2 + o, 9 + o}};
        for (int orient = 0; orient < 2; orient++)
            for (int s = 0; s < 6; s++) {
                float p[6][2];
                for (int k = 0; k < 6; k++) {
                    int idx = orient ? (s + k) % 6 : (s + 6 - k) % 6;
                    p[k][0] = L[idx][0];
                    p[k][1] = L[idx][1];
                }
                cover c;
                cover_init(&c, W, H);
                assert_int_equal(cover_polygon(&c, p, 6), TB_OK);
                for (int j = 0; j < H; j++)
                    for (int i = 0; i < W; i++) {
                        double x = i + 0.5, y = j + 0.5;
                        int in = (x >= 2 + o && x < 10 + o && y >= 1 + o && y < 4 + o) ||
                                 (x >= 2 + o && x < 5 + o && y >= 4 + o && y < 9 + o);
                        assert_int_equal(c.count[j * W + i], in);
                    }
                assert_int_equal(cover_total(&c), 8 * 3 + 3 * 5);
                cover_free(&c);
            }
    }
}

/* Compares the scan of some contours with the reference, pixel by pixel. */
static void check_against_reference(int W, int H, const float (*xy)[2], const int *counts,
                                    int ncontours, tb_fill_rule rule, long *covered)
{
    cover c;
    cover_init(&c, W, H);
    assert_int_equal(tb_scan_contours(W, H, xy, counts, ncontours, rule, cover_span, &c), TB_OK);
    long n = 0;
    for (int j = 0; j < H; j++)
        for (int i = 0; i < W; i++) {
            int expect = ref_inside(xy, counts, ncontours, rule, i, j);
            if (c.count[j * W + i] != expect)
                fail_msg("pixel (%d,%d): count %d, reference %d (rule %d)", i, j,
                         c.count[j * W + i], expect, (int)rule);
            n += expect;
        }
    if (covered)
        *covered = n;
    cover_free(&c);
}

/* Five-pointed star as a simple 10-gon, and the self-intersecting pentagram
 * {5/2}: even-odd leaves the centre pentagon empty, non-zero fills it. */
static void test_scan_star(void **state)
{
    (void)state;
    const int W = 64, H = 64;
    const double cx = 31.7, cy = 32.2, R = 28, r = R * 0.381966;
    float star[10][2], gram[5][2];
    for (int k = 0; k < 10; k++) {
        double a = -TEST_PI / 2 + k * TEST_PI / 5, rad = k % 2 ? r : R;
        star[k][0] = (float)(round((cx + rad * cos(a)) * 256) / 256);
        star[k][1] = (float)(round((cy + rad * sin(a)) * 256) / 256);
    }
    for (int k = 0; k < 5; k++) {
        gram[k][0] = star[(4 * k) % 10][0];
        gram[k][1] = star[(4 * k) % 10][1];
    }
    int n10 = 10, n5 = 5;
    long simple_eo, simple_nz, gram_eo, gram_nz;
    check_against_reference(W, H, star, &n10, 1, TB_FILL_EVEN_ODD, &simple_eo);
    check_against_reference(W, H, star, &n10, 1, TB_FILL_NONZERO, &simple_nz);
    check_against_reference(W, H, gram, &n5, 1, TB_FILL_EVEN_ODD, &gram_eo);
    check_against_reference(W, H, gram, &n5, 1, TB_FILL_NONZERO, &gram_nz);
    assert_int_equal(simple_eo, simple_nz); /* a simple polygon: both rules agree */
    /* Star area = 10 * (1/2) R r sin(36 deg); the pentagram's non-zero fill is
     * the same star (up to snapping), its even-odd fill lacks the pentagon. */
    double star_area = 5 * R * r * sin(TEST_PI / 5);
    double pent_area = 2.5 * r * r * sin(2 * TEST_PI / 5);
    print_message("star: %ld px (area %.1f); pentagram even-odd %ld (area %.1f), non-zero %ld\n",
                  simple_eo, star_area, gram_eo, star_area - pent_area, gram_nz);
    double perim = 10 * hypot(R - r * cos(TEST_PI / 5), r * sin(TEST_PI / 5));
    assert_true(fabs(simple_eo - star_area) <= perim / 2 + 1);
    assert_true(labs(gram_nz - simple_nz) <= 10); /* differ only near the inner vertices */
    assert_true(fabs(gram_eo - (star_area - pent_area)) <= perim + 1);
}

/* Square with a square hole: even-odd gives the ring for either orientation
 * of the hole; non-zero needs the hole reversed. */
static void test_scan_holes(void **state)
{
    (void)state;
    const int W = 24, H = 24;
    const float same[8][2] = {{2, 2}, {22, 2}, {22, 22}, {2, 22}, {7, 7}, {17, 7}, {17, 17}, {7, 17}};
    const float rev[8][2] = {{2, 2}, {22, 2}, {22, 22}, {2, 22}, {7, 7}, {7, 17}, {17, 17}, {17, 7}};
    const int counts[2] = {4, 4};
    long n;
    check_against_reference(W, H, same, counts, 2, TB_FILL_EVEN_ODD, &n);
    assert_int_equal(n, 400 - 100);
    check_against_reference(W, H, rev, counts, 2, TB_FILL_EVEN_ODD, &n);
    assert_int_equal(n, 400 - 100);
    check_against_reference(W, H, same, counts, 2, TB_FILL_NONZERO, &n);
    assert_int_equal(n, 400);
    check_against_reference(W, H, rev, counts, 2, TB_FILL_NONZERO, &n);
    assert_int_equal(n, 400 - 100);
    /* A contour of fewer than 3 vertices contributes nothing. */
    const float with_pair[6][2] = {{2, 2}, {22, 2}, {22, 22}, {2, 22}, {0, 0}, {24, 24}};
    const int counts2[2] = {4, 2};
    check_against_reference(W, H, with_pair, counts2, 2, TB_FILL_EVEN_ODD, &n);
    assert_int_equal(n, 400);
}

/* Exact orientation (twice the signed area) of a triangle on the 1/256 grid. */
static int64_t orient(const float *a, const float *b, const float *c)
{
    int64_t ax = (int64_t)(a[0] * 256.0), ay = (int64_t)(a[1] * 256.0);
    int64_t bx = (int64_t)(b[0] * 256.0), by = (int64_t)(b[1] * 256.0);
    int64_t cx = (int64_t)(c[0] * 256.0), cy = (int64_t)(c[1] * 256.0);
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
}

/* Scans `ntri` triangles into one counter; checks every pixel is covered at
 * most once, each triangle agrees with the reference, and the union equals
 * the reference of `outline` (n vertices). */
static void check_tiling(int W, int H, float (*tri)[3][2], int ntri, const float (*outline)[2],
                         int n)
{
    cover c;
    cover_init(&c, W, H);
    for (int t = 0; t < ntri; t++) {
        assert_int_equal(cover_polygon(&c, tri[t], 3), TB_OK);
    }
    int three = 3;
    /* Centres outside the outline's bounding box are outside everything: the
     * reference (the slow part) is only consulted inside it. */
    double x0 = outline[0][0], x1 = x0, y0 = outline[0][1], y1 = y0;
    for (int k = 1; k < n; k++) {
        x0 = fmin(x0, outline[k][0]);
        x1 = fmax(x1, outline[k][0]);
        y0 = fmin(y0, outline[k][1]);
        y1 = fmax(y1, outline[k][1]);
    }
    for (int j = 0; j < H; j++)
        for (int i = 0; i < W; i++) {
            int in_box = i + 0.5 >= x0 && i + 0.5 <= x1 && j + 0.5 >= y0 && j + 0.5 <= y1;
            int expect = in_box && ref_inside(outline, &n, 1, TB_FILL_EVEN_ODD, i, j), sum = 0;
            for (int t = 0; in_box && t < ntri; t++)
                sum += ref_inside(tri[t], &three, 1, TB_FILL_EVEN_ODD, i, j);
            int got = c.count[j * W + i];
            if (got != expect || sum != expect)
                fail_msg("pixel (%d,%d): covered %d times, triangle references %d, union %d", i, j,
                         got, sum, expect);
        }
    cover_free(&c);
}

/* A random square (rotated, on a fine or a coarse grid) split along either
 * diagonal: every pixel of the square exactly once, none outside. */
static void test_scan_split_square(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("scan_split_square", 202), 2);
    const int W = 40, H = 40;
    for (int trial = 0; trial < 300; trial++) {
        int bits = trial % 3 == 0 ? 1 : 8; /* half-pixel grid: edges through centres */
        double cx = 20 + 6 * tb_rng_double(&rng), cy = 20 + 6 * tb_rng_double(&rng);
        double s = 2 + 14 * tb_rng_double(&rng), a = trial % 4 == 0 ? 0 : tb_rng_double(&rng) * TEST_PI;
        float q[4][2];
        for (int k = 0; k < 4; k++) {
            double ang = a + k * TEST_PI / 2;
            double scale = (double)(1 << bits);
            q[k][0] = (float)(round((cx + s * cos(ang)) * scale) / scale);
            q[k][1] = (float)(round((cy + s * sin(ang)) * scale) / scale);
        }
        for (int d = 0; d < 2; d++) {
            float tri[2][3][2];
            const int idx[2][2][3] = {{{0, 1, 2}, {0, 2, 3}}, {{1, 2, 3}, {1, 3, 0}}};
            for (int t = 0; t < 2; t++)
                for (int v = 0; v < 3; v++) {
                    tri[t][v][0] = q[idx[d][t][v]][0];
                    tri[t][v][1] = q[idx[d][t][v]][1];
                }
            check_tiling(W, H, tri, 2, q, 4);
        }
    }
}

/* A fan of triangles around a centre point (random angles and radii, fine or
 * coarse grid): the union is the star-shaped outline, each pixel once. */
static void test_scan_fan(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("scan_fan", 303), 3);
    const int W = 48, H = 48;
    for (int trial = 0; trial < 300; trial++) {
        int bits = trial % 3 == 0 ? 1 : 8;
        double scale = (double)(1 << bits);
        int k = 4 + (int)tb_rng_below(&rng, 12);
        float centre[2] = {(float)(round((24 + 4 * tb_rng_double(&rng)) * scale) / scale),
                           (float)(round((24 + 4 * tb_rng_double(&rng)) * scale) / scale)};
        float ring[16][2] = {{0}}; /* the first k entries are set below */
        /* Consecutive angles differ by less than pi, so every triangle has the
         * same orientation; retry if snapping made one degenerate. */
        int ok;
        do {
            double a0 = tb_rng_double(&rng) * 2 * TEST_PI;
            for (int i = 0; i < k; i++) {
                double a = a0 + 2 * TEST_PI * (i + 0.8 * tb_rng_double(&rng)) / k;
                double rad = 2 + 24 * tb_rng_double(&rng);
                ring[i][0] = (float)(round((centre[0] + rad * cos(a)) * scale) / scale);
                ring[i][1] = (float)(round((centre[1] + rad * sin(a)) * scale) / scale);
            }
            ok = 1;
            for (int i = 0; i < k; i++)
                ok &= orient(centre, ring[i], ring[(i + 1) % k]) > 0;
        } while (!ok);
        float tri[16][3][2];
        for (int i = 0; i < k; i++) {
            memcpy(tri[i][0], centre, sizeof centre);
            memcpy(tri[i][1], ring[i], sizeof ring[i]);
            memcpy(tri[i][2], ring[(i + 1) % k], sizeof ring[i]);
        }
        check_tiling(W, H, tri, k, ring, k);
    }
}

/* A jittered mesh of triangles larger than the buffer: every pixel exactly once. */
static void test_scan_mesh_covers_once(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("scan_mesh", 404), 4);
    for (int trial = 0; trial < 20; trial++) {
        int W = 1 + (int)tb_rng_below(&rng, 90), H = 1 + (int)tb_rng_below(&rng, 90);
        int nx = 1 + (int)tb_rng_below(&rng, 12), ny = 1 + (int)tb_rng_below(&rng, 12);
        int bits = trial % 2 ? 8 : 1;
        double scale = (double)(1 << bits);
        double cw = (W + 4.0) / nx, ch = (H + 4.0) / ny;
        float (*v)[2] = malloc((size_t)(nx + 1) * (ny + 1) * sizeof *v);
        float (*tri)[3][2] = malloc((size_t)nx * ny * 2 * sizeof *tri);
        assert_non_null(v);
        assert_non_null(tri);
        for (int j = 0; j <= ny; j++)
            for (int i = 0; i <= nx; i++) {
                /* Border vertices stay on the border; inner ones move < 0.2 cell. */
                double x = -2 + i * cw, y = -2 + j * ch;
                if (i > 0 && i < nx)
                    x += (tb_rng_double(&rng) - 0.5) * 0.4 * cw;
                if (j > 0 && j < ny)
                    y += (tb_rng_double(&rng) - 0.5) * 0.4 * ch;
                v[j * (nx + 1) + i][0] = (float)(round(x * scale) / scale);
                v[j * (nx + 1) + i][1] = (float)(round(y * scale) / scale);
            }
        int nt = 0;
        for (int j = 0; j < ny; j++)
            for (int i = 0; i < nx; i++) {
                const float *a = v[j * (nx + 1) + i], *b = v[j * (nx + 1) + i + 1];
                const float *c = v[(j + 1) * (nx + 1) + i + 1], *d = v[(j + 1) * (nx + 1) + i];
                const float *t[2][3];
                if (tb_rng_below(&rng, 2)) {
                    t[0][0] = a; t[0][1] = b; t[0][2] = c;
                    t[1][0] = a; t[1][1] = c; t[1][2] = d;
                } else {
                    t[0][0] = a; t[0][1] = b; t[0][2] = d;
                    t[1][0] = b; t[1][1] = c; t[1][2] = d;
                }
                for (int k = 0; k < 2; k++) {
                    assert_true(orient(t[k][0], t[k][1], t[k][2]) > 0); /* a valid mesh */
                    for (int m = 0; m < 3; m++)
                        memcpy(tri[nt][m], t[k][m], 2 * sizeof(float));
                    nt++;
                }
            }
        cover c;
        cover_init(&c, W, H);
        for (int t = 0; t < nt; t++)
            assert_int_equal(cover_polygon(&c, tri[t], 3), TB_OK);
        for (int k = 0; k < W * H; k++)
            if (c.count[k] != 1)
                fail_msg("mesh %dx%d cells on %dx%d: pixel (%d,%d) covered %d times", nx, ny, W,
                         H, k % W, k / W, c.count[k]);
        cover_free(&c);
        free(v);
        free(tri);
    }
}

/* Vertices far outside (clipped to the guard box first): a huge quad split
 * along a diagonal through the buffer still covers every pixel once, and a
 * band between y = 2.5 and 5.5 running to +-1e30 covers exactly rows 2..4. */
static void test_scan_huge_coordinates(void **state)
{
    (void)state;
    const int W = 50, H = 40;
    cover c;
    cover_init(&c, W, H);
    const float big = 3.0e7f;
    const float q[4][2] = {{-big, -big * 0.9f}, {big, -big * 1.1f}, {big * 1.2f, big}, {-big, big}};
    const float t1[3][2] = {{q[0][0], q[0][1]}, {q[1][0], q[1][1]}, {q[2][0], q[2][1]}};
    const float t2[3][2] = {{q[0][0], q[0][1]}, {q[2][0], q[2][1]}, {q[3][0], q[3][1]}};
    assert_int_equal(cover_polygon(&c, t1, 3), TB_OK);
    assert_int_equal(cover_polygon(&c, t2, 3), TB_OK);
    long n1 = 0;
    for (int k = 0; k < W * H; k++) {
        assert_int_equal(c.count[k], 1);
        n1++;
    }
    assert_int_equal(n1, W * H);

    memset(c.count, 0, (size_t)W * H);
    const float band[4][2] = {{-1e30f, 2.5f}, {1e30f, 2.5f}, {1e30f, 5.5f}, {-1e30f, 5.5f}};
    assert_int_equal(cover_polygon(&c, band, 4), TB_OK);
    for (int j = 0; j < H; j++)
        for (int i = 0; i < W; i++)
            assert_int_equal(c.count[j * W + i], j >= 2 && j < 5);

    /* Two triangles sharing an edge whose ends are both far away (clipped on
     * both sides, in opposite directions): still no double coverage or gap. */
    memset(c.count, 0, (size_t)W * H);
    const float a[2] = {-4.1e6f, -3.3e6f}, b[2] = {5.3e6f, 4.4e6f};
    const float l[3][2] = {{a[0], a[1]}, {b[0], b[1]}, {-4e6f, 4e6f}};
    const float r[3][2] = {{b[0], b[1]}, {a[0], a[1]}, {4e6f, -4e6f}};
    assert_int_equal(cover_polygon(&c, l, 3), TB_OK);
    assert_int_equal(cover_polygon(&c, r, 3), TB_OK);
    for (int k = 0; k < W * H; k++)
        assert_int_equal(c.count[k], 1);
    cover_free(&c);
}

/* Buffer sizes from 1x1 to 4096x4096. */
static void test_scan_resolutions(void **state)
{
    (void)state;
    /* 1x1: a triangle covering the centre, one that misses it, one with the
     * centre exactly on its left edge (covered) and on its right edge (not). */
    cover c;
    cover_init(&c, 1, 1);
    const float hit[3][2] = {{0, 0}, {1, 0}, {0, 1}};       /* centre on the hypotenuse: right edge */
    const float hit2[3][2] = {{1, 1}, {0, 1}, {1, 0}};      /* same edge, left side of this one */
    const float miss[3][2] = {{0, 0}, {0.4f, 0}, {0, 0.4f}};
    assert_int_equal(cover_polygon(&c, hit, 3), TB_OK);
    assert_int_equal(c.count[0], 0);
    assert_int_equal(cover_polygon(&c, hit2, 3), TB_OK);
    assert_int_equal(c.count[0], 1);
    assert_int_equal(cover_polygon(&c, miss, 3), TB_OK);
    assert_int_equal(c.count[0], 1);
    cover_free(&c);

    /* 4096x4096: a quad covering everything, one span per row. */
    const int S = 4096;
    cover big = {.w = S, .h = S};
    big.count = calloc((size_t)S * S, 1);
    assert_non_null(big.count);
    big.last_y = -1;
    const float all[4][2] = {{-1, -1}, {S + 1.0f, -1}, {S + 1.0f, S + 1.0f}, {-1, S + 1.0f}};
    assert_int_equal(cover_polygon(&big, all, 4), TB_OK);
    assert_int_equal(big.spans, S);
    assert_int_equal(cover_total(&big), (long)S * S);
    /* A diagonal band one pixel wide, y - 1 <= x < y: every centre of pixels
     * (j-1, j) lies exactly on its left edge (covered), every centre of
     * (j, j) on its right edge (not covered): one pixel per row but the first. */
    memset(big.count, 0, (size_t)S * S);
    const float band[4][2] = {{0, 0}, {S, S}, {S, S + 1.0f}, {0, 1}};
    assert_int_equal(cover_polygon(&big, band, 4), TB_OK);
    assert_int_equal(cover_total(&big), S - 1);
    for (int j = 1; j < S; j++)
        assert_int_equal(big.count[(size_t)j * S + (size_t)(j - 1)], 1);
    free(big.count);
}

static void test_scan_degenerate(void **state)
{
    (void)state;
    const int W = 16, H = 16;
    cover c;
    cover_init(&c, W, H);
    const float p[4][2] = {{1, 1}, {9, 2}, {5, 9}, {2, 7}};
    /* Fewer than 3 vertices. */
    for (int n = 0; n < 3; n++)
        assert_int_equal(cover_polygon(&c, p, n), TB_OK);
    assert_int_equal(tb_scan_polygon(W, H, NULL, 0, cover_span, &c), TB_OK);
    /* Collinear, repeated and coincident points; a sliver thinner than the
     * snapping grid (1/256 px). */
    const float line[4][2] = {{0, 0}, {4, 4}, {12, 12}, {8, 8}};
    const float same[3][2] = {{3.5f, 3.5f}, {3.5f, 3.5f}, {3.5f, 3.5f}};
    const float dup[4][2] = {{1, 1}, {9, 9}, {9, 9}, {1, 1}};
    const float thin[3][2] = {{0, 0.5f}, {16, 0.5f}, {8, 0.5f + 1.0f / 1024}};
    assert_int_equal(cover_polygon(&c, line, 4), TB_OK);
    assert_int_equal(cover_polygon(&c, same, 3), TB_OK);
    assert_int_equal(cover_polygon(&c, dup, 4), TB_OK);
    assert_int_equal(cover_polygon(&c, thin, 3), TB_OK);
    /* Entirely outside the buffer. */
    const float out[3][2] = {{-10, -10}, {-1, -10}, {-5, -1}};
    const float below[3][2] = {{0, 20}, {10, 20}, {5, 30}};
    assert_int_equal(cover_polygon(&c, out, 3), TB_OK);
    assert_int_equal(cover_polygon(&c, below, 3), TB_OK);
    assert_int_equal(c.spans, 0);
    /* NaN and infinity: an error, nothing drawn. */
    float bad[3][2] = {{1, 1}, {9, 2}, {5, 9}};
    bad[1][0] = NAN;
    tb_clear_error();
    assert_int_equal(cover_polygon(&c, bad, 3), TB_ERR_ARG);
    assert_true(strlen(tb_last_error()) > 0);
    bad[1][0] = INFINITY;
    assert_int_equal(cover_polygon(&c, bad, 3), TB_ERR_ARG);
    bad[1][0] = 9;
    bad[2][1] = -INFINITY;
    assert_int_equal(cover_polygon(&c, bad, 3), TB_ERR_ARG);
    assert_int_equal(c.spans, 0);
    /* Bad arguments. */
    assert_int_equal(tb_scan_polygon(W, H, p, -1, cover_span, &c), TB_ERR_ARG);
    assert_int_equal(tb_scan_polygon(0, H, p, 3, cover_span, &c), TB_ERR_ARG);
    assert_int_equal(tb_scan_polygon(W, -3, p, 3, cover_span, &c), TB_ERR_ARG);
    assert_int_equal(tb_scan_polygon(TB_SCAN_MAX_DIM + 1, H, p, 3, cover_span, &c), TB_ERR_ARG);
    assert_int_equal(tb_scan_polygon(W, H, p, 3, NULL, &c), TB_ERR_ARG);
    assert_int_equal(tb_scan_contours(W, H, p, NULL, 1, TB_FILL_EVEN_ODD, cover_span, &c), TB_ERR_ARG);
    assert_int_equal(tb_scan_contours(W, H, p, (int[]){3}, 1, (tb_fill_rule)7, cover_span, &c), TB_ERR_ARG);
    assert_int_equal(tb_scan_contours(W, H, NULL, (int[]){3}, 1, TB_FILL_EVEN_ODD, cover_span, &c), TB_ERR_ARG);
    assert_int_equal(tb_scan_contours(W, H, p, (int[]){-1}, 1, TB_FILL_EVEN_ODD, cover_span, &c), TB_ERR_ARG);
    assert_int_equal(c.spans, 0);
    /* And the valid quad still draws. */
    assert_int_equal(cover_polygon(&c, p, 4), TB_OK);
    assert_true(c.spans > 0);
    cover_free(&c);
}

/* Many random non-convex (possibly self-intersecting) polygons with many
 * vertices, against the reference, under both fill rules. */
static void test_scan_random_polygons(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("scan_random_polygons", 505), 5);
    const int W = 33, H = 29;
    float p[100][2];
    for (int trial = 0; trial < 200; trial++) {
        int n = 3 + (int)tb_rng_below(&rng, trial % 10 == 0 ? 98 : 10);
        int bits = trial % 2 ? 8 : 1;
        for (int k = 0; k < n; k++) {
            p[k][0] = grid_rand(&rng, -4, W + 4, bits);
            p[k][1] = grid_rand(&rng, -4, H + 4, bits);
        }
        int nn = n;
        check_against_reference(W, H, p, &nn, 1, TB_FILL_EVEN_ODD, NULL);
        check_against_reference(W, H, p, &nn, 1, TB_FILL_NONZERO, NULL);
        /* Split into two contours. */
        int counts[2] = {n / 2, n - n / 2};
        check_against_reference(W, H, p, counts, 2, TB_FILL_EVEN_ODD, NULL);
        check_against_reference(W, H, p, counts, 2, TB_FILL_NONZERO, NULL);
    }
}

/* Span sink that only checks the contract and sums lengths (for buffers too
 * large to hold counters). */
typedef struct span_sum {
    int w, h, last_y, last_x1;
    long long pixels;
} span_sum;

static void sum_span(void *user, int y, int x0, int x1)
{
    span_sum *s = user;
    if (!(y >= 0 && y < s->h && x0 >= 0 && x0 < x1 && x1 <= s->w))
        fail_msg("bad span y=%d [%d, %d) in %dx%d", y, x0, x1, s->w, s->h);
    if (y < s->last_y || (y == s->last_y && x0 < s->last_x1))
        fail_msg("span y=%d [%d, %d) out of order", y, x0, x1);
    s->last_y = y;
    s->last_x1 = x1;
    s->pixels += x1 - x0;
}

/* A coordinate from the ranges where the integer arithmetic is tightest:
 * around the clipping limit, far beyond it, near the largest buffer size. */
static float extreme_coord(tb_rng *r, int size)
{
    const double L = TB_SCAN_COORD_LIMIT;
    switch (tb_rng_below(r, 6)) {
    case 0: return (float)(tb_rng_below(r, 2) ? L : -L);
    case 1: return (float)((tb_rng_double(r) * 2 - 1) * L * 1.001);
    case 2: return (float)((tb_rng_double(r) * 2 - 1) * 3e38);
    case 3: return (float)(size * tb_rng_double(r));
    case 4: return (float)(tb_rng_below(r, 2) ? size : 0);
    default: return (float)((tb_rng_double(r) * 2 - 1) * 1e7);
    }
}

/* Random polygons with extreme coordinates on buffers up to the largest size:
 * spans stay in bounds and in order, the integer arithmetic never overflows
 * (the sanitizer build checks), a polygon around the whole buffer covers it
 * once, and two triangles splitting such a polygon also cover it once. */
static void test_scan_extreme_coordinates(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("scan_extreme", 606), 6);
    const int sizes[] = {1, 3, 1000, TB_SCAN_MAX_DIM};
    for (int trial = 0; trial < 400; trial++) {
        /* Cost grows with rows, not columns: the tallest buffer only once. */
        int W = sizes[tb_rng_below(&rng, 4)], H = trial == 0 ? TB_SCAN_MAX_DIM : sizes[tb_rng_below(&rng, 3)];
        float p[8][2];
        int n = 3 + (int)tb_rng_below(&rng, 6);
        for (int k = 0; k < n; k++) {
            p[k][0] = extreme_coord(&rng, W);
            p[k][1] = extreme_coord(&rng, H);
        }
        span_sum s = {W, H, -1, 0, 0};
        int counts[1] = {n};
        assert_int_equal(tb_scan_contours(W, H, p, counts, 1, (tb_fill_rule)(trial & 1), sum_span, &s),
                         TB_OK);
        assert_true(s.pixels <= (long long)W * H);
    }
    /* A quad far around the largest buffer, whole and split along a diagonal
     * whose ends are both beyond the clipping limit. */
    const int W = TB_SCAN_MAX_DIM, H = 2048;
    /* The diagonal q0-q2 runs through the middle of the buffer. */
    const float q[4][2] = {{-3e9f, -1e9f}, {4e9f, -3e9f}, {3e9f + W, 1e9f + H}, {-3e9f, 4e9f}};
    span_sum s = {W, H, -1, 0, 0};
    assert_int_equal(tb_scan_polygon(W, H, q, 4, sum_span, &s), TB_OK);
    assert_true(s.pixels == (long long)W * H);
    const float t1[3][2] = {{q[0][0], q[0][1]}, {q[1][0], q[1][1]}, {q[2][0], q[2][1]}};
    const float t2[3][2] = {{q[2][0], q[2][1]}, {q[3][0], q[3][1]}, {q[0][0], q[0][1]}};
    span_sum s1 = {W, H, -1, 0, 0}, s2 = {W, H, -1, 0, 0};
    assert_int_equal(tb_scan_polygon(W, H, t1, 3, sum_span, &s1), TB_OK);
    assert_int_equal(tb_scan_polygon(W, H, t2, 3, sum_span, &s2), TB_OK);
    assert_true(s1.pixels + s2.pixels == (long long)W * H);
    assert_true(s1.pixels > 0 && s2.pixels > 0);
}

/* Regression for the clipping of shared edges. The edge q-p below leaves the
 * [-2^21, 2^21] box; its intersection with x = 2^21 lies, in exact arithmetic,
 * almost exactly between two points of the 1/256 grid, and computing it from
 * q towards p or from p towards q rounds to different grid points (found by a
 * random search). The scan converter computes it in one fixed order, so both
 * triangles, walking the edge in opposite directions, clip it to the same
 * point and cover the 2^20 x 2^20 buffer exactly once (about a thousand
 * pixels along the edge would otherwise be lost or doubled). */
static void test_scan_shared_edge_clipped_identically(void **state)
{
    (void)state;
    const int S = TB_SCAN_MAX_DIM;
    const float q[2] = {-1, -1}, p[2] = {2163071.0f, 1076917.25f};
    const float t1[3][2] = {{q[0], q[1]}, {p[0], p[1]}, {-1e6f, 2e6f}};
    const float t2[3][2] = {{p[0], p[1]}, {q[0], q[1]}, {2e6f, -1e6f}};
    span_sum s1 = {S, S, -1, 0, 0}, s2 = {S, S, -1, 0, 0};
    assert_int_equal(tb_scan_polygon(S, S, t1, 3, sum_span, &s1), TB_OK);
    assert_int_equal(tb_scan_polygon(S, S, t2, 3, sum_span, &s2), TB_OK);
    if (s1.pixels + s2.pixels != (long long)S * S)
        fail_msg("%lld + %lld pixels, expected %lld", s1.pixels, s2.pixels, (long long)S * S);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_scan_rectangles),
        cmocka_unit_test(test_scan_right_triangle),
        cmocka_unit_test(test_scan_circle),
        cmocka_unit_test(test_scan_l_shape),
        cmocka_unit_test(test_scan_star),
        cmocka_unit_test(test_scan_holes),
        cmocka_unit_test(test_scan_split_square),
        cmocka_unit_test(test_scan_fan),
        cmocka_unit_test(test_scan_mesh_covers_once),
        cmocka_unit_test(test_scan_huge_coordinates),
        cmocka_unit_test(test_scan_resolutions),
        cmocka_unit_test(test_scan_degenerate),
        cmocka_unit_test(test_scan_random_polygons),
        cmocka_unit_test(test_scan_extreme_coordinates),
        cmocka_unit_test(test_scan_shared_edge_clipped_identically),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
