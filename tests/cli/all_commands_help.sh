#!/bin/sh
# Script test: every subcommand `testbed help` lists (and every benchmark
# `testbed bench --help` lists) answers --help with exit 0, nothing on stderr
# and its usage line first on stdout; `testbed help CMD` prints the same; an
# unknown option is a usage error (exit 2, nothing on stdout, a message on
# stderr naming the option). The lists come from the command itself, so a new
# subcommand is covered without editing this test.
set -eu
: "${TESTBED:?}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

# `testbed help`: the command lines sit between "Commands:" and the first blank line.
"$TESTBED" help >"$tmp/list" || fail "testbed help: exit $?"
cmds=$(awk '/Commands:$/ { on = 1; next } on && /^$/ { exit } on { print $1 }' "$tmp/list")
[ "$(printf '%s\n' "$cmds" | wc -l)" -ge 10 ] || fail "testbed help lists too few commands: $cmds"
"$TESTBED" bench --help >"$tmp/bench" || fail "testbed bench --help: exit $?"
benches=$(sed -n 's/^usage: testbed bench \([a-z]*\).*/\1/p' "$tmp/bench")
[ "$(printf '%s\n' "$benches" | wc -l)" -ge 6 ] || fail "testbed bench --help lists too few benchmarks: $benches"

# check NAME ARGS...: `testbed ARGS... --help` and `testbed ARGS... --no-such-option`.
check() {
  name=$1
  shift
  st=0
  "$TESTBED" "$@" --help >"$tmp/out" 2>"$tmp/err" || st=$?
  [ "$st" -eq 0 ] || fail "$name --help: exit $st"
  [ ! -s "$tmp/err" ] || fail "$name --help wrote to stderr: $(cat "$tmp/err")"
  head -n 1 "$tmp/out" | grep -Eq "^usage: testbed $name( |\$)" ||
    fail "$name --help: first line is not 'usage: testbed $name ...': $(head -n 1 "$tmp/out")"
  st=0
  "$TESTBED" "$@" --no-such-option >"$tmp/out" 2>"$tmp/err" || st=$?
  [ "$st" -eq 2 ] || fail "$name --no-such-option: exit $st, not 2"
  [ ! -s "$tmp/out" ] || fail "$name --no-such-option wrote to stdout: $(cat "$tmp/out")"
  grep -q -- "--no-such-option" "$tmp/err" || fail "$name --no-such-option: no message naming it: $(cat "$tmp/err")"
}

n=0
for c in $cmds; do
  check "$c" "$c"
  "$TESTBED" "$c" --help >"$tmp/direct"
  "$TESTBED" help "$c" >"$tmp/via-help" || fail "testbed help $c: exit $?"
  cmp -s "$tmp/direct" "$tmp/via-help" || fail "testbed help $c differs from testbed $c --help"
  n=$((n + 1))
done
for b in $benches; do
  check "bench $b" bench "$b"
  n=$((n + 1))
done
echo "all commands --help: $n ok"
