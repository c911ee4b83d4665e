/* util/stats/provenance: SHA-256 against the published test vectors, the
 * command line, and provenance stored as image attributes. */
#include "tb_test.h"

#include <string.h>
#include <unistd.h>

#include "tb_version.h"
#include "util/image/image.h"
#include "util/stats/provenance.h"

/* FIPS 180-2 / NIST CSRC example vectors for SHA-256. */
#define SHA_EMPTY "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"
#define SHA_ABC "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
#define SHA_448 "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1"
#define SHA_MILLION_A "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0"

static void tb__write_file(const char *path, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, n, f), n);
    assert_int_equal(fclose(f), 0);
}

static void test_sha256_vectors_in_memory(void **state)
{
    (void)state;
    char hex[TB_SHA256_HEX_SIZE];
    assert_int_equal(tb_sha256_hex("", 0, hex), TB_OK);
    assert_string_equal(hex, SHA_EMPTY);
    assert_int_equal(tb_sha256_hex(NULL, 0, hex), TB_OK);
    assert_string_equal(hex, SHA_EMPTY);
    assert_int_equal(tb_sha256_hex("abc", 3, hex), TB_OK);
    assert_string_equal(hex, SHA_ABC);
    const char *m448 = "abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq";
    assert_int_equal(tb_sha256_hex(m448, strlen(m448), hex), TB_OK);
    assert_string_equal(hex, SHA_448);
}

static void test_sha256_files(void **state)
{
    (void)state;
    char path[512], hex[TB_SHA256_HEX_SIZE];
    snprintf(path, sizeof path, "%s/prov_empty.bin", tb_test_tmpdir());
    tb__write_file(path, "", 0);
    assert_int_equal(tb_sha256_file(path, hex), TB_OK);
    assert_string_equal(hex, SHA_EMPTY);
    tb__write_file(path, "abc", 3);
    assert_int_equal(tb_sha256_file(path, hex), TB_OK);
    assert_string_equal(hex, SHA_ABC);
    /* One million 'a': longer than the 64 KiB read buffer, so chunking is tested. */
    char *a = malloc(1000000);
    assert_non_null(a);
    memset(a, 'a', 1000000);
    tb__write_file(path, a, 1000000);
    free(a);
    assert_int_equal(tb_sha256_file(path, hex), TB_OK);
    assert_string_equal(hex, SHA_MILLION_A);
    unlink(path);

    assert_int_equal(tb_sha256_file("/nonexistent/scene.mid", hex), TB_ERR_IO);
    assert_non_null(strstr(tb_last_error(), "/nonexistent/scene.mid"));
    assert_int_equal(tb_sha256_file(tb_test_tmpdir(), hex), TB_ERR_IO); /* a folder */
}

static void test_provenance_fields(void **state)
{
    (void)state;
    char *argv[] = {"testbed", "render", "my scene.mid", "it's", "--spp=16", ""};
    tb_provenance p;
    assert_int_equal(tb_provenance_init(&p, 6, argv), TB_OK);
    assert_string_equal(p.command_line, "testbed render 'my scene.mid' 'it'\\''s' --spp=16 ''");
    assert_string_equal(p.version, TB_VERSION_STRING);
    assert_string_equal(p.git_revision, TB_GIT_REVISION);
    /* YYYY-MM-DDTHH:MM:SSZ */
    assert_int_equal(strlen(p.time_utc), 20);
    const char *pattern = "dddd-dd-ddTdd:dd:ddZ";
    for (int i = 0; i < 20; i++) {
        if (pattern[i] == 'd')
            assert_true(p.time_utc[i] >= '0' && p.time_utc[i] <= '9');
        else
            assert_int_equal(p.time_utc[i], pattern[i]);
    }
    assert_true(p.cores >= 1);
    assert_true(p.threads >= 1);
    assert_true(strlen(p.os) > 0);
    assert_null(p.scene);
    assert_string_equal(p.scene_sha256, "");
    assert_false(p.has_seed);
    tb_provenance_free(&p);

    assert_int_equal(tb_provenance_init(&p, 0, NULL), TB_OK);
    assert_string_equal(p.command_line, "");
    tb_provenance_free(&p);
    assert_int_equal(tb_provenance_init(&p, 1, NULL), TB_ERR_ARG);
}

static void test_provenance_to_image_attrs(void **state)
{
    (void)state;
    char path[512];
    snprintf(path, sizeof path, "%s/prov_scene.mid", tb_test_tmpdir());
    tb__write_file(path, "abc", 3);
    char *argv[] = {"testbed", "render", path};
    tb_provenance p;
    assert_int_equal(tb_provenance_init(&p, 3, argv), TB_OK);
    tb_image *img = tb_image_create(2, 2, 3, NULL);
    assert_non_null(img);

    /* Unknown fields are left out. */
    assert_int_equal(tb_provenance_to_attrs(&p, img), TB_OK);
    assert_null(tb_image_get_attr(img, "testbed:scene_sha256"));
    assert_null(tb_image_get_attr(img, "testbed:seed"));
    assert_null(tb_image_get_attr(img, "testbed:options"));

    assert_int_equal(tb_provenance_hash_file(&p, path), TB_OK);
    tb_provenance_set_seed(&p, 18446744073709551615u);
    assert_int_equal(tb_provenance_set_options(&p, "spp=16 depth=5"), TB_OK);
    assert_int_equal(tb_provenance_to_attrs(&p, img), TB_OK);
    assert_string_equal(tb_image_get_attr(img, "testbed:scene_sha256"), SHA_ABC);
    assert_string_equal(tb_image_get_attr(img, "testbed:scene"), path);
    assert_string_equal(tb_image_get_attr(img, "testbed:seed"), "18446744073709551615");
    assert_string_equal(tb_image_get_attr(img, "testbed:options"), "spp=16 depth=5");
    assert_string_equal(tb_image_get_attr(img, "testbed:version"), TB_VERSION_STRING);
    assert_string_equal(tb_image_get_attr(img, "testbed:git_revision"), TB_GIT_REVISION);
    assert_string_equal(tb_image_get_attr(img, "testbed:command_line"), p.command_line);
    assert_string_equal(tb_image_get_attr(img, "testbed:time_utc"), p.time_utc);
    assert_string_equal(tb_image_get_attr(img, "testbed:os"), p.os);
    char cores[16];
    snprintf(cores, sizeof cores, "%d", p.cores);
    assert_string_equal(tb_image_get_attr(img, "testbed:cores"), cores);

    /* A failed hash keeps the earlier input. */
    assert_int_equal(tb_provenance_hash_file(&p, "/nonexistent/x.mid"), TB_ERR_IO);
    assert_string_equal(p.scene_sha256, SHA_ABC);

    tb_image_free(img);
    tb_provenance_free(&p);
    unlink(path);
}

/* The attributes reach the file: written and read back in each format that
 * stores strings (the image writers carry attributes; util/image/image.h). */
static void test_provenance_survives_image_files(void **state)
{
    (void)state;
    char *argv[] = {"testbed", "render", "sc\xc3\xa8ne \"1\".mid"};
    tb_provenance p;
    assert_int_equal(tb_provenance_init(&p, 3, argv), TB_OK);
    tb_provenance_set_seed(&p, 7);
    tb_image *img = tb_image_create(3, 2, 3, NULL);
    assert_non_null(img);
    assert_int_equal(tb_provenance_to_attrs(&p, img), TB_OK);
    const char *exts[] = {"png", "exr", "rle"};
    for (int i = 0; i < 3; i++) {
        char path[512];
        snprintf(path, sizeof path, "%s/prov_attrs.%s", tb_test_tmpdir(), exts[i]);
        assert_int_equal(tb_image_write(path, img, NULL), TB_OK);
        tb_image *back = NULL;
        if (tb_image_read(path, NULL, &back) != TB_OK)
            fail_msg("%s: %s", path, tb_last_error());
        const char *cl = tb_image_get_attr(back, "testbed:command_line");
        if (!cl)
            fail_msg("%s: no testbed:command_line after the round trip", exts[i]);
        assert_string_equal(cl, p.command_line);
        assert_string_equal(tb_image_get_attr(back, "testbed:seed"), "7");
        assert_string_equal(tb_image_get_attr(back, "testbed:version"), TB_VERSION_STRING);
        tb_image_free(back);
        unlink(path);
    }
    tb_image_free(img);
    tb_provenance_free(&p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sha256_vectors_in_memory),
        cmocka_unit_test(test_sha256_files),
        cmocka_unit_test(test_provenance_fields),
        cmocka_unit_test(test_provenance_to_image_attrs),
        cmocka_unit_test(test_provenance_survives_image_files),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
