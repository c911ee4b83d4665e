#!/bin/sh
# tools/examples/attributes.c prints a renderer's own attribute of every
# object of example_attributes.mid: from the body, from the geometry block,
# a string, and the default where the object has none (a material's or a CSG
# child's attribute is not the object's).
#   example_attributes.sh EXAMPLE  (with TB_SOURCE_DIR, TB_TEST_TMPDIR set)
set -u
EXAMPLE=$1
T="${TB_TEST_TMPDIR:-/tmp}/example_attributes.$$"
rm -rf "$T" && mkdir -p "$T"
fail() { echo "FAIL: $*"; exit 1; }
MID="$TB_SOURCE_DIR/tests/render/example_attributes.mid"

"$EXAMPLE" "$MID" > "$T/out" 2>&1 || { cat "$T/out"; fail "example run"; }
cat > "$T/expected" <<'OUT'
0 'floor': my_renderer_weight = 0.5
1 'ball': my_renderer_weight = 2.5
2 'box': my_renderer_weight not set (default 1)
3 'post': my_renderer_weight = 4
4 (unnamed): my_renderer_weight = "auto"
OUT
diff "$T/expected" "$T/out" || fail "output differs from the expected lines"
# another name; usage errors; a scene that does not load
"$EXAMPLE" "$MID" my_other > "$T/out2" 2>&1 || fail "example run with a name"
[ "$(grep -c 'my_other not set (default 1)' "$T/out2")" -eq 5 ] || { cat "$T/out2"; fail "missing name"; }
"$EXAMPLE" > /dev/null 2>&1; [ $? -eq 2 ] || fail "no arguments: expected exit 2"
"$EXAMPLE" "$T/missing.mid" > "$T/out3" 2>&1; [ $? -eq 1 ] || fail "missing file: expected exit 1"
grep -q "^attributes: " "$T/out3" || { cat "$T/out3"; fail "missing file message"; }
rm -rf "$T"
echo "attributes example: the expected attribute of every object"
