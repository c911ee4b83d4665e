/* Secondary ray sets shared by the ray benchmarks (bench_raysets.h). */
#include "bench_raysets.h"

#include <math.h>

#include "host/object/hit.h"
#include "host/object/intersect.h"

/* Cosine-distributed direction about unit n from (u1, u2). */
static tb_vec3 tb__cosine_dir(tb_vec3 n, float u1, float u2)
{
    tb_vec3 a = fabsf(n.x) > 0.9f ? (tb_vec3){0.0f, 1.0f, 0.0f} : (tb_vec3){1.0f, 0.0f, 0.0f};
    tb_vec3 t = tb_vec3_normalize(tb_vec3_cross(a, n)), b = tb_vec3_cross(n, t);
    float r = sqrtf(u1), phi = 6.28318530717958648f * u2, z = sqrtf(fmaxf(0.0f, 1.0f - u1));
    float x = r * cosf(phi), y = r * sinf(phi);
    return (tb_vec3){x * t.x + y * b.x + z * n.x, x * t.y + y * b.y + z * n.y, x * t.z + y * b.z + z * n.z};
}

size_t tb_bench_secondary_rays(const tb_scene *s, const tb_area_light *area, const tb_ray *primary, size_t np,
                               tb_rng *rng, tb_ray *shadow, size_t *nshadow, tb_ray *diffuse, size_t *ndiffuse)
{
    size_t no_shadow = 0;
    for (size_t i = 0; i < np; i++) {
        tb_ray r = primary[i];
        tb_hit h;
        tb_vec3 p, perr;
        if (!tb_scene_intersect(s, &r, &h))
            continue;
        r.tmax = h.t;
        if (!tb_object_hit_point(s->objects[h.object], &r, &h, &p, &perr))
            continue;
        float u1 = tb_rng_float(rng), u2 = tb_rng_float(rng), u3 = tb_rng_float(rng), u4 = tb_rng_float(rng);
        /* Shadow: toward a point on a light. */
        tb_light_sample ls;
        bool ok = false;
        if (area)
            ok = tb_area_light_sample(area, p, u1, u2, &ls);
        else if (s->nlights > 0) {
            int l = (int)(u1 * (float)s->nlights);
            ok = tb_light_sample_li(&s->lights[l < s->nlights ? l : s->nlights - 1], p, &ls);
        }
        if (ok) {
            tb_ray sh = ls.shadow;
            sh.o = tb_spawn_ray_origin(p, perr, h.ng, ls.wi);
            shadow[(*nshadow)++] = sh;
        } else
            no_shadow++;
        /* Diffuse: about the normal on the camera's side. */
        tb_vec3 n = tb_vec3_dot(h.ng, r.d) > 0.0f ? tb_vec3_neg(h.ng) : h.ng;
        tb_vec3 w = tb__cosine_dir(n, u3, u4);
        diffuse[(*ndiffuse)++] = tb_ray_make(tb_spawn_ray_origin(p, perr, h.ng, w), w, 0.0f, INFINITY);
    }
    return no_shadow;
}
