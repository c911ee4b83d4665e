/* host/radiosity/adaptive: Cohen et al. 1986 adaptive subdivision on a
 * scene with a sharp shadow (a small square emitter over a small square
 * occluder over a floor). Only the emitter's light reaches the floor
 * directly and what the floor reflects is absorbed by the black emitter
 * and occluder, so one shot gives every solution and the floor's
 * radiosity is rho E F(x -> visible emitter): the solutions differ only by
 * how their meshes represent it. Checked: the refined elements gather at
 * the penumbra, the error against a uniformly fine mesh is below that of a
 * uniform mesh of the same element count, the mesh stays conforming,
 * unshot power is carried over exactly, results are deterministic, the
 * limits (levels, minimum area) hold and bad options are refused. */
#include "tb_test.h"

#include <string.h>

#include "host/radiosity/adaptive.h"
#include "host/radiosity/radiosity.h"
#include "util/container/hash_table.h"

/* Geometry: floor [0,1]^2 at z = 0; occluder [0.35,0.65]^2 at z = 0.3;
 * emitter [0.475,0.525]^2 at z = 0.8. The penumbra on the floor along x
 * runs from x_e + (0.35 - x_e) 0.8 / 0.5 for x_e = 0.525 (0.245) to
 * x_e = 0.475 (0.275), and symmetrically (0.725 to 0.755); likewise along
 * y: a shadow edge 0.03 wide, a quarter of an input element. */
#define OCC_LO 0.35f
#define OCC_HI 0.65f
#define OCC_Z 0.3f
#define EMIT_LO 0.475f
#define EMIT_HI 0.525f
#define EMIT_Z 0.8f
#define PEN_IN 0.275
#define PEN_OUT 0.245
#define FLOOR_RHO 0.5f
#define EMISSION 100.0f

static void push_vert(tb_rad_mesh *m, size_t *cap, float x, float y, float z, float nz)
{
    if (m->nverts == *cap) {
        *cap = *cap ? 2 * *cap : 64;
        m->verts = realloc(m->verts, sizeof *m->verts * *cap);
        assert_non_null(m->verts);
    }
    m->verts[m->nverts++] = (tb_rad_vertex){{x, y, z}, {0, 0, nz}};
}

static void push_elem(tb_rad_mesh *m, size_t *cap, uint32_t a, uint32_t b, uint32_t c, uint32_t d, uint32_t obj,
                      float rho, float e)
{
    if (m->nelems == *cap) {
        *cap = *cap ? 2 * *cap : 64;
        m->elems = realloc(m->elems, sizeof *m->elems * *cap);
        m->rho = realloc(m->rho, sizeof *m->rho * 3 * *cap);
        m->emission = realloc(m->emission, sizeof *m->emission * 3 * *cap);
        assert_true(m->elems && m->rho && m->emission);
    }
    size_t i = m->nelems++;
    m->elems[i] = (tb_rad_element){.v = {a, b, c, d}, .object = obj, .parent = TB_RAD_NONE};
    for (int k = 0; k < 3; k++)
        m->rho[3 * i + k] = rho, m->emission[3 * i + k] = e;
}

/* The scene with the floor as a k x k grid (object 0), the occluder
 * (object 1) and the emitter (object 2) one quad each, facing down. */
static void shadow_scene(tb_rad_mesh *m, uint32_t k)
{
    tb_rad_mesh_init(m);
    m->nchannels = 3;
    size_t vc = 0, ec = 0;
    for (uint32_t j = 0; j <= k; j++)
        for (uint32_t i = 0; i <= k; i++)
            push_vert(m, &vc, (float)i / (float)k, (float)j / (float)k, 0, 1);
    for (uint32_t j = 0; j < k; j++)
        for (uint32_t i = 0; i < k; i++) {
            uint32_t a = j * (k + 1) + i;
            push_elem(m, &ec, a, a + 1, a + k + 2, a + k + 1, 0, FLOOR_RHO, 0);
        }
    float box[2][3] = {{OCC_LO, OCC_HI, OCC_Z}, {EMIT_LO, EMIT_HI, EMIT_Z}};
    for (int o = 0; o < 2; o++) {
        uint32_t b = (uint32_t)m->nverts;
        float lo = box[o][0], hi = box[o][1], z = box[o][2];
        push_vert(m, &vc, lo, lo, z, -1);
        push_vert(m, &vc, hi, lo, z, -1);
        push_vert(m, &vc, hi, hi, z, -1);
        push_vert(m, &vc, lo, hi, z, -1);
        /* counter-clockwise seen from below */
        push_elem(m, &ec, b, b + 3, b + 2, b + 1, 1 + (uint32_t)o, 0, o == 1 ? EMISSION : 0);
    }
    assert_int_equal(tb_rad_mesh_update_geometry(m), TB_OK);
}

static const tb_rad_options ray_opt = {.ff = TB_RAD_FF_RAYCAST, .samples = 64, .seed = 5};
/* After the emitter's shot the unshot fraction is the floor's reflected
 * part (well below 0.9): one shot per solve. */
static const tb_rad_stop one_shot = {.threshold = 0.9};

static tb_rad_solver *solve_uniform_with(uint32_t k, const tb_rad_options *o)
{
    tb_rad_mesh m;
    shadow_scene(&m, k);
    tb_rad_solver *s;
    if (tb_rad_solver_create(&m, NULL, o, &s))
        fail_msg("%s", tb_last_error());
    assert_int_equal(tb_rad_solver_run(s, &one_shot, NULL, NULL, 0), TB_OK);
    assert_int_equal(tb_rad_solver_shots(s), 1);
    tb_rad_mesh_free(&m);
    return s;
}

static tb_rad_solver *solve_uniform(uint32_t k) { return solve_uniform_with(k, &ray_opt); }

/* Floor elements of a solution, bucketed in a 32 x 32 grid over [0,1]^2
 * for point lookups. */
typedef struct floor_index {
    const tb_rad_solver *s;
    tb_array cell[32][32]; /* uint32_t element ids */
} floor_index;

static void index_floor(floor_index *fi, const tb_rad_solver *s)
{
    fi->s = s;
    const tb_rad_mesh *m = tb_rad_solver_mesh(s);
    for (int a = 0; a < 32; a++)
        for (int b = 0; b < 32; b++)
            tb_array_init(&fi->cell[a][b], sizeof(uint32_t));
    for (size_t i = 0; i < m->nelems; i++) {
        const tb_rad_element *e = &m->elems[i];
        if (e->object != 0)
            continue;
        float lo[2] = {2, 2}, hi[2] = {-1, -1};
        for (int k = 0; k < (e->v[3] == TB_RAD_NONE ? 3 : 4); k++) {
            tb_vec3 p = m->verts[e->v[k]].p;
            lo[0] = fminf(lo[0], p.x), lo[1] = fminf(lo[1], p.y), hi[0] = fmaxf(hi[0], p.x), hi[1] = fmaxf(hi[1], p.y);
        }
        int x0 = (int)fmaxf(0, lo[0] * 32 - 1e-3f), x1 = (int)fminf(31, hi[0] * 32 + 1e-3f);
        int y0 = (int)fmaxf(0, lo[1] * 32 - 1e-3f), y1 = (int)fminf(31, hi[1] * 32 + 1e-3f);
        uint32_t id = (uint32_t)i;
        for (int a = x0; a <= x1; a++)
            for (int b = y0; b <= y1; b++)
                tb_array_push(&fi->cell[a][b], &id);
    }
}

static void free_index(floor_index *fi)
{
    for (int a = 0; a < 32; a++)
        for (int b = 0; b < 32; b++)
            tb_array_free(&fi->cell[a][b]);
}

/* The displayed floor radiosity (red channel) at (x, y): the corners'
 * values interpolated linearly over the triangles (v0 v1 v2), (v0 v2 v3)
 * of the element containing the point, as the image display does. */
static double floor_value(const floor_index *fi, double x, double y)
{
    const tb_rad_mesh *m = tb_rad_solver_mesh(fi->s);
    int a = (int)fmin(31, x * 32), b = (int)fmin(31, y * 32);
    const tb_array *c = &fi->cell[a][b];
    for (size_t t = 0; t < c->len; t++) {
        uint32_t i = TB_ARRAY_AT(c, uint32_t, t);
        const tb_rad_element *e = &m->elems[i];
        int n = e->v[3] == TB_RAD_NONE ? 3 : 4;
        for (int tri = 0; tri < n - 2; tri++) {
            int k[3] = {0, tri + 1, tri + 2};
            double px[3], py[3];
            for (int q = 0; q < 3; q++)
                px[q] = m->verts[e->v[k[q]]].p.x, py[q] = m->verts[e->v[k[q]]].p.y;
            double d = (px[1] - px[0]) * (py[2] - py[0]) - (px[2] - px[0]) * (py[1] - py[0]);
            double l1 = ((x - px[0]) * (py[2] - py[0]) - (px[2] - px[0]) * (y - py[0])) / d;
            double l2 = ((px[1] - px[0]) * (y - py[0]) - (x - px[0]) * (py[1] - py[0])) / d;
            double l0 = 1 - l1 - l2;
            if (l0 < -1e-9 || l1 < -1e-9 || l2 < -1e-9)
                continue;
            double v = 0, w[3] = {l0, l1, l2};
            for (int q = 0; q < 3; q++) {
                double b3[3];
                tb_rad_corner_radiosity(fi->s, i, k[q], false, b3);
                v += w[q] * b3[0];
            }
            return v;
        }
    }
    fail_msg("no floor element contains (%g, %g)", x, y);
    return 0;
}

/* RMS difference of two solutions' floor radiosity over 128 x 128 points. */
static double floor_rms(const tb_rad_solver *a, const tb_rad_solver *b)
{
    floor_index *fa = malloc(sizeof *fa), *fb = malloc(sizeof *fb);
    index_floor(fa, a);
    index_floor(fb, b);
    double s = 0;
    int n = 128;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            double x = (i + 0.5) / n, y = (j + 0.5) / n;
            double d = floor_value(fa, x, y) - floor_value(fb, x, y);
            s += d * d;
        }
    free_index(fa), free_index(fb);
    free(fa), free(fb);
    return sqrt(s / (n * n));
}

static size_t count_object(const tb_rad_mesh *m, uint32_t obj)
{
    size_t n = 0;
    for (size_t i = 0; i < m->nelems; i++)
        n += m->elems[i].object == obj;
    return n;
}

/* Conformity of a radiosity mesh, independently: every directed edge used
 * once at most; an edge used once is on the boundary of its object's
 * input square; no vertex inside any element edge. */
static void check_conforming(const tb_rad_mesh *m)
{
    tb_htab dir;
    tb_htab_init(&dir, TB_HTAB_U64);
    for (size_t i = 0; i < m->nelems; i++) {
        const tb_rad_element *e = &m->elems[i];
        int n = e->v[3] == TB_RAD_NONE ? 3 : 4;
        for (int k = 0; k < n; k++) {
            uint64_t key = (uint64_t)e->v[k] << 32 | e->v[(k + 1) % n];
            assert_false(tb_htab_get(&dir, key, NULL));
            tb_htab_put(&dir, key, i);
        }
    }
    size_t it = 0;
    tb_htab_entry en;
    while (tb_htab_next(&dir, &it, &en)) {
        uint32_t a = (uint32_t)(en.key >> 32), b = (uint32_t)en.key;
        if (tb_htab_get(&dir, (uint64_t)b << 32 | a, NULL))
            continue;
        /* a boundary edge: both ends on one side of the floor (or of a
         * square: those are single elements) */
        tb_vec3 p = m->verts[a].p, q = m->verts[b].p;
        bool side = (p.x == q.x && (p.x == 0 || p.x == 1)) || (p.y == q.y && (p.y == 0 || p.y == 1)) || p.z != 0;
        if (!side)
            fail_msg("edge %u-%u (%g,%g)-(%g,%g) is used once inside the floor: a crack or T-junction", a, b, p.x, p.y,
                     q.x, q.y);
    }
    tb_htab_free(&dir);
    for (size_t i = 0; i < m->nelems; i++) {
        const tb_rad_element *e = &m->elems[i];
        int n = e->v[3] == TB_RAD_NONE ? 3 : 4;
        for (int k = 0; k < n; k++) {
            tb_vec3 a = m->verts[e->v[k]].p, b = m->verts[e->v[(k + 1) % n]].p;
            for (size_t v = 0; v < m->nverts; v++) {
                tb_vec3 p = m->verts[v].p;
                if (p.z != a.z || v == e->v[k] || v == e->v[(k + 1) % n])
                    continue;
                double ux = (double)b.x - a.x, uy = (double)b.y - a.y, wx = (double)p.x - a.x, wy = (double)p.y - a.y;
                double t = (ux * wx + uy * wy) / (ux * ux + uy * uy), cr = ux * wy - uy * wx;
                if (t > 1e-9 && t < 1 - 1e-9 && fabs(cr) <= 1e-9 * (ux * ux + uy * uy))
                    fail_msg("vertex %zu lies inside an edge of element %zu (T-vertex)", v, i);
            }
        }
    }
}

/* Elements per unit area of floor near the penumbra (centroid in the
 * penumbra ring [0.245, 0.755]^2 minus [0.275, 0.725]^2 widened by 0.06)
 * and elsewhere. */
static void penumbra_density(const tb_rad_mesh *m, double *near, double *far)
{
    size_t nn = 0, nf = 0;
    double an = 0, af = 0;
    for (size_t i = 0; i < m->nelems; i++) {
        const tb_rad_element *e = &m->elems[i];
        if (e->object != 0)
            continue;
        double cx = e->centroid.x, cy = e->centroid.y;
        bool outer = cx > PEN_OUT - 0.06 && cx < 1 - PEN_OUT + 0.06 && cy > PEN_OUT - 0.06 && cy < 1 - PEN_OUT + 0.06;
        bool inner = cx > PEN_IN + 0.06 && cx < 1 - PEN_IN - 0.06 && cy > PEN_IN + 0.06 && cy < 1 - PEN_IN - 0.06;
        if (outer && !inner)
            nn++, an += e->area;
        else
            nf++, af += e->area;
    }
    *near = nn / an;
    *far = nf / af;
}

static void test_shadow_edge(void **state)
{
    (void)state;
    tb_rad_mesh m;
    shadow_scene(&m, 8);
    tb_rad_adapt_options a = {.threshold = 0.3, .max_levels = 3};
    tb_rad_solver *s;
    tb_rad_adapt_stats st;
    if (tb_rad_adapt_solve(&m, &ray_opt, &one_shot, &a, &s, &st))
        fail_msg("%s", tb_last_error());
    const tb_rad_mesh *am = tb_rad_solver_mesh(s);
    size_t nfloor = count_object(am, 0);
    /* the refined mesh came back in m: the solver's, element for element */
    assert_int_equal(m.nelems, am->nelems);
    assert_int_equal(m.nverts, am->nverts);
    assert_memory_equal(m.elems, am->elems, sizeof *m.elems * m.nelems);
    assert_memory_equal(m.verts, am->verts, sizeof *m.verts * m.nverts);
    assert_memory_equal(m.rho, am->rho, sizeof *m.rho * 3 * m.nelems);
    print_message("adaptive: %d rounds, %zu -> %zu elements (%zu on the floor), %zu marked, %zu gathered\n", st.rounds,
                  st.elems_in, st.elems_out, nfloor, st.marked, st.gathered);
    assert_int_equal(st.rounds, a.max_levels);
    assert_int_equal(st.elems_out, am->nelems);
    check_conforming(am);
    /* every element's parent is the input element it lies in */
    tb_rad_mesh in;
    shadow_scene(&in, 8);
    for (size_t i = 0; i < am->nelems; i++) {
        const tb_rad_element *e = &am->elems[i];
        if (e->parent == TB_RAD_NONE)
            continue;
        assert_true(e->parent < in.nelems);
        const tb_rad_element *p = &in.elems[e->parent];
        assert_int_equal(p->object, e->object);
        tb_vec3 lo = in.verts[p->v[0]].p, hi = in.verts[p->v[2]].p;
        assert_true(e->centroid.x >= lo.x && e->centroid.x <= hi.x && e->centroid.y >= lo.y && e->centroid.y <= hi.y);
    }
    tb_rad_mesh_free(&in);
    double near, far;
    penumbra_density(am, &near, &far);
    print_message("element density: %.0f per unit area near the penumbra, %.0f elsewhere\n", near, far);
    assert_true(near > 3 * far);

    /* error against a uniformly fine floor (96 x 96), against a uniform
     * floor with as many elements as the adaptive one */
    tb_rad_options ref_opt = ray_opt;
    ref_opt.samples = 256; /* finer in space and less noisy than the solutions compared */
    ref_opt.seed = 77;
    tb_rad_solver *fine = solve_uniform_with(96, &ref_opt);
    uint32_t k = (uint32_t)lround(sqrt((double)nfloor));
    tb_rad_solver *uni = solve_uniform(k), *coarse = solve_uniform(8);
    double e_ad = floor_rms(s, fine), e_uni = floor_rms(uni, fine), e_coarse = floor_rms(coarse, fine);
    double top = 0, b3[3];
    for (size_t i = 0; i < tb_rad_solver_mesh(fine)->nelems; i++) {
        tb_rad_element_radiosity(fine, i, false, b3);
        if (tb_rad_solver_mesh(fine)->elems[i].object == 0)
            top = fmax(top, b3[0]);
    }
    print_message("brightest floor element of the reference: %.4f W/m^2\n", top);
    print_message("RMS floor error vs 96x96: adaptive %.4f (%zu elements), uniform %ux%u %.4f, input 8x8 %.4f\n",
                  e_ad, nfloor, k, k, e_uni, e_coarse);
    assert_true(e_ad < 0.7 * e_uni);
    assert_true(e_ad < 0.5 * e_coarse);
    tb_rad_solver_free(fine);
    tb_rad_solver_free(uni);
    tb_rad_solver_free(coarse);
    tb_rad_solver_free(s);
    tb_rad_mesh_free(&m);
}

static void test_carry_and_determinism(void **state)
{
    (void)state;
    tb_rad_mesh m;
    shadow_scene(&m, 6);
    tb_rad_adapt_options a = {.threshold = 0.2, .max_levels = 1};
    tb_rad_solver *s1, *s2;
    tb_rad_adapt_stats st;
    assert_int_equal(tb_rad_adapt_solve(&m, &ray_opt, &one_shot, &a, &s1, &st), TB_OK);
    assert_int_equal(st.rounds, 1);
    assert_int_equal(st.shots, 1); /* the second round has nothing above the threshold to shoot */
    /* unshot power is carried over exactly (each old element's) */
    tb_rad_solver *u = solve_uniform(6);
    tb_rad_energy e0 = tb_rad_solver_energy(u), e1 = tb_rad_solver_energy(s1);
    tb_assert_near(e1.unshot, e0.unshot, 1e-12 * e0.unshot);
    tb_assert_near(e1.emitted, e0.emitted, 1e-12 * e0.emitted);
    /* old vertices keep their irradiance: the input's vertices are the
     * first ones, with the same corner values */
    const tb_rad_mesh *um = tb_rad_solver_mesh(u), *am = tb_rad_solver_mesh(s1);
    for (size_t v = 0; v < um->nverts; v++)
        assert_memory_equal(&um->verts[v].p, &am->verts[v].p, sizeof(tb_vec3));
    assert_true(am->nverts > um->nverts);
    /* determinism: the same again, bit for bit */
    tb_rad_mesh m2;
    shadow_scene(&m2, 6);
    assert_int_equal(tb_rad_adapt_solve(&m2, &ray_opt, &one_shot, &a, &s2, NULL), TB_OK);
    assert_int_equal(m2.nelems, m.nelems);
    assert_memory_equal(m2.verts, m.verts, sizeof *m.verts * m.nverts);
    tb_rad_mesh_free(&m2);
    const tb_rad_mesh *bm = tb_rad_solver_mesh(s2);
    assert_int_equal(am->nelems, bm->nelems);
    assert_int_equal(am->nverts, bm->nverts);
    assert_memory_equal(am->elems, bm->elems, sizeof *am->elems * am->nelems);
    for (size_t i = 0; i < am->nelems; i++) {
        double b1[3], b2[3];
        for (int k = 0; k < 4 && (k < 3 || am->elems[i].v[3] != TB_RAD_NONE); k++) {
            tb_rad_corner_radiosity(s1, i, k, false, b1);
            tb_rad_corner_radiosity(s2, i, k, false, b2);
            assert_memory_equal(b1, b2, sizeof b1);
        }
    }
    tb_rad_solver_free(u);
    tb_rad_solver_free(s1);
    tb_rad_solver_free(s2);
    tb_rad_mesh_free(&m);
}

static void test_limits(void **state)
{
    (void)state;
    tb_rad_mesh m;
    shadow_scene(&m, 8);
    /* a minimum area of a whole input element: nothing can be split */
    tb_rad_adapt_options a = {.threshold = 0.1, .max_levels = 3, .min_area = 1.0 / 64};
    tb_rad_solver *s;
    tb_rad_adapt_stats st;
    assert_int_equal(tb_rad_adapt_solve(&m, &ray_opt, &one_shot, &a, &s, &st), TB_OK);
    assert_int_equal(st.rounds, 0);
    assert_int_equal(tb_rad_solver_mesh(s)->nelems, 66);
    assert_int_equal(m.nelems, 66);
    tb_rad_solver_free(s);
    /* just below: input elements may be split once, their children (a
     * quarter of that) never; the smallest pieces are green corner
     * triangles of a quad with two adjacent split sides, an eighth */
    a.min_area = 1.0 / 64 - 1e-9;
    assert_int_equal(tb_rad_adapt_solve(&m, &ray_opt, &one_shot, &a, &s, &st), TB_OK);
    assert_true(st.rounds >= 1);
    const tb_rad_mesh *am = tb_rad_solver_mesh(s);
    for (size_t i = 0; i < am->nelems; i++)
        if (am->elems[i].object == 0)
            assert_true(am->elems[i].area >= 1.0 / 64 / 8 * (1 - 1e-6));
    tb_rad_solver_free(s);
    /* the criterion on its own: a huge threshold marks nothing, a tiny
     * one every floor element that the light's gradient crosses */
    tb_rad_solver *u = solve_uniform(8);
    tb_array mk = TB_ARRAY_INIT(uint32_t);
    assert_int_equal(tb_rad_adapt_mark(u, 10, 0, NULL, 1, &mk), TB_OK);
    assert_int_equal(mk.len, 0);
    assert_int_equal(tb_rad_adapt_mark(u, 1e-9, 0, NULL, 1, &mk), TB_OK);
    /* the floor but its 4 central elements, whose corners (0.375 .. 0.625)
     * are all in the umbra (the squares are black: no reflected light) */
    assert_int_equal(mk.len, 60);
    for (size_t i = 0; i < mk.len; i++)
        assert_int_equal(tb_rad_solver_mesh(u)->elems[TB_ARRAY_AT(&mk, uint32_t, i)].object, 0);
    uint32_t lv[66];
    for (int i = 0; i < 66; i++)
        lv[i] = 1;
    assert_int_equal(tb_rad_adapt_mark(u, 1e-9, 0, lv, 1, &mk), TB_OK);
    assert_int_equal(mk.len, 0);
    assert_int_equal(tb_rad_adapt_mark(u, 0, 0, NULL, 1, &mk), TB_ERR_ARG);
    tb_array_free(&mk);
    tb_rad_solver_free(u);
    /* refusals */
    tb_rad_adapt_options bad[3] = {{.threshold = 0}, {.threshold = 0.1, .max_levels = -1},
                                   {.threshold = 0.1, .min_area = NAN}};
    for (int i = 0; i < 3; i++) {
        s = (tb_rad_solver *)&s;
        assert_int_equal(tb_rad_adapt_solve(&m, &ray_opt, &one_shot, &bad[i], &s, NULL), TB_ERR_ARG);
        assert_null(s);
    }
    tb_rad_mesh_free(&m);
}

static void test_hemicube(void **state)
{
    (void)state;
    tb_rad_mesh m;
    shadow_scene(&m, 8);
    tb_rad_options o = {.ff = TB_RAD_FF_HEMICUBE, .hemicube_res = 64};
    tb_rad_adapt_options a = {.threshold = 0.25, .max_levels = 2};
    tb_rad_solver *s;
    tb_rad_adapt_stats st;
    assert_int_equal(tb_rad_adapt_solve(&m, &o, &one_shot, &a, &s, &st), TB_OK);
    print_message("hemicube: %d rounds, %zu -> %zu elements, %zu gathered\n", st.rounds, st.elems_in, st.elems_out,
                  st.gathered);
    assert_int_equal(st.rounds, 2);
    const tb_rad_mesh *am = tb_rad_solver_mesh(s);
    check_conforming(am);
    double near, far;
    penumbra_density(am, &near, &far);
    assert_true(near > 3 * far);
    /* gathered elements got light: the lit floor is lit after refinement */
    double b[3], top = 0;
    for (size_t i = 0; i < am->nelems; i++)
        if (am->elems[i].object == 0 && am->elems[i].parent != TB_RAD_NONE) {
            tb_rad_element_radiosity(s, i, false, b);
            top = fmax(top, b[0]);
        }
    assert_true(top > 0);
    tb_rad_solver_free(s);
    tb_rad_mesh_free(&m);
}

/* A floor (8 x 8) under a large emitter close to it (0.25 x 0.25 at height
 * 0.1): every floor element marked once gives the 16 x 16 grid, whose new
 * vertices were gathered from the emitter's shot, many of them in its near
 * field. Their values must match a direct solve on a uniform 16 x 16 floor
 * at the same points. */
static void test_gather_matches_direct(void **state)
{
    (void)state;
    tb_rad_mesh m[2];
    for (int t = 0; t < 2; t++) {
        uint32_t k = t ? 16 : 8;
        shadow_scene(&m[t], k);
        /* drop the occluder, move the emitter down and make it larger */
        m[t].emission[3 * (m[t].nelems - 2)] = 0;
        for (size_t v = m[t].nverts - 8; v < m[t].nverts - 4; v++)
            m[t].verts[v].p.z = -5; /* the occluder out of the way, below the floor, facing down */
        float c[4][2] = {{0.375f, 0.375f}, {0.625f, 0.375f}, {0.625f, 0.625f}, {0.375f, 0.625f}};
        for (int q = 0; q < 4; q++)
            m[t].verts[m[t].nverts - 4 + (size_t)q].p = (tb_vec3){c[q][0], c[q][1], 0.1f};
        assert_int_equal(tb_rad_mesh_update_geometry(&m[t]), TB_OK);
    }
    tb_rad_adapt_options a = {.threshold = 1e-9, .max_levels = 1};
    tb_rad_solver *s, *u;
    assert_int_equal(tb_rad_adapt_solve(&m[0], &ray_opt, &one_shot, &a, &s, NULL), TB_OK);
    assert_int_equal(count_object(tb_rad_solver_mesh(s), 0), 256);
    assert_int_equal(tb_rad_solver_create(&m[1], NULL, &ray_opt, &u), TB_OK);
    assert_int_equal(tb_rad_solver_run(u, &one_shot, NULL, NULL, 0), TB_OK);
    /* corner values of both at every floor vertex, by position */
    const tb_rad_mesh *am = tb_rad_solver_mesh(s), *um = tb_rad_solver_mesh(u);
    double va[17][17], vu[17][17], top = 0, worst = 0;
    for (int pass = 0; pass < 2; pass++) {
        const tb_rad_solver *x = pass ? u : s;
        const tb_rad_mesh *xm = pass ? um : am;
        for (size_t i = 0; i < xm->nelems; i++) {
            if (xm->elems[i].object != 0)
                continue;
            for (int k = 0; k < 4; k++) {
                tb_vec3 p = xm->verts[xm->elems[i].v[k]].p;
                double b[3];
                tb_rad_corner_radiosity(x, i, k, false, b);
                (pass ? vu : va)[lround(p.x * 16)][lround(p.y * 16)] = b[0];
            }
        }
    }
    for (int i = 0; i <= 16; i++)
        for (int j = 0; j <= 16; j++) {
            top = fmax(top, vu[i][j]);
            worst = fmax(worst, fabs(va[i][j] - vu[i][j]));
        }
    print_message("gathered vs direct on the 16 x 16 floor: largest difference %.4f of the brightest %.4f\n",
                  worst, top);
    assert_true(worst < 0.02 * top);
    tb_rad_solver_free(s);
    tb_rad_solver_free(u);
    tb_rad_mesh_free(&m[0]);
    tb_rad_mesh_free(&m[1]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_shadow_edge),
        cmocka_unit_test(test_carry_and_determinism),
        cmocka_unit_test(test_limits),
        cmocka_unit_test(test_hemicube),
        cmocka_unit_test(test_gather_matches_direct),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
