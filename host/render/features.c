/* Shading features of materials and geometry features of objects (features.h). */
#include "host/render/features.h"

#include <stdbool.h>
#include <stddef.h>

#include "host/render/raytrace_internal.h"
#include "host/render/texture.h"

const char *tb_feature_name(uint32_t f)
{
    switch (f) {
#define TB__FEATURE_CASE(name, phrase)                                                                         \
    case (uint32_t)TB_FEAT_##name:                                                                             \
        return phrase;
        TB_FEATURES(TB__FEATURE_CASE)
#undef TB__FEATURE_CASE
    default:
        return NULL;
    }
}

uint32_t tb_feature_first(uint32_t mask)
{
    /* list order is bit order */
    return mask & (~mask + 1u);
}

/* Bit c (c < 3) set if channel c of the image (its only channel if grey)
 * is positive in every texel of every level: then so is every filtered
 * value (nearest, bilinear, trilinear and EWA weights are convex). */
static unsigned tb__texture_positive(const tb_mipmap *t)
{
    unsigned pos = 7;
    for (int l = 0; l < t->nlevels && pos; l++) {
        size_t n = (size_t)t->levels[l].width * (size_t)t->levels[l].height;
        for (size_t x = 0; x < n && pos; x++)
            for (int c = 0; c < 3; c++)
                if (!(t->levels[l].texels[x * (size_t)t->channels + (size_t)(t->channels >= 3 ? c : 0)] > 0.0f))
                    pos &= ~(1u << c);
    }
    return pos;
}

/* Whether colour slot k (0 diffuse, 1 specular, 2 transmission) of a
 * material is black at a hit, after its pattern (a + f (b - a), f in
 * [0, 1]) and its texture `tex` (NULL: none): 0 everywhere, 1 nowhere, -1
 * in some places only. The tracer draws light samples, and spawns mirror,
 * glossy and refracted rays, only for non-black colours, so the last case
 * makes the numbers a point draws depend on the hit. */
static int tb__colour_class(const tb_material *m, int k, const tb_mipmap *tex)
{
    const tb_channels *base = k == 0 ? &m->diffuse : k == 1 ? &m->specular : &m->transmission;
    const tb_material_pattern *p = k == 0 ? m->diffuse_pattern : k == 1 ? m->specular_pattern : NULL;
    bool black = true, positive = false;
    unsigned pos = 0; /* channels < 3 positive everywhere */
    for (int c = 0; c < base->n; c++) {
        bool pc = p && p->kind ? p->a.v[c] > 0.0f && p->b.v[c] > 0.0f : base->v[c] > 0.0f;
        black = black && (p && p->kind ? p->a.v[c] == 0.0f && p->b.v[c] == 0.0f : base->v[c] == 0.0f);
        positive = positive || pc;
        if (pc && c < 3)
            pos |= 1u << c;
    }
    if (black)
        return 0;
    if (tex)
        return pos & tb__texture_positive(tex) ? 1 : -1;
    if (p && p->kind)
        return positive ? 1 : -1;
    return 1; /* a constant, not black */
}

/* The feature of a colour pattern's kind. */
static uint32_t tb__pattern_feature(tb_mid_pattern_kind k)
{
    return k == TB_MID_PATTERN_NONE      ? 0u
           : k == TB_MID_PATTERN_CHECKER ? (uint32_t)TB_FEAT_PATTERN_CHECKER
           : k == TB_MID_PATTERN_NOISE   ? (uint32_t)TB_FEAT_PATTERN_NOISE
                                         : (uint32_t)TB_FEAT_PATTERN_OTHER;
}

/* The feature of a bump map's kind. */
static uint32_t tb__bump_feature(tb_mid_pattern_kind k)
{
    return k == TB_MID_PATTERN_NONE    ? 0u
           : k == TB_MID_PATTERN_NOISE ? (uint32_t)TB_FEAT_BUMP_NOISE
           : k == TB_MID_PATTERN_IMAGE ? (uint32_t)TB_FEAT_BUMP_IMAGE
                                       : (uint32_t)TB_FEAT_BUMP_OTHER;
}

/* The LIT_* features of the scene's emitters: what sampling its area lights takes. */
static uint32_t tb__emitter_features(const tb_scene *s)
{
    uint32_t f = 0;
    for (int i = 0; i < s->nemitters; i++) {
        const tb_emitter *e = &s->emitters[i];
        switch (e->kind) {
        case TB_EMITTER_TRIANGLE: f |= TB_FEAT_LIT_TRIANGLE; break;
        case TB_EMITTER_PARALLELOGRAM: f |= TB_FEAT_LIT_PARALLELOGRAM; break;
        case TB_EMITTER_DISC: f |= TB_FEAT_LIT_DISC; break;
        case TB_EMITTER_SPHERE: f |= e->two_sided ? TB_FEAT_LIT_SPHERE_TWO_SIDED : TB_FEAT_LIT_SPHERE; break;
        default: f |= TB_FEAT_LIT_CUSTOM; break;
        }
    }
    return f;
}

void tb_material_features(const tb_raytracer *rt, uint32_t *out)
{
    const tb_scene *s = rt->scene;
    const int nm = s->nmaterials;
    const uint32_t lit = tb__emitter_features(s);
    for (int i = 0; i < nm; i++) {
        const tb_material *m = &s->materials[i];
        const bool lambert = m->model == TB_MID_MODEL_LAMBERT;
        uint32_t f = 0;
        /* textures: diffuse, specular, transmission, emission (raytrace.c's
         * slots); a Lambert material's specular one is ignored */
        const tb_mipmap *tex[4];
        for (int k = 0; k < 4; k++) {
            tex[k] = k == 1 && lambert ? NULL : tb__rt_texture_mip(rt->textures, k * nm + i);
            if (tex[k])
                f |= TB_FEAT_TEXTURE | (s->spectral ? TB_FEAT_TEXTURE_SPECTRAL : 0u);
        }
        int dcls = tb__colour_class(m, 0, tex[0]), scls = lambert ? 0 : tb__colour_class(m, 1, tex[1]);
        int tcls = tb__colour_class(m, 2, tex[2]);
        if (dcls < 0 || scls < 0 || tcls < 0)
            f |= TB_FEAT_VARYING_BLACK;
        f |= dcls == 1 ? (uint32_t)TB_FEAT_DIFFUSE : 0u;
        f |= scls == 1 ? (uint32_t)TB_FEAT_SPECULAR : 0u;
        f |= tcls == 1 ? (uint32_t)TB_FEAT_TRANSMISSION : 0u;
        f |= m->emits ? (uint32_t)TB_FEAT_EMISSION : 0u;
        switch (m->model) {
        case TB_MID_MODEL_PHONG: case TB_MID_MODEL_LAMBERT: break;
        case TB_MID_MODEL_BLINN: f |= TB_FEAT_BLINN; break;
        case TB_MID_MODEL_GGX: f |= TB_FEAT_GGX; break;
        default: f |= TB_FEAT_MODEL_OTHER; break;
        }
        f |= tb__pattern_feature(m->diffuse_pattern->kind);
        f |= lambert ? 0u : tb__pattern_feature(m->specular_pattern->kind);
        f |= tb__bump_feature(m->bump->kind);
        /* the area-light samples: the diffuse term's, and the GGX lobe's */
        if ((f & TB_FEAT_DIFFUSE) || ((f & TB_FEAT_GGX) && (f & TB_FEAT_SPECULAR)))
            f |= lit;
        out[i] = f;
    }
}

const char *tb_object_feature_name(uint32_t f)
{
    switch (f) {
#define TB__OBJECT_FEATURE_CASE(name, phrase)                                                                  \
    case (uint32_t)TB_OBJ_FEAT_##name:                                                                         \
        return phrase;
        TB_OBJECT_FEATURES(TB__OBJECT_FEATURE_CASE)
#undef TB__OBJECT_FEATURE_CASE
    default:
        return NULL;
    }
}

/* The features of object node `o`: its kind's bit, and a CSG node's
 * children's. A switch over the closed set with no default, so a new
 * primitive kind fails to compile here (-Wswitch) until it has a bit. */
static uint32_t tb__node_features(const tb_object *o)
{
    uint32_t f = 0;
    switch (o->kind) {
    case TB_PRIM_SPHERE: f = TB_OBJ_FEAT_SPHERE; break;
    case TB_PRIM_CUBE: f = TB_OBJ_FEAT_CUBE; break;
    case TB_PRIM_CYLINDER: f = TB_OBJ_FEAT_CYLINDER; break;
    case TB_PRIM_CONE: f = TB_OBJ_FEAT_CONE; break;
    case TB_PRIM_PYRAMID: f = TB_OBJ_FEAT_PYRAMID; break;
    case TB_PRIM_PRISM: f = TB_OBJ_FEAT_PRISM; break;
    case TB_PRIM_TORUS: f = TB_OBJ_FEAT_TORUS; break;
    /* the scene references a meshed polygons object per triangle, another whole (scene.c) */
    case TB_PRIM_POLYGONS: f = o->mesh ? TB_OBJ_FEAT_TRIANGLES : TB_OBJ_FEAT_POLYGONS_UNMESHED; break;
    case TB_PRIM_CONIC: f = TB_OBJ_FEAT_CONIC; break;
    case TB_PRIM_SQUARE_ARCH: f = TB_OBJ_FEAT_SQUARE_ARCH; break;
    case TB_PRIM_ROUND_ARCH: f = TB_OBJ_FEAT_ROUND_ARCH; break;
    case TB_PRIM_UNION: f = TB_OBJ_FEAT_CSG_UNION; break;
    case TB_PRIM_INTERSECTION: f = TB_OBJ_FEAT_CSG_INTERSECTION; break;
    case TB_PRIM_DIFFERENCE: f = TB_OBJ_FEAT_CSG_DIFFERENCE; break;
    }
    for (int i = 0; i < o->nchildren; i++)
        f |= tb__node_features(&o->children[i]);
    return f;
}

void tb_object_features(const tb_scene *s, uint32_t *out)
{
    for (uint32_t i = 0; i < s->nobjects; i++)
        out[i] = tb__node_features(s->objects[i]);
}
