/* What the parts of host/dist share: the accounts, the clock and the
 * message tags. Not installed (an _internal.h header). */
#ifndef TB_HOST_DIST_DIST_INTERNAL_H
#define TB_HOST_DIST_DIST_INTERNAL_H

#include <stdint.h>

#include "host/dist/dist.h"

/* Point-to-point message tags; collectives travel apart from them. */
enum {
    TB__TAG_REQUEST = 11, /* worker -> 0: int, tiles wanted */
    TB__TAG_GRANT = 12,   /* 0 -> worker: int[2], first tile and count (0: none left this pass) */
    TB__TAG_TILE = 13,    /* worker -> 0: a packed film tile */
    TB__TAG_SKIP = 14,    /* worker -> 0: int, a tile skipped after a cancel */
};

/* Adds to this rank's totals (tb_dist_my_stats). */
void tb__dist_account(double work, double wait, uint64_t bytes, uint64_t messages, uint64_t units);

/* Monotonic seconds. */
double tb__dist_now(void);

#endif
