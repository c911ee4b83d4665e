/* Howell's catalogue cases for the form-factor tests and the accuracy table
 * (ff_table.c): closed forms written from the catalogue (J. R. Howell, "A
 * Catalog of Radiation Heat Transfer Configuration Factors", cases B-3, C-11,
 * C-14, C-41), the geometry as tb_ff_polygon arrays, and area-to-area form
 * factors integrated over a grid of receiver points. */
#ifndef TB_TESTS_FORMFACTOR_FF_CASES_H
#define TB_TESTS_FORMFACTOR_FF_CASES_H

#include <math.h>
#include <stdlib.h>

#include "host/radiosity/formfactor.h"

#define FF_PI 3.14159265358979323846

/* B-3: differential element to a parallel a x b rectangle at distance c, the
 * element's normal through a corner of the rectangle. */
static inline double ff_howell_b3(double a, double b, double c)
{
    double x = a / c, y = b / c;
    double sx = sqrt(1.0 + x * x), sy = sqrt(1.0 + y * y);
    return (x / sx * atan(y / sx) + y / sy * atan(x / sy)) / (2.0 * FF_PI);
}

/* C-11: identical, parallel, directly opposed a x b rectangles at distance c. */
static inline double ff_howell_c11(double a, double b, double c)
{
    double x = a / c, y = b / c;
    double sx = sqrt(1.0 + x * x), sy = sqrt(1.0 + y * y);
    double t = 0.5 * log((1.0 + x * x) * (1.0 + y * y) / (1.0 + x * x + y * y)) + x * sy * atan(x / sy) +
               y * sx * atan(y / sx) - x * atan(x) - y * atan(y);
    return 2.0 / (FF_PI * x * y) * t;
}

/* C-14: rectangles at 90 degrees sharing an edge of length l; from the one of
 * width w to the one of height h. */
static inline double ff_howell_c14(double w, double h, double l)
{
    double W = w / l, H = h / l, W2 = W * W, H2 = H * H, s = sqrt(H2 + W2);
    double lg = log((1.0 + W2) * (1.0 + H2) / (1.0 + W2 + H2)) +
                W2 * log(W2 * (1.0 + W2 + H2) / ((1.0 + W2) * (W2 + H2))) +
                H2 * log(H2 * (1.0 + H2 + W2) / ((1.0 + H2) * (H2 + W2)));
    return (W * atan(1.0 / W) + H * atan(1.0 / H) - s * atan(1.0 / s) + 0.25 * lg) / (FF_PI * W);
}

/* C-41: disk of radius r1 to a parallel coaxial disk of radius r2 at distance a. */
static inline double ff_howell_c41(double r1, double r2, double a)
{
    double R1 = r1 / a, R2 = r2 / a, X = 1.0 + (1.0 + R2 * R2) / (R1 * R1);
    return 0.5 * (X - sqrt(X * X - 4.0 * (R2 / R1) * (R2 / R1)));
}

/* A quad from four corners. */
static inline tb_ff_polygon ff_quad(tb_vec3 a, tb_vec3 b, tb_vec3 c, tb_vec3 d)
{
    tb_ff_polygon p = {{a, b, c, d}, 4};
    return p;
}

/* A triangle. */
static inline tb_ff_polygon ff_tri(tb_vec3 a, tb_vec3 b, tb_vec3 c)
{
    tb_ff_polygon p = {{a, b, c, c}, 3};
    return p;
}

/* One Howell configuration: receiver surface 1 (grid of points), shooter
 * surface 2 (polygons), and the catalogue value F12. */
typedef struct ff_case {
    const char *name;
    double exact;        /* Howell's F12 */
    int nshooter;
    tb_ff_polygon shooter[256];
    /* receiver surface: a rectangle o + s ex + t ey (s, t in [0, 1]) or a disk */
    int disk;
    tb_vec3 o, ex, ey;   /* rectangle */
    double radius;       /* disk about o in the plane z = o.z */
    tb_vec3 normal;      /* receiver normal */
} ff_case;

/* C-11: unit squares at distance 1 (scaled by `scale`): receiver z = 0 facing
 * +z, shooter z = 1 facing -z. */
static inline void ff_case_c11(ff_case *c, double scale)
{
    float s = (float)scale;
    c->name = "C-11 parallel unit squares, distance 1";
    c->exact = ff_howell_c11(1.0, 1.0, 1.0);
    c->nshooter = 1;
    c->shooter[0] = ff_quad((tb_vec3){0, 0, s}, (tb_vec3){0, s, s}, (tb_vec3){s, s, s}, (tb_vec3){s, 0, s});
    c->disk = 0;
    c->o = (tb_vec3){0, 0, 0};
    c->ex = (tb_vec3){s, 0, 0};
    c->ey = (tb_vec3){0, s, 0};
    c->normal = (tb_vec3){0, 0, 1};
}

/* C-14: unit squares at 90 degrees sharing the edge x = 0, z = 0 along y:
 * receiver on z = 0 (x in [0, 1]) facing +z, shooter on x = 0 (z in [0, 1])
 * facing +x. */
static inline void ff_case_c14(ff_case *c, double scale)
{
    float s = (float)scale;
    c->name = "C-14 perpendicular unit squares, common edge";
    c->exact = ff_howell_c14(1.0, 1.0, 1.0);
    c->nshooter = 1;
    c->shooter[0] = ff_quad((tb_vec3){0, 0, 0}, (tb_vec3){0, s, 0}, (tb_vec3){0, s, s}, (tb_vec3){0, 0, s});
    c->disk = 0;
    c->o = (tb_vec3){0, 0, 0};
    c->ex = (tb_vec3){s, 0, 0};
    c->ey = (tb_vec3){0, s, 0};
    c->normal = (tb_vec3){0, 0, 1};
}

/* C-41: coaxial unit disks at distance 1; the shooter disk is a fan of
 * `nseg` triangles (nseg <= 256) with the disk's area (radius scaled by
 * sqrt(2 pi / (nseg sin(2 pi / nseg)))), so only the shape differs, by far
 * less than the tested tolerances. */
static inline void ff_case_c41(ff_case *c, double scale, int nseg)
{
    double r = scale, h = scale;
    double k = sqrt(2.0 * FF_PI / (nseg * sin(2.0 * FF_PI / nseg)));
    c->name = "C-41 coaxial unit disks, distance 1";
    c->exact = ff_howell_c41(1.0, 1.0, 1.0);
    c->nshooter = nseg;
    for (int i = 0; i < nseg; i++) {
        double a0 = 2.0 * FF_PI * i / nseg, a1 = 2.0 * FF_PI * (i + 1) / nseg;
        tb_vec3 ctr = {0, 0, (float)h};
        tb_vec3 p0 = {(float)(k * r * cos(a0)), (float)(k * r * sin(a0)), (float)h};
        tb_vec3 p1 = {(float)(k * r * cos(a1)), (float)(k * r * sin(a1)), (float)h};
        c->shooter[i] = ff_tri(ctr, p1, p0); /* clockwise from above: faces -z */
    }
    c->disk = 1;
    c->o = (tb_vec3){0, 0, 0};
    c->radius = r;
    c->normal = (tb_vec3){0, 0, 1};
}

/* Receiver point number i of an m x m grid on the receiver surface (cell
 * midpoints; for the disk, m rings of equal area times m angles), all of
 * equal area. */
static inline tb_vec3 ff_case_receiver(const ff_case *c, int m, int i)
{
    int a = i % m, b = i / m;
    if (c->disk) {
        double rr = c->radius * sqrt((b + 0.5) / m), ang = 2.0 * FF_PI * (a + 0.5) / m;
        return (tb_vec3){(float)(c->o.x + rr * cos(ang)), (float)(c->o.y + rr * sin(ang)), c->o.z};
    }
    double s = (a + 0.5) / m, t = (b + 0.5) / m;
    return (tb_vec3){(float)(c->o.x + s * c->ex.x + t * c->ey.x), (float)(c->o.y + s * c->ex.y + t * c->ey.y),
                     (float)(c->o.z + s * c->ex.z + t * c->ey.z)};
}

/* Area-to-area F12 with the exact point form factor on an m x m receiver grid. */
static inline double ff_case_exact_grid(const ff_case *c, int m)
{
    double sum = 0.0;
    for (int i = 0; i < m * m; i++) {
        tb_vec3 p = ff_case_receiver(c, m, i);
        for (int k = 0; k < c->nshooter; k++)
            sum += tb_ff_point_polygon(p, c->normal, &c->shooter[k]);
    }
    return sum / ((double)m * m);
}

/* Area-to-area F12 by ray casting: each shooter polygon sampled with
 * `nsamples` points (jittered with seed + polygon index, or the strata's
 * centres if `centres`), an m x m receiver grid, through
 * tb_ff_raycast_batch (occluders `occ`, may be NULL). -1 on failure. */
static inline double ff_case_raycast_ex(const ff_case *c, int m, int nsamples, uint64_t seed, int centres, void *occ)
{
    size_t nr = (size_t)m * (size_t)m;
    tb_vec3 *p = malloc(sizeof *p * nr), *n = malloc(sizeof *n * nr), *pts = malloc(sizeof *pts * (size_t)nsamples);
    double *ff = malloc(sizeof *ff * nr);
    double sum = -1.0;
    if (p && n && pts && ff) {
        for (size_t i = 0; i < nr; i++) {
            p[i] = ff_case_receiver(c, m, (int)i);
            n[i] = c->normal;
        }
        sum = 0.0;
        for (int k = 0; k < c->nshooter && sum >= 0.0; k++) {
            tb_vec3 ns;
            double area;
            tb_ff_polygon_frame(&c->shooter[k], &ns, &area);
            tb_status st = centres ? tb_ff_sample_polygon_centres(&c->shooter[k], nsamples, pts)
                                   : tb_ff_sample_polygon(&c->shooter[k], nsamples, seed + (uint64_t)k, pts);
            if (st ||
                tb_ff_raycast_batch(occ, pts, nsamples, ns, area, p, n, nr, ff)) {
                sum = -1.0;
                break;
            }
            for (size_t i = 0; i < nr; i++)
                sum += ff[i];
        }
        if (sum >= 0.0)
            sum /= (double)nr;
    }
    free(p);
    free(n);
    free(pts);
    free(ff);
    return sum;
}

/* Area-to-area F12 by tb_ff_raycast_exact (exact unoccluded part times the
 * samples' visible fraction): each shooter polygon sampled with `nsamples`
 * jittered points (seed + polygon index), an m x m receiver grid, through
 * tb_ff_raycast_exact_batch (occluders `occ`, may be NULL). -1 on failure. */
static inline double ff_case_raycast_exact(const ff_case *c, int m, int nsamples, uint64_t seed, void *occ)
{
    size_t nr = (size_t)m * (size_t)m;
    tb_vec3 *p = malloc(sizeof *p * nr), *n = malloc(sizeof *n * nr), *pts = malloc(sizeof *pts * (size_t)nsamples);
    double *ff = malloc(sizeof *ff * nr);
    double sum = -1.0;
    if (p && n && pts && ff) {
        for (size_t i = 0; i < nr; i++) {
            p[i] = ff_case_receiver(c, m, (int)i);
            n[i] = c->normal;
        }
        sum = 0.0;
        for (int k = 0; k < c->nshooter; k++) {
            if (tb_ff_sample_polygon(&c->shooter[k], nsamples, seed + (uint64_t)k, pts) ||
                tb_ff_raycast_exact_batch(occ, &c->shooter[k], pts, nsamples, p, n, nr, ff)) {
                sum = -1.0;
                break;
            }
            for (size_t i = 0; i < nr; i++)
                sum += ff[i];
        }
        if (sum >= 0.0)
            sum /= (double)nr;
    }
    free(p);
    free(n);
    free(pts);
    free(ff);
    return sum;
}

/* Jittered ray casting (ff_case_raycast_ex). */
static inline double ff_case_raycast(const ff_case *c, int m, int nsamples, uint64_t seed, void *occ)
{
    return ff_case_raycast_ex(c, m, nsamples, seed, 0, occ);
}

/* Area-to-area F12 by hemicubes of resolution res at an m x m receiver grid.
 * -1 on failure. */
static inline double ff_case_hemicube(const ff_case *c, int m, int res)
{
    tb_hemicube *hc = tb_hemicube_create(res);
    double *ff = malloc(sizeof *ff * (size_t)c->nshooter);
    double sum = -1.0;
    if (hc && ff) {
        sum = 0.0;
        for (int i = 0; i < m * m; i++) {
            tb_vec3 p = ff_case_receiver(c, m, i);
            if (tb_hemicube_formfactors(hc, p, c->normal, c->shooter, (size_t)c->nshooter, TB_FF_NONE, ff)) {
                sum = -1.0;
                break;
            }
            for (int k = 0; k < c->nshooter; k++)
                sum += ff[k];
        }
        if (sum >= 0.0)
            sum /= (double)m * m;
    }
    tb_hemicube_free(hc);
    free(ff);
    return sum;
}

#endif
