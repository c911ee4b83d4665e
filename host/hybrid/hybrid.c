/* The hybrid radiosity + ray-tracing renderer (hybrid.h, docs/hybrid.md). */
#include "host/hybrid/hybrid.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "host/object/hit.h"
#include "host/object/intersect.h"
#include "host/render/sampling.h"
#include "host/render/shading.h"
#include "util/stats/stats.h"

TB_STAT_COUNTER(tb__hyb_queries, "Hybrid/indirect queries (diffuse hits)");
TB_STAT_COUNTER(tb__hyb_misses, "Hybrid/hits with no element within tolerance (no indirect light)");
TB_STAT_COUNTER(tb__hyb_gather_rays, "Hybrid/gather rays");

struct tb_hybrid {
    const tb_scene *scene;  /* not owned */
    tb_hybrid_mode mode;
    int gather_rays;        /* in effect */
    int gsx, gsy;           /* strata of the gather rays */
    int nc;                 /* channels */
    tb_rad_solver *full;    /* the whole solution */
    tb_rad_solver *direct;  /* interpolated mode: the same mesh with rho 0 (first shots only) */
    tb_rad_locator *loc;    /* over full's mesh */
    /* Per vertex (nverts * nc): interpolated mode, the indirect irradiance
     * H_full - H_direct + ambient; gather mode, H_full + ambient (an
     * element's reflected radiosity B - E is rho times it). */
    double *hv;
    tb_hybrid_stats stats;
};

tb_hybrid_options tb_hybrid_defaults(void)
{
    return (tb_hybrid_options){
        .mode = TB_HYBRID_INTERPOLATED,
        .stop = {.threshold = TB_RAD_DEFAULT_THRESHOLD},
        .log_prefix = "",
    };
}

void tb_hybrid_free(tb_hybrid *h)
{
    if (!h)
        return;
    tb_rad_locator_free(h->loc);
    tb_rad_solver_free(h->full);
    tb_rad_solver_free(h->direct);
    free(h->hv);
    free(h);
}

const tb_rad_solver *tb_hybrid_solver(const tb_hybrid *h) { return h->full; }

const tb_rad_solver *tb_hybrid_direct_solver(const tb_hybrid *h) { return h->direct; }

const tb_rad_locator *tb_hybrid_locator(const tb_hybrid *h) { return h->loc; }

tb_hybrid_stats tb_hybrid_get_stats(const tb_hybrid *h) { return h->stats; }

/* The direct-only solve: `mesh` with every reflectance 0, so nothing that
 * arrives is shot again and the gathered irradiance is exactly the first
 * shots' of the emitters and lights; with the same shooters, seeds and
 * sample points as the full solve, those first shots deposit the same
 * values there (the solver is linear in what is shot). */
static tb_status tb__direct_solve(tb_hybrid *h, const tb_rad_mesh *mesh, const tb_rad_options *ro)
{
    size_t n = mesh->nelems * (size_t)mesh->nchannels;
    float *zero = calloc(n ? n : 1, sizeof *zero);
    if (!zero)
        return tb_error(TB_ERR_NOMEM, "hybrid: out of memory");
    tb_rad_mesh dm = *mesh; /* a shallow copy: the solver copies what it is given */
    dm.rho = zero;
    tb_status st = tb_rad_solver_create(&dm, NULL, ro, &h->direct);
    free(zero);
    if (st)
        return tb_error_context(st, "hybrid: direct-only solve");
    /* Every emitting shooter and light once; then nothing is left. */
    bool shot = true;
    while (shot && !st)
        st = tb_rad_solver_step(h->direct, &shot);
    h->stats.direct_shots = tb_rad_solver_shots(h->direct);
    h->stats.direct_seconds = tb_rad_solver_seconds(h->direct);
    return st;
}

tb_status tb_hybrid_create_from_mesh(const tb_scene *scene, const tb_rad_mesh *mesh, const tb_hybrid_options *opt,
                                     tb_hybrid **out)
{
    *out = NULL;
    tb_hybrid_options o = opt ? *opt : tb_hybrid_defaults();
    if (!scene || !mesh)
        return tb_error(TB_ERR_ARG, "hybrid: no scene or mesh");
    if (o.mode != TB_HYBRID_INTERPOLATED && o.mode != TB_HYBRID_GATHER)
        return tb_error(TB_ERR_ARG, "hybrid: unknown mode %d", (int)o.mode);
    if (o.gather_rays < 0 || o.gather_rays > TB_HYBRID_MAX_GATHER_RAYS)
        return tb_error(TB_ERR_ARG, "hybrid: gather rays %d not in 0..%d", o.gather_rays, TB_HYBRID_MAX_GATHER_RAYS);
    if (mesh->nchannels != scene->nchannels)
        return tb_error(TB_ERR_ARG, "hybrid: the mesh has %d channels, the scene %d", mesh->nchannels,
                        scene->nchannels);
    for (size_t i = 0; i < mesh->nelems; i++)
        if (mesh->elems[i].object >= scene->nobjects)
            return tb_error(TB_ERR_ARG, "hybrid: element %zu names object %u; the scene has %u", i,
                            mesh->elems[i].object, scene->nobjects);
    tb_hybrid *h = calloc(1, sizeof *h);
    if (!h)
        return tb_error(TB_ERR_NOMEM, "hybrid: out of memory");
    h->scene = scene;
    h->mode = o.mode;
    h->nc = mesh->nchannels;
    h->gather_rays = o.gather_rays ? o.gather_rays : TB_HYBRID_DEFAULT_GATHER_RAYS;
    tb_stratified_dims(h->gather_rays, &h->gsx, &h->gsy);
    tb_rad_options ro = o.solver;
    ro.lights = scene->lights; /* the scene outlives the hybrid (IES tables) */
    ro.nlights = scene->nlights;
    tb_status st = tb_rad_solver_create(mesh, NULL, &ro, &h->full);
    if (!st)
        st = tb_rad_solver_run(h->full, &o.stop, NULL, NULL, 0);
    if (!st && o.mode == TB_HYBRID_INTERPOLATED)
        st = tb__direct_solve(h, mesh, &ro);
    const tb_rad_mesh *m = st ? NULL : tb_rad_solver_mesh(h->full);
    if (!st)
        st = tb_rad_locator_create(m, &h->loc);
    if (!st) {
        h->hv = malloc(m->nverts * (size_t)h->nc * sizeof *h->hv);
        if (!h->hv)
            st = tb_error(TB_ERR_NOMEM, "hybrid: out of memory");
    }
    if (!st) {
        /* The ambient term stands for what the full solve left unshot: all of
         * it is light yet to be reflected, so indirect. */
        double amb[TB_CHANNELS_MAX], hf[TB_CHANNELS_MAX], hd[TB_CHANNELS_MAX];
        tb_rad_ambient(h->full, amb);
        for (size_t v = 0; v < m->nverts; v++) {
            tb_rad_vertex_irradiance(h->full, v, hf);
            if (h->direct)
                tb_rad_vertex_irradiance(h->direct, v, hd);
            for (int c = 0; c < h->nc; c++) {
                /* full >= direct up to rounding: the full solve deposited the
                 * same first shots plus non-negative others */
                double ind = h->direct ? fmax(0.0, hf[c] - hd[c]) : hf[c];
                h->hv[v * (size_t)h->nc + (size_t)c] = ind + amb[c];
            }
        }
        h->stats.elements = m->nelems;
        h->stats.vertices = m->nverts;
        h->stats.shots = tb_rad_solver_shots(h->full);
        h->stats.solve_seconds = tb_rad_solver_seconds(h->full);
        h->stats.unshot_fraction = tb_rad_unshot_fraction(h->full);
    }
    if (st) {
        tb_hybrid_free(h);
        return st;
    }
    if (o.log)
        fprintf(o.log,
                "%shybrid: radiosity pass: %zu elements, %zu vertices, %llu shots in %.3f s (unshot %.3g)%s; "
                "indirect light by %s\n",
                o.log_prefix ? o.log_prefix : "", m->nelems, m->nverts, (unsigned long long)h->stats.shots,
                h->stats.solve_seconds, h->stats.unshot_fraction,
                h->direct ? ", direct-only solve" : "", h->mode == TB_HYBRID_GATHER ? "final gather" : "interpolation");
    if (o.log && h->direct)
        fprintf(o.log, "%shybrid: direct-only solve: %llu shots in %.3f s\n", o.log_prefix ? o.log_prefix : "",
                (unsigned long long)h->stats.direct_shots, h->stats.direct_seconds);
    *out = h;
    return TB_OK;
}

tb_status tb_hybrid_create(const tb_scene *scene, const tb_hybrid_options *opt, tb_hybrid **out)
{
    *out = NULL;
    if (!scene)
        return tb_error(TB_ERR_ARG, "hybrid: no scene");
    tb_hybrid_options o = opt ? *opt : tb_hybrid_defaults();
    tb_rad_mesh_options mo = o.mesh_given ? o.mesh : tb_rad_default_mesh_options(scene);
    tb_rad_mesh mesh;
    tb_rad_mesh_init(&mesh);
    double t0 = 1e-9 * (double)tb_stats_now_ns();
    tb_status st = tb_rad_mesh_from_scene(scene, &mo, &mesh);
    double t_mesh = 1e-9 * (double)tb_stats_now_ns() - t0;
    if (!st)
        st = tb_hybrid_create_from_mesh(scene, &mesh, &o, out);
    tb_rad_mesh_free(&mesh);
    if (st)
        return tb_error_context(st, "hybrid");
    (*out)->stats.mesh_seconds = t_mesh;
    return TB_OK;
}

/* Specular bounces a gather ray follows before it must land on a diffuse
 * surface (glass splits in two at each: at most 2^4 rays per gather ray). */
#define TB__HYB_GATHER_DEPTH 4

static bool tb__black(const tb_channels *c)
{
    for (int k = 0; k < c->n; k++)
        if (c->v[k] != 0.0f)
            return false;
    return true;
}

/* What a gather ray brings back, in radiosity units (pi times radiance),
 * out[0..nc): where it lands, the solution's reflected radiosity B - E of
 * the element there (front sides; the emission is left out, as the direct
 * light comes by shadow rays), plus what the surface's perfect mirror
 * (Phong or Blinn specular colour) or smooth dielectric (Fresnel split)
 * sends along, followed up to TB__HYB_GATHER_DEPTH bounces with the
 * materials' untextured colours. GGX lobes add nothing more than their
 * element's diffuse part. */
static void tb__gather_one(const tb_hybrid *h, const tb_ray *ray, int depth, double *out)
{
    const tb_scene *s = h->scene;
    const int nc = h->nc;
    for (int c = 0; c < nc; c++)
        out[c] = 0.0;
    tb_hit hit;
    if (!tb_scene_intersect(s, ray, &hit))
        return;
    const tb_material *mat = tb_scene_hit_material(s, &hit);
    if (!mat)
        return;
    tb_vec3 p, perr;
    if (!tb_object_hit_point(s->objects[hit.object], ray, &hit, &p, &perr)) {
        p = tb_vec3_add(ray->o, tb_vec3_scale(ray->d, hit.t));
        perr = tb_vec3_scale(tb_vec3_add(tb_vec3_abs(p), tb_vec3_splat(1.0f)), 1e-5f);
    }
    const tb_vec3 d = tb_vec3_normalize(ray->d), wo = tb_vec3_neg(d), ng = hit.ng;
    const bool front = tb_vec3_dot(d, ng) < 0.0f;
    if (front) { /* elements receive and reflect on their front only */
        tb_rad_location at;
        if (tb_rad_locate(h->loc, hit.object, p, ng, &at)) {
            double hv[TB_CHANNELS_MAX];
            tb_rad_location_interpolate(&at, h->hv, nc, hv);
            const float *rho = tb_rad_solver_mesh(h->full)->rho + (size_t)at.element * (size_t)nc;
            for (int c = 0; c < nc; c++)
                out[c] = rho[c] * hv[c];
        } else {
            TB_STAT_INC(tb__hyb_misses);
        }
    }
    if (depth >= TB__HYB_GATHER_DEPTH)
        return;
    double sub[TB_CHANNELS_MAX];
    if (!tb__black(&mat->transmission)) {
        tb_frame fr = tb_frame_from_normal(ng);
        tb_specular_split sp;
        tb_specular_dielectric(tb_frame_to_local(&fr, wo), mat->ior, &sp);
        if (sp.R > 0.0) {
            tb_vec3 w = tb_frame_to_world(&fr, sp.wr);
            tb_ray r = tb_ray_make(tb_spawn_ray_origin(p, perr, ng, w), w, 0.0f, INFINITY);
            tb__gather_one(h, &r, depth + 1, sub);
            for (int c = 0; c < nc; c++)
                out[c] += sp.R * sub[c];
        }
        if (sp.refracts && sp.T > 0.0) {
            tb_vec3 w = tb_vec3_normalize(tb_frame_to_world(&fr, sp.wt));
            tb_ray r = tb_ray_make(tb_spawn_ray_origin(p, perr, ng, w), w, 0.0f, INFINITY);
            tb__gather_one(h, &r, depth + 1, sub);
            for (int c = 0; c < nc; c++)
                out[c] += sp.T * mat->transmission.v[c] * sub[c];
        }
    } else if (mat->model != TB_MID_MODEL_LAMBERT && mat->model != TB_MID_MODEL_GGX && !tb__black(&mat->specular)) {
        const tb_vec3 n = front ? ng : tb_vec3_neg(ng);
        tb_vec3 w = tb_vec3_normalize(tb_reflect(wo, n));
        tb_ray r = tb_ray_make(tb_spawn_ray_origin(p, perr, ng, w), w, 0.0f, INFINITY);
        tb__gather_one(h, &r, depth + 1, sub);
        for (int c = 0; c < nc; c++)
            out[c] += mat->specular.v[c] * sub[c];
    }
}

void tb_hybrid_gather_ray(const tb_hybrid *h, const tb_ray *ray, double *out) { tb__gather_one(h, ray, 0, out); }

tb_channels tb_hybrid_indirect(void *ctx, const tb_rt_indirect_query *q, tb_rng *rng)
{
    const tb_hybrid *h = ctx;
    const int nc = h->nc;
    tb_channels E = tb_channels_splat(nc, 0.0f);
    TB_STAT_INC(tb__hyb_queries);
    double acc[TB_CHANNELS_MAX] = {0};
    if (h->mode == TB_HYBRID_INTERPOLATED) {
        tb_rad_location at;
        if (!tb_rad_locate(h->loc, q->object, q->p, q->n, &at)) {
            TB_STAT_INC(tb__hyb_misses);
            return E;
        }
        tb_rad_location_interpolate(&at, h->hv, nc, acc);
    } else {
        /* Irradiance pi * mean radiance over cosine-distributed directions;
         * radiance (B - E) / pi, so the estimate is the mean of B - E. */
        float u[2 * TB_HYBRID_MAX_GATHER_RAYS];
        tb_stratified_2d(rng, h->gsx, h->gsy, u);
        const tb_frame fr = tb_frame_from_normal(q->n);
        double b[TB_CHANNELS_MAX];
        for (int k = 0; k < h->gather_rays; k++) {
            tb_vec3 w = tb_vec3_normalize(tb_frame_to_world(&fr, tb_sample_cosine_hemisphere(u[2 * k], u[2 * k + 1])));
            tb_ray r = tb_ray_make(q->origin, w, 0.0f, INFINITY);
            TB_STAT_INC(tb__hyb_gather_rays);
            tb__gather_one(h, &r, 0, b);
            for (int c = 0; c < nc; c++)
                acc[c] += b[c];
        }
        for (int c = 0; c < nc; c++)
            acc[c] /= h->gather_rays;
    }
    for (int c = 0; c < nc; c++)
        E.v[c] = (float)acc[c];
    return E;
}

tb_status tb_hybrid_tracer_init(const tb_hybrid *h, const tb_rt_options *rt, tb_raytracer *out)
{
    tb_rt_options o = rt ? *rt : (tb_rt_options){0};
    o.indirect = tb_hybrid_indirect;
    o.indirect_ctx = (void *)h;
    return tb_rt_init(out, h->scene, &o);
}

tb_status tb_render_hybrid(const tb_hybrid *h, const tb_render_options *o, tb_image **out, tb_render_stats *stats)
{
    *out = NULL;
    tb_raytracer rt;
    tb_status st = tb_hybrid_tracer_init(h, o ? &o->rt : NULL, &rt);
    if (st)
        return st;
    tb_render_options ro = o ? *o : tb_render_defaults();
    st = tb_render(h->scene, tb_rt_sample, &rt, &ro, out, stats);
    tb_rt_release(&rt);
    return st;
}

/* ----------------------------------------------------- tb_render_method */

/* The method's per-render context: the tracer first, so tb_rt_sample's ctx
 * is the context itself. */
typedef struct tb__hyb_run {
    tb_raytracer rt;
    tb_hybrid *h;
} tb__hyb_run;

static tb_status tb__hyb_init(void *user, const tb_scene *s, const tb_render_options *o, tb_aa_sample_fn *sample,
                              void **ctx, char *desc, size_t ndesc)
{
    tb_hybrid_method_state *state = user;
    const tb_hybrid_options *ho = &state->opt;
    tb__hyb_run *r = calloc(1, sizeof *r);
    if (!r)
        return tb_error(TB_ERR_NOMEM, "hybrid: out of memory");
    tb_status st = tb_hybrid_create(s, ho, &r->h);
    if (!st)
        st = tb_hybrid_tracer_init(r->h, &o->rt, &r->rt);
    if (st) {
        tb_hybrid_free(r->h);
        free(r);
        return st;
    }
    state->stats = r->h->stats;
    const tb_rad_mesh_options mo = ho->mesh_given ? ho->mesh : tb_rad_default_mesh_options(s);
    snprintf(desc, ndesc,
             "hybrid_mode=%s gather_rays=%d max_edge=%g max_area=%g formfactor=%s rad_samples=%d threshold=%g "
             "rad_seed=%llu elements=%zu max_depth=%d light_samples=%d glossy_samples=%d",
             ho->mode == TB_HYBRID_GATHER ? "gather" : "interpolated", r->h->gather_rays, mo.max_edge, mo.max_area,
             ho->solver.ff == TB_RAD_FF_HEMICUBE ? "hemicube" : "raycast",
             ho->solver.samples ? ho->solver.samples : TB_RAD_DEFAULT_SAMPLES,
             ho->stop.threshold > 0 ? ho->stop.threshold : TB_RAD_DEFAULT_THRESHOLD,
             (unsigned long long)ho->solver.seed, r->h->stats.elements, r->rt.max_depth, r->rt.light_samples,
             r->rt.glossy_samples);
    *sample = tb_rt_sample;
    *ctx = r;
    return TB_OK;
}

static void tb__hyb_release(void *user, void *ctx)
{
    (void)user;
    tb__hyb_run *r = ctx;
    tb_rt_release(&r->rt);
    tb_hybrid_free(r->h);
    free(r);
}

static tb_status tb__hyb_stats(void *user, void *ctx)
{
    (void)user;
    const tb__hyb_run *r = ctx;
    const tb_hybrid_stats *hs = &r->h->stats;
    const struct {
        const char *k;
        double v;
    } kv[] = {{"radiosity_elements", (double)hs->elements},
              {"radiosity_vertices", (double)hs->vertices},
              {"radiosity_shots", (double)hs->shots},
              {"radiosity_direct_shots", (double)hs->direct_shots},
              {"radiosity_mesh_seconds", hs->mesh_seconds},
              {"radiosity_seconds", hs->solve_seconds},
              {"radiosity_direct_seconds", hs->direct_seconds},
              {"radiosity_unshot_fraction", hs->unshot_fraction}};
    tb_status st = TB_OK;
    for (size_t k = 0; k < sizeof kv / sizeof kv[0] && !st; k++)
        st = tb_stats_set_value(kv[k].k, kv[k].v);
    return st;
}

tb_render_method tb_hybrid_method(tb_hybrid_method_state *state)
{
    return (tb_render_method){
        .name = "hybrid",
        .init = tb__hyb_init,
        .release = tb__hyb_release,
        .stats = tb__hyb_stats,
        .user = state,
    };
}
