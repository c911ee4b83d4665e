/* Prints the form-factor accuracy and cost tables of docs/accuracy.md
 * ("Radiosity form factors") and docs/performance.md ("Form factors").
 *
 *     build/<dir>/tests/formfactor/ff_table accuracy
 *     build/<dir>/tests/formfactor/ff_table timing
 *
 * accuracy: relative error against Howell's closed forms (C-11, C-14, C-41)
 * of the area-to-area form factor integrated over a grid of receiver points
 * with the exact point form factor, ray casting (1, 4, 16, 64 samples per
 * shooter polygon; mean and worst over 16 seeds), the exact form factor
 * times the samples' visible fraction (tb_ff_raycast_exact; also with half
 * the shooter hidden by a wall) and hemicubes (32 .. 512).
 * timing: CPU nanoseconds per receiver per sample of tb_ff_raycast (with and
 * without occluders), per receiver of tb_ff_raycast and tb_ff_raycast_exact,
 * and CPU milliseconds per hemicube, one thread. */
#include <stdbool.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "ff_cases.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts); /* CPU time: the shared machine's load matters less */
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void build_cases(ff_case *c)
{
    ff_case_c11(&c[0], 1.0);
    ff_case_c14(&c[1], 1.0);
    ff_case_c41(&c[2], 1.0, 64);
}

static int accuracy(void)
{
    static ff_case cases[3];
    build_cases(cases);
    const int grid_exact = 64, grid_rc = 32, grid_hc = 16, nseeds = 16;
    const int samples[] = {1, 4, 16, 64};
    const int res[] = {32, 64, 128, 256, 512};

    printf("Exact point form factor integrated over a %d x %d receiver grid (midpoints):\n\n", grid_exact,
           grid_exact);
    printf("| case | Howell F12 | integrated | relative error |\n|---|---|---|---|\n");
    for (int c = 0; c < 3; c++) {
        double f = ff_case_exact_grid(&cases[c], grid_exact);
        printf("| %s | %.6f | %.6f | %+.2e |\n", cases[c].name, cases[c].exact, f,
               (f - cases[c].exact) / cases[c].exact);
    }

    printf("\nRay casting, %d x %d receivers, samples per shooter polygon (C-41: per triangle of the "
           "64-triangle fan); relative error mean over %d seeds (signed) / largest |error|:\n\n",
           grid_rc, grid_rc, nseeds);
    printf("| case |");
    for (int s = 0; s < 4; s++)
        printf(" %d sample%s |", samples[s], samples[s] > 1 ? "s" : "");
    printf("\n|---|---|---|---|---|\n");
    for (int c = 0; c < 3; c++) {
        printf("| %s |", cases[c].name);
        for (int s = 0; s < 4; s++) {
            double mean = 0.0, worst = 0.0;
            for (int seed = 1; seed <= nseeds; seed++) {
                double f = ff_case_raycast(&cases[c], grid_rc, samples[s], (uint64_t)seed * 1000, NULL);
                if (f < 0.0) {
                    fprintf(stderr, "ff_table: %s\n", tb_last_error());
                    return 1;
                }
                double e = (f - cases[c].exact) / cases[c].exact;
                mean += e / nseeds;
                worst = fmax(worst, fabs(e));
            }
            printf(" %+.2e / %.2e |", mean, worst);
        }
        printf("\n");
    }
    printf("\nThe same with the strata's centres (tb_ff_sample_polygon_centres; one fixed pattern):\n\n");
    printf("| case |");
    for (int s = 0; s < 4; s++)
        printf(" %d sample%s |", samples[s], samples[s] > 1 ? "s" : "");
    printf("\n|---|---|---|---|---|\n");
    for (int c = 0; c < 3; c++) {
        printf("| %s |", cases[c].name);
        for (int s = 0; s < 4; s++) {
            double f = ff_case_raycast_ex(&cases[c], grid_rc, samples[s], 0, 1, NULL);
            if (f < 0.0) {
                fprintf(stderr, "ff_table: %s\n", tb_last_error());
                return 1;
            }
            printf(" %+.2e |", (f - cases[c].exact) / cases[c].exact);
        }
        printf("\n");
    }

    /* tb_ff_raycast_exact: visibility through occluders holding both
     * surfaces (rays start and end on them), so the rays are really cast. */
    printf("\nExact x visible fraction (tb_ff_raycast_exact), %d x %d receivers, occluders = both surfaces; "
           "relative error mean over %d seeds (signed) / largest |error|:\n\n",
           grid_rc, grid_rc, nseeds);
    printf("| case |");
    for (int s = 0; s < 4; s++)
        printf(" %d sample%s |", samples[s], samples[s] > 1 ? "s" : "");
    printf("\n|---|---|---|---|---|\n");
    for (int c = 0; c < 3; c++) {
        static tb_ff_polygon polys[257];
        int np = cases[c].nshooter;
        memcpy(polys, cases[c].shooter, sizeof polys[0] * (size_t)np);
        if (!cases[c].disk) {
            tb_vec3 a = cases[c].o, b = tb_vec3_add(a, cases[c].ex), d = tb_vec3_add(a, cases[c].ey);
            polys[np++] = ff_quad(a, b, tb_vec3_add(b, cases[c].ey), d); /* counter-clockwise about +z */
        }
        tb_ff_occluders *occ = NULL;
        if (tb_ff_occluders_build(polys, (size_t)np, &occ)) {
            fprintf(stderr, "ff_table: %s\n", tb_last_error());
            return 1;
        }
        printf("| %s |", cases[c].name);
        for (int s = 0; s < 4; s++) {
            double mean = 0.0, worst = 0.0;
            for (int seed = 1; seed <= nseeds; seed++) {
                double f = ff_case_raycast_exact(&cases[c], grid_rc, samples[s], (uint64_t)seed * 1000, occ);
                if (f < 0.0) {
                    fprintf(stderr, "ff_table: %s\n", tb_last_error());
                    return 1;
                }
                double e = (f - cases[c].exact) / cases[c].exact;
                mean += e / nseeds;
                worst = fmax(worst, fabs(e));
            }
            printf(" %+.2e / %.2e |", mean, worst);
        }
        printf("\n");
        tb_ff_occluders_free(occ);
    }
    /* Partial occlusion: a wall in the plane x = 0 hides exactly the x < 0
     * half of a 2 x 2 shooter at height 2 from receivers on [0.05, 1.55] x
     * [-0.75, 0.75]; the answer is the exact form factor of the other half. */
    {
        tb_ff_polygon scene[2] = {
            ff_quad((tb_vec3){-1, -1, 2}, (tb_vec3){-1, 1, 2}, (tb_vec3){1, 1, 2}, (tb_vec3){1, -1, 2}),
            ff_quad((tb_vec3){0, -10, -0.5f}, (tb_vec3){0, 10, -0.5f}, (tb_vec3){0, 10, 1.999f},
                    (tb_vec3){0, -10, 1.999f})};
        tb_ff_polygon half = ff_quad((tb_vec3){0, -1, 2}, (tb_vec3){0, 1, 2}, (tb_vec3){1, 1, 2}, (tb_vec3){1, -1, 2});
        tb_ff_occluders *occ = NULL;
        if (tb_ff_occluders_build(scene, 2, &occ)) {
            fprintf(stderr, "ff_table: %s\n", tb_last_error());
            return 1;
        }
        const int m = 16;
        tb_vec3 up = {0, 0, 1}, ns, pts[64];
        double area, exact = 0.0;
        tb_ff_polygon_frame(&scene[0], &ns, &area);
        for (int i = 0; i < m * m; i++) {
            tb_vec3 p = {(float)(0.05 + 1.5 * (i % m + 0.5) / m), (float)(-0.75 + 1.5 * (i / m + 0.5) / m), 0};
            exact += tb_ff_point_polygon(p, up, &half);
        }
        printf("\nHalf of the shooter hidden by a wall (%d x %d receivers, exact answer %.6f), relative error "
               "mean over %d seeds (signed) / largest |error|:\n\n| estimator |", m, m, exact / (m * m), nseeds);
        for (int s = 0; s < 4; s++)
            printf(" %d sample%s |", samples[s], samples[s] > 1 ? "s" : "");
        printf("\n|---|---|---|---|---|\n");
        for (int est = 0; est < 2; est++) {
            printf("| %s |", est ? "tb_ff_raycast (Wallace)" : "tb_ff_raycast_exact");
            for (int s = 0; s < 4; s++) {
                double mean = 0.0, worst = 0.0;
                for (int seed = 1; seed <= nseeds; seed++) {
                    double sum = 0.0;
                    for (int i = 0; i < m * m; i++) {
                        tb_vec3 p = {(float)(0.05 + 1.5 * (i % m + 0.5) / m),
                                     (float)(-0.75 + 1.5 * (i / m + 0.5) / m), 0};
                        tb_ff_sample_polygon(&scene[0], samples[s], (uint64_t)seed * 1000 + (uint64_t)i, pts);
                        sum += est ? tb_ff_raycast(pts, samples[s], ns, area, p, up, tb_ff_occluders_visible, occ)
                                   : tb_ff_raycast_exact(&scene[0], pts, samples[s], p, up, tb_ff_occluders_visible,
                                                         occ);
                    }
                    double e = (sum - exact) / exact;
                    mean += e / nseeds;
                    worst = fmax(worst, fabs(e));
                }
                printf(" %+.2e / %.2e |", mean, worst);
            }
            printf("\n");
        }
        tb_ff_occluders_free(occ);
    }

    printf("\nHemicube, %d x %d receivers, relative error by resolution against Howell / against the exact "
           "point form factor at the same receivers (the hemicube's own error):\n\n",
           grid_hc, grid_hc);
    printf("| case |");
    for (int r = 0; r < 5; r++)
        printf(" %d |", res[r]);
    printf("\n|---|---|---|---|---|---|\n");
    for (int c = 0; c < 3; c++) {
        double ref = ff_case_exact_grid(&cases[c], grid_hc);
        printf("| %s |", cases[c].name);
        for (int r = 0; r < 5; r++) {
            double f = ff_case_hemicube(&cases[c], grid_hc, res[r]);
            if (f < 0.0) {
                fprintf(stderr, "ff_table: %s\n", tb_last_error());
                return 1;
            }
            printf(" %+.2e / %+.2e |", (f - cases[c].exact) / cases[c].exact, (f - ref) / ref);
        }
        printf("\n");
    }
    /* Every pixel of a hemicube inside a closed box is covered by a face, so
     * the form factors sum to the sum of all delta form factors. */
    tb_ff_polygon box[6];
    for (int f = 0; f < 6; f++) {
        int axis = f / 2;
        float side = (f % 2) ? 1.0f : -1.0f;
        float q[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
        box[f].n = 4;
        for (int v = 0; v < 4; v++) {
            int vv = (f % 2) ? 3 - v : v;
            float c3[3];
            c3[axis] = side;
            c3[(axis + 1) % 3] = q[vv][0];
            c3[(axis + 2) % 3] = q[vv][1];
            box[f].v[v] = (tb_vec3){c3[0], c3[1], c3[2]};
        }
    }
    printf("\nSum of all delta form factors minus 1 (hemicube at the centre of a closed box):\n\n| resolution |");
    for (int r = 0; r < 5; r++)
        printf(" %d |", res[r]);
    printf("\n|---|---|---|---|---|---|\n| sum - 1 |");
    for (int r = 0; r < 5; r++) {
        tb_hemicube *hc = tb_hemicube_create(res[r]);
        double ff[6], sum = 0.0;
        if (!hc || tb_hemicube_formfactors(hc, (tb_vec3){0.1f, -0.2f, 0.3f}, (tb_vec3){0, 0, 1}, box, 6,
                                           TB_FF_NONE, ff)) {
            fprintf(stderr, "ff_table: %s\n", tb_last_error());
            return 1;
        }
        for (int f = 0; f < 6; f++)
            sum += ff[f];
        tb_hemicube_free(hc);
        printf(" %+.2e |", sum - 1.0);
    }
    printf("\n");
    return 0;
}

/* The unit cube's six walls as g x g inward-facing quads each (6 g^2). */
static void make_room(int g, tb_ff_polygon *polys)
{
    size_t k = 0;
    for (int face = 0; face < 6; face++) {
        int axis = face / 2;
        float side = (face % 2) ? 1.0f : 0.0f;
        for (int j = 0; j < g; j++)
            for (int i = 0; i < g; i++) {
                float a0 = (float)i / g, a1 = (float)(i + 1) / g, b0 = (float)j / g, b1 = (float)(j + 1) / g;
                float q[4][2] = {{a0, b0}, {a1, b0}, {a1, b1}, {a0, b1}};
                tb_ff_polygon p = {.n = 4};
                for (int v = 0; v < 4; v++) {
                    int vv = (face % 2) ? 3 - v : v; /* inward-facing on both walls of the axis */
                    float c3[3];
                    c3[axis] = side;
                    c3[(axis + 1) % 3] = q[vv][0];
                    c3[(axis + 2) % 3] = q[vv][1];
                    p.v[v] = (tb_vec3){c3[0], c3[1], c3[2]};
                }
                polys[k++] = p;
            }
    }
}

static int timing(void)
{
    /* A room of 6 x 16 x 16 quads (1536 occluders), receivers on the floor,
     * the shooter a ceiling element. */
    const int g = 16;
    size_t np = 6 * (size_t)g * g;
    tb_ff_polygon *polys = malloc(sizeof *polys * np);
    if (!polys)
        return 1;
    make_room(g, polys);
    tb_ff_occluders *occ = NULL;
    if (tb_ff_occluders_build(polys, np, &occ)) {
        fprintf(stderr, "ff_table: %s\n", tb_last_error());
        return 1;
    }
    const size_t nr = 4096;
    tb_vec3 *p = malloc(sizeof *p * nr), *n = malloc(sizeof *n * nr), pts[64];
    double *ff = malloc(sizeof *ff * nr);
    for (size_t i = 0; i < nr; i++) {
        p[i] = (tb_vec3){(float)((i % 64) + 0.5) / 64.0f, (float)((i / 64) + 0.5) / 64.0f, 0.0f};
        n[i] = (tb_vec3){0, 0, 1};
    }
    const tb_ff_polygon *shooter = &polys[5 * (size_t)g * g + (size_t)g * g / 2 + g / 2]; /* z = 1 */
    tb_vec3 ns;
    double area;
    tb_ff_polygon_frame(shooter, &ns, &area);
    printf("Ray casting, one thread, %zu receivers, room of %zu quads:\n\n", nr, np);
    printf("| samples | ns per receiver per sample, no occluders | with occluders (BVH) |\n|---|---|---|\n");
    const int samples[] = {1, 4, 16, 64};
    for (int s = 0; s < 4; s++) {
        tb_ff_sample_polygon(shooter, samples[s], 7, pts);
        double t[2];
        for (int o = 0; o < 2; o++) {
            double t0 = now();
            int reps = 0;
            do {
                for (size_t i = 0; i < nr; i++)
                    ff[i] = tb_ff_raycast(pts, samples[s], ns, area, p[i], n[i],
                                          o ? tb_ff_occluders_visible : NULL, o ? occ : NULL);
                reps++;
            } while (now() - t0 < 0.5);
            t[o] = (now() - t0) / ((double)reps * nr * samples[s]) * 1e9;
        }
        printf("| %d | %.1f | %.1f |\n", samples[s], t[0], t[1]);
    }
    printf("\nPer receiver (all samples), with occluders: ray casting / exact x visible fraction "
           "(tb_ff_raycast_exact):\n\n| samples | ns per receiver, tb_ff_raycast | tb_ff_raycast_exact |\n|---|---|---|\n");
    for (int s = 0; s < 4; s++) {
        tb_ff_sample_polygon(shooter, samples[s], 7, pts);
        double t[2];
        for (int o = 0; o < 2; o++) {
            double t0 = now();
            int reps = 0;
            do {
                for (size_t i = 0; i < nr; i++)
                    ff[i] = o ? tb_ff_raycast_exact(shooter, pts, samples[s], p[i], n[i], tb_ff_occluders_visible, occ)
                              : tb_ff_raycast(pts, samples[s], ns, area, p[i], n[i], tb_ff_occluders_visible, occ);
                reps++;
            } while (now() - t0 < 0.5);
            t[o] = (now() - t0) / ((double)reps * nr) * 1e9;
        }
        printf("| %d | %.1f | %.1f |\n", samples[s], t[0], t[1]);
    }
    /* The exact point form factor and the sample points. */
    {
        double t0 = now(), acc = 0.0;
        int reps = 0;
        do {
            for (size_t i = 0; i < nr; i++)
                acc += tb_ff_point_polygon(p[i], n[i], shooter);
            reps++;
        } while (now() - t0 < 0.5);
        double ns_pp = (now() - t0) / ((double)reps * nr) * 1e9;
        tb_ff_polygon tri = {{shooter->v[0], shooter->v[1], shooter->v[2]}, 3};
        double ns_s[2];
        for (int w = 0; w < 2; w++) {
            t0 = now();
            reps = 0;
            do {
                tb_ff_sample_polygon(w ? &tri : shooter, 64, (uint64_t)reps, pts);
                acc += pts[0].x;
                reps++;
            } while (now() - t0 < 0.5);
            ns_s[w] = (now() - t0) / ((double)reps * 64) * 1e9;
        }
        printf("\nExact point form factor (tb_ff_point_polygon, quad): %.1f ns per call; sample points "
               "(tb_ff_sample_polygon, 64 per call): %.1f ns per point on a quad, %.1f on a triangle "
               "(checksum %.3g)\n",
               ns_pp, ns_s[0], ns_s[1], acc);
    }
    printf("\nHemicube, one thread, centre on the floor: the room's %zu quads / the room's 6 walls as one "
           "quad each:\n\n", np);
    printf("| resolution | ms per hemicube, %zu quads | 6 quads |\n|---|---|---|\n", np);
    double *hff = malloc(sizeof *hff * np);
    const int res[] = {32, 64, 128, 256, 512};
    tb_ff_polygon walls[6];
    make_room(1, walls);
    for (int r = 0; r < 5; r++) {
        tb_hemicube *hc = tb_hemicube_create(res[r]);
        double ms[2];
        for (int w = 0; w < 2; w++) {
            double t0 = now();
            int reps = 0;
            do {
                tb_vec3 c = p[(size_t)reps * 97 % nr];
                if (tb_hemicube_formfactors(hc, c, (tb_vec3){0, 0, 1}, w ? walls : polys, w ? 6 : np, TB_FF_NONE,
                                            hff)) {
                    fprintf(stderr, "ff_table: %s\n", tb_last_error());
                    return 1;
                }
                if (w) { /* the six walls must still close the room */
                    double sum = 0.0;
                    for (int k = 0; k < 6; k++)
                        sum += hff[k];
                    if (fabs(sum - 1.0) > 1e-2) {
                        fprintf(stderr, "ff_table: walls do not close the room (sum %g)\n", sum);
                        return 1;
                    }
                }
                reps++;
            } while (now() - t0 < 0.5);
            ms[w] = (now() - t0) / reps * 1e3;
        }
        printf("| %d | %.3f | %.3f |\n", res[r], ms[0], ms[1]);
        tb_hemicube_free(hc);
    }
    free(hff);
    free(p);
    free(n);
    free(ff);
    free(polys);
    tb_ff_occluders_free(occ);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc == 2 && strcmp(argv[1], "accuracy") == 0)
        return accuracy();
    if (argc == 2 && strcmp(argv[1], "timing") == 0)
        return timing();
    bool help = argc == 2 && (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0);
    fprintf(help ? stdout : stderr,
            "usage: ff_table accuracy|timing\n"
            "  accuracy  relative errors of the form factors against Howell's catalogue (C-11, C-14, C-41):\n"
            "            exact point form factor, ray casting (1-64 samples), exact x visible fraction\n"
            "            (tb_ff_raycast_exact, 1-64 samples; also half the shooter hidden), hemicube (32-512)\n"
            "  timing    CPU cost, one thread (run with OMP_NUM_THREADS=1): ray casting per receiver and\n"
            "            sample with and without occluders, per receiver of ray casting and exact x visible\n"
            "            fraction, exact point form factor, sample points, hemicube\n"
            "Tables for docs/accuracy.md and docs/performance.md, printed as Markdown.\n");
    return help ? 0 : 2;
}
