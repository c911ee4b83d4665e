/* Progressive radiosity (host/radiosity/radiosity.h) against exact answers:
 * the white furnace, a closed sphere with an emitting cap, energy
 * bookkeeping, reciprocity, thread-count independence, the patches CSV, and
 * the spectral Cornell box image. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
#include <omp.h>

#include "host/radiosity/radiosity.h"
#include "host/radiosity/update_internal.h"
#include "host/render/scene.h"
#include "rad_test.h"
#include "tb_test.h"
#include "util/image/image.h"

#define TB__PI 3.14159265358979323846

/* Furnace: B = E / (1 - rho) = 2 on every element; the ambient term accounts
 * for what is left unshot, so with it every element is within the
 * form-factor error, and without it within that plus the threshold. */
static void tb__furnace(tb_rad_ff_method ff, double tol)
{
    tb_scene *sc = tb_rad_test_load("tests/radiosity/furnace.mid");
    tb_rad_mesh m;
    tb_rad_mesh_options mo = {.max_edge = 0.2};
    assert_int_equal(tb_rad_mesh_from_scene(sc, &mo, &m), TB_OK);
    assert_int_equal(m.nelems, 6 * 25);
    tb_rad_options o = {.ff = ff, .samples = 16, .hemicube_res = 128};
    double thr = 1e-3;
    tb_rad_solver *s = tb_rad_test_solve(&m, &o, thr);
    assert_true(tb_rad_unshot_fraction(s) < thr);
    double b[TB_CHANNELS_MAX], worst = 0.0, worst_na = 0.0;
    for (size_t i = 0; i < m.nelems; i++) {
        tb_rad_element_radiosity(s, i, true, b);
        for (int c = 0; c < m.nchannels; c++)
            worst = fmax(worst, fabs(b[c] - 2.0) / 2.0);
        if (getenv("TB_RAD_DEBUG") && fabs(b[0] - 2.0) > 0.04)
            print_message("element %zu at %g %g %g: %g\n", i, (double)m.elems[i].centroid.x,
                          (double)m.elems[i].centroid.y, (double)m.elems[i].centroid.z, b[0]);
        tb_rad_element_radiosity(s, i, false, b);
        for (int c = 0; c < m.nchannels; c++)
            worst_na = fmax(worst_na, fabs(b[c] - 2.0) / 2.0);
    }
    print_message("furnace %s: worst relative error %.4f (ambient), %.4f (none), %llu shots\n",
                  ff == TB_RAD_FF_HEMICUBE ? "hemicube" : "raycast", worst, worst_na,
                  (unsigned long long)tb_rad_solver_shots(s));
    /* the display values at the corners too: a receiver vertex on the box's
     * edge must count the wall beside it (the limit from inside) */
    double worst_c = 0.0;
    for (size_t i = 0; i < m.nelems; i++)
        for (int k = 0; k < (m.elems[i].v[3] == TB_RAD_NONE ? 3 : 4); k++) {
            tb_rad_corner_radiosity(s, i, k, true, b);
            worst_c = fmax(worst_c, fabs(b[0] - 2.0) / 2.0);
        }
    print_message("furnace corners: worst relative error %.4f\n", worst_c);
    assert_true(worst < tol);
    assert_true(worst_na < tol + 2.0 * thr);
    assert_true(worst_c < tol);
    tb_rad_solver_free(s);
    tb_rad_mesh_free(&m);
    tb_scene_free(sc);
}

static void test_furnace_raycast(void **state)
{
    (void)state;
    tb__furnace(TB_RAD_FF_RAYCAST, 0.02);
}

static void test_furnace_hemicube(void **state)
{
    (void)state;
    tb__furnace(TB_RAD_FF_HEMICUBE, 0.03);
}

/* A closed sphere of radius 1 seen from inside (lat-long quads, triangles
 * at the poles, normals inward), elements above z > cap_z emitting E = 1,
 * reflectance rho. */
static void tb__sphere(tb_rad_mesh *m, int nlat, int nlon, double cap_z, float rho)
{
    tb_rad_mesh_init(m);
    m->nchannels = 3;
    size_t nv = (size_t)(nlat - 1) * (size_t)nlon + 2;
    m->verts = calloc(nv, sizeof *m->verts);
    size_t ne = (size_t)nlat * (size_t)nlon;
    m->elems = calloc(ne, sizeof *m->elems);
    m->rho = calloc(ne * 3, sizeof(float));
    m->emission = calloc(ne * 3, sizeof(float));
    assert_non_null(m->verts);
    m->nverts = nv;
    /* vertex 0: north pole, 1: south, then rings */
    m->verts[0].p = tb_vec3_make(0, 0, 1);
    m->verts[1].p = tb_vec3_make(0, 0, -1);
    for (int i = 1; i < nlat; i++)
        for (int j = 0; j < nlon; j++) {
            double th = TB__PI * i / nlat, ph = 2 * TB__PI * j / nlon;
            m->verts[2 + (size_t)(i - 1) * (size_t)nlon + (size_t)j].p =
                tb_vec3_make((float)(sin(th) * cos(ph)), (float)(sin(th) * sin(ph)), (float)cos(th));
        }
    for (size_t v = 0; v < nv; v++)
        m->verts[v].n = tb_vec3_scale(m->verts[v].p, -1.0f / tb_vec3_length(m->verts[v].p));
#define RING(i, j) ((uint32_t)(2 + (size_t)((i) - 1) * (size_t)nlon + (size_t)(((j) % nlon))))
    size_t e = 0;
    for (int i = 0; i < nlat; i++)
        for (int j = 0; j < nlon; j++, e++) {
            tb_rad_element *el = &m->elems[e];
            el->parent = TB_RAD_NONE;
            /* counter-clockwise seen from inside (the centre) */
            if (i == 0)
                *el = (tb_rad_element){.v = {0, RING(1, j + 1), RING(1, j), TB_RAD_NONE}, .parent = TB_RAD_NONE};
            else if (i == nlat - 1)
                *el = (tb_rad_element){.v = {1, RING(i, j), RING(i, j + 1), TB_RAD_NONE}, .parent = TB_RAD_NONE};
            else
                *el = (tb_rad_element){.v = {RING(i, j), RING(i, j + 1), RING(i + 1, j + 1), RING(i + 1, j)},
                                       .parent = TB_RAD_NONE};
        }
#undef RING
    m->nelems = ne;
    assert_int_equal(tb_rad_mesh_update_geometry(m), TB_OK);
    for (size_t k = 0; k < ne; k++) {
        /* inward: the normal points to the centre */
        assert_true(tb_vec3_dot(m->elems[k].normal, m->elems[k].centroid) < 0.0f);
        for (int c = 0; c < 3; c++) {
            m->rho[k * 3 + (size_t)c] = rho;
            m->emission[k * 3 + (size_t)c] = m->elems[k].centroid.z > cap_z ? 1.0f : 0.0f;
        }
    }
}

/* In a sphere F_ij = A_j / A, so B_i = E_i + rho Ebar / (1 - rho) with Ebar
 * the area-weighted mean emission. */
static void test_sphere_cap(void **state)
{
    (void)state;
    tb_rad_mesh m;
    float rho = 0.6f;
    tb__sphere(&m, 12, 24, 0.8, rho);
    double ea = 0.0, a = 0.0;
    for (size_t i = 0; i < m.nelems; i++)
        ea += m.emission[i * 3] * m.elems[i].area, a += m.elems[i].area;
    double ebar = ea / a;
    assert_true(ebar > 0.0 && ebar < 0.2);
    for (int method = 0; method < 2; method++) {
        /* the inside of a sphere is convex: nothing to occlude */
        tb_rad_options o = {.ff = method ? TB_RAD_FF_HEMICUBE : TB_RAD_FF_RAYCAST, .samples = 16, .no_occlusion = true};
        tb_rad_solver *s = tb_rad_test_solve(&m, &o, 1e-2);
        double worst = 0.0, b[3];
        for (size_t i = 0; i < m.nelems; i++) {
            tb_rad_element_radiosity(s, i, true, b);
            double exact = m.emission[i * 3] + rho * ebar / (1.0 - rho);
            /* relative to the reflected part, the hard one */
            worst = fmax(worst, fabs(b[1] - exact) / (rho * ebar / (1.0 - rho)));
        }
        print_message("sphere cap %s: worst error %.4f of the reflected radiosity\n", method ? "hemicube" : "raycast",
                      worst);
        assert_true(worst < 0.1);
        tb_rad_solver_free(s);
    }
    tb_rad_mesh_free(&m);
}

/* Power bookkeeping: absorbed + unshot + escaped = emitted; in the closed
 * furnace almost nothing escapes, and the absorbed power equals the one
 * computed independently from the solution, sum (1 - rho) H A. */
static void test_energy(void **state)
{
    (void)state;
    /* variant 1: every element its own reflectance (more distinct rows than
     * the update shares its reflected sums over: the per-element path) */
    for (int variant = 0; variant < 2; variant++) {
        tb_scene *sc = tb_rad_test_load("tests/radiosity/furnace.mid");
        tb_rad_mesh m;
        tb_rad_mesh_options mo = {.max_edge = 0.25};
        assert_int_equal(tb_rad_mesh_from_scene(sc, &mo, &m), TB_OK);
        /* only the floor emits, so light has to bounce */
        for (size_t i = 0; i < m.nelems; i++) {
            if (m.elems[i].object != 0)
                for (int c = 0; c < m.nchannels; c++)
                    m.emission[i * (size_t)m.nchannels + (size_t)c] = 0.0f;
            if (variant)
                for (int c = 0; c < m.nchannels; c++)
                    m.rho[i * (size_t)m.nchannels + (size_t)c] *= 1.0f - 0.002f * (float)(i % 200);
        }
        tb_rad_options o = {.samples = 16};
        tb_rad_solver *s = tb_rad_test_solve(&m, &o, 1e-2);
        tb_rad_energy en = tb_rad_solver_energy(s);
        print_message("energy (variant %d, %zu elements): emitted %g absorbed %g unshot %g escaped %g\n", variant,
                      m.nelems, en.emitted, en.absorbed, en.unshot, en.escaped);
        assert_true(en.emitted > 0.0);
        assert_true(!variant || m.nelems > 64); /* more rows than TB__RAD_MAX_ROWS */
        assert_true(en.unshot < 0.01 * en.emitted);
        tb_rad_test_check_energy(s, &m);
        tb_rad_solver_free(s);
        tb_rad_mesh_free(&m);
        tb_scene_free(sc);
    }
}

/* A_i F_ij = A_j F_ji on the solver's own form factors, in the furnace
 * (convex, so point-sampled visibility plays no part), for pairs of
 * elements at least two element sizes apart. */
static void test_reciprocity(void **state)
{
    (void)state;
    tb_scene *sc = tb_rad_test_load("tests/radiosity/furnace.mid");
    tb_rad_mesh m;
    tb_rad_mesh_options mo = {.max_edge = 0.2};
    assert_int_equal(tb_rad_mesh_from_scene(sc, &mo, &m), TB_OK);
    for (int method = 0; method < 2; method++) {
        tb_rad_options o = {.ff = method ? TB_RAD_FF_HEMICUBE : TB_RAD_FF_RAYCAST, .samples = 16,
                            .hemicube_res = 256};
        tb_rad_solver *s = NULL;
        assert_int_equal(tb_rad_solver_create(&m, NULL, &o, &s), TB_OK);
        int checked = 0;
        double worst = 0.0, sum_fij = 0.0, sum_diff = 0.0, sum_max = 0.0;
        for (size_t i = 0; i < m.nelems; i += 4) {
            for (size_t j = i + 1; j < m.nelems; j += 5) {
                const tb_rad_element *ei = &m.elems[i], *ej = &m.elems[j];
                if (tb_vec3_distance(ei->centroid, ej->centroid) < 0.4)
                    continue;
                double fij, fji;
                assert_int_equal(tb_rad_formfactor(s, i, j, &fij), TB_OK);
                assert_int_equal(tb_rad_formfactor(s, j, i, &fji), TB_OK);
                double l = ei->area * fij, r = ej->area * fji;
                sum_fij += fij;
                if (fmax(l, r) < 1e-4 * ei->area)
                    continue; /* coplanar */
                worst = fmax(worst, fabs(l - r) / fmax(l, r));
                sum_diff += fabs(l - r), sum_max += fmax(l, r);
                checked++;
            }
        }
        print_message("reciprocity %s: %d pairs, worst relative difference %.4f, overall %.4f\n",
                      method ? "hemicube" : "raycast", checked, worst, sum_diff / sum_max);
        assert_true(checked > 150);
        assert_true(sum_fij > 0.0);
        /* the corner-mean quadrature of ray-cast F_ji is not symmetric:
         * docs/radiosity.md, "Accuracy" */
        assert_true(sum_diff / sum_max < 0.03);
        assert_true(worst < 0.2);
        tb_rad_solver_free(s);
    }
    tb_rad_mesh_free(&m);
    tb_scene_free(sc);
}

/* The same CSV bytes with 1 and 2 threads. */
static void test_threads(void **state)
{
    (void)state;
    tb_scene *sc = tb_rad_test_load("scenes/cornell-box-rgb.mid");
    tb_rad_mesh m;
    tb_rad_mesh_options mo = {.max_edge = 120};
    assert_int_equal(tb_rad_mesh_from_scene(sc, &mo, &m), TB_OK);
    char p1[1024], p2[1024];
    snprintf(p1, sizeof p1, "%s/rad_threads1.csv", tb_test_tmpdir());
    snprintf(p2, sizeof p2, "%s/rad_threads2.csv", tb_test_tmpdir());
    for (int t = 1; t <= 2; t++) {
        omp_set_num_threads(t);
        tb_rad_options o = {.samples = 4, .seed = 7};
        tb_rad_solver *s = tb_rad_test_solve(&m, &o, 1e-2);
        assert_int_equal(tb_rad_write_patches(s, t == 1 ? p1 : p2), TB_OK);
        tb_rad_solver_free(s);
    }
    size_t n1, n2;
    char *a = tb_rad_test_slurp(p1, &n1), *b = tb_rad_test_slurp(p2, &n2);
    assert_int_equal(n1, n2);
    assert_memory_equal(a, b, n1);
    /* and a different seed changes the answer (the comparison can fail) */
    tb_rad_options o = {.samples = 4, .seed = 8};
    tb_rad_solver *s = tb_rad_test_solve(&m, &o, 1e-2);
    assert_int_equal(tb_rad_write_patches(s, p2), TB_OK);
    tb_rad_solver_free(s);
    free(b);
    b = tb_rad_test_slurp(p2, &n2);
    assert_true(n1 != n2 || memcmp(a, b, n1) != 0);
    free(a), free(b);
    tb_rad_mesh_free(&m);
    tb_scene_free(sc);
}

/* The CSV header, one row per element, object = the face of the cube the
 * centroid lies on, and tb_rad_read_patches reading it back. */
static void test_patches_csv(void **state)
{
    (void)state;
    tb_scene *sc = tb_rad_test_load("tests/radiosity/furnace.mid");
    tb_rad_mesh m;
    tb_rad_mesh_options mo = {.max_edge = 0.5};
    assert_int_equal(tb_rad_mesh_from_scene(sc, &mo, &m), TB_OK);
    tb_rad_options o = {.samples = 4};
    tb_rad_solver *s = tb_rad_test_solve(&m, &o, 0.1);
    char path[1024];
    snprintf(path, sizeof path, "%s/rad_patches.csv", tb_test_tmpdir());
    assert_int_equal(tb_rad_write_patches(s, path), TB_OK);
    size_t len;
    char *text = tb_rad_test_slurp(path, &len);
    const char *hdr = "element,object,area,cx,cy,cz,nx,ny,nz,b_r,b_g,b_b,u_r,u_g,u_b\n";
    assert_memory_equal(text, hdr, strlen(hdr));
    char *line = strchr(text, '\n') + 1;
    size_t rows = 0;
    /* face k of furnace.mid: floor z=0, ceiling z=1, y=0, y=1, x=0, x=1 */
    while (*line) {
        unsigned long el, obj;
        double area, c[3], n[3], b[3], u[3];
        int k = sscanf(line, "%lu,%lu,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &el, &obj, &area, &c[0],
                       &c[1], &c[2], &n[0], &n[1], &n[2], &b[0], &b[1], &b[2], &u[0], &u[1], &u[2]);
        assert_int_equal(k, 15);
        assert_int_equal(el, rows);
        assert_true(obj < 6);
        int axis = obj < 2 ? 2 : obj < 4 ? 1 : 0;
        double side = (obj % 2) ? 1.0 : 0.0;
        tb_assert_near(c[axis], side, 1e-6);
        tb_assert_near(n[axis], side ? -1.0 : 1.0, 1e-6);
        tb_assert_near(area, 0.25, 1e-6);
        /* sanity only (2 x 2 elements per face, 4 samples, stopped at 10%) */
        assert_true(b[0] >= 1.0 && b[0] <= 2.2 && u[0] >= 0.0);
        rows++;
        line = strchr(line, '\n') + 1;
    }
    assert_int_equal(rows, m.nelems);
    free(text);
    size_t nr;
    int ncol;
    double *vals;
    assert_int_equal(tb_rad_read_patches(path, &nr, &ncol, &vals), TB_OK);
    assert_int_equal(nr, m.nelems);
    assert_int_equal(ncol, 3);
    double b[3];
    tb_rad_element_radiosity(s, 5, false, b);
    tb_assert_near(vals[5 * 3 + 1], b[1], 1e-8 * b[1]);
    free(vals);
    tb_rad_solver_free(s);
    tb_rad_mesh_free(&m);
    tb_scene_free(sc);
}

/* Continuing from a state gives the same answer as running on. */
static void test_continue(void **state)
{
    (void)state;
    tb_scene *sc = tb_rad_test_load("tests/radiosity/furnace.mid");
    tb_rad_mesh m;
    tb_rad_mesh_options mo = {.max_edge = 0.25};
    assert_int_equal(tb_rad_mesh_from_scene(sc, &mo, &m), TB_OK);
    tb_rad_options o = {.samples = 8};
    tb_rad_solver *a = NULL, *b = NULL;
    assert_int_equal(tb_rad_solver_create(&m, NULL, &o, &a), TB_OK);
    tb_rad_stop st = {.threshold = 1e-9, .max_shots = 40};
    assert_int_equal(tb_rad_solver_run(a, &st, NULL, NULL, 0), TB_OK);
    tb_rad_state s0 = tb_rad_solver_state(a);
    assert_int_equal(tb_rad_solver_create(&m, &s0, &o, &b), TB_OK);
    tb_assert_near(tb_rad_unshot_fraction(b), tb_rad_unshot_fraction(a), 1e-12);
    double x[3], y[3];
    for (size_t i = 0; i < m.nelems; i++) {
        tb_rad_element_radiosity(a, i, true, x);
        tb_rad_element_radiosity(b, i, true, y);
        tb_assert_near(x[0], y[0], 1e-12);
    }
    tb_rad_energy e = tb_rad_solver_energy(b);
    tb_assert_near(e.absorbed + e.unshot + e.escaped, e.emitted, 1e-9 * e.emitted);
    tb_rad_solver_free(a);
    tb_rad_solver_free(b);
    tb_rad_mesh_free(&m);
    tb_scene_free(sc);
}

/* The display's corner values with the ambient term summed once
 * (tb_rad_corner_radiosity_amb, as the image does) are bit for bit those
 * of tb_rad_corner_radiosity, which sums it at every corner; NULL is no
 * ambient. Mid-solve, so the ambient term is not 0. */
static void test_corner_ambient(void **state)
{
    (void)state;
    tb_scene *sc = tb_rad_test_load("tests/radiosity/furnace.mid");
    tb_rad_mesh m;
    tb_rad_mesh_options mo = {.max_edge = 0.25};
    assert_int_equal(tb_rad_mesh_from_scene(sc, &mo, &m), TB_OK);
    tb_rad_options o = {.samples = 4};
    tb_rad_solver *s = NULL;
    assert_int_equal(tb_rad_solver_create(&m, NULL, &o, &s), TB_OK);
    tb_rad_stop st = {.threshold = 1e-9, .max_shots = 20};
    assert_int_equal(tb_rad_solver_run(s, &st, NULL, NULL, 0), TB_OK);
    double amb[TB_CHANNELS_MAX], x[TB_CHANNELS_MAX], y[TB_CHANNELS_MAX];
    tb_rad_ambient(s, amb);
    assert_true(amb[0] > 0.0);
    for (size_t i = 0; i < m.nelems; i++)
        for (int k = 0; k < (m.elems[i].v[3] == TB_RAD_NONE ? 3 : 4); k++) {
            tb_rad_corner_radiosity(s, i, k, true, x);
            tb_rad_corner_radiosity_amb(s, i, k, amb, y);
            assert_memory_equal(x, y, sizeof(double) * (size_t)m.nchannels);
            tb_rad_corner_radiosity(s, i, k, false, x);
            tb_rad_corner_radiosity_amb(s, i, k, NULL, y);
            assert_memory_equal(x, y, sizeof(double) * (size_t)m.nchannels);
        }
    tb_rad_solver_free(s);
    tb_rad_mesh_free(&m);
    tb_scene_free(sc);
}

/* Checkpoints (tb_rad_solver_pack/unpack): a solver stopped after 60
 * shots, packed, and unpacked into a new solver of the same mesh, shoots on
 * exactly as the original: same shots, every element's radiosity and the
 * energy sums bit for bit. Packed bytes of another mesh, or cut short, are
 * refused and leave the solver as it was. */
static void test_pack(void **state)
{
    (void)state;
    tb_scene *sc = tb_rad_test_load("scenes/cornell-box-rgb.mid");
    tb_rad_mesh m, other;
    tb_rad_mesh_options mo = {.max_edge = 150};
    assert_int_equal(tb_rad_mesh_from_scene(sc, &mo, &m), TB_OK);
    mo.max_edge = 200;
    assert_int_equal(tb_rad_mesh_from_scene(sc, &mo, &other), TB_OK);
    tb_rad_options o = {.samples = 8, .seed = 3};
    tb_rad_solver *whole = NULL, *first = NULL, *second = NULL, *wrong = NULL;
    assert_int_equal(tb_rad_solver_create(&m, NULL, &o, &whole), TB_OK);
    assert_int_equal(tb_rad_solver_create(&m, NULL, &o, &first), TB_OK);
    assert_int_equal(tb_rad_solver_create(&m, NULL, &o, &second), TB_OK);
    assert_int_equal(tb_rad_solver_create(&other, NULL, &o, &wrong), TB_OK);
    tb_rad_stop all = {.threshold = 0.01}, part = {.threshold = 0.01, .max_shots = 60};
    assert_int_equal(tb_rad_solver_run(whole, &all, NULL, NULL, 0), TB_OK);
    assert_int_equal(tb_rad_solver_run(first, &part, NULL, NULL, 0), TB_OK);
    assert_int_equal(tb_rad_solver_shots(first), 60);
    size_t len = tb_rad_solver_packed_size(first);
    unsigned char *buf = malloc(len);
    assert_non_null(buf);
    tb_rad_solver_pack(first, buf);
    assert_int_equal(tb_rad_solver_unpack(wrong, buf, len), TB_ERR_FORMAT);
    assert_int_equal(tb_rad_solver_shots(wrong), 0);
    assert_int_equal(tb_rad_solver_unpack(second, buf, len - 8), TB_ERR_FORMAT);
    assert_int_equal(tb_rad_solver_shots(second), 0);
    assert_int_equal(tb_rad_solver_unpack(second, buf, len), TB_OK);
    free(buf);
    assert_int_equal(tb_rad_solver_shots(second), 60);
    assert_int_equal(tb_rad_solver_run(second, &all, NULL, NULL, 0), TB_OK);
    assert_true(tb_rad_solver_shots(whole) > 60);
    assert_int_equal(tb_rad_solver_shots(second), tb_rad_solver_shots(whole));
    double x[TB_CHANNELS_MAX], y[TB_CHANNELS_MAX];
    for (size_t i = 0; i < m.nelems; i++) {
        tb_rad_element_radiosity(whole, i, false, x);
        tb_rad_element_radiosity(second, i, false, y);
        assert_memory_equal(x, y, (size_t)m.nchannels * sizeof x[0]);
    }
    tb_rad_energy a = tb_rad_solver_energy(whole), b = tb_rad_solver_energy(second);
    assert_memory_equal(&a, &b, sizeof a);
    tb_rad_solver_free(whole);
    tb_rad_solver_free(first);
    tb_rad_solver_free(second);
    tb_rad_solver_free(wrong);
    tb_rad_mesh_free(&m);
    tb_rad_mesh_free(&other);
    tb_scene_free(sc);
}

/* Bad arguments are refused with a message. */
static void test_errors(void **state)
{
    (void)state;
    tb_rad_mesh m;
    tb__sphere(&m, 4, 8, 0.5, 0.5f);
    tb_rad_solver *s = NULL;
    tb_rad_options o = {.samples = -1};
    assert_int_equal(tb_rad_solver_create(&m, NULL, &o, &s), TB_ERR_ARG);
    assert_null(s);
    o = (tb_rad_options){.ff = (tb_rad_ff_method)7};
    assert_int_equal(tb_rad_solver_create(&m, NULL, &o, &s), TB_ERR_ARG);
    m.rho[4] = 1.0f;
    o = (tb_rad_options){0};
    assert_int_equal(tb_rad_solver_create(&m, NULL, &o, &s), TB_ERR_ARG);
    assert_non_null(strstr(tb_last_error(), "reflectance"));
    m.rho[4] = 0.5f;
    m.elems[3].v[1] = 100000;
    assert_int_equal(tb_rad_mesh_update_geometry(&m), TB_ERR_ARG);
    tb_rad_mesh_free(&m);
    char path[1024];
    snprintf(path, sizeof path, "%s/rad_bad.csv", tb_test_tmpdir());
    FILE *f = fopen(path, "w");
    fputs("element,object,area,cx,cy,cz,nx,ny,nz,b_r\n0,0,1,0,0,0,0,0,1,zz\n", f);
    fclose(f);
    size_t nr;
    int nc;
    double *v;
    assert_int_equal(tb_rad_read_patches(path, &nr, &nc, &v), TB_ERR_FORMAT);
}

/* The spectral Cornell box: the red wall is on the left of the image, the
 * green one on the right, and the image is not black. */
static void test_cornell_image(void **state)
{
    (void)state;
    tb_scene *sc = tb_rad_test_load("scenes/cornell-box.mid");
    assert_true(sc->spectral);
    tb_rad_mesh m;
    tb_rad_mesh_options mo = {.max_edge = 100};
    assert_int_equal(tb_rad_mesh_from_scene(sc, &mo, &m), TB_OK);
    tb_rad_options o = {.samples = 4};
    tb_rad_solver *s = tb_rad_test_solve(&m, &o, 1e-2);
    tb_image *img = NULL;
    assert_int_equal(tb_rad_render_image(s, sc, 1, &img), TB_OK);
    assert_int_equal(img->channels, 3);
    /* mean colour of a band of columns at mid height */
    double left[3] = {0}, right[3] = {0}, all = 0.0;
    int w = img->width, h = img->height, n = 0;
    for (int y = h / 3; y < 2 * h / 3; y++)
        for (int x = 0; x < w / 12; x++, n++)
            for (int c = 0; c < 3; c++) {
                left[c] += img->pixels[((size_t)y * (size_t)w + (size_t)(w / 48 + x)) * 3 + (size_t)c];
                right[c] += img->pixels[((size_t)y * (size_t)w + (size_t)(w - 1 - w / 48 - x)) * 3 + (size_t)c];
            }
    for (size_t k = 0; k < (size_t)w * (size_t)h * 3; k++)
        all += img->pixels[k];
    print_message("cornell: left %.4g %.4g %.4g, right %.4g %.4g %.4g\n", left[0] / n, left[1] / n, left[2] / n,
                  right[0] / n, right[1] / n, right[2] / n);
    assert_true(all > 0.0);
    assert_true(left[0] > 2.0 * left[1] && left[0] > 2.0 * left[2]);
    assert_true(right[1] > 1.5 * right[0] && right[1] > right[2]);
    tb_image_free(img);
    tb_rad_solver_free(s);
    tb_rad_mesh_free(&m);
    tb_scene_free(sc);
}

/* Occluders: the walls of a room cannot block a segment inside it. In the
 * furnace nothing occludes; in the Cornell box the blocks' faces all do and
 * the floor, ceiling, back and right walls never do; and
 * visibility through the reduced set equals visibility through every
 * element for segments between element centroids. */
static void test_occluders(void **state)
{
    (void)state;
    tb_scene *sc = tb_rad_test_load("tests/radiosity/furnace.mid");
    tb_rad_mesh m;
    tb_rad_mesh_options mo = {.max_edge = 0.25};
    assert_int_equal(tb_rad_mesh_from_scene(sc, &mo, &m), TB_OK);
    tb_ff_polygon *p = malloc(m.nelems * sizeof *p);
    assert_int_equal(tb_rad_mesh_occluders(&m, p), 0);
    free(p);
    tb_rad_mesh_free(&m);
    tb_scene_free(sc);

    sc = tb_rad_test_load("scenes/cornell-box-rgb.mid");
    mo.max_edge = 80;
    assert_int_equal(tb_rad_mesh_from_scene(sc, &mo, &m), TB_OK);
    p = malloc(m.nelems * sizeof *p);
    tb_ff_polygon *all = malloc(m.nelems * sizeof *all);
    size_t n = tb_rad_mesh_occluders(&m, p);
    size_t blocks = 0;
    for (size_t i = 0; i < m.nelems; i++) {
        tb_rad_mesh_polygon(&m, i, &all[i]);
        blocks += m.elems[i].object >= 6;
    }
    /* every kept polygon lies on a block, the (non-planar) red wall or the
     * light (0.1 mm below the ceiling: it hides the ceiling above it): its
     * centroid is on an element of one of them; a block's side, cut into a
     * grid, is kept as one quad of the side's area */
    double kept_area = 0.0, block_area = 0.0, all_area = 0.0;
    for (size_t i = 0; i < m.nelems; i++) {
        if (m.elems[i].object >= 6)
            block_area += m.elems[i].area;
        if (m.elems[i].object >= 4)
            all_area += m.elems[i].area;
    }
    for (size_t k = 0; k < n; k++) {
        tb_vec3 c = tb_vec3_make(0, 0, 0), nn;
        for (int q = 0; q < p[k].n; q++)
            c = tb_vec3_add(c, tb_vec3_scale(p[k].v[q], 1.0f / (float)p[k].n));
        double area;
        tb_ff_polygon_frame(&p[k], &nn, &area);
        kept_area += area;
        size_t i = 0;
        for (; i < m.nelems; i++) {
            const tb_rad_element *e = &m.elems[i];
            if (e->object < 4 || tb_vec3_dot(nn, e->normal) < 0.999f ||
                fabsf(tb_vec3_dot(tb_vec3_sub(c, e->centroid), e->normal)) > 0.01f)
                continue;
            break;
        }
        assert_true(i < m.nelems);
    }
    /* no element twice (at most the three objects' area), no block element lost */
    assert_true(kept_area <= all_area * (1.0 + 1e-5) && kept_area >= block_area * (1.0 - 1e-5));
    assert_true(n < blocks);
    tb_ff_occluders *oa = NULL, *ob = NULL;
    assert_int_equal(tb_ff_occluders_build(all, m.nelems, &oa), TB_OK);
    assert_int_equal(tb_ff_occluders_build(p, n, &ob), TB_OK);
    int blocked = 0;
    for (size_t i = 0; i < m.nelems; i += 3)
        for (size_t j = i + 1; j < m.nelems; j += 7) {
            /* a little in front of each surface, as sample points and receivers are */
            tb_vec3 a = tb_vec3_add(m.elems[i].centroid, tb_vec3_scale(m.elems[i].normal, 0.01f));
            tb_vec3 b = tb_vec3_add(m.elems[j].centroid, tb_vec3_scale(m.elems[j].normal, 0.01f));
            bool va = tb_ff_occluders_visible(oa, a, b), vb = tb_ff_occluders_visible(ob, a, b);
            if (va != vb)
            assert_true(va == vb);
            blocked += !va;
        }
    print_message("occluders: %zu of %zu elements; %d blocked segments agree\n", n, m.nelems, blocked);
    assert_true(blocked > 100);
    tb_ff_occluders_free(oa);
    tb_ff_occluders_free(ob);
    free(p);
    free(all);
    tb_rad_mesh_free(&m);
    tb_scene_free(sc);
}

/* Box (lo xyz, hi xyz) of n points. */
static void tb__box(const tb_vec3 *p, size_t n, float b[6])
{
    b[0] = b[3] = p[0].x, b[1] = b[4] = p[0].y, b[2] = b[5] = p[0].z;
    for (size_t k = 1; k < n; k++) {
        b[0] = fminf(b[0], p[k].x), b[1] = fminf(b[1], p[k].y), b[2] = fminf(b[2], p[k].z);
        b[3] = fmaxf(b[3], p[k].x), b[4] = fmaxf(b[4], p[k].y), b[5] = fmaxf(b[5], p[k].z);
    }
}

/* Shaft culling (tb_ff_occluders_shaft + tb_ff_shaft_visible) gives exactly
 * the BVH's answer for every segment between its boxes, on the spectral
 * Cornell box's occluders: rotated blocks, the twisted red wall (whose
 * elements are occluders, hit by grazing segments between its own points)
 * and the light 0.1 mm below the ceiling (it hides the ceiling above it).
 * Receivers are element corners moved 1e-3 of the way into the element and
 * the ends are the shooters' sample points, as in the solver. */
static void test_shaft(void **state)
{
    (void)state;
    tb_scene *sc = tb_rad_test_load("scenes/cornell-box-rgb.mid");
    tb_rad_mesh m;
    tb_rad_mesh_options mo = {.max_edge = 60};
    assert_int_equal(tb_rad_mesh_from_scene(sc, &mo, &m), TB_OK);
    tb_ff_polygon *p = malloc(m.nelems * sizeof *p);
    size_t n = tb_rad_mesh_occluders(&m, p);
    tb_ff_occluders *occ = NULL;
    assert_int_equal(tb_ff_occluders_build(p, n, &occ), TB_OK);
    /* receivers: clusters of 8 corners of consecutive elements */
    size_t nr = 0;
    tb_vec3 *rp = malloc(4 * m.nelems * sizeof *rp);
    for (size_t i = 0; i < m.nelems; i++) {
        tb_ff_polygon e;
        tb_rad_mesh_polygon(&m, i, &e);
        for (int k = 0; k < e.n; k++)
            rp[nr++] = tb_vec3_add(e.v[k], tb_vec3_scale(tb_vec3_sub(m.elems[i].centroid, e.v[k]), 1e-3f));
    }
    long segs = 0, blocked = 0, listed = 0, full = 0, shafts = 0;
    for (size_t i = 0; i < m.nelems; i += 5) {
        tb_ff_polygon e;
        tb_rad_mesh_polygon(&m, i, &e);
        tb_vec3 pts[4];
        assert_int_equal(tb_ff_sample_polygon(&e, 4, i, pts), TB_OK);
        float sb[6];
        tb__box(pts, 4, sb);
        for (size_t c = 0; c < nr; c += 8) {
            size_t nc = c + 8 <= nr ? 8 : nr - c;
            float rb[6];
            tb__box(rp + c, nc, rb);
            tb_ff_shaft sh;
            shafts++;
            /* with and without the points: both must be conservative */
            bool ok = tb_ff_occluders_shaft(occ, rb, (c / 8) % 2 ? rp + c : NULL, nc, sb, (c / 8) % 3 ? pts : NULL, 4, &sh);
            if (!ok) {
                full++;
                continue;
            }
            listed += (long)sh.n;
            for (size_t q = c; q < c + nc; q++)
                for (int k = 0; k < 4; k++) {
                    bool bvh = tb_ff_occluders_visible(occ, rp[q], pts[k]);
                    bool shaft = tb_ff_shaft_visible(&sh, rp[q], pts[k]);
                    if (bvh != shaft)
                        fail_msg("element %zu sample %d, receiver %zu: BVH %d, shaft %d (%zu listed)", i, k, q, bvh,
                                 shaft, sh.n);
                    segs++;
                    blocked += !bvh;
                }
        }
    }
    print_message("shafts: %ld (%ld with too many occluders), %.2f occluder triangles listed on average; "
                  "%ld segments (%ld blocked) agree with the BVH\n",
                  shafts, full, (double)listed / (double)(shafts - full), segs, blocked);
    assert_true(blocked > 1000 && segs > 100000);
    assert_true(full < shafts / 4);
    /* the empty cases: no occluders, and a shaft in empty space */
    tb_ff_occluders *none = NULL;
    assert_int_equal(tb_ff_occluders_build(NULL, 0, &none), TB_OK);
    tb_ff_shaft sh;
    float b0[6] = {0, 0, 0, 1, 1, 1}, b1[6] = {5, 5, 5, 6, 6, 6};
    assert_true(tb_ff_occluders_shaft(none, b0, NULL, 0, b1, NULL, 0, &sh) && sh.n == 0);
    assert_true(tb_ff_shaft_visible(&sh, tb_vec3_make(0, 0, 0), tb_vec3_make(6, 6, 6)));
    tb_ff_occluders_free(none);
    free(rp);
    tb_ff_occluders_free(occ);
    free(p);
    tb_rad_mesh_free(&m);
    tb_scene_free(sc);
}

/* The shot update's channel kernels (update_internal.h): the baseline and
 * AVX builds give the same bits as the plain loops, over any split of the
 * ranges, with 31 channels (not a multiple of the vector width), elements
 * of the shooter and with F = 0 left alone, and infinities and NaN passed
 * through as the loops pass them. */
static void test_update_kernels(void **state)
{
    (void)state;
    enum { NV = 37, NE = 29, NC = 31 };
    double dBi[NC];
    float vff[NV], eff[NE], rho[NE * NC];
    uint32_t pel[NE], pof[NE];
    uint64_t x = 12345;
    for (int c = 0; c < NC; c++)
        dBi[c] = (double)((x = x * 6364136223846793005ull + 1442695040888963407ull) >> 11) * 0x1p-53 * 3.0;
    for (int v = 0; v < NV; v++)
        vff[v] = v % 5 == 0 ? 0.0f : (float)((x = x * 6364136223846793005ull + 1) >> 40) * 0x1p-24f;
    vff[3] = INFINITY;
    for (int j = 0; j < NE; j++) {
        float r = (float)((x = x * 6364136223846793005ull + 1) >> 40) * 0x1p-24f;
        eff[j] = j % 7 == 0 ? 0.0f : j % 11 == 0 ? -0.5f : r;
        pel[j] = (uint32_t)((j * 17) % NE); /* a permutation */
        pof[j] = (uint32_t)(j / 3);
        for (int c = 0; c < NC; c++)
            rho[j * NC + c] = (float)((x = x * 6364136223846793005ull + 1) >> 40) * 0x1p-24f * 0.99f;
    }
    eff[4] = NAN;
    static double ref[3][NV * NC], got[3][NV * NC];
    for (int k = 0; k < 3; k++)
        for (int i = 0; i < NV * NC; i++)
            ref[k][i] = 0.25 * (double)(i % 13);
    memcpy(got, ref, sizeof got);
    /* the plain loops, as tb__shoot had them */
    for (int v = 0; v < NV; v++)
        if ((double)vff[v] != 0.0)
            for (int c = 0; c < NC; c++)
                ref[0][v * NC + c] += dBi[c] * (double)vff[v];
    for (int q = 0; q < NE; q++) {
        uint32_t j = pel[q];
        double g = eff[j];
        if (pof[j] == 2 || !(g > 0.0))
            continue;
        for (int c = 0; c < NC; c++) {
            double dh = dBi[c] * g;
            ref[1][j * NC + c] += dh;
            ref[2][j * NC + c] += (double)rho[j * NC + c] * dh;
        }
    }
    for (int avx = 0; avx < 2; avx++) {
        if (avx && !tb__rad_have_avx())
            break;
        for (size_t cut = 0; cut <= NE; cut += 7) {
            double w[3][NV * NC];
            memcpy(w, got, sizeof w);
            tb__rad_update u = {NC, dBi, vff, eff, pel, pof, 2, rho, w[0], w[1], w[2]};
            size_t vcut = cut < NV ? cut : NV;
            if (avx) {
                tb__rad_update_vertices_avx(&u, vcut, NV);
                tb__rad_update_vertices_avx(&u, 0, vcut);
                tb__rad_update_elements_avx(&u, 0, cut);
                tb__rad_update_elements_avx(&u, cut, NE);
            } else {
                tb__rad_update_vertices(&u, vcut, NV);
                tb__rad_update_vertices(&u, 0, vcut);
                tb__rad_update_elements(&u, 0, cut);
                tb__rad_update_elements(&u, cut, NE);
            }
            assert_memory_equal(w[0], ref[0], sizeof ref[0]);
            assert_memory_equal(w[1], ref[1], NE * NC * sizeof(double));
            assert_memory_equal(w[2], ref[2], NE * NC * sizeof(double));
            /* He alone (the solver's deferred replay), then dB alone (its
             * shot): the same bits in each, the other array untouched */
            memcpy(w, got, sizeof w);
            tb__rad_update uh = {NC, dBi, vff, eff, pel, pof, 2, rho, w[0], w[1], NULL};
            tb__rad_update ud = {NC, dBi, vff, eff, pel, pof, 2, rho, w[0], NULL, w[2]};
            if (avx) {
                tb__rad_update_elements_avx(&uh, cut, NE);
                tb__rad_update_elements_avx(&uh, 0, cut);
                assert_memory_equal(w[2], got[2], NE * NC * sizeof(double));
                tb__rad_update_elements_avx(&ud, 0, cut);
                tb__rad_update_elements_avx(&ud, cut, NE);
            } else {
                tb__rad_update_elements(&uh, cut, NE);
                tb__rad_update_elements(&uh, 0, cut);
                assert_memory_equal(w[2], got[2], NE * NC * sizeof(double));
                tb__rad_update_elements(&ud, 0, cut);
                tb__rad_update_elements(&ud, cut, NE);
            }
            assert_memory_equal(w[0], got[0], sizeof got[0]);
            assert_memory_equal(w[1], ref[1], NE * NC * sizeof(double));
            assert_memory_equal(w[2], ref[2], NE * NC * sizeof(double));
        }
    }
    assert_true(isinf(ref[0][3 * NC]) || isnan(ref[0][3 * NC])); /* the infinity reached its vertex */
    assert_true(ref[1][0] == got[1][0]); /* element 0: F = 0, untouched */
}

/* The state's bits after a run: element radiosities (He), unshot (dB),
 * vertex irradiances (Hv) and the energy sums, appended to out[]. */
static size_t tb__state_bits(const tb_rad_solver *s, const tb_rad_mesh *m, double *out)
{
    size_t n = 0, nc = (size_t)m->nchannels;
    for (size_t i = 0; i < m->nelems; i++, n += 2 * nc) {
        tb_rad_element_radiosity(s, i, false, out + n);
        tb_rad_element_unshot(s, i, out + n + nc);
    }
    for (size_t v = 0; v < m->nverts; v++, n += nc)
        tb_rad_vertex_irradiance(s, v, out + n);
    tb_rad_energy e = tb_rad_solver_energy(s);
    out[n++] = e.absorbed, out[n++] = e.unshot, out[n++] = e.escaped;
    return n;
}

/* A report every 7 shots: the sum of the element radiosities then. */
typedef struct tb__report_log {
    const tb_rad_mesh *m;
    double sum[512];
    int n;
} tb__report_log;

static double tb__radiosity_sum(const tb_rad_solver *s, const tb_rad_mesh *m)
{
    double b[TB_CHANNELS_MAX], sum = 0.0;
    for (size_t i = 0; i < m->nelems; i++) {
        tb_rad_element_radiosity(s, i, false, b);
        for (int c = 0; c < m->nchannels; c++)
            sum += b[c];
    }
    return sum;
}

static tb_status tb__report_sum(void *user, const tb_rad_solver *s)
{
    tb__report_log *r = user;
    if (r->n < 512)
        r->sum[r->n++] = tb__radiosity_sum(s, r->m);
    return TB_OK;
}

/* tb_rad_solver_run logs the channel sums of cached shooters and replays
 * them later over the threads (docs/radiosity.md, "Solver"); shot by shot
 * (tb_rad_solver_step) they are made at once. Both must leave the same
 * bits in He, dB, Hv and the energy sums: on one level (dB deferred too)
 * and with patches (dB at once), with more shots than the log holds, with
 * the cache off, and with a report every 7 shots, which must see the state
 * as it is after that shot. */
static void test_deferred(void **state)
{
    (void)state;
    tb_scene *sc = tb_rad_test_load("scenes/cornell-box-rgb.mid");
    for (int level = 0; level < 2; level++) {
        tb_rad_mesh m;
        tb_rad_mesh_options mo = {.max_edge = 110, .patch_edge = level ? 220 : 0};
        assert_int_equal(tb_rad_mesh_from_scene(sc, &mo, &m), TB_OK);
        tb_rad_options o = {.samples = 4, .seed = 5};
        tb_rad_stop stop = {.threshold = 2e-3};
        size_t len = ((m.nelems * 2 + m.nverts) * (size_t)m.nchannels + 3) * sizeof(double);
        double *ref = malloc(len), *got = malloc(len);
        assert_non_null(ref), assert_non_null(got);
        /* eager: shot by shot, the sums of every 7th shot kept */
        tb_rad_solver *e = NULL;
        assert_int_equal(tb_rad_solver_create(&m, NULL, &o, &e), TB_OK);
        tb__report_log want = {.m = &m};
        uint64_t shots = 0;
        while (tb_rad_unshot_fraction(e) >= stop.threshold) {
            bool did = false;
            assert_int_equal(tb_rad_solver_step(e, &did), TB_OK);
            if (!did)
                break;
            if (++shots % 7 == 0)
                assert_int_equal(tb__report_sum(&want, e), TB_OK);
        }
        if (!level)
            assert_true(shots > 300); /* more than the log's 256: replays inside the run too */
        tb__state_bits(e, &m, ref);
        for (int run = 0; run < 3; run++) {
            tb_rad_options oc = o;
            oc.no_cache = run == 1;
            tb_rad_solver *d = NULL;
            assert_int_equal(tb_rad_solver_create(&m, NULL, &oc, &d), TB_OK);
            tb__report_log seen = {.m = &m};
            assert_int_equal(tb_rad_solver_run(d, &stop, run == 2 ? tb__report_sum : NULL, &seen, 7), TB_OK);
            assert_int_equal(tb_rad_solver_shots(d), shots);
            tb__state_bits(d, &m, got);
            assert_memory_equal(got, ref, len);
            if (run == 2) {
                assert_true(seen.n >= want.n && want.n > 10);
                assert_memory_equal(seen.sum, want.sum, (size_t)want.n * sizeof want.sum[0]);
            }
            tb_rad_solver_free(d);
        }
        tb_rad_solver_free(e);
        free(ref), free(got);
        tb_rad_mesh_free(&m);
    }
    tb_scene_free(sc);
}

int main(int argc, char **argv)
{
    if (argc > 1)
        cmocka_set_test_filter(argv[1]);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_furnace_raycast), cmocka_unit_test(test_furnace_hemicube),
        cmocka_unit_test(test_sphere_cap),      cmocka_unit_test(test_energy),
        cmocka_unit_test(test_reciprocity),     cmocka_unit_test(test_threads),
        cmocka_unit_test(test_patches_csv),     cmocka_unit_test(test_continue), cmocka_unit_test(test_corner_ambient),
        cmocka_unit_test(test_pack),
        cmocka_unit_test(test_errors),          cmocka_unit_test(test_cornell_image),
        cmocka_unit_test(test_occluders), cmocka_unit_test(test_shaft), cmocka_unit_test(test_update_kernels),
        cmocka_unit_test(test_deferred),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
