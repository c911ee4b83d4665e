/* The streaming MID reader: opens the input, checks the header, and for each
 * call parses one top-level object (mid_parser.c) and interprets it
 * (mid_schema.c) in an arena that is reset for the next one. */
#include "host/mid/mid_reader.h"
#include "util/base/str.h"

#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "host/mid/mid_internal.h"

/* The absolute form of folder `dir` (NULL or "": the current directory). */
static char *tb__absolute_dir(const char *dir)
{
    char cwd[PATH_MAX];
    if (dir && dir[0] == '/')
        return tb_strdup(dir);
    if (!getcwd(cwd, sizeof cwd))
        return NULL;
    if (!dir || !dir[0] || strcmp(dir, ".") == 0)
        return tb_strdup(cwd);
    size_t n = strlen(cwd) + strlen(dir) + 2;
    char *p = malloc(n);
    if (p)
        snprintf(p, n, "%s/%s", cwd, dir);
    return p;
}

static tb_status tb__reader_new(tb_mid_reader **out, FILE *fp, const char *name, const char *base_dir)
{
    *out = NULL;
    tb_mid_reader *r = calloc(1, sizeof *r);
    if (!r)
        return tb_error(TB_ERR_NOMEM, "%s: out of memory", name);
    r->name = tb_strdup(name);
    r->base_dir = tb__absolute_dir(base_dir);
    if (!r->name || !r->base_dir) {
        tb_mid_reader_close(r);
        return tb_error(TB_ERR_NOMEM, "%s: out of memory (or the current directory is unreadable)", name);
    }
    tb_status st = tb__mid_lexer_init(&r->lx, fp, r->name);
    if (st) {
        tb_mid_reader_close(r);
        return st;
    }
    tb_arena_init(&r->item, 0);
    tb_arena_init(&r->keep, 0);
    tb_array_init(&r->values, sizeof(tb_mid_value));
    tb_array_init(&r->nums, sizeof(tb__mid_num));
    tb_array_init(&r->attrs, sizeof(tb_mid_attr));
    tb_array_init(&r->nodes, sizeof(tb__mid_node));
    tb_array_init(&r->refs, sizeof(tb_mid_ref));
    tb_array_init(&r->order, sizeof(tb__name_idx));
    tb_htab_init(&r->materials, TB_HTAB_STR);
    tb_htab_init(&r->checked, TB_HTAB_STR);
    *out = r;
    return TB_OK;
}

tb_status tb_mid_reader_open_stream(tb_mid_reader **out, FILE *fp, const char *name, const char *base_dir)
{
    if (!out || !fp)
        return tb_error(TB_ERR_ARG, "tb_mid_reader_open_stream: NULL argument");
    return tb__reader_new(out, fp, name ? name : "<stream>", base_dir);
}

tb_status tb_mid_reader_open(tb_mid_reader **out, const char *path)
{
    if (!out || !path)
        return tb_error(TB_ERR_ARG, "tb_mid_reader_open: NULL argument");
    *out = NULL;
    if (strcmp(path, "-") == 0)
        return tb__reader_new(out, stdin, "<stdin>", NULL);
    FILE *fp = fopen(path, "rb");
    if (!fp)
        return tb_error(TB_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    struct stat sb;
    if (fstat(fileno(fp), &sb) == 0 && S_ISDIR(sb.st_mode)) {
        fclose(fp);
        return tb_error(TB_ERR_IO, "%s: is a folder, not a MID file", path);
    }
    /* References resolve against the file's folder. */
    char *dir = tb_strdup(path);
    if (!dir) {
        fclose(fp);
        return tb_error(TB_ERR_NOMEM, "%s: out of memory", path);
    }
    char *slash = strrchr(dir, '/');
    if (slash == dir)
        dir[1] = '\0';
    else if (slash)
        *slash = '\0';
    else
        dir[0] = '\0';
    tb_status st = tb__reader_new(out, fp, path, dir);
    free(dir);
    if (st) {
        fclose(fp);
        return st;
    }
    (*out)->owned_fp = fp;
    return TB_OK;
}

void tb_mid_reader_close(tb_mid_reader *r)
{
    if (!r)
        return;
    if (r->owned_fp)
        fclose(r->owned_fp);
    tb__mid_lexer_free(&r->lx);
    tb_arena_free(&r->item);
    tb_arena_free(&r->keep);
    tb_array_free(&r->values);
    tb_array_free(&r->nums);
    tb_array_free(&r->attrs);
    tb_array_free(&r->nodes);
    tb_array_free(&r->refs);
    tb_array_free(&r->order);
    tb_htab_free(&r->materials);
    tb_htab_free(&r->checked);
    free(r->failed_msg);
    free(r->name);
    free(r->base_dir);
    free(r);
}

tb_status tb__mid_resolve_ref(tb_mid_reader *r, const char *text, tb_mid_loc loc, tb_mid_ref *ref)
{
    if (!text[0])
        return TB__MID_ERR(r, loc, "empty file name in file()");
    size_t n = strlen(text);
    char *path;
    if (text[0] == '/') {
        path = tb__mid_alloc(r, n + 1);
        if (path)
            memcpy(path, text, n + 1);
    } else {
        size_t nb = strlen(r->base_dir);
        bool root = nb > 0 && r->base_dir[nb - 1] == '/';
        path = tb__mid_alloc(r, nb + n + 2);
        if (path)
            snprintf(path, nb + n + 2, "%s%s%s", r->base_dir, root ? "" : "/", text);
    }
    if (!path)
        return tb_error(TB_ERR_NOMEM, "%s: out of memory", r->lx.name);
    ref->text = text;
    ref->path = path;
    if (tb_htab_get_str(&r->checked, path, NULL))
        return TB_OK;
    struct stat sb;
    if (stat(path, &sb) != 0)
        return TB__MID_ERR(r, loc, "data file '%.200s' not found (looked for '%.300s')", text, path);
    if (!S_ISREG(sb.st_mode))
        return TB__MID_ERR(r, loc, "data file '%.200s' is not a regular file ('%.300s')", text, path);
    /* Remember it; a bounded cache keeps the reader's memory flat. */
    if (r->checked.count >= TB__MID_REF_CACHE_MAX)
        tb_htab_clear(&r->checked);
    if (tb_htab_put_str(&r->checked, path, 1))
        return tb_error(TB_ERR_NOMEM, "%s: out of memory", r->lx.name);
    return TB_OK;
}

static tb_status tb__fail(tb_mid_reader *r, tb_status st)
{
    r->failed = st;
    free(r->failed_msg);
    r->failed_msg = tb_strdup(tb_last_error());
    return st;
}

tb_status tb_mid_reader_next(tb_mid_reader *r, tb_mid_item *item)
{
    memset(item, 0, sizeof *item);
    if (r->failed) {
        if (r->failed_msg)
            tb_error(r->failed, "%s", r->failed_msg);
        return r->failed;
    }
    tb_status st;
    if (!r->header_done) {
        if ((st = tb__mid_parse_header(r)))
            return tb__fail(r, st);
        r->header_done = true;
    }
    tb_arena_reset(&r->item);
    r->bump = r->bump_end = NULL;
    r->values.len = r->nums.len = r->attrs.len = r->nodes.len = r->refs.len = 0;
    tb__mid_node node;
    bool eof;
    if ((st = tb__mid_parse_item(r, &node, &eof)))
        return tb__fail(r, st);
    if (eof) {
        item->type = TB_MID_ITEM_END;
        return TB_OK;
    }
    if ((st = tb__mid_interpret(r, &node, item)))
        return tb__fail(r, st);
    return TB_OK;
}

const tb_mid_camera *tb_mid_reader_camera(const tb_mid_reader *r) { return r->camera; }

const tb_mid_material *tb_mid_reader_material(const tb_mid_reader *r, const char *name)
{
    uint64_t p;
    if (!tb_htab_get_str(&r->materials, name, &p))
        return NULL;
    return (const tb_mid_material *)(uintptr_t)p;
}

void tb_mid_reader_version(const tb_mid_reader *r, int *major, int *minor)
{
    if (major)
        *major = r->major;
    if (minor)
        *minor = r->minor;
}

uint64_t tb_mid_reader_offset(const tb_mid_reader *r) { return tb__mid_lexer_offset(&r->lx); }

size_t tb_mid_reader_memory(const tb_mid_reader *r)
{
    return TB__MID_BUF + 1 + TB__MID_BUF_PAD + TB_MID_MAX_TOKEN + 1 + tb_arena_capacity(&r->item) + tb_arena_capacity(&r->keep) +
           r->values.cap * r->values.elem_size + r->nums.cap * r->nums.elem_size + r->attrs.cap * r->attrs.elem_size +
           r->nodes.cap * r->nodes.elem_size + r->refs.cap * r->refs.elem_size + r->order.cap * r->order.elem_size;
}

void *tb__mid_alloc_slow(tb_mid_reader *r, size_t n)
{
    if (n > TB__MID_BLOCK / 4)
        return tb_arena_alloc(&r->item, n);
    char *b = tb_arena_alloc(&r->item, TB__MID_BLOCK);
    if (!b)
        return NULL;
    r->bump = b + ((n + 15) & ~(size_t)15);
    r->bump_end = b + TB__MID_BLOCK;
    return b;
}
