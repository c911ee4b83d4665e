/* Small helpers for input streams shared by the file readers. */
#ifndef TB_UTIL_BASE_STREAM_H
#define TB_UTIL_BASE_STREAM_H

#include <stdio.h>

/* Bytes left in `f` from its current position, or -1 if the stream cannot
 * seek (a pipe). Readers use it to refuse a header that promises more data
 * than the file holds, before allocating for it. */
long long tb_stream_remaining(FILE *f);

#endif
