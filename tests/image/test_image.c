/* The image buffer: construction, names, attributes, format by extension and
 * integer quantisation. */
#include "tb_test.h"

#include <string.h>

#include "util/color/srgb.h"
#include "util/image/image.h"

static void test_create_defaults(void **state)
{
    (void)state;
    static const char *const expect[5][5] = {
        {"Y"}, {"Y", "A"}, {"R", "G", "B"}, {"R", "G", "B", "A"}, {"R", "G", "B", "A", "C4"}};
    for (int n = 1; n <= 5; n++) {
        tb_image *img = tb_image_create(3, 2, n, NULL);
        assert_non_null(img);
        assert_int_equal(img->width, 3);
        assert_int_equal(img->height, 2);
        assert_int_equal(img->channels, n);
        assert_int_equal(img->nattrs, 0);
        for (int c = 0; c < n; c++) {
            assert_string_equal(img->names[c], expect[n - 1][c]);
            assert_int_equal(tb_image_channel(img, expect[n - 1][c]), c);
        }
        for (int i = 0; i < 3 * 2 * n; i++)
            assert_true(img->pixels[i] == 0.0f);
        tb_image_free(img);
    }
    tb_image *img = tb_image_create(4, 3, 6, NULL);
    assert_string_equal(img->names[5], "C5");
    assert_int_equal(tb_image_channel(img, "nope"), -1);
    /* Layout: row 0 on top, x fastest, channels interleaved. */
    assert_ptr_equal(tb_image_at(img, 2, 1), img->pixels + (1 * 4 + 2) * 6);
    tb_image_free(img);
    tb_image_free(NULL);
}

static void test_create_names_and_errors(void **state)
{
    (void)state;
    const char *names[] = {"diffuse.R", "Z"};
    tb_image *img = tb_image_create(1, 1, 2, names);
    assert_non_null(img);
    assert_string_equal(img->names[0], "diffuse.R");
    assert_int_equal(tb_image_channel(img, "Z"), 1);
    tb_image_free(img);

    const char *empty[] = {"R", ""};
    assert_null(tb_image_create(1, 1, 2, empty));
    assert_non_null(strstr(tb_last_error(), "no name"));
    const char *longname[] = {"abcdefghijklmnopqrstuvwxyz0123456"}; /* 33 bytes */
    assert_null(tb_image_create(1, 1, 1, longname));
    assert_null(tb_image_create(0, 1, 1, NULL));
    assert_null(tb_image_create(1, -1, 1, NULL));
    assert_null(tb_image_create(1, 1, 0, NULL));
    assert_null(tb_image_create(1, 1, TB_IMAGE_MAX_CHANNELS + 1, NULL));
    /* 2^31 x 2^31 cannot be asked for (int), but 65536^2 x 4 exceeds the limit. */
    assert_null(tb_image_create(65536, 65536, 4, NULL));
    assert_non_null(strstr(tb_last_error(), "too large"));
    assert_null(tb_image_create(2147483647, 2147483647, 1024, NULL));
}

static void test_attributes(void **state)
{
    (void)state;
    tb_image *img = tb_image_create(1, 1, 1, NULL);
    assert_null(tb_image_get_attr(img, "a"));
    assert_int_equal(tb_image_set_attr(img, "a", "1"), TB_OK);
    assert_int_equal(tb_image_set_attr(img, "b", "two"), TB_OK);
    assert_int_equal(tb_image_set_attr(img, "a", "one"), TB_OK); /* replaces, keeps position */
    assert_int_equal(img->nattrs, 2);
    assert_string_equal(img->attrs[0].key, "a");
    assert_string_equal(img->attrs[0].value, "one");
    assert_string_equal(tb_image_get_attr(img, "b"), "two");
    assert_int_equal(tb_image_set_attr(img, "", "x"), TB_ERR_ARG);
    assert_int_equal(tb_image_set_attr(img, NULL, "x"), TB_ERR_ARG);
    assert_int_equal(tb_image_set_attr(img, "c", NULL), TB_ERR_ARG);
    assert_int_equal(tb_image_set_attr(img, "empty", ""), TB_OK);
    assert_string_equal(tb_image_get_attr(img, "empty"), "");

    img->pixels[0] = 0.25f;
    tb_image *c = tb_image_clone(img);
    assert_non_null(c);
    assert_int_equal(c->nattrs, 3);
    assert_string_equal(tb_image_get_attr(c, "a"), "one");
    assert_true(c->pixels[0] == 0.25f);
    assert_ptr_not_equal(c->attrs[0].value, img->attrs[0].value); /* deep copy */
    tb_image_free(img);
    tb_image_free(c);
}

static void test_format_from_path(void **state)
{
    (void)state;
    assert_int_equal(tb_image_format_from_path("a.rle"), TB_IMAGE_RLE);
    assert_int_equal(tb_image_format_from_path("dir.x/pic.PNG"), TB_IMAGE_PNG);
    assert_int_equal(tb_image_format_from_path("/tmp/x.Pfm"), TB_IMAGE_PFM);
    assert_int_equal(tb_image_format_from_path("x.exr"), TB_IMAGE_EXR);
    assert_int_equal(tb_image_format_from_path("x.exr.tmp"), TB_IMAGE_UNKNOWN);
    assert_int_equal(tb_image_format_from_path("png"), TB_IMAGE_UNKNOWN);
    assert_int_equal(tb_image_format_from_path(".png"), TB_IMAGE_UNKNOWN);
    assert_int_equal(tb_image_format_from_path("dir/.png"), TB_IMAGE_UNKNOWN);
    assert_int_equal(tb_image_format_from_path("x.jpg"), TB_IMAGE_UNKNOWN);
    assert_int_equal(tb_image_format_from_path(""), TB_IMAGE_UNKNOWN);
    assert_int_equal(tb_image_format_from_path(NULL), TB_IMAGE_UNKNOWN);
    assert_string_equal(tb_image_format_name(TB_IMAGE_EXR), "OpenEXR");
    assert_string_equal(tb_image_format_name(TB_IMAGE_UNKNOWN), "unknown");
}

/* Every 8-bit code survives dequantize -> quantize, both encodings, and the
 * dequantized values are those of the definitions. */
static void test_quantize8_all_codes(void **state)
{
    (void)state;
    float prev = -1.0f;
    for (int code = 0; code < 256; code++) {
        float lin = tb_image_dequantize8((unsigned char)code, TB_ENCODING_LINEAR);
        assert_true(lin == (float)code / 255.0f);
        assert_int_equal(tb_image_quantize8(lin, TB_ENCODING_LINEAR), code);
        float s = tb_image_dequantize8((unsigned char)code, TB_ENCODING_SRGB);
        double e = code / 255.0;
        double ref = e <= 0.04045 ? e / 12.92 : pow((e + 0.055) / 1.055, 2.4);
        tb_assert_near(s, ref, 1e-6 * ref + 1e-9);
        assert_true(s > prev); /* strictly increasing: distinct codes stay distinct */
        prev = s;
        assert_int_equal(tb_image_quantize8(s, TB_ENCODING_SRGB), code);
    }
}

static void test_quantize16_all_codes(void **state)
{
    (void)state;
    for (int code = 0; code < 65536; code++) {
        float lin = tb_image_dequantize16((unsigned short)code, TB_ENCODING_LINEAR);
        assert_int_equal(tb_image_quantize16(lin, TB_ENCODING_LINEAR), code);
        float s = tb_image_dequantize16((unsigned short)code, TB_ENCODING_SRGB);
        if (tb_image_quantize16(s, TB_ENCODING_SRGB) != code)
            fail_msg("16-bit sRGB code %d -> %.9g -> %d", code, s, tb_image_quantize16(s, TB_ENCODING_SRGB));
    }
}

/* Rounding and clamping against values worked out by hand. */
static void test_quantize_values(void **state)
{
    (void)state;
    assert_int_equal(tb_image_quantize8(0.5f, TB_ENCODING_LINEAR), 128);   /* 127.5 rounds up */
    assert_int_equal(tb_image_quantize8(0.498f, TB_ENCODING_LINEAR), 127); /* 126.99 */
    /* sRGB(0.5) = 1.055 * 0.5^(1/2.4) - 0.055 = 0.735357; * 255 = 187.52 */
    assert_int_equal(tb_image_quantize8(0.5f, TB_ENCODING_SRGB), 188);
    /* sRGB(0.18) = 0.461356; * 255 = 117.65 */
    assert_int_equal(tb_image_quantize8(0.18f, TB_ENCODING_SRGB), 118);
    /* Linear segment: 0.001 * 12.92 * 255 = 3.29 */
    assert_int_equal(tb_image_quantize8(0.001f, TB_ENCODING_SRGB), 3);
    assert_int_equal(tb_image_quantize8(-1.0f, TB_ENCODING_SRGB), 0);
    assert_int_equal(tb_image_quantize8(-1.0f, TB_ENCODING_LINEAR), 0);
    assert_int_equal(tb_image_quantize8(7.0f, TB_ENCODING_SRGB), 255);
    assert_int_equal(tb_image_quantize8(INFINITY, TB_ENCODING_LINEAR), 255);
    assert_int_equal(tb_image_quantize8(NAN, TB_ENCODING_LINEAR), 0);
    assert_int_equal(tb_image_quantize8(NAN, TB_ENCODING_SRGB), 0);
    assert_int_equal(tb_image_quantize16(0.5f, TB_ENCODING_LINEAR), 32768); /* 32767.5 */
    assert_int_equal(tb_image_quantize16(2.0f, TB_ENCODING_LINEAR), 65535);
    assert_int_equal(tb_image_quantize16(0.5f, TB_ENCODING_SRGB), 48192); /* 0.7353570 * 65535 = 48191.6 */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_create_defaults),
        cmocka_unit_test(test_create_names_and_errors),
        cmocka_unit_test(test_attributes),
        cmocka_unit_test(test_format_from_path),
        cmocka_unit_test(test_quantize8_all_codes),
        cmocka_unit_test(test_quantize16_all_codes),
        cmocka_unit_test(test_quantize_values),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
