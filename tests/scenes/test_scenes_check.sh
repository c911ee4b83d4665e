#!/usr/bin/env bash
# Every bundled scene (scenes/**/*.mid) passes `testbed check`; the Cornell
# Box files are what scenes/tools/cornell_box.py writes. Guards that make the
# test able to fail: at least the six known scenes are found, and a damaged
# copy of one of them is rejected by the same loop.
set -u
: "${TESTBED:?}" "${TB_SOURCE_DIR:?}" "${TB_TEST_TMPDIR:?}"
tmp="$TB_TEST_TMPDIR/scenes_check"
rm -rf "$tmp" && mkdir -p "$tmp"
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }

# check_all DIR: runs testbed check on every .mid under DIR; prints how many
# passed and failed as "PASSED FAILED".
check_all() {
    local ok=0 bad=0 f
    while IFS= read -r -d '' f; do
        if "$TESTBED" check "$f" >"$tmp/out" 2>"$tmp/err"; then
            ok=$((ok + 1))
        else
            bad=$((bad + 1))
            echo "testbed check failed on $f:" >&2
            cat "$tmp/err" >&2
        fi
    done < <(find "$1" -name '*.mid' -print0 | sort -z)
    echo "$ok $bad"
}

read -r ok bad < <(check_all "$TB_SOURCE_DIR/scenes")
echo "scenes: $ok valid, $bad invalid"
[[ $bad == 0 ]] || fail "$bad bundled scene(s) failed testbed check"
[[ $ok -ge 6 ]] || fail "expected at least 6 bundled scenes, found $ok"
for s in cornell-box.mid cornell-box-rgb.mid cornell-box-spheres.mid showcase.mid radiosity-room.mid tests/cornell-box-coplanar-light.mid; do
    [[ -f "$TB_SOURCE_DIR/scenes/$s" ]] || fail "missing scenes/$s"
done

# The loop notices an invalid scene: a copy of the showcase with one material
# used before it is defined.
mkdir -p "$tmp/broken"
sed 's/material = "glass"/material = "no such material"/' "$TB_SOURCE_DIR/scenes/showcase.mid" >"$tmp/broken/showcase.mid"
cp "$TB_SOURCE_DIR/scenes/radiosity-room.mid" "$tmp/broken/"
read -r ok bad < <(check_all "$tmp/broken" 2>/dev/null)
[[ "$ok $bad" == "1 1" ]] || fail "damaged copy: expected 1 valid and 1 invalid, got $ok and $bad"

# The Cornell files are up to date with their generator script.
if command -v python3 >/dev/null; then
    python3 "$TB_SOURCE_DIR/scenes/tools/cornell_box.py" --check || fail "Cornell Box files differ from cornell_box.py"
else
    fail "python3 not found (needed to check scenes/tools/cornell_box.py)"
fi

# The summaries say what the scenes hold.
"$TESTBED" check "$TB_SOURCE_DIR/scenes/cornell-box.mid" >"$tmp/out" 2>&1
grep -qxF "objects: 8 top-level, 8 in all: polygons 8" "$tmp/out" || fail "cornell-box.mid summary"
grep -qxF "bounds: [0 0 0] to [556 548.8 559.2]" "$tmp/out" || fail "cornell-box.mid bounds"
"$TESTBED" check "$TB_SOURCE_DIR/scenes/cornell-box-spheres.mid" >"$tmp/out" 2>&1
grep -qxF "objects: 8 top-level, 8 in all: sphere 2, polygons 6" "$tmp/out" || fail "cornell-box-spheres.mid summary"
grep -qxF "materials: 6: white, green, red, light, mirror, glass" "$tmp/out" || fail "cornell-box-spheres.mid materials"
grep -qxF "bounds: [0 0 0] to [556 548.8 559.2]" "$tmp/out" || fail "cornell-box-spheres.mid bounds"
"$TESTBED" check "$TB_SOURCE_DIR/scenes/showcase.mid" >"$tmp/out" 2>&1
grep -qxF "lights: 3: point_light 1, spot_light 1, directional_light 1" "$tmp/out" || fail "showcase lights"

if [[ $fails != 0 ]]; then
    echo "$fails failure(s)"
    exit 1
fi
echo "all scene checks passed"
