/* Form factors (host/radiosity/formfactor.h) against closed forms from
 * Howell's catalogue (ff_cases.h), an independent Gauss-Legendre quadrature
 * of the form-factor integral, and physical identities: a closed cube's form
 * factors sum to 1, reciprocity, a blocker hiding exactly half the view. */
#include "tb_test.h"

#include <string.h>

#include <omp.h>

#include "ff_cases.h"
#include "util/math/rng.h"

/* The polygon with its corners reversed if its normal does not point along dir. */
static tb_ff_polygon facing(tb_ff_polygon p, tb_vec3 dir)
{
    tb_vec3 n;
    double a;
    tb_ff_polygon_frame(&p, &n, &a);
    if (tb_vec3_dot(n, dir) < 0.0f) {
        tb_ff_polygon r = p;
        for (int k = 0; k < p.n; k++)
            r.v[k] = p.v[p.n - 1 - k];
        return r;
    }
    return p;
}

/* Axis-aligned rectangle in the plane z = z0: [x0, x1] x [y0, y1], facing dir. */
static tb_ff_polygon rect_z(double x0, double x1, double y0, double y1, double z0, tb_vec3 dir)
{
    tb_ff_polygon p = ff_quad((tb_vec3){(float)x0, (float)y0, (float)z0}, (tb_vec3){(float)x1, (float)y0, (float)z0},
                              (tb_vec3){(float)x1, (float)y1, (float)z0}, (tb_vec3){(float)x0, (float)y1, (float)z0});
    return facing(p, dir);
}

/* Gauss-Legendre nodes and weights on [0, 1] (Newton on P_n). */
static void gauss_legendre(int n, double *x, double *w)
{
    for (int i = 0; i < n; i++) {
        double z = cos(FF_PI * (i + 0.75) / (n + 0.5)), dp = 1.0;
        for (int it = 0; it < 100; it++) {
            double p0 = 1.0, p1 = z;
            for (int k = 2; k <= n; k++) {
                double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (z * p1 - p0) / (z * z - 1.0);
            double dz = p1 / dp;
            z -= dz;
            if (fabs(dz) < 1e-16)
                break;
        }
        x[i] = 0.5 * (1.0 - z);
        w[i] = 1.0 / ((1.0 - z * z) * dp * dp);
    }
}

/* ------------------------------------------------------------------ frame */

static void test_frame(void **state)
{
    (void)state;
    tb_ff_polygon q = rect_z(0, 2, 0, 3, 5, (tb_vec3){0, 0, -1});
    tb_vec3 n;
    double a;
    tb_ff_polygon_frame(&q, &n, &a);
    tb_assert_near(a, 6.0, 1e-12);
    tb_assert_near(n.z, -1.0, 1e-7);
    tb_ff_polygon t = ff_tri((tb_vec3){0, 0, 0}, (tb_vec3){1, 0, 0}, (tb_vec3){0, 0, 1});
    tb_ff_polygon_frame(&t, &n, &a);
    tb_assert_near(a, 0.5, 1e-12);
    tb_assert_near(n.y, -1.0, 1e-7);
    /* Degenerate: collinear corners. */
    tb_ff_polygon d = ff_tri((tb_vec3){0, 0, 0}, (tb_vec3){1, 1, 1}, (tb_vec3){2, 2, 2});
    tb_ff_polygon_frame(&d, &n, &a);
    assert_true(a == 0.0);
    assert_true(n.x == 0.0f && n.y == 0.0f && n.z == 0.0f);
}

/* ------------------------------------------------------------ point to polygon */

/* B-3 at three scales (all corner coordinates exact in float). */
static void test_point_b3(void **state)
{
    (void)state;
    const double scales[] = {1.0 / 1024.0, 1.0, 8192.0};
    const double dims[][3] = {{1, 1, 1}, {0.5, 2, 1}, {3, 0.25, 0.75}, {8, 8, 0.125}, {0.125, 0.25, 4}};
    for (int s = 0; s < 3; s++)
        for (int d = 0; d < 5; d++) {
            double k = scales[s], a = dims[d][0] * k, b = dims[d][1] * k, c = dims[d][2] * k;
            tb_ff_polygon r = rect_z(0, a, 0, b, c, (tb_vec3){0, 0, -1});
            double f = tb_ff_point_polygon((tb_vec3){0, 0, 0}, (tb_vec3){0, 0, 1}, &r);
            double ref = ff_howell_b3(dims[d][0], dims[d][1], dims[d][2]);
            tb_assert_near(f, ref, 1e-12 * ref);
        }
}

/* A point under the inside of a rectangle: the sum of four B-3 corners. */
static void test_point_offcenter(void **state)
{
    (void)state;
    tb_ff_polygon r = rect_z(-1, 2, -0.5, 1.5, 1.5, (tb_vec3){0, 0, -1});
    double f = tb_ff_point_polygon((tb_vec3){0, 0, 0}, (tb_vec3){0, 0, 1}, &r);
    double ref = ff_howell_b3(1, 0.5, 1.5) + ff_howell_b3(2, 0.5, 1.5) + ff_howell_b3(1, 1.5, 1.5) +
                 ff_howell_b3(2, 1.5, 1.5);
    tb_assert_near(f, ref, 1e-12);
    /* Translating everything far from the origin changes nothing much. */
    tb_vec3 off = {1000.0f, -2000.0f, 500.0f};
    tb_ff_polygon rt = r;
    for (int k = 0; k < 4; k++)
        rt.v[k] = tb_vec3_add(r.v[k], off);
    tb_assert_near(tb_ff_point_polygon(off, (tb_vec3){0, 0, 1}, &rt), ref, 1e-6);
}

/* Back side, in-plane receivers, polygons behind the tangent plane: 0. */
static void test_point_zero_cases(void **state)
{
    (void)state;
    tb_vec3 o = {0, 0, 0}, up = {0, 0, 1};
    tb_ff_polygon down = rect_z(-1, 1, -1, 1, 1, (tb_vec3){0, 0, -1});
    tb_ff_polygon upw = rect_z(-1, 1, -1, 1, 1, (tb_vec3){0, 0, 1});
    assert_true(tb_ff_point_polygon(o, up, &down) > 0.0);
    assert_true(tb_ff_point_polygon(o, up, &upw) == 0.0);                       /* its back */
    assert_true(tb_ff_point_polygon(o, (tb_vec3){0, 0, -1}, &down) == 0.0);     /* behind the receiver */
    /* Receiver in the shooter's plane (a coplanar neighbour, and on its edge). */
    tb_ff_polygon flat = rect_z(1, 2, -1, 1, 0, up);
    assert_true(tb_ff_point_polygon(o, up, &flat) == 0.0);
    assert_true(tb_ff_point_polygon((tb_vec3){1, 0, 0}, up, &flat) == 0.0);
    assert_true(tb_ff_point_polygon((tb_vec3){0.5f, 0, 0}, (tb_vec3){1, 0, 0}, &flat) == 0.0);
    /* Degenerate polygons give 0, not NaN. */
    tb_ff_polygon line = ff_tri((tb_vec3){0, 0, 1}, (tb_vec3){1, 0, 1}, (tb_vec3){2, 0, 1});
    tb_ff_polygon point = ff_tri((tb_vec3){0, 0, 1}, (tb_vec3){0, 0, 1}, (tb_vec3){0, 0, 1});
    assert_true(tb_ff_point_polygon(o, up, &line) == 0.0);
    assert_true(tb_ff_point_polygon(o, up, &point) == 0.0);
    tb_ff_polygon bad = down;
    bad.n = 5;
    assert_true(tb_ff_point_polygon(o, up, &bad) == 0.0);
    bad.n = 4;
    bad.v[2].x = NAN;
    double f = tb_ff_point_polygon(o, up, &bad);
    assert_false(isnan(f));
    assert_true(tb_ff_point_polygon(o, (tb_vec3){0, 0, 0}, &down) == 0.0); /* zero normal */
}

/* Rotation of v by the unit quaternion (w, x, y, z) plus an offset, in float
 * (as a scene's transform leaves element corners: rounded off every plane). */
static tb_vec3 rot(tb_vec3 v, const double q[4], tb_vec3 off)
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    double m[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                      {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                      {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
    double a[3] = {v.x, v.y, v.z}, r[3];
    for (int i = 0; i < 3; i++)
        r[i] = m[i][0] * a[0] + m[i][1] * a[1] + m[i][2] * a[2];
    return (tb_vec3){(float)(r[0] + off.x), (float)(r[1] + off.y), (float)(r[2] + off.z)};
}

/* Float noise off the planes: receivers on a coplanar neighbour's corner or
 * edge see nothing, and a polygon with corners on the receiver's tangent
 * plane gives the value of the noise-free (axis-aligned) configuration. */
/* A twisted quad (corners alternately 0 and 1.5 high) seen from a point at
 * height 1 looking down: its tangent plane puts the corners alternately in
 * front and behind, so clipping keeps 2 corners and adds 4 crossings, six
 * points (a whole, slightly twisted Cornell box face did this and overran
 * the clip buffer, crashing `--max-edge 0`). Finite and in (0, 1). */
static void test_point_twisted(void **state)
{
    (void)state;
    tb_ff_polygon q = {.n = 4, .v = {{0, 0, 0}, {1, 0, 1.5f}, {1, 1, 0}, {0, 1, 1.5f}}};
    double f = tb_ff_point_polygon((tb_vec3){0.5f, 0.5f, 1}, (tb_vec3){0, 0, -1}, &q);
    assert_true(f > 0.0 && f < 1.0);
}

static void test_point_noise(void **state)
{
    (void)state;
    double q[4] = {0.8, 0.3, -0.4, 0.2};
    double ql = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (int i = 0; i < 4; i++)
        q[i] /= ql;
    const float offs[3] = {0.0f, 3.7f, 250.0f};
    const double scales[3] = {1.0, 1e-3, 1e3};
    for (int o = 0; o < 3; o++)
        for (int sc = 0; sc < 3; sc++) {
            float s = (float)scales[sc];
            tb_vec3 off = {offs[o] * s, -0.6f * offs[o] * s, 0.3f * offs[o] * s};
            tb_vec3 up = rot((tb_vec3){0, 0, 1}, q, (tb_vec3){0, 0, 0});
            /* Shooter on z = 0 facing +z; coplanar receivers at its corner,
             * on its edge and beside it. */
            tb_ff_polygon sh = ff_quad(rot((tb_vec3){0, 0, 0}, q, off), rot((tb_vec3){s, 0, 0}, q, off),
                                       rot((tb_vec3){s, s, 0}, q, off), rot((tb_vec3){0, s, 0}, q, off));
            tb_vec3 pc = rot((tb_vec3){s, s, 0}, q, off), pe = rot((tb_vec3){s, 0.37f * s, 0}, q, off);
            tb_vec3 pb = rot((tb_vec3){1.5f * s, 0.5f * s, 0}, q, off);
            assert_true(tb_ff_point_polygon(pc, up, &sh) == 0.0);
            assert_true(tb_ff_point_polygon(pe, up, &sh) == 0.0);
            assert_true(tb_ff_point_polygon(pb, up, &sh) == 0.0);
            /* A wall on x = s facing -x beside the shooter (C-14's geometry):
             * from points on z = 0 its bottom corners are on the tangent plane. */
            tb_ff_polygon wall = ff_quad(rot((tb_vec3){s, 0, 0}, q, off), rot((tb_vec3){s, 0, s}, q, off),
                                         rot((tb_vec3){s, s, s}, q, off), rot((tb_vec3){s, s, 0}, q, off));
            tb_ff_polygon wall0 = ff_quad((tb_vec3){1, 0, 0}, (tb_vec3){1, 0, 1}, (tb_vec3){1, 1, 1}, (tb_vec3){1, 1, 0});
            const float at[3][2] = {{0.5f, 0.5f}, {0.99f, 0.25f}, {0.999f, 0.5f}};
            for (int k = 0; k < 3; k++) {
                tb_vec3 p = rot((tb_vec3){at[k][0] * s, at[k][1] * s, 0}, q, off);
                double ref = tb_ff_point_polygon((tb_vec3){at[k][0], at[k][1], 0}, (tb_vec3){0, 0, 1}, &wall0);
                double f = tb_ff_point_polygon(p, up, &wall);
                /* the float corners move by ~1e-7 of the coordinates: at
                 * 250 units from the origin and 0.001 from the wall, ~1e-3 relative */
                tb_assert_near(f, ref, (o == 2 ? 3e-3 : 1e-4) * ref);
            }
            /* The receiver on the wall's bottom edge is in its plane. */
            assert_true(tb_ff_point_polygon(rot((tb_vec3){s, 0.5f * s, 0}, q, off), up, &wall) == 0.0);
        }
}

/* A plate straddling the receiver's tangent plane: only the part above
 * counts. Reference: Gauss-Legendre quadrature of cos cos / (pi r^2) over
 * the upper half (smooth there). */
static void test_point_straddle(void **state)
{
    (void)state;
    /* Plate x = 1, y in [-0.5, 0.5], z in [-1, 1], facing -x; receiver at
     * the origin facing +z (the tangent plane cuts the plate at z = 0), and
     * tilted about the y axis (the cut is still along y). */
    tb_ff_polygon plate = facing(ff_quad((tb_vec3){1, -0.5f, -1}, (tb_vec3){1, 0.5f, -1}, (tb_vec3){1, 0.5f, 1},
                                         (tb_vec3){1, -0.5f, 1}),
                                 (tb_vec3){-1, 0, 0});
    const double tilts[] = {0.0, 0.3, -0.4};
    double x[40], w[40];
    gauss_legendre(40, x, w);
    for (int t = 0; t < 3; t++) {
        double th = tilts[t];
        double nx = sin(th), nz = cos(th);
        /* Above the tangent plane: nx * 1 + nz * z > 0, i.e. z > -nx / nz. */
        double z0 = -nx / nz, z1 = 1.0, ref = 0.0;
        for (int i = 0; i < 40; i++)
            for (int j = 0; j < 40; j++) {
                double y = -0.5 + x[i], z = z0 + (z1 - z0) * x[j];
                double r2 = 1.0 + y * y + z * z;
                double cr = (nx * 1.0 + nz * z), cs = 1.0;
                ref += w[i] * w[j] * (z1 - z0) * cr * cs / (FF_PI * r2 * r2);
            }
        double f = tb_ff_point_polygon((tb_vec3){0, 0, 0}, (tb_vec3){(float)nx, 0, (float)nz}, &plate);
        tb_assert_near(f, ref, 1e-7 * ref); /* the float normal limits the agreement */
    }
}

/* The faces of the cube [0, 1]^3 as inward-facing elements: 2 x 2 quads on
 * four faces, 4 triangles on the other two (centre fans). Returns the count. */
static int cube_elements(tb_ff_polygon *out)
{
    int k = 0;
    for (int face = 0; face < 6; face++) {
        int axis = face / 2;
        float side = (float)(face % 2);
        tb_vec3 in = {0, 0, 0};
        if (axis == 0) in.x = side ? -1.0f : 1.0f;
        if (axis == 1) in.y = side ? -1.0f : 1.0f;
        if (axis == 2) in.z = side ? -1.0f : 1.0f;
        if (axis < 2) {
            for (int j = 0; j < 2; j++)
                for (int i = 0; i < 2; i++) {
                    float a0 = 0.5f * i, a1 = a0 + 0.5f, b0 = 0.5f * j, b1 = b0 + 0.5f;
                    float c[4][2] = {{a0, b0}, {a1, b0}, {a1, b1}, {a0, b1}};
                    tb_ff_polygon p = {.n = 4};
                    for (int v = 0; v < 4; v++) {
                        float q[3];
                        q[axis] = side;
                        q[(axis + 1) % 3] = c[v][0];
                        q[(axis + 2) % 3] = c[v][1];
                        p.v[v] = (tb_vec3){q[0], q[1], q[2]};
                    }
                    out[k++] = facing(p, in);
                }
        } else {
            float c[5][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0, 0}};
            for (int e = 0; e < 4; e++) {
                float q0[3], q1[3], qc[3];
                q0[2] = q1[2] = qc[2] = side;
                q0[0] = c[e][0];
                q0[1] = c[e][1];
                q1[0] = c[e + 1][0];
                q1[1] = c[e + 1][1];
                qc[0] = qc[1] = 0.5f;
                tb_ff_polygon p = ff_tri((tb_vec3){qc[0], qc[1], qc[2]}, (tb_vec3){q0[0], q0[1], q0[2]},
                                         (tb_vec3){q1[0], q1[1], q1[2]});
                out[k++] = facing(p, in);
            }
        }
    }
    return k;
}

/* From any interior point with any normal, the cube's form factors sum to 1:
 * exactly for the contour integral (every face that straddles the tangent
 * plane is clipped), approximately for ray casting through the cube as
 * occluders and for the hemicube. */
static void test_closed_cube(void **state)
{
    (void)state;
    tb_ff_polygon el[24];
    int n = cube_elements(el);
    assert_int_equal(n, 24);
    tb_ff_occluders *occ = NULL;
    assert_int_equal(tb_ff_occluders_build(el, (size_t)n, &occ), TB_OK);
    tb_hemicube *hc = tb_hemicube_create(128);
    assert_non_null(hc);
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("closed_cube", 11), 0);
    tb_vec3 pts[256];
    double hff[24];
    for (int trial = 0; trial < 12; trial++) {
        tb_vec3 p = {0.2f + 0.6f * tb_rng_float(&rng), 0.2f + 0.6f * tb_rng_float(&rng),
                     0.2f + 0.6f * tb_rng_float(&rng)};
        tb_vec3 nrm;
        do {
            nrm = (tb_vec3){2 * tb_rng_float(&rng) - 1, 2 * tb_rng_float(&rng) - 1, 2 * tb_rng_float(&rng) - 1};
        } while (tb_vec3_length(nrm) < 0.2f || tb_vec3_length(nrm) > 1.0f);
        nrm = tb_vec3_normalize(nrm);
        if (trial == 0)
            nrm = (tb_vec3){0, 0, 1};
        double sum = 0.0, sum_rc = 0.0;
        for (int i = 0; i < n; i++) {
            sum += tb_ff_point_polygon(p, nrm, &el[i]);
            tb_vec3 ns;
            double area;
            tb_ff_polygon_frame(&el[i], &ns, &area);
            assert_int_equal(tb_ff_sample_polygon(&el[i], 256, (uint64_t)i, pts), TB_OK);
            sum_rc += tb_ff_raycast(pts, 256, ns, area, p, nrm, tb_ff_occluders_visible, occ);
        }
        tb_assert_near(sum, 1.0, 1e-12);
        tb_assert_near(sum_rc, 1.0, 0.02); /* eq. 5's disk term biases low (docs/formfactors.md) */
        assert_int_equal(tb_hemicube_formfactors(hc, p, nrm, el, (size_t)n, TB_FF_NONE, hff), TB_OK);
        double sum_hc = 0.0;
        for (int i = 0; i < n; i++) {
            sum_hc += hff[i];
            tb_assert_near(hff[i], tb_ff_point_polygon(p, nrm, &el[i]), 2e-3);
        }
        tb_assert_near(sum_hc, 1.0, 1e-4);
    }
    tb_hemicube_free(hc);
    tb_ff_occluders_free(occ);
}

/* The hemicube covers every pixel exactly once when elements share edges
 * that its frustum planes clip: from random centres and normals, a room of
 * 6 x 7 x 7 elements and the same room as 6 whole walls both give the sum of
 * all delta form factors, to rounding. */
static void test_hemicube_watertight(void **state)
{
    (void)state;
    enum { G = 7, NP = 6 * G * G };
    static tb_ff_polygon fine[NP], walls[6];
    for (int pass = 0; pass < 2; pass++) {
        int g = pass ? 1 : G, k = 0;
        tb_ff_polygon *out = pass ? walls : fine;
        for (int face = 0; face < 6; face++) {
            int axis = face / 2;
            float side = (float)(face % 2);
            tb_vec3 in = {0, 0, 0};
            if (axis == 0) in.x = side ? -1.0f : 1.0f;
            if (axis == 1) in.y = side ? -1.0f : 1.0f;
            if (axis == 2) in.z = side ? -1.0f : 1.0f;
            for (int j = 0; j < g; j++)
                for (int i = 0; i < g; i++) {
                    /* Uneven spacing (edges at irrational-looking places), the
                     * same along every axis so that walls meeting at a cube
                     * edge share their vertices there (no T-junctions). */
                    float c[4][2];
                    float a0 = (float)pow((double)i / g, 1.1), a1 = (float)pow((double)(i + 1) / g, 1.1);
                    float b0 = (float)pow((double)j / g, 1.1), b1 = (float)pow((double)(j + 1) / g, 1.1);
                    c[0][0] = a0; c[0][1] = b0; c[1][0] = a1; c[1][1] = b0;
                    c[2][0] = a1; c[2][1] = b1; c[3][0] = a0; c[3][1] = b1;
                    tb_ff_polygon p = {.n = 4};
                    for (int v = 0; v < 4; v++) {
                        float q[3];
                        q[axis] = side;
                        q[(axis + 1) % 3] = c[v][0];
                        q[(axis + 2) % 3] = c[v][1];
                        p.v[v] = (tb_vec3){q[0], q[1], q[2]};
                    }
                    out[k++] = facing(p, in);
                }
        }
    }
    tb_hemicube *hc = tb_hemicube_create(64);
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("hemicube_watertight", 3), 0);
    static double ff[NP];
    for (int trial = 0; trial < 20; trial++) {
        tb_vec3 p = {0.1f + 0.8f * tb_rng_float(&rng), 0.1f + 0.8f * tb_rng_float(&rng),
                     0.1f + 0.8f * tb_rng_float(&rng)};
        tb_vec3 nrm = tb_vec3_normalize((tb_vec3){2 * tb_rng_float(&rng) - 1, 2 * tb_rng_float(&rng) - 1,
                                                  2 * tb_rng_float(&rng) - 1});
        assert_int_equal(tb_hemicube_formfactors(hc, p, nrm, fine, NP, TB_FF_NONE, ff), TB_OK);
        double s1 = 0.0, s2 = 0.0;
        for (int i = 0; i < NP; i++)
            s1 += ff[i];
        assert_int_equal(tb_hemicube_formfactors(hc, p, nrm, walls, 6, TB_FF_NONE, ff), TB_OK);
        for (int i = 0; i < 6; i++)
            s2 += ff[i];
        tb_assert_near(s1, s2, 1e-9);
        tb_assert_near(s2, 1.0, 2e-4); /* the delta form factors' own sum at 64 */
    }
    tb_hemicube_free(hc);
}

/* A wall 10^-4 from the centre, with a polygon 10^2 away in the same call:
 * the near plane is relative to the farthest corner, so the wall is kept. */
static void test_hemicube_close(void **state)
{
    (void)state;
    tb_ff_polygon scene[2] = {
        facing(ff_quad((tb_vec3){0, 0, 0}, (tb_vec3){0, 1, 0}, (tb_vec3){0, 1, 1}, (tb_vec3){0, 0, 1}),
               (tb_vec3){1, 0, 0}),
        rect_z(-100, 100, -100, 100, 100, (tb_vec3){0, 0, -1}),
    };
    tb_vec3 p = {1e-4f, 0.5f, 0}, up = {0, 0, 1};
    tb_hemicube *hc = tb_hemicube_create(256);
    double ff[2];
    assert_int_equal(tb_hemicube_formfactors(hc, p, up, scene, 2, TB_FF_NONE, ff), TB_OK);
    double exact = tb_ff_point_polygon(p, up, &scene[0]);
    assert_true(exact > 0.4);
    tb_assert_near(ff[0], exact, 5e-3);
    tb_hemicube_free(hc);
}

/* Twisted (non-planar) quads around the hemicube: a plane can cross such a
 * quad four times, so the frustum clipping grows it by up to half its
 * corners per plane (4 -> 28), not one per plane as for convex polygons.
 * The sanitizer build catches an overflow of the clip buffers; here every
 * answer must also be a form factor. */
static void test_hemicube_twisted(void **state)
{
    (void)state;
    tb_hemicube *hc = tb_hemicube_create(32);
    assert_non_null(hc);
    uint64_t x = 0x9e3779b97f4a7c15u;
    double sum_max = 0.0;
    for (int trial = 0; trial < 20000; trial++) {
        tb_ff_polygon q = {.n = 4};
        for (int k = 0; k < 4; k++) {
            float c[3];
            for (int a = 0; a < 3; a++) {
                x ^= x << 13, x ^= x >> 7, x ^= x << 17;
                c[a] = (float)((double)(x >> 11) * 0x1.0p-53 * 4.0 - 2.0);
            }
            q.v[k] = (tb_vec3){c[0], c[1], c[2] + 0.6f};
        }
        double ff = -1.0;
        assert_int_equal(tb_hemicube_formfactors(hc, (tb_vec3){0, 0, 0}, (tb_vec3){0, 0, 1}, &q, 1, TB_FF_NONE, &ff),
                         TB_OK);
        assert_true(ff >= 0.0 && ff <= 1.0 + 1e-9);
        sum_max = ff > sum_max ? ff : sum_max;
    }
    assert_true(sum_max > 0.05); /* the quads were seen */
    tb_hemicube_free(hc);
}

/* ------------------------------------------------------------ Howell, area to area */

/* Integrating the exact point form factor over a receiver grid reproduces
 * the catalogue (the midpoint rule's own error is ~4e-5 at 48 x 48). */
static void test_howell_exact(void **state)
{
    (void)state;
    static ff_case c;
    ff_case_c11(&c, 1.0);
    tb_assert_near(ff_case_exact_grid(&c, 48), c.exact, 1e-4 * c.exact);
    ff_case_c14(&c, 1.0);
    tb_assert_near(ff_case_exact_grid(&c, 48), c.exact, 1e-4 * c.exact);
    ff_case_c41(&c, 1.0, 64);
    tb_assert_near(ff_case_exact_grid(&c, 48), c.exact, 1e-4 * c.exact);
    /* Tiny and huge scales give the same answer. */
    ff_case_c11(&c, 1e-3);
    tb_assert_near(ff_case_exact_grid(&c, 16), ff_howell_c11(1, 1, 1), 1e-3 * c.exact);
    ff_case_c14(&c, 1e4);
    tb_assert_near(ff_case_exact_grid(&c, 16), ff_howell_c14(1, 1, 1), 1e-3 * c.exact);
}

/* Ray casting converges to the catalogue as the samples grow; its error is
 * dominated by eq. 5's disk term, which biases it low by about the sample
 * area over pi r^2 (docs/formfactors.md, "Accuracy"). */
static void test_howell_raycast(void **state)
{
    (void)state;
    static ff_case c;
    ff_case_c41(&c, 1.0, 64);
    double f16 = ff_case_raycast(&c, 24, 16, 1, NULL);
    tb_assert_near(f16, c.exact, 5e-3 * c.exact); /* 64 triangles x 16 samples */
    ff_case_c11(&c, 1.0);
    double e[4];
    const int ns[4] = {4, 16, 64, 256};
    for (int s = 0; s < 4; s++)
        e[s] = fabs(ff_case_raycast(&c, 24, ns[s], 3, NULL) - c.exact) / c.exact;
    assert_true(e[1] < e[0] && e[2] < e[1] && e[3] < e[2]);
    assert_true(e[1] < 0.03);
    assert_true(e[2] < 0.01);
    assert_true(e[3] < 0.003);
    /* Samples at the strata's centres suit eq. 5's disk term better: less
     * than half the jittered bias at 16 samples, for C-11 and C-14. */
    double jit16 = 0.0;
    for (int seed = 0; seed < 8; seed++)
        jit16 += (ff_case_raycast(&c, 24, 16, (uint64_t)seed * 7, NULL) - c.exact) / 8.0;
    double cen16 = ff_case_raycast_ex(&c, 24, 16, 0, 1, NULL) - c.exact;
    assert_true(jit16 < 0.0 && cen16 < 0.0 && fabs(cen16) < 0.5 * fabs(jit16));
    static ff_case c14;
    ff_case_c14(&c14, 1.0);
    double jit14 = 0.0;
    for (int seed = 0; seed < 8; seed++)
        jit14 += (ff_case_raycast(&c14, 24, 16, (uint64_t)seed * 7, NULL) - c14.exact) / 8.0;
    double cen14 = ff_case_raycast_ex(&c14, 24, 16, 0, 1, NULL) - c14.exact;
    print_message("[ info     ] 16 samples, jittered (mean of 8 seeds) / centres: C-11 %+.2e / %+.2e, C-14 %+.2e / %+.2e\n",
                  jit16 / c.exact, cen16 / c.exact, jit14 / c14.exact, cen14 / c14.exact);
    assert_true(jit14 < 0.0 && cen14 < 0.0 && fabs(cen14) < fabs(jit14));
    /* The same at 1e-3 and 1e4 scale (relative segment margins, double sums). */
    static ff_case small, big;
    ff_case_c11(&small, 1e-3);
    ff_case_c11(&big, 1e4);
    double f1 = ff_case_raycast(&c, 8, 16, 5, NULL);
    tb_assert_near(ff_case_raycast(&small, 8, 16, 5, NULL), f1, 1e-5);
    tb_assert_near(ff_case_raycast(&big, 8, 16, 5, NULL), f1, 1e-5);
}

/* The hemicube's error against the exact point form factor at the same
 * receivers falls as the resolution grows. */
static void test_howell_hemicube(void **state)
{
    (void)state;
    static ff_case cases[3];
    ff_case_c11(&cases[0], 1.0);
    ff_case_c14(&cases[1], 1.0);
    ff_case_c41(&cases[2], 1.0, 64);
    for (int c = 0; c < 3; c++) {
        double ref = ff_case_exact_grid(&cases[c], 6);
        double e16 = fabs(ff_case_hemicube(&cases[c], 6, 16) - ref);
        double e64 = fabs(ff_case_hemicube(&cases[c], 6, 64) - ref);
        double e256 = fabs(ff_case_hemicube(&cases[c], 6, 256) - ref);
        print_message("[ info     ] %s: |hemicube - exact| at 16, 64, 256: %.2e %.2e %.2e\n", cases[c].name, e16,
                      e64, e256);
        assert_true(e256 < e16);
        assert_true(e256 < 2e-3 * ref);
    }
    /* Scale-free. */
    static ff_case big;
    ff_case_c14(&big, 1e4);
    tb_assert_near(ff_case_hemicube(&big, 4, 64), ff_case_hemicube(&cases[1], 4, 64), 1e-5);
}

/* A1 F12 = A2 F21 for two unequal polygons in general position. */
static void test_reciprocity(void **state)
{
    (void)state;
    tb_ff_polygon p1 = rect_z(0, 1, 0, 2, 0, (tb_vec3){0, 0, 1});
    tb_ff_polygon p2 = facing(ff_tri((tb_vec3){-0.5f, 0.2f, 1.0f}, (tb_vec3){2, 0, 1.5f}, (tb_vec3){0, 1.5f, 2.2f}),
                              (tb_vec3){0.2f, 0, -1});
    tb_vec3 n1, n2;
    double a1, a2;
    tb_ff_polygon_frame(&p1, &n1, &a1);
    tb_ff_polygon_frame(&p2, &n2, &a2);
    enum { N = 4096 };
    static tb_vec3 q1[N], q2[N];
    assert_int_equal(tb_ff_sample_polygon(&p1, N, 1, q1), TB_OK);
    assert_int_equal(tb_ff_sample_polygon(&p2, N, 2, q2), TB_OK);
    double f12 = 0.0, f21 = 0.0;
    for (int i = 0; i < N; i++) {
        f12 += tb_ff_point_polygon(q1[i], n1, &p2) / N;
        f21 += tb_ff_point_polygon(q2[i], n2, &p1) / N;
    }
    assert_true(f12 > 0.05);
    tb_assert_near(a1 * f12, a2 * f21, 1e-3 * a1 * f12);
    /* The hemicube too (coarser receivers: 64 each). */
    tb_hemicube *hc = tb_hemicube_create(256);
    double h12 = 0.0, h21 = 0.0, ff;
    assert_int_equal(tb_ff_sample_polygon(&p1, 64, 3, q1), TB_OK);
    assert_int_equal(tb_ff_sample_polygon(&p2, 64, 4, q2), TB_OK);
    for (int i = 0; i < 64; i++) {
        assert_int_equal(tb_hemicube_formfactors(hc, q1[i], n1, &p2, 1, TB_FF_NONE, &ff), TB_OK);
        h12 += ff / 64;
        assert_int_equal(tb_hemicube_formfactors(hc, q2[i], n2, &p1, 1, TB_FF_NONE, &ff), TB_OK);
        h21 += ff / 64;
    }
    tb_hemicube_free(hc);
    tb_assert_near(a1 * h12, a2 * h21, 0.02 * a1 * h12);
}

/* ------------------------------------------------------------ occlusion */

/* A blocker plate halfway to the shooter hides exactly its x < 0 half. */
static void test_blocker(void **state)
{
    (void)state;
    tb_vec3 p = {0, 0, 0}, up = {0, 0, 1};
    tb_ff_polygon scene[2];
    scene[0] = rect_z(-1, 1, -1, 1, 2, (tb_vec3){0, 0, -1});  /* shooter */
    scene[1] = rect_z(-2, 0, -2, 2, 1, (tb_vec3){0, 0, -1});  /* blocker */
    tb_ff_polygon half = rect_z(0, 1, -1, 1, 2, (tb_vec3){0, 0, -1});
    double exact = tb_ff_point_polygon(p, up, &half);
    tb_assert_near(exact, 0.5 * tb_ff_point_polygon(p, up, &scene[0]), 1e-12);

    tb_ff_occluders *occ = NULL;
    assert_int_equal(tb_ff_occluders_build(scene, 2, &occ), TB_OK);
    tb_vec3 pts[256], ns;
    double area;
    tb_ff_polygon_frame(&scene[0], &ns, &area);
    assert_int_equal(tb_ff_sample_polygon(&scene[0], 256, 9, pts), TB_OK);
    double open = tb_ff_raycast(pts, 256, ns, area, p, up, NULL, NULL);
    double blocked = tb_ff_raycast(pts, 256, ns, area, p, up, tb_ff_occluders_visible, occ);
    /* 16 x 16 strata, split at x = 0: exactly the 128 samples with x < 0 are hidden. */
    int hidden = 0;
    for (int k = 0; k < 256; k++)
        hidden += !tb_ff_occluders_visible(occ, p, pts[k]);
    assert_int_equal(hidden, 128);
    tb_assert_near(blocked / open, 0.5, 0.02);
    tb_assert_near(blocked, exact, 0.01 * exact);
    /* The shooter itself does not block rays that end on it, nor does the
     * receiver's own plane. */
    assert_true(tb_ff_occluders_visible(occ, p, (tb_vec3){0.5f, 0.5f, 2.0f}));
    tb_ff_occluders_free(occ);
    /* Segments between points on two tilted plates (boxes that hold the
     * segment's ends) are not blocked by the plates themselves. */
    tb_ff_polygon tilted[2] = {
        facing(ff_quad((tb_vec3){-1, -1, -0.5f}, (tb_vec3){1, -1, 0.5f}, (tb_vec3){1, 1, 0.5f}, (tb_vec3){-1, 1, -0.5f}),
               (tb_vec3){0, 0, 1}),
        facing(ff_quad((tb_vec3){-1, -1, 3.5f}, (tb_vec3){1, -1, 2.5f}, (tb_vec3){1, 1, 2.5f}, (tb_vec3){-1, 1, 3.5f}),
               (tb_vec3){0, 0, -1}),
    };
    assert_int_equal(tb_ff_occluders_build(tilted, 2, &occ), TB_OK);
    tb_vec3 a0[64], b0[64];
    assert_int_equal(tb_ff_sample_polygon(&tilted[0], 64, 1, a0), TB_OK);
    assert_int_equal(tb_ff_sample_polygon(&tilted[1], 64, 2, b0), TB_OK);
    for (int k = 0; k < 64; k++)
        assert_true(tb_ff_occluders_visible(occ, a0[k], b0[63 - k]));
    /* ... but a segment through a plate is. */
    assert_false(tb_ff_occluders_visible(occ, (tb_vec3){0, 0, -2}, b0[5]));
    tb_ff_occluders_free(occ);

    tb_hemicube *hc = tb_hemicube_create(256);
    double ff[2];
    assert_int_equal(tb_hemicube_formfactors(hc, p, up, scene, 2, TB_FF_NONE, ff), TB_OK);
    tb_assert_near(ff[0], exact, 1e-3 * exact);
    /* The blocker faces the receiver: it is seen whole. */
    tb_assert_near(ff[1], tb_ff_point_polygon(p, up, &scene[1]), 1e-3 * ff[1]);
    /* Skipping the blocker gives the whole shooter back. */
    assert_int_equal(tb_hemicube_formfactors(hc, p, up, scene, 2, 1, ff), TB_OK);
    tb_assert_near(ff[0], 2.0 * exact, 2e-3 * exact);
    assert_true(ff[1] == 0.0);
    tb_hemicube_free(hc);
}

/* ------------------------------------------------------------ exact x visible fraction */

/* The receiver surface of a rectangle case as a polygon facing its normal
 * (an occluder the rays start on). */
static tb_ff_polygon case_receiver_poly(const ff_case *c)
{
    tb_vec3 a = c->o, b = tb_vec3_add(c->o, c->ex), d = tb_vec3_add(c->o, c->ey);
    return facing(ff_quad(a, b, tb_vec3_add(b, c->ey), d), c->normal);
}

/* Issue 7: 16 samples within 0.5% of Howell's C-11, C-14 and C-41, with
 * visibility tested through occluders that hold both surfaces (rays start
 * and end on them and must not be blocked by them). Against ray casting at
 * the same samples, which is biased low by eq. 5's disk term. */
static void test_exact_howell(void **state)
{
    (void)state;
    static ff_case c;
    static tb_ff_polygon polys[257];
    for (int which = 0; which < 3; which++) {
        if (which == 0)
            ff_case_c11(&c, 1.0);
        else if (which == 1)
            ff_case_c14(&c, 1.0);
        else
            ff_case_c41(&c, 1.0, 64);
        int np = c.nshooter;
        memcpy(polys, c.shooter, sizeof polys[0] * (size_t)np);
        if (!c.disk)
            polys[np++] = case_receiver_poly(&c);
        tb_ff_occluders *occ = NULL;
        assert_int_equal(tb_ff_occluders_build(polys, (size_t)np, &occ), TB_OK);
        double f = ff_case_raycast_exact(&c, 24, 16, 1, occ);
        double w = ff_case_raycast(&c, 24, 16, 1, occ);
        print_message("[ info     ] %s, 16 samples: exact x fraction %+.2e, Wallace %+.2e (relative)\n", c.name,
                      (f - c.exact) / c.exact, (w - c.exact) / c.exact);
        tb_assert_near(f, c.exact, 5e-3 * c.exact);
        assert_true(fabs(f - c.exact) < fabs(w - c.exact));
        /* with one sample per polygon too: nothing is hidden */
        tb_assert_near(ff_case_raycast_exact(&c, 24, 1, 2, occ), f, 1e-12);
        tb_ff_occluders_free(occ);
    }
}

/* A wall in the plane x = 0 hides exactly the x < 0 half of the shooter from
 * every receiver at x > 0: the answer is the exact form factor of the
 * visible half. The fraction is Wallace's (weighted by the disk terms), so
 * it carries their sampling error; it is far smaller than the disk term's
 * bias of tb_ff_raycast. */
static void test_exact_half_hidden(void **state)
{
    (void)state;
    tb_vec3 up = {0, 0, 1};
    tb_ff_polygon scene[2];
    scene[0] = rect_z(-1, 1, -1, 1, 2, (tb_vec3){0, 0, -1}); /* shooter */
    scene[1] = facing(ff_quad((tb_vec3){0, -10, -0.5f}, (tb_vec3){0, 10, -0.5f}, (tb_vec3){0, 10, 1.999f},
                              (tb_vec3){0, -10, 1.999f}),
                      (tb_vec3){1, 0, 0}); /* wall */
    tb_ff_polygon half = rect_z(0, 1, -1, 1, 2, (tb_vec3){0, 0, -1});
    tb_ff_occluders *occ = NULL;
    assert_int_equal(tb_ff_occluders_build(scene, 2, &occ), TB_OK);
    enum { M = 12 };
    const int ns[3] = {4, 16, 64};
    double err[3];
    for (int s = 0; s < 3; s++) {
        tb_vec3 pts[64], ns3;
        double area, sum_e = 0.0, sum_x = 0.0, sum_w = 0.0;
        tb_ff_polygon_frame(&scene[0], &ns3, &area);
        for (int i = 0; i < M * M; i++) {
            tb_vec3 p = {(float)(0.05 + 1.5 * (i % M + 0.5) / M), (float)(-0.75 + 1.5 * (i / M + 0.5) / M), 0};
            assert_int_equal(tb_ff_sample_polygon(&scene[0], ns[s], (uint64_t)i, pts), TB_OK);
            sum_e += tb_ff_raycast_exact(&scene[0], pts, ns[s], p, up, tb_ff_occluders_visible, occ);
            sum_w += tb_ff_raycast(pts, ns[s], ns3, area, p, up, tb_ff_occluders_visible, occ);
            sum_x += tb_ff_point_polygon(p, up, &half);
        }
        err[s] = (sum_e - sum_x) / sum_x;
        print_message("[ info     ] half hidden, %d samples: exact x fraction %+.2e, Wallace %+.2e (relative)\n",
                      ns[s], err[s], (sum_w - sum_x) / sum_x);
        assert_true(fabs(err[s]) < fabs(sum_w - sum_x) / sum_x);
    }
    assert_true(fabs(err[1]) < 0.02);
    assert_true(fabs(err[2]) < 0.005);
    /* A wall that hides everything (the shooter wholly at x < 0). */
    tb_ff_polygon left = rect_z(-1, -0.1, -1, 1, 1.5, (tb_vec3){0, 0, -1});
    tb_vec3 pts[16];
    assert_int_equal(tb_ff_sample_polygon(&left, 16, 3, pts), TB_OK);
    tb_vec3 p = {0.5f, 0, 0};
    assert_true(tb_ff_point_polygon(p, up, &left) > 0.0);
    assert_true(tb_ff_raycast_exact(&left, pts, 16, p, up, tb_ff_occluders_visible, occ) == 0.0);
    tb_ff_occluders_free(occ);
}

/* Visibility callbacks that count their calls. */
static int vis_calls;
static bool vis_count_yes(void *ctx, tb_vec3 a, tb_vec3 b)
{
    (void)ctx, (void)a, (void)b;
    vis_calls++;
    return true;
}
static bool vis_count_no(void *ctx, tb_vec3 a, tb_vec3 b)
{
    (void)ctx, (void)a, (void)b;
    vis_calls++;
    return false;
}

/* Receivers on the shooter's plane or edge (0, no rays), a tangent plane
 * that leaves no sample in front (one ray decides), tiny and huge scales,
 * determinism for any thread count. */
static void test_exact_hard_cases(void **state)
{
    (void)state;
    tb_vec3 up = {0, 0, 1};
    tb_ff_polygon sh = rect_z(0, 1, 0, 1, 0, up);
    tb_vec3 pts[16];
    assert_int_equal(tb_ff_sample_polygon(&sh, 16, 1, pts), TB_OK);
    const tb_vec3 on[3] = {{0.5f, 0, 0}, {1, 1, 0}, {2, 0.5f, 0}};
    const tb_vec3 nrm[2] = {{0, 0, 1}, {0, 0.6f, 0.8f}};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 2; j++) {
            vis_calls = 0;
            assert_true(tb_ff_raycast_exact(&sh, pts, 16, on[i], nrm[j], vis_count_yes, NULL) == 0.0);
            assert_int_equal(vis_calls, 0);
        }
    /* A receiver below the shooter's plane sees its back. */
    vis_calls = 0;
    assert_true(tb_ff_raycast_exact(&sh, pts, 16, (tb_vec3){0.5f, 0.5f, -1}, up, vis_count_yes, NULL) == 0.0);
    assert_int_equal(vis_calls, 0);
    /* Receiver above the shooter's x = 1 edge, normal tilted so its tangent
     * plane leaves only x > 0.99 of the shooter in front: no sample there. */
    tb_ff_polygon facing_up = rect_z(0, 1, 0, 1, 0, up);
    tb_vec3 p = {1.0f, 0.5f, 0.01f};
    tb_vec3 n = {(float)(1.0 / sqrt(2.0)), 0, (float)(-1.0 / sqrt(2.0))}; /* plane x - 1 = z - 0.01 */
    double exact = tb_ff_point_polygon(p, n, &facing_up);
    assert_true(exact > 0.0);
    tb_vec3 ns;
    double area;
    tb_ff_polygon_frame(&facing_up, &ns, &area);
    assert_true(tb_ff_raycast_visible_fraction(pts, 16, ns, area, p, n, NULL, NULL) == -1.0);
    vis_calls = 0;
    tb_assert_near(tb_ff_raycast_exact(&facing_up, pts, 16, p, n, vis_count_yes, NULL), exact, 1e-15);
    assert_int_equal(vis_calls, 1);
    vis_calls = 0;
    assert_true(tb_ff_raycast_exact(&facing_up, pts, 16, p, n, vis_count_no, NULL) == 0.0);
    assert_int_equal(vis_calls, 1);
    /* Tiny and huge scales: the same relative answer. */
    static ff_case c, small, big;
    ff_case_c14(&c, 1.0);
    ff_case_c14(&small, 1e-3);
    ff_case_c14(&big, 1e4);
    tb_ff_polygon ps[2] = {small.shooter[0], case_receiver_poly(&small)};
    tb_ff_polygon pb[2] = {big.shooter[0], case_receiver_poly(&big)};
    tb_ff_occluders *os = NULL, *ob = NULL;
    assert_int_equal(tb_ff_occluders_build(ps, 2, &os), TB_OK);
    assert_int_equal(tb_ff_occluders_build(pb, 2, &ob), TB_OK);
    double f1 = ff_case_raycast_exact(&c, 8, 16, 5, NULL);
    tb_assert_near(ff_case_raycast_exact(&small, 8, 16, 5, os), f1, 1e-5 * f1);
    tb_assert_near(ff_case_raycast_exact(&big, 8, 16, 5, ob), f1, 1e-5 * f1);
    tb_ff_occluders_free(os);
    tb_ff_occluders_free(ob);
    /* Determinism: the batch equals the single calls bit for bit, for 1 and 2 threads. */
    tb_ff_polygon scene[2] = {rect_z(-1, 1, -1, 1, 2, (tb_vec3){0, 0, -1}), rect_z(-2, 0, -0.3, 2, 1, (tb_vec3){0, 0, -1})};
    tb_ff_occluders *occ = NULL;
    assert_int_equal(tb_ff_occluders_build(scene, 2, &occ), TB_OK);
    enum { R = 300 };
    static tb_vec3 rp[R], rn[R];
    static double ff1[R], ff2[R];
    for (int i = 0; i < R; i++) {
        rp[i] = (tb_vec3){(float)(-1.5 + 3.0 * (i % 20) / 19.0), (float)(-1.5 + 3.0 * (i / 20) / 14.0), 0};
        rn[i] = up;
    }
    assert_int_equal(tb_ff_sample_polygon(&scene[0], 16, 7, pts), TB_OK);
    int nt = omp_get_max_threads();
    omp_set_num_threads(1);
    assert_int_equal(tb_ff_raycast_exact_batch(occ, &scene[0], pts, 16, rp, rn, R, ff1), TB_OK);
    omp_set_num_threads(2);
    assert_int_equal(tb_ff_raycast_exact_batch(occ, &scene[0], pts, 16, rp, rn, R, ff2), TB_OK);
    omp_set_num_threads(nt);
    int partial = 0;
    for (int i = 0; i < R; i++) {
        assert_memory_equal(&ff1[i], &ff2[i], sizeof ff1[i]);
        double one = tb_ff_raycast_exact(&scene[0], pts, 16, rp[i], rn[i], tb_ff_occluders_visible, occ);
        assert_memory_equal(&ff1[i], &one, sizeof one);
        double full = tb_ff_point_polygon(rp[i], rn[i], &scene[0]);
        partial += ff1[i] > 0.0 && ff1[i] < full;
    }
    assert_true(partial > 10); /* the blocker does hide part of the shooter from some receivers */
    tb_ff_occluders_free(occ);
    /* Errors: NULL arguments. */
    assert_int_equal(tb_ff_raycast_exact_batch(NULL, NULL, pts, 16, rp, rn, 1, ff1), TB_ERR_ARG);
    assert_int_equal(tb_ff_raycast_exact_batch(NULL, &scene[0], pts, -1, rp, rn, 1, ff1), TB_ERR_ARG);
}

/* ------------------------------------------------------------ sampling */

/* True if q is in one of the triangles (v0, vk, vk+1) (the test polygons'
 * fans from v0 cover them, the non-convex quad's included). */
static bool inside(const tb_ff_polygon *p, tb_vec3 q, double tol)
{
    tb_vec3 n;
    double a;
    tb_ff_polygon_frame(p, &n, &a);
    for (int k = 1; k + 1 < p->n; k++) {
        tb_vec3 t[3] = {p->v[0], p->v[k], p->v[k + 1]};
        bool in = true;
        for (int e = 0; e < 3; e++) {
            tb_vec3 ed = tb_vec3_sub(t[(e + 1) % 3], t[e]);
            if (tb_vec3_dot(tb_vec3_cross(ed, tb_vec3_sub(q, t[e])), n) < -tol)
                in = false;
        }
        if (in)
            return true;
    }
    return false;
}

/* Exact integral of x^2, y^2, x y over a polygon (triangle fan, edge
 * midpoints: exact for quadratics), divided by the area. */
static void quad_moments(const tb_ff_polygon *p, double m[3])
{
    double total = 0.0;
    m[0] = m[1] = m[2] = 0.0;
    for (int k = 1; k + 1 < p->n; k++) {
        tb_vec3 a = p->v[0], b = p->v[k], c = p->v[k + 1];
        double ar = 0.5 * tb_vec3_length(tb_vec3_cross(tb_vec3_sub(b, a), tb_vec3_sub(c, a)));
        tb_vec3 mid[3] = {tb_vec3_scale(tb_vec3_add(a, b), 0.5f), tb_vec3_scale(tb_vec3_add(b, c), 0.5f),
                          tb_vec3_scale(tb_vec3_add(c, a), 0.5f)};
        for (int i = 0; i < 3; i++) {
            m[0] += ar / 3 * mid[i].x * mid[i].x;
            m[1] += ar / 3 * mid[i].y * mid[i].y;
            m[2] += ar / 3 * mid[i].x * mid[i].y;
        }
        total += ar;
    }
    for (int i = 0; i < 3; i++)
        m[i] /= total;
}

static void test_sample(void **state)
{
    (void)state;
    tb_ff_polygon sq = rect_z(0, 1, 0, 1, 0, (tb_vec3){0, 0, 1});
    tb_vec3 a[64], b[64];
    /* Determinism. */
    assert_int_equal(tb_ff_sample_polygon(&sq, 16, 42, a), TB_OK);
    assert_int_equal(tb_ff_sample_polygon(&sq, 16, 42, b), TB_OK);
    assert_memory_equal(a, b, sizeof(tb_vec3) * 16);
    assert_int_equal(tb_ff_sample_polygon(&sq, 16, 43, b), TB_OK);
    assert_memory_not_equal(a, b, sizeof(tb_vec3) * 16);
    /* Stratified: one sample in each cell of the 4 x 4 grid. */
    int cell[16] = {0};
    for (int k = 0; k < 16; k++) {
        int i = (int)(a[k].x * 4), j = (int)(a[k].y * 4);
        assert_true(i >= 0 && i < 4 && j >= 0 && j < 4);
        cell[j * 4 + i]++;
    }
    for (int c = 0; c < 16; c++)
        assert_int_equal(cell[c], 1);

    /* Equal-area strata, uniform inside each: the sample mean of x^2, y^2, x y
     * over many seeds matches the exact mean, for a triangle, a trapezoid
     * (the linear-Jacobian quad map) and a non-convex quad (two triangles),
     * with sample counts that do not fill a square grid. */
    tb_ff_polygon polys[3] = {
        ff_tri((tb_vec3){0, 0, 0}, (tb_vec3){3, 0.5f, 0}, (tb_vec3){0.5f, 2, 0}),
        ff_quad((tb_vec3){0, 0, 0}, (tb_vec3){4, 0, 0}, (tb_vec3){3, 1, 0}, (tb_vec3){0.5f, 1.5f, 0}),
        ff_quad((tb_vec3){0, 0, 0}, (tb_vec3){3, 0, 0}, (tb_vec3){0.5f, 0.5f, 0}, (tb_vec3){0, 2, 0}), /* halves 0.75, 0.5 */
    };
    const int counts[] = {1, 7, 13, 30};
    for (int p = 0; p < 3; p++)
        for (int c = 0; c < 4; c++) {
            /* Per-seed estimates; the test allows 5 standard errors of their mean. */
            double exact[3], mean[3] = {0, 0, 0}, sq[3] = {0, 0, 0};
            quad_moments(&polys[p], exact);
            const int seeds = 3000;
            for (int s = 0; s < seeds; s++) {
                assert_int_equal(tb_ff_sample_polygon(&polys[p], counts[c], (uint64_t)s, a), TB_OK);
                double est[3] = {0, 0, 0};
                for (int k = 0; k < counts[c]; k++) {
                    assert_true(inside(&polys[p], a[k], 1e-5));
                    est[0] += (double)a[k].x * a[k].x / counts[c];
                    est[1] += (double)a[k].y * a[k].y / counts[c];
                    est[2] += (double)a[k].x * a[k].y / counts[c];
                }
                for (int i = 0; i < 3; i++) {
                    mean[i] += est[i] / seeds;
                    sq[i] += est[i] * est[i] / seeds;
                }
            }
            for (int i = 0; i < 3; i++) {
                double se = sqrt(fmax(sq[i] - mean[i] * mean[i], 0.0) / seeds);
                if (i == 0)
                    print_message("[ info     ] polygon %d, %d samples: mean x^2 %.5f, exact %.5f, standard error %.1e\n",
                                  p, counts[c], mean[0], exact[0], se);
                tb_assert_near(mean[i], exact[i], 5.0 * se + 1e-6);
            }
        }

    /* Centres: inside, no randomness, one per cell of the 4 x 4 grid at its middle. */
    assert_int_equal(tb_ff_sample_polygon_centres(&sq, 16, a), TB_OK);
    for (int k = 0; k < 16; k++) {
        double fx = a[k].x * 4 - floor(a[k].x * 4), fy = a[k].y * 4 - floor(a[k].y * 4);
        tb_assert_near(fx, 0.5, 1e-6);
        tb_assert_near(fy, 0.5, 1e-6);
    }
    for (int p = 0; p < 3; p++) {
        assert_int_equal(tb_ff_sample_polygon_centres(&polys[p], 30, a), TB_OK);
        for (int k = 0; k < 30; k++)
            assert_true(inside(&polys[p], a[k], 1e-5));
    }
    /* Errors. */
    tb_ff_polygon line = ff_tri((tb_vec3){0, 0, 0}, (tb_vec3){1, 1, 1}, (tb_vec3){2, 2, 2});
    assert_int_equal(tb_ff_sample_polygon(&line, 4, 1, a), TB_ERR_ARG);
    assert_int_equal(tb_ff_sample_polygon(&sq, 0, 1, a), TB_ERR_ARG);
    assert_int_equal(tb_ff_sample_polygon_centres(&line, 4, a), TB_ERR_ARG);
    assert_int_equal(tb_ff_sample_polygon_centres(&sq, 0, a), TB_ERR_ARG);
    tb_ff_polygon nan_poly = sq;
    nan_poly.v[1].y = NAN;
    assert_int_equal(tb_ff_sample_polygon(&nan_poly, 4, 1, a), TB_ERR_ARG);
}

/* ------------------------------------------------------------ batch */

static void test_batch(void **state)
{
    (void)state;
    tb_ff_polygon el[24];
    int n = cube_elements(el);
    tb_ff_occluders *occ = NULL;
    assert_int_equal(tb_ff_occluders_build(el, (size_t)n, &occ), TB_OK);
    enum { R = 2000 };
    static tb_vec3 p[R], nr[R];
    static double f1[R], f2[R];
    tb_rng rng;
    tb_rng_seed(&rng, 5, 0);
    for (int i = 0; i < R; i++) {
        p[i] = (tb_vec3){tb_rng_float(&rng), tb_rng_float(&rng), 0.0f}; /* on the floor */
        nr[i] = (tb_vec3){0, 0, 1};
    }
    tb_vec3 pts[16], ns;
    double area;
    const tb_ff_polygon *shooter = &el[8]; /* a wall quad */
    tb_ff_polygon_frame(shooter, &ns, &area);
    assert_int_equal(tb_ff_sample_polygon(shooter, 16, 1, pts), TB_OK);
    omp_set_num_threads(1);
    assert_int_equal(tb_ff_raycast_batch(occ, pts, 16, ns, area, p, nr, R, f1), TB_OK);
    omp_set_num_threads(4);
    assert_int_equal(tb_ff_raycast_batch(occ, pts, 16, ns, area, p, nr, R, f2), TB_OK);
    assert_memory_equal(f1, f2, sizeof f1);
    for (int i = 0; i < R; i += 97)
        assert_true(f1[i] == tb_ff_raycast(pts, 16, ns, area, p[i], nr[i], tb_ff_occluders_visible, occ));
    /* NULL context: no occlusion; errors. */
    assert_int_equal(tb_ff_raycast_batch(NULL, pts, 16, ns, area, p, nr, 10, f2), TB_OK);
    assert_int_equal(tb_ff_raycast_batch(occ, NULL, 16, ns, area, p, nr, 10, f2), TB_ERR_ARG);
    assert_int_equal(tb_ff_raycast_batch(occ, pts, 16, ns, area, p, nr, 0, NULL), TB_OK);
    tb_ff_occluders_free(occ);
}

/* Occluder and hemicube argument errors; degenerate input gives no NaN. */
static void test_errors(void **state)
{
    (void)state;
    tb_ff_occluders *occ = NULL;
    assert_int_equal(tb_ff_occluders_build(NULL, 0, &occ), TB_OK); /* empty: nothing occludes */
    assert_true(tb_ff_occluders_visible(occ, (tb_vec3){0, 0, 0}, (tb_vec3){1, 1, 1}));
    tb_ff_occluders_free(occ);
    tb_ff_polygon bad = rect_z(0, 1, 0, 1, 1, (tb_vec3){0, 0, -1});
    bad.v[0].x = INFINITY;
    assert_int_equal(tb_ff_occluders_build(&bad, 1, &occ), TB_ERR_ARG);
    assert_null(occ);
    bad.v[0].x = 0;
    bad.n = 2;
    assert_int_equal(tb_ff_occluders_build(&bad, 1, &occ), TB_ERR_ARG);
    /* A degenerate polygon among good ones: builds, blocks nothing. */
    tb_ff_polygon two[2] = {rect_z(0, 1, 0, 1, 1, (tb_vec3){0, 0, -1}),
                            ff_tri((tb_vec3){0, 0, 2}, (tb_vec3){1, 1, 2}, (tb_vec3){2, 2, 2})};
    assert_int_equal(tb_ff_occluders_build(two, 2, &occ), TB_OK);
    assert_false(tb_ff_occluders_visible(occ, (tb_vec3){0.5f, 0.5f, 0}, (tb_vec3){0.5f, 0.5f, 3}));
    assert_true(tb_ff_occluders_visible(occ, (tb_vec3){1.5f, 1.5f, 0}, (tb_vec3){1.5f, 1.5f, 3}));
    tb_ff_occluders_free(occ);

    assert_null(tb_hemicube_create(0));
    assert_null(tb_hemicube_create(7));
    assert_null(tb_hemicube_create(1 << 20));
    tb_hemicube *hc = tb_hemicube_create(32);
    double ff[2] = {-1, -1};
    assert_int_equal(tb_hemicube_formfactors(hc, (tb_vec3){0, 0, 0}, (tb_vec3){0, 0, 1}, two, 2, TB_FF_NONE, ff),
                     TB_OK);
    assert_true(ff[0] > 0.0 && ff[1] == 0.0);
    assert_int_equal(tb_hemicube_formfactors(hc, (tb_vec3){0, 0, 0}, (tb_vec3){0, 0, 0}, two, 2, TB_FF_NONE, ff),
                     TB_ERR_ARG);
    assert_int_equal(tb_hemicube_formfactors(hc, (tb_vec3){NAN, 0, 0}, (tb_vec3){0, 0, 1}, two, 2, TB_FF_NONE, ff),
                     TB_ERR_ARG);
    two[1].v[1].z = NAN;
    assert_int_equal(tb_hemicube_formfactors(hc, (tb_vec3){0, 0, 0}, (tb_vec3){0, 0, 1}, two, 2, TB_FF_NONE, ff),
                     TB_ERR_ARG);
    /* Receiver in the shooter's plane: every method gives 0. */
    tb_ff_polygon flat = rect_z(1, 2, 0, 1, 0, (tb_vec3){0, 0, 1});
    assert_int_equal(tb_hemicube_formfactors(hc, (tb_vec3){0, 0.5f, 0}, (tb_vec3){0, 0, 1}, &flat, 1, TB_FF_NONE, ff),
                     TB_OK);
    assert_true(ff[0] == 0.0);
    tb_vec3 pts[4];
    assert_int_equal(tb_ff_sample_polygon(&flat, 4, 1, pts), TB_OK);
    assert_true(tb_ff_raycast(pts, 4, (tb_vec3){0, 0, 1}, 1.0, (tb_vec3){0, 0.5f, 0}, (tb_vec3){0, 0, 1}, NULL,
                              NULL) == 0.0);
    assert_true(tb_ff_raycast(pts, 4, (tb_vec3){0, 0, 1}, 0.0, (tb_vec3){0, 0.5f, 3}, (tb_vec3){0, 0, -1}, NULL,
                              NULL) == 0.0);
    tb_hemicube_free(hc);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_frame),          cmocka_unit_test(test_point_b3),
        cmocka_unit_test(test_point_offcenter), cmocka_unit_test(test_point_zero_cases), cmocka_unit_test(test_point_noise), cmocka_unit_test(test_point_twisted),
        cmocka_unit_test(test_point_straddle), cmocka_unit_test(test_closed_cube), cmocka_unit_test(test_hemicube_watertight), cmocka_unit_test(test_hemicube_close), cmocka_unit_test(test_hemicube_twisted),
        cmocka_unit_test(test_howell_exact),   cmocka_unit_test(test_howell_raycast),
        cmocka_unit_test(test_howell_hemicube), cmocka_unit_test(test_reciprocity),
        cmocka_unit_test(test_blocker), cmocka_unit_test(test_exact_howell), cmocka_unit_test(test_exact_half_hidden), cmocka_unit_test(test_exact_hard_cases),        cmocka_unit_test(test_sample),
        cmocka_unit_test(test_batch),          cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
