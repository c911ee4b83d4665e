/* The cost model of testbed predict / calibrate (host/render/predict.h,
 * docs/predict.md): the terms, the statistics read from util/stats, the
 * pilot render, the evaluation, the fit and COSTS.json. */
#define _GNU_SOURCE /* mkstemps */
#include "host/render/predict.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "host/render/camera.h"
#include "host/render/pathtrace.h"
#include "util/base/outfile.h"
#include "util/image/image.h"
#include "util/stats/lsq.h"
#include "util/stats/stats.h"

const char *tb_predict_method_name(tb_predict_method m)
{
    static const char *const names[] = {"raytrace", "path", "radiosity"};
    return (unsigned)m < TB_PREDICT_METHOD_COUNT ? names[m] : "?";
}

const char *tb_pmodule_name(tb_pmodule m)
{
    static const char *const names[] = {"load", "build", "raytrace", "path", "radiosity", "process", "memory"};
    return (unsigned)m < TB_PM_COUNT ? names[m] : "?";
}

/* The model. Render terms are per method because the same ray costs
 * different work in each renderer (shading, sampling, film). */
static const tb_cost_term tb__terms[] = {
    {"load.parse_byte", TB_PM_LOAD, TB_PF_BYTES, "s/byte"},
    {"load.primitive", TB_PM_LOAD, TB_PF_PRIMS, "s/primitive"},
    {"load.csg_node", TB_PM_LOAD, TB_PF_CSG, "s/CSG node"},
    {"load.mesh", TB_PM_LOAD, TB_PF_MESHES, "s/polygons object"},
    {"load.triangle", TB_PM_LOAD, TB_PF_TRIANGLES, "s/triangle"},
    {"load.emitter_byte", TB_PM_LOAD, TB_PF_EMITTER_BYTES, "s/emitter byte"},
    {"load.emitter_face", TB_PM_LOAD, TB_PF_EMITTER_FACES, "s/emitter face"},
    {"load.csg_probe", TB_PM_LOAD, TB_PF_CSG_PROBES, "s/CSG probe ray"},
    {"load.fixed", TB_PM_LOAD, TB_PF_ONE, "s"},
    {"build.reference", TB_PM_BUILD, TB_PF_REFS, "s/reference"},
    {"build.reference_log", TB_PM_BUILD, TB_PF_REFS_LOG, "s/(reference log2 references)"},
    {"raytrace.sample", TB_PM_RAYTRACE, TB_PF_SAMPLES, "s/camera sample"},
    {"raytrace.ray", TB_PM_RAYTRACE, TB_PF_RAYS, "s/ray"},
    {"raytrace.occlusion_ray", TB_PM_RAYTRACE, TB_PF_OCC_RAYS, "s/occlusion ray"},
    {"raytrace.node", TB_PM_RAYTRACE, TB_PF_NODES, "s/BVH node visited"},
    {"raytrace.test_primitive", TB_PM_RAYTRACE, TB_PF_TESTS_PRIM, "s/test"},
    {"raytrace.test_torus", TB_PM_RAYTRACE, TB_PF_TESTS_TORUS, "s/test"},
    {"raytrace.test_csg", TB_PM_RAYTRACE, TB_PF_TESTS_CSG, "s/test"},
    {"raytrace.test_mesh", TB_PM_RAYTRACE, TB_PF_TESTS_MESH, "s/test"},
    {"raytrace.hit", TB_PM_RAYTRACE, TB_PF_HITS, "s/hit shaded"},
    {"raytrace.leaf_test", TB_PM_RAYTRACE, TB_PF_LEAF_TESTS, "s/reference tested"},
    {"raytrace.noise_octave", TB_PM_RAYTRACE, TB_PF_NOISE_OCTAVES, "s/noise octave (patterns, bump maps)"},
    {"raytrace.sample_channel", TB_PM_RAYTRACE, TB_PF_SAMPLE_CHANNELS, "s/(camera sample x channel)"},
    {"raytrace.hit_channel", TB_PM_RAYTRACE, TB_PF_HIT_CHANNELS, "s/(hit x channel)"},
    {"path.sample", TB_PM_PATH, TB_PF_SAMPLES, "s/camera sample"},
    {"path.ray", TB_PM_PATH, TB_PF_RAYS, "s/ray"},
    {"path.occlusion_ray", TB_PM_PATH, TB_PF_OCC_RAYS, "s/occlusion ray"},
    {"path.node", TB_PM_PATH, TB_PF_NODES, "s/BVH node visited"},
    {"path.test_primitive", TB_PM_PATH, TB_PF_TESTS_PRIM, "s/test"},
    {"path.test_torus", TB_PM_PATH, TB_PF_TESTS_TORUS, "s/test"},
    {"path.test_csg", TB_PM_PATH, TB_PF_TESTS_CSG, "s/test"},
    {"path.test_mesh", TB_PM_PATH, TB_PF_TESTS_MESH, "s/test"},
    {"path.hit", TB_PM_PATH, TB_PF_HITS, "s/hit shaded"},
    {"path.leaf_test", TB_PM_PATH, TB_PF_LEAF_TESTS, "s/reference tested"},
    {"path.noise_octave", TB_PM_PATH, TB_PF_NOISE_OCTAVES, "s/noise octave (patterns, bump maps)"},
    {"path.sample_channel", TB_PM_PATH, TB_PF_SAMPLE_CHANNELS, "s/(camera sample x channel)"},
    {"path.hit_channel", TB_PM_PATH, TB_PF_HIT_CHANNELS, "s/(hit x channel)"},
    {"radiosity.ray", TB_PM_RADIOSITY, TB_PF_RAD_RAYS, "s/form-factor ray"},
    {"radiosity.form_factor", TB_PM_RADIOSITY, TB_PF_RAD_FFS, "s/form factor"},
    {"radiosity.shot_element", TB_PM_RADIOSITY, TB_PF_RAD_SHOT_ELEMS, "s/(shot x element)"},
    {"radiosity.element", TB_PM_RADIOSITY, TB_PF_RAD_ELEMENTS, "s/element"},
    {"radiosity.occlusion_ray", TB_PM_RADIOSITY, TB_PF_RAD_OCC_RAYS, "s/form-factor ray through the BVH"},
    {"radiosity.node", TB_PM_RADIOSITY, TB_PF_RAD_NODES, "s/BVH node visited"},
    {"radiosity.shaft_test", TB_PM_RADIOSITY, TB_PF_RAD_SHAFT_TESTS, "s/(ray x shaft occluder)"},
    {"radiosity.csg_probe", TB_PM_RADIOSITY, TB_PF_RAD_MESH_PROBES, "s/CSG probe ray"},
    {"process.raytrace", TB_PM_PROCESS, TB_PF_IS_RAYTRACE, "s"},
    {"process.path", TB_PM_PROCESS, TB_PF_IS_PATH, "s"},
    {"process.radiosity", TB_PM_PROCESS, TB_PF_IS_RADIOSITY, "s"},
    {"process.pixel", TB_PM_PROCESS, TB_PF_PIXELS, "s/pixel"},
    {"process.pixel_channel", TB_PM_PROCESS, TB_PF_PIXEL_CHANNELS, "s/(pixel x channel)"},
    {"process.image_byte", TB_PM_PROCESS, TB_PF_IMAGE_BYTES, "s/PNG byte (estimated at 1/4 resolution)"},
    {"process.radiosity_pixel_ray", TB_PM_PROCESS, TB_PF_RAD_PIXEL_RAYS, "s/image ray"},
    {"process.vulkan_probe", TB_PM_PROCESS, TB_PF_VULKAN_PROBE, "s (loading and asking the Vulkan driver)"},
    {"process.radiosity_pixel_node", TB_PM_PROCESS, TB_PF_RAD_PIXEL_NODES, "s/image ray's BVH node visited"},
    {"process.radiosity_pixel_leaf_test", TB_PM_PROCESS, TB_PF_RAD_PIXEL_LEAF_TESTS, "s/element an image ray tested"},
    {"memory.raytrace", TB_PM_MEMORY, TB_PF_IS_RAYTRACE, "bytes"},
    {"memory.path", TB_PM_MEMORY, TB_PF_IS_PATH, "bytes"},
    {"memory.radiosity", TB_PM_MEMORY, TB_PF_IS_RADIOSITY, "bytes"},
    {"memory.object_byte", TB_PM_MEMORY, TB_PF_MEM_OBJECTS, "bytes/accounted byte"},
    {"memory.mesh_byte", TB_PM_MEMORY, TB_PF_MEM_MESHES, "bytes/accounted byte"},
    {"memory.emitter_byte", TB_PM_MEMORY, TB_PF_MEM_EMITTERS, "bytes/accounted byte"},
    {"memory.accel_byte", TB_PM_MEMORY, TB_PF_MEM_ACCEL, "bytes/accounted byte"},
    {"memory.vulkan_probe", TB_PM_MEMORY, TB_PF_VULKAN_PROBE, "bytes (the Vulkan driver's libraries)"},
    {"memory.film_byte", TB_PM_MEMORY, TB_PF_FILM_BYTES, "bytes/(pixel x channel x 4)"},
    {"memory.pixel", TB_PM_MEMORY, TB_PF_PIXELS, "bytes/pixel (the images made from the film)"},
    {"memory.element", TB_PM_MEMORY, TB_PF_RAD_ELEMENTS, "bytes/element"},
    {"memory.vertex", TB_PM_MEMORY, TB_PF_RAD_VERTICES, "bytes/vertex"},
    {"memory.form_factor_cache_byte", TB_PM_MEMORY, TB_PF_RAD_CACHE_BYTES, "bytes/cached byte"},
};

#define TB__NTERMS ((int)(sizeof tb__terms / sizeof tb__terms[0]))
_Static_assert(sizeof tb__terms / sizeof tb__terms[0] <= TB_COST_MAX_TERMS, "raise TB_COST_MAX_TERMS");

const tb_cost_term *tb_cost_terms(int *n)
{
    *n = TB__NTERMS;
    return tb__terms;
}

/* ------------------------------------------------------------------ statistics */

const char *tb_pfeat_name(tb_pfeat k)
{
    static const char *const fname[] = {
        "bytes", "primitives", "csg_nodes", "meshes", "triangles", "emitter_bytes", "emitter_faces", "csg_probes",
        "references",
        "references_log2", "camera_samples", "rays", "occlusion_rays", "bvh_nodes", "tests_primitive", "tests_torus",
        "tests_csg", "tests_mesh", "hits", "leaf_tests", "noise_octaves", "sample_channels", "hit_channels", "pixel_channels",
        "pixels", "image_bytes", "rad_rays", "rad_form_factors", "rad_shot_elements", "rad_elements", "rad_occlusion_rays", "rad_nodes",
        "rad_shaft_tests", "rad_vertices", "rad_pixel_rays", "rad_pixel_nodes", "rad_pixel_leaf_tests", "rad_mesh_probes", "rad_cache_bytes", "mem_objects", "mem_meshes", "mem_emitters",
        "mem_accel", "film_bytes", "vulkan_probe", "is_raytrace", "is_path", "is_radiosity", "one"};
    _Static_assert(sizeof fname / sizeof fname[0] == TB_PF_COUNT, "a name per statistic");
    return (unsigned)k < TB_PF_COUNT ? fname[k] : "?";
}

/* A counter's or memory figure's total, 0 if it is not registered. */
static double tb__stat(const char *name, tb_stat_kind kind)
{
    tb_stat_total t;
    if (tb_stats_get(name, kind, &t) != TB_OK) {
        tb_clear_error();
        return 0.0;
    }
    return (double)t.v[0];
}

static double tb__count(const char *name) { return (double)tb_stats_counter(name); }

static double tb__value(const char *key)
{
    double v;
    if (tb_stats_get_value(key, &v) != TB_OK) {
        tb_clear_error();
        return 0.0;
    }
    return v;
}

/* Analytic kinds (every kind but polygons and the CSG operators), as the counters name them. */
static const char *const tb__prim_kinds[] = {"sphere", "cube", "cylinder", "cone", "pyramid",
                                             "prism", "torus", "conic", "square_arch", "round_arch"};
static const char *const tb__csg_kinds[] = {"union", "intersection", "difference"};

void tb_predict_stats_init(tb_predict_stats *f, tb_predict_method m, double file_bytes, int width, int height,
                           int nchannels, int rad_spp, int threads)
{
    memset(f, 0, sizeof *f);
    f->method = m;
    f->threads = threads;
    f->f[TB_PF_BYTES] = file_bytes;
    double px = (double)width * (double)height;
    f->f[TB_PF_PIXELS] = px;
    f->f[TB_PF_FILM_BYTES] = px * (double)nchannels * 4.0;
    f->f[TB_PF_PIXEL_CHANNELS] = px * (double)nchannels;
    f->channels = nchannels;
    /* the radiosity image traces a side x side grid per pixel, side = ceil(sqrt(spp)) (display.c) */
    double side = ceil(sqrt((double)(rad_spp > 0 ? rad_spp : 0)));
    f->f[TB_PF_RAD_PIXEL_RAYS] = m == TB_PREDICT_RADIOSITY ? px * side * side : 0.0;
    f->f[TB_PF_IS_RAYTRACE] = m == TB_PREDICT_RAYTRACE;
    f->f[TB_PF_IS_PATH] = m == TB_PREDICT_PATH;
    f->f[TB_PF_IS_RADIOSITY] = m == TB_PREDICT_RADIOSITY;
    f->f[TB_PF_ONE] = 1.0;
}

void tb_predict_stats_add_scene(tb_predict_stats *f)
{
    char name[64];
    for (size_t k = 0; k < sizeof tb__prim_kinds / sizeof tb__prim_kinds[0]; k++) {
        snprintf(name, sizeof name, "Scene/%s objects", tb__prim_kinds[k]);
        f->f[TB_PF_PRIMS] += tb__count(name);
    }
    for (size_t k = 0; k < sizeof tb__csg_kinds / sizeof tb__csg_kinds[0]; k++) {
        snprintf(name, sizeof name, "Scene/%s objects", tb__csg_kinds[k]);
        f->f[TB_PF_CSG] += tb__count(name);
    }
    double meshes = tb__count("Scene/polygons objects"), tris = tb__count("Scene/triangle references");
    f->f[TB_PF_MESHES] += meshes;
    f->f[TB_PF_TRIANGLES] += tris;
    f->f[TB_PF_REFS] += tb__count("Scene/references");
    f->f[TB_PF_EMITTER_FACES] += tb__count("Polygonize/faces made");
    /* radiosity makes no emitters: its CSG probes are the meshing's */
    f->f[f->method == TB_PREDICT_RADIOSITY ? TB_PF_RAD_MESH_PROBES : TB_PF_CSG_PROBES] +=
        tb__count("Polygonize/CSG probes");
    f->f[TB_PF_REFS_LOG] = f->f[TB_PF_REFS] * log2(f->f[TB_PF_REFS] + 1.0);
    double total = tb__stat("Scene/memory", TB_STAT_KIND_MEMORY);
    double mesh = tb__stat("Scene/memory of meshes", TB_STAT_KIND_MEMORY);
    double emit = tb__stat("Scene/memory of emitters", TB_STAT_KIND_MEMORY);
    double accel = tb__stat("Scene/memory of acceleration", TB_STAT_KIND_MEMORY);
    f->f[TB_PF_EMITTER_BYTES] += emit;
    f->f[TB_PF_MEM_MESHES] += mesh;
    f->f[TB_PF_MEM_EMITTERS] += emit;
    f->f[TB_PF_MEM_ACCEL] += accel;
    f->f[TB_PF_MEM_OBJECTS] += fmax(0.0, total - mesh - emit - accel);
}

void tb_predict_stats_add_work(tb_predict_stats *f, double scale)
{
    char name[64];
    f->f[TB_PF_SAMPLES] += scale * tb__count("Antialias/camera samples");
    f->f[TB_PF_RAYS] += scale * tb__count("BVH/rays");
    f->f[TB_PF_OCC_RAYS] += scale * tb__count("BVH/occlusion rays");
    f->f[TB_PF_NODES] += scale * tb__count("BVH/nodes visited");
    for (size_t k = 0; k < sizeof tb__prim_kinds / sizeof tb__prim_kinds[0]; k++) {
        snprintf(name, sizeof name, "Intersect/%s", tb__prim_kinds[k]);
        f->f[strcmp(tb__prim_kinds[k], "torus") ? TB_PF_TESTS_PRIM : TB_PF_TESTS_TORUS] += scale * tb__count(name);
    }
    for (size_t k = 0; k < sizeof tb__csg_kinds / sizeof tb__csg_kinds[0]; k++) {
        snprintf(name, sizeof name, "Intersect/%s", tb__csg_kinds[k]);
        f->f[TB_PF_TESTS_CSG] += scale * tb__count(name);
    }
    f->f[TB_PF_TESTS_MESH] += scale * tb__count("Intersect/polygons");
    f->f[TB_PF_HITS] += scale * tb__count("Surface/hits shaded");
    f->f[TB_PF_LEAF_TESTS] += scale * tb__count("BVH/primitives tested");
    f->f[TB_PF_NOISE_OCTAVES] += scale * tb__count("Pattern/noise octaves");
    double ch = f->channels > 0 ? f->channels : 3.0;
    f->f[TB_PF_SAMPLE_CHANNELS] = f->f[TB_PF_SAMPLES] * ch;
    f->f[TB_PF_HIT_CHANNELS] = f->f[TB_PF_HITS] * ch;
    if (f->method == TB_PREDICT_RADIOSITY) {
        /* the radiosity image's rays are a term of their own (process); the
         * form factors trace occlusion rays only, the image closest-hit rays */
        double occ = tb__count("BVH/occlusion rays"), img = tb__count("BVH/rays");
        double nodes = tb__count("BVH/nodes visited"), img_nodes = tb__value(TB_RAD_IMAGE_NODES_KEY);
        f->f[TB_PF_RAD_OCC_RAYS] += scale * occ;
        if (img_nodes > 0 && img_nodes <= nodes) { /* the render measured the image's share */
            f->f[TB_PF_RAD_NODES] += scale * (nodes - img_nodes);
            f->f[TB_PF_RAD_PIXEL_NODES] += scale * img_nodes;
            f->f[TB_PF_RAD_PIXEL_LEAF_TESTS] += scale * tb__value(TB_RAD_IMAGE_LEAF_KEY);
        } else if (occ > 0) {
            f->f[TB_PF_RAD_NODES] += scale * nodes * occ / (occ + img);
        }
        f->f[TB_PF_SAMPLES] = f->f[TB_PF_RAYS] = f->f[TB_PF_OCC_RAYS] = f->f[TB_PF_NODES] = 0.0;
        f->f[TB_PF_TESTS_PRIM] = f->f[TB_PF_TESTS_TORUS] = f->f[TB_PF_TESTS_CSG] = f->f[TB_PF_TESTS_MESH] = 0.0;
        f->f[TB_PF_HITS] = 0.0;
        f->f[TB_PF_LEAF_TESTS] = f->f[TB_PF_SAMPLE_CHANNELS] = f->f[TB_PF_HIT_CHANNELS] = 0.0;
        f->f[TB_PF_NOISE_OCTAVES] = 0.0;
        double rays = scale * tb__count("Radiosity/rays (receivers x samples)");
        double shafts = tb__count("Form factors/shafts");
        f->f[TB_PF_RAD_RAYS] += rays;
        if (shafts > 0)
            f->f[TB_PF_RAD_SHAFT_TESTS] += rays * tb__count("Form factors/occluders listed in shafts") / shafts;
        f->f[TB_PF_RAD_FFS] += scale * tb__count("Radiosity/form factors");
        double shots = tb__value("shots"), elems = tb__value("elements");
        f->rad_shots = shots;
        f->f[TB_PF_RAD_ELEMENTS] = elems;
        f->f[TB_PF_RAD_VERTICES] = tb__value("vertices");
        f->f[TB_PF_RAD_SHOT_ELEMS] = shots * elems;
        /* the solver keeps each shooter's form factors, floats over vertices and elements, up to 512 MiB */
        double distinct = fmax(0.0, shots - tb__count("Radiosity/shots from cached form factors"));
        f->f[TB_PF_RAD_CACHE_BYTES] = fmin((double)(512u << 20), distinct * (f->f[TB_PF_RAD_VERTICES] + elems) * 4.0);
    }
}

void tb_predict_stats_sub_work(tb_predict_stats *f, const tb_predict_stats *load)
{
    static const tb_pfeat work[] = {TB_PF_SAMPLES,    TB_PF_RAYS,      TB_PF_OCC_RAYS, TB_PF_NODES,
                                    TB_PF_TESTS_PRIM, TB_PF_TESTS_TORUS, TB_PF_TESTS_CSG, TB_PF_TESTS_MESH,
                                    TB_PF_HITS,       TB_PF_LEAF_TESTS,  TB_PF_NOISE_OCTAVES};
    for (size_t i = 0; i < sizeof work / sizeof work[0]; i++)
        f->f[work[i]] = fmax(0.0, f->f[work[i]] - load->f[work[i]]);
    double ch = f->channels > 0 ? f->channels : 3.0;
    f->f[TB_PF_SAMPLE_CHANNELS] = f->f[TB_PF_SAMPLES] * ch;
    f->f[TB_PF_HIT_CHANNELS] = f->f[TB_PF_HITS] * ch;
}

/* ------------------------------------------------------------------ pilot */

tb_status tb_predict_scene(const char *path, const tb_predict_options *o, tb_predict_stats *f)
{
    if (o->method != TB_PREDICT_RAYTRACE && o->method != TB_PREDICT_PATH)
        return tb_error(TB_ERR_ARG, "predict: tb_predict_scene handles raytrace and path, not %s",
                        tb_predict_method_name(o->method));
    if (o->pilot_divisor < 1)
        return tb_error(TB_ERR_ARG, "predict: the pilot divisor must be >= 1, not %d", o->pilot_divisor);
    struct stat sb;
    if (stat(path, &sb) != 0)
        return tb_error(TB_ERR_IO, "%s: %s", path, strerror(errno));
    int saved = tb_stats_enabled();
    tb_stats_set_enabled(1);
    tb_stats_reset();
    tb_scene_options so = {.accel = o->accel, .threads = o->render.threads};
    tb_scene *s = NULL;
    tb_status st = tb_scene_load(path, &so, &s);
    if (st) {
        tb_stats_set_enabled(saved);
        return st;
    }
    const int W = s->camera.width, H = s->camera.height;
    tb_predict_stats_init(f, o->method, (double)sb.st_size, W, H, s->nchannels, 0, o->render.threads);
    tb_predict_stats_add_scene(f);
    f->f[TB_PF_VULKAN_PROBE] = o->vulkan_probe && o->vulkan_probe(s, o->vulkan_probe_user) ? 1.0 : 0.0;
    /* the pilot: the same render over a sparse, regular subset of the image */
    int pw = W / o->pilot_divisor, ph = H / o->pilot_divisor;
    pw = pw < 1 ? 1 : pw, ph = ph < 1 ? 1 : ph;
    tb_camera full = s->camera;
    st = tb_camera_from_mid(&s->mid_camera, pw, ph, &s->camera);
    int64_t t0 = tb_stats_now_ns();
    tb_stats_reset();
    tb_render_options ro = o->render;
    ro.progress = false;
    ro.on_pass = NULL;
    ro.sample_counts = NULL;
    ro.exchange = NULL;
    ro.persist = NULL;
    ro.cancel = NULL;
    ro.time_budget = 0;
    tb_image *img = NULL;
    if (!st) {
        if (o->method == TB_PREDICT_PATH)
            st = tb_render_path(s, o->path_options, &ro, &img, NULL);
        else
            st = tb_render_raytrace(s, &ro, &img, NULL);
    }
    f->pilot_seconds = 1e-9 * (double)(tb_stats_now_ns() - t0);
    double px_ratio = (double)W * (double)H / ((double)pw * (double)ph);
    if (!st)
        tb_predict_stats_add_work(f, px_ratio);
    if (!st) /* the pilot's image is the render's at 1/D each way: its PNG's bytes stand for the image's */
        st = tb_predict_image_bytes(img, 1, true, px_ratio, &f->f[TB_PF_IMAGE_BYTES]);
    tb_image_free(img);
    s->camera = full;
    tb_scene_free(s);
    tb_stats_reset();
    tb_stats_set_enabled(saved);
    return st;
}

tb_status tb_predict_image_bytes(const tb_image *img, int step, bool expose, double scale, double *bytes)
{
    *bytes = 0.0;
    if (!img || step < 1)
        return tb_error(TB_ERR_ARG, "predict: no image, or a step < 1");
    int w = (img->width + step - 1) / step, h = (img->height + step - 1) / step, nc = img->channels;
    tb_image *sub = tb_image_create(w, h, nc, NULL);
    if (!sub)
        return TB_ERR_NOMEM;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            memcpy(sub->pixels + ((size_t)y * (size_t)w + (size_t)x) * (size_t)nc,
                   img->pixels + ((size_t)y * (size_t)step * (size_t)img->width + (size_t)x * (size_t)step) * (size_t)nc,
                   sizeof(float) * (size_t)nc);
    const char *tmp = getenv("TMPDIR");
    char path[1024];
    snprintf(path, sizeof path, "%s/testbed-predict-XXXXXX.png", tmp && *tmp ? tmp : "/tmp");
    int fd = mkstemps(path, 4);
    if (fd < 0) {
        tb_image_free(sub);
        return tb_error(TB_ERR_IO, "predict: a temporary file in %s: %s", tmp && *tmp ? tmp : "/tmp", strerror(errno));
    }
    close(fd);
    tb_status st = tb_image_write_exposed(path, sub, expose ? NAN : 0.0);
    struct stat sb;
    if (!st && stat(path, &sb) == 0)
        *bytes = (double)sb.st_size * scale;
    unlink(path);
    tb_image_free(sub);
    return st;
}

/* ------------------------------------------------------------------ evaluation */

/* Threads that run at once: the request (0: OpenMP's default) capped at the processors. */
static double tb__eff_threads(int threads)
{
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    int t = threads > 0 ? threads : omp_get_max_threads();
    if (cores > 0 && t > cores)
        t = (int)cores;
    return t < 1 ? 1.0 : (double)t;
}

void tb_predict_eval(const tb_costs *c, const tb_predict_stats *f, tb_prediction *out)
{
    memset(out, 0, sizeof *out);
    double speed = tb__eff_threads(c->threads) / tb__eff_threads(f->threads);
    for (int i = 0; i < TB__NTERMS; i++) {
        const tb_cost_term *t = &tb__terms[i];
        /* a renderer's terms count only for its own method */
        if ((t->module == TB_PM_RAYTRACE && f->method != TB_PREDICT_RAYTRACE) ||
            (t->module == TB_PM_PATH && f->method != TB_PREDICT_PATH) ||
            (t->module == TB_PM_RADIOSITY && f->method != TB_PREDICT_RADIOSITY))
            continue;
        bool parallel = t->module == TB_PM_BUILD || t->module == TB_PM_RAYTRACE || t->module == TB_PM_PATH ||
                        t->module == TB_PM_RADIOSITY;
        double v = c->c[i] * f->f[t->feature] * (parallel ? speed : 1.0);
        out->term[i] = v;
        out->module[t->module] += v;
    }
    for (int m = 0; m < TB_PM_COUNT; m++)
        if (m != TB_PM_MEMORY)
            out->seconds += out->module[m];
    out->peak_rss_bytes = out->module[TB_PM_MEMORY];
}

/* ------------------------------------------------------------------ fit */

/* Relative errors beyond this many robust standard deviations are down-weighted (Huber's k). */
#define TB__HUBER 2.0

static int tb__cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

tb_status tb_costs_fit(const tb_predict_stats *f, const tb_predict_measured *y, int n, int threads, tb_costs *out)
{
    if (n < 1)
        return tb_error(TB_ERR_ARG, "calibrate: no runs to fit");
    memset(out, 0, sizeof *out);
    out->threads = threads;
    double *A = malloc(sizeof *A * (size_t)n * TB_COST_MAX_TERMS), *b = malloc(sizeof *b * (size_t)n);
    double *w = malloc(sizeof *w * (size_t)n), *w0 = malloc(sizeof *w0 * (size_t)n);
    if (!A || !b || !w || !w0) {
        free(A), free(b), free(w), free(w0);
        return tb_error(TB_ERR_NOMEM, "calibrate: out of memory");
    }
    tb_status st = TB_OK;
    for (int m = 0; m < TB_PM_COUNT && !st; m++) {
        int idx[TB_COST_MAX_TERMS], k = 0, rows = 0;
        for (int i = 0; i < TB__NTERMS; i++)
            if (tb__terms[i].module == (tb_pmodule)m)
                idx[k++] = i;
        for (int r = 0; r < n; r++) {
            /* a render module is fitted on its method's runs only */
            bool use = (m != TB_PM_RAYTRACE || f[r].method == TB_PREDICT_RAYTRACE) &&
                       (m != TB_PM_PATH || f[r].method == TB_PREDICT_PATH) &&
                       (m != TB_PM_RADIOSITY || f[r].method == TB_PREDICT_RADIOSITY) &&
                       (m != TB_PM_BUILD || f[r].method != TB_PREDICT_RADIOSITY); /* radiosity builds no BVH */
            double yv = y[r].module[m];
            if (!use || !(yv > 0.0) || !isfinite(yv))
                continue;
            for (int j = 0; j < k; j++)
                A[(size_t)rows * (size_t)k + (size_t)j] = f[r].f[tb__terms[idx[j]].feature];
            b[rows] = yv;
            w[rows] = w0[rows] = 1.0 / yv; /* relative errors: small and large runs count alike */
            rows++;
        }
        if (!rows)
            continue;
        double x[TB_COST_MAX_TERMS];
        tb_lsq_info info;
        if ((st = tb_lsq_fit(A, b, w, rows, k, TB_LSQ_NONNEG, x, &info)))
            break;
        /* Huber reweighting: a run slowed by other jobs on a shared
         * machine (2-5 times its time) would pull every cost of its module;
         * runs whose relative error is beyond TB__HUBER x the robust scale
         * (1.4826 x the median absolute relative error) count less, in
         * proportion, and the fit is redone (a few rounds). */
        for (int round = 0; round < 4 && rows > k; round++) {
            double *res = malloc(sizeof *res * (size_t)rows * 2);
            if (!res) {
                st = tb_error(TB_ERR_NOMEM, "calibrate: out of memory");
                break;
            }
            for (int r = 0; r < rows; r++) {
                double fit = 0.0;
                for (int j = 0; j < k; j++)
                    fit += A[(size_t)r * (size_t)k + (size_t)j] * x[j];
                res[r] = (fit - b[r]) / b[r];
                res[rows + r] = fabs(res[r]);
            }
            qsort(res + rows, (size_t)rows, sizeof *res, tb__cmp_double);
            double scale = 1.4826 * res[rows + rows / 2], lim = TB__HUBER * fmax(scale, 0.02);
            bool changed = false;
            for (int r = 0; r < rows; r++) {
                double wr = fabs(res[r]) > lim ? lim / fabs(res[r]) : 1.0;
                changed |= fabs(wr * w0[r] - w[r]) > 1e-3 * w0[r];
                w[r] = wr * w0[r];
            }
            free(res);
            if (!changed || (st = tb_lsq_fit(A, b, w, rows, k, TB_LSQ_NONNEG, x, &info)))
                break;
        }
        if (st)
            break;
        double ss = 0.0; /* the relative RMS error over every run, down-weighted or not */
        for (int r = 0; r < rows; r++) {
            double fit = 0.0;
            for (int j = 0; j < k; j++)
                fit += A[(size_t)r * (size_t)k + (size_t)j] * x[j];
            ss += (fit - b[r]) * (fit - b[r]) / (b[r] * b[r]);
        }
        for (int j = 0; j < k; j++)
            out->c[idx[j]] = x[j];
        out->fit[m].rows = rows;
        out->fit[m].rel_rms = sqrt(ss / rows);
    }
    free(A), free(b), free(w), free(w0);
    return st;
}

/* ------------------------------------------------------------------ COSTS.json */

tb_status tb_costs_write(const char *path, const tb_costs *c)
{
    tb_outfile of;
    tb_status st = tb_outfile_open(&of, path);
    if (st)
        return st;
    FILE *fp = of.fp;
    fprintf(fp, "{\n  \"schema\": \"" TB_COSTS_SCHEMA "\",\n  \"cpu\": ");
    tb_json_write_string(fp, c->cpu);
    fprintf(fp, ",\n  \"created_utc\": ");
    tb_json_write_string(fp, c->created);
    fprintf(fp, ",\n  \"threads\": %d,\n  \"costs\": {\n", c->threads);
    for (int i = 0; i < TB__NTERMS; i++)
        fprintf(fp, "    \"%s\": %.17g%s\n", tb__terms[i].name, c->c[i], i + 1 < TB__NTERMS ? "," : "");
    fprintf(fp, "  },\n  \"units\": {\n");
    for (int i = 0; i < TB__NTERMS; i++)
        fprintf(fp, "    \"%s\": \"%s\"%s\n", tb__terms[i].name, tb__terms[i].unit, i + 1 < TB__NTERMS ? "," : "");
    fprintf(fp, "  },\n  \"fit\": {\n");
    for (int m = 0; m < TB_PM_COUNT; m++)
        fprintf(fp, "    \"%s\": {\"rows\": %d, \"rel_rms\": %.6g}%s\n", tb_pmodule_name((tb_pmodule)m), c->fit[m].rows,
                isfinite(c->fit[m].rel_rms) ? c->fit[m].rel_rms : 0.0, m + 1 < TB_PM_COUNT ? "," : "");
    fprintf(fp, "  }\n}\n");
    if (ferror(fp)) {
        tb_outfile_abort(&of);
        return tb_error(TB_ERR_IO, "%s: write error", path);
    }
    return tb_outfile_commit(&of);
}

/* A small JSON reader for COSTS.json: enough of RFC 8259 to read any valid
 * document (objects, arrays, strings with escapes, numbers, literals) and
 * say where a bad one goes wrong. */
typedef struct tb__json {
    const char *s, *p, *path;
    char msg[256];
} tb__json;

static tb_status tb__jerr(tb__json *j, const char *what)
{
    int line = 1, col = 1;
    for (const char *q = j->s; q < j->p; q++)
        if (*q == '\n')
            line++, col = 1;
        else
            col++;
    return tb_error(TB_ERR_FORMAT, "%s:%d:%d: error: %s", j->path, line, col, what);
}

static void tb__jws(tb__json *j)
{
    while (*j->p == ' ' || *j->p == '\t' || *j->p == '\n' || *j->p == '\r')
        j->p++;
}

/* Reads a string into buf (truncated to n - 1 bytes; \u escapes other than ASCII become '?'). */
static tb_status tb__jstring(tb__json *j, char *buf, size_t n)
{
    if (*j->p != '"')
        return tb__jerr(j, "expected a string");
    j->p++;
    size_t k = 0;
    while (*j->p != '"') {
        char ch = *j->p;
        if (!ch || (unsigned char)ch < 0x20)
            return tb__jerr(j, "unterminated string");
        if (ch == '\\') {
            j->p++;
            const char *esc = strchr("\"\\/bfnrtu", *j->p);
            if (!*j->p || !esc)
                return tb__jerr(j, "bad escape in a string");
            ch = *j->p == 'n' ? '\n' : *j->p == 't' ? '\t' : *j->p;
            if (*j->p == 'u') {
                for (int d = 1; d <= 4; d++)
                    if (!isxdigit((unsigned char)j->p[d]))
                        return tb__jerr(j, "bad \\u escape in a string");
                unsigned v = (unsigned)strtoul((char[]){j->p[1], j->p[2], j->p[3], j->p[4], 0}, NULL, 16);
                ch = v < 0x80 ? (char)v : '?';
                j->p += 4;
            }
        }
        if (k + 1 < n)
            buf[k++] = ch;
        j->p++;
    }
    j->p++;
    if (n)
        buf[k] = 0;
    return TB_OK;
}

static tb_status tb__jnumber(tb__json *j, double *v)
{
    const char *q = j->p;
    if (*q == '-')
        q++;
    if (!isdigit((unsigned char)*q))
        return tb__jerr(j, "expected a number");
    char *end;
    errno = 0;
    *v = strtod(j->p, &end);
    if (end == j->p || errno == ERANGE)
        return tb__jerr(j, "number out of range");
    j->p = end;
    return TB_OK;
}

/* Skips any value. */
static tb_status tb__jskip(tb__json *j, int depth)
{
    tb__jws(j);
    if (depth > 64)
        return tb__jerr(j, "nested too deeply");
    char c = *j->p;
    if (c == '"')
        return tb__jstring(j, NULL, 0);
    if (c == '{' || c == '[') {
        char close = c == '{' ? '}' : ']';
        j->p++;
        tb__jws(j);
        if (*j->p == close) {
            j->p++;
            return TB_OK;
        }
        for (;;) {
            tb_status st;
            if (c == '{') {
                tb__jws(j);
                if ((st = tb__jstring(j, NULL, 0)))
                    return st;
                tb__jws(j);
                if (*j->p != ':')
                    return tb__jerr(j, "expected ':'");
                j->p++;
            }
            if ((st = tb__jskip(j, depth + 1)))
                return st;
            tb__jws(j);
            if (*j->p == ',') {
                j->p++;
                continue;
            }
            if (*j->p == close) {
                j->p++;
                return TB_OK;
            }
            return tb__jerr(j, c == '{' ? "expected ',' or '}'" : "expected ',' or ']'");
        }
    }
    for (const char *lit = "true\0false\0null\0"; *lit; lit += strlen(lit) + 1)
        if (strncmp(j->p, lit, strlen(lit)) == 0) {
            j->p += strlen(lit);
            return TB_OK;
        }
    double v;
    return tb__jnumber(j, &v);
}

/* Reads the "costs" object into c (every term exactly once). */
static tb_status tb__jcosts(tb__json *j, tb_costs *c, bool *seen)
{
    tb__jws(j);
    if (*j->p != '{')
        return tb__jerr(j, "\"costs\" must be an object of \"term\": cost");
    j->p++;
    tb__jws(j);
    if (*j->p == '}') {
        j->p++;
        return TB_OK;
    }
    for (;;) {
        char key[128], why[256];
        tb__jws(j);
        const char *at = j->p;
        tb_status st = tb__jstring(j, key, sizeof key);
        if (st)
            return st;
        int i = 0;
        while (i < TB__NTERMS && strcmp(tb__terms[i].name, key) != 0)
            i++;
        if (i == TB__NTERMS) {
            j->p = at;
            snprintf(why, sizeof why, "unknown cost term \"%s\" (a COSTS.json of another version? re-run testbed calibrate)", key);
            return tb__jerr(j, why);
        }
        if (seen[i]) {
            j->p = at;
            snprintf(why, sizeof why, "cost term \"%s\" given twice", key);
            return tb__jerr(j, why);
        }
        tb__jws(j);
        if (*j->p != ':')
            return tb__jerr(j, "expected ':'");
        j->p++;
        tb__jws(j);
        at = j->p;
        if ((st = tb__jnumber(j, &c->c[i])))
            return st;
        if (!isfinite(c->c[i]) || c->c[i] < 0.0) {
            j->p = at;
            snprintf(why, sizeof why, "cost \"%s\" must be a finite number >= 0", key);
            return tb__jerr(j, why);
        }
        seen[i] = true;
        tb__jws(j);
        if (*j->p == ',') {
            j->p++;
            continue;
        }
        if (*j->p == '}') {
            j->p++;
            return TB_OK;
        }
        return tb__jerr(j, "expected ',' or '}'");
    }
}

tb_status tb_costs_read(const char *path, tb_costs *c)
{
    memset(c, 0, sizeof *c);
    FILE *fp = fopen(path, "rb");
    if (!fp)
        return tb_error(TB_ERR_IO, "%s: %s", path, strerror(errno));
    size_t cap = 1 << 16, len = 0;
    char *buf = malloc(cap);
    size_t got;
    while (buf && (got = fread(buf + len, 1, cap - len - 1, fp)) > 0) {
        len += got;
        if (len + 1 == cap) {
            char *nb = cap < (1u << 24) ? realloc(buf, cap *= 2) : NULL;
            if (!nb) {
                free(buf);
                buf = NULL;
            }
            buf = nb;
        }
    }
    bool rerr = ferror(fp);
    fclose(fp);
    if (!buf)
        return tb_error(TB_ERR_FORMAT, "%s: too large for a COSTS.json (or out of memory)", path);
    if (rerr) {
        free(buf);
        return tb_error(TB_ERR_IO, "%s: read error", path);
    }
    buf[len] = 0;
    if (strlen(buf) != len) {
        free(buf);
        return tb_error(TB_ERR_FORMAT, "%s: error: a NUL byte: not a JSON file", path);
    }
    tb__json j = {.s = buf, .p = buf, .path = path};
    bool seen[TB_COST_MAX_TERMS] = {0}, schema = false, threads = false;
    tb_status st = TB_OK;
    tb__jws(&j);
    if (*j.p != '{')
        st = tb__jerr(&j, "expected a JSON object (a COSTS.json written by testbed calibrate)");
    else
        j.p++;
    tb__jws(&j);
    if (!st && *j.p == '}')
        j.p++;
    else
        while (!st) {
            char key[64], sval[128];
            tb__jws(&j);
            if ((st = tb__jstring(&j, key, sizeof key)))
                break;
            tb__jws(&j);
            if (*j.p != ':') {
                st = tb__jerr(&j, "expected ':'");
                break;
            }
            j.p++;
            tb__jws(&j);
            const char *at = j.p;
            if (!strcmp(key, "schema")) {
                if (!(st = tb__jstring(&j, sval, sizeof sval)) && strcmp(sval, TB_COSTS_SCHEMA)) {
                    j.p = at;
                    st = tb__jerr(&j, "schema is not \"" TB_COSTS_SCHEMA
                                      "\" (a COSTS.json of another version: re-run testbed calibrate)");
                }
                schema = true;
            } else if (!strcmp(key, "threads")) {
                double v;
                if (!(st = tb__jnumber(&j, &v)) && !(v >= 1 && v <= 4096 && v == floor(v))) {
                    j.p = at;
                    st = tb__jerr(&j, "threads must be a whole number from 1 to 4096");
                }
                c->threads = (int)v;
                threads = true;
            } else if (!strcmp(key, "cpu") && *j.p == '"') {
                st = tb__jstring(&j, c->cpu, sizeof c->cpu);
            } else if (!strcmp(key, "created_utc") && *j.p == '"') {
                st = tb__jstring(&j, c->created, sizeof c->created);
            } else if (!strcmp(key, "costs")) {
                st = tb__jcosts(&j, c, seen);
            } else {
                st = tb__jskip(&j, 0);
            }
            if (st)
                break;
            tb__jws(&j);
            if (*j.p == ',') {
                j.p++;
                continue;
            }
            if (*j.p == '}') {
                j.p++;
                break;
            }
            st = tb__jerr(&j, "expected ',' or '}'");
        }
    if (!st) {
        tb__jws(&j);
        if (*j.p)
            st = tb__jerr(&j, "text after the JSON object");
    }
    if (!st && !schema)
        st = tb_error(TB_ERR_FORMAT, "%s:1:1: error: no \"schema\": \"" TB_COSTS_SCHEMA "\"", path);
    if (!st && !threads)
        st = tb_error(TB_ERR_FORMAT, "%s:1:1: error: no \"threads\"", path);
    for (int i = 0; !st && i < TB__NTERMS; i++)
        if (!seen[i])
            st = tb_error(TB_ERR_FORMAT, "%s:1:1: error: cost term \"%s\" is missing (re-run testbed calibrate)",
                          path, tb__terms[i].name);
    free(buf);
    return st;
}

void tb_prediction_write_json(FILE *out, const tb_costs *c, const tb_predict_stats *f, const tb_prediction *p)
{
    (void)c;
    fprintf(out, "{\n  \"method\": \"%s\",\n  \"seconds\": %.6g,\n  \"peak_rss_bytes\": %.0f,\n  \"modules\": {",
            tb_predict_method_name(f->method), p->seconds, p->peak_rss_bytes);
    for (int m = 0; m < TB_PM_COUNT; m++)
        fprintf(out, "%s\n    \"%s\": %.6g", m ? "," : "", tb_pmodule_name((tb_pmodule)m), p->module[m]);
    fprintf(out, "\n  },\n  \"terms\": {");
    for (int i = 0; i < TB__NTERMS; i++)
        fprintf(out, "%s\n    \"%s\": %.6g", i ? "," : "", tb__terms[i].name, p->term[i]);
    fprintf(out, "\n  },\n  \"statistics\": {");
    for (int i = 0; i < TB_PF_COUNT; i++)
        fprintf(out, "%s\n    \"%s\": %.6g", i ? "," : "", tb_pfeat_name((tb_pfeat)i), f->f[i]);
    fprintf(out, "\n  },\n  \"threads\": %d,\n  \"pilot_seconds\": %.6g", f->threads, f->pilot_seconds);
    if (f->method == TB_PREDICT_RADIOSITY)
        fprintf(out, ",\n  \"radiosity_shots\": %.0f,\n  \"radiosity_shots_extrapolated\": %s", f->rad_shots,
                f->rad_extrapolated ? "true" : "false");
    fprintf(out, "\n}\n");
}
