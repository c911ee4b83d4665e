#!/bin/sh
# Script test: tools/bench/run-all.sh --quick on three cheap benchmarks
# (bench intersect, bench tessellate, trace) prints the machine header, the
# load averages, each benchmark's results table with its rows, and writes the
# same tables to --out; usage errors exit 2. Rates are not checked.
set -eu
: "${TESTBED:?}" "${TB_SOURCE_DIR:?}"
dir=$(mktemp -d "${TB_TEST_TMPDIR:-${TMPDIR:-/tmp}}/run-all.XXXXXX")
trap 'rm -rf "$dir"' EXIT INT TERM
script=$TB_SOURCE_DIR/tools/bench/run-all.sh
out=$(TESTBED="$TESTBED" bash "$script" --quick --only intersect,tessellate,trace --out "$dir/out.md" 2>"$dir/err")
printf '%s\n' "$out"
printf '%s\n' "$out" | awk '
/^  CPU: / { cpu = 1 }
/^  testbed: +testbed [0-9]/ { ver = 1 }
/^load average before: [0-9.]+ / { before++ }
/^load average after: +[0-9.]+ / { after++ }
/^CPU used by other processes before: [0-9.]+ %$/ { busy++ }
/^status: (intersect|tessellate|trace) ok / { ok++ }
/^\| sphere \| [0-9.]+ \| [0-9.]+ \| [0-9.]+ \|$/ { isect = 1 }
/^\| cube - sphere \| / { csg = 1 }
/^\| torus \| [0-9]+ \| [0-9.]+ \| [0-9.]+ \| [0-9]+ \| [0-9.]+ \| [0-9.]+ \|$/ { tess = 1 }
/^\| (bvh|grid) \| [12] \| [0-9.]+ \| [0-9.]+ \|$/ { trace++ }
/^run-all: 3 of 3 benchmarks ran/ { done = 1 }
END {
    if (!cpu || !ver) { print "FAIL: machine header (CPU, testbed version) missing"; bad = 1 }
    if (before != 3 || after != 3) { print "FAIL: expected 3 load-average lines before and after"; bad = 1 }
    if (busy != 3) { print "FAIL: expected 3 lines of the CPU others used"; bad = 1 }
    if (ok != 3) { print "FAIL: expected 3 ok statuses, got " ok; bad = 1 }
    if (!isect || !csg) { print "FAIL: bench intersect rows missing"; bad = 1 }
    if (!tess) { print "FAIL: bench tessellate torus row missing"; bad = 1 }
    if (trace != 4) { print "FAIL: expected 4 trace rows (bvh, grid x 1, 2 threads), got " trace; bad = 1 }
    if (!done) { print "FAIL: summary line missing"; bad = 1 }
    exit bad
}'
# The --out file has the machine table and the same three results tables.
for t in machine intersect/objects tessellate/kinds trace/rates; do
    grep -q "^<!-- run-all.sh table: ${t}[: ]" "$dir/out.md" || { echo "FAIL: --out lacks table $t"; exit 1; }
done
grep -q '^| CPU | ' "$dir/out.md" || { echo "FAIL: --out lacks the CPU row"; exit 1; }
grep -q '^| sphere | ' "$dir/out.md" || { echo "FAIL: --out lacks the sphere row"; exit 1; }
# A loaded machine must be reported as such (the load is what it is here, so
# only check that the warning and the note agree) ...
if grep -q 'machine not idle: figures not valid' "$dir/err"; then
    grep -q '| \*\*no: figures not valid\*\* |' "$dir/out.md" || { echo "FAIL: not-idle note missing in --out"; exit 1; }
fi
# ... and a threshold no machine meets (-1 %) must give the warning on both
# streams and the note in --out, with the log not truncated by the warning.
TESTBED="$TESTBED" RUN_ALL_IDLE_BUSY=-1 bash "$script" --quick --only intersect --out "$dir/busy.md" >"$dir/busy.log" 2>&1 || true
grep -c 'WARNING: machine not idle' "$dir/busy.log" | grep -qx 2 || { echo "FAIL: the not-idle warning is not on stdout and stderr once each"; exit 1; }
grep -q '^run-all: 1 of 1 benchmarks ran' "$dir/busy.log" || { echo "FAIL: the log lost its summary"; exit 1; }
[ "$(tr -d '\000' <"$dir/busy.log" | wc -c)" -eq "$(wc -c <"$dir/busy.log")" ] ||
    { echo "FAIL: NUL bytes in the log (truncated while written)"; exit 1; }
grep -q '| intersect | .* | \*\*no: figures not valid\*\* |' "$dir/busy.md" || { echo "FAIL: not-idle note missing in --out"; exit 1; }
# Usage errors.
set +e
bash "$script" --only nosuch >/dev/null 2>&1; rc=$?
[ "$rc" -eq 2 ] || { echo "FAIL: --only nosuch exited $rc, not 2"; exit 1; }
bash "$script" --frobnicate >/dev/null 2>&1; rc=$?
[ "$rc" -eq 2 ] || { echo "FAIL: an unknown option exited $rc, not 2"; exit 1; }
set -e
bash "$script" --help | grep -q '^  povray ' || { echo "FAIL: --help does not list the benchmarks"; exit 1; }
echo "run-all: ok"
