#!/bin/sh
# Script test (Embree 3 is required by the test build):
# `testbed bench rays --embree` on the Cornell box must trace all three ray
# sets and our BVH and Embree -- two independent implementations -- must
# agree on hit/miss, object and face for all but a tiny fraction of rays
# (rays through shared edges may go either way), with Embree's default, its
# robust mode (--embree-robust) and its SSE2 kernels (--embree-config
# max_isa=sse2, which the header line must report). Rates are not checked.
set -eu
: "${TESTBED:?}" "${TB_SOURCE_DIR:?}"
for mode in --embree --embree-robust "--embree --embree-config max_isa=sse2"; do
# shellcheck disable=SC2086 # mode is split into options on purpose
out=$("$TESTBED" bench rays "$TB_SOURCE_DIR/scenes/cornell-box.mid" $mode --rays 4000 --repeat 1 --threads 1,2)
printf '%s\n' "$out"
printf '%s\n' "$out" | awk -v mode="$mode" '
/ agreement: / { n++; d = $3; t = $5; if (t < 1000 || d > t / 1000) { print "FAIL: " $0; bad = 1 } }
/^primary +4000 / { p++ }
/^Embree .* scene built/ { robust = index($0, "RTC_SCENE_FLAG_ROBUST") > 0; cfg = index($0, "device config max_isa=sse2") > 0 }
END {
    if (n != 3) { print "FAIL: expected 3 agreement lines, got " n; bad = 1 }
    if (p != 2) { print "FAIL: expected primary rows for 1 and 2 threads, got " p; bad = 1 }
    if (robust != (mode == "--embree-robust")) { print "FAIL: " mode ": robust flag reported " robust; bad = 1 }
    if (cfg != (index(mode, "max_isa=sse2") > 0)) { print "FAIL: " mode ": device config reported " cfg; bad = 1 }
    exit bad
}'
done
