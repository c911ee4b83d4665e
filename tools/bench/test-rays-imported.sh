#!/bin/sh
# Script test: tools/bench/rays-imported.sh on a small height field (800
# triangles) traces all three ray sets through the imported (FED) mesh:
# the import reports the mesh, every set has hits, and Embree (an independent
# tracer, required by the test build) agrees with our BVH on hit/miss, object
# and face for all but ties on shared edges (<= 1 in 1000). Rates are not checked.
set -eu
: "${TESTBED:?}" "${TB_SOURCE_DIR:?}"
out=$(HF_N=20 TESTBED="$TESTBED" sh "$TB_SOURCE_DIR/tools/bench/rays-imported.sh" --rays 2000 --repeat 1 --threads 1 --embree 2>&1)
printf '%s\n' "$out"
printf '%s\n' "$out" | awk '
/Wavefront Object Importer\): 1 objects, 1 FED files .*800 faces/ { imported = 1 }
/^scene .*802 triangles/ { scene = 1 }
/^(primary|shadow|diffuse) +[0-9]+ +[0-9.]+ +1 / { sets++; if ($3 + 0 <= 0) { print "FAIL: no hits: " $0; bad = 1 } }
/ agreement: / { agree++; d = $3; t = $5; if (t < 1000 || d > t / 1000) { print "FAIL: " $0; bad = 1 } }
END {
    if (!imported) { print "FAIL: the import summary is missing"; bad = 1 }
    if (!scene) { print "FAIL: the imported scene should hold 800 + 2 triangles"; bad = 1 }
    if (sets != 3) { print "FAIL: expected 3 ray sets, got " sets; bad = 1 }
    if (agree != 3) { print "FAIL: expected 3 Embree agreement lines, got " agree; bad = 1 }
    exit bad
}'
