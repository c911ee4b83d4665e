/* Streaming MID reader: hands out the items of a MID file one at a time, in
 * file order, with memory bounded by the largest single item (plus named
 * materials and the camera, which live until the reader is closed).
 *
 *     tb_mid_reader *r;
 *     tb_mid_item it;
 *     if (tb_mid_reader_open(&r, path)) fail(tb_last_error());
 *     while (!(st = tb_mid_reader_next(r, &it)) && it.type != TB_MID_ITEM_END)
 *         use(&it);                 // valid until the next call
 *     tb_mid_reader_close(r);
 *
 * Every malformed input gives TB_ERR_FORMAT and the message
 * "FILE:LINE:COL: error: ..." (docs/mid.md, section 11). */
#ifndef TB_HOST_SCENE_MID_READER_H
#define TB_HOST_SCENE_MID_READER_H

#include <stdio.h>

#include "host/mid/mid.h"
#include "util/base/error.h"

/* An open MID file being read. */
typedef struct tb_mid_reader tb_mid_reader;

/* Opens the MID file `path` ("-" reads standard input, named "<stdin>", with
 * file references relative to the current directory). TB_ERR_IO if the file
 * cannot be opened; *out is NULL on failure. The header is checked by the
 * first tb_mid_reader_next(). */
tb_status tb_mid_reader_open(tb_mid_reader **out, const char *path);

/* Reads MID text from `fp` (not closed by the reader; fmemopen works).
 * `name` is used in messages; file references resolve against `base_dir`
 * (NULL: the current directory). */
tb_status tb_mid_reader_open_stream(tb_mid_reader **out, FILE *fp, const char *name,
                                    const char *base_dir);

/* The next item; item->type is TB_MID_ITEM_END after the last one. The item
 * and everything it points to stay valid until the next call (named
 * materials and the camera until close). After an error every later call
 * returns the same error. */
tb_status tb_mid_reader_next(tb_mid_reader *r, tb_mid_item *item);

/* The camera read so far, or NULL. */
const tb_mid_camera *tb_mid_reader_camera(const tb_mid_reader *r);

/* The named material `name` defined so far, or NULL. */
const tb_mid_material *tb_mid_reader_material(const tb_mid_reader *r, const char *name);

/* Version of the file's header (0.0 before the first tb_mid_reader_next). */
void tb_mid_reader_version(const tb_mid_reader *r, int *major, int *minor);

/* Bytes of MID text consumed so far. */
uint64_t tb_mid_reader_offset(const tb_mid_reader *r);

/* Bytes the reader holds from the system: read buffer, arenas and scratch
 * stacks (not counting the two hash tables of material names and checked
 * file paths). Stays flat while reading a stream of similar objects. */
size_t tb_mid_reader_memory(const tb_mid_reader *r);

/* Closes the reader (and the file it opened); NULL is allowed. */
void tb_mid_reader_close(tb_mid_reader *r);

#endif
