/* Checkpoints (docs/distributed.md, "Checkpoints"): the state of a long
 * job in one file, written atomically (a temporary file renamed over the
 * old one, util/base/outfile.h), so a job stopped at any moment leaves the
 * last complete checkpoint; `--resume FILE` continues from it and finishes
 * with the result of an uninterrupted run, bit for bit.
 *
 * File: a 48-byte header, the payload, an 8-byte checksum.
 *   magic "TBCKPT\n\0" | u32 version (TB_CKPT_VERSION) | u32 kind (TB_CKPT_*)
 *   | u32 0x01020304 (byte order) | u32 0 | u64 job key | u64 payload bytes
 *   | u64 units done (passes, shots) | payload | u64 FNV-1a of the payload
 * The job key hashes what must not change between the run and its resume
 * (scene bytes, options); a mismatch, another kind, version, byte order, a
 * short file or a bad checksum is refused with the file's name. */
#ifndef TB_HOST_DIST_CHECKPOINT_H
#define TB_HOST_DIST_CHECKPOINT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "host/radiosity/render.h"
#include "host/render/render.h"
#include "util/base/error.h"

/* Version of the file layout; a reader refuses others. */
#define TB_CKPT_VERSION 3u

/* What a checkpoint holds. */
enum {
    TB_CKPT_RENDER = 1,    /* a progressive render: passes done, aa counts, the film */
    TB_CKPT_RADIOSITY = 2, /* a radiosity solve: the refinement's rounds (--adapt), the solver's state */
};

/* FNV-1a 64 of `len` bytes, continuing from `h` (start: TB_CKPT_HASH_SEED). */
uint64_t tb_ckpt_hash(uint64_t h, const void *data, size_t len);

/* The FNV-1a 64 offset basis. */
#define TB_CKPT_HASH_SEED 0xcbf29ce484222325ull

/* Writes a checkpoint atomically: an existing file at `path` is replaced
 * only once the new one is complete. */
tb_status tb_ckpt_write(const char *path, uint32_t kind, uint64_t key, uint64_t units, const void *payload,
                        size_t len);

/* Reads a checkpoint of `kind` for job `key`: *payload (malloc'd; free it)
 * and *len, *units. TB_ERR_FORMAT ("FILE: ...") for anything that is not
 * such a checkpoint, TB_ERR_IO if it cannot be read. */
tb_status tb_ckpt_read(const char *path, uint32_t kind, uint64_t key, void **payload, size_t *len,
                       uint64_t *units);

/* The checkpoints of one progressive render (tb_render_persist of
 * render.h). Fill the fields, then hand tb_ckpt_render_persist(&c) to the
 * render options (rank 0 is the only one that calls it). */
typedef struct tb_ckpt_render {
    const char *path;        /* where to save, or NULL: never */
    double every;            /* seconds between saves (0: after every pass); the last pass always saves */
    const char *resume_path; /* checkpoint to continue, or NULL */
    uint64_t key;            /* the job key (scene and options) */
    double last_save;        /* clock of the last save (set by the persist) */
    int saved_passes;        /* passes in the last checkpoint written or read (-1: none) */
    bool quiet;              /* no line on stderr per save */
} tb_ckpt_render;

/* The persist callbacks over `c` (which must outlive the render). */
tb_render_persist tb_ckpt_render_persist(tb_ckpt_render *c);

/* The checkpoints of a radiosity solve (tb_rad_persist of
 * host/radiosity/render.h): the solver's packed state (tb_rad_solver_pack).
 * In a job of several ranks rank 0 reads the checkpoint and broadcasts it
 * (no shared file system needed), and rank 0 alone writes. */
typedef struct tb_ckpt_rad {
    const char *path;        /* where to save, or NULL: never */
    double every;            /* seconds between saves (0: after every shot); the last shot always saves */
    const char *resume_path; /* checkpoint to continue, or NULL */
    uint64_t key;            /* the job key (scene and options) */
    double last_save;        /* clock of the last save (set by the persist) */
    bool quiet;              /* no line on stderr per save */
} tb_ckpt_rad;

/* The persist callbacks over `c` (which must outlive the solve); every
 * rank of a job calls them. */
tb_rad_persist tb_ckpt_rad_persist(tb_ckpt_rad *c);

/* Says where the last checkpoint is when the launcher stops this process
 * (SIGTERM, as mpirun does when another rank dies): installs a handler that
 * writes `testbed: rank R of N stopped ...; last checkpoint: ...` to stderr
 * and exits with status 143. Rank 0 calls it once; the checkpoint
 * functions keep its message up to date. */
void tb_ckpt_on_term(const char *prog);

/* Sets the message tb_ckpt_on_term writes (what the last checkpoint is). */
void tb_ckpt_note(const char *path, const char *what);

#endif
