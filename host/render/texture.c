/* MIP-maps: construction by exact box reduction (any size), texel access
 * with wrap modes, nearest / bilinear / trilinear / EWA lookups, and the
 * texture footprint from ray differentials (texture.h, docs/textures.md). */
#include "host/render/texture.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "util/stats/stats.h"

TB_STAT_COUNTER(tb__stat_trilinear, "Texture/trilinear lookups");
TB_STAT_COUNTER(tb__stat_ewa, "Texture/EWA lookups");
TB_STAT_COUNTER(tb__stat_ewa_texels, "Texture/EWA texels weighted");
TB_STAT_MEMORY(tb__stat_mip_bytes, "Texture/MIP-map memory");

/* Most texels one EWA level may visit before the lookup moves one level up
 * (only reachable with extreme aspect ratios of non-square images). */
#define TB__EWA_MAX_TEXELS 4096

/* Gaussian falloff of the EWA filter: weight exp(-alpha r^2) - exp(-alpha)
 * on the ellipse's unit disc (Heckbert 1989; pbrt's alpha). */
#define TB__EWA_ALPHA 2.0

/* ---------------------------------------------------------------- building */

/* Reduces `n` samples along one axis to `m` (m = max(1, n / 2)): output i
 * averages the input interval [i r, (i+1) r), r = n / m, each input sample
 * weighted by its overlap with it (2 taps for even n, 3 for odd n).
 * `src`/`dst` are addressed as base + index * stride, `ch` doubles each. */
static void tb__reduce_line(const double *src, size_t sstride, int n, double *dst, size_t dstride,
                            int m, int ch)
{
    double r = (double)n / (double)m;
    for (int i = 0; i < m; i++) {
        double a = (double)i * r, b = (double)(i + 1) * r;
        if (i == m - 1)
            b = (double)n; /* exactly the end, whatever the rounding of (i+1) r */
        double acc[TB_TEX_MAX_CHANNELS] = {0};
        for (int j = (int)floor(a); j < n && (double)j < b; j++) {
            double lo = (double)j > a ? (double)j : a;
            double hi = (double)(j + 1) < b ? (double)(j + 1) : b;
            double w = (hi - lo) / r;
            if (w <= 0.0)
                continue;
            const double *s = src + (size_t)j * sstride;
            for (int c = 0; c < ch; c++)
                acc[c] += w * s[c];
        }
        double *d = dst + (size_t)i * dstride;
        for (int c = 0; c < ch; c++)
            d[c] = acc[c];
    }
}

/* Level l+1 from level l in double: rows first, then columns. */
static void tb__reduce(const double *src, int w, int h, double *dst, int w2, int h2, int ch,
                       double *tmp)
{
    /* tmp: w2 x h */
    for (int y = 0; y < h; y++)
        tb__reduce_line(src + (size_t)y * (size_t)w * (size_t)ch, (size_t)ch, w,
                        tmp + (size_t)y * (size_t)w2 * (size_t)ch, (size_t)ch, w2, ch);
    for (int x = 0; x < w2; x++)
        tb__reduce_line(tmp + (size_t)x * (size_t)ch, (size_t)w2 * (size_t)ch, h,
                        dst + (size_t)x * (size_t)ch, (size_t)w2 * (size_t)ch, h2, ch);
}

tb_mipmap *tb_mipmap_create(const tb_image *img)
{
    if (!img || !img->pixels || img->width < 1 || img->height < 1) {
        tb_error(TB_ERR_ARG, "mipmap: no image");
        return NULL;
    }
    if (img->channels < 1 || img->channels > TB_TEX_MAX_CHANNELS) {
        tb_error(TB_ERR_UNSUPPORTED, "mipmap: %d channels (textures have 1 to %d)", img->channels,
                 TB_TEX_MAX_CHANNELS);
        return NULL;
    }
    int ch = img->channels;
    int nlevels = 1;
    for (int w = img->width, h = img->height; w > 1 || h > 1; nlevels++) {
        w = w > 1 ? w / 2 : 1;
        h = h > 1 ? h / 2 : 1;
    }
    tb_mipmap *m = calloc(1, sizeof *m);
    tb_mip_level *levels = calloc((size_t)nlevels, sizeof *levels);
    size_t n0 = (size_t)img->width * (size_t)img->height * (size_t)ch;
    /* the previous level in double, so each level is rounded to float once */
    double *cur = malloc(n0 * sizeof *cur);
    double *next = malloc(n0 * sizeof *next);
    double *tmp = malloc(n0 * sizeof *tmp);
    if (!m || !levels || !cur || !next || !tmp) {
        free(m);
        free(levels);
        free(cur);
        free(next);
        free(tmp);
        tb_error(TB_ERR_NOMEM, "mipmap: out of memory for %d x %d", img->width, img->height);
        return NULL;
    }
    m->width = img->width;
    m->height = img->height;
    m->channels = ch;
    m->nlevels = nlevels;
    m->levels = levels;
    for (size_t i = 0; i < n0; i++)
        cur[i] = img->pixels[i];
    int w = img->width, h = img->height;
    size_t bytes = 0;
    for (int l = 0; l < nlevels; l++) {
        size_t n = (size_t)w * (size_t)h * (size_t)ch;
        levels[l].width = w;
        levels[l].height = h;
        levels[l].texels = malloc(n * sizeof(float));
        if (!levels[l].texels) {
            free(cur);
            free(next);
            free(tmp);
            tb_mipmap_free(m);
            tb_error(TB_ERR_NOMEM, "mipmap: out of memory for level %d", l);
            return NULL;
        }
        bytes += n * sizeof(float);
        for (size_t i = 0; i < n; i++)
            levels[l].texels[i] = (float)cur[i];
        if (l + 1 < nlevels) {
            int w2 = w > 1 ? w / 2 : 1, h2 = h > 1 ? h / 2 : 1;
            tb__reduce(cur, w, h, next, w2, h2, ch, tmp);
            double *t = cur;
            cur = next;
            next = t;
            w = w2;
            h = h2;
        }
    }
    free(cur);
    free(next);
    free(tmp);
    tb_stat_add(&tb__stat_mip_bytes, (int64_t)bytes);
    return m;
}

void tb_mipmap_free(tb_mipmap *m)
{
    if (!m)
        return;
    if (m->levels)
        for (int l = 0; l < m->nlevels; l++)
            free(m->levels[l].texels);
    free(m->levels);
    free(m);
}

/* ---------------------------------------------------------------- texels */

static int tb__wrap(int i, int n, tb_tex_wrap wrap)
{
    if (wrap == TB_TEX_CLAMP)
        return i < 0 ? 0 : (i >= n ? n - 1 : i);
    int r = i % n;
    return r < 0 ? r + n : r;
}

static const float *tb__texel_ptr(const tb_mip_level *lv, int ch, int x, int y, tb_tex_wrap wrap)
{
    x = tb__wrap(x, lv->width, wrap);
    y = tb__wrap(y, lv->height, wrap);
    return lv->texels + ((size_t)y * (size_t)lv->width + (size_t)x) * (size_t)ch;
}

/* Integer texel index of a coordinate that may be huge or not finite. */
static int tb__index(double s)
{
    if (!(s > -1e9))
        return -1000000000;
    if (s > 1e9)
        return 1000000000;
    return (int)floor(s);
}

static int tb__clamp_level(const tb_mipmap *m, int level)
{
    return level < 0 ? 0 : (level >= m->nlevels ? m->nlevels - 1 : level);
}

void tb_mipmap_texel(const tb_mipmap *m, int level, int x, int y, tb_tex_wrap wrap, float *out)
{
    const tb_mip_level *lv = &m->levels[tb__clamp_level(m, level)];
    const float *t = tb__texel_ptr(lv, m->channels, x, y, wrap);
    for (int c = 0; c < m->channels; c++)
        out[c] = t[c];
}

void tb_mipmap_nearest(const tb_mipmap *m, int level, float u, float v, tb_tex_wrap wrap, float *out)
{
    const tb_mip_level *lv = &m->levels[tb__clamp_level(m, level)];
    int x = tb__index((double)u * lv->width), y = tb__index((1.0 - (double)v) * lv->height);
    const float *t = tb__texel_ptr(lv, m->channels, x, y, wrap);
    for (int c = 0; c < m->channels; c++)
        out[c] = t[c];
}

/* Bilinear interpolation in double into acc (not rounded). */
static void tb__bilinear_d(const tb_mipmap *m, int level, double u, double v, tb_tex_wrap wrap,
                           double *acc)
{
    const tb_mip_level *lv = &m->levels[tb__clamp_level(m, level)];
    double s = u * lv->width - 0.5, t = (1.0 - v) * lv->height - 0.5;
    int x0 = tb__index(s), y0 = tb__index(t);
    double fx = s - floor(s), fy = t - floor(t);
    if (!(fx >= 0.0 && fx < 1.0))
        fx = 0.0;
    if (!(fy >= 0.0 && fy < 1.0))
        fy = 0.0;
    const float *t00 = tb__texel_ptr(lv, m->channels, x0, y0, wrap);
    const float *t10 = tb__texel_ptr(lv, m->channels, x0 + 1, y0, wrap);
    const float *t01 = tb__texel_ptr(lv, m->channels, x0, y0 + 1, wrap);
    const float *t11 = tb__texel_ptr(lv, m->channels, x0 + 1, y0 + 1, wrap);
    for (int c = 0; c < m->channels; c++) {
        double top = (double)t00[c] + fx * ((double)t10[c] - (double)t00[c]);
        double bot = (double)t01[c] + fx * ((double)t11[c] - (double)t01[c]);
        acc[c] = top + fy * (bot - top);
    }
}

void tb_mipmap_bilinear(const tb_mipmap *m, int level, float u, float v, tb_tex_wrap wrap, float *out)
{
    double acc[TB_TEX_MAX_CHANNELS];
    tb__bilinear_d(m, level, u, v, wrap, acc);
    for (int c = 0; c < m->channels; c++)
        out[c] = (float)acc[c];
}

/* ---------------------------------------------------------------- level choice */

/* Size of a texel of level l in level-0 texels (the larger of the two axes). */
static double tb__sigma(const tb_mipmap *m, int l)
{
    double sx = (double)m->width / m->levels[l].width, sy = (double)m->height / m->levels[l].height;
    return sx > sy ? sx : sy;
}

/* tb_mipmap_level_of in double. */
static double tb__level_of(const tb_mipmap *m, double texels)
{
    if (!(texels > 1.0))
        return 0.0;
    for (int l = 0; l + 1 < m->nlevels; l++) {
        double s0 = tb__sigma(m, l), s1 = tb__sigma(m, l + 1);
        if (texels < s1) {
            if (!(s1 > s0))
                return l + 1;
            double f = log(texels / s0) / log(s1 / s0);
            return l + (f < 0.0 ? 0.0 : f);
        }
    }
    return m->nlevels - 1;
}

float tb_mipmap_level_of(const tb_mipmap *m, float texels)
{
    return (float)tb__level_of(m, texels);
}

/* The footprint's axes in level-0 texel units (x right, y down the image). */
static void tb__axes(const tb_mipmap *m, const tb_tex_footprint *fp, double a[2], double b[2])
{
    a[0] = (double)fp->dudx * m->width;
    a[1] = -(double)fp->dvdx * m->height;
    b[0] = (double)fp->dudy * m->width;
    b[1] = -(double)fp->dvdy * m->height;
    for (int i = 0; i < 2; i++) {
        if (!isfinite(a[i]))
            a[i] = 0.0;
        if (!isfinite(b[i]))
            b[i] = 0.0;
    }
}

void tb_mipmap_trilinear(const tb_mipmap *m, float u, float v, const tb_tex_footprint *fp,
                         tb_tex_wrap wrap, float *out)
{
    TB_STAT_INC(tb__stat_trilinear);
    double a[2], b[2];
    tb__axes(m, fp, a, b);
    double la = sqrt(a[0] * a[0] + a[1] * a[1]), lb = sqrt(b[0] * b[0] + b[1] * b[1]);
    double lod = tb__level_of(m, la > lb ? la : lb);
    int l0 = (int)floor(lod);
    double f = lod - l0;
    double c0[TB_TEX_MAX_CHANNELS], c1[TB_TEX_MAX_CHANNELS];
    tb__bilinear_d(m, l0, u, v, wrap, c0);
    if (f > 0.0 && l0 + 1 < m->nlevels) {
        tb__bilinear_d(m, l0 + 1, u, v, wrap, c1);
        for (int c = 0; c < m->channels; c++)
            c0[c] += f * (c1[c] - c0[c]);
    }
    for (int c = 0; c < m->channels; c++)
        out[c] = (float)c0[c];
}

/* ---------------------------------------------------------------- EWA */

/* The EWA sum at one level for axes a, b given in level-0 texels. Returns
 * false if the ellipse covers more than TB__EWA_MAX_TEXELS texels. */
static bool tb__ewa_level(const tb_mipmap *m, int l, double u, double v, const double a0[2],
                          const double b0[2], tb_tex_wrap wrap, double *acc)
{
    const tb_mip_level *lv = &m->levels[l];
    int ch = m->channels;
    if (lv->width == 1 && lv->height == 1) {
        for (int c = 0; c < ch; c++)
            acc[c] = lv->texels[c];
        return true;
    }
    double kx = (double)lv->width / m->width, ky = (double)lv->height / m->height;
    double ax = a0[0] * kx, ay = a0[1] * ky, bx = b0[0] * kx, by = b0[1] * ky;
    /* M = J J^T + I: the footprint ellipse (J's columns are the axes) widened
     * by a unit reconstruction disc; a texel at offset d is inside when
     * d^T M^-1 d < 1 */
    double m00 = ax * ax + bx * bx + 1.0, m01 = ax * ay + bx * by, m11 = ay * ay + by * by + 1.0;
    double det = m00 * m11 - m01 * m01;
    double A = m11 / det, B = -2.0 * m01 / det, C = m00 / det;
    double s = u * lv->width - 0.5, t = (1.0 - v) * lv->height - 0.5;
    if (!(fabs(s) < 1e9 && fabs(t) < 1e9))
        s = t = 0.0;
    double ex = sqrt(m00), ey = sqrt(m11);
    int x0 = (int)ceil(s - ex), x1 = (int)floor(s + ex);
    int y0 = (int)ceil(t - ey), y1 = (int)floor(t + ey);
    if ((double)(x1 - x0 + 1) * (double)(y1 - y0 + 1) > TB__EWA_MAX_TEXELS)
        return false;
    double sum[TB_TEX_MAX_CHANNELS] = {0}, wsum = 0.0;
    double tail = exp(-TB__EWA_ALPHA);
    for (int y = y0; y <= y1; y++) {
        double dy = (double)y - t;
        for (int x = x0; x <= x1; x++) {
            double dx = (double)x - s;
            double r2 = A * dx * dx + B * dx * dy + C * dy * dy;
            if (r2 >= 1.0)
                continue;
            double w = exp(-TB__EWA_ALPHA * r2) - tail;
            const float *tx = tb__texel_ptr(lv, ch, x, y, wrap);
            for (int c = 0; c < ch; c++)
                sum[c] += w * (double)tx[c];
            wsum += w;
        }
    }
    tb_stat_add(&tb__stat_ewa_texels, (int64_t)(x1 - x0 + 1) * (y1 - y0 + 1));
    if (!(wsum > 0.0)) {
        /* cannot happen (the unit disc always holds a texel centre), but
         * never divide by zero */
        tb__bilinear_d(m, l, u, v, wrap, acc);
        return true;
    }
    for (int c = 0; c < ch; c++)
        acc[c] = sum[c] / wsum;
    return true;
}

/* EWA at level l, moving up while the ellipse is too large for the level. */
static void tb__ewa_at(const tb_mipmap *m, int l, double u, double v, const double a[2],
                       const double b[2], tb_tex_wrap wrap, double *acc)
{
    while (!tb__ewa_level(m, l, u, v, a, b, wrap, acc))
        l++; /* the 1 x 1 top level always succeeds */
}

void tb_mipmap_ewa(const tb_mipmap *m, float u, float v, const tb_tex_footprint *fp,
                   tb_tex_wrap wrap, float max_aniso, float *out)
{
    TB_STAT_INC(tb__stat_ewa);
    double a[2], b[2];
    tb__axes(m, fp, a, b);
    double la = sqrt(a[0] * a[0] + a[1] * a[1]), lb = sqrt(b[0] * b[0] + b[1] * b[1]);
    /* a: major axis, b: minor axis */
    if (la < lb) {
        double t0 = a[0], t1 = a[1], tl = la;
        a[0] = b[0];
        a[1] = b[1];
        la = lb;
        b[0] = t0;
        b[1] = t1;
        lb = tl;
    }
    double acc[TB_TEX_MAX_CHANNELS];
    if (la == 0.0) {
        tb__bilinear_d(m, 0, u, v, wrap, acc);
    } else {
        double aniso = max_aniso > 0.0f ? (double)max_aniso : (double)TB_TEX_MAX_ANISO_DEFAULT;
        if (lb * aniso < la) {
            /* too eccentric: lengthen the minor axis (keeping its direction,
             * or perpendicular to the major one if it has none) */
            double want = la / aniso;
            if (lb > 0.0) {
                b[0] *= want / lb;
                b[1] *= want / lb;
            } else {
                b[0] = -a[1] * (want / la);
                b[1] = a[0] * (want / la);
            }
            lb = want;
        }
        double lod = tb__level_of(m, lb);
        int l0 = (int)floor(lod);
        double f = lod - l0;
        tb__ewa_at(m, l0, u, v, a, b, wrap, acc);
        if (f > 0.0 && l0 + 1 < m->nlevels) {
            double acc1[TB_TEX_MAX_CHANNELS];
            tb__ewa_at(m, l0 + 1, u, v, a, b, wrap, acc1);
            for (int c = 0; c < m->channels; c++)
                acc[c] += f * (acc1[c] - acc[c]);
        }
    }
    for (int c = 0; c < m->channels; c++)
        out[c] = (float)acc[c];
}

void tb_mipmap_lookup(const tb_mipmap *m, tb_tex_filter filter, float u, float v,
                      const tb_tex_footprint *fp, tb_tex_wrap wrap, float max_aniso, float *out)
{
    static const tb_tex_footprint zero = {0.0f, 0.0f, 0.0f, 0.0f};
    if (!fp)
        fp = &zero;
    switch (filter) {
    case TB_TEX_NEAREST:
        tb_mipmap_nearest(m, 0, u, v, wrap, out);
        return;
    case TB_TEX_BILINEAR:
        tb_mipmap_bilinear(m, 0, u, v, wrap, out);
        return;
    case TB_TEX_TRILINEAR:
        tb_mipmap_trilinear(m, u, v, fp, wrap, out);
        return;
    case TB_TEX_EWA:
        tb_mipmap_ewa(m, u, v, fp, wrap, max_aniso, out);
        return;
    }
    tb_mipmap_bilinear(m, 0, u, v, wrap, out);
}

/* ---------------------------------------------------------------- differentials */

static tb_dvec3 tb__d(tb_vec3 v) { return tb_vec3_to_d(v); }

/* Where the ray o + t d meets the plane n . x = dist; false if parallel or behind. */
static bool tb__plane_hit(tb_dvec3 n, double dist, tb_vec3 o, tb_vec3 d, tb_dvec3 *hit)
{
    tb_dvec3 od = tb__d(o), dd = tb__d(d);
    double den = tb_dvec3_dot(n, dd);
    if (den == 0.0 || !isfinite(den))
        return false;
    double t = (dist - tb_dvec3_dot(n, od)) / den;
    if (!(t >= 0.0) || !isfinite(t))
        return false;
    *hit = tb_dvec3_add(od, tb_dvec3_scale(dd, t));
    return tb_dvec3_isfinite(*hit);
}

static float tb__clamp_deriv(double x)
{
    return (float)(x > 1e8 ? 1e8 : (x < -1e8 ? -1e8 : x));
}

bool tb_tex_footprint_from_rays(tb_vec3 p, tb_vec3 n, tb_vec3 dpdu, tb_vec3 dpdv,
                                const tb_ray_differential *rd, tb_tex_footprint *fp, tb_vec3 *dpdx,
                                tb_vec3 *dpdy)
{
    *fp = (tb_tex_footprint){0.0f, 0.0f, 0.0f, 0.0f};
    if (dpdx)
        *dpdx = tb_vec3_splat(0.0f);
    if (dpdy)
        *dpdy = tb_vec3_splat(0.0f);
    tb_dvec3 pd = tb__d(p), nd = tb__d(n);
    double dist = tb_dvec3_dot(nd, pd);
    tb_dvec3 px, py;
    if (!tb__plane_hit(nd, dist, rd->rx_o, rd->rx_d, &px) || !tb__plane_hit(nd, dist, rd->ry_o, rd->ry_d, &py))
        return false;
    tb_dvec3 ex = tb_dvec3_sub(px, pd), ey = tb_dvec3_sub(py, pd);
    /* least squares: (A^T A) x = A^T b with A = [dpdu dpdv] */
    tb_dvec3 du = tb__d(dpdu), dv = tb__d(dpdv);
    double uu = tb_dvec3_dot(du, du), uv = tb_dvec3_dot(du, dv), vv = tb_dvec3_dot(dv, dv);
    double det = uu * vv - uv * uv;
    if (!(det > 1e-12 * uu * vv) || !isfinite(det))
        return false;
    double bxu = tb_dvec3_dot(du, ex), bxv = tb_dvec3_dot(dv, ex);
    double byu = tb_dvec3_dot(du, ey), byv = tb_dvec3_dot(dv, ey);
    fp->dudx = tb__clamp_deriv((vv * bxu - uv * bxv) / det);
    fp->dvdx = tb__clamp_deriv((uu * bxv - uv * bxu) / det);
    fp->dudy = tb__clamp_deriv((vv * byu - uv * byv) / det);
    fp->dvdy = tb__clamp_deriv((uu * byv - uv * byu) / det);
    if (dpdx)
        *dpdx = tb_dvec3_to_f(ex);
    if (dpdy)
        *dpdy = tb_dvec3_to_f(ey);
    return true;
}
