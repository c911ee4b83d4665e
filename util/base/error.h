/* Error reporting shared by every module: a status code returned by the call,
 * plus a thread-local message saying what went wrong and where. */
#ifndef TB_UTIL_BASE_ERROR_H
#define TB_UTIL_BASE_ERROR_H

#include <stdarg.h>

/* Result of a fallible call; TB_OK is zero so `if (st) ...` reads naturally. */
typedef enum tb_status {
    TB_OK = 0,
    TB_ERR_ARG,         /* caller passed an invalid argument (NaN, NULL, out of range) */
    TB_ERR_NOMEM,       /* allocation failed */
    TB_ERR_IO,          /* the operating system refused a read/write/open */
    TB_ERR_FORMAT,      /* input file is malformed or truncated */
    TB_ERR_UNSUPPORTED, /* valid input that this build cannot handle */
    TB_ERR_NUMERIC,     /* numerical failure: singular matrix, no convergence */
    TB_ERR_NOT_FOUND,   /* a looked-up key, file or device does not exist */
    TB_ERR_DEVICE,      /* GPU/driver failure */
} tb_status;

/* Records `fmt` as this thread's last error message and returns `st`. */
tb_status tb_error(tb_status st, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

/* tb_error() taking a va_list. */
tb_status tb_verror(tb_status st, const char *fmt, va_list ap);

/* Prefixes this thread's last message with `fmt: ` (adds context on the way up); returns `st`. */
tb_status tb_error_context(tb_status st, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

/* This thread's last error message ("" if none was recorded). */
const char *tb_last_error(void);

/* Clears this thread's last error message. */
void tb_clear_error(void);

/* Short constant name of a status ("format error", ...). */
const char *tb_status_name(tb_status st);

#endif
