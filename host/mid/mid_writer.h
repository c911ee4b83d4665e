/* MID writer: the canonical form of docs/mid.md, section 12. Reading back what
 * it writes gives items equal to the ones written (tb_mid_item_equal). */
#ifndef TB_HOST_SCENE_MID_WRITER_H
#define TB_HOST_SCENE_MID_WRITER_H

#include <stdio.h>

#include "host/mid/mid.h"
#include "util/base/error.h"

/* Writes the header line "mid 1". TB_ERR_IO if the stream reports an error. */
tb_status tb_mid_write_header(FILE *fp);

/* Writes one item in canonical form. Named materials an object refers to
 * must have been written before it. TB_ERR_ARG for an item the format cannot
 * express (a NaN or infinite number, an empty CSG node, an unknown kind);
 * TB_ERR_IO if the stream reports an error. */
tb_status tb_mid_write_item(FILE *fp, const tb_mid_item *item);

#endif
