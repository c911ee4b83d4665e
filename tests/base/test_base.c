/* util/base: error messages and all-or-nothing output files. */
#define _DEFAULT_SOURCE /* mknod and makedev, to make a device to write to */
#include "tb_test.h"

#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "util/base/error.h"
#include "util/base/outfile.h"

#include <sys/sysmacros.h>

static void test_error_message_and_context(void **state)
{
    (void)state;
    tb_clear_error();
    assert_string_equal(tb_last_error(), "");
    assert_int_equal(tb_error(TB_ERR_FORMAT, "bad token '%s'", "x"), TB_ERR_FORMAT);
    assert_string_equal(tb_last_error(), "bad token 'x'");
    assert_int_equal(tb_error_context(TB_ERR_FORMAT, "scene.mid:%d:%d", 3, 7), TB_ERR_FORMAT);
    assert_string_equal(tb_last_error(), "scene.mid:3:7: bad token 'x'");
    assert_string_equal(tb_status_name(TB_ERR_NOMEM), "out of memory");
}

static int tb__count_tmp_files(const char *dir, const char *base)
{
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "ls -a '%s' | grep -c '^%s\\.tmp\\.' || true", dir, base);
    FILE *p = popen(cmd, "r");
    int n = 0;
    if (p) {
        if (fscanf(p, "%d", &n) != 1)
            n = -1;
        pclose(p);
    }
    return n;
}

static void test_outfile_commit_replaces_whole(void **state)
{
    (void)state;
    char path[512];
    snprintf(path, sizeof path, "%s/outfile_commit.txt", tb_test_tmpdir());
    tb_outfile of;
    assert_int_equal(tb_outfile_open(&of, path), TB_OK);
    fputs("first", of.fp);
    assert_int_equal(tb_outfile_commit(&of), TB_OK);

    /* A second write that is aborted leaves the first file untouched. */
    assert_int_equal(tb_outfile_open(&of, path), TB_OK);
    fputs("second, never committed", of.fp);
    tb_outfile_abort(&of);
    tb_outfile_abort(&of); /* twice is harmless */

    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    char buf[64] = {0};
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    assert_int_equal(n, 5);
    assert_string_equal(buf, "first");
    assert_int_equal(tb__count_tmp_files(tb_test_tmpdir(), "outfile_commit.txt"), 0);
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    mode_t mask = umask(0);
    umask(mask);
    assert_int_equal(st.st_mode & 0777, 0666 & ~mask); /* not mkstemp's 0600 */
    unlink(path);
}

/* A device as the output (`-o /dev/null`, `--stats /dev/stdout`) is written
 * in place: renaming the temporary file over it would replace the device node
 * with a regular file (as root, /dev/null itself). Tested on a null device
 * made in the test folder; skipped where mknod is not allowed (not root). */
static void test_outfile_device_in_place(void **state)
{
    (void)state;
    char path[512];
    snprintf(path, sizeof path, "%s/outfile_null_device", tb_test_tmpdir());
    unlink(path);
    if (mknod(path, S_IFCHR | 0666, makedev(1, 3)) != 0)
        skip();
    tb_outfile of;
    assert_int_equal(tb_outfile_open(&of, path), TB_OK);
    fputs("discarded", of.fp);
    assert_int_equal(tb_outfile_commit(&of), TB_OK);
    assert_int_equal(tb_outfile_open(&of, path), TB_OK);
    tb_outfile_abort(&of); /* an abort leaves the device too */
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    assert_true(S_ISCHR(st.st_mode));
    assert_int_equal(tb__count_tmp_files(tb_test_tmpdir(), "outfile_null_device"), 0);
    unlink(path);
}

static void test_outfile_bad_folder(void **state)
{
    (void)state;
    tb_outfile of;
    assert_int_equal(tb_outfile_open(&of, "/nonexistent-folder/x.png"), TB_ERR_IO);
    assert_non_null(strstr(tb_last_error(), "/nonexistent-folder/x.png"));
    assert_int_equal(tb_outfile_open(&of, ""), TB_ERR_ARG);
}

static void test_rng_reference_and_streams(void **state)
{
    (void)state;
    /* First outputs of the PCG32 reference demo (seed 42, stream 54). */
    tb_rng r;
    tb_rng_seed(&r, 42u, 54u);
    const uint32_t expect[6] = {0xa15c02b7, 0x7b47f409, 0xba1d3330, 0x83d2f293, 0xbfa4784b, 0xcbed606e};
    for (int i = 0; i < 6; i++)
        assert_int_equal(tb_rng_u32(&r), expect[i]);
    tb_rng a, b;
    tb_rng_seed(&a, 1, 1);
    tb_rng_seed(&b, 1, 2);
    int same = 0;
    for (int i = 0; i < 100; i++)
        same += tb_rng_u32(&a) == tb_rng_u32(&b);
    assert_true(same < 3);
    double sum = 0;
    for (int i = 0; i < 100000; i++) {
        float f = tb_rng_float(&a);
        double d = tb_rng_double(&a);
        assert_true(f >= 0.0f && f < 1.0f);
        assert_true(d >= 0.0 && d < 1.0);
        uint32_t k = tb_rng_below(&a, 7);
        assert_true(k < 7);
        sum += d;
    }
    tb_assert_near(sum / 100000.0, 0.5, 0.01);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_error_message_and_context),
        cmocka_unit_test(test_outfile_commit_replaces_whole),
        cmocka_unit_test(test_outfile_device_in_place),
        cmocka_unit_test(test_outfile_bad_folder),
        cmocka_unit_test(test_rng_reference_and_streams),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
