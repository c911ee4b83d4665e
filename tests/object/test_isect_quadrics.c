/* Stable quadratics: hits on spheres, cylinders, cones and conics against a
 * long double reference (the textbook formula without any origin shift, 11
 * more bits than double, each root then refined by Newton in long double).
 *
 *  - well-conditioned hits (|cos| between ray and normal > 1e-3) from near and
 *    from 10^4 object sizes away: the float t within 1 ulp of the reference;
 *  - grazing rays (tangent lines moved in or out by 1e-3 .. 1e-7 of the size):
 *    hit or miss as the reference says, and the hit point of
 *    tb_object_hit_point within its error bound of the surface (distance in
 *    long double);
 *  - the same with the textbook formula evaluated in float, to show what the
 *    test catches: it loses most digits from afar (printed, not asserted).
 * Transforms are rotations with uniform scales from 1e-3 to 1e3 and
 * translations, so world distances are object distances times the scale. */
#include "test_isect_common.h"

#include <float.h>

#include "host/object/hit.h"
#include "host/object/intersect.h"
#include "host/object/param.h"

typedef long double ld;

/* A quadric of revolution x^2 + y^2 = c0 + c1 z + c2 z^2 on [z0, z1], written
 * from docs/mid.md for each kind (independently of the library). */
typedef struct ti_rev {
    ld c[3];
    ld z0, z1;
    bool caps;
} ti_rev;

static ti_rev ti_rev_of(tb_prim_kind k, const tb_mid_geometry *g)
{
    ti_rev q = {{1, 0, -1}, -1, 1, false}; /* the sphere */
    if (k == TB_PRIM_CYLINDER) {
        q = (ti_rev){{1, 0, 0}, -1, 1, g->cylinder.caps};
    } else if (k == TB_PRIM_CONE) { /* r = 1 at z = -1, rt at z = 1 */
        ld rt = g->cone.top_radius, a = (1 + rt) / 2, b = (rt - 1) / 2;
        q = (ti_rev){{a * a, 2 * a * b, b * b}, -1, 1, g->cone.caps};
    } else if (k == TB_PRIM_CONIC) {
        q = (ti_rev){{g->conic.c[0], g->conic.c[1], g->conic.c[2]}, g->conic.z0, g->conic.z1, g->conic.caps};
    }
    return q;
}

static ld ti_r2(const ti_rev *q, ld z) { return q->c[0] + q->c[1] * z + q->c[2] * z * z; }

typedef struct ti_ldray {
    ld o[3], d[3];
} ti_ldray;

/* The world ray in object space, in long double (same double matrix). */
static ti_ldray ti_ld_object_ray(const tb_object *obj, const tb_ray *r)
{
    const tb_mat4 *m = &obj->to_world.inv;
    ld o[3] = {r->o.x, r->o.y, r->o.z}, d[3] = {r->d.x, r->d.y, r->d.z};
    ti_ldray q;
    for (int i = 0; i < 3; i++) {
        q.o[i] = (ld)m->m[i][3];
        q.d[i] = 0;
        for (int j = 0; j < 3; j++) {
            q.o[i] += (ld)m->m[i][j] * o[j];
            q.d[i] += (ld)m->m[i][j] * d[j];
        }
    }
    return q;
}

/* Reference first hit with t >= 0; returns false on a miss. *ambiguous is
 * set when the answer sits within 1e-9 of a rim or of tangency. */
static bool ti_ref_hit(const ti_rev *q, bool sphere, const ti_ldray *r, ld *t_out, bool *ambiguous)
{
    const ld *o = r->o, *d = r->d;
    ld A = d[0] * d[0] + d[1] * d[1] - q->c[2] * d[2] * d[2];
    ld B = 2 * (o[0] * d[0] + o[1] * d[1]) - q->c[1] * d[2] - 2 * q->c[2] * o[2] * d[2];
    ld C = o[0] * o[0] + o[1] * o[1] - q->c[0] - q->c[1] * o[2] - q->c[2] * o[2] * o[2];
    ld cand[4];
    int nc = 0;
    *ambiguous = false;
    ld disc = B * B - 4 * A * C;
    ld scale = fabsl(B * B) + fabsl(4 * A * C);
    if (fabsl(disc) < 1e-9L * scale)
        *ambiguous = true;
    if (disc >= 0 && A != 0) {
        ld s = sqrtl(disc);
        ld roots[2] = {(-B - s) / (2 * A), (-B + s) / (2 * A)};
        for (int i = 0; i < 2; i++) {
            ld t = roots[i];
            for (int it = 0; it < 4; it++) { /* Newton on the quadratic */
                ld f = (A * t + B) * t + C, df = 2 * A * t + B;
                if (df == 0)
                    break;
                t -= f / df;
            }
            ld z = o[2] + t * d[2];
            if (!sphere && (fabsl(z - q->z0) < 1e-9L || fabsl(z - q->z1) < 1e-9L))
                *ambiguous = true;
            if (sphere || (z >= q->z0 && z <= q->z1))
                cand[nc++] = t;
        }
    }
    if (!sphere && q->caps && d[2] != 0) {
        ld zc[2] = {q->z0, q->z1};
        for (int i = 0; i < 2; i++) {
            ld t = (zc[i] - o[2]) / d[2];
            ld x = o[0] + t * d[0], y = o[1] + t * d[1], rr = ti_r2(q, zc[i]);
            if (fabsl(x * x + y * y - rr) < 1e-9L * (1 + rr))
                *ambiguous = true;
            if (x * x + y * y <= rr && rr > 0)
                cand[nc++] = t;
        }
    }
    bool found = false;
    for (int i = 0; i < nc; i++)
        if (cand[i] >= 0 && (!found || cand[i] < *t_out)) {
            *t_out = cand[i];
            found = true;
        }
    return found;
}

/* Object-space distance (first order) of p from the surface of the face. */
static ld ti_surface_dist(const ti_rev *q, bool sphere, int face, const ld p[3])
{
    if (sphere)
        return fabsl(sqrtl(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - 1);
    if (face != 0)
        return fabsl(p[2] - (face == 1 ? q->z0 : q->z1));
    ld Q = p[0] * p[0] + p[1] * p[1] - ti_r2(q, p[2]);
    ld gz = q->c[1] + 2 * q->c[2] * p[2];
    ld g = sqrtl(4 * (p[0] * p[0] + p[1] * p[1]) + gz * gz);
    return g > 0 ? fabsl(Q) / g : sqrtl(fabsl(Q));
}

/* A rotation, uniform scale 10^[-3, 3] and translation. */
static tb_transform ti_similarity(tb_rng *r, double *scale)
{
    double s = pow(10.0, ti_uniform(r, -3.0, 3.0));
    tb_transform S, R;
    assert_int_equal(tb_transform_scale((tb_dvec3){s, s, s}, &S), TB_OK);
    assert_int_equal(tb_transform_rotate(ti_uniform(r, 0, 2 * TI_PI), ti_sphere_dir(r), &R), TB_OK);
    tb_transform T = tb_transform_translate(
        (tb_dvec3){s * ti_uniform(r, -20, 20), s * ti_uniform(r, -20, 20), s * ti_uniform(r, -20, 20)});
    tb_transform RS = tb_transform_compose(&R, &S);
    *scale = s;
    return tb_transform_compose(&T, &RS);
}

/* Float ulp of x. */
static double ti_ulp(float x)
{
    float a = fabsf(x);
    return (double)nextafterf(a, INFINITY) - (double)a;
}

typedef struct ti_stats {
    long rays, compared, grazing, mismatches, ulp_fail, dist_fail;
    double worst_ulps, worst_dist; /* worst |t - ref| in ulps; worst distance / bound */
} ti_stats;

static void ti_check_ray(const tb_object *o, const ti_rev *q, bool sphere, double scale, tb_ray ray, bool grazing,
                         ti_stats *S)
{
    ti_ldray lr = ti_ld_object_ray(o, &ray);
    ld tref = 0;
    bool amb;
    bool rhit = ti_ref_hit(q, sphere, &lr, &tref, &amb);
    tb_hit h;
    bool hit = tb_object_intersect(o, &ray, &h);
    S->rays++;
    if (amb)
        return;
    if (hit != rhit) {
        if (S->mismatches++ < 3)
            print_message("%s: library %s, reference %s (t = %Lg)\n", tb_prim_kind_name(o->kind), hit ? "hits" : "misses",
                          rhit ? "hits" : "misses", tref);
        return;
    }
    if (!hit)
        return;
    /* The hit point: within its bound of the surface (world = scale * object distance). */
    tb_vec3 p, perr;
    assert_true(tb_object_hit_point(o, &ray, &h, &p, &perr));
    const tb_mat4 *mi = &o->to_world.inv;
    ld pl[3];
    for (int i = 0; i < 3; i++)
        pl[i] = (ld)mi->m[i][0] * p.x + (ld)mi->m[i][1] * p.y + (ld)mi->m[i][2] * p.z + (ld)mi->m[i][3];
    uint32_t face = h.face;
    double dist = (double)(ti_surface_dist(q, sphere, (int)face, pl) * (ld)scale);
    double bound = sqrt((double)perr.x * perr.x + (double)perr.y * perr.y + (double)perr.z * perr.z);
    S->worst_dist = fmax(S->worst_dist, dist / bound);
    if (!(dist <= bound) && S->dist_fail++ < 3)
        print_message("%s: hit point %g from the surface, bound %g\n", tb_prim_kind_name(o->kind), dist, bound);
    if (grazing) {
        S->grazing++;
        return;
    }
    /* Well-conditioned: t to 1 ulp. */
    ld dl = sqrtl(lr.d[0] * lr.d[0] + lr.d[1] * lr.d[1] + lr.d[2] * lr.d[2]);
    ld pt[3] = {lr.o[0] + tref * lr.d[0], lr.o[1] + tref * lr.d[1], lr.o[2] + tref * lr.d[2]};
    tb_dvec3 nobj = {0, 0, 0};
    if (sphere || face == 0) {
        ld gz = sphere ? -2 * pt[2] : q->c[1] + 2 * q->c[2] * pt[2];
        nobj = (tb_dvec3){(double)pt[0], (double)pt[1], (double)(-gz / 2)};
    } else {
        nobj.z = 1.0;
    }
    double cosang = fabs((double)(nobj.x * lr.d[0] + nobj.y * lr.d[1] + nobj.z * lr.d[2])) /
                    (tb_dvec3_length(nobj) * (double)dl);
    if (cosang < 1e-3)
        return;
    S->compared++;
    double ulps = fabs((double)((ld)h.t - tref)) / ti_ulp((float)tref);
    S->worst_ulps = fmax(S->worst_ulps, ulps);
    if (ulps > 1.0 && S->ulp_fail++ < 3)
        print_message("%s: t = %.9g, reference %.12Lg: %.2f ulps\n", tb_prim_kind_name(o->kind), h.t, tref, ulps);
}

/* A point on the surface (object space) of the quadric's side, and its normal. */
static void ti_side_point(tb_rng *r, const ti_rev *q, bool sphere, tb_dvec3 *p, tb_dvec3 *n)
{
    for (;;) {
        double z = sphere ? ti_uniform(r, -1, 1) : ti_uniform(r, (double)q->z0, (double)q->z1);
        double r2 = sphere ? 1 - z * z : (double)ti_r2(q, z);
        if (r2 <= 1e-6)
            continue;
        double rho = sqrt(r2), phi = ti_uniform(r, 0, 2 * TI_PI);
        *p = (tb_dvec3){rho * cos(phi), rho * sin(phi), z};
        double gz = sphere ? -2 * z : (double)(q->c[1] + 2 * q->c[2] * z);
        *n = tb_dvec3_normalize((tb_dvec3){p->x, p->y, -gz / 2});
        return;
    }
}

static void ti_run_kind(const char *name, tb_prim_kind k, tb_mid_geometry g, uint64_t seed, long nrays)
{
    tb_rng r;
    tb_rng_seed(&r, seed, (uint64_t)k * 7 + 1);
    ti_rev q = ti_rev_of(k, &g);
    bool sphere = k == TB_PRIM_SPHERE;
    ti_stats S = {0};
    enum { NOBJ = 6 };
    tb_object *objs[NOBJ];
    double scales[NOBJ];
    for (int i = 0; i < NOBJ; i++) {
        tb_transform xf = tb_transform_identity();
        scales[i] = 1.0;
        if (i > 0)
            xf = ti_similarity(&r, &scales[i]);
        tb_mid_object m = ti_prim(k, g, xf);
        objs[i] = ti_build(&m, 0);
    }
    for (long i = 0; i < nrays; i++) {
        int oi = (int)(i % NOBJ);
        const tb_object *o = objs[oi];
        int mode = (int)tb_rng_below(&r, 3);
        tb_dvec3 a, b; /* object-space origin and a point on the line */
        bool grazing = false;
        if (mode < 2) {
            /* Toward a random point near the object, from 3 or 10^4 sizes away. */
            b = (tb_dvec3){ti_uniform(&r, -1.2, 1.2), ti_uniform(&r, -1.2, 1.2),
                           ti_uniform(&r, (double)q.z0 - 0.2, (double)q.z1 + 0.2)};
            tb_dvec3 u = ti_sphere_dir(&r);
            double dist = mode == 0 ? 3.0 : 1e4;
            a = (tb_dvec3){b.x + dist * u.x, b.y + dist * u.y, b.z + dist * u.z};
        } else {
            /* Grazing: a tangent line moved along the normal by +-10^[-7, -3]. */
            tb_dvec3 p, n;
            ti_side_point(&r, &q, sphere, &p, &n);
            tb_dvec3 t1, t2;
            tb_vec3 b1, b2;
            tb_vec3_basis((tb_vec3){(float)n.x, (float)n.y, (float)n.z}, &b1, &b2);
            t1 = (tb_dvec3){b1.x, b1.y, b1.z};
            t2 = (tb_dvec3){b2.x, b2.y, b2.z};
            double ang = ti_uniform(&r, 0, 2 * TI_PI);
            tb_dvec3 t = tb_dvec3_add(tb_dvec3_scale(t1, cos(ang)), tb_dvec3_scale(t2, sin(ang)));
            t = tb_dvec3_sub(t, tb_dvec3_scale(n, tb_dvec3_dot(t, n))); /* exactly tangent in double */
            t = tb_dvec3_normalize(t);
            double eps = pow(10.0, ti_uniform(&r, -7, -3)) * (tb_rng_below(&r, 2) ? 1 : -1);
            b = tb_dvec3_add(p, tb_dvec3_scale(n, eps));
            a = tb_dvec3_sub(b, tb_dvec3_scale(t, ti_uniform(&r, 3, 100)));
            grazing = true;
        }
        tb_dvec3 aw = tb_transform_dpoint(&o->to_world, a), bw = tb_transform_dpoint(&o->to_world, b);
        tb_vec3 of = {(float)aw.x, (float)aw.y, (float)aw.z};
        tb_vec3 df = {(float)(bw.x - of.x), (float)(bw.y - of.y), (float)(bw.z - of.z)};
        ti_check_ray(o, &q, sphere, scales[oi], tb_ray_make(of, df, 0.0f, INFINITY), grazing, &S);
    }
    print_message("[ %-10s ] %ld rays: %ld t compared (worst %.2f ulp), %ld grazing hits; hit points within %.6f of "
                  "their bound; %ld hit/miss disagreements\n",
                  name, S.rays, S.compared, S.worst_ulps, S.grazing, S.worst_dist, S.mismatches);
    for (int i = 0; i < NOBJ; i++)
        tb_object_free(objs[i]);
    assert_true(S.compared > nrays / 10);
    assert_int_equal(S.mismatches, 0);
    assert_int_equal(S.ulp_fail, 0);
    assert_int_equal(S.dist_fail, 0);
}

static void test_stable_quadratics(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("stable_quadratics", 31337);
    long n = ti_count(60000, 3000);
    tb_mid_geometry g;
    ti_run_kind("sphere", TB_PRIM_SPHERE, tb_mid_geometry_default(TB_PRIM_SPHERE), seed, n);
    ti_run_kind("cylinder", TB_PRIM_CYLINDER, tb_mid_geometry_default(TB_PRIM_CYLINDER), seed, n);
    ti_run_kind("cone", TB_PRIM_CONE, tb_mid_geometry_default(TB_PRIM_CONE), seed, n);
    g = tb_mid_geometry_default(TB_PRIM_CONE);
    g.cone.top_radius = 0.3;
    ti_run_kind("frustum", TB_PRIM_CONE, g, seed, n);
    ti_run_kind("conic-sph", TB_PRIM_CONIC, tb_mid_geometry_default(TB_PRIM_CONIC), seed, n);
    g = tb_mid_geometry_default(TB_PRIM_CONIC);
    g.conic.c[0] = 0.5, g.conic.c[1] = -0.5, g.conic.c[2] = 0.0; /* paraboloid */
    ti_run_kind("paraboloid", TB_PRIM_CONIC, g, seed, n);
    g = tb_mid_geometry_default(TB_PRIM_CONIC);
    g.conic.c[0] = 0.5, g.conic.c[1] = 0.0, g.conic.c[2] = 0.5; /* hyperboloid of one sheet */
    ti_run_kind("hyperb-1", TB_PRIM_CONIC, g, seed, n);
    g = tb_mid_geometry_default(TB_PRIM_CONIC);
    g.conic.c[0] = -0.25, g.conic.c[1] = 0.0, g.conic.c[2] = 1.0; /* two sheets, the upper one */
    g.conic.z0 = 0.5, g.conic.z1 = 1.5;
    ti_run_kind("hyperb-2", TB_PRIM_CONIC, g, seed, n);
}

/* What the test would see from the textbook float formula (informational). */
static void test_textbook_float_loses(void **state)
{
    (void)state;
    tb_rng r;
    tb_rng_seed(&r, 99, 1);
    double worst = 0.0;
    int missed = 0;
    for (int i = 0; i < 2000; i++) {
        tb_dvec3 b = {ti_uniform(&r, -0.5, 0.5), ti_uniform(&r, -0.5, 0.5), ti_uniform(&r, -0.5, 0.5)};
        tb_dvec3 u = ti_sphere_dir(&r);
        float o[3] = {(float)(b.x + 1e4 * u.x), (float)(b.y + 1e4 * u.y), (float)(b.z + 1e4 * u.z)};
        float d[3] = {(float)b.x - o[0], (float)b.y - o[1], (float)b.z - o[2]};
        float A = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], B = 2 * (o[0] * d[0] + o[1] * d[1] + o[2] * d[2]),
              C = o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - 1.0f;
        float disc = B * B - 4 * A * C;
        float tf = disc >= 0 ? (-B - sqrtf(disc)) / (2 * A) : NAN;
        ti_ldray lr = {{o[0], o[1], o[2]}, {d[0], d[1], d[2]}};
        ti_rev q = {{1, 0, -1}, -1, 1, false};
        ld tref;
        bool amb;
        if (!ti_ref_hit(&q, true, &lr, &tref, &amb) || amb)
            continue;
        if (isnan(tf)) {
            missed++;
            continue;
        }
        worst = fmax(worst, fabs((double)((ld)tf - tref)) / ti_ulp((float)tref));
    }
    print_message("textbook float formula from 1e4 away: %d of the hits missed, worst t error of the others %.3g "
                  "ulps (the library: <= 1)\n",
                  missed, worst);
    assert_true(worst > 1.0 || missed > 0); /* the reference can tell a poor solver from a good one */
}

/* Ends of a revolved solid where the radius is zero close in a point (the
 * object's zclosed flags, set once at build): a line entering there meets
 * the side, not a cap. Down the axis of a pointed cone, of the dome
 * paraboloid r^2 = 0.5 - 0.5 z (apex z = 1) and of the double cone
 * r^2 = z^2 (apex z = 0 inside, r = 1 at both ends: caps); and a cylinder,
 * whose ends are caps. */
static void test_apex_is_side(void **state)
{
    (void)state;
    tb_transform id = tb_transform_identity();
    tb_ray down = tb_ray_make((tb_vec3){0, 0, 5}, (tb_vec3){0, 0, -1}, 0.0f, INFINITY);
    tb_hit h;

    tb_mid_geometry gc = tb_mid_geometry_default(TB_PRIM_CONE);
    gc.cone.top_radius = 0.0;
    tb_mid_object m = ti_prim(TB_PRIM_CONE, gc, id);
    tb_object *o = ti_build(&m, 0);
    assert_true(o->zclosed[1] && !o->zclosed[0]);
    assert_true(tb_object_intersect(o, &down, &h));
    tb_assert_near(h.t, 4.0, 1e-9);
    assert_int_equal(h.face, TB_FACE_CONE_SIDE);
    tb_ray up = tb_ray_make((tb_vec3){0, 0, -5}, (tb_vec3){0, 0, 1}, 0.0f, INFINITY);
    assert_true(tb_object_intersect(o, &up, &h));
    assert_int_equal(h.face, TB_FACE_CONE_BOTTOM);
    tb_object_free(o);

    tb_mid_geometry gd = tb_mid_geometry_default(TB_PRIM_CONIC);
    gd.conic.c[0] = 0.5;
    gd.conic.c[1] = -0.5;
    gd.conic.c[2] = 0.0;
    m = ti_prim(TB_PRIM_CONIC, gd, id);
    o = ti_build(&m, 0);
    assert_true(o->zclosed[1] && !o->zclosed[0]);
    assert_true(tb_object_intersect(o, &down, &h));
    tb_assert_near(h.t, 4.0, 1e-9);
    assert_int_equal(h.face, TB_FACE_CONIC_SIDE);
    tb_object_free(o);

    gd.conic.c[0] = 0.0;
    gd.conic.c[1] = 0.0;
    gd.conic.c[2] = 1.0;
    m = ti_prim(TB_PRIM_CONIC, gd, id);
    o = ti_build(&m, 0);
    assert_true(!o->zclosed[0] && !o->zclosed[1]);
    assert_true(tb_object_intersect(o, &down, &h));
    assert_int_equal(h.face, TB_FACE_CONIC_TOP);
    tb_object_free(o);

    m = ti_prim(TB_PRIM_CYLINDER, tb_mid_geometry_default(TB_PRIM_CYLINDER), id);
    o = ti_build(&m, 0);
    assert_true(!o->zclosed[0] && !o->zclosed[1]);
    assert_true(tb_object_intersect(o, &down, &h));
    assert_int_equal(h.face, TB_FACE_CYLINDER_TOP);
    tb_object_free(o);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stable_quadratics),
        cmocka_unit_test(test_textbook_float_loses),
        cmocka_unit_test(test_apex_is_side),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
