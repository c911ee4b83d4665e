/* The ray tracer as a short program, in the order of the 1991 Testbed paper's
 * pseudocode: read the MID scene (objects, materials, lights, camera), build
 * the acceleration structure, make the image and the antialiasing sampler,
 * and trace every sample of every pixel. The same library calls as
 * `testbed render`, without its options, tiles and threads; render_file.c
 * is the whole command as one call (tb_render_file).
 *
 *     raytrace SCENE.mid OUT.exr [SPP]
 */
#include <stdio.h>
#include <stdlib.h>

#include "host/render/antialias.h"
#include "host/render/film.h"
#include "host/render/raytrace.h"
#include "host/render/render.h"
#include "host/render/scene.h"
#include "util/image/image.h"
#include "util/math/rng.h"

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: raytrace SCENE.mid OUT.{exr,pfm,png} [SPP]\n");
        return 2;
    }
    int spp = argc > 3 ? atoi(argv[3]) : 4;

    /* Read the scene: objects, material table, lights, emitters, camera and
     * a BVH over every object (one reference per mesh triangle). */
    tb_scene *scene;
    if (tb_scene_load(argv[1], NULL, &scene)) {
        fprintf(stderr, "raytrace: %s\n", tb_last_error());
        return 1;
    }

    /* The tracer: the area light made of the scene's emitters, and the
     * shading rules (Lambert + Phong, mirror, Fresnel refraction). */
    tb_raytracer rt;
    if (tb_rt_init(&rt, scene, NULL)) {
        fprintf(stderr, "raytrace: %s\n", tb_last_error());
        tb_scene_free(scene);
        return 1;
    }

    /* The image: a film with a box filter, one value per colour channel
     * (RGB, or spectral bands). */
    tb_filter box;
    tb_filter_init(&box, TB_FILTER_BOX, 0.0, 0.0);
    tb_film_desc fd = {.width = scene->camera.width, .height = scene->camera.height,
                       .channels = scene->nchannels, .filter = &box};
    tb_film *film = tb_film_create(&fd);
    if (!film) {
        fprintf(stderr, "raytrace: %s\n", tb_last_error());
        tb_rt_release(&rt);
        tb_scene_free(scene);
        return 1;
    }

    /* Antialiasing: spp stratified samples per pixel. */
    tb_aa_options aa = tb_aa_defaults();
    aa.spp = spp > 0 ? spp : 1;
    float *xy = malloc(sizeof(float) * 2 * (size_t)aa.spp);
    float value[TB_CHANNELS_MAX];

    /* Per pixel, per sample: the camera ray, its radiance, into the film. */
    for (int y = 0; y < fd.height && xy; y++) {
        for (int x = 0; x < fd.width; x++) {
            tb_pixel_sampler ps;
            tb_pixel_sampler_init(&ps, &aa, x, y);
            int n = tb_pixel_sampler_round(&ps, xy);
            for (int k = 0; k < n; k++) {
                double fx = x + xy[2 * k], fy = y + xy[2 * k + 1];
                tb_rng rng;
                tb_aa_sample_rng(&aa, x, y, (uint32_t)k, &rng);
                tb_rt_sample(&rt, fx, fy, &rng, value);
                tb_film_add(film, fx, fy, value, 1.0);
            }
        }
    }

    /* Resolve (spectral bands -> XYZ -> linear sRGB) and write. */
    tb_image *img = xy ? tb_render_resolve(scene, film) : NULL;
    int rc = 0;
    if (!img || tb_image_write(argv[2], img, NULL)) {
        fprintf(stderr, "raytrace: %s\n", xy ? tb_last_error() : "out of memory");
        rc = 1;
    } else {
        printf("raytrace: wrote %s (%dx%d, %d spp)\n", argv[2], img->width, img->height, aa.spp);
    }
    tb_image_free(img);
    free(xy);
    tb_film_free(film);
    tb_rt_release(&rt);
    tb_scene_free(scene);
    return rc;
}
