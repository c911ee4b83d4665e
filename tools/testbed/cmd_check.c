/* `testbed check SCENE.mid`: reads a MID scene with the streaming reader,
 * stops at the first error, and otherwise prints a summary: objects by kind,
 * materials, lights, camera, world bounds and the data files referenced. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "host/mid/mid_reader.h"
#include "util/container/hash_table.h"
#include "util/math/aabb.h"
#include "util/math/transform.h"

/* What the summary counts. */
typedef struct tb__check {
    const char *file;
    bool warn_unknown;
    long warnings;
    long top_objects;
    long kinds[TB_PRIM_COUNT];
    long lights[3];
    long emitters;
    long materials;
    char names[512];        /* the first material names, for the summary line */
    tb_aabb bounds;
    long unbounded;         /* objects whose extent the reader cannot know (FED meshes) */
    tb_htab seen;           /* resolved path -> 1 */
    long nfiles;
    char **files;           /* "text -> path" lines, in the order first met */
    long cap;
} tb__check;

static void tb__warn_attrs(tb__check *c, const tb_mid_attrs *x, const char *where, const char *name)
{
    if (!c->warn_unknown)
        return;
    for (int i = 0; i < x->count; i++) {
        const tb_mid_attr *a = &x->items[i];
        fprintf(stderr, "%s:%ld:%ld: warning: unknown attribute '%s' in %s%s%s%s\n", c->file, a->loc.line,
                a->loc.col, a->name, where, name ? " '" : "", name ? name : "", name ? "'" : "");
        c->warnings++;
    }
}

static void tb__note_refs(tb__check *c, const tb_mid_ref *refs, int n)
{
    for (int i = 0; i < n; i++) {
        if (tb_htab_get_str(&c->seen, refs[i].path, NULL))
            continue;
        if (tb_htab_put_str(&c->seen, refs[i].path, 1) != TB_OK)
            continue;
        if (c->nfiles == c->cap) {
            long cap = c->cap ? 2 * c->cap : 16;
            char **f = realloc(c->files, (size_t)cap * sizeof *f);
            if (!f)
                continue;
            c->files = f;
            c->cap = cap;
        }
        size_t n = strlen(refs[i].text) + strlen(refs[i].path) + 8;
        char *line = malloc(n);
        if (!line)
            continue;
        snprintf(line, n, "%s -> %s", refs[i].text, refs[i].path);
        c->files[c->nfiles++] = line;
    }
}

/* Largest r^2 of a conic over its z range (ends, and the vertex inside). */
static double tb__conic_rmax(const tb_geom_conic *g)
{
    double zs[3] = {g->z0, g->z1, 0.0};
    int n = 2;
    if (g->c[2] != 0.0) {
        double zv = -g->c[1] / (2.0 * g->c[2]);
        if (zv > g->z0 && zv < g->z1)
            zs[n++] = zv;
    }
    double m = 0.0;
    for (int i = 0; i < n; i++)
        m = fmax(m, g->c[0] + g->c[1] * zs[i] + g->c[2] * zs[i] * zs[i]);
    return sqrt(m);
}

/* The object's canonical box in object space; false if unknown here (FED mesh). */
static bool tb__local_box(const tb_mid_object *o, tb_aabb *b)
{
    const tb_mid_geometry *g = &o->geom;
    float xy = 1.0f;
    *b = (tb_aabb){{-1, -1, -1}, {1, 1, 1}};
    switch (o->kind) {
    case TB_PRIM_CONE: xy = (float)fmax(1.0, g->cone.top_radius); break;
    case TB_PRIM_PYRAMID: xy = (float)fmax(1.0, g->pyramid.top); break;
    case TB_PRIM_PRISM:
        if (g->prism.nprofile > 0) {
            *b = tb_aabb_empty();
            for (int i = 0; i < g->prism.nprofile; i++) {
                tb_vec2 p = g->prism.profile[i];
                *b = tb_aabb_union_point(*b, (tb_vec3){p.x, p.y, -1.0f});
                *b = tb_aabb_union_point(*b, (tb_vec3){p.x, p.y, 1.0f});
            }
            return true;
        }
        break;
    case TB_PRIM_TORUS: {
        float rr = (float)(g->torus.major + g->torus.minor), r = (float)g->torus.minor;
        *b = (tb_aabb){{-rr, -rr, -r}, {rr, rr, r}};
        return true;
    }
    case TB_PRIM_POLYGONS:
        if (g->polygons.mesh.text)
            return false;
        *b = tb_aabb_empty();
        for (int i = 0; i < g->polygons.nvertices; i++)
            *b = tb_aabb_union_point(*b, g->polygons.vertices[i]);
        return true;
    case TB_PRIM_CONIC: {
        float r = (float)tb__conic_rmax(&g->conic);
        *b = (tb_aabb){{-r, -r, (float)g->conic.z0}, {r, r, (float)g->conic.z1}};
        return true;
    }
    default: break;
    }
    b->lo.x = b->lo.y = -xy;
    b->hi.x = b->hi.y = xy;
    return true;
}

/* World box of an object tree; false if some part is unknown here. */
static bool tb__world_box(tb__check *c, const tb_mid_object *o, tb_aabb *out)
{
    if (!tb_prim_is_csg(o->kind)) {
        tb_aabb local;
        if (!tb__local_box(o, &local))
            return false;
        *out = tb_transform_aabb(&o->to_world, &local);
        return true;
    }
    bool known = o->kind != TB_PRIM_INTERSECTION;
    for (int i = 0; i < o->nchildren; i++) {
        tb_aabb b;
        bool k = tb__world_box(c, &o->children[i], &b);
        if (o->kind == TB_PRIM_DIFFERENCE) {
            /* The result lies inside the first child. */
            if (i == 0) {
                *out = b;
                return k;
            }
        } else if (o->kind == TB_PRIM_INTERSECTION) {
            /* Any child with a known box bounds an intersection. */
            if (k) {
                *out = known ? tb_aabb_intersection(*out, b) : b;
                known = true;
            }
        } else {
            if (!k)
                return false;
            *out = i == 0 ? b : tb_aabb_union(*out, b);
        }
    }
    return known;
}

static void tb__count_object(tb__check *c, const tb_mid_object *o)
{
    c->kinds[o->kind]++;
    if (tb_mid_material_emits(&o->material) && !tb_prim_is_csg(o->kind))
        c->emitters++;
    /* The labels are formatted only when there is something to warn about:
     * two snprintf calls per object were 8% of reading a file of small
     * objects (docs/performance.md, "MID reader"). */
    if (c->warn_unknown) {
        tb__warn_attrs(c, &o->extra, tb_prim_kind_name(o->kind), o->name);
        char where[64];
        if (o->geometry_extra.count > 0) {
            snprintf(where, sizeof where, "the geometry of %s", tb_prim_kind_name(o->kind));
            tb__warn_attrs(c, &o->geometry_extra, where, o->name);
        }
        if (o->material.extra.count > 0) {
            snprintf(where, sizeof where, "the rendering of %s", tb_prim_kind_name(o->kind));
            tb__warn_attrs(c, &o->material.extra, where, o->name);
        }
    }
    tb__note_refs(c, o->refs, o->nrefs);
    for (int i = 0; i < o->nchildren; i++)
        tb__count_object(c, &o->children[i]);
}

static void tb__print_summary(const tb__check *c, const tb_mid_reader *r)
{
    int major, minor;
    tb_mid_reader_version(r, &major, &minor);
    long nodes = 0;
    for (int k = 0; k < TB_PRIM_COUNT; k++)
        nodes += c->kinds[k];
    printf("%s: valid MID %d.%d scene\n", c->file, major, minor);
    printf("objects: %ld top-level, %ld in all", c->top_objects, nodes);
    const char *sep = ": ";
    for (int k = 0; k < TB_PRIM_COUNT; k++)
        if (c->kinds[k]) {
            printf("%s%s %ld", sep, tb_prim_kind_name((tb_prim_kind)k), c->kinds[k]);
            sep = ", ";
        }
    printf("\nemitting objects: %ld\n", c->emitters);
    printf("materials: %ld%s%s\n", c->materials, c->materials ? ": " : "", c->names);
    long nl = c->lights[0] + c->lights[1] + c->lights[2];
    printf("lights: %ld", nl);
    sep = ": ";
    for (int k = 0; k < 3; k++)
        if (c->lights[k]) {
            printf("%s%s %ld", sep, tb_light_kind_name((tb_light_kind)k), c->lights[k]);
            sep = ", ";
        }
    printf("\n");
    const tb_mid_camera *cam = tb_mid_reader_camera(r);
    if (cam)
        printf("camera: eye [%g %g %g], look_at [%g %g %g], fov %g deg, %d x %d pixels\n", cam->eye.x,
               cam->eye.y, cam->eye.z, cam->look_at.x, cam->look_at.y, cam->look_at.z, cam->fov, cam->width,
               cam->height);
    else
        printf("camera: none\n");
    if (tb_aabb_is_empty(&c->bounds))
        printf("bounds: %s\n", c->unbounded ? "computed by the object level (FED meshes only)" : "empty");
    else {
        printf("bounds: [%g %g %g] to [%g %g %g]", c->bounds.lo.x, c->bounds.lo.y, c->bounds.lo.z, c->bounds.hi.x,
               c->bounds.hi.y, c->bounds.hi.z);
        if (c->unbounded)
            printf(" without %ld object%s with FED meshes (bounded by the object level)", c->unbounded,
                   c->unbounded == 1 ? "" : "s");
        printf("\n");
    }
    printf("referenced files: %ld\n", c->nfiles);
    for (long i = 0; i < c->nfiles; i++)
        printf("  %s\n", c->files[i]);
    if (c->warn_unknown)
        printf("unknown attributes: %ld\n", c->warnings);
}

int tb_cmd_check(int argc, char **argv)
{
    const char *path = NULL;
    bool warn = false;
    const tb_opt opts[] = {
        {"warn-unknown", .type = TB_OPT_FLAG, .dest = &warn,
         .help = "list attributes the reader does not know (kept, and ignored by\n"
                 "renderers) as FILE:LINE:COL: warning: ... on standard error"},
        {0},
    };
    const tb_cli cli = {
        .prog = "testbed check",
        .err = "testbed check: error: ",
        .usage = "SCENE.mid [--warn-unknown]",
        .intro = "\n"
                 "Reads the MID scene SCENE.mid (- reads standard input) and checks it against the\n"
                 "MID specification (docs/mid.md): syntax, every known attribute's shape and range,\n"
                 "transforms, materials defined before use, and that every referenced data file\n"
                 "exists. The first error is printed as FILE:LINE:COL: error: MESSAGE. A valid scene\n"
                 "gets a summary: objects by kind, materials, lights, camera, world-space bounds of\n"
                 "the objects (boxes of the canonical shapes under their transforms) and the files\n"
                 "it references.\n",
        .opts = opts,
        .outro = "\nExit status: 0 valid scene, 1 invalid scene or unreadable file, 2 usage error.",
        .pos = &path,
        .max_pos = 1,
        .min_pos = 1,
        .missing = "no SCENE.mid given",
    };
    int npos, prc = tb_cli_parse(&cli, argc, argv, &npos);
    if (prc != TB_CLI_OK)
        return prc;
    tb_mid_reader *r;
    if (tb_mid_reader_open(&r, path)) {
        fprintf(stderr, "testbed check: error: %s\n", tb_last_error());
        return TB_EXIT_FAIL;
    }
    tb__check c;
    memset(&c, 0, sizeof c);
    c.file = strcmp(path, "-") == 0 ? "<stdin>" : path;
    c.warn_unknown = warn;
    c.bounds = tb_aabb_empty();
    tb_htab_init(&c.seen, TB_HTAB_STR);
    tb_mid_item it;
    tb_status st;
    while (!(st = tb_mid_reader_next(r, &it)) && it.type != TB_MID_ITEM_END) {
        switch (it.type) {
        case TB_MID_ITEM_OBJECT: {
            c.top_objects++;
            tb__count_object(&c, it.object);
            tb_aabb b;
            if (tb__world_box(&c, it.object, &b))
                c.bounds = tb_aabb_union(c.bounds, b);
            else
                c.unbounded++;
            break;
        }
        case TB_MID_ITEM_MATERIAL: {
            const tb_mid_material *m = it.material;
            size_t n = strlen(c.names);
            if (n < sizeof c.names - 64)
                snprintf(c.names + n, sizeof c.names - n, "%s%s", c.materials ? ", " : "", m->name);
            else if (n < sizeof c.names - 4 && !strstr(c.names, "..."))
                strcat(c.names, ", ...");
            c.materials++;
            tb__warn_attrs(&c, &m->extra, "material", m->name);
            tb__note_refs(&c, m->refs, m->nrefs);
            break;
        }
        case TB_MID_ITEM_LIGHT:
            c.lights[it.light->kind]++;
            tb__warn_attrs(&c, &it.light->extra, tb_light_kind_name(it.light->kind), it.light->name);
            tb__note_refs(&c, it.light->refs, it.light->nrefs);
            break;
        case TB_MID_ITEM_CAMERA:
            tb__warn_attrs(&c, &it.camera->extra, "camera", it.camera->name);
            tb__note_refs(&c, it.camera->refs, it.camera->nrefs);
            break;
        default: break;
        }
    }
    int rc = TB_EXIT_OK;
    if (st) {
        fprintf(stderr, "%s\n", tb_last_error());
        rc = TB_EXIT_FAIL;
    } else
        tb__print_summary(&c, r);
    tb_htab_free(&c.seen);
    for (long i = 0; i < c.nfiles; i++)
        free(c.files[i]);
    free(c.files);
    tb_mid_reader_close(r);
    return rc;
}
