#!/bin/sh
# tools/examples/hybrid.c, a page of public calls (tb_hybrid_create,
# tb_render_hybrid), renders the same pixels as `testbed render --method
# hybrid` (PFM: no provenance in the file, so the bytes are the pixels), in
# both modes, on the Cornell box at 48 x 48 with 80 mm elements.
#   example.sh EXAMPLE  (with TESTBED, TB_SOURCE_DIR, TB_TEST_TMPDIR set)
set -u
EXAMPLE=$1
T="${TB_TEST_TMPDIR:-/tmp}/hybrid_example.$$"
rm -rf "$T" && mkdir -p "$T"
fail() { echo "FAIL: $*"; exit 1; }
BOX="$T/box.mid"
sed 's/resolution = \[512 512\]/resolution = [48 48]/' "$TB_SOURCE_DIR/scenes/cornell-box-rgb.mid" > "$BOX"
for mode in interpolated gather; do
    "$EXAMPLE" "$BOX" "$T/example-$mode.pfm" $mode 80 > "$T/out1" 2>&1 || { cat "$T/out1"; fail "example $mode"; }
    grep -q "elements, [0-9]* shots" "$T/out1" || { cat "$T/out1"; fail "example summary"; }
    "$TESTBED" render "$BOX" --method hybrid --hybrid-mode $mode --max-edge 80 -o "$T/command-$mode.pfm" \
        > "$T/out2" 2>&1 || { cat "$T/out2"; fail "command $mode"; }
    cmp "$T/example-$mode.pfm" "$T/command-$mode.pfm" || fail "$mode: the example's image differs from the command's"
done
cmp -s "$T/example-interpolated.pfm" "$T/example-gather.pfm" && fail "the two modes gave the same image"
"$EXAMPLE" > /dev/null 2>&1; [ $? -eq 2 ] || fail "no arguments: expected exit 2"
"$EXAMPLE" "$BOX" "$T/x.pfm" nearest > /dev/null 2>&1; [ $? -eq 2 ] || fail "unknown mode: expected exit 2"
rm -rf "$T"
echo "hybrid example: the command's pixels in both modes"
