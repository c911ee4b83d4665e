/* The solved mesh written as PLY, .gltf and .glb (host/radiosity/output*.c;
 * docs/radiosity.md, "Outputs"): the glTF files are read back with an
 * independent reader (Assimp's glTF 2 importer) and compared with the PLY
 * (read here by hand from its documented layout): the same vertices in the
 * same order, positions and normals bit-equal, the triangles of every PLY
 * face, and COLOR_0 equal to the PLY's display colour (its 8-bit sRGB
 * within one step, and its float radiance times the scale in its comment);
 * the material is unlit. The scene has red and green walls, so colours in
 * the wrong channel order fail. Also: bad paths leave no file. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/scene.h>
#include <cmocka.h>

#include "host/radiosity/radiosity.h"
#include "host/render/scene.h"
#include "tb_test.h"
#include "util/stats/provenance.h"

/* The PLY as tb_rad_write_ply documents it. */
typedef struct ply {
    size_t nv, nf;
    float (*v)[9];          /* x y z nx ny nz r g b */
    unsigned char (*c)[3];  /* red green blue */
    uint32_t (*f)[5];       /* corner count, then up to 4 indices */
    double scale;           /* from the "times S (red green blue)" comment */
    bool has_provenance;
} ply;

static void ply_read(const char *path, ply *p)
{
    memset(p, 0, sizeof *p);
    FILE *fp = fopen(path, "rb");
    assert_non_null(fp);
    char line[8192];
    bool end = false;
    while (!end && fgets(line, sizeof line, fp)) {
        const char *t;
        if (sscanf(line, "element vertex %zu", &p->nv) == 1 || sscanf(line, "element face %zu", &p->nf) == 1)
            continue;
        if ((t = strstr(line, "8-bit sRGB times ")))
            p->scale = strtod(t + strlen("8-bit sRGB times "), NULL);
        if (!strncmp(line, "comment testbed provenance {", 28) && strstr(line, "\"scene_sha256\""))
            p->has_provenance = true;
        end = !strcmp(line, "end_header\n");
    }
    assert_true(end);
    assert_true(p->nv > 0 && p->nf > 0 && p->scale > 0);
    p->v = malloc(p->nv * sizeof *p->v);
    p->c = malloc(p->nv * sizeof *p->c);
    p->f = malloc(p->nf * sizeof *p->f);
    assert_true(p->v && p->c && p->f);
    for (size_t i = 0; i < p->nv; i++) {
        assert_int_equal(fread(p->v[i], 4, 9, fp), 9);
        assert_int_equal(fread(p->c[i], 1, 3, fp), 3);
    }
    for (size_t i = 0; i < p->nf; i++) {
        unsigned char n;
        uint32_t obj;
        assert_int_equal(fread(&n, 1, 1, fp), 1);
        assert_true(n == 3 || n == 4);
        p->f[i][0] = n;
        assert_int_equal(fread(p->f[i] + 1, 4, n, fp), n);
        assert_int_equal(fread(&obj, 4, 1, fp), 1);
    }
    assert_int_equal(fgetc(fp), EOF);
    fclose(fp);
}

static void ply_free(ply *p)
{
    free(p->v), free(p->c), free(p->f);
}

/* sRGB transfer curve (IEC 61966-2-1), written out here rather than taken
 * from util/color, so the check does not share the writer's code. */
static double srgb_encode(double x)
{
    return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

static bool file_exists(const char *path)
{
    return access(path, F_OK) == 0;
}

/* Reads `path` with Assimp (no post-processing: vertices as stored) and
 * compares it with the PLY. Returns the number of vertices whose colours
 * are not grey (to show the check has teeth). */
static size_t check_gltf(const char *path, const ply *p)
{
    const struct aiScene *sc = aiImportFile(path, 0);
    if (!sc)
        fail_msg("Assimp cannot read %s: %s", path, aiGetErrorString());
    assert_int_equal(sc->mNumMeshes, 1);
    const struct aiMesh *me = sc->mMeshes[0];
    size_t ntri = 0;
    for (size_t f = 0; f < p->nf; f++)
        ntri += p->f[f][0] - 2;
    assert_int_equal(me->mNumVertices, p->nv);
    assert_int_equal(me->mNumFaces, ntri);
    assert_non_null(me->mNormals);
    assert_non_null(me->mColors[0]);
    size_t coloured = 0;
    for (size_t i = 0; i < p->nv; i++) {
        const float *v = p->v[i];
        /* positions and normals are the same floats */
        assert_true(me->mVertices[i].x == v[0] && me->mVertices[i].y == v[1] && me->mVertices[i].z == v[2]);
        assert_true(me->mNormals[i].x == v[3] && me->mNormals[i].y == v[4] && me->mNormals[i].z == v[5]);
        const struct aiColor4D *c = &me->mColors[0][i];
        const double col[3] = {c->r, c->g, c->b};
        for (int k = 0; k < 3; k++) {
            /* linear display colour = clamp(radiance * scale) (the scale is
             * printed with 9 digits) ... */
            double want = fmin(fmax((double)v[6 + k] * p->scale, 0.0), 1.0);
            if (!(fabs(col[k] - want) <= 2e-6 * fmax(want, 1e-3)))
                fail_msg("%s: vertex %zu channel %d: COLOR_0 %.9g, PLY radiance x scale %.9g", path, i, k, col[k],
                         want);
            /* ... and sRGB-encoded, the PLY's 8 bits within one step */
            double e = 255.0 * srgb_encode(col[k]);
            if (!(fabs(e - (double)p->c[i][k]) <= 0.5 + 1e-3))
                fail_msg("%s: vertex %zu channel %d: COLOR_0 %.9g is %.3f/255 in sRGB, PLY %u", path, i, k, col[k],
                         e, p->c[i][k]);
        }
        if (fabs(col[0] - col[1]) > 0.05 || fabs(col[1] - col[2]) > 0.05)
            coloured++;
    }
    /* triangles (c0 c1 c2) and (c0 c2 c3) of every PLY face, in order */
    size_t t = 0;
    for (size_t f = 0; f < p->nf; f++) {
        const uint32_t *pf = p->f[f];
        for (uint32_t k = 0; k + 2 < pf[0]; k++, t++) {
            const struct aiFace *af = &me->mFaces[t];
            assert_int_equal(af->mNumIndices, 3);
            assert_int_equal(af->mIndices[0], pf[1]);
            assert_int_equal(af->mIndices[1], pf[2 + k]);
            assert_int_equal(af->mIndices[2], pf[3 + k]);
        }
    }
    /* KHR_materials_unlit reaches the reader as the unlit shading model */
    assert_true(me->mMaterialIndex < sc->mNumMaterials);
    int shading = -1;
    /* aiGetMaterialInteger is a C99 inline definition in Assimp's header with
     * no external symbol: unoptimised builds (the sanitizer build) fail to
     * link it, so call the array form it wraps. */
    assert_int_equal(aiGetMaterialIntegerArray(sc->mMaterials[me->mMaterialIndex], AI_MATKEY_SHADING_MODEL, &shading,
                                               NULL),
                     aiReturn_SUCCESS);
    assert_int_equal(shading, aiShadingMode_Unlit);
    aiReleaseImport(sc);
    return coloured;
}

static void test_gltf_matches_ply(void **state)
{
    (void)state;
    char scene_path[1024];
    snprintf(scene_path, sizeof scene_path, "%s/scenes/cornell-box-rgb.mid", TB_SOURCE_DIR);
    tb_scene_options so = {.no_accel = true};
    tb_scene *sc = NULL;
    if (tb_scene_load(scene_path, &so, &sc))
        fail_msg("%s", tb_last_error());
    tb_rad_mesh m;
    tb_rad_mesh_options mo = {.max_edge = 100};
    assert_int_equal(tb_rad_mesh_from_scene(sc, &mo, &m), TB_OK);
    tb_rad_options o = {.samples = 4};
    tb_rad_solver *s = NULL;
    assert_int_equal(tb_rad_solver_create(&m, NULL, &o, &s), TB_OK);
    tb_rad_stop stop = {.threshold = 0.05};
    assert_int_equal(tb_rad_solver_run(s, &stop, NULL, NULL, 0), TB_OK);

    tb_provenance prov;
    char *argv[] = {"test_mesh_out", NULL};
    assert_int_equal(tb_provenance_init(&prov, 1, argv), TB_OK);
    assert_int_equal(tb_provenance_hash_file(&prov, scene_path), TB_OK);
    assert_int_equal(tb_provenance_set_options(&prov, "max_edge=100 samples=4 threshold=0.05"), TB_OK);

    char ply_path[1024], gltf_path[1024], glb_path[1024];
    snprintf(ply_path, sizeof ply_path, "%s/mesh_out.ply", tb_test_tmpdir());
    snprintf(gltf_path, sizeof gltf_path, "%s/mesh_out.gltf", tb_test_tmpdir());
    snprintf(glb_path, sizeof glb_path, "%s/mesh_out.glb", tb_test_tmpdir());
    double scale = tb_rad_display_scale(s);
    assert_true(scale > 0 && isfinite(scale));
    assert_int_equal(tb_rad_write_ply(s, ply_path, scale, &prov), TB_OK);
    assert_int_equal(tb_rad_write_gltf(s, gltf_path, scale, false, &prov), TB_OK);
    assert_int_equal(tb_rad_write_gltf(s, glb_path, scale, true, &prov), TB_OK);

    ply p;
    ply_read(ply_path, &p);
    assert_true(p.has_provenance);
    assert_int_equal(p.nf, m.nelems);
    size_t c1 = check_gltf(gltf_path, &p), c2 = check_gltf(glb_path, &p);
    assert_int_equal(c1, c2);
    /* the red and green walls: many vertices are far from grey */
    print_message("%zu vertices, %zu faces, %zu coloured vertices\n", p.nv, p.nf, c1);
    assert_true(c1 > p.nv / 10);

    /* the format follows the extension */
    assert_int_equal(tb_rad_mesh_format_from_path("a/b.PLY"), TB_RAD_MESH_PLY);
    assert_int_equal(tb_rad_mesh_format_from_path("b.gltf"), TB_RAD_MESH_GLTF);
    assert_int_equal(tb_rad_mesh_format_from_path("b.Glb"), TB_RAD_MESH_GLB);
    assert_int_equal(tb_rad_mesh_format_from_path("b.obj"), TB_RAD_MESH_UNKNOWN);
    assert_int_equal(tb_rad_mesh_format_from_path("gltf"), TB_RAD_MESH_UNKNOWN);
    assert_int_equal(tb_rad_mesh_format_from_path("x.gltf/b"), TB_RAD_MESH_UNKNOWN);

    /* an unwritable destination: an error and no file */
    char bad[1024];
    snprintf(bad, sizeof bad, "%s/no-such-dir/x.gltf", tb_test_tmpdir());
    assert_int_not_equal(tb_rad_write_gltf(s, bad, scale, false, &prov), TB_OK);
    assert_false(file_exists(bad));
    snprintf(bad, sizeof bad, "%s/no-such-dir/x.glb", tb_test_tmpdir());
    assert_int_not_equal(tb_rad_write_gltf(s, bad, scale, true, NULL), TB_OK);
    assert_false(file_exists(bad));

    ply_free(&p);
    remove(ply_path), remove(gltf_path), remove(glb_path);
    tb_provenance_free(&prov);
    tb_rad_solver_free(s);
    tb_rad_mesh_free(&m);
    tb_scene_free(sc);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gltf_matches_ply),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
