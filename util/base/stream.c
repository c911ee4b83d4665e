#include "util/base/stream.h"

#include <sys/types.h>

long long tb_stream_remaining(FILE *f)
{
    off_t here = ftello(f);
    if (here < 0 || fseeko(f, 0, SEEK_END) != 0) {
        clearerr(f);
        return -1;
    }
    off_t end = ftello(f);
    if (fseeko(f, here, SEEK_SET) != 0 || end < here) {
        clearerr(f);
        return -1;
    }
    return (long long)(end - here);
}
