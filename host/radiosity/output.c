/* Radiosity outputs: the --patches CSV, the PLY mesh and the display colours
 * shared with the glTF writer (output_gltf.c) (docs/radiosity.md, "Outputs"). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "host/radiosity/output_internal.h"
#include "host/radiosity/radiosity.h"
#include "util/base/outfile.h"
#include "util/color/srgb.h"
#include "util/math/float.h"
#include "util/stats/provenance.h"

/* Column suffix of channel c: r, g, b, or the band's wavelength. */
static void tb__channel_name(const tb_rad_mesh *m, int c, char *buf, size_t n)
{
    if (m->spectral)
        snprintf(buf, n, "%g", m->bands.lambda[c]);
    else
        snprintf(buf, n, "%s", c == 0 ? "r" : c == 1 ? "g" : c == 2 ? "b" : "x");
}

/* Rows of the patches CSV per chunk a thread formats, and chunks per round
 * (the memory held before they are written: about 1 KB a row). */
#define TB__PATCH_CHUNK 64
#define TB__PATCH_ROUND 64

/* The CSV rows of elements [a, z) into fp. */
static void tb__patch_rows(const tb_rad_solver *s, const tb_rad_mesh *m, size_t a, size_t z, FILE *fp)
{
    int nc = m->nchannels;
    double b[TB_CHANNELS_MAX], u[TB_CHANNELS_MAX];
    for (size_t i = a; i < z; i++) {
        const tb_rad_element *e = &m->elems[i];
        fprintf(fp, "%zu,%u,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g", i, e->object, e->area, (double)e->centroid.x,
                (double)e->centroid.y, (double)e->centroid.z, (double)e->normal.x, (double)e->normal.y,
                (double)e->normal.z);
        tb_rad_element_radiosity(s, i, false, b);
        tb_rad_element_unshot(s, i, u);
        for (int c = 0; c < nc; c++)
            fprintf(fp, ",%.9g", b[c]);
        for (int c = 0; c < nc; c++)
            fprintf(fp, ",%.9g", u[c]);
        if (m->npatches > 0)
            fprintf(fp, ",%u", m->patch[i]);
        fputc('\n', fp);
    }
}

tb_status tb_rad_write_patches(const tb_rad_solver *s, const char *path)
{
    const tb_rad_mesh *m = tb_rad_solver_mesh(s);
    tb_outfile of;
    tb_status st = tb_outfile_open(&of, path);
    if (st)
        return st;
    FILE *fp = of.fp;
    int nc = m->nchannels;
    char name[32];
    fputs("element,object,area,cx,cy,cz,nx,ny,nz", fp);
    for (int c = 0; c < nc; c++)
        tb__channel_name(m, c, name, sizeof name), fprintf(fp, ",b_%s", name);
    for (int c = 0; c < nc; c++)
        tb__channel_name(m, c, name, sizeof name), fprintf(fp, ",u_%s", name);
    if (m->npatches > 0) /* two levels: appended, so the one-level columns keep their places */
        fputs(",patch", fp);
    fputc('\n', fp);
    /* rows formatted by all threads, a chunk each into memory, written in
     * order: the same bytes as one thread's fprintf (the number formatting
     * is most of the writer's time) */
    size_t ne = m->nelems;
    bool nomem = false;
    for (size_t r0 = 0; r0 < ne && !nomem; r0 += TB__PATCH_ROUND * TB__PATCH_CHUNK) {
        size_t r1 = r0 + TB__PATCH_ROUND * TB__PATCH_CHUNK < ne ? r0 + TB__PATCH_ROUND * TB__PATCH_CHUNK : ne;
        ptrdiff_t nch = (ptrdiff_t)((r1 - r0 + TB__PATCH_CHUNK - 1) / TB__PATCH_CHUNK);
        char *buf[TB__PATCH_ROUND] = {0};
        size_t len[TB__PATCH_ROUND] = {0};
#pragma omp parallel for schedule(dynamic, 1)
        for (ptrdiff_t k = 0; k < nch; k++) {
            size_t a = r0 + (size_t)k * TB__PATCH_CHUNK, z = a + TB__PATCH_CHUNK < r1 ? a + TB__PATCH_CHUNK : r1;
            FILE *ms = open_memstream(&buf[k], &len[k]);
            if (!ms)
                continue;
            tb__patch_rows(s, m, a, z, ms);
            if (fclose(ms) != 0)
                free(buf[k]), buf[k] = NULL;
        }
        for (ptrdiff_t k = 0; k < nch; k++) {
            if (!buf[k])
                nomem = true;
            else if (!nomem)
                fwrite(buf[k], 1, len[k], fp);
            free(buf[k]);
        }
    }
    if (nomem) {
        tb_outfile_abort(&of);
        return tb_error(TB_ERR_NOMEM, "%s: out of memory formatting the rows", path);
    }
    if (ferror(fp)) {
        tb_outfile_abort(&of);
        return tb_error(TB_ERR_IO, "%s: write failed", path);
    }
    return tb_outfile_commit(&of);
}

tb_status tb_rad_read_patches(const char *path, size_t *nrows, int *ncols, double **b)
{
    *nrows = 0, *ncols = 0, *b = NULL;
    FILE *fp = fopen(path, "r");
    if (!fp)
        return tb_error(TB_ERR_IO, "%s: %s", path, strerror(errno));
    size_t cap = 1 << 16, len = 0;
    char *line = malloc(cap);
    tb_status st = TB_OK;
    size_t lineno = 0, rows = 0, rcap = 0;
    int nb = -1, first_b = -1, ntot = 0;
    double *vals = NULL;
    if (!line) {
        fclose(fp);
        return tb_error(TB_ERR_NOMEM, "out of memory");
    }
    int ch;
    for (;;) {
        len = 0;
        while ((ch = fgetc(fp)) != EOF && ch != '\n') {
            if (len + 1 >= cap) {
                char *p = realloc(line, cap * 2);
                if (!p) {
                    st = tb_error(TB_ERR_NOMEM, "out of memory");
                    goto done;
                }
                line = p, cap *= 2;
            }
            line[len++] = (char)ch;
        }
        if (len == 0 && ch == EOF)
            break;
        line[len] = 0;
        if (len && line[len - 1] == '\r')
            line[--len] = 0;
        lineno++;
        if (lineno == 1) {
            /* header: count the b_ columns and where they start */
            if (strncmp(line, "element,object,area,cx,cy,cz,nx,ny,nz,", 38) != 0) {
                st = tb_error(TB_ERR_FORMAT, "%s:1: not a radiosity patches CSV (header '%.40s')", path, line);
                goto done;
            }
            int col = 0;
            nb = 0;
            for (char *t = line; t; t = strchr(t, ',') ? strchr(t, ',') + 1 : NULL, col++) {
                if (!strncmp(t, "b_", 2)) {
                    if (first_b < 0)
                        first_b = col;
                    nb++;
                }
            }
            ntot = col;
            if (nb == 0) {
                st = tb_error(TB_ERR_FORMAT, "%s:1: no b_ columns", path);
                goto done;
            }
            continue;
        }
        if (rows == rcap) {
            rcap = rcap ? 2 * rcap : 1024;
            double *p = realloc(vals, rcap * (size_t)nb * sizeof *p);
            if (!p) {
                st = tb_error(TB_ERR_NOMEM, "out of memory");
                goto done;
            }
            vals = p;
        }
        char *t = line;
        int col = 0;
        for (; col < ntot && t; col++) {
            char *end;
            double v = strtod(t, &end);
            if (end == t || (*end != ',' && *end != 0)) {
                st = tb_error(TB_ERR_FORMAT, "%s:%zu: column %d is not a number", path, lineno, col + 1);
                goto done;
            }
            if (col >= first_b && col < first_b + nb)
                vals[rows * (size_t)nb + (size_t)(col - first_b)] = v;
            t = *end == ',' ? end + 1 : NULL;
        }
        if (col != ntot || t) {
            st = tb_error(TB_ERR_FORMAT, "%s:%zu: expected %d columns", path, lineno, ntot);
            goto done;
        }
        rows++;
    }
    if (lineno == 0)
        st = tb_error(TB_ERR_FORMAT, "%s: empty file", path);
done:
    free(line);
    fclose(fp);
    if (st) {
        free(vals);
        return st;
    }
    *nrows = rows, *ncols = nb, *b = vals;
    return TB_OK;
}

/* Linear sRGB of a radiosity (channels of the mesh), radiance B / pi. */
static void tb__to_rgb(const tb_rad_mesh *m, const double *b, double rgb[3])
{
    if (m->spectral) {
        double v[TB_CHANNELS_MAX];
        for (int c = 0; c < m->nchannels; c++)
            v[c] = b[c] / TB_PI;
        tb_bands_to_linear_srgb(&m->bands, v, 1.0, rgb);
    } else {
        for (int c = 0; c < 3; c++)
            rgb[c] = (c < m->nchannels ? b[c] : b[0]) / TB_PI;
    }
}

void tb__rad_corner_colour(const tb_rad_solver *s, const double *amb, size_t i, int k, double scale, float radiance[3],
                           float display[3], unsigned char u8[3])
{
    double b[TB_CHANNELS_MAX], rgb[3];
    tb_rad_corner_radiosity_amb(s, i, k, amb, b);
    tb__to_rgb(tb_rad_solver_mesh(s), b, rgb);
    for (int c = 0; c < 3; c++) {
        double x = rgb[c] * scale;
        x = x < 0.0 ? 0.0 : x > 1.0 ? 1.0 : x; /* NaN stays NaN: the solution would be broken */
        radiance[c] = (float)rgb[c];
        display[c] = (float)x;
        double e = tb_srgb_encode((float)x);
        e = e < 0.0 ? 0.0 : e > 1.0 ? 1.0 : e;
        u8[c] = (unsigned char)lround(e * 255.0);
    }
}

char *tb__rad_provenance_json(const tb_provenance *p, int indent, size_t *len)
{
    char *buf = NULL;
    size_t n = 0;
    if (!p)
        return NULL;
    FILE *fp = open_memstream(&buf, &n);
    if (!fp)
        return NULL;
    tb_provenance_write_json(fp, p, indent);
    if (fclose(fp) != 0) {
        free(buf);
        return NULL;
    }
    if (len)
        *len = n;
    return buf;
}

double tb_rad_display_scale(const tb_rad_solver *s)
{
    const tb_rad_mesh *m = tb_rad_solver_mesh(s);
    double sum = 0.0, area = 0.0, b[TB_CHANNELS_MAX];
    for (size_t i = 0; i < m->nelems; i++) {
        bool emits = false;
        for (int c = 0; c < m->nchannels; c++)
            emits |= m->emission[i * (size_t)m->nchannels + (size_t)c] > 0.0f;
        if (emits)
            continue;
        tb_rad_element_radiosity(s, i, true, b);
        double y = 0.0;
        if (m->spectral) {
            double xyz[3];
            tb_bands_to_xyz(&m->bands, b, xyz);
            y = xyz[1];
        } else
            y = 0.2126 * b[0] + 0.7152 * b[1] + 0.0722 * b[2];
        sum += y / TB_PI * m->elems[i].area;
        area += m->elems[i].area;
    }
    double mean = area > 0.0 ? sum / area : 0.0, scale = mean > 0.0 ? 0.18 / mean : 1.0;
    return isfinite(scale) ? scale : 1.0;
}

tb_rad_mesh_format tb_rad_mesh_format_from_path(const char *path)
{
    const char *dot = path ? strrchr(path, '.') : NULL;
    if (!dot || strchr(dot, '/'))
        return TB_RAD_MESH_UNKNOWN;
    if (!strcasecmp(dot, ".ply"))
        return TB_RAD_MESH_PLY;
    if (!strcasecmp(dot, ".gltf"))
        return TB_RAD_MESH_GLTF;
    if (!strcasecmp(dot, ".glb"))
        return TB_RAD_MESH_GLB;
    return TB_RAD_MESH_UNKNOWN;
}

tb_status tb_rad_write_ply(const tb_rad_solver *s, const char *path, double scale, const tb_provenance *prov)
{
    const tb_rad_mesh *m = tb_rad_solver_mesh(s);
    size_t ncorners = 0;
    for (size_t i = 0; i < m->nelems; i++)
        ncorners += m->elems[i].v[3] == TB_RAD_NONE ? 3 : 4;
    char *pj = tb__rad_provenance_json(prov, 0, NULL);
    if (prov && !pj)
        return tb_error(TB_ERR_NOMEM, "%s: out of memory", path);
    /* one comment line: JSON's own newlines are only layout */
    for (char *c = pj; c && *c; c++)
        if (*c == '\n' || *c == '\r')
            *c = ' ';
    tb_outfile of;
    tb_status st = tb_outfile_open(&of, path);
    if (st) {
        free(pj);
        return st;
    }
    FILE *fp = of.fp;
    fprintf(fp,
            "ply\nformat binary_little_endian 1.0\ncomment testbed radiosity solution: colour = radiance B/pi in "
            "linear sRGB (r g b floats) and 8-bit sRGB times %.9g (red green blue)\n",
            scale);
    if (pj)
        fprintf(fp, "comment testbed provenance %s\n", pj);
    free(pj);
    fprintf(fp,
            "element vertex %zu\nproperty float x\nproperty float y\nproperty float z\n"
            "property float nx\nproperty float ny\nproperty float nz\n"
            "property float r\nproperty float g\nproperty float b\n"
            "property uchar red\nproperty uchar green\nproperty uchar blue\n"
            "element face %zu\nproperty list uchar uint vertex_indices\nproperty uint object\nend_header\n",
            ncorners, m->nelems);
    double amb[TB_CHANNELS_MAX]; /* summed once, not at every corner */
    tb_rad_ambient(s, amb);
    for (size_t i = 0; i < m->nelems; i++) {
        const tb_rad_element *e = &m->elems[i];
        int n = e->v[3] == TB_RAD_NONE ? 3 : 4;
        for (int k = 0; k < n; k++) {
            const tb_rad_vertex *v = &m->verts[e->v[k]];
            float rad[3], disp[3];
            unsigned char u8[3];
            tb__rad_corner_colour(s, amb, i, k, scale, rad, disp, u8);
            float f[9] = {v->p.x, v->p.y, v->p.z, e->normal.x, e->normal.y, e->normal.z, rad[0], rad[1], rad[2]};
            fwrite(f, sizeof f, 1, fp);
            fwrite(u8, 1, 3, fp);
        }
    }
    uint32_t base = 0;
    for (size_t i = 0; i < m->nelems; i++) {
        const tb_rad_element *e = &m->elems[i];
        unsigned char n = e->v[3] == TB_RAD_NONE ? 3 : 4;
        uint32_t idx[4] = {base, base + 1, base + 2, base + 3};
        fwrite(&n, 1, 1, fp);
        fwrite(idx, sizeof(uint32_t), n, fp);
        fwrite(&e->object, sizeof(uint32_t), 1, fp);
        base += n;
    }
    if (ferror(fp)) {
        tb_outfile_abort(&of);
        return tb_error(TB_ERR_IO, "%s: write failed", path);
    }
    return tb_outfile_commit(&of);
}
