/* The torus (a quartic solved in double from an origin moved next to the
 * torus, roots polished by Newton): hits against an independent long double
 * reference, which finds the first root of the signed distance along the
 * line by dense sampling and bisection (no polynomial at all).
 *
 * Cases, each for tori of size ~1 (thin, default, fat), 1e-6 and 1e6 (given
 * by the parameters or by a transform):
 *  - rays from 10^4 sizes away aimed at random surface points;
 *  - grazing rays: tangent lines moved in or out by 1e-7 .. 1e-3 of the tube;
 *  - rays along the axis (through the hole: miss), parallel to it through the
 *    tube (analytic t), and through the centre just steeper / shallower than
 *    the tube's silhouette (miss / hit);
 * checking hit or miss, t within 1 float ulp of the reference where the
 * reference is well conditioned, and every hit point of tb_object_hit_point
 * within its error bound of the surface. */
#include "test_isect_common.h"

#include <float.h>

#include "host/object/hit.h"
#include "host/object/intersect.h"
#include "host/object/intersect_internal.h"

typedef long double ld;

typedef struct ti_torus_case {
    const char *name;
    double R, r;  /* geometry */
    double scale; /* uniform scale of the transform */
    bool rotate;  /* and a random rotation */
} ti_torus_case;

typedef struct ti_tstats {
    long rays, compared, mism, ulp_fail, dist_fail, amb;
    double worst_ulps, worst_dist;
} ti_tstats;

static ld ti_sdist(ld R, ld r, const ld p[3])
{
    ld q = sqrtl(p[0] * p[0] + p[1] * p[1]) - R;
    return sqrtl(q * q + p[2] * p[2]) - r;
}

/* Looks for a point of [t0, t1] with f <= 0 (f0, f1 > 0 at the ends), by
 * splitting where the 1-Lipschitz bound (f changes by at most |p - q|)
 * cannot rule one out. 1: found (the first such sample in *tn, the sample
 * before it in *tp); 0: none; -1: undecided at the depth limit. */
static int ti_seek(ld R, ld r, const ld o[3], const ld d[3], ld dl, ld t0, ld f0, ld t1, ld f1, int depth, ld *tp,
                   ld *tn)
{
    if (f0 + f1 >= (t1 - t0) * dl)
        return 0;
    if (depth == 0)
        return -1;
    enum { K = 8 };
    ld pt = t0, pf = f0;
    int undecided = 0;
    for (int i = 1; i <= K; i++) {
        ld t = i == K ? t1 : t0 + (t1 - t0) * i / K;
        ld q[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
        ld f = i == K ? f1 : ti_sdist(R, r, q);
        if (f <= 0) {
            *tp = pt;
            *tn = t;
            return 1;
        }
        int s = ti_seek(R, r, o, d, dl, pt, pf, t, f, depth - 1, tp, tn);
        if (s == 1)
            return 1;
        if (s < 0)
            undecided = 1;
        pt = t;
        pf = f;
    }
    return undecided ? -1 : 0;
}

/* First root t >= 0 of the signed distance along o + t d (object space),
 * inside the bounding sphere. Returns 1 hit, 0 miss, -1 ambiguous (a chord
 * too short for the sampling, or a root near tangency). */
static int ti_ref(ld R, ld r, const ld o[3], const ld d[3], ld *t_out)
{
    ld dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    ld tc = -(o[0] * d[0] + o[1] * d[1] + o[2] * d[2]) / dd;
    ld c[3] = {o[0] + tc * d[0], o[1] + tc * d[1], o[2] + tc * d[2]};
    ld S = R + r, h2 = S * S - (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    if (h2 <= 0)
        return 0;
    ld h = sqrtl(h2 / dd) * 1.001L;
    ld a = tc - h, b = tc + h;
    if (b < 0)
        return 0;
    if (a < 0)
        a = 0;
    enum { N = 150 };
    ld step = (b - a) / N, prev_t = a, prev_f;
    ld p[3] = {o[0] + a * d[0], o[1] + a * d[1], o[2] + a * d[2]};
    prev_f = ti_sdist(R, r, p);
    if (prev_f <= 0)
        return -1; /* starts inside: not a case generated here */
    ld dl = sqrtl(dd);
    for (int i = 1; i <= N; i++) {
        ld t = a + step * i;
        ld q[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
        ld f = ti_sdist(R, r, q), lo = prev_t, hi = t;
        int s = f <= 0 ? 1 : ti_seek(R, r, o, d, dl, prev_t, prev_f, t, f, 10, &lo, &hi);
        if (s < 0)
            return -1; /* a chord thinner than the search could resolve */
        if (s == 1) {
            for (int k = 0; k < 200; k++) {
                ld m = 0.5L * (lo + hi);
                if (m == lo || m == hi)
                    break;
                ld pm[3] = {o[0] + m * d[0], o[1] + m * d[1], o[2] + m * d[2]};
                if (ti_sdist(R, r, pm) <= 0)
                    hi = m;
                else
                    lo = m;
            }
            *t_out = hi;
            /* The cosine between the line and the surface normal there: an
             * almost tangent entry makes t ill-conditioned (not compared). */
            ld ph[3] = {o[0] + hi * d[0], o[1] + hi * d[1], o[2] + hi * d[2]};
            ld rho = sqrtl(ph[0] * ph[0] + ph[1] * ph[1]);
            ld nv[3] = {ph[0] - R * ph[0] / rho, ph[1] - R * ph[1] / rho, ph[2]};
            ld nl = sqrtl(nv[0] * nv[0] + nv[1] * nv[1] + nv[2] * nv[2]);
            ld c = fabsl(nv[0] * d[0] + nv[1] * d[1] + nv[2] * d[2]) / (nl * dl);
            return c < 1e-4L ? -1 : 1;
        }
        prev_t = t;
        prev_f = f;
    }
    return 0;
}

static double ti_ulp(float x)
{
    float a = fabsf(x);
    return (double)nextafterf(a, INFINITY) - (double)a;
}

/* Checks one ray; `expect` is 1 (must hit), 0 (must miss) or -1 (ask the
 * reference); `t_exact` >= 0 replaces the reference t. */
static void ti_check(const tb_object *o, double scale, tb_ray ray, int expect, ld t_exact, ti_tstats *S)
{
    const tb_mat4 *mi = &o->to_world.inv;
    ld ol[3], dl[3];
    for (int i = 0; i < 3; i++) {
        ol[i] = (ld)mi->m[i][0] * ray.o.x + (ld)mi->m[i][1] * ray.o.y + (ld)mi->m[i][2] * ray.o.z + (ld)mi->m[i][3];
        dl[i] = (ld)mi->m[i][0] * ray.d.x + (ld)mi->m[i][1] * ray.d.y + (ld)mi->m[i][2] * ray.d.z;
    }
    ld R = o->geom.torus.major, r = o->geom.torus.minor, tr = -1, tref = -1;
    int rr = ti_ref(R, r, ol, dl, &tr);
    int ref = expect;
    if (expect < 0) { /* the reference decides, unless it cannot */
        if (rr < 0) {
            S->amb++;
            return;
        }
        ref = rr;
    }
    if (t_exact >= 0)
        tref = t_exact;
    else if (rr == 1 && ref == 1)
        tref = tr;
    tb_hit h;
    bool hit = tb_object_intersect(o, &ray, &h);
    S->rays++;
    if (hit != (ref == 1)) {
        if (S->mism++ < 3)
            print_message("torus R=%g r=%g: library %s, expected %s\n", (double)R, (double)r, hit ? "hits" : "misses",
                          ref == 1 ? "a hit" : "a miss");
        return;
    }
    if (!hit)
        return;
    tb_vec3 p, perr;
    assert_true(tb_object_hit_point(o, &ray, &h, &p, &perr));
    ld pl[3];
    for (int i = 0; i < 3; i++)
        pl[i] = (ld)mi->m[i][0] * p.x + (ld)mi->m[i][1] * p.y + (ld)mi->m[i][2] * p.z + (ld)mi->m[i][3];
    double dist = (double)(fabsl(ti_sdist(R, r, pl)) * (ld)scale);
    double bound = sqrt((double)perr.x * perr.x + (double)perr.y * perr.y + (double)perr.z * perr.z);
    S->worst_dist = fmax(S->worst_dist, dist / bound);
    if (!(dist <= bound) && S->dist_fail++ < 3)
        print_message("torus R=%g r=%g: hit point %g from the surface, bound %g\n", (double)R, (double)r, dist, bound);
    if (tref < 0)
        return;
    S->compared++;
    double ulps = fabs((double)((ld)h.t - tref)) / ti_ulp((float)tref);
    S->worst_ulps = fmax(S->worst_ulps, ulps);
    if (ulps > 1.0 && S->ulp_fail++ < 3)
        print_message("torus R=%g r=%g: t = %.9g, reference %.12Lg (%.2f ulps)\n", (double)R, (double)r, h.t, tref,
                      ulps);
}

static tb_ray ti_world_ray(const tb_object *o, tb_dvec3 a, tb_dvec3 b)
{
    tb_dvec3 aw = tb_transform_dpoint(&o->to_world, a), bw = tb_transform_dpoint(&o->to_world, b);
    tb_vec3 of = {(float)aw.x, (float)aw.y, (float)aw.z};
    tb_vec3 df = {(float)(bw.x - of.x), (float)(bw.y - of.y), (float)(bw.z - of.z)};
    return tb_ray_make(of, df, 0.0f, INFINITY);
}

/* Surface point at angles (u around z, v around the tube) and its normal. */
static void ti_torus_point(double R, double r, double u, double v, tb_dvec3 *p, tb_dvec3 *n)
{
    *n = (tb_dvec3){cos(v) * cos(u), cos(v) * sin(u), sin(v)};
    *p = (tb_dvec3){(R + r * cos(v)) * cos(u), (R + r * cos(v)) * sin(u), r * sin(v)};
}

static void ti_torus_case_run(const ti_torus_case *c, uint64_t seed, long n)
{
    tb_rng rng;
    tb_rng_seed(&rng, seed, (uint64_t)(c->name[0] * 131 + c->name[1] * 7 + c->name[2]));
    tb_transform xf = tb_transform_identity();
    if (c->scale != 1.0 || c->rotate) {
        tb_transform S, Rt;
        assert_int_equal(tb_transform_scale((tb_dvec3){c->scale, c->scale, c->scale}, &S), TB_OK);
        assert_int_equal(tb_transform_rotate(ti_uniform(&rng, 0, 2 * TI_PI), ti_sphere_dir(&rng), &Rt), TB_OK);
        xf = tb_transform_compose(&Rt, &S);
    }
    tb_mid_geometry g = tb_mid_geometry_default(TB_PRIM_TORUS);
    g.torus.major = c->R;
    g.torus.minor = c->r;
    tb_mid_object m = ti_prim(TB_PRIM_TORUS, g, xf);
    tb_object *o = ti_build(&m, 0);
    double R = c->R, r = c->r, S = R + r;
    ti_tstats st = {0};
    for (long i = 0; i < n; i++) {
        int mode = (int)(i % 6);
        tb_dvec3 p, nn;
        if (mode <= 1) { /* from 10^4 sizes away toward a surface point */
            ti_torus_point(R, r, ti_uniform(&rng, 0, 2 * TI_PI), ti_uniform(&rng, 0, 2 * TI_PI), &p, &nn);
            tb_dvec3 u = ti_sphere_dir(&rng);
            tb_dvec3 a = tb_dvec3_add(p, tb_dvec3_scale(u, 1e4 * S));
            ti_check(o, c->scale, ti_world_ray(o, a, p), -1, -1, &st); /* the float ray may pass by p: ask the reference */
        } else if (mode <= 3) { /* grazing on the outer (convex) half: in and out by 1e-7 .. 1e-3 of r */
            double v = ti_uniform(&rng, -1.2, 1.2);
            ti_torus_point(R, r, ti_uniform(&rng, 0, 2 * TI_PI), v, &p, &nn);
            tb_vec3 b1, b2;
            tb_vec3_basis((tb_vec3){(float)nn.x, (float)nn.y, (float)nn.z}, &b1, &b2);
            double ang = ti_uniform(&rng, 0, 2 * TI_PI);
            tb_dvec3 t = {cos(ang) * b1.x + sin(ang) * b2.x, cos(ang) * b1.y + sin(ang) * b2.y,
                          cos(ang) * b1.z + sin(ang) * b2.z};
            t = tb_dvec3_normalize(tb_dvec3_sub(t, tb_dvec3_scale(nn, tb_dvec3_dot(t, nn))));
            double eps = pow(10.0, ti_uniform(&rng, -7, -3)) * r;
            bool in = mode == 2; /* in: a chord of length ~sqrt(eps r); the reference decides, on the float ray */
            tb_dvec3 b = tb_dvec3_add(p, tb_dvec3_scale(nn, in ? -eps : eps));
            tb_dvec3 a = tb_dvec3_sub(b, tb_dvec3_scale(t, 3 * S));
            ti_check(o, c->scale, ti_world_ray(o, a, b), -1, -1, &st);
        } else if (mode == 4) { /* parallel to the axis: down the hole, or through the tube */
            double phi = ti_uniform(&rng, 0, 2 * TI_PI);
            if (tb_rng_below(&rng, 4) == 0) {
                double rho = ti_uniform(&rng, 0, 0.999 * (R - r));
                tb_dvec3 a = {rho * cos(phi), rho * sin(phi), 1e4 * S}, b = {a.x, a.y, 0};
                ti_check(o, c->scale, ti_world_ray(o, a, b), 0, -1, &st);
            } else {
                double q = ti_uniform(&rng, -0.99, 0.99) * r, rho = R + q;
                tb_dvec3 a = {rho * cos(phi), rho * sin(phi), 4 * S}, b = {a.x, a.y, 0};
                tb_ray ray = ti_world_ray(o, a, b);
                /* The line is a + t (b - a) in object space up to the rounding
                 * of the float ray: take t from the long double object ray. */
                const tb_mat4 *mi = &o->to_world.inv;
                ld ol[3], dl[3];
                for (int k = 0; k < 3; k++) {
                    ol[k] = (ld)mi->m[k][0] * ray.o.x + (ld)mi->m[k][1] * ray.o.y + (ld)mi->m[k][2] * ray.o.z +
                            (ld)mi->m[k][3];
                    dl[k] = (ld)mi->m[k][0] * ray.d.x + (ld)mi->m[k][1] * ray.d.y + (ld)mi->m[k][2] * ray.d.z;
                }
                /* Solve for the top of the tube along the (slightly tilted) float line by bisection
                 * started from the analytic height. */
                ld zt = sqrtl((ld)r * r - (ld)q * q), tt = (ol[2] - zt) / -dl[2];
                for (int it = 0; it < 3; it++) { /* Newton on the distance along the line */
                    ld pp[3] = {ol[0] + tt * dl[0], ol[1] + tt * dl[1], ol[2] + tt * dl[2]};
                    ld f = ti_sdist(R, r, pp), rho2 = sqrtl(pp[0] * pp[0] + pp[1] * pp[1]);
                    ld gq = rho2 - R, gl = sqrtl(gq * gq + pp[2] * pp[2]);
                    ld df = (gq / gl) * (pp[0] * dl[0] + pp[1] * dl[1]) / rho2 + pp[2] / gl * dl[2];
                    tt -= f / df;
                }
                ti_check(o, c->scale, ray, 1, fabsl(q) < 0.9L * r ? tt : -1, &st);
            }
        } else { /* through the centre, just steeper (miss) or shallower (hit) than the tube */
            double a0 = asin(r / R), phi = ti_uniform(&rng, 0, 2 * TI_PI);
            bool steep = tb_rng_below(&rng, 2);
            double el = a0 * (steep ? 1.01 : 0.99) * (tb_rng_below(&rng, 2) ? 1 : -1);
            tb_dvec3 dir = {cos(el) * cos(phi), cos(el) * sin(phi), sin(el)};
            tb_dvec3 a = tb_dvec3_scale(dir, -1e4 * S), b = {0, 0, 0};
            ti_check(o, c->scale, ti_world_ray(o, a, b), steep ? 0 : 1, -1, &st);
        }
    }
    print_message("[ %-12s ] %ld rays (%ld ambiguous for the reference): %ld t compared, worst %.2f ulp; hit points "
                  "within %.3f of their bound; %ld hit/miss errors\n",
                  c->name, st.rays, st.amb, st.compared, st.worst_ulps, st.worst_dist, st.mism);
    tb_object_free(o);
    assert_true(st.compared > n / 5);
    assert_int_equal(st.mism, 0);
    assert_int_equal(st.ulp_fail, 0);
    assert_int_equal(st.dist_fail, 0);
}

static void test_torus_hard_cases(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("torus", 4242);
    static const ti_torus_case cases[] = {
        {"default", 1.0, 0.25, 1.0, false},      {"thin", 3.0, 0.01, 1.0, true},
        {"fat", 1.0, 0.9, 1.0, true},            {"tiny-param", 1e-6, 2.5e-7, 1.0, false},
        {"huge-param", 1e6, 2.5e5, 1.0, false},  {"tiny-xform", 1.0, 0.25, 1e-6, true},
        {"huge-xform", 1.0, 0.25, 1e6, true},    {"rotated", 2.0, 0.5, 1.0, true},
    };
    long n = ti_count(4000, 600);
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
        ti_torus_case_run(&cases[i], seed, n);
}

/* The any-hit shortcut (tb__torus_clear: no quartic when Q is certainly
 * positive over the segment) against the full crossing list, ray by ray:
 * whenever it says "clear", tb__xings_torus must have no crossing with float
 * t in [tmin, tmax], and tb_object_occluded must agree with
 * tb_object_intersect. Shadow-like segments from hit points on the torus
 * (spawned as the ray tracer does: the origin ~1e-7 off the surface) toward
 * random targets, some past the far side of the tube, some grazing, on the
 * hard-case shapes and transforms above; the shortcut must decide a good
 * share of them (else the test would not test it). */
static void test_torus_any_hit_shortcut(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("torus_any", 4243), 3);
    static const double shapes[][3] = {{1.0, 0.25, 1.0}, {1.0, 0.9, 1.0}, {3.0, 0.01, 1.0}, {2.0, 0.5, 1e-3},
                                       {0.8, 0.25, 1e4}};
    long n = ti_count(20000, 2000), cleared = 0, total = 0;
    for (size_t c = 0; c < sizeof shapes / sizeof shapes[0]; c++) {
        tb_transform S, Rt;
        assert_int_equal(tb_transform_scale((tb_dvec3){shapes[c][2], shapes[c][2], shapes[c][2]}, &S), TB_OK);
        assert_int_equal(tb_transform_rotate(ti_uniform(&rng, 0, 2 * TI_PI), ti_sphere_dir(&rng), &Rt), TB_OK);
        tb_transform xf = tb_transform_compose(&Rt, &S);
        tb_mid_geometry g = tb_mid_geometry_default(TB_PRIM_TORUS);
        g.torus.major = shapes[c][0];
        g.torus.minor = shapes[c][1];
        tb_mid_object m = ti_prim(TB_PRIM_TORUS, g, xf);
        tb_object *o = ti_build(&m, 0);
        const double B = g.torus.major + g.torus.minor;
        for (long i = 0; i < n; i++) {
            tb_dvec3 a = ti_sphere_dir(&rng), b = ti_sphere_dir(&rng);
            tb_ray ray = ti_world_ray(o, tb_dvec3_scale(a, 3.0 * B), tb_dvec3_scale(b, 0.5 * B));
            tb_hit h;
            tb_vec3 p, perr;
            if (!tb_object_intersect(o, &ray, &h) || !tb_object_hit_point(o, &ray, &h, &p, &perr))
                continue;
            /* target: a random point out to 4 B, or (1 in 4) just past the tube's far side */
            tb_dvec3 q = i % 4 == 0 ? tb_dvec3_scale(ti_sphere_dir(&rng), B * ti_uniform(&rng, 0.0, 1.2))
                                    : tb_dvec3_scale(ti_sphere_dir(&rng), B * ti_uniform(&rng, 0.5, 4.0));
            tb_dvec3 qw = tb_transform_dpoint(&o->to_world, q);
            tb_vec3 tq = {(float)qw.x, (float)qw.y, (float)qw.z};
            tb_vec3 w = tb_vec3_sub(tq, p);
            tb_ray sh;
            sh.o = tb_spawn_ray_origin(p, perr, h.ng, w);
            sh.d = tb_vec3_sub(tq, sh.o);
            sh.tmin = 0.0f;
            sh.tmax = i % 3 == 0 ? INFINITY : 1.0f - 1e-4f;
            if (!tb_ray_is_valid(&sh))
                continue;
            total++;
            tb__oray orr = tb__object_ray(o, &sh);
            tb__xbuf xb;
            tb__xbuf_init(&xb);
            tb__xings_torus(o, &orr, &xb);
            bool any = false;
            for (int k = 0; k < xb.n; k++)
                any = any || ((float)xb.x[k].t >= sh.tmin && (float)xb.x[k].t <= sh.tmax);
            tb__xbuf_free(&xb);
            bool clear = tb__torus_clear(o, &orr, sh.tmin, sh.tmax);
            cleared += clear;
            if (clear && any)
                fail_msg("shape %zu ray %ld: the shortcut says clear, but a crossing lies in [0, %a]", c, i,
                         (double)sh.tmax);
            tb_hit h2;
            if (tb_object_occluded(o, &sh) != tb_object_intersect(o, &sh, &h2))
                fail_msg("shape %zu ray %ld: occluded and intersect disagree", c, i);
        }
        tb_object_free(o);
    }
    print_message("[ torus any ] %ld shadow segments, %ld cleared without the quartic\n", total, cleared);
    assert_true(total > n && cleared > total / 4);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_torus_hard_cases),
        cmocka_unit_test(test_torus_any_hit_shortcut),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
