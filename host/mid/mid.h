/* The MID object model: what the reader hands out one item at a time and what
 * the writer writes (docs/mid.md is the format's specification).
 *
 * The set of primitive kinds is closed (enum tb_prim_kind) and each kind with
 * parameters has a small typed struct in the tb_mid_geometry union, so the
 * object level (host/object) switches over kinds instead of looking up
 * attributes by name. Everything else a file says is kept too: unknown
 * attributes as value trees, the transform as the operations written, and
 * which material attributes an object set itself, so the writer can give back
 * an equal file.
 *
 * All pointers in these structs point into memory owned by whoever built the
 * item (the reader's arenas); plain structs, no ownership inside. */
#ifndef TB_HOST_SCENE_MID_H
#define TB_HOST_SCENE_MID_H

#include <stdbool.h>
#include <stdint.h>

#include "util/base/error.h"
#include "util/math/transform.h"
#include "util/math/vec.h"

/* The MID version this code reads and writes (docs/mid.md, section 4). */
#define TB_MID_VERSION_MAJOR 1
#define TB_MID_VERSION_MINOR 1

/* Nesting limit for bodies, blocks, lists and calls together. */
#define TB_MID_MAX_DEPTH 64

/* Longest token, in bytes. */
#define TB_MID_MAX_TOKEN 65535

/* ------------------------------------------------------------ primitive kinds */

/* The closed set of geometric object kinds: primitives, then CSG nodes. */
typedef enum tb_prim_kind {
    TB_PRIM_SPHERE = 0,   /* unit sphere at the origin */
    TB_PRIM_CUBE,         /* [-1,1]^3 */
    TB_PRIM_CYLINDER,     /* radius 1 about z, z in [-1,1] */
    TB_PRIM_CONE,         /* base radius 1 at z=-1, apex or top disc at z=1 */
    TB_PRIM_PYRAMID,      /* base [-1,1]^2 at z=-1, apex or top square at z=1 */
    TB_PRIM_PRISM,        /* n-gon or profile extruded over z in [-1,1] */
    TB_PRIM_TORUS,        /* about z, major and minor radius */
    TB_PRIM_POLYGONS,     /* inline polygons or a FED mesh */
    TB_PRIM_CONIC,        /* r^2 = c0 + c1 z + c2 z^2 revolved about z */
    TB_PRIM_SQUARE_ARCH,  /* [-1,1]^3 with a rectangular opening along y */
    TB_PRIM_ROUND_ARCH,   /* [-1,1]^3 with a round-topped opening along y */
    TB_PRIM_UNION,        /* CSG: any child */
    TB_PRIM_INTERSECTION, /* CSG: every child */
    TB_PRIM_DIFFERENCE,   /* CSG: first child minus the others */
} tb_prim_kind;

/* Number of primitive kinds (TB_PRIM_SPHERE .. TB_PRIM_DIFFERENCE). */
#define TB_PRIM_COUNT 14

/* The MID keyword of a kind ("sphere", "square_arch", ...); "?" if out of range. */
const char *tb_prim_kind_name(tb_prim_kind k);

/* True for union, intersection and difference. */
static inline bool tb_prim_is_csg(tb_prim_kind k)
{
    return k == TB_PRIM_UNION || k == TB_PRIM_INTERSECTION || k == TB_PRIM_DIFFERENCE;
}

/* --------------------------------------------------------------- basic parts */

/* A position in the MID text: line and byte column, both from 1 (long: a
 * multi-gigabyte file may have more than 2^31 lines). */
typedef struct tb_mid_loc {
    long line, col;
} tb_mid_loc;

/* A data block stored outside the MID file: file("..."). */
typedef struct tb_mid_ref {
    const char *text; /* as written in the file; NULL means "no reference" */
    const char *path; /* resolved: absolute, or relative to the current directory */
} tb_mid_ref;

/* Types of a generic value (docs/mid.md, section 3). */
typedef enum tb_mid_value_type {
    TB_MID_NUMBER = 0, /* a number */
    TB_MID_STRING,     /* "text" */
    TB_MID_SYMBOL,     /* a bare identifier: true, false, ... */
    TB_MID_VECTOR,     /* [n1 n2 ...]: a list whose elements are all numbers (also []) */
    TB_MID_LIST,       /* [v1 v2 ...]: any other list */
    TB_MID_CALL,       /* name(v1 v2 ...) */
    TB_MID_BLOCK,      /* { name = value ... } */
    TB_MID_FILE,       /* file("path") */
} tb_mid_value_type;

typedef struct tb_mid_value tb_mid_value;
typedef struct tb_mid_attr tb_mid_attr;

/* One value of the generic syntax tree (how unknown attributes are kept). */
struct tb_mid_value {
    tb_mid_value_type type;
    int count;      /* VECTOR: numbers; LIST, CALL: items; BLOCK: attributes */
    tb_mid_loc loc; /* where the value starts */
    union {
        double number;              /* NUMBER */
        const char *text;           /* STRING, SYMBOL (UTF-8, unescaped) */
        const double *numbers;      /* VECTOR */
        const tb_mid_value *items;  /* LIST elements, CALL arguments */
        const tb_mid_attr *attrs;   /* BLOCK, in file order */
        tb_mid_ref ref;             /* FILE */
    };
    const char *name; /* CALL: the function name; NULL otherwise */
};

/* `name = value`. */
struct tb_mid_attr {
    const char *name;
    tb_mid_value value;
    tb_mid_loc loc; /* of the name */
};

/* A run of attributes (unknown ones kept by the reader), in file order. */
typedef struct tb_mid_attrs {
    const tb_mid_attr *items;
    int count;
} tb_mid_attrs;

/* ---------------------------------------------------------------- transforms */

/* The transform operations (docs/mid.md, 6.1). */
typedef enum tb_mid_op_kind {
    TB_MID_TRANSLATE = 0, /* v[0..2] = offset */
    TB_MID_SCALE,         /* v[0..2] = factors (equal for scale(s)) */
    TB_MID_ROTATE,        /* v[0..2] = axis, v[3] = degrees */
    TB_MID_MATRIX,        /* v[0..15] = rows in reading order, affine */
} tb_mid_op_kind;

/* One transform operation as written. */
typedef struct tb_mid_op {
    tb_mid_op_kind kind;
    double v[16];
} tb_mid_op;

/* The transform of ops[0..n) applied in order (ops[0] first): M = Mn ... M1.
 * TB_ERR_ARG / TB_ERR_NUMERIC with a message if an operation is not
 * invertible (zero scale or axis, non-affine, singular or ill-conditioned
 * matrix) or the product overflows; *bad (unless NULL) is then the index of
 * the failing operation, or n for an overflowing product. */
tb_status tb_mid_ops_transform(const tb_mid_op *ops, int n, tb_transform *out, int *bad);

/* ------------------------------------------------------------------ geometry */

/* cylinder. */
typedef struct tb_geom_cylinder {
    bool caps; /* discs at z = -1 and z = 1 */
} tb_geom_cylinder;

/* cone: radius 1 at z = -1 to top_radius at z = 1. */
typedef struct tb_geom_cone {
    double top_radius; /* 0: a pointed cone */
    bool caps;         /* base disc, and top disc when top_radius > 0 */
} tb_geom_cone;

/* pyramid: [-1,1]^2 at z = -1 to [-top,top]^2 at z = 1. */
typedef struct tb_geom_pyramid {
    double top; /* 0: apex at (0,0,1) */
    bool caps;  /* base square, and top square when top > 0 */
} tb_geom_pyramid;

/* prism: a regular n-gon or a profile polygon extruded over z in [-1,1]. */
typedef struct tb_geom_prism {
    int sides;             /* regular polygon with this many sides; 0 when a profile is given */
    int nprofile;          /* profile points (0 with `sides`) */
    const tb_vec2 *profile; /* profile polygon in the xy plane, either orientation */
    bool caps;             /* end polygons at z = -1 and z = 1 */
} tb_geom_prism;

/* torus about z. */
typedef struct tb_geom_torus {
    double major; /* radius of the centre circle */
    double minor; /* radius of the tube, 0 < minor < major */
} tb_geom_torus;

/* polygons: inline faces over a vertex array, or a FED mesh (mesh.text != NULL). */
typedef struct tb_geom_polygons {
    int nvertices;
    const tb_vec3 *vertices;
    const tb_vec3 *normals;  /* one per vertex, or NULL */
    const tb_vec2 *uvs;      /* one per vertex, or NULL */
    int nfaces;
    const int *face_start;   /* face f uses indices[face_start[f] .. face_start[f+1]) */
    const int *indices;      /* 0-based vertex indices, counter-clockwise seen from the front */
    tb_mid_ref mesh;         /* FED file; text == NULL for inline polygons */
} tb_geom_polygons;

/* conic: r^2 = c[0] + c[1] z + c[2] z^2 revolved about z, z in [z0, z1]. */
typedef struct tb_geom_conic {
    double c[3];
    double z0, z1;
    bool caps; /* discs at z0 and z1 where r > 0 */
} tb_geom_conic;

/* square_arch and round_arch: opening of width w and height h through [-1,1]^3 along y. */
typedef struct tb_geom_arch {
    double width;  /* full width of the opening, 0 < w < 2 */
    double height; /* from z = -1 to the top of the opening */
} tb_geom_arch;

/* Parameters of a primitive, tagged by tb_mid_object.kind (sphere, cube and
 * the CSG nodes have none). */
typedef union tb_mid_geometry {
    tb_geom_cylinder cylinder;
    tb_geom_cone cone;
    tb_geom_pyramid pyramid;
    tb_geom_prism prism;
    tb_geom_torus torus;
    tb_geom_polygons polygons;
    tb_geom_conic conic;
    tb_geom_arch arch; /* square_arch and round_arch */
} tb_mid_geometry;

/* The default geometry of kind `k` (docs/mid.md, 6.3). Polygons and a prism
 * with a profile have no meaningful default (zero counts). */
tb_mid_geometry tb_mid_geometry_default(tb_prim_kind k);

/* ------------------------------------------------------------------ materials */

/* How a colour is given. */
typedef enum tb_mid_color_type {
    TB_MID_COLOR_RGB = 0,       /* linear RGB, sRGB primaries */
    TB_MID_COLOR_SPECTRUM,      /* inline samples */
    TB_MID_COLOR_SPECTRUM_FILE, /* spectrum(file("...")) */
} tb_mid_color_type;

/* A colour or spectrum (docs/mid.md, 7.1). */
typedef struct tb_mid_color {
    tb_mid_color_type type;
    float rgb[3];         /* RGB (a grey value fills all three) */
    int nsamples;         /* SPECTRUM: >= 2 */
    const float *nm;      /* SPECTRUM: wavelengths in nm, strictly increasing */
    const float *values;  /* SPECTRUM: one per wavelength */
    tb_mid_ref file;      /* SPECTRUM_FILE */
} tb_mid_color;

/* The grey colour (v, v, v). */
tb_mid_color tb_mid_color_grey(float v);

/* The reflection model of a material's specular term (MID 1.1 `model`). */
typedef enum tb_mid_model {
    TB_MID_MODEL_PHONG = 0, /* normalised Phong highlight + mirror ray (MID 1.0's meaning; the default) */
    TB_MID_MODEL_BLINN,     /* exactly normalised Blinn-Phong highlight + mirror ray */
    TB_MID_MODEL_LAMBERT,   /* diffuse only: specular, exponent and the specular texture are ignored */
    TB_MID_MODEL_GGX,       /* GGX microfacet lobe: F0 = specular (Schlick), alpha = roughness */
} tb_mid_model;

/* Number of tb_mid_model values. */
#define TB_MID_MODEL_COUNT 4

/* The MID symbol of a model ("phong", ...); "?" if out of range. */
const char *tb_mid_model_name(tb_mid_model m);

/* Kinds of procedural patterns and bump maps (MID 1.1, docs/mid.md 7.2). */
typedef enum tb_mid_pattern_kind {
    TB_MID_PATTERN_NONE = 0, /* no pattern */
    TB_MID_PATTERN_CHECKER,  /* checker(scale, a, b [, space]) */
    TB_MID_PATTERN_NOISE,    /* noise(scale, octaves, a, b [, space]); bump: noise(scale, octaves, height [, space]) */
    TB_MID_PATTERN_IMAGE,    /* bump only: image(file("..."), height) */
} tb_mid_pattern_kind;

/* A procedural colour pattern (diffuse_pattern, specular_pattern) or a bump
 * map (bump). */
typedef struct tb_mid_pattern {
    tb_mid_pattern_kind kind;
    bool object_space;   /* of the object-space point (symbol `object`), else of (u, v) (`uv`, the default) */
    double scale;        /* checks or noise cells per unit of u (or of object space), > 0 */
    double scale_v;      /* per unit of v: equal to scale unless written [su sv] (uv space only) */
    int octaves;         /* noise: 1 .. 16 */
    tb_mid_color a, b;   /* colour patterns: checker even/odd squares; noise value at 0 and 1 */
    double height;       /* bump: height of the unit value in scene units (may be negative) */
    tb_mid_ref image;    /* bump image() */
} tb_mid_pattern;

/* Bits of tb_mid_material.set: the attributes a rendering block wrote itself. */
enum {
    TB_MID_SET_DIFFUSE = 1u << 0,
    TB_MID_SET_SPECULAR = 1u << 1,
    TB_MID_SET_EXPONENT = 1u << 2,
    TB_MID_SET_TRANSMISSION = 1u << 3,
    TB_MID_SET_IOR = 1u << 4,
    TB_MID_SET_EMISSION = 1u << 5,
    TB_MID_SET_DIFFUSE_TEXTURE = 1u << 6,
    TB_MID_SET_SPECULAR_TEXTURE = 1u << 7,
    TB_MID_SET_TRANSMISSION_TEXTURE = 1u << 8,
    TB_MID_SET_EMISSION_TEXTURE = 1u << 9,
    TB_MID_SET_MODEL = 1u << 10,            /* MID 1.1 */
    TB_MID_SET_ROUGHNESS = 1u << 11,        /* MID 1.1 */
    TB_MID_SET_DIFFUSE_PATTERN = 1u << 12,  /* MID 1.1 */
    TB_MID_SET_SPECULAR_PATTERN = 1u << 13, /* MID 1.1 */
    TB_MID_SET_BUMP = 1u << 14,             /* MID 1.1 */
};

/* A material, fully resolved (docs/mid.md, section 7), plus what its block
 * said: `base` and `set` tell the writer which attributes to write. */
typedef struct tb_mid_material {
    const char *name;          /* definition name (material items); NULL in an object */
    const char *base;          /* material = "..." of the block, or NULL */
    unsigned set;              /* TB_MID_SET_* bits of the attributes the block wrote */
    tb_mid_color diffuse;      /* reflectance, [0,1] */
    tb_mid_color specular;     /* Phong/Blinn reflectance, [0,1] */
    tb_mid_color transmission; /* specular transmittance, [0,1] */
    tb_mid_color emission;     /* radiant exitance W/m^2 (per nm for spectra); radiance = M/pi */
    float exponent;            /* Phong/Blinn exponent, >= 0 */
    float ior;                 /* index of refraction of the inside, > 0 */
    tb_mid_ref diffuse_texture, specular_texture, transmission_texture, emission_texture;
    tb_mid_model model;        /* reflection model of the specular term (MID 1.1) */
    float roughness;           /* GGX alpha, [0, 1] (MID 1.1) */
    tb_mid_pattern diffuse_pattern;  /* replaces `diffuse` where set (MID 1.1) */
    tb_mid_pattern specular_pattern; /* replaces `specular` where set (MID 1.1) */
    tb_mid_pattern bump;             /* perturbs the shading normal (MID 1.1) */
    tb_mid_attrs extra;        /* unknown attributes of the block */
    int nrefs;
    const tb_mid_ref *refs;    /* every file() written in the block */
    tb_mid_loc loc;            /* the definition, or the rendering attribute */
} tb_mid_material;

/* The default material (grey 0.5 diffuse, nothing else). */
tb_mid_material tb_mid_material_default(void);

/* True if the material emits (any emission channel or sample > 0, or a spectrum file). */
bool tb_mid_material_emits(const tb_mid_material *m);

/* -------------------------------------------------------------------- objects */

typedef struct tb_mid_object tb_mid_object;

/* A primitive or CSG node. */
struct tb_mid_object {
    tb_prim_kind kind;
    const char *name;              /* NULL if unnamed */
    tb_mid_loc loc;                /* of the keyword */
    int nops;
    const tb_mid_op *ops;          /* the transform as written (object to parent) */
    tb_transform to_world;         /* object to world: parents' transforms times ops */
    tb_mid_geometry geom;          /* by kind */
    tb_mid_attrs geometry_extra;   /* unknown attributes of the geometry block */
    tb_mid_material material;      /* resolved (inherited from the CSG parent when set == 0 and base == NULL) */
    tb_mid_attrs extra;            /* unknown attributes of the object body */
    int nchildren;
    const tb_mid_object *children; /* CSG nodes only */
    int nrefs;
    const tb_mid_ref *refs;        /* every file() of the object's own text (rendering included, children not) */
};

/* ---------------------------------------------------------------------- lights */

/* Light kinds (docs/mid.md, section 9). */
typedef enum tb_light_kind {
    TB_LIGHT_POINT = 0,
    TB_LIGHT_SPOT,
    TB_LIGHT_DIRECTIONAL,
} tb_light_kind;

/* The MID keyword of a light kind ("point_light", ...). */
const char *tb_light_kind_name(tb_light_kind k);

/* A light. */
typedef struct tb_mid_light {
    tb_light_kind kind;
    const char *name;
    tb_mid_loc loc;
    int nops;
    const tb_mid_op *ops;
    tb_transform to_world;  /* light space to world */
    tb_dvec3 position;      /* point, spot: light space */
    tb_dvec3 direction;     /* spot: beam axis; directional: direction of travel (light space) */
    tb_mid_color intensity; /* point, spot: W/sr; directional: irradiance W/m^2 */
    double cone_angle;      /* spot: half-angle of the beam, degrees */
    double cone_delta;      /* spot: width of the falloff, degrees */
    tb_mid_ref ies;         /* point, spot: goniometric file, or text NULL */
    tb_mid_attrs extra;
    int nrefs;
    const tb_mid_ref *refs;
} tb_mid_light;

/* The default light of kind `k`. */
tb_mid_light tb_mid_light_default(tb_light_kind k);

/* ---------------------------------------------------------------------- camera */

/* The camera (docs/mid.md, section 10). */
typedef struct tb_mid_camera {
    const char *name;
    tb_mid_loc loc;
    tb_dvec3 eye, look_at, up;
    double fov;            /* vertical field of view in degrees (derived from focal_length when given) */
    double focal_length;   /* mm; 0 when the file gave fov */
    double film[2];        /* width, height in mm (used with focal_length) */
    int width, height;     /* resolution in pixels */
    double aperture;       /* lens diameter, scene units; 0 = pinhole */
    double focus_distance; /* scene units */
    tb_mid_attrs extra;
    int nrefs;
    const tb_mid_ref *refs;
} tb_mid_camera;

/* The default camera (docs/mid.md, section 10). */
tb_mid_camera tb_mid_camera_default(void);

/* Vertical field of view (degrees) of focal length f (mm) on film [w h] (mm)
 * for an image of res_w x res_h pixels (docs/mid.md, section 10). */
double tb_mid_camera_fov(double f, const double film[2], int res_w, int res_h);

/* ----------------------------------------------------------------------- items */

/* What one top-level entry of a MID file is. */
typedef enum tb_mid_item_type {
    TB_MID_ITEM_END = 0,  /* no more items */
    TB_MID_ITEM_OBJECT,   /* a primitive or CSG tree */
    TB_MID_ITEM_MATERIAL, /* a named material definition */
    TB_MID_ITEM_LIGHT,
    TB_MID_ITEM_CAMERA,
} tb_mid_item_type;

/* One top-level entry. */
typedef struct tb_mid_item {
    tb_mid_item_type type;
    union {
        const tb_mid_object *object;
        const tb_mid_material *material;
        const tb_mid_light *light;
        const tb_mid_camera *camera;
    };
} tb_mid_item;

/* ----------------------------------------------------------------- comparison */

/* True if two values are equal (numbers by ==, strings by bytes, file
 * references by text and resolved path; locations are ignored). */
bool tb_mid_value_equal(const tb_mid_value *a, const tb_mid_value *b);

/* True if two items describe the same thing: every field the writer writes,
 * the resolved materials and the composed transforms (exactly); source
 * locations are ignored. */
bool tb_mid_item_equal(const tb_mid_item *a, const tb_mid_item *b);

#endif
