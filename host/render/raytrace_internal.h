/* The ray tracer's private interface (raytrace.h): the texture, pattern and
 * surface helpers that raytrace*.c share and that the Vulkan renderer
 * (host/gpu) calls to shade a hit exactly as the CPU tracer does. Not
 * installed (an _internal.h header); not part of the public API. */
#ifndef TB_HOST_RENDER_RAYTRACE_INTERNAL_H
#define TB_HOST_RENDER_RAYTRACE_INTERNAL_H

#include <stdbool.h>

#include "host/render/raytrace.h"
#include "host/render/scene.h"
#include "host/render/surface.h"
#include "util/base/error.h"
#include "util/math/vec.h"

struct tb_mipmap;

/* Private (raytrace_texture.c): loads the images paths[0..n) (NULL: none) into *out. */
tb_status tb__rt_textures_load(int n, const char *const *paths, tb__rt_textures **out);
/* Private: frees them; NULL is allowed. */
void tb__rt_textures_free(tb__rt_textures *t);
/* Private: linear RGB of texture i at (u, v) with footprint fp = (du/dx,
 * dv/dx, du/dy, dv/dy) (NULL: point sample) through `filter` (a
 * tb_tex_filter); false if there is no texture i. */
bool tb__rt_texture_rgb(const tb__rt_textures *t, int i, int filter, float u, float v, const float fp[4],
                        double rgb[3]);
/* Private: the MIP pyramid of texture i (NULL: none), for the Vulkan renderer's copy. */
const struct tb_mipmap *tb__rt_texture_mip(const tb__rt_textures *t, int i);
/* Private: the footprint (as above) at hit point p, normal n, tangents
 * dpdu, dpdv, of the offset rays rd = {rx_o, rx_d, ry_o, ry_d}, scaled by
 * `scale`; false (fp zeroed) if it cannot be computed. */
bool tb__rt_footprint(tb_vec3 p, tb_vec3 n, tb_vec3 dpdu, tb_vec3 dpdv, const tb_vec3 rd[4], float scale,
                      float fp[4], tb_vec3 dpdxy[2]);

/* Private: the geometry of a hit that patterns and bump maps need. */
typedef struct tb__rt_surface {
    float u, v;           /* parametric coordinates */
    bool has_fp;          /* fp holds the (u, v) footprint (du/dx, dv/dx, du/dy, dv/dy) */
    float fp[4];
    tb_vec3 p, n;         /* world point, unit shading normal on the viewer's side */
    tb_vec3 dpdu, dpdv;   /* world tangents */
    tb_vec3 po;           /* the point in the object space of the primitive hit */
    tb_vec3 po_du, po_dv; /* its change per unit u and v */
    tb_vec3 po_dx, po_dy; /* its change per pixel (zero: unknown) */
} tb__rt_surface;
/* Private: the surface record of a hit at point p (the tracer's hit point),
 * geometric normal ng, viewer-side normal n, with the footprint of the
 * camera ray's offset rays rd (NULL: none), as the tracer builds it; false
 * if the hit has no tangents (the tracer then ignores patterns and bumps). */
bool tb__rt_hit_surface(const tb_raytracer *rt, const tb_hit *hit, tb_vec3 p, tb_vec3 ng, tb_vec3 n,
                        const tb_vec3 *rd, tb__rt_surface *g);
/* Private: builds the pattern textures of every material of s (bump images
 * through `filter`); *out stays NULL when no material has one. */
tb_status tb__rt_patterns_init(const tb_scene *s, int filter, tb__rt_patterns **out);
/* Private: frees them; NULL is allowed. */
void tb__rt_patterns_free(tb__rt_patterns *p);
/* Private: the blend factor in [0, 1] of pattern `slot` (0 diffuse, 1
 * specular) of material `material` at g; false if it has none. */
bool tb__rt_pattern_factor(const tb__rt_patterns *p, int material, int slot, const tb__rt_surface *g, double *f);
/* Private: the bump-mapped shading normal of material m (index `material`)
 * at g, on the side of g->n; false (n untouched) without a bump map or for
 * degenerate tangents. */
bool tb__rt_bump(const tb__rt_patterns *p, const tb_material *m, int material, const tb__rt_surface *g,
                 tb_vec3 *n);


/* Private (surface.c): the image textures of a tb_surfaces (NULL: none), for
 * the ray tracer's Vulkan renderer and its feature tables. */
const tb__rt_textures *tb__surfaces_textures(const tb_surfaces *ss);
/* Private: its patterns and bump maps (NULL: none). */
const tb__rt_patterns *tb__surfaces_patterns(const tb_surfaces *ss);
/* Private: its scale of the camera ray differentials. */
float tb__surfaces_diff_scale(const tb_surfaces *ss);
/* Private: world tangents dp/du, dp/dv at a hit from the CSG leaf holding
 * the hit's face (*leaf, may be NULL); false if there is none. */
bool tb__surface_tangents(const tb_scene *s, const tb_hit *hit, tb_vec3 *dpdu, tb_vec3 *dpdv,
                          const tb_object **leaf);
/* Private: the pattern/bump record of a hit on `leaf` (fp, dpdxy: the
 * footprint and the point's change per pixel, or NULL). */
void tb__surface_fill(const tb_object *leaf, const tb_hit *hit, tb_vec3 p, tb_vec3 n, tb_vec3 dpdu, tb_vec3 dpdv,
                      const float *fp, const tb_vec3 dpdxy[2], tb__rt_surface *g);

#endif
