/* The texture cache: one pyramid per image file, keyed by the file's
 * resolved path and the read options (texture.h). */

/* realpath() is an X/Open function: glibc declares it for XSI, not for the
 * plain POSIX level the build asks for (XSI 700 includes POSIX 2008). */
#define _XOPEN_SOURCE 700

#include "host/render/texture.h"

#include <errno.h>
#include <limits.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util/container/hash_table.h"
#include "util/stats/stats.h"

TB_STAT_COUNTER(tb__stat_cache_loads, "Texture/images loaded");
TB_STAT_COUNTER(tb__stat_cache_hits, "Texture/cache hits");

struct tb_texture_cache {
    pthread_mutex_t lock; /* guards the table and loading */
    tb_htab table;        /* "resolved path\nencoding" -> tb_mipmap * */
};

tb_texture_cache *tb_texture_cache_create(void)
{
    tb_texture_cache *c = calloc(1, sizeof *c);
    if (!c || pthread_mutex_init(&c->lock, NULL) != 0) {
        free(c);
        tb_error(TB_ERR_NOMEM, "texture cache: out of memory");
        return NULL;
    }
    tb_htab_init(&c->table, TB_HTAB_STR);
    return c;
}

void tb_texture_cache_free(tb_texture_cache *c)
{
    if (!c)
        return;
    size_t it = 0;
    tb_htab_entry e;
    while (tb_htab_next(&c->table, &it, &e))
        tb_mipmap_free((tb_mipmap *)(uintptr_t)e.value);
    tb_htab_free(&c->table);
    pthread_mutex_destroy(&c->lock);
    free(c);
}

size_t tb_texture_cache_count(const tb_texture_cache *c)
{
    return c->table.count;
}

tb_status tb_texture_cache_get(tb_texture_cache *c, const char *base_dir, const char *path,
                               const tb_image_read_options *opts, const tb_mipmap **out)
{
    *out = NULL;
    if (!c || !path || !*path)
        return tb_error(TB_ERR_ARG, "texture cache: no path");
    /* the path as given, relative to base_dir */
    char *joined = NULL;
    if (path[0] != '/' && base_dir && *base_dir) {
        size_t n = strlen(base_dir) + strlen(path) + 2;
        joined = malloc(n);
        if (!joined)
            return tb_error(TB_ERR_NOMEM, "texture cache: out of memory");
        snprintf(joined, n, "%s/%s", base_dir, path);
    }
    const char *given = joined ? joined : path;
    char *resolved = realpath(given, NULL);
    if (!resolved) {
        int e = errno;
        tb_status st = tb_error(e == ENOENT || e == ENOTDIR ? TB_ERR_NOT_FOUND : TB_ERR_IO,
                                "texture %s: %s", given, strerror(e));
        free(joined);
        return st;
    }
    int enc = opts ? (int)opts->encoding : 0;
    size_t klen = strlen(resolved) + 16;
    char *key = malloc(klen);
    if (!key) {
        free(resolved);
        free(joined);
        return tb_error(TB_ERR_NOMEM, "texture cache: out of memory");
    }
    snprintf(key, klen, "%s\n%d", resolved, enc);

    tb_status st = TB_OK;
    pthread_mutex_lock(&c->lock);
    uint64_t v;
    if (tb_htab_get_str(&c->table, key, &v)) {
        *out = (const tb_mipmap *)(uintptr_t)v;
        TB_STAT_INC(tb__stat_cache_hits);
    } else {
        tb_image *img = NULL;
        st = tb_image_read(resolved, opts, &img);
        if (st == TB_OK) {
            tb_mipmap *m = tb_mipmap_create(img);
            if (!m) {
                st = tb_error_context(img->channels > TB_TEX_MAX_CHANNELS ? TB_ERR_UNSUPPORTED : TB_ERR_NOMEM,
                                      "texture %s", given);
            } else if ((st = tb_htab_put_str(&c->table, key, (uint64_t)(uintptr_t)m)) != TB_OK) {
                tb_mipmap_free(m);
            } else {
                *out = m;
                TB_STAT_INC(tb__stat_cache_loads);
            }
        }
        tb_image_free(img);
    }
    pthread_mutex_unlock(&c->lock);
    free(key);
    free(resolved);
    free(joined);
    return st;
}
