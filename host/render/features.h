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

/* The first feature of `mask` in TB_FEATURES order (0 if none); the same
 * for a mask of object features in TB_OBJECT_FEATURES order. */
uint32_t tb_feature_first(uint32_t mask);

/* The features of every material of rt's scene into out[0 .. nmaterials):
 * colours as the tracer sees them (black-ness through patterns and
 * textures), model, patterns, bump map, textures (a Lambert material's
 * specular ones ignored), and for a material that samples the area lights
 * (diffuse, or GGX with a specular colour) the kinds of the scene's
 * emitters. */
void tb_material_features(const tb_raytracer *rt, uint32_t *out);

/* Object features: what geometry intersecting a top-level object takes, as
 * bit flags (docs/architecture.md, "Adding a primitive kind"). The CPU path
 * (tb_object_intersect) intersects every one; the Vulkan intersect kernel
 * declares the mask of those it does (host/gpu/intersect.h) and hands every
 * object with another to the CPU path.
 *
 *     uint32_t *f = malloc(scene->nobjects * sizeof *f);
 *     tb_object_features(scene, f);
 *     if (f[i] & ~supported) ... route object i ...
 *
 * TB_OBJECT_FEATURES lists them in report order: the CSG operations first,
 * so a CSG tree is reported as one whatever its leaves. */

/* X(NAME, phrase): every object feature; its bit is TB_OBJ_FEAT_NAME. */
#define TB_OBJECT_FEATURES(X)                                                                                  \
    X(CSG_UNION, "CSG union")                                                                                  \
    X(CSG_INTERSECTION, "CSG intersection")                                                                    \
    X(CSG_DIFFERENCE, "CSG difference")                                                                        \
    X(POLYGONS_UNMESHED, "polygons without a triangle mesh")                                                   \
    X(TRIANGLES, "triangles of a polygons mesh")                                                               \
    X(SPHERE, "sphere")                                                                                        \
    X(CUBE, "cube")                                                                                            \
    X(CYLINDER, "cylinder")                                                                                    \
    X(CONE, "cone")                                                                                            \
    X(CONIC, "conic")                                                                                          \
    X(PYRAMID, "pyramid")                                                                                      \
    X(PRISM, "prism")                                                                                          \
    X(TORUS, "torus")                                                                                          \
    X(SQUARE_ARCH, "square arch")                                                                              \
    X(ROUND_ARCH, "round arch")

/* Bit positions (private: use the TB_OBJ_FEAT_* masks). */
enum {
#define TB__OBJECT_FEATURE_INDEX(name, phrase) TB__OBJ_FEAT_INDEX_##name,
    TB_OBJECT_FEATURES(TB__OBJECT_FEATURE_INDEX)
#undef TB__OBJECT_FEATURE_INDEX
    TB_OBJ_FEAT_COUNT /* number of object features */
};

/* One bit per object feature (a mask is a uint32_t). */
typedef enum tb_object_feature {
#define TB__OBJECT_FEATURE_BIT(name, phrase) TB_OBJ_FEAT_##name = 1 << TB__OBJ_FEAT_INDEX_##name,
    TB_OBJECT_FEATURES(TB__OBJECT_FEATURE_BIT)
#undef TB__OBJECT_FEATURE_BIT
} tb_object_feature;

_Static_assert(TB_OBJ_FEAT_COUNT <= 31, "tb_object_feature bits must fit an int enum constant");

/* Every object feature bit. */
#define TB_OBJ_FEAT_ALL ((uint32_t)((1u << TB_OBJ_FEAT_COUNT) - 1u))

/* The phrase of object feature bit `f` (one bit set), or NULL for anything else. */
const char *tb_object_feature_name(uint32_t f);

/* The features of every top-level object of scene `s` into out[0 ..
 * nobjects): the bit of its primitive kind (a polygons object: TRIANGLES,
 * or POLYGONS_UNMESHED if it has no triangle mesh, which the scene then
 * references whole), and for a CSG tree the bits of its operations and of
 * all its leaves. */
void tb_object_features(const tb_scene *s, uint32_t *out);

#endif
