/* The binary form of FED (docs/fed.md, "Binary form"): a 36-byte
 * little-endian header, then flat arrays in a fixed order. The header's
 * counts determine the exact file size, which is checked before anything is
 * allocated, so a hostile header cannot make the reader allocate more than
 * the file holds. Errors name the byte offset of the bad value. Also the
 * format-sniffing and whole-file entry points. */
#include "util/mesh/fed.h"

#include <errno.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>

#include "util/base/outfile.h"
#include "util/math/float.h"
#include "util/mesh/fed_internal.h"

_Static_assert(sizeof(tb_vec3) == 12 && sizeof(tb_vec2) == 8, "packed float vectors expected");

#define TB__HEADER_SIZE 36u

/* Flag bits of the header. */
enum {
    TB__FLAG_NORMALS = 1u << 0,
    TB__FLAG_UVS = 1u << 1,
    TB__FLAG_IDS = 1u << 2,
    TB__FLAG_MATERIALS = 1u << 3,
    TB__FLAGS_KNOWN = 0xfu,
};

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
#define TB__BIG_ENDIAN 1
#else
#define TB__BIG_ENDIAN 0
#endif

/* Converts n 32-bit words between file (little-endian) and host order. */
static void tb__swap32(void *p, size_t n)
{
#if TB__BIG_ENDIAN
    uint32_t *w = p;
    for (size_t i = 0; i < n; i++)
        w[i] = __builtin_bswap32(w[i]);
#else
    (void)p, (void)n;
#endif
}

static uint32_t tb__le32(const unsigned char *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static tb_status tb__err(const char *name, uint64_t offset, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

static tb_status tb__err(const char *name, uint64_t offset, const char *fmt, ...)
{
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return tb_error(TB_ERR_FORMAT, "%s: byte %llu: error: %s", name, (unsigned long long)offset, msg);
}

/* Reads n 32-bit words (the size was checked, so a short read is an I/O
 * error or a file that shrank). */
static tb_status tb__read32(FILE *f, const char *name, void *dst, size_t n, uint64_t offset)
{
    if (n && fread(dst, 4, n, f) != n) {
        if (ferror(f))
            return tb_error(TB_ERR_IO, "%s: read error: %s", name, strerror(errno));
        return tb__err(name, offset, "unexpected end of file");
    }
    tb__swap32(dst, n);
    return TB_OK;
}

/* Byte offsets of the arrays, from the header's counts. */
typedef struct tb__layout {
    uint64_t positions, normals, uvs, face_nloops, loop_sizes, corners, ids, materials, end;
} tb__layout;

static tb__layout tb__layout_of(uint32_t flags, uint64_t nv, uint64_t nf, uint64_t nl, uint64_t nc, uint32_t loop_size)
{
    tb__layout L;
    L.positions = TB__HEADER_SIZE;
    L.normals = L.positions + 12 * nv;
    L.uvs = L.normals + ((flags & TB__FLAG_NORMALS) ? 12 * nv : 0);
    L.face_nloops = L.uvs + ((flags & TB__FLAG_UVS) ? 8 * nv : 0);
    L.loop_sizes = L.face_nloops + (nl > nf ? 4 * nf : 0);
    L.corners = L.loop_sizes + (loop_size == 0 ? 4 * nl : 0);
    L.ids = L.corners + 4 * nc;
    L.materials = L.ids + ((flags & TB__FLAG_IDS) ? 4 * nf : 0);
    L.end = L.materials + ((flags & TB__FLAG_MATERIALS) ? 4 * nf : 0);
    return L;
}

/* The binary reader for input whose remaining size is known. */
static tb_status tb__read_sized(FILE *f, const char *name, uint64_t size, tb_fed **out)
{
    unsigned char h[TB__HEADER_SIZE];
    size_t got = fread(h, 1, sizeof h, f);
    if (got < 8 || memcmp(h, TB_FED_BINARY_MAGIC, 8) != 0) {
        if (ferror(f))
            return tb_error(TB_ERR_IO, "%s: read error: %s", name, strerror(errno));
        return tb__err(name, 0, "not a binary FED file (bad magic number)");
    }
    if (got < TB__HEADER_SIZE)
        return tb__err(name, got, "file ends inside the %u-byte header", TB__HEADER_SIZE);
    uint32_t version = tb__le32(h + 8), flags = tb__le32(h + 12);
    uint32_t nv = tb__le32(h + 16), nf = tb__le32(h + 20), nl = tb__le32(h + 24), nc = tb__le32(h + 28);
    uint32_t loop_size = tb__le32(h + 32);
    if (version != TB_FED_VERSION)
        return tb__err(name, 8, "unsupported FED version %u (this reader reads version %d)", version, TB_FED_VERSION);
    if (flags & ~TB__FLAGS_KNOWN)
        return tb__err(name, 12, "unknown flag bits 0x%x", flags & ~TB__FLAGS_KNOWN);
    const uint32_t counts[4] = {nv, nf, nl, nc};
    static const char *const count_names[4] = {"vertex", "face", "loop", "corner"};
    for (int k = 0; k < 4; k++)
        if (counts[k] > TB_FED_MAX_COUNT)
            return tb__err(name, 16 + 4 * (unsigned)k, "%s count %u out of range (at most %u)", count_names[k],
                           counts[k], TB_FED_MAX_COUNT);
    if (nl < nf)
        return tb__err(name, 24, "%u loops for %u faces (every face has at least one)", nl, nf);
    if (nf == 0 && nl > 0)
        return tb__err(name, 24, "%u loops but no faces", nl);
    if (loop_size != 0 && (loop_size < 3 || (uint64_t)nl * loop_size != nc))
        return tb__err(name, 32, "uniform loop size %u does not fit %u loops and %u corners (sizes are >= 3)",
                       loop_size, nl, nc);
    if (loop_size == 0 && (uint64_t)nl * 3 > nc)
        return tb__err(name, 28, "%u corners cannot make %u loops of at least 3", nc, nl);
    tb__layout L = tb__layout_of(flags, nv, nf, nl, nc, loop_size);
    if (L.end != size)
        return tb__err(name, size < L.end ? size : L.end,
                       "the file is %llu bytes, but its header describes %llu", (unsigned long long)size,
                       (unsigned long long)L.end);

    tb_fed *m = tb__fed_alloc(nv, nf, nl, nc, flags & TB__FLAG_NORMALS, flags & TB__FLAG_UVS, flags & TB__FLAG_IDS,
                              flags & TB__FLAG_MATERIALS);
    if (!m)
        return TB_ERR_NOMEM;
    tb_status st = tb__read32(f, name, m->positions, 3 * (size_t)nv, L.positions);
    if (!st && m->normals)
        st = tb__read32(f, name, m->normals, 3 * (size_t)nv, L.normals);
    if (!st && m->uvs)
        st = tb__read32(f, name, m->uvs, 2 * (size_t)nv, L.uvs);
    /* Loops per face, then corners per loop: read as counts, checked, summed
     * in place into offsets. */
    m->face_loops[0] = 0;
    if (!st && nl > nf) {
        st = tb__read32(f, name, m->face_loops + 1, nf, L.face_nloops);
        uint64_t sum = 0;
        for (uint32_t i = 0; i < nf && !st; i++) {
            uint32_t k = m->face_loops[i + 1];
            sum += k;
            if (k == 0)
                st = tb__err(name, L.face_nloops + 4 * (uint64_t)i, "face %u has no loop", i);
            else if (sum > nl)
                st = tb__err(name, L.face_nloops + 4 * (uint64_t)i,
                             "faces 0..%u already have %llu loops; the header says %u", i, (unsigned long long)sum, nl);
            else
                m->face_loops[i + 1] = (uint32_t)sum;
        }
        if (!st && sum != nl)
            st = tb__err(name, L.face_nloops, "the faces have %llu loops; the header says %u", (unsigned long long)sum, nl);
    } else {
        for (uint32_t i = 0; i < nf; i++)
            m->face_loops[i + 1] = i + 1;
    }
    m->loop_corners[0] = 0;
    if (!st && loop_size == 0) {
        st = tb__read32(f, name, m->loop_corners + 1, nl, L.loop_sizes);
        uint64_t sum = 0;
        for (uint32_t i = 0; i < nl && !st; i++) {
            uint32_t k = m->loop_corners[i + 1];
            sum += k;
            if (k < 3)
                st = tb__err(name, L.loop_sizes + 4 * (uint64_t)i, "loop %u has %u corners (at least 3 needed)", i, k);
            else if (sum > nc)
                st = tb__err(name, L.loop_sizes + 4 * (uint64_t)i,
                             "loops 0..%u already have %llu corners; the header says %u", i, (unsigned long long)sum, nc);
            else
                m->loop_corners[i + 1] = (uint32_t)sum;
        }
        if (!st && sum != nc)
            st = tb__err(name, L.loop_sizes, "the loops have %llu corners; the header says %u", (unsigned long long)sum, nc);
    } else if (!st) {
        for (uint32_t i = 0; i < nl; i++)
            m->loop_corners[i + 1] = (i + 1) * loop_size;
    }
    if (!st)
        st = tb__read32(f, name, m->corner_vert, nc, L.corners);
    for (uint32_t c = 0; c < nc && !st; c++)
        if (m->corner_vert[c] >= nv)
            st = tb__err(name, L.corners + 4 * (uint64_t)c, "vertex index %u out of range (%u vertices)",
                         m->corner_vert[c], nv);
    if (!st && m->face_ids)
        st = tb__read32(f, name, m->face_ids, nf, L.ids);
    if (!st && m->face_materials)
        st = tb__read32(f, name, m->face_materials, nf, L.materials);
    if (!st) {
        tb_fed_issue issue;
        st = tb__fed_finish(m, &issue);
        if (st == TB_ERR_FORMAT) {
            /* Point at the value: the corner, the loop's first corner, or the vertex's data. */
            uint64_t off = 0;
            if (issue.corner != TB_FED_NONE)
                off = L.corners + 4 * (uint64_t)issue.corner;
            else if (issue.loop != TB_FED_NONE)
                off = L.corners + 4 * (uint64_t)m->loop_corners[issue.loop];
            else if (issue.vertex != TB_FED_NONE) {
                uint32_t v = issue.vertex;
                if (!tb_isfinite3(m->positions[v]))
                    off = L.positions + 12 * (uint64_t)v;
                else if (m->normals && !tb_isfinite3(m->normals[v]))
                    off = L.normals + 12 * (uint64_t)v;
                else
                    off = L.uvs + 8 * (uint64_t)v;
            }
            st = tb__err(name, off, "%s", issue.message);
        }
    }
    if (st) {
        tb_fed_free(m);
        return st;
    }
    *out = m;
    return TB_OK;
}

tb_status tb_fed_read_binary(FILE *f, const char *name, tb_fed **out)
{
    *out = NULL;
    off_t here = ftello(f), end = -1;
    if (here >= 0 && fseeko(f, 0, SEEK_END) == 0) {
        end = ftello(f);
        if (fseeko(f, here, SEEK_SET) != 0)
            end = -1;
    }
    if (here >= 0 && end >= here)
        return tb__read_sized(f, name, (uint64_t)(end - here), out);
    /* Not seekable (a pipe): read it all (memory grows with the bytes that
     * actually arrive, not with the header's claims), then parse that. */
    size_t len = 0, cap = 1 << 16;
    unsigned char *buf = malloc(cap);
    if (!buf)
        return tb_error(TB_ERR_NOMEM, "%s: out of memory", name);
    for (;;) {
        if (len == cap) {
            unsigned char *nb = cap <= SIZE_MAX / 2 ? realloc(buf, cap * 2) : NULL;
            if (!nb) {
                free(buf);
                return tb_error(TB_ERR_NOMEM, "%s: out of memory after %zu bytes", name, len);
            }
            buf = nb;
            cap *= 2;
        }
        size_t n = fread(buf + len, 1, cap - len, f);
        len += n;
        if (n == 0)
            break;
    }
    if (ferror(f)) {
        free(buf);
        return tb_error(TB_ERR_IO, "%s: read error: %s", name, strerror(errno));
    }
    if (len == 0) {
        free(buf);
        return tb__err(name, 0, "empty file (not a binary FED file)");
    }
    FILE *mf = fmemopen(buf, len, "rb");
    if (!mf) {
        free(buf);
        return tb_error(TB_ERR_NOMEM, "%s: cannot open the data read: %s", name, strerror(errno));
    }
    tb_status st = tb__read_sized(mf, name, len, out);
    fclose(mf);
    free(buf);
    return st;
}

tb_status tb_fed_read(FILE *f, const char *name, tb_fed **out)
{
    *out = NULL;
    int c = getc(f);
    if (c == EOF) {
        if (ferror(f))
            return tb_error(TB_ERR_IO, "%s: read error: %s", name, strerror(errno));
        return tb_error(TB_ERR_FORMAT, "%s:1:1: error: empty file (expected the header 'fed 1')", name);
    }
    if (ungetc(c, f) == EOF)
        return tb_error(TB_ERR_IO, "%s: cannot push back a byte", name);
    /* 0x89 never starts a text FED (it is not ASCII). */
    return c == 0x89 ? tb_fed_read_binary(f, name, out) : tb_fed_read_text(f, name, out);
}

tb_status tb_fed_read_file(const char *path, tb_fed **out)
{
    *out = NULL;
    FILE *f = fopen(path, "rb");
    if (!f)
        return tb_error(errno == ENOENT ? TB_ERR_NOT_FOUND : TB_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    tb_status st = tb_fed_read(f, path, out);
    fclose(f);
    return st;
}

/* ------------------------------------------------------------------- writer */

/* Writes n 32-bit words in little-endian order. */
static bool tb__write32(FILE *f, const void *src, size_t n)
{
#if TB__BIG_ENDIAN
    uint32_t buf[1024];
    const uint32_t *w = src;
    while (n > 0) {
        size_t k = n < 1024 ? n : 1024;
        for (size_t i = 0; i < k; i++)
            buf[i] = __builtin_bswap32(w[i]);
        if (fwrite(buf, 4, k, f) != k)
            return false;
        w += k;
        n -= k;
    }
    return true;
#else
    return fwrite(src, 4, n, f) == n;
#endif
}

/* Writes the differences of consecutive offsets (the per-item counts). */
static bool tb__write_counts(FILE *f, const uint32_t *offsets, uint32_t n)
{
    uint32_t buf[1024];
    for (uint32_t i = 0; i < n;) {
        uint32_t k = n - i < 1024 ? n - i : 1024;
        for (uint32_t j = 0; j < k; j++)
            buf[j] = offsets[i + j + 1] - offsets[i + j];
        if (!tb__write32(f, buf, k))
            return false;
        i += k;
    }
    return true;
}

tb_status tb_fed_write_binary(FILE *f, const tb_fed *m)
{
    uint32_t loop_size = m->nloops ? tb_fed_loop_size(m, 0) : 3;
    for (uint32_t l = 1; l < m->nloops && loop_size; l++)
        if (tb_fed_loop_size(m, l) != loop_size)
            loop_size = 0;
    uint32_t flags = (m->normals ? TB__FLAG_NORMALS : 0) | (m->uvs ? TB__FLAG_UVS : 0) |
                     (m->face_ids ? TB__FLAG_IDS : 0) | (m->face_materials ? TB__FLAG_MATERIALS : 0);
    uint32_t head[7] = {TB_FED_VERSION, flags, m->nverts, m->nfaces, m->nloops, m->ncorners, loop_size};
    bool ok = fwrite(TB_FED_BINARY_MAGIC, 1, 8, f) == 8 && tb__write32(f, head, 7) &&
              tb__write32(f, m->positions, 3 * (size_t)m->nverts) &&
              (!m->normals || tb__write32(f, m->normals, 3 * (size_t)m->nverts)) &&
              (!m->uvs || tb__write32(f, m->uvs, 2 * (size_t)m->nverts)) &&
              (m->nloops == m->nfaces || tb__write_counts(f, m->face_loops, m->nfaces)) &&
              (loop_size != 0 || tb__write_counts(f, m->loop_corners, m->nloops)) &&
              tb__write32(f, m->corner_vert, m->ncorners) &&
              (!m->face_ids || tb__write32(f, m->face_ids, m->nfaces)) &&
              (!m->face_materials || tb__write32(f, m->face_materials, m->nfaces));
    if (!ok || ferror(f))
        return tb_error(TB_ERR_IO, "FED: write error: %s", strerror(errno));
    return TB_OK;
}

tb_status tb_fed_write_file(const char *path, const tb_fed *m, tb_fed_format format)
{
    if (format == TB_FED_FORMAT_AUTO) {
        size_t n = strlen(path);
        format = n >= 5 && strcmp(path + n - 5, ".fedb") == 0 ? TB_FED_FORMAT_BINARY : TB_FED_FORMAT_TEXT;
    }
    tb_outfile of;
    tb_status st = tb_outfile_open(&of, path);
    if (st)
        return st;
    st = format == TB_FED_FORMAT_BINARY ? tb_fed_write_binary(of.fp, m) : tb_fed_write_text(of.fp, m);
    if (st) {
        tb_outfile_abort(&of);
        return tb_error_context(st, "%s", path);
    }
    return tb_outfile_commit(&of);
}
