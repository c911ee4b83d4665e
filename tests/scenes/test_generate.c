/* The procedural scene generator (host/mid/generate.h):
 *
 * - what it writes reads back, item by item, as exactly the items it
 *   generated (tb_mid_item_equal), for every kind and a random seed;
 * - it is deterministic (same seed, same bytes) and the seed matters;
 * - N objects, one per grid cell, at the cell centres;
 * - the geometry it makes is what the kind promises, checked by exact
 *   constructions: geodesic spheres and octahedra are closed, consistently
 *   oriented outward meshes with the right counts; height-field triangles
 *   face +z; prism profiles are simple polygons; CSG operands are closed
 *   solids and every difference has at least two operands;
 * - bad options and a failing sink give errors, and the sink's error stops it. */
#include "tb_test.h"

#include <string.h>

#include "host/mid/generate.h"
#include "host/mid/mid_reader.h"

/* ----------------------------------------------------------- helpers */

/* The scene as MID text in memory. */
static char *write_scene(const tb_gen_options *o, size_t *len)
{
    char *buf = NULL;
    FILE *f = open_memstream(&buf, len);
    assert_non_null(f);
    if (tb_generate_write(f, o))
        fail_msg("%s", tb_last_error());
    assert_int_equal(fclose(f), 0);
    return buf;
}

typedef struct lockstep {
    tb_mid_reader *r;
    long items, objects;
} lockstep;

/* Compares each generated item with the next item read back. */
static tb_status lockstep_sink(void *user, const tb_mid_item *item)
{
    lockstep *ls = user;
    tb_mid_item back;
    if (tb_mid_reader_next(ls->r, &back))
        fail_msg("reading back item %ld: %s", ls->items, tb_last_error());
    if (!tb_mid_item_equal(item, &back))
        fail_msg("item %ld (type %d) reads back different", ls->items, (int)item->type);
    ls->items++;
    ls->objects += item->type == TB_MID_ITEM_OBJECT;
    return TB_OK;
}

static void roundtrip(tb_gen_kind kind, int64_t count, uint64_t seed)
{
    tb_gen_options o = {.kind = kind, .count = count, .seed = seed};
    size_t len;
    char *text = write_scene(&o, &len);
    FILE *in = fmemopen(text, len, "r");
    assert_non_null(in);
    lockstep ls = {0};
    assert_int_equal(tb_mid_reader_open_stream(&ls.r, in, "<generated>", NULL), TB_OK);
    if (tb_generate(&o, lockstep_sink, &ls))
        fail_msg("%s", tb_last_error());
    tb_mid_item end;
    assert_int_equal(tb_mid_reader_next(ls.r, &end), TB_OK);
    assert_int_equal(end.type, TB_MID_ITEM_END);
    assert_int_equal(ls.objects, count);
    /* camera, 2 lights, 8 materials */
    assert_int_equal(ls.items, count + 11);
    tb_mid_reader_close(ls.r);
    fclose(in);
    free(text);
}

static void test_reads_back_equal(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("generate_roundtrip", 20240601);
    roundtrip(TB_GEN_GRID, 60, seed);
    roundtrip(TB_GEN_CSG, 40, seed);
    roundtrip(TB_GEN_MESH, 8, seed);
    roundtrip(TB_GEN_GRID, 0, seed);
}

static void test_deterministic(void **state)
{
    (void)state;
    for (int k = 0; k < TB_GEN_KIND_COUNT; k++) {
        tb_gen_options a = {.kind = (tb_gen_kind)k, .count = 12, .seed = 5};
        tb_gen_options b = a;
        b.seed = 6;
        size_t la, la2, lb;
        char *ta = write_scene(&a, &la), *ta2 = write_scene(&a, &la2), *tb = write_scene(&b, &lb);
        assert_true(la == la2 && memcmp(ta, ta2, la) == 0);
        assert_false(la == lb && memcmp(ta, tb, la) == 0);
        free(ta);
        free(ta2);
        free(tb);
    }
}

/* ------------------------------------------------------ placement */

typedef struct cells {
    int64_t side, n;
    unsigned char *seen;
} cells;

static tb_status cells_sink(void *user, const tb_mid_item *item)
{
    cells *c = user;
    if (item->type != TB_MID_ITEM_OBJECT)
        return TB_OK;
    /* The last operation is the move to the cell centre ((col + 0.5) and
     * (row + 0.5) times the pitch), so it is the translation column. */
    const tb_mat4 *m = &item->object->to_world.m;
    double pitch = 4.5, x = m->m[0][3] / pitch - 0.5, y = m->m[1][3] / pitch - 0.5;
    int64_t col = (int64_t)llround(x), row = (int64_t)llround(y);
    assert_true(x == (double)col && y == (double)row);
    assert_true(col >= 0 && col < c->side && row >= 0 && row < c->side);
    int64_t cell = row * c->side + col;
    assert_true(cell == c->n);
    assert_false(c->seen[cell]);
    c->seen[cell] = 1;
    c->n++;
    return TB_OK;
}

static void test_one_object_per_cell(void **state)
{
    (void)state;
    const int64_t counts[] = {1, 2, 10, 17, 49};
    for (int k = 0; k < TB_GEN_KIND_COUNT; k++)
        for (size_t i = 0; i < sizeof counts / sizeof counts[0]; i++) {
            tb_gen_options o = {.kind = (tb_gen_kind)k, .count = counts[i], .seed = 3};
            cells c = {.side = (int64_t)ceil(sqrt((double)counts[i]))};
            c.seen = calloc((size_t)(c.side * c.side), 1);
            assert_non_null(c.seen);
            assert_int_equal(tb_generate(&o, cells_sink, &c), TB_OK);
            assert_int_equal(c.n, counts[i]);
            free(c.seen);
        }
}

/* ------------------------------------------------------- geometry */

typedef struct edge {
    int a, b;
} edge;

static int edge_cmp(const void *x, const void *y)
{
    const edge *p = x, *q = y;
    return p->a != q->a ? (p->a < q->a ? -1 : 1) : p->b != q->b ? (p->b < q->b ? -1 : 1) : 0;
}

/* Every directed edge occurs once and its reverse once: a closed, consistently
 * oriented 2-manifold (as far as edges tell). */
static void assert_closed(const tb_geom_polygons *p)
{
    int ne = p->face_start[p->nfaces];
    edge *e = malloc((size_t)ne * sizeof *e);
    assert_non_null(e);
    for (int f = 0; f < p->nfaces; f++) {
        int s = p->face_start[f], n = p->face_start[f + 1] - s;
        for (int j = 0; j < n; j++)
            e[s + j] = (edge){p->indices[s + j], p->indices[s + (j + 1) % n]};
    }
    qsort(e, (size_t)ne, sizeof *e, edge_cmp);
    for (int i = 0; i < ne; i++) {
        assert_true(e[i].a != e[i].b);
        if (i > 0 && edge_cmp(&e[i], &e[i - 1]) == 0)
            fail_msg("edge %d-%d used twice in one direction", e[i].a, e[i].b);
        edge r = {e[i].b, e[i].a};
        if (!bsearch(&r, e, (size_t)ne, sizeof *e, edge_cmp))
            fail_msg("edge %d-%d has no opposite", e[i].a, e[i].b);
    }
    free(e);
}

/* Face normals (right-hand rule) point away from the origin. */
static void assert_outward(const tb_geom_polygons *p)
{
    for (int f = 0; f < p->nfaces; f++) {
        const int *ix = &p->indices[p->face_start[f]];
        tb_vec3 a = p->vertices[ix[0]], b = p->vertices[ix[1]], c = p->vertices[ix[2]];
        double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z, vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
        double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
        double cx = (a.x + b.x + c.x) / 3, cy = (a.y + b.y + c.y) / 3, cz = (a.z + b.z + c.z) / 3;
        assert_true(nx * cx + ny * cy + nz * cz > 0.0);
    }
}

static double orient2(tb_vec2 a, tb_vec2 b, tb_vec2 c)
{
    return ((double)b.x - a.x) * ((double)c.y - a.y) - ((double)b.y - a.y) * ((double)c.x - a.x);
}

/* No two non-adjacent edges of the closed outline touch or cross. */
static void assert_simple(const tb_vec2 *p, int n)
{
    for (int i = 0; i < n; i++)
        for (int j = i + 2; j < n; j++) {
            if (i == 0 && j == n - 1)
                continue;
            tb_vec2 a = p[i], b = p[(i + 1) % n], c = p[j], d = p[(j + 1) % n];
            double o1 = orient2(a, b, c), o2 = orient2(a, b, d), o3 = orient2(c, d, a), o4 = orient2(c, d, b);
            if (o1 * o2 <= 0.0 && o3 * o4 <= 0.0)
                fail_msg("profile edges %d and %d meet", i, j);
        }
}

typedef struct shapes {
    long spheres, fields, octahedra, profiles, differences, leaves;
} shapes;

static void check_mesh(shapes *s, const tb_geom_polygons *p)
{
    if (p->uvs) {
        /* A height field: every triangle counter-clockwise seen from +z. */
        s->fields++;
        assert_non_null(p->normals);
        for (int f = 0; f < p->nfaces; f++) {
            const int *ix = &p->indices[p->face_start[f]];
            assert_int_equal(p->face_start[f + 1] - p->face_start[f], 3);
            tb_vec3 a = p->vertices[ix[0]], b = p->vertices[ix[1]], c = p->vertices[ix[2]];
            assert_true(orient2((tb_vec2){a.x, a.y}, (tb_vec2){b.x, b.y}, (tb_vec2){c.x, c.y}) > 0.0);
        }
        for (int i = 0; i < p->nvertices; i++) {
            assert_true(p->uvs[i].x >= 0 && p->uvs[i].x <= 1 && p->uvs[i].y >= 0 && p->uvs[i].y <= 1);
            assert_true(p->normals[i].z > 0);
        }
        return;
    }
    assert_closed(p);
    assert_outward(p);
    if (p->nvertices == 6) {
        s->octahedra++;
        return;
    }
    /* A geodesic sphere of frequency f: 10 f^2 + 2 vertices on the unit sphere
     * (to the 4 decimals written), 20 f^2 triangles. */
    s->spheres++;
    int f = (int)lround(sqrt((p->nvertices - 2) / 10.0));
    assert_int_equal(p->nvertices, 10 * f * f + 2);
    assert_int_equal(p->nfaces, 20 * f * f);
    assert_non_null(p->normals);
    for (int i = 0; i < p->nvertices; i++) {
        tb_vec3 v = p->vertices[i];
        tb_assert_near(sqrt((double)v.x * v.x + (double)v.y * v.y + (double)v.z * v.z), 1.0, 1e-4);
    }
}

static void check_object(shapes *s, const tb_mid_object *o, bool operand)
{
    const tb_mid_geometry *g = &o->geom;
    switch (o->kind) {
    case TB_PRIM_POLYGONS: check_mesh(s, &g->polygons); break;
    case TB_PRIM_PRISM:
        if (g->prism.nprofile) {
            s->profiles++;
            assert_simple(g->prism.profile, g->prism.nprofile);
        }
        break;
    case TB_PRIM_DIFFERENCE: s->differences++; break;
    default: break;
    }
    if (operand && !tb_prim_is_csg(o->kind)) {
        /* CSG operands are closed solids. */
        s->leaves++;
        bool closed = true;
        if (o->kind == TB_PRIM_CYLINDER)
            closed = g->cylinder.caps;
        else if (o->kind == TB_PRIM_CONE)
            closed = g->cone.caps;
        else if (o->kind == TB_PRIM_PYRAMID)
            closed = g->pyramid.caps;
        else if (o->kind == TB_PRIM_PRISM)
            closed = g->prism.caps;
        else if (o->kind == TB_PRIM_CONIC)
            closed = g->conic.caps;
        assert_true(closed);
    }
    if (tb_prim_is_csg(o->kind))
        assert_true(o->nchildren >= 2);
    for (int i = 0; i < o->nchildren; i++)
        check_object(s, &o->children[i], true);
}

static tb_status shapes_sink(void *user, const tb_mid_item *item)
{
    if (item->type == TB_MID_ITEM_OBJECT)
        check_object(user, item->object, false);
    return TB_OK;
}

static void test_geometry_as_promised(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("generate_geometry", 77);
    shapes grid = {0}, csg = {0}, mesh = {0};
    tb_gen_options o = {.kind = TB_GEN_GRID, .count = 300, .seed = seed};
    assert_int_equal(tb_generate(&o, shapes_sink, &grid), TB_OK);
    o.kind = TB_GEN_CSG;
    o.count = 100;
    assert_int_equal(tb_generate(&o, shapes_sink, &csg), TB_OK);
    o.kind = TB_GEN_MESH;
    o.count = 24;
    assert_int_equal(tb_generate(&o, shapes_sink, &mesh), TB_OK);
    print_message("[ measured ] grid: %ld octahedra, %ld profiles; csg: %ld differences, %ld operands; "
                  "mesh: %ld spheres, %ld height fields\n",
                  grid.octahedra, grid.profiles, csg.differences, csg.leaves, mesh.spheres, mesh.fields);
    /* Each shape occurs (the probabilities make a miss astronomically unlikely). */
    assert_true(grid.octahedra > 0 && grid.profiles > 0);
    assert_true(csg.differences > 0 && csg.leaves > 0);
    assert_true(mesh.spheres > 0 && mesh.fields > 0);
}

/* ----------------------------------------------------------- errors */

static tb_status failing_sink(void *user, const tb_mid_item *item)
{
    (void)item;
    int *n = user;
    return ++*n == 5 ? tb_error(TB_ERR_IO, "sink refuses") : TB_OK;
}

static tb_status null_sink(void *user, const tb_mid_item *item)
{
    (void)user;
    (void)item;
    return TB_OK;
}

static void test_errors(void **state)
{
    (void)state;
    tb_gen_kind k;
    for (int i = 0; i < TB_GEN_KIND_COUNT; i++) {
        assert_int_equal(tb_gen_kind_parse(tb_gen_kind_name((tb_gen_kind)i), &k), TB_OK);
        assert_int_equal(k, i);
    }
    assert_int_equal(tb_gen_kind_parse("grids", &k), TB_ERR_ARG);
    assert_string_equal(tb_last_error(), "unknown scene kind 'grids' (expected grid, csg or mesh)");
    assert_string_equal(tb_gen_kind_name((tb_gen_kind)7), "?");

    tb_gen_options o = {.kind = TB_GEN_GRID, .count = -1, .seed = 1};
    assert_int_equal(tb_generate(&o, null_sink, NULL), TB_ERR_ARG);
    o.count = TB_GEN_MAX_COUNT + 1;
    assert_int_equal(tb_generate(&o, null_sink, NULL), TB_ERR_ARG);
    o.count = 10;
    o.kind = (tb_gen_kind)9;
    assert_int_equal(tb_generate(&o, null_sink, NULL), TB_ERR_ARG);
    o.kind = TB_GEN_CSG;
    assert_int_equal(tb_generate(&o, NULL, NULL), TB_ERR_ARG);

    int calls = 0;
    assert_int_equal(tb_generate(&o, failing_sink, &calls), TB_ERR_IO);
    assert_int_equal(calls, 5);
    assert_string_equal(tb_last_error(), "sink refuses");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reads_back_equal),
        cmocka_unit_test(test_deterministic),
        cmocka_unit_test(test_one_object_per_cell),
        cmocka_unit_test(test_geometry_as_promised),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
