/* The table-driven command-line parser of the testbed commands (options.h). */
#include "options.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"

/* Widest option column before the help text moves to a line of its own. */
#define TB__OPT_COLUMN_MAX 24

static bool tb__opt_end(const tb_opt *o)
{
    return !o->name && !o->short_name;
}

static void tb__opt_label(const tb_opt *o, char *buf, size_t len)
{
    if (o->name)
        snprintf(buf, len, "--%s", o->name);
    else
        snprintf(buf, len, "-%c", o->short_name);
}

static FILE *tb__errout(const tb_cli *cli)
{
    return cli->errout ? cli->errout : stderr;
}

static void tb__verror(const tb_cli *cli, const char *fmt, va_list ap)
{
    FILE *e = tb__errout(cli);
    fputs(cli->err, e);
    vfprintf(e, fmt, ap);
    fprintf(e, " (see `%s --help`)\n", cli->prog);
}

int tb_wants_help(int argc, char **argv)
{
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--") == 0)
            return 0;
        if (strcmp(argv[i], "-h") == 0 || strcmp(argv[i], "--help") == 0)
            return 1;
    }
    return 0;
}

int tb_cli_usage_error(const tb_cli *cli, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    tb__verror(cli, fmt, ap);
    va_end(ap);
    return TB_EXIT_USAGE;
}

/* The value's name: the metavar, or for a choice without one the names
 * themselves ("bvh|grid|list"), so the help cannot miss one. */
static void tb__metavar(const tb_opt *o, char *buf, size_t len)
{
    buf[0] = '\0';
    if (o->metavar)
        snprintf(buf, len, (o->flags & TB_OPTF_OPTIONAL) ? "[%s]" : "%s", o->metavar);
    else if (o->type == TB_OPT_CHOICE)
        for (const tb_opt_choice *c = o->choices; c->name; c++)
            snprintf(buf + strlen(buf), len - strlen(buf), "%s%s", c == o->choices ? "" : "|", c->name);
}

/* ---------------------------------------------------------------- values */

static bool tb__parse_ll(const char *s, unsigned flags, long long *out)
{
    if (!*s || ((flags & TB_OPTF_NO_SIGN) && (*s == '-' || *s == '+')))
        return false;
    errno = 0;
    char *end;
    long long v = strtoll(s, &end, (flags & TB_OPTF_BASE0) ? 0 : 10);
    if (errno || end == s || *end)
        return false;
    *out = v;
    return true;
}

static bool tb__parse_ull(const char *s, unsigned flags, unsigned long long *out)
{
    /* strtoull wraps "-1" around to the largest value: never a count */
    if (!*s || *s == '-' || *s == '+' || *s == ' ')
        return false;
    errno = 0;
    char *end;
    unsigned long long v = strtoull(s, &end, (flags & TB_OPTF_BASE0) ? 0 : 10);
    if (errno || end == s || *end)
        return false;
    *out = v;
    return true;
}

static bool tb__parse_dbl(const char *s, double *out)
{
    char *end;
    double v = strtod(s, &end);
    if (end == s || *end || !isfinite(v))
        return false;
    *out = v;
    return true;
}

static bool tb__in_range(const tb_opt *o, double v)
{
    bool lo = (o->flags & TB_OPTF_OPEN_MIN) ? v > o->min : v >= o->min;
    bool hi = (o->flags & TB_OPTF_OPEN_MAX) ? v < o->max : v <= o->max;
    return lo && hi;
}

/* "one of a, b, c" */
static void tb__choice_list(const tb_opt *o, FILE *out)
{
    for (const tb_opt_choice *c = o->choices; c->name; c++)
        fprintf(out, "%s%s", c == o->choices ? "" : ", ", c->name);
}

static int tb__bad_value(const tb_cli *cli, const tb_opt *o, const char *val, const char *why)
{
    FILE *e = tb__errout(cli);
    char label[64];
    tb__opt_label(o, label, sizeof label);
    if (o->type == TB_OPT_CUSTOM) { /* the parser's reason is the whole message */
        fprintf(e, "%s%s: %s (see `%s --help`)\n", cli->err, label, why, cli->prog);
        return TB_EXIT_USAGE;
    }
    fprintf(e, "%s%s: expected ", cli->err, label);
    switch (o->type) {
    case TB_OPT_INT:
        fprintf(e, "an integer in [%.0f, %.0f]", o->min, o->max);
        break;
    case TB_OPT_UINT64:
        if (o->max > 0)
            fprintf(e, "an unsigned integer in [0, %.0f]", o->max);
        else
            fprintf(e, "an unsigned integer");
        break;
    case TB_OPT_DOUBLE:
        if (isinf(o->min) && isinf(o->max))
            fprintf(e, "a finite number");
        else if (isinf(o->max))
            fprintf(e, "a number %s %g", (o->flags & TB_OPTF_OPEN_MIN) ? ">" : ">=", o->min);
        else
            fprintf(e, "a number in %c%g, %g%c", (o->flags & TB_OPTF_OPEN_MIN) ? '(' : '[', o->min, o->max,
                    (o->flags & TB_OPTF_OPEN_MAX) ? ')' : ']');
        break;
    case TB_OPT_CHOICE:
        fprintf(e, "one of ");
        tb__choice_list(o, e);
        break;
    default:
        fprintf(e, "%s", why ? why : "a value");
        break;
    }
    fprintf(e, ", got '%s' (see `%s --help`)\n", val, cli->prog);
    return TB_EXIT_USAGE;
}

/* Stores val into o's destination; TB_CLI_OK or the usage exit status. */
static int tb__set(const tb_cli *cli, const tb_opt *o, const char *val)
{
    switch (o->type) {
    case TB_OPT_FLAG:
        *(bool *)o->dest = true;
        break;
    case TB_OPT_CONST:
        *(int *)o->dest = (int)o->min;
        break;
    case TB_OPT_INT: {
        long long v;
        if (!tb__parse_ll(val, o->flags, &v) || (double)v < o->min || (double)v > o->max)
            return tb__bad_value(cli, o, val, NULL);
        *(int *)o->dest = (int)v;
        break;
    }
    case TB_OPT_UINT64: {
        unsigned long long v;
        if (!tb__parse_ull(val, o->flags, &v) || (o->max > 0 && v > (unsigned long long)o->max))
            return tb__bad_value(cli, o, val, NULL);
        *(uint64_t *)o->dest = (uint64_t)v;
        break;
    }
    case TB_OPT_DOUBLE: {
        double v;
        if (!tb__parse_dbl(val, &v) || !tb__in_range(o, v))
            return tb__bad_value(cli, o, val, NULL);
        *(double *)o->dest = v;
        break;
    }
    case TB_OPT_STRING:
        *(const char **)o->dest = val;
        break;
    case TB_OPT_CHOICE: {
        const tb_opt_choice *c = o->choices;
        while (c->name && strcmp(c->name, val) != 0)
            c++;
        if (!c->name)
            return tb__bad_value(cli, o, val, NULL);
        *(int *)o->dest = c->value;
        break;
    }
    case TB_OPT_REPEAT: {
        tb_opt_strings *s = o->dest;
        if (s->n == TB_OPT_REPEAT_MAX)
            return tb_cli_usage_error(cli, "--%s: given more than %d times", o->name, TB_OPT_REPEAT_MAX);
        s->v[s->n++] = val;
        break;
    }
    case TB_OPT_CUSTOM: {
        char why[160] = "";
        if (o->parse(val, o->dest, why, sizeof why))
            return tb__bad_value(cli, o, val, why);
        break;
    }
    }
    if (o->seen)
        *o->seen = true;
    return TB_CLI_OK;
}

/* An optional value is taken only if it has the type's spelling. */
static bool tb__looks_like_value(const tb_opt *o, const char *val)
{
    long long l;
    unsigned long long u;
    double d;
    switch (o->type) {
    case TB_OPT_INT:
        return tb__parse_ll(val, o->flags, &l);
    case TB_OPT_UINT64:
        return tb__parse_ull(val, o->flags, &u);
    case TB_OPT_DOUBLE:
        return tb__parse_dbl(val, &d);
    default:
        return val[0] != '-';
    }
}

/* ---------------------------------------------------------------- argv */

static const tb_opt *tb__find_long(const tb_opt *t, const char *name, size_t len)
{
    for (; !tb__opt_end(t); t++)
        if (t->name && strlen(t->name) == len && strncmp(t->name, name, len) == 0)
            return t;
    return NULL;
}

static const tb_opt *tb__find_short(const tb_opt *t, char c)
{
    for (; !tb__opt_end(t); t++)
        if (t->short_name == c)
            return t;
    return NULL;
}

int tb_cli_parse(const tb_cli *cli, int argc, char **argv, int *npos)
{
    *npos = 0;
    if (tb_wants_help(argc, argv)) {
        tb_cli_help(cli, stdout);
        return TB_EXIT_OK;
    }
    bool opts_done = false;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (opts_done || a[0] != '-' || a[1] == '\0') {
            if (*npos >= cli->max_pos)
                return tb_cli_usage_error(cli, "unexpected argument '%s'", a);
            cli->pos[(*npos)++] = a;
            continue;
        }
        if (strcmp(a, "--") == 0) {
            opts_done = true;
            continue;
        }
        const tb_opt *o;
        const char *inline_val = NULL;
        if (a[1] == '-') {
            const char *eq = strchr(a + 2, '=');
            size_t len = eq ? (size_t)(eq - (a + 2)) : strlen(a + 2);
            o = tb__find_long(cli->opts, a + 2, len);
            if (o && eq)
                inline_val = eq + 1;
        } else {
            o = a[2] == '\0' ? tb__find_short(cli->opts, a[1]) : NULL;
        }
        if (!o)
            return tb_cli_usage_error(cli, "unknown option '%s'", a);
        char label[64];
        tb__opt_label(o, label, sizeof label);
        if (o->type == TB_OPT_FLAG || o->type == TB_OPT_CONST) {
            if (inline_val)
                return tb_cli_usage_error(cli, "%s takes no value, got '%s'", label, inline_val);
            tb__set(cli, o, NULL);
            continue;
        }
        const char *val = inline_val;
        if (!val && i + 1 < argc && (!(o->flags & TB_OPTF_OPTIONAL) || tb__looks_like_value(o, argv[i + 1])))
            val = argv[++i];
        if (!val && (o->flags & TB_OPTF_OPTIONAL)) {
            if (o->seen)
                *o->seen = true;
            continue;
        }
        if (!val) {
            char mv[96];
            tb__metavar(o, mv, sizeof mv);
            return tb_cli_usage_error(cli, "%s: missing value %s", label, mv);
        }
        int rc = tb__set(cli, o, val);
        if (rc != TB_CLI_OK)
            return rc;
    }
    if (*npos < cli->min_pos)
        return tb_cli_usage_error(cli, "%s", cli->missing ? cli->missing : "too few arguments");
    return TB_CLI_OK;
}

/* ---------------------------------------------------------------- help */

/* "  -o, --name METAVAR" into buf; its length. */
static int tb__left(const tb_opt *o, char *buf, size_t len)
{
    char mvbuf[96] = "";
    tb__metavar(o, mvbuf, sizeof mvbuf);
    const char *mv = mvbuf;
    const char *sp = *mvbuf ? " " : "";
    if (o->name && o->short_name)
        return snprintf(buf, len, "  -%c, --%s%s%s", o->short_name, o->name, sp, mv);
    if (o->name)
        return snprintf(buf, len, "  --%s%s%s", o->name, sp, mv);
    return snprintf(buf, len, "  -%c%s%s", o->short_name, sp, mv);
}

/* dest's current value, as the help's "%D" shows it. */
static void tb__print_default(const tb_opt *o, FILE *out)
{
    switch (o->type) {
    case TB_OPT_INT:
        fprintf(out, "%d", *(const int *)o->dest);
        break;
    case TB_OPT_UINT64:
        fprintf(out, "%llu", (unsigned long long)*(const uint64_t *)o->dest);
        break;
    case TB_OPT_DOUBLE:
        fprintf(out, "%g", *(const double *)o->dest);
        break;
    case TB_OPT_STRING: {
        const char *s = *(const char *const *)o->dest;
        fputs(s ? s : "none", out);
        break;
    }
    case TB_OPT_CHOICE:
        for (const tb_opt_choice *c = o->choices; c->name; c++)
            if (c->value == *(const int *)o->dest) {
                fputs(c->name, out);
                break;
            }
        break;
    default:
        break;
    }
}

void tb_cli_help(const tb_cli *cli, FILE *out)
{
    /* a command without arguments (`testbed version`) has no usage text: no trailing blank */
    const char *usage = cli->usage ? cli->usage : "";
    fprintf(out, "usage: %s%s%s\n", cli->prog, *usage ? " " : "", usage);
    if (cli->intro)
        fprintf(out, "%s\n", cli->intro);
    int col = 12; /* "  -h, --help" */
    char left[128];
    for (const tb_opt *o = cli->opts; !tb__opt_end(o); o++) {
        int n = tb__left(o, left, sizeof left);
        if (n <= TB__OPT_COLUMN_MAX && n > col)
            col = n;
    }
    col += 2;
    for (const tb_opt *o = cli->opts; !tb__opt_end(o); o++) {
        int n = tb__left(o, left, sizeof left);
        fputs(left, out);
        if (n + 1 > col)
            fprintf(out, "\n%*s", col, "");
        else
            fprintf(out, "%*s", col - n, "");
        for (const char *h = o->help ? o->help : ""; *h; h++) {
            if (*h == '\n')
                fprintf(out, "\n%*s", col, "");
            else if (h[0] == '%' && h[1] == 'D')
                tb__print_default(o, out), h++;
            else
                putc(*h, out);
        }
        putc('\n', out);
    }
    fprintf(out, "  -h, --help%*sshow this help\n", col - 12, "");
    if (cli->outro)
        fprintf(out, "%s\n", cli->outro);
}
