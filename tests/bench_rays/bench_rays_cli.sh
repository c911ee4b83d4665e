#!/bin/sh
# Script test: `testbed bench rays` options without Embree. --help documents
# --min-time; a bad --min-time, --threads list, --rays or --repeat, a missing
# or second scene, --embree-config without --embree and an unknown option are
# usage errors (exit 2, a message naming the problem); with the default
# --min-time a short set is traced several times per timed run and says so;
# with --min-time 0 it is traced once (no such line).
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
  grep -qF -- "--min-time: expected a number in [0, 60], got '$bad'" "$err" ||
    { echo "FAIL: no message for --min-time $bad"; cat "$err"; exit 1; }
done
# usage TEXT ARGS...: `bench rays ARGS...` is a usage error (exit 2) whose message holds TEXT.
usage() {
  want=$1
  shift
  if "$TESTBED" bench rays "$@" >/dev/null 2>"$err"; then
    echo "FAIL: bench rays $* accepted"; exit 1
  else
    st=$?
  fi
  [ "$st" -eq 2 ] || { echo "FAIL: bench rays $*: exit $st, not 2"; exit 1; }
  grep -qF -- "$want" "$err" || { echo "FAIL: bench rays $*: message lacks '$want':"; cat "$err"; exit 1; }
}
for bad in 0 257 x 1,x , 1,2,3,4,5,6,7,8,9 -1; do
  usage "--threads: expected up to 8 comma-separated thread counts in [1, 256], got '$bad'" "$scene" --threads "$bad"
done
usage "--rays: expected an integer in [1, 268435456], got '0'" "$scene" --rays 0
usage "--repeat: expected an integer in [1, 100], got '101'" "$scene" --repeat 101
usage "--embree-config needs --embree or --embree-robust" "$scene" --embree-config max_isa=sse2
usage "no SCENE.mid given" --rays 10
usage "unexpected argument" "$scene" "$scene"
usage "unknown option '--bogus'" "$scene" --bogus
out=$("$TESTBED" bench rays "$scene" --rays 2000 --repeat 1 --threads 1)
printf '%s\n' "$out"
printf '%s\n' "$out" | grep -Eq "^primary +each timed run traced the set [0-9]+ times" || { echo "FAIL: no pass count"; exit 1; }
out=$("$TESTBED" bench rays "$scene" --rays 2000 --repeat 1 --threads 1 --min-time 0)
if printf '%s\n' "$out" | grep -q "each timed run"; then echo "FAIL: --min-time 0 still repeats"; exit 1; fi
printf '%s\n' "$out" | grep -Eq "^primary +2000 " || { echo "FAIL: no primary row"; exit 1; }
echo "bench rays CLI: ok"
