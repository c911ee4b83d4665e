/* Growable array of fixed-size elements (any type, chosen at init by its size).
 *
 * One untyped struct instead of macro-generated typed arrays: a single copy of
 * the code, readable in a debugger, and usable from any C file. TB_ARRAY_AT()
 * and TB_ARRAY_PUSH() give typed access. Every size computation is checked:
 * a request whose byte size would overflow (or exceed PTRDIFF_MAX) returns
 * TB_ERR_NOMEM without calling the allocator.
 *
 *     tb_array a;
 *     tb_array_init(&a, sizeof(double));
 *     TB_ARRAY_PUSH(&a, double, 2.5);
 *     double x = TB_ARRAY_AT(&a, double, 0);
 *     tb_array_free(&a);
 */
#ifndef TB_UTIL_CONTAINER_ARRAY_H
#define TB_UTIL_CONTAINER_ARRAY_H

#include <stddef.h>
#include "util/base/error.h"

/* A dynamic array; a zeroed struct is NOT valid (elem_size must be set), use
 * tb_array_init() or TB_ARRAY_INIT. */
typedef struct tb_array {
    void *data;       /* cap * elem_size bytes; NULL while cap == 0 */
    size_t len;       /* elements in use */
    size_t cap;       /* elements allocated */
    size_t elem_size; /* bytes per element, > 0 */
} tb_array;

/* Static initialiser for an empty array of `type`. */
#define TB_ARRAY_INIT(type) { NULL, 0, 0, sizeof(type) }

/* Lvalue of element `i` as `type` (no bounds check). */
#define TB_ARRAY_AT(a, type, i) (((type *)(a)->data)[i])

/* Appends `value` (an expression of `type`); evaluates to a tb_status. */
#define TB_ARRAY_PUSH(a, type, value) tb_array_push((a), (type[1]){value})

/* Makes `a` an empty array of elements of `elem_size` bytes (no allocation). */
void tb_array_init(tb_array *a, size_t elem_size);

/* Frees the storage; `a` is left empty and may be reused. NULL is allowed. */
void tb_array_free(tb_array *a);

/* Pointer to element `i` (no bounds check). */
static inline void *tb_array_at(const tb_array *a, size_t i)
{
    return (char *)a->data + i * a->elem_size;
}

/* Makes room for at least `cap` elements; never shrinks. */
tb_status tb_array_reserve(tb_array *a, size_t cap);

/* Sets the length to `len`; new elements are zero bytes. */
tb_status tb_array_resize(tb_array *a, size_t len);

/* Appends one element copied from `elem` (NULL appends zero bytes). */
tb_status tb_array_push(tb_array *a, const void *elem);

/* Appends `n` elements copied from `elems`. */
tb_status tb_array_push_n(tb_array *a, const void *elems, size_t n);

/* Removes the last element, copying it to `out` unless NULL; TB_ERR_ARG if empty. */
tb_status tb_array_pop(tb_array *a, void *out);

/* Inserts a copy of `elem` (NULL: zero bytes) before index `i` (0 <= i <= len). */
tb_status tb_array_insert(tb_array *a, size_t i, const void *elem);

/* Removes element `i` (copied to `out` unless NULL), shifting the tail down. */
tb_status tb_array_remove(tb_array *a, size_t i, void *out);

/* Sets the length to zero and keeps the storage. */
void tb_array_clear(tb_array *a);

#endif
