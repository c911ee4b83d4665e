#!/bin/sh
# `testbed bench intersect`: runs, prints one row per object with rates, and
# refuses bad arguments with the usage exit status.
set -u
fail() { echo "FAIL: $*"; exit 1; }
out=$("$TESTBED" bench intersect --rays 2000 --seed 7) || fail "bench intersect exited $?"
echo "$out"
for row in sphere cube cylinder cone pyramid prism torus conic square_arch round_arch "mesh 320 tris" \
           "mesh 20480 tris" "cube - sphere"; do
    echo "$out" | grep -q "^$row " || fail "no row for $row"
done
# Every row: hit % in [0, 100] and two positive rates.
echo "$out" | awk 'NR > 3 { n = NF; if ($(n-2) < 0 || $(n-2) > 100 || $(n-1) <= 0 || $n <= 0) bad = 1 }
                   END { exit bad }' || fail "a row has a bad number"
"$TESTBED" bench intersect --rays 0 >/dev/null 2>&1; [ $? -eq 2 ] || fail "--rays 0 accepted"
"$TESTBED" bench intersect --bogus >/dev/null 2>&1; [ $? -eq 2 ] || fail "unknown option accepted"
"$TESTBED" bench nothing >/dev/null 2>&1; [ $? -eq 2 ] || fail "unknown benchmark accepted"
"$TESTBED" bench --help | grep -q "usage: testbed bench" || fail "no help"
echo "OK"
