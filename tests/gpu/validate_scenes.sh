#!/bin/sh
# `testbed validate` on every bundled scene (scenes/*.mid, scenes/tests/*.mid)
# through lavapipe with the validation layer: the Vulkan intersect path must
# agree with the CPU path within docs/accuracy.md's tolerances and the layer
# must report nothing. Also checks the routing report and the usage errors.
set -eu
: "${TESTBED:?}" "${TB_SOURCE_DIR:?}" "${TB_TEST_TMPDIR:?}"
. "$TB_SOURCE_DIR/tests/gpu/gpu_test.sh"
out="$TB_TEST_TMPDIR/validate.out"
n=0
for scene in "$TB_SOURCE_DIR"/scenes/*.mid "$TB_SOURCE_DIR"/scenes/tests/*.mid; do
    [ -f "$scene" ] || continue
    validate_scene "$out" "$scene" --kernel all --rays 3000 --seed 3
    grep -q "^routing: " "$out" || { echo "no routing report: $scene"; exit 1; }
    n=$((n + 1))
done
[ "$n" -ge 1 ] || { echo "no scenes found"; exit 1; }
# The showcase has every kind: every primitive reported on the GPU, only its CSG trees routed.
TB_VK_VALIDATION=1 "$TESTBED" validate "$TB_SOURCE_DIR/scenes/showcase.mid" --rays 500 >"$out" 2>&1
grep -q "(torus): gpu" "$out" || { echo "torus not reported on the GPU"; cat "$out"; exit 1; }
if grep "cpu (routed)" "$out" | grep -qv "(union)\|(intersection)\|(difference)"; then
    echo "a primitive routed"; cat "$out"; exit 1
fi
grep -q "(polygons): gpu" "$out" || { echo "polygons not reported on the GPU"; cat "$out"; exit 1; }
grep -q "(sphere): gpu" "$out" || { echo "spheres not reported on the GPU"; cat "$out"; exit 1; }
grep -q "(cube): gpu" "$out" || { echo "cubes not reported on the GPU"; cat "$out"; exit 1; }
# Usage errors.
set +e
"$TESTBED" validate "$TB_SOURCE_DIR/scenes/cornell-box.mid" --kernel bogus >/dev/null 2>&1
[ $? -eq 2 ] || { echo "--kernel bogus should be a usage error"; exit 1; }
"$TESTBED" validate >/dev/null 2>&1
[ $? -eq 2 ] || { echo "no scene should be a usage error"; exit 1; }
echo "validated $n scenes"
