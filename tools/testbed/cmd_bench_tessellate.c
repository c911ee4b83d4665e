/* `testbed bench tessellate`: tessellation rate of host/object/polygonize.h
 * for every primitive kind (docs/performance.md, "Tessellation"). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "commands.h"
#include "host/object/polygonize.h"
#include "util/mesh/fed.h"

/* Thread CPU time in seconds: steadier than wall time on a shared machine. */
static double tb__tess_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int tb_cmd_bench_tessellate(int argc, char **argv)
{
    tb_poly_options o = {.max_angle = 0.05};
    double seconds = 0.3;
    const tb_opt opts[] = {
        {"angle", .type = TB_OPT_DOUBLE, .dest = &o.max_angle, .min = 0, .max = INFINITY, .metavar = "A",
         .help = "angular tolerance in radians (default %D)"},
        {"edge", .type = TB_OPT_DOUBLE, .dest = &o.max_edge, .min = 0, .max = INFINITY, .metavar = "E",
         .help = "largest edge length, object units (default %D: none)"},
        {"seconds", .type = TB_OPT_DOUBLE, .dest = &seconds, .min = 0, .max = 3600, .metavar = "S",
         .help = "CPU time per kind (default %D)"},
        {"split", .type = TB_OPT_FLAG, .dest = &o.split,
         .help = "one vertex per (point, face, u, v) instead of welded vertices"},
        {0},
    };
    const tb_cli cli = {
        .prog = "testbed bench tessellate",
        .err = "testbed bench tessellate: ",
        .usage = "[--angle A] [--edge E] [--seconds S] [--split]",
        .intro = "\n"
                 "Tessellates every primitive kind with its default geometry (polygons: the six\n"
                 "faces of the cube [-1,1]^3) with tb_polygonize, one thread, repeatedly for at\n"
                 "least S CPU seconds per kind, and prints the mesh size and the rate in meshes\n"
                 "and in triangles per second (a FED face of n corners counts n - 2 triangles).\n",
        .opts = opts,
        .outro = "\nExit status: 0 done, 1 a tessellation failed, 2 usage error.",
    };
    int npos, prc = tb_cli_parse(&cli, argc, argv, &npos);
    if (prc != TB_CLI_OK)
        return prc;
    /* The cube as six quads, for the polygons row. */
    static const tb_vec3 cube_v[8] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                      {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
    static const int cube_i[24] = {0, 3, 2, 1, 4, 5, 6, 7, 0, 1, 5, 4, 2, 3, 7, 6, 1, 2, 6, 5, 0, 4, 7, 3};
    static const int cube_s[7] = {0, 4, 8, 12, 16, 20, 24};

    printf("testbed bench tessellate: angle %g rad, edge %g, %s vertices, one thread\n\n", o.max_angle, o.max_edge,
           o.split ? "split" : "welded");
    printf("%-12s %9s %9s %10s %12s %12s\n", "kind", "vertices", "faces", "triangles", "meshes/s", "Mtris/s");
    int status = TB_EXIT_OK;
    for (int k = TB_PRIM_SPHERE; k <= TB_PRIM_ROUND_ARCH; k++) {
        tb_mid_geometry g = tb_mid_geometry_default((tb_prim_kind)k);
        if (k == TB_PRIM_POLYGONS) {
            g.polygons.nvertices = 8, g.polygons.vertices = cube_v, g.polygons.nfaces = 6;
            g.polygons.face_start = cube_s, g.polygons.indices = cube_i;
        }
        uint64_t meshes = 0, tris = 0;
        uint32_t nv = 0, nf = 0;
        double t0 = tb__tess_now(), t1 = t0;
        do {
            tb_fed *m = NULL;
            if (tb_polygonize((tb_prim_kind)k, &g, &o, &m) != TB_OK) {
                fprintf(stderr, "testbed bench tessellate: %s: %s\n", tb_prim_kind_name((tb_prim_kind)k),
                        tb_last_error());
                status = TB_EXIT_FAIL;
                break;
            }
            nv = m->nverts, nf = m->nfaces;
            uint64_t t = 0;
            for (uint32_t f = 0; f < m->nfaces; f++)
                t += tb_fed_loop_size(m, tb_fed_face_outer(m, f)) - 2;
            tris += t;
            meshes++;
            tb_fed_free(m);
            t1 = tb__tess_now();
        } while (t1 - t0 < seconds);
        if (meshes == 0)
            continue;
        double dt = t1 - t0 > 0.0 ? t1 - t0 : 1e-9;
        printf("%-12s %9u %9u %10llu %12.1f %12.3f\n", tb_prim_kind_name((tb_prim_kind)k), nv, nf,
               (unsigned long long)(tris / meshes), (double)meshes / dt, (double)tris / dt * 1e-6);
        fflush(stdout);
    }
    return status;
}
