#!/bin/sh
# Script test (issue 19): `testbed render --memory-budget` refuses a scene
# predicted over the budget before loading it (exit 1, a message naming what
# takes the memory, no image), accepts it under a generous budget, rejects a
# malformed budget (exit 2); `testbed bench scale` measures two small counts
# and writes one CSV row per count with positive times and memory (prepare may be 0:
# it is the load minus a separate parse pass, clamped, and a preempted parse can exceed it).
set -eu
: "${TESTBED:?}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

"$TESTBED" generate grid --count 300 -o "$tmp/g.mid" || fail "generate: exit $?"
st=0
"$TESTBED" render "$tmp/g.mid" -o "$tmp/small.pfm" --memory-budget 64k --backend cpu >"$tmp/out" 2>"$tmp/err" || st=$?
[ "$st" -eq 1 ] || fail "--memory-budget 64k: exit $st, not 1"
[ ! -e "$tmp/small.pfm" ] || fail "--memory-budget 64k: an image was written"
grep -q "more than the memory budget of 0.1 MiB" "$tmp/err" || fail "no budget message: $(cat "$tmp/err")"
grep -q "objects [0-9.]* MiB ([0-9]* objects, [0-9]* bytes each)" "$tmp/err" || fail "the message does not say what takes the memory: $(cat "$tmp/err")"
grep -q "emitters [0-9.]* MiB" "$tmp/err" || fail "the message does not name the emitters: $(cat "$tmp/err")"
"$TESTBED" render "$tmp/g.mid" -o "$tmp/ok.pfm" --memory-budget 1G --backend cpu --threads 1 >"$tmp/out" 2>"$tmp/err" ||
  fail "--memory-budget 1G: exit $?: $(cat "$tmp/err")"
[ -s "$tmp/ok.pfm" ] || fail "--memory-budget 1G: no image"
st=0
"$TESTBED" render "$tmp/g.mid" -o "$tmp/x.pfm" --memory-budget 12q >"$tmp/out" 2>"$tmp/err" || st=$?
[ "$st" -eq 2 ] || fail "--memory-budget 12q: exit $st, not 2"

"$TESTBED" bench scale --counts 50,200 --threads 1 --dir "$tmp" --csv "$tmp/s.csv" >"$tmp/out" 2>"$tmp/err" ||
  fail "bench scale: exit $?: $(cat "$tmp/err")"
[ "$(wc -l <"$tmp/s.csv")" -eq 3 ] || fail "bench scale: CSV has not 1 + 2 lines: $(cat "$tmp/s.csv")"
awk -F, 'NR > 1 && !($2 > 0 && $4 >= 0 && $5 >= 0 && $7 > 0 && $8 > 0 && $10 > 0) { bad = 1 } END { exit bad }' \
  "$tmp/s.csv" || fail "bench scale: a row with a non-positive figure: $(cat "$tmp/s.csv")"
[ -z "$(ls "$tmp" | grep testbed-bench-scale || true)" ] || fail "bench scale: left its scenes behind"
echo "scale CLI: ok"
