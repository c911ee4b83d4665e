/* Test primitives for the acceleration structure tests: spheres and
 * triangles intersected in double (t rounded to float once), their boxes,
 * callbacks for tb_accel, random scenes and rays, and a brute-force closest
 * hit that applies the tie rule by sorting all candidates (written
 * independently of host/render). */
#ifndef TB_TESTS_RENDER_TEST_ACCEL_PRIMS_H
#define TB_TESTS_RENDER_TEST_ACCEL_PRIMS_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "host/render/accel.h"
#include "util/math/aabb.h"
#include "util/math/float.h"
#include "util/math/rng.h"

enum { TP_SPHERE, TP_TRIANGLE };

/* One test primitive. */
typedef struct tp_prim {
    int kind;
    float c[3], r;      /* sphere centre and radius */
    float v[3][3];      /* triangle vertices */
    uint32_t object;    /* reported object index */
    uint32_t face;      /* reported face ID */
    float tag;          /* added to the reported v: tells apart copies with equal t, object and face */
} tp_prim;

/* A scene: primitives and their references (refs[i] is prims[i]). */
typedef struct tp_scene {
    tp_prim *prims;
    tb_accel_prim *refs;
    size_t n, cap;
} tp_scene;

/* The box of a primitive: exact for triangles, rounded outward for spheres. */
static inline tb_aabb tp_bounds(const tp_prim *p)
{
    if (p->kind == TP_SPHERE)
        return (tb_aabb){{tb_float_round_down((double)p->c[0] - p->r), tb_float_round_down((double)p->c[1] - p->r), tb_float_round_down((double)p->c[2] - p->r)},
                         {tb_float_round_up((double)p->c[0] + p->r), tb_float_round_up((double)p->c[1] + p->r), tb_float_round_up((double)p->c[2] + p->r)}};
    tb_aabb b = tb_aabb_empty();
    for (int i = 0; i < 3; i++)
        b = tb_aabb_union_point(b, (tb_vec3){p->v[i][0], p->v[i][1], p->v[i][2]});
    return b;
}

static inline void tp_add(tp_scene *s, tp_prim p)
{
    if (s->n == s->cap) {
        s->cap = s->cap ? 2 * s->cap : 64;
        s->prims = realloc(s->prims, s->cap * sizeof *s->prims);
        s->refs = realloc(s->refs, s->cap * sizeof *s->refs);
        if (!s->prims || !s->refs)
            abort();
    }
    s->prims[s->n] = p;
    s->refs[s->n] = (tb_accel_prim){tp_bounds(&p), p.object, (uint32_t)s->n};
    s->n++;
}

static inline void tp_add_sphere(tp_scene *s, float x, float y, float z, float r, uint32_t object, uint32_t face)
{
    tp_prim p = {.kind = TP_SPHERE, .c = {x, y, z}, .r = r, .object = object, .face = face};
    tp_add(s, p);
}

static inline void tp_add_triangle(tp_scene *s, const float v[3][3], uint32_t object, uint32_t face)
{
    tp_prim p = {.kind = TP_TRIANGLE, .object = object, .face = face};
    memcpy(p.v, v, sizeof p.v);
    tp_add(s, p);
}

static inline void tp_free(tp_scene *s)
{
    free(s->prims);
    free(s->refs);
    memset(s, 0, sizeof *s);
}

/* Closest hit of primitive p with t in [tmin, tmax] (after rounding t to
 * float). The result depends on tmax only through that filter. */
static inline bool tp_intersect_prim(const tp_prim *p, const tb_ray *ray, tb_hit *hit)
{
    double o[3] = {ray->o.x, ray->o.y, ray->o.z}, d[3] = {ray->d.x, ray->d.y, ray->d.z};
    float ts[2];
    int nt = 0;
    double n[2][3];
    double uv[2][2];
    if (p->kind == TP_SPHERE) {
        if (!(p->r > 0.0f)) /* a point: never hit (its hit would lie off its zero-extent box by rounding) */
            return false;
        double oc[3] = {o[0] - p->c[0], o[1] - p->c[1], o[2] - p->c[2]};
        double a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        double b = oc[0] * d[0] + oc[1] * d[1] + oc[2] * d[2];
        double c = oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2] - (double)p->r * p->r;
        double disc = b * b - a * c;
        if (disc < 0.0)
            return false;
        double q = -(b + copysign(sqrt(disc), b));
        double r0 = q != 0.0 ? q / a : 0.0, r1 = q != 0.0 ? c / q : 0.0;
        if (q == 0.0) /* b == 0 and disc == 0: a tangent touch at the origin's foot point */
            r0 = r1 = 0.0;
        if (r0 > r1) {
            double s = r0;
            r0 = r1;
            r1 = s;
        }
        double rt[2] = {r0, r1};
        for (int i = 0; i < 2; i++) {
            ts[nt] = (float)rt[i];
            for (int k = 0; k < 3; k++)
                n[nt][k] = o[k] + rt[i] * d[k] - p->c[k];
            uv[nt][0] = i;
            uv[nt][1] = 0.5;
            nt++;
        }
    } else {
        double v0[3] = {p->v[0][0], p->v[0][1], p->v[0][2]};
        double e1[3], e2[3], s[3];
        for (int k = 0; k < 3; k++) {
            e1[k] = p->v[1][k] - v0[k];
            e2[k] = p->v[2][k] - v0[k];
            s[k] = o[k] - v0[k];
        }
        double pv[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0]};
        double det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
        if (det == 0.0)
            return false;
        double inv = 1.0 / det;
        double u = (s[0] * pv[0] + s[1] * pv[1] + s[2] * pv[2]) * inv;
        if (u < 0.0 || u > 1.0)
            return false;
        double qv[3] = {s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2], s[0] * e1[1] - s[1] * e1[0]};
        double v = (d[0] * qv[0] + d[1] * qv[1] + d[2] * qv[2]) * inv;
        if (v < 0.0 || u + v > 1.0)
            return false;
        double t = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) * inv;
        ts[0] = (float)t;
        n[0][0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[0][1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[0][2] = e1[0] * e2[1] - e1[1] * e2[0];
        uv[0][0] = u;
        uv[0][1] = v;
        nt = 1;
    }
    for (int i = 0; i < nt; i++) {
        if (!(ts[i] >= ray->tmin && ts[i] <= ray->tmax))
            continue;
        double len = sqrt(n[i][0] * n[i][0] + n[i][1] * n[i][1] + n[i][2] * n[i][2]);
        if (!(len > 0.0))
            len = 1.0;
        hit->t = ts[i];
        hit->object = p->object;
        hit->face = p->face;
        hit->u = (float)uv[i][0];
        hit->v = (float)uv[i][1] + p->tag;
        hit->ng = (tb_vec3){(float)(n[i][0] / len), (float)(n[i][1] / len), (float)(n[i][2] / len)};
        return true;
    }
    return false;
}

/* tb_accel callback: ctx is the tp_scene, prim->sub the primitive's position. */
static inline bool tp_cb_intersect(void *ctx, const tb_accel_prim *prim, uint32_t index, const tb_ray *ray,
                                   tb_hit *hit)
{
    tp_scene *s = ctx;
    if (prim->sub != index) /* the structure must hand back the reference it was given */
        abort();
    return tp_intersect_prim(&s->prims[prim->sub], ray, hit);
}

static inline bool tp_cb_occluded(void *ctx, const tb_accel_prim *prim, uint32_t index, const tb_ray *ray)
{
    tb_hit h;
    return tp_cb_intersect(ctx, prim, index, ray, &h);
}

/* A candidate of the brute-force search. */
typedef struct tp_cand {
    tb_hit hit;
    uint32_t index;
} tp_cand;

static inline int tp_cand_cmp(const void *pa, const void *pb)
{
    const tp_cand *a = pa, *b = pb;
    if (a->hit.t < b->hit.t) return -1;
    if (a->hit.t > b->hit.t) return 1;
    if (a->hit.object != b->hit.object) return a->hit.object < b->hit.object ? -1 : 1;
    if (a->hit.face != b->hit.face) return a->hit.face < b->hit.face ? -1 : 1;
    return a->index < b->index ? -1 : (a->index > b->index);
}

/* Brute force: every primitive's hit over the full [tmin, tmax], sorted by
 * (t, object, face, index); the first is the answer. Invalid rays never hit.
 * Primitives with an empty box are skipped (the structures drop them). */
static inline bool tp_brute(const tp_scene *s, const tb_ray *ray, tb_hit *hit)
{
    if (!tb_ray_is_valid(ray))
        return false;
    tp_cand *c = malloc((s->n ? s->n : 1) * sizeof *c);
    if (!c)
        abort();
    size_t m = 0;
    for (size_t i = 0; i < s->n; i++) {
        if (tb_aabb_is_empty(&s->refs[i].bounds))
            continue;
        if (tp_intersect_prim(&s->prims[i], ray, &c[m].hit)) {
            c[m].index = (uint32_t)i;
            m++;
        }
    }
    bool found = m > 0;
    if (found) {
        qsort(c, m, sizeof *c, tp_cand_cmp);
        *hit = c[0].hit;
    }
    free(c);
    return found;
}

static inline float tp_uniform(tb_rng *r, float lo, float hi) { return lo + (hi - lo) * tb_rng_float(r); }

/* A random unit direction; with probability 1/4 axis-parallel (with random
 * signed zeros in the other components). */
static inline tb_vec3 tp_random_dir(tb_rng *r)
{
    if (tb_rng_below(r, 4) == 0) {
        float v[3];
        for (int k = 0; k < 3; k++)
            v[k] = tb_rng_below(r, 2) ? 0.0f : -0.0f;
        v[tb_rng_below(r, 3)] = tb_rng_below(r, 2) ? 1.0f : -1.0f;
        return (tb_vec3){v[0], v[1], v[2]};
    }
    for (;;) {
        tb_vec3 v = {tp_uniform(r, -1, 1), tp_uniform(r, -1, 1), tp_uniform(r, -1, 1)};
        float l = tb_vec3_length(v);
        if (l > 0.1f && l <= 1.0f)
            return tb_vec3_scale(v, 1.0f / l);
    }
}

/* A random scene in [-1, 1]^3 scaled by `scale` and moved by `offset`:
 * spheres of radii from 1e-3 to 0.3, random and axis-aligned (flat-box)
 * triangles, a few big overlapping spheres, degenerate primitives with
 * zero-extent boxes, and exact duplicates under other object/face numbers
 * (ties). */
static inline void tp_random_scene(tp_scene *s, tb_rng *r, size_t n, float scale, float offset)
{
    uint32_t nobj = (uint32_t)(n / 2 + 1);
    for (size_t i = 0; i < n; i++) {
        uint32_t obj = tb_rng_below(r, nobj), face = tb_rng_below(r, 4);
        unsigned kind = tb_rng_below(r, 16);
        if (kind < 6) {
            float rad = 1e-3f * powf(300.0f, tb_rng_float(r));
            tp_add_sphere(s, offset + scale * tp_uniform(r, -1, 1), offset + scale * tp_uniform(r, -1, 1),
                          offset + scale * tp_uniform(r, -1, 1), scale * rad, obj, face);
        } else if (kind < 11) {
            float v[3][3], c[3], sz = 0.01f * powf(50.0f, tb_rng_float(r));
            for (int k = 0; k < 3; k++)
                c[k] = tp_uniform(r, -1, 1);
            for (int j = 0; j < 3; j++)
                for (int k = 0; k < 3; k++)
                    v[j][k] = offset + scale * (c[k] + sz * tp_uniform(r, -1, 1));
            tp_add_triangle(s, (const float(*)[3])v, obj, face);
        } else if (kind < 13) {
            /* Axis-aligned triangle: a flat box along one axis. */
            float v[3][3], c[3], sz = 0.02f * powf(20.0f, tb_rng_float(r));
            int ax = (int)tb_rng_below(r, 3);
            for (int k = 0; k < 3; k++)
                c[k] = tp_uniform(r, -1, 1);
            for (int j = 0; j < 3; j++)
                for (int k = 0; k < 3; k++)
                    v[j][k] = offset + scale * (k == ax ? c[k] : c[k] + sz * tp_uniform(r, -1, 1));
            tp_add_triangle(s, (const float(*)[3])v, obj, face);
        } else if (kind == 13 && s->n > 0) {
            /* An exact duplicate of an earlier primitive under another number. */
            tp_prim p = s->prims[tb_rng_below(r, (uint32_t)s->n)];
            p.object = obj;
            p.face = tb_rng_below(r, 2) ? p.face : face;
            p.tag = (float)tb_rng_below(r, 3); /* equal t, object and face, other v: the index decides */
            tp_add(s, p);
        } else if (kind == 14) {
            /* Degenerate: a triangle collapsed to a point (zero-extent box, never hit)
             * or a sphere of radius zero. */
            float c[3];
            for (int k = 0; k < 3; k++)
                c[k] = offset + scale * tp_uniform(r, -1, 1);
            if (tb_rng_below(r, 2)) {
                float v[3][3] = {{c[0], c[1], c[2]}, {c[0], c[1], c[2]}, {c[0], c[1], c[2]}};
                tp_add_triangle(s, (const float(*)[3])v, obj, face);
            } else {
                tp_add_sphere(s, c[0], c[1], c[2], 0.0f, obj, face);
            }
        } else {
            /* Rarely, a big sphere overlapping much of the scene. */
            if (tb_rng_below(r, 8) == 0)
                tp_add_sphere(s, offset + scale * tp_uniform(r, -0.5f, 0.5f), offset + scale * tp_uniform(r, -0.5f, 0.5f),
                              offset + scale * tp_uniform(r, -0.5f, 0.5f), scale * tp_uniform(r, 0.5f, 1.2f), obj, face);
            else
                tp_add_sphere(s, offset + scale * tp_uniform(r, -1, 1), offset + scale * tp_uniform(r, -1, 1),
                              offset + scale * tp_uniform(r, -1, 1), scale * 0.05f, obj, face);
        }
    }
}

/* A random ray for a scene in [-1, 1]^3 * scale + offset: from inside or
 * outside, aimed at a primitive or anywhere, with various tmin/tmax. */
static inline tb_ray tp_random_ray(tb_rng *r, const tp_scene *s, float scale, float offset)
{
    tb_vec3 o = {offset + scale * tp_uniform(r, -2, 2), offset + scale * tp_uniform(r, -2, 2),
                 offset + scale * tp_uniform(r, -2, 2)};
    tb_vec3 d = tp_random_dir(r);
    if (s->n > 0 && tb_rng_below(r, 2)) {
        /* Aimed at a primitive's box centre (often a hit, often a grazing one). */
        tb_aabb b = s->refs[tb_rng_below(r, (uint32_t)s->n)].bounds;
        if (!tb_aabb_is_empty(&b)) {
            tb_vec3 c = tb_aabb_centroid(&b);
            tb_vec3 dd = tb_vec3_sub(c, o);
            if (tb_vec3_length(dd) > 0.0f)
                d = tb_vec3_scale(dd, 1.0f / tb_vec3_length(dd));
        }
    }
    if (tb_rng_below(r, 5) == 0)
        d = tb_vec3_scale(d, tp_uniform(r, 0.01f, 100.0f)); /* t is in units of |d| */
    float tmin = 0.0f, tmax = INFINITY;
    switch (tb_rng_below(r, 6)) {
    case 0:
        tmin = tp_uniform(r, -1, 1) * scale;
        break;
    case 1:
        tmax = tp_uniform(r, 0, 3) * scale;
        break;
    case 2:
        tmin = tp_uniform(r, 0, 1) * scale;
        tmax = tmin + tp_uniform(r, 0, 2) * scale;
        break;
    default:
        break;
    }
    return tb_ray_make(o, d, tmin, tmax);
}

#endif
