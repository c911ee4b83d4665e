/* Red-green refinement of element meshes with a refinement tree
 * (util/mesh/refine.h; docs/meshing.md, "Adaptive refinement").
 *
 * State: a forest of red nodes (the base elements and their red children,
 * four per split node, stored consecutively) and the edges they use, each
 * edge once per vertex pair with the nodes using it and, once split, its
 * midpoint and the edge it is a half of. All users of an edge have the same
 * red level (base edges are used by base nodes, halves and interior edges
 * of a level-k node by its level-(k+1) children), which is what makes the
 * 1-irregularity test below a lookup. The conforming mesh is rebuilt from
 * the leaves after every call, green closures included, so greens never
 * enter the tree and are undone simply by refining their red parent. */
#include "util/mesh/refine.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "util/container/hash_table.h"
#include "util/mesh/polygon.h"

typedef struct tb__rnode {
    uint32_t v[4];     /* corners as in tb_mesh_elem */
    uint32_t e[4];     /* edge of side k (v[k] -> v[k+1]) */
    uint32_t face;
    uint32_t parent;   /* node, TB_MESH_NONE for a base node */
    uint32_t child;    /* first of its 4 children, TB_MESH_NONE for a leaf */
    uint32_t base;     /* base element (root) */
    uint32_t level;
    uint32_t out_first, out_count; /* its elements in the current mesh (0 for inner nodes) */
} tb__rnode;

typedef struct tb__redge {
    uint32_t a, b;   /* a < b */
    uint32_t mid;    /* midpoint vertex, TB_MESH_NONE until split */
    uint32_t parent; /* the edge it is a half of, or TB_MESH_NONE */
    uint32_t use;    /* first user (index into uses), TB_MESH_NONE for none */
} tb__redge;

typedef struct tb__ruse {
    uint32_t node, next;
} tb__ruse;

struct tb_mesh_refiner {
    tb_mesh mesh;        /* the current conforming mesh */
    tb_array elem_node;  /* uint32_t per current element: its red leaf */
    tb_array elem_green; /* uint8_t per current element */
    tb_array nodes;      /* tb__rnode */
    tb_array edges;      /* tb__redge */
    tb_array uses;       /* tb__ruse */
    tb_htab edge_map;    /* vertex pair -> edge */
    uint32_t nbase;
    /* per call */
    tb_array stack;      /* uint32_t nodes waiting in a graded split */
    tb_array queue;      /* uint32_t leaves to check for closure */
    tb_array split_log;  /* uint32_t nodes split in this call (for undo) */
    tb_array edge_log;   /* uint32_t edges split in this call (for undo) */
    tb_mesh_refine_stats st;
    tb_status err;
};

#define TB__NODE(r, i) TB_ARRAY_AT(&(r)->nodes, tb__rnode, i)
#define TB__EDGE(r, i) TB_ARRAY_AT(&(r)->edges, tb__redge, i)

static inline uint64_t tb__rkey(uint32_t a, uint32_t b)
{
    return a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
}

static inline int tb__nside(const uint32_t v[4]) { return v[3] == TB_MESH_NONE ? 3 : 4; }

static inline tb_vec3 tb__rpos(const tb_mesh_refiner *r, uint32_t i)
{
    return TB_ARRAY_AT(&r->mesh.positions, tb_vec3, i);
}

static void tb__fail(tb_mesh_refiner *r, tb_status st)
{
    if (st && !r->err)
        r->err = st;
}

/* ------------------------------------------------------------------ pieces */

/* The edge a-b, made (unsplit, no users) if it does not exist yet. */
static uint32_t tb__get_edge(tb_mesh_refiner *r, uint32_t a, uint32_t b, uint32_t parent)
{
    uint64_t id;
    if (tb_htab_get(&r->edge_map, tb__rkey(a, b), &id))
        return (uint32_t)id;
    tb__redge e = {a < b ? a : b, a < b ? b : a, TB_MESH_NONE, parent, TB_MESH_NONE};
    tb_status st = tb_array_push(&r->edges, &e);
    if (!st)
        st = tb_htab_put(&r->edge_map, tb__rkey(a, b), r->edges.len - 1);
    tb__fail(r, st);
    return st ? 0 : (uint32_t)(r->edges.len - 1);
}

static void tb__add_use(tb_mesh_refiner *r, uint32_t e, uint32_t node)
{
    tb__ruse u = {node, TB__EDGE(r, e).use};
    tb_status st = tb_array_push(&r->uses, &u);
    if (!st)
        TB__EDGE(r, e).use = (uint32_t)(r->uses.len - 1);
    tb__fail(r, st);
}

/* A new vertex, the mean of vertices idx[0 .. n-1] (n = 2 or 4) in
 * position (relative to the first, so a mean of equal points is exact),
 * normal (renormalised) and uv. Refused when the vertices are too close
 * for float coordinates to place a distinct point between them. */
static uint32_t tb__mean_vertex(tb_mesh_refiner *r, int n, const uint32_t *idx)
{
    tb_mesh *m = &r->mesh;
    if (m->positions.len >= TB_FED_MAX_COUNT) {
        tb__fail(r, tb_error(TB_ERR_ARG, "mesh refinement: more than %u vertices", TB_FED_MAX_COUNT));
        return 0;
    }
    tb_vec3 p0 = tb__rpos(r, idx[0]);
    double x = 0, y = 0, z = 0, ext = 0;
    for (int i = 1; i < n; i++) {
        tb_vec3 p = tb__rpos(r, idx[i]);
        double dx = (double)p.x - p0.x, dy = (double)p.y - p0.y, dz = (double)p.z - p0.z;
        x += dx, y += dy, z += dz;
        ext = fmax(ext, fmax(fabs(dx), fmax(fabs(dy), fabs(dz))));
    }
    double w = 1.0 / n, ex = p0.x + w * x, ey = p0.y + w * y, ez = p0.z + w * z;
    tb_vec3 p = {(float)ex, (float)ey, (float)ez};
    /* Rounding the new point to float moves it off the true mean; once
     * that is a noticeable part (1/64) of the element's extent, its
     * children could come out flat or inverted. Dyadic coordinates round
     * exactly and go deepest. */
    double dev = fmax(fabs(p.x - ex), fmax(fabs(p.y - ey), fabs(p.z - ez)));
    if (!(ext > 0) || !(dev <= ext / 64)) {
        tb__fail(r, tb_error(TB_ERR_ARG,
                             "mesh refinement: an element near (%g, %g, %g) is too small (%g) to split at float "
                             "resolution",
                             (double)p0.x, (double)p0.y, (double)p0.z, ext));
        return 0;
    }
    tb_status st = tb_array_push(&m->positions, &p);
    if (!st)
        st = tb_mesh_push_attributes(m, n, idx, NULL);
    tb__fail(r, st);
    r->st.new_vertices++;
    return (uint32_t)(m->positions.len - 1);
}

/* Splits edge e at its midpoint (once): makes the two halves and queues
 * its leaf users for the closure check. */
static void tb__split_edge(tb_mesh_refiner *r, uint32_t e)
{
    if (TB__EDGE(r, e).mid != TB_MESH_NONE || r->err)
        return;
    tb__redge ed = TB__EDGE(r, e);
    uint32_t mid = tb__mean_vertex(r, 2, (uint32_t[]){ed.a, ed.b});
    if (r->err)
        return;
    tb__fail(r, tb_array_push(&r->edge_log, &e)); /* logged first, so an undo always sees it */
    if (r->err)
        return;
    TB__EDGE(r, e).mid = mid;
    tb__get_edge(r, ed.a, mid, e);
    tb__get_edge(r, mid, ed.b, e);
    for (uint32_t u = ed.use; u != TB_MESH_NONE && !r->err; u = TB_ARRAY_AT(&r->uses, tb__ruse, u).next) {
        uint32_t n = TB_ARRAY_AT(&r->uses, tb__ruse, u).node;
        if (TB__NODE(r, n).child == TB_MESH_NONE)
            tb__fail(r, tb_array_push(&r->queue, &n));
    }
}

/* Adds node (v, face) as a child of p; returns its index. */
static void tb__add_child(tb_mesh_refiner *r, uint32_t p, uint32_t a, uint32_t b, uint32_t c, uint32_t d)
{
    tb__rnode P = TB__NODE(r, p);
    tb__rnode n = {{a, b, c, d}, {0, 0, 0, 0}, P.face, p, TB_MESH_NONE, P.base, P.level + 1, 0, 0};
    uint32_t id = (uint32_t)r->nodes.len;
    tb_status st = tb_array_push(&r->nodes, &n);
    tb__fail(r, st);
    if (st)
        return;
    int ns = tb__nside(n.v);
    for (int k = 0; k < ns && !r->err; k++) {
        uint32_t e = tb__get_edge(r, n.v[k], n.v[(k + 1) % ns], TB_MESH_NONE);
        if (r->err)
            return;
        TB__NODE(r, id).e[k] = e;
        tb__add_use(r, e, id);
    }
}

/* The red split of leaf n, whose sides are all full edges of the mesh
 * (not halves of an edge some leaf still uses). */
static void tb__split_node(tb_mesh_refiner *r, uint32_t n)
{
    tb__rnode N = TB__NODE(r, n);
    int ns = tb__nside(N.v);
    uint32_t m[4];
    for (int k = 0; k < ns; k++) {
        tb__split_edge(r, N.e[k]);
        if (r->err)
            return;
        m[k] = TB__EDGE(r, N.e[k]).mid;
    }
    uint32_t first = (uint32_t)r->nodes.len;
    const uint32_t *v = N.v, X = TB_MESH_NONE;
    if (ns == 3) {
        /* four triangles similar to the parent, same orientation */
        tb__add_child(r, n, v[0], m[0], m[2], X);
        tb__add_child(r, n, m[0], v[1], m[1], X);
        tb__add_child(r, n, m[2], m[1], v[2], X);
        tb__add_child(r, n, m[0], m[1], m[2], X);
    } else {
        uint32_t c = tb__mean_vertex(r, 4, v);
        if (r->err)
            return;
        tb__add_child(r, n, v[0], m[0], c, m[3]);
        tb__add_child(r, n, m[0], v[1], m[1], c);
        tb__add_child(r, n, c, m[1], v[2], m[2]);
        tb__add_child(r, n, m[3], c, m[2], v[3]);
    }
    if (r->err)
        return;
    tb__fail(r, tb_array_push(&r->split_log, &n));
    if (r->err)
        return;
    TB__NODE(r, n).child = first;
    r->st.red++;
}

/* Refines leaf n red, first refining (recursively) every coarser leaf
 * whose side contains one of n's sides: splitting n would otherwise put a
 * second midpoint on that leaf's side (the mesh must stay 1-irregular).
 * Those leaves are one level coarser each time, so this ends. */
static void tb__refine_graded(tb_mesh_refiner *r, uint32_t n)
{
    size_t bottom = r->stack.len;
    tb__fail(r, tb_array_push(&r->stack, &n));
    while (r->stack.len > bottom && !r->err) {
        uint32_t x = TB_ARRAY_AT(&r->stack, uint32_t, r->stack.len - 1);
        tb__rnode X = TB__NODE(r, x);
        if (X.child != TB_MESH_NONE) {
            r->stack.len--;
            continue;
        }
        uint32_t coarse = TB_MESH_NONE;
        int ns = tb__nside(X.v);
        for (int k = 0; k < ns && coarse == TB_MESH_NONE; k++) {
            uint32_t pe = TB__EDGE(r, X.e[k]).parent;
            if (pe == TB_MESH_NONE)
                continue;
            for (uint32_t u = TB__EDGE(r, pe).use; u != TB_MESH_NONE; u = TB_ARRAY_AT(&r->uses, tb__ruse, u).next) {
                uint32_t y = TB_ARRAY_AT(&r->uses, tb__ruse, u).node;
                if (TB__NODE(r, y).child == TB_MESH_NONE) {
                    coarse = y;
                    break;
                }
            }
        }
        if (coarse != TB_MESH_NONE) {
            tb__fail(r, tb_array_push(&r->stack, &coarse));
            continue;
        }
        tb__split_node(r, x);
        if (x != n)
            r->st.graded++;
        r->stack.len--;
    }
    r->stack.len = bottom;
}

/* Number of split sides of node n, and the last one in *side. */
static int tb__split_sides(const tb_mesh_refiner *r, uint32_t n, int *side)
{
    const tb__rnode *N = &TB__NODE(r, n);
    int ns = tb__nside(N->v), count = 0;
    for (int k = 0; k < ns; k++)
        if (TB__EDGE(r, N->e[k]).mid != TB_MESH_NONE) {
            count++;
            *side = k;
        }
    return count;
}

/* ------------------------------------------------------------- the output */

/* Signed "insideness" of point p in element el of the mesh: the smallest
 * distance of p from the inner side of an edge (negative outside). */
static double tb__inside(const tb_mesh *m, const tb_mesh_elem *el, const double p[3])
{
    int n = tb_mesh_elem_size(el);
    tb_vec3 q[4];
    for (int k = 0; k < n; k++)
        q[k] = TB_ARRAY_AT(&m->positions, tb_vec3, el->v[k]);
    tb_dvec3 nv = tb_polygon_newell(q, NULL, (uint32_t)n);
    double nl = sqrt(nv.x * nv.x + nv.y * nv.y + nv.z * nv.z);
    double worst = INFINITY;
    for (int k = 0; k < n; k++) {
        tb_vec3 a = q[k], b = q[(k + 1) % n];
        double ux = (double)b.x - a.x, uy = (double)b.y - a.y, uz = (double)b.z - a.z;
        double wx = p[0] - a.x, wy = p[1] - a.y, wz = p[2] - a.z;
        double s = ((uy * wz - uz * wy) * nv.x + (uz * wx - ux * wz) * nv.y + (ux * wy - uy * wx) * nv.z) /
                   (nl * sqrt(ux * ux + uy * uy + uz * uz));
        worst = fmin(worst, s);
    }
    return worst;
}

typedef struct tb__build {
    tb_array elems, node, green, map; /* the new mesh's elements and per-element data */
    tb_array leaves;                  /* uint32_t leaves in output order */
    tb_array dfs;
} tb__build;

static void tb__build_free(tb__build *b)
{
    tb_array_free(&b->elems);
    tb_array_free(&b->node);
    tb_array_free(&b->green);
    tb_array_free(&b->map);
    tb_array_free(&b->leaves);
    tb_array_free(&b->dfs);
}

/* Emits element (a b c d) of leaf x, finding the previous element it came from. */
static void tb__emit(tb_mesh_refiner *r, tb__build *b, uint32_t x, bool green, uint32_t a, uint32_t bb, uint32_t c,
                     uint32_t d)
{
    tb_mesh_elem el = {{a, bb, c, d}, TB__NODE(r, x).face, TB_MESH_NONE};
    /* The previous elements covering it are those of the nearest ancestor
     * that was a leaf then (possibly x itself). */
    uint32_t y = x;
    while (TB__NODE(r, y).out_count == 0)
        y = TB__NODE(r, y).parent;
    const tb__rnode *Y = &TB__NODE(r, y);
    uint32_t old = Y->out_first;
    if (Y->out_count > 1) {
        int n = tb_mesh_elem_size(&el);
        double p[3] = {0, 0, 0};
        for (int k = 0; k < n; k++) {
            tb_vec3 q = tb__rpos(r, el.v[k]);
            p[0] += q.x / (double)n, p[1] += q.y / (double)n, p[2] += q.z / (double)n;
        }
        double best = -INFINITY;
        for (uint32_t i = Y->out_first; i < Y->out_first + Y->out_count; i++) {
            double s = tb__inside(&r->mesh, tb_mesh_elem_at(&r->mesh, i), p);
            if (s > best)
                best = s, old = i;
        }
    }
    const tb_mesh_elem *oe = tb_mesh_elem_at(&r->mesh, old);
    bool kept = y == x && memcmp(oe->v, el.v, sizeof el.v) == 0;
    el.parent = kept ? TB_MESH_NONE : old;
    uint8_t g = green;
    tb_status st = tb_array_push(&b->elems, &el);
    if (!st)
        st = tb_array_push(&b->node, &x);
    if (!st)
        st = tb_array_push(&b->green, &g);
    if (!st)
        st = tb_array_push(&b->map, &old);
    tb__fail(r, st);
}

/* The conforming mesh of the current tree: every leaf in tree order, as
 * itself or, with split sides, as its green closure. Replaces r->mesh's
 * elements only on success. */
static void tb__rebuild(tb_mesh_refiner *r, tb_array *old_of_new)
{
    tb__build b;
    tb_array_init(&b.elems, sizeof(tb_mesh_elem));
    tb_array_init(&b.node, sizeof(uint32_t));
    tb_array_init(&b.green, sizeof(uint8_t));
    tb_array_init(&b.map, sizeof(uint32_t));
    tb_array_init(&b.leaves, sizeof(uint32_t));
    tb_array_init(&b.dfs, sizeof(uint32_t));
    r->st.green = 0;
    for (uint32_t root = 0; root < r->nbase && !r->err; root++) {
        tb__fail(r, tb_array_push(&b.dfs, &root));
        while (b.dfs.len && !r->err) {
            uint32_t x = TB_ARRAY_AT(&b.dfs, uint32_t, --b.dfs.len);
            tb__rnode X = TB__NODE(r, x);
            if (X.child != TB_MESH_NONE) {
                for (uint32_t k = 4; k-- > 0;) {
                    uint32_t c = X.child + k;
                    tb__fail(r, tb_array_push(&b.dfs, &c));
                }
                continue;
            }
            tb__fail(r, tb_array_push(&b.leaves, &x));
            int side = 0, ns = tb__nside(X.v);
            int split = tb__split_sides(r, x, &side);
            const uint32_t *v = X.v;
            if (split == 0) {
                tb__emit(r, &b, x, false, v[0], v[1], v[2], v[3]);
            } else if (split == 1) {
                uint32_t m = TB__EDGE(r, X.e[side]).mid, X3 = TB_MESH_NONE;
                uint32_t a = v[side], c = v[(side + 1) % ns], d = v[(side + 2) % ns];
                if (ns == 3) {
                    tb__emit(r, &b, x, true, a, m, d, X3);
                    tb__emit(r, &b, x, true, m, c, d, X3);
                } else {
                    uint32_t e = v[(side + 3) % 4];
                    tb__emit(r, &b, x, true, m, c, d, X3);
                    tb__emit(r, &b, x, true, m, d, e, X3);
                    tb__emit(r, &b, x, true, m, e, a, X3);
                }
                r->st.green += (uint32_t)(ns - 1);
            } else if (split == 2 && ns == 4) {
                /* A quad with two split sides: opposite ones cut it into
                 * two quads; adjacent ones (k and k+1, around corner
                 * k+1) into the corner triangle and a fan from the
                 * opposite corner k+3. */
                uint32_t m[4];
                for (int k = 0; k < 4; k++)
                    m[k] = TB__EDGE(r, X.e[k]).mid;
                if (m[0] != TB_MESH_NONE && m[2] != TB_MESH_NONE) {
                    tb__emit(r, &b, x, true, v[0], m[0], m[2], v[3]);
                    tb__emit(r, &b, x, true, m[0], v[1], v[2], m[2]);
                    r->st.green += 2;
                } else if (m[1] != TB_MESH_NONE && m[3] != TB_MESH_NONE) {
                    tb__emit(r, &b, x, true, v[0], v[1], m[1], m[3]);
                    tb__emit(r, &b, x, true, m[3], m[1], v[2], v[3]);
                    r->st.green += 2;
                } else {
                    int k = m[side] != TB_MESH_NONE && m[(side + 3) % 4] != TB_MESH_NONE ? (side + 3) % 4 : side;
                    uint32_t a = m[k], bm = m[(k + 1) % 4], X3 = TB_MESH_NONE;
                    uint32_t c0 = v[k], c1 = v[(k + 1) % 4], c2 = v[(k + 2) % 4], c3 = v[(k + 3) % 4];
                    tb__emit(r, &b, x, true, a, c1, bm, X3);
                    tb__emit(r, &b, x, true, c3, c0, a, X3);
                    tb__emit(r, &b, x, true, c3, a, bm, X3);
                    tb__emit(r, &b, x, true, c3, bm, c2, X3);
                    r->st.green += 4;
                }
            } else {
                tb__fail(r, tb_error(TB_ERR_NUMERIC, "mesh refinement: leaf %u has %d split sides after closure", x,
                                     split));
            }
        }
    }
    if (!r->err && old_of_new) {
        tb_array_clear(old_of_new);
        tb__fail(r, tb_array_push_n(old_of_new, b.map.data, b.map.len));
    }
    if (!r->err) {
        /* Record where each leaf's elements are, for the next call; inner
         * nodes have none. */
        for (size_t i = 0; i < r->nodes.len; i++)
            TB__NODE(r, i).out_count = 0;
        for (size_t i = 0; i < b.node.len; i++) {
            tb__rnode *X = &TB__NODE(r, TB_ARRAY_AT(&b.node, uint32_t, i));
            if (X->out_count++ == 0)
                X->out_first = (uint32_t)i;
        }
        tb_array t = r->mesh.elems;
        r->mesh.elems = b.elems, b.elems = t;
        t = r->elem_node, r->elem_node = b.node, b.node = t;
        t = r->elem_green, r->elem_green = b.green, b.green = t;
    }
    tb__build_free(&b);
}

/* ------------------------------------------------------------------ public */

void tb_mesh_refiner_free(tb_mesh_refiner *r)
{
    if (!r)
        return;
    tb_mesh_free(&r->mesh);
    tb_array_free(&r->elem_node);
    tb_array_free(&r->elem_green);
    tb_array_free(&r->nodes);
    tb_array_free(&r->edges);
    tb_array_free(&r->uses);
    tb_htab_free(&r->edge_map);
    tb_array_free(&r->stack);
    tb_array_free(&r->queue);
    tb_array_free(&r->split_log);
    tb_array_free(&r->edge_log);
    free(r);
}

tb_status tb_mesh_refiner_create(const tb_mesh *base, tb_mesh_refiner **out)
{
    *out = NULL;
    size_t nv = base->positions.len, ne = base->elems.len;
    if ((base->normals.len && base->normals.len != nv) || (base->uvs.len && base->uvs.len != nv))
        return tb_error(TB_ERR_ARG, "mesh refinement: %zu normals and %zu uvs for %zu vertices", base->normals.len,
                        base->uvs.len, nv);
    /* The adjacency build validates every element: indices, finite
     * positions, no repeated vertex, no zero-length edge, no zero area. */
    tb_fed *adj = NULL;
    tb_status st = tb_mesh_adjacency(base, &adj);
    tb_fed_free(adj);
    if (st)
        return tb_error_context(st, "mesh refinement: base mesh");
    for (size_t i = 0; i < ne; i++) {
        const tb_mesh_elem *e = tb_mesh_elem_at(base, i);
        if (e->v[3] != TB_MESH_NONE && !tb_mesh_quad_convex(base, e->v))
            return tb_error(TB_ERR_FORMAT, "mesh refinement: base element %zu is a quad that is not strictly convex", i);
    }
    tb_mesh_refiner *r = calloc(1, sizeof *r);
    if (!r)
        return tb_error(TB_ERR_NOMEM, "mesh refinement: out of memory");
    tb_mesh_init(&r->mesh);
    tb_array_init(&r->elem_node, sizeof(uint32_t));
    tb_array_init(&r->elem_green, sizeof(uint8_t));
    tb_array_init(&r->nodes, sizeof(tb__rnode));
    tb_array_init(&r->edges, sizeof(tb__redge));
    tb_array_init(&r->uses, sizeof(tb__ruse));
    tb_htab_init(&r->edge_map, TB_HTAB_U64);
    tb_array_init(&r->stack, sizeof(uint32_t));
    tb_array_init(&r->queue, sizeof(uint32_t));
    tb_array_init(&r->split_log, sizeof(uint32_t));
    tb_array_init(&r->edge_log, sizeof(uint32_t));
    r->nbase = (uint32_t)ne;
    st = tb_array_push_n(&r->mesh.positions, base->positions.data, nv);
    if (!st)
        st = tb_array_push_n(&r->mesh.normals, base->normals.data, base->normals.len);
    if (!st)
        st = tb_array_push_n(&r->mesh.uvs, base->uvs.data, base->uvs.len);
    if (!st)
        st = tb_array_push_n(&r->mesh.elems, base->elems.data, ne);
    for (size_t i = 0; i < ne && !st && !r->err; i++) {
        const tb_mesh_elem *e = tb_mesh_elem_at(base, i);
        tb__rnode n = {{e->v[0], e->v[1], e->v[2], e->v[3]}, {0, 0, 0, 0}, e->face, TB_MESH_NONE, TB_MESH_NONE,
                       (uint32_t)i, 0, (uint32_t)i, 1};
        uint32_t id = (uint32_t)i;
        uint8_t g = 0;
        st = tb_array_push(&r->nodes, &n);
        if (!st)
            st = tb_array_push(&r->elem_node, &id);
        if (!st)
            st = tb_array_push(&r->elem_green, &g);
        int ns = tb__nside(n.v);
        for (int k = 0; k < ns && !st && !r->err; k++) {
            uint32_t ed = tb__get_edge(r, n.v[k], n.v[(k + 1) % ns], TB_MESH_NONE);
            if (!r->err) {
                TB__NODE(r, id).e[k] = ed;
                tb__add_use(r, ed, id);
            }
        }
    }
    if (!st)
        st = r->err;
    if (st) {
        tb_mesh_refiner_free(r);
        return st;
    }
    *out = r;
    return TB_OK;
}

const tb_mesh *tb_mesh_refiner_mesh(const tb_mesh_refiner *r) { return &r->mesh; }

uint32_t tb_mesh_refiner_level(const tb_mesh_refiner *r, size_t i)
{
    return TB__NODE(r, TB_ARRAY_AT(&r->elem_node, uint32_t, i)).level;
}

uint32_t tb_mesh_refiner_base(const tb_mesh_refiner *r, size_t i)
{
    return TB__NODE(r, TB_ARRAY_AT(&r->elem_node, uint32_t, i)).base;
}

bool tb_mesh_refiner_is_green(const tb_mesh_refiner *r, size_t i)
{
    return TB_ARRAY_AT(&r->elem_green, uint8_t, i) != 0;
}

static int tb__cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

tb_status tb_mesh_refine(tb_mesh_refiner *r, const uint32_t *marked, size_t nmarked, tb_array *old_of_new,
                         tb_mesh_refine_stats *stats)
{
    size_t ne = r->mesh.elems.len;
    for (size_t i = 0; i < nmarked; i++)
        if (marked[i] >= ne)
            return tb_error(TB_ERR_ARG, "mesh refinement: marked element %u of %zu", marked[i], ne);
    r->st = (tb_mesh_refine_stats){0};
    r->err = TB_OK;
    r->stack.len = r->queue.len = r->split_log.len = r->edge_log.len = 0;
    size_t nn0 = r->nodes.len, ne0 = r->edges.len, nu0 = r->uses.len, nv0 = r->mesh.positions.len;
    size_t nnorm0 = r->mesh.normals.len, nuv0 = r->mesh.uvs.len;

    /* The marked elements as sorted distinct elements, then as their red
     * leaves (a green element stands for its red parent): the result
     * depends on the set only. */
    uint32_t *todo = malloc(sizeof(uint32_t) * (nmarked ? nmarked : 1));
    if (!todo)
        return tb_error(TB_ERR_NOMEM, "mesh refinement: out of memory");
    memcpy(todo, marked, sizeof(uint32_t) * nmarked);
    qsort(todo, nmarked, sizeof *todo, tb__cmp_u32);
    size_t nt = 0;
    for (size_t i = 0; i < nmarked; i++)
        if (i == 0 || todo[i] != todo[i - 1])
            todo[nt++] = todo[i];
    r->st.marked = (uint32_t)nt;
    for (size_t i = 0; i < nt; i++)
        todo[i] = TB_ARRAY_AT(&r->elem_node, uint32_t, todo[i]);
    qsort(todo, nt, sizeof *todo, tb__cmp_u32);

    for (size_t i = 0; i < nt && !r->err; i++)
        if (TB__NODE(r, todo[i]).child == TB_MESH_NONE && TB__NODE(r, todo[i]).level < TB_MESH_REFINE_MAX_LEVEL)
            tb__refine_graded(r, todo[i]);
    free(todo);

    /* Closure: a leaf with more split sides than a green pattern handles
     * (a triangle with 2, a quad with 3) is split red (which splits more
     * edges and queues their leaves), until none is left; the rest get
     * green closures when the mesh is rebuilt. */
    for (size_t q = 0; q < r->queue.len && !r->err; q++) {
        uint32_t x = TB_ARRAY_AT(&r->queue, uint32_t, q);
        int side;
        if (TB__NODE(r, x).child == TB_MESH_NONE && tb__split_sides(r, x, &side) >= tb__nside(TB__NODE(r, x).v) - 1) {
            uint32_t before = r->st.red;
            tb__refine_graded(r, x);
            if (r->st.red > before)
                r->st.closure++;
        }
    }
    if (!r->err)
        tb__rebuild(r, old_of_new);

    tb_status st = r->err;
    if (st) {
        /* Undo everything this call did: the tree, the edges and their
         * users, the vertices. The elements were not replaced. */
        for (size_t i = 0; i < r->split_log.len; i++)
            TB__NODE(r, TB_ARRAY_AT(&r->split_log, uint32_t, i)).child = TB_MESH_NONE;
        for (size_t i = 0; i < r->edge_log.len; i++)
            TB__EDGE(r, TB_ARRAY_AT(&r->edge_log, uint32_t, i)).mid = TB_MESH_NONE;
        for (size_t i = ne0; i < r->edges.len; i++)
            tb_htab_del(&r->edge_map, tb__rkey(TB__EDGE(r, i).a, TB__EDGE(r, i).b));
        r->edges.len = ne0;
        for (size_t i = 0; i < ne0; i++) {
            uint32_t u = TB__EDGE(r, i).use;
            while (u != TB_MESH_NONE && u >= nu0)
                u = TB_ARRAY_AT(&r->uses, tb__ruse, u).next;
            TB__EDGE(r, i).use = u;
        }
        r->uses.len = nu0;
        r->nodes.len = nn0;
        r->mesh.positions.len = nv0;
        r->mesh.normals.len = nnorm0;
        r->mesh.uvs.len = nuv0;
        r->err = TB_OK;
    }
    if (stats)
        *stats = r->st;
    return st;
}
