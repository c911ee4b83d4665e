/* Spectrum files (util/color/spectrum_file.h): parsing, one test per error
 * message, and the end-to-end path MID spectrum(file(...)) -> scene colours. */
#include "tb_test.h"

#include <string.h>
#include <unistd.h>

#include "host/render/scene.h"
#include "util/color/spectrum_file.h"

static const char *tb__write(const char *name, const char *text, size_t len)
{
    static char path[1024];
    snprintf(path, sizeof path, "%s/%s", tb_test_tmpdir(), name);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(text, 1, len, f), len);
    fclose(f);
    return path;
}

static void test_reads_samples_exactly(void **state)
{
    (void)state;
    const char text[] = "# Cornell white, first samples\n"
                        "lambda_nm,white\n"
                        "400,0.343\n"
                        "  404  0.445   # trailing comment\n"
                        "\n"
                        "408 , 0.551\r\n"
                        "412\t0.624\n";
    const char *p = tb__write("ok.spd", text, sizeof text - 1);
    tb_spectrum s;
    assert_int_equal(tb_spectrum_read_file(p, &s), TB_OK);
    assert_int_equal(s.n, 4);
    const double l[4] = {400, 404, 408, 412}, v[4] = {0.343, 0.445, 0.551, 0.624};
    for (int i = 0; i < 4; i++) {
        assert_true(s.lambda[i] == l[i]); /* exactly the decimal's nearest double */
        assert_true(s.value[i] == v[i]);
    }
    tb_spectrum_release(&s);
}

/* Each malformed file and the exact message it must give. */
static void test_error_messages(void **state)
{
    (void)state;
    static const struct {
        const char *text;
        size_t len;
        const char *message; /* after "<path>:" */
    } cases[] = {
        {"400 0.5\n", 8, "2:1: error: a spectrum needs at least 2 samples"},
        {"", 0, "1:1: error: a spectrum needs at least 2 samples"},
        {"400 0.5\n400 0.6\n", 16, "2:1: error: wavelengths must be strictly increasing"},
        {"500 0.5\n400 0.6\n", 16, "2:1: error: wavelengths must be strictly increasing"},
        {"0 0.5\n400 0.6\n", 14, "1:1: error: wavelength must be > 0 nm"},
        {"400\n500 1\n", 10, "1:4: error: expected a value after the wavelength"},
        {"400 0.5 0.7\n500 1\n", 18, "1:9: error: unexpected text after the value (one sample per line: wavelength value)"},
        {"400 0.5\nnm,v\n500 1\n", 20, "2:1: error: expected a wavelength in nm (column names are allowed only before the first sample)"},
        {"a,b\nc,d\n", 8, "2:1: error: expected a wavelength in nm (column names are allowed only before the first sample)"},
        {"400 1e999\n500 1\n", 16, "1:5: error: value out of range"},
        {"400 0.5\n5\0000 1\n", 14, "2:2: error: NUL byte in text"},
        {"x400 0.5\n", 9, NULL}, /* a header line only: then too few samples */
        {".. 1\n", 5, "1:1: error: expected a wavelength in nm"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const char *p = tb__write("bad.spd", cases[i].text, cases[i].len);
        tb_spectrum s;
        tb_status st = tb_spectrum_read_file(p, &s);
        assert_int_equal(st, TB_ERR_FORMAT);
        assert_int_equal(s.n, 0);
        char expect[1200];
        snprintf(expect, sizeof expect, "%s:%s", p,
                 cases[i].message ? cases[i].message : "2:1: error: a spectrum needs at least 2 samples");
        if (strcmp(tb_last_error(), expect) != 0)
            fail_msg("case %zu: got '%s', expected '%s'", i, tb_last_error(), expect);
    }
    tb_spectrum s;
    assert_int_equal(tb_spectrum_read_file("/nonexistent/x.spd", &s), TB_ERR_IO);
    assert_non_null(strstr(tb_last_error(), "/nonexistent/x.spd: cannot open spectrum file"));
}

/* A MID material with spectrum(file(...)) gives exactly the colours of the
 * same samples written inline. */
static void test_mid_spectrum_file_matches_inline(void **state)
{
    (void)state;
    const char spd[] = "400 0.0\n500 8.0\n600 15.6\n700 18.4\n";
    tb__write("lamp.spd", spd, sizeof spd - 1);
    const char *fmt = "mid 1\n"
                      "material \"lamp\" { diffuse = 0.78 emission = %s }\n"
                      "sphere { rendering = { material = \"lamp\" } }\n";
    char text[512];
    snprintf(text, sizeof text, fmt, "spectrum(file(\"lamp.spd\"))");
    char path_file[1024];
    snprintf(path_file, sizeof path_file, "%s", tb__write("lamp_file.mid", text, strlen(text)));
    snprintf(text, sizeof text, fmt, "spectrum([400 500 600 700], [0 8 15.6 18.4])");
    const char *path_inline = tb__write("lamp_inline.mid", text, strlen(text));

    tb_scene *a = NULL, *b = NULL;
    if (tb_scene_load(path_file, NULL, &a))
        fail_msg("%s", tb_last_error());
    if (tb_scene_load(path_inline, NULL, &b))
        fail_msg("%s", tb_last_error());
    assert_true(a->spectral);
    assert_int_equal(a->nchannels, b->nchannels);
    assert_int_equal(a->nmaterials, 1);
    assert_int_equal(b->nmaterials, 1);
    float maxv = 0.0f;
    for (int k = 0; k < a->nchannels; k++) {
        /* Inline MID samples are stored as float, file samples as double: they
         * agree to float rounding of the samples. */
        tb_assert_near(a->materials[0].emission.v[k], b->materials[0].emission.v[k],
                       1e-6 * fabs(b->materials[0].emission.v[k]) + 1e-12);
        if (a->materials[0].emission.v[k] > maxv)
            maxv = a->materials[0].emission.v[k];
    }
    assert_true(maxv > 10.0f); /* the samples reached the bands */
    tb_scene_free(a);
    tb_scene_free(b);

    /* A broken spectrum file fails the load with the file's own location. */
    tb__write("lamp.spd", "400 1\n", 6);
    tb_scene *c = NULL;
    assert_int_not_equal(tb_scene_load(path_file, NULL, &c), TB_OK);
    assert_non_null(strstr(tb_last_error(), "lamp.spd:2:1: error: a spectrum needs at least 2 samples"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reads_samples_exactly),
        cmocka_unit_test(test_error_messages),
        cmocka_unit_test(test_mid_spectrum_file_matches_inline),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
