// CSG trees in the intersect kernel: host/object's interval lists
// (csg.c, rules in host/object/csg.h) per ray with bounded storage.
//
// The host writes a tree as a post-order program (shared/bvh.h, "CSG"):
// a leaf op pushes the leaf's crossings with the whole line (in order of t,
// entries and exits alternating) as a list on a stack; a node op with k
// children replaces the top k lists by the node's list: their ends swept in
// order of (t, child, position), ends closer than TB_CSG_TOL (relative to
// the ray's scale |o|max / |d|max plus |t|) applied as one batch, and an end
// reported where the node's membership changes: the lowest-numbered child's
// end whose own change agrees with the node's (an entry, or a subtracted
// child's exit), the first in t within that child. The lists share one pool
// of TB_CSG_POOL crossings, at most TB_CSG_LISTS lists deep; the host
// refuses a tree that could need more (host/gpu/intersect.c, tb__csg_plan),
// so nothing is ever dropped.
//
// Included by lib/bvh_traverse.glsl after the leaf crossing function
// tb_bvh_leaf_xings (which appends a leaf's crossings with tb_csg_push).
#ifndef TB_LIB_CSG_GLSL
#define TB_LIB_CSG_GLSL

#include "shared/bvh.h"
#include "xings.glsl"

// Crossings of one ray's pending lists; a CSG node needs at most the sum of
// its children's (checked on the host against these bounds).
const int TB_CSG_POOL = TB_GPU_CSG_POOL;
const int TB_CSG_LISTS = TB_GPU_CSG_LISTS;

// Ends of different children closer than this (relative) are one event:
// 2^-17, float rounding of a crossing's t (about 2^-24 times a few dozen),
// where C uses 2^-40 for double.
const float TB_CSG_TOL = 9.5367431640625e-07;

// The pool: crossing i is at t cs_t[i] on leaf cs_leaf[i] (its leaf
// reference, TB_GPU_REF_* | placed index), with cs_fd[i] = face << 2 |
// (too near the origin to resolve in float: 2) | (an entry: 1).
float tb_cs_t[TB_CSG_POOL];
uint tb_cs_leaf[TB_CSG_POOL];
uint tb_cs_fd[TB_CSG_POOL];
int tb_cs_n;
// The lists on the stack: list i starts at pool entry tb_ls[i] and ends where
// the next starts (the last at tb_cs_n).
int tb_ls[TB_CSG_LISTS];
int tb_nls;
// A node's output, before it replaces its children's lists.
float tb_co_t[TB_CSG_POOL];
uint tb_co_leaf[TB_CSG_POOL];
uint tb_co_fd[TB_CSG_POOL];
// Sort order and child of the entries being merged.
int tb_cs_ord[TB_CSG_POOL];
uint tb_cs_child[TB_CSG_POOL];

// Appends a crossing to the pool (the host's bound keeps it within).
void tb_csg_push(float t, uint leaf, uint fd)
{
    if (tb_cs_n < TB_CSG_POOL) {
        tb_cs_t[tb_cs_n] = t;
        tb_cs_leaf[tb_cs_n] = leaf;
        tb_cs_fd[tb_cs_n] = fd;
        ++tb_cs_n;
    }
}

// Appends a primitive's list x (closed solids: entries at even positions);
// `near` marks crossings with t below tlo (unresolvable in float).
void tb_csg_push_xl(tb_xl x, uint leaf, float tlo)
{
    for (int i = 0; i < x.n; ++i)
        tb_csg_push(x.t[i], leaf,
                    (x.f[i] & ~TB_XING_OPEN) << 2 | (x.t[i] < tlo ? 2u : 0u) | ((i & 1) == 0 ? 1u : 0u));
}

// Node membership from the count of children inside (tb__member).
bool tb_csg_member(uint op, int nin, int k, bool first_in)
{
    if (op == TB_GPU_CSG_UNION)
        return nin > 0;
    if (op == TB_GPU_CSG_INTERSECTION)
        return nin == k;
    return first_in && nin == 1;
}

// True if pool entry a precedes b: (t, child, position).
bool tb_csg_before(int a, int b)
{
    if (tb_cs_t[a] != tb_cs_t[b])
        return tb_cs_t[a] < tb_cs_t[b];
    if (tb_cs_child[a] != tb_cs_child[b])
        return tb_cs_child[a] < tb_cs_child[b];
    return a < b;
}

// Starts a list (a leaf's crossings follow with tb_csg_push).
void tb_csg_open_list()
{
    if (tb_nls < TB_CSG_LISTS)
        tb_ls[tb_nls++] = tb_cs_n;
}

// Replaces the top k lists (the node's children, in order) by the node's
// list (op TB_GPU_CSG_*); `scale` is the ray's |o|max / |d|max.
void tb_csg_merge(uint op, int k, float scale)
{
    if (k < 1 || k > tb_nls)
        return; // not a program the host writes
    int first = tb_nls - k, base = tb_ls[first];
    int m = tb_cs_n - base;
    for (int c = 0; c < k; ++c) {
        int e = c + 1 < k ? tb_ls[first + c + 1] : tb_cs_n;
        for (int i = tb_ls[first + c]; i < e; ++i)
            tb_cs_child[i] = uint(c);
    }
    // Insertion sort of the entries (nearly sorted: children's sorted lists in turn).
    for (int i = 0; i < m; ++i) {
        int e = base + i, j = i;
        while (j > 0 && tb_csg_before(e, tb_cs_ord[j - 1])) {
            tb_cs_ord[j] = tb_cs_ord[j - 1];
            --j;
        }
        tb_cs_ord[j] = e;
    }
    uint state = 0u; // bit c: inside child c
    int nin = 0, nout = 0;
    bool in_node = false;
    for (int i = 0; i < m;) {
        float ti = tb_cs_t[tb_cs_ord[i]];
        float tend = ti + TB_CSG_TOL * (scale + abs(ti));
        int j = i;
        for (; j < m && tb_cs_t[tb_cs_ord[j]] <= tend; ++j) {
            int q = tb_cs_ord[j];
            uint bit = 1u << tb_cs_child[q];
            bool now = (tb_cs_fd[q] & 1u) != 0u;
            if (now != ((state & bit) != 0u)) {
                nin += now ? 1 : -1;
                state ^= bit;
            }
        }
        bool after = tb_csg_member(op, nin, k, (state & 1u) != 0u);
        if (after != in_node) {
            bool want = after; // an entry of the node
            int best = -1;
            for (int q = i; q < j; ++q) {
                int e = tb_cs_ord[q];
                bool eff = (tb_cs_fd[e] & 1u) != 0u;
                if (op == TB_GPU_CSG_DIFFERENCE && tb_cs_child[e] > 0u)
                    eff = !eff;
                if (eff == want && (best < 0 || tb_cs_child[e] < tb_cs_child[best]))
                    best = e;
            }
            if (best >= 0 && nout < TB_CSG_POOL) {
                tb_co_t[nout] = tb_cs_t[best];
                tb_co_leaf[nout] = tb_cs_leaf[best];
                tb_co_fd[nout++] = (tb_cs_fd[best] & ~1u) | (want ? 1u : 0u);
                in_node = after;
            }
        }
        i = j;
    }
    if (in_node && nout > 0 && nout < TB_CSG_POOL) { // close a dangling interval, as C
        tb_co_t[nout] = tb_co_t[nout - 1];
        tb_co_leaf[nout] = tb_co_leaf[nout - 1];
        tb_co_fd[nout] = tb_co_fd[nout - 1] & ~1u;
        ++nout;
    }
    for (int i = 0; i < nout; ++i) {
        tb_cs_t[base + i] = tb_co_t[i];
        tb_cs_leaf[base + i] = tb_co_leaf[i];
        tb_cs_fd[base + i] = tb_co_fd[i];
    }
    tb_cs_n = base + nout;
    tb_nls = first + 1;
}

#endif
