#!/usr/bin/env bash
# `testbed generate` end to end: every kind passes `testbed check` with the
# requested number of top-level objects; the same seed gives the same bytes,
# another seed other bytes; -o FILE holds exactly what standard output gets;
# write errors and usage errors give their exit statuses.
set -u
: "${TESTBED:?}" "${TB_SOURCE_DIR:?}" "${TB_TEST_TMPDIR:?}"
tmp="$TB_TEST_TMPDIR/generate_cli"
rm -rf "$tmp" && mkdir -p "$tmp"
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }

# expect_status WANT CMD...: runs CMD, checks its exit status.
expect_status() {
    local want=$1
    shift
    "$@" >"$tmp/out" 2>"$tmp/err"
    local rc=$?
    [[ $rc == "$want" ]] || { fail "'$*': exit $rc, expected $want"; cat "$tmp/err"; }
}

for spec in grid:150 csg:60 mesh:6; do
    kind=${spec%%:*} n=${spec##*:}
    "$TESTBED" generate "$kind" --count "$n" --seed 42 >"$tmp/$kind.a.mid" || fail "$kind: generate exit $?"
    "$TESTBED" generate "$kind" --count "$n" --seed 42 -o "$tmp/$kind.b.mid" || fail "$kind: generate -o exit $?"
    "$TESTBED" generate "$kind" --seed 0x2a --count "$n" >"$tmp/$kind.c.mid" || fail "$kind: hex seed exit $?"
    "$TESTBED" generate "$kind" --count "$n" --seed 43 >"$tmp/$kind.d.mid" || fail "$kind: seed 43 exit $?"
    cmp -s "$tmp/$kind.a.mid" "$tmp/$kind.b.mid" || fail "$kind: -o FILE differs from standard output"
    cmp -s "$tmp/$kind.a.mid" "$tmp/$kind.c.mid" || fail "$kind: same seed (42 = 0x2a) gave different bytes"
    cmp -s "$tmp/$kind.a.mid" "$tmp/$kind.d.mid" && fail "$kind: seeds 42 and 43 gave the same bytes"
    [[ -z "$(find "$tmp" -name '*.tmp.*')" ]] || fail "$kind: temporary file left behind"
    "$TESTBED" check "$tmp/$kind.a.mid" >"$tmp/out" 2>"$tmp/err" || { fail "$kind: testbed check failed"; cat "$tmp/err"; }
    grep -q "^objects: $n top-level, " "$tmp/out" || { fail "$kind: expected $n top-level objects"; cat "$tmp/out"; }
    grep -qxF "lights: 2: point_light 1, directional_light 1" "$tmp/out" || fail "$kind: lights"
    # A different seed is just as valid.
    "$TESTBED" check "$tmp/$kind.d.mid" >/dev/null 2>"$tmp/err" || { fail "$kind: seed 43 invalid"; cat "$tmp/err"; }
done
# The first line is the header, the writer's canonical form.
[[ "$(head -n1 "$tmp/grid.a.mid")" == "mid 1.1" ]] || fail "header"

# Defaults: 100 objects; 0 objects is a valid (empty) scene.
"$TESTBED" generate csg | "$TESTBED" check - >"$tmp/out" 2>"$tmp/err" || fail "default count: check failed"
grep -q "^objects: 100 top-level, " "$tmp/out" || fail "default count is not 100"
"$TESTBED" generate mesh --count 0 | "$TESTBED" check - >"$tmp/out" 2>"$tmp/err" || fail "count 0: check failed"
grep -qxF "objects: 0 top-level, 0 in all" "$tmp/out" || { fail "count 0"; cat "$tmp/out"; }

# Help.
expect_status 0 "$TESTBED" generate --help
grep -q "^usage: testbed generate KIND" "$tmp/out" || fail "--help text"
expect_status 0 "$TESTBED" help generate

# Write errors: a full device on standard output, a missing folder for -o.
if [[ -w /dev/full ]]; then
    "$TESTBED" generate mesh --count 20 >/dev/full 2>"$tmp/err"
    [[ $? == 1 ]] || fail "/dev/full: expected exit 1"
    grep -q "^testbed generate: error: " "$tmp/err" || fail "/dev/full: no message"
fi
expect_status 1 "$TESTBED" generate grid -o "$tmp/no/such/folder/x.mid"
[[ ! -e "$tmp/no" ]] || fail "-o into a missing folder created something"

# Usage errors.
expect_status 2 "$TESTBED" generate
expect_status 2 "$TESTBED" generate spheres
grep -qxF "testbed generate: error: unknown scene kind 'spheres' (expected grid, csg or mesh)" "$tmp/err" ||
    { fail "unknown kind message"; cat "$tmp/err"; }
expect_status 2 "$TESTBED" generate grid csg
expect_status 2 "$TESTBED" generate grid --count
expect_status 2 "$TESTBED" generate grid --count -1
expect_status 2 "$TESTBED" generate grid --count 12x
expect_status 2 "$TESTBED" generate grid --count 1e3
expect_status 2 "$TESTBED" generate grid --count 1000000000001
expect_status 2 "$TESTBED" generate grid --seed banana
expect_status 2 "$TESTBED" generate grid --seed 18446744073709551616
expect_status 2 "$TESTBED" generate grid --bogus
expect_status 0 "$TESTBED" generate grid --count 1 --seed 18446744073709551615

if [[ $fails != 0 ]]; then
    echo "$fails failure(s)"
    exit 1
fi
echo "all generate checks passed"
