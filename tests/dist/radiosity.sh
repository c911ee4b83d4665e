#!/bin/sh
# `mpirun -np N testbed render --method radiosity` (docs/distributed.md,
# "Radiosity"): each shot's receivers shared over 2 and over 3 ranks give
# the one-process `--patches` CSV byte for byte, also with adaptive
# subdivision and two levels (patches and elements), and any thread count;
# the update is split over the ranks (every shot, also with 3 ranks whose
# shooter ranges differ in size) and the energy sums equal one process's;
# the stats have per-rank figures; --several-shooters gives a result that
# does not depend on the thread count and stays within 1 % (relative RMS) of
# the deterministic one; a bad scene stops every rank with its
# file:line:col error.
#   radiosity.sh  (with TESTBED, TB_SOURCE_DIR, TB_TEST_TMPDIR set)
set -u
. "$(dirname "$0")/mpirun.sh"
T="${TB_TEST_TMPDIR:-/tmp}/dist_radiosity.$$"
rm -rf "$T" && mkdir -p "$T"
S="$TB_SOURCE_DIR/scenes/cornell-box.mid"
R="--method radiosity --max-edge 120 --threshold 0.02"
rad1() { "$TESTBED" render "$S" $R "$@" > "$T/out" 2>&1 || { cat "$T/out"; fail "one process: $*"; }; }
radN() { n=$1; shift; $MPIRUN -np "$n" "$TESTBED" render "$S" $R "$@" > "$T/out" 2>&1 || { cat "$T/out"; fail "$n ranks: $*"; }; }

rad1 --patches "$T/p1.csv" --threads 2 --stats "$T/s1.json"
rad1 --patches "$T/a1.csv" --adapt 0.2 --adapt-levels 2
rad1 --patches "$T/t1.csv" --patch-edge 300 --seed 5
for n in 2 3; do
    radN $n --patches "$T/p$n.csv" --threads 1 --stats "$T/s$n.json"
    cmp "$T/p1.csv" "$T/p$n.csv" || fail "$n ranks: patches differ from one process"
    grep -q "rank $((n - 1)): [0-9]* receivers, work" "$T/out" || { cat "$T/out"; fail "no per-rank line"; }
    python3 - "$T/s$n.json" "$n" "$T/s1.json" <<'PY' || fail "per-rank stats of $n ranks"
import json, sys
j = json.load(open(sys.argv[1])); n = int(sys.argv[2]); one = json.load(open(sys.argv[3]))
# every shot made with the update split over the ranks (not the replicated path)
split = j['counters']['Radiosity/shots with the update split over ranks']
assert split == j['shots'] > 0, (split, j['shots'])
assert one['counters']['Radiosity/shots with the update split over ranks'] == 0
# the energy bookkeeping is summed in one order whatever the split
for k in ('power_emitted', 'power_absorbed', 'power_unshot', 'power_escaped'):
    assert j[k] == one[k], (k, j[k], one[k])
assert j['ranks'] == n, j.get('ranks')
got = [j['rank%d_receivers' % r] for r in range(n)]
assert all(g > 0 for g in got), got
# cluster c belongs to rank c mod n: the shares differ by at most a cluster per shot
assert max(got) <= 1.2 * min(got), got
PY
    radN $n --patches "$T/a$n.csv" --adapt 0.2 --adapt-levels 2 --threads 2
    cmp "$T/a1.csv" "$T/a$n.csv" || fail "$n ranks: adaptive patches differ from one process"
done
for n in 2 3; do
    radN $n --patches "$T/t$n.csv" --patch-edge 300 --seed 5
    cmp "$T/t1.csv" "$T/t$n.csv" || fail "$n ranks, two levels: patches differ from one process"
done

# several shooters in flight: the same result for any thread count, close
# to (not equal to) the deterministic one; one rank: no change
radN 2 --patches "$T/v2.csv" --threads 1 --several-shooters
radN 2 --patches "$T/v2b.csv" --threads 2 --several-shooters
cmp "$T/v2.csv" "$T/v2b.csv" || fail "several shooters: 1 and 2 threads differ"
cmp -s "$T/p1.csv" "$T/v2.csv" && fail "several shooters gave the deterministic order's bytes (not in flight?)"
d=$(python3 "$TB_SOURCE_DIR/tools/bench/rad-diff.py" "$T/p1.csv" "$T/v2.csv") || fail "rad-diff"
python3 -c "import sys; r = float(sys.argv[1].split()[3].rstrip(',')); sys.exit(0 if 0 < r < 0.01 else 1)" "$d" ||
    fail "several shooters: $d (expected a relative RMS difference below 1 %)"
rad1 --patches "$T/v1.csv" --several-shooters --threads 2
cmp "$T/p1.csv" "$T/v1.csv" || fail "--several-shooters in one process changed the result"

printf 'mid 1\ncamera {\n  eye = [0 0 oops]\n}\n' > "$T/bad.mid"
$MPIRUN -np 2 "$TESTBED" render "$T/bad.mid" --method radiosity --patches "$T/bad.csv" > "$T/out" 2>&1 &&
    { cat "$T/out"; fail "bad scene accepted"; }
grep -q "bad.mid:3:[0-9]*: error:" "$T/out" || { cat "$T/out"; fail "no file:line:col error"; }
[ ! -e "$T/bad.csv" ] || fail "patches written for a bad scene"
rm -rf "$T"
echo "dist radiosity: ok"
