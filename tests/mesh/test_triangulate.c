/* util/mesh predicates and triangulation: exact orientation against integer
 * arithmetic, and triangulations checked by mt_check_tiling (exact
 * orientation of every triangle, boundary chain equal to the polygon's,
 * areas adding up) on hard cases and random polygons. */
#include "mesh_test.h"

#include <time.h>

#include "util/math/float.h"
#include "util/mesh/polygon.h"

/* ---------------------------------------------------------------- predicates */

/* Exact sign of the orientation determinant of integer points (|coords| < 2^52). */
static int exact_orient_int(int64_t ax, int64_t ay, int64_t bx, int64_t by, int64_t cx, int64_t cy)
{
    __int128 d = (__int128)(ax - cx) * (by - cy) - (__int128)(ay - cy) * (bx - cx);
    return (d > 0) - (d < 0);
}

/* Exact sign for coordinates in [1, 2): they are multiples of 2^-52, so
 * scaled by 2^52 they are integers below 2^53 and the determinant fits in
 * 128 bits. */
static int exact_orient_unit(double ax, double ay, double bx, double by, double cx, double cy)
{
    const double s = 0x1p52;
    return exact_orient_int((int64_t)(ax * s), (int64_t)(ay * s), (int64_t)(bx * s), (int64_t)(by * s),
                            (int64_t)(cx * s), (int64_t)(cy * s));
}

static void test_orient2d_exact(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("orient2d", 11), 1);
    int fast_wrong = 0, zero = 0;
    for (int t = 0; t < 200000; t++) {
        /* c on the line a-b, rounded to double, then nudged by 0 or 1 ulp. */
        double ax = 1 + tb_rng_double(&rng), ay = 1 + tb_rng_double(&rng);
        double bx = 1 + tb_rng_double(&rng), by = 1 + tb_rng_double(&rng);
        double u = tb_rng_double(&rng);
        double cx = ax + u * (bx - ax), cy = ay + u * (by - ay);
        int nudge = (int)tb_rng_below(&rng, 3) - 1;
        if (nudge)
            cy = nextafter(cy, nudge > 0 ? 2.0 : 1.0);
        if (t % 7 == 0) /* some exactly collinear: axis-parallel lines */
            cy = ay = by;
        if (cx < 1 || cx >= 2 || cy < 1 || cy >= 2)
            continue;
        int want = exact_orient_unit(ax, ay, bx, by, cx, cy);
        zero += want == 0;
        int got = tb_orient2d_sign(ax, ay, bx, by, cx, cy);
        if (got != want)
            fail_msg("orient2d sign %d, exact %d at case %d", got, want, t);
        double f = tb_orient2d_fast(ax, ay, bx, by, cx, cy);
        fast_wrong += ((f > 0) - (f < 0)) != want;
        /* Cyclic permutations keep the sign, a swap flips it. */
        assert_int_equal(tb_orient2d_sign(bx, by, cx, cy, ax, ay), want);
        assert_int_equal(tb_orient2d_sign(bx, by, ax, ay, cx, cy), -want);
        /* Scaling by a power of two is exact and keeps the sign. */
        assert_int_equal(tb_orient2d_sign(ax * 0x1p-300, ay * 0x1p-300, bx * 0x1p-300, by * 0x1p-300,
                                          cx * 0x1p-300, cy * 0x1p-300), want);
    }
    print_message("plain double arithmetic got %d of 200000 signs wrong (%d exactly collinear)\n",
                  fast_wrong, zero);
    assert_true(fast_wrong > 0); /* the cases are hard enough to need the exact stage */
    assert_true(zero > 0);

    /* Integer points far from the origin, nearly collinear. */
    for (int t = 0; t < 100000; t++) {
        int64_t ax = (int64_t)tb_rng_u32(&rng) << 19, ay = (int64_t)tb_rng_u32(&rng) << 19;
        int64_t dx = (int64_t)tb_rng_below(&rng, 1u << 20) - (1 << 19);
        int64_t dy = (int64_t)tb_rng_below(&rng, 1u << 20) - (1 << 19);
        int64_t i = tb_rng_below(&rng, 1u << 12), j = tb_rng_below(&rng, 1u << 12);
        int64_t ex = (int64_t)tb_rng_below(&rng, 3) - 1, ey = (int64_t)tb_rng_below(&rng, 3) - 1;
        int64_t bx = ax + i * dx, by = ay + i * dy, cx = ax + j * dx + ex, cy = ay + j * dy + ey;
        assert_int_equal(tb_orient2d_sign((double)ax, (double)ay, (double)bx, (double)by, (double)cx, (double)cy),
                         exact_orient_int(ax, ay, bx, by, cx, cy));
    }

    /* Kettner et al.'s grid near the line y = x: orient((0.5 + i u, 0.5 + j u), (12, 12),
     * (24, 24)) = 12 ((0.5 + j u) - (0.5 + i u)), so the sign is sign(j - i). */
    const double u = 0x1p-53;
    for (int i = 0; i < 64; i++)
        for (int j = 0; j < 64; j++)
            assert_int_equal(tb_orient2d_sign(0.5 + i * u, 0.5 + j * u, 12, 12, 24, 24), (j > i) - (j < i));
}

/* ---------------------------------------------------------- polygon builders */

typedef struct poly {
    double *xy;
    uint32_t n;
    uint32_t rings[512];
    uint32_t nrings;
    uint32_t cap;
} poly;

static void poly_init(poly *p)
{
    memset(p, 0, sizeof *p);
}

static void poly_pt(poly *p, double x, double y)
{
    if (p->n == p->cap) {
        p->cap = p->cap ? 2 * p->cap : 64;
        p->xy = realloc(p->xy, 2 * sizeof(double) * p->cap);
        assert_non_null(p->xy);
    }
    p->xy[2 * p->n] = x;
    p->xy[2 * p->n + 1] = y;
    p->n++;
    p->rings[p->nrings - 1]++;
}

static void poly_ring(poly *p)
{
    assert_true(p->nrings < 512);
    p->rings[p->nrings++] = 0;
}

static void poly_free(poly *p) { free(p->xy); }

static tb_triangulate_stats poly_check(poly *p, uint32_t allowed_flat)
{
    return mt_triangulate_checked(p->xy, p->rings, p->nrings, allowed_flat);
}

/* Adds a ring from a flat list of coordinates. */
static void poly_add(poly *p, const double *c, uint32_t n)
{
    poly_ring(p);
    for (uint32_t k = 0; k < n; k++)
        poly_pt(p, c[2 * k], c[2 * k + 1]);
}

/* --------------------------------------------------------------- hard cases */

static void test_convex_and_orientation(void **state)
{
    (void)state;
    for (int dir = 0; dir < 2; dir++) {
        poly p;
        poly_init(&p);
        poly_ring(&p);
        for (int k = 0; k < 50; k++) {
            double a = (dir ? -1 : 1) * TB_2PI * k / 50;
            poly_pt(&p, cos(a), sin(a));
        }
        tb_triangulate_stats st = poly_check(&p, 0);
        assert_int_equal(st.bridges + st.splices + st.splits + st.degenerate, 0);
        poly_free(&p);
    }
    /* A single triangle, either way round. */
    const double t[] = {0, 0, 1, 0, 0, 1}, tr[] = {0, 0, 0, 1, 1, 0};
    poly p;
    poly_init(&p);
    poly_add(&p, t, 3);
    poly_check(&p, 0);
    poly_free(&p);
    poly_init(&p);
    poly_add(&p, tr, 3);
    poly_check(&p, 0);
    poly_free(&p);
}

static void test_collinear_vertices(void **state)
{
    (void)state;
    /* A square with 10 points on every side: every triangle must still have
     * positive area (no vertex dropped, none degenerate). */
    poly p;
    poly_init(&p);
    poly_ring(&p);
    for (int s = 0; s < 4; s++)
        for (int k = 0; k < 10; k++) {
            double t = k / 10.0;
            double x[4] = {t, 1, 1 - t, 0}, y[4] = {0, t, 1, 1 - t};
            poly_pt(&p, x[s], y[s]);
        }
    poly_check(&p, 0);
    poly_free(&p);

    /* A triangle with 50 points on one side only: one fan. */
    poly_init(&p);
    poly_ring(&p);
    for (int k = 0; k <= 50; k++)
        poly_pt(&p, k, 0);
    poly_pt(&p, 25, 7);
    poly_check(&p, 0);
    poly_free(&p);

    /* A comb: teeth whose sides line up with each other. */
    poly_init(&p);
    poly_ring(&p);
    for (int k = 0; k < 8; k++) {
        poly_pt(&p, 2 * k, 0);
        poly_pt(&p, 2 * k + 1, 0);
        poly_pt(&p, 2 * k + 1, 5);
        poly_pt(&p, 2 * k + 2, 5);
    }
    poly_pt(&p, 16, 6);
    poly_pt(&p, 0, 6);
    poly_check(&p, 0);
    poly_free(&p);

    /* Nearly collinear: the base points are x/3 rounded to double, so the
     * base is a slightly wiggly chain; only exact tests get every sign right. */
    poly_init(&p);
    poly_ring(&p);
    for (int k = 0; k <= 200; k++) {
        double x = 1 + k * 0.1;
        poly_pt(&p, x, x / 3);
    }
    poly_pt(&p, 5, 50);
    poly_check(&p, 0);
    poly_free(&p);
}

static void test_holes(void **state)
{
    (void)state;
    const double outer[] = {0, 0, 10, 0, 10, 10, 0, 10};
    const double hole1[] = {2, 2, 4, 2, 4, 4, 2, 4};            /* counter-clockwise: gets reversed */
    const double hole2[] = {6, 6, 6, 8, 8, 8};                  /* clockwise */
    const double hole3[] = {6, 2, 8, 2, 8, 4, 7, 3, 6, 4};      /* non-convex */
    poly p;
    poly_init(&p);
    poly_add(&p, outer, 4);
    poly_add(&p, hole1, 4);
    tb_triangulate_stats st = poly_check(&p, 0);
    assert_int_equal(st.bridges, 1);
    poly_add(&p, hole2, 3);
    poly_add(&p, hole3, 5);
    st = poly_check(&p, 0);
    assert_int_equal(st.bridges, 3);
    /* n - 2 + 2 * holes */
    assert_int_equal(p.n, 16);
    poly_free(&p);

    /* Holes lined up with outer vertices and each other on the ray. */
    const double o2[] = {0, 0, 20, 0, 20, 2, 0, 2};
    poly_init(&p);
    poly_add(&p, o2, 4);
    for (int k = 0; k < 6; k++) {
        double h[] = {1 + 3 * k, 1, 2 + 3 * k, 0.5, 3 + 3 * k, 1, 2 + 3 * k, 1.5};
        poly_add(&p, h, 4);
    }
    st = poly_check(&p, 0);
    assert_int_equal(st.bridges, 6);
    poly_free(&p);
}

static void test_holes_touching(void **state)
{
    (void)state;
    poly p;
    /* A triangular hole with a corner on the outer corner (0,0). */
    const double sq[] = {0, 0, 4, 0, 4, 4, 0, 4};
    const double h0[] = {0, 0, 2, 1, 1, 2};
    poly_init(&p);
    poly_add(&p, sq, 4);
    poly_add(&p, h0, 3);
    tb_triangulate_stats st = poly_check(&p, 0);
    assert_int_equal(st.splices, 1);
    assert_int_equal(st.bridges, 0);
    poly_free(&p);

    /* A hole touching the boundary at its own leftmost vertex, at an outer
     * vertex in the middle of a side (collinear there). */
    const double sq5[] = {0, 0, 2, 0, 4, 0, 4, 4, 0, 4};
    const double h1[] = {2, 0, 3, 1, 2, 2, 1, 1};
    poly_init(&p);
    poly_add(&p, sq5, 5);
    poly_add(&p, h1, 4);
    st = poly_check(&p, 0);
    assert_int_equal(st.splices, 1);
    poly_free(&p);

    /* Two holes touching each other at a point, neither touching the boundary. */
    const double big[] = {0, 0, 3, 0, 3, 3, 0, 3};
    const double ha[] = {0.5, 0.5, 1.5, 0.5, 1.5, 1.5, 0.5, 1.5};
    const double hb[] = {1.5, 1.5, 2.5, 1.5, 2.5, 2.5, 1.5, 2.5};
    poly_init(&p);
    poly_add(&p, big, 4);
    poly_add(&p, ha, 4);
    poly_add(&p, hb, 4);
    st = poly_check(&p, 0);
    assert_int_equal(st.bridges, 1);
    assert_int_equal(st.splices, 1);
    poly_free(&p);

    /* A hole touching the boundary at two points cuts the square in two:
     * the ring must be split, not triangulated with zero-area slivers. */
    const double h2[] = {0, 0, 3, 1, 4, 4, 1, 3};
    poly_init(&p);
    poly_add(&p, sq, 4);
    poly_add(&p, h2, 4);
    st = poly_check(&p, 0);
    assert_int_equal(st.degenerate, 0);
    poly_free(&p);

    /* An hourglass: one ring through the same point twice. */
    const double hg[] = {0, 0, 2, 0, 1, 1, 2, 2, 0, 2, 1, 1};
    poly_init(&p);
    poly_add(&p, hg, 6);
    st = poly_check(&p, 0);
    assert_int_equal(st.degenerate, 0);
    poly_free(&p);

    /* A grid of square holes touching at corners (a checkerboard). */
    poly_init(&p);
    const double g[] = {0, 0, 6, 0, 6, 6, 0, 6};
    poly_add(&p, g, 4);
    for (int y = 1; y < 5; y++)
        for (int x = 1; x < 5; x++)
            if ((x + y) % 2 == 0) {
                double h[] = {x, y, x + 1, y, x + 1, y + 1, x, y + 1};
                poly_add(&p, h, 4);
            }
    st = poly_check(&p, 0);
    assert_int_equal(st.degenerate, 0);
    poly_free(&p);
}

static void test_slivers_and_duplicates(void **state)
{
    (void)state;
    poly p;
    /* A zigzag band of width 1e-9 over length 1000. */
    poly_init(&p);
    poly_ring(&p);
    for (int k = 0; k <= 100; k++)
        poly_pt(&p, k * 10.0, (k % 2) * 1e-7);
    for (int k = 100; k >= 0; k--)
        poly_pt(&p, k * 10.0, (k % 2) * 1e-7 + 1e-6);
    poly_check(&p, 0);
    poly_free(&p);

    /* A needle triangle with a hole-free sliver interior. */
    const double needle[] = {0, 0, 1e6, 1e-3, 1e6, 2e-3};
    poly_init(&p);
    poly_add(&p, needle, 3);
    poly_check(&p, 0);
    poly_free(&p);

    /* Consecutive duplicate points: a zero-area triangle is unavoidable
     * (the zero-length edge must belong to some triangle). */
    const double dup[] = {0, 0, 1, 0, 1, 0, 1, 1, 0, 1};
    poly_init(&p);
    poly_add(&p, dup, 5);
    tb_triangulate_stats st = poly_check(&p, 1);
    assert_int_equal(st.degenerate, 1);
    poly_free(&p);

    /* A zero-area polygon (all points on a line) still gives n - 2 triangles. */
    const double line[] = {0, 0, 1, 0, 2, 0, 3, 0};
    poly_init(&p);
    poly_add(&p, line, 4);
    poly_check(&p, 2);
    poly_free(&p);
}

/* ------------------------------------------------------------------ random */

/* A star-shaped ring around (cx, cy): sorted random angles, random radii. */
static void add_star(poly *p, tb_rng *rng, double cx, double cy, double rmin, double rmax, int n, bool cw)
{
    double ang[256];
    for (int k = 0; k < n; k++)
        ang[k] = TB_2PI * (k + 0.999 * tb_rng_double(rng)) / n;
    poly_ring(p);
    for (int k = 0; k < n; k++) {
        double a = cw ? -ang[k] : ang[k];
        double r = rmin + (rmax - rmin) * tb_rng_double(rng);
        poly_pt(p, cx + r * cos(a), cy + r * sin(a));
    }
}

static void test_random_star_with_holes(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("star_holes", 21), 2);
    for (int t = 0; t < 300; t++) {
        poly p;
        poly_init(&p);
        /* >= 16 outer points: every gap < 45 degrees, so the inradius is > 0.74 */
        add_star(&p, &rng, 0, 0, 0.8, 1.0, 16 + (int)tb_rng_below(&rng, 60), tb_rng_below(&rng, 2));
        /* Holes in the cells of a grid inside radius 0.6 (cells 0.2 wide). */
        for (int gy = -3; gy < 3; gy++)
            for (int gx = -3; gx < 3; gx++) {
                double cx = (gx + 0.5) * 0.2, cy = (gy + 0.5) * 0.2;
                if (cx * cx + cy * cy > 0.45 * 0.45 || tb_rng_below(&rng, 3) == 0)
                    continue;
                add_star(&p, &rng, cx, cy, 0.03, 0.095, 3 + (int)tb_rng_below(&rng, 6), tb_rng_below(&rng, 2));
            }
        tb_triangulate_stats st = poly_check(&p, 0);
        assert_int_equal(st.bridges, p.nrings - 1);
        poly_free(&p);
    }
}

/* Does segment p0-p1 properly cross q0-q1 (or touch it other than at shared ends)? */
static bool seg_cross(const double *a, const double *b, const double *c, const double *d)
{
    int o1 = tb_orient2d_sign(a[0], a[1], b[0], b[1], c[0], c[1]);
    int o2 = tb_orient2d_sign(a[0], a[1], b[0], b[1], d[0], d[1]);
    int o3 = tb_orient2d_sign(c[0], c[1], d[0], d[1], a[0], a[1]);
    int o4 = tb_orient2d_sign(c[0], c[1], d[0], d[1], b[0], b[1]);
    return o1 * o2 < 0 && o3 * o4 < 0;
}

/* Do closed segments a-b and c-d share a point? */
static bool seg_touch(const double *a, const double *b, const double *c, const double *d)
{
    int o1 = tb_orient2d_sign(a[0], a[1], b[0], b[1], c[0], c[1]);
    int o2 = tb_orient2d_sign(a[0], a[1], b[0], b[1], d[0], d[1]);
    int o3 = tb_orient2d_sign(c[0], c[1], d[0], d[1], a[0], a[1]);
    int o4 = tb_orient2d_sign(c[0], c[1], d[0], d[1], b[0], b[1]);
    if (o1 * o2 < 0 && o3 * o4 < 0)
        return true;
#define ON(p, q, r) (fmin(p[0], q[0]) <= r[0] && r[0] <= fmax(p[0], q[0]) && fmin(p[1], q[1]) <= r[1] && r[1] <= fmax(p[1], q[1]))
    return (o1 == 0 && ON(a, b, c)) || (o2 == 0 && ON(a, b, d)) || (o3 == 0 && ON(c, d, a)) ||
           (o4 == 0 && ON(c, d, b));
#undef ON
}

/* 2-opt: reverses the path between two properly crossing edges until none
 * cross (each move shortens the ring, so this ends). */
static void untangle(double *pts, int n)
{
    for (bool again = true; again;) {
        again = false;
        for (int i = 0; i < n && !again; i++)
            for (int j = i + 2; j < n && !again; j++) {
                if (i == 0 && j == n - 1)
                    continue;
                int i1 = i + 1, j1 = (j + 1) % n;
                if (seg_cross(&pts[2 * i], &pts[2 * i1], &pts[2 * j], &pts[2 * j1])) {
                    for (int a = i1, b = j; a < b; a++, b--)
                        for (int k = 0; k < 2; k++) {
                            double t = pts[2 * a + k];
                            pts[2 * a + k] = pts[2 * b + k];
                            pts[2 * b + k] = t;
                        }
                    again = true;
                }
            }
    }
}

/* Is the ring simple: non-adjacent edges disjoint, adjacent edges meeting
 * only at their shared end, non-zero area? */
static bool ring_is_simple(const double *pts, int n)
{
    for (int i = 0; i < n; i++) {
        const double *a = &pts[2 * i], *b = &pts[2 * ((i + 1) % n)], *c = &pts[2 * ((i + 2) % n)];
        /* b-c must not fold back over a-b */
        if (tb_orient2d_sign(a[0], a[1], b[0], b[1], c[0], c[1]) == 0 &&
            (a[0] - b[0]) * (c[0] - b[0]) + (a[1] - b[1]) * (c[1] - b[1]) > 0)
            return false;
        for (int j = i + 2; j < n; j++) {
            if (i == 0 && j == n - 1)
                continue;
            if (seg_touch(a, b, &pts[2 * j], &pts[2 * ((j + 1) % n)]))
                return false;
        }
    }
    return mt_ring_area2(pts, 0, (uint32_t)n) != 0;
}

/* A random simple polygon: random points, then 2-opt moves (reverse the
 * path between two crossing edges) until nothing crosses. */
static void add_random_simple(poly *p, tb_rng *rng, int n, double cx, double cy, double r)
{
    double pts[2 * 64];
    for (int k = 0; k < n; k++) {
        pts[2 * k] = cx + r * (2 * tb_rng_double(rng) - 1);
        pts[2 * k + 1] = cy + r * (2 * tb_rng_double(rng) - 1);
    }
    untangle(pts, n);
    poly_add(p, pts, (uint32_t)n);
}

static void test_random_simple(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("random_simple", 31), 3);
    for (int t = 0; t < 400; t++) {
        poly p;
        poly_init(&p);
        add_random_simple(&p, &rng, 3 + (int)tb_rng_below(&rng, 40), 0, 0, 1);
        poly_check(&p, 0);
        poly_free(&p);
    }
    /* Random simple holes inside a large square. */
    for (int t = 0; t < 100; t++) {
        poly p;
        poly_init(&p);
        const double sq[] = {-1, -1, 9, -1, 9, 9, -1, 9};
        poly_add(&p, sq, 4);
        for (int gy = 0; gy < 4; gy++)
            for (int gx = 0; gx < 4; gx++)
                if (tb_rng_below(&rng, 2))
                    add_random_simple(&p, &rng, 3 + (int)tb_rng_below(&rng, 12), 2 * gx + 0.5, 2 * gy + 0.5, 0.9);
        poly_check(&p, 0);
        poly_free(&p);
    }
    /* Points on an integer grid: many collinear triples and edges in line. */
    for (int t = 0; t < 300; t++) {
        poly p;
        poly_init(&p);
        double pts[2 * 64];
        int n = 4 + (int)tb_rng_below(&rng, 9);
        for (bool ok = false; !ok;) {
            ok = true;
            for (int k = 0; k < n; k++) {
                pts[2 * k] = tb_rng_below(&rng, 8);
                pts[2 * k + 1] = tb_rng_below(&rng, 8);
                for (int j = 0; j < k; j++)
                    if (pts[2 * j] == pts[2 * k] && pts[2 * j + 1] == pts[2 * k + 1])
                        k--; /* draw again: points are distinct */
            }
            untangle(pts, n);
            ok = ring_is_simple(pts, n);
        }
        poly_add(&p, pts, (uint32_t)n);
        poly_check(&p, 0);
        poly_free(&p);
    }
}

/* --------------------------------------------------------------- large input */

static double seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static void test_large_polygons(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("large", 41), 4);
    const uint32_t n = 100000;
    /* A noisy circle: about half its vertices are reflex. */
    poly p;
    poly_init(&p);
    poly_ring(&p);
    for (uint32_t k = 0; k < n; k++) {
        double a = TB_2PI * k / n, r = 1 + 0.002 * (tb_rng_double(&rng) - 0.5);
        poly_pt(&p, r * cos(a), r * sin(a));
    }
    double t0 = seconds();
    poly_check(&p, 0);
    print_message("noisy circle, %u vertices: %.3f s (triangulation and check)\n", n, seconds() - t0);
    poly_free(&p);

    /* A spiral band: two arms of n/2 vertices each winding 8 times. */
    poly_init(&p);
    poly_ring(&p);
    uint32_t half = n / 2;
    for (uint32_t k = 0; k < half; k++) {
        double a = 8 * TB_2PI * k / half, r = 1 + a;
        poly_pt(&p, r * cos(a), r * sin(a));
    }
    for (uint32_t k = half; k-- > 0;) {
        double a = 8 * TB_2PI * k / half, r = 1 + a + 3;
        poly_pt(&p, r * cos(a), r * sin(a));
    }
    t0 = seconds();
    poly_check(&p, 0);
    print_message("spiral, %u vertices: %.3f s (triangulation and check)\n", n, seconds() - t0);
    poly_free(&p);
}

/* ----------------------------------------------------------------------- 3D */

static void test_triangulate_3d(void **state)
{
    (void)state;
    /* An L-shaped hexagon with a hole, placed on a plane facing -x, -y, -z
     * in turn: triangles must turn counter-clockwise about the normal. */
    const double l2[][2] = {{0, 0}, {4, 0}, {4, 2}, {2, 2}, {2, 4}, {0, 4}, {0.5, 0.5}, {1.5, 0.5}, {1.5, 1.5}, {0.5, 1.5}};
    for (int axis = 0; axis < 3; axis++)
        for (int sign = -1; sign <= 1; sign += 2) {
            tb_vec3 pts[10];
            for (int k = 0; k < 10; k++) {
                float c[3];
                c[axis] = 7.0f;
                c[(axis + 1) % 3] = (float)l2[k][0];
                c[(axis + 2) % 3] = (float)(sign * l2[k][1]);
                pts[k] = tb_vec3_make(c[0], c[1], c[2]);
            }
            uint32_t idx[10], rings[2] = {6, 4};
            for (int k = 0; k < 10; k++)
                idx[k] = (uint32_t)(9 - k) % 10; /* any index mapping */
            tb_vec3 mapped[10];
            for (int k = 0; k < 10; k++)
                mapped[idx[k]] = pts[k];
            tb_array tris = TB_ARRAY_INIT(tb_tri);
            assert_int_equal(tb_triangulate_3d(mapped, idx, rings, 2, &tris, NULL), TB_OK);
            assert_int_equal(tris.len, 10 - 2 + 2);
            tb_dvec3 nrm = tb_polygon_newell(mapped, idx, 6);
            double area = 0;
            for (size_t t = 0; t < tris.len; t++) {
                const uint32_t *v = TB_ARRAY_AT(&tris, tb_tri, t).v;
                tb_vec3 e1 = tb_vec3_sub(mapped[v[1]], mapped[v[0]]), e2 = tb_vec3_sub(mapped[v[2]], mapped[v[0]]);
                tb_vec3 cr = tb_vec3_cross(e1, e2);
                double d = cr.x * nrm.x + cr.y * nrm.y + cr.z * nrm.z;
                assert_true(d > 0);
                area += tb_vec3_length(cr) / 2;
            }
            tb_assert_near(area, 12.0 - 1.0, 1e-5);
            tb_array_free(&tris);
        }
}

static void test_bad_arguments(void **state)
{
    (void)state;
    tb_array tris = TB_ARRAY_INIT(tb_tri);
    const double xy[] = {0, 0, 1, 0, 0, 1, NAN, 0};
    uint32_t r2[] = {2};
    assert_int_equal(tb_triangulate_2d(xy, r2, 1, &tris, NULL), TB_ERR_ARG);
    uint32_t r4[] = {4};
    assert_int_equal(tb_triangulate_2d(xy, r4, 1, &tris, NULL), TB_ERR_ARG);
    assert_int_equal(tris.len, 0);
    tb_array wrong = TB_ARRAY_INIT(double);
    uint32_t r3[] = {3};
    assert_int_equal(tb_triangulate_2d(xy, r3, 1, &wrong, NULL), TB_ERR_ARG);
    tb_array_free(&tris);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_orient2d_exact),
        cmocka_unit_test(test_convex_and_orientation),
        cmocka_unit_test(test_collinear_vertices),
        cmocka_unit_test(test_holes),
        cmocka_unit_test(test_holes_touching),
        cmocka_unit_test(test_slivers_and_duplicates),
        cmocka_unit_test(test_random_star_with_holes),
        cmocka_unit_test(test_random_simple),
        cmocka_unit_test(test_large_polygons),
        cmocka_unit_test(test_triangulate_3d),
        cmocka_unit_test(test_bad_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
