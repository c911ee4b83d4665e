/* `testbed validate --kernel formfactor` (called from cmd_validate.c): the
 * Vulkan form-factor kernel against the CPU batch (tb_ff_raycast_batch) on a
 * scene meshed as the radiosity renderer meshes it, per (receiver, shooter)
 * pair and per sample segment, against the tolerances of docs/accuracy.md
 * ("Form-factor kernel"). */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "ff_elements.h"
#include "host/gpu/formfactor.h"
#include "util/stats/stats.h"

/* Tolerances (docs/accuracy.md, "Form-factor kernel"). */
#define TB__FF_FLOOR 1e-6    /* form factors below this are compared absolutely (relative error = |dF| / 1e-6) */
/* Pairs whose segments all agree: |dF| / max(S, floor), S = sum over the counted samples of
 * da / (pi r^2 + da) (F with every cosine 1). Float against double moves each term by a few u
 * of its cosine-free size whatever the cosines, and the sum adds npts u: (16 + npts) u for a
 * term of about 13 roundings; twice that, at least 1e-5. */
#define TB__FF_TOL_SCALED(npts) fmax(1e-5, 2.0 * (16.0 + (double)(npts)) * 5.9604644775390625e-8)
#define TB__FF_TOL_MEAN 1e-3 /* mean relative error over all pairs (visibility flips included) */
#define TB__FF_TOL_VIS 1e-3  /* fraction of sample segments whose visibility may differ (grazing segments) */

/* The CPU's per-segment answers, by the CPU path's rule (tb_ff_raycast):
 * in front of both surfaces (double) and not blocked (tb_ff_occluders_visible);
 * scale[i]: the sum over the counted samples of da / (pi r^2 + da). */
static void tb__cpu_bits(tb_ff_occluders *occ, const tb_vec3 *pts, int npts, tb_vec3 ns, double da,
                         const tb_ffe_set *e, uint32_t *bits, uint32_t words, double *scale)
{
    ptrdiff_t nr = (ptrdiff_t)e->nrecv;
#pragma omp parallel for schedule(dynamic, 64)
    for (ptrdiff_t i = 0; i < nr; ++i) {
        tb_vec3 p = e->rp[i], n = e->rn[i];
        uint32_t *b = bits + (size_t)i * words;
        memset(b, 0, words * sizeof *b);
        scale[i] = 0.0;
        for (int k = 0; k < npts; ++k) {
            double d[3] = {(double)pts[k].x - p.x, (double)pts[k].y - p.y, (double)pts[k].z - p.z};
            double cr = n.x * d[0] + n.y * d[1] + n.z * d[2], cs = -(ns.x * d[0] + ns.y * d[1] + ns.z * d[2]);
            if (cr > 0.0 && cs > 0.0 && tb_ff_occluders_visible(occ, p, pts[k])) {
                b[k / 32] |= 1u << (k % 32);
                scale[i] += da / (3.14159265358979323846 * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) + da);
            }
        }
    }
}

static unsigned tb__popcount(uint32_t x)
{
    unsigned c = 0;
    for (; x; x &= x - 1)
        ++c;
    return c;
}

int tb_validate_formfactor(const tb_scene *s, tb_gpu_session *sess, long shooters, long samples, long receivers,
                           long seed, bool *ok_out)
{
    *ok_out = false;
    tb_aabb b = s->bounds;
    double diag = sqrt(((double)b.hi.x - b.lo.x) * ((double)b.hi.x - b.lo.x) +
                       ((double)b.hi.y - b.lo.y) * ((double)b.hi.y - b.lo.y) +
                       ((double)b.hi.z - b.lo.z) * ((double)b.hi.z - b.lo.z));
    if (!(diag > 0.0) || !isfinite(diag))
        diag = 1.0;
    double edge = diag / TB_FFE_EDGE_DIVISOR;
    tb_ffe_set e;
    if (tb_ffe_build(s, edge, &e)) {
        fprintf(stderr, "testbed validate: error: formfactor: %s\n", tb_last_error());
        return TB_EXIT_FAIL;
    }
    if (e.n == 0) { /* e.g. only lights, or nothing polygonizable: nothing to compare */
        printf("kernel formfactor: no elements (%u objects could not be polygonized): nothing to compare\n",
               e.skipped);
        tb_ffe_free(&e);
        *ok_out = true;
        return TB_EXIT_OK;
    }
    int rc = TB_EXIT_FAIL;
    size_t all_recv = e.nrecv;
    tb_ffe_subsample(&e, (size_t)receivers, (uint64_t)seed);
    int npts = (int)samples;
    uint32_t words = ((uint32_t)npts + 31u) / 32u;
    size_t nr = e.nrecv;
    uint32_t *shoot = malloc((size_t)shooters * sizeof *shoot);
    tb_vec3 *pts = malloc((size_t)npts * sizeof *pts);
    double *cf = malloc(nr * sizeof *cf), *gf = malloc(nr * sizeof *gf), *sc = malloc(nr * sizeof *sc);
    uint32_t *cb = malloc(nr * words * sizeof *cb), *gb = malloc(nr * words * sizeof *gb);
    tb_ff_occluders *occ = NULL;
    tb_gpu_ff_scene *g = NULL;
    if (!shoot || !pts || !cf || !gf || !sc || !cb || !gb) {
        fprintf(stderr, "testbed validate: error: out of memory for %zu receivers\n", nr);
        goto done;
    }
    if (tb_ff_occluders_build(e.polys, e.n, &occ) || !(g = tb_gpu_ff_scene_create(sess->device, e.polys, e.n))) {
        fprintf(stderr, "testbed validate: error: formfactor: %s\n", tb_last_error());
        goto done;
    }
    size_t ns = tb_ffe_shooters(&e, s, (size_t)shooters, (uint64_t)seed, shoot);
    printf("kernel formfactor: %zu elements (edge %.4g; %u objects not polygonized), %zu receivers (of %zu centroids "
           "and corners), %zu shooters x %d samples, %zu occluder triangles\n",
           e.n, edge, e.skipped, nr, all_recv, ns, npts, tb_gpu_ff_scene_triangles(g));
    double max_agree = 0.0, max_scaled = 0.0, max_all = 0.0, sum_rel = 0.0, cpu_s = 0.0, gpu_s = 0.0, kern_s = 0.0;
    size_t pairs = 0, flipped_pairs = 0, segs = 0, vis_diff = 0, shown = 0;
    for (size_t j = 0; j < ns; ++j) {
        uint32_t el = shoot[j];
        if (tb_ff_sample_polygon(&e.polys[el], npts, (uint64_t)seed * 1000003u + j, pts)) {
            fprintf(stderr, "testbed validate: error: formfactor: %s\n", tb_last_error());
            goto done;
        }
        int64_t t0 = tb_stats_now_ns();
        tb_status st = tb_ff_raycast_batch(occ, pts, npts, e.normal[el], e.area[el], e.rp, e.rn, nr, cf);
        int64_t t1 = tb_stats_now_ns();
        tb_gpu_ff_timing tm;
        if (!st)
            st = tb_gpu_ff_raycast(g, pts, npts, e.normal[el], e.area[el], e.rp, e.rn, nr, gf, gb, &tm);
        int64_t t2 = tb_stats_now_ns();
        if (st) {
            fprintf(stderr, "testbed validate: error: formfactor: %s\n", tb_last_error());
            goto done;
        }
        cpu_s += (double)(t1 - t0) * 1e-9;
        gpu_s += (double)(t2 - t1) * 1e-9;
        kern_s += tm.kernel_seconds;
        tb__cpu_bits(occ, pts, npts, e.normal[el], e.area[el] / npts, &e, cb, words, sc);
        for (size_t i = 0; i < nr; ++i) {
            unsigned diff = 0;
            for (uint32_t w = 0; w < words; ++w)
                diff += tb__popcount(cb[i * words + w] ^ gb[i * words + w]);
            double rel = fabs(gf[i] - cf[i]) / fmax(fabs(cf[i]), TB__FF_FLOOR);
            double scaled = fabs(gf[i] - cf[i]) / fmax(sc[i], TB__FF_FLOOR);
            ++pairs;
            segs += (size_t)npts;
            vis_diff += diff;
            sum_rel += rel;
            max_all = fmax(max_all, rel);
            if (diff) {
                ++flipped_pairs;
                if (shown++ < 5)
                    printf("  differs: shooter %u, receiver %zu (%g %g %g): %u of %d segments; cpu F %.6g, vulkan F "
                           "%.6g\n",
                           el, i, e.rp[i].x, e.rp[i].y, e.rp[i].z, diff, npts, cf[i], gf[i]);
            } else {
                max_agree = fmax(max_agree, rel);
                max_scaled = fmax(max_scaled, scaled);
            }
        }
    }
    double mean = pairs ? sum_rel / (double)pairs : 0.0, f_vis = segs ? (double)vis_diff / (double)segs : 0.0;
    double tol_scaled = TB__FF_TOL_SCALED(npts);
    bool ok_max = max_scaled <= tol_scaled, ok_mean = mean <= TB__FF_TOL_MEAN, ok_vis = f_vis <= TB__FF_TOL_VIS;
    printf("  max scaled error       %9.3g    (pairs whose segments all agree: |dF| / max(sum da/(pi r^2 + da), %g); "
           "tolerance %.3g)  %s\n",
           max_scaled, TB__FF_FLOOR, tol_scaled, ok_max ? "ok" : "BEYOND TOLERANCE");
    printf("  max relative error     %9.3g    (the same pairs, |dF| / max(F, %g): large only where every cosine is "
           "small)\n",
           max_agree, TB__FF_FLOOR);
    printf("  mean relative error    %9.3g    (all %zu pairs; tolerance %g)  %s\n", mean, pairs, TB__FF_TOL_MEAN,
           ok_mean ? "ok" : "BEYOND TOLERANCE");
    printf("  visibility agreement   %9.5f %%  (%zu of %zu segments differ, in %zu pairs; tolerance: at most %g of "
           "segments)  %s\n",
           100.0 * (1.0 - f_vis), vis_diff, segs, flipped_pairs, TB__FF_TOL_VIS, ok_vis ? "ok" : "BEYOND TOLERANCE");
    printf("  max relative error, all pairs %.3g (not a criterion: one flipped segment moves a pair by about 1/%d)\n",
           max_all, npts);
    printf("  time: cpu batch %.3f s (%d threads), vulkan %.3f s (kernel %.3f s device time)\n", cpu_s,
           omp_get_max_threads(), gpu_s, kern_s);
    *ok_out = ok_max && ok_mean && ok_vis;
    rc = TB_EXIT_OK;
done:
    tb_gpu_ff_scene_destroy(g);
    tb_ff_occluders_free(occ);
    tb_ffe_free(&e);
    free(shoot), free(pts), free(cf), free(gf), free(sc), free(cb), free(gb);
    return rc;
}
