/* host/object/polygonize + intersect: the analytic hit and the hit on the
 * polygonal approximation agree within the tessellation tolerance (issue 4,
 * consistency). For random shapes of every kind under random affine
 * transforms, the FED mesh from tb_polygonize is built into a polygons object
 * (same transform) and random rays aimed at the object are intersected with
 * both. The bound (docs/primitives.md, "Tessellation"):
 *
 *   delta = 2 (rho (1 - cos(a / 2)) + (e / 2) tan(a / 2)) * S + eps
 *
 * with a the angular tolerance, e the edge limit, rho the largest distance of
 * a mesh vertex from the object-space origin (every circle of a face has at
 * most that radius), S the transform's largest stretch and eps = 1e-5 of the
 * world size (float vertices). It covers the sagitta bound of both parametric
 * directions (and the conic's chord term).
 *
 * Checked per ray: if both hit, the hit points are within 1.5 delta / |cos|
 * of each other (cos: ray direction against the analytic normal, at least
 * 0.25). Any other outcome (one hits, the other does not, or the points are
 * farther apart, which happens when one of them grazes past a rim or wall)
 * must come from a ray within the silhouette band: moving the ray sideways
 * by at most 2 delta (16 directions around it) changes the analytic answer
 * (hit/miss, or the hit t by more than the bound). Rays outside the band that
 * disagree fail the test; the band rays are counted and must stay a small
 * fraction. */
#include "tb_test.h"

#include "host/object/bounds.h"
#include "host/object/intersect.h"
#include "host/object/object.h"
#include "host/object/polygonize.h"
#include "test_param_shapes.h"
#include "util/mesh/fed.h"

#define TH_SHAPES_PER_KIND 6
#define TH_RAYS_PER_SHAPE 2000

static tb_mid_object th_mid(tb_prim_kind k, tb_mid_geometry g, tb_transform xf)
{
    tb_mid_object m;
    memset(&m, 0, sizeof m);
    m.kind = k;
    m.to_world = xf;
    m.geom = g;
    m.material = tb_mid_material_default();
    return m;
}

static tb_object *th_build(const tb_mid_object *m)
{
    tb_object *o = NULL;
    if (tb_object_from_mid(m, 0, NULL, NULL, &o))
        fail_msg("tb_object_from_mid: %s", tb_last_error());
    return o;
}

/* A polygons object of the FED mesh's outer loops (tessellations of
 * primitives have no holes), under xf. */
static tb_object *th_mesh_object(const tb_fed *fed, tb_transform xf)
{
    int *start = malloc((fed->nfaces + 1) * sizeof *start);
    int *idx = malloc(fed->ncorners * sizeof *idx);
    assert_non_null(start);
    assert_non_null(idx);
    int n = 0;
    for (uint32_t f = 0; f < fed->nfaces; f++) {
        uint32_t l = fed->face_loops[f];
        start[f] = n;
        for (uint32_t c = fed->loop_corners[l]; c < fed->loop_corners[l + 1]; c++)
            idx[n++] = (int)fed->corner_vert[c];
    }
    start[fed->nfaces] = n;
    tb_mid_geometry g;
    memset(&g, 0, sizeof g);
    g.polygons.nvertices = (int)fed->nverts;
    g.polygons.vertices = fed->positions;
    g.polygons.nfaces = (int)fed->nfaces;
    g.polygons.face_start = start;
    g.polygons.indices = idx;
    tb_mid_object m = th_mid(TB_PRIM_POLYGONS, g, xf);
    tb_object *o = th_build(&m);
    free(start);
    free(idx);
    return o;
}

static tb_dvec3 th_dir(tb_rng *r)
{
    double z = ts_uniform(r, -1.0, 1.0), phi = ts_uniform(r, 0.0, 2.0 * TS_PI);
    double s = sqrt(fmax(0.0, 1.0 - z * z));
    return (tb_dvec3){s * cos(phi), s * sin(phi), z};
}

static tb_ray th_ray(tb_dvec3 o, tb_dvec3 d)
{
    return tb_ray_make((tb_vec3){(float)o.x, (float)o.y, (float)o.z}, (tb_vec3){(float)d.x, (float)d.y, (float)d.z},
                       0.0f, INFINITY);
}

/* True if some ray moved sideways by `off` (16 directions perpendicular to d)
 * has a different analytic outcome than (hit0, t0): hit/miss, or t by more
 * than tol. */
static bool th_near_silhouette(const tb_object *obj, tb_dvec3 o, tb_dvec3 d, bool hit0, double t0, double off,
                               double tol)
{
    tb_dvec3 a = fabs(d.x) < 0.6 ? (tb_dvec3){1, 0, 0} : (tb_dvec3){0, 1, 0};
    tb_dvec3 e1 = tb_dvec3_normalize(tb_dvec3_cross(d, a)), e2 = tb_dvec3_cross(d, e1);
    for (int step = 1; step <= 4; step++) {
        double s = off * step / 4.0;
        for (int k = 0; k < 16; k++) {
            double ang = 2.0 * TS_PI * k / 16.0;
            tb_dvec3 oo = tb_dvec3_add(o, tb_dvec3_add(tb_dvec3_scale(e1, s * cos(ang)), tb_dvec3_scale(e2, s * sin(ang))));
            tb_ray ray = th_ray(oo, d);
            tb_hit h;
            bool hit = tb_object_intersect(obj, &ray, &h);
            if (hit != hit0 || (hit && fabs((double)h.t - t0) > tol))
                return true;
        }
    }
    return false;
}

static void test_poly_hits_agree(void **state)
{
    (void)state;
    tb_rng r;
    uint64_t seed = tb_test_seed("poly_hits", 41);
    tb_rng_seed(&r, seed, 4);
    long total = 0, band = 0, both = 0;
    for (int ki = 0; ki < TS_NKINDS; ki++) {
        tb_prim_kind kind = ts_kinds[ki];
        long kband = 0, krays = 0;
        double worst = 0.0; /* largest hit-point distance / bound among accepted pairs */
        for (int si = 0; si < TH_SHAPES_PER_KIND; si++) {
            ts_shape s;
            ts_random_shape(&r, kind, &s);
            tb_transform xf = ts_random_transform(&r);
            double a = ts_uniform(&r, 0.05, 0.3), e = ts_uniform(&r, 0.1, 0.5);
            tb_poly_options opt = {.max_edge = e, .max_angle = a};
            tb_fed *fed = NULL;
            if (tb_polygonize(kind, &s.g, &opt, &fed))
                fail_msg("tb_polygonize: %s", tb_last_error());
            tb_mid_object m = th_mid(kind, s.g, xf);
            tb_object *obj = th_build(&m);
            tb_object *mesh = th_mesh_object(fed, xf);

            double rho = 0.0;
            for (uint32_t i = 0; i < fed->nverts; i++) {
                tb_vec3 p = fed->positions[i];
                rho = fmax(rho, sqrt((double)p.x * p.x + (double)p.y * p.y + (double)p.z * p.z));
            }
            double stretch = tb_bounds_max_stretch(&xf);
            tb_aabb box;
            assert_int_equal(tb_bounds_world(kind, &s.g, &xf, &box), TB_OK);
            tb_dvec3 lo = {box.lo.x, box.lo.y, box.lo.z}, hi = {box.hi.x, box.hi.y, box.hi.z};
            tb_dvec3 c = tb_dvec3_scale(tb_dvec3_add(lo, hi), 0.5);
            double size = tb_dvec3_length(tb_dvec3_sub(hi, lo));
            double eps = 1e-5 * size;
            double delta = 2.0 * (rho * (1.0 - cos(0.5 * a)) + 0.5 * e * tan(0.5 * a)) * stretch + eps;

            for (int ri = 0; ri < TH_RAYS_PER_SHAPE; ri++) {
                /* Aim at a mesh vertex (jittered) half the time, else anywhere in the box. */
                tb_dvec3 target;
                if (ri & 1) {
                    tb_vec3 p = fed->positions[tb_rng_below(&r, fed->nverts)];
                    tb_dvec3 w = tb_transform_dpoint(&xf, (tb_dvec3){p.x, p.y, p.z});
                    target = tb_dvec3_add(w, tb_dvec3_scale(th_dir(&r), 0.02 * size * tb_rng_double(&r)));
                } else {
                    target = (tb_dvec3){ts_uniform(&r, lo.x, hi.x), ts_uniform(&r, lo.y, hi.y), ts_uniform(&r, lo.z, hi.z)};
                }
                tb_dvec3 o = tb_dvec3_add(c, tb_dvec3_scale(th_dir(&r), 1.5 * size + 1.0));
                tb_dvec3 d = tb_dvec3_normalize(tb_dvec3_sub(target, o));
                tb_ray ray = th_ray(o, d);
                tb_hit ha, hm;
                bool a_hit = tb_object_intersect(obj, &ray, &ha);
                bool m_hit = tb_object_intersect(mesh, &ray, &hm);
                krays++;
                bool ok = a_hit == m_hit;
                double bound = 0.0;
                if (ok && a_hit) {
                    both++;
                    double cs = fabs(d.x * ha.ng.x + d.y * ha.ng.y + d.z * ha.ng.z);
                    bound = 1.5 * delta / fmax(cs, 0.25);
                    double dist = fabs((double)ha.t - (double)hm.t); /* |d| = 1 */
                    ok = dist <= bound;
                    if (ok)
                        worst = fmax(worst, dist / bound);
                }
                if (ok)
                    continue;
                double tol = 1.5 * delta / 0.25;
                if (!th_near_silhouette(obj, o, d, a_hit, a_hit ? ha.t : 0.0, 2.0 * delta, tol))
                    fail_msg("seed %llu kind %d shape %d ray %d: analytic %s t=%g, mesh %s t=%g, delta %g, not near "
                             "the silhouette",
                             (unsigned long long)seed, (int)kind, si, ri, a_hit ? "hit" : "miss",
                             a_hit ? (double)ha.t : 0.0, m_hit ? "hit" : "miss", m_hit ? (double)hm.t : 0.0, delta);
                kband++;
            }
            tb_object_free(mesh);
            tb_object_free(obj);
            tb_fed_free(fed);
        }
        print_message("kind %d: %ld rays, %ld disagreeing within the silhouette band (%.3f%%), worst point "
                      "distance / bound %.3f\n",
                      (int)kind, krays, kband, 100.0 * kband / krays, worst);
        /* The band is thin: a few percent of rays at most, even for the
         * coarsest tolerance drawn here. */
        assert_true(kband <= krays / 20);
        total += krays, band += kband;
    }
    print_message("seed %llu: %ld rays, %ld both hit, %ld in the silhouette band\n", (unsigned long long)seed, total,
                  both, band);
    assert_true(both > total / 10);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_poly_hits_agree),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
