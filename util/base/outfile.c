#include "util/base/outfile.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static void tb__outfile_free(tb_outfile *of)
{
    free(of->path);
    free(of->tmp_path);
    of->path = of->tmp_path = NULL;
    of->fp = NULL;
}

tb_status tb_outfile_open(tb_outfile *of, const char *path)
{
    memset(of, 0, sizeof *of);
    if (!path || !*path)
        return tb_error(TB_ERR_ARG, "empty output file name");
    size_t n = strlen(path);
    of->path = malloc(n + 1);
    of->tmp_path = malloc(n + 16);
    if (!of->path || !of->tmp_path) {
        tb__outfile_free(of);
        return tb_error(TB_ERR_NOMEM, "%s: out of memory", path);
    }
    memcpy(of->path, path, n + 1);
    struct stat sb;
    if (stat(path, &sb) == 0 && !S_ISREG(sb.st_mode) && !S_ISDIR(sb.st_mode)) {
        /* a device or FIFO: nothing to replace atomically, and a rename would replace the node itself */
        free(of->tmp_path);
        of->tmp_path = NULL;
        of->fp = fopen(path, "wb");
        if (!of->fp) {
            tb_status st = tb_error(TB_ERR_IO, "%s: cannot open output file: %s", path, strerror(errno));
            tb__outfile_free(of);
            return st;
        }
        return TB_OK;
    }
    /* A dot-prefixed name would be nicer but needs splitting the folder off;
     * a suffix keeps the file in the same folder, which is what rename needs. */
    snprintf(of->tmp_path, n + 16, "%s.tmp.XXXXXX", path);
    int fd = mkstemp(of->tmp_path);
    if (fd < 0) {
        tb_status st = tb_error(TB_ERR_IO, "%s: cannot create output file: %s", path, strerror(errno));
        tb__outfile_free(of);
        return st;
    }
    of->fp = fdopen(fd, "wb");
    if (!of->fp) {
        tb_status st = tb_error(TB_ERR_IO, "%s: %s", path, strerror(errno));
        close(fd);
        unlink(of->tmp_path);
        tb__outfile_free(of);
        return st;
    }
    return TB_OK;
}

tb_status tb_outfile_commit(tb_outfile *of)
{
    if (!of->fp)
        return tb_error(TB_ERR_ARG, "output file is not open");
    int failed = ferror(of->fp) != 0;
    int err = failed ? EIO : 0;
    if (fflush(of->fp) != 0) { failed = 1; err = errno; }
    if (fclose(of->fp) != 0 && !failed) { failed = 1; err = errno; }
    of->fp = NULL;
    if (!failed && of->tmp_path) {
        /* mkstemp creates 0600; give the file the usual permissions. */
        mode_t mask = umask(0);
        umask(mask);
        chmod(of->tmp_path, 0666 & ~mask);
        if (rename(of->tmp_path, of->path) != 0) { failed = 1; err = errno; }
    }
    if (failed) {
        tb_status st = tb_error(TB_ERR_IO, "%s: write failed: %s", of->path, strerror(err));
        if (of->tmp_path)
            unlink(of->tmp_path);
        tb__outfile_free(of);
        return st;
    }
    tb__outfile_free(of);
    return TB_OK;
}

void tb_outfile_abort(tb_outfile *of)
{
    if (of->fp) {
        fclose(of->fp);
        of->fp = NULL;
    }
    if (of->tmp_path)
        unlink(of->tmp_path);
    tb__outfile_free(of);
}
