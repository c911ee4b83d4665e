/* tb_image_read / tb_image_write: dispatch by extension, and the promise that
 * a failed write leaves nothing behind (no partial file, no temporary file,
 * an existing file untouched), including a failure halfway through the data
 * (the file-size limit makes the operating system refuse a write). */
#include "tb_test.h"

#include <dirent.h>
#include <math.h>
#include <signal.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "util/image/image.h"

static char g_dir[512];

/* A fresh, empty folder for this test program. */
static int setup(void **state)
{
    (void)state;
    snprintf(g_dir, sizeof g_dir, "%s/image_io_%d", tb_test_tmpdir(), (int)getpid());
    mkdir(g_dir, 0777);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    DIR *d = opendir(g_dir);
    struct dirent *e;
    char p[1024];
    while (d && (e = readdir(d))) {
        if (e->d_name[0] == '.')
            continue;
        snprintf(p, sizeof p, "%s/%s", g_dir, e->d_name);
        unlink(p);
    }
    if (d)
        closedir(d);
    rmdir(g_dir);
    return 0;
}

static const char *path_of(const char *name)
{
    static char p[1024];
    snprintf(p, sizeof p, "%s/%s", g_dir, name);
    return p;
}

/* Number of entries in the folder whose name starts with `prefix`. */
static int count_files(const char *prefix)
{
    DIR *d = opendir(g_dir);
    assert_non_null(d);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        if (strncmp(e->d_name, prefix, strlen(prefix)) == 0)
            n++;
    closedir(d);
    return n;
}

/* 8-bit sRGB codes, so every format (RLE and PNG included) holds them exactly. */
static tb_image *coded_image(int w, int h, int c)
{
    tb_image *img = tb_image_create(w, h, c, NULL);
    for (int i = 0; i < w * h * c; i++)
        img->pixels[i] = tb_image_dequantize8((unsigned char)((i * 37 + i / 7) & 0xff), TB_ENCODING_SRGB);
    return img;
}

static void test_dispatch_round_trip(void **state)
{
    (void)state;
    const char *names[] = {"a.png", "b.PFM", "c.exr", "d.rle", "e.Png"};
    for (size_t k = 0; k < sizeof names / sizeof *names; k++) {
        tb_image *img = coded_image(11, 6, 3);
        assert_int_equal(tb_image_set_attr(img, "k", "v"), TB_OK);
        const char *p = path_of(names[k]);
        if (tb_image_write(p, img, NULL) != TB_OK)
            fail_msg("%s: %s", names[k], tb_last_error());
        tb_image *back = NULL;
        if (tb_image_read(p, NULL, &back) != TB_OK)
            fail_msg("%s: %s", names[k], tb_last_error());
        assert_int_equal(back->width, 11);
        assert_int_equal(back->height, 6);
        assert_int_equal(back->channels, 3);
        for (int i = 0; i < 11 * 6 * 3; i++)
            if (back->pixels[i] != img->pixels[i])
                fail_msg("%s: value %d is %.9g, wrote %.9g", names[k], i, back->pixels[i], img->pixels[i]);
        tb_image_free(back);
        tb_image_free(img);
    }
    /* The format follows the extension, not the content: a PNG named .pfm is refused. */
    tb_image *img = coded_image(2, 2, 3);
    assert_int_equal(tb_image_write(path_of("real.png"), img, NULL), TB_OK);
    char from[1024];
    snprintf(from, sizeof from, "%s", path_of("real.png")); /* path_of reuses one buffer */
    assert_int_equal(rename(from, path_of("fake.pfm")), 0);
    tb_image *back = NULL;
    assert_int_equal(tb_image_read(path_of("fake.pfm"), NULL, &back), TB_ERR_FORMAT);
    assert_null(back);
    assert_non_null(strstr(tb_last_error(), "fake.pfm"));
    tb_image_free(img);
}

/* tb_image_write_exposed: automatic exposure takes the mean luminance to
 * 0.18 (a uniform 0.72 grey is 2 stops over, so -2), is recorded, and
 * scales the display formats only; an explicit exposure is kept as given. */
static void test_write_exposed(void **state)
{
    (void)state;
    tb_image *img = tb_image_create(4, 3, 3, NULL);
    for (int i = 0; i < 4 * 3 * 3; i++)
        img->pixels[i] = 0.72f;
    assert_int_equal(tb_image_write_exposed(path_of("auto.pfm"), img, NAN), TB_OK);
    assert_null(tb_image_get_attr(img, "exposure")); /* HDR: written as it is */
    assert_int_equal(tb_image_write_exposed(path_of("auto.png"), img, NAN), TB_OK);
    assert_string_equal(tb_image_get_attr(img, "exposure"), "-2");
    tb_image *back = NULL;
    assert_int_equal(tb_image_read(path_of("auto.png"), NULL, &back), TB_OK);
    for (int i = 0; i < 4 * 3 * 3; i++) /* 0.72 * 2^-2 = 0.18, one sRGB code apart at most */
        assert_true(fabsf(back->pixels[i] - 0.18f) < 0.002f);
    tb_image_free(back);
    assert_int_equal(tb_image_write_exposed(path_of("one.png"), img, 1.0), TB_OK);
    assert_string_equal(tb_image_get_attr(img, "exposure"), "1");
    back = NULL;
    assert_int_equal(tb_image_read(path_of("one.png"), NULL, &back), TB_OK);
    assert_true(fabsf(back->pixels[0] - 1.0f) < 1e-6f); /* 1.44 clipped to white */
    tb_image_free(back);
    tb_image_free(img);
}

static void test_bad_names(void **state)
{
    (void)state;
    tb_image *img = coded_image(2, 2, 3);
    assert_int_equal(tb_image_write(path_of("x.jpg"), img, NULL), TB_ERR_ARG);
    assert_non_null(strstr(tb_last_error(), "unknown image format"));
    assert_int_equal(count_files("x.jpg"), 0);
    tb_image *back = (tb_image *)&back;
    assert_int_equal(tb_image_read(path_of("x.jpg"), NULL, &back), TB_ERR_ARG);
    assert_null(back);
    assert_int_equal(tb_image_read(path_of("missing.png"), NULL, &back), TB_ERR_NOT_FOUND);
    assert_non_null(strstr(tb_last_error(), "missing.png"));
    assert_int_equal(tb_image_read(path_of("missing.exr"), NULL, &back), TB_ERR_NOT_FOUND);
    assert_int_equal(tb_image_write("", img, NULL), TB_ERR_ARG);
    assert_int_equal(tb_image_write(path_of("n.png"), NULL, NULL), TB_ERR_ARG);
    tb_image_write_options o = {.exposure = INFINITY};
    assert_int_equal(tb_image_write(path_of("n.png"), img, &o), TB_ERR_ARG);
    assert_int_equal(count_files("n.png"), 0);
    tb_image_free(img);
}

/* Folders that cannot hold the file: nothing is created anywhere. */
static void test_unwritable_folder(void **state)
{
    (void)state;
    tb_image *img = coded_image(4, 4, 3);
    FILE *f = fopen(path_of("plainfile"), "wb");
    fputs("x", f);
    fclose(f);
    const char *exts[] = {"png", "pfm", "exr", "rle"};
    for (int k = 0; k < 4; k++) {
        char p[1024];
        snprintf(p, sizeof p, "%s/no/such/dir/out.%s", g_dir, exts[k]);
        assert_int_equal(tb_image_write(p, img, NULL), TB_ERR_IO);
        assert_non_null(strstr(tb_last_error(), "out."));
        snprintf(p, sizeof p, "%s/plainfile/out.%s", g_dir, exts[k]);
        assert_int_equal(tb_image_write(p, img, NULL), TB_ERR_IO);
    }
    assert_int_equal(count_files("no"), 0);
    assert_int_equal(count_files("plainfile"), 1);
    tb_image_free(img);
}

/* A writer that refuses the image (too many channels for the format) leaves
 * the existing file as it was and no temporary file. */
static void test_refused_image_keeps_old_file(void **state)
{
    (void)state;
    tb_image *five = coded_image(3, 3, 5);
    tb_image *four = coded_image(3, 3, 4);
    const char *cases[][2] = {{"keep.png", "5"}, {"keep.pfm", "4"}};
    for (int k = 0; k < 2; k++) {
        const char *p = path_of(cases[k][0]);
        FILE *f = fopen(p, "wb");
        fputs("old contents", f);
        fclose(f);
        assert_int_equal(tb_image_write(p, cases[k][1][0] == '5' ? five : four, NULL), TB_ERR_UNSUPPORTED);
        f = fopen(p, "rb");
        char buf[32] = {0};
        assert_non_null(fgets(buf, sizeof buf, f));
        fclose(f);
        assert_string_equal(buf, "old contents");
        assert_int_equal(count_files(cases[k][0]), 1); /* no keep.xxx.tmp.* */
    }
    /* OpenEXR's own checks fail before any byte is written, too. */
    const char *dup[] = {"R", "R"};
    tb_image *d = tb_image_create(2, 2, 2, dup);
    assert_int_equal(tb_image_write(path_of("dup.exr"), d, NULL), TB_ERR_ARG);
    assert_int_equal(count_files("dup.exr"), 0);
    tb_image_free(d);
    tb_image_free(five);
    tb_image_free(four);
}

/* The operating system refuses to grow any file beyond 16 KiB while each
 * format writes ~200-800 KiB: every writer fails partway, and nothing is
 * left, while a file already there survives unchanged. */
static void test_failure_mid_write(void **state)
{
    (void)state;
    tb_rng rng;
    tb_rng_seed(&rng, tb_test_seed("mid-write failure", 5), 0);
    tb_image *img = tb_image_create(256, 256, 3, NULL);
    for (int i = 0; i < 256 * 256 * 3; i++)
        img->pixels[i] = tb_rng_float(&rng); /* noise: compresses badly */
    const char *names[] = {"big.png", "big.pfm", "big.exr", "big.rle"};
    for (int k = 0; k < 4; k++) {
        /* A complete file first, to check it survives the failed overwrite. */
        assert_int_equal(tb_image_write(path_of(names[k]), img, NULL), TB_OK);
        struct stat before;
        assert_int_equal(stat(path_of(names[k]), &before), 0);
        assert_true(before.st_size > 64 * 1024);

        struct rlimit old, lim;
        assert_int_equal(getrlimit(RLIMIT_FSIZE, &old), 0);
        lim = old;
        lim.rlim_cur = 16 * 1024;
        void (*prev)(int) = signal(SIGXFSZ, SIG_IGN); /* get EFBIG, not a signal */
        assert_int_equal(setrlimit(RLIMIT_FSIZE, &lim), 0);
        img->pixels[0] = 0.5f; /* different contents from the file on disk */
        tb_status st = tb_image_write(path_of(names[k]), img, NULL);
        setrlimit(RLIMIT_FSIZE, &old);
        signal(SIGXFSZ, prev);
        if (st != TB_ERR_IO)
            fail_msg("%s: status %d (%s)", names[k], st, tb_last_error());
        assert_non_null(strstr(tb_last_error(), names[k]));

        struct stat after;
        assert_int_equal(stat(path_of(names[k]), &after), 0);
        assert_int_equal(after.st_size, before.st_size);
        assert_int_equal(after.st_mtime, before.st_mtime);
        assert_int_equal(count_files(names[k]), 1); /* no temporary file left */
        tb_image *back = NULL;
        assert_int_equal(tb_image_read(path_of(names[k]), NULL, &back), TB_OK);
        tb_image_free(back);
    }
    tb_image_free(img);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_dispatch_round_trip),
        cmocka_unit_test(test_write_exposed),
        cmocka_unit_test(test_bad_names),
        cmocka_unit_test(test_unwritable_folder),
        cmocka_unit_test(test_refused_image_keeps_old_file),
        cmocka_unit_test(test_failure_mid_write),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
