/* Timing of the mesh module for docs/meshing.md and docs/fed.md (not a test:
 * no wall-clock time is asserted anywhere). Usage: mesh_bench [TMPDIR]
 *  - a 10^6-triangle FED (a 708 x 708 height-field grid, two triangles per
 *    cell): build, write and read in both forms;
 *  - triangulation of 10^5-vertex polygons (noisy circle, spiral band). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "util/math/rng.h"
#include "util/mesh/fed.h"
#include "util/mesh/mesh.h"
#include "util/mesh/triangulate.h"

/* CPU time of this process: on a shared, loaded machine it says what the
 * code costs far more steadily than wall-clock time (single-threaded code). */
static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static int fail(const char *what)
{
    fprintf(stderr, "mesh_bench: %s: %s\n", what, tb_last_error());
    return 1;
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : ".";
    enum { N = 708 };
    uint32_t nv = (N + 1) * (N + 1), nf = 2 * N * N;
    tb_vec3 *pos = malloc(sizeof(tb_vec3) * nv);
    uint32_t *sizes = malloc(sizeof(uint32_t) * nf), *corners = malloc(sizeof(uint32_t) * 3 * (size_t)nf);
    if (!pos || !sizes || !corners)
        return 1;
    for (uint32_t y = 0; y <= N; y++)
        for (uint32_t x = 0; x <= N; x++)
            pos[y * (N + 1) + x] = tb_vec3_make((float)x, (float)y, (float)(sin(x * 0.05) * cos(y * 0.07)));
    for (uint32_t y = 0, f = 0; y < N; y++)
        for (uint32_t x = 0; x < N; x++, f += 2) {
            uint32_t a = y * (N + 1) + x, b = a + 1, c = b + N + 1, d = a + N + 1;
            uint32_t *t = &corners[3 * (size_t)f];
            t[0] = a, t[1] = b, t[2] = c, t[3] = a, t[4] = c, t[5] = d;
            sizes[f] = sizes[f + 1] = 3;
        }
    tb_fed_desc desc = {.nverts = nv, .positions = pos, .nfaces = nf, .nloops = nf, .loop_sizes = sizes,
                        .corners = corners};
    tb_fed *m;
    double t0 = now();
    if (tb_fed_build(&desc, &m, NULL))
        return fail("build");
    double t_build = now() - t0;
    char bpath[1024], tpath[1024];
    snprintf(bpath, sizeof bpath, "%s/mesh_bench.fedb", dir);
    snprintf(tpath, sizeof tpath, "%s/mesh_bench.fed", dir);
    t0 = now();
    if (tb_fed_write_file(bpath, m, TB_FED_FORMAT_BINARY))
        return fail("write binary");
    double t_wb = now() - t0;
    t0 = now();
    if (tb_fed_write_file(tpath, m, TB_FED_FORMAT_TEXT))
        return fail("write text");
    double t_wt = now() - t0;
    tb_fed *b, *t;
    t0 = now();
    if (tb_fed_read_file(bpath, &b))
        return fail("read binary");
    double t_rb = now() - t0;
    t0 = now();
    if (tb_fed_read_file(tpath, &t))
        return fail("read text");
    double t_rt = now() - t0;
    if (!tb_fed_equal(m, b) || !tb_fed_equal(m, t))
        return fail("round trip");
    FILE *f = fopen(bpath, "rb");
    fseek(f, 0, SEEK_END);
    long bsize = ftell(f);
    fclose(f);
    f = fopen(tpath, "rb");
    fseek(f, 0, SEEK_END);
    long tsize = ftell(f);
    fclose(f);
    printf("FED, %u triangles, %u vertices, %u edges (CPU seconds):\n", nf, nv, m->nedges);
    printf("  build from arrays   %7.3f s\n", t_build);
    printf("  write binary        %7.3f s  (%.1f MB)\n", t_wb, bsize / 1e6);
    printf("  read binary         %7.3f s  (%.0f MB/s, including edges and adjacency)\n", t_rb, bsize / 1e6 / t_rb);
    printf("  write text          %7.3f s  (%.1f MB)\n", t_wt, tsize / 1e6);
    printf("  read text           %7.3f s  (%.0f MB/s)\n", t_rt, tsize / 1e6 / t_rt);
    /* Meshing: the same triangles as elements, and the 10^6 triangles
     * subdivided to a quarter of their edge length. */
    tb_mesh me;
    tb_mesh_init(&me);
    t0 = now();
    if (tb_mesh_from_fed(m, NULL, &me))
        return fail("mesh");
    printf("  mesh, no subdivision          %7.3f s  (%zu elements)\n", now() - t0, tb_mesh_nelems(&me));
    /* 0.75: sides (1) and diagonals (1.41) both get 2 parts, the regular
     * pattern; 0.5: 2 and 3 parts, the general path (triangulate + bisect). */
    const double bounds[2] = {0.75, 0.5};
    for (int b = 0; b < 2; b++) {
        tb_mesh_opts mo = {.max_edge = bounds[b], .quads = true};
        t0 = now();
        if (tb_mesh_from_fed(m, &mo, &me))
            return fail("mesh");
        size_t nq = 0;
        for (size_t i = 0; i < tb_mesh_nelems(&me); i++)
            nq += tb_mesh_elem_size(tb_mesh_elem_at(&me, i)) == 4;
        printf("  mesh, max edge %.2f, quads    %7.3f s  (%zu elements, %zu quads, %zu vertices)\n", bounds[b],
               now() - t0, tb_mesh_nelems(&me), nq, me.positions.len);
    }
    tb_mesh_free(&me);
    remove(bpath);
    remove(tpath);
    tb_fed_free(m), tb_fed_free(b), tb_fed_free(t);
    free(pos), free(sizes), free(corners);

    /* Triangulation of large polygons. */
    for (int kind = 0; kind < 2; kind++)
        for (uint32_t n = 10000; n <= 1000000; n *= 10) {
            double *xy = malloc(16 * (size_t)n);
            tb_rng rng;
            tb_rng_seed(&rng, 41, 4);
            if (kind == 0) {
                for (uint32_t k = 0; k < n; k++) {
                    double a = 6.283185307179586 * k / n, r = 1 + 0.002 * (tb_rng_double(&rng) - 0.5);
                    xy[2 * k] = r * cos(a), xy[2 * k + 1] = r * sin(a);
                }
            } else {
                uint32_t h = n / 2;
                for (uint32_t k = 0; k < h; k++) {
                    double a = 8 * 6.283185307179586 * k / h, r = 1 + a;
                    xy[2 * k] = r * cos(a), xy[2 * k + 1] = r * sin(a);
                }
                for (uint32_t k = 0; k < h; k++) {
                    double a = 8 * 6.283185307179586 * (h - 1 - k) / h, r = 4 + a;
                    xy[2 * (h + k)] = r * cos(a), xy[2 * (h + k) + 1] = r * sin(a);
                }
            }
            tb_array tris = TB_ARRAY_INIT(tb_tri);
            t0 = now();
            if (tb_triangulate_2d(xy, &n, 1, &tris, NULL))
                return fail("triangulate");
            printf("triangulate %-13s %8u vertices: %7.3f s CPU (%zu triangles)\n",
                   kind ? "spiral band" : "noisy circle", n, now() - t0, tris.len);
            tb_array_free(&tris);
            free(xy);
        }
    return 0;
}
