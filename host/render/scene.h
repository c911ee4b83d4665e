/* Scene assembly: a MID file read with the streaming reader, one object at a
 * time, into everything a renderer needs (docs/rendering.md):
 *
 *   - the persistent objects (host/object), index = order of appearance of
 *     the top-level objects in the file, from 0;
 *   - a deduplicated material table, colours converted to the render
 *     representation (host/render/channels.h): spectral render bands if any
 *     material or light of the scene is spectral, linear RGB otherwise;
 *   - the point, spot and directional lights, and the emissive objects (area
 *     lights) with their areas and, where the shape allows, ready emitters;
 *   - the unknown MID attributes, for renderers that read their own
 *     extensions (tb_scene_object_attr and friends, below);
 *   - the camera, the world bounds, and an acceleration structure
 *     (host/render/accel.h) in which every triangle of a polygons object is a
 *     reference of its own and every other object (analytic or CSG) one.
 *
 *     tb_scene *s;
 *     if (tb_scene_load("scenes/cornell-box.mid", NULL, &s)) die(tb_last_error());
 *     tb_ray r = tb_camera_ray(&s->camera, x + 0.5, y + 0.5, 0.5f, 0.5f);
 *     tb_hit h;
 *     if (tb_scene_intersect(s, &r, &h)) {
 *         const tb_material *m = tb_scene_hit_material(s, &h);
 *         ...
 *     }
 *     tb_scene_free(s);
 *
 * The struct is public for reading; treat it as read-only once loaded. Any
 * number of threads may query a loaded scene at once. */
#ifndef TB_HOST_RENDER_SCENE_H
#define TB_HOST_RENDER_SCENE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "host/object/hit.h"
#include "host/object/object.h"
#include "host/render/accel.h"
#include "host/render/camera.h"
#include "host/render/channels.h"
#include "host/render/lights.h"
#include "host/mid/mid.h"
#include "util/base/error.h"
#include "util/color/bands.h"
#include "util/math/aabb.h"
#include "util/math/ray.h"

/* `sub` of an acceleration reference that stands for a whole object (an
 * analytic primitive or a CSG tree); polygons objects give one reference per
 * triangle, whose `sub` is the triangle's index in obj->mesh. */
#define TB_SCENE_WHOLE_OBJECT UINT32_MAX

/* How colours are represented. */
typedef enum tb_scene_color {
    TB_SCENE_COLOR_AUTO = 0, /* spectral if any material or light colour is a spectrum, else RGB */
    TB_SCENE_COLOR_RGB,      /* linear RGB; spectra are converted through XYZ (channels.h) */
    TB_SCENE_COLOR_SPECTRAL, /* render bands; RGB colours upsampled by Smits' method */
} tb_scene_color;

/* Load options; a zeroed struct (or NULL) means every default. */
typedef struct tb_scene_options {
    tb_accel_kind accel;          /* structure to build: TB_ACCEL_BVH (the default), _GRID or _LIST */
    tb_accel_options accel_opts;  /* its options (zeroed: defaults); threads 0 takes `threads` below */
    int threads;                  /* threads for building (0: OpenMP's default) */
    tb_scene_color color;         /* colour representation (default: as the scene needs) */
    const tb_bands *bands;        /* bands of a spectral scene (NULL: util/color's default 400-700 nm at 10 nm) */
    bool no_accel;                /* build no acceleration structure (tb_scene_intersect then misses) */
    size_t memory_budget;         /* bytes the scene may take (0: no budget). tb_scene_load predicts the
                                     need first (tb_scene_predict_memory) and refuses a scene over it before
                                     building anything, saying what takes the memory; every load also stops
                                     cleanly once it has taken more than the budget, or without one, 90% of
                                     the memory available when it started */
    bool no_emitters;             /* make no area-light emitters (nemitters 0, the emissive list is still
                                     made): for renderers that do not sample emitters (radiosity), so
                                     curved and CSG emitters are not tessellated */
    bool tessellated_emitters;    /* every curved primitive's emitters are the triangles of its tessellation
                                     (the former behaviour, for comparisons); default: one analytic surface
                                     emitter per primitive (docs/lights.md) */
} tb_scene_options;

/* A procedural pattern or bump map of a material (MID 1.1, docs/mid.md 7.2),
 * colours in the scene's representation. */
typedef struct tb_material_pattern {
    tb_mid_pattern_kind kind; /* TB_MID_PATTERN_NONE: none */
    bool object_space;        /* of the object-space point (else of (u, v)) */
    float scale, scale_v;     /* checks or noise cells per unit of u (or object space), of v */
    int octaves;              /* noise */
    tb_channels a, b;         /* colour patterns: checker even/odd squares, noise at 0 and 1 */
    float height;             /* bump: height of the unit value, scene units */
    const char *image;        /* bump image(): resolved path */
} tb_material_pattern;

/* One entry of the material table: a MID material (docs/mid.md, section 7)
 * with its colours in the scene's representation. */
typedef struct tb_material {
    tb_channels diffuse;      /* Lambertian reflectance */
    tb_channels specular;     /* Phong/Blinn specular reflectance */
    tb_channels transmission; /* specular transmittance */
    tb_channels emission;     /* radiant exitance M of a diffuse emitter (radiance M / pi): W/m^2 per
                                 channel in RGB, W/m^2/nm per band in a spectral scene */
    float exponent;           /* Phong/Blinn exponent */
    float ior;                /* index of refraction of the inside */
    bool emits;               /* the emission is not zero */
    const char *name;         /* the named MID material the first block using it started from, or NULL */
    const char *diffuse_texture;      /* resolved path of the image, or NULL (loaded by the texture module) */
    const char *specular_texture;     /* likewise */
    const char *transmission_texture; /* likewise */
    const char *emission_texture;     /* likewise */
    tb_mid_model model;       /* reflection model of the specular term (MID 1.1) */
    float roughness;          /* GGX alpha */
    /* The patterns, never NULL: a material without one points to the scene's
     * pattern of kind NONE (zero colours), so each is 8 bytes, not 296. */
    const tb_material_pattern *diffuse_pattern;  /* replaces `diffuse` when kind != NONE */
    const tb_material_pattern *specular_pattern; /* replaces `specular` when kind != NONE */
    const tb_material_pattern *bump;             /* perturbs the shading normal when kind != NONE */
} tb_material;

/* An emissive object: a top-level object one of whose surfaces emits. */
typedef struct tb_scene_emissive {
    uint32_t object;     /* top-level object index */
    int material;        /* material of the (first, in pre-order) emitting leaf */
    double area;         /* world-space area of its emitting surface, scene units^2, when known
                            without tessellating (polygons, a sphere under a similarity); else NaN:
                            tb_scene_emissive_area computes it (docs/rendering.md, "Emissive objects") */
    int first_emitter;   /* its emitters are emitters[first_emitter .. first_emitter + nemitters) */
    int nemitters;       /* curved and CSG objects: the triangles of their tessellation (scene_emit.c) */
} tb_scene_emissive;

/* Figures about the load (also reported through util/stats, "Scene/..."). */
typedef struct tb_scene_stats {
    uint32_t objects_by_kind[TB_PRIM_COUNT]; /* top-level objects of each kind */
    uint64_t triangles;      /* triangles of the polygons objects (one reference each) */
    size_t nprims;           /* acceleration references */
    double load_seconds;     /* wall time of reading and building the objects, lights and materials */
    double accel_seconds;    /* wall time of the acceleration structure build */
    size_t fed_files;        /* FED files read: each once, however many objects refer to it */
    size_t fed_bytes;        /* memory of those files' meshes (held once, shared by their objects) */
} tb_scene_stats;

typedef struct tb__scene_priv tb__scene_priv;

/* A loaded scene (read-only). */
typedef struct tb_scene {
    char *name;                 /* the file's name as given (or the stream name) */
    uint32_t nobjects;
    tb_object **objects;        /* objects[i] is top-level object i (MID order) */
    int nmaterials;
    tb_material *materials;     /* the deduplicated table; tb_object.material indexes it */
    bool spectral;              /* colours are band values (else linear RGB) */
    int nchannels;              /* channels of every colour: 3, or bands.n */
    tb_bands bands;             /* the render bands (meaningful when spectral) */
    int nlights;
    tb_light *lights;           /* point, spot and directional lights, in file order */
    int nemissive;
    tb_scene_emissive *emissive;/* emissive objects, in object order */
    int nemitters;
    tb_emitter *emitters;       /* area-light emitters of the emissive objects (host/render/lights.h) */
    bool has_camera;            /* the file has a camera (else `camera` is MID's default camera) */
    tb_mid_camera mid_camera;   /* the camera as the file gave it (no names, attributes or references:
                                   its unknown attributes are tb_scene_camera_attrs) */
    tb_camera camera;           /* ready to make rays, at the file's resolution */
    tb_aabb bounds;             /* world box of every object */
    tb_accel *accel;            /* NULL with no_accel. Query it through tb_scene_intersect, which
                                   completes the (u, v) and normal of hits on mesh triangles (left 0
                                   by the structure); tb_accel_occluded may be called directly */
    size_t nprims;              /* acceleration references */
    tb_accel_prim *prims;       /* those references in build order (a triangle: object, sub = its index in
                                   the object's mesh) while no structure is built over them (no_accel);
                                   NULL once one is (the structure keeps its own copy): tb_scene_refs */
    tb_scene_stats stats;
    tb__scene_priv *priv;       /* owned storage (strings, IES tables) */
} tb_scene;

/* Loads the MID file at `path` ("-": standard input). Errors: the reader's
 * "FILE:LINE:COL: error: ..." (TB_ERR_FORMAT, TB_ERR_IO), and the same form
 * for objects the object level refuses, colours that cannot be converted
 * (a spectrum file: TB_ERR_UNSUPPORTED) and unreadable IES files, located at
 * the object, material or light. *out is NULL on failure. */
tb_status tb_scene_load(const char *path, const tb_scene_options *opt, tb_scene **out);

/* Loads MID text from `fp` (not closed); `name` is used in messages and file
 * references resolve against `base_dir` (NULL: the current directory). */
tb_status tb_scene_load_stream(FILE *fp, const char *name, const char *base_dir, const tb_scene_options *opt,
                               tb_scene **out);

/* Replaces the acceleration structure by a new one of `kind` (opt NULL:
 * defaults). On failure the scene keeps its old structure. */
tb_status tb_scene_rebuild_accel(tb_scene *s, tb_accel_kind kind, const tb_accel_options *opt);

/* The s->nprims acceleration references in build order, made again from the
 * objects when the scene no longer holds them (s->prims NULL): *out is a new
 * array the caller frees (NULL when there is none). TB_ERR_NOMEM. */
tb_status tb_scene_refs(const tb_scene *s, tb_accel_prim **out);

/* The world-space area of emissive object `i` (index into s->emissive): the
 * stored one, or else computed now from two tessellations (Richardson
 * extrapolation, docs/rendering.md). TB_ERR_UNSUPPORTED for a CSG object,
 * TB_ERR_ARG for a bad index; a failed tessellation's error otherwise. */
tb_status tb_scene_emissive_area(const tb_scene *s, int i, double *area);

/* Heap bytes counted per allocation on top of the size asked for (glibc's
 * chunk header and rounding): part of every figure of tb_scene_memory. */
#define TB_SCENE_MALLOC_OVERHEAD 16

/* Where a loaded scene's memory is (bytes; docs/rendering.md, "Memory"). */
typedef struct tb_scene_memory_use {
    size_t objects;      /* objects other than polygons meshes: structs, parameters, CSG trees, names */
    size_t meshes;       /* polygons objects: their structs and triangulated meshes (corners, BVH) */
    size_t fed;          /* FED files, held once however many objects share them */
    size_t materials;    /* the material table */
    size_t emitters;     /* area-light emitters and the emissive-object list */
    size_t lights;       /* point, spot and directional lights */
    size_t prims;        /* the scene's array of acceleration references (0 once a structure is built) */
    size_t accel;        /* the acceleration structure */
    size_t total;        /* the sum */
    size_t nobjects;     /* objects counted in `objects` */
    uint64_t triangles;  /* triangles of the polygons objects */
    double per_object;   /* (objects + their references' share of prims and accel) / nobjects */
    double per_triangle; /* (meshes + the triangle references' share of prims and accel) / triangles */
} tb_scene_memory_use;

/* Fills *m with where the scene's memory is (all zero for NULL). */
void tb_scene_memory(const tb_scene *s, tb_scene_memory_use *m);

/* Predicts what loading and rendering the scene at `path` will take (the
 * same parts as tb_scene_memory, the acceleration structure at its build
 * peak, emitters with a renderer's area-light tables over them) from one
 * streaming pass over the file, which holds one object at a time. FED
 * meshes are estimated from their file sizes. The reader's errors. */
tb_status tb_scene_predict_memory(const char *path, tb_scene_memory_use *u);

/* The memory the system can give without swapping (Linux MemAvailable), in
 * bytes; 0 when unknown. */
size_t tb_scene_available_memory(void);

/* Frees the scene; NULL is allowed. */
void tb_scene_free(tb_scene *s);

/* Closest hit with ray->tmin <= t <= ray->tmax (host/object/hit.h: object
 * index, face ID, (u, v), unit outward geometric normal); false on a miss
 * (*hit untouched) and for invalid rays. BVH and grid answer bit for bit
 * alike (docs/accel.md, "Tie rule"). */
bool tb_scene_intersect(const tb_scene *s, const tb_ray *ray, tb_hit *hit);

/* tb_scene_intersect with hit->u = hit->v = 0 (the rest bit for bit the
 * same): for renderers whose materials read no (u, v) (no texture, pattern
 * or bump map), which so skip computing them for every candidate hit. */
bool tb_scene_intersect_no_uv(const tb_scene *s, const tb_ray *ray, tb_hit *hit);

/* True if anything is hit with ray->tmin <= t <= ray->tmax. */
bool tb_scene_occluded(const tb_scene *s, const tb_ray *ray);

/* tb_scene_occluded with top-level object `object` left out (UINT32_MAX:
 * none): for a shadow ray to a point sampled on a convex emitter, which
 * cannot block the segment to its own visible side. */
bool tb_scene_occluded_except(const tb_scene *s, const tb_ray *ray, uint32_t object);

/* The primitive (CSG leaf, or the object itself) a hit is on, and the face
 * ID within it (*local, may be NULL); NULL for a hit not from this scene. */
const tb_object *tb_scene_hit_leaf(const tb_scene *s, const tb_hit *hit, uint32_t *local);

/* The material of the surface a hit is on; NULL for a hit not from this scene. */
const tb_material *tb_scene_hit_material(const tb_scene *s, const tb_hit *hit);

/* ------------------------------------------------------------------ unknown attributes */

/* Attributes for renderers (docs/rendering.md): the MID attributes this
 * library does not know, kept with their values so that a renderer can read
 * its own extensions, e.g. `my_renderer_weight = 2.5` in an object body.
 * They are deep copies owned by the scene (valid until tb_scene_free), in
 * file order, and stored in side tables: an object without any costs no
 * memory. Material attributes are the effective ones of the block that made
 * the material: those of the named material it starts from (or, in a CSG
 * tree, of its parent's material), then its own, its own replacing
 * same-named ones; two blocks whose unknown attributes differ give two
 * entries of the material table. The lookups return NULL (the runs {NULL, 0})
 * for a name, index or node that has none. */

/* The unknown attributes of object node `node` (a top-level object or any
 * node of its CSG tree, e.g. from tb_scene_hit_leaf): of its body, or with
 * `geometry` of its geometry block. */
tb_mid_attrs tb_scene_node_attrs(const tb_scene *s, const tb_object *node, bool geometry);

/* The unknown attributes of material-table entry `material`. */
tb_mid_attrs tb_scene_material_attrs(const tb_scene *s, int material);

/* The unknown attributes of light `light` (index into s->lights). */
tb_mid_attrs tb_scene_light_attrs(const tb_scene *s, int light);

/* The unknown attributes of the camera. */
tb_mid_attrs tb_scene_camera_attrs(const tb_scene *s);

/* The value of attribute `name` in `attrs`, or NULL. */
const tb_mid_value *tb_scene_attr_find(tb_mid_attrs attrs, const char *name);

/* Unknown attribute `name` of a node: its body first, then its geometry block. */
const tb_mid_value *tb_scene_node_attr(const tb_scene *s, const tb_object *node, const char *name);

/* Unknown attribute `name` of top-level object `object` (body, then geometry block). */
const tb_mid_value *tb_scene_object_attr(const tb_scene *s, uint32_t object, const char *name);

/* Unknown attribute `name` of material-table entry `material`. */
const tb_mid_value *tb_scene_material_attr(const tb_scene *s, int material, const char *name);

/* Unknown attribute `name` of light `light`. */
const tb_mid_value *tb_scene_light_attr(const tb_scene *s, int light, const char *name);

/* Unknown attribute `name` of the camera. */
const tb_mid_value *tb_scene_camera_attr(const tb_scene *s, const char *name);

/* Attribute `name` inside a block value `{ name = ... }`; NULL if `block`
 * is NULL, not a block, or has no such attribute. */
const tb_mid_value *tb_scene_attr_field(const tb_mid_value *block, const char *name);

/* v's number, or `def` when v is NULL or not a number. */
double tb_scene_attr_number(const tb_mid_value *v, double def);

/* v's text when it is a string or a symbol (`true`, `fast`), else `def`. */
const char *tb_scene_attr_string(const tb_mid_value *v, const char *def);

/* v's n numbers when it is a vector of exactly n > 0 numbers, else `def`. */
const double *tb_scene_attr_vector(const tb_mid_value *v, int n, const double *def);

/* Prints a short summary (objects by kind, triangles, materials, colours,
 * lights, emitters, camera, bounds, acceleration structure, times). */
void tb_scene_print_summary(const tb_scene *s, FILE *out);

#endif
