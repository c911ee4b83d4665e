/* The ray tracer as one library call: tb_render_file does what `testbed
 * render --backend cpu` does (host/render/render_file.h): read the MID
 * scene, build the BVH, trace SPP stratified samples per pixel in tiles on
 * every core (the image does not depend on the thread count), and write the
 * image with its provenance. Same options, same bytes as the command.
 * tools/examples/raytrace.c spells out the algorithm underneath.
 *
 *     render_file SCENE.mid OUT.{exr,pfm,png} [SPP] [STATS.json]
 */
#include <stdio.h>
#include <stdlib.h>

#include "host/render/render_file.h"

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: render_file SCENE.mid OUT.{exr,pfm,png} [SPP] [STATS.json]\n");
        return 2;
    }

    /* The defaults of the command: one pass, box filter, automatic PNG
     * exposure; every tb_render_options field is there to change. */
    tb_render_file_options opt = tb_render_file_defaults();
    opt.image_path = argv[2];
    if (argc > 3)
        opt.render.aa.spp = atoi(argv[3]);
    if (argc > 4)
        opt.stats_path = argv[4];
    opt.render.progress = true;       /* a progress bar on a terminal */
    opt.argc = argc, opt.argv = argv; /* recorded in the image's provenance */

    /* Load, trace, write. */
    tb_render_file_result res;
    if (tb_render_file(argv[1], &opt, &res)) {
        fprintf(stderr, "render_file: %s\n", tb_last_error());
        return 1;
    }
    printf("render_file: %dx%d, %llu samples, %.3f s (%d threads, %s); wrote %s\n", res.width, res.height,
           (unsigned long long)res.stats.aa.samples, res.stats.seconds, res.threads,
           res.spectral ? "spectral" : "rgb", opt.image_path);
    return 0;
}
