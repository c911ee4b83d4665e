/* Procedural MID scenes (generate.h): a grid of mixed primitives, random CSG
 * trees, or tessellated meshes, made one object at a time. */
#include "host/mid/generate.h"

#include <math.h>
#include <string.h>

#include "host/mid/mid_writer.h"
#include "util/container/arena.h"
#include "util/math/float.h"
#include "util/math/rng.h"

/* Grid cell size in scene units: a generated object reaches at most about
 * 2.1 units from its centre, so neighbours rarely touch. */
#define TB__PITCH 4.5

/* Height of the objects' centres above the z = 0 plane. */
#define TB__Z 2.25

/* Materials of the palette. */
enum { TB__MAT_COUNT = 8, TB__MAT_LAMP = 7 };

static const char *const tb__kind_names[TB_GEN_KIND_COUNT] = {"grid", "csg", "mesh"};

/* The 11 primitive kinds (everything but the CSG nodes). */
static const tb_prim_kind tb__prims[] = {
    TB_PRIM_SPHERE, TB_PRIM_CUBE,    TB_PRIM_CYLINDER, TB_PRIM_CONE,        TB_PRIM_PYRAMID,    TB_PRIM_PRISM,
    TB_PRIM_TORUS,  TB_PRIM_POLYGONS, TB_PRIM_CONIC,   TB_PRIM_SQUARE_ARCH, TB_PRIM_ROUND_ARCH,
};
#define TB__NPRIMS ((uint32_t)(sizeof tb__prims / sizeof tb__prims[0]))

const char *tb_gen_kind_name(tb_gen_kind k)
{
    return (int)k >= 0 && (int)k < TB_GEN_KIND_COUNT ? tb__kind_names[k] : "?";
}

tb_status tb_gen_kind_parse(const char *name, tb_gen_kind *out)
{
    for (int k = 0; k < TB_GEN_KIND_COUNT; k++)
        if (name && strcmp(name, tb__kind_names[k]) == 0) {
            *out = (tb_gen_kind)k;
            return TB_OK;
        }
    return tb_error(TB_ERR_ARG, "unknown scene kind '%s' (expected grid, csg or mesh)", name ? name : "(null)");
}

/* ------------------------------------------------------------------ state */

typedef struct tb__gen {
    tb_gen_options opt;
    tb_rng rng;                           /* this object's stream */
    tb_arena arena;                       /* this object's memory, reset after each */
    bool nomem;                           /* an allocation failed */
    int64_t side;                         /* grid cells per row */
    tb_mid_material mats[TB__MAT_COUNT];  /* the palette as defined */
} tb__gen;

/* SplitMix64's finaliser: spreads (seed, index) over the PCG seed space so
 * neighbouring objects get unrelated streams. */
static uint64_t tb__mix(uint64_t x)
{
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

static uint32_t tb__below(tb__gen *g, uint32_t n) { return tb_rng_below(&g->rng, n); }
static bool tb__chance(tb__gen *g, uint32_t percent) { return tb__below(g, 100) < percent; }
static double tb__uni(tb__gen *g, double lo, double hi) { return lo + (hi - lo) * tb_rng_double(&g->rng); }

/* x rounded to 3 decimals: short numbers in the file, as a modeler would write. */
static double tb__q3(double x) { return round(x * 1000.0) / 1000.0; }

/* x rounded to 4 decimals, as a float: mesh data as an exporter writes it
 * (and 5-6 digit numbers that the writer prints on its first try). */
static float tb__q4f(double x) { return (float)(round(x * 10000.0) / 10000.0); }

/* A quantised uniform number in [lo, hi]. */
static double tb__uq(tb__gen *g, double lo, double hi) { return tb__q3(tb__uni(g, lo, hi)); }

static void *tb__alloc(tb__gen *g, size_t n)
{
    void *p = tb_arena_alloc_zero(&g->arena, n);
    if (!p)
        g->nomem = true;
    return p;
}

/* ------------------------------------------------------------- transforms */

/* An operation list under construction (at most 4 operations). */
typedef struct tb__ops {
    tb_mid_op op[4];
    int n;
} tb__ops;

static void tb__translate(tb__ops *o, double x, double y, double z)
{
    o->op[o->n++] = (tb_mid_op){.kind = TB_MID_TRANSLATE, .v = {x, y, z}};
}

static void tb__scale(tb__ops *o, double x, double y, double z)
{
    o->op[o->n++] = (tb_mid_op){.kind = TB_MID_SCALE, .v = {x, y, z}};
}

/* A rotation about a random axis (never shorter than 0.1) by a random angle. */
static void tb__rotate_random(tb__gen *g, tb__ops *o)
{
    double a[3];
    do
        for (int i = 0; i < 3; i++)
            a[i] = tb__uq(g, -1.0, 1.0);
    while (a[0] * a[0] + a[1] * a[1] + a[2] * a[2] < 0.01);
    o->op[o->n++] = (tb_mid_op){.kind = TB_MID_ROTATE, .v = {a[0], a[1], a[2], tb__uq(g, 0.0, 360.0)}};
}

/* A uniform scale in [lo, hi], or per axis in 30% of cases. */
static void tb__scale_random(tb__gen *g, tb__ops *o, double lo, double hi)
{
    if (tb__chance(g, 30))
        tb__scale(o, tb__uq(g, lo, hi), tb__uq(g, lo, hi), tb__uq(g, lo, hi));
    else {
        double s = tb__uq(g, lo, hi);
        tb__scale(o, s, s, s);
    }
}

/* Gives `obj` the operations and its world transform (parent NULL: top level,
 * as the reader composes them). */
static tb_status tb__place(tb__gen *g, tb_mid_object *obj, const tb__ops *o, const tb_transform *parent)
{
    tb_mid_op *ops = NULL;
    if (o->n) {
        ops = tb__alloc(g, (size_t)o->n * sizeof *ops);
        if (!ops)
            return TB_ERR_NOMEM;
        memcpy(ops, o->op, (size_t)o->n * sizeof *ops);
    }
    obj->ops = ops;
    obj->nops = o->n;
    tb_transform local;
    tb_status st = tb_mid_ops_transform(o->op, o->n, &local, NULL);
    if (st)
        return st; /* cannot happen: scales >= 0.3, axes >= 0.1 long */
    obj->to_world = parent ? tb_transform_compose(parent, &local) : local;
    return TB_OK;
}

/* -------------------------------------------------------------- materials */

/* What a rendering block that names only `base` gives. */
static tb_mid_material tb__named(const tb_mid_material *base)
{
    tb_mid_material m = *base;
    m.name = NULL;
    m.base = base->name;
    m.set = 0;
    m.extra = (tb_mid_attrs){NULL, 0};
    m.refs = NULL;
    m.nrefs = 0;
    return m;
}

/* What an object without a rendering block inherits from its parent. */
static tb_mid_material tb__inherit(const tb_mid_material *parent)
{
    tb_mid_material m = tb__named(parent);
    m.base = NULL;
    return m;
}

static tb_mid_color tb__rgb(float r, float g, float b)
{
    tb_mid_color c;
    memset(&c, 0, sizeof c);
    c.type = TB_MID_COLOR_RGB;
    c.rgb[0] = r;
    c.rgb[1] = g;
    c.rgb[2] = b;
    return c;
}

/* A rendering block naming a palette material (rarely the lamp), in 25% of
 * cases with its own diffuse colour. */
static tb_mid_material tb__random_material(tb__gen *g)
{
    int i = tb__chance(g, 2) ? TB__MAT_LAMP : (int)tb__below(g, TB__MAT_LAMP);
    tb_mid_material m = tb__named(&g->mats[i]);
    if (tb__chance(g, 25)) {
        m.diffuse = tb__rgb((float)tb__uq(g, 0, 1), (float)tb__uq(g, 0, 1), (float)tb__uq(g, 0, 1));
        m.set |= TB_MID_SET_DIFFUSE;
    }
    return m;
}

static void tb__palette(tb__gen *g)
{
    static const char *const names[TB__MAT_COUNT] = {"matte white", "matte red", "matte green", "phong blue",
                                                     "phong gold",  "glass",     "mirror",      "lamp"};
    for (int i = 0; i < TB__MAT_COUNT; i++) {
        g->mats[i] = tb_mid_material_default();
        g->mats[i].name = names[i];
    }
    tb_mid_material *m = g->mats;
    m[0].diffuse = tb_mid_color_grey(0.8f);
    m[1].diffuse = tb__rgb(0.7f, 0.12f, 0.1f);
    m[2].diffuse = tb__rgb(0.15f, 0.55f, 0.2f);
    m[3].diffuse = tb__rgb(0.1f, 0.2f, 0.6f);
    m[3].specular = tb_mid_color_grey(0.5f);
    m[3].exponent = 60.0f;
    m[3].set = TB_MID_SET_SPECULAR | TB_MID_SET_EXPONENT;
    m[4].diffuse = tb__rgb(0.4f, 0.3f, 0.05f);
    m[4].specular = tb__rgb(0.6f, 0.5f, 0.2f);
    m[4].exponent = 200.0f;
    m[4].set = TB_MID_SET_SPECULAR | TB_MID_SET_EXPONENT;
    m[5].diffuse = tb_mid_color_grey(0.0f);
    m[5].specular = tb_mid_color_grey(0.05f);
    m[5].transmission = tb_mid_color_grey(0.9f);
    m[5].ior = 1.5f;
    m[5].set = TB_MID_SET_SPECULAR | TB_MID_SET_TRANSMISSION | TB_MID_SET_IOR;
    m[6].diffuse = tb_mid_color_grey(0.0f);
    m[6].specular = tb_mid_color_grey(0.9f);
    m[6].exponent = 10000.0f;
    m[6].set = TB_MID_SET_SPECULAR | TB_MID_SET_EXPONENT;
    m[7].diffuse = tb_mid_color_grey(0.8f);
    m[7].emission = tb__rgb(20.0f, 18.0f, 15.0f);
    m[7].set = TB_MID_SET_EMISSION;
    for (int i = 0; i < TB__MAT_COUNT; i++)
        m[i].set |= TB_MID_SET_DIFFUSE;
}

/* --------------------------------------------------------------- geometry */

/* The octahedron |x| + |y| + |z| = 1 as 8 outward triangles: a closed mesh. */
static tb_status tb__octahedron(tb__gen *g, tb_geom_polygons *p)
{
    tb_vec3 *v = tb__alloc(g, 6 * sizeof *v);
    int *start = tb__alloc(g, 9 * sizeof *start);
    int *idx = tb__alloc(g, 24 * sizeof *idx);
    if (!v || !start || !idx)
        return TB_ERR_NOMEM;
    v[0] = (tb_vec3){1, 0, 0};
    v[1] = (tb_vec3){-1, 0, 0};
    v[2] = (tb_vec3){0, 1, 0};
    v[3] = (tb_vec3){0, -1, 0};
    v[4] = (tb_vec3){0, 0, 1};
    v[5] = (tb_vec3){0, 0, -1};
    for (int f = 0; f < 8; f++) {
        int sx = f & 1, sy = (f >> 1) & 1, sz = (f >> 2) & 1;
        int a = sx, b = 2 + sy, c = 4 + sz;
        /* (+x, +y, +z) runs counter-clockwise seen from outside; each mirror
         * (a negative axis) reverses the sense. */
        if ((sx + sy + sz) & 1) {
            int t = b;
            b = c;
            c = t;
        }
        start[f] = 3 * f;
        idx[3 * f] = a;
        idx[3 * f + 1] = b;
        idx[3 * f + 2] = c;
    }
    start[8] = 24;
    p->nvertices = 6;
    p->vertices = v;
    p->nfaces = 8;
    p->face_start = start;
    p->indices = idx;
    return TB_OK;
}

/* A star-shaped simple polygon: n points at increasing angles (jittered) and
 * radii in [0.4, 1]; the angles never wrap, so the outline cannot cross
 * itself. */
static tb_status tb__profile(tb__gen *g, tb_geom_prism *p)
{
    int n = 5 + (int)tb__below(g, 12);
    tb_vec2 *pt = tb__alloc(g, (size_t)n * sizeof *pt);
    if (!pt)
        return TB_ERR_NOMEM;
    double step = 2.0 * TB_PI / n;
    for (int i = 0; i < n; i++) {
        double a = step * (i + tb__uni(g, -0.3, 0.3)), r = tb__uni(g, 0.4, 1.0);
        pt[i] = (tb_vec2){(float)tb__q3(r * cos(a)), (float)tb__q3(r * sin(a))};
    }
    p->sides = 0;
    p->nprofile = n;
    p->profile = pt;
    return TB_OK;
}

/* Random parameters for a primitive of kind `k`; `solid` asks for closed
 * surfaces (CSG operands): caps on, closed conics. */
static tb_status tb__primitive(tb__gen *g, tb_mid_object *o, bool solid)
{
    tb_prim_kind k = tb__prims[tb__below(g, TB__NPRIMS)];
    tb_mid_geometry *geo = &o->geom;
    o->kind = k;
    *geo = tb_mid_geometry_default(k);
    switch (k) {
    case TB_PRIM_CYLINDER: geo->cylinder.caps = solid || tb__chance(g, 80); break;
    case TB_PRIM_CONE:
        geo->cone.top_radius = tb__chance(g, 50) ? 0.0 : tb__uq(g, 0.1, 0.9);
        geo->cone.caps = solid || tb__chance(g, 80);
        break;
    case TB_PRIM_PYRAMID:
        geo->pyramid.top = tb__chance(g, 50) ? 0.0 : tb__uq(g, 0.1, 0.9);
        geo->pyramid.caps = solid || tb__chance(g, 80);
        break;
    case TB_PRIM_PRISM:
        if (tb__chance(g, 50)) {
            geo->prism.sides = 3 + (int)tb__below(g, 10);
        } else if (tb__profile(g, &geo->prism))
            return TB_ERR_NOMEM;
        geo->prism.caps = solid || tb__chance(g, 80);
        break;
    case TB_PRIM_TORUS:
        geo->torus.major = 1.0;
        geo->torus.minor = tb__uq(g, 0.1, 0.5);
        break;
    case TB_PRIM_POLYGONS: return tb__octahedron(g, &geo->polygons);
    case TB_PRIM_CONIC: {
        tb_geom_conic *c = &geo->conic;
        switch (tb__below(g, 4)) {
        case 0: /* ellipsoid */
            c->c[0] = 1.0, c->c[1] = 0.0, c->c[2] = -1.0;
            c->z0 = -1.0, c->z1 = 1.0;
            break;
        case 1: /* paraboloid, apex at z = 1 */
            c->c[0] = 0.5, c->c[1] = -0.5, c->c[2] = 0.0;
            c->z0 = -1.0, c->z1 = 1.0;
            break;
        case 2: /* hyperboloid of one sheet, waist sqrt(c0) */
            c->c[0] = tb__uq(g, 0.2, 0.8), c->c[1] = 0.0, c->c[2] = tb__uq(g, 0.2, 1.0);
            c->z0 = -1.0, c->z1 = 1.0;
            break;
        default: /* one sheet of a hyperboloid of two sheets: r^2 = z^2 - 0.25 */
            c->c[0] = -0.25, c->c[1] = 0.0, c->c[2] = 1.0;
            c->z0 = 0.6, c->z1 = 1.0;
            break;
        }
        c->caps = solid || tb__chance(g, 80);
        break;
    }
    case TB_PRIM_SQUARE_ARCH:
        geo->arch.width = tb__uq(g, 0.3, 1.7);
        geo->arch.height = tb__uq(g, 0.3, 1.9);
        break;
    case TB_PRIM_ROUND_ARCH:
        geo->arch.width = tb__uq(g, 0.3, 1.7);
        geo->arch.height = tb__uq(g, geo->arch.width / 2.0 + 0.05, 1.9);
        break;
    default: break; /* sphere, cube: no parameters */
    }
    return TB_OK;
}

/* Centre of grid cell i. */
static void tb__cell(const tb__gen *g, int64_t i, double *x, double *y)
{
    *x = ((double)(i % g->side) + 0.5) * TB__PITCH;
    *y = ((double)(i / g->side) + 0.5) * TB__PITCH;
}

/* ------------------------------------------------------------------ grid */

static tb_status tb__grid_object(tb__gen *g, int64_t i, tb_mid_object *o)
{
    tb_status st = tb__primitive(g, o, false);
    if (st)
        return st;
    tb__ops ops = {.n = 0};
    double x, y;
    tb__cell(g, i, &x, &y);
    tb__rotate_random(g, &ops);
    tb__scale_random(g, &ops, 0.5, 1.2);
    tb__translate(&ops, x, y, TB__Z);
    o->material = tb__random_material(g);
    return tb__place(g, o, &ops, NULL);
}

/* ------------------------------------------------------------------- csg */

/* A CSG node with `levels` levels of nodes below and including it (0: a
 * primitive leaf), placed under `parent` (NULL: top level). */
static tb_status tb__csg_node(tb__gen *g, tb_mid_object *o, int levels, bool first, const tb__ops *top,
                              const tb_transform *parent, const tb_mid_material *inherited)
{
    tb_status st;
    tb__ops ops = {.n = 0};
    if (top)
        ops = *top;
    else {
        /* Operands overlap around the parent's origin; a difference keeps its
         * first operand big and subtracts smaller ones. */
        tb__rotate_random(g, &ops);
        if (first)
            tb__scale_random(g, &ops, 0.8, 1.0);
        else
            tb__scale_random(g, &ops, 0.4, 0.8);
        tb__translate(&ops, tb__uq(g, -0.5, 0.5), tb__uq(g, -0.5, 0.5), tb__uq(g, -0.5, 0.5));
    }
    /* The tree's root names a material; 30% of the nodes below their own. */
    if (top || tb__chance(g, 30))
        o->material = tb__random_material(g);
    else
        o->material = tb__inherit(inherited);
    if (levels == 0)
        st = tb__primitive(g, o, true);
    else {
        static const tb_prim_kind ops_kinds[3] = {TB_PRIM_UNION, TB_PRIM_INTERSECTION, TB_PRIM_DIFFERENCE};
        o->kind = ops_kinds[tb__below(g, 3)];
        st = TB_OK;
    }
    if (st || (st = tb__place(g, o, &ops, parent)) || levels == 0)
        return st;
    int n = 2 + (int)tb__below(g, 2);
    tb_mid_object *ch = tb__alloc(g, (size_t)n * sizeof *ch);
    if (!ch)
        return TB_ERR_NOMEM;
    o->children = ch;
    o->nchildren = n;
    for (int c = 0; c < n; c++) {
        /* Below the top, a branch stops early in 30% of cases. */
        int sub = levels - 1;
        if (sub > 0 && tb__chance(g, 30))
            sub = 0;
        bool big = c == 0 || o->kind != TB_PRIM_DIFFERENCE;
        if ((st = tb__csg_node(g, &ch[c], sub, big, NULL, &o->to_world, &o->material)))
            return st;
    }
    return TB_OK;
}

static tb_status tb__csg_object(tb__gen *g, int64_t i, tb_mid_object *o)
{
    tb__ops ops = {.n = 0};
    double x, y;
    tb__cell(g, i, &x, &y);
    tb__rotate_random(g, &ops);
    tb__scale_random(g, &ops, 0.8, 1.2);
    tb__translate(&ops, x, y, TB__Z);
    return tb__csg_node(g, o, 1 + (int)tb__below(g, 3), true, &ops, NULL, NULL);
}

/* ------------------------------------------------------------------ mesh */

/* Corners of the icosahedron (before normalisation) and its 20 faces. */
static const double tb__ico_v[12][3] = {
    {-1, 1.6180339887498949, 0}, {1, 1.6180339887498949, 0}, {-1, -1.6180339887498949, 0},
    {1, -1.6180339887498949, 0}, {0, -1, 1.6180339887498949}, {0, 1, 1.6180339887498949},
    {0, -1, -1.6180339887498949}, {0, 1, -1.6180339887498949}, {1.6180339887498949, 0, -1},
    {1.6180339887498949, 0, 1}, {-1.6180339887498949, 0, -1}, {-1.6180339887498949, 0, 1},
};
static const int tb__ico_f[20][3] = {
    {0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
    {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
    {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1},
};

/* The index of the vertex at parameter t (0..f) from corner a toward corner
 * b of the geodesic sphere of frequency f (edges numbered by `edge`). */
static int tb__ico_edge_vertex(const int edge[12][12], int f, int a, int b, int t)
{
    if (t == 0)
        return a;
    if (t == f)
        return b;
    int lo = a < b ? a : b;
    int s = a == lo ? t : f - t; /* parameter from the lower-numbered corner */
    return 12 + edge[a][b] * (f - 1) + (s - 1);
}

/* Vertex (i, j) of face `face`: barycentric weights (f-i-j, i, j)/f of the
 * face's corners (A, B, C). */
static int tb__ico_index(const int edge[12][12], int f, int face, int i, int j)
{
    const int *c = tb__ico_f[face];
    int k = f - i - j;
    if (j == 0)
        return tb__ico_edge_vertex(edge, f, c[0], c[1], i);
    if (i == 0)
        return tb__ico_edge_vertex(edge, f, c[0], c[2], j);
    if (k == 0)
        return tb__ico_edge_vertex(edge, f, c[1], c[2], j);
    /* Interior: rows i = 1..f-2, row i holds j = 1..f-1-i. */
    int before = (i - 1) * (f - 1) - (i - 1) * i / 2;
    return 12 + 30 * (f - 1) + face * (f - 1) * (f - 2) / 2 + before + (j - 1);
}

/* (x, y, z) normalised, each component rounded to 4 decimals. */
static tb_vec3 tb__unit(double x, double y, double z)
{
    double n = sqrt(x * x + y * y + z * z);
    return (tb_vec3){tb__q4f(x / n), tb__q4f(y / n), tb__q4f(z / n)};
}

/* A geodesic sphere: the icosahedron with every face split into f^2
 * triangles, vertices pushed onto the unit sphere (shared, so the mesh is
 * closed; coordinates rounded to 4 decimals); normals are the vertex
 * directions. */
static tb_status tb__geodesic(tb__gen *g, tb_geom_polygons *p, int f)
{
    int nv = 10 * f * f + 2, nf = 20 * f * f;
    tb_vec3 *v = tb__alloc(g, (size_t)nv * sizeof *v);
    tb_vec3 *nrm = tb__alloc(g, (size_t)nv * sizeof *nrm);
    int *start = tb__alloc(g, (size_t)(nf + 1) * sizeof *start);
    int *idx = tb__alloc(g, (size_t)nf * 3 * sizeof *idx);
    if (!v || !nrm || !start || !idx)
        return TB_ERR_NOMEM;
    int edge[12][12];
    int ne = 0;
    memset(edge, -1, sizeof edge);
    for (int fc = 0; fc < 20; fc++)
        for (int e = 0; e < 3; e++) {
            int a = tb__ico_f[fc][e], b = tb__ico_f[fc][(e + 1) % 3];
            if (edge[a][b] < 0)
                edge[a][b] = edge[b][a] = ne++;
        }
    const double(*c)[3] = tb__ico_v;
    for (int a = 0; a < 12; a++)
        v[a] = tb__unit(c[a][0], c[a][1], c[a][2]);
    /* Edge vertices, each computed once from its lower-numbered corner. */
    for (int a = 0; a < 12; a++)
        for (int b = a + 1; b < 12; b++)
            if (edge[a][b] >= 0)
                for (int t = 1; t < f; t++) {
                    double s = (double)t / f;
                    v[tb__ico_edge_vertex(edge, f, a, b, t)] =
                        tb__unit(c[a][0] + s * (c[b][0] - c[a][0]), c[a][1] + s * (c[b][1] - c[a][1]),
                                 c[a][2] + s * (c[b][2] - c[a][2]));
                }
    int n = 0;
    for (int fc = 0; fc < 20; fc++) {
        const double *A = c[tb__ico_f[fc][0]], *B = c[tb__ico_f[fc][1]], *C = c[tb__ico_f[fc][2]];
        for (int i = 1; i < f; i++)
            for (int j = 1; i + j < f; j++) {
                double wa = (double)(f - i - j) / f, wb = (double)i / f, wc = (double)j / f;
                v[tb__ico_index(edge, f, fc, i, j)] = tb__unit(wa * A[0] + wb * B[0] + wc * C[0],
                                                               wa * A[1] + wb * B[1] + wc * C[1],
                                                               wa * A[2] + wb * B[2] + wc * C[2]);
            }
        /* Triangles keep the corner order, which runs counter-clockwise seen
         * from outside. */
        for (int i = 0; i < f; i++)
            for (int j = 0; i + j < f; j++) {
                int t[2][3] = {{tb__ico_index(edge, f, fc, i, j), tb__ico_index(edge, f, fc, i + 1, j),
                                tb__ico_index(edge, f, fc, i, j + 1)},
                               {0, 0, 0}};
                int cnt = 1;
                if (i + j + 1 < f) {
                    t[1][0] = tb__ico_index(edge, f, fc, i + 1, j);
                    t[1][1] = tb__ico_index(edge, f, fc, i + 1, j + 1);
                    t[1][2] = tb__ico_index(edge, f, fc, i, j + 1);
                    cnt = 2;
                }
                for (int q = 0; q < cnt; q++) {
                    start[n] = 3 * n;
                    memcpy(&idx[3 * n], t[q], sizeof t[q]);
                    n++;
                }
            }
    }
    start[nf] = 3 * nf;
    for (int a = 0; a < nv; a++)
        nrm[a] = v[a];
    p->nvertices = nv;
    p->vertices = v;
    p->normals = nrm;
    p->nfaces = nf;
    p->face_start = start;
    p->indices = idx;
    return TB_OK;
}

/* A height field over [-1,1]^2: m x m cells, two triangles each, facing +z;
 * height a sum of three random waves, with exact normals and (u, v). */
static tb_status tb__height_field(tb__gen *g, tb_geom_polygons *p, int m)
{
    int row = m + 1, nv = row * row, nf = 2 * m * m;
    tb_vec3 *v = tb__alloc(g, (size_t)nv * sizeof *v);
    tb_vec3 *nrm = tb__alloc(g, (size_t)nv * sizeof *nrm);
    tb_vec2 *uv = tb__alloc(g, (size_t)nv * sizeof *uv);
    int *start = tb__alloc(g, (size_t)(nf + 1) * sizeof *start);
    int *idx = tb__alloc(g, (size_t)nf * 3 * sizeof *idx);
    if (!v || !nrm || !uv || !start || !idx)
        return TB_ERR_NOMEM;
    double amp[3], fx[3], fy[3], ph[3];
    for (int k = 0; k < 3; k++) {
        amp[k] = tb__uni(g, 0.02, 0.15);
        fx[k] = tb__uni(g, -6.0, 6.0);
        fy[k] = tb__uni(g, -6.0, 6.0);
        ph[k] = tb__uni(g, 0.0, 2.0 * TB_PI);
    }
    for (int r = 0; r < row; r++)
        for (int c = 0; c < row; c++) {
            double x = -1.0 + 2.0 * c / m, y = -1.0 + 2.0 * r / m, z = 0.0, dx = 0.0, dy = 0.0;
            for (int k = 0; k < 3; k++) {
                double arg = fx[k] * x + fy[k] * y + ph[k];
                z += amp[k] * sin(arg);
                dx += amp[k] * fx[k] * cos(arg);
                dy += amp[k] * fy[k] * cos(arg);
            }
            int i = r * row + c;
            v[i] = (tb_vec3){tb__q4f(x), tb__q4f(y), tb__q4f(z)};
            nrm[i] = tb__unit(-dx, -dy, 1.0);
            uv[i] = (tb_vec2){tb__q4f((double)c / m), tb__q4f((double)r / m)};
        }
    int n = 0;
    for (int r = 0; r < m; r++)
        for (int c = 0; c < m; c++) {
            int a = r * row + c, b = a + 1, d = a + row, e = d + 1;
            /* a(x,y) b(x+1,y) e(x+1,y+1) d(x,y+1): counter-clockwise seen from +z. */
            int t[2][3] = {{a, b, e}, {a, e, d}};
            for (int q = 0; q < 2; q++) {
                start[n] = 3 * n;
                memcpy(&idx[3 * n], t[q], sizeof t[q]);
                n++;
            }
        }
    start[nf] = 3 * nf;
    p->nvertices = nv;
    p->vertices = v;
    p->normals = nrm;
    p->uvs = uv;
    p->nfaces = nf;
    p->face_start = start;
    p->indices = idx;
    return TB_OK;
}

static tb_status tb__mesh_object(tb__gen *g, int64_t i, tb_mid_object *o)
{
    o->kind = TB_PRIM_POLYGONS;
    o->geom = tb_mid_geometry_default(TB_PRIM_POLYGONS);
    tb_status st = tb__chance(g, 50) ? tb__geodesic(g, &o->geom.polygons, 2 + (int)tb__below(g, 9))
                                     : tb__height_field(g, &o->geom.polygons, 8 + (int)tb__below(g, 17));
    if (st)
        return st;
    tb__ops ops = {.n = 0};
    double x, y;
    tb__cell(g, i, &x, &y);
    ops.op[ops.n++] = (tb_mid_op){.kind = TB_MID_ROTATE, .v = {0, 0, 1, tb__uq(g, 0.0, 360.0)}};
    tb__scale_random(g, &ops, 1.0, 1.6);
    tb__translate(&ops, x, y, TB__Z);
    o->material = tb__random_material(g);
    return tb__place(g, o, &ops, NULL);
}

/* ------------------------------------------------------------ the scene */

static tb_status tb__emit(tb_gen_sink sink, void *user, tb_mid_item_type type, const void *p)
{
    tb_mid_item it;
    it.type = type;
    switch (type) {
    case TB_MID_ITEM_OBJECT: it.object = p; break;
    case TB_MID_ITEM_MATERIAL: it.material = p; break;
    case TB_MID_ITEM_LIGHT: it.light = p; break;
    case TB_MID_ITEM_CAMERA: it.camera = p; break;
    default: break;
    }
    return sink(user, &it);
}

/* Camera, lights and the palette. */
static tb_status tb__preamble(tb__gen *g, tb_gen_sink sink, void *user)
{
    double extent = (double)g->side * TB__PITCH, cx = extent / 2.0;
    tb_mid_camera cam = tb_mid_camera_default();
    cam.name = "overview";
    cam.look_at = (tb_dvec3){cx, cx, 0.0};
    cam.eye = (tb_dvec3){cx, cx - 1.1 * extent - 4.0, 0.9 * extent + 4.0};
    cam.up = (tb_dvec3){0.0, 0.0, 1.0};
    cam.fov = 50.0;
    cam.width = 1024;
    cam.height = 768;
    double dx = cam.look_at.x - cam.eye.x, dy = cam.look_at.y - cam.eye.y, dz = cam.look_at.z - cam.eye.z;
    cam.focus_distance = sqrt(dx * dx + dy * dy + dz * dz);
    tb_status st = tb__emit(sink, user, TB_MID_ITEM_CAMERA, &cam);
    if (st)
        return st;
    tb_mid_light sun = tb_mid_light_default(TB_LIGHT_DIRECTIONAL);
    sun.name = "sun";
    sun.direction = (tb_dvec3){-0.3, 0.5, -1.0};
    sun.intensity = tb__rgb(2.0f, 1.9f, 1.7f);
    if ((st = tb__emit(sink, user, TB_MID_ITEM_LIGHT, &sun)))
        return st;
    /* Intensity grows with the square of the height, so the grid gets about
     * 2 W/m^2 whatever its size. */
    tb_mid_light lamp = tb_mid_light_default(TB_LIGHT_POINT);
    lamp.name = "overhead";
    lamp.position = (tb_dvec3){cx, cx, extent + 10.0};
    float in = (float)(2.0 * (extent + 10.0) * (extent + 10.0));
    lamp.intensity = tb__rgb(in, in, in);
    if ((st = tb__emit(sink, user, TB_MID_ITEM_LIGHT, &lamp)))
        return st;
    for (int i = 0; i < TB__MAT_COUNT; i++)
        if ((st = tb__emit(sink, user, TB_MID_ITEM_MATERIAL, &g->mats[i])))
            return st;
    return TB_OK;
}

tb_status tb_generate(const tb_gen_options *opt, tb_gen_sink sink, void *user)
{
    if (!opt || !sink)
        return tb_error(TB_ERR_ARG, "tb_generate: NULL argument");
    if ((int)opt->kind < 0 || (int)opt->kind >= TB_GEN_KIND_COUNT)
        return tb_error(TB_ERR_ARG, "tb_generate: unknown kind %d", (int)opt->kind);
    if (opt->count < 0 || opt->count > TB_GEN_MAX_COUNT)
        return tb_error(TB_ERR_ARG, "tb_generate: count %lld is out of range (0 to %lld)", (long long)opt->count,
                        (long long)TB_GEN_MAX_COUNT);
    tb__gen g;
    memset(&g, 0, sizeof g);
    g.opt = *opt;
    tb_arena_init(&g.arena, 0);
    g.side = 1;
    while (g.side * g.side < opt->count)
        g.side++;
    tb__palette(&g);
    tb_status st = tb__preamble(&g, sink, user);
    for (int64_t i = 0; !st && i < opt->count; i++) {
        tb_rng_seed(&g.rng, tb__mix(opt->seed ^ tb__mix((uint64_t)i)), (uint64_t)opt->kind);
        tb_mid_object o;
        memset(&o, 0, sizeof o);
        o.material = tb_mid_material_default();
        switch (opt->kind) {
        case TB_GEN_GRID: st = tb__grid_object(&g, i, &o); break;
        case TB_GEN_CSG: st = tb__csg_object(&g, i, &o); break;
        case TB_GEN_MESH: st = tb__mesh_object(&g, i, &o); break;
        }
        if (g.nomem)
            st = tb_error(TB_ERR_NOMEM, "tb_generate: out of memory");
        else if (!st)
            st = tb__emit(sink, user, TB_MID_ITEM_OBJECT, &o);
        tb_arena_reset(&g.arena);
    }
    tb_arena_free(&g.arena);
    return st;
}

static tb_status tb__write_sink(void *user, const tb_mid_item *item)
{
    return tb_mid_write_item((FILE *)user, item);
}

tb_status tb_generate_write(FILE *fp, const tb_gen_options *opt)
{
    tb_status st = tb_mid_write_header(fp);
    if (!st)
        st = tb_generate(opt, tb__write_sink, fp);
    return st;
}
