/* Command-line pieces shared by the testbed commands: the Vulkan set-up of
 * those that run a kernel on a scene (render, bench gpu, bench formfactor,
 * validate), the command line the provenance records and the load average
 * the benchmarks print. */
#ifndef TB_TOOLS_TESTBED_CLI_UTIL_H
#define TB_TOOLS_TESTBED_CLI_UTIL_H

#include <stdbool.h>

#include "host/gpu/gpu.h"
#include "host/render/scene.h"
#include "options.h"

/* The --backend names (auto, vulkan, cpu) as tb_gpu_mode values, for a TB_OPT_CHOICE. */
extern const tb_opt_choice tb_cli_backends[];

/* The --accel names (bvh, grid, list) as tb_accel_kind values, for a TB_OPT_CHOICE. */
extern const tb_opt_choice tb_cli_accels[];

/* Loads the scene at `path` and opens Vulkan device `device` (the same
 * choice as `--backend vulkan`). On failure prints `who` followed by the
 * error message to stderr, frees what it made and returns false. */
bool tb_cli_open_vulkan(const char *who, const char *path, long device, tb_scene **s, tb_gpu_session *sess);

/* The whole command line for the provenance: "testbed" followed by the
 * subcommand's argv[0 .. argc) and a NULL, in a malloc'd array (free it;
 * the strings are argv's). NULL when out of memory. */
char **tb_cli_full_argv(int argc, char **argv);

/* The default COSTS.json of testbed calibrate and predict (docs/predict.md):
 * $XDG_CACHE_HOME/testbed/costs.json, else $HOME/.cache/testbed/costs.json.
 * 0 on success; -1 if neither variable is set or the path does not fit. */
int tb_cli_default_costs_path(char *buf, size_t len);

/* The 1-, 5- and 15-minute load averages (/proc/loadavg; zeros when it
 * cannot be read), printed beside benchmark figures. */
void tb_cli_load_average(double load[3]);

#endif
