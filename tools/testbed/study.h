/* `testbed study` (docs/study.md): what cmd_study.c plans and runs (the
 * cells: one render per scene x method x budget x seed, as child processes
 * of this binary) and study_report.c turns into the outputs (cells.csv,
 * study.json, report.md, index.html, gnuplot plots, display images). */
#ifndef TB_TOOLS_TESTBED_STUDY_H
#define TB_TOOLS_TESTBED_STUDY_H

#include <limits.h>
#include <stdbool.h>
#include <stddef.h>

#include "util/base/error.h"
#include "util/image/image.h"

/* Most scenes, budgets and seeds of one study. */
#define TB_STUDY_MAX_SCENES 64
#define TB_STUDY_MAX_BUDGETS 32
#define TB_STUDY_MAX_SEEDS 1000

/* The renderers a study compares (the names are `testbed render --method`'s). */
typedef enum tb_study_method {
    TB_STUDY_RAYTRACE = 0, /* the Whitted ray tracer */
    TB_STUDY_RADIOSITY,    /* progressive radiosity, Gouraud-shaded image */
    TB_STUDY_HYBRID,       /* radiosity pass + ray tracer */
    TB_STUDY_PATH,         /* the path tracer */
    TB_STUDY_NMETHODS,
} tb_study_method;

/* The `--method` name of each tb_study_method. */
extern const char *const tb_study_method_names[TB_STUDY_NMETHODS];

/* What a budget counts (docs/study.md, "Budgets"). */
typedef enum tb_study_budget_kind {
    TB_STUDY_SPP = 0,  /* samples per pixel (radiosity: mesh refinement) */
    TB_STUDY_SECONDS,  /* the renderer's own time budget */
} tb_study_budget_kind;

/* One scene of the study. */
typedef struct tb_study_scene {
    const char *path;          /* as given */
    char name[64];             /* file stem, made unique within the study; names folders and images */
    char sha256[65];           /* of the scene file's bytes: part of every cell's key */
    double diagonal;           /* bounding-box diagonal (radiosity budgets) */
    bool reference_given;      /* --reference named the image, else the study rendered it */
    char reference[PATH_MAX];  /* the reference image */
    double reference_spp;      /* samples per pixel of a rendered reference (0 if given) */
    tb_image *ref;             /* the reference, loaded to measure errors */
} tb_study_scene;

/* One render: a scene with one method, budget and seed. */
typedef struct tb_study_cell {
    int scene, method, budget, seed; /* indices into the study's lists (method: into methods[]) */
    char dir[512];                   /* its folder, relative to the output folder */
    bool reused;                     /* found finished (same key) and not rendered again */
    double wall_seconds;             /* the render process, start to exit */
    double cpu_seconds;              /* its user + system time */
    double peak_rss_bytes;           /* its peak resident set size */
    double relmse, rmse, ssim;       /* against the scene's reference (util/image/compare.h, all channels) */
    long long nonfinite;             /* its pixels with a NaN or infinite channel (left out of the errors) */
} tb_study_cell;

/* A whole study, as planned and measured. */
typedef struct tb_study {
    const char *out;                       /* the output folder */
    int nscenes;
    tb_study_scene scenes[TB_STUDY_MAX_SCENES];
    int nmethods;
    tb_study_method methods[TB_STUDY_NMETHODS]; /* in the order given */
    int nbudgets;
    double budgets[TB_STUDY_MAX_BUDGETS];  /* increasing */
    tb_study_budget_kind kind;
    int nseeds;                            /* seeds 0 .. nseeds-1 */
    const char *reference_method;          /* renders missing references */
    int reference_spp;
    bool time_cpu;                         /* equal-time axis, time fits and plots: CPU seconds, not wall */
    double radiosity_edge;                 /* radiosity's longest element edge at budget 1 (0: the scene's default) */
    char *method_args[TB_STUDY_NMETHODS];  /* --args per method (NULL: none), verbatim */
    size_t ncells;
    tb_study_cell *cells;                  /* scene-major, then method, budget, seed */
    int rendered, reused;                  /* cells rendered by this run, reused */
} tb_study;

/* The cell of scene s, method index m, budget index b, seed k. */
static inline tb_study_cell *tb_study_cell_at(const tb_study *st, int s, int m, int b, int k)
{
    return &st->cells[(((size_t)s * (size_t)st->nmethods + (size_t)m) * (size_t)st->nbudgets + (size_t)b) *
                          (size_t)st->nseeds + (size_t)k];
}

/* Writes DIR/cells.csv, DIR/study.json, DIR/report.md, DIR/index.html, the
 * plots (DIR/plots, when gnuplot runs) and the display images (DIR/images)
 * from a measured study (study_report.c). */
tb_status tb_study_write_outputs(tb_study *st);

#endif
