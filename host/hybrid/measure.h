/* Virtual instruments (docs/measure.md): irradiance meters (cosine-corrected,
 * at a point, facing a direction) and radiance meters (at a point, looking
 * along a direction through an acceptance cone) read off a scene by the path
 * tracer or from a radiosity solution, with standard errors from independent
 * sample batches, optional spectral filters, and a comparison with measured
 * values. `testbed measure` is this module on the command line.
 *
 *     tb_sensor_set ss;
 *     if (tb_sensors_read_file("sensors.csv", &ss)) die(tb_last_error());
 *     tb_measure_result *r = calloc(ss.n, sizeof *r);
 *     tb_measure_options o = tb_measure_defaults();
 *     if (tb_measure(scene, &ss, &o, r)) die(tb_last_error());
 *     tb_measure_write_csv(stdout, scene, &ss, r);
 *
 * Deterministic: the same scene, sensors, seed and options give the same
 * bits for any thread count (a random stream per sensor and batch). */
#ifndef TB_HOST_HYBRID_MEASURE_H
#define TB_HOST_HYBRID_MEASURE_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "host/hybrid/hybrid.h"
#include "host/render/channels.h"
#include "host/render/scene.h"
#include "util/base/error.h"
#include "util/color/spectrum.h"
#include "util/math/vec.h"

/* What a sensor measures. */
typedef enum tb_sensor_kind {
    TB_SENSOR_IRRADIANCE = 0, /* cosine-corrected meter: W/m^2 per channel (W/m^2/nm per band), lux */
    TB_SENSOR_RADIANCE,       /* mean radiance over a cone of directions: W/m^2/sr (per nm), cd/m^2 */
} tb_sensor_kind;

/* The most characters of a sensor name. */
#define TB_SENSOR_NAME_MAX 127

/* One instrument of a sensors file. */
typedef struct tb_sensor {
    char name[TB_SENSOR_NAME_MAX + 1]; /* unique within its set */
    tb_sensor_kind kind;
    tb_vec3 p;             /* position (world units) */
    tb_vec3 d;             /* unit direction: the meter's normal (irradiance) or viewing axis (radiance) */
    double half_angle_deg; /* radiance: acceptance cone half-angle in (0, 90]; irradiance: 0 */
    char *filter_path;     /* the filter file as resolved (relative to the sensors file), or NULL */
    tb_spectrum filter;    /* spectral transmission (n == 0: none) */
    long line;             /* line of the sensors file */
} tb_sensor;

/* A sensors file. */
typedef struct tb_sensor_set {
    int n;         /* sensors */
    tb_sensor *s;  /* n sensors in file order */
    bool filtered; /* some sensor has a filter (the scene must then be spectral) */
} tb_sensor_set;

/* Reads a sensors CSV (docs/measure.md): a header `name,kind,x,y,z,dx,dy,dz`
 * optionally followed by `half_angle_deg` and `filter`, then one sensor per
 * line; `#` lines and blank lines are skipped. Filter files (spectrum files,
 * nm and value) are resolved relative to the sensors file's folder. A bad
 * row gives TB_ERR_FORMAT "FILE:LINE: error: ..."; a missing file TB_ERR_IO.
 * *out is zeroed on failure. */
tb_status tb_sensors_read_file(const char *path, tb_sensor_set *out);

/* tb_sensors_read_file from an open stream; `name` is used in messages,
 * filters resolve against `base_dir` (NULL: the current folder). */
tb_status tb_sensors_read_stream(FILE *f, const char *name, const char *base_dir, tb_sensor_set *out);

/* Frees a sensor set (harmless on a zeroed one). */
void tb_sensors_free(tb_sensor_set *set);

/* How the readings are estimated. */
typedef enum tb_measure_method {
    TB_MEASURE_PATH = 0,  /* the path tracer's radiance, NEE + MIS on every light (unbiased) */
    TB_MEASURE_RADIOSITY, /* direct light exact by light sampling + reflected light of a radiosity solution */
} tb_measure_method;

/* Independent batches the samples of a sensor are split into (standard errors). */
#define TB_MEASURE_BATCHES 16
/* Default samples per sensor. */
#define TB_MEASURE_DEFAULT_SAMPLES 4096

/* Options of tb_measure; tb_measure_defaults() gives the defaults. */
typedef struct tb_measure_options {
    tb_measure_method method;
    int samples;              /* per sensor, rounded up to a multiple of TB_MEASURE_BATCHES (>= 1) */
    uint64_t seed;            /* seeds every sensor's streams */
    int threads;              /* 0: OpenMP's default */
    tb_hybrid_options rad;    /* radiosity method: the mesh and solver (mode and gather rays are ignored) */
    bool progress;            /* progress bar with ETA on a terminal */
    FILE *log;                /* one line about the radiosity pass, or NULL */
} tb_measure_options;

/* Path method, TB_MEASURE_DEFAULT_SAMPLES, seed 1, the radiosity defaults. */
tb_measure_options tb_measure_defaults(void);

/* One sensor's reading. */
typedef struct tb_measure_result {
    int nc;                         /* channels (the scene's) */
    double value[TB_CHANNELS_MAX];  /* per channel, the filter applied */
    double value_se[TB_CHANNELS_MAX]; /* standard error of each */
    double reading, reading_se;     /* the radiometric reading: spectral, int value dl over the bands
                                       (W/m^2 or W/m^2/sr); RGB, the luminance Y of the channels */
    double photometric, photometric_se; /* 683 lm/W int value ybar dl: lux or cd/m^2 */
    int samples;                    /* samples taken */
} tb_measure_result;

/* Reads every sensor of `set` off scene `s` (loaded with an acceleration
 * structure; spectral if set->filtered) into out[0 .. set->n).
 * TB_ERR_ARG for bad options or a filter on an RGB scene; the path tracer's
 * and the radiosity pass's errors. */
tb_status tb_measure(const tb_scene *s, const tb_sensor_set *set, const tb_measure_options *o,
                     tb_measure_result *out);

/* Writes the readings as CSV (docs/measure.md, "Output"). TB_ERR_IO on a
 * write error. */
tb_status tb_measure_write_csv(FILE *f, const tb_scene *s, const tb_sensor_set *set, const tb_measure_result *r);

/* Prints the readings as an aligned table. */
void tb_measure_print_table(FILE *f, const tb_sensor_set *set, const tb_measure_result *r);

/* One measured value of a MEASURED file. */
typedef struct tb_measured {
    int sensor;         /* index in the sensor set */
    double value;       /* measured reading */
    double uncertainty; /* standard uncertainty (0: not given) */
    long line;          /* line of the file */
} tb_measured;

/* A MEASURED file. */
typedef struct tb_measured_set {
    int n;
    tb_measured *m; /* in file order */
} tb_measured_set;

/* Reads a MEASURED CSV: header `name,value` or `name,value,uncertainty`,
 * one row per sensor of `sensors` (`#` and blank lines skipped). A bad row
 * (unknown sensor name, duplicate, non-number, negative uncertainty) gives
 * TB_ERR_FORMAT "FILE:LINE: error: ...". *out is zeroed on failure. */
tb_status tb_measured_read_file(const char *path, const tb_sensor_set *sensors, tb_measured_set *out);

/* tb_measured_read_file from an open stream; `name` is used in messages. */
tb_status tb_measured_read_stream(FILE *f, const char *name, const tb_sensor_set *sensors, tb_measured_set *out);

/* Frees a measured set (harmless on a zeroed one). */
void tb_measured_free(tb_measured_set *set);

/* Which simulated quantity a measured value is compared with. */
typedef enum tb_compare_quantity {
    TB_COMPARE_READING = 0, /* tb_measure_result.reading */
    TB_COMPARE_PHOTOMETRIC, /* tb_measure_result.photometric */
} tb_compare_quantity;

/* The comparison of simulated readings with measured ones. */
typedef struct tb_compare_summary {
    int compared;      /* measured values compared */
    int disagree;      /* |residual| > k * combined uncertainty */
    double rms_rel;    /* root mean square relative error (over measured values != 0) */
    double max_rel;    /* largest |relative error| */
    double rms_resid;  /* root mean square residual */
    double max_resid;  /* largest |residual| */
} tb_compare_summary;

/* Compares: per measured value, residual = simulated - measured, relative
 * error = residual / measured, combined uncertainty sqrt(u_meas^2 + se^2),
 * disagreement when |residual| > k times it. Prints a table (to f, may be
 * NULL) and the summary line; fills *sum. */
void tb_measure_compare(FILE *f, const tb_sensor_set *set, const tb_measure_result *r, const tb_measured_set *m,
                        tb_compare_quantity q, double k, tb_compare_summary *sum);

#endif
