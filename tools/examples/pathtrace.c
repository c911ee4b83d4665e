/* A complete path tracer as a short program of public calls: the surface
 * record, composite BSDF and light set of host/render/surface.h, driven by
 * tb_render (tiles, threads, per-sample random streams). The algorithm of
 * `testbed render --method path` (docs/pathtrace.md): next-event estimation
 * from every light with the area-light sample and BSDF-sampled emission
 * weighted by the power heuristic, Russian roulette after 3 bounces. Its
 * images equal the command's statistically (tests/render/pt_example.sh);
 * it point-samples image textures, which the command filters over the
 * pixel's footprint at the first hit.
 *
 *     pathtrace SCENE.mid OUT.{exr,pfm,png} [SPP [SEED]]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "host/render/render.h"
#include "host/render/surface.h"
#include "util/image/image.h"

/* What every sample reads (shared by the threads, read-only). */
typedef struct renderer {
    const tb_scene *scene;
    tb_surfaces *surfaces; /* materials: textures, patterns, bumps */
    tb_light_set lights;   /* delta lights + the area light of all emitters */
} renderer;

/* L += beta * f * Li * s, per channel. */
static void gather(tb_channels *L, const tb_channels *beta, tb_channels f, tb_channels Li, double s)
{
    for (int c = 0; c < L->n; c++)
        L->v[c] += (float)((double)beta->v[c] * f.v[c] * Li.v[c] * s);
}

/* Next-event estimation at surface sf: every delta light, one area sample. */
static void direct(const renderer *r, const tb_surface *sf, const tb_surface_bsdf *b, const tb_channels *beta,
                   tb_channels *L, tb_rng *rng)
{
    const tb_light_set *ls = &r->lights;
    for (int i = 0; i < tb_light_set_count(ls); i++) {
        const bool area = i == ls->nlights;
        float u1 = area ? tb_rng_float(rng) : 0.0f, u2 = area ? tb_rng_float(rng) : 0.0f;
        tb_light_sample l;
        if (!tb_light_set_sample(ls, i, sf->p, u1, u2, &l))
            continue;
        tb_channels f = tb_surface_bsdf_eval(b, sf->wo, l.wi), Le = l.L;
        double pl = 1.0;
        if (tb_channels_is_black(f))
            continue;
        /* delta lights: the shadow ray; the area light: the exact emitter must be seen */
        bool seen = area ? tb_light_set_visible_emitter(ls, r->surfaces, sf, &l, &Le, &pl)
                         : !tb_light_set_occluded(ls, sf, &l);
        if (!seen)
            continue;
        double w = area ? tb_power_heuristic(pl, tb_surface_bsdf_pdf(b, sf->wo, l.wi)) / pl : 1.0;
        gather(L, beta, f, Le, fabs((double)tb_vec3_dot(l.wi, sf->n)) * w);
    }
}

/* Radiance along one camera ray: the path loop. */
static tb_channels radiance(const renderer *r, tb_ray ray, tb_rng *rng)
{
    const int nc = r->scene->nchannels;
    tb_channels L = tb_channels_splat(nc, 0.0f), beta = tb_channels_splat(nc, 1.0f);
    const tb_channels one = tb_channels_splat(nc, 1.0f);
    bool prev_delta = true; /* the camera ray: emission counts fully */
    double prev_pdf = 0.0;
    tb_vec3 prev_p = ray.o;
    for (int depth = 0; depth < 1024; depth++) {
        tb_hit hit;
        tb_surface sf;
        if (!tb_scene_intersect(r->scene, &ray, &hit) || !tb_surface_at(r->surfaces, &ray, &hit, NULL, &sf))
            break;
        /* emission found by the BSDF sample, weighted against the light sample */
        if (sf.emits && sf.front) {
            double w = prev_delta ? 1.0
                                  : tb_power_heuristic(prev_pdf, tb_light_set_emitter_pdf(&r->lights, prev_p, &sf));
            gather(&L, &beta, one, tb_surface_emitted(&sf), w);
        }
        tb_surface_bsdf b;
        tb_surface_bsdf_init(&sf, TB_SURFACE_PHYSICAL, &b);
        if (b.lobes & (TB_LOBE_DIFFUSE | TB_LOBE_GLOSSY))
            direct(r, &sf, &b, &beta, &L, rng);
        /* the next direction from the BSDF */
        float uc = tb_rng_float(rng), u1 = tb_rng_float(rng), u2 = tb_rng_float(rng);
        tb_surface_sample s;
        if (!tb_surface_bsdf_sample(&b, sf.wo, uc, u1, u2, &s))
            break;
        beta = tb_channels_mul(beta, s.weight);
        if (!tb_channels_is_finite(beta) || tb_channels_is_black(beta))
            break;
        prev_delta = s.delta, prev_pdf = s.pdf, prev_p = sf.p;
        ray = tb_surface_spawn(&sf, s.wi);
        /* Russian roulette: survive with q = min(1, max beta), divide by q */
        if (depth + 1 >= 3) {
            double q = fmin(1.0, (double)tb_channels_max(beta));
            if (q < 1.0) {
                if (!((double)tb_rng_float(rng) < q))
                    break;
                beta = tb_channels_scale(beta, (float)(1.0 / q));
            }
        }
    }
    return L;
}

/* tb_render's per-sample function: the camera ray of film point (x, y). */
static void sample(void *ctx, double x, double y, tb_rng *rng, float *out)
{
    const renderer *r = ctx;
    const tb_camera *cam = &r->scene->camera;
    float lu, lv;
    tb_camera_lens_numbers(cam, rng, &lu, &lv);
    tb_channels L = radiance(r, tb_camera_ray(cam, x, y, lu, lv), rng);
    for (int c = 0; c < r->scene->nchannels; c++)
        out[c] = L.v[c];
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: pathtrace SCENE.mid OUT.{exr,pfm,png} [SPP [SEED]]\n");
        return 2;
    }
    tb_render_options o = tb_render_defaults();
    o.aa.spp = argc > 3 ? atoi(argv[3]) : 16;
    if (argc > 4)
        o.aa.seed = strtoull(argv[4], NULL, 10);
    if (o.aa.spp < 1) {
        fprintf(stderr, "pathtrace: SPP must be at least 1\n");
        return 2;
    }
    renderer r = {0};
    tb_scene *scene = NULL;
    tb_image *img = NULL;
    tb_status st = tb_scene_load(argv[1], NULL, &scene);
    if (!st) {
        r.scene = scene;
        st = tb_surfaces_create(scene, NULL, &r.surfaces);
    }
    if (!st)
        st = tb_light_set_init(&r.lights, scene);
    if (!st)
        st = tb_render(scene, sample, &r, &o, &img, NULL);
    if (!st)
        st = tb_image_write(argv[2], img, NULL);
    if (st)
        fprintf(stderr, "pathtrace: %s\n", tb_last_error());
    else
        printf("pathtrace: wrote %s (%dx%d, %d spp)\n", argv[2], img->width, img->height, o.aa.spp);
    tb_image_free(img);
    tb_light_set_release(&r.lights);
    tb_surfaces_free(r.surfaces);
    tb_scene_free(scene);
    return st ? 1 : 0;
}
