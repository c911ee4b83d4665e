/* util/mesh/fed: building, adjacency queries against hand-counted meshes
 * (cube, annulus, grid, torus), Euler characteristics, and every validation
 * rule with its message. */
#include "tb_test.h"

#include <string.h>

#include "util/math/float.h"
#include "util/mesh/fed.h"

/* Builds from a simple description: faces of one loop each. */
static tb_fed *build_simple(const tb_vec3 *pos, uint32_t nv, const uint32_t *sizes, uint32_t nf,
                            const uint32_t *corners)
{
    tb_fed_desc d = {.nverts = nv, .positions = pos, .nfaces = nf, .nloops = nf, .loop_sizes = sizes,
                     .corners = corners};
    tb_fed *m = NULL;
    tb_fed_issue is;
    if (tb_fed_build(&d, &m, &is))
        fail_msg("build: %s", tb_last_error());
    return m;
}

static const tb_vec3 cube_pos[8] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                    {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
/* Outward-facing quads (counter-clockwise seen from outside). */
static const uint32_t cube_faces[24] = {0, 3, 2, 1, 4, 5, 6, 7, 0, 1, 5, 4, 1, 2, 6, 5, 2, 3, 7, 6, 3, 0, 4, 7};
static const uint32_t four[6] = {4, 4, 4, 4, 4, 4};

static void test_cube_queries(void **state)
{
    (void)state;
    tb_fed *m = build_simple(cube_pos, 8, four, 6, cube_faces);
    assert_int_equal(m->nedges, 12);
    assert_true(tb_fed_is_closed(m));
    assert_int_equal(tb_fed_euler_characteristic(m), 2);
    assert_int_equal(tb_fed_count_boundary_edges(m), 0);
    assert_int_equal(tb_fed_count_nonmanifold_edges(m), 0);
    for (uint32_t v = 0; v < 8; v++) {
        uint32_t n;
        const uint32_t *f = tb_fed_vertex_faces(m, v, &n);
        assert_int_equal(n, 3);
        for (uint32_t i = 0; i < n; i++) {
            bool uses = false; /* each listed face really has v */
            for (uint32_t c = tb_fed_face_corner_begin(m, f[i]); c < tb_fed_face_corner_end(m, f[i]); c++)
                uses |= m->corner_vert[c] == v;
            assert_true(uses);
            if (i)
                assert_true(f[i] > f[i - 1]);
        }
    }
    for (uint32_t e = 0; e < m->nedges; e++) {
        assert_int_equal(tb_fed_edge_nuses(m, e), 2);
        assert_true(m->edges[e].v[0] < m->edges[e].v[1]);
        assert_true(tb_fed_edge_use_forward(m, e, 0) != tb_fed_edge_use_forward(m, e, 1));
        uint32_t faces[4];
        assert_int_equal(tb_fed_edge_faces(m, e, faces, 4), 2);
        assert_int_equal(tb_fed_find_edge(m, m->edges[e].v[1], m->edges[e].v[0]), e);
    }
    /* Edge 0-1 is shared by the bottom face (0) and the front face (2). */
    uint32_t e01 = tb_fed_find_edge(m, 0, 1), faces[2];
    assert_true(e01 != TB_FED_NONE);
    assert_int_equal(tb_fed_edge_faces(m, e01, faces, 2), 2);
    assert_int_equal(faces[0], 0);
    assert_int_equal(faces[1], 2);
    assert_int_equal(tb_fed_find_edge(m, 0, 6), TB_FED_NONE); /* a diagonal is no edge */
    /* Every face has 4 edges (corner_edge), each joining its corner to the next. */
    for (uint32_t f = 0; f < 6; f++) {
        assert_int_equal(tb_fed_face_corner_end(m, f) - tb_fed_face_corner_begin(m, f), 4);
        for (uint32_t c = tb_fed_face_corner_begin(m, f); c < tb_fed_face_corner_end(m, f); c++) {
            const tb_fed_edge *e = &m->edges[m->corner_edge[c]];
            uint32_t a = m->corner_vert[c], b = m->corner_vert[tb_fed_corner_next(m, c)];
            assert_true((e->v[0] == a && e->v[1] == b) || (e->v[0] == b && e->v[1] == a));
        }
        /* outward normals of area 4 */
        tb_dvec3 n = tb_fed_face_normal(m, f);
        tb_vec3 ctr = {0, 0, 0};
        for (uint32_t k = 0; k < 4; k++)
            ctr = tb_vec3_add(ctr, m->positions[tb_fed_loop_vertex(m, tb_fed_face_outer(m, f), k)]);
        assert_true(n.x * ctr.x + n.y * ctr.y + n.z * ctr.z > 0);
        tb_assert_near(tb_fed_face_area(m, f), 4.0, 1e-12);
    }
    tb_fed_report r;
    assert_int_equal(tb_fed_check(m, &r), 0);
    assert_true(r.closed);
    tb_fed_free(m);
}

static void test_annulus_grid_torus(void **state)
{
    (void)state;
    /* A square with a square hole: one face, two loops. V - E + F - H = 8 - 8 + 1 - 1 = 0. */
    const tb_vec3 p[8] = {{0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}, {1, 1, 0}, {1, 3, 0}, {3, 3, 0}, {3, 1, 0}};
    const uint32_t nl[1] = {2}, sizes[2] = {4, 4}, corners[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    tb_fed_desc d = {.nverts = 8, .positions = p, .nfaces = 1, .face_nloops = nl, .nloops = 2,
                     .loop_sizes = sizes, .corners = corners};
    tb_fed *m = NULL;
    assert_int_equal(tb_fed_build(&d, &m, NULL), TB_OK);
    assert_int_equal(tb_fed_face_nloops(m, 0), 2);
    assert_int_equal(m->nedges, 8);
    assert_int_equal(tb_fed_count_boundary_edges(m), 8);
    assert_false(tb_fed_is_closed(m));
    assert_int_equal(tb_fed_euler_characteristic(m), 0);
    tb_assert_near(tb_fed_face_area(m, 0), 16.0 - 4.0, 1e-12);
    tb_fed_report r;
    assert_int_equal(tb_fed_check(m, &r), 0); /* the hole runs clockwise: fine */
    assert_int_equal(r.boundary_edges, 8);
    tb_fed_free(m);

    /* An n x n grid of quads (a disc): chi = 1, boundary 4n. And the same
     * grid with opposite sides identified (a torus): closed, chi = 0. */
    enum { N = 7 };
    tb_vec3 gp[(N + 1) * (N + 1)];
    for (int y = 0; y <= N; y++)
        for (int x = 0; x <= N; x++)
            gp[y * (N + 1) + x] = tb_vec3_make((float)x, (float)y, 0);
    uint32_t gc[4 * N * N], gs[N * N], tc[4 * N * N];
    tb_vec3 tp[N * N];
    for (int y = 0; y < N; y++)
        for (int x = 0; x < N; x++) {
            uint32_t *q = &gc[4 * (y * N + x)];
            q[0] = (uint32_t)(y * (N + 1) + x), q[1] = q[0] + 1, q[2] = q[1] + N + 1, q[3] = q[0] + N + 1;
            gs[y * N + x] = 4;
            uint32_t *t = &tc[4 * (y * N + x)];
            t[0] = (uint32_t)(y * N + x), t[1] = (uint32_t)(y * N + (x + 1) % N);
            t[2] = (uint32_t)(((y + 1) % N) * N + (x + 1) % N), t[3] = (uint32_t)(((y + 1) % N) * N + x);
            /* a real torus so that no face is degenerate */
            double u = TB_2PI * x / N, v = TB_2PI * y / N;
            tp[y * N + x] = tb_vec3_make((float)((3 + cos(v)) * cos(u)), (float)((3 + cos(v)) * sin(u)), (float)sin(v));
        }
    m = build_simple(gp, (N + 1) * (N + 1), gs, N * N, gc);
    assert_int_equal(tb_fed_euler_characteristic(m), 1);
    assert_int_equal(tb_fed_count_boundary_edges(m), 4 * N);
    assert_int_equal(m->nedges, 2 * N * (N + 1));
    tb_fed_free(m);
    m = build_simple(tp, N * N, gs, N * N, tc);
    assert_true(tb_fed_is_closed(m));
    assert_int_equal(tb_fed_euler_characteristic(m), 0);
    assert_int_equal(m->nedges, 2 * N * N);
    tb_fed_check(m, &r);
    assert_int_equal(r.counts[TB_FED_ISSUE_ORIENTATION], 0);
    assert_true(r.closed);
    tb_fed_free(m);
}

static void test_warnings(void **state)
{
    (void)state;
    /* Three triangles on edge 0-1 (a fin): non-manifold, 3 faces on the edge. */
    const tb_vec3 p[6] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {5, 5, 5}};
    const uint32_t s3[3] = {3, 3, 3};
    const uint32_t fin[9] = {0, 1, 2, 1, 0, 3, 0, 1, 4};
    tb_fed *m = build_simple(p, 6, s3, 3, fin);
    tb_fed_report r;
    uint32_t n = tb_fed_check(m, &r);
    assert_int_equal(r.counts[TB_FED_ISSUE_NONMANIFOLD], 1);
    assert_int_equal(r.counts[TB_FED_ISSUE_UNUSED_VERTEX], 1); /* vertex 5 */
    assert_int_equal(n, 2);
    uint32_t e = tb_fed_find_edge(m, 0, 1), faces[3];
    assert_true(tb_fed_edge_is_nonmanifold(m, e));
    assert_int_equal(tb_fed_edge_faces(m, e, faces, 3), 3);
    assert_int_equal(tb_fed_count_nonmanifold_edges(m), 1);
    assert_string_equal(r.issues[0].message, "edge 0 (vertices 0-1): used 3 times (non-manifold)");
    assert_string_equal(r.issues[1].message, "vertex 5: used by no face");
    assert_int_equal(r.issues[1].vertex, 5);
    tb_fed_free(m);

    /* Two triangles running the shared edge 0-1 the same way. */
    const uint32_t flip[6] = {0, 1, 2, 0, 1, 3};
    m = build_simple(p, 5, s3, 2, flip);
    tb_fed_check(m, &r);
    assert_int_equal(r.counts[TB_FED_ISSUE_ORIENTATION], 1);
    assert_string_equal(r.issues[0].message,
                        "edge 0 (vertices 0-1): faces 0 and 1 both run it from vertex 0 (inconsistent orientation)");
    assert_false(r.closed);
    tb_fed_free(m);

    /* A hole turning the same way as its outer loop. */
    const tb_vec3 q[8] = {{0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}, {1, 1, 0}, {3, 1, 0}, {3, 3, 0}, {1, 3, 0}};
    const uint32_t nl[1] = {2}, sizes[2] = {4, 4}, corners[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    tb_fed_desc d = {.nverts = 8, .positions = q, .nfaces = 1, .face_nloops = nl, .nloops = 2,
                     .loop_sizes = sizes, .corners = corners};
    assert_int_equal(tb_fed_build(&d, &m, NULL), TB_OK);
    tb_fed_check(m, &r);
    assert_int_equal(r.counts[TB_FED_ISSUE_HOLE_ORIENTATION], 1);
    assert_string_equal(r.issues[0].message,
                        "face 0 (hole 1): turns the same way as the outer loop (holes run opposite)");
    tb_fed_free(m);

    /* The Cornell box red wall: its fourth vertex is ~3 mm off the plane. */
    const tb_vec3 red[4] = {{552.8f, 0, 0}, {549.6f, 0, 559.2f}, {556, 548.8f, 559.2f}, {556, 548.8f, 0}};
    const uint32_t s4[1] = {4}, quad[4] = {0, 1, 2, 3};
    m = build_simple(red, 4, s4, 1, quad);
    tb_fed_check(m, &r);
    assert_int_equal(r.counts[TB_FED_ISSUE_NONPLANAR], 1);
    assert_int_equal(r.issues[0].face, 0);
    tb_fed_free(m);
}

/* Expects tb_fed_build to fail with `kind` and exactly `message`. */
static void expect_fatal(const tb_fed_desc *d, tb_fed_issue_kind kind, const char *message)
{
    tb_fed *m = (tb_fed *)1;
    tb_fed_issue is;
    tb_status st = tb_fed_build(d, &m, &is);
    assert_int_equal(st, TB_ERR_FORMAT);
    assert_null(m);
    assert_true(tb_fed_issue_fatal(is.kind));
    assert_int_equal(is.kind, kind);
    assert_string_equal(is.message, message);
    assert_string_equal(tb_last_error(), message);
}

static void test_fatal_errors(void **state)
{
    (void)state;
    tb_vec3 p[6] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {2, 2, 0}, {1, 0, 0}};
    uint32_t sizes[2] = {3, 4}, nl[1] = {2};
    tb_fed_desc d = {.nverts = 5, .positions = p, .nfaces = 2, .nloops = 2, .loop_sizes = sizes};

    uint32_t bad_index[7] = {0, 1, 2, 0, 1, 9, 3};
    d.corners = bad_index;
    expect_fatal(&d, TB_FED_ISSUE_INDEX, "face 1 (outer loop), corner 2: vertex index 9 out of range (5 vertices)");
    tb_fed_issue is;
    tb_fed *m;
    tb_fed_build(&d, &m, &is);
    assert_int_equal(is.face, 1);
    assert_int_equal(is.loop, 1);
    assert_int_equal(is.corner, 5);
    assert_int_equal(is.vertex, 9);

    uint32_t repeated[7] = {0, 1, 2, 0, 1, 1, 2};
    d.corners = repeated;
    expect_fatal(&d, TB_FED_ISSUE_REPEATED_VERTEX, "face 1 (outer loop), corner 1: vertex 1 repeated at the next corner");
    uint32_t wrap[7] = {0, 1, 0, 0, 1, 2, 3}; /* last corner equals the first */
    d.corners = wrap;
    expect_fatal(&d, TB_FED_ISSUE_REPEATED_VERTEX, "face 0 (outer loop), corner 2: vertex 0 repeated at the next corner");

    d.nverts = 6; /* vertex 5 sits where vertex 1 is */
    uint32_t zero_edge[7] = {0, 1, 2, 0, 1, 5, 2};
    d.corners = zero_edge;
    expect_fatal(&d, TB_FED_ISSUE_ZERO_EDGE,
                 "face 1 (outer loop), corner 1: vertices 1 and 5 are at the same position (zero-length edge)");
    d.nverts = 5;

    uint32_t two[7] = {0, 1, 2, 0, 1, 0, 1};
    d.corners = two;
    expect_fatal(&d, TB_FED_ISSUE_FEW_VERTICES, "face 1 (outer loop): only 2 distinct vertices (at least 3 needed)");

    uint32_t collinear[7] = {0, 2, 4, 0, 1, 2, 3}; /* (0,0) (1,1) (2,2) */
    d.corners = collinear;
    expect_fatal(&d, TB_FED_ISSUE_DEGENERATE, "face 0 (outer loop): zero area (degenerate: 0 relative to its size squared)");

    /* A degenerate hole, reported as such. */
    uint32_t hs[2] = {4, 3};
    tb_fed_desc dh = {.nverts = 5, .positions = p, .nfaces = 1, .face_nloops = nl, .nloops = 2, .loop_sizes = hs};
    uint32_t hole_deg[7] = {0, 1, 2, 3, 0, 2, 4};
    dh.corners = hole_deg;
    expect_fatal(&dh, TB_FED_ISSUE_DEGENERATE, "face 0 (hole 1): zero area (degenerate: 0 relative to its size squared)");

    uint32_t ok[7] = {0, 1, 2, 0, 1, 2, 3};
    d.corners = ok;
    p[3].y = NAN;
    expect_fatal(&d, TB_FED_ISSUE_NONFINITE, "vertex 3: position is not finite");
    p[3].y = 1;
    tb_vec3 nrm[5] = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, INFINITY}, {0, 0, 1}};
    d.normals = nrm;
    expect_fatal(&d, TB_FED_ISSUE_NONFINITE, "vertex 3: normal is not finite");
    d.normals = NULL;
    tb_vec2 uv[5] = {{0, 0}, {0, 0}, {-INFINITY, 0}, {0, 0}, {0, 0}};
    d.uvs = uv;
    expect_fatal(&d, TB_FED_ISSUE_NONFINITE, "vertex 2: uv is not finite");
    d.uvs = NULL;

    uint32_t short_sizes[2] = {3, 2};
    d.loop_sizes = short_sizes;
    expect_fatal(&d, TB_FED_ISSUE_BAD_COUNT, "face 1 (outer loop): 2 corners (at least 3 needed)");
    d.loop_sizes = sizes;
    uint32_t no_loops[2] = {2, 0};
    tb_fed_desc dz = d;
    dz.face_nloops = no_loops;
    expect_fatal(&dz, TB_FED_ISSUE_BAD_COUNT, "face 1 has no loop");
    dz.face_nloops = NULL;
    dz.nloops = 3;
    expect_fatal(&dz, TB_FED_ISSUE_BAD_COUNT, "3 loops for 2 faces of one loop each");

    /* Missing arrays are argument errors. */
    tb_fed_desc bad = {.nverts = 3};
    assert_int_equal(tb_fed_build(&bad, &m, NULL), TB_ERR_ARG);

    /* The same mesh without mistakes builds. */
    assert_int_equal(tb_fed_build(&d, &m, NULL), TB_OK);
    assert_int_equal(m->nfaces, 2);
    tb_fed_free(m);
}

static void test_touching_hole_shares_vertex(void **state)
{
    (void)state;
    /* A hole touching the outer loop at vertex 0 (the same index in both
     * loops) is valid; the vertex lists the face once. */
    const tb_vec3 p[6] = {{0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}, {1, 2, 0}, {2, 1, 0}};
    const uint32_t nl[1] = {2}, sizes[2] = {4, 3}, corners[7] = {0, 1, 2, 3, 0, 4, 5};
    tb_fed_desc d = {.nverts = 6, .positions = p, .nfaces = 1, .face_nloops = nl, .nloops = 2,
                     .loop_sizes = sizes, .corners = corners};
    tb_fed *m;
    assert_int_equal(tb_fed_build(&d, &m, NULL), TB_OK);
    uint32_t n;
    const uint32_t *f = tb_fed_vertex_faces(m, 0, &n);
    assert_int_equal(n, 1);
    assert_int_equal(f[0], 0);
    tb_assert_near(tb_fed_face_area(m, 0), 16.0 - 1.5, 1e-12);
    tb_fed_free(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cube_queries),
        cmocka_unit_test(test_annulus_grid_torus),
        cmocka_unit_test(test_warnings),
        cmocka_unit_test(test_fatal_errors),
        cmocka_unit_test(test_touching_hole_shares_vertex),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
