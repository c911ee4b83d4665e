/* Internal interface of the importer (host/mid/import*.c): the mesh
 * conversion and the material, light and camera mappings, each testable on
 * its own. docs/import.md states every rule implemented here. */
#ifndef TB_HOST_SCENE_IMPORT_INTERNAL_H
#define TB_HOST_SCENE_IMPORT_INTERNAL_H

#include <stdbool.h>
#include <stdint.h>

#include <assimp/camera.h>
#include <assimp/light.h>
#include <assimp/material.h>
#include <assimp/mesh.h>

#include "host/mid/mid.h"
#include "util/base/error.h"
#include "util/mesh/fed.h"

/* What converting one Assimp mesh into a FED mesh left out or changed. */
typedef struct tb__import_mesh_report {
    uint32_t faces_in;      /* source faces with 3 or more corners */
    uint32_t points_lines;  /* source faces with 1 or 2 indices (not written) */
    uint32_t degenerate;    /* polygons dropped: fewer than 3 distinct corners, or zero area as FED defines it */
    uint32_t nonfinite;     /* polygons dropped: a corner at a NaN or infinite position */
    uint32_t collapsed;     /* corners removed for sitting at the previous corner's position */
    uint32_t first_dropped; /* Assimp index of the first dropped polygon, or UINT32_MAX */
    bool normals_dropped;   /* the mesh had normals, some not finite: none written */
    bool uvs_dropped;       /* the mesh had (u,v), some not finite: none written */
} tb__import_mesh_report;

/* Text formats whose coordinates can be re-rounded from the file's text. */
typedef enum tb__import_text_kind {
    TB__TEXT_OBJ = 0, /* "v x y z" lines */
    TB__TEXT_PLY,     /* ASCII PLY: the vertex element's x, y, z columns */
    TB__TEXT_STL,     /* ASCII STL: "vertex x y z" lines */
} tb__import_text_kind;

/* The file's vertex coordinates, correctly rounded (import_text.c). */
typedef struct tb__import_reround {
    float *vals;        /* sorted distinct coordinates (strtof of the file's text) */
    size_t n;
    bool active;        /* vals is usable */
    uint64_t changed;   /* coordinates moved one ulp onto a number of the file */
    uint64_t undecided; /* coordinates not in the file with both or neither neighbour in it: kept */
} tb__import_reround;

/* Reads the coordinates of the text model `path`. A file that cannot be
 * opened or parsed leaves `r` inactive (TB_OK); TB_ERR_NOMEM. */
tb_status tb__import_reround_load(const char *path, tb__import_text_kind kind, tb__import_reround *r);

/* The coordinate of the file that Assimp's value `a` stands for: a itself
 * if it is one, else its only neighbour (one ulp away) that is; a when
 * undecided or r is NULL or inactive. Counts in r. */
float tb__import_reround_value(tb__import_reround *r, float a);

/* Frees the coordinates (r stays valid and inactive). */
void tb__import_reround_free(tb__import_reround *r);

/* Builds the FED mesh of `m`: positions copied bit for bit, normals and the
 * first (u,v) channel when present and finite, one loop per face with 3 or
 * more corners, consecutive corners at the same position merged, faces FED
 * rejects as degenerate dropped (all counted in *rep). With `join`, vertices
 * equal bit for bit in every written attribute become one. With `rr`, each
 * coordinate is first passed through tb__import_reround_value. Vertices no
 * written face uses are left out; the others keep their relative order.
 * *out is NULL (and TB_OK returned) when no face is left. TB_ERR_FORMAT for
 * an index out of range, TB_ERR_UNSUPPORTED beyond FED's counts, TB_ERR_NOMEM. */
tb_status tb__import_mesh_fed(const struct aiMesh *m, bool join, tb__import_reround *rr, tb_fed **out,
                              tb__import_mesh_report *rep);

/* Warning sink of the mappings: `fmt` formatted, sent to the user's callback. */
typedef struct tb__import_warner {
    void (*fn)(void *user, const char *message);
    void *user;
    uint32_t count; /* warnings sent so far */
} tb__import_warner;

/* Sends one warning. */
void tb__import_warn(tb__import_warner *w, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* Texture slots a MID material can take. */
enum { TB__TEX_DIFFUSE = 0, TB__TEX_SPECULAR, TB__TEX_EMISSION, TB__TEX_COUNT };

/* Longest texture path kept from Assimp (aiString's limit). */
#define TB__IMPORT_PATH_MAX 1024

/* An Assimp material mapped to MID (docs/import.md, "Materials"). */
typedef struct tb__import_material {
    tb_mid_material mat;                          /* values and set bits; no name, no textures yet */
    bool pbr;                                     /* mapped as glTF metallic-roughness */
    char tex[TB__TEX_COUNT][TB__IMPORT_PATH_MAX]; /* Assimp texture paths ("" for none), by TB__TEX_* */
} tb__import_material;

/* Maps `am` to a MID material. `label` names the material in warnings
 * (values clamped into MID's ranges). Metallic-roughness (glTF) is used when
 * the material has AI_MATKEY_METALLIC_FACTOR, the Phong mapping otherwise. */
void tb__import_map_material(const struct aiMaterial *am, const char *label, tb__import_warner *w,
                             tb__import_material *out);

/* Radiometric watts per photometric lumen used for glTF lights: 1/683
 * (the luminous efficacy of 555 nm light). */
#define TB_IMPORT_LUMENS_PER_WATT 683.0

/* Maps `al` to a MID light placed by `ops` (light space to world, already
 * checked). `photometric`: the source gives candela and lux (glTF
 * KHR_lights_punctual), converted with TB_IMPORT_LUMENS_PER_WATT. Returns
 * false (after a warning) for kinds MID has no counterpart for. */
bool tb__import_map_light(const struct aiLight *al, bool photometric, const char *label, tb__import_warner *w,
                          tb_mid_light *out);

/* Maps `ac`, whose node has the world transform `world` (row-major 4x4,
 * column vectors), to the MID camera. `gltf`: the camera came from the glTF 2
 * importer, so it sits at its node's origin looking down -Z with +Y up (Assimp
 * 5.2 also copies the node's translation into mPosition, which would count it
 * twice), and its horizontal FOV is yfov * aspect (Assimp before 5.3) or
 * 2 atan(tan(yfov/2) aspect) (later); other importers follow aiCamera's
 * documentation (half the horizontal angle). Returns false (after a warning)
 * for an orthographic or degenerate camera. */
bool tb__import_map_camera(const struct aiCamera *ac, const double world[16], bool gltf, const char *label,
                           tb__import_warner *w, tb_mid_camera *out);

#endif
