/* Timings of util/mesh/refine for docs/meshing.md, section 7 (run by hand:
 * refine_bench [N [ROUNDS [FRACTION]]]; not a test): an N x N quad grid
 * (default 300), ROUNDS rounds (default 3) each marking FRACTION (default
 * 0.1) of the current elements at random (PCG32, seed 1), CPU time per
 * round. */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "util/math/rng.h"
#include "util/mesh/refine.h"

static double cpu_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int main(int argc, char **argv)
{
    uint32_t n = argc > 1 ? (uint32_t)atoi(argv[1]) : 300;
    int rounds = argc > 2 ? atoi(argv[2]) : 3;
    double frac = argc > 3 ? atof(argv[3]) : 0.1;
    if (n < 1 || n > 4000 || rounds < 0 || !(frac >= 0 && frac <= 1)) {
        fprintf(stderr, "usage: refine_bench [N (1..4000) [ROUNDS [FRACTION]]]\n");
        return 2;
    }
    tb_mesh m;
    tb_mesh_init(&m);
    for (uint32_t j = 0; j <= n; j++)
        for (uint32_t i = 0; i <= n; i++) {
            tb_vec3 p = {(float)i, (float)j, 0};
            if (tb_array_push(&m.positions, &p))
                return 1;
        }
    for (uint32_t j = 0; j < n; j++)
        for (uint32_t i = 0; i < n; i++) {
            uint32_t a = j * (n + 1) + i;
            tb_mesh_elem e = {{a, a + 1, a + n + 2, a + n + 1}, 0, TB_MESH_NONE};
            if (tb_array_push(&m.elems, &e))
                return 1;
        }
    double t0 = cpu_seconds();
    tb_mesh_refiner *r;
    if (tb_mesh_refiner_create(&m, &r)) {
        fprintf(stderr, "%s\n", tb_last_error());
        return 1;
    }
    printf("create: %zu elements, %.3f s\n", m.elems.len, cpu_seconds() - t0);
    tb_rng g;
    tb_rng_seed(&g, 1, 1);
    tb_array map = TB_ARRAY_INIT(uint32_t);
    for (int round = 0; round < rounds; round++) {
        size_t ne = tb_mesh_refiner_mesh(r)->elems.len, k = 0;
        uint32_t *mk = malloc(sizeof *mk * (ne + 1));
        if (!mk)
            return 1;
        for (size_t i = 0; i < ne; i++)
            if (tb_rng_double(&g) < frac)
                mk[k++] = (uint32_t)i;
        tb_mesh_refine_stats st;
        double a = cpu_seconds();
        if (tb_mesh_refine(r, mk, k, &map, &st)) {
            fprintf(stderr, "%s\n", tb_last_error());
            return 1;
        }
        double b = cpu_seconds();
        printf("round %d: %zu -> %zu elements (%u marked, %u red splits: %u graded, %u closure; %u green): %.3f s\n",
               round, ne, tb_mesh_refiner_mesh(r)->elems.len, st.marked, st.red, st.graded, st.closure, st.green,
               b - a);
        free(mk);
    }
    tb_array_free(&map);
    tb_mesh_refiner_free(r);
    tb_mesh_free(&m);
    return 0;
}
