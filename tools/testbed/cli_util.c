/* Command-line pieces shared by the testbed commands (cli_util.h). */
#include "cli_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const tb_opt_choice tb_cli_backends[] = {
    {"auto", TB_GPU_MODE_AUTO}, {"vulkan", TB_GPU_MODE_VULKAN}, {"cpu", TB_GPU_MODE_CPU}, {NULL, 0}};

const tb_opt_choice tb_cli_accels[] = {
    {"bvh", TB_ACCEL_BVH}, {"grid", TB_ACCEL_GRID}, {"list", TB_ACCEL_LIST}, {NULL, 0}};

bool tb_cli_open_vulkan(const char *who, const char *path, long device, tb_scene **s, tb_gpu_session *sess)
{
    *s = NULL;
    if (tb_scene_load(path, NULL, s)) {
        fprintf(stderr, "%s%s\n", who, tb_last_error());
        return false;
    }
    if (tb_gpu_backend_choose(TB_GPU_MODE_VULKAN, (int)device, false, sess)) {
        fprintf(stderr, "%s%s\n", who, tb_last_error());
        tb_scene_free(*s);
        *s = NULL;
        return false;
    }
    return true;
}

char **tb_cli_full_argv(int argc, char **argv)
{
    char **full = malloc(sizeof *full * ((size_t)argc + 2));
    if (!full)
        return NULL;
    full[0] = "testbed";
    memcpy(full + 1, argv, sizeof *full * (size_t)argc);
    full[argc + 1] = NULL;
    return full;
}

int tb_cli_default_costs_path(char *buf, size_t len)
{
    const char *xdg = getenv("XDG_CACHE_HOME"), *home = getenv("HOME");
    int n;
    if (xdg && *xdg)
        n = snprintf(buf, len, "%s/testbed/costs.json", xdg);
    else if (home && *home)
        n = snprintf(buf, len, "%s/.cache/testbed/costs.json", home);
    else
        return -1;
    return n < 0 || (size_t)n >= len ? -1 : 0;
}

void tb_cli_load_average(double load[3])
{
    load[0] = load[1] = load[2] = 0.0;
    FILE *f = fopen("/proc/loadavg", "r");
    if (!f)
        return;
    if (fscanf(f, "%lf %lf %lf", &load[0], &load[1], &load[2]) != 3)
        load[0] = load[1] = load[2] = 0.0;
    fclose(f);
}
