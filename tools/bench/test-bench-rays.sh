#!/bin/sh
# Script test (registered only when Embree 3 was found at configure time):
# `testbed bench rays --embree` on the Cornell box must trace all three ray
# sets and our BVH and Embree -- two independent implementations -- must
# agree on hit/miss, object and face for all but a tiny fraction of rays
# (rays through shared edges may go either way). Rates are not checked.
set -eu
: "${TESTBED:?}" "${TB_SOURCE_DIR:?}"
out=$("$TESTBED" bench rays "$TB_SOURCE_DIR/scenes/cornell-box.mid" --embree --rays 4000 --repeat 1 --threads 1,2)
printf '%s\n' "$out"
printf '%s\n' "$out" | awk '
/ agreement: / { n++; d = $3; t = $5; if (t < 1000 || d > t / 1000) { print "FAIL: " $0; bad = 1 } }
/^primary +4000 / { p++ }
END {
    if (n != 3) { print "FAIL: expected 3 agreement lines, got " n; bad = 1 }
    if (p != 2) { print "FAIL: expected primary rows for 1 and 2 threads, got " p; bad = 1 }
    exit bad
}'
