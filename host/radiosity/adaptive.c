/* Adaptive subdivision on top of the progressive solver
 * (host/radiosity/adaptive.h; docs/radiosity.md, "Adaptive subdivision").
 *
 * Carrying a solution over a refinement. The solver's state is the
 * gathered irradiance H (per vertex and per element with ray-cast form
 * factors, per element with the hemicube) and the unshot radiosity dB per
 * element. Refinement keeps vertex indices, so old vertices keep their H,
 * and elements left whole keep theirs. New receivers have
 * received nothing, yet, from the shots already made; every element j has
 * so far shot S_j = B_j - dB_j (its radiosity minus what it has not shot),
 * so their H is gathered anew as sum_j S_j F(receiver -> j) over the
 * previous mesh (Cohen et al. 1986: the elements gather from the patches).
 * dB is a density, so a child inherits its old element's, scaled so that
 * each old element's unshot power is kept exactly (children of an undone
 * green closure straddle two old elements). */
#include "host/radiosity/adaptive.h"
#include "host/radiosity/lights.h"
#include "host/radiosity/render.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "util/color/bands.h"
#include "util/color/srgb.h"
#include "util/mesh/refine.h"
#include "util/stats/stats.h"

_Static_assert(TB_RAD_ADAPT_MAX_LEVELS == TB_MESH_REFINE_MAX_LEVEL, "one limit for the levels");

TB_STAT_COUNTER(tb__adapt_marked, "Radiosity/adaptive: elements marked");
TB_STAT_COUNTER(tb__adapt_gathered, "Radiosity/adaptive: receivers gathered");

/* The near field of a shooter, in its radii (max centroid-corner
 * distance): the solver's rule (docs/radiosity.md, "Ray-cast form
 * factors"). */
#define TB__ADAPT_NEAR 4.0

/* Luminance of one colour in the mesh's channels. */
static double tb__lum(const tb_rad_mesh *m, const double *v)
{
    if (m->spectral) {
        double xyz[3];
        tb_bands_to_xyz(&m->bands, v, xyz);
        return xyz[1];
    }
    if (m->nchannels == 3)
        return tb_linear_srgb_luminance(v);
    double s = 0;
    for (int c = 0; c < m->nchannels; c++)
        s += v[c];
    return s / m->nchannels;
}

static inline int tb__nc(const tb_rad_element *e) { return e->v[3] == TB_RAD_NONE ? 3 : 4; }

tb_status tb_rad_adapt_mark(const tb_rad_solver *s, double threshold, double min_area, const uint32_t *level,
                            int max_levels, tb_array *marked)
{
    tb_array_clear(marked);
    if (!(threshold > 0) || !isfinite(threshold) || !(min_area >= 0) || !isfinite(min_area))
        return tb_error(TB_ERR_ARG, "adaptive subdivision: threshold %g or minimum area %g out of range", threshold,
                        min_area);
    const tb_rad_mesh *m = tb_rad_solver_mesh(s);
    int nc = m->nchannels;
    double b[TB_CHANNELS_MAX];
    /* The reference: the brightest element's reflected radiosity. */
    double top = 0;
    for (size_t i = 0; i < m->nelems; i++) {
        tb_rad_element_radiosity(s, i, false, b);
        for (int c = 0; c < nc; c++)
            b[c] -= m->emission[i * (size_t)nc + (size_t)c];
        top = fmax(top, tb__lum(m, b));
    }
    if (!(top > 0))
        return TB_OK; /* nothing lit yet: no gradient anywhere */
    for (size_t i = 0; i < m->nelems; i++) {
        const tb_rad_element *e = &m->elems[i];
        if ((level && level[i] >= (uint32_t)max_levels) || !(e->area > min_area))
            continue;
        double lo = INFINITY, hi = -INFINITY;
        for (int k = 0; k < tb__nc(e); k++) {
            tb_rad_corner_radiosity(s, i, k, false, b);
            for (int c = 0; c < nc; c++)
                b[c] -= m->emission[i * (size_t)nc + (size_t)c];
            double y = tb__lum(m, b);
            lo = fmin(lo, y), hi = fmax(hi, y);
        }
        if (hi - lo > threshold * top) {
            uint32_t id = (uint32_t)i;
            tb_status st = tb_array_push(marked, &id);
            if (st)
                return st;
        }
    }
    tb_stat_add(&tb__adapt_marked, (int64_t)marked->len);
    return TB_OK;
}

/* SplitMix64 of (seed, round, shooter): the sample points of one gather. */
static uint64_t tb__gather_seed(uint64_t seed, uint64_t round, uint64_t j)
{
    uint64_t z = seed ^ (0xd1b54a32d192ed03ull * (round + 1)) ^ (0x9e3779b97f4a7c15ull * (j + 1));
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* The elements of `m` as a util/mesh mesh (face = object), for the refiner. */
static tb_status tb__to_mesh(const tb_rad_mesh *m, tb_mesh *out)
{
    tb_mesh_init(out);
    tb_status st = TB_OK;
    for (size_t v = 0; v < m->nverts && !st; v++) {
        st = tb_array_push(&out->positions, &m->verts[v].p);
        if (!st)
            st = tb_array_push(&out->normals, &m->verts[v].n);
    }
    for (size_t i = 0; i < m->nelems && !st; i++) {
        const tb_rad_element *e = &m->elems[i];
        tb_mesh_elem el = {{e->v[0], e->v[1], e->v[2], e->v[3]}, e->object, TB_MESH_NONE};
        st = tb_array_push(&out->elems, &el);
    }
    return st;
}

/* The refiner's current mesh as a radiosity mesh; materials from `prev`
 * through the map. */
static tb_status tb__from_refiner(const tb_mesh_refiner *r, const tb_rad_mesh *prev, const uint32_t *map,
                                  tb_rad_mesh *out)
{
    const tb_mesh *m = tb_mesh_refiner_mesh(r);
    int nc = prev->nchannels;
    tb_rad_mesh_init(out);
    out->nchannels = nc, out->spectral = prev->spectral, out->bands = prev->bands;
    size_t nv = m->positions.len, ne = m->elems.len;
    out->verts = malloc(sizeof *out->verts * (nv ? nv : 1));
    out->elems = malloc(sizeof *out->elems * (ne ? ne : 1));
    out->rho = malloc(sizeof *out->rho * (ne ? ne : 1) * (size_t)nc);
    out->emission = malloc(sizeof *out->emission * (ne ? ne : 1) * (size_t)nc);
    if (!out->verts || !out->elems || !out->rho || !out->emission) {
        tb_rad_mesh_free(out);
        return tb_error(TB_ERR_NOMEM, "adaptive subdivision: out of memory");
    }
    out->nverts = nv, out->nelems = ne;
    for (size_t v = 0; v < nv; v++)
        out->verts[v] = (tb_rad_vertex){TB_ARRAY_AT(&m->positions, tb_vec3, v), TB_ARRAY_AT(&m->normals, tb_vec3, v)};
    for (size_t i = 0; i < ne; i++) {
        const tb_mesh_elem *e = tb_mesh_elem_at(m, i);
        bool whole = tb_mesh_refiner_level(r, i) == 0 && !tb_mesh_refiner_is_green(r, i);
        out->elems[i] = (tb_rad_element){.v = {e->v[0], e->v[1], e->v[2], e->v[3]}, .object = e->face,
                                         .parent = whole ? TB_RAD_NONE : tb_mesh_refiner_base(r, i)};
        memcpy(out->rho + i * (size_t)nc, prev->rho + map[i] * (size_t)nc, sizeof *out->rho * (size_t)nc);
        memcpy(out->emission + i * (size_t)nc, prev->emission + map[i] * (size_t)nc,
               sizeof *out->emission * (size_t)nc);
    }
    /* a refined element stays in the patch of the element it came from */
    tb_status st = tb_rad_mesh_copy_patches(out, prev, map);
    if (!st)
        st = tb_rad_mesh_update_geometry(out);
    if (st)
        tb_rad_mesh_free(out);
    return st;
}

/* New receivers also get the direct light of the lights already shot
 * (host/radiosity/lights.h): a light shot over the new mesh gives new
 * vertices (ray cast) their irradiance and new elements (hemicube) their
 * mean irradiance, exactly what a solver on the new mesh would have given. */
static tb_status tb__carry_lights(const tb_rad_solver *s, const tb_rad_mesh *nm, const tb_mesh_refiner *r,
                                  const tb_rad_options *opt, double *H)
{
    tb_rad_state os = tb_rad_solver_state(s);
    bool any = false;
    for (int k = 0; k < opt->nlights && os.lights_shot; k++)
        any |= os.lights_shot[k] != 0;
    if (!any)
        return TB_OK;
    size_t nv0 = tb_rad_solver_mesh(s)->nverts, nc = (size_t)nm->nchannels;
    bool hemi = opt->ff == TB_RAD_FF_HEMICUBE;
    double *ev = malloc(sizeof *ev * nm->nverts * nc), *ee = malloc(sizeof *ee * nm->nelems * nc);
    tb_rad_lights *L = NULL;
    tb_status st = ev && ee ? TB_OK : tb_error(TB_ERR_NOMEM, "adaptive subdivision: out of memory");
    if (!st)
        st = tb_rad_lights_create(nm, opt->lights, opt->nlights, &L);
    const tb_mesh *rm = tb_mesh_refiner_mesh(r);
    for (int k = 0; k < opt->nlights && !st; k++) {
        if (!os.lights_shot[k] || (st = tb_rad_lights_shoot(L, k, ev, ee)))
            continue;
        if (hemi) {
            for (size_t i = 0; i < nm->nelems; i++)
                if (tb_mesh_elem_at(rm, i)->parent != TB_MESH_NONE)
                    for (size_t c = 0; c < nc; c++)
                        H[i * nc + c] += ee[i * nc + c];
        } else {
            for (size_t x = nv0 * nc; x < nm->nverts * nc; x++)
                H[x] += ev[x];
        }
    }
    tb_rad_lights_free(L);
    free(ev), free(ee);
    return st;
}

/* The new solver's initial state: H of new receivers gathered from what
 * the old elements have shot, old receivers' H kept, dB carried. */
static tb_status tb__carry(const tb_rad_solver *s, const tb_rad_mesh *nm, const tb_mesh_refiner *r,
                           const uint32_t *map, const tb_rad_options *opt, uint64_t round, double *H, double *He,
                           double *dB, size_t *gathered)
{
    const tb_rad_mesh *om = tb_rad_solver_mesh(s);
    tb_rad_state os = tb_rad_solver_state(s);
    int nc = om->nchannels;
    size_t one = om->nelems, nne = nm->nelems;
    bool hemi = opt->ff == TB_RAD_FF_HEMICUBE;
    tb_status st = TB_OK;

    /* dB: the old density, each old element's unshot power kept. */
    double *area_to = calloc(one, sizeof(double));
    double *shot = malloc(sizeof(double) * one * (size_t)nc);
    tb_ff_polygon *polys = malloc(sizeof *polys * one);
    if (!area_to || !shot || !polys) {
        st = tb_error(TB_ERR_NOMEM, "adaptive subdivision: out of memory");
        goto out;
    }
    for (size_t i = 0; i < nne; i++)
        area_to[map[i]] += nm->elems[i].area;
    for (size_t i = 0; i < nne; i++) {
        double k = om->elems[map[i]].area / area_to[map[i]];
        for (int c = 0; c < nc; c++)
            dB[i * (size_t)nc + (size_t)c] = os.unshot[map[i] * (size_t)nc + (size_t)c] * k;
    }
    /* What every old element has shot so far: B - dB (radiosity without
     * the ambient term). */
    bool any = false;
    for (size_t j = 0; j < one; j++) {
        double b[TB_CHANNELS_MAX];
        tb_rad_element_radiosity(s, j, false, b);
        for (int c = 0; c < nc; c++) {
            double v = b[c] - os.unshot[j * (size_t)nc + (size_t)c];
            shot[j * (size_t)nc + (size_t)c] = v > 0 ? v : 0;
            any |= v > 0;
        }
        tb_rad_mesh_polygon(om, j, &polys[j]);
    }

    if (hemi) {
        /* Per element: kept elements keep H; new ones look at the old
         * mesh through a hemicube at their centroid (their own old
         * element, coplanar, left out). */
        tb_hemicube *hc = tb_hemicube_create(opt->hemicube_res > 0 ? opt->hemicube_res : TB_RAD_DEFAULT_HEMICUBE_RES);
        double *ff = malloc(sizeof(double) * one);
        if (!hc || !ff) {
            tb_hemicube_free(hc);
            free(ff);
            st = tb_error(TB_ERR_NOMEM, "adaptive subdivision: out of memory");
            goto out;
        }
        const tb_mesh *rm = tb_mesh_refiner_mesh(r);
        for (size_t i = 0; i < nne && !st; i++) {
            double *h = H + i * (size_t)nc;
            if (tb_mesh_elem_at(rm, i)->parent == TB_MESH_NONE) {
                memcpy(h, os.gathered + map[i] * (size_t)nc, sizeof(double) * (size_t)nc);
                continue;
            }
            for (int c = 0; c < nc; c++)
                h[c] = 0;
            (*gathered)++;
            if (!any)
                continue;
            st = tb_hemicube_formfactors(hc, nm->elems[i].centroid, nm->elems[i].normal, polys, one, map[i], ff);
            for (size_t j = 0; j < one && !st; j++)
                if (ff[j] > 0)
                    for (int c = 0; c < nc; c++)
                        h[c] += shot[j * (size_t)nc + (size_t)c] * ff[j];
        }
        tb_hemicube_free(hc);
        free(ff);
        goto out;
    }

    /* Ray cast: per vertex; vertex indices are stable, so the first
     * om->nverts keep theirs and the rest are gathered, one old shooter
     * at a time through the solver's form-factor backend. */
    size_t nv0 = om->nverts, nnew = nm->nverts - nv0;
    memcpy(H, os.gathered, sizeof(double) * nv0 * (size_t)nc);
    memset(H + nv0 * (size_t)nc, 0, sizeof(double) * nnew * (size_t)nc);
    *gathered += nnew;
    if (!nnew || !any)
        goto out;
    int ns = opt->samples > 0 ? opt->samples : TB_RAD_DEFAULT_SAMPLES;
    tb_vec3 *p = malloc(sizeof *p * nnew), *n = malloc(sizeof *n * nnew), *pts = malloc(sizeof *pts * (size_t)ns);
    double *ff = malloc(sizeof(double) * nnew);
    tb_ff_occluders *occ = NULL;
    tb_ff_batch_fn batch = opt->batch;
    void *ctx = opt->batch_ctx;
    if (!p || !n || !pts || !ff)
        st = tb_error(TB_ERR_NOMEM, "adaptive subdivision: out of memory");
    if (!st && !batch) {
        batch = tb_ff_raycast_batch;
        if (!opt->no_occlusion && !(st = tb_ff_occluders_build(polys, one, &occ)))
            ctx = occ;
    }
    for (size_t v = 0; v < nnew && !st; v++)
        p[v] = nm->verts[nv0 + v].p, n[v] = nm->verts[nv0 + v].n;
    for (size_t j = 0; j < one && !st; j++) {
        const double *sj = shot + j * (size_t)nc;
        bool shoots = false;
        for (int c = 0; c < nc; c++)
            shoots |= sj[c] > 0;
        if (!shoots)
            continue;
        const tb_rad_element *e = &om->elems[j];
        st = tb_ff_sample_polygon(&polys[j], ns, tb__gather_seed(opt->seed, round, j), pts);
        if (!st)
            st = batch(ctx, pts, ns, e->normal, e->area, p, n, nnew, ff);
        /* Near the shooter (within TB__ADAPT_NEAR of its radii) the
         * sampled estimate is poor; as the solver does there, take the
         * exact unoccluded point-to-polygon form factor times the visible
         * fraction the samples measured. Receivers in the shooter's plane
         * see nothing of it. */
        double rad2 = 0;
        for (int k = 0; k < polys[j].n; k++) {
            tb_vec3 d = tb_vec3_sub(polys[j].v[k], e->centroid);
            rad2 = fmax(rad2, (double)tb_vec3_dot(d, d));
        }
        double rad = sqrt(rad2);
        for (size_t v = 0; v < nnew && !st; v++) {
            tb_vec3 d = tb_vec3_sub(p[v], e->centroid);
            if (!((double)tb_vec3_dot(d, d) < TB__ADAPT_NEAR * TB__ADAPT_NEAR * rad2))
                continue;
            if (fabs((double)tb_vec3_dot(d, e->normal)) <= 1e-6 * rad) {
                ff[v] = 0;
                continue;
            }
            double exact = tb_ff_point_polygon(p[v], n[v], &polys[j]);
            if (!(exact >= 0) || !isfinite(exact))
                continue;
            double open = tb_ff_raycast(pts, ns, e->normal, e->area, p[v], n[v], NULL, NULL);
            double vis = open > 0 ? fmin(1, ff[v] / open) : 1;
            ff[v] = exact * vis;
        }
        for (size_t v = 0; v < nnew && !st; v++)
            if (ff[v] > 0)
                for (int c = 0; c < nc; c++)
                    H[(nv0 + v) * (size_t)nc + (size_t)c] += sj[c] * ff[v];
    }
    tb_ff_occluders_free(occ);
    free(p), free(n), free(pts), free(ff);
out:
    if (!st)
        st = tb__carry_lights(s, nm, r, opt, H);
    if (!st && !hemi) {
        /* Element irradiance (ray cast): kept elements keep theirs (the
         * solver's estimate, exact next to a shooter); new ones start
         * from the mean of their corners, as the solver does. */
        const tb_mesh *rm = tb_mesh_refiner_mesh(r);
        for (size_t i = 0; i < nne; i++) {
            const tb_rad_element *e = &nm->elems[i];
            double *h = He + i * (size_t)nc;
            if (tb_mesh_elem_at(rm, i)->parent == TB_MESH_NONE && os.gathered_elems) {
                memcpy(h, os.gathered_elems + map[i] * (size_t)nc, sizeof(double) * (size_t)nc);
                continue;
            }
            int k = tb__nc(e);
            for (int c = 0; c < nc; c++) {
                double sum = 0;
                for (int q = 0; q < k; q++)
                    sum += H[e->v[q] * (size_t)nc + (size_t)c];
                h[c] = sum / k;
            }
        }
    }
    free(area_to), free(shot), free(polys);
    return st;
}

/* A deep copy of a radiosity mesh. */
static tb_status tb__copy_mesh(const tb_rad_mesh *m, tb_rad_mesh *out)
{
    tb_rad_mesh_init(out);
    size_t nc = (size_t)m->nchannels, ne = m->nelems ? m->nelems : 1;
    *out = *m;
    out->patch = NULL, out->patch_poly = NULL, out->npatches = 0;
    out->verts = malloc(sizeof *out->verts * (m->nverts ? m->nverts : 1));
    out->elems = malloc(sizeof *out->elems * ne);
    out->rho = malloc(sizeof *out->rho * ne * nc);
    out->emission = malloc(sizeof *out->emission * ne * nc);
    if (!out->verts || !out->elems || !out->rho || !out->emission) {
        tb_rad_mesh_free(out);
        return tb_error(TB_ERR_NOMEM, "adaptive subdivision: out of memory");
    }
    memcpy(out->verts, m->verts, sizeof *out->verts * m->nverts);
    memcpy(out->elems, m->elems, sizeof *out->elems * m->nelems);
    memcpy(out->rho, m->rho, sizeof *out->rho * m->nelems * nc);
    memcpy(out->emission, m->emission, sizeof *out->emission * m->nelems * nc);
    tb_status st = tb_rad_mesh_copy_patches(out, m, NULL);
    if (st)
        tb_rad_mesh_free(out);
    return st;
}

/* The refinement's state in a checkpoint (tb_rad_persist's `extra`): u64
 * rounds done, shots of the finished rounds, elements marked, receivers
 * gathered; then per round u64 n and its n marked elements (u32). */
typedef struct tb__adapt_ckpt {
    const tb_rad_persist *pe;
    tb_array bytes;          /* the state as saved (unsigned char) */
    const tb_rad_adapt_stats *sts;
} tb__adapt_ckpt;

/* Rewrites the head of c->bytes from *sts. */
static void tb__adapt_ckpt_head(tb__adapt_ckpt *c)
{
    uint64_t h[4] = {(uint64_t)c->sts->rounds, c->sts->shots, c->sts->marked, c->sts->gathered};
    memcpy(c->bytes.data, h, sizeof h);
}

/* tb_rad_solver_run's report: the persist's save after every shot. */
static tb_status tb__adapt_on_shot(void *user, const tb_rad_solver *s)
{
    tb__adapt_ckpt *c = user;
    tb__adapt_ckpt_head(c);
    return c->pe->save(c->pe->ctx, s, c->bytes.data, c->bytes.len, c->sts->shots + tb_rad_solver_shots(s), false);
}

/* Runs s to `stop`, saving as the persist decides when there is one. */
static tb_status tb__adapt_run(tb_rad_solver *s, const tb_rad_stop *stop, tb__adapt_ckpt *c)
{
    if (!c->pe || !c->pe->save)
        return tb_rad_solver_run(s, stop, NULL, NULL, 0);
    return tb_rad_solver_run(s, stop, tb__adapt_on_shot, c, 1);
}

tb_status tb_rad_adapt_solve(tb_rad_mesh *mesh, const tb_rad_options *opt, const tb_rad_stop *stop,
                             const tb_rad_adapt_options *aopt, tb_rad_solver **out, tb_rad_adapt_stats *stats)
{
    return tb_rad_adapt_solve_persist(mesh, opt, stop, aopt, NULL, out, stats);
}

/* Rebuilds the mesh of a saved state: replays its rounds' refinements from
 * *cur (replaced by the refined mesh) and restores *sts; c->bytes becomes
 * the saved state. */
static tb_status tb__adapt_replay(tb_mesh_refiner *r, tb_rad_mesh *cur, const unsigned char *x, size_t len,
                                  tb_rad_adapt_stats *sts, tb__adapt_ckpt *c, tb_array *map)
{
    uint64_t h[4];
    if (len < sizeof h)
        return tb_error(TB_ERR_FORMAT, "adaptive subdivision: saved state of %zu bytes", len);
    memcpy(h, x, sizeof h);
    if (h[0] > TB_RAD_ADAPT_MAX_LEVELS)
        return tb_error(TB_ERR_FORMAT, "adaptive subdivision: saved state of %llu rounds", (unsigned long long)h[0]);
    size_t at = sizeof h;
    for (uint64_t k = 0; k < h[0]; k++) {
        uint64_t n;
        if (len - at < sizeof n)
            return tb_error(TB_ERR_FORMAT, "adaptive subdivision: saved state truncated");
        memcpy(&n, x + at, sizeof n);
        at += sizeof n;
        if (n > (len - at) / sizeof(uint32_t))
            return tb_error(TB_ERR_FORMAT, "adaptive subdivision: saved state truncated");
        uint32_t *marked = malloc(n ? n * sizeof *marked : 1);
        if (!marked)
            return tb_error(TB_ERR_NOMEM, "adaptive subdivision: out of memory");
        memcpy(marked, x + at, n * sizeof *marked);
        at += n * sizeof *marked;
        for (uint64_t i = 0; i < n; i++)
            if (marked[i] >= cur->nelems) {
                free(marked);
                return tb_error(TB_ERR_FORMAT, "adaptive subdivision: saved state marks element %u of %zu",
                                marked[i], cur->nelems);
            }
        tb_status st = tb_mesh_refine(r, marked, (size_t)n, map, NULL);
        free(marked);
        tb_rad_mesh nm;
        if (!st)
            st = tb__from_refiner(r, cur, map->data, &nm);
        if (st)
            return st;
        tb_rad_mesh_free(cur);
        *cur = nm;
    }
    if (at != len)
        return tb_error(TB_ERR_FORMAT, "adaptive subdivision: saved state has %zu bytes too many", len - at);
    sts->rounds = (int)h[0], sts->shots = h[1], sts->marked = (size_t)h[2], sts->gathered = (size_t)h[3];
    tb_array_clear(&c->bytes);
    return tb_array_push_n(&c->bytes, x, len);
}

tb_status tb_rad_adapt_solve_persist(tb_rad_mesh *mesh, const tb_rad_options *opt, const tb_rad_stop *stop,
                                     const tb_rad_adapt_options *aopt, const tb_rad_persist *persist,
                                     tb_rad_solver **out, tb_rad_adapt_stats *stats)
{
    *out = NULL;
    tb_rad_adapt_stats sts = {.elems_in = mesh->nelems};
    tb_rad_options o = {0};
    if (opt)
        o = *opt;
    int levels = aopt->max_levels ? aopt->max_levels : TB_RAD_ADAPT_DEFAULT_LEVELS;
    if (!(aopt->threshold > 0) || !isfinite(aopt->threshold))
        return tb_error(TB_ERR_ARG, "adaptive subdivision: threshold %g is not positive", aopt->threshold);
    if (levels < 1 || levels > TB_RAD_ADAPT_MAX_LEVELS)
        return tb_error(TB_ERR_ARG, "adaptive subdivision: %d levels not in 1..%d", levels, TB_RAD_ADAPT_MAX_LEVELS);
    if (!(aopt->min_area >= 0) || !isfinite(aopt->min_area))
        return tb_error(TB_ERR_ARG, "adaptive subdivision: minimum area %g out of range", aopt->min_area);

    tb_mesh base;
    tb_mesh_refiner *r = NULL;
    tb_status st = tb__to_mesh(mesh, &base);
    if (!st)
        st = tb_mesh_refiner_create(&base, &r);
    tb_mesh_free(&base);
    if (st)
        return tb_error_context(st, "adaptive subdivision");

    double t0 = 1e-9 * (double)tb_stats_now_ns();
    tb_rad_solver *s = NULL;
    tb_array marked = TB_ARRAY_INIT(uint32_t), map = TB_ARRAY_INIT(uint32_t);
    uint32_t *level = NULL;
    tb__adapt_ckpt ck = {.pe = persist, .bytes = TB_ARRAY_INIT(unsigned char), .sts = &sts};
    uint64_t zero[4] = {0, 0, 0, 0};
    st = tb_array_push_n(&ck.bytes, zero, sizeof zero);
    /* a saved state: the mesh of its round, the solver's state */
    bool found = false;
    void *extra = NULL, *saved = NULL;
    size_t extra_len = 0, saved_len = 0;
    tb_rad_mesh cur;
    bool have_cur = false;
    if (!st && persist && persist->load)
        st = persist->load(persist->ctx, &found, &extra, &extra_len, &saved, &saved_len);
    if (!st && found && !extra_len)
        st = tb_error(TB_ERR_FORMAT, "the checkpoint is of a solve without adaptive subdivision");
    if (!st && found && !(st = tb__copy_mesh(mesh, &cur))) {
        have_cur = true;
        st = tb__adapt_replay(r, &cur, extra, extra_len, &sts, &ck, &map);
    }
    if (!st)
        st = tb_rad_solver_create(have_cur ? &cur : mesh, NULL, &o, &s);
    if (have_cur)
        tb_rad_mesh_free(&cur);
    if (!st && found)
        st = tb_rad_solver_unpack(s, saved, saved_len);
    free(extra);
    free(saved);
    /* a round's shot limit counts the shots it made before the save */
    tb_rad_stop first = stop ? *stop : (tb_rad_stop){0};
    bool ran_out = false;
    if (found && first.max_shots > 0) {
        uint64_t done = tb_rad_solver_shots(s);
        ran_out = done >= first.max_shots;
        first.max_shots -= ran_out ? first.max_shots : done;
    }
    if (!st && !ran_out)
        st = tb__adapt_run(s, &first, &ck);
    for (int round = sts.rounds; round < levels && !st; round++) {
        const tb_rad_mesh *sm = tb_rad_solver_mesh(s);
        free(level);
        level = malloc(sizeof *level * (sm->nelems ? sm->nelems : 1));
        if (!level) {
            st = tb_error(TB_ERR_NOMEM, "adaptive subdivision: out of memory");
            break;
        }
        for (size_t i = 0; i < sm->nelems; i++)
            level[i] = tb_mesh_refiner_level(r, i);
        st = tb_rad_adapt_mark(s, aopt->threshold, aopt->min_area, level, levels, &marked);
        if (st || marked.len == 0)
            break;
        sts.marked += marked.len;
        uint64_t n = marked.len;
        if (persist && ((st = tb_array_push_n(&ck.bytes, &n, sizeof n)) ||
                        (st = tb_array_push_n(&ck.bytes, marked.data, marked.len * sizeof(uint32_t)))))
            break;
        st = tb_mesh_refine(r, marked.data, marked.len, &map, NULL);
        if (st)
            break;
        tb_rad_mesh nm;
        st = tb__from_refiner(r, sm, map.data, &nm);
        if (st)
            break;
        size_t nrecv = o.ff == TB_RAD_FF_HEMICUBE ? nm.nelems : nm.nverts;
        double *H = malloc(sizeof(double) * (nrecv ? nrecv : 1) * (size_t)nm.nchannels);
        double *dB = malloc(sizeof(double) * (nm.nelems ? nm.nelems : 1) * (size_t)nm.nchannels);
        double *He = malloc(sizeof(double) * (nm.nelems ? nm.nelems : 1) * (size_t)nm.nchannels);
        if (!H || !dB || !He)
            st = tb_error(TB_ERR_NOMEM, "adaptive subdivision: out of memory");
        if (!st)
            st = tb__carry(s, &nm, r, map.data, &o, (uint64_t)round, H, He, dB, &sts.gathered);
        tb_rad_solver *ns = NULL;
        if (!st) {
            tb_rad_state state = {.gathered = H, .unshot = dB,
                                  .gathered_elems = o.ff == TB_RAD_FF_HEMICUBE ? NULL : He,
                                  .lights_shot = tb_rad_solver_state(s).lights_shot};
            st = tb_rad_solver_create(&nm, &state, &o, &ns);
        }
        free(H), free(dB), free(He);
        tb_rad_mesh_free(&nm);
        if (st)
            break;
        sts.shots += tb_rad_solver_shots(s);
        tb_rad_solver_free(s);
        s = ns;
        sts.rounds++;
        st = tb__adapt_run(s, stop, &ck);
    }
    if (!st && persist && persist->save) {
        tb__adapt_ckpt_head(&ck);
        st = persist->save(persist->ctx, s, ck.bytes.data, ck.bytes.len, sts.shots + tb_rad_solver_shots(s), true);
    }
    tb_array_free(&ck.bytes);
    free(level);
    tb_array_free(&marked);
    tb_array_free(&map);
    tb_mesh_refiner_free(r);
    tb_rad_mesh fin;
    if (!st && sts.rounds > 0 && !(st = tb__copy_mesh(tb_rad_solver_mesh(s), &fin))) {
        tb_rad_mesh_free(mesh);
        *mesh = fin;
    }
    if (st) {
        tb_rad_solver_free(s);
        /* over several processes the others are mid-solve: stop them all */
        if (o.exchange && o.exchange->ranks > 1 && o.exchange->fail)
            o.exchange->fail(o.exchange->ctx, st);
        return st;
    }
    sts.shots += tb_rad_solver_shots(s);
    sts.elems_out = tb_rad_solver_mesh(s)->nelems;
    sts.seconds = 1e-9 * (double)tb_stats_now_ns() - t0;
    tb_stat_add(&tb__adapt_gathered, (int64_t)sts.gathered);
    if (stats)
        *stats = sts;
    *out = s;
    return TB_OK;
}
