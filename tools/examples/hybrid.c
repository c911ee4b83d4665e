/* The hybrid radiosity + ray-tracing renderer as a short program of public
 * calls (docs/hybrid.md): load the scene, solve its diffuse interreflection
 * by radiosity (host/hybrid: mesh, full solve and, for the interpolated
 * mode, the direct-only solve), then ray trace from the camera with direct
 * light by shadow rays and indirect diffuse light from the solution, and
 * write the image. The same image, pixel for pixel, as
 * `testbed render SCENE --method hybrid [--hybrid-mode gather] [--max-edge L]`
 * with the command's defaults (1 sample per pixel, box filter).
 *
 *     hybrid SCENE.mid OUT.{exr,pfm,png} [interpolated|gather] [MAX_EDGE]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "host/hybrid/hybrid.h"
#include "host/render/render.h"
#include "host/render/scene.h"
#include "util/image/image.h"

int main(int argc, char **argv)
{
    if (argc < 3 || (argc > 3 && strcmp(argv[3], "interpolated") && strcmp(argv[3], "gather"))) {
        fprintf(stderr, "usage: hybrid SCENE.mid OUT.{exr,pfm,png} [interpolated|gather] [MAX_EDGE]\n");
        return 2;
    }
    tb_scene *scene = NULL;
    if (tb_scene_load(argv[1], NULL, &scene)) { /* with a BVH: the ray tracer needs it */
        fprintf(stderr, "hybrid: %s\n", tb_last_error());
        return 1;
    }

    /* Pass 1, view-independent: radiosity on the scene's default mesh (or
     * elements of MAX_EDGE), stopped at 0.3% unshot power. */
    tb_hybrid_options ho = tb_hybrid_defaults();
    if (argc > 3 && !strcmp(argv[3], "gather"))
        ho.mode = TB_HYBRID_GATHER;
    if (argc > 4) {
        ho.mesh_given = true;
        ho.mesh.max_edge = atof(argv[4]);
    }
    ho.log = stderr; /* the mesh size, shots and seconds */
    tb_hybrid *h = NULL;
    tb_status st = tb_hybrid_create(scene, &ho, &h);

    /* Pass 2, view-dependent: the Whitted ray tracer with the solution's
     * indirect light at every diffuse hit, through the render driver. */
    tb_image *img = NULL;
    tb_render_stats rs;
    if (!st) {
        tb_render_options ro = tb_render_defaults();
        st = tb_render_hybrid(h, &ro, &img, &rs);
    }
    if (!st)
        st = tb_image_write_exposed(argv[2], img, NAN); /* PNG: mean luminance to 0.18 */
    if (st)
        fprintf(stderr, "hybrid: %s\n", tb_last_error());
    else
        printf("hybrid: %zu elements, %llu shots, %.3f s radiosity; %dx%d, %.3f s ray tracing; wrote %s\n",
               tb_hybrid_get_stats(h).elements, (unsigned long long)tb_hybrid_get_stats(h).shots,
               tb_hybrid_get_stats(h).solve_seconds + tb_hybrid_get_stats(h).direct_seconds, img->width,
               img->height, rs.seconds, argv[2]);
    tb_image_free(img);
    tb_hybrid_free(h);
    tb_scene_free(scene);
    return st ? 1 : 0;
}
