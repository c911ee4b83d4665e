/* util/mesh/fed files: the text and binary readers (a test per error
 * message, with its location), and round trips memory -> text -> memory,
 * memory -> binary -> memory and text <-> binary on random meshes. */
#include "tb_test.h"

#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "util/mesh/fed.h"

/* ------------------------------------------------------------------ helpers */

static tb_status read_text_str(const char *text, size_t len, tb_fed **m)
{
    FILE *f = len ? fmemopen((void *)text, len, "rb") : fopen("/dev/null", "rb");
    assert_non_null(f);
    tb_status st = tb_fed_read_text(f, "t.fed", m);
    fclose(f);
    return st;
}

static void expect_text_error(const char *text, const char *message)
{
    tb_fed *m = (tb_fed *)1;
    tb_status st = read_text_str(text, strlen(text), &m);
    if (st != TB_ERR_FORMAT)
        fail_msg("input %s: status %d (%s), expected a format error", text, st, tb_last_error());
    assert_null(m);
    if (strcmp(tb_last_error(), message) != 0)
        fail_msg("input:\n%s\nmessage:  %s\nexpected: %s", text, tb_last_error(), message);
}

/* A growable byte buffer for crafting binary files. */
typedef struct bytes {
    unsigned char *p;
    size_t n, cap;
} bytes;

static void put(bytes *b, const void *src, size_t n)
{
    if (b->n + n > b->cap) {
        b->cap = (b->n + n) * 2 + 64;
        b->p = realloc(b->p, b->cap);
        assert_non_null(b->p);
    }
    memcpy(b->p + b->n, src, n);
    b->n += n;
}

static void put_u32(bytes *b, uint32_t v)
{
    unsigned char c[4] = {(unsigned char)v, (unsigned char)(v >> 8), (unsigned char)(v >> 16), (unsigned char)(v >> 24)};
    put(b, c, 4);
}

static void put_f32(bytes *b, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    put_u32(b, u);
}

/* Header: magic, version 1, flags, counts, uniform loop size. */
static void put_header(bytes *b, uint32_t flags, uint32_t nv, uint32_t nf, uint32_t nl, uint32_t nc, uint32_t loop_size)
{
    put(b, TB_FED_BINARY_MAGIC, 8);
    put_u32(b, 1);
    put_u32(b, flags);
    put_u32(b, nv);
    put_u32(b, nf);
    put_u32(b, nl);
    put_u32(b, nc);
    put_u32(b, loop_size);
}

static tb_status read_binary_bytes(const bytes *b, tb_fed **m)
{
    FILE *f = fmemopen(b->p, b->n, "rb");
    assert_non_null(f);
    tb_status st = tb_fed_read_binary(f, "b.fedb", m);
    fclose(f);
    return st;
}

static void expect_binary_error(bytes *b, const char *message)
{
    tb_fed *m = (tb_fed *)1;
    tb_status st = read_binary_bytes(b, &m);
    if (st != TB_ERR_FORMAT)
        fail_msg("status %d (%s), expected a format error", st, tb_last_error());
    assert_null(m);
    if (strcmp(tb_last_error(), message) != 0)
        fail_msg("message:  %s\nexpected: %s", tb_last_error(), message);
    free(b->p);
    *b = (bytes){0};
}

/* ---------------------------------------------------------------- text form */

static void test_text_example(void **state)
{
    (void)state;
    const char *text = "fed 1\r\n"
                       "# a square with a triangular hole, and a triangle\n"
                       "vertices 7   # positions\n"
                       "0 0 0\n4 0 0\n4 4 0\n0 4 0\n"
                       "1 1 0\n 1.5 3 0 \n3 1 0\n"
                       "\n"
                       "normals 7\n0 0 1\n0 0 1\n0 0 1\n0 0 1\n0 0 1\n0 0 1\n0 0 1\n"
                       "uvs 7\n0 0\n1 0\n1 1\n0 1\n.25 .25\n0.375 0.75\n0.75 +0.25e0\n"
                       "faces 2\n"
                       "0 1 2 3 hole 4 5 6 id 7 material 2\n"
                       "4 6 1 material -1\n";
    tb_fed *m;
    if (read_text_str(text, strlen(text), &m))
        fail_msg("%s", tb_last_error());
    assert_int_equal(m->nverts, 7);
    assert_int_equal(m->nfaces, 2);
    assert_int_equal(m->nloops, 3);
    assert_int_equal(m->ncorners, 10);
    assert_true(m->positions[5].x == 1.5f && m->positions[5].y == 3.0f);
    assert_non_null(m->normals);
    assert_true(m->uvs[6].x == 0.75f && m->uvs[6].y == 0.25f && m->uvs[4].x == 0.25f);
    assert_int_equal(tb_fed_face_nloops(m, 0), 2);
    assert_int_equal(tb_fed_loop_vertex(m, 1, 1), 5);
    /* ids appear when any face has one; faces without get 0 */
    assert_non_null(m->face_ids);
    assert_int_equal(m->face_ids[0], 7);
    assert_int_equal(m->face_ids[1], 0);
    assert_int_equal(m->face_materials[0], 2);
    assert_int_equal(m->face_materials[1], -1);
    tb_fed_free(m);
}

static void test_text_errors(void **state)
{
    (void)state;
    expect_text_error("", "t.fed:1:1: error: expected the header 'fed 1' at the start of the file, found end of file");
    expect_text_error("mid 1\n", "t.fed:1:1: error: expected the header 'fed 1' at the start of the file, found 'mid'");
    expect_text_error("# fed\nfed 1\n", "t.fed:1:6: error: expected the header 'fed 1' at the start of the file, found end of line");
    expect_text_error("fed\n", "t.fed:1:4: error: expected a version number after 'fed', found end of line");
    expect_text_error("fed 2\n", "t.fed:1:5: error: unsupported FED version 2 (this reader reads FED 1)");
    expect_text_error("fed 1 x\n", "t.fed:1:7: error: expected end of line after the header, found 'x'");
    expect_text_error("fed 1\nfaces 0\n", "t.fed:2:1: error: expected 'vertices COUNT', found 'faces'");
    expect_text_error("fed 1\nvertices -1\n",
                      "t.fed:2:10: error: a count of vertices -1 out of range (0 to 2147483647)");
    expect_text_error("fed 1\nvertices 2147483648\n",
                      "t.fed:2:10: error: a count of vertices 2147483648 out of range (0 to 2147483647)");
    expect_text_error("fed 1\nvertices 3 4\n", "t.fed:2:12: error: expected end of line after 'vertices 3', found '4'");
    expect_text_error("fed 1\nvertices 2\n0 0 0\n", "t.fed:4:1: error: expected vertex 1 of 2 (3 numbers), found end of file");
    /* a hostile count: nothing is allocated for it, the file just ends */
    expect_text_error("fed 1\nvertices 2000000000\n0 0 0\n",
                      "t.fed:4:1: error: expected vertex 1 of 2000000000 (3 numbers), found end of file");
    expect_text_error("fed 1\nvertices 1\n0 0\n", "t.fed:3:4: error: vertex 0: expected 3 numbers, found 2");
    expect_text_error("fed 1\nvertices 1\n0 0 x\n", "t.fed:3:5: error: vertex 0: expected 3 numbers, found 2");
    expect_text_error("fed 1\nvertices 1\n0 0 0 0\n",
                      "t.fed:3:7: error: expected end of line after vertex 0 (3 numbers per line), found '0'");
    expect_text_error("fed 1\nvertices 1\n0 0 1e39\n",
                      "t.fed:3:5: error: number 1e39 out of range for a float (largest 3.40282e+38)");
    expect_text_error("fed 1\nvertices 1\n0 0 1.5.2\n", "t.fed:3:5: error: malformed number '1.5.2'");
    expect_text_error("fed 1\nvertices 1\n0 0 -\n", "t.fed:3:5: error: malformed number '-'");
    expect_text_error("fed 1\nvertices 1\n0 0 nan\n", "t.fed:3:5: error: vertex 0: expected 3 numbers, found 2");
    expect_text_error("fed 1\nvertices 0\nedges 0\n",
                      "t.fed:3:1: error: unknown section 'edges' (expected 'normals', 'uvs' or 'faces')");
    expect_text_error("fed 1\nvertices 0\n5\n", "t.fed:3:1: error: expected 'normals', 'uvs' or 'faces', found '5'");
    expect_text_error("fed 1\nvertices 1\n0 0 0\nnormals 2\n", "t.fed:4:1: error: 'normals 2' does not match the 1 vertices");
    expect_text_error("fed 1\nvertices 0\nuvs 0\nnormals 0\n",
                      "t.fed:4:1: error: section 'normals' out of order or repeated (order: vertices, normals, uvs, faces)");
    expect_text_error("fed 1\nvertices 1\n0 0 0\nuvs 1\n0\n", "t.fed:5:2: error: uv 0: expected 2 numbers, found 1");
    expect_text_error("fed 1\nvertices 0\nfaces 0\n@", "t.fed:4:1: error: unexpected character '@'");
    expect_text_error("fed 1\n\xc3\xa9\n", "t.fed:2:1: error: unexpected byte 0xc3 (outside comments only ASCII is allowed)");
    expect_text_error("fed 1 # \xc3\xa9 is fine here\nvert-ices 0\n", "t.fed:2:1: error: malformed word 'vert-ices'");
    char longtok[300] = "fed 1\nvertices 1\n";
    size_t n = strlen(longtok);
    memset(longtok + n, '1', 200);
    strcpy(longtok + n + 200, " 0 0\n");
    expect_text_error(longtok, "t.fed:3:1: error: token too long (more than 128 bytes)");

    const char *tri = "fed 1\nvertices 3\n0 0 0\n1 0 0\n0 1 0\nfaces 1\n";
    const struct {
        const char *face, *message;
    } faces[] = {
        {"0 1 3\n", "t.fed:7:5: error: vertex index 3 out of range (3 vertices)"},
        {"0 1 -2\n", "t.fed:7:5: error: vertex index -2 out of range (0 to 2147483647)"},
        {"0 1\n", "t.fed:7:1: error: face 0: a loop needs at least 3 vertices, found 2"},
        {"id 5\n", "t.fed:7:1: error: face 0: expected vertex indices, found 'id'"},
        {"0 1 2 hole 0 1\n", "t.fed:7:7: error: face 0: a hole needs at least 3 vertices, found 2"},
        {"0 1 2 foo\n", "t.fed:7:7: error: face 0: expected 'hole', 'id', 'material' or end of line, found 'foo'"},
        {"0 1 2 id 1 id 2\n", "t.fed:7:12: error: face 0: 'id' given twice"},
        {"0 1 2 id x\n", "t.fed:7:10: error: expected face id, found 'x'"},
        {"0 1 2 id\n", "t.fed:7:9: error: expected face id, found end of line"},
        {"0 1 2 material 3000000000\n",
         "t.fed:7:16: error: material index 3000000000 out of range (-2147483648 to 2147483647)"},
        {"0 1 2 id 1 hole 0 1 2\n", "t.fed:7:12: error: face 0: 'hole' after 'id' or 'material' (holes come first)"},
        {"", "t.fed:7:1: error: unexpected end of file: 0 of 1 faces read"},
        {"0 1 2\n0 1 2\n", "t.fed:8:1: error: expected end of file after the 1 faces, found '0'"},
        /* problems found when the mesh is built, located at the loop */
        {"  0 1 0\n", "t.fed:7:3: error: face 0 (outer loop), corner 2: vertex 0 repeated at the next corner"},
        {"0 1 0 1\n", "t.fed:7:1: error: face 0 (outer loop): only 2 distinct vertices (at least 3 needed)"},
        {"0 1 2 hole 0 1 1\n", "t.fed:7:12: error: face 0 (hole 1), corner 1: vertex 1 repeated at the next corner"},
        {"0 1 2 hole 2 1 0 1\n",
         "t.fed:7:12: error: face 0 (hole 1): zero area (degenerate: 0 relative to its size squared)"},
    };
    for (size_t k = 0; k < sizeof faces / sizeof faces[0]; k++) {
        char buf[256];
        snprintf(buf, sizeof buf, "%s%s", tri, faces[k].face);
        expect_text_error(buf, faces[k].message);
    }
    expect_text_error("fed 1\nvertices 4\n0 0 0\n1 1 1\n2 2 2\n1 0 0\nfaces 2\n0 1 3\n  0 1 2\n",
                      "t.fed:9:3: error: face 1 (outer loop): zero area (degenerate: 0 relative to its size squared)");
    expect_text_error("fed 1\nvertices 4\n0 0 0\n1 0 0\n1 0 0\n0 1 0\nfaces 1\n0 1 2 3\n",
                      "t.fed:8:1: error: face 0 (outer loop), corner 1: vertices 1 and 2 are at the same position "
                      "(zero-length edge)");
    expect_text_error("fed 1\nvertices 3\n0 0 0\n1 0 0\n0 1 0\nfaces 1\n0 1 2 hole 0 1 0 1\n",
                      "t.fed:7:12: error: face 0 (hole 1): only 2 distinct vertices (at least 3 needed)");
}

/* -------------------------------------------------------------- binary form */

static void test_binary_errors(void **state)
{
    (void)state;
    bytes b = {0};
    put(&b, "fed 1\nvertices 0\n", 17);
    expect_binary_error(&b, "b.fedb: byte 0: error: not a binary FED file (bad magic number)");
    put(&b, TB_FED_BINARY_MAGIC, 8);
    put_u32(&b, 1);
    expect_binary_error(&b, "b.fedb: byte 12: error: file ends inside the 36-byte header");
    put_header(&b, 0, 0, 0, 0, 0, 3);
    b.p[8] = 2;
    expect_binary_error(&b, "b.fedb: byte 8: error: unsupported FED version 2 (this reader reads version 1)");
    put_header(&b, 0x30, 0, 0, 0, 0, 3);
    expect_binary_error(&b, "b.fedb: byte 12: error: unknown flag bits 0x30");
    put_header(&b, 0, 0x80000000u, 0, 0, 0, 3);
    expect_binary_error(&b, "b.fedb: byte 16: error: vertex count 2147483648 out of range (at most 2147483647)");
    put_header(&b, 0, 0, 2, 1, 3, 3);
    expect_binary_error(&b, "b.fedb: byte 24: error: 1 loops for 2 faces (every face has at least one)");
    put_header(&b, 0, 0, 0, 1, 0, 0);
    expect_binary_error(&b, "b.fedb: byte 24: error: 1 loops but no faces");
    put_header(&b, 0, 3, 1, 1, 2, 2);
    expect_binary_error(&b, "b.fedb: byte 32: error: uniform loop size 2 does not fit 1 loops and 2 corners (sizes are >= 3)");
    put_header(&b, 0, 3, 1, 2, 5, 0);
    expect_binary_error(&b, "b.fedb: byte 28: error: 5 corners cannot make 2 loops of at least 3");
    /* A hostile header asking for 2^31 - 1 vertices in a 36-byte file: the
     * size check comes first (under ASan a 25 GB allocation would abort). */
    put_header(&b, 0, 0x7fffffff, 1, 1, 3, 3);
    expect_binary_error(&b, "b.fedb: byte 36: error: the file is 36 bytes, but its header describes 25769803812");

    /* Valid framing around bad values. */
    const float tri[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    put_header(&b, 0, 3, 1, 1, 3, 3);
    for (int k = 0; k < 9; k++)
        put_f32(&b, tri[k]);
    put_u32(&b, 0), put_u32(&b, 1), put_u32(&b, 2);
    put_u32(&b, 0); /* a trailing byte too many */
    expect_binary_error(&b, "b.fedb: byte 84: error: the file is 88 bytes, but its header describes 84");

    put_header(&b, 0, 3, 1, 1, 3, 3);
    for (int k = 0; k < 9; k++)
        put_f32(&b, tri[k]);
    put_u32(&b, 0), put_u32(&b, 7), put_u32(&b, 2);
    expect_binary_error(&b, "b.fedb: byte 76: error: vertex index 7 out of range (3 vertices)");

    put_header(&b, 0, 3, 1, 1, 3, 3);
    for (int k = 0; k < 9; k++)
        put_f32(&b, k == 4 ? NAN : tri[k]);
    put_u32(&b, 0), put_u32(&b, 1), put_u32(&b, 2);
    expect_binary_error(&b, "b.fedb: byte 48: error: vertex 1: position is not finite");

    put_header(&b, 1, 3, 1, 1, 3, 3); /* with normals */
    for (int k = 0; k < 9; k++)
        put_f32(&b, tri[k]);
    for (int k = 0; k < 9; k++)
        put_f32(&b, k == 8 ? INFINITY : 0.0f);
    put_u32(&b, 0), put_u32(&b, 1), put_u32(&b, 2);
    expect_binary_error(&b, "b.fedb: byte 96: error: vertex 2: normal is not finite");

    put_header(&b, 0, 3, 1, 1, 3, 3);
    for (int k = 0; k < 9; k++)
        put_f32(&b, tri[k]);
    put_u32(&b, 0), put_u32(&b, 1), put_u32(&b, 1);
    expect_binary_error(&b, "b.fedb: byte 76: error: face 0 (outer loop), corner 1: vertex 1 repeated at the next corner");

    put_header(&b, 0, 3, 1, 1, 3, 3);
    for (int k = 0; k < 9; k++)
        put_f32(&b, k < 3 ? 0.0f : 1.0f); /* (0,0,0) (1,1,1) (1,1,1) */
    put_u32(&b, 0), put_u32(&b, 1), put_u32(&b, 2);
    expect_binary_error(&b, "b.fedb: byte 76: error: face 0 (outer loop), corner 1: vertices 1 and 2 are at the same "
                            "position (zero-length edge)");

    const float line[9] = {0, 0, 0, 1, 1, 1, 3, 3, 3};
    put_header(&b, 0, 3, 1, 1, 3, 3);
    for (int k = 0; k < 9; k++)
        put_f32(&b, line[k]);
    put_u32(&b, 0), put_u32(&b, 1), put_u32(&b, 2);
    expect_binary_error(&b, "b.fedb: byte 72: error: face 0 (outer loop): zero area (degenerate: 0 relative to its "
                            "size squared)");

    /* Per-face loop counts (2 faces, 3 loops) and per-loop sizes. */
    put_header(&b, 0, 3, 2, 3, 9, 0);
    for (int k = 0; k < 9; k++)
        put_f32(&b, tri[k]);
    put_u32(&b, 1), put_u32(&b, 0); /* face 1 has no loop */
    put_u32(&b, 3), put_u32(&b, 3), put_u32(&b, 3);
    for (int k = 0; k < 9; k++)
        put_u32(&b, (uint32_t)k % 3);
    expect_binary_error(&b, "b.fedb: byte 76: error: face 1 has no loop");
    put_header(&b, 0, 3, 2, 3, 9, 0);
    for (int k = 0; k < 9; k++)
        put_f32(&b, tri[k]);
    put_u32(&b, 2), put_u32(&b, 2);
    put_u32(&b, 3), put_u32(&b, 3), put_u32(&b, 3);
    for (int k = 0; k < 9; k++)
        put_u32(&b, (uint32_t)k % 3);
    expect_binary_error(&b, "b.fedb: byte 76: error: faces 0..1 already have 4 loops; the header says 3");
    put_header(&b, 0, 3, 2, 3, 9, 0);
    for (int k = 0; k < 9; k++)
        put_f32(&b, tri[k]);
    put_u32(&b, 1), put_u32(&b, 2);
    put_u32(&b, 3), put_u32(&b, 2), put_u32(&b, 4);
    for (int k = 0; k < 9; k++)
        put_u32(&b, (uint32_t)k % 3);
    expect_binary_error(&b, "b.fedb: byte 84: error: loop 1 has 2 corners (at least 3 needed)");
    put_header(&b, 0, 3, 2, 3, 9, 0);
    for (int k = 0; k < 9; k++)
        put_f32(&b, tri[k]);
    put_u32(&b, 1), put_u32(&b, 2);
    put_u32(&b, 3), put_u32(&b, 3), put_u32(&b, 3);
    for (int k = 0; k < 9; k++)
        put_u32(&b, (uint32_t)k % 3);
    tb_fed *m;
    if (read_binary_bytes(&b, &m))
        fail_msg("%s", tb_last_error());
    assert_int_equal(m->nfaces, 2);
    assert_int_equal(tb_fed_face_nloops(m, 1), 2);
    assert_int_equal(m->nedges, 3);
    tb_fed_free(m);
    free(b.p);
}

/* ------------------------------------------------------------- round trips */

/* A random valid mesh: random positions in a random scale, faces of random
 * distinct vertices (random positions make degenerate loops vanishingly
 * unlikely; the generator retries if one occurs), holes on some faces, and
 * optional arrays. Vertices no face uses get extreme values (denormals,
 * -0, huge) to exercise the number formatting. */
static tb_fed *random_mesh(tb_rng *rng)
{
    for (;;) {
        uint32_t nv = 3 + tb_rng_below(rng, 60), nf = tb_rng_below(rng, 20);
        tb_vec3 *pos = malloc(sizeof(tb_vec3) * nv), *nrm = malloc(sizeof(tb_vec3) * nv);
        tb_vec2 *uv = malloc(sizeof(tb_vec2) * nv);
        uint32_t *fl = malloc(sizeof(uint32_t) * (nf + 1)), *ls = malloc(sizeof(uint32_t) * 3 * (nf + 1));
        uint32_t *cs = malloc(sizeof(uint32_t) * 3 * (nf + 1) * 8);
        int32_t *ids = malloc(sizeof(int32_t) * (nf + 1)), *mats = malloc(sizeof(int32_t) * (nf + 1));
        float scale = ldexpf(1.0f, (int)tb_rng_below(rng, 60) - 30);
        for (uint32_t v = 0; v < nv; v++) {
            pos[v] = tb_vec3_make(scale * (2 * tb_rng_float(rng) - 1), scale * (2 * tb_rng_float(rng) - 1),
                                  scale * (2 * tb_rng_float(rng) - 1));
            nrm[v] = tb_vec3_make(tb_rng_float(rng), -tb_rng_float(rng), 0.1f);
            uv[v] = (tb_vec2){tb_rng_float(rng), (float)tb_rng_u32(rng)};
        }
        uint32_t nl = 0, nc = 0;
        bool *used = calloc(nv, 1);
        for (uint32_t f = 0; f < nf; f++) {
            fl[f] = 1 + (tb_rng_below(rng, 4) == 0 ? 1 + tb_rng_below(rng, 2) : 0);
            for (uint32_t l = 0; l < fl[f]; l++) {
                uint32_t k = 3 + tb_rng_below(rng, 6 < nv - 2 ? 6 : nv - 2);
                ls[nl++] = k;
                /* k distinct vertices (a partial shuffle) */
                uint32_t pick[64];
                for (uint32_t i = 0; i < nv; i++)
                    pick[i] = i;
                for (uint32_t i = 0; i < k; i++) {
                    uint32_t j = i + tb_rng_below(rng, nv - i), t = pick[i];
                    pick[i] = pick[j], pick[j] = t;
                    cs[nc++] = pick[i];
                    used[pick[i]] = true;
                }
            }
            ids[f] = (int32_t)tb_rng_u32(rng);
            mats[f] = (int32_t)tb_rng_below(rng, 5) - 2;
        }
        const float special[] = {-0.0f, 0x1p-149f, 1e-38f, 3.4028235e38f, -3.4028235e38f, 1.0f / 3, 16777217.0f};
        for (uint32_t v = 0; v < nv; v++)
            if (!used[v])
                pos[v].y = special[tb_rng_below(rng, 7)];
        free(used);
        tb_fed_desc d = {.nverts = nv, .positions = pos, .nfaces = nf, .face_nloops = fl, .nloops = nl,
                         .loop_sizes = ls, .corners = cs};
        if (tb_rng_below(rng, 2))
            d.normals = nrm;
        if (tb_rng_below(rng, 2))
            d.uvs = uv;
        if (tb_rng_below(rng, 2))
            d.face_ids = ids;
        if (tb_rng_below(rng, 2))
            d.face_materials = mats;
        tb_fed *m = NULL;
        tb_status st = tb_fed_build(&d, &m, NULL);
        free(pos), free(nrm), free(uv), free(fl), free(ls), free(cs), free(ids), free(mats);
        if (!st)
            return m;
        assert_int_equal(st, TB_ERR_FORMAT); /* a degenerate draw: try again */
    }
}

/* Writes with `write` to memory and reads back with `read`. */
static tb_fed *through_memory(const tb_fed *m, tb_status (*write)(FILE *, const tb_fed *),
                              tb_status (*read)(FILE *, const char *, tb_fed **), char **buf, size_t *len)
{
    FILE *f = open_memstream(buf, len);
    assert_non_null(f);
    assert_int_equal(write(f, m), TB_OK);
    fclose(f);
    FILE *r = fmemopen(*buf, *len, "rb");
    assert_non_null(r);
    tb_fed *back = NULL;
    if (read(r, "mem", &back))
        fail_msg("read back: %s", tb_last_error());
    fclose(r);
    return back;
}

static void test_round_trips(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("fed_round_trip", 51), 5);
    for (int t = 0; t < 300; t++) {
        tb_fed *m = random_mesh(&rng);
        char *tbuf = NULL, *bbuf = NULL, *tbuf2 = NULL, *bbuf2 = NULL;
        size_t tlen = 0, blen = 0, tlen2 = 0, blen2 = 0;
        tb_fed *a = through_memory(m, tb_fed_write_text, tb_fed_read_text, &tbuf, &tlen);
        tb_fed *b = through_memory(m, tb_fed_write_binary, tb_fed_read_binary, &bbuf, &blen);
        assert_true(tb_fed_equal(m, a));
        assert_true(tb_fed_equal(m, b));
        /* text -> memory -> binary is byte-identical to memory -> binary, and back */
        tb_fed *c = through_memory(a, tb_fed_write_binary, tb_fed_read, &bbuf2, &blen2);
        tb_fed *d = through_memory(b, tb_fed_write_text, tb_fed_read, &tbuf2, &tlen2);
        assert_true(blen == blen2 && memcmp(bbuf, bbuf2, blen) == 0);
        assert_true(tlen == tlen2 && memcmp(tbuf, tbuf2, tlen) == 0);
        assert_true(tb_fed_equal(m, c) && tb_fed_equal(m, d));
        /* derived data agrees too */
        assert_int_equal(a->nedges, m->nedges);
        assert_memory_equal(a->edges, m->edges, m->nedges * sizeof(tb_fed_edge));
        tb_fed_free(a), tb_fed_free(b), tb_fed_free(c), tb_fed_free(d), tb_fed_free(m);
        free(tbuf), free(bbuf), free(tbuf2), free(bbuf2);
    }
}

/* -------------------------------------------------------------------- files */

static void test_files(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("fed_files", 52), 6);
    tb_fed *m = random_mesh(&rng);
    char tpath[512], bpath[512], bad[512];
    snprintf(tpath, sizeof tpath, "%s/mesh_test.fed", tb_test_tmpdir());
    snprintf(bpath, sizeof bpath, "%s/mesh_test.fedb", tb_test_tmpdir());
    snprintf(bad, sizeof bad, "%s/no/such/dir/x.fed", tb_test_tmpdir());
    assert_int_equal(tb_fed_write_file(tpath, m, TB_FED_FORMAT_AUTO), TB_OK);
    assert_int_equal(tb_fed_write_file(bpath, m, TB_FED_FORMAT_AUTO), TB_OK);
    /* the extension chose the form; the reader sniffs it */
    FILE *f = fopen(bpath, "rb");
    char magic[8];
    assert_int_equal(fread(magic, 1, 8, f), 8);
    fclose(f);
    assert_memory_equal(magic, TB_FED_BINARY_MAGIC, 8);
    tb_fed *a, *b;
    assert_int_equal(tb_fed_read_file(tpath, &a), TB_OK);
    assert_int_equal(tb_fed_read_file(bpath, &b), TB_OK);
    assert_true(tb_fed_equal(m, a) && tb_fed_equal(m, b));
    tb_fed_free(a), tb_fed_free(b);
    /* explicit form regardless of the name */
    assert_int_equal(tb_fed_write_file(tpath, m, TB_FED_FORMAT_BINARY), TB_OK);
    assert_int_equal(tb_fed_read_file(tpath, &a), TB_OK);
    assert_true(tb_fed_equal(m, a));
    tb_fed_free(a);
    /* a pipe cannot seek: the binary reader reads it all first */
    char cmd[600];
    snprintf(cmd, sizeof cmd, "cat '%s'", bpath);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    assert_int_equal(tb_fed_read(p, "pipe", &a), TB_OK);
    pclose(p);
    assert_true(tb_fed_equal(m, a));
    tb_fed_free(a);
    /* all or nothing: a write that cannot happen leaves nothing */
    assert_int_not_equal(tb_fed_write_file(bad, m, TB_FED_FORMAT_AUTO), TB_OK);
    struct stat sb;
    assert_int_not_equal(stat(bad, &sb), 0);
    assert_int_equal(tb_fed_read_file(bad, &a), TB_ERR_NOT_FOUND);
    /* an empty file */
    snprintf(cmd, sizeof cmd, "%s/mesh_empty.fed", tb_test_tmpdir());
    f = fopen(cmd, "wb");
    fclose(f);
    assert_int_equal(tb_fed_read_file(cmd, &a), TB_ERR_FORMAT);
    assert_true(strstr(tb_last_error(), "mesh_empty.fed:1:1: error: empty file") != NULL);
    unlink(cmd);
    unlink(tpath);
    unlink(bpath);
    tb_fed_free(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_text_example),
        cmocka_unit_test(test_text_errors),
        cmocka_unit_test(test_binary_errors),
        cmocka_unit_test(test_round_trips),
        cmocka_unit_test(test_files),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
