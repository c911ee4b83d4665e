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

int tb_cmd_generate(int argc, char **argv)
{
    const char *kind = NULL, *out = NULL;
    tb_gen_options opt = {.kind = TB_GEN_GRID, .count = 100, .seed = 1};
    uint64_t count = (uint64_t)opt.count;
    const tb_opt opts[] = {
        {"count", .type = TB_OPT_UINT64, .dest = &count, .max = (double)TB_GEN_MAX_COUNT, .metavar = "N",
         .help = "number of objects (default %D; 0 to 10^12, TB_GEN_MAX_COUNT)"},
        {"seed", .type = TB_OPT_UINT64, .dest = &opt.seed, .metavar = "S", .flags = TB_OPTF_BASE0,
         .help = "random seed, an unsigned 64-bit integer (default %D)"},
        {.short_name = 'o', .type = TB_OPT_STRING, .dest = &out, .metavar = "FILE",
         .help = "write FILE (appears only when complete) instead of standard output"},
        {0},
    };
    const tb_cli cli = {
        .prog = "testbed generate",
        .err = "testbed generate: error: ",
        .usage = "KIND [--count N] [--seed S] [-o FILE]",
        .intro = "\n"
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
                 "         normals and uvs) (about 46 KB per object)\n",
        .opts = opts,
        .outro = "\nExit status: 0 written, 1 write error, 2 usage error.",
        .pos = &kind,
        .max_pos = 1,
        .min_pos = 1,
        .missing = "no KIND given (grid, csg, mesh)",
    };
    int npos, rc = tb_cli_parse(&cli, argc, argv, &npos);
    if (rc != TB_CLI_OK)
        return rc;
    opt.count = (int64_t)count;
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
