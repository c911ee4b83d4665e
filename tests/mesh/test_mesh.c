/* util/mesh meshing: the non-planar quad rule (Cornell box red wall), the
 * quad criterion, and subdivision checked for conformity (the elements
 * rebuilt as a FED: closed inputs stay closed and keep their Euler
 * characteristic; open ones keep their boundary as a set of segments; no
 * vertex lies inside another element's edge), maximum edge length, area and
 * orientation. */
#include "tb_test.h"

#include <float.h>
#include <string.h>

#include "util/math/float.h"
#include "util/mesh/mesh.h"
#include "util/mesh/polygon.h"

/* ------------------------------------------------------------------ helpers */

/* A FED from faces given as -1-terminated loops, with a -2 before each hole. */
static tb_fed *fed_from(const tb_vec3 *pos, uint32_t nv, const int *spec)
{
    uint32_t fl[256], ls[512], cs[4096], nf = 0, nl = 0, nc = 0;
    for (const int *p = spec; *p != -9;) {
        fl[nf] = 0;
        for (;;) {
            uint32_t n = 0;
            while (*p >= 0)
                cs[nc++] = (uint32_t)*p++, n++;
            ls[nl++] = n;
            fl[nf]++;
            if (*p == -2) {
                p++;
                continue;
            }
            p++; /* -1: end of face */
            break;
        }
        nf++;
    }
    tb_fed_desc d = {.nverts = nv, .positions = pos, .nfaces = nf, .face_nloops = fl, .nloops = nl,
                     .loop_sizes = ls, .corners = cs};
    tb_fed *m;
    if (tb_fed_build(&d, &m, NULL))
        fail_msg("fed: %s", tb_last_error());
    return m;
}

static double dist3(tb_vec3 a, tb_vec3 b)
{
    double dx = (double)a.x - b.x, dy = (double)a.y - b.y, dz = (double)a.z - b.z;
    return sqrt(dx * dx + dy * dy + dz * dz);
}

/* Distance of p from segment a-b, and where along it (0..1) the nearest point is. */
static double seg_dist(tb_vec3 p, tb_vec3 a, tb_vec3 b, double *t)
{
    double ux = (double)b.x - a.x, uy = (double)b.y - a.y, uz = (double)b.z - a.z;
    double wx = (double)p.x - a.x, wy = (double)p.y - a.y, wz = (double)p.z - a.z;
    double uu = ux * ux + uy * uy + uz * uz;
    *t = uu > 0 ? (ux * wx + uy * wy + uz * wz) / uu : 0;
    double s = fmin(1, fmax(0, *t));
    double dx = wx - s * ux, dy = wy - s * uy, dz = wz - s * uz;
    return sqrt(dx * dx + dy * dy + dz * dz);
}

static const tb_vec3 *sort_pos;

/* A key along a direction no test mesh is aligned with. */
static double skew_key(tb_vec3 p) { return 0.5773 * p.x + 0.6180 * p.y + 0.5334 * p.z; }

static int cmp_key(const void *a, const void *b)
{
    double x = skew_key(sort_pos[*(const uint32_t *)a]), y = skew_key(sort_pos[*(const uint32_t *)b]);
    return (x > y) - (x < y);
}

/* Sorts vertex indices by skew_key. */
static void sort_by_key(uint32_t *idx, uint32_t n, const tb_vec3 *pos)
{
    sort_pos = pos;
    qsort(idx, n, sizeof *idx, cmp_key);
}

/* The element mesh as a FED (elements become faces); NULL if the elements
 * are not a valid FED (degenerate, zero-length edges, ...). */
static tb_fed *elements_as_fed(const tb_mesh *m)
{
    size_t ne = tb_mesh_nelems(m);
    uint32_t *ls = malloc(sizeof(uint32_t) * (ne + 1)), *cs = malloc(sizeof(uint32_t) * (4 * ne + 1));
    uint32_t nc = 0;
    for (size_t i = 0; i < ne; i++) {
        const tb_mesh_elem *e = tb_mesh_elem_at(m, i);
        ls[i] = (uint32_t)tb_mesh_elem_size(e);
        for (int k = 0; k < tb_mesh_elem_size(e); k++)
            cs[nc++] = e->v[k];
    }
    tb_fed_desc d = {.nverts = (uint32_t)m->positions.len, .positions = m->positions.data,
                     .nfaces = (uint32_t)ne, .nloops = (uint32_t)ne, .loop_sizes = ls, .corners = cs};
    tb_fed *f = NULL;
    tb_fed_build(&d, &f, NULL);
    free(ls), free(cs);
    return f;
}

typedef struct check {
    double max_edge;     /* bound to respect (0: none) */
    bool quads_allowed;  /* quads may appear */
} check;

#define PROBLEM(...)                                                                               \
    do {                                                                                           \
        snprintf(why, nwhy, __VA_ARGS__);                                                          \
        goto out;                                                                                  \
    } while (0)

/* Every property the meshing promises, checked independently; false if all
 * hold, else true with the first problem in why. */
static bool mesh_problem(const tb_fed *src, const tb_mesh *m, check ck, char *why, size_t nwhy)
{
    double size = 0, maxabs = 0;
    for (uint32_t v = 0; v < src->nverts; v++) {
        tb_vec3 p = src->positions[v];
        size = fmax(size, dist3(p, src->positions[0]));
        maxabs = fmax(maxabs, fmax(fabs(p.x), fmax(fabs(p.y), fabs(p.z))));
    }
    double tol = 1e-5 * size;
    tb_fed *el = NULL;
    double *covered = NULL;
    uint32_t *byx = NULL;
    /* FED vertices keep their index and position */
    if (m->positions.len < src->nverts || memcmp(m->positions.data, src->positions, src->nverts * sizeof(tb_vec3)))
        PROBLEM("the FED vertices moved");
    /* elements: valid polygons (tb_fed_build rejects degenerate ones), facing like their face */
    if (!(el = elements_as_fed(m)))
        PROBLEM("elements are not a valid mesh: %s", tb_last_error());
    double area = 0;
    for (size_t i = 0; i < tb_mesh_nelems(m); i++) {
        const tb_mesh_elem *e = tb_mesh_elem_at(m, i);
        if (e->face >= src->nfaces || e->parent != TB_MESH_NONE)
            PROBLEM("element %zu: bad face or parent", i);
        tb_dvec3 fn = tb_fed_face_normal(src, e->face), en = tb_fed_face_normal(el, (uint32_t)i);
        if (!(fn.x * en.x + fn.y * en.y + fn.z * en.z > 0))
            PROBLEM("element %zu faces away from its face", i);
        area += tb_mesh_elem_area(m, i);
        if (tb_mesh_elem_size(e) == 4) {
            tb_vec3 q[4];
            for (int k = 0; k < 4; k++)
                q[k] = TB_ARRAY_AT(&m->positions, tb_vec3, e->v[k]);
            if (!ck.quads_allowed || !tb_mesh_quad_check(q, 0, NULL))
                PROBLEM("element %zu: a quad that should not be there", i);
        }
    }
    /* area preserved (planar faces) */
    double want = 0;
    for (uint32_t f = 0; f < src->nfaces; f++)
        want += tb_fed_face_area(src, f);
    if (!(fabs(area - want) <= 1e-5 * want))
        PROBLEM("element area %.9g, face area %.9g", area, want);
    /* edge bound, up to the rounding of vertex positions to float (a few
     * ulps of the largest coordinate) */
    for (uint32_t e = 0; e < el->nedges && ck.max_edge > 0; e++) {
        double len = dist3(el->positions[el->edges[e].v[0]], el->positions[el->edges[e].v[1]]);
        if (len > ck.max_edge + 8 * FLT_EPSILON * maxabs)
            PROBLEM("edge %u is %.9g long (bound %.9g)", e, len, ck.max_edge);
    }
    /* conformity: every element edge is used once (on the source's
     * boundary) or twice in opposite directions */
    if (tb_fed_count_nonmanifold_edges(el) != tb_fed_count_nonmanifold_edges(src))
        PROBLEM("non-manifold edges appeared");
    tb_fed_report r;
    tb_fed_check(el, &r);
    if (r.counts[TB_FED_ISSUE_ORIENTATION])
        PROBLEM("elements with inconsistent orientation");
    if (tb_fed_is_closed(src) &&
        (!tb_fed_is_closed(el) || tb_fed_euler_characteristic(el) != tb_fed_euler_characteristic(src)))
        PROBLEM("a closed mesh came out open or with another Euler characteristic");
    /* no T-junctions: no vertex lies inside an element edge it is not an end
     * of (vertices sorted along a skew direction, so each edge looks only
     * at the vertices in its range along it) */
    byx = malloc(sizeof(uint32_t) * (el->nverts + 1));
    uint32_t nused = 0;
    for (uint32_t v = 0; v < el->nverts; v++)
        if (el->vert_faces[v + 1] > el->vert_faces[v])
            byx[nused++] = v;
    sort_by_key(byx, nused, el->positions);
    double ttol = 1e-3 * tol;
    for (uint32_t e = 0; e < el->nedges; e++) {
        tb_vec3 a = el->positions[el->edges[e].v[0]], b = el->positions[el->edges[e].v[1]];
        double x0 = fmin(skew_key(a), skew_key(b)) - 2 * ttol, x1 = fmax(skew_key(a), skew_key(b)) + 2 * ttol;
        uint32_t lo = 0, hi = nused;
        while (lo < hi) { /* first vertex with key >= x0 */
            uint32_t mid = (lo + hi) / 2;
            if (skew_key(el->positions[byx[mid]]) < x0)
                lo = mid + 1;
            else
                hi = mid;
        }
        for (uint32_t k = lo; k < nused && skew_key(el->positions[byx[k]]) <= x1; k++) {
            uint32_t v = byx[k];
            if (v == el->edges[e].v[0] || v == el->edges[e].v[1])
                continue;
            double t;
            if (seg_dist(el->positions[v], a, b, &t) <= ttol && t > 0 && t < 1)
                PROBLEM("vertex %u lies inside edge %u-%u (a T-junction)", v, el->edges[e].v[0], el->edges[e].v[1]);
        }
    }
    /* boundary unchanged as a set of segments: each boundary element edge
     * lies on a source boundary edge, and their lengths add up to it */
    covered = calloc(src->nedges + 1, sizeof(double));
    for (uint32_t e = 0; e < el->nedges; e++) {
        if (!tb_fed_edge_is_boundary(el, e))
            continue;
        tb_vec3 a = el->positions[el->edges[e].v[0]], b = el->positions[el->edges[e].v[1]];
        uint32_t found = TB_FED_NONE;
        for (uint32_t s = 0; s < src->nedges && found == TB_FED_NONE; s++) {
            if (!tb_fed_edge_is_boundary(src, s))
                continue;
            tb_vec3 p = src->positions[src->edges[s].v[0]], q = src->positions[src->edges[s].v[1]];
            double t;
            if (seg_dist(a, p, q, &t) <= tol && seg_dist(b, p, q, &t) <= tol)
                found = s;
        }
        if (found == TB_FED_NONE)
            PROBLEM("boundary edge %u-%u of the elements is on no boundary edge of the source (a crack)",
                    el->edges[e].v[0], el->edges[e].v[1]);
        covered[found] += dist3(a, b);
    }
    for (uint32_t s = 0; s < src->nedges; s++) {
        double len = dist3(src->positions[src->edges[s].v[0]], src->positions[src->edges[s].v[1]]);
        if (tb_fed_edge_is_boundary(src, s) && !(fabs(covered[s] - len) <= tol))
            PROBLEM("boundary edge %u: elements cover %.9g of its %.9g", s, covered[s], len);
    }
    tb_fed_free(el);
    free(covered);
    free(byx);
    return false;
out:
    tb_fed_free(el);
    free(covered);
    free(byx);
    return true;
}

static void check_mesh(const tb_fed *src, const tb_mesh *m, check ck)
{
    char why[256];
    if (mesh_problem(src, m, ck, why, sizeof why))
        fail_msg("%s", why);
}

/* Expects mesh_problem to find a problem whose message contains `what`. */
static void expect_problem(const tb_fed *src, const tb_mesh *m, check ck, const char *what)
{
    char why[256];
    if (!mesh_problem(src, m, ck, why, sizeof why))
        fail_msg("the checker missed: %s", what);
    if (!strstr(why, what))
        fail_msg("the checker found '%s', expected '%s'", why, what);
}

static size_t count_quads(const tb_mesh *m)
{
    size_t n = 0;
    for (size_t i = 0; i < tb_mesh_nelems(m); i++)
        n += tb_mesh_elem_size(tb_mesh_elem_at(m, i)) == 4;
    return n;
}

static const tb_vec3 cube_pos[8] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                    {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
static const int cube_quads[] = {0, 3, 2, 1, -1, 4, 5, 6, 7, -1, 0, 1, 5, 4, -1,
                                 1, 2, 6, 5, -1, 2, 3, 7, 6, -1, 3, 0, 4, 7, -1, -9};
static const int cube_tris[] = {0, 3, 2, -1, 0, 2, 1, -1, 4, 5, 6, -1, 4, 6, 7, -1, 0, 1, 5, -1, 0, 5, 4, -1,
                                1, 2, 6, -1, 1, 6, 5, -1, 2, 3, 7, -1, 2, 7, 6, -1, 3, 0, 4, -1, 3, 4, 7, -1, -9};

/* The Cornell box room (mm), vertices in the published order, faces sharing them. */
static const tb_vec3 room_pos[12] = {
    {552.8f, 0, 0},      {0, 0, 0},          {0, 0, 559.2f},     {549.6f, 0, 559.2f}, /* floor */
    {556, 548.8f, 0},    {556, 548.8f, 559.2f}, {0, 548.8f, 559.2f}, {0, 548.8f, 0}, /* ceiling */
};
static const int room_faces[] = {
    0, 1, 2, 3, -1,  /* floor */
    4, 5, 6, 7, -1,  /* ceiling */
    3, 2, 6, 5, -1,  /* back wall */
    0, 3, 5, 4, -1,  /* left (red) wall: non-planar */
    2, 1, 7, 6, -1,  /* right (green) wall */
    -9};

/* ------------------------------------------------------------------- tests */

static void test_cornell_red_wall(void **state)
{
    (void)state;
    const tb_vec3 red[4] = {{552.8f, 0, 0}, {549.6f, 0, 559.2f}, {556, 548.8f, 559.2f}, {556, 548.8f, 0}};
    /* The fourth vertex is ~3.2 mm off the plane of the first three... */
    tb_vec3 e1 = tb_vec3_sub(red[1], red[0]), e2 = tb_vec3_sub(red[2], red[0]);
    tb_vec3 n = tb_vec3_normalize(tb_vec3_cross(e1, e2));
    double off = fabs(tb_vec3_dot(n, tb_vec3_sub(red[3], red[0])));
    assert_true(off > 3.0 && off < 3.5);
    /* ...so the wall is not planar by the documented test: its vertices are
     * +-0.8 mm from the Newell plane, against 1e-5 of a 783 mm diagonal. */
    assert_false(tb_polygon_is_planar(red, NULL, 4, 0));
    double dev = tb_polygon_planarity(red, NULL, 4);
    assert_true(dev > 0.7 && dev < 0.9);
    /* Its diagonals: p0-p2 is 783.515 mm, p1-p3 783.535 mm: the shorter, p0-p2, is used. */
    assert_int_equal(tb_quad_split_diagonal(red[0], red[1], red[2], red[3]), TB_QUAD_DIAG_02);
    /* Meshed alone: exactly the two triangles (0 1 2) and (0 2 3), even with quads on. */
    const int face[] = {0, 1, 2, 3, -1, -9};
    tb_fed *f = fed_from(red, 4, face);
    tb_mesh m;
    tb_mesh_init(&m);
    tb_mesh_opts o = {.quads = true};
    assert_int_equal(tb_mesh_from_fed(f, &o, &m), TB_OK);
    assert_int_equal(tb_mesh_nelems(&m), 2);
    const tb_mesh_elem *a = tb_mesh_elem_at(&m, 0), *b = tb_mesh_elem_at(&m, 1);
    assert_int_equal(tb_mesh_elem_size(a), 3);
    assert_true(a->v[0] == 0 && a->v[1] == 1 && a->v[2] == 2);
    assert_true(b->v[0] == 0 && b->v[1] == 2 && b->v[2] == 3);
    /* the surface is those two triangles: its area is theirs (computed here
     * in double with Heron's formula) */
    double want = 0;
    for (int h = 0; h < 2; h++) {
        tb_vec3 A = red[0], B = red[1 + h], C = red[2 + h];
        double a = dist3(B, C), b = dist3(A, C), cc = dist3(A, B), sp = (a + b + cc) / 2;
        want += sqrt(sp * (sp - a) * (sp - b) * (sp - cc));
    }
    tb_assert_near(tb_mesh_elem_area(&m, 0) + tb_mesh_elem_area(&m, 1), want, 1e-9 * want);
    tb_mesh_free(&m);
    tb_fed_free(f);

    /* Other diagonal cases: a skew quad whose p1-p3 is the shorter, and a
     * planar dart (reflex corner at p2) whose shorter diagonal p1-p3 lies
     * outside it, so p0-p2 is taken; the same dart started one corner later
     * (reflex at p1) must take p1-p3 although it is the longer. */
    const tb_vec3 skew[4] = {{0, 0, 0}, {2, -1, 0.3f}, {4, 0, 0}, {2, 1, -0.3f}};
    assert_int_equal(tb_quad_split_diagonal(skew[0], skew[1], skew[2], skew[3]), TB_QUAD_DIAG_13);
    const tb_vec3 dart[4] = {{0, 0, 0}, {4, -1, 0}, {3, 0, 0}, {4, 1, 0}};
    assert_int_equal(tb_quad_split_diagonal(dart[0], dart[1], dart[2], dart[3]), TB_QUAD_DIAG_02);
    assert_int_equal(tb_quad_split_diagonal(dart[1], dart[2], dart[3], dart[0]), TB_QUAD_DIAG_13);
}

static void test_quad_criterion(void **state)
{
    (void)state;
    double s;
    const tb_vec3 square[4] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    assert_true(tb_mesh_quad_check(square, 0, &s));
    tb_assert_near(s, 0, 1e-12);
    const tb_vec3 rect[4] = {{0, 0, 5}, {0, 7, 5}, {0, 7, 6}, {0, 0, 6}};
    assert_true(tb_mesh_quad_check(rect, 0, &s));
    tb_assert_near(s, 0, 1e-12);
    /* a rhombus of 60 and 120 degrees passes with score 30 degrees */
    const tb_vec3 rh60[4] = {{0, 0, 0}, {1, 0, 0}, {1.5f, 0.8660254f, 0}, {0.5f, 0.8660254f, 0}};
    assert_true(tb_mesh_quad_check(rh60, 0, &s));
    tb_assert_near(s, tb_radians(30), 1e-6);
    /* 20 degrees fails */
    float c20 = (float)cos(tb_radians(20)), s20 = (float)sin(tb_radians(20));
    const tb_vec3 rh20[4] = {{0, 0, 0}, {1, 0, 0}, {1 + c20, s20, 0}, {c20, s20, 0}};
    assert_false(tb_mesh_quad_check(rh20, 0, NULL));
    /* concave, clockwise-then-counterclockwise (bow tie) and non-planar fail */
    const tb_vec3 concave[4] = {{0, 0, 0}, {2, 0, 0}, {0.5f, 0.5f, 0}, {0, 2, 0}};
    assert_false(tb_mesh_quad_check(concave, 0, NULL));
    const tb_vec3 bowtie[4] = {{0, 0, 0}, {1, 1, 0}, {1, 0, 0}, {0, 1, 0}};
    assert_false(tb_mesh_quad_check(bowtie, 0, NULL));
    const tb_vec3 bent[4] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0.01f}, {0, 1, 0}};
    assert_false(tb_mesh_quad_check(bent, 0, NULL));
    assert_true(tb_mesh_quad_check(bent, 0.1, NULL)); /* with a looser tolerance it is planar enough */
}

static void test_no_subdivision(void **state)
{
    (void)state;
    tb_fed *f = fed_from(cube_pos, 8, cube_quads);
    tb_mesh m;
    tb_mesh_init(&m);
    /* quads off: each face becomes two triangles */
    assert_int_equal(tb_mesh_from_fed(f, NULL, &m), TB_OK);
    assert_int_equal(tb_mesh_nelems(&m), 12);
    assert_int_equal(m.positions.len, 8);
    check_mesh(f, &m, (check){0, false});
    /* quads on: one quad per face */
    tb_mesh_opts o = {.quads = true};
    assert_int_equal(tb_mesh_from_fed(f, &o, &m), TB_OK);
    assert_int_equal(tb_mesh_nelems(&m), 6);
    assert_int_equal(count_quads(&m), 6);
    check_mesh(f, &m, (check){0, true});
    tb_mesh_free(&m);
    tb_fed_free(f);
}

static void test_subdivide_cube(void **state)
{
    (void)state;
    tb_mesh m;
    tb_mesh_init(&m);
    /* quads: 2 / 0.3 -> 7 parts per edge, a 7 x 7 grid per face */
    tb_fed *f = fed_from(cube_pos, 8, cube_quads);
    tb_mesh_opts o = {.max_edge = 0.3, .quads = true};
    assert_int_equal(tb_mesh_from_fed(f, &o, &m), TB_OK);
    assert_int_equal(tb_mesh_nelems(&m), 6 * 49);
    assert_int_equal(count_quads(&m), 6 * 49);
    assert_int_equal(m.positions.len, 6 * 7 * 7 + 2); /* a subdivided cube: 6k^2 + 2 vertices */
    check_mesh(f, &m, (check){0.3, true});
    /* by area: 0.04 -> edge bound 0.2 -> 10 parts */
    tb_mesh_opts oa = {.max_area = 0.04};
    assert_int_equal(tb_mesh_from_fed(f, &oa, &m), TB_OK);
    for (size_t i = 0; i < tb_mesh_nelems(&m); i++)
        assert_true(tb_mesh_elem_area(&m, i) <= 0.04 * (1 + 1e-6));
    check_mesh(f, &m, (check){0.2, false});
    tb_fed_free(f);

    /* triangulated cube: sides (2) get 7 parts, face diagonals (2.83) 10:
     * the general path (triangulate + bisect) must still close up */
    f = fed_from(cube_pos, 8, cube_tris);
    assert_int_equal(tb_mesh_from_fed(f, &o, &m), TB_OK);
    check_mesh(f, &m, (check){0.3, true});
    assert_true(count_quads(&m) > 0);
    tb_mesh_opts ot = {.max_edge = 0.45};
    assert_int_equal(tb_mesh_from_fed(f, &ot, &m), TB_OK);
    check_mesh(f, &m, (check){0.45, false});
    tb_fed_free(f);
    tb_mesh_free(&m);
}

static void test_subdivide_frame(void **state)
{
    (void)state;
    /* A square frame (a closed solid of genus 1): top and bottom faces have
     * holes, and every face meets its neighbours on shared edges. */
    tb_vec3 p[16];
    for (int z = 0; z < 2; z++)
        for (int k = 0; k < 4; k++) {
            static const float ox[4] = {0, 3, 3, 0}, oy[4] = {0, 0, 3, 3};
            static const float ix[4] = {1, 2, 2, 1}, iy[4] = {1, 1, 2.2f, 2.2f};
            p[8 * z + k] = tb_vec3_make(ox[k], oy[k], (float)z);
            p[8 * z + 4 + k] = tb_vec3_make(ix[k], iy[k], (float)z);
        }
    const int frame[] = {
        0, 3, 2, 1, -2, 4, 5, 6, 7, -1,       /* bottom (facing -z), hole counter-clockwise seen from +z */
        8, 9, 10, 11, -2, 12, 15, 14, 13, -1, /* top */
        0, 1, 9, 8, -1, 1, 2, 10, 9, -1, 2, 3, 11, 10, -1, 3, 0, 8, 11, -1, /* outer walls */
        4, 12, 13, 5, -1, 5, 13, 14, 6, -1, 6, 14, 15, 7, -1, 7, 15, 12, 4, -1, /* inner walls */
        -9};
    tb_fed *f = fed_from(p, 16, frame);
    assert_true(tb_fed_is_closed(f));
    assert_int_equal(tb_fed_euler_characteristic(f), 0);
    tb_mesh m;
    tb_mesh_init(&m);
    const double bounds[] = {0, 0.7, 0.33, 0.1};
    for (int k = 0; k < 4; k++)
        for (int q = 0; q < 2; q++) {
            tb_mesh_opts o = {.max_edge = bounds[k], .quads = q};
            assert_int_equal(tb_mesh_from_fed(f, &o, &m), TB_OK);
            check_mesh(f, &m, (check){bounds[k], q});
        }
    tb_mesh_free(&m);
    tb_fed_free(f);
}

static void test_subdivide_cornell_room(void **state)
{
    (void)state;
    tb_fed *f = fed_from(room_pos, 8, room_faces);
    tb_mesh m;
    tb_mesh_init(&m);
    tb_mesh_opts o = {.max_edge = 100, .quads = true};
    assert_int_equal(tb_mesh_from_fed(f, &o, &m), TB_OK);
    check_mesh(f, &m, (check){100, true});
    /* The red wall (face 3) was split along p0-p2 (room vertices 0 and 5):
     * each of its elements lies in the plane of triangle (0 3 5) or of
     * (0 5 4), none straddles the diagonal. The planar floor is a 6 x 6 grid
     * of quads (every side is 549.6..559.2 mm). */
    size_t floor_quads = 0, red = 0;
    const uint32_t halves[2][3] = {{0, 3, 5}, {0, 5, 4}};
    for (size_t i = 0; i < tb_mesh_nelems(&m); i++) {
        const tb_mesh_elem *e = tb_mesh_elem_at(&m, i);
        floor_quads += e->face == 0 && tb_mesh_elem_size(e) == 4;
        if (e->face != 3)
            continue;
        red++;
        int in_half = 0;
        for (int h = 0; h < 2; h++) {
            tb_vec3 A = room_pos[halves[h][0]], B = room_pos[halves[h][1]], C = room_pos[halves[h][2]];
            tb_vec3 n = tb_vec3_normalize(tb_vec3_cross(tb_vec3_sub(B, A), tb_vec3_sub(C, A)));
            bool all = true;
            for (int k = 0; k < tb_mesh_elem_size(e); k++)
                all &= fabs(tb_vec3_dot(n, tb_vec3_sub(TB_ARRAY_AT(&m.positions, tb_vec3, e->v[k]), A))) < 1e-3;
            in_half += all;
        }
        assert_int_equal(in_half, 1);
    }
    assert_true(red > 2);
    assert_int_equal(floor_quads, 36);
    tb_mesh_free(&m);
    tb_fed_free(f);
}

/* The room's floor (face 0, a planar convex quad whose opposite sides are
 * 552.8 and 549.6 mm, 559.2 and 559.21) is a grid of quads at every bound:
 * where the two lengths round to different part counts (55 mm: 11 and 10)
 * both sides take the larger, so the floor's element count never rises as
 * the bound grows (it once jumped from 169 at 45 mm to 1537 at 55 mm, the
 * floor triangulated and bisected), and the whole mesh stays conforming. */
static void test_quad_sides_matched(void **state)
{
    (void)state;
    tb_fed *f = fed_from(room_pos, 8, room_faces);
    size_t last = SIZE_MAX;
    for (double edge = 40; edge <= 80; edge += 2.5) {
        tb_mesh m;
        tb_mesh_init(&m);
        tb_mesh_opts o = {.max_edge = edge, .quads = true};
        assert_int_equal(tb_mesh_from_fed(f, &o, &m), TB_OK);
        check_mesh(f, &m, (check){edge, true});
        size_t floor_elems = 0, floor_quads = 0;
        for (size_t i = 0; i < tb_mesh_nelems(&m); i++) {
            const tb_mesh_elem *e = tb_mesh_elem_at(&m, i);
            floor_elems += e->face == 0;
            floor_quads += e->face == 0 && tb_mesh_elem_size(e) == 4;
        }
        /* x: the floor's 552.8 and 549.6 mm sides, tied through the back wall and
         * the ceiling to their 556 mm sides; z: 559.2 and 559.21 mm */
        size_t k = (size_t)ceil(556.0 / edge), kz = (size_t)ceil(559.21 / edge);
        if (floor_quads != floor_elems || floor_elems != k * kz)
            fail_msg("edge %g: floor %zu elements, %zu quads; expected a %zu x %zu grid", edge, floor_elems,
                     floor_quads, k, kz);
        if (floor_elems > last)
            fail_msg("edge %g: floor %zu elements, more than %zu at a smaller bound", edge, floor_elems, last);
        last = floor_elems;
        tb_mesh_free(&m);
    }
    tb_fed_free(f);
}

static void test_subdivide_faces(void **state)
{
    (void)state;
    tb_mesh m;
    tb_mesh_init(&m);
    /* An equilateral triangle: k = 10 on every side, the regular pattern of 100. */
    const tb_vec3 tri[3] = {{0, 0, 0}, {1, 0, 0}, {0.5f, 0.8660254f, 0}};
    const int t1[] = {0, 1, 2, -1, -9};
    tb_fed *f = fed_from(tri, 3, t1);
    tb_mesh_opts o = {.max_edge = 0.1};
    assert_int_equal(tb_mesh_from_fed(f, &o, &m), TB_OK);
    assert_int_equal(tb_mesh_nelems(&m), 100);
    assert_int_equal(m.positions.len, 66); /* (k+1)(k+2)/2 */
    check_mesh(f, &m, (check){0.1, false});
    o.quads = true;
    assert_int_equal(tb_mesh_from_fed(f, &o, &m), TB_OK);
    assert_int_equal(count_quads(&m), 45); /* every rhombus of two triangles; the 10 on the diagonal stay */
    check_mesh(f, &m, (check){0.1, true});
    tb_fed_free(f);

    /* A trapezoid (sides 4, 2.06, 2, 2.06: mismatched parts) and an L-shaped
     * hexagon with a hole: the general path. */
    const tb_vec3 tz[4] = {{0, 0, 0}, {4, 0, 0}, {3, 1.8f, 0}, {1, 1.8f, 0}};
    const int tzf[] = {0, 1, 2, 3, -1, -9};
    f = fed_from(tz, 4, tzf);
    for (int q = 0; q < 2; q++) {
        tb_mesh_opts ot = {.max_edge = 0.37, .quads = q};
        assert_int_equal(tb_mesh_from_fed(f, &ot, &m), TB_OK);
        check_mesh(f, &m, (check){0.37, q});
    }
    tb_fed_free(f);
    const tb_vec3 ls[10] = {{0, 0, 2}, {4, 0, 2}, {4, 2, 2}, {2, 2, 2}, {2, 4, 2}, {0, 4, 2},
                            {0.5f, 0.5f, 2}, {0.5f, 1.5f, 2}, {1.5f, 1.5f, 2}, {1.5f, 0.5f, 2}};
    const int lsf[] = {0, 1, 2, 3, 4, 5, -2, 6, 7, 8, 9, -1, -9};
    f = fed_from(ls, 10, lsf);
    for (int q = 0; q < 2; q++) {
        tb_mesh_opts ol = {.max_edge = 0.3, .quads = q};
        assert_int_equal(tb_mesh_from_fed(f, &ol, &m), TB_OK);
        check_mesh(f, &m, (check){0.3, q});
    }
    tb_fed_free(f);
    tb_mesh_free(&m);
}

static void test_hole_touching_boundary(void **state)
{
    (void)state;
    /* A hole touching the outer loop at vertex 0 (the same index in both
     * loops), and a second hole touching the first at vertex 5. */
    const tb_vec3 p[9] = {{0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}, {1, 2, 0},
                          {2, 1, 0}, {3, 1.5f, 0}, {3, 0.5f, 0}, {0, 0, 0}};
    const int faces[] = {0, 1, 2, 3, -2, 0, 4, 5, -2, 5, 6, 7, -1, -9};
    tb_fed *f = fed_from(p, 8, faces);
    tb_mesh m;
    tb_mesh_init(&m);
    const double bounds[3] = {0, 0.9, 0.3};
    for (int k = 0; k < 3; k++)
        for (int q = 0; q < 2; q++) {
            tb_mesh_opts o = {.max_edge = bounds[k], .quads = q};
            assert_int_equal(tb_mesh_from_fed(f, &o, &m), TB_OK);
            check_mesh(f, &m, (check){bounds[k], q});
        }
    /* without subdivision: 4 + 3 + 3 corners, the holes spliced, no bridge: 8 triangles */
    assert_int_equal(tb_mesh_from_fed(f, NULL, &m), TB_OK);
    assert_int_equal(tb_mesh_nelems(&m), 8);
    tb_mesh_free(&m);
    tb_fed_free(f);
}

static void test_attributes_interpolated(void **state)
{
    (void)state;
    /* uv = (x/4, y/3) at the corners of a 4 x 3 rectangle; interpolation
     * along edges, grids and bisections keeps uv = (x/4, y/3) everywhere. */
    const tb_vec3 p[5] = {{0, 0, 0}, {4, 0, 0}, {4, 3, 0}, {0, 3, 0}, {2, 4, 0}};
    const tb_vec2 uv[5] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0.5f, 4.0f / 3}};
    const tb_vec3 nrm[5] = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    const uint32_t sizes[2] = {4, 3}, corners[7] = {0, 1, 2, 3, 3, 2, 4};
    tb_fed_desc d = {.nverts = 5, .positions = p, .normals = nrm, .uvs = uv, .nfaces = 2, .nloops = 2,
                     .loop_sizes = sizes, .corners = corners};
    tb_fed *f;
    assert_int_equal(tb_fed_build(&d, &f, NULL), TB_OK);
    tb_mesh m;
    tb_mesh_init(&m);
    tb_mesh_opts o = {.max_edge = 0.3};
    assert_int_equal(tb_mesh_from_fed(f, &o, &m), TB_OK);
    assert_int_equal(m.uvs.len, m.positions.len);
    assert_int_equal(m.normals.len, m.positions.len);
    for (size_t v = 0; v < m.positions.len; v++) {
        tb_vec3 q = TB_ARRAY_AT(&m.positions, tb_vec3, v);
        tb_vec2 t = TB_ARRAY_AT(&m.uvs, tb_vec2, v);
        tb_assert_near(t.x, q.x / 4, 1e-6);
        tb_assert_near(t.y, q.y / 3, 1e-6);
        tb_vec3 n = TB_ARRAY_AT(&m.normals, tb_vec3, v);
        assert_true(n.x == 0 && n.y == 0 && n.z == 1);
    }
    check_mesh(f, &m, (check){0.3, false});
    tb_mesh_free(&m);
    tb_fed_free(f);
}

static void test_random_faces(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("mesh_random", 61), 7);
    tb_mesh m;
    tb_mesh_init(&m);
    for (int t = 0; t < 40; t++) {
        /* Two faces sharing the side (-1,0)-(1,0) in a random plane: a
         * random upper half-disc polygon with a square hole, and a random
         * lower one. */
        tb_vec3 p[64];
        uint32_t n = 5 + tb_rng_below(&rng, 10), nv = 0;
        double ang[32];
        for (uint32_t k = 0; k < n; k++)
            ang[k] = TB_PI * (k + 0.9 * tb_rng_double(&rng)) / n; /* a half disc: first face */
        /* frame: random orthonormal basis */
        tb_vec3 a = tb_vec3_normalize(tb_vec3_make(tb_rng_float(&rng) - 0.5f, tb_rng_float(&rng) - 0.5f, tb_rng_float(&rng) - 0.5f));
        tb_vec3 b, c3;
        tb_vec3_basis(a, &b, &c3);
        tb_vec3 o = tb_vec3_make(3 * tb_rng_float(&rng), 3 * tb_rng_float(&rng), 3 * tb_rng_float(&rng));
#define PT(x, y) tb_vec3_add(o, tb_vec3_add(tb_vec3_scale(b, (float)(x)), tb_vec3_scale(c3, (float)(y))))
        p[nv++] = PT(-1, 0); /* 0 */
        p[nv++] = PT(1, 0);  /* 1 */
        for (uint32_t k = 0; k < n; k++) {
            double r = 0.8 + 0.2 * tb_rng_double(&rng);
            p[nv++] = PT(r * cos(ang[k] + 0.01) * 0.95, r * sin(ang[k] + 0.01) * 0.95 + 0.001);
        }
        /* second face below the x axis: 1 -> (points) -> 0 */
        uint32_t m2 = 3 + tb_rng_below(&rng, 5), first2 = nv;
        for (uint32_t k = 0; k < m2; k++) {
            double ag = -TB_PI * (k + 0.5) / m2;
            p[nv++] = PT(cos(ag) * 0.9, sin(ag) * 0.9);
        }
        uint32_t hole = nv;
        for (uint32_t k = 0; k < 4; k++) {
            double ag = -TB_PI_2 * k;
            p[nv++] = PT(0.15 * cos(ag), 0.4 + 0.15 * sin(ag));
        }
#undef PT
        int spec[128], s = 0;
        /* face 1: 0 -> 1 is the shared side, then the half-disc points from
         * angle near 0 to near pi: counter-clockwise about b x c3; the hole
         * runs clockwise */
        spec[s++] = 0;
        spec[s++] = 1;
        for (uint32_t k = 0; k < n; k++)
            spec[s++] = (int)(2 + k);
        spec[s++] = -2;
        for (uint32_t k = 0; k < 4; k++)
            spec[s++] = (int)(hole + k);
        spec[s++] = -1;
        /* face 2: 1 -> 0 (the shared side, opposite way), then the lower
         * points from near -pi to near 0: counter-clockwise too */
        spec[s++] = 1;
        spec[s++] = 0;
        for (uint32_t k = m2; k-- > 0;)
            spec[s++] = (int)(first2 + k);
        spec[s++] = -1;
        spec[s++] = -9;
        tb_fed *f = fed_from(p, nv, spec);
        tb_fed_report r;
        tb_fed_check(f, &r);
        assert_int_equal(r.counts[TB_FED_ISSUE_ORIENTATION], 0);
        double L = 0.05 + 0.4 * tb_rng_double(&rng);
        tb_mesh_opts op = {.max_edge = L, .quads = tb_rng_below(&rng, 2)};
        assert_int_equal(tb_mesh_from_fed(f, &op, &m), TB_OK);
        check_mesh(f, &m, (check){L, op.quads});
        tb_fed_free(f);
    }
    tb_mesh_free(&m);
}

static void test_adjacency(void **state)
{
    (void)state;
    /* A subdivided cube: every element edge has exactly two elements, the
     * neighbour across an edge shares its two vertices, and the elements
     * around a grid vertex inside a face are the 4 quads touching it. */
    tb_fed *f = fed_from(cube_pos, 8, cube_quads);
    tb_mesh m;
    tb_mesh_init(&m);
    tb_mesh_opts o = {.max_edge = 0.5, .quads = true};
    assert_int_equal(tb_mesh_from_fed(f, &o, &m), TB_OK);
    tb_fed *adj;
    assert_int_equal(tb_mesh_adjacency(&m, &adj), TB_OK);
    assert_int_equal(adj->nfaces, tb_mesh_nelems(&m));
    assert_true(tb_fed_is_closed(adj));
    for (uint32_t e = 0; e < adj->nedges; e++) {
        uint32_t faces[2];
        assert_int_equal(tb_fed_edge_faces(adj, e, faces, 2), 2);
        for (int k = 0; k < 2; k++) {
            const tb_mesh_elem *el = tb_mesh_elem_at(&m, faces[k]);
            int has = 0;
            for (int c = 0; c < tb_mesh_elem_size(el); c++)
                has += el->v[c] == adj->edges[e].v[0] || el->v[c] == adj->edges[e].v[1];
            assert_int_equal(has, 2);
        }
    }
    uint32_t n, inner = 0;
    for (uint32_t v = 0; v < adj->nverts; v++) {
        tb_fed_vertex_faces(adj, v, &n);
        inner += n == 4;
    }
    assert_int_equal(inner, 6 * 3 * 3 + 12 * 3); /* grid vertices inside faces, and inner edge points */
    tb_fed_free(adj);
    tb_mesh_free(&m);
    tb_fed_free(f);
}

/* The checker itself must catch broken meshes. */
static void test_checker_catches_problems(void **state)
{
    (void)state;
    /* two unit squares side by side: 0 1 4 3 and 1 2 5 4 */
    const tb_vec3 p[6] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}, {1, 1, 0}, {2, 1, 0}};
    const int faces[] = {0, 1, 4, 3, -1, 1, 2, 5, 4, -1, -9};
    tb_fed *f = fed_from(p, 6, faces);
    tb_mesh m;
    tb_mesh_init(&m);
    assert_int_equal(tb_mesh_from_fed(f, NULL, &m), TB_OK);
    check_mesh(f, &m, (check){0, false}); /* the real output passes */
    tb_mesh_elem *e = m.elems.data;
    /* a T-junction: the left square split at the middle of the shared edge
     * (vertex 6 at (1, 0.5)), the right one not */
    tb_mesh bad;
    tb_mesh_init(&bad);
    assert_int_equal(tb_array_push_n(&bad.positions, p, 6), TB_OK);
    tb_vec3 mid = {1, 0.5f, 0};
    assert_int_equal(tb_array_push(&bad.positions, &mid), TB_OK);
    const tb_mesh_elem tj[5] = {{{0, 1, 6, TB_MESH_NONE}, 0, TB_MESH_NONE}, {{0, 6, 4, TB_MESH_NONE}, 0, TB_MESH_NONE},
                                {{0, 4, 3, TB_MESH_NONE}, 0, TB_MESH_NONE}, {{1, 2, 5, TB_MESH_NONE}, 1, TB_MESH_NONE},
                                {{1, 5, 4, TB_MESH_NONE}, 1, TB_MESH_NONE}};
    assert_int_equal(tb_array_push_n(&bad.elems, tj, 5), TB_OK);
    expect_problem(f, &bad, (check){0, false}, "T-junction");
    /* a crack: the right square uses a copy of vertex 1 */
    bad.elems.len = 0;
    bad.positions.len = 6;
    assert_int_equal(tb_array_push(&bad.positions, &p[1]), TB_OK);
    const tb_mesh_elem cr[4] = {{{0, 1, 4, TB_MESH_NONE}, 0, TB_MESH_NONE}, {{0, 4, 3, TB_MESH_NONE}, 0, TB_MESH_NONE},
                                {{6, 2, 5, TB_MESH_NONE}, 1, TB_MESH_NONE}, {{6, 5, 4, TB_MESH_NONE}, 1, TB_MESH_NONE}};
    assert_int_equal(tb_array_push_n(&bad.elems, cr, 4), TB_OK);
    expect_problem(f, &bad, (check){0, false}, "crack");
    /* edges too long, a missing element, a flipped one, a stray quad */
    expect_problem(f, &m, (check){0.9, false}, "long");
    m.elems.len--;
    expect_problem(f, &m, (check){0, false}, "area");
    m.elems.len++;
    uint32_t t = e[0].v[1];
    e[0].v[1] = e[0].v[2], e[0].v[2] = t;
    expect_problem(f, &m, (check){0, false}, "faces away");
    tb_mesh_opts oq = {.quads = true};
    assert_int_equal(tb_mesh_from_fed(f, &oq, &m), TB_OK);
    expect_problem(f, &m, (check){0, false}, "quad");
    tb_mesh_free(&bad);
    tb_mesh_free(&m);
    tb_fed_free(f);
}

static void test_bad_bounds(void **state)
{
    (void)state;
    tb_fed *f = fed_from(cube_pos, 8, cube_quads);
    tb_mesh m;
    tb_mesh_init(&m);
    tb_mesh_opts tiny = {.max_edge = 1e-7};
    assert_int_equal(tb_mesh_from_fed(f, &tiny, &m), TB_ERR_ARG);
    assert_true(strstr(tb_last_error(), "below the float resolution") != NULL);
    tb_mesh_opts many = {.max_edge = 2e-5};
    assert_int_equal(tb_mesh_from_fed(f, &many, &m), TB_ERR_ARG);
    assert_true(strstr(tb_last_error(), "elements") != NULL);
    assert_int_equal(tb_mesh_nelems(&m), 0);
    tb_mesh_opts nan = {.max_edge = NAN};
    assert_int_equal(tb_mesh_from_fed(f, &nan, &m), TB_ERR_ARG);
    tb_mesh_free(&m);
    tb_fed_free(f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cornell_red_wall),
        cmocka_unit_test(test_quad_criterion),
        cmocka_unit_test(test_no_subdivision),
        cmocka_unit_test(test_subdivide_cube),
        cmocka_unit_test(test_subdivide_frame),
        cmocka_unit_test(test_subdivide_cornell_room),
        cmocka_unit_test(test_quad_sides_matched),
        cmocka_unit_test(test_subdivide_faces),
        cmocka_unit_test(test_hole_touching_boundary),
        cmocka_unit_test(test_attributes_interpolated),
        cmocka_unit_test(test_random_faces),
        cmocka_unit_test(test_adjacency),
        cmocka_unit_test(test_checker_catches_problems),
        cmocka_unit_test(test_bad_bounds),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
