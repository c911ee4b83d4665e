/* Hash table from 64-bit integer keys or string keys to 64-bit values, and the
 * hash functions it uses.
 *
 * Open addressing with Robin Hood linear probing (Celis 1986): an entry being
 * inserted takes the slot of any entry that sits closer to its home slot, which
 * keeps probe lengths short and lets a failed lookup stop early. Deletion shifts
 * the following entries back (no tombstones), so a table with heavy churn never
 * degrades. The slot count is a power of two and grows x2 when the load would
 * exceed 0.8.
 *
 * A table holds one kind of key, chosen at init: integers (TB_HTAB_U64) or
 * zero-terminated strings (TB_HTAB_STR, copied into an arena owned by the
 * table; the arena is compacted when deleted keys outweigh live ones). Values
 * are uint64_t; store a pointer as (uint64_t)(uintptr_t)p. Iteration order is
 * unspecified, and any insertion or deletion invalidates running iterations and
 * string pointers returned by tb_htab_next().
 */
#ifndef TB_UTIL_CONTAINER_HASH_TABLE_H
#define TB_UTIL_CONTAINER_HASH_TABLE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "util/base/error.h"
#include "util/container/arena.h"

/* 64-bit mixer (SplitMix64 finaliser, Steele et al. 2014): a bijection, so
 * distinct keys never collide in the full hash, and every output bit depends
 * on every input bit. */
uint64_t tb_hash_u64(uint64_t x);

/* Hash of `n` bytes: 64-bit FNV-1a, then the tb_hash_u64() finaliser because
 * FNV-1a alone mixes poorly into the low bits a power-of-two table uses. Not
 * keyed, so not meant for hostile input. */
uint64_t tb_hash_bytes(const void *p, size_t n);

/* tb_hash_bytes() of a zero-terminated string (without the terminator). */
uint64_t tb_hash_str(const char *s);

/* What the keys of a table are. */
typedef enum tb_htab_keys {
    TB_HTAB_U64 = 0, /* uint64_t keys, any value */
    TB_HTAB_STR = 1, /* zero-terminated strings, copied into the table */
} tb_htab_keys;

typedef struct tb__htab_slot tb__htab_slot;

/* A hash table. */
typedef struct tb_htab {
    tb__htab_slot *slots; /* `cap` slots, NULL while cap == 0 */
    size_t cap;           /* slot count: 0 or a power of two */
    size_t count;         /* entries stored */
    tb_htab_keys keys;    /* key kind, fixed at init */
    tb_arena strings;     /* copies of string keys */
    size_t live_bytes;    /* arena bytes of stored string keys */
    size_t dead_bytes;    /* arena bytes of deleted string keys, reclaimed by compaction */
} tb_htab;

/* One entry, as returned by tb_htab_next(). */
typedef struct tb_htab_entry {
    uint64_t key;    /* integer key (TB_HTAB_U64 tables; 0 otherwise) */
    const char *str; /* string key (TB_HTAB_STR tables; NULL otherwise), owned by the table */
    uint64_t value;
} tb_htab_entry;

/* An empty table of the given key kind (allocates nothing). */
void tb_htab_init(tb_htab *h, tb_htab_keys keys);

/* Frees all memory; the table is empty and reusable. NULL is allowed. */
void tb_htab_free(tb_htab *h);

/* Removes every entry, keeping the slot array. */
void tb_htab_clear(tb_htab *h);

/* Makes room for `n` entries without further growth. */
tb_status tb_htab_reserve(tb_htab *h, size_t n);

/* Sets the value of integer key `key`, inserting it or replacing the old value. */
tb_status tb_htab_put(tb_htab *h, uint64_t key, uint64_t value);

/* Sets the value of string key `key` (copied on insertion). */
tb_status tb_htab_put_str(tb_htab *h, const char *key, uint64_t value);

/* True if `key` is present; its value goes to `*value` unless NULL. */
bool tb_htab_get(const tb_htab *h, uint64_t key, uint64_t *value);

/* True if string `key` is present; its value goes to `*value` unless NULL. */
bool tb_htab_get_str(const tb_htab *h, const char *key, uint64_t *value);

/* Removes `key`; true if it was present. */
bool tb_htab_del(tb_htab *h, uint64_t key);

/* Removes string `key`; true if it was present. */
bool tb_htab_del_str(tb_htab *h, const char *key);

/* Iteration: start with *iter = 0; each call stores the next entry in `*e` and
 * returns true, or returns false when all entries have been visited. */
bool tb_htab_next(const tb_htab *h, size_t *iter, tb_htab_entry *e);

#endif
