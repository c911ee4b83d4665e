/* Helpers shared by the render tests that build scenes from MID text and
 * scale their sample counts for the sanitizer build. */
#ifndef TB_TESTS_RENDER_TEST_SCENE_TEXT_H
#define TB_TESTS_RENDER_TEST_SCENE_TEXT_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "host/render/scene.h"
#include "tb_test.h"

/* The scene of MID `text` ("t.mid" in messages, files relative to the test's
 * temporary folder) with options `opt` (NULL: defaults); fails the test if it
 * does not load. */
static inline tb_scene *tp_scene_text_opt(const char *text, const tb_scene_options *opt)
{
    FILE *fp = fmemopen((void *)text, strlen(text), "r");
    assert_non_null(fp);
    tb_scene *s = NULL;
    tb_status st = tb_scene_load_stream(fp, "t.mid", tb_test_tmpdir(), opt, &s);
    fclose(fp);
    if (st)
        fail_msg("%s", tb_last_error());
    return s;
}

/* The same with default options. */
static inline tb_scene *tp_scene_text(const char *text) { return tp_scene_text_opt(text, NULL); }

/* Path-tracer sample counts are divided by $TB_PT_TEST_DIVISOR (the sanitizer
 * build sets it); 1 when unset or not positive. */
static inline long tp_pt_divisor(void)
{
    const char *e = getenv("TB_PT_TEST_DIVISOR");
    long d = e ? atol(e) : 1;
    return d > 0 ? d : 1;
}

#endif
