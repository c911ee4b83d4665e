/* Shared pieces of the intersection tests (test_isect_*.c): building objects
 * from hand-made MID objects, random transforms and rays, closed meshes built
 * here (icosphere, subdivided cube), and independent references written from
 * docs/mid.md: point membership and surface normals of every kind, in double.
 * Nothing here calls the intersection code. */
#ifndef TB_TESTS_OBJECT_TEST_ISECT_COMMON_H
#define TB_TESTS_OBJECT_TEST_ISECT_COMMON_H

#include "tb_test.h"

#include <stdbool.h>
#include <string.h>

#include "host/object/object.h"
#include "host/mid/mid.h"
#include "util/math/rng.h"
#include "util/math/transform.h"

#define TI_PI 3.14159265358979323846

/* ------------------------------------------------------------------ scale */

/* Work factor: $TB_TEST_SCALE if set, else 1 in a normal build and 1/50 under
 * AddressSanitizer (where every memory access is checked). The full counts
 * (10^6 rays) run in the normal build. */
static inline double ti_scale(void)
{
    const char *e = getenv("TB_TEST_SCALE");
    if (e)
        return atof(e);
#if defined(__SANITIZE_ADDRESS__)
    return 0.02;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
    return 0.02;
#endif
#endif
    return 1.0;
}

/* n scaled, at least `lo`. */
static inline long ti_count(long n, long lo)
{
    long m = (long)((double)n * ti_scale());
    return m < lo ? lo : m;
}

/* ------------------------------------------------------------------ random */

static inline double ti_uniform(tb_rng *r, double a, double b) { return a + (b - a) * tb_rng_double(r); }

/* Uniform direction on the unit sphere (double). */
static inline tb_dvec3 ti_sphere_dir(tb_rng *r)
{
    double z = ti_uniform(r, -1.0, 1.0), phi = ti_uniform(r, 0.0, 2.0 * TI_PI);
    double s = sqrt(fmax(0.0, 1.0 - z * z));
    return (tb_dvec3){s * cos(phi), s * sin(phi), z};
}

/* A random affine transform: scale per axis in [smin, smax] (a mirror now and
 * then), a random rotation, a translation in [-tr, tr]^3. */
static inline tb_transform ti_random_transform(tb_rng *r, double smin, double smax, double tr, bool mirror)
{
    tb_dvec3 s = {exp(ti_uniform(r, log(smin), log(smax))), exp(ti_uniform(r, log(smin), log(smax))),
                  exp(ti_uniform(r, log(smin), log(smax)))};
    if (mirror && tb_rng_below(r, 4) == 0)
        s.x = -s.x;
    tb_transform S, R;
    assert_int_equal(tb_transform_scale(s, &S), TB_OK);
    assert_int_equal(tb_transform_rotate(ti_uniform(r, 0.0, 2.0 * TI_PI), ti_sphere_dir(r), &R), TB_OK);
    tb_transform T = tb_transform_translate(
        (tb_dvec3){ti_uniform(r, -tr, tr), ti_uniform(r, -tr, tr), ti_uniform(r, -tr, tr)});
    tb_transform RS = tb_transform_compose(&R, &S);
    return tb_transform_compose(&T, &RS);
}

/* ------------------------------------------------------------------ objects */

/* A primitive as the MID reader would hand it out. */
static inline tb_mid_object ti_prim(tb_prim_kind k, tb_mid_geometry g, tb_transform xf)
{
    tb_mid_object m;
    memset(&m, 0, sizeof m);
    m.kind = k;
    m.to_world = xf;
    m.geom = g;
    m.material = tb_mid_material_default();
    return m;
}

/* A CSG node over children (their to_world must already include xf). */
static inline tb_mid_object ti_csg(tb_prim_kind k, const tb_mid_object *children, int n, tb_transform xf)
{
    tb_mid_object m = ti_prim(k, tb_mid_geometry_default(k), xf);
    m.children = children;
    m.nchildren = n;
    return m;
}

/* Builds an object, failing the test with the library's message on error. */
static inline tb_object *ti_build(const tb_mid_object *m, uint32_t index)
{
    tb_object *o = NULL;
    tb_status st = tb_object_from_mid(m, index, NULL, NULL, &o);
    if (st)
        fail_msg("tb_object_from_mid: %s", tb_last_error());
    return o;
}

/* A closed mesh owned by the test (inline polygons form). */
typedef struct ti_mesh {
    int nv, nf;
    tb_vec3 *v;
    int *start, *idx;
} ti_mesh;

static inline void ti_mesh_free(ti_mesh *m)
{
    free(m->v);
    free(m->start);
    free(m->idx);
    memset(m, 0, sizeof *m);
}

static inline tb_mid_geometry ti_mesh_geom(const ti_mesh *m)
{
    tb_mid_geometry g;
    memset(&g, 0, sizeof g);
    g.polygons.nvertices = m->nv;
    g.polygons.vertices = m->v;
    g.polygons.nfaces = m->nf;
    g.polygons.face_start = m->start;
    g.polygons.indices = m->idx;
    return g;
}

/* Midpoint cache for icosphere subdivision: edge (a, b) -> new vertex. */
static inline int ti__midpoint(ti_mesh *m, int *keys, int *vals, int cap, int a, int b)
{
    int lo = a < b ? a : b, hi = a < b ? b : a;
    unsigned h = ((unsigned)lo * 2654435761u ^ (unsigned)hi * 40503u) % (unsigned)cap;
    while (keys[2 * h] != -1) {
        if (keys[2 * h] == lo && keys[2 * h + 1] == hi)
            return vals[h];
        h = (h + 1) % (unsigned)cap;
    }
    tb_vec3 p = m->v[lo], q = m->v[hi];
    double x = (double)p.x + q.x, y = (double)p.y + q.y, z = (double)p.z + q.z, l = sqrt(x * x + y * y + z * z);
    m->v[m->nv] = (tb_vec3){(float)(x / l), (float)(y / l), (float)(z / l)};
    keys[2 * h] = lo;
    keys[2 * h + 1] = hi;
    vals[h] = m->nv;
    return m->nv++;
}

/* The unit icosphere: an icosahedron with its triangles split `levels`
 * times, new vertices pushed to the sphere, vertices shared (a closed mesh,
 * counter-clockwise seen from outside). 20 4^levels triangles. */
static inline ti_mesh ti_icosphere(int levels)
{
    int nf = 20, nv = 12;
    for (int i = 0; i < levels; i++) {
        nv += nf * 3 / 2;
        nf *= 4;
    }
    ti_mesh m = {0, nf, malloc(sizeof(tb_vec3) * (size_t)nv), malloc(sizeof(int) * (size_t)(nf + 1)),
                 malloc(sizeof(int) * 3 * (size_t)nf)};
    double t = (1.0 + sqrt(5.0)) / 2.0, l = sqrt(1.0 + t * t);
    const double base[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    for (int i = 0; i < 12; i++)
        m.v[i] = (tb_vec3){(float)(base[i][0] / l), (float)(base[i][1] / l), (float)(base[i][2] / l)};
    m.nv = 12;
    static const int f20[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                   {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                   {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                   {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    int *tri = malloc(sizeof(int) * 3 * (size_t)nf), ntri = 20;
    memcpy(tri, f20, sizeof f20);
    for (int lv = 0; lv < levels; lv++) {
        int cap = ntri * 4 + 7;
        int *keys = malloc(sizeof(int) * 2 * (size_t)cap), *vals = malloc(sizeof(int) * (size_t)cap);
        for (int i = 0; i < 2 * cap; i++)
            keys[i] = -1;
        int *nt = malloc(sizeof(int) * 12 * (size_t)ntri);
        for (int f = 0; f < ntri; f++) {
            int a = tri[3 * f], b = tri[3 * f + 1], c = tri[3 * f + 2];
            int ab = ti__midpoint(&m, keys, vals, cap, a, b), bc = ti__midpoint(&m, keys, vals, cap, b, c),
                ca = ti__midpoint(&m, keys, vals, cap, c, a);
            int q[12] = {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca};
            memcpy(&nt[12 * f], q, sizeof q);
        }
        free(tri);
        free(keys);
        free(vals);
        tri = nt;
        ntri *= 4;
    }
    for (int f = 0; f <= nf; f++)
        m.start[f] = 3 * f;
    memcpy(m.idx, tri, sizeof(int) * 3 * (size_t)nf);
    free(tri);
    return m;
}

/* The cube [-1,1]^3 with each face split into n x n quads (shared vertices;
 * quads as polygons of 4, so the build triangulates them). */
static inline ti_mesh ti_cube_mesh(int n)
{
    /* Vertices on the surface of the (n+1)^3 lattice. */
    int side = n + 1;
    int *id = malloc(sizeof(int) * (size_t)(side * side * side));
    ti_mesh m = {0, 6 * n * n, malloc(sizeof(tb_vec3) * (size_t)(side * side * side)),
                 malloc(sizeof(int) * (size_t)(6 * n * n + 1)), malloc(sizeof(int) * 4 * (size_t)(6 * n * n))};
    for (int i = 0; i < side; i++)
        for (int j = 0; j < side; j++)
            for (int k = 0; k < side; k++) {
                int on = i == 0 || i == n || j == 0 || j == n || k == 0 || k == n;
                id[(i * side + j) * side + k] = on ? m.nv : -1;
                if (on)
                    m.v[m.nv++] = (tb_vec3){-1.0f + 2.0f * (float)i / (float)n, -1.0f + 2.0f * (float)j / (float)n,
                                            -1.0f + 2.0f * (float)k / (float)n};
            }
#define TI_ID(i, j, k) id[((i) * side + (j)) * side + (k)]
    int f = 0;
    for (int axis = 0; axis < 3; axis++)
        for (int s = 0; s < 2; s++)
            for (int a = 0; a < n; a++)
                for (int b = 0; b < n; b++) {
                    int q[4][3];
                    int c = s ? n : 0;
                    /* corners (a,b) (a+1,b) (a+1,b+1) (a,b+1) in the face's (u,v) axes */
                    int uv[4][2] = {{a, b}, {a + 1, b}, {a + 1, b + 1}, {a, b + 1}};
                    for (int k = 0; k < 4; k++) {
                        int u = uv[k][0], v = uv[k][1];
                        if (axis == 0)
                            q[k][0] = c, q[k][1] = u, q[k][2] = v;
                        else if (axis == 1)
                            q[k][0] = v, q[k][1] = c, q[k][2] = u;
                        else
                            q[k][0] = u, q[k][1] = v, q[k][2] = c;
                    }
                    /* (u, v) turn counter-clockwise about +axis; reverse on the - side. */
                    m.start[f] = 4 * f;
                    for (int k = 0; k < 4; k++) {
                        int kk = s ? k : 3 - k;
                        m.idx[4 * f + k] = TI_ID(q[kk][0], q[kk][1], q[kk][2]);
                    }
                    f++;
                }
#undef TI_ID
    m.start[f] = 4 * f;
    free(id);
    return m;
}

/* ------------------------------------------------------------------ references */

/* Even-odd point-in-polygon for n points xy[]. */
static inline bool ti_in_polygon(const double *xy, int n, double x, double y)
{
    bool in = false;
    for (int i = 0, j = n - 1; i < n; j = i++) {
        double xi = xy[2 * i], yi = xy[2 * i + 1], xj = xy[2 * j], yj = xy[2 * j + 1];
        if ((yi > y) != (yj > y) && x < (xj - xi) * (y - yi) / (yj - yi) + xi)
            in = !in;
    }
    return in;
}

/* Inside the closed solid primitive (kind, g) at object-space p (docs/mid.md
 * 6.3). Polygons: only the meshes of this file, whose solids are known: the
 * cube mesh is [-1,1]^3, the icosphere the convex hull of its vertices
 * (approximated here by the unit ball, so callers stay away from it). */
static inline bool ti_inside(tb_prim_kind k, const tb_mid_geometry *g, tb_dvec3 p)
{
    double rho2 = p.x * p.x + p.y * p.y;
    switch (k) {
    case TB_PRIM_SPHERE: return rho2 + p.z * p.z <= 1.0;
    case TB_PRIM_CUBE:
    case TB_PRIM_POLYGONS: return fabs(p.x) <= 1.0 && fabs(p.y) <= 1.0 && fabs(p.z) <= 1.0;
    case TB_PRIM_CYLINDER: return rho2 <= 1.0 && fabs(p.z) <= 1.0;
    case TB_PRIM_CONE: {
        double r = 0.5 * ((1.0 + g->cone.top_radius) + (g->cone.top_radius - 1.0) * p.z);
        return fabs(p.z) <= 1.0 && r >= 0.0 && sqrt(rho2) <= r;
    }
    case TB_PRIM_PYRAMID: {
        double h = 0.5 * ((1.0 + g->pyramid.top) + (g->pyramid.top - 1.0) * p.z);
        return fabs(p.z) <= 1.0 && fabs(p.x) <= h && fabs(p.y) <= h;
    }
    case TB_PRIM_PRISM: {
        if (fabs(p.z) > 1.0)
            return false;
        if (g->prism.nprofile > 0) {
            double xy[2 * 64];
            int n = g->prism.nprofile;
            for (int i = 0; i < n && i < 64; i++) {
                xy[2 * i] = g->prism.profile[i].x;
                xy[2 * i + 1] = g->prism.profile[i].y;
            }
            return ti_in_polygon(xy, n, p.x, p.y);
        }
        /* Regular n-gon: inside every edge's half-plane (apothem test in the sector). */
        int n = g->prism.sides;
        double ang = atan2(p.y, p.x);
        if (ang < 0)
            ang += 2.0 * TI_PI;
        int kk = (int)floor(ang / (2.0 * TI_PI / n));
        double mid = (kk + 0.5) * 2.0 * TI_PI / n;
        return p.x * cos(mid) + p.y * sin(mid) <= cos(TI_PI / n);
    }
    case TB_PRIM_TORUS: {
        double q = sqrt(rho2) - g->torus.major;
        return q * q + p.z * p.z <= g->torus.minor * g->torus.minor;
    }
    case TB_PRIM_CONIC: {
        const double *c = g->conic.c;
        return p.z >= g->conic.z0 && p.z <= g->conic.z1 && rho2 <= c[0] + c[1] * p.z + c[2] * p.z * p.z;
    }
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH: {
        if (!(fabs(p.x) <= 1.0 && fabs(p.y) <= 1.0 && fabs(p.z) <= 1.0))
            return false;
        double hw = 0.5 * g->arch.width, h = g->arch.height;
        if (fabs(p.x) >= hw)
            return true;
        if (k == TB_PRIM_SQUARE_ARCH)
            return p.z >= -1.0 + h;
        double zs = -1.0 + h - hw;
        return p.z > zs && p.x * p.x + (p.z - zs) * (p.z - zs) >= hw * hw;
    }
    default: return false;
    }
}

/* Inside a built object (any tree) at world point p: the reference of the
 * CSG tests, from the object's own transforms and parameters. */
static inline bool ti_inside_object(const tb_object *o, tb_dvec3 p)
{
    if (tb_prim_is_csg(o->kind)) {
        if (o->kind == TB_PRIM_UNION) {
            for (int i = 0; i < o->nchildren; i++)
                if (ti_inside_object(&o->children[i], p))
                    return true;
            return false;
        }
        if (o->kind == TB_PRIM_INTERSECTION) {
            for (int i = 0; i < o->nchildren; i++)
                if (!ti_inside_object(&o->children[i], p))
                    return false;
            return true;
        }
        if (!ti_inside_object(&o->children[0], p))
            return false;
        for (int i = 1; i < o->nchildren; i++)
            if (ti_inside_object(&o->children[i], p))
                return false;
        return true;
    }
    tb_dvec3 q = tb_mat4_mul_point(&o->to_world.inv, p);
    return ti_inside(o->kind, &o->geom, q);
}

#endif
