#!/bin/sh
# Script test: `testbed bench rays` options without Embree. --help documents
# --min-time; a bad --min-time is a usage error (exit 2, a message naming the
# option); with the default --min-time a short set is traced several times per
# timed run and says so; with --min-time 0 it is traced once (no such line).
set -eu
: "${TESTBED:?}" "${TB_SOURCE_DIR:?}"
scene="$TB_SOURCE_DIR/scenes/cornell-box.mid"
err=$(mktemp)
trap 'rm -f "$err"' EXIT
"$TESTBED" bench rays --help | grep -q -- "--min-time S"
for bad in -1 x 61 1e9; do
  if "$TESTBED" bench rays "$scene" --min-time "$bad" >/dev/null 2>"$err"; then
    echo "FAIL: --min-time $bad accepted"; exit 1
  else
    st=$?
  fi
  [ "$st" -eq 2 ] || { echo "FAIL: --min-time $bad: exit $st, not 2"; exit 1; }
  grep -q -- "--min-time needs seconds" "$err" || { echo "FAIL: no message for --min-time $bad"; exit 1; }
done
out=$("$TESTBED" bench rays "$scene" --rays 2000 --repeat 1 --threads 1)
printf '%s\n' "$out"
printf '%s\n' "$out" | grep -Eq "^primary +each timed run traced the set [0-9]+ times" || { echo "FAIL: no pass count"; exit 1; }
out=$("$TESTBED" bench rays "$scene" --rays 2000 --repeat 1 --threads 1 --min-time 0)
if printf '%s\n' "$out" | grep -q "each timed run"; then echo "FAIL: --min-time 0 still repeats"; exit 1; fi
printf '%s\n' "$out" | grep -Eq "^primary +2000 " || { echo "FAIL: no primary row"; exit 1; }
echo "bench rays CLI: ok"
