/* Emissive objects: the world-space area of an emitting primitive and its
 * emitters for area-light sampling (docs/rendering.md, "Emissive objects";
 * docs/lights.md): exact ones for polygons and spheres under a similarity,
 * an analytic surface emitter (emit_surface.h) for every other primitive,
 * a lazily tessellated emitter (emit_csg.h) for CSG objects; triangles of
 * the world-space tessellation for CSG objects and every curved primitive
 * when a renderer asks for tessellated emitters. */
#include <math.h>
#include <stdlib.h>

#include "host/object/polygonize.h"
#include "host/render/emit_csg.h"
#include "host/render/emit_surface.h"
#include "host/render/scene_internal.h"
#include "util/base/error.h"
#include "util/container/array.h"
#include "util/math/transform.h"
#include "util/mesh/fed.h"
#include "util/mesh/triangulate.h"

/* Angular tolerances of the two tessellations whose areas are extrapolated:
 * 4 and 2 degrees (90 and 180 segments per full turn, exactly doubling). */
#define TB__AREA_ANGLE_COARSE (4.0 * 3.14159265358979323846 / 180.0)
#define TB__AREA_ANGLE_FINE (2.0 * 3.14159265358979323846 / 180.0)

/* Determinant of the transform's linear part. */
static double tb__det3(const tb_transform *t)
{
    const double(*m)[4] = t->m.m;
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

/* Area of polygons object `o` in world space: its triangles transformed. */
static double tb__mesh_area(const tb_object *o)
{
    const tb_object_mesh *m = o->mesh;
    double sum = 0.0;
    for (uint32_t i = 0; m && i < m->ntris; i++) {
        const uint32_t *tv = &m->tris[3 * (size_t)i];
        tb_dvec3 p[3];
        for (int k = 0; k < 3; k++)
            p[k] = tb_transform_dpoint(&o->to_world, tb_vec3_to_d(m->vertices[tv[k]]));
        sum += 0.5 * tb_dvec3_length(tb_dvec3_cross(tb_dvec3_sub(p[1], p[0]), tb_dvec3_sub(p[2], p[0])));
    }
    return sum;
}

/* World area of the tessellation of `leaf` at angular tolerance `angle`: each
 * face's object-space area scaled by Nanson's formula |det L| |L^-T n| (exact
 * for flat faces under any affine map). */
static tb_status tb__tess_area(const tb_object *leaf, double angle, double *area)
{
    tb_poly_options po = {0};
    po.max_angle = angle;
    po.max_segments = TB_POLY_MAX_SEGMENTS;
    tb_fed *fed;
    tb_status st = tb_polygonize(leaf->kind, &leaf->geom, &po, &fed);
    if (st)
        return st;
    double det = fabs(tb__det3(&leaf->to_world)), sum = 0.0;
    for (uint32_t f = 0; f < fed->nfaces; f++) {
        tb_dvec3 n = tb_fed_face_normal(fed, f);
        double len = tb_dvec3_length(n);
        if (!(len > 0.0))
            continue;
        tb_dvec3 nw = tb_transform_dnormal(&leaf->to_world, tb_dvec3_scale(n, 1.0 / len));
        sum += tb_fed_face_area(fed, f) * det * tb_dvec3_length(nw);
    }
    tb_fed_free(fed);
    *area = sum;
    return TB_OK;
}

/* True for kinds whose every face is flat (their tessellation is exact). */
static bool tb__all_flat(tb_prim_kind k)
{
    return k == TB_PRIM_CUBE || k == TB_PRIM_PYRAMID || k == TB_PRIM_PRISM || k == TB_PRIM_SQUARE_ARCH;
}

/* True if every leaf of the tree under o has only flat faces. */
static bool tb__tree_flat(const tb_object *o)
{
    if (!tb_prim_is_csg(o->kind))
        return tb__all_flat(o->kind) || o->kind == TB_PRIM_POLYGONS;
    for (int i = 0; i < o->nchildren; i++)
        if (!tb__tree_flat(&o->children[i]))
            return false;
    return true;
}

static bool tb__similarity(const tb_transform *t, double *s);

bool tb__scene_leaf_area_exact(const tb_object *leaf, double *area)
{
    if (leaf->kind == TB_PRIM_POLYGONS) {
        *area = tb__mesh_area(leaf);
        return true;
    }
    double sc;
    if (leaf->kind == TB_PRIM_SPHERE && tb__similarity(&leaf->to_world, &sc)) {
        /* A sphere of radius sc (the case that becomes one sphere emitter):
         * exactly, instead of two fine tessellations (a render's largest
         * fixed cost on a scene with a lamp globe). */
        *area = 4.0 * TB_PI * sc * sc;
        return true;
    }
    return false;
}

tb_status tb__scene_leaf_area(const tb_object *leaf, double *area)
{
    if (tb_prim_is_csg(leaf->kind))
        return tb_error(TB_ERR_UNSUPPORTED, "scene: no area for a CSG node");
    if (tb__scene_leaf_area_exact(leaf, area))
        return TB_OK;
    double fine;
    tb_status st = tb__tess_area(leaf, TB__AREA_ANGLE_FINE, &fine);
    if (st)
        return st;
    if (tb__all_flat(leaf->kind)) {
        *area = fine;
        return TB_OK;
    }
    /* The inscribed tessellation's area error is c h^2 + O(h^4) for facet
     * size h; halving h and extrapolating removes the h^2 term. */
    double coarse;
    st = tb__tess_area(leaf, TB__AREA_ANGLE_COARSE, &coarse);
    if (st)
        return st;
    *area = (4.0 * fine - coarse) / 3.0;
    return TB_OK;
}

/* True if the linear part of t is a rotation (or mirror) times a uniform
 * scale; *s is that scale. */
static bool tb__similarity(const tb_transform *t, double *s)
{
    const double(*m)[4] = t->m.m;
    tb_dvec3 c[3];
    for (int j = 0; j < 3; j++)
        c[j] = (tb_dvec3){m[0][j], m[1][j], m[2][j]};
    double s2 = tb_dvec3_length2(c[0]), tol = 1e-9 * s2;
    for (int i = 0; i < 3; i++) {
        if (!(fabs(tb_dvec3_length2(c[i]) - s2) <= tol))
            return false;
        for (int j = i + 1; j < 3; j++)
            if (!(fabs(tb_dvec3_dot(c[i], c[j])) <= tol))
                return false;
    }
    *s = sqrt(s2);
    return true;
}

/* Angular tolerance of the tessellation that stands in for a curved or CSG
 * emitter in light sampling (4 degrees: 90 segments per full turn). */
#define TB__EMIT_ANGLE (4.0 * 3.14159265358979323846 / 180.0)
/* Edge of the CSG refinement along intersection curves, as a fraction of the
 * object's world box diagonal (the size the tessellation tolerance is tied to). */
#define TB__EMIT_CSG_EDGE 0.02

/* Emitters from the world-space tessellation of o (a primitive other than
 * polygons, or a CSG tree; scene_internal.h): every face triangulated,
 * triangles keeping the face's outward (front) orientation. On a curved
 * surface the inscribed triangles lie up to a sagitta inside the exact
 * surface, where shadow rays aimed at them would be stopped by the exact
 * surface itself; each is moved out along its normal by a bound on that
 * gap, half its longest edge times tan(angle / 2). */
tb_status tb__scene_tess_emitters(const tb_object *o, tb_channels L, double angle, double edge, int segments,
                                  tb_array *out, int *count)
{
    *count = 0;
    /* As for areas (scene.c), a shape that cannot be tessellated is not worth
     * refusing the scene for: it gets no emitters (only memory is fatal). */
    tb_aabb box;
    tb_status st = tb__scene_object_bounds(o, &box);
    if (st) {
        if (st != TB_ERR_NOMEM)
            tb_clear_error();
        return st == TB_ERR_NOMEM ? st : TB_OK;
    }
    double diag = tb_dvec3_length(tb_dvec3_sub(tb_vec3_to_d(box.hi), tb_vec3_to_d(box.lo)));
    if (!(diag > 0.0) || !isfinite(diag))
        return TB_OK;
    tb_poly_options po = {0};
    po.max_angle = angle;
    po.max_segments = segments;
    tb_fed *fed;
    if ((st = tb_polygonize_object(o, &po, edge * diag, &fed))) {
        if (st != TB_ERR_NOMEM)
            tb_clear_error();
        return st == TB_ERR_NOMEM ? st : TB_OK;
    }
    bool curved = !tb__tree_flat(o);
    double lift_k = curved ? 0.5 * tan(0.5 * angle) : 0.0;
    tb_array tris, pts, sizes;
    tb_array_init(&tris, sizeof(tb_tri));
    tb_array_init(&pts, sizeof(tb_vec3));
    tb_array_init(&sizes, sizeof(uint32_t));
    int n = 0;
    for (uint32_t f = 0; f < fed->nfaces && n >= 0; f++) {
        pts.len = sizes.len = tris.len = 0;
        for (uint32_t l = fed->face_loops[f]; l < fed->face_loops[f + 1] && n >= 0; l++) {
            uint32_t c0 = fed->loop_corners[l], c1 = fed->loop_corners[l + 1], sz = c1 - c0;
            for (uint32_t c = c0; c < c1 && n >= 0; c++)
                if (tb_array_push(&pts, &fed->positions[fed->corner_vert[c]]))
                    n = -1;
            if (n >= 0 && tb_array_push(&sizes, &sz))
                n = -1;
        }
        if (n < 0)
            break;
        if (tb_triangulate_3d(pts.data, NULL, sizes.data, (uint32_t)sizes.len, &tris, NULL)) {
            tb_clear_error(); /* a degenerate face (a sliver at a pole): nothing to sample */
            continue;
        }
        uint32_t face = fed->face_ids ? (uint32_t)fed->face_ids[f] : o->face_base;
        for (size_t t = 0; t < tris.len; t++) {
            const tb_tri *tr = tb_array_at(&tris, t);
            tb_vec3 p[3];
            for (int k = 0; k < 3; k++)
                p[k] = ((const tb_vec3 *)pts.data)[tr->v[k]];
            tb_emitter e = tb_emitter_triangle(p[0], p[1], p[2], L);
            double area = tb_emitter_area(&e);
            if (!(area > 0.0))
                continue; /* a sliver that vanished in float: nothing to sample */
            if (curved) {
                tb_dvec3 d[3];
                for (int k = 0; k < 3; k++)
                    d[k] = tb_vec3_to_d(p[k]);
                tb_dvec3 nrm = tb_dvec3_cross(tb_dvec3_sub(d[1], d[0]), tb_dvec3_sub(d[2], d[0]));
                double edge = fmax(tb_dvec3_length(tb_dvec3_sub(d[1], d[0])),
                                   fmax(tb_dvec3_length(tb_dvec3_sub(d[2], d[1])),
                                        tb_dvec3_length(tb_dvec3_sub(d[0], d[2]))));
                tb_dvec3 off = tb_dvec3_scale(nrm, lift_k * edge / tb_dvec3_length(nrm));
                for (int k = 0; k < 3; k++)
                    p[k] = tb_dvec3_to_f(tb_dvec3_add(d[k], off));
                e = tb_emitter_triangle(p[0], p[1], p[2], L);
            }
            e.object = o->index;
            e.face = face;
            if (out && tb_array_push(out, &e)) {
                n = -1;
                break;
            }
            n++;
        }
    }
    tb_array_free(&tris);
    tb_array_free(&pts);
    tb_array_free(&sizes);
    tb_fed_free(fed);
    if (n < 0)
        return tb_error(TB_ERR_NOMEM, "scene: out of memory for the emitters of a tessellated object");
    *count = n;
    return TB_OK;
}

/* The tessellated emitters at the eager tolerances (tessellated_emitters). */
static tb_status tb__tess_default(const tb_object *o, tb_channels L, tb_array *out, int *count)
{
    return tb__scene_tess_emitters(o, L, TB__EMIT_ANGLE, TB__EMIT_CSG_EDGE, TB_POLY_DEFAULT_SEGMENTS, out, count);
}

/* The lazily tessellated emitter of CSG object o (emit_csg.h): appended to
 * out (when not NULL), else only measured; *bytes gets its unbuilt size.
 * A tree without finite bounds gets no emitter. */
static tb_status tb__csg_emitter(const tb_object *o, tb_channels L, tb_array *out, int *count, size_t *bytes)
{
    tb_csg_emitter *ce;
    tb_status st = tb_csg_emitter_make(o, L, &ce);
    if (st) {
        if (st != TB_ERR_NOMEM)
            tb_clear_error();
        return st == TB_ERR_NOMEM ? st : TB_OK;
    }
    if (bytes)
        *bytes += tb_csg_emitter_bytes(ce) + TB_SCENE_MALLOC_OVERHEAD;
    *count = 1;
    if (!out) {
        tb_csg_emitter_free(ce);
        return TB_OK;
    }
    tb_emitter e = tb_emitter_csg(ce);
    if (tb_array_push(out, &e)) {
        tb_csg_emitter_free(ce);
        *count = 0;
        return tb_error(TB_ERR_NOMEM, "scene: out of memory for emitters");
    }
    return TB_OK;
}

/* The analytic emitter of primitive `leaf` (emit_surface.h): appended to
 * out (when not NULL) with its table, else only measured; *bytes gets the
 * table's bytes. A surface that cannot have one (no area) gets no emitter. */
static tb_status tb__surface_emitter(const tb_object *leaf, tb_channels L, tb_array *out, int *count, size_t *bytes)
{
    tb_surface_emitter *se;
    tb_status st = tb_surface_emitter_make(leaf, &se);
    if (st) {
        if (st != TB_ERR_NOMEM)
            tb_clear_error();
        return st == TB_ERR_NOMEM ? st : TB_OK;
    }
    if (tb_surface_emitter_partial(se)) {
        /* arch faces: the table's area is an estimate; the tessellation's
         * (exact for flat faces; a round arch's vault by extrapolation) */
        double a;
        if (tb__scene_leaf_area(leaf, &a) == TB_OK && a > 0.0 && isfinite(a))
            tb_surface_emitter_set_area(se, a);
        else
            tb_clear_error();
    }
    if (bytes)
        *bytes += tb_surface_emitter_bytes(se, TB_SCENE_MALLOC_OVERHEAD);
    if (!out) {
        tb_surface_emitter_free(se);
        *count = 1;
        return TB_OK;
    }
    tb_emitter e = tb_emitter_surface(se, L);
    if (tb_array_push(out, &e)) {
        tb_surface_emitter_free(se);
        return tb_error(TB_ERR_NOMEM, "scene: out of memory for emitters");
    }
    *count = 1;
    return TB_OK;
}

tb_status tb__scene_leaf_emitters(const tb_object *leaf, tb_channels L, bool tessellate, tb_array *out, int *count,
                                  size_t *bytes)
{
    *count = 0;
    if (leaf->kind == TB_PRIM_SPHERE) {
        double s;
        if (!tb__similarity(&leaf->to_world, &s))
            return tessellate ? tb__tess_default(leaf, L, out, count) : tb__surface_emitter(leaf, L, out, count, bytes);
        if (out) {
            tb_dvec3 c = tb_transform_dpoint(&leaf->to_world, (tb_dvec3){0.0, 0.0, 0.0});
            tb_emitter e = tb_emitter_sphere(tb_dvec3_to_f(c), (float)s, L);
            e.object = leaf->index;
            e.face = leaf->face_base;
            if (tb_array_push(out, &e))
                return tb_error(TB_ERR_NOMEM, "scene: out of memory for emitters");
        }
        *count = 1;
        return TB_OK;
    }
    if (tb_prim_is_csg(leaf->kind) && !tessellate)
        return tb__csg_emitter(leaf, L, out, count, bytes);
    if (tb_prim_is_csg(leaf->kind) || (tessellate && leaf->kind != TB_PRIM_POLYGONS))
        return tb__tess_default(leaf, L, out, count);
    if (leaf->kind != TB_PRIM_POLYGONS)
        return tb__surface_emitter(leaf, L, out, count, bytes);
    if (!leaf->mesh)
        return TB_OK;
    const tb_object_mesh *m = leaf->mesh;
    /* A mirroring transform reverses the winding in world space; the front
     * side must stay the object's front side. */
    bool swap = tb_transform_swaps_handedness(&leaf->to_world);
    int n = 0;
    for (uint32_t i = 0; i < m->ntris; i++) {
        const uint32_t *tv = &m->tris[3 * (size_t)i];
        tb_vec3 p[3];
        for (int k = 0; k < 3; k++)
            p[k] = tb_dvec3_to_f(tb_transform_dpoint(&leaf->to_world, tb_vec3_to_d(m->vertices[tv[k]])));
        tb_emitter e = swap ? tb_emitter_triangle(p[0], p[2], p[1], L) : tb_emitter_triangle(p[0], p[1], p[2], L);
        if (!(tb_emitter_area(&e) > 0.0))
            continue; /* a sliver that vanished in float: nothing to sample */
        e.object = leaf->index;
        e.face = leaf->face_base + m->tri_face[i];
        if (out && tb_array_push(out, &e))
            return tb_error(TB_ERR_NOMEM, "scene: out of memory for emitters");
        n++;
    }
    *count = n;
    return TB_OK;
}

void tb__scene_free_emitter(tb_emitter *e)
{
    if (tb_emitter_is_surface(e)) {
        tb_surface_emitter_free(e->ctx);
        e->ctx = NULL;
    } else if (tb_emitter_is_csg(e)) {
        tb_csg_emitter_free(e->ctx);
        e->ctx = NULL;
    }
}
