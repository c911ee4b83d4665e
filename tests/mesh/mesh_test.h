/* Helpers shared by the util/mesh tests: an independent check that a set of
 * triangles tiles a polygon with holes exactly. */
#ifndef TB_TESTS_MESH_MESH_TEST_H
#define TB_TESTS_MESH_MESH_TEST_H

#include "tb_test.h"

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "util/container/array.h"
#include "util/container/hash_table.h"
#include "util/mesh/predicates.h"
#include "util/mesh/triangulate.h"

/* Twice the signed area of ring [first, first + n) of xy, in long double. */
static inline long double mt_ring_area2(const double *xy, uint32_t first, uint32_t n)
{
    long double s = 0;
    for (uint32_t k = 0; k < n; k++) {
        uint32_t i = first + k, j = first + (k + 1) % n;
        s += (long double)xy[2 * i] * xy[2 * j + 1] - (long double)xy[2 * j] * xy[2 * i + 1];
    }
    return s;
}

/* Adds `d` to the net count of the directed edge u->v (and -d to v->u): the
 * 1-chain boundary of a set of triangles. */
static inline void mt_chain_add(tb_htab *h, uint32_t u, uint32_t v, int64_t d)
{
    if (u == v)
        return; /* zero-length edges (coincident points with one index) cancel */
    if (u > v) {
        uint32_t t = u;
        u = v;
        v = t;
        d = -d;
    }
    uint64_t key = (uint64_t)u << 32 | v, old = 0;
    tb_htab_get(h, key, &old);
    assert_int_equal(tb_htab_put(h, key, (uint64_t)((int64_t)old + d)), TB_OK);
}

/* Checks that tris tile the polygon given by xy and ring sizes (ring 0
 * outer, the rest holes, any orientation):
 *  - every triangle is counter-clockwise by the exact predicate (strictly,
 *    except for at most `allowed_flat` zero-area ones);
 *  - the boundary of the triangles as a 1-chain equals the polygon boundary
 *    (points at one position identified)
 *    (outer ring counter-clockwise, holes clockwise); with positive
 *    triangles this means every point of the polygon is covered exactly once
 *    and nothing outside is covered;
 *  - the triangle areas add up to the polygon area (long double shoelace).
 * Returns the number of zero-area triangles. */
static inline uint32_t mt_check_tiling(const double *xy, const uint32_t *ring_size, uint32_t nrings,
                                       const tb_tri *tris, size_t ntris, uint32_t allowed_flat)
{
    /* Points at the same position count as one (canon[i]: the lowest index
     * there): where a hole touches the boundary at a point that has two
     * indices, the triangles may use either. */
    uint32_t npts = 0;
    for (uint32_t r = 0; r < nrings; r++)
        npts += ring_size[r];
    uint32_t *canon = malloc(sizeof(uint32_t) * (npts ? npts : 1));
    assert_non_null(canon);
    tb_htab pos;
    tb_htab_init(&pos, TB_HTAB_U64);
    for (uint32_t i = 0; i < npts; i++) {
        uint64_t bx, by, hit;
        double x = xy[2 * i] + 0.0, y = xy[2 * i + 1] + 0.0; /* -0 -> +0 */
        memcpy(&bx, &x, 8);
        memcpy(&by, &y, 8);
        uint64_t key = tb_hash_u64(bx) ^ (by * 0x9e3779b97f4a7c15ull);
        canon[i] = i;
        /* chain of candidates under one hash: probe key, key+1, ... */
        for (;; key++) {
            if (!tb_htab_get(&pos, key, &hit)) {
                assert_int_equal(tb_htab_put(&pos, key, i), TB_OK);
                break;
            }
            if (xy[2 * hit] == x && xy[2 * hit + 1] == y) {
                canon[i] = (uint32_t)hit;
                break;
            }
        }
    }
    tb_htab_free(&pos);
    tb_htab h;
    tb_htab_init(&h, TB_HTAB_U64);
    long double tri_area = 0, tri_abs = 0, poly_area = 0;
    uint32_t flat = 0;
    for (size_t t = 0; t < ntris; t++) {
        const uint32_t *v = tris[t].v;
        double o = tb_orient2d(xy[2 * v[0]], xy[2 * v[0] + 1], xy[2 * v[1]], xy[2 * v[1] + 1],
                               xy[2 * v[2]], xy[2 * v[2] + 1]);
        if (o < 0)
            fail_msg("triangle %zu (%u %u %u) is clockwise", t, v[0], v[1], v[2]);
        if (o == 0)
            flat++;
        for (int k = 0; k < 3; k++)
            mt_chain_add(&h, canon[v[k]], canon[v[(k + 1) % 3]], 1);
        long double a = 0;
        for (int k = 0; k < 3; k++) {
            uint32_t i = v[k], j = v[(k + 1) % 3];
            a += (long double)xy[2 * i] * xy[2 * j + 1] - (long double)xy[2 * j] * xy[2 * i + 1];
        }
        tri_area += a;
        tri_abs += a < 0 ? -a : a;
    }
    if (flat > allowed_flat)
        fail_msg("%u zero-area triangles (%u allowed)", flat, allowed_flat);
    uint32_t first = 0;
    for (uint32_t r = 0; r < nrings; r++) {
        long double a = mt_ring_area2(xy, first, ring_size[r]);
        bool reverse = (r == 0) ? a < 0 : a > 0;
        poly_area += reverse ? -a : a;
        for (uint32_t k = 0; k < ring_size[r]; k++) {
            uint32_t i = first + k, j = first + (k + 1) % ring_size[r];
            if (reverse)
                mt_chain_add(&h, canon[j], canon[i], -1);
            else
                mt_chain_add(&h, canon[i], canon[j], -1);
        }
        first += ring_size[r];
    }
    size_t it = 0;
    tb_htab_entry e;
    while (tb_htab_next(&h, &it, &e))
        if (e.value != 0)
            fail_msg("edge %u-%u: triangle boundary and polygon boundary differ by %lld",
                     (unsigned)(e.key >> 32), (unsigned)(e.key & 0xffffffffu), (long long)e.value);
    tb_htab_free(&h);
    free(canon);
    long double tol = 1e-12L * (tri_abs > 0 ? tri_abs : 1);
    long double diff = tri_area - poly_area;
    if (diff < -tol || diff > tol)
        fail_msg("triangle area %.17Lg != polygon area %.17Lg", tri_area / 2, poly_area / 2);
    return flat;
}

/* Triangulates with tb_triangulate_2d and checks the tiling and the
 * triangle count N - 2 + 2 bridges - 2 splits; returns the stats. */
static inline tb_triangulate_stats mt_triangulate_checked(const double *xy, const uint32_t *ring_size,
                                                          uint32_t nrings, uint32_t allowed_flat)
{
    tb_array tris = TB_ARRAY_INIT(tb_tri);
    tb_triangulate_stats st;
    tb_status s = tb_triangulate_2d(xy, ring_size, nrings, &tris, &st);
    if (s)
        fail_msg("tb_triangulate_2d: %s", tb_last_error());
    uint64_t n = 0;
    for (uint32_t r = 0; r < nrings; r++)
        n += ring_size[r];
    const char *dump = getenv("TB_MESH_TEST_DUMP");
    if (dump && st.forced) {
        /* the failing polygon, for debugging: "ring sizes" line, then x y per line */
        FILE *f = fopen(dump, "w");
        if (f) {
            for (uint32_t r = 0; r < nrings; r++)
                fprintf(f, "%u ", ring_size[r]);
            fprintf(f, "\n");
            for (uint64_t k = 0; k < n; k++)
                fprintf(f, "%a %a\n", xy[2 * k], xy[2 * k + 1]);
            fclose(f);
        }
    }
    assert_int_equal(st.forced, 0);
    assert_int_equal(tris.len, n - 2 + 2 * (uint64_t)st.bridges - 2 * (uint64_t)st.splits);
    uint32_t flat = mt_check_tiling(xy, ring_size, nrings, tris.data, tris.len, allowed_flat);
    assert_int_equal(flat, st.degenerate);
    tb_array_free(&tris);
    return st;
}

#endif
