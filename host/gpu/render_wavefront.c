/* The wavefront (render.h; docs/gpu.md, "Shade kernel and wavefront
 * renderer"): every path's top ray intersected on the device, the hits
 * shaded by the shade kernel or routed to the CPU path with their subtrees
 * (render_route.c), the shadow rays traced, the secondary rays pushed; until
 * every path's stack is empty. */
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "host/gpu/render_internal.h"
#include "host/object/intersect.h"
#include "host/render/camera.h"
#include "host/render/raytrace_internal.h"
#include "host/render/sampling.h"
#include "util/stats/stats.h"

TB_STAT_COUNTER(tb__gr_rays, "GPU render/rays intersected");
TB_STAT_COUNTER(tb__gr_shadow, "GPU render/shadow rays");
TB_STAT_COUNTER(tb__gr_gpu_shaded, "GPU render/hits shaded by the kernel");
TB_STAT_COUNTER(tb__gr_cpu_shaded, "GPU render/hits routed to the CPU path");

void tb__gr_push(tb__paths *P, size_t p, const tb_ray *ray, int depth, const float *thr, const tb_rt_mis *mis)
{
    int k = P->top[p]++;
    size_t e = p * (size_t)P->cap + (size_t)k;
    P->ray[e] = *ray;
    P->depth[e] = depth;
    if (mis)
        P->mis[e] = *mis;
    else
        P->mis[e].nb = 0.0;
    memcpy(P->thr + e * (size_t)P->nch, thr, sizeof(float) * (size_t)P->nch);
}

/* One wave's active paths (popped entries). */
typedef struct tb__wave {
    size_t n;
    size_t *path;
    tb_ray *ray;
    int *depth;
    float *thr;       /* [a * nch + c] */
    tb_rt_mis *mis;   /* glossy rays' weighting (nb = 0: none) */
    tb_hit *hit;
    size_t *item_of;  /* items: index into the wave */
    size_t *routed;   /* routed hits: index into the wave */
    int *mat;         /* material of each hit */
    size_t *sstart;   /* item j's shadow rays are shadow[sstart[j] .. sstart[j + 1]) */
    tb_gpu_surface *surf; /* surface records of hits on patterned materials (any_surface only) */
    uint8_t *sok;     /* 1: surf[a] is set; 0: none needed; 2: needed but the hit has no tangents (routed) */
    tb_ray *shadow;   /* shadow rays of one chunk */
    size_t *shadow_src; /* value slot index (chunk-local) of each shadow ray */
    uint8_t *occl;
} tb__wave;

/* Runs the shade kernel on r->items[0..ni) and handles its outputs for the
 * wave entries w->item_of[base ..]. */
static tb_status tb__shade_chunk(tb_gpu_renderer *r, tb__paths *P, tb__wave *w, size_t base, size_t ni,
                                 size_t nlu)
{
    const int nch = r->nch, S = r->S, G = r->nglossy;
    const size_t SW = (size_t)r->sw, NR = TB_GPU_SHADE_RAYS((size_t)S, (size_t)G),
                 NV = TB_GPU_SHADE_VALUES((size_t)S, (size_t)nch, SW, (size_t)G, (size_t)r->pw),
                 SL = (size_t)nch + 1;
    double w0 = tb__gr_now();
    tb_status st = tb_gpu_buffer_upload(r->b_items, 0, r->items, ni * sizeof *r->items);
    if (!st && nlu)
        st = tb_gpu_buffer_upload(r->b_lightu, 0, r->lightu, nlu * sizeof *r->lightu);
    if (!st && r->any_surface) /* records of items without the flag are not read */
        st = tb_gpu_buffer_upload(r->b_surf, 0, r->surf, ni * sizeof *r->surf);
    if (st)
        return st;
    tb_gpu_kernel *k = tb_gpu_kernel_get(r->dev, &(tb_gpu_kernel_desc){.spirv = tb_gpu_builtin("shade"),
                                                                        .buffers = 11,
                                                                        .push_size = sizeof(tb_gpu_shade_push),
                                                                        .spec = r->spec,
                                                                        .spec_count = 17});
    if (!k)
        return TB_ERR_DEVICE;
    tb_gpu_shade_push push = {(uint32_t)ni, r->perm_col, 0, 0};
    tb_gpu_dispatch d = {k,
                         {r->b_items, r->b_lightu, r->b_emitters, r->b_lights, r->b_materials, r->b_colours,
                          r->b_rays, r->b_values, r->b_surf, r->b_texinfo, r->b_texels},
                         &push,
                         ni,
                         0.0};
    if ((st = tb_gpu_run(r->dev, &d, 1)))
        return st;
    r->st.shade_seconds += d.seconds;
    if ((st = tb_gpu_buffer_download(r->b_rays, 0, r->orays, ni * NR * sizeof(tb_gpu_ray))) ||
        (st = tb_gpu_buffer_download(r->b_values, 0, r->ovals, ni * NV * sizeof(float))))
        return st;
    r->st.shade_wall_seconds += tb__gr_now() - w0;

    /* Emission, secondary rays; shadow rays collected. The outputs are
     * word-major (shared/shade.h): word w of item j at w ni + j; shadow slot
     * s's words (flag, a, b[, c]) are SW s .. SW s + SW - 1, colour slot k's
     * (flag, channels) follow from SW S + k SL, the glossy densities from
     * SW S + (3 + G) SL; ray slot k at k ni + j. */
#define TB__W(j, w) r->ovals[(size_t)(w) * ni + (j)]
#define TB__C(j, k, c) TB__W(j, SW * (size_t)S + (size_t)(k) * SL + (size_t)(c))
#define TB__PDF(j, k) TB__W(j, SW * (size_t)S + (3 + (size_t)G) * SL + (size_t)(k))
#define TB__PAT(j, k) TB__W(j, SW * (size_t)S + (3 + (size_t)G) * SL + (size_t)G + (size_t)(k))
    /* shadow rays of the chunk in item order (sequential: it compacts) */
    size_t ns = 0;
    for (size_t j = 0; j < ni; j++) {
        w->sstart[j] = ns;
        for (int s = 0; s < S; s++)
            if (TB__W(j, SW * (size_t)s) != 0.0f) {
                w->shadow[ns] = r->orays[(size_t)s * ni + j];
                w->shadow_src[ns++] = j * (size_t)S + (size_t)s;
            }
    }
    w->sstart[ni] = ns;
    const int nthreads = r->threads > 0 ? r->threads : omp_get_max_threads();
    /* items belong to distinct paths: any thread order gives the same sums */
#pragma omp parallel for schedule(static) num_threads(nthreads)
    for (size_t j = 0; j < ni; j++) {
        size_t a = w->item_of[base + j], p = w->path[a];
        const float *thr = w->thr + a * (size_t)nch;
        float *L = P->L + p * (size_t)nch;
        float tmp[TB_CHANNELS_MAX];
        if (TB__C(j, 0, 0) != 0.0f) {
            /* a glossy ray's emission is weighted against the light samples
             * of the point it left (power heuristic), in double as on the
             * CPU path */
            float wm = w->mis[a].nb > 0.0 ? (float)tb_rt_mis_weight(&r->rt, &w->mis[a]) : 1.0f;
            for (int c = 0; c < nch; c++)
                L[c] += thr[c] * (TB__C(j, 0, 1 + c) * wm);
        }
        /* refracted first, so the mirror ray is on top (the CPU traces it first) */
        for (int k = 2; k >= 1; k--) {
            if (TB__C(j, k, 0) == 0.0f)
                continue;
            for (int c = 0; c < nch; c++)
                tmp[c] = thr[c] * TB__C(j, k, 1 + c);
            tb__gr_push(P, p, &r->orays[(size_t)(S + k - 1) * ni + j], w->depth[a] + 1, tmp, NULL);
        }
        /* glossy rays, the last first so that ray 0 is on top (the CPU
         * traces them in order), each weighted 1 / (rays sampled) */
        const tb_gpu_shade_item *it = &r->items[j];
        if (it->glossy > 0) {
            tb_rt_mis mis = {.p = tb_vec3_add(it->o, tb_vec3_scale(it->d, it->t)),
                             .nb = (double)it->glossy, .nl = (double)r->rt.light_samples};
            float inv = 1.0f / (float)it->glossy;
            for (int k = (int)it->glossy - 1; k >= 0; k--) {
                if (TB__C(j, 3 + k, 0) == 0.0f)
                    continue;
                const tb_ray *gr = &r->orays[(size_t)(S + 2 + k) * ni + j];
                for (int c = 0; c < nch; c++)
                    tmp[c] = thr[c] * (TB__C(j, 3 + k, 1 + c) * inv);
                mis.w = gr->d;
                mis.pdf = TB__PDF(j, k);
                tb__gr_push(P, p, gr, w->depth[a] + 1, tmp, &mis);
            }
        }
    }
    if (ns) {
        double t0 = tb__gr_now();
        st = tb_gpu_occluded(r->gscene, w->shadow, ns, w->occl, NULL);
        r->st.trace_seconds += tb__gr_now() - t0;
        if (st)
            return st;
        r->st.shadow_rays += ns;
        tb_stat_add(&tb__gr_shadow, (int64_t)ns);
        /* An unblocked shadow ray adds (diffuse a + specular b) x its light's
         * colour (the light's intensity, or the sampled emitter's radiance). */
#pragma omp parallel for schedule(static) num_threads(nthreads)
        for (size_t j = 0; j < ni; j++) {
            size_t a = w->item_of[base + j], p = w->path[a];
            const tb_gpu_shade_item *it = &r->items[j];
            const float *thr = w->thr + a * (size_t)nch;
            const float *dif = r->col + (size_t)it->material * 4 * (size_t)nch, *spec = dif + nch;
            /* colour patterns: the blend a + f (b - a) of the kernel's
             * factors, in double as the CPU tracer blends */
            float pdif[TB_CHANNELS_MAX], pspec[TB_CHANNELS_MAX];
            for (int k = 0; k < r->pw0; k++) {
                float f = TB__PAT(j, k);
                if (f < 0.0f)
                    continue;
                const float *pa = r->col + r->pat_col[2 * (size_t)it->material + (size_t)k], *pb = pa + nch;
                float *out = k == 0 ? pdif : pspec;
                for (int c = 0; c < nch; c++)
                    out[c] = (float)((double)pa[c] + (double)f * ((double)pb[c] - (double)pa[c]));
                if (k == 0)
                    dif = pdif;
                else
                    spec = pspec;
            }
            /* image textures: times the texture's RGB (RGB scenes only) */
            for (int k = 0; r->pw > r->pw0 && k < 2; k++) {
                if (TB__PAT(j, (size_t)r->pw0 + 3 * (size_t)k) < 0.0f)
                    continue;
                const float *src = k == 0 ? dif : spec;
                float *out = k == 0 ? pdif : pspec;
                for (int c = 0; c < nch; c++)
                    out[c] = src[c] * TB__PAT(j, (size_t)r->pw0 + 3 * (size_t)k + (size_t)c);
                if (k == 0)
                    dif = pdif;
                else
                    spec = pspec;
            }
            float *L = P->L + p * (size_t)nch;
            for (size_t q = w->sstart[j]; q < w->sstart[j + 1]; q++) {
                if (w->occl[q])
                    continue;
                size_t k = w->shadow_src[q] % (size_t)S;
                const float *lc =
                    k < (size_t)r->nlights
                        ? r->col + r->light_col + k * (size_t)nch
                        : r->col + r->emitter_col +
                              (size_t)r->lightu[it->light_base + (k - (size_t)r->nlights)].emitter * (size_t)nch;
                float ca = TB__W(j, SW * k + 1), cb = TB__W(j, SW * k + 2), cc = SW > 3 ? TB__W(j, SW * k + 3) : 0.0f;
                for (int c = 0; c < nch; c++)
                    L[c] += thr[c] * ((dif[c] * ca + spec[c] * cb + cc) * lc[c]);
            }
        }
    }
#undef TB__PAT
#undef TB__PDF
#undef TB__C
#undef TB__W
    return TB_OK;
}

/* The surface record of wave entry a (a hit on a patterned material), as
 * the CPU tracer builds it at that hit: the hit point from the object,
 * the camera ray's differentials for a camera ray of the renderer (the
 * lens numbers again from the sample's stream). 1 if set, 2 if the hit has
 * no tangents (the CPU then shades without the patterns: the hit is routed). */
static uint8_t tb__surface(const tb_gpu_renderer *r, const tb__paths *P, tb__wave *w, size_t a)
{
    const tb_scene *s = r->scene;
    const tb_hit *h = &w->hit[a];
    const tb_ray *ray = &w->ray[a];
    tb_vec3 p, perr;
    if (!tb_object_hit_point(s->objects[h->object], ray, h, &p, &perr))
        p = tb_vec3_add(ray->o, tb_vec3_scale(ray->d, h->t)); /* raytrace.c's fallback */
    tb_vec3 d = tb_vec3_normalize(ray->d);
    tb_vec3 n = tb_vec3_dot(d, h->ng) < 0.0f ? h->ng : tb_vec3_neg(h->ng);
    tb_vec3 rd[4];
    const tb_vec3 *rdp = NULL;
    size_t path = w->path[a];
    if (w->depth[a] == 0 && P->xy) {
        tb_rng rng0 = P->rng0[path];
        float lu, lv;
        tb_camera_lens_numbers(&s->camera, &rng0, &lu, &lv);
        tb_camera_ray_diff cd;
        tb_camera_ray_differential(&s->camera, P->xy[2 * path], P->xy[2 * path + 1], lu, lv, &cd);
        rd[0] = cd.rx_o, rd[1] = cd.rx_d, rd[2] = cd.ry_o, rd[3] = cd.ry_d;
        rdp = rd;
    }
    tb__rt_surface g;
    if (!tb__rt_hit_surface(&r->rt, h, p, h->ng, n, rdp, &g)) {
        if (r->mpat[w->mat[a]] != 2)
            return 2;
        /* textures only: the CPU looks them up at (u, v) without a footprint */
        w->surf[a] = (tb_gpu_surface){.u = h->u, .v = h->v};
        return 1;
    }
    w->surf[a] = (tb_gpu_surface){.po = g.po, .u = g.u, .po_du = g.po_du, .v = g.v, .po_dv = g.po_dv,
                                  .has_fp = g.has_fp, .po_dx = g.po_dx, .po_dy = g.po_dy, .dpdu = g.dpdu,
                                  .dpdv = g.dpdv};
    if (g.has_fp) {
        w->surf[a].fp0 = g.fp[0];
        w->surf[a].fp1 = g.fp[1];
        w->surf[a].fp2 = g.fp[2];
        w->surf[a].fp3 = g.fp[3];
    }
    return 1;
}

/* Traces every path's stack empty. */
tb_status tb__gr_wavefront(tb_gpu_renderer *r, tb__paths *P)
{
    const tb_scene *s = r->scene;
    const int nch = r->nch;
    const size_t n = P->n, S = (size_t)r->S;
    tb__wave w = {0};
    w.path = malloc(n * sizeof *w.path);
    w.ray = malloc(n * sizeof *w.ray);
    w.depth = malloc(n * sizeof *w.depth);
    w.thr = malloc(n * (size_t)nch * sizeof *w.thr);
    w.mis = malloc(n * sizeof *w.mis);
    w.surf = r->any_surface ? malloc(n * sizeof *w.surf) : NULL;
    w.sok = r->any_surface ? malloc(n ? n : 1) : NULL;
    w.hit = malloc(n * sizeof *w.hit);
    w.item_of = malloc(n * sizeof *w.item_of);
    w.routed = malloc(n * sizeof *w.routed);
    w.mat = malloc(n * sizeof *w.mat);
    w.sstart = malloc((r->chunk + 1) * sizeof *w.sstart);
    w.shadow = malloc(r->chunk * (S ? S : 1) * sizeof *w.shadow);
    w.shadow_src = malloc(r->chunk * (S ? S : 1) * sizeof *w.shadow_src);
    w.occl = malloc(r->chunk * (S ? S : 1));
    tb_status st = TB_OK;
    if (!w.path || !w.ray || !w.depth || !w.thr || !w.mis || (r->any_surface && (!w.surf || !w.sok)) || !w.hit ||
        !w.item_of || !w.routed || !w.mat || !w.sstart || !w.shadow || !w.shadow_src || !w.occl)
        st = tb_error(TB_ERR_NOMEM, "GPU render: out of memory for %zu paths", n);
    const int nthreads = r->threads > 0 ? r->threads : omp_get_max_threads();
    double wave0 = tb__gr_now();
    while (!st) {
        /* pop the top of every active path */
        w.n = 0;
        for (size_t p = 0; p < n; p++) {
            if (P->top[p] == 0)
                continue;
            size_t e = p * (size_t)P->cap + (size_t)(--P->top[p]);
            w.path[w.n] = p;
            w.ray[w.n] = P->ray[e];
            w.depth[w.n] = P->depth[e];
            w.mis[w.n] = P->mis[e];
            memcpy(w.thr + w.n * (size_t)nch, P->thr + e * (size_t)nch, sizeof(float) * (size_t)nch);
            w.n++;
        }
        if (w.n == 0)
            break;
        r->st.waves++;
        double t0 = tb__gr_now();
        st = tb_gpu_intersect(r->gscene, w.ray, w.n, w.hit, NULL);
        r->st.trace_seconds += tb__gr_now() - t0;
        if (st)
            break;
        r->st.rays += w.n;
        tb_stat_add(&tb__gr_rays, (int64_t)w.n);
        /* Materials, and the surface records of patterned hits (in parallel:
         * each entry its own). */
#pragma omp parallel for schedule(dynamic, 64) num_threads(nthreads)
        for (size_t a = 0; a < w.n; a++) {
            const tb_hit *h = &w.hit[a];
            const tb_material *m = h->object == TB_GPU_NO_HIT ? NULL : tb_scene_hit_material(s, h);
            w.mat[a] = m ? (int)(m - s->materials) : -1;
            if (r->any_surface)
                w.sok[a] = m && !r->route[w.mat[a]] && r->mpat[w.mat[a]] ? tb__surface(r, P, &w, a) : 0;
        }
        /* Classify the hits: kernel items and routed hits (wave indices). */
        size_t nit = 0, nrt = 0;
        for (size_t a = 0; a < w.n; a++) {
            if (w.mat[a] < 0)
                continue;
            if (r->route[w.mat[a]] || (r->any_surface && w.sok[a] == 2))
                w.routed[nrt++] = a;
            else
                w.item_of[nit++] = a;
        }
        /* Routed hits: the CPU path for the ray and everything it spawns, with
         * the path's stream (paths are distinct: any thread order gives the
         * same sums). */
        double c0 = tb__gr_now();
#pragma omp parallel for schedule(dynamic, 16) num_threads(nthreads)
        for (size_t q = 0; q < nrt; q++) {
            size_t a = w.routed[q], p = w.path[a];
            float tmp[TB_CHANNELS_MAX];
            if (w.depth[a] == 0 && P->xy) {
                tb_rng rng0 = P->rng0[p];
                tb_rt_sample(&r->rt, P->xy[2 * p], P->xy[2 * p + 1], &rng0, tmp);
                P->rng[p] = rng0;
            } else {
                tb_channels Lc = tb_rt_radiance_at(&r->rt, &w.ray[a], &P->rng[p], w.depth[a],
                                                   w.mis[a].nb > 0.0 ? &w.mis[a] : NULL);
                memcpy(tmp, Lc.v, sizeof(float) * (size_t)nch);
            }
            float *L = P->L + p * (size_t)nch;
            const float *thr = w.thr + a * (size_t)nch;
            for (int c = 0; c < nch; c++)
                L[c] += thr[c] * tmp[c];
        }
        if (nrt)
            r->st.cpu_seconds += tb__gr_now() - c0;
        r->st.cpu_shaded += nrt;
        tb_stat_add(&tb__gr_cpu_shaded, (int64_t)nrt);
        r->st.gpu_shaded += nit;
        tb_stat_add(&tb__gr_gpu_shaded, (int64_t)nit);
        /* Kernel items in chunks; item j's light samples at j * nsamples. */
        for (size_t base = 0; base < nit && !st; base += r->chunk) {
            size_t ni = nit - base < r->chunk ? nit - base : r->chunk;
#pragma omp parallel for schedule(static) num_threads(nthreads)
            for (size_t j = 0; j < ni; j++) {
                size_t a = w.item_of[base + j], p = w.path[a];
                const tb_hit *h = &w.hit[a];
                int mi = w.mat[a];
                tb_gpu_shade_item *item = &r->items[j];
                *item = (tb_gpu_shade_item){.o = w.ray[a].o, .t = h->t, .d = w.ray[a].d, .material = (uint32_t)mi,
                                            .ng = h->ng, .light_base = (uint32_t)(j * (size_t)r->lu_per)};
                if (w.depth[a] < r->rt.max_depth)
                    item->flags |= TB_GPU_SHADE_SPAWN;
                if (r->any_surface && w.sok[a] == 1) {
                    item->flags |= TB_GPU_SHADE_SURFACE;
                    r->surf[j] = w.surf[a];
                }
                const uint8_t mf = r->mflags[mi];
                if (r->nsamples > 0 && (mf & (TB_GPU_MAT_DIFFUSE | TB_GPU_MAT_GGX))) {
                    /* the CPU path's numbers: strata from the sample's stream, the
                     * emitter by the double CDF (tb_area_light_sample) */
                    float u[2 * TB__GR_MAX_LIGHT_SAMPLES];
                    item->flags |= TB_GPU_SHADE_AREA;
                    tb_stratified_2d(&P->rng[p], r->rt.lsx, r->rt.lsy, u);
                    for (int k = 0; k < r->nsamples; k++) {
                        double pmf, ur;
                        int e = tb_distrib1d_sample_discrete(&r->rt.lights.area.select, u[2 * k], &pmf, &ur);
                        float u1r = (float)ur;
                        if (u1r >= 1.0f)
                            u1r = 0x1.fffffep-1f;
                        r->lightu[item->light_base + (uint32_t)k] =
                            (tb_gpu_light_u){(uint32_t)e, u1r, u[2 * k + 1], (float)pmf};
                    }
                }
                /* glossy rays (raytrace.c): below the depth limit, not on a
                 * dielectric; glossy_samples of them at a camera ray's hit,
                 * one deeper; their strata drawn after the light samples */
                if ((mf & TB_GPU_MAT_GGX) && !(mf & TB_GPU_MAT_TRANSMISSION) && w.depth[a] < r->rt.max_depth) {
                    float u[2 * TB__GR_MAX_LIGHT_SAMPLES];
                    int nx = w.depth[a] == 0 ? r->rt.gsx : 1, ny = w.depth[a] == 0 ? r->rt.gsy : 1;
                    item->glossy = (uint32_t)(nx * ny);
                    tb_stratified_2d(&P->rng[p], nx, ny, u);
                    for (int k = 0; k < nx * ny; k++)
                        r->lightu[item->light_base + (uint32_t)(r->nsamples + k)] =
                            (tb_gpu_light_u){0, u[2 * k], u[2 * k + 1], 0.0f};
                }
            }
            st = tb__shade_chunk(r, P, &w, base, ni, ni * (size_t)r->lu_per);
        }
    }
    r->st.wave_seconds += tb__gr_now() - wave0;
    free(w.path), free(w.ray), free(w.depth), free(w.thr), free(w.hit), free(w.item_of), free(w.shadow),
        free(w.shadow_src), free(w.occl), free(w.routed), free(w.mat), free(w.sstart), free(w.mis), free(w.surf),
        free(w.sok);
    return st;
}

/* Allocates the stacks of n paths. */
tb_status tb__gr_paths_alloc(tb__paths *P, size_t n, int cap, int nch)
{
    memset(P, 0, sizeof *P);
    P->n = n;
    P->cap = cap;
    P->nch = nch;
    P->ray = malloc(n * (size_t)cap * sizeof *P->ray);
    P->depth = malloc(n * (size_t)cap * sizeof *P->depth);
    P->thr = malloc(n * (size_t)cap * (size_t)nch * sizeof *P->thr);
    P->mis = malloc(n * (size_t)cap * sizeof *P->mis);
    P->top = calloc(n ? n : 1, sizeof *P->top);
    if (!P->ray || !P->depth || !P->thr || !P->mis || !P->top)
        return tb_error(TB_ERR_NOMEM, "GPU render: out of memory for %zu paths", n);
    return TB_OK;
}

void tb__gr_paths_free(tb__paths *P)
{
    free(P->ray), free(P->depth), free(P->thr), free(P->mis), free(P->top);
}

tb_status tb_gpu_radiance(tb_gpu_renderer *r, const tb_ray *rays, tb_rng *rngs, size_t n, float *out)
{
    tb__paths P;
    tb_status st = tb__gr_paths_alloc(&P, n, r->cap_stack, r->nch);
    float one[TB_CHANNELS_MAX];
    for (int c = 0; c < TB_CHANNELS_MAX; c++)
        one[c] = 1.0f;
    if (!st) {
        P.rng = rngs;
        P.L = out;
        memset(out, 0, n * (size_t)r->nch * sizeof *out);
        for (size_t i = 0; i < n; i++)
            tb__gr_push(&P, i, &rays[i], 0, one, NULL);
        st = tb__gr_wavefront(r, &P);
    }
    tb__gr_paths_free(&P);
    return st;
}

void tb__gr_push_camera(tb__paths *P, size_t q, const tb_camera *cam, double x, double y, tb_rng *rng,
                        tb_rng *rng0)
{
    float one[TB_CHANNELS_MAX];
    for (int c = 0; c < P->nch; c++)
        one[c] = 1.0f;
    *rng0 = *rng;
    float lu, lv;
    tb_camera_lens_numbers(cam, rng, &lu, &lv);
    tb_ray ray = tb_camera_ray(cam, x, y, lu, lv);
    P->top[q] = 0;
    tb__gr_push(P, q, &ray, 0, one, NULL);
}
