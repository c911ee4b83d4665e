/* Two path tracers of the same scene that differ only in how emitters are
 * represented (analytic or lazily tessellated against eagerly tessellated)
 * must agree: the radiance toward points, estimated with independent
 * streams, within 4 standard errors of the difference. Shared by the
 * surface- and CSG-emitter tests. */
#ifndef TB_TESTS_RENDER_TEST_PT_AGREE_H
#define TB_TESTS_RENDER_TEST_PT_AGREE_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "host/render/pathtrace.h"
#include "util/math/rng.h"

/* A Monte Carlo estimate: mean and its standard error. */
typedef struct tp_est {
    double mean, se;
} tp_est;

/* Radiance (channel 1) along the ray from o toward target, n paths. */
static inline tp_est tp_pt_estimate(const tb_pathtracer *pt, tb_vec3 o, tb_vec3 target, long n, uint64_t seed)
{
    double s1 = 0.0, s2 = 0.0;
    tb_rng rng;
    tb_rng_seed(&rng, seed, 11);
    tb_vec3 d = tb_vec3_normalize(tb_vec3_sub(target, o));
    for (long i = 0; i < n; i++) {
        tb_ray ray = tb_ray_make(o, d, 0.0f, INFINITY);
        tb_channels L = tb_pt_radiance(pt, &ray, &rng);
        s1 += L.v[1];
        s2 += (double)L.v[1] * L.v[1];
    }
    tp_est e = {s1 / n, 0.0};
    e.se = sqrt(fmax(0.0, s2 / n - e.mean * e.mean) / n);
    return e;
}

/* Fails unless scenes a and b (named name_a, name_b in messages), path traced
 * to depth 2 with n paths per point from eye, agree at every point and a sees
 * light at each. */
static inline void tp_pt_agree(const tb_scene *a, const char *name_a, const tb_scene *b, const char *name_b,
                               tb_vec3 eye, const tb_vec3 *pts, int npts, long n, uint64_t seed)
{
    tb_pt_options po = {0};
    po.max_depth = 2;
    tb_pathtracer *pa = NULL, *pb = NULL;
    assert_int_equal(tb_pt_create(a, &po, &pa), TB_OK);
    assert_int_equal(tb_pt_create(b, &po, &pb), TB_OK);
    for (int k = 0; k < npts; k++) {
        tp_est ea = tp_pt_estimate(pa, eye, pts[k], n, seed + 2 * (uint64_t)k);
        tp_est eb = tp_pt_estimate(pb, eye, pts[k], n, seed + 2 * (uint64_t)k + 1);
        double bound = 4.0 * sqrt(ea.se * ea.se + eb.se * eb.se);
        printf("[ pt       ] point %d: %s %.5f +- %.5f, %s %.5f +- %.5f\n", k, name_a, ea.mean, ea.se, name_b, eb.mean,
               eb.se);
        if (!(fabs(ea.mean - eb.mean) <= bound))
            fail_msg("point %d: %s %.6g, %s %.6g, differ by more than %.3g (4 sigma)", k, name_a, ea.mean, name_b,
                     eb.mean, bound);
        assert_true(ea.mean > 0.0);
    }
    tb_pt_free(pa);
    tb_pt_free(pb);
}

#endif
