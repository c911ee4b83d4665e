/* Output files that appear whole or not at all: write to a temporary file in
 * the destination folder, then rename it over the final name on success. */
#ifndef TB_UTIL_BASE_OUTFILE_H
#define TB_UTIL_BASE_OUTFILE_H

#include <stdio.h>
#include "util/base/error.h"

/* An output file being written; `fp` is the stream to write to. */
typedef struct tb_outfile {
    FILE *fp;         /* open on the temporary file */
    char *path;       /* final name, taken on commit */
    char *tmp_path;   /* temporary name in the same folder (same filesystem, so rename is atomic);
                       * NULL when `path` is a device or FIFO, written in place (renaming over
                       * /dev/null would replace the device with a file) */
} tb_outfile;

/* Creates the temporary file for `path` (a device or FIFO such as /dev/null
 * or /dev/stdout is opened in place); on failure nothing is left on disk. */
tb_status tb_outfile_open(tb_outfile *of, const char *path);

/* Flushes, closes and renames the temporary file to its final name. On failure
 * the temporary file is removed and any existing file at `path` is untouched. */
tb_status tb_outfile_commit(tb_outfile *of);

/* Closes and removes the temporary file (after a failed write). Safe to call twice. */
void tb_outfile_abort(tb_outfile *of);

#endif
