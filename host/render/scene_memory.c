/* Memory accounting of a loaded scene and the prediction behind
 * --memory-budget (docs/performance.md, "Scale"; docs/rendering.md,
 * "Memory"). Bytes are the sizes the loader asks malloc for plus
 * TB_SCENE_MALLOC_OVERHEAD per allocation (glibc's chunk header and
 * rounding), so they track the resident size of the scene's heap. */
#include "host/render/scene.h"

#include <string.h>

#include "host/render/scene_internal.h"
#include "util/mesh/fed.h"

/* Bytes of one allocation of n bytes (0 for none). */
static size_t tb__alloc(size_t n) { return n ? n + TB_SCENE_MALLOC_OVERHEAD : 0; }

/* Bytes of a triangulated mesh (tb_object_mesh and its arrays). */
static size_t tb__mesh_bytes(const tb_object_mesh *m)
{
    if (!m)
        return 0;
    size_t nv = m->nvertices, nt = m->ntris;
    return tb__alloc(sizeof *m) + tb__alloc(nv * sizeof(tb_vec3)) + tb__alloc(nv * 3 * sizeof(double)) +
           tb__alloc(nt * 3 * sizeof(uint32_t)) + tb__alloc(nt * sizeof(uint32_t)) +
           tb__alloc(nt * sizeof(tb_vec3)) + (m->tri_uv ? tb__alloc(nt * 6 * sizeof(float)) : 0) +
           tb__alloc((size_t)m->nnodes * sizeof(tb_object_bvh_node));
}

/* Bytes a node owns besides its own struct (which its parent's array or the
 * top-level allocation holds), children included; a polygons node's mesh
 * goes to *mesh, everything else to the return value. */
static size_t tb__node_bytes(const tb_object *o, size_t *mesh)
{
    size_t n = o->name ? tb__alloc(strlen(o->name) + 1) : 0;
    n += tb__alloc((size_t)o->nprofile * 2 * sizeof(double));
    if (o->kind == TB_PRIM_PRISM)
        n += tb__alloc((size_t)o->geom.prism.nprofile * sizeof(tb_vec2));
    if (o->kind == TB_PRIM_POLYGONS) {
        const tb_geom_polygons *g = &o->geom.polygons;
        size_t m = 0;
        if (!o->fed_shared) { /* a shared file's arrays are counted once, in fed_bytes */
            size_t nv = (size_t)g->nvertices, nidx = g->face_start ? (size_t)g->face_start[g->nfaces] : 0;
            m += tb__alloc(nv * sizeof(tb_vec3)) + (g->normals ? tb__alloc(nv * sizeof(tb_vec3)) : 0) +
                 (g->uvs ? tb__alloc(nv * sizeof(tb_vec2)) : 0) +
                 tb__alloc(((size_t)g->nfaces + 1) * sizeof(int)) + tb__alloc(nidx * sizeof(int));
        }
        if (o->mesh_file.text)
            n += tb__alloc(strlen(o->mesh_file.text) + 1);
        if (o->mesh_file.path)
            n += tb__alloc(strlen(o->mesh_file.path) + 1);
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
    m->materials = tb__alloc((size_t)s->nmaterials * sizeof(tb_material));
    m->emitters = tb__alloc((size_t)s->nemitters * sizeof(tb_emitter)) +
                  tb__alloc((size_t)s->nemissive * sizeof(tb_scene_emissive));
    m->lights = tb__alloc((size_t)s->nlights * sizeof(tb_light));
    m->prims = tb__alloc(s->nprims * sizeof(tb_accel_prim));
    if (s->accel) {
        tb_accel_stats as;
        tb_accel_get_stats(s->accel, &as);
        m->accel = as.memory_bytes;
    }
    m->total = m->objects + m->meshes + m->fed + m->materials + m->emitters + m->lights + m->prims + m->accel;
    m->triangles = s->stats.triangles;
    /* Each reference's share: its record and the structure over all of them. */
    double per_ref = s->nprims ? (double)(m->prims + m->accel) / (double)s->nprims : 0.0;
    m->per_object = m->nobjects ? ((double)m->objects + per_ref * (double)whole) / (double)m->nobjects : 0.0;
    m->per_triangle = m->triangles ? ((double)m->meshes + per_ref * (double)(s->nprims - whole)) / (double)m->triangles
                                   : 0.0;
}
