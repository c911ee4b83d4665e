/* `testbed calibrate [-o COSTS.json]`: renders a fixed set of generated
 * scenes with the ray tracer, the path tracer and radiosity, each run in a
 * child process of its own (its peak resident memory is its own), and fits
 * the cost model's per-unit costs (host/render/predict.h) on the runs'
 * counters, timers and peak memory (docs/predict.md). */
#define _GNU_SOURCE /* wait4 */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cli_util.h"
#include "commands.h"
#include "host/mid/generate.h"
#include "host/mid/mid_writer.h"
#include "host/render/predict.h"
#include "host/render/scene.h"
#include "util/base/outfile.h"
#include "util/base/progress.h"
#include "util/stats/provenance.h"
#include "util/stats/stats.h"

/* What the calibration does to the generated materials. */
enum {
    TB__LOOK_AS_MADE = 0, /* the generator's palette */
    TB__LOOK_LAMBERT,     /* every material Lambert (no specular, no transmission): with env 3 and no CSG, a scene
                             the Vulkan path tracer takes, so --backend auto probes the device */
    TB__LOOK_PATTERNED,   /* every material with a noise diffuse pattern and a noise bump map (per-hit noise
                             octaves, as in scenes/materials.mid) */
};

/* One calibration run: a generated scene and the render's options. */
typedef struct tb__cal_run {
    tb_gen_kind kind;
    int count;           /* objects */
    int width, height;   /* the camera's resolution */
    tb_predict_method method;
    const char *args;    /* extra render options, space separated */
    double weight;       /* rough relative cost, for the progress bar's ETA */
    int env;             /* what surrounds the grid: 0 nothing (the sky), 1 a floor, 2 a closed room, 3 a closed
                            room lit only by an emitting ceiling panel (no point or directional light) */
    bool spectral;       /* the floor / room is spectral, so the scene renders 31 bands */
    int tori;            /* top-level objects kept: 0 all, 1 all but tori, 2 tori only (a torus test costs
                            several times another primitive's: this separates them) */
    int look;            /* the materials: TB__LOOK_* */
} tb__cal_run;

/* The quick set (seconds; the tests use it), the default set (about two
 * minutes on 2 cores) and the long one. Kinds, sizes, resolutions and
 * options vary so that each term's statistic varies apart from the others:
 * object kinds and counts (load, build, tests by kind), resolution and spp
 * (samples, pixels, film), depth (rays per sample), radiosity mesh size,
 * sample points and shots. */
static const tb__cal_run tb__cal_quick[] = {
    {TB_GEN_GRID, 8, 64, 48, TB_PREDICT_RAYTRACE, "", 1, 0, false, 0, TB__LOOK_AS_MADE},
    {TB_GEN_MESH, 4, 96, 72, TB_PREDICT_RAYTRACE, "", 1, 0, false, 0, TB__LOOK_AS_MADE},
    {TB_GEN_CSG, 3, 200, 150, TB_PREDICT_RAYTRACE, "", 1, 0, false, 0, TB__LOOK_AS_MADE},
    {TB_GEN_GRID, 20, 320, 240, TB_PREDICT_RAYTRACE, "", 1, 0, false, 0, TB__LOOK_AS_MADE},
    {TB_GEN_CSG, 6, 64, 48, TB_PREDICT_PATH, "", 1, 0, false, 0, TB__LOOK_AS_MADE},
    {TB_GEN_MESH, 2, 48, 36, TB_PREDICT_PATH, "--spp 2", 1, 0, false, 0, TB__LOOK_AS_MADE},
    {TB_GEN_MESH, 8, 320, 240, TB_PREDICT_PATH, "", 1, 0, false, 0, TB__LOOK_AS_MADE},
    {TB_GEN_GRID, 12, 480, 360, TB_PREDICT_PATH, "", 1, 0, false, 0, TB__LOOK_AS_MADE},
    {TB_GEN_GRID, 4, 1024, 768, TB_PREDICT_PATH, "", 2, 0, false, 0, TB__LOOK_AS_MADE},
    {TB_GEN_MESH, 6, 800, 600, TB_PREDICT_RAYTRACE, "--light-samples 1", 2, 0, false, 0, TB__LOOK_AS_MADE},
    {TB_GEN_GRID, 6, 64, 48, TB_PREDICT_RAYTRACE, "", 1, 2, true, 0, TB__LOOK_AS_MADE},
    {TB_GEN_GRID, 6, 64, 48, TB_PREDICT_PATH, "", 1, 3, false, 0, TB__LOOK_AS_MADE},
    {TB_GEN_GRID, 2, 48, 36, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 8 --samples 2 --spp 1", 1, 0, false, 0, TB__LOOK_AS_MADE},
    {TB_GEN_GRID, 3, 64, 48, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 12 --samples 1 --spp 2", 1, 0, false, 0, TB__LOOK_AS_MADE},
    {TB_GEN_MESH, 1, 160, 120, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 6 --samples 1", 1, 0, false, 0, TB__LOOK_AS_MADE},
    {TB_GEN_CSG, 2, 96, 72, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 4 --samples 1 --spp 1", 1, 0, false, 0, TB__LOOK_AS_MADE},
};

/* The default set's runs; the long set adds larger scenes to them. */
#define TB__CAL_DEFAULT_RUNS \
    /* raytrace: open grids (rays to the sky), floors and closed rooms (every ray hits), RGB and spectral */                       \
    {TB_GEN_GRID, 30, 320, 240, TB_PREDICT_RAYTRACE, "", 2, 0, false, 0, TB__LOOK_AS_MADE},                                                          \
    {TB_GEN_GRID, 30, 320, 240, TB_PREDICT_RAYTRACE, "--backend cpu", 2, 0, false, 0, TB__LOOK_AS_MADE}, /* no Vulkan probe */ \
    /* noise patterns and bump maps on every material (per-hit noise octaves) */                               \
    {TB_GEN_GRID, 16, 240, 180, TB_PREDICT_RAYTRACE, "", 2, 2, false, 0, TB__LOOK_PATTERNED},                     \
    {TB_GEN_MESH, 6, 240, 180, TB_PREDICT_RAYTRACE, "", 2, 3, false, 0, TB__LOOK_PATTERNED},                      \
    {TB_GEN_MESH, 20, 480, 360, TB_PREDICT_RAYTRACE, "--backend cpu", 2, 2, false, 0, TB__LOOK_AS_MADE},                     \
    {TB_GEN_GRID, 300, 480, 360, TB_PREDICT_RAYTRACE, "", 3, 0, false, 0, TB__LOOK_AS_MADE},                                                         \
    {TB_GEN_GRID, 60, 320, 240, TB_PREDICT_RAYTRACE, "--spp 4", 4, 2, false, 0, TB__LOOK_AS_MADE},                                                   \
    {TB_GEN_GRID, 16, 240, 180, TB_PREDICT_RAYTRACE, "", 2, 2, true, 0, TB__LOOK_AS_MADE},                                                           \
    {TB_GEN_GRID, 100, 320, 240, TB_PREDICT_RAYTRACE, "", 2, 1, false, 0, TB__LOOK_AS_MADE},                                                         \
    {TB_GEN_GRID, 30, 320, 240, TB_PREDICT_RAYTRACE, "--max-depth 2", 2, 2, false, 0, TB__LOOK_AS_MADE},                                             \
    {TB_GEN_GRID, 6, 160, 120, TB_PREDICT_RAYTRACE, "--spp 4", 2, 2, true, 0, TB__LOOK_AS_MADE},                                                     \
    {TB_GEN_CSG, 6, 240, 180, TB_PREDICT_RAYTRACE, "", 2, 2, false, 0, TB__LOOK_AS_MADE},                                                            \
    {TB_GEN_CSG, 20, 320, 240, TB_PREDICT_RAYTRACE, "", 3, 0, false, 0, TB__LOOK_AS_MADE},                                                           \
    {TB_GEN_CSG, 6, 240, 180, TB_PREDICT_RAYTRACE, "--spp 2", 2, 2, true, 0, TB__LOOK_AS_MADE},                                                      \
    {TB_GEN_MESH, 10, 320, 240, TB_PREDICT_RAYTRACE, "", 2, 0, false, 0, TB__LOOK_AS_MADE},                                                          \
    {TB_GEN_MESH, 50, 320, 240, TB_PREDICT_RAYTRACE, "--light-samples 1", 2, 2, false, 0, TB__LOOK_AS_MADE},                                         \
    {TB_GEN_MESH, 4, 240, 180, TB_PREDICT_RAYTRACE, "", 2, 2, true, 0, TB__LOOK_AS_MADE},                                                            \
    {TB_GEN_MESH, 80, 480, 360, TB_PREDICT_RAYTRACE, "", 3, 1, false, 0, TB__LOOK_AS_MADE},                                                          \
    {TB_GEN_GRID, 20, 320, 240, TB_PREDICT_RAYTRACE, "", 2, 3, false, 0, TB__LOOK_AS_MADE},                                                          \
    {TB_GEN_MESH, 6, 240, 180, TB_PREDICT_RAYTRACE, "--spp 2", 2, 3, true, 0, TB__LOOK_AS_MADE},                                                     \
    {TB_GEN_CSG, 4, 240, 180, TB_PREDICT_RAYTRACE, "", 2, 3, false, 0, TB__LOOK_AS_MADE},                                                            \
    {TB_GEN_GRID, 30, 800, 600, TB_PREDICT_RAYTRACE, "", 3, 0, false, 0, TB__LOOK_AS_MADE},                                                          \
    {TB_GEN_GRID, 9, 480, 360, TB_PREDICT_RAYTRACE, "", 3, 2, true, 0, TB__LOOK_AS_MADE},                                                            \
    {TB_GEN_CSG, 9, 320, 240, TB_PREDICT_RAYTRACE, "", 2, 0, false, 0, TB__LOOK_AS_MADE},                                                            \
    {TB_GEN_CSG, 12, 320, 240, TB_PREDICT_RAYTRACE, "", 2, 1, false, 0, TB__LOOK_AS_MADE},                                                           \
    {TB_GEN_CSG, 9, 240, 180, TB_PREDICT_RAYTRACE, "--spp 2", 2, 3, true, 0, TB__LOOK_AS_MADE},                                                      \
    {TB_GEN_MESH, 20, 640, 480, TB_PREDICT_RAYTRACE, "", 3, 0, false, 0, TB__LOOK_AS_MADE},                                                          \
    {TB_GEN_GRID, 300, 480, 360, TB_PREDICT_RAYTRACE, "", 3, 0, false, 1, TB__LOOK_AS_MADE},                                                         \
    {TB_GEN_GRID, 300, 320, 240, TB_PREDICT_RAYTRACE, "", 3, 2, false, 2, TB__LOOK_AS_MADE},                                                         \
    {TB_GEN_GRID, 200, 480, 360, TB_PREDICT_RAYTRACE, "", 3, 0, false, 2, TB__LOOK_AS_MADE},                                                         \
    {TB_GEN_GRID, 100, 240, 180, TB_PREDICT_RAYTRACE, "", 3, 3, false, 1, TB__LOOK_AS_MADE},                                                         \
    /* path */                                                                                                                     \
    {TB_GEN_GRID, 30, 320, 240, TB_PREDICT_PATH, "--spp 2", 2, 0, false, 0, TB__LOOK_AS_MADE},                                                       \
    {TB_GEN_GRID, 300, 480, 360, TB_PREDICT_PATH, "", 3, 0, false, 0, TB__LOOK_AS_MADE},                                                             \
    {TB_GEN_GRID, 60, 240, 180, TB_PREDICT_PATH, "--spp 2", 3, 2, false, 0, TB__LOOK_AS_MADE},                                                       \
    {TB_GEN_GRID, 16, 240, 180, TB_PREDICT_PATH, "", 3, 2, true, 0, TB__LOOK_AS_MADE},                                                               \
    {TB_GEN_GRID, 100, 320, 240, TB_PREDICT_PATH, "", 2, 1, false, 0, TB__LOOK_AS_MADE},                                                             \
    {TB_GEN_GRID, 30, 240, 180, TB_PREDICT_PATH, "--max-depth 3", 2, 2, false, 0, TB__LOOK_AS_MADE},                                                 \
    {TB_GEN_GRID, 6, 160, 120, TB_PREDICT_PATH, "--spp 4", 3, 2, true, 0, TB__LOOK_AS_MADE},                                                         \
    {TB_GEN_CSG, 6, 240, 180, TB_PREDICT_PATH, "", 3, 2, false, 0, TB__LOOK_AS_MADE},                                                                \
    {TB_GEN_CSG, 20, 320, 240, TB_PREDICT_PATH, "--spp 2", 3, 0, false, 0, TB__LOOK_AS_MADE},                                                        \
    {TB_GEN_CSG, 6, 160, 120, TB_PREDICT_PATH, "--spp 2", 3, 2, true, 0, TB__LOOK_AS_MADE},                                                          \
    {TB_GEN_MESH, 10, 320, 240, TB_PREDICT_PATH, "--spp 2", 2, 0, false, 0, TB__LOOK_AS_MADE},                                                       \
    {TB_GEN_MESH, 50, 240, 180, TB_PREDICT_PATH, "", 3, 2, false, 0, TB__LOOK_AS_MADE},                                                              \
    {TB_GEN_MESH, 4, 160, 120, TB_PREDICT_PATH, "--spp 2", 3, 2, true, 0, TB__LOOK_AS_MADE},                                                         \
    {TB_GEN_MESH, 80, 480, 360, TB_PREDICT_PATH, "--max-depth 3", 3, 1, false, 0, TB__LOOK_AS_MADE},                                                 \
    {TB_GEN_GRID, 20, 240, 180, TB_PREDICT_PATH, "", 3, 3, false, 0, TB__LOOK_AS_MADE},                                                              \
    {TB_GEN_MESH, 6, 240, 180, TB_PREDICT_PATH, "", 3, 3, true, 0, TB__LOOK_AS_MADE},                                                                \
    {TB_GEN_CSG, 4, 160, 120, TB_PREDICT_PATH, "--spp 2", 3, 3, false, 0, TB__LOOK_AS_MADE},                                                         \
    {TB_GEN_GRID, 9, 160, 120, TB_PREDICT_PATH, "--spp 4", 3, 3, true, 0, TB__LOOK_AS_MADE},                                                         \
    {TB_GEN_GRID, 30, 800, 600, TB_PREDICT_PATH, "", 3, 0, false, 0, TB__LOOK_AS_MADE},                                                              \
    {TB_GEN_GRID, 9, 480, 360, TB_PREDICT_PATH, "", 4, 2, true, 0, TB__LOOK_AS_MADE},                                                                \
    {TB_GEN_CSG, 9, 320, 240, TB_PREDICT_PATH, "--spp 2", 2, 0, false, 0, TB__LOOK_AS_MADE},                                                         \
    {TB_GEN_CSG, 12, 320, 240, TB_PREDICT_PATH, "", 3, 1, false, 0, TB__LOOK_AS_MADE},                                                               \
    {TB_GEN_CSG, 9, 160, 120, TB_PREDICT_PATH, "--spp 2", 3, 3, true, 0, TB__LOOK_AS_MADE},                                                          \
    {TB_GEN_MESH, 20, 640, 480, TB_PREDICT_PATH, "", 3, 0, false, 0, TB__LOOK_AS_MADE},                                                              \
    {TB_GEN_GRID, 300, 480, 360, TB_PREDICT_PATH, "", 3, 0, false, 1, TB__LOOK_AS_MADE},                                                             \
    {TB_GEN_GRID, 300, 320, 240, TB_PREDICT_PATH, "--spp 2", 3, 2, false, 2, TB__LOOK_AS_MADE},                                                      \
    {TB_GEN_GRID, 200, 480, 360, TB_PREDICT_PATH, "", 3, 0, false, 2, TB__LOOK_AS_MADE},                                                             \
    {TB_GEN_GRID, 100, 240, 180, TB_PREDICT_PATH, "", 3, 3, false, 1, TB__LOOK_AS_MADE},                                                             \
    {TB_GEN_GRID, 16, 160, 120, TB_PREDICT_PATH, "", 3, 2, false, 0, TB__LOOK_PATTERNED},                        \
    {TB_GEN_MESH, 6, 240, 180, TB_PREDICT_PATH, "", 3, 3, false, 0, TB__LOOK_PATTERNED},                         \
    /* Lambert, panel-lit: the Vulkan path tracer takes them, so --backend auto probes the device (its driver's \
     * libraries: resident memory and time no other path run has) */                                             \
    {TB_GEN_GRID, 20, 240, 180, TB_PREDICT_PATH, "", 3, 3, false, 0, TB__LOOK_LAMBERT},                                      \
    {TB_GEN_MESH, 6, 320, 240, TB_PREDICT_PATH, "", 3, 3, true, 0, TB__LOOK_LAMBERT},                                        \
    {TB_GEN_GRID, 60, 160, 120, TB_PREDICT_PATH, "--spp 2", 3, 3, false, 0, TB__LOOK_LAMBERT},                               \
    /* radiosity */                                                                                                                \
    {TB_GEN_GRID, 4, 160, 120, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 60 --spp 2", 3, 0, false, 0, TB__LOOK_AS_MADE},                   \
    {TB_GEN_GRID, 9, 320, 240, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 40 --samples 4", 4, 0, false, 0, TB__LOOK_AS_MADE},               \
    {TB_GEN_CSG, 4, 160, 120, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 40 --samples 8", 4, 0, false, 0, TB__LOOK_AS_MADE},                \
    {TB_GEN_MESH, 2, 320, 240, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 60 --samples 4 --spp 1", 3, 0, false, 0, TB__LOOK_AS_MADE},       \
    {TB_GEN_GRID, 6, 240, 180, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 150 --samples 2", 4, 0, false, 0, TB__LOOK_AS_MADE},              \
    {TB_GEN_GRID, 16, 320, 240, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 80 --samples 16", 8, 0, false, 0, TB__LOOK_AS_MADE},             \
    {TB_GEN_MESH, 4, 320, 240, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 300 --samples 8", 8, 0, false, 0, TB__LOOK_AS_MADE},              \
    {TB_GEN_GRID, 9, 240, 180, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 400 --samples 1", 8, 0, false, 0, TB__LOOK_AS_MADE},              \
    {TB_GEN_GRID, 4, 240, 180, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 300 --samples 2", 6, 2, false, 0, TB__LOOK_AS_MADE},              \
    {TB_GEN_GRID, 9, 160, 120, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 200 --samples 4 --max-edge 4", 6, 2, false, 0, TB__LOOK_AS_MADE}, \
    {TB_GEN_GRID, 4, 160, 120, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 400 --samples 2", 6, 3, false, 0, TB__LOOK_AS_MADE},              \
    {TB_GEN_GRID, 9, 800, 600, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 10 --samples 1 --spp 4", 4, 0, false, 0, TB__LOOK_AS_MADE},       \
    {TB_GEN_MESH, 4, 1024, 768, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 10 --samples 1 --spp 1", 3, 0, false, 0, TB__LOOK_AS_MADE},      \
    {TB_GEN_GRID, 9, 240, 180, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 200 --samples 8", 6, 3, false, 0, TB__LOOK_AS_MADE},              \
    {TB_GEN_GRID, 16, 160, 120, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 150 --samples 4", 6, 2, false, 0, TB__LOOK_AS_MADE},             \
    {TB_GEN_GRID, 6, 160, 120, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 200 --samples 4", 6, 3, true, 0, TB__LOOK_AS_MADE},

static const tb__cal_run tb__cal_default[] = {
    TB__CAL_DEFAULT_RUNS
};

static const tb__cal_run tb__cal_long[] = {
    TB__CAL_DEFAULT_RUNS
    /* larger scenes */
    {TB_GEN_GRID, 1500, 800, 600, TB_PREDICT_RAYTRACE, "", 8, 0, false, 0, TB__LOOK_AS_MADE},
    {TB_GEN_GRID, 400, 480, 360, TB_PREDICT_RAYTRACE, "", 6, 2, true, 0, TB__LOOK_AS_MADE},
    {TB_GEN_MESH, 300, 640, 480, TB_PREDICT_RAYTRACE, "", 8, 2, false, 0, TB__LOOK_AS_MADE},
    {TB_GEN_CSG, 60, 480, 360, TB_PREDICT_RAYTRACE, "", 8, 1, false, 0, TB__LOOK_AS_MADE},
    {TB_GEN_GRID, 1500, 800, 600, TB_PREDICT_PATH, "--spp 2", 8, 0, false, 0, TB__LOOK_AS_MADE},
    {TB_GEN_GRID, 400, 480, 360, TB_PREDICT_PATH, "--spp 2", 8, 2, true, 0, TB__LOOK_AS_MADE},
    {TB_GEN_MESH, 300, 640, 480, TB_PREDICT_PATH, "", 8, 2, false, 0, TB__LOOK_AS_MADE},
    {TB_GEN_CSG, 60, 480, 360, TB_PREDICT_PATH, "", 8, 1, false, 0, TB__LOOK_AS_MADE},
    {TB_GEN_CSG, 9, 320, 240, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 100 --samples 4", 8, 0, false, 0, TB__LOOK_AS_MADE},
    {TB_GEN_MESH, 6, 320, 240, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 100 --samples 8", 8, 0, false, 0, TB__LOOK_AS_MADE},
    {TB_GEN_GRID, 16, 240, 180, TB_PREDICT_RADIOSITY, "--threshold 1e-9 --max-shots 400 --samples 2", 10, 2, false, 0, TB__LOOK_AS_MADE},
};

/* tb_gen_sink: writes every item, the camera with the run's resolution. */
typedef struct tb__cal_writer {
    FILE *fp;
    int width, height;
    bool no_lights; /* leave the generator's lights out */
    int tori;       /* tb__cal_run.tori */
    int look;       /* tb__cal_run.look */
} tb__cal_writer;

static tb_status tb__cal_sink(void *user, const tb_mid_item *item)
{
    tb__cal_writer *w = user;
    if (item->type == TB_MID_ITEM_LIGHT && w->no_lights)
        return TB_OK;
    if (item->type == TB_MID_ITEM_OBJECT && w->tori && (item->object->kind == TB_PRIM_TORUS) != (w->tori == 2))
        return TB_OK;
    if (item->type == TB_MID_ITEM_MATERIAL && w->look != TB__LOOK_AS_MADE) {
        tb_mid_material m = *item->material;
        if (w->look == TB__LOOK_LAMBERT) {
            m.specular = m.transmission = tb_mid_color_grey(0.0f);
            m.set &= ~(unsigned)(TB_MID_SET_SPECULAR | TB_MID_SET_EXPONENT | TB_MID_SET_TRANSMISSION | TB_MID_SET_IOR);
        } else {
            /* fBm of 4 and 5 octaves in (u, v), as the bundled materials scene's plaster and hammered metal */
            m.diffuse_pattern = (tb_mid_pattern){.kind = TB_MID_PATTERN_NOISE, .scale = 12, .scale_v = 12,
                                                 .octaves = 4, .a = tb_mid_color_grey(0.2f), .b = m.diffuse};
            m.bump = (tb_mid_pattern){.kind = TB_MID_PATTERN_NOISE, .scale = 30, .scale_v = 30, .octaves = 5,
                                      .height = 0.005};
            m.set |= TB_MID_SET_DIFFUSE_PATTERN | TB_MID_SET_BUMP;
        }
        tb_mid_item copy = {.type = TB_MID_ITEM_MATERIAL, .material = &m};
        return tb_mid_write_item(w->fp, &copy);
    }
    if (item->type != TB_MID_ITEM_CAMERA)
        return tb_mid_write_item(w->fp, item);
    tb_mid_camera cam = *item->camera;
    cam.width = w->width, cam.height = w->height;
    tb_mid_item copy = {.type = TB_MID_ITEM_CAMERA, .camera = &cam};
    return tb_mid_write_item(w->fp, &copy);
}

/* Writes the floor or the room around the generated grid (the generator's
 * layout: objects on a pitch of 4.5 from the origin, the camera above the
 * front edge, a lamp above the middle). The open grid sees mostly sky, so
 * its rays rarely hit; the room makes every ray hit and paths bounce as in
 * closed scenes (the Cornell boxes), which separates the per-hit and
 * per-channel costs from the per-ray ones. */
static void tb__cal_room(FILE *fp, const tb__cal_run *r)
{
    int side = 1;
    while (side * side < r->count)
        side++;
    double e = side * 4.5, c = e / 2.0, h = 1.1 * e + 6.0, x0 = c - h, x1 = c + h, z1 = e + 14.0;
    const char *mat = r->spectral ? "spectral wall" : "matte white";
    if (r->spectral)
        fprintf(fp, "material \"spectral wall\" {\n    diffuse = spectrum([400 500 600 700], [0.55 0.75 0.7 0.6])\n}\n");
    /* faces counter-clockwise seen from inside (their fronts face in) */
    fprintf(fp, "polygons \"calibration room\" {\n    geometry = {\n        vertices = [");
    const double v[8][3] = {{x0, x0, 0}, {x1, x0, 0}, {x1, x1, 0}, {x0, x1, 0},
                            {x0, x0, z1}, {x1, x0, z1}, {x1, x1, z1}, {x0, x1, z1}};
    for (int i = 0; i < 8; i++)
        fprintf(fp, "[%.6g %.6g %.6g]%s", v[i][0], v[i][1], v[i][2], i < 7 ? " " : "]\n");
    fprintf(fp, "        faces = [[0 1 2 3]");
    if (r->env >= 2)
        fprintf(fp, " [4 7 6 5] [0 4 5 1] [3 2 6 7] [0 3 7 4] [1 5 6 2]");
    fprintf(fp, "]\n    }\n    rendering = {\n        material = \"%s\"\n    }\n}\n", mat);
    if (r->env == 3) {
        /* the panel just under the ceiling, facing down: area-light sampling as in the Cornell boxes */
        double a = c - 0.25 * h, b = c + 0.25 * h, z = z1 - 0.01;
        fprintf(fp,
                "polygons \"calibration panel\" {\n    geometry = {\n        vertices = [[%.6g %.6g %.6g] [%.6g %.6g %.6g] "
                "[%.6g %.6g %.6g] [%.6g %.6g %.6g]]\n        faces = [[0 1 2 3]]\n    }\n    rendering = {\n"
                "        material = \"lamp\"\n    }\n}\n",
                a, a, z, a, b, z, b, b, z, b, a, z);
    }
}

/* The file of run r's scene in dir (runs that differ only in options share it). */
static void tb__cal_scene_path(const tb__cal_run *r, const char *dir, char *buf, size_t n)
{
    snprintf(buf, n, "%s/%s-%d-%dx%d-%s%d-t%d%s.mid", dir, tb_gen_kind_name(r->kind), r->count, r->width, r->height,
             r->spectral ? "s" : "e", r->env, r->tori, r->look == TB__LOOK_LAMBERT ? "-lambert" : r->look ? "-patterned" : "");
}

/* Writes run r's scene to path. */
static tb_status tb__cal_scene(const tb__cal_run *r, const char *path)
{
    tb_outfile of;
    tb_status st = tb_outfile_open(&of, path);
    if (st)
        return st;
    tb__cal_writer w = {of.fp, r->width, r->height, r->env == 3, r->tori, r->look};
    tb_gen_options go = {.kind = r->kind, .count = r->count, .seed = 1};
    st = tb_mid_write_header(of.fp);
    if (!st)
        st = tb_generate(&go, tb__cal_sink, &w);
    if (!st && r->env > 0)
        tb__cal_room(of.fp, r);
    if (st) {
        tb_outfile_abort(&of);
        return st;
    }
    return tb_outfile_commit(&of);
}

/* What a child sends back. */
typedef struct tb__cal_result {
    int ok;
    tb_predict_stats f;
    tb_predict_measured y;
} tb__cal_result;

static double tb__cal_timer(const char *name)
{
    tb_stat_total t;
    if (tb_stats_get(name, TB_STAT_KIND_TIMER, &t) != TB_OK) {
        tb_clear_error();
        return 0.0;
    }
    return 1e-9 * (double)t.v[1];
}

static double tb__cal_value(const char *key)
{
    double v;
    if (tb_stats_get_value(key, &v) != TB_OK) {
        tb_clear_error();
        return 0.0;
    }
    return v;
}

/* Runs fn(arg, out) in a forked child and copies its `size` bytes of
 * result back through a pipe; *ru gets the child's resource use (its peak
 * resident memory is its own). True if the child wrote everything and
 * exited 0; *why says otherwise. */
static bool tb__cal_fork(void (*fn)(void *arg, void *out), void *arg, void *out, size_t size, struct rusage *ru,
                         char *why, size_t whylen)
{
    int fd[2];
    if (pipe(fd)) {
        snprintf(why, whylen, "pipe: %s", strerror(errno));
        return false;
    }
    fflush(NULL);
    pid_t pid = fork();
    if (pid < 0) {
        close(fd[0]), close(fd[1]);
        snprintf(why, whylen, "fork: %s", strerror(errno));
        return false;
    }
    if (pid == 0) {
        close(fd[0]);
        fn(arg, out);
        ssize_t w = write(fd[1], out, size);
        _exit(w == (ssize_t)size ? 0 : 1);
    }
    close(fd[1]);
    size_t got = 0;
    ssize_t n;
    while (got < size && (n = read(fd[0], (char *)out + got, size - got)) != 0) {
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0)
            break;
        got += (size_t)n;
    }
    close(fd[0]);
    int status = 0;
    memset(ru, 0, sizeof *ru);
    while (wait4(pid, &status, 0, ru) < 0 && errno == EINTR)
        ;
    if (got != size || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        snprintf(why, whylen, "the child process failed");
        return false;
    }
    return true;
}

/* What the calibration children are given. */
typedef struct tb__cal_job {
    const tb__cal_run *r;
    const char *scene, *dir;
    int threads;
} tb__cal_job;

/* In a child: the work counters of loading the scene alone (CSG
 * tessellation traces probe rays through the intersection code). The
 * result's method is 0 if the load failed. */
static void tb__cal_load_child(void *arg, void *out)
{
    const tb__cal_job *j = arg;
    tb_predict_stats *f = out;
    memset(f, 0, sizeof *f);
    f->method = j->r->method;
    tb_stats_set_enabled(1);
    tb_stats_reset();
    tb_scene_options so = {.accel = TB_ACCEL_BVH, .threads = j->threads};
    tb_scene *s = NULL;
    if (tb_scene_load(j->scene, &so, &s) == TB_OK) {
        tb_predict_stats_add_work(f, 1.0);
        f->channels = s->nchannels;
    } else {
        _exit(1);
    }
    tb_scene_free(s);
}

/* The load's work counters, measured in a process of its own so the
 * render's peak memory stays its own. */
static bool tb__cal_load_work(const tb__cal_run *r, const char *scene, int threads, tb_predict_stats *load)
{
    tb__cal_job j = {r, scene, NULL, threads};
    struct rusage ru;
    char why[64];
    return tb__cal_fork(tb__cal_load_child, &j, load, sizeof *load, &ru, why, sizeof why);
}

/* In the child: runs `testbed render` on the scene and measures it. */
static void tb__cal_child(const tb__cal_run *r, const char *scene, const char *dir, int threads,
                          tb__cal_result *out)
{
    memset(out, 0, sizeof *out);
    char img[1100], thr[16], logp[1100], js[1100];
    snprintf(img, sizeof img, "%s/out.png", dir);
    snprintf(js, sizeof js, "%s/stats.json", dir); /* the run values (seconds, elements, ...) are set with it */
    snprintf(logp, sizeof logp, "%s/render.log", dir);
    snprintf(thr, sizeof thr, "%d", threads);
    int fd = open(logp, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
        dup2(fd, 1);
        dup2(fd, 2);
        close(fd);
    }
    char argbuf[256];
    snprintf(argbuf, sizeof argbuf, "%s", r->args);
    char *argv[32];
    int argc = 0;
    argv[argc++] = "render";
    argv[argc++] = (char *)scene;
    argv[argc++] = "--method";
    argv[argc++] = (char *)tb_predict_method_name(r->method);
    argv[argc++] = "-o";
    argv[argc++] = img;
    argv[argc++] = "--threads";
    argv[argc++] = thr;
    argv[argc++] = "--stats";
    argv[argc++] = js;
    for (char *save = NULL, *tok = strtok_r(argbuf, " ", &save); tok && argc < 30; tok = strtok_r(NULL, " ", &save))
        argv[argc++] = tok;
    argv[argc] = NULL;
    tb_predict_stats load;
    memset(&load, 0, sizeof load);
    if (!tb__cal_load_work(r, scene, threads, &load)) /* also the scene's colour channels */
        return;
    tb_stats_set_enabled(1);
    tb_stats_reset();
    int64_t t0 = tb_stats_now_ns();
    int rc = tb_cmd_render(argc, argv);
    double wall = 1e-9 * (double)(tb_stats_now_ns() - t0);
    fflush(stdout);
    if (rc != 0)
        return;
    struct stat sb;
    int rad_spp = 4;
    const char *sp = strstr(r->args, "--spp ");
    if (sp && r->method == TB_PREDICT_RADIOSITY)
        rad_spp = atoi(sp + 6);
    tb_predict_stats_init(&out->f, r->method, stat(scene, &sb) == 0 ? (double)sb.st_size : 0.0, r->width, r->height,
                          (int)load.channels, rad_spp, threads);
    tb_predict_stats_add_scene(&out->f);
    tb_predict_stats_add_work(&out->f, 1.0);
    if (r->method != TB_PREDICT_RADIOSITY)
        tb_predict_stats_sub_work(&out->f, &load);
    out->f.f[TB_PF_VULKAN_PROBE] = tb__cal_value(TB_VULKAN_PROBE_KEY) > 0.0; /* as the render did */
    /* the PNG's bytes as predict estimates them: from every TB_PREDICT_IMAGE_STEP-th pixel, as the pilot's image */
    tb_image *png = NULL;
    if (tb_image_read(img, NULL, &png) == TB_OK)
        tb_predict_image_bytes(png, TB_PREDICT_IMAGE_STEP, false, (double)TB_PREDICT_IMAGE_STEP * TB_PREDICT_IMAGE_STEP,
                               &out->f.f[TB_PF_IMAGE_BYTES]);
    tb_image_free(png);
    tb_predict_measured *y = &out->y;
    y->wall = wall;
    y->module[TB_PM_LOAD] = tb__cal_timer("Scene/load");
    y->module[TB_PM_BUILD] = tb__cal_timer("Scene/accel build");
    double render = tb__cal_value("seconds");
    if (r->method == TB_PREDICT_RADIOSITY)
        y->module[TB_PM_RADIOSITY] = render + tb__cal_value("mesh_seconds");
    else
        y->module[r->method == TB_PREDICT_PATH ? TB_PM_PATH : TB_PM_RAYTRACE] = render;
    double rest = wall;
    for (int m = 0; m < TB_PM_PROCESS; m++)
        rest -= y->module[m];
    y->module[TB_PM_PROCESS] = rest;
    out->ok = 1;
}

static void tb__cal_render_child(void *arg, void *out)
{
    const tb__cal_job *j = arg;
    tb__cal_child(j->r, j->scene, j->dir, j->threads, out);
}

/* Runs r in a child; fills *res (peak memory from wait4). */
static int tb__cal_run_one(const tb__cal_run *r, const char *scene, const char *dir, int threads,
                           tb__cal_result *res, char *why, size_t whylen)
{
    tb__cal_job j = {r, scene, dir, threads};
    struct rusage ru;
    if (!tb__cal_fork(tb__cal_render_child, &j, res, sizeof *res, &ru, why, whylen) || !res->ok) {
        snprintf(why, whylen, "the render failed (see %s/render.log)", dir);
        return 0;
    }
    res->y.module[TB_PM_MEMORY] = (double)ru.ru_maxrss * 1024.0;
    return 1;
}

/* Runs shorter than this (seconds) are timed 3 times and each module's
 * median kept: their fixed costs (start-up, the Vulkan probe: 0.1-0.5 s)
 * vary from run to run by a good part of the whole. */
#define TB__CAL_SHORT 0.5

static double tb__cal_median3(double a, double b, double c)
{
    return fmax(fmin(a, b), fmin(fmax(a, b), c));
}

/* Times r twice more and keeps each measured module's (and the wall
 * time's) median of the three in *res; the statistics are the same counts
 * every time. */
static int tb__cal_repeat(const tb__cal_run *r, const char *scene, const char *dir, int threads, tb__cal_result *res,
                          char *why, size_t whylen)
{
    tb__cal_result more[2];
    for (int k = 0; k < 2; k++)
        if (!tb__cal_run_one(r, scene, dir, threads, &more[k], why, whylen))
            return 0;
    for (int m = 0; m < TB_PM_COUNT; m++)
        res->y.module[m] = tb__cal_median3(res->y.module[m], more[0].y.module[m], more[1].y.module[m]);
    res->y.wall = tb__cal_median3(res->y.wall, more[0].y.wall, more[1].y.wall);
    return 1;
}

/* mkdir -p of path's folder. */
static int tb__cal_mkdirs(const char *path)
{
    char buf[4096];
    snprintf(buf, sizeof buf, "%s", path);
    char *slash = strrchr(buf, '/');
    if (!slash)
        return 0;
    *slash = 0;
    for (char *p = buf + 1; *p; p++)
        if (*p == '/') {
            *p = 0;
            if (mkdir(buf, 0755) && errno != EEXIST)
                return -1;
            *p = '/';
        }
    return buf[0] && mkdir(buf, 0755) && errno != EEXIST ? -1 : 0;
}

int tb_cmd_calibrate(int argc, char **argv)
{
    const char *out_path = NULL, *keep = NULL, *runs_csv = NULL;
    int set = 1, threads = 0;
    static const tb_opt_choice sets[] = {{"quick", 0}, {"default", 1}, {"long", 2}, {NULL, 0}};
    const tb_opt opts[] = {
        {.short_name = 'o', .type = TB_OPT_STRING, .dest = &out_path, .metavar = "COSTS.json",
         .help = "where to write the costs (default: $XDG_CACHE_HOME/testbed/costs.json, or\n"
                 "~/.cache/testbed/costs.json: where testbed predict looks)"},
        {"set", .type = TB_OPT_CHOICE, .dest = &set, .choices = sets, .metavar = "S",
         .help = "quick (seconds; a smoke test, inaccurate), default (about 2 minutes on 2\n"
                 "cores) or long (about 10 minutes: larger scenes, a more accurate fit)"},
        {"threads", .type = TB_OPT_INT, .dest = &threads, .min = 0, .max = 4096, .metavar = "N",
         .help = "OpenMP threads of the runs (default: OpenMP's default; predict scales\n"
                 "the parallel modules from it)"},
        {"keep", .type = TB_OPT_STRING, .dest = &keep, .metavar = "DIR",
         .help = "keep the scenes, images and logs in DIR (default: a temporary folder, removed)"},
        {"runs", .type = TB_OPT_STRING, .dest = &runs_csv, .metavar = "FILE.csv",
         .help = "write one row per run: the statistics, the measured and the fitted modules"},
        {0},
    };
    const tb_cli cli = {
        .prog = "testbed calibrate",
        .err = "testbed calibrate: ",
        .usage = "[-o COSTS.json] [--set quick|default|long] [--threads N]",
        .intro = "Renders a fixed set of generated scenes (grid, csg, mesh; several sizes, resolutions\n"
                 "and options) with the ray tracer, the path tracer and radiosity, each in a process\n"
                 "of its own, and fits this machine's per-unit costs by non-negative least squares on\n"
                 "the runs' counters, timers and peak memory, for testbed predict (docs/predict.md).",
        .opts = opts,
        .outro = "Exit status: 0 written, 1 a run or the write failed, 2 usage error.",
    };
    int npos, prc = tb_cli_parse(&cli, argc, argv, &npos);
    if (prc != TB_CLI_OK)
        return prc;
    char def[4096];
    if (!out_path) {
        if (tb_cli_default_costs_path(def, sizeof def) != 0)
            return tb_cli_usage_error(&cli, "no -o given and neither XDG_CACHE_HOME nor HOME is set");
        out_path = def;
    }
    if (tb__cal_mkdirs(out_path) != 0) {
        fprintf(stderr, "testbed calibrate: cannot create the folder of %s: %s\n", out_path, strerror(errno));
        return TB_EXIT_FAIL;
    }
    const tb__cal_run *runs = set == 0 ? tb__cal_quick : set == 1 ? tb__cal_default : tb__cal_long;
    int nruns = set == 0 ? (int)(sizeof tb__cal_quick / sizeof *runs)
                : set == 1 ? (int)(sizeof tb__cal_default / sizeof *runs)
                           : (int)(sizeof tb__cal_long / sizeof *runs);
    char dir[1024];
    const char *tmpdir = getenv("TMPDIR");
    if (strlen(keep ? keep : tmpdir ? tmpdir : "") > 900)
        return tb_cli_usage_error(&cli, "the folder's name is too long (at most 900 bytes)");
    if (keep) {
        snprintf(dir, sizeof dir, "%s", keep);
        if (mkdir(dir, 0755) && errno != EEXIST) {
            fprintf(stderr, "testbed calibrate: %s: %s\n", dir, strerror(errno));
            return TB_EXIT_FAIL;
        }
    } else {
        snprintf(dir, sizeof dir, "%s/testbed-calibrate-XXXXXX", tmpdir && *tmpdir ? tmpdir : "/tmp");
        if (!mkdtemp(dir)) {
            fprintf(stderr, "testbed calibrate: %s: %s\n", dir, strerror(errno));
            return TB_EXIT_FAIL;
        }
    }
    tb__cal_result *res = calloc((size_t)nruns, sizeof *res);
    tb_predict_stats *f = calloc((size_t)nruns, sizeof *f);
    tb_predict_measured *y = calloc((size_t)nruns, sizeof *y);
    int rc = TB_EXIT_OK;
    if (!res || !f || !y) {
        fprintf(stderr, "testbed calibrate: out of memory\n");
        rc = TB_EXIT_FAIL;
        goto done;
    }
    double total = 0.0;
    for (int i = 0; i < nruns; i++)
        total += runs[i].weight;
    tb_progress bar;
    bool bar_on = tb_progress_start(&bar, "calibrate", (int64_t)(100.0 * total), NULL, 0) == TB_OK;
    /* Runs in an order that takes the methods in turn (and each method's
     * runs in their listed order): on a machine whose load drifts, every
     * module then sees the same mix of quiet and busy moments, instead of
     * the ray tracer's runs all meeting one load and radiosity's another. */
    int *order = malloc(sizeof *order * (size_t)nruns), next[TB_PREDICT_METHOD_COUNT] = {0}, done_runs = 0;
    if (!order) {
        fprintf(stderr, "testbed calibrate: out of memory\n");
        rc = TB_EXIT_FAIL;
        goto done;
    }
    while (done_runs < nruns)
        for (int m = 0; m < TB_PREDICT_METHOD_COUNT; m++) {
            while (next[m] < nruns && runs[next[m]].method != (tb_predict_method)m)
                next[m]++;
            if (next[m] < nruns)
                order[done_runs++] = next[m]++;
        }
    for (int k = 0; k < nruns && rc == TB_EXIT_OK; k++) {
        int i = order[k];
        char scene[4096], why[4200];
        tb__cal_scene_path(&runs[i], dir, scene, sizeof scene);
        struct stat sb;
        if (stat(scene, &sb) != 0 && tb__cal_scene(&runs[i], scene)) {
            snprintf(why, sizeof why, "%s", tb_last_error());
            rc = TB_EXIT_FAIL;
        } else if (!tb__cal_run_one(&runs[i], scene, dir, threads, &res[i], why, sizeof why) ||
                   (res[i].y.wall < TB__CAL_SHORT && !tb__cal_repeat(&runs[i], scene, dir, threads, &res[i], why,
                                                                     sizeof why))) {
            rc = TB_EXIT_FAIL;
        }
        if (rc != TB_EXIT_OK) {
            if (bar_on)
                tb_progress_finish(&bar), bar_on = false;
            fprintf(stderr, "testbed calibrate: run %d (%s %s %d objects, %s): %s\n", i + 1,
                    tb_predict_method_name(runs[i].method), tb_gen_kind_name(runs[i].kind), runs[i].count,
                    runs[i].args[0] ? runs[i].args : "default options", why);
            break;
        }
        f[i] = res[i].f;
        y[i] = res[i].y;
        if (bar_on)
            tb_progress_add(&bar, (int64_t)(100.0 * runs[i].weight));
    }
    free(order);
    if (bar_on)
        tb_progress_finish(&bar);
    if (rc != TB_EXIT_OK)
        goto done;
    tb_costs costs;
    int used_threads = threads > 0 ? threads : (int)f[0].threads;
    if (used_threads <= 0) {
        tb_provenance prov;
        if (tb_provenance_init(&prov, 0, NULL) == TB_OK) {
            used_threads = prov.threads;
            tb_provenance_free(&prov);
        }
    }
    if (tb_costs_fit(f, y, nruns, used_threads > 0 ? used_threads : 1, &costs)) {
        fprintf(stderr, "testbed calibrate: %s\n", tb_last_error());
        rc = TB_EXIT_FAIL;
        goto done;
    }
    tb_provenance prov;
    if (tb_provenance_init(&prov, 0, NULL) == TB_OK) {
        snprintf(costs.cpu, sizeof costs.cpu, "%.127s", prov.cpu);
        snprintf(costs.created, sizeof costs.created, "%.31s", prov.time_utc);
        tb_provenance_free(&prov);
    }
    if (tb_costs_write(out_path, &costs)) {
        fprintf(stderr, "testbed calibrate: %s\n", tb_last_error());
        rc = TB_EXIT_FAIL;
        goto done;
    }
    if (runs_csv) {
        tb_outfile of;
        if (tb_outfile_open(&of, runs_csv) == TB_OK) {
            fprintf(of.fp, "run,method,kind,count,width,height,args,wall");
            for (int m = 0; m < TB_PM_COUNT; m++)
                fprintf(of.fp, ",measured_%s,fitted_%s", tb_pmodule_name((tb_pmodule)m),
                        tb_pmodule_name((tb_pmodule)m));
            for (int k = 0; k < TB_PF_COUNT; k++)
                fprintf(of.fp, ",%s", tb_pfeat_name((tb_pfeat)k));
            fprintf(of.fp, "\n");
            for (int i = 0; i < nruns; i++) {
                tb_prediction p;
                tb_predict_eval(&costs, &f[i], &p);
                fprintf(of.fp, "%d,%s,%s,%d,%d,%d,\"%s\",%.6g", i + 1, tb_predict_method_name(runs[i].method),
                        tb_gen_kind_name(runs[i].kind), runs[i].count, runs[i].width, runs[i].height, runs[i].args,
                        y[i].wall);
                for (int m = 0; m < TB_PM_COUNT; m++)
                    fprintf(of.fp, ",%.6g,%.6g", y[i].module[m], p.module[m]);
                for (int k = 0; k < TB_PF_COUNT; k++)
                    fprintf(of.fp, ",%.6g", f[i].f[k]);
                fprintf(of.fp, "\n");
            }
            if (tb_outfile_commit(&of))
                fprintf(stderr, "testbed calibrate: %s\n", tb_last_error()), rc = TB_EXIT_FAIL;
        } else {
            fprintf(stderr, "testbed calibrate: %s\n", tb_last_error());
            rc = TB_EXIT_FAIL;
        }
    }
    printf("testbed calibrate: %d runs; wrote %s\n", nruns, out_path);
    for (int m = 0; m < TB_PM_COUNT; m++)
        if (costs.fit[m].rows)
            printf("  %-10s %2d runs, relative rms error of the fit %.1f%%\n", tb_pmodule_name((tb_pmodule)m),
                   costs.fit[m].rows, 100.0 * costs.fit[m].rel_rms);
done:
    if (!keep) {
        /* the scenes, the last image and log: all ours, in our own folder */
        for (int i = 0; i < nruns; i++) {
            char scene[4096];
            tb__cal_scene_path(&runs[i], dir, scene, sizeof scene);
            unlink(scene);
        }
        char p[4200];
        if (rc == TB_EXIT_OK) {
            snprintf(p, sizeof p, "%s/out.png", dir), unlink(p);
            snprintf(p, sizeof p, "%s/render.log", dir), unlink(p);
            snprintf(p, sizeof p, "%s/stats.json", dir), unlink(p);
            rmdir(dir);
        } else {
            fprintf(stderr, "testbed calibrate: the runs' files are in %s\n", dir);
        }
    }
    free(res), free(f), free(y);
    return rc;
}
