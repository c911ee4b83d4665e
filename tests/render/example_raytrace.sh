#!/bin/sh
# tools/examples/raytrace.c, the Whitted ray tracer as a page of public calls
# (the surface, BSDF and light API of host/render/surface.h, driven by
# tb_render), makes the pixels of `testbed render --backend cpu` at the same
# samples per pixel, to float rounding: it draws the same numbers in the same
# order and shades by the same rules, so relMSE < 1e-10 (below 1e-12 is
# seen), while one sample more per pixel moves relMSE past 1e-4. A change of
# the command's shading or sampling order must be made in the example too.
# The RGB Cornell box at 48 x 48 and the spheres variant (mirror and glass)
# at 32 x 32, 4 spp.
#   example_raytrace.sh EXAMPLE  (with TESTBED, TB_SOURCE_DIR, TB_TEST_TMPDIR set)
set -u
EXAMPLE=$1
T="${TB_TEST_TMPDIR:-/tmp}/raytrace_example.$$"
rm -rf "$T" && mkdir -p "$T"
fail() { echo "FAIL: $*"; exit 1; }
sed 's/resolution = \[512 512\]/resolution = [48 48]/' "$TB_SOURCE_DIR/scenes/cornell-box-rgb.mid" > "$T/box.mid"
sed 's/resolution = \[512 512\]/resolution = [32 32]/' "$TB_SOURCE_DIR/scenes/cornell-box-spheres.mid" > "$T/spheres.mid"
for s in box spheres; do
    grep -q "resolution = \[[34][28] [34][28]\]" "$T/$s.mid" || fail "$s: the resolution was not replaced"
    "$EXAMPLE" "$T/$s.mid" "$T/example-$s.pfm" 4 > "$T/out1" 2>&1 || { cat "$T/out1"; fail "example $s"; }
    grep -q "wrote .*, 4 spp" "$T/out1" || { cat "$T/out1"; fail "example summary"; }
    "$TESTBED" render "$T/$s.mid" --spp 4 --backend cpu -o "$T/command-$s.pfm" > "$T/out2" 2>&1 ||
        { cat "$T/out2"; fail "command $s"; }
    "$TESTBED" compare "$T/example-$s.pfm" "$T/command-$s.pfm" --json > "$T/cmp-$s.json" || fail "compare $s"
    python3 - "$T/cmp-$s.json" <<'PY' || fail "$s: the example's image differs from the command's"
import json, sys
a = json.load(open(sys.argv[1]))["all"]
print(a)
assert a["relmse"] < 1e-10, a
PY
done
# the check can fail: 5 samples per pixel are another image
"$TESTBED" render "$T/box.mid" --spp 5 --backend cpu -o "$T/command-5.pfm" > /dev/null 2>&1 || fail "5 spp render"
"$TESTBED" compare "$T/example-box.pfm" "$T/command-5.pfm" --json > "$T/cmp-5.json" || fail "compare 5 spp"
python3 -c 'import json,sys; a=json.load(open(sys.argv[1]))["all"]; assert a["relmse"] > 1e-4, a' "$T/cmp-5.json" ||
    fail "4 and 5 spp were not told apart"

cmp -s "$T/example-box.pfm" "$T/example-spheres.pfm" && fail "two scenes gave the same image"
"$EXAMPLE" > /dev/null 2>&1; [ $? -eq 2 ] || fail "no arguments: expected exit 2"
"$EXAMPLE" "$T/missing.mid" "$T/x.pfm" > "$T/out3" 2>&1 && fail "missing scene: expected failure"
grep -q "missing.mid" "$T/out3" || { cat "$T/out3"; fail "missing scene message"; }
[ -e "$T/x.pfm" ] && fail "missing scene: an output file was left"
rm -rf "$T"
echo "raytrace example: the command's pixels on two scenes"
