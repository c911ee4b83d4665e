/* `testbed`: one command, many subcommands, all built from the library. */
#include <stdio.h>
#include <string.h>

#include "commands.h"
#include "tb_version.h"

/* Add a subcommand here and in commands.h; keep the table in alphabetical order. */
static const tb_command tb__commands[] = {
    {"bench", "benchmarks: intersect, tessellate, accel, rays (vs Embree), gpu (Vulkan kernel)", tb_cmd_bench},
    {"calibrate", "fit this machine's per-unit render costs for testbed predict (docs/predict.md)", tb_cmd_calibrate},
    {"check", "validate a MID scene and summarise it", tb_cmd_check},
    {"compare", "error metrics (MSE, PSNR, SSIM, ...) of an image against a reference", tb_cmd_compare},
    {"convert", "convert an image between RLE, PNG, PFM and OpenEXR", tb_cmd_convert},
    {"devices", "list the Vulkan devices and which one --backend auto/vulkan uses", tb_cmd_devices},
    {"generate", "write a procedural MID scene (grid, csg, mesh) for scaling tests", tb_cmd_generate},
    {"help", "list the subcommands, or show one's help", tb_cmd_help},
    {"import", "convert a model (OBJ, PLY, STL, glTF, ... via Assimp) to MID + FED files", tb_cmd_import},
    {"measure", "virtual irradiance and radiance meters read off a scene, compared with measurements", tb_cmd_measure},
    {"predict", "predict a render's wall time and peak memory, per module, from the calibrated costs", tb_cmd_predict},
    {"render", "render a MID scene to an image with the Whitted ray tracer", tb_cmd_render},
    {"study", "compare renderers over budgets and seeds against a reference: tables, plots, an HTML page", tb_cmd_study},
    {"trace", "closest hits of a file of rays through a scene (a ray server for scripts)", tb_cmd_trace},
    {"validate", "the Vulkan kernels against the CPU path on the same rays (agreement, routing, --bench)", tb_cmd_validate},
    {"version", "print the version and git revision", tb_cmd_version},
};

static const size_t tb__ncommands = sizeof tb__commands / sizeof tb__commands[0];

static const tb_command *tb__find(const char *name)
{
    for (size_t i = 0; i < tb__ncommands; i++)
        if (strcmp(tb__commands[i].name, name) == 0)
            return &tb__commands[i];
    return NULL;
}

static void tb__usage(FILE *out)
{
    fprintf(out, "usage: testbed <command> [options]\n\n"
                 "Testbed for Image Synthesis %s. Commands:\n", TB_VERSION_STRING);
    for (size_t i = 0; i < tb__ncommands; i++)
        fprintf(out, "  %-10s %s\n", tb__commands[i].name, tb__commands[i].summary);
    fprintf(out, "\nRun `testbed <command> --help` for a command's options.\n");
}

int tb_cmd_help(int argc, char **argv)
{
    const char *name = NULL;
    static const tb_opt no_opts[] = {{0}};
    const tb_cli cli = {
        .prog = "testbed help",
        .err = "testbed help: error: ",
        .usage = "[COMMAND]",
        .intro = "\nLists the subcommands, or shows COMMAND's help (the same as `testbed COMMAND --help`).",
        .opts = no_opts,
        .pos = &name,
        .max_pos = 1,
    };
    int npos, rc = tb_cli_parse(&cli, argc, argv, &npos);
    if (rc != TB_CLI_OK)
        return rc;
    if (!name) {
        tb__usage(stdout);
        return TB_EXIT_OK;
    }
    const tb_command *c = tb__find(name);
    if (!c) {
        fprintf(stderr, "testbed: error: no command '%s' (see `testbed help`)\n", name);
        return TB_EXIT_USAGE;
    }
    char *sub[] = {(char *)c->name, "--help", NULL};
    return c->run(2, sub);
}

int tb_cmd_version(int argc, char **argv)
{
    static const tb_opt no_opts[] = {{0}};
    const tb_cli cli = {
        .prog = "testbed version",
        .err = "testbed version: error: ",
        .usage = "",
        .intro = "\nPrints the library version and the git revision it was built from.",
        .opts = no_opts,
    };
    int npos, rc = tb_cli_parse(&cli, argc, argv, &npos);
    if (rc != TB_CLI_OK)
        return rc;
    printf("testbed %s (%s)\n", TB_VERSION_STRING, TB_GIT_REVISION);
    return TB_EXIT_OK;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        tb__usage(stderr);
        return TB_EXIT_USAGE;
    }
    if (strcmp(argv[1], "-h") == 0 || strcmp(argv[1], "--help") == 0) {
        tb__usage(stdout);
        return TB_EXIT_OK;
    }
    if (strcmp(argv[1], "--version") == 0)
        return tb_cmd_version(1, argv);
    const tb_command *c = tb__find(argv[1]);
    if (!c) {
        fprintf(stderr, "testbed: error: no command '%s' (see `testbed help`)\n", argv[1]);
        return TB_EXIT_USAGE;
    }
    return c->run(argc - 1, argv + 1);
}
