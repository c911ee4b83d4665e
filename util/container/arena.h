/* Arena (bump) allocator: many small allocations freed all at once.
 *
 * Memory comes from chunks of `chunk_size` bytes; an allocation takes the next
 * suitably aligned bytes of the current chunk, or starts a new chunk. A request
 * larger than a quarter of the chunk size gets a chunk of its own, so a big
 * block never wastes the rest of a normal chunk. Allocations are aligned to
 * alignof(max_align_t) unless an explicit power-of-two alignment is asked for.
 *
 * Scopes: tb_arena_mark_get() records the current top; tb_arena_release() frees
 * everything allocated after that mark (marks nest like a stack: releasing an
 * outer mark invalidates the inner ones). tb_arena_reset() releases everything
 * but keeps one chunk for reuse; tb_arena_free() returns all memory.
 *
 * Under AddressSanitizer the unused and released bytes of each chunk are
 * poisoned, so reads past an allocation or after a release are reported.
 * Not thread-safe: one arena per thread or task.
 */
#ifndef TB_UTIL_CONTAINER_ARENA_H
#define TB_UTIL_CONTAINER_ARENA_H

#include <stddef.h>
#include "util/base/error.h"

/* Default bytes per chunk when tb_arena_init() is given 0. */
#define TB_ARENA_DEFAULT_CHUNK ((size_t)64 * 1024)

typedef struct tb__arena_chunk tb__arena_chunk;

/* An arena; initialise with tb_arena_init() (a zeroed struct also works and
 * uses the default chunk size). */
typedef struct tb_arena {
    tb__arena_chunk *head;  /* current normal chunk; older ones follow via ->prev */
    tb__arena_chunk *large; /* dedicated chunks of large requests, newest first */
    tb__arena_chunk *spare; /* one released normal chunk kept for reuse, or NULL */
    size_t chunk_size;      /* usable bytes of a normal chunk (0: default) */
} tb_arena;

/* A position to return to with tb_arena_release(). */
typedef struct tb_arena_mark {
    tb__arena_chunk *head;  /* head chunk when the mark was taken */
    size_t used;            /* bytes used in that chunk */
    tb__arena_chunk *large; /* newest large chunk when the mark was taken */
} tb_arena_mark;

/* Empty arena whose normal chunks hold `chunk_size` bytes (0: TB_ARENA_DEFAULT_CHUNK). */
void tb_arena_init(tb_arena *a, size_t chunk_size);

/* `size` bytes aligned to alignof(max_align_t); NULL (TB_ERR_NOMEM) on failure.
 * Size 0 is treated as 1 so that every call returns a distinct pointer. */
void *tb_arena_alloc(tb_arena *a, size_t size);

/* `size` bytes aligned to `align` (a power of two, any size); NULL on failure
 * (TB_ERR_ARG for a bad alignment, TB_ERR_NOMEM otherwise). */
void *tb_arena_alloc_aligned(tb_arena *a, size_t size, size_t align);

/* Like tb_arena_alloc(), with the bytes set to zero. */
void *tb_arena_alloc_zero(tb_arena *a, size_t size);

/* A copy of the zero-terminated string `s` in the arena, or NULL. */
char *tb_arena_strdup(tb_arena *a, const char *s);

/* The current top of the arena, for a later tb_arena_release(). */
tb_arena_mark tb_arena_mark_get(const tb_arena *a);

/* Frees everything allocated since `m` was taken. */
void tb_arena_release(tb_arena *a, tb_arena_mark m);

/* Frees every allocation; keeps one chunk so the next use need not allocate. */
void tb_arena_reset(tb_arena *a);

/* Returns all memory to the system; the arena is empty and reusable. NULL is allowed. */
void tb_arena_free(tb_arena *a);

/* Bytes held from the system (chunk payloads, including the spare chunk). */
size_t tb_arena_capacity(const tb_arena *a);

#endif
