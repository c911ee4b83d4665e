/* Which materials the shade kernel shades (render.h): every material's
 * shading features (host/render/features.h) against the kernel's mask
 * TB_GPU_SHADE_FEATURES; a material using another feature is routed to the
 * CPU path. docs/gpu.md, "Routing by feature mask". */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "host/gpu/render_internal.h"
#include "host/render/features.h"
#include "host/render/raytrace_internal.h"
#include "host/render/texture.h"

const char *tb_gpu_route_reason(uint32_t features, uint32_t supported)
{
    uint32_t f = tb_feature_first(features & ~supported);
    /* the kernel's own words where a feature's name alone does not say why */
    switch (f) {
    case 0:
        return NULL;
    case TB_FEAT_TEXTURE_SPECTRAL:
        return "image texture in a spectral scene (the kernel has no RGB-to-spectrum upsampling)";
    case TB_FEAT_TEXTURE:
        return "image textures larger than the device's storage-buffer limit";
    case TB_FEAT_VARYING_BLACK:
        return "colour (pattern or image texture) black in some places only (the numbers a point draws would "
               "depend on it)";
    case TB_FEAT_LIT_CUSTOM:
    case TB_FEAT_LIT_SPHERE_TWO_SIDED:
        return "lit by an emitter the kernel does not sample (custom or two-sided sphere)";
    default:
        return tb_feature_name(f);
    }
}

const char *tb_gpu_renderer_material_route(const tb_gpu_renderer *r, int m)
{
    return m >= 0 && m < r->scene->nmaterials ? r->route[m] : NULL;
}

/* Floats of the MIP pyramids of all distinct images, which go into one
 * texel buffer (RGB scenes: spectral ones route textured materials). */
static size_t tb__texture_floats(const tb_gpu_renderer *r)
{
    const tb_scene *s = r->scene;
    const int nm = s->nmaterials;
    size_t n = 0;
    if (!r->rt.textures || s->spectral)
        return 0;
    for (int q = 0; q < 4 * nm; q++) {
        const tb_mipmap *t = tb__rt_texture_mip(r->rt.textures, q);
        bool seen = false;
        for (int q2 = 0; q2 < q && t && !seen; q2++)
            seen = tb__rt_texture_mip(r->rt.textures, q2) == t;
        for (int l = 0; t && !seen && l < t->nlevels; l++)
            n += (size_t)t->levels[l].width * (size_t)t->levels[l].height * (size_t)t->channels;
    }
    return n;
}

/* The kernel's flags of a material (TB_GPU_MAT_*) from its features. */
static uint8_t tb__kernel_flags(uint32_t f)
{
    uint8_t k = 0;
    if (f & TB_FEAT_DIFFUSE)
        k |= TB_GPU_MAT_DIFFUSE;
    if (f & TB_FEAT_SPECULAR)
        k |= TB_GPU_MAT_SPECULAR;
    if (f & TB_FEAT_BLINN)
        k |= TB_GPU_MAT_BLINN;
    if ((f & TB_FEAT_GGX) && (f & TB_FEAT_SPECULAR))
        k |= TB_GPU_MAT_GGX;
    if (f & TB_FEAT_TRANSMISSION)
        k |= TB_GPU_MAT_TRANSMISSION;
    if (f & TB_FEAT_EMISSION)
        k |= TB_GPU_MAT_EMITS;
    return k;
}

/* Records why material i is routed (the renderer's first one in the stats too). */
static tb_status tb__route(tb_gpu_renderer *r, int i, const char *why)
{
    const tb_material *m = &r->scene->materials[i];
    char buf[sizeof r->st.routed_reason];
    snprintf(buf, sizeof buf, "material %d%s%s%s: %s", i, m->name ? " (" : "", m->name ? m->name : "",
             m->name ? ")" : "", why);
    size_t n = strlen(buf) + 1;
    if (!(r->route[i] = malloc(n)))
        return tb_error(TB_ERR_NOMEM, "GPU render: out of memory");
    memcpy(r->route[i], buf, n);
    if (r->st.routed_materials++ == 0)
        memcpy(r->st.routed_reason, buf, sizeof buf);
    return TB_OK;
}

/* What shading material i (shaded by the kernel, features f) asks of the kernel. */
static void tb__add_uses(tb_gpu_renderer *r, int i, uint32_t f)
{
    tb__gr_uses *u = &r->uses;
    const uint8_t k = r->mflags[i];
    u->phong = u->phong || ((k & TB_GPU_MAT_SPECULAR) && !(k & TB_GPU_MAT_GGX) && r->scene->nlights > 0);
    u->mirror = u->mirror || ((k & TB_GPU_MAT_SPECULAR) && !(k & TB_GPU_MAT_TRANSMISSION) && !(k & TB_GPU_MAT_GGX));
    u->ggx = u->ggx || (k & TB_GPU_MAT_GGX);
    u->dielectric = u->dielectric || (k & TB_GPU_MAT_TRANSMISSION);
    u->emission = u->emission || (k & TB_GPU_MAT_EMITS);
    if (f & (TB_FEAT_PATTERN_CHECKER | TB_FEAT_PATTERN_NOISE | TB_FEAT_BUMP_NOISE))
        r->mpat[i] = 1;
    u->colour_pattern = u->colour_pattern || (f & (TB_FEAT_PATTERN_CHECKER | TB_FEAT_PATTERN_NOISE));
    u->bump = u->bump || (f & TB_FEAT_BUMP_NOISE);
    if (f & TB_FEAT_PATTERN_CHECKER)
        u->pattern_kinds |= 1u << TB_GPU_PATTERN_CHECKER;
    if (f & (TB_FEAT_PATTERN_NOISE | TB_FEAT_BUMP_NOISE))
        u->pattern_kinds |= 1u << TB_GPU_PATTERN_NOISE;
    if (f & TB_FEAT_TEXTURE) {
        u->texture = true;
        if (!r->mpat[i])
            r->mpat[i] = 2; /* textures only: without tangents, a lookup without footprint */
    }
}

tb_status tb__gr_route_materials(tb_gpu_renderer *r)
{
    const tb_scene *s = r->scene;
    const int nm = s->nmaterials;
    tb__gr_uses *u = &r->uses;
    for (int i = 0; i < s->nlights; i++) {
        u->ies = u->ies || s->lights[i].ies;
        u->spot = u->spot || s->lights[i].kind == TB_LIGHT_SPOT;
    }
    for (int i = 0; i < s->nemitters; i++) {
        const tb_emitter *e = &s->emitters[i];
        if (e->kind <= TB_EMITTER_SPHERE && !(e->kind == TB_EMITTER_SPHERE && e->two_sided))
            u->emitter_kinds |= 1u << e->kind;
    }
    if (!u->emitter_kinds)
        u->emitter_kinds = 1; /* no emitter: the constant only prunes code */
    /* the device's limit takes image textures off the kernel's mask */
    r->tex_floats = tb__texture_floats(r);
    uint32_t supported = TB_GPU_SHADE_FEATURES;
    if (r->tex_floats * sizeof(float) > tb_gpu_device_info_of(r->dev)->max_storage_buffer_range)
        supported &= ~(uint32_t)TB_FEAT_TEXTURE;
    tb_material_features(&r->rt, r->features);
    for (int i = 0; i < nm; i++) {
        r->mflags[i] = tb__kernel_flags(r->features[i]);
        const char *why = tb_gpu_route_reason(r->features[i], supported);
        tb_status st = why ? tb__route(r, i, why) : TB_OK;
        if (st)
            return st;
        if (!why)
            tb__add_uses(r, i, r->features[i]);
    }
    return TB_OK;
}
