/* `testbed validate --kernel shade` (validate_shade.h): the Vulkan wavefront
 * renderer against the CPU ray tracer on the same scene, samples and seed. */
#include "validate_shade.h"

#include <math.h>
#include <stdio.h>

#include "host/gpu/render.h"
#include "host/render/render.h"
#include "util/image/image.h"

int tb_validate_shade(const tb_scene *s, tb_gpu_session *sess, long samples, long seed, bool *ok)
{
    *ok = false;
    const int spp = 4;
    /* A shallow copy of the scene with a smaller camera: only the camera differs. */
    tb_scene sc = *s;
    double aspect = (double)s->camera.width / s->camera.height;
    int width = (int)fmin(96.0, fmax(8.0, floor(sqrt((double)samples / spp * aspect))));
    int w = width < s->camera.width ? width : s->camera.width;
    int h = (int)lround((double)s->camera.height * w / s->camera.width);
    if (h < 1)
        h = 1;
    if (tb_camera_from_mid(&s->mid_camera, w, h, &sc.camera)) {
        fprintf(stderr, "testbed validate: error: %s\n", tb_last_error());
        return 1;
    }
    tb_render_options o = tb_render_defaults();
    o.aa.spp = spp;
    o.aa.seed = (uint64_t)seed;
    o.rt.spp = spp;
    tb_image *cpu = NULL, *gpu = NULL;
    tb_render_stats rc, rg;
    tb_gpu_render_stats gs;
    if (tb_render_raytrace(&sc, &o, &cpu, &rc) ||
        tb_gpu_render_raytrace(sess->device, &sc, &o, &gpu, &rg, &gs)) {
        fprintf(stderr, "testbed validate: error: shade: %s\n", tb_last_error());
        tb_image_free(cpu);
        return 1;
    }
    double num = 0.0, den = 0.0, maxd = 0.0, sa = 0.0, sb = 0.0;
    size_t npx = (size_t)w * (size_t)h, differ = 0;
    int mx = 0, my = 0;
    for (size_t i = 0; i < npx; i++) {
        double pd = 0.0, pr = 0.0;
        for (int c = 0; c < 3; c++) {
            double a = gpu->pixels[i * 3 + (size_t)c], b = cpu->pixels[i * 3 + (size_t)c];
            num += (a - b) * (a - b);
            sa += a;
            sb += b;
            den += b * b;
            pd = fmax(pd, fabs(a - b));
            pr = fmax(pr, fabs(b));
        }
        if (pd > 1e-3 * (pr + 1e-3))
            differ++;
        if (pd > maxd) {
            maxd = pd;
            mx = (int)(i % (size_t)w);
            my = (int)(i / (size_t)w);
        }
    }
    double nmse = den > 0.0 ? num / den : (num > 0.0 ? INFINITY : 0.0);
    double bias = sb != 0.0 ? (sa - sb) / sb : (sa != 0.0 ? INFINITY : 0.0);
    bool ok_nmse = nmse <= TB_VALIDATE_SHADE_TOL_NMSE, ok_bias = fabs(bias) <= TB_VALIDATE_SHADE_TOL_BIAS;
    *ok = ok_nmse && ok_bias;
    printf("kernel shade: %dx%d, %d spp, seed %ld: %llu hits shaded by the kernel, %llu routed to the CPU path%s%s\n",
           w, h, spp, seed, (unsigned long long)gs.gpu_shaded, (unsigned long long)gs.cpu_shaded,
           gs.routed_materials ? ": " : "", gs.routed_reason);
    printf("  %llu rays, %llu shadow rays, %llu waves; cpu %.3f s, vulkan %.3f s (shade kernel %.3f s)\n",
           (unsigned long long)gs.rays, (unsigned long long)gs.shadow_rays, (unsigned long long)gs.waves, rc.seconds,
           rg.seconds, gs.shade_seconds);
    printf("  pixels differing by more than 0.1%%: %zu of %zu; largest |difference| %.4g at (%d, %d)\n", differ, npx,
           maxd, mx, my);
    printf("  image NMSE        %9.3g  (tolerance %.0e)  %s\n", nmse, TB_VALIDATE_SHADE_TOL_NMSE,
           ok_nmse ? "ok" : "FAIL");
    printf("  mean bias         %9.3g  (sum (vulkan - cpu) / sum cpu; tolerance %.0e)  %s\n", bias,
           TB_VALIDATE_SHADE_TOL_BIAS, ok_bias ? "ok" : "FAIL");
    tb_image_free(cpu);
    tb_image_free(gpu);
    return 0;
}
