#!/bin/sh
# `testbed render --method path` (docs/pathtrace.md): the Cornell box renders
# (no NaN or Inf, red wall on the left, provenance method=path), --max-depth 1 (direct
# light only) is darker than the uncapped default, --passes with --report
# against --reference writes a row per pass, Ctrl-C writes the image so far
# and exits 130, and the refusals exit 2 with a message: --backend vulkan
# with --adaptive (path) and at all (hybrid), bad --max-depth values, ray-tracer
# options with the path tracer and --rr-depth without it.
#   pt_cli.sh  (with TESTBED, TB_SOURCE_DIR, TB_TEST_TMPDIR set)
set -u
T="${TB_TEST_TMPDIR:-/tmp}/pt_cli.$$"
rm -rf "$T" && mkdir -p "$T"
fail() { echo "FAIL: $*"; exit 1; }
BOX="$TB_SOURCE_DIR/scenes/cornell-box.mid"

"$TESTBED" render "$BOX" --method path --spp 1 --threads 2 -o "$T/a.pfm" --stats "$T/a.json" > "$T/out" 2>&1 ||
    { cat "$T/out"; fail "render --method path"; }
grep -q "path tracer, 512x512, 262144 samples" "$T/out" || { cat "$T/out"; fail "summary line"; }
"$TESTBED" render "$BOX" --method path --spp 1 --max-depth 1 -o "$T/d.pfm" > "$T/out" 2>&1 ||
    { cat "$T/out"; fail "render --max-depth 1"; }
python3 - "$T/a.pfm" "$T/d.pfm" "$T/a.json" <<'PY' || fail "image checks"
import json, math, struct, sys
def pfm(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF"
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        v = struct.unpack(("<" if scale < 0 else ">") + "%df" % (w * h * 3), f.read())
    return w, h, v
w, h, a = pfm(sys.argv[1])
_, _, d = pfm(sys.argv[2])
# (single spectral samples can be out of the sRGB gamut: components may be < 0, but finite)
assert all(math.isfinite(x) for x in a), "NaN or Inf pixel"
def mean(v, ch, x0, x1):
    s = n = 0
    for y in range(h // 4, 3 * h // 4):
        for x in range(x0, x1):
            s += v[3 * (y * w + x) + ch]; n += 1
    return s / n
# the red wall is on the left: red over green there, green over red on the right
assert mean(a, 0, 20, 60) > 2 * mean(a, 1, 20, 60), "left wall not red"
assert mean(a, 1, w - 60, w - 20) > 1.5 * mean(a, 0, w - 60, w - 20), "right wall not green"
ma, md = sum(a) / len(a), sum(d) / len(d)
assert md < 0.85 * ma, ("direct-only not darker", md, ma)
print("mean all bounces %.4f, direct only %.4f" % (ma, md))
opts = json.load(open(sys.argv[3]))["provenance"]["options"]
assert "method=path" in opts and "max_depth=0" in opts, opts
PY

# two passes with a report against the first image
"$TESTBED" render "$BOX" --method path --spp 1 --passes 2 -o "$T/r.pfm" --report "$T/r.csv" --reference "$T/a.pfm" \
    > "$T/out" 2>&1 || { cat "$T/out"; fail "--report"; }
[ "$(wc -l < "$T/r.csv")" -eq 3 ] || { cat "$T/r.csv"; fail "report rows"; }

# Ctrl-C: the image so far, exit 130
"$TESTBED" render "$BOX" --method path --spp 4096 --threads 1 -o "$T/c.pfm" > "$T/cout" 2> "$T/cerr" &
pid=$!
i=0
while ! grep -q "Ctrl-C writes" "$T/cerr" 2>/dev/null; do
    i=$((i + 1)); [ $i -lt 300 ] || { kill $pid; fail "no start line"; }; sleep 0.1
done
sleep 0.5
kill -INT $pid
wait $pid; rc=$?
[ $rc -eq 130 ] || { cat "$T/cout" "$T/cerr"; fail "Ctrl-C: exit $rc, expected 130"; }
[ -s "$T/c.pfm" ] || fail "Ctrl-C: no image written"
grep -q "INTERRUPTED" "$T/cout" || fail "Ctrl-C: summary does not say INTERRUPTED"

# refusals: exit 2 with a message
expect2() { # expect2 WHAT PATTERN ARGS...
    what=$1; pat=$2; shift 2
    "$TESTBED" render "$BOX" -o "$T/x.pfm" "$@" > "$T/out" 2>&1; rc=$?
    [ $rc -eq 2 ] || { cat "$T/out"; fail "$what: exit $rc, expected 2"; }
    grep -q -- "$pat" "$T/out" || { cat "$T/out"; fail "$what: message lacks '$pat'"; }
}
expect2 "adaptive path on vulkan" "no adaptive antialiasing" --method path --backend vulkan --adaptive
expect2 "hybrid on vulkan" "runs on the CPU only" --method hybrid --backend vulkan
expect2 "negative depth" "max-depth" --method path --max-depth -1
expect2 "depth too large" "max-depth" --method path --max-depth 5000
expect2 "depth not a number" "max-depth" --method path --max-depth deep
expect2 "raytrace depth > 64" "at most 64" --max-depth 100
expect2 "light samples with path" "light-samples" --method path --light-samples 4
expect2 "rr-depth without path" "rr-depth" --rr-depth 2
[ ! -e "$T/x.pfm" ] || fail "a refused command wrote an image"
rm -rf "$T"
echo "pt_cli: all checks passed"
