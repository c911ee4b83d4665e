/* Memory accounting of a loaded scene and the prediction behind
 * --memory-budget (docs/performance.md, "Scale"; docs/rendering.md,
 * "Memory"). Bytes are the sizes the loader asks malloc for plus
 * TB_SCENE_MALLOC_OVERHEAD per allocation (glibc's chunk header and
 * rounding), so they track the resident size of the scene's heap. */
#include "host/render/scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "host/mid/mid_reader.h"
#include "host/render/emit_surface.h"
#include "host/render/scene_internal.h"
#include "util/container/hash_table.h"
#include "util/mesh/fed.h"

/* Bytes of one allocation of n bytes (0 for none). */
static size_t tb__alloc(size_t n) { return n ? n + TB_SCENE_MALLOC_OVERHEAD : 0; }

/* Bytes of a triangulated mesh (tb_object_mesh and its arrays; its object-space
 * vertices are the geometry's, counted with it). */
static size_t tb__mesh_bytes(const tb_object_mesh *m)
{
    if (!m)
        return 0;
    size_t nv = m->nvertices, nt = m->ntris;
    return tb__alloc(sizeof *m) + tb__alloc(nv * 3 * sizeof(double)) + tb__alloc(nt * 3 * sizeof(uint32_t)) +
           tb__alloc(nt * sizeof(uint32_t)) + (m->tri_uv ? tb__alloc(nt * 6 * sizeof(float)) : 0) +
           tb__alloc(nt * sizeof(tb_vec3)) +
           tb__alloc((size_t)m->nnodes * sizeof(tb_object_bvh_node));
}

/* Bytes a node owns besides its own struct (which its parent's array or the
 * top-level allocation holds), children included; a polygons node's mesh
 * goes to *mesh, everything else to the return value. */
static size_t tb__node_bytes(const tb_object *o, size_t *mesh)
{
    size_t n = o->name ? tb__alloc(strlen(o->name) + 1) : 0;
    if (o->kind == TB_PRIM_PRISM)
        n += tb__alloc((size_t)o->nprofile * 2 * sizeof(double)) +
             tb__alloc((size_t)o->geom.prism.nprofile * sizeof(tb_vec2));
    if (o->kind == TB_PRIM_POLYGONS) {
        const tb_geom_polygons *g = &o->geom.polygons;
        size_t m = 0;
        if (!o->fed || !o->fed->shared) { /* a shared file's arrays are counted once, in fed_bytes */
            size_t nv = (size_t)g->nvertices, nidx = g->face_start ? (size_t)g->face_start[g->nfaces] : 0;
            m += tb__alloc(nv * sizeof(tb_vec3)) + (g->normals ? tb__alloc(nv * sizeof(tb_vec3)) : 0) +
                 (g->uvs ? tb__alloc(nv * sizeof(tb_vec2)) : 0) +
                 tb__alloc(((size_t)g->nfaces + 1) * sizeof(int)) + tb__alloc(nidx * sizeof(int));
        }
        if (o->fed) {
            n += tb__alloc(sizeof *o->fed);
            if (o->fed->file.text)
                n += tb__alloc(strlen(o->fed->file.text) + 1);
            if (o->fed->file.path)
                n += tb__alloc(strlen(o->fed->file.path) + 1);
        }
        *mesh += m + tb__mesh_bytes(o->mesh);
    }
    if (o->nchildren) {
        n += tb__alloc((size_t)o->nchildren * sizeof(tb_object));
        for (int i = 0; i < o->nchildren; i++)
            n += tb__node_bytes(&o->children[i], mesh);
    }
    return n;
}

void tb_scene_memory(const tb_scene *s, tb_scene_memory_use *m)
{
    memset(m, 0, sizeof *m);
    if (!s)
        return;
    size_t whole = 0; /* acceleration references that stand for whole objects */
    for (uint32_t i = 0; i < s->nobjects; i++) {
        const tb_object *o = s->objects[i];
        size_t mesh = 0, own = tb__alloc(sizeof *o) + sizeof(tb_object *) + tb__node_bytes(o, &mesh);
        if (o->kind == TB_PRIM_POLYGONS && o->mesh) {
            m->meshes += own + mesh;
        } else {
            m->objects += own + mesh; /* (a CSG tree's polygons leaves: their meshes go with the object) */
            m->nobjects++;
            whole++;
        }
    }
    m->fed = s->stats.fed_bytes;
    size_t npats = s->nmaterials > 0; /* the shared pattern of kind NONE, then each material's own */
    for (int i = 0; i < s->nmaterials; i++)
        npats += (s->materials[i].diffuse_pattern->kind != TB_MID_PATTERN_NONE) +
                 (s->materials[i].specular_pattern->kind != TB_MID_PATTERN_NONE) +
                 (s->materials[i].bump->kind != TB_MID_PATTERN_NONE);
    m->materials = tb__alloc((size_t)s->nmaterials * sizeof(tb_material)) + tb__alloc(npats * sizeof(tb_material_pattern));
    m->emitters = tb__alloc((size_t)s->nemitters * sizeof(tb_emitter)) +
                  tb__alloc((size_t)s->nemissive * sizeof(tb_scene_emissive));
    for (int i = 0; i < s->nemitters; i++)
        if (tb_emitter_is_surface(&s->emitters[i]))
            m->emitters += tb_surface_emitter_bytes(s->emitters[i].ctx, TB_SCENE_MALLOC_OVERHEAD);
    m->lights = tb__alloc((size_t)s->nlights * sizeof(tb_light));
    m->prims = s->prims ? tb__alloc(s->nprims * sizeof(tb_accel_prim)) : 0; /* dropped once the structure is built */
    size_t tri_only = 0; /* held for the triangle references alone */
    if (s->accel) {
        tb_accel_stats as;
        tb_accel_get_stats(s->accel, &as);
        m->accel = as.memory_bytes;
        tri_only = as.tri_bytes;
    }
    m->total = m->objects + m->meshes + m->fed + m->materials + m->emitters + m->lights + m->prims + m->accel;
    m->triangles = s->stats.triangles;
    /* Each reference's share of the structure over all of them; the
     * triangle records and packed corners go to the triangles alone. */
    double per_ref = s->nprims ? (double)(m->prims + m->accel - tri_only) / (double)s->nprims : 0.0;
    m->per_object = m->nobjects ? ((double)m->objects + per_ref * (double)whole) / (double)m->nobjects : 0.0;
    m->per_triangle = m->triangles ? ((double)m->meshes + (double)tri_only + per_ref * (double)(s->nprims - whole)) /
                                         (double)m->triangles
                                   : 0.0;
}

size_t tb__scene_object_bytes(const tb_object *o)
{
    size_t mesh = 0, n = tb__alloc(sizeof *o) + tb__node_bytes(o, &mesh);
    return n + mesh;
}

/* ------------------------------------------------------------------ prediction */

/* TB__SCENE_BUILD_PER_REF (scene_internal.h): the reference (32), the
 * triangle record the build copies (80, kept by the BVH for every
 * reference), and the binary and 8-wide BVH nodes (measured with
 * tb_scene_memory: 200 to 300 bytes per reference on the generated grid). */
/* A FED file's triangles, estimated from its size when only the size is known. */
#define TB__PRED_FED_BYTES_PER_TRI 24

/* Adds the prediction for object node `m` (and its children). */
static void tb__predict_node(const tb_mid_object *m, tb_scene_memory_use *u, size_t *refs, bool top,
                             size_t *fedsize, size_t *feds_seen_n, char ***feds_seen)
{
    size_t n = top ? tb__alloc(sizeof(tb_object)) + 2 * sizeof(tb_object *) : 0;
    if (m->name)
        n += tb__alloc(strlen(m->name) + 1);
    if (m->kind == TB_PRIM_PRISM)
        n += tb__alloc((size_t)m->geom.prism.nprofile * sizeof(tb_vec2)) +
             tb__alloc((size_t)(m->geom.prism.nprofile ? m->geom.prism.nprofile : m->geom.prism.sides) * 16);
    if (m->kind == TB_PRIM_POLYGONS) {
        const tb_geom_polygons *g = &m->geom.polygons;
        size_t nv = 0, nt = 0, geom = 0;
        if (g->mesh.text) {
            const char *path = g->mesh.path ? g->mesh.path : g->mesh.text;
            struct stat sb;
            size_t size = stat(path, &sb) == 0 ? (size_t)sb.st_size : 0;
            nt = size / TB__PRED_FED_BYTES_PER_TRI;
            nv = nt / 2 + 3;
            bool seen = false;
            for (size_t i = 0; i < *feds_seen_n && !seen; i++)
                seen = strcmp((*feds_seen)[i], path) == 0;
            if (!seen) {
                char **q = realloc(*feds_seen, (*feds_seen_n + 1) * sizeof *q);
                if (q) {
                    *feds_seen = q;
                    if ((q[*feds_seen_n] = strdup(path)) != NULL)
                        ++*feds_seen_n;
                }
                *fedsize += 12 * size; /* the mesh with its edges and adjacency, and the inline form */
            }
        } else {
            nv = (size_t)g->nvertices;
            for (int f = 0; f < g->nfaces; f++)
                nt += (size_t)(g->face_start[f + 1] - g->face_start[f] - 2);
            geom = tb__alloc(nv * sizeof(tb_vec3)) + (g->normals ? tb__alloc(nv * sizeof(tb_vec3)) : 0) +
                   (g->uvs ? tb__alloc(nv * sizeof(tb_vec2)) : 0) + tb__alloc(((size_t)g->nfaces + 1) * sizeof(int)) +
                   tb__alloc((size_t)g->face_start[g->nfaces] * sizeof(int));
        }
        /* The triangulated mesh as tb__mesh_bytes counts it, with one BVH node per triangle (an upper bound). */
        size_t mesh = geom + tb__alloc(sizeof(tb_object_mesh)) + tb__alloc(nv * 3 * sizeof(double)) +
                      tb__alloc(nt * 3 * sizeof(uint32_t)) + tb__alloc(nt * sizeof(uint32_t)) +
                      (g->uvs ? 0 : tb__alloc(nt * 6 * sizeof(float))) + tb__alloc(nt * sizeof(tb_vec3)) +
                      tb__alloc(nt * sizeof(tb_object_bvh_node));
        if (top) {
            u->meshes += n + mesh;
            u->triangles += nt;
            *refs += nt;
            return;
        }
        n += mesh;
    }
    if (m->nchildren)
        n += tb__alloc((size_t)m->nchildren * sizeof(tb_object));
    u->objects += n;
    for (int i = 0; i < m->nchildren; i++)
        tb__predict_node(&m->children[i], u, refs, false, fedsize, feds_seen_n, feds_seen);
    if (top) {
        u->nobjects++;
        ++*refs;
    }
}

/* True if any node of m emits. */
static bool tb__mid_emits(const tb_mid_object *m)
{
    if (!tb_prim_is_csg(m->kind))
        return tb_mid_material_emits(&m->material);
    for (int i = 0; i < m->nchildren; i++)
        if (tb__mid_emits(&m->children[i]))
            return true;
    return false;
}

tb_status tb_scene_predict_memory(const char *path, tb_scene_memory_use *u)
{
    memset(u, 0, sizeof *u);
    tb_mid_reader *r;
    tb_status st = tb_mid_reader_open(&r, path);
    if (st)
        return st;
    size_t refs = 0, fedsize = 0, nfeds = 0, nemitters = 0, nemissive = 0, tables = 0;
    char **feds = NULL;
    tb_htab mats;
    tb_htab_init(&mats, TB_HTAB_U64);
    tb_mid_item it;
    while (!st && !(st = tb_mid_reader_next(r, &it)) && it.type != TB_MID_ITEM_END) {
        if (it.type == TB_MID_ITEM_LIGHT) {
            u->lights += sizeof(tb_light);
            continue;
        }
        if (it.type != TB_MID_ITEM_OBJECT)
            continue;
        const tb_mid_object *m = it.object;
        tb__predict_node(m, u, &refs, true, &fedsize, &nfeds, &feds);
        st = tb__scene_predict_materials(m, &mats);
        if (!st && tb__mid_emits(m)) {
            /* Emitters: counted on the object itself (tessellated emitters
             * depend on its shape), which is then freed. */
            tb_object *o;
            int k = 0;
            if (tb_object_from_mid(m, 0, NULL, NULL, &o) == TB_OK) {
                st = tb__scene_leaf_emitters(o, tb_channels_splat(3, 0.0f), false, NULL, &k, &tables);
                tb_object_free(o);
            } else {
                tb_clear_error(); /* the load will report it, located */
            }
            nemitters += (size_t)k;
            nemissive++;
        }
    }
    tb_mid_reader_close(r);
    size_t nmats = mats.count;
    tb_htab_free(&mats);
    for (size_t i = 0; i < nfeds; i++)
        free(feds[i]);
    free(feds);
    if (st)
        return st;
    u->fed = fedsize;
    /* The material table and the copies kept until colours are converted. */
    u->materials = nmats * (tb__alloc(sizeof(tb_material)) + 1024);
    /* The scene's emitters (the renderers' area light reads them in place,
     * tb_area_light_init_shared) and the light's areas and selection table. */
    u->emitters = tb__alloc(nemitters * (sizeof(tb_emitter) + 3 * sizeof(double))) +
                  tb__alloc(nemissive * sizeof(tb_scene_emissive)) + tables;
    u->prims = tb__alloc(refs * sizeof(tb_accel_prim));
    u->accel = refs * (TB__SCENE_BUILD_PER_REF - sizeof(tb_accel_prim));
    u->total = u->objects + u->meshes + u->fed + u->materials + u->emitters + u->lights + u->prims + u->accel;
    double per_ref = refs ? (double)(u->prims + u->accel) / (double)refs : 0.0;
    u->per_object = u->nobjects ? (double)u->objects / (double)u->nobjects + per_ref : 0.0;
    u->per_triangle = u->triangles ? (double)u->meshes / (double)u->triangles + per_ref : 0.0;
    return TB_OK;
}

/* Appends "name X MiB" parts, largest first, to buf. */
void tb__scene_memory_describe(const tb_scene_memory_use *u, char *buf, size_t len)
{
    struct {
        const char *name;
        size_t bytes;
    } part[7] = {{"objects", u->objects}, {"meshes", u->meshes}, {"FED files", u->fed},
                 {"materials", u->materials}, {"emitters", u->emitters}, {"lights", u->lights},
                 {"acceleration", u->prims + u->accel}};
    for (int i = 1; i < 7; i++)
        for (int j = i; j > 0 && part[j].bytes > part[j - 1].bytes; j--) {
            __typeof__(part[0]) t = part[j];
            part[j] = part[j - 1];
            part[j - 1] = t;
        }
    size_t n = 0;
    buf[0] = 0;
    for (int i = 0; i < 7 && n < len; i++) {
        if (!part[i].bytes)
            continue;
        n += (size_t)snprintf(buf + n, len - n, "%s%s %.1f MiB", n ? ", " : "", part[i].name,
                              (double)part[i].bytes / 1048576.0);
        if (n < len && strcmp(part[i].name, "objects") == 0 && u->nobjects)
            n += (size_t)snprintf(buf + n, len - n, " (%zu objects, %.0f bytes each)", u->nobjects,
                                  (double)part[i].bytes / (double)u->nobjects);
        else if (n < len && strcmp(part[i].name, "meshes") == 0 && u->triangles)
            n += (size_t)snprintf(buf + n, len - n, " (%llu triangles, %.0f bytes each)",
                                  (unsigned long long)u->triangles, (double)part[i].bytes / (double)u->triangles);
    }
}

size_t tb_scene_available_memory(void)
{
    FILE *f = fopen("/proc/meminfo", "r");
    if (!f)
        return 0;
    char line[256];
    size_t kb = 0;
    while (fgets(line, sizeof line, f))
        if (sscanf(line, "MemAvailable: %zu kB", &kb) == 1)
            break;
    fclose(f);
    return kb * 1024;
}
