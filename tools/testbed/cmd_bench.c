/* `testbed bench WHAT`: single-thread micro-benchmarks of the object level.
 * Each benchmark is a row of tb__benches; `intersect` measures ray tests per
 * second for every primitive kind (and a mesh and a CSG tree). Results go to
 * docs/performance.md with the command that produced them. */
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "commands.h"
#include "host/object/bounds.h"
#include "host/object/intersect.h"
#include "host/object/object.h"
#include "util/math/rng.h"

static void tb__bench_usage(FILE *out)
{
    fprintf(out,
            "usage: testbed bench intersect [--rays N] [--seed S]\n"
            "\n"
            "Single-thread benchmarks of the object level.\n"
            "\n"
            "  intersect    for every primitive kind with its default geometry (plus polygon\n"
            "               meshes and a CSG difference), N random rays from a sphere of radius\n"
            "               3 around the object aimed at uniform points of its bounding box;\n"
            "               times tb_object_intersect (closest hit, with u, v and the normal)\n"
            "               and tb_object_occluded (any hit) over the same rays and prints the\n"
            "               rate in millions of rays per second and the fraction that hit.\n"
            "\n"
            "  --rays N     rays per object (default 1000000)\n"
            "  --seed S     random seed (default 1)\n"
            "\n"
            "usage: testbed bench accel [--tris N,...] [--rays N] [--threads T,...] [--accel K,...]\n"
            "                           [--seed S] [--no-stats]\n"
            "\n"
            "  accel        the BVH, the uniform grid and the plain list (host/render/accel.h)\n"
            "               on triangle soups and tessellated spheres of N triangles (default\n"
            "               1000,100000): primary, diffuse and shadow ray sets of N rays\n"
            "               (default 200000) with T threads (default 1,2); prints Mrays/s\n"
            "               (wall clock) and Mrays per CPU second, then checks that the three\n"
            "               structures gave the same answers (exit status 1 if not). --accel\n"
            "               bvh,grid,list chooses the structures; --no-stats turns counters off\n"
            "               (details: testbed bench accel --help).\n"
            "  -h, --help   show this help\n"
            "\n"
            "usage: testbed bench tessellate [--angle A] [--edge E] [--seconds S] [--split]\n"
            "\n"
            "  tessellate   tb_polygonize of every kind: mesh size, meshes/s and Mtriangles/s\n"
            "               (details: testbed bench tessellate --help)\n"
            "\n"
            "usage: testbed bench rays SCENE.mid [--embree] [--rays N] [--threads T,...] [--seed S]\n"
            "\n"
            "  rays         primary, shadow and diffuse rays of a scene through our BVH and (with\n"
            "               --embree) Embree 3: Mrays/s, ratio, scaling, agreement (details:\n"
            "               testbed bench rays --help)\n"
            "\n"
            "usage: testbed bench gpu SCENE.mid [--rays N] [--repeat R] [--seed S] [--device N]\n"
            "\n"
            "  gpu          the Vulkan intersect kernel vs the CPU path on primary, shadow and\n"
            "               diffuse rays: Mrays/s, kernel device time, ratio (testbed bench gpu --help)\n"
            "\n"
            "usage: testbed bench formfactor SCENE.mid [--shooters N] [--samples N] [--repeat R] [--device N]\n"
            "\n"
            "  formfactor   ray-cast form factors per second, the Vulkan kernel vs the CPU batch, on the\n"
            "               scene meshed as for radiosity (details: testbed bench formfactor --help)\n"
            "\n"
            "usage: testbed bench scale [--kind grid|csg|mesh] [--counts 1e4,1e5,...] [--threads T]\n"
            "\n"
            "  scale        generated scenes of growing size: parse, prepare, build and first-pixel\n"
            "               time and peak memory per count (details: testbed bench scale --help)\n"
            "\n"
            "Exit status: 0 done, 1 an object could not be built, 2 usage error.\n");
}

static double tb__now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts); /* CPU time: steadier than wall time on a shared machine */
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* A unit geodesic sphere (icosahedron split `levels` times), counter-clockwise
 * from outside, into caller-provided storage sized for 20 4^levels faces. */
typedef struct tb__mesh {
    int nv, nf;
    tb_vec3 *v;
    int *start, *idx;
} tb__mesh;

static int tb__mid(tb__mesh *m, int *key, int cap, int a, int b)
{
    int lo = a < b ? a : b, hi = a < b ? b : a;
    unsigned h = ((unsigned)lo * 2654435761u ^ (unsigned)hi * 40503u) % (unsigned)cap;
    while (key[3 * h] != -1) {
        if (key[3 * h] == lo && key[3 * h + 1] == hi)
            return key[3 * h + 2];
        h = (h + 1) % (unsigned)cap;
    }
    tb_vec3 p = m->v[lo], q = m->v[hi];
    double x = (double)p.x + q.x, y = (double)p.y + q.y, z = (double)p.z + q.z, l = sqrt(x * x + y * y + z * z);
    m->v[m->nv] = (tb_vec3){(float)(x / l), (float)(y / l), (float)(z / l)};
    key[3 * h] = lo, key[3 * h + 1] = hi, key[3 * h + 2] = m->nv;
    return m->nv++;
}

static int tb__icosphere(int levels, tb__mesh *m)
{
    int nf = 20, nv = 12;
    for (int i = 0; i < levels; i++)
        nv += nf * 3 / 2, nf *= 4;
    m->v = malloc(sizeof(tb_vec3) * (size_t)nv);
    m->start = malloc(sizeof(int) * (size_t)(nf + 1));
    m->idx = malloc(sizeof(int) * 3 * (size_t)nf);
    int *tmp = malloc(sizeof(int) * 3 * (size_t)nf);
    if (!m->v || !m->start || !m->idx || !tmp) {
        free(tmp);
        return 0;
    }
    double t = (1.0 + sqrt(5.0)) / 2.0, l = sqrt(1.0 + t * t);
    const double b[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                             {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    for (int i = 0; i < 12; i++)
        m->v[i] = (tb_vec3){(float)(b[i][0] / l), (float)(b[i][1] / l), (float)(b[i][2] / l)};
    static const int f20[60] = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4,
                                11, 10, 2, 10, 7, 6, 7, 1, 8, 3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8,
                                3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
    memcpy(m->idx, f20, sizeof f20);
    m->nv = 12;
    int n = 20;
    for (int lv = 0; lv < levels; lv++) {
        int cap = 4 * n + 7;
        int *key = malloc(sizeof(int) * 3 * (size_t)cap);
        if (!key) {
            free(tmp);
            return 0;
        }
        for (int i = 0; i < 3 * cap; i++)
            key[i] = -1;
        for (int f = 0; f < n; f++) {
            int a = m->idx[3 * f], c1 = m->idx[3 * f + 1], c2 = m->idx[3 * f + 2];
            int ab = tb__mid(m, key, cap, a, c1), bc = tb__mid(m, key, cap, c1, c2), ca = tb__mid(m, key, cap, c2, a);
            int q[12] = {a, ab, ca, c1, bc, ab, c2, ca, bc, ab, bc, ca};
            memcpy(&tmp[12 * f], q, sizeof q);
        }
        free(key);
        n *= 4;
        memcpy(m->idx, tmp, sizeof(int) * 3 * (size_t)n);
    }
    free(tmp);
    m->nf = n;
    for (int f = 0; f <= n; f++)
        m->start[f] = 3 * f;
    return 1;
}

/* One row of the intersect table. */
typedef struct tb__case {
    const char *name;
    tb_mid_object obj;
} tb__case;

static tb_mid_object tb__prim(tb_prim_kind k)
{
    tb_mid_object m;
    memset(&m, 0, sizeof m);
    m.kind = k;
    m.to_world = tb_transform_identity();
    m.geom = tb_mid_geometry_default(k);
    m.material = tb_mid_material_default();
    return m;
}

static int tb__bench_intersect(uint64_t nrays, uint64_t seed)
{
    tb__mesh small = {0}, big = {0};
    if (!tb__icosphere(2, &small) || !tb__icosphere(5, &big)) {
        fprintf(stderr, "testbed bench: out of memory\n");
        return TB_EXIT_FAIL;
    }
    tb__case cases[20];
    int nc = 0;
    for (int k = TB_PRIM_SPHERE; k <= TB_PRIM_ROUND_ARCH; k++) {
        if (k == TB_PRIM_POLYGONS)
            continue;
        cases[nc].name = tb_prim_kind_name((tb_prim_kind)k);
        cases[nc++].obj = tb__prim((tb_prim_kind)k);
    }
    tb__mesh *meshes[2] = {&small, &big};
    const char *mesh_names[2] = {"mesh 320 tris", "mesh 20480 tris"};
    for (int i = 0; i < 2; i++) {
        tb_mid_object m = tb__prim(TB_PRIM_POLYGONS);
        m.geom.polygons.nvertices = meshes[i]->nv;
        m.geom.polygons.vertices = meshes[i]->v;
        m.geom.polygons.nfaces = meshes[i]->nf;
        m.geom.polygons.face_start = meshes[i]->start;
        m.geom.polygons.indices = meshes[i]->idx;
        cases[nc].name = mesh_names[i];
        cases[nc++].obj = m;
    }
    tb_mid_object kids[2] = {tb__prim(TB_PRIM_CUBE), tb__prim(TB_PRIM_SPHERE)};
    tb_transform s;
    if (tb_transform_scale((tb_dvec3){1.3, 1.3, 1.3}, &s) == TB_OK)
        kids[1].to_world = s;
    tb_mid_object diff = tb__prim(TB_PRIM_DIFFERENCE);
    diff.children = kids;
    diff.nchildren = 2;
    cases[nc].name = "cube - sphere";
    cases[nc++].obj = diff;

    tb_ray *rays = malloc(sizeof *rays * (size_t)nrays);
    if (!rays) {
        fprintf(stderr, "testbed bench: out of memory for %" PRIu64 " rays\n", nrays);
        return TB_EXIT_FAIL;
    }
    printf("testbed bench intersect: %" PRIu64 " random rays per object toward its bounding box, one thread\n\n",
           nrays);
    printf("%-16s %7s %18s %18s\n", "object", "hit %", "closest Mrays/s", "any-hit Mrays/s");
    int status = TB_EXIT_OK;
    for (int c = 0; c < nc; c++) {
        tb_object *o = NULL;
        if (tb_object_from_mid(&cases[c].obj, 0, NULL, NULL, &o) != TB_OK) {
            fprintf(stderr, "testbed bench: %s: %s\n", cases[c].name, tb_last_error());
            status = TB_EXIT_FAIL;
            continue;
        }
        tb_aabb box;
        const tb_object *leaf = tb_prim_is_csg(o->kind) ? &o->children[0] : o;
        if (tb_bounds_world(leaf->kind, &leaf->geom, &leaf->to_world, &box) != TB_OK)
            box = (tb_aabb){{-1, -1, -1}, {1, 1, 1}};
        tb_rng rng;
        tb_rng_seed(&rng, seed, (uint64_t)c);
        for (uint64_t i = 0; i < nrays; i++) {
            double z = 2.0 * tb_rng_double(&rng) - 1.0, phi = 6.283185307179586 * tb_rng_double(&rng);
            double rr = sqrt(fmax(0.0, 1.0 - z * z));
            tb_vec3 o3 = {(float)(3.0 * rr * cos(phi)), (float)(3.0 * rr * sin(phi)), (float)(3.0 * z)};
            tb_vec3 t = {box.lo.x + (box.hi.x - box.lo.x) * tb_rng_float(&rng),
                         box.lo.y + (box.hi.y - box.lo.y) * tb_rng_float(&rng),
                         box.lo.z + (box.hi.z - box.lo.z) * tb_rng_float(&rng)};
            rays[i] = tb_ray_make(o3, (tb_vec3){t.x - o3.x, t.y - o3.y, t.z - o3.z}, 0.0f, INFINITY);
        }
        uint64_t hits = 0, occ = 0;
        tb_hit h;
        double t0 = tb__now();
        for (uint64_t i = 0; i < nrays; i++)
            hits += tb_object_intersect(o, &rays[i], &h);
        double t1 = tb__now();
        for (uint64_t i = 0; i < nrays; i++)
            occ += tb_object_occluded(o, &rays[i]);
        double t2 = tb__now();
        if (occ != hits)
            fprintf(stderr, "testbed bench: %s: %" PRIu64 " closest hits but %" PRIu64 " occluded\n", cases[c].name,
                    hits, occ);
        printf("%-16s %7.1f %18.2f %18.2f\n", cases[c].name, 100.0 * (double)hits / (double)nrays,
               (double)nrays / (t1 - t0) * 1e-6, (double)nrays / (t2 - t1) * 1e-6);
        fflush(stdout);
        tb_object_free(o);
    }
    free(rays);
    tb__mesh *all[2] = {&small, &big};
    for (int i = 0; i < 2; i++) {
        free(all[i]->v);
        free(all[i]->start);
        free(all[i]->idx);
    }
    return status;
}

/* `testbed bench intersect [--rays N] [--seed S]` (argv[0] is "intersect"). */
static int tb__bench_intersect_cmd(int argc, char **argv)
{
    uint64_t nrays = 1000000, seed = 1;
    const tb_opt opts[] = {
        {"rays", .type = TB_OPT_UINT64, .dest = &nrays, .max = 4294967296.0, .metavar = "N", .flags = TB_OPTF_BASE0,
         .help = "rays per object, 1 .. 2^32 (default %D)"},
        {"seed", .type = TB_OPT_UINT64, .dest = &seed, .metavar = "S", .flags = TB_OPTF_BASE0,
         .help = "random seed (default %D)"},
        {0},
    };
    const tb_cli cli = {
        .prog = "testbed bench intersect",
        .err = "testbed bench intersect: ",
        .usage = "[--rays N] [--seed S]",
        .intro = "\n"
                 "For every primitive kind with its default geometry (plus polygon meshes and a CSG\n"
                 "difference), N random rays from a sphere of radius 3 around the object aimed at\n"
                 "uniform points of its bounding box; times tb_object_intersect (closest hit, with\n"
                 "u, v and the normal) and tb_object_occluded (any hit) over the same rays and prints\n"
                 "the rate in millions of rays per second and the fraction that hit, one thread.\n",
        .opts = opts,
        .outro = "\nExit status: 0 done, 1 an object could not be built, 2 usage error.",
    };
    int npos, prc = tb_cli_parse(&cli, argc, argv, &npos);
    if (prc != TB_CLI_OK)
        return prc;
    if (nrays == 0)
        return tb_cli_usage_error(&cli, "--rays: expected an integer in [1, 2^32], got '0'");
    return tb__bench_intersect(nrays, seed);
}

/* The benchmarks: add a row (and a paragraph to the usage text) for a new one. */
static const struct {
    const char *name;
    int (*run)(int argc, char **argv); /* argv[0] is the benchmark's name */
} tb__benches[] = {
    {"intersect", tb__bench_intersect_cmd},
    {"accel", tb_cmd_bench_accel}, /* cmd_bench_accel.c */
    {"tessellate", tb_cmd_bench_tessellate}, /* cmd_bench_tessellate.c */
    {"rays", tb_cmd_bench_rays}, /* cmd_bench_rays.c */
    {"gpu", tb_cmd_bench_gpu},   /* cmd_bench_gpu.c */
    {"formfactor", tb_cmd_bench_formfactor}, /* cmd_bench_formfactor.c */
    {"scale", tb_cmd_bench_scale},           /* cmd_bench_scale.c */
};

int tb_cmd_bench(int argc, char **argv)
{
    /* `bench WHAT --help` is the benchmark's own help (from its option table). */
    if (argc < 2 || tb_wants_help(2, argv)) {
        tb__bench_usage(argc < 2 ? stderr : stdout);
        return argc < 2 ? TB_EXIT_USAGE : TB_EXIT_OK;
    }
    for (size_t i = 0; i < sizeof tb__benches / sizeof tb__benches[0]; i++)
        if (strcmp(argv[1], tb__benches[i].name) == 0)
            return tb__benches[i].run(argc - 1, argv + 1);
    fprintf(stderr, "testbed bench: no benchmark '%s' (see testbed bench --help)\n", argv[1]);
    return TB_EXIT_USAGE;
}
