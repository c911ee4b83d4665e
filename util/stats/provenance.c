#include "util/stats/provenance.h"
#include "util/base/str.h"

#include <errno.h>
#include <inttypes.h>
#include <omp.h>
#include <openssl/evp.h>
#include <stdlib.h>
#include <string.h>
#include <sys/utsname.h>
#include <time.h>
#include <unistd.h>

#include "tb_version.h"
#include "util/image/image.h"
#include "util/stats/stats.h"

/* Copies `src` into the fixed buffer `dst` of size `n`, truncating. */
static void tb__copy(char *dst, size_t n, const char *src)
{
    snprintf(dst, n, "%s", src ? src : "");
}

/* Characters a shell leaves alone; anything else gets the argument quoted.
 * Bytes >= 0x80 count as safe so UTF-8 file names stay readable. */
static int tb__shell_safe(const char *a)
{
    if (!*a)
        return 0;
    for (const unsigned char *s = (const unsigned char *)a; *s; s++)
        if (!(*s >= 0x80 || (*s >= 'a' && *s <= 'z') || (*s >= 'A' && *s <= 'Z') ||
              (*s >= '0' && *s <= '9') || strchr("_./=:,+@%-", *s)))
            return 0;
    return 1;
}

/* argv joined by spaces, each argument quoted for a POSIX shell if needed, so
 * the line can be pasted back to repeat the run. */
static char *tb__join_args(int argc, char **argv)
{
    size_t n = 1;
    for (int i = 0; i < argc; i++)
        n += 4 * strlen(argv[i] ? argv[i] : "") + 3; /* worst case: every char is ' -> '\'' */
    char *out = malloc(n), *o = out;
    if (!out)
        return NULL;
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i] ? argv[i] : "";
        if (i)
            *o++ = ' ';
        if (tb__shell_safe(a)) {
            size_t k = strlen(a);
            memcpy(o, a, k);
            o += k;
            continue;
        }
        *o++ = '\'';
        for (; *a; a++) {
            if (*a == '\'') {
                memcpy(o, "'\\''", 4);
                o += 4;
            } else {
                *o++ = *a;
            }
        }
        *o++ = '\'';
    }
    *o = '\0';
    return out;
}

/* The CPU's model name from /proc/cpuinfo (Linux); "" elsewhere. */
static void tb__cpu_model(char *dst, size_t n)
{
    dst[0] = '\0';
    FILE *f = fopen("/proc/cpuinfo", "r");
    if (!f)
        return;
    /* x86 says "model name"; other architectures use one of the others. */
    static const char *const keys[] = {"model name", "Hardware", "Processor", "cpu model", "cpu"};
    int best = (int)(sizeof keys / sizeof keys[0]);
    char line[512];
    while (fgets(line, sizeof line, f)) {
        char *colon = strchr(line, ':');
        if (!colon)
            continue;
        char *end = colon;
        while (end > line && (end[-1] == ' ' || end[-1] == '\t'))
            end--;
        size_t klen = (size_t)(end - line);
        for (int k = 0; k < best; k++) {
            if (strlen(keys[k]) == klen && memcmp(line, keys[k], klen) == 0) {
                char *v = colon + 1;
                while (*v == ' ' || *v == '\t')
                    v++;
                v[strcspn(v, "\r\n")] = '\0';
                if (*v) {
                    tb__copy(dst, n, v);
                    best = k;
                }
                break;
            }
        }
        if (best == 0)
            break;
    }
    fclose(f);
}

tb_status tb_provenance_init(tb_provenance *p, int argc, char **argv)
{
    if (!p || argc < 0 || (argc > 0 && !argv))
        return tb_error(TB_ERR_ARG, "tb_provenance_init: bad arguments");
    memset(p, 0, sizeof *p);
    tb__copy(p->version, sizeof p->version, TB_VERSION_STRING);
    tb__copy(p->git_revision, sizeof p->git_revision, TB_GIT_REVISION);
    p->command_line = tb__join_args(argc, argv);
    if (!p->command_line)
        return tb_error(TB_ERR_NOMEM, "provenance: out of memory");

    if (gethostname(p->hostname, sizeof p->hostname) != 0)
        p->hostname[0] = '\0';
    p->hostname[sizeof p->hostname - 1] = '\0'; /* gethostname need not terminate on truncation */
    struct utsname u;
    if (uname(&u) == 0)
        snprintf(p->os, sizeof p->os, "%s %s %s", u.sysname, u.release, u.machine);
    tb__cpu_model(p->cpu, sizeof p->cpu);
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    p->cores = cores > 0 ? (int)cores : 0;
    p->threads = omp_get_max_threads();

    time_t now = time(NULL);
    struct tm tm;
    if (now != (time_t)-1 && gmtime_r(&now, &tm))
        strftime(p->time_utc, sizeof p->time_utc, "%Y-%m-%dT%H:%M:%SZ", &tm);
    return TB_OK;
}

void tb_provenance_free(tb_provenance *p)
{
    if (!p)
        return;
    free(p->command_line);
    free(p->options);
    free(p->scene);
    p->command_line = p->options = p->scene = NULL;
}

tb_status tb_provenance_set_options(tb_provenance *p, const char *options)
{
    if (!p || !options)
        return tb_error(TB_ERR_ARG, "tb_provenance_set_options: NULL argument");
    char *copy = tb_strdup(options);
    if (!copy)
        return tb_error(TB_ERR_NOMEM, "provenance: out of memory");
    free(p->options);
    p->options = copy;
    return TB_OK;
}

void tb_provenance_set_seed(tb_provenance *p, uint64_t seed)
{
    p->seed = seed;
    p->has_seed = 1;
}

/* ---------------------------------------------------------------- SHA-256 */

static void tb__hex(const unsigned char *md, unsigned len, char *hex)
{
    static const char digits[] = "0123456789abcdef";
    for (unsigned i = 0; i < len; i++) {
        hex[2 * i] = digits[md[i] >> 4];
        hex[2 * i + 1] = digits[md[i] & 15];
    }
    hex[2 * len] = '\0';
}

/* Finishes `ctx` into `hex`; frees ctx. */
static tb_status tb__sha256_final(EVP_MD_CTX *ctx, char hex[TB_SHA256_HEX_SIZE])
{
    unsigned char md[EVP_MAX_MD_SIZE];
    unsigned len = 0;
    int ok = EVP_DigestFinal_ex(ctx, md, &len) == 1 && len == 32;
    EVP_MD_CTX_free(ctx);
    if (!ok)
        return tb_error(TB_ERR_UNSUPPORTED, "SHA-256: OpenSSL digest failed");
    tb__hex(md, len, hex);
    return TB_OK;
}

static EVP_MD_CTX *tb__sha256_begin(void)
{
    EVP_MD_CTX *ctx = EVP_MD_CTX_new();
    if (ctx && EVP_DigestInit_ex(ctx, EVP_sha256(), NULL) != 1) {
        EVP_MD_CTX_free(ctx);
        ctx = NULL;
    }
    if (!ctx)
        tb_error(TB_ERR_UNSUPPORTED, "SHA-256: OpenSSL cannot create a digest context");
    return ctx;
}

tb_status tb_sha256_hex(const void *data, size_t n, char hex[TB_SHA256_HEX_SIZE])
{
    if ((!data && n) || !hex)
        return tb_error(TB_ERR_ARG, "tb_sha256_hex: NULL argument");
    EVP_MD_CTX *ctx = tb__sha256_begin();
    if (!ctx)
        return TB_ERR_UNSUPPORTED;
    if (n && EVP_DigestUpdate(ctx, data, n) != 1) {
        EVP_MD_CTX_free(ctx);
        return tb_error(TB_ERR_UNSUPPORTED, "SHA-256: OpenSSL digest failed");
    }
    return tb__sha256_final(ctx, hex);
}

tb_status tb_sha256_file(const char *path, char hex[TB_SHA256_HEX_SIZE])
{
    if (!path || !hex)
        return tb_error(TB_ERR_ARG, "tb_sha256_file: NULL argument");
    FILE *f = fopen(path, "rb");
    if (!f)
        return tb_error(TB_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    enum { BUF = 1 << 16 };
    unsigned char *buf = malloc(BUF);
    EVP_MD_CTX *ctx = buf ? tb__sha256_begin() : NULL;
    if (!ctx) {
        fclose(f);
        free(buf);
        return buf ? tb_error_context(TB_ERR_UNSUPPORTED, "%s", path)
                   : tb_error(TB_ERR_NOMEM, "%s: out of memory", path);
    }
    size_t got;
    int ok = 1;
    while ((got = fread(buf, 1, BUF, f)) > 0)
        if (EVP_DigestUpdate(ctx, buf, got) != 1)
            ok = 0;
    int read_err = ferror(f) ? errno : 0;
    int failed_read = ferror(f) != 0;
    fclose(f);
    free(buf);
    if (failed_read || !ok) {
        EVP_MD_CTX_free(ctx);
        if (failed_read)
            return tb_error(TB_ERR_IO, "%s: read failed: %s", path, strerror(read_err ? read_err : EIO));
        return tb_error(TB_ERR_UNSUPPORTED, "%s: SHA-256: OpenSSL digest failed", path);
    }
    return tb__sha256_final(ctx, hex);
}

tb_status tb_provenance_hash_file(tb_provenance *p, const char *path)
{
    if (!p || !path)
        return tb_error(TB_ERR_ARG, "tb_provenance_hash_file: NULL argument");
    char hex[TB_SHA256_HEX_SIZE];
    tb_status st = tb_sha256_file(path, hex);
    if (st)
        return st;
    char *copy = tb_strdup(path);
    if (!copy)
        return tb_error(TB_ERR_NOMEM, "provenance: out of memory");
    free(p->scene);
    p->scene = copy;
    memcpy(p->scene_sha256, hex, sizeof hex);
    return TB_OK;
}

/* ---------------------------------------------------------------- output */

/* One provenance entry; `str` NULL means unknown (JSON null, no image attribute). */
typedef struct tb__field {
    const char *key;
    const char *str;
    int numeric;     /* write `str` unquoted in JSON */
} tb__field;

/* The provenance as (key, value) pairs, in a fixed order; `num` holds the text
 * of the numeric fields. Returns the number of fields. */
static int tb__fields(const tb_provenance *p, tb__field f[16], char num[3][32])
{
#define TB__S(s) ((s) && (s)[0] ? (s) : NULL)
    int n = 0;
    snprintf(num[0], 32, "%d", p->cores);
    snprintf(num[1], 32, "%d", p->threads);
    snprintf(num[2], 32, "%" PRIu64, p->seed);
    f[n++] = (tb__field){"version", TB__S(p->version), 0};
    f[n++] = (tb__field){"git_revision", TB__S(p->git_revision), 0};
    f[n++] = (tb__field){"command_line", TB__S(p->command_line), 0};
    f[n++] = (tb__field){"options", TB__S(p->options), 0};
    f[n++] = (tb__field){"scene", TB__S(p->scene), 0};
    f[n++] = (tb__field){"scene_sha256", TB__S(p->scene_sha256), 0};
    f[n++] = (tb__field){"hostname", TB__S(p->hostname), 0};
    f[n++] = (tb__field){"os", TB__S(p->os), 0};
    f[n++] = (tb__field){"cpu", TB__S(p->cpu), 0};
    f[n++] = (tb__field){"cores", p->cores > 0 ? num[0] : NULL, 1};
    f[n++] = (tb__field){"threads", p->threads > 0 ? num[1] : NULL, 1};
    f[n++] = (tb__field){"time_utc", TB__S(p->time_utc), 0};
    f[n++] = (tb__field){"seed", p->has_seed ? num[2] : NULL, 1};
#undef TB__S
    return n;
}

tb_status tb_provenance_to_attrs(const tb_provenance *p, struct tb_image *img)
{
    if (!p || !img)
        return tb_error(TB_ERR_ARG, "tb_provenance_to_attrs: NULL argument");
    tb__field f[16];
    char num[3][32];
    int n = tb__fields(p, f, num);
    for (int i = 0; i < n; i++) {
        if (!f[i].str)
            continue;
        char key[64];
        snprintf(key, sizeof key, "testbed:%s", f[i].key);
        tb_status st = tb_image_set_attr(img, key, f[i].str);
        if (st)
            return st;
    }
    return TB_OK;
}

void tb_provenance_write_json(FILE *out, const tb_provenance *p, int indent)
{
    tb__field f[16];
    char num[3][32];
    int n = tb__fields(p, f, num);
    fputc('{', out);
    for (int i = 0; i < n; i++) {
        fprintf(out, "%s\n%*s", i ? "," : "", indent + 2, "");
        tb_json_write_string(out, f[i].key);
        fputs(": ", out);
        if (!f[i].str)
            fputs("null", out);
        else if (f[i].numeric)
            fputs(f[i].str, out);
        else
            tb_json_write_string(out, f[i].str);
    }
    fprintf(out, "\n%*s}", indent, "");
}
