#!/bin/sh
# tools/examples/render_file.c, one tb_render_file call on a page, makes the
# same image as `testbed render --backend cpu`, byte for byte: the command is
# a thin layer over that call. The Cornell box at 2 samples per pixel as PFM
# (no provenance in the file, so the bytes are the pixels), and the stats
# JSON of both has the same keys and sample count.
#   example.sh EXAMPLE  (with TESTBED, TB_SOURCE_DIR, TB_TEST_TMPDIR set)
set -u
EXAMPLE=$1
T="${TB_TEST_TMPDIR:-/tmp}/render_example.$$"
rm -rf "$T" && mkdir -p "$T"
fail() { echo "FAIL: $*"; exit 1; }
BOX="$TB_SOURCE_DIR/scenes/cornell-box.mid"

"$EXAMPLE" "$BOX" "$T/example.pfm" 2 "$T/example.json" > "$T/out1" 2>&1 || { cat "$T/out1"; fail "example run"; }
"$TESTBED" render "$BOX" -o "$T/command.pfm" --spp 2 --backend cpu --stats "$T/command.json" > "$T/out2" 2>&1 ||
    { cat "$T/out2"; fail "command run"; }
cmp "$T/example.pfm" "$T/command.pfm" || fail "the example's image differs from the command's"
grep -q "512x512, 524288 samples" "$T/out1" || { cat "$T/out1"; fail "example summary"; }
# the same stats keys and counts (times differ); the provenance records each program's own command line
python3 - "$T/example.json" "$T/command.json" <<'PY' || fail "stats JSON"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
assert list(a) == list(b), (list(a), list(b))
for k in ("samples", "passes", "interrupted"):
    assert a[k] == b[k], (k, a[k], b[k])
assert a["provenance"]["options"] == b["provenance"]["options"], (a["provenance"], b["provenance"])
PY
# usage: no arguments is exit 2; an unknown image format is an error, not a file
"$EXAMPLE" > /dev/null 2>&1; [ $? -eq 2 ] || fail "no arguments: expected exit 2"
"$EXAMPLE" "$BOX" "$T/x.bmp" 1 > "$T/out3" 2>&1 && fail "unknown format: expected failure"
grep -q "unknown image format" "$T/out3" || { cat "$T/out3"; fail "unknown format message"; }
rm -rf "$T"
echo "render example: same PFM bytes as the command"
