/* FED: face-edge meshes (Weiler 1985, "Edge-based data structures for solid
 * modeling in curved-surface environments"), the mesh form that MID objects
 * reference with file("x.fed") and the object level uses for polygonal
 * approximations of primitives. docs/fed.md is the specification: model,
 * queries, validation rules, and the text and binary file formats.
 *
 * A mesh has vertices (float positions, optional normals and (u,v)), faces
 * with one outer loop and any number of inner loops (holes), and the edges
 * those loops use, each undirected edge stored once with the corners that
 * use it. All arrays are flat and indexed by uint32_t, so a mesh of 10^6
 * triangles is a few dozen contiguous allocations:
 *
 *   face f      loops face_loops[f] .. face_loops[f+1]-1 (the first is the outer loop)
 *   loop l      corners loop_corners[l] .. loop_corners[l+1]-1, in order
 *   corner c    vertex corner_vert[c]; edge corner_edge[c] runs from it to the next corner
 *   edge e      vertices edges[e].v[0] < edges[e].v[1]; its uses (corners)
 *               edge_use_corner[edge_uses[e] .. edge_uses[e+1]-1]
 *   vertex v    faces vert_face[vert_faces[v] .. vert_faces[v+1]-1] (each once, ascending)
 *
 * A tb_fed is immutable after tb_fed_build (or a reader) returns it; build
 * one with tb_fed_build from plain arrays. Counts and indices are below 2^31. */
#ifndef TB_UTIL_MESH_FED_H
#define TB_UTIL_MESH_FED_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "util/base/error.h"
#include "util/math/vec.h"

/* Version of the FED formats this code reads and writes. */
#define TB_FED_VERSION 1

/* Largest count of vertices, faces, loops or corners (and largest index + 1). */
#define TB_FED_MAX_COUNT 0x7fffffffu

/* "No such element" in index results. */
#define TB_FED_NONE UINT32_MAX

/* A loop whose area is at most this times the square of its size (bounding
 * box diagonal) is degenerate: far below what float coordinates resolve. */
#define TB_FED_DEGENERATE_REL 1e-12

/* One undirected edge. */
typedef struct tb_fed_edge {
    uint32_t v[2]; /* end vertices, v[0] < v[1] */
} tb_fed_edge;

/* A face-edge mesh; see the layout above. Optional arrays are NULL when absent. */
typedef struct tb_fed {
    uint32_t nverts, nfaces, nloops, ncorners, nedges;
    tb_vec3 *positions;       /* nverts */
    tb_vec3 *normals;         /* nverts, or NULL */
    tb_vec2 *uvs;             /* nverts, or NULL */
    int32_t *face_ids;        /* nfaces, or NULL: the parametric face of a primitive, for the object level */
    int32_t *face_materials;  /* nfaces, or NULL: material index, meaning chosen by the user */
    uint32_t *face_loops;     /* nfaces + 1 offsets into the loops */
    uint32_t *loop_corners;   /* nloops + 1 offsets into the corners */
    uint32_t *loop_face;      /* nloops: the face of each loop */
    uint32_t *corner_vert;    /* ncorners: vertex of each corner */
    uint32_t *corner_edge;    /* ncorners: edge from this corner to the next one of its loop */
    uint32_t *corner_loop;    /* ncorners: loop of each corner */
    tb_fed_edge *edges;       /* nedges, in order of first use */
    uint32_t *edge_uses;      /* nedges + 1 offsets into edge_use_corner */
    uint32_t *edge_use_corner;/* ncorners: the corners using each edge, ascending */
    uint32_t *vert_faces;     /* nverts + 1 offsets into vert_face */
    uint32_t *vert_face;      /* faces around each vertex, each once, ascending */
} tb_fed;

/* Plain arrays to build a mesh from (copied by tb_fed_build). */
typedef struct tb_fed_desc {
    uint32_t nverts;
    const tb_vec3 *positions;      /* nverts */
    const tb_vec3 *normals;        /* nverts, or NULL */
    const tb_vec2 *uvs;            /* nverts, or NULL */
    uint32_t nfaces;
    const uint32_t *face_nloops;   /* loops of each face (>= 1), or NULL: one loop each */
    uint32_t nloops;               /* total loops: the sum of face_nloops (nfaces if NULL) */
    const uint32_t *loop_sizes;    /* corners of each loop (>= 3) */
    const uint32_t *corners;       /* vertex indices of all loops in order */
    const int32_t *face_ids;       /* nfaces, or NULL */
    const int32_t *face_materials; /* nfaces, or NULL */
} tb_fed_desc;

/* Kinds of problems validation finds. The first group is fatal: a mesh with
 * any of them is not built (readers report the location in the file). The
 * second group is reported by tb_fed_check and never stops a mesh from
 * being used; everything downstream (triangulation, subdivision, ray
 * tracing) works on such meshes. */
typedef enum tb_fed_issue_kind {
    /* fatal */
    TB_FED_ISSUE_BAD_COUNT = 0,   /* a count out of range or inconsistent */
    TB_FED_ISSUE_INDEX,           /* vertex index >= vertex count */
    TB_FED_ISSUE_NONFINITE,       /* NaN or infinite position, normal or uv */
    TB_FED_ISSUE_REPEATED_VERTEX, /* the same vertex at two consecutive corners */
    TB_FED_ISSUE_ZERO_EDGE,       /* consecutive corners at the same position */
    TB_FED_ISSUE_FEW_VERTICES,    /* a loop with fewer than 3 distinct vertices */
    TB_FED_ISSUE_DEGENERATE,      /* a loop of (near) zero area */
    /* warnings */
    TB_FED_ISSUE_NONMANIFOLD,     /* an edge used by more than two corners */
    TB_FED_ISSUE_ORIENTATION,     /* an edge used twice in the same direction */
    TB_FED_ISSUE_HOLE_ORIENTATION,/* a hole turning the same way as its outer loop */
    TB_FED_ISSUE_NONPLANAR,       /* a face off its plane by more than TB_MESH_PLANAR_TOL */
    TB_FED_ISSUE_UNUSED_VERTEX,   /* a vertex no face uses */
} tb_fed_issue_kind;

/* Number of issue kinds. */
#define TB_FED_ISSUE_KINDS 12

/* True for the kinds that stop a mesh from being built. */
static inline bool tb_fed_issue_fatal(tb_fed_issue_kind k) { return k <= TB_FED_ISSUE_DEGENERATE; }

/* Short name of an issue kind ("non-manifold edge", ...). */
const char *tb_fed_issue_name(tb_fed_issue_kind k);

/* One problem and where it is; fields that do not apply are TB_FED_NONE. */
typedef struct tb_fed_issue {
    tb_fed_issue_kind kind;
    uint32_t face;      /* face index */
    uint32_t loop;      /* loop index (global; the face's outer loop is face_loops[face]) */
    uint32_t corner;    /* corner index (global) */
    uint32_t vertex;    /* vertex index */
    uint32_t edge;      /* edge index (warnings only) */
    char message[192];  /* the full message, as also set with tb_error for fatal ones */
} tb_fed_issue;

/* Builds a mesh from `d`, copying the arrays and deriving edges (one per
 * vertex pair) and adjacency. On a fatal problem returns TB_ERR_FORMAT (or
 * TB_ERR_ARG for missing arrays), sets the message ("face 3 (loop 4, hole 1),
 * corner 2: ...") and fills *issue if not NULL. TB_ERR_NOMEM. */
tb_status tb_fed_build(const tb_fed_desc *d, tb_fed **out, tb_fed_issue *issue);

/* Frees a mesh (NULL is allowed). */
void tb_fed_free(tb_fed *m);

/* ------------------------------------------------------------------ queries */

/* Outer loop of face f. */
static inline uint32_t tb_fed_face_outer(const tb_fed *m, uint32_t f) { return m->face_loops[f]; }
/* Number of loops of face f (1 + holes). */
static inline uint32_t tb_fed_face_nloops(const tb_fed *m, uint32_t f)
{
    return m->face_loops[f + 1] - m->face_loops[f];
}
/* First corner of face f; its corners (all loops) are first .. tb_fed_face_corner_end - 1. */
static inline uint32_t tb_fed_face_corner_begin(const tb_fed *m, uint32_t f)
{
    return m->loop_corners[m->face_loops[f]];
}
/* One past the last corner of face f. */
static inline uint32_t tb_fed_face_corner_end(const tb_fed *m, uint32_t f)
{
    return m->loop_corners[m->face_loops[f + 1]];
}
/* Number of corners of loop l. */
static inline uint32_t tb_fed_loop_size(const tb_fed *m, uint32_t l)
{
    return m->loop_corners[l + 1] - m->loop_corners[l];
}
/* Vertex k (0-based, wrapping) of loop l. */
static inline uint32_t tb_fed_loop_vertex(const tb_fed *m, uint32_t l, uint32_t k)
{
    return m->corner_vert[m->loop_corners[l] + k % tb_fed_loop_size(m, l)];
}
/* The corner after c in its loop (wrapping). */
static inline uint32_t tb_fed_corner_next(const tb_fed *m, uint32_t c)
{
    uint32_t l = m->corner_loop[c];
    return c + 1 < m->loop_corners[l + 1] ? c + 1 : m->loop_corners[l];
}
/* The face of corner c. */
static inline uint32_t tb_fed_corner_face(const tb_fed *m, uint32_t c) { return m->loop_face[m->corner_loop[c]]; }

/* Faces around vertex v: *count of them at the returned pointer, ascending. */
static inline const uint32_t *tb_fed_vertex_faces(const tb_fed *m, uint32_t v, uint32_t *count)
{
    *count = m->vert_faces[v + 1] - m->vert_faces[v];
    return m->vert_face + m->vert_faces[v];
}
/* Number of corners (loop uses) of edge e: 1 on a boundary, 2 inside a manifold. */
static inline uint32_t tb_fed_edge_nuses(const tb_fed *m, uint32_t e)
{
    return m->edge_uses[e + 1] - m->edge_uses[e];
}
/* Corner of use i of edge e (the corner the edge leaves from). */
static inline uint32_t tb_fed_edge_use(const tb_fed *m, uint32_t e, uint32_t i)
{
    return m->edge_use_corner[m->edge_uses[e] + i];
}
/* Face of use i of edge e. */
static inline uint32_t tb_fed_edge_face(const tb_fed *m, uint32_t e, uint32_t i)
{
    return tb_fed_corner_face(m, tb_fed_edge_use(m, e, i));
}
/* True if use i of edge e runs from edges[e].v[0] to v[1]. */
static inline bool tb_fed_edge_use_forward(const tb_fed *m, uint32_t e, uint32_t i)
{
    return m->corner_vert[tb_fed_edge_use(m, e, i)] == m->edges[e].v[0];
}
/* A boundary edge: used by one corner. */
static inline bool tb_fed_edge_is_boundary(const tb_fed *m, uint32_t e) { return tb_fed_edge_nuses(m, e) == 1; }
/* A non-manifold edge: used by more than two corners. */
static inline bool tb_fed_edge_is_nonmanifold(const tb_fed *m, uint32_t e) { return tb_fed_edge_nuses(m, e) > 2; }

/* The edge between vertices a and b, or TB_FED_NONE. */
uint32_t tb_fed_find_edge(const tb_fed *m, uint32_t a, uint32_t b);

/* Writes the distinct faces using edge e (ascending) to out[0 .. cap-1];
 * returns how many there are (possibly more than cap). */
uint32_t tb_fed_edge_faces(const tb_fed *m, uint32_t e, uint32_t *out, uint32_t cap);

/* Number of boundary edges. */
uint32_t tb_fed_count_boundary_edges(const tb_fed *m);

/* Number of non-manifold edges. */
uint32_t tb_fed_count_nonmanifold_edges(const tb_fed *m);

/* True if the mesh is closed and consistently oriented (watertight): every
 * edge is used exactly twice, once in each direction. */
bool tb_fed_is_closed(const tb_fed *m);

/* Euler characteristic V - E + F - H of the surface: V counts vertices used
 * by some face, H the holes (inner loops; a face with h holes is a disc with
 * h holes, whose characteristic is 1 - h). 2 for a sphere, 0 for a torus,
 * 1 for a disc. */
int64_t tb_fed_euler_characteristic(const tb_fed *m);

/* Newell normal of face f's outer loop (twice its vector area) in double. */
tb_dvec3 tb_fed_face_normal(const tb_fed *m, uint32_t f);

/* Area of face f: outer loop minus holes, each measured along the outer
 * loop's normal (exact for planar faces). */
double tb_fed_face_area(const tb_fed *m, uint32_t f);

/* --------------------------------------------------------------- validation */

/* Most issues a tb_fed_report keeps in full. */
#define TB_FED_REPORT_MAX 32

/* The warnings of a mesh (fatal problems never reach a built mesh). */
typedef struct tb_fed_report {
    uint32_t counts[TB_FED_ISSUE_KINDS]; /* how many of each kind */
    uint32_t nissues;                    /* issues kept in `issues` (the first ones found) */
    tb_fed_issue issues[TB_FED_REPORT_MAX];
    uint32_t boundary_edges;             /* edges used once (an open surface has some; not a warning) */
    bool closed;                         /* tb_fed_is_closed */
} tb_fed_report;

/* Checks a built mesh for the warning kinds (non-manifold edges, edges used
 * twice in one direction, holes turning the wrong way, non-planar faces,
 * unused vertices) and summarises it. Returns the number of warnings. */
uint32_t tb_fed_check(const tb_fed *m, tb_fed_report *r);

/* -------------------------------------------------------------------- files */

/* The two file forms (docs/fed.md). */
typedef enum tb_fed_format {
    TB_FED_FORMAT_AUTO = 0, /* writing: binary for names ending in ".fedb", else text; reading: by content */
    TB_FED_FORMAT_TEXT,     /* "fed 1" text */
    TB_FED_FORMAT_BINARY,   /* little-endian arrays after a magic number */
} tb_fed_format;

/* The 8 bytes a binary FED file starts with: "\x89FEDB\r\n\x1a" (like PNG's,
 * so text-mode transfers and truncation to 7 bits are detected). */
#define TB_FED_BINARY_MAGIC "\x89" "FEDB\r\n\x1a"

/* Reads a text FED from `f`; `name` prefixes messages ("name:line:col:
 * error: ..."). TB_ERR_FORMAT for malformed input, TB_ERR_IO, TB_ERR_NOMEM. */
tb_status tb_fed_read_text(FILE *f, const char *name, tb_fed **out);

/* Reads a binary FED from `f` ("name: byte N: error: ..."). The counts in the
 * header are checked against the input's size before anything is allocated
 * (for non-seekable input, against the bytes actually read). */
tb_status tb_fed_read_binary(FILE *f, const char *name, tb_fed **out);

/* Reads either form from `f`, deciding by its first bytes. */
tb_status tb_fed_read(FILE *f, const char *name, tb_fed **out);

/* Reads the FED file at `path` (either form). */
tb_status tb_fed_read_file(const char *path, tb_fed **out);

/* Writes the text form to `f` (shortest round-tripping float digits). */
tb_status tb_fed_write_text(FILE *f, const tb_fed *m);

/* Writes the binary form to `f`. */
tb_status tb_fed_write_binary(FILE *f, const tb_fed *m);

/* Writes `m` to `path` all or nothing (util/base/outfile.h), in `format`
 * (TB_FED_FORMAT_AUTO: binary if the name ends in ".fedb"). */
tb_status tb_fed_write_file(const char *path, const tb_fed *m, tb_fed_format format);

/* True if two meshes hold the same data: counts, positions, normals, uvs,
 * face ids and materials bit for bit, and the same loops. */
bool tb_fed_equal(const tb_fed *a, const tb_fed *b);

#endif
