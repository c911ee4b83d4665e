/* IES LM-63 goniometric files: the luminous intensity of a luminaire as a
 * table of candela values over vertical and horizontal angles (docs/lights.md,
 * "IES files"). This module parses LM-63-1986/1991/1995/2002 files with
 * TILT=NONE and photometric type C, interpolates the table bilinearly in
 * (vertical, horizontal) angle with the standard symmetry conventions,
 * integrates it exactly (total flux) and samples directions from it.
 *
 * Angles and frame (type C): the vertical angle gamma runs from 0 at the
 * nadir (straight down) to 180 at the zenith; the horizontal angle C runs
 * counter-clockwise seen from above, 0 along the luminaire's +x axis. In the
 * PHOTOMETRIC FRAME used by the direction functions below the nadir is -z
 * and (gamma, C) is the unit direction
 *     (sin gamma cos C, sin gamma sin C, -cos gamma).
 * host/render/lights.h places this frame in the scene (docs/mid.md, 9).
 *
 * Candela values are returned as the file gives them times the candela
 * multiplier (absolute photometry in cd); tb_ies_normalized divides by the
 * largest table value, which is what a MID light uses. */
#ifndef TB_HOST_RENDER_IES_H
#define TB_HOST_RENDER_IES_H

#include <stddef.h>

#include "host/render/sampling.h"
#include "util/base/error.h"
#include "util/math/vec.h"

/* How the horizontal angles of the table cover the full circle. */
typedef enum tb_ies_symmetry {
    TB_IES_SYM_FULL = 0,     /* 0 .. 360: no symmetry */
    TB_IES_SYM_ROTATIONAL,   /* one horizontal angle (0): the same in every plane */
    TB_IES_SYM_QUADRANT,     /* 0 .. 90: symmetric about the 0-180 and 90-270 planes */
    TB_IES_SYM_BILATERAL,    /* 0 .. 180: symmetric about the 0-180 plane */
    TB_IES_SYM_BILATERAL_90, /* 90 .. 270: symmetric about the 90-270 plane */
} tb_ies_symmetry;

/* One [KEYWORD] line of the header. */
typedef struct tb_ies_keyword {
    char *key;   /* without the brackets, e.g. "MANUFAC" */
    char *value; /* the rest of the line, spaces trimmed */
} tb_ies_keyword;

/* A parsed IES file (read-only after tb_ies_parse; share between threads freely). */
typedef struct tb_ies {
    char version[16];          /* "LM-63-2002", "LM-63-1995", "LM-63-1991" or "LM-63-1986" */
    int nkeywords;
    tb_ies_keyword *keywords;  /* header keywords in file order */
    int lamps;                 /* number of lamps, >= 1 */
    double lumens_per_lamp;    /* rated lumens of each lamp; -1 for absolute photometry */
    double multiplier;         /* candela multiplier, > 0 (already applied to `candela`) */
    int photometric_type;      /* 1 = type C (the only one read) */
    int units;                 /* 1 = feet, 2 = metres (of the dimensions below) */
    double width, length, height; /* luminous opening, in `units` */
    double ballast_factor;     /* stored, not applied (docs/lights.md) */
    double ballast_lamp_factor;/* LM-63-1995 ballast-lamp photometric factor ("future use" in 2002); stored */
    double input_watts;        /* stored */
    int nv, nh;                /* number of vertical and horizontal angles */
    double *v_angles;          /* nv vertical angles, degrees, strictly increasing, within [0, 180] */
    double *h_angles;          /* nh horizontal angles, degrees, strictly increasing */
    double *candela;           /* nh x nv: candela[h * nv + v] = file value x multiplier (cd) */
    tb_ies_symmetry symmetry;  /* from the horizontal angle range */
    double max_candela;        /* largest value of `candela` (> 0) */
    /* Sampling table: cells of a grid over (gamma, C) covering the full
     * circle, each with the mean of the interpolated intensity at its corners;
     * directions are drawn cell by cell in proportion to mean x solid angle and
     * uniformly by solid angle inside a cell. */
    int sv, sh;                /* grid breakpoints in gamma and C */
    double *s_gamma;           /* sv vertical breakpoints (degrees) */
    double *s_c;               /* sh horizontal breakpoints over [0, 360] (degrees) */
    double *s_mean;            /* (sv-1) x (sh-1) corner means, row (gamma) major */
    tb_distrib1d s_cells;      /* over the cells, weight mean x solid angle */
} tb_ies;

/* Parses `len` bytes of LM-63 text (need not be NUL-terminated). `name`
 * appears in messages ("name:LINE: error: ..."). On error *out is NULL and the
 * status is TB_ERR_FORMAT (malformed, truncated, inconsistent),
 * TB_ERR_UNSUPPORTED (TILT=INCLUDE or a tilt file, photometric type A or B)
 * or TB_ERR_NOMEM. */
tb_status tb_ies_parse(const char *text, size_t len, const char *name, tb_ies **out);

/* Reads and parses the file at `path` (at most 64 MiB); TB_ERR_IO if it cannot be read. */
tb_status tb_ies_read(const char *path, tb_ies **out);

/* Frees a parsed file; NULL is allowed. */
void tb_ies_free(tb_ies *ies);

/* Candela (file value x multiplier) at vertical angle `vertical` and
 * horizontal angle `horizontal`, in degrees: the horizontal angle is reduced
 * by the file's symmetry into the table's range (any real value is
 * accepted: it is taken modulo 360), then the table is interpolated
 * bilinearly in (vertical, horizontal). At a tabulated pair of angles the
 * result is exactly the tabulated value. 0 for vertical angles outside the
 * table's range (e.g. above 90 in a file that stops at 90) and for NaN. */
double tb_ies_candela(const tb_ies *ies, double vertical, double horizontal);

/* The photometric angles (degrees) of a direction in the photometric frame
 * (nadir -z; C = 0 along +x, C = 90 along +y); w need not be unit length. C is
 * in [0, 360). */
void tb_ies_angles(tb_vec3 w, double *vertical, double *horizontal);

/* The unit direction of (vertical, horizontal) in the photometric frame. */
tb_vec3 tb_ies_direction(double vertical, double horizontal);

/* tb_ies_candela in direction w of the photometric frame. */
double tb_ies_candela_dir(const tb_ies *ies, tb_vec3 w);

/* tb_ies_candela_dir / max_candela: in [0, 1] (the MID normalisation). */
double tb_ies_normalized(const tb_ies *ies, tb_vec3 w);

/* Total flux: the exact integral over the sphere of the interpolated
 * intensity (piecewise bilinear in the angles), in lumens when the values are
 * in candela. Compare with lamps x lumens_per_lamp for relative photometry. */
double tb_ies_flux(const tb_ies *ies);

/* Samples a direction of the photometric frame with density (solid angle)
 * *pdf, roughly proportional to the intensity (exactly so within each cell
 * of the sampling grid up to the intensity's variation in the cell); never a
 * direction of zero intensity's cell. */
tb_vec3 tb_ies_sample(const tb_ies *ies, float u1, float u2, double *pdf);

/* Density of tb_ies_sample at direction w (photometric frame). */
double tb_ies_pdf(const tb_ies *ies, tb_vec3 w);

#endif
