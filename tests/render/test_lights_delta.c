/* Point, spot and directional lights: irradiance against E = I cos(theta) /
 * d^2 and E = E0 cos(theta), the spot falloff at and between its edges, the
 * placement of MID lights and their IES frames, power against quadrature, and
 * emission sampling against its density. */
#include <string.h>

#include "tb_test.h"

#include "host/render/lights.h"
#include "test_shading_support.h"
#include "util/math/transform.h"

static tb_vec3 rand_point(tb_rng *r, double s)
{
    return tb_vec3_make((float)(s * (2 * tb_rng_double(r) - 1)), (float)(s * (2 * tb_rng_double(r) - 1)),
                        (float)(s * (2 * tb_rng_double(r) - 1)));
}

static tb_vec3 rand_dir(tb_rng *r)
{
    double z = 1.0 - 2.0 * tb_rng_double(r), p = 2.0 * M_PI * tb_rng_double(r);
    double s = sqrt(fmax(0.0, 1.0 - z * z));
    return tb_vec3_make((float)(s * cos(p)), (float)(s * sin(p)), (float)z);
}

static double dot_d(tb_vec3 a, tb_vec3 b) { return (double)a.x * b.x + (double)a.y * b.y + (double)a.z * b.z; }

static void test_point_irradiance(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("point light", 41), 0);
    for (int k = 0; k < 2000; k++) {
        tb_vec3 lp = rand_point(&rng, 10.0), p = rand_point(&rng, 10.0), n = rand_dir(&rng);
        double I = 0.1 + 100.0 * tb_rng_double(&rng);
        tb_light l = tb_light_point(lp, tb_channels_rgb((float)I, (float)(2 * I), 0.0f));
        tb_light_sample s;
        assert_true(tb_light_sample_li(&l, p, &s));
        assert_true(s.delta && s.pdf == 1.0 && s.emitter == -1);
        /* Independent: E = I cos(theta) / d^2 in double. */
        double dx = (double)lp.x - p.x, dy = (double)lp.y - p.y, dz = (double)lp.z - p.z;
        double d2 = dx * dx + dy * dy + dz * dz, d = sqrt(d2);
        double cos_t = (n.x * dx + n.y * dy + n.z * dz) / d;
        double E = s.L.v[0] * fmax(0.0, dot_d(n, s.wi));
        tb_assert_near(E, I * fmax(0.0, cos_t) / d2, 1e-5 * I / d2);
        tb_assert_near(s.L.v[1], 2.0 * I / d2, 1e-6 * I / d2);
        tb_assert_near(s.dist, d, 1e-6 * d);
        /* The shadow segment runs from p to just short of the light. */
        tb_vec3 end = tb_ray_at(&s.shadow, 1.0f);
        tb_assert_near(tb_vec3_distance(end, lp), 0.0, 1e-5 * (1.0 + d));
        assert_true(s.shadow.tmin == 0.0f && s.shadow.tmax < 1.0f && s.shadow.tmax > 0.999f);
    }
    /* A point at the light itself gets nothing (and no NaN). */
    tb_light l = tb_light_point(tb_vec3_make(1, 2, 3), tb_channels_splat(1, 1.0f));
    tb_light_sample s;
    assert_false(tb_light_sample_li(&l, tb_vec3_make(1, 2, 3), &s));
    assert_true(tb_channels_is_black(s.L));
}

static void test_directional(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("directional", 42), 0);
    for (int k = 0; k < 1000; k++) {
        tb_vec3 dir = tb_vec3_scale(rand_dir(&rng), 3.0f), n = rand_dir(&rng), p = rand_point(&rng, 5.0);
        tb_light l = tb_light_directional(dir, tb_channels_splat(1, 2.5f));
        tb_light_sample s;
        assert_true(tb_light_sample_li(&l, p, &s));
        double c = -dot_d(n, dir) / tb_vec3_length(dir);
        tb_assert_near(s.L.v[0] * fmax(0.0, dot_d(n, s.wi)), 2.5 * fmax(0.0, c), 1e-6);
        assert_true(isinf(s.dist) && isinf(s.shadow.tmax));
        tb_assert_near(dot_d(s.wi, dir), -tb_vec3_length(dir), 1e-6);
    }
}

static void test_spot_falloff(void **state)
{
    (void)state;
    double ct = cos(30.0 * M_PI / 180.0), cf = cos(20.0 * M_PI / 180.0);
    /* Edges: 0 at and beyond cone_angle, 1 at and within cone_angle - cone_delta. */
    assert_true(tb_spot_falloff(ct, cf, ct) == 0.0);
    assert_true(tb_spot_falloff(ct, cf, cos(40.0 * M_PI / 180.0)) == 0.0);
    assert_true(tb_spot_falloff(ct, cf, -1.0) == 0.0);
    assert_true(tb_spot_falloff(ct, cf, cf) == 1.0);
    assert_true(tb_spot_falloff(ct, cf, 1.0) == 1.0);
    /* Between: smoothstep of the cosine: 1/2 half way, 5/32 a quarter of the way. */
    tb_assert_near(tb_spot_falloff(ct, cf, ct + 0.5 * (cf - ct)), 0.5, 1e-14);
    tb_assert_near(tb_spot_falloff(ct, cf, ct + 0.25 * (cf - ct)), 0.15625, 1e-14);
    tb_assert_near(tb_spot_falloff(ct, cf, ct + 0.75 * (cf - ct)), 0.84375, 1e-14);
    /* Continuous and non-decreasing across the band, flat at both ends. */
    double prev = 0.0;
    for (int k = 0; k <= 1000; k++) {
        double c = ct - 0.01 + (cf - ct + 0.02) * k / 1000.0;
        double v = tb_spot_falloff(ct, cf, c);
        assert_true(v >= prev && v - prev < 0.01);
        prev = v;
    }
    /* cone_delta = 0: a hard edge. */
    assert_true(tb_spot_falloff(ct, ct, ct) == 0.0);
    assert_true(tb_spot_falloff(ct, ct, ct + 1e-12) == 1.0);

    /* Through a spot light: intensity toward directions at given angles. */
    tb_vec3 axis = tb_vec3_make(0.0f, 0.0f, -1.0f);
    tb_light l = tb_light_spot(tb_vec3_make(0, 0, 5), axis, tb_channels_splat(1, 8.0f), 30.0, 10.0);
    const double angles[] = {0.0, 19.9, 20.1, 25.0, 29.9, 30.1, 90.0, 170.0};
    for (int k = 0; k < 8; k++) {
        double a = angles[k] * M_PI / 180.0;
        tb_vec3 w = tb_vec3_make((float)sin(a), 0.0f, (float)-cos(a));
        double want = 8.0 * tb_spot_falloff(ct, cf, cos(a));
        if (angles[k] < 20.0)
            want = 8.0;
        if (angles[k] > 30.0)
            want = 0.0;
        tb_assert_near(tb_light_intensity(&l, w).v[0], want, 1e-5);
    }
    /* Irradiance at a point on the floor under the spot, 25 degrees off axis. */
    double a = 25.0 * M_PI / 180.0, h = 5.0;
    tb_vec3 p = tb_vec3_make((float)(h * tan(a)), 0.0f, 0.0f);
    tb_light_sample s;
    assert_true(tb_light_sample_li(&l, p, &s));
    double d2 = h * h / (cos(a) * cos(a));
    tb_assert_near(s.L.v[0] * dot_d(tb_vec3_make(0, 0, 1), s.wi),
                   8.0 * tb_spot_falloff(ct, cf, cos(a)) * cos(a) / d2, 1e-6);
    /* Outside the cone: no light. */
    assert_false(tb_light_sample_li(&l, tb_vec3_make(10.0f, 0.0f, 0.0f), &s));
}

/* A MID light with the given kind and transform. */
static tb_mid_light mid_light(tb_light_kind kind, tb_transform T)
{
    tb_mid_light m = tb_mid_light_default(kind);
    m.to_world = T;
    return m;
}

static void test_from_mid(void **state)
{
    (void)state;
    tb_transform T = tb_transform_translate(tb_dvec3_make(10, 0, 0));
    tb_mid_light m = mid_light(TB_LIGHT_POINT, T);
    m.position = tb_dvec3_make(1, 2, 3);
    m.intensity = tb_mid_color_grey(4.0f);
    tb_light l;
    assert_int_equal(tb_light_from_mid(&m, NULL, NULL, &l), TB_OK);
    assert_true(l.kind == TB_LIGHT_POINT && l.intensity.n == 3 && l.intensity.v[2] == 4.0f);
    assert_true(l.position.x == 11.0f && l.position.y == 2.0f && l.position.z == 3.0f);
    assert_true(l.axis.z == -1.0f && l.xaxis.x == 1.0f);

    /* Spot, default direction -z, rotated 90 degrees about x: the beam points along +y. */
    tb_transform R;
    assert_int_equal(tb_transform_rotate_deg(90.0, tb_dvec3_make(1, 0, 0), &R), TB_OK);
    m = mid_light(TB_LIGHT_SPOT, R);
    assert_int_equal(tb_light_from_mid(&m, NULL, NULL, &l), TB_OK);
    tb_assert_near(l.axis.y, 1.0, 1e-7);
    tb_assert_near(l.xaxis.x, 1.0, 1e-7);
    tb_assert_near(l.cos_total, cos(30.0 * M_PI / 180.0), 1e-15);
    tb_assert_near(l.cos_falloff, cos(25.0 * M_PI / 180.0), 1e-15);

    /* Spot along light-space +x: the smallest rotation from -z to +x turns +x into +z. */
    m = mid_light(TB_LIGHT_SPOT, tb_transform_identity());
    m.direction = tb_dvec3_make(2, 0, 0);
    assert_int_equal(tb_light_from_mid(&m, NULL, NULL, &l), TB_OK);
    tb_assert_near(l.axis.x, 1.0, 1e-7);
    tb_assert_near(l.xaxis.z, 1.0, 1e-7);
    /* Straight up (+z): the rotation is 180 degrees about x, +x stays. */
    m.direction = tb_dvec3_make(0, 0, 1);
    assert_int_equal(tb_light_from_mid(&m, NULL, NULL, &l), TB_OK);
    tb_assert_near(l.xaxis.x, 1.0, 1e-7);

    /* Directional: direction through the transform's linear part only. */
    m = mid_light(TB_LIGHT_DIRECTIONAL, T);
    m.direction = tb_dvec3_make(0, 3, 0);
    assert_int_equal(tb_light_from_mid(&m, NULL, NULL, &l), TB_OK);
    tb_assert_near(l.axis.y, 1.0, 1e-7);

    /* Bad cone. */
    m = mid_light(TB_LIGHT_SPOT, tb_transform_identity());
    m.cone_delta = 40.0;
    assert_int_equal(tb_light_from_mid(&m, NULL, NULL, &l), TB_ERR_ARG);
}

/* Intensity of light l toward direction w, for quadrature. */
static double intensity_fn(void *c, tb_vec3 w) { return tb_light_intensity((const tb_light *)c, w).v[0]; }

static void test_power_and_emission(void **state)
{
    (void)state;
    uint64_t seed = tb_test_seed("light power", 43);
    tb_light lights[3] = {
        tb_light_point(tb_vec3_make(0, 0, 0), tb_channels_splat(1, 3.0f)),
        tb_light_spot(tb_vec3_make(0, 0, 0), tb_vec3_make(1, 1, 0), tb_channels_splat(1, 3.0f), 40.0, 15.0),
        tb_light_spot(tb_vec3_make(0, 0, 0), tb_vec3_make(0, 0, 1), tb_channels_splat(1, 3.0f), 90.0, 0.0),
    };
    for (int k = 0; k < 3; k++) {
        tb_light *l = &lights[k];
        /* Power against quadrature of the intensity over the cone (the
         * sphere for the point light), about the axis. */
        tb_vec3 pole = l->kind == TB_LIGHT_SPOT ? l->axis : tb_vec3_make(0, 0, 1);
        double tmax = l->kind == TB_LIGHT_SPOT ? acos(l->cos_total) : M_PI;
        double q = tst_integrate_sphere(intensity_fn, l, pole, tmax, 48, 8, 8);
        double P = tb_light_power(l, 0.0).v[0];
        tb_assert_near(P, q, 2e-4 * q);
        if (k == 0)
            tb_assert_near(P, 4.0 * M_PI * 3.0, 1e-5);
        if (k == 2)
            tb_assert_near(P, 2.0 * M_PI * 3.0, 1e-5); /* a hemisphere */
        /* Emission sampling: E[I(w) / pdf(w)] = power. */
        tb_rng rng;
        tb_rng_seed(&rng, seed + k, 0);
        double s = 0.0, s2 = 0.0;
        int n = 20000;
        for (int i = 0; i < n; i++) {
            tb_vec3 w;
            double pdf;
            tb_channels I;
            assert_true(tb_light_sample_emission(l, tb_rng_float(&rng), tb_rng_float(&rng), &w, &pdf, &I));
            double v = I.v[0] / pdf;
            s += v;
            s2 += v * v;
        }
        double mean = s / n, sd = sqrt(fmax(0.0, s2 / n - mean * mean) / n);
        tb_assert_near(mean, P, 5.0 * sd + 1e-6 * P);
    }
    tb_light d = tb_light_directional(tb_vec3_make(0, 0, -1), tb_channels_splat(1, 2.0f));
    tb_assert_near(tb_light_power(&d, 3.0).v[0], M_PI * 9.0 * 2.0, 1e-5);
    tb_vec3 w;
    double pdf;
    tb_channels I;
    assert_false(tb_light_sample_emission(&d, 0.5f, 0.5f, &w, &pdf, &I));
}

/* tb_light_sample_li sets every field of the record, whatever it held
 * before (it no longer zeroes it first): the same call on two records
 * filled with different bytes gives the same fields, and a sample that
 * gives no light (p at the point light, p outside a spot's cone) is the
 * zeroed delta record. Fails when a field is left unset. */
static void test_sample_record_complete(void **state)
{
    (void)state;
    const tb_light lights[3] = {
        tb_light_point(tb_vec3_make(1, 2, 3), tb_channels_rgb(1.0f, 2.0f, 3.0f)),
        tb_light_spot(tb_vec3_make(0, 0, 5), tb_vec3_make(0, 0, -1), tb_channels_rgb(8.0f, 4.0f, 2.0f), 30.0, 10.0),
        tb_light_directional(tb_vec3_make(0.3f, 0.2f, -1), tb_channels_rgb(2.0f, 2.0f, 1.0f)),
    };
    const tb_vec3 pts[4] = {{0, 0, 0}, {0.5f, -0.5f, 0.25f}, {1, 2, 3}, {20, 0, 0}};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 4; j++) {
            tb_light_sample a, b;
            memset(&a, 0x5a, sizeof a);
            memset(&b, 0xa5, sizeof b);
            bool ra = tb_light_sample_li(&lights[i], pts[j], &a);
            bool rb = tb_light_sample_li(&lights[i], pts[j], &b);
            assert_int_equal(ra, rb);
            assert_memory_equal(&a.L, &b.L, sizeof a.L);
            assert_memory_equal(&a.wi, &b.wi, sizeof a.wi);
            assert_memory_equal(&a.dist, &b.dist, sizeof a.dist);
            assert_memory_equal(&a.pdf, &b.pdf, sizeof a.pdf);
            assert_memory_equal(&a.point, &b.point, sizeof a.point);
            assert_memory_equal(&a.normal, &b.normal, sizeof a.normal);
            assert_memory_equal(&a.shadow, &b.shadow, sizeof a.shadow);
            assert_int_equal(a.delta, b.delta);
            assert_true(a.delta);
            assert_int_equal(a.emitter, -1);
            assert_true(a.pdf == 1.0);
            if (!ra && i < 2) /* no light: the zeroed record */
                assert_true(a.L.n == 3 && a.L.v[0] == 0.0f && a.dist == 0.0f && a.wi.x == 0.0f);
        }
}

/* tb_light_delta_at is tb_light_sample_li's scalar part bit for bit: the
 * same direction and distance, intensity x scale equal to its L channel by
 * channel, and false exactly where it gives no light for a reason other
 * than a black L (outside a spot cone, p at the light). Random points near
 * and far, spots hit inside, at and beyond the cone's edge. */
static void test_delta_at_matches_sample(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("delta at", 43), 0);
    for (int k = 0; k < 3000; k++) {
        tb_vec3 lp = rand_point(&rng, k % 3 == 0 ? 1e-3 : 10.0);
        tb_channels I = tb_channels_rgb((float)(100 * tb_rng_double(&rng)), 0.0f, (float)tb_rng_double(&rng));
        tb_light l;
        switch (k % 3) {
        case 0: l = tb_light_point(lp, I); break;
        case 1: l = tb_light_spot(lp, rand_dir(&rng), I, 5.0 + 80.0 * tb_rng_double(&rng), 5.0); break;
        default: l = tb_light_directional(rand_dir(&rng), I); break;
        }
        tb_vec3 p = k % 50 == 0 ? lp : rand_point(&rng, k % 7 == 0 ? 1e4 : 10.0);
        tb_light_sample s;
        bool rs = tb_light_sample_li(&l, p, &s);
        tb_vec3 wi;
        float dist, scale;
        bool rd = tb_light_delta_at(&l, p, &wi, &dist, &scale);
        bool black = true;
        for (int c = 0; c < 3 && rd; c++) {
            float v = l.intensity.v[c] * scale;
            assert_memory_equal(&v, &s.L.v[c], sizeof v);
            black = black && v == 0.0f;
        }
        if (rd) {
            assert_memory_equal(&wi, &s.wi, sizeof wi);
            assert_memory_equal(&dist, &s.dist, sizeof dist);
            assert_int_equal(rs, !black);
        } else {
            assert_false(rs);
        }
    }
    /* The light at p: no direction, no light. */
    tb_vec3 wi;
    float dist, scale;
    tb_light l = tb_light_point(tb_vec3_make(1, 2, 3), tb_channels_rgb(1, 1, 1));
    assert_false(tb_light_delta_at(&l, tb_vec3_make(1, 2, 3), &wi, &dist, &scale));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_point_irradiance),
        cmocka_unit_test(test_directional),
        cmocka_unit_test(test_spot_falloff),
        cmocka_unit_test(test_from_mid),
        cmocka_unit_test(test_power_and_emission),
        cmocka_unit_test(test_sample_record_complete),
        cmocka_unit_test(test_delta_at_matches_sample),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
