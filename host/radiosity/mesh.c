/* Radiosity meshes: a scene's objects polygonized in world space and meshed
 * into elements (docs/radiosity.md, "Meshing"). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "host/object/object.h"
#include "host/object/polygonize.h"
#include "host/radiosity/patches_internal.h"
#include "host/radiosity/radiosity.h"
#include "util/mesh/mesh.h"

/* Relative planarity tolerance of the faces meshed into grids. */
#define TB__RAD_PLANAR_TOL 1e-2

/* Corners whose element normals are within this angle share a vertex. */
#define TB__RAD_CREASE_COS 0.8660254037844387 /* cos 30 degrees */

void tb_rad_mesh_init(tb_rad_mesh *m)
{
    memset(m, 0, sizeof *m);
}

void tb_rad_mesh_free(tb_rad_mesh *m)
{
    if (!m)
        return;
    free(m->verts);
    free(m->elems);
    free(m->rho);
    free(m->emission);
    free(m->patch);
    free(m->patch_poly);
    int nc = m->nchannels;
    bool sp = m->spectral;
    tb_bands b = m->bands;
    tb_rad_mesh_init(m);
    m->nchannels = nc, m->spectral = sp, m->bands = b;
}

/* Newell normal (unnormalized, twice the area vector) and area centroid of
 * a planar polygon, in double. */
static void tb__poly_frame(const tb_vec3 *v, int n, double nrm[3], double c[3])
{
    nrm[0] = nrm[1] = nrm[2] = 0.0;
    for (int k = 0; k < n; k++) {
        const tb_vec3 a = v[k], b = v[(k + 1) % n];
        nrm[0] += ((double)a.y - b.y) * ((double)a.z + b.z);
        nrm[1] += ((double)a.z - b.z) * ((double)a.x + b.x);
        nrm[2] += ((double)a.x - b.x) * ((double)a.y + b.y);
    }
    /* area centroid: fan of triangles from corner 0 */
    double sw = 0.0;
    c[0] = c[1] = c[2] = 0.0;
    for (int k = 1; k + 1 < n; k++) {
        double e1[3] = {(double)v[k].x - v[0].x, (double)v[k].y - v[0].y, (double)v[k].z - v[0].z};
        double e2[3] = {(double)v[k + 1].x - v[0].x, (double)v[k + 1].y - v[0].y, (double)v[k + 1].z - v[0].z};
        double cr[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        double w = sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
        c[0] += w * ((double)v[0].x + v[k].x + v[k + 1].x) / 3.0;
        c[1] += w * ((double)v[0].y + v[k].y + v[k + 1].y) / 3.0;
        c[2] += w * ((double)v[0].z + v[k].z + v[k + 1].z) / 3.0;
        sw += w;
    }
    if (sw > 0.0)
        c[0] /= sw, c[1] /= sw, c[2] /= sw;
}

tb_status tb_rad_mesh_update_geometry(tb_rad_mesh *m)
{
    for (size_t i = 0; i < m->nelems; i++) {
        tb_rad_element *e = &m->elems[i];
        int n = e->v[3] == TB_RAD_NONE ? 3 : 4;
        tb_vec3 p[4];
        for (int k = 0; k < n; k++) {
            if (e->v[k] >= m->nverts)
                return tb_error(TB_ERR_ARG, "radiosity mesh: element %zu: vertex index %u out of range", i, e->v[k]);
            p[k] = m->verts[e->v[k]].p;
        }
        double nrm[3], c[3];
        tb__poly_frame(p, n, nrm, c);
        double len = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
        if (!(len > 0.0) || !isfinite(len))
            return tb_error(TB_ERR_ARG, "radiosity mesh: element %zu is degenerate", i);
        e->area = 0.5 * len;
        e->normal = tb_vec3_make((float)(nrm[0] / len), (float)(nrm[1] / len), (float)(nrm[2] / len));
        e->centroid = tb_vec3_make((float)c[0], (float)c[1], (float)c[2]);
    }
    return TB_OK;
}

void tb_rad_mesh_polygon(const tb_rad_mesh *m, size_t i, tb_ff_polygon *out)
{
    const tb_rad_element *e = &m->elems[i];
    out->n = e->v[3] == TB_RAD_NONE ? 3 : 4;
    for (int k = 0; k < TB_FF_MAX_VERTS; k++)
        out->v[k] = k < out->n ? m->verts[e->v[k]].p : tb_vec3_splat(0.0f);
}

/* Growable output arrays. */
typedef struct tb__mb {
    tb_rad_mesh *m;
    size_t vcap, ecap;
    bool patches;       /* two levels: m->patch grows with the elements */
    size_t pcap;        /* of m->patch_poly */
} tb__mb;

static tb_status tb__push_vert(tb__mb *b, tb_rad_vertex v)
{
    if (b->m->nverts == b->vcap) {
        size_t cap = b->vcap ? 2 * b->vcap : 1024;
        tb_rad_vertex *p = realloc(b->m->verts, cap * sizeof *p);
        if (!p)
            return tb_error(TB_ERR_NOMEM, "radiosity mesh: out of memory");
        b->m->verts = p, b->vcap = cap;
    }
    b->m->verts[b->m->nverts++] = v;
    return TB_OK;
}

static tb_status tb__push_elem(tb__mb *b, const tb_rad_element *e, const tb_channels *rho, const tb_channels *em)
{
    tb_rad_mesh *m = b->m;
    int nc = m->nchannels;
    if (m->nelems == b->ecap) {
        size_t cap = b->ecap ? 2 * b->ecap : 1024;
        tb_rad_element *pe = realloc(m->elems, cap * sizeof *pe);
        if (pe)
            m->elems = pe;
        float *pr = realloc(m->rho, cap * (size_t)nc * sizeof *pr);
        if (pr)
            m->rho = pr;
        float *pm = realloc(m->emission, cap * (size_t)nc * sizeof *pm);
        if (pm)
            m->emission = pm;
        uint32_t *pp = b->patches ? realloc(m->patch, cap * sizeof *pp) : NULL;
        if (pp)
            m->patch = pp;
        if (!pe || !pr || !pm || (b->patches && !pp))
            return tb_error(TB_ERR_NOMEM, "radiosity mesh: out of memory");
        b->ecap = cap;
    }
    size_t i = m->nelems++;
    m->elems[i] = *e;
    for (int c = 0; c < nc; c++) {
        m->rho[i * (size_t)nc + (size_t)c] = rho->v[c];
        m->emission[i * (size_t)nc + (size_t)c] = em->v[c];
    }
    return TB_OK;
}

/* Two levels: the last element pushed lies in patch k of `pm`; the patch
 * gets the mesh's next index (and its outline) at its first element. */
static tb_status tb__push_patch(tb__mb *b, const tb_mesh *pm, uint32_t k, uint32_t *pglob)
{
    tb_rad_mesh *m = b->m;
    if (pglob[k] == TB_RAD_NONE) {
        if (m->npatches == b->pcap) {
            size_t cap = b->pcap ? 2 * b->pcap : 256;
            tb_ff_polygon *p = realloc(m->patch_poly, cap * sizeof *p);
            if (!p)
                return tb_error(TB_ERR_NOMEM, "radiosity mesh: out of memory");
            m->patch_poly = p, b->pcap = cap;
        }
        const tb_mesh_elem *pe = tb_mesh_elem_at(pm, k);
        tb_ff_polygon *poly = &m->patch_poly[m->npatches];
        poly->n = tb_mesh_elem_size(pe);
        for (int q = 0; q < poly->n; q++)
            poly->v[q] = TB_ARRAY_AT(&pm->positions, tb_vec3, pe->v[q]);
        pglob[k] = (uint32_t)m->npatches++;
    }
    m->patch[m->nelems - 1] = pglob[k];
    return TB_OK;
}

/* The material of FED face f of object o (CSG: its leaf's). */
static int tb__face_material(const tb_object *o, const tb_fed *fed, uint32_t f)
{
    if (fed->face_ids && o->nchildren > 0) {
        const tb_object *leaf = tb_object_leaf_for_face(o, (uint32_t)fed->face_ids[f], NULL);
        if (leaf && leaf->material >= 0)
            return leaf->material;
    }
    return o->material;
}

/* Meshes one object's world-space FED into the output. */
static tb_status tb__add_object(tb__mb *b, const tb_scene *s, const tb_object *o, const tb_fed *fed,
                                const tb_rad_mesh_options *opt)
{
    tb_mesh mesh;
    tb_mesh_init(&mesh);
    /* A face a little off its plane (the Cornell box's red wall: 3.2 mm over
     * 550 mm) is gridded as a bilinear patch rather than split in two
     * triangles that longest-edge bisection then refines into thousands of
     * slivers; each element is then off its own plane by only the face's
     * deviation over the number of cells (docs/radiosity.md, "Meshing"). */
    tb_mesh_opts mo = {.max_edge = opt->max_edge, .max_area = opt->max_area, .quads = true,
                       .planar_tol = TB__RAD_PLANAR_TOL};
    tb_mesh pmesh; /* two levels: the patches (each element's face is its patch there) */
    uint32_t *pglob = NULL; /* two levels: the mesh's index of each patch, TB_RAD_NONE until it has an element */
    tb_status st;
    if (b->patches) {
        tb_mesh_opts po = mo;
        po.max_edge = opt->patch_edge, po.max_area = opt->patch_area;
        st = tb__rad_mesh_two_level(fed, &po, &mo, &pmesh, &mesh);
        size_t np = tb_mesh_nelems(&pmesh);
        if (!st && !(pglob = malloc(sizeof *pglob * (np ? np : 1))))
            st = tb_error(TB_ERR_NOMEM, "radiosity mesh: out of memory");
        for (size_t k = 0; k < np && pglob; k++)
            pglob[k] = TB_RAD_NONE;
    } else {
        tb_mesh_init(&pmesh);
        st = tb_mesh_from_fed(fed, &mo, &mesh);
    }
    if (st) {
        free(pglob);
        tb_mesh_free(&pmesh);
        tb_mesh_free(&mesh);
        return st;
    }
    size_t nmv = mesh.positions.len, ne = tb_mesh_nelems(&mesh);
    bool has_n = mesh.normals.len == nmv;
    /* per mesh vertex, a chain of output vertices (one per crease side) */
    uint32_t *head = malloc((nmv ? nmv : 1) * sizeof *head);
    tb_array chain, rep, nsum; /* next index, representative normal, normal sum (area weighted) */
    tb_array_init(&chain, sizeof(uint32_t));
    tb_array_init(&rep, sizeof(tb_vec3));
    tb_array_init(&nsum, sizeof(double) * 4); /* [3]: 1 if the normal came from the surface */
    size_t vbase = b->m->nverts;
    if (!head) {
        st = tb_error(TB_ERR_NOMEM, "radiosity mesh: out of memory");
        goto done;
    }
    for (size_t k = 0; k < nmv; k++)
        head[k] = TB_RAD_NONE;
    for (size_t i = 0; i < ne && !st; i++) {
        const tb_mesh_elem *me = tb_mesh_elem_at(&mesh, i);
        int n = tb_mesh_elem_size(me);
        tb_vec3 p[4];
        for (int k = 0; k < n; k++)
            p[k] = TB_ARRAY_AT(&mesh.positions, tb_vec3, me->v[k]);
        double nrm[3], c[3];
        tb__poly_frame(p, n, nrm, c);
        double len = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
        if (!(len > 0.0))
            continue; /* a sliver below float resolution carries no energy */
        tb_vec3 en = tb_vec3_make((float)(nrm[0] / len), (float)(nrm[1] / len), (float)(nrm[2] / len));
        tb_rad_element e = {.v = {TB_RAD_NONE, TB_RAD_NONE, TB_RAD_NONE, TB_RAD_NONE},
                            .object = o->index,
                            .parent = TB_RAD_NONE};
        for (int k = 0; k < n && !st; k++) {
            uint32_t mv = me->v[k], ov = TB_RAD_NONE;
            for (uint32_t q = head[mv]; q != TB_RAD_NONE; q = TB_ARRAY_AT(&chain, uint32_t, q)) {
                if (tb_vec3_dot(TB_ARRAY_AT(&rep, tb_vec3, q), en) > TB__RAD_CREASE_COS) {
                    ov = q;
                    break;
                }
            }
            if (ov == TB_RAD_NONE) {
                ov = (uint32_t)chain.len;
                double z[4] = {0, 0, 0, 0};
                tb_rad_vertex rv = {.p = p[k], .n = en};
                if (has_n) {
                    /* the surface's own normal (curved objects), unless it is
                     * far from this side of a crease */
                    tb_vec3 vn = TB_ARRAY_AT(&mesh.normals, tb_vec3, mv);
                    float l = tb_vec3_length(vn);
                    if (l > 0.0f && tb_vec3_dot(tb_vec3_scale(vn, 1.0f / l), en) > TB__RAD_CREASE_COS)
                        rv.n = tb_vec3_scale(vn, 1.0f / l), z[3] = 1.0;
                }
                if ((st = tb_array_push(&chain, &head[mv])) || (st = tb_array_push(&rep, &en)) ||
                    (st = tb_array_push(&nsum, z)))
                    break;
                head[mv] = ov;
                if ((st = tb__push_vert(b, rv)))
                    break;
            }
            double *ns = (double *)tb_array_at(&nsum, ov);
            ns[0] += nrm[0], ns[1] += nrm[1], ns[2] += nrm[2];
            e.v[k] = (uint32_t)(vbase + ov);
        }
        if (st)
            break;
        uint32_t face = b->patches ? tb_mesh_elem_at(&pmesh, me->face)->face : me->face;
        const tb_material *mat = NULL;
        int mi = tb__face_material(o, fed, face);
        if (mi >= 0 && mi < s->nmaterials)
            mat = &s->materials[mi];
        tb_channels rho = tb_channels_splat(s->nchannels, 0.0f), em = rho;
        if (mat) {
            rho = mat->diffuse;
            em = mat->emission;
        }
        for (int ch = 0; ch < s->nchannels; ch++) {
            if (!(rho.v[ch] >= 0.0f && rho.v[ch] < 1.0f)) {
                st = tb_error(TB_ERR_UNSUPPORTED,
                              "radiosity: object %u: diffuse reflectance %g in channel %d is not in [0, 1)",
                              o->index, (double)rho.v[ch], ch);
                break;
            }
            if (!(em.v[ch] >= 0.0f) || !isfinite(em.v[ch])) {
                st = tb_error(TB_ERR_UNSUPPORTED, "radiosity: object %u: emission %g in channel %d is invalid",
                              o->index, (double)em.v[ch], ch);
                break;
            }
        }
        if (!st)
            st = tb__push_elem(b, &e, &rho, &em);
        if (!st && b->patches)
            st = tb__push_patch(b, &pmesh, me->face, pglob);
    }
    /* vertices without a surface normal take their elements' mean normal */
    for (size_t q = 0; q < chain.len && !st; q++) {
        tb_rad_vertex *rv = &b->m->verts[vbase + q];
        const double *ns = (const double *)tb_array_at(&nsum, q);
        double l = sqrt(ns[0] * ns[0] + ns[1] * ns[1] + ns[2] * ns[2]);
        if (ns[3] == 0.0 && l > 0.0)
            rv->n = tb_vec3_make((float)(ns[0] / l), (float)(ns[1] / l), (float)(ns[2] / l));
    }
done:
    free(pglob);
    tb_mesh_free(&pmesh);
    free(head);
    tb_array_free(&chain);
    tb_array_free(&rep);
    tb_array_free(&nsum);
    tb_mesh_free(&mesh);
    return st;
}

/* A copy of `fed` with positions and normals taken to world space. */
static tb_status tb__fed_to_world(const tb_fed *f, const tb_transform *t, tb_fed **out)
{
    *out = NULL;
    tb_vec3 *pos = malloc((f->nverts ? f->nverts : 1) * sizeof *pos);
    tb_vec3 *nrm = f->normals ? malloc((f->nverts ? f->nverts : 1) * sizeof *nrm) : NULL;
    uint32_t *sizes = malloc((f->nloops ? f->nloops : 1) * sizeof *sizes);
    uint32_t *nl = malloc((f->nfaces ? f->nfaces : 1) * sizeof *nl);
    tb_status st = TB_OK;
    if (!pos || (f->normals && !nrm) || !sizes || !nl) {
        st = tb_error(TB_ERR_NOMEM, "radiosity mesh: out of memory");
        goto done;
    }
    bool flip = tb_transform_swaps_handedness(t);
    for (uint32_t v = 0; v < f->nverts; v++) {
        pos[v] = tb_transform_point(t, f->positions[v]);
        if (nrm) {
            tb_vec3 n = tb_transform_normal(t, f->normals[v]);
            float l = tb_vec3_length(n);
            nrm[v] = l > 0.0f ? tb_vec3_scale(n, 1.0f / l) : n;
        }
    }
    for (uint32_t l = 0; l < f->nloops; l++)
        sizes[l] = tb_fed_loop_size(f, l);
    for (uint32_t fc = 0; fc < f->nfaces; fc++)
        nl[fc] = tb_fed_face_nloops(f, fc);
    /* a mirroring transform reverses every loop so the front stays the front */
    uint32_t *corners = malloc((f->ncorners ? f->ncorners : 1) * sizeof *corners);
    if (!corners) {
        st = tb_error(TB_ERR_NOMEM, "radiosity mesh: out of memory");
        goto done;
    }
    for (uint32_t l = 0; l < f->nloops; l++) {
        uint32_t b = f->loop_corners[l], n = sizes[l];
        for (uint32_t k = 0; k < n; k++)
            corners[b + k] = f->corner_vert[b + (flip ? n - 1 - k : k)];
    }
    tb_fed_desc d = {.nverts = f->nverts,
                     .positions = pos,
                     .normals = nrm,
                     .nfaces = f->nfaces,
                     .face_nloops = nl,
                     .nloops = f->nloops,
                     .loop_sizes = sizes,
                     .corners = corners,
                     .face_ids = f->face_ids};
    st = tb_fed_build(&d, out, NULL);
    free(corners);
done:
    free(pos);
    free(nrm);
    free(sizes);
    free(nl);
    return st;
}

/* The inline polygons of `obj` as a world-space FED, one face per polygon. */
static tb_status tb__polygons_world(const tb_object *obj, tb_fed **out)
{
    const tb_geom_polygons *g = &obj->geom.polygons;
    *out = NULL;
    size_t nv = (size_t)g->nvertices, nf = (size_t)g->nfaces, ncorn = (size_t)g->face_start[g->nfaces];
    tb_vec3 *pos = malloc((nv ? nv : 1) * sizeof *pos);
    tb_vec3 *nrm = g->normals ? malloc((nv ? nv : 1) * sizeof *nrm) : NULL;
    uint32_t *sizes = malloc((nf ? nf : 1) * sizeof *sizes);
    uint32_t *corners = malloc((ncorn ? ncorn : 1) * sizeof *corners);
    int32_t *ids = malloc((nf ? nf : 1) * sizeof *ids);
    tb_status st = TB_OK;
    if (!pos || (g->normals && !nrm) || !sizes || !corners || !ids) {
        st = tb_error(TB_ERR_NOMEM, "radiosity mesh: out of memory");
        goto done;
    }
    bool flip = tb_transform_swaps_handedness(&obj->to_world);
    for (size_t v = 0; v < nv; v++) {
        pos[v] = tb_transform_point(&obj->to_world, g->vertices[v]);
        if (nrm) {
            tb_vec3 n = tb_transform_normal(&obj->to_world, g->normals[v]);
            float l = tb_vec3_length(n);
            nrm[v] = l > 0.0f ? tb_vec3_scale(n, 1.0f / l) : n;
        }
    }
    for (size_t f = 0; f < nf; f++) {
        int b = g->face_start[f], n = g->face_start[f + 1] - b;
        sizes[f] = (uint32_t)n;
        ids[f] = (int32_t)f;
        for (int k = 0; k < n; k++)
            corners[b + k] = (uint32_t)g->indices[b + (flip ? n - 1 - k : k)];
    }
    tb_fed_desc d = {.nverts = (uint32_t)nv,
                     .positions = pos,
                     .normals = nrm,
                     .nfaces = (uint32_t)nf,
                     .nloops = (uint32_t)nf,
                     .loop_sizes = sizes,
                     .corners = corners,
                     .face_ids = ids};
    st = tb_fed_build(&d, out, NULL);
done:
    free(pos);
    free(nrm);
    free(sizes);
    free(corners);
    free(ids);
    return st;
}

tb_rad_mesh_options tb_rad_default_mesh_options(const tb_scene *scene)
{
    tb_rad_mesh_options o = {.max_angle = TB_POLY_DEFAULT_ANGLE};
    tb_vec3 ext = tb_vec3_sub(scene->bounds.hi, scene->bounds.lo);
    double diag = tb_vec3_length(ext);
    if (ext.x >= 0 && ext.y >= 0 && ext.z >= 0 && isfinite(diag) && diag > 0.0)
        o.max_edge = diag / TB_RAD_DEFAULT_EDGE_DIVISIONS;
    return o;
}

tb_status tb_rad_mesh_from_scene(const tb_scene *scene, const tb_rad_mesh_options *opt, tb_rad_mesh *out)
{
    tb_rad_mesh_options o = {0};
    if (opt)
        o = *opt;
    if (!(o.max_edge >= 0.0) || !(o.max_area >= 0.0) || !(o.max_angle >= 0.0) || !isfinite(o.max_edge) ||
        !isfinite(o.max_area) || !isfinite(o.max_angle))
        return tb_error(TB_ERR_ARG, "radiosity mesh: max edge, area and angle must be finite and >= 0");
    if (!(o.patch_edge >= 0.0) || !(o.patch_area >= 0.0) || !isfinite(o.patch_edge) || !isfinite(o.patch_area))
        return tb_error(TB_ERR_ARG, "radiosity mesh: patch edge and area must be finite and >= 0");
    bool patches = o.patch_edge > 0.0 || o.patch_area > 0.0;
    if (patches) {
        /* the edge bounds the mesher applies: min(edge, sqrt(area)) */
        double le = o.max_edge > 0.0 ? o.max_edge : INFINITY, lp = o.patch_edge > 0.0 ? o.patch_edge : INFINITY;
        if (o.max_area > 0.0)
            le = fmin(le, sqrt(o.max_area));
        if (o.patch_area > 0.0)
            lp = fmin(lp, sqrt(o.patch_area));
        if (!isfinite(le))
            return tb_error(TB_ERR_ARG, "radiosity mesh: patches need an element size (max edge or area)");
        if (lp < le)
            return tb_error(TB_ERR_ARG, "radiosity mesh: patches (edge %g) must not be smaller than elements (edge %g)",
                            lp, le);
    }
    tb_rad_mesh_init(out);
    out->nchannels = scene->nchannels;
    out->spectral = scene->spectral;
    out->bands = scene->bands;
    tb__mb b = {.m = out, .patches = patches};
    /* CSG boundary resolution: the element size, but never coarser than
     * 1/50 of the scene (elements of 1/24 of it, the command's default, lost
     * the showcase's small CSG pieces that faces-whole meshing kept) */
    tb_vec3 ext = tb_vec3_sub(scene->bounds.hi, scene->bounds.lo);
    double diag = tb_vec3_length(ext);
    double csg_edge = o.max_edge > 0.0 ? o.max_edge : (o.max_area > 0 ? sqrt(o.max_area) : diag / 50.0);
    if (diag / 50.0 > 0.0 && isfinite(diag))
        csg_edge = fmin(csg_edge, diag / 50.0);
    if (!(csg_edge > 0.0))
        csg_edge = 1.0;
    tb_status st = TB_OK;
    for (uint32_t i = 0; i < scene->nobjects && !st; i++) {
        const tb_object *obj = scene->objects[i];
        tb_fed *fed = NULL;
        if (obj->kind == TB_PRIM_POLYGONS && obj->fed) {
            st = tb__fed_to_world(obj->fed->fed, &obj->to_world, &fed);
        } else if (obj->kind == TB_PRIM_POLYGONS) {
            /* inline polygons keep their faces whole (quads stay quads; the
             * polygonizer would triangulate them): the element mesher
             * subdivides them */
            st = tb__polygons_world(obj, &fed);
        } else {
            tb_poly_options po = {.max_edge = o.max_edge, .max_angle = o.max_angle, .split = true};
            st = tb_polygonize_object(obj, &po, csg_edge, &fed);
        }
        if (!st)
            st = tb__add_object(&b, scene, obj, fed, &o);
        if (st)
            st = tb_error_context(st, "radiosity mesh: object %u%s%s", i, obj->name ? " " : "",
                                  obj->name ? obj->name : "");
        tb_fed_free(fed);
    }
    if (!st && out->nelems == 0)
        st = tb_error(TB_ERR_ARG, "radiosity mesh: the scene has no surfaces");
    if (!st)
        st = tb_rad_mesh_update_geometry(out);
    if (st)
        tb_rad_mesh_free(out);
    return st;
}

/* One distinct plane of the mesh and whether every vertex is on its front. */
typedef struct tb__plane {
    double n[3], d; /* n . x = d */
    bool enclosing;
} tb__plane;

/* Most plane x vertex tests tb_rad_mesh_occluders makes before it gives up
 * and keeps every element. */
#define TB__RAD_ENCLOSURE_WORK 50000000.0

static inline int tb__elem_nv(const tb_rad_element *e) { return e->v[3] == TB_RAD_NONE ? 3 : 4; }

static inline double tb__rad_coord(tb_vec3 p, int a) { return a == 0 ? p.x : a == 1 ? p.y : p.z; }

/* Elements a and b in one plane (normals within 1.4e-3 rad of each other, b's
 * centroid within eps of a's plane): float normals of one face's elements
 * differ in the last bits. */
static bool tb__rad_coplanar(const tb_rad_element *a, const tb_rad_element *b, double eps)
{
    if (!((double)tb_vec3_dot(a->normal, b->normal) >= 1.0 - 1e-6))
        return false;
    tb_vec3 d = tb_vec3_sub(b->centroid, a->centroid);
    return fabs((double)tb_vec3_dot(d, a->normal)) <= eps;
}

/* The convex hull of the corners of elements idx[0..n) (one plane), when
 * it is a triangle or quad whose area is the elements' total (so they tile
 * it): written to *out, counter-clockwise seen from the elements' front. */
static bool tb__rad_merge_face(const tb_rad_mesh *m, const uint32_t *idx, size_t n, tb_ff_polygon *out)
{
    const tb_rad_element *e0 = &m->elems[idx[0]];
    /* project on the plane: drop the normal's largest axis */
    double an[3] = {fabs(e0->normal.x), fabs(e0->normal.y), fabs(e0->normal.z)};
    int ax = an[0] >= an[1] && an[0] >= an[2] ? 0 : an[1] >= an[2] ? 1 : 2;
    int u = (ax + 1) % 3, w = (ax + 2) % 3;
    size_t np = 0;
    double total = 0.0;
    for (size_t k = 0; k < n; k++)
        np += (size_t)tb__elem_nv(&m->elems[idx[k]]), total += m->elems[idx[k]].area;
    uint32_t *pv = malloc(2 * np * sizeof *pv);
    if (!pv)
        return false;
    np = 0;
    for (size_t k = 0; k < n; k++)
        for (int c = 0; c < tb__elem_nv(&m->elems[idx[k]]); c++)
            pv[np++] = m->elems[idx[k]].v[c];
    /* sort by (u, w) (insertion sort: the groups are small) */
#define TB__C(v, a) tb__rad_coord(m->verts[(v)].p, (a))
    for (size_t k = 1; k < np; k++) {
        uint32_t x = pv[k];
        size_t j = k;
        while (j > 0 && (TB__C(pv[j - 1], u) > TB__C(x, u) ||
                         (TB__C(pv[j - 1], u) == TB__C(x, u) && TB__C(pv[j - 1], w) > TB__C(x, w))))
            pv[j] = pv[j - 1], j--;
        pv[j] = x;
    }
    double lo[2] = {TB__C(pv[0], u), TB__C(pv[0], w)}, hi[2] = {lo[0], lo[1]};
    for (size_t k = 1; k < np; k++) {
        lo[0] = fmin(lo[0], TB__C(pv[k], u)), hi[0] = fmax(hi[0], TB__C(pv[k], u));
        lo[1] = fmin(lo[1], TB__C(pv[k], w)), hi[1] = fmax(hi[1], TB__C(pv[k], w));
    }
    double size = fmax(hi[0] - lo[0], hi[1] - lo[1]), tol = 1e-6 * size * size;
    /* Andrew's monotone chain; nearly collinear corners (the grid's points
     * along a side, off the line by float rounding) are dropped */
    uint32_t *h = pv + np;
    size_t nh = 0;
    for (int pass = 0; pass < 2; pass++) {
        size_t base = nh;
        for (size_t q = 0; q < np; q++) {
            uint32_t c = pass ? pv[np - 1 - q] : pv[q];
            while (nh >= base + 2) {
                uint32_t a = h[nh - 2], b = h[nh - 1];
                double cr = (TB__C(b, u) - TB__C(a, u)) * (TB__C(c, w) - TB__C(a, w)) -
                            (TB__C(b, w) - TB__C(a, w)) * (TB__C(c, u) - TB__C(a, u));
                if (cr > tol)
                    break;
                nh--;
            }
            h[nh++] = c;
        }
        nh--; /* the last point starts the other chain */
    }
#undef TB__C
    bool ok = nh >= 3 && nh <= TB_FF_MAX_VERTS;
    if (ok) {
        out->n = (int)nh;
        for (size_t k = 0; k < nh; k++)
            out->v[k] = m->verts[h[k]].p;
        tb_vec3 nn;
        double area;
        tb_ff_polygon_frame(out, &nn, &area);
        ok = fabs(area - total) <= 1e-5 * total;
        /* and truly flat: a twisted surface (the Cornell box's red wall) is
         * left as its elements, whose receivers would otherwise end up behind
         * (or in front of) the flattened face */
        for (size_t k = 0; k < np && ok; k++) {
            tb_vec3 a = out->v[0], b = m->verts[pv[k]].p;
            double dd = nn.x * ((double)b.x - a.x) + nn.y * ((double)b.y - a.y) + nn.z * ((double)b.z - a.z);
            ok = fabs(dd) <= 1e-6 * size;
        }
        if (ok && tb_vec3_dot(nn, e0->normal) < 0.0f)
            for (size_t k = 0; k < nh / 2; k++) {
                tb_vec3 t = out->v[k];
                out->v[k] = out->v[nh - 1 - k], out->v[nh - 1 - k] = t;
            }
    }
    free(pv);
    return ok;
}

size_t tb_rad_mesh_occluders(const tb_rad_mesh *m, tb_ff_polygon *out)
{
    size_t ne = m->nelems, nv = m->nverts, nout = 0;
    /* scene size, for the tolerance */
    tb_vec3 lo = m->verts[0].p, hi = lo;
    for (size_t v = 1; v < nv; v++)
        lo = tb_vec3_min(lo, m->verts[v].p), hi = tb_vec3_max(hi, m->verts[v].p);
    double eps = 1e-6 * (double)tb_vec3_length(tb_vec3_sub(hi, lo));
    /* distinct planes (elements of one face share theirs): keyed by the exact
     * float normal and the rounded offset, found by a linear scan that stops
     * being worth it for curved meshes, where the work bound below bails out */
    tb__plane *pl = malloc((ne ? ne : 1) * sizeof *pl);
    uint32_t *of = malloc((ne ? ne : 1) * sizeof *of);
    size_t np = 0;
    bool ok = pl && of;
    for (size_t i = 0; i < ne && ok; i++) {
        const tb_rad_element *e = &m->elems[i];
        double n[3] = {e->normal.x, e->normal.y, e->normal.z};
        double d = n[0] * e->centroid.x + n[1] * e->centroid.y + n[2] * e->centroid.z;
        size_t k = np;
        for (size_t q = np; q-- > 0 && np - q <= 64;) /* recent planes: the same face's elements are consecutive */
            if (pl[q].n[0] == n[0] && pl[q].n[1] == n[1] && pl[q].n[2] == n[2] && fabs(pl[q].d - d) <= eps) {
                k = q;
                break;
            }
        if (k == np) {
            if ((double)(np + 1) * (double)nv > TB__RAD_ENCLOSURE_WORK) {
                ok = false;
                break;
            }
            pl[np].n[0] = n[0], pl[np].n[1] = n[1], pl[np].n[2] = n[2], pl[np].d = d, pl[np].enclosing = true;
            np++;
        }
        of[i] = (uint32_t)k;
    }
    if (ok)
        for (size_t q = 0; q < np; q++)
            for (size_t v = 0; v < nv && pl[q].enclosing; v++) {
                tb_vec3 p = m->verts[v].p;
                if (pl[q].n[0] * p.x + pl[q].n[1] * p.y + pl[q].n[2] * p.z < pl[q].d - eps)
                    pl[q].enclosing = false;
            }
    if (!ok) {
        for (size_t i = 0; i < ne; i++)
            tb_rad_mesh_polygon(m, i, &out[nout++]);
        free(pl);
        free(of);
        return nout;
    }
    /* The kept elements of one object in one plane usually tile one convex
     * face (a block's side cut into a grid): that face occludes exactly what
     * its elements do, and one quad instead of dozens makes the visibility
     * tree several levels shallower. Groups that do not tile a convex
     * triangle or quad stay as their elements. */
    uint32_t *idx = malloc((ne ? ne : 1) * sizeof *idx);
    bool *done = calloc(ne ? ne : 1, sizeof *done);
    if (!idx || !done) {
        for (size_t i = 0; i < ne; i++)
            if (!pl[of[i]].enclosing)
                tb_rad_mesh_polygon(m, i, &out[nout++]);
    } else {
        for (size_t i = 0; i < ne; i++) {
            if (done[i] || pl[of[i]].enclosing)
                continue;
            size_t ng = 0;
            for (size_t j = i; j < ne; j++)
                if (!done[j] && !pl[of[j]].enclosing && m->elems[j].object == m->elems[i].object &&
                    tb__rad_coplanar(&m->elems[i], &m->elems[j], eps))
                    idx[ng++] = (uint32_t)j, done[j] = true;
            if (ng > 1 && tb__rad_merge_face(m, idx, ng, &out[nout])) {
                nout++;
                continue;
            }
            for (size_t k = 0; k < ng; k++)
                tb_rad_mesh_polygon(m, idx[k], &out[nout++]);
        }
    }
    free(idx);
    free(done);
    free(pl);
    free(of);
    return nout;
}
