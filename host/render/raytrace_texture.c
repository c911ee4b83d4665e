/* The ray tracer's image textures and their footprints (raytrace_internal.h). */
#include <stdbool.h>
#include <stdlib.h>

#include "host/render/raytrace_internal.h"
#include "host/render/texture.h"
#include "util/base/error.h"

struct tb__rt_textures {
    tb_texture_cache *cache;
    int n;
    const tb_mipmap **mip; /* per index given to load: its image, or NULL */
};

tb_status tb__rt_textures_load(int n, const char *const *paths, tb__rt_textures **out)
{
    *out = NULL;
    tb__rt_textures *t = calloc(1, sizeof *t);
    if (!t)
        return tb_error(TB_ERR_NOMEM, "raytrace: out of memory");
    t->n = n;
    t->cache = tb_texture_cache_create();
    t->mip = calloc(n > 0 ? (size_t)n : 1, sizeof *t->mip);
    if (!t->cache || !t->mip) {
        tb__rt_textures_free(t);
        return tb_error(TB_ERR_NOMEM, "raytrace: out of memory");
    }
    for (int i = 0; i < n; i++) {
        if (!paths[i])
            continue;
        tb_status st = tb_texture_cache_get(t->cache, NULL, paths[i], NULL, &t->mip[i]);
        if (st) {
            tb__rt_textures_free(t);
            return st;
        }
    }
    *out = t;
    return TB_OK;
}

void tb__rt_textures_free(tb__rt_textures *t)
{
    if (!t)
        return;
    tb_texture_cache_free(t->cache);
    free(t->mip);
    free(t);
}

const tb_mipmap *tb__rt_texture_mip(const tb__rt_textures *t, int i)
{
    return t && i >= 0 && i < t->n ? t->mip[i] : NULL;
}

bool tb__rt_texture_rgb(const tb__rt_textures *t, int i, int filter, float u, float v, const float fp[4],
                        double rgb[3])
{
    if (!t || i < 0 || i >= t->n || !t->mip[i])
        return false;
    const tb_mipmap *m = t->mip[i];
    float texel[TB_TEX_MAX_CHANNELS];
    tb_tex_footprint f = {0};
    if (fp)
        f = (tb_tex_footprint){fp[0], fp[1], fp[2], fp[3]};
    tb_mipmap_lookup(m, (tb_tex_filter)filter, u, v, &f, TB_TEX_REPEAT, TB_TEX_MAX_ANISO_DEFAULT, texel);
    for (int c = 0; c < 3; c++)
        rgb[c] = texel[m->channels >= 3 ? c : 0]; /* a grey image gives one value for all three */
    return true;
}

bool tb__rt_footprint(tb_vec3 p, tb_vec3 n, tb_vec3 dpdu, tb_vec3 dpdv, const tb_vec3 rd[4], float scale,
                      float fp[4], tb_vec3 dpdxy[2])
{
    /* pbrt-v4 scales the camera ray differentials by max(1/8, 1/sqrt(spp)):
     * with more samples per pixel each one stands for a smaller area. The
     * footprint is linear in the offsets (to first order), so scaling it is
     * the same thing and keeps the offset rays exact for the plane test. */
    tb_ray_differential d;
    d.rx_o = rd[0];
    d.rx_d = rd[1];
    d.ry_o = rd[2];
    d.ry_d = rd[3];
    tb_tex_footprint f;
    tb_vec3 dx, dy;
    bool ok = tb_tex_footprint_from_rays(p, n, dpdu, dpdv, &d, &f, &dx, &dy);
    if (dpdxy) {
        dpdxy[0] = tb_vec3_scale(dx, scale);
        dpdxy[1] = tb_vec3_scale(dy, scale);
    }
    fp[0] = f.dudx * scale;
    fp[1] = f.dvdx * scale;
    fp[2] = f.dudy * scale;
    fp[3] = f.dvdy * scale;
    return ok;
}

/* raytrace.c names the default filter by value (it cannot include this header). */
_Static_assert(TB_TEX_EWA == 3 && TB_TEX_TRILINEAR == 2 && TB_TEX_BILINEAR == 1,
               "raytrace.c's TB__RT_TEX_EWA and the --texture-filter values follow tb_tex_filter");
