/* Importer: one Assimp mesh to one FED mesh (docs/import.md, "Meshes").
 *
 * Positions are never computed, only copied, so they stay bit for bit what
 * Assimp read (or, for text formats, the file's numbers correctly rounded:
 * import_text.c). Faces are filtered with the same rules tb_fed_build applies
 * (polygon.h's Newell area and size), so a model with a few degenerate
 * triangles loses those faces instead of failing as a whole. */
#include "host/mid/import_internal.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util/math/float.h"
#include "util/mesh/polygon.h"

/* One vertex's written attributes, for joining by sort: 8 floats (position,
 * normal, uv; absent ones zero) compared as bytes, then the index. */
typedef struct tb__vkey {
    float a[8];
    uint32_t index;
} tb__vkey;

static int tb__vkey_cmp(const void *pa, const void *pb)
{
    const tb__vkey *a = pa, *b = pb;
    int c = memcmp(a->a, b->a, sizeof a->a);
    if (c)
        return c;
    return a->index < b->index ? -1 : a->index > b->index;
}

static bool tb__finite3(const struct aiVector3D *v) { return isfinite(v->x) && isfinite(v->y) && isfinite(v->z); }

static bool tb__same_pos(const tb_vec3 *p, uint32_t a, uint32_t b) { return tb_vec3_equal(p[a], p[b]); }

tb_status tb__import_mesh_fed(const struct aiMesh *m, bool join, tb__import_reround *rr, tb_fed **out,
                              tb__import_mesh_report *rep)
{
    *out = NULL;
    *rep = (tb__import_mesh_report){.first_dropped = UINT32_MAX};
    uint32_t nv = m->mNumVertices;
    if (nv > TB_FED_MAX_COUNT || m->mNumFaces > TB_FED_MAX_COUNT)
        return tb_error(TB_ERR_UNSUPPORTED, "%u vertices and %u faces: more than FED's limit of %u", nv,
                        m->mNumFaces, TB_FED_MAX_COUNT);

    /* Which optional attributes are written: all finite, or none. */
    bool normals = m->mNormals != NULL, uvs = m->mTextureCoords[0] != NULL && m->mNumUVComponents[0] >= 2;
    for (uint32_t i = 0; i < nv && normals; i++)
        if (!tb__finite3(&m->mNormals[i]))
            normals = false, rep->normals_dropped = true;
    for (uint32_t i = 0; i < nv && uvs; i++)
        if (!(isfinite(m->mTextureCoords[0][i].x) && isfinite(m->mTextureCoords[0][i].y)))
            uvs = false, rep->uvs_dropped = true;

    tb_status st = TB_OK;
    tb_vec3 *pos = malloc((size_t)(nv ? nv : 1) * sizeof *pos);
    uint32_t *rep_of = malloc((size_t)(nv ? nv : 1) * sizeof *rep_of); /* vertex -> representative */
    uint32_t *newidx = malloc((size_t)(nv ? nv : 1) * sizeof *newidx);
    uint64_t ncorner_cap = 0;
    for (uint32_t f = 0; f < m->mNumFaces; f++)
        ncorner_cap += m->mFaces[f].mNumIndices;
    if (ncorner_cap > TB_FED_MAX_COUNT) {
        free(pos), free(rep_of), free(newidx);
        return tb_error(TB_ERR_UNSUPPORTED, "%llu face corners: more than FED's limit of %u",
                        (unsigned long long)ncorner_cap, TB_FED_MAX_COUNT);
    }
    uint32_t *corners = malloc((size_t)(ncorner_cap ? ncorner_cap : 1) * sizeof *corners);
    uint32_t *sizes = malloc((size_t)(m->mNumFaces ? m->mNumFaces : 1) * sizeof *sizes);
    uint32_t *src_face = malloc((size_t)(m->mNumFaces ? m->mNumFaces : 1) * sizeof *src_face);
    tb_vec3 *vpos = NULL, *vnrm = NULL;
    tb_vec2 *vuv = NULL;
    if (!pos || !rep_of || !newidx || !corners || !sizes || !src_face) {
        st = tb_error(TB_ERR_NOMEM, "out of memory converting a mesh of %u vertices", nv);
        goto done;
    }
    for (uint32_t i = 0; i < nv; i++)
        pos[i] = (tb_vec3){tb__import_reround_value(rr, m->mVertices[i].x), tb__import_reround_value(rr, m->mVertices[i].y),
                           tb__import_reround_value(rr, m->mVertices[i].z)};

    /* Representatives: the lowest index of each group of equal records. */
    for (uint32_t i = 0; i < nv; i++)
        rep_of[i] = i;
    if (join && nv > 1) {
        tb__vkey *keys = calloc(nv, sizeof *keys);
        if (!keys) {
            st = tb_error(TB_ERR_NOMEM, "out of memory joining %u vertices", nv);
            goto done;
        }
        for (uint32_t i = 0; i < nv; i++) {
            tb__vkey *k = &keys[i];
            k->a[0] = pos[i].x, k->a[1] = pos[i].y, k->a[2] = pos[i].z;
            if (normals)
                k->a[3] = m->mNormals[i].x, k->a[4] = m->mNormals[i].y, k->a[5] = m->mNormals[i].z;
            if (uvs)
                k->a[6] = m->mTextureCoords[0][i].x, k->a[7] = m->mTextureCoords[0][i].y;
            k->index = i;
        }
        qsort(keys, nv, sizeof *keys, tb__vkey_cmp);
        for (uint32_t i = 1; i < nv; i++)
            if (memcmp(keys[i].a, keys[i - 1].a, sizeof keys[i].a) == 0)
                rep_of[keys[i].index] = rep_of[keys[i - 1].index];
        free(keys);
    }

    /* Faces: map to representatives, merge repeated positions, drop what FED rejects. */
    uint32_t nf = 0, nc = 0;
    for (uint32_t f = 0; f < m->mNumFaces; f++) {
        const struct aiFace *face = &m->mFaces[f];
        uint32_t n = face->mNumIndices;
        if (n < 3) {
            rep->points_lines++;
            continue;
        }
        rep->faces_in++;
        uint32_t *c = corners + nc, k = 0;
        bool finite = true;
        for (uint32_t i = 0; i < n; i++) {
            uint32_t v = face->mIndices[i];
            if (v >= nv) {
                st = tb_error(TB_ERR_FORMAT, "face %u: vertex index %u out of range (%u vertices)", f, v, nv);
                goto done;
            }
            v = rep_of[v];
            if (!tb_isfinite3(pos[v]))
                finite = false;
            if (k > 0 && tb__same_pos(pos, c[k - 1], v)) {
                rep->collapsed++;
                continue;
            }
            c[k++] = v;
        }
        while (k > 1 && tb__same_pos(pos, c[k - 1], c[0])) {
            k--;
            rep->collapsed++;
        }
        bool ok = finite && k >= 3;
        if (ok) { /* tb_fed_build's rules: a third distinct vertex, non-zero area */
            bool third = false;
            for (uint32_t i = 2; i < k && !third; i++)
                third = c[i] != c[0] && c[i] != c[1];
            double size = tb_polygon_size(pos, c, k);
            tb_dvec3 nn = tb_polygon_newell(pos, c, k);
            double area2 = sqrt(nn.x * nn.x + nn.y * nn.y + nn.z * nn.z);
            ok = third && area2 > 2 * TB_FED_DEGENERATE_REL * size * size;
        }
        if (!ok) {
            if (finite)
                rep->degenerate++;
            else
                rep->nonfinite++;
            if (rep->first_dropped == UINT32_MAX)
                rep->first_dropped = f;
            continue;
        }
        sizes[nf] = k;
        src_face[nf] = f;
        nf++;
        nc += k;
    }
    if (nf == 0)
        goto done;

    /* Keep used vertices only, in their original order. */
    for (uint32_t i = 0; i < nv; i++)
        newidx[i] = UINT32_MAX;
    for (uint32_t i = 0; i < nc; i++)
        newidx[corners[i]] = 0;
    uint32_t nused = 0;
    for (uint32_t i = 0; i < nv; i++)
        if (newidx[i] == 0)
            newidx[i] = nused++;
    vpos = malloc((size_t)nused * sizeof *vpos);
    vnrm = normals ? malloc((size_t)nused * sizeof *vnrm) : NULL;
    vuv = uvs ? malloc((size_t)nused * sizeof *vuv) : NULL;
    if (!vpos || (normals && !vnrm) || (uvs && !vuv)) {
        st = tb_error(TB_ERR_NOMEM, "out of memory converting a mesh of %u vertices", nv);
        goto done;
    }
    for (uint32_t i = 0; i < nv; i++) {
        uint32_t j = newidx[i];
        if (j == UINT32_MAX)
            continue;
        vpos[j] = pos[i];
        if (vnrm)
            vnrm[j] = (tb_vec3){m->mNormals[i].x, m->mNormals[i].y, m->mNormals[i].z};
        if (vuv)
            vuv[j] = (tb_vec2){m->mTextureCoords[0][i].x, m->mTextureCoords[0][i].y};
    }
    for (uint32_t i = 0; i < nc; i++)
        corners[i] = newidx[corners[i]];

    /* The filter above applies FED's rules, so this normally succeeds at
     * once; should a face still be refused, drop it and build again. */
    for (;;) {
        tb_fed_desc d = {.nverts = nused, .positions = vpos, .normals = vnrm, .uvs = vuv, .nfaces = nf,
                         .nloops = nf, .loop_sizes = sizes, .corners = corners};
        tb_fed_issue issue;
        st = tb_fed_build(&d, out, &issue);
        if (st != TB_ERR_FORMAT || issue.face == TB_FED_NONE || issue.face >= nf || nf == 1)
            break;
        uint32_t f = issue.face, start = 0;
        for (uint32_t i = 0; i < f; i++)
            start += sizes[i];
        memmove(corners + start, corners + start + sizes[f], (size_t)(nc - start - sizes[f]) * sizeof *corners);
        nc -= sizes[f];
        if (rep->first_dropped == UINT32_MAX || src_face[f] < rep->first_dropped)
            rep->first_dropped = src_face[f];
        memmove(sizes + f, sizes + f + 1, (size_t)(nf - f - 1) * sizeof *sizes);
        memmove(src_face + f, src_face + f + 1, (size_t)(nf - f - 1) * sizeof *src_face);
        nf--;
        rep->degenerate++;
    }
    if (st && st != TB_ERR_NOMEM)
        st = tb_error_context(st, "building the FED mesh");

done:
    free(pos), free(rep_of), free(newidx), free(corners), free(sizes), free(src_face);
    free(vpos), free(vnrm), free(vuv);
    return st;
}
