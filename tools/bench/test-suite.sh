#!/bin/sh
# Script test: tools/bench/suite.sh --quick (every generated kind, one
# assimp-testmodels model, a bundled scene, at a few thousand triangles) runs
# `bench rays --embree` and `bench accel --scene --embree` on every scene, and
# Embree -- an independent tracer -- agrees with our BVH (suite.sh's exit
# status: <= 1 ray in 1000 differs, or none in Embree's robust mode). Every row
# must have rates, build figures and an SAH ratio within 25 % of Embree's
# (a loose bound: a broken builder is off by far more). Rates are not checked.
# Also: suite-gen.py is deterministic and refuses bad arguments, and
# `bench accel --embree` without --scene is a usage error.
set -eu
: "${TESTBED:?}" "${TB_SOURCE_DIR:?}"
tmp=${TB_TEST_TMPDIR:-${TMPDIR:-/tmp}}/suite-test.$$
mkdir -p "$tmp"
trap 'rm -rf "$tmp"' EXIT INT TERM
gen="$TB_SOURCE_DIR/tools/bench/suite-gen.py"
python3 "$gen" slivers --tris 500 --seed 7 >"$tmp/a.mid"
python3 "$gen" slivers --tris 500 --seed 7 >"$tmp/b.mid"
cmp "$tmp/a.mid" "$tmp/b.mid" || { echo "FAIL: suite-gen.py is not deterministic"; exit 1; }
python3 "$gen" slivers --tris 500 --seed 8 >"$tmp/c.mid"
! cmp -s "$tmp/a.mid" "$tmp/c.mid" || { echo "FAIL: --seed changes nothing"; exit 1; }
for bad in "nosuchkind" "bumpy --tris 0" "bumpy --tris x" "bumpy --frobnicate" "--rest 1 2 3"; do
    # shellcheck disable=SC2086 # bad is split into arguments on purpose
    if python3 "$gen" $bad >/dev/null 2>"$tmp/err"; then
        echo "FAIL: suite-gen.py $bad succeeded"
        exit 1
    fi
    grep -q "error" "$tmp/err" || { echo "FAIL: suite-gen.py $bad: no error message"; exit 1; }
done
set +e
"$TESTBED" bench accel --embree >/dev/null 2>&1
rc=$?
set -e
[ $rc = 2 ] || { echo "FAIL: bench accel --embree without --scene: exit $rc, expected 2"; exit 1; }

out=$(TESTBED="$TESTBED" sh "$TB_SOURCE_DIR/tools/bench/suite.sh" --quick --keep "$tmp/suite" 2>&1) || {
    printf '%s\n' "$out"
    echo "FAIL: suite.sh --quick failed"
    exit 1
}
printf '%s\n' "$out"
printf '%s\n' "$out" | awk -F'|' '
$2 ~ /^ (bumpy|terrain|boxes|slivers|objects|mixed|human|cornell-box) $/ {
    rows++
    if ($3 + 0 <= 0) { print "FAIL: no triangles: " $0; bad = 1 }
    for (k = 4; k <= 6; k++) if ($k !~ /[0-9]/ || $k ~ / - /) { print "FAIL: missing ratio: " $0; bad = 1 }
    n = split($8, b, "/"); if (n != 2 || b[1] + 0 <= 0 || b[2] + 0 <= 0) { print "FAIL: build rates: " $0; bad = 1 }
    if ($11 + 0 < 0.75 || $11 + 0 > 1.25) { print "FAIL: SAH ratio out of [0.75, 1.25]: " $0; bad = 1 }
}
/^\| minimum over the suite/ { mins = 1 }
/^\| SAH ours \/ Embree \(maximum\)/ { sah = 1 }
END {
    if (rows != 8) { print "FAIL: expected 8 scene rows, got " rows; bad = 1 }
    if (!mins || !sah) { print "FAIL: the minimum table is missing"; bad = 1 }
    exit bad
}'
