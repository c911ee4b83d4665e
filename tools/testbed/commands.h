/* The subcommands of the `testbed` command: each is a main() of its own,
 * called with argv[0] set to the subcommand name. */
#ifndef TB_TOOLS_TESTBED_COMMANDS_H
#define TB_TOOLS_TESTBED_COMMANDS_H

#include <stdbool.h>

/* One row of the subcommand table. */
typedef struct tb_command {
    const char *name;                 /* as typed after `testbed` */
    const char *summary;              /* one line for `testbed help` */
    int (*run)(int argc, char **argv);
} tb_command;

/* `testbed bench WHAT`: object-level benchmarks (cmd_bench.c). */
int tb_cmd_bench(int argc, char **argv);
/* `testbed bench accel`: BVH / grid / list rays per second (cmd_bench_accel.c; argv[0] is "accel"). */
int tb_cmd_bench_accel(int argc, char **argv);
/* `testbed bench accel --scene`: a scene's BVH build, ours vs Embree's, at each of threads[0..nthreads),
 * best of `repeat` (bench_build.c); returns the exit status. */
int tb_bench_accel_scene(const char *path, const long *threads, int nthreads, int repeat, bool embree);
/* `testbed bench tessellate`: tessellation rate per kind (cmd_bench_tessellate.c; argv[0] is "tessellate"). */
int tb_cmd_bench_tessellate(int argc, char **argv);
/* `testbed bench rays`: scene rays through our BVH and Embree 3 (cmd_bench_rays.c; argv[0] is "rays"). */
int tb_cmd_bench_rays(int argc, char **argv);
/* `testbed bench formfactor`: form factors per second, Vulkan kernel vs CPU batch (cmd_bench_formfactor.c; argv[0] is "formfactor"). */
int tb_cmd_bench_formfactor(int argc, char **argv);
/* `testbed bench gpu`: the Vulkan intersect kernel vs the CPU path per ray set (cmd_bench_gpu.c; argv[0] is "gpu"). */
int tb_cmd_bench_gpu(int argc, char **argv);
/* `testbed bench scale`: load and first-pixel time and peak memory of generated scenes by size (cmd_bench_scale.c; argv[0] is "scale"). */
int tb_cmd_bench_scale(int argc, char **argv);
/* `testbed calibrate [-o COSTS.json]`: fit the cost model of testbed predict (cmd_calibrate.c). */
int tb_cmd_calibrate(int argc, char **argv);
/* `testbed check SCENE.mid`: validate and summarise a MID scene (cmd_check.c). */
int tb_cmd_check(int argc, char **argv);
/* `testbed compare A B`: error metrics against a reference image (cmd_compare.c). */
int tb_cmd_compare(int argc, char **argv);
/* `testbed convert IN OUT`: image format conversion (cmd_convert.c). */
int tb_cmd_convert(int argc, char **argv);
/* `testbed devices`: the Vulkan devices and the backend choice (cmd_devices.c). */
int tb_cmd_devices(int argc, char **argv);
/* `testbed generate KIND`: a procedural MID scene (cmd_generate.c). */
int tb_cmd_generate(int argc, char **argv);
/* `testbed help [CMD]`. */
int tb_cmd_help(int argc, char **argv);
/* `testbed import MODEL -o OUT.mid`: a model to MID + FED through Assimp (cmd_import.c). */
int tb_cmd_import(int argc, char **argv);
/* `testbed predict SCENE [render options]`: predicted wall time and peak memory (cmd_predict.c). */
int tb_cmd_predict(int argc, char **argv);
/* `testbed measure SCENE --sensors S.csv`: virtual irradiance and radiance meters (cmd_measure.c). */
int tb_cmd_measure(int argc, char **argv);
/* `testbed render SCENE -o OUT`: the Whitted ray tracer (cmd_render.c). */
int tb_cmd_render(int argc, char **argv);
/* `testbed render SCENE --method radiosity`: progressive radiosity (cmd_render_radiosity.c; called by tb_cmd_render). */
int tb_cmd_render_radiosity(int argc, char **argv);
/* `testbed render SCENE --method hybrid`: radiosity + ray tracing (cmd_render_hybrid.c; called by tb_cmd_render). */
int tb_cmd_render_hybrid(int argc, char **argv);
/* `testbed study SCENE... -o DIR`: methods x budgets x seeds against a reference (cmd_study.c, study_report.c). */
int tb_cmd_study(int argc, char **argv);
/* `testbed trace SCENE --rays RAYS --hits HITS`: closest hits of a ray file (cmd_trace.c). */
int tb_cmd_trace(int argc, char **argv);
/* `testbed validate SCENE`: Vulkan kernels vs the CPU path (cmd_validate.c). */
int tb_cmd_validate(int argc, char **argv);
/* `testbed version`. */
int tb_cmd_version(int argc, char **argv);

/* Exit statuses shared by all subcommands. */
enum {
    TB_EXIT_OK = 0,
    TB_EXIT_FAIL = 1,   /* the command ran and the answer is "no" or the input is bad */
    TB_EXIT_USAGE = 2,  /* bad command line */
};

/* tb_wants_help(): options.h. */
#include <stdbool.h>
#include "options.h"

#endif
