/* tests/import: `testbed import` (host/mid/import.h) on hand-made files with
 * known values and on models of Debian's assimp-testmodels package.
 *
 * Every check compares with something the importer did not compute: the
 * source file parsed here (OBJ/PLY/STL vertex lines with strtof, binary STL,
 * PLY and glTF buffers read as bytes), Assimp's own scene read again here,
 * or values worked out by hand in docs/import.md's mappings. The output is
 * read back through the MID reader (which also validates it, as `testbed
 * check` does) and the FED reader. */
#include "tb_test.h"

#include <dirent.h>
#include <errno.h>
#include <stdbool.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "host/mid/import.h"
#include "host/mid/mid_reader.h"
#include "util/mesh/fed.h"

#ifndef TB_ASSIMP_MODELS
#define TB_ASSIMP_MODELS "/usr/share/assimp/models"
#endif
#define DATA TB_TESTS_DIR "/import/data"
#define PI 3.14159265358979323846
#define MAXP 1024

/* ------------------------------------------------------------------ helpers */

static void rm_tree(const char *path)
{
    struct stat sb;
    if (lstat(path, &sb) != 0)
        return;
    if (S_ISDIR(sb.st_mode)) {
        DIR *d = opendir(path);
        struct dirent *e;
        while (d && (e = readdir(d))) {
            if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
                continue;
            char sub[MAXP];
            snprintf(sub, sizeof sub, "%s/%s", path, e->d_name);
            rm_tree(sub);
        }
        if (d)
            closedir(d);
        rmdir(path);
    } else
        unlink(path);
}

/* A fresh empty folder under the test tmpdir. */
static void workdir(char *out, const char *name)
{
    snprintf(out, MAXP, "%s/import-%s", tb_test_tmpdir(), name);
    rm_tree(out);
    assert_int_equal(mkdir(out, 0777), 0);
}

static int name_cmp(const void *a, const void *b) { return strcmp(a, b); }

/* The entries of `dir`, sorted, as one "a|b|c" string (to compare before/after). */
static void list_dir(const char *dir, char *out, size_t n)
{
    char names[64][256];
    int k = 0;
    DIR *d = opendir(dir);
    assert_non_null(d);
    struct dirent *e;
    while ((e = readdir(d)) && k < 64)
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, ".."))
            snprintf(names[k++], 256, "%s", e->d_name);
    closedir(d);
    qsort(names, (size_t)k, sizeof names[0], name_cmp);
    out[0] = '\0';
    for (int i = 0; i < k; i++) {
        strncat(out, names[i], n - strlen(out) - 1);
        strncat(out, "|", n - strlen(out) - 1);
    }
}

static char *read_all(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *b = malloc((size_t)n + 1);
    assert_non_null(b);
    assert_int_equal(fread(b, 1, (size_t)n, f), (size_t)n);
    b[n] = '\0';
    fclose(f);
    *len = (size_t)n;
    return b;
}

static bool files_equal(const char *a, const char *b)
{
    size_t na, nb;
    char *x = read_all(a, &na), *y = read_all(b, &nb);
    bool eq = x && y && na == nb && memcmp(x, y, na) == 0;
    free(x), free(y);
    return eq;
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fputs(text, f);
    assert_int_equal(fclose(f), 0);
}

/* Warnings collected from the importer, one per line. */
typedef struct warnbuf {
    int n;
    char text[16384];
} warnbuf;

static void collect(void *user, const char *msg)
{
    warnbuf *w = user;
    w->n++;
    strncat(w->text, msg, sizeof w->text - strlen(w->text) - 1);
    strncat(w->text, "\n", sizeof w->text - strlen(w->text) - 1);
}

static tb_status import(const char *model, const char *out, tb_import_opts *opts, tb_import_stats *st, warnbuf *w)
{
    tb_import_opts o = opts ? *opts : (tb_import_opts){0};
    if (w) {
        memset(w, 0, sizeof *w);
        o.warn = collect;
        o.warn_user = w;
    }
    return tb_import(model, out, &o, st);
}

/* ------------------------------------------------------- reading MID back */

typedef struct obj_rec {
    char *name;           /* or NULL */
    char *mesh;           /* resolved FED path */
    char *base;           /* material name, or NULL */
    tb_mid_material mat;  /* resolved (texture pointers cleared) */
    tb_transform world;
} obj_rec;

typedef struct mat_rec {
    char *name;
    tb_mid_material mat;  /* texture pointers cleared */
    char *diffuse_tex;    /* resolved path or NULL */
} mat_rec;

typedef struct light_rec {
    char *name;
    tb_mid_light l;       /* ops, refs cleared */
} light_rec;

typedef struct scene_rec {
    int nobj, nmat, nlight;
    obj_rec obj[256];
    mat_rec mat[64];
    light_rec light[16];
    bool has_cam;
    tb_mid_camera cam;
} scene_rec;

static char *dup0(const char *s) { return s ? strdup(s) : NULL; }

static void clear_refs(tb_mid_material *m)
{
    m->name = m->base = NULL;
    m->diffuse_texture = m->specular_texture = m->transmission_texture = m->emission_texture = (tb_mid_ref){0};
    m->extra = (tb_mid_attrs){0};
    m->nrefs = 0;
    m->refs = NULL;
}

/* Reads a MID file (failing the test on any reader error). */
static scene_rec *read_scene(const char *path)
{
    scene_rec *s = calloc(1, sizeof *s);
    assert_non_null(s);
    tb_mid_reader *r;
    if (tb_mid_reader_open(&r, path))
        fail_msg("%s", tb_last_error());
    tb_mid_item it;
    tb_status st;
    while (!(st = tb_mid_reader_next(r, &it)) && it.type != TB_MID_ITEM_END) {
        if (it.type == TB_MID_ITEM_OBJECT) {
            assert_true(s->nobj < 256);
            const tb_mid_object *o = it.object;
            assert_int_equal(o->kind, TB_PRIM_POLYGONS);
            obj_rec *rec = &s->obj[s->nobj++];
            rec->name = dup0(o->name);
            rec->mesh = dup0(o->geom.polygons.mesh.path);
            rec->base = dup0(o->material.base);
            rec->mat = o->material;
            clear_refs(&rec->mat);
            rec->world = o->to_world;
        } else if (it.type == TB_MID_ITEM_MATERIAL) {
            assert_true(s->nmat < 64);
            mat_rec *rec = &s->mat[s->nmat++];
            rec->name = dup0(it.material->name);
            rec->diffuse_tex = dup0(it.material->diffuse_texture.path);
            rec->mat = *it.material;
            clear_refs(&rec->mat);
        } else if (it.type == TB_MID_ITEM_LIGHT) {
            assert_true(s->nlight < 16);
            light_rec *rec = &s->light[s->nlight++];
            rec->name = dup0(it.light->name);
            rec->l = *it.light;
            rec->l.name = NULL;
            rec->l.ops = NULL;
            rec->l.nops = 0;
            rec->l.refs = NULL;
            rec->l.extra = (tb_mid_attrs){0};
        } else if (it.type == TB_MID_ITEM_CAMERA) {
            s->has_cam = true;
            s->cam = *it.camera;
            s->cam.name = NULL;
            s->cam.refs = NULL;
            s->cam.extra = (tb_mid_attrs){0};
        }
    }
    if (st)
        fail_msg("%s", tb_last_error());
    tb_mid_reader_close(r);
    return s;
}

static void free_scene(scene_rec *s)
{
    for (int i = 0; i < s->nobj; i++)
        free(s->obj[i].name), free(s->obj[i].mesh), free(s->obj[i].base);
    for (int i = 0; i < s->nmat; i++)
        free(s->mat[i].name), free(s->mat[i].diffuse_tex);
    for (int i = 0; i < s->nlight; i++)
        free(s->light[i].name);
    free(s);
}

static const mat_rec *find_mat(const scene_rec *s, const char *name)
{
    for (int i = 0; i < s->nmat; i++)
        if (!strcmp(s->mat[i].name, name))
            return &s->mat[i];
    fail_msg("no material '%s'", name);
    return NULL;
}

static tb_fed *load_fed(const char *path)
{
    tb_fed *m;
    if (tb_fed_read_file(path, &m))
        fail_msg("%s", tb_last_error());
    return m;
}

static void assert_rgb(const tb_mid_color *c, float r, float g, float b)
{
    assert_int_equal(c->type, TB_MID_COLOR_RGB);
    if (c->rgb[0] != r || c->rgb[1] != g || c->rgb[2] != b)
        fail_msg("colour [%.9g %.9g %.9g], expected [%.9g %.9g %.9g]", c->rgb[0], c->rgb[1], c->rgb[2], r, g, b);
}

static bool same_bits(tb_vec3 a, tb_vec3 b) { return memcmp(&a, &b, sizeof a) == 0; }

/* ------------------------------------------- OBJ + MTL with known values */

/* The OBJ file parsed here: `v` lines with strtof, faces by usemtl group. */
typedef struct obj_src {
    int nv;
    tb_vec3 v[64];
    int ngroups;
    char group[16][32];
    int nfaces[16];
    int face_n[16][16];
    int face_v[16][16][8];
} obj_src;

static void parse_obj(const char *path, obj_src *o)
{
    memset(o, 0, sizeof *o);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char line[512];
    int g = -1;
    while (fgets(line, sizeof line, f)) {
        char *p = line, *e;
        if (!strncmp(line, "v ", 2)) {
            float x = strtof(p + 2, &e), y = strtof(e, &e), z = strtof(e, &e);
            o->v[o->nv++] = (tb_vec3){x, y, z};
        } else if (!strncmp(line, "usemtl ", 7)) {
            g = o->ngroups++;
            sscanf(line + 7, "%31s", o->group[g]);
        } else if (!strncmp(line, "f ", 2)) {
            if (g < 0)
                g = o->ngroups++; /* faces before any usemtl */
            int k = o->nfaces[g]++, n = 0;
            p += 2;
            for (long idx; (idx = strtol(p, &e, 10)), e != p; p = e)
                o->face_v[g][k][n++] = (int)idx - 1;
            o->face_n[g][k] = n;
        }
    }
    fclose(f);
}

/* The face as FED should hold it: consecutive corners at the same position
 * merged, and nothing if fewer than 3 corners are left or all corners lie
 * on one line (zero area). */
static int expected_face(const obj_src *o, const int *vi, int n, int *out)
{
    int k = 0;
    for (int i = 0; i < n; i++)
        if (k == 0 || !same_bits(o->v[out[k - 1]], o->v[vi[i]]))
            out[k++] = vi[i];
    while (k > 1 && same_bits(o->v[out[k - 1]], o->v[out[0]]))
        k--;
    if (k < 3)
        return 0;
    tb_vec3 a = o->v[out[0]];
    for (int i = 1; i + 1 < k; i++) {
        tb_vec3 b = o->v[out[i]], c = o->v[out[i + 1]];
        double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z, wx = c.x - a.x, wy = c.y - a.y, wz = c.z - a.z;
        if (uy * wz - uz * wy != 0 || uz * wx - ux * wz != 0 || ux * wy - uy * wx != 0)
            return k;
    }
    return 0;
}

static void test_obj_materials(void **state)
{
    (void)state;
    char w[MAXP], out[MAXP + 16], path[MAXP + 64];
    workdir(w, "obj");
    snprintf(out, sizeof out, "%s/m.mid", w);
    tb_import_stats st;
    warnbuf wb;
    if (import(DATA "/materials.obj", out, NULL, &st, &wb))
        fail_msg("%s", tb_last_error());
    print_message("warnings:\n%s", wb.text);
    scene_rec *s = read_scene(out);

    /* One object per usemtl group, in file order, each naming its material. */
    obj_src src;
    parse_obj(DATA "/materials.obj", &src);
    assert_int_equal(src.ngroups, 4);
    assert_int_equal(s->nobj, 4);
    assert_int_equal(st.objects, 4);
    assert_int_equal(st.fed_files, 4);
    assert_int_equal(st.materials, 4);
    assert_int_equal(st.textures, 1);
    for (int g = 0; g < 4; g++)
        assert_string_equal(s->obj[g].base, src.group[g]);

    /* Materials, mapped as docs/import.md says (all values exact in binary). */
    const mat_rec *m = find_mat(s, "full");
    assert_rgb(&m->mat.diffuse, 0.25f, 0.5f, 0.75f);
    assert_rgb(&m->mat.specular, 0.125f, 0.25f, 0.375f);
    assert_true(m->mat.exponent == 37.5f);
    assert_rgb(&m->mat.emission, 2, 4, 8);
    assert_true(m->mat.ior == 1.5f);
    assert_rgb(&m->mat.transmission, 0.5f * 0.25f, 0.25f * 0.25f, 1 * 0.25f); /* Tf (1 - d) */
    assert_true(m->mat.set & TB_MID_SET_DIFFUSE_TEXTURE);
    assert_non_null(m->diffuse_tex);
    snprintf(path, sizeof path, "%s/m.data/tex.png", w);
    assert_true(files_equal(DATA "/tex.png", path));
    assert_non_null(strstr(m->diffuse_tex, "m.data/tex.png"));

    m = find_mat(s, "clamped");
    assert_rgb(&m->mat.diffuse, 1, 0, 0.5f);     /* from 1.5 -0.25 0.5 */
    assert_rgb(&m->mat.specular, 1, 0.5f, 0);    /* from 2 0.5 0 */
    assert_true(m->mat.exponent == 0);           /* no Ns: Assimp's 0 */
    assert_rgb(&m->mat.emission, 0, 0, 3);       /* from -1 0 3 */
    assert_true(m->mat.ior == 1);                /* Ni 0 refused */
    assert_false(m->mat.set & TB_MID_SET_IOR);
    assert_non_null(strstr(wb.text, "material 'clamped': diffuse"));
    assert_non_null(strstr(wb.text, "material 'clamped': specular"));
    assert_non_null(strstr(wb.text, "material 'clamped': emission"));
    assert_non_null(strstr(wb.text, "material 'clamped': ior"));

    m = find_mat(s, "tr");
    assert_rgb(&m->mat.diffuse, 0.5f, 0.5f, 0.5f);
    assert_rgb(&m->mat.transmission, 0.25f, 0.25f, 0.25f); /* Tr 0.25, Tf absent */
    assert_false(m->mat.set & TB_MID_SET_SPECULAR);
    m = find_mat(s, "ghost"); /* not in the MTL file: Assimp's defaults */
    assert_rgb(&m->mat.diffuse, 0.6f, 0.6f, 0.6f);

    /* Objects resolve to their materials. */
    assert_rgb(&s->obj[0].mat.diffuse, 0.25f, 0.5f, 0.75f);
    assert_rgb(&s->obj[1].mat.diffuse, 1, 0, 0.5f);

    /* Geometry against the OBJ text: polygons kept, positions bit for bit,
     * shared vertices shared again, the degenerate face left out. */
    int skipped = 0;
    for (int g = 0; g < 4; g++) {
        tb_fed *fed = load_fed(s->obj[g].mesh);
        bool used[64] = {0};
        int nused = 0, f = 0;
        for (int k = 0; k < src.nfaces[g]; k++) {
            int ef[8];
            int n = expected_face(&src, src.face_v[g][k], src.face_n[g][k], ef);
            if (n == 0) {
                skipped++;
                continue;
            }
            assert_true((uint32_t)f < fed->nfaces);
            uint32_t l = tb_fed_face_outer(fed, (uint32_t)f);
            assert_int_equal(tb_fed_loop_size(fed, l), n);
            for (int i = 0; i < n; i++) {
                if (!same_bits(fed->positions[tb_fed_loop_vertex(fed, l, (uint32_t)i)], src.v[ef[i]]))
                    fail_msg("group %d face %d corner %d: position differs from the OBJ file", g, k, i);
                if (!used[ef[i]])
                    used[ef[i]] = true, nused++;
            }
            f++;
        }
        assert_int_equal(fed->nfaces, f);
        assert_int_equal(fed->nverts, nused); /* joined back to the file's vertices */
        tb_fed_free(fed);
    }
    assert_int_equal(skipped, 1);
    assert_int_equal(st.skipped_faces, 1);
    assert_non_null(strstr(wb.text, "1 degenerate polygons"));
    free_scene(s);
    rm_tree(w);
}

/* ------------------------------------------------ hand-made glTF scene */

static tb_dvec3 apply(const tb_transform *t, tb_dvec3 p, double w)
{
    const double(*m)[4] = t->m.m;
    return (tb_dvec3){m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z + m[0][3] * w,
                      m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z + m[1][3] * w,
                      m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z + m[2][3] * w};
}

static void assert_vec_near(tb_dvec3 a, double x, double y, double z, double tol)
{
    if (!(fabs(a.x - x) <= tol && fabs(a.y - y) <= tol && fabs(a.z - z) <= tol))
        fail_msg("[%.17g %.17g %.17g], expected [%.17g %.17g %.17g] within %g", a.x, a.y, a.z, x, y, z, tol);
}

static void assert_matrix_near(const tb_transform *t, const double e[12], double tol)
{
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++)
            if (!(fabs(t->m.m[r][c] - e[r * 4 + c]) <= tol))
                fail_msg("world[%d][%d] = %.17g, expected %.17g", r, c, t->m.m[r][c], e[r * 4 + c]);
}

static void test_gltf_scene(void **state)
{
    (void)state;
    char w[MAXP], out[MAXP + 16];
    workdir(w, "gltf");
    snprintf(out, sizeof out, "%s/s.mid", w);
    tb_import_stats st;
    warnbuf wb;
    if (import(DATA "/scene.gltf", out, NULL, &st, &wb))
        fail_msg("%s", tb_last_error());
    print_message("warnings:\n%s", wb.text);
    assert_string_equal(st.format, "glTF2 Importer");
    scene_rec *s = read_scene(out);

    /* Camera: the first one, at its node's world origin, looking down the
     * node's -Z (rotated 90 degrees about Y: world -X), yfov 0.5 rad,
     * aspect 1.5 -> 512 x 341; the orthographic one warned about. */
    assert_true(s->has_cam);
    assert_vec_near(s->cam.eye, 1, 3, 13, 0);
    assert_vec_near(tb_dvec3_normalize(tb_dvec3_sub(s->cam.look_at, s->cam.eye)), -1, 0, 0, 1e-6);
    assert_vec_near(s->cam.up, 0, 1, 0, 1e-6);
    tb_assert_near(s->cam.fov, 0.5 * 180 / PI, 1e-12);
    assert_int_equal(s->cam.width, 512);
    assert_int_equal(s->cam.height, 341);
    assert_non_null(strstr(wb.text, "camera 'cam2'"));

    /* Lights: candela and lux over 683 lm/W; placed by their nodes. */
    assert_int_equal(s->nlight, 3);
    assert_int_equal(st.lights, 3);
    const tb_mid_light *l = &s->light[0].l;
    assert_int_equal(l->kind, TB_LIGHT_POINT);
    assert_rgb(&l->intensity, 2, 1, 0.5f); /* [1 0.5 0.25] x 1366 cd */
    assert_vec_near(apply(&l->to_world, l->position, 1), 1, 7, 3, 0);
    assert_non_null(strstr(wb.text, "light 'bulb': glTF range ignored"));
    l = &s->light[1].l;
    assert_int_equal(l->kind, TB_LIGHT_SPOT);
    assert_rgb(&l->intensity, 1, 1, 1); /* 683 cd */
    tb_assert_near(l->cone_angle, 0.5 * 180 / PI, 1e-12);
    tb_assert_near(l->cone_delta, 0.25 * 180 / PI, 1e-12);
    assert_vec_near(apply(&l->to_world, l->position, 1), 3, 7, 3, 0);
    assert_vec_near(tb_dvec3_normalize(apply(&l->to_world, l->direction, 0)), 0, -1, 0, 1e-6);
    l = &s->light[2].l;
    assert_int_equal(l->kind, TB_LIGHT_DIRECTIONAL);
    assert_rgb(&l->intensity, 1.5f, 1.5f, 1.5f); /* 0.5 x 2049 lux */
    assert_vec_near(tb_dvec3_normalize(apply(&l->to_world, l->direction, 0)), 0, 0, -1, 0);

    /* Materials: metallic-roughness split (docs/import.md). */
    const mat_rec *m = find_mat(s, "dielectric");
    assert_rgb(&m->mat.diffuse, 0.5f, 0.25f, 1);
    assert_rgb(&m->mat.specular, 0.04f, 0.04f, 0.04f);
    assert_true(m->mat.exponent == 30); /* alpha = 0.25: 2 / alpha^2 - 2 */
    assert_true(m->mat.ior == 1.5f);
    m = find_mat(s, "metal");
    assert_rgb(&m->mat.diffuse, 0, 0, 0);
    assert_rgb(&m->mat.specular, 1, 0.5f, 0.25f);
    assert_true(m->mat.exponent == 510); /* alpha = 0.0625 */
    m = find_mat(s, "emitter");
    assert_rgb(&m->mat.diffuse, 1, 1, 1);
    assert_true(m->mat.exponent == 0); /* roughness 1 */
    assert_rgb(&m->mat.emission, (float)PI, (float)(0.5 * PI), (float)(0.25 * PI));

    /* Objects in node order; a mesh placed twice shares its FED file. */
    assert_int_equal(s->nobj, 5);
    assert_int_equal(st.fed_files, 4);
    const char *mats[5] = {"dielectric", "metal", NULL, "emitter", "emitter"};
    for (int i = 0; i < 5; i++) {
        if (mats[i])
            assert_string_equal(s->obj[i].base, mats[i]);
        else {
            assert_null(s->obj[i].base); /* no glTF material: MID's default */
            assert_rgb(&s->obj[i].mat.diffuse, 0.5f, 0.5f, 0.5f);
        }
    }
    assert_string_equal(s->obj[3].mesh, s->obj[4].mesh);
    assert_string_equal(s->obj[3].name, "panel A");

    /* World transforms from the nodes' TRS and matrix, worked out by hand
     * (the quaternion [0 0.6 0 0.8] is a rotation with cos 0.28, sin 0.96). */
    const double body[12] = {0.56, 0, 1.92, 1, 0, 2, 0, 2, -1.92, 0, 0.56, 3};
    const double panel_a[12] = {1, 0, 0, 1, 0, 1, 0, 2, 0, 0, 1, -1};
    const double panel_b[12] = {0.5, 0, 0, 5, 0, 0.5, 0, 2, 0, 0, 0.5, 3};
    for (int i = 0; i < 3; i++)
        assert_matrix_near(&s->obj[i].world, body, 1e-6);
    assert_matrix_near(&s->obj[3].world, panel_a, 0);
    assert_matrix_near(&s->obj[4].world, panel_b, 0);

    /* Positions bit for bit as in scene.bin, in the buffer's vertex order;
     * the triangles as the index buffers give them. */
    size_t nbin;
    char *bin = read_all(DATA "/scene.bin", &nbin);
    assert_non_null(bin);
    /* Byte offsets and sizes of the four position arrays and their indices
     * (make_scene_gltf.py's layout). */
    const struct {
        size_t pos;
        int nv;
        size_t idx;
        int ni;
    } prim[4] = {{0, 4, 48, 6}, {60, 3, 96, 3}, {104, 3, 140, 3}, {148, 3, 0, 0}};
    const int obj_of_prim[4] = {0, 1, 2, 3};
    for (int p = 0; p < 4; p++) {
        tb_fed *fed = load_fed(s->obj[obj_of_prim[p]].mesh);
        assert_int_equal(fed->nverts, prim[p].nv);
        for (int v = 0; v < prim[p].nv; v++) {
            tb_vec3 e;
            memcpy(&e, bin + prim[p].pos + 12 * (size_t)v, 12);
            assert_true(same_bits(fed->positions[v], e));
        }
        int ntri = prim[p].ni ? prim[p].ni / 3 : 1;
        assert_int_equal(fed->nfaces, ntri);
        for (int f = 0; f < ntri; f++) {
            uint32_t l = tb_fed_face_outer(fed, (uint32_t)f);
            assert_int_equal(tb_fed_loop_size(fed, l), 3);
            for (int c = 0; c < 3; c++) {
                uint16_t want = (uint16_t)(f * 3 + c);
                if (prim[p].ni)
                    memcpy(&want, bin + prim[p].idx + 2 * (size_t)(f * 3 + c), 2);
                assert_int_equal(tb_fed_loop_vertex(fed, l, (uint32_t)c), want);
            }
        }
        tb_fed_free(fed);
    }
    free(bin);
    free_scene(s);
    rm_tree(w);
}

/* ------------------------------------------- models of assimp-testmodels */

/* Source positions parsed here, sorted for lookup. */
typedef struct pos_set {
    size_t n, cap;
    tb_vec3 *p;
} pos_set;

static void pos_add(pos_set *s, float x, float y, float z)
{
    if (s->n == s->cap) {
        s->cap = s->cap ? 2 * s->cap : 1024;
        s->p = realloc(s->p, s->cap * sizeof *s->p);
        assert_non_null(s->p);
    }
    s->p[s->n++] = (tb_vec3){x, y, z};
}

static int pos_cmp(const void *a, const void *b) { return memcmp(a, b, sizeof(tb_vec3)); }

static bool pos_has(const pos_set *s, tb_vec3 p)
{
    return bsearch(&p, s->p, s->n, sizeof *s->p, pos_cmp) != NULL;
}

/* Positions of a text format: every line starting with `key` followed by
 * three numbers (OBJ "v", STL "vertex"), or for PLY the first three numbers
 * of each of the `nply` lines after end_header. strtof rounds correctly. */
static void parse_text_positions(const char *path, const char *key, pos_set *s)
{
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char line[4096];
    long ply_left = -1;
    while (fgets(line, sizeof line, f)) {
        char *p = line, *e;
        while (*p == ' ' || *p == '\t')
            p++;
        if (!key) { /* PLY */
            if (!strncmp(p, "element vertex", 14))
                ply_left = strtol(p + 14, NULL, 10);
            if (!strncmp(p, "end_header", 10)) {
                key = "";
                continue;
            }
            if (!key || ply_left-- <= 0)
                continue;
        } else if (*key && (strncmp(p, key, strlen(key)) || (p[strlen(key)] != ' ' && p[strlen(key)] != '\t')))
            continue;
        p += strlen(key);
        float x = strtof(p, &e), y = strtof(e, &e), z = strtof(e, &e);
        pos_add(s, x, y, z);
        if (*key == '\0' && ply_left == 0)
            break;
    }
    fclose(f);
}

/* Positions of a binary STL: 80-byte header, count, 50-byte facets. */
static void parse_stl_binary(const char *path, pos_set *s)
{
    size_t n;
    char *b = read_all(path, &n);
    assert_non_null(b);
    uint32_t count;
    memcpy(&count, b + 80, 4);
    assert_true(84 + 50 * (size_t)count <= n);
    for (uint32_t i = 0; i < count; i++)
        for (int v = 0; v < 3; v++) {
            float x[3];
            memcpy(x, b + 84 + 50 * (size_t)i + 12 + 12 * (size_t)v, 12);
            pos_add(s, x[0], x[1], x[2]);
        }
    free(b);
}

/* Positions of a binary little-endian PLY whose vertices are x y z floats only. */
static void parse_ply_binary(const char *path, pos_set *s)
{
    size_t n;
    char *b = read_all(path, &n);
    assert_non_null(b);
    char *hdr_end = strstr(b, "end_header\n");
    assert_non_null(hdr_end);
    long nv = strtol(strstr(b, "element vertex") + 14, NULL, 10);
    const char *data = hdr_end + 11;
    for (long i = 0; i < nv; i++) {
        float x[3];
        memcpy(x, data + 12 * i, 12);
        pos_add(s, x[0], x[1], x[2]);
    }
    free(b);
}

/* One below or above in float's order. */
static float ulp_step(float x, int d) { return d == 0 ? x : nextafterf(x, d < 0 ? -INFINITY : INFINITY); }

/* Exact (0), within one ulp per component (1), or not found (2). */
static int pos_match(const pos_set *s, tb_vec3 p)
{
    if (pos_has(s, p))
        return 0;
    for (int dx = -1; dx <= 1; dx++)
        for (int dy = -1; dy <= 1; dy++)
            for (int dz = -1; dz <= 1; dz++)
                if (pos_has(s, (tb_vec3){ulp_step(p.x, dx), ulp_step(p.y, dy), ulp_step(p.z, dz)}))
                    return 1;
    return 2;
}

/* Positions of face f of Assimp mesh m with consecutive repeats merged. */
static int ai_face(const struct aiMesh *m, unsigned f, tb_vec3 *out, int cap)
{
    const struct aiFace *face = &m->mFaces[f];
    int k = 0;
    for (unsigned i = 0; i < face->mNumIndices && k < cap; i++) {
        const struct aiVector3D *v = &m->mVertices[face->mIndices[i]];
        tb_vec3 p = {v->x, v->y, v->z};
        if (k == 0 || !(out[k - 1].x == p.x && out[k - 1].y == p.y && out[k - 1].z == p.z))
            out[k++] = p;
    }
    while (k > 1 && out[k - 1].x == out[0].x && out[k - 1].y == out[0].y && out[k - 1].z == out[0].z)
        k--;
    return k;
}

/* True if the corners enclose no area by FED's rule (Newell normal at most
 * 2e-12 times the squared bounding-box diagonal), computed independently. */
static bool degenerate(const tb_vec3 *p, int n)
{
    if (n < 3)
        return true;
    double nx = 0, ny = 0, nz = 0, lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < n; i++) {
        tb_vec3 a = p[i], b = p[(i + 1) % n];
        nx += ((double)a.y - b.y) * ((double)a.z + b.z);
        ny += ((double)a.z - b.z) * ((double)a.x + b.x);
        nz += ((double)a.x - b.x) * ((double)a.y + b.y);
        double c[3] = {a.x, a.y, a.z};
        for (int k = 0; k < 3; k++)
            lo[k] = fmin(lo[k], c[k]), hi[k] = fmax(hi[k], c[k]);
    }
    double d2 = 0;
    for (int k = 0; k < 3; k++)
        d2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    return sqrt(nx * nx + ny * ny + nz * nz) <= 2.0000001e-12 * d2;
}

typedef struct walk {
    const struct aiScene *ai;
    scene_rec *s;
    int next;             /* next MID object to compare */
    uint64_t skipped;     /* Assimp polygons not in the FED files */
    uint64_t points_lines;
    const pos_set *src;   /* source positions, or NULL */
    bool text;            /* src parsed from text: one ulp allowed (Assimp's fast_atof) */
    uint64_t exact, off_by_ulp;
    bool seen[4096];      /* meshes whose FED file was checked */
} walk;

/* Equal bit for bit, or for text formats (re-rounded by the importer)
 * within one ulp per component. */
static bool close_bits(tb_vec3 a, tb_vec3 b, bool text)
{
    if (same_bits(a, b))
        return true;
    if (!text)
        return false;
    const float x[3] = {a.x, a.y, a.z}, y[3] = {b.x, b.y, b.z};
    for (int k = 0; k < 3; k++)
        if (memcmp(&x[k], &y[k], sizeof(float)) != 0 && nextafterf(x[k], -INFINITY) != y[k] &&
            nextafterf(x[k], INFINITY) != y[k])
            return false;
    return true;
}

/* Compares Assimp's mesh m with the FED file written for it (positions bit
 * for bit; for text formats the importer may have moved a coordinate one
 * ulp onto the file's number, which the source check below verifies). */
static void check_mesh(walk *wk, const struct aiMesh *m, const tb_fed *fed)
{
    uint32_t f = 0;
    unsigned cap = 3;
    for (unsigned i = 0; i < m->mNumFaces; i++)
        cap = m->mFaces[i].mNumIndices > cap ? m->mFaces[i].mNumIndices : cap;
    tb_vec3 *want = malloc(cap * sizeof *want);
    assert_non_null(want);
    for (unsigned i = 0; i < m->mNumFaces; i++) {
        if (m->mFaces[i].mNumIndices < 3) {
            wk->points_lines++;
            continue;
        }
        int n = ai_face(m, i, want, (int)cap);
        bool match = f < fed->nfaces && tb_fed_face_nloops(fed, f) == 1 &&
                     tb_fed_loop_size(fed, tb_fed_face_outer(fed, f)) == (uint32_t)n;
        for (int c = 0; match && c < n; c++)
            match = close_bits(fed->positions[tb_fed_loop_vertex(fed, tb_fed_face_outer(fed, f), (uint32_t)c)],
                               want[c], wk->text);
        if (match)
            f++;
        else {
            if (!degenerate(want, n))
                fail_msg("mesh '%s' face %u: not in the FED file, and not degenerate", m->mName.data, i);
            wk->skipped++;
        }
    }
    free(want);
    assert_int_equal(f, fed->nfaces); /* every FED face is an Assimp face, in order */
    if (wk->src)
        for (uint32_t v = 0; v < fed->nverts; v++) {
            int r = pos_match(wk->src, fed->positions[v]);
            if (r == 2 || (r == 1 && !wk->text))
                fail_msg("mesh '%s' vertex %u [%.9g %.9g %.9g]: not a source position%s", m->mName.data, v,
                         fed->positions[v].x, fed->positions[v].y, fed->positions[v].z,
                         r == 1 ? " (one ulp off in a binary file)" : "");
            if (r == 0)
                wk->exact++;
            else
                wk->off_by_ulp++;
        }
}

static void walk_node(walk *wk, const struct aiNode *n, const double parent[16])
{
    double world[16];
    const struct aiMatrix4x4 *t = &n->mTransformation;
    const double local[16] = {t->a1, t->a2, t->a3, t->a4, t->b1, t->b2, t->b3, t->b4,
                              t->c1, t->c2, t->c3, t->c4, t->d1, t->d2, t->d3, t->d4};
    for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++) {
            double s = 0;
            for (int k = 0; k < 4; k++)
                s += parent[r * 4 + k] * local[k * 4 + c];
            world[r * 4 + c] = s;
        }
    for (unsigned i = 0; i < n->mNumMeshes; i++) {
        const struct aiMesh *m = wk->ai->mMeshes[n->mMeshes[i]];
        assert_true(wk->next < wk->s->nobj);
        const obj_rec *o = &wk->s->obj[wk->next++];
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 4; c++)
                if (!(fabs(o->world.m.m[r][c] - world[r * 4 + c]) <= 1e-12 * (1 + fabs(world[r * 4 + c]))))
                    fail_msg("object %d: world[%d][%d] %.17g, the nodes give %.17g", wk->next - 1, r, c,
                             o->world.m.m[r][c], world[r * 4 + c]);
        unsigned idx = n->mMeshes[i];
        if (idx < 4096 && wk->seen[idx])
            continue;
        if (idx < 4096)
            wk->seen[idx] = true;
        tb_fed *fed = load_fed(o->mesh);
        check_mesh(wk, m, fed);
        tb_fed_free(fed);
    }
    for (unsigned i = 0; i < n->mNumChildren; i++)
        walk_node(wk, n->mChildren[i], world);
}

typedef enum { SRC_NONE, SRC_OBJ, SRC_PLY_TEXT, SRC_STL_TEXT, SRC_STL_BINARY, SRC_PLY_BINARY } src_kind;

static void check_model(const char *rel, src_kind kind, bool binary_fed)
{
    char model[MAXP], w[MAXP], out[MAXP + 16];
    snprintf(model, sizeof model, "%s/%s", TB_ASSIMP_MODELS, rel);
    const char *base = strrchr(rel, '/') + 1;
    workdir(w, base);
    snprintf(out, sizeof out, "%s/out.mid", w);
    tb_import_stats st;
    tb_import_opts opts = {.binary_fed = binary_fed};
    warnbuf wb;
    if (import(model, out, &opts, &st, &wb))
        fail_msg("%s: %s", rel, tb_last_error());
    scene_rec *s = read_scene(out);
    assert_int_equal(s->nobj, st.objects);

    /* Assimp's scene read again here, with the same reading options. */
    const struct aiScene *ai = aiImportFile(model, aiProcess_ValidateDataStructure);
    assert_non_null(ai);
    pos_set src = {0};
    switch (kind) {
    case SRC_OBJ: parse_text_positions(model, "v", &src); break;
    case SRC_PLY_TEXT: parse_text_positions(model, NULL, &src); break;
    case SRC_STL_TEXT: parse_text_positions(model, "vertex", &src); break;
    case SRC_STL_BINARY: parse_stl_binary(model, &src); break;
    case SRC_PLY_BINARY: parse_ply_binary(model, &src); break;
    case SRC_NONE: break;
    }
    if (src.n)
        qsort(src.p, src.n, sizeof *src.p, pos_cmp);
    walk *wk = calloc(1, sizeof *wk);
    assert_non_null(wk);
    *wk = (walk){.ai = ai, .s = s, .src = src.n ? &src : NULL,
                 .text = kind == SRC_OBJ || kind == SRC_PLY_TEXT || kind == SRC_STL_TEXT};
    const double id[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    walk_node(wk, ai->mRootNode, id);
    assert_int_equal(wk->next, s->nobj); /* one object per placed mesh, in node order */
    assert_int_equal(wk->skipped + wk->points_lines, st.skipped_faces);
    print_message("%-24s %3d objects, %6llu vertices, %6llu faces, %3llu skipped; positions: %llu exact, "
                  "%llu one ulp from strtof; %llu coordinates corrected, %llu undecided\n",
                  base, s->nobj, (unsigned long long)st.vertices, (unsigned long long)st.faces,
                  (unsigned long long)st.skipped_faces, (unsigned long long)wk->exact,
                  (unsigned long long)wk->off_by_ulp, (unsigned long long)st.rerounded,
                  (unsigned long long)st.undecided);
    if (kind != SRC_NONE)
        assert_true(wk->exact + wk->off_by_ulp == st.vertices);
    /* Text formats: Assimp's one-ulp misroundings are corrected to the file's
     * numbers; only coordinates the importer reported undecided may stay off. */
    assert_true(wk->off_by_ulp <= st.undecided);
    if (!wk->text)
        assert_int_equal(st.rerounded + st.undecided, 0);
    free(wk);
    free(src.p);
    aiReleaseImport(ai);
    free_scene(s);
    rm_tree(w);
}

static void test_models_obj(void **state)
{
    (void)state;
    check_model("OBJ/spider.obj", SRC_OBJ, false);
    check_model("OBJ/concave_polygon.obj", SRC_OBJ, false);
    check_model("OBJ/cube_usemtl.obj", SRC_OBJ, true);
}

static void test_models_ply(void **state)
{
    (void)state;
    check_model("PLY/cube.ply", SRC_PLY_TEXT, false);
    check_model("PLY/cube_binary.ply", SRC_PLY_BINARY, false);
    check_model("PLY/Wuson.ply", SRC_PLY_TEXT, true);
}

static void test_models_stl(void **state)
{
    (void)state;
    check_model("STL/Spider_ascii.stl", SRC_STL_TEXT, false);
    check_model("STL/Spider_binary.stl", SRC_STL_BINARY, true);
    check_model("STL/sphereWithHole.stl", SRC_STL_TEXT, false);
}

static void test_models_gltf(void **state)
{
    (void)state;
    check_model("glTF2/BoxTextured-glTF/BoxTextured.gltf", SRC_NONE, false);
    check_model("glTF2/cameras/Cameras.gltf", SRC_NONE, false);
}

/* Numbers Assimp's parser rounds one ulp off come out as strtof reads them. */
static void test_rounding(void **state)
{
    (void)state;
    char w[MAXP], out[MAXP + 16];
    workdir(w, "round");
    snprintf(out, sizeof out, "%s/r.mid", w);
    obj_src src;
    parse_obj(DATA "/rounding.obj", &src);
    assert_int_equal(src.nv, 4);
    /* The file is a fair test only if Assimp misrounds some of it. */
    const struct aiScene *ai = aiImportFile(DATA "/rounding.obj", aiProcess_ValidateDataStructure);
    assert_non_null(ai);
    int off = 0;
    for (unsigned i = 0; i < ai->mMeshes[0]->mNumVertices; i++) {
        const struct aiVector3D *v = &ai->mMeshes[0]->mVertices[i];
        tb_vec3 p = {v->x, v->y, v->z};
        bool found = false;
        for (int k = 0; k < src.nv; k++)
            found |= same_bits(p, src.v[k]);
        off += !found;
    }
    aiReleaseImport(ai);
    assert_true(off > 0);

    tb_import_stats st;
    if (import(DATA "/rounding.obj", out, NULL, &st, NULL))
        fail_msg("%s", tb_last_error());
    assert_true(st.rerounded > 0);
    assert_int_equal(st.undecided, 0);
    scene_rec *s = read_scene(out);
    tb_fed *fed = load_fed(s->obj[0].mesh);
    assert_int_equal(fed->nverts, 4);
    for (uint32_t v = 0; v < 4; v++)
        assert_true(same_bits(fed->positions[v], src.v[v]));
    tb_fed_free(fed);
    free_scene(s);

    /* --no-join and --triangulate do not change that. */
    tb_import_opts o = {.join = TB_IMPORT_JOIN_NEVER, .triangulate = true};
    if (import(DATA "/rounding.obj", out, &o, &st, NULL))
        fail_msg("%s", tb_last_error());
    s = read_scene(out);
    fed = load_fed(s->obj[0].mesh);
    assert_int_equal(fed->nverts, 6);
    const int corner_v[6] = {0, 1, 2, 1, 2, 3};
    for (uint32_t v = 0; v < 6; v++)
        assert_true(same_bits(fed->positions[v], src.v[corner_v[v]]));
    tb_fed_free(fed);
    free_scene(s);
    rm_tree(w);
}

/* The OBJ importer's vertices are joined back by default, not with --no-join;
 * STL's are left alone unless --join is asked for, which joins corners equal
 * in position and (facet) normal only. */
static void test_join(void **state)
{
    (void)state;
    char w[MAXP], out[MAXP + 16];
    workdir(w, "join");
    snprintf(out, sizeof out, "%s/j.mid", w);
    const struct {
        const char *model;
        tb_import_join join;
        uint64_t nverts;
    } cases[] = {
        {TB_ASSIMP_MODELS "/OBJ/box.obj", TB_IMPORT_JOIN_AUTO, 8},   /* 8 "v" lines */
        {TB_ASSIMP_MODELS "/OBJ/box.obj", TB_IMPORT_JOIN_NEVER, 24}, /* 6 quads */
        {DATA "/facets.stl", TB_IMPORT_JOIN_AUTO, 9},                /* 3 facets */
        {DATA "/facets.stl", TB_IMPORT_JOIN_NEVER, 9},
        {DATA "/facets.stl", TB_IMPORT_JOIN_ALWAYS, 7}, /* the coplanar pair shares 2; the third facet's normal differs */
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        tb_import_opts o = {.join = cases[i].join};
        tb_import_stats st;
        if (import(cases[i].model, out, &o, &st, NULL))
            fail_msg("%s", tb_last_error());
        if (st.vertices != cases[i].nverts)
            fail_msg("%s, join %d: %llu vertices, expected %llu", cases[i].model, (int)cases[i].join,
                     (unsigned long long)st.vertices, (unsigned long long)cases[i].nverts);
    }
    rm_tree(w);
}

/* --triangulate: triangles only; the same positions; --binary-fed: .fedb
 * files holding the same meshes as the text ones. */
static void test_triangulate_binary(void **state)
{
    (void)state;
    char w[MAXP], a[MAXP + 16], b[MAXP + 16];
    workdir(w, "tri");
    snprintf(a, sizeof a, "%s/a.mid", w);
    snprintf(b, sizeof b, "%s/b.mid", w);
    tb_import_stats sa, sb;
    tb_import_opts tri = {.triangulate = true, .binary_fed = true};
    if (import(TB_ASSIMP_MODELS "/PLY/cube.ply", a, NULL, &sa, NULL) ||
        import(TB_ASSIMP_MODELS "/PLY/cube.ply", b, &tri, &sb, NULL))
        fail_msg("%s", tb_last_error());
    assert_int_equal(sa.faces, 6);
    assert_int_equal(sb.faces, 12);
    scene_rec *s = read_scene(b), *t = read_scene(a);
    assert_int_equal(s->nobj, 1);
    assert_non_null(strstr(s->obj[0].mesh, "b.data/mesh-0.fedb"));
    size_t n;
    char *bytes = read_all(s->obj[0].mesh, &n);
    assert_true(n > 8 && memcmp(bytes, TB_FED_BINARY_MAGIC, 8) == 0);
    free(bytes);
    tb_fed *fb = load_fed(s->obj[0].mesh), *fa = load_fed(t->obj[0].mesh);
    for (uint32_t f = 0; f < fb->nfaces; f++)
        assert_int_equal(tb_fed_loop_size(fb, tb_fed_face_outer(fb, f)), 3);
    assert_int_equal(fa->nverts, fb->nverts);
    for (uint32_t v = 0; v < fa->nverts; v++)
        assert_true(same_bits(fa->positions[v], fb->positions[v]));
    tb_fed_free(fa), tb_fed_free(fb);
    free_scene(s), free_scene(t);

    /* Binary and text files of one import hold equal meshes. */
    tb_import_opts bin = {.binary_fed = true};
    if (import(DATA "/materials.obj", a, NULL, &sa, NULL) || import(DATA "/materials.obj", b, &bin, &sb, NULL))
        fail_msg("%s", tb_last_error());
    s = read_scene(b), t = read_scene(a);
    assert_int_equal(s->nobj, t->nobj);
    for (int i = 0; i < s->nobj; i++) {
        fa = load_fed(t->obj[i].mesh), fb = load_fed(s->obj[i].mesh);
        assert_true(tb_fed_equal(fa, fb));
        tb_fed_free(fa), tb_fed_free(fb);
    }
    free_scene(s), free_scene(t);
    rm_tree(w);
}

/* ------------------------------------------------------------- failures */

/* A glTF file whose first node holds a good triangle and whose second
 * starts a chain of `depth` nested nodes ending in the same mesh: the import
 * fails after the first FED file was written. */
static void write_deep_gltf(const char *path, int depth)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0,1]}],\"nodes\":[{\"mesh\":0}");
    for (int i = 0; i < depth; i++)
        fprintf(f, ",{\"children\":[%d]}", i + 2);
    fprintf(f, ",{\"mesh\":0}],\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
               "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\","
               "\"min\":[0,0,0],\"max\":[1,1,0]}],\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
               "\"buffers\":[{\"byteLength\":36,\"uri\":\"data:application/octet-stream;base64,"
               "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA\"}]}\n");
    assert_int_equal(fclose(f), 0);
}

/* Runs a failing import into folder `dir` and checks that it is left as it was. */
static void expect_fail(const char *model, const char *dir, const char *out, tb_status want, const char *msg)
{
    char before[4096], after[4096];
    list_dir(dir, before, sizeof before);
    tb_status st = import(model, out, NULL, NULL, NULL);
    if (st == TB_OK)
        fail_msg("importing %s succeeded", model);
    print_message("%s -> %s\n", model, tb_last_error());
    if (want)
        assert_int_equal(st, want);
    if (msg && !strstr(tb_last_error(), msg))
        fail_msg("message '%s' does not contain '%s'", tb_last_error(), msg);
    list_dir(dir, after, sizeof after);
    assert_string_equal(before, after);
}

static void test_failures(void **state)
{
    (void)state;
    char w[MAXP], in[MAXP + 8], out[MAXP + 8], path[MAXP + 64], mid[MAXP + 64];
    workdir(w, "fail");
    snprintf(in, sizeof in, "%s/in", w);
    snprintf(out, sizeof out, "%s/out", w);
    assert_int_equal(mkdir(in, 0777), 0);
    assert_int_equal(mkdir(out, 0777), 0);
    snprintf(mid, sizeof mid, "%s/x.mid", out);

    /* The model: missing, a folder, not a model, broken JSON, no polygons. */
    snprintf(path, sizeof path, "%s/missing.obj", in);
    expect_fail(path, out, mid, TB_ERR_NOT_FOUND, "missing.obj: No such file");
    expect_fail(in, out, mid, TB_ERR_IO, "not a regular file");
    snprintf(path, sizeof path, "%s/noise.xyz", in);
    write_text(path, "\x01\x02 this is no model\n");
    expect_fail(path, out, mid, TB_ERR_FORMAT, "Assimp cannot read it");
    snprintf(path, sizeof path, "%s/broken.gltf", in);
    write_text(path, "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [");
    expect_fail(path, out, mid, TB_ERR_FORMAT, "broken.gltf");
    snprintf(path, sizeof path, "%s/points.obj", in);
    write_text(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\np 1 2 3\nl 1 2\n");
    expect_fail(path, out, mid, 0, "points.obj");

    /* A failure after FED files were written removes them too. */
    snprintf(path, sizeof path, "%s/deep.gltf", in);
    write_deep_gltf(path, 300);
    expect_fail(path, out, mid, TB_ERR_UNSUPPORTED, "deeper than");
    write_deep_gltf(path, 3); /* the same file, shallow: imports */
    tb_import_stats st;
    if (import(path, mid, NULL, &st, NULL))
        fail_msg("%s", tb_last_error());
    assert_int_equal(st.objects, 2);
    assert_int_equal(st.fed_files, 1);

    /* An existing output survives a failed import untouched, and a good
     * import replaces all of it. */
    char data[MAXP + 64], marker[MAXP + 96];
    snprintf(data, sizeof data, "%s/x.data", out);
    snprintf(marker, sizeof marker, "%s/marker", data);
    write_text(marker, "old\n");
    write_text(mid, "old\n");
    write_deep_gltf(path, 300);
    expect_fail(path, out, mid, TB_ERR_UNSUPPORTED, NULL);
    size_t n;
    char *text = read_all(mid, &n);
    assert_string_equal(text, "old\n");
    free(text);
    assert_int_equal(access(marker, F_OK), 0);
    if (import(TB_ASSIMP_MODELS "/OBJ/box.obj", mid, NULL, NULL, NULL))
        fail_msg("%s", tb_last_error());
    assert_int_equal(access(marker, F_OK), -1);
    scene_rec *s = read_scene(mid);
    assert_int_equal(s->nobj, 1);
    free_scene(s);
    char listing[4096];
    list_dir(out, listing, sizeof listing);
    assert_string_equal(listing, "x.data|x.mid|");

    /* The data folder's name taken by a file: refused at the end, nothing
     * written, the file kept. */
    snprintf(mid, sizeof mid, "%s/f.mid", out);
    snprintf(data, sizeof data, "%s/f.data", out);
    write_text(data, "mine\n");
    expect_fail(DATA "/materials.obj", out, mid, TB_ERR_IO, "not a folder");
    text = read_all(data, &n);
    assert_string_equal(text, "mine\n");
    free(text);

    /* The output's folder does not exist. */
    snprintf(mid, sizeof mid, "%s/nowhere/x.mid", out);
    expect_fail(DATA "/materials.obj", out, mid, TB_ERR_IO, "nowhere");
    rm_tree(w);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_obj_materials),
        cmocka_unit_test(test_gltf_scene),
        cmocka_unit_test(test_models_obj),
        cmocka_unit_test(test_models_ply),
        cmocka_unit_test(test_models_stl),
        cmocka_unit_test(test_models_gltf),
        cmocka_unit_test(test_rounding),
        cmocka_unit_test(test_join),
        cmocka_unit_test(test_triangulate_binary),
        cmocka_unit_test(test_failures),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
