/* String helpers shared by every module. */
#ifndef TB_UTIL_BASE_STR_H
#define TB_UTIL_BASE_STR_H

/* A malloc'ed copy of `s`; NULL for a NULL `s` or when out of memory. */
char *tb_strdup(const char *s);

#endif
