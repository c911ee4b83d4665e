/* Progressive-refinement radiosity (Cohen, Chen, Wallace and Greenberg 1988)
 * over a mesh of planar elements (docs/radiosity.md):
 *
 *     tb_rad_mesh m;
 *     tb_rad_mesh_from_scene(scene, NULL, &m);         // or build one yourself
 *     tb_rad_solver *s;
 *     tb_rad_solver_create(&m, NULL, &opt, &s);        // NULL state: nothing shot yet
 *     tb_rad_stop stop = {.threshold = 3e-3};
 *     tb_rad_solver_run(s, &stop, NULL, NULL);
 *     tb_rad_element_radiosity(s, i, true, b);          // b[0..nchannels)
 *     tb_rad_solver_free(s);
 *
 * Representation. Radiosity B and emission E are per unit area, in the
 * scene's colour channels (RGB, or spectral render bands), in the unit of
 * MID emission: W/m^2 per channel (W/m^2/nm per band); radiance is B / pi.
 * The solver keeps
 *   - per VERTEX, the gathered irradiance H_v (per channel): the sum over
 *     shots of dB_shooter F(v -> shooter), a vertex being a receiver point
 *     with its own normal (Wallace, Elmquist and Haines 1989);
 *   - per ELEMENT, the gathered irradiance H_e, the sum over shots of
 *     dB_shooter F_e,shooter (the mean of its corners' point form factors,
 *     or a better estimate next to the shooter: docs/radiosity.md), and the
 *     unshot radiosity dB_e (per channel).
 * An element's radiosity is E_e + rho_e * H_e; the value at corner k of
 * element e (for Gouraud display) is E_e + rho_e * H_v. So vertices may be
 * shared by elements of different materials, and refining an element
 * (adaptive subdivision) only needs H at the new vertices, and H and dB for
 * the children (their parent's: both are densities), given to
 * tb_rad_solver_create as the initial state.
 *
 * With TB_RAD_FF_HEMICUBE the form factors are element to element, from a
 * hemicube at the shooter's centroid; H is then kept per element and H_v is
 * the area-weighted mean of the elements around v that face the same way.
 *
 * Determinism: the shooter is the element with the most unshot power
 * (ties: the lower index, util/container/pqueue.h); the sample points of
 * shooter k come from a PCG32 stream seeded by (seed, k), the same at every
 * shot of k (so its form factors, rounded to float, are cached); form-factor
 * backends answer independently of the thread count. So the solution is
 * bit-identical for any thread count. */
#ifndef TB_HOST_RADIOSITY_RADIOSITY_H
#define TB_HOST_RADIOSITY_RADIOSITY_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "host/radiosity/formfactor.h"
#include "host/render/scene.h"
#include "util/base/error.h"
#include "util/math/vec.h"

struct tb_image;
struct tb_provenance;

/* "No vertex / no element" in radiosity mesh indices. */
#define TB_RAD_NONE UINT32_MAX

/* Default stop threshold on the unshot fraction of emitted power. */
#define TB_RAD_DEFAULT_THRESHOLD 3e-3

/* Default samples per shooter for ray-cast form factors. */
#define TB_RAD_DEFAULT_SAMPLES 16

/* Default hemicube resolution (top face, pixels per side). */
#define TB_RAD_DEFAULT_HEMICUBE_RES 128

/* A receiver point: an element corner with the normal it receives with. */
typedef struct tb_rad_vertex {
    tb_vec3 p; /* world position */
    tb_vec3 n; /* unit normal (the surface's, for curved objects; the element plane's at a crease) */
} tb_rad_vertex;

/* One element: a planar convex triangle or quad. */
typedef struct tb_rad_element {
    uint32_t v[4];     /* vertices, counter-clockwise seen from the front; v[3] == TB_RAD_NONE for a triangle */
    uint32_t object;   /* top-level object index (MID order) */
    uint32_t parent;   /* element it was split from, or TB_RAD_NONE (informative; the solver ignores it) */
    double area;       /* filled by tb_rad_mesh_update_geometry */
    tb_vec3 centroid;  /* filled by tb_rad_mesh_update_geometry (area centroid) */
    tb_vec3 normal;    /* filled by tb_rad_mesh_update_geometry (unit, Newell) */
} tb_rad_element;

/* An element mesh with its materials. Arrays are owned (malloc) when made
 * by this module; tb_rad_mesh_free frees them. */
typedef struct tb_rad_mesh {
    int nchannels;          /* channels per colour: 3 (RGB) or the number of bands */
    bool spectral;          /* channels are bands (see `bands`) */
    tb_bands bands;         /* the bands when spectral */
    size_t nverts;
    tb_rad_vertex *verts;
    size_t nelems;
    tb_rad_element *elems;
    float *rho;             /* nelems * nchannels: diffuse reflectance, in [0, 1) */
    float *emission;        /* nelems * nchannels: emitted radiosity (W/m^2 per channel) */
    /* Patches (Cohen et al. 1986): coarse shooters, each the union of its
     * elements. npatches == 0: one level, every element its own patch. */
    size_t npatches;
    uint32_t *patch;        /* nelems: the patch of each element (npatches > 0), else NULL */
    tb_ff_polygon *patch_poly; /* npatches: each patch's outline (its shots' sample points lie on it) */
} tb_rad_mesh;

/* How to mesh a scene; zeroed means faces whole (the command's default
 * meshing is tb_rad_default_mesh_options). */
typedef struct tb_rad_mesh_options {
    double max_edge;  /* > 0: longest element edge (world units); 0: none */
    double max_area;  /* > 0: largest element area (world units^2); 0: none */
    double max_angle; /* curved surfaces: polygonization angle (radians); 0: the object level's default */
    double patch_edge; /* > 0: faces are first cut into patches with no edge longer than this, each then
                          meshed into elements (needs an element size no larger); 0: none */
    double patch_area; /* > 0: largest patch area (an edge bound of its square root); 0: none */
} tb_rad_mesh_options;

/* The element size `testbed render --method radiosity` uses when neither
 * --max-edge nor --max-area is given: the scene's bounding-box diagonal over
 * this (the Cornell box: 960.7 / 24 = 40 mm, 1322 elements). */
#define TB_RAD_DEFAULT_EDGE_DIVISIONS 24

/* The command's default meshing of `scene`: max_edge = the diagonal of its
 * bounds over TB_RAD_DEFAULT_EDGE_DIVISIONS (0, faces whole, when the
 * bounds are empty or not finite) and max_angle = the polygonizer's default
 * angle (TB_POLY_DEFAULT_ANGLE, 15 degrees), which an edge limit alone
 * would turn off: curved surfaces stay as round as with faces whole. */
tb_rad_mesh_options tb_rad_default_mesh_options(const tb_scene *scene);

/* An empty mesh. */
void tb_rad_mesh_init(tb_rad_mesh *m);

/* Frees the arrays (the mesh stays a valid empty mesh). */
void tb_rad_mesh_free(tb_rad_mesh *m);

/* Every object of `scene` polygonized in world space, meshed into elements
 * (util/mesh/mesh.h) and given its material's diffuse reflectance and
 * emission. Vertices are shared within an object between elements that
 * face the same way (within 30 degrees) and split at creases. TB_ERR_ARG
 * for bad options, TB_ERR_UNSUPPORTED for a reflectance >= 1 (the solution
 * would not converge), TB_ERR_NOMEM. */
tb_status tb_rad_mesh_from_scene(const tb_scene *scene, const tb_rad_mesh_options *opt, tb_rad_mesh *out);

/* Recomputes area, centroid and normal of every element from its vertices;
 * TB_ERR_ARG for an out-of-range vertex index or a degenerate element. */
tb_status tb_rad_mesh_update_geometry(tb_rad_mesh *m);

/* Copies src's patches into dst (whose own are freed first): the outlines,
 * and for every element i of dst the patch of src's element map[i] (map
 * NULL: the same index; dst->nelems must then equal src->nelems). A src
 * without patches leaves dst without. TB_ERR_NOMEM. */
tb_status tb_rad_mesh_copy_patches(tb_rad_mesh *dst, const tb_rad_mesh *src, const uint32_t *map);

/* Element i as a form-factor polygon. */
void tb_rad_mesh_polygon(const tb_rad_mesh *m, size_t i, tb_ff_polygon *out);

/* The elements that can block a segment between two points of the mesh,
 * as polygons, into out[0..nelems): all but those whose plane has every
 * vertex of the mesh on its front (within 1e-6 of the mesh's size): a
 * segment between two points in front of a plane cannot cross it, so the
 * walls of a room never occlude. The kept elements of one object that tile
 * a flat convex triangle or quad (a block's side cut into a grid) are
 * written as that one polygon. The same visibility, fewer occluders.
 * Returns how many were written. Gives up (keeps all) when the mesh has so
 * many distinct planes that the check would cost more than 5e7 tests. */
size_t tb_rad_mesh_occluders(const tb_rad_mesh *m, tb_ff_polygon *out);

/* Form-factor method. */
typedef enum tb_rad_ff_method {
    TB_RAD_FF_RAYCAST = 0, /* shooter samples to receiver vertices, visibility by rays */
    TB_RAD_FF_HEMICUBE,    /* hemicube at the shooter's centroid, element to element */
} tb_rad_ff_method;

/* Solver options; zeroed means defaults. */
/* A shot's receivers shared over the processes of a job (host/dist over
 * MPI; host/radiosity does not know MPI). Every process runs the same
 * solver on the same mesh: each computes the ray-cast form factors of its
 * share of the receiver clusters (cluster c belongs to process c mod
 * ranks), the shares are gathered, and every process then makes the same
 * update, so the shooting order and every value are those of one process. */
typedef struct tb_rad_exchange {
    void *ctx;  /* passed to every function */
    int rank;   /* this process */
    int ranks;  /* processes in the job */
    /* Collective: every process's `mine` (n_mine values, for `receivers` of
     * its receivers) concatenated in rank order into all[] (counts[r] values
     * from rank r). */
    tb_status (*allgather)(void *ctx, const double *mine, size_t n_mine, double *all, const size_t *counts,
                           size_t receivers);
    /* The same for floats (the several-shooters mode's form factors). */
    tb_status (*allgatherf)(void *ctx, const float *mine, size_t n_mine, float *all, const size_t *counts);
    /* Collective, the update split over processes by shooter (docs/distributed.md):
     * buf holds n doubles, every process's own: buf[0] = h (the same everywhere),
     * buf[1..h) a candidate (buf[1] its unshot power, buf[2] its shooter's key,
     * then its payload), buf[h..n) values only one process has nonzero. On return
     * every process has the candidate of the largest power (ties: the lower key)
     * and the element-wise sums of the rest (exact: one term is nonzero).
     * NULL: no split. */
    tb_status (*select)(void *ctx, double *buf, size_t n);
    /* As allgather, for the solver's state (gathered when a split solve ends:
     * not counted as receivers). */
    tb_status (*allgather_state)(void *ctx, const double *mine, size_t n_mine, double *all, const size_t *counts);
    /* Rank 0's `flag` on every process (a stop decision that reads a clock). */
    int (*agree)(void *ctx, int flag);
    /* The lowest-ranked failure among every process's `st` (its message as
     * this process's last error), or TB_OK on all. */
    tb_status (*agree_status)(void *ctx, tb_status st);
    /* After the solve, on every process: each process's share of the work
     * into the stats values. NULL: nothing. */
    tb_status (*report)(void *ctx);
    /* A failure on this process alone during the solve (`st`, its message in
     * tb_last_error()), where the others cannot learn of it: stops every
     * process of the job with that message (does not return). NULL: return
     * the failure (the others may then wait for this one forever). */
    void (*fail)(void *ctx, tb_status st);
    /* false: the deterministic mode above. true: several shooters in flight
     * (one per process, at most TB_RAD_MAX_IN_FLIGHT): each process
     * computes one shooter's form factors whole, all are exchanged, and
     * every process shoots them in rank order. Faster (one exchange per
     * `ranks` shots, no waiting on each other's rays) but a different
     * shooting order: the answer depends on the number of processes
     * (docs/distributed.md gives the measured difference). */
    bool several;
} tb_rad_exchange;

/* Most shooters in flight at once in the several-shooters mode. */
#define TB_RAD_MAX_IN_FLIGHT 1024

typedef struct tb_rad_options {
    tb_rad_ff_method ff;  /* form-factor method */
    int samples;          /* ray cast: sample points per shooter; 0: TB_RAD_DEFAULT_SAMPLES */
    int hemicube_res;     /* hemicube: top-face resolution; 0: TB_RAD_DEFAULT_HEMICUBE_RES */
    uint64_t seed;        /* seeds the shooters' sample points */
    tb_ff_batch_fn batch; /* ray cast backend; NULL: tb_ff_raycast_batch over occluders the solver builds */
    void *batch_ctx;      /* its context (occluders over tb_rad_mesh_occluders, or every element) */
    bool no_occlusion;    /* ray cast with the CPU backend: no visibility test (convex enclosures, tests) */
    bool no_cache;        /* do not keep each shooter's form factors for its next shots (up to 512 MB are
                             kept by default; the answer is the same either way) */
    const tb_light *lights; /* point, spot and directional lights shot as sources (host/radiosity/lights.h),
                               copied at create; an IES table they point to must outlive the solver */
    int nlights;            /* how many */
    const tb_rad_exchange *exchange; /* NULL: one process; else ray-cast form factors (CPU backend) shared
                                      * over processes, the same answer */
} tb_rad_options;

/* Initial state (e.g. carried over a refinement); NULL arrays mean zero H
 * and "everything still to shoot" (dB = E). */
typedef struct tb_rad_state {
    const double *gathered;       /* nverts * nchannels: H_v (ray cast) -- or nelems * nchannels: H_e (hemicube) */
    const double *unshot;         /* nelems * nchannels: dB_e */
    const double *gathered_elems; /* ray cast: nelems * nchannels: H_e; NULL: the mean of the corners' H_v */
    const unsigned char *lights_shot; /* nlights: nonzero for a light already shot; NULL: none yet */
} tb_rad_state;

/* A solver (opaque). */
typedef struct tb_rad_solver tb_rad_solver;

/* A solver for `mesh` (copied; geometry must be up to date), starting from
 * `state` (NULL: nothing shot). TB_ERR_ARG for bad options, an empty mesh
 * or reflectances outside [0, 1); TB_ERR_NOMEM; the backend's errors. */
tb_status tb_rad_solver_create(const tb_rad_mesh *mesh, const tb_rad_state *state, const tb_rad_options *opt,
                               tb_rad_solver **out);

/* Frees a solver; NULL is allowed. */
void tb_rad_solver_free(tb_rad_solver *s);

/* The solver's copy of the mesh. */
const tb_rad_mesh *tb_rad_solver_mesh(const tb_rad_solver *s);

/* Shoots the patch (the element, on one level) with the most unshot power once, or a light not yet
 * shot whose power is at least that (each light shoots once, directly:
 * host/radiosity/lights.h). *shot (may be NULL) is false if nothing was
 * left to shoot. */
tb_status tb_rad_solver_step(tb_rad_solver *s, bool *shot);

/* When to stop tb_rad_solver_run (any condition that is set). */
typedef struct tb_rad_stop {
    double threshold;   /* unshot fraction of emitted power; <= 0: TB_RAD_DEFAULT_THRESHOLD */
    double time_budget; /* > 0: seconds of wall time; 0: none */
    uint64_t max_shots; /* > 0: shots in this call; 0: none */
    bool progress;      /* draw a progress bar with ETA on a terminal (util/base/progress.h) */
} tb_rad_stop;

/* Called by tb_rad_solver_run after every `every` shots and at the end;
 * a non-OK status stops the run and is returned. */
typedef tb_status (*tb_rad_report_fn)(void *user, const tb_rad_solver *s);

/* Shoots until a stop condition holds (or nothing is left to shoot). */
tb_status tb_rad_solver_run(tb_rad_solver *s, const tb_rad_stop *stop, tb_rad_report_fn report, void *user,
                            uint64_t every);

/* Shots so far (this solver). */
uint64_t tb_rad_solver_shots(const tb_rad_solver *s);

/* Wall seconds spent shooting so far. */
double tb_rad_solver_seconds(const tb_rad_solver *s);

/* Unshot power over emitted power, summed over channels (1 before the first
 * shot from a fresh start; 0 if nothing emits). */
double tb_rad_unshot_fraction(const tb_rad_solver *s);

/* Power bookkeeping, summed over channels (W, or W/nm per band, times the
 * scene's units^2): emitted (sum E A, plus the lights' power), absorbed
 * (sum over shots of the received power times 1 - rho), unshot (sum dB A,
 * plus the power of lights not yet shot) and escaped (shot power that
 * reached no element: leaves an open scene, or form-factor error). */
typedef struct tb_rad_energy {
    double emitted, absorbed, unshot, escaped;
} tb_rad_energy;

/* The bookkeeping above. emitted == absorbed + unshot + escaped up to rounding. */
tb_rad_energy tb_rad_solver_energy(const tb_rad_solver *s);

/* The ambient term (Cohen et al. 1988): per channel, sum(dB A) / sum(A)
 * times 1 / (1 - area-weighted mean rho). out[0..nchannels). */
void tb_rad_ambient(const tb_rad_solver *s, double *out);

/* Radiosity of element i, out[0..nchannels); with `ambient`, plus rho times
 * the ambient term. */
void tb_rad_element_radiosity(const tb_rad_solver *s, size_t i, bool ambient, double *out);

/* Shooters of the solver: the mesh's patches, or its elements when it has
 * none (patch p is then element p). */
size_t tb_rad_solver_npatches(const tb_rad_solver *s);

/* Radiosity of patch p: the area-weighted mean of its elements'
 * (tb_rad_element_radiosity), out[0..nchannels). */
void tb_rad_patch_radiosity(const tb_rad_solver *s, size_t p, bool ambient, double *out);

/* Unshot power of patch p (summed over channels) as the shooter queue holds
 * it: the sum of its elements' unshot powers, 0 once shot. */
double tb_rad_patch_unshot_power(const tb_rad_solver *s, size_t p);

/* Unshot radiosity of element i, out[0..nchannels). */
void tb_rad_element_unshot(const tb_rad_solver *s, size_t i, double *out);

/* Radiosity at corner k of element i (Gouraud display), out[0..nchannels). */
void tb_rad_corner_radiosity(const tb_rad_solver *s, size_t i, int k, bool ambient, double *out);

/* tb_rad_corner_radiosity with the ambient term given (amb from
 * tb_rad_ambient, NULL for none): the same values, for loops over every
 * corner, which would otherwise sum the ambient over all elements at each
 * corner (quadratic in the elements). */
void tb_rad_corner_radiosity_amb(const tb_rad_solver *s, size_t i, int k, const double *amb, double *out);

/* Gathered irradiance H_v at vertex v (the display's value, without the
 * ambient term), out[0..nchannels): corner k of element i shows
 * E_i + rho_i (H_v + ambient) with v = its k-th vertex. */
void tb_rad_vertex_irradiance(const tb_rad_solver *s, size_t v, double *out);

/* The current state (pointers into the solver, valid until the next step
 * or free): what tb_rad_solver_create takes to continue elsewhere. */
tb_rad_state tb_rad_solver_state(const tb_rad_solver *s);

/* The whole progressive state of a solver as bytes, for checkpoints
 * (host/dist/checkpoint.h): shots, energy sums, gathered irradiance at
 * vertices and elements, unshot radiosity and power, lights shot. A solver
 * made again for the same mesh and options and given these bytes
 * (tb_rad_solver_unpack) shoots on exactly as the original would have:
 * shooter order and every value, bit for bit. (The shooters' sample points
 * come from a seed per shooter, so there is no random stream to save.) */
size_t tb_rad_solver_packed_size(const tb_rad_solver *s);

/* Writes the state into buf[0 .. tb_rad_solver_packed_size). */
void tb_rad_solver_pack(const tb_rad_solver *s, void *buf);

/* Replaces the state of `s` (a solver of the same mesh and options) by
 * packed bytes. TB_ERR_FORMAT if they are short or were packed from a mesh
 * of another size, channel count or light count; `s` is unchanged then. */
tb_status tb_rad_solver_unpack(tb_rad_solver *s, const void *buf, size_t len);


/* The form factor F_ij from shooter i (a patch; an element on one level) to
 * element j (fraction of the power leaving i that reaches j; 0 for j in i) exactly as a shot from i moves energy: ray cast, A_j / A_i times F_ji, F_ji the mean over j's
 * corners of F(v -> i) or, next to i, the near-field estimate
 * (docs/radiosity.md); hemicube, the hemicube at i's centroid. For
 * reciprocity checks; costs a shot unless i's form factors are cached. */
tb_status tb_rad_formfactor(tb_rad_solver *s, size_t i, size_t j, double *f);

/* --patches CSV: header `element,object,area,cx,cy,cz,nx,ny,nz,` then
 * b_r,b_g,b_b (RGB) or b_<nm> per band (its wavelength, e.g. b_400), then
 * the unshot columns likewise (u_r.. or u_<nm>), then, when the mesh has
 * patches, `patch` (the element's patch index); one row per element, no
 * ambient term, radiosity in W/m^2 per channel. Written all-or-nothing. */
tb_status tb_rad_write_patches(const tb_rad_solver *s, const char *path);

/* Reads a --patches CSV written by tb_rad_write_patches: *nrows rows of
 * *ncols radiosity values (the b_ columns), row-major, malloc'd into *b. */
tb_status tb_rad_read_patches(const char *path, size_t *nrows, int *ncols, double **b);

/* Mesh file formats of the solved mesh (tb_rad_mesh_format_from_path). */
typedef enum tb_rad_mesh_format {
    TB_RAD_MESH_UNKNOWN = 0,
    TB_RAD_MESH_PLY,  /* .ply: binary little-endian PLY (tb_rad_write_ply) */
    TB_RAD_MESH_GLTF, /* .gltf: glTF 2.0 JSON, the buffer embedded as a base64 data URI (tb_rad_write_gltf) */
    TB_RAD_MESH_GLB,  /* .glb: binary glTF 2.0 (tb_rad_write_gltf) */
} tb_rad_mesh_format;

/* The format named by a path's extension (case-insensitive), or TB_RAD_MESH_UNKNOWN. */
tb_rad_mesh_format tb_rad_mesh_format_from_path(const char *path);

/* The display scale of the mesh outputs' 8-bit / clamped colours: 0.18 over
 * the area-weighted mean luminance of the radiance B / pi (ambient term
 * included) of the elements that do not emit; 1 if that mean is 0. */
double tb_rad_display_scale(const tb_rad_solver *s);

/* The solved mesh as binary PLY with per-vertex linear RGB colours (float
 * r,g,b properties and 8-bit sRGB red,green,blue), one vertex per element
 * corner (so colours can differ across materials), the ambient term
 * included, radiosity scaled by `scale` before the 8-bit conversion;
 * `prov` (may be NULL) as a `comment testbed provenance {JSON}` line.
 * Written all-or-nothing. */
tb_status tb_rad_write_ply(const tb_rad_solver *s, const char *path, double scale, const struct tb_provenance *prov);

/* The solved mesh as glTF 2.0: `binary` false writes one .gltf JSON file
 * with the buffer as a base64 data URI, true a .glb. The same vertices in
 * the same order as tb_rad_write_ply (one per element corner), triangles
 * (v0 v1 v2) and, for quads, (v0 v2 v3); POSITION (with min/max), NORMAL
 * (the element's), COLOR_0 = the PLY's display colour before sRGB encoding
 * (linear radiance times `scale`, clamped to [0, 1]), _RADIANCE = the PLY's
 * float r g b; one KHR_materials_unlit material; `prov` (may be NULL) in
 * asset.extras. Coordinates are the scene's, unscaled. Written
 * all-or-nothing; TB_ERR_UNSUPPORTED if a .glb would exceed 4 GB. */
tb_status tb_rad_write_gltf(const tb_rad_solver *s, const char *path, double scale, bool binary,
                            const struct tb_provenance *prov);

/* The solution seen from the scene's camera at its resolution: spp rays
 * per pixel on a regular sub-pixel grid (spp rounded up to a square) against
 * the elements, the corners' radiosities (ambient term included)
 * interpolated linearly over the triangles (v0 v1 v2) and (v0 v2 v3) of
 * each element, radiance B / pi, back faces and misses black; a box-filtered
 * film of the scene's channels resolved like the ray tracer's images
 * (tb_render_resolve: linear sRGB). */
tb_status tb_rad_render_image(const tb_rad_solver *s, const tb_scene *scene, int spp, struct tb_image **out);

#endif
