/* FED meshes: building (validation + derived edges and adjacency), queries,
 * and the warning checks. File formats are in fed_text.c and fed_binary.c. */
#include "util/mesh/fed.h"

#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "util/math/float.h"
#include "util/mesh/fed_internal.h"
#include "util/mesh/polygon.h"

const char *tb_fed_issue_name(tb_fed_issue_kind k)
{
    static const char *const names[TB_FED_ISSUE_KINDS] = {
        "bad count",         "vertex index out of range", "non-finite value",
        "repeated vertex",   "zero-length edge",          "too few vertices",
        "degenerate loop",   "non-manifold edge",         "inconsistent orientation",
        "hole orientation",  "non-planar face",           "unused vertex",
    };
    return (unsigned)k < TB_FED_ISSUE_KINDS ? names[k] : "?";
}

/* ------------------------------------------------------------ construction */

void tb_fed_free(tb_fed *m)
{
    if (!m)
        return;
    free(m->positions);
    free(m->normals);
    free(m->uvs);
    free(m->face_ids);
    free(m->face_materials);
    free(m->face_loops);
    free(m->loop_corners);
    free(m->loop_face);
    free(m->corner_vert);
    free(m->corner_edge);
    free(m->corner_loop);
    free(m->edges);
    free(m->edge_uses);
    free(m->edge_use_corner);
    free(m->vert_faces);
    free(m->vert_face);
    free(m);
}

/* malloc of n elements of `size` bytes (at least one byte), NULL on overflow. */
static void *tb__alloc_n(size_t n, size_t size)
{
    if (size && n > SIZE_MAX / size)
        return NULL;
    size_t bytes = n * size;
    return malloc(bytes ? bytes : 1);
}

tb_fed *tb__fed_alloc(uint32_t nverts, uint32_t nfaces, uint32_t nloops, uint32_t ncorners,
                      bool normals, bool uvs, bool ids, bool materials)
{
    tb_fed *m = calloc(1, sizeof *m);
    if (!m) {
        tb_error(TB_ERR_NOMEM, "FED: out of memory");
        return NULL;
    }
    m->nverts = nverts, m->nfaces = nfaces, m->nloops = nloops, m->ncorners = ncorners;
    m->positions = tb__alloc_n(nverts, sizeof(tb_vec3));
    m->normals = normals ? tb__alloc_n(nverts, sizeof(tb_vec3)) : NULL;
    m->uvs = uvs ? tb__alloc_n(nverts, sizeof(tb_vec2)) : NULL;
    m->face_ids = ids ? tb__alloc_n(nfaces, sizeof(int32_t)) : NULL;
    m->face_materials = materials ? tb__alloc_n(nfaces, sizeof(int32_t)) : NULL;
    m->face_loops = tb__alloc_n((size_t)nfaces + 1, sizeof(uint32_t));
    m->loop_corners = tb__alloc_n((size_t)nloops + 1, sizeof(uint32_t));
    m->corner_vert = tb__alloc_n(ncorners, sizeof(uint32_t));
    if (!m->positions || (normals && !m->normals) || (uvs && !m->uvs) || (ids && !m->face_ids) ||
        (materials && !m->face_materials) || !m->face_loops || !m->loop_corners || !m->corner_vert) {
        tb_fed_free(m);
        tb_error(TB_ERR_NOMEM, "FED: out of memory for %u vertices and %u corners", nverts, ncorners);
        return NULL;
    }
    return m;
}

/* Records a fatal issue: fills *issue and sets the error message. */
static tb_status tb__fail(tb_fed_issue *issue, tb_fed_issue_kind kind, uint32_t face, uint32_t loop,
                          uint32_t corner, uint32_t vertex, const char *fmt, ...)
    __attribute__((format(printf, 7, 8)));

static tb_status tb__fail(tb_fed_issue *issue, tb_fed_issue_kind kind, uint32_t face, uint32_t loop,
                          uint32_t corner, uint32_t vertex, const char *fmt, ...)
{
    tb_fed_issue tmp;
    tb_fed_issue *is = issue ? issue : &tmp;
    *is = (tb_fed_issue){kind, face, loop, corner, vertex, TB_FED_NONE, {0}};
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(is->message, sizeof is->message, fmt, ap);
    va_end(ap);
    return tb_error(TB_ERR_FORMAT, "%s", is->message);
}

/* "face 3 (outer loop)" or "face 3 (hole 2)" for loop l of face f. */
static void tb__loop_name(const tb_fed *m, uint32_t f, uint32_t l, char *buf, size_t n)
{
    uint32_t h = l - m->face_loops[f];
    if (h == 0)
        snprintf(buf, n, "face %u (outer loop)", f);
    else
        snprintf(buf, n, "face %u (hole %u)", f, h);
}

/* Twice the area of loop l and its size (bounding box diagonal). */
static double tb__loop_area2(const tb_fed *m, uint32_t l, double *size)
{
    const uint32_t *idx = m->corner_vert + m->loop_corners[l];
    uint32_t n = tb_fed_loop_size(m, l);
    tb_dvec3 nv = tb_polygon_newell(m->positions, idx, n);
    *size = tb_polygon_size(m->positions, idx, n);
    return sqrt(nv.x * nv.x + nv.y * nv.y + nv.z * nv.z);
}

/* Checks the fatal rules loop by loop. */
static tb_status tb__validate(tb_fed *m, tb_fed_issue *issue)
{
    char where[64];
    if (m->face_loops[0] != 0 || m->face_loops[m->nfaces] != m->nloops)
        return tb__fail(issue, TB_FED_ISSUE_BAD_COUNT, TB_FED_NONE, TB_FED_NONE, TB_FED_NONE, TB_FED_NONE,
                        "the faces' loop counts add up to %u, but there are %u loops",
                        m->face_loops[m->nfaces] - m->face_loops[0], m->nloops);
    for (uint32_t f = 0; f < m->nfaces; f++)
        if (m->face_loops[f + 1] <= m->face_loops[f])
            return tb__fail(issue, TB_FED_ISSUE_BAD_COUNT, f, TB_FED_NONE, TB_FED_NONE, TB_FED_NONE,
                            "face %u has no loop", f);
    for (uint32_t l = 0; l < m->nloops; l++)
        if (m->loop_corners[l + 1] < m->loop_corners[l] || m->loop_corners[l + 1] - m->loop_corners[l] < 3) {
            uint32_t f = 0; /* the face of loop l, for the message (face_loops is valid here) */
            while (f + 1 < m->nfaces && m->face_loops[f + 1] <= l)
                f++;
            tb__loop_name(m, f, l, where, sizeof where);
            return tb__fail(issue, TB_FED_ISSUE_BAD_COUNT, f, l, TB_FED_NONE, TB_FED_NONE,
                            "%s: %u corners (at least 3 needed)", where,
                            m->loop_corners[l + 1] < m->loop_corners[l] ? 0 : m->loop_corners[l + 1] - m->loop_corners[l]);
        }
    if (m->loop_corners[0] != 0 || m->loop_corners[m->nloops] != m->ncorners)
        return tb__fail(issue, TB_FED_ISSUE_BAD_COUNT, TB_FED_NONE, TB_FED_NONE, TB_FED_NONE, TB_FED_NONE,
                        "the loops' corner counts add up to %u, but there are %u corners",
                        m->loop_corners[m->nloops] - m->loop_corners[0], m->ncorners);
    for (uint32_t v = 0; v < m->nverts; v++) {
        const char *what = NULL;
        if (!tb_isfinite3(m->positions[v]))
            what = "position";
        else if (m->normals && !tb_isfinite3(m->normals[v]))
            what = "normal";
        else if (m->uvs && !(isfinite(m->uvs[v].x) && isfinite(m->uvs[v].y)))
            what = "uv";
        if (what)
            return tb__fail(issue, TB_FED_ISSUE_NONFINITE, TB_FED_NONE, TB_FED_NONE, TB_FED_NONE, v,
                            "vertex %u: %s is not finite", v, what);
    }
    for (uint32_t f = 0; f < m->nfaces; f++) {
        for (uint32_t l = m->face_loops[f]; l < m->face_loops[f + 1]; l++) {
            uint32_t c0 = m->loop_corners[l], n = m->loop_corners[l + 1] - c0;
            for (uint32_t k = 0; k < n; k++) {
                uint32_t v = m->corner_vert[c0 + k];
                if (v >= m->nverts) {
                    tb__loop_name(m, f, l, where, sizeof where);
                    return tb__fail(issue, TB_FED_ISSUE_INDEX, f, l, c0 + k, v,
                                    "%s, corner %u: vertex index %u out of range (%u vertices)", where, k,
                                    v, m->nverts);
                }
            }
            for (uint32_t k = 0; k < n; k++) {
                uint32_t a = m->corner_vert[c0 + k], b = m->corner_vert[c0 + (k + 1) % n];
                if (a == b) {
                    tb__loop_name(m, f, l, where, sizeof where);
                    return tb__fail(issue, TB_FED_ISSUE_REPEATED_VERTEX, f, l, c0 + k, a,
                                    "%s, corner %u: vertex %u repeated at the next corner", where, k, a);
                }
                if (tb_vec3_equal(m->positions[a], m->positions[b])) {
                    tb__loop_name(m, f, l, where, sizeof where);
                    return tb__fail(issue, TB_FED_ISSUE_ZERO_EDGE, f, l, c0 + k, a,
                                    "%s, corner %u: vertices %u and %u are at the same position "
                                    "(zero-length edge)", where, k, a, b);
                }
            }
            uint32_t a = m->corner_vert[c0], b = m->corner_vert[c0 + 1];
            bool third = false;
            for (uint32_t k = 2; k < n && !third; k++)
                third = m->corner_vert[c0 + k] != a && m->corner_vert[c0 + k] != b;
            if (!third) {
                tb__loop_name(m, f, l, where, sizeof where);
                return tb__fail(issue, TB_FED_ISSUE_FEW_VERTICES, f, l, TB_FED_NONE, TB_FED_NONE,
                                "%s: only 2 distinct vertices (at least 3 needed)", where);
            }
            double size, area2 = tb__loop_area2(m, l, &size);
            if (!(area2 > 2 * TB_FED_DEGENERATE_REL * size * size)) {
                tb__loop_name(m, f, l, where, sizeof where);
                return tb__fail(issue, TB_FED_ISSUE_DEGENERATE, f, l, TB_FED_NONE, TB_FED_NONE,
                                "%s: zero area (degenerate: %.3g relative to its size squared)", where,
                                size > 0 ? area2 / 2 / (size * size) : 0.0);
            }
        }
    }
    return TB_OK;
}

/* Derives loop_face, corner_loop, the edges and the adjacency arrays. */
static tb_status tb__derive(tb_fed *m)
{
    uint32_t nc = m->ncorners;
    m->loop_face = tb__alloc_n(m->nloops, sizeof(uint32_t));
    m->corner_loop = tb__alloc_n(nc, sizeof(uint32_t));
    m->corner_edge = tb__alloc_n(nc, sizeof(uint32_t));
    m->edges = tb__alloc_n(nc, sizeof(tb_fed_edge)); /* at most one new edge per corner; shrunk below */
    m->vert_faces = tb__alloc_n((size_t)m->nverts + 1, sizeof(uint32_t));
    if (!m->loop_face || !m->corner_loop || !m->corner_edge || !m->edges || !m->vert_faces)
        return tb_error(TB_ERR_NOMEM, "FED: out of memory for %u corners", nc);
    for (uint32_t f = 0; f < m->nfaces; f++)
        for (uint32_t l = m->face_loops[f]; l < m->face_loops[f + 1]; l++) {
            m->loop_face[l] = f;
            for (uint32_t c = m->loop_corners[l]; c < m->loop_corners[l + 1]; c++)
                m->corner_loop[c] = l;
        }

    /* Edges: one per unordered vertex pair, numbered in order of first use.
     * The corners are bucketed by their pair's lower vertex (a counting
     * sort), so finding a pair's first corner is a scan of a few entries in
     * one place; that is about twice as fast as a hash table keyed on the
     * pair (docs/fed.md, "Performance"). A bucket lists its corners in
     * corner order, so the first entry with the same upper vertex is the
     * pair's first use. */
    typedef struct {
        uint32_t hi, corner;
    } tb__use;
    uint32_t *bstart = calloc((size_t)m->nverts + 1, sizeof(uint32_t));
    tb__use *uses = tb__alloc_n(nc, sizeof(tb__use));
    if (!bstart || !uses) {
        free(bstart);
        free(uses);
        return tb_error(TB_ERR_NOMEM, "FED: out of memory for %u corners", nc);
    }
    for (uint32_t l = 0; l < m->nloops; l++) {
        uint32_t c0 = m->loop_corners[l], c1 = m->loop_corners[l + 1];
        for (uint32_t c = c0; c < c1; c++) {
            uint32_t a = m->corner_vert[c], b = m->corner_vert[c + 1 < c1 ? c + 1 : c0];
            bstart[(a < b ? a : b) + 1]++;
        }
    }
    for (uint32_t v = 0; v < m->nverts; v++)
        bstart[v + 1] += bstart[v];
    for (uint32_t l = 0; l < m->nloops; l++) {
        uint32_t c0 = m->loop_corners[l], c1 = m->loop_corners[l + 1];
        for (uint32_t c = c0; c < c1; c++) {
            uint32_t a = m->corner_vert[c], b = m->corner_vert[c + 1 < c1 ? c + 1 : c0];
            uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
            uses[bstart[lo]++] = (tb__use){hi, c};
        }
    }
    for (uint32_t v = m->nverts; v > 0; v--) /* the fill advanced each start to the next one's */
        bstart[v] = bstart[v - 1];
    bstart[0] = 0;
    uint32_t ne = 0;
    for (uint32_t l = 0; l < m->nloops; l++) {
        uint32_t c0 = m->loop_corners[l], c1 = m->loop_corners[l + 1];
        for (uint32_t c = c0; c < c1; c++) {
            uint32_t a = m->corner_vert[c], b = m->corner_vert[c + 1 < c1 ? c + 1 : c0];
            uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
            const tb__use *u = uses + bstart[lo];
            while (u->hi != hi)
                u++; /* stops at the pair's first corner, at c itself at the latest */
            if (u->corner == c) {
                m->edges[ne] = (tb_fed_edge){{lo, hi}};
                m->corner_edge[c] = ne++;
            } else {
                m->corner_edge[c] = m->corner_edge[u->corner];
            }
        }
    }
    free(bstart);
    free(uses);
    m->nedges = ne;
    tb_fed_edge *shrunk = realloc(m->edges, (ne ? ne : 1) * sizeof(tb_fed_edge));
    if (shrunk)
        m->edges = shrunk;

    /* Edge uses: the corners of each edge, ascending (counting sort). */
    m->edge_uses = calloc((size_t)ne + 1, sizeof(uint32_t));
    m->edge_use_corner = tb__alloc_n(nc, sizeof(uint32_t));
    if (!m->edge_uses || !m->edge_use_corner)
        return tb_error(TB_ERR_NOMEM, "FED: out of memory for %u edges", ne);
    for (uint32_t c = 0; c < nc; c++)
        m->edge_uses[m->corner_edge[c] + 1]++;
    for (uint32_t e = 0; e < ne; e++)
        m->edge_uses[e + 1] += m->edge_uses[e];
    for (uint32_t c = 0; c < nc; c++)
        m->edge_use_corner[m->edge_uses[m->corner_edge[c]]++] = c;
    for (uint32_t e = ne; e > 0; e--) /* the fill advanced each start to the next one's */
        m->edge_uses[e] = m->edge_uses[e - 1];
    m->edge_uses[0] = 0;

    /* Faces around each vertex: corners per vertex bound the count; a face
     * visiting a vertex twice is stored once (its corners are consecutive in
     * the fill, which runs face by face). */
    uint32_t *fill = calloc((size_t)m->nverts + 1, sizeof(uint32_t));
    m->vert_face = tb__alloc_n(nc, sizeof(uint32_t));
    if (!fill || !m->vert_face) {
        free(fill);
        return tb_error(TB_ERR_NOMEM, "FED: out of memory for vertex adjacency");
    }
    memset(m->vert_faces, 0, ((size_t)m->nverts + 1) * sizeof(uint32_t));
    for (uint32_t c = 0; c < nc; c++)
        m->vert_faces[m->corner_vert[c] + 1]++;
    for (uint32_t v = 0; v < m->nverts; v++)
        m->vert_faces[v + 1] += m->vert_faces[v];
    for (uint32_t f = 0; f < m->nfaces; f++)
        for (uint32_t c = tb_fed_face_corner_begin(m, f); c < tb_fed_face_corner_end(m, f); c++) {
            uint32_t v = m->corner_vert[c], at = m->vert_faces[v] + fill[v];
            if (fill[v] == 0 || m->vert_face[at - 1] != f) {
                m->vert_face[at] = f;
                fill[v]++;
            }
        }
    /* Compact away the room left by faces counted twice. */
    uint32_t out = 0;
    for (uint32_t v = 0; v < m->nverts; v++) {
        uint32_t start = m->vert_faces[v];
        m->vert_faces[v] = out;
        memmove(m->vert_face + out, m->vert_face + start, (size_t)fill[v] * sizeof(uint32_t));
        out += fill[v];
    }
    m->vert_faces[m->nverts] = out;
    free(fill);
    return TB_OK;
}

tb_status tb__fed_finish(tb_fed *m, tb_fed_issue *issue)
{
    /* Per-item arrays of zero items are stored as absent, so that every form
     * (the text form cannot say "ids present" without a face) agrees. */
    if (m->nverts == 0) {
        free(m->normals), free(m->uvs);
        m->normals = NULL, m->uvs = NULL;
    }
    if (m->nfaces == 0) {
        free(m->face_ids), free(m->face_materials);
        m->face_ids = NULL, m->face_materials = NULL;
    }
    tb_status st = tb__validate(m, issue);
    if (!st)
        st = tb__derive(m);
    return st;
}

tb_status tb_fed_build(const tb_fed_desc *d, tb_fed **out, tb_fed_issue *issue)
{
    *out = NULL;
    if (!d || (d->nverts && !d->positions) || (d->nloops && (!d->loop_sizes)))
        return tb_error(TB_ERR_ARG, "tb_fed_build: missing arrays");
    if (d->nverts > TB_FED_MAX_COUNT || d->nfaces > TB_FED_MAX_COUNT || d->nloops > TB_FED_MAX_COUNT)
        return tb__fail(issue, TB_FED_ISSUE_BAD_COUNT, TB_FED_NONE, TB_FED_NONE, TB_FED_NONE, TB_FED_NONE,
                        "too many vertices, faces or loops (at most %u)", TB_FED_MAX_COUNT);
    if (!d->face_nloops && d->nloops != d->nfaces)
        return tb__fail(issue, TB_FED_ISSUE_BAD_COUNT, TB_FED_NONE, TB_FED_NONE, TB_FED_NONE, TB_FED_NONE,
                        "%u loops for %u faces of one loop each", d->nloops, d->nfaces);
    uint64_t nloops = 0, ncorners = 0;
    for (uint32_t f = 0; f < d->nfaces; f++)
        nloops += d->face_nloops ? d->face_nloops[f] : 1;
    if (nloops != d->nloops)
        return tb__fail(issue, TB_FED_ISSUE_BAD_COUNT, TB_FED_NONE, TB_FED_NONE, TB_FED_NONE, TB_FED_NONE,
                        "the faces' loop counts add up to %llu, but there are %u loops",
                        (unsigned long long)nloops, d->nloops);
    for (uint32_t l = 0; l < d->nloops; l++)
        ncorners += d->loop_sizes[l];
    if (ncorners > TB_FED_MAX_COUNT)
        return tb__fail(issue, TB_FED_ISSUE_BAD_COUNT, TB_FED_NONE, TB_FED_NONE, TB_FED_NONE, TB_FED_NONE,
                        "too many corners (%llu, at most %u)", (unsigned long long)ncorners, TB_FED_MAX_COUNT);
    if (ncorners && !d->corners)
        return tb_error(TB_ERR_ARG, "tb_fed_build: missing corner array");
    tb_fed *m = tb__fed_alloc(d->nverts, d->nfaces, d->nloops, (uint32_t)ncorners, d->normals != NULL,
                              d->uvs != NULL, d->face_ids != NULL, d->face_materials != NULL);
    if (!m)
        return TB_ERR_NOMEM;
    if (d->nverts)
        memcpy(m->positions, d->positions, (size_t)d->nverts * sizeof(tb_vec3));
    if (d->normals && d->nverts)
        memcpy(m->normals, d->normals, (size_t)d->nverts * sizeof(tb_vec3));
    if (d->uvs && d->nverts)
        memcpy(m->uvs, d->uvs, (size_t)d->nverts * sizeof(tb_vec2));
    if (d->face_ids && d->nfaces)
        memcpy(m->face_ids, d->face_ids, (size_t)d->nfaces * sizeof(int32_t));
    if (d->face_materials && d->nfaces)
        memcpy(m->face_materials, d->face_materials, (size_t)d->nfaces * sizeof(int32_t));
    if (ncorners)
        memcpy(m->corner_vert, d->corners, (size_t)ncorners * sizeof(uint32_t));
    m->face_loops[0] = 0;
    for (uint32_t f = 0; f < d->nfaces; f++)
        m->face_loops[f + 1] = m->face_loops[f] + (d->face_nloops ? d->face_nloops[f] : 1);
    m->loop_corners[0] = 0;
    for (uint32_t l = 0; l < d->nloops; l++)
        m->loop_corners[l + 1] = m->loop_corners[l] + d->loop_sizes[l];
    tb_status st = tb__fed_finish(m, issue);
    if (st) {
        tb_fed_free(m);
        return st;
    }
    *out = m;
    return TB_OK;
}

/* ------------------------------------------------------------------ queries */

uint32_t tb_fed_find_edge(const tb_fed *m, uint32_t a, uint32_t b)
{
    if (a >= m->nverts || b >= m->nverts || a == b)
        return TB_FED_NONE;
    uint32_t nf;
    const uint32_t *faces = tb_fed_vertex_faces(m, a, &nf);
    for (uint32_t i = 0; i < nf; i++)
        for (uint32_t c = tb_fed_face_corner_begin(m, faces[i]); c < tb_fed_face_corner_end(m, faces[i]); c++) {
            const tb_fed_edge *e = &m->edges[m->corner_edge[c]];
            if ((e->v[0] == a && e->v[1] == b) || (e->v[0] == b && e->v[1] == a))
                return m->corner_edge[c];
        }
    return TB_FED_NONE;
}

uint32_t tb_fed_edge_faces(const tb_fed *m, uint32_t e, uint32_t *out, uint32_t cap)
{
    uint32_t n = 0, last = TB_FED_NONE;
    for (uint32_t i = 0; i < tb_fed_edge_nuses(m, e); i++) {
        uint32_t f = tb_fed_edge_face(m, e, i); /* ascending: uses are in corner order */
        if (f == last)
            continue;
        if (n < cap)
            out[n] = f;
        n++;
        last = f;
    }
    return n;
}

uint32_t tb_fed_count_boundary_edges(const tb_fed *m)
{
    uint32_t n = 0;
    for (uint32_t e = 0; e < m->nedges; e++)
        n += tb_fed_edge_is_boundary(m, e);
    return n;
}

uint32_t tb_fed_count_nonmanifold_edges(const tb_fed *m)
{
    uint32_t n = 0;
    for (uint32_t e = 0; e < m->nedges; e++)
        n += tb_fed_edge_is_nonmanifold(m, e);
    return n;
}

bool tb_fed_is_closed(const tb_fed *m)
{
    if (m->nfaces == 0)
        return false;
    for (uint32_t e = 0; e < m->nedges; e++)
        if (tb_fed_edge_nuses(m, e) != 2 || tb_fed_edge_use_forward(m, e, 0) == tb_fed_edge_use_forward(m, e, 1))
            return false;
    return true;
}

int64_t tb_fed_euler_characteristic(const tb_fed *m)
{
    int64_t used = 0;
    for (uint32_t v = 0; v < m->nverts; v++)
        used += m->vert_faces[v + 1] > m->vert_faces[v];
    return used - (int64_t)m->nedges + m->nfaces - ((int64_t)m->nloops - m->nfaces);
}

tb_dvec3 tb_fed_face_normal(const tb_fed *m, uint32_t f)
{
    uint32_t l = m->face_loops[f];
    return tb_polygon_newell(m->positions, m->corner_vert + m->loop_corners[l], tb_fed_loop_size(m, l));
}

double tb_fed_face_area(const tb_fed *m, uint32_t f)
{
    tb_dvec3 n = tb_fed_face_normal(m, f);
    double len = sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
    if (!(len > 0))
        return 0;
    double area = len / 2;
    for (uint32_t l = m->face_loops[f] + 1; l < m->face_loops[f + 1]; l++) {
        tb_dvec3 h = tb_polygon_newell(m->positions, m->corner_vert + m->loop_corners[l], tb_fed_loop_size(m, l));
        area -= fabs(h.x * n.x + h.y * n.y + h.z * n.z) / len / 2;
    }
    return area;
}

/* --------------------------------------------------------------- warnings */

/* Counts a warning and keeps it if there is room. */
static void tb__warn(tb_fed_report *r, tb_fed_issue_kind kind, uint32_t face, uint32_t loop, uint32_t vertex,
                     uint32_t edge, const char *fmt, ...) __attribute__((format(printf, 7, 8)));

static void tb__warn(tb_fed_report *r, tb_fed_issue_kind kind, uint32_t face, uint32_t loop, uint32_t vertex,
                     uint32_t edge, const char *fmt, ...)
{
    r->counts[kind]++;
    if (r->nissues >= TB_FED_REPORT_MAX)
        return;
    tb_fed_issue *is = &r->issues[r->nissues++];
    *is = (tb_fed_issue){kind, face, loop, TB_FED_NONE, vertex, edge, {0}};
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(is->message, sizeof is->message, fmt, ap);
    va_end(ap);
}

/* Largest distance of a vertex of face f (any loop) from the plane through
 * its outer loop's centroid perpendicular to that loop's Newell normal. */
static double tb__face_planarity(const tb_fed *m, uint32_t f, double *size)
{
    uint32_t l0 = m->face_loops[f];
    const uint32_t *outer = m->corner_vert + m->loop_corners[l0];
    uint32_t n0 = tb_fed_loop_size(m, l0);
    *size = tb_polygon_size(m->positions, outer, n0);
    if (tb_fed_face_nloops(m, f) == 1)
        return tb_polygon_planarity(m->positions, outer, n0);
    tb_dvec3 nv = tb_fed_face_normal(m, f);
    double len = sqrt(nv.x * nv.x + nv.y * nv.y + nv.z * nv.z);
    double cx = 0, cy = 0, cz = 0;
    for (uint32_t k = 0; k < n0; k++) {
        tb_vec3 p = m->positions[outer[k]];
        cx += p.x, cy += p.y, cz += p.z;
    }
    cx /= n0, cy /= n0, cz /= n0;
    double worst = 0;
    for (uint32_t c = tb_fed_face_corner_begin(m, f); c < tb_fed_face_corner_end(m, f); c++) {
        tb_vec3 p = m->positions[m->corner_vert[c]];
        double d = fabs((p.x - cx) * nv.x + (p.y - cy) * nv.y + (p.z - cz) * nv.z) / len;
        worst = d > worst ? d : worst;
    }
    return worst;
}

uint32_t tb_fed_check(const tb_fed *m, tb_fed_report *r)
{
    memset(r, 0, sizeof *r);
    for (uint32_t e = 0; e < m->nedges; e++) {
        uint32_t nu = tb_fed_edge_nuses(m, e);
        const tb_fed_edge *ed = &m->edges[e];
        if (nu == 1) {
            r->boundary_edges++;
        } else if (nu > 2) {
            tb__warn(r, TB_FED_ISSUE_NONMANIFOLD, tb_fed_edge_face(m, e, 0), TB_FED_NONE, ed->v[0], e,
                     "edge %u (vertices %u-%u): used %u times (non-manifold)", e, ed->v[0], ed->v[1], nu);
        } else if (tb_fed_edge_use_forward(m, e, 0) == tb_fed_edge_use_forward(m, e, 1)) {
            tb__warn(r, TB_FED_ISSUE_ORIENTATION, tb_fed_edge_face(m, e, 1), TB_FED_NONE, ed->v[0], e,
                     "edge %u (vertices %u-%u): faces %u and %u both run it from vertex %u "
                     "(inconsistent orientation)", e, ed->v[0], ed->v[1], tb_fed_edge_face(m, e, 0),
                     tb_fed_edge_face(m, e, 1), m->corner_vert[tb_fed_edge_use(m, e, 0)]);
        }
    }
    for (uint32_t f = 0; f < m->nfaces; f++) {
        tb_dvec3 n = tb_fed_face_normal(m, f);
        for (uint32_t l = m->face_loops[f] + 1; l < m->face_loops[f + 1]; l++) {
            tb_dvec3 h = tb_polygon_newell(m->positions, m->corner_vert + m->loop_corners[l], tb_fed_loop_size(m, l));
            if (h.x * n.x + h.y * n.y + h.z * n.z > 0)
                tb__warn(r, TB_FED_ISSUE_HOLE_ORIENTATION, f, l, TB_FED_NONE, TB_FED_NONE,
                         "face %u (hole %u): turns the same way as the outer loop (holes run opposite)", f,
                         l - m->face_loops[f]);
        }
        if (tb_fed_face_corner_end(m, f) - tb_fed_face_corner_begin(m, f) > 3) {
            double size, dev = tb__face_planarity(m, f, &size);
            if (dev > TB_MESH_PLANAR_TOL * size)
                tb__warn(r, TB_FED_ISSUE_NONPLANAR, f, m->face_loops[f], TB_FED_NONE, TB_FED_NONE,
                         "face %u: a vertex is %.3g off the face's plane (%.2g of its size; tolerance %.0e)", f,
                         dev, dev / size, TB_MESH_PLANAR_TOL);
        }
    }
    for (uint32_t v = 0; v < m->nverts; v++)
        if (m->vert_faces[v + 1] == m->vert_faces[v])
            tb__warn(r, TB_FED_ISSUE_UNUSED_VERTEX, TB_FED_NONE, TB_FED_NONE, v, TB_FED_NONE,
                     "vertex %u: used by no face", v);
    r->closed = tb_fed_is_closed(m);
    uint32_t total = 0;
    for (int k = 0; k < TB_FED_ISSUE_KINDS; k++)
        total += r->counts[k];
    return total;
}

/* -------------------------------------------------------------- comparison */

bool tb_fed_equal(const tb_fed *a, const tb_fed *b)
{
    if (a->nverts != b->nverts || a->nfaces != b->nfaces || a->nloops != b->nloops || a->ncorners != b->ncorners)
        return false;
    if (!a->normals != !b->normals || !a->uvs != !b->uvs || !a->face_ids != !b->face_ids ||
        !a->face_materials != !b->face_materials)
        return false;
    size_t nv = a->nverts, nf = a->nfaces;
    if (memcmp(a->positions, b->positions, nv * sizeof(tb_vec3)) != 0 ||
        (a->normals && memcmp(a->normals, b->normals, nv * sizeof(tb_vec3)) != 0) ||
        (a->uvs && memcmp(a->uvs, b->uvs, nv * sizeof(tb_vec2)) != 0) ||
        (a->face_ids && memcmp(a->face_ids, b->face_ids, nf * sizeof(int32_t)) != 0) ||
        (a->face_materials && memcmp(a->face_materials, b->face_materials, nf * sizeof(int32_t)) != 0))
        return false;
    return memcmp(a->face_loops, b->face_loops, (nf + 1) * sizeof(uint32_t)) == 0 &&
           memcmp(a->loop_corners, b->loop_corners, ((size_t)a->nloops + 1) * sizeof(uint32_t)) == 0 &&
           memcmp(a->corner_vert, b->corner_vert, (size_t)a->ncorners * sizeof(uint32_t)) == 0;
}
