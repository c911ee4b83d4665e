/* util/base/progress: what the bar draws, when it stays silent, and exact
 * counts under concurrent updates. */
#define _XOPEN_SOURCE 700 /* posix_openpt, grantpt, unlockpt, ptsname */
#include "tb_test.h"

#include <fcntl.h>
#include <omp.h>
#include <poll.h>
#include <string.h>
#include <unistd.h>

#include "util/base/progress.h"

/* Everything written to `f` so far. */
static char *tb__slurp(FILE *f)
{
    fflush(f);
    long n = ftell(f);
    assert_true(n >= 0);
    char *buf = calloc((size_t)n + 1, 1);
    assert_non_null(buf);
    rewind(f);
    assert_int_equal(fread(buf, 1, (size_t)n, f), (size_t)n);
    fseek(f, 0, SEEK_END);
    return buf;
}

static void test_forced_bar_shows_percent_and_eta(void **state)
{
    (void)state;
    FILE *f = tmpfile();
    assert_non_null(f);
    tb_progress p;
    assert_int_equal(tb_progress_start(&p, "render", 100, f, TB_PROGRESS_FORCE), TB_OK);
    assert_true(tb_progress_active(&p));
    tb_progress_add(&p, 42); /* the first update draws at once */
    char *s = tb__slurp(f);
    print_message("%s\n", s);
    assert_non_null(strstr(s, "render ["));
    assert_non_null(strstr(s, " 42%"));
    assert_non_null(strstr(s, " elapsed, ETA "));
    /* The bar is 30 cells; 42% fills floor(0.42 * 30) = 12 of them. */
    char *open = strchr(s, '['), *close = strchr(s, ']');
    assert_true(open && close && close - open - 1 == 30);
    assert_int_equal(strspn(open + 1, "#"), 12);
    assert_null(strchr(s, '\n')); /* still on one line */
    free(s);

    tb_progress_add(&p, 58);
    tb_progress_finish(&p);
    s = tb__slurp(f);
    size_t n = strlen(s);
    assert_true(n > 0 && s[n - 1] == '\n');
    char *last = strrchr(s, '\r');
    assert_non_null(last);
    assert_non_null(strstr(last, "100%"));
    assert_non_null(strstr(last, "[##############################]"));
    assert_null(strstr(last, "ETA")); /* the final line has no estimate */
    tb_progress_finish(&p);           /* a second finish adds nothing */
    char *s2 = tb__slurp(f);
    assert_string_equal(s, s2);
    free(s);
    free(s2);
    fclose(f);
}

static void test_silent_when_not_a_terminal(void **state)
{
    (void)state;
    FILE *f = tmpfile();
    assert_non_null(f);
    tb_progress p;
    assert_int_equal(tb_progress_start(&p, "work", 10, f, 0), TB_OK);
    assert_false(tb_progress_active(&p));
    for (int i = 0; i < 10; i++)
        tb_progress_add(&p, 1);
    tb_progress_finish(&p);
    assert_int_equal(tb_progress_done(&p), 10); /* still counts */
    fflush(f);
    assert_int_equal(ftell(f), 0);
    assert_int_equal(tb_progress_start(&p, "x", -1, f, 0), TB_ERR_ARG);
    fclose(f);
}

/* On a real terminal (a pseudo-terminal here) the bar draws unless
 * TB_NO_PROGRESS is set. */
static void test_terminal_and_environment(void **state)
{
    (void)state;
    int master = posix_openpt(O_RDWR | O_NOCTTY);
    /* No pseudo-terminal is a broken test machine (in a chroot: mount
     * devpts), not a pass: the terminal case is the one users see. */
    if (master < 0 || grantpt(master) != 0 || unlockpt(master) != 0)
        fail_msg("no pseudo-terminal (posix_openpt/grantpt/unlockpt failed): mount /dev/pts");
    int slave = open(ptsname(master), O_RDWR | O_NOCTTY);
    assert_true(slave >= 0);
    FILE *tty = fdopen(slave, "w");
    assert_non_null(tty);
    const char *old = getenv("TB_NO_PROGRESS");
    char *saved = old ? strdup(old) : NULL;

    setenv("TB_NO_PROGRESS", "1", 1);
    tb_progress p;
    assert_int_equal(tb_progress_start(&p, "tty", 4, tty, 0), TB_OK);
    assert_false(tb_progress_active(&p));
    assert_int_equal(tb_progress_start(&p, "tty", 4, tty, TB_PROGRESS_FORCE), TB_OK);
    assert_true(tb_progress_active(&p)); /* forcing wins */

    unsetenv("TB_NO_PROGRESS");
    assert_int_equal(tb_progress_start(&p, "tty", 4, tty, 0), TB_OK);
    assert_true(tb_progress_active(&p));
    tb_progress_add(&p, 1);
    tb_progress_add(&p, 3);
    tb_progress_finish(&p);
    char buf[4096] = {0};
    size_t got = 0;
    struct pollfd pfd = {master, POLLIN, 0};
    while (got < sizeof buf - 1 && poll(&pfd, 1, 200) > 0) {
        ssize_t r = read(master, buf + got, sizeof buf - 1 - got);
        if (r <= 0)
            break;
        got += (size_t)r;
        if (strstr(buf, "100%"))
            break;
    }
    assert_non_null(strstr(buf, " 25%")); /* the first add drew at once */
    assert_non_null(strstr(buf, "100%"));

    if (saved) {
        setenv("TB_NO_PROGRESS", saved, 1);
        free(saved);
    }
    fclose(tty);
    close(master);
}

/* Many threads adding at once: the count is exact, and the output stays whole
 * lines (one drawer at a time). */
static void test_concurrent_adds_exact(void **state)
{
    (void)state;
    FILE *f = tmpfile();
    assert_non_null(f);
    tb_progress p;
    const int n = 100000;
    assert_int_equal(tb_progress_start(&p, "par", n, f, TB_PROGRESS_FORCE), TB_OK);
#pragma omp parallel for num_threads(8) schedule(dynamic, 64)
    for (int i = 0; i < n; i++)
        tb_progress_add(&p, 1);
    assert_int_equal(tb_progress_done(&p), n);
    tb_progress_finish(&p);
    char *s = tb__slurp(f);
    /* Every drawn line starts with '\r' and the label. */
    int lines = 0;
    for (char *c = strchr(s, '\r'); c; c = strchr(c + 1, '\r')) {
        assert_int_equal(strncmp(c, "\rpar [", 6), 0);
        lines++;
    }
    assert_true(lines >= 2); /* the first add and the finish */
    assert_non_null(strstr(strrchr(s, '\r'), "100%"));
    free(s);
    fclose(f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_forced_bar_shows_percent_and_eta),
        cmocka_unit_test(test_silent_when_not_a_terminal),
        cmocka_unit_test(test_terminal_and_environment),
        cmocka_unit_test(test_concurrent_adds_exact),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
