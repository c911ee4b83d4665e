/* Patches over elements (Cohen, Greenberg, Immel and Brock 1986;
 * docs/radiosity.md, "Patches and elements"): the two-level mesh (patches
 * tiled by their elements, conforming), the furnace and the energy
 * bookkeeping with patches shooting, a patch's unshot power as the sum of
 * its elements', the Cornell box against the one-level solution on the same
 * elements, thread independence, bad meshes and options. */
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
#include "host/render/scene.h"
#include "rad_measure.h"
#include "rad_test.h"
#include "tb_test.h"

static int tb__nv(const tb_rad_element *e) { return e->v[3] == TB_RAD_NONE ? 3 : 4; }

/* Newell area of a polygon. */
static double tb__poly_area(const tb_ff_polygon *p)
{
    double n[3] = {0, 0, 0};
    for (int k = 0; k < p->n; k++) {
        tb_vec3 a = p->v[k], b = p->v[(k + 1) % p->n];
        n[0] += ((double)a.y - b.y) * ((double)a.z + b.z);
        n[1] += ((double)a.z - b.z) * ((double)a.x + b.x);
        n[2] += ((double)a.x - b.x) * ((double)a.y + b.y);
    }
    return 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

/* An undirected edge between two positions (sorted), for the conformity check. */
typedef struct tb__edge {
    float a[3], b[3];
} tb__edge;

static int tb__cmp_edge(const void *x, const void *y) { return memcmp(x, y, sizeof(tb__edge)); }

/* The furnace cube cut into 2 x 2 patches of 2 x 2 elements per face: each
 * patch is tiled by its elements (areas sum to the outline's, every element
 * corner inside the outline's bounds), and the closed cube's elements meet
 * edge to edge: every edge, by position, is used by exactly two elements
 * (a T-junction at a patch boundary would leave edges used once). */
static void test_mesh(void **state)
{
    (void)state;
    tb_scene *sc = tb_rad_test_load("tests/radiosity/furnace.mid");
    tb_rad_mesh m;
    tb_rad_mesh_options mo = {.max_edge = 0.25, .patch_edge = 0.5};
    assert_int_equal(tb_rad_mesh_from_scene(sc, &mo, &m), TB_OK);
    assert_int_equal(m.nelems, 6 * 16);
    assert_int_equal(m.npatches, 6 * 4);
    double *area = calloc(m.npatches, sizeof *area);
    int *count = calloc(m.npatches, sizeof *count);
    assert_non_null(area), assert_non_null(count);
    for (size_t i = 0; i < m.nelems; i++) {
        uint32_t p = m.patch[i];
        assert_true(p < m.npatches);
        area[p] += m.elems[i].area;
        count[p]++;
        const tb_ff_polygon *pp = &m.patch_poly[p];
        for (int k = 0; k < tb__nv(&m.elems[i]); k++) {
            tb_vec3 v = m.verts[m.elems[i].v[k]].p;
            float lo[3] = {1e9f, 1e9f, 1e9f}, hi[3] = {-1e9f, -1e9f, -1e9f};
            for (int q = 0; q < pp->n; q++) {
                float c[3] = {pp->v[q].x, pp->v[q].y, pp->v[q].z};
                for (int x = 0; x < 3; x++)
                    lo[x] = fminf(lo[x], c[x]), hi[x] = fmaxf(hi[x], c[x]);
            }
            float c[3] = {v.x, v.y, v.z};
            for (int x = 0; x < 3; x++)
                assert_true(c[x] >= lo[x] - 1e-6f && c[x] <= hi[x] + 1e-6f);
        }
    }
    for (size_t p = 0; p < m.npatches; p++) {
        assert_int_equal(count[p], 4);
        tb_assert_near(area[p], tb__poly_area(&m.patch_poly[p]), 1e-6);
        tb_assert_near(area[p], 0.25, 1e-6);
    }
    size_t ned = 0;
    tb__edge *ed = malloc(sizeof *ed * 4 * m.nelems);
    assert_non_null(ed);
    for (size_t i = 0; i < m.nelems; i++)
        for (int k = 0; k < tb__nv(&m.elems[i]); k++) {
            tb_vec3 a = m.verts[m.elems[i].v[k]].p, b = m.verts[m.elems[i].v[(k + 1) % tb__nv(&m.elems[i])]].p;
            float pa[3] = {a.x, a.y, a.z}, pb[3] = {b.x, b.y, b.z};
            tb__edge e;
            memset(&e, 0, sizeof e);
            bool swap = memcmp(pa, pb, sizeof pa) > 0;
            memcpy(e.a, swap ? pb : pa, sizeof pa), memcpy(e.b, swap ? pa : pb, sizeof pb);
            ed[ned++] = e;
        }
    qsort(ed, ned, sizeof *ed, tb__cmp_edge);
    for (size_t k = 0; k < ned;) {
        size_t r = k;
        while (r < ned && !tb__cmp_edge(&ed[r], &ed[k]))
            r++;
        assert_int_equal(r - k, 2);
        k = r;
    }
    free(ed), free(area), free(count);
    tb_rad_mesh_free(&m);
    tb_scene_free(sc);
}

/* Furnace with patches shooting: B = E / (1 - rho) = 2 on every element
 * (ambient included: it stands for the unshot rest) and every corner, with
 * both form-factor methods; 3 x 3 patches of 2 x 2 elements per face. */
static void tb__furnace(tb_rad_ff_method ff, double tol)
{
    tb_scene *sc = tb_rad_test_load("tests/radiosity/furnace.mid");
    tb_rad_mesh m;
    tb_rad_mesh_options mo = {.max_edge = 0.2, .patch_edge = 0.4};
    assert_int_equal(tb_rad_mesh_from_scene(sc, &mo, &m), TB_OK);
    assert_int_equal(m.nelems, 6 * 36);
    assert_int_equal(m.npatches, 6 * 9);
    tb_rad_options o = {.ff = ff, .samples = 16, .hemicube_res = 128};
    double thr = 1e-3;
    tb_rad_solver *s = tb_rad_test_solve(&m, &o, thr);
    assert_int_equal(tb_rad_solver_npatches(s), 54);
    double b[TB_CHANNELS_MAX], worst = 0.0, worst_c = 0.0, worst_p = 0.0;
    for (size_t i = 0; i < m.nelems; i++) {
        tb_rad_element_radiosity(s, i, true, b);
        for (int c = 0; c < m.nchannels; c++)
            worst = fmax(worst, fabs(b[c] - 2.0) / 2.0);
        if (getenv("TB_RAD_DEBUG") && fabs(b[0] - 2.0) > 0.04)
            print_message("element %zu (patch %u) at %g %g %g: %g\n", i, m.patch[i], (double)m.elems[i].centroid.x,
                          (double)m.elems[i].centroid.y, (double)m.elems[i].centroid.z, b[0]);
        for (int k = 0; k < tb__nv(&m.elems[i]); k++) {
            tb_rad_corner_radiosity(s, i, k, true, b);
            worst_c = fmax(worst_c, fabs(b[0] - 2.0) / 2.0);
        }
    }
    for (size_t p = 0; p < m.npatches; p++) {
        tb_rad_patch_radiosity(s, p, true, b);
        worst_p = fmax(worst_p, fabs(b[0] - 2.0) / 2.0);
    }
    print_message("furnace with patches, %s: worst relative error %.4f elements, %.4f corners, %.4f patches, "
                  "%llu shots\n",
                  ff == TB_RAD_FF_HEMICUBE ? "hemicube" : "raycast", worst, worst_c, worst_p,
                  (unsigned long long)tb_rad_solver_shots(s));
    assert_true(worst < tol);
    assert_true(worst_c < tol);
    assert_true(worst_p < tol);
    tb_rad_solver_free(s);
    tb_rad_mesh_free(&m);
    tb_scene_free(sc);
}

static void test_furnace_raycast(void **state)
{
    (void)state;
    tb__furnace(TB_RAD_FF_RAYCAST, 0.005); /* measured 0.13%: near every patch, the exact element mean */
}

/* The hemicube sits at the patch's centroid; next to the patch the exact
 * element mean times the hemicube's visible fraction (measured 1.4%; 7.5%
 * with the centroid's hemicube alone). */
static void test_furnace_hemicube(void **state)
{
    (void)state;
    tb__furnace(TB_RAD_FF_HEMICUBE, 0.03);
}

/* Only the floor emits. Bookkeeping to rounding after every shot; the
 * queue's patch powers are the sums of their elements' unshot powers
 * (recomputed here from the elements' unshot radiosity), and a patch just
 * shot holds nothing; at the end the absorbed power equals the one
 * recomputed from the solution, sum (1 - rho) (B - E) / rho A. */
static void test_energy(void **state)
{
    (void)state;
    tb_scene *sc = tb_rad_test_load("tests/radiosity/furnace.mid");
    tb_rad_mesh m;
    tb_rad_mesh_options mo = {.max_edge = 0.125, .patch_edge = 0.5};
    assert_int_equal(tb_rad_mesh_from_scene(sc, &mo, &m), TB_OK);
    for (size_t i = 0; i < m.nelems; i++)
        if (m.elems[i].object != 0)
            for (int c = 0; c < m.nchannels; c++)
                m.emission[i * (size_t)m.nchannels + (size_t)c] = 0.0f;
    tb_rad_options o = {.samples = 16};
    tb_rad_solver *s = NULL;
    assert_int_equal(tb_rad_solver_create(&m, NULL, &o, &s), TB_OK);
    int nc = m.nchannels;
    double *sum = malloc(sizeof *sum * m.npatches);
    assert_non_null(sum);
    double worst_q = 0.0, u[TB_CHANNELS_MAX];
    for (int shot = 0; shot < 400 && tb_rad_unshot_fraction(s) >= 1e-2; shot++) {
        bool did;
        assert_int_equal(tb_rad_solver_step(s, &did), TB_OK);
        assert_true(did);
        for (size_t p = 0; p < m.npatches; p++)
            sum[p] = 0.0;
        for (size_t i = 0; i < m.nelems; i++) {
            tb_rad_element_unshot(s, i, u);
            for (int c = 0; c < nc; c++)
                sum[m.patch[i]] += u[c] * m.elems[i].area;
        }
        double top = 0.0;
        size_t ptop = 0;
        for (size_t p = 0; p < m.npatches; p++) {
            double q = tb_rad_patch_unshot_power(s, p);
            worst_q = fmax(worst_q, fabs(q - sum[p]) / fmax(sum[p], 1e-300));
            if (q > top)
                top = q, ptop = p;
        }
        (void)ptop;
        tb_rad_energy en = tb_rad_solver_energy(s);
        tb_assert_near(en.absorbed + en.unshot + en.escaped, en.emitted, 1e-9 * en.emitted);
    }
    print_message("patch unshot power against the sum of its elements': worst relative difference %.3g\n", worst_q);
    assert_true(worst_q < 1e-12);
    /* the next shooter is the patch with most unshot power; after its shot its elements hold nothing */
    size_t best = 0;
    for (size_t p = 1; p < m.npatches; p++)
        if (tb_rad_patch_unshot_power(s, p) > tb_rad_patch_unshot_power(s, best))
            best = p;
    assert_true(tb_rad_patch_unshot_power(s, best) > 0.0);
    bool did;
    assert_int_equal(tb_rad_solver_step(s, &did), TB_OK);
    assert_true(did);
    assert_true(tb_rad_patch_unshot_power(s, best) == 0.0);
    for (size_t i = 0; i < m.nelems; i++)
        if (m.patch[i] == best) {
            tb_rad_element_unshot(s, i, u);
            for (int c = 0; c < nc; c++)
                assert_true(u[c] == 0.0);
        }
    tb_rad_stop stop = {.threshold = 1e-2};
    assert_int_equal(tb_rad_solver_run(s, &stop, NULL, NULL, 0), TB_OK);
    tb_rad_energy en = tb_rad_solver_energy(s);
    print_message("energy with patches: emitted %g absorbed %g unshot %g escaped %g (%.2f%%)\n", en.emitted,
                  en.absorbed, en.unshot, en.escaped, 100.0 * en.escaped / en.emitted);
    tb_rad_test_check_energy(s, &m);
    free(sum);
    tb_rad_solver_free(s);
    tb_rad_mesh_free(&m);
    tb_scene_free(sc);
}

/* The Cornell box on the same elements (max edge 60, patches of 120): the
 * two-level solution against a one-level reference (64 samples, to 1e-3),
 * next to the one-level solution with the same samples and threshold. The
 * patches cost fewer shots and agree with the reference nearly as well. */
static void test_cornell(void **state)
{
    (void)state;
    tb_scene *sc = tb_rad_test_load("scenes/cornell-box-rgb.mid");
    tb_rad_mesh m;
    tb_rad_mesh_options mo = {.max_edge = 60, .patch_edge = 120};
    assert_int_equal(tb_rad_mesh_from_scene(sc, &mo, &m), TB_OK);
    size_t np = m.npatches;
    assert_true(np > 0 && np < m.nelems / 2);
    m.npatches = 0; /* the same elements, one level */
    tb_rad_options ro = {.samples = 64};
    tb_rad_solver *s = tb_rad_test_solve(&m, &ro, 1e-3);
    double *ref = tb_rad_test_radiosities(s);
    tb_rad_solver_free(s);
    tb_rad_options o = {.samples = 4};
    s = tb_rad_test_solve(&m, &o, 1e-2);
    double *one = tb_rad_test_radiosities(s);
    uint64_t shots1 = tb_rad_solver_shots(s);
    tb_rad_solver_free(s);
    m.npatches = np;
    s = tb_rad_test_solve(&m, &o, 1e-2);
    double *two = tb_rad_test_radiosities(s);
    uint64_t shots2 = tb_rad_solver_shots(s);
    tb_rad_solver_free(s);
    double e1 = tb_rad_test_nrmse(&m, one, ref), e2 = tb_rad_test_nrmse(&m, two, ref), e12 = tb_rad_test_nrmse(&m, two, one);
    print_message("Cornell box, %zu elements, %zu patches: NRMSE one level %.4f (%llu shots), two levels %.4f "
                  "(%llu shots), two against one %.4f\n",
                  m.nelems, np, e1, (unsigned long long)shots1, e2, (unsigned long long)shots2, e12);
    assert_true(shots2 < shots1 / 2);
    assert_true(e2 < 0.05);
    assert_true(e12 < 0.05);
    free(ref), free(one), free(two);
    tb_rad_mesh_free(&m);
    tb_scene_free(sc);
}

/* With patches, the same CSV bytes with 1 and 2 threads, for both methods;
 * the CSV ends with the patch column. */
static void test_threads(void **state)
{
    (void)state;
    tb_scene *sc = tb_rad_test_load("scenes/cornell-box-rgb.mid");
    tb_rad_mesh m;
    tb_rad_mesh_options mo = {.max_edge = 60, .patch_edge = 150};
    assert_int_equal(tb_rad_mesh_from_scene(sc, &mo, &m), TB_OK);
    char p1[1024], p2[1024];
    snprintf(p1, sizeof p1, "%s/rad_patches_threads1.csv", tb_test_tmpdir());
    snprintf(p2, sizeof p2, "%s/rad_patches_threads2.csv", tb_test_tmpdir());
    for (int method = 0; method < 2; method++) {
        for (int t = 1; t <= 2; t++) {
            omp_set_num_threads(t);
            tb_rad_options o = {.ff = method ? TB_RAD_FF_HEMICUBE : TB_RAD_FF_RAYCAST, .samples = 4, .seed = 7,
                                .hemicube_res = 64};
            tb_rad_solver *s = tb_rad_test_solve(&m, &o, 1e-2);
            assert_int_equal(tb_rad_write_patches(s, t == 1 ? p1 : p2), TB_OK);
            tb_rad_solver_free(s);
        }
        size_t n1, n2;
        char *a = tb_rad_test_slurp(p1, &n1), *b = tb_rad_test_slurp(p2, &n2);
        assert_int_equal(n1, n2);
        assert_memory_equal(a, b, n1);
        const char *nl = strchr(a, '\n');
        assert_non_null(nl);
        assert_true(nl - a > 6 && !strncmp(nl - 6, ",patch", 6));
        free(a), free(b);
    }
    tb_rad_mesh_free(&m);
    tb_scene_free(sc);
}

/* Bad patch options and meshes are refused. */
static void test_errors(void **state)
{
    (void)state;
    tb_scene *sc = tb_rad_test_load("tests/radiosity/furnace.mid");
    tb_rad_mesh m;
    tb_rad_mesh_options bad[] = {
        {.max_edge = 0.25, .patch_edge = 0.2}, /* patches smaller than elements */
        {.max_area = 0.04, .patch_edge = 0.1}, /* likewise, through the area */
        {.patch_edge = 0.5},                   /* no element size */
        {.max_edge = 0.25, .patch_edge = -1},
        {.max_edge = 0.25, .patch_area = NAN},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++)
        assert_int_equal(tb_rad_mesh_from_scene(sc, &bad[k], &m), TB_ERR_ARG);
    tb_rad_mesh_options mo = {.max_edge = 0.25, .patch_area = 0.25};
    assert_int_equal(tb_rad_mesh_from_scene(sc, &mo, &m), TB_OK);
    assert_int_equal(m.npatches, 24);
    tb_rad_solver *s = NULL;
    m.patch[3] = (uint32_t)m.npatches; /* out of range */
    assert_int_equal(tb_rad_solver_create(&m, NULL, NULL, &s), TB_ERR_ARG);
    uint32_t keep = m.patch[0];
    for (size_t i = 0; i < m.nelems; i++) /* patch `keep` loses its elements */
        if (m.patch[i] == keep || i == 3)
            m.patch[i] = keep == 0 ? 1 : 0;
    assert_int_equal(tb_rad_solver_create(&m, NULL, NULL, &s), TB_ERR_ARG);
    assert_null(s);
    tb_rad_mesh_free(&m);
    tb_scene_free(sc);
}

int main(int argc, char **argv)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mesh),   cmocka_unit_test(test_furnace_raycast), cmocka_unit_test(test_furnace_hemicube),
        cmocka_unit_test(test_energy), cmocka_unit_test(test_cornell),         cmocka_unit_test(test_threads),
        cmocka_unit_test(test_errors),
    };
    if (argc > 1)
        cmocka_set_test_filter(argv[1]);
    return cmocka_run_group_tests(tests, NULL, NULL);
}
