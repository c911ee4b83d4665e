# Shell helpers shared by the GPU script tests (sourced: `. "$TB_SOURCE_DIR/tests/gpu/gpu_test.sh"`).

# scratch_dir NAME: sets t to a folder of the calling script's own under
# $TB_TEST_TMPDIR, removed on exit. The GPU scripts run in parallel and write
# files of the same names (resized scenes, split-cpu.pfm).
scratch_dir() {
    t="$TB_TEST_TMPDIR/$1.$$"
    mkdir -p "$t"
    trap 'rm -rf "$t"' EXIT
}

# Image NMSE = sum (a - b)^2 / sum b^2 of two PFM files (b the reference).
nmse() { python3 "$TB_SOURCE_DIR/tests/gpu/pfm_compare.py" nmse "$1" "$2"; }

# mapcmp A.pfm B.pfm (sample maps): "differing-pixels total-A total-B min-A max-A pixels"
mapcmp() { python3 "$TB_SOURCE_DIR/tests/gpu/pfm_compare.py" mapcmp "$1" "$2"; }

# sized IN.mid OUT.mid W H: the scene IN with its camera resolution set to W x H.
sized() { sed "s/resolution = \[[0-9]* [0-9]*\]/resolution = [$3 $4]/" "$1" >"$2"; }

# validate_scene OUT SCENE ARGS...: `testbed validate SCENE ARGS...` under the
# validation layer, its output in OUT; exits the test (printing OUT) if it
# fails or the layer reported anything.
validate_scene() {
    vs_out="$1" vs_scene="$2"
    shift 2
    if ! TB_VK_VALIDATION=1 "$TESTBED" validate "$vs_scene" "$@" >"$vs_out" 2>&1; then
        echo "FAIL: testbed validate $vs_scene $*"
        cat "$vs_out"
        exit 1
    fi
    grep -q "validation layer       0 errors, 0 warnings  ok" "$vs_out" ||
        { echo "no validation line: $vs_scene"; cat "$vs_out"; exit 1; }
}
