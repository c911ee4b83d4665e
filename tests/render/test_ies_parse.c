/* IES LM-63 parsing: the fields of the test files, header variants (1986
 * labels, keywords, CRLF, commas, numbers split across lines), and one case
 * per error message with its file:line location. */
#include "tb_test.h"

#include <string.h>

#include "host/render/ies.h"

static tb_ies *read_data(const char *name)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/render/data/%s", TB_TESTS_DIR, name);
    tb_ies *ies = NULL;
    tb_status st = tb_ies_read(path, &ies);
    if (st)
        fail_msg("%s: %s", name, tb_last_error());
    return ies;
}

static void test_fields(void **state)
{
    (void)state;
    tb_ies *l = read_data("lambertian.ies");
    assert_string_equal(l->version, "LM-63-2002");
    assert_int_equal(l->nkeywords, 3);
    assert_string_equal(l->keywords[1].key, "MANUFAC");
    assert_string_equal(l->keywords[1].value, "Testbed test data");
    assert_int_equal(l->lamps, 1);
    tb_assert_near(l->lumens_per_lamp, 3141.592654, 0.0);
    assert_true(l->multiplier == 1.0 && l->photometric_type == 1 && l->units == 2);
    assert_int_equal(l->nv, 37);
    assert_int_equal(l->nh, 1);
    assert_int_equal(l->symmetry, TB_IES_SYM_ROTATIONAL);
    assert_true(l->v_angles[36] == 180.0 && l->candela[0] == 1000.0);
    assert_true(l->max_candela == 1000.0);
    tb_ies_free(l);

    tb_ies *q = read_data("quadrant.ies");
    assert_int_equal(q->symmetry, TB_IES_SYM_QUADRANT);
    assert_true(q->lamps == 2 && q->multiplier == 2.5);
    assert_true(q->candela[0] == 250.0); /* 100 x 2.5 */
    tb_ies_free(q);
    tb_ies *b = read_data("bilateral.ies");
    assert_int_equal(b->symmetry, TB_IES_SYM_BILATERAL);
    assert_true(b->lumens_per_lamp == -1.0);
    tb_ies_free(b);
    tb_ies *f = read_data("full.ies");
    assert_int_equal(f->symmetry, TB_IES_SYM_FULL);
    assert_string_equal(f->version, "LM-63-1995");
    tb_ies_free(f);
    tb_ies *n = read_data("bilateral90.ies");
    assert_int_equal(n->symmetry, TB_IES_SYM_BILATERAL_90);
    tb_ies_free(n);
}

static tb_status parse(const char *text, tb_ies **out)
{
    return tb_ies_parse(text, strlen(text), "t.ies", out);
}

static void test_variants(void **state)
{
    (void)state;
    /* LM-63-1986: no version line, free text before TILT; commas and CRLF; the
     * numbers wrap anywhere. */
    const char *t1986 = "Some luminaire\r\nLABEL LINE 2\r\nTILT=NONE\r\n1,1000,1,3\r\n,1,1,1,0,0,0,1,1,1\r\n"
                        "0 45\r\n90 0 300 200\r\n100\r\n";
    tb_ies *ies;
    assert_int_equal(parse(t1986, &ies), TB_OK);
    assert_string_equal(ies->version, "LM-63-1986");
    assert_int_equal(ies->nkeywords, 0);
    assert_true(ies->nv == 3 && ies->candela[2] == 100.0 && ies->input_watts == 1.0);
    tb_ies_free(ies);
    /* IESNA91 with keywords, spaces around '=', a DOS end-of-file mark. */
    const char *t91 = "IESNA91\n[TEST] x\n[MANUFAC]  ACME  \n  TILT = NONE\n1 -1 1 2 1 1 1 0 0 0\n1 1 0\n0 90\n0\n"
                      "5 0\n\x1a";
    assert_int_equal(parse(t91, &ies), TB_OK);
    assert_string_equal(ies->version, "LM-63-1991");
    assert_string_equal(ies->keywords[1].value, "ACME");
    tb_ies_free(ies);
    /* No trailing newline; exponents; a leading '+'. */
    const char *t3 = "IESNA:LM-63-2002\nTILT=NONE\n1 1e3 +1.0 2 1 1 2 0 0 0 1 1 0 0.0 9E1 0 1 2.5e1";
    assert_int_equal(parse(t3, &ies), TB_OK);
    assert_true(ies->v_angles[1] == 90.0 && ies->candela[1] == 25.0 && ies->lumens_per_lamp == 1000.0);
    tb_ies_free(ies);
}

/* A header + the given number part. */
static char *mk(const char *tilt, const char *numbers)
{
    static char buf[4096];
    snprintf(buf, sizeof buf, "IESNA:LM-63-2002\n[TEST] error case\n%s\n%s", tilt, numbers);
    return buf;
}

static void expect_error(const char *text, tb_status want, const char *message)
{
    tb_ies *ies = (tb_ies *)1;
    tb_status st = parse(text, &ies);
    if (st != want)
        fail_msg("status %d (%s), wanted %d; message: %s", st, tb_status_name(st), want, tb_last_error());
    assert_null(ies);
    if (strcmp(tb_last_error(), message) != 0)
        fail_msg("message\n  '%s'\nwanted\n  '%s'", tb_last_error(), message);
}

static void test_errors(void **state)
{
    (void)state;
    const char *T = "TILT=NONE";
    expect_error("", TB_ERR_FORMAT, "t.ies:1: error: no TILT= line before the end of the file");
    expect_error("IESNA:LM-63-2002\n[TEST] x\n", TB_ERR_FORMAT,
                 "t.ies:3: error: no TILT= line before the end of the file");
    expect_error(mk("TILT=INCLUDE", "1\n"), TB_ERR_UNSUPPORTED,
                 "t.ies:3: error: TILT=INCLUDE (lamp tilt factors) is not supported; only TILT=NONE");
    expect_error(mk("TILT=lamp.tlt", "1\n"), TB_ERR_UNSUPPORTED,
                 "t.ies:3: error: TILT=<file> (tilt factors in another file) is not supported; only TILT=NONE");
    expect_error(mk("TILT NONE", "1\n"), TB_ERR_FORMAT, "t.ies:3: error: expected '=' after TILT");
    expect_error(mk(T, ""), TB_ERR_FORMAT, "t.ies:4: error: expected the number of lamps, found end of file");
    expect_error(mk(T, "one"), TB_ERR_FORMAT, "t.ies:4: error: expected the number of lamps, found 'one'");
    expect_error(mk(T, "1.5"), TB_ERR_FORMAT,
                 "t.ies:4: error: the number of lamps must be an integer from 1 to 1000000, found 1.5");
    expect_error(mk(T, "1 0"), TB_ERR_FORMAT,
                 "t.ies:4: error: lumens per lamp must be > 0 or -1 (absolute photometry), found 0");
    expect_error(mk(T, "1 100 0"), TB_ERR_FORMAT, "t.ies:4: error: the candela multiplier must be > 0, found 0");
    expect_error(mk(T, "1 100 nan"), TB_ERR_FORMAT, "t.ies:4: error: expected the candela multiplier, found 'nan'");
    expect_error(mk(T, "1 100 1 1"), TB_ERR_FORMAT,
                 "t.ies:4: error: the number of vertical angles must be an integer from 2 to 100000, found 1");
    expect_error(mk(T, "1 100 1 2 1 2"), TB_ERR_UNSUPPORTED,
                 "t.ies:4: error: photometric type 2 (B) is not supported; only type 1 (C)");
    expect_error(mk(T, "1 100 1 2 1 3"), TB_ERR_UNSUPPORTED,
                 "t.ies:4: error: photometric type 3 (A) is not supported; only type 1 (C)");
    expect_error(mk(T, "1 100 1 2 1 1 3"), TB_ERR_FORMAT,
                 "t.ies:4: error: the units type must be an integer from 1 to 2, found 3");
    expect_error(mk(T, "1 100 1 2 1 1 2 0 0 inf"), TB_ERR_FORMAT,
                 "t.ies:4: error: expected the luminous height, found 'inf'");
    expect_error(mk(T, "1 100 1 2 1 1 2 0 0 0\n1 1 0\n0 1e999"), TB_ERR_FORMAT,
                 "t.ies:6: error: vertical angle 2 of 2 '1e999' is out of range");
    /* Counts the file cannot hold: refused before allocating. */
    expect_error(mk(T, "1 100 1 1000 1000 1 2 0 0 0\n1 1 0\n0 1 2\n"), TB_ERR_FORMAT,
                 "t.ies:7: error: file truncated: 1000 vertical x 1000 horizontal angles need 1002000 more numbers, "
                 "but only 7 bytes remain");
    /* Truncated in the middle of the candela values. */
    expect_error(mk(T, "1 100 1 3 1 1 2 0 0 0\n1 1 0\n0 45 90\n0\n10 20\n"), TB_ERR_FORMAT,
                 "t.ies:9: error: expected candela value 3 of 3 (horizontal angle 0, vertical angle 90), found end of file");
    expect_error(mk(T, "1 100 1 3 1 1 2 0 0 0\n1 1 0\n0 50 45\n0\n10 20 30\n"), TB_ERR_FORMAT,
                 "t.ies:6: error: vertical angles must increase: 45 follows 50");
    expect_error(mk(T, "1 100 1 2 1 1 2 0 0 0\n1 1 0\n0 190\n0\n10 20\n"), TB_ERR_FORMAT,
                 "t.ies:6: error: vertical angle 190 is outside [0, 180]");
    expect_error(mk(T, "1 100 1 2 3 1 2 0 0 0\n1 1 0\n0 90\n0 90 45\n1 2 3 4 5 6\n"), TB_ERR_FORMAT,
                 "t.ies:7: error: horizontal angles must increase: 45 follows 90");
    expect_error(mk(T, "1 100 1 2 2 1 2 0 0 0\n1 1 0\n0 90\n0 120\n1 2 3 4\n"), TB_ERR_FORMAT,
                 "t.ies:7: error: horizontal angles must run 0..90, 0..180, 0..360 or 90..270 (or be the single "
                 "angle 0), found 0..120");
    expect_error(mk(T, "1 100 1 2 1 1 2 0 0 0\n1 1 0\n0 90\n0\n10 -1\n"), TB_ERR_FORMAT,
                 "t.ies:8: error: negative candela value -1 (horizontal 0, vertical 90)");
    expect_error(mk(T, "1 100 1 2 1 1 2 0 0 0\n1 1 0\n0 90\n0\n10 NaN\n"), TB_ERR_FORMAT,
                 "t.ies:8: error: expected candela value 2 of 2 (horizontal angle 0, vertical angle 90), found 'NaN'");
    /* More values than the counts say. */
    expect_error(mk(T, "1 100 1 2 1 1 2 0 0 0\n1 1 0\n0 90\n0\n10 20\n30\n"), TB_ERR_FORMAT,
                 "t.ies:9: error: unexpected '30' after the 2 candela values");
    expect_error(mk(T, "1 100 1 2 1 1 2 0 0 0\n1 1 0\n0 90\n0\n0 0\n"), TB_ERR_FORMAT,
                 "t.ies:8: error: every candela value is 0");
    expect_error(mk(T, "1 100 1e300 2 1 1 2 0 0 0\n1 1 0\n0 90\n0\n1e10 0\n"), TB_ERR_FORMAT,
                 "t.ies:8: error: candela value 10000000000 times the multiplier exceeds 1e+30");
    expect_error(mk("IESNA:LM-63-2002\n[BROKEN line", "x"), TB_ERR_FORMAT, "t.ies:4: error: keyword line without ']'");
    /* A table whose sampling grid would be too large: 2 vertical angles (0,
     * 180: 180 one-degree rows) x 23303 horizontal angles over 0..360. */
    {
        int nh = 23303;
        size_t cap = 64 + (size_t)nh * 40;
        char *big = malloc(cap);
        size_t n = (size_t)snprintf(big, cap, "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 2 %d 1 2 0 0 0\n1 1 0\n0 180\n", nh);
        for (int j = 0; j < nh; j++)
            n += (size_t)snprintf(big + n, cap - n, "%.10g\n", j == nh - 1 ? 360.0 : 360.0 * j / (nh - 1));
        for (int j = 0; j < nh; j++)
            n += (size_t)snprintf(big + n, cap - n, "1 1\n");
        expect_error(big, TB_ERR_UNSUPPORTED,
                     "t.ies: error: the table is too large to sample (4194360 grid cells, at most 4194304)");
        free(big);
    }
    /* Unreadable file. */
    tb_ies *ies = (tb_ies *)1;
    assert_int_equal(tb_ies_read("/nonexistent/lamp.ies", &ies), TB_ERR_IO);
    assert_null(ies);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fields),
        cmocka_unit_test(test_variants),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
