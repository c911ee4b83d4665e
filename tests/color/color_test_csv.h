/* Test-side CSV reader for the colour tables, written independently of the
 * build-time generator so the tests can compare the compiled tables with the
 * files they come from. */
#ifndef TB_TESTS_COLOR_CSV_H
#define TB_TESTS_COLOR_CSV_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TB_TEST_CSV_MAX_ROWS 256
#define TB_TEST_CSV_MAX_COLS 12

/* A numeric table: column c, row r is v[c][r]. */
typedef struct tb_test_csv {
    int rows, cols;
    char names[TB_TEST_CSV_MAX_COLS][32];
    double v[TB_TEST_CSV_MAX_COLS][TB_TEST_CSV_MAX_ROWS];
} tb_test_csv;

/* Reads `path` ('#' comments, one header line, numeric rows); 0 on success. */
static inline int tb_test_csv_read(const char *path, tb_test_csv *t)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return -1;
    char line[1024];
    memset(t, 0, sizeof *t);
    int header = 0;
    while (fgets(line, sizeof line, f)) {
        if (line[0] == '#' || line[0] == '\n' || line[0] == '\r')
            continue;
        char *save = NULL;
        int c = 0;
        for (char *tok = strtok_r(line, ",\r\n", &save); tok; tok = strtok_r(NULL, ",\r\n", &save), c++) {
            if (c >= TB_TEST_CSV_MAX_COLS)
                goto fail;
            if (!header) {
                snprintf(t->names[c], sizeof t->names[c], "%s", tok);
            } else {
                char *end;
                if (t->rows >= TB_TEST_CSV_MAX_ROWS)
                    goto fail;
                t->v[c][t->rows] = strtod(tok, &end);
                if (end == tok)
                    goto fail;
            }
        }
        if (!header) {
            t->cols = c;
            header = 1;
        } else {
            if (c != t->cols)
                goto fail;
            t->rows++;
        }
    }
    fclose(f);
    return t->rows > 0 ? 0 : -1;
fail:
    fclose(f);
    return -1;
}

/* Reads a file of the source tree, failing the test if it cannot. */
#define TB_TEST_READ_CSV(rel, t)                                                        \
    do {                                                                                \
        char tb__path[1024];                                                            \
        snprintf(tb__path, sizeof tb__path, "%s/%s", TB_SOURCE_DIR, rel);               \
        if (tb_test_csv_read(tb__path, t) != 0)                                         \
            fail_msg("cannot read table %s", tb__path);                                 \
    } while (0)

#endif
