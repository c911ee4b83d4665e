/* `testbed measure SCENE --sensors SENSORS.csv`: virtual irradiance and
 * radiance meters read off a scene by the path tracer or a radiosity
 * solution, optionally compared with measured values (host/hybrid/measure.h,
 * docs/measure.md). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "host/hybrid/measure.h"
#include "options.h"
#include "util/base/outfile.h"

int tb_cmd_measure(int argc, char **argv)
{
    const char *scene_path = NULL, *sensors_path = NULL, *out_path = NULL, *measured_path = NULL;
    tb_measure_options mo = tb_measure_defaults();
    int method = TB_MEASURE_PATH, quantity = TB_COMPARE_READING;
    bool spectral = false;
    bool fail_on_disagree = false, edge_given = false;
    double coverage = 2.0;
    const tb_opt_choice methods[] = {{"path", TB_MEASURE_PATH}, {"radiosity", TB_MEASURE_RADIOSITY}, {NULL, 0}};
    const tb_opt_choice quantities[] = {{"reading", TB_COMPARE_READING}, {"photometric", TB_COMPARE_PHOTOMETRIC},
                                        {NULL, 0}};
    const tb_opt opts[] = {
        {"sensors", .type = TB_OPT_STRING, .dest = &sensors_path, .metavar = "SENSORS.csv",
         .help = "the instruments: name,kind,x,y,z,dx,dy,dz,half_angle_deg,filter (required)"},
        {"output", 'o', TB_OPT_STRING, .dest = &out_path, .metavar = "OUT.csv",
         .help = "write the readings as CSV (default: a table on stdout)"},
        {"method", .type = TB_OPT_CHOICE, .dest = &method, .choices = methods, .metavar = "M",
         .help = "path (the path tracer, unbiased; default) or radiosity (direct light\n"
                 "by light sampling + the reflected light of a radiosity solution)"},
        {"samples", .type = TB_OPT_INT, .dest = &mo.samples, .min = 1, .max = 1 << 28, .metavar = "N",
         .help = "samples per sensor, rounded up to a multiple of 16 (default %D)"},
        {"seed", .type = TB_OPT_UINT64, .dest = &mo.seed, .metavar = "S", .help = "seed of every sensor's streams (default %D)"},
        {"threads", .type = TB_OPT_INT, .dest = &mo.threads, .min = 0, .max = 4096, .metavar = "N",
         .help = "OpenMP threads (0: all; the readings do not depend on it)"},
        {"spectral", .type = TB_OPT_FLAG, .dest = &spectral,
         .help = "render in spectral bands even if the scene is RGB (implied by a filter)"},
        {"max-edge", .type = TB_OPT_DOUBLE, .dest = &mo.rad.mesh.max_edge, .min = 0, .max = 1e30, .metavar = "L",
         .seen = &edge_given,
         .help = "radiosity: longest element edge, scene units (default: the bounding-box\n"
                 "diagonal / 24, as `testbed render --method radiosity`)"},
        {"threshold", .type = TB_OPT_DOUBLE, .dest = &mo.rad.stop.threshold, .min = 0, .max = 1, .metavar = "X",
         .flags = TB_OPTF_OPEN_MIN | TB_OPTF_OPEN_MAX,
         .help = "radiosity: stop shooting below this unshot fraction of the emitted power\n(default %D)"},
        {"compare", .type = TB_OPT_STRING, .dest = &measured_path, .metavar = "MEASURED.csv",
         .help = "compare with measured values: name,value[,uncertainty]"},
        {"compare-quantity", .type = TB_OPT_CHOICE, .dest = &quantity, .choices = quantities, .metavar = "Q",
         .help = "what MEASURED's values are: reading (W/m^2, W/m^2/sr through the\n"
                 "filter; default) or photometric (lx, cd/m^2)"},
        {"coverage", .type = TB_OPT_DOUBLE, .dest = &coverage, .min = 0, .max = 100, .metavar = "K",
         .flags = TB_OPTF_OPEN_MIN,
         .help = "a sensor disagrees when |simulated - measured| > K x the combined\n"
                 "uncertainty sqrt(u^2 + se^2) (default %D)"},
        {"fail-on-disagree", .type = TB_OPT_FLAG, .dest = &fail_on_disagree,
         .help = "exit with status 3 when some sensor disagrees"},
        {0},
    };
    const char *pos[1] = {NULL};
    const tb_cli cli = {
        .prog = "testbed measure",
        .err = "testbed measure: error: ",
        .usage = "SCENE.mid --sensors SENSORS.csv [options]",
        .intro = "\n"
                 "Virtual instruments: cosine-corrected irradiance meters (W/m^2 and lux) and\n"
                 "radiance meters with an acceptance cone (W/m^2/sr and cd/m^2), with optional\n"
                 "spectral filters, read off the scene with standard errors from 16 independent\n"
                 "batches, and optionally compared with measured values (docs/measure.md).\n",
        .opts = opts,
        .outro = "\n"
                 "Exit status: 0 measured (even when sensors disagree with MEASURED, which is\n"
                 "printed), 1 bad input (a bad CSV row is reported as FILE:LINE: error: ...;\n"
                 "no output file is written), 2 usage error, 3 --fail-on-disagree and some\n"
                 "sensor disagrees.",
        .pos = pos,
        .max_pos = 1,
        .min_pos = 1,
        .missing = "no SCENE.mid given",
    };
    int npos, prc = tb_cli_parse(&cli, argc, argv, &npos);
    if (prc != TB_CLI_OK)
        return prc;
    scene_path = pos[0];
    if (!sensors_path)
        return tb_cli_usage_error(&cli, "--sensors SENSORS.csv is required");
    mo.method = (tb_measure_method)method;
    mo.progress = true;
    mo.log = stderr;

    int rc = TB_EXIT_FAIL;
    tb_sensor_set ss = {0};
    tb_measured_set ms = {0};
    tb_scene *scene = NULL;
    tb_measure_result *res = NULL;
    /* every input is read and checked before the long work */
    if (tb_sensors_read_file(sensors_path, &ss)) {
        fprintf(stderr, "%s\n", tb_last_error());
        goto done;
    }
    if (measured_path && tb_measured_read_file(measured_path, &ss, &ms)) {
        fprintf(stderr, "%s\n", tb_last_error());
        goto done;
    }
    tb_scene_options so = {0};
    so.threads = mo.threads;
    if (spectral || ss.filtered)
        so.color = TB_SCENE_COLOR_SPECTRAL;
    if (tb_scene_load(scene_path, &so, &scene)) {
        fprintf(stderr, "%s\n", tb_last_error());
        goto done;
    }
    if (edge_given) { /* the default meshing but for the edge */
        const double edge = mo.rad.mesh.max_edge;
        mo.rad.mesh = tb_rad_default_mesh_options(scene);
        mo.rad.mesh.max_edge = edge;
        mo.rad.mesh_given = true;
    }
    res = calloc((size_t)ss.n, sizeof *res);
    if (!res) {
        fprintf(stderr, "testbed measure: error: out of memory\n");
        goto done;
    }
    if (tb_measure(scene, &ss, &mo, res)) {
        fprintf(stderr, "testbed measure: error: %s\n", tb_last_error());
        goto done;
    }
    if (out_path) {
        tb_outfile of;
        if (tb_outfile_open(&of, out_path)) {
            fprintf(stderr, "testbed measure: error: %s\n", tb_last_error());
            goto done;
        }
        if (tb_measure_write_csv(of.fp, scene, &ss, res)) {
            fprintf(stderr, "testbed measure: error: %s: %s\n", out_path, tb_last_error());
            tb_outfile_abort(&of);
            goto done;
        }
        if (tb_outfile_commit(&of)) {
            fprintf(stderr, "testbed measure: error: %s\n", tb_last_error());
            goto done;
        }
    } else {
        tb_measure_print_table(stdout, &ss, res);
    }
    rc = TB_EXIT_OK;
    if (measured_path) {
        tb_compare_summary sum;
        if (!out_path)
            putchar('\n');
        tb_measure_compare(stdout, &ss, res, &ms, (tb_compare_quantity)quantity, coverage, &sum);
        if (fail_on_disagree && sum.disagree)
            rc = 3;
    }
done:
    free(res);
    tb_scene_free(scene);
    tb_measured_free(&ms);
    tb_sensors_free(&ss);
    return rc;
}
