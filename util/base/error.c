#include "util/base/error.h"

#include <stdio.h>
#include <string.h>

/* Long enough for a path, a location and a sentence. */
#define TB__ERROR_LEN 1024

static _Thread_local char tb__message[TB__ERROR_LEN];

tb_status tb_verror(tb_status st, const char *fmt, va_list ap)
{
    vsnprintf(tb__message, sizeof tb__message, fmt, ap);
    return st;
}

tb_status tb_error(tb_status st, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    tb_verror(st, fmt, ap);
    va_end(ap);
    return st;
}

tb_status tb_error_context(tb_status st, const char *fmt, ...)
{
    char old[TB__ERROR_LEN];
    memcpy(old, tb__message, sizeof old);
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(tb__message, sizeof tb__message, fmt, ap);
    va_end(ap);
    /* Append ": old", truncated to fit (a capped message is intended; done by
     * hand because gcc -Wformat-truncation rejects the snprintf spelling). */
    if (n >= 0 && (size_t)n + 2 < sizeof tb__message) {
        size_t used = (size_t)n;
        memcpy(tb__message + used, ": ", 2);
        used += 2;
        size_t len = strnlen(old, sizeof old);
        if (len > sizeof tb__message - 1 - used)
            len = sizeof tb__message - 1 - used;
        memcpy(tb__message + used, old, len);
        tb__message[used + len] = '\0';
    }
    return st;
}

const char *tb_last_error(void) { return tb__message; }

void tb_clear_error(void) { tb__message[0] = '\0'; }

const char *tb_status_name(tb_status st)
{
    switch (st) {
    case TB_OK: return "ok";
    case TB_ERR_ARG: return "invalid argument";
    case TB_ERR_NOMEM: return "out of memory";
    case TB_ERR_IO: return "I/O error";
    case TB_ERR_FORMAT: return "format error";
    case TB_ERR_UNSUPPORTED: return "unsupported";
    case TB_ERR_NUMERIC: return "numerical failure";
    case TB_ERR_NOT_FOUND: return "not found";
    case TB_ERR_DEVICE: return "device error";
    }
    return "unknown status";
}
