/* Patches against one level on the Cornell box (docs/performance.md,
 * "Radiosity: patches over elements"); run by hand, not a test:
 *   OMP_WAIT_POLICY=passive OMP_NUM_THREADS=2 build/dev/tests/radiosity/radiosity_patches_bench \
 *       [SCENE [MAX_EDGE [SAMPLES [THRESHOLD [PATCH_EDGE...]]]]]
 * For each patch edge (0: one level) the scene is meshed with patches, and on
 * the same elements: a reference (one level, 64 samples, to 1e-3), the one-level
 * solution and the two-level one (SAMPLES, to THRESHOLD). Printed: shots,
 * shooting seconds and the NRMSE of the element radiosities against the
 * reference (over the reflected part B - E, as --report), and the two-level
 * time as a ratio of the one-level time measured in the same run. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "host/radiosity/radiosity.h"
#include "host/render/scene.h"
#include "rad_measure.h"

static tb_rad_solver *tb__solve(const tb_rad_mesh *m, int samples, double thr)
{
    tb_rad_options o = {.samples = samples};
    tb_rad_solver *s = NULL;
    tb_rad_stop stop = {.threshold = thr};
    if (tb_rad_solver_create(m, NULL, &o, &s) || tb_rad_solver_run(s, &stop, NULL, NULL, 0)) {
        fprintf(stderr, "radiosity_patches_bench: %s\n", tb_last_error());
        exit(1);
    }
    return s;
}

int main(int argc, char **argv)
{
    const char *path = argc > 1 ? argv[1] : TB_SOURCE_DIR "/scenes/cornell-box-rgb.mid";
    double edge = argc > 2 ? atof(argv[2]) : 35.0;
    int samples = argc > 3 ? atoi(argv[3]) : 4;
    double thr = argc > 4 ? atof(argv[4]) : 0.01;
    double def[] = {0, 70, 105, 140, 210};
    int npe = argc > 5 ? argc - 5 : 5;
    tb_scene_options so = {.no_accel = true};
    tb_scene *sc = NULL;
    if (tb_scene_load(path, &so, &sc)) {
        fprintf(stderr, "radiosity_patches_bench: %s\n", tb_last_error());
        return 1;
    }
    printf("%s, max edge %g, %d samples, threshold %g\n", path, edge, samples, thr);
    printf("patch edge | elements | patches | one level: shots, s, NRMSE | two levels: shots (per N), s, NRMSE | "
           "time ratio\n");
    for (int k = 0; k < npe; k++) {
        double pe = argc > 5 ? atof(argv[5 + k]) : def[k];
        tb_rad_mesh_options mo = {.max_edge = edge, .patch_edge = pe};
        tb_rad_mesh m;
        if (tb_rad_mesh_from_scene(sc, &mo, &m)) {
            fprintf(stderr, "radiosity_patches_bench: %s\n", tb_last_error());
            return 1;
        }
        size_t np = m.npatches;
        m.npatches = 0;
        tb_rad_solver *s = tb__solve(&m, 64, 1e-3);
        double *ref = tb_rad_test_radiosities(s);
        tb_rad_solver_free(s);
        s = tb__solve(&m, samples, thr);
        double *b1 = tb_rad_test_radiosities(s), t1 = tb_rad_solver_seconds(s);
        unsigned long long n1 = (unsigned long long)tb_rad_solver_shots(s);
        tb_rad_solver_free(s);
        m.npatches = np;
        s = tb__solve(&m, samples, thr);
        double *b2 = tb_rad_test_radiosities(s), t2 = tb_rad_solver_seconds(s);
        unsigned long long n2 = (unsigned long long)tb_rad_solver_shots(s);
        tb_rad_solver_free(s);
        printf("%10g | %8zu | %7zu | %5llu, %6.3f, %.4f | %5llu (%.2f N), %6.3f, %.4f | %.2f\n", pe, m.nelems,
               np ? np : m.nelems, n1, t1, tb_rad_test_nrmse(&m, b1, ref), n2, (double)n2 / (double)m.nelems, t2,
               tb_rad_test_nrmse(&m, b2, ref), t2 / t1);
        fflush(stdout);
        free(ref), free(b1), free(b2);
        tb_rad_mesh_free(&m);
    }
    tb_scene_free(sc);
    return 0;
}
