/* Consistency of hits on randomized primitives of every kind (open variants
 * included) under random affine transforms (non-uniform scales, mirrors):
 *
 *  - t in [tmin, tmax]; occluded agrees with intersect; u, v in [0, 1];
 *  - the hit point of tb_object_hit_point lies within its error bound of the
 *    surface of the reported face (world distance to first order,
 *    |F| / |M^-T grad F|, with F the face's implicit function written here);
 *  - ng has unit length and is the outward normal of that face there, M^-T
 *    grad F normalised (within 1e-5);
 *  - no boundary is crossed before the hit (closed solids: membership is the
 *    same at sample points between tmin and t);
 *  - the face agrees with param's nearest face (except within 1e-6 of an
 *    edge), and param maps (face, u, v) back to the hit point. */
#include "test_isect_common.h"

#include "host/object/intersect.h"
#include "host/object/param.h"
#include "util/math/float.h"

typedef long double ld;

/* Implicit function of face `face` at object-space p, positive outside, and
 * its gradient (outward). false if this file has no formula for it. */
static bool ti_face_fn(const tb_object *o, int face, const ld p[3], ld *F, ld g[3])
{
    const tb_mid_geometry *gm = &o->geom;
    g[0] = g[1] = g[2] = 0;
    int ax = face / 2;
    ld sgn = face % 2 ? 1 : -1;
    switch (o->kind) {
    case TB_PRIM_SPHERE:
        *F = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] - 1;
        g[0] = 2 * p[0], g[1] = 2 * p[1], g[2] = 2 * p[2];
        return true;
    case TB_PRIM_CUBE:
    case TB_PRIM_SQUARE_ARCH:
    case TB_PRIM_ROUND_ARCH:
        if (face < 6) {
            *F = sgn * p[ax] - 1;
            g[ax] = sgn;
            return true;
        }
        if (face == TB_FACE_ARCH_INNER_LEFT || face == TB_FACE_ARCH_INNER_RIGHT) {
            ld hw = gm->arch.width / 2, s = face == TB_FACE_ARCH_INNER_LEFT ? 1 : -1;
            *F = s * p[0] + hw;
            g[0] = s;
            return true;
        }
        if (o->kind == TB_PRIM_SQUARE_ARCH) {
            *F = -(p[2] - (-1 + (ld)gm->arch.height));
            g[2] = -1;
            return true;
        } else {
            ld hw = gm->arch.width / 2, zs = -1 + (ld)gm->arch.height - hw;
            *F = hw * hw - (p[0] * p[0] + (p[2] - zs) * (p[2] - zs));
            g[0] = -2 * p[0], g[2] = -2 * (p[2] - zs);
            return true;
        }
    case TB_PRIM_CYLINDER:
    case TB_PRIM_CONE:
    case TB_PRIM_CONIC: {
        ld c[3] = {1, 0, 0}, z0 = -1, z1 = 1;
        if (o->kind == TB_PRIM_CONE) {
            ld rt = gm->cone.top_radius, a = (1 + rt) / 2, b = (rt - 1) / 2;
            c[0] = a * a, c[1] = 2 * a * b, c[2] = b * b;
        } else if (o->kind == TB_PRIM_CONIC) {
            c[0] = gm->conic.c[0], c[1] = gm->conic.c[1], c[2] = gm->conic.c[2];
            z0 = gm->conic.z0, z1 = gm->conic.z1;
        }
        if (face == 0) {
            *F = p[0] * p[0] + p[1] * p[1] - (c[0] + c[1] * p[2] + c[2] * p[2] * p[2]);
            g[0] = 2 * p[0], g[1] = 2 * p[1], g[2] = -(c[1] + 2 * c[2] * p[2]);
        } else if (face == 1) {
            *F = z0 - p[2];
            g[2] = -1;
        } else {
            *F = p[2] - z1;
            g[2] = 1;
        }
        return true;
    }
    case TB_PRIM_PYRAMID: {
        ld top = gm->pyramid.top, a0 = (1 + top) / 2, b0 = (top - 1) / 2;
        if (face < 4) {
            *F = sgn * p[ax] - (a0 + b0 * p[2]);
            g[ax] = sgn, g[2] = -b0;
        } else if (face == TB_FACE_PYRAMID_BOTTOM) {
            *F = -1 - p[2];
            g[2] = -1;
        } else {
            *F = p[2] - 1;
            g[2] = 1;
        }
        return true;
    }
    case TB_PRIM_PRISM: {
        if (face == TB_FACE_PRISM_BOTTOM || face == TB_FACE_PRISM_TOP) {
            ld s = face == TB_FACE_PRISM_TOP ? 1 : -1;
            *F = s * p[2] - 1;
            g[2] = s;
            return true;
        }
        int k = face - TB_FACE_PRISM_SIDE0, n;
        ld P[2], Q[2], area = 0;
        if (gm->prism.nprofile > 0) {
            n = gm->prism.nprofile;
            const tb_vec2 *pr = gm->prism.profile;
            P[0] = pr[k].x, P[1] = pr[k].y, Q[0] = pr[(k + 1) % n].x, Q[1] = pr[(k + 1) % n].y;
            for (int i = 0; i < n; i++)
                area += (ld)pr[i].x * pr[(i + 1) % n].y - (ld)pr[(i + 1) % n].x * pr[i].y;
        } else {
            n = gm->prism.sides;
            P[0] = cosl(2 * TI_PI * k / n), P[1] = sinl(2 * TI_PI * k / n);
            Q[0] = cosl(2 * TI_PI * (k + 1) / n), Q[1] = sinl(2 * TI_PI * (k + 1) / n);
            area = 1;
        }
        ld s = area > 0 ? 1 : -1, ex = Q[0] - P[0], ey = Q[1] - P[1];
        g[0] = s * ey, g[1] = -s * ex;
        *F = g[0] * (p[0] - P[0]) + g[1] * (p[1] - P[1]);
        return true;
    }
    case TB_PRIM_TORUS: {
        ld R = gm->torus.major, r = gm->torus.minor, rho = sqrtl(p[0] * p[0] + p[1] * p[1]);
        ld q[3] = {p[0] - R * p[0] / rho, p[1] - R * p[1] / rho, p[2]};
        ld l = sqrtl(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
        *F = l - r;
        g[0] = q[0] / l, g[1] = q[1] / l, g[2] = q[2] / l;
        return true;
    }
    case TB_PRIM_POLYGONS: {
        const tb_geom_polygons *pg = &gm->polygons;
        int s = pg->face_start[face], e = pg->face_start[face + 1];
        ld n[3] = {0, 0, 0};
        for (int i = s; i < e; i++) { /* Newell */
            tb_vec3 a = pg->vertices[pg->indices[i]], b = pg->vertices[pg->indices[i + 1 < e ? i + 1 : s]];
            n[0] += ((ld)a.y - b.y) * ((ld)a.z + b.z);
            n[1] += ((ld)a.z - b.z) * ((ld)a.x + b.x);
            n[2] += ((ld)a.x - b.x) * ((ld)a.y + b.y);
        }
        tb_vec3 v0 = pg->vertices[pg->indices[s]];
        *F = n[0] * (p[0] - v0.x) + n[1] * (p[1] - v0.y) + n[2] * (p[2] - v0.z);
        g[0] = n[0], g[1] = n[1], g[2] = n[2];
        return true;
    }
    default: return false;
    }
}

typedef struct ti_variant {
    const char *name;
    tb_prim_kind kind;
    tb_mid_geometry g;
} ti_variant;

typedef struct ti_kstats {
    long rays, hits, dist_fail, normal_fail, order_fail, face_fail, param_fail, misc_fail;
    double worst_dist, worst_normal;
} ti_kstats;

static void ti_consistency(const ti_variant *var, uint64_t seed, long nrays)
{
    tb_rng r;
    tb_rng_seed(&r, seed, (uint64_t)var->kind * 977 + (uint64_t)var->name[0]);
    enum { NOBJ = 8 };
    tb_object *objs[NOBJ];
    for (int i = 0; i < NOBJ; i++) {
        tb_mid_object m = ti_prim(var->kind, var->g, ti_random_transform(&r, 0.1, 10.0, 20.0, true));
        objs[i] = ti_build(&m, 0);
    }
    ti_kstats S = {0};
    for (long i = 0; i < nrays; i++) {
        const tb_object *o = objs[i % NOBJ];
        tb_dvec3 q = {ti_uniform(&r, -1.3, 1.3), ti_uniform(&r, -1.3, 1.3), ti_uniform(&r, -1.3, 1.3)};
        tb_dvec3 target = tb_transform_dpoint(&o->to_world, q);
        tb_dvec3 u = ti_sphere_dir(&r);
        double dist = o->scale * (i % 5 == 0 ? 0.3 : 4.0);
        tb_vec3 orig = {(float)(target.x + dist * u.x), (float)(target.y + dist * u.y), (float)(target.z + dist * u.z)};
        tb_vec3 d = {(float)(target.x - orig.x), (float)(target.y - orig.y), (float)(target.z - orig.z)};
        tb_ray ray = tb_ray_make(orig, d, (float)ti_uniform(&r, -0.5, 0.3), i % 7 == 0 ? 1.0f : INFINITY);
        S.rays++;
        tb_hit h;
        bool hit = tb_object_intersect(o, &ray, &h);
        if (hit != tb_object_occluded(o, &ray)) {
            S.misc_fail++;
            continue;
        }
        if (!hit)
            continue;
        S.hits++;
        if (!(h.t >= ray.tmin && h.t <= ray.tmax) || !(h.u >= 0 && h.u <= 1 && h.v >= 0 && h.v <= 1) ||
            h.object != 0) {
            S.misc_fail++;
            continue;
        }
        /* The range ends at the hit's float t, and one float past it on
         * either side: occluded (an any-hit path of its own for the quadrics)
         * must still agree with intersect, the hit itself being in range. */
        float ends[4][2] = {{ray.tmin, h.t},
                            {ray.tmin, tb_next_float_down(h.t)},
                            {h.t, ray.tmax},
                            {tb_next_float_up(h.t), ray.tmax}};
        for (int e = 0; e < 4; e++) {
            tb_ray re = ray;
            re.tmin = ends[e][0];
            re.tmax = ends[e][1];
            if (!(re.tmin <= re.tmax))
                continue;
            tb_hit he;
            bool ie = tb_object_intersect(o, &re, &he), oe = tb_object_occluded(o, &re);
            if (ie != oe || (e % 2 == 0 && !oe)) {
                if (S.misc_fail++ < 3)
                    print_message("%s: range [%a, %a] around hit t = %a: intersect %d, occluded %d\n", var->name,
                                  (double)re.tmin, (double)re.tmax, (double)h.t, ie, oe);
            }
        }
        tb_vec3 p, perr;
        if (!tb_object_hit_point(o, &ray, &h, &p, &perr)) {
            S.misc_fail++;
            continue;
        }
        /* Distance from the face's surface, to first order, in world units. */
        const tb_mat4 *mi = &o->to_world.inv;
        ld po[3];
        for (int k = 0; k < 3; k++)
            po[k] = (ld)mi->m[k][0] * p.x + (ld)mi->m[k][1] * p.y + (ld)mi->m[k][2] * p.z + (ld)mi->m[k][3];
        ld F = 0, g[3];
        assert_true(ti_face_fn(o, (int)h.face, po, &F, g));
        ld gw[3]; /* M^-T grad F */
        for (int k = 0; k < 3; k++)
            gw[k] = (ld)mi->m[0][k] * g[0] + (ld)mi->m[1][k] * g[1] + (ld)mi->m[2][k] * g[2];
        ld gl = sqrtl(gw[0] * gw[0] + gw[1] * gw[1] + gw[2] * gw[2]);
        double wdist = (double)(fabsl(F) / gl);
        double bound = sqrt((double)perr.x * perr.x + (double)perr.y * perr.y + (double)perr.z * perr.z);
        S.worst_dist = fmax(S.worst_dist, wdist / bound);
        if (!(wdist <= bound * 1.001) && S.dist_fail++ < 3)
            print_message("%s face %u: hit point %g from the surface, bound %g\n", var->name, h.face, wdist, bound);
        /* The normal. */
        double nl = sqrt((double)h.ng.x * h.ng.x + (double)h.ng.y * h.ng.y + (double)h.ng.z * h.ng.z);
        double dn = fmax(fabs(h.ng.x - (double)(gw[0] / gl)),
                         fmax(fabs(h.ng.y - (double)(gw[1] / gl)), fabs(h.ng.z - (double)(gw[2] / gl))));
        bool apex = (o->kind == TB_PRIM_CONE || o->kind == TB_PRIM_CONIC) && h.face == 0 &&
                    (double)(gl / o->scale) < 1e-3; /* gradient vanishing at an apex */
        /* The expected normal is evaluated at the float point p, which may
         * lie perr away from the exact hit: allow twice the change of that
         * normal over the error box (summed over the axes). */
        double sens = 0.0;
        float pe[3] = {perr.x, perr.y, perr.z};
        for (int a = 0; a < 3; a++) {
            double sa = 0.0; /* the box's corners combine the axes: sum their changes */
            for (int sg = -1; sg <= 1; sg += 2) {
                ld q2[3], F2, g2[3], w2[3];
                for (int k = 0; k < 3; k++)
                    q2[k] = po[k] + sg * (ld)mi->m[k][a] * pe[a];
                ti_face_fn(o, (int)h.face, q2, &F2, g2);
                for (int k = 0; k < 3; k++)
                    w2[k] = (ld)mi->m[0][k] * g2[0] + (ld)mi->m[1][k] * g2[1] + (ld)mi->m[2][k] * g2[2];
                ld l2 = sqrtl(w2[0] * w2[0] + w2[1] * w2[1] + w2[2] * w2[2]);
                for (int k = 0; k < 3; k++)
                    sa = fmax(sa, (double)fabsl(w2[k] / l2 - gw[k] / gl));
            }
            sens += sa;
        }
        double ntol = 2e-7 + 2.0 * sens;
        S.worst_normal = fmax(S.worst_normal, apex ? 0.0 : dn / ntol);
        if ((fabs(nl - 1.0) > 1e-6 || (!apex && dn > ntol)) && S.normal_fail++ < 3)
            print_message("%s face %u: normal (%g %g %g), expected (%Lg %Lg %Lg)\n", var->name, h.face, h.ng.x, h.ng.y,
                          h.ng.z, gw[0] / gl, gw[1] / gl, gw[2] / gl);
        /* Nothing crossed before t (closed solids). */
        if (o->closed) {
            double margin = 1e-5 * (fabs(h.t) + 1.0);
            double t0 = ray.tmin + margin, t1 = h.t - margin;
            if (t1 > t0) {
                tb_dvec3 pa = {orig.x + t0 * d.x, orig.y + t0 * d.y, orig.z + t0 * d.z};
                bool in0 = ti_inside(o->kind, &o->geom, tb_mat4_mul_point(mi, pa));
                for (int s = 0; s < 4; s++) {
                    double t = t0 + (t1 - t0) * tb_rng_double(&r);
                    tb_dvec3 pt = {orig.x + t * d.x, orig.y + t * d.y, orig.z + t * d.z};
                    if (ti_inside(o->kind, &o->geom, tb_mat4_mul_point(mi, pt)) != in0) {
                        if (S.order_fail++ < 3)
                            print_message("%s: a boundary before the hit at t = %g (sample at %g)\n", var->name, h.t,
                                          t);
                        break;
                    }
                }
            }
        }
        /* Param: the nearest face is ours (away from edges), and (face, u, v) maps back to p. */
        tb_dvec3 pd = {(double)po[0], (double)po[1], (double)po[2]};
        int pf;
        double pu, pv;
        if (tb_param_from_point(o->kind, &o->geom, pd, -1, &pf, &pu, &pv) != TB_OK) {
            S.param_fail++;
            continue;
        }
        if ((uint32_t)pf != h.face) {
            double size = 1.0 + fmax(fabs(pd.x), fmax(fabs(pd.y), fabs(pd.z)));
            double d0 = tb_param_face_distance(o->kind, &o->geom, (int)h.face, pd);
            double d1 = tb_param_face_distance(o->kind, &o->geom, pf, pd);
            if (!(d0 <= 1e-6 * size && d1 <= 1e-6 * size) && S.face_fail++ < 3)
                print_message("%s: face %u, param's nearest %d (distances %g, %g)\n", var->name, h.face, pf, d0, d1);
        }
        tb_dvec3 back;
        if (tb_param_eval(o->kind, &o->geom, (int)h.face, h.u, h.v, &back, NULL, NULL, NULL) != TB_OK) {
            S.param_fail++;
            continue;
        }
        tb_dvec3 bw = tb_transform_dpoint(&o->to_world, back);
        double err = fmax(fabs(bw.x - p.x), fmax(fabs(bw.y - p.y), fabs(bw.z - p.z)));
        double size = fmax(fabs(p.x), fmax(fabs(p.y), fabs(p.z))) + o->scale;
        if (!(err <= 1e-5 * size) && S.param_fail++ < 3)
            print_message("%s face %u: (u, v) = (%g, %g) maps %g away from the hit point\n", var->name, h.face, h.u,
                          h.v, err);
    }
    print_message("[ %-10s ] %ld rays, %ld hits: points within %.3f of their bound, normals within %.2f of their tolerance\n", var->name,
                  S.rays, S.hits, S.worst_dist, S.worst_normal);
    for (int i = 0; i < NOBJ; i++)
        tb_object_free(objs[i]);
    assert_true(S.hits > S.rays / 10);
    assert_int_equal(S.misc_fail, 0);
    assert_int_equal(S.dist_fail, 0);
    assert_int_equal(S.normal_fail, 0);
    assert_int_equal(S.order_fail, 0);
    assert_int_equal(S.face_fail, 0);
    assert_int_equal(S.param_fail, 0);
}

static void test_consistency(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("consistency", 2718);
    long n = ti_count(20000, 1000);
    ti_mesh mesh = ti_cube_mesh(3);
    static const tb_vec2 L[6] = {{-1, -1}, {-1, 1}, {1, 1}, {1, 0}, {0, 0}, {0, -1}};
    ti_variant v[24];
    int nv = 0;
    for (int k = TB_PRIM_SPHERE; k <= TB_PRIM_ROUND_ARCH; k++) {
        tb_mid_geometry g = tb_mid_geometry_default((tb_prim_kind)k);
        if (k == TB_PRIM_POLYGONS)
            g = ti_mesh_geom(&mesh);
        v[nv++] = (ti_variant){tb_prim_kind_name((tb_prim_kind)k), (tb_prim_kind)k, g};
    }
    tb_mid_geometry g;
    g = tb_mid_geometry_default(TB_PRIM_CYLINDER), g.cylinder.caps = false;
    v[nv++] = (ti_variant){"open cyl", TB_PRIM_CYLINDER, g};
    g = tb_mid_geometry_default(TB_PRIM_CONE), g.cone.top_radius = 0.4, g.cone.caps = false;
    v[nv++] = (ti_variant){"open frust", TB_PRIM_CONE, g};
    g = tb_mid_geometry_default(TB_PRIM_CONE), g.cone.top_radius = 2.0;
    v[nv++] = (ti_variant){"frustum", TB_PRIM_CONE, g};
    g = tb_mid_geometry_default(TB_PRIM_PYRAMID), g.pyramid.top = 0.5, g.pyramid.caps = false;
    v[nv++] = (ti_variant){"open pyr", TB_PRIM_PYRAMID, g};
    g = tb_mid_geometry_default(TB_PRIM_PRISM), g.prism.sides = 0, g.prism.nprofile = 6, g.prism.profile = L;
    v[nv++] = (ti_variant){"L prism", TB_PRIM_PRISM, g};
    g = tb_mid_geometry_default(TB_PRIM_PRISM), g.prism.sides = 200;
    v[nv++] = (ti_variant){"prism 200", TB_PRIM_PRISM, g};
    g = tb_mid_geometry_default(TB_PRIM_PRISM), g.prism.sides = 7, g.prism.caps = false;
    v[nv++] = (ti_variant){"open prism", TB_PRIM_PRISM, g};
    g = tb_mid_geometry_default(TB_PRIM_TORUS), g.torus.minor = 0.8;
    v[nv++] = (ti_variant){"fat torus", TB_PRIM_TORUS, g};
    g = tb_mid_geometry_default(TB_PRIM_CONIC), g.conic.c[0] = 0.3, g.conic.c[1] = 0.1, g.conic.c[2] = 0.6;
    v[nv++] = (ti_variant){"hyperb", TB_PRIM_CONIC, g};
    g.conic.caps = false;
    v[nv++] = (ti_variant){"open hyp", TB_PRIM_CONIC, g};
    g = tb_mid_geometry_default(TB_PRIM_CONIC), g.conic.c[0] = 0.5, g.conic.c[1] = -0.5, g.conic.c[2] = 0;
    v[nv++] = (ti_variant){"paraboloid", TB_PRIM_CONIC, g};
    g = tb_mid_geometry_default(TB_PRIM_ROUND_ARCH), g.arch.width = 1.2, g.arch.height = 0.6;
    v[nv++] = (ti_variant){"low arch", TB_PRIM_ROUND_ARCH, g};
    for (int i = 0; i < nv; i++)
        ti_consistency(&v[i], seed, n);
    ti_mesh_free(&mesh);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_consistency),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
