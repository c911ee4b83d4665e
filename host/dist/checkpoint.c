/* Checkpoint files and the progressive render's persist (checkpoint.h). */
#include "host/dist/checkpoint.h"
#include "host/dist/dist.h"
#include "host/dist/dist_internal.h"

#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "util/base/outfile.h"

static const char tb__ckpt_magic[8] = {'T', 'B', 'C', 'K', 'P', 'T', '\n', '\0'};

/* The header as it lies in the file (48 bytes, no padding). */
typedef struct tb__ckpt_header {
    char magic[8];
    uint32_t version, kind, order, zero;
    uint64_t key, len, units;
} tb__ckpt_header;

_Static_assert(sizeof(tb__ckpt_header) == 48, "checkpoint header is 48 bytes");

uint64_t tb_ckpt_hash(uint64_t h, const void *data, size_t len)
{
    const unsigned char *p = data;
    for (size_t i = 0; i < len; i++) {
        h ^= p[i];
        h *= 0x100000001b3ull;
    }
    return h;
}

tb_status tb_ckpt_write(const char *path, uint32_t kind, uint64_t key, uint64_t units, const void *payload,
                        size_t len)
{
    tb__ckpt_header h;
    memset(&h, 0, sizeof h);
    memcpy(h.magic, tb__ckpt_magic, sizeof h.magic);
    h.version = TB_CKPT_VERSION;
    h.kind = kind;
    h.order = 0x01020304u;
    h.key = key;
    h.len = len;
    h.units = units;
    uint64_t sum = tb_ckpt_hash(TB_CKPT_HASH_SEED, payload, len);
    tb_outfile of;
    tb_status st = tb_outfile_open(&of, path);
    if (st)
        return st;
    if (fwrite(&h, sizeof h, 1, of.fp) != 1 || (len && fwrite(payload, 1, len, of.fp) != len) ||
        fwrite(&sum, sizeof sum, 1, of.fp) != 1) {
        tb_outfile_abort(&of);
        return tb_error(TB_ERR_IO, "%s: cannot write the checkpoint", path);
    }
    return tb_outfile_commit(&of);
}

tb_status tb_ckpt_read(const char *path, uint32_t kind, uint64_t key, void **payload, size_t *len,
                       uint64_t *units)
{
    *payload = NULL;
    *len = 0;
    FILE *fp = fopen(path, "rb");
    if (!fp)
        return tb_error(TB_ERR_IO, "%s: cannot open the checkpoint", path);
    tb__ckpt_header h;
    tb_status st = TB_OK;
    void *buf = NULL;
    uint64_t sum = 0;
    if (fread(&h, sizeof h, 1, fp) != 1 || memcmp(h.magic, tb__ckpt_magic, sizeof h.magic) != 0)
        st = tb_error(TB_ERR_FORMAT, "%s: not a testbed checkpoint", path);
    else if (h.order != 0x01020304u)
        st = tb_error(TB_ERR_FORMAT, "%s: written on a machine of another byte order", path);
    else if (h.version != TB_CKPT_VERSION)
        st = tb_error(TB_ERR_FORMAT, "%s: checkpoint version %u, this testbed reads version %u", path, h.version,
                      TB_CKPT_VERSION);
    else if (h.kind != kind)
        st = tb_error(TB_ERR_FORMAT, "%s: a %s checkpoint, not a %s one", path,
                      h.kind == TB_CKPT_RENDER ? "render" : h.kind == TB_CKPT_RADIOSITY ? "radiosity" : "unknown",
                      kind == TB_CKPT_RENDER ? "render" : "radiosity");
    else if (h.key != key)
        st = tb_error(TB_ERR_FORMAT, "%s: written for another job (scene or options differ: key %016llx, this "
                      "job %016llx)", path, (unsigned long long)h.key, (unsigned long long)key);
    else if (h.len > ((uint64_t)1 << 40) || !(buf = malloc(h.len ? (size_t)h.len : 1)))
        st = tb_error(TB_ERR_FORMAT, "%s: payload of %llu bytes", path, (unsigned long long)h.len);
    else if ((h.len && fread(buf, 1, (size_t)h.len, fp) != h.len) || fread(&sum, sizeof sum, 1, fp) != 1)
        st = tb_error(TB_ERR_FORMAT, "%s: truncated checkpoint", path);
    else if (sum != tb_ckpt_hash(TB_CKPT_HASH_SEED, buf, (size_t)h.len))
        st = tb_error(TB_ERR_FORMAT, "%s: checksum mismatch (the file is damaged)", path);
    fclose(fp);
    if (st) {
        free(buf);
        return st;
    }
    *payload = buf;
    *len = (size_t)h.len;
    if (units)
        *units = h.units;
    return TB_OK;
}

/* ------------------------------------------------------ the termination note */

/* The line written on SIGTERM: built outside the handler, swapped in whole. */
static char tb__ckpt_notes[2][1024];
static atomic_int tb__ckpt_which = -1;
static const char *tb__ckpt_prog = "testbed";

static void tb__ckpt_on_sigterm(int sig)
{
    (void)sig;
    int w = atomic_load(&tb__ckpt_which);
    static const char none[] = ": stopped by the launcher (a rank of the job died, or it was killed); "
                               "no checkpoint written yet\n";
    ssize_t rc = write(2, tb__ckpt_prog, strlen(tb__ckpt_prog));
    if (w >= 0)
        rc = write(2, tb__ckpt_notes[w], strlen(tb__ckpt_notes[w]));
    else
        rc = write(2, none, sizeof none - 1);
    (void)rc;
    _exit(143);
}

void tb_ckpt_on_term(const char *prog)
{
    tb__ckpt_prog = prog;
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = tb__ckpt_on_sigterm;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGTERM, &sa, NULL);
}

void tb_ckpt_note(const char *path, const char *what)
{
    int w = atomic_load(&tb__ckpt_which) == 0 ? 1 : 0;
    snprintf(tb__ckpt_notes[w], sizeof tb__ckpt_notes[w],
             ": rank %d of %d stopped by the launcher (a rank of the job died, or it was killed); "
             "last checkpoint: %s (%s), intact: continue with --resume %s\n",
             tb_dist_rank(), tb_dist_size(), path, what, path);
    atomic_store(&tb__ckpt_which, w);
}

/* ------------------------------------------------- a progressive render */

/* Render payload: i32 passes done, i32 max_spp_used, u64 samples,
 * ring_samples, pixels, pixels_refined, then the packed film. */
#define TB__CKPT_RENDER_HEAD (2 * sizeof(int32_t) + 4 * sizeof(uint64_t))

static tb_status tb__ckpt_restore(void *ctx, tb_film *film, tb_render_stats *done)
{
    tb_ckpt_render *c = ctx;
    c->last_save = tb__dist_now();
    if (!c->resume_path)
        return TB_OK;
    void *buf;
    size_t len;
    uint64_t units;
    tb_status st = tb_ckpt_read(c->resume_path, TB_CKPT_RENDER, c->key, &buf, &len, &units);
    if (st)
        return st;
    if (len < TB__CKPT_RENDER_HEAD) {
        free(buf);
        return tb_error(TB_ERR_FORMAT, "%s: render checkpoint payload of %zu bytes", c->resume_path, len);
    }
    int32_t ints[2];
    uint64_t u[4];
    memcpy(ints, buf, sizeof ints);
    memcpy(u, (char *)buf + sizeof ints, sizeof u);
    st = tb_film_unpack(film, (char *)buf + TB__CKPT_RENDER_HEAD, len - TB__CKPT_RENDER_HEAD);
    free(buf);
    if (st)
        return tb_error_context(st, "%s", c->resume_path);
    if (ints[0] < 0 || (uint64_t)ints[0] != units)
        return tb_error(TB_ERR_FORMAT, "%s: %d passes in the payload, %llu in the header", c->resume_path,
                        (int)ints[0], (unsigned long long)units);
    done->passes_done = ints[0];
    done->aa.max_spp_used = ints[1];
    done->aa.samples = u[0];
    done->aa.ring_samples = u[1];
    done->aa.pixels = u[2];
    done->aa.pixels_refined = u[3];
    c->saved_passes = ints[0];
    char what[64];
    snprintf(what, sizeof what, "%d passes", ints[0]);
    tb_ckpt_note(c->resume_path, what);
    return TB_OK;
}

static tb_status tb__ckpt_save(void *ctx, const tb_film *film, const tb_render_stats *done, bool last)
{
    tb_ckpt_render *c = ctx;
    if (!c->path || (!last && tb__dist_now() - c->last_save < c->every))
        return TB_OK;
    size_t flen = tb_film_packed_size(film), len = TB__CKPT_RENDER_HEAD + flen;
    char *buf = malloc(len);
    if (!buf)
        return tb_error(TB_ERR_NOMEM, "out of memory for a checkpoint of %zu bytes", len);
    int32_t ints[2] = {done->passes_done, done->aa.max_spp_used};
    uint64_t u[4] = {done->aa.samples, done->aa.ring_samples, done->aa.pixels, done->aa.pixels_refined};
    memcpy(buf, ints, sizeof ints);
    memcpy(buf + sizeof ints, u, sizeof u);
    tb_film_pack(film, buf + TB__CKPT_RENDER_HEAD);
    tb_status st = tb_ckpt_write(c->path, TB_CKPT_RENDER, c->key, (uint64_t)done->passes_done, buf, len);
    free(buf);
    if (st)
        return st;
    c->last_save = tb__dist_now();
    c->saved_passes = done->passes_done;
    char what[64];
    snprintf(what, sizeof what, "%d passes", done->passes_done);
    tb_ckpt_note(c->path, what);
    if (!c->quiet)
        fprintf(stderr, "testbed: checkpoint %s: %s\n", c->path, what);
    return TB_OK;
}

tb_render_persist tb_ckpt_render_persist(tb_ckpt_render *c)
{
    return (tb_render_persist){.ctx = c, .restore = tb__ckpt_restore, .save = tb__ckpt_save};
}

/* ------------------------------------------------- a radiosity solve */

/* Radiosity payload: u64 bytes of the refinement's state, those bytes,
 * then the solver's packed state. */
static tb_status tb__ckpt_rad_load(void *ctx, bool *found, void **extra, size_t *extra_len, void **state,
                                   size_t *state_len)
{
    tb_ckpt_rad *c = ctx;
    c->last_save = tb__dist_now();
    *found = false, *extra = *state = NULL, *extra_len = *state_len = 0;
    if (!c->resume_path)
        return TB_OK;
    void *buf = NULL;
    size_t len = 0;
    uint64_t units = 0;
    tb_status st = TB_OK;
    if (tb_dist_rank() == 0)
        st = tb_ckpt_read(c->resume_path, TB_CKPT_RADIOSITY, c->key, &buf, &len, &units);
    /* rank 0 read it (or failed); the others get its bytes */
    if ((st = tb_dist_agree_status(st, NULL)))
        return st;
    if (tb_dist_size() > 1) {
        uint64_t n[2] = {(uint64_t)len, units};
        if ((st = tb_dist_bcast_bytes(n, sizeof n)))
            return st;
        if (tb_dist_rank() != 0) {
            len = (size_t)n[0], units = n[1];
            if (!(buf = malloc(len ? len : 1)))
                st = tb_error(TB_ERR_NOMEM, "out of memory for a checkpoint of %zu bytes", len);
        }
        if ((st = tb_dist_agree_status(st, NULL)) || (st = tb_dist_bcast_bytes(buf, len))) {
            free(buf);
            return st;
        }
    }
    uint64_t xl = 0;
    if (len >= sizeof xl)
        memcpy(&xl, buf, sizeof xl);
    if (len < sizeof xl || xl > len - sizeof xl) {
        free(buf);
        return tb_error(TB_ERR_FORMAT, "%s: radiosity payload of %zu bytes", c->resume_path, len);
    }
    size_t sl = len - sizeof xl - (size_t)xl;
    if ((xl && !(*extra = malloc((size_t)xl))) || !(*state = malloc(sl ? sl : 1))) {
        free(*extra), *extra = NULL;
        free(buf);
        return tb_error(TB_ERR_NOMEM, "out of memory for a checkpoint of %zu bytes", len);
    }
    if (xl) /* (no extra: *extra stays NULL, which memcpy may not take even for 0 bytes) */
        memcpy(*extra, (char *)buf + sizeof xl, (size_t)xl);
    memcpy(*state, (char *)buf + sizeof xl + xl, sl);
    free(buf);
    *extra_len = (size_t)xl, *state_len = sl, *found = true;
    char what[64];
    snprintf(what, sizeof what, "%llu shots", (unsigned long long)units);
    if (tb_dist_rank() == 0)
        tb_ckpt_note(c->resume_path, what);
    return TB_OK;
}

static tb_status tb__ckpt_rad_save(void *ctx, const tb_rad_solver *s, const void *extra, size_t extra_len,
                                   uint64_t shots, bool last)
{
    tb_ckpt_rad *c = ctx;
    if (!c->path || tb_dist_rank() != 0 || (!last && tb__dist_now() - c->last_save < c->every))
        return TB_OK;
    uint64_t xl = extra_len;
    size_t len = sizeof xl + extra_len + tb_rad_solver_packed_size(s);
    char *buf = malloc(len);
    if (!buf)
        return tb_error(TB_ERR_NOMEM, "out of memory for a checkpoint of %zu bytes", len);
    memcpy(buf, &xl, sizeof xl);
    if (extra_len)
        memcpy(buf + sizeof xl, extra, extra_len);
    tb_rad_solver_pack(s, buf + sizeof xl + extra_len);
    tb_status st = tb_ckpt_write(c->path, TB_CKPT_RADIOSITY, c->key, shots, buf, len);
    free(buf);
    if (st)
        return st;
    c->last_save = tb__dist_now();
    char what[64];
    snprintf(what, sizeof what, "%llu shots", (unsigned long long)shots);
    tb_ckpt_note(c->path, what);
    if (!c->quiet && last)
        fprintf(stderr, "testbed: checkpoint %s: %s\n", c->path, what);
    return TB_OK;
}

tb_rad_persist tb_ckpt_rad_persist(tb_ckpt_rad *c)
{
    return (tb_rad_persist){.ctx = c, .load = tb__ckpt_rad_load, .save = tb__ckpt_rad_save};
}
