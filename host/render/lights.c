/* Point, spot, directional and area lights (lights.h, docs/lights.md). */
#include "host/render/lights.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "util/math/float.h"
#include "util/math/transform.h"

static tb_dvec3 tb__d(tb_vec3 v) { return tb_vec3_to_d(v); }

static tb_channels tb__black(int n) { return tb_channels_splat(n, 0.0f); }

/* tb__black(n)'s channel count: for a sample just zeroed whole, setting n
 * alone gives the same bytes as storing tb__black(n) (two fewer copies of
 * the channels per light sample). */
static int tb__black_n(int n) { return n < 1 ? 1 : (n > TB_CHANNELS_MAX ? TB_CHANNELS_MAX : n); }

/* ---------------------------------------------------------- delta lights */

/* +x turned by the smallest rotation taking (0, 0, -1) to the unit vector d
 * (Rodrigues with v = a x d, c = a . d); +x itself when d is (nearly) +z. */
static tb_dvec3 tb__spot_x(tb_dvec3 d)
{
    tb_dvec3 a = {0.0, 0.0, -1.0}, x = {1.0, 0.0, 0.0};
    double c = tb_dvec3_dot(a, d);
    if (1.0 + c < 1e-12)
        return x; /* 180 degrees: about x */
    tb_dvec3 v = tb_dvec3_cross(a, d);
    tb_dvec3 vx = tb_dvec3_cross(v, x);
    tb_dvec3 vvx = tb_dvec3_cross(v, vx);
    return tb_dvec3_add(tb_dvec3_add(x, vx), tb_dvec3_scale(vvx, 1.0 / (1.0 + c)));
}

/* x made perpendicular to the unit axis and normalised (any perpendicular
 * vector if x is parallel to it). */
static tb_dvec3 tb__ortho(tb_dvec3 x, tb_dvec3 axis)
{
    tb_dvec3 p = tb_dvec3_sub(x, tb_dvec3_scale(axis, tb_dvec3_dot(x, axis)));
    double l = tb_dvec3_length(p);
    if (!(l > 1e-9 * tb_dvec3_length(x))) {
        tb_dvec3 b1, b2;
        tb_dvec3_basis(axis, &b1, &b2);
        return b1;
    }
    return tb_dvec3_scale(p, 1.0 / l);
}

tb_light tb_light_point(tb_vec3 p, tb_channels I)
{
    return (tb_light){.kind = TB_LIGHT_POINT, .position = p, .axis = {0.0f, 0.0f, -1.0f},
                      .xaxis = {1.0f, 0.0f, 0.0f}, .intensity = I, .cos_total = -1.0,
                      .cos_falloff = -1.0};
}

tb_light tb_light_spot(tb_vec3 p, tb_vec3 axis, tb_channels I, double cone_angle, double cone_delta)
{
    tb_dvec3 d = tb_dvec3_normalize(tb__d(axis));
    tb_light l = {.kind = TB_LIGHT_SPOT, .position = p, .intensity = I};
    l.axis = tb_dvec3_to_f(d);
    l.xaxis = tb_dvec3_to_f(tb__ortho(tb__spot_x(d), d));
    l.cos_total = cos(tb_radians(cone_angle));
    l.cos_falloff = cos(tb_radians(cone_angle - cone_delta));
    return l;
}

tb_light tb_light_directional(tb_vec3 dir, tb_channels E)
{
    tb_dvec3 d = tb_dvec3_normalize(tb__d(dir));
    tb_light l = {.kind = TB_LIGHT_DIRECTIONAL, .intensity = E};
    l.axis = tb_dvec3_to_f(d);
    l.xaxis = tb_dvec3_to_f(tb__ortho(tb_dvec3_make(1.0, 0.0, 0.0), d));
    return l;
}

tb_status tb_light_from_mid(const tb_mid_light *m, const tb_bands *bands, const tb_ies *ies,
                            tb_light *out)
{
    if (!m || !out)
        return tb_error(TB_ERR_ARG, "light: NULL argument");
    tb_channels I;
    tb_status st = tb_channels_from_mid_color(&m->intensity, bands, TB_COLOR_EMISSION, &I);
    if (st)
        return tb_error_context(st, "light '%s'", m->name ? m->name : "");
    const tb_transform *T = &m->to_world;
    switch (m->kind) {
    case TB_LIGHT_POINT: {
        tb_dvec3 p = tb_transform_dpoint(T, m->position);
        *out = tb_light_point(tb_dvec3_to_f(p), I);
        tb_dvec3 nadir = tb_dvec3_normalize(tb_transform_dvector(T, tb_dvec3_make(0, 0, -1)));
        tb_dvec3 x = tb__ortho(tb_transform_dvector(T, tb_dvec3_make(1, 0, 0)), nadir);
        out->axis = tb_dvec3_to_f(nadir);
        out->xaxis = tb_dvec3_to_f(x);
        break;
    }
    case TB_LIGHT_SPOT: {
        double dl = tb_dvec3_length(m->direction);
        if (!(dl > 0.0) || !isfinite(dl))
            return tb_error(TB_ERR_ARG, "light '%s': zero or non-finite direction", m->name ? m->name : "");
        if (!(m->cone_angle > 0.0 && m->cone_angle <= 90.0 && m->cone_delta >= 0.0 &&
              m->cone_delta <= m->cone_angle))
            return tb_error(TB_ERR_ARG, "light '%s': cone_angle %g / cone_delta %g out of range",
                            m->name ? m->name : "", m->cone_angle, m->cone_delta);
        tb_dvec3 d = tb_dvec3_scale(m->direction, 1.0 / dl);
        tb_dvec3 p = tb_transform_dpoint(T, m->position);
        tb_dvec3 axis = tb_dvec3_normalize(tb_transform_dvector(T, d));
        tb_dvec3 x = tb__ortho(tb_transform_dvector(T, tb__spot_x(d)), axis);
        *out = tb_light_spot(tb_dvec3_to_f(p), tb_dvec3_to_f(axis), I, m->cone_angle, m->cone_delta);
        out->xaxis = tb_dvec3_to_f(x);
        break;
    }
    case TB_LIGHT_DIRECTIONAL: {
        tb_dvec3 d = tb_transform_dvector(T, m->direction);
        double dl = tb_dvec3_length(d);
        if (!(dl > 0.0) || !isfinite(dl))
            return tb_error(TB_ERR_ARG, "light '%s': zero or non-finite direction", m->name ? m->name : "");
        *out = tb_light_directional(tb_dvec3_to_f(d), I);
        break;
    }
    default:
        return tb_error(TB_ERR_ARG, "light: unknown kind %d", (int)m->kind);
    }
    if (ies && m->kind != TB_LIGHT_DIRECTIONAL)
        out->ies = ies;
    return TB_OK;
}

double tb_spot_falloff(double cos_total, double cos_falloff, double cos_theta)
{
    if (cos_theta <= cos_total)
        return 0.0;
    if (cos_theta >= cos_falloff)
        return 1.0;
    double t = (cos_theta - cos_total) / (cos_falloff - cos_total);
    return t * t * (3.0 - 2.0 * t);
}

/* Scalar factor of the intensity toward unit world direction w. */
static double tb__shape(const tb_light *l, tb_dvec3 w)
{
    double k = 1.0;
    tb_dvec3 axis = tb__d(l->axis);
    if (l->kind == TB_LIGHT_SPOT)
        k = tb_spot_falloff(l->cos_total, l->cos_falloff, tb_dvec3_dot(w, axis));
    if (l->ies && k > 0.0) {
        /* Photometric frame: x, y = x cross nadir, z = -nadir. */
        tb_dvec3 x = tb__d(l->xaxis), y = tb_dvec3_cross(x, axis);
        tb_vec3 local = tb_dvec3_to_f(tb_dvec3_make(tb_dvec3_dot(w, x), tb_dvec3_dot(w, y),
                                                    -tb_dvec3_dot(w, axis)));
        k *= tb_ies_normalized(l->ies, local);
    }
    return k;
}

tb_channels tb_light_intensity(const tb_light *l, tb_vec3 w)
{
    if (l->kind == TB_LIGHT_DIRECTIONAL)
        return tb__black(l->intensity.n);
    double k = tb__shape(l, tb_dvec3_normalize(tb__d(w)));
    return tb_channels_scale(l->intensity, (float)k);
}

/* The delta-light sample record before its light-specific fields: zeroed,
 * with the channel count, no emitter, delta, pdf 1. */
static void tb__delta_blank(const tb_light *l, tb_light_sample *s)
{
    *s = (tb_light_sample){0};
    s->L.n = tb__black_n(l->intensity.n);
    s->emitter = -1;
    s->delta = true;
    s->pdf = 1.0;
}

bool tb_light_sample_li(const tb_light *l, tb_vec3 p, tb_light_sample *s)
{
    if (l->kind == TB_LIGHT_DIRECTIONAL) {
        /* Every field set below (no zeroing first). */
        s->delta = true;
        s->pdf = 1.0;
        s->normal = (tb_vec3){0.0f, 0.0f, 0.0f};
        s->emitter = -1;
        tb_vec3 wi = tb_vec3_neg(l->axis);
        s->wi = wi;
        s->dist = INFINITY;
        s->point = p;
        s->L = l->intensity;
        s->shadow = tb_ray_make(p, wi, 0.0f, INFINITY);
        return !tb_channels_is_black(s->L);
    }
    tb_dvec3 d = tb_dvec3_sub(tb__d(l->position), tb__d(p));
    double dist = tb_dvec3_length(d);
    if (!(dist > 0.0) || !isfinite(dist)) {
        tb__delta_blank(l, s);
        return false;
    }
    tb_dvec3 wi = tb_dvec3_scale(d, 1.0 / dist);
    double k = tb__shape(l, tb_dvec3_neg(wi));
    if (!(k > 0.0)) {
        tb__delta_blank(l, s);
        return false;
    }
    /* Every field set, without zeroing the record first (s->L is written
     * whole below, its channels past n zero as tb_channels_scale keeps them). */
    s->delta = true;
    s->pdf = 1.0;
    s->normal = (tb_vec3){0.0f, 0.0f, 0.0f};
    s->emitter = -1;
    s->wi = tb_dvec3_to_f(wi);
    s->dist = (float)dist;
    s->point = l->position;
    s->L = tb_channels_scale(l->intensity, (float)(k / (dist * dist)));
    s->shadow = tb_ray_make(p, tb_dvec3_to_f(d), 0.0f, 1.0f - TB_SHADOW_EPSILON);
    return !tb_channels_is_black(s->L);
}

bool tb_light_delta_at(const tb_light *l, tb_vec3 p, tb_vec3 *wi, float *dist, float *scale)
{
    /* The operations of tb_light_sample_li, without its 132-byte record. */
    if (l->kind == TB_LIGHT_DIRECTIONAL) {
        *wi = tb_vec3_neg(l->axis);
        *dist = INFINITY;
        *scale = 1.0f;
        return true;
    }
    tb_dvec3 d = tb_dvec3_sub(tb__d(l->position), tb__d(p));
    double dd = tb_dvec3_length(d);
    if (!(dd > 0.0) || !isfinite(dd))
        return false;
    tb_dvec3 w = tb_dvec3_scale(d, 1.0 / dd);
    double k = tb__shape(l, tb_dvec3_neg(w));
    if (!(k > 0.0))
        return false;
    *wi = tb_dvec3_to_f(w);
    *dist = (float)dd;
    *scale = (float)(k / (dd * dd));
    return true;
}

/* World direction of a photometric-frame direction of light l. */
static tb_vec3 tb__from_photometric(const tb_light *l, tb_vec3 v)
{
    tb_dvec3 x = tb__d(l->xaxis), axis = tb__d(l->axis), y = tb_dvec3_cross(x, axis);
    tb_dvec3 w = tb_dvec3_add(tb_dvec3_add(tb_dvec3_scale(x, v.x), tb_dvec3_scale(y, v.y)),
                              tb_dvec3_scale(axis, -(double)v.z));
    return tb_dvec3_to_f(tb_dvec3_normalize(w));
}

bool tb_light_sample_emission(const tb_light *l, float u1, float u2, tb_vec3 *w, double *pdf,
                              tb_channels *intensity)
{
    if (l->kind == TB_LIGHT_DIRECTIONAL)
        return false;
    if (l->ies) {
        tb_vec3 v = tb_ies_sample(l->ies, u1, u2, pdf);
        *w = tb__from_photometric(l, v);
    } else if (l->kind == TB_LIGHT_SPOT) {
        tb_vec3 v = tb_sample_uniform_cone(u1, u2, l->cos_total);
        tb_dvec3 axis = tb__d(l->axis), b1, b2;
        tb_dvec3_basis(axis, &b1, &b2);
        tb_dvec3 d = tb_dvec3_add(tb_dvec3_add(tb_dvec3_scale(b1, v.x), tb_dvec3_scale(b2, v.y)),
                                  tb_dvec3_scale(axis, v.z));
        *w = tb_dvec3_to_f(tb_dvec3_normalize(d));
        *pdf = tb_uniform_cone_pdf(l->cos_total);
    } else {
        *w = tb_sample_uniform_sphere(u1, u2);
        *pdf = TB_INV_4PI;
    }
    *intensity = tb_light_intensity(l, *w);
    return *pdf > 0.0;
}

tb_channels tb_light_power(const tb_light *l, double scene_radius)
{
    double k;
    if (l->kind == TB_LIGHT_DIRECTIONAL) {
        k = TB_PI * scene_radius * scene_radius;
    } else if (!l->ies) {
        k = l->kind == TB_LIGHT_POINT
                ? 4.0 * TB_PI
                : TB_2PI * ((1.0 - l->cos_falloff) + 0.5 * (l->cos_falloff - l->cos_total));
    } else if (l->kind == TB_LIGHT_POINT) {
        k = tb_ies_flux(l->ies) / l->ies->max_candela;
    } else {
        /* Midpoint rule over the cone in (cos theta, phi) about the axis. */
        enum { NC = 2048, NP = 256 };
        tb_dvec3 axis = tb__d(l->axis), b1, b2;
        tb_dvec3_basis(axis, &b1, &b2);
        double sum = 0.0, dz = (1.0 - l->cos_total) / NC;
        for (int i = 0; i < NC; i++) {
            double z = l->cos_total + (i + 0.5) * dz, r = sqrt(fmax(0.0, 1.0 - z * z));
            for (int j = 0; j < NP; j++) {
                double ph = TB_2PI * (j + 0.5) / NP;
                tb_dvec3 w = tb_dvec3_add(tb_dvec3_add(tb_dvec3_scale(b1, r * cos(ph)),
                                                       tb_dvec3_scale(b2, r * sin(ph))),
                                          tb_dvec3_scale(axis, z));
                sum += tb__shape(l, w);
            }
        }
        k = sum * dz * TB_2PI / NP;
    }
    return tb_channels_scale(l->intensity, (float)k);
}

/* ----------------------------------------------------------- emitters */

tb_emitter tb_emitter_triangle(tb_vec3 a, tb_vec3 b, tb_vec3 c, tb_channels L)
{
    return (tb_emitter){.kind = TB_EMITTER_TRIANGLE, .v = {a, b, c}, .radiance = L};
}

tb_emitter tb_emitter_parallelogram(tb_vec3 corner, tb_vec3 p1, tb_vec3 p2, tb_channels L)
{
    return (tb_emitter){.kind = TB_EMITTER_PARALLELOGRAM, .v = {corner, p1, p2}, .radiance = L};
}

tb_emitter tb_emitter_disc(tb_vec3 centre, tb_vec3 normal, float radius, tb_channels L)
{
    tb_vec3 n = tb_dvec3_to_f(tb_dvec3_normalize(tb__d(normal)));
    return (tb_emitter){.kind = TB_EMITTER_DISC, .v = {centre, n, {0, 0, 0}}, .radius = radius,
                        .radiance = L};
}

tb_emitter tb_emitter_sphere(tb_vec3 centre, float radius, tb_channels L)
{
    return (tb_emitter){.kind = TB_EMITTER_SPHERE, .v = {centre, {0, 0, 0}, {0, 0, 0}},
                        .radius = radius, .radiance = L};
}

tb_channels tb_radiance_from_exitance(tb_channels M) { return tb_channels_scale(M, (float)TB_INV_PI); }

/* Edge vectors and the (unnormalised) front normal of a planar polygon emitter. */
static tb_dvec3 tb__plane(const tb_emitter *e, tb_dvec3 *e1, tb_dvec3 *e2)
{
    *e1 = tb_dvec3_sub(tb__d(e->v[1]), tb__d(e->v[0]));
    *e2 = tb_dvec3_sub(tb__d(e->v[2]), tb__d(e->v[0]));
    return tb_dvec3_cross(*e1, *e2);
}

double tb_emitter_area(const tb_emitter *e)
{
    tb_dvec3 e1, e2;
    switch (e->kind) {
    case TB_EMITTER_TRIANGLE:
        return 0.5 * tb_dvec3_length(tb__plane(e, &e1, &e2));
    case TB_EMITTER_PARALLELOGRAM:
        return tb_dvec3_length(tb__plane(e, &e1, &e2));
    case TB_EMITTER_DISC:
        return TB_PI * (double)e->radius * e->radius;
    case TB_EMITTER_SPHERE:
        return 4.0 * TB_PI * (double)e->radius * e->radius;
    default:
        return e->area;
    }
}

bool tb_emitter_intersect(const tb_emitter *e, tb_vec3 of, tb_vec3 df, double *t, tb_vec3 *q, tb_vec3 *n)
{
    tb_dvec3 o = tb__d(of), d = tb__d(df);
    tb_dvec3 e1, e2, nn;
    double tt;
    switch (e->kind) {
    case TB_EMITTER_TRIANGLE:
    case TB_EMITTER_PARALLELOGRAM: {
        /* Moller-Trumbore: o + t d = v0 + s e1 + r e2. */
        nn = tb__plane(e, &e1, &e2);
        tb_dvec3 pv = tb_dvec3_cross(d, e2);
        double det = tb_dvec3_dot(e1, pv);
        if (det == 0.0)
            return false;
        tb_dvec3 tv = tb_dvec3_sub(o, tb__d(e->v[0]));
        double s = tb_dvec3_dot(tv, pv) / det;
        tb_dvec3 qv = tb_dvec3_cross(tv, e1);
        double r = tb_dvec3_dot(d, qv) / det;
        tt = tb_dvec3_dot(e2, qv) / det;
        if (s < 0.0 || r < 0.0 || s > 1.0 || r > 1.0)
            return false;
        if (e->kind == TB_EMITTER_TRIANGLE && s + r > 1.0)
            return false;
        break;
    }
    case TB_EMITTER_DISC: {
        nn = tb__d(e->v[1]);
        double dn = tb_dvec3_dot(d, nn);
        if (dn == 0.0)
            return false;
        tb_dvec3 c = tb__d(e->v[0]);
        tt = tb_dvec3_dot(tb_dvec3_sub(c, o), nn) / dn;
        tb_dvec3 x = tb_dvec3_sub(tb_dvec3_add(o, tb_dvec3_scale(d, tt)), c);
        if (tb_dvec3_length2(x) > (double)e->radius * e->radius)
            return false;
        break;
    }
    case TB_EMITTER_SPHERE: {
        tb_dvec3 c = tb__d(e->v[0]), oc = tb_dvec3_sub(o, c);
        double a = tb_dvec3_dot(d, d), b = tb_dvec3_dot(oc, d);
        /* Discriminant from the distance of the centre to the line (no cancellation). */
        tb_dvec3 perp = tb_dvec3_sub(oc, tb_dvec3_scale(d, b / a));
        double r = e->radius, disc = r * r - tb_dvec3_length2(perp);
        if (disc < 0.0)
            return false;
        double h = sqrt(a * disc);
        double q1 = -(b + copysign(h, b));
        double t0 = q1 / a, t1 = tb_dvec3_dot(oc, oc) - r * r;
        t1 = q1 != 0.0 ? t1 / q1 : t0;
        double lo = fmin(t0, t1), hi = fmax(t0, t1);
        tt = lo > 0.0 ? lo : hi;
        nn = tb_dvec3_sub(tb_dvec3_add(o, tb_dvec3_scale(d, tt)), c);
        break;
    }
    case TB_EMITTER_CUSTOM:
        return e->intersect && e->intersect(e->ctx, of, df, 0.0, t, q, n);
    default:
        return false;
    }
    if (!(tt > 0.0) || !isfinite(tt))
        return false;
    *t = tt;
    *q = tb_dvec3_to_f(tb_dvec3_add(o, tb_dvec3_scale(d, tt)));
    *n = tb_dvec3_to_f(tb_dvec3_normalize(nn));
    return true;
}

tb_channels tb_emitter_radiance(const tb_emitter *e, tb_vec3 n, tb_vec3 w)
{
    float c = tb_vec3_dot(n, w);
    if (c > 0.0f || (c < 0.0f && e->two_sided))
        return e->radiance;
    return tb__black(e->radiance.n);
}

/* ------------------------------------------------------------ area lights */

void tb_area_light_release(tb_area_light *a)
{
    if (!a)
        return;
    if (!a->shared)
        free(a->emitters);
    free(a->areas);
    tb_distrib1d_release(&a->select);
    *a = (tb_area_light){0};
}

/* tb_area_light_init, copying the emitters or (shared) pointing at them. */
static tb_status tb__area_light_init(tb_area_light *a, const tb_emitter *e, int n, bool shared)
{
    *a = (tb_area_light){0};
    if (!e || n < 1)
        return tb_error(TB_ERR_ARG, "area light: needs at least one emitter (got %d)", n);
    a->shared = shared;
    a->emitters = shared ? (tb_emitter *)e : malloc(sizeof(tb_emitter) * (size_t)n);
    a->areas = malloc(sizeof(double) * (size_t)n);
    double *w = malloc(sizeof(double) * (size_t)n);
    if (!a->emitters || !a->areas || !w) {
        free(w);
        tb_area_light_release(a);
        return tb_error(TB_ERR_NOMEM, "area light: out of memory for %d emitters", n);
    }
    if (!shared)
        memcpy(a->emitters, e, sizeof(tb_emitter) * (size_t)n);
    a->n = n;
    tb_status st = TB_OK;
    for (int i = 0; i < n && !st; i++) {
        const tb_emitter *x = &e[i];
        double area = tb_emitter_area(x);
        a->areas[i] = area;
        if (!(area > 0.0) || !isfinite(area))
            st = tb_error(TB_ERR_ARG, "area light: emitter %d has area %g", i, area);
        else if (x->kind == TB_EMITTER_DISC && !(fabsf(tb_vec3_length(x->v[1]) - 1.0f) < 1e-3f))
            st = tb_error(TB_ERR_ARG, "area light: disc %d has no unit normal", i);
        else if (x->kind == TB_EMITTER_CUSTOM && (!x->sample || !x->pdf))
            st = tb_error(TB_ERR_ARG, "area light: custom emitter %d has no callbacks", i);
        else if (x->kind < TB_EMITTER_TRIANGLE || x->kind > TB_EMITTER_CUSTOM)
            st = tb_error(TB_ERR_ARG, "area light: emitter %d has unknown kind %d", i, (int)x->kind);
        else if (x->radiance.n < 1 || x->radiance.n > TB_CHANNELS_MAX || x->radiance.n != e[0].radiance.n)
            st = tb_error(TB_ERR_ARG, "area light: emitter %d has %d channels (emitter 0: %d)", i,
                          x->radiance.n, e[0].radiance.n);
        if (st)
            break;
        for (int c = 0; c < x->radiance.n; c++)
            if (!(x->radiance.v[c] >= 0.0f) || !isfinite(x->radiance.v[c]))
                st = tb_error(TB_ERR_ARG, "area light: emitter %d has radiance %g in channel %d", i,
                              x->radiance.v[c], c);
        w[i] = area * tb_channels_average(x->radiance) * (x->two_sided ? 2.0 : 1.0);
        a->power += TB_PI * w[i];
    }
    if (!st)
        st = tb_distrib1d_init(&a->select, w, n);
    free(w);
    if (st) {
        tb_area_light_release(a);
        return tb_error_context(st, "area light");
    }
    return TB_OK;
}

tb_status tb_area_light_init(tb_area_light *a, const tb_emitter *e, int n) { return tb__area_light_init(a, e, n, false); }

tb_status tb_area_light_init_shared(tb_area_light *a, const tb_emitter *e, int n)
{
    return tb__area_light_init(a, e, n, true);
}

/* max(x, 0), NaN -> 0: what fmax(0.0, x) gives for these arguments (never
 * -0: they are 1 - y), by a comparison instead of a libm call on the area
 * light's per-sample path. */
static inline double tb__pos(double x)
{
    return x > 0.0 ? x : 0.0;
}

/* Sphere seen from outside: sin^2 and 1 - cos of the half-angle of the cone
 * it subtends at distance dc (> r). */
static void tb__cone(double r, double dc, double *sin2, double *one_minus_cos)
{
    double s2 = (r / dc) * (r / dc);
    *sin2 = s2;
    /* 1 - sqrt(1 - s2) = s2 / (1 + sqrt(1 - s2)): no cancellation for small spheres. */
    *one_minus_cos = s2 / (1.0 + sqrt(tb__pos(1.0 - s2)));
}

/* The per-point values of sphere emitter i (e) seen from at->pf. */
static void tb__sphere_at(const tb_emitter *e, int i, tb_dvec3 p, tb_area_light_at *at)
{
    tb_dvec3 c = tb__d(e->v[0]), pc = tb_dvec3_sub(p, c);
    double r = e->radius, dc = tb_dvec3_length(pc);
    at->emitter = i;
    at->c = c;
    at->dc = dc;
    at->outside = dc > r * (1.0 + 1e-7);
    if (!at->outside)
        return;
    tb__cone(r, dc, &at->s2max, &at->omc_max);
    at->sqrt_s2max = sqrt(at->s2max);
    at->axis = tb_dvec3_scale(pc, 1.0 / dc);
    tb_dvec3_basis(at->axis, &at->b1, &at->b2);
}

/* Samples emitter e (index i) seen from p = at->pf: point q, front normal
 * nq, solid-angle density. */
static bool tb__sample_emitter(const tb_emitter *e, int i, double area, tb_dvec3 p, tb_area_light_at *at,
                               float u1, float u2, tb_dvec3 *q, tb_dvec3 *nq, double *pdf_sa)
{
    double pdf_a = 1.0 / area;
    switch (e->kind) {
    case TB_EMITTER_TRIANGLE: {
        tb_vec2 b = tb_sample_triangle(u1, u2);
        double b0 = b.x, b1 = b.y, b2 = 1.0 - b0 - b1;
        *q = tb_dvec3_add(tb_dvec3_add(tb_dvec3_scale(tb__d(e->v[0]), b0), tb_dvec3_scale(tb__d(e->v[1]), b1)),
                          tb_dvec3_scale(tb__d(e->v[2]), b2));
        tb_dvec3 e1, e2;
        *nq = tb_dvec3_normalize(tb__plane(e, &e1, &e2));
        break;
    }
    case TB_EMITTER_PARALLELOGRAM: {
        tb_dvec3 e1, e2;
        *nq = tb_dvec3_normalize(tb__plane(e, &e1, &e2));
        *q = tb_dvec3_add(tb__d(e->v[0]), tb_dvec3_add(tb_dvec3_scale(e1, u1), tb_dvec3_scale(e2, u2)));
        break;
    }
    case TB_EMITTER_DISC: {
        tb_vec2 d = tb_sample_disk_concentric(u1, u2);
        tb_dvec3 n = tb__d(e->v[1]), b1, b2;
        tb_dvec3_basis(n, &b1, &b2);
        double r = e->radius;
        *q = tb_dvec3_add(tb__d(e->v[0]), tb_dvec3_add(tb_dvec3_scale(b1, r * d.x), tb_dvec3_scale(b2, r * d.y)));
        *nq = n;
        break;
    }
    case TB_EMITTER_SPHERE: {
        if (at->emitter != i)
            tb__sphere_at(e, i, p, at);
        tb_dvec3 c = at->c;
        double r = e->radius;
        if (at->outside) {
            /* Uniform in the cone of directions the sphere subtends (the
             * visible cap): theta from the axis p -> c, then the point where
             * that direction meets the sphere, found through the angle alpha
             * at the centre (sin alpha / sin theta = dc / r). */
            double s2max = at->s2max, omc_max = at->omc_max;
            double omc = u1 * omc_max; /* 1 - cos theta, uniform */
            double ct = 1.0 - omc, s2 = omc * (2.0 - omc);
            double cos_alpha = s2 / at->sqrt_s2max + ct * sqrt(tb__pos(1.0 - s2 / s2max));
            double sin_alpha = sqrt(tb__pos(1.0 - cos_alpha * cos_alpha));
            double cphi, sphi; /* of phi = 2 pi u2, uniform about the axis */
            tb_sincos_2pi(u2, &cphi, &sphi);
            *nq = tb_dvec3_add(tb_dvec3_add(tb_dvec3_scale(at->b1, sin_alpha * cphi),
                                            tb_dvec3_scale(at->b2, sin_alpha * sphi)),
                               tb_dvec3_scale(at->axis, cos_alpha));
            *nq = tb_dvec3_normalize(*nq);
            *q = tb_dvec3_add(c, tb_dvec3_scale(*nq, r));
            *pdf_sa = 1.0 / (TB_2PI * omc_max);
            return true;
        }
        if (!e->two_sided)
            return false; /* inside a sphere that emits outward */
        tb_vec3 w = tb_sample_uniform_sphere(u1, u2);
        *nq = tb__d(w);
        *q = tb_dvec3_add(c, tb_dvec3_scale(*nq, r));
        break;
    }
    case TB_EMITTER_CUSTOM: {
        tb_vec3 qf, nf;
        if (!e->sample(e->ctx, u1, u2, &qf, &nf, &pdf_a) || !(pdf_a > 0.0))
            return false;
        *q = tb__d(qf);
        *nq = tb_dvec3_normalize(tb__d(nf));
        break;
    }
    default:
        return false;
    }
    /* Area density to solid angle: pdf_A d^2 / |cos theta_q|. */
    tb_dvec3 d = tb_dvec3_sub(*q, p);
    double d2 = tb_dvec3_length2(d);
    double cq = -tb_dvec3_dot(*nq, d) / sqrt(d2);
    if (!(d2 > 0.0) || cq == 0.0 || (cq < 0.0 && !e->two_sided))
        return false;
    *pdf_sa = pdf_a * d2 / fabs(cq);
    return isfinite(*pdf_sa);
}

void tb_area_light_at_init(tb_area_light_at *at, tb_vec3 p)
{
    *at = (tb_area_light_at){.pf = p, .emitter = -1};
}

/* The sample that gives no light: zeroed, with the channel count. */
static bool tb__no_sample(const tb_area_light *a, tb_light_sample *s)
{
    *s = (tb_light_sample){0};
    s->L.n = tb__black_n(a->emitters[0].radiance.n);
    s->emitter = -1;
    return false;
}

bool tb_area_light_sample_at(const tb_area_light *a, tb_area_light_at *at, float u1, float u2,
                             tb_light_sample *s)
{
    double pmf, ur;
    int i = tb_distrib1d_sample_discrete(&a->select, u1, &pmf, &ur);
    float u1r = (float)ur;
    if (u1r >= 1.0f)
        u1r = 0x1.fffffep-1f;
    const tb_emitter *e = &a->emitters[i];
    const tb_vec3 pf = at->pf;
    tb_dvec3 p = tb__d(pf), q, nq;
    double pdf;
    if (!tb__sample_emitter(e, i, a->areas[i], p, at, u1r, u2, &q, &nq, &pdf))
        return tb__no_sample(a, s);
    tb_dvec3 d = tb_dvec3_sub(q, p);
    double dist = tb_dvec3_length(d);
    if (!(dist > 0.0))
        return tb__no_sample(a, s);
    /* Every field set (no zeroing of the whole record first). */
    s->L = e->radiance;
    s->wi = tb_dvec3_to_f(tb_dvec3_scale(d, 1.0 / dist));
    s->dist = (float)dist;
    s->pdf = pmf * pdf;
    s->delta = false;
    s->point = tb_dvec3_to_f(q);
    s->normal = tb_dvec3_to_f(nq);
    s->emitter = i;
    s->shadow = tb_ray_make(pf, tb_dvec3_to_f(d), 0.0f, 1.0f - TB_SHADOW_EPSILON);
    return s->pdf > 0.0 && !tb_channels_is_black(s->L);
}

bool tb_area_light_sample(const tb_area_light *a, tb_vec3 pf, float u1, float u2, tb_light_sample *s)
{
    tb_area_light_at at;
    tb_area_light_at_init(&at, pf);
    return tb_area_light_sample_at(a, &at, u1, u2, s);
}

double tb_area_light_pdf(const tb_area_light *a, int emitter, tb_vec3 pf, tb_vec3 qf, tb_vec3 nqf)
{
    if (emitter < 0 || emitter >= a->n)
        return 0.0;
    const tb_emitter *e = &a->emitters[emitter];
    double pmf = tb_distrib1d_pmf(&a->select, emitter);
    tb_dvec3 p = tb__d(pf), q = tb__d(qf), nq = tb_dvec3_normalize(tb__d(nqf));
    if (e->kind == TB_EMITTER_SPHERE) {
        tb_dvec3 c = tb__d(e->v[0]), pc = tb_dvec3_sub(p, c);
        double r = e->radius, dc = tb_dvec3_length(pc);
        if (dc > r * (1.0 + 1e-7)) {
            double s2max, omc_max;
            tb__cone(r, dc, &s2max, &omc_max);
            return pmf / (TB_2PI * omc_max);
        }
        if (!e->two_sided)
            return 0.0;
    }
    double pdf_a = e->kind == TB_EMITTER_CUSTOM ? e->pdf(e->ctx, qf) : 1.0 / a->areas[emitter];
    tb_dvec3 d = tb_dvec3_sub(q, p);
    double d2 = tb_dvec3_length2(d);
    if (!(d2 > 0.0))
        return 0.0;
    double cq = -tb_dvec3_dot(nq, d) / sqrt(d2);
    if (cq == 0.0 || (cq < 0.0 && !e->two_sided))
        return 0.0;
    return pmf * pdf_a * d2 / fabs(cq);
}

double tb_area_light_pdf_line(const tb_area_light *a, int emitter, tb_vec3 p, tb_vec3 w)
{
    if (emitter < 0 || emitter >= a->n)
        return 0.0;
    const tb_emitter *e = &a->emitters[emitter];
    double t;
    tb_vec3 q, nq;
    if (e->kind != TB_EMITTER_CUSTOM || !e->intersect)
        return tb_emitter_intersect(e, p, w, &t, &q, &nq) ? tb_area_light_pdf(a, emitter, p, q, nq) : 0.0;
    /* Every crossing: the sampler may return any point of the surface that
     * faces p, hidden ones included (a torus seen through its hole). */
    double pdf = 0.0, tmin = 0.0;
    for (int k = 0; k < 64 && e->intersect(e->ctx, p, w, tmin, &t, &q, &nq); k++) {
        pdf += tb_area_light_pdf(a, emitter, p, q, nq);
        /* past this crossing: the float ray parameter's resolution */
        double next = t * (1.0 + 0x1p-20) + 0x1p-60;
        if (!(next > tmin))
            break;
        tmin = next;
    }
    return pdf;
}

tb_channels tb_area_light_irradiance(const tb_area_light *a, tb_vec3 p, tb_vec3 n, int n_samples,
                                     tb_rng *rng, tb_occluded_fn occluded, void *ctx)
{
    int nch = a->emitters[0].radiance.n;
    double acc[TB_CHANNELS_MAX] = {0};
    if (n_samples < 1)
        n_samples = 1;
    int nx, ny;
    tb_stratified_dims(n_samples, &nx, &ny);
    for (int k = 0; k < nx * ny; k++) {
        float j1 = tb_rng_float(rng), j2 = tb_rng_float(rng), u1, u2;
        tb_stratified_point(nx, ny, k, j1, j2, &u1, &u2);
        tb_light_sample s;
        if (!tb_area_light_sample(a, p, u1, u2, &s))
            continue;
        double c = tb_vec3_dot(n, s.wi);
        if (!(c > 0.0))
            continue;
        if (occluded && occluded(ctx, &s.shadow))
            continue;
        double k2 = c / s.pdf;
        for (int i = 0; i < nch; i++)
            acc[i] += s.L.v[i] * k2;
    }
    tb_channels E = tb__black(nch);
    for (int i = 0; i < nch; i++)
        E.v[i] = (float)(acc[i] / (nx * ny));
    return E;
}
