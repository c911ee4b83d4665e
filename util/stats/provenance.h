/* Provenance of a run: which build, command line, input (with its SHA-256),
 * machine, time and seed produced a result. Written into the JSON report
 * (tb_stats_write_json) and into images as "testbed:*" string attributes, so a
 * picture or a number can be traced back to how it was made. See docs/stats.md. */
#ifndef TB_UTIL_STATS_PROVENANCE_H
#define TB_UTIL_STATS_PROVENANCE_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include "util/base/error.h"

struct tb_image;

/* Hex digest length of SHA-256 plus the terminating zero. */
#define TB_SHA256_HEX_SIZE 65

/* Everything known about how a run was made. Strings are "" when unknown;
 * heap-owned fields are freed by tb_provenance_free. */
typedef struct tb_provenance {
    char version[32];            /* TB_VERSION_STRING of the library */
    char git_revision[64];       /* TB_GIT_REVISION (`git describe` at configure time) */
    char *command_line;          /* argv joined by spaces, shell-quoted where needed (heap) */
    char *options;               /* resolved options as the command states them, or NULL (heap) */
    char *scene;                 /* path of the input file, or NULL (heap) */
    char scene_sha256[TB_SHA256_HEX_SIZE]; /* lowercase hex digest of the input file, "" if none */
    char hostname[256];
    char os[256];                /* uname: "sysname release machine" */
    char cpu[256];               /* "model name" from /proc/cpuinfo, "" if unavailable */
    int cores;                   /* processors online (0 if unknown) */
    int threads;                 /* OpenMP threads a parallel region would use */
    char time_utc[32];           /* when tb_provenance_init ran, ISO 8601 "YYYY-MM-DDTHH:MM:SSZ" */
    uint64_t seed;               /* the run's random seed, valid if has_seed */
    int has_seed;
} tb_provenance;

/* Fills `p` with the build, machine and time, and the command line from
 * argc/argv (argv may be NULL when argc is 0). */
tb_status tb_provenance_init(tb_provenance *p, int argc, char **argv);

/* Frees the heap-owned fields; `p` may then be initialised again. */
void tb_provenance_free(tb_provenance *p);

/* Records `path` as the run's input and its SHA-256 (as `sha256sum` prints it). */
tb_status tb_provenance_hash_file(tb_provenance *p, const char *path);

/* Records the run's resolved options (replacing earlier ones). */
tb_status tb_provenance_set_options(tb_provenance *p, const char *options);

/* Records the run's random seed. */
void tb_provenance_set_seed(tb_provenance *p, uint64_t seed);

/* Stores every known field in `img` as a string attribute "testbed:<key>"
 * (the same keys as the JSON report's "provenance" object). */
tb_status tb_provenance_to_attrs(const tb_provenance *p, struct tb_image *img);

/* Writes `p` as a JSON object (no trailing newline), indented by `indent` spaces. */
void tb_provenance_write_json(FILE *out, const tb_provenance *p, int indent);

/* SHA-256 of the file at `path` as lowercase hex into `hex`. */
tb_status tb_sha256_file(const char *path, char hex[TB_SHA256_HEX_SIZE]);

/* SHA-256 of `n` bytes at `data` as lowercase hex into `hex`. */
tb_status tb_sha256_hex(const void *data, size_t n, char hex[TB_SHA256_HEX_SIZE]);

#endif
