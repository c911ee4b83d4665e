#include "util/itembuf/itembuf.h"

#include <math.h>
#include <stdlib.h>

tb_itembuf *tb_itembuf_create(int width, int height)
{
    if (width < 1 || height < 1 || width > TB_SCAN_MAX_DIM || height > TB_SCAN_MAX_DIM) {
        tb_error(TB_ERR_ARG, "item buffer: size %dx%d outside 1..%d", width, height, TB_SCAN_MAX_DIM);
        return NULL;
    }
    size_t n = (size_t)width * (size_t)height; /* <= 2^40: no overflow on 64-bit size_t */
    tb_itembuf *buf = malloc(sizeof *buf);
    if (buf) {
        buf->width = width;
        buf->height = height;
        buf->ids = malloc(n * sizeof *buf->ids);
        buf->depth = malloc(n * sizeof *buf->depth);
    }
    if (!buf || !buf->ids || !buf->depth) {
        tb_itembuf_free(buf);
        tb_error(TB_ERR_NOMEM, "item buffer: cannot allocate %dx%d pixels", width, height);
        return NULL;
    }
    tb_itembuf_clear(buf);
    return buf;
}

void tb_itembuf_free(tb_itembuf *buf)
{
    if (!buf)
        return;
    free(buf->ids);
    free(buf->depth);
    free(buf);
}

void tb_itembuf_clear(tb_itembuf *buf)
{
    size_t n = (size_t)buf->width * (size_t)buf->height;
    for (size_t i = 0; i < n; i++) {
        buf->ids[i] = TB_ITEMBUF_EMPTY;
        buf->depth[i] = INFINITY;
    }
}

/* What the span callback needs: the buffer, the item and its depth plane
 * z(x, y) = z0 + gx (x - x0) + gy (y - y0). */
typedef struct tb__draw {
    tb_itembuf *buf;
    uint32_t id;
    double x0, y0, z0, gx, gy;
} tb__draw;

static void tb__draw_span(void *user, int y, int x0, int x1)
{
    const tb__draw *d = user;
    size_t row = (size_t)y * (size_t)d->buf->width;
    uint32_t *ids = d->buf->ids + row;
    float *depth = d->buf->depth + row;
    double zrow = d->z0 + d->gy * ((y + 0.5) - d->y0);
    for (int x = x0; x < x1; x++) {
        float z = (float)(zrow + d->gx * ((x + 0.5) - d->x0));
        /* Nearer wins; equal depth: lower id, whatever the drawing order. */
        if (z < depth[x] || (z == depth[x] && d->id < ids[x])) {
            depth[x] = z;
            ids[x] = d->id;
        }
    }
}

/* Plane through three well-separated vertices: a = leftmost, b = farthest from
 * a, c = farthest from the line ab. False if all vertices are collinear. */
static int tb__depth_plane(const float (*xy)[2], const float *depth, int n, tb__draw *d)
{
    int a = 0, b = 0, c = 0;
    for (int i = 1; i < n; i++)
        if (xy[i][0] < xy[a][0] || (xy[i][0] == xy[a][0] && xy[i][1] < xy[a][1]))
            a = i;
    double ax = xy[a][0], ay = xy[a][1], best = 0;
    for (int i = 0; i < n; i++) {
        double dx = xy[i][0] - ax, dy = xy[i][1] - ay, d2 = dx * dx + dy * dy;
        if (d2 > best) {
            best = d2;
            b = i;
        }
    }
    double ex = xy[b][0] - ax, ey = xy[b][1] - ay;
    best = 0;
    for (int i = 0; i < n; i++) {
        double cr = fabs(ex * (xy[i][1] - ay) - ey * (xy[i][0] - ax));
        if (cr > best) {
            best = cr;
            c = i;
        }
    }
    if (best == 0)
        return 0;
    double fx = xy[c][0] - ax, fy = xy[c][1] - ay;
    double det = ex * fy - fx * ey;
    double za = depth ? depth[a] : 0, eb = depth ? depth[b] - za : 0, ec = depth ? depth[c] - za : 0;
    d->x0 = ax;
    d->y0 = ay;
    d->z0 = za;
    d->gx = (eb * fy - ec * ey) / det;
    d->gy = (ex * ec - fx * eb) / det;
    return 1;
}

tb_status tb_itembuf_draw_contours(tb_itembuf *buf, const float (*xy)[2], const float *depth,
                                   const int *counts, int ncontours, tb_fill_rule rule, uint32_t id)
{
    if (!buf)
        return tb_error(TB_ERR_ARG, "item buffer: NULL buffer");
    if (id == TB_ITEMBUF_EMPTY)
        return tb_error(TB_ERR_ARG, "item buffer: id %u is reserved for empty pixels", (unsigned)id);
    if (ncontours < 0 || (ncontours > 0 && !counts))
        return tb_error(TB_ERR_ARG, "item buffer: bad contour list");
    int n = 0;
    for (int c = 0; c < ncontours; c++) {
        if (counts[c] < 0 || counts[c] > INT32_MAX / 16 - n)
            return tb_error(TB_ERR_ARG, "item buffer: bad vertex count %d", counts[c]);
        n += counts[c];
    }
    if (n > 0 && !xy)
        return tb_error(TB_ERR_ARG, "item buffer: NULL vertex array");
    for (int i = 0; depth && i < n; i++)
        if (!isfinite(depth[i]))
            return tb_error(TB_ERR_ARG, "item buffer: depth of vertex %d is not finite (%g)", i,
                            (double)depth[i]);
    for (int i = 0; i < n; i++)
        if (!isfinite(xy[i][0]) || !isfinite(xy[i][1]))
            return tb_error(TB_ERR_ARG, "item buffer: vertex %d is not finite (%g, %g)", i,
                            (double)xy[i][0], (double)xy[i][1]);
    tb__draw d = {buf, id, 0, 0, 0, 0, 0};
    if (n < 3 || !tb__depth_plane(xy, depth, n, &d))
        return TB_OK; /* no interior */
    return tb_scan_contours(buf->width, buf->height, xy, counts, ncontours, rule, tb__draw_span, &d);
}

tb_status tb_itembuf_draw_polygon(tb_itembuf *buf, const float (*xy)[2], const float *depth, int n,
                                  uint32_t id)
{
    if (n < 0)
        return tb_error(TB_ERR_ARG, "item buffer: negative vertex count %d", n);
    return tb_itembuf_draw_contours(buf, xy, depth, &n, 1, TB_FILL_EVEN_ODD, id);
}

tb_status tb_itembuf_accumulate(const tb_itembuf *buf, const float *weights, double *sum_per_id,
                                uint32_t nids)
{
    size_t n = (size_t)buf->width * (size_t)buf->height;
    for (size_t i = 0; i < n; i++)
        if (buf->ids[i] != TB_ITEMBUF_EMPTY && buf->ids[i] >= nids)
            return tb_error(TB_ERR_ARG, "item buffer: pixel %zu holds id %u, beyond the %u sums", i,
                            (unsigned)buf->ids[i], (unsigned)nids);
    for (size_t i = 0; i < n; i++)
        if (buf->ids[i] != TB_ITEMBUF_EMPTY)
            sum_per_id[buf->ids[i]] += weights ? (double)weights[i] : 1.0;
    return TB_OK;
}
