/* Internals of the MID reader shared by its source files: the lexer
 * (mid_lexer.c), the schema-free parser that turns one top-level object into
 * a syntax tree (mid_parser.c), and the interpretation of that tree as typed
 * objects (mid_schema.c), driven by mid_reader.c. Not installed. */
#ifndef TB_HOST_SCENE_MID_INTERNAL_H
#define TB_HOST_SCENE_MID_INTERNAL_H

#include <stdbool.h>
#include <stddef.h>
#include <locale.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "host/mid/mid.h"
#include "host/mid/mid_reader.h"
#include "util/base/error.h"
#include "util/container/arena.h"
#include "util/container/array.h"
#include "util/container/hash_table.h"

/* Bytes read from the file at a time; more than a maximal token, so a token
 * never needs a bigger buffer. */
#define TB__MID_BUF ((size_t)256 * 1024)
/* Zero bytes allocated after the buffer's sentinel, so the lexer may load
 * 8 bytes at any position up to the sentinel (word-at-a-time skipping). */
#define TB__MID_BUF_PAD 8

/* Token types. */
typedef enum tb__mid_tok {
    TB__T_EOF = 0,
    TB__T_IDENT,
    TB__T_STRING,
    TB__T_NUMBER,
    TB__T_LBRACE,   /* { */
    TB__T_RBRACE,   /* } */
    TB__T_LBRACKET, /* [ */
    TB__T_RBRACKET, /* ] */
    TB__T_LPAREN,   /* ( */
    TB__T_RPAREN,   /* ) */
    TB__T_EQUAL,    /* = */
    TB__T_COMMA,    /* , */
} tb__mid_tok;

/* The lexer: a buffered byte stream and the current token. */
typedef struct tb__mid_lexer {
    FILE *fp;
    const char *name;     /* file name for messages */
    char *buf;            /* TB__MID_BUF + 1 + TB__MID_BUF_PAD bytes; buf[end] == 0 is a sentinel */
    size_t pos, end;      /* next byte, end of valid bytes */
    size_t keep;          /* bytes from here on survive a refill (the token being read) */
    uint64_t base;        /* file offset of buf[0] */
    bool eof;             /* fp has no more bytes */
    tb_status io_status;  /* TB_ERR_IO after a read error */
    long line;            /* line of buf[pos] */
    uint64_t line_start;  /* file offset of the first byte of that line */
    /* The current token. */
    tb__mid_tok type;
    tb_mid_loc loc;
    const char *text;     /* IDENT, NUMBER: raw bytes in buf; STRING: unescaped, in str */
    size_t len;           /* bytes of text */
    double number;        /* NUMBER */
    char *str;            /* TB_MID_MAX_TOKEN + 1 bytes of scratch */
} tb__mid_lexer;

/* Sets up `lx` to read `fp`. TB_ERR_NOMEM on failure. */
tb_status tb__mid_lexer_init(tb__mid_lexer *lx, FILE *fp, const char *name);
/* Frees the lexer's buffers (not fp). */
void tb__mid_lexer_free(tb__mid_lexer *lx);
/* Reads the next token into lx->type/loc/text/len/number. */
tb_status tb__mid_lex(tb__mid_lexer *lx);
/* Records "NAME:LINE:COL: error: MESSAGE" and returns TB_ERR_FORMAT. */
tb_status tb__mid_errorf(const tb__mid_lexer *lx, tb_mid_loc loc, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* A short description of the current token for "found ..." ("end of file",
 * "'}'", "number 1.5", "identifier 'foo'", "string \"x\""), written to out. */
void tb__mid_describe_token(const tb__mid_lexer *lx, char *out, size_t size);
/* File offset of the next unread byte. */
uint64_t tb__mid_lexer_offset(const tb__mid_lexer *lx);

/* Top-level and nested object keywords: the primitive kinds first (same
 * values as tb_prim_kind), then the others. */
enum {
    TB__K_MATERIAL = TB_PRIM_COUNT,
    TB__K_POINT_LIGHT,
    TB__K_SPOT_LIGHT,
    TB__K_DIRECTIONAL_LIGHT,
    TB__K_CAMERA,
    TB__K_COUNT,
};
/* Keyword code of `name`, or -1. */
int tb__mid_keyword(const char *name);
/* The keyword of code k. */
const char *tb__mid_keyword_name(int k);

/* One object as written: keyword, name, attributes, child objects. */
typedef struct tb__mid_node tb__mid_node;
struct tb__mid_node {
    int keyword;              /* TB_PRIM_* or TB__K_* */
    const char *name;         /* NULL if none */
    tb_mid_loc loc;           /* of the keyword */
    tb_mid_attr *attrs;       /* in file order */
    int nattrs;
    tb__mid_node *children;   /* in file order */
    int nchildren;
};

/* Name and position of one attribute, for the sort that finds repeats. */
typedef struct tb__name_idx {
    const char *name;
    int idx;
} tb__name_idx;

/* A number of a list being parsed, with its position (needed if the list
 * turns out not to be all numbers). */
typedef struct tb__mid_num {
    double number;
    tb_mid_loc loc;
} tb__mid_num;

/* A file reference already checked, kept so a file used by many objects is
 * looked up once. */
#define TB__MID_REF_CACHE_MAX 4096

/* The reader. */
struct tb_mid_reader {
    tb__mid_lexer lx;
    FILE *owned_fp;           /* closed by tb_mid_reader_close (NULL for streams and stdin) */
    char *name;               /* for messages */
    char *base_dir;           /* absolute folder that file references resolve against */
    bool header_done;
    int major, minor;         /* the file's version */
    tb_status failed;         /* sticky error */
    char *failed_msg;         /* its message, given again on later calls */
    tb_arena item;            /* everything of the current item; reset per item */
    tb_arena keep;            /* named materials, the camera: live until close */
    tb_array values;          /* scratch stack of tb_mid_value while parsing lists/calls */
    tb_array nums;            /* scratch stack of tb__mid_num while parsing lists */
    tb_array attrs;           /* scratch stack of tb_mid_attr */
    tb_array nodes;           /* scratch stack of tb__mid_node */
    tb_array refs;            /* scratch tb_mid_ref while collecting an object's references */
    tb_array order;           /* scratch tb__name_idx for duplicate detection */
    tb_htab materials;        /* name -> tb_mid_material * (in keep) */
    tb_htab checked;          /* resolved path -> 1 for files found to exist */
    const tb_mid_camera *camera;
    /* Storage handed out by next(). */
    tb_mid_object *object;
    tb_mid_light light;
    /* Bump pointer into the current block of `item` (see tb__mid_alloc). */
    char *bump, *bump_end;
};

/* AddressSanitizer builds allocate every piece from the arena itself, so
 * each one keeps its own poisoned bounds (the fuzzer relies on that). */
#if defined(__SANITIZE_ADDRESS__)
#define TB__MID_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define TB__MID_ASAN 1
#endif
#endif

/* Bytes of the blocks tb__mid_alloc takes from the item arena. */
#define TB__MID_BLOCK ((size_t)8192)

/* tb__mid_alloc when the current block is full. */
void *tb__mid_alloc_slow(tb_mid_reader *r, size_t n);

/* n bytes (16-byte aligned) of the current item: an inline bump in blocks of
 * the item arena, since a parse makes many small allocations. NULL when out
 * of memory. */
static inline void *tb__mid_alloc(tb_mid_reader *r, size_t n)
{
#ifdef TB__MID_ASAN
    return tb_arena_alloc(&r->item, n);
#else
    size_t k = (n + 15) & ~(size_t)15;
    if (k >= n && (uintptr_t)r->bump_end - (uintptr_t)r->bump >= k) {
        void *p = r->bump;
        r->bump += k;
        return p;
    }
    return tb__mid_alloc_slow(r, n);
#endif
}

/* Parses the version header. */
tb_status tb__mid_parse_header(tb_mid_reader *r);
/* Parses the next top-level object into *node (in r->item); *eof is set at
 * the end of the file instead. */
tb_status tb__mid_parse_item(tb_mid_reader *r, tb__mid_node *node, bool *eof);
/* Resolves file reference `text` (checking the file exists) into *ref. */
tb_status tb__mid_resolve_ref(tb_mid_reader *r, const char *text, tb_mid_loc loc, tb_mid_ref *ref);

/* Interprets a parsed top-level node as an item (mid_schema.c). */
tb_status tb__mid_interpret(tb_mid_reader *r, const tb__mid_node *node, tb_mid_item *item);

/* tb_array_push with the common case (room left) inline: the reader pushes
 * every value and attribute it parses. */
static inline __attribute__((always_inline)) tb_status tb__mid_push_sz(tb_array *a, const void *elem,
                                                                        size_t size)
{
    /* size is a constant here (see tb__mid_push), so the copy is a few
     * moves instead of a memcpy call. */
    if (a->len < a->cap && a->elem_size == size) {
        memcpy((char *)a->data + a->len * size, elem, size);
        a->len++;
        return TB_OK;
    }
    return tb_array_push(a, elem);
}
/* Pushes *elem (whose type must be the array's element type) on a. */
#define tb__mid_push(a, elem) tb__mid_push_sz((a), (elem), sizeof *(elem))

/* The "C" locale for numbers (a '.' decimal point whatever the program's
 * LC_NUMERIC), created once; (locale_t)0 if it could not be. Used with
 * uselocale() around strtod and printf of numbers. */
locale_t tb__mid_c_locale(void);

/* Keyword code of the n bytes at s, or -1. */
int tb__mid_keyword_n(const char *s, size_t n);

/* The identity transform, as a constant. */
extern const tb_transform tb__mid_identity;

/* The default material (docs/mid.md, section 7), as a constant. */
extern const tb_mid_material tb__mid_default_material;

/* Error at `loc` of the reader's file (see tb__mid_errorf). */
#define TB__MID_ERR(r, loc, ...) tb__mid_errorf(&(r)->lx, (loc), __VA_ARGS__)

#endif
