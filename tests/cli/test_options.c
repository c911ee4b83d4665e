/* tools/testbed/options.c: every option type parsed into its variable,
 * range and syntax errors with the usage status and a message naming the
 * option and the value, missing values, unknown options, --name=value,
 * "--", optional values, positional arguments, and help text made from the
 * table (every option, the choices, the defaults). */
#include "tb_test.h"

#include <string.h>

#include "commands.h"
#include "options.h"

/* The variables of one test command, reset by tb__fixture. */
typedef struct tb__vars {
    bool flag, n_seen;
    int n, choice;
    uint64_t seed;
    double x, frac, opt;
    const char *path;
    tb_opt_strings tags;
    int custom;
    const char *pos[2];
    char err[1024];
    FILE *errout;
} tb__vars;

static tb__vars V;

/* CUSTOM: "a:b" pairs of digits, stored as a*10+b. */
static int tb__pair(const char *val, void *dest, char *why, size_t len)
{
    if (strlen(val) != 3 || val[1] != ':' || val[0] < '0' || val[0] > '9' || val[2] < '0' || val[2] > '9') {
        snprintf(why, len, "expected a pair D:D, got '%s'", val);
        return 1;
    }
    *(int *)dest = (val[0] - '0') * 10 + (val[2] - '0');
    return 0;
}

static const tb_opt_choice tb__colours[] = {{"red", 1}, {"green", 2}, {"blue", 3}, {NULL, 0}};

#define TB__OPTS                                                                                                     \
    {                                                                                                                \
        {"flag", 'f', TB_OPT_FLAG, &V.flag, .help = "a flag"},                                                      \
        {"count", 'n', TB_OPT_INT, &V.n, .min = 1, .max = 100, .metavar = "N", .help = "a count (default %D)",      \
         .seen = &V.n_seen},                                                                                         \
        {"seed", 0, TB_OPT_UINT64, &V.seed, .metavar = "S", .help = "a seed (default %D)", .flags = TB_OPTF_BASE0}, \
        {"scale", 0, TB_OPT_DOUBLE, &V.x, .min = -2, .max = 2, .metavar = "X", .help = "a scale\nsecond line"},     \
        {"frac", 0, TB_OPT_DOUBLE, &V.frac, .min = 0, .max = 1, .metavar = "F", .help = "open range",               \
         .flags = TB_OPTF_OPEN_MIN | TB_OPTF_OPEN_MAX},                                                              \
        {"adaptive", 0, TB_OPT_DOUBLE, &V.opt, .min = 0, .max = 10, .metavar = "T", .help = "optional value",       \
         .flags = TB_OPTF_OPTIONAL},                                                                                 \
        {.short_name = 'o', .type = TB_OPT_STRING, .dest = &V.path, .metavar = "FILE", .help = "output"},            \
        {"colour", 0, TB_OPT_CHOICE, &V.choice, .help = "a colour (default %D)", .choices = tb__colours},           \
        {"tag", 0, TB_OPT_REPEAT, &V.tags, .metavar = "T", .help = "a tag, again and again"},                       \
        {"pair", 0, TB_OPT_CUSTOM, &V.custom, .metavar = "D:D", .help = "custom", .parse = tb__pair},                \
        {0},                                                                                                         \
    }

static const tb_opt tb__opts[] = TB__OPTS;

static const tb_cli tb__cli = {
    .prog = "testbed demo",
    .err = "testbed demo: ",
    .usage = "IN [OUT] [options]",
    .intro = "A command for the tests.",
    .opts = tb__opts,
    .outro = "Exit status: 0 fine.",
    .pos = V.pos,
    .max_pos = 2,
};

static int tb__setup(void **state)
{
    (void)state;
    memset(&V, 0, sizeof V);
    V.n = 7, V.choice = 2, V.seed = 5;
    V.errout = fmemopen(V.err, sizeof V.err - 1, "w");
    return V.errout ? 0 : -1;
}

static int tb__teardown(void **state)
{
    (void)state;
    fclose(V.errout);
    return 0;
}

/* Parses the words of `line` (at most 30, space-separated) as argv[1..]. */
static int tb__parse(const char *line, int *npos)
{
    static char buf[512];
    char *argv[32] = {"demo"};
    int argc = 1;
    snprintf(buf, sizeof buf, "%s", line);
    for (char *t = strtok(buf, " "); t && argc < 31; t = strtok(NULL, " "))
        argv[argc++] = t;
    argv[argc] = NULL;
    tb_cli cli = tb__cli;
    cli.errout = V.errout;
    int np = 0;
    int rc = tb_cli_parse(&cli, argc, argv, &np);
    fflush(V.errout);
    if (npos)
        *npos = np;
    return rc;
}

static void test_every_type(void **state)
{
    (void)state;
    int npos;
    assert_int_equal(tb__parse("in -f --count 42 --seed 0x10 --scale -1.5 --frac 0.25 -o out.png --colour blue "
                               "--tag a --tag b --pair 3:4 out",
                               &npos),
                     TB_CLI_OK);
    assert_int_equal(npos, 2);
    assert_string_equal(V.pos[0], "in");
    assert_string_equal(V.pos[1], "out");
    assert_true(V.flag);
    assert_int_equal(V.n, 42);
    assert_true(V.n_seen);
    assert_int_equal(V.seed, 16);
    assert_true(V.x == -1.5);
    assert_true(V.frac == 0.25);
    assert_string_equal(V.path, "out.png");
    assert_int_equal(V.choice, 3);
    assert_int_equal(V.tags.n, 2);
    assert_string_equal(V.tags.v[0], "a");
    assert_string_equal(V.tags.v[1], "b");
    assert_int_equal(V.custom, 34);
    assert_string_equal(V.err, "");
}

static void test_defaults_untouched(void **state)
{
    (void)state;
    assert_int_equal(tb__parse("in", NULL), TB_CLI_OK);
    assert_int_equal(V.n, 7);
    assert_false(V.n_seen);
    assert_int_equal(V.choice, 2);
    assert_false(V.flag);
    assert_null(V.path);
}

static void test_equals_form_and_short(void **state)
{
    (void)state;
    assert_int_equal(tb__parse("--count=9 --scale=2 -n 10 --colour=red -- -notanoption", NULL), TB_CLI_OK);
    assert_int_equal(V.n, 10); /* the last one wins */
    assert_true(V.x == 2.0);
    assert_int_equal(V.choice, 1);
    assert_string_equal(V.pos[0], "-notanoption");
    assert_int_equal(tb__parse("--flag=1", NULL), TB_EXIT_USAGE);
    assert_non_null(strstr(V.err, "--flag takes no value"));
}

static void test_int_range(void **state)
{
    (void)state;
    assert_int_equal(tb__parse("--count 0", NULL), TB_EXIT_USAGE);
    assert_string_equal(V.err, "testbed demo: --count: expected an integer in [1, 100], got '0' "
                               "(see `testbed demo --help`)\n");
    assert_int_equal(V.n, 7);
}

static void test_int_syntax(void **state)
{
    (void)state;
    assert_int_equal(tb__parse("--count 5x", NULL), TB_EXIT_USAGE);
    assert_non_null(strstr(V.err, "--count: expected an integer in [1, 100], got '5x'"));
}

static void test_uint64(void **state)
{
    (void)state;
    assert_int_equal(tb__parse("--seed 18446744073709551615", NULL), TB_CLI_OK);
    assert_true(V.seed == UINT64_MAX);
    assert_int_equal(tb__parse("--seed -1", NULL), TB_EXIT_USAGE);
    assert_non_null(strstr(V.err, "--seed: expected an unsigned integer, got '-1'"));
}

static void test_double_range(void **state)
{
    (void)state;
    assert_int_equal(tb__parse("--scale 2.5", NULL), TB_EXIT_USAGE);
    assert_non_null(strstr(V.err, "--scale: expected a number in [-2, 2], got '2.5'"));
}

static void test_double_open_range(void **state)
{
    (void)state;
    assert_int_equal(tb__parse("--frac 1", NULL), TB_EXIT_USAGE);
    assert_non_null(strstr(V.err, "--frac: expected a number in (0, 1), got '1'"));
    assert_int_equal(tb__parse("--frac 0", NULL), TB_EXIT_USAGE);
    assert_int_equal(tb__parse("--frac nan", NULL), TB_EXIT_USAGE);
    assert_int_equal(tb__parse("--scale inf", NULL), TB_EXIT_USAGE);
}

static void test_choice_error(void **state)
{
    (void)state;
    assert_int_equal(tb__parse("--colour mauve", NULL), TB_EXIT_USAGE);
    assert_non_null(strstr(V.err, "--colour: expected one of red, green, blue, got 'mauve'"));
}

static void test_custom_error(void **state)
{
    (void)state;
    assert_int_equal(tb__parse("--pair 12", NULL), TB_EXIT_USAGE);
    assert_non_null(strstr(V.err, "--pair: expected a pair D:D, got '12'"));
}

static void test_missing_value(void **state)
{
    (void)state;
    assert_int_equal(tb__parse("in --count", NULL), TB_EXIT_USAGE);
    assert_non_null(strstr(V.err, "testbed demo: --count: missing value N"));
    assert_int_equal(tb__parse("-o", NULL), TB_EXIT_USAGE);
    assert_non_null(strstr(V.err, "-o: missing value FILE"));
}

static void test_unknown_option(void **state)
{
    (void)state;
    assert_int_equal(tb__parse("--colr red", NULL), TB_EXIT_USAGE);
    assert_string_equal(V.err, "testbed demo: unknown option '--colr' (see `testbed demo --help`)\n");
    assert_int_equal(tb__parse("-x", NULL), TB_EXIT_USAGE);
    assert_int_equal(tb__parse("-fo", NULL), TB_EXIT_USAGE);
}

static void test_too_many_positional(void **state)
{
    (void)state;
    assert_int_equal(tb__parse("a b c", NULL), TB_EXIT_USAGE);
    assert_non_null(strstr(V.err, "unexpected argument 'c'"));
    /* "-" alone is a file name (standard input) */
    int npos;
    assert_int_equal(tb__parse("- b", &npos), TB_CLI_OK);
    assert_int_equal(npos, 2);
    assert_string_equal(V.pos[0], "-");
}

static void test_optional_value(void **state)
{
    (void)state;
    bool seen = false;
    tb_opt opts[] = TB__OPTS;
    opts[5].seen = &seen;
    tb_cli cli = tb__cli;
    cli.opts = opts, cli.errout = V.errout;
    char *a1[] = {"demo", "--adaptive", "in", NULL};
    int np;
    assert_int_equal(tb_cli_parse(&cli, 3, a1, &np), TB_CLI_OK);
    assert_true(seen);
    assert_true(V.opt == 0.0);
    assert_int_equal(np, 1); /* "in" is not a number: left as an argument */
    char *a2[] = {"demo", "--adaptive", "0.5", NULL};
    assert_int_equal(tb_cli_parse(&cli, 3, a2, &np), TB_CLI_OK);
    assert_true(V.opt == 0.5);
    assert_int_equal(np, 0);
    char *a3[] = {"demo", "--adaptive", "11", NULL}; /* a number, out of range: an error, not an argument */
    assert_int_equal(tb_cli_parse(&cli, 3, a3, &np), TB_EXIT_USAGE);
    char *a4[] = {"demo", "--adaptive", NULL};
    assert_int_equal(tb_cli_parse(&cli, 2, a4, &np), TB_CLI_OK);
}

static void test_repeat_limit(void **state)
{
    (void)state;
    char *argv[2 * TB_OPT_REPEAT_MAX + 4] = {"demo"};
    int argc = 1;
    for (int i = 0; i <= TB_OPT_REPEAT_MAX; i++)
        argv[argc++] = "--tag", argv[argc++] = "t";
    tb_cli cli = tb__cli;
    cli.errout = V.errout;
    int np;
    assert_int_equal(tb_cli_parse(&cli, argc, argv, &np), TB_EXIT_USAGE);
    assert_int_equal(V.tags.n, TB_OPT_REPEAT_MAX);
}

/* The help names every option of the table, shows choices and defaults,
 * indents continuation lines, and --help returns 0 before any parsing. */
static void test_help_from_table(void **state)
{
    (void)state;
    char buf[4096] = "";
    FILE *f = fmemopen(buf, sizeof buf - 1, "w");
    assert_non_null(f);
    tb_cli_help(&tb__cli, f);
    fclose(f);
    assert_true(strncmp(buf, "usage: testbed demo IN [OUT] [options]\nA command for the tests.\n", 64) == 0);
    for (const tb_opt *o = tb__opts; o->name || o->short_name; o++) {
        char want[64];
        if (o->name)
            snprintf(want, sizeof want, "--%s", o->name);
        else
            snprintf(want, sizeof want, "  -%c", o->short_name);
        assert_non_null(strstr(buf, want));
    }
    assert_non_null(strstr(buf, "  -f, --flag "));
    assert_non_null(strstr(buf, "--count N"));
    assert_non_null(strstr(buf, "a count (default 7)"));
    assert_non_null(strstr(buf, "a seed (default 5)"));
    assert_non_null(strstr(buf, "--colour red|green|blue"));
    assert_non_null(strstr(buf, "a colour (default green)"));
    assert_non_null(strstr(buf, "--adaptive [T]"));
    assert_non_null(strstr(buf, "-h, --help"));
    assert_non_null(strstr(buf, "Exit status: 0 fine.\n"));
    /* the continuation line starts at the help column */
    const char *opt = strstr(buf, "  --scale X"), *a = strstr(buf, "a scale\n"), *b = strstr(buf, "second line");
    assert_non_null(opt);
    assert_non_null(a);
    assert_non_null(b);
    assert_int_equal((int)(b - (a + 8)), (int)(a - opt));
    assert_int_equal(tb__parse("--count 0 --help", NULL), TB_EXIT_OK);
    assert_string_equal(V.err, "");
}

/* Required positional arguments: fewer than min_pos is the command's
 * `missing` message and a usage error; min_pos of them is fine. (--help
 * without arguments: cli_all_commands_help, on every command.) */
static void test_too_few_positional(void **state)
{
    (void)state;
    tb_cli cli = tb__cli;
    cli.min_pos = 1, cli.missing = "no IN given", cli.errout = V.errout;
    char *none[] = {"demo", "--count", "3", NULL}, *one[] = {"demo", "a", NULL};
    int npos;
    assert_int_equal(tb_cli_parse(&cli, 3, none, &npos), TB_EXIT_USAGE);
    assert_int_equal(tb_cli_parse(&cli, 2, one, &npos), TB_CLI_OK);
    assert_int_equal(npos, 1);
    fflush(V.errout);
    assert_string_equal(V.err, "testbed demo: no IN given (see `testbed demo --help`)\n");
}

/* A command without arguments or options (`testbed version`): the usage line
 * is the name alone, --help still works and any option is unknown. */
static void test_no_options(void **state)
{
    (void)state;
    static const tb_opt none[] = {{0}};
    tb_cli cli = {.prog = "testbed bare", .err = "testbed bare: ", .opts = none, .errout = V.errout};
    char buf[512] = "";
    FILE *f = fmemopen(buf, sizeof buf - 1, "w");
    assert_non_null(f);
    tb_cli_help(&cli, f);
    fclose(f);
    assert_true(strncmp(buf, "usage: testbed bare\n", 20) == 0);
    int npos;
    char *ok[] = {"bare", NULL}, *bad[] = {"bare", "--x", NULL}, *arg[] = {"bare", "y", NULL};
    assert_int_equal(tb_cli_parse(&cli, 1, ok, &npos), TB_CLI_OK);
    assert_int_equal(tb_cli_parse(&cli, 2, bad, &npos), TB_EXIT_USAGE);
    assert_int_equal(tb_cli_parse(&cli, 2, arg, &npos), TB_EXIT_USAGE);
    fflush(V.errout);
    assert_string_equal(V.err, "testbed bare: unknown option '--x' (see `testbed bare --help`)\n"
                               "testbed bare: unexpected argument 'y' (see `testbed bare --help`)\n");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_every_type, tb__setup, tb__teardown),
        cmocka_unit_test_setup_teardown(test_defaults_untouched, tb__setup, tb__teardown),
        cmocka_unit_test_setup_teardown(test_equals_form_and_short, tb__setup, tb__teardown),
        cmocka_unit_test_setup_teardown(test_int_range, tb__setup, tb__teardown),
        cmocka_unit_test_setup_teardown(test_int_syntax, tb__setup, tb__teardown),
        cmocka_unit_test_setup_teardown(test_uint64, tb__setup, tb__teardown),
        cmocka_unit_test_setup_teardown(test_double_range, tb__setup, tb__teardown),
        cmocka_unit_test_setup_teardown(test_double_open_range, tb__setup, tb__teardown),
        cmocka_unit_test_setup_teardown(test_choice_error, tb__setup, tb__teardown),
        cmocka_unit_test_setup_teardown(test_custom_error, tb__setup, tb__teardown),
        cmocka_unit_test_setup_teardown(test_missing_value, tb__setup, tb__teardown),
        cmocka_unit_test_setup_teardown(test_unknown_option, tb__setup, tb__teardown),
        cmocka_unit_test_setup_teardown(test_too_many_positional, tb__setup, tb__teardown),
        cmocka_unit_test_setup_teardown(test_optional_value, tb__setup, tb__teardown),
        cmocka_unit_test_setup_teardown(test_repeat_limit, tb__setup, tb__teardown),
        cmocka_unit_test_setup_teardown(test_help_from_table, tb__setup, tb__teardown),
        cmocka_unit_test_setup_teardown(test_too_few_positional, tb__setup, tb__teardown),
        cmocka_unit_test_setup_teardown(test_no_options, tb__setup, tb__teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
