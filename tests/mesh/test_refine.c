/* util/mesh/refine: conforming red-green refinement, checked independently
 * after every step: every interior edge used by exactly two elements in
 * opposite directions, boundary edges only on the base boundary, no vertex
 * inside another element's edge, every element facing like its face, area
 * per FED face preserved (exactly, in long double, for dyadic coordinates),
 * each new element inside the old element the map names; plus bounded
 * angles under repeated refinement of one spot, determinism and refusals. */
#include "tb_test.h"

#include <float.h>
#include <string.h>

#include "util/container/hash_table.h"
#include "util/math/float.h"
#include "util/mesh/mesh.h"
#include "util/mesh/refine.h"

/* ------------------------------------------------------------------ helpers */

static tb_vec3 P(const tb_mesh *m, uint32_t i) { return TB_ARRAY_AT(&m->positions, tb_vec3, i); }

/* Newell normal (twice the vector area) of an element, in long double. */
static void newell(const tb_mesh *m, const tb_mesh_elem *e, long double n[3])
{
    int k = tb_mesh_elem_size(e);
    n[0] = n[1] = n[2] = 0;
    for (int i = 0; i < k; i++) {
        tb_vec3 a = P(m, e->v[i]), b = P(m, e->v[(i + 1) % k]);
        n[0] += ((long double)a.y - b.y) * ((long double)a.z + b.z);
        n[1] += ((long double)a.z - b.z) * ((long double)a.x + b.x);
        n[2] += ((long double)a.x - b.x) * ((long double)a.y + b.y);
    }
}

/* Smallest interior angle of an element, degrees. */
static double min_angle_pts(const tb_vec3 *q, int n)
{
    double worst = 180;
    for (int i = 0; i < n; i++) {
        tb_vec3 p = q[i], a = q[(i + 1) % n], b = q[(i + n - 1) % n];
        double ux = (double)a.x - p.x, uy = (double)a.y - p.y, uz = (double)a.z - p.z;
        double wx = (double)b.x - p.x, wy = (double)b.y - p.y, wz = (double)b.z - p.z;
        double cx = uy * wz - uz * wy, cy = uz * wx - ux * wz, cz = ux * wy - uy * wx;
        double ang = atan2(sqrt(cx * cx + cy * cy + cz * cz), ux * wx + uy * wy + uz * wz) * 180 / TB_PI;
        worst = fmin(worst, ang);
    }
    return worst;
}

static double elem_min_angle(const tb_mesh *m, const tb_mesh_elem *e)
{
    tb_vec3 q[4];
    int n = tb_mesh_elem_size(e);
    for (int k = 0; k < n; k++)
        q[k] = P(m, e->v[k]);
    return min_angle_pts(q, n);
}

static double mesh_min_angle(const tb_mesh *m)
{
    double worst = 180;
    for (size_t i = 0; i < tb_mesh_nelems(m); i++)
        worst = fmin(worst, elem_min_angle(m, tb_mesh_elem_at(m, i)));
    return worst;
}

/* The angle bound red-green refinement promises for a base mesh: red
 * children of triangles are similar to them (and of squares, squares), so
 * every element is similar to a base element or to one of its green
 * splits (a triangle cut from a side's midpoint to the opposite corner, a
 * quad fanned from a side's midpoint). */
static double shape_bound(const tb_mesh *m)
{
    double worst = 180;
    for (size_t i = 0; i < tb_mesh_nelems(m); i++) {
        const tb_mesh_elem *e = tb_mesh_elem_at(m, i);
        int n = tb_mesh_elem_size(e);
        tb_vec3 q[4];
        for (int k = 0; k < n; k++)
            q[k] = P(m, e->v[k]);
        worst = fmin(worst, min_angle_pts(q, n));
        for (int s = 0; s < n; s++) {
            tb_vec3 a = q[s], b = q[(s + 1) % n];
            tb_vec3 mid = {(a.x + b.x) / 2, (a.y + b.y) / 2, (a.z + b.z) / 2};
            for (int k = 1; k < n; k++) { /* fan triangles (mid, q[s+k], q[s+k+1]) */
                tb_vec3 t[3] = {mid, q[(s + k) % n], q[(s + k + 1) % n]};
                worst = fmin(worst, min_angle_pts(t, 3));
            }
        }
        if (n == 4) {
            tb_vec3 mid[4];
            for (int s = 0; s < 4; s++)
                mid[s] = (tb_vec3){(q[s].x + q[(s + 1) % 4].x) / 2, (q[s].y + q[(s + 1) % 4].y) / 2,
                                   (q[s].z + q[(s + 1) % 4].z) / 2};
            for (int s = 0; s < 2; s++) { /* opposite sides s, s+2: two quads */
                tb_vec3 h1[4] = {q[s], mid[s], mid[s + 2], q[(s + 3) % 4]};
                tb_vec3 h2[4] = {mid[s], q[s + 1], q[s + 2], mid[s + 2]};
                worst = fmin(worst, fmin(min_angle_pts(h1, 4), min_angle_pts(h2, 4)));
            }
            for (int k = 0; k < 4; k++) { /* adjacent sides k, k+1: corner triangle + fan from k+3 */
                tb_vec3 a = mid[k], b = mid[(k + 1) % 4], c0 = q[k], c1 = q[(k + 1) % 4], c2 = q[(k + 2) % 4],
                        c3 = q[(k + 3) % 4];
                tb_vec3 t[4][3] = {{a, c1, b}, {c3, c0, a}, {c3, a, b}, {c3, b, c2}};
                for (int i = 0; i < 4; i++)
                    worst = fmin(worst, min_angle_pts(t[i], 3));
            }
        }
    }
    return worst;
}

static void base_face_normals(const tb_mesh *base, long double (*fn)[3], uint32_t nfaces)
{
    for (uint32_t f = 0; f < nfaces; f++)
        fn[f][0] = fn[f][1] = fn[f][2] = 0;
    for (size_t i = 0; i < tb_mesh_nelems(base); i++) {
        const tb_mesh_elem *e = tb_mesh_elem_at(base, i);
        long double n[3];
        newell(base, e, n);
        for (int k = 0; k < 3; k++)
            fn[e->face][k] += n[k];
    }
}

static uint32_t max_face(const tb_mesh *m)
{
    uint32_t f = 0;
    for (size_t i = 0; i < tb_mesh_nelems(m); i++)
        f = tb_mesh_elem_at(m, i)->face > f ? tb_mesh_elem_at(m, i)->face : f;
    return f + 1;
}

/* p strictly inside segment a-b (not at its ends)? */
static bool inside_segment(tb_vec3 p, tb_vec3 a, tb_vec3 b)
{
    double ux = (double)b.x - a.x, uy = (double)b.y - a.y, uz = (double)b.z - a.z;
    double wx = (double)p.x - a.x, wy = (double)p.y - a.y, wz = (double)p.z - a.z;
    double uu = ux * ux + uy * uy + uz * uz;
    double t = (ux * wx + uy * wy + uz * wz) / uu;
    if (!(t > 1e-9 && t < 1 - 1e-9))
        return false;
    double dx = wx - t * ux, dy = wy - t * uy, dz = wz - t * uz;
    return dx * dx + dy * dy + dz * dz <= 1e-14 * uu;
}

static const tb_mesh *sort_mesh;

static int cmp_x(const void *a, const void *b)
{
    float x = P(sort_mesh, *(const uint32_t *)a).x, y = P(sort_mesh, *(const uint32_t *)b).x;
    return (x > y) - (x < y);
}

static uint64_t dkey(uint32_t a, uint32_t b) { return (uint64_t)a << 32 | b; }

#define PROBLEM(...)                                                                                               \
    do {                                                                                                           \
        snprintf(why, nwhy, __VA_ARGS__);                                                                          \
        goto out;                                                                                                  \
    } while (0)

/* Everything refinement promises about mesh m made from `base`; false if
 * all holds, else true with the first problem in why. `exact_flat`: the
 * meshes lie in z = 0 with dyadic coordinates, so per-face areas must
 * match exactly. */
static bool refine_problem(const tb_mesh *base, const tb_mesh *m, bool exact_flat, char *why, size_t nwhy)
{
    bool bad = true;
    tb_htab dir, bnd;
    tb_htab_init(&dir, TB_HTAB_U64);
    tb_htab_init(&bnd, TB_HTAB_U64);
    uint32_t nf = max_face(base);
    long double(*fn)[3] = calloc(nf, sizeof *fn);
    long double *area0 = calloc(nf, sizeof(long double)), *area1 = calloc(nf, sizeof(long double));
    uint8_t *used = calloc(m->positions.len + 1, 1);
    uint32_t *sorted = malloc(sizeof(uint32_t) * (m->positions.len + 1));
    base_face_normals(base, fn, nf);
    size_t nv = m->positions.len;
    /* directed edges of the base, to know its boundary */
    for (size_t i = 0; i < tb_mesh_nelems(base); i++) {
        const tb_mesh_elem *e = tb_mesh_elem_at(base, i);
        int n = tb_mesh_elem_size(e);
        for (int k = 0; k < n; k++)
            tb_htab_put(&bnd, dkey(e->v[k], e->v[(k + 1) % n]), 1);
        long double a[3];
        newell(base, e, a);
        area0[e->face] += exact_flat ? a[2] : sqrtl(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    }
    for (size_t i = 0; i < tb_mesh_nelems(m); i++) {
        const tb_mesh_elem *e = tb_mesh_elem_at(m, i);
        int n = tb_mesh_elem_size(e);
        if (e->face >= nf)
            PROBLEM("element %zu: face %u", i, e->face);
        for (int k = 0; k < n; k++) {
            if (e->v[k] >= nv)
                PROBLEM("element %zu: vertex %u of %zu", i, e->v[k], nv);
            used[e->v[k]] = 1;
        }
        long double a[3];
        newell(m, e, a);
        long double dot = a[0] * fn[e->face][0] + a[1] * fn[e->face][1] + a[2] * fn[e->face][2];
        if (!(dot > 0))
            PROBLEM("element %zu does not face like face %u", i, e->face);
        area1[e->face] += exact_flat ? a[2] : sqrtl(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        for (int k = 0; k < n; k++) {
            uint64_t key = dkey(e->v[k], e->v[(k + 1) % n]);
            if (tb_htab_get(&dir, key, NULL))
                PROBLEM("edge %u->%u used twice in one direction", e->v[k], e->v[(k + 1) % n]);
            tb_htab_put(&dir, key, i);
        }
    }
    /* no vertex inside an element edge (vertices sorted by x, so each
     * edge looks only at those within its x range) */
    uint32_t nsorted = 0;
    for (uint32_t v = 0; v < nv; v++)
        if (used[v])
            sorted[nsorted++] = v;
    sort_mesh = m;
    qsort(sorted, nsorted, sizeof *sorted, cmp_x);
    for (size_t i = 0; i < tb_mesh_nelems(m); i++) {
        const tb_mesh_elem *e = tb_mesh_elem_at(m, i);
        int n = tb_mesh_elem_size(e);
        for (int k = 0; k < n; k++) {
            tb_vec3 a = P(m, e->v[k]), b = P(m, e->v[(k + 1) % n]);
            float lo[3] = {fminf(a.x, b.x), fminf(a.y, b.y), fminf(a.z, b.z)};
            float hi[3] = {fmaxf(a.x, b.x), fmaxf(a.y, b.y), fmaxf(a.z, b.z)};
            uint32_t l = 0, h = nsorted;
            while (l < h) { /* first vertex with x >= lo[0] */
                uint32_t mid = (l + h) / 2;
                if (P(m, sorted[mid]).x < lo[0])
                    l = mid + 1;
                else
                    h = mid;
            }
            for (uint32_t j = l; j < nsorted && P(m, sorted[j]).x <= hi[0]; j++) {
                uint32_t v = sorted[j];
                if (v == e->v[k] || v == e->v[(k + 1) % n])
                    continue;
                tb_vec3 p = P(m, v);
                if (p.y < lo[1] || p.y > hi[1] || p.z < lo[2] || p.z > hi[2])
                    continue;
                if (inside_segment(p, a, b))
                    PROBLEM("vertex %u lies inside edge %u-%u of element %zu (a T-vertex)", v, e->v[k],
                            e->v[(k + 1) % n], i);
            }
        }
    }
    /* interior edges: used once each way; edges used once: on the base
     * boundary (inside a base boundary edge, or one) */
    size_t it = 0;
    tb_htab_entry en;
    while (tb_htab_next(&dir, &it, &en)) {
        uint32_t a = (uint32_t)(en.key >> 32), b = (uint32_t)en.key;
        if (tb_htab_get(&dir, dkey(b, a), NULL))
            continue;
        bool on = false;
        size_t it2 = 0;
        tb_htab_entry e2;
        while (!on && tb_htab_next(&bnd, &it2, &e2)) {
            uint32_t c = (uint32_t)(e2.key >> 32), d = (uint32_t)e2.key;
            if (tb_htab_get(&bnd, dkey(d, c), NULL))
                continue; /* interior base edge */
            bool ina = a == c || inside_segment(P(m, a), P(m, c), P(m, d));
            bool inb = b == d || inside_segment(P(m, b), P(m, c), P(m, d));
            on = ina && inb;
        }
        if (!on)
            PROBLEM("edge %u->%u is used once but is not on the base boundary", a, b);
    }
    for (uint32_t f = 0; f < nf; f++) {
        if (exact_flat ? area0[f] != area1[f] : fabsl(area0[f] - area1[f]) > 1e-12L * area0[f])
            PROBLEM("face %u: area %.20Lg became %.20Lg", f, area0[f] / 2, area1[f] / 2);
    }
    bad = false;
out:
    tb_htab_free(&dir);
    tb_htab_free(&bnd);
    free(fn), free(area0), free(area1), free(used), free(sorted);
    return bad;
}

static void check_refined(const tb_mesh *base, const tb_mesh *m, bool exact_flat)
{
    char why[256];
    if (refine_problem(base, m, exact_flat, why, sizeof why))
        fail_msg("%s", why);
}

/* Every element is closed-surface conforming: each edge used twice, opposite ways. */
static void check_closed(const tb_mesh *m, int64_t euler)
{
    tb_htab dir, und;
    tb_htab_init(&dir, TB_HTAB_U64);
    tb_htab_init(&und, TB_HTAB_U64);
    uint8_t *used = calloc(m->positions.len, 1);
    int64_t V = 0;
    for (size_t i = 0; i < tb_mesh_nelems(m); i++) {
        const tb_mesh_elem *e = tb_mesh_elem_at(m, i);
        int n = tb_mesh_elem_size(e);
        for (int k = 0; k < n; k++) {
            uint32_t a = e->v[k], b = e->v[(k + 1) % n];
            assert_false(tb_htab_get(&dir, dkey(a, b), NULL));
            tb_htab_put(&dir, dkey(a, b), 1);
            tb_htab_put(&und, a < b ? dkey(a, b) : dkey(b, a), 1);
            V += !used[a];
            used[a] = 1;
        }
    }
    size_t it = 0;
    tb_htab_entry en;
    while (tb_htab_next(&dir, &it, &en))
        if (!tb_htab_get(&dir, dkey((uint32_t)en.key, (uint32_t)(en.key >> 32)), NULL))
            fail_msg("edge %u->%u has no opposite use: the surface is not closed", (unsigned)(en.key >> 32),
                     (unsigned)(uint32_t)en.key);
    assert_int_equal(V - (int64_t)und.count + (int64_t)tb_mesh_nelems(m), euler);
    tb_htab_free(&dir);
    tb_htab_free(&und);
    free(used);
}

/* Smallest distance of p inside element e (negative outside), independent
 * of the library's own test. */
static double inside_elem(const tb_mesh *m, const tb_mesh_elem *e, const double p[3])
{
    long double nrm[3];
    newell(m, e, nrm);
    double nl = (double)sqrtl(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
    int n = tb_mesh_elem_size(e);
    double worst = INFINITY;
    for (int k = 0; k < n; k++) {
        tb_vec3 a = P(m, e->v[k]), b = P(m, e->v[(k + 1) % n]);
        double u[3] = {(double)b.x - a.x, (double)b.y - a.y, (double)b.z - a.z};
        double w[3] = {p[0] - a.x, p[1] - a.y, p[2] - a.z};
        double c[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        double s = (c[0] * (double)nrm[0] + c[1] * (double)nrm[1] + c[2] * (double)nrm[2]) /
                   (nl * sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]));
        worst = fmin(worst, s);
    }
    return worst;
}

/* Checks the map and parent fields of a refinement step: every new
 * element's centroid lies in the old element the map names, and its parent
 * is that element unless it is the old element unchanged (then NONE). */
static void check_map(const tb_mesh *m, const tb_mesh_elem *old, size_t nold, const tb_array *map)
{
    assert_int_equal(map->len, tb_mesh_nelems(m));
    for (size_t i = 0; i < tb_mesh_nelems(m); i++) {
        const tb_mesh_elem *e = tb_mesh_elem_at(m, i);
        uint32_t o = TB_ARRAY_AT(map, uint32_t, i);
        assert_true(o < nold);
        int n = tb_mesh_elem_size(e);
        double c[3] = {0, 0, 0};
        for (int k = 0; k < n; k++)
            c[0] += P(m, e->v[k]).x / (double)n, c[1] += P(m, e->v[k]).y / (double)n,
                c[2] += P(m, e->v[k]).z / (double)n;
        if (inside_elem(m, &old[o], c) < -1e-9)
            fail_msg("element %zu: centroid outside old element %u", i, o);
        bool same = memcmp(old[o].v, e->v, sizeof e->v) == 0;
        assert_int_equal(e->face, old[o].face);
        assert_int_equal(e->parent, same ? TB_MESH_NONE : o);
    }
}

typedef struct step {
    tb_mesh_refine_stats st;
    size_t before;
} step;

/* One refinement step with every check. */
static step refine_checked(tb_mesh_refiner *r, const tb_mesh *base, const uint32_t *marks, size_t n,
                           bool exact_flat)
{
    const tb_mesh *m = tb_mesh_refiner_mesh(r);
    size_t nold = tb_mesh_nelems(m);
    tb_mesh_elem *old = malloc(sizeof *old * (nold + 1));
    memcpy(old, m->elems.data, sizeof *old * nold);
    tb_array map = TB_ARRAY_INIT(uint32_t);
    step s = {.before = nold};
    if (tb_mesh_refine(r, marks, n, &map, &s.st))
        fail_msg("tb_mesh_refine: %s", tb_last_error());
    m = tb_mesh_refiner_mesh(r);
    check_refined(base, m, exact_flat);
    check_map(m, old, nold, &map);
    uint32_t greens = 0;
    for (size_t i = 0; i < tb_mesh_nelems(m); i++) {
        greens += tb_mesh_refiner_is_green(r, i);
        uint32_t b = tb_mesh_refiner_base(r, i);
        assert_true(b < tb_mesh_nelems(base));
        assert_int_equal(tb_mesh_elem_at(m, i)->face, tb_mesh_elem_at(base, b)->face);
    }
    assert_int_equal(greens, s.st.green);
    free(old);
    tb_array_free(&map);
    return s;
}

/* A flat mesh in z = 0 from corner lists (-1 ends a triangle's 4th slot). */
static void flat_mesh(tb_mesh *m, const float (*xy)[2], uint32_t nv, const uint32_t (*el)[5], uint32_t ne,
                      bool attrs)
{
    tb_mesh_init(m);
    for (uint32_t i = 0; i < nv; i++) {
        tb_vec3 p = {xy[i][0], xy[i][1], 0};
        assert_int_equal(tb_array_push(&m->positions, &p), TB_OK);
        if (attrs) {
            /* uv linear in position with dyadic coefficients, so exactly
             * linear after refinement too; normals tilted differently per
             * vertex so interpolation is visible */
            tb_vec2 uv = {p.x * 0.25f + 1, p.y * 0.5f - 2};
            tb_vec3 nr = {p.x * 0.125f, 0, 1};
            float l = sqrtf(nr.x * nr.x + 1);
            nr.x /= l, nr.z /= l;
            assert_int_equal(tb_array_push(&m->uvs, &uv), TB_OK);
            assert_int_equal(tb_array_push(&m->normals, &nr), TB_OK);
        }
    }
    for (uint32_t i = 0; i < ne; i++) {
        tb_mesh_elem e = {{el[i][0], el[i][1], el[i][2], el[i][3]}, el[i][4], TB_MESH_NONE};
        assert_int_equal(tb_array_push(&m->elems, &e), TB_OK);
    }
}

/* n x n unit squares over [0, n]^2, cell (i, j) = element j*n + i; when
 * `mixed`, every cell with i + j odd is two triangles instead (face = 1). */
static void grid_mesh(tb_mesh *m, uint32_t n, bool mixed, bool attrs)
{
    float(*xy)[2] = malloc(sizeof *xy * (n + 1) * (n + 1));
    uint32_t(*el)[5] = malloc(sizeof *el * 2 * n * n);
    for (uint32_t j = 0; j <= n; j++)
        for (uint32_t i = 0; i <= n; i++)
            xy[j * (n + 1) + i][0] = (float)i, xy[j * (n + 1) + i][1] = (float)j;
    uint32_t ne = 0;
    for (uint32_t j = 0; j < n; j++)
        for (uint32_t i = 0; i < n; i++) {
            uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
            if (mixed && (i + j) % 2) {
                uint32_t t1[5] = {a, b, c, TB_MESH_NONE, 1}, t2[5] = {a, c, d, TB_MESH_NONE, 1};
                memcpy(el[ne++], t1, sizeof t1);
                memcpy(el[ne++], t2, sizeof t2);
            } else {
                uint32_t q[5] = {a, b, c, d, 0};
                memcpy(el[ne++], q, sizeof q);
            }
        }
    flat_mesh(m, (const float(*)[2])xy, (n + 1) * (n + 1), (const uint32_t(*)[5])el, ne, attrs);
    free(xy), free(el);
}

/* Elements with a vertex at (x, y). */
static size_t elems_at(const tb_mesh *m, float x, float y, uint32_t *out, size_t cap)
{
    size_t n = 0;
    for (size_t i = 0; i < tb_mesh_nelems(m); i++) {
        const tb_mesh_elem *e = tb_mesh_elem_at(m, i);
        for (int k = 0; k < tb_mesh_elem_size(e); k++)
            if (P(m, e->v[k]).x == x && P(m, e->v[k]).y == y && n < cap) {
                out[n++] = (uint32_t)i;
                break;
            }
    }
    return n;
}

/* -------------------------------------------------------------------- tests */

static void test_checker_catches_problems(void **state)
{
    (void)state;
    char why[256];
    tb_mesh base, m;
    grid_mesh(&base, 2, false, false);
    assert_false(refine_problem(&base, &base, true, why, sizeof why));
    /* a T-vertex: cell 0 split into two quads at a new midpoint of its
     * shared right edge without telling cell 1 */
    grid_mesh(&m, 2, false, false);
    tb_vec3 a = {1, 0.5f, 0}, b = {0, 0.5f, 0};
    tb_array_push(&m.positions, &a);
    tb_array_push(&m.positions, &b);
    tb_mesh_elem *e0 = &TB_ARRAY_AT(&m.elems, tb_mesh_elem, 0);
    tb_mesh_elem lower = {{0, 1, 9, 10}, 0, 0}, upper = {{10, 9, 4, 3}, 0, 0};
    *e0 = lower;
    tb_array_push(&m.elems, &upper);
    assert_true(refine_problem(&base, &m, true, why, sizeof why));
    assert_non_null(strstr(why, "T-vertex"));
    tb_mesh_free(&m);
    /* a flipped element */
    grid_mesh(&m, 2, false, false);
    tb_mesh_elem *e = &TB_ARRAY_AT(&m.elems, tb_mesh_elem, 3);
    uint32_t t = e->v[1];
    e->v[1] = e->v[3], e->v[3] = t;
    assert_true(refine_problem(&base, &m, true, why, sizeof why));
    tb_mesh_free(&m);
    /* a missing element (a hole: edges used once inside) */
    grid_mesh(&m, 2, false, false);
    m.elems.len--;
    assert_true(refine_problem(&base, &m, true, why, sizeof why));
    assert_non_null(strstr(why, "once"));
    tb_mesh_free(&m);
    /* an area change: a boundary vertex moved outward by 2^-20 */
    grid_mesh(&m, 2, false, false);
    TB_ARRAY_AT(&m.positions, tb_vec3, 1).y = -0x1p-20f;
    assert_true(refine_problem(&base, &m, true, why, sizeof why));
    tb_mesh_free(&m);
    /* the triangle version of a T-vertex: a triangle fan that uses a
     * midpoint on an edge shared with an unsplit neighbour, both edges
     * present: caught as a vertex inside an edge */
    float xy[5][2] = {{0, 0}, {2, 0}, {2, 2}, {0, 2}, {1, 1}};
    uint32_t el[3][5] = {{0, 1, 4, TB_MESH_NONE, 0}, {1, 2, 4, TB_MESH_NONE, 0}, {0, 2, 3, TB_MESH_NONE, 0}};
    flat_mesh(&m, (const float(*)[2])xy, 5, (const uint32_t(*)[5])el, 3, false);
    assert_true(refine_problem(&m, &m, true, why, sizeof why));
    assert_non_null(strstr(why, "T-vertex"));
    tb_mesh_free(&m);
    tb_mesh_free(&base);
}

static void test_one_triangle(void **state)
{
    (void)state;
    float xy[3][2] = {{0, 0}, {4, 0}, {1, 3}};
    uint32_t el[1][5] = {{0, 1, 2, TB_MESH_NONE, 0}};
    tb_mesh base;
    flat_mesh(&base, (const float(*)[2])xy, 3, (const uint32_t(*)[5])el, 1, true);
    tb_mesh_refiner *r;
    assert_int_equal(tb_mesh_refiner_create(&base, &r), TB_OK);
    uint32_t mk = 0;
    step s = refine_checked(r, &base, &mk, 1, true);
    const tb_mesh *m = tb_mesh_refiner_mesh(r);
    assert_int_equal(tb_mesh_nelems(m), 4);
    assert_int_equal(s.st.red, 1);
    assert_int_equal(s.st.new_vertices, 3);
    for (size_t i = 0; i < 4; i++) {
        assert_int_equal(tb_mesh_refiner_level(r, i), 1);
        tb_assert_near(tb_mesh_elem_area(m, i), 6.0 / 4, 1e-12); /* 4 congruent triangles */
        tb_assert_near(elem_min_angle(m, tb_mesh_elem_at(m, i)), elem_min_angle(&base, tb_mesh_elem_at(&base, 0)),
                       1e-9);
    }
    /* refine the child at corner 0: the middle child gets one split side
     * (green, 2 triangles), the other corner children touch it only at a
     * vertex: 4 + 2 + 2 elements */
    uint32_t at0[4];
    assert_int_equal(elems_at(m, 0, 0, at0, 4), 1);
    s = refine_checked(r, &base, at0, 1, true);
    m = tb_mesh_refiner_mesh(r);
    assert_int_equal(tb_mesh_nelems(m), 8);
    assert_int_equal(s.st.green, 2);
    assert_int_equal(s.st.red, 1);
    /* uv and normals interpolated: uv exactly linear in position (dyadic
     * data), normals unit length and between their ends */
    for (size_t v = 0; v < m->positions.len; v++) {
        tb_vec3 p = P(m, v);
        tb_vec2 uv = TB_ARRAY_AT(&m->uvs, tb_vec2, v);
        assert_true(uv.x == p.x * 0.25f + 1 && uv.y == p.y * 0.5f - 2);
        tb_vec3 n = TB_ARRAY_AT(&m->normals, tb_vec3, v);
        tb_assert_near(n.x * n.x + n.y * n.y + n.z * n.z, 1, 1e-6);
        assert_true(n.x >= 0 && n.x <= 0.125f * 4);
    }
    /* mid of edge 0-1 is (2, 0): normal the renormalised mean of (0,0,1) and (4/8,0,1)/|.| */
    tb_mesh_refiner_free(r);
    tb_mesh_free(&base);
}

static void test_grid_neighbours_green(void **state)
{
    (void)state;
    tb_mesh base;
    grid_mesh(&base, 4, false, false);
    tb_mesh_refiner *r;
    assert_int_equal(tb_mesh_refiner_create(&base, &r), TB_OK);
    uint32_t mk = 5; /* cell (1, 1): four neighbours across sides */
    step s = refine_checked(r, &base, &mk, 1, true);
    const tb_mesh *m = tb_mesh_refiner_mesh(r);
    /* 4 children + 4 neighbours fanned into 3 triangles + 11 untouched */
    assert_int_equal(tb_mesh_nelems(m), 4 + 12 + 11);
    assert_int_equal(s.st.green, 12);
    assert_int_equal(s.st.red, 1);
    /* mark one green triangle of the right neighbour (cell 6): the closure
     * is undone and cell 6 is split red, which greens its own neighbours */
    uint32_t g = TB_MESH_NONE;
    for (size_t i = 0; i < tb_mesh_nelems(m) && g == TB_MESH_NONE; i++)
        if (tb_mesh_refiner_is_green(r, i) && tb_mesh_refiner_base(r, i) == 6)
            g = (uint32_t)i;
    assert_int_not_equal(g, TB_MESH_NONE);
    s = refine_checked(r, &base, &g, 1, true);
    m = tb_mesh_refiner_mesh(r);
    assert_int_equal(s.st.red, 1);
    size_t in6 = 0, green6 = 0;
    for (size_t i = 0; i < tb_mesh_nelems(m); i++)
        if (tb_mesh_refiner_base(r, i) == 6) {
            in6++;
            green6 += tb_mesh_refiner_is_green(r, i);
            assert_int_equal(tb_mesh_refiner_level(r, i), 1);
        }
    assert_int_equal(in6, 4);
    assert_int_equal(green6, 0);
    /* 5 and 6 split (8), neighbours of both (2, 4, 9, 7, 10; 1... ) greened */
    assert_int_equal(tb_mesh_nelems(m), 8 + 6 * 3 + 8);
    /* cell 1 split too: cell 2 (neighbour of 1 and 6) then has two
     * adjacent split sides and is closed green (corner triangle + fan) */
    for (size_t i = 0; i < tb_mesh_nelems(m); i++)
        if (tb_mesh_refiner_is_green(r, i) && tb_mesh_refiner_base(r, i) == 1) {
            g = (uint32_t)i;
            break;
        }
    s = refine_checked(r, &base, &g, 1, true);
    m = tb_mesh_refiner_mesh(r);
    assert_int_equal(s.st.red, 1);
    assert_int_equal(s.st.closure, 0);
    size_t in2 = 0;
    for (size_t i = 0; i < tb_mesh_nelems(m); i++)
        if (tb_mesh_refiner_base(r, i) == 2) {
            in2++;
            assert_true(tb_mesh_refiner_is_green(r, i));
            assert_int_equal(tb_mesh_elem_size(tb_mesh_elem_at(m, i)), 3);
        }
    assert_int_equal(in2, 4);
    /* cell 3 split: cell 2 has three split sides and is split red (a
     * closure split); cell 7 (3 below it, 6 to its left) has two adjacent
     * split sides: green */
    for (size_t i = 0; i < tb_mesh_nelems(m); i++)
        if (tb_mesh_refiner_base(r, i) == 3) {
            g = (uint32_t)i;
            break;
        }
    s = refine_checked(r, &base, &g, 1, true);
    m = tb_mesh_refiner_mesh(r);
    assert_int_equal(s.st.red, 2);
    assert_int_equal(s.st.closure, 1);
    size_t in7 = 0;
    for (size_t i = 0; i < tb_mesh_nelems(m); i++)
        if (tb_mesh_refiner_base(r, i) == 7) {
            in7++;
            assert_true(tb_mesh_refiner_is_green(r, i));
        }
    assert_int_equal(in7, 4);
    /* cell 13 split: cell 9 between 5 and 13 has two opposite split sides
     * and becomes two quads of half its area */
    for (size_t i = 0; i < tb_mesh_nelems(m); i++)
        if (tb_mesh_refiner_base(r, i) == 13) {
            g = (uint32_t)i;
            break;
        }
    s = refine_checked(r, &base, &g, 1, true);
    m = tb_mesh_refiner_mesh(r);
    assert_int_equal(s.st.red, 1);
    size_t in9 = 0;
    for (size_t i = 0; i < tb_mesh_nelems(m); i++)
        if (tb_mesh_refiner_base(r, i) == 9) {
            in9++;
            assert_true(tb_mesh_refiner_is_green(r, i));
            assert_int_equal(tb_mesh_elem_size(tb_mesh_elem_at(m, i)), 4);
            tb_assert_near(tb_mesh_elem_area(m, i), 0.5, 0);
        }
    assert_int_equal(in9, 2);
    tb_mesh_refiner_free(r);
    tb_mesh_free(&base);
}

/* Refines the elements at one point `times` times; checks every step and
 * the angle bound; returns the element count. */
static size_t refine_point(const tb_mesh *base, float x, float y, int times, bool greens_first)
{
    tb_mesh_refiner *r;
    assert_int_equal(tb_mesh_refiner_create(base, &r), TB_OK);
    double bound = shape_bound(base);
    uint32_t at[64];
    for (int t = 0; t < times; t++) {
        const tb_mesh *m = tb_mesh_refiner_mesh(r);
        size_t n = elems_at(m, x, y, at, 64);
        assert_true(n > 0);
        if (greens_first) {
            /* mark only one element, a green one if there is one (its
             * closure must be undone, never split again) */
            size_t pick = 0;
            for (size_t k = 0; k < n; k++)
                if (tb_mesh_refiner_is_green(r, at[k])) {
                    pick = k;
                    break;
                }
            at[0] = at[pick];
            n = 1;
        }
        refine_checked(r, base, at, n, true);
        m = tb_mesh_refiner_mesh(r);
        double worst = mesh_min_angle(m);
        if (worst < bound - 1e-9)
            fail_msg("step %d: smallest angle %.6f below the bound %.6f", t, worst, bound);
    }
    const tb_mesh *m = tb_mesh_refiner_mesh(r);
    size_t n = elems_at(m, x, y, at, 64);
    uint32_t deepest = 0;
    for (size_t k = 0; k < n; k++)
        deepest = tb_mesh_refiner_level(r, at[k]) > deepest ? tb_mesh_refiner_level(r, at[k]) : deepest;
    if (!greens_first)
        assert_int_equal(deepest, times);
    print_message("point (%g, %g)%s: deepest level %u\n", x, y, greens_first ? ", greens marked" : "", deepest);
    size_t ne = tb_mesh_nelems(m);
    tb_mesh_refiner_free(r);
    return ne;
}

static void test_refine_corner_20_times(void **state)
{
    (void)state;
    tb_mesh base;
    /* mixed: quads and triangles (cells with i + j odd are two triangles,
     * face 1); the point (2, 2) has both kinds around it, (0, 0) is a quad
     * corner, (4, 0) a triangle corner */
    grid_mesh(&base, 4, true, false);
    size_t n1 = refine_point(&base, 0, 0, 20, false);
    size_t n2 = refine_point(&base, 2, 2, 20, false);
    size_t n3 = refine_point(&base, 4, 0, 20, false);
    size_t n4 = refine_point(&base, 2, 2, 20, true);
    print_message("corner 20x: %zu, %zu, %zu, %zu elements (greens marked)\n", n1, n2, n3, n4);
    /* grading: refinement of one point adds a bounded number of elements
     * per level (a 1-irregular mesh), not a growing one */
    assert_true(n1 < 24 + 20 * 12);
    assert_true(n2 < 24 + 20 * 40);
    assert_true(n3 < 24 + 20 * 12);
    /* a skewed base: the bound follows the base's shapes */
    float xy[5][2] = {{0, 0}, {8, 0}, {9, 2}, {1, 2}, {3, 7}};
    uint32_t el[3][5] = {{0, 1, 2, 3, 0}, {3, 2, 4, TB_MESH_NONE, 1}, {0, 3, 4, TB_MESH_NONE, 2}};
    tb_mesh sk;
    flat_mesh(&sk, (const float(*)[2])xy, 5, (const uint32_t(*)[5])el, 3, false);
    refine_point(&sk, 1, 2, 20, false);
    refine_point(&sk, 1, 2, 20, true);
    tb_mesh_free(&sk);
    tb_mesh_free(&base);
}

/* A random mark set: each element with probability p. */
static size_t random_marks(tb_rng *g, size_t ne, double p, uint32_t *out)
{
    size_t n = 0;
    for (size_t i = 0; i < ne; i++)
        if (tb_rng_double(g) < p)
            out[n++] = (uint32_t)i;
    return n;
}

static void test_random_mixed(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("test_random_mixed", 7);
    tb_rng g;
    tb_rng_seed(&g, seed, 1);
    tb_mesh base;
    grid_mesh(&base, 6, true, true);
    tb_mesh_refiner *r;
    assert_int_equal(tb_mesh_refiner_create(&base, &r), TB_OK);
    double bound = shape_bound(&base);
    uint32_t *marks = NULL;
    for (int round = 0; round < 7; round++) {
        size_t ne = tb_mesh_nelems(tb_mesh_refiner_mesh(r));
        marks = realloc(marks, sizeof *marks * (ne + 1));
        size_t n = random_marks(&g, ne, 0.12, marks);
        refine_checked(r, &base, marks, n, true);
        const tb_mesh *m = tb_mesh_refiner_mesh(r);
        assert_true(mesh_min_angle(m) >= bound - 1e-9);
        for (size_t v = 0; v < m->positions.len; v++) {
            tb_vec3 p = P(m, v);
            tb_vec2 uv = TB_ARRAY_AT(&m->uvs, tb_vec2, v);
            assert_true(uv.x == p.x * 0.25f + 1 && uv.y == p.y * 0.5f - 2);
        }
    }
    print_message("random mixed: %zu elements after 7 rounds\n", tb_mesh_nelems(tb_mesh_refiner_mesh(r)));
    free(marks);
    tb_mesh_refiner_free(r);
    tb_mesh_free(&base);
}

static tb_fed *cube_fed(void)
{
    static const tb_vec3 pos[8] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                   {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
    static const uint32_t corners[24] = {0, 3, 2, 1, 4, 5, 6, 7, 0, 1, 5, 4, 1, 2, 6, 5, 2, 3, 7, 6, 3, 0, 4, 7};
    static const uint32_t sizes[6] = {4, 4, 4, 4, 4, 4};
    tb_fed_desc d = {.nverts = 8, .positions = pos, .nfaces = 6, .nloops = 6, .loop_sizes = sizes,
                     .corners = corners};
    tb_fed *f;
    if (tb_fed_build(&d, &f, NULL))
        fail_msg("%s", tb_last_error());
    return f;
}

static void test_closed_cube(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("test_closed_cube", 11);
    tb_rng g;
    tb_rng_seed(&g, seed, 2);
    tb_fed *f = cube_fed();
    tb_mesh base;
    tb_mesh_init(&base);
    tb_mesh_opts o = {.max_edge = 0.5, .quads = true};
    assert_int_equal(tb_mesh_from_fed(f, &o, &base), TB_OK);
    assert_int_equal(tb_mesh_nelems(&base), 96);
    check_closed(&base, 2);
    tb_mesh_refiner *r;
    assert_int_equal(tb_mesh_refiner_create(&base, &r), TB_OK);
    uint32_t *marks = NULL;
    for (int round = 0; round < 5; round++) {
        size_t ne = tb_mesh_nelems(tb_mesh_refiner_mesh(r));
        marks = realloc(marks, sizeof *marks * (ne + 1));
        size_t n = random_marks(&g, ne, 0.1, marks);
        refine_checked(r, &base, marks, n, false);
        check_closed(tb_mesh_refiner_mesh(r), 2);
    }
    /* cube edges: refinement crosses FED faces through shared edges */
    free(marks);
    tb_mesh_refiner_free(r);
    tb_mesh_free(&base);
    tb_fed_free(f);
}

static bool same_mesh(const tb_mesh *a, const tb_mesh *b)
{
    return a->positions.len == b->positions.len && a->elems.len == b->elems.len &&
           a->normals.len == b->normals.len && a->uvs.len == b->uvs.len &&
           !memcmp(a->positions.data, b->positions.data, a->positions.len * sizeof(tb_vec3)) &&
           !memcmp(a->elems.data, b->elems.data, a->elems.len * sizeof(tb_mesh_elem)) &&
           (!a->normals.len || !memcmp(a->normals.data, b->normals.data, a->normals.len * sizeof(tb_vec3))) &&
           (!a->uvs.len || !memcmp(a->uvs.data, b->uvs.data, a->uvs.len * sizeof(tb_vec2)));
}

static void test_deterministic(void **state)
{
    (void)state;
    tb_rng g;
    tb_rng_seed(&g, 99, 3);
    tb_mesh base;
    grid_mesh(&base, 5, true, true);
    tb_mesh_refiner *r1, *r2;
    assert_int_equal(tb_mesh_refiner_create(&base, &r1), TB_OK);
    assert_int_equal(tb_mesh_refiner_create(&base, &r2), TB_OK);
    uint32_t *marks = NULL, *shuffled = NULL;
    for (int round = 0; round < 4; round++) {
        size_t ne = tb_mesh_nelems(tb_mesh_refiner_mesh(r1));
        marks = realloc(marks, sizeof *marks * (ne + 1));
        shuffled = realloc(shuffled, sizeof *shuffled * 2 * (ne + 1));
        size_t n = random_marks(&g, ne, 0.15, marks);
        /* the same set reversed, with every element twice */
        for (size_t i = 0; i < n; i++)
            shuffled[i] = shuffled[2 * n - 1 - i] = marks[n - 1 - i];
        tb_array m1 = TB_ARRAY_INIT(uint32_t), m2 = TB_ARRAY_INIT(uint32_t);
        tb_mesh_refine_stats s1, s2;
        assert_int_equal(tb_mesh_refine(r1, marks, n, &m1, &s1), TB_OK);
        assert_int_equal(tb_mesh_refine(r2, shuffled, 2 * n, &m2, &s2), TB_OK);
        assert_true(same_mesh(tb_mesh_refiner_mesh(r1), tb_mesh_refiner_mesh(r2)));
        assert_int_equal(m1.len, m2.len);
        assert_memory_equal(m1.data, m2.data, m1.len * sizeof(uint32_t));
        assert_memory_equal(&s1, &s2, sizeof s1);
        assert_int_equal(s1.marked, n);
        tb_array_free(&m1), tb_array_free(&m2);
    }
    free(marks), free(shuffled);
    tb_mesh_refiner_free(r1);
    tb_mesh_refiner_free(r2);
    tb_mesh_free(&base);
}

static void test_refusals(void **state)
{
    (void)state;
    tb_mesh_refiner *r = (tb_mesh_refiner *)&r;
    tb_mesh m;
    /* repeated vertex */
    float xy[5][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {2, 0}};
    uint32_t rep[1][5] = {{0, 1, 1, TB_MESH_NONE, 0}};
    flat_mesh(&m, (const float(*)[2])xy, 5, (const uint32_t(*)[5])rep, 1, false);
    assert_int_equal(tb_mesh_refiner_create(&m, &r), TB_ERR_FORMAT);
    assert_null(r);
    tb_mesh_free(&m);
    /* zero area (collinear) */
    uint32_t flat[1][5] = {{0, 1, 4, TB_MESH_NONE, 0}};
    flat_mesh(&m, (const float(*)[2])xy, 5, (const uint32_t(*)[5])flat, 1, false);
    assert_int_equal(tb_mesh_refiner_create(&m, &r), TB_ERR_FORMAT);
    tb_mesh_free(&m);
    /* a non-convex quad (dart) */
    float dart[4][2] = {{0, 0}, {4, 0}, {1, 1}, {0, 4}};
    uint32_t q[1][5] = {{0, 1, 2, 3, 0}};
    flat_mesh(&m, (const float(*)[2])dart, 4, (const uint32_t(*)[5])q, 1, false);
    assert_int_equal(tb_mesh_refiner_create(&m, &r), TB_ERR_FORMAT);
    tb_mesh_free(&m);
    /* a slightly non-planar convex quad is accepted and split as a
     * bilinear patch (the radiosity mesh has them on the Cornell red wall) */
    flat_mesh(&m, (const float(*)[2])dart, 4, (const uint32_t(*)[5])q, 1, false);
    TB_ARRAY_AT(&m.positions, tb_vec3, 2) = (tb_vec3){4, 4, 0.25f};
    assert_int_equal(tb_mesh_refiner_create(&m, &r), TB_OK);
    uint32_t all = 0;
    assert_int_equal(tb_mesh_refine(r, &all, 1, NULL, NULL), TB_OK);
    const tb_mesh *nq = tb_mesh_refiner_mesh(r);
    assert_int_equal(tb_mesh_nelems(nq), 4);
    long double va[3] = {0, 0, 0}, v0[3]; /* vector area is additive, planar or not */
    for (size_t i = 0; i < 4; i++) {
        long double a[3];
        newell(nq, tb_mesh_elem_at(nq, i), a);
        for (int k = 0; k < 3; k++)
            va[k] += a[k];
        assert_true(elem_min_angle(nq, tb_mesh_elem_at(nq, i)) > 30);
    }
    newell(&m, tb_mesh_elem_at(&m, 0), v0);
    for (int k = 0; k < 3; k++)
        tb_assert_near((double)va[k], (double)v0[k], 1e-9);
    tb_mesh_refiner_free(r);
    tb_mesh_free(&m);
    /* a vertex index out of range */
    uint32_t oor[1][5] = {{0, 1, 7, TB_MESH_NONE, 0}};
    flat_mesh(&m, (const float(*)[2])xy, 5, (const uint32_t(*)[5])oor, 1, false);
    assert_int_not_equal(tb_mesh_refiner_create(&m, &r), TB_OK);
    tb_mesh_free(&m);
    /* a non-finite position */
    uint32_t ok[1][5] = {{0, 1, 2, TB_MESH_NONE, 0}};
    flat_mesh(&m, (const float(*)[2])xy, 5, (const uint32_t(*)[5])ok, 1, false);
    TB_ARRAY_AT(&m.positions, tb_vec3, 2).x = NAN;
    assert_int_not_equal(tb_mesh_refiner_create(&m, &r), TB_OK);
    TB_ARRAY_AT(&m.positions, tb_vec3, 2).x = 1;
    /* normals of the wrong length */
    tb_vec3 n = {0, 0, 1};
    tb_array_push(&m.normals, &n);
    assert_int_equal(tb_mesh_refiner_create(&m, &r), TB_ERR_ARG);
    m.normals.len = 0;
    /* marks out of range; then refinement down to float resolution: the
     * failing call leaves everything as it was */
    assert_int_equal(tb_mesh_refiner_create(&m, &r), TB_OK);
    uint32_t bad = 1;
    assert_int_equal(tb_mesh_refine(r, &bad, 1, NULL, NULL), TB_ERR_ARG);
    assert_int_equal(tb_mesh_nelems(tb_mesh_refiner_mesh(r)), 1);
    tb_status st = TB_OK;
    int steps = 0;
    tb_mesh copy;
    tb_mesh_init(&copy);
    while (!st && steps < 200) {
        const tb_mesh *cur = tb_mesh_refiner_mesh(r);
        tb_mesh_free(&copy);
        tb_mesh_init(&copy);
        tb_array_push_n(&copy.positions, cur->positions.data, cur->positions.len);
        tb_array_push_n(&copy.elems, cur->elems.data, cur->elems.len);
        uint32_t at[64];
        size_t k = elems_at(cur, 1, 1, at, 64); /* corner (1, 1): away from 0, so float runs out */
        st = tb_mesh_refine(r, at, k, NULL, NULL);
        steps++;
    }
    assert_int_equal(st, TB_ERR_ARG);
    assert_non_null(strstr(tb_last_error(), "float resolution"));
    print_message("float resolution reached after %d levels\n", steps - 1);
    assert_true(steps > 15 && steps < 30);
    assert_true(same_mesh(tb_mesh_refiner_mesh(r), &copy));
    /* still usable: refine somewhere else */
    uint32_t at[64];
    size_t k = elems_at(tb_mesh_refiner_mesh(r), 0, 0, at, 64);
    assert_int_equal(tb_mesh_refine(r, at, k, NULL, NULL), TB_OK);
    check_refined(&m, tb_mesh_refiner_mesh(r), true);
    tb_mesh_free(&copy);
    tb_mesh_refiner_free(r);
    tb_mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_checker_catches_problems),
        cmocka_unit_test(test_one_triangle),
        cmocka_unit_test(test_grid_neighbours_green),
        cmocka_unit_test(test_refine_corner_20_times),
        cmocka_unit_test(test_random_mixed),
        cmocka_unit_test(test_closed_cube),
        cmocka_unit_test(test_deterministic),
        cmocka_unit_test(test_refusals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
