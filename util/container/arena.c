#include "util/container/arena.h"

#include <stdalign.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* AddressSanitizer hooks: poison the bytes of a chunk nobody owns. */
#if defined(__SANITIZE_ADDRESS__)
#define TB__ARENA_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define TB__ARENA_ASAN 1
#endif
#endif
#ifdef TB__ARENA_ASAN
#include <sanitizer/asan_interface.h>
#define TB__POISON(p, n) ASAN_POISON_MEMORY_REGION((p), (n))
#define TB__UNPOISON(p, n) ASAN_UNPOISON_MEMORY_REGION((p), (n))
#else
#define TB__POISON(p, n) ((void)(p), (void)(n))
#define TB__UNPOISON(p, n) ((void)(p), (void)(n))
#endif

/* Smallest chunk payload; tiny chunks would make every request "large". */
#define TB__ARENA_MIN_CHUNK ((size_t)256)

struct tb__arena_chunk {
    tb__arena_chunk *prev; /* next older chunk of the same list */
    size_t size;           /* payload bytes */
    size_t used;           /* payload bytes handed out (including alignment padding) */
    alignas(max_align_t) unsigned char data[];
};

void tb_arena_init(tb_arena *a, size_t chunk_size)
{
    a->head = NULL;
    a->large = NULL;
    a->spare = NULL;
    a->chunk_size = chunk_size;
}

static size_t tb__arena_chunk_size(const tb_arena *a)
{
    size_t s = a->chunk_size ? a->chunk_size : TB_ARENA_DEFAULT_CHUNK;
    return s < TB__ARENA_MIN_CHUNK ? TB__ARENA_MIN_CHUNK : s;
}

/* A chunk with `size` payload bytes, all poisoned; NULL on overflow or failure. */
static tb__arena_chunk *tb__arena_new_chunk(size_t size)
{
    if (size > (size_t)PTRDIFF_MAX - sizeof(tb__arena_chunk))
        return NULL;
    tb__arena_chunk *c = malloc(sizeof(tb__arena_chunk) + size);
    if (!c)
        return NULL;
    c->prev = NULL;
    c->size = size;
    c->used = 0;
    TB__POISON(c->data, size);
    return c;
}

/* Takes `size` bytes aligned to `align` from `c`, or NULL if they do not fit. */
static void *tb__arena_take(tb__arena_chunk *c, size_t size, size_t align)
{
    uintptr_t top = (uintptr_t)(c->data + c->used);
    size_t pad = (size_t)((align - (top & (align - 1))) & (align - 1));
    size_t room = c->size - c->used;
    if (pad > room || size > room - pad)
        return NULL;
    unsigned char *p = c->data + c->used + pad;
    c->used += pad + size;
    TB__UNPOISON(p, size);
    return p;
}

void *tb_arena_alloc_aligned(tb_arena *a, size_t size, size_t align)
{
    if (align == 0 || (align & (align - 1)) != 0) {
        tb_error(TB_ERR_ARG, "arena: alignment %zu is not a power of two", align);
        return NULL;
    }
    if (size == 0)
        size = 1;
    /* Worst-case bytes including padding, given that payloads start max_align_t-aligned. */
    size_t slack = align > alignof(max_align_t) ? align - alignof(max_align_t) : 0;
    if (size > (size_t)PTRDIFF_MAX - slack) {
        tb_error(TB_ERR_NOMEM, "arena: request of %zu bytes is too large", size);
        return NULL;
    }
    size_t need = size + slack, chunk = tb__arena_chunk_size(a);

    if (need > chunk / 4) {
        tb__arena_chunk *c = tb__arena_new_chunk(need);
        if (!c) {
            tb_error(TB_ERR_NOMEM, "arena: cannot allocate %zu bytes", size);
            return NULL;
        }
        c->prev = a->large;
        a->large = c;
        return tb__arena_take(c, size, align); /* fits by construction */
    }
    void *p = a->head ? tb__arena_take(a->head, size, align) : NULL;
    if (p)
        return p;
    tb__arena_chunk *c = a->spare;
    if (c) {
        a->spare = NULL;
        c->used = 0;
    } else if (!(c = tb__arena_new_chunk(chunk))) {
        tb_error(TB_ERR_NOMEM, "arena: cannot allocate a chunk of %zu bytes", chunk);
        return NULL;
    }
    c->prev = a->head;
    a->head = c;
    return tb__arena_take(c, size, align); /* need <= chunk/4 always fits */
}

void *tb_arena_alloc(tb_arena *a, size_t size)
{
    return tb_arena_alloc_aligned(a, size, alignof(max_align_t));
}

void *tb_arena_alloc_zero(tb_arena *a, size_t size)
{
    void *p = tb_arena_alloc(a, size);
    if (p)
        memset(p, 0, size);
    return p;
}

char *tb_arena_strdup(tb_arena *a, const char *s)
{
    size_t n = strlen(s) + 1;
    char *p = tb_arena_alloc_aligned(a, n, 1);
    if (p)
        memcpy(p, s, n);
    return p;
}

tb_arena_mark tb_arena_mark_get(const tb_arena *a)
{
    tb_arena_mark m = {a->head, a->head ? a->head->used : 0, a->large};
    return m;
}

void tb_arena_release(tb_arena *a, tb_arena_mark m)
{
    while (a->large && a->large != m.large) {
        tb__arena_chunk *c = a->large;
        a->large = c->prev;
        free(c);
    }
    size_t chunk = tb__arena_chunk_size(a);
    while (a->head && a->head != m.head) {
        tb__arena_chunk *c = a->head;
        a->head = c->prev;
        /* Keep one chunk: a scope that keeps crossing a chunk boundary would
         * otherwise call malloc/free on every iteration. */
        if (!a->spare && c->size == chunk) {
            TB__POISON(c->data, c->size);
            c->prev = NULL;
            a->spare = c;
        } else {
            free(c);
        }
    }
    if (a->head && m.used <= a->head->used) {
        TB__POISON(a->head->data + m.used, a->head->used - m.used);
        a->head->used = m.used;
    }
}

void tb_arena_reset(tb_arena *a)
{
    tb_arena_mark empty = {NULL, 0, NULL};
    tb_arena_release(a, empty);
}

void tb_arena_free(tb_arena *a)
{
    if (!a)
        return;
    tb_arena_reset(a);
    free(a->spare);
    a->spare = NULL;
}

size_t tb_arena_capacity(const tb_arena *a)
{
    size_t total = a->spare ? a->spare->size : 0;
    for (const tb__arena_chunk *c = a->head; c; c = c->prev)
        total += c->size;
    for (const tb__arena_chunk *c = a->large; c; c = c->prev)
        total += c->size;
    return total;
}
