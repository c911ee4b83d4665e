/* The camera: primary rays for continuous film coordinates, with ray
 * differentials for texture filtering and a thin lens for depth of field
 * (docs/rendering.md, "Camera").
 *
 *     tb_camera cam;
 *     if (tb_camera_from_mid(mid_camera, 0, 0, &cam)) fail(tb_last_error());
 *     tb_ray r = tb_camera_ray(&cam, px + 0.5, py + 0.5, lens_u, lens_v);   // pixel centre
 *
 * Film (raster) coordinates are those of the film module (host/render/film.h):
 * x to the right, y DOWN from the top of the image, pixel (i, j) covers
 * [i, i+1) x [j, j+1), so its centre is (i + 1/2, j + 1/2) and the image is
 * [0, width] x [0, height]. The camera looks from `eye` along `forward`;
 * raster x grows along `right` and raster y against `up` (the MID camera's
 * look_at frame, util/math/transform.h tb_transform_look_at). Pixels are
 * square: the horizontal field of view follows from the vertical one and the
 * aspect ratio. Computed in double, each output component rounded once. */
#ifndef TB_HOST_RENDER_CAMERA_H
#define TB_HOST_RENDER_CAMERA_H

#include <stdbool.h>

#include "host/mid/mid.h"
#include "util/base/error.h"
#include "util/math/ray.h"
#include "util/math/rng.h"
#include "util/math/vec.h"

/* A pinhole or thin-lens perspective camera (read-only after init). */
typedef struct tb_camera {
    tb_dvec3 eye;          /* centre of the lens (the pinhole), world space */
    tb_dvec3 right;        /* unit: the image's +x direction in the world */
    tb_dvec3 up;           /* unit: the image's up direction (raster -y) */
    tb_dvec3 forward;      /* unit: the view direction, eye toward look_at */
    int width, height;     /* resolution in pixels */
    double fov_y, fov_x;   /* full vertical and horizontal field of view, degrees */
    double tan_y, tan_x;   /* tan(fov_y / 2), tan(fov_x / 2) = tan_y * width / height */
    double lens_radius;    /* aperture / 2 in scene units; 0 is a pinhole */
    double focus_distance; /* distance along `forward` of the plane in focus (scene units) */
} tb_camera;

/* A primary ray with the rays of the film points one pixel to the right and
 * one pixel down (same lens point): texture filtering estimates the footprint
 * of a pixel from how far the neighbours land (pbrt's RayDifferential). The
 * rx/ry fields are those of host/render/texture.h's tb_ray_differential:
 * copy them into one for tb_tex_footprint_from_rays (this header does not
 * include texture.h, so both can be used together). */
typedef struct tb_camera_ray_diff {
    tb_ray ray;           /* the ray of film point (x, y): unit direction, tmin 0, tmax +inf */
    tb_vec3 rx_o, rx_d;   /* origin and unit direction of the ray of (x + 1, y) */
    tb_vec3 ry_o, ry_d;   /* origin and unit direction of the ray of (x, y + 1) */
} tb_camera_ray_diff;

/* Sets up a camera at `eye` looking at `look_at` with image up from `up`
 * (the part perpendicular to the view direction), vertical field of view
 * fov_y (degrees, in (0, 180)), width x height pixels (1..65536), lens
 * diameter `aperture` (>= 0; 0: pinhole) focused at `focus_distance` (> 0;
 * used only with an aperture). TB_ERR_ARG with a message otherwise. */
tb_status tb_camera_init(tb_camera *c, tb_dvec3 eye, tb_dvec3 look_at, tb_dvec3 up, double fov_y, int width,
                         int height, double aperture, double focus_distance);

/* The camera a MID `camera` item describes (docs/mid.md, section 10).
 * width and height (both > 0) replace the file's resolution; 0 keeps it.
 * With a focal length the field of view is recomputed for the new aspect
 * ratio (tb_mid_camera_fov: the largest centred film region of that shape). */
tb_status tb_camera_from_mid(const tb_mid_camera *m, int width, int height, tb_camera *out);

/* The primary ray through film point (x, y) (raster coordinates, y down; any
 * real values, also outside the image). (lens_u, lens_v) in [0, 1)^2 pick the
 * point on the lens (concentric disc map); they are ignored by a pinhole.
 * The direction has unit length, so t is the distance from the origin;
 * tmin = 0, tmax = +inf. Pinhole rays start at the eye; thin-lens rays start
 * on the lens and pass through the point where the pinhole ray of (x, y)
 * meets the plane in focus. */
tb_ray tb_camera_ray(const tb_camera *c, double x, double y, float lens_u, float lens_v);

/* The lens numbers of one camera sample: for a thin lens two floats drawn
 * from rng (lens_u first), for a pinhole 0.5 and 0.5 with nothing drawn, so
 * a pinhole sample's stream is left for the renderer. */
static inline void tb_camera_lens_numbers(const tb_camera *c, tb_rng *rng, float *lens_u, float *lens_v)
{
    *lens_u = *lens_v = 0.5f;
    if (c->lens_radius > 0.0) {
        *lens_u = tb_rng_float(rng);
        *lens_v = tb_rng_float(rng);
    }
}

/* tb_camera_ray plus the neighbours' rays (film points (x + 1, y) and
 * (x, y + 1) through the same lens point). */
void tb_camera_ray_differential(const tb_camera *c, double x, double y, float lens_u, float lens_v,
                                tb_camera_ray_diff *out);

/* Film coordinates of the world point p as the pinhole sees it (the inverse
 * of tb_camera_ray with a pinhole; for a thin lens, where p is in focus).
 * False, with *x and *y untouched, if p is not in front of the eye. */
bool tb_camera_project(const tb_camera *c, tb_dvec3 p, double *x, double *y);

#endif
