#!/bin/sh
# tools/examples/radiosity.c, a page of library calls (tb_rad_render), makes
# the same patches CSV as `testbed render --method radiosity --patches`, byte
# for byte: the command is a thin layer over that one call. The Cornell box
# with the default mesh (1322 elements), stopped after 300 shots to keep the
# test short; the example's image is written and read back too.
#   example.sh EXAMPLE  (with TESTBED, TB_SOURCE_DIR, TB_TEST_TMPDIR set)
set -u
EXAMPLE=$1
NAME=radiosity_example; . "$TB_SOURCE_DIR/tests/radiosity/rad_cli.sh"
BOX="$TB_SOURCE_DIR/scenes/cornell-box.mid"

"$EXAMPLE" "$BOX" "$T/example.csv" "$T/example.pfm" 300 > "$T/out1" 2>&1 || { cat "$T/out1"; fail "example run"; }
rad "$BOX" --patches "$T/command.csv" --max-shots 300 --threads 2 > "$T/out2" 2>&1 ||
    { cat "$T/out2"; fail "command run"; }
[ "$(wc -l < "$T/command.csv")" -eq 1323 ] || fail "command CSV has $(wc -l < "$T/command.csv") lines, not 1 + 1322"
cmp "$T/example.csv" "$T/command.csv" || fail "the example's CSV differs from the command's"
grep -q "1322 elements, 300 shots" "$T/out1" || { cat "$T/out1"; fail "example summary"; }
"$TESTBED" compare "$T/example.pfm" "$T/example.pfm" > /dev/null || fail "the example's image does not read back"
# usage: no arguments is exit 2
"$EXAMPLE" > /dev/null 2>&1; [ $? -eq 2 ] || fail "no arguments: expected exit 2"
rm -rf "$T"
echo "radiosity example: same CSV bytes as the command"
