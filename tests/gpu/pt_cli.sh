#!/bin/sh
# `testbed render --method path --backend vulkan` (docs/gpu.md, "Path
# tracer"): renders the RGB Cornell box under the validation layer (summary
# line, stats, provenance backend=vulkan, finite pixels), the same image for
# the same seed and another for another seed; renders the materials scene
# (patterns, bump maps) under the validation layer; refuses a scene with
# features the kernel lacks (a pattern on a torus) (exit 1, the reason, no image) while --backend auto renders
# it on the CPU saying why; --adaptive with vulkan is a usage error (exit 2).
# Statistical equality with the CPU path is pt_equivalence.c's.
set -eu
: "${TESTBED:?}" "${TB_SOURCE_DIR:?}" "${TB_TEST_TMPDIR:?}"
. "$TB_SOURCE_DIR/tests/gpu/gpu_test.sh"
scratch_dir pt_cli
fail() { echo "FAIL: $*"; [ -f "$t/out" ] && cat "$t/out"; exit 1; }

sized "$TB_SOURCE_DIR/scenes/cornell-box-rgb.mid" "$t/box.mid" 24 24
sized "$TB_SOURCE_DIR/scenes/materials.mid" "$t/materials.mid" 24 24
# a pattern on a torus: its (u, v) is not on the device
cat >"$t/refused.mid" <<'MID'
mid 1.1
camera "c" { eye = [0 -6 3] look_at = [0 0 0] up = [0 0 1] fov = 45 resolution = [24 24] }
point_light "l" { position = [0 -3 4] intensity = 10 }
torus "t" { geometry = { major = 1 minor = 0.3 } rendering = { diffuse = 0.5 diffuse_pattern = checker(8, 0.2, 0.8) } }
MID

TB_VK_VALIDATION=1 "$TESTBED" render "$t/box.mid" --method path --backend vulkan --spp 4 -o "$t/a.pfm" \
    --stats "$t/a.json" >"$t/out" 2>&1 || fail "render"
grep -q "vulkan path tracer: 2304 paths" "$t/out" || fail "summary line"
if grep -qi "validation" "$t/out"; then fail "validation messages"; fi
grep -q '"gpu_paths": 2304' "$t/a.json" || fail "stats gpu_paths"
grep -q 'method=path.*backend=vulkan' "$t/a.json" || fail "provenance backend=vulkan"
python3 - "$t/a.pfm" <<'PY' || fail "image"
import math, struct, sys
with open(sys.argv[1], "rb") as f:
    assert f.readline().strip() == b"PF"
    w, h = map(int, f.readline().split())
    s = float(f.readline())
    v = struct.unpack(("<" if s < 0 else ">") + "%df" % (w * h * 3), f.read())
assert all(math.isfinite(x) and x >= 0 for x in v), "non-finite or negative pixel"
assert sum(v) > 0, "black image"
PY
"$TESTBED" render "$t/box.mid" --method path --backend vulkan --spp 4 -o "$t/b.pfm" >"$t/out" 2>&1 || fail "again"
cmp -s "$t/a.pfm" "$t/b.pfm" || fail "the same seed gave another image"
"$TESTBED" render "$t/box.mid" --method path --backend vulkan --spp 4 --seed 9 -o "$t/c.pfm" >"$t/out" 2>&1 ||
    fail "seed 9"
if cmp -s "$t/a.pfm" "$t/c.pfm"; then fail "another seed gave the same image"; fi

# patterns and bump maps on the device
TB_VK_VALIDATION=1 "$TESTBED" render "$t/materials.mid" --method path --backend vulkan --spp 1 -o "$t/m.pfm" \
    >"$t/out" 2>&1 || fail "materials render"
grep -q "vulkan path tracer: 576 paths" "$t/out" || fail "materials summary line"
if grep -qi "validation" "$t/out"; then fail "validation messages (materials)"; fi

# a scene the kernel does not take: vulkan refuses, auto uses the CPU
if "$TESTBED" render "$t/refused.mid" --method path --backend vulkan --spp 1 -o "$t/s.pfm" >"$t/out" 2>&1; then
    fail "the torus with a pattern should be refused"
fi
grep -q "does not take this scene: patterns or bump maps on objects other than spheres, cubes and polygons" \
    "$t/out" || fail "refusal message"
[ ! -e "$t/s.pfm" ] || fail "a refused render wrote an image"
"$TESTBED" render "$t/refused.mid" --method path --backend auto --spp 1 -o "$t/s.pfm" >"$t/out" 2>&1 || fail "auto"
grep -q "backend cpu" "$t/out" || fail "auto should say it renders on the CPU"
if grep -q "vulkan path tracer:" "$t/out"; then fail "auto ran the kernel on the refused scene"; fi

"$TESTBED" render "$t/box.mid" --method path --backend vulkan --adaptive -o "$t/x.pfm" >"$t/out" 2>&1 && rc=0 || rc=$?
[ "$rc" -eq 2 ] || fail "--adaptive with vulkan: exit $rc, expected 2"
grep -q "no adaptive antialiasing" "$t/out" || fail "--adaptive message"
echo "pt_cli (gpu): all checks passed"
