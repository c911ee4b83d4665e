/* Indexed priority queue: a binary max-heap of (key, priority) pairs where a
 * key's priority can be raised or lowered in O(log n).
 *
 * Keys are small non-negative integers (patch, light or task ids): a position
 * index, grown on demand to the largest key seen, maps each key to its heap
 * slot, so update/remove by key need no search. Memory is O(max key + size).
 *
 * Order: a higher priority comes first; among equal priorities the LOWER key
 * comes first (so results do not depend on insertion order, which matters for
 * progressive radiosity picking the patch with most unshot energy). -0.0 and
 * +0.0 are equal. NaN priorities are refused; infinities are allowed.
 */
#ifndef TB_UTIL_CONTAINER_PQUEUE_H
#define TB_UTIL_CONTAINER_PQUEUE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "util/base/error.h"

/* Largest key accepted (the position index needs key + 1 entries). */
#define TB_PQUEUE_MAX_KEY ((uint32_t)0x7ffffffe)

typedef struct tb__pqueue_node tb__pqueue_node;

/* An indexed max-heap; initialise with tb_pqueue_init(). */
typedef struct tb_pqueue {
    tb__pqueue_node *heap; /* `size` nodes in heap order, root at 0 */
    size_t size;           /* keys in the queue */
    size_t heap_cap;       /* nodes allocated */
    uint32_t *pos;         /* pos[key]: heap slot of key, or UINT32_MAX if absent */
    size_t pos_cap;        /* entries of `pos` (keys 0 .. pos_cap-1 are indexable) */
} tb_pqueue;

/* An empty queue (allocates nothing). */
void tb_pqueue_init(tb_pqueue *q);

/* Frees all memory; the queue is empty and reusable. NULL is allowed. */
void tb_pqueue_free(tb_pqueue *q);

/* Removes every key, keeping the memory. */
void tb_pqueue_clear(tb_pqueue *q);

/* Makes room for keys 0 .. nkeys-1 without further allocation. */
tb_status tb_pqueue_reserve(tb_pqueue *q, size_t nkeys);

/* Inserts `key` with `priority`, or changes its priority if present (up or down). */
tb_status tb_pqueue_set(tb_pqueue *q, uint32_t key, double priority);

/* True if `key` is in the queue; its priority goes to `*priority` unless NULL. */
bool tb_pqueue_get(const tb_pqueue *q, uint32_t key, double *priority);

/* Removes `key`; true if it was present. */
bool tb_pqueue_remove(tb_pqueue *q, uint32_t key);

/* The first key (highest priority, lowest key on ties) without removing it;
 * false if empty. Either output may be NULL. */
bool tb_pqueue_peek(const tb_pqueue *q, uint32_t *key, double *priority);

/* Removes and returns the first key; false if empty. Either output may be NULL. */
bool tb_pqueue_pop(tb_pqueue *q, uint32_t *key, double *priority);

/* Number of keys in the queue. */
static inline size_t tb_pqueue_size(const tb_pqueue *q) { return q->size; }

#endif
