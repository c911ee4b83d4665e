/* Textures looked up by parametric coordinates (u, v) (docs/textures.md):
 * image textures through a MIP-map with bilinear, trilinear or EWA filtering,
 * a procedural checkerboard in 2D or 3D (optionally box-filtered in closed
 * form) and
 * Perlin noise (fBm / turbulence), bump mapping from a height texture, the
 * footprint (du/dx, dv/dx, du/dy, dv/dy) from ray differentials, and a cache
 * that loads each image file once.
 *
 * Conventions:
 *  - u runs to the right and v UP the image: (u, v) = (0, 0) is the
 *    bottom-left corner of the image, (1, 1) the top-right (tb_image keeps row
 *    0 at the top). Texel (x, y) of level 0 has its centre at
 *    u = (x + 1/2) / width, v = 1 - (y + 1/2) / height.
 *  - A footprint is the change of (u, v) from one pixel to the next in x and
 *    in y; a zero footprint means "point sample" (finest level).
 *  - Values are linear floats (tb_image_read decodes sRGB files), up to
 *    TB_TEX_MAX_CHANNELS per lookup. */
#ifndef TB_HOST_RENDER_TEXTURE_H
#define TB_HOST_RENDER_TEXTURE_H

#include <stdbool.h>
#include <stddef.h>

#include "util/base/error.h"
#include "util/image/image.h"
#include "util/math/vec.h"

/* Most channels a texture lookup returns (RGBA). */
#define TB_TEX_MAX_CHANNELS 4

/* Default EWA anisotropy limit (pbrt's maxAnisotropy). */
#define TB_TEX_MAX_ANISO_DEFAULT 8.0f

/* What happens outside [0,1]^2. */
typedef enum tb_tex_wrap {
    TB_TEX_REPEAT = 0, /* tile the plane */
    TB_TEX_CLAMP = 1,  /* repeat the edge texels */
} tb_tex_wrap;

/* How an image texture is filtered. */
typedef enum tb_tex_filter {
    TB_TEX_NEAREST = 0,   /* nearest texel of level 0 (no filtering at all) */
    TB_TEX_BILINEAR = 1,  /* bilinear on level 0 (no prefiltering: aliases when minified) */
    TB_TEX_TRILINEAR = 2, /* bilinear on the two levels around the footprint's major axis, blended */
    TB_TEX_EWA = 3,       /* elliptical weighted average (Heckbert 1989), Gaussian weights */
} tb_tex_filter;

/* The texture-space footprint of a pixel: d(u,v)/dx and d(u,v)/dy. */
typedef struct tb_tex_footprint {
    float dudx, dvdx; /* change of (u, v) one pixel to the right */
    float dudy, dvdy; /* change of (u, v) one pixel down */
} tb_tex_footprint;

/* ---------------------------------------------------------------- MIP-maps */

/* One level of a MIP-map: width * height * channels floats, row 0 at the top. */
typedef struct tb_mip_level {
    int width, height;
    float *texels;
} tb_mip_level;

/* A MIP-map pyramid, read-only after construction (safe to share between
 * threads). Level l+1 has size max(1, floor(w_l / 2)) x max(1, floor(h_l / 2))
 * and each of its texels is the box-filtered average of the area of level l it
 * covers: 2 texels per axis for an even size, 3 with fractional weights for an
 * odd one (docs/textures.md), so every level has exactly the mean of level 0. */
typedef struct tb_mipmap {
    int width, height;     /* level 0 */
    int channels;          /* 1 .. TB_TEX_MAX_CHANNELS */
    int nlevels;           /* down to 1 x 1 */
    tb_mip_level *levels;  /* nlevels levels, finest first */
} tb_mipmap;

/* Builds the pyramid of `img` (1 to 4 channels, copied). NULL on failure
 * (TB_ERR_UNSUPPORTED for more channels, TB_ERR_NOMEM). */
tb_mipmap *tb_mipmap_create(const tb_image *img);

/* Frees a pyramid; NULL is allowed. */
void tb_mipmap_free(tb_mipmap *m);

/* Texel (x, y) of `level` (clamped to the pyramid) with the wrap applied to x
 * and y, into out[0 .. channels). */
void tb_mipmap_texel(const tb_mipmap *m, int level, int x, int y, tb_tex_wrap wrap, float *out);

/* Nearest texel of `level` at (u, v). */
void tb_mipmap_nearest(const tb_mipmap *m, int level, float u, float v, tb_tex_wrap wrap, float *out);

/* Bilinear interpolation of the texel centres of `level` at (u, v). */
void tb_mipmap_bilinear(const tb_mipmap *m, int level, float u, float v, tb_tex_wrap wrap, float *out);

/* Continuous level for a filter width of `texels` level-0 texels: 0 at or
 * below 1, else l + f where level l's texel spans sigma_l <= texels <
 * sigma_{l+1} level-0 texels (sigma_l = max(width / w_l, height / h_l)) and f
 * interpolates log(texels) between them; nlevels - 1 at the top. Equals
 * log2(texels) for power-of-two sizes. */
float tb_mipmap_level_of(const tb_mipmap *m, float texels);

/* Trilinear lookup: the footprint's longer axis (in level-0 texels) picks the
 * continuous level (tb_mipmap_level_of); bilinear on its two neighbouring
 * levels, blended. */
void tb_mipmap_trilinear(const tb_mipmap *m, float u, float v, const tb_tex_footprint *fp,
                         tb_tex_wrap wrap, float *out);

/* EWA lookup: the ellipse spanned by the footprint's two axes (one pixel
 * radius, in texels) plus a one-texel reconstruction disc, with Gaussian
 * weights exp(-2 r^2) - exp(-2); the minor axis is lengthened to at least
 * major / max_aniso (<= 0: TB_TEX_MAX_ANISO_DEFAULT) and picks the level, so
 * the filter is sharp across the footprint and long along it; the two
 * levels around it are blended. A zero footprint is a bilinear lookup. */
void tb_mipmap_ewa(const tb_mipmap *m, float u, float v, const tb_tex_footprint *fp,
                   tb_tex_wrap wrap, float max_aniso, float *out);

/* Any of the filters above (max_aniso for EWA only). */
void tb_mipmap_lookup(const tb_mipmap *m, tb_tex_filter filter, float u, float v,
                      const tb_tex_footprint *fp, tb_tex_wrap wrap, float max_aniso, float *out);

/* ----------------------------------------------------------- ray differentials */

/* The rays through the neighbouring pixels, one to the right (x) and one
 * below (y) of the ray that hit. */
typedef struct tb_ray_differential {
    tb_vec3 rx_o, rx_d; /* origin and direction of the x-offset ray */
    tb_vec3 ry_o, ry_d; /* origin and direction of the y-offset ray */
} tb_ray_differential;

/* pbrt's method: intersects the two offset rays with the tangent plane at hit
 * point p (normal n), giving dp/dx and dp/dy, then solves
 * [dp/du dp/dv] (du, dv) = dp/dx (and dp/dy) in the least-squares sense (the
 * 2x2 normal equations), in double. dpdx / dpdy may be NULL. Returns false
 * and a zero footprint (and zero dp/dx, dp/dy) if an offset ray is parallel
 * to the plane or points away from it, or dp/du, dp/dv are degenerate.
 * Components are clamped to +-1e8. */
bool tb_tex_footprint_from_rays(tb_vec3 p, tb_vec3 n, tb_vec3 dpdu, tb_vec3 dpdv,
                                const tb_ray_differential *rd, tb_tex_footprint *fp, tb_vec3 *dpdx,
                                tb_vec3 *dpdy);

/* ---------------------------------------------------------------- noise */

/* Ken Perlin's improved noise (SIGGRAPH 2002): gradient noise over the
 * integer lattice with his permutation table and 12 edge gradients, quintic
 * fade. Deterministic, zero at every lattice point, |noise| <= 2 (in practice
 * about 1; docs/textures.md has the measured range). Period 256. */
double tb_noise3(double x, double y, double z);

/* The permutation of 0..255 tb_noise3 uses (Perlin's): 256 entries, for
 * the GPU's twin of the noise (shaders/lib/pattern.glsl). */
const unsigned char *tb_noise_permutation(void);

/* Fractional Brownian motion: sum over octaves i of omega^i noise(l^i p) with
 * lacunarity l = 1.99 (not 2, so octaves do not share lattice zeros). The
 * octave count is limited by the footprint (dpdx, dpdy: the change of p per
 * pixel; zero vectors: no limit) so no octave finer than the pixel spacing
 * is summed; the last one fades in (pbrt's scheme). octaves <= 32. */
double tb_fbm3(tb_dvec3 p, tb_dvec3 dpdx, tb_dvec3 dpdy, double omega, int octaves);

/* Turbulence: the same sum over |noise|. */
double tb_turbulence3(tb_dvec3 p, tb_dvec3 dpdx, tb_dvec3 dpdy, double omega, int octaves);

/* Closed-form average of the 2D checkerboard (1 on squares where
 * floor(s) + floor(t) is odd, 0 elsewhere) over the box [s0, s1] x [t0, t1];
 * a degenerate box is a point sample. */
double tb_checker_box_average(double s0, double s1, double t0, double t1);

/* The 3D checkerboard (1 in cells where floor(x) + floor(y) + floor(z) is
 * odd) averaged over the box [x0, x1] x [y0, y1] x [z0, z1] in closed form. */
double tb_checker3_box_average(double x0, double x1, double y0, double y1, double z0, double z1);

/* ---------------------------------------------------------------- textures */

/* Texture kinds. */
typedef enum tb_texture_kind {
    TB_TEXTURE_CONSTANT = 0,
    TB_TEXTURE_IMAGE,
    TB_TEXTURE_CHECKER,
    TB_TEXTURE_NOISE,
} tb_texture_kind;

/* Noise texture kinds. */
typedef enum tb_noise_kind {
    TB_NOISE_FBM = 0,        /* value 0.5 + 0.5 fBm, clamped to [0, 1] */
    TB_NOISE_TURBULENCE = 1, /* value turbulence, clamped to [0, 1] */
} tb_noise_kind;

/* A texture: a closed set of kinds behind one lookup. Build with the
 * constructors below, then adjust the mapping if needed. Plain data; the
 * image it refers to must outlive it. */
typedef struct tb_texture {
    tb_texture_kind kind;
    int channels;                  /* values per lookup, 1 .. TB_TEX_MAX_CHANNELS */
    float su, sv, ou, ov;          /* mapping: the lookup uses (su u + ou, sv v + ov) */
    float a[TB_TEX_MAX_CHANNELS];  /* constant: the value; checker: even squares; noise: value at 0 */
    float b[TB_TEX_MAX_CHANNELS];  /* checker: odd squares; noise: value at 1 */
    const tb_mipmap *mip;          /* image */
    tb_tex_filter filter;          /* image */
    tb_tex_wrap wrap;              /* image */
    float max_aniso;               /* image, EWA (<= 0: default) */
    bool filtered;                 /* checker: box-filter over the footprint (else point sample) */
    tb_noise_kind noise;           /* noise */
    int octaves;                   /* noise: most octaves */
    float omega;                   /* noise: amplitude ratio between octaves */
    bool solid;                    /* noise, checker: of the 3D point p * su (else of the mapped (u, v), z = 0) */
} tb_texture;

/* A constant of `channels` values. */
tb_texture tb_texture_constant(int channels, const float *value);

/* An image texture over `mip` (its channel count). */
tb_texture tb_texture_image(const tb_mipmap *mip, tb_tex_filter filter, tb_tex_wrap wrap);

/* A checkerboard of unit squares in the mapped (u, v): `even` where
 * floor(s) + floor(t) is even, `odd` elsewhere; `filtered`: the closed-form
 * box average over the footprint's bounding box. */
tb_texture tb_texture_checker(int channels, const float *even, const float *odd, bool filtered);

/* A noise texture blending lo (at 0) to hi (at 1). */
tb_texture tb_texture_noise(int channels, const float *lo, const float *hi, tb_noise_kind kind,
                            int octaves, float omega);

/* Where and how big the lookup is. */
typedef struct tb_tex_query {
    float u, v;          /* parametric coordinates */
    tb_tex_footprint fp; /* their change per pixel (zero: point sample) */
    tb_vec3 p;           /* the point (solid noise) */
    tb_vec3 dpdx, dpdy;  /* its change per pixel (solid noise; zero: no limit) */
} tb_tex_query;

/* Evaluates `t` at `q` into out[0 .. t->channels). */
void tb_texture_eval(const tb_texture *t, const tb_tex_query *q, float *out);

/* Channel 0 of tb_texture_eval (height and scalar textures). */
float tb_texture_eval1(const tb_texture *t, const tb_tex_query *q);

/* ---------------------------------------------------------------- bump mapping */

/* The shading geometry at a hit, as the bump mapper needs it. */
typedef struct tb_bump_geom {
    tb_vec3 p;          /* point */
    tb_vec3 n;          /* unit shading normal (the side the result is oriented to) */
    tb_vec3 dpdu, dpdv; /* tangents; dpdu x dpdv along n */
    tb_vec3 dndu, dndv; /* normal derivatives (zero for flat faces) */
    float u, v;         /* parametric coordinates */
    tb_tex_footprint fp;/* for the difference steps and the height lookups */
    /* Solid height textures are looked up at p; when the texture's space is
     * not the world (e.g. object space), tp_du, tp_dv give the change of that
     * point per unit u and v (zero: dpdu, dpdv) and dpdx, dpdy its change
     * per pixel (zero: no octave limit). */
    tb_vec3 tp_du, tp_dv;
    tb_vec3 dpdx, dpdy;
} tb_bump_geom;

/* pbrt's bump mapping: the surface displaced by scale * h(u, v) along n has
 *   dp'/du = dp/du + (h(u + du, v) - h(u, v)) / du * n + h dn/du
 * (likewise for v; forward differences with du = (|du/dx| + |du/dy|) / 2, or
 * 1/2048 without a footprint), and normal n' = normalise(dp'/du x dp'/dv)
 * turned to n's side. Heights are channel 0 of `height` times `scale`, in
 * world units. Writes n' and the displaced tangents (either may be NULL).
 * Returns false (and n unchanged) if the displaced tangents are degenerate. */
bool tb_bump_map(const tb_texture *height, float scale, const tb_bump_geom *g, tb_vec3 *n_out,
                 tb_vec3 *dpdu_out, tb_vec3 *dpdv_out);

/* ---------------------------------------------------------------- cache */

/* Image pyramids keyed by resolved path and read options (opaque). */
typedef struct tb_texture_cache tb_texture_cache;

/* An empty cache; NULL when out of memory. */
tb_texture_cache *tb_texture_cache_create(void);

/* Frees the cache and every pyramid it holds; NULL is allowed. */
void tb_texture_cache_free(tb_texture_cache *c);

/* The pyramid of image `path` (relative paths are taken from `base_dir`, e.g.
 * the scene file's folder; NULL: the working directory), loading and building
 * it on the first request for that file. Two spellings of one file
 * (dir/../x.png, ./x.png, symbolic links) resolve to the same entry. The
 * pyramid belongs to the cache. Thread-safe. */
tb_status tb_texture_cache_get(tb_texture_cache *c, const char *base_dir, const char *path,
                               const tb_image_read_options *opts, const tb_mipmap **out);

/* Number of distinct images loaded. */
size_t tb_texture_cache_count(const tb_texture_cache *c);

#endif
