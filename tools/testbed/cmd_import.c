/* `testbed import MODEL -o OUT.mid`: a model read through Assimp, written as
 * MID plus FED files (host/mid/import.h, docs/import.md). */
#include <signal.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "host/mid/import.h"

static void tb__import_warning(void *user, const char *message)
{
    (void)user;
    fprintf(stderr, "testbed import: warning: %s\n", message);
}

int tb_cmd_import(int argc, char **argv)
{
    const char *model = NULL, *out = NULL;
    bool quiet = false;
    tb_import_opts opts = {.warn = tb__import_warning};
    int join = (int)opts.join;
    const tb_opt table[] = {
        {.short_name = 'o', .type = TB_OPT_STRING, .dest = &out, .metavar = "OUT.mid",
         .help = "the MID file to write (required)"},
        {"binary-fed", .type = TB_OPT_FLAG, .dest = &opts.binary_fed,
         .help = "write binary FED files (.fedb) instead of text (.fed)"},
        {"triangulate", .type = TB_OPT_FLAG, .dest = &opts.triangulate,
         .help = "split polygons into triangles (default: kept as polygons)"},
        {"join", .type = TB_OPT_CONST, .dest = &join, .min = TB_IMPORT_JOIN_ALWAYS,
         .help = "join vertices equal in position, normal and (u,v) for every format\n"
                 "(default: only for OBJ, whose reader unfolds the file's shared vertices)"},
        {"no-join", .type = TB_OPT_CONST, .dest = &join, .min = TB_IMPORT_JOIN_NEVER,
         .help = "one FED vertex per Assimp vertex, also for OBJ"},
        {"quiet", 'q', TB_OPT_FLAG, &quiet, .help = "no warnings and no summary"},
        {0},
    };
    const tb_cli cli = {
        .prog = "testbed import",
        .err = "testbed import: error: ",
        .usage = "MODEL -o OUT.mid [--binary-fed] [--triangulate] [--join|--no-join] [--quiet]",
        .intro = "\n"
                 "Reads MODEL through Assimp (tested: OBJ + MTL, PLY, STL, glTF 2.0; any other format\n"
                 "Assimp reads is tried) and writes OUT.mid with one polygons object per mesh and\n"
                 "node, in the model's node order, plus the folder OUT.data/ beside it (replaced if\n"
                 "it exists) with one FED file per mesh and copies of the textures. Vertex positions\n"
                 "are written bit for bit as Assimp read them (for OBJ, ASCII PLY and ASCII STL, where\n"
                 "Assimp's parser rounds a number one ulp off, as the file's text reads correctly\n"
                 "rounded); node transforms become MID transforms;\n"
                 "MTL and glTF materials, glTF cameras and KHR_lights_punctual lights are mapped as\n"
                 "docs/import.md describes. Output appears whole or not at all.\n",
        .opts = table,
        .outro = "\nExit status: 0 imported, 1 the model cannot be imported or the output written,\n"
                 "2 usage error.",
        .pos = &model,
        .max_pos = 1,
    };
    int npos, rc = tb_cli_parse(&cli, argc, argv, &npos);
    if (rc != TB_CLI_OK)
        return rc;
    opts.join = (tb_import_join)join;
    if (!model || !out)
        return tb_cli_usage_error(&cli, "%s", !model ? "no MODEL given" : "no output given (-o OUT.mid)");
    if (strcmp(out, "-") == 0) {
        fprintf(stderr, "testbed import: error: -o -: the MID file needs a folder beside it for its FED files, "
                        "so it cannot go to standard output\n");
        return TB_EXIT_USAGE;
    }
    if (quiet)
        opts.warn = NULL;
    /* A closed pipe on stderr must not kill the import halfway (the cleanup of
     * its temporary files would not run); writes just fail. */
    signal(SIGPIPE, SIG_IGN);
    tb_import_stats s;
    if (tb_import(model, out, &opts, &s)) {
        fprintf(stderr, "testbed import: error: %s\n", tb_last_error());
        return TB_EXIT_FAIL;
    }
    if (!quiet) {
        char *data = tb_import_data_dir(out);
        printf("%s (%s): %u objects, %u FED files in %s (%llu vertices, %llu faces), %u materials, "
               "%u textures, %u lights, %s camera; %llu faces skipped, %u warnings\n",
               model, s.format[0] ? s.format : "unknown format", s.objects, s.fed_files, data ? data : "?",
               (unsigned long long)s.vertices, (unsigned long long)s.faces, s.materials, s.textures, s.lights,
               s.cameras ? "1" : "no", (unsigned long long)s.skipped_faces, s.warnings);
        if (s.rerounded || s.undecided)
            printf("  %llu coordinates corrected to the file's text (Assimp's parser rounds some one ulp off), "
                   "%llu undecided\n", (unsigned long long)s.rerounded, (unsigned long long)s.undecided);
        free(data);
    }
    return TB_EXIT_OK;
}
