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
// The child of each entry being merged (tb_csg_merge sorts the entries in
// place and writes the node's list over them, so no second pool is kept:
// the private arrays' size is the kernel's cost on lavapipe, docs/gpu.md
// "Speed").
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
    for (int c = 0; c < k; ++c) {
        int e = c + 1 < k ? tb_ls[first + c + 1] : tb_cs_n;
        for (int i = tb_ls[first + c]; i < e; ++i)
            tb_cs_child[i] = uint(c);
    }
    // Stable insertion sort of the entries by (t, child), in place (nearly
    // sorted: the children's sorted lists in turn), so ties keep their
    // position as the third key.
    for (int i = base + 1; i < tb_cs_n; ++i) {
        float t = tb_cs_t[i];
        uint l = tb_cs_leaf[i], fd = tb_cs_fd[i], c = tb_cs_child[i];
        int j = i;
        while (j > base && (tb_cs_t[j - 1] > t || (tb_cs_t[j - 1] == t && tb_cs_child[j - 1] > c))) {
            tb_cs_t[j] = tb_cs_t[j - 1];
            tb_cs_leaf[j] = tb_cs_leaf[j - 1];
            tb_cs_fd[j] = tb_cs_fd[j - 1];
            tb_cs_child[j] = tb_cs_child[j - 1];
            --j;
        }
        tb_cs_t[j] = t;
        tb_cs_leaf[j] = l;
        tb_cs_fd[j] = fd;
        tb_cs_child[j] = c;
    }
    // The sweep: the node's list is written over the entries already swept
    // (each batch of ends gives at most one, so entry base + nout is never
    // one still to be read).
    uint state = 0u; // bit c: inside child c
    int nin = 0, nout = 0;
    bool in_node = false;
    for (int i = base; i < tb_cs_n;) {
        float ti = tb_cs_t[i];
        float tend = ti + TB_CSG_TOL * (scale + abs(ti));
        int j = i;
        for (; j < tb_cs_n && tb_cs_t[j] <= tend; ++j) {
            uint bit = 1u << tb_cs_child[j];
            bool now = (tb_cs_fd[j] & 1u) != 0u;
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
                bool eff = (tb_cs_fd[q] & 1u) != 0u;
                if (op == TB_GPU_CSG_DIFFERENCE && tb_cs_child[q] > 0u)
                    eff = !eff;
                if (eff == want && (best < 0 || tb_cs_child[q] < tb_cs_child[best]))
                    best = q;
            }
            if (best >= 0 && base + nout < TB_CSG_POOL) {
                int o = base + nout++;
                tb_cs_t[o] = tb_cs_t[best];
                tb_cs_leaf[o] = tb_cs_leaf[best];
                tb_cs_fd[o] = (tb_cs_fd[best] & ~1u) | (want ? 1u : 0u);
                in_node = after;
            }
        }
        i = j;
    }
    if (in_node && nout > 0 && base + nout < TB_CSG_POOL) { // close a dangling interval, as C
        int o = base + nout++;
        tb_cs_t[o] = tb_cs_t[o - 1];
        tb_cs_leaf[o] = tb_cs_leaf[o - 1];
        tb_cs_fd[o] = tb_cs_fd[o - 1] & ~1u;
    }
    tb_cs_n = base + nout;
    tb_nls = first + 1;
}

#endif
