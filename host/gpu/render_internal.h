/* What the files of the Vulkan ray tracer (render.h) share: the renderer,
 * the paths of a wavefront call, and the steps each file provides.
 *
 *     render_route.c      materials -> shading features -> kernel or CPU path
 *     render_upload.c     tb_gpu_renderer_create: tables and buffers on the device
 *     render_wavefront.c  the intersect -> shade -> occlude loop (tb_gpu_radiance)
 *     render_adaptive.c   adaptive antialiasing in rounds of wavefront calls
 *     render.c            tb_gpu_render_raytrace on host/render's pass driver
 *
 * Not installed (an _internal.h header). */
#ifndef TB_HOST_GPU_RENDER_INTERNAL_H
#define TB_HOST_GPU_RENDER_INTERNAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "host/gpu/gpu.h"
#include "host/gpu/intersect.h"
#include "host/gpu/render.h"
#include "host/render/camera.h"
#include "host/render/raytrace.h"
#include "host/render/render_internal.h"
#include "shaders/shared/hit.h"
#include "shaders/shared/ray.h"
#include "shaders/shared/shade.h"
#include "util/math/rng.h"

/* Most light samples per point (raytrace.c's stack array). */
#define TB__GR_MAX_LIGHT_SAMPLES 1024
/* Largest output of one shade dispatch, bytes (rays plus values). */
#define TB__GR_CHUNK_BYTES (24u << 20)
/* Specialization constants of the shade kernel (ids 1 .. 17). */
#define TB__GR_SPEC 17

/* What the kernel must handle, over the materials it shades (and the
 * scene's lights and emitters): its specialization constants. */
typedef struct tb__gr_uses {
    bool spot, ies;                 /* some delta light is a spot, has an IES table */
    uint32_t emitter_kinds;         /* bit per tb_emitter_kind sampled (1 when there is no emitter) */
    bool phong, mirror, dielectric; /* highlights of delta lights, mirror rays, refraction */
    bool emission, ggx;
    bool colour_pattern, bump, texture;
    uint32_t pattern_kinds;         /* bit per TB_GPU_PATTERN_* */
} tb__gr_uses;

struct tb_gpu_renderer {
    tb_gpu_device *dev;
    const tb_scene *scene;
    tb_gpu_scene *gscene;
    tb_raytracer rt;      /* the CPU tracer: routed hits, light-sample strata, the area light's CDF */
    int nch;              /* channels */
    int nlights;          /* delta lights */
    int nsamples;         /* area-light samples per point (0: no area light) */
    int S;                /* shadow slots per item */
    int sw;               /* words per shadow slot (3, or 4 with GGX: shared/shade.h) */
    int nglossy;          /* most glossy rays per item (0: no GGX material) */
    int lu_per;           /* light-sample buffer entries per item: nsamples + nglossy */
    int cap_stack;        /* stack entries per path */
    int pw0;              /* pattern words per item (2 with colour patterns, else 0) */
    int pw;               /* pattern and texture words per item (pw0, and 6 with textures) */
    bool any_surface;     /* some material has a pattern or a bump map: items carry surface records */
    size_t tex_floats;    /* floats of the distinct images' MIP pyramids (RGB scenes) */
    tb__gr_uses uses;     /* what the kernel is specialised for */
    uint32_t *features;   /* per material: its shading features (host/render/features.h) */
    uint8_t *mpat;        /* per material: its hits need a surface record: 1 for a pattern or bump map
                             (routed without tangents), 2 for image textures only */
    uint32_t *pat_col;    /* per material: colour-table offsets of its diffuse and specular pattern colours
                             (a, then b; 0: no pattern) */
    char **route;         /* per material: why it is routed, or NULL */
    uint8_t *mflags;      /* per material: TB_GPU_MAT_* */
    tb_gpu_spec_constant spec[TB__GR_SPEC];
    tb_gpu_buffer *b_texinfo, *b_texels; /* image textures: records and MIP pyramids */
    tb_gpu_buffer *b_surf;  /* surface records of one chunk (item j's at j) */
    tb_gpu_buffer *b_items, *b_lightu, *b_emitters, *b_lights, *b_materials, *b_colours, *b_rays, *b_values;
    size_t chunk;         /* items per shade dispatch */
    uint32_t light_col, emitter_col, perm_col;
    float *col;           /* the colour table (as uploaded): the host applies the shadow rays' colours */
    int threads;          /* OpenMP threads of the host's loops (0: OpenMP's default) */
    /* host staging of one chunk */
    tb_gpu_shade_item *items;
    tb_gpu_light_u *lightu;
    tb_gpu_surface *surf;
    tb_ray *orays;
    float *ovals;
    tb_gpu_render_stats st;
};

/* Monotonic wall clock, seconds. */
double tb__gr_now(void);

/* The shade kernel's record of emitter e of area `area` (render_upload.c;
 * the path tracer's kernel reads the same records). */
tb_gpu_emitter tb__gpu_emitter_record(const tb_emitter *e, double area);

/* render_route.c: the features of every material, which are routed (and
 * why), the kernel's per-material flags and what the kernel must handle
 * (r->uses). TB_ERR_NOMEM. */
tb_status tb__gr_route_materials(tb_gpu_renderer *r);

/* Per-path state of one wavefront call. A path is one camera sample (or
 * one ray of tb_gpu_radiance); its stack holds the rays still to trace, each
 * with its depth and throughput. */
typedef struct tb__paths {
    size_t n;
    int cap;            /* stack entries per path */
    int nch;
    tb_ray *ray;        /* [path * cap + k] */
    int *depth;
    float *thr;         /* [(path * cap + k) * nch + c] */
    tb_rt_mis *mis;     /* a glossy ray's weighting context (nb = 0: not a glossy ray) */
    int *top;           /* entries on each stack */
    tb_rng *rng;        /* the paths' streams (caller's) */
    float *L;           /* [path * nch + c] (caller's) */
    /* renderer: film positions and the streams before the lens draws, so a
     * camera ray whose hit is routed is traced as tb_rt_sample traces it
     * (with ray differentials for its textures) */
    const double *xy;   /* NULL: plain rays */
    const tb_rng *rng0;
} tb__paths;

/* Allocates the stacks of n paths (the streams, radiance and film
 * positions are the caller's). */
tb_status tb__gr_paths_alloc(tb__paths *P, size_t n, int cap, int nch);

/* Frees what tb__gr_paths_alloc allocated. */
void tb__gr_paths_free(tb__paths *P);

/* Pushes a ray with its depth, throughput thr[0 .. nch) and glossy
 * weighting (NULL: none) on path p's stack. */
void tb__gr_push(tb__paths *P, size_t p, const tb_ray *ray, int depth, const float *thr, const tb_rt_mis *mis);

/* Pushes the camera ray of film point (x, y) for path q with stream *rng
 * (from tb_aa_sample_rng), as tb_rt_sample makes it (the lens numbers
 * first); keeps the stream before the lens draws in rng0. */
void tb__gr_push_camera(tb__paths *P, size_t q, const tb_camera *cam, double x, double y, tb_rng *rng,
                        tb_rng *rng0);

/* Traces every path's stack empty, adding radiance to P->L. */
tb_status tb__gr_wavefront(tb_gpu_renderer *r, tb__paths *P);

/* The samples of the row batches and adaptive rounds of a render. */
typedef struct tb__gr_batch {
    tb_gpu_renderer *r;
    tb__paths P;
    size_t cap;         /* samples per wavefront call */
    double *xy;         /* film positions (cap x 2) */
    tb_rng *rng, *rng0; /* streams, and before the lens draws (cap) */
    float *L;           /* radiance (cap x nch) */
    int nth;            /* OpenMP threads of the host's loops */
} tb__gr_batch;

/* render_adaptive.c: one adaptive pass (tb__render_engine.pass) over the
 * film's tiles in batches whose first rounds fit one wavefront call. */
tb_status tb__gr_adaptive_pass(tb__gr_batch *b, tb__render_run *run, tb_film *film, const tb_aa_options *aa,
                               tb_aa_stats *as);

/* Marks tiles t .. ntiles-1 skipped (a stopped render), counted in as. */
void tb__gr_skip_tiles(tb_film *film, int t, tb_aa_stats *as);

#endif
