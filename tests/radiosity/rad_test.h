/* cmocka helpers shared by the radiosity unit tests: load a scene of the
 * source tree, solve a mesh to a threshold, read a whole file. */
#ifndef TB_TESTS_RADIOSITY_RAD_TEST_H
#define TB_TESTS_RADIOSITY_RAD_TEST_H

#include "host/radiosity/radiosity.h"
#include "host/render/scene.h"
#include "tb_test.h"

/* The scene at `rel` (relative to the source tree), without an accelerator; fails the test on error. */
static inline tb_scene *tb_rad_test_load(const char *rel)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", TB_SOURCE_DIR, rel);
    tb_scene_options so = {.no_accel = true};
    tb_scene *s = NULL;
    if (tb_scene_load(path, &so, &s))
        fail_msg("%s", tb_last_error());
    return s;
}

/* A solver for m with options o, run until the unshot fraction of emitted power is below threshold; fails the test on error. */
static inline tb_rad_solver *tb_rad_test_solve(const tb_rad_mesh *m, const tb_rad_options *o, double threshold)
{
    tb_rad_solver *s = NULL;
    if (tb_rad_solver_create(m, NULL, o, &s))
        fail_msg("%s", tb_last_error());
    tb_rad_stop stop = {.threshold = threshold};
    if (tb_rad_solver_run(s, &stop, NULL, NULL, 0))
        fail_msg("%s", tb_last_error());
    return s;
}

/* The whole file at path, NUL-terminated (malloc'ed), its length in *len. */
static inline char *tb_rad_test_slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *buf = malloc((size_t)n + 1);
    assert_non_null(buf);
    assert_int_equal(fread(buf, 1, (size_t)n, f), (size_t)n);
    buf[n] = 0;
    fclose(f);
    *len = (size_t)n;
    return buf;
}

/* The solver's energy bookkeeping on a solved mesh: absorbed + unshot +
 * escaped = emitted, under 2% escaped, and the absorbed power equal to the
 * one computed independently from the element radiosities,
 * sum over elements and channels of (1 - rho) (B - E) / rho A. */
static inline void tb_rad_test_check_energy(const tb_rad_solver *s, const tb_rad_mesh *m)
{
    tb_rad_energy en = tb_rad_solver_energy(s);
    tb_assert_near(en.absorbed + en.unshot + en.escaped, en.emitted, 1e-9 * en.emitted);
    assert_true(fabs(en.escaped) < 0.02 * en.emitted);
    double absorbed = 0.0, b[TB_CHANNELS_MAX];
    int nc = m->nchannels;
    for (size_t i = 0; i < m->nelems; i++) {
        tb_rad_element_radiosity(s, i, false, b);
        for (int c = 0; c < nc; c++) {
            double rho = m->rho[i * (size_t)nc + (size_t)c], e = m->emission[i * (size_t)nc + (size_t)c];
            absorbed += (1.0 - rho) * (b[c] - e) / rho * m->elems[i].area;
        }
    }
    tb_assert_near(absorbed, en.absorbed, 1e-6 * en.emitted);
}

#endif
