/* The solved radiosity mesh as glTF 2.0 (.gltf with an embedded base64
 * buffer, or .glb): the PLY's vertices, normals and colours, for viewers
 * that read glTF (docs/radiosity.md, "Outputs"). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <openssl/evp.h>

#include "host/radiosity/output_internal.h"
#include "host/radiosity/radiosity.h"
#include "tb_version.h"
#include "util/base/outfile.h"
#include "util/stats/provenance.h"
#include "util/stats/stats.h"

/* glTF enums (WebGL values). */
#define TB__GL_FLOAT 5126
#define TB__GL_UNSIGNED_INT 5125
#define TB__GL_ARRAY_BUFFER 34962
#define TB__GL_ELEMENT_ARRAY_BUFFER 34963

/* GLB container: magic "glTF", version 2, chunk types "JSON" and "BIN\0". */
#define TB__GLB_MAGIC 0x46546C67u
#define TB__GLB_JSON 0x4E4F534Au
#define TB__GLB_BIN 0x004E4942u

/* Vertex attribute arrays in buffer order; indices come last. */
enum { TB__ATTR_POSITION, TB__ATTR_NORMAL, TB__ATTR_COLOR, TB__ATTR_RADIANCE, TB__ATTR_COUNT };

static const char *const tb__attr_name[TB__ATTR_COUNT] = {"POSITION", "NORMAL", "COLOR_0", "_RADIANCE"};

/* Little-endian uint32 (the buffer and the GLB are little-endian whatever the host). */
static void tb__put_u32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)v, p[1] = (unsigned char)(v >> 8), p[2] = (unsigned char)(v >> 16),
    p[3] = (unsigned char)(v >> 24);
}

static void tb__put_f32(unsigned char *p, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    tb__put_u32(p, u);
}

/* `n` bytes as base64 (RFC 4648, with padding) through OpenSSL, in pieces
 * whose length is a multiple of 3 so the output is one unbroken string. */
static void tb__write_base64(FILE *fp, const unsigned char *data, size_t n)
{
    enum { PIECE = 3 * 16384 };
    unsigned char out[4 * (PIECE / 3) + 1];
    for (size_t off = 0; off < n; off += PIECE) {
        size_t k = n - off < PIECE ? n - off : PIECE;
        int w = EVP_EncodeBlock(out, data + off, (int)k);
        fwrite(out, 1, (size_t)w, fp);
    }
}

/* The glTF JSON; `uri_data` non-NULL embeds the buffer as a data URI. */
static void tb__write_json(FILE *fp, const tb_rad_mesh *m, size_t nverts, size_t nidx, const float lo[3],
                           const float hi[3], size_t bytes, const unsigned char *uri_data, double scale,
                           const tb_provenance *prov)
{
    size_t attr_bytes = nverts * 12;
    fputs("{\n  \"asset\": {\n    \"version\": \"2.0\",\n    \"generator\": ", fp);
    char gen[160];
    snprintf(gen, sizeof gen, "testbed %s radiosity (%s)", prov && prov->version[0] ? prov->version : TB_VERSION_STRING,
             prov && prov->git_revision[0] ? prov->git_revision : TB_GIT_REVISION);
    tb_json_write_string(fp, gen);
    fputs(",\n    \"extras\": {\n      \"colours\": ", fp);
    tb_json_write_string(fp, "COLOR_0 is the radiance B/pi (ambient term included) in linear sRGB times "
                             "display_scale, clamped to [0, 1]: the PLY's 8-bit red green blue before sRGB "
                             "encoding. _RADIANCE is the unscaled, unclamped linear sRGB radiance B/pi (the "
                             "PLY's float r g b), in W/m^2/sr per unit of MID emission.");
    fprintf(fp, ",\n      \"display_scale\": %.17g,\n      \"display_rule\": ", scale);
    tb_json_write_string(fp, "the area-weighted mean luminance of B/pi over the elements that do not emit is "
                             "mapped to 0.18; no tone curve");
    fprintf(fp, ",\n      \"units\": \"the scene's (MID) units and axes, unscaled\",\n      \"elements\": %zu,\n"
                "      \"colour_channels\": \"%s\",\n      \"provenance\": ",
            m->nelems, m->spectral ? "spectral" : "rgb");
    if (prov)
        tb_provenance_write_json(fp, prov, 6);
    else
        fputs("null", fp);
    fputs("\n    }\n  },\n", fp);
    fputs("  \"extensionsUsed\": [\"KHR_materials_unlit\"],\n  \"scene\": 0,\n"
          "  \"scenes\": [{\"nodes\": [0]}],\n  \"nodes\": [{\"mesh\": 0, \"name\": \"radiosity solution\"}],\n"
          "  \"meshes\": [{\"name\": \"radiosity solution\", \"primitives\": [{\"attributes\": {",
          fp);
    for (int a = 0; a < TB__ATTR_COUNT; a++)
        fprintf(fp, "%s\"%s\": %d", a ? ", " : "", tb__attr_name[a], a);
    fprintf(fp, "}, \"indices\": %d, \"material\": 0, \"mode\": 4}]}],\n", TB__ATTR_COUNT);
    /* Unlit: viewers show COLOR_0 as computed. The PBR values are the
     * extension's recommended fallback for viewers without it. */
    fputs("  \"materials\": [{\"name\": \"radiosity (unlit vertex colours)\", \"pbrMetallicRoughness\": "
          "{\"baseColorFactor\": [1, 1, 1, 1], \"metallicFactor\": 0, \"roughnessFactor\": 1}, "
          "\"extensions\": {\"KHR_materials_unlit\": {}}}],\n",
          fp);
    fputs("  \"accessors\": [\n", fp);
    for (int a = 0; a < TB__ATTR_COUNT; a++) {
        fprintf(fp, "    {\"bufferView\": %d, \"componentType\": %d, \"count\": %zu, \"type\": \"VEC3\"", a,
                TB__GL_FLOAT, nverts);
        if (a == TB__ATTR_POSITION) /* required for POSITION; floats print exactly with 9 digits */
            fprintf(fp, ", \"min\": [%.9g, %.9g, %.9g], \"max\": [%.9g, %.9g, %.9g]", (double)lo[0], (double)lo[1],
                    (double)lo[2], (double)hi[0], (double)hi[1], (double)hi[2]);
        fputs("},\n", fp);
    }
    fprintf(fp, "    {\"bufferView\": %d, \"componentType\": %d, \"count\": %zu, \"type\": \"SCALAR\"}\n  ],\n",
            TB__ATTR_COUNT, TB__GL_UNSIGNED_INT, nidx);
    fputs("  \"bufferViews\": [\n", fp);
    for (int a = 0; a < TB__ATTR_COUNT; a++)
        fprintf(fp, "    {\"buffer\": 0, \"byteOffset\": %zu, \"byteLength\": %zu, \"target\": %d},\n",
                (size_t)a * attr_bytes, attr_bytes, TB__GL_ARRAY_BUFFER);
    fprintf(fp, "    {\"buffer\": 0, \"byteOffset\": %zu, \"byteLength\": %zu, \"target\": %d}\n  ],\n",
            (size_t)TB__ATTR_COUNT * attr_bytes, nidx * 4, TB__GL_ELEMENT_ARRAY_BUFFER);
    fprintf(fp, "  \"buffers\": [{\"byteLength\": %zu", bytes);
    if (uri_data) {
        fputs(", \"uri\": \"data:application/octet-stream;base64,", fp);
        tb__write_base64(fp, uri_data, bytes);
        fputc('"', fp);
    }
    fputs("}]\n}\n", fp);
}

tb_status tb_rad_write_gltf(const tb_rad_solver *s, const char *path, double scale, bool binary,
                            const tb_provenance *prov)
{
    const tb_rad_mesh *m = tb_rad_solver_mesh(s);
    size_t nverts = 0, nidx = 0;
    for (size_t i = 0; i < m->nelems; i++) {
        int n = m->elems[i].v[3] == TB_RAD_NONE ? 3 : 4;
        nverts += (size_t)n, nidx += 3 * (size_t)(n - 2);
    }
    /* uint32 indices may not hold 2^32 - 1 (the primitive-restart value) */
    if (nverts == 0)
        return tb_error(TB_ERR_ARG, "%s: the mesh is empty", path);
    if (nverts >= UINT32_MAX || nverts > SIZE_MAX / (TB__ATTR_COUNT * 12 + 8))
        return tb_error(TB_ERR_UNSUPPORTED, "%s: %zu vertices are too many for glTF", path, nverts);
    size_t attr_bytes = nverts * 12, bytes = TB__ATTR_COUNT * attr_bytes + nidx * 4;
    unsigned char *buf = malloc(bytes ? bytes : 1);
    if (!buf)
        return tb_error(TB_ERR_NOMEM, "%s: out of memory", path);
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    size_t v = 0, t = 0;
    unsigned char *idx = buf + TB__ATTR_COUNT * attr_bytes;
    double amb[TB_CHANNELS_MAX]; /* summed once, not at every corner */
    tb_rad_ambient(s, amb);
    for (size_t i = 0; i < m->nelems; i++) {
        const tb_rad_element *e = &m->elems[i];
        int n = e->v[3] == TB_RAD_NONE ? 3 : 4;
        for (int k = 0; k < n; k++, v++) {
            const tb_rad_vertex *rv = &m->verts[e->v[k]];
            float val[TB__ATTR_COUNT][3] = {{rv->p.x, rv->p.y, rv->p.z}, {e->normal.x, e->normal.y, e->normal.z}};
            unsigned char u8[3];
            tb__rad_corner_colour(s, amb, i, k, scale, val[TB__ATTR_RADIANCE], val[TB__ATTR_COLOR], u8);
            for (int a = 0; a < TB__ATTR_COUNT; a++)
                for (int c = 0; c < 3; c++)
                    tb__put_f32(buf + (size_t)a * attr_bytes + v * 12 + (size_t)c * 4, val[a][c]);
            for (int c = 0; c < 3; c++)
                lo[c] = fminf(lo[c], val[TB__ATTR_POSITION][c]), hi[c] = fmaxf(hi[c], val[TB__ATTR_POSITION][c]);
        }
        /* the image's split of a quad: (v0 v1 v2), (v0 v2 v3), counter-clockwise like the element */
        uint32_t b = (uint32_t)(v - (size_t)n);
        uint32_t tri[2][3] = {{b, b + 1, b + 2}, {b, b + 2, b + 3}};
        for (int k = 0; k < n - 2; k++)
            for (int c = 0; c < 3; c++, t++)
                tb__put_u32(idx + t * 4, tri[k][c]);
    }

    tb_status st = TB_OK;
    tb_outfile of;
    if (!binary) {
        if ((st = tb_outfile_open(&of, path)))
            goto done;
        tb__write_json(of.fp, m, nverts, nidx, lo, hi, bytes, buf, scale, prov);
    } else {
        /* the JSON chunk's length goes before it: build it in memory */
        char *json = NULL;
        size_t jlen = 0;
        FILE *mf = open_memstream(&json, &jlen);
        if (!mf) {
            st = tb_error(TB_ERR_NOMEM, "%s: out of memory", path);
            goto done;
        }
        tb__write_json(mf, m, nverts, nidx, lo, hi, bytes, NULL, scale, prov);
        if (fclose(mf) != 0) {
            free(json);
            st = tb_error(TB_ERR_NOMEM, "%s: out of memory", path);
            goto done;
        }
        /* chunks start and end on 4-byte boundaries: JSON padded with
         * spaces, BIN with zeros */
        size_t jpad = (4 - jlen % 4) % 4, bpad = (4 - bytes % 4) % 4;
        size_t total = 12 + 8 + jlen + jpad + 8 + bytes + bpad;
        if (total > UINT32_MAX) {
            free(json);
            st = tb_error(TB_ERR_UNSUPPORTED, "%s: %zu bytes: a .glb holds at most 4 GB (write .gltf)", path, total);
            goto done;
        }
        if ((st = tb_outfile_open(&of, path))) {
            free(json);
            goto done;
        }
        unsigned char h[12];
        tb__put_u32(h, TB__GLB_MAGIC), tb__put_u32(h + 4, 2), tb__put_u32(h + 8, (uint32_t)total);
        fwrite(h, 1, 12, of.fp);
        tb__put_u32(h, (uint32_t)(jlen + jpad)), tb__put_u32(h + 4, TB__GLB_JSON);
        fwrite(h, 1, 8, of.fp);
        fwrite(json, 1, jlen, of.fp);
        fwrite("   ", 1, jpad, of.fp);
        free(json);
        tb__put_u32(h, (uint32_t)(bytes + bpad)), tb__put_u32(h + 4, TB__GLB_BIN);
        fwrite(h, 1, 8, of.fp);
        fwrite(buf, 1, bytes, of.fp);
        fwrite("\0\0\0", 1, bpad, of.fp);
    }
    if (ferror(of.fp)) {
        tb_outfile_abort(&of);
        st = tb_error(TB_ERR_IO, "%s: write failed", path);
    } else
        st = tb_outfile_commit(&of);
done:
    free(buf);
    return st;
}
