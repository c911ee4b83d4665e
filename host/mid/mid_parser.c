/* MID parser: the grammar of docs/mid.md, section 3, without the schema. It
 * turns one top-level object into a tree of tb__mid_node / tb_mid_attr /
 * tb_mid_value in the reader's item arena. Lists, blocks and bodies collect
 * their elements on scratch stacks (reused from item to item) and copy them
 * into the arena when they close, so nothing is reallocated in the arena. */
#include "host/mid/mid_internal.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#define TB__FOUND(r, buf) tb__mid_describe_token(&(r)->lx, (buf), sizeof(buf))

static tb_status tb__adv(tb_mid_reader *r) { return tb__mid_lex(&r->lx); }

/* Names the format defines, shared instead of copied for every use (an
 * attribute name, call name or symbol is compared, never written to). */
static const char *const tb__known[] = {
    "transform", "geometry", "rendering", "material", "diffuse", "specular", "exponent", "transmission", "ior",
    "emission", "diffuse_texture", "specular_texture", "transmission_texture", "emission_texture", "caps",
    "top_radius", "top", "sides", "profile", "major", "minor", "vertices", "faces", "normals", "uvs", "mesh",
    "coefficients", "z_range", "width", "height", "position", "direction", "intensity", "irradiance",
    "cone_angle", "cone_delta", "ies", "eye", "look_at", "up", "fov", "focal_length", "film", "resolution",
    "aperture", "focus_distance", "translate", "scale", "rotate", "matrix", "spectrum", "file", "true", "false",
};

/* Open-addressing table over tb__known, built once. */
#define TB__INTERN_SLOTS 256
static const char *tb__intern_slot[TB__INTERN_SLOTS];
static pthread_once_t tb__intern_once = PTHREAD_ONCE_INIT;

static unsigned tb__intern_hash(const char *s, size_t n)
{
    return ((unsigned)n * 31u + (unsigned char)s[0] * 7u + (unsigned char)s[n - 1] * 131u) & (TB__INTERN_SLOTS - 1);
}

static void tb__intern_build(void)
{
    for (size_t i = 0; i < sizeof tb__known / sizeof tb__known[0]; i++) {
        unsigned h = tb__intern_hash(tb__known[i], strlen(tb__known[i]));
        while (tb__intern_slot[h])
            h = (h + 1) & (TB__INTERN_SLOTS - 1);
        tb__intern_slot[h] = tb__known[i];
    }
}

/* The shared copy of the n bytes at s if the format defines that name, else NULL. */
static const char *tb__intern(const char *s, size_t n)
{
    if (n == 0 || n > 24)
        return NULL;
    for (unsigned h = tb__intern_hash(s, n);; h = (h + 1) & (TB__INTERN_SLOTS - 1)) {
        const char *k = tb__intern_slot[h];
        if (!k)
            return NULL;
        size_t i = 0;
        while (i < n && k[i] == s[i])
            i++;
        if (i == n && k[n] == '\0')
            return k;
    }
}

/* The current token's text (an identifier): shared if the format defines
 * it, else copied into the item arena. */
static const char *tb__name(tb_mid_reader *r)
{
    const char *k = tb__intern(r->lx.text, r->lx.len);
    if (k)
        return k;
    char *s = tb__mid_alloc(r, r->lx.len + 1);
    if (s) {
        memcpy(s, r->lx.text, r->lx.len);
        s[r->lx.len] = '\0';
    }
    return s;
}

/* The current token's text, copied into the item arena. */
static char *tb__copy_text(tb_mid_reader *r)
{
    char *s = tb__mid_alloc(r, r->lx.len + 1);
    if (s) {
        memcpy(s, r->lx.text, r->lx.len);
        s[r->lx.len] = '\0';
    }
    return s;
}

/* Element i of a scratch stack; NULL while the stack has no storage (no
 * arithmetic on a null pointer). */
static void *tb__slot(const tb_array *a, size_t i)
{
    return a->data ? (char *)a->data + i * a->elem_size : NULL;
}

static tb_status tb__nomem(tb_mid_reader *r)
{
    return tb_error(TB_ERR_NOMEM, "%s: out of memory", r->lx.name);
}

/* Copies `n` elements of `size` bytes into the item arena (NULL for n == 0). */
static tb_status tb__to_arena(tb_mid_reader *r, const void *src, size_t n, size_t size, void **out)
{
    *out = NULL;
    if (n == 0)
        return TB_OK;
    void *p = tb__mid_alloc(r, n * size);
    if (!p)
        return tb__nomem(r);
    memcpy(p, src, n * size);
    *out = p;
    return TB_OK;
}

/* Pushes attribute *a on r->attrs. Member by member: gcc copies the
 * 72-byte struct with `rep movsl`, slow to start for so few bytes. */
static inline tb_status tb__push_attr(tb_mid_reader *r, const tb_mid_attr *a)
{
    tb_array *s = &r->attrs;
    if (s->len < s->cap) {
        tb_mid_attr *d = (tb_mid_attr *)s->data + s->len++;
        d->name = a->name;
        d->value = a->value;
        d->loc = a->loc;
        return TB_OK;
    }
    return tb_array_push(s, a);
}

static bool tb__starts_value(tb__mid_tok t)
{
    return t == TB__T_NUMBER || t == TB__T_STRING || t == TB__T_IDENT || t == TB__T_LBRACKET ||
           t == TB__T_LBRACE;
}

static tb_status tb__too_deep(tb_mid_reader *r)
{
    return TB__MID_ERR(r, r->lx.loc, "nesting deeper than %d levels", TB_MID_MAX_DEPTH);
}

static int tb__cmp_name_idx(const void *a, const void *b)
{
    const tb__name_idx *x = a, *y = b;
    int c = strcmp(x->name, y->name);
    return c ? c : (x->idx > y->idx) - (x->idx < y->idx);
}

/* "duplicate attribute" for the first repeated name in file order. */
static tb_status tb__check_duplicates(tb_mid_reader *r, const tb_mid_attr *a, size_t n)
{
    if (n < 2)
        return TB_OK;
    if (n <= 16) {
        for (size_t j = 1; j < n; j++)
            for (size_t i = 0; i < j; i++)
                if (a[i].name[0] == a[j].name[0] && strcmp(a[i].name, a[j].name) == 0)
                    return TB__MID_ERR(r, a[j].loc, "duplicate attribute '%.40s' (first given at %ld:%ld)",
                                       a[j].name, a[i].loc.line, a[i].loc.col);
        return TB_OK;
    }
    /* Sorting by (name, position): each repeat follows its first occurrence. */
    tb_array_clear(&r->order);
    if (tb_array_resize(&r->order, n))
        return tb__nomem(r);
    tb__name_idx *o = r->order.data;
    for (size_t i = 0; i < n; i++)
        o[i] = (tb__name_idx){a[i].name, (int)i};
    qsort(o, n, sizeof *o, tb__cmp_name_idx);
    int best = -1, first = -1;
    for (size_t i = 1; i < n; i++) {
        if (strcmp(o[i].name, o[i - 1].name) == 0 && (i < 2 || strcmp(o[i - 1].name, o[i - 2].name) != 0)) {
            /* o[i] is the second occurrence of its name. */
            if (best < 0 || o[i].idx < best) {
                best = o[i].idx;
                first = o[i - 1].idx;
            }
        }
    }
    if (best >= 0)
        return TB__MID_ERR(r, a[best].loc, "duplicate attribute '%.40s' (first given at %ld:%ld)",
                           a[best].name, a[first].loc.line, a[first].loc.col);
    return TB_OK;
}

static tb_status tb__parse_value(tb_mid_reader *r, tb_mid_value *v, int depth, const char *attr);

/* The elements of a list (call == NULL) or of call `call` up to the closing
 * bracket, pushed on r->values; the current token is the opener (skip_open)
 * or the next element. */
static tb_status tb__parse_items(tb_mid_reader *r, const char *call, tb_mid_loc open, int depth, bool skip_open)
{
    tb__mid_lexer *lx = &r->lx;
    tb__mid_tok close = call ? TB__T_RPAREN : TB__T_RBRACKET;
    char closech = call ? ')' : ']';
    char found[96], what[64];
    tb_status st;
    if (skip_open && (st = tb__adv(r)))
        return st;
    for (;;) {
        if (lx->type == close)
            return TB_OK;
        if (!tb__starts_value(lx->type)) {
            if (call)
                snprintf(what, sizeof what, "'%.40s('", call);
            else
                snprintf(what, sizeof what, "the list");
            if (lx->type == TB__T_EOF)
                return TB__MID_ERR(r, lx->loc, "expected '%c' to close %s opened at %ld:%ld, found end of file",
                                   closech, what, open.line, open.col);
            TB__FOUND(r, found);
            return TB__MID_ERR(r, lx->loc, "expected a value or '%c' to close %s opened at %ld:%ld, found %s",
                               closech, what, open.line, open.col, found);
        }
        tb_mid_value v;
        if ((st = tb__parse_value(r, &v, depth + 1, NULL)))
            return st;
        if (tb__mid_push(&r->values, &v))
            return tb__nomem(r);
        if (lx->type == TB__T_COMMA) {
            if ((st = tb__adv(r)))
                return st;
            if (!tb__starts_value(lx->type)) {
                TB__FOUND(r, found);
                return TB__MID_ERR(r, lx->loc, "expected a value after ',', found %s", found);
            }
        }
    }
}

/* [ ... ]: a VECTOR when every element is a number, else a LIST. */
static tb_status tb__parse_list(tb_mid_reader *r, tb_mid_value *v, int depth)
{
    tb__mid_lexer *lx = &r->lx;
    if (depth > TB_MID_MAX_DEPTH)
        return tb__too_deep(r);
    /* Fast path for the common case, a list of numbers: they go to a stack
     * of (number, position) instead of one generic value each. */
    size_t first = r->values.len, nums0 = r->nums.len;
    tb_status st = tb__adv(r);
    if (st)
        return st;
    while (lx->type == TB__T_NUMBER) {
        tb__mid_num x = {lx->number, lx->loc};
        if (tb__mid_push(&r->nums, &x))
            return tb__nomem(r);
        if ((st = tb__adv(r)))
            return st;
        if (lx->type == TB__T_COMMA) {
            if ((st = tb__adv(r)))
                return st;
            if (!tb__starts_value(lx->type)) {
                char found[96];
                TB__FOUND(r, found);
                return TB__MID_ERR(r, lx->loc, "expected a value after ',', found %s", found);
            }
        }
    }
    size_t nn = r->nums.len - nums0;
    const tb__mid_num *nums = tb__slot(&r->nums, nums0);
    if (lx->type == TB__T_RBRACKET) {
        if (nn > INT32_MAX)
            return TB__MID_ERR(r, v->loc, "list with more than %d elements", INT32_MAX);
        v->type = TB_MID_VECTOR;
        v->count = (int)nn;
        double *d = NULL;
        if (nn) {
            if (!(d = tb__mid_alloc(r, nn * sizeof *d)))
                return tb__nomem(r);
            for (size_t i = 0; i < nn; i++)
                d[i] = nums[i].number;
        }
        v->numbers = d;
        r->nums.len = nums0;
        return tb__adv(r);
    }
    /* Something else follows: the numbers so far become generic values. */
    for (size_t i = 0; i < nn; i++) {
        tb_mid_value x;
        memset(&x, 0, sizeof x);
        x.type = TB_MID_NUMBER;
        x.number = nums[i].number;
        x.loc = nums[i].loc;
        if (tb__mid_push(&r->values, &x))
            return tb__nomem(r);
    }
    r->nums.len = nums0;
    if ((st = tb__parse_items(r, NULL, v->loc, depth, false)))
        return st;
    size_t n = r->values.len - first;
    if (n > INT32_MAX)
        return TB__MID_ERR(r, v->loc, "list with more than %d elements", INT32_MAX);
    const tb_mid_value *items = tb__slot(&r->values, first);
    bool numbers = true;
    for (size_t i = 0; i < n && numbers; i++)
        numbers = items[i].type == TB_MID_NUMBER;
    v->count = (int)n;
    if (numbers) {
        v->type = TB_MID_VECTOR;
        double *d = NULL;
        if (n) {
            d = tb__mid_alloc(r, n * sizeof *d);
            if (!d)
                return tb__nomem(r);
            for (size_t i = 0; i < n; i++)
                d[i] = items[i].number;
        }
        v->numbers = d;
    } else {
        v->type = TB_MID_LIST;
        void *p;
        if ((st = tb__to_arena(r, items, n, sizeof *items, &p)))
            return st;
        v->items = p;
    }
    r->values.len = first;
    return tb__adv(r);
}

/* name( ... ), and file("path"). The name is the previous token. */
static tb_status tb__parse_call(tb_mid_reader *r, tb_mid_value *v, const char *name, int depth)
{
    if (depth > TB_MID_MAX_DEPTH)
        return tb__too_deep(r);
    size_t first = r->values.len;
    tb_status st = tb__parse_items(r, name, v->loc, depth, true);
    if (st)
        return st;
    size_t n = r->values.len - first;
    if (n > INT32_MAX)
        return TB__MID_ERR(r, v->loc, "call with more than %d arguments", INT32_MAX);
    const tb_mid_value *items = tb__slot(&r->values, first);
    if (name[0] == 'f' && strcmp(name, "file") == 0) { /* most calls are transforms: skip the strcmp call */
        if (n != 1 || items[0].type != TB_MID_STRING)
            return TB__MID_ERR(r, v->loc, "file() takes one string: file(\"path/to/data\")");
        v->type = TB_MID_FILE;
        if ((st = tb__mid_resolve_ref(r, items[0].text, items[0].loc, &v->ref)))
            return st;
    } else {
        v->type = TB_MID_CALL;
        v->name = name;
        v->count = (int)n;
        void *p;
        if ((st = tb__to_arena(r, items, n, sizeof *items, &p)))
            return st;
        v->items = p;
    }
    r->values.len = first;
    return tb__adv(r);
}

/* name = value (the name is the current token). */
static tb_status tb__parse_attr(tb_mid_reader *r, int depth)
{
    tb__mid_lexer *lx = &r->lx;
    tb_mid_attr a = {.loc = lx->loc};
    if (!(a.name = tb__name(r)))
        return tb__nomem(r);
    tb_status st = tb__adv(r);
    if (st)
        return st;
    if (lx->type != TB__T_EQUAL) {
        char found[96];
        TB__FOUND(r, found);
        return TB__MID_ERR(r, lx->loc, "expected '=' after attribute name '%.40s', found %s", a.name, found);
    }
    if ((st = tb__adv(r)) || (st = tb__parse_value(r, &a.value, depth, a.name)))
        return st;
    if (tb__push_attr(r, &a))
        return tb__nomem(r);
    return TB_OK;
}

/* The attributes on r->attrs from `first`, checked for repeats and moved
 * into the arena. */
static tb_status tb__take_attrs(tb_mid_reader *r, size_t first, tb_mid_attr **out, int *count)
{
    size_t n = r->attrs.len - first;
    if (n > INT32_MAX)
        return tb_error(TB_ERR_FORMAT, "%s: too many attributes", r->lx.name);
    const tb_mid_attr *a = tb__slot(&r->attrs, first);
    tb_status st = tb__check_duplicates(r, a, n);
    if (st)
        return st;
    void *p;
    if ((st = tb__to_arena(r, a, n, sizeof *a, &p)))
        return st;
    *out = p;
    *count = (int)n;
    r->attrs.len = first;
    return TB_OK;
}

/* { name = value ... } as a value. */
static tb_status tb__parse_block(tb_mid_reader *r, tb_mid_value *v, int depth)
{
    tb__mid_lexer *lx = &r->lx;
    if (depth > TB_MID_MAX_DEPTH)
        return tb__too_deep(r);
    size_t first = r->attrs.len;
    tb_status st = tb__adv(r);
    if (st)
        return st;
    char found[96];
    for (;;) {
        if (lx->type == TB__T_RBRACE)
            break;
        if (lx->type == TB__T_IDENT) {
            if ((st = tb__parse_attr(r, depth + 1)))
                return st;
            continue;
        }
        if (lx->type == TB__T_EOF)
            return TB__MID_ERR(r, lx->loc, "expected '}' to close the block opened at %ld:%ld, found end of file",
                               v->loc.line, v->loc.col);
        TB__FOUND(r, found);
        return TB__MID_ERR(r, lx->loc,
                           "expected an attribute name or '}' to close the block opened at %ld:%ld, found %s",
                           v->loc.line, v->loc.col, found);
    }
    v->type = TB_MID_BLOCK;
    tb_mid_attr *attrs;
    if ((st = tb__take_attrs(r, first, &attrs, &v->count)))
        return st;
    v->attrs = attrs;
    return tb__adv(r);
}

static tb_status tb__parse_value(tb_mid_reader *r, tb_mid_value *v, int depth, const char *attr)
{
    tb__mid_lexer *lx = &r->lx;
    memset(v, 0, sizeof *v);
    v->loc = lx->loc;
    switch (lx->type) {
    case TB__T_NUMBER:
        v->type = TB_MID_NUMBER;
        v->number = lx->number;
        return tb__adv(r);
    case TB__T_STRING:
        v->type = TB_MID_STRING;
        if (!(v->text = tb__copy_text(r)))
            return tb__nomem(r);
        return tb__adv(r);
    case TB__T_IDENT: {
        const char *name = tb__name(r);
        if (!name)
            return tb__nomem(r);
        tb_status st = tb__adv(r);
        if (st)
            return st;
        if (lx->type == TB__T_LPAREN)
            return tb__parse_call(r, v, name, depth);
        v->type = TB_MID_SYMBOL;
        v->text = name;
        return TB_OK;
    }
    case TB__T_LBRACKET:
        return tb__parse_list(r, v, depth);
    case TB__T_LBRACE:
        return tb__parse_block(r, v, depth);
    default: {
        char found[96];
        TB__FOUND(r, found);
        return TB__MID_ERR(r, lx->loc, "expected a value for '%.40s', found %s", attr ? attr : "?", found);
    }
    }
}

/* "(the file is MID 1.3; this reader knows MID 1.0)" when the file is newer. */
static const char *tb__version_note(const tb_mid_reader *r, char *buf, size_t size)
{
    buf[0] = '\0';
    if (r->major == TB_MID_VERSION_MAJOR && r->minor > TB_MID_VERSION_MINOR)
        snprintf(buf, size, " (the file is MID %d.%d; this reader knows MID %d.%d)", r->major, r->minor,
                 TB_MID_VERSION_MAJOR, TB_MID_VERSION_MINOR);
    return buf;
}

static tb_status tb__unknown_kind(tb_mid_reader *r, const char *name, tb_mid_loc loc)
{
    char note[96];
    return TB__MID_ERR(r, loc,
                       "unknown object kind '%.40s'%s (expected sphere, cube, cylinder, cone, pyramid, "
                       "prism, torus, polygons, conic, square_arch, round_arch, union, intersection, "
                       "difference, material, point_light, spot_light, directional_light or camera)",
                       name, tb__version_note(r, note, sizeof note));
}

/* KEYWORD [NAME] { entries }: the keyword was the previous token (code k, at
 * loc); the current token is the name or '{'. A top-level object stops on its
 * closing brace (so the reader does not read past the object it returns). */
static tb_status tb__parse_object(tb_mid_reader *r, tb__mid_node *node, int k, tb_mid_loc loc, int depth,
                                  bool top)
{
    tb__mid_lexer *lx = &r->lx;
    memset(node, 0, sizeof *node);
    node->keyword = k;
    node->loc = loc;
    const char *kw = tb__mid_keyword_name(k);
    char found[96];
    tb_status st;
    if (lx->type == TB__T_STRING) {
        if (!(node->name = tb__copy_text(r)))
            return tb__nomem(r);
        if ((st = tb__adv(r)))
            return st;
    }
    if (lx->type != TB__T_LBRACE) {
        TB__FOUND(r, found);
        return TB__MID_ERR(r, lx->loc, "expected '{' to start the body of '%s', found %s", kw, found);
    }
    if (depth > TB_MID_MAX_DEPTH)
        return tb__too_deep(r);
    bool csg = k < TB_PRIM_COUNT && tb_prim_is_csg((tb_prim_kind)k);
    size_t attrs0 = r->attrs.len, nodes0 = r->nodes.len;
    if ((st = tb__adv(r)))
        return st;
    for (;;) {
        if (lx->type == TB__T_RBRACE)
            break;
        if (lx->type == TB__T_EOF)
            return TB__MID_ERR(r, lx->loc, "expected '}' to close '%s' opened at %ld:%ld, found end of file", kw,
                               loc.line, loc.col);
        if (lx->type != TB__T_IDENT) {
            TB__FOUND(r, found);
            return TB__MID_ERR(r, lx->loc, "expected an attribute name%s or '}' to close '%s' opened at %ld:%ld, found %s",
                               csg ? ", an object" : "", kw, loc.line, loc.col, found);
        }
        /* An attribute (name =) or a child object (kind { or kind "name"). */
        tb_mid_attr a = {.loc = lx->loc};
        if (!(a.name = tb__name(r)))
            return tb__nomem(r);
        if ((st = tb__adv(r)))
            return st;
        if (lx->type == TB__T_EQUAL) {
            if ((st = tb__adv(r)) || (st = tb__parse_value(r, &a.value, depth + 1, a.name)))
                return st;
            if (tb__push_attr(r, &a))
                return tb__nomem(r);
            continue;
        }
        if (lx->type != TB__T_LBRACE && lx->type != TB__T_STRING) {
            TB__FOUND(r, found);
            return TB__MID_ERR(r, lx->loc, "expected '=' after attribute name '%.40s', found %s", a.name, found);
        }
        int ck = tb__mid_keyword(a.name);
        if (!csg) {
            if (ck >= 0)
                return TB__MID_ERR(r, a.loc, "'%s' cannot contain objects (only union, intersection and difference can)",
                                   kw);
            TB__FOUND(r, found);
            return TB__MID_ERR(r, lx->loc, "expected '=' after attribute name '%.40s', found %s", a.name, found);
        }
        if (ck < 0)
            return tb__unknown_kind(r, a.name, a.loc);
        if (ck >= TB_PRIM_COUNT)
            return TB__MID_ERR(r, a.loc, "a %s cannot be part of a %s (CSG nodes contain primitives and CSG nodes)",
                               a.name, kw);
        tb__mid_node child;
        if ((st = tb__parse_object(r, &child, ck, a.loc, depth + 1, false)))
            return st;
        if (tb__mid_push(&r->nodes, &child))
            return tb__nomem(r);
    }
    /* Closing brace: move the collected entries into the arena. */
    if ((st = tb__take_attrs(r, attrs0, &node->attrs, &node->nattrs)))
        return st;
    size_t nn = r->nodes.len - nodes0;
    void *p;
    if ((st = tb__to_arena(r, tb__slot(&r->nodes, nodes0), nn, sizeof(tb__mid_node), &p)))
        return st;
    node->children = p;
    node->nchildren = (int)nn;
    r->nodes.len = nodes0;
    return top ? TB_OK : tb__adv(r);
}

tb_status tb__mid_parse_header(tb_mid_reader *r)
{
    tb__mid_lexer *lx = &r->lx;
    pthread_once(&tb__intern_once, tb__intern_build);
    char found[96];
    tb_status st = tb__adv(r);
    if (st)
        return st;
    if (lx->type != TB__T_IDENT || lx->len != 3 || memcmp(lx->text, "mid", 3) != 0 || lx->loc.line != 1 ||
        lx->loc.col != 1) {
        TB__FOUND(r, found);
        return TB__MID_ERR(r, lx->loc, "expected the version header 'mid 1' at the start of the file, found %s",
                           found);
    }
    if ((st = tb__adv(r)))
        return st;
    if (lx->type != TB__T_NUMBER || lx->loc.line != 1) {
        TB__FOUND(r, found);
        return TB__MID_ERR(r, lx->loc, "expected a version number after 'mid' on the first line (e.g. 'mid 1'), found %s",
                           found);
    }
    /* MAJOR or MAJOR.MINOR, digits only. */
    const char *t = lx->text;
    size_t n = lx->len, i = 0;
    long major = 0, minor = 0;
    bool ok = n > 0 && t[0] >= '0' && t[0] <= '9';
    for (; ok && i < n && t[i] != '.'; i++) {
        ok = t[i] >= '0' && t[i] <= '9' && major < 100000;
        major = major * 10 + (t[i] - '0');
    }
    if (ok && i < n) {
        i++;
        ok = i < n;
        for (; ok && i < n; i++) {
            ok = t[i] >= '0' && t[i] <= '9' && minor < 100000;
            minor = minor * 10 + (t[i] - '0');
        }
    }
    if (!ok)
        return TB__MID_ERR(r, lx->loc, "malformed version '%.*s' (expected MAJOR or MAJOR.MINOR, e.g. 'mid 1')",
                           n > 40 ? 40 : (int)n, t);
    if (major != TB_MID_VERSION_MAJOR)
        return TB__MID_ERR(r, lx->loc, "unsupported MID version %.*s (this reader reads MID %d.x)",
                           n > 40 ? 40 : (int)n, t, TB_MID_VERSION_MAJOR);
    r->major = (int)major;
    r->minor = (int)minor;
    return TB_OK;
}

tb_status tb__mid_parse_item(tb_mid_reader *r, tb__mid_node *node, bool *eof)
{
    tb__mid_lexer *lx = &r->lx;
    *eof = false;
    tb_status st = tb__adv(r);
    if (st)
        return st;
    if (lx->type == TB__T_EOF) {
        *eof = true;
        return TB_OK;
    }
    if (lx->type != TB__T_IDENT) {
        char found[96];
        TB__FOUND(r, found);
        return TB__MID_ERR(r, lx->loc, "expected an object such as 'sphere { }', found %s", found);
    }
    tb_mid_loc loc = lx->loc;
    int k = tb__mid_keyword_n(lx->text, lx->len);
    if (k < 0) {
        char name[48];
        snprintf(name, sizeof name, "%.*s", lx->len > 40 ? 40 : (int)lx->len, lx->text);
        return tb__unknown_kind(r, name, loc);
    }
    if ((st = tb__adv(r)))
        return st;
    return tb__parse_object(r, node, k, loc, 1, true);
}
