/* The bundled scenes say what they claim, checked through the MID reader
 * against the published data and independent computations:
 *
 * - cornell-box.mid: every surface's vertices equal the published quads (the
 *   numbers are typed here from the Cornell data, not from the scene), the
 *   light is 0.1 mm below the ceiling, every wall faces into the box and every
 *   block face out of its block, the red wall is 3.2 mm off planar, the camera
 *   has the published fov 2 atan(12.5/35), the reflectance spectra equal the
 *   measured CSV, the emission is pi times the published radiance;
 * - cornell-box-rgb.mid: same geometry; its RGB values equal util/color's
 *   conversion of the spectra (the file was written by an independent Python
 *   computation, scenes/tools/cornell_box.py);
 * - tests/cornell-box-coplanar-light.mid: the same scene with the light
 *   exactly in the ceiling's plane;
 * - cornell-box-spheres.mid: the same walls, light, camera and materials,
 *   a mirror sphere (left, back) and a glass sphere (right, front) instead of
 *   the blocks, resting 0.1 mm above the floor inside the box;
 * - showcase.mid: every primitive kind, CSG node and light kind occurs; every
 *   object stands on the ground and lies inside the camera's view;
 * - radiosity-room.mid: diffuse only, walls face in, furniture inside the room
 *   and not overlapping, the light just below the ceiling. */
#include "tb_test.h"

#include <string.h>

#include "host/mid/mid_reader.h"
#include "util/color/cie.h"
#include "util/color/srgb.h"
#include "util/math/float.h"
#include "util/math/transform.h"

#define SCENES TB_SOURCE_DIR "/scenes"

/* ------------------------------------------------------- published data */

/* The Cornell Box data, typed from the published tables (mm). */
typedef struct published_quad {
    const char *name;     /* object name in the scene */
    const char *material; /* material it names */
    double v[4][3];
} published_quad;

static const published_quad tb__surfaces[] = {
    {"floor", "white", {{552.8, 0, 0}, {0, 0, 0}, {0, 0, 559.2}, {549.6, 0, 559.2}}},
    {"light", "light", {{343, 548.8, 227}, {343, 548.8, 332}, {213, 548.8, 332}, {213, 548.8, 227}}},
    {"ceiling", "white", {{556, 548.8, 0}, {556, 548.8, 559.2}, {0, 548.8, 559.2}, {0, 548.8, 0}}},
    {"back wall", "white", {{549.6, 0, 559.2}, {0, 0, 559.2}, {0, 548.8, 559.2}, {556, 548.8, 559.2}}},
    {"right wall", "green", {{0, 0, 559.2}, {0, 0, 0}, {0, 548.8, 0}, {0, 548.8, 559.2}}},
    {"left wall", "red", {{552.8, 0, 0}, {549.6, 0, 559.2}, {556, 548.8, 559.2}, {556, 548.8, 0}}},
};

static const struct {
    const char *name;
    double f[5][4][3]; /* top, then four sides */
} tb__blocks[2] = {
    {"short block",
     {{{130, 165, 65}, {82, 165, 225}, {240, 165, 272}, {290, 165, 114}},
      {{290, 0, 114}, {290, 165, 114}, {240, 165, 272}, {240, 0, 272}},
      {{130, 0, 65}, {130, 165, 65}, {290, 165, 114}, {290, 0, 114}},
      {{82, 0, 225}, {82, 165, 225}, {130, 165, 65}, {130, 0, 65}},
      {{240, 0, 272}, {240, 165, 272}, {82, 165, 225}, {82, 0, 225}}}},
    {"tall block",
     {{{423, 330, 247}, {265, 330, 296}, {314, 330, 456}, {472, 330, 406}},
      {{423, 0, 247}, {423, 330, 247}, {472, 330, 406}, {472, 0, 406}},
      {{472, 0, 406}, {472, 330, 406}, {314, 330, 456}, {314, 0, 456}},
      {{314, 0, 456}, {314, 330, 456}, {265, 330, 296}, {265, 0, 296}},
      {{265, 0, 296}, {265, 330, 296}, {423, 330, 247}, {423, 0, 247}}}},
};

/* Published relative spectral radiance of the light. */
static const double tb__light_nm[4] = {400, 500, 600, 700};
static const double tb__light_l[4] = {0, 8, 15.6, 18.4};

/* ------------------------------------------------------------ a scene copy */

/* What the tests keep of one top-level object (items die on the next read). */
typedef struct kept {
    char name[64];
    tb_prim_kind kind;
    char material[64];      /* base material name, or "" */
    int nv, nf;
    tb_vec3 v[32];          /* polygons: vertices (the Cornell objects have <= 8) */
    int start[16], idx[64]; /* polygons: faces */
    tb_dvec3 lo, hi;        /* world box (CSG rules as testbed check) */
} kept;

typedef struct scene {
    kept obj[64];
    int n;
    int kinds[TB_PRIM_COUNT]; /* nodes of each kind, CSG children included */
    int lights[3];
    bool all_diffuse;         /* no object or material has specular or transmission */
    bool nested_csg;          /* some CSG node has a CSG child */
    tb_mid_camera cam;
    bool has_cam;
    tb_mid_reader *r;         /* open until scene_close, for the named materials */
} scene;

static tb_dvec3 dmin(tb_dvec3 a, tb_dvec3 b) { return (tb_dvec3){fmin(a.x, b.x), fmin(a.y, b.y), fmin(a.z, b.z)}; }
static tb_dvec3 dmax(tb_dvec3 a, tb_dvec3 b) { return (tb_dvec3){fmax(a.x, b.x), fmax(a.y, b.y), fmax(a.z, b.z)}; }

/* The canonical object-space box of a primitive (docs/mid.md, 6.3). */
static void local_box(const tb_mid_object *o, tb_dvec3 *lo, tb_dvec3 *hi)
{
    const tb_mid_geometry *g = &o->geom;
    double r = 1.0, z0 = -1.0, z1 = 1.0;
    switch (o->kind) {
    case TB_PRIM_CONE: r = fmax(1.0, g->cone.top_radius); break;
    case TB_PRIM_PYRAMID: r = fmax(1.0, g->pyramid.top); break;
    case TB_PRIM_TORUS: r = g->torus.major + g->torus.minor, z0 = -g->torus.minor, z1 = g->torus.minor; break;
    case TB_PRIM_CONIC: {
        double m = 0.0, zs[3] = {g->conic.z0, g->conic.z1, 0.0};
        int n = 2;
        if (g->conic.c[2] != 0.0) {
            double zv = -g->conic.c[1] / (2.0 * g->conic.c[2]);
            if (zv > g->conic.z0 && zv < g->conic.z1)
                zs[n++] = zv;
        }
        for (int i = 0; i < n; i++)
            m = fmax(m, g->conic.c[0] + g->conic.c[1] * zs[i] + g->conic.c[2] * zs[i] * zs[i]);
        r = sqrt(m), z0 = g->conic.z0, z1 = g->conic.z1;
        break;
    }
    case TB_PRIM_PRISM:
        if (g->prism.nprofile) {
            *lo = (tb_dvec3){INFINITY, INFINITY, -1};
            *hi = (tb_dvec3){-INFINITY, -INFINITY, 1};
            for (int i = 0; i < g->prism.nprofile; i++) {
                lo->x = fmin(lo->x, g->prism.profile[i].x), hi->x = fmax(hi->x, g->prism.profile[i].x);
                lo->y = fmin(lo->y, g->prism.profile[i].y), hi->y = fmax(hi->y, g->prism.profile[i].y);
            }
            return;
        }
        break;
    case TB_PRIM_POLYGONS:
        *lo = (tb_dvec3){INFINITY, INFINITY, INFINITY};
        *hi = (tb_dvec3){-INFINITY, -INFINITY, -INFINITY};
        for (int i = 0; i < g->polygons.nvertices; i++) {
            tb_vec3 p = g->polygons.vertices[i];
            *lo = dmin(*lo, (tb_dvec3){p.x, p.y, p.z});
            *hi = dmax(*hi, (tb_dvec3){p.x, p.y, p.z});
        }
        return;
    default: break;
    }
    *lo = (tb_dvec3){-r, -r, z0};
    *hi = (tb_dvec3){r, r, z1};
}

/* World box of an object tree: a difference lies in its first child, an
 * intersection in every child, a union in all together. */
static void world_box(const tb_mid_object *o, tb_dvec3 *lo, tb_dvec3 *hi)
{
    if (!tb_prim_is_csg(o->kind)) {
        tb_dvec3 a, b;
        local_box(o, &a, &b);
        *lo = (tb_dvec3){INFINITY, INFINITY, INFINITY};
        *hi = (tb_dvec3){-INFINITY, -INFINITY, -INFINITY};
        for (int c = 0; c < 8; c++) {
            tb_dvec3 p = {c & 1 ? b.x : a.x, c & 2 ? b.y : a.y, c & 4 ? b.z : a.z};
            p = tb_transform_dpoint(&o->to_world, p);
            *lo = dmin(*lo, p);
            *hi = dmax(*hi, p);
        }
        return;
    }
    world_box(&o->children[0], lo, hi);
    if (o->kind == TB_PRIM_DIFFERENCE)
        return;
    for (int i = 1; i < o->nchildren; i++) {
        tb_dvec3 a, b;
        world_box(&o->children[i], &a, &b);
        if (o->kind == TB_PRIM_UNION)
            *lo = dmin(*lo, a), *hi = dmax(*hi, b);
        else
            *lo = dmax(*lo, a), *hi = dmin(*hi, b);
    }
}

static bool is_black(const tb_mid_color *c)
{
    return c->type == TB_MID_COLOR_RGB && c->rgb[0] == 0.0f && c->rgb[1] == 0.0f && c->rgb[2] == 0.0f;
}

static void count_nodes(scene *s, const tb_mid_object *o)
{
    s->kinds[o->kind]++;
    if (!is_black(&o->material.specular) || !is_black(&o->material.transmission))
        s->all_diffuse = false;
    for (int i = 0; i < o->nchildren; i++) {
        if (tb_prim_is_csg(o->children[i].kind))
            s->nested_csg = true;
        count_nodes(s, &o->children[i]);
    }
}

static void keep(scene *s, const tb_mid_object *o)
{
    assert_true(s->n < 64);
    kept *k = &s->obj[s->n++];
    memset(k, 0, sizeof *k);
    snprintf(k->name, sizeof k->name, "%s", o->name ? o->name : "");
    snprintf(k->material, sizeof k->material, "%s", o->material.base ? o->material.base : "");
    k->kind = o->kind;
    world_box(o, &k->lo, &k->hi);
    if (o->kind == TB_PRIM_POLYGONS && o->geom.polygons.nvertices <= 32 && o->geom.polygons.nfaces < 16 &&
        o->geom.polygons.face_start[o->geom.polygons.nfaces] <= 64) {
        const tb_geom_polygons *p = &o->geom.polygons;
        k->nv = p->nvertices;
        k->nf = p->nfaces;
        memcpy(k->v, p->vertices, (size_t)p->nvertices * sizeof *p->vertices);
        memcpy(k->start, p->face_start, (size_t)(p->nfaces + 1) * sizeof *p->face_start);
        memcpy(k->idx, p->indices, (size_t)p->face_start[p->nfaces] * sizeof *p->indices);
    }
    count_nodes(s, o);
}

static scene *scene_read(const char *path)
{
    scene *s = calloc(1, sizeof *s);
    assert_non_null(s);
    s->all_diffuse = true;
    if (tb_mid_reader_open(&s->r, path))
        fail_msg("%s", tb_last_error());
    tb_mid_item it;
    tb_status st;
    while (!(st = tb_mid_reader_next(s->r, &it)) && it.type != TB_MID_ITEM_END) {
        if (it.type == TB_MID_ITEM_OBJECT)
            keep(s, it.object);
        else if (it.type == TB_MID_ITEM_LIGHT)
            s->lights[it.light->kind]++;
        else if (it.type == TB_MID_ITEM_CAMERA) {
            s->cam = *it.camera;
            s->has_cam = true;
        } else if (it.type == TB_MID_ITEM_MATERIAL) {
            if (!is_black(&it.material->specular) || !is_black(&it.material->transmission))
                s->all_diffuse = false;
        }
    }
    if (st)
        fail_msg("%s", tb_last_error());
    return s;
}

static void scene_close(scene *s)
{
    tb_mid_reader_close(s->r);
    free(s);
}

static const kept *find(const scene *s, const char *name)
{
    for (int i = 0; i < s->n; i++)
        if (strcmp(s->obj[i].name, name) == 0)
            return &s->obj[i];
    fail_msg("no object named '%s'", name);
    return NULL;
}

/* Vertex j of face f. */
static tb_dvec3 vert(const kept *k, int f, int j)
{
    tb_vec3 p = k->v[k->idx[k->start[f] + j]];
    return (tb_dvec3){p.x, p.y, p.z};
}

/* Newell's normal of face f: the right-hand-rule normal of a counter-clockwise loop. */
static tb_dvec3 newell(const kept *k, int f, tb_dvec3 *centroid)
{
    int n = k->start[f + 1] - k->start[f];
    tb_dvec3 nr = {0, 0, 0}, c = {0, 0, 0};
    for (int i = 0; i < n; i++) {
        tb_dvec3 a = vert(k, f, i), b = vert(k, f, (i + 1) % n);
        nr.x += (a.y - b.y) * (a.z + b.z);
        nr.y += (a.z - b.z) * (a.x + b.x);
        nr.z += (a.x - b.x) * (a.y + b.y);
        c.x += a.x / n, c.y += a.y / n, c.z += a.z / n;
    }
    *centroid = c;
    return nr;
}

static double dot3(tb_dvec3 a, tb_dvec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static tb_dvec3 sub3(tb_dvec3 a, tb_dvec3 b) { return (tb_dvec3){a.x - b.x, a.y - b.y, a.z - b.z}; }

/* -------------------------------------------------------------- Cornell */

/* Checks the geometry of a Cornell scene; the light is at height light_y;
 * the published blocks unless `blocks` is false (the spheres variant). */
static void check_cornell_geometry(const scene *s, double light_y, bool blocks)
{
    assert_int_equal(s->n, 8);
    for (size_t q = 0; q < sizeof tb__surfaces / sizeof tb__surfaces[0]; q++) {
        const published_quad *pq = &tb__surfaces[q];
        const kept *k = find(s, pq->name);
        assert_int_equal(k->kind, TB_PRIM_POLYGONS);
        assert_string_equal(k->material, pq->material);
        assert_int_equal(k->nf, 1);
        assert_int_equal(k->start[1], 4);
        for (int j = 0; j < 4; j++) {
            tb_dvec3 p = vert(k, 0, j);
            double y = strcmp(pq->name, "light") == 0 ? light_y : pq->v[j][1];
            assert_true(p.x == (float)pq->v[j][0] && p.y == (float)y && p.z == (float)pq->v[j][2]);
        }
    }
    for (int b = 0; b < 2 && blocks; b++) {
        const kept *k = find(s, tb__blocks[b].name);
        assert_int_equal(k->kind, TB_PRIM_POLYGONS);
        assert_string_equal(k->material, "white");
        assert_int_equal(k->nf, 5);
        assert_int_equal(k->nv, 8); /* corners shared between faces */
        for (int f = 0; f < 5; f++) {
            assert_int_equal(k->start[f + 1] - k->start[f], 4);
            for (int j = 0; j < 4; j++) {
                tb_dvec3 p = vert(k, f, j);
                const double *e = tb__blocks[b].f[f][j];
                assert_true(p.x == (float)e[0] && p.y == (float)e[1] && p.z == (float)e[2]);
            }
        }
    }
}

static void test_cornell_geometry_as_published(void **state)
{
    (void)state;
    scene *s = scene_read(SCENES "/cornell-box.mid");
    check_cornell_geometry(s, 548.7, true);
    /* The lowering is 0.1 mm (as floats: the nearest float to each). */
    tb_assert_near(find(s, "ceiling")->v[0].y - find(s, "light")->v[0].y, 0.1, 1e-4);
    scene_close(s);
}

static void test_cornell_faces_point_the_right_way(void **state)
{
    (void)state;
    scene *s = scene_read(SCENES "/cornell-box.mid");
    const tb_dvec3 inside = {278, 274.4, 279.6};
    for (size_t q = 0; q < sizeof tb__surfaces / sizeof tb__surfaces[0]; q++) {
        const kept *k = find(s, tb__surfaces[q].name);
        tb_dvec3 c, n = newell(k, 0, &c);
        if (!(dot3(n, sub3(inside, c)) > 0.0))
            fail_msg("'%s' faces away from the inside of the box", k->name);
    }
    for (int b = 0; b < 2; b++) {
        const kept *k = find(s, tb__blocks[b].name);
        tb_dvec3 mid = {0, 0, 0};
        for (int i = 0; i < k->nv; i++)
            mid.x += k->v[i].x / k->nv, mid.y += k->v[i].y / k->nv, mid.z += k->v[i].z / k->nv;
        for (int f = 0; f < k->nf; f++) {
            tb_dvec3 c, n = newell(k, f, &c);
            if (!(dot3(n, sub3(c, mid)) > 0.0))
                fail_msg("'%s' face %d points into its block", k->name, f);
        }
    }
    scene_close(s);
}

static void test_cornell_red_wall_is_not_planar(void **state)
{
    (void)state;
    scene *s = scene_read(SCENES "/cornell-box.mid");
    const kept *k = find(s, "left wall");
    tb_dvec3 a = vert(k, 0, 0), b = vert(k, 0, 1), c = vert(k, 0, 2), d = vert(k, 0, 3);
    tb_dvec3 u = sub3(b, a), v = sub3(c, a);
    tb_dvec3 n = {u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
    double off = fabs(dot3(n, sub3(d, a))) / sqrt(dot3(n, n));
    print_message("[ measured ] red wall: 4th vertex %.4f mm off the plane of the first three\n", off);
    /* The data say "about 3.2 mm"; the exact value from the published numbers is 3.1997. */
    tb_assert_near(off, 3.2, 0.01);
    scene_close(s);
}

static void test_cornell_camera(void **state)
{
    (void)state;
    scene *s = scene_read(SCENES "/cornell-box.mid");
    assert_true(s->has_cam);
    const tb_mid_camera *c = &s->cam;
    double fov = 2.0 * atan(12.5 / 35.0) * 180.0 / TB_PI;
    tb_assert_near(c->fov, fov, 1e-12);
    tb_assert_near(c->fov, 39.3076481, 5e-8); /* the published value */
    assert_true(c->eye.x == 278 && c->eye.y == 273 && c->eye.z == -800);
    tb_dvec3 dir = sub3(c->look_at, c->eye);
    assert_true(dir.x == 0 && dir.y == 0 && dir.z > 0);
    assert_true(c->up.x == 0 && c->up.y > 0 && c->up.z == 0);
    assert_true(c->focal_length == 35 && c->film[0] == 25 && c->film[1] == 25);
    assert_int_equal(c->width, 512);
    assert_int_equal(c->height, 512);
    scene_close(s);
}

/* The measured reflectances: lambda and the white, green, red columns. */
typedef struct refl {
    int n;
    double nm[128], v[3][128];
} refl;

static void read_reflectances(refl *r)
{
    FILE *f = fopen(SCENES "/data/cornell-box-reflectance.csv", "r");
    assert_non_null(f);
    char line[256];
    r->n = 0;
    bool header = false;
    while (fgets(line, sizeof line, f)) {
        if (line[0] == '#' || line[0] == '\n')
            continue;
        if (!header) {
            assert_string_equal(line, "lambda_nm,white,green,red\n");
            header = true;
            continue;
        }
        assert_true(r->n < 128);
        int got = sscanf(line, "%lf,%lf,%lf,%lf", &r->nm[r->n], &r->v[0][r->n], &r->v[1][r->n], &r->v[2][r->n]);
        assert_int_equal(got, 4);
        r->n++;
    }
    fclose(f);
    assert_int_equal(r->n, 76); /* 400-700 nm at 4 nm */
}

static const char *const tb__walls[3] = {"white", "green", "red"};

static void test_cornell_spectra_as_measured(void **state)
{
    (void)state;
    refl r;
    read_reflectances(&r);
    scene *s = scene_read(SCENES "/cornell-box.mid");
    for (int w = 0; w < 3; w++) {
        const tb_mid_material *m = tb_mid_reader_material(s->r, tb__walls[w]);
        assert_non_null(m);
        assert_int_equal(m->diffuse.type, TB_MID_COLOR_SPECTRUM);
        assert_int_equal(m->diffuse.nsamples, r.n);
        for (int i = 0; i < r.n; i++) {
            assert_true(m->diffuse.nm[i] == (float)r.nm[i]);
            assert_true(m->diffuse.values[i] == (float)r.v[w][i]);
        }
        assert_true(is_black(&m->specular) && is_black(&m->transmission) && is_black(&m->emission));
    }
    const tb_mid_material *m = tb_mid_reader_material(s->r, "light");
    assert_non_null(m);
    assert_int_equal(m->emission.type, TB_MID_COLOR_SPECTRUM);
    assert_int_equal(m->emission.nsamples, 4);
    for (int i = 0; i < 4; i++) {
        assert_true(m->emission.nm[i] == (float)tb__light_nm[i]);
        /* Exitance M = pi L, written to 7 digits. */
        tb_assert_near(m->emission.values[i], TB_PI * tb__light_l[i], 1e-6 * TB_PI * tb__light_l[i]);
    }
    scene_close(s);
}

static void spectrum_of(const tb_mid_color *c, tb_spectrum *out)
{
    double nm[128], v[128];
    assert_int_equal(c->type, TB_MID_COLOR_SPECTRUM);
    assert_true(c->nsamples <= 128);
    for (int i = 0; i < c->nsamples; i++)
        nm[i] = c->nm[i], v[i] = c->values[i];
    assert_int_equal(tb_spectrum_init(out, c->nsamples, nm, v), TB_OK);
}

static void test_cornell_rgb_matches_util_color(void **state)
{
    (void)state;
    scene *spec = scene_read(SCENES "/cornell-box.mid");
    scene *rgb = scene_read(SCENES "/cornell-box-rgb.mid");
    /* Same geometry and camera. */
    check_cornell_geometry(rgb, 548.7, true);
    assert_true(rgb->has_cam);
    assert_true(rgb->cam.fov == spec->cam.fov);
    for (int w = 0; w < 4; w++) {
        const char *name = w < 3 ? tb__walls[w] : "light";
        const tb_mid_material *ms = tb_mid_reader_material(spec->r, name);
        const tb_mid_material *mr = tb_mid_reader_material(rgb->r, name);
        assert_non_null(ms);
        assert_non_null(mr);
        tb_spectrum sp;
        double xyz[3], want[3];
        const tb_mid_color *got;
        if (w < 3) {
            spectrum_of(&ms->diffuse, &sp);
            assert_int_equal(tb_reflectance_to_xyz(&sp, tb_illuminant_d65(), 1.0, xyz), TB_OK);
            got = &mr->diffuse;
        } else {
            spectrum_of(&ms->emission, &sp);
            assert_int_equal(tb_emission_to_xyz(&sp, TB_EMISSION_RADIOMETRIC, xyz), TB_OK);
            got = &mr->emission;
            assert_true(mr->diffuse.rgb[0] == ms->diffuse.rgb[0]);
        }
        tb_xyz_to_linear_srgb(xyz, want);
        tb_spectrum_release(&sp);
        assert_int_equal(got->type, TB_MID_COLOR_RGB);
        print_message("[ measured ] %-5s file (%.7g %.7g %.7g), util/color (%.7g %.7g %.7g)\n", name,
                      (double)got->rgb[0], (double)got->rgb[1], (double)got->rgb[2], want[0], want[1], want[2]);
        for (int c = 0; c < 3; c++)
            tb_assert_near(got->rgb[c], want[c], 1e-6 * fmax(1.0, fabs(want[c])));
    }
    scene_close(spec);
    scene_close(rgb);
}

static void test_cornell_coplanar_variant(void **state)
{
    (void)state;
    scene *s = scene_read(SCENES "/tests/cornell-box-coplanar-light.mid");
    check_cornell_geometry(s, 548.8, true);
    assert_true(find(s, "light")->v[0].y == find(s, "ceiling")->v[0].y);
    scene_close(s);
}

static bool is_grey(const tb_mid_color *c, float v)
{
    return c->type == TB_MID_COLOR_RGB && c->rgb[0] == v && c->rgb[1] == v && c->rgb[2] == v;
}

static void test_cornell_spheres_variant(void **state)
{
    (void)state;
    scene *s = scene_read(SCENES "/cornell-box-spheres.mid");
    scene *box = scene_read(SCENES "/cornell-box.mid");
    check_cornell_geometry(s, 548.7, false);
    /* The published camera and the measured materials, exactly as cornell-box.mid has them. */
    assert_true(s->has_cam && box->has_cam);
    tb_mid_item ca = {.type = TB_MID_ITEM_CAMERA, .camera = &s->cam};
    tb_mid_item cb = {.type = TB_MID_ITEM_CAMERA, .camera = &box->cam};
    assert_true(tb_mid_item_equal(&ca, &cb));
    static const char *const mats[] = {"white", "green", "red", "light"};
    for (int i = 0; i < 4; i++) {
        tb_mid_item ma = {.type = TB_MID_ITEM_MATERIAL, .material = tb_mid_reader_material(s->r, mats[i])};
        tb_mid_item mb = {.type = TB_MID_ITEM_MATERIAL, .material = tb_mid_reader_material(box->r, mats[i])};
        assert_non_null(ma.material);
        assert_non_null(mb.material);
        if (!tb_mid_item_equal(&ma, &mb))
            fail_msg("material '%s' differs from cornell-box.mid's", mats[i]);
    }
    /* Two spheres of radius 95 mm (similarity transforms: the world box is the sphere's).
     * The mirror at the left back (the image's left is world +x), the glass at the right front. */
    const kept *m = find(s, "mirror sphere"), *g = find(s, "glass sphere");
    const kept *sp[2] = {m, g};
    tb_dvec3 c[2];
    for (int i = 0; i < 2; i++) {
        assert_int_equal(sp[i]->kind, TB_PRIM_SPHERE);
        c[i] = (tb_dvec3){(sp[i]->lo.x + sp[i]->hi.x) / 2, (sp[i]->lo.y + sp[i]->hi.y) / 2,
                          (sp[i]->lo.z + sp[i]->hi.z) / 2};
        tb_assert_near(sp[i]->hi.x - sp[i]->lo.x, 190.0, 1e-9);
        tb_assert_near(sp[i]->hi.y - sp[i]->lo.y, 190.0, 1e-9);
        tb_assert_near(sp[i]->hi.z - sp[i]->lo.z, 190.0, 1e-9);
        /* resting 0.1 mm above the floor (y = 0), inside the walls (x in [0, 549.6], z <= 559.2) */
        tb_assert_near(sp[i]->lo.y, 0.1, 1e-9);
        assert_true(sp[i]->lo.x > 0.0 && sp[i]->hi.x < 549.6 && sp[i]->lo.z > 0.0 && sp[i]->hi.z < 559.2);
    }
    assert_true(c[0].x > 278.0 && c[0].z > 279.6);
    assert_true(c[1].x < 278.0 && c[1].z < 279.6);
    tb_dvec3 d = sub3(c[0], c[1]);
    assert_true(sqrt(dot3(d, d)) > 190.0);
    assert_string_equal(m->material, "mirror");
    assert_string_equal(g->material, "glass");
    const tb_mid_material *mm = tb_mid_reader_material(s->r, "mirror");
    const tb_mid_material *gm = tb_mid_reader_material(s->r, "glass");
    assert_non_null(mm);
    assert_non_null(gm);
    /* the mirror reflects, nothing diffuse or transmitted */
    assert_true(is_black(&mm->diffuse) && is_black(&mm->transmission) && is_black(&mm->emission));
    assert_true(is_grey(&mm->specular, 0.95f) && mm->exponent == 10000.0f);
    /* the glass: a dielectric of index 1.5, transmission 1, a little specular */
    assert_true(is_black(&gm->diffuse) && is_black(&gm->emission));
    assert_true(is_grey(&gm->transmission, 1.0f) && gm->ior == 1.5f);
    assert_true(is_grey(&gm->specular, 0.05f));
    scene_close(box);
    scene_close(s);
}

/* ------------------------------------------------------------ showcase */

static void test_showcase_has_everything_in_view(void **state)
{
    (void)state;
    scene *s = scene_read(SCENES "/showcase.mid");
    for (int k = 0; k < TB_PRIM_COUNT; k++)
        if (s->kinds[k] == 0)
            fail_msg("showcase has no %s", tb_prim_kind_name((tb_prim_kind)k));
    for (int k = 0; k < 3; k++)
        assert_true(s->lights[k] > 0);
    assert_true(s->nested_csg);
    assert_true(s->has_cam);
    const tb_mid_camera *c = &s->cam;
    tb_transform cam;
    assert_int_equal(tb_transform_look_at(c->eye, c->look_at, c->up, &cam), TB_OK);
    tb_transform view = tb_transform_inverse(&cam);
    double ty = tan(c->fov * TB_PI / 360.0), tx = ty * c->width / c->height;
    int standing = 0;
    for (int i = 0; i < s->n; i++) {
        const kept *k = &s->obj[i];
        if (strcmp(k->name, "ground") == 0) {
            assert_true(k->lo.z == 0.0 && k->hi.z == 0.0);
            continue;
        }
        /* Nothing sinks into the ground; all but the lamp globe (on its column) stand on it. */
        if (k->lo.z < -1e-9)
            fail_msg("'%s' reaches below the ground (z = %g)", k->name, k->lo.z);
        if (fabs(k->lo.z) <= 1e-9)
            standing++;
        else if (strcmp(k->name, "lamp globe") != 0)
            fail_msg("'%s' floats at z = %g", k->name, k->lo.z);
        for (int q = 0; q < 8; q++) {
            tb_dvec3 p = {q & 1 ? k->hi.x : k->lo.x, q & 2 ? k->hi.y : k->lo.y, q & 4 ? k->hi.z : k->lo.z};
            tb_dvec3 v = tb_transform_dpoint(&view, p);
            /* The look_at transform maps the eye to the origin looking down -z. */
            double d = -v.z;
            if (!(d > 0.0 && fabs(v.x) <= 0.98 * tx * d && fabs(v.y) <= 0.98 * ty * d))
                fail_msg("a corner of '%s' is outside the view", k->name);
        }
    }
    assert_int_equal(standing, s->n - 2);
    scene_close(s);
}

/* -------------------------------------------------------------- the room */

static void test_radiosity_room(void **state)
{
    (void)state;
    scene *s = scene_read(SCENES "/radiosity-room.mid");
    assert_true(s->all_diffuse);
    assert_int_equal(s->lights[0] + s->lights[1] + s->lights[2], 0);
    const tb_dvec3 lo = {0, 0, 0}, hi = {5, 4, 2.7}, mid = {2.5, 2, 1.35};
    assert_true(s->has_cam);
    assert_true(s->cam.eye.x > lo.x && s->cam.eye.x < hi.x && s->cam.eye.y > lo.y && s->cam.eye.y < hi.y &&
                s->cam.eye.z > lo.z && s->cam.eye.z < hi.z);
    int shell = 0, boxes = 0;
    for (int i = 0; i < s->n; i++) {
        const kept *k = &s->obj[i];
        if (k->kind == TB_PRIM_POLYGONS) {
            shell++;
            for (int f = 0; f < k->nf; f++) {
                tb_dvec3 c, n = newell(k, f, &c);
                if (!(dot3(n, sub3(mid, c)) > 0.0))
                    fail_msg("'%s' faces away from the room", k->name);
            }
            continue;
        }
        assert_int_equal(k->kind, TB_PRIM_CUBE);
        boxes++;
        if (!(k->lo.x >= lo.x && k->lo.y >= lo.y && k->lo.z >= -1e-12 && k->hi.x <= hi.x && k->hi.y <= hi.y &&
              k->hi.z <= hi.z))
            fail_msg("'%s' is not inside the room", k->name);
        for (int j = 0; j < i; j++) {
            const kept *o = &s->obj[j];
            if (o->kind != TB_PRIM_CUBE)
                continue;
            /* Touching is fine, overlapping volumes are not. */
            double ox = fmin(k->hi.x, o->hi.x) - fmax(k->lo.x, o->lo.x);
            double oy = fmin(k->hi.y, o->hi.y) - fmax(k->lo.y, o->lo.y);
            double oz = fmin(k->hi.z, o->hi.z) - fmax(k->lo.z, o->lo.z);
            if (ox > 1e-9 && oy > 1e-9 && oz > 1e-9)
                fail_msg("'%s' and '%s' overlap", k->name, o->name);
        }
    }
    assert_int_equal(shell, 7);
    assert_true(boxes >= 4);
    const kept *light = find(s, "light panel");
    assert_true(light->lo.z == light->hi.z && light->hi.z < hi.z && light->hi.z > hi.z - 0.01);
    const tb_mid_material *panel = tb_mid_reader_material(s->r, "panel");
    assert_non_null(panel);
    assert_true(tb_mid_material_emits(panel));
    scene_close(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cornell_geometry_as_published),
        cmocka_unit_test(test_cornell_faces_point_the_right_way),
        cmocka_unit_test(test_cornell_red_wall_is_not_planar),
        cmocka_unit_test(test_cornell_camera),
        cmocka_unit_test(test_cornell_spectra_as_measured),
        cmocka_unit_test(test_cornell_rgb_matches_util_color),
        cmocka_unit_test(test_cornell_coplanar_variant),
        cmocka_unit_test(test_cornell_spheres_variant),
        cmocka_unit_test(test_showcase_has_everything_in_view),
        cmocka_unit_test(test_radiosity_room),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
