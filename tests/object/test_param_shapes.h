/* Random primitives for the param / bounds / polygonize property tests, and
 * independent descriptions of each kind written from docs/mid.md (inside
 * tests, face domains, areas and volumes) that the tests check the library
 * against. Nothing here calls the code under test. */
#ifndef TB_TESTS_OBJECT_TEST_PARAM_SHAPES_H
#define TB_TESTS_OBJECT_TEST_PARAM_SHAPES_H

#include <math.h>
#include <stdbool.h>
#include <string.h>

#include "host/mid/mid.h"
#include "util/math/rng.h"
#include "util/math/transform.h"

#define TS_PI 3.14159265358979323846

/* The primitive kinds (all but CSG). */
static const tb_prim_kind ts_kinds[] = {
    TB_PRIM_SPHERE, TB_PRIM_CUBE,  TB_PRIM_CYLINDER, TB_PRIM_CONE,        TB_PRIM_PYRAMID,    TB_PRIM_PRISM,
    TB_PRIM_TORUS,  TB_PRIM_POLYGONS, TB_PRIM_CONIC, TB_PRIM_SQUARE_ARCH, TB_PRIM_ROUND_ARCH,
};
#define TS_NKINDS ((int)(sizeof ts_kinds / sizeof ts_kinds[0]))

/* Room for a random profile / polygon set. */
#define TS_MAXV 64
#define TS_MAXF 8
#define TS_MAXI 256

/* One random primitive with its storage. */
typedef struct ts_shape {
    tb_prim_kind kind;
    tb_mid_geometry g;
    tb_vec2 profile[TS_MAXV];
    tb_vec3 verts[TS_MAXI];
    tb_vec2 uvs[TS_MAXI];
    int face_start[TS_MAXF + 1];
    int indices[TS_MAXI];
} ts_shape;

static inline double ts_uniform(tb_rng *r, double a, double b) { return a + (b - a) * tb_rng_double(r); }

/* A random star-shaped loop of n >= 3 points: angles jittered about 2 pi i / n
 * (consecutive ones less than pi apart, so the loop is simple and turns
 * counter-clockwise about the origin), radii in [rmin, 1]. */
static inline void ts_star(tb_rng *r, int n, double rmin, double *xs, double *ys)
{
    for (int i = 0; i < n; i++) {
        double ang = 2.0 * TS_PI * (i + 0.3 + 0.4 * tb_rng_double(r)) / n;
        double rad = ts_uniform(r, rmin, 1.0);
        xs[i] = rad * cos(ang), ys[i] = rad * sin(ang);
    }
}

/* A random conic r^2 = c2 (z - zv)^2 + k (or c1 z + c0), >= 0 on [z0, z1],
 * touching 0 at an end (a pole) about a third of the time. */
static inline void ts_random_conic(tb_rng *r, tb_geom_conic *c)
{
    double z0 = ts_uniform(r, -1.5, 0.5), z1 = z0 + ts_uniform(r, 0.3, 2.0);
    int fam = (int)tb_rng_below(r, 4);
    bool pole = tb_rng_below(r, 3) == 0;
    double extra = pole ? 0.0 : ts_uniform(r, 0.05, 1.0);
    c->z0 = z0, c->z1 = z1, c->caps = tb_rng_below(r, 4) != 0;
    if (fam == 0) { /* paraboloid: q = c1 z + c0 */
        double c1 = ts_uniform(r, 0.3, 2.0) * (tb_rng_below(r, 2) ? 1 : -1);
        double c0 = -fmin(c1 * z0, c1 * z1) + extra;
        c->c[0] = c0, c->c[1] = c1, c->c[2] = 0.0;
        return;
    }
    double c2 = fam == 1 ? -ts_uniform(r, 0.2, 2.0) : ts_uniform(r, 0.2, 2.0);
    double zv = ts_uniform(r, z0 - 0.5, z1 + 0.5), k;
    double e0 = (z0 - zv) * (z0 - zv), e1 = (z1 - zv) * (z1 - zv);
    if (c2 < 0.0) {
        k = -c2 * fmax(e0, e1) + extra; /* ellipsoid: the wider end decides */
        if (pole && tb_rng_below(r, 2)) { /* a sphere-like piece with both poles */
            zv = 0.5 * (z0 + z1), k = -c2 * (z1 - zv) * (z1 - zv);
        }
    } else if (fam == 2) {
        k = extra; /* hyperboloid of one sheet or a cone through its apex (k = 0) */
        if (pole)
            zv = tb_rng_below(r, 2) ? z0 : z1; /* apex at an end */
    } else {
        /* two sheets: r^2 = c2 (z - zv)^2 - m with the range on one sheet */
        double m = ts_uniform(r, 0.05, 0.5), a = sqrt(m / c2);
        zv = z0 - a - (pole ? 0.0 : ts_uniform(r, 0.01, 0.3));
        k = -m;
    }
    c->c[0] = c2 * zv * zv + k, c->c[1] = -2.0 * c2 * zv, c->c[2] = c2;
}

/* A random primitive of kind k. Polygons: 1..4 planar star-shaped polygons in
 * random planes (uvs: an orientation-preserving affine image of plane
 * coordinates, about half the time). */
static inline void ts_random_shape(tb_rng *r, tb_prim_kind k, ts_shape *s)
{
    memset(s, 0, sizeof *s);
    s->kind = k;
    s->g = tb_mid_geometry_default(k);
    switch (k) {
    case TB_PRIM_CYLINDER:
        s->g.cylinder.caps = tb_rng_below(r, 4) != 0;
        break;
    case TB_PRIM_CONE:
        s->g.cone.top_radius = tb_rng_below(r, 3) == 0 ? 0.0 : ts_uniform(r, 0.05, 2.0);
        s->g.cone.caps = tb_rng_below(r, 4) != 0;
        break;
    case TB_PRIM_PYRAMID:
        s->g.pyramid.top = tb_rng_below(r, 3) == 0 ? 0.0 : ts_uniform(r, 0.05, 2.0);
        s->g.pyramid.caps = tb_rng_below(r, 4) != 0;
        break;
    case TB_PRIM_PRISM:
        s->g.prism.caps = tb_rng_below(r, 4) != 0;
        if (tb_rng_below(r, 2)) {
            s->g.prism.sides = tb_rng_below(r, 5) == 0 ? 1000 : 3 + (int)tb_rng_below(r, 10);
        } else {
            int n = 3 + (int)tb_rng_below(r, 12);
            double xs[TS_MAXV], ys[TS_MAXV];
            ts_star(r, n, 0.3, xs, ys);
            bool rev = tb_rng_below(r, 2);
            for (int i = 0; i < n; i++) {
                int j = rev ? n - 1 - i : i;
                s->profile[i] = (tb_vec2){(float)(1.5 * xs[j] + 0.2), (float)(0.8 * ys[j] - 0.1)};
            }
            s->g.prism.sides = 0, s->g.prism.nprofile = n, s->g.prism.profile = s->profile;
        }
        break;
    case TB_PRIM_TORUS:
        s->g.torus.major = ts_uniform(r, 0.5, 2.0);
        s->g.torus.minor = s->g.torus.major * ts_uniform(r, 0.05, 0.9);
        break;
    case TB_PRIM_POLYGONS: {
        int nf = 1 + (int)tb_rng_below(r, 4), nv = 0, ni = 0;
        bool uvs = tb_rng_below(r, 2);
        for (int f = 0; f < nf; f++) {
            int n = 3 + (int)tb_rng_below(r, 8);
            double xs[TS_MAXV], ys[TS_MAXV];
            ts_star(r, n, 0.35, xs, ys);
            /* Random plane: centre, and an orthonormal frame from a random rotation. */
            tb_dvec3 c = {ts_uniform(r, -2, 2), ts_uniform(r, -2, 2), ts_uniform(r, -2, 2)};
            tb_transform rot;
            tb_transform_rotate(ts_uniform(r, 0, 2 * TS_PI),
                                (tb_dvec3){ts_uniform(r, -1, 1), ts_uniform(r, -1, 1), ts_uniform(r, -1, 1) + 0.01},
                                &rot);
            tb_dvec3 e1 = tb_transform_dvector(&rot, (tb_dvec3){1, 0, 0});
            tb_dvec3 e2 = tb_transform_dvector(&rot, (tb_dvec3){0, 1, 0});
            double sc = ts_uniform(r, 0.3, 2.0);
            double a = ts_uniform(r, 0.2, 0.4), b = ts_uniform(r, -0.1, 0.1), d = ts_uniform(r, 0.2, 0.4);
            s->face_start[f] = ni;
            for (int i = 0; i < n; i++) {
                tb_dvec3 p = tb_dvec3_add(c, tb_dvec3_add(tb_dvec3_scale(e1, sc * xs[i]), tb_dvec3_scale(e2, sc * ys[i])));
                s->verts[nv] = tb_dvec3_to_f(p);
                s->uvs[nv] = (tb_vec2){(float)(0.5 + a * xs[i] + b * ys[i]), (float)(0.5 + d * ys[i])};
                s->indices[ni++] = nv++;
            }
        }
        s->face_start[nf] = ni;
        tb_geom_polygons *p = &s->g.polygons;
        p->nvertices = nv, p->vertices = s->verts, p->nfaces = nf;
        p->face_start = s->face_start, p->indices = s->indices;
        p->uvs = uvs ? s->uvs : NULL;
        break;
    }
    case TB_PRIM_CONIC:
        ts_random_conic(r, &s->g.conic);
        break;
    case TB_PRIM_SQUARE_ARCH:
        s->g.arch.width = ts_uniform(r, 0.1, 1.9);
        s->g.arch.height = ts_uniform(r, 0.1, 1.9);
        break;
    case TB_PRIM_ROUND_ARCH: {
        double w = ts_uniform(r, 0.1, 1.9);
        s->g.arch.width = w;
        s->g.arch.height = tb_rng_below(r, 4) == 0 ? 0.5 * w : ts_uniform(r, 0.5 * w, 1.95);
        break;
    }
    default:
        break;
    }
}

/* A random affine transform: rotation, non-uniform scale (mirroring a
 * quarter of the time), shear and translation. */
static inline tb_transform ts_random_transform(tb_rng *r)
{
    tb_transform rot, sc, out;
    tb_transform_rotate(ts_uniform(r, 0, 2 * TS_PI),
                        (tb_dvec3){ts_uniform(r, -1, 1), ts_uniform(r, -1, 1), ts_uniform(r, -1, 1) + 0.01}, &rot);
    double m = tb_rng_below(r, 4) == 0 ? -1.0 : 1.0;
    tb_transform_scale((tb_dvec3){m * ts_uniform(r, 0.2, 3), ts_uniform(r, 0.2, 3), ts_uniform(r, 0.2, 3)}, &sc);
    tb_mat4 sh = {{{1, ts_uniform(r, -0.5, 0.5), 0, 0}, {0, 1, ts_uniform(r, -0.5, 0.5), 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}};
    tb_transform shear;
    tb_transform_from_matrix(&sh, &shear);
    tb_transform tr = tb_transform_translate((tb_dvec3){ts_uniform(r, -5, 5), ts_uniform(r, -5, 5), ts_uniform(r, -5, 5)});
    out = tb_transform_compose(&shear, &sc);
    out = tb_transform_compose(&rot, &out);
    return tb_transform_compose(&tr, &out);
}

/* ----------------------------------------------------------- 2D helpers */

/* Even-odd point-in-polygon for a loop of n 2D points. */
static inline bool ts_in_loop(const double *xs, const double *ys, int n, double x, double y)
{
    bool in = false;
    for (int i = 0, j = n - 1; i < n; j = i++)
        if ((ys[i] > y) != (ys[j] > y) && x < xs[j] + (y - ys[j]) * (xs[i] - xs[j]) / (ys[i] - ys[j]))
            in = !in;
    return in;
}

/* The prism's polygon (regular or profile) as loops. */
static inline int ts_prism_loop(const tb_geom_prism *p, double *xs, double *ys, int cap)
{
    int n = p->sides > 0 ? p->sides : p->nprofile;
    if (n > cap)
        return -1;
    for (int i = 0; i < n; i++) {
        if (p->sides > 0)
            xs[i] = cos(2 * TS_PI * i / n), ys[i] = sin(2 * TS_PI * i / n);
        else
            xs[i] = p->profile[i].x, ys[i] = p->profile[i].y;
    }
    return n;
}

/* r^2 of a conic. */
static inline double ts_conic_q(const tb_geom_conic *c, double z) { return c->c[0] + c->c[1] * z + c->c[2] * z * z; }

/* True if (x, z) is inside an arch's opening (open set). */
static inline bool ts_in_opening(tb_prim_kind k, const tb_geom_arch *a, double x, double z)
{
    double hw = 0.5 * a->width;
    if (!(fabs(x) < hw))
        return false;
    if (k == TB_PRIM_SQUARE_ARCH)
        return z < -1.0 + a->height;
    double zs = -1.0 + a->height - hw;
    return z <= zs || x * x + (z - zs) * (z - zs) < hw * hw;
}

/* Independent inside test of the solid (object space, open interior) for
 * every kind but polygons. */
static inline bool ts_inside(const ts_shape *s, tb_dvec3 p)
{
    double rho = hypot(p.x, p.y);
    switch (s->kind) {
    case TB_PRIM_SPHERE: return p.x * p.x + p.y * p.y + p.z * p.z < 1.0;
    case TB_PRIM_CUBE: return fabs(p.x) < 1 && fabs(p.y) < 1 && fabs(p.z) < 1;
    case TB_PRIM_CYLINDER: return rho < 1 && fabs(p.z) < 1;
    case TB_PRIM_CONE: return fabs(p.z) < 1 && rho < 1 + (s->g.cone.top_radius - 1) * (p.z + 1) / 2;
    case TB_PRIM_PYRAMID: {
        double h = 1 + (s->g.pyramid.top - 1) * (p.z + 1) / 2;
        return fabs(p.z) < 1 && fabs(p.x) < h && fabs(p.y) < h;
    }
    case TB_PRIM_PRISM: {
        static double xs[2000], ys[2000];
        int n = ts_prism_loop(&s->g.prism, xs, ys, 2000);
        return fabs(p.z) < 1 && ts_in_loop(xs, ys, n, p.x, p.y);
    }
    case TB_PRIM_TORUS: {
        double d = rho - s->g.torus.major;
        return d * d + p.z * p.z < s->g.torus.minor * s->g.torus.minor;
    }
    case TB_PRIM_CONIC:
        return p.z > s->g.conic.z0 && p.z < s->g.conic.z1 && rho * rho < ts_conic_q(&s->g.conic, p.z);
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH:
        return fabs(p.x) < 1 && fabs(p.y) < 1 && fabs(p.z) < 1 && !ts_in_opening(s->kind, &s->g.arch, p.x, p.z);
    default: return false;
    }
}

/* True if object-space point p (from eval of `face`) lies on the face proper
 * for faces whose (u, v) square is larger than the face (arch faces with the
 * opening, prism caps, polygons); true for every other face. */
static inline bool ts_on_face_domain(const ts_shape *s, int face, tb_dvec3 p, double u, double v)
{
    const double eps = 1e-9;
    switch (s->kind) {
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH:
        if (face == 2 || face == 3) /* front, back */
            return !ts_in_opening(s->kind, &s->g.arch, p.x, p.z) &&
                   !ts_in_opening(s->kind, &s->g.arch, p.x + eps, p.z + eps) &&
                   !ts_in_opening(s->kind, &s->g.arch, p.x - eps, p.z + eps);
        if (face == 4)
            return fabs(p.x) >= 0.5 * s->g.arch.width + eps;
        return true;
    case TB_PRIM_PRISM:
        if (face <= 1) {
            static double xs[2000], ys[2000];
            int n = ts_prism_loop(&s->g.prism, xs, ys, 2000);
            return ts_in_loop(xs, ys, n, p.x, p.y);
        }
        return true;
    case TB_PRIM_POLYGONS: {
        const tb_geom_polygons *g = &s->g.polygons;
        int b = g->face_start[face], n = g->face_start[face + 1] - b;
        double xs[TS_MAXV], ys[TS_MAXV];
        if (g->uvs) { /* (u, v) inside the polygon's uv loop */
            for (int i = 0; i < n; i++)
                xs[i] = g->uvs[g->indices[b + i]].x, ys[i] = g->uvs[g->indices[b + i]].y;
            return ts_in_loop(xs, ys, n, u, v);
        }
        /* p inside the loop, projected along the largest normal axis */
        tb_dvec3 nn = {0, 0, 0};
        for (int i = 0; i < n; i++) {
            tb_vec3 a = g->vertices[g->indices[b + i]], c = g->vertices[g->indices[b + (i + 1) % n]];
            nn.x += ((double)a.y - c.y) * ((double)a.z + c.z);
            nn.y += ((double)a.z - c.z) * ((double)a.x + c.x);
            nn.z += ((double)a.x - c.x) * ((double)a.y + c.y);
        }
        int ax = fabs(nn.x) > fabs(nn.y) ? (fabs(nn.x) > fabs(nn.z) ? 0 : 2) : (fabs(nn.y) > fabs(nn.z) ? 1 : 2);
        int i0 = (ax + 1) % 3, i1 = (ax + 2) % 3;
        for (int i = 0; i < n; i++) {
            tb_dvec3 q = tb_vec3_to_d(g->vertices[g->indices[b + i]]);
            xs[i] = tb_dvec3_get(q, i0), ys[i] = tb_dvec3_get(q, i1);
        }
        return ts_in_loop(xs, ys, n, tb_dvec3_get(p, i0), tb_dvec3_get(p, i1));
    }
    default:
        (void)u, (void)v;
        return true;
    }
}

#endif
