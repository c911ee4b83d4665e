/* The command-line parser every `testbed` subcommand uses: a command is a
 * table of options (tb_opt) plus a few lines of text (tb_cli); tb_cli_parse
 * reads argv into the variables the table points at, and tb_cli_help prints
 * the usage from the same table, so help and parsing cannot drift apart.
 *
 * Accepted spellings: `--name VALUE`, `--name=VALUE`, `-x VALUE`; "--" ends
 * the options; "-" alone is a positional argument (standard input/output).
 * docs/architecture.md, "Adding a command", is the checklist. */
#ifndef TB_TOOLS_TESTBED_OPTIONS_H
#define TB_TOOLS_TESTBED_OPTIONS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

/* What an option's value is, and so what `dest` points at. */
typedef enum tb_opt_type {
    TB_OPT_FLAG,   /* no value; dest: bool, set true */
    TB_OPT_CONST,  /* no value; dest: int, set to min (--join/--no-join: the last one given wins) */
    TB_OPT_INT,    /* whole number in [min, max]; dest: int */
    TB_OPT_UINT64, /* unsigned whole number <= max (max 0: any); dest: uint64_t */
    TB_OPT_DOUBLE, /* finite number in [min, max] (see TB_OPTF_OPEN_*; either may be infinite); dest: double */
    TB_OPT_STRING, /* any text; dest: const char * */
    TB_OPT_CHOICE, /* one of `choices`; dest: int, set to the choice's value */
    TB_OPT_REPEAT, /* text, may be given again; dest: tb_opt_strings, appended to */
    TB_OPT_CUSTOM, /* text handed to `parse`; dest: whatever parse expects */
} tb_opt_type;

/* Flags of a tb_opt. */
enum {
    TB_OPTF_OPEN_MIN = 1u << 0, /* DOUBLE: min itself is refused (x > min) */
    TB_OPTF_OPEN_MAX = 1u << 1, /* DOUBLE: max itself is refused (x < max) */
    TB_OPTF_OPTIONAL = 1u << 2, /* the value may be left out: the next argument is taken only if it parses */
    TB_OPTF_BASE0 = 1u << 3,    /* INT/UINT64: 0x.. hexadecimal and 0.. octal too (strtol base 0) */
    TB_OPTF_NO_SIGN = 1u << 4,  /* INT/UINT64: refuse a leading '-' or '+' */
};

/* One named value of a TB_OPT_CHOICE option; a {NULL} row ends the list. */
typedef struct tb_opt_choice {
    const char *name; /* as typed */
    int value;        /* stored in the int dest */
} tb_opt_choice;

/* Most values a TB_OPT_REPEAT option keeps. */
#define TB_OPT_REPEAT_MAX 64

/* The values of a TB_OPT_REPEAT option, in command-line order. */
typedef struct tb_opt_strings {
    const char *v[TB_OPT_REPEAT_MAX];
    int n;
} tb_opt_strings;

/* One row of an option table; a row with neither name nor short_name ends it. */
typedef struct tb_opt {
    const char *name;   /* long name without "--" ("spp"), or NULL */
    char short_name;    /* 'o' for -o, or 0 */
    tb_opt_type type;
    void *dest;         /* the variable set; holds the default before parsing */
    double min, max;    /* INT, DOUBLE: allowed range; UINT64: max only (0: none) */
    const char *metavar; /* the value's name in the help ("N", "FILE.csv") */
    const char *help;   /* help text; '\n' starts an indented line; "%D" prints dest's default */
    unsigned flags;     /* TB_OPTF_* */
    const tb_opt_choice *choices; /* CHOICE: the names */
    bool *seen;         /* if not NULL, set true when the option is given */
    /* CUSTOM: parses val into dest; 0 if fine, else writes the message
     * ("expected KIND[:RADIUS], got 'x'") into why and returns nonzero. */
    int (*parse)(const char *val, void *dest, char *why, size_t why_len);
} tb_opt;

/* A command's description for the parser and the help text. */
typedef struct tb_cli {
    const char *prog;     /* "testbed render": starts the usage line and names the --help hint */
    const char *err;      /* prefix of every error message ("testbed render: ") */
    const char *usage;    /* text after "usage: PROG " (may hold more lines; NULL or "": none) */
    const char *intro;    /* paragraph after the usage line, or NULL */
    const tb_opt *opts;   /* the option table */
    const char *outro;    /* text after the options (exit statuses, notes), or NULL */
    const char **pos;     /* where positional arguments go */
    int max_pos;          /* how many fit (more is a usage error) */
    int min_pos;          /* how many must be given (fewer is a usage error) */
    const char *missing;  /* the usage error when fewer than min_pos are given ("no SCENE.mid given") */
    FILE *errout;         /* where errors go; NULL: stderr (tests set a memory stream) */
} tb_cli;

/* Result of tb_cli_parse besides an exit status. */
enum {
    TB_CLI_OK = -1, /* parsed: run the command */
};

/* Parses argv[1..argc-1] (argv[0] is the subcommand's name). Returns
 * TB_CLI_OK and the number of positional arguments in *npos, or the exit
 * status to return now: 0 after printing --help to stdout, 2 after printing
 * a usage error to stderr. */
int tb_cli_parse(const tb_cli *cli, int argc, char **argv, int *npos);

/* Prints the usage text generated from the table. */
void tb_cli_help(const tb_cli *cli, FILE *out);

/* True if argv[1..argc-1] holds -h or --help before any "--". */
int tb_wants_help(int argc, char **argv);

/* Prints "<err>MESSAGE (see `PROG --help`)" to stderr and returns the usage
 * exit status (2): for checks between options that the table cannot say. */
int tb_cli_usage_error(const tb_cli *cli, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

#endif
