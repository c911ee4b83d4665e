/* Progressive radiosity as a short program: one library call does what
 * `testbed render --method radiosity` does (host/radiosity/render.h): read
 * the MID scene, mesh every surface into elements (the default element size:
 * the scene's diagonal / 24), shoot the patch with the most unshot power
 * until less than 0.3% of the emitted power is left, and write the
 * per-element radiosities and, if asked, the Gouraud-shaded image from the
 * scene camera. Same options, same bytes as the command.
 *
 *     radiosity SCENE.mid PATCHES.csv [IMAGE] [MAX_SHOTS]
 */
#include <stdio.h>
#include <stdlib.h>

#include "host/radiosity/render.h"

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: radiosity SCENE.mid PATCHES.csv [IMAGE.{exr,pfm,png}] [MAX_SHOTS]\n");
        return 2;
    }

    /* The defaults of the command: ray-cast form factors (16 sample points
     * per shooter), threshold 0.3%, 4 rays per pixel for the image. */
    tb_rad_render_options opt = tb_rad_render_defaults();
    opt.patches_path = argv[2];
    if (argc > 3 && argv[3][0])
        opt.image_path = argv[3];
    if (argc > 4)
        opt.stop.max_shots = strtoull(argv[4], NULL, 10);
    opt.argc = argc, opt.argv = argv; /* recorded in the image's provenance */
    opt.log = stderr;                 /* the mesh size and the lights */
    opt.log_prefix = "radiosity: ";

    /* Load, mesh, solve, write. */
    tb_rad_render_result res;
    if (tb_rad_render(argv[1], &opt, &res)) {
        fprintf(stderr, "radiosity: %s\n", tb_last_error());
        return 1;
    }
    printf("radiosity: %zu elements, %llu shots, unshot fraction %.3g, %.3f s; wrote %s\n", res.elements,
           (unsigned long long)res.shots, res.unshot_fraction, res.seconds, opt.patches_path);
    return 0;
}
