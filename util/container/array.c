#include "util/container/array.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

void tb_array_init(tb_array *a, size_t elem_size)
{
    a->data = NULL;
    a->len = 0;
    a->cap = 0;
    a->elem_size = elem_size;
}

void tb_array_free(tb_array *a)
{
    if (!a)
        return;
    free(a->data);
    a->data = NULL;
    a->len = 0;
    a->cap = 0;
}

/* Largest element count whose byte size fits in ptrdiff_t: beyond it pointer
 * differences inside the block would overflow, so no allocation may be larger. */
static size_t tb__array_max_elems(const tb_array *a)
{
    return (size_t)PTRDIFF_MAX / a->elem_size;
}

/* Reallocates to exactly `cap` elements (cap <= tb__array_max_elems()). */
static tb_status tb__array_realloc(tb_array *a, size_t cap)
{
    void *p = realloc(a->data, cap * a->elem_size);
    if (!p)
        return tb_error(TB_ERR_NOMEM, "array: cannot allocate %zu elements of %zu bytes", cap,
                        a->elem_size);
    a->data = p;
    a->cap = cap;
    return TB_OK;
}

tb_status tb_array_reserve(tb_array *a, size_t cap)
{
    if (a->elem_size == 0)
        return tb_error(TB_ERR_ARG, "array: element size is zero (not initialised?)");
    if (cap <= a->cap)
        return TB_OK;
    if (cap > tb__array_max_elems(a))
        return tb_error(TB_ERR_NOMEM, "array: %zu elements of %zu bytes overflow the address space",
                        cap, a->elem_size);
    return tb__array_realloc(a, cap);
}

/* Room for `extra` more elements, growing geometrically so that n pushes cost
 * O(n) copies in total. */
static tb_status tb__array_grow(tb_array *a, size_t extra)
{
    if (a->elem_size == 0)
        return tb_error(TB_ERR_ARG, "array: element size is zero (not initialised?)");
    size_t max = tb__array_max_elems(a);
    if (extra > max - a->len)
        return tb_error(TB_ERR_NOMEM, "array: %zu + %zu elements of %zu bytes overflow the address space",
                        a->len, extra, a->elem_size);
    size_t need = a->len + extra;
    if (need <= a->cap)
        return TB_OK;
    size_t cap = a->cap < 8 ? 8 : a->cap;
    while (cap < need)
        cap = cap > max / 2 ? max : cap * 2;
    return tb__array_realloc(a, cap);
}

tb_status tb_array_resize(tb_array *a, size_t len)
{
    if (len > a->len) {
        tb_status st = tb__array_grow(a, len - a->len);
        if (st)
            return st;
        memset((char *)a->data + a->len * a->elem_size, 0, (len - a->len) * a->elem_size);
    }
    a->len = len;
    return TB_OK;
}

tb_status tb_array_push(tb_array *a, const void *elem)
{
    return tb_array_insert(a, a->len, elem);
}

tb_status tb_array_push_n(tb_array *a, const void *elems, size_t n)
{
    if (n == 0)
        return TB_OK;
    if (!elems)
        return tb_error(TB_ERR_ARG, "array: push_n of %zu elements from NULL", n);
    uintptr_t base = (uintptr_t)a->data, e = (uintptr_t)elems;
    int inside = a->data && e >= base && e < base + a->len * a->elem_size;
    tb_status st = tb__array_grow(a, n);
    if (st)
        return st;
    if (inside) /* appending a slice of itself: the storage may have moved */
        elems = (char *)a->data + (e - base);
    memcpy((char *)a->data + a->len * a->elem_size, elems, n * a->elem_size);
    a->len += n;
    return TB_OK;
}

tb_status tb_array_pop(tb_array *a, void *out)
{
    if (a->len == 0)
        return tb_error(TB_ERR_ARG, "array: pop from an empty array");
    a->len--;
    if (out)
        memcpy(out, (char *)a->data + a->len * a->elem_size, a->elem_size);
    return TB_OK;
}

tb_status tb_array_insert(tb_array *a, size_t i, const void *elem)
{
    if (i > a->len)
        return tb_error(TB_ERR_ARG, "array: insert at %zu past the end (length %zu)", i, a->len);
    /* `elem` may point into this array (push of an own element): keep its
     * offset, since growing can move the storage. */
    uintptr_t base = (uintptr_t)a->data, e = (uintptr_t)elem;
    int inside = elem && a->data && e >= base && e < base + a->len * a->elem_size;
    size_t offset = inside ? (size_t)(e - base) : 0;
    tb_status st = tb__array_grow(a, 1);
    if (st)
        return st;
    char *at = (char *)a->data + i * a->elem_size;
    if (inside) /* also shifted up by one slot if it sat at or after `at` */
        elem = (char *)a->data + offset + (offset >= i * a->elem_size ? a->elem_size : 0);
    memmove(at + a->elem_size, at, (a->len - i) * a->elem_size);
    if (elem) /* after the move, so `elem` (re-derived above) points at the shifted copy */
        memcpy(at, elem, a->elem_size);
    else
        memset(at, 0, a->elem_size);
    a->len++;
    return TB_OK;
}

tb_status tb_array_remove(tb_array *a, size_t i, void *out)
{
    if (i >= a->len)
        return tb_error(TB_ERR_ARG, "array: remove at %zu out of range (length %zu)", i, a->len);
    char *at = (char *)a->data + i * a->elem_size;
    if (out)
        memcpy(out, at, a->elem_size);
    memmove(at, at + a->elem_size, (a->len - i - 1) * a->elem_size);
    a->len--;
    return TB_OK;
}

void tb_array_clear(tb_array *a)
{
    a->len = 0;
}
