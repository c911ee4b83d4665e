/* `testbed generate KIND`: writes a procedural MID scene (host/mid/generate.h)
 * to standard output or, all or nothing, to a file. */
#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "host/mid/generate.h"
#include "util/base/outfile.h"

static void tb__generate_usage(FILE *out)
{
    fprintf(out,
            "usage: testbed generate KIND [--count N] [--seed S] [-o FILE]\n"
            "\n"
            "Writes a procedural MID scene for scaling tests: a camera, two lights, a palette\n"
            "of 8 named materials, then N top-level objects on a square grid. Objects are\n"
            "written as they are made, so memory stays constant for any N. The output is the\n"
            "MID writer's canonical form and depends only on KIND, N and S.\n"
            "\n"
            "Kinds:\n"
            "  grid   one primitive per cell, all 11 kinds mixed, random parameters,\n"
            "         rotations, scales and materials (about 0.3 KB per object)\n"
            "  csg    one random CSG tree per cell: union/intersection/difference nodes,\n"
            "         1 to 3 levels deep, over closed primitives (about 2.3 KB per object)\n"
            "  mesh   one inline polygon mesh per cell: a geodesic sphere (42 to 1002\n"
            "         vertices, with normals) or a height field (81 to 625 vertices, with\n"
            "         normals and uvs) (about 46 KB per object)\n"
            "\n"
            "  --count N    number of objects (default 100; 0 to %" PRId64 ")\n"
            "  --seed S     random seed, an unsigned 64-bit integer (default 1)\n"
            "  -o FILE      write FILE (appears only when complete) instead of standard output\n"
            "  -h, --help   show this help\n"
            "\n"
            "Exit status: 0 written, 1 write error, 2 usage error.\n",
            TB_GEN_MAX_COUNT);
}

/* A whole decimal (or 0x hex for the seed) number in [0, max]. */
static int tb__parse_u64(const char *s, uint64_t max, int base, uint64_t *out)
{
    if (!s || !*s || *s == '-' || *s == '+' || *s == ' ')
        return 0;
    errno = 0;
    char *end;
    unsigned long long v = strtoull(s, &end, base);
    if (errno || *end || v > max)
        return 0;
    *out = v;
    return 1;
}

int tb_cmd_generate(int argc, char **argv)
{
    if (tb_wants_help(argc, argv)) {
        tb__generate_usage(stdout);
        return TB_EXIT_OK;
    }
    const char *kind = NULL, *out = NULL;
    tb_gen_options opt = {.kind = TB_GEN_GRID, .count = 100, .seed = 1};
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *val = i + 1 < argc ? argv[i + 1] : NULL;
        uint64_t v;
        if (strcmp(a, "--count") == 0 || strcmp(a, "--seed") == 0 || strcmp(a, "-o") == 0) {
            if (!val) {
                fprintf(stderr, "testbed generate: error: %s needs a value\n", a);
                return TB_EXIT_USAGE;
            }
            i++;
            if (strcmp(a, "-o") == 0)
                out = val;
            else if (strcmp(a, "--count") == 0) {
                if (!tb__parse_u64(val, (uint64_t)TB_GEN_MAX_COUNT, 10, &v)) {
                    fprintf(stderr, "testbed generate: error: --count wants an integer from 0 to %" PRId64
                                    ", not '%s'\n", TB_GEN_MAX_COUNT, val);
                    return TB_EXIT_USAGE;
                }
                opt.count = (int64_t)v;
            } else {
                if (!tb__parse_u64(val, UINT64_MAX, 0, &v)) {
                    fprintf(stderr, "testbed generate: error: --seed wants an unsigned 64-bit integer, not '%s'\n",
                            val);
                    return TB_EXIT_USAGE;
                }
                opt.seed = v;
            }
        } else if (a[0] == '-' && a[1] != '\0') {
            fprintf(stderr, "testbed generate: error: unknown option '%s'\n", a);
            tb__generate_usage(stderr);
            return TB_EXIT_USAGE;
        } else if (!kind)
            kind = a;
        else {
            fprintf(stderr, "testbed generate: error: one kind at a time ('%s' and '%s')\n", kind, a);
            return TB_EXIT_USAGE;
        }
    }
    if (!kind) {
        tb__generate_usage(stderr);
        return TB_EXIT_USAGE;
    }
    if (tb_gen_kind_parse(kind, &opt.kind)) {
        fprintf(stderr, "testbed generate: error: %s\n", tb_last_error());
        return TB_EXIT_USAGE;
    }
    tb_status st;
    if (out && strcmp(out, "-") != 0) {
        tb_outfile of;
        if (tb_outfile_open(&of, out)) {
            fprintf(stderr, "testbed generate: error: %s\n", tb_last_error());
            return TB_EXIT_FAIL;
        }
        setvbuf(of.fp, NULL, _IOFBF, 1 << 20);
        st = tb_generate_write(of.fp, &opt);
        if (st)
            tb_outfile_abort(&of);
        else
            st = tb_outfile_commit(&of);
    } else {
        /* A large buffer: the writer makes many small writes. */
        static char buf[1 << 20];
        setvbuf(stdout, buf, _IOFBF, sizeof buf);
        st = tb_generate_write(stdout, &opt);
        if (!st && fflush(stdout) != 0)
            st = tb_error(TB_ERR_IO, "standard output: %s", strerror(errno));
    }
    if (st) {
        fprintf(stderr, "testbed generate: error: %s\n", tb_last_error());
        return TB_EXIT_FAIL;
    }
    return TB_EXIT_OK;
}
