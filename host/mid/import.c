/* Importer: reads a model with Assimp and writes MID + FED (docs/import.md).
 *
 * The scene is walked once, depth first from Assimp's root node, and each
 * item is written as soon as it is known: the camera, the lights, then one
 * polygons object per mesh a node places (its FED file and its material are
 * written when first used). Everything goes to temporary names (the MID file
 * beside its final name, the FED files and textures into a fresh folder) and
 * is renamed into place only after the last write succeeded. */
#include "host/mid/import.h"
#include "util/base/str.h"

#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <assimp/cimport.h>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "host/mid/import_internal.h"
#include "host/mid/mid_writer.h"
#include "util/base/outfile.h"
#include "util/container/hash_table.h"

/* Deepest node hierarchy walked (each level may add a matrix to a transform). */
#define TB__MAX_NODE_DEPTH 256

/* Importer name of Assimp's OBJ and glTF 2 readers (scene metadata "SourceAsset_Format"). */
#define TB__FORMAT_OBJ "Wavefront Object Importer"
#define TB__FORMAT_GLTF2 "glTF2 Importer"

/* Material states. */
enum { TB__MAT_PENDING = 0, TB__MAT_NAMED, TB__MAT_DEFAULT };

typedef struct tb__imp {
    const tb_import_opts *opts;
    tb_import_stats *stats;
    tb__import_warner warn;
    const char *model;          /* path as given */
    char *model_dir;            /* its folder ("." when none), for texture paths */
    const struct aiScene *scene;
    bool gltf;                  /* read by the glTF 2 importer */
    bool join;                  /* join equal vertex records */
    /* output */
    char *out_dir;              /* folder of the MID file ("." when none) */
    char *data_rel;             /* the data folder as the MID file refers to it: "scene.data" */
    char *data_final;           /* its path: out_dir/scene.data */
    char *tmp_dir;              /* the folder being filled, renamed to data_final at the end */
    bool tmp_moved;             /* tmp_dir has become data_final */
    tb_outfile of;              /* the MID file */
    bool of_open;
    /* per mesh: FED file number, -1 before conversion, -2 nothing to write */
    int64_t *mesh_file;
    /* per material */
    uint8_t *mat_state;         /* TB__MAT_* */
    char **mat_name;            /* MID name of named materials */
    tb_htab mat_names;          /* MID material names in use */
    tb_htab tex_src;            /* texture path as Assimp gives it -> 1 + index in tex_ref (0: failed) */
    tb_htab tex_files;          /* file names used in the data folder */
    char **tex_ref;             /* file("...") text of each texture written */
    size_t ntex, ctex;
    size_t nmat;                /* entries of mat_state and mat_name */
    tb__import_reround rr;      /* text formats: the file's coordinates */
    uint32_t nfiles;            /* FED files written */
} tb__imp;

/* ------------------------------------------------------------------- strings */

static char *tb__printf(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
static char *tb__printf(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    if (n < 0)
        return NULL;
    char *s = malloc((size_t)n + 1);
    if (!s)
        return NULL;
    va_start(ap, fmt);
    vsnprintf(s, (size_t)n + 1, fmt, ap);
    va_end(ap);
    return s;
}

/* Length of the valid UTF-8 sequence at s (1..4), or 0 (MID's rules: no
 * overlong forms, no surrogates, at most U+10FFFF). */
static int tb__utf8_len(const unsigned char *s)
{
    unsigned c = s[0];
    if (c < 0x80)
        return 1;
    int n = c >= 0xF0 ? 4 : c >= 0xE0 ? 3 : c >= 0xC2 ? 2 : 0;
    if (n == 0 || c > 0xF4)
        return 0;
    unsigned cp = c & (0x7F >> n);
    for (int i = 1; i < n; i++) {
        if ((s[i] & 0xC0) != 0x80)
            return 0;
        cp = cp << 6 | (s[i] & 0x3F);
    }
    if ((n == 3 && cp < 0x800) || (n == 4 && (cp < 0x10000 || cp > 0x10FFFF)) || (cp >= 0xD800 && cp <= 0xDFFF))
        return 0;
    return n;
}

static bool tb__utf8_valid(const char *s)
{
    const unsigned char *p = (const unsigned char *)s;
    while (*p) {
        int n = tb__utf8_len(p);
        if (!n)
            return false;
        p += n;
    }
    return true;
}

/* A copy of s with every byte that is not part of valid UTF-8 replaced by
 * '?' (MID strings are UTF-8; names in older files are often Latin-1). */
static char *tb__utf8_clean(const char *s)
{
    char *d = tb_strdup(s);
    if (!d)
        return NULL;
    unsigned char *p = (unsigned char *)d;
    while (*p) {
        int n = tb__utf8_len(p);
        if (n)
            p += n;
        else
            *p++ = '?';
    }
    return d;
}

static char *tb__dirname(const char *path)
{
    const char *slash = strrchr(path, '/');
    if (!slash)
        return tb_strdup(".");
    if (slash == path)
        return tb_strdup("/");
    size_t n = (size_t)(slash - path);
    char *d = malloc(n + 1);
    if (d) {
        memcpy(d, path, n);
        d[n] = '\0';
    }
    return d;
}

static const char *tb__basename(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

char *tb_import_data_dir(const char *out_mid)
{
    size_t n = strlen(out_mid);
    if (n > 4 && strcmp(out_mid + n - 4, ".mid") == 0)
        n -= 4;
    char *d = malloc(n + 6);
    if (!d) {
        tb_error(TB_ERR_NOMEM, "out of memory");
        return NULL;
    }
    memcpy(d, out_mid, n);
    memcpy(d + n, ".data", 6);
    return d;
}

/* --------------------------------------------------------------------- files */

/* Removes `path` and, for a folder, everything in it. */
static void tb__remove_tree(const char *path)
{
    struct stat sb;
    if (lstat(path, &sb) != 0)
        return;
    if (S_ISDIR(sb.st_mode)) {
        DIR *d = opendir(path);
        if (d) {
            struct dirent *e;
            while ((e = readdir(d))) {
                if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
                    continue;
                char *sub = tb__printf("%s/%s", path, e->d_name);
                if (sub)
                    tb__remove_tree(sub);
                free(sub);
            }
            closedir(d);
        }
        rmdir(path);
    } else
        unlink(path);
}

/* Copies the file `src` to `dst` (a new file in the temporary folder). */
static tb_status tb__copy_file(const char *src, const char *dst)
{
    FILE *in = fopen(src, "rb");
    if (!in)
        return tb_error(TB_ERR_IO, "%s: %s", src, strerror(errno));
    FILE *out = fopen(dst, "wb");
    if (!out) {
        tb_status st = tb_error(TB_ERR_IO, "%s: %s", dst, strerror(errno));
        fclose(in);
        return st;
    }
    char buf[65536];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, in)) > 0)
        if (fwrite(buf, 1, n, out) != n)
            break;
    bool bad_in = ferror(in), bad_out = ferror(out);
    fclose(in);
    if (fclose(out) != 0)
        bad_out = true;
    if (bad_in)
        return tb_error(TB_ERR_IO, "%s: read error", src);
    if (bad_out)
        return tb_error(TB_ERR_IO, "%s: write error", dst);
    return TB_OK;
}

static tb_status tb__write_bytes(const char *dst, const void *data, size_t n)
{
    FILE *out = fopen(dst, "wb");
    if (!out)
        return tb_error(TB_ERR_IO, "%s: %s", dst, strerror(errno));
    bool bad = fwrite(data, 1, n, out) != n;
    if (fclose(out) != 0)
        bad = true;
    return bad ? tb_error(TB_ERR_IO, "%s: write error", dst) : TB_OK;
}

/* ------------------------------------------------------------------ warnings */

#define tb__warn(im, ...) tb__import_warn(&(im)->warn, __VA_ARGS__)

/* ------------------------------------------------------------------ textures */

static bool tb__ends_with_ci(const char *s, const char *end)
{
    size_t n = strlen(s), m = strlen(end);
    if (n < m)
        return false;
    for (size_t i = 0; i < m; i++)
        if (tolower((unsigned char)s[n - m + i]) != end[i])
            return false;
    return true;
}

/* A file name in the data folder not used yet, from `want` ("a.png", "a-2.png", ...). */
static char *tb__unique_file(tb__imp *im, const char *want)
{
    char *name = tb_strdup(want);
    const char *dot = strrchr(want, '.');
    size_t stem = dot && dot != want ? (size_t)(dot - want) : strlen(want);
    for (int k = 2; name && tb_htab_get_str(&im->tex_files, name, NULL); k++) {
        free(name);
        name = tb__printf("%.*s-%d%s", (int)stem, want, k, want + stem);
    }
    if (name && tb_htab_put_str(&im->tex_files, name, 1)) {
        free(name);
        return NULL;
    }
    return name;
}

/* The file("...") text of texture `src` (Assimp's path) used by material
 * `label`, copying or extracting it into the data folder on first use; NULL
 * (after a warning) if it cannot be found. Errors: TB_ERR_IO, TB_ERR_NOMEM. */
static tb_status tb__texture(tb__imp *im, const char *src, const char *label, const char **ref)
{
    *ref = NULL;
    uint64_t slot;
    if (tb_htab_get_str(&im->tex_src, src, &slot)) {
        *ref = slot ? im->tex_ref[slot - 1] : NULL;
        return TB_OK;
    }
    char *want = NULL, *from = NULL;
    const struct aiTexture *emb = NULL;
    tb_status st = TB_OK;
    if (src[0] == '*') { /* embedded: "*N" */
        char *end;
        unsigned long i = strtoul(src + 1, &end, 10);
        if (*end || i >= im->scene->mNumTextures) {
            tb__warn(im, "material '%s': embedded texture '%s' does not exist: left out", label, src);
            goto remember;
        }
        emb = im->scene->mTextures[i];
        if (emb->mHeight != 0) {
            tb__warn(im, "material '%s': embedded texture '%s' is uncompressed pixel data, which is not exported: "
                         "left out", label, src);
            goto remember;
        }
        char hint[sizeof emb->achFormatHint + 1];
        size_t k = 0;
        for (size_t j = 0; j < sizeof emb->achFormatHint && emb->achFormatHint[j]; j++)
            if (isalnum((unsigned char)emb->achFormatHint[j]))
                hint[k++] = (char)tolower((unsigned char)emb->achFormatHint[j]);
        hint[k] = '\0';
        want = tb__printf("texture-%lu.%s", i, k ? hint : "bin");
    } else {
        char *p = tb_strdup(src);
        if (!p)
            return tb_error(TB_ERR_NOMEM, "out of memory");
        for (char *q = p; *q; q++)
            if (*q == '\\')
                *q = '/'; /* Windows separators, common in MTL files */
        from = p[0] == '/' ? tb_strdup(p) : tb__printf("%s/%s", im->model_dir, p);
        free(p);
        if (!from)
            return tb_error(TB_ERR_NOMEM, "out of memory");
        struct stat sb;
        if (stat(from, &sb) != 0 || !S_ISREG(sb.st_mode)) {
            tb__warn(im, "material '%s': texture '%s' not found (%s): left out", label, src, from);
            goto remember;
        }
        want = tb__utf8_clean(tb__basename(from));
    }
    if (!want) {
        st = tb_error(TB_ERR_NOMEM, "out of memory");
        goto out;
    }
    char *name = tb__unique_file(im, want);
    char *path = name ? tb__printf("%s/%s", im->tmp_dir, name) : NULL;
    char *text = name ? tb__printf("%s/%s", im->data_rel, name) : NULL;
    if (!name || !path || !text || (im->ntex == im->ctex && !(im->ctex = im->ctex ? 2 * im->ctex : 8))) {
        free(name), free(path), free(text);
        st = tb_error(TB_ERR_NOMEM, "out of memory");
        goto out;
    }
    char **grown = realloc(im->tex_ref, im->ctex * sizeof *grown);
    if (!grown) {
        free(name), free(path), free(text);
        st = tb_error(TB_ERR_NOMEM, "out of memory");
        goto out;
    }
    im->tex_ref = grown;
    st = emb ? tb__write_bytes(path, emb->pcData, emb->mWidth) : tb__copy_file(from, path);
    if (!st && !(tb__ends_with_ci(name, ".png") || tb__ends_with_ci(name, ".exr") ||
                 tb__ends_with_ci(name, ".pfm") || tb__ends_with_ci(name, ".rle")))
        tb__warn(im, "material '%s': texture '%s' is not PNG, OpenEXR, PFM or RLE, which util/image reads: "
                     "copied and referenced anyway", label, name);
    free(name), free(path);
    if (st) {
        free(text);
        goto out;
    }
    im->tex_ref[im->ntex++] = text;
    im->stats->textures++;
    *ref = text;
remember:
    if (tb_htab_put_str(&im->tex_src, src, *ref ? im->ntex : 0))
        st = tb_error(TB_ERR_NOMEM, "out of memory");
out:
    free(want), free(from);
    return st;
}

/* ----------------------------------------------------------------- materials */

static void tb__material_label(const struct aiMaterial *am, char *buf, size_t n, unsigned idx)
{
    struct aiString s;
    if (aiGetMaterialString(am, AI_MATKEY_NAME, &s) == aiReturn_SUCCESS && s.length > 0)
        snprintf(buf, n, "%s", s.data);
    else
        snprintf(buf, n, "material-%u", idx);
}

/* True for the materials Assimp makes up when the source has none
 * (docs/import.md: such meshes get MID's default material). */
static bool tb__is_default_material(const tb__imp *im, unsigned idx)
{
    const struct aiMaterial *am = im->scene->mMaterials[idx];
    struct aiString s;
    bool named = aiGetMaterialString(am, AI_MATKEY_NAME, &s) == aiReturn_SUCCESS && s.length > 0;
    if (named && strcmp(s.data, AI_DEFAULT_MATERIAL_NAME) == 0)
        return true;
    if (im->gltf) /* the glTF 2 importer appends its default material last */
        return idx + 1 == im->scene->mNumMaterials;
    return !named;
}

/* Writes material `idx` on first use; *name is its MID name, NULL for the default. */
static tb_status tb__material(tb__imp *im, unsigned idx, const char **name)
{
    *name = NULL;
    if (idx >= im->scene->mNumMaterials)
        return TB_OK;
    if (im->mat_state[idx] == TB__MAT_PENDING) {
        if (tb__is_default_material(im, idx)) {
            im->mat_state[idx] = TB__MAT_DEFAULT;
            return TB_OK;
        }
        const struct aiMaterial *am = im->scene->mMaterials[idx];
        char raw[1100];
        tb__material_label(am, raw, sizeof raw, idx);
        char *label = tb__utf8_clean(raw);
        if (!label)
            return tb_error(TB_ERR_NOMEM, "out of memory");
        char *unique = tb_strdup(label);
        for (int k = 2; unique && tb_htab_get_str(&im->mat_names, unique, NULL); k++) {
            free(unique);
            unique = tb__printf("%s #%d", label, k);
        }
        tb__import_material *mm = malloc(sizeof *mm);
        if (!unique || !mm || tb_htab_put_str(&im->mat_names, unique, idx)) {
            free(label), free(unique), free(mm);
            return tb_error(TB_ERR_NOMEM, "out of memory");
        }
        tb__import_map_material(am, label, &im->warn, mm);
        static const unsigned bits[TB__TEX_COUNT] = {TB_MID_SET_DIFFUSE_TEXTURE, TB_MID_SET_SPECULAR_TEXTURE,
                                                     TB_MID_SET_EMISSION_TEXTURE};
        tb_mid_ref *slots[TB__TEX_COUNT] = {&mm->mat.diffuse_texture, &mm->mat.specular_texture,
                                            &mm->mat.emission_texture};
        tb_status st = TB_OK;
        for (int t = 0; t < TB__TEX_COUNT && !st; t++) {
            if (!mm->tex[t][0])
                continue;
            const char *ref;
            st = tb__texture(im, mm->tex[t], label, &ref);
            if (!st && ref) {
                slots[t]->text = slots[t]->path = ref;
                mm->mat.set |= bits[t];
            }
        }
        if (!st) {
            mm->mat.name = unique;
            tb_mid_item item = {.type = TB_MID_ITEM_MATERIAL, .material = &mm->mat};
            st = tb_mid_write_item(im->of.fp, &item);
        }
        free(label), free(mm);
        if (st) {
            free(unique);
            return st;
        }
        im->mat_name[idx] = unique;
        im->mat_state[idx] = TB__MAT_NAMED;
        im->stats->materials++;
    }
    *name = im->mat_state[idx] == TB__MAT_NAMED ? im->mat_name[idx] : NULL;
    return TB_OK;
}

/* -------------------------------------------------------------- transforms */

/* Exactly the identity (-0 counts as 0: it changes nothing either). */
static bool tb__is_identity(const struct aiMatrix4x4 *m)
{
    return m->a1 == 1 && m->a2 == 0 && m->a3 == 0 && m->a4 == 0 && m->b1 == 0 && m->b2 == 1 && m->b3 == 0 &&
           m->b4 == 0 && m->c1 == 0 && m->c2 == 0 && m->c3 == 1 && m->c4 == 0 && m->d1 == 0 && m->d2 == 0 &&
           m->d3 == 0 && m->d4 == 1;
}

/* The MID matrix operation of an Assimp matrix (both row-major, column vectors). */
static tb_mid_op tb__matrix_op(const struct aiMatrix4x4 *m)
{
    tb_mid_op op = {.kind = TB_MID_MATRIX,
                    .v = {m->a1, m->a2, m->a3, m->a4, m->b1, m->b2, m->b3, m->b4, m->c1, m->c2, m->c3, m->c4, m->d1,
                          m->d2, m->d3, m->d4}};
    return op;
}

/* The transform of node `n` to the world as MID operations (innermost
 * first, identities left out) into ops[0..*nops). */
static tb_status tb__node_ops(const struct aiNode *n, tb_mid_op *ops, int *nops)
{
    int k = 0;
    for (const struct aiNode *p = n; p; p = p->mParent) {
        if (k == TB__MAX_NODE_DEPTH)
            return tb_error(TB_ERR_UNSUPPORTED, "node hierarchy deeper than %d levels", TB__MAX_NODE_DEPTH);
        if (!tb__is_identity(&p->mTransformation))
            ops[k++] = tb__matrix_op(&p->mTransformation);
    }
    *nops = k;
    return TB_OK;
}

static const struct aiNode *tb__find_node(const struct aiNode *n, const char *name, int depth)
{
    if (!n || depth > TB__MAX_NODE_DEPTH)
        return NULL;
    if (strcmp(n->mName.data, name) == 0)
        return n;
    for (unsigned i = 0; i < n->mNumChildren; i++) {
        const struct aiNode *f = tb__find_node(n->mChildren[i], name, depth + 1);
        if (f)
            return f;
    }
    return NULL;
}

/* ----------------------------------------------------------- camera, lights */

static tb_status tb__cameras(tb__imp *im)
{
    bool done = false;
    for (unsigned i = 0; i < im->scene->mNumCameras; i++) {
        const struct aiCamera *ac = im->scene->mCameras[i];
        char *label = tb__utf8_clean(ac->mName.data);
        if (!label)
            return tb_error(TB_ERR_NOMEM, "out of memory");
        if (done) {
            tb__warn(im, "camera '%s': MID has one camera; only the first is imported", label);
            free(label);
            continue;
        }
        double world[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
        const struct aiNode *n = tb__find_node(im->scene->mRootNode, ac->mName.data, 0);
        for (; n; n = n->mParent) { /* world = parent ... node, in double */
            tb_mid_op op = tb__matrix_op(&n->mTransformation);
            double r[16];
            for (int a = 0; a < 4; a++)
                for (int b = 0; b < 4; b++) {
                    double s = 0;
                    for (int c = 0; c < 4; c++)
                        s += op.v[a * 4 + c] * world[c * 4 + b];
                    r[a * 4 + b] = s;
                }
            memcpy(world, r, sizeof r);
        }
        tb_mid_camera cam;
        if (tb__import_map_camera(ac, world, im->gltf, label, &im->warn, &cam)) {
            cam.name = label;
            tb_mid_item item = {.type = TB_MID_ITEM_CAMERA, .camera = &cam};
            tb_status st = tb_mid_write_item(im->of.fp, &item);
            if (st) {
                free(label);
                return st;
            }
            done = true;
            im->stats->cameras = 1;
        }
        free(label);
    }
    return TB_OK;
}

static tb_status tb__lights(tb__imp *im)
{
    tb_mid_op *ops = malloc(TB__MAX_NODE_DEPTH * sizeof *ops);
    if (!ops)
        return tb_error(TB_ERR_NOMEM, "out of memory");
    tb_status st = TB_OK;
    for (unsigned i = 0; i < im->scene->mNumLights && !st; i++) {
        const struct aiLight *al = im->scene->mLights[i];
        char *label = tb__utf8_clean(al->mName.data);
        if (!label) {
            st = tb_error(TB_ERR_NOMEM, "out of memory");
            break;
        }
        const struct aiNode *n = tb__find_node(im->scene->mRootNode, al->mName.data, 0);
        int nops = 0;
        tb_transform xf;
        tb_mid_light li;
        if (n && n->mMetaData) {
            for (unsigned k = 0; k < n->mMetaData->mNumProperties; k++)
                if (strcmp(n->mMetaData->mKeys[k].data, "PBR_LightRange") == 0)
                    tb__warn(im, "light '%s': glTF range ignored (MID lights fall off as 1/r^2 without a cut-off)",
                             label);
        }
        if (n && tb__node_ops(n, ops, &nops))
            tb__warn(im, "light '%s': %s: skipped", label, tb_last_error());
        else if (tb_mid_ops_transform(ops, nops, &xf, NULL))
            tb__warn(im, "light '%s': its node's transform is not usable in MID (%s): skipped", label,
                     tb_last_error());
        else if (tb__import_map_light(al, im->gltf, label, &im->warn, &li)) {
            li.name = label;
            li.nops = nops;
            li.ops = ops;
            li.to_world = xf;
            tb_mid_item item = {.type = TB_MID_ITEM_LIGHT, .light = &li};
            st = tb_mid_write_item(im->of.fp, &item);
            if (!st)
                im->stats->lights++;
        }
        free(label);
    }
    free(ops);
    return st;
}

/* ------------------------------------------------------------------- meshes */

/* Converts and writes mesh `idx` on first use; *file is its FED file
 * number, or -2 when it has nothing to write. */
static tb_status tb__mesh(tb__imp *im, unsigned idx, const char *label, int64_t *file)
{
    if (im->mesh_file[idx] != -1) {
        *file = im->mesh_file[idx];
        return TB_OK;
    }
    const struct aiMesh *m = im->scene->mMeshes[idx];
    tb_fed *fed;
    tb__import_mesh_report rep;
    tb_status st = tb__import_mesh_fed(m, im->join, &im->rr, &fed, &rep);
    if (st)
        return tb_error_context(st, "%s: mesh '%s'", im->model, label);
    uint64_t skipped = (uint64_t)rep.points_lines + rep.degenerate + rep.nonfinite;
    im->stats->skipped_faces += skipped;
    if (rep.points_lines)
        tb__warn(im, "mesh '%s': %u points or lines left out (MID polygons need 3 corners or more)", label,
                 rep.points_lines);
    if (rep.degenerate)
        tb__warn(im, "mesh '%s': %u degenerate polygons (zero area or fewer than 3 distinct corners) left out, "
                     "the first is face %u", label, rep.degenerate, rep.first_dropped);
    if (rep.nonfinite)
        tb__warn(im, "mesh '%s': %u polygons with a NaN or infinite vertex position left out", label,
                 rep.nonfinite);
    if (rep.collapsed)
        tb__warn(im, "mesh '%s': %u polygon corners at the same position as the previous corner merged", label,
                 rep.collapsed);
    if (rep.normals_dropped)
        tb__warn(im, "mesh '%s': some normals are NaN or infinite: no normals written", label);
    if (rep.uvs_dropped)
        tb__warn(im, "mesh '%s': some (u,v) are NaN or infinite: no (u,v) written", label);
    if (!fed) {
        tb__warn(im, "mesh '%s': no polygons to write: left out", label);
        im->mesh_file[idx] = *file = -2;
        return TB_OK;
    }
    uint32_t n = im->nfiles;
    const char *ext = im->opts->binary_fed ? "fedb" : "fed";
    char *path = tb__printf("%s/mesh-%u.%s", im->tmp_dir, n, ext);
    if (!path) {
        tb_fed_free(fed);
        return tb_error(TB_ERR_NOMEM, "out of memory");
    }
    st = tb_fed_write_file(path, fed, im->opts->binary_fed ? TB_FED_FORMAT_BINARY : TB_FED_FORMAT_TEXT);
    if (!st) {
        im->nfiles++;
        im->stats->fed_files++;
        im->stats->vertices += fed->nverts;
        im->stats->faces += fed->nfaces;
        im->mesh_file[idx] = *file = n;
    }
    tb_fed_free(fed);
    free(path);
    return st;
}

/* The objects of node `n` (one per mesh), then its children's, depth first. */
static tb_status tb__node(tb__imp *im, const struct aiNode *n, int depth, tb_mid_op *ops)
{
    if (depth >= TB__MAX_NODE_DEPTH)
        return tb_error(TB_ERR_UNSUPPORTED, "%s: node hierarchy deeper than %d levels", im->model,
                        TB__MAX_NODE_DEPTH);
    tb_status st = TB_OK;
    if (n->mNumMeshes > 0) {
        char *node_name = tb__utf8_clean(n->mName.data);
        if (!node_name)
            return tb_error(TB_ERR_NOMEM, "out of memory");
        int nops = 0;
        tb_transform xf = tb_transform_identity();
        unsigned nmeshes = n->mNumMeshes;
        st = tb__node_ops(n, ops, &nops);
        if (!st && tb_mid_ops_transform(ops, nops, &xf, NULL)) {
            tb__warn(im, "node '%s': its transform is not usable in MID (%s): its %u meshes are left out", node_name,
                     tb_last_error(), n->mNumMeshes);
            nmeshes = 0;
        }
        for (unsigned i = 0; i < nmeshes && !st; i++) {
            unsigned idx = n->mMeshes[i];
            if (idx >= im->scene->mNumMeshes)
                continue;
            const struct aiMesh *m = im->scene->mMeshes[idx];
            char *mesh_name = tb__utf8_clean(m->mName.data);
            char *name = !mesh_name                                              ? NULL
                         : n->mNumMeshes > 1 && mesh_name[0] && strcmp(mesh_name, node_name) != 0
                             ? tb__printf("%s/%s", node_name, mesh_name)
                             : tb_strdup(node_name[0] ? node_name : mesh_name);
            if (!name) {
                free(mesh_name);
                st = tb_error(TB_ERR_NOMEM, "out of memory");
                break;
            }
            int64_t file = -2;
            const char *mat = NULL;
            st = tb__mesh(im, idx, name, &file);
            if (!st && file >= 0)
                st = tb__material(im, m->mMaterialIndex, &mat);
            if (!st && file >= 0) {
                char *ref = tb__printf("%s/mesh-%u.%s", im->data_rel, (unsigned)file,
                                       im->opts->binary_fed ? "fedb" : "fed");
                if (!ref)
                    st = tb_error(TB_ERR_NOMEM, "out of memory");
                else {
                    tb_mid_object o = {.kind = TB_PRIM_POLYGONS, .name = name[0] ? name : NULL, .nops = nops,
                                       .ops = ops, .to_world = xf};
                    o.geom.polygons.mesh = (tb_mid_ref){ref, ref};
                    o.material = tb_mid_material_default();
                    o.material.base = mat;
                    tb_mid_item item = {.type = TB_MID_ITEM_OBJECT, .object = &o};
                    st = tb_mid_write_item(im->of.fp, &item);
                    if (!st)
                        im->stats->objects++;
                    free(ref);
                }
            }
            free(name), free(mesh_name);
        }
        free(node_name);
        if (st)
            return st;
    }
    for (unsigned i = 0; i < n->mNumChildren && !st; i++)
        if (n->mChildren[i])
            st = tb__node(im, n->mChildren[i], depth + 1, ops);
    return st;
}

/* -------------------------------------------------------------------- import */

static const char *tb__scene_format(const struct aiScene *s)
{
    const struct aiMetadata *md = s->mMetaData;
    for (unsigned i = 0; md && i < md->mNumProperties; i++)
        if (strcmp(md->mKeys[i].data, "SourceAsset_Format") == 0 && md->mValues[i].mType == AI_AISTRING)
            return ((const struct aiString *)md->mValues[i].mData)->data;
    return "";
}

/* Which text format `model` is, for re-rounding its coordinates; -1 for
 * binary files and other formats. */
static int tb__text_kind(const char *model, const char *format)
{
    if (strcmp(format, TB__FORMAT_OBJ) == 0)
        return TB__TEXT_OBJ;
    bool ply = strcmp(format, "Stanford Polygon Library (PLY) Importer") == 0;
    bool stl = strcmp(format, "Stereolithography (STL) Importer") == 0;
    if (!ply && !stl)
        return -1;
    FILE *f = fopen(model, "rb");
    if (!f)
        return -1;
    char head[256] = {0};
    size_t n = fread(head, 1, sizeof head - 1, f);
    int kind = -1;
    if (ply && n > 4 && strstr(head, "format ascii"))
        kind = TB__TEXT_PLY;
    else if (stl && n >= 84 && strncmp(head, "solid", 5) == 0) {
        /* Binary STL files may start with "solid" too; their size gives them away. */
        uint32_t count;
        memcpy(&count, head + 80, 4);
        struct stat sb;
        if (fstat(fileno(f), &sb) == 0 && (uint64_t)sb.st_size != 84 + 50 * (uint64_t)count)
            kind = TB__TEXT_STL;
    } else if (stl && n >= 5 && n < 84 && strncmp(head, "solid", 5) == 0)
        kind = TB__TEXT_STL;
    fclose(f);
    return kind;
}

/* Moves the finished data folder and MID file into place; an existing data
 * folder is replaced (moved aside first, removed last). */
static tb_status tb__commit(tb__imp *im)
{
    char *old = NULL;
    struct stat sb;
    if (lstat(im->data_final, &sb) == 0) {
        if (!S_ISDIR(sb.st_mode))
            return tb_error(TB_ERR_IO, "%s exists and is not a folder: not replaced", im->data_final);
        old = tb__printf("%s/.%s.old.XXXXXX", im->out_dir, tb__basename(im->data_final));
        if (!old)
            return tb_error(TB_ERR_NOMEM, "out of memory");
        if (!mkdtemp(old) || rename(im->data_final, old) != 0) {
            tb_status st = tb_error(TB_ERR_IO, "%s: cannot move the old folder aside: %s", im->data_final,
                                    strerror(errno));
            rmdir(old);
            free(old);
            return st;
        }
    }
    if (rename(im->tmp_dir, im->data_final) != 0) {
        tb_status st = tb_error(TB_ERR_IO, "%s: cannot rename the new folder into place: %s", im->data_final,
                                strerror(errno));
        if (old && rename(old, im->data_final) != 0)
            tb__remove_tree(old);
        free(old);
        return st;
    }
    im->tmp_moved = true;
    im->of_open = false;
    tb_status st = tb_outfile_commit(&im->of);
    if (st) {
        tb__remove_tree(im->data_final);
        if (old && rename(old, im->data_final) != 0)
            tb__remove_tree(old);
    } else if (old)
        tb__remove_tree(old);
    free(old);
    return st;
}

static tb_status tb__run(tb__imp *im, const char *out_mid)
{
    /* The model must be a readable file before Assimp sees it: its messages
     * for a missing file are vague. */
    struct stat sb;
    if (stat(im->model, &sb) != 0)
        return tb_error(errno == ENOENT ? TB_ERR_NOT_FOUND : TB_ERR_IO, "%s: %s", im->model, strerror(errno));
    if (!S_ISREG(sb.st_mode))
        return tb_error(TB_ERR_IO, "%s: not a regular file", im->model);
    FILE *probe = fopen(im->model, "rb");
    if (!probe)
        return tb_error(TB_ERR_IO, "%s: %s", im->model, strerror(errno));
    fclose(probe);

    im->model_dir = tb__dirname(im->model);
    im->out_dir = tb__dirname(out_mid);
    im->data_final = tb_import_data_dir(out_mid);
    if (!im->model_dir || !im->out_dir || !im->data_final)
        return tb_error(TB_ERR_NOMEM, "out of memory");
    im->data_rel = tb_strdup(tb__basename(im->data_final));
    if (!im->data_rel)
        return tb_error(TB_ERR_NOMEM, "out of memory");
    if (!tb__utf8_valid(im->data_rel) || strpbrk(im->data_rel, "\"\\\n\r\t"))
        return tb_error(TB_ERR_ARG, "%s: the output's name must be valid UTF-8 without quotes, backslashes or "
                                    "control characters (MID file references are UTF-8 strings)", out_mid);

    struct aiPropertyStore *props = aiCreatePropertyStore();
    aiSetImportPropertyInteger(props, AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, 1);
    aiSetImportPropertyInteger(props, AI_CONFIG_FBX_CONVERT_TO_M, 0);
    aiSetImportPropertyInteger(props, AI_CONFIG_IMPORT_NO_SKELETON_MESHES, 1);
    unsigned flags = aiProcess_ValidateDataStructure | (im->opts->triangulate ? aiProcess_Triangulate : 0);
    im->scene = aiImportFileExWithProperties(im->model, flags, NULL, props);
    aiReleasePropertyStore(props);
    if (!im->scene) {
        const char *why = aiGetErrorString();
        return tb_error(TB_ERR_FORMAT, "%s: Assimp cannot read it: %s", im->model, why && *why ? why : "no reason given");
    }
    const struct aiScene *s = im->scene;
    tb_status st;
    if (s->mFlags & AI_SCENE_FLAGS_INCOMPLETE)
        return tb_error(TB_ERR_FORMAT, "%s: Assimp read only part of it (incomplete scene)", im->model);
    if (!s->mRootNode)
        return tb_error(TB_ERR_FORMAT, "%s: Assimp gave a scene without a root node", im->model);
    if (s->mFlags & AI_SCENE_FLAGS_VALIDATION_WARNING)
        tb__warn(im, "Assimp's validation found problems in the model (run assimp info for details)");
    const char *format = tb__scene_format(s);
    size_t flen = strlen(format) < sizeof im->stats->format ? strlen(format) : sizeof im->stats->format - 1;
    memcpy(im->stats->format, format, flen);
    im->stats->format[flen] = '\0';
    im->gltf = strcmp(im->stats->format, TB__FORMAT_GLTF2) == 0;
    int text = tb__text_kind(im->model, im->stats->format);
    if (text >= 0 && (st = tb__import_reround_load(im->model, (tb__import_text_kind)text, &im->rr)))
        return st;
    im->join = im->opts->join == TB_IMPORT_JOIN_ALWAYS ||
               (im->opts->join == TB_IMPORT_JOIN_AUTO && strcmp(im->stats->format, TB__FORMAT_OBJ) == 0);

    size_t nm = s->mNumMeshes ? s->mNumMeshes : 1, nmat = s->mNumMaterials ? s->mNumMaterials : 1;
    im->mesh_file = malloc(nm * sizeof *im->mesh_file);
    im->mat_state = calloc(nmat, sizeof *im->mat_state);
    im->mat_name = calloc(nmat, sizeof *im->mat_name);
    im->nmat = nmat;
    if (!im->mesh_file || !im->mat_state || !im->mat_name)
        return tb_error(TB_ERR_NOMEM, "out of memory");
    for (size_t i = 0; i < s->mNumMeshes; i++)
        im->mesh_file[i] = -1;

    /* Output: the temporary folder, then the MID file. */
    im->tmp_dir = tb__printf("%s/.%s.XXXXXX", im->out_dir, im->data_rel);
    if (!im->tmp_dir)
        return tb_error(TB_ERR_NOMEM, "out of memory");
    if (!mkdtemp(im->tmp_dir)) {
        tb_status st = tb_error(TB_ERR_IO, "%s: cannot create a folder there: %s", im->out_dir, strerror(errno));
        free(im->tmp_dir);
        im->tmp_dir = NULL;
        return st;
    }
    mode_t mask = umask(0);
    umask(mask);
    chmod(im->tmp_dir, 0777 & ~mask);
    st = tb_outfile_open(&im->of, out_mid);
    if (st)
        return st;
    im->of_open = true;

    st = tb_mid_write_header(im->of.fp);
    if (!st)
        st = tb__cameras(im);
    if (!st)
        st = tb__lights(im);
    tb_mid_op *ops = st ? NULL : malloc(TB__MAX_NODE_DEPTH * sizeof *ops);
    if (!st && !ops)
        st = tb_error(TB_ERR_NOMEM, "out of memory");
    if (!st)
        st = tb__node(im, s->mRootNode, 0, ops);
    free(ops);
    if (st)
        return st;
    im->stats->rerounded = im->rr.changed;
    im->stats->undecided = im->rr.undecided;
    if (im->rr.undecided)
        tb__warn(im, "%llu coordinates Assimp read are no number of the file's vertex lines and cannot be matched "
                     "to exactly one: kept as Assimp read them",
                 (unsigned long long)im->rr.undecided);
    uint32_t unplaced = 0;
    for (size_t i = 0; i < s->mNumMeshes; i++)
        unplaced += im->mesh_file[i] == -1;
    if (unplaced)
        tb__warn(im, "%u of %u meshes are not placed by any node: left out", unplaced, s->mNumMeshes);
    if (im->stats->objects == 0)
        return tb_error(TB_ERR_NOT_FOUND, "%s: nothing to import: no polygons (%u meshes%s)", im->model,
                        s->mNumMeshes, s->mNumMeshes ? ", only points, lines or degenerate faces" : "");
    return tb__commit(im);
}

tb_status tb_import(const char *model, const char *out_mid, const tb_import_opts *opts, tb_import_stats *stats)
{
    static const tb_import_opts defaults = {0};
    tb_import_stats local;
    tb__imp im = {.opts = opts ? opts : &defaults, .stats = stats ? stats : &local, .model = model};
    memset(im.stats, 0, sizeof *im.stats);
    im.warn.fn = im.opts->warn;
    im.warn.user = im.opts->warn_user;
    tb_htab_init(&im.mat_names, TB_HTAB_STR);
    tb_htab_init(&im.tex_src, TB_HTAB_STR);
    tb_htab_init(&im.tex_files, TB_HTAB_STR);

    tb_status st = !model || !*model || !out_mid || !*out_mid
                       ? tb_error(TB_ERR_ARG, "tb_import: empty model or output name")
                       : tb__run(&im, out_mid);

    if (im.of_open)
        tb_outfile_abort(&im.of);
    if (im.tmp_dir && !im.tmp_moved)
        tb__remove_tree(im.tmp_dir);
    if (im.scene)
        aiReleaseImport(im.scene);
    for (size_t i = 0; im.mat_name && i < im.nmat; i++)
        free(im.mat_name[i]);
    im.stats->warnings = im.warn.count;
    free(im.model_dir), free(im.out_dir), free(im.data_rel), free(im.data_final), free(im.tmp_dir);
    free(im.mesh_file), free(im.mat_state);
    free(im.mat_name);
    for (size_t i = 0; i < im.ntex; i++)
        free(im.tex_ref[i]);
    free(im.tex_ref);
    tb_htab_free(&im.mat_names);
    tb_htab_free(&im.tex_src);
    tb_htab_free(&im.tex_files);
    tb__import_reround_free(&im.rr);
    return st;
}
