#!/bin/sh
# `testbed validate --kernel shade` on every bundled scene (scenes/*.mid,
# scenes/tests/*.mid) through lavapipe with the validation layer: the Vulkan
# wavefront renderer's image against the CPU ray tracer's within the NMSE and
# bias tolerances of docs/accuracy.md ("Shade kernel"), the layer silent,
# and the routing reported (two independent renders: any shading error of
# the kernel beyond float rounding shows in the NMSE or the bias).
set -eu
: "${TESTBED:?}" "${TB_SOURCE_DIR:?}" "${TB_TEST_TMPDIR:?}"
. "$TB_SOURCE_DIR/tests/gpu/gpu_test.sh"
out="$TB_TEST_TMPDIR/shade_validate.out"
n=0
for scene in "$TB_SOURCE_DIR"/scenes/*.mid "$TB_SOURCE_DIR"/scenes/tests/*.mid; do
    [ -f "$scene" ] || continue
    validate_scene "$out" "$scene" --kernel shade --seed 5 --rays 16384
    grep "kernel shade:\|NMSE\|bias" "$out" | sed "s|^|$(basename "$scene"): |"
    grep -q "^kernel shade: .* hits shaded by the kernel, [0-9]* routed to the CPU path" "$out" ||
        { echo "no routing line: $scene"; cat "$out"; exit 1; }
    grep -q "image NMSE .* ok$" "$out" || { echo "no NMSE verdict: $scene"; cat "$out"; exit 1; }
    # the MID 1.1 materials (GGX, checker and noise patterns, noise bumps) run on the kernel
    case "$scene" in */scenes/materials.mid)
        grep -q "^kernel shade: .* [1-9][0-9]* hits shaded by the kernel, 0 routed to the CPU path" "$out" ||
            { echo "materials.mid: hits routed to the CPU path"; cat "$out"; exit 1; } ;;
    esac
    grep -q "mean bias .* ok$" "$out" || { echo "no bias verdict: $scene"; cat "$out"; exit 1; }
    n=$((n + 1))
done
[ "$n" -ge 1 ] || { echo "no scenes found"; exit 1; }
"$TESTBED" validate --help | grep -q "shade" || { echo "shade not in validate --help"; exit 1; }
echo "validated the shade kernel on $n scenes"
