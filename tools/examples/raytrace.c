/* The Whitted ray tracer as a short program, in the order of the 1991
 * Testbed paper's pseudocode: read the MID scene (objects, materials,
 * lights, camera, acceleration structure), then for every sample of every
 * pixel trace the camera ray and shade its hits from the public surface
 * and light API (host/render/surface.h): emission, point/spot/directional
 * lights by shadow rays (Lambert + the Phong or Blinn highlight), soft
 * shadows from 4 stratified samples of the area light of all emitters
 * (diffuse), a perfect mirror weighted by the specular colour, and a
 * smooth dielectric's Fresnel reflection and refraction, to depth 5. That
 * is the algorithm of `testbed render` (docs/raytrace.md) for Lambert,
 * Phong and Blinn materials (the command's GGX glossy rays and texture
 * footprints are left out here); its images equal the command's to float
 * rounding on such scenes (tests/render/example_raytrace.sh). tb_render
 * drives the samples (tiles, threads, per-sample random streams);
 * render_file.c is the whole command as one call.
 *
 *     raytrace SCENE.mid OUT.{exr,pfm,png} [SPP [SEED]]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "host/render/render.h"
#include "host/render/sampling.h"
#include "host/render/surface.h"
#include "util/image/image.h"
#include "util/math/float.h"

#define DEPTH 5         /* deepest reflected or refracted ray */
#define LIGHT_SAMPLES 4 /* area-light samples per shading point (2 x 2 strata) */

typedef struct tracer {
    const tb_scene *scene;
    tb_surfaces *surfaces; /* materials: textures, patterns, bumps */
    tb_light_set lights;   /* delta lights + the area light of all emitters */
} tracer;

static tb_channels trace(const tracer *t, const tb_ray *ray, int depth, tb_rng *rng)
{
    const int nc = t->scene->nchannels;
    tb_channels L = tb_channels_splat(nc, 0.0f);
    tb_hit hit;
    tb_surface sf;
    if (!tb_scene_intersect(t->scene, ray, &hit) || !tb_surface_at(t->surfaces, ray, &hit, NULL, &sf))
        return L;
    L = tb_surface_emitted(&sf);
    const tb_light_set *ls = &t->lights;
    /* point, spot and directional lights: f = diffuse / pi + highlight */
    for (int i = 0; i < ls->nlights; i++) {
        tb_light_sample l;
        if (!tb_light_set_sample(ls, i, sf.p, 0.0f, 0.0f, &l))
            continue;
        float cosi = tb_vec3_dot(sf.n, l.wi), lobe = (float)tb_surface_phong_lobe(&sf, l.wi);
        if (cosi <= 0.0f || tb_light_set_occluded(ls, &sf, &l))
            continue;
        for (int c = 0; c < nc; c++)
            L.v[c] += (sf.diffuse.v[c] / (float)TB_PI + sf.specular.v[c] * lobe) * l.L.v[c] * cosi;
    }
    /* the area light: stratified samples, irradiance E, diffuse / pi E */
    if (ls->has_area && !tb_channels_is_black(sf.diffuse)) {
        float u[2 * LIGHT_SAMPLES];
        tb_stratified_2d(rng, 2, 2, u);
        tb_channels E = tb_channels_splat(nc, 0.0f);
        for (int k = 0; k < LIGHT_SAMPLES; k++) {
            tb_light_sample l;
            if (!tb_light_set_sample(ls, ls->nlights, sf.p, u[2 * k], u[2 * k + 1], &l))
                continue;
            float cosi = tb_vec3_dot(sf.n, l.wi);
            if (cosi > 0.0f && !tb_light_set_occluded(ls, &sf, &l))
                E = tb_channels_add_scaled(E, l.L, (float)(cosi / l.pdf));
        }
        const float es = (float)(1.0 / (TB_PI * LIGHT_SAMPLES));
        L = tb_channels_add(L, tb_channels_scale(tb_channels_mul(sf.diffuse, E), es));
    }
    if (depth >= DEPTH)
        return L;
    /* Whitted's rays: the dielectric's reflection (prob. R) and refraction
     * both traced, or the mirror weighted by the specular colour */
    tb_surface_bsdf b;
    tb_surface_bsdf_init(&sf, TB_SURFACE_WHITTED, &b);
    if (b.lobes & TB_LOBE_DIELECTRIC) {
        tb_frame fr = tb_frame_from_normal(sf.ng);
        tb_specular_split sp;
        tb_specular_dielectric(tb_frame_to_local(&fr, sf.wo), sf.ior, &sp);
        tb_ray r = tb_surface_spawn(&sf, tb_frame_to_world(&fr, sp.wr));
        L = tb_channels_add_scaled(L, trace(t, &r, depth + 1, rng), (float)sp.R);
        if (sp.refracts) {
            r = tb_surface_spawn(&sf, tb_vec3_normalize(tb_frame_to_world(&fr, sp.wt)));
            L = tb_channels_add(L, tb_channels_scale(tb_channels_mul(sf.transmission, trace(t, &r, depth + 1, rng)),
                                                     (float)sp.T));
        }
    } else if (b.lobes & TB_LOBE_MIRROR) {
        tb_vec3 wr = tb_vec3_normalize(tb_reflect(sf.wo, sf.n));
        if (tb_vec3_dot(wr, sf.nv) > 0.0f) { /* a bumped normal can mirror into the surface */
            tb_ray r = tb_surface_spawn(&sf, wr);
            L = tb_channels_add(L, tb_channels_mul(b.mirror, trace(t, &r, depth + 1, rng)));
        }
    }
    return L;
}

/* tb_render's per-sample function: the camera ray of film point (x, y). */
static void sample(void *ctx, double x, double y, tb_rng *rng, float *out)
{
    const tracer *t = ctx;
    const tb_camera *cam = &t->scene->camera;
    float lu, lv;
    tb_camera_lens_numbers(cam, rng, &lu, &lv);
    tb_ray r = tb_camera_ray(cam, x, y, lu, lv);
    tb_channels L = trace(t, &r, 0, rng);
    for (int c = 0; c < t->scene->nchannels; c++)
        out[c] = L.v[c];
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: raytrace SCENE.mid OUT.{exr,pfm,png} [SPP [SEED]]\n");
        return 2;
    }
    tb_render_options o = tb_render_defaults();
    o.aa.spp = argc > 3 ? atoi(argv[3]) : 4;
    if (argc > 4)
        o.aa.seed = strtoull(argv[4], NULL, 10);
    if (o.aa.spp < 1) {
        fprintf(stderr, "raytrace: SPP must be at least 1\n");
        return 2;
    }
    tracer t = {0};
    tb_scene *scene = NULL;
    tb_image *img = NULL;
    tb_status st = tb_scene_load(argv[1], NULL, &scene);
    if (!st) {
        t.scene = scene;
        st = tb_surfaces_create(scene, NULL, &t.surfaces);
    }
    if (!st)
        st = tb_light_set_init(&t.lights, scene);
    if (!st)
        st = tb_render(scene, sample, &t, &o, &img, NULL);
    if (!st)
        st = tb_image_write(argv[2], img, NULL);
    if (st)
        fprintf(stderr, "raytrace: %s\n", tb_last_error());
    else
        printf("raytrace: wrote %s (%dx%d, %d spp)\n", argv[2], img->width, img->height, o.aa.spp);
    tb_image_free(img);
    tb_light_set_release(&t.lights);
    tb_surfaces_free(t.surfaces);
    tb_scene_free(scene);
    return st ? 1 : 0;
}
