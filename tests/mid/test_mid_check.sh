#!/usr/bin/env bash
# `testbed check` end to end: summary of the example scene (expected values
# worked out by hand from tests/mid/data/example.mid), --warn-unknown,
# standard input, an invalid scene, a missing file, and usage errors.
set -u
: "${TESTBED:?}" "${TB_SOURCE_DIR:?}" "${TB_TEST_TMPDIR:?}"
data="$TB_SOURCE_DIR/tests/mid/data"
tmp="$TB_TEST_TMPDIR/mid_check"
rm -rf "$tmp" && mkdir -p "$tmp"
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }

# expect_line FILE LINE: FILE holds LINE exactly.
expect_line() { grep -qxF -- "$2" "$1" || { fail "missing line: $2"; echo "--- $1:"; cat "$1"; }; }

# --- the example scene
"$TESTBED" check "$data/example.mid" >"$tmp/out" 2>"$tmp/err"
rc=$?
[[ $rc == 0 ]] || fail "example.mid: exit $rc"
[[ ! -s "$tmp/err" ]] || { fail "example.mid: unexpected stderr"; cat "$tmp/err"; }
expect_line "$tmp/out" "$data/example.mid: valid MID 1.0 scene"
expect_line "$tmp/out" "objects: 15 top-level, 19 in all: sphere 3, cube 2, cylinder 2, cone 1, pyramid 1, prism 2, torus 1, polygons 2, conic 1, square_arch 1, round_arch 1, union 1, difference 1"
expect_line "$tmp/out" "emitting objects: 1"
expect_line "$tmp/out" "materials: 5: white, red, glossy red, glass, lamp"
expect_line "$tmp/out" "lights: 3: point_light 1, spot_light 1, directional_light 1"
# fov = 2 atan(24 mm / (2 x 50 mm)) = 26.9915 degrees (a 4:3 image on a 36x24 film)
expect_line "$tmp/out" "camera: eye [0 -8 2], look_at [0 0 1], fov 26.9915 deg, 640 x 480 pixels"
# floor +-4 in x and y at z = 0; the top sphere (unit, at z = 5) reaches z = 6
expect_line "$tmp/out" "bounds: [-4 -4 0] to [4 4 6]"
expect_line "$tmp/out" "referenced files: 1"
expect_line "$tmp/out" "  checker.png -> $data/checker.png"

# --- --warn-unknown: the two unknown attributes of the last sphere, at their lines
"$TESTBED" check --warn-unknown "$data/example.mid" >"$tmp/out" 2>"$tmp/err" || fail "--warn-unknown: exit $?"
line_note=$(grep -n '^    note = ' "$data/example.mid" | cut -d: -f1)
line_custom=$(grep -n '^    x_custom = ' "$data/example.mid" | cut -d: -f1)
expect_line "$tmp/err" "$data/example.mid:$line_note:5: warning: unknown attribute 'note' in sphere"
expect_line "$tmp/err" "$data/example.mid:$line_custom:5: warning: unknown attribute 'x_custom' in sphere"
[[ $(wc -l <"$tmp/err") == 2 ]] || fail "--warn-unknown: expected 2 warnings"
expect_line "$tmp/out" "unknown attributes: 2"

# --- standard input: references resolve against the current folder
(cd "$data" && "$TESTBED" check - <example.mid) >"$tmp/out" 2>"$tmp/err" || fail "stdin: exit $?"
expect_line "$tmp/out" "<stdin>: valid MID 1.0 scene"
expect_line "$tmp/out" "  checker.png -> $data/checker.png"
(cd "$tmp" && "$TESTBED" check - <"$data/example.mid") >"$tmp/out" 2>"$tmp/err"
[[ $? == 1 ]] || fail "stdin from another folder should fail"
grep -q "error: data file 'checker.png' not found (looked for '$tmp/checker.png')" "$tmp/err" ||
    { fail "stdin: missing-file message"; cat "$tmp/err"; }

# --- an invalid scene: exit 1, the message on stderr, nothing on stdout
printf 'mid 1\nsphere {\n    transform = [scale(0)]\n' >"$tmp/bad.mid"
"$TESTBED" check "$tmp/bad.mid" >"$tmp/out" 2>"$tmp/err"
rc=$?
[[ $rc == 1 ]] || fail "bad.mid: exit $rc, expected 1"
[[ ! -s "$tmp/out" ]] || fail "bad.mid: stdout not empty"
expect_line "$tmp/err" "$tmp/bad.mid:4:1: error: expected '}' to close 'sphere' opened at 2:1, found end of file"
printf 'mid 1\nsphere {\n    transform = [scale(0)]\n}\n' >"$tmp/bad.mid"
"$TESTBED" check "$tmp/bad.mid" >"$tmp/out" 2>"$tmp/err"
[[ $? == 1 ]] || fail "bad.mid (zero scale): exit"
expect_line "$tmp/err" "$tmp/bad.mid:3:18: error: scale factors must be non-zero (a zero scale is singular)"

# --- a file that does not exist
"$TESTBED" check "$tmp/none.mid" >"$tmp/out" 2>"$tmp/err"
[[ $? == 1 ]] || fail "missing file: exit"
expect_line "$tmp/err" "testbed check: error: $tmp/none.mid: cannot open: No such file or directory"

# --- usage
"$TESTBED" check >"$tmp/out" 2>"$tmp/err"; [[ $? == 2 ]] || fail "no argument: exit should be 2"
"$TESTBED" check --bogus "$data/example.mid" >"$tmp/out" 2>"$tmp/err"; [[ $? == 2 ]] || fail "bad option: exit should be 2"
expect_line "$tmp/err" "testbed check: error: unknown option '--bogus' (see \`testbed check --help\`)"
"$TESTBED" check a.mid b.mid >"$tmp/out" 2>"$tmp/err"; [[ $? == 2 ]] || fail "two scenes: exit should be 2"
"$TESTBED" check --help >"$tmp/out" 2>"$tmp/err" || fail "--help: exit"
grep -q '^usage: testbed check SCENE.mid \[--warn-unknown\]' "$tmp/out" || fail "--help text"
"$TESTBED" help check >"$tmp/out" 2>"$tmp/err" || fail "help check: exit"
"$TESTBED" help >"$tmp/out" 2>&1
grep -q '^  check ' "$tmp/out" || fail "check missing from testbed help"

if ((fails)); then
    echo "$fails failure(s)"
    exit 1
fi
echo "testbed check: all good"
