/* The ray tracer's diffuse textures (raytrace.h). A file of its own from
 * when host/render/texture.h and camera.h (through scene.h) both defined
 * tb_ray_differential and could not be included together. */
#include <stdbool.h>
#include <stdlib.h>

#include "host/render/texture.h"
#include "util/base/error.h"

/* The private declarations of raytrace.h, repeated here (see above); keep
 * them identical. */
typedef struct tb__rt_textures tb__rt_textures;
tb_status tb__rt_textures_load(int n, const char *const *paths, tb__rt_textures **out);
void tb__rt_textures_free(tb__rt_textures *t);
bool tb__rt_texture_rgb(const tb__rt_textures *t, int i, float u, float v, double rgb[3]);

struct tb__rt_textures {
    tb_texture_cache *cache;
    int n;
    const tb_mipmap **mip; /* per material: its diffuse texture, or NULL */
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

bool tb__rt_texture_rgb(const tb__rt_textures *t, int i, float u, float v, double rgb[3])
{
    if (!t || i < 0 || i >= t->n || !t->mip[i])
        return false;
    const tb_mipmap *m = t->mip[i];
    float texel[TB_TEX_MAX_CHANNELS];
    tb_mipmap_bilinear(m, 0, u, v, TB_TEX_REPEAT, texel);
    for (int c = 0; c < 3; c++)
        rgb[c] = texel[m->channels >= 3 ? c : 0]; /* a grey image gives one value for all three */
    return true;
}
