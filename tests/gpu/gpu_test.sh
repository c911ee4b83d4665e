# Shell helpers shared by the GPU script tests (sourced: `. "$TB_SOURCE_DIR/tests/gpu/gpu_test.sh"`).

# Image NMSE = sum (a - b)^2 / sum b^2 of two PFM files (b the reference).
nmse() {
    python3 - "$1" "$2" <<'EOF_PY'
import struct, sys
def rd(p):
    with open(p, 'rb') as f:
        assert f.readline().strip() == b'PF'
        w, h = map(int, f.readline().split())
        s = float(f.readline())
        n = w * h * 3
        return struct.unpack(('<' if s < 0 else '>') + '%df' % n, f.read(4 * n))
a, b = rd(sys.argv[1]), rd(sys.argv[2])
assert len(a) == len(b)
num = sum((x - y) ** 2 for x, y in zip(a, b))
den = sum(y * y for y in b)
print('%.6g' % (num / den if den > 0 else float('inf')))
EOF_PY
}

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
