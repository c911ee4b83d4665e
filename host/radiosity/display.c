/* The radiosity solution seen from the scene camera (docs/radiosity.md,
 * "Display"): rays against the elements, corner radiosities interpolated. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "host/radiosity/radiosity.h"
#include "host/render/accel.h"
#include "host/render/film.h"
#include "host/render/render.h"
#include "util/math/float.h"

/* Ray against triangle (a, b, c) (Moller-Trumbore, double): t and the
 * barycentrics of b and c; false on a miss. */
static bool tb__tri(const tb_ray *r, tb_vec3 a, tb_vec3 b, tb_vec3 c, double *t, double *u, double *v)
{
    double e1[3] = {(double)b.x - a.x, (double)b.y - a.y, (double)b.z - a.z};
    double e2[3] = {(double)c.x - a.x, (double)c.y - a.y, (double)c.z - a.z};
    double d[3] = {r->d.x, r->d.y, r->d.z};
    double p[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0]};
    double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
    if (det == 0.0)
        return false;
    double inv = 1.0 / det;
    double s[3] = {(double)r->o.x - a.x, (double)r->o.y - a.y, (double)r->o.z - a.z};
    double uu = (s[0] * p[0] + s[1] * p[1] + s[2] * p[2]) * inv;
    if (uu < 0.0 || uu > 1.0)
        return false;
    double q[3] = {s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2], s[0] * e1[1] - s[1] * e1[0]};
    double vv = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) * inv;
    if (vv < 0.0 || uu + vv > 1.0)
        return false;
    double tt = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) * inv;
    if (!(tt >= r->tmin && tt <= r->tmax))
        return false;
    *t = tt, *u = uu, *v = vv;
    return true;
}

/* Closest hit of element i: t, the triangle (0: v0 v1 v2, 1: v0 v2 v3)
 * and its barycentrics. */
static bool tb__elem_hit(const tb_rad_mesh *m, uint32_t i, const tb_ray *r, double *t, int *tri, double *u,
                         double *v)
{
    const tb_rad_element *e = &m->elems[i];
    bool hit = false;
    double tt, uu, vv;
    if (tb__tri(r, m->verts[e->v[0]].p, m->verts[e->v[1]].p, m->verts[e->v[2]].p, &tt, &uu, &vv))
        hit = true, *t = tt, *tri = 0, *u = uu, *v = vv;
    if (e->v[3] != TB_RAD_NONE &&
        tb__tri(r, m->verts[e->v[0]].p, m->verts[e->v[2]].p, m->verts[e->v[3]].p, &tt, &uu, &vv) &&
        (!hit || tt < *t))
        hit = true, *t = tt, *tri = 1, *u = uu, *v = vv;
    return hit;
}

static bool tb__accel_isect(void *ctx, const tb_accel_prim *prim, uint32_t index, const tb_ray *ray, tb_hit *hit)
{
    (void)index;
    const tb_rad_mesh *m = ctx;
    double t, u, v;
    int tri;
    if (!tb__elem_hit(m, prim->sub, ray, &t, &tri, &u, &v))
        return false;
    memset(hit, 0, sizeof *hit);
    hit->t = (float)t;
    if (!(hit->t >= ray->tmin && hit->t <= ray->tmax))
        return false;
    hit->object = prim->object;
    hit->face = prim->sub;
    hit->ng = m->elems[prim->sub].normal;
    return true;
}

tb_status tb_rad_render_image(const tb_rad_solver *s, const tb_scene *scene, int spp, tb_image **out)
{
    *out = NULL;
    if (spp < 1 || spp > 1024)
        return tb_error(TB_ERR_ARG, "radiosity image: samples per pixel %d not in 1..1024", spp);
    const tb_rad_mesh *m = tb_rad_solver_mesh(s);
    if (m->nchannels != scene->nchannels)
        return tb_error(TB_ERR_ARG, "radiosity image: the solution has %d channels, the scene %d", m->nchannels,
                        scene->nchannels);
    int nc = m->nchannels;
    tb_accel_prim *prims = malloc(m->nelems * sizeof *prims);
    float *corner = malloc(m->nelems * 4 * (size_t)nc * sizeof *corner);
    if (!prims || !corner) {
        free(prims), free(corner);
        return tb_error(TB_ERR_NOMEM, "radiosity image: out of memory");
    }
    /* every corner's radiance, ambient included (summed over the elements once, not at every corner) */
    double b[TB_CHANNELS_MAX], amb[TB_CHANNELS_MAX];
    tb_rad_ambient(s, amb);
    for (size_t i = 0; i < m->nelems; i++) {
        const tb_rad_element *e = &m->elems[i];
        int n = e->v[3] == TB_RAD_NONE ? 3 : 4;
        tb_aabb box = {m->verts[e->v[0]].p, m->verts[e->v[0]].p};
        for (int k = 0; k < n; k++) {
            box.lo = tb_vec3_min(box.lo, m->verts[e->v[k]].p);
            box.hi = tb_vec3_max(box.hi, m->verts[e->v[k]].p);
            tb_rad_corner_radiosity_amb(s, i, k, amb, b);
            for (int c = 0; c < nc; c++)
                corner[(i * 4 + (size_t)k) * (size_t)nc + (size_t)c] = (float)(b[c] / TB_PI);
        }
        prims[i] = (tb_accel_prim){.bounds = box, .object = e->object, .sub = (uint32_t)i};
    }
    tb_accel_callbacks cb = {.intersect = tb__accel_isect, .ctx = (void *)m};
    tb_accel *acc = NULL;
    tb_status st = tb_accel_build(TB_ACCEL_BVH, prims, m->nelems, &cb, NULL, &acc);
    free(prims);
    tb_film *film = NULL;
    if (!st) {
        tb_film_desc fd = {.width = scene->camera.width, .height = scene->camera.height, .channels = nc};
        film = tb_film_create(&fd);
        if (!film)
            st = TB_ERR_NOMEM;
    }
    int side = (int)ceil(sqrt((double)spp));
    int ntiles = st ? 0 : tb_film_tile_count(film);
    int failed = 0;
#pragma omp parallel for schedule(dynamic, 1)
    for (int ti = 0; ti < ntiles; ti++) {
        tb_film_tile *tile = tb_film_tile_create(film, ti);
        if (!tile) {
#pragma omp atomic write
            failed = 1;
            continue;
        }
        tb_tile_rect r = tb_film_tile_pixels(tile);
        float val[TB_CHANNELS_MAX];
        for (int y = r.y0; y < r.y1; y++)
            for (int x = r.x0; x < r.x1; x++)
                for (int sy = 0; sy < side; sy++)
                    for (int sx = 0; sx < side; sx++) {
                        double fx = x + (sx + 0.5) / side, fy = y + (sy + 0.5) / side;
                        tb_ray ray = tb_camera_ray(&scene->camera, fx, fy, 0.5f, 0.5f);
                        tb_hit h;
                        for (int c = 0; c < nc; c++)
                            val[c] = 0.0f;
                        if (tb_accel_intersect(acc, &ray, &h) && tb_vec3_dot(h.ng, ray.d) < 0.0f) {
                            double t, u, v;
                            int tri;
                            if (tb__elem_hit(m, h.face, &ray, &t, &tri, &u, &v)) {
                                int k1 = tri ? 2 : 1, k2 = tri ? 3 : 2;
                                const float *c0 = corner + ((size_t)h.face * 4) * (size_t)nc;
                                const float *c1 = corner + ((size_t)h.face * 4 + (size_t)k1) * (size_t)nc;
                                const float *c2 = corner + ((size_t)h.face * 4 + (size_t)k2) * (size_t)nc;
                                for (int c = 0; c < nc; c++)
                                    val[c] = (float)((1.0 - u - v) * c0[c] + u * c1[c] + v * c2[c]);
                            }
                        }
                        tb_film_tile_add(tile, fx, fy, val, 1.0);
                    }
        if (tb_film_tile_submit(film, tile)) {
#pragma omp atomic write
            failed = 1;
        }
    }
    if (!st && failed)
        st = tb_error(TB_ERR_NOMEM, "radiosity image: film tiles: %s", tb_last_error());
    if (!st) {
        *out = tb_render_resolve(scene, film);
        if (!*out)
            st = TB_ERR_NOMEM;
    }
    tb_film_free(film);
    tb_accel_free(acc);
    free(corner);
    return st;
}
