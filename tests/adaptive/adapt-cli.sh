#!/bin/sh
# `testbed render --method radiosity --adapt`: the options reach the solver
# (more elements, most of them in the penumbra ring of shadow.mid), bad
# combinations are refused with the usage exit code, --help documents them.
set -eu
T="$TB_TEST_TMPDIR/adapt-cli"
rm -rf "$T" && mkdir -p "$T"
S="$TB_SOURCE_DIR/tests/adaptive/shadow.mid"
run() { "$TESTBED" render "$S" --method radiosity --max-edge 0.125 --samples 16 --threshold 0.9 "$@"; }

run --patches "$T/uniform.csv" >/dev/null 2>&1
run --adapt 0.3 --adapt-levels 2 --patches "$T/adaptive.csv" >/dev/null 2>"$T/err.txt"
n0=$(($(wc -l <"$T/uniform.csv") - 1))
n1=$(($(wc -l <"$T/adaptive.csv") - 1))
echo "elements: uniform $n0, adaptive $n1"
[ "$n0" -eq 74 ] || { echo "expected 64 floor + 9 occluder + 1 lamp elements, got $n0"; exit 1; }
[ "$n1" -gt "$n0" ] || { echo "--adapt did not refine"; exit 1; }
grep -q "adaptive subdivision: 2 rounds" "$T/err.txt" || { cat "$T/err.txt"; exit 1; }
# floor elements (object 0) by centroid: inside the widened penumbra ring, and elsewhere
awk -F, 'NR > 1 && $2 == 0 {
    x = $4; y = $5; a = $3
    outer = x > 0.185 && x < 0.815 && y > 0.185 && y < 0.815
    inner = x > 0.335 && x < 0.665 && y > 0.335 && y < 0.665
    if (outer && !inner) { nn++; an += a } else { nf++; af += a }
} END {
    dn = nn / an; df = nf / af
    printf "density near the penumbra %.0f, elsewhere %.0f\n", dn, df
    exit !(dn > 3 * df)
}' "$T/adaptive.csv"
# the same again: deterministic
run --adapt 0.3 --adapt-levels 2 --patches "$T/again.csv" --threads 1 >/dev/null 2>&1
cmp "$T/adaptive.csv" "$T/again.csv"

usage() {
    set +e
    run "$@" --patches "$T/x.csv" >/dev/null 2>"$T/usage.txt"
    rc=$?
    set -e
    [ "$rc" -eq 2 ] || { echo "expected exit 2 for: $*, got $rc"; cat "$T/usage.txt"; exit 1; }
}
usage --adapt 0
usage --adapt -1
usage --adapt x
usage --adapt-levels 2
usage --min-area 0.01
usage --adapt 0.3 --adapt-levels 0
usage --adapt 0.3 --min-area -1
usage --adapt 0.3 --report "$T/r.csv" --reference "$T/uniform.csv"
"$TESTBED" render --method radiosity --help | grep -q -- "--adapt X"
"$TESTBED" render --method radiosity --help | grep -q -- "--adapt-levels N"
"$TESTBED" render --method radiosity --help | grep -q -- "--min-area A"
echo ok
