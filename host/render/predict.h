/* Cost prediction (docs/predict.md): a linear model of a render's wall time
 * and peak memory over statistics of the scene and of the work, whose
 * per-unit costs `testbed calibrate` fits on this machine and `testbed
 * predict` applies.
 *
 *     tb_costs c;
 *     tb_predict_stats f;
 *     tb_prediction p;
 *     if (tb_costs_read(path, &c) || tb_predict_scene(scene, &po, &f)) die(tb_last_error());
 *     tb_predict_eval(&c, &f, &p);   // p.seconds, p.peak_rss_bytes, p.module_seconds[]
 *
 * A model term is a cost per unit (seconds or bytes) times one statistic
 * (tb_pfeat); the terms are grouped in modules, each fitted on its own
 * measured time (tb_costs_fit), so a module's share of a prediction is
 * the sum of its terms. */
#ifndef TB_HOST_RENDER_PREDICT_H
#define TB_HOST_RENDER_PREDICT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "host/render/pathtrace.h"
#include "host/render/render.h"
#include "host/render/scene.h"
#include "util/base/error.h"
#include "util/image/image.h"

/* The renderer a prediction is for. */
typedef enum tb_predict_method {
    TB_PREDICT_RAYTRACE = 0, /* the Whitted ray tracer */
    TB_PREDICT_PATH,         /* the path tracer */
    TB_PREDICT_RADIOSITY,    /* progressive radiosity (ray-cast or hemicube form factors) */
} tb_predict_method;

/* Number of methods. */
#define TB_PREDICT_METHOD_COUNT 3

/* The method's name as on the command line ("raytrace", "path", "radiosity"). */
const char *tb_predict_method_name(tb_predict_method m);

/* The statistics the terms multiply (all counts of one run). */
typedef enum tb_pfeat {
    TB_PF_BYTES = 0,       /* bytes of the scene file */
    TB_PF_PRIMS,           /* analytic primitive nodes (every kind but polygons and CSG operators) */
    TB_PF_CSG,             /* CSG operator nodes */
    TB_PF_MESHES,          /* polygons objects */
    TB_PF_TRIANGLES,       /* mesh triangles */
    TB_PF_EMITTER_BYTES,   /* bytes of area-light emitters (tessellated curved and CSG emitters) */
    TB_PF_EMITTER_FACES,   /* faces made tessellating emitters (Polygonize/faces made) */
    TB_PF_CSG_PROBES,      /* probe rays classifying CSG emitter facets (Polygonize/CSG probes) */
    TB_PF_REFS,            /* acceleration references */
    TB_PF_REFS_LOG,        /* references x log2(references + 1) */
    TB_PF_SAMPLES,         /* camera samples */
    TB_PF_RAYS,            /* closest-hit rays through the BVH */
    TB_PF_OCC_RAYS,        /* occlusion (shadow) rays through the BVH */
    TB_PF_NODES,           /* BVH nodes visited */
    TB_PF_TESTS_PRIM,      /* intersection tests of analytic primitives but tori */
    TB_PF_TESTS_TORUS,     /* intersection tests of tori (a quartic: several times a quadric's cost) */
    TB_PF_TESTS_CSG,       /* intersection tests of CSG operators */
    TB_PF_TESTS_MESH,      /* intersection tests of polygons objects (their inner BVH walk included) */
    TB_PF_HITS,            /* surface records made (shading per hit) */
    TB_PF_LEAF_TESTS,      /* references tested at BVH leaves (triangles included: BVH/primitives tested) */
    TB_PF_NOISE_OCTAVES,   /* noise octaves evaluated by procedural patterns and bump maps (Pattern/noise octaves) */
    TB_PF_SAMPLE_CHANNELS, /* camera samples x colour channels (3 RGB, 31 spectral: film and path throughput) */
    TB_PF_HIT_CHANNELS,    /* hits x colour channels (shading evaluates every band) */
    TB_PF_PIXEL_CHANNELS,  /* pixels x colour channels (resolving and writing the image) */
    TB_PF_PIXELS,          /* image pixels */
    TB_PF_IMAGE_BYTES,     /* bytes of the PNG written, estimated from an image of 1/4 of the resolution each way
                              (the pilot's; calibration: every 4th pixel of the render's), times 16: deflate's
                              work follows the content (a noisy room costs several times a sky per pixel) */
    TB_PF_RAD_RAYS,        /* radiosity: form-factor rays (receivers x sample points) */
    TB_PF_RAD_FFS,         /* radiosity: form factors */
    TB_PF_RAD_SHOT_ELEMS,  /* radiosity: shots x elements (each shot updates every element) */
    TB_PF_RAD_ELEMENTS,    /* radiosity: elements of the mesh */
    TB_PF_RAD_OCC_RAYS,    /* radiosity: form-factor rays traced through the BVH (shafts with too many occluders) */
    TB_PF_RAD_NODES,       /* radiosity: BVH nodes those rays visit (the image rays' share taken out: the
                              nodes split in proportion to the occlusion and the image rays) */
    TB_PF_RAD_SHAFT_TESTS, /* radiosity: form-factor rays x occluders listed per shaft (rays tested against
                              a shaft's occluder list) */
    TB_PF_RAD_VERTICES,    /* radiosity: vertices of the mesh */
    TB_PF_RAD_PIXEL_RAYS,  /* radiosity: image rays (pixels x ceil(sqrt(--spp))^2: a square grid per pixel) */
    TB_PF_RAD_PIXEL_NODES, /* radiosity: BVH nodes the image rays visit (an image that sees mostly sky costs
                            * little per ray: a pilot image measures it) */
    TB_PF_RAD_PIXEL_LEAF_TESTS, /* radiosity: elements the image rays test at BVH leaves (a ray that hits tests
                                   several, a sky ray few: a pilot image measures it) */
    TB_PF_RAD_MESH_PROBES, /* radiosity: CSG probe rays of meshing (Polygonize/CSG probes after the load) */
    TB_PF_RAD_CACHE_BYTES, /* radiosity: form factors cached, (distinct shooters) x (vertices + elements) x 4,
                              at most the solver's 512 MiB */
    TB_PF_MEM_OBJECTS,     /* bytes of objects (tb_scene_memory: objects + FED files + materials + lights) */
    TB_PF_MEM_MESHES,      /* bytes of meshes (tb_scene_memory) */
    TB_PF_MEM_EMITTERS,    /* bytes of emitters (tb_scene_memory) */
    TB_PF_MEM_ACCEL,       /* bytes of references and acceleration structure (tb_scene_memory) */
    TB_PF_FILM_BYTES,      /* pixels x channels x 4: the film and the images made from it */
    TB_PF_VULKAN_PROBE,    /* 1 if the render probes the Vulkan device (--backend auto: the ray tracer always, the
                              path tracer on a scene its Vulkan kernel takes; the driver's libraries load) */
    TB_PF_IS_RAYTRACE,     /* 1 for the ray tracer, else 0 (fixed costs per method) */
    TB_PF_IS_PATH,         /* 1 for the path tracer */
    TB_PF_IS_RADIOSITY,    /* 1 for radiosity */
    TB_PF_ONE,             /* 1 */
    TB_PF_COUNT
} tb_pfeat;

/* The statistic's name in JSON and CSV output ("triangles", "rays", ...). */
const char *tb_pfeat_name(tb_pfeat k);

/* Modules: each is fitted on its own measurement and reported on its own. */
typedef enum tb_pmodule {
    TB_PM_LOAD = 0,   /* parse the file and prepare the objects, emitters, references (the Scene/load timer) */
    TB_PM_BUILD,      /* build the BVH (Scene/accel build) */
    TB_PM_RAYTRACE,   /* the ray tracer's passes (the run's `seconds`) */
    TB_PM_PATH,       /* the path tracer's passes */
    TB_PM_RADIOSITY,  /* meshing and shooting (`mesh_seconds` + `seconds`) */
    TB_PM_PROCESS,    /* the rest of the command: start-up, device probe, image resolve and write, stats */
    TB_PM_MEMORY,     /* peak resident memory (bytes, not seconds) */
    TB_PM_COUNT
} tb_pmodule;

/* The module's name ("load", "build", ...). */
const char *tb_pmodule_name(tb_pmodule m);

/* One term of the model. */
typedef struct tb_cost_term {
    const char *name;   /* "module.what", the key in COSTS.json */
    tb_pmodule module;
    tb_pfeat feature;   /* the statistic it multiplies */
    const char *unit;   /* what the cost is per ("s/byte", "bytes/element", ...) */
} tb_cost_term;

/* The terms of the model, in COSTS.json order; *n is set to their number. */
const tb_cost_term *tb_cost_terms(int *n);

/* Most terms. */
#define TB_COST_MAX_TERMS 96

/* How well one module's fit went. */
typedef struct tb_cost_fit {
    int rows;        /* runs used */
    double rel_rms;  /* root mean square of (fitted - measured) / measured */
} tb_cost_fit;

/* The fitted per-unit costs of this machine (COSTS.json). */
typedef struct tb_costs {
    double c[TB_COST_MAX_TERMS]; /* by term index; >= 0 */
    int threads;                 /* OpenMP threads of the calibration runs */
    char cpu[128];               /* the calibrating machine's CPU model ("" if unknown) */
    char created[32];            /* ISO 8601 UTC time of the calibration ("" if unknown) */
    tb_cost_fit fit[TB_PM_COUNT];
} tb_costs;

/* The statistics of one run (measured or predicted). */
typedef struct tb_predict_stats {
    tb_predict_method method;
    double f[TB_PF_COUNT];  /* by tb_pfeat */
    int threads;            /* OpenMP threads of the run (0: OpenMP's default) */
    double channels;        /* colour channels of the image (3 RGB, 31 spectral; 0 counts as 3) */
    double rad_shots;       /* radiosity: shots (reported, also inside RAD_SHOT_ELEMS) */
    bool rad_extrapolated;  /* radiosity: the shot count was extrapolated from the pilot's decay */
    double pilot_seconds;   /* wall time spent on the pilot */
} tb_predict_stats;

/* What a calibration run measured besides its statistics. */
typedef struct tb_predict_measured {
    double module[TB_PM_COUNT]; /* seconds per module (memory: peak resident bytes) */
    double wall;                /* seconds of the whole command */
} tb_predict_measured;

/* A prediction. */
typedef struct tb_prediction {
    double seconds;               /* wall time of the command */
    double peak_rss_bytes;        /* peak resident memory */
    double module[TB_PM_COUNT];   /* per module: seconds (memory: bytes) */
    double term[TB_COST_MAX_TERMS]; /* per term: seconds or bytes */
} tb_prediction;

/* Sets the statistics that do not come from counters: the method, the
 * scene file's size, the image (width x height pixels of nchannels, also
 * the channels the work counters of tb_predict_stats_add_work are
 * multiplied by for the per-channel terms) and,
 * for radiosity, the image's rays per pixel (rad_spp). */
void tb_predict_stats_init(tb_predict_stats *f, tb_predict_method m, double file_bytes, int width, int height,
                           int nchannels, int rad_spp, int threads);

/* Adds what a scene load left in util/stats (the Scene/... object counters
 * and memory figures; reset the statistics before the load). */
void tb_predict_stats_add_scene(tb_predict_stats *f);

/* Subtracts the work counters of a scene load (the intersection tests of
 * CSG tessellation) that f holds in `load` (filled by add_work after a
 * load alone), so that f keeps the render's own; never below 0. */
void tb_predict_stats_sub_work(tb_predict_stats *f, const tb_predict_stats *load);

/* Adds the work counters a render left in util/stats (camera samples, BVH
 * rays, nodes, tests by kind, hits; radiosity's rays, form factors and the
 * run values elements, vertices and shots), each times `scale`. */
void tb_predict_stats_add_work(tb_predict_stats *f, double scale);

/* What tb_predict_scene needs besides the scene. */
typedef struct tb_predict_options {
    tb_predict_method method;   /* raytrace or path (radiosity: host/radiosity/predict.h) */
    tb_render_options render;   /* the render's options (spp, passes, depth, threads, ...) */
    tb_accel_kind accel;        /* the acceleration structure */
    const tb_pt_options *path_options; /* path: its options (NULL: defaults) */
    int pilot_divisor;          /* pilot image: width and height / this (>= 1; 1: the whole image) */
    /* Whether the render would probe the Vulkan device on the loaded scene
     * (host/render may not use host/gpu: the command knows its rule); NULL:
     * it would not. */
    bool (*vulkan_probe)(const tb_scene *s, void *user);
    void *vulkan_probe_user;    /* vulkan_probe's argument */
} tb_predict_options;

/* Loads the scene at `path` once, gathers its statistics and runs the
 * pilot: the same render at 1/pilot_divisor of the resolution in each
 * direction, whose work counters, scaled by the pixel ratio, stand for the
 * full render's. TB_ERR_ARG for radiosity or a bad divisor; the loader's
 * and renderer's errors. */
tb_status tb_predict_scene(const char *path, const tb_predict_options *o, tb_predict_stats *f);

/* The prediction of the model `c` for the statistics f. Parallel modules
 * (build, renders) are scaled by the calibration's threads over f's (both
 * capped at the processors online). */
void tb_predict_eval(const tb_costs *c, const tb_predict_stats *f, tb_prediction *out);

/* Fits every module's costs by non-negative least squares on relative
 * errors (util/stats/lsq.h) over n runs; `threads` is recorded. TB_ERR_ARG
 * when n < 1. */
tb_status tb_costs_fit(const tb_predict_stats *f, const tb_predict_measured *y, int n, int threads, tb_costs *out);

/* The schema COSTS.json is written with and the only one read: bumped
 * whenever the terms change, so an older file is refused. */
#define TB_COSTS_SCHEMA "testbed-costs-5"

/* The --stats value in which the radiosity renderer puts the BVH nodes its
 * image rays visited (the form factors' nodes are the rest of the counter). */
#define TB_RAD_IMAGE_NODES_KEY "image_bvh_nodes"

/* The --stats value in which the radiosity renderer puts the elements its
 * image rays tested at BVH leaves (BVH/primitives tested during the image). */
#define TB_RAD_IMAGE_LEAF_KEY "image_leaf_tests"

/* The --stats value `testbed render` sets to 1 when it probes the Vulkan
 * device (--backend auto or vulkan), which calibration reads. */
#define TB_VULKAN_PROBE_KEY "vulkan_probed"

/* How many pixels of the image the TB_PF_IMAGE_BYTES estimate keeps in
 * each direction (1 of this many). */
#define TB_PREDICT_IMAGE_STEP 4

/* The TB_PF_IMAGE_BYTES estimate of an image: the size of the PNG of every
 * `step`-th pixel of img in each direction (step >= 1), times `scale`;
 * `expose`: scaled to the automatic exposure as the render's PNG is (a
 * linear pilot image), else written as it is (an image read from a PNG).
 * Writes and removes a temporary file (in $TMPDIR, else /tmp). */
tb_status tb_predict_image_bytes(const tb_image *img, int step, bool expose, double scale, double *bytes);

/* Writes COSTS.json (whole or not at all). */
tb_status tb_costs_write(const char *path, const tb_costs *c);

/* Reads COSTS.json. TB_ERR_IO if it cannot be read; TB_ERR_FORMAT with
 * "path:line:col: error: ..." for bad JSON, a wrong schema, a missing or
 * unknown term, or a negative or non-finite cost. */
tb_status tb_costs_read(const char *path, tb_costs *c);

/* Writes the prediction as JSON: {"seconds": ..., "peak_rss_bytes": ...,
 * "modules": {"load": s, ...}, "terms": {...}, "statistics": {...}}. */
void tb_prediction_write_json(FILE *out, const tb_costs *c, const tb_predict_stats *f, const tb_prediction *p);

#endif
