/* Procedural MID scenes for scaling tests and benchmarks (docs/scenes.md).
 *
 * A generated scene is a camera, two lights and a palette of named materials,
 * then `count` top-level objects laid out on a square grid in the z = 0
 * plane. Objects are made one at a time and handed to a callback (or written
 * with the canonical MID writer), so memory does not grow with `count`: a
 * multi-gigabyte file streams out in constant memory.
 *
 * Deterministic: object i depends only on (seed, kind, i), never on the
 * objects before it, so the same options give the same bytes on every run. */
#ifndef TB_HOST_SCENE_GENERATE_H
#define TB_HOST_SCENE_GENERATE_H

#include <stdint.h>
#include <stdio.h>

#include "host/mid/mid.h"
#include "util/base/error.h"

/* What the objects are. */
typedef enum tb_gen_kind {
    TB_GEN_GRID = 0, /* one primitive per cell, all 11 kinds mixed, random parameters */
    TB_GEN_CSG,      /* one random CSG tree (depth 1 to 3) of closed primitives per cell */
    TB_GEN_MESH,     /* one inline polygon mesh per cell: a geodesic sphere or a height field */
} tb_gen_kind;

/* Number of generator kinds. */
#define TB_GEN_KIND_COUNT 3

/* Largest `count` accepted (about 3.5e13 bytes of MID at the smallest objects). */
#define TB_GEN_MAX_COUNT ((int64_t)1000000000000)

/* The name of a kind as typed on the command line ("grid", "csg", "mesh"); "?" if out of range. */
const char *tb_gen_kind_name(tb_gen_kind k);

/* The kind named `name`; TB_ERR_ARG (message lists the kinds) if there is none. */
tb_status tb_gen_kind_parse(const char *name, tb_gen_kind *out);

/* What to generate. */
typedef struct tb_gen_options {
    tb_gen_kind kind;
    int64_t count; /* top-level objects, 0 .. TB_GEN_MAX_COUNT */
    uint64_t seed; /* any value; equal seeds give equal scenes */
} tb_gen_options;

/* Receives one item; it and everything it points to are valid only during
 * the call. A non-zero return stops the generator, which returns it. */
typedef tb_status (*tb_gen_sink)(void *user, const tb_mid_item *item);

/* Generates the scene item by item in file order: camera, lights, materials,
 * then the objects. Every item is what the MID reader would hand out for its
 * canonical text (resolved materials, composed world transforms), so
 * tb_mid_item_equal holds between a generated item and the item read back
 * from its written form. TB_ERR_ARG for bad options, TB_ERR_NOMEM, or the
 * sink's status. */
tb_status tb_generate(const tb_gen_options *opt, tb_gen_sink sink, void *user);

/* Writes the scene to `fp` in canonical MID form (header included).
 * TB_ERR_IO if the stream reports a write error. */
tb_status tb_generate_write(FILE *fp, const tb_gen_options *opt);

#endif
