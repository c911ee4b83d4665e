/* The perspective camera: pinhole and thin lens, rays for continuous film
 * coordinates with differentials (docs/rendering.md, "Camera"). */
#include "host/render/camera.h"

#include <math.h>

#include "host/render/sampling.h"
#include "util/math/float.h"
#include "util/math/transform.h"

tb_status tb_camera_init(tb_camera *c, tb_dvec3 eye, tb_dvec3 look_at, tb_dvec3 up, double fov_y, int width,
                         int height, double aperture, double focus_distance)
{
    if (!c)
        return tb_error(TB_ERR_ARG, "camera: NULL argument");
    if (!(fov_y > 0.0 && fov_y < 180.0))
        return tb_error(TB_ERR_ARG, "camera: field of view %g degrees is not in (0, 180)", fov_y);
    if (width < 1 || width > 65536 || height < 1 || height > 65536)
        return tb_error(TB_ERR_ARG, "camera: resolution %d x %d is not in 1..65536", width, height);
    if (!(aperture >= 0.0) || !isfinite(aperture))
        return tb_error(TB_ERR_ARG, "camera: aperture %g is not a finite number >= 0", aperture);
    if (aperture > 0.0 && !(focus_distance > 0.0 && isfinite(focus_distance)))
        return tb_error(TB_ERR_ARG, "camera: focus distance %g is not a finite number > 0", focus_distance);
    tb_transform view;
    tb_status st = tb_transform_look_at(eye, look_at, up, &view);
    if (st)
        return tb_error_context(st, "camera");
    /* The look_at frame: camera +x right, +y up, -z toward the target. */
    c->eye = eye;
    c->right = tb_dvec3_normalize(tb_transform_dvector(&view, (tb_dvec3){1.0, 0.0, 0.0}));
    c->up = tb_dvec3_normalize(tb_transform_dvector(&view, (tb_dvec3){0.0, 1.0, 0.0}));
    c->forward = tb_dvec3_normalize(tb_transform_dvector(&view, (tb_dvec3){0.0, 0.0, -1.0}));
    c->width = width;
    c->height = height;
    c->fov_y = fov_y;
    c->tan_y = tan(fov_y * (TB_PI / 360.0));
    c->tan_x = c->tan_y * (double)width / (double)height;
    c->fov_x = atan(c->tan_x) * (360.0 / TB_PI);
    c->lens_radius = 0.5 * aperture;
    c->focus_distance = focus_distance > 0.0 ? focus_distance : tb_dvec3_length(tb_dvec3_sub(look_at, eye));
    return TB_OK;
}

tb_status tb_camera_from_mid(const tb_mid_camera *m, int width, int height, tb_camera *out)
{
    if (!m || !out)
        return tb_error(TB_ERR_ARG, "camera: NULL argument");
    int w = width > 0 ? width : m->width, h = height > 0 ? height : m->height;
    double fov = m->fov;
    if (m->focal_length > 0.0 && (w != m->width || h != m->height))
        fov = tb_mid_camera_fov(m->focal_length, m->film, w, h);
    return tb_camera_init(out, m->eye, m->look_at, m->up, fov, w, h, m->aperture, m->focus_distance);
}

/* The unrounded direction (forward + sx right + sy up) of film point (x, y):
 * its component along `forward` is 1, so it reaches the plane in focus at
 * the focus distance times itself. */
static tb_dvec3 tb__film_dir(const tb_camera *c, double x, double y)
{
    double sx = (2.0 * x / c->width - 1.0) * c->tan_x;
    double sy = (1.0 - 2.0 * y / c->height) * c->tan_y;
    return (tb_dvec3){c->forward.x + sx * c->right.x + sy * c->up.x,
                      c->forward.y + sx * c->right.y + sy * c->up.y,
                      c->forward.z + sx * c->right.z + sy * c->up.z};
}

/* Origin and unit direction (double) of the ray of film point (x, y) through
 * lens point (lx, ly) (unit disc coordinates along right and up). */
static void tb__ray_d(const tb_camera *c, double x, double y, double lx, double ly, tb_dvec3 *o, tb_dvec3 *d)
{
    tb_dvec3 dir = tb__film_dir(c, x, y);
    if (c->lens_radius <= 0.0) {
        *o = c->eye;
        *d = tb_dvec3_normalize(dir);
        return;
    }
    double rx = c->lens_radius * lx, ry = c->lens_radius * ly;
    tb_dvec3 lens = {c->eye.x + rx * c->right.x + ry * c->up.x, c->eye.y + rx * c->right.y + ry * c->up.y,
                     c->eye.z + rx * c->right.z + ry * c->up.z};
    tb_dvec3 focus = tb_dvec3_add(c->eye, tb_dvec3_scale(dir, c->focus_distance));
    *o = lens;
    *d = tb_dvec3_normalize(tb_dvec3_sub(focus, lens));
}

/* The lens point of a sample: the concentric map of the unit square onto the
 * unit disc (host/render/sampling.h); (0, 0) for a pinhole. */
static void tb__lens(const tb_camera *c, float u, float v, double *lx, double *ly)
{
    *lx = *ly = 0.0;
    if (c->lens_radius > 0.0) {
        tb_vec2 p = tb_sample_disk_concentric(u, v);
        *lx = p.x;
        *ly = p.y;
    }
}

tb_ray tb_camera_ray(const tb_camera *c, double x, double y, float lens_u, float lens_v)
{
    double lx, ly;
    tb__lens(c, lens_u, lens_v, &lx, &ly);
    tb_dvec3 o, d;
    tb__ray_d(c, x, y, lx, ly, &o, &d);
    return tb_ray_make(tb_dvec3_to_f(o), tb_dvec3_to_f(d), 0.0f, INFINITY);
}

void tb_camera_ray_differential(const tb_camera *c, double x, double y, float lens_u, float lens_v,
                                tb_camera_ray_diff *out)
{
    double lx, ly;
    tb__lens(c, lens_u, lens_v, &lx, &ly);
    tb_dvec3 o, d;
    tb__ray_d(c, x, y, lx, ly, &o, &d);
    out->ray = tb_ray_make(tb_dvec3_to_f(o), tb_dvec3_to_f(d), 0.0f, INFINITY);
    tb__ray_d(c, x + 1.0, y, lx, ly, &o, &d);
    out->rx_o = tb_dvec3_to_f(o);
    out->rx_d = tb_dvec3_to_f(d);
    tb__ray_d(c, x, y + 1.0, lx, ly, &o, &d);
    out->ry_o = tb_dvec3_to_f(o);
    out->ry_d = tb_dvec3_to_f(d);
}

bool tb_camera_project(const tb_camera *c, tb_dvec3 p, double *x, double *y)
{
    tb_dvec3 v = tb_dvec3_sub(p, c->eye);
    double z = tb_dvec3_dot(v, c->forward);
    if (!(z > 0.0))
        return false;
    double sx = tb_dvec3_dot(v, c->right) / z, sy = tb_dvec3_dot(v, c->up) / z;
    *x = (sx / c->tan_x + 1.0) * 0.5 * c->width;
    *y = (1.0 - sy / c->tan_y) * 0.5 * c->height;
    return true;
}
