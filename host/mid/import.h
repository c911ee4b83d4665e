/* Importing models from other formats into MID (docs/import.md): OBJ (+MTL),
 * PLY, STL, glTF 2.0 and whatever else Assimp reads, through Assimp's C API.
 *
 * One call reads the model and writes OUT.mid plus a folder OUT.data/ beside
 * it holding one FED file per source mesh (and copies of the textures the
 * materials use); the MID file references them with relative file("...")
 * paths. Vertex positions are copied bit for bit from what Assimp read (for
 * OBJ, ASCII PLY and ASCII STL, corrected to the correctly rounded value of
 * the file's text where Assimp's parser was one ulp off); node transforms
 * become MID transforms. The output appears whole or not at all:
 * everything is written under temporary names and renamed at the end, and on
 * any failure whatever was written is removed. */
#ifndef TB_HOST_SCENE_IMPORT_H
#define TB_HOST_SCENE_IMPORT_H

#include <stdbool.h>
#include <stdint.h>

#include "util/base/error.h"

/* Which Assimp vertices become one FED vertex. */
typedef enum tb_import_join {
    TB_IMPORT_JOIN_AUTO = 0, /* join for formats whose importer unfolds shared vertices (OBJ), else keep */
    TB_IMPORT_JOIN_ALWAYS,   /* join vertices equal in every written attribute, for every format */
    TB_IMPORT_JOIN_NEVER,    /* one FED vertex per Assimp vertex (unused ones dropped) */
} tb_import_join;

/* Called once per warning (a value clamped, a face dropped, a light skipped, ...). */
typedef void (*tb_import_warn_fn)(void *user, const char *message);

/* How to import; a zeroed struct means text FED files, polygons kept,
 * automatic joining, warnings discarded. */
typedef struct tb_import_opts {
    bool binary_fed;        /* write binary FED files (.fedb) instead of text (.fed) */
    bool triangulate;       /* split polygons into triangles (Assimp's aiProcess_Triangulate) */
    tb_import_join join;    /* vertex joining policy */
    tb_import_warn_fn warn; /* NULL: warnings are only counted */
    void *warn_user;        /* passed to warn */
} tb_import_opts;

/* What an import wrote. */
typedef struct tb_import_stats {
    uint32_t objects;        /* MID polygons objects (one per mesh instance) */
    uint32_t fed_files;      /* FED files (one per distinct source mesh) */
    uint64_t vertices;       /* FED vertices, summed over the files */
    uint64_t faces;          /* FED faces, summed over the files */
    uint64_t skipped_faces;  /* source faces not written: points, lines, degenerate polygons */
    uint64_t rerounded;      /* text formats: coordinates Assimp misrounded, set to the file's value */
    uint64_t undecided;      /* text formats: coordinates not found in the file, kept as Assimp read them */
    uint32_t materials;      /* named MID materials */
    uint32_t textures;       /* texture files copied or extracted */
    uint32_t lights;         /* MID lights */
    uint32_t cameras;        /* 0 or 1 */
    uint32_t warnings;       /* warnings reported */
    char format[64];         /* the Assimp importer that read the model ("Wavefront Object Importer") */
} tb_import_stats;

/* Imports `model` into the MID file `out_mid` and the folder
 * tb_import_data_dir(out_mid) beside it (replaced if it exists). `opts` and
 * `stats` may be NULL. Errors name the model or the output path:
 * TB_ERR_IO (unreadable model, unwritable output), TB_ERR_FORMAT (Assimp
 * could not read the model; its message is included), TB_ERR_NOT_FOUND
 * (nothing to import: no polygon faces), TB_ERR_NOMEM. On failure nothing
 * is left on disk and an existing output is untouched. */
tb_status tb_import(const char *model, const char *out_mid, const tb_import_opts *opts, tb_import_stats *stats);

/* The data folder's path for `out_mid`: its name without a ".mid" ending,
 * plus ".data" ("dir/scene.mid" -> "dir/scene.data"). malloc'ed; NULL with
 * TB_ERR_NOMEM. */
char *tb_import_data_dir(const char *out_mid);

#endif
