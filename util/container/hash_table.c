#include "util/container/hash_table.h"

#include <stdlib.h>
#include <string.h>

/* Smallest non-zero slot count. */
#define TB__HTAB_MIN_CAP ((size_t)16)
/* Compaction of string keys starts only once this many bytes are dead. */
#define TB__HTAB_MIN_DEAD ((size_t)4096)

struct tb__htab_slot {
    uint64_t hash;  /* full hash of the key; 0 marks an empty slot */
    uint64_t key;   /* the integer key, or the (uintptr_t) of the string copy */
    uint64_t value;
};

uint64_t tb_hash_u64(uint64_t x)
{
    x += 0x9e3779b97f4a7c15ull; /* so that key 0 does not hash to 0 */
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

uint64_t tb_hash_bytes(const void *p, size_t n)
{
    const unsigned char *b = p;
    uint64_t h = 0xcbf29ce484222325ull; /* FNV-1a 64 offset basis */
    for (size_t i = 0; i < n; i++)
        h = (h ^ b[i]) * 0x100000001b3ull; /* FNV 64 prime */
    return tb_hash_u64(h);
}

uint64_t tb_hash_str(const char *s)
{
    return tb_hash_bytes(s, strlen(s));
}

/* Hash as stored in a slot: never 0, which marks empty slots. */
static uint64_t tb__htab_slot_hash(uint64_t h)
{
    return h ? h : 1;
}

void tb_htab_init(tb_htab *h, tb_htab_keys keys)
{
    h->slots = NULL;
    h->cap = 0;
    h->count = 0;
    h->keys = keys;
    tb_arena_init(&h->strings, 0);
    h->live_bytes = 0;
    h->dead_bytes = 0;
}

void tb_htab_free(tb_htab *h)
{
    if (!h)
        return;
    free(h->slots);
    tb_arena_free(&h->strings);
    tb_htab_init(h, h->keys);
}

void tb_htab_clear(tb_htab *h)
{
    if (h->slots)
        memset(h->slots, 0, h->cap * sizeof *h->slots);
    h->count = 0;
    tb_arena_reset(&h->strings);
    h->live_bytes = 0;
    h->dead_bytes = 0;
}

/* Probe distance of the entry in slot `i` from its home slot. */
static size_t tb__htab_dist(const tb_htab *h, size_t i)
{
    return (i - (size_t)(h->slots[i].hash & (h->cap - 1))) & (h->cap - 1);
}

/* Slot index holding the key, or SIZE_MAX. `str` is the string key (STR tables). */
static size_t tb__htab_find(const tb_htab *h, uint64_t hash, uint64_t key, const char *str)
{
    if (h->cap == 0)
        return SIZE_MAX;
    size_t mask = h->cap - 1, i = (size_t)(hash & mask);
    for (size_t dist = 0;; dist++, i = (i + 1) & mask) {
        const tb__htab_slot *s = &h->slots[i];
        /* Robin Hood invariant: every entry further along sits closer to its home
         * than we would, so the key cannot be there. */
        if (s->hash == 0 || tb__htab_dist(h, i) < dist)
            return SIZE_MAX;
        if (s->hash == hash &&
            (str ? strcmp((const char *)(uintptr_t)s->key, str) == 0 : s->key == key))
            return i;
    }
}

/* Places an entry known to be absent (the table has a free slot). */
static void tb__htab_place(tb_htab *h, tb__htab_slot cur)
{
    size_t mask = h->cap - 1, i = (size_t)(cur.hash & mask);
    for (size_t dist = 0;; dist++, i = (i + 1) & mask) {
        tb__htab_slot *s = &h->slots[i];
        if (s->hash == 0) {
            *s = cur;
            return;
        }
        size_t d = tb__htab_dist(h, i);
        if (d < dist) { /* the richer entry moves on */
            tb__htab_slot t = *s;
            *s = cur;
            cur = t;
            dist = d;
        }
    }
}

/* Reallocates to `cap` slots (a power of two >= count / 0.8) and reinserts. */
static tb_status tb__htab_rehash(tb_htab *h, size_t cap)
{
    tb__htab_slot *slots = calloc(cap, sizeof *slots);
    if (!slots)
        return tb_error(TB_ERR_NOMEM, "hash table: cannot allocate %zu slots", cap);
    tb__htab_slot *old = h->slots;
    size_t old_cap = h->cap;
    h->slots = slots;
    h->cap = cap;
    for (size_t i = 0; i < old_cap; i++)
        if (old[i].hash)
            tb__htab_place(h, old[i]);
    free(old);
    return TB_OK;
}

/* Slot count for `n` entries at load <= 0.8, or 0 if it cannot be allocated. */
static size_t tb__htab_cap_for(size_t n)
{
    size_t max = (size_t)PTRDIFF_MAX / sizeof(tb__htab_slot);
    if (n > max / 5 * 4)
        return 0;
    size_t need = n + n / 4 + 1, cap = TB__HTAB_MIN_CAP;
    while (cap < need)
        cap *= 2; /* cannot overflow: need <= max < SIZE_MAX / 2 */
    return cap <= max ? cap : 0;
}

tb_status tb_htab_reserve(tb_htab *h, size_t n)
{
    if (n <= h->count)
        n = h->count;
    size_t cap = tb__htab_cap_for(n);
    if (cap == 0)
        return tb_error(TB_ERR_NOMEM, "hash table: %zu entries are too many", n);
    return cap > h->cap ? tb__htab_rehash(h, cap) : TB_OK;
}

/* Grows if one more entry would push the load above 0.8. */
static tb_status tb__htab_room_for_one(tb_htab *h)
{
    if (h->cap && (h->count + 1) * 5 <= h->cap * 4)
        return TB_OK;
    size_t cap = h->cap ? h->cap * 2 : TB__HTAB_MIN_CAP;
    if (h->cap > (size_t)PTRDIFF_MAX / sizeof(tb__htab_slot) / 2)
        return tb_error(TB_ERR_NOMEM, "hash table: too many entries (%zu)", h->count);
    return tb__htab_rehash(h, cap);
}

tb_status tb_htab_put(tb_htab *h, uint64_t key, uint64_t value)
{
    if (h->keys != TB_HTAB_U64)
        return tb_error(TB_ERR_ARG, "hash table: integer key given to a table of string keys");
    uint64_t hash = tb__htab_slot_hash(tb_hash_u64(key));
    size_t i = tb__htab_find(h, hash, key, NULL);
    if (i != SIZE_MAX) {
        h->slots[i].value = value;
        return TB_OK;
    }
    tb_status st = tb__htab_room_for_one(h);
    if (st)
        return st;
    tb__htab_place(h, (tb__htab_slot){hash, key, value});
    h->count++;
    return TB_OK;
}

tb_status tb_htab_put_str(tb_htab *h, const char *key, uint64_t value)
{
    if (h->keys != TB_HTAB_STR)
        return tb_error(TB_ERR_ARG, "hash table: string key given to a table of integer keys");
    if (!key)
        return tb_error(TB_ERR_ARG, "hash table: NULL string key");
    size_t len = strlen(key);
    uint64_t hash = tb__htab_slot_hash(tb_hash_bytes(key, len));
    size_t i = tb__htab_find(h, hash, 0, key);
    if (i != SIZE_MAX) {
        h->slots[i].value = value;
        return TB_OK;
    }
    tb_status st = tb__htab_room_for_one(h);
    if (st)
        return st;
    char *copy = tb_arena_alloc_aligned(&h->strings, len + 1, 1);
    if (!copy)
        return tb_error_context(TB_ERR_NOMEM, "hash table: copying a key of %zu bytes", len);
    memcpy(copy, key, len + 1);
    tb__htab_place(h, (tb__htab_slot){hash, (uint64_t)(uintptr_t)copy, value});
    h->count++;
    h->live_bytes += len + 1;
    return TB_OK;
}

bool tb_htab_get(const tb_htab *h, uint64_t key, uint64_t *value)
{
    if (h->keys != TB_HTAB_U64)
        return false;
    size_t i = tb__htab_find(h, tb__htab_slot_hash(tb_hash_u64(key)), key, NULL);
    if (i == SIZE_MAX)
        return false;
    if (value)
        *value = h->slots[i].value;
    return true;
}

bool tb_htab_get_str(const tb_htab *h, const char *key, uint64_t *value)
{
    if (h->keys != TB_HTAB_STR || !key)
        return false;
    size_t i = tb__htab_find(h, tb__htab_slot_hash(tb_hash_str(key)), 0, key);
    if (i == SIZE_MAX)
        return false;
    if (value)
        *value = h->slots[i].value;
    return true;
}

/* Empties slot `i`, shifting the entries after it back towards their homes. */
static void tb__htab_remove_at(tb_htab *h, size_t i)
{
    size_t mask = h->cap - 1;
    for (size_t j = (i + 1) & mask; h->slots[j].hash && tb__htab_dist(h, j) > 0;
         i = j, j = (j + 1) & mask)
        h->slots[i] = h->slots[j];
    h->slots[i].hash = 0;
    h->count--;
}

bool tb_htab_del(tb_htab *h, uint64_t key)
{
    if (h->keys != TB_HTAB_U64)
        return false;
    size_t i = tb__htab_find(h, tb__htab_slot_hash(tb_hash_u64(key)), key, NULL);
    if (i == SIZE_MAX)
        return false;
    tb__htab_remove_at(h, i);
    return true;
}

/* Copies the live string keys into a fresh arena, dropping deleted ones. On
 * allocation failure the table keeps the old arena (still valid). */
static void tb__htab_compact(tb_htab *h)
{
    tb_arena fresh;
    tb_arena_init(&fresh, 0);
    /* Copy first, switch pointers only once every copy succeeded. */
    char **copies = malloc(h->count * sizeof *copies + 1);
    if (!copies)
        return;
    size_t n = 0;
    for (size_t i = 0; i < h->cap; i++) {
        if (!h->slots[i].hash)
            continue;
        copies[n] = tb_arena_strdup(&fresh, (const char *)(uintptr_t)h->slots[i].key);
        if (!copies[n]) {
            free(copies);
            tb_arena_free(&fresh);
            return;
        }
        n++;
    }
    n = 0;
    for (size_t i = 0; i < h->cap; i++)
        if (h->slots[i].hash)
            h->slots[i].key = (uint64_t)(uintptr_t)copies[n++];
    free(copies);
    tb_arena_free(&h->strings);
    h->strings = fresh;
    h->dead_bytes = 0;
}

bool tb_htab_del_str(tb_htab *h, const char *key)
{
    if (h->keys != TB_HTAB_STR || !key)
        return false;
    size_t len = strlen(key);
    size_t i = tb__htab_find(h, tb__htab_slot_hash(tb_hash_bytes(key, len)), 0, key);
    if (i == SIZE_MAX)
        return false;
    tb__htab_remove_at(h, i);
    h->live_bytes -= len + 1;
    h->dead_bytes += len + 1;
    /* Amortised: each compaction copies at most as many bytes as were deleted. */
    if (h->dead_bytes > TB__HTAB_MIN_DEAD && h->dead_bytes > h->live_bytes)
        tb__htab_compact(h);
    return true;
}

bool tb_htab_next(const tb_htab *h, size_t *iter, tb_htab_entry *e)
{
    for (size_t i = *iter; i < h->cap; i++) {
        const tb__htab_slot *s = &h->slots[i];
        if (!s->hash)
            continue;
        if (h->keys == TB_HTAB_STR) {
            e->key = 0;
            e->str = (const char *)(uintptr_t)s->key;
        } else {
            e->key = s->key;
            e->str = NULL;
        }
        e->value = s->value;
        *iter = i + 1;
        return true;
    }
    *iter = h->cap;
    return false;
}
