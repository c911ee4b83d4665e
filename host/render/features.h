/* Shading features: what shading a material's hits uses, as bit flags
 * (docs/architecture.md, "Adding a material feature"). The CPU tracer
 * (raytrace.h) implements every feature; a renderer that implements only
 * some (the Vulkan shade kernel, host/gpu/render.h) declares the mask of
 * those it does and hands every material using another to the CPU tracer.
 *
 *     uint32_t *f = malloc(scene->nmaterials * sizeof *f);
 *     tb_material_features(&rt, f);
 *     if (f[m] & ~supported) ... route material m ...
 *
 * TB_FEATURES lists them in report order: a renderer that does not support
 * several features of a material names the first one in this order. */
#ifndef TB_HOST_RENDER_FEATURES_H
#define TB_HOST_RENDER_FEATURES_H

#include <stdint.h>

#include "host/render/raytrace.h"

/* X(NAME, phrase): every feature; its bit is TB_FEAT_NAME. */
#define TB_FEATURES(X)                                                                                         \
    X(TEXTURE_SPECTRAL, "image texture in a spectral scene")                                                   \
    X(TEXTURE, "image texture")                                                                                \
    X(PATTERN_OTHER, "procedural pattern of an unknown kind")                                                  \
    X(VARYING_BLACK, "colour (pattern or image texture) black in some places only")                            \
    X(BUMP_IMAGE, "bump map from an image")                                                                    \
    X(BUMP_OTHER, "bump map of an unknown kind")                                                               \
    X(MODEL_OTHER, "reflection model of an unknown kind")                                                      \
    X(LIT_CUSTOM, "lit by a custom emitter")                                                                   \
    X(LIT_SPHERE_TWO_SIDED, "lit by a two-sided sphere emitter")                                               \
    X(DIFFUSE, "diffuse colour (not black)")                                                                   \
    X(SPECULAR, "specular colour (not black, model not Lambert)")                                              \
    X(TRANSMISSION, "transmission colour (not black): refraction")                                             \
    X(EMISSION, "emission")                                                                                    \
    X(BLINN, "Blinn-Phong model")                                                                              \
    X(GGX, "GGX model")                                                                                        \
    X(PATTERN_CHECKER, "checker pattern")                                                                      \
    X(PATTERN_NOISE, "noise pattern")                                                                          \
    X(BUMP_NOISE, "bump map from noise")                                                                       \
    X(LIT_TRIANGLE, "lit by a triangle emitter")                                                               \
    X(LIT_PARALLELOGRAM, "lit by a parallelogram emitter")                                                     \
    X(LIT_DISC, "lit by a disc emitter")                                                                       \
    X(LIT_SPHERE, "lit by a sphere emitter")

/* Bit positions (private: use the TB_FEAT_* masks). */
enum {
#define TB__FEATURE_INDEX(name, phrase) TB__FEAT_INDEX_##name,
    TB_FEATURES(TB__FEATURE_INDEX)
#undef TB__FEATURE_INDEX
    TB_FEAT_COUNT /* number of features */
};

/* One bit per feature (a mask is a uint32_t). */
typedef enum tb_feature {
#define TB__FEATURE_BIT(name, phrase) TB_FEAT_##name = 1 << TB__FEAT_INDEX_##name,
    TB_FEATURES(TB__FEATURE_BIT)
#undef TB__FEATURE_BIT
} tb_feature;

_Static_assert(TB_FEAT_COUNT <= 31, "tb_feature bits must fit an int enum constant");

/* Every feature bit. */
#define TB_FEAT_ALL ((uint32_t)((1u << TB_FEAT_COUNT) - 1u))

/* The phrase of feature bit `f` (one bit set), or NULL for anything else. */
const char *tb_feature_name(uint32_t f);

/* The first feature of `mask` in TB_FEATURES order (0 if none). */
uint32_t tb_feature_first(uint32_t mask);

/* The features of every material of rt's scene into out[0 .. nmaterials):
 * colours as the tracer sees them (black-ness through patterns and
 * textures), model, patterns, bump map, textures (a Lambert material's
 * specular ones ignored), and for a material that samples the area lights
 * (diffuse, or GGX with a specular colour) the kinds of the scene's
 * emitters. */
void tb_material_features(const tb_raytracer *rt, uint32_t *out);

#endif
