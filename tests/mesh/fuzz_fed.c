/* libFuzzer target for the FED readers; FUZZ_FED_BINARY selects the binary
 * reader, otherwise the text reader. Any input must give TB_OK or an error
 * status, never a crash, hang, leak or sanitizer report. An accepted mesh is
 * checked (tb_fed_check, adjacency walks), written back in the same form and
 * re-read: the two meshes must be equal. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "util/mesh/fed.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0)
        return 0; /* fmemopen needs a non-empty buffer; the unit tests cover empty files */
    FILE *f = fmemopen((void *)data, size, "rb");
    if (!f)
        return 0;
    tb_fed *m = NULL;
#ifdef FUZZ_FED_BINARY
    tb_status st = tb_fed_read_binary(f, "fuzz", &m);
#else
    tb_status st = tb_fed_read_text(f, "fuzz", &m);
#endif
    fclose(f);
    if (st != TB_OK) {
        if (m)
            __builtin_trap(); /* a failed read must not return a mesh */
        return 0;
    }
    tb_fed_report r;
    tb_fed_check(m, &r);
    /* Adjacency must be consistent: every use of an edge is a corner whose
     * step runs along that edge, and every face around a vertex has it. */
    for (uint32_t e = 0; e < m->nedges; e++)
        for (uint32_t i = 0; i < tb_fed_edge_nuses(m, e); i++) {
            uint32_t c = tb_fed_edge_use(m, e, i);
            uint32_t a = m->corner_vert[c], b = m->corner_vert[tb_fed_corner_next(m, c)];
            if (m->corner_edge[c] != e || !((a == m->edges[e].v[0] && b == m->edges[e].v[1]) ||
                                            (b == m->edges[e].v[0] && a == m->edges[e].v[1])))
                __builtin_trap();
        }
    for (uint32_t v = 0; v < m->nverts; v++) {
        uint32_t n;
        const uint32_t *fs = tb_fed_vertex_faces(m, v, &n);
        for (uint32_t i = 0; i < n; i++) {
            int found = 0;
            for (uint32_t c = tb_fed_face_corner_begin(m, fs[i]); c < tb_fed_face_corner_end(m, fs[i]); c++)
                found |= m->corner_vert[c] == v;
            if (!found)
                __builtin_trap();
        }
    }
    char *buf = NULL;
    size_t len = 0;
    FILE *w = open_memstream(&buf, &len);
    if (!w)
        __builtin_trap();
#ifdef FUZZ_FED_BINARY
    st = tb_fed_write_binary(w, m);
#else
    st = tb_fed_write_text(w, m);
#endif
    fclose(w);
    if (st != TB_OK || len == 0)
        __builtin_trap();
    FILE *rb = fmemopen(buf, len, "rb");
    tb_fed *back = NULL;
    if (!rb || tb_fed_read(rb, "fuzz-back", &back) != TB_OK)
        __builtin_trap(); /* anything read must be written readably */
    fclose(rb);
    if (!tb_fed_equal(m, back))
        __builtin_trap();
    tb_fed_free(back);
    free(buf);
    tb_fed_free(m);
    return 0;
}
