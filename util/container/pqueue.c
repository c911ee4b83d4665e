#include "util/container/pqueue.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define TB__PQ_ABSENT UINT32_MAX

struct tb__pqueue_node {
    double priority;
    uint32_t key;
};

void tb_pqueue_init(tb_pqueue *q)
{
    memset(q, 0, sizeof *q);
}

void tb_pqueue_free(tb_pqueue *q)
{
    if (!q)
        return;
    free(q->heap);
    free(q->pos);
    tb_pqueue_init(q);
}

void tb_pqueue_clear(tb_pqueue *q)
{
    for (size_t i = 0; i < q->size; i++)
        q->pos[q->heap[i].key] = TB__PQ_ABSENT;
    q->size = 0;
}

/* True if node `a` must come before node `b`. */
static bool tb__pq_before(const tb__pqueue_node *a, const tb__pqueue_node *b)
{
    if (a->priority != b->priority)
        return a->priority > b->priority;
    return a->key < b->key;
}

static void tb__pq_put(tb_pqueue *q, size_t i, tb__pqueue_node n)
{
    q->heap[i] = n;
    q->pos[n.key] = (uint32_t)i;
}

/* Moves the node at `i` towards the root while it beats its parent. */
static void tb__pq_up(tb_pqueue *q, size_t i)
{
    tb__pqueue_node n = q->heap[i];
    while (i > 0) {
        size_t parent = (i - 1) / 2;
        if (!tb__pq_before(&n, &q->heap[parent]))
            break;
        tb__pq_put(q, i, q->heap[parent]);
        i = parent;
    }
    tb__pq_put(q, i, n);
}

/* Moves the node at `i` towards the leaves while a child beats it. */
static void tb__pq_down(tb_pqueue *q, size_t i)
{
    tb__pqueue_node n = q->heap[i];
    for (;;) {
        size_t c = 2 * i + 1;
        if (c >= q->size)
            break;
        if (c + 1 < q->size && tb__pq_before(&q->heap[c + 1], &q->heap[c]))
            c++;
        if (!tb__pq_before(&q->heap[c], &n))
            break;
        tb__pq_put(q, i, q->heap[c]);
        i = c;
    }
    tb__pq_put(q, i, n);
}

/* Grows the position index to hold keys below `nkeys`. */
static tb_status tb__pq_grow_pos(tb_pqueue *q, size_t nkeys)
{
    if (nkeys <= q->pos_cap)
        return TB_OK;
    size_t cap = q->pos_cap < 16 ? 16 : q->pos_cap;
    while (cap < nkeys)
        cap *= 2;
    if (cap > (size_t)TB_PQUEUE_MAX_KEY + 1)
        cap = (size_t)TB_PQUEUE_MAX_KEY + 1;
    uint32_t *pos = realloc(q->pos, cap * sizeof *pos);
    if (!pos)
        return tb_error(TB_ERR_NOMEM, "priority queue: cannot index %zu keys", cap);
    memset(pos + q->pos_cap, 0xff, (cap - q->pos_cap) * sizeof *pos); /* TB__PQ_ABSENT */
    q->pos = pos;
    q->pos_cap = cap;
    return TB_OK;
}

/* Room for `n` heap nodes. */
static tb_status tb__pq_grow_heap(tb_pqueue *q, size_t n)
{
    if (n <= q->heap_cap)
        return TB_OK;
    size_t cap = q->heap_cap < 16 ? 16 : q->heap_cap;
    while (cap < n)
        cap *= 2;
    tb__pqueue_node *heap = realloc(q->heap, cap * sizeof *heap);
    if (!heap)
        return tb_error(TB_ERR_NOMEM, "priority queue: cannot hold %zu keys", cap);
    q->heap = heap;
    q->heap_cap = cap;
    return TB_OK;
}

tb_status tb_pqueue_reserve(tb_pqueue *q, size_t nkeys)
{
    if (nkeys > (size_t)TB_PQUEUE_MAX_KEY + 1)
        return tb_error(TB_ERR_NOMEM, "priority queue: %zu keys exceed the largest key %u", nkeys,
                        (unsigned)TB_PQUEUE_MAX_KEY);
    tb_status st = tb__pq_grow_pos(q, nkeys);
    return st ? st : tb__pq_grow_heap(q, nkeys);
}

tb_status tb_pqueue_set(tb_pqueue *q, uint32_t key, double priority)
{
    if (isnan(priority))
        return tb_error(TB_ERR_ARG, "priority queue: NaN priority for key %u", (unsigned)key);
    if (key > TB_PQUEUE_MAX_KEY)
        return tb_error(TB_ERR_ARG, "priority queue: key %u exceeds the largest key %u",
                        (unsigned)key, (unsigned)TB_PQUEUE_MAX_KEY);
    if (key < q->pos_cap && q->pos[key] != TB__PQ_ABSENT) {
        size_t i = q->pos[key];
        double old = q->heap[i].priority;
        q->heap[i].priority = priority;
        if (priority > old)
            tb__pq_up(q, i);
        else if (priority < old)
            tb__pq_down(q, i);
        return TB_OK;
    }
    tb_status st = tb__pq_grow_pos(q, (size_t)key + 1);
    if (!st)
        st = tb__pq_grow_heap(q, q->size + 1);
    if (st)
        return st;
    q->heap[q->size] = (tb__pqueue_node){priority, key};
    q->size++;
    tb__pq_up(q, q->size - 1);
    return TB_OK;
}

bool tb_pqueue_get(const tb_pqueue *q, uint32_t key, double *priority)
{
    if (key >= q->pos_cap || q->pos[key] == TB__PQ_ABSENT)
        return false;
    if (priority)
        *priority = q->heap[q->pos[key]].priority;
    return true;
}

bool tb_pqueue_remove(tb_pqueue *q, uint32_t key)
{
    if (key >= q->pos_cap || q->pos[key] == TB__PQ_ABSENT)
        return false;
    size_t i = q->pos[key];
    q->pos[key] = TB__PQ_ABSENT;
    q->size--;
    if (i == q->size)
        return true;
    /* The last node fills the hole; it may belong above or below it. */
    tb__pqueue_node last = q->heap[q->size];
    tb__pq_put(q, i, last);
    if (i > 0 && tb__pq_before(&last, &q->heap[(i - 1) / 2]))
        tb__pq_up(q, i);
    else
        tb__pq_down(q, i);
    return true;
}

bool tb_pqueue_peek(const tb_pqueue *q, uint32_t *key, double *priority)
{
    if (q->size == 0)
        return false;
    if (key)
        *key = q->heap[0].key;
    if (priority)
        *priority = q->heap[0].priority;
    return true;
}

bool tb_pqueue_pop(tb_pqueue *q, uint32_t *key, double *priority)
{
    uint32_t k;
    if (!tb_pqueue_peek(q, &k, priority))
        return false;
    if (key)
        *key = k;
    tb_pqueue_remove(q, k);
    return true;
}
