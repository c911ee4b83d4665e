/* Point, spot and directional lights as radiosity sources
 * (host/radiosity/lights.h) against exact answers: a point light over a
 * plane (element means against an independent quadrature, corners against
 * I cos / r^2), a spot light's cone and falloff, a directional light with an
 * occluder, an IES distribution, energy in a closed box, a light outside a closed box, spectral
 * bands, the hemicube path, adaptive refinement and thread independence. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
#include <omp.h>

#include "host/radiosity/adaptive.h"
#include "host/radiosity/lights.h"
#include "host/radiosity/radiosity.h"
#include "tb_test.h"

#define TB__PI 3.14159265358979323846

/* Appends a planar grid of nu x nv quads: corner o, edges u and v (front
 * side: u x v), reflectance rho (all channels), to m (nchannels set). */
static void tb__grid(tb_rad_mesh *m, tb_vec3 o, tb_vec3 u, tb_vec3 v, int nu, int nv, float rho, uint32_t object)
{
    size_t v0 = m->nverts, e0 = m->nelems, nc = (size_t)m->nchannels;
    size_t addv = (size_t)(nu + 1) * (size_t)(nv + 1), adde = (size_t)nu * (size_t)nv;
    m->verts = realloc(m->verts, sizeof *m->verts * (v0 + addv));
    m->elems = realloc(m->elems, sizeof *m->elems * (e0 + adde));
    m->rho = realloc(m->rho, sizeof *m->rho * (e0 + adde) * nc);
    m->emission = realloc(m->emission, sizeof *m->emission * (e0 + adde) * nc);
    assert_true(m->verts && m->elems && m->rho && m->emission);
    tb_vec3 n = tb_vec3_normalize(tb_vec3_cross(u, v));
    for (int j = 0; j <= nv; j++)
        for (int i = 0; i <= nu; i++) {
            tb_rad_vertex *x = &m->verts[v0 + (size_t)j * (size_t)(nu + 1) + (size_t)i];
            x->p = tb_vec3_add(o, tb_vec3_add(tb_vec3_scale(u, (float)i / (float)nu),
                                              tb_vec3_scale(v, (float)j / (float)nv)));
            x->n = n;
        }
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++) {
            size_t e = e0 + (size_t)j * (size_t)nu + (size_t)i;
            uint32_t a = (uint32_t)(v0 + (size_t)j * (size_t)(nu + 1) + (size_t)i);
            m->elems[e] = (tb_rad_element){.v = {a, a + 1, a + 1 + (uint32_t)(nu + 1), a + (uint32_t)(nu + 1)},
                                           .object = object, .parent = TB_RAD_NONE};
            for (size_t c = 0; c < nc; c++)
                m->rho[e * nc + c] = rho, m->emission[e * nc + c] = 0.0f;
        }
    m->nverts += addv;
    m->nelems += adde;
}

static void tb__mesh(tb_rad_mesh *m, int nc)
{
    tb_rad_mesh_init(m);
    m->nchannels = nc;
}

/* The floor z = 0, [-2, 2]^2, n x n elements. */
static void tb__floor(tb_rad_mesh *m, int n, float rho)
{
    tb__grid(m, tb_vec3_make(-2, -2, 0), tb_vec3_make(4, 0, 0), tb_vec3_make(0, 4, 0), n, n, rho, 0);
}

static tb_rad_solver *tb__create(const tb_rad_mesh *m, const tb_light *l, int n, tb_rad_ff_method ff)
{
    tb_rad_options o = {.ff = ff, .samples = 16, .lights = l, .nlights = n};
    tb_rad_solver *s = NULL;
    if (tb_rad_solver_create(m, NULL, &o, &s))
        fail_msg("%s", tb_last_error());
    return s;
}

static void tb__run(tb_rad_solver *s, double thr, uint64_t shots)
{
    tb_rad_stop stop = {.threshold = thr, .max_shots = shots};
    if (tb_rad_solver_run(s, &stop, NULL, NULL, 0))
        fail_msg("%s", tb_last_error());
}

/* The test's own spot falloff (docs/lights.md): smoothstep in cos theta. */
static double tb__falloff(double cos_total, double cos_falloff, double c)
{
    if (c <= cos_total)
        return 0.0;
    if (c >= cos_falloff)
        return 1.0;
    double t = (c - cos_total) / (cos_falloff - cos_total);
    return t * t * (3.0 - 2.0 * t);
}

/* Irradiance on the floor (normal +z) at (x, y) from a light at (lx, ly, h)
 * of axis intensity I pointing down (spot: cones; point: ct = -2). */
static double tb__E(double x, double y, double lx, double ly, double h, double I, double ct, double cf)
{
    double dx = x - lx, dy = y - ly, r2 = dx * dx + dy * dy + h * h, r = sqrt(r2);
    double cs = h / r; /* angle to the downward axis = angle of incidence */
    double f = ct < -1.0 ? 1.0 : tb__falloff(ct, cf, cs);
    return I * f * cs / r2;
}

/* The mean of tb__E over floor element e by a q x q midpoint rule. */
static double tb__E_mean(const tb_rad_mesh *m, size_t e, int q, double lx, double ly, double h, double I, double ct,
                         double cf)
{
    const tb_rad_element *el = &m->elems[e];
    tb_vec3 a = m->verts[el->v[0]].p, b = m->verts[el->v[2]].p;
    double sum = 0.0;
    for (int j = 0; j < q; j++)
        for (int i = 0; i < q; i++) {
            double x = a.x + (b.x - a.x) * (i + 0.5) / q, y = a.y + (b.y - a.y) * (j + 0.5) / q;
            sum += tb__E(x, y, lx, ly, h, I, ct, cf);
        }
    return sum / ((double)q * q);
}

/* The same mean over any element (triangle or convex quad, in z = 0): q x q
 * sub-triangles of (v0 v1 v2) and (v0 v2 v3), centroid rule. */
static double tb__E_mean_poly(const tb_rad_mesh *m, size_t e, int q, double lx, double ly, double h, double I)
{
    const tb_rad_element *el = &m->elems[e];
    int nk = el->v[3] == TB_RAD_NONE ? 3 : 4;
    double sum = 0.0, area = 0.0;
    for (int t = 0; t + 2 < nk; t++) {
        tb_vec3 p0 = m->verts[el->v[0]].p, p1 = m->verts[el->v[t + 1]].p, p2 = m->verts[el->v[t + 2]].p;
        double ux = p1.x - p0.x, uy = p1.y - p0.y, vx = p2.x - p0.x, vy = p2.y - p0.y;
        double at = 0.5 * fabs(ux * vy - uy * vx), cell = at / ((double)q * q);
        for (int i = 0; i < q; i++)
            for (int j = 0; j < q - i; j++)
                for (int d = 0; d < 2; d++) {
                    if (d && i + j >= q - 1)
                        continue;
                    double u = d ? (i + 2.0 / 3.0) / q : (i + 1.0 / 3.0) / q;
                    double v = d ? (j + 2.0 / 3.0) / q : (j + 1.0 / 3.0) / q;
                    sum += cell * tb__E(p0.x + u * ux + v * vx, p0.y + u * uy + v * vy, lx, ly, h, I, -2, 0);
                }
        area += at;
    }
    return sum / area;
}

/* Point light over a plane: every element's B = rho x the element mean of
 * I cos / r^2 (independent 128 x 128 midpoint quadrature), per channel;
 * every corner value rho I cos / r^2 at the vertex (the receiver sits 1e-3
 * of the way to the element centroid). One shot (the light) is the whole
 * answer: a plane does not see itself. */
static void test_point_plane(void **state)
{
    (void)state;
    tb_rad_mesh m;
    tb__mesh(&m, 3);
    tb__floor(&m, 16, 0.3f);
    assert_int_equal(tb_rad_mesh_update_geometry(&m), TB_OK);
    const double lx = 0.3, ly = 0.2, h = 1.0, I[3] = {2.0, 1.0, 0.5};
    tb_light l = tb_light_point(tb_vec3_make((float)lx, (float)ly, (float)h), tb_channels_rgb(2.0f, 1.0f, 0.5f));
    tb_rad_solver *s = tb__create(&m, &l, 1, TB_RAD_FF_RAYCAST);
    assert_true(tb_rad_unshot_fraction(s) == 1.0);
    tb__run(s, 1e-3, 1);
    assert_int_equal(tb_rad_solver_shots(s), 1);
    double b[TB_CHANNELS_MAX], worst_e = 0.0, worst_c = 0.0, worst_centre = 0.0;
    for (size_t e = 0; e < m.nelems; e++) {
        tb_rad_element_radiosity(s, e, false, b);
        double want = 0.3 * tb__E_mean(&m, e, 128, lx, ly, h, 1.0, -2, 0);
        for (int c = 0; c < 3; c++)
            worst_e = fmax(worst_e, fabs(b[c] - I[c] * want) / (I[c] * want));
        tb_vec3 cc = m.elems[e].centroid;
        worst_centre = fmax(worst_centre, fabs(b[0] - 0.3 * I[0] * tb__E(cc.x, cc.y, lx, ly, h, 1, -2, 0)) / b[0]);
        for (int k = 0; k < 4; k++) {
            tb_rad_corner_radiosity(s, e, k, false, b);
            tb_vec3 p = m.verts[m.elems[e].v[k]].p;
            double w = 0.3 * tb__E(p.x, p.y, lx, ly, h, 1.0, -2, 0);
            for (int c = 0; c < 3; c++)
                worst_c = fmax(worst_c, fabs(b[c] - I[c] * w) / (I[c] * w));
        }
    }
    print_message("point light over a plane: element means %.2e, corners %.2e (relative); element mean vs the "
                  "centroid value %.2e\n",
                  worst_e, worst_c, worst_centre);
    assert_true(worst_e < 2e-5);
    assert_true(worst_c < 1e-3);
    /* bookkeeping: the light's 4 pi I per channel; what missed the plane escaped */
    tb_rad_energy en = tb_rad_solver_energy(s);
    assert_true(fabs(en.emitted - 4.0 * TB__PI * 3.5) < 1e-5 * en.emitted);
    assert_true(fabs(en.emitted - en.absorbed - en.unshot - en.escaped) < 1e-9 * en.emitted);
    tb_rad_solver_free(s);
    tb_rad_mesh_free(&m);
}

/* Spot light pointing down from height 1 (cone 30, falloff 10 degrees):
 * corners against I falloff(cos) cos / r^2, elements inside the full-beam
 * disc against the quadrature, elements wholly outside the cone exactly 0,
 * elements in the falloff ring against the quadrature (the cells' midpoint
 * rule in solid angle). */
static void test_spot_cone(void **state)
{
    (void)state;
    tb_rad_mesh m;
    tb__mesh(&m, 3);
    tb__floor(&m, 32, 0.5f);
    assert_int_equal(tb_rad_mesh_update_geometry(&m), TB_OK);
    const double h = 1.0, I = 3.0;
    tb_light l = tb_light_spot(tb_vec3_make(0, 0, (float)h), tb_vec3_make(0, 0, -1), tb_channels_splat(3, (float)I),
                               30.0, 10.0);
    double ct = l.cos_total, cf = l.cos_falloff;
    tb_rad_solver *s = tb__create(&m, &l, 1, TB_RAD_FF_RAYCAST);
    tb__run(s, 1e-3, 1);
    double b[TB_CHANNELS_MAX], worst_c = 0.0, worst_in = 0.0, worst_ring = 0.0, outside = 0.0;
    int n_in = 0, n_out = 0, n_ring = 0;
    double r_in = h * tan(20.0 * TB__PI / 180.0), r_out = h * tan(30.0 * TB__PI / 180.0);
    for (size_t e = 0; e < m.nelems; e++) {
        for (int k = 0; k < 4; k++) {
            tb_rad_corner_radiosity(s, e, k, false, b);
            tb_vec3 p = m.verts[m.elems[e].v[k]].p;
            double w = 0.5 * tb__E(p.x, p.y, 0, 0, h, I, ct, cf);
            worst_c = fmax(worst_c, fabs(b[0] - w) / (0.5 * I / (h * h))); /* relative to the peak */
        }
        /* nearest and farthest distance of the element from the axis */
        tb_vec3 a = m.verts[m.elems[e].v[0]].p, c = m.verts[m.elems[e].v[2]].p;
        double nx = fmax(0.0, fmax(a.x, -c.x)), ny = fmax(0.0, fmax(a.y, -c.y));
        double fx = fmax(fabs(a.x), fabs(c.x)), fy = fmax(fabs(a.y), fabs(c.y));
        double near = sqrt(nx * nx + ny * ny), far = sqrt(fx * fx + fy * fy);
        tb_rad_element_radiosity(s, e, false, b);
        double want = 0.5 * tb__E_mean(&m, e, 128, 0, 0, h, I, ct, cf);
        if (far < r_in)
            worst_in = fmax(worst_in, fabs(b[0] - want) / want), n_in++;
        else if (near > r_out)
            outside = fmax(outside, fabs(b[0])), n_out++;
        else
            worst_ring = fmax(worst_ring, fabs(b[0] - want) / (0.5 * I / (h * h))), n_ring++;
    }
    print_message("spot: corners %.2e of the peak; %d elements in the beam %.2e; %d in the falloff ring %.2e of the "
                  "peak; %d outside, largest B %g\n",
                  worst_c, n_in, worst_in, n_ring, worst_ring, n_out, outside);
    assert_true(n_in >= 8 && n_ring >= 16 && n_out > 900);
    assert_true(worst_c < 1e-3);
    assert_true(worst_in < 2e-5);
    assert_true(worst_ring < 2e-3);
    assert_true(outside == 0.0);
    tb_rad_solver_free(s);
    tb_rad_mesh_free(&m);
}

/* A point light with an IES distribution: tests/render/data/lambertian.ies
 * tabulates I = I0 cos(gamma) (5 degree steps, linearly interpolated), so on
 * the floor below E = I0 cos(gamma) cos(theta) / r^2 = I0 h^2 / r^4 at every
 * corner and in the element means (independent quadrature of the exact
 * cosine), to the table's interpolation error (at most about 1e-3). */
static double tb__E_ies(double x, double y, double h) { return h * h / pow(x * x + y * y + h * h, 2.0); }

static void test_ies(void **state)
{
    (void)state;
    tb_ies *ies = NULL;
    if (tb_ies_read(TB_SOURCE_DIR "/tests/render/data/lambertian.ies", &ies))
        fail_msg("%s", tb_last_error());
    tb_rad_mesh m;
    tb__mesh(&m, 3);
    tb__floor(&m, 16, 0.5f);
    assert_int_equal(tb_rad_mesh_update_geometry(&m), TB_OK);
    const double h = 0.8, I0 = 2.0;
    tb_light l = tb_light_point(tb_vec3_make(0, 0, (float)h), tb_channels_splat(3, (float)I0));
    l.ies = ies;
    tb_rad_solver *s = tb__create(&m, &l, 1, TB_RAD_FF_RAYCAST);
    tb__run(s, 1e-3, 1);
    double b[TB_CHANNELS_MAX], worst_c = 0.0, worst_e = 0.0;
    for (size_t e = 0; e < m.nelems; e++) {
        for (int k = 0; k < 4; k++) {
            tb_rad_corner_radiosity(s, e, k, false, b);
            tb_vec3 p = m.verts[m.elems[e].v[k]].p;
            double w = 0.5 * I0 * tb__E_ies(p.x, p.y, h);
            worst_c = fmax(worst_c, fabs(b[0] - w) / w);
        }
        const tb_rad_element *el = &m.elems[e];
        tb_vec3 a = m.verts[el->v[0]].p, c = m.verts[el->v[2]].p;
        double sum = 0.0;
        for (int j = 0; j < 128; j++)
            for (int i = 0; i < 128; i++)
                sum += tb__E_ies(a.x + (c.x - a.x) * (i + 0.5) / 128, a.y + (c.y - a.y) * (j + 0.5) / 128, h);
        double want = 0.5 * I0 * sum / (128.0 * 128.0);
        tb_rad_element_radiosity(s, e, false, b);
        worst_e = fmax(worst_e, fabs(b[0] - want) / want);
    }
    print_message("IES point light: corners %.2e, element means %.2e (relative)\n", worst_c, worst_e);
    assert_true(worst_c < 1.5e-3);
    assert_true(worst_e < 1.5e-3);
    /* its power: I0 x the table's flux over its maximum (about pi I0) */
    tb_rad_energy en = tb_rad_solver_energy(s);
    assert_true(fabs(en.emitted - 3.0 * I0 * TB__PI) < 1e-3 * en.emitted);
    tb_rad_solver_free(s);
    tb_rad_mesh_free(&m);
    tb_ies_free(ies);
}

/* Directional light straight down (E = 2) onto a floor (rho 0.5, [-1, 1]^2,
 * 16 x 16) under a square occluder [-0.45, 0.45]^2 at z = 0.5 facing the
 * floor. Black occluder: lit elements B = rho E, elements with every corner
 * in the shadow 0, the rest in between. Grey occluder: the same after the
 * light's shot; after solving, shadowed elements get only interreflection. */
static void tb__directional(float occ_rho, double *lit, double *shadow, double *shadow_after)
{
    tb_rad_mesh m;
    tb__mesh(&m, 3);
    tb__grid(&m, tb_vec3_make(-1, -1, 0), tb_vec3_make(2, 0, 0), tb_vec3_make(0, 2, 0), 16, 16, 0.5f, 0);
    size_t nfloor = m.nelems;
    /* facing down: u x v = -z */
    tb__grid(&m, tb_vec3_make(-0.45f, -0.45f, 0.5f), tb_vec3_make(0, 0.9f, 0), tb_vec3_make(0.9f, 0, 0), 2, 2, occ_rho,
             1);
    assert_int_equal(tb_rad_mesh_update_geometry(&m), TB_OK);
    tb_light l = tb_light_directional(tb_vec3_make(0, 0, -1), tb_channels_splat(3, 2.0f));
    tb_rad_solver *s = tb__create(&m, &l, 1, TB_RAD_FF_RAYCAST);
    tb__run(s, 1e-3, 1);
    double b[TB_CHANNELS_MAX];
    *lit = 0.0, *shadow = 0.0, *shadow_after = INFINITY;
    int n_lit = 0, n_sh = 0, n_mid = 0;
    unsigned char *inside = calloc(nfloor, 1);
    for (size_t e = 0; e < nfloor; e++) {
        int in = 0;
        for (int k = 0; k < 4; k++) {
            tb_vec3 p = m.verts[m.elems[e].v[k]].p;
            in += fabsf(p.x) < 0.45f && fabsf(p.y) < 0.45f;
        }
        tb_rad_element_radiosity(s, e, false, b);
        if (in == 0)
            *lit = fmax(*lit, fabs(b[0] - 1.0)), n_lit++;
        else if (in == 4)
            *shadow = fmax(*shadow, fabs(b[0])), n_sh++, inside[e] = 1;
        else
            assert_true(b[0] > 0.0 && b[0] < 1.0), n_mid++;
    }
    for (size_t e = nfloor; e < m.nelems; e++) { /* the occluder faces away from the light */
        tb_rad_element_radiosity(s, e, false, b);
        assert_true(b[0] == 0.0);
    }
    assert_int_equal(n_sh, 36);
    assert_int_equal(n_mid, 28);
    tb__run(s, 1e-4, 0);
    for (size_t e = 0; e < nfloor; e++)
        if (inside[e]) {
            tb_rad_element_radiosity(s, e, false, b);
            *shadow_after = fmin(*shadow_after, b[0]);
        }
    free(inside);
    tb_rad_solver_free(s);
    tb_rad_mesh_free(&m);
}

static void test_directional_shadow(void **state)
{
    (void)state;
    double lit, shadow, after;
    tb__directional(0.0f, &lit, &shadow, &after);
    print_message("directional, black occluder: lit |B - rho E| %.2e, shadowed B %g, after solving %g\n", lit,
                  shadow, after);
    assert_true(lit < 1e-6 && shadow == 0.0 && after == 0.0);
    tb__directional(0.8f, &lit, &shadow, &after);
    print_message("directional, grey occluder: lit %.2e, shadowed %g after the light, at least %g after solving\n",
                  lit, shadow, after);
    assert_true(lit < 1e-6 && shadow == 0.0);
    assert_true(after > 1e-3 && after < 0.3); /* interreflection only: well below rho E = 1 */
}

/* The closed unit cube (rho 0.5, 4 x 4 per face, inward) around a point
 * light. After the light's shot the faces have received all of 4 pi I (exact
 * solid angles): nothing escaped. Solved: emitted = absorbed + unshot +
 * escaped, and with uniform rho the total radiosity power sum B A is
 * rho P / (1 - rho) (every bounce), within the form-factor error. */
static void tb__box(tb_rad_mesh *m, int n, float rho)
{
    tb__mesh(m, 3);
    tb_vec3 X = tb_vec3_make(1, 0, 0), Y = tb_vec3_make(0, 1, 0), Z = tb_vec3_make(0, 0, 1), O = tb_vec3_make(0, 0, 0);
    tb__grid(m, O, X, Y, n, n, rho, 0); /* floor z = 0, normal +z */
    tb__grid(m, Z, Y, X, n, n, rho, 1); /* ceiling z = 1, normal -z */
    tb__grid(m, O, Z, X, n, n, rho, 2); /* y = 0, normal +y */
    tb__grid(m, Y, X, Z, n, n, rho, 3); /* y = 1, normal -y */
    tb__grid(m, O, Y, Z, n, n, rho, 4); /* x = 0, normal +x */
    tb__grid(m, X, Z, Y, n, n, rho, 5); /* x = 1, normal -x */
    assert_int_equal(tb_rad_mesh_update_geometry(m), TB_OK);
    for (size_t e = 0; e < m->nelems; e++) { /* inward */
        tb_vec3 d = tb_vec3_sub(tb_vec3_make(0.5f, 0.5f, 0.5f), m->elems[e].centroid);
        assert_true(tb_vec3_dot(d, m->elems[e].normal) > 0.0f);
    }
}

static void test_energy_box(void **state)
{
    (void)state;
    tb_rad_mesh m;
    tb__box(&m, 4, 0.5f);
    tb_light l = tb_light_point(tb_vec3_make(0.4f, 0.55f, 0.7f), tb_channels_rgb(1.0f, 2.0f, 0.5f));
    tb_rad_solver *s = tb__create(&m, &l, 1, TB_RAD_FF_RAYCAST);
    double P = 4.0 * TB__PI * 3.5;
    tb__run(s, 1e-3, 1);
    tb_rad_energy en = tb_rad_solver_energy(s);
    print_message("box, after the light: emitted %.9g (4 pi I %.9g), escaped %.3e\n", en.emitted, P, en.escaped);
    assert_true(fabs(en.emitted - P) < 1e-6 * P);
    assert_true(fabs(en.escaped) < 1e-6 * P);
    tb__run(s, 1e-3, 0);
    en = tb_rad_solver_energy(s);
    double sum = 0.0, b[TB_CHANNELS_MAX];
    for (size_t e = 0; e < m.nelems; e++) {
        tb_rad_element_radiosity(s, e, true, b);
        sum += (b[0] + b[1] + b[2]) * m.elems[e].area;
    }
    double want = 0.5 * P / (1.0 - 0.5);
    print_message("box solved: absorbed %.6g unshot %.3g escaped %.3g (%.2f%%); sum B A %.6g, rho P / (1 - rho) "
                  "%.6g (%.2f%%)\n",
                  en.absorbed, en.unshot, en.escaped, 100.0 * en.escaped / en.emitted, sum, want,
                  100.0 * (sum - want) / want);
    assert_true(fabs(en.emitted - en.absorbed - en.unshot - en.escaped) < 1e-9 * en.emitted);
    assert_true(en.escaped < 0.02 * en.emitted);
    assert_true(fabs(sum - want) < 0.03 * want);
    tb_rad_solver_free(s);

    /* a light outside the closed box: the walls block it (they must be
     * occluders for it although every mesh point is in front of them) */
    tb_light out = tb_light_point(tb_vec3_make(0.5f, 0.5f, 2.0f), tb_channels_splat(3, 1.0f));
    s = tb__create(&m, &out, 1, TB_RAD_FF_RAYCAST);
    tb__run(s, 1e-3, 0);
    for (size_t e = 0; e < m.nelems; e++) {
        tb_rad_element_radiosity(s, e, false, b);
        assert_true(b[0] == 0.0);
        for (int k = 0; k < 4; k++) {
            tb_rad_corner_radiosity(s, e, k, false, b);
            assert_true(b[0] == 0.0);
        }
    }
    en = tb_rad_solver_energy(s);
    assert_true(fabs(en.escaped - en.emitted) < 1e-9 * en.emitted);
    tb_rad_solver_free(s);
    tb_rad_mesh_free(&m);
}

/* Spectral bands: each band of the solution follows the light's band. */
static void test_spectral(void **state)
{
    (void)state;
    tb_rad_mesh m;
    tb__mesh(&m, 31);
    tb__floor(&m, 8, 0.4f);
    assert_int_equal(tb_rad_mesh_update_geometry(&m), TB_OK);
    tb_channels I = tb_channels_splat(31, 0.0f);
    for (int c = 0; c < 31; c++)
        I.v[c] = 0.1f + 0.05f * (float)c;
    tb_light l = tb_light_point(tb_vec3_make(0, 0, 1.5f), I);
    tb_rad_solver *s = tb__create(&m, &l, 1, TB_RAD_FF_RAYCAST);
    tb__run(s, 1e-3, 1);
    double b[TB_CHANNELS_MAX], worst = 0.0;
    for (size_t e = 0; e < m.nelems; e++) {
        tb_rad_element_radiosity(s, e, false, b);
        double want = 0.4 * tb__E_mean(&m, e, 128, 0, 0, 1.5, 1.0, -2, 0);
        for (int c = 0; c < 31; c++)
            worst = fmax(worst, fabs(b[c] - I.v[c] * want) / (I.v[c] * want));
    }
    print_message("31 bands: worst relative error %.2e\n", worst);
    assert_true(worst < 2e-5);
    tb_rad_solver_free(s);
    tb_rad_mesh_free(&m);
}

/* The hemicube path takes the same element irradiance from a light. */
static void test_hemicube(void **state)
{
    (void)state;
    tb_rad_mesh m;
    tb__box(&m, 4, 0.5f);
    tb_light l = tb_light_spot(tb_vec3_make(0.5f, 0.5f, 0.9f), tb_vec3_make(0.2f, 0, -1), tb_channels_splat(3, 1.0f),
                               50.0, 20.0);
    tb_rad_solver *a = tb__create(&m, &l, 1, TB_RAD_FF_RAYCAST), *h = tb__create(&m, &l, 1, TB_RAD_FF_HEMICUBE);
    tb__run(a, 1e-3, 1);
    tb__run(h, 1e-3, 1);
    double ba[TB_CHANNELS_MAX], bh[TB_CHANNELS_MAX], any = 0.0;
    for (size_t e = 0; e < m.nelems; e++) {
        tb_rad_element_radiosity(a, e, false, ba);
        tb_rad_element_radiosity(h, e, false, bh);
        assert_true(ba[0] == bh[0]);
        any = fmax(any, ba[0]);
    }
    assert_true(any > 0.0);
    tb__run(h, 1e-3, 0);
    tb_rad_energy en = tb_rad_solver_energy(h);
    assert_true(fabs(en.emitted - en.absorbed - en.unshot - en.escaped) < 1e-9 * en.emitted);
    tb_rad_solver_free(a);
    tb_rad_solver_free(h);
    tb_rad_mesh_free(&m);
}

/* Adaptive refinement: the new receivers get the light too. Ray cast: every
 * corner value of the refined floor is rho I cos / r^2 at its vertex;
 * hemicube: every element (new ones included) is rho x its exact mean. */
static void tb__adaptive(tb_rad_ff_method ff)
{
    tb_rad_mesh m;
    tb__mesh(&m, 3);
    tb__floor(&m, 8, 0.5f);
    assert_int_equal(tb_rad_mesh_update_geometry(&m), TB_OK);
    size_t n0 = m.nelems;
    tb_light l = tb_light_point(tb_vec3_make(0.1f, -0.2f, 0.6f), tb_channels_splat(3, 1.0f));
    tb_rad_options o = {.ff = ff, .samples = 4, .hemicube_res = 32, .lights = &l, .nlights = 1};
    tb_rad_stop stop = {.threshold = 1e-3};
    tb_rad_adapt_options ao = {.threshold = 0.05, .max_levels = 2};
    tb_rad_solver *s = NULL;
    tb_rad_adapt_stats as;
    if (tb_rad_adapt_solve(&m, &o, &stop, &ao, &s, &as))
        fail_msg("%s", tb_last_error());
    const tb_rad_mesh *sm = tb_rad_solver_mesh(s);
    double b[TB_CHANNELS_MAX], worst = 0.0;
    for (size_t e = 0; e < sm->nelems; e++) {
        if (ff == TB_RAD_FF_HEMICUBE) {
            tb_rad_element_radiosity(s, e, false, b);
            double want = 0.5 * tb__E_mean_poly(sm, e, 64, 0.1, -0.2, 0.6, 1.0);
            worst = fmax(worst, fabs(b[0] - want) / want);
            continue;
        }
        for (int k = 0; k < (sm->elems[e].v[3] == TB_RAD_NONE ? 3 : 4); k++) {
            tb_rad_corner_radiosity(s, e, k, false, b);
            tb_vec3 p = sm->verts[sm->elems[e].v[k]].p;
            double w = 0.5 * tb__E(p.x, p.y, 0.1, -0.2, 0.6, 1.0, -2, 0);
            worst = fmax(worst, fabs(b[0] - w) / w);
        }
    }
    print_message("adaptive %s: %zu -> %zu elements, %s within %.2e\n", ff == TB_RAD_FF_HEMICUBE ? "hemicube" : "ray cast",
                  n0, sm->nelems, ff == TB_RAD_FF_HEMICUBE ? "elements" : "corners", worst);
    assert_true(sm->nelems > n0);
    assert_true(worst < (ff == TB_RAD_FF_HEMICUBE ? 2e-5 : 2e-3));
    tb_rad_energy en = tb_rad_solver_energy(s);
    assert_true(en.unshot < 1e-3 * en.emitted);
    tb_rad_solver_free(s);
    tb_rad_mesh_free(&m);
}

static void test_adaptive(void **state)
{
    (void)state;
    tb__adaptive(TB_RAD_FF_RAYCAST);
    tb__adaptive(TB_RAD_FF_HEMICUBE);
}

/* 1 and 2 threads: identical bits (all three kinds, an occluder, a box). */
static void tb__solution(int threads, double **out, size_t *n)
{
    omp_set_num_threads(threads);
    tb_rad_mesh m;
    tb__box(&m, 6, 0.6f);
    tb__grid(&m, tb_vec3_make(0.3f, 0.3f, 0.5f), tb_vec3_make(0, 0.4f, 0), tb_vec3_make(0.4f, 0, 0), 3, 3, 0.5f, 6);
    assert_int_equal(tb_rad_mesh_update_geometry(&m), TB_OK);
    tb_light l[3] = {
        tb_light_point(tb_vec3_make(0.5f, 0.5f, 0.9f), tb_channels_splat(3, 1.0f)),
        tb_light_spot(tb_vec3_make(0.2f, 0.8f, 0.9f), tb_vec3_make(0.3f, -0.4f, -1), tb_channels_rgb(3, 2, 1), 40, 10),
        tb_light_directional(tb_vec3_make(0.1f, 0.2f, -1), tb_channels_splat(3, 0.5f)),
    };
    tb_rad_solver *s = tb__create(&m, l, 3, TB_RAD_FF_RAYCAST);
    tb__run(s, 1e-3, 0);
    size_t cnt = m.nelems * 15;
    double *v = malloc(sizeof *v * cnt);
    assert_non_null(v);
    for (size_t e = 0; e < m.nelems; e++) {
        tb_rad_element_radiosity(s, e, false, v + e * 15);
        for (int k = 0; k < 4; k++)
            tb_rad_corner_radiosity(s, e, k, false, v + e * 15 + 3 + 3 * k);
    }
    *out = v, *n = cnt;
    tb_rad_solver_free(s);
    tb_rad_mesh_free(&m);
}

static void test_threads(void **state)
{
    (void)state;
    double *a, *b;
    size_t na, nb;
    tb__solution(1, &a, &na);
    tb__solution(2, &b, &nb);
    assert_int_equal(na, nb);
    assert_memory_equal(a, b, na * sizeof *a);
    free(a), free(b);
}

/* Bad lights are refused. */
static void test_errors(void **state)
{
    (void)state;
    tb_rad_mesh m;
    tb__mesh(&m, 3);
    tb__floor(&m, 2, 0.5f);
    assert_int_equal(tb_rad_mesh_update_geometry(&m), TB_OK);
    tb_light l = tb_light_point(tb_vec3_make(0, 0, 1), tb_channels_splat(31, 1.0f)); /* bands on an RGB mesh */
    tb_rad_options o = {.lights = &l, .nlights = 1};
    tb_rad_solver *s = NULL;
    assert_int_equal(tb_rad_solver_create(&m, NULL, &o, &s), TB_ERR_ARG);
    assert_null(s);
    l = tb_light_point(tb_vec3_make(0, 0, 1), tb_channels_splat(3, -1.0f));
    assert_int_equal(tb_rad_solver_create(&m, NULL, &o, &s), TB_ERR_ARG);
    l = tb_light_point(tb_vec3_make(0, NAN, 1), tb_channels_splat(3, 1.0f));
    assert_int_equal(tb_rad_solver_create(&m, NULL, &o, &s), TB_ERR_ARG);
    tb_rad_mesh_free(&m);
}

int main(int argc, char **argv)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_point_plane), cmocka_unit_test(test_spot_cone),  cmocka_unit_test(test_ies),
        cmocka_unit_test(test_directional_shadow),
        cmocka_unit_test(test_energy_box),  cmocka_unit_test(test_spectral),  cmocka_unit_test(test_hemicube),
        cmocka_unit_test(test_adaptive),    cmocka_unit_test(test_threads),   cmocka_unit_test(test_errors),
    };
    if (argc > 1)
        cmocka_set_test_filter(argv[1]);
    return cmocka_run_group_tests(tests, NULL, NULL);
}
